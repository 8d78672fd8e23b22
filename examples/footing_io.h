/* footing_io.h - the state and the outputs of the MPMxDEM footing driver (examples/mpmdem_footing.c;
 * examples, not library): its options, rows and checkpointed state (struct ft, the whole model), the
 * material tables of Liang & Zhao (2019) Table 2, and the outputs: the field pictures, footing.csv, the
 * ultimate load and the load-settlement plot, the mechanism at every row (footing_mech.h), and the
 * summary with its RESULT line.
 *
 * ULTIMATE LOAD (Vesic's rule, as the paper: the first point where the slope
 * of the load-settlement curve reaches zero, or its steady minimum). The
 * curve of an explicit MPM with points crossing cells is noisy, so: (1)
 * centred moving average of q over a window of --smooth (in d/B); (2) a
 * PEAK is the first row whose smoothed q is the largest of everything up to
 * one window after it (zero slope, not a wiggle), at least one window
 * before the end (confirmed); (3) otherwise the curve hardens: slope s by
 * central differences of the smoothed curve, s0 its largest value, s_min
 * its smallest after that; the ultimate is the first row with s <= s_min +
 * 0.1 (s0 - s_min) from which the slope stays inside that band to the end
 * (steady minimum slope), again one window before the end. If neither is
 * found the output says "ultimate load NOT reached" and N_q is the value at
 * the last row (RESULT ultimate_reached=0).
 *
 * MECHANISM (footing_mech.h), at every CSV row from the points: the wedge
 * angle (in each column of cells under the footing, the depth of the largest
 * eps_q; the line through the footing's corner fitted to them), and the
 * heave (the surface row's largest uplift beyond the footing, and the
 * outermost x where it is still 10 % of that), the log spiral (the eps_q
 * ridge along rays from the footing's corner over Prandtl's fan at the RVE's
 * friction angle phi, i.e. from his wedge side at pi/4 + phi/2 to the
 * passive zone at pi/4 - phi/2; ln r fitted linearly in psi: phi_fit, r0,
 * and the RMS misfit to eq 44 at phi; "not found" when no ridge stands out);
 * printed and in RESULT at the ultimate load's row and at the end, next to
 * Prandtl's pi/4 + phi/2 and the x where his passive zone meets the ground.
 *
 * Outputs in --out DIR (default build/mpm_footing): footing.csv
 * (load-settlement), footing_load.svg, rve_biaxial.svg and rve_mohr.svg (phi
 * measurement), eps_q_dB*.svg (stages, one colour scale; the fitted log
 * spiral drawn on them when found) and eps_q_end.svg (the same),
 * rotation_end.svg, void_ratio_end.svg, displacement_end.svg (failure mode;
 * the footing, the wall and the base drawn on the points), points_NNNNNN.vtk,
 * checkpoint.bin; a RESULT line.
 */
#ifndef FOOTING_IO_H
#define FOOTING_IO_H

#include "mpmdem.h"
#include "mpmdem_phi.h"
#include "footing_mech.h"

#define FT_NSTAGE 6
#define FT_DEM_DT_REF 3.16e-5 /* Guo & Zhao's DEM step at E = 600 MPa */

typedef struct ft_opts {
    int nx, ny, material, paper;
    double width, depth, B, foot_height, surcharge, velocity, ramp, final_dB, every, smooth;
    double phi_deg; /* > 0: skip the measurement */
    double phi_p[FT_MAXPHI];
    int nphi;
    const char *phi_list;
    double phi_strain;   /* largest axial strain of a biaxial RVE test */
    double grid_damping; /* local non-viscous grid damping (0: none, as the paper) */
    int max_steps;       /* 0: no limit */
    int phi_only;        /* 1: measure the angle, prepare one RVE at q_s, print, exit */
} ft_opts;

typedef struct ft_row { /* one CSV row: means over an output interval; the mechanism at its end */
    double t, d, q, load, ek, dem_mean, secs;
    double wedge, heave_x, heave_u; /* footing_mech.h: wedge angle [deg], heave's outer x and top [m] */
    double sp_phi, sp_r0, sp_rms;   /* fm_spiral: fitted angle [deg], r0 and eq 44 misfit [m]; NAN if none */
    int sp_rays;                    /* rays with an eps_q ridge, found or not (found: sp_phi not NAN) */
} ft_row;

/* what a checkpoint carries besides points and RVEs */
typedef struct ft_state {
    long step;
    double t, disp;
    gk_mpm_body body;
    double acc_load, acc_dt, acc_ek, acc_dem; /* sums since the last row */
    long nacc;
    double next_out; /* settlement d/B of the next row */
    int nstage;
    double wall; /* wall seconds of the runs before this one */
} ft_state;

typedef struct ft { /* the whole model */
    mpd_run run;
    mpd_opts o;
    ft_opts f;
    mpd_proto P;
    gk_rve_state st0;
    mpd_micro M;
    gk_mpm_grid g;
    gk_mpm_points pts;
    gk_mpm_def def;
    mpd_edge *edge;
    int nedge, measured;
    double *x0; /* initial point positions (displacement field) */
    ft_state S;
    mpd_rows rows;
    mpd_snaps snaps;
    double h, b, bnode, dt, c, dot, phi, phi_res, rss_before, rss_after, t_first;
    long long dem_first;
    gk_mpm_body body_run; /* the footing as the run starts it (a checkpoint's is it, moved down) */
} ft;

static const char *material_names[3] = {"dense", "medium", "soft"};
static const double table2_e0[3] = {0.1874, 0.2314, 0.2299};
static const double paper_phi[3] = {28.1, 20.8, 18.2};
static const double paper_nq[3] = {14.4, 4.8, 3.7};
static const double paper_nq_analytic[3] = {14.8, 3.7, 3.1};
static const double ft_stages[FT_NSTAGE] = {0.05, 0.1, 0.25, 0.5, 1.0, 1.5};

/* kB of a /proc/self/status line ("VmHWM", "VmRSS"); -1 if unavailable */
static double proc_kb(const char *key) {
    FILE *fp = fopen("/proc/self/status", "r");
    char line[256];
    double v = -1.0;
    size_t n = strlen(key);
    if (!fp) return -1.0;
    while (fgets(line, sizeof line, fp))
        if (!strncmp(line, key, n) && line[n] == ':') {
            v = atof(line + n + 1);
            break;
        }
    fclose(fp);
    return v;
}

/* the footing (its base and edges, drawn at most 3 cells tall), the smooth wall and the base */
static void outline(const ft *X, mpd_outline *ol) {
    double W = X->f.width, D = X->f.depth, yb = D - X->S.disp, hs = fmin(X->f.foot_height, 3 * X->h);
    double foot[8], box[6];
    foot[0] = 0, foot[1] = yb + hs, foot[2] = X->b, foot[3] = yb + hs, foot[4] = X->b, foot[5] = yb,
    foot[6] = 0, foot[7] = yb;
    box[0] = 0, box[1] = 0, box[2] = W, box[3] = 0, box[4] = W, box[5] = D + 2 * X->h;
    memset(ol, 0, sizeof *ol);
    mpd_outline_add(ol, 4, foot);
    mpd_outline_add(ol, 3, box);
}

/* the fitted log spiral r = r0 exp(psi tan phi_fit) about the footing's corner over Prandtl's fan at the
 * RVE's angle (fm_spiral's), as two polylines of 6 points (11 chords of the 90 deg fan); nothing if NAN */
static void outline_spiral(const ft *X, double phi_fit, double r0, mpd_outline *ol) {
    double d2r = FM_PI / 180.0, a = fm_prandtl_wedge(X->phi), th0 = 180.0 + a, fan = fm_spiral_fan(a, X->phi);
    double yb = X->f.depth - X->S.disp, xy[12];
    int half, k;
    if (!(isfinite(phi_fit) && isfinite(r0))) return;
    for (half = 0; half < 2; ++half) {
        for (k = 0; k < 6; ++k) {
            double psi = fan * (5 * half + k) / 10.0, r = r0 * exp(psi * d2r * tan(phi_fit * d2r));
            xy[2 * k] = X->b + r * cos((th0 + psi) * d2r), xy[2 * k + 1] = yb + r * sin((th0 + psi) * d2r);
        }
        mpd_outline_add(ol, 6, xy);
    }
}

/* a field picture of the points with the outline, and the fitted log spiral (phi_fit, r0) if not NAN */
static int snap_field(ft *X, int k, const char *file, const char *title, double phi_fit, double r0) {
    mpd_outline ol;
    outline(X, &ol);
    outline_spiral(X, phi_fit, r0, &ol);
    return mpd_snap_field(&X->run, &X->snaps, &X->M, &X->pts, k, file, title, X->dot, &ol);
}

/* |u| of the points at the end */
static int displacement_field(ft *X) {
    int n = X->pts.n, p, bad;
    double *u = (double *)malloc((size_t)n * sizeof *u + 1);
    mpd_outline ol;
    if (!u) return fprintf(stderr, "mpmdem_footing: out of memory\n"), 1;
    for (p = 0; p < n; ++p) {
        double dx = X->pts.x[0][p] - X->x0[2 * p], dy = X->pts.x[1][p] - X->x0[2 * p + 1];
        u[p] = sqrt(dx * dx + dy * dy);
    }
    outline(X, &ol);
    bad =
        mpd_snap_add(&X->run, &X->snaps, "displacement_end",
                     "displacement |u| at the end (Liang & Zhao Fig 14)", "|u| [m]", &X->pts, u, X->dot, &ol);
    free(u);
    return bad;
}

static void put_csv(FILE *fp, const void *user) {
    const ft *X = (const ft *)user;
    int k;
    fprintf(fp, "time,d,d_over_B,q,q_over_qs,load_half,kinetic_energy,dem_steps_per_point,seconds,"
                "wedge_deg,heave_x_over_B,heave_over_B,spiral_phi_deg,spiral_r0_over_B,spiral_rms_over_B,"
                "spiral_rays\n");
    for (k = 0; k < X->rows.n; ++k) {
        const ft_row *r = (const ft_row *)mpd_row(&X->rows, k);
        fprintf(fp, "%.6g,%.6g,%.6g,%.9g,%.6g,%.9g,%.6g,%.4g,%.3f,%.5g,%.5g,%.5g,%.4g,%.4g,%.3g,%d\n", r->t,
                r->d, r->d / X->f.B, r->q, r->q / X->f.surcharge, r->load, r->ek, r->dem_mean, r->secs,
                r->wedge, r->heave_x / X->f.B, r->heave_u / X->f.B, r->sp_phi, r->sp_r0 / X->f.B,
                r->sp_rms / X->f.B, r->sp_rays);
    }
}

/* the ultimate load by the rule of the top comment; returns the row index
 * (or the last row if not reached) and sets *reached, *mode */
static int ultimate(const double *x, const double *q, int n, double w, double *qsm, int *reached,
                    const char **mode) {
    int k, j, js = 0, end = n - 1;
    double *s = NULL, s0 = -HUGE_VAL, smin = HUGE_VAL;
    *reached = 0, *mode = "not reached";
    if (n < 3) return n - 1;
    smooth_curve(x, q, n, w, qsm);
    while (end > 0 && x[n - 1] - x[end] < w) --end; /* rows that have a full window after them */
    for (k = 1; k <= end; ++k) {                    /* 1: zero slope = a confirmed maximum */
        int ok = 1;
        for (j = 0; j < n && ok; ++j)
            if (x[j] <= x[k] + w && qsm[j] > qsm[k]) ok = 0;
        if (ok && qsm[k] > qsm[0]) {
            *reached = 1, *mode = "peak (zero slope)";
            return k;
        }
    }
    s = (double *)malloc((size_t)n * sizeof *s);
    if (!s) return n - 1;
    for (k = 1; k < n - 1; ++k) s[k] = (qsm[k + 1] - qsm[k - 1]) / (x[k + 1] - x[k - 1]);
    s[0] = s[1], s[n - 1] = s[n - 2];
    for (k = 0; k < n; ++k)
        if (s[k] > s0) s0 = s[k], js = k;
    for (k = js; k < n; ++k)
        if (s[k] < smin) smin = s[k];
    for (k = js + 1; k <= end; ++k) {
        double band = smin + 0.1 * (s0 - smin);
        int ok = s[k] <= band;
        for (j = k; ok && j < n; ++j)
            if (s[j] > band) ok = 0;
        if (ok) {
            *reached = 1, *mode = "steady minimum slope";
            free(s);
            return k;
        }
    }
    free(s);
    return n - 1;
}

static int load_plot(const ft *X, const double *qsm, int ku, double nq46, double nq47) {
    int n = X->rows.n, k, s, bad;
    double *x = (double *)malloc(3 * (size_t)n * sizeof *x + 1), *y = x + n, *ys = y + n, hx[2], h1[2], h2[2],
           ux[1], uy[1], B = X->f.B, qs = X->f.surcharge;
    char l1[80], l2[80], lu[80];
    gk_plot pl;
    if (!x) return fprintf(stderr, "mpmdem_footing: out of memory\n"), 1;
    for (k = 0; k < n; ++k) {
        const ft_row *r = (const ft_row *)mpd_row(&X->rows, k);
        x[k] = r->d / B, y[k] = r->q / qs, ys[k] = qsm[k] / qs;
    }
    gk_plot_init(&pl, "MPMxDEM rigid footing: load-settlement (Liang & Zhao Fig 16)", "settlement d/B",
                 "footing pressure q / q_s");
    gk_plot_add(&pl, x, y, n, "q / q_s (interval means)");
    gk_plot_add(&pl, x, ys, n, "smoothed (ultimate-load rule)");
    hx[0] = 0, hx[1] = x[n - 1], h1[0] = h1[1] = nq46, h2[0] = h2[1] = nq47;
    snprintf(l1, sizeof l1, "N_q eq 46, phi = %.1f deg: %.2f", X->phi, nq46);
    snprintf(l2, sizeof l2, "N_q eq 47, phi_r = %.1f deg: %.2f", phi_reduced(X->phi), nq47);
    if ((s = gk_plot_add(&pl, hx, h1, 2, l1)) >= 0) pl.s[s].dashed = 1;
    if ((s = gk_plot_add(&pl, hx, h2, 2, l2)) >= 0) pl.s[s].dashed = 1;
    if (ku >= 0) {
        ux[0] = x[ku], uy[0] = ys[ku];
        snprintf(lu, sizeof lu, "ultimate: N_q = %.2f", ys[ku]);
        gk_plot_add(&pl, ux, uy, 1, lu);
    }
    pl.has_ylim = 1, pl.ylim[0] = 0, pl.ylim[1] = 1.15 * nq46;
    for (k = 0; k < n; ++k)
        if (1.1 * y[k] > pl.ylim[1]) pl.ylim[1] = 1.1 * y[k];
    bad = mpd_plot(&X->run, &pl, "footing_load.svg");
    free(x);
    return bad;
}

/* the failure mechanism of the points now (footing_mech.h): wedge angle, heave, log spiral (*sp: over
 * Prandtl's fan at the RVE's angle); 0 or 1 (out of memory) */
static int mechanism(const ft *X, double *wedge, double *hx, double *hu, fm_spiral_fit *sp) {
    int n = X->pts.n, p, ns = 0;
    double *eq = (double *)malloc(3 * (size_t)n * sizeof *eq + 1), *xs = eq + n, *uy = xs + n;
    double h = X->h, top = X->f.depth - h / X->o.ppc; /* between the top row of points and the next */
    *wedge = *hx = *hu = NAN;
    if (!eq) return fprintf(stderr, "mpmdem_footing: out of memory\n"), 1;
    for (p = 0; p < n; ++p) {
        eq[p] = gk_strain_q(X->M.eps + 9 * (size_t)p, 2);
        if (X->x0[2 * p + 1] > top) /* the surface row of points */
            xs[ns] = X->pts.x[0][p], uy[ns] = X->pts.x[1][p] - X->x0[2 * p + 1], ++ns;
    }
    *wedge = fm_wedge_angle(X->pts.x[0], X->pts.x[1], eq, n, h, X->b, X->f.depth - X->S.disp, NULL);
    *hx = fm_heave(xs, uy, ns, X->b, hu);
    fm_spiral(X->pts.x[0], X->pts.x[1], eq, n, h / X->o.ppc, X->b, X->f.depth - X->S.disp,
              fm_prandtl_wedge(X->phi), X->phi, sp);
    free(eq);
    return 0;
}

/* the ultimate load, the end fields, and the summary with its RESULT line; 0 or 1 (a write failed) */
static int finish(ft *X, double secs, long steps_run, long long dems, int bad) {
    const ft_opts *f = &X->f;
    int n = X->rows.n, ku = -1, reached = 0, k, excl = X->S.step == steps_run && steps_run > 1, np = X->pts.n;
    double *x = (double *)malloc(3 * (size_t)n * sizeof *x + 1), *q = x + n, *qsm = q + n, nq = NAN, qu = NAN,
           du = NAN;
    double wu = NAN, hxu = NAN, huu = NAN, we = NAN, hxe = NAN, spu = NAN, spr0 = NAN, sprms = NAN, spe = NAN;
    int sprays = 0, sprays_end = 0, nsearch = fm_spiral_nsearch(fm_prandtl_wedge(X->phi), X->phi);
    double nq46 = nq_prandtl(X->phi), nq47 = nq_prandtl(phi_reduced(X->phi)), hwm, per_rve, ck_mb = 0;
    /* cost per RVE per step without the first step's one-off relaxation of every RVE */
    double per_step_rve = steps_run ? (secs - (excl ? X->t_first : 0)) / (steps_run - excl) / np : 0.0;
    double dem_after_first =
        steps_run ? (double)(dems - (excl ? X->dem_first : 0)) / (steps_run - excl) / np : 0.0;
    const char *mode = "not reached";
    char buf[64], path[MPD_PATH];
    struct stat st;
    if (!x) return fprintf(stderr, "mpmdem_footing: out of memory\n"), 1;
    if (n > 0) {
        for (k = 0; k < n; ++k) {
            const ft_row *r = (const ft_row *)mpd_row(&X->rows, k);
            x[k] = r->d / f->B, q[k] = qsm[k] = r->q;
        }
        ku = ultimate(x, q, n, f->smooth, qsm, &reached, &mode);
        qu = qsm[ku], du = x[ku], nq = qu / f->surcharge;
        if (!bad) bad = load_plot(X, qsm, reached ? ku : -1, nq46, nq47);
    }
    if (!bad)
        bad = snap_field(X, MPD_EPS_Q, "eps_q_end",
                         "deviatoric strain eps_q at the end (failure mode, Liang & Zhao Fig 14)",
                         n > 0 ? ((const ft_row *)mpd_row(&X->rows, n - 1))->sp_phi : NAN,
                         n > 0 ? ((const ft_row *)mpd_row(&X->rows, n - 1))->sp_r0 : NAN) ||
              snap_field(X, MPD_ROTATION, "rotation_end",
                         "rotation of F = RU at the end (Liang & Zhao Fig 15)", NAN, NAN) ||
              snap_field(X, MPD_VOID, "void_ratio_end", "void ratio at the end (Liang & Zhao Fig 15)", NAN,
                         NAN) ||
              displacement_field(X) || mpd_write_vtk(&X->run, X->S.step, &X->M, &X->pts);
    if (!mpd_path(&X->run, path, "checkpoint.bin") && stat(path, &st) == 0) ck_mb = st.st_size / 1048576.0;
    if (!bad)
        printf("wrote %s/footing.csv, footing_load.svg, %seps_q_*.svg, rotation_end.svg, void_ratio_end.svg, "
               "displacement_end.svg, points_*.vtk (ParaView), checkpoint.bin\n",
               X->run.out, X->measured ? "rve_biaxial.svg, rve_mohr.svg, " : "");
    if (n > 0) {
        const ft_row *r0 = (const ft_row *)mpd_row(&X->rows, 0),
                     *rl = (const ft_row *)mpd_row(&X->rows, n - 1);
        printf(
            "load-settlement: q(d/B = %.4f) = %.2f kPa (q_s = %g kPa); at the end d/B = %.4f: q = %.1f kPa\n",
            r0->d / f->B, r0->q / 1e3, f->surcharge / 1e3, rl->d / f->B, rl->q / 1e3);
    }
    if (reached)
        printf("ultimate load (%s, smoothing window d/B %g): p_u = %.1f kPa at d/B = %.4f -> N_q = p_u/q_s = "
               "%.2f\n",
               mode, f->smooth, qu / 1e3, du, nq);
    else
        printf("ultimate load NOT reached by d/B = %.4f (no zero or steady minimum slope confirmed one "
               "window before "
               "the end): N_q below is the last smoothed value, a lower bound; run further (--final)\n",
               n ? x[n - 1] : 0.0);
    printf("N_q: MPMxDEM %.2f; eq 46 (general shear, phi = %.2f deg) %.2f; eq 47 (local/punching, phi_r = "
           "%.2f deg) "
           "%.2f; ratio %.3f to eq 46\n",
           nq, X->phi, nq46, phi_reduced(X->phi), nq47, nq / nq46);
    if (isnan(phi_of_nq(nq)))
        printf("no angle's eq 46 gives the MPMxDEM N_q %.3g (eq 46 spans %.3g at 0 deg to %.4g at 60 deg; "
               "RESULT "
               "phi_mobilised_deg=nan)\n",
               nq, nq_prandtl(0.0), nq_prandtl(60.0));
    else
        printf("the MPMxDEM N_q is eq 46 of phi = %.2f deg (the angle the footing mobilises)\n",
               phi_of_nq(nq));
    if (X->measured)
        printf("N_q of eq 46 with the residual angle phi_res = %.2f deg (the softened end of the RVE tests): "
               "%.2f; "
               "MPMxDEM / that = %.3f\n",
               X->phi_res, nq_prandtl(X->phi_res), nq / nq_prandtl(X->phi_res));
    printf("Liang & Zhao '%s': N_q %.1f (MPMxDEM) vs %.1f (analytic, phi = %.1f deg)\n",
           material_names[f->material], paper_nq[f->material], paper_nq_analytic[f->material],
           paper_phi[f->material]);
    if (n > 0) {
        const ft_row *ru = (const ft_row *)mpd_row(&X->rows, ku),
                     *rl = (const ft_row *)mpd_row(&X->rows, n - 1);
        wu = ru->wedge, hxu = ru->heave_x, huu = ru->heave_u, we = rl->wedge, hxe = rl->heave_x;
        printf(
            "mechanism at the %s (d/B = %.4f): wedge angle %.1f deg (Prandtl pi/4 + phi/2 = %.2f; Liang & "
            "Zhao 54.8 vs 59.05); heave up to %.3g B, reaching x = %.2f B from the axis = %.2f B beyond the "
            "footing edge (Prandtl's passive zone: x = %.2f B; Liang & Zhao: heave about 2.5 B wide)\n",
            reached ? "ultimate load" : "last row", du, wu, fm_prandtl_wedge(X->phi), huu / f->B, hxu / f->B,
            (hxu - X->b) / f->B, fm_prandtl_reach(X->b, X->phi) / f->B);
        printf("mechanism at the end (d/B = %.4f): wedge angle %.1f deg; heave reaching x = %.2f B\n",
               rl->d / f->B, we, hxe / f->B);
        spu = ru->sp_phi, spr0 = ru->sp_r0, sprms = ru->sp_rms, sprays = ru->sp_rays, spe = rl->sp_phi;
        sprays_end = rl->sp_rays;
        if (!isnan(spu))
            printf("log spiral (eq 44) at the %s: the eps_q ridge on %d rays from the footing's corner fits "
                   "ln r = ln r0 + psi tan(phi) with phi = %.1f deg (the RVE's %.2f; Liang & Zhao: eq 44 at "
                   "28.1 \"agrees perfectly\"), r0 = %.2f B (Prandtl's wedge side: %.2f B); RMS distance "
                   "to eq 44 at the RVE's angle %.3f B (h = %.3f B)\n",
                   reached ? "ultimate load" : "last row", sprays, spu, X->phi, spr0 / f->B,
                   X->b / cos(fm_prandtl_wedge(X->phi) * FM_PI / 180.0) / f->B, sprms / f->B, X->h / f->B);
        else
            printf("log spiral (eq 44) at the %s: not found (an eps_q ridge stands out on %d of the %d rays "
                   "from the footing's corner; a spiral needs half of them; RESULT spiral_found=0)\n",
                   reached ? "ultimate load" : "last row", sprays, nsearch);
        if (!isnan(spe))
            printf("log spiral at the end: phi = %.1f deg on %d rays\n", spe, sprays_end);
        else
            printf("log spiral at the end: not found (a ridge on %d of the %d rays)\n", sprays_end, nsearch);
    }
    hwm = proc_kb("VmHWM");
    per_rve = X->rss_after > 0 && X->rss_before > 0 ? (X->rss_after - X->rss_before) / np : NAN;
    printf("cost: %s for %ld MPM steps, %lld DEM steps over all RVEs (%.1f per point per MPM step); %.4g s "
           "per MPM "
           "step per 1000 RVEs (%.3g us per RVE DEM step)\n",
           mpd_duration(secs, buf, sizeof buf), steps_run, dems,
           steps_run ? (double)dems / steps_run / np : 0.0, steps_run ? secs / steps_run * 1000.0 / np : 0.0,
           dems ? 1e6 * secs / (double)dems : 0.0);
    mpd_print_traffic(&X->run, &X->M, steps_run, X->o.threads);
    printf(
        "memory (rank 0): VmHWM %.1f MB, %.1f kB per RVE (RSS growth on creation), checkpoint file %.1f MB\n",
        hwm / 1024, per_rve, ck_mb);
    {
        /* the paper's size: 7776 RVEs, h = 12/108, 0.1 m/s to d/B = 1.5 with a 0.5 s ramp */
        double hp = 12.0 / 108.0, dtp = X->o.cfl * hp / X->c, stepsp = (1.5 * f->B / 0.1 + 0.25) / dtp;
        double base = hwm > 0 && isfinite(per_rve) ? hwm - per_rve * np : NAN;
        printf("paper size projection (7776 RVEs, h = %.4g m, dt = %.3g s, %.0f MPM steps at 0.1 m/s to d/B "
               "= 1.5): "
               "memory ~ %.2f GB, checkpoint file %.2f GB; wall ~ %s on these cores at this run's %.3g ms "
               "per RVE per "
               "MPM step (first step excluded; %.1f DEM steps per RVE per MPM step here)\n",
               hp, dtp, stepsp, (base + 7776.0 * per_rve) / 1048576.0, 7776.0 * ck_mb / np / 1024.0,
               mpd_duration(per_step_rve * 7776.0 * stepsp, buf, sizeof buf), 1e3 * per_step_rve,
               dem_after_first);
    }
    printf("RESULT Nq=%.5g Nq_analytic=%.5g Nq_analytic_local=%.5g phi_deg=%.4g phi_res_deg=%.4g "
           "Nq_analytic_res=%.5g "
           "phi_mobilised_deg=%.4g q_ult=%.6g d_ult_over_B=%.4g ultimate_reached=%d n_rves=%d mpm_steps=%ld "
           "dt=%.4g "
           "seconds_per_step=%.4g seconds_per_step_per_1000_rves=%.4g "
           "seconds_per_step_per_1000_rves_after_first=%.4g "
           "mem_per_rve_kb=%.4g vmhwm_mb=%.5g total_seconds=%.2f wedge_deg=%.4g wedge_prandtl_deg=%.4g "
           "heave_x_over_B=%.4g heave_width_over_B=%.4g heave_over_B=%.4g prandtl_reach_over_B=%.4g "
           "wedge_end_deg=%.4g heave_x_end_over_B=%.4g spiral_found=%d spiral_phi_deg=%.4g "
           "spiral_r0_over_B=%.4g spiral_rms_over_B=%.4g spiral_rays=%d spiral_rays_searched=%d "
           "spiral_phi_end_deg=%.4g spiral_rays_end=%d\n",
           nq, nq46, nq47, X->phi, X->phi_res, X->measured ? nq_prandtl(X->phi_res) : NAN, phi_of_nq(nq), qu,
           du, reached, np, steps_run, X->dt, steps_run ? secs / steps_run : 0.0,
           steps_run ? secs / steps_run * 1000.0 / np : 0.0, 1000.0 * per_step_rve, per_rve, hwm / 1024, secs,
           wu, fm_prandtl_wedge(X->phi), hxu / f->B, (hxu - X->b) / f->B, huu / f->B,
           fm_prandtl_reach(X->b, X->phi) / f->B, we, hxe / f->B, !isnan(spu), spu, spr0 / f->B, sprms / f->B,
           sprays, nsearch, spe, sprays_end);
    free(x);
    return bad;
}

#endif /* FOOTING_IO_H */
