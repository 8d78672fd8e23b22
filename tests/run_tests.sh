#!/bin/sh
# Runs every test program given on the command line, prints their output and
# ends with the line "N passed, N failed". A program that crashes or exits
# non-zero without a summary line counts as one failure.
passed=0
failed=0
for t in "$@"; do
    out=$("$t" 2>&1)
    rc=$?
    printf '%s\n' "$out"
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
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
