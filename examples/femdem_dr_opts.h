/* femdem_dr_opts.h - the options of build/femdem_dr (examples/femdem_dr.c; examples, not library):
 * the tests, the options with their defaults, the usage text (femdem_dr --help) and the parser, on
 * examples/cli.h: every value is parsed strictly and a refused one is named (status 2).
 */
#ifndef FEMDEM_DR_OPTS_H
#define FEMDEM_DR_OPTS_H

#include "gk_frame.h"
#include "cli.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PROG "femdem_dr"

enum { TEST_BIAXIAL = 0, TEST_RVE = 1, TEST_DNS = 2 };

typedef struct opts {
    int test, nx, ny, iso_steps, steps, threads, frame, no_rotation, lock_frame, vtk_every, checkpoint,
        max_dr, servo_max, rayleigh, predictor;
    int rve_max, stop_after, material, paper;
    int tiles[2];
    double strain, pressure, friction, width, height, kn_ratio, dt_factor, damping, tol_energy, tol_dr,
        tol_servo;
    double xi, gamma, force_tol, force_stop, dns_tol;
    const char *out, *restart, *packing, *tiles_s;
} opts;

static void usage(FILE *fp) {
    fprintf(fp,
            "usage: " PROG " [--test biaxial|rve|dns] [options] --out DIR\n"
            "  --paper                 the paper's sizes: --nx 2 --ny 4 --steps 50, dns --dns-tiles 2x4\n"
            "                          (options given as well win)\n"
            "  --nx N --ny N           Q4 elements across and up (1 x 2)\n"
            "  --iso-steps N           isotropic stage in N steps (10)\n"
            "  --steps N               biaxial stage in N steps (20)\n"
            "  --strain E              final axial strain d / h_ic (0.10)\n"
            "  --pressure P            confinement sigma0 [Pa = N/m per m] (1.5e5)\n"
            "  --friction MU           contact friction (0.4)\n"
            "  --no-rotation           the paper's theta_p = 0: the inner particles do not rotate, the\n"
            "                          servo frame does (the periodic cell, the dns: no particle does)\n"
            "  --lock-frame            with --no-rotation and the servo frame: the frame does not rotate\n"
            "                          either (no moment is corrected)\n"
            "  --frame servo|periodic  RVE boundary: the servo frame (paper) or the periodic cell\n"
            "  --packing FILE          framed packing (examples/data/frame228_a002.txt)\n"
            "  --kn-ratio K            k_n / sigma0 (100)\n"
            "  --dt-factor F           DEM step / sqrt(m_min / k_n) (0.4)\n"
            "  --damping A             local damping alpha = beta (0.7)\n"
            "  --tol-energy T          RVE relaxation E_kin / E_pot (1e-3)\n"
            "  --tol-servo T           servo residual eps_a (1e-4)\n"
            "  --servo-max N           servo corrections per RVE run (20)\n"
            "  --rve-max-steps N       DEM steps per RVE run at most (20000)\n"
            "  --dr-tol T              macro DR E_kin / E_kin,max (1e-3)\n"
            "  --dr-xi X --dr-gamma G  eqs 25, 27 (1, 0.5)\n"
            "  --dr-force-tol T        also |f_ext - f_int| <= T max|f| to end a step (0: eq 28 alone)\n"
            "  --dr-force-stop T       or |f_ext - f_int| <= T max|f| alone ends a step (2e-3 with\n"
            "                          the homogeneous predictor on a mesh, else 0: eq 28 decides)\n"
            "  --rayleigh step|total   eq 26 relative to the step's start (step) or to U = 0 (total)\n"
            "  --predictor none|homogeneous  where a mesh's load step starts: the uniform specimen's\n"
            "                          next state (homogeneous: the last step's mean stretches\n"
            "                          repeated, the platen's increment spread over the height), or,\n"
            "                          as the paper writes it, the last state with only the loads and\n"
            "                          the platen moved (none)\n"
            "  --material paper|guo-zhao  the contact law above, or Guo & Zhao 2014's (femdem_biaxial's:\n"
            "                          k_n = E r*, E 0.6 GPa, k_t 0.8 k_n, friction angle 0.5, 2650 kg/m^3,\n"
            "                          0.1 m disks, damping 0.1; with --frame periodic)\n"
            "  --max-dr N              DR iterations per load step (20000)\n"
            "  --width W --height H    specimen [m] (0.01 x 0.02)\n"
            "  --dns-tiles NXxNY       dns: copies of the periodic cell (1x2)\n"
            "  --dns-tol T             dns: E_kin / E_pot that ends a biaxial load step (1e-5: the\n"
            "                          platen force is the measurement, and at eq 31's 1e-3 the curve\n"
            "                          depends on the step size)\n"
            "  --threads N             OpenMP threads over the Gauss points (1)\n"
            "  --vtk-every K           VTK every K steps (10; 0: only the last)\n"
            "  --checkpoint K          checkpoint every K steps (10)\n"
            "  --restart DIR           continue from DIR/checkpoint.bin\n"
            "  --stop-after K          stop after load step K with a checkpoint (split a long run)\n"
            "  --out DIR               output directory (required)\n");
}

/* the defaults (femdem_dr --help) */
static void dr_opts_default(opts *o) {
    memset(o, 0, sizeof *o);
    o->test = TEST_BIAXIAL, o->nx = 1, o->ny = 2, o->iso_steps = 10, o->steps = 20, o->threads = 1;
    o->frame = GK_FRAME_SERVO, o->vtk_every = 10, o->checkpoint = 10, o->max_dr = 20000, o->servo_max = 20,
    o->rve_max = 20000;
    o->tiles[0] = 1, o->tiles[1] = 2;
    o->strain = 0.10, o->pressure = 1.5e5, o->friction = 0.4, o->width = 0.01, o->height = 0.02;
    o->kn_ratio = 100.0, o->dt_factor = 0.4, o->damping = 0.7, o->tol_energy = 1e-3, o->tol_dr = 1e-3;
    o->tol_servo = 1e-4, o->xi = 1.0, o->gamma = 0.5, o->dns_tol = 1e-5;
    o->predictor = 1, o->force_stop = -1.0; /* homogeneous; the force stop follows it (parse) */
    o->packing = "examples/data/frame228_a002.txt";
}

/* the options (examples/cli.h: every value parsed strictly, a refused one named, status 2);
 * --help prints the usage and exits 0. 0, or 2 after a message. */
static int parse(int argc, char **argv, opts *o) {
    const cli_opt tab[] = {
        {"--nx", CLI_INT, &o->nx, 1, 64, NULL, NULL, 0},
        {"--ny", CLI_INT, &o->ny, 1, 128, NULL, NULL, 0},
        {"--iso-steps", CLI_INT, &o->iso_steps, 1, 100000, NULL, NULL, 0},
        {"--steps", CLI_INT, &o->steps, 1, 1000000, NULL, NULL, 0},
        {"--threads", CLI_INT, &o->threads, 1, 1024, NULL, NULL, 0},
        {"--vtk-every", CLI_INT, &o->vtk_every, 0, 1000000, NULL, NULL, 0},
        {"--checkpoint", CLI_INT, &o->checkpoint, 1, 1000000, NULL, NULL, 0},
        {"--max-dr", CLI_INT, &o->max_dr, 1, 100000000, NULL, NULL, 0},
        {"--servo-max", CLI_INT, &o->servo_max, 1, 100000, NULL, NULL, 0},
        {"--rve-max-steps", CLI_INT, &o->rve_max, 10, 100000000, NULL, NULL, 0},
        {"--stop-after", CLI_INT, &o->stop_after, 1, 100000000, NULL, NULL, 0},
        {"--strain", CLI_REAL, &o->strain, 0.0, 0.5, NULL, NULL, 0},
        /* the four positive values: any finite number here, the sign checked below */
        {"--pressure", CLI_REAL, &o->pressure, -HUGE_VAL, HUGE_VAL, "a number > 0", NULL, 0},
        {"--friction", CLI_REAL, &o->friction, 0.0, 10.0, NULL, NULL, 0},
        {"--width", CLI_REAL, &o->width, -HUGE_VAL, HUGE_VAL, "a number > 0", NULL, 0},
        {"--height", CLI_REAL, &o->height, -HUGE_VAL, HUGE_VAL, "a number > 0", NULL, 0},
        {"--kn-ratio", CLI_REAL, &o->kn_ratio, -HUGE_VAL, HUGE_VAL, "a number > 0", NULL, 0},
        {"--dt-factor", CLI_REAL, &o->dt_factor, 0.01, 1.0, NULL, NULL, 0},
        {"--damping", CLI_REAL, &o->damping, 0.0, 0.99, NULL, NULL, 0},
        {"--tol-energy", CLI_REAL, &o->tol_energy, 1e-12, 1.0, NULL, NULL, 0},
        {"--tol-servo", CLI_REAL, &o->tol_servo, 1e-15, 1.0, NULL, NULL, 0},
        {"--dr-tol", CLI_REAL, &o->tol_dr, 1e-12, 0.5, NULL, NULL, 0},
        {"--dr-xi", CLI_REAL, &o->xi, 1e-6, 100.0, NULL, NULL, 0},
        {"--dr-gamma", CLI_REAL, &o->gamma, 1e-6, 1.0, NULL, NULL, 0},
        {"--dr-force-tol", CLI_REAL, &o->force_tol, 0.0, 1.0, NULL, NULL, 0},
        {"--dr-force-stop", CLI_REAL, &o->force_stop, 0.0, 1.0, NULL, NULL, 0},
        {"--rayleigh", CLI_CHOICE, &o->rayleigh, 0, 0, NULL, "step|total", 0},
        {"--predictor", CLI_CHOICE, &o->predictor, 0, 0, NULL, "none|homogeneous", 0},
        {"--material", CLI_CHOICE, &o->material, 0, 0, NULL, "paper|guo-zhao", 0},
        {"--out", CLI_STR, &o->out, 0, 0, NULL, NULL, 0},
        {"--restart", CLI_STR, &o->restart, 0, 0, NULL, NULL, 0},
        {"--packing", CLI_STR, &o->packing, 0, 0, NULL, NULL, 0},
        {"--test", CLI_CHOICE, &o->test, 0, 0, NULL, "biaxial|rve|dns", 0},  /* index: TEST_* */
        {"--frame", CLI_CHOICE, &o->frame, 0, 0, NULL, "servo|periodic", 0}, /* index: gk_frame_kind */
        {"--dns-tiles", CLI_STR, &o->tiles_s, 0, 0, NULL, NULL, 0},
        {"--dns-tol", CLI_REAL, &o->dns_tol, 1e-12, 1.0, NULL, NULL, 0},
        {"--no-rotation", CLI_FLAG, &o->no_rotation, 0, 0, NULL, NULL, 0},
        {"--lock-frame", CLI_FLAG, &o->lock_frame, 0, 0, NULL, NULL, 0},
        {"--paper", CLI_FLAG, &o->paper, 0, 0, NULL, NULL, 0},
        {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    const cli_opt *const tables[] = {tab, NULL};
    const char *pos_name[4] = {"--pressure", "--width", "--height", "--kn-ratio"};
    double pos[4];
    int i, k, help;
    for (i = 1; i < argc; ++i) /* --paper first: the options given with it win wherever they stand */
        if (!strcmp(argv[i], "--paper"))
            o->nx = 2, o->ny = 4, o->steps = 50, o->tiles[0] = 2, o->tiles[1] = 4;
    if (cli_parse(PROG, argc, argv, tables, &help)) return 2;
    if (help) {
        usage(stdout);
        exit(0);
    }
    pos[0] = o->pressure, pos[1] = o->width, pos[2] = o->height, pos[3] = o->kn_ratio;
    for (k = 0; k < 4; ++k)
        if (!(pos[k] > 0.0)) {
            fprintf(stderr, PROG ": %s %g must be > 0\n", pos_name[k], pos[k]);
            return 2;
        }
    for (k = 0; tab[k].name; ++k)
        if (tab[k].kind == CLI_STR && *(const char **)tab[k].dst && !**(const char **)tab[k].dst) {
            fprintf(stderr, PROG ": %s needs a non-empty value\n", tab[k].name);
            return 2;
        }
    if (o->material == 1 && o->frame == GK_FRAME_SERVO) {
        fprintf(stderr,
                PROG ": --material guo-zhao (k_n = E r*) needs --frame periodic: the servo's gains are per "
                     "constant k_n\n");
        return 2;
    }
    if (o->tiles_s) {
        int a = 0, b = 0, n = 0;
        if (sscanf(o->tiles_s, "%dx%d%n", &a, &b, &n) != 2 || o->tiles_s[n] || a < 1 || b < 1 || a > 16 ||
            b > 16) {
            fprintf(stderr, PROG ": --dns-tiles '%s' must be NXxNY with 1 <= NX, NY <= 16 (e.g. 1x2)\n",
                    o->tiles_s);
            return 2;
        }
        o->tiles[0] = a, o->tiles[1] = b;
    }
    if (o->lock_frame && (!o->no_rotation || o->frame != GK_FRAME_SERVO || o->test == TEST_DNS)) {
        fprintf(stderr, PROG ": --lock-frame goes with --no-rotation and the servo frame (the periodic "
                             "cell and the dns lock every particle already)\n");
        return 2;
    }
    if (!o->out) {
        fprintf(stderr, PROG ": --out DIR is required (see --help)\n");
        return 2;
    }
    if (o->force_stop < 0.0) /* a predicted step starts near equilibrium: eq 28 cannot judge it alone */
        o->force_stop = o->predictor == 1 && o->test == TEST_BIAXIAL ? 2e-3 : 0.0;
    return 0;
}

/* the rotation lock: ROT_FREE; ROT_ALL every particle (GK_RVE_NO_ROTATION); ROT_INNER the inner
 * particles, the servo frame turning (gk_frame_def.lock_inner) */
enum { ROT_FREE = 0, ROT_ALL = 1, ROT_INNER = 2 };
static int rotation_lock(const opts *o) {
    if (!o->no_rotation) return ROT_FREE;
    return o->frame == GK_FRAME_SERVO && o->test != TEST_DNS && !o->lock_frame ? ROT_INNER : ROT_ALL;
}
static const char *rotation_name(const opts *o) {
    static const char *const name[3] = {"free", "locked", "locked-inner"};
    return name[rotation_lock(o)];
}

#endif /* FEMDEM_DR_OPTS_H */
