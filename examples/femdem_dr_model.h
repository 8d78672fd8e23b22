/* femdem_dr_model.h - the model of build/femdem_dr (examples/femdem_dr.c; examples, not library):
 * the Q4 mesh with a framed RVE per Gauss point, its setup, one dynamic-relaxation iteration and the
 * relaxation of one load step.
 *
 * THE MODEL (Liu, Bosco & Suiker 2018 sec 4.1). A 10 x 20 mm specimen,
 * total-Lagrange bilinear quadrilaterals (Q4, 2 x 2 Gauss points), bottom
 * edge supported vertically, lower-left node horizontally. Stage 1: the
 * pressure sigma0 on the left, right and top edges in --iso-steps equal
 * steps. Stage 2: the top edge (a smooth rigid platen: one vertical
 * displacement, free horizontally) moves down by d = eps h_ic in --steps
 * steps to --strain, h_ic the height after stage 1, the sides still at
 * sigma0. Pressures are follower loads on the current edges (Cauchy
 * tractions). 2D stresses are per unit thickness: N/m, printed as Pa with
 * a 1 m thick specimen.
 *
 * THE MACRO SOLVER (gk_explicit.h): every load step is relaxed by adaptive
 * dynamic relaxation (eqs 20-29): HRZ lumped masses of density
 * rho v_m = 2000 x 0.82 kg/m^2 (eq 24), C = alpha M with alpha = 2 xi omega
 * (eq 25), omega from the Rayleigh quotient of eq 26 (U and f_int taken
 * relative to the unloaded state, whose f_int is the packing's own small
 * stress), dt = gamma (2 / omega)(sqrt(xi^2 + 1) - xi) (eq 27, xi 1, gamma
 * 0.5), bounded by the element frequencies (gk_explicit_elem_omega with
 * twice the Taylor tangent of the packing: an upper bound, since the
 * particles only soften it), converged when E_kin / E_kin,max <= --dr-tol
 * (eq 28, 1e-3). Velocities start from 0 at every load step. A mesh's
 * displacements start from the uniform specimen's next state (--predictor
 * homogeneous, the default: run_fem's predict in femdem_dr.c), and such a
 * step, started near equilibrium, also ends once |f_ext - f_int| <= 2e-3
 * max|f| (--dr-force-stop: eq 28 alone does not end it); --predictor none
 * starts from the last step's with only the loads and the platen moved,
 * as the paper writes it, and eq 28 alone ends it. Every DR
 * iteration (Table 1) computes F = I + dU/dX at each Gauss point, runs its
 * RVE from its last state by dF (gk_twoscale.h with a gk_frame.h
 * procedure), takes P back and assembles f_int = int B^T P dV0
 * (gk_fem_elem_force on the reference mesh). No tangent anywhere.
 *
 * THE RVE (gk_frame.h, one per Gauss point): the 228-particle framed
 * packing examples/data/frame228_a002.txt (205 disks of the periodic cell,
 * radii uniform in 0.30-0.45 mm, cell 10.6 mm, 10 + 10 + 1 of them centred
 * on the cell boundary: P = 184 inner and Q = 44 boundary particles).
 *   --frame servo (default, the paper's): the boundary particles are
 *     prescribed to F X_q + w_q and servo-controlled to periodicity
 *     (eqs 5-14, 33-37, Table 2), P from the boundary forces (eq 14);
 *   --frame periodic (grainkit's): the 205 disks in the periodic cell
 *     deformed with F, P = det F sigma F^-T from the Love stress.
 * Both relax to E_kin / E_pot <= --tol-energy (eqs 30-32, 1e-3).
 * Contact law (eq 10): linear, k_s = 0.2 k_n, Coulomb mu = --friction, local
 * non-viscous damping 0.7 on translation and rotation, disks of density
 * 2000 kg/m^3 and thickness 1 m. STIFFNESS: Table 3 gives k_n = 1e4 N/m with
 * sigma0 = 0.15 MN/m, which would make the overlaps ~15 particle diameters;
 * the response of a linear-contact packing depends on k_n only through
 * k_n / sigma0 (and R_min / L, R_max / R_min), so k_n is set as a ratio to
 * the confinement, --kn-ratio 100 (k_n = 1.5e7 N/m: overlaps ~ 1e-2 of a
 * diameter at sigma0). DEM step 0.4 sqrt(m_min / k_n) = 2.5 us (the paper:
 * 1 us). --no-rotation locks every particle's rotation (the paper's
 * theta_p = 0). --packing takes another framed packing (the anisotropic
 * ones: frame228_a005.txt, frame228_a008.txt).
 *
 * --test rve: the RVE alone on the same path: a homogeneous specimen (F =
 * diag(F11, F22), the two edge displacements relaxed by the same DR with
 * the masses of the 1 x 1 mesh), i.e. what the 1 x 1 mesh does when its four
 * RVEs stay alike.
 */
#ifndef FEMDEM_DR_MODEL_H
#define FEMDEM_DR_MODEL_H

#include "gk_explicit.h"
#include "gk_fem.h"
#include "gk_frame.h"
#include "gk_io.h"
#include "gk_twoscale.h"
#include "femdem_dr_opts.h"

#define NCOL 12 /* columns of dr.csv */
#define RHO 2000.0

/* ------------------------------------------------------------------ model */
typedef struct row {
    double v[NCOL];
} row;

typedef struct model {
    opts o;
    int single; /* --test rve: one point, two dofs                          */
    gk_mesh mesh;
    gk_quad q;
    int ngp, ndof, nnode;
    double *dNdX, *wgp; /* per Gauss point: 8 derivatives, detJ x weight (reference) */
    double *mass, *u, *v, *fint, *fext, *f0, *u0, *P, *H, *Hacc, *dH, *deq;
    unsigned char *fixed;
    int *top, ntop, *edge, nedge; /* top nodes; loaded boundary edges (a, b, side 0 right 1 top 2 left) */
    gk_packing pk;
    gk_frame fr;
    gk_frame_set fs;
    gk_frame_stats *stats;
    gk_twoscale ts;
    gk_dr dr;
    double omega_max, h0, h_ic, J_ic, t0;
    row *rows;
    int nrows, caprows, step_done, have_f0;
    long long dem_total, runs_total, capped_total, unconverged;
    /* the relative force residual a load step ended with (gk_dr.resid): the
     * largest, its step, and how many steps ended above RESID_WARN */
    double resid_last, resid_max;
    long long resid_step, resid_over;
} model;

/* a load step that ends with |f_ext - f_int| above this share of the largest
 * force was stopped by eq 28's energy ratio before equilibrium: warned */
#define RESID_WARN 0.05

static void die_alloc(void) {
    fprintf(stderr, PROG ": out of memory\n");
    exit(1);
}
static void *xcalloc(size_t n, size_t s) {
    void *p = calloc(n ? n : 1, s);
    if (!p) die_alloc();
    return p;
}

static gk_rve_def rve_def(const opts *o) {
    gk_rve_def d = gk_rve_def_default();
    if (o->material == 1) { /* Guo & Zhao 2014's, as examples/femdem_biaxial.c: E r*, their YADE time step */
        d.dt = 3.1602315723728926e-05;
        d.flags = rotation_lock(o) == ROT_ALL ? GK_RVE_NO_ROTATION : 0u;
        return d;
    }
    d.mat.law = GK_LAW_LINEAR;
    d.mat.kn = o->kn_ratio * o->pressure;
    d.mat.kt_ratio = 0.2;
    d.mat.friction = o->friction;
    d.mat.density = RHO;
    d.thickness = 1.0;
    d.damping = o->damping;
    d.damping_form = GK_DAMP_COMPONENT;
    d.dt_factor = o->dt_factor;
    d.flags = rotation_lock(o) == ROT_ALL ? GK_RVE_NO_ROTATION : 0u;
    return d;
}

/* the specimen's mean density rho v_m (eq 24) from the packing's solid fraction */
static double macro_density(const gk_packing *pk) {
    double a = 0.0;
    int p;
    for (p = 0; p < pk->n; ++p) a += GK_PI * pk->r[p] * pk->r[p];
    return RHO * a / (pk->h[0] * pk->h[4]);
}

/* H = dU/dX at every Gauss point */
static void gradients(const model *m, const double *u, double *H) {
    int g;
    if (m->single) {
        memset(H, 0, 9 * sizeof(double));
        H[0] = u[0] / m->o.width, H[4] = u[1] / m->o.height;
        return;
    }
    for (g = 0; g < m->ngp; ++g)
        gk_fem_grad(&m->mesh, g / m->q.n, m->dNdX + 8 * (size_t)g, u, H + 9 * (size_t)g);
}

/* f_int = int B^T P dV0 */
static void internal_force(const model *m, const double *P, double *f) {
    int e, a, k;
    memset(f, 0, (size_t)m->ndof * sizeof(double));
    if (m->single) {
        f[0] = P[0] * m->o.height, f[1] = P[4] * m->o.width;
        return;
    }
    for (e = 0; e < m->mesh.nelem; ++e)
        for (k = 0; k < m->q.n; ++k) {
            int g = e * m->q.n + k;
            const double *s = P + 9 * (size_t)g, *dN = m->dNdX + 8 * (size_t)g;
            for (a = 0; a < 4; ++a) {
                int n = m->mesh.conn[4 * e + a];
                f[2 * n] += m->wgp[g] * (s[0] * dN[2 * a] + s[1] * dN[2 * a + 1]);
                f[2 * n + 1] += m->wgp[g] * (s[3] * dN[2 * a] + s[4] * dN[2 * a + 1]);
            }
        }
}

/* follower pressures on the current edges: p_side on the sides, p_top on the top */
static void external_force(const model *m, const double *u, double p_side, double p_top, double *f) {
    int k;
    memset(f, 0, (size_t)m->ndof * sizeof(double));
    if (m->single) {
        f[0] = -p_side * (m->o.height + u[1]);
        f[1] = -p_top * (m->o.width + u[0]);
        return;
    }
    for (k = 0; k < m->nedge; ++k) {
        int a = m->edge[3 * k], b = m->edge[3 * k + 1], side = m->edge[3 * k + 2];
        double xa = m->mesh.x[2 * a] + u[2 * a], ya = m->mesh.x[2 * a + 1] + u[2 * a + 1];
        double xb = m->mesh.x[2 * b] + u[2 * b], yb = m->mesh.x[2 * b + 1] + u[2 * b + 1];
        double p = side == 1 ? p_top : p_side, fx, fy;
        /* counter-clockwise edge a -> b: outward normal x length = (dy, -dx); traction -p n */
        fx = -p * (yb - ya), fy = p * (xb - xa);
        f[2 * a] += 0.5 * fx, f[2 * a + 1] += 0.5 * fy;
        f[2 * b] += 0.5 * fx, f[2 * b + 1] += 0.5 * fy;
    }
}

/* counter-clockwise boundary edges of the structured mesh on the right, top and left sides */
static void boundary_edges(model *m) {
    int nx = m->o.nx, ny = m->o.ny, i, j, k = 0;
    m->edge = (int *)xcalloc(3 * (size_t)(2 * ny + nx), sizeof(int));
    /* node (i, j) of a structured Q4 mesh: j (nx + 1) + i (gk_mesh_structured, x fastest) */
    for (j = 0; j < ny; ++j) /* right, upwards */
        m->edge[3 * k] = j * (nx + 1) + nx, m->edge[3 * k + 1] = (j + 1) * (nx + 1) + nx,
                    m->edge[3 * k + 2] = 0, ++k;
    for (i = nx; i > 0; --i) /* top, leftwards */
        m->edge[3 * k] = ny * (nx + 1) + i, m->edge[3 * k + 1] = ny * (nx + 1) + i - 1,
                    m->edge[3 * k + 2] = 1, ++k;
    for (j = ny; j > 0; --j) /* left, downwards */
        m->edge[3 * k] = j * (nx + 1), m->edge[3 * k + 1] = (j - 1) * (nx + 1), m->edge[3 * k + 2] = 2, ++k;
    m->nedge = k;
}

static double mean_top(const model *m, const double *u) {
    double s = 0.0;
    int k;
    if (m->single) return m->o.height + u[1];
    for (k = 0; k < m->ntop; ++k) s += m->mesh.x[2 * m->top[k] + 1] + u[2 * m->top[k] + 1];
    return s / m->ntop;
}

/* ------------------------------------------------------------------ setup */
static int setup(model *m) {
    const opts *o = &m->o;
    gk_err err;
    gk_twoscale_def d;
    gk_twoscale_proto pr;
    int e, g, k;
    if (gk_packing_read(o->packing, &m->pk, NULL, &err)) {
        fprintf(stderr, PROG ": %s\n", err.msg);
        return 1;
    }
    if (o->frame == GK_FRAME_SERVO && gk_frame_build(&m->fr, &m->pk, NULL, &err)) {
        fprintf(stderr, PROG ": %s: %s\n", o->packing, err.msg);
        return 1;
    }
    if (m->single) {
        m->ngp = 1, m->ndof = 2;
        m->wgp = (double *)xcalloc(1, sizeof(double));
        m->wgp[0] = o->width * o->height;
    } else {
        int n[3];
        double org[3] = {0, 0, 0}, len[3];
        n[0] = o->nx, n[1] = o->ny, n[2] = 1;
        len[0] = o->width, len[1] = o->height, len[2] = 0;
        if (gk_mesh_structured(&m->mesh, GK_Q4, n, org, len, NULL, &err) ||
            gk_quad_rule(&m->q, GK_Q4, 2, &err)) {
            fprintf(stderr, PROG ": %s\n", err.msg);
            return 1;
        }
        m->nnode = m->mesh.nnode, m->ndof = 2 * m->nnode, m->ngp = m->mesh.nelem * m->q.n;
        m->dNdX = (double *)xcalloc(8 * (size_t)m->ngp, sizeof(double));
        m->wgp = (double *)xcalloc((size_t)m->ngp, sizeof(double));
        for (e = 0; e < m->mesh.nelem; ++e)
            for (k = 0; k < m->q.n; ++k) {
                double detJ;
                g = e * m->q.n + k;
                if (gk_fem_jacobian(&m->mesh, e, m->q.xi[k], NULL, m->dNdX + 8 * (size_t)g, &detJ, &err)) {
                    fprintf(stderr, PROG ": %s\n", err.msg);
                    return 1;
                }
                m->wgp[g] = detJ * m->q.w[k];
            }
        boundary_edges(m);
        m->top = (int *)xcalloc((size_t)o->nx + 1, sizeof(int));
        m->ntop = gk_mesh_nodes_on_plane(&m->mesh, 1, o->height, 1e-9 * o->height, m->top);
    }
    m->mass = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->u = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->v = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->fint = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->fext = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->f0 = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->u0 = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->fixed = (unsigned char *)xcalloc((size_t)m->ndof, 1);
    m->P = (double *)xcalloc(9 * (size_t)m->ngp, sizeof(double));
    m->H = (double *)xcalloc(9 * (size_t)m->ngp, sizeof(double));
    m->Hacc = (double *)xcalloc(9 * (size_t)m->ngp, sizeof(double));
    m->dH = (double *)xcalloc(9 * (size_t)m->ngp, sizeof(double));
    m->deq = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    m->stats = (gk_frame_stats *)xcalloc((size_t)m->ngp, sizeof(gk_frame_stats));
    /* masses (eq 24) and supports */
    {
        double rho = macro_density(&m->pk);
        if (m->single) {
            m->mass[0] = m->mass[1] = 0.5 * rho * o->width * o->height; /* one edge of the 1 x 1 mesh */
        } else {
            double *mn = (double *)xcalloc((size_t)m->nnode, sizeof(double));
            if (gk_fem_lumped_mass(&m->mesh, &m->q, rho, mn, &err)) {
                fprintf(stderr, PROG ": %s\n", err.msg);
                return 1;
            }
            for (k = 0; k < m->nnode; ++k) {
                m->mass[2 * k] = m->mass[2 * k + 1] = mn[k];
                if (m->mesh.x[2 * k + 1] <= 1e-12 * o->height) m->fixed[2 * k + 1] = 1; /* bottom: u_y = 0 */
            }
            m->fixed[0] = 1; /* node 0 = (0, 0): u_x = 0 */
            free(mn);
        }
    }
    /* the RVEs */
    memset(&d, 0, sizeof d);
    memset(&m->fs, 0, sizeof m->fs);
    m->fs.kind = (gk_frame_kind)o->frame;
    m->fs.def.tol_energy = o->tol_energy;
    m->fs.def.tol_servo = o->tol_servo;
    m->fs.def.max_servo = o->servo_max;
    m->fs.def.max_steps = o->rve_max;
    m->fs.def.lock_inner = rotation_lock(o) == ROT_INNER;
    m->fs.frames = &m->fr;
    m->fs.stats = m->stats;
    pr.packing = o->frame == GK_FRAME_SERVO ? &m->fr.framed : &m->pk;
    pr.state = NULL;
    d.npoints = m->ngp, d.protos = &pr, d.nprotos = 1, d.threads = o->threads;
    d.rve = rve_def(o);
    d.proc = gk_frame_run, d.proc_user = &m->fs;
    if (gk_twoscale_create(&m->ts, &d)) {
        fprintf(stderr, PROG ": %s\n", gk_twoscale_error(&m->ts));
        return 1;
    }
    /* bound on the highest frequency: twice the Taylor tangent of the packing (an upper bound) */
    {
        gk_rve r;
        gk_rve_def rd = rve_def(o);
        double D[16], Dg[16 * 4], Ke[64], me[8];
        if (gk_rve_create(&r, &rd, &m->pk) || gk_rve_refresh(&r) || gk_homog_tangent(&r, 0u, D)) {
            fprintf(stderr, PROG ": %s\n", gk_rve_error(&r));
            return 1;
        }
        gk_rve_destroy(&r);
        for (k = 0; k < 16; ++k) D[k] *= 2.0;
        m->omega_max = 0.0;
        if (m->single) { /* the homogeneous mode: k = D_1111 H / W on the mass of one edge */
            double kx = D[0] * o->height / o->width, ky = D[15] * o->width / o->height;
            m->omega_max = sqrt((kx > ky ? kx : ky) / m->mass[0]);
        } else {
            for (e = 0; e < m->mesh.nelem; ++e) {
                double om, area = 0.0;
                for (k = 0; k < 4; ++k) memcpy(Dg + 16 * k, D, sizeof D);
                if (gk_fem_elem_stiffness(&m->mesh, e, &m->q, Dg, Ke, &err)) {
                    fprintf(stderr, PROG ": %s\n", err.msg);
                    return 1;
                }
                for (k = 0; k < 4; ++k) area += m->wgp[e * 4 + k];
                for (k = 0; k < 8; ++k) me[k] = 0.25 * macro_density(&m->pk) * area;
                om = gk_explicit_elem_omega(8, Ke, me);
                if (om > m->omega_max) m->omega_max = om;
            }
        }
    }
    {
        gk_dr_def dd;
        memset(&dd, 0, sizeof dd);
        dd.xi = o->xi, dd.gamma = o->gamma, dd.tol = o->tol_dr, dd.omega_max = m->omega_max;
        dd.omega_cap = m->omega_max, dd.force_tol = o->force_tol, dd.force_stop = o->force_stop;
        dd.max_iter = o->max_dr;
        if (gk_dr_init(&m->dr, &dd, m->ndof, m->mass, m->fixed, &err)) {
            fprintf(stderr, PROG ": %s\n", err.msg);
            return 1;
        }
    }
    m->h0 = o->height;
    m->h_ic = o->height;
    m->J_ic = 1.0;
    return 0;
}

/* ------------------------------------------------------------------ one DR iteration */
/* the RVEs at U, f_int; 0 or 3 (points failed: the message said) */
static int evaluate(model *m) {
    int g, k;
    const gk_twoscale_point *pts;
    gradients(m, m->u, m->H);
    for (g = 0; g < 9 * m->ngp; ++g) m->dH[g] = m->H[g] - m->Hacc[g];
    if (gk_twoscale_run(&m->ts, m->dH, NULL, m->P, NULL)) {
        fprintf(stderr, PROG ": %s\n", gk_twoscale_error(&m->ts));
        return 3;
    }
    gk_twoscale_accept(&m->ts);
    pts = gk_twoscale_points(&m->ts);
    for (g = 0; g < m->ngp; ++g) {
        m->dem_total += pts[g].work;
        m->capped_total += m->stats[g].capped;
        for (k = 0; k < 9; ++k) m->Hacc[9 * g + k] += m->dH[9 * g + k];
    }
    m->runs_total += m->ngp;
    internal_force(m, m->P, m->fint);
    return 0;
}

/* ------------------------------------------------------------------ the load path */
/* relax one load step; 0, 3 (RVEs failed) */
static int dr_step(model *m, double p_side, double p_top, int *iters) {
    int rc, k;
    gk_dr_begin(&m->dr);
    for (k = 0; k < m->ndof; ++k) m->v[k] = 0.0;
    for (;;) {
        if ((rc = evaluate(m)) != 0) return rc;
        if (m->o.rayleigh == 0 && m->dr.iter == 0) { /* eq 26 relative to this step's start */
            memcpy(m->u0, m->u, (size_t)m->ndof * sizeof(double));
            memcpy(m->f0, m->fint, (size_t)m->ndof * sizeof(double));
            gk_dr_reference(&m->dr, m->u0, m->f0);
        } else if (!m->have_f0) { /* the unloaded state's own internal force: the reference of eq 26 */
            memcpy(m->f0, m->fint, (size_t)m->ndof * sizeof(double));
            gk_dr_reference(&m->dr, NULL, m->f0);
            m->have_f0 = 1;
        }
        external_force(m, m->u, p_side, p_top, m->fext);
        if (gk_dr_iterate(&m->dr, m->fint, m->fext, m->u, m->v)) {
            fprintf(stderr, PROG ": %s\n", m->dr.err.msg);
            return 3;
        }
        if (getenv("FDR_DEBUG") && m->single)
            fprintf(
                stderr,
                "it %ld u %.4e %.4e fint %.4e %.4e fext %.4e %.4e om %.4e dt %.3e ek %.3e max %.3e g %u\n",
                m->dr.iter, m->u[0], m->u[1], m->fint[0], m->fint[1], m->fext[0], m->fext[1], m->dr.omega,
                m->dr.dt, m->dr.ekin, m->dr.ekin_max, m->dr.guards);
        if (m->dr.converged) break;
        if (m->dr.iter >= m->o.max_dr) {
            ++m->unconverged;
            fprintf(stderr,
                    PROG ": warning: load step not relaxed in %d DR iterations (E_kin / E_kin,max %.2g)\n",
                    m->o.max_dr, m->dr.ekin / m->dr.ekin_max);
            break;
        }
    }
    *iters = (int)m->dr.iter;
    m->resid_last = m->dr.resid;
    return 0;
}

#endif /* FEMDEM_DR_MODEL_H */
