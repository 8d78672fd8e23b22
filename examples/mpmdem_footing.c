/* mpmdem_footing.c - the MPMxDEM rigid footing of seed 003 (Liang & Zhao,
 * Sec 3.3): a rigid rough strip footing pushed into a weightless soil with a
 * 20 kPa surcharge; every material point has its own periodic 400-disk RVE.
 * Load-settlement curve, the bearing-capacity factor N_q = p_u / q_s (eq 45)
 * against Prandtl's N_q = tan^2(pi/4 + phi/2) exp(pi tan phi) (eq 46; eq 47
 * phi_r = atan(2/3 tan phi) for local / punching failure), with phi the
 * friction angle of the RVE MEASURED here by single-RVE drained biaxial
 * tests; the failure mode picture (eps_q field). Seed: N_q 14.4 (MPMxDEM)
 * vs 14.8 (eq 46, phi = 28.1 deg) for the dense packing.
 *
 *   build/mpmdem_footing                  # reduced default (about a minute)
 *   build/mpmdem_footing --paper          # 12 x 8 m, 108 x 72 cells, 7776 RVEs
 *
 * GEOMETRY (half model, x = 0 is the symmetry plane). The paper: soil 12 m
 * wide, 8 m deep, footing "1 m x 2 m (width x height)", d/B = 1.5 at the end.
 * B here is the FULL footing width, B = 1 m: the footing is 2 m tall and
 * must still stick out of the ground at d = 1.5 B, so B <= 1.33 m, and
 * "width" is the physical footing's. The half model therefore carries the
 * half-width b = B/2 = 0.5 m (--B changes it). Loads are per unit length
 * (plane strain) OF THE HALF MODEL: the footing pressure is q = load / b
 * (= full load / B); N_q does not depend on B for a weightless soil, only
 * the resolution b/h and the domain size in footing widths do.
 *
 * BOUNDARIES. Left (x = 0): roller (symmetry plane). Right: smooth rigid
 * wall = roller. Base: fixed. Top: the surcharge q_s as a follower load
 * (mpd_edge, mpmdem.h: the edge turns and stretches with F, its load goes
 * to the nodes with the weights of the edge) on the top edges of the top row
 * of points beyond the footing edge x = b. The footing is a gk_mpm_body box
 * (its ghost part too), STICK contact (rough base and side), prescribed
 * velocity -v ramped up linearly over --ramp seconds; load = -force_y (the
 * reaction, per unit length of the half model), averaged over each output
 * interval. FOOTING EDGE: a nodal rigid body covering the nodes x <= x_k
 * carries a uniform stress over x <= x_k + h/2 (each node's tributary
 * width), so the body covers x <= B/2 - h/2 and b = x_k + h/2 = B/2 exactly
 * when B/2 = (k + 1/2) h (the default h = 0.2 and the paper's h = 1/9 m
 * are; otherwise b is the nearest such width below B/2, printed, and q =
 * load / b). Covering x <= B/2 instead makes the footing half a cell wider
 * than b: +25 % load at b = 2 h.
 *
 * INITIAL STATE. Weightless soil under a uniform 20 kPa surface load is at
 * sigma = -20 kPa I everywhere (roller walls, fixed base): every RVE is the
 * packing consolidated ISOTROPICALLY to q_s by mpd_prepare_rve (one prepared
 * RVE copied to every point), so the model starts in equilibrium and the
 * footing's first reaction is q_s b.
 *
 * MATERIAL = seed 003 Table 2 (--material dense | medium | soft): E, kt/kn
 * (the table's nu), interparticle friction, rolling beta and eta, local
 * damping 0.1. "Medium dense" differs from "dense" only by e0 (0.2314 vs
 * 0.1874): give it a looser packing with --packing (the default one is
 * dense: e ~ 0.18 at 20 kPa; examples/data/rve400_e0223.txt is looser). DEM step: 3.16e-5 s sqrt(6e8 / E), the same
 * fraction of the critical step as seed 000's 3.16e-5 s at E = 600 MPa.
 *
 * FRICTION ANGLE (what eq 46 needs). Before the footing, the driver runs one
 * RVE per confining pressure (--phi-pressures, default 10, 20, 30 kPa; the
 * seed used 10..30 kPa): prepared at sigma_3 like the footing's RVEs, then a
 * drained biaxial test with gk_rve_set_servo (axis 0 stress-controlled at
 * -sigma_3, axis 1 compressed at constant rate: the inertial number
 * --dem-inertial at sigma_3 with the adaptive DEM rule, --dem-strain per DEM
 * step with the strain rule, i.e. as the MPM's RVEs deform) to
 * --phi-strain and on until the peak lies 1 % of strain behind (a hardening
 * RVE, e.g. a loose one, that has not peaked by 25 % uses its maximum). Peak = maximum of the mobilised sin phi = (s1 - s3)/(s1 +
 * s3) after a centred moving average over +-0.1 % axial strain (a 400-disk
 * RVE is noisy). phi per test = asin of that; the Mohr-Coulomb envelope
 * through the origin tangent (least squares) to the peak circles, sin phi
 * = sum(c r) / sum(c^2) (c, r = centre and radius), is the phi used (the
 * regression r = c sin phi + c' cos phi with a cohesion c' is printed too).
 * The same fit of the means over the last 2 % of strain gives phi_res (the
 * softened end of the tests, not yet a critical state at 8 %): the dense
 * RVE peaks at ~0.7 % and loses ~7 deg, and a footing on it fails
 * progressively, so its N_q lies between eq 46 of phi_res and of phi; the
 * output also gives the phi whose eq 46 is the computed N_q.
 * Nothing is cached: every run measures (or --phi-deg X skips it).
 *
 * ULTIMATE LOAD (Vesic's rule, as the seed: the first point where the slope
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
 * TIME STEP, DEM STEPS: mpmdem.h (dt = cfl h / c from the RVE's Taylor
 * tangent; DEM steps per MPM step by its --dem-rule, default adaptive).
 *
 * RATE. The PIC part of the PIC/FLIP blend damps like a viscosity: its
 * shear stress is of order rho alpha c v / cfl (~6 kPa at alpha 0.1, 0.1
 * m/s here), not small next to the strength of a soil at 20 kPa, so N_q
 * grows with alpha v (measured with --dem-rule strain on the 18 x 12 grid:
 * 12.8 at 0.1 m/s, 15.2 at 0.25 m/s, 11.9 at 0.25 m/s with alpha 0; on a
 * 24 x 16 grid 1 m/s gave ~1.5 x the 0.25 m/s value). The default keeps
 * the seed's alpha = 0.1 and 0.1 m/s.
 *
 * SIZE AND COST. The paper's grid (--paper: 12 x 8 m, 108 x 72 cells, h =
 * 0.111 m, 1 point per cell = 7776 RVEs x 400 disks, 0.1 m/s to d/B = 1.5)
 * takes hours. The default is a reduced problem that finishes in about a
 * minute on 2 idle cores and still reaches the ultimate load: a 6 x 3 m
 * domain (the Prandtl mechanism of phi <= 32 deg reaches 5.3 B from the
 * axis and ~1.5 B deep), h = 0.2 m (b = 2.5 cells, 450 RVEs), the seed's
 * 0.1 m/s, to d/B = 0.14 (the dense footing peaks at d/B ~ 0.06). The run
 * prints its memory (VmHWM, per RVE) and projects the paper-size memory and
 * wall time; --max-steps N stops early (e.g. a 5-step run at the paper's
 * size to measure both there).
 *
 * Outputs in --out DIR: footing.csv (load-settlement), footing_load.svg,
 * rve_biaxial.svg and rve_mohr.svg (phi measurement), eps_q_dB*.svg (stages)
 * and eps_q_end.svg, rotation_end.svg, void_ratio_end.svg, displacement_end.svg
 * (failure mode), points_NNNNNN.vtk, checkpoint.bin; a RESULT line.
 */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_base.h"
#include "gk_dem.h"
#include "gk_homog.h"
#include "gk_io.h"
#include "gk_mpm.h"
#include "mpmdem.h"

#define FT_MAXPHI 6
#define FT_NSTAGE 6
#define FT_DEM_DT_REF 3.16e-5 /* seed 000's DEM step at E = 600 MPa */

typedef struct ft_opts {
    int nx, ny, material;
    double width, depth, B, foot_height, surcharge, velocity, ramp, final_dB, every, smooth;
    double phi_deg; /* > 0: skip the measurement */
    double phi_p[FT_MAXPHI];
    int nphi;
    double phi_strain;   /* largest axial strain of a biaxial RVE test */
    double grid_damping; /* local non-viscous grid damping (0: none, as the seed) */
    long max_steps;      /* 0: no limit */
} ft_opts;

typedef struct ft_row { /* one CSV row: means over an output interval */
    double t, d, q, load, ek, dem_mean, secs;
} ft_row;

/* what a checkpoint must carry besides points and RVEs */
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

static const char *material_names[3] = {"dense", "medium", "soft"};

/* seed 003 Table 2 (400 disks, r 3-7 mm, rho 2650, nu = kt/kn 0.5, beta 1.0, alpha 0.1) */
static void apply_material(mpd_opts *o, int m) {
    o->young = m == 2 ? 80e6 : 800e6;
    o->kt_ratio = 0.5;
    o->friction_deg = m == 2 ? 20.0 : 23.0;
    o->roll_beta = 1.0;
    o->roll_eta = m == 2 ? 0.02 : 0.05;
    o->dem_damping = 0.1;
}
static const double table2_e0[3] = {0.1874, 0.2314, 0.2299};
static const double seed_phi[3] = {28.1, 20.8, 18.2};
static const double seed_nq[3] = {14.4, 4.8, 3.7};
static const double seed_nq_analytic[3] = {14.8, 3.7, 3.1};

static void paper_size(ft_opts *f) {
    f->width = 12.0, f->depth = 8.0, f->nx = 108, f->ny = 72;
    f->velocity = 0.1, f->ramp = 0.5, f->final_dB = 1.5, f->every = 0.01, f->smooth = 0.05;
}

static void usage(FILE *fp, const mpd_opts *d, const ft_opts *f) {
    fprintf(
        fp,
        "mpmdem_footing - MPMxDEM rigid rough strip footing of seed 003 Sec 3.3: weightless soil, "
        "surcharge,\n"
        "half model (symmetry plane at x = 0, smooth right wall, fixed base), every material point a "
        "periodic\n"
        "400-disk RVE; load-settlement curve, N_q vs eqs 45-47 with the RVE's measured friction angle.\n\n"
        "usage: mpmdem_footing [options]\n"
        "  --nx N --ny N          cells across the width and the depth (default %d x %d; paper 108 x 72)\n"
        "  --width W --depth D    soil domain of the half model [m] (default %g x %g; paper 12 x 8);\n"
        "                         W/nx must equal D/ny\n"
        "  --paper                the paper's size: 12 x 8 m, 108 x 72 cells (7776 RVEs), 0.1 m/s, ramp 0.5 "
        "s,\n"
        "                         to d/B = 1.5, rows every 0.01 (other flags given override it)\n"
        "  --B W                  FULL footing width [m] (default %g: the seed's 1 m x 2 m footing); the\n"
        "                         half model carries b = B/2; q = load / b\n"
        "  --footing-height H     footing height above the ground [m] (default %g)\n"
        "  --surcharge Q          surcharge q_s on the ground outside the footing [Pa] (default %g)\n"
        "  --velocity V           footing speed [m/s] (default %g; the seed's 0.1)\n"
        "  --ramp T               the speed ramps up linearly over T seconds (default %g)\n"
        "  --final X              final settlement d/B (default %g; the seed's 1.5)\n"
        "  --every X              d/B between CSV rows (default %g)\n"
        "  --smooth X             moving-average window in d/B for the ultimate-load rule (default %g)\n"
        "  --material M           dense | medium | soft: seed 003 Table 2 contact parameters (default\n"
        "                         dense: E 800 MPa, kt/kn 0.5, friction 23 deg, beta 1.0, eta 0.05, damping\n"
        "                         0.1; soft: E 80 MPa, 20 deg, eta 0.02; medium = dense with e0 0.2314:\n"
        "                         give it a looser --packing). --young etc. given too override it.\n"
        "  --phi-deg X            friction angle for eq 46 [deg]; skips the RVE biaxial measurement\n"
        "  --phi-pressures LIST   confining pressures of the measurement [kPa], comma-separated, at most %d\n"
        "                         (default 10,20,30; the seed used 10,15,20,25,30)\n"
        "  --phi-strain E         axial strain a measurement test runs to at least; then on until its peak "
        "lies\n"
        "                         1 %% behind, at most 25 %% (default %g)\n"
        "  --grid-damping A       local non-viscous damping on the grid nodes in [0, 1) (default %g: none,\n"
        "                         as the seed; reactions never include it)\n"
        "  --max-steps N          stop after N MPM steps (timing / memory probe; default: no limit)\n"
        "  --help                 this text\n",
        f->nx, f->ny, f->width, f->depth, f->B, f->foot_height, f->surcharge, f->velocity, f->ramp,
        f->final_dB, f->every, f->smooth, FT_MAXPHI, f->phi_strain, f->grid_damping);
    mpd_usage_common(fp, d);
    fprintf(
        fp,
        "  (footing: --dem-dt defaults to 3.16e-5 s x sqrt(6e8 / E), seed 000's fraction of the critical "
        "step)\n"
        "\noutputs in --out: footing.csv (time,d,d_over_B,q,q_over_qs,load_half,kinetic_energy,\n"
        "  dem_steps_per_point,seconds), footing_load.svg, rve_biaxial.svg, rve_mohr.svg, eps_q_dB*.svg,\n"
        "  eps_q_end.svg, rotation_end.svg, void_ratio_end.svg, displacement_end.svg, points_*.vtk,\n"
        "  checkpoint.bin\n"
        "ends with: RESULT Nq=... Nq_analytic=... Nq_analytic_local=... phi_deg=... phi_res_deg=...\n"
        "           Nq_analytic_res=... phi_mobilised_deg=... q_ult=... d_ult_over_B=... "
        "ultimate_reached=...\n"
        "           n_rves=... mpm_steps=... dt=... seconds_per_step=... seconds_per_step_per_1000_rves=...\n"
        "           seconds_per_step_per_1000_rves_after_first=... mem_per_rve_kb=... vmhwm_mb=... "
        "total_seconds=...\n");
}

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
    gk_servo sv;
    gk_err err;
    double rate, L[9], *s1 = NULL, *s3 = NULL, *wa = NULL, *wb = NULL;
    int chunk, cap, n = 0, k, bad = 0;
    gk_rve_state_init(&st, NULL);
    if (mpd_prepare_rve(&P, out->s3, &st, &err)) {
        snprintf(out->msg, sizeof out->msg, "%s", err.msg);
        gk_rve_state_free(&st);
        return out->status = 1;
    }
    out->e0 = P.e0, out->p0 = P.p0;
    if (gk_rve_create(&r, &P.def, &P.pk) || gk_rve_state_restore(&st, &r)) {
        snprintf(out->msg, sizeof out->msg, "RVE: %s", gk_rve_error(&r));
        gk_rve_state_free(&st);
        return out->status = 1;
    }
    gk_rve_state_free(&st);
    if (o->dem_adaptive) { /* the inertial number the coupling's RVEs deform at, at sigma_3 */
        double one[9], rmean = 0;
        for (k = 0; k < r.n; ++k) rmean += (double)r.r[k];
        rmean /= r.n;
        gk_m3_zero(one);
        one[4] = 1.0;
        rate = o->dem_inertial / gk_inertial_number(one, 2, rmean, r.def.mat.density, out->s3);
    } else {
        rate = o->dem_strain / r.dt; /* the coupling's strain per DEM step */
    }
    memset(&sv, 0, sizeof sv);
    sv.mode[0] = GK_SERVO_STRESS, sv.target[0] = -out->s3;
    sv.mode[1] = GK_SERVO_STRAIN, sv.rate[1] = -rate;
    sv.mode[2] = GK_SERVO_STRAIN;
    sv.max_rate = 10.0 * rate; /* lateral strain rate: dilatancy can exceed the axial one */
    sv.gain = 0.5;
    gk_m3_zero(L);
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
    if (!bad && (gk_rve_set_velocity_gradient(&r, L) || gk_rve_set_servo(&r, &sv))) {
        snprintf(out->msg, sizeof out->msg, "servo: %s", gk_rve_error(&r));
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

static void phi_plots(const char *out, const ft_phi_test *T, int n, double phi) {
    char path[1200], lab[FT_MAXPHI][64], el[64];
    gk_plot pl;
    gk_err err;
    int k, j, m = 97, s;
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
    snprintf(path, sizeof path, "%s/rve_biaxial.svg", out);
    gk_plot_svg(&pl, path, &err);
    for (k = 0; k < n; ++k) free(x[k]);
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
    snprintf(path, sizeof path, "%s/rve_mohr.svg", out);
    gk_plot_svg(&pl, path, &err);
}

/* ---------------------------------------------------------- outputs */
static void write_csv(const char *out, const ft_row *r, int n, double B, double qs) {
    char path[1200];
    FILE *fp;
    int k;
    snprintf(path, sizeof path, "%s/footing.csv", out);
    fp = fopen(path, "w");
    if (!fp) {
        fprintf(stderr, "warning: cannot write %s\n", path);
        return;
    }
    fprintf(fp, "time,d,d_over_B,q,q_over_qs,load_half,kinetic_energy,dem_steps_per_point,seconds\n");
    for (k = 0; k < n; ++k)
        fprintf(fp, "%.6g,%.6g,%.6g,%.9g,%.6g,%.9g,%.6g,%.4g,%.3f\n", r[k].t, r[k].d, r[k].d / B, r[k].q,
                r[k].q / qs, r[k].load, r[k].ek, r[k].dem_mean, r[k].secs);
    fclose(fp);
}

static void stage_field(const char *out, const char *tag, const char *title, const mpd_rves *F,
                        const gk_mpm_points *pts, int k, double dot) {
    char path[1200];
    snprintf(path, sizeof path, "%s/%s.svg", out, tag);
    mpd_svg_field(path, title, F, pts, k, dot);
}

static void displacement_field(const char *out, const gk_mpm_points *pts, const double *x0, double dot) {
    char path[1200];
    gk_err err;
    int n = pts->n, p;
    double *xy = (double *)malloc(2 * (size_t)n * sizeof *xy), *u = (double *)malloc((size_t)n * sizeof *u);
    if (xy && u) {
        for (p = 0; p < n; ++p) {
            double dx = pts->x[0][p] - x0[2 * p], dy = pts->x[1][p] - x0[2 * p + 1];
            xy[2 * p] = pts->x[0][p], xy[2 * p + 1] = pts->x[1][p];
            u[p] = sqrt(dx * dx + dy * dy);
        }
        snprintf(path, sizeof path, "%s/displacement_end.svg", out);
        if (gk_svg_field(path, "displacement |u| [m] at the end (seed 003 Fig 14)", "|u| [m]", n, 1, xy, u,
                         dot, &err))
            fprintf(stderr, "warning: %s\n", err.msg);
    }
    free(xy), free(u);
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

static void load_plot(const char *out, const ft_row *r, int n, const double *qsm, double B, double qs, int ku,
                      double nq46, double nq47, double phi) {
    double *x = (double *)malloc((size_t)n * sizeof *x), *y = (double *)malloc((size_t)n * sizeof *y),
           *ys = (double *)malloc((size_t)n * sizeof *ys);
    double hx[2], h1[2], h2[2], ux[1], uy[1];
    char path[1200], l1[80], l2[80], lu[80];
    gk_plot pl;
    gk_err err;
    int k, s;
    if (x && y && ys && n > 0) {
        for (k = 0; k < n; ++k) x[k] = r[k].d / B, y[k] = r[k].q / qs, ys[k] = qsm[k] / qs;
        gk_plot_init(&pl, "MPMxDEM rigid footing: load-settlement (seed 003 Fig 16)", "settlement d/B",
                     "footing pressure q / q_s");
        gk_plot_add(&pl, x, y, n, "q / q_s (interval means)");
        gk_plot_add(&pl, x, ys, n, "smoothed (ultimate-load rule)");
        hx[0] = 0, hx[1] = x[n - 1], h1[0] = h1[1] = nq46, h2[0] = h2[1] = nq47;
        snprintf(l1, sizeof l1, "N_q eq 46, phi = %.1f deg: %.2f", phi, nq46);
        snprintf(l2, sizeof l2, "N_q eq 47, phi_r = %.1f deg: %.2f", phi_reduced(phi), nq47);
        s = gk_plot_add(&pl, hx, h1, 2, l1);
        if (s >= 0) pl.s[s].dashed = 1;
        s = gk_plot_add(&pl, hx, h2, 2, l2);
        if (s >= 0) pl.s[s].dashed = 1;
        if (ku >= 0) {
            ux[0] = x[ku], uy[0] = ys[ku];
            snprintf(lu, sizeof lu, "ultimate: N_q = %.2f", ys[ku]);
            gk_plot_add(&pl, ux, uy, 1, lu);
        }
        pl.has_ylim = 1, pl.ylim[0] = 0;
        pl.ylim[1] = 1.15 * nq46;
        for (k = 0; k < n; ++k)
            if (1.1 * y[k] > pl.ylim[1]) pl.ylim[1] = 1.1 * y[k];
        snprintf(path, sizeof path, "%s/footing_load.svg", out);
        gk_plot_svg(&pl, path, &err);
    }
    free(x), free(y), free(ys);
}

static int parse_list(const char *s, double *v, int max) {
    int n = 0;
    char buf[256], *tok, *save = NULL;
    snprintf(buf, sizeof buf, "%s", s);
    for (tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        double x;
        if (n >= max || mpd_num(tok, &x) || !(x > 0)) return -1;
        v[n++] = x * 1e3;
    }
    return n;
}

int main(int argc, char **argv) {
    mpd_opts o, od;
    ft_opts f, fd;
    mpd_proto P;
    gk_rve_state st0;
    mpd_rves F;
    gk_mpm_grid g;
    gk_mpm_points pts;
    gk_mpm_def def;
    ft_state S;
    ft_row *rows = NULL;
    ft_phi_test T[FT_MAXPHI];
    int nrows = 0, caprows = 0, i, status = 0, measured = 0, gl, nedge = 0;
    mpd_edge *edge = NULL;
    double h, b, bnode, dt, c, lo[3], hi[3], org[3], t_start, phi, phi_c = NAN, coh = NAN, *x0 = NULL;
    double phi_res = NAN, phi_rc = NAN, coh_r = NAN;
    double rss_before, rss_after, stages[FT_NSTAGE] = {0.05, 0.1, 0.25, 0.5, 1.0, 1.5};
    long nsteps_total, step0;
    long long dem0, dem_first = 0;
    double t_first = 0;
    gk_err err;
    char buf[64], what[300], path[1200];
    int n[3];

    /* ---- options: presets (--material, --paper) first, then every flag */
    memset(&fd, 0, sizeof fd);
    fd.nx = 30, fd.ny = 15, fd.width = 6.0, fd.depth = 3.0, fd.B = 1.0, fd.foot_height = 2.0;
    fd.surcharge = 2e4, fd.velocity = 0.1, fd.ramp = 0.1, fd.final_dB = 0.14, fd.every = 0.005;
    fd.smooth = 0.04, fd.phi_deg = 0, fd.nphi = 3, fd.phi_p[0] = 1e4, fd.phi_p[1] = 2e4, fd.phi_p[2] = 3e4;
    fd.phi_strain = 0.08;
    mpd_opts_default(&od, "build/mpmdem_footing");
    apply_material(&od, 0);
    od.dem_dt = FT_DEM_DT_REF * sqrt(6e8 / od.young);
    o = od, f = fd;
    for (i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) return usage(stdout, &od, &fd), 0;
        if (!strcmp(argv[i], "--paper")) paper_size(&f);
        if (!strcmp(argv[i], "--material") && i + 1 < argc) {
            int m;
            for (m = 0; m < 3; ++m)
                if (!strcmp(argv[i + 1], material_names[m])) break;
            if (m == 3)
                return fprintf(stderr, "mpmdem_footing: --material %s: use dense, medium or soft\n",
                               argv[i + 1]),
                       2;
            f.material = m;
            apply_material(&o, m);
        }
    }
    o.dem_dt = -1.0; /* not given: from E below */
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i];
        double v;
        int r = mpd_parse_common(&o, argc, argv, &i);
        if (r < 0) return 2;
        if (r > 0) continue;
        if (!strcmp(a, "--paper")) continue;
        if (i + 1 >= argc) return fprintf(stderr, "mpmdem_footing: %s needs a value (see --help)\n", a), 2;
        if (!strcmp(a, "--material")) {
            ++i;
            continue;
        }
        if (!strcmp(a, "--phi-pressures")) {
            f.nphi = parse_list(argv[++i], f.phi_p, FT_MAXPHI);
            if (f.nphi < 1)
                return fprintf(stderr,
                               "mpmdem_footing: --phi-pressures %s: need 1 to %d positive pressures in kPa, "
                               "comma-separated\n",
                               argv[i], FT_MAXPHI),
                       2;
            continue;
        }
        if (mpd_num(argv[i + 1], &v))
            return fprintf(stderr, "mpmdem_footing: %s %s: not a number\n", a, argv[i + 1]), 2;
        if (!strcmp(a, "--nx"))
            f.nx = (int)v;
        else if (!strcmp(a, "--ny"))
            f.ny = (int)v;
        else if (!strcmp(a, "--width"))
            f.width = v;
        else if (!strcmp(a, "--depth"))
            f.depth = v;
        else if (!strcmp(a, "--B"))
            f.B = v;
        else if (!strcmp(a, "--footing-height"))
            f.foot_height = v;
        else if (!strcmp(a, "--surcharge"))
            f.surcharge = v;
        else if (!strcmp(a, "--velocity"))
            f.velocity = v;
        else if (!strcmp(a, "--ramp"))
            f.ramp = v;
        else if (!strcmp(a, "--final"))
            f.final_dB = v;
        else if (!strcmp(a, "--every"))
            f.every = v;
        else if (!strcmp(a, "--smooth"))
            f.smooth = v;
        else if (!strcmp(a, "--phi-deg")) {
            if (!(v > 0 && v < 60))
                return fprintf(stderr, "mpmdem_footing: --phi-deg %s: need an angle in (0, 60)\n",
                               argv[i + 1]),
                       2;
            f.phi_deg = v;
        } else if (!strcmp(a, "--phi-strain"))
            f.phi_strain = v;
        else if (!strcmp(a, "--grid-damping"))
            f.grid_damping = v;
        else if (!strcmp(a, "--max-steps")) {
            if (v != floor(v) || v < 1 || v > 1e12)
                return fprintf(stderr, "mpmdem_footing: --max-steps %s: need a positive integer\n",
                               argv[i + 1]),
                       2;
            f.max_steps = (long)v;
        } else
            return fprintf(stderr, "mpmdem_footing: unknown option %s (see --help)\n", a), 2;
        ++i;
    }
    if (o.dem_dt < 0) o.dem_dt = FT_DEM_DT_REF * sqrt(6e8 / o.young);
    if (f.nx < 1 || f.ny < 1 || f.nx > 4000 || f.ny > 4000 || !(f.width > 0) || !(f.depth > 0) ||
        !(f.B > 0) || !(f.foot_height > 0) || !(f.surcharge > 0) || !(f.velocity > 0) || !(f.ramp >= 0) ||
        !(f.final_dB > 0 && f.final_dB <= 3) || !(f.every > 0 && f.every <= f.final_dB) || !(f.smooth > 0) ||
        !(f.phi_strain >= 0.01 && f.phi_strain <= FT_PHI_STRAIN_MAX) ||
        !(f.grid_damping >= 0 && f.grid_damping < 1) || mpd_check_opts(&o))
        return fprintf(stderr, "mpmdem_footing: an option is out of range (see --help)\n"), 2;
    h = f.width / f.nx;
    /* the footing covers the nodes x <= b - h/2; their tributary width (the
     * reach of a uniform stress under them) ends half a cell further: that is
     * the effective half-width, = b when b/h = k + 1/2 */
    bnode = floor((0.5 * f.B - 0.5 * h) / h + 1e-9) * h;
    b = bnode + 0.5 * h;
    if (fabs(f.depth / f.ny - h) > 1e-9 * h)
        return fprintf(stderr, "mpmdem_footing: cells must be square: width/nx = %g, depth/ny = %g\n", h,
                       f.depth / f.ny),
               2;
    if (bnode < h * (1 - 1e-9) || b > 0.5 * f.width)
        return fprintf(
                   stderr,
                   "mpmdem_footing: the half footing B/2 = %g m must span at least 1.5 cells (h = %g m) and "
                   "at most half the width\n",
                   0.5 * f.B, h),
               2;
    if (f.final_dB * f.B >= 0.9 * f.depth)
        return fprintf(stderr, "mpmdem_footing: --final %g: the footing would reach the base\n", f.final_dB),
               2;
    if (mpd_mkdir(o.out)) return 1;
    /* from here on every exit goes through `done`, which frees what exists */
    memset(&P, 0, sizeof P), memset(&F, 0, sizeof F), memset(&g, 0, sizeof g), memset(&pts, 0, sizeof pts);
    gk_rve_state_init(&st0, NULL);
    memset(T, 0, sizeof T);
#define FAIL(msg)                                     \
    do {                                              \
        fprintf(stderr, "mpmdem_footing: %s\n", msg); \
        status = 1;                                   \
        goto done;                                    \
    } while (0)

    /* ---- the RVE: open the packing, measure phi, prepare at q_s */
    if (mpd_proto_open(&P, &o, &err)) FAIL(err.msg);
    printf("mpmdem_footing: seed 003 Table 2 '%s': E = %g MPa, kt/kn = %g, friction %g deg, beta %g, eta %g, "
           "damping %g; DEM dt = %.3g s\n",
           material_names[f.material], o.young / 1e6, o.kt_ratio, o.friction_deg, o.roll_beta, o.roll_eta,
           o.dem_damping, o.dem_dt);
    if (f.material == 1 && !strcmp(o.packing, od.packing))
        printf(
            "note: 'medium' has Table 2's dense contact law; with the shipped dense packing it is the dense "
            "soil (give a looser --packing for e0 = 0.2314, e.g. examples/data/rve400_e0223.txt)\n");
    if (f.phi_deg > 0) {
        phi = f.phi_deg;
        printf("friction angle: phi = %g deg given (--phi-deg), no measurement\n", phi);
    } else {
        int k, nbad = 0;
        double t0 = gk_wtime();
        printf(
            "friction angle: %d drained biaxial RVE tests (sigma_3 held by the servo; axial compression at "
            "%s) ...\n",
            f.nphi,
            o.dem_adaptive ? "the inertial number of --dem-inertial at sigma_3"
                           : "--dem-strain per DEM step");
        fflush(stdout);
        for (k = 0; k < f.nphi; ++k) T[k].s3 = f.phi_p[k];
        GK_OMP(parallel for num_threads(o.threads) schedule(dynamic, 1) reduction(+ : nbad))
        for (k = 0; k < f.nphi; ++k) nbad += phi_test(&P, &o, f.phi_strain, &T[k]);
        for (k = 0; k < f.nphi; ++k) {
            if (T[k].status) {
                fprintf(stderr, "mpmdem_footing: RVE biaxial at sigma_3 = %g kPa: %s\n", T[k].s3 / 1e3,
                        T[k].msg);
                continue;
            }
            printf("  sigma_3 = %4.0f kPa (%.3g /s): e0 = %.4f, peak sigma_1 = %.1f kPa (sigma_3 %.1f) at "
                   "%.2f %% axial "
                   "strain -> phi = %.2f deg; residual (mean over %.1f-%.1f %%) %.2f deg\n",
                   T[k].s3 / 1e3, T[k].rate, T[k].e0, T[k].s1 / 1e3, T[k].s3m / 1e3, 100 * T[k].eps_peak,
                   T[k].phi, fmax(0.0, 100 * T[k].eps_end - 2), 100 * T[k].eps_end, T[k].phi_res);
            if (T[k].nopeak)
                printf("    (no peak by %.0f %% axial strain: the maximum is used, a hardening RVE)\n",
                       100 * FT_PHI_STRAIN_MAX);
        }
        if (nbad) {
            status = 1;
            goto done;
        }
        phi = phi_fit(T, f.nphi, 0, &phi_c, &coh);
        phi_res = phi_fit(T, f.nphi, 1, &phi_rc, &coh_r);
        measured = 1;
        printf("  Mohr-Coulomb envelope of the peaks through the origin: phi = %.2f deg", phi);
        if (f.nphi >= 2 && isfinite(phi_c))
            printf(" (with cohesion: phi = %.2f deg, c = %.2f kPa)", phi_c, coh / 1e3);
        printf("; seed 003 '%s': %.1f deg\n", material_names[f.material], seed_phi[f.material]);
        printf("  residual envelope (end of the tests): phi_res = %.2f deg; %.1f s for the tests\n", phi_res,
               gk_wtime() - t0);
        phi_plots(o.out, T, f.nphi, phi);
    }
    if (mpd_prepare_rve(&P, f.surcharge, &st0, &err)) FAIL(err.msg);
    c = sqrt(P.M / P.rho);
    dt = o.cfl * h / c;

    /* ---- grid: ghost layers; room above the ground for the heave */
    gl = mpd_ghost_layers(o.basis);
    {
        int up = gl + (int)ceil(fmax(f.final_dB * f.B, 2 * h) / h);
        org[0] = -gl * h, org[1] = -gl * h, org[2] = 0;
        n[0] = f.nx + 2 * gl + 1, n[1] = f.ny + gl + up + 1, n[2] = 1;
        if (gk_mpm_grid_create(&g, 2, org, h, n, NULL, &err) ||
            gk_mpm_grid_set_bc(&g, 0, GK_MPM_BC_ROLLER, 0, gl + 1, &err) || /* symmetry plane x = 0 */
            gk_mpm_grid_set_bc(&g, 1, GK_MPM_BC_ROLLER, 0, gl + 1, &err) || /* smooth wall x = W */
            gk_mpm_grid_set_bc(&g, 2, GK_MPM_BC_FIXED, 0, gl + 1, &err))    /* base y = 0 */
            FAIL(err.msg);
    }
    lo[0] = 0, lo[1] = 0, lo[2] = 0, hi[0] = f.width, hi[1] = f.depth, hi[2] = 0;
    if (gk_mpm_points_create_box(&pts, 2, lo, hi, h, o.ppc, P.rho, NULL, &err)) FAIL(err.msg);
    rss_before = proc_kb("VmRSS");
    if (mpd_rves_create(&F, pts.n, &P, &st0, NULL, NULL, &o, &err)) FAIL(err.msg);
    rss_after = proc_kb("VmRSS");
    edge = (mpd_edge *)calloc((size_t)pts.n, sizeof *edge);
    x0 = (double *)malloc(2 * (size_t)pts.n * sizeof *x0);
    if (!edge || !x0) FAIL("out of memory");
    for (i = 0; i < pts.n; ++i) {
        double a = 0.5 * h / o.ppc, xl = pts.x[0][i] - a, xr = pts.x[0][i] + a;
        mpd_rve_sigma(&F.rve[i], pts.sigma + 9 * (size_t)i);
        x0[2 * i] = pts.x[0][i], x0[2 * i + 1] = pts.x[1][i];
        if (pts.x[1][i] < f.depth - 2 * a || xr <= b + 1e-9 * h) continue;
        if (xl < b) xl = b; /* the part of the top edge beyond the footing edge */
        edge[nedge].p = i, edge[nedge].pressure = f.surcharge;
        edge[nedge].off[0] = 0.5 * (xl + xr) - pts.x[0][i], edge[nedge].off[1] = a;
        edge[nedge].e[0] = -(xr - xl), edge[nedge].e[1] = 0; /* outward normal (e_y, -e_x) = up */
        ++nedge;
    }
    def = mpd_mpm_def(&o);
    def.damping = f.grid_damping;
    memset(&S, 0, sizeof S);
    S.body.lo[0] = org[0] - h, S.body.hi[0] = bnode + 1e-9 * h;
    S.body.lo[1] = f.depth - 1e-9 * h, S.body.hi[1] = f.depth + f.foot_height;
    S.body.contact = GK_MPM_CONTACT_STICK;
    S.next_out = 0.0; /* a row after the first step (d ~ 0) */
    if (o.restart) {
        void *blob[2];
        size_t size[2] = {sizeof S, 0};
        ft_row *rr = NULL;
        blob[0] = &S, blob[1] = &rr;
        if (mpd_ck_read(o.restart, "footing", blob, size, 2, &pts, &F, &err)) FAIL(err.msg);
        rows = rr, nrows = caprows = (int)(size[1] / sizeof *rows);
    }
    g.body = &S.body, g.nbody = 1;
    nsteps_total = (long)ceil((f.final_dB * f.B / f.velocity + 0.5 * f.ramp) / dt);
    if (f.max_steps && f.max_steps < nsteps_total) nsteps_total = f.max_steps;
    printf("grid: %d x %d cells over %g x %g m (half model), h = %.4g m; footing B = %g m, half-width b = %g "
           "m = "
           "%.3g cells (nodes x <= %.4g m), rough; surcharge %g kPa\n",
           f.nx, f.ny, f.width, f.depth, h, f.B, b, b / h, bnode, f.surcharge / 1e3);
    if (fabs(b - 0.5 * f.B) > 1e-6 * f.B)
        printf(
            "note: B/2 = %g m is not (k + 1/2) h: the footing's effective half-width is b = %g m (q = load / "
            "b); choose h = B / (2k + 1) for an exact footing\n",
            0.5 * f.B, b);
    printf("%d points (= RVEs of %d disks), basis %d, alpha %g, grid damping %g\n", pts.n, F.rve[0].n,
           (int)o.basis, o.alpha, f.grid_damping);
    printf("RVE at q_s: p0 = %.4g kPa, e0 = %.4f (Table 2: %.4f), rho = %.1f kg/m3, M (Taylor) = %.4g MPa -> "
           "c = "
           "%.1f m/s; MPM dt = %.4g s (cfl %.2f)\n",
           P.p0 / 1e3, P.e0, table2_e0[f.material], P.rho, P.M / 1e6, c, dt, o.cfl);
    mpd_print_dem_rule(&o);
    printf("memory: %.1f kB per RVE (RSS growth over creating %d RVEs)\n",
           rss_after > 0 && rss_before > 0 ? (rss_after - rss_before) / pts.n : -1.0, pts.n);
    printf("footing at %g m/s (ramp %g s) to d/B = %g: about %ld MPM steps%s\n", f.velocity, f.ramp,
           f.final_dB, nsteps_total, f.max_steps ? " (--max-steps)" : "");
    fflush(stdout);
    if (!o.restart) {
        snprintf(path, sizeof path, "%s/points_%06ld.vtk", o.out, 0L);
        mpd_write_vtk(path, &F, &pts);
    }
    t_start = gk_wtime();
    step0 = S.step, dem0 = F.dem_steps;
    while (S.disp < f.final_dB * f.B * (1 - 1e-12) && !(f.max_steps && S.step - step0 >= f.max_steps)) {
        double vf = f.velocity * (f.ramp > 0 && S.t < f.ramp ? fmin(1.0, (S.t + 0.5 * dt) / f.ramp) : 1.0),
               ek, m, mom[3];
        S.body.v[1] = -vf;
        if (mpd_step(&g, &pts, &def, dt, &F, edge, nedge, &err)) { /* also moves the footing */
            fprintf(stderr, "mpmdem_footing: step %ld (d/B = %.4f): %s\n", S.step, S.disp / f.B, err.msg);
            status = 3;
            break;
        }
        S.t += dt, S.disp += vf * dt, ++S.step;
        if (S.step == 1) t_first = gk_wtime() - t_start, dem_first = F.dem_steps - dem0; /* fresh runs only */
        S.acc_load += -S.body.force[1] * dt, S.acc_dt += dt;
        gk_mpm_points_totals(&pts, &m, mom, &ek);
        S.acc_ek += ek, ++S.nacc;
        {
            long long sum = 0;
            for (i = 0; i < pts.n; ++i) sum += F.nsub[i];
            S.acc_dem += (double)sum / pts.n;
        }
        if (S.disp >= S.next_out * f.B * (1 - 1e-9) || S.disp >= f.final_dB * f.B * (1 - 1e-12) ||
            (f.max_steps && S.step - step0 >= f.max_steps)) {
            ft_row r;
            r.t = S.t, r.d = S.disp, r.load = S.acc_load / S.acc_dt, r.q = r.load / b;
            r.ek = S.acc_ek / S.nacc, r.dem_mean = S.acc_dem / S.nacc;
            r.secs = S.wall + gk_wtime() - t_start;
            S.acc_load = S.acc_dt = 0, S.acc_ek = S.acc_dem = 0, S.nacc = 0;
            while (S.next_out * f.B <= S.disp * (1 + 1e-9)) S.next_out += f.every;
            if (nrows == caprows) {
                caprows = caprows ? 2 * caprows : 64;
                ft_row *grown = (ft_row *)realloc(rows, (size_t)caprows * sizeof *rows);
                if (!grown) FAIL("out of memory");
                rows = grown;
            }
            rows[nrows++] = r;
            write_csv(o.out, rows, nrows, f.B, f.surcharge);
            while (S.nstage < FT_NSTAGE && stages[S.nstage] <= f.final_dB &&
                   r.d >= stages[S.nstage] * f.B * (1 - 1e-9)) {
                char tag[32], title[120];
                snprintf(tag, sizeof tag, "eps_q_dB%.2f", stages[S.nstage]);
                snprintf(title, sizeof title, "deviatoric strain eps_q at d/B = %.2f", stages[S.nstage]);
                stage_field(o.out, tag, title, &F, &pts, 0, 0.5 * h / o.ppc);
                ++S.nstage;
            }
            if (!o.quiet) {
                snprintf(what, sizeof what, "d/B %.4f  q %.1f kPa (q/q_s %.2f)  DEM %.1f/pt", r.d / f.B,
                         r.q / 1e3, r.q / f.surcharge, r.dem_mean);
                gk_progress(stderr, S.step - step0, nsteps_total - step0, t_start, what);
            }
        }
        if (o.vtk_every && S.step % o.vtk_every == 0) {
            snprintf(path, sizeof path, "%s/points_%06ld.vtk", o.out, S.step);
            mpd_write_vtk(path, &F, &pts);
        }
        if (o.checkpoint_every && S.step % o.checkpoint_every == 0) {
            void *blob[2];
            size_t size[2];
            double w0 = S.wall;
            S.wall += gk_wtime() - t_start;
            blob[0] = &S, size[0] = sizeof S, blob[1] = rows, size[1] = (size_t)nrows * sizeof *rows;
            mpd_ck_write(o.out, "footing", blob, size, 2, &pts, &F);
            S.wall = w0;
        }
    }
    {
        double secs = gk_wtime() - t_start, *x = NULL, *q = NULL, *qsm = NULL, nq = NAN, qu = NAN, du = NAN;
        double nq46 = nq_prandtl(phi), nq47 = nq_prandtl(phi_reduced(phi)), hwm, per_rve, ck_mb = 0;
        long steps_run = S.step - step0;
        long long dems = F.dem_steps - dem0;
        int excl = step0 == 0 && steps_run > 1; /* leave out the first step's one-off relaxation */
        double per_step_rve = steps_run ? (secs - (excl ? t_first : 0)) / (steps_run - excl) / pts.n : 0.0;
        double dem_after_first =
            steps_run ? (double)(dems - (excl ? dem_first : 0)) / (steps_run - excl) / pts.n : 0.0;
        int ku = -1, reached = 0, k;
        const char *mode = "not reached";
        void *blob[2];
        size_t size[2];
        double w0 = S.wall;
        S.wall += secs;
        blob[0] = &S, size[0] = sizeof S, blob[1] = rows, size[1] = (size_t)nrows * sizeof *rows;
        if (status == 0) mpd_ck_write(o.out, "footing", blob, size, 2, &pts, &F);
        S.wall = w0;
        for (k = 0; k < F.n; ++k) ck_mb += gk_rve_state_size(&F.rve[k]) / 1048576.0;
        write_csv(o.out, rows, nrows, f.B, f.surcharge);
        x = (double *)malloc((size_t)(nrows + 1) * sizeof *x);
        q = (double *)malloc((size_t)(nrows + 1) * sizeof *q);
        qsm = (double *)malloc((size_t)(nrows + 1) * sizeof *qsm);
        if (x && q && qsm && nrows > 0) {
            for (k = 0; k < nrows; ++k) x[k] = rows[k].d / f.B, q[k] = rows[k].q, qsm[k] = rows[k].q;
            ku = ultimate(x, q, nrows, f.smooth, qsm, &reached, &mode);
            qu = qsm[ku], du = x[ku], nq = qu / f.surcharge;
            load_plot(o.out, rows, nrows, qsm, f.B, f.surcharge, reached ? ku : -1, nq46, nq47, phi);
        }
        stage_field(o.out, "eps_q_end", "deviatoric strain eps_q at the end (failure mode, seed 003 Fig 14)",
                    &F, &pts, 0, 0.5 * h / o.ppc);
        stage_field(o.out, "rotation_end", "rotation of F = RU [deg] at the end (seed 003 Fig 15)", &F, &pts,
                    2, 0.5 * h / o.ppc);
        stage_field(o.out, "void_ratio_end", "void ratio at the end (seed 003 Fig 15)", &F, &pts, 5,
                    0.5 * h / o.ppc);
        displacement_field(o.out, &pts, x0, 0.5 * h / o.ppc);
        snprintf(path, sizeof path, "%s/points_%06ld.vtk", o.out, S.step);
        mpd_write_vtk(path, &F, &pts);
        printf("wrote %s/footing.csv, footing_load.svg, %seps_q_*.svg, rotation_end.svg, void_ratio_end.svg, "
               "displacement_end.svg, points_*.vtk (ParaView), checkpoint.bin\n",
               o.out, measured ? "rve_biaxial.svg, rve_mohr.svg, " : "");
        if (nrows > 0)
            printf("load-settlement: q(d/B = %.4f) = %.2f kPa (q_s = %g kPa); at the end d/B = %.4f: q = "
                   "%.1f kPa\n",
                   rows[0].d / f.B, rows[0].q / 1e3, f.surcharge / 1e3, rows[nrows - 1].d / f.B,
                   rows[nrows - 1].q / 1e3);
        if (reached)
            printf("ultimate load (%s, smoothing window d/B %g): p_u = %.1f kPa at d/B = %.4f -> N_q = "
                   "p_u/q_s = "
                   "%.2f\n",
                   mode, f.smooth, qu / 1e3, du, nq);
        else
            printf("ultimate load NOT reached by d/B = %.4f (no zero or steady minimum slope confirmed one "
                   "window "
                   "before the end): N_q below is the last smoothed value, a lower bound; run further "
                   "(--final)\n",
                   nrows ? rows[nrows - 1].d / f.B : 0.0);
        printf(
            "N_q: MPMxDEM %.2f; eq 46 (general shear, phi = %.2f deg) %.2f; eq 47 (local/punching, phi_r = "
            "%.2f deg) %.2f; ratio %.3f to eq 46\n",
            nq, phi, nq46, phi_reduced(phi), nq47, nq / nq46);
        if (isnan(phi_of_nq(nq)))
            printf(
                "no angle's eq 46 gives the MPMxDEM N_q %.3g (eq 46 spans %.3g at 0 deg to %.4g at 60 deg; "
                "RESULT phi_mobilised_deg=nan)\n",
                nq, nq_prandtl(0.0), nq_prandtl(60.0));
        else
            printf("the MPMxDEM N_q is eq 46 of phi = %.2f deg (the angle the footing mobilises)\n",
                   phi_of_nq(nq));
        if (measured)
            printf("N_q of eq 46 with the residual angle phi_res = %.2f deg (the softened end of the RVE "
                   "tests): "
                   "%.2f; MPMxDEM / that = %.3f\n",
                   phi_res, nq_prandtl(phi_res), nq / nq_prandtl(phi_res));
        printf("seed 003 '%s': N_q %.1f (MPMxDEM) vs %.1f (analytic, phi = %.1f deg)\n",
               material_names[f.material], seed_nq[f.material], seed_nq_analytic[f.material],
               seed_phi[f.material]);
        hwm = proc_kb("VmHWM");
        per_rve = rss_after > 0 && rss_before > 0 ? (rss_after - rss_before) / pts.n : NAN;
        printf("cost: %s for %ld MPM steps, %lld DEM steps over all RVEs (%.1f per point per MPM step); %.4g "
               "s per "
               "MPM step per 1000 RVEs (%.3g us per RVE DEM step)\n",
               mpd_duration(secs, buf, sizeof buf), steps_run, dems,
               steps_run ? (double)dems / steps_run / pts.n : 0.0,
               steps_run ? secs / steps_run * 1000.0 / pts.n : 0.0, dems ? 1e6 * secs / (double)dems : 0.0);
        printf("memory: VmHWM %.1f MB, %.1f kB per RVE (RSS growth on creation), checkpoint %.1f MB of RVE "
               "states\n",
               hwm / 1024, per_rve, ck_mb);
        {
            /* the paper's size: 7776 RVEs, h = 12/108, 0.1 m/s to d/B = 1.5 with a 0.5 s ramp; cost per
             * RVE per MPM step of this run without its first step (the one-off relaxation of every RVE) */
            double hp = 12.0 / 108.0, dtp = o.cfl * hp / c, stepsp = (1.5 * f.B / 0.1 + 0.25) / dtp;
            double base = hwm > 0 && isfinite(per_rve) ? hwm - per_rve * pts.n : NAN;
            double tp = per_step_rve * 7776.0 * stepsp;
            printf("paper size projection (7776 RVEs, h = %.4g m, dt = %.3g s, %.0f MPM steps at 0.1 m/s to "
                   "d/B = "
                   "1.5): memory ~ %.2f GB, checkpoint file %.2f GB; wall ~ %s on these cores at this run's "
                   "%.3g ms "
                   "per RVE per MPM step (first step excluded; %.1f DEM steps per RVE per MPM step here)\n",
                   hp, dtp, stepsp, (base + 7776.0 * per_rve) / 1048576.0, 7776.0 * ck_mb / pts.n / 1024.0,
                   mpd_duration(tp, buf, sizeof buf), 1e3 * per_step_rve, dem_after_first);
        }
        printf("RESULT Nq=%.5g Nq_analytic=%.5g Nq_analytic_local=%.5g phi_deg=%.4g phi_res_deg=%.4g "
               "Nq_analytic_res=%.5g phi_mobilised_deg=%.4g q_ult=%.6g d_ult_over_B=%.4g ultimate_reached=%d "
               "n_rves=%d "
               "mpm_steps=%ld dt=%.4g "
               "seconds_per_step=%.4g seconds_per_step_per_1000_rves=%.4g "
               "seconds_per_step_per_1000_rves_after_first=%.4g mem_per_rve_kb=%.4g vmhwm_mb=%.5g "
               "total_seconds=%.2f\n",
               nq, nq46, nq47, phi, phi_res, measured ? nq_prandtl(phi_res) : NAN, phi_of_nq(nq), qu, du,
               reached, pts.n, steps_run, dt, steps_run ? secs / steps_run : 0.0,
               steps_run ? secs / steps_run * 1000.0 / pts.n : 0.0, 1000.0 * per_step_rve, per_rve,
               hwm / 1024, secs);
        free(x), free(q), free(qsm);
    }
done : {
    int k;
    for (k = 0; k < FT_MAXPHI; ++k) free(T[k].eps), free(T[k].ratio);
}
#undef FAIL
    free(rows), free(edge), free(x0);
    mpd_rves_free(&F);
    gk_rve_state_free(&st0);
    mpd_proto_close(&P);
    gk_mpm_points_destroy(&pts);
    gk_mpm_grid_destroy(&g);
    return status;
}
