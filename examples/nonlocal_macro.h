/* nonlocal_macro.h - the macro side of build/femdem_nonlocal (examples/femdem_nonlocal.c; examples,
 * not library): the Hex8 mesh of each test with its ties and platens, the explicit step with the
 * corotational update and the nonlocal average, the coarse time step, the measurements (the CSV
 * rows, the shear profile and band) and the linear elastic column of the wave test.
 *
 * THE MODEL (eqs 44-66 and Appendix A of the paper)
 *   Macro: 8-node hexahedra with one Gauss point and Flanagan-Belytschko
 *   stiffness hourglass control (k = kappa (lambda + 2 mu) V sum|grad N|^2 /
 *   192, kappa = --hourglass 0.1, lambda and mu of the RVE; its stored energy
 *   1/2 k sum (gamma . u)^2 per element is an output, against the stress work
 *   int sigma : d eps V, trapezoidal in time). --gauss 8 is the fully
 *   integrated element instead: 2 x 2 x 2 Gauss points, an RVE at each (eight
 *   times the DEM), no hourglass modes and no control; the outputs per element
 *   are the means of its points. It is the local reference for the choice of
 *   kappa; its element bound on the frequency (eq 65) is within 3 % of the
 *   1-point one's on the tests' meshes, so the same steps serve. Lumped mass
 *   (rho V / 8 per node, rho = RVE mass / RVE volume of eq 26, times
 *   --mass-scale), explicit central differences (eqs 51-52; gk_explicit.h),
 *   updated Lagrangian with the corotational update of eqs 60-62
 *   (gk_explicit.h: F at mid-step, polar decomposition, the strain increment
 *   rotated in and the stress out; what the missing Appendix B leaves open is
 *   written there). Stress tension-positive inside, compression-positive in
 *   every output.
 *   Nonlocal (eq 58, Appendix A; gk_nonlocal.h): the whole strain increment at
 *   every Gauss point is replaced by its bell-weighted average over the
 *   points within R (--nonlocal R, or off), normalised per point without
 *   volumes as the paper writes it, with every periodic image, truncated at
 *   free boundaries. All local increments of a step are known before any
 *   DEM run, so the average uses current increments only (the paper's
 *   staggered form takes a neighbour's previous one when it must).
 *   Stability (not in the paper): averaging the strain scales a strain wave's
 *   stiffness by the operator's symbol S(k) (gk_nonlocal.h), which is
 *   negative for some waves once the mesh spacing falls below R / sqrt 2;
 *   the driver prints min S for its mesh and warns when it is negative.
 *   --nonlocal-mix M averages M <eps> + (1 - M) eps instead (symbol
 *   1 - M + M S), which is positive for M < 1 / (1 - min S).
 *   One step: forces -> velocities and displacements (eqs 22-23) ->
 *   corotational increments -> nonlocal average -> rotate in (eq 60) -> all
 *   RVEs (threads) -> rotate out (eq 62) -> internal forces.
 *
 * TIME STEPS (eqs 63-66). K and G of the RVE are measured first (Table II:
 *   isotropic compression and simple shear of the RVE alone, ten increments
 *   of 1e-5, relaxed to I_uf < 1e-3: secant moduli at 1e-4). The coarse step
 *   is --dt-safety 0.5 x eq 65 at the highest frequency of the mesh, bounded
 *   by the element frequencies with that elastic stiffness
 *   (gk_explicit_elem_omega), or --dt (refused above eq 65). The DEM's
 *   highest frequency (eq 64 over the RVE's contacts) gives the step ratio
 *   of eq 66, which is printed: the DEM needs ~20 of its critical steps per
 *   coarse step to keep physical time; it runs instead as the dynamic
 *   relaxation the paper describes (sec 2.3.4: its masses are not
 *   physical), with the step counts above.
 *
 * DAMPING AND LOADING OF THE MACRO SCALE (the paper's mass scaling and
 *   dynamic relaxation come without numbers). Mass-proportional damping
 *   alpha M (v - v_hom) (gk_explicit_step with alpha M v_hom added to the
 *   force), alpha = 2 --xi omega_1 (--xi 0.3; 0 in the wave test), omega_1 =
 *   (pi / 2) c / H the fundamental frequency of the specimen (c = sqrt(G /
 *   rho) in the shear tests, sqrt(E / rho) otherwise). v_hom is the
 *   homogeneous part of the velocity field (mean velocity and volume average
 *   of grad v): the damping acts on waves and transients and never resists
 *   a homogeneous deformation, which plain alpha M v does (at these rates a
 *   critically damped alpha M v adds a viscous stress of the order of the
 *   material's). A single element is homogeneous through and through; there
 *   v_hom keeps only the loading's own gradient, so the lateral (normal)
 *   motion is damped, which biases the lateral stress by alpha rho eps_rate
 *   W^2 / 2 (~0.5 % at the default 4000 steps). The specimen starts with
 *   the loading's homogeneous velocity field (u_x = V y / H, or u_y = -V y /
 *   H): a steady homogeneous deformation needs no acceleration, so the
 *   platen's start sends no wave (with a velocity ramp over the first 10 %
 *   of 4000 steps the simple shear's top row was overstressed by the start-up
 *   wave, rho c V ~ 3 x the strength, and localized there). Mass scaling does not make an explicit
 *   quasi-static run cheaper: the inertial stress rho c v of a platen speed v
 *   is unchanged when rho and dt are scaled together, so what counts is the
 *   number of steps (--steps).
 */
#ifndef NONLOCAL_MACRO_H
#define NONLOCAL_MACRO_H

#include "gk_explicit.h"
#include "gk_fem.h"
#include "gk_nonlocal.h"
#include "nonlocal_micro.h"

/* ------------------------------------------------------------ the macro side */
#define NCOL 17 /* columns of the CSV rows kept in memory (and in the checkpoint) */
static const char *csv_head =
    "step,time,strain,stress,stress_2,p,q,porosity,Z,u_probe,dem_steps_mean,dem_steps_max,"
    "dem_capped,kinetic,work_int,hourglass,seconds";

typedef struct pface {
    int n[4];
    int axis, sign; /* outward normal along +-axis (the current normal is used, oriented this way) */
} pface;

typedef struct model {
    const opts *o;
    micro *mi;
    int test, nn, nd, ne, nr;
    int ngp, np;      /* Gauss points (and RVEs) per element (--gauss 1|8) and in all: point p is element
                         p / ngp's Gauss point p % ngp                                                   */
    double L[3];      /* specimen size [m]                                      */
    gk_mesh ref, cur; /* reference and current configurations                   */
    gk_quad q1;       /* one Gauss point (the masses, and the rule when ngp = 1)  */
    gk_quad q;        /* the rule of the points: 1 or 2 x 2 x 2                  */
    gk_dofmap dm;     /* periodic ties (identity without)                       */
    double *u, *v, *fint, *fext, *f, *mass, *vhom; /* nd                                   */
    double *ur, *vr, *fr, *mr; /* nr: the independent dofs                               */
    unsigned char *fix, *fixr; /* prescribed velocity                                    */
    double *vpre;              /* nd: the prescribed velocity of this step               */
    double *dNdX, *Vp;         /* per point: reference gradients (24), volume w det J      */
    double *V0, *hg;           /* per element: volume, hourglass stiffness (0 for ngp 8)    */
    double *fe;                /* 24 per element: B^T sigma V of the last internal_force  */
    double *wint, *ehg;        /* per element: the stress work since step 0 and the hourglass energy [J] */
    double *Hn, *H, *deps, *depsnl, *dH, *Rh, *R1, *sigR, *sig; /* 9 per point              */
    gk_twoscale_field *fld;                                     /* per point                */
    double *He, *sige;      /* 9 per element: the means of its points' H and sigma (elem_means) */
    gk_twoscale_field *fle; /* per element: the means of its points' fields (elem_fields)    */
    gk_nonlocal nl;
    double sym_raw, sym_k[3]; /* min of the averaging's symbol on this grid as built (gk_nonlocal.h; after
                                 --nonlocal-mix M: 1 - M + M sym_raw) and k h where reached */
    int sym_dim;
    gk_twoscale ts;
    int *top, ntop, *bot, nbot, *right, nright; /* node lists                                */
    pface *pf;
    int npf;
    double omega_c, omega1, alpha, dt, vload, time, kin;
    long step, nsteps;
    int probe; /* wave: element 9 (1-based)                              */
    /* history */
    double *rows;
    long nrow, caprow;
    /* simple shear: per-row profiles */
    double *gam_peak, *prof12, *prof_end; /* ny each; prof: gamma then porosity (2 ny)         */
    int have12;
    double peak;
    /* wave: arrival time per element (multiscale), -1 before */
    double *arrival;
    double t0;
    long dem_total;
} model;

static int node_id(const model *md, int i, int j, int k) {
    return (k * (md->o->mesh[1] + 1) + j) * (md->o->mesh[0] + 1) + i;
}

/* the points' reference gradients and volumes (w det J), the elements'
 * volumes; with one point, the Flanagan-Belytschko hourglass stiffness
 * k = kappa (lambda + 2 mu) V sum_a |grad N_a|^2 / 192 (their stiffness form
 * with gk_fem_hex8_hourglass's unscaled gamma vectors); the fully integrated
 * element (8 points) has no hourglass modes and k = 0 */
static int macro_geometry(model *md) {
    int e, a, g;
    double lam2mu = md->mi->K + 4.0 / 3.0 * md->mi->G;
    gk_err err;
    for (e = 0; e < md->ne; ++e) {
        double s = 0.0;
        md->V0[e] = 0.0;
        for (g = 0; g < md->ngp; ++g) {
            int p = md->ngp * e + g;
            double det;
            if (gk_fem_jacobian(&md->ref, e, md->q.xi[g], NULL, md->dNdX + 24 * p, &det, &err))
                return fprintf(stderr, "femdem_nonlocal: %s\n", err.msg), 1;
            md->Vp[p] = md->q.w[g] * det;
            md->V0[e] += md->Vp[p];
        }
        if (md->ngp == 1) {
            for (a = 0; a < 24; ++a) s += md->dNdX[24 * e + a] * md->dNdX[24 * e + a];
            md->hg[e] = md->o->kappa * lam2mu * md->V0[e] * s / 192.0;
        }
    }
    return 0;
}

/* H = du/dX at point p (reference gradients) */
static void point_grad(const model *md, const double *u, int p, double H[9]) {
    const int *c = md->ref.conn + 8 * (p / md->ngp);
    const double *g = md->dNdX + 24 * p;
    int a, i, j;
    gk_m3_zero(H);
    for (a = 0; a < 8; ++a)
        for (i = 0; i < 3; ++i)
            for (j = 0; j < 3; ++j) H[3 * i + j] += u[3 * c[a] + i] * g[3 * a + j];
}

/* He and sige: each element's mean of its points' H and sigma (exactly the
 * point's own values with one point; equal weights, the points' volumes on
 * the meshes of the tests being equal) */
static void elem_means(model *md) {
    int e, g, i, n = md->ngp;
    for (e = 0; e < md->ne; ++e)
        for (i = 0; i < 9; ++i) {
            double h = 0.0, sg = 0.0;
            for (g = 0; g < n; ++g) h += md->H[9 * (n * e + g) + i], sg += md->sig[9 * (n * e + g) + i];
            md->He[9 * e + i] = h / n, md->sige[9 * e + i] = sg / n;
        }
}

/* fld (per point) from the RVEs, and fle: each element's mean of the fields
 * the outputs use (the others left 0) */
static void elem_fields(model *md) {
    int e, g, n = md->ngp;
    gk_twoscale_fields(&md->ts, md->fld);
    memset(md->fle, 0, sizeof(gk_twoscale_field) * md->ne);
    for (e = 0; e < md->ne; ++e) {
        gk_twoscale_field *m = md->fle + e;
        for (g = 0; g < n; ++g) {
            const gk_twoscale_field *f = md->fld + n * e + g;
            m->p += f->p / n, m->q += f->q / n, m->void_ratio += f->void_ratio / n;
            m->coordination += f->coordination / n, m->rotation += f->rotation / n;
            m->dem_steps += f->dem_steps / n;
        }
    }
}

/* the highest frequency of the mesh (element bound, the RVE's elastic K and G) */
static double macro_omega(model *md) {
    double D[8 * 81], Ke[576], me[24], wmax = 0.0, E, nu, K = md->mi->K, G = md->mi->G;
    int e, a, b;
    gk_err err;
    E = 9.0 * K * G / (3.0 * K + G);
    nu = (3.0 * K - 2.0 * G) / (2.0 * (3.0 * K + G));
    gk_fem_elastic_tangent(3, E, nu, D);
    for (a = 1; a < md->ngp; ++a) memcpy(D + 81 * a, D, sizeof(double) * 81); /* one per Gauss point */
    for (e = 0; e < md->ne; ++e) {
        double xe[24], ue[24], fh[24];
        const int *c = md->ref.conn + 8 * e;
        if (gk_fem_elem_stiffness(&md->ref, e, &md->q, D, Ke, &err)) return -1.0;
        for (a = 0; a < 8; ++a)
            for (b = 0; b < 3; ++b) xe[3 * a + b] = md->ref.x[3 * c[a] + b];
        for (b = 0; b < 24; ++b) { /* hourglass columns by unit displacements */
            memset(ue, 0, sizeof ue);
            ue[b] = 1.0;
            gk_fem_hex8_hourglass(xe, ue, md->hg[e], fh);
            for (a = 0; a < 24; ++a) Ke[24 * a + b] -= fh[a];
        }
        for (a = 0; a < 24; ++a) me[a] = md->mi->rho * md->o->mass_scale * md->V0[e] / 8.0;
        {
            double w = gk_explicit_elem_omega(24, Ke, me);
            if (w > wmax) wmax = w;
        }
    }
    return wmax;
}

static void add_pface(model *md, const int *nodes, int axis, int sign) {
    pface *p = md->pf + md->npf++;
    memcpy(p->n, nodes, sizeof p->n);
    p->axis = axis, p->sign = sign;
}

/* periodic ties along the axes in the mask (the hi face's nodes follow the
 * lo face's, every component) and, for the shear tests, a rigid top platen
 * (every top node's u_y follows one top node's: the platen carries the
 * normal pressure and cannot tilt, as in a simple-shear apparatus; without
 * it a single 1-point element shears by rotating its top face) */
static int build_ties(model *md, unsigned axes, int platen) {
    int nn = md->nn, ax, a, k, nt = 0, np, *ps, *pm, *tied, *sl, *ms;
    gk_err err;
    gk_result r = GK_OK;
    ps = (int *)xcalloc((size_t)nn, sizeof(int)), pm = (int *)xcalloc((size_t)nn, sizeof(int));
    tied = (int *)xcalloc((size_t)nn, sizeof(int));
    sl = (int *)xcalloc((size_t)3 * nn, sizeof(int)), ms = (int *)xcalloc((size_t)3 * nn, sizeof(int));
    for (ax = 0; ax < 3 && !r; ++ax) {
        if (!(axes & (1u << ax))) continue;
        r = gk_mesh_periodic_pairs(&md->ref, ax, 0.0, md->L[ax], 1e-9, ps, pm, &np, &err);
        for (k = 0; k < np && !r; ++k) {
            if (tied[ps[k]])
                continue; /* an edge node already tied along an earlier axis: the chain does the rest */
            tied[ps[k]] = 1;
            for (a = 0; a < 3; ++a, ++nt) sl[nt] = 3 * ps[k] + a, ms[nt] = 3 * pm[k] + a;
        }
    }
    if (platen && !r) {
        int t0 = node_id(md, 0, md->o->mesh[1], 0);
        for (k = 0; k < md->ntop; ++k) {
            int n = md->top[k];
            if (n == t0 || tied[n]) continue;
            sl[nt] = 3 * n + 1, ms[nt++] = 3 * t0 + 1;
        }
    }
    if (!r) r = gk_dofmap_ties(&md->dm, md->nd, nt, sl, ms, NULL, NULL, &err);
    free(ps), free(pm), free(tied), free(sl), free(ms);
    if (r) return fprintf(stderr, "femdem_nonlocal: %s\n", err.msg), 1;
    return 0;
}

/* mesh, boundary conditions, masses, ties for the test */
static int macro_setup(model *md) {
    const opts *o = md->o;
    int t = o->test, nx = o->mesh[0], ny = o->mesh[1], nz = o->mesh[2], i, j, k, a, e;
    double orig[3] = {0, 0, 0}, *mn;
    unsigned axes = 0;
    gk_err err;
    gk_result r;
    md->test = t;
    if (t == T_EBIAX || t == T_ESHEAR) md->L[0] = md->L[1] = md->L[2] = 0.01;
    if (t == T_WAVE) md->L[0] = 0.1, md->L[1] = 0.01, md->L[2] = 0.01;
    if (t == T_SSHEAR) md->L[0] = 0.0506, md->L[1] = 0.118, md->L[2] = 0.0127;
    if (t == T_BIAX) md->L[0] = 0.04, md->L[1] = 0.08, md->L[2] = 0.005;
    r = gk_mesh_structured(&md->ref, GK_HEX8, o->mesh, orig, md->L, NULL, &err);
    if (!r) r = gk_mesh_structured(&md->cur, GK_HEX8, o->mesh, orig, md->L, NULL, &err);
    if (!r) r = gk_quad_rule(&md->q1, GK_HEX8, 1, &err);
    if (!r) r = gk_quad_rule(&md->q, GK_HEX8, o->gauss == 8 ? 2 : 1, &err);
    if (r) return fprintf(stderr, "femdem_nonlocal: %s\n", err.msg), 1;
    md->nn = md->ref.nnode, md->nd = 3 * md->nn, md->ne = md->ref.nelem;
    md->ngp = md->q.n, md->np = md->ne * md->ngp;
#define ALLOC(p, n) p = xcalloc((size_t)(n), sizeof *(p))
    ALLOC(md->u, md->nd), ALLOC(md->v, md->nd), ALLOC(md->fint, md->nd), ALLOC(md->fext, md->nd);
    ALLOC(md->f, md->nd), ALLOC(md->mass, md->nd), ALLOC(md->vhom, md->nd), ALLOC(md->fix, md->nd);
    ALLOC(md->vpre, md->nd), ALLOC(md->dNdX, 24 * md->np), ALLOC(md->Vp, md->np), ALLOC(md->V0, md->ne);
    ALLOC(md->hg, md->ne), ALLOC(md->Hn, 9 * md->np), ALLOC(md->H, 9 * md->np), ALLOC(md->deps, 9 * md->np),
        ALLOC(md->depsnl, 9 * md->np);
    ALLOC(md->dH, 9 * md->np), ALLOC(md->Rh, 9 * md->np), ALLOC(md->R1, 9 * md->np),
        ALLOC(md->sigR, 9 * md->np);
    ALLOC(md->sig, 9 * md->np), ALLOC(md->fld, md->np), ALLOC(md->He, 9 * md->ne),
        ALLOC(md->sige, 9 * md->ne);
    ALLOC(md->fle, md->ne), ALLOC(md->top, md->nn), ALLOC(md->bot, md->nn);
    ALLOC(md->right, md->nn), ALLOC(md->pf, 2 * (nx * nz + ny * nz + nx * ny)), ALLOC(md->arrival, md->ne);
    ALLOC(md->gam_peak, ny), ALLOC(md->prof12, 2 * ny), ALLOC(md->prof_end, 2 * ny);
    ALLOC(md->fe, 24 * md->ne), ALLOC(md->wint, md->ne), ALLOC(md->ehg, md->ne);
    if (macro_geometry(md)) return 1;
    /* lumped masses: rho V / 8 per node (HRZ of the 1-point hexahedron) */
    ALLOC(mn, md->nn);
    if (gk_fem_lumped_mass(&md->ref, &md->q1, md->mi->rho * o->mass_scale, mn, &err))
        return fprintf(stderr, "femdem_nonlocal: %s\n", err.msg), 1;
    for (a = 0; a < md->nn; ++a)
        for (k = 0; k < 3; ++k) md->mass[3 * a + k] = mn[a];
    free(mn);
    /* node sets */
    for (k = 0; k <= nz; ++k)
        for (j = 0; j <= ny; ++j)
            for (i = 0; i <= nx; ++i) {
                int n = node_id(md, i, j, k);
                if (j == ny) md->top[md->ntop++] = n;
                if (j == 0) md->bot[md->nbot++] = n;
                if (i == nx) md->right[md->nright++] = n;
            }
    /* prescribed dofs (velocities set per step in loading()) and pressure faces */
    for (a = 0; a < md->nn; ++a) {
        const double *x = md->ref.x + 3 * a;
        int is_top = fabs(x[1] - md->L[1]) < 1e-12, is_bot = fabs(x[1]) < 1e-12;
        int is_left = fabs(x[0]) < 1e-12, is_right = fabs(x[0] - md->L[0]) < 1e-12;
        switch (t) {
        case T_EBIAX:
            if (is_bot || is_top) md->fix[3 * a + 1] = 1;
            if (is_left) md->fix[3 * a] = 1;
            md->fix[3 * a + 2] = 1; /* plane strain */
            break;
        case T_ESHEAR:
            if (is_bot) md->fix[3 * a] = md->fix[3 * a + 1] = 1;
            if (is_top) md->fix[3 * a] = 1;
            md->fix[3 * a + 2] = 1;
            break;
        case T_WAVE:
            if (is_left || is_right) md->fix[3 * a] = md->fix[3 * a + 1] = md->fix[3 * a + 2] = 1;
            break;
        case T_SSHEAR:
            if (is_bot) md->fix[3 * a] = md->fix[3 * a + 1] = md->fix[3 * a + 2] = 1;
            if (is_top) md->fix[3 * a] = 1;
            break;
        case T_BIAX:
            if (is_bot || is_top) md->fix[3 * a + 1] = 1;
            if (is_bot && x[0] <= 0.5 * md->L[0] + 1e-12) md->fix[3 * a] = 1; /* rough left half */
            md->fix[3 * a + 2] = 1;
            break;
        }
    }
    {
        int *fc = (int *)xcalloc((size_t)md->ne * 24, sizeof(int)), nf, nfn, f;
        if (t == T_EBIAX || t == T_BIAX) {
            nf = gk_mesh_faces_on_plane(&md->ref, 0, md->L[0], 1e-12, fc, &nfn);
            for (f = 0; f < nf; ++f) add_pface(md, fc + 4 * f, 0, 1);
        }
        if (t == T_BIAX) {
            nf = gk_mesh_faces_on_plane(&md->ref, 0, 0.0, 1e-12, fc, &nfn);
            for (f = 0; f < nf; ++f) add_pface(md, fc + 4 * f, 0, -1);
        }
        if (t == T_ESHEAR || t == T_SSHEAR) {
            nf = gk_mesh_faces_on_plane(&md->ref, 1, md->L[1], 1e-12, fc, &nfn);
            for (f = 0; f < nf; ++f) add_pface(md, fc + 4 * f, 1, 1);
        }
        free(fc);
    }
    if (t == T_WAVE) axes = 2u | 4u;
    if (t == T_SSHEAR) axes = 1u | 4u;
    if (build_ties(md, axes, t == T_ESHEAR || t == T_SSHEAR)) return 1;
    md->nr = md->dm.nred;
    ALLOC(md->ur, md->nr), ALLOC(md->vr, md->nr), ALLOC(md->fr, md->nr), ALLOC(md->mr, md->nr),
        ALLOC(md->fixr, md->nr);
    if (gk_dofmap_restrict(&md->dm, NULL, md->mass, md->mr, &err))
        return fprintf(stderr, "femdem_nonlocal: the tied mass: %s\n", err.msg), 1;
    for (a = 0; a < md->nd; ++a)
        if (md->fix[a]) md->fixr[md->dm.red[a]] = 1;
    /* nonlocal neighbourhoods of the Gauss points (reference configuration) */
    {
        double *xg = (double *)xcalloc((size_t)md->np * 3, sizeof(double)), per[3] = {0, 0, 0};
        for (e = 0; e < md->np; ++e) gk_mesh_point(&md->ref, e / md->ngp, md->q.xi[e % md->ngp], xg + 3 * e);
        for (k = 0; k < 3; ++k)
            if (axes & (1u << k)) per[k] = md->L[k];
        r = gk_nonlocal_build(&md->nl, 3, md->np, xg, o->R, per, NULL, &err);
        free(xg);
        if (!r) r = gk_nonlocal_mix(&md->nl, o->mix, &err);
        if (r) return fprintf(stderr, "femdem_nonlocal: %s\n", err.msg), 1;
        /* stability: the symbol of the (mixed) average on the mesh's regular grid, over the
         * axes that have neighbours (more than one element, or periodic) */
        {
            double h[3], s = 1.0, kk[3] = {0, 0, 0};
            int dim = 0;
            for (k = 0; k < 3; ++k)
                if (o->mesh[k] > 1 || per[k] > 0.0) h[dim++] = md->L[k] / o->mesh[k];
            if (dim && o->R > 0.0 && gk_nonlocal_grid_symbol(dim, h, o->R, &s, kk, &err))
                return fprintf(stderr, "femdem_nonlocal: %s\n", err.msg), 1;
            md->sym_raw = s;
            md->sym_dim = dim;
            for (k = 0; k < 3; ++k) md->sym_k[k] = kk[k] * (k < dim ? h[k] : 0.0);
        }
    }
    md->probe = t == T_WAVE ? (md->ne >= 9 ? 8 : md->ne - 1) : 0;
    for (e = 0; e < md->ne; ++e) md->arrival[e] = -1.0;
#undef ALLOC
    return 0;
}

/* the prescribed velocities of step n (at its mid-point) */
static void loading(model *md, long n) {
    int a, t = md->test;
    double V = md->vload;
    for (a = 0; a < md->nd; ++a) md->vpre[a] = 0.0;
    for (a = 0; a < md->nn; ++a) {
        const double *x = md->ref.x + 3 * a;
        int is_top = fabs(x[1] - md->L[1]) < 1e-12, is_right = fabs(x[0] - md->L[0]) < 1e-12;
        if ((t == T_EBIAX || t == T_BIAX) && is_top) md->vpre[3 * a + 1] = -V;
        if ((t == T_ESHEAR || t == T_SSHEAR) && is_top) md->vpre[3 * a] = V;
        if (t == T_WAVE && is_right) { /* u_y = a sin(2 pi f t) exactly at every step end */
            double w = 2.0 * GK_PI * md->o->frequency;
            md->vpre[3 * a + 1] =
                md->o->amplitude * (sin(w * (n + 1) * md->dt) - sin(w * n * md->dt)) / md->dt;
        }
    }
}

/* f_ext: the pressure on the current faces (their current normals) */
static void external_force(model *md) {
    int k, a;
    for (a = 0; a < md->nd; ++a) md->fext[a] = 0.0;
    for (k = 0; k < md->npf; ++k) {
        const pface *p = md->pf + k;
        const double *x0 = md->cur.x + 3 * p->n[0], *x1 = md->cur.x + 3 * p->n[1],
                     *x2 = md->cur.x + 3 * p->n[2], *x3 = md->cur.x + 3 * p->n[3];
        double d1[3], d2[3], nrm[3], len, t[3];
        for (a = 0; a < 3; ++a) d1[a] = x2[a] - x0[a], d2[a] = x3[a] - x1[a];
        gk_v3_cross(d1, d2, nrm);
        len = sqrt(gk_v3_dot(nrm, nrm));
        if (nrm[p->axis] * p->sign < 0) len = -len;
        for (a = 0; a < 3; ++a) t[a] = -md->o->pressure * nrm[a] / len;
        gk_fem_face_load(&md->cur, 4, p->n, t, md->fext, NULL);
    }
}

/* element e's hourglass forces f (24) from the displacement field u with
 * stiffness k (gk_fem_hex8_hourglass on the reference geometry); returns
 * u_e . f = -k sum (gamma . u)^2 */
static double elem_hourglass(const model *md, const double *u, int e, double k, double *f) {
    double xe[24], ue[24], uf = 0.0;
    const int *c = md->ref.conn + 8 * e;
    int a, i;
    for (a = 0; a < 8; ++a)
        for (i = 0; i < 3; ++i) xe[3 * a + i] = md->ref.x[3 * c[a] + i], ue[3 * a + i] = u[3 * c[a] + i];
    gk_fem_hex8_hourglass(xe, ue, k, f);
    for (a = 0; a < 24; ++a) uf += ue[a] * f[a];
    return uf;
}

/* f_int = sum_e B^T sigma V on the current configuration + hourglass forces
 * (stiffness form on the reference geometry and the total displacement:
 * zero for every rigid motion and homogeneous deformation). Keeps each
 * element's B^T sigma V for the work (work_half_step) and its hourglass energy,
 * the stiffness form's 1/2 k sum (gamma . u)^2 = -1/2 u . f_hg */
static int internal_force(model *md) {
    int e, a, k;
    gk_err err;
    for (a = 0; a < md->nd; ++a) md->fint[a] = 0.0;
    for (e = 0; e < md->ne; ++e) {
        double *fe = md->fe + 24 * e, fh[24];
        const int *c = md->ref.conn + 8 * e;
        if (gk_fem_elem_force(&md->cur, e, &md->q, md->sig + 9 * md->ngp * e, fe, &err))
            return fprintf(stderr, "femdem_nonlocal: step %ld: %s\n", md->step, err.msg), 1;
        md->ehg[e] = -0.5 * elem_hourglass(md, md->u, e, md->hg[e], fh);
        for (a = 0; a < 8; ++a)
            for (k = 0; k < 3; ++k) md->fint[3 * c[a] + k] += fe[3 * a + k] - fh[3 * a + k];
    }
    return 0;
}

/* the element's hourglass deformation as a strain: sqrt(sum_alpha,i (gamma^alpha .
 * u_i)^2), what the control penalises (gamma: gk_fem_hex8_hourglass's vectors, the
 * eight nodal values +-1 of each mode on a box), over 8 (the modes' rms nodal
 * amplitude) over half the element's size V0^(1/3) / 2. Independent of kappa,
 * unlike the energy; compare it with eps_q. */
static double hourglass_strain(const model *md, int e) {
    double fh[24], s = -elem_hourglass(md, md->u, e, 1.0, fh);
    return sqrt(s > 0.0 ? s : 0.0) / 8.0 / (0.5 * cbrt(md->V0[e]));
}

/* half of the step's stress work per element, B^T sigma V . v dt / 2 with
 * the step's (mid-step) velocity: called with the forces before and after
 * the step it is the trapezoidal rule for int sigma : d eps V, the work
 * the RVEs were made to do (against it the hourglass energy is what the
 * control stores; how much the element deforms in its hourglass modes is
 * hourglass_strain) */
static void work_half_step(model *md) {
    int e, a, k;
    for (e = 0; e < md->ne; ++e) {
        const int *c = md->ref.conn + 8 * e;
        const double *fe = md->fe + 24 * e;
        double w = 0.0;
        for (a = 0; a < 8; ++a)
            for (k = 0; k < 3; ++k) w += fe[3 * a + k] * md->v[3 * c[a] + k];
        md->wint[e] += 0.5 * md->dt * w;
    }
}

/* the homogeneous part of the velocity field: mean velocity plus the volume
 * average of grad v (reference gradients) about the centre of mass. A single
 * element is homogeneous through and through (every mode would escape the
 * damping), so there only the loading's own gradient (the platen speed over
 * the height) is kept and the lateral or normal motion is damped; for a 10 mm
 * element at the default rates that resists the Poisson expansion with
 * alpha rho eps_rate W^2 / 2 ~ 60 Pa. */
static void velocity_hom(model *md) {
    double vb[3] = {0, 0, 0}, xb[3] = {0, 0, 0}, M = 0.0, Lb[9], Vt = 0.0;
    int a, e, i, j;
    gk_m3_zero(Lb);
    for (a = 0; a < md->nn; ++a) {
        double m = md->mass[3 * a];
        M += m;
        for (i = 0; i < 3; ++i) vb[i] += m * md->v[3 * a + i], xb[i] += m * md->cur.x[3 * a + i];
    }
    for (i = 0; i < 3; ++i) vb[i] /= M, xb[i] /= M;
    for (e = 0; e < md->np; ++e) {
        double G[9];
        point_grad(md, md->v, e, G);
        for (i = 0; i < 9; ++i) Lb[i] += md->Vp[e] * G[i];
        Vt += md->Vp[e];
    }
    for (i = 0; i < 9; ++i) Lb[i] /= Vt;
    if (md->ne == 1) { /* the loading's gradient only (see above) */
        int k = md->test == T_EBIAX ? 4 : 1;
        double keep = Lb[k];
        gk_m3_zero(Lb);
        Lb[k] = keep;
    }
    for (a = 0; a < md->nn; ++a)
        for (i = 0; i < 3; ++i) {
            double s = vb[i];
            for (j = 0; j < 3; ++j) s += Lb[3 * i + j] * (md->cur.x[3 * a + j] - xb[j]);
            md->vhom[3 * a + i] = s;
        }
}

/* one coarse step n -> n + 1 */
static int macro_step(model *md) {
    int a, e, k;
    gk_err err;
    gk_result r;
    loading(md, md->step);
    if (md->alpha > 0.0) velocity_hom(md);
    for (a = 0; a < md->nd; ++a) /* alpha M (v - v_hom): the v_hom part enters as a force */
        md->f[a] =
            md->fext[a] - md->fint[a] + (md->alpha > 0.0 ? md->alpha * md->mass[a] * md->vhom[a] : 0.0);
    if (gk_dofmap_restrict(&md->dm, NULL, md->f, md->fr, &err))
        return fprintf(stderr, "femdem_nonlocal: step %ld: %s\n", md->step, err.msg), 1;
    for (a = 0; a < md->nd; ++a)
        if (md->fix[a]) md->vr[md->dm.red[a]] = md->vpre[a];
    r = gk_explicit_step(md->nr, md->mr, md->fixr, md->fr, md->alpha, md->dt, md->vr, md->ur,
                         &err); /* eqs 22-23 */
    if (r) return fprintf(stderr, "femdem_nonlocal: step %ld: %s\n", md->step, err.msg), 1;
    gk_dofmap_expand(&md->dm, md->ur, 0, md->u);
    gk_dofmap_expand(&md->dm, md->vr, 0, md->v);
    for (a = 0; a < md->nd; ++a) md->cur.x[a] = md->ref.x[a] + md->u[a];
    work_half_step(md); /* with the forces of the start of the step */
    /* corotational increments (eqs 60-61) at every point */
    for (e = 0; e < md->np; ++e) {
        point_grad(md, md->u, e, md->H + 9 * e);
        if (gk_corot_increment(3, md->Hn + 9 * e, md->H + 9 * e, md->deps + 9 * e, md->Rh + 9 * e,
                               md->R1 + 9 * e, &err))
            return fprintf(stderr, "femdem_nonlocal: step %ld, element %d: %s\n", md->step, e / md->ngp,
                           err.msg),
                   1;
    }
    gk_nonlocal_apply(&md->nl, 9, md->deps, md->depsnl); /* eq 58 (R = 0: each point alone) */
    for (e = 0; e < md->np; ++e) gk_corot_rotate_in(md->Rh + 9 * e, md->depsnl + 9 * e, md->dH + 9 * e);
    r = gk_twoscale_run(&md->ts, md->dH, NULL, md->sigR, NULL);
    if (r) {
        const gk_twoscale_point *pt = gk_twoscale_points(&md->ts);
        fprintf(stderr, "femdem_nonlocal: step %ld: %s\n", md->step, gk_twoscale_error(&md->ts));
        for (e = 0; e < md->np; ++e)
            if (pt[e].code) {
                if (md->ngp == 1)
                    fprintf(stderr, "  Gauss point %d: %s\n", e, gk_twoscale_point_error(&md->ts, e));
                else
                    fprintf(stderr, "  Gauss point %d (element %d): %s\n", e, e / md->ngp,
                            gk_twoscale_point_error(&md->ts, e));
            }
        return 3;
    }
    if (gk_twoscale_accept(&md->ts))
        return fprintf(stderr, "femdem_nonlocal: %s\n", gk_twoscale_error(&md->ts)), 1;
    {
        const gk_twoscale_point *pt = gk_twoscale_points(&md->ts);
        for (e = 0; e < md->np; ++e) md->dem_total += pt[e].work;
    }
    for (e = 0; e < md->np; ++e)
        gk_corot_rotate_out(md->R1 + 9 * e, md->sigR + 9 * e, md->sig + 9 * e); /* eq 62 */
    memcpy(md->Hn, md->H, sizeof(double) * 9 * md->np);
    elem_means(md);
    ++md->step;
    md->time += md->dt;
    external_force(md);
    if (internal_force(md)) return 1;
    work_half_step(md); /* and of its end */
    md->kin = gk_explicit_kinetic_energy(md->nd, md->mass, NULL, md->v);
    (void)k;
    return 0;
}

/* ------------------------------------------------------------ measurements */
/* strain, stress, stress_2 of the test (compression-positive for the biaxial
 * tests; shear strain and stress for the shear tests and the wave probe) */
static void measure(model *md, double *strain, double *stress, double *stress2, double *uprobe) {
    int t = md->test, a, e;
    double s = 0.0, area = 0.0, lat = 0.0;
    *uprobe = 0.0;
    for (e = 0; e < md->np; ++e) lat += md->sig[9 * e + (t == T_ESHEAR || t == T_SSHEAR ? 4 : 0)];
    lat /= md->np;
    if (t == T_EBIAX || t == T_BIAX) {
        for (a = 0; a < md->ntop; ++a) s += md->fint[3 * md->top[a] + 1];
        for (e = 0; e < md->ne; ++e) /* the current area of the top face: nodes 3, 2, 6, 7 of the top row */
            if ((e / md->o->mesh[0]) % md->o->mesh[1] == md->o->mesh[1] - 1) {
                const int *c = md->ref.conn + 8 * e;
                double dx = md->cur.x[3 * c[2]] - md->cur.x[3 * c[3]],
                       dz = md->cur.x[3 * c[7] + 2] - md->cur.x[3 * c[3] + 2];
                area += fabs(dx * dz);
            }
        *strain = -md->u[3 * md->top[0] + 1] / md->L[1];
        *stress = -s / area;
        *stress2 = -lat;
        *uprobe = md->u[3 * md->right[0]];
    } else if (t == T_ESHEAR || t == T_SSHEAR) {
        for (a = 0; a < md->nbot; ++a) s += md->fint[3 * md->bot[a]];
        *strain = md->u[3 * md->top[0]] / md->L[1];
        *stress = -s / (md->L[0] * md->L[2]);
        *stress2 = -lat;
        *uprobe = md->u[3 * md->top[0] + 1];
    } else if (t == T_WAVE) {
        const double *H = md->H + 9 * md->probe, *sg = md->sig + 9 * md->probe;
        *strain = H[1] + H[3];
        *stress = sg[1];
        *stress2 = -sg[0];
        *uprobe = md->u[3 * md->right[0] + 1];
    }
}

/* per-row means (simple shear): engineering shear strain of the macro
 * displacement gradient, porosity (of the element means: He, fle) */
static void row_profile(model *md, double *prof) {
    int nx = md->o->mesh[0], ny = md->o->mesh[1], nz = md->o->mesh[2], i, j, k;
    for (j = 0; j < ny; ++j) {
        double g = 0.0, n = 0.0;
        for (k = 0; k < nz; ++k)
            for (i = 0; i < nx; ++i) {
                int e = (k * ny + j) * nx + i;
                const double *H = md->He + 9 * e;
                g += H[1] + H[3];
                n += md->fle[e].void_ratio / (1.0 + md->fle[e].void_ratio);
            }
        prof[j] = g / (nx * nz);
        prof[ny + j] = n / (nx * nz);
    }
}

/* band centre and width from the rows' shear strain above the least row's (nonlocal_io.h) */
static void band(const model *md, const double *prof, double *centre, double *width, double *share) {
    int ny = md->o->mesh[1], j, jm = 0, j0, j1;
    double h = md->L[1] / ny, gmin = HUGE_VAL, sw = 0.0, sy = 0.0, sg = 0.0, sa = 0.0;
    for (j = 0; j < ny; ++j) {
        if (prof[j] < gmin) gmin = prof[j];
        if (prof[j] > prof[jm]) jm = j;
        sa += prof[j];
    }
    if (!(prof[jm] > gmin)) {
        *centre = *width = *share = NAN;
        return;
    }
    for (j0 = jm; j0 > 0 && prof[j0 - 1] - gmin >= 0.1 * (prof[jm] - gmin);) --j0;
    for (j1 = jm; j1 < ny - 1 && prof[j1 + 1] - gmin >= 0.1 * (prof[jm] - gmin);) ++j1;
    for (j = j0; j <= j1; ++j) sw += prof[j] - gmin, sy += (prof[j] - gmin) * (j + 0.5) * h, sg += prof[j];
    *centre = 1e3 * sy / sw;
    *width = 1e3 * sw * h / (prof[jm] - gmin);
    *share = sa > 0.0 ? sg / sa : NAN;
}

/* the paper's reading of its Fig 14a (nonlocal_io.h): the peak of a row
 * profile v at half its height above the rows' median, the profile linear
 * between the row centres and flat over the half rows at the faces; centre
 * = the midpoint of the two crossings, width = their distance [mm]; nan if
 * no row is above the median or a value is not finite */
static void peak_fwhm(const model *md, const double *v, double *centre, double *width) {
    int ny = md->o->mesh[1], i, j, jm = 0, a, b;
    double h = md->L[1] / ny, med, half, lo, hi, *s;
    *centre = *width = NAN;
    for (j = 0; j < ny; ++j)
        if (!isfinite(v[j])) return;
    s = (double *)xcalloc((size_t)ny, sizeof(double));
    for (j = 0; j < ny; ++j) {
        for (i = j; i > 0 && s[i - 1] > v[j]; --i) s[i] = s[i - 1]; /* insertion sort: ny is small */
        s[i] = v[j];
        if (v[j] > v[jm]) jm = j;
    }
    med = ny % 2 ? s[ny / 2] : 0.5 * (s[ny / 2 - 1] + s[ny / 2]);
    free(s);
    if (!(v[jm] > med)) return;
    half = med + 0.5 * (v[jm] - med);
    for (a = jm; a > 0 && v[a - 1] >= half;) --a;
    for (b = jm; b < ny - 1 && v[b + 1] >= half;) ++b;
    lo = a == 0 ? 0.0 : (a - 0.5 + (half - v[a - 1]) / (v[a] - v[a - 1])) * h;
    hi = b == ny - 1 ? md->L[1] : (b + 0.5 + (v[b] - half) / (v[b] - v[b + 1])) * h;
    *centre = 0.5e3 * (lo + hi);
    *width = 1e3 * (hi - lo);
}

static int record(model *md, double seconds) {
    double row[NCOL], strain, stress, s2, up, p = 0, q = 0, por = 0, Z = 0, dm = 0, dx = 0, capped = 0;
    const gk_twoscale_point *pt = gk_twoscale_points(&md->ts);
    int e, n = md->np;
    gk_twoscale_fields(&md->ts, md->fld);
    measure(md, &strain, &stress, &s2, &up);
    for (e = 0; e < n; ++e) {
        int w = md->step > 0 ? pt[e].n_deform + pt[e].n_relax : 0;
        p += md->fld[e].p, q += md->fld[e].q, por += md->fld[e].void_ratio / (1 + md->fld[e].void_ratio);
        Z += md->fld[e].coordination, dm += w;
        if (w > dx) dx = w;
        if (md->step > 0 && w >= md->o->dem_max) capped += 1;
    }
    if (md->test == T_WAVE) { /* the probe's own state (Fig 8) */
        const gk_twoscale_field *f = md->fld + md->probe;
        p = f->p * n, q = f->q * n, por = f->void_ratio / (1 + f->void_ratio) * n, Z = f->coordination * n;
    }
    row[0] = (double)md->step, row[1] = md->time, row[2] = strain, row[3] = stress, row[4] = s2;
    row[5] = p / n, row[6] = q / n, row[7] = por / n, row[8] = Z / n, row[9] = up, row[10] = dm / n,
    row[11] = dx;
    row[12] = capped, row[13] = md->kin, row[14] = 0.0, row[15] = 0.0, row[16] = seconds;
    for (e = 0; e < md->ne; ++e) row[14] += md->wint[e], row[15] += md->ehg[e]; /* per element */
    if (md->nrow == md->caprow) {
        double *nr;
        md->caprow = md->caprow ? 2 * md->caprow : 256;
        nr = (double *)realloc(md->rows, sizeof(double) * NCOL * md->caprow);
        if (!nr) return fprintf(stderr, "femdem_nonlocal: out of memory\n"), 1;
        md->rows = nr;
    }
    memcpy(md->rows + NCOL * md->nrow++, row, sizeof row);
    return 0;
}

/* the wave's front reaches an element when its shear strain first passes
 * F a / (element length), F = --front-threshold (both columns) */
static double wave_front_strain(const model *md) {
    return md->o->front * md->o->amplitude / (md->L[0] / md->o->mesh[0]);
}

/* per step bookkeeping that is not a CSV row: the peak profile and the 12 %
 * profile of the simple shear, the wave's arrival times */
static void track(model *md) {
    double strain, stress, s2, up;
    int e, ny = md->o->mesh[1];
    if (md->test == T_SSHEAR) {
        double *prof = (double *)xcalloc((size_t)2 * ny, sizeof(double));
        elem_fields(md);
        measure(md, &strain, &stress, &s2, &up);
        row_profile(md, prof);
        if (stress > md->peak) {
            md->peak = stress;
            memcpy(md->gam_peak, prof, sizeof(double) * ny);
        }
        if (!md->have12 && strain >= 0.12) {
            memcpy(md->prof12, prof, sizeof(double) * 2 * ny);
            md->have12 = 1;
        }
        free(prof);
    }
    if (md->test == T_WAVE) {
        double thr = wave_front_strain(md);
        for (e = 0; e < md->ne; ++e) {
            const double *H = md->He + 9 * e;
            if (md->arrival[e] < 0 && fabs(H[1] + H[3]) > thr) md->arrival[e] = md->time;
        }
    }
}

/* ------------------------------------------------------------ wave: the elastic column */
/* the same mesh, ties, masses, steps and excitation with a linear elastic
 * material (the RVE's K and G, initial stress -p I): arrival times by the
 * same threshold, so that the comparison with the multiscale column is
 * free of the mesh's dispersion */
static void wave_elastic(model *md, double *arr) {
    int e, a, k, i, j;
    long n;
    gk_err err;
    gk_result r;
    double lam = md->mi->K - 2.0 / 3.0 * md->mi->G, mu = md->mi->G;
    double thr = wave_front_strain(md);
    double *u = (double *)xcalloc((size_t)md->nd, sizeof(double)),
           *f = (double *)xcalloc((size_t)md->nd, sizeof(double));
    double *ur = (double *)xcalloc((size_t)md->nr, sizeof(double)),
           *vr = (double *)xcalloc((size_t)md->nr, sizeof(double));
    double *fr = (double *)xcalloc((size_t)md->nr, sizeof(double));
    for (e = 0; e < md->ne; ++e) arr[e] = -1.0;
    for (n = 0; n < md->o->steps; ++n) {
        for (a = 0; a < md->nd; ++a) f[a] = 0.0;
        for (e = 0; e < md->ne; ++e) {
            double H[9], s[9], fe[24], fh[24], tr;
            const int *c = md->ref.conn + 8 * e;
            point_grad(md, u, e, H); /* (one point per element) */
            tr = H[0] + H[4] + H[8];
            for (i = 0; i < 3; ++i)
                for (j = 0; j < 3; ++j)
                    s[3 * i + j] =
                        mu * (H[3 * i + j] + H[3 * j + i]) + (i == j ? lam * tr - md->o->pressure : 0.0);
            gk_fem_elem_force(&md->ref, e, &md->q1, s, fe, NULL);
            elem_hourglass(md, u, e, md->hg[e], fh);
            for (a = 0; a < 8; ++a)
                for (k = 0; k < 3; ++k) f[3 * c[a] + k] -= fe[3 * a + k] - fh[3 * a + k];
            if (arr[e] < 0 && fabs(H[1] + H[3]) > thr) arr[e] = n * md->dt;
        }
        loading(md, n);
        r = gk_dofmap_restrict(&md->dm, NULL, f, fr, &err);
        if (!r) {
            for (a = 0; a < md->nd; ++a)
                if (md->fix[a]) vr[md->dm.red[a]] = md->vpre[a];
            r = gk_explicit_step(md->nr, md->mr, md->fixr, fr, 0.0, md->dt, vr, ur, &err);
        }
        if (r) {
            /* a force that became NaN or infinite: no arrival is trusted (the speed is nan) */
            fprintf(stderr, "femdem_nonlocal: warning: the elastic column at step %ld: %s\n", n, err.msg);
            for (e = 0; e < md->ne; ++e) arr[e] = -1.0;
            break;
        }
        gk_dofmap_expand(&md->dm, ur, 0, u);
    }
    free(u), free(f), free(ur), free(vr), free(fr);
}

/* least-squares speed of the front: distance from the driven end against arrival */
static double front_speed(const model *md, const double *arr) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0, n = 0;
    int e;
    for (e = 0; e < md->ne - 1; ++e) { /* the driven element itself is left out */
        double d = md->L[0] - (e + 0.5) * md->L[0] / md->ne, t = arr[e];
        if (t < 0) continue;
        sx += t, sy += d, sxx += t * t, sxy += t * d, n += 1;
    }
    return n >= 2 ? (n * sxy - sx * sy) / (n * sxx - sx * sx) : NAN;
}

/* everything the model holds (each pointer NULL or allocated) */
static void model_free(model *md) {
    free(md->u), free(md->v), free(md->fint), free(md->fext), free(md->f), free(md->mass), free(md->vhom);
    free(md->ur), free(md->vr), free(md->fr), free(md->mr), free(md->fix), free(md->fixr), free(md->vpre);
    free(md->dNdX), free(md->Vp), free(md->He), free(md->sige), free(md->fle), free(md->V0), free(md->hg),
        free(md->Hn), free(md->H), free(md->deps), free(md->depsnl);
    free(md->dH), free(md->Rh), free(md->R1), free(md->sigR), free(md->sig), free(md->fld), free(md->top);
    free(md->bot), free(md->right), free(md->pf), free(md->rows), free(md->gam_peak), free(md->prof12);
    free(md->prof_end), free(md->arrival), free(md->fe), free(md->wint), free(md->ehg);
    gk_mesh_free(&md->ref), gk_mesh_free(&md->cur), gk_dofmap_free(&md->dm), gk_nonlocal_free(&md->nl);
    gk_twoscale_destroy(&md->ts);
}

/* the coarse step: eq 65 from the element bound with the RVE's K, G (or --dt, refused above it),
 * the platen speed, the macro damping; eq 66 printed with the run's parameters. 0, or the exit
 * status after a message */
static int macro_time_steps(model *md) {
    const opts *o = md->o;
    const micro *mi = md->mi;
    double smix;
    md->omega_c = macro_omega(md);
    if (!(md->omega_c > 0))
        return fprintf(stderr, "femdem_nonlocal: no stable step (element frequency %g)\n", md->omega_c), 1;
    md->dt = o->dt_safety * gk_explicit_dt_critical(md->omega_c, 0.0);
    if (o->dt > 0) {
        if (o->dt > gk_explicit_dt_critical(md->omega_c, 0.0))
            return fprintf(stderr,
                           "femdem_nonlocal: --dt %g is above the stable step %g of eq 65 for this mesh\n",
                           o->dt, gk_explicit_dt_critical(md->omega_c, 0.0)),
                   2;
        md->dt = o->dt;
    }
    md->nsteps = o->steps;
    md->vload = o->strain * md->L[1] / (md->nsteps * md->dt);
    {
        double rho = mi->rho * o->mass_scale, E = 9.0 * mi->K * mi->G / (3.0 * mi->K + mi->G);
        double c = (o->test == T_ESHEAR || o->test == T_SSHEAR) ? sqrt(mi->G / rho) : sqrt(E / rho);
        md->omega1 = 0.5 * GK_PI * c / md->L[1];
        md->alpha = 2.0 * o->xi * md->omega1;
    }
    smix = 1.0 - o->mix + o->mix * md->sym_raw; /* the symbol after --nonlocal-mix */
    printf("mesh %dx%dx%d (%d Gauss points), nonlocal %s (R %g m, mix %g, %d neighbour pairs, symbol min "
           "%.4f), dt %.4g s (eq 65: omega_max "
           "%.4g rad/s), eq 66: %.1f DEM critical steps per coarse step (omega_f %.4g rad/s, DEM dt %.3g s), "
           "damping alpha %.4g 1/s\nDEM runs: I_uf < %g (eq 57) within %d-%d steps, %ld coarse steps\n",
           o->mesh[0], o->mesh[1], o->mesh[2], md->np, o->R > 0 ? "on" : "off", o->R, o->mix,
           md->nl.start[md->np], smix, md->dt, md->omega_c,
           gk_explicit_substeps(md->omega_c, 0.0, mi->omega_f, 0.0), mi->omega_f, mi->dt_f, md->alpha, o->iuf,
           o->dem_min, o->dem_max, md->nsteps);
    fflush(stdout);
    if (smix < 0.0)
        fprintf(stderr,
                "femdem_nonlocal: warning: on this mesh the averaged strain has modes of negative stiffness "
                "(symbol min %.4f at k h = %.2f %.2f %.2f over the %d axes with neighbours; gk_nonlocal.h): "
                "they can grow whatever the material; --nonlocal-mix below %.3f keeps every mode stiff\n",
                smix, md->sym_k[0], md->sym_k[1], md->sym_k[2], md->sym_dim, 1.0 / (1.0 - md->sym_raw));
    return 0;
}

#endif /* NONLOCAL_MACRO_H */
