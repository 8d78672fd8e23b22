/* femdem_dr - FEMxDEM by explicit adaptive dynamic relaxation with servo-framed
 * RVEs, and the same specimen as one DEM simulation (Liu, Bosco & Suiker 2018).
 *
 *   build/femdem_dr --out DIR            the reduced run: 1 x 2 mesh (8 RVEs), 10 + 20 steps
 *   build/femdem_dr --paper --out DIR    the paper's parametric mesh 2 x 4 (32 RVEs), 10 + 50 steps
 *   build/femdem_dr --test biaxial --nx N --ny M --threads 2 --out DIR
 *                   [--iso-steps 10 --steps 20 --strain 0.10 --pressure 1.5e5 --friction 0.4]
 *                   [--no-rotation] [--frame servo|periodic] [--packing FILE] [--restart DIR]
 *   build/femdem_dr --test rve ...          the RVE alone on the same stress path
 *   build/femdem_dr --test dns --dns-tiles 1x2|2x4 ...   the specimen as one DEM scene
 *
 * THE MODEL (Liu, Bosco & Suiker 2018 sec 4.1). A 10 x 20 mm specimen,
 * total-Lagrange bilinear quadrilaterals (Q4, 2 x 2 Gauss points), bottom
 * edge supported vertically, lower-left node horizontally. Stage 1: the
 * pressure sigma0 on the left, right and top edges in --iso-steps equal
 * steps. Stage 2: the top edge (a smooth rigid platen: one vertical
 * displacement, free horizontally) moves down by d = eps h_ic in --steps
 * steps to --strain, h_ic the height after stage 1, the sides still at
 * sigma0. Pressures are follower loads on the current edges (Cauchy
 * tractions). 2D stresses are per unit thickness: N/m, printed as Pa with
 * a 1 m thick specimen.
 *
 * THE MACRO SOLVER (gk_explicit.h): every load step is relaxed by adaptive
 * dynamic relaxation (eqs 20-29): HRZ lumped masses of density
 * rho v_m = 2000 x 0.82 kg/m^2 (eq 24), C = alpha M with alpha = 2 xi omega
 * (eq 25), omega from the Rayleigh quotient of eq 26 (U and f_int taken
 * relative to the unloaded state, whose f_int is the packing's own small
 * stress), dt = gamma (2 / omega)(sqrt(xi^2 + 1) - xi) (eq 27, xi 1, gamma
 * 0.5), bounded by the element frequencies (gk_explicit_elem_omega with
 * twice the Taylor tangent of the packing: an upper bound, since the
 * particles only soften it), converged when E_kin / E_kin,max <= --dr-tol
 * (eq 28, 1e-3). Velocities start from 0 at every load step. Every DR
 * iteration (Table 1) computes F = I + dU/dX at each Gauss point, runs its
 * RVE from its last state by dF (gk_twoscale.h with a gk_frame.h
 * procedure), takes P back and assembles f_int = int B^T P dV0
 * (gk_fem_elem_force on the reference mesh). No tangent anywhere.
 *
 * THE RVE (gk_frame.h, one per Gauss point): the 228-particle framed
 * packing examples/data/frame228_a002.txt (205 disks of the periodic cell,
 * radii uniform in 0.30-0.45 mm, cell 10.6 mm, 10 + 10 + 1 of them centred
 * on the cell boundary: P = 184 inner and Q = 44 boundary particles).
 *   --frame servo (default, the paper's): the boundary particles are
 *     prescribed to F X_q + w_q and servo-controlled to periodicity
 *     (eqs 5-14, 33-37, Table 2), P from the boundary forces (eq 14);
 *   --frame periodic (grainkit's): the 205 disks in the periodic cell
 *     deformed with F, P = det F sigma F^-T from the Love stress.
 * Both relax to E_kin / E_pot <= --tol-energy (eqs 30-32, 1e-3).
 * Contact law (eq 10): linear, k_s = 0.2 k_n, Coulomb mu = --friction, local
 * non-viscous damping 0.7 on translation and rotation, disks of density
 * 2000 kg/m^3 and thickness 1 m. STIFFNESS: Table 3 gives k_n = 1e4 N/m with
 * sigma0 = 0.15 MN/m, which would make the overlaps ~15 particle diameters;
 * the response of a linear-contact packing depends on k_n only through
 * k_n / sigma0 (and R_min / L, R_max / R_min), so k_n is set as a ratio to
 * the confinement, --kn-ratio 100 (k_n = 1.5e7 N/m: overlaps ~ 1e-2 of a
 * diameter at sigma0). DEM step 0.4 sqrt(m_min / k_n) = 2.5 us (the paper:
 * 1 us). --no-rotation locks every particle's rotation (the paper's
 * theta_p = 0). --packing takes another framed packing (the anisotropic
 * ones: frame228_a005.txt, frame228_a008.txt).
 *
 * --test rve: the RVE alone on the same path: a homogeneous specimen (F =
 * diag(F11, F22), the two edge displacements relaxed by the same DR with
 * the masses of the 1 x 1 mesh), i.e. what the 1 x 1 mesh does when its four
 * RVEs stay alike.
 *
 * --test dns: the specimen as one DEM scene (gk_scene.h): the periodic
 * packing tiled --dns-tiles NXxNY times (1x2: 2L x L, 2x4: 4L x 2L; the
 * paper's DNS A and B with 441 and 1681 disks; here 205 NX NY disks plus
 * the boundary copies closing the right and top edges: 444 for 1x2), the
 * same contact law; bottom and top rigid frictionless platens (walls), the
 * sides confined by follower-pressure membranes along the boundary
 * particles (anchored to the platens, tension-only links), the top platen
 * servo-controlled to sigma0 in stage 1, then displacement-driven; every
 * load step relaxed to the same E_kin / E_pot. The paper drives its DNS by
 * the servo frame of Liu et al. (2017) (tractions in stage 1,
 * displacements in stage 2); walls and membranes are the closest
 * equivalent grainkit has. Stresses from the platen force and the
 * membrane pressure.
 *
 * OUTPUTS in DIR (every failed write: exit status 1)
 *   dr.csv       step,stage,eps_axial,sigma_bar,sigma_11,sigma_22,J,coordination,anisotropy,
 *                dr_iterations,dem_steps,seconds
 *                one row per load step (step 0: the unloaded state). stage 1 isotropic, 2
 *                biaxial. eps_axial = (h_ref - h) / h_ref (h_ref = h_0 in stage 1, h_ic in
 *                stage 2, eq 41); sigma_11, sigma_22: mean Cauchy stress over the Gauss
 *                points (eq 16; dns: the side pressure and the platen force / width),
 *                COMPRESSION POSITIVE [Pa = N/m per m]; sigma_bar = |(s11 - s22) / (s11 +
 *                s22)| (eq 40) averaged over the Gauss points; J = J_rel = (det F - det F_ic) /
 *                det F_ic in stage 2, det F - 1 in stage 1 (mean over the Gauss points);
 *                coordination 2 C / (P + Q) and anisotropy Pi_1 / Pi_2 - 1 (eqs 38-39) of the
 *                RVEs, averaged; dr_iterations of the step; dem_steps: all DEM steps of the
 *                step (every Gauss point, every iteration)
 *   mesh_NNNN.vtk, gp_NNNN.vtk   every --vtk-every steps: the deformed mesh (displacement;
 *                per element sigma_bar, J, deq) and the Gauss points (sigma_11, sigma_22,
 *                sigma_bar, J, coordination, anisotropy, deq = |dF| of the last step,
 *                dem_steps)
 *   dr_stress.svg (sigma_bar vs eps), dr_volume.svg (J_rel vs eps), dr_fabric.svg
 *                (coordination and 10 x anisotropy vs eps), deq_field.svg (the incremental
 *                equivalent strain of the last step on the deformed mesh, Fig 7)
 *   checkpoint.bin  every --checkpoint steps, at --stop-after K and at the end
 *                (gk_twoscale_save; the macro state in its driver block); --restart DIR
 *                continues from DIR/checkpoint.bin to the same rows (only the seconds differ)
 *   RESULT peak_sigma_bar=... eps_at_peak=... sigma_bar_0073=... anisotropy_0073=...
 *          eps_dilation=... dr_iterations_mean=... seconds=... (+ dem_steps_per_run,
 *          rve_capped_runs: RVE runs stopped by --servo-max or --rve-max-steps before their
 *          tolerance, dr_unconverged_steps: load steps stopped by --max-dr)
 *          eps_dilation: the strain of the smallest J_rel (compaction turns to dilation).
 *
 * RESULTS (the reduced load path: 10 + 20 steps, 0.5 % per biaxial step, 1 thread; from
 * `build/femdem_dr [--nx N --ny M] [--frame periodic] [--test rve|dns] --vtk-every 0 --out DIR`;
 * sigma_bar at axial strain 1, 2, 3, 5 %, its peak, sigma_bar and A at 7.3 %, all RVE DEM steps)
 *   run                 1 %    2 %    3 %    5 %    peak          7.3 %: s_bar  A      DEM steps
 *   servo, RVE alone    0.187  0.294  0.343  0.370  0.383 at 6.5  0.332  0.295  2.3e5
 *   servo, 1 x 1        0.187  0.296  0.341  0.372  0.378 at 5.5  0.309  0.285  2.8e6
 *   servo, 1 x 2        0.174  0.279  0.335  0.365  0.365 at 5.0  0.323  0.292  5.0e6
 *   servo, 2 x 4        0.169  0.271  0.327  0.360  0.360 at 5.0  0.317  0.256  2.3e7
 *   periodic, RVE alone 0.207  0.314  0.345  0.358  0.370 at 4.5  0.325  0.240  2.1e4
 *   periodic, 1 x 1     0.208  0.311  0.339  0.337  0.363 at 4.5  0.331  0.249  1.7e5
 *   periodic, 1 x 2     0.204  0.308  0.338  0.349  0.356 at 4.0  0.340  0.241  4.2e5
 *   periodic, 2 x 4     0.199  0.300  0.329  0.350  0.351 at 4.5  0.330  0.245  3.1e6
 *   periodic, 4 x 8     0.191  0.292  0.321  0.340  0.340 at 5.0  0.292  0.197  1.3e7
 *   DNS 1x2 (444 disks) 0.181  0.287  0.304  0.180  0.312 at 7.5  0.308  0.165  (2.0e6 of 444)
 *   --paper --frame periodic (2 x 4, 10 + 50 steps of 0.2 %): peak 0.357 at 4.0 %, at 7.3 %
 *     0.334 and A 0.247, 4.1e6 DEM steps; --paper (servo): 2.2e7 DEM steps to 2 % (sigma_bar
 *     0.278 there, 0.271 with 0.5 % steps), 2-3e6 per step from there: >= 1.2e8 to 10 %.
 *   periodic 2 x 4, mu 0.2 / 0.6:  peaks 0.235 at 7.0 / 0.420 at 5.5 %; coordination at 7.3 %
 *     4.10 / 3.76 (mu 0.4: 3.89); locked rotation: 0.590 at 7.5 %, at 7.3 % sigma_bar 0.590,
 *     A 0.304; packings with A0 0.05 / 0.08: peaks 0.352 at 5.0 / 0.352 at 4.0 %.
 * Against Liu, Bosco & Suiker (2018), who give numbers only for Figs 10-11 (at 7.3 %: free
 * 0.39, locked 0.48; A 0.27 and 0.33): the locked rotation is stronger and more anisotropic
 * (A ratio free / locked 0.81 here, 0.82 there) but far stronger here (stress ratio 0.56,
 * there 0.81); the peak comes earlier (4-5 %, there near 7 %); higher friction gives a higher
 * stress and a lower coordination as there, but not their larger compaction; the initial
 * anisotropy changes nothing here (there: a lower, earlier peak). The meshes agree within
 * 10 % to 5 % strain (the paper: "very close"; the largest spread at 1 %); the servo frame
 * and the periodic cell within 10 % (RVE alone) to 15 % (2 x 4); the 444-disk DNS within
 * 11 % of the 2 x 4 meshes to 3 %, then it slips (0.30 to 0.18 at 3.5 %, back to 0.31 at
 * 7.5 %: a specimen a few grains wide). The packings are looser than the paper's (solid
 * fraction 0.82 against 0.846) and the DEM is stiffer relative to the confinement than
 * Table 3's raw numbers allow (see THE RVE).
 */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_explicit.h"
#include "gk_fem.h"
#include "gk_frame.h"
#include "gk_io.h"
#include "gk_twoscale.h"
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>

#define PROG "femdem_dr"
#define NCOL 12 /* columns of dr.csv */
#define RHO 2000.0
#define CK_MAGIC 0x31524446u /* "FDR1" */

enum { TEST_BIAXIAL = 0, TEST_RVE = 1, TEST_DNS = 2 };

typedef struct opts {
    int test, nx, ny, iso_steps, steps, threads, frame, no_rotation, vtk_every, checkpoint, max_dr, servo_max, rayleigh;
    int rve_max, stop_after, material, paper;
    int tiles[2];
    double strain, pressure, friction, width, height, kn_ratio, dt_factor, damping, tol_energy, tol_dr, tol_servo;
    double xi, gamma, force_tol;
    const char *out, *restart, *packing, *test_s, *frame_s, *tiles_s, *rayleigh_s, *material_s;
} opts;

/* ------------------------------------------------------------------ options */
typedef enum { O_INT, O_REAL, O_STR, O_FLAG } okind;
typedef struct optdef {
    const char *name;
    okind kind;
    void *dst;
    double lo, hi; /* closed range (O_INT, O_REAL); lo > hi: positive */
} optdef;

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
            "  --no-rotation           particles do not rotate\n"
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
            "  --rayleigh step|total   eq 26 relative to the step's start (step) or to U = 0 (total)\n"
            "  --material paper|guo-zhao  the contact law above, or Guo & Zhao 2014's (femdem_biaxial's:\n"
            "                          k_n = E r*, E 0.6 GPa, k_t 0.8 k_n, friction angle 0.5, 2650 kg/m^3,\n"
            "                          0.1 m disks, damping 0.1; with --frame periodic)\n"
            "  --max-dr N              DR iterations per load step (20000)\n"
            "  --width W --height H    specimen [m] (0.01 x 0.02)\n"
            "  --dns-tiles NXxNY       dns: copies of the periodic cell (1x2)\n"
            "  --threads N             OpenMP threads over the Gauss points (1)\n"
            "  --vtk-every K           VTK every K steps (10; 0: only the last)\n"
            "  --checkpoint K          checkpoint every K steps (10)\n"
            "  --restart DIR           continue from DIR/checkpoint.bin\n"
            "  --stop-after K          stop after load step K with a checkpoint (split a long run)\n"
            "  --out DIR               output directory (required)\n");
}

static int parse(int argc, char **argv, opts *o) {
    const optdef tab[] = {
        {"--nx", O_INT, &o->nx, 1, 64},
        {"--ny", O_INT, &o->ny, 1, 128},
        {"--iso-steps", O_INT, &o->iso_steps, 1, 100000},
        {"--steps", O_INT, &o->steps, 1, 1000000},
        {"--threads", O_INT, &o->threads, 1, 1024},
        {"--vtk-every", O_INT, &o->vtk_every, 0, 1000000},
        {"--checkpoint", O_INT, &o->checkpoint, 1, 1000000},
        {"--max-dr", O_INT, &o->max_dr, 1, 100000000},
        {"--servo-max", O_INT, &o->servo_max, 1, 100000},
        {"--rve-max-steps", O_INT, &o->rve_max, 10, 100000000},
        {"--stop-after", O_INT, &o->stop_after, 1, 100000000},
        {"--strain", O_REAL, &o->strain, 0.0, 0.5},
        {"--pressure", O_REAL, &o->pressure, 1, 0},
        {"--friction", O_REAL, &o->friction, 0.0, 10.0},
        {"--width", O_REAL, &o->width, 1, 0},
        {"--height", O_REAL, &o->height, 1, 0},
        {"--kn-ratio", O_REAL, &o->kn_ratio, 1, 0},
        {"--dt-factor", O_REAL, &o->dt_factor, 0.01, 1.0},
        {"--damping", O_REAL, &o->damping, 0.0, 0.99},
        {"--tol-energy", O_REAL, &o->tol_energy, 1e-12, 1.0},
        {"--tol-servo", O_REAL, &o->tol_servo, 1e-15, 1.0},
        {"--dr-tol", O_REAL, &o->tol_dr, 1e-12, 0.5},
        {"--dr-xi", O_REAL, &o->xi, 1e-6, 100.0},
        {"--dr-gamma", O_REAL, &o->gamma, 1e-6, 1.0},
        {"--dr-force-tol", O_REAL, &o->force_tol, 0.0, 1.0},
        {"--rayleigh", O_STR, &o->rayleigh_s, 0, 0},
        {"--material", O_STR, &o->material_s, 0, 0},
        {"--out", O_STR, &o->out, 0, 0},
        {"--restart", O_STR, &o->restart, 0, 0},
        {"--packing", O_STR, &o->packing, 0, 0},
        {"--test", O_STR, &o->test_s, 0, 0},
        {"--frame", O_STR, &o->frame_s, 0, 0},
        {"--dns-tiles", O_STR, &o->tiles_s, 0, 0},
        {"--no-rotation", O_FLAG, &o->no_rotation, 0, 0},
        {"--paper", O_FLAG, &o->paper, 0, 0},
        {NULL, O_FLAG, NULL, 0, 0}};
    int i;
    for (i = 1; i < argc; ++i) /* --paper first: the options given with it win wherever they stand */
        if (!strcmp(argv[i], "--paper")) o->nx = 2, o->ny = 4, o->steps = 50, o->tiles[0] = 2, o->tiles[1] = 4;
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i], *v;
        const optdef *d;
        char *end;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            exit(0);
        }
        for (d = tab; d->name && strcmp(d->name, a); ++d) continue;
        if (!d->name) {
            fprintf(stderr, PROG ": unknown option %s (see --help)%s\n", a,
                    strchr(a, '=') ? "; values follow the option after a space" : "");
            return 2;
        }
        if (d->kind == O_FLAG) {
            *(int *)d->dst = 1;
            continue;
        }
        if (i + 1 >= argc) {
            fprintf(stderr, PROG ": %s needs a value\n", a);
            return 2;
        }
        v = argv[++i];
        if (d->kind == O_STR) {
            if (!*v) {
                fprintf(stderr, PROG ": %s needs a non-empty value\n", a);
                return 2;
            }
            *(const char **)d->dst = v;
        } else if (d->kind == O_INT) {
            long x;
            errno = 0;
            x = strtol(v, &end, 10);
            if (end == v || *end || errno == ERANGE) {
                fprintf(stderr, PROG ": %s '%s' is not a whole number\n", a, v);
                return 2;
            }
            if (x < (long)d->lo || x > (long)d->hi) {
                fprintf(stderr, PROG ": %s %ld is out of range [%.0f, %.0f]\n", a, x, d->lo, d->hi);
                return 2;
            }
            *(int *)d->dst = (int)x;
        } else {
            double x;
            errno = 0;
            x = strtod(v, &end);
            if (end == v || *end || errno == ERANGE || !isfinite(x)) {
                fprintf(stderr, PROG ": %s '%s' is not a finite number\n", a, v);
                return 2;
            }
            if (d->lo > d->hi ? !(x > 0.0) : (x < d->lo || x > d->hi)) {
                if (d->lo > d->hi)
                    fprintf(stderr, PROG ": %s %g must be > 0\n", a, x);
                else
                    fprintf(stderr, PROG ": %s %g is out of range [%g, %g]\n", a, x, d->lo, d->hi);
                return 2;
            }
            *(double *)d->dst = x;
        }
    }
    if (o->test_s) {
        if (!strcmp(o->test_s, "biaxial")) o->test = TEST_BIAXIAL;
        else if (!strcmp(o->test_s, "rve")) o->test = TEST_RVE;
        else if (!strcmp(o->test_s, "dns")) o->test = TEST_DNS;
        else {
            fprintf(stderr, PROG ": --test '%s' must be biaxial, rve or dns\n", o->test_s);
            return 2;
        }
    }
    if (o->frame_s) {
        if (!strcmp(o->frame_s, "servo")) o->frame = GK_FRAME_SERVO;
        else if (!strcmp(o->frame_s, "periodic")) o->frame = GK_FRAME_PERIODIC;
        else {
            fprintf(stderr, PROG ": --frame '%s' must be servo or periodic\n", o->frame_s);
            return 2;
        }
    }
    if (o->material_s) {
        if (!strcmp(o->material_s, "paper")) o->material = 0;
        else if (!strcmp(o->material_s, "guo-zhao")) o->material = 1;
        else {
            fprintf(stderr, PROG ": --material '%s' must be paper or guo-zhao\n", o->material_s);
            return 2;
        }
        if (o->material == 1 && o->frame == GK_FRAME_SERVO) {
            fprintf(stderr, PROG ": --material guo-zhao (k_n = E r*) needs --frame periodic: the servo's gains are per "
                            "constant k_n\n");
            return 2;
        }
    }
    if (o->rayleigh_s) {
        if (!strcmp(o->rayleigh_s, "step")) o->rayleigh = 0;
        else if (!strcmp(o->rayleigh_s, "total")) o->rayleigh = 1;
        else {
            fprintf(stderr, PROG ": --rayleigh '%s' must be step or total\n", o->rayleigh_s);
            return 2;
        }
    }
    if (o->tiles_s) {
        int a = 0, b = 0, n = 0;
        if (sscanf(o->tiles_s, "%dx%d%n", &a, &b, &n) != 2 || o->tiles_s[n] || a < 1 || b < 1 || a > 16 || b > 16) {
            fprintf(stderr, PROG ": --dns-tiles '%s' must be NXxNY with 1 <= NX, NY <= 16 (e.g. 1x2)\n", o->tiles_s);
            return 2;
        }
        o->tiles[0] = a, o->tiles[1] = b;
    }
    if (!o->out) {
        fprintf(stderr, PROG ": --out DIR is required (see --help)\n");
        return 2;
    }
    return 0;
}

/* ------------------------------------------------------------------ model */
typedef struct row {
    double v[NCOL];
} row;

typedef struct model {
    opts o;
    int single;             /* --test rve: one point, two dofs                          */
    gk_mesh mesh;
    gk_quad q;
    int ngp, ndof, nnode;
    double *dNdX, *wgp;     /* per Gauss point: 8 derivatives, detJ x weight (reference) */
    double *mass, *u, *v, *fint, *fext, *f0, *u0, *P, *H, *Hacc, *dH, *deq;
    unsigned char *fixed;
    int *top, ntop, *edge, nedge; /* top nodes; loaded boundary edges (a, b, side 0 right 1 top 2 left) */
    gk_packing pk;
    gk_frame fr;
    gk_frame_set fs;
    gk_frame_stats *stats;
    gk_twoscale ts;
    gk_dr dr;
    double omega_max, h0, h_ic, J_ic, t0;
    row *rows;
    int nrows, caprows, step_done, have_f0;
    long long dem_total, runs_total, capped_total, unconverged;
} model;

static void die_alloc(void) {
    fprintf(stderr, PROG ": out of memory\n");
    exit(1);
}
static void *xcalloc(size_t n, size_t s) {
    void *p = calloc(n ? n : 1, s);
    if (!p) die_alloc();
    return p;
}

static gk_rve_def rve_def(const opts *o) {
    gk_rve_def d = gk_rve_def_default();
    if (o->material == 1) { /* Guo & Zhao 2014's, as examples/femdem_biaxial.c: E r*, their YADE time step */
        d.dt = 3.1602315723728926e-05;
        d.flags = o->no_rotation ? GK_RVE_NO_ROTATION : 0u;
        return d;
    }
    d.mat.law = GK_LAW_LINEAR;
    d.mat.kn = o->kn_ratio * o->pressure;
    d.mat.kt_ratio = 0.2;
    d.mat.friction = o->friction;
    d.mat.density = RHO;
    d.thickness = 1.0;
    d.damping = o->damping;
    d.damping_form = GK_DAMP_COMPONENT;
    d.dt_factor = o->dt_factor;
    d.flags = o->no_rotation ? GK_RVE_NO_ROTATION : 0u;
    return d;
}

/* the specimen's mean density rho v_m (eq 24) from the packing's solid fraction */
static double macro_density(const gk_packing *pk) {
    double a = 0.0;
    int p;
    for (p = 0; p < pk->n; ++p) a += GK_PI * pk->r[p] * pk->r[p];
    return RHO * a / (pk->h[0] * pk->h[4]);
}

/* H = dU/dX at every Gauss point */
static void gradients(const model *m, const double *u, double *H) {
    int g;
    if (m->single) {
        memset(H, 0, 9 * sizeof(double));
        H[0] = u[0] / m->o.width, H[4] = u[1] / m->o.height;
        return;
    }
    for (g = 0; g < m->ngp; ++g) gk_fem_grad(&m->mesh, g / m->q.n, m->dNdX + 8 * (size_t)g, u, H + 9 * (size_t)g);
}

/* f_int = int B^T P dV0 */
static void internal_force(const model *m, const double *P, double *f) {
    int e, a, k;
    memset(f, 0, (size_t)m->ndof * sizeof(double));
    if (m->single) {
        f[0] = P[0] * m->o.height, f[1] = P[4] * m->o.width;
        return;
    }
    for (e = 0; e < m->mesh.nelem; ++e)
        for (k = 0; k < m->q.n; ++k) {
            int g = e * m->q.n + k;
            const double *s = P + 9 * (size_t)g, *dN = m->dNdX + 8 * (size_t)g;
            for (a = 0; a < 4; ++a) {
                int n = m->mesh.conn[4 * e + a];
                f[2 * n] += m->wgp[g] * (s[0] * dN[2 * a] + s[1] * dN[2 * a + 1]);
                f[2 * n + 1] += m->wgp[g] * (s[3] * dN[2 * a] + s[4] * dN[2 * a + 1]);
            }
        }
}

/* follower pressures on the current edges: p_side on the sides, p_top on the top */
static void external_force(const model *m, const double *u, double p_side, double p_top, double *f) {
    int k;
    memset(f, 0, (size_t)m->ndof * sizeof(double));
    if (m->single) {
        f[0] = -p_side * (m->o.height + u[1]);
        f[1] = -p_top * (m->o.width + u[0]);
        return;
    }
    for (k = 0; k < m->nedge; ++k) {
        int a = m->edge[3 * k], b = m->edge[3 * k + 1], side = m->edge[3 * k + 2];
        double xa = m->mesh.x[2 * a] + u[2 * a], ya = m->mesh.x[2 * a + 1] + u[2 * a + 1];
        double xb = m->mesh.x[2 * b] + u[2 * b], yb = m->mesh.x[2 * b + 1] + u[2 * b + 1];
        double p = side == 1 ? p_top : p_side, fx, fy;
        /* counter-clockwise edge a -> b: outward normal x length = (dy, -dx); traction -p n */
        fx = -p * (yb - ya), fy = p * (xb - xa);
        f[2 * a] += 0.5 * fx, f[2 * a + 1] += 0.5 * fy;
        f[2 * b] += 0.5 * fx, f[2 * b + 1] += 0.5 * fy;
    }
}

/* counter-clockwise boundary edges of the structured mesh on the right, top and left sides */
static void boundary_edges(model *m) {
    int nx = m->o.nx, ny = m->o.ny, i, j, k = 0;
    m->edge = (int *)xcalloc(3 * (size_t)(2 * ny + nx), sizeof(int));
    /* node (i, j) of a structured Q4 mesh: j (nx + 1) + i (gk_mesh_structured, x fastest) */
    for (j = 0; j < ny; ++j) /* right, upwards */
        m->edge[3 * k] = j * (nx + 1) + nx, m->edge[3 * k + 1] = (j + 1) * (nx + 1) + nx, m->edge[3 * k + 2] = 0, ++k;
    for (i = nx; i > 0; --i) /* top, leftwards */
        m->edge[3 * k] = ny * (nx + 1) + i, m->edge[3 * k + 1] = ny * (nx + 1) + i - 1, m->edge[3 * k + 2] = 1, ++k;
    for (j = ny; j > 0; --j) /* left, downwards */
        m->edge[3 * k] = j * (nx + 1), m->edge[3 * k + 1] = (j - 1) * (nx + 1), m->edge[3 * k + 2] = 2, ++k;
    m->nedge = k;
}

static double mean_top(const model *m, const double *u) {
    double s = 0.0;
    int k;
    if (m->single) return m->o.height + u[1];
    for (k = 0; k < m->ntop; ++k) s += m->mesh.x[2 * m->top[k] + 1] + u[2 * m->top[k] + 1];
    return s / m->ntop;
}

/* ------------------------------------------------------------------ setup */
static int setup(model *m) {
    const opts *o = &m->o;
    gk_err err;
    gk_twoscale_def d;
    gk_twoscale_proto pr;
    int e, g, k;
    if (gk_packing_read(o->packing, &m->pk, NULL, &err)) {
        fprintf(stderr, PROG ": %s\n", err.msg);
        return 1;
    }
    if (o->frame == GK_FRAME_SERVO && gk_frame_build(&m->fr, &m->pk, NULL, &err)) {
        fprintf(stderr, PROG ": %s: %s\n", o->packing, err.msg);
        return 1;
    }
    if (m->single) {
        m->ngp = 1, m->ndof = 2;
        m->wgp = (double *)xcalloc(1, sizeof(double));
        m->wgp[0] = o->width * o->height;
    } else {
        int n[3];
        double org[3] = {0, 0, 0}, len[3];
        n[0] = o->nx, n[1] = o->ny, n[2] = 1;
        len[0] = o->width, len[1] = o->height, len[2] = 0;
        if (gk_mesh_structured(&m->mesh, GK_Q4, n, org, len, NULL, &err) || gk_quad_rule(&m->q, GK_Q4, 2, &err)) {
            fprintf(stderr, PROG ": %s\n", err.msg);
            return 1;
        }
        m->nnode = m->mesh.nnode, m->ndof = 2 * m->nnode, m->ngp = m->mesh.nelem * m->q.n;
        m->dNdX = (double *)xcalloc(8 * (size_t)m->ngp, sizeof(double));
        m->wgp = (double *)xcalloc((size_t)m->ngp, sizeof(double));
        for (e = 0; e < m->mesh.nelem; ++e)
            for (k = 0; k < m->q.n; ++k) {
                double detJ;
                g = e * m->q.n + k;
                if (gk_fem_jacobian(&m->mesh, e, m->q.xi[k], NULL, m->dNdX + 8 * (size_t)g, &detJ, &err)) {
                    fprintf(stderr, PROG ": %s\n", err.msg);
                    return 1;
                }
                m->wgp[g] = detJ * m->q.w[k];
            }
        boundary_edges(m);
        m->top = (int *)xcalloc((size_t)o->nx + 1, sizeof(int));
        m->ntop = gk_mesh_nodes_on_plane(&m->mesh, 1, o->height, 1e-9 * o->height, m->top);
    }
    m->mass = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->u = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->v = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->fint = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->fext = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->f0 = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->u0 = (double *)xcalloc((size_t)m->ndof, sizeof(double));
    m->fixed = (unsigned char *)xcalloc((size_t)m->ndof, 1);
    m->P = (double *)xcalloc(9 * (size_t)m->ngp, sizeof(double));
    m->H = (double *)xcalloc(9 * (size_t)m->ngp, sizeof(double));
    m->Hacc = (double *)xcalloc(9 * (size_t)m->ngp, sizeof(double));
    m->dH = (double *)xcalloc(9 * (size_t)m->ngp, sizeof(double));
    m->deq = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    m->stats = (gk_frame_stats *)xcalloc((size_t)m->ngp, sizeof(gk_frame_stats));
    /* masses (eq 24) and supports */
    {
        double rho = macro_density(&m->pk);
        if (m->single) {
            m->mass[0] = m->mass[1] = 0.5 * rho * o->width * o->height; /* one edge of the 1 x 1 mesh */
        } else {
            double *mn = (double *)xcalloc((size_t)m->nnode, sizeof(double));
            if (gk_fem_lumped_mass(&m->mesh, &m->q, rho, mn, &err)) {
                fprintf(stderr, PROG ": %s\n", err.msg);
                return 1;
            }
            for (k = 0; k < m->nnode; ++k) {
                m->mass[2 * k] = m->mass[2 * k + 1] = mn[k];
                if (m->mesh.x[2 * k + 1] <= 1e-12 * o->height) m->fixed[2 * k + 1] = 1; /* bottom: u_y = 0 */
            }
            m->fixed[0] = 1; /* node 0 = (0, 0): u_x = 0 */
            free(mn);
        }
    }
    /* the RVEs */
    memset(&d, 0, sizeof d);
    memset(&m->fs, 0, sizeof m->fs);
    m->fs.kind = (gk_frame_kind)o->frame;
    m->fs.def.tol_energy = o->tol_energy;
    m->fs.def.tol_servo = o->tol_servo;
    m->fs.def.max_servo = o->servo_max;
    m->fs.def.max_steps = o->rve_max;
    m->fs.frames = &m->fr;
    m->fs.stats = m->stats;
    pr.packing = o->frame == GK_FRAME_SERVO ? &m->fr.framed : &m->pk;
    pr.state = NULL;
    d.npoints = m->ngp, d.protos = &pr, d.nprotos = 1, d.threads = o->threads;
    d.rve = rve_def(o);
    d.proc = gk_frame_run, d.proc_user = &m->fs;
    if (gk_twoscale_create(&m->ts, &d)) {
        fprintf(stderr, PROG ": %s\n", gk_twoscale_error(&m->ts));
        return 1;
    }
    /* bound on the highest frequency: twice the Taylor tangent of the packing (an upper bound) */
    {
        gk_rve r;
        gk_rve_def rd = rve_def(o);
        double D[16], Dg[16 * 4], Ke[64], me[8];
        if (gk_rve_create(&r, &rd, &m->pk) || gk_rve_refresh(&r) || gk_homog_tangent(&r, 0u, D)) {
            fprintf(stderr, PROG ": %s\n", gk_rve_error(&r));
            return 1;
        }
        gk_rve_destroy(&r);
        for (k = 0; k < 16; ++k) D[k] *= 2.0;
        m->omega_max = 0.0;
        if (m->single) { /* the homogeneous mode: k = D_1111 H / W on the mass of one edge */
            double kx = D[0] * o->height / o->width, ky = D[15] * o->width / o->height;
            m->omega_max = sqrt((kx > ky ? kx : ky) / m->mass[0]);
        } else {
            for (e = 0; e < m->mesh.nelem; ++e) {
                double om, area = 0.0;
                for (k = 0; k < 4; ++k) memcpy(Dg + 16 * k, D, sizeof D);
                if (gk_fem_elem_stiffness(&m->mesh, e, &m->q, Dg, Ke, &err)) {
                    fprintf(stderr, PROG ": %s\n", err.msg);
                    return 1;
                }
                for (k = 0; k < 4; ++k) area += m->wgp[e * 4 + k];
                for (k = 0; k < 8; ++k) me[k] = 0.25 * macro_density(&m->pk) * area;
                om = gk_explicit_elem_omega(8, Ke, me);
                if (om > m->omega_max) m->omega_max = om;
            }
        }
    }
    {
        gk_dr_def dd;
        memset(&dd, 0, sizeof dd);
        dd.xi = o->xi, dd.gamma = o->gamma, dd.tol = o->tol_dr, dd.omega_max = m->omega_max;
        dd.omega_cap = m->omega_max, dd.force_tol = o->force_tol;
        dd.max_iter = o->max_dr;
        if (gk_dr_init(&m->dr, &dd, m->ndof, m->mass, m->fixed, &err)) {
            fprintf(stderr, PROG ": %s\n", err.msg);
            return 1;
        }
    }
    m->h0 = o->height;
    m->h_ic = o->height;
    m->J_ic = 1.0;
    return 0;
}

/* ------------------------------------------------------------------ one DR iteration */
/* the RVEs at U, f_int; 0 or 3 (points failed: the message said) */
static int evaluate(model *m) {
    int g, k;
    const gk_twoscale_point *pts;
    gradients(m, m->u, m->H);
    for (g = 0; g < 9 * m->ngp; ++g) m->dH[g] = m->H[g] - m->Hacc[g];
    if (gk_twoscale_run(&m->ts, m->dH, NULL, m->P, NULL)) {
        fprintf(stderr, PROG ": %s\n", gk_twoscale_error(&m->ts));
        return 3;
    }
    gk_twoscale_accept(&m->ts);
    pts = gk_twoscale_points(&m->ts);
    for (g = 0; g < m->ngp; ++g) {
        m->dem_total += pts[g].work;
        m->capped_total += m->stats[g].capped;
        for (k = 0; k < 9; ++k) m->Hacc[9 * g + k] += m->dH[9 * g + k];
    }
    m->runs_total += m->ngp;
    internal_force(m, m->P, m->fint);
    return 0;
}

/* ------------------------------------------------------------------ rows, outputs */
/* the macro state as a row of dr.csv */
static void make_row(model *m, int step, int stage, int iters, long long dem, row *r) {
    double s11 = 0.0, s22 = 0.0, sb = 0.0, J = 0.0, W = 0.0, Z = 0.0, A = 0.0, h = mean_top(m, m->u);
    int g;
    for (g = 0; g < m->ngp; ++g) {
        double F[9], s[9], w = m->wgp[g];
        int k;
        gk_m3_identity(F);
        for (k = 0; k < 9; ++k) F[k] += m->Hacc[9 * g + k];
        gk_frame_cauchy(m->P + 9 * (size_t)g, F, s);
        s11 -= w * s[0], s22 -= w * s[4], J += w * gk_m3_det(F), W += w;
        sb += fabs(s[0] + s[4]) > 0.0 ? fabs((s[0] - s[4]) / (s[0] + s[4])) : 0.0;
        Z += m->stats[g].coordination, A += m->stats[g].anisotropy;
    }
    J /= W;
    r->v[0] = step, r->v[1] = stage;
    r->v[2] = stage == 2 ? (m->h_ic - h) / m->h_ic : (m->h0 - h) / m->h0;
    r->v[3] = sb / m->ngp, r->v[4] = s11 / W, r->v[5] = s22 / W;
    r->v[6] = stage == 2 ? (J - m->J_ic) / m->J_ic : J - 1.0;
    r->v[7] = Z / m->ngp, r->v[8] = A / m->ngp;
    r->v[9] = iters, r->v[10] = (double)dem, r->v[11] = gk_wtime() - m->t0;
}

static void add_row(model *m, const row *r) {
    if (m->nrows == m->caprows) {
        m->caprows = 2 * m->caprows + 64;
        m->rows = (row *)realloc(m->rows, (size_t)m->caprows * sizeof(row));
        if (!m->rows) die_alloc();
    }
    m->rows[m->nrows++] = *r;
}

static int write_csv(const model *m, const char *name) {
    char path[1024];
    FILE *fp;
    int i, ok;
    snprintf(path, sizeof path, "%s/%s", m->o.out, name);
    fp = fopen(path, "w");
    if (!fp) {
        fprintf(stderr, PROG ": cannot write %s\n", path);
        return 1;
    }
    fprintf(fp, "step,stage,eps_axial,sigma_bar,sigma_11,sigma_22,J,coordination,anisotropy,dr_iterations,dem_steps,"
                "seconds\n");
    for (i = 0; i < m->nrows; ++i) {
        const double *v = m->rows[i].v;
        fprintf(fp, "%d,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%.6g,%d,%.0f,%.3f\n", (int)v[0], (int)v[1], v[2], v[3], v[4],
                v[5], v[6], v[7], v[8], (int)v[9], v[10], v[11]);
    }
    ok = !ferror(fp);
    if (fclose(fp) != 0) ok = 0;
    if (!ok) fprintf(stderr, PROG ": cannot write %s\n", path);
    return !ok;
}

static int write_vtk(const model *m, int step) {
    char path[1024];
    gk_vtk v;
    gk_result r = GK_OK;
    double *xyz, *s11, *s22, *sb, *J, *Z, *A, *dem, *cell;
    int g, k, nn = m->nnode, ne = m->mesh.nelem;
    if (m->single) return 0;
    xyz = (double *)xcalloc(3 * (size_t)(nn > m->ngp ? nn : m->ngp), sizeof(double));
    s11 = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    s22 = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    sb = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    J = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    Z = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    A = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    dem = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    cell = (double *)xcalloc(3 * (size_t)ne, sizeof(double));
    for (g = 0; g < m->ngp; ++g) {
        double F[9], s[9];
        gk_m3_identity(F);
        for (k = 0; k < 9; ++k) F[k] += m->Hacc[9 * g + k];
        gk_frame_cauchy(m->P + 9 * (size_t)g, F, s);
        s11[g] = -s[0], s22[g] = -s[4];
        sb[g] = fabs(s[0] + s[4]) > 0.0 ? fabs((s[0] - s[4]) / (s[0] + s[4])) : 0.0;
        J[g] = gk_m3_det(F), Z[g] = m->stats[g].coordination, A[g] = m->stats[g].anisotropy;
        dem[g] = (double)m->stats[g].steps;
        cell[g / 4] += sb[g] / 4, cell[ne + g / 4] += J[g] / 4, cell[2 * ne + g / 4] += m->deq[g] / 4;
    }
    snprintf(path, sizeof path, "%s/mesh_%04d.vtk", m->o.out, step);
    for (k = 0; k < nn; ++k) {
        xyz[3 * k] = m->mesh.x[2 * k] + m->u[2 * k], xyz[3 * k + 1] = m->mesh.x[2 * k + 1] + m->u[2 * k + 1];
        xyz[3 * k + 2] = 0.0;
    }
    r = gk_vtk_open(&v, path, "femdem_dr deformed mesh");
    if (!r) r = gk_vtk_points(&v, nn, xyz);
    if (!r) r = gk_vtk_cells(&v, ne, 4, m->mesh.conn, GK_VTK_QUAD);
    if (!r) {
        double *d3 = (double *)xcalloc(3 * (size_t)nn, sizeof(double));
        for (k = 0; k < nn; ++k) d3[3 * k] = m->u[2 * k], d3[3 * k + 1] = m->u[2 * k + 1];
        r = gk_vtk_point_vector(&v, "displacement", d3);
        free(d3);
    }
    if (!r) r = gk_vtk_cell_scalar(&v, "sigma_bar", cell);
    if (!r) r = gk_vtk_cell_scalar(&v, "J", cell + ne);
    if (!r) r = gk_vtk_cell_scalar(&v, "deq", cell + 2 * ne);
    if (!r) r = gk_vtk_close(&v);
    else if (v.fp) fclose(v.fp);
    if (!r) {
        int *conn = (int *)xcalloc((size_t)m->ngp, sizeof(int));
        snprintf(path, sizeof path, "%s/gp_%04d.vtk", m->o.out, step);
        for (g = 0; g < m->ngp; ++g) {
            double x[3], X[3], N[4], dN[8], uu[2] = {0, 0};
            int e = g / 4, a;
            gk_fem_shape(GK_Q4, m->q.xi[g % 4], N, dN);
            gk_mesh_point(&m->mesh, e, m->q.xi[g % 4], X);
            for (a = 0; a < 4; ++a) {
                int n = m->mesh.conn[4 * e + a];
                uu[0] += N[a] * m->u[2 * n], uu[1] += N[a] * m->u[2 * n + 1];
            }
            x[0] = X[0] + uu[0], x[1] = X[1] + uu[1], x[2] = 0.0;
            memcpy(xyz + 3 * g, x, sizeof x);
            conn[g] = g;
        }
        r = gk_vtk_open(&v, path, "femdem_dr Gauss points");
        if (!r) r = gk_vtk_points(&v, m->ngp, xyz);
        if (!r) r = gk_vtk_cells(&v, m->ngp, 1, conn, GK_VTK_VERTEX);
        if (!r) r = gk_vtk_point_scalar(&v, "sigma_11", s11);
        if (!r) r = gk_vtk_point_scalar(&v, "sigma_22", s22);
        if (!r) r = gk_vtk_point_scalar(&v, "sigma_bar", sb);
        if (!r) r = gk_vtk_point_scalar(&v, "J", J);
        if (!r) r = gk_vtk_point_scalar(&v, "coordination", Z);
        if (!r) r = gk_vtk_point_scalar(&v, "anisotropy", A);
        if (!r) r = gk_vtk_point_scalar(&v, "deq", m->deq);
        if (!r) r = gk_vtk_point_scalar(&v, "dem_steps", dem);
        if (!r) r = gk_vtk_close(&v);
        else if (v.fp) fclose(v.fp);
        free(conn);
    }
    if (r) fprintf(stderr, PROG ": %s\n", v.err.msg[0] ? v.err.msg : "cannot write the VTK files");
    free(xyz), free(s11), free(s22), free(sb), free(J), free(Z), free(A), free(dem), free(cell);
    return r != GK_OK;
}

static int write_svgs(const model *m) {
    char path[1024];
    gk_plot p;
    gk_err err;
    double *x = (double *)xcalloc((size_t)m->nrows + 1, sizeof(double)), *y = (double *)xcalloc((size_t)m->nrows + 1, sizeof(double));
    double *z = (double *)xcalloc((size_t)m->nrows + 1, sizeof(double)), *a = (double *)xcalloc((size_t)m->nrows + 1, sizeof(double));
    double *jj = (double *)xcalloc((size_t)m->nrows + 1, sizeof(double));
    int i, n = 0, bad = 0;
    for (i = 0; i < m->nrows; ++i) {
        const double *v = m->rows[i].v;
        if (v[1] != 2 && !(i + 1 < m->nrows && m->rows[i + 1].v[1] == 2)) continue; /* the start of stage 2 */
        x[n] = 100.0 * (v[1] == 2 ? v[2] : 0.0), y[n] = v[3], jj[n] = 100.0 * (v[1] == 2 ? v[6] : 0.0);
        z[n] = v[7], a[n] = 10.0 * v[8], ++n;
    }
    gk_plot_init(&p, "FEMxDEM by dynamic relaxation: stress ratio", "axial strain eps = d / h_ic [%]",
                 "sigma_bar = |s11 - s22| / |s11 + s22|");
    gk_plot_add(&p, x, y, n, m->o.test == TEST_DNS ? "DNS" : (m->o.frame == GK_FRAME_SERVO ? "servo frame" : "periodic cell"));
    snprintf(path, sizeof path, "%s/dr_stress.svg", m->o.out);
    bad |= gk_plot_svg(&p, path, &err) != GK_OK;
    gk_plot_init(&p, "volumetric deformation", "axial strain [%]", "J_rel = (det F - det F_ic) / det F_ic [%]");
    gk_plot_add(&p, x, jj, n, "J_rel");
    snprintf(path, sizeof path, "%s/dr_volume.svg", m->o.out);
    bad |= gk_plot_svg(&p, path, &err) != GK_OK;
    gk_plot_init(&p, "micro-structure", "axial strain [%]", "coordination 2C/(P+Q); 10 x anisotropy");
    gk_plot_add(&p, x, z, n, "coordination");
    gk_plot_add(&p, x, a, n, "10 x anisotropy (eq 38)");
    snprintf(path, sizeof path, "%s/dr_fabric.svg", m->o.out);
    bad |= gk_plot_svg(&p, path, &err) != GK_OK;
    if (!m->single && m->o.test != TEST_DNS) { /* Fig 7: the incremental equivalent strain on the deformed mesh */
        int ne = m->mesh.nelem, e, k;
        double *xy = (double *)xcalloc(8 * (size_t)ne, sizeof(double)), *val = (double *)xcalloc((size_t)ne, sizeof(double));
        double ol[10];
        int ollen = 5;
        gk_field_def fd;
        for (e = 0; e < ne; ++e)
            for (k = 0; k < 4; ++k) {
                int nd = m->mesh.conn[4 * e + k];
                xy[8 * e + 2 * k] = m->mesh.x[2 * nd] + m->u[2 * nd];
                xy[8 * e + 2 * k + 1] = m->mesh.x[2 * nd + 1] + m->u[2 * nd + 1];
                val[e] += 0.25 * 100.0 * m->deq[4 * e + k];
            }
        { /* the specimen's corners as the outline */
            int c[5];
            c[0] = 0, c[1] = m->o.nx, c[2] = m->nnode - 1, c[3] = m->nnode - 1 - m->o.nx, c[4] = 0;
            for (k = 0; k < 5; ++k) ol[2 * k] = m->mesh.x[2 * c[k]] + m->u[2 * c[k]], ol[2 * k + 1] = m->mesh.x[2 * c[k] + 1] + m->u[2 * c[k] + 1];
        }
        memset(&fd, 0, sizeof fd);
        fd.title = "incremental equivalent strain of the last step";
        fd.label = "deq = |dF| [%]";
        fd.xlabel = "x [mm]", fd.ylabel = "y [mm]", fd.coord_scale = 1e3;
        fd.nlines = 1, fd.line_len = &ollen, fd.line_xy = ol;
        snprintf(path, sizeof path, "%s/deq_field.svg", m->o.out);
        bad |= gk_field_svg(path, &fd, ne, 4, xy, val, &err) != GK_OK;
        free(xy), free(val);
    }
    if (bad) fprintf(stderr, PROG ": cannot write the SVG plots in %s\n", m->o.out);
    free(x), free(y), free(z), free(a), free(jj);
    return bad;
}

/* ------------------------------------------------------------------ checkpoint */
/* driver block: uint32 magic, int32 ngp, ndof, frame, no_rotation, test, step_done, nrows, have_f0;
 * double h_ic, J_ic, omega, dr_total, dem_total, runs_total, capped_total, unconverged, 8 option values;
 * u, v, f0 (ndof each), Hacc (9 ngp), P (9 ngp), rows */
#define CK_NI 9
#define CK_ND 16
static void ck_opts(const model *m, double *d) {
    const opts *o = &m->o;
    d[8] = o->strain, d[9] = o->pressure, d[10] = o->friction, d[11] = o->iso_steps, d[12] = o->steps;
    d[13] = o->kn_ratio, d[14] = o->nx * 1000.0 + o->ny, d[15] = o->width * o->height;
}

static int save_checkpoint(model *m) {
    size_t n = 4 + 4 * (CK_NI - 1) + 8 * (CK_ND + 3 * (size_t)m->ndof + 18 * (size_t)m->ngp + (size_t)NCOL * m->nrows);
    unsigned char *b = (unsigned char *)xcalloc(n, 1), *o = b;
    int32_t iv[CK_NI - 1];
    double dv[CK_ND];
    uint32_t magic = CK_MAGIC;
    char path[1024];
    int i, bad;
    iv[0] = m->ngp, iv[1] = m->ndof, iv[2] = m->o.frame, iv[3] = m->o.no_rotation, iv[4] = m->o.test;
    iv[5] = m->step_done, iv[6] = m->nrows, iv[7] = m->have_f0;
    dv[0] = m->h_ic, dv[1] = m->J_ic, dv[2] = m->dr.omega, dv[3] = (double)m->dr.total, dv[4] = (double)m->dem_total;
    dv[5] = (double)m->runs_total, dv[6] = (double)m->capped_total, dv[7] = (double)m->unconverged;
    ck_opts(m, dv);
    memcpy(o, &magic, 4), o += 4;
    memcpy(o, iv, sizeof iv), o += sizeof iv;
    memcpy(o, dv, sizeof dv), o += sizeof dv;
    memcpy(o, m->u, 8 * (size_t)m->ndof), o += 8 * (size_t)m->ndof;
    memcpy(o, m->v, 8 * (size_t)m->ndof), o += 8 * (size_t)m->ndof;
    memcpy(o, m->f0, 8 * (size_t)m->ndof), o += 8 * (size_t)m->ndof;
    memcpy(o, m->Hacc, 72 * (size_t)m->ngp), o += 72 * (size_t)m->ngp;
    memcpy(o, m->P, 72 * (size_t)m->ngp), o += 72 * (size_t)m->ngp;
    for (i = 0; i < m->nrows; ++i) memcpy(o, m->rows[i].v, 8 * NCOL), o += 8 * NCOL;
    snprintf(path, sizeof path, "%s/checkpoint.bin", m->o.out);
    bad = gk_twoscale_save(&m->ts, path, b, (size_t)(o - b)) != GK_OK;
    if (bad) fprintf(stderr, PROG ": %s\n", gk_twoscale_error(&m->ts));
    free(b);
    return bad;
}

static int load_checkpoint(model *m) {
    char path[1024];
    void *blk = NULL;
    size_t nb = 0, need;
    const unsigned char *b;
    int32_t iv[CK_NI - 1];
    double dv[CK_ND], want[CK_ND];
    uint32_t magic;
    int i;
    snprintf(path, sizeof path, "%s/checkpoint.bin", m->o.restart);
    if (gk_twoscale_load(&m->ts, path, &blk, &nb)) {
        fprintf(stderr, PROG ": %s\n", gk_twoscale_error(&m->ts));
        return 1;
    }
    b = (const unsigned char *)blk;
    need = 4 + sizeof iv + sizeof dv;
    if (nb < need) goto bad;
    memcpy(&magic, b, 4), memcpy(iv, b + 4, sizeof iv), memcpy(dv, b + 4 + sizeof iv, sizeof dv);
    ck_opts(m, want);
    if (magic != CK_MAGIC || iv[0] != m->ngp || iv[1] != m->ndof || iv[2] != m->o.frame || iv[3] != m->o.no_rotation ||
        iv[4] != m->o.test || iv[6] < 0 || iv[5] < 0)
        goto bad;
    for (i = 8; i < CK_ND; ++i)
        if (dv[i] != want[i]) {
            fprintf(stderr, PROG ": %s was written with other options (strain, pressure, friction, steps, stiffness or mesh)\n", path);
            gk_twoscale_free(&m->ts, blk);
            return 1;
        }
    need += 8 * (3 * (size_t)m->ndof + 18 * (size_t)m->ngp + (size_t)NCOL * iv[6]);
    if (nb != need) goto bad;
    /* a checksum only proves the file is what some writer wrote: check what
     * this run will trust (every real finite, counters in range) */
    if (iv[5] > m->o.iso_steps + m->o.steps || (iv[7] != 0 && iv[7] != 1)) goto bad_value;
    for (i = 0; i < 8; ++i)
        if (!isfinite(dv[i]) || (i >= 3 && dv[i] < 0.0)) goto bad_value;
    for (b += 4 + sizeof iv + sizeof dv; b < (const unsigned char *)blk + nb; b += 8) {
        double x;
        memcpy(&x, b, 8);
        if (!isfinite(x)) goto bad_value;
    }
    b = (const unsigned char *)blk;
    b += 4 + sizeof iv + sizeof dv;
    memcpy(m->u, b, 8 * (size_t)m->ndof), b += 8 * (size_t)m->ndof;
    memcpy(m->v, b, 8 * (size_t)m->ndof), b += 8 * (size_t)m->ndof;
    memcpy(m->f0, b, 8 * (size_t)m->ndof), b += 8 * (size_t)m->ndof;
    memcpy(m->Hacc, b, 72 * (size_t)m->ngp), b += 72 * (size_t)m->ngp;
    memcpy(m->P, b, 72 * (size_t)m->ngp), b += 72 * (size_t)m->ngp;
    m->nrows = 0;
    for (i = 0; i < iv[6]; ++i) {
        row r;
        memcpy(r.v, b, 8 * NCOL), b += 8 * NCOL;
        add_row(m, &r);
    }
    m->step_done = iv[5], m->have_f0 = iv[7];
    m->h_ic = dv[0], m->J_ic = dv[1], m->dr.omega = dv[2], m->dr.total = (long)dv[3];
    m->dem_total = (long long)dv[4], m->runs_total = (long long)dv[5], m->capped_total = (long long)dv[6];
    m->unconverged = (long long)dv[7];
    if (m->have_f0) gk_dr_reference(&m->dr, NULL, m->f0);
    gk_twoscale_free(&m->ts, blk);
    printf("restarted from %s at step %d\n", path, m->step_done);
    return 0;
bad:
    fprintf(stderr, PROG ": %s is not a checkpoint of this run (another test, mesh, frame or rotation)\n", path);
    gk_twoscale_free(&m->ts, blk);
    return 1;
bad_value:
    fprintf(stderr, PROG ": %s: the run's block holds a non-finite or out-of-range value; not restarted\n",
            path);
    gk_twoscale_free(&m->ts, blk);
    return 1;
}

/* ------------------------------------------------------------------ the load path */
/* relax one load step; 0, 3 (RVEs failed) */
static int dr_step(model *m, double p_side, double p_top, int *iters) {
    int rc, k;
    gk_dr_begin(&m->dr);
    for (k = 0; k < m->ndof; ++k) m->v[k] = 0.0;
    for (;;) {
        if ((rc = evaluate(m)) != 0) return rc;
        if (m->o.rayleigh == 0 && m->dr.iter == 0) { /* eq 26 relative to this step's start */
            memcpy(m->u0, m->u, (size_t)m->ndof * sizeof(double));
            memcpy(m->f0, m->fint, (size_t)m->ndof * sizeof(double));
            gk_dr_reference(&m->dr, m->u0, m->f0);
        } else if (!m->have_f0) { /* the unloaded state's own internal force: the reference of eq 26 */
            memcpy(m->f0, m->fint, (size_t)m->ndof * sizeof(double));
            gk_dr_reference(&m->dr, NULL, m->f0);
            m->have_f0 = 1;
        }
        external_force(m, m->u, p_side, p_top, m->fext);
        if (gk_dr_iterate(&m->dr, m->fint, m->fext, m->u, m->v)) {
            fprintf(stderr, PROG ": %s\n", m->dr.err.msg);
            return 3;
        }
        if (getenv("FDR_DEBUG") && m->single)
            fprintf(stderr, "it %ld u %.4e %.4e fint %.4e %.4e fext %.4e %.4e om %.4e dt %.3e ek %.3e max %.3e g %u\n", m->dr.iter,
                    m->u[0], m->u[1], m->fint[0], m->fint[1], m->fext[0], m->fext[1], m->dr.omega, m->dr.dt, m->dr.ekin,
                    m->dr.ekin_max, m->dr.guards);
        if (m->dr.converged) break;
        if (m->dr.iter >= m->o.max_dr) {
            ++m->unconverged;
            fprintf(stderr, PROG ": warning: load step not relaxed in %d DR iterations (E_kin / E_kin,max %.2g)\n",
                    m->o.max_dr, m->dr.ekin / m->dr.ekin_max);
            break;
        }
    }
    *iters = (int)m->dr.iter;
    return 0;
}

static double interp(const model *m, int col, double eps) {
    int i;
    for (i = 1; i < m->nrows; ++i) {
        const double *a = m->rows[i - 1].v, *b = m->rows[i].v;
        if (a[1] == 2 && b[1] == 2 && a[2] <= eps && b[2] >= eps && b[2] > a[2])
            return a[col] + (b[col] - a[col]) * (eps - a[2]) / (b[2] - a[2]);
    }
    return NAN;
}

static void result_line(const model *m) {
    double peak = 0.0, epk = 0.0, jmin = HUGE_VAL, edil = NAN, iters = 0.0;
    int i, nst = 0;
    for (i = 0; i < m->nrows; ++i) {
        const double *v = m->rows[i].v;
        if (v[0] > 0) iters += v[9], ++nst;
        if (v[1] != 2) continue;
        if (v[3] > peak) peak = v[3], epk = v[2];
        if (v[6] < jmin) jmin = v[6], edil = v[2];
    }
    printf("RESULT peak_sigma_bar=%.4f eps_at_peak=%.4f sigma_bar_0073=%.4f anisotropy_0073=%.4f eps_dilation=%.4f "
           "dr_iterations_mean=%.1f seconds=%.1f dem_steps_per_run=%.1f rve_capped_runs=%lld dr_unconverged_steps=%lld "
           "frame=%s rotation=%s\n",
           peak, epk, interp(m, 3, 0.073), interp(m, 8, 0.073), edil, nst ? iters / nst : 0.0, gk_wtime() - m->t0,
           m->runs_total ? (double)m->dem_total / (double)m->runs_total : 0.0, m->capped_total, m->unconverged,
           m->o.frame == GK_FRAME_SERVO ? "servo" : "periodic", m->o.no_rotation ? "locked" : "free");
}

static int run_fem(model *m) {
    const opts *o = &m->o;
    int nsteps = o->iso_steps + o->steps, step, rc, k;
    row r;
    long long dem0;
    if (o->restart) {
        if (load_checkpoint(m)) return 1;
    } else {
        make_row(m, 0, 1, 0, 0, &r); /* the unloaded state (no RVE has run: P = 0, as Table 1's first increment) */
        add_row(m, &r);
    }
    for (step = m->step_done + 1; step <= nsteps; ++step) {
        int stage = step <= o->iso_steps ? 1 : 2, iters = 0, g;
        double ps = o->pressure * (stage == 1 ? (double)step / o->iso_steps : 1.0), pt = stage == 1 ? ps : 0.0;
        double Hs[9 * 1];
        double *Hstart = (double *)xcalloc(9 * (size_t)m->ngp, sizeof(double));
        memcpy(Hstart, m->Hacc, 9 * (size_t)m->ngp * sizeof(double));
        (void)Hs;
        if (stage == 2) { /* the platen: every top node down to d below its height after stage 1 */
            double d = o->strain * m->h_ic * (step - o->iso_steps) / o->steps;
            if (m->single) {
                m->fixed[1] = 1;
                m->u[1] = (m->h_ic - m->h0) - d;
            } else {
                for (k = 0; k < m->ntop; ++k) {
                    int n = m->top[k];
                    m->fixed[2 * n + 1] = 1;
                    m->u[2 * n + 1] = (m->h_ic - m->h0) - d;
                }
            }
        }
        dem0 = m->dem_total;
        if ((rc = dr_step(m, ps, pt, &iters)) != 0) {
            free(Hstart);
            save_checkpoint(m);
            return rc;
        }
        for (g = 0; g < m->ngp; ++g) { /* deq: |dF| over the step */
            double s2 = 0.0;
            for (k = 0; k < 9; ++k) s2 += (m->Hacc[9 * g + k] - Hstart[9 * g + k]) * (m->Hacc[9 * g + k] - Hstart[9 * g + k]);
            m->deq[g] = sqrt(s2);
        }
        free(Hstart);
        if (step == o->iso_steps) { /* the end of stage 1: h_ic, det F_ic; the top becomes the platen */
            double J = 0.0, W = 0.0;
            m->h_ic = mean_top(m, m->u);
            for (g = 0; g < m->ngp; ++g) {
                double F[9];
                gk_m3_identity(F);
                for (k = 0; k < 9; ++k) F[k] += m->Hacc[9 * g + k];
                J += m->wgp[g] * gk_m3_det(F), W += m->wgp[g];
            }
            m->J_ic = J / W;
            if (!m->single) /* a rigid platen: the top nodes level at h_ic */
                for (k = 0; k < m->ntop; ++k) m->u[2 * m->top[k] + 1] = m->h_ic - m->h0;
        }
        make_row(m, step, stage, iters, m->dem_total - dem0, &r);
        add_row(m, &r);
        m->step_done = step;
        {
            char what[256];
            snprintf(what, sizeof what, "stage %d  eps %.3f %%  sigma_bar %.4f  s11 %.4g s22 %.4g  DR %d  DEM/run %.0f",
                     stage, 100.0 * r.v[2], r.v[3], r.v[4], r.v[5], iters,
                     (double)(m->dem_total - dem0) / (iters > 0 ? (double)iters * m->ngp : 1.0));
            gk_progress(stderr, step, nsteps, m->t0, what);
        }
        if (write_csv(m, "dr.csv")) return 1;
        if ((o->vtk_every > 0 && step % o->vtk_every == 0) || step == nsteps)
            if (write_vtk(m, step)) return 1;
        if (step % o->checkpoint == 0 || step == nsteps || step == o->stop_after)
            if (save_checkpoint(m)) return 1;
        if (step == o->stop_after) {
            printf("stopped after step %d (%s/checkpoint.bin)\n", step, o->out);
            return 0;
        }
    }
    if (write_svgs(m)) return 1;
    result_line(m);
    return 0;
}

/* ------------------------------------------------------------------ the DNS */
typedef struct dns {
    gk_scene sc;
    int32_t *left, *right;
    int nl, nr, bottom, top;
    double width0, h0;
} dns;

/* the specimen: the periodic packing tiled nt[0] x nt[1] times, closed on the right and on the top
 * by the copies of the boundary particles of x = 0 and y = 0 (as the framed RVE); the chains are
 * the particles on x = 0 (left, top to bottom) and on x = W (right, bottom to top) */
static int dns_build(model *m, dns *D) {
    const opts *o = &m->o;
    const gk_packing *pk = &m->pk;
    gk_packing t, sp;
    gk_err err;
    gk_scene_def sd = gk_scene_def_default();
    int nx = o->tiles[0], ny = o->tiles[1], n, p, i, j, k = 0, extra = 0;
    double L0 = pk->h[0], L1 = pk->h[4], W = nx * L0, H = ny * L1, tol = 1e-9 * L0, rmax = 0.0;
    if (gk_packing_tile(pk, nx, ny, 1, &t, NULL, &err)) {
        fprintf(stderr, PROG ": %s\n", err.msg);
        return 1;
    }
    for (p = 0; p < pk->n; ++p) {
        int onx = fabs(pk->x[p]) <= tol, ony = fabs(pk->y[p]) <= tol;
        extra += (onx ? ny : 0) + (ony ? nx : 0) + (onx && ony);
        if (pk->r[p] > rmax) rmax = pk->r[p];
    }
    n = t.n + extra;
    if (gk_packing_alloc(&sp, 2, n, NULL, &err)) {
        fprintf(stderr, PROG ": %s\n", err.msg);
        return 1;
    }
    for (p = 0; p < t.n; ++p) sp.x[k] = t.x[p], sp.y[k] = t.y[p], sp.r[k] = t.r[p], ++k;
    for (p = 0; p < pk->n; ++p) {
        int onx = fabs(pk->x[p]) <= tol, ony = fabs(pk->y[p]) <= tol;
        if (onx)
            for (j = 0; j < ny; ++j) sp.x[k] = W, sp.y[k] = pk->y[p] + j * L1, sp.r[k] = pk->r[p], ++k;
        if (ony)
            for (i = 0; i < nx; ++i) sp.x[k] = pk->x[p] + i * L0, sp.y[k] = H, sp.r[k] = pk->r[p], ++k;
        if (onx && ony) sp.x[k] = W, sp.y[k] = H, sp.r[k] = pk->r[p], ++k;
    }
    gk_packing_free(&t);
    sd.dim = 2;
    sd.lo[0] = -0.25 * W, sd.hi[0] = 1.25 * W, sd.lo[1] = -0.25 * H, sd.hi[1] = 1.25 * H;
    sd.lost = GK_LOST_DELETE;
    sd.rve = rve_def(o);
    if (gk_scene_create(&D->sc, &sd, &sp)) {
        fprintf(stderr, PROG ": %s\n", gk_scene_error(&D->sc));
        gk_packing_free(&sp);
        return 1;
    }
    /* the chains: x = 0 downwards, x = W upwards (ids = indices of sp) */
    D->left = (int32_t *)xcalloc((size_t)n, sizeof(int32_t));
    D->right = (int32_t *)xcalloc((size_t)n, sizeof(int32_t));
    for (D->nl = D->nr = 0, p = 0; p < n; ++p) {
        if (fabs(sp.x[p]) <= tol) D->left[D->nl++] = p;
        if (fabs(sp.x[p] - W) <= tol) D->right[D->nr++] = p;
    }
    for (i = 1; i < D->nl; ++i) /* insertion sorts: left by y descending, right by y ascending */
        for (j = i; j > 0 && sp.y[D->left[j]] > sp.y[D->left[j - 1]]; --j) {
            int32_t x = D->left[j];
            D->left[j] = D->left[j - 1], D->left[j - 1] = x;
        }
    for (i = 1; i < D->nr; ++i)
        for (j = i; j > 0 && sp.y[D->right[j]] < sp.y[D->right[j - 1]]; --j) {
            int32_t x = D->right[j];
            D->right[j] = D->right[j - 1], D->right[j - 1] = x;
        }
    {
        gk_wall_def fl = gk_wall_def_default(), lid = gk_wall_def_default();
        gk_material wm;
        double ylo = 1e300, yhi = -1e300;
        for (p = 0; p < n; ++p) {
            if (sp.y[p] - sp.r[p] < ylo) ylo = sp.y[p] - sp.r[p];
            if (sp.y[p] + sp.r[p] > yhi) yhi = sp.y[p] + sp.r[p];
        }
        gk_scene_pair_material(&sd.rve.mat, NULL, &wm, &err);
        wm.friction = 0.0; /* smooth platens */
        fl.point[1] = ylo, fl.normal[1] = 1.0, fl.mat = wm;
        lid.point[1] = yhi, lid.normal[1] = -1.0, lid.mat = wm;
        lid.drive = GK_DRIVE_STRESS, lid.area = W * D->sc.rve.volume_factor, lid.target = 0.0;
        lid.max_speed = 1e-3 * D->sc.rve.rmin / D->sc.rve.dt; /* the RVEs' ramp */
        if (gk_scene_add_wall(&D->sc, &fl, &D->bottom) || gk_scene_add_wall(&D->sc, &lid, &D->top) ||
            gk_scene_add_membrane(&D->sc, D->nl, D->left, 0.0, sd.rve.mat.kn, D->top, D->bottom, NULL) ||
            gk_scene_add_membrane(&D->sc, D->nr, D->right, 0.0, sd.rve.mat.kn, D->bottom, D->top, NULL) ||
            gk_scene_prescribe(&D->sc, gk_scene_index(&D->sc, D->left[D->nl - 1]), NULL, NULL)) {
            fprintf(stderr, PROG ": %s\n", gk_scene_error(&D->sc));
            gk_packing_free(&sp);
            return 1;
        }
        D->h0 = yhi - ylo;
    }
    D->width0 = W;
    gk_packing_free(&sp);
    printf("femdem_dr: DNS of %d x %d cells: %d disks, %.4g x %.4g mm, chains of %d and %d\n", nx, ny, n, 1e3 * W,
           1e3 * H, D->nl, D->nr);
    return 0;
}

/* the chains' mean x (the width the pressures act across) */
static double dns_width(const dns *D) {
    double xl = 0.0, xr = 0.0, x[3];
    int k;
    for (k = 0; k < D->nl; ++k) gk_scene_position(&D->sc, gk_scene_index(&D->sc, D->left[k]), x), xl += x[0];
    for (k = 0; k < D->nr; ++k) gk_scene_position(&D->sc, gk_scene_index(&D->sc, D->right[k]), x), xr += x[0];
    return xr / D->nr - xl / D->nl;
}

/* relax to eq 31 (and, with the lid servo on, the lid within 1 % of its target); the relaxation
 * checks, or -1 after the message */
static long dns_relax(model *m, dns *D, long *steps) {
    gk_wall *lid = &D->sc.walls[D->top];
    long checks = 0;
    double ek, ep;
    for (;;) {
        int servo = lid->def.drive == GK_DRIVE_STRESS;
        if (gk_scene_step(&D->sc, 50)) {
            fprintf(stderr, PROG ": %s\n", gk_scene_error(&D->sc));
            return -1;
        }
        *steps += 50, ++checks;
        gk_frame_energy(&D->sc.rve, NULL, &ek, &ep);
        if ((ep > 0.0 ? ek <= m->o.tol_energy * ep : ek == 0.0) &&
            (!servo || fabs(lid->resistance - lid->def.target * lid->def.area) <= 0.01 * lid->def.target * lid->def.area))
            return checks;
        if (*steps > 50L * m->o.max_dr) {
            ++m->unconverged;
            fprintf(stderr, PROG ": warning: the DNS did not relax (E_kin / E_pot %.2g)\n", ep > 0 ? ek / ep : 0.0);
            return checks;
        }
    }
}

static void dns_row(model *m, dns *D, int step, int stage, long checks, long steps, row *r) {
    double w = dns_width(D), h = D->sc.walls[D->top].pos[1] - D->sc.walls[D->bottom].pos[1], phi[9], Fa[9];
    double s22 = D->sc.walls[D->top].resistance / (w * D->sc.rve.volume_factor), s11 = D->sc.mem[0].pressure;
    double J = w * h / (D->width0 * D->h0);
    gk_homog_fabric(&D->sc.rve, phi, Fa);
    r->v[0] = step, r->v[1] = stage;
    r->v[2] = stage == 2 ? (m->h_ic - h) / m->h_ic : (D->h0 - h) / D->h0;
    r->v[3] = s11 + s22 > 0.0 ? fabs((s11 - s22) / (s11 + s22)) : 0.0;
    r->v[4] = s11, r->v[5] = s22;
    r->v[6] = stage == 2 ? (J - m->J_ic) / m->J_ic : J - 1.0;
    r->v[7] = 2.0 * D->sc.rve.ncontacts / D->sc.rve.n, r->v[8] = gk_fabric_ratio(phi, 2);
    r->v[9] = (double)checks, r->v[10] = (double)steps, r->v[11] = gk_wtime() - m->t0;
}

static int run_dns(model *m) {
    const opts *o = &m->o;
    dns D;
    row r;
    int step, nsteps = o->iso_steps + o->steps;
    gk_wall *lid;
    memset(&D, 0, sizeof D);
    if (gk_packing_read(o->packing, &m->pk, NULL, NULL) && !m->pk.n) {
        fprintf(stderr, PROG ": cannot read %s\n", o->packing);
        return 1;
    }
    if (dns_build(m, &D)) return 1;
    lid = &D.sc.walls[D.top];
    m->h0 = D.h0, m->h_ic = D.h0, m->J_ic = 1.0;
    dns_row(m, &D, 0, 1, 0, 0, &r);
    add_row(m, &r);
    for (step = 1; step <= nsteps; ++step) {
        int stage = step <= o->iso_steps ? 1 : 2;
        long steps = 0, checks;
        if (stage == 1) {
            double p = o->pressure * step / o->iso_steps;
            D.sc.mem[0].pressure = D.sc.mem[1].pressure = p;
            lid->def.target = p, lid->def.area = dns_width(&D) * D.sc.rve.volume_factor;
        } else {
            double d = o->strain * m->h_ic / o->steps, v = 1e-3 * D.sc.rve.rmin / D.sc.rve.dt; /* the RVEs' ramp */
            long n = (long)ceil(d / (v * D.sc.rve.dt));
            lid->def.drive = GK_DRIVE_VELOCITY;
            lid->def.velocity[1] = -d / (n * D.sc.rve.dt);
            if (gk_scene_step(&D.sc, n)) {
                fprintf(stderr, PROG ": %s\n", gk_scene_error(&D.sc));
                return 1;
            }
            steps += n;
            lid->def.velocity[1] = 0.0;
        }
        if ((checks = dns_relax(m, &D, &steps)) < 0) return 1;
        if (step == o->iso_steps) {
            m->h_ic = lid->pos[1] - D.sc.walls[D.bottom].pos[1];
            m->J_ic = dns_width(&D) * m->h_ic / (D.width0 * D.h0);
        }
        m->dem_total += steps;
        dns_row(m, &D, step, stage, checks, steps, &r);
        add_row(m, &r);
        {
            char what[256];
            snprintf(what, sizeof what, "stage %d  eps %.3f %%  sigma_bar %.4f  s11 %.4g s22 %.4g  DEM %ld  lost %ld",
                     stage, 100.0 * r.v[2], r.v[3], r.v[4], r.v[5], steps, D.sc.lost);
            gk_progress(stderr, step, nsteps, m->t0, what);
        }
        if (write_csv(m, "dr.csv")) return 1;
        if ((o->vtk_every > 0 && step % o->vtk_every == 0) || step == nsteps) {
            char path[1024];
            gk_err err;
            snprintf(path, sizeof path, "%s/dns_%04d.vtk", o->out, step);
            if (gk_scene_write_vtk(&D.sc, path, &err)) {
                fprintf(stderr, PROG ": %s\n", err.msg);
                return 1;
            }
        }
    }
    if (write_svgs(m)) return 1;
    m->runs_total = nsteps;
    result_line(m);
    printf("DNS lost_particles=%ld\n", D.sc.lost);
    gk_scene_destroy(&D.sc);
    free(D.left), free(D.right);
    return 0;
}

/* ------------------------------------------------------------------ main */
int main(int argc, char **argv) {
    model m;
    int rc;
    char kn_txt[32];
    memset(&m, 0, sizeof m);
    m.o.test = TEST_BIAXIAL, m.o.nx = 1, m.o.ny = 2, m.o.iso_steps = 10, m.o.steps = 20, m.o.threads = 1;
    m.o.frame = GK_FRAME_SERVO, m.o.vtk_every = 10, m.o.checkpoint = 10, m.o.max_dr = 20000, m.o.servo_max = 20, m.o.rve_max = 20000;
    m.o.tiles[0] = 1, m.o.tiles[1] = 2;
    m.o.strain = 0.10, m.o.pressure = 1.5e5, m.o.friction = 0.4, m.o.width = 0.01, m.o.height = 0.02;
    m.o.kn_ratio = 100.0, m.o.dt_factor = 0.4, m.o.damping = 0.7, m.o.tol_energy = 1e-3, m.o.tol_dr = 1e-3;
    m.o.tol_servo = 1e-4, m.o.xi = 1.0, m.o.gamma = 0.5;
    m.o.packing = "examples/data/frame228_a002.txt";
    if ((rc = parse(argc, argv, &m.o)) != 0) return rc;
    if (mkdir(m.o.out, 0777) != 0 && errno != EEXIST) {
        fprintf(stderr, PROG ": cannot create %s\n", m.o.out);
        return 1;
    }
    m.t0 = gk_wtime();
    if (m.o.test == TEST_DNS) {
        if (m.o.restart) {
            fprintf(stderr, PROG ": --restart is for --test biaxial and rve\n");
            return 2;
        }
        rc = run_dns(&m);
        gk_packing_free(&m.pk);
        free(m.rows);
        return rc;
    }
    m.single = m.o.test == TEST_RVE;
    if (m.single) m.o.nx = m.o.ny = 1;
    if (setup(&m)) return 1;
    if (m.o.material == 1) snprintf(kn_txt, sizeof kn_txt, "E r*");
    else snprintf(kn_txt, sizeof kn_txt, "%.4g N/m", m.o.kn_ratio * m.o.pressure);
    printf("femdem_dr: %s, %s RVE (%d particles, %d boundary), rotation %s, %d Gauss points, k_n %s, "
           "omega_max %.4g rad/s\n",
           m.single ? "the RVE alone" : "biaxial test", m.o.frame == GK_FRAME_SERVO ? "servo-framed" : "periodic-cell",
           m.o.frame == GK_FRAME_SERVO ? m.fr.n : m.pk.n, m.o.frame == GK_FRAME_SERVO ? m.fr.nq : 0,
           m.o.no_rotation ? "locked" : "free", m.ngp, kn_txt, m.omega_max);
    rc = run_fem(&m);
    gk_twoscale_destroy(&m.ts);
    gk_frame_free(&m.fr);
    gk_packing_free(&m.pk);
    if (!m.single) gk_mesh_free(&m.mesh);
    free(m.dNdX), free(m.wgp), free(m.mass), free(m.u), free(m.v), free(m.fint), free(m.fext), free(m.f0), free(m.u0);
    free(m.P), free(m.H), free(m.Hacc), free(m.dH), free(m.deq), free(m.fixed), free(m.top), free(m.edge);
    free(m.stats), free(m.rows);
    return rc;
}
