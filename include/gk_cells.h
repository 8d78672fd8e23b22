/* gk_cells.h - contact detection with cell lists for grainkit.   (grainkit v0.1)
 *
 * Bins particles of a periodic (possibly sheared or rotated) cell by a
 * counting sort in reduced coordinates and lists candidate pairs: every pair
 * (i, j), i < j, whose nearest-image distance is below r_i + r_j + skin.
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_CELLS_IMPLEMENTATION) in one file.
 *
 * WHY REDUCED COORDINATES. Two particles closer than c differ in reduced
 * coordinate k by at most c / w_k, where w_k is the perpendicular width of
 * the cell across axis k (gk_pcell_widths). Bins of reduced width >= c / w_k
 * therefore make the 3^dim neighbouring bins exact in any skewed cell; there
 * is no special case for Lees-Edwards shear.
 *
 * ORDER (documented and fixed): pairs are sorted by i, then by j, with i < j.
 * The order depends only on which pairs are candidates, never on the binning,
 * the thread count or the SIMD width. gk_dem.h relies on it for its
 * fixed-order force reduction and to carry contact history across rebuilds
 * by a linear merge.
 *
 * HOW. The particles are copied in bin order once per call; the bins of a
 * stencil row along axis 0 are then one or two runs of that copy, which each
 * particle scans a SIMD block at a time with no branch per candidate. The
 * pairs found bin by bin are put in (i, j) order by a counting sort on i and
 * a short sort of each row.
 *
 * POLYDISPERSITY. The bin size is set by the largest pair cutoff
 * (2 r_max + skin); per-pair cutoffs r_i + r_j + skin are tested exactly, so a
 * size ratio of 10 is correct (small particles share bins; it costs time,
 * not accuracy).
 *
 * OPEN AXES. An axis whose bit is set in gk_cells.open is not periodic: its
 * bins span the particles' own extent along it (not the whole cell) and the
 * neighbour search does not wrap around it. The pair test still takes the
 * nearest image, so the caller keeps every particle within less than half
 * the cell along an open axis (gk_scene.h uses a cell twice the domain):
 * then no image is ever nearer than the particle itself. open = 0 (what
 * gk_cells_init sets) is the periodic cell of the RVE, unchanged.
 *
 * VERLET SKIN. gk_cells_skin_margin bounds how much closer than when a list
 * was built (reduced positions s0 in cell h0) any pair can now be: through
 * the smallest singular value of the affine map A = h h0^-1 and the sum of
 * the two largest non-affine displacements of distinct particles
 * (gk_cells_disp2_top2, gk_cells_skin_margin2; gk_cells_skin_margin takes
 * twice the largest, a looser bound). While the margin is positive the list
 * still holds every touching pair; gk_dem.h tests its outer list with the
 * two largest and its inner list, at every step, with twice the largest (the
 * one its update tracks), gk_cells_skin_ok is the yes/no form.
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_CELLS_H
#define GK_CELLS_H

#include "gk_base.h"
#include "gk_pcell.h"

typedef struct gk_cells {
    int dim, n;
    int nbin[3];
    int nbins;
    unsigned open;        /* bit k set: axis k is open (not periodic), see OPEN AXES */
    double lo[3], inv[3]; /* open axis k: bin = (s - lo[k]) inv[k], clamped      */
    int32_t *bin_start;   /* nbins + 1: particles of bin b are order[bin_start[b] .. bin_start[b+1]) */
    int32_t *order;       /* particle indices sorted by bin, ascending inside a bin */
    int32_t *bin_of;      /* bin of each particle */
    int32_t *buf;         /* scratch: the pairs of gk_cells_pairs, bin by bin */
    double *sorted;       /* scratch: coordinates, radius, index in bin order */
    size_t cap_bins, cap_n, cap_buf, cap_sorted;
    gk_allocator alloc;
} gk_cells;

/* Candidate pair list, sorted by (i, j), i < j; start[p] .. start[p+1] are
 * the pairs whose first particle is p (CSR by i). */
typedef struct gk_pairlist {
    int n;          /* number of pairs */
    int np;         /* number of particles the CSR covers */
    int32_t *i, *j; /* n each */
    int32_t *start; /* np + 1 */
    size_t cap, cap_np;
    gk_allocator alloc;
} gk_pairlist;

#ifdef __cplusplus
extern "C" {
#endif

GKDEF void gk_cells_init(gk_cells *c, const gk_allocator *alloc);
GKDEF void gk_cells_free(gk_cells *c);
/* Bins n particles with reduced coordinates s[0..dim-1][n] (any real values;
 * they are wrapped into [0,1) for binning) in cell h with bin size >= cutoff.
 * GK_ERR_CELL if cutoff >= half the smallest cell width (minimum image would
 * be ambiguous). */
GK_INLINE int gk__open_bin(double s, double lo, double inv, int nb) {
    double t = (s - lo) * inv; /* compared before the conversion: a NaN or a huge t is no int */
    return t >= (double)nb ? nb - 1 : (t >= 1.0 ? (int)t : 0);
}

GKDEF gk_result gk_cells_bin(gk_cells *c, int dim, const double h[9], int n, const double *const s[3],
                             double cutoff, gk_err *err);
/* After gk_cells_bin: all pairs with nearest-image distance < r_i + r_j + skin. */
GKDEF gk_result gk_cells_pairs(gk_cells *c, const double h[9], const double *const s[3], const gk_real *r,
                               double skin, gk_pairlist *out, gk_err *err);

GKDEF void gk_pairlist_init(gk_pairlist *p, const gk_allocator *alloc);
GKDEF void gk_pairlist_free(gk_pairlist *p);
GKDEF gk_result gk_pairlist_reserve(gk_pairlist *p, size_t npairs, size_t np);

/* Verlet margin of a list built in cell h0 with this skin, now in cell h,
 * when no particle has moved more than sqrt(dispmax2) apart from the affine
 * map: a pair listed out (at least r_i + r_j + skin apart, r_i + r_j <= 2 rmax)
 * is now at least r_i + r_j + margin apart. Negative (-1) if h0 is singular
 * or dispmax2 is not finite: the list must be rebuilt. */
GKDEF double gk_cells_skin_margin(int dim, const double h0[9], const double h[9], double skin, double rmax,
                                  double dispmax2);
/* The same margin from the two largest squared non-affine displacements of
 * distinct particles, top2[0] >= top2[1]: two particles have moved apart from
 * the affine map by at most sqrt(top2[0]) + sqrt(top2[1]), which is tighter
 * than gk_cells_skin_margin's 2 sqrt(dispmax2) (that is top2 = {d, d}) */
GKDEF double gk_cells_skin_margin2(int dim, const double h0[9], const double h[9], double skin, double rmax,
                                   const double top2[2]);
/* largest squared non-affine displacement |h (s - s0)|^2 over n particles */
GKDEF double gk_cells_disp2_max(int dim, const double h[9], int n, const double *const s0[3],
                                const double *const s[3]);
/* the two largest of them over distinct particles, top2[0] >= top2[1] (0 for a
 * missing particle); a NaN displacement is kept in top2[0] */
GKDEF void gk_cells_disp2_top2(int dim, const double h[9], int n, const double *const s0[3],
                               const double *const s[3], double top2[2]);
/* Verlet criterion: 1 if a list built at s0 in cell h0 (with this skin and
 * largest radius rmax) is still complete at s in cell h (gk_cells_skin_margin2
 * > 0). dispmax2 receives the largest squared non-affine displacement. */
GKDEF int gk_cells_skin_ok(int dim, const double h0[9], const double h[9], int n, const double *const s0[3],
                           const double *const s[3], double skin, double rmax, double *dispmax2);

#ifdef __cplusplus
}
#endif
#endif /* GK_CELLS_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_CELLS_IMPLEMENTATION)) && !defined(GK_CELLS_IMPL_ONCE)
#define GK_CELLS_IMPL_ONCE

GKDEF void gk_cells_init(gk_cells *c, const gk_allocator *alloc) {
    c->dim = c->n = c->nbins = 0;
    c->nbin[0] = c->nbin[1] = c->nbin[2] = 0;
    c->open = 0;
    c->bin_start = c->order = c->bin_of = c->buf = NULL;
    c->sorted = NULL;
    c->cap_bins = c->cap_n = c->cap_buf = c->cap_sorted = 0;
    if (alloc)
        c->alloc = *alloc;
    else {
        c->alloc.alloc = NULL;
        c->alloc.free = NULL;
        c->alloc.user = NULL;
    }
}

GKDEF void gk_cells_free(gk_cells *c) {
    gk_free(&c->alloc, c->bin_start);
    gk_free(&c->alloc, c->order);
    gk_free(&c->alloc, c->bin_of);
    gk_free(&c->alloc, c->buf);
    gk_free(&c->alloc, c->sorted);
    gk_cells_init(c, &c->alloc);
}

GKDEF void gk_pairlist_init(gk_pairlist *p, const gk_allocator *alloc) {
    p->n = p->np = 0;
    p->i = p->j = p->start = NULL;
    p->cap = p->cap_np = 0;
    if (alloc)
        p->alloc = *alloc;
    else {
        p->alloc.alloc = NULL;
        p->alloc.free = NULL;
        p->alloc.user = NULL;
    }
}

GKDEF void gk_pairlist_free(gk_pairlist *p) {
    gk_free(&p->alloc, p->i);
    gk_free(&p->alloc, p->j);
    gk_free(&p->alloc, p->start);
    gk_pairlist_init(p, &p->alloc);
}

GKDEF gk_result gk_pairlist_reserve(gk_pairlist *p, size_t npairs, size_t np) {
    if (npairs > p->cap) {
        size_t cap = p->cap ? p->cap : 64;
        while (cap < npairs) cap *= 2;
        if (gk_realloc(&p->alloc, (void **)&p->i, (size_t)p->n, cap, sizeof(int32_t))) return GK_ERR_ALLOC;
        if (gk_realloc(&p->alloc, (void **)&p->j, (size_t)p->n, cap, sizeof(int32_t))) return GK_ERR_ALLOC;
        p->cap = cap;
    }
    if (np + 1 > p->cap_np) {
        if (gk_realloc(&p->alloc, (void **)&p->start, 0, np + 1, sizeof(int32_t))) return GK_ERR_ALLOC;
        p->cap_np = np + 1;
    }
    return GK_OK;
}

static gk_result gk__cells_grow(gk_cells *c, int32_t **arr, size_t *cap, size_t need) {
    if (need <= *cap) return GK_OK;
    if (gk_realloc(&c->alloc, (void **)arr, 0, need, sizeof(int32_t))) return GK_ERR_ALLOC;
    *cap = need;
    return GK_OK;
}

/* bin of a finite reduced coordinate (the caller has checked finiteness) */
GK_INLINE int gk__wrap_bin(double s, int nb) {
    double f = (s - floor(s)) * (double)nb;
    int b = f < (double)nb ? (int)f : nb - 1;
    return b < 0 ? 0 : b;
}

/* the largest bin count along one axis: bounds every product and the 3/4
 * shrink step below in int */
#define GK__CELLS_MAXBIN (1 << 29)

GKDEF gk_result gk_cells_bin(gk_cells *c, int dim, const double h[9], int n, const double *const s[3],
                             double cutoff, gk_err *err) {
    double hinv[9], w[3], total = 1.0, det;
    int k, p, nbin[3];
    if (dim != 2 && dim != 3) return gk_err_set(err, GK_ERR_ARG, "dimension %d (must be 2 or 3)", dim);
    if (n < 0) return gk_err_set(err, GK_ERR_ARG, "particle count %d < 0", n);
    if (!(cutoff > 0.0) || !isfinite(cutoff))
        return gk_err_set(err, GK_ERR_ARG, "cutoff %g must be > 0", cutoff);
    det = gk_m3_inverse(h, hinv);
    if (!(det > 0.0) || !isfinite(det) || !gk_m3_isfinite(hinv))
        return gk_err_set(err, GK_ERR_CELL, "cell matrix is singular, inverted or not finite (det %g)", det);
    for (k = 0; k < dim; ++k) {
        const double *row = hinv + 3 * k;
        w[k] = 1.0 / sqrt(row[0] * row[0] + row[1] * row[1] + (dim == 3 ? row[2] * row[2] : 0.0));
        if (!(cutoff < 0.5 * w[k]))
            return gk_err_set(err, GK_ERR_CELL,
                              "cell width %g across axis %d is less than twice the interaction distance %g: "
                              "nearest image ambiguous (use a larger cell)",
                              w[k], k, cutoff);
        /* compared as a double first: a huge cell or a tiny cutoff never reaches the int cast */
        nbin[k] = w[k] / cutoff < (double)GK__CELLS_MAXBIN ? (int)(w[k] / cutoff) : GK__CELLS_MAXBIN;
        if (c->open & (1u << k)) { /* bins over the particles' extent only */
            double smin = 1e300, smax = -1e300, nb;
            for (p = 0; p < n; ++p) {
                if (s[k][p] < smin) smin = s[k][p];
                if (s[k][p] > smax) smax = s[k][p];
            }
            if (n == 0 || !(smax >= smin) || !(smax - smin < 1.0))
                return gk_err_set(
                    err, GK_ERR_OUTSIDE,
                    "open axis %d: the particles span %g of the cell (must be below 1, not NaN)", k,
                    smax - smin);
            c->lo[k] = smin;
            nb = (smax - smin) * w[k] / cutoff;
            nbin[k] = nb < (double)GK__CELLS_MAXBIN ? (int)nb : GK__CELLS_MAXBIN;
        }
        if (nbin[k] < 1) nbin[k] = 1;
    }
    for (k = 0; k < dim; ++k)
        for (p = 0; p < n; ++p)
            if (!isfinite(s[k][p]))
                return gk_err_set(err, GK_ERR_NAN, "particle %d has a non-finite reduced coordinate %g", p,
                                  s[k][p]);
    if (dim == 2) nbin[2] = 1;
    /* keep the grid at most ~2n + 27 bins (dilute or huge cells) */
    for (;;) {
        total = (double)nbin[0] * nbin[1] * nbin[2];
        if (total <= 2.0 * n + 27) break;
        for (k = 0; k < dim; ++k)
            if (nbin[k] > 3) nbin[k] = nbin[k] * 3 / 4 > 3 ? nbin[k] * 3 / 4 : 3;
        if (nbin[0] <= 3 && nbin[1] <= 3 && nbin[2] <= 3) break;
    }
    total = (double)nbin[0] * nbin[1] * nbin[2]; /* <= 2n + 27 or 27 */
    if (total >= (double)INT32_MAX)
        return gk_err_set(err, GK_ERR_ALLOC, "%.0f cell-list bins overflow int", total);
    if (gk__cells_grow(c, &c->bin_start, &c->cap_bins, (size_t)total + 1))
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for %.0f cell-list bins", total);
    for (k = 0; k < 3; ++k) c->nbin[k] = nbin[k];
    c->nbins = (int)total;
    for (k = 0; k < dim; ++k)
        if (c->open & (1u << k)) {
            double smax = c->lo[k];
            for (p = 0; p < n; ++p)
                if (s[k][p] > smax) smax = s[k][p];
            c->inv[k] = smax > c->lo[k] ? (double)c->nbin[k] / (smax - c->lo[k]) : 0.0;
            if (!(c->inv[k] <= 1e300)) c->inv[k] = 0.0; /* an extent of a denormal: one bin */
        }
    if ((size_t)n + 1 > c->cap_n) { /* order and bin_of share one capacity */
        size_t cap = (size_t)n + 1;
        if (gk_realloc(&c->alloc, (void **)&c->order, 0, cap, sizeof(int32_t)) ||
            gk_realloc(&c->alloc, (void **)&c->bin_of, 0, cap, sizeof(int32_t)))
            return gk_err_set(err, GK_ERR_ALLOC, "out of memory for %d particles in the cell list", n);
        c->cap_n = cap;
    }
    c->dim = dim;
    c->n = n;
    for (k = 0; k <= c->nbins; ++k) c->bin_start[k] = 0;
    for (p = 0; p < n; ++p) {
        int b;
        if (c->open) {
            int bk[3] = {0, 0, 0};
            for (k = 0; k < dim; ++k)
                bk[k] = (c->open & (1u << k)) ? gk__open_bin(s[k][p], c->lo[k], c->inv[k], c->nbin[k])
                                              : gk__wrap_bin(s[k][p], c->nbin[k]);
            b = bk[0] + c->nbin[0] * (bk[1] + c->nbin[1] * bk[2]);
        } else {
            b = gk__wrap_bin(s[0][p], c->nbin[0]) +
                c->nbin[0] * (gk__wrap_bin(s[1][p], c->nbin[1]) +
                              c->nbin[1] * (dim == 3 ? gk__wrap_bin(s[2][p], c->nbin[2]) : 0));
        }
        c->bin_of[p] = b;
        ++c->bin_start[b + 1];
    }
    for (k = 0; k < c->nbins; ++k) c->bin_start[k + 1] += c->bin_start[k];
    /* stable scatter: ascending particle index inside each bin */
    for (p = 0; p < n; ++p) {
        int b = c->bin_of[p];
        c->order[c->bin_start[b]++] = p;
    }
    for (k = c->nbins; k > 0; --k) c->bin_start[k] = c->bin_start[k - 1];
    c->bin_start[0] = 0;
    return GK_OK;
}

/* a stencil bin index u in [-1, nb] wrapped into [0, nb) */
GK_INLINE int gk__cells_wrap(int u, int nb) { return u < 0 ? u + nb : (u >= nb ? u - nb : u); }

/* the particles in bin order, as doubles (coordinates, radius, index), with
 * GK_VD_W entries of padding: room for n */
static gk_result gk__cells_sorted_grow(gk_cells *c, size_t n) {
    size_t cap = c->cap_sorted ? c->cap_sorted : 64;
    while (cap < n + GK_VD_W) cap *= 2;
    if (cap == c->cap_sorted) return GK_OK;
    gk_free(&c->alloc, c->sorted);
    c->sorted = NULL;
    c->cap_sorted = 0;
    if (gk_realloc(&c->alloc, (void **)&c->sorted, 0, 5 * cap, sizeof(double))) return GK_ERR_ALLOC;
    c->cap_sorted = cap;
    return GK_OK;
}

/* particle p (P: its coordinates, radius, the skin and p, broadcast)
 * against the sorted entries [f0, f1): the pairs (p, q) with q > p within
 * r_p + r_q + skin go to buf (which has room for f1 - f0 + GK_VD_W more),
 * GK_VD_W entries at a time. The arithmetic of gk_pcell_image, lane by lane:
 * every SIMD width keeps the same pairs. */
GK_FORCE_INLINE int gk__cells_scan(const gk_cells *c, const gk_vd P[6], const gk_vd H[9], int p, int f0,
                                   int f1, int np, const int dim) {
    const size_t cap = c->cap_sorted;
    const double *cx = c->sorted, *cy = cx + cap, *cz = cx + 2 * cap, *cr = cx + 3 * cap, *cq = cx + 4 * cap;
    const gk_vd end = gk_vd_set1((double)f1);
    int32_t *buf = c->buf;
    /* lane l holds f0 + l (exact in double). Not from a local array filled here:
     * its vector load right after the element stores stalls (store forwarding) */
    static const double iota[8] = {0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0};
    gk_vd lane = gk_vd_add(gk_vd_set1((double)f0), gk_vd_loadu(iota));
    int f;
    for (f = f0; f < f1; f += GK_VD_W, lane = gk_vd_add(lane, gk_vd_set1((double)GK_VD_W))) {
        gk_vd a = gk_vd_sub(gk_vd_loadu(cx + f), P[0]), b = gk_vd_sub(gk_vd_loadu(cy + f), P[1]), d2, q;
        const gk_vd cut = gk_vd_add(gk_vd_add(P[3], gk_vd_loadu(cr + f)), P[4]);
        unsigned bits;
        a = gk_vd_sub(a, gk_vd_round(a));
        b = gk_vd_sub(b, gk_vd_round(b));
        if (dim == 2) {
            gk_vd dx = gk_vd_add(gk_vd_mul(H[0], a), gk_vd_mul(H[1], b));
            gk_vd dy = gk_vd_add(gk_vd_mul(H[3], a), gk_vd_mul(H[4], b));
            d2 = gk_vd_add(gk_vd_mul(dx, dx), gk_vd_mul(dy, dy));
        } else {
            gk_vd e = gk_vd_sub(gk_vd_loadu(cz + f), P[2]), dx, dy, dz;
            e = gk_vd_sub(e, gk_vd_round(e));
            dx = gk_vd_add(gk_vd_add(gk_vd_mul(H[0], a), gk_vd_mul(H[1], b)), gk_vd_mul(H[2], e));
            dy = gk_vd_add(gk_vd_add(gk_vd_mul(H[3], a), gk_vd_mul(H[4], b)), gk_vd_mul(H[5], e));
            dz = gk_vd_add(gk_vd_add(gk_vd_mul(H[6], a), gk_vd_mul(H[7], b)), gk_vd_mul(H[8], e));
            d2 = gk_vd_add(gk_vd_add(gk_vd_mul(dx, dx), gk_vd_mul(dy, dy)), gk_vd_mul(dz, dz));
        }
        q = gk_vd_loadu(cq + f);
        bits = gk_vdm_bits(gk_vdm_and(gk_vdm_and(gk_vd_lt(d2, gk_vd_mul(cut, cut)), gk_vd_gt(q, P[5])),
                                      gk_vd_lt(lane, end)));
        if (!bits) continue;
        np += gk_pairs_compress(bits, p, cq + f, buf + 2 * (size_t)np);
    }
    return np;
}

GKDEF gk_result gk_cells_pairs(gk_cells *c, const double h[9], const double *const s[3], const gk_real *r,
                               double skin, gk_pairlist *out, gk_err *err) {
    int off[3][3], noff[3], k, p, q, e, dim = c->dim, n = c->n, bx, by, bz, np = 0;
    gk_vd H[9];
    if (gk_pairlist_reserve(out, out->cap ? out->cap : (size_t)4 * n + 16, (size_t)n))
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for the pair list");
    out->n = 0;
    out->np = n;
    for (k = 0; k < 3; ++k) {
        int nb = c->nbin[k];
        if (k >= dim || nb == 1) {
            noff[k] = 1;
            off[k][0] = 0;
        } else if (nb == 2 && !(c->open & (1u << k))) { /* bins -1 and +1 coincide: visit each once */
            noff[k] = 2;
            off[k][0] = 0;
            off[k][1] = 1;
        } else {
            noff[k] = 3;
            off[k][0] = -1;
            off[k][1] = 0;
            off[k][2] = 1;
        }
    }
    if (gk__cells_grow(c, &c->buf, &c->cap_buf, 2 * out->cap) || gk__cells_sorted_grow(c, (size_t)n))
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for the pair buffer");
    { /* the particles in bin order; the padding is never kept (index -1) */
        const size_t cap = c->cap_sorted;
        double *x = c->sorted;
        for (e = 0; e < n; ++e) {
            int o = c->order[e];
            x[e] = s[0][o];
            x[cap + e] = s[1][o];
            x[2 * cap + e] = dim == 3 ? s[2][o] : 0.0;
            x[3 * cap + e] = (double)r[o];
            x[4 * cap + e] = (double)o;
        }
        for (e = n; e < n + GK_VD_W; ++e) {
            for (k = 0; k < 4; ++k) x[k * cap + e] = 0.0;
            x[4 * cap + e] = -1.0;
        }
    }
    for (k = 0; k < 9; ++k) H[k] = gk_vd_set1(h[k]);
    /* pass 1, bin by bin. The neighbour bins of a row along axis 0 are
     * consecutive in bin order, so their particles are one or two runs of the
     * sorted entries (two where the row wraps): each particle of the bin is
     * tested against those runs without a branch; the pairs (p, q), q > p,
     * into buf (two ints each) */
    for (bx = 0; bx < c->nbin[0]; ++bx) {
        int xs[3][2], nxs = 0, a0, a1, a2;
        for (a0 = 0; a0 < noff[0]; ++a0) { /* the x bins of the stencil as runs [lo, hi] */
            int u = bx + off[0][a0], w = gk__cells_wrap(u, c->nbin[0]);
            if ((c->open & 1u) && w != u) continue; /* no wrap across an open axis */
            if (nxs > 0 && xs[nxs - 1][1] + 1 == w)
                xs[nxs - 1][1] = w;
            else {
                xs[nxs][0] = xs[nxs][1] = w;
                ++nxs;
            }
        }
        for (bz = 0; bz < c->nbin[2]; ++bz)
            for (by = 0; by < c->nbin[1]; ++by) {
                int run[18][2], nrun = 0, t, b = bx + c->nbin[0] * (by + c->nbin[1] * bz);
                size_t total = 0;
                if (c->bin_start[b] == c->bin_start[b + 1]) continue;
                for (a2 = 0; a2 < noff[2]; ++a2)
                    for (a1 = 0; a1 < noff[1]; ++a1) {
                        int u1 = by + off[1][a1], u2 = bz + off[2][a2], w1, w2, row;
                        w1 = gk__cells_wrap(u1, c->nbin[1]);
                        w2 = gk__cells_wrap(u2, c->nbin[2]);
                        if (((c->open & 2u) && w1 != u1) || ((c->open & 4u) && w2 != u2)) continue;
                        row = c->nbin[0] * (w1 + c->nbin[1] * w2);
                        for (t = 0; t < nxs; ++t) {
                            int f0 = c->bin_start[row + xs[t][0]], f1 = c->bin_start[row + xs[t][1] + 1];
                            if (f0 == f1) continue;
                            run[nrun][0] = f0;
                            run[nrun][1] = f1;
                            total += (size_t)(f1 - f0);
                            ++nrun;
                        }
                    }
                for (e = c->bin_start[b]; e < c->bin_start[b + 1]; ++e) {
                    const size_t cap = c->cap_sorted;
                    gk_vd P[6];
                    int pp = c->order[e];
                    /* room for every write of this particle: its candidates plus a block per run */
                    size_t room = total + (size_t)nrun * GK_VD_W;
                    if ((size_t)np + room > c->cap_buf / 2) {
                        size_t want = 4 * ((size_t)np + room); /* ints: twice the pairs needed */
                        if (room > (size_t)(INT32_MAX / 2 - np))
                            return gk_err_set(err, GK_ERR_ALLOC, "more than %ld candidate pairs",
                                              (long)(INT32_MAX / 2));
                        if (gk_realloc(&c->alloc, (void **)&c->buf, 2 * (size_t)np, want, sizeof(int32_t)))
                            return gk_err_set(err, GK_ERR_ALLOC, "out of memory for the pair buffer");
                        c->cap_buf = want;
                    }
                    for (k = 0; k < 4; ++k) P[k] = gk_vd_set1(c->sorted[k * cap + (size_t)e]);
                    P[4] = gk_vd_set1(skin);
                    P[5] = gk_vd_set1((double)pp);
                    for (t = 0; t < nrun; ++t)
                        np = dim == 2 ? gk__cells_scan(c, P, H, pp, run[t][0], run[t][1], np, 2)
                                      : gk__cells_scan(c, P, H, pp, run[t][0], run[t][1], np, 3);
                }
            }
    }
    /* pass 2: by a counting sort on p into rows, each row then sorted by q
     * (rows are short: a few to a few tens) */
    if ((size_t)np > out->cap && gk_pairlist_reserve(out, (size_t)np, (size_t)n))
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for %d pairs", np);
    for (p = 0; p <= n; ++p) out->start[p] = 0;
    for (q = 0; q < np; ++q) ++out->start[c->buf[2 * q] + 1];
    for (p = 0; p < n; ++p) out->start[p + 1] += out->start[p];
    for (q = 0; q < np; ++q) {
        int32_t pp = c->buf[2 * q], at = out->start[pp]++;
        out->i[at] = pp;
        out->j[at] = c->buf[2 * q + 1];
    }
    for (p = n; p > 0; --p) out->start[p] = out->start[p - 1];
    out->start[0] = 0;
    for (p = 0; p < n; ++p) {
        int32_t *row = out->j + out->start[p];
        int cnt = out->start[p + 1] - out->start[p];
        for (q = 1; q < cnt; ++q) {
            int32_t v = row[q];
            int t = q - 1;
            while (t >= 0 && row[t] > v) {
                row[t + 1] = row[t];
                --t;
            }
            row[t + 1] = v;
        }
    }
    out->n = np;
    return GK_OK;
}

/* smallest singular value of a 3x3 (dim x dim block) */
static double gk__sigma_min(int dim, const double A[9]) {
    double AtA[9], At[9], val[3], vec[9];
    gk_m3_transpose(A, At);
    gk_m3_mul(At, A, AtA);
    if (dim == 2) {
        double a = AtA[0], b = AtA[1], d = AtA[4];
        double lmin = 0.5 * (a + d) - sqrt(0.25 * (a - d) * (a - d) + b * b);
        return lmin > 0.0 ? sqrt(lmin) : 0.0;
    }
    gk_m3_sym_eigen(AtA, val, vec);
    return val[0] > 0.0 ? sqrt(val[0]) : 0.0;
}

/* margin with the two particles' relative non-affine displacement bounded by dsum */
static double gk__skin_margin(int dim, const double h0[9], const double h[9], double skin, double rmax,
                              double dsum) {
    double h0i[9], A[9], smin;
    if (!(gk_m3_inverse(h0, h0i) > 0.0) || !isfinite(dsum)) return -1.0;
    gk_m3_mul(h, h0i, A);
    smin = gk__sigma_min(dim, A);
    /* a pair listed out had |d0| >= R + skin; now |d| >= smin (R + skin) - dsum,
     * and |d| - R >= smin skin - (1 - smin) R - dsum with R <= 2 rmax */
    return smin * skin - (smin < 1.0 ? (1.0 - smin) * 2.0 * rmax : 0.0) - dsum;
}

GKDEF double gk_cells_skin_margin(int dim, const double h0[9], const double h[9], double skin, double rmax,
                                  double dispmax2) {
    return gk__skin_margin(dim, h0, h, skin, rmax, 2.0 * sqrt(dispmax2));
}

GKDEF double gk_cells_skin_margin2(int dim, const double h0[9], const double h[9], double skin, double rmax,
                                   const double top2[2]) {
    return gk__skin_margin(dim, h0, h, skin, rmax, sqrt(top2[0]) + sqrt(top2[1]));
}

GKDEF void gk_cells_disp2_top2(int dim, const double h[9], int n, const double *const s0[3],
                               const double *const s[3], double top2[2]) {
    double a = 0.0, b = 0.0;
    int p;
    for (p = 0; p < n; ++p) {
        double dx = s[0][p] - s0[0][p], dy = s[1][p] - s0[1][p], dz = dim == 3 ? s[2][p] - s0[2][p] : 0.0;
        double ex = h[0] * dx + h[1] * dy + h[2] * dz;
        double ey = h[3] * dx + h[4] * dy + h[5] * dz;
        double ez = dim == 3 ? h[6] * dx + h[7] * dy + h[8] * dz : 0.0;
        double d2 = ex * ex + ey * ey + ez * ez;
        if (d2 != d2) {
            top2[0] = d2, top2[1] = 0.0; /* a NaN: the margin refuses it */
            return;
        }
        b = d2 < a ? (d2 > b ? d2 : b) : a;
        a = d2 > a ? d2 : a;
    }
    top2[0] = a, top2[1] = b;
}

GKDEF double gk_cells_disp2_max(int dim, const double h[9], int n, const double *const s0[3],
                                const double *const s[3]) {
    double t2[2];
    gk_cells_disp2_top2(dim, h, n, s0, s, t2);
    return t2[0]; /* a NaN is kept: the margin refuses it */
}

GKDEF int gk_cells_skin_ok(int dim, const double h0[9], const double h[9], int n, const double *const s0[3],
                           const double *const s[3], double skin, double rmax, double *dispmax2) {
    double t2[2];
    gk_cells_disp2_top2(dim, h, n, s0, s, t2);
    if (dispmax2) *dispmax2 = t2[0];
    return gk_cells_skin_margin2(dim, h0, h, skin, rmax, t2) > 0.0;
}

#endif /* GK_CELLS implementation */
