/* mpmdem_biaxial.c - the MPMxDEM biaxial test of seed 003 (Liang & Zhao,
 * Sec 3.2): a 1 x 2 m specimen of material points, each with its own
 * periodic 400-disk RVE, 100 kPa lateral pressure on both sides, fixed base,
 * rough rigid top plate moving down at 0.02 m/s (ramped), no gravity.
 * Reported by the seed for mesh M (20x10 cells, 4 points per cell): peak
 * sigma_yy ~ 280 kPa at ~1.6 % axial strain, ~220 kPa at 8 %, cross-shaped
 * shear bands, rotations up to 58 deg in the bands at 15 %.
 *
 *   build/mpmdem_biaxial                       # 8 x 16 cells, 1 point each, to 3 %
 *   build/mpmdem_biaxial --nx 10 --ny 20 --ppc 2 --strain 0.15   # the seed's M4
 *
 * Model. Points fill the specimen (ppc^2 per cell, h = width / nx); the grid
 * is padded by ghost layers and by room for the bulge. The base and the top
 * plate are rigid STICK bodies (rough; the base at rest): their reactions
 * are the axial loads. The lateral pressure is a follower load on the outer
 * edges of the points of the outer columns (mpd_edge in mpmdem.h: the edge
 * turns and stretches with the point's F, and its load goes to the nodes
 * with the weights of the edge, so the initial state is in equilibrium). Every point's RVE starts from the packing
 * (default: the seed 000 authors' 400 disks, consolidated to 100 kPa, e =
 * 0.177 as seed 003 states) and receives dH = dt L each MPM step (USF,
 * mpmdem.h). sigma_yy = -(plate reaction)/width (the rough plate keeps the
 * top width), averaged over each output interval; eps_v from the point
 * volumes; rotation of each point from the polar decomposition of F.
 *
 * Outputs in --out DIR: biaxial.csv, biaxial_stress.svg, biaxial_volume.svg,
 * rotation_*.svg and eps_q_*.svg (fields at 1.5 %, 2 %, 3 % and the end,
 * the seed's stages), points_NNNNNN.vtk, checkpoint.bin; a RESULT line.
 */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_base.h"
#include "gk_dem.h"
#include "gk_homog.h"
#include "gk_io.h"
#include "gk_mpm.h"
#include "mpmdem.h"

typedef struct bx_opts {
    int nx, ny;
    double width, height, pressure, velocity, ramp, strain, every;
} bx_opts;

typedef struct bx_row { /* one CSV row: means over an output interval */
    double t, eps, syy_top, syy_base, ev, ek, dem_mean, secs;
} bx_row;

/* the state a checkpoint must carry besides points and RVEs */
typedef struct bx_state {
    long step;
    double t, disp;
    gk_mpm_body body[2];              /* 0: base, 1: top plate */
    double acc_top, acc_base, acc_dt; /* force x dt accumulated since the last row */
    double acc_ek, acc_dem;           /* kinetic energy, DEM steps per point: sums */
    long nacc;                        /*   over the MPM steps since the last row    */
    double next_out;                  /* axial strain of the next CSV row */
    int nstage;
} bx_state;

static void usage(FILE *fp, const mpd_opts *d) {
    fprintf(
        fp,
        "mpmdem_biaxial - MPMxDEM biaxial test of seed 003 Sec 3.2: every material point has a periodic\n"
        "400-disk RVE; lateral pressure, rough top plate, fixed base, no gravity.\n\n"
        "usage: mpmdem_biaxial [options]\n"
        "  --nx N --ny N          cells across the width and the height (default 8 x 16; seed meshes\n"
        "                         C 8x16, M 10x20, F 15x30 with --ppc 1 or 2, or 3 for 9 points per cell)\n"
        "  --width W --height H   specimen [m] (default 1 x 2); W/nx must equal H/ny\n"
        "  --pressure P           lateral pressure sigma_3 [Pa] (default 1e5)\n"
        "  --velocity V           top plate speed [m/s] (default 0.02, the seed's)\n"
        "  --ramp T               the plate speed ramps up linearly over T seconds (default 0.5)\n"
        "  --strain E             final axial strain (default 0.03; the seed goes to 0.15)\n"
        "  --every E              axial strain between CSV rows (default 0.001)\n"
        "  --help                 this text\n");
    mpd_usage_common(fp, d);
    fprintf(fp,
            "\nends with: RESULT peak_sigma_yy=... eps_at_peak=... sigma_yy_end=... max_rotation_deg=...\n"
            "           n_rves=... mpm_steps=... seconds_per_step=... seconds_per_step_per_1000_rves=...\n");
}

static void write_csv(const char *out, const bx_row *r, int n) {
    char path[1200];
    FILE *fp;
    int k;
    snprintf(path, sizeof path, "%s/biaxial.csv", out);
    fp = fopen(path, "w");
    if (!fp) {
        fprintf(stderr, "warning: cannot write %s\n", path);
        return;
    }
    fprintf(fp, "time,eps_axial,sigma_yy,sigma_yy_base,eps_v,kinetic_energy,dem_steps_per_point,seconds\n");
    for (k = 0; k < n; ++k)
        fprintf(fp, "%.6g,%.6g,%.9g,%.9g,%.6g,%.6g,%.4g,%.3f\n", r[k].t, r[k].eps, r[k].syy_top,
                r[k].syy_base, r[k].ev, r[k].ek, r[k].dem_mean, r[k].secs);
    fclose(fp);
}

static void write_plots(const char *out, const bx_row *r, int n) {
    double *x = (double *)malloc((size_t)(n + 1) * sizeof *x),
           *y1 = (double *)malloc((size_t)(n + 1) * sizeof *y1),
           *y2 = (double *)malloc((size_t)(n + 1) * sizeof *y2);
    char path[1200];
    gk_err err;
    gk_plot pl;
    int k;
    if (x && y1 && y2) {
        for (k = 0; k < n; ++k)
            x[k] = 100 * r[k].eps, y1[k] = r[k].syy_top / 1e3, y2[k] = r[k].syy_base / 1e3;
        gk_plot_init(&pl, "MPMxDEM biaxial (seed 003 Fig 6: peak ~280 kPa at 1.6 %)", "axial strain [%]",
                     "sigma_yy [kPa]");
        gk_plot_add(&pl, x, y1, n, "top plate reaction / width");
        gk_plot_add(&pl, x, y2, n, "base reaction / width");
        snprintf(path, sizeof path, "%s/biaxial_stress.svg", out);
        gk_plot_svg(&pl, path, &err);
        for (k = 0; k < n; ++k) y1[k] = 100 * r[k].ev;
        gk_plot_init(&pl, "MPMxDEM biaxial: volumetric strain (compression positive)", "axial strain [%]",
                     "eps_v [%]");
        gk_plot_add(&pl, x, y1, n, "specimen (sum of point volumes)");
        snprintf(path, sizeof path, "%s/biaxial_volume.svg", out);
        gk_plot_svg(&pl, path, &err);
    }
    free(x), free(y1), free(y2);
}

static void stage_fields(const char *out, const char *tag, const mpd_rves *f, const gk_mpm_points *pts,
                         double dot) {
    char path[1200], title[200];
    snprintf(path, sizeof path, "%s/rotation_%s.svg", out, tag);
    snprintf(title, sizeof title, "rotation of F = RU [deg] at %s axial strain (seed 003 Fig 8)", tag);
    mpd_svg_field(path, title, f, pts, 2, dot);
    snprintf(path, sizeof path, "%s/eps_q_%s.svg", out, tag);
    snprintf(title, sizeof title, "deviatoric strain eps_q at %s axial strain", tag);
    mpd_svg_field(path, title, f, pts, 0, dot);
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* the dominant shear band: the points whose eps_q exceeds twice the median,
 * their principal axis (largest eigenvector of the covariance of their
 * positions, weighted by eps_q) -> angle from the horizontal in [0, 90] deg.
 * NaN when no point stands out (no localisation yet). */
static double band_angle(const mpd_rves *f, const gk_mpm_points *pts) {
    int n = pts->n, p, m = 0;
    double *e = (double *)malloc((size_t)n * sizeof *e), *s = (double *)malloc((size_t)n * sizeof *s), med,
           w = 0, mx = 0, my = 0, cxx = 0, cyy = 0, cxy = 0, ang = NAN;
    if (e && s) {
        for (p = 0; p < n; ++p) {
            double v[MPD_NFIELD];
            mpd_fields(f, pts, p, v);
            e[p] = s[p] = v[0];
        }
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
            ang = 0.5 * atan2(2 * cxy, cxx - cyy) * 180.0 / MPD_PI; /* principal direction */
            ang = fabs(ang);
            if (ang > 90) ang = 180 - ang;
        }
    }
    free(e), free(s);
    return ang;
}

int main(int argc, char **argv) {
    mpd_opts o, od;
    bx_opts b = {8, 16, 1.0, 2.0, 1e5, 0.02, 0.5, 0.03, 0.001};
    mpd_proto P;
    gk_rve_state st0;
    mpd_rves F;
    gk_mpm_grid g;
    gk_mpm_points pts;
    gk_mpm_def def;
    bx_state S;
    bx_row *rows = NULL;
    int nrows = 0, caprows = 0, i, nedge = 0, status = 0;
    mpd_edge *edge = NULL;
    double h, dt, c, lo[3], hi[3], org[3], vol0 = 0, t0, t_start, stages[3] = {0.015, 0.02, 0.03};
    long nsteps_total, step0;
    long long dem0;
    gk_err err;
    char buf[64], what[300], path[1200];
    int n[3];

    mpd_opts_default(&od, "build/mpmdem_biaxial");
    o = od;
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i];
        double v;
        int r = mpd_parse_common(&o, argc, argv, &i);
        if (r < 0) return 2;
        if (r > 0) continue;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) return usage(stdout, &od), 0;
        if (i + 1 >= argc) return fprintf(stderr, "mpmdem_biaxial: %s needs a value (see --help)\n", a), 2;
        if (mpd_num(argv[i + 1], &v))
            return fprintf(stderr, "mpmdem_biaxial: %s %s: not a number\n", a, argv[i + 1]), 2;
        if (!strcmp(a, "--nx"))
            b.nx = (int)v;
        else if (!strcmp(a, "--ny"))
            b.ny = (int)v;
        else if (!strcmp(a, "--width"))
            b.width = v;
        else if (!strcmp(a, "--height"))
            b.height = v;
        else if (!strcmp(a, "--pressure"))
            b.pressure = v;
        else if (!strcmp(a, "--velocity"))
            b.velocity = v;
        else if (!strcmp(a, "--ramp"))
            b.ramp = v;
        else if (!strcmp(a, "--strain"))
            b.strain = v;
        else if (!strcmp(a, "--every"))
            b.every = v;
        else
            return fprintf(stderr, "mpmdem_biaxial: unknown option %s (see --help)\n", a), 2;
        ++i;
    }
    if (b.nx < 1 || b.ny < 1 || b.nx > 2000 || b.ny > 2000 || !(b.width > 0) || !(b.height > 0) ||
        !(b.pressure >= 0) || !(b.velocity > 0) || !(b.ramp >= 0) || !(b.strain > 0 && b.strain < 0.5) ||
        !(b.every > 0) || mpd_check_opts(&o))
        return fprintf(stderr, "mpmdem_biaxial: an option is out of range (see --help)\n"), 2;
    h = b.width / b.nx;
    if (fabs(b.height / b.ny - h) > 1e-9 * h)
        return fprintf(stderr, "mpmdem_biaxial: cells must be square: width/nx = %g, height/ny = %g\n", h,
                       b.height / b.ny),
               2;
    if (mpd_mkdir(o.out)) return 1;

    /* ---- the RVE every point starts from */
    gk_rve_state_init(&st0, NULL);
    if (mpd_proto_open(&P, &o, &err) || mpd_prepare_rve(&P, b.pressure, &st0, &err)) {
        fprintf(stderr, "mpmdem_biaxial: %s\n", err.msg);
        return 1;
    }
    c = sqrt(P.M / P.rho);
    dt = o.cfl * h / c;
    /* ---- grid: ghost layers, room for a 30 % bulge on each side, the plate above */
    {
        int gl = mpd_ghost_layers(o.basis), padx = gl + (int)ceil(0.3 * b.nx);
        org[0] = -padx * h, org[1] = -gl * h, org[2] = 0;
        n[0] = b.nx + 2 * padx + 1, n[1] = b.ny + 2 * gl + 1, n[2] = 1;
        if (gk_mpm_grid_create(&g, 2, org, h, n, NULL, &err))
            return fprintf(stderr, "mpmdem_biaxial: %s\n", err.msg), 1;
    }
    lo[0] = 0, lo[1] = 0, lo[2] = 0, hi[0] = b.width, hi[1] = b.height, hi[2] = 0;
    if (gk_mpm_points_create_box(&pts, 2, lo, hi, h, o.ppc, P.rho, NULL, &err))
        return fprintf(stderr, "mpmdem_biaxial: %s\n", err.msg), 1;
    if (mpd_rves_create(&F, pts.n, &P, &st0, NULL, NULL, &o, &err))
        return fprintf(stderr, "mpmdem_biaxial: %s\n", err.msg), 1;
    edge = (mpd_edge *)calloc((size_t)pts.n, sizeof *edge);
    if (!edge) return fprintf(stderr, "mpmdem_biaxial: out of memory\n"), 1;
    for (i = 0; i < pts.n; ++i) { /* the lateral pressure on the outer columns' outer edges */
        double a = 0.5 * h / o.ppc, side = pts.x[0][i] < 2 * a ? -1 : pts.x[0][i] > b.width - 2 * a ? 1 : 0;
        mpd_rve_sigma(&F.rve[i], pts.sigma + 9 * (size_t)i);
        vol0 += pts.vol0[i];
        if (side == 0) continue;
        edge[nedge].p = i, edge[nedge].pressure = b.pressure;
        edge[nedge].off[0] = side * a, edge[nedge].off[1] = 0;
        edge[nedge].e[0] = 0, edge[nedge].e[1] = side * 2 * a;
        ++nedge;
    }
    def = mpd_mpm_def(&o);
    memset(&S, 0, sizeof S);
    S.body[0].lo[0] = org[0] - h, S.body[0].hi[0] = -org[0] + b.width + h;
    S.body[0].lo[1] = org[1] - h, S.body[0].hi[1] = 1e-9 * h;
    S.body[1].lo[0] = S.body[0].lo[0], S.body[1].hi[0] = S.body[0].hi[0];
    S.body[1].lo[1] = b.height - 1e-9 * h, S.body[1].hi[1] = b.height + 10 * h;
    S.body[0].contact = S.body[1].contact = GK_MPM_CONTACT_STICK;
    S.next_out = b.every;
    if (o.restart) {
        void *blob[2];
        size_t size[2] = {sizeof S, 0};
        bx_row *rr = NULL;
        blob[0] = &S, blob[1] = &rr;
        if (mpd_ck_read(o.restart, "biaxial", blob, size, 2, &pts, &F, &err))
            return fprintf(stderr, "mpmdem_biaxial: %s\n", err.msg), 1;
        rows = rr, nrows = caprows = (int)(size[1] / sizeof *rows);
    }
    g.body = S.body, g.nbody = 2;
    nsteps_total = (long)ceil((b.strain * b.height / b.velocity + 0.5 * b.ramp) / dt);
    printf("mpmdem_biaxial: %d x %d cells, h = %.4g m, %d points (= RVEs of %d disks), basis %d, alpha %g\n",
           b.nx, b.ny, h, pts.n, F.rve[0].n, (int)o.basis, o.alpha);
    printf("RVE: p0 = %.4g kPa, e0 = %.4f, rho = %.1f kg/m3, M (Taylor) = %.4g MPa -> c = %.1f m/s; MPM dt = "
           "%.4g s "
           "(cfl %.2f); DEM dt = %.3g s\n",
           P.p0 / 1e3, P.e0, P.rho, P.M / 1e6, c, dt, o.cfl, F.rve[0].dt);
    mpd_print_dem_rule(&o);
    printf("about %ld MPM steps to %.1f %% axial strain at %g m/s\n", nsteps_total, 100 * b.strain,
           b.velocity);
    if (!o.restart) {
        snprintf(path, sizeof path, "%s/points_%06ld.vtk", o.out, 0L);
        mpd_write_vtk(path, &F, &pts);
    }
    t_start = gk_wtime();
    t0 = t_start;
    step0 = S.step, dem0 = F.dem_steps;
    {
        while (S.disp < b.strain * b.height * (1 - 1e-12)) {
            double vplate = b.velocity * (b.ramp > 0 && S.t < b.ramp ? (S.t + 0.5 * dt) / b.ramp : 1.0), ek,
                   m, mom[3];
            S.body[1].v[1] = -vplate;
            if (mpd_step(&g, &pts, &def, dt, &F, edge, nedge, &err)) {
                fprintf(stderr, "mpmdem_biaxial: step %ld (axial strain %.3f %%): %s\n", S.step,
                        100 * S.disp / b.height, err.msg);
                status = 3;
                break;
            }
            S.t += dt, S.disp += vplate * dt, ++S.step;
            S.acc_top += -S.body[1].force[1] * dt, S.acc_base += S.body[0].force[1] * dt, S.acc_dt += dt;
            gk_mpm_points_totals(&pts, &m, mom, &ek);
            S.acc_ek += ek, ++S.nacc;
            {
                long long sum = 0;
                for (i = 0; i < pts.n; ++i) sum += F.nsub[i];
                S.acc_dem += (double)sum / pts.n;
            }
            if (S.disp >= S.next_out * b.height * (1 - 1e-9) || S.disp >= b.strain * b.height * (1 - 1e-12)) {
                bx_row r;
                double vol = 0;
                for (i = 0; i < pts.n; ++i) vol += pts.vol[i];
                r.t = S.t, r.eps = S.disp / b.height;
                r.syy_top = S.acc_top / S.acc_dt / b.width, r.syy_base = S.acc_base / S.acc_dt / b.width;
                r.ev = (vol0 - vol) / vol0, r.ek = S.acc_ek / S.nacc, r.dem_mean = S.acc_dem / S.nacc;
                r.secs = gk_wtime() - t0;
                S.acc_top = S.acc_base = S.acc_dt = 0, S.acc_ek = S.acc_dem = 0, S.nacc = 0;
                S.next_out += b.every;
                if (nrows == caprows) {
                    caprows = caprows ? 2 * caprows : 64;
                    rows = (bx_row *)realloc(rows, (size_t)caprows * sizeof *rows);
                    if (!rows) return fprintf(stderr, "mpmdem_biaxial: out of memory\n"), 1;
                }
                rows[nrows++] = r;
                write_csv(o.out, rows, nrows);
                while (S.nstage < 3 && r.eps >= stages[S.nstage] * (1 - 1e-9)) {
                    char tag[32];
                    snprintf(tag, sizeof tag, "%.1f%%", 100 * stages[S.nstage]);
                    stage_fields(o.out, tag, &F, &pts, 0.5 * h / o.ppc);
                    ++S.nstage;
                }
                if (!o.quiet) {
                    snprintf(what, sizeof what,
                             "eps %.2f %%  sigma_yy %.1f kPa (base %.1f)  eps_v %.3f %%  DEM %.1f/pt",
                             100 * r.eps, r.syy_top / 1e3, r.syy_base / 1e3, 100 * r.ev, r.dem_mean);
                    gk_progress(stderr, S.step, nsteps_total, t_start, what);
                }
            }
            if (o.vtk_every && S.step % o.vtk_every == 0) {
                snprintf(path, sizeof path, "%s/points_%06ld.vtk", o.out, S.step);
                mpd_write_vtk(path, &F, &pts);
            }
            if (o.checkpoint_every && S.step % o.checkpoint_every == 0) {
                void *blob[2];
                size_t size[2];
                blob[0] = &S, size[0] = sizeof S, blob[1] = rows, size[1] = (size_t)nrows * sizeof *rows;
                mpd_ck_write(o.out, "biaxial", blob, size, 2, &pts, &F);
            }
        }
    }
    {
        double secs = gk_wtime() - t_start, peak = 0, epk = 0, rmax = 0, ang = band_angle(&F, &pts);
        long steps_run = S.step - step0;
        void *blob[2];
        size_t size[2];
        int k;
        blob[0] = &S, size[0] = sizeof S, blob[1] = rows, size[1] = (size_t)nrows * sizeof *rows;
        if (status == 0) mpd_ck_write(o.out, "biaxial", blob, size, 2, &pts, &F);
        write_csv(o.out, rows, nrows);
        write_plots(o.out, rows, nrows);
        stage_fields(o.out, "end", &F, &pts, 0.5 * h / o.ppc);
        snprintf(path, sizeof path, "%s/points_%06ld.vtk", o.out, S.step);
        mpd_write_vtk(path, &F, &pts);
        for (k = 0; k < nrows; ++k)
            if (rows[k].syy_top > peak) peak = rows[k].syy_top, epk = rows[k].eps;
        for (i = 0; i < pts.n; ++i) {
            double v[MPD_NFIELD];
            mpd_fields(&F, &pts, i, v);
            if (fabs(v[2]) > rmax) rmax = fabs(v[2]);
        }
        printf("wrote %s/biaxial.csv, biaxial_stress.svg, biaxial_volume.svg, rotation_*.svg, eps_q_*.svg, "
               "points_*.vtk (ParaView), checkpoint.bin\n",
               o.out);
        printf("seed 003 (mesh M4, its RVE): peak sigma_yy ~ 280 kPa at 1.6 %%; here %.1f kPa at %.2f %% "
               "(sigma_1/sigma_3 = %.2f; seed ~2.8)\n",
               peak / 1e3, 100 * epk, b.pressure > 0 ? peak / b.pressure : 0.0);
        if (ang == ang)
            printf("shear band: %.1f deg from the horizontal (principal axis of the points with eps_q > 2 x "
                   "median; "
                   "seed 003: first band ~60 deg)\n",
                   ang);
        else
            printf("shear band: none yet (no point with eps_q > 2 x median)\n");
        printf("cost: %s for %ld MPM steps, %lld DEM steps over all RVEs (%.1f per point per MPM step)\n",
               mpd_duration(secs, buf, sizeof buf), steps_run, F.dem_steps - dem0,
               steps_run ? (double)(F.dem_steps - dem0) / steps_run / pts.n : 0.0);
        printf(
            "RESULT peak_sigma_yy=%.6g eps_at_peak=%.5g sigma_yy_end=%.6g eps_end=%.5g max_rotation_deg=%.3g "
            "band_angle_deg=%.3g "
            "n_rves=%d mpm_steps=%ld dt=%.4g seconds_per_step=%.4g seconds_per_step_per_1000_rves=%.4g "
            "total_seconds=%.2f\n",
            peak, epk, nrows ? rows[nrows - 1].syy_top : 0.0, nrows ? rows[nrows - 1].eps : 0.0, rmax, ang,
            pts.n, steps_run, dt, steps_run ? secs / steps_run : 0.0,
            steps_run ? secs / steps_run * 1000.0 / pts.n : 0.0, secs);
    }
    free(rows);
    free(edge);
    mpd_rves_free(&F);
    gk_rve_state_free(&st0);
    mpd_proto_close(&P);
    gk_mpm_points_destroy(&pts);
    gk_mpm_grid_destroy(&g);
    return status;
}
