#!/bin/sh
# Runs every test program given on the command line, prints their output,
# each program's name and wall time, and ends with the line
# "N passed, N failed". A program that crashes or exits non-zero without a
# summary line counts as one failure.
#
# TEST_JOBS=N runs N programs at a time (default: the -jN of the make that
# calls this script, else 1). One at a time, the output streams as it comes;
# with more, each program's output is printed whole when it ends, in the
# order given. Test programs write only files of their own (names that no
# other test program uses; test_docs checks this), so they can run together.
passed=0
failed=0
now() { date +%s.%N 2>/dev/null || date +%s; }
jobs=${TEST_JOBS:-}
if [ -z "$jobs" ]; then
    # make exports " -j2 --jobserver-auth=..." (GNU make) to the commands it runs
    jobs=$(printf '%s\n' " ${MAKEFLAGS:-}" | sed -n 's/.* -j\([0-9][0-9]*\).*/\1/p')
    [ -n "$jobs" ] || jobs=1
fi
case $jobs in '' | *[!0-9]* | 0) echo "run_tests.sh: TEST_JOBS '$jobs' is not a positive whole number" >&2; exit 2 ;; esac
all0=$(now)
tmp=$(mktemp -d) || exit 1
trap 'rm -rf "$tmp"' EXIT

# count one finished program: $1 name, $2 its output file, $3 exit status, $4 $5 start, end
count() {
    echo "   ($(awk -v a="$4" -v b="$5" 'BEGIN { printf "%.1f", b - a }') s)"
    sum=$(grep -E '^# .*: [0-9]+ passed, [0-9]+ failed$' "$2" | tail -n 1)
    if [ -n "$sum" ]; then
        p=$(printf '%s' "$sum" | sed -E 's/.*: ([0-9]+) passed, ([0-9]+) failed/\1/')
        f=$(printf '%s' "$sum" | sed -E 's/.*: ([0-9]+) passed, ([0-9]+) failed/\2/')
        passed=$((passed + p))
        failed=$((failed + f))
        if [ "$3" -ne 0 ] && [ "$f" -eq 0 ]; then
            echo "FAIL $1 exited with status $3"
            failed=$((failed + 1))
        fi
    else
        echo "FAIL $1 (exit status $3, no summary line: crashed?)"
        failed=$((failed + 1))
    fi
}

# print finished program number $1 of a parallel run
show() {
    name=$(cat "$tmp/$1.name")
    echo "== $name"
    cat "$tmp/$1.out"
    read -r rc t0 t1 < "$tmp/$1.st"
    count "$name" "$tmp/$1.out" "$rc" "$t0" "$t1"
}

if [ "$jobs" -eq 1 ]; then
    for t in "$@"; do
        echo "== $t"
        t0=$(now)
        # stream the output as it comes, keep it for the summary line
        { "$t" 2>&1; echo $? > "$tmp/rc"; } | tee "$tmp/out"
        count "$t" "$tmp/out" "$(cat "$tmp/rc")" "$t0" "$(now)"
    done
else
    echo "== $# test programs, $jobs at a time"
    # start a program whenever fewer than $jobs run (a finished one leaves N.st);
    # print the finished ones in the order given
    n=0        # started
    shown=0    # printed
    running=0
    for t in "$@"; do
        while [ "$running" -ge "$jobs" ]; do
            running=0
            i=$shown
            while [ "$i" -lt "$n" ]; do
                i=$((i + 1))
                [ -f "$tmp/$i.st" ] || running=$((running + 1))
            done
            [ "$running" -ge "$jobs" ] && sleep 0.1
            while [ "$shown" -lt "$n" ] && [ -f "$tmp/$((shown + 1)).st" ]; do
                shown=$((shown + 1))
                show "$shown"
            done
        done
        n=$((n + 1))
        printf '%s\n' "$t" > "$tmp/$n.name"
        (
            t0=$(now)
            "$t" > "$tmp/$n.out" 2>&1
            rc=$?
            echo "$rc $t0 $(now)" > "$tmp/$n.st.part" && mv "$tmp/$n.st.part" "$tmp/$n.st"
        ) &
        running=$((running + 1))
    done
    wait
    while [ "$shown" -lt "$n" ]; do
        shown=$((shown + 1))
        show "$shown"
    done
fi
echo "== all tests: $(awk -v a="$all0" -v b="$(now)" 'BEGIN { printf "%.0f", b - a }') s"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
