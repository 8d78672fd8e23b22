/* mpmdem_collapse.c - the MPMxDEM granular column collapse of seed 003
 * (Liang & Zhao, Sec 3.5): a column 1 m wide and 1 m high (aspect a = 1) of
 * material points, each with its own periodic RVE pre-consolidated to the
 * geostatic pressure of its depth, collapses under gravity when the smooth
 * gate on its right is removed at t = 0. Left: symmetry plane (roller);
 * base: rigid, Coulomb friction 0.4. Seed 003 reports, with 16 x 16 cells,
 * 4 points per cell and 1000-disk RVEs: run-out d* = (d_f - d_0)/d_0 = 1.8
 * (eq 48; experiments 1.6), the kinetic energy peaking at ~0.1 E_p0 near
 * 0.4 s, the dissipated energy ending at ~0.55 E_p0, the deposit at rest by
 * ~1.6 s.
 *
 *   build/mpmdem_collapse                         # 8 x 8 cells, 1 point each
 *   build/mpmdem_collapse --nx 16 --ppc 2         # the seed's size, 1024 RVEs
 *
 * Model. Square cells h = width / nx; the column holds nx x ny cells (ny =
 * nx height / width) with ppc^2 points each (uGIMP by default). The grid
 * reaches --domain widths to the right (the deposit must stay inside) and
 * carries ghost layers below and left: the x- face is a ROLLER and the y-
 * face a Coulomb FRICTION wall (gk_mpm_grid_set_bc), both acting on the
 * ghost layers plus the wall plane (x = 0, y = 0). Gravity -g e_y on every
 * point (gk_mpm_def.gravity). USF with the PIC/FLIP blend, alpha_PIC = 5e-4
 * (seed 003's value for this case; the other drivers default to 0.1).
 *
 * Geostatic pre-consolidation. The column depth is cut into --levels equal
 * bins; bin k (from the top) has pressure p_k = max(rho g z_k, rho g h/2),
 * z_k its mid-depth and rho the bulk density of the packing as shipped; the
 * floor rho g h/2 (the pressure half a cell deep) keeps the top RVE from
 * being unloaded to nothing. One RVE is consolidated isotropically to each
 * p_k (mpd_prepare_rve, friction on, so the packing's fabric is kept and the
 * void ratio follows the pressure) and every point starts from the state of
 * its bin (mpd_rves_create's pick callback); its mass is the bin's bulk
 * density times its area, its stress the RVE's Love stress. With --levels =
 * the number of point rows every row has its own pressure.
 *
 * Time step and DEM steps. dt = cfl h / c with c from the stiffest prepared
 * RVE's Taylor tangent (mpmdem.h). This is a dynamic flow, so the DEM steps
 * per MPM step are capped by default at the REAL-TIME count
 * dem_max = ceil(dt / dt_DEM): an RVE never runs more DEM time than the MPM
 * step lasts (a flowing point cannot be more quasi-static than the flow).
 * Below the cap the rule of mpmdem.h decides (--dem-rule adaptive, the
 * default: the RVE deforms at inertial number <= --dem-inertial and relaxes
 * while unbalanced; at the low pressures of the column, 1-20 kPa, flowing
 * points hit the cap, i.e. their RVEs run exactly in real time, and the
 * dead zone runs few steps; --dem-rule strain: <= --dem-strain per step).
 * --dem-max overrides the cap.
 *
 * Measures (every --every seconds, CSV row):
 *   front: the points connected to the deposit are found by a flood fill
 *     from the point nearest the corner (0, 0); two points are connected
 *     when their deformed boxes (half-extents (|F_00| + |F_01|) l0 and
 *     (|F_10| + |F_11|) l0 about the centre, l0 = h / (2 ppc)) overlap in x
 *     and in y within --front-tol times their extents. The front d_f is the
 *     furthest centre of a connected point plus l0 (the paper: "the farthest
 *     point ... after removing the scatter points, which is not in contact
 *     with the main deposit"; + l0 makes d_f = d_0 at t = 0), and
 *     d* = (d_f - d_0) / d_0 [eq 48]. front_box is the edge of the furthest
 *     deformed box instead (larger: the front points are stretched several
 *     times along the base), front_raw the furthest centre + l0 over all
 *     points, scattered ones included.
 *   height: the highest connected centre + l0 (initially H).
 *   energies [seed 003 Sec 3.5.2]: E_p0 = sum m g y0, E_p = sum m g y,
 *     E_k = sum m |v|^2 / 2 (point velocities), E_d = E_p0 - E_p - E_k,
 *     all divided by E_p0 (E_d includes the elastic energy released from
 *     the pre-consolidated RVEs, ~1e-3 E_p0, hence E_d dips slightly below
 *     zero in the first steps).
 *   rest: the first row after the peak of E_k with E_k < --rest-frac E_p0;
 *     the run stops --rest-hold s later (unless --no-stop or E_k rises
 *     again).
 *   mass: sum of point masses and sum of grid node masses after the last
 *     P2G (equal while every point's support lies in the grid).
 *   loose_rves: RVEs without a contact (zero stress: the free surface and
 *     the thin flowing front; physical, counted), frozen_rves: RVEs that
 *     refused the last dH (below).
 *
 * RVE cells that get too thin. gk_rve_deform refuses (GK_ERR_CELL) a dH
 * that would leave the periodic cell narrower than twice the interaction
 * distance 2 (2 r_max + skin) = 0.029 m for the 400-disk cell of 0.198 m.
 * The points at the flow front slide along the base stretched ~8x and
 * squeezed to a few centimetres (F_yy ~ 0.17); their RVEs have almost no
 * contacts by then. In the default run the thinnest cell comes to 0.032 m,
 * 10 % above the limit (with a Verlet skin of 0.4 mean radii, limit 0.032 m,
 * the front point's RVE was refused at t = 1.12 s). --thin-cell freeze
 * (default): that RVE skips the increment (no DEM steps, its last stress
 * kept; the MPM strain still accumulates) and takes the next dH that fits;
 * every newly frozen point is named on stderr with its F, pressure and
 * contacts, and counted (frozen_rves, thin_points in RESULT). --thin-cell
 * stop ends the run at the first refusal, naming the point (mpd_step /
 * mpd_stress of mpmdem.h, which this option uses).
 *
 * Outputs in --out DIR: collapse.csv, collapse_energy.svg, collapse_front.svg,
 * eps_q_T.svg and velocity_T.svg at the --snapshots times and at the end,
 * points_NNNNNN.vtk (first, last, every --vtk-every steps),
 * checkpoint.bin; a RESULT line.
 */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_base.h"
#include "gk_dem.h"
#include "gk_homog.h"
#include "gk_io.h"
#include "gk_mpm.h"
#include "mpmdem.h"

#define CL_MAX_LEVELS 64
#define CL_MAX_SNAP 16
/* main's error exit after the first allocation: message, status 1, cleanup */
#define CL_FAIL(...)                  \
    do {                              \
        fprintf(stderr, __VA_ARGS__); \
        status = 1;                   \
        goto done;                    \
    } while (0)

typedef struct cl_opts {
    int nx, levels, stop_at_rest, thin_freeze;
    double width, height, mu, gravity, t_end, every, domain, front_tol, rest_frac, rest_hold;
    int nsnap;
    double snap[CL_MAX_SNAP];
} cl_opts;

typedef struct cl_row { /* one CSV row */
    double t, front, front_box, front_raw, height, ek, ep, ed, mass, mass_grid, dem_mean, secs;
    int loose, frozen;
} cl_row;

/* the state a checkpoint must carry besides points, RVEs and rows */
typedef struct cl_state {
    long step;
    double t, dt, Ep0, next_out;
    int dem_max, nsnap;
    double ek_peak, t_ek_peak, t_rest;
    int at_rest;
    double acc_dem; /* DEM steps per point, summed over the steps since the last row */
    long nacc;
    long long thin_total;
} cl_state;

/* the stress update with the thin-cell policy (mpd_stress + freeze) */
typedef struct cl_ctx {
    mpd_rves *f;
    int *thin;     /* refused MPM steps per point (checkpointed) */
    int thin_step; /* refusals in the last step */
    long warned;   /* warnings printed */
    double t;      /* time at the start of the step, for the warnings */
} cl_ctx;

static void usage(FILE *fp, const mpd_opts *d) {
    fprintf(
        fp,
        "mpmdem_collapse - MPMxDEM granular column collapse of seed 003 Sec 3.5: every material point has\n"
        "a periodic RVE pre-consolidated to the geostatic pressure of its depth; gravity, symmetry plane\n"
        "on the left, rigid base with Coulomb friction, the gate on the right removed at t = 0.\n\n"
        "usage: mpmdem_collapse [options]\n"
        "  --nx N                 cells across the column width (default 8; the seed: 16 with --ppc 2)\n"
        "  --width D0 --height H0 column [m] (default 1 x 1, aspect a = 1); H0 / (D0/nx) must be whole\n"
        "  --mu M                 Coulomb friction of the base (default 0.4)\n"
        "  --gravity G            [m/s^2] (default 9.81)\n"
        "  --t-end T              simulated time [s] (default 2.0; the run stops earlier at rest, see\n"
        "                         --rest-frac; the seed's deposit rests by 1.6 s)\n"
        "  --every DT             time between CSV rows and progress lines [s] (default 0.01)\n"
        "  --snapshots T1,T2,...  times of the eps_q / velocity SVG snapshots (default 0.2,0.4,0.7,1,1.3)\n"
        "  --levels N             pressure levels (depth bins) of the pre-consolidation (default: one per\n"
        "                         point row, at most 8); p_k = max(rho g z_k, rho g h/2)\n"
        "  --domain X             grid length to the right of the symmetry plane, in column widths\n"
        "                         (default 5)\n"
        "  --front-tol F          connection tolerance of the front detection (default 0.5)\n"
        "  --rest-frac F          at rest when E_k < F E_p0 after the E_k peak (default 5e-3)\n"
        "  --rest-hold T          stop once at rest for T seconds (default 0.05)\n"
        "  --no-stop              run to --t-end even when at rest\n"
        "  --thin-cell freeze|stop  an RVE cell too thin for the next dH: keep that RVE frozen (no DEM\n"
        "                         steps, stress kept), name and count it (default), or end the run\n"
        "  --help                 this text\n"
        "defaults that differ from the common list below: --alpha 5e-4 (seed 003, column collapse);\n"
        "--dem-max = ceil(dt_MPM / dt_DEM), the real-time count (printed at start), unless given.\n"
        "The seed's RVEs have 1000 disks (Table 3: r 3-7 mm, E 600 MPa, kt/kn 0.8, friction 28.6 deg,\n"
        "no rolling); the default packing is the 400-disk one (same contact law): use --packing for\n"
        "another, e.g. made by build/gk_pack --dim 2 --n 1000 --pressure 2e4 --target-void-ratio 0.2.\n\n");
    mpd_usage_common(fp, d);
    fprintf(fp, "\nends with: RESULT dstar=... dstar_paper=1.8 Ek_peak_over_Ep0=... t_Ek_peak=... "
                "Ed_final_over_Ep0=...\n"
                "           final_height=... t_rest=... (-1: not at rest) n_rves=... mpm_steps=... dt=... "
                "dem_max=...\n"
                "           thin_points=... seconds_per_step=... seconds_per_step_per_1000_rves=... "
                "total_seconds=...\n"
                "exit status: 0 done, 1 setup failed, 2 bad arguments, 3 the simulation failed (message)\n");
}

static int parse_times(const char *s, double *t, int cap) {
    int n = 0;
    char buf[512], *tok, *save = NULL;
    if (strlen(s) >= sizeof buf) return -1;
    strcpy(buf, s);
    for (tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        double v;
        if (n == cap || mpd_num(tok, &v) || v < 0) return -1;
        if (n > 0 && v <= t[n - 1]) return -1;
        t[n++] = v;
    }
    return n;
}

/* ---------------------------------------------------- initial state */
typedef struct cl_pick {
    const gk_mpm_points *pts;
    double height;
    int levels;
} cl_pick;

static int level_of(const cl_pick *c, double y) {
    int k = (int)floor((c->height - y) / (c->height / c->levels));
    return k < 0 ? 0 : k >= c->levels ? c->levels - 1 : k;
}

static int pick_level(int p, void *user) {
    cl_pick *c = (cl_pick *)user;
    return level_of(c, c->pts->x[1][p]);
}

/* ------------------------------------------------------ stress update */
static gk_result cl_stress(gk_mpm_points *pts, double dt, void *user, gk_err *err) {
    cl_ctx *c = (cl_ctx *)user;
    mpd_rves *f = c->f;
    int p, nthin = 0;
    long long total = 0;
    GK_OMP(parallel for num_threads(f->o->threads) schedule(dynamic, 2) reduction(+ : total))
    for (p = 0; p < pts->n; ++p) {
        double dH[9];
        int k, ns;
        gk_mpm_point_dH(pts, p, dt, dH);
        dH[2] = dH[5] = dH[6] = dH[7] = dH[8] = 0.0; /* plane */
        if (f->o->dem_adaptive) {                    /* as mpd_stress */
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
        if (f->status[p] == GK_ERR_CELL) ns = 0; /* refused up front: the RVE is unchanged */
        f->nsub[p] = ns;
        total += ns;
        if (f->status[p] && f->status[p] != GK_ERR_CELL) continue;
        if (!f->status[p]) mpd_rve_sigma(&f->rve[p], pts->sigma + 9 * (size_t)p);
        for (k = 0; k < 9; ++k) f->eps[9 * (size_t)p + k] += 0.5 * (dH[k] + dH[3 * (k % 3) + k / 3]);
    }
    f->dem_steps += total;
    for (p = 0; p < pts->n; ++p) {
        if (!f->status[p]) continue;
        if (f->status[p] != GK_ERR_CELL)
            return gk_err_set(err, (gk_result)f->status[p], "RVE of point %d at (%.4g, %.4g) m: %s", p,
                              pts->x[0][p], pts->x[1][p], gk_rve_error(&f->rve[p]));
        ++nthin;
        if (c->thin[p]++ == 0 && c->warned++ < 20) {
            const double *F = pts->F + 9 * (size_t)p;
            double s9[9];
            gk_rve_stress(&f->rve[p], s9);
            fprintf(
                stderr,
                "warning: t = %.4f s: point %d at (%.4g, %.4g) m, F = [%.3g %.3g; %.3g %.3g]: its RVE "
                "refuses "
                "dH (%s); frozen: no DEM steps, its stress kept (p = %.4g Pa, %d contacts) until a dH fits "
                "again\n",
                c->t, p, pts->x[0][p], pts->x[1][p], F[0], F[1], F[3], F[4], gk_rve_error(&f->rve[p]),
                gk_stress_p(s9, 2), f->rve[p].ncontacts);
        }
    }
    c->thin_step = nthin;
    return GK_OK;
}

/* -------------------------------------------------------- measures */
typedef struct cl_measure {
    double front, front_box, front_raw, height, ep, ek, mass;
    int connected, loose;
} cl_measure;

/* flood fill from the point nearest (0, 0) over overlapping deformed boxes */
static int measure(const gk_mpm_points *pts, const mpd_rves *f, double l0, double tol, double g,
                   cl_measure *m, int *work) {
    int n = pts->n, p, q, seed = 0, head = 0, tail = 0;
    double *ex = (double *)malloc(2 * (size_t)n * sizeof *ex), *ey, best = 1e300, mom[3];
    char *in = (char *)calloc((size_t)n, 1);
    if (!ex || !in) {
        free(ex), free(in);
        return 1;
    }
    ey = ex + n;
    memset(m, 0, sizeof *m);
    m->front_raw = -1e300;
    for (p = 0; p < n; ++p) {
        const double *F = pts->F + 9 * (size_t)p;
        ex[p] = (fabs(F[0]) + fabs(F[1])) * l0;
        ey[p] = (fabs(F[3]) + fabs(F[4])) * l0;
        if (pts->x[0][p] + pts->x[1][p] < best) best = pts->x[0][p] + pts->x[1][p], seed = p;
        if (pts->x[0][p] + l0 > m->front_raw) m->front_raw = pts->x[0][p] + l0;
        m->ep += pts->m[p] * g * pts->x[1][p];
        if (f->rve[p].ncontacts == 0) ++m->loose;
    }
    gk_mpm_points_totals(pts, &m->mass, mom, &m->ek);
    work[tail++] = seed, in[seed] = 1;
    m->front = m->front_box = m->height = -1e300;
    while (head < tail) {
        double xp, yp;
        p = work[head++];
        xp = pts->x[0][p], yp = pts->x[1][p];
        if (xp + l0 > m->front) m->front = xp + l0;
        if (xp + ex[p] > m->front_box) m->front_box = xp + ex[p];
        if (yp + l0 > m->height) m->height = yp + l0;
        for (q = 0; q < n; ++q)
            if (!in[q] && fabs(pts->x[0][q] - xp) <= (1 + tol) * (ex[p] + ex[q]) &&
                fabs(pts->x[1][q] - yp) <= (1 + tol) * (ey[p] + ey[q]))
                in[q] = 1, work[tail++] = q;
    }
    m->connected = tail;
    free(ex), free(in);
    return 0;
}

/* ---------------------------------------------------------- outputs */
static void write_csv(const char *out, const cl_row *r, int n, double d0) {
    char path[1200];
    FILE *fp;
    int k;
    snprintf(path, sizeof path, "%s/collapse.csv", out);
    fp = fopen(path, "w");
    if (!fp) {
        fprintf(stderr, "warning: cannot write %s\n", path);
        return;
    }
    fprintf(fp, "time,front,dstar,front_box,front_raw,height,Ek_over_Ep0,Ep_over_Ep0,Ed_over_Ep0,mass,"
                "mass_grid,loose_rves,frozen_rves,dem_steps_per_point,seconds\n");
    for (k = 0; k < n; ++k)
        fprintf(fp, "%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.9g,%.9g,%d,%d,%.4g,%.3f\n", r[k].t,
                r[k].front, (r[k].front - d0) / d0, r[k].front_box, r[k].front_raw, r[k].height, r[k].ek,
                r[k].ep, r[k].ed, r[k].mass, r[k].mass_grid, r[k].loose, r[k].frozen, r[k].dem_mean,
                r[k].secs);
    fclose(fp);
}

static void write_plots(const char *out, const cl_row *r, int n, double d0) {
    double *x = (double *)malloc((size_t)(n + 1) * sizeof *x),
           *y1 = (double *)malloc((size_t)(n + 1) * sizeof *y1),
           *y2 = (double *)malloc((size_t)(n + 1) * sizeof *y2),
           *y3 = (double *)malloc((size_t)(n + 1) * sizeof *y3);
    double tx[2], ty1[2], ty2[2], ty3[2];
    char path[1200];
    gk_err err;
    gk_plot pl;
    int k, s;
    if (x && y1 && y2 && y3 && n > 0) {
        for (k = 0; k < n; ++k) x[k] = r[k].t, y1[k] = r[k].ek, y2[k] = r[k].ep, y3[k] = r[k].ed;
        tx[0] = 0, tx[1] = x[n - 1] > 1.6 ? x[n - 1] : 1.6;
        gk_plot_init(&pl, "MPMxDEM column collapse: energies / E_p0 (seed 003 Fig 27)", "time [s]",
                     "energy / E_p0");
        gk_plot_add(&pl, x, y2, n, "E_p potential");
        gk_plot_add(&pl, x, y1, n, "E_k kinetic");
        gk_plot_add(&pl, x, y3, n, "E_d dissipated");
        ty1[0] = ty1[1] = 0.55;
        s = gk_plot_add(&pl, tx, ty1, 2, "seed 003: E_d final 0.55");
        if (s >= 0) pl.s[s].dashed = 1;
        ty2[0] = ty2[1] = 0.1;
        s = gk_plot_add(&pl, tx, ty2, 2, "seed 003: E_k peak 0.1 (~0.4 s)");
        if (s >= 0) pl.s[s].dashed = 1;
        ty3[0] = ty3[1] = 0.63;
        s = gk_plot_add(&pl, tx, ty3, 2, "Lajeunesse: E_d = 1 - 0.74/2a");
        if (s >= 0) pl.s[s].dashed = 1;
        snprintf(path, sizeof path, "%s/collapse_energy.svg", out);
        gk_plot_svg(&pl, path, &err);

        for (k = 0; k < n; ++k)
            y1[k] = (r[k].front - d0) / d0, y2[k] = (r[k].front_box - d0) / d0,
            y3[k] = (r[k].front_raw - d0) / d0;
        gk_plot_init(&pl, "MPMxDEM column collapse: run-out d* = (d_f - d_0)/d_0 (seed 003 eq 48)",
                     "time [s]", "(front - d_0) / d_0");
        gk_plot_add(&pl, x, y1, n, "furthest connected point (centre + l0): d*");
        gk_plot_add(&pl, x, y2, n, "edge of its deformed box (F)");
        gk_plot_add(&pl, x, y3, n, "furthest point, scattered included");
        ty1[0] = ty1[1] = 1.8;
        s = gk_plot_add(&pl, tx, ty1, 2, "seed 003: d* = 1.8");
        if (s >= 0) pl.s[s].dashed = 1;
        ty2[0] = ty2[1] = 1.6;
        s = gk_plot_add(&pl, tx, ty2, 2, "experiments (Lube): 1.6");
        if (s >= 0) pl.s[s].dashed = 1;
        snprintf(path, sizeof path, "%s/collapse_front.svg", out);
        gk_plot_svg(&pl, path, &err);
    }
    free(x), free(y1), free(y2), free(y3);
}

/* eps_q and |v| of the points as coloured dots */
static void snapshot(const char *out, const char *tag, double t, const mpd_rves *f, const gk_mpm_points *pts,
                     double dot) {
    char path[1200], title[200];
    int n = pts->n, p;
    double *xy = (double *)malloc(2 * (size_t)n * sizeof *xy), *v = (double *)malloc((size_t)n * sizeof *v);
    gk_err err;
    snprintf(path, sizeof path, "%s/eps_q_%s.svg", out, tag);
    snprintf(title, sizeof title, "deviatoric strain eps_q at t = %.3f s (seed 003 Fig 26)", t);
    mpd_svg_field(path, title, f, pts, 0, dot);
    if (!xy || !v) {
        free(xy), free(v);
        return;
    }
    for (p = 0; p < n; ++p) {
        xy[2 * p] = pts->x[0][p], xy[2 * p + 1] = pts->x[1][p];
        v[p] = sqrt(pts->v[0][p] * pts->v[0][p] + pts->v[1][p] * pts->v[1][p]);
    }
    snprintf(path, sizeof path, "%s/velocity_%s.svg", out, tag);
    snprintf(title, sizeof title, "speed |v| [m/s] at t = %.3f s (seed 003 Fig 26)", t);
    if (gk_svg_field(path, title, "|v| [m/s]", n, 1, xy, v, dot, &err))
        fprintf(stderr, "warning: could not write %s\n", path);
    free(xy), free(v);
}

/* a CSV row of the current state; resets the DEM-step accumulator */
static int make_row(cl_row *r, cl_state *S, const gk_mpm_points *pts, const mpd_rves *F, const gk_mpm_grid *g,
                    double l0, const cl_opts *b, double t_start, int *work) {
    cl_measure m;
    double mg = 0;
    size_t i;
    int p;
    if (measure(pts, F, l0, b->front_tol, b->gravity, &m, work)) return 1;
    for (i = 0; i < g->nnode; ++i) mg += g->m[i];
    memset(r, 0, sizeof *r);
    for (p = 0; p < pts->n; ++p) r->frozen += F->status[p] == GK_ERR_CELL;
    r->t = S->t, r->front = m.front, r->front_box = m.front_box, r->front_raw = m.front_raw;
    r->height = m.height;
    r->ep = m.ep / S->Ep0, r->ek = m.ek / S->Ep0, r->ed = 1 - r->ep - r->ek;
    r->mass = m.mass, r->mass_grid = S->step > 0 ? mg : m.mass, r->loose = m.loose;
    r->dem_mean = S->nacc ? S->acc_dem / S->nacc : 0;
    r->secs = gk_wtime() - t_start;
    S->acc_dem = 0, S->nacc = 0;
    return 0;
}

static int ck_write(const char *out, cl_state *S, cl_row *rows, int nrows, int *thin, gk_mpm_points *pts,
                    const mpd_rves *F) {
    void *blob[3];
    size_t size[3];
    blob[0] = S, size[0] = sizeof *S;
    blob[1] = thin, size[1] = (size_t)pts->n * sizeof *thin;
    blob[2] = rows, size[2] = (size_t)nrows * sizeof *rows;
    return mpd_ck_write(out, "collapse", blob, size, 3, pts, F);
}

int main(int argc, char **argv) {
    mpd_opts o, od;
    cl_opts b;
    mpd_proto P;
    gk_rve_state st[CL_MAX_LEVELS];
    double lev_p[CL_MAX_LEVELS], lev_rho[CL_MAX_LEVELS], lev_e[CL_MAX_LEVELS], lev_M[CL_MAX_LEVELS],
        lev_pa[CL_MAX_LEVELS];
    mpd_rves F;
    gk_mpm_grid g;
    gk_mpm_points pts;
    gk_mpm_def def;
    cl_state S;
    cl_ctx C;
    cl_pick pk;
    cl_row *rows = NULL;
    int nrows = 0, caprows = 0, i, k, status = 0, ny, rows_pts, dem_max_given = 0, *work = NULL, *thin = NULL;
    double h, c, Mmax = 0, rho_ref, lo[3], hi[3], org[3], t_start, t0, l0, prep_secs;
    long nsteps_total, step0;
    gk_err err;
    gk_result res;
    char buf[64], buf2[64], path[1200], tag[32], rule[96];
    int n[3];

    memset(&P, 0, sizeof P), memset(&F, 0, sizeof F), memset(&g, 0, sizeof g), memset(&pts, 0, sizeof pts);
    for (k = 0; k < CL_MAX_LEVELS; ++k) gk_rve_state_init(&st[k], NULL);
    mpd_opts_default(&od, "build/mpmdem_collapse");
    od.alpha = 5e-4;
    o = od;
    memset(&b, 0, sizeof b);
    b.nx = 8, b.levels = 0, b.stop_at_rest = 1, b.thin_freeze = 1;
    b.width = 1.0, b.height = 1.0, b.mu = 0.4, b.gravity = 9.81, b.t_end = 2.0, b.every = 0.01;
    b.domain = 5.0, b.front_tol = 0.5, b.rest_frac = 5e-3, b.rest_hold = 0.05;
    b.nsnap = parse_times("0.2,0.4,0.7,1,1.3", b.snap, CL_MAX_SNAP);
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i];
        double v;
        int r;
        if (!strcmp(a, "--dem-max")) dem_max_given = 1;
        r = mpd_parse_common(&o, argc, argv, &i);
        if (r < 0) return 2;
        if (r > 0) continue;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) return usage(stdout, &od), 0;
        if (!strcmp(a, "--no-stop")) {
            b.stop_at_rest = 0;
            continue;
        }
        if (i + 1 >= argc) return fprintf(stderr, "mpmdem_collapse: %s needs a value (see --help)\n", a), 2;
        if (!strcmp(a, "--thin-cell")) {
            const char *val = argv[++i];
            if (!strcmp(val, "stop"))
                b.thin_freeze = 0;
            else if (!strcmp(val, "freeze"))
                b.thin_freeze = 1;
            else
                return fprintf(stderr, "mpmdem_collapse: --thin-cell %s: use stop or freeze\n", val), 2;
            continue;
        }
        if (!strcmp(a, "--snapshots")) {
            b.nsnap = parse_times(argv[++i], b.snap, CL_MAX_SNAP);
            if (b.nsnap < 0)
                return fprintf(stderr,
                               "mpmdem_collapse: --snapshots %s: need up to %d increasing times >= 0, "
                               "comma-separated\n",
                               argv[i], CL_MAX_SNAP),
                       2;
            continue;
        }
        if (mpd_num(argv[i + 1], &v))
            return fprintf(stderr, "mpmdem_collapse: %s %s: not a number\n", a, argv[i + 1]), 2;
        if (!strcmp(a, "--nx"))
            b.nx = v == floor(v) && v >= 1 && v <= 1000 ? (int)v : -1;
        else if (!strcmp(a, "--levels"))
            b.levels = v == floor(v) && v >= 1 && v <= CL_MAX_LEVELS ? (int)v : -1;
        else if (!strcmp(a, "--width"))
            b.width = v;
        else if (!strcmp(a, "--height"))
            b.height = v;
        else if (!strcmp(a, "--mu"))
            b.mu = v;
        else if (!strcmp(a, "--gravity"))
            b.gravity = v;
        else if (!strcmp(a, "--t-end"))
            b.t_end = v;
        else if (!strcmp(a, "--every"))
            b.every = v;
        else if (!strcmp(a, "--domain"))
            b.domain = v;
        else if (!strcmp(a, "--front-tol"))
            b.front_tol = v;
        else if (!strcmp(a, "--rest-frac"))
            b.rest_frac = v;
        else if (!strcmp(a, "--rest-hold"))
            b.rest_hold = v;
        else
            return fprintf(stderr, "mpmdem_collapse: unknown option %s (see --help)\n", a), 2;
        ++i;
    }
    if (b.nx < 1) return fprintf(stderr, "mpmdem_collapse: --nx needs an integer in [1, 1000]\n"), 2;
    if (b.levels < 0)
        return fprintf(stderr, "mpmdem_collapse: --levels needs an integer in [1, %d]\n", CL_MAX_LEVELS), 2;
    {
        struct {
            const char *flag, *need;
            int ok;
        } chk[] = {{"--width", "a positive length", b.width > 0},
                   {"--height", "a positive length", b.height > 0},
                   {"--mu", "a friction coefficient >= 0", b.mu >= 0},
                   {"--gravity", "a positive value", b.gravity > 0},
                   {"--t-end", "a positive time", b.t_end > 0},
                   {"--every", "a positive time", b.every > 0},
                   {"--domain", "at least 1.5 column widths", b.domain >= 1.5},
                   {"--front-tol", "a value >= 0", b.front_tol >= 0},
                   {"--rest-frac", "a value >= 0", b.rest_frac >= 0},
                   {"--rest-hold", "a time >= 0", b.rest_hold >= 0}};
        for (k = 0; k < (int)(sizeof chk / sizeof *chk); ++k)
            if (!chk[k].ok)
                return fprintf(stderr, "mpmdem_collapse: %s: need %s\n", chk[k].flag, chk[k].need), 2;
    }
    h = b.width / b.nx;
    ny = (int)floor(b.height / h + 0.5);
    if (ny < 1 || fabs(ny * h - b.height) > 1e-9 * b.height)
        return fprintf(stderr, "mpmdem_collapse: the height %g is not a whole number of cells %g\n", b.height,
                       h),
               2;
    rows_pts = ny * o.ppc;
    if (b.levels == 0) b.levels = rows_pts < 8 ? rows_pts : 8;
    if (b.levels > rows_pts) b.levels = rows_pts;
    l0 = h / (2.0 * o.ppc);
    if (!dem_max_given) o.dem_max = 1000000; /* placeholder until dt is known */
    if (mpd_check_opts(&o)) return 2;
    if (mpd_mkdir(o.out)) return 1;

    /* ---- the RVEs: bulk density of the packing, then one state per level */
    t0 = gk_wtime();
    if (mpd_proto_open(&P, &o, &err)) CL_FAIL("mpmdem_collapse: %s\n", err.msg);
    if (mpd_prepare_rve(&P, 0.0, &st[0], &err)) CL_FAIL("mpmdem_collapse: %s\n", err.msg);
    rho_ref = P.rho;
    for (k = 0; k < b.levels; ++k) {
        double z = b.height * (k + 0.5) / b.levels;
        lev_p[k] = rho_ref * b.gravity * (z > 0.5 * h ? z : 0.5 * h);
    }
    {
        int bad = 0;
        char msg[GK_ERR_MSG_LEN] = "";
        GK_OMP(parallel for num_threads(o.threads) schedule(dynamic, 1))
        for (k = 0; k < b.levels; ++k) {
            mpd_proto Pk = P;
            gk_err e;
            if (mpd_prepare_rve(&Pk, lev_p[k], &st[k], &e)) {
                GK_OMP(critical) {
                    bad = 1;
                    snprintf(msg, sizeof msg, "%s", e.msg);
                }
                continue;
            }
            lev_rho[k] = Pk.rho, lev_e[k] = Pk.e0, lev_M[k] = Pk.M, lev_pa[k] = Pk.p0;
        }
        if (bad) CL_FAIL("mpmdem_collapse: %s\n", msg);
    }
    for (k = 0; k < b.levels; ++k)
        if (lev_M[k] > Mmax) Mmax = lev_M[k];
    prep_secs = gk_wtime() - t0;

    /* ---- grid: ghost layers left and below, the run-out room to the right, a cell above */
    {
        int gl = mpd_ghost_layers(o.basis), nxd = (int)ceil(b.domain * b.width / h);
        org[0] = -gl * h, org[1] = -gl * h, org[2] = 0;
        n[0] = nxd + 2 * gl + 1, n[1] = ny + 2 * gl + 2, n[2] = 1;
        if (gk_mpm_grid_create(&g, 2, org, h, n, NULL, &err) ||
            gk_mpm_grid_set_bc(&g, 0, GK_MPM_BC_ROLLER, 0.0, gl + 1, &err) ||
            gk_mpm_grid_set_bc(&g, 2, GK_MPM_BC_FRICTION, b.mu, gl + 1, &err))
            CL_FAIL("mpmdem_collapse: %s\n", err.msg);
    }
    lo[0] = 0, lo[1] = 0, lo[2] = 0, hi[0] = b.width, hi[1] = b.height, hi[2] = 0;
    if (gk_mpm_points_create_box(&pts, 2, lo, hi, h, o.ppc, rho_ref, NULL, &err))
        CL_FAIL("mpmdem_collapse: %s\n", err.msg);
    pk.pts = &pts, pk.height = b.height, pk.levels = b.levels;
    if (mpd_rves_create(&F, pts.n, &P, st, pick_level, &pk, &o, &err))
        CL_FAIL("mpmdem_collapse: %s\n", err.msg);
    thin = (int *)calloc((size_t)pts.n, sizeof *thin);
    work = (int *)malloc((size_t)pts.n * sizeof *work);
    if (!thin || !work) CL_FAIL("mpmdem_collapse: out of memory\n");
    memset(&S, 0, sizeof S);
    for (i = 0; i < pts.n; ++i) {
        pts.m[i] = lev_rho[level_of(&pk, pts.x[1][i])] * pts.vol0[i];
        mpd_rve_sigma(&F.rve[i], pts.sigma + 9 * (size_t)i);
        S.Ep0 += pts.m[i] * b.gravity * pts.x[1][i];
    }
    def = mpd_mpm_def(&o);
    def.gravity[1] = -b.gravity;
    c = sqrt(Mmax / rho_ref);
    S.dt = o.cfl * h / c;
    S.dem_max = dem_max_given ? o.dem_max : (int)ceil(S.dt / F.rve[0].dt * (1 - 1e-12));
    S.next_out = b.every;
    S.t_rest = -1;
    if (o.restart) {
        void *blob[3];
        size_t size[3] = {sizeof S, (size_t)pts.n * sizeof *thin, 0};
        cl_row *rr = NULL;
        blob[0] = &S, blob[1] = thin, blob[2] = &rr;
        res = mpd_ck_read(o.restart, "collapse", blob, size, 3, &pts, &F, &err);
        rows = rr; /* freed at the end whatever happened */
        if (res) CL_FAIL("mpmdem_collapse: %s\n", err.msg);
        nrows = caprows = (int)(size[2] / sizeof *rows);
        if (nrows < 1) CL_FAIL("mpmdem_collapse: %s/checkpoint.bin holds no rows\n", o.restart);
        printf("restarted from %s/checkpoint.bin at t = %.4f s (step %ld)\n", o.restart, S.t, S.step);
    }
    o.dem_max = S.dem_max;
    if (mpd_check_opts(&o)) {
        status = 2;
        goto done;
    }
    C.f = &F, C.thin = thin, C.thin_step = 0, C.warned = 0, C.t = 0;
    nsteps_total = (long)ceil(b.t_end / S.dt - 1e-9);

    printf("mpmdem_collapse: column %g x %g m (a = %g), %d x %d cells, h = %.4g m, %d points (= RVEs of %d "
           "disks), basis %d, alpha_PIC %g, base mu %g\n",
           b.width, b.height, b.height / b.width, b.nx, ny, h, pts.n, F.rve[0].n, (int)o.basis, o.alpha,
           b.mu);
    printf(
        "geostatic pre-consolidation: %d levels, p_k = max(rho g z_k, rho g h/2), rho = %.1f kg/m3 (%.1f s "
        "on %d threads)\n",
        b.levels, rho_ref, prep_secs, o.threads);
    for (k = 0; k < b.levels; ++k)
        printf("  level %d: depth %.3f-%.3f m  p target %.4g kPa, reached %.4g kPa, e = %.4f, rho = %.1f, M "
               "= %.4g MPa\n",
               k, b.height * k / b.levels, b.height * (k + 1) / b.levels, lev_p[k] / 1e3, lev_pa[k] / 1e3,
               lev_e[k], lev_rho[k], lev_M[k] / 1e6);
    if (o.dem_adaptive)
        snprintf(rule, sizeof rule, "adaptive, I <= %g, unbalanced <= %g", o.dem_inertial, o.dem_unbalanced);
    else
        snprintf(rule, sizeof rule, "strain, <= %g per DEM step", o.dem_strain);
    printf("MPM dt = %.4g s (cfl %.2f, c = %.1f m/s from M = %.4g MPa); DEM dt = %.3g s; DEM steps per MPM "
           "step %d..%d (%s), rule: %s\n",
           S.dt, o.cfl, c, Mmax / 1e6, F.rve[0].dt, o.dem_min, S.dem_max,
           dem_max_given ? "--dem-max" : "cap = real-time count ceil(dt/dt_DEM)", rule);
    printf("about %ld MPM steps to t = %g s (stops at rest: %s); E_p0 = %.6g J/m\n", nsteps_total, b.t_end,
           b.stop_at_rest ? "yes" : "no", S.Ep0);
    t_start = gk_wtime();
    if (!o.restart) {
        cl_row r;
        snprintf(path, sizeof path, "%s/points_%06ld.vtk", o.out, 0L);
        mpd_write_vtk(path, &F, &pts);
        if (make_row(&r, &S, &pts, &F, &g, l0, &b, t_start, work))
            CL_FAIL("mpmdem_collapse: out of memory\n");
        rows = (cl_row *)malloc(64 * sizeof *rows);
        if (!rows) CL_FAIL("mpmdem_collapse: out of memory\n");
        caprows = 64;
        rows[nrows++] = r;
        if (S.nsnap < b.nsnap && b.snap[S.nsnap] <= 0) {
            snapshot(o.out, "0", 0.0, &F, &pts, l0);
            ++S.nsnap;
        }
    }
    step0 = S.step;
    while (S.t < b.t_end - 0.5 * S.dt) {
        C.t = S.t;
        res = b.thin_freeze ? gk_mpm_step(&g, &pts, &def, S.dt, cl_stress, &C, &err)
                            : mpd_step(&g, &pts, &def, S.dt, &F, NULL, 0, &err);
        if (res) {
            fprintf(stderr, "mpmdem_collapse: step %ld (t = %.4f s): %s%s\n", S.step, S.t, err.msg,
                    err.code == GK_ERR_CELL
                        ? " (a thin RVE cell: --thin-cell freeze, the default, continues past it)"
                        : "");
            status = 3;
            break;
        }
        S.t += S.dt, ++S.step;
        S.thin_total += C.thin_step;
        {
            long long sum = 0;
            for (i = 0; i < pts.n; ++i) sum += F.nsub[i];
            S.acc_dem += (double)sum / pts.n, ++S.nacc;
        }
        if (S.t >= S.next_out - 1e-9 * S.dt) {
            cl_row r;
            if (make_row(&r, &S, &pts, &F, &g, l0, &b, t_start, work))
                CL_FAIL("mpmdem_collapse: out of memory\n");
            S.acc_dem = 0, S.nacc = 0;
            while (S.next_out <= S.t + 1e-9 * S.dt) S.next_out += b.every;
            if (nrows == caprows) {
                caprows = caprows ? 2 * caprows : 64;
                cl_row *nr = (cl_row *)realloc(rows, (size_t)caprows * sizeof *rows);
                if (!nr) CL_FAIL("mpmdem_collapse: out of memory\n");
                rows = nr;
            }
            rows[nrows++] = r;
            write_csv(o.out, rows, nrows, b.width);
            if (r.ek > S.ek_peak) S.ek_peak = r.ek, S.t_ek_peak = r.t;
            if (S.ek_peak > 10 * b.rest_frac && r.t > S.t_ek_peak && r.ek < b.rest_frac) {
                if (!S.at_rest) S.at_rest = 1, S.t_rest = r.t;
            } else
                S.at_rest = 0, S.t_rest = -1;
            while (S.nsnap < b.nsnap && S.t >= b.snap[S.nsnap] - 0.5 * S.dt) {
                snprintf(tag, sizeof tag, "%g", b.snap[S.nsnap]);
                snapshot(o.out, tag, S.t, &F, &pts, l0);
                ++S.nsnap;
            }
            if (!o.quiet) {
                double el = gk_wtime() - t_start;
                long done = S.step - step0;
                fprintf(
                    stderr,
                    "t %.3f/%.3g s  step %ld/%ld  d* %.3f  height %.3f  Ek %.4f Ep %.4f Ed %.4f  loose %d  "
                    "DEM %.1f/pt | %s elapsed, ETA %s\n",
                    r.t, b.t_end, S.step, nsteps_total, (r.front - b.width) / b.width, r.height, r.ek, r.ep,
                    r.ed, r.loose, r.dem_mean, mpd_duration(el, buf, sizeof buf),
                    mpd_duration(done ? el / done * (nsteps_total - S.step) : 0.0, buf2, sizeof buf2));
            }
        }
        if (o.vtk_every && S.step % o.vtk_every == 0) {
            snprintf(path, sizeof path, "%s/points_%06ld.vtk", o.out, S.step);
            mpd_write_vtk(path, &F, &pts);
        }
        if (o.checkpoint_every && S.step % o.checkpoint_every == 0)
            ck_write(o.out, &S, rows, nrows, thin, &pts, &F);
        if (b.stop_at_rest && S.at_rest && S.t >= S.t_rest + b.rest_hold - 1e-9 * S.dt) break;
    }
    {
        double secs = gk_wtime() - t_start, dstar, ekp = 0, tkp = 0;
        long steps_run = S.step - step0;
        const cl_row *last;
        int nthin = 0;
        if (status == 0) ck_write(o.out, &S, rows, nrows, thin, &pts, &F);
        if (rows[nrows - 1].t < S.t - 0.5 * S.dt) { /* the end, off the row schedule: not checkpointed */
            cl_row r;
            if (make_row(&r, &S, &pts, &F, &g, l0, &b, t_start, work))
                CL_FAIL("mpmdem_collapse: out of memory\n");
            if (nrows == caprows) {
                caprows = caprows ? 2 * caprows : 64;
                cl_row *nr = (cl_row *)realloc(rows, (size_t)caprows * sizeof *rows);
                if (!nr) CL_FAIL("mpmdem_collapse: out of memory\n");
                rows = nr;
            }
            rows[nrows++] = r;
        }
        last = &rows[nrows - 1];
        write_csv(o.out, rows, nrows, b.width);
        write_plots(o.out, rows, nrows, b.width);
        snapshot(o.out, "end", S.t, &F, &pts, l0);
        snprintf(path, sizeof path, "%s/points_%06ld.vtk", o.out, S.step);
        mpd_write_vtk(path, &F, &pts);
        for (k = 0; k < nrows; ++k)
            if (rows[k].ek > ekp) ekp = rows[k].ek, tkp = rows[k].t;
        for (i = 0; i < pts.n; ++i) nthin += thin[i] > 0;
        dstar = (last->front - b.width) / b.width;
        printf("wrote %s/collapse.csv, collapse_energy.svg, collapse_front.svg, eps_q_*.svg, velocity_*.svg, "
               "points_*.vtk (ParaView), checkpoint.bin\n",
               o.out);
        printf(
            "at t = %.3f s: front %.4g m, d* = %.3f (seed 003: 1.8, experiments 1.6); edge of the deformed "
            "front point %.4g m, furthest point incl. scattered %.4g m; height %.4g m\n",
            last->t, last->front, dstar, last->front_box, last->front_raw, last->height);
        printf("energies / E_p0: E_k peak %.4f at %.3f s (seed ~0.1 at ~0.4 s); E_d %.4f (seed 0.55, "
               "Lajeunesse 1 - 0.74/2a = %.2f); %s\n",
               ekp, tkp, last->ed, 1 - 0.74 / (2 * b.height / b.width),
               S.at_rest ? "at rest" : "NOT at rest at the end");
        if (S.at_rest) printf("at rest (E_k < %g E_p0) from t = %.3f s\n", b.rest_frac, S.t_rest);
        printf("RVEs without contacts at the end: %d of %d (zero stress); thin-cell refusals: %lld (%d "
               "points)\n",
               last->loose, pts.n, S.thin_total, nthin);
        printf("cost: %s for %ld MPM steps, %lld DEM steps over all RVEs (%.2f per point per MPM step)\n",
               mpd_duration(secs, buf, sizeof buf), steps_run, F.dem_steps,
               steps_run ? (double)F.dem_steps / steps_run / pts.n : 0.0);
        printf(
            "RESULT dstar=%.4g dstar_paper=1.8 Ek_peak_over_Ep0=%.4g t_Ek_peak=%.4g Ed_final_over_Ep0=%.4g "
            "final_height=%.4g t_rest=%.4g n_rves=%d mpm_steps=%ld dt=%.4g dem_max=%d thin_points=%d "
            "seconds_per_step=%.4g seconds_per_step_per_1000_rves=%.4g total_seconds=%.2f\n",
            dstar, ekp, tkp, last->ed, last->height, S.at_rest ? S.t_rest : -1.0, pts.n, steps_run, S.dt,
            S.dem_max, nthin, steps_run ? secs / steps_run : 0.0,
            steps_run ? secs / steps_run * 1000.0 / pts.n : 0.0, secs);
    }
done:
    free(rows);
    free(thin);
    free(work);
    mpd_rves_free(&F);
    for (k = 0; k < CL_MAX_LEVELS; ++k) gk_rve_state_free(&st[k]);
    mpd_proto_close(&P);
    gk_mpm_points_destroy(&pts);
    gk_mpm_grid_destroy(&g);
    return status;
}
