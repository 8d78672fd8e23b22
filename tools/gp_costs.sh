#!/bin/sh
# gp_costs.sh DIR - the cost pairs of bench_twoscale --model --costs from a femdem_biaxial run:
# for every Gauss point and every pair of consecutive load steps, its DEM steps at one step and
# at the next ("w0 w1" per line), read from DIR/gp_NNNN.vtk (the dem_steps field; the run needs
# --vtk-every 1, the default).
#   build/femdem_biaxial --nx 4 --ny 8 --element q8 --steps 40 --out build/costs_run
#   tools/gp_costs.sh build/costs_run > build/costs.txt
#   build/bench_twoscale --model --costs build/costs.txt
# These pairs are across load steps only (they evaluate the balance at accept). For every run,
# Newton iterations included, use femdem_biaxial --cost-log FILE and bench_twoscale --cost-log FILE.
set -eu
[ $# -eq 1 ] && [ -d "$1" ] || { echo "usage: tools/gp_costs.sh DIR (a femdem_biaxial output directory)" >&2; exit 2; }
tmp=$(mktemp -d) || exit 1
trap 'rm -rf "$tmp"' EXIT
prev=""
n=0
for f in "$1"/gp_[0-9]*.vtk; do
    [ -f "$f" ] || continue
    n=$((n + 1))
    cur="$tmp/$n"
    # the values after "SCALARS dem_steps double 1" and its LOOKUP_TABLE line, up to the next keyword
    awk '/^SCALARS dem_steps /{on = 1; getline; next} on && /^[A-Z]/{on = 0} on && NF == 1 {print $1}' "$f" > "$cur"
    [ -s "$cur" ] || { echo "gp_costs.sh: no dem_steps field in $f" >&2; exit 1; }
    if [ -n "$prev" ]; then
        [ "$(wc -l < "$prev")" -eq "$(wc -l < "$cur")" ] || { echo "gp_costs.sh: $f has another point count" >&2; exit 1; }
        paste -d ' ' "$prev" "$cur"
    fi
    prev=$cur
done
[ "$n" -ge 2 ] || { echo "gp_costs.sh: fewer than two gp_NNNN.vtk files in $1" >&2; exit 1; }
