/* hybrid.c - hybrid continuum-grain simulation of shear bands: an MPM
 * continuum everywhere until an oracle finds the band, then grains in the
 * band (Chen, Chantharayukhonthorn, Yue, Grinspun & Kamrin 2021).
 *
 *   build/hybrid --test planar|biaxial --mode dem|continuum|hybrid [options]
 *
 * TESTS (2D; compression-positive stresses in every output)
 *   planar   planar shear (Sec 6.1, Table 3): a W x H specimen, periodic
 *            left-right, bottom fixed, a rough top platen moving sideways
 *            at --speed while a servo holds the normal stress --pressure.
 *            tau = platen shear force / W, strain = platen displacement / W
 *            (the paper's definitions), sigma_n = platen normal force / W,
 *            eps_v = (H - H0) / H0.
 *   biaxial  the 2D analogue of the triaxial test (Sec 6.2, Table 5): a
 *            W x H specimen, confined by --pressure through a membrane
 *            (grains: a chain of the outermost grains, pressure plus
 *            tension-only springs of 1e4 N/m, App. B; continuum: a follower
 *            traction on its outer points), bottom rough, top platen
 *            frictionless moving down at --speed. strain = axial strain,
 *            sigma_n = axial stress, tau = (sigma_n - pressure) / 2,
 *            eps_v = area / area0 - 1 (from the material's extent per row).
 * MODES
 *   dem        grains everywhere (the ground truth)
 *   continuum  MPM everywhere: Hencky-like hypoelastic Drucker-Prager with
 *              critical-state softening [eqs 4-8]; the oracle runs and
 *              reports, nothing is enriched
 *   hybrid     MPM until the oracle triggers (Alg. 1), then the region
 *              within --phi0 of the flagged nodes becomes grains from the
 *              same packing as dem mode, kinematically trained (Sec 4.1.1),
 *              coupled through a one-cell overlap (eq 9); gk_hybrid.h has
 *              the method.
 *
 * MATERIAL (Chen et al. Tables 1-2). Grains: disks, D50 = 1 mm, diameters
 * normal with sd 0.08 mm cut at 2 sd; linear contacts k_n = 1.772e6 N/m,
 * k_t = k_n / 2, mu = 0.5, dt = 5e-7 s. Normal dashpot gamma_n = 7 N s/m
 * (e = 0.1 for the mean grain: 83.5 % of critical). The paper's disks carry
 * its grain mass m = 1.98e-5 kg (what gamma_n = 7 and e = 0.1 imply) and
 * its stresses are per a thickness of one diameter (what App. F's
 * k_n/(P d) and the calibrated K = 630 MPa imply): here t = 1 mm and
 * density 25300 kg/m^3 (m = 1.98e-5 kg). Measured on the consolidated
 * packing at 400 kPa: K = 767 MPa, G = 417 MPa (the paper: 630, 460).
 * Tangential dashpot: 40 % of critical (the paper's gamma_t = 7 N s/m with
 * k_t = k_n/2 is 118 % of critical; with rotating disks at dt = 5e-7 s that
 * keeps a packing oscillating in grainkit's leap-frog, so it is reduced).
 * Packing: --grains disks generated in a periodic cell of the specimen's
 * aspect, consolidated to --pressure frictionless with light damping (the
 * paper pours with mu = 0.01), then mu = 0.5 and the paper's damping
 * (packing fraction ~0.85: the paper's 84-86 %). Written to
 * OUT/packing.txt; --packing reads one (the same specimen for every mode).
 * Continuum: K = 630 MPa, G = 460 MPa, phi_cs = 0.27 rad, Phi_cs = 0.815,
 * chi = 7, xi = 0.01, no cohesion, density = the packing's, initial stress
 * -pressure I, initial Phi = the packing's (over-consolidated) or --phi.
 * "Weak" points (Phi = Phi_cs, left out of the oracle) seed the band: the
 * middle row of cells (planar), one cell at the lower right (biaxial).
 * MPM: uGIMP, PIC fraction --alpha (0.05), 2 x 2 points per cell, USF,
 * the grain time step.
 *
 * ORACLE AND ENRICHMENT (gk_hybrid.h): every --oracle-every steps the
 * plastic strain rate and the plastic strain of the last tau_l go to the
 * nodes; Alg. 1 with --c0, --c1, --cl, --cg (Tables 4, 6). On the trigger
 * (hybrid mode) the packing's grains whose reference positions lie in the
 * discrete zone (by the continuum's reference configuration) are trained:
 * the overlap grains (and, biaxial, those on the specimen's surface and
 * the bottom layer) are moved by --train times the continuum displacement
 * at --train-speed, then held for a tenth of that time; the grains that end
 * in the continuum zone are dropped, the discrete points deleted, mass and
 * momentum matched.
 *
 * OUTPUT in --out DIR: hybrid.csv (time, strain, tau, sigma_n, eps_v,
 * eps_v_band, grains, points, enriched, flagged_nodes, seconds; stresses
 * in Pa compression-positive, eps_v positive in dilation, eps_v_band the
 * same inside the band window: a rectangle around the expected band, of
 * half-width --band-window, measured by mass), points_*.vtk and
 * grains_*.vtk (start, enrichment, window start, end), stress_strain.svg,
 * volume.svg, band.svg (the incremental shear strain over the band window
 * --window S0 S1 (strain), grains by Cundall's best fit, points by F),
 * packing.txt, and on stdout a line
 *   RESULT mode=M peak_tau=Pa band_thickness_D50=X strain_at_enrichment=S
 *          seconds=T speedup_vs_dem=R
 * (band thickness by App. A: top --percentile, outliers beyond 2 sd out,
 * minimum-area box; speedup_vs_dem = --dem-seconds / seconds, nan without).
 * On stdout, "cost:" counts the grain-steps and point-steps of the run (the
 * N_D and element terms of the cost model of Sec 6.4.1) with the wall time
 * spent in each.
 *
 * COST. The defaults are reduced (3 x 6 cm planar, 1778 grains; 3 x 4.71
 * cm biaxial, 1435 grains; 5x the paper's platen speed): one thread, about
 * 25 CPU s for dem and 35-75 CPU s for continuum or hybrid. --paper runs
 * the paper's sizes (Tables 3, 5: 7640 and 5910 grains at 0.02 m/s): about
 * 40x the grain-steps of the reduced runs (4 x the grains, 10 x the steps),
 * so some 40 x 23 CPU s = 15 CPU min for each dem run (estimated, not run
 * to the end).
 *
 * KNOWN LIMITS. The planar continuum and hybrid runs at the default size
 * stop at 43 % (continuum) and 49 % (hybrid) strain: a point of the top
 * layer leaves the grid ("its support leaves the grid"); run them to
 * --strain 0.3 --window 0.2 0.3. The continuum's cost per MPM point-step is far above
 * the paper's relative to a grain-step, so the hybrid is slower than dem at
 * these sizes (see the cost: line).
 */
#define GK_IMPLEMENTATION
#define _POSIX_C_SOURCE 200809L
#include "gk_hybrid.h"
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define T_PLANAR 0
#define T_BIAXIAL 1
#define M_DEM 0
#define M_CONT 1
#define M_HYBRID 2

static const char *test_name[] = {"planar", "biaxial"};
static const char *mode_name[] = {"dem", "continuum", "hybrid"};

/* ------------------------------------------------------------------ material */
#define DIAM 1e-3 /* D50 [m] */
#define THICK 1e-3      /* stress thickness: one diameter */
#define RHO_S 25300.0   /* grain mass 1.98e-5 kg for D = 1 mm, t = 1 mm */
#define KN 1.7720938e6  /* Table 1 */
#define DT 5e-7
#define PHI_CS 0.815    /* Table 2 */
#define K_C 6.3e8
#define G_C 4.6e8

typedef struct opts {
    int test, mode;
    const char *out, *packing;
    double width, height, pressure, speed, strain_end, out_every;
    double cell, alpha, train, train_speed, phi0, c0, c1, cl, cg, phi_init, weak_dphi, xi;
    double win0, win1, band_window, percentile, dem_seconds, platen_zeta, ramp;
    int ppd, threads, oracle_every, quiet;
    long grains;
    unsigned long seed;
} opts;

/* ------------------------------------------------------------------ options */
static void defaults(opts *o, int test) {
    memset(o, 0, sizeof *o);
    o->test = test;
    o->mode = M_HYBRID;
    o->out = "build/hybrid_out";
    o->width = 0.03;
    o->speed = 0.1;
    o->cell = 0.005;
    o->ppd = 2;
    o->alpha = 0.0;
    o->train = 1.0;
    o->percentile = 98.0;
    o->threads = 1;
    o->oracle_every = 20;
    o->seed = 1;
    o->platen_zeta = 0.05;
    o->ramp = 40.0;
    o->weak_dphi = 0.8425 - PHI_CS;
    o->xi = 0.01;
    o->dem_seconds = -1.0;
    if (test == T_PLANAR) { /* Tables 3-4 */
        o->height = 0.06;
        o->pressure = 4e5;
        o->strain_end = 0.57;
        o->out_every = 0.005;
        o->phi0 = 0.015; /* the paper: 0.022 for its 12 cm specimen */
        o->c0 = 1e-6;
        o->c1 = 1e-4;
        o->cl = 8e-4;
        o->cg = 1.2e-3;
        o->win0 = 0.37;
        o->win1 = 0.57;
        o->band_window = 0.011;
    } else { /* Tables 5-6 */
        o->height = 0.0471;
        o->pressure = 1e5;
        o->strain_end = 0.1061;
        o->out_every = 0.001;
        o->phi0 = 0.01;
        o->c0 = 1e-6;
        o->c1 = 8e-3;
        o->cl = 2e-2;
        o->cg = 9.6e-3;
        o->win0 = 0.055;
        o->win1 = 0.085;
        o->band_window = 0.005;
    }
}

static void usage(FILE *fp) {
    opts p, b;
    defaults(&p, T_PLANAR);
    defaults(&b, T_BIAXIAL);
    fprintf(fp,
            "usage: hybrid --test planar|biaxial --mode dem|continuum|hybrid [options]\n"
            "  --out DIR            output directory (default %s)\n"
            "  --threads T          OpenMP threads (default 1; results do not depend on it)\n"
            "  --width W --height H specimen [m] (planar %g x %g, biaxial %g x %g; paper 0.06 x 0.12, 0.06 x 0.0942)\n"
            "  --grains N           grains of the generated packing (0: from the size, packing fraction 0.85)\n"
            "  --packing FILE       read the packing (a periodic cell) instead of generating it\n"
            "  --seed S             packing generator seed (default %lu)\n"
            "  --pressure P         normal (planar) / confining (biaxial) stress [Pa] (default %g, %g)\n"
            "  --speed V            platen speed [m/s] (default %g; paper 0.02)\n"
            "  --strain S           run to this strain (default %g, %g)\n"
            "  --out-every S        CSV row every S of strain (default %g, %g)\n"
            "  --cell H             MPM cell [m] (default %g)\n"
            "  --ppd K              MPM points per cell edge (default %d)\n"
            "  --alpha A            MPM PIC fraction (default %g)\n"
            "  --phi0 D             enrichment margin phi_0 [m] (default %g, %g)\n"
            "  --c0 C --c1 C --cl C --cg C   oracle constants (defaults Tables 4 and 6)\n"
            "  --oracle-every N     oracle evaluated every N steps (default %d)\n"
            "  --train F            kinematic training fraction in [0, 1] (default %g; below 1: planar only)\n"
            "  --train-speed V      speed of the trained boundary [m/s] (default: --speed)\n"
            "  --phi PHI            initial continuum packing fraction (default: the packing's; below\n"
            "                       Phi_cs = 0.815 the continuum is under-consolidated)\n"
            "  --weak-dphi D        the weak points' packing fraction is the others' minus D (default %g)\n"
            "  --xi X               rate of eq 8's relaxation of Phi to Phi_cs (default %g, Table 2)\n"
            "  --window S0 S1       strain window of the band measurement (default %g %g, %g %g)\n"
            "  --band-window B      half-width of the eps_v_band window [m] (default %g, %g)\n"
            "  --percentile Q       band grains: value above the Q-th percentile (default %g)\n"
            "  --platen-damping Z   planar top platen: damping ratio of its dashpot (default %g)\n"
            "  --ramp K             the platen speed rises linearly over K wave transits H / c (default %g)\n"
            "  --dem-seconds S      wall seconds of the dem run of the same test (for speedup_vs_dem)\n"
            "  --paper              the paper's specimen and speed (Tables 3, 5): 6 x 12 cm (planar, phi_0 2.2 cm) or\n"
            "                       6 x 9.42 cm (biaxial), 0.02 m/s; the other flags override it\n"
            "  --quiet              no progress lines\n",
            p.out, p.width, p.height, b.width, b.height, p.seed, p.pressure, b.pressure, p.speed, p.strain_end,
            b.strain_end, p.out_every, b.out_every, p.cell, p.ppd, p.alpha, p.phi0, b.phi0, p.oracle_every,
            p.train, p.weak_dphi, p.xi, p.win0, p.win1, b.win0, b.win1, p.band_window, b.band_window, p.percentile, p.platen_zeta, p.ramp);
}

static int num(const char *s, double *v) {
    char *end;
    errno = 0;
    *v = strtod(s, &end);
    return end != s && *end == '\0' && errno == 0 && isfinite(*v);
}

/* strict parsing: every flag known, every value a number in range, errors name the flag */
static int parse(int argc, char **argv, opts *o) {
    int i, test = -1, mode = -1, have[64];
    double v;
    for (i = 1; i + 1 < argc; ++i) {
        if (!strcmp(argv[i], "--test")) {
            if (!strcmp(argv[i + 1], "planar"))
                test = T_PLANAR;
            else if (!strcmp(argv[i + 1], "biaxial"))
                test = T_BIAXIAL;
            else if (!strcmp(argv[i + 1], "indent"))
                return fprintf(stderr,
                               "error: --test indent: the plate indentation (Sec 6.3) is not implemented "
                               "(planar or biaxial)\n"),
                       1;
            else
                return fprintf(stderr, "error: --test %s: use planar or biaxial\n", argv[i + 1]), 1;
        }
    }
    if (test < 0) return fprintf(stderr, "error: --test planar|biaxial is required\n"), 1;
    defaults(o, test);
    for (i = 1; i < argc; ++i)
        if (!strcmp(argv[i], "--paper")) { /* Tables 3-6; the other flags override it */
            o->width = 0.06;
            o->height = test == T_PLANAR ? 0.12 : 0.0942;
            o->speed = 0.02;
            if (test == T_PLANAR) {
                o->phi0 = 0.022;
                o->band_window = 0.022;
            }
        }
    memset(have, 0, sizeof have);
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) return usage(stdout), 2;
        if (!strcmp(a, "--quiet")) {
            o->quiet = 1;
            continue;
        }
        if (!strcmp(a, "--paper")) continue;
        if (!val) return fprintf(stderr, "error: %s needs a value (or is unknown; see --help)\n", a), 1;
        ++i;
        if (!strcmp(a, "--test")) continue;
        if (!strcmp(a, "--mode")) {
            if (!strcmp(val, "dem"))
                mode = M_DEM;
            else if (!strcmp(val, "continuum"))
                mode = M_CONT;
            else if (!strcmp(val, "hybrid"))
                mode = M_HYBRID;
            else
                return fprintf(stderr, "error: --mode %s: use dem, continuum or hybrid\n", val), 1;
            continue;
        }
        if (!strcmp(a, "--out")) {
            o->out = val;
            continue;
        }
        if (!strcmp(a, "--packing")) {
            o->packing = val;
            continue;
        }
        if (!strcmp(a, "--window")) {
            double v2;
            if (i + 1 >= argc || !num(val, &v) || !num(argv[i + 1], &v2) || !(v >= 0.0 && v2 > v))
                return fprintf(stderr, "error: --window needs two strains S0 < S1\n"), 1;
            o->win0 = v;
            o->win1 = v2;
            ++i;
            continue;
        }
        if (!num(val, &v)) return fprintf(stderr, "error: %s %s: not a number\n", a, val), 1;
#define REAL(flag, field, ok, what)                                                      \
    if (!strcmp(a, flag)) {                                                              \
        if (!(ok)) return fprintf(stderr, "error: %s %s: need %s\n", a, val, what), 1;   \
        o->field = v;                                                                    \
        continue;                                                                        \
    }
#define INT(flag, field, lo, hi)                                                                        \
    if (!strcmp(a, flag)) {                                                                             \
        if (v != floor(v) || v < (lo) || v > (hi))                                                      \
            return fprintf(stderr, "error: %s %s: need an integer in [%g, %g]\n", a, val, (double)(lo), \
                           (double)(hi)),                                                               \
                   1;                                                                                   \
        o->field = v;                                                                                   \
        continue;                                                                                       \
    }
        REAL("--width", width, v >= 0.005 && v <= 10.0, "a width in [0.005, 10] m")
        REAL("--height", height, v >= 0.005 && v <= 10.0, "a height in [0.005, 10] m")
        REAL("--pressure", pressure, v > 0.0 && v <= 1e8, "a stress in (0, 1e8] Pa")
        REAL("--speed", speed, v > 0.0 && v <= 10.0, "a speed in (0, 10] m/s")
        REAL("--strain", strain_end, v > 0.0 && v <= 2.0, "a strain in (0, 2]")
        REAL("--out-every", out_every, v > 0.0, "a positive strain")
        REAL("--cell", cell, v > 0.0, "a positive cell size")
        REAL("--alpha", alpha, v >= 0.0 && v <= 1.0, "a value in [0, 1]")
        REAL("--train", train, v >= 0.0 && v <= 1.0, "a fraction in [0, 1]")
        REAL("--train-speed", train_speed, v > 0.0 && v <= 10.0, "a speed in (0, 10] m/s")
        REAL("--phi0", phi0, v > 0.0, "a positive distance")
        REAL("--c0", c0, v >= 0.0, "a value >= 0")
        REAL("--c1", c1, v >= 0.0, "a value >= 0")
        REAL("--cl", cl, v > 0.0, "a positive value")
        REAL("--cg", cg, v > 0.0, "a positive value")
        REAL("--phi", phi_init, v > 0.5 && v < 0.95, "a packing fraction in (0.5, 0.95)")
        REAL("--weak-dphi", weak_dphi, v >= 0.0 && v < 0.3, "a value in [0, 0.3)")
        REAL("--xi", xi, v >= 0.0 && v <= 1e3, "a value in [0, 1e3]")
        REAL("--band-window", band_window, v > 0.0, "a positive half-width")
        REAL("--percentile", percentile, v >= 50.0 && v < 100.0, "a percentile in [50, 100)")
        REAL("--platen-damping", platen_zeta, v >= 0.0 && v <= 10.0, "a value in [0, 10]")
        REAL("--ramp", ramp, v >= 0.0 && v <= 1e4, "a value in [0, 1e4]")
        REAL("--dem-seconds", dem_seconds, v > 0.0, "a positive time")
        INT("--threads", threads, 1, 256)
        INT("--grains", grains, 0, 5000000)
        INT("--ppd", ppd, 1, 4)
        INT("--oracle-every", oracle_every, 1, 1000000)
        INT("--seed", seed, 0, 4294967295.0)
#undef REAL
#undef INT
        return fprintf(stderr, "error: unknown option %s (see --help)\n", a), 1;
    }
    if (mode < 0) return fprintf(stderr, "error: --mode dem|continuum|hybrid is required\n"), 1;
    o->mode = mode;
    if (o->train_speed <= 0.0) o->train_speed = o->speed;
    if (o->win1 > o->strain_end + 1e-12)
        return fprintf(stderr, "error: --window end %g beyond --strain %g\n", o->win1, o->strain_end), 1;
    if (o->test == T_BIAXIAL && o->train < 1.0)
        return fprintf(stderr, "error: --train %g: below 1 only for the planar test (the band region moves)\n",
                       o->train),
               1;
    (void)have;
    return 0;
}

static gk_material grain_material(double zeta_n, double zeta_t) {
    gk_material m = gk_material_default();
    m.kn = KN;
    m.kt_ratio = 0.5;
    m.friction = 0.5;
    m.density = RHO_S;
    m.zeta_n = zeta_n;
    m.zeta_t = zeta_t;
    return m;
}
/* gamma_n = 7 N s/m for two mean grains: zeta = 7 / (2 sqrt(m/2 k_n)) */
static double zeta_paper(void) {
    double m = RHO_S * THICK * GK_PI * 0.25 * DIAM * DIAM;
    return 7.0 / (2.0 * sqrt(0.5 * m * KN));
}

/* ------------------------------------------------------------------ packing */
static int make_dir(const char *d) {
    char buf[1024];
    size_t k, n = strlen(d);
    struct stat st;
    if (n + 1 > sizeof buf) return fprintf(stderr, "error: --out %s: path too long\n", d), 1;
    memcpy(buf, d, n + 1);
    for (k = 1; k <= n; ++k)
        if (buf[k] == '/' || buf[k] == '\0') {
            char c = buf[k];
            buf[k] = '\0';
            if (mkdir(buf, 0755) && errno != EEXIST) return fprintf(stderr, "error: cannot create %s\n", buf), 1;
            buf[k] = c;
        }
    if (stat(d, &st) || !S_ISDIR(st.st_mode)) return fprintf(stderr, "error: --out %s: not a directory\n", d), 1;
    return 0;
}

/* the servo of gk_rve at fixed shape (the cell stays a rectangle, so the
 * specimen stays periodic) to the isotropic stress p with friction mu:
 * until every sigma_kk is within 0.2 % and the unbalanced force ratio is
 * below 1e-3 for three checks in a row */
static int consolidate(gk_rve *rve, double p, double mu) {
    gk_servo sv;
    long st, calm = 0;
    int k, q;
    memset(&sv, 0, sizeof sv);
    for (k = 0; k < 2; ++k) {
        sv.mode[k] = GK_SERVO_STRESS;
        sv.target[k] = -p;
    }
    sv.max_rate = 1e-2 * sqrt(p / RHO_S) / DIAM; /* inertial number 1e-2 */
    sv.gain = 0.5;
    if (gk_rve_set_friction(rve, mu) || gk_rve_set_servo(rve, &sv))
        return fprintf(stderr, "error: consolidation: %s\n", gk_rve_error(rve)), 1;
    for (st = 0; st < 4000000; st += 1000) {
        double fs = 0.0, un, e0, e1;
        if (gk_rve_step(rve, 1000)) return fprintf(stderr, "error: consolidation: %s\n", gk_rve_error(rve)), 1;
        for (q = 0; q < rve->n; ++q) fs += sqrt((double)rve->f[0][q] * rve->f[0][q] + (double)rve->f[1][q] * rve->f[1][q]);
        un = rve->fc_mean > 0.0 ? fs / rve->n / rve->fc_mean : 1.0;
        e0 = fabs(rve->stress[0] + p) / p;
        e1 = fabs(rve->stress[4] + p) / p;
        calm = (e0 < 2e-3 && e1 < 2e-3 && un < 1e-3) ? calm + 1 : 0;
        if (calm >= 3) break;
    }
    gk_rve_set_servo(rve, NULL);
    if (calm < 3) return fprintf(stderr, "error: consolidation to %g Pa (mu %g) did not settle\n", p, mu), 1;
    /* friction is switched on with zero tangential history */
    for (q = 0; rve->ft[0] && q < rve->pl.n; ++q) rve->ft[0][q] = 0;
    return 0;
}

/* the specimen: generated (or read), consolidated to the pressure with the paper's contact law */
static int make_packing(const opts *o, gk_packing *out, double *phi) {
    gk_packing pk;
    gk_err e;
    gk_rve rve;
    gk_rve_def d = gk_rve_def_default();
    double tr[41], tc[41], s[9];
    int k;
    if (o->packing) {
        if (gk_packing_read(o->packing, out, NULL, &e)) return fprintf(stderr, "error: %s\n", e.msg), 1;
        if (out->dim != 2) return fprintf(stderr, "error: %s is not a 2D packing\n", o->packing), 1;
    } else {
        gk_gen_def g;
        double amean = GK_PI * 0.25 * DIAM * DIAM * (1.0 + 0.08 * 0.08);
        for (k = 0; k < 41; ++k) { /* diameters normal (1 mm, 0.08 mm) cut at 2 sd, by number */
            double z = -2.0 + 4.0 * k / 40.0;
            tr[k] = 0.5 * (DIAM + 8e-5 * z);
            tc[k] = 0.5 * (1.0 + erf(z / sqrt(2.0)));
        }
        for (k = 40; k >= 0; --k) tc[k] = (tc[k] - tc[0]) / (tc[40] - tc[0]);
        tc[40] = 1.0;
        memset(&g, 0, sizeof g);
        g.dim = 2;
        g.n = o->grains > 0 ? (int)o->grains : (int)floor(0.85 * o->width * o->height / amean + 0.5);
        g.psd = GK_PSD_TABLE_NUMBER;
        g.ntable = 41;
        g.table_r = tr;
        g.table_cum = tc;
        g.aspect[0] = 1.0;
        g.aspect[1] = o->height / o->width;
        g.seed = o->seed;
        if (gk_packing_generate(&pk, &g, NULL, &e)) return fprintf(stderr, "error: packing: %s\n", e.msg), 1;
        d.mat = grain_material(0.2, 0.0); /* light damping while consolidating (see the header) */
        d.thickness = THICK;
        d.dt = DT;
        d.damping = 0.2;
        d.threads = o->threads;
        if (gk_rve_create(&rve, &d, &pk)) return fprintf(stderr, "error: packing: %s\n", gk_rve_error(&rve)), 1;
        gk_packing_free(&pk);
        if (consolidate(&rve, o->pressure, 0.0) || consolidate(&rve, o->pressure, 0.5)) {
            gk_rve_destroy(&rve);
            return 1;
        }
        gk_rve_stress(&rve, s);
        if (!o->quiet)
            printf("packing: %d grains consolidated to %.4g, %.4g Pa in a %.4g x %.4g m cell\n", rve.n, -s[0], -s[4],
                   rve.cell.h[0], rve.cell.h[4]);
        if (gk_rve_to_packing(&rve, out, NULL, &e)) return fprintf(stderr, "error: %s\n", e.msg), 1;
        gk_rve_destroy(&rve);
    }
    *phi = 0.0;
    for (k = 0; k < out->n; ++k) *phi += GK_PI * out->r[k] * out->r[k];
    *phi /= out->h[0] * out->h[4];
    {
        char path[1100];
        snprintf(path, sizeof path, "%s/packing.txt", o->out);
        if (gk_packing_write(path, out, "hybrid.c specimen", &e))
            return fprintf(stderr, "error: cannot write %s\n", path), 1;
    }
    /* positions into [0, W) x [0, H) */
    for (k = 0; k < out->n; ++k) {
        out->x[k] -= out->h[0] * floor(out->x[k] / out->h[0]);
        out->y[k] -= out->h[4] * floor(out->y[k] / out->h[4]);
    }
    return 0;
}

/* ------------------------------------------------------------------ the run */
typedef struct run {
    opts o;
    double W, H, phi_pack, rho, M, c, t, strain, dt;
    long step;
    gk_packing pk; /* the specimen's reference packing, positions in [0, W) x [0, H) */
    /* grains */
    gk_scene sc;
    int have_sc, top_wall;
    unsigned char *role; /* by stable id: 0 free, 1 bottom layer, 2 top layer */
    int nrole;
    /* platen: top displacement and velocity */
    double plate_x, plate_y, plate_vy, y_plate0;
    double tau, sig_n; /* last measured, compression-positive [Pa] */
    /* continuum */
    int have_mpm;
    gk_mpm_grid g;
    gk_hybrid_periodic per;
    gk_mpm_points P;
    gk_hybrid_cont C;
    gk_mpm_def md;
    gk_mpm_body body;
    double h, dxp, dyp;
    double *side; /* per point: -1 left column, +1 right column, 0 (biaxial traction) */
    double *Fw;   /* per point: F at the window start (9) */
    unsigned char *bcmask;
    /* oracle */
    gk_hybrid_oracle orc;
    gk_hybrid_history hist;
    double *past, *pval, *nnum, *nden, *nrate, *nrec, t_push;
    unsigned char *active;
    int triggered;
    double strain_trigger;
    /* hybrid */
    int enriched;
    double strain_enrich, *dist, *xpre[2];
    unsigned char *coupled;
    int cap_g, mask_n;
    double grain_scale; /* the enrichment's grain mass factor */
    gk_hybrid_coupling cpl;
    /* measurements */
    double phi0_band, A0, peak_tau, win_c[2], win_e[2], win_a;
    int window_taken, nw, band_on_grains;
    double *Xw[2];
    int32_t *idw;
    FILE *csv;
    double t_start, next_out;
    /* cost counters */
    double sec_dem, sec_mpm, sec_cpl;
    long steps_dem, grain_steps, point_steps;
} run;

static double wtime(void) { return gk_wtime(); }

static gk_scene_def scene_def(const run *R) {
    gk_scene_def d = gk_scene_def_default();
    d.dim = 2;
    if (R->o.test == T_PLANAR) {
        d.periodic = 1u;
        d.lo[0] = 0.0;
        d.hi[0] = R->W;
    } else {
        d.lo[0] = -0.5 * R->W;
        d.hi[0] = 1.5 * R->W;
    }
    d.lo[1] = -0.5 * R->H;
    d.hi[1] = 1.5 * R->H;
    d.rve.mat = grain_material(zeta_paper(), 0.4);
    d.rve.thickness = THICK;
    d.rve.dt = DT;
    d.rve.damping = 0.0;
    d.rve.threads = R->o.threads;
    return d;
}

/* the grains' role by stable id, from their reference positions */
static int role_of(const run *R, double y) {
    if (y < 1.5 * DIAM) return 1;
    if (y > R->H - 1.5 * DIAM) return 2;
    return 0;
}

/* The planar top platen under a constant normal stress: a rigid platen of
 * the specimen's mass M_p pressed by p W t, its vertical velocity from
 * M_p dv/dt = F - p W t - c v (F the specimen's push on it; c = 2 zeta
 * sqrt(k M_p), k = (K + G) W t / H, zeta = --platen-damping), the same
 * law for the grains and the continuum. A dilating specimen lifts it with
 * a force error c v (1-3 % of p W t at the dilation rates of these tests). */
static double platen_velocity(run *R, double F, double dt) {
    double A = R->W * THICK, Mp = R->rho * R->W * R->H * THICK, k = R->M * A / R->H;
    double c = 2.0 * R->o.platen_zeta * sqrt(k * Mp);
    R->plate_vy += dt * (F - R->o.pressure * A - c * R->plate_vy) / Mp;
    return R->plate_vy;
}

/* the platen speed at time t: a linear rise over --ramp wave transits (a
 * sudden start sends a stress wave rho c_s V through the specimen) */
static double platen_speed(const run *R, double t) {
    double tr = R->o.ramp * R->H / R->c;
    return t >= tr ? R->o.speed : R->o.speed * t / tr;
}

/* ---- membranes on the grains at the specimen's sides (biaxial) */
/* On each side, the outermost free grain of every band of D50 along y whose
 * outer edge lies within 1.5 D50 of the side (left[row], right[row]
 * for rows of row_h), chained in height order (the material on the chain's
 * left: down the left side, up the right side), split where a gap of 3 D50
 * opens; a chain end within 2 D50 of the top wall is tied to it. */
static int add_membranes(run *R, const double *left, const double *right, int nrow, double row_h) {
    gk_scene *sc = &R->sc;
    int n = sc->rve.n, s, p, k, nb = (int)ceil(2.0 * R->H / DIAM) + 1, nsel;
    int32_t *ids = (int32_t *)malloc((size_t)n * sizeof(int32_t));
    int *best = (int *)malloc((size_t)nb * sizeof(int)), *ord = (int *)malloc((size_t)nb * sizeof(int));
    double *bx = (double *)malloc((size_t)nb * sizeof(double)), *yy = (double *)malloc((size_t)nb * sizeof(double));
    double ytop = R->top_wall >= 0 ? sc->walls[R->top_wall].pos[1] : HUGE_VAL;
    if (!ids || !best || !ord || !bx || !yy) return fprintf(stderr, "error: out of memory\n"), 1;
    for (s = -1; s <= 1; s += 2) {
        for (k = 0; k < nb; ++k) best[k] = -1;
        for (p = 0; p < n; ++p) {
            double x[3], r = (double)sc->rve.r[p], edge;
            int row, band;
            if (sc->flags[p] & GK_PARTICLE_PRESCRIBED) continue;
            gk_scene_position(sc, p, x);
            row = (int)floor(x[1] / row_h);
            band = (int)floor(x[1] / DIAM);
            if (row < 0 || row >= nrow || band < 0 || band >= nb) continue;
            edge = s < 0 ? left[row] : right[row];
            if (!isfinite(edge)) continue;
            if (s < 0 ? x[0] - r < edge + 1.5 * DIAM : x[0] + r > edge - 1.5 * DIAM) {
                double out = s < 0 ? -(x[0] - r) : x[0] + r;
                if (best[band] < 0 || out > bx[band]) {
                    best[band] = p;
                    bx[band] = out;
                }
            }
        }
        nsel = 0;
        for (k = 0; k < nb; ++k) {
            int kk = s < 0 ? nb - 1 - k : k; /* left: top to bottom; right: bottom to top */
            if (best[kk] >= 0) {
                double x[3];
                gk_scene_position(sc, best[kk], x);
                ord[nsel] = best[kk];
                yy[nsel++] = x[1];
            }
        }
        for (p = 0; p < nsel;) {
            int q = p + 1, m, a0 = -1, a1 = -1;
            while (q < nsel && fabs(yy[q] - yy[q - 1]) < 3.0 * DIAM) ++q;
            m = q - p;
            if (m >= 2) {
                for (k = 0; k < m; ++k) ids[k] = sc->rve.id[ord[p + k]];
                if (s < 0 && ytop - yy[p] < 2.0 * DIAM) a0 = R->top_wall;
                if (s > 0 && ytop - yy[q - 1] < 2.0 * DIAM) a1 = R->top_wall;
                if (gk_scene_add_membrane(sc, m, ids, R->o.pressure, 1e4, a0, a1, NULL))
                    return fprintf(stderr, "error: membrane: %s\n", gk_scene_error(sc)), 1;
            }
            p = q;
        }
    }
    free(ids);
    free(best);
    free(ord);
    free(bx);
    free(yy);
    return 0;
}

/* the material's extent per row (grains: x -+ r; points: x -+ half their size) */
static void extent_rows(const run *R, int nrow, double row_h, double *left, double *right) {
    int k, p;
    for (k = 0; k < nrow; ++k) {
        left[k] = HUGE_VAL;
        right[k] = -HUGE_VAL;
    }
    if (R->have_sc)
        for (p = 0; p < R->sc.rve.n; ++p) {
            double x[3], r = (double)R->sc.rve.r[p];
            gk_scene_position(&R->sc, p, x);
            k = (int)floor(x[1] / row_h);
            if (k < 0 || k >= nrow) continue;
            if (x[0] - r < left[k]) left[k] = x[0] - r;
            if (x[0] + r > right[k]) right[k] = x[0] + r;
        }
    if (R->have_mpm)
        for (p = 0; p < R->P.n; ++p) {
            double x = R->P.x[0][p], half = 0.5 * R->dxp * sqrt(R->P.vol[p] / R->P.vol0[p]);
            k = (int)floor(R->P.x[1][p] / row_h);
            if (k < 0 || k >= nrow) continue;
            if (x - half < left[k]) left[k] = x - half;
            if (x + half > right[k]) right[k] = x + half;
        }
}

static double specimen_height(const run *R) { return R->H + R->plate_y; }

/* rows for the specimen's extent: one MPM cell (two rows of points, a few grains) */
static int extent_nrow(const run *R) {
    int n = (int)floor(R->H / R->o.cell);
    return n > 1 ? n : 1;
}

/* biaxial: area from the material's extent per row */
static double specimen_area(const run *R) {
    int nrow = extent_nrow(R), k;
    double Hc = specimen_height(R), row_h = Hc / nrow, A = 0.0, *l, *r;
    l = (double *)malloc((size_t)nrow * sizeof(double));
    r = (double *)malloc((size_t)nrow * sizeof(double));
    if (!l || !r) {
        free(l);
        free(r);
        return NAN;
    }
    extent_rows(R, nrow, row_h, l, r);
    for (k = 0; k < nrow; ++k)
        if (r[k] > l[k]) A += (r[k] - l[k]) * row_h;
    free(l);
    free(r);
    return A;
}

/* overlap of [x - d/2, x + d/2] with [-b, b], as a fraction of d */
static double overlap1(double x, double d, double b) {
    double lo = x - 0.5 * d, hi = x + 0.5 * d, a = lo > -b ? lo : -b, c = hi < b ? hi : b;
    return c > a ? (c - a) / d : 0.0;
}

/* solid fraction inside the band window: grains by their disk area (an
 * overlap grain, which carries w of its mass, by w of it), points by
 * their solid area vol0 Phi0 (overlap points carry 1 - w of it); each
 * counted by its overlap with the window (grains as squares of their
 * area, points as their cell) */
static double band_solid_fraction(const run *R) {
    double S = 0.0, area, b = R->o.band_window, phi0 = R->o.phi_init > 0.0 ? R->o.phi_init : R->phi_pack;
    int p, planar = R->o.test == T_PLANAR;
    area = planar ? R->W * 2.0 * b : 2.0 * R->win_a * 2.0 * b;
#define WIN_ADD(x, y, d, a)                                                                        \
    do {                                                                                           \
        double u = ((x)-R->win_c[0]) * R->win_e[0] + ((y)-R->win_c[1]) * R->win_e[1];              \
        double w = -((x)-R->win_c[0]) * R->win_e[1] + ((y)-R->win_c[1]) * R->win_e[0];             \
        S += (a)*overlap1(w, (d), b) * (planar ? 1.0 : overlap1(u, (d), R->win_a));                \
    } while (0)
    if (R->have_sc)
        for (p = 0; p < R->sc.rve.n; ++p) {
            double x[3], r = (double)R->sc.rve.r[p], a = GK_PI * r * r;
            if (R->sc.flags[p] & GK_PARTICLE_PRESCRIBED) continue;
            if (R->enriched) a *= R->sc.mass[p] / (R->grain_scale * RHO_S * THICK * a); /* 1 or w */
            gk_scene_position(&R->sc, p, x);
            WIN_ADD(x[0], x[1], sqrt(GK_PI) * r, a);
        }
    if (R->have_mpm)
        for (p = 0; p < R->P.n; ++p) WIN_ADD(R->P.x[0][p], R->P.x[1][p], sqrt(R->P.vol[p]), R->P.vol0[p] * phi0);
#undef WIN_ADD
    return S / area;
}

/* ------------------------------------------------------------------ grains */
/* the all-grain specimen: the packing with its top and bottom layers as
 * platens (planar: rough, prescribed grains) or bottom layer and a
 * frictionless wall (biaxial), membranes on the sides (biaxial) */
static int setup_dem(run *R) {
    gk_scene_def d = scene_def(R);
    gk_scene *sc = &R->sc;
    int p, n;
    double z[3] = {0.0, 0.0, 0.0};
    if (gk_scene_create(sc, &d, &R->pk)) return fprintf(stderr, "error: scene: %s\n", gk_scene_error(sc)), 1;
    R->have_sc = 1;
    n = sc->rve.n;
    for (p = 0; p < n; ++p) {
        double x[3];
        int role;
        gk_scene_position(sc, p, x);
        role = role_of(R, x[1]);
        R->role[sc->rve.id[p]] = (unsigned char)role;
        if (role == 1 || (role == 2 && R->o.test == T_PLANAR)) {
            double v[3] = {0.0, 0.0, 0.0};
            if (role == 2) v[0] = platen_speed(R, 0.0);
            if (gk_scene_prescribe(sc, p, v, z)) return fprintf(stderr, "error: %s\n", gk_scene_error(sc)), 1;
        }
    }
    if (R->o.test == T_BIAXIAL) {
        gk_wall_def w = gk_wall_def_default();
        double ytop = -HUGE_VAL;
        int nrow = (int)floor(R->H / (2.0 * DIAM)), k;
        double *l = (double *)malloc((size_t)nrow * sizeof(double)), *r = (double *)malloc((size_t)nrow * sizeof(double));
        for (p = 0; p < n; ++p) {
            double x[3];
            gk_scene_position(sc, p, x);
            if (x[1] + (double)sc->rve.r[p] > ytop) ytop = x[1] + (double)sc->rve.r[p];
        }
        w.kind = GK_WALL_PLANE;
        w.point[1] = ytop;
        w.normal[1] = -1.0;
        w.mat = grain_material(zeta_paper(), 0.4);
        w.mat.friction = 0.0;
        w.drive = GK_DRIVE_VELOCITY;
        if (gk_scene_add_wall(sc, &w, &R->top_wall)) return fprintf(stderr, "error: %s\n", gk_scene_error(sc)), 1;
        R->y_plate0 = ytop;
        if (!l || !r) return fprintf(stderr, "error: out of memory\n"), 1;
        for (k = 0; k < nrow; ++k) { /* the packing's sides */
            l[k] = 0.0;
            r[k] = R->W;
        }
        if (add_membranes(R, l, r, nrow, R->H / nrow)) return 1;
        free(l);
        free(r);
        /* preload: the cut-open top reloaded to the confining pressure by the wall's servo */
        sc->walls[R->top_wall].def.drive = GK_DRIVE_STRESS;
        sc->walls[R->top_wall].def.target = R->o.pressure;
        sc->walls[R->top_wall].def.area = R->W * THICK;
        sc->walls[R->top_wall].def.gain = 0.05;
        sc->walls[R->top_wall].def.max_speed = R->o.speed;
        for (k = 0; k < 200; ++k) {
            double s;
            if (gk_scene_step(sc, 500)) return fprintf(stderr, "error: preload: %s\n", gk_scene_error(sc)), 1;
            s = sc->walls[R->top_wall].force[1] / (R->W * THICK);
            if (k >= 10 && fabs(s - R->o.pressure) < 0.01 * R->o.pressure) break;
        }
        sc->walls[R->top_wall].def.drive = GK_DRIVE_VELOCITY;
        sc->walls[R->top_wall].def.velocity[1] = -platen_speed(R, 0.0);
        R->y_plate0 = sc->walls[R->top_wall].pos[1];
        sc->rve.time = 0.0;
    }
    return 0;
}

/* the platen loads of the grains (compression-positive, per the specimen width) */
static void dem_measure(run *R) {
    gk_scene *sc = &R->sc;
    if (R->o.test == T_PLANAR) {
        double fx = 0.0, fy = 0.0;
        int p;
        for (p = 0; p < sc->rve.n; ++p)
            if (R->role[sc->rve.id[p]] == 2) {
                fx += sc->load[0][p];
                fy += sc->load[1][p];
            }
        R->tau = -fx / (R->W * THICK);
        R->sig_n = fy / (R->W * THICK);
    }
}

/* K steps of the all-grain specimen */
static int dem_steps(run *R, long K) {
    gk_scene *sc = &R->sc;
    double t0 = wtime(), V = platen_speed(R, R->t);
    int p;
    if (R->o.test == T_PLANAR) {
        double z[3] = {0.0, 0.0, 0.0}, v[3];
        v[0] = V;
        v[1] = R->plate_vy;
        v[2] = 0.0;
        for (p = 0; p < sc->rve.n; ++p)
            if (R->role[sc->rve.id[p]] == 2) gk_scene_prescribe(sc, p, v, z);
    } else {
        sc->walls[R->top_wall].def.velocity[1] = -V;
    }
    if (gk_scene_step(sc, K)) return fprintf(stderr, "error: DEM: %s\n", gk_scene_error(sc)), 1;
    R->sec_dem += wtime() - t0;
    R->grain_steps += (long)sc->rve.n * K;
    R->t += K * R->dt;
    R->step += K;
    if (R->o.test == T_PLANAR) {
        R->plate_x += V * K * R->dt;
        R->plate_y += R->plate_vy * K * R->dt;
        dem_measure(R);
        platen_velocity(R, R->sig_n * R->W * THICK, K * R->dt);
        R->strain = R->plate_x / R->W;
    } else {
        double A = specimen_area(R);
        R->plate_y = sc->walls[R->top_wall].pos[1] - R->y_plate0;
        R->sig_n = sc->walls[R->top_wall].force[1] / THICK / (A / specimen_height(R));
        R->tau = 0.5 * (R->sig_n - R->o.pressure);
        R->strain = -R->plate_y / R->H;
    }
    return 0;
}

/* ------------------------------------------------------------------ continuum */
static int setup_mpm(run *R) {
    const opts *o = &R->o;
    gk_mpm_dp dp;
    gk_err e;
    double org[3] = {0.0, 0.0, 0.0}, Phi0;
    int n[3] = {1, 1, 1}, ncx = (int)floor(R->W / o->cell + 0.5), nxp, nyp, i, j, p, margin;
    if (ncx < 3) return fprintf(stderr, "error: --cell %g: fewer than 3 cells across %g m\n", o->cell, R->W), 1;
    R->h = R->W / ncx;
    if (R->dt > 0.3 * R->h / R->c)
        return fprintf(stderr, "error: the MPM step %g s is above 0.3 h / c = %g s\n", R->dt, 0.3 * R->h / R->c), 1;
    margin = o->test == T_PLANAR ? 1 : 3;
    org[0] = -margin * R->h;
    org[1] = -R->h;
    n[0] = ncx + 2 * margin + (o->test == T_PLANAR ? 1 : 1);
    n[1] = (int)ceil(R->H / R->h) + 5;
    if (gk_mpm_grid_create(&R->g, 2, org, R->h, n, NULL, &e)) return fprintf(stderr, "error: grid: %s\n", e.msg), 1;
    memset(&R->per, 0, sizeof R->per);
    if (o->test == T_PLANAR) {
        R->per.ghost[0] = 1;
        R->per.period[0] = ncx;
    }
    R->md = gk_mpm_def_default();
    R->md.basis = GK_MPM_UGIMP;
    R->md.alpha = o->alpha;
    R->md.threads = o->threads;
    if (gk_hybrid_periodic_check(&R->g, &R->per, R->md.basis, &e)) return fprintf(stderr, "error: %s\n", e.msg), 1;
    gk_mpm_grid_set_bc(&R->g, 2, GK_MPM_BC_FIXED, 0.0, 2, &e); /* bottom: no slip */
    /* points: ppd per cell edge on the cells' lattice (a point row that straddled
     * a cell boundary would tie a band to its neighbours); the continuum's
     * height is the whole number of cells nearest the packing's (its top
     * surface on a node row, where the platen acts) */
    nxp = ncx * o->ppd;
    nyp = (int)floor(R->H / R->h + 0.5) * o->ppd;
    R->dxp = R->dyp = R->h / o->ppd;
    if (gk_mpm_points_create(&R->P, 2, nxp * nyp, NULL, &e)) return fprintf(stderr, "error: %s\n", e.msg), 1;
    R->side = (double *)calloc((size_t)nxp * nyp, sizeof(double));
    R->Fw = (double *)calloc(9 * (size_t)nxp * nyp, sizeof(double));
    if (!R->side || !R->Fw) return fprintf(stderr, "error: out of memory\n"), 1;
    for (j = 0, p = 0; j < nyp; ++j)
        for (i = 0; i < nxp; ++i, ++p) {
            R->P.x[0][p] = (i + 0.5) * R->dxp;
            R->P.x[1][p] = (j + 0.5) * R->dyp;
            R->P.vol0[p] = R->P.vol[p] = R->dxp * R->dyp;
            R->P.m[p] = R->rho * R->dxp * R->dyp;
            R->P.lp[p] = 0.5 * (R->dxp < R->dyp ? R->dxp : R->dyp);
            R->P.sigma[9 * p] = R->P.sigma[9 * p + 4] = -o->pressure;
            if (o->test == T_BIAXIAL) R->side[p] = i == 0 ? -1.0 : (i == nxp - 1 ? 1.0 : 0.0);
        }
    if (gk_mpm_dp_init(&dp, 2, K_C, G_C, 0.27, 0.0, 0.0, &e)) return fprintf(stderr, "error: %s\n", e.msg), 1;
    dp.tan_phi_cs = tan(0.27);
    dp.Phi_cs = PHI_CS;
    dp.chi = 7.0;
    dp.xi = o->xi;
    Phi0 = o->phi_init > 0.0 ? o->phi_init : R->phi_pack;
    if (gk_hybrid_cont_init(&R->C, &R->P, &dp, Phi0, NULL, &e)) return fprintf(stderr, "error: %s\n", e.msg), 1;
    /* the weak points that seed the band */
    for (p = 0; p < R->P.n; ++p) {
        double x = R->P.x[0][p], y = R->P.x[1][p];
        /* a whole cell row (planar) or cell (biaxial): a band of weak points that
         * shares its cells with strong ones could not slip alone */
        int weak = o->test == T_PLANAR ? (int)floor(y / R->h) == (int)floor(0.5 * R->H / R->h)
                                       : (x > R->W - 2.0 * R->h && x < R->W - R->h && y > R->h && y < 2.0 * R->h);
        if (weak) R->C.Phi[p] = Phi0 - o->weak_dphi;
    }
    /* the top platen: rough and servo-controlled (planar) or frictionless (biaxial) */
    memset(&R->body, 0, sizeof R->body);
    R->body.lo[0] = org[0] - R->h;
    R->body.hi[0] = org[0] + (n[0] + 1) * R->h;
    R->body.lo[1] = R->H - 1e-9; /* the nodes at and above the material's top surface */
    R->body.hi[1] = org[1] + (n[1] + 1) * R->h;
    if (o->test == T_PLANAR) {
        R->body.contact = GK_MPM_CONTACT_STICK;
        R->body.v[0] = o->speed;
    } else {
        R->body.contact = GK_MPM_CONTACT_SMOOTH;
        R->body.face = 3; /* its y- face: normal -y into the material */
        R->body.v[1] = -o->speed;
    }
    R->g.body = &R->body;
    R->g.nbody = 1;
    R->have_mpm = 1;
    R->bcmask = (unsigned char *)malloc(R->g.nnode);
    if (!R->bcmask) return fprintf(stderr, "error: out of memory\n"), 1;
    return 0;
}

/* biaxial: the confining pressure as a follower traction on the outer columns
 * of continuum points (overlap and discrete points: the grains' membrane) */
static void mpm_traction(run *R) {
    int p, k;
    for (k = 0; k < 2; ++k) memset(R->P.fext[k], 0, (size_t)R->P.n * sizeof(double));
    if (R->o.test != T_BIAXIAL) return;
    for (p = 0; p < R->P.n; ++p)
        if (R->side[p] != 0.0 && R->C.zone[p] == GK_ZONE_CONTINUUM) {
            double N0[2] = {R->side[p], 0.0};
            gk_hybrid_traction(&R->P, p, N0, R->dyp, R->o.pressure);
        }
}

static int mpm_predict(run *R) {
    gk_err e;
    double t0 = wtime();
    if (R->o.test == T_PLANAR) {
        R->body.v[0] = platen_speed(R, R->t);
        R->body.v[1] = R->plate_vy;
    } else {
        R->body.v[1] = -platen_speed(R, R->t);
    }
    if (R->have_sc && R->top_wall >= 0) R->sc.walls[R->top_wall].def.velocity[1] = R->body.v[1];
    mpm_traction(R);
    if (gk_hybrid_mpm_predict(&R->g, &R->per, &R->P, &R->md, R->dt, gk_hybrid_dp_stress, &R->C, &e))
        return fprintf(stderr, "error: MPM at t = %g s: %s\n", R->t, e.msg), 1;
    R->sec_mpm += wtime() - t0;
    return 0;
}

static int mpm_finish(run *R) {
    gk_err e;
    double t0 = wtime();
    if (gk_hybrid_mpm_finish(&R->g, &R->per, &R->P, &R->C, &R->md, R->dt, &e))
        return fprintf(stderr, "error: MPM at t = %g s: %s\n", R->t, e.msg), 1;
    R->sec_mpm += wtime() - t0;
    R->point_steps += R->P.n;
    return 0;
}

/* platen loads after a continuum step (plus the grains' wall in a hybrid biaxial test) */
static void mpm_measure(run *R) {
    double W = R->W;
    if (R->o.test == T_PLANAR) {
        R->plate_x += R->body.v[0] * R->dt;
        R->plate_y += R->body.v[1] * R->dt;
        R->tau = R->body.force[0] / W;
        R->sig_n = -R->body.force[1] / W;
        platen_velocity(R, R->sig_n * R->W * THICK, R->dt);
        R->strain = R->plate_x / R->W;
    } else {
        double F = -R->body.force[1];
        R->plate_y += R->body.v[1] * R->dt;
        if (R->have_sc && R->top_wall >= 0) F += R->sc.walls[R->top_wall].force[1] / THICK;
        W = specimen_area(R) / specimen_height(R);
        R->sig_n = F / W;
        R->tau = 0.5 * (R->sig_n - R->o.pressure);
        R->strain = -R->plate_y / R->H;
    }
}

/* ------------------------------------------------------------------ oracle */
static int oracle_setup(run *R) {
    gk_hybrid_oracle_def d;
    gk_err e;
    size_t nn = R->g.nnode;
    int n = R->P.n;
    d.c0 = R->o.c0;
    d.c1 = R->o.c1;
    d.cl = R->o.cl;
    d.cg = R->o.cg;
    d.D50 = DIAM;
    if (gk_hybrid_oracle_init(&R->orc, &d, nn, NULL, &e) || gk_hybrid_history_init(&R->hist, n, 3, 512, NULL, &e))
        return fprintf(stderr, "error: %s\n", e.msg), 1;
    R->past = (double *)malloc(3 * (size_t)n * sizeof(double));
    R->pval = (double *)malloc(2 * (size_t)n * sizeof(double));
    R->nnum = (double *)malloc(2 * nn * sizeof(double));
    R->nden = (double *)malloc(nn * sizeof(double));
    R->nrate = (double *)malloc(nn * sizeof(double));
    R->nrec = (double *)malloc(nn * sizeof(double));
    R->active = (unsigned char *)malloc(nn);
    if (!R->past || !R->pval || !R->nnum || !R->nden || !R->nrate || !R->nrec || !R->active)
        return fprintf(stderr, "error: out of memory\n"), 1;
    R->t_push = -HUGE_VAL;
    return 0;
}

/* Alg. 1 at time t: returns 1 on the trigger */
static int oracle_eval(run *R) {
    gk_err e;
    double gd = R->C.gdot_max, tau_l, tau_g, *xs[3];
    size_t I, nn = R->g.nnode;
    int p, n = R->P.n;
    if (!(gd > 0.0)) return 0;
    tau_l = R->o.cl / gd;
    tau_g = R->o.cg / gd;
    if (R->t - R->t_push >= tau_l / 256.0) {
        if (gk_hybrid_history_push(&R->hist, R->t, R->C.ep, &e)) return fprintf(stderr, "error: %s\n", e.msg), -1;
        R->t_push = R->t;
    }
    gk_hybrid_history_at(&R->hist, R->t - tau_l, R->past);
    for (p = 0; p < n; ++p) {
        double a = R->C.ep[3 * p] - R->past[3 * p], b = R->C.ep[3 * p + 1] - R->past[3 * p + 1],
               c = R->C.ep[3 * p + 2] - R->past[3 * p + 2];
        R->pval[2 * p] = R->C.rate[p];
        R->pval[2 * p + 1] = sqrt(a * a + b * b + 2.0 * c * c);
    }
    xs[0] = R->P.x[0];
    xs[1] = R->P.x[1];
    xs[2] = NULL;
    if (gk_hybrid_rasterize(&R->g, &R->per, R->md.basis, R->P.lp[0], n, (const double *const *)xs, R->P.m, R->pval, 2,
                            NULL, R->nnum, R->nden, &e))
        return fprintf(stderr, "error: oracle: %s\n", e.msg), -1;
    gk_hybrid_bc_mask(&R->g, R->bcmask);
    for (I = 0; I < nn; ++I) {
        R->active[I] = R->nden[I] > 0.0 && !R->bcmask[I];
        R->nrate[I] = R->nden[I] > 0.0 ? R->nnum[I] / R->nden[I] : 0.0;
        R->nrec[I] = R->nden[I] > 0.0 ? R->nnum[nn + I] / R->nden[I] : 0.0;
    }
    return gk_hybrid_oracle_step(&R->orc, &R->g, &R->per, R->nrate, R->nrec, R->active, R->t, tau_g);
}

/* ------------------------------------------------------------------ enrichment */
/* grain p of the hybrid scene: in the overlap and free (coupled this step)? */
static void coupling_mask(run *R) {
    gk_scene *sc = &R->sc;
    int p;
    for (p = 0; p < sc->rve.n; ++p) {
        double x[3], d;
        R->coupled[p] = 0;
        if (sc->flags[p] & GK_PARTICLE_PRESCRIBED) continue;
        gk_scene_position(sc, p, x);
        if (!gk_hybrid_interp(&R->g, &R->per, R->dist, 1, R->nden, x, &d)) continue;
        R->coupled[p] = gk_hybrid_zone(d, R->o.phi0, R->h) == GK_ZONE_OVERLAP;
    }
}

static int grow_grain_arrays(run *R, int n) {
    if (n <= R->cap_g) return 0;
    free(R->xpre[0]);
    free(R->xpre[1]);
    free(R->coupled);
    R->xpre[0] = (double *)malloc((size_t)n * sizeof(double));
    R->xpre[1] = (double *)malloc((size_t)n * sizeof(double));
    R->coupled = (unsigned char *)malloc((size_t)n);
    if (!R->xpre[0] || !R->xpre[1] || !R->coupled) return fprintf(stderr, "error: out of memory\n"), 1;
    R->cap_g = n;
    return 0;
}

/* Sec 4: zones from the flagged nodes, the reference packing's grains of the
 * discrete zone trained (Sec 4.1.1), the swap (gk_hybrid_enrich) */
static int enrich(run *R) {
    const opts *o = &R->o;
    gk_mpm_grid *g = &R->g;
    gk_err e;
    size_t I, nn = g->nnode;
    int p, k, n = R->P.n, ng, nsel = 0, ndrop = 0, nb = 0, status = 1;
    double *num = NULL, *val = NULL, *X0w[3] = {NULL, NULL, NULL}, *xs[3], umax = 0.0, *u[2] = {NULL, NULL},
           *vg[2] = {NULL, NULL};
    unsigned char *bnd = NULL, *gz = NULL;
    int32_t *drop = NULL;
    gk_packing sub;
    gk_scene_def sd = scene_def(R);
    gk_hybrid_enrich_report rep;
    long ntrain, nrelax;
    double t0 = wtime();
    memset(&sub, 0, sizeof sub);
    /* the distance to the flagged nodes on every node, zones of the points */
    R->dist = (double *)malloc(nn * sizeof(double));
    num = (double *)malloc(4 * nn * sizeof(double));
    val = (double *)malloc(4 * (size_t)n * sizeof(double));
    X0w[0] = (double *)malloc((size_t)n * sizeof(double));
    X0w[1] = (double *)malloc((size_t)n * sizeof(double));
    X0w[2] = NULL;
    if (!R->dist || !num || !val || !X0w[0] || !X0w[1]) {
        fprintf(stderr, "error: out of memory\n");
        goto done;
    }
    {
        double ylo = HUGE_VAL, yhi = -HUGE_VAL;
        for (I = 0; I < nn; ++I) {
            double x[3];
            gk_mpm_grid_node_position(g, I, x);
            R->dist[I] = gk_hybrid_distance(g, &R->per, R->orc.flag, x);
            if (R->orc.flag[I]) {
                if (x[1] < ylo) ylo = x[1];
                if (x[1] > yhi) yhi = x[1];
            }
        }
        if (!o->quiet) printf("flagged nodes between y = %.4g and %.4g m\n", ylo, yhi);
    }
    for (p = 0; p < n; ++p) {
        double x[3] = {R->P.x[0][p], R->P.x[1][p], 0.0};
        R->C.zone[p] =
            (unsigned char)gk_hybrid_zone(gk_hybrid_distance(g, &R->per, R->orc.flag, x), o->phi0, R->h);
    }
    /* the continuum's reference configuration on the nodes: displacement and zone fractions */
    for (p = 0; p < n; ++p) {
        val[4 * p] = R->P.x[0][p] - R->C.X0[0][p];
        val[4 * p + 1] = R->P.x[1][p] - R->C.X0[1][p];
        val[4 * p + 2] = R->C.zone[p] == GK_ZONE_DISCRETE;
        val[4 * p + 3] = R->C.zone[p] == GK_ZONE_OVERLAP;
        X0w[0][p] = R->C.X0[0][p];
        X0w[1][p] = R->C.X0[1][p];
        if (o->test == T_PLANAR) X0w[0][p] -= R->W * floor(X0w[0][p] / R->W);
    }
    if (gk_hybrid_rasterize(g, &R->per, R->md.basis, R->P.lp[0], n, (const double *const *)X0w, R->P.m, val,
                            4, NULL, num, R->nden, &e)) {
        fprintf(stderr, "error: enrichment: %s\n", e.msg);
        goto done;
    }
    for (k = 0; k < 4; ++k)
        for (I = 0; I < nn; ++I)
            num[(size_t)k * nn + I] = R->nden[I] > 0.0 ? num[(size_t)k * nn + I] / R->nden[I] : 0.0;
    /* the reference packing's grains that go to the discrete zone */
    if (gk_packing_alloc(&sub, 2, R->pk.n, NULL, &e)) {
        fprintf(stderr, "error: %s\n", e.msg);
        goto done;
    }
    sub.h[0] = R->pk.h[0];
    sub.h[4] = R->pk.h[4];
    u[0] = (double *)malloc((size_t)R->pk.n * sizeof(double));
    u[1] = (double *)malloc((size_t)R->pk.n * sizeof(double));
    bnd = (unsigned char *)malloc((size_t)R->pk.n);
    if (!u[0] || !u[1] || !bnd) {
        fprintf(stderr, "error: out of memory\n");
        goto done;
    }
    for (k = 0; k < R->pk.n; ++k) {
        double X[3] = {R->pk.x[k], R->pk.y[k], 0.0}, f[4];
        int surface;
        if (!gk_hybrid_interp(g, &R->per, num, 4, R->nden, X, f)) continue;
        if (f[2] + f[3] < 0.5) continue;
        surface =
            o->test == T_BIAXIAL && (X[0] < 1.5 * DIAM || X[0] > R->W - 1.5 * DIAM || role_of(R, X[1]) != 0);
        sub.x[nsel] = X[0];
        sub.y[nsel] = X[1];
        sub.r[nsel] = R->pk.r[k];
        u[0][nsel] = o->train * f[0];
        u[1][nsel] = o->train * f[1];
        bnd[nsel] = f[3] >= f[2] || surface;
        if (bnd[nsel] && fabs(u[0][nsel]) > umax) umax = fabs(u[0][nsel]);
        if (bnd[nsel] && fabs(u[1][nsel]) > umax) umax = fabs(u[1][nsel]);
        nb += bnd[nsel];
        ++nsel;
    }
    if (nsel < 10) {
        fprintf(stderr, "error: enrichment: only %d grains in the discrete zone\n", nsel);
        goto done;
    }
    sub.n = nsel;
    /* the training scene (the hybrid's scene from now on) */
    if (gk_scene_create(&R->sc, &sd, &sub)) {
        fprintf(stderr, "error: scene: %s\n", gk_scene_error(&R->sc));
        goto done;
    }
    R->have_sc = 1;
    ng = R->sc.rve.n;
    {
        /* the scene stores the grains in its own order: id = index in sub */
        double *ua[2];
        int bad;
        unsigned char *bm = (unsigned char *)malloc((size_t)ng);
        ua[0] = (double *)malloc((size_t)ng * sizeof(double));
        ua[1] = (double *)malloc((size_t)ng * sizeof(double));
        if (!bm || !ua[0] || !ua[1]) {
            fprintf(stderr, "error: out of memory\n");
            free(bm), free(ua[0]), free(ua[1]);
            goto done;
        }
        for (p = 0; p < ng; ++p) {
            int q = R->sc.rve.id[p];
            bm[p] = bnd[q];
            ua[0][p] = u[0][q];
            ua[1][p] = u[1][q];
            R->role[q] = (unsigned char)role_of(R, sub.y[q]);
        }
        ntrain = (long)ceil(umax / (o->train_speed * R->dt));
        if (ntrain < 1000) ntrain = 1000;
        nrelax = ntrain / 10 > 500 ? ntrain / 10 : 500;
        if (!o->quiet)
            printf("enrichment at strain %.4g: %d flagged nodes, %d grains (%d on the trained boundary), "
                   "training "
                   "%ld + %ld steps (largest boundary displacement %.3g mm)\n",
                   R->strain, R->orc.nflag, ng, nb, ntrain, nrelax, 1e3 * umax);
        bad = gk_hybrid_train(&R->sc, bm, (const double *const *)ua, ntrain, nrelax, &e) != GK_OK;
        free(bm);
        free(ua[0]);
        free(ua[1]);
        if (bad) {
            fprintf(stderr, "error: %s\n", e.msg);
            goto done;
        }
        R->grain_steps += (long)ng * (ntrain + nrelax);
    }
    /* the grains that ended in the continuum zone leave */
    drop = (int32_t *)malloc((size_t)ng * sizeof(int32_t));
    if (!drop) {
        fprintf(stderr, "error: out of memory\n");
        goto done;
    }
    for (p = 0; p < ng; ++p) {
        double x[3];
        gk_scene_position(&R->sc, p, x);
        if (gk_hybrid_zone(gk_hybrid_distance(g, &R->per, R->orc.flag, x), o->phi0, R->h) ==
            GK_ZONE_CONTINUUM)
            drop[ndrop++] = R->sc.rve.id[p];
    }
    if (ndrop && gk_scene_remove(&R->sc, ndrop, drop)) {
        fprintf(stderr, "error: %s\n", gk_scene_error(&R->sc));
        goto done;
    }
    ng = R->sc.rve.n;
    /* the continuum's velocity at the grains; their zones */
    gz = (unsigned char *)malloc((size_t)ng);
    vg[0] = (double *)malloc((size_t)ng * sizeof(double));
    vg[1] = (double *)malloc((size_t)ng * sizeof(double));
    if (!gz || !vg[0] || !vg[1]) {
        fprintf(stderr, "error: out of memory\n");
        goto done;
    }
    for (p = 0; p < n; ++p) {
        val[2 * p] = R->P.v[0][p];
        val[2 * p + 1] = R->P.v[1][p];
    }
    xs[0] = R->P.x[0];
    xs[1] = R->P.x[1];
    xs[2] = NULL;
    if (gk_hybrid_rasterize(g, &R->per, R->md.basis, R->P.lp[0], n, (const double *const *)xs, R->P.m, val, 2,
                            NULL, num, R->nden, &e)) {
        fprintf(stderr, "error: enrichment: %s\n", e.msg);
        goto done;
    }
    for (k = 0; k < 2; ++k)
        for (I = 0; I < nn; ++I)
            num[(size_t)k * nn + I] = R->nden[I] > 0.0 ? num[(size_t)k * nn + I] / R->nden[I] : 0.0;
    for (p = 0; p < ng; ++p) {
        double x[3], v[2] = {0.0, 0.0};
        gk_scene_position(&R->sc, p, x);
        gk_hybrid_interp(g, &R->per, num, 2, R->nden, x, v);
        vg[0][p] = v[0];
        vg[1][p] = v[1];
        gz[p] = (unsigned char)gk_hybrid_zone(gk_hybrid_distance(g, &R->per, R->orc.flag, x), o->phi0, R->h);
    }
    {
        double *extra[2];
        int stride[2] = {1, 9};
        extra[0] = R->side;
        extra[1] = R->Fw;
        if (gk_hybrid_enrich(&R->P, &R->C, &R->sc, gz, (const double *const *)vg, 0.5, THICK, 2, extra,
                             stride, &rep, &e)) {
            fprintf(stderr, "error: %s\n", e.msg);
            goto done;
        }
        R->grain_scale = rep.mass_scale;
    }
    if (!o->quiet)
        printf("swap: %d points deleted, %d in the overlap; %d grains (%d in the overlap, %d left the zone); "
               "mass "
               "%.6g -> %.6g kg/m (grain mass x %.4f)\n",
               rep.points_deleted, rep.points_overlap, ng, rep.grains_overlap, ndrop, rep.mass_before,
               rep.mass_after, rep.mass_scale);
    /* the boundary of the grains: platen layers, top wall, membranes */
    for (p = 0; p < ng; ++p) {
        int role = R->role[R->sc.rve.id[p]];
        double z[3] = {0.0, 0.0, 0.0};
        if (role && o->test == T_PLANAR) {
            fprintf(stderr,
                    "error: the discrete zone reaches a platen (--phi0 %g m too large for a %g m specimen)\n",
                    o->phi0, R->H);
            goto done;
        }
        if (role == 1 && gk_scene_prescribe(&R->sc, p, z, z)) {
            fprintf(stderr, "error: %s\n", gk_scene_error(&R->sc));
            goto done;
        }
    }
    if (o->test == T_BIAXIAL) {
        int nrow = extent_nrow(R);
        double row_h = specimen_height(R) / nrow, ytop = R->H + R->plate_y, *l, *r, gmax = -HUGE_VAL;
        for (p = 0; p < ng; ++p) {
            double x[3];
            gk_scene_position(&R->sc, p, x);
            if (x[1] + (double)R->sc.rve.r[p] > gmax) gmax = x[1] + (double)R->sc.rve.r[p];
        }
        if (ytop - gmax < 2.0 * DIAM) { /* grains near the platen: the frictionless wall, moving with it */
            gk_wall_def w = gk_wall_def_default();
            w.kind = GK_WALL_PLANE;
            w.point[1] = gmax > ytop ? gmax : ytop;
            w.normal[1] = -1.0;
            w.mat = grain_material(zeta_paper(), 0.4);
            w.mat.friction = 0.0;
            w.drive = GK_DRIVE_VELOCITY;
            w.velocity[1] = R->body.v[1];
            if (gk_scene_add_wall(&R->sc, &w, &R->top_wall)) {
        fprintf(stderr, "error: %s\n", gk_scene_error(&R->sc));
        goto done;
    }
        }
        /* the specimen's sides at enrichment: the extent of the continuum's outer points per row */
        l = (double *)malloc((size_t)nrow * sizeof(double));
        r = (double *)malloc((size_t)nrow * sizeof(double));
        if (!l || !r) {
        fprintf(stderr, "error: out of memory\n");
        goto done;
    }
        extent_rows(R, nrow, row_h, l, r);
        if (add_membranes(R, l, r, nrow, row_h)) {
            free(l), free(r);
            goto done;
        }
        free(l);
        free(r);
    }
    /* the coupling */
    if (gk_hybrid_coupling_init(&R->cpl, g, NULL, &e)) {
        fprintf(stderr, "error: %s\n", e.msg);
        goto done;
    }
    for (I = 0; I < nn; ++I) R->nden[I] = 1.0; /* every node carries a distance */
    if (grow_grain_arrays(R, ng)) goto done;
    R->enriched = 1;
    R->strain_enrich = R->strain;
    gk_hybrid_history_free(&R->hist);
    status = 0;
done: /* every exit: the scratch freed */
    gk_packing_free(&sub);
    free(num);
    free(val);
    free(X0w[0]);
    free(X0w[1]);
    free(u[0]);
    free(u[1]);
    free(bnd);
    free(gz);
    free(vg[0]);
    free(vg[1]);
    free(drop);
    R->sec_dem += wtime() - t0;
    return status;
}

/* one step of the hybrid: continuum to vn, grains one step, coupling, continuum G2P */
static int hybrid_step(run *R) {
    gk_scene *sc = &R->sc;
    gk_err e;
    gk_hybrid_couple_report rep;
    int p, ng = sc->rve.n;
    double t0;
    if (grow_grain_arrays(R, ng)) return 1;
    for (p = 0; p < ng; ++p) {
        double x[3];
        gk_scene_position(sc, p, x);
        R->xpre[0][p] = x[0];
        R->xpre[1][p] = x[1];
    }
    /* which grains lie in the overlap: every 20 steps (a grain moves < 1e-3 D50 per step) */
    if (R->step % 20 == 0 || R->mask_n != ng) {
        coupling_mask(R);
        R->mask_n = ng;
    }
    if (mpm_predict(R)) return 1;
    t0 = wtime();
    if (gk_scene_step(sc, 1)) return fprintf(stderr, "error: DEM at t = %g s: %s\n", R->t, gk_scene_error(sc)), 1;
    R->sec_dem += wtime() - t0;
    R->grain_steps += ng;
    t0 = wtime();
    gk_hybrid_bc_mask(&R->g, R->bcmask);
    if (gk_hybrid_couple(&R->cpl, &R->g, &R->per, R->md.basis, R->P.lp[0], sc, (const double *const *)R->xpre,
                         R->coupled, R->bcmask, THICK, R->dt, &rep, &e))
        return fprintf(stderr, "error: coupling at t = %g s: %s\n", R->t, e.msg), 1;
    R->sec_cpl += wtime() - t0;
    return mpm_finish(R);
}

/* one step of the continuum (continuum and hybrid modes), with the oracle */
static int continuum_step(run *R) {
    if (R->enriched) {
        if (hybrid_step(R)) return 1;
    } else {
        if (mpm_predict(R) || mpm_finish(R)) return 1;
    }
    R->t += R->dt;
    ++R->step;
    mpm_measure(R);
    if (!R->enriched && R->step % R->o.oracle_every == 0) {
        int trig = oracle_eval(R);
        if (trig < 0) return 1;
        if (trig && !R->triggered) {
            R->triggered = 1;
            R->strain_trigger = R->strain;
            if (!R->o.quiet) printf("oracle: %d nodes flagged and unchanged for tau_g at strain %.4g\n", R->orc.nflag, R->strain);
        }
        if (trig && R->o.mode == M_HYBRID && enrich(R)) return 1;
    }
    return 0;
}

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
        double *xyz = (double *)malloc(3 * (size_t)n * sizeof(double)), *f = (double *)malloc(3 * (size_t)n * sizeof(double));
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
             !gk_vtk_cells(&v, n, 1, conn, GK_VTK_VERTEX) && !gk_vtk_point_scalar(&v, "packing_fraction", f) &&
             !gk_vtk_point_scalar(&v, "plastic_strain", f + n) && !gk_vtk_point_scalar(&v, "zone", f + 2 * n) &&
             !gk_vtk_point_tensor(&v, "stress", R->P.sigma) && !gk_vtk_close(&v);
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
    double ev, evb = R->phi0_band / band_solid_fraction(R) - 1.0;
    if (R->o.test == T_PLANAR)
        ev = R->plate_y / R->H;
    else
        ev = specimen_area(R) / R->A0 - 1.0;
    if (fprintf(R->csv, "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%d,%d,%d,%d,%.3f\n", R->t, R->strain, R->tau, R->sig_n, ev, evb,
                grains, points, R->enriched, R->enriched ? 0 : R->orc.nflag, wtime() - R->t_start) < 0)
        return fprintf(stderr, "error: cannot write %s/hybrid.csv\n", R->o.out), 1;
    if (R->tau > R->peak_tau) R->peak_tau = R->tau;
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
    h->tau[h->n] = 1e-3 * R->tau;
    h->sn[h->n] = 1e-3 * R->sig_n;
    h->ev[h->n] = 100.0 * ev;
    h->evb[h->n] = 100.0 * evb;
    ++h->n;
    if (!R->o.quiet)
        printf("t %.4f s  strain %6.3f %%  tau %8.2f kPa  sigma_n %8.2f kPa  eps_v %7.3f %%  band %7.3f %%  %s%s\n",
               R->t, 100.0 * R->strain, 1e-3 * R->tau, 1e-3 * R->sig_n, 100.0 * ev, 100.0 * evb,
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
static int band_measure(run *R, double *thick_D50) {
    gk_err e;
    gk_hybrid_band_result b;
    int n, p, q = 0, bad = 0;
    double *xy, *val, *X[2], *x[2], *eps, period[2] = {0.0, 0.0}, *px, *py;
    char path[1200];
    *thick_D50 = NAN;
    if (!R->window_taken) return 0;
    n = R->band_on_grains ? R->nw : R->P.n;
    xy = (double *)malloc(8 * (size_t)n * sizeof(double));
    val = (double *)malloc((size_t)n * sizeof(double));
    px = (double *)malloc((size_t)n * sizeof(double));
    py = (double *)malloc((size_t)n * sizeof(double));
    if (!xy || !val || !px || !py) return fprintf(stderr, "error: out of memory\n"), 1;
    if (R->band_on_grains) {
        double *half = (double *)malloc((size_t)n * sizeof(double));
        X[0] = (double *)malloc((size_t)n * sizeof(double));
        X[1] = (double *)malloc((size_t)n * sizeof(double));
        x[0] = (double *)malloc((size_t)n * sizeof(double));
        x[1] = (double *)malloc((size_t)n * sizeof(double));
        eps = (double *)malloc(4 * (size_t)n * sizeof(double));
        if (!half || !X[0] || !X[1] || !x[0] || !x[1] || !eps) return fprintf(stderr, "error: out of memory\n"), 1;
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
        if (gk_hybrid_cundall(q, (const double *const *)X, (const double *const *)x, period, 1.6 * DIAM, eps, NULL, &e))
            return fprintf(stderr, "error: Cundall strain: %s\n", e.msg), 1;
        for (p = 0; p < q; ++p) {
            val[p] = eps[4 * p + 3];
            px[p] = x[0][p];
            py[p] = x[1][p];
        }
        n = q;
        for (p = 0; p < n; ++p) {
            double a = half[p];
            xy[8 * p] = px[p] - a, xy[8 * p + 1] = py[p] - a, xy[8 * p + 2] = px[p] + a, xy[8 * p + 3] = py[p] - a;
            xy[8 * p + 4] = px[p] + a, xy[8 * p + 5] = py[p] + a, xy[8 * p + 6] = px[p] - a, xy[8 * p + 7] = py[p] + a;
        }
        free(half);
        free(X[0]);
        free(X[1]);
        free(x[0]);
        free(x[1]);
        free(eps);
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
            xy[8 * p] = px[p] - a, xy[8 * p + 1] = py[p] - a, xy[8 * p + 2] = px[p] + a, xy[8 * p + 3] = py[p] - a;
            xy[8 * p + 4] = px[p] + a, xy[8 * p + 5] = py[p] + a, xy[8 * p + 6] = px[p] - a, xy[8 * p + 7] = py[p] + a;
        }
    }
    if (gk_hybrid_band(n, px, py, val, R->o.percentile, 2.0, &b, NULL, &e) == GK_OK) {
        /* points: the box of their centres plus the spacing of one point (the material it carries) */
        if (!R->band_on_grains) b.thickness += R->dyp;
        *thick_D50 = b.thickness / DIAM;
        if (!R->o.quiet)
            printf("band (App. A, %s, strain %.3g-%.3g): thickness %.2f D50, angle %.1f deg, centre (%.2f, %.2f) cm, %d of "
                   "%d above the %g-th percentile kept\n",
                   R->band_on_grains ? "grains, Cundall" : "points", R->o.win0, R->strain, b.thickness / DIAM,
                   b.angle * 180.0 / GK_PI, 100.0 * b.centre[0], 100.0 * b.centre[1], b.kept, b.selected, R->o.percentile);
    }
    {
        gk_field_def fd;
        int len[2] = {2, 2};
        double Hc = specimen_height(R), lines[8] = {-0.05 * R->W, 0.0, 1.05 * R->W, 0.0, -0.05 * R->W, Hc, 1.05 * R->W, Hc};
        char title[200];
        memset(&fd, 0, sizeof fd);
        snprintf(title, sizeof title, "%s %s: incremental shear strain, strain %.3g to %.3g", test_name[R->o.test],
                 mode_name[R->o.mode], R->o.win0, R->strain);
        fd.title = title;
        fd.label = "gamma (incremental) [-]";
        fd.xlabel = "x [mm]";
        fd.ylabel = "y [mm]";
        fd.coord_scale = 1e3;
        fd.nlines = 2;
        fd.line_len = len;
        fd.line_xy = lines;
        snprintf(path, sizeof path, "%s/band.svg", R->o.out);
        if (gk_field_svg(path, &fd, n, 4, xy, val, &e)) bad = fprintf(stderr, "error: cannot write %s\n", path);
    }
    free(xy);
    free(val);
    free(px);
    free(py);
    return bad != 0;
}

static int write_plots(const run *R, const hist_t *h) {
    gk_plot pl;
    gk_err e;
    char path[1200], title[200];
    int bad = 0;
    snprintf(title, sizeof title, "%s shear, %s", test_name[R->o.test], mode_name[R->o.mode]);
    gk_plot_init(&pl, title, R->o.test == T_PLANAR ? "strain = platen displacement / W [%]" : "axial strain [%]",
                 "stress [kPa]");
    gk_plot_add(&pl, h->s, h->tau, h->n, R->o.test == T_PLANAR ? "tau" : "tau = (sigma_1 - sigma_3)/2");
    gk_plot_add(&pl, h->s, h->sn, h->n, R->o.test == T_PLANAR ? "sigma_n" : "sigma_1 (axial)");
    snprintf(path, sizeof path, "%s/stress_strain.svg", R->o.out);
    if (gk_plot_svg(&pl, path, &e)) bad = fprintf(stderr, "error: cannot write %s\n", path);
    gk_plot_init(&pl, title, R->o.test == T_PLANAR ? "strain [%]" : "axial strain [%]", "volumetric strain [%] (dilation +)");
    gk_plot_add(&pl, h->s, h->ev, h->n, "specimen");
    gk_plot_add(&pl, h->s, h->evb, h->n, "band window");
    snprintf(path, sizeof path, "%s/volume.svg", R->o.out);
    if (gk_plot_svg(&pl, path, &e)) bad = fprintf(stderr, "error: cannot write %s\n", path);
    return bad != 0;
}

/* ------------------------------------------------------------------ main */
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
    free(R->Xw[0]);
    free(R->Xw[1]);
    free(R->idw);
}

int main(int argc, char **argv) {
    static run Rs;
    run *R = &Rs;
    opts *o = &R->o;
    hist_t h;
    char path[1200];
    double thick = NAN, secs, hg;
    int rc = parse(argc, argv, o), status = 0;
    if (rc) return rc == 2 ? 0 : 2;
    memset(&h, 0, sizeof h);
    R->top_wall = -1;
    R->dt = DT;
    if (make_dir(o->out)) return 1;
    R->t_start = wtime();
    if (make_packing(o, &R->pk, &R->phi_pack)) return 1;
    R->W = R->pk.h[0];
    /* the specimen: the packing's width (periodic, planar) and a whole number of
     * MPM cells of height (the continuum's top surface on a node row, where its
     * platen acts): the packing is cut there, for every mode alike */
    hg = R->W / floor(R->W / o->cell + 0.5);
    R->H = floor(R->pk.h[4] / hg + 1e-9) * hg;
    {
        int k, q = 0;
        for (k = 0; k < R->pk.n; ++k)
            if (R->pk.y[k] < R->H) {
                R->pk.x[q] = R->pk.x[k];
                R->pk.y[q] = R->pk.y[k];
                R->pk.r[q] = R->pk.r[k];
                ++q;
            }
        R->pk.n = q;
        R->pk.h[4] = R->H;
    }
    R->rho = R->phi_pack * RHO_S;
    R->M = K_C + G_C;
    R->c = sqrt(R->M / R->rho);
    R->role = (unsigned char *)calloc((size_t)R->pk.n, 1);
    if (!R->role) return fprintf(stderr, "error: out of memory\n"), 1;
    if (!o->quiet)
        printf("%s %s: specimen %.4g x %.4g m, %d grains, packing fraction %.4f, pressure %g Pa, speed %g m/s, dt %g s\n",
               test_name[o->test], mode_name[o->mode], R->W, R->H, R->pk.n, R->phi_pack, o->pressure, o->speed, R->dt);
    if (o->mode == M_DEM) {
        if (setup_dem(R)) return 1;
    } else {
        if (setup_mpm(R) || oracle_setup(R)) return 1;
        if (!o->quiet)
            printf("continuum: %.4g x %.4g m, cells of %.4g m, %d points, c = %.4g m/s (0.3 h/c = %.3g s)\n", R->W, R->H,
                   R->h, R->P.n, R->c, 0.3 * R->h / R->c);
    }
    /* the band window: planar, the mid-height strip; biaxial, the line from the weak cell through the centre */
    R->win_c[0] = 0.5 * R->W;
    R->win_c[1] = 0.5 * R->H;
    R->win_e[0] = 1.0;
    R->win_e[1] = 0.0;
    if (o->test == T_BIAXIAL) {
        double dx = 0.5 * R->W - (R->W - 1.5 * hg), dy = 0.5 * R->H - 1.5 * hg, L = sqrt(dx * dx + dy * dy);
        R->win_e[0] = dx / L;
        R->win_e[1] = dy / L;
        R->win_a = 0.3 * (fabs(R->W / R->win_e[0]) < fabs(R->H / R->win_e[1]) ? fabs(R->W / R->win_e[0]) : fabs(R->H / R->win_e[1]));
    }
    R->A0 = specimen_area(R);
    R->phi0_band = band_solid_fraction(R);
    R->sig_n = o->pressure; /* the consolidated state, before the first step */
    snprintf(path, sizeof path, "%s/hybrid.csv", o->out);
    R->csv = fopen(path, "w");
    if (!R->csv) return fprintf(stderr, "error: cannot write %s\n", path), 1;
    fprintf(R->csv, "time,strain,tau,sigma_n,eps_v,eps_v_band,grains,points,enriched,flagged_nodes,seconds\n");
    if (write_vtk(R, "start") || csv_row(R, &h)) return 1;
    R->next_out = o->out_every;
    while (R->strain < o->strain_end - 1e-12) {
        int was = R->enriched;
        if (o->mode == M_DEM) {
            if (dem_steps(R, 10)) {
                status = 1;
                break;
            }
        } else if (continuum_step(R)) {
            status = 1;
            break;
        }
        if (R->enriched && !was && write_vtk(R, "enrichment")) status = 1;
        if (!R->window_taken && R->strain >= o->win0 && take_window(R)) status = 1;
        if (R->strain >= R->next_out - 1e-12) {
            if (csv_row(R, &h)) {
                status = 1;
                break;
            }
            while (R->next_out <= R->strain + 1e-12) R->next_out += o->out_every;
        }
        if (status) break;
    }
    secs = wtime() - R->t_start;
    if (!status) {
        if (band_measure(R, &thick) || write_vtk(R, "end") || write_plots(R, &h)) status = 1;
    }
    if (fclose(R->csv)) {
        fprintf(stderr, "error: cannot write %s/hybrid.csv\n", o->out);
        status = 1;
    }
    if (!o->quiet && R->grain_steps > 0)
        printf("cost: %.3g s in the grains (%.3g grain-steps, %.3g us each), %.3g s in the continuum (%.3g point-steps, "
               "%.3g us each), %.3g s coupling\n",
               R->sec_dem, (double)R->grain_steps, 1e6 * R->sec_dem / (double)R->grain_steps, R->sec_mpm,
               (double)R->point_steps, R->point_steps ? 1e6 * R->sec_mpm / (double)R->point_steps : 0.0, R->sec_cpl);
    printf("RESULT mode=%s peak_tau=%.6g band_thickness_D50=%.4g strain_at_enrichment=%.4g seconds=%.2f "
           "speedup_vs_dem=%.3g\n",
           mode_name[o->mode], R->peak_tau, thick,
           o->mode == M_HYBRID ? (R->enriched ? R->strain_enrich : NAN) : (R->triggered ? R->strain_trigger : NAN), secs,
           o->dem_seconds > 0.0 ? o->dem_seconds / secs : NAN);
    free(h.s);
    free(h.tau);
    free(h.sn);
    free(h.ev);
    free(h.evb);
    run_free(R);
    return status;
}
