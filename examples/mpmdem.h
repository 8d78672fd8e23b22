/* mpmdem.h - the MPM side the three MPMxDEM drivers share (examples, not library).
 *
 * mpmdem_biaxial.c, mpmdem_footing.c and mpmdem_collapse.c put one periodic
 * 2D RVE behind every material point of an explicit MPM (Liang & Zhao 2019).
 * The micro side - one RVE per point, the DEM steps of each MPM step, the
 * per-point fields, the RVEs' checkpoint, threads or MPI ranks - is
 * gk_twoscale.h; this file is what the drivers add on the MPM side. A driver
 * defines GK_IMPLEMENTATION and includes it (it includes the grainkit
 * headers):
 *
 *   mpd_begin / mpd_end     the run: MPI (built with GK_TWOSCALE_MPI), the
 *                           output folder, messages on rank 0 only
 *   mpd_opts, mpd_common_opts   the flags every driver takes (cli.h tables)
 *   mpd_proto, mpd_prepare_rve  the packing, the DEM material, consolidation
 *                           to a pressure; bulk density, P-wave modulus
 *   mpd_micro               the gk_twoscale set of the points and the MPM
 *                           strain each point has accumulated; mpd_stress is
 *                           the gk_mpm_stress_fn of the step (Liang & Zhao
 *                           2019 Sec 2.3 (b): dH = dt L -> RVE -> Love stress)
 *   mpd_edge, mpd_step      one USF step with follower edge pressures
 *   mpd_fields              the per-point fields (strains, rotation, p, q, ...)
 *   mpmdem_io.h             what the drivers write: CSV, plots, VTK, field
 *                           pictures, the checkpoint (gk_twoscale's file with
 *                           the driver's block: points, state, rows, pictures)
 *
 * THE DEM STEPS PER MPM STEP (the paper leaves it unstated; it says the DEM
 * runs "until a quasi-static state"): gk_twoscale's rule. Default
 * (--dem-rule adaptive): the point's dH is applied over
 *     n = clamp(ceil(I_1 / I_max), dem_min, dem_max)
 * steps, I_1 the inertial number (Guo & Zhao 2014 eq 20) of dH in one DEM
 * step at the RVE's current pressure, so the RVE deforms at I <= I_max (5e-4:
 * at 100 kPa the count of the 1e-5-strain-per-step rule of Guo & Zhao's
 * scripts; more steps where p is low), then relaxes at fixed cell while its
 * unbalanced force ratio exceeds --dem-unbalanced (5e-3), within dem_max
 * steps in all. --dem-rule strain: n = clamp(ceil(max|dH_ij| / dem_strain),
 * dem_min, dem_max), no relaxation. dem_max caps the cost; the collapse sets
 * it to the real-time count dt_MPM / dt_DEM (a flowing point cannot be more
 * quasi-static than the flow), the quasi-static drivers leave it large.
 *
 * THE MPM TIME STEP: dt = cfl h / c, c = sqrt(M / rho) with M = max(D_xxxx,
 * D_yyyy) of the Taylor (affine, Guo & Zhao 2014 eq 9) tangent of the
 * prepared RVE: the affine tangent bounds the RVE's stiffness from above, so
 * c bounds the P-wave speed and the step is safe while the contact network
 * keeps its stiffness (the drivers print M, rho, c, dt).
 *
 * MPI. Built with mpicc and -DGK_TWOSCALE_MPI (make mpi: build/mpmdem_NAME_mpi),
 * every rank runs the whole MPM (it is cheap next to the RVEs) and the
 * gk_twoscale set spreads the RVEs over the ranks (each stores only its
 * own); rank 0 alone prints and writes. The results are those of the
 * OpenMP build, bit for bit, for any rank and thread count:
 *     mpirun -np 2 build/mpmdem_biaxial_mpi --threads 1 --out DIR
 *
 * OUTPUT AND EXIT STATUS. --out DIR is created (with its parents) and must
 * not be a file; every result written (CSV, SVG, VTK, checkpoint) is
 * checked, and one that cannot be written ends the run with its path and
 * status 1. Status: 0 done, 1 setup or output failed, 2 bad arguments, 3 the
 * simulation failed (the message names the point; the last checkpoint
 * written is intact).
 *
 * FIELD PICTURES (mpd_snap_add): the points as dots in metres at equal aspect,
 * the geometry (plates, walls, footing, base) drawn on top, a colour bar
 * with the quantity's unit, strains in %. The snapshots of one quantity in
 * a run share ONE colour scale: the range of that quantity over all its
 * snapshots so far; a snapshot that widens it rewrites the earlier ones
 * (the snapshots travel in the checkpoint, so a restart keeps the scale).
 */
#ifndef MPMDEM_H
#define MPMDEM_H

#define _POSIX_C_SOURCE 200809L
#include "gk_base.h"
#include "gk_dem.h"
#include "gk_homog.h"
#include "gk_io.h"
#include "gk_mpm.h"
#include "gk_twoscale.h"
#include "cli.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define MPD_PI 3.14159265358979323846
#define MPD_PATH 1200

/* ---------------------------------------------------------------- the run */
typedef struct mpd_run {
    const char *prog; /* driver name for messages */
    const char *out;  /* output folder            */
    int rank, nranks;
} mpd_run;

static void mpd_begin(mpd_run *run, const char *prog, int *argc, char ***argv) {
    memset(run, 0, sizeof *run);
    run->prog = prog, run->nranks = 1;
#ifdef GK_TWOSCALE_MPI
    {
        int provided;
        MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
        MPI_Comm_rank(MPI_COMM_WORLD, &run->rank);
        MPI_Comm_size(MPI_COMM_WORLD, &run->nranks);
        if (run->rank != 0) { /* the driver is replicated: rank 0 speaks for all */
            FILE *q = freopen("/dev/null", "w", stdout);
            q = freopen("/dev/null", "w", stderr);
            (void)q;
        }
    }
#else
    (void)argc, (void)argv;
#endif
}

static int mpd_end(int status) {
#ifdef GK_TWOSCALE_MPI
    MPI_Finalize();
#endif
    return status;
}

/* rank 0's verdict on every rank (rank 0 alone writes files) */
static int mpd_agree(const mpd_run *run, int bad) {
#ifdef GK_TWOSCALE_MPI
    if (run->nranks > 1) MPI_Bcast(&bad, 1, MPI_INT, 0, MPI_COMM_WORLD);
#else
    (void)run;
#endif
    return bad;
}

/* the output folder and its parents; an existing file is refused */
static int mpd_out_dir(const mpd_run *run) {
    char buf[MPD_PATH];
    struct stat st;
    size_t k, n = strlen(run->out);
    int bad = 0;
    if (run->rank == 0) {
        if (n == 0 || n >= sizeof buf) {
            fprintf(stderr, "%s: --out '%s': need a folder name of 1 to %d characters\n", run->prog, run->out,
                    (int)sizeof buf - 1);
            bad = 1;
        }
        for (k = 1; !bad && k <= n; ++k) /* each prefix ending at a '/' or the end */
            if (k == n || run->out[k] == '/') {
                memcpy(buf, run->out, k), buf[k] = 0;
                if (stat(buf, &st) == 0 ? !S_ISDIR(st.st_mode) : mkdir(buf, 0755) != 0 && errno != EEXIST) {
                    fprintf(stderr, "%s: --out %s: %s is %s\n", run->prog, run->out, buf,
                            stat(buf, &st) == 0 ? "a file, not a folder" : "a folder that cannot be created");
                    bad = 1;
                }
            }
    }
    return mpd_agree(run, bad);
}

/* DIR/name; 1 (said) if the path is too long */
static int mpd_path(const mpd_run *run, char *buf, const char *name) {
    if (snprintf(buf, MPD_PATH, "%s/%s", run->out, name) < MPD_PATH) return 0;
    fprintf(stderr, "%s: the output path %s/%s is too long\n", run->prog, run->out, name);
    return 1;
}

/* a result that could not be written: said once, status 1 */
static int mpd_write_failed(const mpd_run *run, const char *path, const char *why) {
    fprintf(stderr, "%s: cannot write %s%s%s\n", run->prog, path, why ? ": " : "", why ? why : "");
    return 1;
}

/* ---------------------------------------------------------------- options */
typedef struct mpd_opts {
    const char *out, *packing, *restart;
    int threads, ppc, basis;             /* basis: index of mpd_basis_names                          */
    double alpha;                        /* PIC fraction (Liang & Zhao: 0.1)                         */
    double cfl;                          /* dt = cfl h / c                                           */
    int dem_rule;                        /* 0 adaptive, 1 strain (gk_twoscale_rule_kind)            */
    double dem_inertial, dem_unbalanced; /* bounds of the adaptive rule                              */
    double dem_strain;                   /* RVE strain per DEM step bound (strain rule)              */
    int dem_min, dem_max;
    double dem_dt; /* DEM time step [s]; 0 -> 0.5 x critical                                          */
    double young, kt_ratio, friction_deg, roll_beta, roll_eta, dem_damping;
    int vtk_every; /* MPM steps between VTK files (0: first and last only)                           */
    int checkpoint_every;
    int quiet;
} mpd_opts;

static const gk_mpm_basis mpd_basis[4] = {GK_MPM_LINEAR, GK_MPM_UGIMP, GK_MPM_QUADRATIC, GK_MPM_CUBIC};

static void mpd_opts_default(mpd_opts *o, const char *out) {
    gk_material m = gk_material_default(); /* Guo & Zhao 2014 / Liang & Zhao 2019 Table 3 values */
    memset(o, 0, sizeof *o);
    o->out = out;
    o->packing = "examples/data/rve400.txt";
    o->threads = 2;
    o->ppc = 1;
    o->basis = 1; /* uGIMP */
    o->alpha = 0.1;
    o->cfl = 0.4;
    o->dem_inertial = 5e-4;
    o->dem_unbalanced = 5e-3;
    o->dem_strain = 1e-5;
    o->dem_min = 1;
    o->dem_max = 1000;
    o->dem_dt = 3.16e-5; /* the step of Guo & Zhao's scripts with this packing */
    o->young = m.young;
    o->kt_ratio = m.kt_ratio;
    o->friction_deg = atan(m.friction) * 180.0 / MPD_PI;
    o->dem_damping = 0.1; /* Liang & Zhao 2019 eq 29, alpha = 0.1 */
}

/* the table of the common flags, pointing into *o (24 and the terminator) */
#define MPD_NCOMMON 25
static void mpd_common_opts(mpd_opts *o, cli_opt *t) {
    const cli_opt c[MPD_NCOMMON] = {
        {"--out", CLI_STR, &o->out, 0, 0, NULL, NULL, 0},
        {"--threads", CLI_INT, &o->threads, 1, 1024, NULL, NULL, 0},
        {"--ppc", CLI_INT, &o->ppc, 1, 4, NULL, NULL, 0},
        {"--basis", CLI_CHOICE, &o->basis, 0, 0, NULL, "linear|ugimp|quadratic|cubic", 0},
        {"--alpha", CLI_REAL, &o->alpha, 0, 1, NULL, NULL, 0},
        {"--cfl", CLI_REAL, &o->cfl, 0, 1, NULL, NULL, CLI_LO_OPEN},
        {"--packing", CLI_STR, &o->packing, 0, 0, NULL, NULL, 0},
        {"--dem-rule", CLI_CHOICE, &o->dem_rule, 0, 0, NULL, "adaptive|strain", 0},
        {"--dem-inertial", CLI_REAL, &o->dem_inertial, 0, 1, NULL, NULL, CLI_LO_OPEN},
        {"--dem-unbalanced", CLI_REAL, &o->dem_unbalanced, 0, HUGE_VAL, "a positive number", NULL,
         CLI_LO_OPEN},
        {"--dem-strain", CLI_REAL, &o->dem_strain, 0, 1, NULL, NULL, CLI_LO_OPEN},
        {"--dem-min", CLI_INT, &o->dem_min, 1, 1000000, NULL, NULL, 0},
        {"--dem-max", CLI_INT, &o->dem_max, 1, 1000000, NULL, NULL, 0},
        {"--dem-dt", CLI_REAL, &o->dem_dt, 0, 1, NULL, NULL, 0},
        {"--young", CLI_REAL, &o->young, 0, HUGE_VAL, "a positive modulus", NULL, CLI_LO_OPEN},
        {"--kt-ratio", CLI_REAL, &o->kt_ratio, 0, 1, NULL, NULL, 0},
        {"--friction-deg", CLI_REAL, &o->friction_deg, 0, 90, NULL, NULL, CLI_HI_OPEN},
        {"--roll-beta", CLI_REAL, &o->roll_beta, 0, HUGE_VAL, "a number >= 0", NULL, 0},
        {"--roll-eta", CLI_REAL, &o->roll_eta, 0, HUGE_VAL, "a number >= 0", NULL, 0},
        {"--dem-damping", CLI_REAL, &o->dem_damping, 0, 1, NULL, NULL, CLI_HI_OPEN},
        {"--vtk-every", CLI_INT, &o->vtk_every, 0, 1000000000, NULL, NULL, 0},
        {"--checkpoint", CLI_INT, &o->checkpoint_every, 0, 1000000000, NULL, NULL, 0},
        {"--restart", CLI_STR, &o->restart, 0, 0, NULL, NULL, 0},
        {"--quiet", CLI_FLAG, &o->quiet, 0, 0, NULL, NULL, 0},
        {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    memcpy(t, c, sizeof c);
}

static int mpd_check_opts(const mpd_run *run, const mpd_opts *o) {
    if (o->dem_min > o->dem_max) {
        fprintf(stderr, "%s: --dem-min %d exceeds --dem-max %d\n", run->prog, o->dem_min, o->dem_max);
        return 2;
    }
    return 0;
}

/* the DEM-step rule in force, as the quasi-static drivers print it at start */
GK_INLINE void mpd_print_dem_rule(const mpd_opts *o) {
    if (o->dem_rule == GK_TWOSCALE_ADAPTIVE)
        printf("DEM steps per MPM step: adaptive, I <= %g then relaxation to an unbalanced force ratio < %g, "
               "%d..%d steps\n",
               o->dem_inertial, o->dem_unbalanced, o->dem_min, o->dem_max);
    else
        printf("DEM steps per MPM step: <= %g strain per DEM step, %d..%d steps\n", o->dem_strain, o->dem_min,
               o->dem_max);
}

static void mpd_usage_common(FILE *fp, const mpd_opts *d) {
    fprintf(
        fp,
        "common options (MPMxDEM):\n"
        "  --out DIR              output folder, created with its parents (default %s)\n"
        "  --threads T            OpenMP threads over the RVEs and the MPM (default %d)\n"
        "  --ppc K                material points per cell edge: K^2 per cell (default %d)\n"
        "  --basis B              linear | ugimp | quadratic | cubic (default ugimp; the paper: GIMP)\n"
        "  --alpha A              PIC fraction of the PIC/FLIP blend, eq 19 (default %g)\n"
        "  --cfl C                MPM step = C h / c, c from the RVE's Taylor tangent (default %g)\n"
        "  --packing FILE         RVE packing every point starts from (default %s)\n"
        "  --dem-rule R           adaptive | strain: DEM steps per MPM step from the inertial number and\n"
        "                         the unbalanced force (default), or from the strain per DEM step\n"
        "  --dem-inertial I       adaptive: inertial number bound of the RVE deformation (default %g)\n"
        "  --dem-unbalanced U     adaptive: relax until the unbalanced force ratio < U (default %g)\n"
        "  --dem-strain S         strain rule: RVE strain per DEM step bound (default %g)\n",
        d->out, d->threads, d->ppc, d->alpha, d->cfl, d->packing, d->dem_inertial, d->dem_unbalanced,
        d->dem_strain);
    fprintf(
        fp,
        "  --dem-min N --dem-max N  bounds of the DEM steps per MPM step (default %d, %d)\n"
        "  --dem-dt DT            DEM time step [s] (default %g)\n"
        "  --young E --kt-ratio R --friction-deg PHI --roll-beta B --roll-eta ETA\n"
        "                         DEM contact law, Liang & Zhao eqs 26-28 (defaults %g Pa, %g, %g deg, "
        "%g, %g)\n"
        "  --dem-damping A        local non-viscous damping in the RVEs, eq 29 (default %g)\n"
        "  --vtk-every N          VTK of the points every N MPM steps (default: first and last)\n"
        "  --checkpoint N         checkpoint every N MPM steps into DIR/checkpoint.bin (0: at the end)\n"
        "  --restart DIR          continue from DIR/checkpoint.bin (same flags) to the same result\n"
        "  --quiet                no progress lines\n"
        "MPI: build/<driver>_mpi (make mpi) under mpirun spreads the RVEs over the ranks (same results).\n"
        "exit status: 0 done, 1 setup or an output failed, 2 bad arguments, 3 the simulation failed\n",
        d->dem_min, d->dem_max, d->dem_dt, d->young, d->kt_ratio, d->friction_deg, d->roll_beta, d->roll_eta,
        d->dem_damping);
}

/* parse argv against the common table and the driver's; 0, 1 after --help (printed), 2 refused (the
 * driver checks the options together with mpd_check_opts once its defaults are settled) */
static int mpd_parse(const mpd_run *run, int argc, char **argv, mpd_opts *o, const cli_opt *mine,
                     void (*usage)(FILE *fp)) {
    cli_opt common[MPD_NCOMMON];
    const cli_opt *tables[3];
    int help = 0, r;
    mpd_common_opts(o, common);
    tables[0] = common, tables[1] = mine, tables[2] = NULL;
    r = cli_parse(run->rank == 0 ? run->prog : NULL, argc, argv, tables, &help);
    if (r) return 2;
    if (help) return usage(stdout), 1;
    return 0;
}

/* a comma-separated list of 1 to cap numbers in [lo, hi] ((lo, hi] if lo_open), increasing if
 * `rising`; the count, or -1 after a message naming the option */
GK_INLINE int mpd_list(const mpd_run *run, const char *opt, const char *s, double *v, int cap, double lo,
                       int lo_open, double hi, int rising) {
    const char *p = s;
    int n = 0;
    for (;;) {
        char tok[64], *end;
        size_t len = strcspn(p, ",");
        double x;
        if (n == cap || len == 0 || len >= sizeof tok) break;
        memcpy(tok, p, len), tok[len] = 0;
        errno = 0;
        x = strtod(tok, &end);
        if (*end || errno || !(lo_open ? x > lo : x >= lo) || !(x <= hi) ||
            (rising && n > 0 && !(x > v[n - 1])))
            break;
        v[n++] = x, p += len;
        if (*p == 0) return n;
        ++p; /* the comma: a value must follow */
    }
    fprintf(stderr, "%s: %s '%s': need 1 to %d%s numbers in %c%g, %g], comma-separated\n", run->prog, opt, s,
            cap, rising ? " increasing" : "", lo_open ? '(' : '[', lo, hi);
    return -1;
}

/* ------------------------------------------------------------ the RVE */
/* What every point of a driver starts from. */
typedef struct mpd_proto {
    gk_packing pk;  /* the packing file (every RVE is created from it)        */
    gk_rve_def def; /* the DEM definition built from the options              */
    double rho;     /* bulk density of the RVE: solid mass / cell volume      */
    double M;       /* P-wave modulus max(D_xxxx, D_yyyy), Taylor tangent [Pa] */
    double p0, e0;  /* pressure and void ratio of the consolidated state      */
    double dt;      /* DEM time step of its RVEs [s]                          */
} mpd_proto;

static gk_result mpd_proto_open(mpd_proto *P, const mpd_opts *o, gk_err *err) {
    memset(P, 0, sizeof *P);
    if (gk_packing_read(o->packing, &P->pk, NULL, err)) return err->code;
    if (P->pk.dim != 2) {
        gk_packing_free(&P->pk);
        return gk_err_set(err, GK_ERR_ARG, "%s is a %dD packing; the MPMxDEM drivers are 2D", o->packing,
                          P->pk.dim);
    }
    P->def = gk_rve_def_default();
    P->def.dt = o->dem_dt;
    P->def.mat.young = o->young;
    P->def.mat.kt_ratio = o->kt_ratio;
    P->def.mat.friction = tan(o->friction_deg * MPD_PI / 180.0);
    P->def.mat.roll_beta = o->roll_beta;
    P->def.mat.roll_eta = o->roll_eta;
    P->def.damping = o->dem_damping;
    return GK_OK;
}

static void mpd_proto_close(mpd_proto *P) { gk_packing_free(&P->pk); }

/* One RVE from the packing, brought to the isotropic pressure p (compression
 * positive) by gk_rve_consolidate with the contact friction on (the packing's
 * fabric is kept; the void ratio is what it becomes), its state in *st.
 * p <= 0: the packing as it is. Fills rho, M, p0, e0, dt of P from the result. */
static gk_result mpd_prepare_rve(mpd_proto *P, double p, gk_rve_state *st, gk_err *err) {
    gk_rve r;
    double s[9], D[16];
    gk_result res;
    if (gk_rve_create(&r, &P->def, &P->pk)) return gk_err_set(err, GK_ERR_ARG, "RVE: %s", gk_rve_error(&r));
    res = gk_rve_refresh(&r);
    if (!res && p > 0.0) {
        gk_consolidate_def cd;
        gk_consolidate_report rep;
        memset(&cd, 0, sizeof cd);
        cd.pressure = p;
        cd.friction = P->def.mat.friction;
        cd.stress_tol = 2e-3;
        res = gk_rve_consolidate(&r, &cd, &rep);
    }
    if (res) {
        gk_err_set(err, res, "RVE preparation at %g Pa: %s", p, gk_rve_error(&r));
        gk_rve_destroy(&r);
        return res;
    }
    gk_rve_stress(&r, s);
    if (gk_homog_tangent(&r, 0u, D)) {
        gk_rve_destroy(&r);
        return gk_err_set(err, GK_ERR_STATE, "RVE tangent failed");
    }
    P->rho = r.mass_total / gk_rve_volume(&r);
    P->M = D[0] > D[15] ? D[0] : D[15];
    P->p0 = gk_stress_p(s, 2);
    P->e0 = gk_homog_void_ratio(&r);
    P->dt = r.dt;
    res = gk_rve_state_save(st, &r);
    gk_rve_destroy(&r);
    if (res) return gk_err_set(err, res, "out of memory saving the RVE state");
    return GK_OK;
}

/* the level (0 at the top) of a point at height y in `levels` equal layers over `depth` (the
 * geostatic levels of mpd_prepare_levels; points outside take the nearest level) */
GK_INLINE int mpd_level_of(double depth, int levels, double y) {
    int k = (int)floor((depth - y) / (depth / levels));
    return k < 0 ? 0 : k >= levels ? levels - 1 : k;
}

/* Geostatic RVE levels (mpmdem_collapse, mpmdem_pipe): the packing prepared
 * as it is first (st[0]; its bulk density *rho_ref), then `levels` equal
 * layers over `depth`, each level's RVE consolidated (in parallel) to the
 * weight of the material above its layer's middle, at least half a cell h
 * deep: p[k] = rho_ref g z. Per level the density, void ratio, P-wave modulus
 * and pressure reached; *Mmax the largest modulus (and its value on entry).
 * 0, or 1 with the first failing level's message in *err. */
GK_INLINE int mpd_prepare_levels(mpd_proto *P, const mpd_opts *o, int levels, double depth, double g,
                                 double h, gk_rve_state *st, double *p, double *rho, double *e0, double *M,
                                 double *pa, double *rho_ref, double *Mmax, gk_err *err) {
    char msg[GK_ERR_MSG_LEN] = "";
    int k, bad = 0;
    if (mpd_proto_open(P, o, err) || mpd_prepare_rve(P, 0.0, &st[0], err)) return 1;
    *rho_ref = P->rho;
    for (k = 0; k < levels; ++k) {
        double z = depth * (k + 0.5) / levels;
        p[k] = *rho_ref * g * (z > 0.5 * h ? z : 0.5 * h);
    }
    GK_OMP(parallel for num_threads(o->threads) schedule(dynamic, 1))
    for (k = 0; k < levels; ++k) {
        mpd_proto Pk = *P;
        gk_err e;
        if (mpd_prepare_rve(&Pk, p[k], &st[k], &e)) {
            GK_OMP(critical) {
                bad = 1;
                snprintf(msg, sizeof msg, "%s", e.msg);
            }
            continue;
        }
        rho[k] = Pk.rho, e0[k] = Pk.e0, M[k] = Pk.M, pa[k] = Pk.p0;
    }
    if (bad) return gk_err_set(err, GK_ERR_STATE, "%s", msg), 1;
    for (k = 0; k < levels; ++k) *Mmax = fmax(*Mmax, M[k]);
    return 0;
}

/* A drained biaxial test of ONE RVE (the "pure DEM" of the MPMxDEM drivers:
 * mpmdem_footing's friction angle, mpmdem_single's reference): *r created
 * from the prepared state st, driven by gk_rve_set_servo with axis 0
 * stress-controlled at -s3 (s3 compression positive) and axis 1 compressed
 * at a constant rate, *rate [1/s]: the inertial number --dem-inertial at s3
 * with the adaptive DEM rule, --dem-strain per DEM step with the strain
 * rule, i.e. as the MPM's RVEs deform. gk_rve_step advances it; the axial
 * strain is 1 - F_yy of its cell. 0, or 1 with msg (*r destroyed). */
GK_INLINE int mpd_rve_biaxial(gk_rve *r, const mpd_proto *P, const gk_rve_state *st, const mpd_opts *o,
                              double s3, double *rate, char *msg, size_t nmsg) {
    gk_servo sv;
    double L[9];
    int k;
    if (gk_rve_create(r, &P->def, &P->pk)) return snprintf(msg, nmsg, "RVE: %s", gk_rve_error(r)), 1;
    if (gk_rve_state_restore(st, r)) {
        snprintf(msg, nmsg, "RVE: %s", gk_rve_error(r));
        gk_rve_destroy(r);
        return 1;
    }
    if (o->dem_rule == 0) { /* the inertial number the coupling's RVEs deform at, at s3 */
        double one[9], rmean = 0;
        for (k = 0; k < r->n; ++k) rmean += (double)r->r[k];
        rmean /= r->n;
        gk_m3_zero(one);
        one[4] = 1.0;
        *rate = o->dem_inertial / gk_inertial_number(one, 2, rmean, r->def.mat.density, s3);
    } else {
        *rate = o->dem_strain / r->dt; /* the coupling's strain per DEM step */
    }
    memset(&sv, 0, sizeof sv);
    sv.mode[0] = GK_SERVO_STRESS, sv.target[0] = -s3;
    sv.mode[1] = GK_SERVO_STRAIN, sv.rate[1] = -*rate;
    sv.mode[2] = GK_SERVO_STRAIN;
    sv.max_rate = 10.0 * *rate; /* lateral strain rate: dilatancy can exceed the axial one */
    sv.gain = 0.5;
    gk_m3_zero(L);
    if (gk_rve_set_velocity_gradient(r, L) || gk_rve_set_servo(r, &sv)) {
        snprintf(msg, nmsg, "servo: %s", gk_rve_error(r));
        gk_rve_destroy(r);
        return 1;
    }
    return 0;
}

/* ------------------------------------------------------- RVE per point */
typedef struct mpd_micro {
    gk_twoscale ts;            /* the RVEs (gk_twoscale.h)                                         */
    int n, freeze;             /* points; 1: a point whose RVE refuses dH as GK_ERR_CELL is frozen  */
    double *dH, *sig;          /* 9 n: the increments sent, the stresses back                       */
    double *eps;               /* 9 n: the point's small strain, sum of sym(dH) [Liang & Zhao (b)]  */
    int *nsub, *frozen, *thin; /* per point: DEM steps of the last MPM step; refused it; refusals   */
    int thin_step;             /* refusals in the last MPM step                                     */
    long long dem_steps;       /* DEM steps over all points and MPM steps (cost)                    */
    long long bytes;           /* bytes this rank sent to others in the MPM steps (MPI traffic)     */
    long warned;               /* frozen-point warnings printed                                     */
    double t;                  /* time at the start of the step (for those warnings)                */
    gk_twoscale_field *fld;    /* n: the fields of the accepted states (mpd_micro_fields)           */
} mpd_micro;

static void mpd_micro_free(mpd_micro *m) {
    if (m->ts.n > 0) gk_twoscale_destroy(&m->ts);
    free(m->dH), free(m->sig), free(m->eps), free(m->nsub), free(m->frozen), free(m->thin), free(m->fld);
    memset(m, 0, sizeof *m);
}

/* n points, point p starting from states[pick[p]] (pick NULL: states[0] everywhere); the RVEs'
 * stresses (2D block) into pts->sigma */
static gk_result mpd_micro_create(mpd_micro *m, gk_mpm_points *pts, const mpd_proto *P,
                                  const gk_rve_state *states, int nstates, const int *pick, const mpd_opts *o,
                                  gk_err *err) {
    gk_twoscale_def d;
    gk_twoscale_proto pr[64];
    int n = pts->n, k, p;
    memset(m, 0, sizeof *m);
    memset(&d, 0, sizeof d);
    if (nstates < 1 || nstates > 64) return gk_err_set(err, GK_ERR_ARG, "%d RVE states (1..64)", nstates);
    for (k = 0; k < nstates; ++k) pr[k].packing = &P->pk, pr[k].state = &states[k];
    d.npoints = n, d.protos = pr, d.nprotos = nstates, d.pick = pick;
    d.rve = P->def;
    d.rule.kind = o->dem_rule ? GK_TWOSCALE_STRAIN : GK_TWOSCALE_ADAPTIVE;
    d.rule.inertial_max = o->dem_inertial, d.rule.unbalanced_max = o->dem_unbalanced;
    d.rule.strain = o->dem_strain, d.rule.n_min = o->dem_min, d.rule.n_max = o->dem_max;
    d.threads = o->threads;
    m->n = n;
    m->dH = (double *)calloc(9 * (size_t)n, sizeof(double));
    m->sig = (double *)calloc(9 * (size_t)n, sizeof(double));
    m->eps = (double *)calloc(9 * (size_t)n, sizeof(double));
    m->nsub = (int *)calloc((size_t)n, sizeof(int));
    m->frozen = (int *)calloc((size_t)n, sizeof(int));
    m->thin = (int *)calloc((size_t)n, sizeof(int));
    m->fld = (gk_twoscale_field *)calloc((size_t)n, sizeof *m->fld);
    if (!m->dH || !m->sig || !m->eps || !m->nsub || !m->frozen || !m->thin || !m->fld) {
        mpd_micro_free(m);
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for %d points", n);
    }
    if (gk_twoscale_create(&m->ts, &d)) {
        gk_err_set(err, m->ts.err.code, "%s", gk_twoscale_error(&m->ts));
        mpd_micro_free(m);
        return err->code;
    }
    if (gk_twoscale_accepted(&m->ts, m->sig, NULL)) {
        gk_err_set(err, m->ts.err.code, "%s", gk_twoscale_error(&m->ts));
        mpd_micro_free(m);
        return err->code;
    }
    for (p = 0; p < n; ++p) { /* the point's stress is its RVE's (gk_mpm tracks the plane block) */
        double *s = pts->sigma + 9 * (size_t)p;
        const double *r = m->sig + 9 * (size_t)p;
        gk_m3_zero(s);
        s[0] = r[0], s[1] = r[1], s[3] = r[3], s[4] = r[4];
    }
    return GK_OK;
}

/* the fields of the accepted states into m->fld (collective under MPI) */
static gk_result mpd_micro_fields(mpd_micro *m, gk_err *err) {
    if (gk_twoscale_fields(&m->ts, m->fld))
        return gk_err_set(err, m->ts.err.code, "%s", gk_twoscale_error(&m->ts));
    return GK_OK;
}

/* gk_mpm_stress_fn: every point's RVE deforms by dH = dt L (stretch and spin)
 * by the DEM-step rule and returns its Love stress [Liang & Zhao 2019 Sec 2.3
 * (b)]. A failing RVE stops the run with its point and message - unless
 * m->freeze and it refused the increment because its cell would get too thin
 * (GK_ERR_CELL): that point keeps its RVE and stress, and its MPM strain goes
 * on (frozen, counted in m->thin, the first 20 named on stderr). */
static gk_result mpd_stress(gk_mpm_points *pts, double dt, void *user, gk_err *err) {
    mpd_micro *m = (mpd_micro *)user;
    const gk_twoscale_point *rp;
    gk_result res;
    int p, k, bad = -1, warn = 0;
    long long b0 = m->ts.stats.bytes_out;
    for (p = 0; p < pts->n; ++p) {
        double *dH = m->dH + 9 * (size_t)p;
        gk_mpm_point_dh(pts, p, dt, dH);
        dH[2] = dH[5] = dH[6] = dH[7] = dH[8] = 0.0; /* plane */
    }
    res = gk_twoscale_run(&m->ts, m->dH, NULL, m->sig, NULL);
    if (res && res != GK_ERR_STATE) return gk_err_set(err, res, "%s", gk_twoscale_error(&m->ts));
    rp = gk_twoscale_points(&m->ts);
    m->thin_step = 0;
    for (p = 0; p < pts->n; ++p) {
        const double *dH = m->dH + 9 * (size_t)p, *s = m->sig + 9 * (size_t)p;
        double *sp = pts->sigma + 9 * (size_t)p;
        int frz = m->freeze && rp[p].code == GK_ERR_CELL;
        if (rp[p].code && !frz) {
            if (bad < 0) bad = p;
            continue;
        }
        m->nsub[p] = rp[p].n_deform + rp[p].n_relax;
        m->dem_steps += rp[p].work;
        m->frozen[p] = frz;
        if (frz) {
            ++m->thin_step;
            warn += m->thin[p]++ == 0;
        } else
            sp[0] = s[0], sp[1] = s[1], sp[3] = s[3], sp[4] = s[4];
        for (k = 0; k < 9; ++k) m->eps[9 * (size_t)p + k] += 0.5 * (dH[k] + dH[3 * (k % 3) + k / 3]);
    }
    if (bad >= 0) {
        gk_twoscale_reject(&m->ts);
        return gk_err_set(err, (gk_result)rp[bad].code, "RVE of point %d at (%.4g, %.4g) m: %s", bad,
                          pts->x[0][bad], pts->x[1][bad], gk_twoscale_point_error(&m->ts, bad));
    }
    if (gk_twoscale_accept(&m->ts)) return gk_err_set(err, m->ts.err.code, "%s", gk_twoscale_error(&m->ts));
    m->bytes += m->ts.stats.bytes_out - b0; /* the step's: dH, results, migrations (not checkpoints) */
    if (warn && m->warned < 20 && mpd_micro_fields(m, err) == GK_OK)
        for (p = 0; p < pts->n && m->warned < 20; ++p)
            if (m->frozen[p] && m->thin[p] == 1) {
                const double *F = pts->F + 9 * (size_t)p;
                ++m->warned;
                fprintf(
                    stderr,
                    "warning: t = %.4f s: point %d at (%.4g, %.4g) m, F = [%.3g %.3g; %.3g %.3g]: its RVE "
                    "refuses dH (%s); frozen: no DEM steps, its stress kept (p = %.4g Pa, %g contacts) until "
                    "a "
                    "dH fits again\n",
                    m->t, p, pts->x[0][p], pts->x[1][p], F[0], F[1], F[3], F[4],
                    gk_twoscale_point_error(&m->ts, p), m->fld[p].p, m->fld[p].contacts);
            }
    return GK_OK;
}

/* ------------------------------------------------------ the MPM step */
/* A pressure on the boundary edge of a point (a follower load: it turns and
 * stretches with the point). In the reference configuration the edge has
 * its midpoint at x_p + off and the vector e (oriented so that the outward
 * normal is (e_y, -e_x) / |e|); now at x_p + F off and F e, and it receives
 * f = -pressure ((F e)_y, -(F e)_x): the pressure times the current length,
 * along the current normal. The force goes to the grid nodes with the weights
 * of the EDGE midpoint (the tent for linear/uGIMP), not of the point centre:
 * applied at the centre, half of it would land one node inside the body
 * (uGIMP at a cell centre splits 1/2-1/2) and the uniform initial state
 * would not be in equilibrium - the nodal loads here are the consistent ones
 * of a uniform pressure, matching the internal forces of a uniform stress. */
typedef struct mpd_edge {
    int p;           /* point index */
    double off[2];   /* reference offset centre -> edge midpoint [m] */
    double e[2];     /* reference edge vector [m] */
    double pressure; /* [Pa], compression positive */
} mpd_edge;

/* One USF step (Liang & Zhao 2019 Sec 2.3; the sequence gk_mpm_step runs)
 * with the edge loads added to the nodal external forces after P2G, then the
 * rigid bodies advance by v dt. The RVEs update in mpd_stress. */
static gk_result mpd_step(gk_mpm_grid *g, gk_mpm_points *pts, const gk_mpm_def *def, double dt, mpd_micro *m,
                          const mpd_edge *edge, int nedge, gk_err *err) {
    gk_mpm_basis lb = def->basis == GK_MPM_UGIMP ? GK_MPM_LINEAR : def->basis;
    gk_result r;
    int k, a;
    if ((r = gk_mpm_p2g(g, pts, def, GK_MPM_P2G_MOMENTUM, err))) return r;
    if ((r = gk_mpm_g2p(g, pts, def, dt, GK_MPM_G2P_GRADIENT_OLD, err))) return r;
    if ((r = mpd_stress(pts, dt, m, err))) return r;
    if ((r = gk_mpm_p2g(g, pts, def, GK_MPM_P2G_FORCE, err))) return r;
    for (k = 0; k < nedge; ++k) {
        const mpd_edge *E = &edge[k];
        const double *F = pts->F + 9 * (size_t)E->p;
        double x[3], fe[2];
        gk_mpm_stencil st;
        x[0] = pts->x[0][E->p] + F[0] * E->off[0] + F[1] * E->off[1];
        x[1] = pts->x[1][E->p] + F[3] * E->off[0] + F[4] * E->off[1];
        x[2] = 0.0;
        fe[0] = F[0] * E->e[0] + F[1] * E->e[1], fe[1] = F[3] * E->e[0] + F[4] * E->e[1];
        if ((r = gk_mpm_shape(g, lb, x, 0.0, &st, err))) return r;
        for (a = 0; a < st.n; ++a) {
            g->fext[0][st.node[a]] += -E->pressure * fe[1] * st.w[a];
            g->fext[1][st.node[a]] += E->pressure * fe[0] * st.w[a];
        }
    }
    if ((r = gk_mpm_grid_update(g, def, dt, err))) return r;
    if ((r = gk_mpm_g2p(g, pts, def, dt, GK_MPM_G2P_VELOCITY | GK_MPM_G2P_POSITION, err))) return r;
    gk_mpm_bodies_advance(g->body, g->nbody, dt);
    return GK_OK;
}

/* the MPM options every driver uses (Liang & Zhao: USF, PIC/FLIP blend) */
static gk_mpm_def mpd_mpm_def(const mpd_opts *o) {
    gk_mpm_def d = gk_mpm_def_default();
    d.basis = mpd_basis[o->basis];
    d.transfer = GK_MPM_PIC_FLIP;
    d.scheme = GK_MPM_USF;
    d.alpha = o->alpha;
    d.threads = o->threads;
    return d;
}

/* ghost node layers a basis needs outside the material (support radius) */
static int mpd_ghost_layers(const mpd_opts *o) { return mpd_basis[o->basis] == GK_MPM_CUBIC ? 3 : 2; }

/* ------------------------------------------------------------- fields */
#define MPD_NFIELD 9
static const char *mpd_field_names[MPD_NFIELD] = {
    "eps_q",        "eps_v",    "rotation_deg", "p", "q", "void_ratio", "fabric_anisotropy",
    "coordination", "dem_steps"};
enum { MPD_EPS_Q, MPD_EPS_V, MPD_ROTATION, MPD_P, MPD_Q, MPD_VOID, MPD_FABRIC, MPD_COORD, MPD_DEM };

/* every field of every point, field-major out[k n + p] (collective): eps_q [Liang & Zhao eq 35 with
 * the 2D deviator] and eps_v compression-positive (eq 34) of the point's strain, rotation of F = R U
 * [eqs 36-40] in degrees counter-clockwise, p, q [eqs 31-33] compression-positive [Pa], void ratio,
 * |F_a| [eqs 41-43], coordination 2 N_c / N_p, DEM steps of the last MPM step */
static gk_result mpd_fields(mpd_micro *m, const gk_mpm_points *pts, double *out, gk_err *err) {
    int n = pts->n, p;
    gk_result res = mpd_micro_fields(m, err);
    if (res) return res;
    for (p = 0; p < n; ++p) {
        const double *e = m->eps + 9 * (size_t)p;
        const gk_twoscale_field *f = &m->fld[p];
        out[MPD_EPS_Q * n + p] = gk_strain_q(e, 2);
        out[MPD_EPS_V * n + p] = -gk_strain_v(e, 2);
        out[MPD_ROTATION * n + p] = gk_rotation_angle(pts->F + 9 * (size_t)p, 2) * 180.0 / MPD_PI;
        out[MPD_P * n + p] = f->p, out[MPD_Q * n + p] = f->q, out[MPD_VOID * n + p] = f->void_ratio;
        out[MPD_FABRIC * n + p] = f->fabric, out[MPD_COORD * n + p] = f->coordination;
        out[MPD_DEM * n + p] = m->nsub[p];
    }
    return GK_OK;
}

#include "mpmdem_io.h"

#endif /* MPMDEM_H */
