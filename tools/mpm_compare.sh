#!/bin/sh
# mpm_compare.sh - do two builds of the MPMxDEM drivers give the same numbers?
#
#   tools/mpm_compare.sh REF_BIN NEW_BIN WORK [CASE...]
#
# REF_BIN and NEW_BIN are folders holding mpmdem_biaxial, mpmdem_footing and
# mpmdem_collapse (e.g. an older build and build/). Each CASE (default: all
# below) runs the REF and the NEW driver with the same flags (--threads 1
# --quiet) into WORK/CASE.ref and WORK/CASE.new (an existing WORK/CASE.ref
# with its .out is reused), then compares the CSV in every column but
# `seconds` and the RESULT line in every key but the timings and the memory.
# A restart case runs NEW in two parts (the first to the given stop, then
# --restart to the end) against the uninterrupted REF run (its _default for the README sizes). Prints one line per case,
# SAME or DIFF (with the first differing lines); exit status 1 if any differs.
#
# The cases are the MPMxDEM commands of examples/README.md:
#   bx_default      mpmdem_biaxial                          (128 RVEs to 3 %)
#   bx_strain       mpmdem_biaxial --dem-rule strain
#   bx_restart      mpmdem_biaxial to 1.5 %, then --restart to 3 %
#   ft_default      mpmdem_footing                          (450 RVEs to d/B 0.14)
#   ft_medium       mpmdem_footing --material medium --packing examples/data/rve400_e0223.txt --final 0.3
#   ft_soft         mpmdem_footing --material soft --packing examples/data/rve400_e0223.txt --final 0.3
#   ft_restart      mpmdem_footing to d/B 0.07, then --restart to 0.14
#   cl_default      mpmdem_collapse                         (64 RVEs to rest)
#   cl_restart      mpmdem_collapse to t = 0.8 s, then --restart (to rest)
# They take 10-30 minutes each at one thread on a busy machine. The tests'
# sizes (tests/test_mpmdem_*.c, seconds each):
#   bx_test         mpmdem_biaxial 2 x 4 cells to 0.2 %     (bx_test_restart: 0.1 %, then to 0.2 %)
#   ft_test         mpmdem_footing 4 x 3 cells with the friction-angle tests
#   ft_test_u       mpmdem_footing 4 x 3 cells to d/B 0.08  (ft_test_restart: 0.01, then to 0.02)
#   cl_test         mpmdem_collapse 4 x 4 cells to t = 0.15 s (cl_test_restart: 0.075 s, then on)
set -u
[ $# -ge 3 ] || { sed -n '2,/^[^#]/ s/^# \{0,1\}//p' "$0"; exit 2; }
REF=$1 NEW=$2 W=$3
shift 3
mkdir -p "$W" || exit 1
CASES=${*:-"bx_default bx_strain bx_restart ft_default ft_medium ft_soft ft_restart cl_default cl_restart"}
FT="--width 2 --depth 1.5 --nx 4 --ny 3 --B 1.5 --velocity 0.25 --ramp 0.01 --every 0.005 --smooth 0.01"
LOOSE="--material medium --packing examples/data/rve400_e0223.txt --final 0.3"
# the flags of a case, and for a restart case the first part's stop
args() {
    case $1 in
    bx_default | bx_restart) echo "mpmdem_biaxial csv=biaxial.csv" ;;
    bx_strain) echo "mpmdem_biaxial csv=biaxial.csv --dem-rule strain" ;;
    ft_default | ft_restart) echo "mpmdem_footing csv=footing.csv" ;;
    ft_medium) echo "mpmdem_footing csv=footing.csv $LOOSE" ;;
    ft_soft) echo "mpmdem_footing csv=footing.csv --material soft --packing examples/data/rve400_e0223.txt --final 0.3" ;;
    cl_default | cl_restart) echo "mpmdem_collapse csv=collapse.csv" ;;
    bx_test | bx_test_restart) echo "mpmdem_biaxial csv=biaxial.csv --nx 2 --ny 4 --every 0.0005 --strain 0.002" ;;
    ft_test) echo "mpmdem_footing csv=footing.csv $FT --final 0.02 --phi-pressures 20 --phi-strain 0.025" ;;
    ft_test_u) echo "mpmdem_footing csv=footing.csv $FT --final 0.08 --smooth 0.02 --phi-deg 30" ;;
    ft_test_restart) echo "mpmdem_footing csv=footing.csv $FT --final 0.02 --phi-deg 30" ;;
    cl_test | cl_test_restart) echo "mpmdem_collapse csv=collapse.csv --nx 4 --every 0.025 --snapshots 0.05 --t-end 0.15" ;;
    *) echo "unknown case $1" >&2; exit 2 ;;
    esac
}
first_part() {
    case $1 in
    bx_restart) echo "--strain 0.015" ;;
    ft_restart) echo "--final 0.07" ;;
    cl_restart) echo "--t-end 0.8 --no-stop" ;;
    bx_test_restart) echo "--strain 0.001" ;;
    ft_test_restart) echo "--final 0.01" ;;
    cl_test_restart) echo "--t-end 0.075" ;;
    esac
}
# a CSV without its `seconds` column
strip_csv() { awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == "seconds") s = i } { o = ""; for (i = 1; i <= NF; ++i) if (i != s) o = o (o == "" ? "" : ",") $i; print o }' "$1"; }
# the RESULT line's key=value pairs but the timings and the memory, one per line
# (a restart's mpm_steps counts the steps of its second part only: left out there)
strip_result() { grep '^RESULT ' "$1" | tail -n 1 | tr ' ' '\n' | grep = | grep -Ev "^(seconds_per_step[a-z0-9_]*|total_seconds|mem_per_rve_kb|vmhwm_mb$2)="; }
status=0
for c in $CASES; do
    set -- $(args "$c")
    drv=$1 csv=${2#csv=}
    shift 2
    r=$c
    case $c in # the uninterrupted run is the reference
    *_test_restart) ;; # REF runs it uninterrupted
    *_restart) r=${c%_restart}_default ;;
    esac
    if [ ! -s "$W/$r.ref.out" ] || ! grep -q '^RESULT ' "$W/$r.ref.out"; then
        "$REF/$drv" "$@" --threads 1 --quiet --out "$W/$r.ref" > "$W/$r.ref.out" 2>&1 || echo "$c: the REF run failed (status $?)"
    fi
    fp=$(first_part "$c")
    if [ -n "$fp" ]; then
        "$NEW/$drv" "$@" $fp --threads 1 --quiet --out "$W/$c.new1" > "$W/$c.new1.out" 2>&1 &&
            "$NEW/$drv" "$@" --threads 1 --quiet --restart "$W/$c.new1" --out "$W/$c.new" > "$W/$c.new.out" 2>&1 ||
            echo "$c: the NEW run failed (status $?)"
    else
        "$NEW/$drv" "$@" --threads 1 --quiet --out "$W/$c.new" > "$W/$c.new.out" 2>&1 || echo "$c: the NEW run failed (status $?)"
    fi
    strip_csv "$W/$r.ref/$csv" > "$W/$c.ref.csv"
    strip_csv "$W/$c.new/$csv" > "$W/$c.new.csv"
    skip=
    [ -n "$fp" ] && skip='|mpm_steps'
    strip_result "$W/$r.ref.out" "$skip" > "$W/$c.ref.result"
    strip_result "$W/$c.new.out" "$skip" > "$W/$c.new.result"
    rows=$(($(wc -l < "$W/$c.ref.csv") - 1))
    if [ "$rows" -gt 0 ] && cmp -s "$W/$c.ref.csv" "$W/$c.new.csv" && [ -s "$W/$c.ref.result" ] &&
        cmp -s "$W/$c.ref.result" "$W/$c.new.result"; then
        echo "SAME $c: $csv ($rows rows, every column but seconds) and RESULT ($(wc -l < "$W/$c.ref.result") keys)"
    else
        echo "DIFF $c:"
        diff "$W/$c.ref.csv" "$W/$c.new.csv" | head -n 6
        diff "$W/$c.ref.result" "$W/$c.new.result" | head -n 6
        status=1
    fi
done
exit $status
