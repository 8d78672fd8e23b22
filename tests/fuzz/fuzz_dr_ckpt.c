/* fuzz_dr_ckpt.c - libFuzzer harness: the --restart reader of the FEMxDEM
 * dynamic-relaxation driver (load_checkpoint of examples/femdem_dr_io.h:
 * gk_twoscale_load_take with its take_checkpoint) on arbitrary bytes. The driver
 * itself is compiled in (its main renamed), so the harness calls the very
 * functions the driver's main does: parse, setup, run_fem.
 *
 * One small run is made once, deterministically: the biaxial test on a 1 x 1
 * mesh (4 Gauss points), each with a periodic-cell RVE of a 12-disk 2D
 * packing (consolidated to 100 kPa), 2 isotropic and 3 biaxial steps of at
 * most 4 DR iterations, RVE runs of at most 60 DEM steps, stopped after step
 * 3 (--stop-after): its checkpoint is the pristine one every input starts
 * from. The model's state that no checkpoint carries (supports, RVE
 * statistics, the DR's own state, scratch) is kept as setup left it and put
 * back before each restart, as a new process would have it.
 *
 * Input: one mode byte, then the file (DIR/checkpoint.bin). As in
 * fuzz_twoscale.c, an even mode byte makes the harness write the right
 * FNV-1a checksum into the file's last 8 bytes, so the fuzzer gets past
 * gk_twoscale_load to the driver's block; an odd one gives the bytes as they
 * are. Each input:
 *   - refused: a message on stderr, and the model (step, rows, displacements,
 *     velocities, the reference force, accumulated H, stresses, h_ic, J_ic,
 *     the DR's omega and counters) byte for byte as before;
 *   - accepted: every one of those finite and in range (the step at most
 *     the run's, one row per step, rows finite with their step and stage,
 *     h_ic and J_ic > 0 and the setup's before the end of stage 1, det(I +
 *     H) > 0, counters >= 0), then the driver's own loop (run_fem with
 *     --stop-after the next step) either runs that step to finite
 *     displacements, stresses and rows or stops with a message. The model
 *     then returns to the pristine checkpoint.
 * The driver's output is silenced during each call and its stderr captured
 * (to check that a refusal says something); FUZZ_VERBOSE=1 in the
 * environment lets it through (and skips that check) to read a sanitizer's
 * report.
 * Seeds (tests/fuzz/corpus/dr_ckpt): the pristine checkpoint, one a step
 * later, truncated copies, bit flips in the block (the step, h_ic, the DR's
 * omega, a displacement, an accumulated H, a stress, a row) with the
 * checksum mended, and one with another tag, written by this file compiled
 * with -DFUZZ_MAKE_SEEDS:
 *   cc -O2 -Iinclude -Itests/fuzz -DFUZZ_MAKE_SEEDS tests/fuzz/fuzz_dr_ckpt.c -lm -o build/seeds && build/seeds DIR
 * Its folders are in $TMPDIR (default /tmp), named by the process id,
 * removed at exit. Build and run: make fuzz (tests/fuzz/replay.c). */
#define _POSIX_C_SOURCE 200809L
#define main femdem_dr_main
#include "../../examples/femdem_dr.c"
#undef main
#include "fuzz_driver.h"

static model M;
static char in_dir[400], ref_dir[400], out_dir[400], pk_path[400], cap_path[400];
static unsigned char *snap0; /* the pristine model's state */
static size_t nsnap;
static double *acc0; /* the pristine set's accepted stresses */
static int ready;

/* the state no checkpoint carries, as setup left it */
static struct {
    unsigned char *fixed;
    gk_frame_stats *stats;
    double *deq, *H, *dH, *fint, *fext, *u0, resid_last;
    gk_dr dr;
} side0;

static void cleanup(void) {
    fuzz_remove_dir(in_dir), fuzz_remove_dir(ref_dir), fuzz_remove_dir(out_dir), remove(pk_path),
        remove(cap_path);
}

/* the model's state a checkpoint carries, as bytes (malloc'ed) */
static unsigned char *model_bytes(size_t *n) {
    size_t nd = (size_t)M.ndof * sizeof(double), g9 = 9 * (size_t)M.ngp * sizeof(double);
    size_t parts[22];
    const void *src[22];
    src[0] = &M.step_done, parts[0] = sizeof M.step_done;
    src[1] = &M.nrows, parts[1] = sizeof M.nrows;
    src[2] = M.rows, parts[2] = (size_t)M.nrows * sizeof(row);
    src[3] = &M.have_f0, parts[3] = sizeof M.have_f0;
    src[4] = &M.h_ic, parts[4] = sizeof M.h_ic;
    src[5] = &M.J_ic, parts[5] = sizeof M.J_ic;
    src[6] = &M.dr.omega, parts[6] = sizeof M.dr.omega;
    src[7] = &M.dr.total, parts[7] = sizeof M.dr.total;
    src[8] = &M.dr.f0, parts[8] = sizeof M.dr.f0;
    src[9] = &M.dem_total, parts[9] = sizeof M.dem_total;
    src[10] = &M.runs_total, parts[10] = sizeof M.runs_total;
    src[11] = &M.capped_total, parts[11] = sizeof M.capped_total;
    src[12] = &M.unconverged, parts[12] = sizeof M.unconverged;
    src[13] = &M.resid_max, parts[13] = sizeof M.resid_max;
    src[14] = &M.resid_step, parts[14] = sizeof M.resid_step;
    src[15] = &M.resid_over, parts[15] = sizeof M.resid_over;
    src[16] = M.u, parts[16] = nd;
    src[17] = M.v, parts[17] = nd;
    src[18] = M.f0, parts[18] = nd;
    src[19] = M.Hacc, parts[19] = g9;
    src[20] = M.P, parts[20] = g9;
    src[21] = &M.dr.u0, parts[21] = sizeof M.dr.u0;
    return fuzz_concat(src, parts, 22, n);
}

/* the model and the set as the pristine checkpoint left them */
static int same_as_pristine(void) {
    size_t n;
    unsigned char *b = model_bytes(&n);
    int same = n == nsnap && memcmp(b, snap0, n) == 0 && fuzz_same_set(&M.ts, acc0);
    free(b);
    return same;
}

static void *dup_bytes(const void *p, size_t n) {
    void *c = malloc(n + 1);
    FUZZ_CHECK(c != NULL);
    memcpy(c, p, n);
    return c;
}

/* what a new process has before its restart: setup's supports, statistics, DR state and scratch */
static void side_put(void) {
    size_t nd = (size_t)M.ndof, g9 = 9 * (size_t)M.ngp;
    memcpy(M.fixed, side0.fixed, nd), memcpy(M.stats, side0.stats, (size_t)M.ngp * sizeof *M.stats);
    memcpy(M.deq, side0.deq, (size_t)M.ngp * sizeof(double));
    memcpy(M.H, side0.H, g9 * sizeof(double)), memcpy(M.dH, side0.dH, g9 * sizeof(double));
    memcpy(M.fint, side0.fint, nd * sizeof(double)), memcpy(M.fext, side0.fext, nd * sizeof(double));
    memcpy(M.u0, side0.u0, nd * sizeof(double));
    M.resid_last = side0.resid_last, M.dr = side0.dr;
}

/* back to the pristine checkpoint */
static void restore(void) {
    int bad;
    side_put();
    M.o.restart = ref_dir;
    fuzz_quiet_begin();
    bad = load_checkpoint(&M);
    fuzz_quiet_end();
    FUZZ_CHECK(bad == 0);
}

static void fuzz_setup(void) {
    gk_rve_def def = gk_rve_def_default();
    char *argv[40];
    int argc, rc;
    size_t nd, g9;
    if (ready) return;
    fuzz_temp_dir(in_dir, sizeof in_dir, "dr", "in");
    fuzz_temp_dir(ref_dir, sizeof ref_dir, "dr", "ref");
    fuzz_temp_dir(out_dir, sizeof out_dir, "dr", "out");
    fuzz_temp_path(pk_path, sizeof pk_path, "dr", "pk");
    fuzz_temp_path(cap_path, sizeof cap_path, "dr", "stderr");
    atexit(cleanup);
    fuzz_quiet_open(cap_path);
    fuzz_small_packing(pk_path, "fuzz_dr_ckpt", 1e5, &def); /* 12 disks consolidated to 100 kPa */
    {
        const char *a[] = {"femdem_dr", "--nx",         "1",        "--ny",
                           "1",         "--frame",      "periodic", "--packing",
                           pk_path,     "--iso-steps",  "2",        "--steps",
                           "3",         "--max-dr",     "4",        "--rve-max-steps",
                           "60",        "--threads",    "1",        "--vtk-every",
                           "0",         "--checkpoint", "1",        "--stop-after",
                           "3",         "--out",        ref_dir};
        for (argc = 0; argc < (int)(sizeof a / sizeof *a); ++argc) argv[argc] = (char *)a[argc];
        argv[argc] = NULL;
    }
    memset(&M, 0, sizeof M);
    dr_opts_default(&M.o);
    FUZZ_CHECK(parse(argc, argv, &M.o) == 0);
    M.t0 = gk_wtime();
    fuzz_quiet_begin();
    rc = setup(&M);
    fuzz_quiet_end();
    FUZZ_CHECK(rc == 0);
    nd = (size_t)M.ndof, g9 = 9 * (size_t)M.ngp;
    side0.fixed = (unsigned char *)dup_bytes(M.fixed, nd);
    side0.stats = (gk_frame_stats *)dup_bytes(M.stats, (size_t)M.ngp * sizeof *M.stats);
    side0.deq = (double *)dup_bytes(M.deq, (size_t)M.ngp * sizeof(double));
    side0.H = (double *)dup_bytes(M.H, g9 * sizeof(double));
    side0.dH = (double *)dup_bytes(M.dH, g9 * sizeof(double));
    side0.fint = (double *)dup_bytes(M.fint, nd * sizeof(double));
    side0.fext = (double *)dup_bytes(M.fext, nd * sizeof(double));
    side0.u0 = (double *)dup_bytes(M.u0, nd * sizeof(double));
    side0.resid_last = M.resid_last, side0.dr = M.dr;
    fuzz_quiet_begin();
    rc = run_fem(&M);
    fuzz_quiet_end();
    FUZZ_CHECK(rc == 0 && M.step_done == 3 && M.nrows == 4);
    M.o.out = out_dir;
    restore();
    snap0 = model_bytes(&nsnap);
    acc0 = fuzz_set_stresses(&M.ts);
    ready = 1;
}

/* the accepted model: every value finite and in range */
static void check_model(void) {
    size_t nd = (size_t)M.ndof, k;
    double L = M.o.width > M.o.height ? M.o.width : M.o.height;
    int i, g, nsteps = M.o.iso_steps + M.o.steps;
    FUZZ_CHECK(M.step_done >= 0 && M.step_done <= nsteps && M.nrows == M.step_done + 1);
    for (i = 0; i < M.nrows; ++i) {
        const double *v = M.rows[i].v;
        for (k = 0; k < NCOL; ++k) FUZZ_CHECK(fabs(v[k]) <= 1e100);
        FUZZ_CHECK(v[0] == i && v[1] == (i > M.o.iso_steps ? 2 : 1) && v[9] >= 0 && v[9] <= INT_MAX);
        FUZZ_CHECK(v[10] >= 0 && v[11] >= 0);
    }
    FUZZ_CHECK(M.have_f0 == 0 || M.have_f0 == 1);
    FUZZ_CHECK(M.h_ic > 0 && M.h_ic <= M.o.height + 10 * L && M.J_ic > 0 && M.J_ic <= 1e100);
    if (M.step_done < M.o.iso_steps) FUZZ_CHECK(M.h_ic == M.o.height && M.J_ic == 1.0);
    FUZZ_CHECK(M.dr.omega >= 0 && M.dr.omega <= M.omega_max && M.dr.total >= 0);
    FUZZ_CHECK(M.dem_total >= 0 && M.runs_total >= 0 && M.capped_total >= 0 && M.unconverged >= 0);
    FUZZ_CHECK(M.unconverged <= M.step_done && M.resid_max >= 0 && M.resid_max <= 2);
    FUZZ_CHECK(M.resid_step >= 0 && M.resid_step <= M.step_done && M.resid_over >= 0 &&
               M.resid_over <= M.step_done);
    for (k = 0; k < nd; ++k) {
        FUZZ_CHECK(fabs(M.u[k]) <= 10 * L && (!side0.fixed[k] || M.u[k] == 0.0));
        FUZZ_CHECK(fabs(M.v[k]) <= 1e100 && fabs(M.f0[k]) <= 1e100);
    }
    for (g = 0; g < M.ngp; ++g) {
        double F[9];
        gk_m3_identity(F);
        for (i = 0; i < 9; ++i) {
            FUZZ_CHECK(fabs(M.Hacc[9 * g + i]) <= 1e6 && fabs(M.P[9 * g + i]) <= 1e100);
            F[i] += M.Hacc[9 * g + i];
        }
        FUZZ_CHECK(gk_m3_det(F) > 0);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    int bad, rc, step;
    long said;
    if (size < 1) return 0;
    fuzz_setup();
    fuzz_write_checkpoint_in(in_dir, data, size);
    M.o.restart = in_dir;
    fuzz_quiet_begin();
    bad = load_checkpoint(&M);
    said = fuzz_quiet_end();
    if (bad) {
        FUZZ_CHECK(said != 0);
        FUZZ_CHECK(same_as_pristine());
        restore();
        return 0;
    }
    check_model();
    /* the driver's own loop from this restart, to the next step */
    step = M.step_done;
    side_put();
    M.o.restart = in_dir, M.o.stop_after = step + 1;
    fuzz_quiet_begin();
    rc = run_fem(&M);
    said = fuzz_quiet_end();
    if (rc == 0) {
        fuzz_all_finite(M.u, (size_t)M.ndof), fuzz_all_finite(M.P, 9 * (size_t)M.ngp);
        fuzz_all_finite(M.Hacc, 9 * (size_t)M.ngp);
        for (bad = 0; bad < M.nrows; ++bad) fuzz_all_finite(M.rows[bad].v, NCOL);
    } else
        FUZZ_CHECK(said != 0);
    M.o.stop_after = 3;
    restore();
    FUZZ_CHECK(same_as_pristine());
    return 0;
}

#ifdef FUZZ_MAKE_SEEDS
/* the pristine checkpoint, truncated copies, bit flips in the driver's block (checksum mended), one a
 * step later, one with another driver's tag */
int main(int argc, char **argv) {
    unsigned char *b, *c;
    size_t n, b0, nb, k, nd, ng;
    uint32_t magic = CK_MAGIC;
    if (argc < 2) return 2;
    fuzz_setup();
    b = fuzz_slurp_checkpoint(ref_dir, &n);
    fuzz_write_seed(argv[1], "ckpt_step3", 0, b, n);
    /* the driver's block: its magic, then 8 ints and CK_ND reals, the arrays and the rows */
    nd = (size_t)M.ndof, ng = (size_t)M.ngp;
    nb = 4 + 4 * (CK_NI - 1) + 8 * (CK_ND + 3 * nd + 18 * ng + (size_t)NCOL * M.nrows);
    FUZZ_CHECK(n > nb + 8);
    b0 = n - 8 - nb;
    FUZZ_CHECK(memcmp(b + b0, &magic, 4) == 0);
    fuzz_write_seed(argv[1], "ckpt_truncated_block", 0, b, n - nb / 2);
    fuzz_write_seed(argv[1], "ckpt_truncated_records", 0, b, b0 / 2);
    FUZZ_CHECK((c = (unsigned char *)malloc(n)) != NULL);
    for (k = 0; k < 7; ++k) {
        static const char *names[7] = {"ckpt_flip_step", "ckpt_flip_h_ic",   "ckpt_flip_omega", "ckpt_flip_u",
                                       "ckpt_flip_H",    "ckpt_flip_stress", "ckpt_flip_row"};
        size_t d0 = b0 + 4 + 4 * (CK_NI - 1), a0 = d0 + 8 * CK_ND, at[7];
        at[0] = b0 + 4 + 4 * 5 + 3;                             /* step_done, its high byte */
        at[1] = d0 + 7;                                         /* h_ic: exponent */
        at[2] = d0 + 2 * 8 + 7;                                 /* omega */
        at[3] = a0 + 3 * 8 + 7;                                 /* u of node 1, y */
        at[4] = a0 + 3 * nd * 8 + 7;                            /* Hacc[0] of point 0 */
        at[5] = a0 + (3 * nd + 9 * ng) * 8 + 4 * 8 + 7;         /* P_22 of point 0 */
        at[6] = a0 + (3 * nd + 18 * ng) * 8 + NCOL * 8 * 2 + 7; /* row 2: its step */
        memcpy(c, b, n);
        c[at[k]] ^= 0x40;
        fuzz_write_seed(argv[1], names[k], 0, c, n);
    }
    memcpy(c, b, n);
    memcpy(c + b0, "FDR1", 4);
    fuzz_write_seed(argv[1], "ckpt_other_tag", 0, c, n);
    free(c), free(b);
    /* a step later */
    side_put();
    M.o.restart = ref_dir, M.o.stop_after = 4, M.o.out = ref_dir;
    fuzz_quiet_begin();
    FUZZ_CHECK(run_fem(&M) == 0);
    fuzz_quiet_end();
    b = fuzz_slurp_checkpoint(ref_dir, &n);
    fuzz_write_seed(argv[1], "ckpt_step4", 0, b, n);
    free(b);
    return 0;
}
#endif
