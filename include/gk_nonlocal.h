/* gk_nonlocal.h - nonlocal averaging over points within a radius. (grainkit v0.1)
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_NONLOCAL_IMPLEMENTATION, or
 * GK_FEM_IMPLEMENTATION) in one file.
 *
 *   gk_nonlocal_build   the neighbours and weights of n points (once)
 *   gk_nonlocal_apply   the averaged field: ncomp values per point
 *   gk_nonlocal_free
 *   gk_nonlocal_bell    the kernel a(r) of eq A.3
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
 * ncomp = 6 (Voigt) or 9 (3x3) values per point. */
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

#endif /* GK_NONLOCAL implementation */
