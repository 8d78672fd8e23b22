/* hybrid_setup.h - the set-up of the hybrid continuum-grain driver (examples/hybrid.c; examples, not
 * library): the tests and modes, the material constants, the command-line options (defaults, usage,
 * strict parsing), the packing (generated and consolidated, or read), the run's state (struct run)
 * and the specimen's geometry: top platen, membranes, extent per row, band window.
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
 */
#ifndef HYBRID_SETUP_H
#define HYBRID_SETUP_H

#include "gk_hybrid.h"
#include "cli.h"
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define T_PLANAR 0
#define T_BIAXIAL 1
#define T_INDENT 2
#define M_DEM 0
#define M_CONT 1
#define M_HYBRID 2

static const char *test_name[] = {"planar", "biaxial", "indent"};
static const char *mode_name[] = {"dem", "continuum", "hybrid"};

/* ------------------------------------------------------------------ material */
#define DIAM 1e-3      /* D50 [m] */
#define THICK 1e-3     /* stress thickness: one diameter */
#define RHO_S 25300.0  /* grain mass 1.98e-5 kg for D = 1 mm, t = 1 mm */
#define KN 1.7720938e6 /* Table 1 */
#define DT 5e-7
#define PHI_CS 0.815 /* Table 2 */
#define K_C 6.3e8
#define G_C 4.6e8
#define GRAV 9.81 /* Table 7 */

typedef struct opts {
    int test, mode;
    const char *out, *packing;
    double width, height, pressure, speed, strain_end, out_every;
    double cell, alpha, train, train_speed, phi0, c0, c1, cl, cg, phi_init, weak_dphi, xi;
    double win0, win1, band_window, percentile, dem_seconds, platen_zeta, ramp;
    double intruder; /* indent: the intruder's width B [m] (its height 0.4 B, Table 8) */
    double probe[3]; /* --probe S Y0 Y1 (dem): strain, strip */
    int probe_on;
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
    } else if (test == T_INDENT) { /* Tables 7-9 at a fifth of the size */
        o->width = 0.12;
        o->height = 0.04;
        o->intruder = 0.01;
        o->speed = 0.1;
        o->cell = 0.0025;
        o->pressure = 1e5;   /* the packing's consolidation (it then relaxes to its weight in the bin) */
        o->strain_end = 0.3; /* the intruder's top (0.4 B) stays above the bed */
        o->out_every = 0.01;
        o->phi0 = 0.01; /* the paper: 0.025 = 5 of its cells for its 5 cm intruder */
        o->c0 = 1e-6;
        o->c1 = 8e-3;
        o->cl = 2e-2;
        o->cg = 9.6e-3;
        o->win0 = 0.1;
        o->win1 = 0.3;
        o->band_window = 0.005;
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
    opts p, b, d;
    defaults(&p, T_PLANAR);
    defaults(&b, T_BIAXIAL);
    defaults(&d, T_INDENT);
    fprintf(
        fp,
        "usage: hybrid --test planar|biaxial|indent --mode dem|continuum|hybrid [options]\n"
        "  (defaults given as planar, biaxial[, indent])\n"
        "  --out DIR            output directory (default %s)\n"
        "  --threads T          OpenMP threads (default 1; results do not depend on it)\n"
        "  --width W --height H specimen or bin [m] (%g x %g, %g x %g, %g x %g; paper 0.06 x 0.12, 0.06 x "
        "0.0942, 0.6 x 0.2)\n"
        "  --intruder B         indent: the intruder's width [m], its height 0.4 B (default %g; paper 0.05)\n"
        "  --grains N           grains of the generated packing (0: from the size, packing fraction 0.85)\n"
        "  --packing FILE       read the packing (a periodic cell) instead of generating it\n"
        "  --seed S             packing generator seed (default %lu)\n"
        "  --pressure P         normal (planar) / confining (biaxial) stress, indent: the packing's\n"
        "                       consolidation before it settles in the bin [Pa] (default %g, %g, %g)\n"
        "  --speed V            platen / intruder speed [m/s] (default %g, %g, %g; paper 0.02, 0.02, 0.05)\n"
        "  --strain S           run to this strain (default %g, %g, %g; indent: depth / B)\n"
        "  --out-every S        CSV row every S of strain (default %g, %g, %g)\n"
        "  --cell H             MPM cell [m] (default %g, %g, %g)\n"
        "  --ppd K              MPM points per cell edge (default %d)\n"
        "  --alpha A            MPM PIC fraction (default %g)\n"
        "  --phi0 D             enrichment margin phi_0 [m] (default %g, %g, %g)\n"
        "  --c0 C --c1 C --cl C --cg C   oracle constants (defaults Tables 4, 6 and 9)\n"
        "  --oracle-every N     oracle evaluated every N steps (default %d)\n"
        "  --train F            kinematic training fraction in [0, 1] (default %g; below 1: planar only)\n"
        "  --train-speed V      speed of the trained boundary [m/s] (default: --speed)\n"
        "  --phi PHI            initial continuum packing fraction (default: the packing's; below\n"
        "                       Phi_cs = 0.815 the continuum is under-consolidated)\n"
        "  --weak-dphi D        the weak points' packing fraction is the others' minus D (default %g)\n"
        "  --xi X               rate of eq 8's relaxation of Phi to Phi_cs (default %g, Table 2)\n"
        "  --window S0 S1       strain window of the band measurement (default %g %g, %g %g, %g %g)\n"
        "  --band-window B      half-width of the eps_v_band window [m] (default %g, %g)\n"
        "  --percentile Q       band grains: value above the Q-th percentile (default %g)\n"
        "  --platen-damping Z   planar top platen: damping ratio of its dashpot (default %g)\n"
        "  --ramp K             the platen speed rises linearly over K wave transits H / c (default %g)\n"
        "  --dem-seconds S      wall seconds of the dem run of the same test (for speedup_vs_dem)\n"
        "  --probe S Y0 Y1      dem, planar: the grains' mean stress in the strip Y0 <= y < Y1 [m] at strain "
        "S\n"
        "                       (the hybrid run prints this option for its discrete zone and enrichment "
        "strain)\n"
        "  --paper              the paper's sizes and speeds (Tables 3, 5, 7-8): 6 x 12 cm\n"
        "                       (planar, phi_0 2.2 cm), 6 x 9.42 cm (biaxial), 0.02 m/s; indent: a\n"
        "                       60 x 20 cm bin, a 5 cm intruder at 0.05 m/s, cells of 0.5 cm, phi_0\n"
        "                       2.5 cm; the other flags override it\n"
        "  --quiet              no progress lines\n",
        p.out, p.width, p.height, b.width, b.height, d.width, d.height, d.intruder, p.seed, p.pressure,
        b.pressure, d.pressure, p.speed, b.speed, d.speed, p.strain_end, b.strain_end, d.strain_end,
        p.out_every, b.out_every, d.out_every, p.cell, b.cell, d.cell, p.ppd, p.alpha, p.phi0, b.phi0, d.phi0,
        p.oracle_every, p.train, p.weak_dphi, p.xi, p.win0, p.win1, b.win0, b.win1, d.win0, d.win1,
        p.band_window, b.band_window, p.percentile, p.platen_zeta, p.ramp);
}

static int num(const char *s, double *v) {
    char *end;
    errno = 0;
    *v = strtod(s, &end);
    return end != s && *end == '\0' && errno == 0 && isfinite(*v);
}

/* strict parsing (examples/cli.h): every flag known, every value a number in range, errors name the
 * flag; 0 to run, 2 after --help, 1 after a message */
static int parse(int argc, char **argv, opts *o) {
    int i, test = -1, mode = -1;
    for (i = 1; i < argc; ++i) /* --help needs no --test */
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) return usage(stdout), 2;
    for (i = 1; i + 1 < argc; ++i) {
        if (!strcmp(argv[i], "--test")) {
            if (!strcmp(argv[i + 1], "planar"))
                test = T_PLANAR;
            else if (!strcmp(argv[i + 1], "biaxial"))
                test = T_BIAXIAL;
            else if (!strcmp(argv[i + 1], "indent"))
                test = T_INDENT;
            else
                return fprintf(stderr, "error: --test %s: use planar, biaxial or indent\n", argv[i + 1]), 1;
        }
    }
    if (test < 0) return fprintf(stderr, "error: --test planar|biaxial|indent is required\n"), 1;
    defaults(o, test);
    for (i = 1; i < argc; ++i)
        if (!strcmp(argv[i], "--paper")) { /* Tables 3-8; the other flags override it */
            o->width = test == T_INDENT ? 0.6 : 0.06;
            o->height = test == T_PLANAR ? 0.12 : (test == T_INDENT ? 0.2 : 0.0942);
            o->speed = test == T_INDENT ? 0.05 : 0.02;
            if (test == T_INDENT) {
                o->intruder = 0.05;
                o->cell = 0.005;
                o->phi0 = 0.025;
            }
            if (test == T_PLANAR) {
                o->phi0 = 0.022;
                o->band_window = 0.022;
            }
        }
    {
        int grains = (int)o->grains, paper = 0, help = 0, n = 1, r = 0;
        const char *test_arg = NULL;
        const cli_opt table[] = {
            {"--test", CLI_STR, &test_arg, 0, 0, NULL, NULL, 0}, /* read above */
            {"--mode", CLI_CHOICE, &mode, 0, 0, NULL, "dem|continuum|hybrid", 0},
            {"--out", CLI_STR, &o->out, 0, 0, NULL, NULL, 0},
            {"--packing", CLI_STR, &o->packing, 0, 0, NULL, NULL, 0},
            {"--quiet", CLI_FLAG, &o->quiet, 0, 0, NULL, NULL, 0},
            {"--paper", CLI_FLAG, &paper, 0, 0, NULL, NULL, 0}, /* applied above */
            {"--width", CLI_REAL, &o->width, 0.005, 10.0, "a width in [0.005, 10] m", NULL, 0},
            {"--height", CLI_REAL, &o->height, 0.005, 10.0, "a height in [0.005, 10] m", NULL, 0},
            {"--intruder", CLI_REAL, &o->intruder, 0.002, 10.0, "a width in [0.002, 10] m", NULL, 0},
            {"--pressure", CLI_REAL, &o->pressure, 0.0, 1e8, "a stress in (0, 1e8] Pa", NULL, CLI_LO_OPEN},
            {"--speed", CLI_REAL, &o->speed, 0.0, 10.0, "a speed in (0, 10] m/s", NULL, CLI_LO_OPEN},
            {"--strain", CLI_REAL, &o->strain_end, 0.0, 2.0, "a strain in (0, 2]", NULL, CLI_LO_OPEN},
            {"--out-every", CLI_REAL, &o->out_every, 0.0, HUGE_VAL, "a positive strain", NULL, CLI_LO_OPEN},
            {"--cell", CLI_REAL, &o->cell, 0.0, HUGE_VAL, "a positive cell size", NULL, CLI_LO_OPEN},
            {"--alpha", CLI_REAL, &o->alpha, 0.0, 1.0, "a value in [0, 1]", NULL, 0},
            {"--train", CLI_REAL, &o->train, 0.0, 1.0, "a fraction in [0, 1]", NULL, 0},
            {"--train-speed", CLI_REAL, &o->train_speed, 0.0, 10.0, "a speed in (0, 10] m/s", NULL,
             CLI_LO_OPEN},
            {"--phi0", CLI_REAL, &o->phi0, 0.0, HUGE_VAL, "a positive distance", NULL, CLI_LO_OPEN},
            {"--c0", CLI_REAL, &o->c0, 0.0, HUGE_VAL, "a value >= 0", NULL, 0},
            {"--c1", CLI_REAL, &o->c1, 0.0, HUGE_VAL, "a value >= 0", NULL, 0},
            {"--cl", CLI_REAL, &o->cl, 0.0, HUGE_VAL, "a positive value", NULL, CLI_LO_OPEN},
            {"--cg", CLI_REAL, &o->cg, 0.0, HUGE_VAL, "a positive value", NULL, CLI_LO_OPEN},
            {"--phi", CLI_REAL, &o->phi_init, 0.5, 0.95, "a packing fraction in (0.5, 0.95)", NULL,
             CLI_LO_OPEN | CLI_HI_OPEN},
            {"--weak-dphi", CLI_REAL, &o->weak_dphi, 0.0, 0.3, "a value in [0, 0.3)", NULL, CLI_HI_OPEN},
            {"--xi", CLI_REAL, &o->xi, 0.0, 1e3, "a value in [0, 1e3]", NULL, 0},
            {"--band-window", CLI_REAL, &o->band_window, 0.0, HUGE_VAL, "a positive half-width", NULL,
             CLI_LO_OPEN},
            {"--percentile", CLI_REAL, &o->percentile, 50.0, 100.0, "a percentile in [50, 100)", NULL,
             CLI_HI_OPEN},
            {"--platen-damping", CLI_REAL, &o->platen_zeta, 0.0, 10.0, "a value in [0, 10]", NULL, 0},
            {"--ramp", CLI_REAL, &o->ramp, 0.0, 1e4, "a value in [0, 1e4]", NULL, 0},
            {"--dem-seconds", CLI_REAL, &o->dem_seconds, 0.0, HUGE_VAL, "a positive time", NULL, CLI_LO_OPEN},
            {"--threads", CLI_INT, &o->threads, 1, 256, NULL, NULL, 0},
            {"--grains", CLI_INT, &grains, 0, 5000000, NULL, NULL, 0},
            {"--ppd", CLI_INT, &o->ppd, 1, 4, NULL, NULL, 0},
            {"--oracle-every", CLI_INT, &o->oracle_every, 1, 1000000, NULL, NULL, 0},
            {"--seed", CLI_ULONG, &o->seed, 0, 0, NULL, NULL, 0}, /* at most 4294967295: checked below */
            {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
        const cli_opt *const tables[] = {table, NULL};
        /* --window S0 S1 and --probe S Y0 Y1 take several values, which cli.h does not: the
         * arguments are handed to cli_parse a stretch at a time, each --window or --probe read
         * between two stretches, so that every refusal (and --help) still comes in the order of
         * the command line */
        char **seg = (char **)malloc((size_t)(argc + 1) * sizeof *seg);
        if (!seg) return fprintf(stderr, "error: out of memory\n"), 1;
        seg[0] = argv[0];
        for (i = 1; i <= argc && !r && !help; ++i) {
            const cli_opt *k = NULL;
            int t;
            if (i < argc && strcmp(argv[i], "--window") && strcmp(argv[i], "--probe")) {
                for (t = 0; table[t].name && !k; ++t)
                    if (!strcmp(argv[i], table[t].name)) k = &table[t];
                seg[n++] = argv[i];
                if (k && k->kind != CLI_FLAG && i + 1 < argc) seg[n++] = argv[++i];
                continue;
            }
            /* the end, or a --window or --probe: the stretch before it */
            if (cli_parse("hybrid", n, seg, tables, &help)) r = 1;
            n = 1;
            if (r || help || i == argc) break;
            if (!strcmp(argv[i], "--probe")) {
                double v0, v1, v2;
                if (i + 3 >= argc || !num(argv[i + 1], &v0) || !num(argv[i + 2], &v1) ||
                    !num(argv[i + 3], &v2) || !(v0 > 0.0 && v0 <= 2.0) ||
                    !(v1 >= 0.0 && v2 > v1 && v2 <= 10.0))
                    r = (fprintf(
                             stderr,
                             "error: --probe needs a strain S in (0, 2] and a strip 0 <= Y0 < Y1 <= 10 m\n"),
                         1);
                else
                    o->probe[0] = v0, o->probe[1] = v1, o->probe[2] = v2, o->probe_on = 1, i += 3;
                continue;
            }
            {
                double v0, v1;
                if (i + 2 >= argc || !num(argv[i + 1], &v0) || !num(argv[i + 2], &v1) ||
                    !(v0 >= 0.0 && v1 > v0))
                    r = (fprintf(stderr, "error: --window needs two strains S0 < S1\n"), 1);
                else
                    o->win0 = v0, o->win1 = v1, i += 2;
            }
        }
        free(seg);
        if (r) return 1;
        if (help) return usage(stdout), 2;
        if (o->seed > 4294967295UL)
            return fprintf(stderr,
                           "hybrid: --seed %lu is out of range: needs a whole number in [0, 4294967295]\n",
                           o->seed),
                   1;
        o->grains = grains;
        (void)test_arg, (void)paper;
    }
    if (mode < 0) return fprintf(stderr, "error: --mode dem|continuum|hybrid is required\n"), 1;
    o->mode = mode;
    if (o->train_speed <= 0.0) o->train_speed = o->speed;
    if (o->probe_on && (o->mode != M_DEM || o->test != T_PLANAR))
        return fprintf(stderr,
                       "error: --probe is a measurement of the planar dem run (a hybrid run reports its "
                       "trained packing's stress itself)\n"),
               1;
    if (o->probe_on && o->probe[0] > o->strain_end)
        return fprintf(stderr, "error: --probe strain %g beyond --strain %g\n", o->probe[0], o->strain_end),
               1;
    if (o->win1 > o->strain_end + 1e-12)
        return fprintf(stderr, "error: --window end %g beyond --strain %g\n", o->win1, o->strain_end), 1;
    if (o->test == T_INDENT) {
        if (o->intruder > 0.5 * o->width || 0.4 * o->intruder > 0.5 * o->height)
            return fprintf(stderr,
                           "error: --intruder %g: wider than half the bin (%g m) or taller than half its "
                           "depth (%g m)\n",
                           o->intruder, o->width, o->height),
                   1;
    }
    if (o->test != T_PLANAR && o->train < 1.0)
        return fprintf(stderr,
                       "error: --train %g: below 1 only for the planar test (the band region moves)\n",
                       o->train),
               1;
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
            if (mkdir(buf, 0755) && errno != EEXIST)
                return fprintf(stderr, "error: cannot create %s\n", buf), 1;
            buf[k] = c;
        }
    if (stat(d, &st) || !S_ISDIR(st.st_mode))
        return fprintf(stderr, "error: --out %s: not a directory\n", d), 1;
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
        if (gk_rve_step(rve, 1000))
            return fprintf(stderr, "error: consolidation: %s\n", gk_rve_error(rve)), 1;
        for (q = 0; q < rve->n; ++q)
            fs += sqrt((double)rve->f[0][q] * rve->f[0][q] + (double)rve->f[1][q] * rve->f[1][q]);
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
        if (gk_rve_create(&rve, &d, &pk))
            return fprintf(stderr, "error: packing: %s\n", gk_rve_error(&rve)), 1;
        gk_packing_free(&pk);
        if (consolidate(&rve, o->pressure, 0.0) || consolidate(&rve, o->pressure, 0.5)) {
            gk_rve_destroy(&rve);
            return 1;
        }
        gk_rve_stress(&rve, s);
        if (!o->quiet)
            printf("packing: %d grains consolidated to %.4g, %.4g Pa in a %.4g x %.4g m cell\n", rve.n, -s[0],
                   -s[4], rve.cell.h[0], rve.cell.h[4]);
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
    /* indent: the intruder's depth [m], the grains' intruder (4 segment walls) and its start */
    double depth, y_intr0;
    int intr[4], nintr, bin_bottom;
    double qsum[2]; /* indent: sums of tau and sigma_n since the last CSV row (its mean is written) */
    long qn;
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
    double packing_tau; /* hybrid: the trained packing's mean shear stress; dem: --probe's [Pa] */
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
    if (R->o.test == T_INDENT) d.gravity[1] = -GRAV;
    d.rve.mat = grain_material(zeta_paper(), 0.4);
    d.rve.thickness = THICK;
    d.rve.dt = DT;
    d.rve.damping = 0.0;
    d.rve.threads = R->o.threads;
    return d;
}

/* the grains' role by stable id, from their reference positions */
static int role_of(const run *R, double y) {
    if (R->o.test == T_INDENT) return 0; /* the bin's walls hold the bed */
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

/* ---- indent: the bin and the intruder of the grains */
/* the bin: a rough bottom (the grains' friction) and smooth sides, planes at
 * y = 0, x = 0 and x = W (the continuum's: no-slip bottom, roller sides) */
static int add_bin_walls(run *R) {
    int k;
    for (k = 0; k < 3; ++k) {
        gk_wall_def w = gk_wall_def_default();
        w.kind = GK_WALL_PLANE;
        w.mat = grain_material(zeta_paper(), 0.4);
        if (k == 0)
            w.normal[1] = 1.0;
        else {
            w.point[0] = k == 1 ? 0.0 : R->W;
            w.normal[0] = k == 1 ? 1.0 : -1.0;
            w.mat.friction = 0.0;
        }
        if (gk_scene_add_wall(&R->sc, &w, k == 0 ? &R->bin_bottom : NULL))
            return fprintf(stderr, "error: %s\n", gk_scene_error(&R->sc)), 1;
    }
    return 0;
}

/* the intruder: a rigid B x 0.4 B rectangle of four segments (rough: the
 * grains' friction) centred on the bin, its bottom at y, moving at (0, -v) */
static int add_intruder(run *R, double y, double v) {
    double B = R->o.intruder, Hi = 0.4 * B, x0 = 0.5 * (R->W - B);
    double a[4][2] = {{x0, y}, {x0, y}, {x0 + B, y}, {x0, y + Hi}},
           e[4][2] = {{B, 0}, {0, Hi}, {0, Hi}, {B, 0}};
    int k;
    for (k = 0; k < 4; ++k) {
        gk_wall_def w = gk_wall_def_default();
        w.kind = GK_WALL_SEGMENT;
        w.point[0] = a[k][0];
        w.point[1] = a[k][1];
        w.e1[0] = e[k][0];
        w.e1[1] = e[k][1];
        w.normal[1] = -1.0;
        w.mat = grain_material(zeta_paper(), 0.4);
        w.drive = GK_DRIVE_VELOCITY;
        w.velocity[1] = -v;
        if (gk_scene_add_wall(&R->sc, &w, &R->intr[k]))
            return fprintf(stderr, "error: %s\n", gk_scene_error(&R->sc)), 1;
    }
    R->nintr = 4;
    return 0;
}

/* the grains' intruder moves down at v [m/s] from the next step on */
static void intruder_velocity(run *R, double v) {
    int k;
    for (k = 0; k < R->nintr; ++k) R->sc.walls[R->intr[k]].def.velocity[1] = -v;
}

/* the grains' push on the intruder [N] (x, y): the sum over its four walls */
static void intruder_force(const run *R, double f[2]) {
    int k;
    f[0] = f[1] = 0.0;
    for (k = 0; k < R->nintr; ++k) {
        f[0] += R->sc.walls[R->intr[k]].force[0];
        f[1] += R->sc.walls[R->intr[k]].force[1];
    }
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
    double *bx = (double *)malloc((size_t)nb * sizeof(double)),
           *yy = (double *)malloc((size_t)nb * sizeof(double));
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
#define WIN_ADD(x, y, d, a)                                                            \
    do {                                                                               \
        double u = ((x)-R->win_c[0]) * R->win_e[0] + ((y)-R->win_c[1]) * R->win_e[1];  \
        double w = -((x)-R->win_c[0]) * R->win_e[1] + ((y)-R->win_c[1]) * R->win_e[0]; \
        S += (a)*overlap1(w, (d), b) * (planar ? 1.0 : overlap1(u, (d), R->win_a));    \
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
        for (p = 0; p < R->P.n; ++p)
            WIN_ADD(R->P.x[0][p], R->P.x[1][p], sqrt(R->P.vol[p]), R->P.vol0[p] * phi0);
#undef WIN_ADD
    return S / area;
}

#endif /* HYBRID_SETUP_H */
