/* gk_base.h - grainkit base: reals, result codes, allocator, small tensors,
 * random numbers and the SIMD wide type.                 (grainkit v0.1)
 *
 * grainkit is a header-only C99 library of kernels for two-scale granular
 * mechanics (a DEM packing behind every Gauss point or material point).
 * Every other header includes this one.
 *
 * DO THIS in exactly one C or C++ file before including any grainkit header:
 *
 *     #define GK_IMPLEMENTATION
 *     #include "gk_dem.h"      (pulls in gk_base, gk_cells, gk_contact, gk_pcell)
 *
 * Other files include the headers without the define and see declarations.
 * Each header can also be switched on alone with GK_<MODULE>_IMPLEMENTATION
 * (e.g. GK_BASE_IMPLEMENTATION); GK_IMPLEMENTATION switches on all of them.
 *
 * CONFIGURATION (define before including)
 *
 *   macro             default      meaning
 *   ----------------  -----------  -----------------------------------------
 *   GK_REAL_FLOAT     undefined    gk_real = float (velocities, forces,
 *                                  contact history, radii); particle positions
 *                                  stay double in reduced cell coordinates
 *   GK_STATIC         undefined    all non-inline functions get internal
 *                                  linkage (lets one program hold a float and
 *                                  a double copy of grainkit side by side)
 *   GK_NO_SIMD        undefined    wide type has one lane (scalar build)
 *   GK_SIMD_WIDTH     auto         force 512, 256, 128 or 0 (bits)
 *   GK_HW_GATHER      undefined    use vgather instructions (default: loads)
 *   GK_ASSERT(c)      assert(c)    internal invariant checks
 *   GK_MALLOC/GK_FREE malloc/free  default allocator behind gk_allocator
 *   GK_FILE_MAX       INT_MAX      largest file gk_file_read accepts [bytes]
 *                                  (a reader given /dev/zero stops there)
 *   GK_IMPLEMENTATION_ELSEWHERE    (on the command line) a GK_IMPLEMENTATION
 *                    undefined     in the file is ignored: the program links
 *                                  the implementation from an object compiled
 *                                  once (many single-file programs, one
 *                                  implementation; per-module
 *                                  GK_<MODULE>_IMPLEMENTATION still apply)
 *
 * CONVENTIONS (all headers)
 *   - SI units throughout: m, kg, s, N, Pa.
 *   - Stress is tension-positive inside grainkit. The papers and the
 *     example outputs are compression-positive: the conversion happens at
 *     output and is stated there.
 *   - Tensors are 3x3 row-major double[9], a[3*i+j] = a_ij. A 2D problem uses
 *     the upper-left 2x2 block and keeps a_22 = 1 for maps (cell matrix,
 *     deformation gradient) and a_22 = 0 for rates and stresses.
 *   - Displacement-gradient (and velocity-gradient) components are
 *     H_ij = du_i/dx_j: H01 = du_x/dy.
 *   - Voigt order: 2D (xx, yy, xy); 3D (xx, yy, zz, yz, xz, xy).
 *   - Every function that can fail returns a gk_result; on failure it leaves
 *     its inputs unchanged and writes a message to the gk_err it was given
 *     (or to the object's own error buffer).
 *
 * REVISION HISTORY
 *   0.1  first release: base, cells, contact, pcell, dem, homog
 *
 * LICENCE: MIT, see the end of this file.
 */
#ifndef GK_BASE_H
#define GK_BASE_H

#ifdef GK_IMPLEMENTATION_ELSEWHERE
#undef GK_IMPLEMENTATION
#endif

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <math.h>

#define GK_VERSION_MAJOR 0
#define GK_VERSION_MINOR 1
#define GK_VERSION_PATCH 0
#define GK_VERSION_STRING "0.1.0"

/* ---------------------------------------------------------------- linkage */
#ifdef GK_STATIC
#if defined(__GNUC__) || defined(__clang__)
#define GKDEF static __attribute__((unused)) /* a program may use only some */
#else
#define GKDEF static
#endif
#else
#ifdef __cplusplus
#define GKDEF extern "C"
#else
#define GKDEF extern
#endif
#endif
/* leaf helpers: always visible, never a bare `inline` (C99 -O0 link hazard) */
#define GK_INLINE static inline

/* GK_UNROLL before a loop over the axes (2 or 3 turns, constant after
 * inlining): gcc -O2 otherwise keeps such a loop in the kernels and passes
 * its vectors through the stack (the 3D step is about 1.7x faster with it,
 * bench/README.md). Define it empty before the first include to turn it off
 * (same results either way) */
#ifndef GK_UNROLL
#if defined(__clang__)
#define GK_UNROLL _Pragma("unroll")
#elif defined(__GNUC__) && __GNUC__ >= 8
#define GK_UNROLL _Pragma("GCC unroll 4")
#else
#define GK_UNROLL
#endif
#endif

#if defined(__GNUC__) || defined(__clang__)
#define GK_FORCE_INLINE static inline __attribute__((always_inline))
#define GK_UNUSED __attribute__((unused))
#define GK_LIKELY(x) __builtin_expect(!!(x), 1)
#define GK_UNLIKELY(x) __builtin_expect(!!(x), 0)
#define GK_PREFETCH(p) __builtin_prefetch(p)
#else
#define GK_FORCE_INLINE static inline
#define GK_UNUSED
#define GK_LIKELY(x) (x)
#define GK_UNLIKELY(x) (x)
#define GK_PREFETCH(p) ((void)(p))
#endif

#ifdef __cplusplus
#define GK_RESTRICT __restrict
#else
#define GK_RESTRICT restrict
#endif

/* C99 has no _Static_assert: negative array size on failure. */
#define GK_STATIC_ASSERT(cond, name) typedef char gk__static_assert_##name[(cond) ? 1 : -1]

/* OpenMP is optional; without -fopenmp the pragmas vanish (no -Wunknown-pragmas). */
#ifdef _OPENMP
#include <omp.h>
#define GK_PRAGMA_(x) _Pragma(#x)
#define GK_OMP(x) GK_PRAGMA_(omp x)
#else
#define GK_OMP(x)
#endif

#ifndef GK_ASSERT
#include <assert.h>
#define GK_ASSERT(c) assert(c)
#endif

/* ------------------------------------------------------------------ reals */
#ifdef GK_REAL_FLOAT
typedef float gk_real;
#define GK_REAL_NAME "float"
#define GK_REAL_EPS 1.1920929e-7f
#else
typedef double gk_real;
#define GK_REAL_NAME "double"
#define GK_REAL_EPS 2.220446049250313e-16
#endif

#define GK_PI 3.14159265358979323846

/* ---------------------------------------------------------- result codes */
typedef enum gk_result {
    GK_OK = 0,
    GK_ERR_ARG,         /* an argument is out of its documented range          */
    GK_ERR_NAN,         /* a NaN or infinite value in the input                */
    GK_ERR_RADIUS,      /* a radius <= 0 (or a size ratio beyond support)      */
    GK_ERR_MASS,        /* a mass, density or inertia <= 0                     */
    GK_ERR_DT,          /* time step <= 0 or above the critical time step      */
    GK_ERR_ALLOC,       /* the allocator returned NULL                         */
    GK_ERR_IO,          /* a file could not be opened, read or written         */
    GK_ERR_FORMAT,      /* malformed file or buffer                            */
    GK_ERR_CELL,        /* degenerate, inverted or too small periodic cell     */
    GK_ERR_OUTSIDE,     /* a particle outside the cell where inside is needed  */
    GK_ERR_SINGULAR,    /* singular matrix or Jacobian                         */
    GK_ERR_DIVERGED,    /* an iteration or simulation blew up                  */
    GK_ERR_STATE,       /* call not valid in the object's current state        */
    GK_ERR_MESH,        /* invalid mesh: inverted/degenerate element, bad ids  */
    GK_ERR_UNSUPPORTED, /* valid request this build or module does not do    */
    GK_ERR_NOCONVERGE,  /* an iteration stopped at its cap without converging */
    GK_RESULT_COUNT
} gk_result;

#define GK_ERR_MSG_LEN 256
typedef struct gk_err {
    gk_result code;
    char msg[GK_ERR_MSG_LEN]; /* human-readable, names the offending value */
} gk_err;

/* ------------------------------------------------------------- allocator */
/* A zero-initialised gk_allocator means malloc/free. `alloc` must return
 * memory aligned to `align` (a power of two, at most 4096) or NULL. */
typedef struct gk_allocator {
    void *(*alloc)(size_t size, size_t align, void *user);
    void (*free)(void *ptr, void *user);
    void *user;
} gk_allocator;

#define GK_ALIGN 64 /* alignment of every grainkit array (one cache line) */

/* ------------------------------------------------------------ random */
/* xoshiro256** seeded by splitmix64: deterministic on every platform. */
typedef struct gk_rng {
    uint64_t s[4];
} gk_rng;

/* ---------------------------------------------------------- declarations */
#ifdef __cplusplus
extern "C" {
#endif

GKDEF const char *gk_result_string(gk_result r);
GKDEF const char *gk_version(void);
/* sets e->code and e->msg (printf format); returns code. e may be NULL. */
GKDEF gk_result gk_err_set(gk_err *e, gk_result code, const char *fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
GKDEF void gk_err_clear(gk_err *e);

GKDEF void *gk_alloc(const gk_allocator *a, size_t size);
GKDEF void gk_free(const gk_allocator *a, void *ptr);
/* grow *ptr (elements of elem_size) from old_n to new_n, copying old_n; on
 * failure *ptr is untouched and GK_ERR_ALLOC returned. */
GKDEF gk_result gk_realloc(const gk_allocator *a, void **ptr, size_t old_n, size_t new_n, size_t elem_size);
/* Reads a whole file into a NUL-terminated buffer (*text, free it with
 * gk_free(alloc, *text)) of *len bytes plus the NUL. Reads until end of file,
 * so pipes work and a file's announced size is never trusted; a directory, an
 * unreadable file or one above GK_FILE_MAX bytes is GK_ERR_IO naming the path
 * and the reason. On error *text and *len are untouched. */
GKDEF gk_result gk_file_read(const char *path, const gk_allocator *alloc, char **text, size_t *len,
                             gk_err *err);
/* Closes a FILE * that was written: fflush, ferror and fclose,
 * so a lost byte anywhere (disk full, /dev/full, a quota) is GK_ERR_IO naming
 * path and reason. The file is closed in every case. */
GKDEF gk_result gk_file_close(FILE *fp, const char *path, gk_err *err);

GKDEF void gk_rng_seed(gk_rng *r, uint64_t seed);
GKDEF uint64_t gk_rng_u64(gk_rng *r);
GKDEF double gk_rng_uniform(gk_rng *r); /* [0, 1) with 53 random bits */
GKDEF double gk_rng_normal(gk_rng *r);  /* standard normal (Box-Muller) */

/* 3x3 tensors that are not one-liners */
GKDEF double gk_m3_inverse(const double a[9], double inv[9]); /* returns det; inv untouched if det==0 */
/* eigen-decomposition of a symmetric 3x3 (cyclic Jacobi): values ascending, columns of vec */
GKDEF void gk_m3_sym_eigen(const double a[9], double val[3], double vec[9]);
/* polar decomposition F = R U (R proper rotation, U symmetric positive definite).
 * dim 2 or 3. Returns GK_ERR_SINGULAR if det F <= 0. */
GKDEF gk_result gk_m3_polar(const double F[9], int dim, double R[9], double U[9]);
/* matrix exponential exp(A) (scaling and squaring + Taylor to machine precision) */
GKDEF void gk_m3_exp(const double A[9], double E[9]);
/* rotation matrix from axis-angle vector w (|w| = angle) */
GKDEF void gk_m3_rotation(const double w[3], double R[9]);
/* axis-angle vector of a rotation matrix (inverse of gk_m3_rotation, angle in [0, pi]) */
GKDEF void gk_m3_rotation_vector(const double R[9], double w[3]);

#ifdef __cplusplus
}
#endif

/* ------------------------------------------------- inline tensor helpers */
GK_INLINE void gk_m3_zero(double a[9]) {
    int k;
    for (k = 0; k < 9; ++k) a[k] = 0.0;
}
GK_INLINE void gk_m3_identity(double a[9]) {
    gk_m3_zero(a);
    a[0] = a[4] = a[8] = 1.0;
}
GK_INLINE void gk_m3_copy(const double a[9], double b[9]) {
    int k;
    for (k = 0; k < 9; ++k) b[k] = a[k];
}
GK_INLINE double gk_m3_det(const double a[9]) {
    return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
           a[2] * (a[3] * a[7] - a[4] * a[6]);
}
GK_INLINE double gk_m3_trace(const double a[9]) { return a[0] + a[4] + a[8]; }
/* c = a b (c may alias neither) */
GK_INLINE void gk_m3_mul(const double a[9], const double b[9], double c[9]) {
    int i, j;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j)
            c[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}
GK_INLINE void gk_m3_transpose(const double a[9], double t[9]) {
    int i, j;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) t[3 * j + i] = a[3 * i + j];
}
GK_INLINE void gk_m3_matvec(const double a[9], const double x[3], double y[3]) {
    int i;
    for (i = 0; i < 3; ++i) y[i] = a[3 * i] * x[0] + a[3 * i + 1] * x[1] + a[3 * i + 2] * x[2];
}
/* symmetric and skew parts */
GK_INLINE void gk_m3_sym(const double a[9], double s[9]) {
    int i, j;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) s[3 * i + j] = 0.5 * (a[3 * i + j] + a[3 * j + i]);
}
GK_INLINE void gk_m3_skew(const double a[9], double w[9]) {
    int i, j;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) w[3 * i + j] = 0.5 * (a[3 * i + j] - a[3 * j + i]);
}
/* Frobenius norm and double contraction */
GK_INLINE double gk_m3_ddot(const double a[9], const double b[9]) {
    double s = 0.0;
    int k;
    for (k = 0; k < 9; ++k) s += a[k] * b[k];
    return s;
}
GK_INLINE double gk_m3_norm(const double a[9]) { return sqrt(gk_m3_ddot(a, a)); }
GK_INLINE int gk_m3_isfinite(const double a[9]) {
    int k;
    for (k = 0; k < 9; ++k)
        if (!isfinite(a[k])) return 0;
    return 1;
}
GK_INLINE double gk_v3_dot(const double a[3], const double b[3]) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
GK_INLINE void gk_v3_cross(const double a[3], const double b[3], double c[3]) {
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}
GK_INLINE double gk_clamp(double x, double lo, double hi) { return x < lo ? lo : (x > hi ? hi : x); }

/* ======================================================= SIMD wide types
 * One wide type per precision, chosen here and nowhere else (Box2D style):
 *   gk_vd   GK_VD_W lanes of double      gk_vdm  its lane mask
 *   gk_vf   GK_VF_W lanes of float       gk_vfm  its lane mask
 * A closed set of operations (load, store, splat, add, sub, mul, div, sqrt,
 * min, max, compare, select, gather, round) with a one-lane scalar twin
 * (GK_NO_SIMD). Only correctly rounded operations are used (no reciprocal or
 * rsqrt approximations, no FMA contraction), so every lane computes exactly
 * what the scalar code computes. */
#if !defined(GK_SIMD_WIDTH)
#if defined(GK_NO_SIMD)
#define GK_SIMD_WIDTH 0
#elif defined(__AVX512F__) && defined(__AVX512DQ__)
#define GK_SIMD_WIDTH 512
#elif defined(__AVX2__)
#define GK_SIMD_WIDTH 256
#elif defined(__SSE4_1__)
#define GK_SIMD_WIDTH 128
#else
#define GK_SIMD_WIDTH 0
#endif
#endif

#if GK_SIMD_WIDTH == 512
#include <immintrin.h>
#define GK_SIMD_NAME "avx512"
#define GK_VD_W 8
#define GK_VF_W 16
typedef __m512d gk_vd;
typedef __mmask8 gk_vdm;
typedef __m512 gk_vf;
typedef __mmask16 gk_vfm;
GK_FORCE_INLINE gk_vd gk_vd_zero(void) { return _mm512_setzero_pd(); }
GK_FORCE_INLINE gk_vd gk_vd_set1(double a) { return _mm512_set1_pd(a); }
GK_FORCE_INLINE gk_vd gk_vd_load(const double *p) { return _mm512_load_pd(p); }
GK_FORCE_INLINE gk_vd gk_vd_loadu(const double *p) { return _mm512_loadu_pd(p); }
GK_FORCE_INLINE void gk_vd_store(double *p, gk_vd a) { _mm512_store_pd(p, a); }
GK_FORCE_INLINE void gk_vd_storeu(double *p, gk_vd a) { _mm512_storeu_pd(p, a); }
GK_FORCE_INLINE gk_vd gk_vd_add(gk_vd a, gk_vd b) { return _mm512_add_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_sub(gk_vd a, gk_vd b) { return _mm512_sub_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_mul(gk_vd a, gk_vd b) { return _mm512_mul_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_div(gk_vd a, gk_vd b) { return _mm512_div_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_sqrt(gk_vd a) { return _mm512_sqrt_pd(a); }
GK_FORCE_INLINE gk_vd gk_vd_min(gk_vd a, gk_vd b) { return _mm512_min_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_max(gk_vd a, gk_vd b) { return _mm512_max_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_round(gk_vd a) {
    return _mm512_roundscale_pd(a, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
}
GK_FORCE_INLINE gk_vd gk_vd_floor(gk_vd a) {
    return _mm512_roundscale_pd(a, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
}
GK_FORCE_INLINE gk_vdm gk_vd_lt(gk_vd a, gk_vd b) { return _mm512_cmp_pd_mask(a, b, _CMP_LT_OQ); }
GK_FORCE_INLINE gk_vdm gk_vd_le(gk_vd a, gk_vd b) { return _mm512_cmp_pd_mask(a, b, _CMP_LE_OQ); }
GK_FORCE_INLINE gk_vdm gk_vd_gt(gk_vd a, gk_vd b) { return _mm512_cmp_pd_mask(a, b, _CMP_GT_OQ); }
GK_FORCE_INLINE gk_vdm gk_vdm_and(gk_vdm a, gk_vdm b) { return (gk_vdm)(a & b); }
GK_FORCE_INLINE gk_vdm gk_vdm_or(gk_vdm a, gk_vdm b) { return (gk_vdm)(a | b); }
GK_FORCE_INLINE gk_vdm gk_vdm_not(gk_vdm a) { return (gk_vdm)(~a); }
GK_FORCE_INLINE int gk_vdm_any(gk_vdm a) { return a != 0; }
/* select: lanes of a where m is set, b elsewhere */
GK_FORCE_INLINE gk_vd gk_vd_select(gk_vdm m, gk_vd a, gk_vd b) { return _mm512_mask_blend_pd(m, b, a); }
/* gathers are plain loads + inserts: on the AMD EPYC this was tuned on they are
 * 2.5x faster than vgatherdpd (1.75 vs 4.4 ns per 8 doubles); define
 * GK_HW_GATHER to use the gather instructions instead */
GK_FORCE_INLINE gk_vd gk_vd_gather(const double *base, const int32_t *idx) {
#ifdef GK_HW_GATHER
    return _mm512_i32gather_pd(_mm256_loadu_si256((const __m256i *)(const void *)idx), base, 8);
#else
    return _mm512_set_pd(base[idx[7]], base[idx[6]], base[idx[5]], base[idx[4]], base[idx[3]], base[idx[2]],
                         base[idx[1]], base[idx[0]]);
#endif
}
/* A window gather: when every index of a vector lies in [idx[0], idx[0] + GK_VD_W)
 * (the i side of a block of pairs sorted by i), one load of the GK_VD_W entries
 * from base + idx[0] and a permutation replace the GK_VD_W loads and inserts,
 * with the same values. gk_vd_win_make tells whether idx allows it (n: the
 * length of the arrays it will read); gk_vd_gather_win gathers either way.
 * gk_vf_win: the same for floats. */
typedef struct gk_vd_win {
    __m512i lane; /* idx[l] - at */
    int32_t at;
    int ok;
} gk_vd_win;
#define GK_VD_HAS_WIN 1
GK_FORCE_INLINE void gk_vd_win_make(const int32_t *idx, int32_t n, gk_vd_win *w) {
    int32_t at = idx[0];
    w->lane = _mm512_sub_epi64(_mm512_cvtepi32_epi64(_mm256_loadu_si256((const __m256i *)(const void *)idx)),
                               _mm512_set1_epi64(at));
    w->at = at;
    w->ok =
        at >= 0 && at <= n - GK_VD_W && _mm512_cmplt_epu64_mask(w->lane, _mm512_set1_epi64(GK_VD_W)) == 0xff;
}
GK_FORCE_INLINE gk_vd gk_vd_gather_win(const double *base, const int32_t *idx, const gk_vd_win *w) {
    if (w->ok) return _mm512_permutexvar_pd(w->lane, _mm512_loadu_pd(base + w->at));
    return gk_vd_gather(base, idx);
}
/* the same for GK_VF_W floats */
typedef struct gk_vf_win {
    __m512i lane; /* idx[l] - at */
    int32_t at;
    int ok;
} gk_vf_win;
GK_FORCE_INLINE void gk_vf_win_make(const int32_t *idx, int32_t n, gk_vf_win *w) {
    int32_t at = idx[0];
    w->lane = _mm512_sub_epi32(_mm512_loadu_si512((const void *)idx), _mm512_set1_epi32(at));
    w->at = at;
    w->ok = at >= 0 && at <= n - GK_VF_W &&
            _mm512_cmplt_epu32_mask(w->lane, _mm512_set1_epi32(GK_VF_W)) == 0xffff;
}
GK_FORCE_INLINE unsigned gk_vdm_bits(gk_vdm m) { return (unsigned)m; }
/* the number of set bits of a lane mask */
GK_FORCE_INLINE int gk__mask_count(unsigned m) {
#ifdef __POPCNT__
    return _mm_popcnt_u32(m);
#else
    int k = 0;
    for (; m; m &= m - 1) ++k;
    return k;
#endif
}
/* Compaction of a block of GK_VD_W int32 entries by a lane mask (512 bits
 * only): gk_i32_compress writes the src[l] whose bit l of m is set to dst in
 * lane order, and may write all GK_VD_W entries of dst; gk_i32_ranks writes
 * dst[l] = base + the number of set bits below bit l where bit l is set, -1
 * elsewhere, and returns the number of set bits. */
GK_FORCE_INLINE void gk_i32_compress(unsigned m, const int32_t *src, int32_t *dst) {
    __m512i v = _mm512_castsi256_si512(_mm256_loadu_si256((const __m256i *)(const void *)src));
    _mm256_storeu_si256((__m256i *)(void *)dst,
                        _mm512_castsi512_si256(_mm512_maskz_compress_epi32((__mmask16)m, v)));
}
GK_FORCE_INLINE int gk_i32_ranks(unsigned m, int32_t base, int32_t *dst) {
    __m512i r = _mm512_maskz_expand_epi32(
        (__mmask16)m, _mm512_add_epi32(_mm512_set1_epi32(base), _mm512_set_epi32(15, 14, 13, 12, 11, 10, 9, 8,
                                                                                 7, 6, 5, 4, 3, 2, 1, 0)));
    r = _mm512_mask_blend_epi32((__mmask16)m, _mm512_set1_epi32(-1), r);
    _mm256_storeu_si256((__m256i *)(void *)dst, _mm512_castsi512_si256(r));
    return gk__mask_count(m);
}
/* Candidate pairs of a block (a generic version below): for each lane l
 * whose bit of m is set, in lane order, the pair (p, (int32_t)q[l]) appended
 * to buf as two ints; may write GK_VD_W pairs; returns the number appended.
 * q holds GK_VD_W indices stored as doubles (exact). */
#define GK_HAS_PAIRS_COMPRESS 1
GK_FORCE_INLINE int gk_pairs_compress(unsigned m, int32_t p, const double *q, int32_t *buf) {
    __m512i qi = _mm512_cvtepu32_epi64(_mm512_cvttpd_epi32(_mm512_loadu_pd(q)));
    __m512i v = _mm512_or_si512(_mm512_slli_epi64(qi, 32), _mm512_set1_epi64((long long)(uint32_t)p));
    _mm512_storeu_si512((void *)buf, _mm512_maskz_compress_epi64((__mmask8)m, v));
    return gk__mask_count(m);
}
GK_FORCE_INLINE gk_vd gk_vd_xorsign(gk_vd a) { /* -a, exactly */
    return _mm512_castsi512_pd(
        _mm512_xor_si512(_mm512_castpd_si512(a), _mm512_set1_epi64((long long)0x8000000000000000ull)));
}
GK_FORCE_INLINE gk_vd gk_vd_abs(gk_vd a) { return _mm512_abs_pd(a); }
/* r[l][k] = r[k][l]: the 8 x 8 transpose, three rounds of two-source
 * shuffles (24); rows of lanes become per-lane records and back */
#define GK_VD_HAS_TRANSPOSE8 1
GK_FORCE_INLINE void gk_vd_transpose8(gk_vd r[8]) {
    /* written out: as loops, gcc kept them and passed the vectors through the
     * stack. t: pairs of rows interleaved (r0[0] r1[0] r0[2] r1[2] ...); u:
     * their 128-bit lanes 0 and 2 (0x88) or 1 and 3 (0xdd) side by side */
    gk_vd t0 = _mm512_unpacklo_pd(r[0], r[1]), t1 = _mm512_unpackhi_pd(r[0], r[1]);
    gk_vd t2 = _mm512_unpacklo_pd(r[2], r[3]), t3 = _mm512_unpackhi_pd(r[2], r[3]);
    gk_vd t4 = _mm512_unpacklo_pd(r[4], r[5]), t5 = _mm512_unpackhi_pd(r[4], r[5]);
    gk_vd t6 = _mm512_unpacklo_pd(r[6], r[7]), t7 = _mm512_unpackhi_pd(r[6], r[7]);
    gk_vd u0 = _mm512_shuffle_f64x2(t0, t2, 0x88), u1 = _mm512_shuffle_f64x2(t1, t3, 0x88);
    gk_vd u2 = _mm512_shuffle_f64x2(t0, t2, 0xdd), u3 = _mm512_shuffle_f64x2(t1, t3, 0xdd);
    gk_vd u4 = _mm512_shuffle_f64x2(t4, t6, 0x88), u5 = _mm512_shuffle_f64x2(t5, t7, 0x88);
    gk_vd u6 = _mm512_shuffle_f64x2(t4, t6, 0xdd), u7 = _mm512_shuffle_f64x2(t5, t7, 0xdd);
    r[0] = _mm512_shuffle_f64x2(u0, u4, 0x88);
    r[1] = _mm512_shuffle_f64x2(u1, u5, 0x88);
    r[2] = _mm512_shuffle_f64x2(u2, u6, 0x88);
    r[3] = _mm512_shuffle_f64x2(u3, u7, 0x88);
    r[4] = _mm512_shuffle_f64x2(u0, u4, 0xdd);
    r[5] = _mm512_shuffle_f64x2(u1, u5, 0xdd);
    r[6] = _mm512_shuffle_f64x2(u2, u6, 0xdd);
    r[7] = _mm512_shuffle_f64x2(u3, u7, 0xdd);
}
GK_FORCE_INLINE gk_vf gk_vf_zero(void) { return _mm512_setzero_ps(); }
GK_FORCE_INLINE gk_vf gk_vf_set1(float a) { return _mm512_set1_ps(a); }
GK_FORCE_INLINE gk_vf gk_vf_load(const float *p) { return _mm512_load_ps(p); }
GK_FORCE_INLINE gk_vf gk_vf_loadu(const float *p) { return _mm512_loadu_ps(p); }
GK_FORCE_INLINE void gk_vf_store(float *p, gk_vf a) { _mm512_store_ps(p, a); }
GK_FORCE_INLINE void gk_vf_storeu(float *p, gk_vf a) { _mm512_storeu_ps(p, a); }
GK_FORCE_INLINE gk_vf gk_vf_add(gk_vf a, gk_vf b) { return _mm512_add_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_sub(gk_vf a, gk_vf b) { return _mm512_sub_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_mul(gk_vf a, gk_vf b) { return _mm512_mul_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_div(gk_vf a, gk_vf b) { return _mm512_div_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_sqrt(gk_vf a) { return _mm512_sqrt_ps(a); }
GK_FORCE_INLINE gk_vf gk_vf_min(gk_vf a, gk_vf b) { return _mm512_min_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_max(gk_vf a, gk_vf b) { return _mm512_max_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_abs(gk_vf a) { return _mm512_abs_ps(a); }
GK_FORCE_INLINE gk_vf gk_vf_xorsign(gk_vf a) {
    return _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(a), _mm512_set1_epi32((int)0x80000000u)));
}
GK_FORCE_INLINE gk_vfm gk_vf_lt(gk_vf a, gk_vf b) { return _mm512_cmp_ps_mask(a, b, _CMP_LT_OQ); }
GK_FORCE_INLINE gk_vfm gk_vf_le(gk_vf a, gk_vf b) { return _mm512_cmp_ps_mask(a, b, _CMP_LE_OQ); }
GK_FORCE_INLINE gk_vfm gk_vf_gt(gk_vf a, gk_vf b) { return _mm512_cmp_ps_mask(a, b, _CMP_GT_OQ); }
GK_FORCE_INLINE gk_vfm gk_vfm_and(gk_vfm a, gk_vfm b) { return (gk_vfm)(a & b); }
GK_FORCE_INLINE gk_vfm gk_vfm_or(gk_vfm a, gk_vfm b) { return (gk_vfm)(a | b); }
GK_FORCE_INLINE gk_vfm gk_vfm_not(gk_vfm a) { return (gk_vfm)(~a); }
GK_FORCE_INLINE int gk_vfm_any(gk_vfm a) { return a != 0; }
GK_FORCE_INLINE unsigned gk_vfm_bits(gk_vfm m) { return (unsigned)m; }
GK_FORCE_INLINE gk_vf gk_vf_select(gk_vfm m, gk_vf a, gk_vf b) { return _mm512_mask_blend_ps(m, b, a); }
GK_FORCE_INLINE gk_vf gk_vf_gather(const float *base, const int32_t *idx) {
#ifdef GK_HW_GATHER
    return _mm512_i32gather_ps(_mm512_loadu_si512((const void *)idx), base, 4);
#else
    return _mm512_set_ps(base[idx[15]], base[idx[14]], base[idx[13]], base[idx[12]], base[idx[11]],
                         base[idx[10]], base[idx[9]], base[idx[8]], base[idx[7]], base[idx[6]], base[idx[5]],
                         base[idx[4]], base[idx[3]], base[idx[2]], base[idx[1]], base[idx[0]]);
#endif
}
GK_FORCE_INLINE gk_vf gk_vf_gather_win(const float *base, const int32_t *idx, const gk_vf_win *w) {
    if (w->ok) return _mm512_permutexvar_ps(w->lane, _mm512_loadu_ps(base + w->at));
    return gk_vf_gather(base, idx);
}
/* float lanes 0..7 (half 0) or 8..15 (half 1) widened to double, exactly */
GK_FORCE_INLINE gk_vd gk_vd_from_vf(gk_vf a, int half) {
    return half ? _mm512_cvtps_pd(_mm512_extractf32x8_ps(a, 1)) : _mm512_cvtps_pd(_mm512_castps512_ps256(a));
}
/* two double vectors (lanes 0..7, 8..15) rounded to one float vector */
GK_FORCE_INLINE gk_vf gk_vf_from_vd2(gk_vd lo, gk_vd hi) {
    return _mm512_insertf32x8(_mm512_castps256_ps512(_mm512_cvtpd_ps(lo)), _mm512_cvtpd_ps(hi), 1);
}
#elif GK_SIMD_WIDTH == 256
#include <immintrin.h>
#define GK_SIMD_NAME "avx2"
#define GK_VD_W 4
#define GK_VF_W 8
typedef __m256d gk_vd;
typedef __m256d gk_vdm;
typedef __m256 gk_vf;
typedef __m256 gk_vfm;
GK_FORCE_INLINE gk_vd gk_vd_zero(void) { return _mm256_setzero_pd(); }
GK_FORCE_INLINE gk_vd gk_vd_set1(double a) { return _mm256_set1_pd(a); }
GK_FORCE_INLINE gk_vd gk_vd_load(const double *p) { return _mm256_load_pd(p); }
GK_FORCE_INLINE gk_vd gk_vd_loadu(const double *p) { return _mm256_loadu_pd(p); }
GK_FORCE_INLINE void gk_vd_store(double *p, gk_vd a) { _mm256_store_pd(p, a); }
GK_FORCE_INLINE void gk_vd_storeu(double *p, gk_vd a) { _mm256_storeu_pd(p, a); }
GK_FORCE_INLINE gk_vd gk_vd_add(gk_vd a, gk_vd b) { return _mm256_add_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_sub(gk_vd a, gk_vd b) { return _mm256_sub_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_mul(gk_vd a, gk_vd b) { return _mm256_mul_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_div(gk_vd a, gk_vd b) { return _mm256_div_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_sqrt(gk_vd a) { return _mm256_sqrt_pd(a); }
GK_FORCE_INLINE gk_vd gk_vd_min(gk_vd a, gk_vd b) { return _mm256_min_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_max(gk_vd a, gk_vd b) { return _mm256_max_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_round(gk_vd a) {
    return _mm256_round_pd(a, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
}
GK_FORCE_INLINE gk_vd gk_vd_floor(gk_vd a) { return _mm256_floor_pd(a); }
GK_FORCE_INLINE gk_vdm gk_vd_lt(gk_vd a, gk_vd b) { return _mm256_cmp_pd(a, b, _CMP_LT_OQ); }
GK_FORCE_INLINE gk_vdm gk_vd_le(gk_vd a, gk_vd b) { return _mm256_cmp_pd(a, b, _CMP_LE_OQ); }
GK_FORCE_INLINE gk_vdm gk_vd_gt(gk_vd a, gk_vd b) { return _mm256_cmp_pd(a, b, _CMP_GT_OQ); }
GK_FORCE_INLINE gk_vdm gk_vdm_and(gk_vdm a, gk_vdm b) { return _mm256_and_pd(a, b); }
GK_FORCE_INLINE gk_vdm gk_vdm_or(gk_vdm a, gk_vdm b) { return _mm256_or_pd(a, b); }
GK_FORCE_INLINE gk_vdm gk_vdm_not(gk_vdm a) {
    return _mm256_xor_pd(a, _mm256_castsi256_pd(_mm256_set1_epi64x(-1)));
}
GK_FORCE_INLINE int gk_vdm_any(gk_vdm a) { return _mm256_movemask_pd(a) != 0; }
GK_FORCE_INLINE gk_vd gk_vd_select(gk_vdm m, gk_vd a, gk_vd b) { return _mm256_blendv_pd(b, a, m); }
GK_FORCE_INLINE gk_vd gk_vd_gather(const double *base, const int32_t *idx) {
#ifdef GK_HW_GATHER
    return _mm256_i32gather_pd(base, _mm_loadu_si128((const __m128i *)(const void *)idx), 8);
#else
    return _mm256_set_pd(base[idx[3]], base[idx[2]], base[idx[1]], base[idx[0]]);
#endif
}
GK_FORCE_INLINE unsigned gk_vdm_bits(gk_vdm m) { return (unsigned)_mm256_movemask_pd(m); }
GK_FORCE_INLINE gk_vd gk_vd_xorsign(gk_vd a) { return _mm256_xor_pd(a, _mm256_set1_pd(-0.0)); }
GK_FORCE_INLINE gk_vd gk_vd_abs(gk_vd a) { return _mm256_andnot_pd(_mm256_set1_pd(-0.0), a); }
GK_FORCE_INLINE gk_vf gk_vf_zero(void) { return _mm256_setzero_ps(); }
GK_FORCE_INLINE gk_vf gk_vf_set1(float a) { return _mm256_set1_ps(a); }
GK_FORCE_INLINE gk_vf gk_vf_load(const float *p) { return _mm256_load_ps(p); }
GK_FORCE_INLINE gk_vf gk_vf_loadu(const float *p) { return _mm256_loadu_ps(p); }
GK_FORCE_INLINE void gk_vf_store(float *p, gk_vf a) { _mm256_store_ps(p, a); }
GK_FORCE_INLINE void gk_vf_storeu(float *p, gk_vf a) { _mm256_storeu_ps(p, a); }
GK_FORCE_INLINE gk_vf gk_vf_add(gk_vf a, gk_vf b) { return _mm256_add_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_sub(gk_vf a, gk_vf b) { return _mm256_sub_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_mul(gk_vf a, gk_vf b) { return _mm256_mul_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_div(gk_vf a, gk_vf b) { return _mm256_div_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_sqrt(gk_vf a) { return _mm256_sqrt_ps(a); }
GK_FORCE_INLINE gk_vf gk_vf_min(gk_vf a, gk_vf b) { return _mm256_min_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_max(gk_vf a, gk_vf b) { return _mm256_max_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_abs(gk_vf a) { return _mm256_andnot_ps(_mm256_set1_ps(-0.0f), a); }
GK_FORCE_INLINE gk_vf gk_vf_xorsign(gk_vf a) { return _mm256_xor_ps(a, _mm256_set1_ps(-0.0f)); }
GK_FORCE_INLINE gk_vfm gk_vf_lt(gk_vf a, gk_vf b) { return _mm256_cmp_ps(a, b, _CMP_LT_OQ); }
GK_FORCE_INLINE gk_vfm gk_vf_le(gk_vf a, gk_vf b) { return _mm256_cmp_ps(a, b, _CMP_LE_OQ); }
GK_FORCE_INLINE gk_vfm gk_vf_gt(gk_vf a, gk_vf b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
GK_FORCE_INLINE gk_vfm gk_vfm_and(gk_vfm a, gk_vfm b) { return _mm256_and_ps(a, b); }
GK_FORCE_INLINE gk_vfm gk_vfm_or(gk_vfm a, gk_vfm b) { return _mm256_or_ps(a, b); }
GK_FORCE_INLINE gk_vfm gk_vfm_not(gk_vfm a) {
    return _mm256_xor_ps(a, _mm256_castsi256_ps(_mm256_set1_epi32(-1)));
}
GK_FORCE_INLINE int gk_vfm_any(gk_vfm a) { return _mm256_movemask_ps(a) != 0; }
GK_FORCE_INLINE unsigned gk_vfm_bits(gk_vfm m) { return (unsigned)_mm256_movemask_ps(m); }
GK_FORCE_INLINE gk_vf gk_vf_select(gk_vfm m, gk_vf a, gk_vf b) { return _mm256_blendv_ps(b, a, m); }
GK_FORCE_INLINE gk_vf gk_vf_gather(const float *base, const int32_t *idx) {
#ifdef GK_HW_GATHER
    return _mm256_i32gather_ps(base, _mm256_loadu_si256((const __m256i *)(const void *)idx), 4);
#else
    return _mm256_set_ps(base[idx[7]], base[idx[6]], base[idx[5]], base[idx[4]], base[idx[3]], base[idx[2]],
                         base[idx[1]], base[idx[0]]);
#endif
}
GK_FORCE_INLINE gk_vf gk_vf_from_vd2(gk_vd lo, gk_vd hi) {
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm256_cvtpd_ps(lo)), _mm256_cvtpd_ps(hi), 1);
}
GK_FORCE_INLINE gk_vd gk_vd_from_vf(gk_vf a, int half) {
    return half ? _mm256_cvtps_pd(_mm256_extractf128_ps(a, 1)) : _mm256_cvtps_pd(_mm256_castps256_ps128(a));
}
#elif GK_SIMD_WIDTH == 128
#include <smmintrin.h>
#define GK_SIMD_NAME "sse4"
#define GK_VD_W 2
#define GK_VF_W 4
typedef __m128d gk_vd;
typedef __m128d gk_vdm;
typedef __m128 gk_vf;
typedef __m128 gk_vfm;
GK_FORCE_INLINE gk_vd gk_vd_zero(void) { return _mm_setzero_pd(); }
GK_FORCE_INLINE gk_vd gk_vd_set1(double a) { return _mm_set1_pd(a); }
GK_FORCE_INLINE gk_vd gk_vd_load(const double *p) { return _mm_load_pd(p); }
GK_FORCE_INLINE gk_vd gk_vd_loadu(const double *p) { return _mm_loadu_pd(p); }
GK_FORCE_INLINE void gk_vd_store(double *p, gk_vd a) { _mm_store_pd(p, a); }
GK_FORCE_INLINE void gk_vd_storeu(double *p, gk_vd a) { _mm_storeu_pd(p, a); }
GK_FORCE_INLINE gk_vd gk_vd_add(gk_vd a, gk_vd b) { return _mm_add_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_sub(gk_vd a, gk_vd b) { return _mm_sub_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_mul(gk_vd a, gk_vd b) { return _mm_mul_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_div(gk_vd a, gk_vd b) { return _mm_div_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_sqrt(gk_vd a) { return _mm_sqrt_pd(a); }
GK_FORCE_INLINE gk_vd gk_vd_min(gk_vd a, gk_vd b) { return _mm_min_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_max(gk_vd a, gk_vd b) { return _mm_max_pd(a, b); }
GK_FORCE_INLINE gk_vd gk_vd_round(gk_vd a) {
    return _mm_round_pd(a, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
}
GK_FORCE_INLINE gk_vd gk_vd_floor(gk_vd a) { return _mm_floor_pd(a); }
GK_FORCE_INLINE gk_vdm gk_vd_lt(gk_vd a, gk_vd b) { return _mm_cmplt_pd(a, b); }
GK_FORCE_INLINE gk_vdm gk_vd_le(gk_vd a, gk_vd b) { return _mm_cmple_pd(a, b); }
GK_FORCE_INLINE gk_vdm gk_vd_gt(gk_vd a, gk_vd b) { return _mm_cmpgt_pd(a, b); }
GK_FORCE_INLINE gk_vdm gk_vdm_and(gk_vdm a, gk_vdm b) { return _mm_and_pd(a, b); }
GK_FORCE_INLINE gk_vdm gk_vdm_or(gk_vdm a, gk_vdm b) { return _mm_or_pd(a, b); }
GK_FORCE_INLINE gk_vdm gk_vdm_not(gk_vdm a) { return _mm_xor_pd(a, _mm_castsi128_pd(_mm_set1_epi64x(-1))); }
GK_FORCE_INLINE int gk_vdm_any(gk_vdm a) { return _mm_movemask_pd(a) != 0; }
GK_FORCE_INLINE gk_vd gk_vd_select(gk_vdm m, gk_vd a, gk_vd b) { return _mm_blendv_pd(b, a, m); }
GK_FORCE_INLINE gk_vd gk_vd_gather(const double *base, const int32_t *idx) {
    return _mm_set_pd(base[idx[1]], base[idx[0]]);
}
GK_FORCE_INLINE unsigned gk_vdm_bits(gk_vdm m) { return (unsigned)_mm_movemask_pd(m); }
GK_FORCE_INLINE gk_vd gk_vd_xorsign(gk_vd a) { return _mm_xor_pd(a, _mm_set1_pd(-0.0)); }
GK_FORCE_INLINE gk_vd gk_vd_abs(gk_vd a) { return _mm_andnot_pd(_mm_set1_pd(-0.0), a); }
GK_FORCE_INLINE gk_vf gk_vf_zero(void) { return _mm_setzero_ps(); }
GK_FORCE_INLINE gk_vf gk_vf_set1(float a) { return _mm_set1_ps(a); }
GK_FORCE_INLINE gk_vf gk_vf_load(const float *p) { return _mm_load_ps(p); }
GK_FORCE_INLINE gk_vf gk_vf_loadu(const float *p) { return _mm_loadu_ps(p); }
GK_FORCE_INLINE void gk_vf_store(float *p, gk_vf a) { _mm_store_ps(p, a); }
GK_FORCE_INLINE void gk_vf_storeu(float *p, gk_vf a) { _mm_storeu_ps(p, a); }
GK_FORCE_INLINE gk_vf gk_vf_add(gk_vf a, gk_vf b) { return _mm_add_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_sub(gk_vf a, gk_vf b) { return _mm_sub_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_mul(gk_vf a, gk_vf b) { return _mm_mul_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_div(gk_vf a, gk_vf b) { return _mm_div_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_sqrt(gk_vf a) { return _mm_sqrt_ps(a); }
GK_FORCE_INLINE gk_vf gk_vf_min(gk_vf a, gk_vf b) { return _mm_min_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_max(gk_vf a, gk_vf b) { return _mm_max_ps(a, b); }
GK_FORCE_INLINE gk_vf gk_vf_abs(gk_vf a) { return _mm_andnot_ps(_mm_set1_ps(-0.0f), a); }
GK_FORCE_INLINE gk_vf gk_vf_xorsign(gk_vf a) { return _mm_xor_ps(a, _mm_set1_ps(-0.0f)); }
GK_FORCE_INLINE gk_vfm gk_vf_lt(gk_vf a, gk_vf b) { return _mm_cmplt_ps(a, b); }
GK_FORCE_INLINE gk_vfm gk_vf_le(gk_vf a, gk_vf b) { return _mm_cmple_ps(a, b); }
GK_FORCE_INLINE gk_vfm gk_vf_gt(gk_vf a, gk_vf b) { return _mm_cmpgt_ps(a, b); }
GK_FORCE_INLINE gk_vfm gk_vfm_and(gk_vfm a, gk_vfm b) { return _mm_and_ps(a, b); }
GK_FORCE_INLINE gk_vfm gk_vfm_or(gk_vfm a, gk_vfm b) { return _mm_or_ps(a, b); }
GK_FORCE_INLINE gk_vfm gk_vfm_not(gk_vfm a) { return _mm_xor_ps(a, _mm_castsi128_ps(_mm_set1_epi32(-1))); }
GK_FORCE_INLINE int gk_vfm_any(gk_vfm a) { return _mm_movemask_ps(a) != 0; }
GK_FORCE_INLINE unsigned gk_vfm_bits(gk_vfm m) { return (unsigned)_mm_movemask_ps(m); }
GK_FORCE_INLINE gk_vf gk_vf_select(gk_vfm m, gk_vf a, gk_vf b) { return _mm_blendv_ps(b, a, m); }
GK_FORCE_INLINE gk_vf gk_vf_gather(const float *base, const int32_t *idx) {
    return _mm_set_ps(base[idx[3]], base[idx[2]], base[idx[1]], base[idx[0]]);
}
GK_FORCE_INLINE gk_vf gk_vf_from_vd2(gk_vd lo, gk_vd hi) {
    return _mm_movelh_ps(_mm_cvtpd_ps(lo), _mm_cvtpd_ps(hi));
}
GK_FORCE_INLINE gk_vd gk_vd_from_vf(gk_vf a, int half) {
    return _mm_cvtps_pd(half ? _mm_movehl_ps(a, a) : a);
}
#else
#define GK_SIMD_NAME "scalar"
#define GK_VD_W 1
#define GK_VF_W 1
typedef double gk_vd;
typedef int gk_vdm;
typedef float gk_vf;
typedef int gk_vfm;
GK_FORCE_INLINE gk_vd gk_vd_zero(void) { return 0.0; }
GK_FORCE_INLINE gk_vd gk_vd_set1(double a) { return a; }
GK_FORCE_INLINE gk_vd gk_vd_load(const double *p) { return *p; }
GK_FORCE_INLINE gk_vd gk_vd_loadu(const double *p) { return *p; }
GK_FORCE_INLINE void gk_vd_store(double *p, gk_vd a) { *p = a; }
GK_FORCE_INLINE void gk_vd_storeu(double *p, gk_vd a) { *p = a; }
GK_FORCE_INLINE gk_vd gk_vd_add(gk_vd a, gk_vd b) { return a + b; }
GK_FORCE_INLINE gk_vd gk_vd_sub(gk_vd a, gk_vd b) { return a - b; }
GK_FORCE_INLINE gk_vd gk_vd_mul(gk_vd a, gk_vd b) { return a * b; }
GK_FORCE_INLINE gk_vd gk_vd_div(gk_vd a, gk_vd b) { return a / b; }
GK_FORCE_INLINE gk_vd gk_vd_sqrt(gk_vd a) { return sqrt(a); }
/* min/max follow the x86 rule (second operand if either is NaN) */
GK_FORCE_INLINE gk_vd gk_vd_min(gk_vd a, gk_vd b) { return a < b ? a : b; }
GK_FORCE_INLINE gk_vd gk_vd_max(gk_vd a, gk_vd b) { return a > b ? a : b; }
GK_FORCE_INLINE gk_vd gk_vd_round(gk_vd a) { return rint(a); }
GK_FORCE_INLINE gk_vd gk_vd_floor(gk_vd a) { return floor(a); }
GK_FORCE_INLINE gk_vdm gk_vd_lt(gk_vd a, gk_vd b) { return a < b; }
GK_FORCE_INLINE gk_vdm gk_vd_le(gk_vd a, gk_vd b) { return a <= b; }
GK_FORCE_INLINE gk_vdm gk_vd_gt(gk_vd a, gk_vd b) { return a > b; }
GK_FORCE_INLINE gk_vdm gk_vdm_and(gk_vdm a, gk_vdm b) { return a && b; }
GK_FORCE_INLINE gk_vdm gk_vdm_or(gk_vdm a, gk_vdm b) { return a || b; }
GK_FORCE_INLINE gk_vdm gk_vdm_not(gk_vdm a) { return !a; }
GK_FORCE_INLINE int gk_vdm_any(gk_vdm a) { return a; }
GK_FORCE_INLINE gk_vd gk_vd_select(gk_vdm m, gk_vd a, gk_vd b) { return m ? a : b; }
GK_FORCE_INLINE gk_vd gk_vd_gather(const double *base, const int32_t *idx) { return base[idx[0]]; }
GK_FORCE_INLINE unsigned gk_vdm_bits(gk_vdm m) { return (unsigned)(m != 0); }
GK_FORCE_INLINE gk_vd gk_vd_xorsign(gk_vd a) { return -a; }
GK_FORCE_INLINE gk_vd gk_vd_abs(gk_vd a) { return fabs(a); }
GK_FORCE_INLINE gk_vf gk_vf_zero(void) { return 0.0f; }
GK_FORCE_INLINE gk_vf gk_vf_set1(float a) { return a; }
GK_FORCE_INLINE gk_vf gk_vf_load(const float *p) { return *p; }
GK_FORCE_INLINE gk_vf gk_vf_loadu(const float *p) { return *p; }
GK_FORCE_INLINE void gk_vf_store(float *p, gk_vf a) { *p = a; }
GK_FORCE_INLINE void gk_vf_storeu(float *p, gk_vf a) { *p = a; }
GK_FORCE_INLINE gk_vf gk_vf_add(gk_vf a, gk_vf b) { return a + b; }
GK_FORCE_INLINE gk_vf gk_vf_sub(gk_vf a, gk_vf b) { return a - b; }
GK_FORCE_INLINE gk_vf gk_vf_mul(gk_vf a, gk_vf b) { return a * b; }
GK_FORCE_INLINE gk_vf gk_vf_div(gk_vf a, gk_vf b) { return a / b; }
GK_FORCE_INLINE gk_vf gk_vf_sqrt(gk_vf a) { return (float)sqrt((double)a); }
GK_FORCE_INLINE gk_vf gk_vf_min(gk_vf a, gk_vf b) { return a < b ? a : b; }
GK_FORCE_INLINE gk_vf gk_vf_max(gk_vf a, gk_vf b) { return a > b ? a : b; }
GK_FORCE_INLINE gk_vf gk_vf_abs(gk_vf a) { return (float)fabs((double)a); }
GK_FORCE_INLINE gk_vf gk_vf_xorsign(gk_vf a) { return -a; }
GK_FORCE_INLINE gk_vfm gk_vf_lt(gk_vf a, gk_vf b) { return a < b; }
GK_FORCE_INLINE gk_vfm gk_vf_le(gk_vf a, gk_vf b) { return a <= b; }
GK_FORCE_INLINE gk_vfm gk_vf_gt(gk_vf a, gk_vf b) { return a > b; }
GK_FORCE_INLINE gk_vfm gk_vfm_and(gk_vfm a, gk_vfm b) { return a && b; }
GK_FORCE_INLINE gk_vfm gk_vfm_or(gk_vfm a, gk_vfm b) { return a || b; }
GK_FORCE_INLINE gk_vfm gk_vfm_not(gk_vfm a) { return !a; }
GK_FORCE_INLINE int gk_vfm_any(gk_vfm a) { return a; }
GK_FORCE_INLINE unsigned gk_vfm_bits(gk_vfm m) { return (unsigned)(m != 0); }
GK_FORCE_INLINE gk_vf gk_vf_select(gk_vfm m, gk_vf a, gk_vf b) { return m ? a : b; }
GK_FORCE_INLINE gk_vf gk_vf_gather(const float *base, const int32_t *idx) { return base[idx[0]]; }
/* the scalar build has one float lane and one double lane: only `lo` is used */
GK_FORCE_INLINE gk_vf gk_vf_from_vd2(gk_vd lo, gk_vd hi) {
    (void)hi;
    return (float)lo;
}
GK_FORCE_INLINE gk_vd gk_vd_from_vf(gk_vf a, int half) {
    (void)half;
    return (double)a;
}
#endif

#ifndef GK_HAS_PAIRS_COMPRESS
GK_FORCE_INLINE int gk_pairs_compress(unsigned m, int32_t p, const double *q, int32_t *buf) {
    int l, k = 0;
    for (l = 0; l < GK_VD_W; ++l) { /* written always, kept where the bit is set */
        buf[2 * k] = p;
        buf[2 * k + 1] = (int32_t)q[l];
        k += (int)(m >> l & 1u);
    }
    return k;
}
#endif

#ifndef GK_VD_HAS_WIN
/* No window gather below 512 bits (with AVX2's 4 lanes it saved nothing,
 * measured): gk_vd_win_make and gk_vf_win_make always say no, the window
 * gathers are gathers. */
typedef struct gk_vd_win {
    int ok;
} gk_vd_win;
GK_FORCE_INLINE void gk_vd_win_make(const int32_t *idx, int32_t n, gk_vd_win *w) {
    (void)idx;
    (void)n;
    w->ok = 0;
}
GK_FORCE_INLINE gk_vd gk_vd_gather_win(const double *base, const int32_t *idx, const gk_vd_win *w) {
    (void)w;
    return gk_vd_gather(base, idx);
}
typedef struct gk_vf_win {
    int ok;
} gk_vf_win;
GK_FORCE_INLINE void gk_vf_win_make(const int32_t *idx, int32_t n, gk_vf_win *w) {
    (void)idx;
    (void)n;
    w->ok = 0;
}
GK_FORCE_INLINE gk_vf gk_vf_gather_win(const float *base, const int32_t *idx, const gk_vf_win *w) {
    (void)w;
    return gk_vf_gather(base, idx);
}
#endif

/* The working-precision wide type gk_vr (GK_VR_W lanes of gk_real) used by
 * the DEM kernels; positions stay double (gk_vd). */
#ifdef GK_REAL_FLOAT
typedef gk_vf gk_vr;
typedef gk_vfm gk_vrm;
#define GK_VR_W GK_VF_W
#define GK_VR_DHALVES (GK_VF_W == 1 ? 1 : 2) /* double vectors per gk_vr */
#define gk_vr_zero gk_vf_zero
#define gk_vr_set1 gk_vf_set1
#define gk_vr_load gk_vf_load
#define gk_vr_loadu gk_vf_loadu
#define gk_vr_store gk_vf_store
#define gk_vr_storeu gk_vf_storeu
#define gk_vr_add gk_vf_add
#define gk_vr_sub gk_vf_sub
#define gk_vr_mul gk_vf_mul
#define gk_vr_div gk_vf_div
#define gk_vr_sqrt gk_vf_sqrt
#define gk_vr_min gk_vf_min
#define gk_vr_max gk_vf_max
#define gk_vr_abs gk_vf_abs
#define gk_vr_neg gk_vf_xorsign
#define gk_vr_lt gk_vf_lt
#define gk_vr_le gk_vf_le
#define gk_vr_gt gk_vf_gt
#define gk_vrm_and gk_vfm_and
#define gk_vrm_or gk_vfm_or
#define gk_vrm_not gk_vfm_not
#define gk_vrm_any gk_vfm_any
#define gk_vrm_bits gk_vfm_bits
#define gk_vr_select gk_vf_select
#define gk_vr_gather gk_vf_gather
typedef gk_vf_win gk_vr_win;
#define gk_vr_win_make gk_vf_win_make
#define gk_vr_gather_win gk_vf_gather_win
#else
typedef gk_vd gk_vr;
typedef gk_vdm gk_vrm;
#define GK_VR_W GK_VD_W
#define GK_VR_DHALVES 1
#define gk_vr_zero gk_vd_zero
#define gk_vr_set1 gk_vd_set1
#define gk_vr_load gk_vd_load
#define gk_vr_loadu gk_vd_loadu
#define gk_vr_store gk_vd_store
#define gk_vr_storeu gk_vd_storeu
#define gk_vr_add gk_vd_add
#define gk_vr_sub gk_vd_sub
#define gk_vr_mul gk_vd_mul
#define gk_vr_div gk_vd_div
#define gk_vr_sqrt gk_vd_sqrt
#define gk_vr_min gk_vd_min
#define gk_vr_max gk_vd_max
#define gk_vr_abs gk_vd_abs
#define gk_vr_neg gk_vd_xorsign
#define gk_vr_lt gk_vd_lt
#define gk_vr_le gk_vd_le
#define gk_vr_gt gk_vd_gt
#define gk_vrm_and gk_vdm_and
#define gk_vrm_or gk_vdm_or
#define gk_vrm_not gk_vdm_not
#define gk_vrm_any gk_vdm_any
#define gk_vrm_bits gk_vdm_bits
#define gk_vr_select gk_vd_select
#define gk_vr_gather gk_vd_gather
typedef gk_vd_win gk_vr_win;
#define gk_vr_win_make gk_vd_win_make
#define gk_vr_gather_win gk_vd_gather_win
#endif

#endif /* GK_BASE_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_BASE_IMPLEMENTATION)) && !defined(GK_BASE_IMPL_ONCE)
#define GK_BASE_IMPL_ONCE

#include <errno.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#ifndef GK_MALLOC
#include <stdlib.h>
#define GK_MALLOC(n) malloc(n)
#define GK_FREE(p) free(p)
#endif

GKDEF const char *gk_version(void) { return GK_VERSION_STRING " (" GK_REAL_NAME ", " GK_SIMD_NAME ")"; }

GKDEF const char *gk_result_string(gk_result r) {
    switch (r) {
    case GK_OK: return "ok";
    case GK_ERR_ARG: return "invalid argument";
    case GK_ERR_NAN: return "NaN or infinite value";
    case GK_ERR_RADIUS: return "invalid radius";
    case GK_ERR_MASS: return "invalid mass or density";
    case GK_ERR_DT: return "invalid time step";
    case GK_ERR_ALLOC: return "out of memory";
    case GK_ERR_IO: return "input/output error";
    case GK_ERR_FORMAT: return "malformed input";
    case GK_ERR_CELL: return "invalid periodic cell";
    case GK_ERR_OUTSIDE: return "particle outside the cell";
    case GK_ERR_SINGULAR: return "singular matrix";
    case GK_ERR_DIVERGED: return "diverged";
    case GK_ERR_STATE: return "invalid state for this call";
    case GK_ERR_MESH: return "invalid mesh";
    case GK_ERR_UNSUPPORTED: return "unsupported";
    case GK_ERR_NOCONVERGE: return "did not converge";
    default: return "unknown result code";
    }
}

GKDEF gk_result gk_err_set(gk_err *e, gk_result code, const char *fmt, ...) {
    if (e) {
        va_list ap;
        e->code = code;
        va_start(ap, fmt);
        vsnprintf(e->msg, sizeof e->msg, fmt, ap);
        va_end(ap);
    }
    return code;
}

GKDEF void gk_err_clear(gk_err *e) {
    if (e) {
        e->code = GK_OK;
        e->msg[0] = '\0';
    }
}

/* Default aligned allocation on plain malloc: over-allocate, store the offset. */
static void *gk__default_alloc(size_t size, size_t align, void *user) {
    unsigned char *raw, *p;
    (void)user;
    if (align < sizeof(void *)) align = sizeof(void *);
    if (size > (size_t)-1 - align - sizeof(void *)) return NULL;
    raw = (unsigned char *)GK_MALLOC(size + align + sizeof(void *));
    if (!raw) return NULL;
    p = raw + sizeof(void *);
    p += (align - ((uintptr_t)p & (align - 1))) & (align - 1);
    memcpy(p - sizeof(void *), &raw, sizeof(void *));
    return p;
}
static void gk__default_free(void *ptr, void *user) {
    unsigned char *raw;
    (void)user;
    if (!ptr) return;
    memcpy(&raw, (unsigned char *)ptr - sizeof(void *), sizeof(void *));
    GK_FREE(raw);
}

GKDEF void *gk_alloc(const gk_allocator *a, size_t size) {
    if (size == 0) size = 1;
    if (a && a->alloc) return a->alloc(size, GK_ALIGN, a->user);
    return gk__default_alloc(size, GK_ALIGN, NULL);
}
GKDEF void gk_free(const gk_allocator *a, void *ptr) {
    if (!ptr) return;
    if (a && a->alloc) {
        if (a->free) a->free(ptr, a->user);
    } else {
        gk__default_free(ptr, NULL);
    }
}
GKDEF gk_result gk_realloc(const gk_allocator *a, void **ptr, size_t old_n, size_t new_n, size_t elem_size) {
    void *p;
    if (new_n != 0 && elem_size > (size_t)-1 / new_n) return GK_ERR_ALLOC;
    p = gk_alloc(a, new_n * elem_size);
    if (!p) return GK_ERR_ALLOC;
    if (*ptr && old_n) memcpy(p, *ptr, (old_n < new_n ? old_n : new_n) * elem_size);
    gk_free(a, *ptr);
    *ptr = p;
    return GK_OK;
}

#ifndef GK_FILE_MAX
#define GK_FILE_MAX ((size_t)INT_MAX)
#endif
GKDEF gk_result gk_file_read(const char *path, const gk_allocator *alloc, char **text, size_t *len,
                             gk_err *err) {
    FILE *fp;
    char *buf = NULL;
    size_t n = 0, cap = 0;
    int bad;
    if (!path) return gk_err_set(err, GK_ERR_ARG, "no file name given");
    errno = 0;
    fp = fopen(path, "rb");
    if (!fp)
        return gk_err_set(err, GK_ERR_IO, "cannot open '%s': %s", path,
                          errno ? strerror(errno) : "unknown error");
    for (;;) {
        size_t got;
        if (n + 1 >= cap) { /* grow by doubling; one byte always left for the NUL */
            size_t nc = cap ? 2 * cap : 65536;
            if (cap > GK_FILE_MAX) {
                fclose(fp);
                gk_free(alloc, buf);
                return gk_err_set(err, GK_ERR_IO, "'%s' is larger than %lu bytes (GK_FILE_MAX)", path,
                                  (unsigned long)GK_FILE_MAX);
            }
            if (gk_realloc(alloc, (void **)&buf, n, nc, 1)) {
                fclose(fp);
                gk_free(alloc, buf);
                return gk_err_set(err, GK_ERR_ALLOC, "out of memory reading '%s' (%lu bytes so far)", path,
                                  (unsigned long)n);
            }
            cap = nc;
        }
        errno = 0;
        got = fread(buf + n, 1, cap - 1 - n, fp);
        n += got;
        if (got == 0) break;
    }
    bad = ferror(fp);
    if (bad) {
        int e = errno;
        fclose(fp);
        gk_free(alloc, buf);
        return gk_err_set(err, GK_ERR_IO, "cannot read '%s': %s", path, e ? strerror(e) : "read error");
    }
    fclose(fp);
    if (n > GK_FILE_MAX) {
        gk_free(alloc, buf);
        return gk_err_set(err, GK_ERR_IO, "'%s' is larger than %lu bytes (GK_FILE_MAX)", path,
                          (unsigned long)GK_FILE_MAX);
    }
    buf[n] = '\0';
    *text = buf;
    *len = n;
    return GK_OK;
}

GKDEF gk_result gk_file_close(FILE *fp, const char *path, gk_err *err) {
    int bad, e;
    if (!fp) return gk_err_set(err, GK_ERR_ARG, "no file to close ('%s')", path ? path : "");
    errno = 0;
    bad = fflush(fp) != 0 || ferror(fp);
    e = errno;
    if (fclose(fp) != 0) {
        bad = 1;
        if (!e) e = errno;
    }
    if (bad)
        return gk_err_set(err, GK_ERR_IO, "error writing '%s': %s", path ? path : "file",
                          e ? strerror(e) : "write error");
    return GK_OK;
}

/* ---- random numbers: splitmix64 seeding, xoshiro256** generator */
static uint64_t gk__splitmix64(uint64_t *x) {
    uint64_t z = (*x += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
GKDEF void gk_rng_seed(gk_rng *r, uint64_t seed) {
    int k;
    for (k = 0; k < 4; ++k) r->s[k] = gk__splitmix64(&seed);
}
static uint64_t gk__rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
GKDEF uint64_t gk_rng_u64(gk_rng *r) {
    uint64_t *s = r->s;
    uint64_t result = gk__rotl(s[1] * 5, 7) * 9;
    uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = gk__rotl(s[3], 45);
    return result;
}
GKDEF double gk_rng_uniform(gk_rng *r) { return (double)(gk_rng_u64(r) >> 11) * (1.0 / 9007199254740992.0); }
GKDEF double gk_rng_normal(gk_rng *r) {
    double u1 = 1.0 - gk_rng_uniform(r); /* (0, 1] */
    double u2 = gk_rng_uniform(r);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * GK_PI * u2);
}

/* ---- tensors */
GKDEF double gk_m3_inverse(const double a[9], double inv[9]) {
    double det = gk_m3_det(a), id;
    if (det == 0.0 || !isfinite(det)) return det;
    id = 1.0 / det;
    inv[0] = (a[4] * a[8] - a[5] * a[7]) * id;
    inv[1] = (a[2] * a[7] - a[1] * a[8]) * id;
    inv[2] = (a[1] * a[5] - a[2] * a[4]) * id;
    inv[3] = (a[5] * a[6] - a[3] * a[8]) * id;
    inv[4] = (a[0] * a[8] - a[2] * a[6]) * id;
    inv[5] = (a[2] * a[3] - a[0] * a[5]) * id;
    inv[6] = (a[3] * a[7] - a[4] * a[6]) * id;
    inv[7] = (a[1] * a[6] - a[0] * a[7]) * id;
    inv[8] = (a[0] * a[4] - a[1] * a[3]) * id;
    return det;
}

GKDEF void gk_m3_sym_eigen(const double a_in[9], double val[3], double vec[9]) {
    double a[9];
    int sweep, p, q, k, i, j;
    gk_m3_sym(a_in, a);
    gk_m3_identity(vec);
    for (sweep = 0; sweep < 50; ++sweep) {
        double off = a[1] * a[1] + a[2] * a[2] + a[5] * a[5];
        double scale = a[0] * a[0] + a[4] * a[4] + a[8] * a[8] + 2.0 * off;
        if (off <= 1e-32 * scale || off == 0.0) break;
        for (p = 0; p < 2; ++p) {
            for (q = p + 1; q < 3; ++q) {
                double apq = a[3 * p + q], app, aqq, theta, t, c, s;
                if (apq == 0.0) continue;
                app = a[3 * p + p];
                aqq = a[3 * q + q];
                theta = (aqq - app) / (2.0 * apq);
                t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                c = 1.0 / sqrt(t * t + 1.0);
                s = t * c;
                for (k = 0; k < 3; ++k) { /* A <- A J (columns p, q) */
                    double akp = a[3 * k + p], akq = a[3 * k + q];
                    a[3 * k + p] = c * akp - s * akq;
                    a[3 * k + q] = s * akp + c * akq;
                }
                for (k = 0; k < 3; ++k) { /* A <- J^T A (rows p, q) */
                    double apk = a[3 * p + k], aqk = a[3 * q + k];
                    a[3 * p + k] = c * apk - s * aqk;
                    a[3 * q + k] = s * apk + c * aqk;
                }
                for (k = 0; k < 3; ++k) {
                    double vkp = vec[3 * k + p], vkq = vec[3 * k + q];
                    vec[3 * k + p] = c * vkp - s * vkq;
                    vec[3 * k + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    for (k = 0; k < 3; ++k) val[k] = a[4 * k];
    /* sort ascending, permuting columns */
    for (i = 0; i < 2; ++i)
        for (j = i + 1; j < 3; ++j)
            if (val[j] < val[i]) {
                double t = val[i];
                val[i] = val[j];
                val[j] = t;
                for (k = 0; k < 3; ++k) {
                    t = vec[3 * k + i];
                    vec[3 * k + i] = vec[3 * k + j];
                    vec[3 * k + j] = t;
                }
            }
}

GKDEF gk_result gk_m3_polar(const double F[9], int dim, double R[9], double U[9]) {
    double Rt[9];
    if (dim == 2) {
        /* closed form: R = rotation by atan2(F10 - F01, F00 + F11) */
        double det = F[0] * F[4] - F[1] * F[3];
        double c, s, th;
        if (!(det > 0.0) || !isfinite(det)) return GK_ERR_SINGULAR;
        th = atan2(F[3] - F[1], F[0] + F[4]);
        c = cos(th);
        s = sin(th);
        gk_m3_identity(R);
        R[0] = c;
        R[1] = -s;
        R[3] = s;
        R[4] = c;
    } else {
        /* Higham's scaled Newton iteration R <- (g R + R^-T / g)/2 */
        double X[9], Xi[9], det;
        int it, k;
        det = gk_m3_det(F);
        if (!(det > 0.0) || !isfinite(det)) return GK_ERR_SINGULAR;
        gk_m3_copy(F, X);
        for (it = 0; it < 100; ++it) {
            double d = gk_m3_inverse(X, Xi), g, diff = 0.0, XiT[9];
            if (d == 0.0) return GK_ERR_SINGULAR;
            g = pow(fabs(d), -1.0 / 3.0);
            gk_m3_transpose(Xi, XiT);
            for (k = 0; k < 9; ++k) {
                double nx = 0.5 * (g * X[k] + XiT[k] / g);
                diff += (nx - X[k]) * (nx - X[k]);
                X[k] = nx;
            }
            if (diff < 1e-30) break;
        }
        gk_m3_copy(X, R);
    }
    gk_m3_transpose(R, Rt);
    gk_m3_mul(Rt, F, U);
    { /* symmetrise U against round-off */
        double S[9];
        gk_m3_sym(U, S);
        gk_m3_copy(S, U);
    }
    return GK_OK;
}

GKDEF void gk_m3_exp(const double A[9], double E[9]) {
    double B[9], T[9], P[9], nrm = gk_m3_norm(A);
    int s = 0, k, i;
    while (nrm > 0.5 && s < 60) {
        nrm *= 0.5;
        ++s;
    }
    for (k = 0; k < 9; ++k) B[k] = ldexp(A[k], -s);
    gk_m3_identity(E);
    gk_m3_identity(T);
    for (i = 1; i <= 20; ++i) { /* Taylor: |B| <= 0.5, 20 terms reach 1e-25 */
        gk_m3_mul(T, B, P);
        for (k = 0; k < 9; ++k) {
            T[k] = P[k] / (double)i;
            E[k] += T[k];
        }
    }
    for (i = 0; i < s; ++i) {
        gk_m3_mul(E, E, P);
        gk_m3_copy(P, E);
    }
}

GKDEF void gk_m3_rotation(const double w[3], double R[9]) {
    double th = sqrt(gk_v3_dot(w, w)), k[3], c, s, v;
    gk_m3_identity(R);
    if (th == 0.0) return;
    k[0] = w[0] / th;
    k[1] = w[1] / th;
    k[2] = w[2] / th;
    c = cos(th);
    s = sin(th);
    v = 1.0 - c;
    R[0] = c + k[0] * k[0] * v;
    R[1] = k[0] * k[1] * v - k[2] * s;
    R[2] = k[0] * k[2] * v + k[1] * s;
    R[3] = k[1] * k[0] * v + k[2] * s;
    R[4] = c + k[1] * k[1] * v;
    R[5] = k[1] * k[2] * v - k[0] * s;
    R[6] = k[2] * k[0] * v - k[1] * s;
    R[7] = k[2] * k[1] * v + k[0] * s;
    R[8] = c + k[2] * k[2] * v;
}

GKDEF void gk_m3_rotation_vector(const double R[9], double w[3]) {
    double c = gk_clamp(0.5 * (gk_m3_trace(R) - 1.0), -1.0, 1.0);
    double th = acos(c), s = sin(th);
    if (th < 1e-8) { /* small angle: skew part */
        w[0] = 0.5 * (R[7] - R[5]);
        w[1] = 0.5 * (R[2] - R[6]);
        w[2] = 0.5 * (R[3] - R[1]);
    } else if (GK_PI - th > 1e-6) {
        double f = th / (2.0 * s);
        w[0] = f * (R[7] - R[5]);
        w[1] = f * (R[2] - R[6]);
        w[2] = f * (R[3] - R[1]);
    } else { /* near pi: axis from the symmetric part R = 2kk^T - I */
        double kx = sqrt(gk_clamp(0.5 * (R[0] + 1.0), 0.0, 1.0));
        double ky = sqrt(gk_clamp(0.5 * (R[4] + 1.0), 0.0, 1.0));
        double kz = sqrt(gk_clamp(0.5 * (R[8] + 1.0), 0.0, 1.0));
        if (kx >= ky && kx >= kz) {
            ky = R[1] / (2.0 * kx);
            kz = R[2] / (2.0 * kx);
        } else if (ky >= kz) {
            kx = R[1] / (2.0 * ky);
            kz = R[5] / (2.0 * ky);
        } else {
            kx = R[2] / (2.0 * kz);
            ky = R[5] / (2.0 * kz);
        }
        w[0] = th * kx;
        w[1] = th * ky;
        w[2] = th * kz;
    }
}

#endif /* GK_BASE implementation */

/*
MIT License. Copyright (c) 2026 the grainkit authors.
Permission is hereby granted, free of charge, to any person obtaining a copy of
this software and associated documentation files (the "Software"), to deal in
the Software without restriction, including without limitation the rights to
use, copy, modify, merge, publish, distribute, sublicense, and/or sell copies of
the Software, and to permit persons to whom the Software is furnished to do so,
subject to the following conditions: The above copyright notice and this
permission notice shall be included in all copies or substantial portions of the
Software. THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND,
EXPRESS OR IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF
MERCHANTABILITY, FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO
EVENT SHALL THE AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR
OTHER LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING
FROM, OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN
THE SOFTWARE.
*/
