/* gk_homog.h - micro to macro: tangent, fabric, state variables.  (grainkit v0.1)
 *
 * Homogenised quantities of a gk_rve (gk_dem.h) and tensor invariants.
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_HOMOG_IMPLEMENTATION) in one file.
 *
 * WHAT IS HERE (paper equations in brackets)
 *   gk_rve_stress (gk_dem.h)   Love-Weber stress  sigma = -(1/V) sum F (x) d
 *                              [Guo & Zhao 2014 eq 5, Liang & Zhao 2019 eq 30, Liu et al. 2016 eq 44b]
 *   gk_homog_tangent           Taylor (Voigt) tangent [Guo & Zhao 2014 eq 9]:
 *        D_ijkl = (1/V) sum_c [k_n n_i n_k + k_t (delta_ik - n_i n_k)] d_j d_l
 *     (in 2D delta_ik - n_i n_k = t_i t_k, exactly eq 9; in 3D the whole
 *     tangent plane instead of YADE's single shear-force direction).
 *     k_n = dF_n/d delta, k_t = tangential stiffness (Hertz: at the current
 *     overlap). Options:
 *       GK_TANGENT_SLIDING_KEEP  sliding contacts keep k_t (YADE). Default:
 *                                a contact on its Coulomb cap gets k_t = 0
 *                                (the softest consistent choice: further
 *                                shear in the slip direction adds no force).
 *       GK_TANGENT_GEOMETRIC     add the initial-stress terms, so that D is
 *                                the exact derivative of the Love stress
 *                                under an affine, no-slip, no-spin map:
 *         + (1/V) sum [-(F_n/|d|)(delta_ik - n_i n_k) + n_i F_t,k/|d|] d_j d_l
 *         + sigma_il delta_jk - sigma_ij delta_kl
 *       GK_TANGENT_RAW           skip the minor symmetrisation. Default: D is
 *                                symmetrised in (i,j) and in (k,l) as YADE's
 *                                Voigt form, so D:W = 0 for a spin W.
 *       GK_TANGENT_RELAXED       the particles relax: the contact network of
 *                                the current state (the same springs A as eq 9,
 *                                sliding ones by the rule above) with every
 *                                particle's translation and rotation free to
 *                                minimise the spring energy at the imposed dH:
 *         D = (1/V) (K_EE - K_Ef K_ff^-1 K_fE)
 *                                (static condensation; K_EE / V is eq 9).
 *                                Always between 0 and eq 9 (H:D:H of both, any
 *                                H), and equal to eq 9 for a Bravais lattice.
 *                                It is the quasi-static response of the RVE
 *                                to a small dH without slip (tested against
 *                                the DEM relaxed to equilibrium), softer
 *                                where the network is close to a mechanism,
 *                                which the affine eq 9 does not see. Cost: a
 *                                banded Cholesky of the particle system in
 *                                reverse Cuthill-McKee order, O(n b^2) for n
 *                                unknowns (dim + rotations per particle with a
 *                                contact) and band b: far more than eq 9.
 *                                Exact mechanisms (rigid translation, one-
 *                                contact particles, free spins) are pinned by
 *                                a diagonal shift of 1e-10 x the largest
 *                                diagonal entry. Rolling springs are not
 *                                included; not with GK_TANGENT_GEOMETRIC
 *                                (-> GK_ERR_ARG).
 *     Layout: D[((i*dim + j)*dim + k)*dim + l], d sigma_ij = D_ijkl dH_kl,
 *     tension-positive, [Pa]. No contacts -> D = 0 (never NaN).
 *   gk_fabric_ratio            A = Pi_1 / Pi_2 - 1 from the eigenvalues of phi
 *                              [Liu, Bosco & Suiker 2018 eq 38]
 *   gk_homog_fabric            phi = (1/N_c) sum n (x) n; 2D anisotropy
 *                              F_a = 4 dev phi, |F_a| = sqrt(F_a:F_a / 2)
 *                              [Guo & Zhao 2014 eqs 22-25, Liang & Zhao 2019 eqs 41-43];
 *                              3D: F_a = 15/2 dev phi, |F_a| = sqrt(3/2 F_a:F_a)
 *   gk_homog_coordination      Z = 2 N_c / N_p; YADE's avgNumInteractions
 *                              (skipFree=True) = (2 N_c - N_1)/(N_p - N_0 - N_1)
 *                              (N_k: particles with k contacts); mechanical Z_m after
 *                              removing rattlers (< dim + 1 contacts) iteratively
 *   gk_homog_void_ratio        e = (V_cell - V_solid) / V_solid (2D: areas)
 *   gk_homog_unbalanced        mean |sum F_p| / mean |F_c| (YADE), and the
 *                              RMS ratio I_uf of Liu et al. 2016 eq 57
 *   gk_homog_mean_rotation     2D mean particle rotation (incl. cell spin);
 *                              3D (GK_RVE_TRACK_ROTATION): mean magnitude of
 *                              the particles' accumulated rotation vectors
 *   gk_stress_p, gk_stress_q   p = -tr sigma / dim (compression-positive);
 *                              2D q = sqrt(s:s / 2) [Guo & Zhao 2014 eq 7];
 *                              3D q = sqrt(3/2 s:s)
 *   gk_strain_v, gk_strain_q   eps_v = tr eps (tension-positive: dilation > 0;
 *                              the seeds flip it); 2D eps_q = sqrt(2 e:e)
 *                              [Guo & Zhao 2014 eq 13]; 3D eps_q = sqrt(2/3 e:e)
 *   gk_rotation_angle          rotation of the polar decomposition of F
 *                              [Liang & Zhao 2019 eqs 36-40], radians (2D: signed)
 *   gk_inertial_number, gk_rve_unbalanced, gk_rve_deform_adaptive,
 *   gk_rve_relax               are in gk_dem.h (they drive the RVE); gk_homog_unbalanced
 *                              gives gk_rve_unbalanced's mean ratio and the RMS one
 *   gk_tangent_voigt           D -> Voigt matrix (3x3 in 2D, 6x6 in 3D), with
 *                              engineering shear strain columns
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_HOMOG_H
#define GK_HOMOG_H

#include "gk_dem.h"

#define GK_TANGENT_SLIDING_KEEP 1u
#define GK_TANGENT_GEOMETRIC 2u
#define GK_TANGENT_RAW 4u
#define GK_TANGENT_RELAXED 8u

typedef struct gk_coordination {
    double z;        /* 2 N_c / N_p                                 */
    double z_nofree; /* YADE avgNumInteractions(skipFree=True): (2C - N1)/(N - N0 - N1),
                          N0, N1 = particles with 0 and 1 contacts       */
    double z_mech;   /* after iterative removal of rattlers          */
    int contacts, rattlers, free_particles;
} gk_coordination;

#ifdef __cplusplus
extern "C" {
#endif

GKDEF gk_result gk_homog_tangent(const gk_rve *rve, unsigned opts, double *D);
GKDEF double gk_homog_fabric(const gk_rve *rve, double phi[9], double Fa[9]);
GKDEF gk_result gk_homog_coordination(const gk_rve *rve, gk_coordination *out);
GKDEF double gk_homog_void_ratio(const gk_rve *rve);
GKDEF void gk_homog_unbalanced(const gk_rve *rve, double *mean_ratio, double *rms_ratio);
GKDEF double gk_homog_mean_rotation(const gk_rve *rve);
GKDEF double gk_rotation_angle(const double F[9], int dim);
GKDEF void gk_tangent_voigt(const double *D, int dim, double *V);

#ifdef __cplusplus
}
#endif

GK_INLINE double gk_stress_p(const double s[9], int dim) {
    return -(s[0] + s[4] + (dim == 3 ? s[8] : 0.0)) / dim;
}
GK_INLINE double gk_stress_q(const double s[9], int dim) {
    double m = (s[0] + s[4] + (dim == 3 ? s[8] : 0.0)) / dim, ss = 0.0, d;
    int i, j;
    for (i = 0; i < dim; ++i)
        for (j = 0; j < dim; ++j) {
            d = 0.5 * (s[3 * i + j] + s[3 * j + i]) - (i == j ? m : 0.0);
            ss += d * d;
        }
    return dim == 2 ? sqrt(0.5 * ss) : sqrt(1.5 * ss);
}
/* fabric anisotropy as an eigenvalue ratio, A = Pi_1 / Pi_2 - 1 (largest over
 * smallest eigenvalue of the fabric tensor phi of gk_homog_fabric; Liu,
 * Bosco & Suiker 2018 eqs 38-39; 3D: largest over smallest); 0 for an
 * isotropic fabric, +inf when the smallest eigenvalue is 0 (no contacts: 0) */
GK_INLINE double gk_fabric_ratio(const double phi[9], int dim) {
    double lo, hi;
    if (dim == 2) {
        double m = 0.5 * (phi[0] + phi[4]), h = 0.5 * (phi[0] - phi[4]), b = 0.5 * (phi[1] + phi[3]);
        double r = sqrt(h * h + b * b);
        hi = m + r, lo = m - r;
    } else {
        double val[3], vec[9];
        gk_m3_sym_eigen(phi, val, vec);
        lo = val[0], hi = val[2];
    }
    if (!(hi > 0.0)) return 0.0;
    return lo > 0.0 ? hi / lo - 1.0 : HUGE_VAL;
}
GK_INLINE double gk_strain_v(const double e[9], int dim) { return e[0] + e[4] + (dim == 3 ? e[8] : 0.0); }
GK_INLINE double gk_strain_q(const double e[9], int dim) {
    double m = gk_strain_v(e, dim) / dim, ee = 0.0, d;
    int i, j;
    for (i = 0; i < dim; ++i)
        for (j = 0; j < dim; ++j) {
            d = 0.5 * (e[3 * i + j] + e[3 * j + i]) - (i == j ? m : 0.0);
            ee += d * d;
        }
    return dim == 2 ? sqrt(2.0 * ee) : sqrt(2.0 / 3.0 * ee);
}

#endif /* GK_HOMOG_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_HOMOG_IMPLEMENTATION)) && !defined(GK_HOMOG_IMPL_ONCE)
#define GK_HOMOG_IMPL_ONCE

#include <string.h>

/* geometry of pair c at the current positions: branch d, |d|. dim is
 * rve->dim, a constant where the caller is inlined with one */
GK_FORCE_INLINE double gk__pair_branch_d(const gk_rve *rve, int c, double d[3], const int dim) {
    int i = rve->pl.i[c], j = rve->pl.j[c], k;
    double ds[3];
    for (k = 0; k < 3; ++k) ds[k] = k < dim ? rve->s[k][j] - rve->s[k][i] : 0.0;
    gk_pcell_image(rve->cell.h, dim, ds, d);
    if (dim == 2) d[2] = 0.0;
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

static double gk__pair_branch(const gk_rve *rve, int c, double d[3]) {
    return gk__pair_branch_d(rve, c, d, rve->dim);
}

/* contact springs of eq 9 for pair c: A (dim x dim, row-major in 3 x 3), branch d; 0 = no contact */
GK_FORCE_INLINE int gk__contact_spring_d(const gk_rve *rve, int c, unsigned opts, double A[9], double d[3],
                                         double n[3], double *dd_out, const int dim) {
    int a = rve->pl.i[c], b = rve->pl.j[c], i, k;
    double dd, delta;
    gk_real kn, fn, kt;
    if (!(rve->cs[c] & GK_CS_CONTACT)) return 0;
    dd = gk__pair_branch_d(rve, c, d, dim);
    if (!(dd > 0.0)) return 0;
    for (k = 0; k < 3; ++k) n[k] = d[k] / dd;
    delta = (double)rve->r[a] + (double)rve->r[b] - dd;
    gk_contact_stiffness(&rve->K, rve->def.mat.law, rve->r[a], rve->r[b], (gk_real)(delta > 0 ? delta : 0),
                         &kn, &fn, &kt);
    if (!(rve->phys & GK_PHYS_TANGENT)) kt = 0;
    if ((rve->cs[c] & GK_CS_SLIDING) && !(opts & GK_TANGENT_SLIDING_KEEP)) kt = 0;
    for (i = 0; i < dim; ++i)
        for (k = 0; k < dim; ++k)
            A[3 * i + k] = (double)kn * n[i] * n[k] + (double)kt * ((i == k ? 1.0 : 0.0) - n[i] * n[k]);
    *dd_out = dd;
    return 1;
}

static int gk__contact_spring(const gk_rve *rve, int c, unsigned opts, double A[9], double d[3], double n[3],
                              double *dd_out) {
    return gk__contact_spring_d(rve, c, opts, A, d, n, dd_out, rve->dim);
}

/* reverse Cuthill-McKee order of the nodes with neighbours of an undirected
 * graph (xadj/adj); pos[node] = place, -1 for isolated nodes; returns count */
static int gk__rcm(int nv, const int *xadj, const int *adj, int *pos, int *order, int *lev) {
    int cnt = 0, v, q, i;
    for (v = 0; v < nv; ++v) pos[v] = -1;
    for (;;) {
        int start = -1, head, tail, pass;
        for (v = 0; v < nv; ++v) /* unplaced node of least degree starts a component */
            if (pos[v] < 0 && xadj[v + 1] > xadj[v] &&
                (start < 0 || xadj[v + 1] - xadj[v] < xadj[start + 1] - xadj[start]))
                start = v;
        if (start < 0) break;
        for (pass = 0; pass < 2; ++pass) { /* pseudo-peripheral: least-degree node of the last BFS level */
            int best = start, last = 0;
            for (i = 0; i < nv; ++i) lev[i] = -1;
            lev[start] = 0, order[cnt] = start, head = cnt, tail = cnt + 1;
            while (head < tail) {
                int u = order[head++];
                for (q = xadj[u]; q < xadj[u + 1]; ++q)
                    if (lev[adj[q]] < 0) lev[adj[q]] = lev[u] + 1, order[tail++] = adj[q];
            }
            for (i = cnt; i < tail; ++i) last = lev[order[i]] > last ? lev[order[i]] : last;
            for (i = cnt; i < tail; ++i)
                if (lev[order[i]] == last &&
                    xadj[order[i] + 1] - xadj[order[i]] < xadj[best + 1] - xadj[best])
                    best = order[i];
            start = best;
        }
        order[cnt] = start, pos[start] = cnt, head = cnt, tail = cnt + 1; /* Cuthill-McKee */
        while (head < tail) {
            int u = order[head++], first = tail;
            for (q = xadj[u]; q < xadj[u + 1]; ++q)
                if (pos[adj[q]] < 0) pos[adj[q]] = tail, order[tail++] = adj[q];
            for (i = first + 1; i < tail; ++i) { /* new neighbours by increasing degree */
                int w = order[i], dw = xadj[w + 1] - xadj[w], m = i;
                while (m > first && xadj[order[m - 1] + 1] - xadj[order[m - 1]] > dw)
                    order[m] = order[m - 1], --m;
                order[m] = w;
            }
            for (i = first; i < tail; ++i) pos[order[i]] = i;
        }
        cnt = tail;
    }
    for (i = 0; i < cnt; ++i) pos[order[i]] = cnt - 1 - i; /* reversed */
    return cnt;
}

/* GK_TANGENT_RELAXED: D = (K_EE - K_Ef K_ff^-1 K_fE) / V over the fluctuations
 * q = (u, r_mean theta) of every particle with a contact. Relative displacement
 * at contact c (particles a -> b, branch d, normal n):
 *   delta = dH d + u_b - u_a + r_a n x theta_a + r_b n x theta_b = G dH + B q,
 * spring force A delta, energy (1/2) sum delta.A.delta. */
static gk_result gk__tangent_relaxed(const gk_rve *rve, unsigned opts, double V, double *D) {
    const gk_allocator *al = &rve->def.alloc;
    int dim = rve->dim, np = rve->n, nr = (rve->phys & GK_PHYS_ROTATION) ? (dim == 2 ? 1 : 3) : 0,
        nq = dim + nr, ne = dim * dim, nc = 0, nv, ndof, bw = 0, w, c, p, i, j, k, e, x, y;
    int *ca = NULL, *xadj = NULL, *adj = NULL, *pos = NULL, *order = NULL, *lev = NULL;
    double *cA = NULL, *cd = NULL, *cB = NULL, *L = NULL, *F = NULL, rmean = 0.0, dmax = 0.0, reg;
    gk_result res = GK_OK;
    size_t sz = (size_t)(rve->pl.n > 0 ? rve->pl.n : 1);
    ca = (int *)gk_alloc(al, 2 * sz * sizeof(int));
    cA = (double *)gk_alloc(al, 9 * sz * sizeof(double));
    cd = (double *)gk_alloc(al, 3 * sz * sizeof(double));
    cB = (double *)gk_alloc(al, 2 * 3 * 6 * sz * sizeof(double)); /* B_a, B_b: dim x nq each */
    xadj = (int *)gk_alloc(al, ((size_t)np + 1) * sizeof(int));
    adj = (int *)gk_alloc(al, 2 * sz * sizeof(int));
    pos = (int *)gk_alloc(al, (size_t)np * sizeof(int));
    order = (int *)gk_alloc(al, (size_t)np * sizeof(int));
    lev = (int *)gk_alloc(al, (size_t)np * sizeof(int));
    if (!ca || !cA || !cd || !cB || !xadj || !adj || !pos || !order || !lev) {
        res = GK_ERR_ALLOC;
        goto done;
    }
    for (p = 0; p < np; ++p) rmean += (double)rve->r[p] / np;
    for (p = 0; p <= np; ++p) xadj[p] = 0;
    for (c = 0; c < rve->pl.n; ++c) { /* the springs, and the contact graph */
        double n[3], dd, N[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}, *Ba = cB + 36 * (size_t)nc, *Bb = Ba + 18;
        int a = rve->pl.i[c], b = rve->pl.j[c];
        if (!gk__contact_spring(rve, c, opts, cA + 9 * (size_t)nc, cd + 3 * (size_t)nc, n, &dd)) continue;
        if (dim == 2) /* n x (theta e_z) = theta (n_y, -n_x) */
            N[0] = n[1], N[3] = -n[0];
        else /* n x theta = N theta */
            N[1] = -n[2], N[2] = n[1], N[3] = n[2], N[5] = -n[0], N[6] = -n[1], N[7] = n[0];
        for (i = 0; i < dim; ++i) /* B row i: [-e_i | r_a/rm N_i] and [e_i | r_b/rm N_i] */
            for (k = 0; k < nq; ++k) {
                double rot = k >= dim ? N[3 * i + (k - dim)] / rmean : 0.0;
                Ba[6 * i + k] = k < dim ? -(i == k ? 1.0 : 0.0) : (double)rve->r[a] * rot;
                Bb[6 * i + k] = k < dim ? (i == k ? 1.0 : 0.0) : (double)rve->r[b] * rot;
            }
        ca[2 * nc] = a, ca[2 * nc + 1] = b;
        if (a != b) ++xadj[a + 1], ++xadj[b + 1];
        ++nc;
    }
    if (nc == 0) goto done; /* no contacts: D = 0 as eq 9 */
    for (p = 0; p < np; ++p) xadj[p + 1] += xadj[p];
    for (p = 0; p < np; ++p) lev[p] = xadj[p];
    for (c = 0; c < nc; ++c)
        if (ca[2 * c] != ca[2 * c + 1])
            adj[lev[ca[2 * c]]++] = ca[2 * c + 1], adj[lev[ca[2 * c + 1]]++] = ca[2 * c];
    nv = gk__rcm(np, xadj, adj, pos, order, lev);
    for (c = 0; c < nc; ++c) {
        int da = pos[ca[2 * c]] - pos[ca[2 * c + 1]];
        if (da < 0) da = -da;
        if (da > bw) bw = da;
    }
    ndof = nv * nq, bw = (bw + 1) * nq - 1, w = bw + 1;
    L = (double *)gk_alloc(al, (size_t)ndof * w * sizeof(double));
    F = (double *)gk_alloc(al, (size_t)ndof * ne * sizeof(double));
    if (!L || !F) {
        res = GK_ERR_ALLOC;
        goto done;
    }
    memset(L, 0, (size_t)ndof * w * sizeof(double));
    memset(F, 0, (size_t)ndof * ne * sizeof(double));
#define GK__L(r, s) L[(size_t)(r)*w + (s) - (r) + bw]
    for (c = 0; c < nc; ++c) { /* K_ff (lower band) += B^T A B; F = -K_fE */
        const double *A = cA + 9 * (size_t)c, *d = cd + 3 * (size_t)c;
        for (x = 0; x < 2; ++x) {
            const double *Bx = cB + 36 * (size_t)c + 18 * x;
            int px = pos[ca[2 * c + x]];
            double AB[3 * 6]; /* A B_y */
            for (y = 0; y < 2; ++y) {
                const double *By = cB + 36 * (size_t)c + 18 * y;
                int py = pos[ca[2 * c + y]];
                for (i = 0; i < dim; ++i)
                    for (k = 0; k < nq; ++k) {
                        double s = 0.0;
                        for (j = 0; j < dim; ++j) s += A[3 * i + j] * By[6 * j + k];
                        AB[6 * i + k] = s;
                    }
                for (k = 0; k < nq; ++k)
                    for (j = 0; j < nq; ++j) {
                        int I = px * nq + k, J = py * nq + j;
                        double s = 0.0;
                        if (I < J) continue;
                        for (i = 0; i < dim; ++i) s += Bx[6 * i + k] * AB[6 * i + j];
                        GK__L(I, J) += s;
                    }
            }
            for (k = 0; k < nq; ++k) /* unit dH = e_m (x) e_l: (A G)_i = A_im d_l */
                for (e = 0; e < ne; ++e) {
                    int m = e / dim, l = e % dim;
                    double s = 0.0;
                    for (i = 0; i < dim; ++i) s += Bx[6 * i + k] * A[3 * i + m] * d[l];
                    F[(size_t)(px * nq + k) * ne + e] -= s;
                }
        }
    }
    for (i = 0; i < ndof; ++i) dmax = GK__L(i, i) > dmax ? GK__L(i, i) : dmax;
    /* a shift far below any contact stiffness pins the exact mechanisms (rigid translation,
     * one-contact particles, free spins), whose right-hand sides are zero */
    reg = 1e-10 * dmax;
    for (i = 0; i < ndof; ++i) GK__L(i, i) += reg;
    for (i = 0; i < ndof; ++i) { /* banded Cholesky, L L^T */
        int j0 = i - bw > 0 ? i - bw : 0, m;
        for (j = j0; j <= i; ++j) {
            int m0 = j - bw > j0 ? j - bw : j0;
            double s = GK__L(i, j);
            for (m = m0; m < j; ++m) s -= GK__L(i, m) * GK__L(j, m);
            if (j < i)
                GK__L(i, j) = s / GK__L(j, j);
            else if (s > 0.0)
                GK__L(i, i) = sqrt(s);
            else {
                res = GK_ERR_SINGULAR;
                goto done;
            }
        }
    }
    for (e = 0; e < ne; ++e) { /* q_e = K_ff^-1 F_e, in place */
        int m;
        for (i = 0; i < ndof; ++i) {
            double s = F[(size_t)i * ne + e];
            for (m = i - bw > 0 ? i - bw : 0; m < i; ++m) s -= GK__L(i, m) * F[(size_t)m * ne + e];
            F[(size_t)i * ne + e] = s / GK__L(i, i);
        }
        for (i = ndof - 1; i >= 0; --i) {
            double s = F[(size_t)i * ne + e];
            for (m = i + 1; m <= i + bw && m < ndof; ++m) s -= GK__L(m, i) * F[(size_t)m * ne + e];
            F[(size_t)i * ne + e] = s / GK__L(i, i);
        }
    }
#undef GK__L
    for (c = 0; c < nc; ++c) { /* D_ij,e = (1/V) sum (A (G e + B q_e))_i d_j */
        const double *A = cA + 9 * (size_t)c, *d = cd + 3 * (size_t)c;
        for (e = 0; e < ne; ++e) {
            double del[3] = {0, 0, 0};
            del[e / dim] = d[e % dim];
            for (x = 0; x < 2; ++x) {
                const double *Bx = cB + 36 * (size_t)c + 18 * x;
                const double *q = F + (size_t)pos[ca[2 * c + x]] * nq * ne + e;
                for (i = 0; i < dim; ++i)
                    for (k = 0; k < nq; ++k) del[i] += Bx[6 * i + k] * q[(size_t)k * ne];
            }
            for (i = 0; i < dim; ++i) {
                double f = 0.0;
                for (k = 0; k < dim; ++k) f += A[3 * i + k] * del[k];
                for (j = 0; j < dim; ++j) D[(i * dim + j) * ne + e] += f * d[j] / V;
            }
        }
    }
done:
    gk_free(al, ca), gk_free(al, cA), gk_free(al, cd), gk_free(al, cB), gk_free(al, xadj), gk_free(al, adj);
    gk_free(al, pos), gk_free(al, order), gk_free(al, lev), gk_free(al, L), gk_free(al, F);
    return res;
}

/* eq 9's sum over the contacts (and the geometric terms) into D, not yet
 * divided by V; dim a constant after inlining: the same operations */
GK_FORCE_INLINE void gk__taylor_sum(const gk_rve *rve, unsigned opts, double *D, const int dim) {
    int c, i, j, k, l;
    for (c = 0; c < rve->pl.n; ++c) {
        double d[3], n[3], dd, A[9];
        if (!gk__contact_spring_d(rve, c, opts, A, d, n, &dd, dim)) continue;
        if (opts & GK_TANGENT_GEOMETRIC) { /* A_ik += -(F_n/|d|)(delta_ik - n_i n_k) + n_i F_t,k / |d| */
            double F[3], Fn, Ft[3];
            for (k = 0; k < 3; ++k) F[k] = k < dim ? (double)rve->fc[k][c] : 0.0;
            Fn = F[0] * n[0] + F[1] * n[1] + F[2] * n[2];
            for (k = 0; k < 3; ++k) Ft[k] = F[k] - Fn * n[k];
            for (i = 0; i < dim; ++i)
                for (k = 0; k < dim; ++k)
                    A[3 * i + k] += -(Fn / dd) * ((i == k ? 1.0 : 0.0) - n[i] * n[k]) + n[i] * Ft[k] / dd;
        }
        /* A_ik = kn n_i n_k + kt (delta_ik - n_i n_k) [+ geometric]; D_ijkl += A_ik d_j d_l / V */
        for (i = 0; i < dim; ++i)
            for (j = 0; j < dim; ++j)
                for (k = 0; k < dim; ++k)
                    for (l = 0; l < dim; ++l)
                        D[((i * dim + j) * dim + k) * dim + l] += A[3 * i + k] * d[j] * d[l];
    }
}

GKDEF gk_result gk_homog_tangent(const gk_rve *rve, unsigned opts, double *D) {
    int dim = rve->dim, n4 = dim * dim * dim * dim, i, j, k, l;
    double V = gk_rve_volume(rve);
    for (k = 0; k < n4; ++k) D[k] = 0.0;
    if (!(V > 0.0)) return GK_ERR_CELL;
    if (opts & GK_TANGENT_RELAXED) { /* the condensation builds D, divided by V; not with GEOMETRIC */
        gk_result res = (opts & GK_TANGENT_GEOMETRIC) ? GK_ERR_ARG : gk__tangent_relaxed(rve, opts, V, D);
        if (res) {
            for (k = 0; k < n4; ++k) D[k] = 0.0;
            return res;
        }
    } else {
        if (dim == 2)
            gk__taylor_sum(rve, opts, D, 2);
        else
            gk__taylor_sum(rve, opts, D, 3);
        for (k = 0; k < n4; ++k) D[k] /= V;
    }
    if (opts & GK_TANGENT_GEOMETRIC) {
        const double *s = rve->stress;
        for (i = 0; i < dim; ++i)
            for (j = 0; j < dim; ++j)
                for (k = 0; k < dim; ++k)
                    for (l = 0; l < dim; ++l)
                        D[((i * dim + j) * dim + k) * dim + l] +=
                            (j == k ? s[3 * i + l] : 0.0) - (k == l ? s[3 * i + j] : 0.0);
    }
    if (!(opts & GK_TANGENT_RAW)) {
        double T[81]; /* n4 <= 3^4 */
        for (i = 0; i < dim; ++i)
            for (j = 0; j < dim; ++j)
                for (k = 0; k < dim; ++k)
                    for (l = 0; l < dim; ++l) {
#define GK__DI(a, b, c2, d2) D[(((a)*dim + (b)) * dim + (c2)) * dim + (d2)]
                        T[((i * dim + j) * dim + k) * dim + l] =
                            0.25 * (GK__DI(i, j, k, l) + GK__DI(j, i, k, l) + GK__DI(i, j, l, k) +
                                    GK__DI(j, i, l, k));
#undef GK__DI
                    }
        memcpy(D, T, (size_t)n4 * sizeof(double));
    }
    return GK_OK;
}

GKDEF double gk_homog_fabric(const gk_rve *rve, double phi[9], double Fa[9]) {
    int dim = rve->dim, c, k, l, nc = 0;
    double dev[9], ss = 0.0, f = dim == 2 ? 4.0 : 7.5;
    gk_m3_zero(phi);
    for (c = 0; c < rve->pl.n; ++c) {
        double d[3], dd;
        if (!(rve->cs[c] & GK_CS_CONTACT)) continue;
        dd = gk__pair_branch(rve, c, d);
        if (!(dd > 0.0)) continue;
        for (k = 0; k < 3; ++k)
            for (l = 0; l < 3; ++l) phi[3 * k + l] += d[k] * d[l] / (dd * dd);
        ++nc;
    }
    if (nc) {
        for (k = 0; k < 9; ++k) phi[k] /= nc;
    }
    for (k = 0; k < 9; ++k) dev[k] = 0.0;
    if (nc)
        for (k = 0; k < dim; ++k)
            for (l = 0; l < dim; ++l) dev[3 * k + l] = f * (phi[3 * k + l] - (k == l ? 1.0 / dim : 0.0));
    if (Fa) gk_m3_copy(dev, Fa);
    for (k = 0; k < 9; ++k) ss += dev[k] * dev[k];
    return dim == 2 ? sqrt(0.5 * ss) : sqrt(1.5 * ss);
}

GKDEF gk_result gk_homog_coordination(const gk_rve *rve, gk_coordination *out) {
    int n = rve->n, c, p, nc = 0, changed, alive, links, nfree = 0, n1 = 0;
    int *cnt = (int *)gk_alloc(&rve->def.alloc, (size_t)n * sizeof(int));
    unsigned char *dead = (unsigned char *)gk_alloc(&rve->def.alloc, (size_t)n);
    if (!cnt || !dead) {
        gk_free(&rve->def.alloc, cnt);
        gk_free(&rve->def.alloc, dead);
        return GK_ERR_ALLOC;
    }
    for (p = 0; p < n; ++p) {
        cnt[p] = 0;
        dead[p] = 0;
    }
    for (c = 0; c < rve->pl.n; ++c)
        if (rve->cs[c] & GK_CS_CONTACT) {
            ++cnt[rve->pl.i[c]];
            ++cnt[rve->pl.j[c]];
            ++nc;
        }
    for (p = 0; p < n; ++p) {
        if (cnt[p] == 0) ++nfree;
        if (cnt[p] == 1) ++n1;
    }
    out->contacts = nc;
    out->free_particles = nfree;
    out->z = n ? 2.0 * nc / n : 0.0;
    out->z_nofree = n - nfree - n1 > 0 ? (2.0 * nc - n1) / (n - nfree - n1) : 0.0;
    /* rattlers: fewer than dim + 1 contacts, removed until none is left */
    do {
        changed = 0;
        for (p = 0; p < n; ++p)
            if (!dead[p] && cnt[p] < rve->dim + 1) {
                dead[p] = 1;
                changed = 1;
                for (c = rve->pl.start[p]; c < rve->pl.start[p + 1]; ++c)
                    if ((rve->cs[c] & GK_CS_CONTACT) && !dead[rve->pl.j[c]]) --cnt[rve->pl.j[c]];
                for (c = rve->jstart[p]; c < rve->jstart[p + 1]; ++c) {
                    int e = rve->jlist[c];
                    if ((rve->cs[e] & GK_CS_CONTACT) && !dead[rve->pl.i[e]]) --cnt[rve->pl.i[e]];
                }
            }
    } while (changed);
    alive = 0;
    links = 0;
    for (p = 0; p < n; ++p)
        if (!dead[p]) {
            ++alive;
            links += cnt[p];
        }
    out->rattlers = n - alive;
    out->z_mech = alive ? (double)links / alive : 0.0;
    gk_free(&rve->def.alloc, cnt);
    gk_free(&rve->def.alloc, dead);
    return GK_OK;
}

GKDEF double gk_homog_void_ratio(const gk_rve *rve) { return gk_rve_volume(rve) / rve->solid_volume - 1.0; }

GKDEF void gk_homog_unbalanced(const gk_rve *rve, double *mean_ratio, double *rms_ratio) {
    if (mean_ratio) *mean_ratio = gk_rve_unbalanced(rve);
    if (rms_ratio) *rms_ratio = gk_rve_unbalanced_rms(rve);
}

GKDEF double gk_homog_mean_rotation(const gk_rve *rve) {
    double s = 0.0;
    int p;
    if (!rve->theta) return 0.0;
    for (p = 0; p < rve->n; ++p)
        s += rve->dim == 2 ? rve->theta[p] : sqrt(gk_v3_dot(rve->theta + 3 * p, rve->theta + 3 * p));
    return s / rve->n;
}

GKDEF double gk_rotation_angle(const double F[9], int dim) {
    double R[9], U[9], w[3];
    if (gk_m3_polar(F, dim, R, U) != GK_OK) return 0.0;
    if (dim == 2) return atan2(R[3], R[0]);
    gk_m3_rotation_vector(R, w);
    return sqrt(gk_v3_dot(w, w));
}

GKDEF void gk_tangent_voigt(const double *D, int dim, double *V) {
    static const int v2[3][2] = {{0, 0}, {1, 1}, {0, 1}};
    static const int v3[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};
    int nv = dim == 2 ? 3 : 6, a, b;
    for (a = 0; a < nv; ++a)
        for (b = 0; b < nv; ++b) {
            int i = dim == 2 ? v2[a][0] : v3[a][0], j = dim == 2 ? v2[a][1] : v3[a][1];
            int k = dim == 2 ? v2[b][0] : v3[b][0], l = dim == 2 ? v2[b][1] : v3[b][1];
            /* sigma_a = sum_b V_ab eps_b with engineering shear gamma = 2 eps_kl:
             * D_ijkl eps_kl + D_ijlk eps_lk = (D_ijkl + D_ijlk)/2 gamma; rows use sigma_ij */
            double x =
                k == l
                    ? D[((i * dim + j) * dim + k) * dim + l]
                    : 0.5 * (D[((i * dim + j) * dim + k) * dim + l] + D[((i * dim + j) * dim + l) * dim + k]);
            V[a * nv + b] = x;
        }
}

#endif /* GK_HOMOG implementation */
