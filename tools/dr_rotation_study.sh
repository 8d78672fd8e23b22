#!/bin/sh
# dr_rotation_study.sh - how much stronger is the RVE whose particles cannot rotate (Liu, Bosco &
# Suiker 2018, Figs 10-11: at 7.3 % axial strain sigma_bar 0.39 free, 0.48 locked, ratio 0.81),
# and how does that depend on the contact stiffness, which the paper's Table 3 leaves open
# (k_n = 1e4 N/m against a 0.15 MN/m confinement)?
#
#   tools/dr_rotation_study.sh [--report] WORK [JOBS] [KN_RATIOS]
#
# Run from the project's root; BUILD=DIR takes the programs from DIR instead of build/.
# The 228-disk RVE alone (build/femdem_dr --test rve: the servo frame, the reduced load path of
# 10 + 20 steps to 10 %) on each shipped packing (examples/data/frame228_a00{2,5,8}.txt), at each
# k_n / sigma0 of KN_RATIOS (default "10 20 30 50 100 300 1000"), three ways: free rotation;
# --no-rotation, the paper's theta_p = 0 for the inner particles (the frame turns with the servo's
# moment corrections); --no-rotation --lock-frame, no particle turning at all.
# Writes WORK/rotation.csv (one row per run) and WORK/ratio.svg (the free / locked ratio of
# sigma_bar at 7.3 % against log10 k_n / sigma0, the paper's 0.81 dashed), and prints per
# stiffness the means over the packings: sigma_bar and A at 7.3 % for each way, the ratio free /
# locked (inner) with its spread (standard deviation over the packings), the peak strains.
# About 2.5 minutes on 2 cores (JOBS runs at a time, default 2; a run takes about 1 s at k_n = 1000
# sigma0, up to 15 s at 10: the soft RVEs relax slowly). Exit status 1 if a run could not be
# started or a result not written.
# --report runs nothing: the table and the figure of WORK's runs.
set -u
report=0
[ "${1:-}" = --report ] && { report=1; shift; }
[ $# -ge 1 ] || { sed -n '2,/^[^#]/ s/^# \{0,1\}//p' "$0"; exit 2; }
W=$1 J=${2:-2} KS=${3:-"10 20 30 50 100 300 1000"}
B=${BUILD:-build}
PK="a002 a005 a008"
mkdir -p "$W" || exit 1
[ -x "$B/femdem_dr" ] && [ -x "$B/csv_plot" ] || { echo "dr_rotation_study: make $B/femdem_dr $B/csv_plot first" >&2; exit 1; }
fail=0
if [ $report = 0 ]; then
    for k in $KS; do
        for p in $PK; do
            for m in free inner all; do echo "$k $p $m"; done
        done
    done | xargs -P "$J" -n 3 sh -c 'o="$0/k$2/$3_$4"
        [ -f "$o.out" ] && grep -q "^RESULT" "$o.out" && exit 0
        case $4 in free) lock= ;; inner) lock=--no-rotation ;; *) lock="--no-rotation --lock-frame" ;; esac
        mkdir -p "$0/k$2" && "$1/femdem_dr" --test rve --packing "examples/data/frame228_$3.txt" --kn-ratio "$2" \
            $lock --vtk-every 0 --out "$o" > "$o.out" 2> "$o.err"' "$W" "$B" || fail=1
fi
# one row per run, from the RESULT line
{
    echo "kn_ratio,packing,rotation,peak_sigma_bar,eps_at_peak,sigma_bar_0073,anisotropy_0073,dem_steps_per_run"
    for k in $KS; do
        for p in $PK; do
            for m in free inner all; do
                o="$W/k$k/${p}_$m.out"
                if grep -q '^RESULT' "$o" 2> /dev/null; then
                    sed -n 's/^RESULT peak_sigma_bar=\([^ ]*\) eps_at_peak=\([^ ]*\) sigma_bar_0073=\([^ ]*\) anisotropy_0073=\([^ ]*\) .* dem_steps_per_run=\([^ ]*\) .*/\1,\2,\3,\4,\5/p' "$o" |
                        sed "s/^/$k,$p,$m,/"
                else
                    echo "$k,$p,$m,nan,nan,nan,nan,nan"
                    fail=1
                fi
            done
        done
    done
} > "$W/rotation.csv" || fail=1
# means over the packings per stiffness; the ratio free / inner-locked of sigma_bar at 7.3 % per
# packing, then its mean and standard deviation
awk -F, 'NR > 1 && $6 != "nan" {
        k = $1; key = k "," $3; s[key] += $6; a[key] += $7; e[key] += $5; n[key]++
        if (!(k in seen)) { seen[k] = 1; order[nk++] = k }
        v[k "," $2 "," $3] = $6 }
    END {
        printf "%-8s %-21s %-21s %-21s %-15s %s\n", "k_n/s0", "free: s_bar A eps_pk", "inner: s_bar A eps_pk",
            "all: s_bar A eps_pk", "free/inner", "free/all"
        split("a002 a005 a008", P, " ")
        for (i = 0; i < nk; ++i) {
            k = order[i]
            line = sprintf("%-8s", k)
            for (m = 1; m <= 3; ++m) {
                w = m == 1 ? "free" : (m == 2 ? "inner" : "all"); key = k "," w
                line = line sprintf(" %.3f %.3f %.3f    ", n[key] ? s[key] / n[key] : 0, n[key] ? a[key] / n[key] : 0,
                                    n[key] ? e[key] / n[key] : 0)
            }
            for (m = 2; m <= 3; ++m) {
                w = m == 2 ? "inner" : "all"; c = 0; r1 = 0; r2 = 0
                for (j = 1; j <= 3; ++j)
                    if ((k "," P[j] ",free") in v && (k "," P[j] "," w) in v && v[k "," P[j] "," w] > 0) {
                        r = v[k "," P[j] ",free"] / v[k "," P[j] "," w]; r1 += r; r2 += r * r; c++ }
                mr = c ? r1 / c : 0; sd = c > 1 ? sqrt((r2 - c * mr * mr) / (c - 1) > 0 ? (r2 - c * mr * mr) / (c - 1) : 0) : 0
                line = line sprintf(" %.3f +- %.3f", mr, sd)
                if (m == 2) ratio[i] = mr
            }
            print line
        }
        print "log10_kn_ratio,ratio" > "'"$W"'/ratio_inner.csv"
        print "log10_kn_ratio,ratio" > "'"$W"'/ratio_paper.csv"
        for (i = 0; i < nk; ++i) {
            printf "%.4f,%.4f\n", log(order[i]) / log(10), ratio[i] >> "'"$W"'/ratio_inner.csv"
            printf "%.4f,0.81\n", log(order[i]) / log(10) >> "'"$W"'/ratio_paper.csv"
        }
    }' "$W/rotation.csv" || fail=1
"$B/csv_plot" --x log10_kn_ratio --y ratio --dashed 2 --ylim 0,1 \
    --title "sigma_bar at 7.3 %: free / inner particles locked (228-disk RVE, servo frame)" \
    --xlabel "log10 k_n / sigma0" --ylabel "free / locked" --out "$W/ratio.svg" \
    "$W/ratio_inner.csv=this RVE (mean of 3 packings)" "$W/ratio_paper.csv=Liu, Bosco & Suiker 2018" > /dev/null || fail=1
exit $fail
