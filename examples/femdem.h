/* femdem.h - what the FEMxDEM drivers share (examples, not library).
 *
 * femdem_biaxial.c (biaxial and single-element tests), femdem_cyclic.c (cyclic simple shear) and
 * femdem_probe.c (the noise and Krylov diagnostics) are one 2D plane-strain FEM mesh (Q4 or Q8,
 * gk_fem.h) with a periodic DEM RVE at every Gauss point, the RVEs being a gk_twoscale set
 * (gk_twoscale.h): per Newton iteration every Gauss point gets the whole-step displacement
 * gradient dH = grad u (stretch and spin, Guo & Zhao 2014 eq 10), its RVE re-runs from the last
 * converged state and returns its Love stress (eq 5) and tangent (eq 9, or eq 8). This header
 * holds the model: options shared by the drivers (fd_common_opts, fd_usage_common), the mesh and
 * its boundary sets, the set of RVEs (fd_setup), the linear solve and the residual, the RVE
 * evaluation of an iterate (fd_eval) and the commit of a converged step. The outputs (CSV, VTK,
 * SVG) and the checkpoint are in femdem_io.h, the Newton iteration in femdem_newton.h.
 *
 * Built with GK_TWOSCALE_MPI (mpicc; `make mpi` builds build/femdem_biaxial_mpi) the RVEs are
 * spread over the MPI ranks; the FEM is replicated on every rank (the same numbers everywhere)
 * and rank 0 alone prints and writes (M->root).
 *
 * Every failed write of a result (CSV, VTK, SVG, checkpoint) is an error: the functions return
 * non-zero after saying so once, and the drivers exit with status 1.
 */
#ifndef FEMDEM_H
#define FEMDEM_H

#include "gk_fem.h"
#include "gk_io.h"
#include "gk_twoscale.h"
#include "cli.h"
#include <errno.h>
#include <stdarg.h>
#include <sys/stat.h>
#include <sys/types.h>

#define FD_AND_M 5             /* Anderson memory */
#define FD_DEM_INERTIAL 5e-4   /* adaptive rule defaults (see --help) */
#define FD_DEM_UNBALANCED 2e-2 /* measured for these drivers: femdem_biaxial.c's header */
#define FD_DEM_MAX_FACTOR 4    /* adaptive: --dem-max = 4 x the strain rule's count of the increment */
#define FD_DEM_STRAIN 1e-5     /* strain rule: the authors' */
#define FD_DEM_MIN 2
#define FD_DEM_MAX 20000
#define FD_DEM_EVERY 20 /* adaptive rule: relaxation steps between unbalanced-force checks */
#define FD_SEED_DT \
    3.1602315723728926e-05 /* the Guo & Zhao authors' YADE time step (PWaveTimeStep of rve400) */
#define FD_MAX_PACKINGS 64
#define FD_NFIELD 10
#define FD_PI 3.14159265358979323846

typedef struct fd_opts {
    int nx, ny, steps, threads, quad, max_iter, checkpoint, verbose, vtk_every, dem_min, dem_max, aitken;
    int elem_kind, tkind,
        tmode; /* --element q4|q8 (1); --tangent taylor|yade|relaxed|perturbation, as tmode: 0 1 3 2 */
    gk_elem_type elem;
    const char *out, *restart, *packing, *tangent, *test;
    double width, height, pressure, inc, tol, ftol, dt, dem_strain, xi;
    int dem_rule; /* --dem-rule: 0 adaptive (gk_rve_deform_adaptive), 1 strain */
    double dem_inertial, dem_unbalanced, tangent_reuse;
    int cyclic;      /* 0 biaxial/single, 1 cyclic strain-, 2 stress-controlled */
    int ed_newton;   /* E_d from the Newton correction before relaxation (1) or the step taken (0, eq 21) */
    int extrapolate; /* predictor: the last converged increment, scaled (1), or the tangent solve (0) */
    int relax_kind;  /* --relaxation aitken|anderson|none */
    unsigned long packing_seed; /* --packing A,B,...: seed of the per-Gauss-point draw */
    const char *fields_at;      /* --fields-at: axial strains [%] of the fabric maps (biaxial) */
    const char *cost_log;       /* --cost-log: the DEM steps of every Gauss point at every run (biaxial) */
    int balance_run;            /* --balance: MPI rebalance at every accept (0) or before every run (1) */
} fd_opts;

/* one row of a driver's CSV: the state after a converged step and the work of the step */
typedef struct fd_row {
    double eps, syy, sxx, ev, secs, Ed, Ef, inc;
    int iters, failed;
    /* DEM steps per Gauss point of the accepted iterate (mean, max); all DEM steps and tangents of the
     * step (every iteration, perturbed run and failed attempt since the last converged step) */
    double dem_mean;
    int dem_max;
    long long dem_total, t_reused, t_computed;
} fd_row;

struct fd_model;
/* a diagnostic at Newton iteration `it` (femdem_probe.c); non-zero: an RVE run failed */
typedef int (*fd_probe_fn)(struct fd_model *M, int it, double Ef, gk_err *err);

typedef struct fd_model {
    fd_opts o;
    const char *prog; /* for messages                                              */
    int root;         /* this rank prints and writes                               */
    gk_mesh mesh;
    gk_quad q;
    int ngp, npe, ndof;
    gk_twoscale ts; /* the RVEs, one per Gauss point                             */
    double *dH;     /* ngp x 9: dH of the last iterate                           */
    double *sig, *sig_n, *D, *D_n, *dNdx, *detJ, *v0;
    int *failed; /* Gauss points without contacts (tangent floored)          */
    long long pend_dem, pend_reused, pend_computed; /* work since the last converged step */
    gk_csr K;
    double *u, *du, *dprev, *fint, *fext, *R, *rhs, *utot, *A0x, *andF, *andG, *fprev, *Gprev;
    int *fix, nfix, *fixtop, *top, ntop, *right, nright, *lface, nlf, *rface, nrf, nfn;
    double area0, eps_done, scale;
    double *ulast, inclast; /* --predictor extrapolate: the last converged increment and its strain */
    int step;
    fd_row *curve;
    int ncurve, cap;
    double *hist; /* biaxial: the Gauss-point fields (FD_NFIELD each) of every row */
    /* cyclic: periodic ties, condensed matrix, reduced work arrays */
    gk_dofmap dm;
    gk_csr Kr;
    int *rfix;
    double *rvals, *rr, *ur;
    fd_probe_fn probe;                     /* diagnostics at a Newton iteration (NULL: none) */
    FILE *cost_log;                        /* --cost-log (rank 0; NULL: none)                  */
    int (*checkpoint)(struct fd_model *M); /* the driver's checkpoint (cut-back give-up)      */
} fd_model;

/* ------------------------------------------------------------ messages */
/* MPI started (the MPI build); whether this process prints and writes (rank 0) */
static int fd_start(int *argc, char ***argv) {
    int rank = 0;
#ifdef GK_TWOSCALE_MPI
    MPI_Init(argc, argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
#else
    (void)argc, (void)argv;
#endif
    return rank == 0;
}
static void fd_stop(void) {
#ifdef GK_TWOSCALE_MPI
    MPI_Finalize();
#endif
}

static void fd_say(const fd_model *M, const char *fmt, ...) {
    va_list ap;
    if (!M->root) return;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
}

/* rank 0's verdict on every rank (its writes decide) */
static int fd_agree(const fd_model *M, int bad) {
    (void)M;
#ifdef GK_TWOSCALE_MPI
    MPI_Bcast(&bad, 1, MPI_INT, 0, MPI_COMM_WORLD); /* the drivers run on the world (gk_twoscale_create) */
#endif
    return bad;
}

static double fd_norm(const double *v, int n) {
    double s = 0.0;
    int k;
    for (k = 0; k < n; ++k) s += v[k] * v[k];
    return sqrt(s);
}

/* --out: a directory (created); an existing file of that name is an error */
static int fd_mkdir_out(const fd_model *M) {
    struct stat st;
    int bad = 0;
    if (M->root) {
        if (mkdir(M->o.out, 0777) != 0 && errno != EEXIST)
            bad = 1;
        else if (stat(M->o.out, &st) != 0 || !S_ISDIR(st.st_mode))
            bad = 1;
        if (bad)
            fprintf(stderr, "%s: --out %s: cannot create that directory (a file of that name?)\n", M->prog,
                    M->o.out);
    }
    return fd_agree(M, bad);
}

/* ------------------------------------------------------------- options */
/* the options every FEMxDEM driver takes (o's fields); NULL-terminated */
static const cli_opt *fd_common_opts(fd_opts *o) {
    static cli_opt t[40];
    const cli_opt src[] = {
        {"--nx", CLI_INT, &o->nx, 1, 1000, NULL, NULL, 0},
        {"--ny", CLI_INT, &o->ny, 1, 1000, NULL, NULL, 0},
        {"--element", CLI_CHOICE, &o->elem_kind, 0, 0, NULL, "q4|q8", 0},
        {"--quad", CLI_INT, &o->quad, 1, 3, NULL, NULL, 0},
        {"--increment", CLI_REAL, &o->inc, 0, 0.1, NULL, NULL, CLI_LO_OPEN | CLI_HI_OPEN},
        {"--threads", CLI_INT, &o->threads, 1, 1024, NULL, NULL, 0},
        {"--out", CLI_STR, &o->out, 0, 0, NULL, NULL, 0},
        {"--tangent", CLI_CHOICE, &o->tkind, 0, 0, NULL, "taylor|yade|relaxed|perturbation", 0},
        {"--xi", CLI_REAL, &o->xi, 0, 1, "a number in (0, 1)", NULL, CLI_LO_OPEN | CLI_HI_OPEN},
        {"--restart", CLI_STR, &o->restart, 0, 0, NULL, NULL, 0},
        {"--checkpoint", CLI_INT, &o->checkpoint, 0, 1000000, NULL, NULL, 0},
        {"--packing", CLI_STR, &o->packing, 0, 0, NULL, NULL, 0},
        {"--packing-seed", CLI_ULONG, &o->packing_seed, 0, 0, NULL, NULL, 0},
        {"--width", CLI_REAL, &o->width, 0, HUGE_VAL, "a positive length", NULL, CLI_LO_OPEN | CLI_HI_OPEN},
        {"--height", CLI_REAL, &o->height, 0, HUGE_VAL, "a positive length", NULL, CLI_LO_OPEN | CLI_HI_OPEN},
        {"--pressure", CLI_REAL, &o->pressure, 0, HUGE_VAL, "a pressure >= 0", NULL, CLI_HI_OPEN},
        {"--tol", CLI_REAL, &o->tol, 0, HUGE_VAL, "a positive number", NULL, CLI_LO_OPEN | CLI_HI_OPEN},
        {"--ftol", CLI_REAL, &o->ftol, 0, HUGE_VAL, "a number >= 0", NULL, CLI_HI_OPEN},
        {"--ed", CLI_CHOICE, &o->ed_newton, 0, 0, NULL, "step|newton", 0},
        {"--max-iter", CLI_INT, &o->max_iter, 2, 100000, NULL, NULL, 0},
        {"--dt", CLI_REAL, &o->dt, 0, HUGE_VAL, "a positive time step", NULL, CLI_LO_OPEN | CLI_HI_OPEN},
        {"--vtk-every", CLI_INT, &o->vtk_every, 0, 1000000, NULL, NULL, 0},
        {"--relaxation", CLI_CHOICE, &o->relax_kind, 0, 0, NULL, "aitken|anderson|none", 0},
        {"--predictor", CLI_CHOICE, &o->extrapolate, 0, 0, NULL, "tangent|extrapolate", 0},
        {"--verbose", CLI_FLAG, &o->verbose, 0, 0, NULL, NULL, 0},
        {"--dem-rule", CLI_CHOICE, &o->dem_rule, 0, 0, NULL, "adaptive|strain", 0},
        {"--dem-inertial", CLI_REAL, &o->dem_inertial, 0, HUGE_VAL, "a positive number", NULL,
         CLI_LO_OPEN | CLI_HI_OPEN},
        {"--dem-unbalanced", CLI_REAL, &o->dem_unbalanced, 0, HUGE_VAL, "a positive number", NULL,
         CLI_LO_OPEN | CLI_HI_OPEN},
        {"--dem-strain", CLI_REAL, &o->dem_strain, 0, HUGE_VAL, "a positive number", NULL,
         CLI_LO_OPEN | CLI_HI_OPEN},
        {"--dem-min", CLI_INT, &o->dem_min, 1, 10000000, NULL, NULL, 0},
        {"--dem-max", CLI_INT, &o->dem_max, 1, 10000000, NULL, NULL, 0},
        {"--tangent-reuse", CLI_REAL, &o->tangent_reuse, 0, 1, "a fraction 0 <= X < 1 (0: off)", NULL,
         CLI_HI_OPEN},
        {"--balance", CLI_CHOICE, &o->balance_run, 0, 0, NULL, "accept|run", 0},
        {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    memcpy(t, src, sizeof src);
    return t;
}

/* defaults shared by the drivers (before parsing; a driver sets its own mesh and specimen) */
static void fd_opts_default(fd_opts *o) {
    memset(o, 0, sizeof *o);
    o->elem_kind = 1, o->steps = 100, o->threads = 2, o->quad = 2, o->max_iter = 20, o->checkpoint = 10;
    o->dem_min = FD_DEM_MIN, o->dem_max = 0 /* 0: from the rule, after parsing */;
    o->dem_inertial = FD_DEM_INERTIAL, o->dem_unbalanced = FD_DEM_UNBALANCED, o->dem_strain = FD_DEM_STRAIN;
    o->out = "femdem_out", o->tangent = "taylor", o->inc = 1e-3, o->tol = 0.01, o->ftol = 3e-3;
    o->dt = FD_SEED_DT, o->xi = 5e-5, o->packing_seed = 1;
}

/* after parsing: the words into modes, the rule's step bounds, the checks between options. 0, or 2
 * after a message. */
static int fd_opts_finish(const char *prog, fd_opts *o) {
    static const char *tnames[4] = {"taylor", "yade", "relaxed", "perturbation"};
    static const int tmode[4] = {0, 1, 3, 2}, relax[3] = {1, 2, 0}; /* relax: aitken anderson none */
    o->elem = o->elem_kind == 0 ? GK_Q4 : GK_Q8;
    o->tangent = tnames[o->tkind], o->tmode = tmode[o->tkind];
    o->aitken = relax[o->relax_kind];
    if (o->dem_max == 0) { /* default: the strain rule's 20000; adaptive 4 x the strain rule's count */
        o->dem_max = FD_DEM_MAX;
        if (o->dem_rule == 0 && o->inc > 0 && o->inc < 0.1 && o->dem_strain > 0)
            o->dem_max = (int)ceil(FD_DEM_MAX_FACTOR * o->inc / o->dem_strain - 1e-9);
        if (o->dem_max < o->dem_min) o->dem_max = o->dem_min;
    }
    if (o->dem_min > o->dem_max) {
        cli_say(prog, "%s: --dem-min %d exceeds --dem-max %d\n", prog, o->dem_min, o->dem_max);
        return 2;
    }
    return 0;
}

static void fd_usage_common(FILE *fp) {
    fprintf(
        fp,
        "  --nx, --ny N           elements across the width and the height\n"
        "  --element q8|q4        8-node serendipity (default) or 4-node bilinear quad\n"
        "  --quad 2|3             Gauss points per direction (default 2: Q8 reduced as in the authors'\n"
        "                         script, 4 RVEs per element; 3: Q8 full integration, 9 RVEs)\n"
        "  --increment F          strain per load step (default 0.001)\n"
        "  --threads T            OpenMP threads over the RVEs (results identical for any T)\n"
        "  --out DIR              output directory (created)\n"
        "  --tangent KIND         taylor (eq 9, sliding contacts k_t = 0, default), yade (eq 9 keeping\n"
        "                         k_t of sliding contacts, as the authors' code), relaxed (the\n"
        "                         RVE's contact network with the particles relaxed, GK_TANGENT_RELAXED:\n"
        "                         its quasi-static response without slip; 8 x 16 mesh: fewer iterations\n"
        "                         before the peak, 10 x the time per step), perturbation (eq 8)\n"
        "  --xi X                 perturbation size of eq 8 (default 5e-5, Guo & Zhao 2014 Fig 6)\n"
        "  --restart DIR          continue from DIR/checkpoint.bin (same mesh and packings)\n"
        "  --checkpoint K         write DIR/checkpoint.bin every K steps (default 10; always at the end)\n"
        "  --packing FILE[,FILE]  RVE at every Gauss point. A comma-separated list seeds heterogeneity:\n"
        "                         each Gauss point draws one of the files (uniformly, in Gauss-point\n"
        "                         order, from --packing-seed; the counts are printed; at most 64 files)\n"
        "  --packing-seed S       seed of that draw (default 1): the same list and seed give the same\n"
        "                         assignment on every run and restart\n"
        "  --tol T                Newton tolerance on E_d = |du|/|u| (eq 21; default 0.01)\n"
        "  --ftol F               a step also converges when E_f = |R_free|/|f_int| < F (default 0.003;\n"
        "                         0: eq 21 alone; see README \"Convergence\")\n");
    fprintf(
        fp,
        "  --ed step|newton       what E_d measures: step (default; eq 21 as written: the change of the\n"
        "                         iterate, so after an Aitken factor below 1 or a halving it is smaller\n"
        "                         than the Newton correction) or newton (the Newton correction before\n"
        "                         relaxation; a halving is not one)\n"
        "  --max-iter N           iterations before a load step is cut back (default 20)\n"
        "  --dt DT                DEM time step (default 3.16e-5 s, the authors')\n"
        "  --vtk-every K          VTK files every K steps (0: none)\n"
        "  --relaxation KIND      aitken (default): Newton corrections scaled by the Aitken factor of the\n"
        "                         last two corrections (in [0.25, 4]); anderson: Anderson mixing of the\n"
        "                         Newton map u + d(u) over the last iterates; none: plain Newton\n"
        "  --verbose              print E_d, E_f, the DEM steps per RVE (mean, max) and the time of every\n"
        "                         Newton iteration\n"
        "\nDEM steps per RVE run and tangent reuse:\n"
        "  --dem-rule R           DEM steps per RVE run: adaptive (default) = gk_rve_deform_adaptive: dH "
        "over\n"
        "                         n = ceil(I_1 / I_max) steps, I_1 the inertial number (eq 20) of dH in\n"
        "                         one DEM step at the RVE's pressure, then relaxation at fixed cell while "
        "the\n"
        "                         unbalanced force ratio > U; strain = the authors' rule n_s = max|dH| / S,\n"
        "                         no relaxation. Both clamped to [--dem-min, --dem-max] in all\n");
    fprintf(
        fp,
        "  --dem-inertial I       adaptive: inertial number bound I_max of the deformation (default %g)\n"
        "  --dem-unbalanced U     adaptive: relax until the unbalanced force ratio < U (default %g)\n"
        "  --dem-strain S         strain rule: RVE strain per DEM step (default %g: the authors' rule,\n"
        "                         100 steps per 0.1 %%); --dem-min N --dem-max N: exactly N steps per run\n"
        "  --dem-min, --dem-max   bounds of the DEM steps per RVE run (default %d, and %d with the strain\n"
        "                         rule, %d x the strain rule's count of --increment with the adaptive one:\n"
        "                         400 at 0.1 %%). A cut-back increment keeps the step count of the full one\n"
        "                         (either rule: S or I_max is scaled by the cut-back factor)\n"
        "  --tangent-reuse X      keep a Gauss point's last computed tangent while its contact network has\n"
        "                         changed by less than the fraction X since (default 0: off; 0 <= X < 1).\n"
        "                         Change = (contacts created + contacts lost + contacts whose sliding state\n"
        "                         flipped) / contacts when the tangent was computed; contacts are pairs of\n"
        "                         particle ids. The stored tangents and networks are in the checkpoint\n"
        "  --balance accept|run   MPI build: move RVEs between ranks by their cost after every accepted\n"
        "                         step (accept, default) or before every Newton iteration, by the last\n"
        "                         one's costs (run; gk_twoscale_def.balance). The results are the same\n",
        FD_DEM_INERTIAL, FD_DEM_UNBALANCED, FD_DEM_STRAIN, FD_DEM_MIN, FD_DEM_MAX, FD_DEM_MAX_FACTOR);
}

/* -------------------------------------------------------------- setup */
/* --packing A,B,...: the files (at most FD_MAX_PACKINGS), 2D; their number, or -1 (err set) */
static int fd_read_packings(const char *list_in, gk_packing *pks, gk_err *err) {
    char *list = (char *)malloc(strlen(list_in) + 1), *name, *save = NULL;
    int npk = 0, bad = 0;
    if (!list) return gk_err_set(err, GK_ERR_ALLOC, "out of memory"), -1;
    strcpy(list, list_in);
    for (name = strtok_r(list, ",", &save); name && !bad; name = strtok_r(NULL, ",", &save)) {
        if (npk == FD_MAX_PACKINGS) {
            gk_err_set(err, GK_ERR_ARG, "more than %d packings", FD_MAX_PACKINGS);
            bad = 1;
        } else if (gk_packing_read(name, &pks[npk], NULL, err))
            bad = 1;
        else if (pks[npk++].dim != 2) {
            gk_err_set(err, GK_ERR_ARG, "%s is a %dD packing; this driver is 2D", name, pks[npk - 1].dim);
            bad = 1;
        }
    }
    free(list);
    if (!bad && npk == 0) gk_err_set(err, GK_ERR_ARG, "--packing names no file"), bad = 1;
    if (bad) {
        while (npk > 0) gk_packing_free(&pks[--npk]);
        return -1;
    }
    return npk;
}

/* the prototype of the RVEs: cyclic with --pressure P differing from the packing's own by more than
 * 0.5 %: the packing re-consolidated to P with its contact friction (the fabric kept); 0, or 1 */
static int fd_consolidated(fd_model *M, const gk_rve_def *def, const gk_packing *pk, gk_rve_state *st,
                           int *use, gk_err *err) {
    gk_rve r;
    double s0[9], p0;
    *use = 0;
    if (!M->o.cyclic || !(M->o.pressure > 0)) return 0;
    if (gk_rve_create(&r, def, pk)) return gk_err_set(err, GK_ERR_ARG, "RVE: %s", gk_rve_error(&r)), 1;
    if (gk_rve_refresh(&r)) {
        gk_err_set(err, GK_ERR_STATE, "%s", gk_rve_error(&r));
        gk_rve_destroy(&r);
        return 1;
    }
    gk_rve_stress(&r, s0);
    p0 = -0.5 * (s0[0] + s0[4]);
    if (fabs(p0 - M->o.pressure) > 5e-3 * M->o.pressure) {
        gk_consolidate_def cd;
        gk_consolidate_report rep;
        memset(&cd, 0, sizeof cd);
        cd.pressure = M->o.pressure;
        cd.friction = def->mat.friction; /* keep the fabric: no frictionless re-packing */
        if (gk_rve_consolidate(&r, &cd, &rep) || gk_rve_refresh(&r) || gk_rve_state_save(st, &r)) {
            gk_err_set(err, GK_ERR_STATE, "consolidation to %g Pa: %s", M->o.pressure, gk_rve_error(&r));
            gk_rve_destroy(&r);
            return 1;
        }
        if (M->root)
            printf("%s: RVE consolidated from p = %.1f kPa to %.1f kPa (void ratio %.4f)\n", M->prog,
                   p0 / 1e3, M->o.pressure / 1e3, rep.void_ratio);
        *use = 1;
    }
    gk_rve_destroy(&r);
    return 0;
}

/* the set of RVEs, one per Gauss point: the same packing everywhere (Guo & Zhao 2014: uniform RVE, no
 * imperfection), or with --packing A,B,... each Gauss point draws one of the files (gk_twoscale_draw:
 * seeded by --packing-seed, in Gauss-point order, so every run and restart gets the same assignment
 * whatever the thread or rank count); then the initial stresses and tangents */
static int fd_make_rves(fd_model *M, gk_err *err) {
    const fd_opts *o = &M->o;
    gk_packing pks[FD_MAX_PACKINGS];
    gk_twoscale_proto pr[FD_MAX_PACKINGS];
    gk_twoscale_def d;
    gk_twoscale_field *f = NULL;
    gk_rve_state st;
    int npk, k, g, *pick = NULL, cnt[FD_MAX_PACKINGS], use = 0, status = 1;
    gk_result res;
    memset(&d, 0, sizeof d);
    d.rve = gk_rve_def_default();
    d.rve.dt = o->dt;
    if ((npk = fd_read_packings(o->packing, pks, err)) < 0) return 1;
    gk_rve_state_init(&st, NULL);
    if (!(pick = (int *)malloc((size_t)M->ngp * sizeof *pick)) ||
        !(f = (gk_twoscale_field *)malloc((size_t)M->ngp * sizeof *f))) {
        gk_err_set(err, GK_ERR_ALLOC, "out of memory");
        goto out;
    }
    gk_twoscale_draw(M->ngp, npk, (uint64_t)o->packing_seed, pick);
    if (npk > 1 && M->root) {
        for (k = 0; k < npk; ++k) cnt[k] = 0;
        for (g = 0; g < M->ngp; ++g) ++cnt[pick[g]];
        printf("%s: %d packings drawn over %d Gauss points (--packing-seed %lu):", M->prog, npk, M->ngp,
               o->packing_seed);
        for (k = 0; k < npk; ++k) printf(" %d", cnt[k]);
        printf("\n");
    }
    if (fd_consolidated(M, &d.rve, &pks[0], &st, &use, err)) goto out;
    for (k = 0; k < npk; ++k) pr[k].packing = &pks[k], pr[k].state = NULL;
    if (use) pr[0].state = &st;
    d.npoints = M->ngp, d.protos = pr, d.nprotos = npk, d.pick = pick, d.threads = o->threads;
    d.rule.kind = o->dem_rule ? GK_TWOSCALE_STRAIN : GK_TWOSCALE_ADAPTIVE;
    d.rule.inertial_max = o->dem_inertial, d.rule.unbalanced_max = o->dem_unbalanced;
    d.rule.strain = o->dem_strain, d.rule.n_min = o->dem_min, d.rule.n_max = o->dem_max;
    d.rule.every = FD_DEM_EVERY;
    d.tangent = o->tmode == 2 ? GK_TWOSCALE_TANGENT_PERTURBATION : GK_TWOSCALE_TANGENT_HOMOG;
    /* perturbation: eq 9 where eq 8 is not run (the first tangent) */
    d.tangent_opts = o->tmode == 1 ? GK_TANGENT_SLIDING_KEEP : o->tmode == 3 ? GK_TANGENT_RELAXED : 0u;
    d.xi = o->xi, d.reuse = o->tangent_reuse;
    d.balance = o->balance_run ? GK_TWOSCALE_BALANCE_RUN : GK_TWOSCALE_BALANCE_ACCEPT;
    if ((res = gk_twoscale_create(&M->ts, &d)) != GK_OK) {
        gk_err_set(err, res, "RVEs: %s", gk_twoscale_error(&M->ts));
        goto out;
    }
    if (gk_twoscale_accepted(&M->ts, M->sig_n, M->D_n) || gk_twoscale_fields(&M->ts, f)) {
        gk_err_set(err, GK_ERR_STATE, "%s", gk_twoscale_error(&M->ts));
        goto out;
    }
    for (g = 0; g < M->ngp; ++g) M->v0[g] = f[g].volume;
    status = 0;
out:
    for (k = 0; k < npk; ++k) gk_packing_free(&pks[k]);
    gk_rve_state_free(&st);
    free(pick), free(f);
    return status;
}

/* the mesh, its boundary sets, the work arrays and the RVEs; 0, or 1 with err set */
static int fd_setup(fd_model *M, gk_err *err) {
    fd_opts *o = &M->o;
    int n[3], a;
    double org[3] = {0, 0, 0}, len[3];
    n[0] = o->nx, n[1] = o->ny, n[2] = 1;
    len[0] = o->width, len[1] = o->height, len[2] = 1;
    if (gk_mesh_structured(&M->mesh, o->elem, n, org, len, NULL, err)) return 1;
    if (gk_quad_rule(&M->q, o->elem, o->quad, err)) return 1;
    if (gk_mesh_check(&M->mesh, &M->q, err)) return 1;
    M->npe = M->mesh.npe;
    M->ngp = M->mesh.nelem * M->q.n;
    M->ndof = 2 * M->mesh.nnode;
    if (gk_csr_from_mesh(&M->K, &M->mesh, NULL, err)) return 1;
#define FD_ALLOC(p, n)                                                      \
    do {                                                                    \
        (p) = calloc((size_t)(n) + 1, sizeof *(p));                         \
        if (!(p)) return gk_err_set(err, GK_ERR_ALLOC, "out of memory"), 1; \
    } while (0)
    FD_ALLOC(M->dH, 9 * M->ngp);
    FD_ALLOC(M->sig, 9 * M->ngp);
    FD_ALLOC(M->sig_n, 9 * M->ngp);
    FD_ALLOC(M->D, 16 * M->ngp);
    FD_ALLOC(M->D_n, 16 * M->ngp);
    FD_ALLOC(M->dNdx, 16 * M->ngp);
    FD_ALLOC(M->detJ, M->ngp);
    FD_ALLOC(M->v0, M->ngp);
    FD_ALLOC(M->failed, M->ngp);
    FD_ALLOC(M->u, M->ndof);
    FD_ALLOC(M->du, M->ndof);
    FD_ALLOC(M->dprev, M->ndof);
    FD_ALLOC(M->andF, FD_AND_M * M->ndof);
    FD_ALLOC(M->andG, FD_AND_M * M->ndof);
    FD_ALLOC(M->fprev, M->ndof);
    FD_ALLOC(M->Gprev, M->ndof);
    FD_ALLOC(M->fint, M->ndof);
    FD_ALLOC(M->fext, M->ndof);
    FD_ALLOC(M->R, M->ndof);
    FD_ALLOC(M->rhs, M->ndof);
    FD_ALLOC(M->utot, M->ndof);
    FD_ALLOC(M->ulast, M->ndof);
    FD_ALLOC(M->A0x, M->ndof);
    FD_ALLOC(M->fix, M->ndof);
    FD_ALLOC(M->fixtop, M->ndof);
    FD_ALLOC(M->top, M->mesh.nnode);
    FD_ALLOC(M->right, M->mesh.nnode);
    FD_ALLOC(M->lface, 3 * M->mesh.nelem);
    FD_ALLOC(M->rface, 3 * M->mesh.nelem);
    memcpy(M->A0x, M->mesh.x, (size_t)M->ndof * sizeof(double));
    { /* boundary sets, fixed for the whole run (node ids persist) */
        double tol = 1e-9 * o->height, best = 1e30;
        int nb, *bot, centre = -1;
        FD_ALLOC(bot, M->mesh.nnode);
        nb = gk_mesh_nodes_on_plane(&M->mesh, 1, 0.0, tol, bot);
        M->ntop = gk_mesh_nodes_on_plane(&M->mesh, 1, o->height, tol, M->top);
        M->nright = gk_mesh_nodes_on_plane(&M->mesh, 0, o->width, tol, M->right);
        M->nlf = gk_mesh_faces_on_plane(&M->mesh, 0, 0.0, tol, M->lface, &M->nfn);
        M->nrf = gk_mesh_faces_on_plane(&M->mesh, 0, o->width, tol, M->rface, &M->nfn);
        M->nfix = 0;
        if (o->cyclic) { /* simple shear: bottom fixed; top u_x = platen (fixtop), u_y = 0 */
            for (a = 0; a < nb; ++a) {
                M->fix[M->nfix] = 2 * bot[a], M->fixtop[M->nfix++] = 0;
                M->fix[M->nfix] = 2 * bot[a] + 1, M->fixtop[M->nfix++] = 0;
            }
            for (a = 0; a < M->ntop; ++a) {
                M->fix[M->nfix] = 2 * M->top[a], M->fixtop[M->nfix++] = 1;
                M->fix[M->nfix] = 2 * M->top[a] + 1, M->fixtop[M->nfix++] = 0;
            }
        } else { /* biaxial: smooth platens, bottom-centre node pinned in x */
            for (a = 0; a < nb; ++a) {
                double dx = fabs(M->mesh.x[2 * bot[a]] - 0.5 * o->width);
                M->fix[M->nfix] = 2 * bot[a] + 1, M->fixtop[M->nfix++] = 0;
                if (dx < best - tol) best = dx, centre = bot[a];
            }
            for (a = 0; a < M->ntop; ++a) M->fix[M->nfix] = 2 * M->top[a] + 1, M->fixtop[M->nfix++] = 1;
            M->fix[M->nfix] = 2 * centre, M->fixtop[M->nfix++] = 0;
        }
        free(bot);
        if (o->cyclic) { /* left/right periodic: u(right node) = u(left node at the same height) */
            if (gk_dofmap_periodic(&M->dm, &M->mesh, 1u, NULL, tol, NULL, err) ||
                gk_dofmap_csr(&M->dm, &M->K, &M->Kr, NULL, err))
                return 1;
            FD_ALLOC(M->rfix, M->nfix);
            FD_ALLOC(M->rvals, M->nfix);
            FD_ALLOC(M->rr, M->dm.nred);
            FD_ALLOC(M->ur, M->dm.nred);
        }
    }
    M->cap = 64;
    FD_ALLOC(M->curve, M->cap);
#undef FD_ALLOC
    M->area0 = o->width * o->height;
    M->scale = 1.0;
    return fd_make_rves(M, err);
}

static void fd_free(fd_model *M) {
    void *p[] = {M->dH,    M->sig,   M->sig_n, M->D,     M->D_n,  M->dNdx,  M->detJ,   M->v0,   M->failed,
                 M->u,     M->du,    M->dprev, M->andF,  M->andG, M->fprev, M->Gprev,  M->fint, M->fext,
                 M->R,     M->rhs,   M->utot,  M->ulast, M->A0x,  M->fix,   M->fixtop, M->top,  M->right,
                 M->lface, M->rface, M->rfix,  M->rvals, M->rr,   M->ur,    M->curve,  M->hist};
    size_t k;
    for (k = 0; k < sizeof p / sizeof *p; ++k) free(p[k]);
    if (M->cost_log) fclose(M->cost_log); /* an error path: the driver closed it otherwise */
    gk_twoscale_destroy(&M->ts);
    gk_dofmap_free(&M->dm);
    gk_csr_free(&M->Kr);
    gk_csr_free(&M->K);
    gk_mesh_free(&M->mesh);
}

/* room for one more row */
static int fd_row_room(fd_model *M) {
    fd_row *c;
    if (M->ncurve < M->cap) return 0;
    c = (fd_row *)realloc(M->curve, 2 * (size_t)M->cap * sizeof *c);
    if (!c) return 1;
    M->curve = c, M->cap *= 2;
    return 0;
}

/* -------------------------------------------------------- the macro model */
static void fd_gradients(fd_model *M) {
    int e, g;
    for (e = 0; e < M->mesh.nelem; ++e)
        for (g = 0; g < M->q.n; ++g) {
            int id = e * M->q.n + g;
            gk_fem_jacobian(&M->mesh, e, M->q.xi[g], NULL, M->dNdx + 16 * (size_t)id, &M->detJ[id], NULL);
        }
}

static int fd_external_force(fd_model *M, gk_err *err) {
    double tl[3] = {M->o.pressure, 0, 0}, tr[3] = {-M->o.pressure, 0, 0};
    int f;
    memset(M->fext, 0, (size_t)M->ndof * sizeof(double));
    if (M->o.cyclic) return 0; /* simple shear: displacement-driven, no traction */
    for (f = 0; f < M->nlf; ++f)
        if (gk_fem_face_load(&M->mesh, M->nfn, M->lface + f * M->nfn, tl, M->fext, err)) return 1;
    for (f = 0; f < M->nrf; ++f)
        if (gk_fem_face_load(&M->mesh, M->nfn, M->rface + f * M->nfn, tr, M->fext, err)) return 1;
    return 0;
}

/* K from tangents D, rhs with Dirichlet values; solve into x */
static int fd_solve(fd_model *M, const double *D, const double *rhs_in, double top_value, double *x,
                    gk_err *err) {
    gk_solver s;
    double vals[4096], *vp = vals;
    int k, r = 0;
    gk_solver_init(&s);
    if (M->nfix > 4096 && !(vp = (double *)malloc((size_t)M->nfix * sizeof(double))))
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory"), 1;
    for (k = 0; k < M->nfix; ++k) vp[k] = M->fixtop[k] ? top_value : 0.0;
    memcpy(M->rhs, rhs_in, (size_t)M->ndof * sizeof(double));
    if (M->dm.n) { /* tied (periodic) dofs: solve K_r = T^T K T for the independent dofs */
        int nr = 0;
        if (gk_fem_assemble(&M->mesh, &M->q, D, NULL, &M->K, NULL, err) ||
            gk_dofmap_condense(&M->dm, &M->K, &M->Kr, err) ||
            gk_dofmap_restrict(&M->dm, NULL, M->rhs, M->rr, err) ||
            gk_dofmap_dirichlet(&M->dm, M->nfix, M->fix, vp, M->rfix, M->rvals, &nr, err) ||
            gk_fem_dirichlet(&M->Kr, M->rr, nr, M->rfix, M->rvals, err) ||
            gk_solver_factor(&s, &M->Kr, NULL, err) || gk_solver_solve(&s, M->rr, M->ur))
            r = 1;
        else
            gk_dofmap_expand(&M->dm, M->ur, 0, x);
    } else if (gk_fem_assemble(&M->mesh, &M->q, D, NULL, &M->K, NULL, err) ||
               gk_fem_dirichlet(&M->K, M->rhs, M->nfix, M->fix, vp, err) ||
               gk_solver_factor(&s, &M->K, NULL, err) || gk_solver_solve(&s, M->rhs, x))
        r = 1;
    gk_solver_free(&s);
    if (vp != vals) free(vp);
    return r;
}

/* residual R = f_int(sig) - f_ext, zero at prescribed dofs; returns E_f */
static double fd_residual(fd_model *M, const double *sig, gk_err *err) {
    int k;
    double nf;
    if (gk_fem_assemble(&M->mesh, &M->q, NULL, sig, NULL, M->fint, err)) return HUGE_VAL;
    for (k = 0; k < M->ndof; ++k) M->R[k] = M->fint[k] - M->fext[k];
    nf = fd_norm(M->fint, M->ndof);
    if (M->dm.n) { /* tied dofs: R_r = T^T R, kept at the independent dof of each reduced one */
        const gk_dofmap *dm = &M->dm;
        gk_dofmap_restrict(dm, NULL, M->R, M->rr, err);
        for (k = 0; k < M->nfix; ++k) M->rr[dm->red[M->fix[k]]] = 0.0;
        for (k = 0; k < M->ndof; ++k) M->R[k] = dm->rep[dm->red[k]] == k ? M->rr[dm->red[k]] : 0.0;
    } else
        for (k = 0; k < M->nfix; ++k) M->R[M->fix[k]] = 0.0;
    return nf > 0 ? fd_norm(M->R, M->ndof) / nf : 0.0;
}

/* every Gauss point: dH = grad u, its RVE from the converged state (gk_twoscale_run, the DEM step rule
 * and the cut-back scale M->scale), stress and tangent into M->sig and M->D. Counts the DEM steps and
 * tangents into M->pend_*. Returns the number of failed RVEs (their messages in err). */
static int fd_eval(fd_model *M, const double *u, gk_err *err) {
    const gk_twoscale_point *pts;
    gk_twoscale_run_def rd;
    gk_result res;
    int g, a, i, j, nbad = 0;
    for (g = 0; g < M->ngp; ++g) {
        const int *c = M->mesh.conn + (size_t)(g / M->q.n) * M->npe;
        double *H = M->dH + 9 * (size_t)g;
        gk_m3_zero(H);
        for (a = 0; a < M->npe; ++a)
            for (i = 0; i < 2; ++i)
                for (j = 0; j < 2; ++j) H[3 * i + j] += u[2 * c[a] + i] * M->dNdx[(size_t)g * 16 + 2 * a + j];
    }
    rd.scale = M->scale;
    if ((res = gk_twoscale_run(&M->ts, M->dH, &rd, M->sig, M->D)) != GK_OK && res != GK_ERR_STATE)
        return gk_err_set(err, res, "%s", gk_twoscale_error(&M->ts)), M->ngp; /* refused: nothing ran */
    pts = gk_twoscale_points(&M->ts);
    for (g = 0; g < M->ngp; ++g) {
        M->pend_dem += pts[g].work;
        M->pend_reused += pts[g].tangent == 2, M->pend_computed += pts[g].tangent == 1;
        nbad += pts[g].code != 0;
    }
    if (M->cost_log) { /* --cost-log: the load step being solved, its increment scale, every point's work */
        fprintf(M->cost_log, "%d %.17g", M->step + 1, M->scale);
        for (g = 0; g < M->ngp; ++g) fprintf(M->cost_log, " %d", pts[g].work);
        fprintf(M->cost_log, "\n");
    }
    if (nbad) gk_err_set(err, GK_ERR_STATE, "%s", gk_twoscale_error(&M->ts));
    return nbad;
}

/* DEM steps per Gauss point of the last RVE runs: mean and max */
static void fd_dem_stats(const fd_model *M, double *mean, int *mx) {
    const gk_twoscale_point *pts = gk_twoscale_points(&M->ts);
    long long sum = 0;
    int g;
    *mx = 0;
    for (g = 0; g < M->ngp; ++g) {
        int s = pts[g].n_deform + pts[g].n_relax;
        sum += s;
        if (s > *mx) *mx = s;
    }
    *mean = M->ngp > 0 ? (double)sum / M->ngp : 0.0;
}

/* a converged step's row: the DEM steps of the accepted iterate and the work since the last row */
static void fd_row_work(fd_model *M, fd_row *c) {
    fd_dem_stats(M, &c->dem_mean, &c->dem_max);
    c->dem_total = M->pend_dem, c->t_reused = M->pend_reused, c->t_computed = M->pend_computed;
    M->pend_dem = M->pend_reused = M->pend_computed = 0;
}

/* the closing keys of the RESULT lines: the DEM rule and the work of the whole run, summed over the
 * rows (so a restart, which reads the rows back, reports the whole run) */
static void fd_print_work_totals(const fd_model *M) {
    long long dtot = 0, reu = 0, comp = 0;
    int k, dmax = 0;
    for (k = 0; k < M->ncurve; ++k) {
        dtot += M->curve[k].dem_total, reu += M->curve[k].t_reused, comp += M->curve[k].t_computed;
        if (M->curve[k].dem_max > dmax) dmax = M->curve[k].dem_max;
    }
    if (M->root)
        printf(" dem_rule=%s dem_steps_total=%lld dem_steps_max=%d tangents_reused=%lld "
               "tangents_computed=%lld\n",
               M->o.dem_rule ? "strain" : "adaptive", dtot, dmax, reu, comp);
}

/* a Gauss point without contacts has D = 0; give it a small floor so that K stays invertible (and
 * mark the points with fewer contacts than half their particles as failed). Returns the floored. */
static int fd_floor_tangents(fd_model *M, double *D) {
    const gk_twoscale_point *pts = gk_twoscale_points(&M->ts);
    double mean = 0.0;
    int g, nf = 0, k;
    for (g = 0; g < M->ngp; ++g) mean += D[16 * g] + D[16 * g + 15];
    mean /= 2.0 * M->ngp;
    for (g = 0; g < M->ngp; ++g) {
        M->failed[g] = pts[g].contacts < pts[g].particles / 2;
        if (D[16 * g] + D[16 * g + 15] < 2e-3 * mean) {
            double Df[16];
            gk_fem_elastic_tangent(2, 1e-4 * mean, 0.2, Df);
            for (k = 0; k < 16; ++k) D[16 * g + k] += Df[k];
            ++nf;
        }
    }
    return nf;
}

/* a converged step: the trial states become the converged ones, the mesh moves */
static int fd_commit(fd_model *M, gk_err *err) {
    int k;
    if (gk_twoscale_accept(&M->ts)) return gk_err_set(err, GK_ERR_STATE, "%s", gk_twoscale_error(&M->ts)), 1;
    memcpy(M->sig_n, M->sig, (size_t)M->ngp * 9 * sizeof(double));
    memcpy(M->D_n, M->D, (size_t)M->ngp * 16 * sizeof(double));
    fd_floor_tangents(M, M->D_n);
    gk_mesh_update(&M->mesh, M->u);
    for (k = 0; k < M->ndof; ++k) M->utot[k] += M->u[k];
    return 0;
}

#endif /* FEMDEM_H */
