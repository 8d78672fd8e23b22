/* mpmdem_collapse.c - the MPMxDEM granular column collapse of Liang &
 * Zhao (2019) Sec 3.5: a column 1 m wide and 1 m high (aspect a = 1) of
 * material points, each with its own periodic RVE pre-consolidated to the
 * geostatic pressure of its depth, collapses under gravity when the smooth
 * gate on its right is removed at t = 0. Left: symmetry plane (roller);
 * base: rigid, Coulomb friction 0.4. The paper reports, with 16 x 16 cells,
 * 4 points per cell and 1000-disk RVEs: run-out d* = (d_f - d_0)/d_0 = 1.8
 * (eq 48; experiments 1.6), the kinetic energy peaking at ~0.1 E_p0 near
 * 0.4 s, the dissipated energy ending at ~0.55 E_p0, the deposit at rest by
 * ~1.6 s.
 *
 *   build/mpmdem_collapse                         # 8 x 8 cells, 1 point each
 *   build/mpmdem_collapse --paper                 # the paper's size: 16 x 16 x 4, 1000 disks
 *   mpirun -np 2 build/mpmdem_collapse_mpi --threads 1   # the RVEs on 2 ranks
 *
 * Model. Square cells h = width / nx; the column holds nx x ny cells (ny =
 * nx height / width) with ppc^2 points each (uGIMP by default). The grid
 * reaches --domain widths to the right (the deposit must stay inside) and
 * carries ghost layers below and left: the x- face is a ROLLER and the y-
 * face a Coulomb FRICTION wall (gk_mpm_grid_set_bc), both acting on the
 * ghost layers plus the wall plane (x = 0, y = 0). Gravity -g e_y on every
 * point (gk_mpm_def.gravity). USF with the PIC/FLIP blend, alpha_PIC = 5e-4
 * (the paper's value for this case; the other drivers default to 0.1).
 *
 * Geostatic pre-consolidation. The column depth is cut into --levels equal
 * bins; bin k (from the top) has pressure p_k = max(rho g z_k, rho g h/2),
 * z_k its mid-depth and rho the bulk density of the packing as shipped; the
 * floor rho g h/2 (the pressure half a cell deep) keeps the top RVE from
 * being unloaded to nothing. One RVE is consolidated isotropically to each
 * p_k (mpd_prepare_rve, friction on, so the packing's fabric is kept and the
 * void ratio follows the pressure) and every point starts from the state of
 * its bin (mpd_micro_create's pick); its mass is the bin's bulk
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
 *   energies [Liang & Zhao Sec 3.5.2]: E_p0 = sum m g y0, E_p = sum m g y,
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
 * stop ends the run at the first refusal, naming the point (mpd_stress
 * of mpmdem.h does both).
 *
 * Outputs in --out DIR (default build/mpm_collapse): collapse.csv,
 * collapse_energy.svg, collapse_front.svg, eps_q_T.svg and velocity_T.svg at
 * the --snapshots times and at the end (one colour scale per quantity; the
 * symmetry plane and the base drawn), points_NNNNNN.vtk (first, last, every
 * --vtk-every steps), checkpoint.bin; a RESULT line.
 */
#define GK_IMPLEMENTATION
#include "mpmdem.h"

#define CL_MAX_LEVELS 64
#define CL_MAX_SNAP 16

typedef struct cl_opts {
    int nx, levels, no_stop, thin_freeze, paper;
    double width, height, mu, gravity, t_end, every, domain, front_tol, rest_frac, rest_hold;
    const char *snap_list;
    int nsnap;
    double snap[CL_MAX_SNAP];
} cl_opts;

typedef struct cl_row { /* one CSV row */
    double t, front, front_box, front_raw, height, ek, ep, ed, mass, mass_grid, dem_mean, secs;
    int loose, frozen;
} cl_row;

/* the state a checkpoint carries besides points, RVEs and rows */
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

typedef struct cl_measure {
    double front, front_box, front_raw, height, ep, ek, mass;
    int connected, loose;
} cl_measure;

typedef struct cl { /* the whole model */
    mpd_run run;
    mpd_opts o;
    cl_opts b;
    mpd_proto P;
    gk_rve_state st[CL_MAX_LEVELS];
    double lev_p[CL_MAX_LEVELS], lev_rho[CL_MAX_LEVELS], lev_e[CL_MAX_LEVELS], lev_M[CL_MAX_LEVELS],
        lev_pa[CL_MAX_LEVELS];
    mpd_micro M;
    gk_mpm_grid g;
    gk_mpm_points pts;
    gk_mpm_def def;
    cl_state S;
    mpd_rows rows;
    mpd_snaps snaps;
    int ny, dem_max_given, *work, *pick;
    double h, l0, c, rho_ref, Mmax, prep_secs;
    double dt_run, Ep0_run; /* the run's time step and E_p0 (a checkpoint's must be the same) */
} cl;

/* paper: the preset of --paper (Liang & Zhao's 16 x 16 cells, 4 points each, 1000-disk RVEs) */
static void defaults(cl *X, int paper) {
    cl_opts *b = &X->b;
    mpd_opts_default(&X->o, "build/mpm_collapse");
    X->o.alpha = 5e-4;
    X->o.dem_max = 0; /* 0: not given, the real-time count */
    memset(b, 0, sizeof *b);
    b->nx = 8, b->width = 1.0, b->height = 1.0, b->mu = 0.4, b->gravity = 9.81, b->t_end = 2.0,
    b->every = 0.01;
    b->domain = 5.0, b->front_tol = 0.5, b->rest_frac = 5e-3, b->rest_hold = 0.05;
    b->snap_list = "0.2,0.4,0.7,1,1.3", b->thin_freeze = 1;
    if (paper) b->paper = 1, b->nx = 16, X->o.ppc = 2, X->o.packing = "examples/data/rve1000.txt";
}

static void usage(FILE *fp) {
    cl X;
    defaults(&X, 0);
    X.o.dem_max = 1000;
    fprintf(
        fp,
        "mpmdem_collapse - MPMxDEM granular column collapse of Liang & Zhao (2019) Sec 3.5: every material\n"
        "point has a periodic RVE pre-consolidated to the geostatic pressure of its depth; gravity, "
        "symmetry\n"
        "plane on the left, rigid base with Coulomb friction, the gate on the right removed at t = 0.\n\n"
        "usage: mpmdem_collapse [options]\n"
        "  --paper                the paper's size: --nx 16 --ppc 2 --packing examples/data/rve1000.txt\n"
        "                         (1024 RVEs of 1000 disks; other flags given override it)\n"
        "  --nx N                 cells across the column width (default 8; the paper: 16 with --ppc 2)\n"
        "  --width D0 --height H0 column [m] (default 1 x 1, aspect a = 1); H0 / (D0/nx) must be whole\n"
        "  --mu M                 Coulomb friction of the base (default 0.4)\n"
        "  --gravity G            [m/s^2] (default 9.81)\n"
        "  --t-end T              simulated time [s] (default 2.0; the run stops earlier at rest, see\n"
        "                         --rest-frac; the paper's deposit rests by 1.6 s)\n"
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
        "  --thin-cell stop|freeze  an RVE cell too thin for the next dH: end the run, or keep that RVE\n"
        "                         frozen (no DEM steps, stress kept), name and count it (default)\n"
        "  --help                 this text\n"
        "defaults that differ from the common list below: --alpha 5e-4 (Liang & Zhao, column collapse);\n"
        "--dem-max = ceil(dt_MPM / dt_DEM), the real-time count (printed at start), unless given.\n"
        "The paper's RVEs have 1000 disks (Table 3: r 3-7 mm, E 600 MPa, kt/kn 0.8, friction 28.6 deg,\n"
        "no rolling); the default packing is the 400-disk one (same contact law): use --packing for\n"
        "another, e.g. made by build/gk_pack --dim 2 --n 1000 --pressure 2e4 --target-void-ratio 0.2.\n\n");
    mpd_usage_common(fp, &X.o);
    fprintf(fp, "\nends with: RESULT dstar=... dstar_paper=1.8 Ek_peak_over_Ep0=... t_Ek_peak=... "
                "Ed_final_over_Ep0=...\n"
                "           final_height=... t_rest=... (-1: not at rest) n_rves=... mpm_steps=... dt=... "
                "dem_max=...\n"
                "           thin_points=... seconds_per_step=... seconds_per_step_per_1000_rves=... "
                "total_seconds=...\n");
}

static int parse(cl *X, int argc, char **argv) {
    cl_opts *b = &X->b;
    const cli_opt mine[] = {
        {"--paper", CLI_FLAG, &b->paper, 0, 0, NULL, NULL, 0},
        {"--nx", CLI_INT, &b->nx, 1, 1000, NULL, NULL, 0},
        {"--levels", CLI_INT, &b->levels, 1, CL_MAX_LEVELS, NULL, NULL, 0},
        {"--width", CLI_REAL, &b->width, 0, 1e4, "a positive length", NULL, CLI_LO_OPEN},
        {"--height", CLI_REAL, &b->height, 0, 1e4, "a positive length", NULL, CLI_LO_OPEN},
        {"--mu", CLI_REAL, &b->mu, 0, 1e3, "a friction coefficient >= 0", NULL, 0},
        {"--gravity", CLI_REAL, &b->gravity, 0, 1e4, "a positive value", NULL, CLI_LO_OPEN},
        {"--t-end", CLI_REAL, &b->t_end, 0, 1e6, "a positive time", NULL, CLI_LO_OPEN},
        {"--every", CLI_REAL, &b->every, 0, 1e6, "a positive time", NULL, CLI_LO_OPEN},
        {"--domain", CLI_REAL, &b->domain, 1.5, 1e3, "at least 1.5 column widths", NULL, 0},
        {"--front-tol", CLI_REAL, &b->front_tol, 0, 1e3, "a value >= 0", NULL, 0},
        {"--rest-frac", CLI_REAL, &b->rest_frac, 0, 1, "a value in [0, 1]", NULL, 0},
        {"--rest-hold", CLI_REAL, &b->rest_hold, 0, 1e6, "a time >= 0", NULL, 0},
        {"--snapshots", CLI_STR, &b->snap_list, 0, 0, NULL, NULL, 0},
        {"--no-stop", CLI_FLAG, &b->no_stop, 0, 0, NULL, NULL, 0},
        {"--thin-cell", CLI_CHOICE, &b->thin_freeze, 0, 0, NULL, "stop|freeze", 0},
        {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    int r, rows_pts;
    /* the flags, twice: the preset (--paper) first, then every flag given over it */
    defaults(X, 0);
    if ((r = mpd_parse(&X->run, argc, argv, &X->o, mine, usage)) != 0) return r;
    r = b->paper;
    defaults(X, r);
    mpd_parse(&X->run, argc, argv, &X->o, mine, usage);
    X->run.out = X->o.out;
    X->dem_max_given = X->o.dem_max > 0;
    if (!X->dem_max_given) X->o.dem_max = 1000000; /* placeholder until dt is known */
    if ((b->nsnap = mpd_list(&X->run, "--snapshots", b->snap_list, b->snap, CL_MAX_SNAP, 0, 0, 1e6, 1)) < 0)
        return 2;
    X->h = b->width / b->nx;
    X->ny = (int)floor(b->height / X->h + 0.5);
    if (X->ny < 1 || fabs(X->ny * X->h - b->height) > 1e-9 * b->height)
        return fprintf(stderr, "mpmdem_collapse: the height %g is not a whole number of cells %g\n",
                       b->height, X->h),
               2;
    rows_pts = X->ny * X->o.ppc;
    if (b->levels == 0) b->levels = rows_pts < 8 ? rows_pts : 8;
    if (b->levels > rows_pts) b->levels = rows_pts;
    X->l0 = X->h / (2.0 * X->o.ppc);
    return mpd_check_opts(&X->run, &X->o);
}

/* ---------------------------------------------------- initial state */
/* one RVE state per pressure level (mpd_prepare_levels) */
static int prepare_levels(cl *X, gk_err *err) {
    const cl_opts *b = &X->b;
    double t0 = gk_wtime();
    if (mpd_prepare_levels(&X->P, &X->o, b->levels, b->height, b->gravity, X->h, X->st, X->lev_p, X->lev_rho,
                           X->lev_e, X->lev_M, X->lev_pa, &X->rho_ref, &X->Mmax, err))
        return 1;
    X->prep_secs = gk_wtime() - t0;
    return 0;
}

/* a checkpoint's state and rows as read (mpd_load's driver check, ctx the model): every value finite
 * and within MPD_MAX_VALUE, the time step, DEM cap and initial potential energy the run's, counters and
 * the snapshot index in range, the next row not behind the time by more than one interval, a row at
 * least */
static int cl_check(const void *vS, const mpd_rows *R, const void *ctx, char *why, size_t nwhy) {
    const cl_state *S = (const cl_state *)vS;
    const cl *X = (const cl *)ctx;
    double v[8];
    int k, j;
    v[0] = S->t, v[1] = S->dt, v[2] = S->Ep0, v[3] = S->next_out, v[4] = S->ek_peak, v[5] = S->t_ek_peak;
    v[6] = S->t_rest, v[7] = S->acc_dem;
    for (k = 0; k < 8; ++k)
        if (!mpd_sane(v[k])) return snprintf(why, nwhy, "collapse state: a non-finite value"), 1;
    if (S->dt != X->dt_run || S->Ep0 != X->Ep0_run || S->dem_max != X->o.dem_max)
        return snprintf(
                   why, nwhy,
                   "written by another run (time step %g s, DEM cap %d, E_p0 %g J; this run %g s, %d, %g J)",
                   S->dt, S->dem_max, S->Ep0, X->dt_run, X->o.dem_max, X->Ep0_run),
               1;
    if (S->step < 0 || S->step > 1000000000000L || S->nacc < 0 || S->nacc > S->step || S->thin_total < 0 ||
        S->nsnap < 0 || S->nsnap > X->b.nsnap || (S->at_rest != 0 && S->at_rest != 1) || !(S->t >= 0) ||
        S->next_out < S->t - 2 * (X->b.every + S->dt))
        return snprintf(why, nwhy, "collapse state: a step, snapshot or output counter out of range"), 1;
    if (R->n < 1) return snprintf(why, nwhy, "it holds no rows"), 1;
    for (k = 0; k < R->n; ++k) {
        const cl_row *r = (const cl_row *)mpd_row(R, k);
        double w[12];
        w[0] = r->t, w[1] = r->front, w[2] = r->front_box, w[3] = r->front_raw, w[4] = r->height;
        w[5] = r->ek, w[6] = r->ep, w[7] = r->ed, w[8] = r->mass, w[9] = r->mass_grid, w[10] = r->dem_mean;
        w[11] = r->secs;
        for (j = 0; j < 12; ++j)
            if (!mpd_sane(w[j])) return snprintf(why, nwhy, "row %d: a non-finite value", k), 1;
        if (r->loose < 0 || r->frozen < 0) return snprintf(why, nwhy, "row %d: a negative count", k), 1;
    }
    return 0;
}

/* the levels' RVEs, the grid (roller x = 0, friction base), the points with their levels' masses;
 * dt and the real-time DEM-step cap */
static int setup(cl *X, gk_err *err) {
    const cl_opts *b = &X->b;
    cl_state *S = &X->S;
    double h = X->h, org[3], lo[3] = {0, 0, 0}, hi[3];
    int n[3], i, gl = mpd_ghost_layers(&X->o), nxd = (int)ceil(b->domain * b->width / h);
    if (prepare_levels(X, err)) return 1;
    org[0] = -gl * h, org[1] = -gl * h, org[2] = 0;
    n[0] = nxd + 2 * gl + 1, n[1] = X->ny + 2 * gl + 2, n[2] = 1;
    hi[0] = b->width, hi[1] = b->height, hi[2] = 0;
    if (gk_mpm_grid_create(&X->g, 2, org, h, n, NULL, err) ||
        gk_mpm_grid_set_bc(&X->g, 0, GK_MPM_BC_ROLLER, 0.0, gl + 1, err) ||
        gk_mpm_grid_set_bc(&X->g, 2, GK_MPM_BC_FRICTION, b->mu, gl + 1, err) ||
        gk_mpm_points_create_box(&X->pts, 2, lo, hi, h, X->o.ppc, X->rho_ref, NULL, err))
        return 1;
    memset(S, 0, sizeof *S);
    X->c = sqrt(X->Mmax / X->rho_ref);
    S->dt = X->o.cfl * h / X->c;
    S->dem_max = X->dem_max_given ? X->o.dem_max : (int)ceil(S->dt / X->P.dt * (1 - 1e-12));
    X->o.dem_max = S->dem_max;
    if (mpd_check_opts(&X->run, &X->o)) return 2;
    X->pick = (int *)malloc((size_t)X->pts.n * sizeof *X->pick);
    X->work = (int *)malloc((size_t)X->pts.n * sizeof *X->work);
    if (!X->pick || !X->work) return gk_err_set(err, GK_ERR_ALLOC, "out of memory"), 1;
    for (i = 0; i < X->pts.n; ++i) X->pick[i] = mpd_level_of(X->b.height, X->b.levels, X->pts.x[1][i]);
    if (mpd_micro_create(&X->M, &X->pts, &X->P, X->st, b->levels, X->pick, &X->o, err)) return 1;
    X->M.freeze = b->thin_freeze;
    for (i = 0; i < X->pts.n; ++i) {
        X->pts.m[i] = X->lev_rho[X->pick[i]] * X->pts.vol0[i];
        S->Ep0 += X->pts.m[i] * b->gravity * X->pts.x[1][i];
    }
    X->def = mpd_mpm_def(&X->o);
    X->def.gravity[1] = -b->gravity;
    S->next_out = b->every;
    S->t_rest = -1;
    X->rows.size = sizeof(cl_row);
    X->dt_run = S->dt, X->Ep0_run = S->Ep0;
    if (X->o.restart) {
        if (mpd_load(X->o.restart, &X->M, &X->pts, "collapse", S, sizeof *S, &X->rows, &X->snaps, cl_check, X,
                     err))
            return 1;
        printf("restarted from %s/checkpoint.bin at t = %.4f s (step %ld)\n", X->o.restart, S->t, S->step);
    }
    return 0;
}

/* -------------------------------------------------------- measures */
/* flood fill from the point nearest (0, 0) over overlapping deformed boxes; the loose RVEs of the
 * fields fld of the accepted states */
static int measure(const gk_mpm_points *pts, const gk_twoscale_field *fld, double l0, double tol, double g,
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
        if (fld[p].contacts == 0) ++m->loose;
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
static void put_csv(FILE *fp, const void *user) {
    const cl *X = (const cl *)user;
    double d0 = X->b.width;
    int k;
    fprintf(fp, "time,front,dstar,front_box,front_raw,height,Ek_over_Ep0,Ep_over_Ep0,Ed_over_Ep0,mass,"
                "mass_grid,loose_rves,frozen_rves,dem_steps_per_point,seconds\n");
    for (k = 0; k < X->rows.n; ++k) {
        const cl_row *r = (const cl_row *)mpd_row(&X->rows, k);
        fprintf(fp, "%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.9g,%.9g,%d,%d,%.4g,%.3f\n", r->t,
                r->front, (r->front - d0) / d0, r->front_box, r->front_raw, r->height, r->ek, r->ep, r->ed,
                r->mass, r->mass_grid, r->loose, r->frozen, r->dem_mean, r->secs);
    }
}

/* a dashed horizontal reference line over tx */
static void ref_line(gk_plot *pl, const double *tx, double *ty, double v, const char *label) {
    int s;
    ty[0] = ty[1] = v;
    if ((s = gk_plot_add(pl, tx, ty, 2, label)) >= 0) pl->s[s].dashed = 1;
}

static int write_plots(const cl *X) {
    int n = X->rows.n, k, bad;
    double *x = (double *)malloc(4 * (size_t)n * sizeof *x + 1), *y1 = x + n, *y2 = y1 + n, *y3 = y2 + n,
           d0 = X->b.width;
    double tx[2], ty[3][2];
    gk_plot pl;
    if (!x) return fprintf(stderr, "mpmdem_collapse: out of memory\n"), 1;
    for (k = 0; k < n; ++k) {
        const cl_row *r = (const cl_row *)mpd_row(&X->rows, k);
        x[k] = r->t, y1[k] = r->ek, y2[k] = r->ep, y3[k] = r->ed;
    }
    tx[0] = 0, tx[1] = x[n - 1] > 1.6 ? x[n - 1] : 1.6;
    gk_plot_init(&pl, "MPMxDEM column collapse: energies / E_p0 (Liang & Zhao Fig 27)", "time [s]",
                 "energy / E_p0");
    gk_plot_add(&pl, x, y2, n, "E_p potential");
    gk_plot_add(&pl, x, y1, n, "E_k kinetic");
    gk_plot_add(&pl, x, y3, n, "E_d dissipated");
    ref_line(&pl, tx, ty[0], 0.55, "Liang & Zhao: E_d final 0.55");
    ref_line(&pl, tx, ty[1], 0.1, "Liang & Zhao: E_k peak 0.1 (~0.4 s)");
    ref_line(&pl, tx, ty[2], 0.63, "Lajeunesse: E_d = 1 - 0.74/2a");
    bad = mpd_plot(&X->run, &pl, "collapse_energy.svg");
    for (k = 0; !bad && k < n; ++k) {
        const cl_row *r = (const cl_row *)mpd_row(&X->rows, k);
        y1[k] = (r->front - d0) / d0, y2[k] = (r->front_box - d0) / d0, y3[k] = (r->front_raw - d0) / d0;
    }
    gk_plot_init(&pl, "MPMxDEM column collapse: run-out d* = (d_f - d_0)/d_0 (Liang & Zhao eq 48)",
                 "time [s]", "(front - d_0) / d_0");
    ref_line(&pl, tx, ty[0], 1.8, "Liang & Zhao: d* = 1.8");
    ref_line(&pl, tx, ty[1], 1.6, "experiments (Lube): 1.6");
    gk_plot_add(&pl, x, y3, n, "furthest point, scattered included");
    gk_plot_add(&pl, x, y2, n, "edge of its deformed box (F)");
    gk_plot_add(&pl, x, y1, n, "d*: furthest connected point (centre + l0)"); /* last: drawn on top */
    if (!bad) bad = mpd_plot(&X->run, &pl, "collapse_front.svg");
    free(x);
    return bad;
}

/* eps_q and |v| of the points (the symmetry plane and the base drawn) */
static int snapshot(cl *X, const char *tag) {
    char file[48], title[160];
    double *v = (double *)malloc((size_t)X->pts.n * sizeof *v + 1), xmax = 0, line[6];
    mpd_outline ol;
    int p, bad;
    if (!v) return fprintf(stderr, "mpmdem_collapse: out of memory\n"), 1;
    for (p = 0; p < X->pts.n; ++p) {
        v[p] = sqrt(X->pts.v[0][p] * X->pts.v[0][p] + X->pts.v[1][p] * X->pts.v[1][p]);
        xmax = fmax(xmax, X->pts.x[0][p]);
    }
    line[0] = 0, line[1] = X->b.height + X->h, line[2] = 0, line[3] = 0, line[4] = xmax + X->h, line[5] = 0;
    memset(&ol, 0, sizeof ol);
    mpd_outline_add(&ol, 3, line);
    snprintf(file, sizeof file, "eps_q_%s", tag);
    snprintf(title, sizeof title, "deviatoric strain eps_q at t = %.3f s (Liang & Zhao Fig 26)", X->S.t);
    bad = mpd_snap_field(&X->run, &X->snaps, &X->M, &X->pts, MPD_EPS_Q, file, title, X->l0, &ol);
    snprintf(file, sizeof file, "velocity_%s", tag);
    snprintf(title, sizeof title, "speed |v| at t = %.3f s (Liang & Zhao Fig 26)", X->S.t);
    if (!bad) bad = mpd_snap_add(&X->run, &X->snaps, file, title, "|v| [m/s]", &X->pts, v, X->l0, &ol);
    free(v);
    return bad;
}

/* a CSV row of the current state (resets the DEM-step sums); 0 or 1 (said) */
static int add_row(cl *X, double t_start) {
    cl_state *S = &X->S;
    cl_measure m;
    cl_row r;
    gk_err err;
    double mg = 0;
    size_t i;
    int p;
    if (mpd_micro_fields(&X->M, &err)) return fprintf(stderr, "mpmdem_collapse: %s\n", err.msg), 1;
    if (measure(&X->pts, X->M.fld, X->l0, X->b.front_tol, X->b.gravity, &m, X->work))
        return fprintf(stderr, "mpmdem_collapse: out of memory\n"), 1;
    for (i = 0; i < X->g.nnode; ++i) mg += X->g.m[i];
    memset(&r, 0, sizeof r);
    for (p = 0; p < X->pts.n; ++p) r.frozen += X->M.frozen[p];
    r.t = S->t, r.front = m.front, r.front_box = m.front_box, r.front_raw = m.front_raw;
    r.height = m.height;
    r.ep = m.ep / S->Ep0, r.ek = m.ek / S->Ep0, r.ed = 1 - r.ep - r.ek;
    r.mass = m.mass, r.mass_grid = S->step > 0 ? mg : m.mass, r.loose = m.loose;
    r.dem_mean = S->nacc ? S->acc_dem / S->nacc : 0;
    r.secs = gk_wtime() - t_start;
    S->acc_dem = 0, S->nacc = 0;
    return mpd_rows_push(&X->run, &X->rows, &r);
}

/* after a step: a CSV row when due, rest detection, snapshots, progress; 0 or 1 (said) */
static int after_step(cl *X, double t_start, long step0, long nsteps_total) {
    const cl_opts *b = &X->b;
    cl_state *S = &X->S;
    const cl_row *r;
    long long sum = 0;
    int i, bad;
    S->t += S->dt, ++S->step;
    S->thin_total += X->M.thin_step;
    for (i = 0; i < X->pts.n; ++i) sum += X->M.nsub[i];
    S->acc_dem += (double)sum / X->pts.n, ++S->nacc;
    if (S->t < S->next_out - 1e-9 * S->dt) return 0;
    if ((bad = add_row(X, t_start)) != 0) return bad;
    while (S->next_out <= S->t + 1e-9 * S->dt) S->next_out += b->every;
    r = (const cl_row *)mpd_row(&X->rows, X->rows.n - 1);
    bad = mpd_write(&X->run, "collapse.csv", put_csv, X);
    if (r->ek > S->ek_peak) S->ek_peak = r->ek, S->t_ek_peak = r->t;
    if (S->ek_peak > 10 * b->rest_frac && r->t > S->t_ek_peak && r->ek < b->rest_frac) {
        if (!S->at_rest) S->at_rest = 1, S->t_rest = r->t;
    } else
        S->at_rest = 0, S->t_rest = -1;
    while (!bad && S->nsnap < b->nsnap && S->t >= b->snap[S->nsnap] - 0.5 * S->dt) {
        char tag[32];
        snprintf(tag, sizeof tag, "%g", b->snap[S->nsnap]);
        bad = snapshot(X, tag);
        ++S->nsnap;
    }
    if (!X->o.quiet) {
        char buf[64], buf2[64];
        double el = gk_wtime() - t_start;
        long done = S->step - step0;
        fprintf(stderr,
                "t %.3f/%.3g s  step %ld/%ld  d* %.3f  height %.3f  Ek %.4f Ep %.4f Ed %.4f  loose %d  DEM "
                "%.1f/pt | "
                "%s elapsed, ETA %s\n",
                r->t, b->t_end, S->step, nsteps_total, (r->front - b->width) / b->width, r->height, r->ek,
                r->ep, r->ed, r->loose, r->dem_mean, mpd_duration(el, buf, sizeof buf),
                mpd_duration(done ? el / done * (nsteps_total - S->step) : 0.0, buf2, sizeof buf2));
    }
    return bad;
}

/* the end: a last row off the schedule, CSV, plots, fields, the summary and RESULT; 0 or 1 */
static int finish(cl *X, double t_start, long steps_run, int bad) {
    const cl_opts *b = &X->b;
    cl_state *S = &X->S;
    double secs, dstar, ekp = 0, tkp = 0;
    const cl_row *last;
    int k, nthin = 0, n = X->pts.n;
    char buf[64];
    if (((const cl_row *)mpd_row(&X->rows, X->rows.n - 1))->t < S->t - 0.5 * S->dt && add_row(X, t_start))
        return 1;
    if (!bad)
        bad = mpd_write(&X->run, "collapse.csv", put_csv, X) || write_plots(X) || snapshot(X, "end") ||
              mpd_write_vtk(&X->run, S->step, &X->M, &X->pts);
    secs = gk_wtime() - t_start;
    last = (const cl_row *)mpd_row(&X->rows, X->rows.n - 1);
    for (k = 0; k < X->rows.n; ++k) {
        const cl_row *r = (const cl_row *)mpd_row(&X->rows, k);
        if (r->ek > ekp) ekp = r->ek, tkp = r->t;
    }
    for (k = 0; k < n; ++k) nthin += X->M.thin[k] > 0;
    dstar = (last->front - b->width) / b->width;
    if (!bad)
        printf("wrote %s/collapse.csv, collapse_energy.svg, collapse_front.svg, eps_q_*.svg, velocity_*.svg, "
               "points_*.vtk (ParaView), checkpoint.bin\n",
               X->run.out);
    printf("at t = %.3f s: front %.4g m, d* = %.3f (Liang & Zhao: 1.8, experiments 1.6); edge of the "
           "deformed front "
           "point %.4g m, furthest point incl. scattered %.4g m; height %.4g m\n",
           last->t, last->front, dstar, last->front_box, last->front_raw, last->height);
    printf("energies / E_p0: E_k peak %.4f at %.3f s (paper ~0.1 at ~0.4 s); E_d %.4f (paper 0.55, "
           "Lajeunesse 1 - "
           "0.74/2a = %.2f); %s\n",
           ekp, tkp, last->ed, 1 - 0.74 / (2 * b->height / b->width),
           S->at_rest ? "at rest" : "NOT at rest at the end");
    if (S->at_rest) printf("at rest (E_k < %g E_p0) from t = %.3f s\n", b->rest_frac, S->t_rest);
    printf("RVEs without contacts at the end: %d of %d (zero stress); thin-cell refusals: %lld (%d points)\n",
           last->loose, n, S->thin_total, nthin);
    printf("cost: %s for %ld MPM steps, %lld DEM steps over all RVEs (%.2f per point per MPM step)\n",
           mpd_duration(secs, buf, sizeof buf), steps_run, X->M.dem_steps,
           steps_run ? (double)X->M.dem_steps / steps_run / n : 0.0);
    mpd_print_traffic(&X->run, &X->M, steps_run, X->o.threads);
    printf("RESULT dstar=%.4g dstar_paper=1.8 Ek_peak_over_Ep0=%.4g t_Ek_peak=%.4g Ed_final_over_Ep0=%.4g "
           "final_height=%.4g t_rest=%.4g n_rves=%d mpm_steps=%ld dt=%.4g dem_max=%d thin_points=%d "
           "seconds_per_step=%.4g seconds_per_step_per_1000_rves=%.4g total_seconds=%.2f\n",
           dstar, ekp, tkp, last->ed, last->height, S->at_rest ? S->t_rest : -1.0, n, steps_run, S->dt,
           S->dem_max, nthin, steps_run ? secs / steps_run : 0.0,
           steps_run ? secs / steps_run * 1000.0 / n : 0.0, secs);
    return bad;
}

static void print_setup(const cl *X, long nsteps_total) {
    const cl_opts *b = &X->b;
    int k;
    printf("mpmdem_collapse: column %g x %g m (a = %g), %d x %d cells, h = %.4g m, %d points (= RVEs of %d "
           "disks), "
           "basis %d, alpha_PIC %g, base mu %g\n",
           b->width, b->height, b->height / b->width, b->nx, X->ny, X->h, X->pts.n, X->P.pk.n,
           (int)X->def.basis, X->o.alpha, b->mu);
    printf("geostatic pre-consolidation: %d levels, p_k = max(rho g z_k, rho g h/2), rho = %.1f kg/m3 (%.1f "
           "s on %d "
           "threads)\n",
           b->levels, X->rho_ref, X->prep_secs, X->o.threads);
    for (k = 0; k < b->levels; ++k)
        printf("  level %d: depth %.3f-%.3f m  p target %.4g kPa, reached %.4g kPa, e = %.4f, rho = %.1f, M "
               "= %.4g "
               "MPa\n",
               k, b->height * k / b->levels, b->height * (k + 1) / b->levels, X->lev_p[k] / 1e3,
               X->lev_pa[k] / 1e3, X->lev_e[k], X->lev_rho[k], X->lev_M[k] / 1e6);
    printf(
        "MPM dt = %.4g s (cfl %.2f, c = %.1f m/s from M = %.4g MPa); DEM dt = %.3g s; DEM steps per MPM step "
        "%d..%d (%s), rule: ",
        X->S.dt, X->o.cfl, X->c, X->Mmax / 1e6, X->P.dt, X->o.dem_min, X->S.dem_max,
        X->dem_max_given ? "--dem-max" : "cap = real-time count ceil(dt/dt_DEM)");
    if (X->o.dem_rule == 0)
        printf("adaptive, I <= %g, unbalanced <= %g\n", X->o.dem_inertial, X->o.dem_unbalanced);
    else
        printf("strain, <= %g per DEM step\n", X->o.dem_strain);
    printf("about %ld MPM steps to t = %g s (stops at rest: %s); E_p0 = %.6g J/m\n", nsteps_total, b->t_end,
           b->no_stop ? "no" : "yes", X->S.Ep0);
}

static int run(cl *X, int argc, char **argv) {
    const cl_opts *b = &X->b;
    cl_state *S = &X->S;
    double t_start;
    long nsteps_total, step0;
    int status = parse(X, argc, argv), bad = 0;
    gk_err err;
    if (status) return status == 1 ? 0 : status;
    /* the inputs (packing, checkpoint) first: bad input leaves no output folder behind */
    if ((status = setup(X, &err)) != 0)
        return status == 2 ? 2 : (fprintf(stderr, "mpmdem_collapse: %s\n", err.msg), 1);
    if (mpd_out_dir(&X->run)) return 1;
    nsteps_total = (long)ceil(b->t_end / S->dt - 1e-9);
    print_setup(X, nsteps_total);
    t_start = gk_wtime();
    if (!X->o.restart) { /* the first row, VTK and (at t = 0) snapshot */
        if (mpd_write_vtk(&X->run, 0, &X->M, &X->pts) || add_row(X, t_start)) return 1;
        if (S->nsnap < b->nsnap && b->snap[S->nsnap] <= 0) {
            if (snapshot(X, "0")) return 1;
            ++S->nsnap;
        }
    }
    step0 = S->step;
    while (!bad && S->t < b->t_end - 0.5 * S->dt) {
        X->M.t = S->t;
        if (mpd_step(&X->g, &X->pts, &X->def, S->dt, &X->M, NULL, 0, &err)) {
            fprintf(stderr, "mpmdem_collapse: step %ld (t = %.4f s): %s%s\n", S->step, S->t, err.msg,
                    err.code == GK_ERR_CELL
                        ? " (a thin RVE cell: --thin-cell freeze, the default, continues past it)"
                        : "");
            status = 3;
            break;
        }
        bad = after_step(X, t_start, step0, nsteps_total);
        if (!bad && X->o.vtk_every && S->step % X->o.vtk_every == 0)
            bad = mpd_write_vtk(&X->run, S->step, &X->M, &X->pts);
        if (!bad && X->o.checkpoint_every && S->step % X->o.checkpoint_every == 0)
            bad = mpd_save(&X->run, &X->M, &X->pts, "collapse", S, sizeof *S, &X->rows, &X->snaps);
        if (!b->no_stop && S->at_rest && S->t >= S->t_rest + b->rest_hold - 1e-9 * S->dt) break;
    }
    if (!bad && status == 0)
        bad = mpd_save(&X->run, &X->M, &X->pts, "collapse", S, sizeof *S, &X->rows, &X->snaps);
    bad = finish(X, t_start, S->step - step0, bad);
    return status ? status : bad;
}

int main(int argc, char **argv) {
    cl X;
    int status, k;
    memset(&X, 0, sizeof X);
    for (k = 0; k < CL_MAX_LEVELS; ++k) gk_rve_state_init(&X.st[k], NULL);
    mpd_begin(&X.run, "mpmdem_collapse", &argc, &argv);
    status = run(&X, argc, argv);
    free(X.work), free(X.pick);
    mpd_free_all(&X.M, &X.P, &X.pts, &X.g, &X.rows, &X.snaps);
    for (k = 0; k < CL_MAX_LEVELS; ++k) gk_rve_state_free(&X.st[k]);
    return mpd_end(status);
}
