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
# csv_plot: a good run, an SVG that cannot be written, a bad field, a refused option
printf 'a,b\n0,1\n1,2\n' > "$T/cp.csv" && printf 'a,b\n0,1\n1,x\n' > "$T/cp_bad.csv"
run 0 "$B/csv_plot" --x a --y b --out "$T/cp.svg" "$T/cp.csv=one" "$T/cp.csv"
run 1 "$B/csv_plot" --x a --y b --out /dev/full "$T/cp.csv"
run 1 "$B/csv_plot" --x a --y b --out "$T/cp2.svg" "$T/cp_bad.csv"
run 2 "$B/csv_plot" --x a --y b --xlim 1 --out "$T/cp2.svg" "$T/cp.csv"
# the MPMxDEM drivers at their tests' sizes: a run, its restart, a corrupt checkpoint, a result that
# cannot be written, a refused option
BX="--nx 2 --ny 4 --every 0.0005 --quiet --threads 2"
run 0 "$B/mpmdem_biaxial" $BX --strain 0.001 --out "$T/bx"
run 0 "$B/mpmdem_biaxial" $BX --strain 0.0015 --restart "$T/bx" --out "$T/bx2"
head -c 3000 "$T/bx/checkpoint.bin" > "$T/bx_cut.bin" && mkdir -p "$T/bxc" && mv "$T/bx_cut.bin" "$T/bxc/checkpoint.bin"
run 1 "$B/mpmdem_biaxial" $BX --strain 0.0015 --restart "$T/bxc" --out "$T/bx3"
rm -rf "$T/bxw" && mkdir -p "$T/bxw" && ln -s /dev/full "$T/bxw/biaxial.csv"
run 1 "$B/mpmdem_biaxial" $BX --strain 0.0005 --out "$T/bxw"
run 2 "$B/mpmdem_biaxial" $BX --nx 3
run 0 "$B/mpmdem_footing" --width 2 --depth 1.5 --nx 4 --ny 3 --B 1.5 --velocity 0.25 --ramp 0.01 \
    --every 0.005 --smooth 0.01 --phi-deg 30 --final 0.01 --quiet --threads 2 --out "$T/ft"
run 0 "$B/mpmdem_single" --strain 0.003 --packing "$T/pack.txt" --quiet --threads 2 --out "$T/sg"
rm -rf "$T/sgw" && mkdir -p "$T/sgw" && ln -s /dev/full "$T/sgw/single.csv"
run 1 "$B/mpmdem_single" --strain 0.003 --packing "$T/pack.txt" --quiet --threads 2 --out "$T/sgw"
run 2 "$B/mpmdem_single" --margin -1
run 0 "$B/mpmdem_collapse" --nx 4 --every 0.025 --snapshots 0.05 --t-end 0.05 --quiet --threads 2 --out "$T/cl"
run 0 "$B/mpmdem_collapse" --paper --nx 4 --ppc 1 --levels 1 --t-end 0.01 --every 0.005 --snapshots 0.005 --quiet --threads 1 --out "$T/clp"
PP="--width 3 --nx 12 --ny 5 --penetration 0.02 --lateral 0.01 --v-down 1 --v-lateral 1 --ramp 0.005 --every 0.01 --quiet --threads 2"
run 0 "$B/mpmdem_pipe" $PP --max-steps 10 --out "$T/pp"
run 0 "$B/mpmdem_pipe" $PP --restart "$T/pp" --out "$T/pp2"
run 2 "$B/mpmdem_pipe" $PP --diameter 0.3
# the 3D explicit nonlocal FEMxDEM driver on one element: a run stopped half way, its restart, a
# truncated checkpoint, a refused option
NL="--test element-shear --packing examples/data/rve160_hm.txt --steps 4 --strain 0.001 --threads 2"
run 0 "$B/femdem_nonlocal" $NL --stop-after 2 --out "$T/nl"
run 0 "$B/femdem_nonlocal" $NL --restart "$T/nl" --out "$T/nl"
mkdir -p "$T/nlc" && head -c 2000 "$T/nl/checkpoint.bin" > "$T/nlc/checkpoint.bin"
run 1 "$B/femdem_nonlocal" $NL --restart "$T/nlc" --out "$T/nl2"
run 2 "$B/femdem_nonlocal" $NL --steps 0 --out "$T/nl3"
# its simple shear on a 1x4x1 column to the end: the band measures, profile.csv and its plot
run 0 "$B/femdem_nonlocal" --test simple-shear --packing examples/data/rve160_hm.txt --mesh 1x4x1 --steps 4 \
    --strain 0.001 --out "$T/nls"
# the imperfect RVE in every element of its row, on two layers (2x4x2)
run 0 "$B/femdem_nonlocal" --test simple-shear --packing examples/data/rve160_hm.txt --mesh 2x4x2 --steps 2 \
    --strain 0.001 --imperfect-row --out "$T/nlr"
# a result that cannot be written (a full device in its place) is exit 1 with every buffer freed:
# the RVE test's rve.csv, the simple shear's profile.csv, the one element's rve_alone.csv, the wave's
# wave_arrival.csv
NW="--packing examples/data/rve160_hm.txt --strain 0.001"
for f in nlw1/rve.csv nlw2/profile.csv nlw3/rve_alone.csv nlw4/wave_arrival.csv; do
    rm -rf "$T/${f%/*}" && mkdir -p "$T/${f%/*}" && ln -s /dev/full "$T/$f"
done
run 1 "$B/femdem_nonlocal" --test rve --packing examples/data/rve160_hm.txt --steps 2 --out "$T/nlw1"
run 1 "$B/femdem_nonlocal" --test simple-shear $NW --mesh 1x4x1 --steps 2 --out "$T/nlw2"
run 1 "$B/femdem_nonlocal" --test element-shear $NW --steps 2 --out "$T/nlw3"
run 1 "$B/femdem_nonlocal" --test wave --packing examples/data/rve160_hm.txt --steps 4 --out "$T/nlw4"
# the fully integrated element (8 RVEs per element) on a 2x2 biaxial mesh, stopped and restarted
NG="--test biaxial --gauss 8 --mesh 2x2x1 --packing examples/data/rve160_hm.txt --steps 4 --strain 0.001"
run 0 "$B/femdem_nonlocal" $NG --stop-after 2 --out "$T/ng"
run 0 "$B/femdem_nonlocal" $NG --restart "$T/ng" --out "$T/ng"
# the dynamic-relaxation FEMxDEM driver (periodic frame RVE) and a refused option
run 0 "$B/femdem_dr" --test rve --frame periodic --steps 4 --strain 0.02 --out "$T/dr"
run 2 "$B/femdem_dr" --test rve --frame periodic --steps -1 --out "$T/dr2"
# the hybrid continuum-grain driver: a small planar shear through its enrichment (and with the overlap's
# contacts weighted, the band over Delaunay neighbours across the periodic seam), and one refused at the enrichment (the discrete zone reaches a platen)
HY="--test planar --mode hybrid --width 0.008 --cell 0.002 --strain 0.002 --out-every 0.001 --window 0.001 0.002"
run 0 "$B/hybrid" $HY --height 0.016 --phi0 0.003 --threads 2 --out "$T/hy"
run 0 "$B/hybrid" $HY --height 0.016 --phi0 0.003 --weigh-overlap --delaunay --threads 1 --out "$T/hyw"
run 1 "$B/hybrid" $HY --height 0.012 --phi0 0.004 --threads 2 --out "$T/hy2"
# biaxial on a 1.2 x 1.8 cm specimen: the zone reaches the top platen (training targets corrected,
# the top wall seated by its servo, the swap; the band over Delaunay neighbours, the open cells at the
# zone's edges left out)
run 0 "$B/hybrid" --test biaxial --mode hybrid --width 0.012 --height 0.018 --cell 0.003 --strain 0.008 \
    --out-every 0.001 --window 0.007 0.008 --interior --threads 2 --out "$T/hyb"
# plate indentation on a 2 x 1 cm bin: settling, the oracle made eager (c1 0) so that the intruder's
# training and the swap run; an intruder wider than half the bin refused
IND="--test indent --mode hybrid --width 0.02 --height 0.01 --cell 0.0025 --strain 0.02 --out-every 0.01 --window 0.01 0.02"
run 0 "$B/hybrid" $IND --intruder 0.005 --c1 0 --cg 1e-4 --phi0 0.004 --threads 2 --out "$T/hyi"
run 2 "$B/hybrid" $IND --intruder 0.015 --out "$T/hyi2"
# bench_scene_box (bench/peers/run_box.sh): a pour that writes the settled packing, a compression
# read back from it, the impacts, a write that fails, untrusted data files, a refused option
SB="--nx 2 --nz 2 --pour 200 --compress 20"
run 0 "$B/bench_scene_box" $SB --write-data "$T/sb0.data" --write-settled "$T/sb.data"
run 0 "$B/bench_scene_box" $SB --from "$T/sb.data"
run 0 "$B/bench_scene_box" --impact --write-data "$T/sbi.data"
run 1 "$B/bench_scene_box" $SB --write-settled /dev/full
run 1 "$B/bench_scene_box" $SB --from tests
printf '99999999999 atoms\n\nAtoms\n\n1 1 0.002 2650 0.001 0.001 0.001\n' >"$T/sb_n.data"
run 1 "$B/bench_scene_box" $SB --from "$T/sb_n.data"
printf '2 atoms\n\nAtoms\n\n1 1 0.002 2650 0.001 0.001 0.001\n1 1 0.002 2650 0.003 0.001 0.001\n' >"$T/sb_id.data"
run 1 "$B/bench_scene_box" $SB --from "$T/sb_id.data"
printf '1 atoms\n\nAtoms\n\n1 1 0.002 2650 0.001 nan 0.001\n' >"$T/sb_nan.data"
run 1 "$B/bench_scene_box" $SB --from "$T/sb_nan.data"
printf '1 atoms\n\nAtoms\n\n1 1 0.002 2650 0.001 0.001 5\n' >"$T/sb_out.data"
run 1 "$B/bench_scene_box" $SB --from "$T/sb_out.data"
printf '1 atoms\n\nAtoms\n\n1 1 1e300 2650 0.001 0.001 0.001\n' >"$T/sb_big.data"
run 1 "$B/bench_scene_box" $SB --from "$T/sb_big.data"
run 2 "$B/bench_scene_box" --nx 1
echo "# smoke_asan: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
