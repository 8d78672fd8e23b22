/* gk_frame.h - the RVE of an explicit two-scale model under a deformation
 * gradient F, relaxed to equilibrium: a frame of boundary particles
 * servo-controlled to periodicity, or the deforming periodic cell.
 *                                                               (grainkit v0.1)
 *
 * Liu, Bosco & Suiker (2018) drive every Gauss point's RVE by F alone (no
 * tangent: the macro scale is solved by dynamic relaxation, gk_explicit.h)
 * and read back the first Piola-Kirchhoff stress P. Their RVE is a square
 * of P inner and Q boundary particles; the boundary particles ("the frame")
 * are moved to x_q = F X_q + w_q, their fluctuations w_q made periodic
 * (w^+ = w^-, theta^+ = theta^-, eq 12) and servo-corrected until the
 * boundary forces are anti-periodic (a^+ + a^- = 0, eq 13). grainkit's own
 * RVE is the periodic cell deformed with F (gk_dem.h): periodicity exact by
 * construction. Both are here, with the same relaxation and the same
 * output, as gk_twoscale.h procedures (THE CALLER'S PROCEDURE there).
 *
 * DO THIS in one C/C++ file:   #define GK_IMPLEMENTATION
 *                              #include "gk_frame.h"   (gk_scene.h, gk_homog.h)
 *
 *   gk_frame fr;                                   // from a framed periodic packing
 *   gk_frame_build(&fr, &periodic_packing, NULL, &err);
 *   gk_frame_set set = {GK_FRAME_SERVO, def, &fr, stats};   // one frame per prototype
 *   twoscale_def.protos[0].packing = &fr.framed;   // the RVE every point gets
 *   twoscale_def.proc = gk_frame_run, twoscale_def.proc_user = &set;
 *   ... gk_twoscale_run(&ts, dH, NULL, P, NULL) gives P (eq 14) per point
 *
 * THE FRAMED RVE (gk_frame_build). The input is a periodic packing in a box
 * cell [0, L0) x [0, L1) that is "geometrically periodic": the particles
 * crossing the cell boundary are centred on it, i.e. have x = 0 or y = 0
 * exactly (tools/gk_pack --frame), with exactly one at the corner (0, 0).
 * Cut along those lines, each such particle is a boundary particle with a
 * partner on the opposite side: a particle on x = 0 gives the pair (0, y),
 * (L0, y); on y = 0, (x, 0), (x, L1); the corner gives the four corners. The
 * others are the inner particles. fr.framed is that RVE as a packing, its
 * origin at (L0/2, L1/2) of a 2 L0 x 2 L1 periodic cell, far enough from
 * its images that nothing interacts with them up to strains of ~80 %.
 * Boundary particles are listed counter-clockwise from the corner (0, 0)
 * (bottom, right, top, left edge), with reference positions X_q relative
 * to the origin, radii R_q and the area vectors of eq 5,
 *     A_q = R_q/(R_q + R_q-1) (X_q - X_q-1) x e3 + R_q/(R_q + R_q+1) (X_q+1 - X_q) x e3,
 * which sum to 0 and give sum X_q (x) A_q = V I exactly (opposite edges
 * cancel each other's radius weighting), so eq 11, F = (1/V) sum x_q (x)
 * A_q, is the F imposed whenever w is periodic (gk_frame_gradient checks
 * it). V = L0 L1 (x the 2D thickness in the stress). A frame-frame contact
 * exists twice (once per edge copy), where the periodic cell has it once;
 * an inner particle crossing the boundary lines (fr.crossing; 0 for the
 * shipped packings) loses its contacts across it. These are the two
 * differences between the two RVEs of one packing.
 *
 * ONE RUN OF THE SERVO FRAME (GK_FRAME_SERVO; Liu, Bosco & Suiker 2018
 * Table 2; the RVE wrapped in a gk_scene, the frame particles prescribed):
 *   1. every boundary particle moves to x_q = F X_q + w_q, w_q its
 *      fluctuation at the accepted state (x_q - F_acc X_q), its rotation
 *      kept; corners to F X_c exactly (w = 0). Table 2 step 1 writes
 *      x_q = F X_q, theta_q = 0; the text adds the corrections "to the
 *      previously converged increment": we keep the converged fluctuation,
 *      the better start. The frame moves over n = ceil(max|dx| / (ramp r_min))
 *      DEM steps at constant speed, then is held;
 *   2. dynamic relaxation (eq 30; the RVE's local damping, alpha = beta)
 *      until E_kin / E_pot <= tol_energy (eqs 31-32: E_kin of the inner
 *      particles, translation and rotation; E_pot = sum over contacts of
 *      f_n^2 / 2 k_n + f_s^2 / 2 k_s), checked every `every` steps;
 *   3. boundary forces a_q = -(contact forces on q), moments m_q (eq 9);
 *      residuals of the pairs Delta a_e = a_e^+ + a_e^-, Delta m_e (eq 33)
 *      and of the corners Delta m_c = sum m_c (eq 36), and (Table 2 step 5)
 *          r_a = sqrt(sum_e |Delta a_e|^2 / a~_e^2 + (Delta m_e / m~_e)^2 + (Delta m_c / m~_c)^2),
 *      a~ = M R / dt^2, m~ = M R^2 / dt^2 (M, R of the particle, dt the DEM
 *      step). In units of the contact stiffness a~ ~ k_n R / f_dt^2 (dt =
 *      f_dt sqrt(m_min / k_n)), so r_a <= eps_a = 1e-4 bounds the imbalance
 *      relative to the boundary forces by ~ eps_a f_dt^-2 k_n / (sigma
 *      sqrt(E/2)): loose at low stress, about 10 % of a boundary force at
 *      sigma = 1e-3 k_n with f_dt = 0.4. The stats report that relative
 *      imbalance too, sqrt(sum (|Delta a|^2 + (Delta m / R)^2) / sum |a_q|^2);
 *   4. while r_a > tol_servo: both partners move by Delta u_e = -g_a Delta a_e,
 *      rotate by -g_m Delta m_e, the corners by -g_m Delta m_c (eqs 34-35),
 *      with g_a = gain_a / k_n, g_m = gain_m / (k_n R_q^2), then steps 2-3
 *      again. The minus: a_q is the force ON q from outside, so the pair
 *      moves with its net contact force -Delta a_e, as a free periodic
 *      particle would (the paper's g_a M / dt^2 = 100 is a magnitude; the
 *      sign that reduces r_a is this one). The scale that matters is
 *      g k_eff ~ 1, a Newton step with the pair's contact stiffness;
 *   5. P = (1/V) sum_q a_q (x) X_q (eq 14), tension-positive, and its
 *      Cauchy stress sigma = P F^T / det F (eq 16) by gk_frame_cauchy.
 * The paper's locked rotation (Figs 10-11) is theta_p = 0 for the inner
 * particles p: def.lock_inner = 1 holds their spin at zero
 * (gk_scene_lock_rotation) while the frame turns with its moment
 * corrections. Without rotation in the RVE's def (GK_RVE_NO_ROTATION) no
 * particle turns, boundary ones included, and no moment is corrected. The
 * periodic cell has no frame: every particle is inner, so it takes
 * GK_RVE_NO_ROTATION for the paper's lock, and refuses lock_inner.
 *
 * ONE RUN OF THE PERIODIC CELL (GK_FRAME_PERIODIC): the cell is deformed by
 * dH (gk_rve_deform, the cell boundary moving at most ramp r_min per step),
 * then relaxed at fixed cell to the same E_kin / E_pot <= tol_energy (every
 * particle's fluctuation); P = det F sigma F^-T from the Love stress sigma
 * (gk_dem.h) and F = I + H + dH.
 *
 * A run that reaches max_steps, or max_servo corrections, stops there and
 * is reported in its stats (capped), not as an error: an explicit driver
 * goes on and relaxes further at its next iteration.
 *
 * FUNCTIONS
 *   gk_frame_build(fr, periodic, alloc, err) / gk_frame_free(fr)
 *   gk_frame_run    the gk_twoscale procedure (user = a gk_frame_set)
 *   gk_frame_gradient(fr, x, F)       eq 11 from boundary positions
 *   gk_frame_energy(rve, skip, &ek, &ep)   eqs 31-32 (linear contact law)
 *   gk_frame_piola(sigma, F, P) / gk_frame_cauchy(P, F, sigma)   eq 16 both ways
 *
 * CONVENTIONS as gk_base.h: SI, tension-positive, 3x3 row-major, 2D only
 * (disks; the plane block of F). Contact law: linear (eq 32); the servo's
 * gains are per k_n, so the servo frame takes a constant k_n (gk_material.kn).
 *
 * REFERENCES: Liu J., Bosco E., Suiker A.S.J. (2018) Multi-scale modelling
 * of granular materials: numerical framework and study on micro-structural
 * features. Comp Part Mech (eqs 5-16, 30-37, Table 2). Liu J. et al. (2017)
 * Granular Matter 19:72 (the servo-controlled boundary conditions).
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_FRAME_H
#define GK_FRAME_H

#include "gk_homog.h"
#include "gk_scene.h"

typedef enum gk_frame_kind { GK_FRAME_SERVO = 0, GK_FRAME_PERIODIC = 1 } gk_frame_kind;

typedef struct gk_frame_def {
    double tol_energy; /* eq 31: E_kin / E_pot; 0 -> 1e-3                                   */
    double tol_servo;  /* eq 37: eps_a of r_a (Table 2 step 5); 0 -> 1e-4                   */
    double gain_a;     /* g_a k_n; 0 -> 0.3                                                 */
    double gain_m;     /* g_m k_n R_q^2; 0 -> 0.3                                           */
    double ramp;       /* boundary displacement per DEM step, in r_min; 0 -> 1e-3           */
    int every;         /* DEM steps between energy checks; 0 -> 10                          */
    int max_servo;     /* servo corrections per run; 0 -> 20                                */
    long max_steps;    /* DEM steps per run; 0 -> 200 000                                   */
    int lock_inner;    /* 1: the inner particles do not turn, the frame does (servo only)   */
} gk_frame_def;

/* what one run did (per point; written by that point's run only) */
typedef struct gk_frame_stats {
    long steps;          /* DEM steps of the run                                      */
    long ramp_steps;     /* ... of which the frame or cell moved                      */
    int servo;           /* servo corrections (0 for the periodic cell)               */
    int capped;          /* 1 if max_steps or max_servo stopped it                    */
    double residual;     /* r_a of Table 2 step 5 at the end (servo)                  */
    double residual_rel; /* the same imbalance relative to the boundary forces        */
    double energy_ratio; /* E_kin / E_pot at the end                                  */
    double coordination; /* 2 contacts / particles (all the RVE's particles)          */
    double anisotropy;   /* A = Pi_1 / Pi_2 - 1 of every contact (eq 38)              */
    double F[9];         /* the deformation gradient of the run                       */
} gk_frame_stats;

typedef struct gk_frame {
    int n;             /* particles of the framed RVE (inner + boundary copies)      */
    int nq, npair;     /* boundary particles Q (4 corners + E edge), edge pairs E/2 */
    int ninner;        /* P                                                          */
    int crossing;      /* inner particles whose disk crosses the boundary lines      */
    double L[2];       /* the periodic cell's edges                                  */
    double origin[2];  /* the frame's corner (0, 0) in the framed RVE's cell         */
    double V;          /* L0 L1                                                      */
    gk_packing framed; /* the framed RVE (ids = indices in it)                       */
    int32_t *q;        /* nq: framed index of each boundary particle, counter-clockwise */
    int32_t *source;   /* n: index in the periodic packing of each framed particle   */
    double *X, *A, *R; /* nq: reference position and area vector (2 each), radius   */
    int *pair;         /* npair x 2: boundary list indices (minus, plus)             */
    int corner[4];     /* boundary list indices of the corners, counter-clockwise    */
    gk_allocator alloc;
} gk_frame;

/* the first argument of gk_frame_run */
typedef struct gk_frame_set {
    gk_frame_kind kind;
    gk_frame_def def;
    const gk_frame *frames; /* GK_FRAME_SERVO: one per prototype of the set            */
    gk_frame_stats *stats;  /* one per point, or NULL                                  */
} gk_frame_set;

#ifdef __cplusplus
extern "C" {
#endif

GKDEF gk_result gk_frame_build(gk_frame *fr, const gk_packing *periodic, const gk_allocator *alloc,
                               gk_err *err);
GKDEF void gk_frame_free(gk_frame *fr);
/* the gk_twoscale_proc_fn of both RVEs: stress = P (eq 14 or det F sigma F^-T) */
GKDEF gk_result gk_frame_run(void *set, int point, int proto, gk_rve *rve, const double H[9],
                             const double dH[9], double scale, double stress[9], int *steps);
/* eq 11 from the positions x (2 per boundary particle, relative to the origin) */
GKDEF void gk_frame_gradient(const gk_frame *fr, const double *x, double F[9]);
/* eqs 31-32: kinetic energy of the particles whose skip[id] is 0 (skip NULL: all), elastic energy of
 * every contact of the last step (k_n constant or E r*); GK_ERR_ARG (nothing written) for a non-linear
 * law, GK_ERR_ALLOC */
GKDEF gk_result gk_frame_energy(const gk_rve *rve, const unsigned char *skip, double *ekin, double *epot);

#ifdef __cplusplus
}
#endif

/* P = det F sigma F^-T and back, sigma = P F^T / det F (eq 16); 2D: the plane block */
GK_INLINE void gk_frame_piola(const double sigma[9], const double F[9], double P[9]) {
    double Fi[9], t[9];
    int k;
    gk_m3_inverse(F, Fi);
    gk_m3_transpose(Fi, t);
    gk_m3_mul(sigma, t, P);
    for (k = 0; k < 9; ++k) P[k] *= gk_m3_det(F);
}
GK_INLINE void gk_frame_cauchy(const double P[9], const double F[9], double sigma[9]) {
    double Ft[9];
    int k;
    gk_m3_transpose(F, Ft);
    gk_m3_mul(P, Ft, sigma);
    for (k = 0; k < 9; ++k) sigma[k] /= gk_m3_det(F);
}

#endif /* GK_FRAME_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_FRAME_IMPLEMENTATION)) && !defined(GK_FRAME_IMPL_ONCE)
#define GK_FRAME_IMPL_ONCE

#include <stdlib.h>
#include <string.h>

GKDEF void gk_frame_free(gk_frame *fr) {
    const gk_allocator *a = &fr->alloc;
    gk_packing_free(&fr->framed);
    gk_free(a, fr->q), gk_free(a, fr->source), gk_free(a, fr->X), gk_free(a, fr->A), gk_free(a, fr->R);
    gk_free(a, fr->pair);
    fr->q = fr->source = NULL, fr->X = fr->A = fr->R = NULL, fr->pair = NULL;
    fr->n = fr->nq = fr->npair = 0;
}

/* boundary entries before sorting: edge (0 bottom, 1 right, 2 top, 3 left), coordinate along it */
typedef struct gk__fq {
    int edge, src, corner; /* corner: 0..3 or -1 */
    double s, c;           /* sort key along the edge (counter-clockwise), the coordinate itself */
} gk__fq;
static int gk__fq_cmp(const void *a, const void *b) {
    const gk__fq *x = (const gk__fq *)a, *y = (const gk__fq *)b;
    if (x->edge != y->edge) return x->edge < y->edge ? -1 : 1;
    return x->s < y->s ? -1 : x->s > y->s;
}

GKDEF gk_result gk_frame_build(gk_frame *out, const gk_packing *pk, const gk_allocator *alloc, gk_err *err) {
    gk_frame F;
    gk__fq *e = NULL;
    int *role = NULL, n, p, k, nline = 0, ncorner = 0, ncopy, m, i;
    double L0, L1, tol;
    gk_result res = GK_OK;
    memset(&F, 0, sizeof F);
    if (alloc) F.alloc = *alloc;
    if (!pk || pk->dim != 2 || pk->n < 1 || !pk->x || !pk->y || !pk->r)
        return gk_err_set(err, GK_ERR_ARG, "frame: a 2D packing is needed");
    L0 = pk->h[0], L1 = pk->h[4];
    if (pk->h[1] != 0.0 || pk->h[3] != 0.0 || !(L0 > 0.0) || !(L1 > 0.0))
        return gk_err_set(err, GK_ERR_ARG, "frame: the packing's cell must be a box");
    n = pk->n;
    tol = 1e-12 * (L0 > L1 ? L0 : L1);
    role = (int *)gk_alloc(&F.alloc, (size_t)n * sizeof(int));
    if (!role) return gk_err_set(err, GK_ERR_ALLOC, "frame: out of memory");
    for (p = 0; p < n; ++p) { /* bit 0: on x = 0 (or L0), bit 1: on y = 0 (or L1) */
        double x = pk->x[p], y = pk->y[p];
        if (!isfinite(x) || !isfinite(y) || !(pk->r[p] > 0.0)) {
            gk_free(&F.alloc, role);
            return gk_err_set(err, GK_ERR_ARG, "frame: particle %d has a bad position or radius", p);
        }
        role[p] = (fabs(x) <= tol || fabs(x - L0) <= tol) | ((fabs(y) <= tol || fabs(y - L1) <= tol) << 1);
        nline += role[p] == 1 || role[p] == 2;
        ncorner += role[p] == 3;
    }
    if (ncorner != 1) {
        gk_free(&F.alloc, role);
        return gk_err_set(err, GK_ERR_ARG,
                          "frame: %d particles at the cell corner (needs exactly one: a packing made with "
                          "gk_pack --frame)",
                          ncorner);
    }
    ncopy = 2 * nline + 4;
    F.nq = ncopy;
    F.npair = nline;
    F.ninner = n - nline - 1;
    F.n = F.ninner + F.nq;
    F.L[0] = L0, F.L[1] = L1, F.V = L0 * L1;
    F.origin[0] = 0.5 * L0, F.origin[1] = 0.5 * L1;
    e = (gk__fq *)gk_alloc(&F.alloc, (size_t)ncopy * sizeof *e);
    F.q = (int32_t *)gk_alloc(&F.alloc, (size_t)ncopy * sizeof(int32_t));
    F.source = (int32_t *)gk_alloc(&F.alloc, (size_t)F.n * sizeof(int32_t));
    F.X = (double *)gk_alloc(&F.alloc, 2 * (size_t)ncopy * sizeof(double));
    F.A = (double *)gk_alloc(&F.alloc, 2 * (size_t)ncopy * sizeof(double));
    F.R = (double *)gk_alloc(&F.alloc, (size_t)ncopy * sizeof(double));
    F.pair = (int *)gk_alloc(&F.alloc, 2 * (size_t)(nline + 1) * sizeof(int));
    if (!e || !F.q || !F.source || !F.X || !F.A || !F.R || !F.pair) {
        res = gk_err_set(err, GK_ERR_ALLOC, "frame: out of memory");
        goto done;
    }
    /* the boundary copies, each on its edge with its coordinate along the edge (counter-clockwise) */
    for (m = 0, p = 0; p < n; ++p) {
        double x = fabs(pk->x[p] - L0) <= tol ? 0.0 : pk->x[p],
               y = fabs(pk->y[p] - L1) <= tol ? 0.0 : pk->y[p];
        if (role[p] == 3) {
            for (k = 0; k < 4; ++k)
                e[m].edge = k, e[m].src = p, e[m].corner = k, e[m].s = -1.0, e[m].c = 0.0, ++m;
        } else if (role[p] == 2) { /* on y = 0: bottom (x ascending) and top (x descending) */
            e[m].edge = 0, e[m].src = p, e[m].corner = -1, e[m].s = x, e[m].c = x, ++m;
            e[m].edge = 2, e[m].src = p, e[m].corner = -1, e[m].s = -x, e[m].c = x, ++m;
        } else if (role[p] == 1) { /* on x = 0: right (y ascending) and left (y descending) */
            e[m].edge = 1, e[m].src = p, e[m].corner = -1, e[m].s = y, e[m].c = y, ++m;
            e[m].edge = 3, e[m].src = p, e[m].corner = -1, e[m].s = -y, e[m].c = y, ++m;
        }
    }
    for (i = 0; i < ncopy; ++i) /* each edge's corner first */
        if (e[i].corner >= 0) e[i].s = -2.0 * (L0 > L1 ? L0 : L1);
    qsort(e, (size_t)ncopy, sizeof *e, gk__fq_cmp);
    /* the framed packing: inner particles first (wrapped into the cell), then the boundary copies */
    res = gk_packing_init(&F.framed, 2, F.n, &F.alloc, err);
    if (res) goto done;
    gk_m3_identity(F.framed.h);
    F.framed.h[0] = 2.0 * L0, F.framed.h[4] = 2.0 * L1;
    for (m = 0, p = 0; p < n; ++p) {
        double x, y, r = pk->r[p];
        if (role[p]) continue;
        x = pk->x[p] - L0 * floor(pk->x[p] / L0), y = pk->y[p] - L1 * floor(pk->y[p] / L1);
        F.crossing += x < r || x > L0 - r || y < r || y > L1 - r;
        F.framed.x[m] = F.origin[0] + x, F.framed.y[m] = F.origin[1] + y, F.framed.r[m] = r;
        F.source[m++] = p;
    }
    for (i = 0; i < ncopy; ++i) {
        const gk__fq *c = &e[i];
        double X = 0.0, Y = 0.0;
        if (c->corner >= 0) {
            X = (c->corner == 1 || c->corner == 2) ? L0 : 0.0;
            Y = c->corner >= 2 ? L1 : 0.0;
            F.corner[c->corner] = i;
        } else if (c->edge == 0)
            X = c->c;
        else if (c->edge == 1)
            X = L0, Y = c->c;
        else if (c->edge == 2)
            X = c->c, Y = L1;
        else
            Y = c->c;
        F.X[2 * i] = X, F.X[2 * i + 1] = Y, F.R[i] = pk->r[c->src];
        F.framed.x[m] = F.origin[0] + X, F.framed.y[m] = F.origin[1] + Y, F.framed.r[m] = pk->r[c->src];
        F.source[m] = c->src;
        F.q[i] = m++;
    }
    /* pairs (minus, plus): bottom with top, left with right, by their source particle */
    for (k = 0, i = 0; i < ncopy; ++i) {
        int j;
        if (e[i].corner >= 0 || (e[i].edge != 0 && e[i].edge != 3)) continue;
        for (j = 0; j < ncopy; ++j)
            if (e[j].corner < 0 && e[j].src == e[i].src && e[j].edge == (e[i].edge == 0 ? 2 : 1)) break;
        F.pair[2 * k] = i, F.pair[2 * k + 1] = j, ++k;
    }
    /* eq 5 */
    for (i = 0; i < ncopy; ++i) {
        int a = (i + ncopy - 1) % ncopy, b = (i + 1) % ncopy;
        double wa = F.R[i] / (F.R[i] + F.R[a]), wb = F.R[i] / (F.R[i] + F.R[b]);
        double da[2], db[2];
        da[0] = F.X[2 * i] - F.X[2 * a], da[1] = F.X[2 * i + 1] - F.X[2 * a + 1];
        db[0] = F.X[2 * b] - F.X[2 * i], db[1] = F.X[2 * b + 1] - F.X[2 * i + 1];
        F.A[2 * i] = wa * da[1] + wb * db[1]; /* (d x e3) = (d_y, -d_x) */
        F.A[2 * i + 1] = -(wa * da[0] + wb * db[0]);
    }
done:
    gk_free(&F.alloc, e);
    gk_free(&F.alloc, role);
    if (res) {
        gk_frame_free(&F);
        return res;
    }
    *out = F;
    return GK_OK;
}

GKDEF void gk_frame_gradient(const gk_frame *fr, const double *x, double F[9]) {
    int i, a, b;
    gk_m3_zero(F);
    for (i = 0; i < fr->nq; ++i)
        for (a = 0; a < 2; ++a)
            for (b = 0; b < 2; ++b) F[3 * a + b] += x[2 * i + a] * fr->A[2 * i + b] / fr->V;
    F[8] = 1.0;
}

GKDEF gk_result gk_frame_energy(const gk_rve *rve, const unsigned char *skip, double *ekin, double *epot) {
    gk_rve_contact k;
    double ek = 0.0, ep = 0.0, kn = (double)rve->K.kn_const, *rad = NULL;
    int c = 0, p, d, maxid = 0;
    if (rve->def.mat.law != GK_LAW_LINEAR) return GK_ERR_ARG;
    if (!(kn > 0.0)) { /* k_n = E r*, r* = 2 r_i r_j / (r_i + r_j) (gk_contact.h): the radii by packing id */
        for (p = 0; p < rve->n; ++p)
            if (rve->id[p] > maxid) maxid = rve->id[p];
        rad = (double *)gk_alloc(&rve->def.alloc, ((size_t)maxid + 1) * sizeof(double));
        if (!rad) return GK_ERR_ALLOC;
        for (p = 0; p < rve->n; ++p) rad[rve->id[p]] = (double)rve->r[p];
    }
    for (p = 0; p < rve->n; ++p) {
        double m = 1.0 / (double)rve->minv[p];
        if (skip && skip[rve->id[p]]) continue;
        for (d = 0; d < rve->dim; ++d) ek += 0.5 * m * (double)rve->v[d][p] * (double)rve->v[d][p];
        if (rve->w[2]) ek += 0.5 / (double)rve->Iinv[p] * (double)rve->w[2][p] * (double)rve->w[2][p];
    }
    while (gk_rve_contact_next(rve, &c, &k)) {
        double dd = sqrt(k.d[0] * k.d[0] + k.d[1] * k.d[1] + k.d[2] * k.d[2]), fn = 0.0, f2 = 0.0, kk = kn,
               kt;
        for (d = 0; d < 3; ++d) fn += k.f[d] * k.d[d] / dd, f2 += k.f[d] * k.f[d];
        if (rad) kk = (double)rve->K.young * 2.0 * rad[k.i] * rad[k.j] / (rad[k.i] + rad[k.j]);
        kt = (double)rve->K.kt_ratio * kk;
        ep += 0.5 * fn * fn / kk + (kt > 0.0 ? 0.5 * (f2 - fn * fn) / kt : 0.0);
    }
    gk_free(&rve->def.alloc, rad);
    *ekin = ek, *epot = ep;
    return GK_OK;
}

/* the energy ratio is reached (0/0 counts: at rest with no contact) */
static int gk__frame_calm(double ek, double ep, double tol) { return ep > 0.0 ? ek <= tol * ep : ek == 0.0; }

/* the RVE's coordination and fabric anisotropy into the stats */
static void gk__frame_state(const gk_rve *rve, gk_frame_stats *st) {
    double phi[9], Fa[9];
    st->coordination = rve->n > 0 ? 2.0 * rve->ncontacts / rve->n : 0.0;
    gk_homog_fabric(rve, phi, Fa);
    st->anisotropy = gk_fabric_ratio(phi, 2);
}

/* ------------------------------------------------------------ servo frame */
typedef struct gk__fw {
    gk_scene sc;
    const gk_frame *fr;
    const gk_frame_def *d;
    int *idx;            /* nq: scene index of each boundary particle */
    unsigned char *skip; /* by framed id: 1 boundary                   */
    double *dx, *dth;    /* nq x 2, nq: the next move                  */
    long steps, ramp, relax;
    int rot, capped;
    double ek, ep;
} gk__fw;

/* the frame moves by dx, dth over n steps at constant speed, then is held */
static gk_result gk__fw_move(gk__fw *w) {
    gk_scene *sc = &w->sc;
    const gk_frame *fr = w->fr;
    double mx = 0.0, dt = sc->rve.dt, zero[3] = {0, 0, 0};
    long n;
    int i;
    gk_result r;
    for (i = 0; i < fr->nq; ++i) {
        double d = sqrt(w->dx[2 * i] * w->dx[2 * i] + w->dx[2 * i + 1] * w->dx[2 * i + 1]);
        if (d > mx) mx = d;
        if (fabs(w->dth[i]) * fr->R[i] > mx) mx = fabs(w->dth[i]) * fr->R[i];
    }
    n = (long)ceil(mx / (w->d->ramp * sc->rve.rmin));
    if (n < 1) return GK_OK;
    if (n > w->d->max_steps) n = w->d->max_steps;
    for (i = 0; i < fr->nq; ++i) {
        double v[3], s[3];
        v[0] = w->dx[2 * i] / (n * dt), v[1] = w->dx[2 * i + 1] / (n * dt), v[2] = 0.0;
        s[0] = s[1] = 0.0, s[2] = w->rot ? w->dth[i] / (n * dt) : 0.0;
        if ((r = gk_scene_prescribe(sc, w->idx[i], v, s)) != GK_OK) return r;
    }
    if ((r = gk_scene_step(sc, n)) != GK_OK) return r;
    for (i = 0; i < fr->nq; ++i)
        if ((r = gk_scene_prescribe(sc, w->idx[i], zero, zero)) != GK_OK) return r;
    w->steps += n, w->ramp += n;
    return GK_OK;
}

/* eq 30 until eq 31 (or the step cap) */
static gk_result gk__fw_relax(gk__fw *w) {
    gk_result r;
    do {
        if (w->steps >= w->d->max_steps) {
            w->capped = 1;
            return GK_OK;
        }
        if ((r = gk_scene_step(&w->sc, w->d->every)) != GK_OK) return r;
        w->steps += w->d->every, w->relax += w->d->every;
        if ((r = gk_frame_energy(&w->sc.rve, w->skip, &w->ek, &w->ep)) != GK_OK)
            return gk_err_set(&w->sc.err, r, "frame: eqs 31-32 need the linear contact law");
    } while (!gk__frame_calm(w->ek, w->ep, w->d->tol_energy));
    return GK_OK;
}

/* eq 33, 36 residuals, r_a of Table 2 step 5 (returned) and relative (*rel); the next corrections
 * (eqs 34-35) into dx, dth */
static double gk__fw_residual(gk__fw *w, double *rel) {
    const gk_frame *fr = w->fr;
    const gk_scene *sc = &w->sc;
    double kn = (double)sc->rve.K.kn_const, dt2 = sc->rve.dt * sc->rve.dt, num = 0.0, den = 0.0, ra = 0.0;
    double dmc = 0.0, Rc = fr->R[fr->corner[0]], Mc = sc->mass[w->idx[fr->corner[0]]];
    int i, e, c;
    for (i = 0; i < fr->nq; ++i) {
        int p = w->idx[i];
        den += sc->load[0][p] * sc->load[0][p] + sc->load[1][p] * sc->load[1][p];
        w->dx[2 * i] = w->dx[2 * i + 1] = w->dth[i] = 0.0;
    }
    for (e = 0; e < fr->npair; ++e) {
        int a = fr->pair[2 * e], b = fr->pair[2 * e + 1], pa = w->idx[a], pb = w->idx[b];
        /* Delta a = a^- + a^+ = -(contact forces on both): the pair moves with -Delta a */
        double dax = -(sc->load[0][pa] + sc->load[0][pb]), day = -(sc->load[1][pa] + sc->load[1][pb]);
        double dm = w->rot ? -(sc->loadt[2][pa] + sc->loadt[2][pb]) : 0.0, R = fr->R[a],
               at = sc->mass[pa] * R / dt2;
        num += dax * dax + day * day + (dm / R) * (dm / R);
        ra += (dax * dax + day * day) / (at * at) + (dm / (at * R)) * (dm / (at * R));
        w->dx[2 * a] = w->dx[2 * b] = -w->d->gain_a / kn * dax;
        w->dx[2 * a + 1] = w->dx[2 * b + 1] = -w->d->gain_a / kn * day;
        w->dth[a] = w->dth[b] = -w->d->gain_m / (kn * R * R) * dm;
    }
    if (w->rot) {
        for (c = 0; c < 4; ++c) dmc -= sc->loadt[2][w->idx[fr->corner[c]]];
        num += (dmc / Rc) * (dmc / Rc);
        ra += (dmc * dt2 / (Mc * Rc * Rc)) * (dmc * dt2 / (Mc * Rc * Rc));
        for (c = 0; c < 4; ++c) w->dth[fr->corner[c]] = -w->d->gain_m / (kn * Rc * Rc) * dmc;
    }
    *rel = den > 0.0 ? sqrt(num / den) : 0.0;
    return sqrt(ra);
}

static gk_result gk__frame_servo(const gk_frame_set *set, const gk_frame *fr, gk_rve *rve, const double H[9],
                                 const double dH[9], double P[9], gk_frame_stats *st) {
    gk__fw w;
    const gk_allocator *al = &rve->def.alloc;
    double Fa[4], Fn[4], res = 0.0, rel = 0.0, zero[3] = {0.0, 0.0, 0.0};
    int i, it = 0, nq = fr->nq;
    gk_result r;
    memset(&w, 0, sizeof w);
    w.fr = fr, w.d = &set->def;
    w.rot = !(rve->def.flags & GK_RVE_NO_ROTATION);
    if (rve->n != fr->n)
        return gk_err_set(&rve->err, GK_ERR_ARG, "frame: the RVE has %d particles, its frame %d", rve->n,
                          fr->n);
    if (!(rve->K.kn_const > 0))
        return gk_err_set(&rve->err, GK_ERR_ARG,
                          "frame: the servo's gains need a constant k_n (gk_material.kn)");
    for (i = 0; i < 4; ++i) {
        Fa[i] = H[3 * (i / 2) + i % 2] + (i == 0 || i == 3);
        Fn[i] = Fa[i] + dH[3 * (i / 2) + i % 2];
    }
    w.idx = (int *)gk_alloc(al, (size_t)nq * sizeof(int));
    w.skip = (unsigned char *)gk_alloc(al, (size_t)fr->n);
    w.dx = (double *)gk_alloc(al, 2 * (size_t)nq * sizeof(double));
    w.dth = (double *)gk_alloc(al, (size_t)nq * sizeof(double));
    if (!w.idx || !w.skip || !w.dx || !w.dth) {
        r = gk_err_set(&rve->err, GK_ERR_ALLOC, "frame: out of memory");
        goto out;
    }
    if ((r = gk_scene_wrap(&w.sc, rve)) != GK_OK) {
        gk_err_set(&rve->err, r, "%s", gk_scene_error(&w.sc));
        goto out;
    }
    memset(w.skip, 0, (size_t)fr->n);
    for (i = 0; i < nq; ++i) {
        double x[3], X = fr->X[2 * i], Y = fr->X[2 * i + 1], wx, wy;
        int corner = i == fr->corner[0] || i == fr->corner[1] || i == fr->corner[2] || i == fr->corner[3];
        w.idx[i] = gk_scene_index(&w.sc, fr->q[i]);
        w.skip[fr->q[i]] = 1;
        gk_scene_position(&w.sc, w.idx[i], x);
        x[0] -= fr->origin[0], x[1] -= fr->origin[1];
        wx = corner ? 0.0 : x[0] - (Fa[0] * X + Fa[1] * Y); /* the accepted fluctuation */
        wy = corner ? 0.0 : x[1] - (Fa[2] * X + Fa[3] * Y);
        w.dx[2 * i] = Fn[0] * X + Fn[1] * Y + wx - x[0];
        w.dx[2 * i + 1] = Fn[2] * X + Fn[3] * Y + wy - x[1];
        w.dth[i] = 0.0;
    }
    /* the frame is held (prescribed, at rest) from the start, so that a run with nothing to move
     * (dH = 0) relaxes the inside against it and records its loads (eq 9) like any other */
    for (i = 0, r = GK_OK; i < nq && r == GK_OK; ++i) r = gk_scene_prescribe(&w.sc, w.idx[i], zero, zero);
    if (set->def.lock_inner)
        for (i = 0; i < w.sc.rve.n && r == GK_OK; ++i)
            if (!w.skip[w.sc.rve.id[i]]) r = gk_scene_lock_rotation(&w.sc, i, 1);
    if (!r) r = gk__fw_move(&w);
    while (!r) {
        if ((r = gk__fw_relax(&w)) != GK_OK) break;
        res = gk__fw_residual(&w, &rel);
        if (res <= set->def.tol_servo) break;
        if (it == set->def.max_servo || w.capped) {
            w.capped = 1;
            break;
        }
        ++it;
        r = gk__fw_move(&w);
    }
    if (!r) { /* eq 14 */
        gk_m3_zero(P);
        for (i = 0; i < nq; ++i) {
            int p = w.idx[i], a, b;
            for (a = 0; a < 2; ++a)
                for (b = 0; b < 2; ++b)
                    P[3 * a + b] -= w.sc.load[a][p] * fr->X[2 * i + b] / (fr->V * w.sc.rve.volume_factor);
        }
    }
    if (st) {
        st->steps = w.steps, st->ramp_steps = w.ramp, st->servo = it, st->capped = w.capped;
        st->residual = res, st->residual_rel = rel, st->energy_ratio = w.ep > 0.0 ? w.ek / w.ep : 0.0;
        gk__frame_state(&w.sc.rve, st);
    }
    if (r) gk_err_set(&w.sc.rve.err, r, "%s", gk_scene_error(&w.sc));
    gk_scene_unwrap(&w.sc, rve);
out:
    gk_free(al, w.idx), gk_free(al, w.skip), gk_free(al, w.dx), gk_free(al, w.dth);
    return r;
}

/* ------------------------------------------------------------ periodic cell */
static gk_result gk__frame_periodic(const gk_frame_set *set, gk_rve *rve, const double F[9],
                                    const double dH[9], double P[9], gk_frame_stats *st) {
    double mx = 0.0, w[3], sigma[9], ek = 0.0, ep = 0.0, L0[9], Ls[9];
    long n, steps = 0;
    int k, capped = 0;
    gk_result r;
    gk_pcell_widths(&rve->cell, w);
    for (k = 0; k < 4; ++k) {
        double d = fabs(dH[3 * (k / 2) + k % 2]) * (w[0] > w[1] ? w[0] : w[1]);
        if (d > mx) mx = d;
    }
    n = (long)ceil(mx / (set->def.ramp * rve->rmin));
    if (n > 0) {
        if (n > set->def.max_steps) n = set->def.max_steps;
        if ((r = gk_rve_deform(rve, dH, (int)n)) != GK_OK) return r;
        steps = n;
    }
    gk_m3_copy(rve->L, Ls);
    gk_m3_zero(L0);
    gk_rve_set_velocity_gradient(rve, L0);
    do {
        if (steps >= set->def.max_steps) {
            capped = 1;
            break;
        }
        if ((r = gk_rve_step(rve, set->def.every)) != GK_OK) return r;
        steps += set->def.every;
        if ((r = gk_frame_energy(rve, NULL, &ek, &ep)) != GK_OK)
            return gk_err_set(&rve->err, r, "frame: eqs 31-32 need the linear contact law");
    } while (!gk__frame_calm(ek, ep, set->def.tol_energy));
    gk_rve_set_velocity_gradient(rve, Ls);
    gk_rve_stress(rve, sigma);
    gk_frame_piola(sigma, F, P);
    if (st) {
        st->steps = steps, st->ramp_steps = n, st->servo = 0, st->capped = capped;
        st->residual = 0.0, st->energy_ratio = ep > 0.0 ? ek / ep : 0.0;
        gk__frame_state(rve, st);
    }
    return GK_OK;
}

GKDEF gk_result gk_frame_run(void *user, int point, int proto, gk_rve *rve, const double H[9],
                             const double dH[9], double scale, double stress[9], int *steps) {
    const gk_frame_set *in = (const gk_frame_set *)user;
    gk_frame_set set;
    gk_frame_stats st;
    double F[9];
    int k;
    gk_result r;
    (void)scale;
    memset(&st, 0, sizeof st);
    if (!in || rve->dim != 2)
        return gk_err_set(&rve->err, GK_ERR_ARG, "frame: a 2D RVE and its gk_frame_set are needed");
    set = *in;
    if (set.def.tol_energy == 0) set.def.tol_energy = 1e-3;
    if (set.def.tol_servo == 0) set.def.tol_servo = 1e-4;
    if (set.def.gain_a == 0) set.def.gain_a = 0.3;
    if (set.def.gain_m == 0) set.def.gain_m = 0.3;
    if (set.def.ramp == 0) set.def.ramp = 1e-3;
    if (set.def.every == 0) set.def.every = 10;
    if (set.def.max_servo == 0) set.def.max_servo = 20;
    if (set.def.max_steps == 0) set.def.max_steps = 200000;
    if (!(set.def.tol_energy > 0) || !(set.def.tol_servo > 0) || !(set.def.gain_a > 0) ||
        !(set.def.gain_m > 0) || !(set.def.ramp > 0) || set.def.every < 1 || set.def.max_servo < 1 ||
        set.def.max_steps < 1)
        return gk_err_set(&rve->err, GK_ERR_ARG, "frame: tolerances, gains, ramp and caps must be > 0");
    if (set.def.lock_inner != 0 && set.def.lock_inner != 1)
        return gk_err_set(&rve->err, GK_ERR_ARG, "frame: lock_inner %d is not 0 or 1", set.def.lock_inner);
    if (set.def.lock_inner && set.kind == GK_FRAME_PERIODIC)
        return gk_err_set(&rve->err, GK_ERR_ARG,
                          "frame: the periodic cell has no frame (every particle is inner): lock the "
                          "rotation with GK_RVE_NO_ROTATION, not lock_inner");
    gk_m3_identity(F);
    for (k = 0; k < 9; ++k) F[k] += H[k] + dH[k];
    if (!(gk_m3_det(F) > 0.0)) return gk_err_set(&rve->err, GK_ERR_CELL, "frame: det F = %g", gk_m3_det(F));
    if (set.kind == GK_FRAME_SERVO) {
        if (!set.frames) return gk_err_set(&rve->err, GK_ERR_ARG, "frame: no frames given");
        r = gk__frame_servo(&set, &set.frames[proto], rve, H, dH, stress, &st);
    } else if (set.kind == GK_FRAME_PERIODIC) {
        r = gk__frame_periodic(&set, rve, F, dH, stress, &st);
    } else
        return gk_err_set(&rve->err, GK_ERR_ARG, "frame: unknown kind %d", (int)set.kind);
    gk_m3_copy(F, st.F);
    if (set.stats) set.stats[point] = st;
    *steps = (int)(st.steps < 2000000000L ? st.steps : 2000000000L);
    return r;
}

#endif /* GK_FRAME implementation */
