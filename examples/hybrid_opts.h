/* hybrid_opts.h - the tests, modes, material constants and command-line
 * options (defaults, usage, strict parsing) of the hybrid continuum-grain
 * driver (examples/hybrid.c; examples, not library).
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
#ifndef HYBRID_OPTS_H
#define HYBRID_OPTS_H

#include "gk_hybrid.h"
#include "cli.h"
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
#define PARTITION 0.5  /* w of eq 9: the overlap grains' share of their mass */
#define RHO_S 25300.0  /* grain mass 1.98e-5 kg for D = 1 mm, t = 1 mm */
#define KN 1.7720938e6 /* Table 1 */
#define DT 5e-7
#define PHI_CS 0.815 /* Table 2 */
#define K_C 6.3e8
#define G_C 4.6e8
#define GRAV 9.81 /* Table 7 */

/* ------------------------------------------------------------------ coupling bookkeeping */
/* steps between updates of the coupling mask and removals of escaped grains (a grain moves under
 * 1e-3 D50 per step) */
#define REFRESH_EVERY 20
/* cells: a free grain is removed once this much further out sideways its coupling support would
 * leave the grid (a generous spare: at 2 m/s a grain moves 0.02 mm, under 0.01 cell, between two
 * checks) */
#define ESCAPE_SPARE 1.25
/* cells: planar, a free grain touching none this far beyond the overlap's outer edge (phi0 + h / 2
 * from the flagged nodes) is a stray and is removed (coupling_mask) */
#define STRAY_CELLS 1.0
/* cells: biaxial and indent, a point this far inside the discrete zone (beyond the overlap's inner
 * edge, phi0 - h / 2 from the flagged nodes) couples the grains whose stencils share its nodes
 * (coupling_mask) */
#define DEEP_CELLS 0.5

typedef struct opts {
    int test, mode;
    const char *out, *packing;
    double width, height, pressure, speed, strain_end, out_every;
    double cell, alpha, train, train_speed, phi0, c0, c1, cl, cg, phi_init, weak_dphi, xi;
    double win0, win1, band_window, percentile, dem_seconds, platen_zeta, ramp;
    double intruder; /* indent: the intruder's width B [m] (its height 0.4 B, Table 8) */
    double probe[3]; /* --probe S Y0 Y1 (dem): strain, strip */
    int probe_on;
    int ppd, threads, oracle_every, quiet, keep_strays;
    int weigh_overlap; /* --weigh-overlap: overlap grains carry w of their contact forces */
    int delaunay;      /* --delaunay: Cundall strain over Delaunay neighbours (else within 1.6 D50) */
    int interior;      /* --interior: the band leaves out grains with an open cell (implies --delaunay) */
    int band_grains;   /* > 0: band grains are the band_grains largest values (not --percentile) */
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
        "                       Phi_cs = 0.815 the continuum is under-consolidated; below 0.7755,\n"
        "                       weak points included, eq 7 gives a negative friction: refused)\n"
        "  --weak-dphi D        the weak points' packing fraction is the others' minus D (default %g)\n"
        "  --xi X               rate of eq 8's relaxation of Phi to Phi_cs (default %g, Table 2)\n"
        "  --window S0 S1       strain window of the band measurement (default %g %g, %g %g, %g %g)\n"
        "  --band-window B      half-width of the eps_v_band window [m] (default %g, %g)\n"
        "  --percentile Q       band grains: value above the Q-th percentile (default %g)\n"
        "  --delaunay           band grains: Cundall strain over each grain's Delaunay neighbours,\n"
        "                       as App. A (by default over the grains within 1.6 D50)\n"
        "  --interior           band grains: --delaunay, leaving out the grains whose cell is open\n"
        "                       (the free sides, the edge of the measured set: one-sided fits;\n"
        "                       drawn grey in band.svg)\n"
        "  --band-grains N      band grains: the N largest values instead (a hybrid measures only\n"
        "                       its discrete zone's grains and prints its count: give it to a dem\n"
        "                       run to compare bands measured on as many grains)\n"
        "  --platen-damping Z   planar top platen: damping ratio of its dashpot (default %g)\n"
        "  --ramp K             the platen speed rises linearly over K wave transits H / c (default %g)\n"
        "  --dem-seconds S      wall seconds of the dem run of the same test (for speedup_vs_dem)\n"
        "  --probe S Y0 Y1      dem, planar: the grains' mean stress in the strip Y0 <= y < Y1 [m] at strain "
        "S\n"
        "                       (the hybrid run prints this option for its discrete zone and enrichment "
        "strain)\n",
        p.out, p.width, p.height, b.width, b.height, d.width, d.height, d.intruder, p.seed, p.pressure,
        b.pressure, d.pressure, p.speed, b.speed, d.speed, p.strain_end, b.strain_end, d.strain_end,
        p.out_every, b.out_every, d.out_every, p.cell, b.cell, d.cell, p.ppd, p.alpha, p.phi0, b.phi0, d.phi0,
        p.oracle_every, p.train, p.weak_dphi, p.xi, p.win0, p.win1, b.win0, b.win1, d.win0, d.win1,
        p.band_window, b.band_window, p.percentile, p.platen_zeta, p.ramp);
    fputs("  --paper              the paper's sizes and speeds (Tables 3, 5, 7-8): 6 x 12 cm\n"
          "                       (planar, phi_0 2.2 cm), 6 x 9.42 cm (biaxial), 0.02 m/s; indent: a\n"
          "                       60 x 20 cm bin, a 5 cm intruder at 0.05 m/s, cells of 0.5 cm, phi_0\n"
          "                       2.5 cm; the other flags override it\n"
          "  --keep-strays        planar hybrid: keep the free grains that stray more than a cell beyond\n"
          "                       the overlap touching none (by default removed, and counted)\n"
          "  --weigh-overlap      hybrid: a grain that holds w = 1/2 of its mass (in the overlap at the\n"
          "                       swap) carries w of its contact forces too, each contact scaled by its\n"
          "                       grains' mean w (eq 9 read literally; by default the forces are whole)\n"
          "  --quiet              no progress lines\n",
          fp);
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
            {"--keep-strays", CLI_FLAG, &o->keep_strays, 0, 0, NULL, NULL, 0},
            {"--weigh-overlap", CLI_FLAG, &o->weigh_overlap, 0, 0, NULL, NULL, 0},
            {"--delaunay", CLI_FLAG, &o->delaunay, 0, 0, NULL, NULL, 0},
            {"--interior", CLI_FLAG, &o->interior, 0, 0, NULL, NULL, 0},
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
            {"--band-grains", CLI_INT, &o->band_grains, 3, 5000000, NULL, NULL, 0},
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
    if (o->band_grains > 0 && (o->test == T_INDENT || o->mode == M_CONT))
        return fprintf(stderr, "error: --band-grains: a count of grains (planar or biaxial, dem or hybrid; "
                               "the continuum's band is measured on its points)\n"),
               1;
    if (o->keep_strays && (o->test != T_PLANAR || o->mode != M_HYBRID))
        return fprintf(stderr, "error: --keep-strays is an option of the planar hybrid run\n"), 1;
    if (o->weigh_overlap && o->mode != M_HYBRID)
        return fprintf(stderr, "error: --weigh-overlap is an option of the hybrid run (--mode hybrid)\n"), 1;
    if (o->interior) o->delaunay = 1;
    if (o->delaunay && o->mode == M_CONT)
        return fprintf(stderr, "error: --%s measures grains: the continuum's band is of its points\n",
                       o->interior ? "interior" : "delaunay"),
               1;
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

#endif /* HYBRID_OPTS_H */
