/* mpmdem_pipe.c - the MPMxDEM pipe-soil interaction of Liang & Zhao (2019)
 * Sec 3.4 (Figs 19-24): a rough rigid pipe (D = 1 m) is pushed vertically
 * 0.8 m into a soil under gravity, then 0.7 m to the left; every material
 * point has its own periodic 400-disk RVE ("Dense" of Table 2) consolidated
 * isotropically to the geostatic pressure p = rho g z of its depth. The
 * paper (9 x 2.5 m, 9800 cells, 1 point each): the vertical reaction V
 * peaks at ~250 kN/m at the end of the penetration, then drops; in the
 * lateral stage V ~ 25 kN/m steady while H rises to ~50 kN/m, then slightly;
 * asymmetric, interlayered shear bands.
 *
 *   build/mpmdem_pipe                        # reduced: 6 x 2.5 m, h = 0.25 m, 240 RVEs
 *   build/mpmdem_pipe --paper                # 9 x 2.49 m, 188 x 52 cells, 9776 RVEs
 *   build/mpmdem_pipe --paper --max-steps 5  # measures its cost and projects the whole run
 *   mpirun -np 2 build/mpmdem_pipe_mpi --threads 1   # the RVEs on 2 ranks
 *
 * MODEL. Square cells h = width / nx; the soil is nx x ny cells (depth =
 * ny h) with ppc^2 points each (uGIMP by default). Sides: smooth walls
 * (roller); base: fixed; ghost node layers outside all three; room above
 * the ground for the heave. Gravity -g e_y on every point. The pipe is a
 * gk_mpm_body CIRCLE (gk_mpm.h: the nodes within its radius get its contact,
 * normal radial), its bottom starting on the ground at mid-width. Contact
 * (--contact): friction with mu = 0.5 by default - a rough pipe that the
 * soil behind it can still leave in the lateral stage (the paper: "the soil
 * behind the pipe ... slips down to fill the gap"); stick (no separation,
 * the soil is dragged along) and smooth are there to compare.
 *
 * GEOSTATIC START (as mpmdem_collapse): the depth is cut into --levels bins
 * (default: one per point row, at most 64); bin k has p_k = max(rho g z_k,
 * rho g h/2) (z_k its mid-depth, rho the bulk density of the packing as
 * shipped; the floor keeps the top RVEs from being unloaded to nothing); one
 * RVE is consolidated isotropically to each p_k and every point of the bin
 * starts from it, mass = its bulk density times the point's area. sigma =
 * -p I with p = rho g z is in equilibrium under gravity between roller
 * walls (K0 = 1, as the paper's isotropic compaction).
 *
 * PATH (the paper's Fig 20: velocity ramps at both ends of each stage):
 * stage 1 down by --penetration (0.8 m) at up to --v-down, stage 2 left by
 * --lateral (0.7 m) at up to --v-lateral (the paper: a smaller horizontal
 * velocity, so the soil behind the pipe has time to rearrange); each stage's
 * speed rises linearly over --ramp seconds, holds, and falls linearly over
 * --ramp seconds to zero (a trapezoid of duration L / v + ramp), evaluated
 * at mid-step; the last step of a stage is cut to its exact length.
 *
 * REACTIONS per unit length (plane strain): H = -force_x, V = -force_y of
 * the body (gk_mpm.h: the momentum change it imposed on the nodes / dt, the
 * force on the soil): V > 0 pushes the pipe up, H > 0 resists its motion
 * to the left. Each CSV row is the mean over its interval (--every s); a
 * row also ends each stage. RESULT: V_peak (largest row in stage 1), V at
 * the end of the penetration (its last row, the speed ramped down to 0), H
 * at the end (the last row before the lateral speed ramps down), V and H
 * steady in the lateral stage (time means over its second half), the
 * paper's values, the cost. The paper's numbers are the MPMxDEM's, read from its Fig 21.
 *
 * SIZE AND COST. --paper is the paper's size with square cells: h = 9/188 m,
 * 188 x 52 = 9776 cells (9800 in the paper), depth 2.49 m; hours. The
 * default is reduced to finish in minutes on 2 cores: a 6 m wide domain (3
 * m either side of the pipe's start; at the end of the default run points
 * with eps_q > 10 % reach from x = 0.11 m to 4.65 m, i.e. the left wall:
 * narrower than the mechanism, the smooth walls are part of the result;
 * --width 9 --nx 36 is the paper's width at this h, 360 RVEs, where they
 * span x = 1.35-6.16 m, clear of both walls), h = 0.25 m (D = 4 cells:
 * coarse, the reactions are noisy as points cross cells) and the pipe at
 * 0.4 m/s down, 0.2 m/s left with 0.2 s ramps (the paper does not give its speeds; see
 * RATE). Each run prints its cost per RVE per MPM step and projects the
 * --paper run from it (--max-steps N stops after N steps).
 *
 * DEM STEPS per MPM step: the rule of mpmdem.h (--dem-rule, default
 * adaptive), capped by default at the REAL-TIME count ceil(dt / dt_DEM)
 * (as mpmdem_collapse): uncapped (--dem-max 1000), the adaptive rule spent
 * 186 DEM steps per point per MPM step on a 12 x 5 cell model of this
 * driver (why so many was not analysed), the capped default run 11.5.
 * --dem-max overrides the cap.
 *
 * RATE. The PIC part of the PIC/FLIP blend (alpha 0.1, the paper's) damps
 * like a viscosity of shear stress ~ rho alpha c v / cfl: ~25 kPa at 0.4
 * m/s, small next to the ~250 kPa under the pipe at the end of the
 * penetration, not next to the ~50 kPa of the lateral stage at 0.2 m/s.
 * --v-down, --v-lateral and --alpha change it.
 *
 * POINTS D, E, F (the paper's Figs 22E-24): D and F inside the left and
 * right dominant shear bands, E under the pipe. The paper marks them only
 * in its figures and gives no coordinates; its text says D and F are pushed
 * laterally upward by ~0.08 sqrt 2 m in the penetration and E is pushed
 * down slightly to the right of the pipe's axis. Here they are the material
 * points nearest, at the start, to these positions relative to the pipe's
 * start (x0 its centre, depth below the ground): D (x0 - 1.1 m, 0.6 m),
 * E (x0 + 0.1 m, 1.05 m), F (x0 + 1.1 m, 0.6 m) - chosen from that text
 * (beside the pipe's final depth, where the bands from its bottom rise to
 * the ground; just under its final bottom), not read off the paper's figure.
 * The run prints the points chosen and, at the end, the paper's numbers
 * against its own: the lifts of D and F in the penetration; eps_q and the
 * rotation of D and F at the lateral onset (paper: D 0.5, 10 deg
 * anticlockwise; F 1.2, 30 deg clockwise); E's largest p (paper ~700 kPa);
 * D's eps_q and rotation at the end (paper 2.6, 58 deg); F's p and q at
 * the end (paper: toward the origin, then p ~15, q ~4 kPa). eps_q and
 * eps_v are those of the point's small strain (sum of sym dH, mpmdem.h),
 * the rotation that of F = R U, counter-clockwise positive.
 *
 * Outputs in --out DIR (default build/mpm_pipe): pipe.csv, pipe_force.svg
 * (H and V against the pipe's travel), points_DEF.csv (a row at t = 0,
 * then the state of D, E, F at the end of every pipe.csv row: time, stage,
 * pipe x and bottom y, travel, and per point x, y, p, q [kPa], eps_q,
 * eps_v, rotation [deg], void ratio, coordination, DEM steps of the last
 * MPM step), points_DEF.svg (eps_q against the pipe's travel),
 * points_DEF_rotation.svg (rotation), points_DEF_pq.svg (the p-q paths),
 * each with the paper's values dashed, eps_q_pen.svg, rotation_pen.svg (end
 * of penetration), eps_q_end.svg, rotation_end.svg, points_NNNNNN.vtk
 * (first, last, every --vtk-every steps), checkpoint.bin; a RESULT line.
 *
 * pipe_io.h: the model's state (struct pp, what the checkpoint carries), the
 * CSVs, the plots and the summary of D, E, F; this file: options, the
 * initial state, the path, the step loop, the fields and main.
 */
#define GK_IMPLEMENTATION
#include "pipe_io.h"

/* Liang & Zhao Table 2 "Dense" (400 disks, r 3-7 mm, rho 2650, E 800 MPa, kt/kn 0.5, friction 23 deg,
 * rolling beta 1.0, eta 0.05, local damping 0.1); the DEM step as mpmdem_footing's */
static void defaults(pp *X, int paper) {
    pp_opts *b = &X->b;
    memset(b, 0, sizeof *b);
    b->nx = 24, b->ny = 10, b->width = 6.0, b->D = 1.0, b->mu = 0.5, b->contact = 1, b->gravity = 9.81;
    b->pen = 0.8, b->lat = 0.7, b->v_down = 0.4, b->v_lat = 0.2, b->ramp = 0.2, b->every = 0.02,
    b->room = 1.0;
    if (paper) b->nx = 188, b->ny = 52, b->width = 9.0, b->every = 0.02;
    mpd_opts_default(&X->o, "build/mpm_pipe");
    X->o.young = 800e6, X->o.kt_ratio = 0.5, X->o.friction_deg = 23.0, X->o.roll_beta = 1.0;
    X->o.roll_eta = 0.05, X->o.dem_damping = 0.1;
    X->o.dem_dt = PP_DEM_DT_REF * sqrt(6e8 / X->o.young);
    X->o.dem_max = 0; /* 0: not given, the real-time count */
}

static void usage(FILE *fp) {
    pp X;
    defaults(&X, 0);
    X.o.dem_max = 1000;
    fprintf(fp,
            "mpmdem_pipe - MPMxDEM pipe-soil interaction of Liang & Zhao (2019) Sec 3.4: a rough rigid pipe "
            "pushed\n"
            "down 0.8 m into a soil under gravity (RVEs consolidated to rho g z), then 0.7 m to the left.\n\n"
            "usage: mpmdem_pipe [options]\n"
            "  --paper                the paper's size: 9 m wide, 188 x 52 cells (h = 9/188 m, 9776 RVEs)\n"
            "  --nx N --ny N          cells across the width and the depth (default %d x %d); depth = ny h\n"
            "  --width W              soil width [m] (default %g; the paper's 9); h = W / nx\n"
            "  --diameter D           pipe diameter [m] (default %g), at least 2 cells\n"
            "  --contact stick|friction|smooth   pipe-soil contact (default friction)\n"
            "  --mu M                 Coulomb coefficient of --contact friction (default %g)\n"
            "  --penetration L        vertical stage: depth of the pipe bottom below the ground [m] "
            "(default %g)\n"
            "  --lateral L            lateral stage: travel to the left [m] (default %g; 0: none)\n"
            "  --v-down V             top speed of the vertical stage [m/s] (default %g)\n"
            "  --v-lateral V          top speed of the lateral stage [m/s] (default %g)\n"
            "  --ramp T               speed ramps at both ends of each stage [s] (default %g)\n"
            "  --gravity G            [m/s^2] (default %g)\n"
            "  --levels N             pressure levels of the geostatic start (default: one per point row, "
            "at most %d)\n"
            "  --room R               grid room above the ground for the heave [m] (default %g)\n"
            "  --every DT             time between CSV rows and progress lines [s] (default %g)\n"
            "  --max-steps N          stop after N MPM steps (cost probe; default: the whole path)\n"
            "  --help                 this text\n"
            "material: Liang & Zhao Table 2 'Dense' (E 800 MPa, kt/kn 0.5, friction 23 deg, beta 1.0, eta "
            "0.05,\n"
            "damping 0.1), DEM dt 3.16e-5 s sqrt(6e8 / E); --young etc. below override it.\n"
            "defaults that differ from the common list below: --dem-max = ceil(dt_MPM / dt_DEM), the "
            "real-time\ncount (printed at start), unless given.\n\n",
            X.b.nx, X.b.ny, X.b.width, X.b.D, X.b.mu, X.b.pen, X.b.lat, X.b.v_down, X.b.v_lat, X.b.ramp,
            X.b.gravity, PP_MAX_LEVELS, X.b.room, X.b.every);
    mpd_usage_common(fp, &X.o);
    fprintf(
        fp,
        "\nends with: RESULT V_peak_kN=... V_peak_paper_kN=250 V_end_penetration_kN=... H_end_kN=... "
        "H_end_paper_kN=50\n"
        "           V_lateral_kN=... V_lateral_paper_kN=25 H_lateral_kN=... penetration=... lateral=... "
        "n_rves=...\n"
        "           mpm_steps=... dt=... seconds_per_step=... seconds_per_step_per_1000_rves=... "
        "total_seconds=...\n"
        "           paper_projection_hours=... D_lift_m=... F_lift_m=... D_eps_q_onset=...\n"
        "           D_rotation_onset=... F_eps_q_onset=... F_rotation_onset=... E_p_max_kPa=...\n"
        "           D_eps_q_end=... D_rotation_end=... F_eps_q_end=... F_p_min_lateral_kPa=...\n"
        "           F_p_end_kPa=... F_q_end_kPa=...\n"
        "writes pipe.csv, pipe_force.svg, points_DEF.csv (the paper's points D, E, F: the material points\n"
        "nearest to x0 - 1.1, x0 + 0.1, x0 + 1.1 m at 0.6, 1.05, 0.6 m depth, x0 the pipe's start),\n"
        "points_DEF.svg, points_DEF_rotation.svg, points_DEF_pq.svg, eps_q_*.svg, rotation_*.svg,\n"
        "points_*.vtk and checkpoint.bin into --out.\n");
}

/* the flags, twice: the preset (--paper) first, then every flag given over it */
static int parse(pp *X, int argc, char **argv) {
    pp_opts *b = &X->b;
    const cli_opt mine[] = {
        {"--paper", CLI_FLAG, &b->paper, 0, 0, NULL, NULL, 0},
        {"--nx", CLI_INT, &b->nx, 2, 4000, NULL, NULL, 0},
        {"--ny", CLI_INT, &b->ny, 2, 4000, NULL, NULL, 0},
        {"--levels", CLI_INT, &b->levels, 1, PP_MAX_LEVELS, NULL, NULL, 0},
        {"--width", CLI_REAL, &b->width, 0, 1e4, "a positive length", NULL, CLI_LO_OPEN},
        {"--diameter", CLI_REAL, &b->D, 0, 1e4, "a positive length", NULL, CLI_LO_OPEN},
        {"--contact", CLI_CHOICE, &b->contact, 0, 0, NULL, "stick|friction|smooth", 0},
        {"--mu", CLI_REAL, &b->mu, 0, 1e3, "a friction coefficient >= 0", NULL, 0},
        {"--penetration", CLI_REAL, &b->pen, 0, 1e4, "a positive length", NULL, CLI_LO_OPEN},
        {"--lateral", CLI_REAL, &b->lat, 0, 1e4, "a length >= 0", NULL, 0},
        {"--v-down", CLI_REAL, &b->v_down, 0, 1e3, "a positive speed", NULL, CLI_LO_OPEN},
        {"--v-lateral", CLI_REAL, &b->v_lat, 0, 1e3, "a positive speed", NULL, CLI_LO_OPEN},
        {"--ramp", CLI_REAL, &b->ramp, 0, 1e6, "a time >= 0", NULL, 0},
        {"--gravity", CLI_REAL, &b->gravity, 0, 1e4, "a positive value", NULL, CLI_LO_OPEN},
        {"--room", CLI_REAL, &b->room, 0, 1e4, "a length >= 0", NULL, 0},
        {"--every", CLI_REAL, &b->every, 0, 1e6, "a positive time", NULL, CLI_LO_OPEN},
        {"--max-steps", CLI_INT, &b->max_steps, 1, 2000000000, NULL, NULL, 0},
        {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    int r, rows_pts;
    defaults(X, 0);
    if ((r = mpd_parse(&X->run, argc, argv, &X->o, mine, usage)) != 0) return r;
    r = b->paper;
    defaults(X, r);
    mpd_parse(&X->run, argc, argv, &X->o, mine, usage);
    X->run.out = X->o.out;
    X->dem_max_given = X->o.dem_max > 0;
    if (!X->dem_max_given) X->o.dem_max = 1000000; /* placeholder until dt is known */
    if (mpd_check_opts(&X->run, &X->o)) return 2;
    X->h = b->width / b->nx;
    X->depth = b->ny * X->h;
    if (b->D < 2 * X->h)
        return fprintf(stderr, "mpmdem_pipe: --diameter %g m is less than 2 cells (h = %g m)\n", b->D, X->h),
               2;
    if (b->pen + b->D > X->depth + b->room)
        return fprintf(stderr,
                       "mpmdem_pipe: --penetration %g m: the pipe would leave the grid (depth %g m + --room "
                       "%g m)\n",
                       b->pen, X->depth, b->room),
               2;
    if (b->pen > X->depth - 2 * X->h)
        return fprintf(stderr, "mpmdem_pipe: --penetration %g m reaches the base (depth %g m)\n", b->pen,
                       X->depth),
               2;
    if (b->lat + 0.5 * b->D > 0.5 * b->width - 2 * X->h)
        return fprintf(stderr, "mpmdem_pipe: --lateral %g m takes the pipe to the wall (width %g m)\n",
                       b->lat, b->width),
               2;
    if (b->ramp > b->pen / b->v_down || (b->lat > 0 && b->ramp > b->lat / b->v_lat))
        return fprintf(stderr,
                       "mpmdem_pipe: --ramp %g s is longer than a stage at full speed (L / v): the speed "
                       "would not reach its top\n",
                       b->ramp),
               2;
    rows_pts = b->ny * X->o.ppc;
    if (b->levels == 0) b->levels = rows_pts < PP_MAX_LEVELS ? rows_pts : PP_MAX_LEVELS;
    if (b->levels > rows_pts) b->levels = rows_pts;
    X->dot = 0.5 * X->h / X->o.ppc;
    return 0;
}

/* ---------------------------------------------------- initial state */
/* one RVE state per pressure level (mpd_prepare_levels) */
static int prepare_levels(pp *X, gk_err *err) {
    const pp_opts *b = &X->b;
    double t0 = gk_wtime();
    if (mpd_prepare_levels(&X->P, &X->o, b->levels, X->depth, b->gravity, X->h, X->st, X->lev_p, X->lev_rho,
                           X->lev_e, X->lev_M, X->lev_pa, &X->rho_ref, &X->Mmax, err))
        return 1;
    X->prep_secs = gk_wtime() - t0;
    return 0;
}

/* a checkpoint's state and rows as read (mpd_load's driver check, ctx the model): every value finite
 * and within MPD_MAX_VALUE, the time step the run's, the stage, rows and watched points in range, the
 * next row not behind the time by more than one interval, the pipe the run's circle and contact law */
static int check_state(const void *vS, const mpd_rows *R, const void *ctx, char *why, size_t nwhy) {
    const pp_state *S = (const pp_state *)vS;
    const pp *X = (const pp *)ctx;
    const gk_mpm_body *B = &S->body;
    double v[15];
    int k, j;
    v[0] = S->t, v[1] = S->dt, v[2] = S->done, v[3] = S->t_stage, v[4] = S->pen, v[5] = S->lat;
    v[6] = S->acc_H, v[7] = S->acc_V, v[8] = S->acc_dt, v[9] = S->next_out, v[10] = B->centre[0];
    v[11] = B->centre[1], v[12] = S->acc_dem, v[13] = S->wall, v[14] = B->mu;
    for (k = 0; k < 15; ++k)
        if (!mpd_sane(v[k])) return snprintf(why, nwhy, "pipe state: a non-finite value"), 1;
    for (k = 0; k < 3; ++k)
        if (!mpd_sane(B->v[k]) || !mpd_sane(B->force[k]))
            return snprintf(why, nwhy, "pipe state: a non-finite value"), 1;
    if (S->dt != X->dt_run)
        return snprintf(why, nwhy, "written with another time step (%g s; this run %g s)", S->dt, X->dt_run),
               1;
    if (S->step < 0 || S->step > 1000000000000L || S->stage < 0 || S->stage > 2 || S->pen_row < -1 ||
        S->pen_row >= R->n || S->nacc < 0 || S->nacc > S->step || !(S->t >= 0) || !(S->done >= 0) ||
        !(S->t_stage >= 0) || !(S->wall >= 0) || S->next_out < S->t - 2 * (X->b.every + S->dt))
        return snprintf(why, nwhy, "pipe state out of range"), 1;
    if (B->shape != GK_MPM_CIRCLE || B->radius != 0.5 * X->b.D || B->contact != pp_contacts[X->b.contact] ||
        B->mu != (X->b.contact == 1 ? X->b.mu : 0.0))
        return snprintf(why, nwhy, "the pipe is not this run's (diameter or contact law)"), 1;
    if (mpd_watch_check(S->pt, pp_pt_name, PP_NPT, X->pts.n, why, nwhy)) return 1;
    for (j = 0; j < PP_NPT * PP_NQ; ++j)
        if (!mpd_sane(S->pt0[j / PP_NQ][j % PP_NQ]))
            return snprintf(why, nwhy, "a non-finite start of point %s", pp_pt_name[j / PP_NQ]), 1;
    for (k = 0; k < R->n; ++k) {
        const pp_row *r = (const pp_row *)mpd_row(R, k);
        double w[9];
        w[0] = r->t, w[1] = r->x, w[2] = r->y, w[3] = r->pen, w[4] = r->lat, w[5] = r->H, w[6] = r->V;
        w[7] = r->dem_mean, w[8] = r->secs;
        for (j = 0; j < 9; ++j)
            if (!mpd_sane(w[j])) return snprintf(why, nwhy, "row %d: a non-finite value", k), 1;
        for (j = 0; j < PP_NPT * PP_NQ; ++j)
            if (!mpd_sane(r->pt[j / PP_NQ][j % PP_NQ]))
                return snprintf(why, nwhy, "row %d: a non-finite value of point %s", k,
                                pp_pt_name[j / PP_NQ]),
                       1;
        if (r->stage < 0 || r->stage > 1) return snprintf(why, nwhy, "row %d: stage out of range", k), 1;
    }
    return 0;
}

/* the state of the points D, E, F now (collective: every point's fields) */
static gk_result sample_points(pp *X, double out[PP_NPT][PP_NQ], gk_err *err) {
    static const int f[PP_NQ - 2] = {MPD_P,        MPD_Q,    MPD_EPS_Q, MPD_EPS_V,
                                     MPD_ROTATION, MPD_VOID, MPD_COORD, MPD_DEM};
    int k;
    gk_result r = mpd_fields(&X->M, &X->pts, X->fld, err);
    if (r) return r;
    for (k = 0; k < PP_NPT; ++k) mpd_point_state(&X->pts, X->fld, X->S.pt[k], f, PP_NQ - 2, out[k]);
    return GK_OK;
}

/* the material point nearest to each of pp_pt_at */
static void pick_points(pp *X) {
    int k;
    for (k = 0; k < PP_NPT; ++k)
        X->S.pt[k] = mpd_nearest(&X->pts, X->x0 + pp_pt_at[k][0], X->depth - pp_pt_at[k][1]);
}

/* the levels' RVEs, the grid (rollers, fixed base), the points with their levels' masses, dt, the pipe */
static int setup(pp *X, gk_err *err) {
    const pp_opts *b = &X->b;
    pp_state *S = &X->S;
    double h = X->h, org[3], lo[3] = {0, 0, 0}, hi[3];
    int n[3], i, gl = mpd_ghost_layers(&X->o), up = (int)ceil(b->room / h) + gl;
    if (prepare_levels(X, err)) return 1;
    org[0] = -gl * h, org[1] = -gl * h, org[2] = 0;
    n[0] = b->nx + 2 * gl + 1, n[1] = b->ny + gl + up + 1, n[2] = 1;
    hi[0] = b->width, hi[1] = X->depth, hi[2] = 0;
    if (gk_mpm_grid_create(&X->g, 2, org, h, n, NULL, err) ||
        gk_mpm_grid_set_bc(&X->g, 0, GK_MPM_BC_ROLLER, 0.0, gl + 1, err) ||
        gk_mpm_grid_set_bc(&X->g, 1, GK_MPM_BC_ROLLER, 0.0, gl + 1, err) ||
        gk_mpm_grid_set_bc(&X->g, 2, GK_MPM_BC_FIXED, 0.0, gl + 1, err) ||
        gk_mpm_points_create_box(&X->pts, 2, lo, hi, h, X->o.ppc, X->rho_ref, NULL, err))
        return 1;
    memset(S, 0, sizeof *S);
    X->c = sqrt(X->Mmax / X->rho_ref);
    S->dt = X->o.cfl * h / X->c;
    if (!X->dem_max_given) X->o.dem_max = (int)ceil(S->dt / X->P.dt * (1 - 1e-12));
    if (mpd_check_opts(&X->run, &X->o)) return 2;
    X->pick = (int *)malloc((size_t)X->pts.n * sizeof *X->pick);
    X->fld = (double *)malloc((size_t)MPD_NFIELD * X->pts.n * sizeof *X->fld);
    if (!X->pick || !X->fld) return gk_err_set(err, GK_ERR_ALLOC, "out of memory"), 1;
    for (i = 0; i < X->pts.n; ++i) X->pick[i] = mpd_level_of(X->depth, X->b.levels, X->pts.x[1][i]);
    if (mpd_micro_create(&X->M, &X->pts, &X->P, X->st, b->levels, X->pick, &X->o, err)) return 1;
    for (i = 0; i < X->pts.n; ++i) X->pts.m[i] = X->lev_rho[X->pick[i]] * X->pts.vol0[i];
    X->def = mpd_mpm_def(&X->o);
    X->def.gravity[1] = -b->gravity;
    X->x0 = 0.5 * b->width;
    S->body.shape = GK_MPM_CIRCLE;
    S->body.centre[0] = X->x0, S->body.centre[1] = X->depth + 0.5 * b->D, S->body.radius = 0.5 * b->D;
    S->body.contact = pp_contacts[b->contact];
    S->body.mu = b->contact == 1 ? b->mu : 0.0;
    S->next_out = b->every;
    S->pen_row = -1;
    X->rows.size = sizeof(pp_row);
    pick_points(X);
    X->dt_run = S->dt;
    if (X->o.restart) {
        if (mpd_load(X->o.restart, &X->M, &X->pts, "pipe", S, sizeof *S, &X->rows, &X->snaps, check_state, X,
                     err))
            return 1;
        printf("restarted from %s/checkpoint.bin at t = %.4f s (step %ld, stage %d)\n", X->o.restart, S->t,
               S->step, S->stage + 1);
    } else if (sample_points(X, S->pt0, err))
        return 1;
    X->g.body = &S->body, X->g.nbody = 1;
    return 0;
}

/* -------------------------------------------------------- the path */
/* stage length, top speed and direction */
static void stage_of(const pp *X, int stage, double *L, double *v, double dir[2]) {
    *L = stage == 0 ? X->b.pen : X->b.lat;
    *v = stage == 0 ? X->b.v_down : X->b.v_lat;
    dir[0] = stage == 0 ? 0.0 : -1.0, dir[1] = stage == 0 ? -1.0 : 0.0;
}

/* the pipe velocity of the next step (trapezoid at mid-step, the last step cut to the stage's end);
 * returns the distance it will travel */
static double set_velocity(pp *X) {
    pp_state *S = &X->S;
    double L, v, dir[2], tm = S->t_stage + 0.5 * S->dt, T, s, ds, r = X->b.ramp;
    stage_of(X, S->stage, &L, &v, dir);
    T = L / v + r;
    s = r > 0 ? v * fmin(1.0, fmin(tm / r, (T - tm) / r)) : v;
    ds = s > 0 ? s * S->dt : 0.0;
    if (S->done + ds > L || tm >= T) ds = L - S->done;
    S->body.v[0] = dir[0] * ds / S->dt, S->body.v[1] = dir[1] * ds / S->dt, S->body.v[2] = 0;
    return ds;
}

/* eps_q and the rotation of the points; the pipe (a 15-gon), the walls and the base drawn */
static int snapshot(pp *X, const char *tag, const char *when) {
    char file[48], title[160];
    double box[8], arc[12], cx = X->S.body.centre[0], cy = X->S.body.centre[1], R = X->S.body.radius;
    mpd_outline ol;
    int a, k, bad;
    memset(&ol, 0, sizeof ol);
    box[0] = 0, box[1] = X->depth + X->h, box[2] = 0, box[3] = 0, box[4] = X->b.width, box[5] = 0,
    box[6] = X->b.width, box[7] = X->depth + X->h;
    mpd_outline_add(&ol, 4, box);
    for (a = 0; a < 3; ++a) {
        for (k = 0; k < 6; ++k) {
            double th = 2.0 * MPD_PI * (5 * a + k) / 15.0;
            arc[2 * k] = cx + R * cos(th), arc[2 * k + 1] = cy + R * sin(th);
        }
        mpd_outline_add(&ol, 6, arc);
    }
    snprintf(file, sizeof file, "eps_q_%s", tag);
    snprintf(title, sizeof title, "deviatoric strain eps_q, %s, t = %.3f s (Liang & Zhao Fig 22)", when,
             X->S.t);
    bad = mpd_snap_field(&X->run, &X->snaps, &X->M, &X->pts, MPD_EPS_Q, file, title, X->dot, &ol);
    snprintf(file, sizeof file, "rotation_%s", tag);
    snprintf(title, sizeof title, "rotation of F (counter-clockwise), %s, t = %.3f s", when, X->S.t);
    if (!bad)
        bad = mpd_snap_field(&X->run, &X->snaps, &X->M, &X->pts, MPD_ROTATION, file, title, X->dot, &ol);
    return bad;
}

/* a CSV row of the means since the last one (resets them); 0 or 1 (said) */
static int add_row(pp *X, double t_start) {
    pp_state *S = &X->S;
    pp_row r;
    gk_err err;
    memset(&r, 0, sizeof r);
    r.t = S->t, r.x = S->body.centre[0], r.y = S->body.centre[1] - S->body.radius, r.pen = S->pen,
    r.lat = S->lat;
    r.stage = S->stage > 1 ? 1 : S->stage;
    r.H = S->acc_dt > 0 ? S->acc_H / S->acc_dt : 0.0, r.V = S->acc_dt > 0 ? S->acc_V / S->acc_dt : 0.0;
    r.dem_mean = S->nacc ? S->acc_dem / S->nacc : 0;
    r.secs = S->wall + gk_wtime() - t_start;
    S->acc_H = S->acc_V = S->acc_dt = S->acc_dem = 0, S->nacc = 0;
    if (sample_points(X, r.pt, &err))
        return fprintf(stderr, "mpmdem_pipe: the points D, E, F at t = %.4f s: %s\n", S->t, err.msg), 1;
    return mpd_rows_push(&X->run, &X->rows, &r);
}

/* after a step of length ds: sums, a row when due or at a stage's end, the end-of-penetration
 * snapshot, progress; 0 or 1 (said) */
static int after_step(pp *X, double ds, double t_start, long step0, long nsteps_total) {
    pp_state *S = &X->S;
    double L, v, dir[2];
    long long sum = 0;
    int i, bad = 0, ended = 0;
    stage_of(X, S->stage, &L, &v, dir);
    S->t += S->dt, S->t_stage += S->dt, S->done += ds, ++S->step;
    if (S->stage == 0)
        S->pen += ds;
    else
        S->lat += ds;
    S->acc_H += -S->body.force[0] * S->dt, S->acc_V += -S->body.force[1] * S->dt, S->acc_dt += S->dt;
    for (i = 0; i < X->pts.n; ++i) sum += X->M.nsub[i];
    S->acc_dem += (double)sum / X->pts.n, ++S->nacc;
    if (S->done >= L * (1 - 1e-12)) ended = 1;
    if (!ended && S->t < S->next_out - 1e-9 * S->dt) return 0;
    if ((bad = add_row(X, t_start)) != 0) return bad;
    while (S->next_out <= S->t + 1e-9 * S->dt) S->next_out += X->b.every;
    if (ended) {
        if (S->stage == 0) {
            S->pen_row = X->rows.n - 1;
            bad = snapshot(X, "pen", "end of penetration");
        }
        S->stage += S->stage == 0 && X->b.lat > 0 ? 1 : 2 - S->stage;
        S->done = 0, S->t_stage = 0;
    }
    if (!bad)
        bad = mpd_write(&X->run, "pipe.csv", put_csv, X) ||
              mpd_write(&X->run, "points_DEF.csv", put_def_csv, X);
    if (!X->o.quiet) {
        const pp_row *r = (const pp_row *)mpd_row(&X->rows, X->rows.n - 1);
        char buf[64], buf2[64];
        double el = gk_wtime() - t_start;
        long done = S->step - step0;
        fprintf(stderr,
                "t %.3f s  step %ld/%ld  stage %d  down %.3f m  left %.3f m  V %.2f kN/m  H %.2f kN/m  DEM "
                "%.1f/pt | %s elapsed, ETA %s\n",
                r->t, S->step, nsteps_total, r->stage + 1, r->pen, r->lat, r->V / 1e3, r->H / 1e3,
                r->dem_mean, mpd_duration(el, buf, sizeof buf),
                mpd_duration(done ? el / done * (nsteps_total - S->step) : 0.0, buf2, sizeof buf2));
    }
    return bad;
}

static int save(pp *X, double t_start) {
    double w0 = X->S.wall;
    int bad;
    X->S.wall += gk_wtime() - t_start;
    bad = mpd_save(&X->run, &X->M, &X->pts, "pipe", &X->S, sizeof X->S, &X->rows, &X->snaps);
    X->S.wall = w0;
    return bad;
}

/* MPM steps of the whole path at time step dt */
static double path_steps(const pp_opts *b, double dt) {
    return (b->pen / b->v_down + b->ramp + (b->lat > 0 ? b->lat / b->v_lat + b->ramp : 0.0)) / dt;
}

/* the end: a last row, CSV, plot, fields, the summary and RESULT; 0 or 1 */
static int finish(pp *X, double t_start, long steps_run, int bad) {
    const pp_opts *b = &X->b;
    pp_state *S = &X->S;
    double secs = gk_wtime() - t_start, vpk = NAN, vpen = NAN, hend = NAN, vlat = NAN, hlat = NAN, per_rve,
           hp, dtp, stepsp, sv = 0, sh = 0, sw = 0;
    int k, n, np = X->pts.n;
    char buf[64];
    double dv[PP_NDV];
    if (S->acc_dt > 0 && add_row(X, t_start)) return 1;
    n = X->rows.n;
    if (!bad)
        bad = mpd_write(&X->run, "pipe.csv", put_csv, X) ||
              mpd_write(&X->run, "points_DEF.csv", put_def_csv, X) ||
              (n > 0 && (write_plot(X) || write_def_plots(X))) ||
              snapshot(X, "end", S->stage == 2 ? "end" : "last step") ||
              mpd_write_vtk(&X->run, S->step, &X->M, &X->pts);

    for (k = 0; k < n; ++k) {
        const pp_row *r = (const pp_row *)mpd_row(&X->rows, k);
        if (r->stage == 0 && !(r->V <= vpk)) vpk = r->V;
        if (r->stage == 1 && r->lat <= b->lat - 0.5 * b->v_lat * b->ramp * (1 + 1e-9)) hend = r->H;
        if (r->stage == 1 && r->lat >= 0.5 * b->lat) {
            double w = k > 0 ? r->t - ((const pp_row *)mpd_row(&X->rows, k - 1))->t : r->t;
            sv += w * r->V, sh += w * r->H, sw += w;
        }
    }
    if (S->pen_row >= 0) vpen = ((const pp_row *)mpd_row(&X->rows, S->pen_row))->V;
    if (S->stage != 2) hend = NAN;
    if (sw > 0 && S->stage == 2) vlat = sv / sw, hlat = sh / sw;
    if (!bad)
        printf("wrote %s/pipe.csv, pipe_force.svg, points_DEF.csv, points_DEF.svg, points_DEF_rotation.svg, "
               "points_DEF_pq.svg, eps_q_*.svg, rotation_*.svg, points_*.vtk (ParaView), checkpoint.bin\n",
               X->run.out);
    printf("pipe at the end: down %.4g m, left %.4g m (%s)\n", S->pen, S->lat,
           S->stage == 2 ? "the whole path" : "stopped before the end of the path");
    printf("penetration: V peak %.4g kN/m, V at its end %.4g kN/m (Liang & Zhao: ~250 kN/m at the end of "
           "penetration, then a drop)\n",
           vpk / 1e3, vpen / 1e3);
    printf(
        "lateral stage, second half: V %.4g kN/m (Liang & Zhao ~25, steady), H %.4g kN/m; H at the end (the "
        "last row before the speed ramps down) %.4g kN/m (Liang & Zhao ~50, rising slightly)\n",
        vlat / 1e3, hlat / 1e3, hend / 1e3);
    def_summary(X, dv);
    per_rve = steps_run ? secs / steps_run / np : 0.0;
    printf(
        "cost: %s for %ld MPM steps, %lld DEM steps over all RVEs (%.2f per point per MPM step); %.4g s per "
        "MPM step per 1000 RVEs\n",
        mpd_duration(secs, buf, sizeof buf), steps_run, X->M.dem_steps,
        steps_run ? (double)X->M.dem_steps / steps_run / np : 0.0, 1000.0 * per_rve);
    mpd_print_traffic(&X->run, &X->M, steps_run, X->o.threads);
    /* the paper's size at this run's speeds and cost per RVE per MPM step */
    hp = 9.0 / 188.0, dtp = S->dt * hp / X->h, stepsp = path_steps(b, dtp);
    printf(
        "paper size projection (9776 RVEs, h = %.4g m, dt ~ %.3g s, %.0f MPM steps for this path): wall ~ %s "
        "on these cores at this run's %.3g ms per RVE per MPM step\n",
        hp, dtp, stepsp, mpd_duration(per_rve * 9776.0 * stepsp, buf, sizeof buf), 1e3 * per_rve);
    printf(
        "RESULT V_peak_kN=%.5g V_peak_paper_kN=250 V_end_penetration_kN=%.5g H_end_kN=%.5g H_end_paper_kN=50 "
        "V_lateral_kN=%.5g V_lateral_paper_kN=25 H_lateral_kN=%.5g penetration=%.5g lateral=%.5g n_rves=%d "
        "mpm_steps=%ld dt=%.4g seconds_per_step=%.4g seconds_per_step_per_1000_rves=%.4g "
        "total_seconds=%.2f paper_projection_hours=%.4g D_lift_m=%.4g F_lift_m=%.4g D_eps_q_onset=%.4g "
        "D_rotation_onset=%.4g F_eps_q_onset=%.4g F_rotation_onset=%.4g E_p_max_kPa=%.5g D_eps_q_end=%.4g "
        "D_rotation_end=%.4g F_eps_q_end=%.4g F_p_min_lateral_kPa=%.4g F_p_end_kPa=%.4g F_q_end_kPa=%.4g\n",
        vpk / 1e3, vpen / 1e3, hend / 1e3, vlat / 1e3, hlat / 1e3, S->pen, S->lat, np, steps_run, S->dt,
        steps_run ? secs / steps_run : 0.0, 1000.0 * per_rve, secs, per_rve * 9776.0 * stepsp / 3600.0, dv[0],
        dv[1], dv[2], dv[3], dv[4], dv[5], dv[6], dv[7], dv[8], dv[9], dv[10], dv[11], dv[12]);
    return bad;
}

static void print_setup(const pp *X, long nsteps_total) {
    const pp_opts *b = &X->b;
    int k;
    printf(
        "mpmdem_pipe: soil %g x %.4g m, %d x %d cells, h = %.4g m, %d points (= RVEs of %d disks), basis %d, "
        "alpha %g; pipe D = %g m (%.3g cells), contact %s",
        b->width, X->depth, b->nx, b->ny, X->h, X->pts.n, X->P.pk.n, (int)X->def.basis, X->o.alpha, b->D,
        b->D / X->h,
        b->contact == 0   ? "stick"
        : b->contact == 1 ? "friction"
                          : "smooth");
    if (b->contact == 1) printf(" mu %g", b->mu);
    printf("\nmaterial: Liang & Zhao Table 2 'Dense': E %g MPa, kt/kn %g, friction %g deg, beta %g, eta %g, "
           "damping %g; DEM dt %.3g s\n",
           X->o.young / 1e6, X->o.kt_ratio, X->o.friction_deg, X->o.roll_beta, X->o.roll_eta,
           X->o.dem_damping, X->o.dem_dt);
    printf("geostatic start: %d levels, p_k = max(rho g z_k, rho g h/2), rho = %.1f kg/m3 (%.1f s on %d "
           "threads)\n",
           b->levels, X->rho_ref, X->prep_secs, X->o.threads);
    for (k = 0; k < b->levels; ++k)
        printf(
            "  level %d: depth %.3f-%.3f m  p target %.4g kPa, reached %.4g kPa, e = %.4f, rho = %.1f, M = "
            "%.4g MPa\n",
            k, X->depth * k / b->levels, X->depth * (k + 1) / b->levels, X->lev_p[k] / 1e3,
            X->lev_pa[k] / 1e3, X->lev_e[k], X->lev_rho[k], X->lev_M[k] / 1e6);
    printf("MPM dt = %.4g s (cfl %.2f, c = %.1f m/s from M = %.4g MPa); ", X->S.dt, X->o.cfl, X->c,
           X->Mmax / 1e6);
    mpd_print_dem_rule(&X->o);
    printf("DEM steps per MPM step at most %d (%s)\n", X->o.dem_max,
           X->dem_max_given ? "--dem-max" : "the real-time count ceil(dt / dt_DEM)");
    printf("path: down %g m at up to %g m/s, then left %g m at up to %g m/s, ramps %g s: about %ld MPM "
           "steps%s\n",
           b->pen, b->v_down, b->lat, b->v_lat, b->ramp, nsteps_total, b->max_steps ? " (--max-steps)" : "");
    fflush(stdout);
}

static int run(pp *X, int argc, char **argv) {
    const pp_opts *b = &X->b;
    pp_state *S = &X->S;
    double t_start;
    long nsteps_total, step0;
    int status = parse(X, argc, argv), bad = 0;
    gk_err err;
    if (status) return status == 1 ? 0 : status;
    /* the inputs (packing, checkpoint) first: bad input leaves no output folder behind */
    if ((status = setup(X, &err)) != 0)
        return status == 2 ? 2 : (fprintf(stderr, "mpmdem_pipe: %s\n", err.msg), 1);
    if (mpd_out_dir(&X->run)) return 1;
    nsteps_total = (long)ceil(path_steps(b, S->dt));
    if (b->max_steps && S->step + b->max_steps < nsteps_total) nsteps_total = S->step + b->max_steps;
    print_setup(X, nsteps_total);
    t_start = gk_wtime();
    if (!X->o.restart && mpd_write_vtk(&X->run, 0, &X->M, &X->pts)) return 1;
    step0 = S->step;
    while (!bad && S->stage < 2 && !(b->max_steps && S->step - step0 >= b->max_steps)) {
        double ds = set_velocity(X);
        X->M.t = S->t;
        if (mpd_step(&X->g, &X->pts, &X->def, S->dt, &X->M, NULL, 0, &err)) { /* also moves the pipe */
            fprintf(stderr, "mpmdem_pipe: step %ld (t = %.4f s): %s\n", S->step, S->t, err.msg);
            status = 3;
            break;
        }
        bad = after_step(X, ds, t_start, step0, nsteps_total);
        if (!bad && X->o.vtk_every && S->step % X->o.vtk_every == 0)
            bad = mpd_write_vtk(&X->run, S->step, &X->M, &X->pts);
        if (!bad && X->o.checkpoint_every && S->step % X->o.checkpoint_every == 0) bad = save(X, t_start);
    }
    if (!bad && status == 0) bad = save(X, t_start);
    bad = finish(X, t_start, S->step - step0, bad);
    return status ? status : bad;
}

int main(int argc, char **argv) {
    pp X;
    int status, k;
    memset(&X, 0, sizeof X);
    for (k = 0; k < PP_MAX_LEVELS; ++k) gk_rve_state_init(&X.st[k], NULL);
    mpd_begin(&X.run, "mpmdem_pipe", &argc, &argv);
    status = run(&X, argc, argv);
    free(X.pick), free(X.fld);
    mpd_free_all(&X.M, &X.P, &X.pts, &X.g, &X.rows, &X.snaps);
    for (k = 0; k < PP_MAX_LEVELS; ++k) gk_rve_state_free(&X.st[k]);
    return mpd_end(status);
}
