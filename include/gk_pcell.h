/* gk_pcell.h - periodic cell kinematics for grainkit.            (grainkit v0.1)
 *
 * A periodic cell is the lattice spanned by the columns of the cell matrix h:
 * a particle at reduced coordinates s (s in [0,1)^dim) sits at x = h s, and
 * its periodic images at h (s + k) for every integer vector k. Deforming the
 * cell (h <- E h) moves every particle affinely with it; the DEM integrates
 * only the fluctuation around that affine field (gk_dem.h). This is the
 * deforming-cell (Parrinello-Rahman kinematics, strain-controlled) form used
 * by YADE's Cell and by the Guo & Zhao 2014 authors' code.
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_PCELL_IMPLEMENTATION) in one file
 * before including; see gk_base.h.
 *
 * WHAT IS HERE
 *   gk_pcell_init          cell from a matrix h (columns = edge vectors)
 *   gk_pcell_advance       h <- E h for one time step (E = incremental map)
 *   gk_pcell_widths        perpendicular widths (face distances) of the cell
 *   gk_pcell_reduce        lattice reduction: an equivalent, less skewed h' = h M
 *   gk_pcell_min_image     branch vector to the nearest image
 *   gk_path_init/_step     a displacement-gradient increment dH split over
 *                          n steps (det(I + dH) <= 0 is refused on both):
 *                          GK_PATH_CONSTANT_L  constant velocity gradient
 *                                              L = dH/(n dt) (Guo & Zhao 2014 [C],
 *                                              YADE); end map exp(dH) =
 *                                              I + dH + dH^2/2 + ...
 *                          GK_PATH_OBJECTIVE   rotation by angle and stretch
 *                                              linearly: ends exactly at
 *                                              I + dH = R U, any size
 *   gk_servo_rates         mixed stress/strain control of the diagonal of L
 *
 * LEES-EDWARDS. Simple shear of a periodic cell with L01 = gamma_dot is the
 * deforming-cell form of Lees-Edwards boundaries (h = [[Lx, gamma Ly],
 * [0, Ly]]; an image crossing the top face is shifted by gamma Ly). When the
 * cell becomes too skewed, gk_pcell_reduce finds the equivalent cell with
 * gamma -> gamma - round(gamma Ly / Lx): the same infinite lattice, so every
 * pair distance is unchanged (a "flip"). Any shear strain or spin is reachable.
 *
 * CONVENTIONS: SI units; h, E, L, M are row-major 3x3 double[9]; in 2D the
 * third row/column is the identity (h22 = 1, L22 = 0). Velocity gradient
 * L_ij = dv_i/dx_j, displacement gradient H_ij = du_i/dx_j. Stresses given to
 * the servo are tension-positive.
 *
 * The minimum-image convention (rounding reduced coordinate differences) is
 * exact for every pair closer than half the smallest perpendicular width, so
 * gk_dem.h requires 2 x (largest interaction distance) < min width and
 * reduces the cell when skew would break it.
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_PCELL_H
#define GK_PCELL_H

#include "gk_base.h"

typedef struct gk_pcell {
    int dim;     /* 2 or 3                                                     */
    double h[9]; /* cell matrix, columns are the edge vectors: x = h s        */
    double hinv[9];
    double F[9]; /* accumulated map since init: product of every E (remaps
                     change h, never F); F - I is the total applied H         */
    long flips;  /* number of lattice reductions applied                      */
} gk_pcell;

typedef enum gk_path_kind {
    GK_PATH_CONSTANT_L = 0, /* L = dH/(n dt) constant; E = exp(L dt) each step */
    GK_PATH_OBJECTIVE = 1   /* M(a) = R(a theta) (I + a (U - I)), a = k/n       */
} gk_path_kind;

/* An incremental deformation carried out over nsteps steps: the end map is
 * exp(dH) on GK_PATH_CONSTANT_L and exactly I + dH on GK_PATH_OBJECTIVE. */
typedef struct gk_path {
    int dim, nsteps;
    gk_path_kind kind;
    double dH[9];
    double Estep[9]; /* CONSTANT_L: exp(dH / n)                              */
    double U[9];     /* OBJECTIVE: right stretch of I + dH                     */
    double w[3];     /* OBJECTIVE: rotation vector of R (2D: w[2] = angle)     */
} gk_path;

typedef enum gk_servo_mode { GK_SERVO_STRAIN = 0, GK_SERVO_STRESS = 1 } gk_servo_mode;

/* Mixed control of the diagonal of L. Axis k is either strain-controlled
 * (L_kk = rate[k]) or stress-controlled (L_kk drives sigma_kk to target[k]).
 * Off-diagonal terms of L are left to the caller (prescribed). */
typedef struct gk_servo {
    gk_servo_mode mode[3];
    double target[3];       /* stress targets sigma_kk [Pa], tension-positive        */
    double rate[3];         /* prescribed L_kk for strain-controlled axes [1/s]       */
    double max_rate;        /* cap on |L_kk| for stress-controlled axes [1/s] (> 0)   */
    double gain;            /* fraction of the stress error corrected per step; 0 -> 0.02 */
    int shear;              /* 1: also drive the shear stresses sigma_kl (k < l) to    */
    double shear_target[3]; /* these targets (xy, xz, yz) with a symmetric L_kl = L_lk */
} gk_servo;

#ifdef __cplusplus
extern "C" {
#endif

GKDEF gk_result gk_pcell_init(gk_pcell *c, int dim, const double h[9], gk_err *err);
GKDEF gk_result gk_pcell_init_box(gk_pcell *c, int dim, double lx, double ly, double lz, gk_err *err);
/* h <- E h, F <- E F. Fails (cell unchanged) if E has NaN or det(E h) <= 0. */
GKDEF gk_result gk_pcell_advance(gk_pcell *c, const double E[9], gk_err *err);
/* perpendicular widths: w[k] = volume / area of the face spanned by the other edges */
GKDEF void gk_pcell_widths(const gk_pcell *c, double w[3]);
/* Lattice (Lagrange-Gauss) reduction: returns 1 and an integer unimodular M
 * with h' = h M less skewed (every |e_k . e_l| <= |e_k|^2 / 2 + margin), or 0
 * if h is already reduced. Reduced coordinates map as s' = M^-1 s. */
GKDEF int gk_pcell_reduce(const gk_pcell *c, double M[9]);
/* h <- h M (M from gk_pcell_reduce); counts a flip */
GKDEF void gk_pcell_apply_basis(gk_pcell *c, const double M[9]);

GKDEF gk_result gk_path_init(gk_path *p, int dim, gk_path_kind kind, const double dH[9], int nsteps,
                             gk_err *err);
/* incremental map E_k taking the cell from step k-1 to step k (k = 1..n) */
GKDEF void gk_path_step(const gk_path *p, int k, double E[9]);
/* map from the start of the path to step k: M(k/n) */
GKDEF void gk_path_map(const gk_path *p, int k, double M[9]);

/* Servo: writes L_kk for k < dim from the current stress sigma (tension-
 * positive) and per-axis stiffness estimates stiff[k] [Pa] (e.g. the Taylor
 * tangent's D_kkkk; <= 0 means unknown: move at max_rate). With shear = 1
 * it also writes the symmetric off-diagonal rates L_kl = L_lk that drive
 * sigma_kl to shear_target, using half the mean of stiff[k] and stiff[l] as
 * the shear stiffness (a pure shear rate eps_kl changes sigma_kl by 2 G). */
GKDEF void gk_servo_rates(const gk_servo *s, int dim, const double sigma[9], const double stiff[3], double dt,
                          double L[9]);

#ifdef __cplusplus
}
#endif

GK_INLINE double gk_pcell_volume(const gk_pcell *c) { return gk_m3_det(c->h); }

/* Branch vector to the nearest image, d = h (ds - round(ds)), of a reduced
 * difference ds = s_j - s_i: the one place grainkit rounds to the nearest
 * image (the DEM kernels inline it; their SIMD twin is gk__simd_branch in
 * gk_dem.h). dim 2: the upper-left block of h, d[2] = 0. */
GK_FORCE_INLINE void gk_pcell_image(const double h[9], int dim, const double ds[3], double d[3]) {
    double a = ds[0] - rint(ds[0]), b = ds[1] - rint(ds[1]), c;
    if (dim == 2) {
        d[0] = h[0] * a + h[1] * b;
        d[1] = h[3] * a + h[4] * b;
        d[2] = 0.0;
        return;
    }
    c = ds[2] - rint(ds[2]);
    d[0] = h[0] * a + h[1] * b + h[2] * c;
    d[1] = h[3] * a + h[4] * b + h[5] * c;
    d[2] = h[6] * a + h[7] * b + h[8] * c;
}

/* gk_pcell_image in the cell c */
GK_INLINE void gk_pcell_min_image(const gk_pcell *c, const double ds[3], double d[3]) {
    gk_pcell_image(c->h, c->dim, ds, d);
}

/* simple shear velocity gradient (Lees-Edwards): v_i = rate * x_j, i != j */
GK_INLINE void gk_pcell_shear_velgrad(double L[9], int i, int j, double rate) {
    gk_m3_zero(L);
    L[3 * i + j] = rate;
}

#endif /* GK_PCELL_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_PCELL_IMPLEMENTATION)) && !defined(GK_PCELL_IMPL_ONCE)
#define GK_PCELL_IMPL_ONCE

static gk_result gk__pcell_check(int dim, const double h[9], gk_err *err) {
    if (dim != 2 && dim != 3) return gk_err_set(err, GK_ERR_ARG, "dimension %d (must be 2 or 3)", dim);
    if (!gk_m3_isfinite(h)) return gk_err_set(err, GK_ERR_NAN, "cell matrix has a NaN or infinite entry");
    if (dim == 2 && (h[2] != 0.0 || h[5] != 0.0 || h[6] != 0.0 || h[7] != 0.0 || h[8] != 1.0))
        return gk_err_set(err, GK_ERR_CELL, "2D cell matrix must have third row and column (0,0,1)");
    if (!(gk_m3_det(h) > 0.0))
        return gk_err_set(err, GK_ERR_CELL, "cell matrix has det %g <= 0 (degenerate or inverted)",
                          gk_m3_det(h));
    if (!isfinite(gk_m3_det(h)))
        return gk_err_set(err, GK_ERR_CELL, "cell matrix has a volume beyond the range of double (det %g)",
                          gk_m3_det(h));
    return GK_OK;
}

GKDEF gk_result gk_pcell_init(gk_pcell *c, int dim, const double h[9], gk_err *err) {
    gk_result r = gk__pcell_check(dim, h, err);
    if (r) return r;
    c->dim = dim;
    gk_m3_copy(h, c->h);
    gk_m3_inverse(c->h, c->hinv);
    gk_m3_identity(c->F);
    c->flips = 0;
    return GK_OK;
}

GKDEF gk_result gk_pcell_init_box(gk_pcell *c, int dim, double lx, double ly, double lz, gk_err *err) {
    double h[9];
    gk_m3_identity(h);
    h[0] = lx;
    h[4] = ly;
    if (dim == 3) h[8] = lz;
    if (!(lx > 0.0) || !(ly > 0.0) || (dim == 3 && !(lz > 0.0)))
        return gk_err_set(err, GK_ERR_CELL, "cell lengths %g %g %g must be > 0", lx, ly, dim == 3 ? lz : 1.0);
    return gk_pcell_init(c, dim, h, err);
}

GKDEF gk_result gk_pcell_advance(gk_pcell *c, const double E[9], gk_err *err) {
    double h[9], F[9];
    gk_result r;
    if (!gk_m3_isfinite(E)) return gk_err_set(err, GK_ERR_NAN, "incremental cell map has a NaN entry");
    gk_m3_mul(E, c->h, h);
    if (c->dim == 2) { /* keep the 2D block structure exact */
        h[2] = h[5] = h[6] = h[7] = 0.0;
        h[8] = 1.0;
    }
    r = gk__pcell_check(c->dim, h, err);
    if (r) return r;
    gk_m3_mul(E, c->F, F);
    if (c->dim == 2) {
        F[2] = F[5] = F[6] = F[7] = 0.0;
        F[8] = 1.0;
    }
    gk_m3_copy(h, c->h);
    gk_m3_copy(F, c->F);
    gk_m3_inverse(c->h, c->hinv);
    return GK_OK;
}

GKDEF void gk_pcell_widths(const gk_pcell *c, double w[3]) {
    /* row k of h^-1 is normal to the faces of constant s_k; width = 1/|row| */
    int k;
    for (k = 0; k < 3; ++k) {
        const double *row = c->hinv + 3 * k;
        double n2 =
            k < c->dim ? row[0] * row[0] + row[1] * row[1] + (c->dim == 3 ? row[2] * row[2] : 0.0) : 0.0;
        w[k] = (k < c->dim && n2 > 0.0) ? 1.0 / sqrt(n2) : 0.0;
    }
}

GKDEF int gk_pcell_reduce(const gk_pcell *c, double M[9]) {
    double e[3][3], m[3][3];
    int changed = 0, pass, stage, a, b, k, d = c->dim;
    for (a = 0; a < 3; ++a)
        for (k = 0; k < 3; ++k) {
            e[a][k] = c->h[3 * k + a]; /* column a */
            m[a][k] = (a == k) ? 1.0 : 0.0;
        }
    /* Stage 1 reduces later edges against earlier ones only (e_b -= q e_a,
     * a < b): for Lees-Edwards shear along x this is the usual remap that
     * keeps the first edge. Stage 2 (all ordered pairs, Lagrange-Gauss)
     * runs only if two edges are still closer than 37 degrees apart. */
    for (stage = 0; stage < 2; ++stage) {
        if (stage == 1) {
            int bad = 0;
            for (a = 0; a < d; ++a)
                for (b = a + 1; b < d; ++b) {
                    double ea = e[a][0] * e[a][0] + e[a][1] * e[a][1] + e[a][2] * e[a][2];
                    double eb2 = e[b][0] * e[b][0] + e[b][1] * e[b][1] + e[b][2] * e[b][2];
                    double ab = e[a][0] * e[b][0] + e[a][1] * e[b][1] + e[a][2] * e[b][2];
                    if (ab * ab > 0.64 * ea * eb2) bad = 1;
                }
            if (!bad) break;
        }
        for (pass = 0; pass < 64; ++pass) {
            int any = 0;
            for (a = 0; a < d; ++a)
                for (b = 0; b < d; ++b) {
                    double ee, eb, q;
                    if (a == b || (stage == 0 && b < a)) continue;
                    ee = e[a][0] * e[a][0] + e[a][1] * e[a][1] + e[a][2] * e[a][2];
                    eb = e[a][0] * e[b][0] + e[a][1] * e[b][1] + e[a][2] * e[b][2];
                    /* margin 1e-3 so a cell at exactly half a period does not flip back and forth */
                    if (fabs(eb) <= (0.5 + 1e-3) * ee) continue;
                    q = rint(eb / ee);
                    for (k = 0; k < 3; ++k) {
                        e[b][k] -= q * e[a][k];
                        m[b][k] -= q * m[a][k];
                    }
                    any = changed = 1;
                }
            if (!any) break;
        }
    }
    for (a = 0; a < 3; ++a)
        for (k = 0; k < 3; ++k) M[3 * k + a] = m[a][k]; /* column a of M = coefficients of new edge a */
    return changed;
}

GKDEF void gk_pcell_apply_basis(gk_pcell *c, const double M[9]) {
    double h[9];
    gk_m3_mul(c->h, M, h);
    gk_m3_copy(h, c->h);
    gk_m3_inverse(c->h, c->hinv);
    ++c->flips;
}

/* ---- deformation paths */
GKDEF gk_result gk_path_init(gk_path *p, int dim, gk_path_kind kind, const double dH[9], int nsteps,
                             gk_err *err) {
    double F[9], R[9], U[9];
    int k;
    if (dim != 2 && dim != 3) return gk_err_set(err, GK_ERR_ARG, "dimension %d (must be 2 or 3)", dim);
    if (nsteps < 1) return gk_err_set(err, GK_ERR_ARG, "deformation over %d steps (must be >= 1)", nsteps);
    if (kind != GK_PATH_CONSTANT_L && kind != GK_PATH_OBJECTIVE)
        return gk_err_set(err, GK_ERR_ARG, "unknown deformation path kind %d", (int)kind);
    if (!gk_m3_isfinite(dH)) return gk_err_set(err, GK_ERR_NAN, "dH has a NaN or infinite entry");
    if (dim == 2 && (dH[2] != 0.0 || dH[5] != 0.0 || dH[6] != 0.0 || dH[7] != 0.0 || dH[8] != 0.0))
        return gk_err_set(err, GK_ERR_ARG, "2D dH must have zero third row and column");
    gk_m3_identity(F);
    for (k = 0; k < 9; ++k) F[k] += dH[k];
    /* both paths: a displacement-gradient increment with det(I + dH) <= 0
     * inverts material, even where exp(dH) would not */
    if (!(gk_m3_det(F) > 0.0) || (kind == GK_PATH_OBJECTIVE && gk_m3_polar(F, dim, R, U) != GK_OK))
        return gk_err_set(err, GK_ERR_SINGULAR, "I + dH has det %g <= 0 (inverts the cell)", gk_m3_det(F));
    p->dim = dim;
    p->nsteps = nsteps;
    p->kind = kind;
    gk_m3_copy(dH, p->dH);
    if (kind == GK_PATH_CONSTANT_L) {
        double A[9];
        for (k = 0; k < 9; ++k) A[k] = dH[k] / (double)nsteps;
        gk_m3_exp(A, p->Estep);
        gk_m3_identity(p->U);
        p->w[0] = p->w[1] = p->w[2] = 0.0;
    } else {
        gk_m3_copy(U, p->U);
        if (dim == 2) {
            p->w[0] = p->w[1] = 0.0;
            p->w[2] = atan2(R[3], R[0]);
        } else {
            gk_m3_rotation_vector(R, p->w);
        }
    }
    return GK_OK;
}

GKDEF void gk_path_map(const gk_path *p, int k, double M[9]) {
    int i;
    if (p->kind == GK_PATH_CONSTANT_L) {
        double A[9];
        for (i = 0; i < 9; ++i) A[i] = p->dH[i] * ((double)k / (double)p->nsteps);
        gk_m3_exp(A, M);
    } else {
        double a = (double)k / (double)p->nsteps, w[3], R[9], S[9];
        for (i = 0; i < 3; ++i) w[i] = a * p->w[i];
        gk_m3_rotation(w, R);
        gk_m3_identity(S);
        for (i = 0; i < 9; ++i) S[i] += a * (p->U[i] - (i % 4 == 0 ? 1.0 : 0.0));
        gk_m3_mul(R, S, M);
    }
    if (p->dim == 2) {
        M[2] = M[5] = M[6] = M[7] = 0.0;
        M[8] = 1.0;
    }
}

GKDEF void gk_path_step(const gk_path *p, int k, double E[9]) {
    if (p->kind == GK_PATH_CONSTANT_L) {
        gk_m3_copy(p->Estep, E);
    } else {
        double M1[9], M0[9], M0i[9];
        gk_path_map(p, k, M1);
        gk_path_map(p, k - 1, M0);
        gk_m3_inverse(M0, M0i);
        gk_m3_mul(M1, M0i, E);
    }
    if (p->dim == 2) {
        E[2] = E[5] = E[6] = E[7] = 0.0;
        E[8] = 1.0;
    }
}

GKDEF void gk_servo_rates(const gk_servo *s, int dim, const double sigma[9], const double stiff[3], double dt,
                          double L[9]) {
    double gain = s->gain > 0.0 ? s->gain : 0.02;
    int k;
    for (k = 0; k < dim; ++k) {
        if (s->mode[k] == GK_SERVO_STRESS) {
            double err = s->target[k] - sigma[4 * k], rate;
            if (stiff[k] > 0.0 && dt > 0.0)
                rate = gain * err / (stiff[k] * dt);
            else
                rate = err > 0.0 ? s->max_rate : (err < 0.0 ? -s->max_rate : 0.0);
            L[4 * k] = gk_clamp(rate, -s->max_rate, s->max_rate);
        } else {
            L[4 * k] = s->rate[k];
        }
    }
    if (s->shear) {
        static const int pk[3][2] = {{0, 1}, {0, 2}, {1, 2}};
        int q;
        for (q = 0; q < (dim == 3 ? 3 : 1); ++q) {
            int a = pk[q][0], b = pk[q][1];
            double sig = 0.5 * (sigma[3 * a + b] + sigma[3 * b + a]), err = s->shear_target[q] - sig;
            double G = 0.25 * (stiff[a] + stiff[b]), rate; /* half the mean normal stiffness */
            if (G > 0.0 && dt > 0.0)
                rate = gain * err / (2.0 * G * dt);
            else
                rate = err > 0.0 ? s->max_rate : (err < 0.0 ? -s->max_rate : 0.0);
            rate = gk_clamp(rate, -s->max_rate, s->max_rate);
            L[3 * a + b] = rate;
            L[3 * b + a] = rate;
        }
    }
}

#endif /* GK_PCELL implementation */
