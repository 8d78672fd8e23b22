#!/bin/sh
# run_box.sh - the grainkit scene benchmark (bench_scene_box: spheres poured
# into a box under gravity, then compressed by a moving lid) next to the same
# scene in LAMMPS (bench/peers/lammps_box.in). LAMMPS is skipped with a
# message when `lmp` is not installed (exit status 0); only a failing
# grainkit run makes the script fail.
#
# Both codes start from the exact same atoms (bench_scene_box --write-data)
# with the same law, dt and walls (bench/scene_box.c, header). Compared: the
# packing height after pouring (2 x the mean centre height, and the highest
# centre), the lid force at 20 points of the compression (equal travel from
# 1 mm above each code's own 2<z> + R) and the lid's height (the compressed
# packing's) at equal lid forces - the two pours differ chaotically, so the
# bed jams at slightly different lid heights and the steep force curve
# magnifies that at equal travel, not at equal force; speed as
# particle-steps/s per core (grainkit 1 thread, LAMMPS 1 MPI rank), wall
# clock and CPU time of each phase, measured one after the other in this
# run (paired): on a shared machine quote the ratio of a quiet run.
#
# Environment: BOX_NX (10), BOX_NZ (20), BOX_POUR (40000), BOX_COMP (30000),
# BOX_WORK (build/peers_box).
set -u
cd "$(dirname "$0")/../.." || exit 1
BENCH=build/bench_scene_box
WORK=${BOX_WORK:-build/peers_box}
NX=${BOX_NX:-10}
NZ=${BOX_NZ:-20}
POUR=${BOX_POUR:-40000}
COMP=${BOX_COMP:-30000}
if [ ! -x "$BENCH" ]; then
    echo "run_box: $BENCH missing (make $BENCH)" >&2
    exit 1
fi
mkdir -p "$WORK" || exit 1
loadavg() { cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo '?'; }
kv() { printf '%s\n' "$2" | tr ' ' '\n' | sed -n "s/^$1=//p" | head -n 1; }
echo "run_box: $(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc 2>/dev/null || echo '?') cores, load average $(loadavg); $NX x $NX x $NZ spheres, $POUR + $COMP steps"

"$BENCH" --nx "$NX" --nz "$NZ" --pour "$POUR" --compress "$COMP" --write-data "$WORK/box.data" >"$WORK/grainkit.out" 2>&1 || {
    echo "run_box: grainkit failed:" >&2
    cat "$WORK/grainkit.out" >&2
    exit 1
}
cat "$WORK/grainkit.out"
GP=$(grep 'phase=pour' "$WORK/grainkit.out")
GC=$(grep 'phase=compress' "$WORK/grainkit.out")

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
OMP_NUM_THREADS=1 lmp -log none -echo none -in bench/peers/lammps_box.in -var data "$WORK/box.data" -var L "$L" \
    -var kn 1e4 -var kt 5e3 -var mu 0.5 -var etap "$ETAP" -var etaw "$ETAW" -var dt 5e-6 -var skin 1e-4 \
    -var pour "$POUR" -var comp "$COMP" -var vlid 0.02 -var R 1e-3 >"$WORK/lammps.log" 2>&1
if ! grep -q '^LIDEND' "$WORK/lammps.log"; then
    echo "FAIL peer=lammps: no result, see $WORK/lammps.log"
    grep -E 'ERROR' "$WORK/lammps.log" | head -n 3
    exit 0
fi
# loop times and the lid force at the thermo lines of the second run
LT=$(grep '^Loop time of' "$WORK/lammps.log" | awk '{print $4}')
TP=$(echo "$LT" | sed -n 1p)
TC=$(echo "$LT" | sed -n 2p)
POURL=$(grep '^POUR' "$WORK/lammps.log")
LF=$(awk '/^ *Step +Atoms +v_F/ {on = 1; next} on && /^Loop time/ {on = 0} on && NF == 4 && $1 > 0 {print $3}' "$WORK/lammps.log")
# CPU seconds of each run: "Loop time" x the "% CPU use" LAMMPS reports
CP=$(awk '/^Loop time of/ {t = $4} /CPU use with/ {for (i = 1; i <= NF; ++i) if ($i ~ /%$/) {c = $i; sub("%", "", c); print t * c / 100}}' "$WORK/lammps.log")
CPP=$(echo "$CP" | sed -n 1p)
CPC=$(echo "$CP" | sed -n 2p)
n=$(kv n "$GP")
echo "LAMMPS phase=pour seconds=$TP particle_steps_per_s=$(awk -v n="$n" -v s="$POUR" -v t="$TP" 'BEGIN {printf "%.4g", n*s/t}') $(echo "$POURL" | cut -d' ' -f2-)"
echo "LAMMPS phase=compress seconds=$TC particle_steps_per_s=$(awk -v n="$n" -v s="$COMP" -v t="$TC" 'BEGIN {printf "%.4g", n*s/t}') lid_forces=$(echo $LF | tr ' ' ',')"
echo
echo "Physics (grainkit vs LAMMPS, same atoms, law, dt):"
awk -v gz="$(kv zmean "$GP")" -v gx="$(kv zmax "$GP")" -v lz="$(kv zmean "$POURL")" -v lx="$(kv zmax "$POURL")" 'BEGIN {
    printf "  packing height 2<z>: %.6g vs %.6g m (%+.2f %%); highest centre %.6g vs %.6g m (%+.2f %%)\n",
        2*gz, 2*lz, 100*(gz-lz)/lz, gx, lx, 100*(gx-lx)/lx }'
# the lid force at equal travel, and the lid height (the compressed packing's height) at equal force
GF=$(k=1; while [ $k -le 20 ]; do kv "lid_force_$k" "$GC"; k=$((k + 1)); done | tr '\n' ' ')
awk -v g="$GF" -v l="$LF" -v gz0="$(kv lid_start "$GC")" -v lz0="$(kv zmean "$POURL")" -v steps="$COMP" 'BEGIN {
    ng = split(g, G, " "); nl = split(l, Lf, " "); dz = 0.02 * 5e-6 * steps / 20; lz0 = 2 * lz0 + 1e-3 + 1e-3
    printf "  lid force at equal travel (every %.3g mm), grainkit vs LAMMPS:\n   ", 1e3 * dz
    for (k = 1; k <= ng && k <= nl; ++k) printf " %.4g/%.4g", G[k], Lf[k]
    printf " N\n"
    split("2 5 10 20 30", F, " ")
    for (q = 1; q <= 5; ++q) {
        zg = zl = 0
        for (k = 2; k <= ng; ++k) if (!zg && G[k] >= F[q]) zg = gz0 - dz * (k - 1 + (F[q] - G[k-1]) / (G[k] - G[k-1]))
        for (k = 2; k <= nl; ++k) if (!zl && Lf[k] >= F[q]) zl = lz0 - dz * (k - 1 + (F[q] - Lf[k-1]) / (Lf[k] - Lf[k-1]))
        if (zg && zl) printf "  lid height at a lid force of %g N: %.5g vs %.5g mm (%+.2f %%)\n", F[q], 1e3 * zg, 1e3 * zl, 100 * (zg - zl) / zl
    }
}'
echo "Speed, particle-steps/s per core, grainkit / LAMMPS (wall clock; CPU time in brackets, less hurt by a shared machine):"
awk -v a="$(kv particle_steps_per_s "$GP")" -v n="$n" -v s="$POUR" -v t="$TP" -v gc="$(kv cpu_seconds "$GP")" -v lc="$CPP" 'BEGIN {
    b = n*s/t; printf "  pour:     %.4g vs %.4g: %.2fx  (CPU %.4g vs %.4g s: %.2fx)\n", a, b, a/b, gc, lc, lc/gc}'
awk -v a="$(kv particle_steps_per_s "$GC")" -v n="$n" -v s="$COMP" -v t="$TC" -v gc="$(kv cpu_seconds "$GC")" -v lc="$CPC" 'BEGIN {
    b = n*s/t; printf "  compress: %.4g vs %.4g: %.2fx  (CPU %.4g vs %.4g s: %.2fx)\n", a, b, a/b, gc, lc, lc/gc}'
echo "run_box: load average at the end $(loadavg) (above the core count: other jobs shared the cores)"
exit 0
