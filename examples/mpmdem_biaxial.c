/* mpmdem_biaxial.c - the MPMxDEM biaxial test of Liang & Zhao (2019) Sec
 * 3.2: a 1 x 2 m specimen of material points, each with its own periodic
 * 400-disk RVE, 100 kPa lateral pressure on both sides, fixed base, rough
 * rigid top plate moving down at 0.02 m/s (ramped), no gravity. Reported by
 * the paper for mesh M (20x10 cells, 4 points per cell): peak sigma_yy ~ 280
 * kPa at ~1.6 % axial strain, ~220 kPa at 8 %, cross-shaped shear bands,
 * rotations up to 58 deg in the bands at 15 %.
 *
 *   build/mpmdem_biaxial                       # 8 x 16 cells, 1 point each, to 3 %
 *   build/mpmdem_biaxial --nx 10 --ny 20 --ppc 2 --strain 0.15   # the paper's M4
 *   mpirun -np 2 build/mpmdem_biaxial_mpi --threads 1         # the RVEs on 2 ranks
 *
 * Model. Points fill the specimen (ppc^2 per cell, h = width / nx); the grid
 * is padded by ghost layers and by room for the bulge. The base and the top
 * plate are rigid STICK bodies (rough; the base at rest): their reactions
 * are the axial loads. The lateral pressure is a follower load on the outer
 * edges of the points of the outer columns (mpd_edge in mpmdem.h: the edge
 * turns and stretches with the point's F, and its load goes to the nodes
 * with the weights of the edge, so the initial state is in equilibrium).
 * Every point's RVE starts from the packing (default: Guo & Zhao's 400
 * disks, consolidated to 100 kPa, e = 0.175; the paper states 0.177) and
 * receives dH = dt L each MPM step (USF, mpmdem.h). sigma_yy = -(plate
 * reaction)/width (the rough plate keeps the top width), averaged over each
 * output interval; eps_v from the point volumes; rotation of each point from
 * the polar decomposition of F.
 *
 * Outputs in --out DIR (default build/mpm_biaxial): biaxial.csv,
 * biaxial_stress.svg, biaxial_volume.svg, rotation_*.svg and eps_q_*.svg
 * (fields at 1.5 %, 2 %, 3 % and the end, the paper's stages; one colour
 * scale per quantity), points_ABC.csv and points_ABC_*.svg (the paper's
 * points A, B, C: their state at the start and at every biaxial.csv row),
 * points_NNNNNN.vtk, checkpoint.bin; a RESULT line.
 */
#define GK_IMPLEMENTATION
#include "mpmdem_watch.h"

typedef struct bx_opts {
    int nx, ny;
    double width, height, pressure, velocity, ramp, strain, every;
} bx_opts;

/* the paper's points A, B, C (Sec 3.2, Figs 5 and 9-11): A in the bottom part, far from the shear
 * bands; B at the centre, where the two bands cross ("the lower center of the cross-shape shear
 * bands"); C in the upper right part, inside the rightward-tilting band. The paper marks them only in
 * its figures: these are positions chosen from that text, as fractions of the width and the height (a
 * band at 60 deg through the centre passes x = 0.85 W at y = 0.8 H); each is the material point nearest
 * to its position at the start. */
#define BX_NPT 3
#define BX_NQ 11 /* x, y, then the fields of bx_q_field */
static const char *const bx_pt_name[BX_NPT] = {"A", "B", "C"};
static const double bx_pt_at[BX_NPT][2] = {{0.5, 0.1}, {0.5, 0.45}, {0.85, 0.8}};
static const char *const bx_q_name[BX_NQ] = {"x",
                                             "y",
                                             "p_kPa",
                                             "q_kPa",
                                             "eps_q",
                                             "eps_v",
                                             "rotation_deg",
                                             "void_ratio",
                                             "fabric_anisotropy",
                                             "coordination",
                                             "dem_steps"};
static const int bx_q_field[BX_NQ - 2] = {MPD_P,    MPD_Q,      MPD_EPS_Q, MPD_EPS_V, MPD_ROTATION,
                                          MPD_VOID, MPD_FABRIC, MPD_COORD, MPD_DEM};
enum { BX_X, BX_Y, BX_P, BX_Q, BX_EQ, BX_EV, BX_ROT, BX_E, BX_FA, BX_Z, BX_DEM };

typedef struct bx_row { /* one CSV row: means over an output interval; the points A, B, C at its end */
    double t, eps, syy_top, syy_base, ev, ek, dem_mean, secs;
    double pt[BX_NPT][BX_NQ];
} bx_row;

/* the state a checkpoint carries besides points and RVEs */
typedef struct bx_state {
    long step;
    double t, disp;
    gk_mpm_body body[2];              /* 0: base, 1: top plate */
    double acc_top, acc_base, acc_dt; /* force x dt accumulated since the last row */
    double acc_ek, acc_dem;           /* kinetic energy, DEM steps per point: sums */
    long nacc;                        /*   over the MPM steps since the last row    */
    double next_out;                  /* axial strain of the next CSV row */
    int nstage;
    int pt[BX_NPT];            /* the material points A, B, C */
    double pt0[BX_NPT][BX_NQ]; /* their state at the start */
} bx_state;

typedef struct bx { /* the whole model */
    mpd_run run;
    mpd_opts o;
    bx_opts b;
    mpd_proto P;
    gk_rve_state st0;
    mpd_micro M;
    gk_mpm_grid g;
    gk_mpm_points pts;
    gk_mpm_def def;
    mpd_edge *edge;
    int nedge;
    bx_state S;
    mpd_rows rows;
    mpd_snaps snaps;
    double *fld; /* MPD_NFIELD x points: the fields when a row is taken */
    double h, dt, c, vol0, dot;
} bx;

static const double bx_stages[3] = {0.015, 0.02, 0.03};

static void usage(FILE *fp) {
    mpd_opts d;
    mpd_opts_default(&d, "build/mpm_biaxial");
    fprintf(
        fp,
        "mpmdem_biaxial - MPMxDEM biaxial test of Liang & Zhao (2019) Sec 3.2: every material point has a\n"
        "periodic 400-disk RVE; lateral pressure, rough top plate, fixed base, no gravity.\n\n"
        "usage: mpmdem_biaxial [options]\n"
        "  --nx N --ny N          cells across the width and the height (default 8 x 16; the paper's meshes\n"
        "                         C 8x16, M 10x20, F 15x30 with --ppc 1 or 2, or 3 for 9 points per cell)\n"
        "  --width W --height H   specimen [m] (default 1 x 2); W/nx must equal H/ny\n"
        "  --pressure P           lateral pressure sigma_3 [Pa] (default 1e5)\n"
        "  --velocity V           top plate speed [m/s] (default 0.02, the paper's)\n"
        "  --ramp T               the plate speed ramps up linearly over T seconds (default 0.5)\n"
        "  --strain E             final axial strain (default 0.03; the paper goes to 0.15)\n"
        "  --every E              axial strain between CSV rows (default 0.001)\n"
        "  --help                 this text\n");
    mpd_usage_common(fp, &d);
    fprintf(fp,
            "\nends with: RESULT peak_sigma_yy=... eps_at_peak=... sigma_yy_end=... max_rotation_deg=...\n"
            "           n_rves=... mpm_steps=... seconds_per_step=... seconds_per_step_per_1000_rves=...\n");
}

static int parse(bx *X, int argc, char **argv) {
    bx_opts *b = &X->b;
    const cli_opt mine[] = {{"--nx", CLI_INT, &b->nx, 1, 2000, NULL, NULL, 0},
                            {"--ny", CLI_INT, &b->ny, 1, 2000, NULL, NULL, 0},
                            {"--width", CLI_REAL, &b->width, 0, 1e4, NULL, NULL, CLI_LO_OPEN},
                            {"--height", CLI_REAL, &b->height, 0, 1e4, NULL, NULL, CLI_LO_OPEN},
                            {"--pressure", CLI_REAL, &b->pressure, 0, 1e10, NULL, NULL, 0},
                            {"--velocity", CLI_REAL, &b->velocity, 0, 1e3, NULL, NULL, CLI_LO_OPEN},
                            {"--ramp", CLI_REAL, &b->ramp, 0, 1e6, NULL, NULL, 0},
                            {"--strain", CLI_REAL, &b->strain, 0, 0.5, NULL, NULL, CLI_LO_OPEN | CLI_HI_OPEN},
                            {"--every", CLI_REAL, &b->every, 0, 0.5, NULL, NULL, CLI_LO_OPEN},
                            {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    bx_opts def = {8, 16, 1.0, 2.0, 1e5, 0.02, 0.5, 0.03, 0.001};
    int r;
    *b = def;
    mpd_opts_default(&X->o, "build/mpm_biaxial");
    if ((r = mpd_parse(&X->run, argc, argv, &X->o, mine, usage)) != 0) return r;
    X->run.out = X->o.out;
    if (mpd_check_opts(&X->run, &X->o)) return 2;
    X->h = b->width / b->nx;
    if (fabs(b->height / b->ny - X->h) > 1e-9 * X->h) {
        fprintf(stderr, "mpmdem_biaxial: cells must be square: width/nx = %g, height/ny = %g\n", X->h,
                b->height / b->ny);
        return 2;
    }
    return 0;
}

/* a checkpoint's state and rows in range (mpd_load, ctx the model): counters >= 0 (the stage an index
 * of bx_stages), times, plates, sums and rows finite and within MPD_MAX_VALUE, each plate a box with a
 * known contact law and face, the watched points points of the run */
static int bx_check(const void *state, const mpd_rows *R, const void *ctx, char *why, size_t nwhy) {
    const bx_state *S = (const bx_state *)state;
    double v[7];
    int k, j;
    if (mpd_watch_check(S->pt, bx_pt_name, BX_NPT, ((const bx *)ctx)->pts.n, why, nwhy)) return 1;
    v[0] = S->t, v[1] = S->disp, v[2] = S->acc_top, v[3] = S->acc_base, v[4] = S->acc_dt, v[5] = S->acc_ek;
    v[6] = S->acc_dem;
    for (k = 0; k < 7; ++k)
        if (!mpd_sane(v[k])) return snprintf(why, nwhy, "a non-finite time, displacement or sum"), 1;
    if (S->step < 0 || S->step > 1000000000000L || S->nacc < 0 || S->nacc > S->step || S->nstage < 0 ||
        S->nstage > 3 || !(S->next_out > 0 && S->next_out < 1e6) || !(S->t >= 0))
        return snprintf(why, nwhy, "a step, stage or output counter out of range"), 1;
    for (k = 0; k < 2; ++k) {
        const gk_mpm_body *b = &S->body[k];
        for (j = 0; j < 3; ++j)
            if (!mpd_sane(b->lo[j]) || !mpd_sane(b->hi[j]) || !mpd_sane(b->v[j]) || !mpd_sane(b->force[j]) ||
                !(b->lo[j] <= b->hi[j]))
                return snprintf(why, nwhy, "plate %d is not a finite box", k), 1;
        if ((int)b->contact < 0 || (int)b->contact > (int)GK_MPM_CONTACT_SMOOTH ||
            !(b->mu >= 0 && b->mu < 1e6) || b->face < 0 || b->face > 6)
            return snprintf(why, nwhy, "plate %d: contact law out of range", k), 1;
    }
    for (k = 0; k < R->n; ++k) {
        const bx_row *r = (const bx_row *)mpd_row(R, k);
        double w[8];
        w[0] = r->t, w[1] = r->eps, w[2] = r->syy_top, w[3] = r->syy_base, w[4] = r->ev, w[5] = r->ek;
        w[6] = r->dem_mean, w[7] = r->secs;
        for (j = 0; j < 8; ++j)
            if (!mpd_sane(w[j])) return snprintf(why, nwhy, "row %d: a non-finite value", k), 1;
        for (j = 0; j < BX_NPT * BX_NQ; ++j)
            if (!mpd_sane(r->pt[j / BX_NQ][j % BX_NQ]))
                return snprintf(why, nwhy, "row %d: a non-finite value of point %s", k,
                                bx_pt_name[j / BX_NQ]),
                       1;
    }
    for (j = 0; j < BX_NPT * BX_NQ; ++j)
        if (!mpd_sane(S->pt0[j / BX_NQ][j % BX_NQ]))
            return snprintf(why, nwhy, "a non-finite start of point %s", bx_pt_name[j / BX_NQ]), 1;
    return 0;
}

/* the state of the points A, B, C now (collective: every point's fields) */
static gk_result sample_points(bx *X, double out[BX_NPT][BX_NQ], gk_err *err) {
    int k;
    gk_result r = mpd_fields(&X->M, &X->pts, X->fld, err);
    if (r) return r;
    for (k = 0; k < BX_NPT; ++k) mpd_point_state(&X->pts, X->fld, X->S.pt[k], bx_q_field, BX_NQ - 2, out[k]);
    return GK_OK;
}

/* the prepared RVE at every point, the grid with its two plates, the points and their edge loads */
static int setup(bx *X, gk_err *err) {
    bx_opts *b = &X->b;
    double h = X->h, org[3], lo[3] = {0, 0, 0}, hi[3];
    int n[3], i, gl = mpd_ghost_layers(&X->o), padx = gl + (int)ceil(0.3 * b->nx);
    bx_state *S = &X->S;
    if (mpd_proto_open(&X->P, &X->o, err) || mpd_prepare_rve(&X->P, b->pressure, &X->st0, err)) return 1;
    X->c = sqrt(X->P.M / X->P.rho);
    X->dt = X->o.cfl * h / X->c;
    /* grid: ghost layers, room for a 30 % bulge on each side, the plate above */
    org[0] = -padx * h, org[1] = -gl * h, org[2] = 0;
    n[0] = b->nx + 2 * padx + 1, n[1] = b->ny + 2 * gl + 1, n[2] = 1;
    hi[0] = b->width, hi[1] = b->height, hi[2] = 0;
    if (gk_mpm_grid_create(&X->g, 2, org, h, n, NULL, err) ||
        gk_mpm_points_create_box(&X->pts, 2, lo, hi, h, X->o.ppc, X->P.rho, NULL, err) ||
        mpd_micro_create(&X->M, &X->pts, &X->P, &X->st0, 1, NULL, &X->o, err))
        return 1;
    if (!(X->edge = (mpd_edge *)calloc((size_t)X->pts.n, sizeof *X->edge)))
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory"), 1;
    for (i = 0; i < X->pts.n; ++i) { /* the lateral pressure on the outer columns' outer edges */
        double a = 0.5 * h / X->o.ppc, side = X->pts.x[0][i] < 2 * a              ? -1
                                              : X->pts.x[0][i] > b->width - 2 * a ? 1
                                                                                  : 0;
        mpd_edge *E = &X->edge[X->nedge];
        X->vol0 += X->pts.vol0[i];
        if (side == 0) continue;
        E->p = i, E->pressure = b->pressure, E->off[0] = side * a, E->off[1] = 0, E->e[0] = 0,
        E->e[1] = side * 2 * a;
        ++X->nedge;
    }
    X->def = mpd_mpm_def(&X->o);
    X->dot = 0.5 * h / X->o.ppc;
    memset(S, 0, sizeof *S);
    S->body[0].lo[0] = org[0] - h, S->body[0].hi[0] = -org[0] + b->width + h;
    S->body[0].lo[1] = org[1] - h, S->body[0].hi[1] = 1e-9 * h;
    S->body[1].lo[0] = S->body[0].lo[0], S->body[1].hi[0] = S->body[0].hi[0];
    S->body[1].lo[1] = b->height - 1e-9 * h, S->body[1].hi[1] = b->height + 10 * h;
    S->body[0].contact = S->body[1].contact = GK_MPM_CONTACT_STICK;
    S->next_out = b->every;
    X->rows.size = sizeof(bx_row);
    if (!(X->fld = (double *)malloc((size_t)MPD_NFIELD * X->pts.n * sizeof *X->fld)))
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory"), 1;
    for (i = 0; i < BX_NPT; ++i)
        S->pt[i] = mpd_nearest(&X->pts, bx_pt_at[i][0] * b->width, bx_pt_at[i][1] * b->height);
    if (X->o.restart) {
        if (mpd_load(X->o.restart, &X->M, &X->pts, "biaxial", S, sizeof *S, &X->rows, &X->snaps, bx_check, X,
                     err))
            return 1;
    } else if (sample_points(X, S->pt0, err))
        return 1;
    X->g.body = S->body, X->g.nbody = 2;
    return 0;
}

/* the base and the plate over the specimen's current width */
static void outline(const bx *X, mpd_outline *ol) {
    double x0 = 1e300, x1 = -1e300, y = X->b.height - X->S.disp, e = 0.5 * X->h, base[4], plate[4];
    int p;
    for (p = 0; p < X->pts.n; ++p) x0 = fmin(x0, X->pts.x[0][p]), x1 = fmax(x1, X->pts.x[0][p]);
    base[0] = x0 - 2 * e, base[1] = 0, base[2] = x1 + 2 * e, base[3] = 0;
    plate[0] = base[0], plate[1] = y, plate[2] = base[2], plate[3] = y;
    memset(ol, 0, sizeof *ol);
    mpd_outline_add(ol, 2, base);
    mpd_outline_add(ol, 2, plate);
}

/* rotation and eps_q fields at a stage (the paper's Fig 8) */
static int stage_fields(bx *X, const char *tag) {
    char file[48], title[160];
    mpd_outline ol;
    int bad;
    outline(X, &ol);
    snprintf(file, sizeof file, "rotation_%s", tag);
    snprintf(title, sizeof title, "rotation of F = RU at %s axial strain (Liang & Zhao Fig 8)", tag);
    bad = mpd_snap_field(&X->run, &X->snaps, &X->M, &X->pts, MPD_ROTATION, file, title, X->dot, &ol);
    snprintf(file, sizeof file, "eps_q_%s", tag);
    snprintf(title, sizeof title, "deviatoric strain eps_q at %s axial strain", tag);
    return bad || mpd_snap_field(&X->run, &X->snaps, &X->M, &X->pts, MPD_EPS_Q, file, title, X->dot, &ol);
}

static void put_csv(FILE *fp, const void *user) {
    const mpd_rows *R = (const mpd_rows *)user;
    int k;
    fprintf(fp, "time,eps_axial,sigma_yy,sigma_yy_base,eps_v,kinetic_energy,dem_steps_per_point,seconds\n");
    for (k = 0; k < R->n; ++k) {
        const bx_row *r = (const bx_row *)mpd_row(R, k);
        fprintf(fp, "%.6g,%.6g,%.9g,%.9g,%.6g,%.6g,%.4g,%.3f\n", r->t, r->eps, r->syy_top, r->syy_base, r->ev,
                r->ek, r->dem_mean, r->secs);
    }
}

static int write_plots(const bx *X) {
    int n = X->rows.n, k, bad = 1;
    double *x = (double *)malloc((size_t)(n + 1) * 3 * sizeof *x), *y1 = x + n + 1, *y2 = y1 + n + 1;
    gk_plot pl;
    if (!x) return fprintf(stderr, "mpmdem_biaxial: out of memory for the plots\n"), 1;
    for (k = 0; k < n; ++k) {
        const bx_row *r = (const bx_row *)mpd_row(&X->rows, k);
        x[k] = 100 * r->eps, y1[k] = r->syy_top / 1e3, y2[k] = r->syy_base / 1e3;
    }
    gk_plot_init(&pl, "MPMxDEM biaxial (Liang & Zhao Fig 6: peak ~280 kPa at 1.6 %)", "axial strain [%]",
                 "sigma_yy [kPa]");
    gk_plot_add(&pl, x, y1, n, "top plate reaction / width");
    if ((k = gk_plot_add(&pl, x, y2, n, "base reaction / width")) >= 0)
        pl.s[k].dashed = 1; /* on top, visible */
    if (!mpd_plot(&X->run, &pl, "biaxial_stress.svg")) {
        for (k = 0; k < n; ++k) y1[k] = 100 * ((const bx_row *)mpd_row(&X->rows, k))->ev;
        gk_plot_init(&pl, "MPMxDEM biaxial: volumetric strain (compression positive)", "axial strain [%]",
                     "eps_v [%]");
        gk_plot_add(&pl, x, y1, n, "specimen (sum of point volumes)");
        bad = mpd_plot(&X->run, &pl, "biaxial_volume.svg");
    }
    free(x);
    return bad;
}

/* points_ABC.csv: the start, then a line per row of biaxial.csv: the points' state at its end */
static void put_abc_csv(FILE *fp, const void *user) {
    const bx *X = (const bx *)user;
    int k;
    fprintf(fp, "time,eps_axial");
    mpd_watch_csv_head(fp, bx_pt_name, BX_NPT, bx_q_name, BX_NQ);
    fprintf(fp, "\n0,0");
    mpd_watch_csv_row(fp, X->S.pt0[0], BX_NPT, BX_NQ);
    fprintf(fp, "\n");
    for (k = 0; k < X->rows.n; ++k) {
        const bx_row *r = (const bx_row *)mpd_row(&X->rows, k);
        fprintf(fp, "%.6g,%.6g", r->t, r->eps);
        mpd_watch_csv_row(fp, r->pt[0], BX_NPT, BX_NQ);
        fprintf(fp, "\n");
    }
}

/* the histories of A, B, C (the paper's Fig 10): q against the point's own eps_q, the p-q paths, the
 * rotation and the fabric anisotropy against the axial strain; the paper's values in the titles (its
 * sense of rotation is not stated for C); 0 or 1 (said) */
static int write_abc_plots(const bx *X) {
    static const struct {
        int x, y; /* BX_* on the axes; x < 0: the axial strain */
        const char *file, *title, *xl, *yl;
    } fig[4] = {
        {BX_EQ, BX_Q, "points_ABC.svg",
         "MPMxDEM biaxial: q of points A, B, C (Liang & Zhao Fig 10: A peaks at eps_q ~1 %, B ~150 kPa)",
         "deviatoric strain eps_q of the point", "q [kPa]"},
        {BX_P, BX_Q, "points_ABC_pq.svg",
         "MPMxDEM biaxial: stress paths of A, B, C (Liang & Zhao: B up to p ~420, q ~150 kPa)", "p [kPa]",
         "q [kPa]"},
        {-1, BX_ROT, "points_ABC_rotation.svg",
         "rotation of A, B, C (Liang & Zhao at 15 %: A -0.1, B 10 clockwise, C 38 deg)", "axial strain [%]",
         "rotation of F = R U, counter-clockwise [deg]"},
        {-1, BX_FA, "points_ABC_fabric.svg",
         "fabric anisotropy of A, B, C (Liang & Zhao: A ~0.075, B 0.2-0.3 with fluctuations)",
         "axial strain [%]", "F_a"}};
    int n = X->rows.n + 1, k, i, f, bad = 0;
    double *a = (double *)malloc((size_t)n * (1 + 2 * BX_NPT) * sizeof *a);
    char lab[BX_NPT][16];
    gk_plot pl;
    if (!a) return fprintf(stderr, "mpmdem_biaxial: out of memory for the plots\n"), 1;
    for (i = 0; i < BX_NPT; ++i) snprintf(lab[i], sizeof lab[i], "point %s", bx_pt_name[i]);
    for (f = 0; f < 4 && !bad; ++f) {
        double *ax = a + n, *ay = ax + BX_NPT * n;
        for (k = 0; k < n; ++k) {
            const bx_row *r = k ? (const bx_row *)mpd_row(&X->rows, k - 1) : NULL;
            a[k] = r ? 100 * r->eps : 0.0;
            for (i = 0; i < BX_NPT; ++i) {
                const double *v = r ? r->pt[i] : X->S.pt0[i];
                ax[i * n + k] = fig[f].x < 0 ? a[k] : v[fig[f].x], ay[i * n + k] = v[fig[f].y];
            }
        }
        gk_plot_init(&pl, fig[f].title, fig[f].xl, fig[f].yl);
        for (i = 0; i < BX_NPT; ++i) gk_plot_add(&pl, ax + i * n, ay + i * n, n, lab[i]);
        bad = mpd_plot(&X->run, &pl, fig[f].file);
    }
    free(a);
    return bad;
}

/* the paper's numbers for A, B, C (Liang & Zhao Sec 3.2, Fig 10) against this run's, printed; into v:
 * A's largest q and its eps_q there, A's fabric anisotropy and rotation at the end, B's largest p and q,
 * B's rotation and fabric anisotropy at the end, C's rotation and eps_q at the end */
#define BX_NDV 10
static void abc_summary(const bx *X, double v[BX_NDV]) {
    const double *e[BX_NPT];
    int k, i;
    for (i = 0; i < BX_NPT; ++i)
        e[i] = X->rows.n ? ((const bx_row *)mpd_row(&X->rows, X->rows.n - 1))->pt[i] : X->S.pt0[i];
    v[0] = X->S.pt0[0][BX_Q], v[1] = X->S.pt0[0][BX_EQ], v[4] = X->S.pt0[1][BX_P], v[5] = X->S.pt0[1][BX_Q];
    for (k = 0; k < X->rows.n; ++k) {
        const bx_row *r = (const bx_row *)mpd_row(&X->rows, k);
        if (r->pt[0][BX_Q] > v[0]) v[0] = r->pt[0][BX_Q], v[1] = r->pt[0][BX_EQ];
        if (r->pt[1][BX_P] > v[4]) v[4] = r->pt[1][BX_P];
        if (r->pt[1][BX_Q] > v[5]) v[5] = r->pt[1][BX_Q];
    }
    v[2] = e[0][BX_FA], v[3] = e[0][BX_ROT], v[6] = e[1][BX_ROT], v[7] = e[1][BX_FA], v[8] = e[2][BX_ROT];
    v[9] = e[2][BX_EQ];
    for (i = 0; i < BX_NPT; ++i)
        printf("point %s: material point %d at (%.4g, %.4g) m at the start (asked for %.3g W, %.3g H)\n",
               bx_pt_name[i], X->S.pt[i], X->S.pt0[i][BX_X], X->S.pt0[i][BX_Y], bx_pt_at[i][0],
               bx_pt_at[i][1]);
    printf(
        "point A: q peaks at %.4g kPa at eps_q %.3g %% (Liang & Zhao: a small peak at ~1 %%); at the end F_a "
        "%.3g, rotation %.3g deg (0.075, -0.1)\n",
        v[0], 100 * v[1], v[2], v[3]);
    printf("point B: p up to %.4g kPa, q up to %.4g kPa (Liang & Zhao ~420, ~150); at the end rotation %.3g "
           "deg, "
           "F_a %.3g (10 deg clockwise, 0.2-0.3)\n",
           v[4], v[5], v[6], v[7]);
    printf("point C: at the end rotation %.3g deg, eps_q %.3g (Liang & Zhao: 38 deg)\n", v[8], v[9]);
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* the dominant shear band: the points whose eps_q exceeds twice the median,
 * their principal axis (largest eigenvector of the covariance of their
 * positions, weighted by eps_q) -> angle from the horizontal in [0, 90] deg.
 * NaN when no point stands out (no localisation yet). */
static double band_angle(const mpd_micro *M, const gk_mpm_points *pts) {
    int n = pts->n, p, m = 0;
    double *e = (double *)malloc(2 * (size_t)n * sizeof *e), *s = e + n, med, w = 0, mx = 0, my = 0, cxx = 0,
           cyy = 0, cxy = 0, ang = NAN;
    if (!e) return NAN;
    for (p = 0; p < n; ++p) e[p] = s[p] = gk_strain_q(M->eps + 9 * (size_t)p, 2);
    qsort(s, (size_t)n, sizeof *s, cmp_double);
    med = s[n / 2];
    for (p = 0; p < n; ++p)
        if (e[p] > 2 * med) ++m, w += e[p], mx += e[p] * pts->x[0][p], my += e[p] * pts->x[1][p];
    if (m >= 3 && w > 0) {
        mx /= w, my /= w;
        for (p = 0; p < n; ++p)
            if (e[p] > 2 * med) {
                double dx = pts->x[0][p] - mx, dy = pts->x[1][p] - my;
                cxx += e[p] * dx * dx, cyy += e[p] * dy * dy, cxy += e[p] * dx * dy;
            }
        ang = fabs(0.5 * atan2(2 * cxy, cxx - cyy) * 180.0 / MPD_PI); /* principal direction */
        if (ang > 90) ang = 180 - ang;
    }
    free(e);
    return ang;
}

/* after a step: the interval sums, and a CSV row (with the stage fields) when due; 0 or 1 (said) */
static int after_step(bx *X, double vplate, double t0, double t_start, long step0, long nsteps_total) {
    bx_state *S = &X->S;
    const bx_opts *b = &X->b;
    double ek, m, mom[3];
    long long sum = 0;
    int i, bad;
    bx_row r;
    gk_err err;
    S->t += X->dt, S->disp += vplate * X->dt, ++S->step;
    S->acc_top += -S->body[1].force[1] * X->dt, S->acc_base += S->body[0].force[1] * X->dt,
        S->acc_dt += X->dt;
    gk_mpm_points_totals(&X->pts, &m, mom, &ek);
    S->acc_ek += ek, ++S->nacc;
    for (i = 0; i < X->pts.n; ++i) sum += X->M.nsub[i];
    S->acc_dem += (double)sum / X->pts.n;
    if (!(S->disp >= S->next_out * b->height * (1 - 1e-9) || S->disp >= b->strain * b->height * (1 - 1e-12)))
        return 0;
    r.t = S->t, r.eps = S->disp / b->height, r.ev = 0;
    for (i = 0; i < X->pts.n; ++i) r.ev += X->pts.vol[i];
    r.syy_top = S->acc_top / S->acc_dt / b->width, r.syy_base = S->acc_base / S->acc_dt / b->width;
    r.ev = (X->vol0 - r.ev) / X->vol0, r.ek = S->acc_ek / S->nacc, r.dem_mean = S->acc_dem / S->nacc;
    r.secs = gk_wtime() - t0;
    S->acc_top = S->acc_base = S->acc_dt = 0, S->acc_ek = S->acc_dem = 0, S->nacc = 0;
    S->next_out += b->every;
    if (sample_points(X, r.pt, &err))
        return fprintf(stderr, "mpmdem_biaxial: the points A, B, C at %.3f %%: %s\n", 100 * r.eps, err.msg),
               1;
    bad = mpd_rows_push(&X->run, &X->rows, &r) || mpd_write(&X->run, "biaxial.csv", put_csv, &X->rows) ||
          mpd_write(&X->run, "points_ABC.csv", put_abc_csv, X);
    while (!bad && S->nstage < 3 && r.eps >= bx_stages[S->nstage] * (1 - 1e-9)) {
        char tag[32];
        snprintf(tag, sizeof tag, "%.1f%%", 100 * bx_stages[S->nstage]);
        bad = stage_fields(X, tag);
        ++S->nstage;
    }
    if (!X->o.quiet) {
        char what[300];
        snprintf(what, sizeof what, "eps %.2f %%  sigma_yy %.1f kPa (base %.1f)  eps_v %.3f %%  DEM %.1f/pt",
                 100 * r.eps, r.syy_top / 1e3, r.syy_base / 1e3, 100 * r.ev, r.dem_mean);
        gk_progress_since(stderr, S->step, step0, nsteps_total, t_start, what);
    }
    return bad;
}

/* the summary and the RESULT line */
static void report(bx *X, double secs, long steps_run, long long dems, int wrote) {
    double peak = 0, epk = 0, rmax = 0, ang = band_angle(&X->M, &X->pts), last = 0, eps_end = 0, v[BX_NDV];
    char buf[64];
    int k, n = X->pts.n;
    for (k = 0; k < X->rows.n; ++k) {
        const bx_row *r = (const bx_row *)mpd_row(&X->rows, k);
        if (r->syy_top > peak) peak = r->syy_top, epk = r->eps;
        last = r->syy_top, eps_end = r->eps;
    }
    for (k = 0; k < n; ++k)
        rmax = fmax(rmax, fabs(gk_rotation_angle(X->pts.F + 9 * (size_t)k, 2) * 180.0 / MPD_PI));
    if (wrote)
        printf("wrote %s/biaxial.csv, biaxial_stress.svg, biaxial_volume.svg, rotation_*.svg, eps_q_*.svg, "
               "points_ABC.csv, points_ABC*.svg, points_*.vtk (ParaView), checkpoint.bin\n",
               X->run.out);
    printf("Liang & Zhao (mesh M4, their RVE): peak sigma_yy ~ 280 kPa at 1.6 %%; here %.1f kPa at %.2f %% "
           "(sigma_1/sigma_3 = %.2f; paper ~2.8)\n",
           peak / 1e3, 100 * epk, X->b.pressure > 0 ? peak / X->b.pressure : 0.0);
    if (ang == ang)
        printf(
            "shear band: %.1f deg from the horizontal (principal axis of the points with eps_q > 2 x median; "
            "Liang & Zhao: first band ~60 deg)\n",
            ang);
    else
        printf("shear band: none yet (no point with eps_q > 2 x median)\n");
    abc_summary(X, v);
    printf("cost: %s for %ld MPM steps, %lld DEM steps over all RVEs (%.1f per point per MPM step)\n",
           mpd_duration(secs, buf, sizeof buf), steps_run, dems,
           steps_run ? (double)dems / steps_run / n : 0.0);
    mpd_print_traffic(&X->run, &X->M, steps_run, X->o.threads);
    printf("RESULT peak_sigma_yy=%.6g eps_at_peak=%.5g sigma_yy_end=%.6g eps_end=%.5g max_rotation_deg=%.3g "
           "band_angle_deg=%.3g n_rves=%d mpm_steps=%ld dt=%.4g seconds_per_step=%.4g "
           "seconds_per_step_per_1000_rves=%.4g total_seconds=%.2f A_q_peak_kPa=%.4g A_eps_q_at_q_peak=%.4g "
           "A_fabric_end=%.4g A_rotation_end_deg=%.4g B_p_peak_kPa=%.4g B_q_peak_kPa=%.4g "
           "B_rotation_end_deg=%.4g "
           "B_fabric_end=%.4g C_rotation_end_deg=%.4g C_eps_q_end=%.4g\n",
           peak, epk, last, eps_end, rmax, ang, n, steps_run, X->dt, steps_run ? secs / steps_run : 0.0,
           steps_run ? secs / steps_run * 1000.0 / n : 0.0, secs, v[0], v[1], v[2], v[3], v[4], v[5], v[6],
           v[7], v[8], v[9]);
}

static int run(bx *X, int argc, char **argv) {
    const bx_opts *b = &X->b;
    bx_state *S = &X->S;
    double t0, t_start;
    long nsteps_total, step0;
    long long dem0;
    int status = parse(X, argc, argv), bad = 0;
    gk_err err;
    if (status) return status == 1 ? 0 : status;
    /* the inputs (packing, checkpoint) first: bad input leaves no output folder behind */
    if (setup(X, &err)) return fprintf(stderr, "mpmdem_biaxial: %s\n", err.msg), 1;
    if (mpd_out_dir(&X->run)) return 1;
    nsteps_total = (long)ceil((b->strain * b->height / b->velocity + 0.5 * b->ramp) / X->dt);
    printf("mpmdem_biaxial: %d x %d cells, h = %.4g m, %d points (= RVEs of %d disks), basis %d, alpha %g\n",
           b->nx, b->ny, X->h, X->pts.n, X->P.pk.n, (int)X->def.basis, X->o.alpha);
    printf("RVE: p0 = %.4g kPa, e0 = %.4f, rho = %.1f kg/m3, M (Taylor) = %.4g MPa -> c = %.1f m/s; MPM dt = "
           "%.4g s "
           "(cfl %.2f); DEM dt = %.3g s\n",
           X->P.p0 / 1e3, X->P.e0, X->P.rho, X->P.M / 1e6, X->c, X->dt, X->o.cfl, X->P.dt);
    mpd_print_dem_rule(&X->o);
    printf("about %ld MPM steps to %.1f %% axial strain at %g m/s\n", nsteps_total, 100 * b->strain,
           b->velocity);
    if (!X->o.restart && mpd_write_vtk(&X->run, 0, &X->M, &X->pts)) return 1;
    t_start = t0 = gk_wtime();
    step0 = S->step, dem0 = X->M.dem_steps;
    while (!bad && S->disp < b->strain * b->height * (1 - 1e-12)) {
        double vplate = b->velocity * (b->ramp > 0 && S->t < b->ramp ? (S->t + 0.5 * X->dt) / b->ramp : 1.0);
        S->body[1].v[1] = -vplate;
        if (mpd_step(&X->g, &X->pts, &X->def, X->dt, &X->M, X->edge, X->nedge, &err)) {
            fprintf(stderr, "mpmdem_biaxial: step %ld (axial strain %.3f %%): %s\n", S->step,
                    100 * S->disp / b->height, err.msg);
            status = 3;
            break;
        }
        bad = after_step(X, vplate, t0, t_start, step0, nsteps_total);
        if (!bad && X->o.vtk_every && S->step % X->o.vtk_every == 0)
            bad = mpd_write_vtk(&X->run, S->step, &X->M, &X->pts);
        if (!bad && X->o.checkpoint_every && S->step % X->o.checkpoint_every == 0)
            bad = mpd_save(&X->run, &X->M, &X->pts, "biaxial", S, sizeof *S, &X->rows, &X->snaps);
    }
    if (!bad && status == 0)
        bad = mpd_save(&X->run, &X->M, &X->pts, "biaxial", S, sizeof *S, &X->rows, &X->snaps);
    if (!bad)
        bad = mpd_write(&X->run, "biaxial.csv", put_csv, &X->rows) ||
              mpd_write(&X->run, "points_ABC.csv", put_abc_csv, X) || write_plots(X) || write_abc_plots(X) ||
              stage_fields(X, "end");
    if (!bad) bad = mpd_write_vtk(&X->run, S->step, &X->M, &X->pts);
    report(X, gk_wtime() - t_start, S->step - step0, X->M.dem_steps - dem0, !bad);
    return status ? status : bad;
}

int main(int argc, char **argv) {
    bx X;
    int status;
    memset(&X, 0, sizeof X);
    gk_rve_state_init(&X.st0, NULL);
    mpd_begin(&X.run, "mpmdem_biaxial", &argc, &argv);
    status = run(&X, argc, argv);
    free(X.edge);
    free(X.fld);
    mpd_free_all(&X.M, &X.P, &X.pts, &X.g, &X.rows, &X.snaps);
    gk_rve_state_free(&X.st0);
    return mpd_end(status);
}
