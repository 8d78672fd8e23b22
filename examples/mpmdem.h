/* mpmdem.h - what the three MPMxDEM drivers share (examples, not library).
 *
 * mpmdem_biaxial.c, mpmdem_footing.c and mpmdem_collapse.c put one periodic
 * 2D RVE behind every material point of an explicit MPM (seed 003, Liang &
 * Zhao; notes in ../shared/notes/seed-003.md). This file holds the parts
 * they have in common, included once by each driver after the grainkit
 * headers with GK_IMPLEMENTATION:
 *
 *   mpd_opts / mpd_parse_common / mpd_usage_common   flags every driver takes
 *   mpd_prepare_rve     the packing, the DEM material, consolidation to a
 *                       pressure, the bulk density and P-wave modulus
 *   mpd_rves_*          one RVE per point; mpd_stress is the
 *                       gk_mpm_stress_fn of gk_mpm_step (seed 003 Sec 2.3
 *                       (b): dH = dt L -> RVE -> total Love stress back)
 *   mpd_fields          per-point output fields
 *   mpd_write_vtk / mpd_svg_field   material points for ParaView / an SVG
 *   mpd_ck_write / mpd_ck_read      checkpoints (every RVE, every point)
 *
 * THE DEM STEPS PER MPM STEP (the paper leaves it unstated; it says the DEM
 * runs "until a quasi-static state"). Default (--dem-rule adaptive):
 * gk_rve_deform_adaptive (gk_homog.h) - the point's dH is applied over
 *     n = clamp(ceil(I_1 / I_max), dem_min, dem_max)
 * steps, I_1 the inertial number (seed 000 eq 20) of dH in one DEM step at
 * the RVE's current pressure, so the RVE deforms at I <= I_max (5e-4: at
 * 100 kPa the same count as the 1e-5-strain-per-step rule of seed 000's
 * scripts; more steps where p is low), then relaxes at fixed cell while its
 * unbalanced force ratio exceeds --dem-unbalanced (5e-3), within dem_max
 * steps in all. --dem-rule strain: n_s = clamp(ceil(max|dH_ij| /
 * dem_strain), dem_min, dem_max), no relaxation. dem_max caps the cost; the
 * collapse driver sets it to the real-time count dt_MPM / dt_DEM (a flowing
 * point cannot be more quasi-static than the flow), the quasi-static
 * drivers leave it large.
 *
 * THE MPM TIME STEP: dt = cfl h / c, c = sqrt(M / rho) with M = max(D_xxxx,
 * D_yyyy) of the Taylor (affine, eq 9 of seed 000) tangent of the prepared
 * RVE: the affine tangent bounds the RVE's real stiffness from above, so c
 * is an upper bound of the P-wave speed and the step is safe while the
 * contact network keeps its stiffness (the drivers print M, rho, c, dt).
 */
#ifndef MPMDEM_H
#define MPMDEM_H

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define MPD_PI 3.14159265358979323846

typedef struct mpd_opts {
    const char *out, *packing, *restart;
    int threads, ppc;
    gk_mpm_basis basis;
    double alpha;                        /* PIC fraction (seed 003: 0.1)                          */
    double cfl;                          /* dt = cfl h / c                                        */
    int dem_adaptive;                    /* 1: gk_rve_deform_adaptive, 0: the strain rule         */
    double dem_inertial, dem_unbalanced; /* bounds of the adaptive rule        */
    double dem_strain;                   /* RVE strain per DEM step bound (strain rule)           */
    int dem_min, dem_max;
    double dem_dt; /* DEM time step [s]; 0 -> 0.5 x critical                */
    double young, kt_ratio, friction_deg, roll_beta, roll_eta, dem_damping;
    int vtk_every; /* MPM steps between VTK files (0: first and last only)   */
    int checkpoint_every;
    int quiet;
} mpd_opts;

static void mpd_opts_default(mpd_opts *o, const char *out) {
    gk_material m = gk_material_default(); /* seed 000 / seed 003 Table 3 values */
    memset(o, 0, sizeof *o);
    o->out = out;
    o->packing = "examples/data/rve400.txt";
    o->threads = 2;
    o->ppc = 1;
    o->basis = GK_MPM_UGIMP;
    o->alpha = 0.1;
    o->cfl = 0.4;
    o->dem_adaptive = 1;
    o->dem_inertial = 5e-4;
    o->dem_unbalanced = 5e-3;
    o->dem_strain = 1e-5;
    o->dem_min = 1;
    o->dem_max = 1000;
    o->dem_dt = 3.16e-5; /* the step seed 000's scripts use with this packing */
    o->young = m.young;
    o->kt_ratio = m.kt_ratio;
    o->friction_deg = atan(m.friction) * 180.0 / MPD_PI;
    o->dem_damping = 0.1; /* seed 003 eq 29, alpha = 0.1 */
    o->vtk_every = 0;
    o->checkpoint_every = 0;
}

/* the DEM-step rule in force, as the quasi-static drivers print it at start (the collapse prints its
 * real-time cap with it); inline: a driver that does not call it gets no unused-function warning */
GK_INLINE void mpd_print_dem_rule(const mpd_opts *o) {
    if (o->dem_adaptive)
        printf("DEM steps per MPM step: adaptive, I <= %g then relaxation to an unbalanced force ratio < %g, "
               "%d..%d steps\n",
               o->dem_inertial, o->dem_unbalanced, o->dem_min, o->dem_max);
    else
        printf("DEM steps per MPM step: <= %g strain per DEM step, %d..%d steps\n", o->dem_strain, o->dem_min,
               o->dem_max);
}

static void mpd_usage_common(FILE *fp, const mpd_opts *d) {
    fprintf(
        fp,
        "common options (MPMxDEM):\n"
        "  --out DIR              output directory (default %s)\n"
        "  --threads T            OpenMP threads over the RVEs and the MPM (default %d)\n"
        "  --ppc K                material points per cell edge: K^2 per cell (default %d)\n"
        "  --basis B              linear | ugimp | quadratic | cubic (default ugimp; seed 003: GIMP)\n"
        "  --alpha A              PIC fraction of the PIC/FLIP blend, eq 19 (default %g)\n"
        "  --cfl C                MPM step = C h / c, c from the RVE's Taylor tangent (default %g)\n"
        "  --packing FILE         RVE packing every point starts from (default %s)\n"
        "  --dem-rule R           adaptive | strain: DEM steps per MPM step from the inertial number and\n"
        "                         the unbalanced force (default), or from the strain per DEM step\n"
        "  --dem-inertial I       adaptive: inertial number bound of the RVE deformation (default %g)\n"
        "  --dem-unbalanced U     adaptive: relax until the unbalanced force ratio < U (default %g)\n"
        "  --dem-strain S         strain rule: RVE strain per DEM step bound (default %g)\n"
        "  --dem-min N --dem-max N  bounds of the DEM steps per MPM step (default %d, %d)\n"
        "  --dem-dt DT            DEM time step [s] (default %g)\n"
        "  --young E --kt-ratio R --friction-deg PHI --roll-beta B --roll-eta ETA\n"
        "                         DEM contact law, seed 003 eqs 26-28 (defaults %g Pa, %g, %g deg, %g, %g)\n"
        "  --dem-damping A        local non-viscous damping in the RVEs, eq 29 (default %g)\n"
        "  --vtk-every N          VTK of the points every N MPM steps (default: first and last)\n"
        "  --checkpoint N         checkpoint every N MPM steps into DIR/checkpoint.bin (0: at the end)\n"
        "  --restart DIR          continue from DIR/checkpoint.bin (same flags) to the same result\n"
        "  --quiet                no progress lines\n",
        d->out, d->threads, d->ppc, d->alpha, d->cfl, d->packing, d->dem_inertial, d->dem_unbalanced,
        d->dem_strain, d->dem_min, d->dem_max, d->dem_dt, d->young, d->kt_ratio, d->friction_deg,
        d->roll_beta, d->roll_eta, d->dem_damping);
}

/* numbers on the command line: the whole string must parse and be finite */
static int mpd_num(const char *s, double *v) {
    char *end;
    errno = 0;
    *v = strtod(s, &end);
    return !(end != s && *end == '\0' && errno == 0 && isfinite(*v));
}

/* consumes argv[*i] (and its value) if it is a common flag: 1 consumed, 0 not
 * a common flag, -1 bad value (message on stderr) */
static int mpd_parse_common(mpd_opts *o, int argc, char **argv, int *i) {
    const char *a = argv[*i], *val = *i + 1 < argc ? argv[*i + 1] : NULL;
    double v = 0.0;
    static const char *with_value[] = {
        "--out",        "--threads",      "--ppc",       "--basis",        "--alpha",         "--cfl",
        "--packing",    "--dem-strain",   "--dem-min",   "--dem-max",      "--dem-dt",        "--young",
        "--kt-ratio",   "--friction-deg", "--roll-beta", "--roll-eta",     "--dem-damping",   "--vtk-every",
        "--checkpoint", "--restart",      "--dem-rule",  "--dem-inertial", "--dem-unbalanced"};
    size_t k;
    if (!strcmp(a, "--quiet")) return o->quiet = 1, 1;
    for (k = 0; k < sizeof with_value / sizeof *with_value; ++k)
        if (!strcmp(a, with_value[k])) break;
    if (k == sizeof with_value / sizeof *with_value) return 0;
    if (!val) return fprintf(stderr, "error: %s needs a value\n", a), -1;
    ++*i;
    if (!strcmp(a, "--out")) return o->out = val, 1;
    if (!strcmp(a, "--packing")) return o->packing = val, 1;
    if (!strcmp(a, "--restart")) return o->restart = val, 1;
    if (!strcmp(a, "--dem-rule")) {
        if (!strcmp(val, "adaptive"))
            o->dem_adaptive = 1;
        else if (!strcmp(val, "strain"))
            o->dem_adaptive = 0;
        else
            return fprintf(stderr, "error: --dem-rule %s: use adaptive or strain\n", val), -1;
        return 1;
    }
    if (!strcmp(a, "--basis")) {
        if (!strcmp(val, "linear"))
            o->basis = GK_MPM_LINEAR;
        else if (!strcmp(val, "ugimp"))
            o->basis = GK_MPM_UGIMP;
        else if (!strcmp(val, "quadratic"))
            o->basis = GK_MPM_QUADRATIC;
        else if (!strcmp(val, "cubic"))
            o->basis = GK_MPM_CUBIC;
        else
            return fprintf(stderr, "error: --basis %s: use linear, ugimp, quadratic or cubic\n", val), -1;
        return 1;
    }
    if (mpd_num(val, &v)) return fprintf(stderr, "error: %s %s: not a number\n", a, val), -1;
#define MPD_INT(flag, field, lo, hi)                                                                   \
    if (!strcmp(a, flag)) {                                                                            \
        if (v != floor(v) || v < (lo) || v > (hi))                                                     \
            return fprintf(stderr, "error: %s %s: need an integer in [%d, %d]\n", a, val, lo, hi), -1; \
        return o->field = (int)v, 1;                                                                   \
    }
#define MPD_REAL(flag, field, ok, what)                                                 \
    if (!strcmp(a, flag)) {                                                             \
        if (!(ok)) return fprintf(stderr, "error: %s %s: need %s\n", a, val, what), -1; \
        return o->field = v, 1;                                                         \
    }
    MPD_INT("--threads", threads, 1, 1024)
    MPD_INT("--ppc", ppc, 1, 4)
    MPD_INT("--dem-min", dem_min, 1, 1000000)
    MPD_INT("--dem-max", dem_max, 1, 1000000)
    MPD_INT("--vtk-every", vtk_every, 0, 1000000000)
    MPD_INT("--checkpoint", checkpoint_every, 0, 1000000000)
    MPD_REAL("--alpha", alpha, v >= 0.0 && v <= 1.0, "a value in [0, 1]")
    MPD_REAL("--cfl", cfl, v > 0.0 && v <= 1.0, "a value in (0, 1]")
    MPD_REAL("--dem-strain", dem_strain, v > 0.0, "a positive value")
    MPD_REAL("--dem-inertial", dem_inertial, v > 0.0, "a positive value")
    MPD_REAL("--dem-unbalanced", dem_unbalanced, v > 0.0, "a positive value")
    MPD_REAL("--dem-dt", dem_dt, v >= 0.0, "a value >= 0")
    MPD_REAL("--young", young, v > 0.0, "a positive modulus")
    MPD_REAL("--kt-ratio", kt_ratio, v >= 0.0 && v <= 1.0, "a value in [0, 1]")
    MPD_REAL("--friction-deg", friction_deg, v >= 0.0 && v < 90.0, "an angle in [0, 90)")
    MPD_REAL("--roll-beta", roll_beta, v >= 0.0, "a value >= 0")
    MPD_REAL("--roll-eta", roll_eta, v >= 0.0, "a value >= 0")
    MPD_REAL("--dem-damping", dem_damping, v >= 0.0 && v < 1.0, "a value in [0, 1)")
#undef MPD_INT
#undef MPD_REAL
    return 0;
}

static int mpd_check_opts(const mpd_opts *o) {
    if (o->dem_min > o->dem_max)
        return fprintf(stderr, "error: --dem-min %d exceeds --dem-max %d\n", o->dem_min, o->dem_max), 1;
    return 0;
}

static int mpd_mkdir(const char *d) {
    if (mkdir(d, 0755) && errno != EEXIST) return fprintf(stderr, "error: cannot create %s\n", d), 1;
    return 0;
}

/* ------------------------------------------------------------ the RVE */
/* What every point of a driver starts from. */
typedef struct mpd_proto {
    gk_packing pk;  /* the packing file (every RVE is created from it)        */
    gk_rve_def def; /* the DEM definition built from the options              */
    double rho;     /* bulk density of the RVE: solid mass / cell volume      */
    double M;       /* P-wave modulus max(D_xxxx, D_yyyy), Taylor tangent [Pa] */
    double p0, e0;  /* pressure and void ratio of the consolidated state      */
} mpd_proto;

static gk_result mpd_proto_open(mpd_proto *P, const mpd_opts *o, gk_err *err) {
    memset(P, 0, sizeof *P);
    if (gk_packing_read(o->packing, &P->pk, NULL, err)) return err->code;
    if (P->pk.dim != 2) {
        gk_packing_free(&P->pk);
        return gk_err_set(err, GK_ERR_ARG, "%s is a %dD packing; the MPMxDEM drivers are 2D", o->packing,
                          P->pk.dim);
    }
    P->def = gk_rve_def_default();
    P->def.dt = o->dem_dt;
    P->def.mat.young = o->young;
    P->def.mat.kt_ratio = o->kt_ratio;
    P->def.mat.friction = tan(o->friction_deg * MPD_PI / 180.0);
    P->def.mat.roll_beta = o->roll_beta;
    P->def.mat.roll_eta = o->roll_eta;
    P->def.damping = o->dem_damping;
    return GK_OK;
}

static void mpd_proto_close(mpd_proto *P) { gk_packing_free(&P->pk); }

/* One RVE from the packing, brought to the isotropic pressure p (compression
 * positive) by gk_rve_consolidate with the contact friction on (the packing's
 * fabric is kept; the void ratio is what it becomes), its state in *st.
 * p <= 0: the packing as it is. Fills rho, M, p0, e0 of P from the result. */
static gk_result mpd_prepare_rve(mpd_proto *P, double p, gk_rve_state *st, gk_err *err) {
    gk_rve r;
    double s[9], D[16];
    gk_result res;
    if (gk_rve_create(&r, &P->def, &P->pk)) return gk_err_set(err, GK_ERR_ARG, "RVE: %s", gk_rve_error(&r));
    res = gk_rve_refresh(&r);
    if (!res && p > 0.0) {
        gk_consolidate_def cd;
        gk_consolidate_report rep;
        memset(&cd, 0, sizeof cd);
        cd.pressure = p;
        cd.friction = P->def.mat.friction;
        cd.stress_tol = 2e-3;
        res = gk_rve_consolidate(&r, &cd, &rep);
    }
    if (res) {
        gk_err_set(err, res, "RVE preparation at %g Pa: %s", p, gk_rve_error(&r));
        gk_rve_destroy(&r);
        return res;
    }
    gk_rve_stress(&r, s);
    if (gk_homog_tangent(&r, 0u, D)) {
        gk_rve_destroy(&r);
        return gk_err_set(err, GK_ERR_STATE, "RVE tangent failed");
    }
    P->rho = r.mass_total / gk_rve_volume(&r);
    P->M = D[0] > D[15] ? D[0] : D[15];
    P->p0 = gk_stress_p(s, 2);
    P->e0 = gk_homog_void_ratio(&r);
    res = gk_rve_state_save(st, &r);
    gk_rve_destroy(&r);
    if (res) return gk_err_set(err, res, "out of memory saving the RVE state");
    return GK_OK;
}

/* ------------------------------------------------------- RVE per point */
typedef struct mpd_rves {
    int n;
    gk_rve *rve;
    double *eps; /* accumulated small strain sum sym(dH), 9 per point [seed 003 (b)] */
    int *nsub;   /* DEM steps of the last MPM step, per point                        */
    int *status; /* gk_result of the last RVE call, per point                        */
    const mpd_opts *o;
    long long dem_steps; /* sum of n_s over points and MPM steps (cost measure)     */
} mpd_rves;

static void mpd_rves_free(mpd_rves *f) {
    int p;
    if (f->rve)
        for (p = 0; p < f->n; ++p) gk_rve_destroy(&f->rve[p]);
    free(f->rve);
    free(f->eps);
    free(f->nsub);
    free(f->status);
    memset(f, 0, sizeof *f);
}

/* n RVEs created from the packing, each then set to the state chosen for it
 * by pick(p, user) (an index into states[]) */
static gk_result mpd_rves_create(mpd_rves *f, int n, const mpd_proto *P, const gk_rve_state *states,
                                 int (*pick)(int p, void *user), void *user, const mpd_opts *o, gk_err *err) {
    int p;
    memset(f, 0, sizeof *f);
    f->n = n;
    f->o = o;
    f->rve = (gk_rve *)calloc((size_t)n, sizeof *f->rve);
    f->eps = (double *)calloc(9 * (size_t)n, sizeof *f->eps);
    f->nsub = (int *)calloc((size_t)n, sizeof *f->nsub);
    f->status = (int *)calloc((size_t)n, sizeof *f->status);
    if (!f->rve || !f->eps || !f->nsub || !f->status) {
        mpd_rves_free(f);
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for %d RVEs", n);
    }
    for (p = 0; p < n; ++p) {
        int k = pick ? pick(p, user) : 0;
        if (gk_rve_create(&f->rve[p], &P->def, &P->pk) || gk_rve_state_restore(&states[k], &f->rve[p])) {
            gk_err_set(err, GK_ERR_STATE, "RVE %d: %s", p, gk_rve_error(&f->rve[p]));
            f->n = p + 1;
            mpd_rves_free(f);
            return GK_ERR_STATE;
        }
    }
    return GK_OK;
}

static int mpd_dem_steps(const mpd_opts *o, const double dH[9]) {
    double mx = 0.0, n;
    int k;
    for (k = 0; k < 9; ++k)
        if (fabs(dH[k]) > mx) mx = fabs(dH[k]);
    n = ceil(mx / o->dem_strain);
    if (n < o->dem_min) n = o->dem_min;
    if (n > o->dem_max) n = o->dem_max;
    return (int)n;
}

/* Initial point stress = the RVE's stress (2D block; sigma_zz of the plane is
 * not tracked by gk_mpm) */
static void mpd_rve_sigma(const gk_rve *r, double *sig) {
    double s[9];
    gk_rve_stress(r, s);
    gk_m3_zero(sig);
    sig[0] = s[0], sig[1] = s[1], sig[3] = s[3], sig[4] = s[4];
}

/* gk_mpm_stress_fn: every point's RVE deforms by dH = dt L (stretch and spin)
 * over n_s DEM steps and returns its total Love stress [seed 003 Sec 2.3 (b)].
 * Points are independent: parallel, and the result does not depend on the
 * thread count. A failing RVE stops the run with its point and message. */
static gk_result mpd_stress(gk_mpm_points *pts, double dt, void *user, gk_err *err) {
    mpd_rves *f = (mpd_rves *)user;
    int p;
    long long total = 0;
    (void)dt;
    GK_OMP(parallel for num_threads(f->o->threads) schedule(dynamic, 2) reduction(+ : total))
    for (p = 0; p < pts->n; ++p) {
        double dH[9];
        int k, ns;
        gk_mpm_point_dH(pts, p, dt, dH);
        dH[2] = dH[5] = dH[6] = dH[7] = dH[8] = 0.0; /* plane */
        if (f->o->dem_adaptive) {
            gk_adapt_def ad;
            gk_adapt_report rep;
            memset(&ad, 0, sizeof ad);
            ad.inertial_max = f->o->dem_inertial, ad.unbalanced_max = f->o->dem_unbalanced;
            ad.n_min = f->o->dem_min, ad.n_max = f->o->dem_max;
            memset(&rep, 0, sizeof rep);
            f->status[p] = (int)gk_rve_deform_adaptive(&f->rve[p], dH, &ad, &rep);
            ns = rep.n_deform + rep.n_relax;
        } else {
            ns = mpd_dem_steps(f->o, dH);
            f->status[p] = (int)gk_rve_deform(&f->rve[p], dH, ns);
        }
        f->nsub[p] = ns;
        total += ns;
        if (f->status[p]) continue;
        mpd_rve_sigma(&f->rve[p], pts->sigma + 9 * (size_t)p);
        for (k = 0; k < 9; ++k) f->eps[9 * (size_t)p + k] += 0.5 * (dH[k] + dH[3 * (k % 3) + k / 3]);
    }
    f->dem_steps += total;
    for (p = 0; p < pts->n; ++p)
        if (f->status[p])
            return gk_err_set(err, (gk_result)f->status[p], "RVE of point %d at (%.4g, %.4g) m: %s", p,
                              pts->x[0][p], pts->x[1][p], gk_rve_error(&f->rve[p]));
    return GK_OK;
}

/* ------------------------------------------------------ the MPM step */
/* A pressure on the boundary edge of a point (a follower load: it turns and
 * stretches with the point). In the reference configuration the edge has
 * its midpoint at x_p + off and the vector e (oriented so that the outward
 * normal is (e_y, -e_x) / |e|); now at x_p + F off and F e, and it receives
 * f = -pressure ((F e)_y, -(F e)_x): the pressure times the current length,
 * along the current normal. The force goes to the grid nodes with the weights
 * of the EDGE midpoint (the tent for linear/uGIMP), not of the point centre:
 * applied at the centre, half of it would land one node inside the body
 * (uGIMP at a cell centre splits 1/2-1/2) and the uniform initial state
 * would not be in equilibrium - the nodal loads here are the consistent ones
 * of a uniform pressure, matching the internal forces of a uniform stress. */
typedef struct mpd_edge {
    int p;           /* point index */
    double off[2];   /* reference offset centre -> edge midpoint [m] */
    double e[2];     /* reference edge vector [m] */
    double pressure; /* [Pa], compression positive */
} mpd_edge;

/* One USF step (seed 003 Sec 2.3; the sequence gk_mpm_step runs) with the
 * edge loads added to the nodal external forces after P2G, then the rigid
 * bodies advance by v dt. The RVEs update in mpd_stress. */
static gk_result mpd_step(gk_mpm_grid *g, gk_mpm_points *pts, const gk_mpm_def *def, double dt, mpd_rves *f,
                          const mpd_edge *edge, int nedge, gk_err *err) {
    gk_mpm_basis lb = def->basis == GK_MPM_UGIMP ? GK_MPM_LINEAR : def->basis;
    gk_result r;
    int k, a;
    if (def->scheme != GK_MPM_USF) return gk_err_set(err, GK_ERR_ARG, "mpd_step runs USF only");
    if ((r = gk_mpm_p2g(g, pts, def, GK_MPM_P2G_MOMENTUM, err))) return r;
    if ((r = gk_mpm_g2p(g, pts, def, dt, GK_MPM_G2P_GRADIENT_OLD, err))) return r;
    if ((r = mpd_stress(pts, dt, f, err))) return r;
    if ((r = gk_mpm_p2g(g, pts, def, GK_MPM_P2G_FORCE, err))) return r;
    for (k = 0; k < nedge; ++k) {
        const mpd_edge *E = &edge[k];
        const double *F = pts->F + 9 * (size_t)E->p;
        double x[3], fe[2];
        gk_mpm_stencil st;
        x[0] = pts->x[0][E->p] + F[0] * E->off[0] + F[1] * E->off[1];
        x[1] = pts->x[1][E->p] + F[3] * E->off[0] + F[4] * E->off[1];
        x[2] = 0.0;
        fe[0] = F[0] * E->e[0] + F[1] * E->e[1], fe[1] = F[3] * E->e[0] + F[4] * E->e[1];
        if ((r = gk_mpm_shape(g, lb, x, 0.0, &st, err))) return r;
        for (a = 0; a < st.n; ++a) {
            g->fext[0][st.node[a]] += -E->pressure * fe[1] * st.w[a];
            g->fext[1][st.node[a]] += E->pressure * fe[0] * st.w[a];
        }
    }
    if ((r = gk_mpm_grid_update(g, def, dt, err))) return r;
    if ((r = gk_mpm_g2p(g, pts, def, dt, GK_MPM_G2P_VELOCITY | GK_MPM_G2P_POSITION, err))) return r;
    gk_mpm_bodies_advance(g->body, g->nbody, dt);
    return GK_OK;
}

/* ------------------------------------------------------------- fields */
#define MPD_NFIELD 9
static const char *mpd_field_names[MPD_NFIELD] = {
    "eps_q",        "eps_v",    "rotation_deg", "p", "q", "void_ratio", "fabric_anisotropy",
    "coordination", "dem_steps"};

/* eps_q [seed 003 eq 35 with the 2D deviator], eps_v compression-positive
 * (eq 34 with the seeds' sign), rotation of F = R U [eqs 36-40] in degrees
 * (counter-clockwise positive), p, q [eqs 31-33] compression-positive [Pa],
 * void ratio, |F_a| [eqs 41-43], coordination 2 N_c / N_p, DEM steps of the
 * last MPM step */
static void mpd_fields(const mpd_rves *f, const gk_mpm_points *pts, int p, double *v) {
    const gk_rve *r = &f->rve[p];
    double s[9], phi[9], Fa[9];
    const double *e = f->eps + 9 * (size_t)p;
    gk_rve_stress(r, s);
    v[0] = gk_strain_q(e, 2);
    v[1] = -gk_strain_v(e, 2);
    v[2] = gk_rotation_angle(pts->F + 9 * (size_t)p, 2) * 180.0 / MPD_PI;
    v[3] = gk_stress_p(s, 2);
    v[4] = gk_stress_q(s, 2);
    v[5] = gk_homog_void_ratio(r);
    v[6] = gk_homog_fabric(r, phi, Fa);
    v[7] = r->n > 0 ? 2.0 * r->ncontacts / r->n : 0.0;
    v[8] = f->nsub[p];
}

/* all fields of all points, field-major: out[k * n + p] */
static double *mpd_all_fields(const mpd_rves *f, const gk_mpm_points *pts) {
    double *out = (double *)malloc((size_t)MPD_NFIELD * (size_t)pts->n * sizeof *out);
    int p, k;
    if (!out) return NULL;
    for (p = 0; p < pts->n; ++p) {
        double v[MPD_NFIELD];
        mpd_fields(f, pts, p, v);
        for (k = 0; k < MPD_NFIELD; ++k) out[(size_t)k * pts->n + p] = v[k];
    }
    return out;
}

/* material points as VTK vertices: the fields above, velocity, stress */
static int mpd_write_vtk(const char *path, const mpd_rves *f, const gk_mpm_points *pts) {
    gk_vtk v;
    int n = pts->n, p, k, ok;
    double *xyz = (double *)malloc(3 * (size_t)n * sizeof *xyz),
           *vel = (double *)malloc(3 * (size_t)n * sizeof *vel);
    int *conn = (int *)malloc((size_t)n * sizeof *conn);
    double *fld = mpd_all_fields(f, pts);
    ok = xyz && vel && conn && fld;
    if (ok) {
        for (p = 0; p < n; ++p) {
            xyz[3 * p] = pts->x[0][p], xyz[3 * p + 1] = pts->x[1][p], xyz[3 * p + 2] = 0.0;
            vel[3 * p] = pts->v[0][p], vel[3 * p + 1] = pts->v[1][p], vel[3 * p + 2] = 0.0;
            conn[p] = p;
        }
        ok = !gk_vtk_open(&v, path, "grainkit MPMxDEM material points") && !gk_vtk_points(&v, n, xyz) &&
             !gk_vtk_cells(&v, n, 1, conn, GK_VTK_VERTEX);
        for (k = 0; ok && k < MPD_NFIELD; ++k)
            ok = !gk_vtk_point_scalar(&v, mpd_field_names[k], fld + (size_t)k * n);
        ok = ok && !gk_vtk_point_vector(&v, "velocity", vel) &&
             !gk_vtk_point_tensor(&v, "stress", pts->sigma) && !gk_vtk_close(&v);
    }
    free(xyz), free(vel), free(conn), free(fld);
    if (!ok) fprintf(stderr, "warning: could not write %s\n", path);
    return !ok;
}

/* one field on the points as coloured dots */
static int mpd_svg_field(const char *path, const char *title, const mpd_rves *f, const gk_mpm_points *pts,
                         int k, double dot) {
    gk_err err;
    int n = pts->n, p, bad;
    double *xy = (double *)malloc(2 * (size_t)n * sizeof *xy), *fld = mpd_all_fields(f, pts);
    bad = !xy || !fld;
    if (!bad) {
        for (p = 0; p < n; ++p) xy[2 * p] = pts->x[0][p], xy[2 * p + 1] = pts->x[1][p];
        bad =
            gk_svg_field(path, title, mpd_field_names[k], n, 1, xy, fld + (size_t)k * n, dot, &err) != GK_OK;
    }
    free(xy), free(fld);
    if (bad) fprintf(stderr, "warning: could not write %s\n", path);
    return bad;
}

/* -------------------------------------------------------- checkpoints */
/* File: magic, driver tag, nblob x (size, bytes) of driver data, the points
 * (every array), the accumulated strains and the RVE states. Written to a
 * temporary file then renamed, so a crash never leaves half a checkpoint. */
#define MPD_CK_MAGIC "GKMPMDEM1"

static int mpd_points_io(gk_mpm_points *pts, FILE *fp, int write) {
    size_t n = (size_t)pts->n;
    int k, ok = 1;
    double *a1[] = {pts->x[0],    pts->x[1], pts->v[0], pts->v[1], pts->fext[0],
                    pts->fext[1], pts->m,    pts->vol0, pts->vol,  pts->lp};
    double *a9[] = {pts->F, pts->L, pts->sigma, pts->C};
    for (k = 0; k < (int)(sizeof a1 / sizeof *a1); ++k)
        ok &= (write ? fwrite(a1[k], sizeof(double), n, fp) : fread(a1[k], sizeof(double), n, fp)) == n;
    for (k = 0; k < (int)(sizeof a9 / sizeof *a9); ++k)
        ok &= (write ? fwrite(a9[k], sizeof(double), 9 * n, fp) : fread(a9[k], sizeof(double), 9 * n, fp)) ==
              9 * n;
    return ok;
}

static int mpd_ck_write(const char *dir, const char *tag, void *const *blob, const size_t *size, int nblob,
                        gk_mpm_points *pts, const mpd_rves *f) {
    char path[1200], tmp[1300], tg[16];
    FILE *fp;
    int k, ok = 1;
    size_t cap = 0;
    void *buf = NULL;
    snprintf(path, sizeof path, "%s/checkpoint.bin", dir);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    fp = fopen(tmp, "wb");
    if (!fp) return fprintf(stderr, "error: cannot write %s\n", tmp), 1;
    memset(tg, 0, sizeof tg);
    strncpy(tg, tag, sizeof tg - 1);
    ok &= fwrite(MPD_CK_MAGIC, 1, 9, fp) == 9 && fwrite(tg, 1, sizeof tg, fp) == sizeof tg;
    ok &= fwrite(&nblob, sizeof nblob, 1, fp) == 1 && fwrite(&pts->n, sizeof pts->n, 1, fp) == 1;
    for (k = 0; k < nblob; ++k)
        ok &= fwrite(&size[k], sizeof *size, 1, fp) == 1 && fwrite(blob[k], 1, size[k], fp) == size[k];
    ok &= mpd_points_io(pts, fp, 1);
    ok &= fwrite(f->eps, sizeof(double), 9 * (size_t)f->n, fp) == 9 * (size_t)f->n;
    ok &= fwrite(&f->dem_steps, sizeof f->dem_steps, 1, fp) == 1;
    for (k = 0; k < f->n && ok; ++k) {
        size_t n = gk_rve_state_size(&f->rve[k]);
        if (n > cap) {
            free(buf);
            cap = n;
            buf = malloc(cap);
            if (!buf) ok = 0;
        }
        if (ok && gk_rve_save(&f->rve[k], buf, cap, &n)) ok = 0;
        ok &= fwrite(&n, sizeof n, 1, fp) == 1 && fwrite(buf, 1, n, fp) == n;
    }
    free(buf);
    ok &= fclose(fp) == 0;
    if (!ok || rename(tmp, path)) return fprintf(stderr, "error: cannot write %s\n", path), 1;
    return 0;
}

/* blobs of the sizes given are read into blob[k] (size[k] must match);
 * blob sizes of 0 mean "variable": that blob is malloc'ed into *blob[k] and
 * its size returned in size[k] */
static gk_result mpd_ck_read(const char *dir, const char *tag, void **blob, size_t *size, int nblob,
                             gk_mpm_points *pts, mpd_rves *f, gk_err *err) {
    char path[1200], magic[9], tg[16], want[16];
    FILE *fp;
    int k, nb = 0, np = 0, ok = 1;
    snprintf(path, sizeof path, "%s/checkpoint.bin", dir);
    fp = fopen(path, "rb");
    if (!fp) return gk_err_set(err, GK_ERR_IO, "cannot open %s", path);
    memset(want, 0, sizeof want);
    strncpy(want, tag, sizeof want - 1);
    ok &= fread(magic, 1, 9, fp) == 9 && !memcmp(magic, MPD_CK_MAGIC, 9);
    ok &= fread(tg, 1, sizeof tg, fp) == sizeof tg && !memcmp(tg, want, sizeof tg);
    ok &=
        fread(&nb, sizeof nb, 1, fp) == 1 && nb == nblob && fread(&np, sizeof np, 1, fp) == 1 && np == pts->n;
    if (!ok) {
        fclose(fp);
        return gk_err_set(err, GK_ERR_FORMAT, "%s is not a %s checkpoint of this model (same flags needed)",
                          path, tag);
    }
    for (k = 0; k < nblob && ok; ++k) {
        size_t s = 0;
        ok &= fread(&s, sizeof s, 1, fp) == 1 && s < ((size_t)1 << 34);
        if (!ok) break;
        if (size[k] == 0) {
            void *b = malloc(s ? s : 1);
            ok &= b && fread(b, 1, s, fp) == s;
            *(void **)blob[k] = b;
            size[k] = s;
        } else
            ok &= s == size[k] && fread(blob[k], 1, s, fp) == s;
    }
    ok = ok && mpd_points_io(pts, fp, 0);
    ok = ok && fread(f->eps, sizeof(double), 9 * (size_t)f->n, fp) == 9 * (size_t)f->n;
    ok = ok && fread(&f->dem_steps, sizeof f->dem_steps, 1, fp) == 1;
    for (k = 0; k < f->n && ok; ++k) {
        size_t n;
        void *buf;
        ok &= fread(&n, sizeof n, 1, fp) == 1 && n < ((size_t)1 << 31);
        if (!ok) break;
        buf = malloc(n);
        ok &= buf && fread(buf, 1, n, fp) == n && gk_rve_restore(&f->rve[k], buf, n) == GK_OK;
        free(buf);
    }
    fclose(fp);
    if (!ok) return gk_err_set(err, GK_ERR_FORMAT, "%s: truncated or corrupt checkpoint", path);
    return GK_OK;
}

/* the MPM options every driver uses (seed 003: USF, PIC/FLIP blend) */
static gk_mpm_def mpd_mpm_def(const mpd_opts *o) {
    gk_mpm_def d = gk_mpm_def_default();
    d.basis = o->basis;
    d.transfer = GK_MPM_PIC_FLIP;
    d.scheme = GK_MPM_USF;
    d.alpha = o->alpha;
    d.threads = o->threads;
    return d;
}

/* ghost node layers a basis needs outside the material (support radius) */
static int mpd_ghost_layers(gk_mpm_basis b) { return b == GK_MPM_CUBIC ? 3 : 2; }

/* "12.3 s" / "4.5 min" / "2.1 h" */
static const char *mpd_duration(double s, char *buf, size_t cap) {
    if (s < 120.0)
        snprintf(buf, cap, "%.1f s", s);
    else if (s < 7200.0)
        snprintf(buf, cap, "%.1f min", s / 60.0);
    else
        snprintf(buf, cap, "%.1f h", s / 3600.0);
    return buf;
}

#endif /* MPMDEM_H */
