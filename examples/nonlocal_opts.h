/* nonlocal_opts.h - the options of build/femdem_nonlocal (examples/femdem_nonlocal.c) and the
 * tests they select (examples, not library): the test names, the options, the usage text and the
 * parser with every test's defaults (femdem_nonlocal --help lists them), on examples/cli.h: every
 * value is parsed strictly and a refused one is named (status 2).
 *
 * TESTS (units SI; stresses in the outputs compression-positive)
 *   rve              Table II: K and G of the RVE alone from isotropic
 *                    compression and simple shear to --strain (2e-3) in
 *                    --steps increments; initial porosity, Z, p.
 *   element-biaxial  one 10 mm element (Fig 5 left): bottom and left face on
 *                    rollers, plane strain, the top pressed down, --pressure
 *                    on the right face; and the RVE alone on the same path
 *                    with the same corotational kinematics, its lateral
 *                    stress held at --pressure per increment by a secant /
 *                    regula falsi iteration (1e-3 p; where a 512-sphere
 *                    RVE's response jumps - up to 6 % of p between
 *                    neighbouring increments at critical state - the closest
 *                    run within 10 % of p; rve_alone.csv has its stress_2),
 *                    --lone-increments 400 (half of them in the first tenth
 *                    of the strain). Compared over ten equal strain windows
 *                    (mean stress of each curve; both fluctuate by several %
 *                    at critical state): rve_alone_dev_pct = the largest gap
 *                    / the RVE's peak, and peak_ratio (Fig 6a).
 *   element-shear    one element (Fig 5 right): bottom fixed, the top moved
 *                    horizontally as a rigid platen (one u_y) carrying the
 *                    normal --pressure, plane strain; the RVE alone likewise
 *                    with its normal stress held (Fig 6b).
 *   wave             Fig 8: a 100 x 10 x 10 mm column of 10 elements, left
 *                    end fixed, lateral faces periodic (eps_22 = eps_33 =
 *                    eps_23 = 0), the right end moved transversally u_y = a
 *                    sin(2 pi f t) (--amplitude 1e-4 m, --frequency 1e4 Hz,
 *                    --dt 1e-6 s, --duration 1e-3 s), no macro damping. The
 *                    front's arrival per element (the first time |gamma| >
 *                    F a / h, --front-threshold F, default 1e-3) against
 *                    sqrt(G / rho) and against a linear elastic column of
 *                    the same mesh, steps and excitation (the RVE's K and
 *                    G, initial stress -p I). A small F catches the
 *                    columns' earliest response, which the discrete column
 *                    (4.5 elements per wavelength) spreads ahead of
 *                    sqrt(G / rho); a larger F arrives later; the loops of
 *                    element 9 and its porosity and Z (Fig 8a, b).
 *   simple-shear     Figs 9-14: 50.6 x 118 x 12.7 mm, --mesh 5x12x1 (the
 *                    paper's "12 x 5 x 1": 12 rows over the height), bottom
 *                    fixed, the top a rigid platen moved horizontally under
 *                    --pressure, periodic in x and z, one imperfect RVE
 *                    (--imperfection N particles removed at random, by
 *                    default 25 x N_particles / 4096 as the paper's 25 of
 *                    4096, re-consolidated to --pressure with friction) in
 *                    the middle column of the row starting at 3/4 of the
 *                    height (--imperfect-row: in every element of that
 *                    row). Shear stress = base reaction / base area,
 *                    strain = u_top / 118 mm.
 *   biaxial          Figs 15-19: 40 x 80 x 5 mm plane strain (--mesh 4x8x1),
 *                    the top a smooth platen pressed down, --pressure on both
 *                    sides, the bottom on rollers and rough (u_x = 0) on its
 *                    left half: the paper's unspecified "asymmetric boundary
 *                    condition" that starts the band; contact damping 0.
 */
#ifndef NONLOCAL_OPTS_H
#define NONLOCAL_OPTS_H

#include "cli.h"
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { T_RVE, T_EBIAX, T_ESHEAR, T_WAVE, T_SSHEAR, T_BIAX, T_COUNT };
static const char *test_name[T_COUNT] = {"rve",  "element-biaxial", "element-shear",
                                         "wave", "simple-shear",    "biaxial"};

typedef struct opts {
    int test, mesh[3], threads, steps, stop_after, checkpoint, vtk_every, every, imperfection, dem_min,
        dem_max, lone, paper, gauss, imperfect_row;
    double R, mix, pressure, strain, iuf, dem_inertial, dem_damping, contact_damping, density, xi, mass_scale,
        kappa, dt, dt_safety;
    double amplitude, frequency, duration, front;
    const char *packing, *out, *restart;
} opts;

/* ------------------------------------------------------------ small helpers */
static void *xcalloc(size_t n, size_t sz) {
    void *p = calloc(n ? n : 1, sz);
    if (!p) {
        fprintf(stderr, "femdem_nonlocal: out of memory (%lu x %lu bytes)\n", (unsigned long)n,
                (unsigned long)sz);
        exit(1);
    }
    return p;
}

static void usage(FILE *fp) {
    fprintf(fp,
            "usage: femdem_nonlocal --test rve|element-biaxial|element-shear|wave|simple-shear|biaxial --out "
            "DIR\n"
            "  [--mesh NXxNYxNZ] [--nonlocal R|off] [--nonlocal-mix M] [--pressure P] [--strain S]\n"
            "  [--steps N] [--packing F] [--threads T] [--restart DIR] [--stop-after N] [--checkpoint K]\n"
            "  [--vtk-every K] [--every K] [--imperfection N] [--iuf X] [--dem-inertial I] [--dem-min N]\n"
            "  [--dem-max N] [--dem-damping A] [--contact-damping Z] [--density RHO] [--xi X]\n"
            "  [--mass-scale S] [--hourglass K] [--dt DT] [--dt-safety F] [--amplitude A] [--frequency F]\n"
            "  [--duration T] [--front-threshold F] [--lone-increments N] [--gauss 1|8] [--paper]\n"
            "  [--imperfect-row]\n");
    fprintf(fp,
            "defaults: --pressure 4.16e5 --packing examples/data/rve512_hm.txt --threads 1 --nonlocal off\n"
            "  --iuf 0.01 --dem-inertial 2e-3 --dem-min 10 --dem-max 4000 (biaxial: 20; simple-shear with\n"
            "  --dem-max 20: 7x faster, but the capped RVEs spread the strain and no band forms)\n"
            "  --dem-damping 0.2 --contact-damping 0.12 (biaxial 0) --density 2492 --xi 0.3 (wave 0)\n"
            "  --mass-scale 1 --hourglass 0.1 (0 with --gauss 8) --dt-safety 0.5 --lone-increments 400\n"
            "  --gauss 1 (one Gauss point and RVE per element; 8: fully integrated, 8 RVEs per element,\n"
            "  no hourglass control: the local reference; element, simple-shear and biaxial tests)\n"
            "  rve: --strain 2e-3 --steps 20; element-biaxial: --mesh 1x1x1 --strain 0.05 --steps 4000;\n"
            "  element-shear: --mesh 1x1x1 --strain 0.1 --steps 4000; wave: --mesh 10x1x1 --dt 1e-6\n"
            "  --duration 1e-3 --amplitude 1e-4 --frequency 1e4 --front-threshold 1e-3 (an element's\n"
            "  front: its shear strain first above F x amplitude / element length); simple-shear:\n"
            "  --mesh 5x12x1 --strain 0.2 --steps 4000 --imperfection 25 x N/4096; biaxial: --mesh 4x8x1\n"
            "  --strain 0.08 --steps 3000.\n"
            "  --paper: the paper's size, the 4096-sphere RVE (--packing examples/data/rve4096_hm.txt) and\n"
            "  its I_uf rule in the biaxial test too (--dem-max 4000); flags given override it. The paper's\n"
            "  nonlocal radius: --nonlocal 6.75e-3. --nonlocal-mix M (default 1, the paper): average\n"
            "  M <eps> + (1 - M) eps, part of the strain kept local (see gk_nonlocal.h, stability).\n"
            "  --imperfect-row: the imperfect RVE in every element of its row, not in its middle one\n"
            "  (the paper names one imperfect cell, not which elements carry it).\n"
            "See the top of examples/femdem_nonlocal.c for the model, the outputs and the RESULT line.\n");
}

/* --test NAME: its index in test_name (the last --test counts, a misspelt one is refused where it
 * stands) */
static int test_opt(const char *prog, const char *name, const char *v, void *dst) {
    int t, *test = (int *)dst;
    for (t = 0; t < T_COUNT; ++t)
        if (!strcmp(v, test_name[t])) {
            *test = t;
            return 0;
        }
    cli_say(prog,
            "%s: %s '%s' is not one of rve, element-biaxial, element-shear, wave, simple-shear, biaxial\n",
            prog, name, v);
    return 2;
}

/* --mesh NXxNYxNZ, counts 1-1000 (a cli.h CLI_FUNC: checked where it stands) */
static int mesh_opt(const char *prog, const char *name, const char *v, void *dst) {
    int *mesh = (int *)dst, k;
    const char *q = v;
    char *e;
    for (k = 0; k < 3; ++k) {
        long x;
        errno = 0;
        x = strtol(q, &e, 10);
        if (e == q || errno || x < 1 || x > 1000 || (k < 2 && *e != 'x') || (k == 2 && *e)) {
            cli_say(prog, "%s: %s '%s' is not NXxNYxNZ with counts 1-1000\n", prog, name, v);
            return 2;
        }
        mesh[k] = (int)x;
        q = e + 1;
    }
    return 0;
}

/* --nonlocal R|off: a radius > 0 [m], or off (0) */
static int nonlocal_opt(const char *prog, const char *name, const char *v, void *dst) {
    static const cli_opt real = {"--nonlocal", CLI_REAL, NULL, -HUGE_VAL, HUGE_VAL, "a radius > 0 [m] or off",
                                 NULL,         0};
    cli_opt o = real;
    double *R = (double *)dst;
    if (!strcmp(v, "off")) {
        *R = 0.0;
        return 0;
    }
    o.name = name, o.dst = R;
    if (cli_value(prog, &o, v)) return 2;
    if (!(*R > 0.0)) {
        cli_say(prog, "%s: %s '%s' must be a radius > 0 [m] or off\n", prog, name, v);
        return 2;
    }
    return 0;
}

/* the options (examples/cli.h: every value parsed strictly, a refused one named, status 2), then
 * the defaults of the test and the ranges (below: they depend on the test); --help prints the
 * usage and exits 0. 0, or 2 after a message. */
static int parse(int argc, char **argv, opts *o) {
    /* any whole number / finite number in the table; the ranges are checked below */
    const double I0 = INT_MIN, I1 = INT_MAX, R0 = -HUGE_VAL, R1 = HUGE_VAL;
    cli_func test_f, mesh_f, nonlocal_f;
    const cli_opt tab[] = {
        {"--test", CLI_FUNC, &test_f, 0, 0, NULL, NULL, 0},
        {"--mesh", CLI_FUNC, &mesh_f, 0, 0, NULL, NULL, 0},
        {"--nonlocal", CLI_FUNC, &nonlocal_f, 0, 0, NULL, NULL, 0},
        {"--nonlocal-mix", CLI_REAL, &o->mix, R0, R1, "a number in [0, 1]", NULL, 0},
        {"--pressure", CLI_REAL, &o->pressure, R0, R1, "a number > 0", NULL, 0},
        {"--strain", CLI_REAL, &o->strain, R0, R1, "a number in (0, 0.5)", NULL, 0},
        {"--steps", CLI_INT, &o->steps, I0, I1, NULL, NULL, 0},
        {"--stop-after", CLI_INT, &o->stop_after, I0, I1, NULL, NULL, 0},
        {"--threads", CLI_INT, &o->threads, I0, I1, NULL, NULL, 0},
        {"--checkpoint", CLI_INT, &o->checkpoint, I0, I1, NULL, NULL, 0},
        {"--vtk-every", CLI_INT, &o->vtk_every, I0, I1, NULL, NULL, 0},
        {"--every", CLI_INT, &o->every, I0, I1, NULL, NULL, 0},
        {"--imperfection", CLI_INT, &o->imperfection, I0, I1, NULL, NULL, 0},
        {"--iuf", CLI_REAL, &o->iuf, R0, R1, "a number in (0, 1)", NULL, 0},
        {"--dem-inertial", CLI_REAL, &o->dem_inertial, R0, R1, "a number in (0, 1)", NULL, 0},
        {"--dem-min", CLI_INT, &o->dem_min, I0, I1, NULL, NULL, 0},
        {"--dem-max", CLI_INT, &o->dem_max, I0, I1, NULL, NULL, 0},
        {"--lone-increments", CLI_INT, &o->lone, I0, I1, NULL, NULL, 0},
        {"--gauss", CLI_INT, &o->gauss, I0, I1, NULL, NULL, 0},
        {"--dem-damping", CLI_REAL, &o->dem_damping, R0, R1, "a number in [0, 1)", NULL, 0},
        {"--contact-damping", CLI_REAL, &o->contact_damping, R0, R1, "a number in [0, 1)", NULL, 0},
        {"--density", CLI_REAL, &o->density, R0, R1, "a number > 0", NULL, 0},
        {"--xi", CLI_REAL, &o->xi, R0, R1, "a number in [0, 10]", NULL, 0},
        {"--mass-scale", CLI_REAL, &o->mass_scale, R0, R1, "a number > 0", NULL, 0},
        {"--hourglass", CLI_REAL, &o->kappa, R0, R1, "a number in [0, 1]", NULL, 0},
        {"--dt", CLI_REAL, &o->dt, R0, R1, "a number >= 0", NULL, 0},
        {"--dt-safety", CLI_REAL, &o->dt_safety, R0, R1, "a number in (0, 1]", NULL, 0},
        {"--amplitude", CLI_REAL, &o->amplitude, R0, R1, "a number > 0", NULL, 0},
        {"--frequency", CLI_REAL, &o->frequency, R0, R1, "a number > 0", NULL, 0},
        {"--duration", CLI_REAL, &o->duration, R0, R1, "a number > 0", NULL, 0},
        {"--front-threshold", CLI_REAL, &o->front, R0, R1, "a number in (0, 1]", NULL, 0},
        {"--packing", CLI_STR, &o->packing, 0, 0, NULL, NULL, 0},
        {"--out", CLI_STR, &o->out, 0, 0, NULL, NULL, 0},
        {"--restart", CLI_STR, &o->restart, 0, 0, NULL, NULL, 0},
        {"--paper", CLI_FLAG, &o->paper, 0, 0, NULL, NULL, 0},
        {"--imperfect-row", CLI_FLAG, &o->imperfect_row, 0, 0, NULL, NULL, 0},
        {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    const cli_opt *const tables[] = {tab, NULL};
    int help;
    memset(o, 0, sizeof *o);
    o->test = -1;
    o->R = 0.0;
    o->mix = 1.0;
    o->pressure = 4.16e5;
    o->strain = -1;
    o->steps = -1;
    o->threads = 1;
    o->checkpoint = 0;
    o->vtk_every = 0;
    o->every = -1;
    o->imperfection = -1;
    o->iuf = 0.01;
    o->dem_inertial = 2e-3;
    o->dem_min = 10;
    o->dem_max = -1;
    o->lone = 400;
    o->dem_damping = 0.2;
    o->contact_damping = -1;
    o->density = 2492.0;
    o->xi = -1;
    o->mass_scale = 1.0;
    o->kappa = NAN; /* 0.1, or 0 with --gauss 8 (a given value is finite) */
    o->gauss = 1;
    o->dt = 0.0;
    o->dt_safety = 0.5;
    o->amplitude = 1e-4;
    o->frequency = 1e4;
    o->duration = 1e-3;
    o->front = 1e-3;
    o->packing = NULL;
    test_f.fn = test_opt, test_f.dst = &o->test;
    mesh_f.fn = mesh_opt, mesh_f.dst = o->mesh;
    nonlocal_f.fn = nonlocal_opt, nonlocal_f.dst = &o->R;
    if (cli_parse("femdem_nonlocal", argc, argv, tables, &help)) return 2;
    if (help) {
        usage(stdout);
        exit(0);
    }
    if (o->test < 0) {
        fprintf(stderr, "femdem_nonlocal: --test is required (see --help)\n");
        return 2;
    }
    if (!o->out) {
        fprintf(stderr, "femdem_nonlocal: --out DIR is required\n");
        return 2;
    }
    /* test defaults */
    {
        static const int mesh[T_COUNT][3] = {{1, 1, 1},  {1, 1, 1},  {1, 1, 1},
                                             {10, 1, 1}, {5, 12, 1}, {4, 8, 1}};
        static const double strain[T_COUNT] = {2e-3, 0.05, 0.1, 0.0, 0.2, 0.08};
        static const int steps[T_COUNT] = {20, 4000, 4000, 0, 4000, 3000};
        int t = o->test, k;
        if (!o->mesh[0])
            for (k = 0; k < 3; ++k) o->mesh[k] = mesh[t][k];
        if (o->strain < 0) o->strain = strain[t];
        if (t == T_WAVE) {
            if (o->dt == 0.0) o->dt = 1e-6;
            if (o->steps < 0) o->steps = (int)floor(o->duration / o->dt + 0.5);
        }
        if (o->steps < 0) o->steps = steps[t];
        if (o->dem_max < 0) o->dem_max = t == T_BIAX && !o->paper ? 20 : 4000;
        if (!o->packing)
            o->packing = o->paper ? "examples/data/rve4096_hm.txt" : "examples/data/rve512_hm.txt";
        if (o->imperfection < 0)
            o->imperfection = t == T_SSHEAR ? -2 : 0; /* -2: 25 x N / 4096 (after reading) */
        if (o->contact_damping < 0) o->contact_damping = t == T_BIAX ? 0.0 : 0.12;
        if (o->xi < 0) o->xi = t == T_WAVE ? 0.0 : 0.3;
        if (o->every < 0)
            o->every = o->steps / (t == T_EBIAX || t == T_ESHEAR ? 1000 : 200) > 1
                           ? o->steps / (t == T_EBIAX || t == T_ESHEAR ? 1000 : 200)
                           : 1;
    }
#define REQ(c, ...)                           \
    if (!(c)) {                               \
        fprintf(stderr, "femdem_nonlocal: "); \
        fprintf(stderr, __VA_ARGS__);         \
        fputc('\n', stderr);                  \
        return 2;                             \
    }
    REQ(o->pressure > 0, "--pressure %g must be > 0 [Pa]", o->pressure);
    REQ(o->strain > 0 || o->test == T_WAVE, "--strain %g must be > 0", o->strain);
    REQ(o->strain < 0.5, "--strain %g must be below 0.5", o->strain);
    REQ(o->steps >= 1 && o->steps <= 100000000, "--steps %d must be 1-1e8", o->steps);
    REQ(o->stop_after >= 0 && o->stop_after <= o->steps, "--stop-after %d must be 0-%d (--steps)",
        o->stop_after, o->steps);
    REQ(o->threads >= 1 && o->threads <= 1024, "--threads %d must be 1-1024", o->threads);
    REQ(o->checkpoint >= 0, "--checkpoint %d must be >= 0", o->checkpoint);
    REQ(o->vtk_every >= 0, "--vtk-every %d must be >= 0", o->vtk_every);
    REQ(o->every >= 1, "--every %d must be >= 1", o->every);
    REQ(o->imperfection >= -2, "--imperfection %d must be >= 0", o->imperfection);
    REQ(!o->imperfect_row || o->imperfection != 0,
        "--imperfect-row needs an imperfection (--imperfection N > 0)");
    REQ(o->iuf > 0 && o->iuf < 1, "--iuf %g must be in (0, 1)", o->iuf);
    REQ(o->dem_inertial > 0 && o->dem_inertial < 1, "--dem-inertial %g must be in (0, 1)", o->dem_inertial);
    REQ(o->dem_min >= 1 && o->dem_max >= o->dem_min && o->dem_max <= 1000000,
        "--dem-min %d, --dem-max %d: 1 <= min <= max <= 1e6", o->dem_min, o->dem_max);
    REQ(o->lone >= 2 && o->lone <= 100000, "--lone-increments %d must be 2-100000", o->lone);
    REQ(o->dem_damping >= 0 && o->dem_damping < 1, "--dem-damping %g must be in [0, 1)", o->dem_damping);
    REQ(o->contact_damping >= 0 && o->contact_damping < 1, "--contact-damping %g must be in [0, 1)",
        o->contact_damping);
    REQ(o->density > 0, "--density %g must be > 0", o->density);
    REQ(o->xi >= 0 && o->xi <= 10, "--xi %g must be in [0, 10]", o->xi);
    REQ(o->mass_scale > 0, "--mass-scale %g must be > 0", o->mass_scale);
    REQ(o->gauss == 1 || o->gauss == 8, "--gauss %d must be 1 or 8 (Gauss points per element)", o->gauss);
    REQ(isnan(o->kappa) || (o->kappa >= 0 && o->kappa <= 1), "--hourglass %g must be in [0, 1]", o->kappa);
    REQ(o->gauss == 1 || isnan(o->kappa) || o->kappa == 0.0,
        "--hourglass %g is for one Gauss point per element: --gauss 8 has no hourglass modes to control",
        o->kappa);
    REQ(o->gauss == 1 || o->test == T_EBIAX || o->test == T_ESHEAR || o->test == T_SSHEAR ||
            o->test == T_BIAX,
        "--gauss 8 is for the element, simple-shear and biaxial tests (not --test %s)", test_name[o->test]);
    REQ(o->gauss == 1 || o->R == 0.0,
        "--gauss 8 is the local reference: --nonlocal needs one Gauss point per element (its stability bound "
        "is computed for a regular grid of points)");
    if (isnan(o->kappa)) o->kappa = o->gauss == 1 ? 0.1 : 0.0;
    REQ(o->dt >= 0, "--dt %g must be >= 0 (0: from eq 65)", o->dt);
    REQ(o->dt_safety > 0 && o->dt_safety <= 1, "--dt-safety %g must be in (0, 1]", o->dt_safety);
    REQ(o->amplitude > 0 && o->frequency > 0 && o->duration > 0,
        "--amplitude, --frequency, --duration must be > 0");
    REQ(o->front > 0 && o->front <= 1, "--front-threshold %g must be in (0, 1]", o->front);
    REQ(o->front == 1e-3 || o->test == T_WAVE, "--front-threshold is for --test wave");
    REQ(o->test != T_RVE || o->R == 0.0, "--nonlocal is for mesh tests, not --test rve");
    REQ(o->mix >= 0 && o->mix <= 1, "--nonlocal-mix %g must be in [0, 1]", o->mix);
    REQ(o->mix == 1.0 || o->R > 0.0, "--nonlocal-mix %g needs --nonlocal R", o->mix);
#undef REQ
    return 0;
}

#endif /* NONLOCAL_OPTS_H */
