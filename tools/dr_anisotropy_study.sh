#!/bin/sh
# dr_anisotropy_study.sh - does a higher initial fabric anisotropy give a lower, earlier peak
# (Liu, Bosco & Suiker 2018, Figs 12-14)? An ensemble of 228-disk RVEs alone (build/femdem_dr
# --test rve, the servo frame), so that the answer is not one packing's noise.
#
#   tools/dr_anisotropy_study.sh [--report] WORK [JOBS] [SEEDS]
#
# Run from the project's root; BUILD=DIR takes the programs from DIR instead of build/.
# 1. Packings: gk_pack as examples/data/frame228_a00N.txt (205 disks, 21 on the frame lines, 1500 Pa),
#    --target-anisotropy 0.02, 0.05, 0.08 with each seed of SEEDS (1 to 10); gk_pack raises
#    the anisotropy towards the target but never lowers it, so a seed whose packing already holds
#    more gives the same packing for several targets: those are run once.
# 2. Every distinct packing at two stiffnesses, both relaxed to equilibrium in every load step
#    (--dr-force-tol 1e-2): k_n = 100 sigma0 (the driver's default) and k_n = 1e5 sigma0 (the
#    packing files' own k_n / p, where the isotropic stage mostly keeps the packing's anisotropy).
# 3. Prints per run: the packing's A0 (eq 38: Pi_1 / Pi_2 - 1, whatever the axis of Pi_1), a_y
#    (phi_yy / phi_xx - 1 of the fabric tensor gk_pack writes: signed, > 0 when the contact
#    normals are in excess along the loading axis), A at the end of the isotropic stage (A_iso,
#    unsigned), the peak stress ratio and its strain, sigma_bar at 7.3 %, the mean sigma_bar
#    over 2-10 %, and the largest force residual; then for each stiffness the least-squares
#    slope of the peak, of its strain and of the 2-10 % mean against each of A0, a_y and A_iso,
#    with its standard error and the correlation r (a slope within two standard errors of 0: no
#    resolved effect).
# Writes WORK/anisotropy.csv (one row per run). Exit status 1 if a run could not be started or a
# result not written. The default seeds give 22 distinct packings, about 20 minutes on 2 cores
# (a packing 20 s, a run 3 s at k_n = 100 sigma0 and about a minute at 1e5); JOBS runs at a
# time (default 2). --report runs nothing: the table of WORK's runs.
set -u
report=0
[ "${1:-}" = --report ] && { report=1; shift; }
[ $# -ge 1 ] || { sed -n '2,/^[^#]/ s/^# \{0,1\}//p' "$0"; exit 2; }
W=$1 J=${2:-2} SEEDS=${3:-"1 2 3 4 5 6 7 8 9 10"}
B=${BUILD:-build}
mkdir -p "$W" || exit 1
[ -x "$B/femdem_dr" ] && [ -x "$B/gk_pack" ] || { echo "dr_anisotropy_study: make $B/femdem_dr $B/gk_pack first" >&2; exit 1; }
fail=0
if [ $report = 0 ]; then
    for s in $SEEDS; do
        for a in 0.02 0.05 0.08; do
            echo "$s $a"
        done
    done | xargs -P "$J" -n 2 sh -c '[ -f "$0/pack_a$3_s$2.txt" ] ||
        "$1/gk_pack" --dim 2 --n 205 --rmin 3e-4 --rmax 4.5e-4 --pressure 1500 --kn 1.5e8 --kt-ratio 0.2 \
            --friction-angle 0.380506377112365 --density 2000 --thickness 1 --frame 10 --seed "$2" \
            --target-anisotropy "$3" --out "$0/pack_a$3_s$2.txt" > "$0/pack_a$3_s$2.log" 2>&1' "$W" "$B" ||
        fail=1
    # the distinct packings (the particle lines, not the comments naming the target)
    : > "$W/distinct.txt"
    for f in "$W"/pack_a*_s*.txt; do
        [ -f "$f" ] || continue
        sum=$(grep -v '^#' "$f" | cksum | cut -d' ' -f1)
        grep -q " $sum\$" "$W/distinct.txt" || echo "$(basename "$f" .txt) $sum" >> "$W/distinct.txt"
    done
    for k in 100 1e5; do
        cut -d' ' -f1 "$W/distinct.txt" | while read -r p; do echo "$k $p"; done
    done | xargs -P "$J" -n 2 sh -c '[ -f "$0/k$2/$3.out" ] && grep -q "^RESULT" "$0/k$2/$3.out" && exit 0
        mkdir -p "$0/k$2" && "$1/femdem_dr" --test rve --packing "$0/$3.txt" --kn-ratio "$2" --dr-force-tol 1e-2 \
            --vtk-every 0 --out "$0/k$2/$3" > "$0/k$2/$3.out" 2> "$0/k$2/$3.err"' "$W" "$B" || fail=1
fi
[ -f "$W/distinct.txt" ] || { echo "dr_anisotropy_study: no packings in $W" >&2; exit 1; }
# a_y = phi_yy / phi_xx - 1 of the packing's contact fabric, from the tensor gk_pack writes
# next to its A0 (signed: > 0 when the contact normals are in excess along y, the loading axis)
fabric_y() {
    sed -n 's/^# fabric tensor phi = .*: xx \([^ ]*\) yy \([^ ]*\) .*/\1 \2/p' "$1" |
        awk 'NF == 2 && $1 > 0 { printf "%.4f", $2 / $1 - 1; f = 1 } END { if (!f) printf "nan" }'
}
# one line per run: k name A0 a_y A_iso peak eps_peak sb073 mean_2_10 resid_max
{
    echo "kn_ratio,packing,A0,a_y,A_iso,peak_sigma_bar,eps_at_peak,sigma_bar_0073,mean_sigma_bar_2_10,dr_residual_max"
    for k in 100 1e5; do
        cut -d' ' -f1 "$W/distinct.txt" | while read -r p; do
            o="$W/k$k/$p.out" c="$W/k$k/$p/dr.csv"
            grep -q '^RESULT' "$o" 2> /dev/null && [ -f "$c" ] || { echo "$k,$p,nan,nan,nan,nan,nan,nan,nan,nan"; continue; }
            a0=$(sed -n 's/^# fabric anisotropy A = .* = \([0-9.e+-]*\) .*/\1/p' "$W/$p.txt")
            awk -F, -v k="$k" -v p="$p" -v a0="$a0" -v ay="$(fabric_y "$W/$p.txt")" \
                -v res="$(sed -n 's/.* dr_residual_max=\([^ ]*\) .*/\1/p' "$o")" '
                NR == 1 { next }
                $2 == 1 { aiso = $9 }
                $2 == 2 { if ($4 > pk) { pk = $4; ep = $3 }
                          if ($3 >= 0.02 - 1e-9) { s += $4; n++ }
                          if (px < 0.073 && $3 >= 0.073) s73 = py + ($4 - py) * (0.073 - px) / ($3 - px)
                          px = $3; py = $4 }
                END { printf "%s,%s,%s,%s,%.4f,%.4f,%.4f,%.4f,%.4f,%s\n", k, p, a0, ay, aiso, pk, ep, s73, n ? s / n : 0, res }' "$c"
        done
    done
} > "$W/anisotropy.csv" || fail=1
column -t -s, "$W/anisotropy.csv" 2> /dev/null || cat "$W/anisotropy.csv"
# least squares y = a + b x per stiffness, x = A0, a_y, A_iso: b, its standard error, r
for k in 100 1e5; do
    for xc in "3 A0" "4 a_y" "5 A_iso"; do
        for col in "6 peak" "7 eps_at_peak" "9 mean_2_10"; do
            set -- $xc $col
            awk -F, -v k="$k" -v xc="$1" -v xname="$2" -v c="$3" -v name="$4" 'BEGIN { n = 0 }
                NR > 1 && $1 == k && $c != "nan" {
                    x[n] = $xc; y[n] = $c; sx += $xc; sy += $c; n++
                    if (n == 1 || $xc < lo) lo = $xc; if (n == 1 || $xc > hi) hi = $xc }
                END { if (n < 3) { printf "k_n/sigma0 %-4s %-5s %-12s too few runs\n", k, xname, name; exit }
                      mx = sx / n; my = sy / n
                      for (i = 0; i < n; ++i) { sxx += (x[i] - mx)^2; syy += (y[i] - my)^2; sxy += (x[i] - mx) * (y[i] - my) }
                      b = sxy / sxx; a = my - b * mx
                      for (i = 0; i < n; ++i) e += (y[i] - a - b * x[i])^2
                      se = sqrt(e / (n - 2) / sxx); r = syy > 0 ? sxy / sqrt(sxx * syy) : 0
                      printf "k_n/sigma0 %-4s %-5s %-12s n %2d  x %+.3f..%+.3f  mean %.4f  slope %+.3f +- %.3f  r %+.2f%s\n",
                          k, xname, name, n, lo, hi, my, b, se, r, (b > 2 * se || b < -2 * se) ? "" : "  (no resolved effect)" }' "$W/anisotropy.csv"
        done
    done
done
exit $fail
