#!/bin/sh
# run_peers.sh - the grainkit DEM step benchmark next to the same workload in
# LAMMPS, LIGGGHTS and YADE (make bench-peers). Peers that are not installed
# are skipped with a message (exit status 0); only a failing grainkit run
# makes the script fail.
#
# Workload, identical in every code (bench/data/README.md): linear contacts
# with constant kn = 2e5 N/m, kt = 0.5 kn, Coulomb mu = 0.5, no damping,
# density 2650 with sphere masses (also in 2D), dt = 2.7e-6 s, simple shear
# vx = 1.5 y (Lees-Edwards / deforming periodic cell), neighbour skin 0.5 mm.
# Every code starts from the exact packing grainkit starts from
# (bench_dem_step --write-packing), with the affine velocity field, runs
# W = S/10 + 10 warm-up steps and then R timed repeats of S steps (median),
# and reports contacts and stress at the end, so the physics is compared at
# the same step.
#
# Cases: 3d_10k (bench/data/bench3d_20k.txt, 20 000 spheres), 3d_1k,
# 2d_10k, rve400 (the 400-disk seed-000 packing run with the peers' workload
# above, not with its own YADE material, which LAMMPS's constant-kn Hooke law
# and lack of local damping cannot express).
#
# Environment:
#   PEERS_CASES    cases to run ("3d_10k 3d_1k 2d_10k rve400")
#   PEERS_STEPS    timed steps per repeat for every case (default per case:
#                  3d_10k 200, 3d_1k 1000, 2d_10k 300, rve400 2500: YADE,
#                  at ~0.8 M particle-steps/s, sets the pace; about 3 min)
#   PEERS_REPEATS  timed repeats (3)
#   PEERS_LIST     codes to run ("grainkit lammps liggghts yade")
#   PEERS_WORK     scratch directory (build/peers)
#   PEERS_MPIRUN   MPI launcher for the 2-rank LAMMPS run (mpirun)
#   PEERS_THREADS  thread / rank counts ("1 2"); "1" alone runs every code on
#                  one core, e.g. under `taskset -c 1` on a machine whose cores
#                  run at unequal speeds
#
# LAMMPS also runs once more on one rank in an orthogonal box under pure shear
# at the same rate from rest (peer lammps_pure, its faster box): a speed
# reference only, since its stress is not that of the simple shear; packings
# whose cell is skewed skip it.
#
# Output: one "PEER peer=... case=... ranks=... n=... steps=...
# particle_steps_per_s=... contact_steps_per_s=... pair_fraction=...
# contacts_per_particle=... sxx=... syy=... sxy=..." line per run (stress
# tension-positive at the end of the run; 2D in N/m), then a physics table and
# a ratio table grainkit/peer per case and thread (rank) count.
set -u
cd "$(dirname "$0")/../.." || exit 1
ROOT=$(pwd)
BENCH=build/bench_dem_step
PEERDIR=bench/peers
WORK=${PEERS_WORK:-build/peers}
CASES=${PEERS_CASES:-"3d_10k 3d_1k 2d_10k rve400"}
REPS=${PEERS_REPEATS:-3}
LIST=${PEERS_LIST:-"grainkit lammps liggghts yade"}
MPIRUN=${PEERS_MPIRUN:-mpirun}
THREADS=${PEERS_THREADS:-"1 2"}
case " $THREADS " in
*" 1 "*) ;;
*) echo "run_peers: PEERS_THREADS='$THREADS' must include 1 (the one-thread run writes the packing)" >&2; exit 2 ;;
esac
for th in $THREADS; do
    case $th in 1 | 2) ;; *) echo "run_peers: PEERS_THREADS='$THREADS': counts are 1 and 2" >&2; exit 2 ;; esac
done
RES=$WORK/results.txt

if [ ! -x "$BENCH" ]; then
    echo "run_peers: $BENCH missing (make $BENCH)" >&2
    exit 1
fi
mkdir -p "$WORK" || exit 1
: >"$RES"

have() { command -v "$1" >/dev/null 2>&1; }
wants() { case " $LIST " in *" $1 "*) return 0 ;; esac; return 1; }

steps_for() {
    if [ -n "${PEERS_STEPS:-}" ]; then echo "$PEERS_STEPS"; return; fi
    case $1 in
    3d_10k) echo 200 ;; 3d_1k) echo 1000 ;; 2d_10k) echo 300 ;; rve400) echo 2500 ;;
    *) echo 200 ;;
    esac
}

# median of the numbers on stdin (one per line)
median() { sort -g | awk '{a[NR]=$1} END{if(NR==0){print "nan"}else if(NR%2){print a[(NR+1)/2]}else{print 0.5*(a[NR/2]+a[NR/2+1])}}'; }

# key=value lookup in a line: kv KEY "line"
kv() { printf '%s\n' "$2" | tr ' ' '\n' | sed -n "s/^$1=//p" | head -n 1; }

emit() { # the PEER line, also kept in $RES
    printf '%s\n' "$1" | tee -a "$RES"
}

skip() { printf 'SKIP %s\n' "$1" | tee -a "$RES"; }

# LAMMPS / LIGGGHTS log -> PEER line. $1 peer $2 case $3 ranks $4 steps $5 log $6 note
parse_lmp() {
    peer=$1 cs=$2 ranks=$3 st=$4 log=$5 note=$6
    nloop=$(grep -c '^Loop time of' "$log")
    if [ "$nloop" -lt 3 ] || ! grep -q '^PHYS ' "$log"; then
        echo "FAIL peer=$peer case=$cs ranks=$ranks: no result, see $log" | tee -a "$RES"
        grep -E 'ERROR|rror' "$log" | head -n 3
        return
    fi
    # loop times and Pair %total of the timed runs (run 0 and warm-up are the first two)
    awk '/^Loop time of/ {k++; t[k]=$4; for (i=1;i<NF;i++) if ($i=="with") n[k]=$(i+1)}
         /^Pair +\|/ {p[k]=$NF}
         /^Pair +time/ {x=$NF; gsub(/[()]/,"",x); p[k]=x}
         END {for (i=3;i<=k;i++) print t[i], (p[i]==""?"nan":p[i]), n[i]}' "$log" >"$log.t"
    sec=$(awk '{print $1}' "$log.t" | median)
    pf=$(awk '{print $2}' "$log.t" | median)
    n=$(tail -n 1 "$log.t" | awk '{print $3}')
    phys=$(grep '^PHYS ' "$log" | tail -n 1)
    phys0=$(grep '^PHYS0 ' "$log" | tail -n 1)
    c=$(kv contacts "$phys")
    c0=$(kv contacts "$phys0")
    awk -v peer="$peer" -v cs="$cs" -v r="$ranks" -v n="$n" -v st="$st" -v sec="$sec" -v pf="$pf" -v c="$c" -v c0="$c0" \
        -v pxx="$(kv pxx "$phys")" -v pyy="$(kv pyy "$phys")" -v pxy="$(kv pxy "$phys")" -v note="$note" \
        -v p0="$(kv pxx "$phys0")" -v q0="$(kv pyy "$phys0")" 'BEGIN {
        printf "PEER peer=%s case=%s ranks=%s n=%d steps=%d particle_steps_per_s=%.4g contact_steps_per_s=%.4g pair_fraction=%s contacts_per_particle=%.3f sxx=%.6g syy=%.6g sxy=%.6g contacts_per_particle_start=%.3f sxx_start=%.6g syy_start=%.6g seconds_median=%.4g note=%s\n",
            peer, cs, r, n, st, n*st/sec, c*st/sec, (pf=="nan"?"-":sprintf("%.3f", pf/100)), c/n, -pxx, -pyy, -pxy, c0/n, -p0, -q0, sec, note }' |
        tee -a "$RES"
}

# LAMMPS on the peer input: lmp_run DATA LOG [-var NAME VALUE ...] after LMP_LAUNCH="" (one
# process) or LMP_LAUNCH="mpirun flags -np N"; dim, W, S, REPS are the case's
lmp_run() {
    lr_data=$1 lr_log=$2
    shift 2
    # shellcheck disable=SC2086
    OMP_NUM_THREADS=1 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 $LMP_LAUNCH \
        lmp -log none -echo none -in $PEERDIR/lammps.in -var data "$lr_data" -var dim "$dim" -var warm "$W" \
        -var steps "$S" -var reps "$REPS" "$@" >"$lr_log" 2>&1
}

loadavg() { cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo '?'; }
echo "run_peers: $(date -u '+%Y-%m-%d %H:%M UTC'), $(uname -m), $(nproc 2>/dev/null || echo '?') cores, load average $(loadavg); cases: $CASES; repeats $REPS"
have python3 || echo "run_peers: python3 not found: LAMMPS and LIGGGHTS (need the data-file converter) will be skipped"
MPI_FLAGS=""
if have "$MPIRUN" && "$MPIRUN" --version 2>&1 | grep -q 'Open MPI'; then
    MPI_FLAGS="--oversubscribe --bind-to none"
    if [ "$(id -u)" = 0 ]; then MPI_FLAGS="$MPI_FLAGS --allow-run-as-root"; fi
fi

for cs in $CASES; do
    S=$(steps_for "$cs")
    W=$((S / 10 + 10))
    pk=$WORK/$cs.txt
    case $cs in
    rve400) gargs="--case 2d_10k --packing examples/data/rve400.txt" ;;
    *) gargs="--case $cs" ;;
    esac
    echo
    echo "== case $cs: $S timed steps x $REPS repeats after $W warm-up steps"
    # grainkit first: it also writes the exact starting packing
    for th in $THREADS; do
        if [ "$th" = 2 ] && ! wants grainkit; then continue; fi
        wp=""
        [ "$th" = 1 ] && wp="--write-packing $pk"
        # shellcheck disable=SC2086
        line=$("$BENCH" $gargs --threads "$th" --steps "$S" --repeats "$REPS" $wp | grep '^BENCH')
        if [ -z "$line" ]; then
            echo "run_peers: grainkit failed on $cs" >&2
            exit 1
        fi
        emit "$(printf '%s\n' "$line" | awk -v cs="$cs" -v th="$th" '{
                for (i=1;i<=NF;i++) {split($i,a,"="); v[a[1]]=a[2]}
                printf "PEER peer=grainkit case=%s ranks=%s n=%s steps=%s particle_steps_per_s=%s contact_steps_per_s=%s pair_fraction=- contacts_per_particle=%s sxx=%s syy=%s sxy=%s seconds_median=%s note=%s,%s\n",
                    cs, th, v["n"], v["steps"], v["particle_steps_per_s"], v["contact_steps_per_s"], v["contacts_per_particle"],
                    v["sxx"], v["syy"], v["sxy"], v["seconds_median"], v["real"], v["simd"] }')"
    done
    dim=$(head -n 1 "$pk" | awk '{print $1}')

    if wants lammps; then
        if ! have lmp; then
            skip "peer=lammps case=$cs: lmp not found (Debian: apt-get install lammps openmpi-bin)"
        elif ! have python3; then
            skip "peer=lammps case=$cs: python3 not found"
        elif python3 $PEERDIR/pack2lammps.py "$pk" "$WORK/$cs.data" 2>"$WORK/$cs.conv"; then
            note=match
            if grep -q rotated "$WORK/$cs.conv"; then note="cell_rotated_$(sed -n 's/.*by ~\([^ ]*\) rad.*/\1/p' "$WORK/$cs.conv")rad"; fi
            for np in $THREADS; do
                log=$WORK/lammps_${cs}_np$np.log
                if [ "$np" = 1 ]; then
                    LMP_LAUNCH="" lmp_run "$WORK/$cs.data" "$log"
                elif have "$MPIRUN"; then
                    LMP_LAUNCH="$MPIRUN $MPI_FLAGS -np 2" lmp_run "$WORK/$cs.data" "$log"
                else
                    skip "peer=lammps case=$cs ranks=2: $MPIRUN not found"
                    continue
                fi
                parse_lmp lammps "$cs" "$np" "$S" "$log" "$note"
            done
            # LAMMPS's faster orthogonal box: pure shear at the same rate from rest, one
            # rank, a speed reference only (its stress is not the simple shear's)
            if python3 $PEERDIR/pack2lammps.py "$pk" "$WORK/${cs}_pure.data" --orthogonal --shear-rate 0 \
                2>"$WORK/${cs}_pure.conv"; then
                log=$WORK/lammps_pure_${cs}_np1.log
                LMP_LAUNCH="" lmp_run "$WORK/${cs}_pure.data" "$log" -var mode pure
                parse_lmp lammps_pure "$cs" 1 "$S" "$log" "pure_shear"
            else
                skip "peer=lammps_pure case=$cs: the starting cell is skewed (pure shear runs in an orthogonal box)"
            fi
        else
            skip "peer=lammps case=$cs: conversion failed: $(cat "$WORK/$cs.conv")"
        fi
    fi

    if wants liggghts; then
        # LIGGGHTS 3.8 accepts a triclinic box but builds no periodic ghost
        # atoms in it (contacts across the boundary are lost and the packing
        # explodes), so it runs in an orthogonal box WITHOUT shear and with
        # zero initial velocities; packings whose cell is skewed are skipped.
        if ! have liggghts; then
            skip "peer=liggghts case=$cs: liggghts not found (Debian: apt-get install liggghts)"
        elif ! have python3; then
            skip "peer=liggghts case=$cs: python3 not found"
        elif python3 $PEERDIR/pack2lammps.py "$pk" "$WORK/${cs}_orth.data" --orthogonal --style granular \
            --shear-rate 0 2>"$WORK/${cs}_orth.conv"; then
            log=$WORK/liggghts_${cs}_np1.log
            (cd "$WORK" && liggghts -log none -echo none -in "$ROOT/$PEERDIR/liggghts.in" -var data "${cs}_orth.data" \
                -var dim "$dim" -var warm "$W" -var steps "$S" -var reps "$REPS" -var shear 0) >"$log" 2>&1
            parse_lmp liggghts "$cs" 1 "$S" "$log" "no_shear"
        else
            skip "peer=liggghts case=$cs: the starting cell is skewed and LIGGGHTS 3.8 has no working triclinic periodic box"
        fi
    fi

    if wants yade; then
        if ! have yade; then
            skip "peer=yade case=$cs: yade not found (Debian: apt-get install yade)"
        else
            for j in $THREADS; do
                log=$WORK/yade_${cs}_j$j.log
                yade -j"$j" -n -x $PEERDIR/yade_bench.py "$pk" "$W" "$S" "$REPS" >"$log" 2>&1
                line=$(grep '^YADE ' "$log" | tail -n 1)
                if [ -z "$line" ]; then
                    echo "FAIL peer=yade case=$cs ranks=$j: no result, see $log" | tee -a "$RES"
                    continue
                fi
                emit "$(printf '%s\n' "$line" | awk -v cs="$cs" -v j="$j" '{
                    for (i=1;i<=NF;i++) {split($i,a,"="); v[a[1]]=a[2]}
                    s=v["seconds_median"]; n=v["n"]; st=v["steps"]
                    printf "PEER peer=yade case=%s ranks=%s n=%d steps=%d particle_steps_per_s=%.4g contact_steps_per_s=%.4g pair_fraction=- contacts_per_particle=%.3f sxx=%.6g syy=%.6g sxy=%.6g contacts_per_particle_start=%.3f seconds_median=%.4g note=threads%s\n",
                        cs, j, n, st, n*st/s, v["contacts"]*st/s, v["contacts"]/n, v["sxx"], v["syy"], v["sxy"], v["contacts0"]/n, s, v["threads"] }')"
            done
        fi
    fi
done

echo
echo "Physics at the end of the runs (same step count; stress tension-positive, Pa, 2D N/m;"
echo "dev = largest relative difference to grainkit 1-thread in contacts, sxx, syy, sxy; @0 = at step 0):"
awk '/^PEER/ {
    for (i=2;i<=NF;i++) {split($i,a,"="); v[a[1]]=a[2]}
    if (v["peer"]=="grainkit" && v["ranks"]==1) {gc[v["case"]]=v["contacts_per_particle"]; gx[v["case"]]=v["sxx"]; gy[v["case"]]=v["syy"]; gs[v["case"]]=v["sxy"]}
    k++; L[k]=v["case"] SUBSEP v["peer"] SUBSEP v["ranks"] SUBSEP v["contacts_per_particle"] SUBSEP v["sxx"] SUBSEP v["syy"] SUBSEP v["sxy"] SUBSEP v["note"] SUBSEP \
        (("contacts_per_particle_start" in v) ? v["contacts_per_particle_start"] : "-") SUBSEP (("sxx_start" in v) ? v["sxx_start"] : "-")
    delete v }
  function rd(a,b) { return b==0 ? 0 : (a-b)/(b<0?-b:b) }
  function ab(x) { return x<0?-x:x }
  END {
    printf "%-8s %-11s %5s %8s %12s %12s %12s %7s %8s %12s  %s\n", "case", "peer", "ranks", "cont/p", "sxx", "syy", "sxy", "dev", "cont/p@0", "sxx@0", "note"
    for (i=1;i<=k;i++) {
        split(L[i], f, SUBSEP); c=f[1]
        d=ab(rd(f[4],gc[c])); e=ab(rd(f[5],gx[c])); if(e>d)d=e; e=ab(rd(f[6],gy[c])); if(e>d)d=e; e=ab(rd(f[7],gs[c])); if(e>d)d=e
        printf "%-8s %-11s %5s %8s %12.6g %12.6g %12.6g %6.2f%% %8s %12s  %s\n", c, f[2], f[3], f[4], f[5], f[6], f[7], 100*d, f[9], f[10], f[8]
    }
  }' "$RES"

echo
echo "Speed: million particle-steps/s (Mps), contact-steps/s in the PEER lines; ratio = grainkit / peer"
echo "at the same thread (grainkit OpenMP) / rank (LAMMPS MPI) / thread (YADE -j) count:"
awk '/^PEER/ {
    for (i=2;i<=NF;i++) {split($i,a,"="); v[a[1]]=a[2]}
    c=v["case"]; if (!(c in seen)) {seen[c]=1; nc++; order[nc]=c}
    r[c, v["peer"], v["ranks"]]=v["particle_steps_per_s"]/1e6
    pf[c, v["peer"], v["ranks"]]=v["pair_fraction"]
    delete v }
  function cell(c,p,t) { return ((c,p,t) in r) ? sprintf("%8.2f", r[c,p,t]) : sprintf("%8s", "-") }
  function ratio(c,p,t) { return ((c,p,t) in r && (c,"grainkit",t) in r && r[c,p,t]>0) ? sprintf("%8.1fx", r[c,"grainkit",t]/r[c,p,t]) : sprintf("%9s", "-") }
  END {
    printf "%-8s %3s %8s %8s %9s %8s %9s %8s %9s %8s %9s\n", "case", "thr", "grainkit", "lammps", "gk/lmp", "lmp_pure", "gk/lmp_p",
        "liggghts", "gk/lig", "yade", "gk/yade"
    for (i=1;i<=nc;i++) for (t=1;t<=2;t++) {
        c=order[i]
        printf "%-8s %3d %s %s %s %s %s %s %s %s %s\n", c, t, cell(c,"grainkit",t), cell(c,"lammps",t), ratio(c,"lammps",t),
            cell(c,"lammps_pure",t), ratio(c,"lammps_pure",t), cell(c,"liggghts",t), ratio(c,"liggghts",t),
            cell(c,"yade",t), ratio(c,"yade",t)
    }
  }' "$RES"
echo
echo "run_peers: load average at the end $(loadavg) (a load above the core count means other jobs shared the"
echo "cores: multi-thread/rank rates are then the first to suffer). PEER lines kept in $RES, logs in $WORK/"
exit 0
