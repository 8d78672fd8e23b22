#!/bin/sh
# Smoke runs of the tools and drivers built with AddressSanitizer +
# UndefinedBehaviorSanitizer, leak detection on (make check-smoke). Each run
# states the exit status it must end with: 0 for a good run, 1 for a refused
# input or a result that could not be written, 2 for a refused option. A
# sanitizer report fails the run whatever the status. A driver joins with
# its name in the Makefile's SMOKE list and its runs below.
B=${B:-build/asan}
T=${T:-build/tests/smoke}
mkdir -p "$T" || exit 1
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
passed=0
failed=0
run() { # run WANT PROGRAM ARGS...
    want=$1
    shift
    out=$("$@" 2>&1)
    rc=$?
    if [ "$rc" -ne "$want" ] || printf '%s\n' "$out" | grep -q -E 'Sanitizer|runtime error:'; then
        echo "FAIL (exit $rc, wanted $want) $*"
        printf '%s\n' "$out" | tail -n 25
        failed=$((failed + 1))
    else
        echo "ok   (exit $rc) $*"
        passed=$((passed + 1))
    fi
}
P=examples/data/rve400.txt
# rve_path: a good run, a result that cannot be written, untrusted packings
run 0 "$B/rve_path" --packing $P --dH "0 0.001 0 0" --increments 2 --steps-per-increment 20 --out "$T/rve.csv"
run 1 "$B/rve_path" --packing $P --dH "0 0.001 0 0" --increments 1 --steps-per-increment 5 --out /dev/full
run 1 "$B/rve_path" --packing $P --dH "0 0.001 0 0" --increments 1 --steps-per-increment 5 --out "$T/r.csv" \
    --svg /dev/full
run 1 "$B/rve_path" --packing $P --dH "0 0.5 0 0" --increments 1 --steps-per-increment 1 --out "$T/r.csv"
run 1 "$B/rve_path" --packing tests/fuzz/crashers/packing/announces_2e9 --dH "0 0 0 0"
run 0 "$B/rve_path" --packing tests/fuzz/crashers/packing/huge_cell_bins_overflow --dH "0 0 0 0" \
    --increments 1 --steps-per-increment 2 --out "$T/h.csv"
run 1 "$B/rve_path" --packing tests --dH "0 0 0 0"
run 2 "$B/rve_path" --packing $P --dH "0 0.001 0 0" --friction-deg 95
# gk_pack: a good run, an unreachable void ratio, a packing that cannot be written
run 0 "$B/gk_pack" --n 60 --out "$T/pack.txt"
run 1 "$B/gk_pack" --n 60 --target-void-ratio 2.5 --out "$T/pack2.txt"
run 1 "$B/gk_pack" --n 60 --out /dev/full
run 2 "$B/gk_pack" --n 60 --friction-deg 95 --out "$T/pack3.txt"
echo "# smoke_asan: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
