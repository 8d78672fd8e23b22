#!/bin/sh
# run_box.sh - the grainkit scene benchmark (bench_scene_box: spheres poured
# into a box under gravity, then compressed by a moving lid) next to the same
# scene in LAMMPS (bench/peers/lammps_box.in). LAMMPS is skipped with a
# SKIP line when `lmp` is not installed (exit status 0); a failing grainkit
# run or write makes the script fail (exit status 1).
#
# Both codes pour the exact same atoms (bench_scene_box --write-data) with
# the same law, dt and walls (bench/scene_box.c, header), and both compress
# the exact same settled packing: the one grainkit poured, as a data file
# (--write-settled: positions and radii; velocities and spins zero, no
# contact history in either code), under the same lid (start and speed).
# Compared: the law alone (bench_scene_box --impact: an oblique sphere-floor
# and an oblique sphere-sphere impact without gravity, velocities and spins
# after them), the packing height after pouring (2 x the mean centre height,
# and the highest centre; the two pours diverge chaotically, so this is a
# statistical comparison), the lid force at 20 points of the compression
# (equal lid travel), and the bed's stiffness once jammed; speed as
# particle-steps/s per core (grainkit 1 thread, LAMMPS 1 MPI rank), wall
# clock and CPU time of each phase, measured one after the other in this
# run (paired): quote the ratios of a run on a quiet machine.
#
# The compression is itself chaotic (force chains buckle): moving one sphere
# of the settled packing by 1 nm changes the lid force at a given travel by
# a few per cent in either code. BOX_ENSEMBLE=k (default 0) therefore also
# compresses k copies of the settled packing, copy s with sphere
# 1 + (617 s mod n) moved by (-1)^(s+1) nm along y, in both codes, and
# compares the means over the k + 1 starts (mean +- standard deviation;
# the difference of the means +- its standard error). Cost per member:
# one compression in each code (about 20 CPU seconds together).
#
# Environment: BOX_NX (10), BOX_NZ (20), BOX_POUR (40000), BOX_COMP (30000),
# BOX_ENSEMBLE (0), BOX_WORK (build/peers_box).
set -u
cd "$(dirname "$0")/../.." || exit 1
BENCH=build/bench_scene_box
WORK=${BOX_WORK:-build/peers_box}
NX=${BOX_NX:-10}
NZ=${BOX_NZ:-20}
POUR=${BOX_POUR:-40000}
COMP=${BOX_COMP:-30000}
ENS=${BOX_ENSEMBLE:-0}
if [ ! -x "$BENCH" ]; then
    echo "run_box: $BENCH missing (make $BENCH)" >&2
    exit 1
fi
case "$ENS" in '' | *[!0-9]*)
    echo "run_box: BOX_ENSEMBLE must be a count (got '$ENS')" >&2
    exit 1
    ;;
esac
mkdir -p "$WORK" || exit 1
NPROC=$(nproc 2>/dev/null || echo 0)
loadavg() { cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo '?'; }
kv() { printf '%s\n' "$2" | tr ' ' '\n' | sed -n "s/^$1=//p" | head -n 1; }
echo "run_box: $(date -u '+%Y-%m-%d %H:%M UTC'), $NPROC cores, load average $(loadavg); $NX x $NX x $NZ spheres, $POUR + $COMP steps"

"$BENCH" --nx "$NX" --nz "$NZ" --pour "$POUR" --compress "$COMP" --write-data "$WORK/box.data" \
    --write-settled "$WORK/settled.data" >"$WORK/grainkit.out" 2>&1 || {
    echo "run_box: grainkit failed:" >&2
    cat "$WORK/grainkit.out" >&2
    exit 1
}
"$BENCH" --impact --write-data "$WORK/impact.data" >>"$WORK/grainkit.out" 2>&1 || {
    echo "run_box: grainkit failed (impacts):" >&2
    cat "$WORK/grainkit.out" >&2
    exit 1
}
cat "$WORK/grainkit.out"
GP=$(grep 'phase=pour' "$WORK/grainkit.out")
GC=$(grep 'phase=compress' "$WORK/grainkit.out")
GI=$(grep '^IMPACT' "$WORK/grainkit.out")

if ! command -v lmp >/dev/null 2>&1; then
    echo "SKIP peer=lammps: lmp not found (Debian: apt-get install lammps)"
    exit 0
fi
# the law's constants (bench/scene_box.c): R 1 mm, rho 2650, kn 1e4, kt 0.5 kn, mu 0.5, e 0.5, dt 5e-6, skin 0.1 mm
L=$(awk -v nx="$NX" 'BEGIN {printf "%.17g", nx * 2.4e-3}')
ETAP=$(awk 'BEGIN {pi = 3.141592653589793; m = 2650 * 4 / 3 * pi * 1e-9; l = log(0.5); z = -l / sqrt(pi * pi + l * l);
                   printf "%.17g", 2 * z * sqrt(2 * 1e4 / m)}')
ETAW=$(awk 'BEGIN {pi = 3.141592653589793; m = 2650 * 4 / 3 * pi * 1e-9; l = log(0.5); z = -l / sqrt(pi * pi + l * l);
                   printf "%.17g", 2 * z * sqrt(1e4 / m)}')
lammps() { # phase data-file log [-var name value ...]
    ph=$1 dat=$2 log=$3
    shift 3
    OMP_NUM_THREADS=1 lmp -log none -echo none -in bench/peers/lammps_box.in -var phase "$ph" -var data "$dat" \
        -var kn 1e4 -var kt 5e3 -var mu 0.5 -var etap "$ETAP" -var etaw "$ETAW" -var dt 5e-6 \
        -var skin 1e-4 "$@" >"$log" 2>&1
}
Z0=$(kv lid_start "$GC")
# the lid force at the thermo lines of a compression log after step 0, on one line
lammps_forces() { awk '/^ *Step +Atoms +v_F/ {on = 1; next} on && /^Loop time/ {on = 0} on && NF == 4 && $1 > 0 {printf "%s ", $3}' "$1"; }
grainkit_forces() { k=1; while [ $k -le 20 ]; do printf '%s ' "$(kv "lid_force_$k" "$1")"; k=$((k + 1)); done; }
lammps pour "$WORK/box.data" "$WORK/lammps_pour.log" -var L "$L" -var pour "$POUR"
lammps compress "$WORK/settled.data" "$WORK/lammps_compress.log" -var L "$L" -var comp "$COMP" -var z0 "$Z0" -var vlid 0.02
lammps impact "$WORK/impact.data" "$WORK/lammps_impact.log" -var L 0.024
for f in pour:POUR compress:LIDEND impact:IMPACT; do
    if ! grep -q "^${f#*:}" "$WORK/lammps_${f%%:*}.log"; then
        echo "FAIL peer=lammps: no result, see $WORK/lammps_${f%%:*}.log"
        grep -E 'ERROR' "$WORK/lammps_${f%%:*}.log" | head -n 3
        exit 0
    fi
done
# loop time and CPU seconds ("Loop time" x the "% CPU use" LAMMPS reports) of a log
looptime() { grep '^Loop time of' "$1" | awk '{print $4}'; }
cputime() { awk '/^Loop time of/ {t = $4} /CPU use with/ {for (i = 1; i <= NF; ++i) if ($i ~ /%$/) {c = $i; sub("%", "", c); print t * c / 100}}' "$1"; }
TP=$(looptime "$WORK/lammps_pour.log")
TC=$(looptime "$WORK/lammps_compress.log")
CPP=$(cputime "$WORK/lammps_pour.log")
CPC=$(cputime "$WORK/lammps_compress.log")
POURL=$(grep '^POUR' "$WORK/lammps_pour.log")
LF=$(lammps_forces "$WORK/lammps_compress.log")
n=$(kv n "$GP")
echo "LAMMPS phase=pour seconds=$TP particle_steps_per_s=$(awk -v n="$n" -v s="$POUR" -v t="$TP" 'BEGIN {printf "%.4g", n*s/t}') $(echo "$POURL" | cut -d' ' -f2-)"
echo "LAMMPS phase=compress seconds=$TC particle_steps_per_s=$(awk -v n="$n" -v s="$COMP" -v t="$TC" 'BEGIN {printf "%.4g", n*s/t}') start=settled lid_forces=$(echo $LF | tr ' ' ',')"
echo
echo "Physics, grainkit vs LAMMPS (same law and dt):"
LI=$(grep '^IMPACT' "$WORK/lammps_impact.log")
echo "  the law alone (no gravity; sphere 1 hits the floor, 2 hits 3 obliquely): velocities [m/s], spins [rad/s] after the impacts"
for q in vx1 vz1 wy1 vx2 vz2 wy2 vx3 vz3 wy3; do
    awk -v q="$q" -v g="$(kv "$q" "$GI")" -v l="$(kv "$q" "$LI")" 'BEGIN {
        printf "    %-4s %12.8g %12.8g  %+.4f %%\n", q, g, l, (l != 0 ? 100 * (g - l) / (l < 0 ? -l : l) : 0) }'
done
echo "    (the definitions that differ: bench/peers/RESULTS_box.md, \"Same law\")"
awk -v gz="$(kv zmean "$GP")" -v gx="$(kv zmax "$GP")" -v lz="$(kv zmean "$POURL")" -v lx="$(kv zmax "$POURL")" 'BEGIN {
    printf "  pour (same starting atoms): packing height 2<z> %.6g vs %.6g mm (%+.2f %%); highest centre %.6g vs %.6g mm (%+.2f %%)\n",
        2e3*gz, 2e3*lz, 100*(gz-lz)/lz, 1e3*gx, 1e3*lx, 100*(gx-lx)/lx }'
GF=$(grainkit_forces "$GC")
awk -v g="$GF" -v l="$LF" -v steps="$COMP" 'BEGIN {
    ng = split(g, G, " "); nl = split(l, Lf, " "); dz = 0.02 * 5e-6 * steps / 20
    printf "  compression (same settled packing, same lid): lid force at equal travel\n"
    printf "    %8s %12s %12s %9s\n", "travel", "grainkit", "LAMMPS", "diff"
    for (k = 1; k <= ng && k <= nl; ++k) {
        d = (Lf[k] >= 1 ? sprintf("%+.2f %%", 100 * (G[k] - Lf[k]) / Lf[k]) : "")
        printf "    %5.2f mm %10.4g N %10.4g N %9s\n", 1e3 * k * dz, G[k], Lf[k], d
    }
    # stiffness once jammed: least-squares slope of force vs travel over the last 5 points
    for (c = 0; c < 2; ++c) {
        sx = sy = sxx = sxy = 0
        for (k = ng - 4; k <= ng; ++k) {
            x = 1e3 * k * dz; y = c ? Lf[k] : G[k]
            sx += x; sy += y; sxx += x * x; sxy += x * y
        }
        S[c] = (5 * sxy - sx * sy) / (5 * sxx - sx * sx)
    }
    printf "  stiffness once jammed (slope over the last 5 points, %.2f-%.2f mm): %.4g vs %.4g N/mm %s\n",
        1e3 * (ng - 4) * dz, 1e3 * ng * dz, S[0], S[1], (S[1] > 0 ? sprintf("(%+.2f %%)", 100 * (S[0] - S[1]) / S[1]) : "")
}'
echo "Speed, particle-steps/s per core, grainkit / LAMMPS (wall clock; CPU time in brackets, less hurt by a shared machine):"
awk -v a="$(kv particle_steps_per_s "$GP")" -v n="$n" -v s="$POUR" -v t="$TP" -v gc="$(kv cpu_seconds "$GP")" -v lc="$CPP" 'BEGIN {
    b = n*s/t; printf "  pour:     %.4g vs %.4g: %.2fx  (CPU %.4g vs %.4g s: %.2fx)\n", a, b, a/b, gc, lc, lc/gc}'
awk -v a="$(kv particle_steps_per_s "$GC")" -v n="$n" -v s="$COMP" -v t="$TC" -v gc="$(kv cpu_seconds "$GC")" -v lc="$CPC" 'BEGIN {
    b = n*s/t; printf "  compress: %.4g vs %.4g: %.2fx  (CPU %.4g vs %.4g s: %.2fx)\n", a, b, a/b, gc, lc, lc/gc}'
if [ "$ENS" -gt 0 ]; then
    echo "Ensemble: the settled packing and $ENS copies with one sphere moved by 1 nm, compressed in both codes:"
    { echo "g $GF"; echo "l $LF"; } >"$WORK/ensemble.txt"
    s=1
    while [ "$s" -le "$ENS" ]; do
        m="$WORK/member$s.data"
        awk -v id=$((1 + (617 * s) % n)) -v e="$([ $((s % 2)) -eq 1 ] && echo 1e-9 || echo -1e-9)" \
            'on && NF == 7 && $1 == id {$6 = sprintf("%.17g", $6 + e)} /^Atoms/ {on = 1} {print}' \
            "$WORK/settled.data" >"$m" || exit 1
        "$BENCH" --nx "$NX" --nz "$NZ" --compress "$COMP" --from "$m" >"$WORK/member$s.out" 2>&1 || {
            echo "run_box: grainkit failed on $m:" >&2
            cat "$WORK/member$s.out" >&2
            exit 1
        }
        lammps compress "$m" "$WORK/lammps_member$s.log" -var L "$L" -var comp "$COMP" -var z0 "$Z0" -var vlid 0.02
        if ! grep -q '^LIDEND' "$WORK/lammps_member$s.log"; then
            echo "FAIL peer=lammps: no result, see $WORK/lammps_member$s.log"
            exit 0
        fi
        echo "g $(grainkit_forces "$(grep 'phase=compress' "$WORK/member$s.out")")" >>"$WORK/ensemble.txt"
        echo "l $(lammps_forces "$WORK/lammps_member$s.log")" >>"$WORK/ensemble.txt"
        s=$((s + 1))
    done
    awk -v steps="$COMP" -v want=$((ENS + 1)) '
    { c = ($1 == "l"); if (NF != 21) next; ++N[c]
      for (k = 1; k <= 20; ++k) { S[c, k] += $(k + 1); Q[c, k] += $(k + 1) ^ 2 }
      sx = sy = sxx = sxy = 0
      for (k = 16; k <= 20; ++k) { x = 1e3 * k * dz; y = $(k + 1); sx += x; sy += y; sxx += x * x; sxy += x * y }
      st = (5 * sxy - sx * sy) / (5 * sxx - sx * sx); S[c, 0] += st; Q[c, 0] += st ^ 2 }
    BEGIN { dz = 0.02 * 5e-6 * steps / 20 }
    function line(label, k, unit,   m0, m1, s0, s1, e) {
        m0 = S[0, k] / N[0]; m1 = S[1, k] / N[1]
        s0 = sqrt((Q[0, k] - N[0] * m0 ^ 2) / (N[0] - 1)); s1 = sqrt((Q[1, k] - N[1] * m1 ^ 2) / (N[1] - 1))
        e = sqrt(s0 ^ 2 / N[0] + s1 ^ 2 / N[1])
        printf "    %-10s %8.4g +- %-7.3g %8.4g +- %-7.3g %s\n", label, m0, s0, m1, s1,
            (m1 > 0 ? sprintf("%+6.2f +- %.2f %%", 100 * (m0 - m1) / m1, 100 * e / m1) : "-")
    }
    END {
        if (N[0] != want || N[1] != want) { printf "  ensemble incomplete (%d and %d of %d members)\n", N[0], N[1], want; exit 1 }
        printf "  means over %d starts (+- standard deviation), difference of the means (+- its standard error):\n", want
        printf "    %-10s %19s %19s %16s\n", "travel", "grainkit [N]", "LAMMPS [N]", "difference"
        for (k = 13; k <= 20; ++k) line(sprintf("%.2f mm", 1e3 * k * dz), k)
        line("stiffness", 0)
        printf "    (stiffness in N/mm: slope over the last 5 points)\n"
    }' "$WORK/ensemble.txt" || exit 1
fi
awk -v l="$(loadavg)" -v c="$NPROC" 'BEGIN {
    printf "run_box: load average at the end %s%s\n", l, (c > 0 && l + 0 > c) ? " (above the core count: other jobs shared the cores)" : "" }'
exit 0
