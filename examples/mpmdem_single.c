/* mpmdem_single.c - the single element test of Liang & Zhao (2019) Sec 3.1
 * (their Figs 3-4): ONE MPM cell with 2 x 2 material points, each with its
 * own periodic 400-disk RVE, a confining pressure sigma_xx = 100 kPa on the
 * right side, rollers on the left and the bottom, a prescribed downward
 * displacement of the top, no gravity; and, in the same run, the RVE alone
 * in a drained biaxial test at the same lateral stress (the paper's "pure
 * DEM simulations under the same boundary conditions"). The paper reports
 * that the two stress-strain and dilatancy curves are nearly identical to
 * large strain; the element is homogeneous, so they should be.
 *
 *   build/mpmdem_single                      # to 10 % axial strain
 *   build/mpmdem_single --strain 0.01 --packing FILE   # short, another packing
 *
 * Model. The element, a square of side --size with --ppc 2 (2 x 2 points;
 * the paper's four), sits in the lower left corner of ONE grid cell of side
 * (1 + --margin) x size: as it widens (dilatancy) its points and its right
 * edge stay in that cell, the velocity field over it stays bilinear. (With
 * --margin 0 the cell is the element; its right points' uGIMP domains and
 * its right edge leave the cell at the first lateral strain, into nodes that
 * only they touch, and the 4 RVEs no longer see the same dH.) The left wall, the base and the top plate are
 * smooth (frictionless) rigid bodies: rollers. The plate moves down at
 * --velocity (ramped up over --ramp seconds, as the paper's loads are); the
 * right side carries the follower pressure of mpd_edge (mpmdem.h). With
 * smooth walls all around, the velocity field of the cell is bilinear with
 * equal right-node velocities, so every point receives the same dH = dt L
 * each MPM step (Liang & Zhao Sec 2.3 (b)): the element is homogeneous and
 * its response is that of its RVE driven by the MPM. The element's axial
 * strain is 1 - F_yy of its points; its sigma_yy the work-conjugate
 * reaction of the top plate, R h / V (see after_step), averaged over each
 * output interval (the points' mean RVE stress is written next to it);
 * eps_v from the point volumes (compression positive).
 *
 * The RVE alone (mpd_rve_biaxial, the drained biaxial of mpmdem_footing's
 * friction angle): the same prepared RVE, sigma_xx held at -pressure by the
 * servo, axial strain at the rate the adaptive DEM rule lets the element's
 * RVEs deform (the inertial number --dem-inertial at the lateral stress),
 * advanced after every MPM step until its axial strain (1 - F_yy) reaches
 * the element's; its sigma_yy is averaged over the same intervals, eps_v =
 * 1 - det F of its cell.
 *
 * Outputs in --out DIR (default build/mpm_single): single.csv,
 * single_stress.svg, single_volume.svg; a RESULT line with both peaks, the
 * largest relative difference of sigma_yy and the largest difference of
 * eps_v over the path.
 */
#define GK_IMPLEMENTATION
#include "mpmdem.h"

typedef struct sg_opts {
    double size, margin, pressure, velocity, ramp, strain, every;
} sg_opts;

typedef struct sg_row { /* one CSV row: stresses are means over the output interval */
    double t, disp, eps, syy, syy_pts, spread, ev, eps_dem, syy_dem, sxx_dem, ev_dem, dem_mean, secs;
} sg_row;

typedef struct sg { /* the whole model */
    mpd_run run;
    mpd_opts o;
    sg_opts b;
    mpd_proto P;
    gk_rve_state st0;
    mpd_micro M;
    gk_mpm_grid g;
    gk_mpm_points pts;
    gk_mpm_def def;
    gk_mpm_body body[3]; /* 0: base, 1: left wall, 2: top plate */
    mpd_edge edge[4];
    int nedge;
    gk_rve alone; /* the RVE alone (drained biaxial) */
    int alone_open;
    double rate_alone;
    long long dem_alone;
    mpd_rows rows;
    mpd_snaps snaps; /* none taken (mpd_free_all frees them) */
    double h, dt, c, vol0, a;
    long step;
    double t, disp, eps, acc_dt, acc_syy, acc_pts, acc_dem, acc_sub, spread, next_out;
    long nacc;
} sg;

static void usage(FILE *fp) {
    mpd_opts d;
    mpd_opts_default(&d, "build/mpm_single");
    d.ppc = 2;
    fprintf(
        fp,
        "mpmdem_single - the single element test of Liang & Zhao (2019) Sec 3.1: one MPM cell,\n"
        "2 x 2 points, each with a periodic 400-disk RVE; lateral pressure on the right, smooth\n"
        "rollers left and bottom, a smooth top plate moving down; against the RVE alone in a\n"
        "drained biaxial test.\n\n"
        "usage: mpmdem_single [options]\n"
        "  --size L               side of the element [m] (default 1)\n"
        "  --margin M             the cell is (1 + M) L: room for the element to widen inside it (default\n"
        "                         0.25; 0: the element fills the cell and its points leave it as it widens)\n"
        "  --pressure P           lateral pressure sigma_xx [Pa] (default 1e5, the paper's)\n"
        "  --velocity V           top plate speed [m/s] (default 0.01: 1 %% axial strain per second)\n"
        "  --ramp T               the plate speed ramps up linearly over T seconds (default 0.5)\n"
        "  --strain E             final axial strain (default 0.1)\n"
        "  --every E              axial strain between CSV rows (default 0.001)\n"
        "  --help                 this text\n");
    mpd_usage_common(fp, &d);
    fprintf(fp, "(--vtk-every, --checkpoint and --restart are not used by this driver)\n"
                "\nends with: RESULT peak_sigma_yy=... peak_sigma_yy_dem=... max_rel_diff_sigma_yy=...\n"
                "           max_diff_eps_v=... mpm_steps=... total_seconds=...\n");
}

static int parse(sg *X, int argc, char **argv) {
    sg_opts *b = &X->b;
    const cli_opt mine[] = {{"--size", CLI_REAL, &b->size, 0, 1e4, NULL, NULL, CLI_LO_OPEN},
                            {"--margin", CLI_REAL, &b->margin, 0, 10, NULL, NULL, 0},
                            {"--pressure", CLI_REAL, &b->pressure, 0, 1e10, NULL, NULL, CLI_LO_OPEN},
                            {"--velocity", CLI_REAL, &b->velocity, 0, 1e3, NULL, NULL, CLI_LO_OPEN},
                            {"--ramp", CLI_REAL, &b->ramp, 0, 1e6, NULL, NULL, 0},
                            {"--strain", CLI_REAL, &b->strain, 0, 0.5, NULL, NULL, CLI_LO_OPEN | CLI_HI_OPEN},
                            {"--every", CLI_REAL, &b->every, 0, 0.5, NULL, NULL, CLI_LO_OPEN},
                            {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    sg_opts def = {1.0, 0.25, 1e5, 0.01, 0.5, 0.1, 0.001};
    int r;
    *b = def;
    mpd_opts_default(&X->o, "build/mpm_single");
    X->o.ppc = 2;
    if ((r = mpd_parse(&X->run, argc, argv, &X->o, mine, usage)) != 0) return r;
    X->run.out = X->o.out;
    if (mpd_check_opts(&X->run, &X->o)) return 2;
    if (X->o.restart) {
        fprintf(stderr, "mpmdem_single: --restart: this driver writes no checkpoint\n");
        return 2;
    }
    X->h = b->size * (1 + b->margin);
    return 0;
}

/* the prepared RVE at every point and alone, the grid with its three smooth walls, the points and the
 * pressure on the right edges */
static int setup(sg *X, gk_err *err) {
    sg_opts *b = &X->b;
    double h = X->h, org[3], lo[3] = {0, 0, 0}, hi[3], big = 10 * h, tiny = 1e-9 * h;
    int n[3], i, gl = mpd_ghost_layers(&X->o);
    char msg[400];
    if (mpd_proto_open(&X->P, &X->o, err) || mpd_prepare_rve(&X->P, b->pressure, &X->st0, err)) return 1;
    X->c = sqrt(X->P.M / X->P.rho);
    X->dt = X->o.cfl * h / X->c;
    /* grid: the cell [0, h]^2 (the element in its lower left corner) and ghost layers around it */
    org[0] = -gl * h, org[1] = -gl * h, org[2] = 0;
    n[0] = n[1] = 2 * gl + 2, n[2] = 1;
    hi[0] = b->size, hi[1] = b->size, hi[2] = 0;
    if (gk_mpm_grid_create(&X->g, 2, org, h, n, NULL, err) ||
        gk_mpm_points_create_box(&X->pts, 2, lo, hi, b->size, X->o.ppc, X->P.rho, NULL, err) ||
        mpd_micro_create(&X->M, &X->pts, &X->P, &X->st0, 1, NULL, &X->o, err))
        return 1;
    X->a = 0.5 * b->size / X->o.ppc;
    for (i = 0; i < X->pts.n; ++i) {
        X->vol0 += X->pts.vol0[i];
        if (X->pts.x[0][i] > b->size - 2 * X->a) { /* the right column (ppc <= 4 points) */
            mpd_edge *E = &X->edge[X->nedge++];
            E->p = i, E->pressure = b->pressure, E->off[0] = X->a, E->off[1] = 0, E->e[0] = 0,
            E->e[1] = 2 * X->a;
        }
    }
    X->def = mpd_mpm_def(&X->o);
    memset(X->body, 0, sizeof X->body);
    /* base: normal +y (face y+ = 4); left wall: normal +x (x+ = 2); top plate: normal -y (y- = 3) */
    X->body[0].lo[0] = org[0] - h, X->body[0].hi[0] = b->size + big;
    X->body[0].lo[1] = org[1] - h, X->body[0].hi[1] = tiny, X->body[0].face = 4;
    X->body[1].lo[0] = org[0] - h, X->body[1].hi[0] = tiny;
    X->body[1].lo[1] = org[1] - h, X->body[1].hi[1] = b->size + big, X->body[1].face = 2;
    X->body[2].lo[0] = org[0] - h, X->body[2].hi[0] = b->size + big;
    X->body[2].lo[1] = b->size - tiny, X->body[2].hi[1] = b->size + big, X->body[2].face = 3;
    for (i = 0; i < 3; ++i) X->body[i].contact = GK_MPM_CONTACT_SMOOTH;
    X->g.body = X->body, X->g.nbody = 3;
    X->next_out = b->every;
    X->rows.size = sizeof(sg_row);
    if (mpd_rve_biaxial(&X->alone, &X->P, &X->st0, &X->o, b->pressure, &X->rate_alone, msg, sizeof msg))
        return gk_err_set(err, GK_ERR_ARG, "the RVE alone: %s", msg), 1;
    X->alone_open = 1;
    return 0;
}

static void put_csv(FILE *fp, const void *user) {
    const mpd_rows *R = (const mpd_rows *)user;
    int k;
    fprintf(fp, "time,plate_displacement,eps_axial,sigma_yy,sigma_yy_points,point_spread,eps_v,eps_axial_dem,"
                "sigma_yy_dem,sigma_xx_dem,eps_v_dem,dem_steps_per_point,seconds\n");
    for (k = 0; k < R->n; ++k) {
        const sg_row *r = (const sg_row *)mpd_row(R, k);
        fprintf(fp, "%.6g,%.6g,%.6g,%.9g,%.9g,%.3g,%.6g,%.6g,%.9g,%.9g,%.6g,%.4g,%.3f\n", r->t, r->disp,
                r->eps, r->syy, r->syy_pts, r->spread, r->ev, r->eps_dem, r->syy_dem, r->sxx_dem, r->ev_dem,
                r->dem_mean, r->secs);
    }
}

static int write_plots(const sg *X) {
    int n = X->rows.n, k, bad = 1;
    double *x = (double *)malloc((size_t)(n + 1) * 3 * sizeof *x), *y1 = x + n + 1, *y2 = y1 + n + 1;
    gk_plot pl;
    if (!x) return fprintf(stderr, "mpmdem_single: out of memory for the plots\n"), 1;
    for (k = 0; k < n; ++k) {
        const sg_row *r = (const sg_row *)mpd_row(&X->rows, k);
        x[k] = 100 * r->eps, y1[k] = r->syy / 1e3, y2[k] = r->syy_dem / 1e3;
    }
    gk_plot_init(&pl, "single element (Liang & Zhao Fig 4A): MPMxDEM element vs the RVE alone",
                 "axial strain [%]", "sigma_yy [kPa]");
    gk_plot_add(&pl, x, y1, n, "element: top plate reaction / width");
    if ((k = gk_plot_add(&pl, x, y2, n, "RVE alone: drained biaxial")) >= 0) pl.s[k].dashed = 1;
    if (!mpd_plot(&X->run, &pl, "single_stress.svg")) {
        for (k = 0; k < n; ++k) {
            const sg_row *r = (const sg_row *)mpd_row(&X->rows, k);
            y1[k] = 100 * r->ev, y2[k] = 100 * r->ev_dem;
        }
        gk_plot_init(&pl, "single element (Liang & Zhao Fig 4B): volumetric strain, compression positive",
                     "axial strain [%]", "eps_v [%]");
        gk_plot_add(&pl, x, y1, n, "element: point volumes");
        if ((k = gk_plot_add(&pl, x, y2, n, "RVE alone: cell area")) >= 0) pl.s[k].dashed = 1;
        bad = mpd_plot(&X->run, &pl, "single_volume.svg");
    }
    free(x);
    return bad;
}

/* after a step: the RVE alone to the element's axial strain, the interval sums, a CSV row when due.
 * The element's axial strain is 1 - F_yy of its points (the mean; they are equal): the cell their
 * RVEs have, and the measure of the RVE alone. It is not the plate displacement over the initial
 * height: the plate holds the top NODES, one cell height h above the base, so the material (of
 * height H < h) compresses at v H / h (the small strains dH add up to d / h, F_yy = exp(-d / h)).
 * For the same reason the element's stress from the reaction is the work-conjugate one, sigma_yy =
 * R h / V (V the element's area): a uniform sigma gives the top nodes R = sigma V / h (eq 12 with
 * the gradient 1/h of the cell's shape functions), R / width would be short by H / h. */
static int after_step(sg *X, double vplate, double t0, long nsteps_total) {
    const sg_opts *b = &X->b;
    gk_rve *A = &X->alone;
    double eps = 0, s = 0, vol = 0, lo = HUGE_VAL, hi = -HUGE_VAL;
    long long sum = 0;
    int i, n = X->pts.n;
    sg_row r;
    X->t += X->dt, X->disp += vplate * X->dt, ++X->step;
    for (i = 0; i < n; ++i) {
        double syy = -X->pts.sigma[9 * (size_t)i + 4];
        eps += 1.0 - X->pts.F[9 * (size_t)i + 4], s += syy, vol += X->pts.vol[i], sum += X->M.nsub[i];
        lo = fmin(lo, syy), hi = fmax(hi, syy);
    }
    eps /= n, s /= n;
    X->eps = eps;
    X->spread = fmax(X->spread, (hi - lo) / s);
    while (1.0 - A->cell.F[4] < eps) {
        if (gk_rve_step(A, 1)) {
            fprintf(stderr, "mpmdem_single: the RVE alone at axial strain %.4f %%: %s\n", 100 * eps,
                    gk_rve_error(A));
            return 3;
        }
        ++X->dem_alone;
    }
    X->acc_syy += -X->body[2].force[1] * X->h / vol * X->dt, X->acc_pts += s * X->dt;
    X->acc_dem += -A->stress[4] * X->dt, X->acc_dt += X->dt;
    X->acc_sub += (double)sum / n, ++X->nacc;
    if (!(eps >= X->next_out * (1 - 1e-9) || eps >= b->strain * (1 - 1e-12))) return 0;
    memset(&r, 0, sizeof r);
    r.t = X->t, r.disp = X->disp, r.eps = eps, r.ev = (X->vol0 - vol) / X->vol0, r.spread = X->spread;
    r.syy = X->acc_syy / X->acc_dt, r.syy_pts = X->acc_pts / X->acc_dt, r.syy_dem = X->acc_dem / X->acc_dt;
    r.eps_dem = 1.0 - A->cell.F[4], r.sxx_dem = -A->stress[0];
    r.ev_dem = 1.0 - (A->cell.F[0] * A->cell.F[4] - A->cell.F[1] * A->cell.F[3]);
    r.dem_mean = X->acc_sub / X->nacc, r.secs = gk_wtime() - t0;
    X->acc_syy = X->acc_pts = X->acc_dem = X->acc_dt = X->acc_sub = X->spread = 0, X->nacc = 0;
    X->next_out += b->every;
    if (mpd_rows_push(&X->run, &X->rows, &r) || mpd_write(&X->run, "single.csv", put_csv, &X->rows)) return 1;
    if (!X->o.quiet) {
        char what[300];
        snprintf(what, sizeof what, "eps %.2f %%  sigma_yy %.1f kPa (alone %.1f)  eps_v %.3f %% (alone %.3f)",
                 100 * r.eps, r.syy / 1e3, r.syy_dem / 1e3, 100 * r.ev, 100 * r.ev_dem);
        gk_progress(stderr, X->step, nsteps_total, t0, what);
    }
    return 0;
}

/* the comparison and the RESULT line */
static void report(sg *X, double secs, int wrote) {
    double pk = 0, epk = 0, pkd = 0, epkd = 0, dsy = 0, dev = 0, edsy = 0, spread = 0, dpts = 0, fsp = 0;
    const sg_row *last = X->rows.n ? (const sg_row *)mpd_row(&X->rows, X->rows.n - 1) : NULL;
    char buf[64];
    int k, p;
    /* the points' deformation gradients: equal if the element is homogeneous */
    for (p = 1; p < X->pts.n; ++p)
        for (k = 0; k < 9; ++k) fsp = fmax(fsp, fabs(X->pts.F[9 * (size_t)p + k] - X->pts.F[k]));
    for (k = 0; k < X->rows.n; ++k) {
        const sg_row *r = (const sg_row *)mpd_row(&X->rows, k);
        double d = fabs(r->syy - r->syy_dem) / r->syy_dem;
        if (r->syy > pk) pk = r->syy, epk = r->eps;
        if (r->syy_dem > pkd) pkd = r->syy_dem, epkd = r->eps;
        if (d > dsy) dsy = d, edsy = r->eps;
        dev = fmax(dev, fabs(r->ev - r->ev_dem)), spread = fmax(spread, r->spread);
        dpts = fmax(dpts, fabs(r->syy - r->syy_pts) / r->syy_pts);
    }
    if (wrote) printf("wrote %s/single.csv, single_stress.svg, single_volume.svg\n", X->run.out);
    printf("element:   peak sigma_yy %.1f kPa at %.2f %%, eps_v at the end %.3f %%\n", pk / 1e3, 100 * epk,
           last ? 100 * last->ev : 0.0);
    printf("RVE alone: peak sigma_yy %.1f kPa at %.2f %%, eps_v at the end %.3f %%\n", pkd / 1e3, 100 * epkd,
           last ? 100 * last->ev_dem : 0.0);
    printf("largest |element - alone| / alone of sigma_yy: %.2f %% (at %.2f %%); of eps_v: %.3f %% strain\n",
           100 * dsy, 100 * edsy, 100 * dev);
    printf("homogeneity: F of the points differ by %.2g at the end; their sigma_yy by up to %.3g of the mean "
           "(their DEM); plate reaction (R h / V) vs the points' mean: %.2f %%\n",
           fsp, spread, 100 * dpts);
    printf("cost: %s for %ld MPM steps (dt %.4g s); DEM steps: %lld over the 4 RVEs, %lld alone\n",
           mpd_duration(secs, buf, sizeof buf), X->step, X->dt, X->M.dem_steps, X->dem_alone);
    printf("RESULT peak_sigma_yy=%.6g eps_at_peak=%.5g peak_sigma_yy_dem=%.6g eps_at_peak_dem=%.5g "
           "max_rel_diff_sigma_yy=%.4g eps_at_max_diff=%.4g max_diff_eps_v=%.4g eps_v_end=%.5g "
           "eps_v_end_dem=%.5g "
           "eps_end=%.5g max_point_spread=%.3g f_spread=%.3g plate_vs_points=%.4g n_rves=%d mpm_steps=%ld "
           "dt=%.4g dem_steps=%lld dem_steps_alone=%lld total_seconds=%.2f\n",
           pk, epk, pkd, epkd, dsy, edsy, dev, last ? last->ev : 0.0, last ? last->ev_dem : 0.0,
           last ? last->eps : 0.0, spread, fsp, dpts, X->pts.n, X->step, X->dt, X->M.dem_steps, X->dem_alone,
           secs);
}

static int run(sg *X, int argc, char **argv) {
    const sg_opts *b = &X->b;
    double t0;
    long nsteps_total;
    int status = parse(X, argc, argv), bad = 0;
    gk_err err;
    if (status) return status == 1 ? 0 : status;
    /* the inputs (packing) first: bad input leaves no output folder behind */
    if (setup(X, &err)) return fprintf(stderr, "mpmdem_single: %s\n", err.msg), 1;
    if (mpd_out_dir(&X->run)) return 1;
    nsteps_total = (long)ceil((-log(1 - b->strain) * b->size / b->velocity + 0.5 * b->ramp) / X->dt);
    printf(
        "mpmdem_single: a %.4g m element in one %.4g m cell, %d points (= RVEs of %d disks), basis %d, alpha "
        "%g, smooth rollers\n",
        b->size, X->h, X->pts.n, X->P.pk.n, (int)X->def.basis, X->o.alpha);
    printf("RVE: p0 = %.4g kPa, e0 = %.4f, rho = %.1f kg/m3, M (Taylor) = %.4g MPa -> c = %.1f m/s; MPM dt = "
           "%.4g s (cfl %.2f); DEM dt = %.3g s\n",
           X->P.p0 / 1e3, X->P.e0, X->P.rho, X->P.M / 1e6, X->c, X->dt, X->o.cfl, X->P.dt);
    mpd_print_dem_rule(&X->o);
    printf("element: %.3g axial strain per MPM step at full speed; RVE alone: %.3g per DEM step (%.4g /s)\n",
           b->velocity * X->dt / b->size, X->rate_alone * X->alone.dt, X->rate_alone);
    printf("about %ld MPM steps to %.1f %% axial strain at %g m/s\n", nsteps_total, 100 * b->strain,
           b->velocity);
    t0 = gk_wtime();
    while (!bad && X->eps < b->strain * (1 - 1e-12)) {
        double vplate = b->velocity * (b->ramp > 0 && X->t < b->ramp ? (X->t + 0.5 * X->dt) / b->ramp : 1.0);
        X->body[2].v[1] = -vplate;
        X->M.t = X->t;
        if (mpd_step(&X->g, &X->pts, &X->def, X->dt, &X->M, X->edge, X->nedge, &err)) {
            fprintf(stderr, "mpmdem_single: step %ld (axial strain %.3f %%): %s\n", X->step,
                    100 * X->disp / b->size, err.msg);
            status = 3;
            break;
        }
        bad = after_step(X, vplate, t0, nsteps_total);
    }
    if (bad == 3) status = 3, bad = 0;
    if (!bad) bad = mpd_write(&X->run, "single.csv", put_csv, &X->rows) || write_plots(X);
    report(X, gk_wtime() - t0, !bad);
    return status ? status : bad;
}

int main(int argc, char **argv) {
    sg X;
    int status;
    memset(&X, 0, sizeof X);
    gk_rve_state_init(&X.st0, NULL);
    mpd_begin(&X.run, "mpmdem_single", &argc, &argv);
    status = run(&X, argc, argv);
    if (X.alone_open) gk_rve_destroy(&X.alone);
    mpd_free_all(&X.M, &X.P, &X.pts, &X.g, &X.rows, &X.snaps);
    gk_rve_state_free(&X.st0);
    return mpd_end(status);
}
