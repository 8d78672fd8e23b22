/* hybrid_output.h - the outputs of the hybrid driver (examples/hybrid.c; examples, not library): the
 * VTK files, the CSV rows, the band measurement and the plots, and run_free.
 *
 * OUTPUT in --out DIR: hybrid.csv (time, strain, tau, sigma_n, eps_v,
 * eps_v_band, grains, points, enriched, flagged_nodes, seconds; stresses
 * in Pa compression-positive, eps_v positive in dilation, eps_v_band the
 * same inside the band window: a rectangle around the expected band, of
 * half-width --band-window, measured by mass; indent: tau and sigma_n the
 * intruder's vertical and horizontal load / B averaged since the previous
 * row, eps_v and eps_v_band nan), points_*.vtk and
 * grains_*.vtk (start, enrichment, window start, end; "stopped" when a step
 * fails, e.g. a grain leaves the grid), stress_strain.svg,
 * volume.svg (not for indent), band.svg (the incremental shear strain
 * over the band window --window S0 S1 (strain), grains by Cundall's best
 * fit over the grains within 1.6 D50, or over Delaunay neighbours with
 * --delaunay, grey where not measured, e.g. the open cells --interior
 * leaves out; points by F),
 * packing.txt, and on stdout a line
 *   RESULT mode=M peak_tau=Pa band_thickness_D50=X strain_at_enrichment=S
 *          seconds=T speedup_vs_dem=R packing_tau=Pa band_count=N
 * (band thickness by App. A: top --percentile, or the --band-grains N
 * largest, outliers beyond 2 sd out, minimum-area box, nan for indent;
 * band_count the grains (continuum: points) selected for it, 0 when not
 * measured; a hybrid measures only its discrete zone's grains, so its
 * band_count is the --band-grains of a dem run of the same test measured
 * on as many grains (also printed); peak_tau for indent the peak of the
 * rows' q; speedup_vs_dem = --dem-seconds / seconds, nan without;
 * packing_tau, planar only: hybrid, the mean shear stress of the trained
 * packing in the discrete zone before it is inserted (Fig 13; with --train
 * 0 the untrained one), dem, that of the grains in the --probe strip at the
 * probe's strain (the contacts with their midpoint in the strip,
 * gk_scene_stress_box), nan otherwise; the hybrid run prints the --probe
 * that measures its own zone at its enrichment strain).
 * On stdout, "cost:" counts the grain-steps and point-steps of the run (the
 * N_D and element terms of the cost model of Sec 6.4.1) with the wall time
 * spent in each. Biaxial hybrid: a grain squeezed out of the discrete zone
 * that flies off towards the grid's side is removed before its coupling
 * would leave the grid (remove_escaped); planar hybrid: one that strays
 * more than a cell beyond the overlap into the continuum zone (coupling_mask).
 * Either only when it touches no grain, with a line on stdout, and at the
 * end a warning on stderr gives the count and the share of the grains'
 * mass removed.
 */
#ifndef HYBRID_OUTPUT_H
#define HYBRID_OUTPUT_H

#include "hybrid_enrich.h"

/* ------------------------------------------------------------------ output */
static int write_vtk(run *R, const char *tag) {
    char path[1200];
    gk_err e;
    int bad = 0;
    if (R->have_sc) {
        snprintf(path, sizeof path, "%s/grains_%s.vtk", R->o.out, tag);
        if (gk_scene_write_vtk(&R->sc, path, &e)) bad = fprintf(stderr, "error: cannot write %s\n", path);
    }
    if (R->have_mpm && R->P.n > 0) {
        gk_vtk v;
        int n = R->P.n, p, ok;
        double *xyz = (double *)malloc(3 * (size_t)n * sizeof(double)),
               *f = (double *)malloc(3 * (size_t)n * sizeof(double));
        int *conn = (int *)malloc((size_t)n * sizeof(int));
        snprintf(path, sizeof path, "%s/points_%s.vtk", R->o.out, tag);
        ok = xyz && f && conn;
        for (p = 0; ok && p < n; ++p) {
            double a = R->C.ep[3 * p], b = R->C.ep[3 * p + 1], c = R->C.ep[3 * p + 2];
            xyz[3 * p] = R->P.x[0][p];
            xyz[3 * p + 1] = R->P.x[1][p];
            xyz[3 * p + 2] = 0.0;
            conn[p] = p;
            f[p] = R->C.Phi[p];
            f[n + p] = sqrt(a * a + b * b + 2.0 * c * c);
            f[2 * n + p] = R->C.zone[p];
        }
        ok = ok && !gk_vtk_open(&v, path, "grainkit hybrid: material points") && !gk_vtk_points(&v, n, xyz) &&
             !gk_vtk_cells(&v, n, 1, conn, GK_VTK_VERTEX) &&
             !gk_vtk_point_scalar(&v, "packing_fraction", f) &&
             !gk_vtk_point_scalar(&v, "plastic_strain", f + n) &&
             !gk_vtk_point_scalar(&v, "zone", f + 2 * n) && !gk_vtk_point_tensor(&v, "stress", R->P.sigma) &&
             !gk_vtk_close(&v);
        if (!ok) bad = fprintf(stderr, "error: cannot write %s\n", path);
        free(xyz);
        free(f);
        free(conn);
    }
    return bad != 0;
}

/* CSV history, kept for the plots */
typedef struct hist_t {
    double *s, *tau, *sn, *ev, *evb;
    int n, cap;
} hist_t;

static int csv_row(run *R, hist_t *h) {
    int grains = R->have_sc ? R->sc.rve.n : 0, points = R->have_mpm ? R->P.n : 0;
    double ev, evb = R->o.test == T_INDENT ? NAN : R->phi0_band / band_solid_fraction(R) - 1.0, tau = R->tau,
               sn = R->sig_n;
    if (R->o.test == T_INDENT && R->qn > 0) { /* the intruder's load averaged since the last row */
        tau = R->qsum[0] / (double)R->qn;
        sn = R->qsum[1] / (double)R->qn;
        R->qsum[0] = R->qsum[1] = 0.0;
        R->qn = 0;
    }
    if (R->o.test == T_PLANAR)
        ev = R->plate_y / R->H;
    else if (R->o.test == T_INDENT)
        ev = NAN; /* an open bed: no specimen volume */
    else
        ev = specimen_area(R) / R->A0 - 1.0;
    if (fprintf(R->csv, "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%d,%d,%d,%d,%.3f\n", R->t, R->strain, tau, sn, ev, evb,
                grains, points, R->enriched, R->enriched ? 0 : R->orc.nflag, wtime() - R->t_start) < 0)
        return fprintf(stderr, "error: cannot write %s/hybrid.csv\n", R->o.out), 1;
    if (tau > R->peak_tau) R->peak_tau = tau;
    if (h->n == h->cap) {
        int c = h->cap ? 2 * h->cap : 256;
        double **a[5];
        int k;
        a[0] = &h->s;
        a[1] = &h->tau;
        a[2] = &h->sn;
        a[3] = &h->ev;
        a[4] = &h->evb;
        for (k = 0; k < 5; ++k) {
            double *q = (double *)realloc(*a[k], (size_t)c * sizeof(double));
            if (!q) return fprintf(stderr, "error: out of memory\n"), 1;
            *a[k] = q;
        }
        h->cap = c;
    }
    h->s[h->n] = 100.0 * R->strain;
    h->tau[h->n] = 1e-3 * tau;
    h->sn[h->n] = 1e-3 * sn;
    h->ev[h->n] = 100.0 * ev;
    h->evb[h->n] = 100.0 * evb;
    ++h->n;
    if (!R->o.quiet)
        printf("t %.4f s  strain %6.3f %%  tau %8.2f kPa  sigma_n %8.2f kPa  eps_v %7.3f %%  band %7.3f %%  "
               "%s%s\n",
               R->t, 100.0 * R->strain, 1e-3 * tau, 1e-3 * sn, 100.0 * ev, 100.0 * evb,
               R->enriched ? "enriched" : "", R->triggered && !R->enriched ? "flagged" : "");
    return 0;
}

/* the window start: grain positions by id, point deformation gradients */
static int take_window(run *R) {
    int p;
    R->window_taken = 1;
    R->band_on_grains = R->o.mode == M_DEM || (R->o.mode == M_HYBRID && R->enriched);
    if (R->band_on_grains) {
        int n = R->sc.rve.n;
        R->Xw[0] = (double *)malloc((size_t)n * sizeof(double));
        R->Xw[1] = (double *)malloc((size_t)n * sizeof(double));
        R->idw = (int32_t *)malloc((size_t)n * sizeof(int32_t));
        if (!R->Xw[0] || !R->Xw[1] || !R->idw) return fprintf(stderr, "error: out of memory\n"), 1;
        R->nw = 0;
        for (p = 0; p < n; ++p) {
            double x[3], d;
            gk_scene_position(&R->sc, p, x);
            /* hybrid: the grains of the discrete zone (the overlap's are tied to the continuum) */
            if (R->enriched && gk_hybrid_interp(&R->g, &R->per, R->dist, 1, R->nden, x, &d) &&
                gk_hybrid_zone(d, R->o.phi0, R->h) != GK_ZONE_DISCRETE)
                continue;
            R->Xw[0][R->nw] = x[0];
            R->Xw[1][R->nw] = x[1];
            R->idw[R->nw++] = R->sc.rve.id[p];
        }
    } else {
        memcpy(R->Fw, R->P.F, 9 * (size_t)R->P.n * sizeof(double));
    }
    return write_vtk(R, "window");
}

/* App. A over the window: incremental shear strain, band thickness; band.svg */
static int band_measure(run *R, double *thick_D50, int *count) {
    gk_err e;
    gk_hybrid_band_result b;
    int n, p, q = 0, bad = 0, nopen = 0;
    unsigned char *open = NULL;
    double *xy, *val, *X[2] = {NULL, NULL}, *x[2] = {NULL, NULL}, *eps = NULL, *half = NULL,
                      period[2] = {0.0, 0.0}, *px, *py, reach;
    char path[1200];
    *thick_D50 = NAN;
    *count = 0;
    if (!R->window_taken) return 0;
    n = R->band_on_grains ? R->nw : R->P.n;
    xy = (double *)malloc(8 * (size_t)n * sizeof(double));
    val = (double *)malloc((size_t)n * sizeof(double));
    px = (double *)malloc((size_t)n * sizeof(double));
    py = (double *)malloc((size_t)n * sizeof(double));
    if (R->band_on_grains) {
        half = (double *)malloc((size_t)n * sizeof(double));
        X[0] = (double *)malloc((size_t)n * sizeof(double));
        X[1] = (double *)malloc((size_t)n * sizeof(double));
        x[0] = (double *)malloc((size_t)n * sizeof(double));
        x[1] = (double *)malloc((size_t)n * sizeof(double));
        eps = (double *)malloc(4 * (size_t)n * sizeof(double));
        if (R->o.delaunay) open = (unsigned char *)malloc((size_t)n); /* the open-cell flags */
    }
    if (!xy || !val || !px || !py ||
        (R->band_on_grains &&
         (!half || !X[0] || !X[1] || !x[0] || !x[1] || !eps || (R->o.delaunay && !open)))) {
        bad = fprintf(stderr, "error: out of memory\n");
        goto done;
    }
    if (R->band_on_grains) {
        for (p = 0; p < R->nw; ++p) {
            int i = gk_scene_index(&R->sc, R->idw[p]);
            double xx[3];
            if (i < 0) continue;
            gk_scene_position(&R->sc, i, xx);
            X[0][q] = R->Xw[0][p];
            X[1][q] = R->Xw[1][p];
            x[0][q] = xx[0];
            x[1][q] = xx[1];
            half[q] = 0.5 * sqrt(GK_PI) * (double)R->sc.rve.r[i];
            ++q;
        }
        if (R->o.test == T_PLANAR) period[0] = R->W;
        /* 4 D50 closes a dense packing's cells (within 1.4 D50 of the grain); a narrow periodic
           specimen allows a third of its width */
        reach = period[0] > 0.0 && period[0] < 12.0 * DIAM ? period[0] / 3.0 : 4.0 * DIAM;
        if (R->o.delaunay ? gk_hybrid_cundall_delaunay(q, (const double *const *)X, (const double *const *)x,
                                                       period, reach, eps, NULL, open, NULL, &e)
                          : gk_hybrid_cundall(q, (const double *const *)X, (const double *const *)x, period,
                                              1.6 * DIAM, eps, NULL, &e)) {
            bad = fprintf(stderr, "error: Cundall strain: %s\n", e.msg);
            goto done;
        }
        if (R->o.delaunay) {
            for (p = 0; p < q; ++p) nopen += open[p];
            if (!R->o.quiet)
                printf("Cundall strain over Delaunay neighbours: %d of %d grains at the edge of the measured "
                       "set (open cells)%s\n",
                       nopen, q, R->o.interior ? ", left out" : "");
        }
        for (p = 0; p < q; ++p) {
            val[p] = R->o.interior && open[p] ? NAN : eps[4 * p + 3];
            px[p] = x[0][p];
            py[p] = x[1][p];
        }
        n = q;
        for (p = 0; p < n; ++p) {
            double a = half[p];
            xy[8 * p] = px[p] - a, xy[8 * p + 1] = py[p] - a, xy[8 * p + 2] = px[p] + a,
                   xy[8 * p + 3] = py[p] - a;
            xy[8 * p + 4] = px[p] + a, xy[8 * p + 5] = py[p] + a, xy[8 * p + 6] = px[p] - a,
                       xy[8 * p + 7] = py[p] + a;
        }
    } else {
        for (p = 0; p < n; ++p) {
            double Fi[9], D[9], m, d0, d1, s, a;
            const double *F = R->P.F + 9 * p;
            gk_m3_inverse(R->Fw + 9 * p, Fi);
            gk_m3_mul(F, Fi, D);
            m = 0.5 * (D[0] + D[4]);
            d0 = D[0] - m;
            d1 = D[4] - m;
            s = 0.5 * (D[1] + D[3]);
            val[p] = sqrt(2.0 * (d0 * d0 + d1 * d1 + 2.0 * s * s));
            px[p] = R->P.x[0][p];
            py[p] = R->P.x[1][p];
            a = 0.5 * sqrt(R->P.vol[p]);
            xy[8 * p] = px[p] - a, xy[8 * p + 1] = py[p] - a, xy[8 * p + 2] = px[p] + a,
                   xy[8 * p + 3] = py[p] - a;
            xy[8 * p + 4] = px[p] + a, xy[8 * p + 5] = py[p] + a, xy[8 * p + 6] = px[p] - a,
                       xy[8 * p + 7] = py[p] + a;
        }
    }
    if (R->o.test == T_INDENT) { /* two curved bands: App. A's one straight box does not apply */
        if (!R->o.quiet) printf("band: not measured (indent: curved bands; see band.svg)\n");
    } else if ((R->o.band_grains > 0
                    ? gk_hybrid_band_top(n, px, py, val, R->o.band_grains, 2.0, &b, NULL, &e)
                    : gk_hybrid_band(n, px, py, val, R->o.percentile, 2.0, &b, NULL, &e)) != GK_OK) {
        /* a percentile of fewer than 3 values: no band (NaN); more grains asked for than measured: an error */
        if (R->o.band_grains > 0)
            bad = fprintf(stderr, "error: --band-grains %d: %s (the grains with a Cundall strain)\n",
                          R->o.band_grains, e.msg);
    } else {
        /* points: the box of their centres plus the spacing of one point (the material it carries) */
        if (!R->band_on_grains) b.thickness += R->dyp;
        *thick_D50 = b.thickness / DIAM;
        *count = b.selected;
        if (!R->o.quiet) {
            char sel[80];
            if (R->o.band_grains > 0)
                snprintf(sel, sizeof sel, "the %d largest of %d", R->o.band_grains, b.finite);
            else
                snprintf(sel, sizeof sel, "above the %g-th percentile of %d", R->o.percentile, b.finite);
            printf("band (App. A, %s, strain %.3g-%.3g): thickness %.2f D50, angle %.1f deg, centre (%.2f, "
                   "%.2f) cm, %d of %d selected (%s) kept\n",
                   R->band_on_grains ? "grains, Cundall" : "points", R->o.win0, R->strain, b.thickness / DIAM,
                   b.angle * 180.0 / GK_PI, 100.0 * b.centre[0], 100.0 * b.centre[1], b.kept, b.selected,
                   sel);
            if (R->enriched && R->band_on_grains && R->o.band_grains == 0 && b.selected >= 3)
                printf("the same count of band grains in a dem run of this test: --band-grains %d\n",
                       b.selected);
        }
    }
    {
        gk_field_def fd;
        int len[2] = {2, 2};
        double Hc = specimen_height(R),
               lines[8] = {-0.05 * R->W, 0.0, 1.05 * R->W, 0.0, -0.05 * R->W, Hc, 1.05 * R->W, Hc};
        char title[200];
        memset(&fd, 0, sizeof fd);
        snprintf(title, sizeof title, "%s %s: incremental shear strain, strain %.3g to %.3g",
                 test_name[R->o.test], mode_name[R->o.mode], R->o.win0, R->strain);
        fd.title = title;
        fd.label = "gamma (incremental) [%]";
        fd.xlabel = "x [mm]";
        fd.ylabel = "y [mm]";
        fd.coord_scale = 1e3;
        fd.nlines = 2;
        fd.line_len = len;
        fd.line_xy = lines;
        snprintf(path, sizeof path, "%s/band.svg", R->o.out);
        for (p = 0; p < n; ++p) val[p] *= 100.0; /* strain in % as in every plot (the band was measured) */
        if (gk_field_svg(path, &fd, n, 4, xy, val, &e))
            bad = fprintf(stderr, "error: cannot write %s\n", path);
    }
done:
    free(xy);
    free(val);
    free(px);
    free(py);
    free(half);
    free(X[0]);
    free(X[1]);
    free(x[0]);
    free(x[1]);
    free(eps);
    free(open);
    return bad != 0;
}

static int write_plots(const run *R, const hist_t *h) {
    gk_plot pl;
    gk_err e;
    char path[1200], title[200];
    int bad = 0, t = R->o.test;
    const char *xl[3] = {"strain = platen displacement / W [%]", "axial strain [%]",
                         "intruder depth / width [%]"};
    const char *l1[3] = {"tau", "tau = (sigma_1 - sigma_3)/2", "q = vertical force / B"};
    const char *l2[3] = {"sigma_n", "sigma_1 (axial)", "horizontal force / B"};
    if (t == T_INDENT)
        snprintf(title, sizeof title, "plate indentation, %s", mode_name[R->o.mode]);
    else
        snprintf(title, sizeof title, "%s shear, %s", test_name[t], mode_name[R->o.mode]);
    gk_plot_init(&pl, title, xl[t], "stress [kPa]");
    gk_plot_add(&pl, h->s, h->tau, h->n, l1[t]);
    gk_plot_add(&pl, h->s, h->sn, h->n, l2[t]);
    snprintf(path, sizeof path, "%s/stress_strain.svg", R->o.out);
    if (gk_plot_svg(&pl, path, &e)) bad = fprintf(stderr, "error: cannot write %s\n", path);
    if (t == T_INDENT) return bad != 0; /* an open bed: no volume */
    gk_plot_init(&pl, title, t == T_PLANAR ? "strain [%]" : "axial strain [%]",
                 "volumetric strain [%] (dilation +)");
    gk_plot_add(&pl, h->s, h->ev, h->n, "specimen");
    gk_plot_add(&pl, h->s, h->evb, h->n, "band window");
    snprintf(path, sizeof path, "%s/volume.svg", R->o.out);
    if (gk_plot_svg(&pl, path, &e)) bad = fprintf(stderr, "error: cannot write %s\n", path);
    return bad != 0;
}

/* ------------------------------------------------------------------ the end of a run */
static void run_free(run *R) {
    if (R->have_sc) gk_scene_destroy(&R->sc);
    if (R->have_mpm) {
        gk_mpm_grid_destroy(&R->g);
        gk_mpm_points_destroy(&R->P);
        gk_hybrid_cont_free(&R->C);
        gk_hybrid_oracle_free(&R->orc);
        gk_hybrid_history_free(&R->hist);
        if (R->enriched) gk_hybrid_coupling_free(&R->cpl);
    }
    gk_packing_free(&R->pk);
    free(R->role);
    free(R->side);
    free(R->Fw);
    free(R->bcmask);
    free(R->past);
    free(R->pval);
    free(R->nnum);
    free(R->nden);
    free(R->nrate);
    free(R->nrec);
    free(R->active);
    free(R->dist);
    free(R->xpre[0]);
    free(R->xpre[1]);
    free(R->coupled);
    free(R->wid);
    free(R->cw);
    free(R->deep);
    free(R->drop_ids);
    free(R->Xw[0]);
    free(R->Xw[1]);
    free(R->idw);
}
#endif /* HYBRID_OUTPUT_H */
