/* mpmdem_phi.h - the friction angle of an RVE, measured as mpmdem_footing.c
 * needs it for Prandtl's N_q (examples, not library; included by the
 * footing driver after mpmdem.h).
 *
 * One RVE per confining pressure sigma_3: prepared at sigma_3 like the
 * footing's RVEs (mpd_prepare_rve), then a drained biaxial test with
 * gk_rve_set_servo (axis 0 stress-controlled at -sigma_3, axis 1 compressed
 * at constant rate: the inertial number --dem-inertial at sigma_3 with the
 * adaptive DEM rule, --dem-strain per DEM step with the strain rule, i.e. as
 * the MPM's RVEs deform) to --phi-strain and on until the peak lies 1 % of
 * strain behind (a hardening RVE that has not peaked by 25 % uses its
 * maximum). Peak = maximum of the mobilised sin phi = (s1 - s3)/(s1 + s3)
 * after a centred moving average over +-0.1 % axial strain (a 400-disk RVE
 * is noisy). phi per test = asin of that; the Mohr-Coulomb envelope through
 * the origin tangent (least squares) to the peak circles, sin phi = sum(c r)
 * / sum(c^2) (c, r = centre and radius), is the phi used (the regression r
 * = c sin phi + c' cos phi with a cohesion c' is printed too). The same fit
 * of the means over the last 2 % of strain gives phi_res.
 *
 *   nq_prandtl(phi)     N_q of Prandtl, Liang & Zhao eq 46
 *   phi_reduced(phi)    Terzaghi's reduced angle for local failure, eq 47
 *   phi_of_nq(nq)       the angle whose eq 46 is nq
 *   phi_measure(...)    the tests, the envelopes, rve_biaxial.svg and rve_mohr.svg
 */
#ifndef MPMDEM_PHI_H
#define MPMDEM_PHI_H

#include "mpmdem.h"

#define FT_MAXPHI 6
typedef struct ft_phi_test {
    double s3;                     /* confining pressure [Pa] */
    double e0, p0;                 /* state after preparation */
    double rate;                   /* axial strain rate [1/s] */
    double s1, s3m, eps_peak, phi; /* smoothed peak: s1, s3 [Pa], strain, phi [deg] */
    double r1, r3, phi_res;        /* residual: means over the last 2 % of axial strain */
    double eps_end;
    int nsamp, nopeak;   /* nopeak: no peak by FT_PHI_STRAIN_MAX (the maximum is used) */
    double *eps, *ratio; /* sampled curve: axial strain, s1/s3 (for the plot) */
    int status;
    char msg[400];
} ft_phi_test;

/* N_q of Prandtl, eq 46 (phi in degrees) */
static double nq_prandtl(double phi_deg) {
    double p = phi_deg * MPD_PI / 180.0, t = tan(MPD_PI / 4 + p / 2);
    return t * t * exp(MPD_PI * tan(p));
}
/* the angle whose eq 46 gives N_q (bisection; N_q < 1 has none) [deg] */
static double phi_of_nq(double nq) {
    double lo = 0.0, hi = 60.0;
    int k;
    if (!(nq >= 1.0) || nq > nq_prandtl(hi)) return NAN;
    for (k = 0; k < 60; ++k) {
        double m = 0.5 * (lo + hi);
        if (nq_prandtl(m) < nq)
            lo = m;
        else
            hi = m;
    }
    return 0.5 * (lo + hi);
}

/* Terzaghi's reduced angle for local / punching failure, eq 47 [deg] */
static double phi_reduced(double phi_deg) {
    return atan(2.0 / 3.0 * tan(phi_deg * MPD_PI / 180.0)) * 180.0 / MPD_PI;
}

/* centred moving average of y over x-window w (shrinks at the ends to stay centred) */
static void smooth_curve(const double *x, const double *y, int n, double w, double *ys) {
    int k, j;
    for (k = 0; k < n; ++k) {
        double hw = 0.5 * w, s = 0.0;
        int c = 0;
        if (x[k] - x[0] < hw) hw = x[k] - x[0];
        if (x[n - 1] - x[k] < hw) hw = x[n - 1] - x[k];
        for (j = 0; j < n; ++j)
            if (fabs(x[j] - x[k]) <= hw * (1 + 1e-12)) s += y[j], ++c;
        ys[k] = c ? s / c : y[k];
    }
}

/* ------------------------------------------------- friction angle of the RVE */
#define FT_PHI_STRAIN_MAX 0.25 /* a test that has not peaked by then uses its maximum */

/* index of the largest smoothed sin phi_mob = (s1 - s3)/(s1 + s3) (means
 * over +-0.1 % of axial strain); the smoothed s1, s3 there */
static int smoothed_peak(const double *eps, const double *s1, const double *s3, int n, double *a, double *b,
                         double *a_pk, double *b_pk) {
    int k, kb = 0;
    double best = -2.0;
    smooth_curve(eps, s1, n, 0.002, a);
    smooth_curve(eps, s3, n, 0.002, b);
    for (k = 0; k < n; ++k) {
        double sn = a[k] + b[k] > 0 ? (a[k] - b[k]) / (a[k] + b[k]) : -1.0;
        if (sn > best) best = sn, kb = k;
    }
    *a_pk = a[kb], *b_pk = b[kb];
    return kb;
}
/* one drained biaxial test (see the top comment); 0 or 1 with out->msg */
static int phi_test(const mpd_proto *P0, const mpd_opts *o, double max_strain, ft_phi_test *out) {
    mpd_proto P = *P0; /* mpd_prepare_rve writes rho, M, p0, e0: keep the caller's */
    gk_rve_state st;
    gk_rve r;
    gk_err err;
    double rate, *s1 = NULL, *s3 = NULL, *wa = NULL, *wb = NULL;
    int chunk, cap, n = 0, k, bad = 0;
    gk_rve_state_init(&st, NULL);
    if (mpd_prepare_rve(&P, out->s3, &st, &err)) {
        snprintf(out->msg, sizeof out->msg, "%s", err.msg);
        gk_rve_state_free(&st);
        return out->status = 1;
    }
    out->e0 = P.e0, out->p0 = P.p0;
    bad = mpd_rve_biaxial(&r, &P, &st, o, out->s3, &rate, out->msg, sizeof out->msg);
    gk_rve_state_free(&st);
    if (bad) return out->status = 1;
    out->rate = rate;
    chunk = (int)ceil(1e-4 / (rate * r.dt)); /* a sample every 1e-4 of axial strain */
    cap = (int)ceil(1.5 * FT_PHI_STRAIN_MAX / (chunk * rate * r.dt)) + 10; /* the servo moves F_11 a little */
    out->eps = (double *)malloc((size_t)cap * sizeof(double));
    out->ratio = (double *)malloc((size_t)cap * sizeof(double));
    s1 = (double *)malloc((size_t)cap * sizeof(double));
    s3 = (double *)malloc((size_t)cap * sizeof(double));
    wa = (double *)malloc((size_t)cap * sizeof(double));
    wb = (double *)malloc((size_t)cap * sizeof(double));
    if (!out->eps || !out->ratio || !s1 || !s3 || !wa || !wb) {
        snprintf(out->msg, sizeof out->msg, "out of memory");
        bad = 1;
    }
    /* to --phi-strain, then on until the peak lies 1 % of strain behind (a hardening RVE) */
    while (!bad && n < cap) {
        double e;
        if (gk_rve_step(&r, chunk)) {
            snprintf(out->msg, sizeof out->msg, "biaxial at %g Pa: %s", out->s3, gk_rve_error(&r));
            bad = 1;
            break;
        }
        e = 1.0 - r.cell.F[4];
        out->eps[n] = e, s1[n] = -r.stress[4], s3[n] = -r.stress[0];
        out->ratio[n] = s3[n] > 0 ? s1[n] / s3[n] : 0.0;
        ++n;
        if (e >= FT_PHI_STRAIN_MAX) {
            out->nopeak = 1;
            break;
        }
        if (e >= max_strain && n % 50 == 0) {
            double u, v;
            if (out->eps[smoothed_peak(out->eps, s1, s3, n, wa, wb, &u, &v)] <= e - 0.01) break;
        }
    }
    out->nsamp = n;
    if (!bad && n > 0) {
        int kp = smoothed_peak(out->eps, s1, s3, n, wa, wb, &out->s1, &out->s3m), c = 0;
        double sn = (out->s1 - out->s3m) / (out->s1 + out->s3m);
        out->eps_peak = out->eps[kp];
        out->phi = sn > 0 ? asin(sn) * 180.0 / MPD_PI : 0.0;
        out->eps_end = out->eps[n - 1];
        out->r1 = out->r3 = 0;
        for (k = 0; k < n; ++k)
            if (out->eps[k] >= out->eps_end - 0.02) out->r1 += s1[k], out->r3 += s3[k], ++c;
        if (c) out->r1 /= c, out->r3 /= c;
        out->phi_res = out->r1 > out->r3 && out->r3 > 0
                           ? asin((out->r1 - out->r3) / (out->r1 + out->r3)) * 180.0 / MPD_PI
                           : 0.0;
    }
    free(wa), free(wb);
    free(s1), free(s3);
    gk_rve_destroy(&r);
    return out->status = bad;
}

/* Mohr-Coulomb envelope: through the origin (least squares tangent) and
 * with cohesion (regression of the radii on the centres) */
static double phi_fit(const ft_phi_test *T, int n, int residual, double *phi_c, double *coh) {
    double sc = 0, sr = 0, scc = 0, scr = 0, sinp;
    int k;
    for (k = 0; k < n; ++k) {
        double a = residual ? T[k].r1 : T[k].s1, b = residual ? T[k].r3 : T[k].s3m;
        double c = 0.5 * (a + b), r = 0.5 * (a - b);
        sc += c, sr += r, scc += c * c, scr += c * r;
    }
    sinp = scr / scc;
    *phi_c = *coh = NAN;
    if (n >= 2) {
        double slope = (n * scr - sc * sr) / (n * scc - sc * sc), icpt = (sr - slope * sc) / n;
        if (fabs(slope) < 1) {
            *phi_c = asin(slope) * 180.0 / MPD_PI;
            *coh = icpt / cos(asin(slope));
        }
    }
    return asin(gk_clamp(sinp, -1.0, 1.0)) * 180.0 / MPD_PI;
}

/* rve_biaxial.svg (the tests' curves) and rve_mohr.svg (peak circles, envelope; equal aspect) */
static int phi_plots(const mpd_run *run, const ft_phi_test *T, int n, double phi) {
    char lab[FT_MAXPHI][64], el[64];
    gk_plot pl;
    int k, j, m = 97, s, bad;
    double cx[FT_MAXPHI][97], cy[FT_MAXPHI][97], ex[2], ey[2], smax = 0, *x[FT_MAXPHI];
    gk_plot_init(&pl, "RVE drained biaxial tests (the friction angle eq 46 uses)", "axial strain [%]",
                 "sigma_1 / sigma_3");
    for (k = 0; k < n; ++k) {
        x[k] = (double *)malloc((size_t)(T[k].nsamp + 1) * sizeof(double));
        if (!x[k]) continue;
        for (j = 0; j < T[k].nsamp; ++j) x[k][j] = 100 * T[k].eps[j];
        snprintf(lab[k], sizeof lab[k], "sigma_3 = %g kPa: phi = %.1f deg", T[k].s3 / 1e3, T[k].phi);
        gk_plot_add(&pl, x[k], T[k].ratio, T[k].nsamp, lab[k]);
    }
    bad = mpd_plot(run, &pl, "rve_biaxial.svg");
    for (k = 0; k < n; ++k) free(x[k]);
    if (bad) return 1;
    gk_plot_init(&pl, "Mohr circles at the peak and the envelope through the origin", "sigma [kPa]",
                 "tau [kPa]");
    for (k = 0; k < n; ++k) {
        double c = 0.5 * (T[k].s1 + T[k].s3m) / 1e3, r = 0.5 * (T[k].s1 - T[k].s3m) / 1e3;
        for (j = 0; j < m; ++j) {
            double a = MPD_PI * j / (m - 1);
            cx[k][j] = c - r * cos(a), cy[k][j] = r * sin(a);
        }
        if (T[k].s1 / 1e3 > smax) smax = T[k].s1 / 1e3;
        snprintf(lab[k], sizeof lab[k], "sigma_3 = %g kPa", T[k].s3 / 1e3);
        gk_plot_add(&pl, cx[k], cy[k], m, lab[k]);
    }
    ex[0] = 0, ey[0] = 0, ex[1] = smax, ey[1] = smax * tan(phi * MPD_PI / 180.0);
    snprintf(el, sizeof el, "envelope phi = %.2f deg", phi);
    s = gk_plot_add(&pl, ex, ey, 2, el);
    if (s >= 0) pl.s[s].dashed = 1;
    pl.has_ylim = 1, pl.ylim[0] = 0, pl.ylim[1] = 0.75 * smax;
    pl.equal_aspect = 1; /* circles look like circles */
    return mpd_plot(run, &pl, "rve_mohr.svg");
}

/* the tests at the n pressures press[] [Pa] (rank 0, on the option's threads; the angles then on
 * every rank), printed and plotted: *phi and *phi_res [deg]; 0, or 1 (said) */
static int phi_measure(const mpd_run *run, const mpd_proto *P, const mpd_opts *o, const double *press, int n,
                       double strain, const char *material, double paper_phi, double *phi, double *phi_res) {
    ft_phi_test T[FT_MAXPHI];
    double v[3] = {0, 0, 0}, phi_c = NAN, coh = NAN, phi_rc, coh_r, t0 = gk_wtime();
    int k, nbad = 0;
    memset(T, 0, sizeof T);
    if (run->rank == 0) {
        printf(
            "friction angle: %d drained biaxial RVE tests (sigma_3 held by the servo; axial compression at "
            "%s) ...\n",
            n,
            o->dem_rule == 0 ? "the inertial number of --dem-inertial at sigma_3"
                             : "--dem-strain per DEM step");
        fflush(stdout);
        for (k = 0; k < n; ++k) T[k].s3 = press[k];
        GK_OMP(parallel for num_threads(o->threads) schedule(dynamic, 1) reduction(+ : nbad))
        for (k = 0; k < n; ++k) nbad += phi_test(P, o, strain, &T[k]);
        for (k = 0; k < n; ++k) {
            if (T[k].status) {
                fprintf(stderr, "%s: RVE biaxial at sigma_3 = %g kPa: %s\n", run->prog, T[k].s3 / 1e3,
                        T[k].msg);
                continue;
            }
            printf("  sigma_3 = %4.0f kPa (%.3g /s): e0 = %.4f, peak sigma_1 = %.1f kPa (sigma_3 %.1f) at "
                   "%.2f %% "
                   "axial strain -> phi = %.2f deg; residual (mean over %.1f-%.1f %%) %.2f deg\n",
                   T[k].s3 / 1e3, T[k].rate, T[k].e0, T[k].s1 / 1e3, T[k].s3m / 1e3, 100 * T[k].eps_peak,
                   T[k].phi, fmax(0.0, 100 * T[k].eps_end - 2), 100 * T[k].eps_end, T[k].phi_res);
            if (T[k].nopeak)
                printf("    (no peak by %.0f %% axial strain: the maximum is used, a hardening RVE)\n",
                       100 * FT_PHI_STRAIN_MAX);
        }
        v[0] = nbad;
        if (!nbad) {
            v[1] = phi_fit(T, n, 0, &phi_c, &coh);
            v[2] = phi_fit(T, n, 1, &phi_rc, &coh_r);
            printf("  Mohr-Coulomb envelope of the peaks through the origin: phi = %.2f deg", v[1]);
            if (n >= 2 && isfinite(phi_c))
                printf(" (with cohesion: phi = %.2f deg, c = %.2f kPa)", phi_c, coh / 1e3);
            printf("; Liang & Zhao '%s': %.1f deg\n", material, paper_phi);
            printf("  residual envelope (end of the tests): phi_res = %.2f deg; %.1f s for the tests\n", v[2],
                   gk_wtime() - t0);
        }
    }
#ifdef GK_TWOSCALE_MPI
    MPI_Bcast(v, 3, MPI_DOUBLE, 0, MPI_COMM_WORLD);
#endif
    if (v[0] == 0.0) v[0] = phi_plots(run, T, n, v[1]); /* collective: rank 0 writes */
    for (k = 0; k < FT_MAXPHI; ++k) free(T[k].eps), free(T[k].ratio);
    *phi = v[1], *phi_res = v[2];
    return v[0] != 0.0;
}

#endif /* MPMDEM_PHI_H */
