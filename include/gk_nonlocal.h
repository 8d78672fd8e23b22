/* gk_nonlocal.h - nonlocal averaging over points within a radius. (grainkit v0.1)
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_NONLOCAL_IMPLEMENTATION, or
 * GK_FEM_IMPLEMENTATION) in one file.
 *
 *   gk_nonlocal_build   the neighbours and weights of n points (once)
 *   gk_nonlocal_apply   the averaged field: ncomp values per point
 *   gk_nonlocal_free
 *   gk_nonlocal_bell    the kernel a(r) of eq A.3
 *   gk_nonlocal_grid_symbol  how the average scales a wave on a regular grid:
 *                       its minimum says whether averaging the strain is stable
 *   gk_nonlocal_mix     keep part of the field local: m w_IJ + (1 - m) delta_IJ
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_NONLOCAL_H
#define GK_NONLOCAL_H

#include "gk_base.h"

/* NONLOCAL AVERAGING (Liu, Sun, Yuan & Fish 2016, Appendix A, eqs 58-59,
 * A.3-A.6). A field phi given at n points (Gauss points) is replaced by
 *     <phi>(x_I) = sum_{J in Q_I} a*(x_I, x_J) phi(x_J)                 (A.6)
 *     a*(x_I, x_J) = a(|x_I - x_J|) / sum_{K in Q_I} a(|x_I - x_K|)       (A.4)
 *     a(r) = (1 - r^2/R^2)^2 for r < R, 0 beyond (the bell kernel)        (A.3)
 *     Q_I = {J : |x_I - x_J| < R}, I itself included                      (A.5)
 * exactly as the paper writes the discrete form: the weights are normalised
 * per point and carry NO quadrature weights or volumes (on a uniform mesh the
 * two agree; on a graded one the paper's form weighs a fine region more).
 *   - Periodic directions (period[k] > 0 along axis k): every periodic
 *     image of x_J within R counts, a(x_I, x_J) = sum_images a(|x_J + k P -
 *     x_I|) (I's own images too when a period is below R): the average over
 *     the infinite periodic medium, for any R and period.
 *   - Boundaries: points near a free or fixed boundary have a neighbourhood
 *     cut by it; the renormalisation of A.4 makes the weights still sum to
 *     one (a constant is kept), but the kernel is then one-sided, so a
 *     linear field is reproduced exactly only where Q_I is symmetric about
 *     x_I (interior points of a regular grid, and any point across a
 *     periodic face); near a boundary the average is pulled inward by up to
 *     about R/2 times the gradient. The paper does not say how it treats
 *     boundaries; this is the plain truncation.
 *   - R = 0 switches the operator off (local model: every point averages
 *     itself alone); so does a mesh whose point spacing is at least R.
 *   - Q_I is built once (reference configuration, as the paper precomputes
 *     it) by a direct O(n^2) search: ~0.1 s at 10 000 points.
 * The paper averages the whole strain-increment tensor (eq 58): apply with
 * ncomp = 6 (Voigt) or 9 (3x3) values per point.
 *
 * STABILITY OF AVERAGING THE STRAIN (not in the paper). On a regular grid the
 * operator turns a wave phi = cos(k . x) into S(k) cos(k . x), with the symbol
 *     S(k) = sum_m a(|m h|) cos(k . m h) / sum_m a(|m h|)
 * (m over the integer lattice, h the spacings, every grid point alike). When
 * the average of the strain enters the stress, a strain wave of wave vector k
 * has its stiffness scaled by S(k): where S < 0 the model has modes of NEGATIVE
 * stiffness, which can grow in an explicit run whatever the material (an
 * element's hourglass control stiffens only the modes it cannot see). The
 * bell's Fourier transform has negative lobes: fine grids tend to S(k) = 48
 * J_3(kR) / (kR)^3 in 2D, whose minimum is -0.029 (about -0.021 in 3D), so
 * every grid fine enough to carry waves of length ~R has such modes. On a
 * square grid of spacing h (2D), S >= 0 everywhere while R <= sqrt(2) h (only
 * the four edge neighbours count, each with a(h) <= 1/4); at R = 2h the
 * chequerboard k = (pi/h, pi/h) has S = (1 - 4 a(h) + 4 a(sqrt 2 h)) / (1 +
 * 4 a(h) + 4 a(sqrt 2 h)) = -1/17 (a(h) = 9/16, a(sqrt 2 h) = 1/4, a(2h) = 0).
 * gk_nonlocal_grid_symbol gives min S for any spacings and R;
 * gk_nonlocal_mix(nl, m) with m < 1 / (1 - min S) keeps every symbol
 * 1 - m + m S positive (part of the strain stays local, an option beyond the
 * paper). */
typedef struct gk_nonlocal {
    int n;      /* points                                                    */
    int *start; /* n + 1: point I's neighbours are nbr[start[I] .. start[I+1]) */
    int *nbr;   /* neighbour ids, ascending, I itself included              */
    double *w;  /* a*(x_I, x_J) of eq A.4, summing to 1 per point           */
    double R;   /* radius [m]; 0: local                                     */
    gk_allocator alloc;
} gk_nonlocal;

/* eq A.3 */
GK_INLINE double gk_nonlocal_bell(double r, double R) {
    double t;
    if (!(r < R)) return 0.0;
    t = 1.0 - (r * r) / (R * R);
    return t * t;
}

#ifdef __cplusplus
extern "C" {
#endif
/* x: n points of dim coordinates; period: NULL or 3 values (> 0: periodic
 * along that axis with this period). Any previous content of nl is ignored
 * (free it first). */
GKDEF gk_result gk_nonlocal_build(gk_nonlocal *nl, int dim, int n, const double *x, double R,
                                  const double *period, const gk_allocator *alloc, gk_err *err);
/* out[ncomp I + c] = sum_J w_IJ in[ncomp J + c]; out must not alias in */
GKDEF void gk_nonlocal_apply(const gk_nonlocal *nl, int ncomp, const double *in, double *out);
GKDEF void gk_nonlocal_free(gk_nonlocal *nl);
/* min over the Brillouin zone of S(k) (above) for an infinite regular grid of
 * dim axes with spacings h[0..dim) and radius R: written to *s_min, and the wave
 * vector where it is reached to k_min (dim values, rad/m; NULL: not wanted).
 * S is sampled on GK_NONLOCAL_SYMBOL_SAMPLES (32) intervals of [0, pi/h_k] per
 * axis, the zone's corners included (S is even in every k_k). R <= min h: 1
 * (local). Refused (GK_ERR_ARG) where the sampled sums would exceed 1e9 terms
 * (3D beyond R ~ 15 h). */
GKDEF gk_result gk_nonlocal_grid_symbol(int dim, const double *h, double R, double *s_min, double *k_min,
                                        gk_err *err);
/* w_IJ -> m w_IJ + (1 - m) delta_IJ, 0 <= m <= 1 (m = 1 leaves nl as built,
 * m = 0 makes it local; a second call mixes again: m1 m2 in all); the weights
 * still sum to one */
GKDEF gk_result gk_nonlocal_mix(gk_nonlocal *nl, double m, gk_err *err);
#ifdef __cplusplus
}
#endif
#endif /* GK_NONLOCAL_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_NONLOCAL_IMPLEMENTATION) || defined(GK_FEM_IMPLEMENTATION)) && \
    !defined(GK_NONLOCAL_IMPL_ONCE)
#define GK_NONLOCAL_IMPL_ONCE

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------- nonlocal averaging */
GKDEF void gk_nonlocal_free(gk_nonlocal *nl) {
    gk_free(&nl->alloc, nl->start);
    gk_free(&nl->alloc, nl->nbr);
    gk_free(&nl->alloc, nl->w);
    memset(nl, 0, sizeof *nl);
}

/* bell weight of point b (with all its periodic images) seen from a */
static double gk__nl_weight(int dim, const double *xa, const double *xb, const double *period, double R) {
    int k, lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}, i0, i1, i2;
    double d[3] = {0, 0, 0}, w = 0.0;
    for (k = 0; k < dim; ++k) {
        d[k] = xb[k] - xa[k];
        if (period && period[k] > 0.0) { /* images k P with |d + k P| < R */
            lo[k] = (int)floor((-R - d[k]) / period[k]) + 1;
            hi[k] = (int)ceil((R - d[k]) / period[k]) - 1;
        }
    }
    for (i0 = lo[0]; i0 <= hi[0]; ++i0)
        for (i1 = lo[1]; i1 <= hi[1]; ++i1)
            for (i2 = lo[2]; i2 <= hi[2]; ++i2) {
                int im[3] = {i0, i1, i2};
                double r2 = 0.0;
                for (k = 0; k < dim; ++k) {
                    double e = d[k] + (im[k] ? im[k] * period[k] : 0.0);
                    r2 += e * e;
                }
                w += gk_nonlocal_bell(sqrt(r2), R);
            }
    return w;
}

GKDEF gk_result gk_nonlocal_build(gk_nonlocal *nl, int dim, int n, const double *x, double R,
                                  const double *period, const gk_allocator *alloc, gk_err *err) {
    gk_nonlocal z;
    size_t cnt = 0, cap;
    int I, J, k;
    memset(&z, 0, sizeof z);
    if (alloc) z.alloc = *alloc;
    if (dim < 1 || dim > 3 || n < 1 || !x)
        return gk_err_set(err, GK_ERR_ARG, "nonlocal: dimension %d, %d points", dim, n);
    if (!(R >= 0.0) || !isfinite(R))
        return gk_err_set(err, GK_ERR_ARG, "nonlocal: radius %g must be >= 0", R);
    for (k = 0; k < n * dim; ++k)
        if (!isfinite(x[k]))
            return gk_err_set(err, GK_ERR_NAN, "nonlocal: coordinate %d of point %d is %g", k % dim, k / dim,
                              x[k]);
    if (period)
        for (k = 0; k < dim; ++k) {
            if (!(period[k] >= 0.0) || !isfinite(period[k]) || (period[k] > 0.0 && !(R / period[k] < 1000.0)))
                return gk_err_set(err, GK_ERR_ARG, "nonlocal: period %g along axis %d (radius %g)", period[k],
                                  k, R);
        }
    /* count, then fill: neighbours in ascending order */
    for (I = 0; I < n; ++I)
        for (J = 0; J < n; ++J)
            if (J == I || gk__nl_weight(dim, x + (size_t)dim * I, x + (size_t)dim * J, period, R) > 0.0)
                ++cnt;
    cap = cnt;
    z.start = (int *)gk_alloc(&z.alloc, ((size_t)n + 1) * sizeof(int));
    z.nbr = (int *)gk_alloc(&z.alloc, cap * sizeof(int));
    z.w = (double *)gk_alloc(&z.alloc, cap * sizeof(double));
    if (!z.start || !z.nbr || !z.w) {
        gk_nonlocal_free(&z);
        return gk_err_set(err, GK_ERR_ALLOC, "nonlocal: %lu neighbour pairs", (unsigned long)cap);
    }
    cnt = 0;
    for (I = 0; I < n; ++I) {
        double sum = 0.0;
        size_t b = cnt, c;
        z.start[I] = (int)cnt;
        for (J = 0; J < n; ++J) {
            double a = gk__nl_weight(dim, x + (size_t)dim * I, x + (size_t)dim * J, period, R);
            if (J == I && !(a > 0.0)) a = 1.0; /* R = 0: the point alone */
            if (!(a > 0.0)) continue;
            z.nbr[cnt] = J;
            z.w[cnt++] = a;
            sum += a;
        }
        for (c = b; c < cnt; ++c) z.w[c] /= sum; /* eq A.4 */
    }
    z.start[n] = (int)cnt;
    z.n = n;
    z.R = R;
    *nl = z;
    return GK_OK;
}

GKDEF void gk_nonlocal_apply(const gk_nonlocal *nl, int ncomp, const double *in, double *out) {
    int I, c, p;
    for (I = 0; I < nl->n; ++I) {
        double *o = out + (size_t)ncomp * I;
        for (c = 0; c < ncomp; ++c) o[c] = 0.0;
        for (p = nl->start[I]; p < nl->start[I + 1]; ++p) {
            const double *v = in + (size_t)ncomp * nl->nbr[p];
            double w = nl->w[p];
            for (c = 0; c < ncomp; ++c) o[c] += w * v[c];
        }
    }
}

#ifndef GK_NONLOCAL_SYMBOL_SAMPLES
#define GK_NONLOCAL_SYMBOL_SAMPLES 32
#endif

GKDEF gk_result gk_nonlocal_grid_symbol(int dim, const double *h, double R, double *s_min, double *k_min,
                                        gk_err *err) {
    int k, m[3] = {0, 0, 0}, M[3] = {0, 0, 0}, q[3] = {0, 0, 0}, nq = GK_NONLOCAL_SYMBOL_SAMPLES;
    double best = 2.0, kbest[3] = {0, 0, 0}, sum = 0.0;
    double terms = 1.0;
    if (dim < 1 || dim > 3 || !h || !s_min)
        return gk_err_set(err, GK_ERR_ARG, "nonlocal symbol: dimension %d (1-3) and outputs needed", dim);
    if (!(R >= 0.0) || !isfinite(R))
        return gk_err_set(err, GK_ERR_ARG, "nonlocal symbol: radius %g must be >= 0", R);
    for (k = 0; k < dim; ++k) {
        if (!(h[k] > 0.0) || !isfinite(h[k]))
            return gk_err_set(err, GK_ERR_ARG, "nonlocal symbol: spacing %g along axis %d must be > 0", h[k],
                              k);
        if (!(R / h[k] <= 100.0))
            return gk_err_set(err, GK_ERR_ARG, "nonlocal symbol: radius %g is over 100 spacings %g (axis %d)",
                              R, h[k], k);
        M[k] = (int)floor(R / h[k]);
        terms *= (2.0 * M[k] + 1.0) * (nq + 1.0);
    }
    if (terms > 1e9)
        return gk_err_set(err, GK_ERR_ARG,
                          "nonlocal symbol: %.3g terms to sum (limit 1e9): radius %g too large "
                          "against the spacings",
                          terms, R);
    /* the first wave vector is k = 0, whose sum is the denominator (the point itself counts 1) */
    for (q[0] = 0; q[0] <= (dim > 0 ? nq : 0); ++q[0])
        for (q[1] = 0; q[1] <= (dim > 1 ? nq : 0); ++q[1])
            for (q[2] = 0; q[2] <= (dim > 2 ? nq : 0); ++q[2]) {
                double kv[3] = {0, 0, 0}, s = 0.0;
                for (k = 0; k < dim; ++k) kv[k] = GK_PI * q[k] / (nq * h[k]);
                for (m[0] = -M[0]; m[0] <= M[0]; ++m[0])
                    for (m[1] = -M[1]; m[1] <= M[1]; ++m[1])
                        for (m[2] = -M[2]; m[2] <= M[2]; ++m[2]) {
                            double r2 = 0.0, ph = 0.0, a;
                            for (k = 0; k < dim; ++k) {
                                r2 += (m[k] * h[k]) * (m[k] * h[k]);
                                ph += kv[k] * m[k] * h[k];
                            }
                            a = m[0] == 0 && m[1] == 0 && m[2] == 0 ? 1.0 : gk_nonlocal_bell(sqrt(r2), R);
                            if (a > 0.0) s += a * cos(ph);
                        }
                if (q[0] == 0 && q[1] == 0 && q[2] == 0) sum = s;
                s /= sum;
                if (s < best) {
                    best = s;
                    for (k = 0; k < 3; ++k) kbest[k] = kv[k];
                }
            }
    *s_min = best;
    if (k_min)
        for (k = 0; k < dim; ++k) k_min[k] = kbest[k];
    return GK_OK;
}

GKDEF gk_result gk_nonlocal_mix(gk_nonlocal *nl, double m, gk_err *err) {
    int I, p;
    if (!nl || !nl->start) return gk_err_set(err, GK_ERR_STATE, "nonlocal mix: the operator is not built");
    if (!(m >= 0.0 && m <= 1.0))
        return gk_err_set(err, GK_ERR_ARG, "nonlocal mix: m = %g must be in [0, 1]", m);
    for (I = 0; I < nl->n; ++I)
        for (p = nl->start[I]; p < nl->start[I + 1]; ++p)
            nl->w[p] = m * nl->w[p] + (nl->nbr[p] == I ? 1.0 - m : 0.0);
    return GK_OK;
}

#endif /* GK_NONLOCAL implementation */
