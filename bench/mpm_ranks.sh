#!/bin/sh
# mpm_ranks.sh - the MPMxDEM footing's RVEs on 2 MPI ranks against 2 OpenMP threads.
#
#   make build/mpmdem_footing mpi && bench/mpm_ranks.sh [STEPS] [REPEATS]
#   (GK_MPIRUN: the mpirun command and its flags; default mpirun --oversubscribe)
#
# Runs the default footing of mpmdem_footing (30 x 15 cells, 450 RVEs of 400
# disks; --phi-deg 30 skips the friction-angle tests) for STEPS MPM steps
# (default 60) in three configurations, one right after the other, REPEATS
# times (default 3):
#   1x1  build/mpmdem_footing --threads 1
#   1x2  build/mpmdem_footing --threads 2
#   2x1  $GK_MPIRUN -np 2 build/mpmdem_footing_mpi --threads 1
# For each run: seconds per MPM step without the first step (the one-off
# relaxation of every RVE: RESULT seconds_per_step_per_1000_rves_after_first
# x 0.45), the bytes all ranks sent per MPM step and the RVE migrations of the
# load balance (the driver's "MPI:" line). For each repeat the paired ratios
# (the three runs of a repeat meet the same load from other jobs):
#   speedup of 2 threads t(1x1)/t(1x2), of 2 ranks t(1x1)/t(2x1),
#   efficiency of 2 ranks t(1x1) / (2 t(2x1)), ranks against threads t(1x2)/t(2x1).
# It also checks that the three give the same footing.csv (every column but
# seconds). Wall-clock figures want an otherwise idle machine.
set -u
STEPS=${1:-60}
REP=${2:-3}
W=${BENCH_DIR:-build/bench_mpm_ranks}
ARGS="--phi-deg 30 --max-steps $STEPS --quiet"
# mpirun and its flags: Open MPI refuses root without --allow-run-as-root and more ranks than it
# counts cores without --oversubscribe
if [ -z "${GK_MPIRUN:-}" ]; then
    GK_MPIRUN="mpirun --oversubscribe"
    [ "$(id -u)" = 0 ] && GK_MPIRUN="$GK_MPIRUN --allow-run-as-root"
fi
[ -x build/mpmdem_footing ] && [ -x build/mpmdem_footing_mpi ] || {
    echo "mpm_ranks.sh: needs build/mpmdem_footing and build/mpmdem_footing_mpi (make build/mpmdem_footing mpi: mpicc)"
    exit 2
}
mkdir -p "$W" || exit 1
# seconds per step after the first, bytes per step, migrations of one run's output
stats() {
    awk '/^RESULT / { for (i = 1; i <= NF; ++i) if ($i ~ /^seconds_per_step_per_1000_rves_after_first=/) { split($i, a, "="); t = a[2] * 0.45 } }
         /^MPI ranks=/ { for (i = 1; i <= NF; ++i) { split($i, a, "="); if (a[1] == "bytes_sent_per_step") b = a[2]; if (a[1] == "point_moves") m = a[2] } }
         END { printf "%.6g %s %s", t, b, m }' "$1"
}
strip() { cut -d, -f1-8 "$1"; }
echo "footing, 450 RVEs, $STEPS MPM steps, $REP repeats (s/step after the first; bytes/step; migrations)"
for r in $(seq 1 "$REP"); do
    build/mpmdem_footing $ARGS --threads 1 --out "$W/1x1" > "$W/1x1.out" 2>&1 || echo "1x1 failed"
    build/mpmdem_footing $ARGS --threads 2 --out "$W/1x2" > "$W/1x2.out" 2>&1 || echo "1x2 failed"
    $GK_MPIRUN -np 2 build/mpmdem_footing_mpi $ARGS --threads 1 --out "$W/2x1" > "$W/2x1.out" 2>&1 || echo "2x1 failed"
    set -- $(stats "$W/1x1.out") $(stats "$W/1x2.out") $(stats "$W/2x1.out")
    awk -v r="$r" -v a="$1" -v b="$4" -v c="$7" -v cb="$8" -v cm="$9" 'BEGIN {
        printf "repeat %s: 1x1 %.4g s, 1x2 %.4g s, 2x1 %.4g s (%.0f bytes/step, %d migrations) | 2 threads %.3fx, 2 ranks %.3fx, 2-rank efficiency %.1f %%, ranks/threads %.3f\n",
               r, a, b, c, cb, cm, a / b, a / c, 100 * a / (2 * c), b / c }'
    for k in 1x2 2x1; do
        strip "$W/$k/footing.csv" > "$W/$k.strip"
        strip "$W/1x1/footing.csv" | cmp -s - "$W/$k.strip" || echo "DIFFERENT footing.csv: 1x1 and $k"
    done
done
