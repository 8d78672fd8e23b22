#!/bin/sh
# Runs every test program given on the command line, prints their output,
# each program's name and wall time, and ends with the line
# "N passed, N failed". A program that crashes or exits non-zero without a
# summary line counts as one failure.
passed=0
failed=0
now() { date +%s.%N 2>/dev/null || date +%s; }
all0=$(now)
tmp=$(mktemp) || exit 1
trap 'rm -f "$tmp" "$tmp.rc"' EXIT
for t in "$@"; do
    echo "== $t"
    t0=$(now)
    # stream the output as it comes, keep it for the summary line
    { "$t" 2>&1; echo $? > "$tmp.rc"; } | tee "$tmp"
    rc=$(cat "$tmp.rc")
    out=$(cat "$tmp")
    t1=$(now)
    echo "   ($(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }') s)"
    sum=$(printf '%s\n' "$out" | grep -E '^# .*: [0-9]+ passed, [0-9]+ failed$' | tail -n 1)
    if [ -n "$sum" ]; then
        p=$(printf '%s' "$sum" | sed -E 's/.*: ([0-9]+) passed, ([0-9]+) failed/\1/')
        f=$(printf '%s' "$sum" | sed -E 's/.*: ([0-9]+) passed, ([0-9]+) failed/\2/')
        passed=$((passed + p))
        failed=$((failed + f))
        if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then
            echo "FAIL $t exited with status $rc"
            failed=$((failed + 1))
        fi
    else
        echo "FAIL $t (exit status $rc, no summary line: crashed?)"
        failed=$((failed + 1))
    fi
done
echo "== all tests: $(awk -v a="$all0" -v b="$(now)" 'BEGIN { printf "%.0f", b - a }') s"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
