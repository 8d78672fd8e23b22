#!/bin/sh
# bench/knockout.sh [DIR [ROUNDS]] - what bounds the 3D force loop (bench/README.md, "Where the time
# goes"). Builds bench/knockout.c against copies of include/ in which parts of the AVX-512 double
# 3D force loop are removed, alone and together, and times each copy on one saved state of
# bench_dem_step's 3d_10k case (20 000 spheres; ROUNDS rounds, default 5, each variant once per
# round, one core: KO_CORE, default 1). Prints the median time per pair and its ratio to the whole
# loop. The copies compute wrong forces: they are measurements, not grainkit.
#   j  the j sides' gathers (positions, radius, velocity, spin) become one contiguous load each
#   s  the force records' scatter (transpose, permutations, read-modify-writes) is dropped; the
#      forces and torques are summed into a register instead, so they are still computed
#   t  of that scatter, only the transpose and permutations (the records get untransposed rows)
#   w  of that scatter, only the read-modify-writes (the records are summed into a register)
#   q  the law's square roots become copies and its divisions products (three of each per block)
# Run from anywhere; needs an AVX-512 CPU, cc (CC) with OpenMP and sed.
# bench/knockout.sh --patch-only DIR: only make the patched copies (make test checks that every
# patch still finds its line).
set -eu
cd "$(dirname "$0")/.."
patch_only=0
if [ "${1:-}" = --patch-only ]; then
    patch_only=1
    shift
fi
D=${1:-build/knockout}
R=${2:-5}
CORE=${KO_CORE:-1}
CC=${CC:-cc}
FLAGS="-std=c99 -O2 -march=native -ffp-contract=off -fno-fast-math -fopenmp"
if [ "$patch_only" = 0 ] && ! $CC -march=native -dM -E - </dev/null | grep -q '__AVX512F__'; then
    echo "knockout.sh: this CPU has no AVX-512; the loop it studies is the AVX-512 double one"
    exit 0
fi
mkdir -p "$D"

# sed -i EXPR FILE, failing unless it changed the file
patch_() {
    cp "$2" "$2.orig"
    sed -i "$1" "$2"
    if cmp -s "$2" "$2.orig"; then
        echo "knockout.sh: '$1' changed nothing in $2 (the loop's source moved on: update this script)" >&2
        exit 1
    fi
    rm -f "$2.orig"
}

# variant NAME KNOCKOUTS: a copy of include/ with those knockouts, and its knockout program
variant() {
    v="$D/$1"
    rm -rf "$v"
    mkdir -p "$v"
    cp include/*.h "$v/"
    case "$2" in *j*)
        patch_ 's/gk_vd_gather(rve->s\[\([012]\)\], j4)/gk__ko_load(rve->s[\1], j4, rve->n)/' "$v/gk_dem.h"
        patch_ '/^GK_FORCE_INLINE void gk__forces_simd_3d(/,/^#undef GK__GI/ s/gk_vr_gather(\([^,]*\), jj)/gk__ko_load(\1, jj, rve->n)/g' "$v/gk_dem.h"
        ;;
    esac
    case "$2" in *s*)
        patch_ 's/gk__scatter_rec_3d(rve->frec, ii, jj, &o, fl & GK_PHYS_ROTATION);/GK_KO_SINK(\&o);/' "$v/gk_dem.h"
        ;;
    esac
    case "$2" in *t*)
        patch_ 's|gk_vd_transpose8(r); /\* r\[l\] = (f, tj, ti0, ti1) of lane l \*/|/* knocked out */|' "$v/gk_dem.h"
        patch_ 's/gk_vd rj = _mm512_maskz_mov_pd(0x3f, r\[l\]);/gk_vd rj = r[l];/' "$v/gk_dem.h"
        patch_ 's/gk_vd ri = _mm512_xor_pd(_mm512_maskz_permutex2var_pd(0x3f, r\[l\], idx, ti2), neg);/gk_vd ri = _mm512_xor_pd(r[(l + 1) \& 7], neg); (void)idx; (void)ti2;/' "$v/gk_dem.h"
        ;;
    esac
    case "$2" in *w*)
        patch_ 's/gk_vd_store(aj, gk_vd_add(gk_vd_load(aj), rj));/ko_sink = _mm512_add_pd(ko_sink, rj); (void)aj;/' "$v/gk_dem.h"
        patch_ 's/gk_vd_store(ai, gk_vd_add(gk_vd_load(ai), ri));/ko_sink = _mm512_add_pd(ko_sink, ri); (void)ai;/' "$v/gk_dem.h"
        ;;
    esac
    case "$2" in *q*)
        patch_ '/^GK_FORCE_INLINE void gk_contact_rotate_history_w(/,/^#endif \/\* GK_CONTACT_H/ { s/gk_vr_sqrt(/GK_KO_SQRT(/g; s/gk_vr_div(/GK_KO_DIV(/g; }' "$v/gk_contact.h"
        ;;
    esac
    [ "$patch_only" = 1 ] || $CC $FLAGS -I"$v" -o "$v/knockout" bench/knockout.c -lm
}

names="whole j s t w q js jq sq jsq"
for n in $names; do
    if [ "$n" = whole ]; then variant whole ""; else variant "$n" "$n"; fi
done
[ "$patch_only" = 0 ] || exit 0
"$D/whole/knockout" --make "$D/state.bin"
pin=""
command -v taskset >/dev/null 2>&1 && pin="taskset -c $CORE"
: >"$D/times.txt"
i=0
while [ "$i" -lt "$R" ]; do
    for n in $names; do
        t=$($pin "$D/$n/knockout" "$D/state.bin" | sed -n 's/.*: \([0-9.]*\) ns per pair.*/\1/p')
        echo "$n $t" >>"$D/times.txt"
    done
    i=$((i + 1))
done
echo "3D force loop, 20 000 spheres, one core; median of $R rounds (each variant once per round):"
echo "removed                                          ns per pair  time / whole loop"
for n in $names; do
    grep "^$n " "$D/times.txt" | awk '{print $2}' | sort -n |
        awk -v n="$n" '{a[NR] = $1} END {m = NR % 2 ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2; print n, m}'
done | awk '
    BEGIN {
        w["whole"] = "nothing (the whole loop)"; w["j"] = "j: the j-side gathers"; w["s"] = "s: the records scatter";
        w["q"] = "q: the square roots and divisions";
        w["t"] = "t: of s, the transpose and permutations"; w["w"] = "w: of s, the read-modify-writes"; w["js"] = "j + s"; w["jq"] = "j + q"; w["sq"] = "s + q";
        w["jsq"] = "j + s + q"
    }
    { m[NR] = $2; k[NR] = $1 }
    END { for (i = 1; i <= NR; ++i) printf "%-48s %11.2f  %.3f\n", w[k[i]], m[i], m[i] / m[1] }'
