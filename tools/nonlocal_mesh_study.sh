#!/bin/sh
# nonlocal_mesh_study.sh - the plane-strain biaxial mesh study of Liu, Sun, Yuan & Fish (2016,
# Figs 15-19) with build/femdem_nonlocal: three meshes, local against nonlocal.
#
#   tools/nonlocal_mesh_study.sh [--report] [--relaxed] WORK [THREADS]
#
# Run from the project's root (the driver's default packing is examples/data/rve512_hm.txt);
# BUILD=DIR takes the programs from DIR instead of build/.
#
# Runs (into WORK/NAME; a run whose WORK/NAME/biaxial.csv exists is reused) the 40 x 80 x 5 mm
# specimen to 8 % axial strain with the 512-sphere RVEs, every mesh with the same coarse step
# (1.826e-6 s, the finest mesh's stable step) and the same 5000 steps, so that every RVE sees
# the same strain increment per DEM run and the platen the same speed:
#   L4 L8 L12    local, meshes 4x8x1, 8x16x1, 12x24x1 (elements 10, 5, 3.3 mm)
#   N8 N12       nonlocal as the paper (R 6.75 mm, eq 58); on 4x8x1 no point has a neighbour
#                within R, so the 4x8 nonlocal run is L4 itself; N12 runs to 2 % only
#   M8 M12       nonlocal with --nonlocal-mix 0.9 (0.9 <eps> + 0.1 eps; see gk_nonlocal.h,
#                stability: the paper's average has modes of negative stiffness on 12x24x1)
# then prints per run: the symbol min of the averaging on its mesh (< 0: unstable), how the run
# ended, the largest kinetic energy to 2 % strain, the peak, the stress [kPa] at 2-8 %, and at 6 %
# (the paper's Figs 17 and 19) the largest Gauss-point eps_q and the share of the specimen where
# eps_q exceeds half of that, and the mean DEM steps per RVE run; then the spread of the stress over the meshes, (max - min) / mean,
# for each family. Writes WORK/mesh_study.svg (every curve). Exit status 1 if a run could not be
# started or a result not written. About 60 minutes on 2 cores. --report runs nothing: the
# table and the figure of the runs WORK holds.
#
# --relaxed: every DEM run relaxed to the paper's I_uf < 0.01 (eq 57; --dem-max 4000) instead of
# 20 steps, to 6 % (step 3750 of the same 5000), the runs L4 L8 N8 M8 L12 M12 (an RVE stopped
# while its particles still move resists in proportion to its rate, which can spread the strain
# over the elements: examples/femdem_nonlocal.c, simple shear). The relaxed specimen rings, so the
# stress at S is the mean over the 1 % of strain before S and the peak the largest mean of five
# rows (0.2 %). About 10 (4x8x1), 75 (8x16x1) and 180 (12x24x1, projected) minutes per run on
# one core.
# RUNS="L4 L8 N8" runs (and reports) only those, in either mode. HOURGLASS=K runs with --hourglass
# K instead of the driver's 0.1; WORK/hourglass records it and a WORK made with another K is refused.
# The column hg_% is the hourglass energy in % of the stress work at 6 % (nan for a CSV without
# those columns).
set -u
report=0 relaxed=0
while [ $# -ge 1 ]; do
    case $1 in
    --report) report=1 ;;
    --relaxed) relaxed=1 ;;
    *) break ;;
    esac
    shift
done
[ $# -ge 1 ] || { sed -n '2,/^[^#]/ s/^# \{0,1\}//p' "$0"; exit 2; }
W=$1 T=${2:-2}
B=${BUILD:-build}
mkdir -p "$W" || exit 1
[ -x "$B/femdem_nonlocal" ] && [ -x "$B/csv_plot" ] || { echo "nonlocal_mesh_study: make $B/femdem_nonlocal $B/csv_plot first" >&2; exit 1; }
if [ $relaxed = 1 ]; then
    RUNS=${RUNS:-L4 L8 N8 M8 L12 M12}
    dem="--dem-max 4000" stop=3750 win=0.01
else
    RUNS=${RUNS:-L4 L8 L12 N8 N12 M8 M12}
    dem="--dem-max 20" stop=0 win=0
fi
K=${HOURGLASS:-0.1}
if [ -f "$W/hourglass" ]; then
    k0=$(cat "$W/hourglass")
    [ "$k0" = "$K" ] || { echo "nonlocal_mesh_study: $W was run with --hourglass $k0, not $K" >&2; exit 1; }
elif [ $report = 0 ]; then
    echo "$K" > "$W/hourglass" || exit 1
fi
run() { # NAME MESH R MIX [STOP]
    case " $RUNS " in *" $1 "*) ;; *) return 0 ;; esac
    [ -f "$W/$1/biaxial.csv" ] || [ $report = 1 ] && return 0
    "$B/femdem_nonlocal" --test biaxial --mesh "$2" --nonlocal "$3" --nonlocal-mix "$4" --dt 1.826e-6 \
        --steps 5000 --stop-after "${5:-$stop}" $dem --hourglass "$K" --vtk-every 750 \
        --threads "$T" --out "$W/$1" \
        > "$W/$1.log" 2>&1
    echo "$1: exit $?" >> "$W/status.txt"
    [ -f "$W/$1/biaxial.csv" ]
}
fail=0
run L4 4x8x1 off 1 || fail=1
run L8 8x16x1 off 1 || fail=1
run L12 12x24x1 off 1 || fail=1
run M8 8x16x1 6.75e-3 0.9 || fail=1
run M12 12x24x1 6.75e-3 0.9 || fail=1
run N8 8x16x1 6.75e-3 1 || fail=1
[ $relaxed = 1 ] || run N12 12x24x1 6.75e-3 1 1250 || fail=1 # to 2 %: the paper's average is unstable there
# the stress [kPa] of NAME's CSV at strain S: linear interpolation (20-step runs, smooth curves) or,
# relaxed, the mean of the rows over the 1 % of strain before S (the relaxed specimen rings, a row
# lies up to 30-220 kPa off its window's mean); nan beyond the run
at() {
    [ -f "$W/$1/biaxial.csv" ] || { printf nan; return; }
    awk -F, -v s="$2" -v win="$win" 'NR == 1 { for (c = 1; c <= NF; ++c) { if ($c == "strain") xs = c; if ($c == "stress") ys = c } next }
        { x = $xs; y = $ys; if (x >= s - 1e-9) f = 1
          if (win > 0) { if (x > s - win + 1e-9 && x <= s + 1e-9) { t += y; k++ } }
          else if (n && px <= s && s <= x && x > px) v = py + (y - py) * (s - px) / (x - px)
          px = x; py = y; n = 1 }
        END { if (win > 0) v = k ? t / k : 0; if (f) printf "%.0f", v / 1e3; else printf "nan" }' "$W/$1/biaxial.csv"
}
# relaxed: the peak [kPa] and its strain [%] as the largest mean of 5 consecutive rows (0.2 %)
peak_rows() {
    awk -F, 'NR == 1 { for (c = 1; c <= NF; ++c) { if ($c == "strain") xs = c; if ($c == "stress") ys = c } next }
        { x[n] = $xs; y[n] = $ys; n++ }
        END { for (i = 0; i + 5 <= n; ++i) { t = 0; for (j = i; j < i + 5; ++j) t += y[j]
                  if (t / 5 > m || i == 0) { m = t / 5; e = x[i + 2] } }
              printf "%.0f %.2f", m / 1e3, 100 * e }' "$W/$1/biaxial.csv"
}
# eps_q at step 3750 (6 %): max and the share of cells above half of it (the elements are equal)
band() {
    f="$W/$1/mesh_003750.vtk"
    [ -f "$f" ] || { printf "nan nan"; return; }
    awk '/^SCALARS eps_q/ { on = 1; getline; next } on && /^[A-Z]/ { on = 0 }
        on { for (i = 1; i <= NF; ++i) { v[n++] = $i; if ($i > m) m = $i } }
        END { for (i = 0; i < n; ++i) if (v[i] > 0.5 * m) k++; printf "%.3f %.3f", m, k / n }' "$f"
}
# the hourglass energy in % of the stress work at step 3750 (6 %)
hg_pct() {
    awk -F, 'NR == 1 { for (c = 1; c <= NF; ++c) { if ($c == "work_int") w = c; if ($c == "hourglass") h = c } next }
        w && $1 == 3750 && $w > 0 { v = 100 * $h / $w }
        END { if (v == "") printf "nan"; else printf "%.2f", v }' "$W/$1/biaxial.csv"
}
printf "%-4s %-8s %-6s %-4s %-8s %-15s %-9s %-9s %-7s %-6s %-6s %-6s %-6s %-6s %-6s %-6s %-9s %-6s %-9s %s\n" run mesh R_mm mix \
    symbol ended Ek_max_J peak_kPa at_% 2% 3% 4% 5% 6% 7% 8% eps_q_max share dem_steps hg_%
for r in $RUNS; do
    [ -f "$W/$r/biaxial.csv" ] || { printf "%-4s (no output)\n" "$r"; continue; }
    mesh=$(sed -n 's/^mesh \([0-9x]*\) .*/\1/p' "$W/$r.log" | head -n 1)
    R=$(sed -n 's/.*nonlocal [a-z]* (R \([^ ]*\) m, mix \([^,]*\),.*symbol min \([^)]*\)).*/\1 \2 \3/p' "$W/$r.log" | head -n 1)
    if grep -q '^RESULT' "$W/$r.log"; then
        ended=8%
        pk=$(sed -n 's/^RESULT.* peak_stress=\([^ ]*\) eps_at_peak=\([^ ]*\) .*/\1 \2/p' "$W/$r.log" |
            awk '{ printf "%.0f %.2f", $1 / 1e3, 100 * $2 }')
    else
        # the step it stopped at (5000 steps to 8 %)
        ended=$(sed -n 's/.*stopped at step \([0-9]*\) .*/failed@\1/p; s/^stopped after step \([0-9]*\) .*/stopped@\1/p' \
            "$W/$r.log" | awk -F@ 'NR == 1 { printf "%s@%.2f%%", $1, 0.08 * $2 / 50 }')
        pk="nan nan"
        [ $relaxed = 1 ] && pk=$(peak_rows "$r")
    fi
    ek=$(awk -F, 'NR == 1 { for (c = 1; c <= NF; ++c) if ($c == "kinetic") k = c; next }
        $3 <= 0.02 && $k > m { m = $k } END { printf "%.3g", m }' "$W/$r/biaxial.csv")
    printf "%-4s %-8s %-6s %-4s %-8s %-15s %-9s %-9s %-7s" "$r" "$mesh" $(echo "$R" | awk '{ printf "%g %g %.4f", $1 * 1e3, $2, $3 }') \
        "$ended" "$ek" $pk
    for s in 0.02 0.03 0.04 0.05 0.06 0.07 0.08; do printf " %-6s" "$(at "$r" $s)"; done
    printf " %-9s %-6s" $(band "$r")
    awk -F, 'NR == 1 { for (c = 1; c <= NF; ++c) if ($c == "dem_steps_mean") k = c; next }
        { t += $k; n++ } END { printf " %-9.0f", n ? t / n : 0 }' "$W/$r/biaxial.csv"
    printf " %s\n" "$(hg_pct "$r")"
done
# the spread over the meshes of each family, at every strain (the paper's average on the two
# meshes where it is stable, and local on the same two for comparison)
for fam in "local L4 L8 L12" "mix0.9 L4 M8 M12" "local-2 L4 L8" "paper-2 L4 N8"; do
    set -- $fam
    name=$1
    shift
    printf "spread %-8s" "$name"
    for s in 0.03 0.04 0.05 0.06 0.07 0.08; do
        v=""
        for r in "$@"; do v="$v $(at "$r" $s)"; done
        printf " %s%%:%s" "$(echo "$s" | awk '{ print 100 * $1 }')" "$(echo "$v" |
            awk '{ if ($0 ~ /nan/) { printf "nan"; exit } m = $1; M = $1; t = 0
                   for (i = 1; i <= NF; ++i) { if ($i < m) m = $i; if ($i > M) M = $i; t += $i }
                   printf "%.1f%%", 100 * (M - m) / (t / NF) }')"
    done
    echo
done
set --
for r in $RUNS; do [ -f "$W/$r/biaxial.csv" ] && set -- "$@" "$W/$r/biaxial.csv=$r"; done
"$B/csv_plot" --x strain --y stress --x-scale 100 --y-scale 1e-3 --xlabel "axial strain [%]" \
    --ylabel "axial stress [kPa]" --title "biaxial mesh study: local (L), nonlocal R 6.75 mm (N), mix 0.9 (M)" \
    --out "$W/mesh_study.svg" "$@" || fail=1
exit $fail
