/* pipe_io.h - the state and the outputs of the MPMxDEM pipe-soil driver (examples/mpmdem_pipe.c;
 * examples, not library): its options, the points D, E, F of Liang & Zhao (2019), the CSV rows and
 * the checkpointed state (struct pp, the whole model), and the outputs: pipe.csv, points_DEF.csv, the
 * force and point-history plots, and the summary of D, E, F against the paper. */
#ifndef PIPE_IO_H
#define PIPE_IO_H

#include "mpmdem_watch.h"

#define PP_MAX_LEVELS 64
#define PP_DEM_DT_REF 3.16e-5 /* Guo & Zhao's DEM step at E = 600 MPa */

typedef struct pp_opts {
    int nx, ny, levels, paper, contact, max_steps;
    double width, D, mu, gravity, pen, lat, v_down, v_lat, ramp, every, room;
} pp_opts;

/* the paper's points D, E, F (Figs 22E-24): where they start, relative to the pipe's start (its centre
 * at mid-width, its bottom on the ground): dx right of the centre, depth below the ground [m]. The paper
 * shows them only in its figures (D/F in the left/right dominant shear band, E under the pipe, pushed
 * down slightly to the right); these are positions chosen from that text, see the header. */
#define PP_NPT 3
#define PP_NQ 10 /* per point: x, y, p, q, eps_q, eps_v, rotation, void ratio, coordination, DEM steps */
static const char *const pp_pt_name[PP_NPT] = {"D", "E", "F"};
static const double pp_pt_at[PP_NPT][2] = {{-1.1, 0.6}, {0.1, 1.05}, {1.1, 0.6}};
static const char *const pp_q_name[PP_NQ] = {
    "x", "y", "p_kPa", "q_kPa", "eps_q", "eps_v", "rotation_deg", "void_ratio", "coordination", "dem_steps"};

typedef struct pp_row { /* one CSV row: means over its interval; the pipe and the points at its end */
    double t, x, y, pen, lat, H, V, dem_mean, secs;
    double pt[PP_NPT][PP_NQ];
    int stage;
} pp_row;

/* what a checkpoint carries besides points, RVEs, rows and pictures */
typedef struct pp_state {
    long step;
    double t, dt;
    gk_mpm_body body;
    int stage;            /* 0 penetration, 1 lateral, 2 done */
    double done, t_stage; /* distance and time into the current stage */
    double pen, lat;      /* penetration (down) and lateral travel (left) so far [m] */
    double acc_H, acc_V, acc_dt, acc_dem;
    long nacc;
    double next_out;
    int pen_row;               /* the row that ends the penetration (-1: not yet) */
    double wall;               /* wall seconds of the runs before this one */
    int pt[PP_NPT];            /* the material points D, E, F (nearest to pp_pt_at at the start) */
    double pt0[PP_NPT][PP_NQ]; /* their state at the start */
} pp_state;

typedef struct pp { /* the whole model */
    mpd_run run;
    mpd_opts o;
    pp_opts b;
    mpd_proto P;
    gk_rve_state st[PP_MAX_LEVELS];
    double lev_p[PP_MAX_LEVELS], lev_rho[PP_MAX_LEVELS], lev_e[PP_MAX_LEVELS], lev_M[PP_MAX_LEVELS],
        lev_pa[PP_MAX_LEVELS];
    mpd_micro M;
    gk_mpm_grid g;
    gk_mpm_points pts;
    gk_mpm_def def;
    pp_state S;
    mpd_rows rows;
    mpd_snaps snaps;
    int *pick, dem_max_given;
    double *fld; /* MPD_NFIELD x points: the fields when a row is taken */
    double h, depth, dot, c, rho_ref, Mmax, prep_secs, x0;
    double dt_run; /* the run's time step (a checkpoint's must be the same) */
} pp;

static const gk_mpm_contact pp_contacts[3] = {GK_MPM_CONTACT_STICK, GK_MPM_CONTACT_FRICTION,
                                              GK_MPM_CONTACT_SMOOTH};

/* ---------------------------------------------------------- outputs */
static void put_csv(FILE *fp, const void *user) {
    const pp *X = (const pp *)user;
    int k;
    fprintf(fp,
            "time,pipe_x,pipe_bottom_y,penetration,lateral,stage,H_kN_per_m,V_kN_per_m,dem_steps_per_point,"
            "seconds\n");
    for (k = 0; k < X->rows.n; ++k) {
        const pp_row *r = (const pp_row *)mpd_row(&X->rows, k);
        fprintf(fp, "%.6g,%.6g,%.6g,%.6g,%.6g,%d,%.6g,%.6g,%.4g,%.3f\n", r->t, r->x, r->y, r->pen, r->lat,
                r->stage + 1, r->H / 1e3, r->V / 1e3, r->dem_mean, r->secs);
    }
}

/* points_DEF.csv: the start (t = 0), then a line per row of pipe.csv: the points' state at its end */
static void put_def_csv(FILE *fp, const void *user) {
    const pp *X = (const pp *)user;
    int k;
    fprintf(fp, "time,stage,pipe_x,pipe_bottom_y,travel");
    mpd_watch_csv_head(fp, pp_pt_name, PP_NPT, pp_q_name, PP_NQ);
    fprintf(fp, "\n0,1,%.6g,%.6g,0", X->x0, X->depth);
    mpd_watch_csv_row(fp, X->S.pt0[0], PP_NPT, PP_NQ);
    fprintf(fp, "\n");
    for (k = 0; k < X->rows.n; ++k) {
        const pp_row *r = (const pp_row *)mpd_row(&X->rows, k);
        fprintf(fp, "%.6g,%d,%.6g,%.6g,%.6g", r->t, r->stage + 1, r->x, r->y, r->pen + r->lat);
        mpd_watch_csv_row(fp, r->pt[0], PP_NPT, PP_NQ);
        fprintf(fp, "\n");
    }
}

/* a dashed horizontal reference line from x0 to x1 */
static void ref_line(gk_plot *pl, double *tx, double *ty, double x0, double x1, double v, const char *label) {
    int s;
    tx[0] = x0, tx[1] = x1, ty[0] = ty[1] = v;
    if ((s = gk_plot_add(pl, tx, ty, 2, label)) >= 0) pl->s[s].dashed = 1;
}

static int write_plot(const pp *X) {
    int n = X->rows.n, k, bad;
    double *x = (double *)malloc(3 * (size_t)n * sizeof *x + 1), *H = x + n, *V = H + n, rx[3][2], ry[3][2];
    double s0 = X->b.pen, s1 = X->b.pen + X->b.lat;
    gk_plot pl;
    if (!x) return fprintf(stderr, "mpmdem_pipe: out of memory\n"), 1;
    for (k = 0; k < n; ++k) {
        const pp_row *r = (const pp_row *)mpd_row(&X->rows, k);
        x[k] = r->pen + r->lat, H[k] = r->H / 1e3, V[k] = r->V / 1e3;
    }
    gk_plot_init(&pl, "MPMxDEM pipe: reactions per m (Liang & Zhao Fig 21); down to 0.8 m, then 0.7 m left",
                 "pipe travel: penetration + lateral [m]", "reaction [kN/m]");
    gk_plot_add(&pl, x, V, n, "V vertical");
    gk_plot_add(&pl, x, H, n, "H horizontal (against the motion)");
    ref_line(&pl, rx[0], ry[0], 0.75 * s0, s0, 250, "Liang & Zhao: V peak ~250");
    if (X->b.lat > 0) {
        ref_line(&pl, rx[1], ry[1], s0, s1, 25, "Liang & Zhao: V lateral ~25");
        ref_line(&pl, rx[2], ry[2], s0, s1, 50, "Liang & Zhao: H lateral ~50, rising slightly");
    }
    bad = mpd_plot(&X->run, &pl, "pipe_force.svg");
    free(x);
    return bad;
}

/* the histories of D, E, F: eps_q and rotation against the pipe's travel (the paper's values as dashed
 * lines where it gives them: at the onset of the lateral stage and at its end), and the p-q paths
 * (F's end marked; E's ~700 kPa only in the title: a line there would squeeze the paths); 0 or 1 (said) */
static int write_def_plots(const pp *X) {
    int n = X->rows.n + 1, k, i, bad;
    double *a = (double *)malloc((1 + 4 * PP_NPT) * (size_t)n * sizeof *a + 1), *tr = a, rx[4][2], ry[4][2];
    double *eq = a + n, *rot = eq + PP_NPT * n, *pp_ = rot + PP_NPT * n, *qq = pp_ + PP_NPT * n;
    double s0 = X->b.pen, s1 = X->b.pen + X->b.lat;
    char lab[PP_NPT][16];
    gk_plot pl;
    if (!a) return fprintf(stderr, "mpmdem_pipe: out of memory\n"), 1;
    for (k = 0; k < n; ++k) {
        const pp_row *r = k ? (const pp_row *)mpd_row(&X->rows, k - 1) : NULL;
        tr[k] = r ? r->pen + r->lat : 0.0;
        for (i = 0; i < PP_NPT; ++i) {
            const double *v = r ? r->pt[i] : X->S.pt0[i];
            eq[i * n + k] = v[4], rot[i * n + k] = v[6], pp_[i * n + k] = v[2], qq[i * n + k] = v[3];
        }
    }
    for (i = 0; i < PP_NPT; ++i) snprintf(lab[i], sizeof lab[i], "point %s", pp_pt_name[i]);
    gk_plot_init(&pl, "MPMxDEM pipe: eps_q of points D, E, F (Liang & Zhao Fig 24); lateral stage from 0.8 m",
                 "pipe travel: penetration + lateral [m]", "deviatoric strain eps_q");
    for (i = 0; i < PP_NPT; ++i) gk_plot_add(&pl, tr, eq + i * n, n, lab[i]);
    ref_line(&pl, rx[0], ry[0], 0.75 * s0, s0, 0.5, "Liang & Zhao: D 0.5 at the lateral onset");
    ref_line(&pl, rx[1], ry[1], 0.75 * s0, s0, 1.2, "Liang & Zhao: F 1.2 at the lateral onset");
    if (X->b.lat > 0)
        ref_line(&pl, rx[2], ry[2], s1 - 0.25 * X->b.lat, s1, 2.6, "Liang & Zhao: D 2.6 at the end");
    bad = mpd_plot(&X->run, &pl, "points_DEF.svg");
    gk_plot_init(&pl, "MPMxDEM pipe: rotation of points D, E, F (counter-clockwise > 0; Liang & Zhao Fig 24)",
                 "pipe travel: penetration + lateral [m]", "rotation of F = R U [deg]");
    for (i = 0; i < PP_NPT; ++i) gk_plot_add(&pl, tr, rot + i * n, n, lab[i]);
    ref_line(&pl, rx[0], ry[0], 0.75 * s0, s0, 10, "Liang & Zhao: D +10 (anticlockwise) at the onset");
    ref_line(&pl, rx[1], ry[1], 0.75 * s0, s0, -30, "Liang & Zhao: F -30 (clockwise) at the onset");
    if (X->b.lat > 0)
        ref_line(&pl, rx[2], ry[2], s1 - 0.25 * X->b.lat, s1, 58, "Liang & Zhao: D +58 at the end");
    if (!bad) bad = mpd_plot(&X->run, &pl, "points_DEF_rotation.svg");
    gk_plot_init(&pl, "MPMxDEM pipe: stress paths of points D, E, F (Liang & Zhao Fig 24: E up to ~700 kPa)",
                 "p [kPa]", "q [kPa]");
    for (i = 0; i < PP_NPT; ++i) gk_plot_add(&pl, pp_ + i * n, qq + i * n, n, lab[i]);
    ref_line(&pl, rx[1], ry[1], 5, 25, 4, "Liang & Zhao: F ends near p 15, q 4");
    if (!bad) bad = mpd_plot(&X->run, &pl, "points_DEF_pq.svg");
    free(a);
    return bad;
}

/* the paper's numbers for D, E, F (Liang & Zhao Sec 3.4) against this run's, printed; into v: the lifts of
 * D and F in the penetration, D's and F's eps_q and rotation at the lateral onset, E's largest p, D's
 * eps_q and rotation at the end, F's eps_q at the end, F's smallest p in the lateral stage, F's p and q
 * at the end (NAN where the run did not get there) */
#define PP_NDV 13
static void def_summary(const pp *X, double v[PP_NDV]) {
    const pp_state *S = &X->S;
    const pp_row *on = S->pen_row >= 0 ? (const pp_row *)mpd_row(&X->rows, S->pen_row) : NULL;
    const pp_row *end =
        S->stage == 2 && X->rows.n > 0 ? (const pp_row *)mpd_row(&X->rows, X->rows.n - 1) : NULL;
    double lift[2] = {NAN, NAN}, pmax = X->S.pt0[1][2], pmin = NAN;
    int k, i;
    for (k = 0; k < X->rows.n; ++k) {
        const pp_row *r = (const pp_row *)mpd_row(&X->rows, k);
        if (r->pt[1][2] > pmax) pmax = r->pt[1][2];
        if (r->stage == 1 && !(r->pt[2][2] >= pmin)) pmin = r->pt[2][2];
    }
    for (i = 0; on && i < 2; ++i) {
        const double *a = S->pt0[2 * i], *b = on->pt[2 * i];
        lift[i] = sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]));
    }
    v[0] = lift[0], v[1] = lift[1];
    v[2] = on ? on->pt[0][4] : NAN, v[3] = on ? on->pt[0][6] : NAN;
    v[4] = on ? on->pt[2][4] : NAN, v[5] = on ? on->pt[2][6] : NAN;
    v[6] = pmax;
    v[7] = end ? end->pt[0][4] : NAN, v[8] = end ? end->pt[0][6] : NAN, v[9] = end ? end->pt[2][4] : NAN;
    v[10] = end ? pmin : NAN, v[11] = end ? end->pt[2][2] : NAN, v[12] = end ? end->pt[2][3] : NAN;
    for (i = 0; i < PP_NPT; ++i)
        printf("point %s: material point %d, at (%.4g, %.4g) m at the start (%.3g m %s of the pipe's start, "
               "%.3g m deep; asked for %g m, %g m deep)\n",
               pp_pt_name[i], S->pt[i], S->pt0[i][0], S->pt0[i][1], fabs(S->pt0[i][0] - X->x0),
               S->pt0[i][0] < X->x0 ? "left" : "right", X->depth - S->pt0[i][1], pp_pt_at[i][0],
               pp_pt_at[i][1]);
    printf("penetration: D lifted %.3g m, F %.3g m (Liang & Zhao: both ~0.08 sqrt 2 = 0.113 m, laterally "
           "upward); at the lateral onset D eps_q %.3g rotation %.3g deg, F eps_q %.3g rotation %.3g deg "
           "(Liang & Zhao: D 0.5, |10| anticlockwise; F 1.2, |30| clockwise); E p up to %.4g kPa (Liang & "
           "Zhao ~700 kPa)\n",
           v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
    printf("lateral stage: D eps_q -> %.3g, rotation -> %.3g deg (Liang & Zhao 0.5 -> 2.6, 15 -> 58 deg); F "
           "eps_q -> %.3g (Liang & Zhao 1.3 -> 1.4), p down to %.3g kPa, at the end p %.3g kPa q %.3g kPa "
           "(Liang & Zhao: toward the origin, then p ~15 kPa, q ~4 kPa)\n",
           v[7], v[8], v[9], v[10], v[11], v[12]);
}

#endif /* PIPE_IO_H */
