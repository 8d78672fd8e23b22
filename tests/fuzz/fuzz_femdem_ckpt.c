/* fuzz_femdem_ckpt.c - libFuzzer harness: the FEMxDEM biaxial driver's
 * --restart reader (fdb_restart of examples/femdem_biaxial.h: fd_ck_load of
 * examples/femdem_io.h within gk_twoscale_load_take: the model's block, then
 * the driver's own part, then the model written) on arbitrary bytes, through
 * the driver's own functions.
 *
 * One small model is built once, deterministically: the single-element test
 * (one Q4 element, 2 x 2 Gauss points) on a 12-disk 2D packing consolidated
 * to 100 kPa, increment 1e-4, at most 2 Newton iterations; one load step is
 * run by the driver's loop (fdb_loop), which writes the pristine checkpoint
 * every input starts from.
 *
 * Input: one mode byte, then the file (DIR/checkpoint.bin). As in
 * fuzz_twoscale.c, an even mode byte makes the harness write the right
 * FNV-1a checksum into the file's last 8 bytes, so the fuzzer gets past
 * gk_twoscale_load to the driver's block; an odd one gives the bytes as
 * they are. Each input:
 *   - refused: a message, and the model (step, strain, increment scale,
 *     rows, mesh, displacements, stresses, tangents, last increment, fields
 *     of the rows) byte for byte as before;
 *   - accepted: every one of those in range and finite, the deformed mesh
 *     valid (gk_mesh_check), the Gauss-point fields finite, and the driver's
 *     next load step (fd_load_step) runs: converged with finite
 *     displacements, stresses and tangents, or not converged, or an error
 *     with a message. The model then returns to the pristine checkpoint.
 * Seeds (tests/fuzz/corpus/femdem_ckpt): the pristine checkpoint, one a step
 * later, one of the cyclic driver's tag, and truncated and bit-flipped
 * copies (checksum mended), written by this file compiled with
 * -DFUZZ_MAKE_SEEDS:
 *   cc -O2 -Iinclude -Itests/fuzz -DFUZZ_MAKE_SEEDS tests/fuzz/fuzz_femdem_ckpt.c -lm -o build/seeds && build/seeds DIR
 * Its folders are in $TMPDIR (default /tmp), named by the process id,
 * removed at exit. Build and run: make fuzz (tests/fuzz/replay.c). */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-function" /* the driver's header has more than this uses */
#endif
#include "gk_fem.h"
#include "gk_io.h"
#include "gk_twoscale.h"
#include "../../examples/femdem_biaxial.h"
#include "fuzz_fd.h"

static fd_model M;
static char in_dir[400], ref_dir[400], out_dir[400], pk_path[400];
static unsigned char *snap0; /* the pristine model's state */
static size_t nsnap;
static double *acc0; /* the pristine set's accepted stresses */
static int ready;

static void cleanup(void) {
    fuzz_remove_dir(in_dir), fuzz_remove_dir(ref_dir), fuzz_remove_dir(out_dir), remove(pk_path);
    if (ready) fd_free(&M), free(snap0), free(acc0);
}

/* the model's state a checkpoint carries, as bytes (malloc'ed): the model's block, then the driver's
 * part (the last increment, its displacements, the rows' fields) */
static unsigned char *model_bytes(size_t *n) {
    size_t nb, parts[4];
    unsigned char *b = fz_fd_bytes(&M, &nb), *all;
    const void *src[4];
    src[0] = b, parts[0] = nb;
    src[1] = &M.inclast, parts[1] = sizeof M.inclast;
    src[2] = M.ulast, parts[2] = (size_t)M.ndof * sizeof(double);
    src[3] = M.hist, parts[3] = (size_t)M.ncurve * M.ngp * FD_NFIELD * sizeof(double);
    all = fuzz_concat(src, parts, 4, n);
    free(b);
    return all;
}

/* the model and the set as the pristine checkpoint left them */
static int same_as_pristine(void) {
    size_t n;
    unsigned char *b = model_bytes(&n);
    int same = n == nsnap && memcmp(b, snap0, n) == 0 && fuzz_same_set(&M.ts, acc0);
    free(b);
    return same;
}

/* back to the pristine checkpoint */
static void restore(void) {
    gk_err err;
    M.o.restart = ref_dir;
    FUZZ_CHECK(fdb_restart(&M, &err) == 0);
    M.pend_dem = M.pend_reused = M.pend_computed = 0;
}

static void setup(void) {
    gk_rve_def def = gk_rve_def_default();
    gk_err err;
    if (ready) return;
    fuzz_temp_dir(in_dir, sizeof in_dir, "femdem", "in");
    fuzz_temp_dir(ref_dir, sizeof ref_dir, "femdem", "ref");
    fuzz_temp_dir(out_dir, sizeof out_dir, "femdem", "out");
    fuzz_temp_path(pk_path, sizeof pk_path, "femdem", "pk");
    atexit(cleanup);
    fuzz_small_packing(pk_path, "fuzz_femdem_ckpt", 1e5, &def); /* 12 disks consolidated to 100 kPa */
    /* the model: the driver's defaults, its single-element test, one load step */
    memset(&M, 0, sizeof M);
    M.prog = "fuzz_femdem_ckpt", M.root = 1;
    fdb_defaults(&M);
    M.o.test = "single", M.o.packing = pk_path, M.o.dt = def.dt, M.o.threads = 1, M.o.inc = 1e-4;
    M.o.steps = 1, M.o.max_iter = 2, M.o.checkpoint = 1, M.o.vtk_every = 0, M.o.out = ref_dir;
    FUZZ_CHECK(fdb_check(&M) == 0);
    M.checkpoint = fdb_checkpoint;
    FUZZ_CHECK(fd_setup(&M, &err) == 0);
    fdb_first_row(&M, &err);
    FUZZ_CHECK(fdb_record(&M) == 0);
    M.root = 0; /* quiet from here on (fd_say; no writes depend on it without MPI) */
    FUZZ_CHECK(fdb_loop(&M, gk_wtime(), &err) == 0 && M.ncurve == 2);
    M.o.out = out_dir;
    restore();
    snap0 = model_bytes(&nsnap);
    acc0 = fuzz_set_stresses(&M.ts);
    ready = 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    size_t n = 0, k;
    gk_err err;
    double L = 0.0, syy, sxx, ev, Ed = 0, Ef = 0;
    int r, iters = 0;
    if (size < 1) return 0;
    setup();
    fuzz_write_checkpoint_in(in_dir, data, size);
    err.msg[0] = '\0';
    M.o.restart = in_dir;
    if (fdb_restart(&M, &err)) {
        FUZZ_CHECK(err.msg[0] != '\0');
        FUZZ_CHECK(same_as_pristine());
        restore();
        return 0;
    }
    /* accepted: every value in range and finite */
    fz_fd_accepted(&M);
    n = (size_t)M.ndof;
    for (k = 0; k < n; ++k) L = fmax(L, fabs(M.A0x[k]));
    fuzz_all_finite(M.ulast, n);
    for (k = 0; k < n; ++k) FUZZ_CHECK(fabs(M.ulast[k]) <= 10 * L);
    fuzz_all_finite(M.hist, (size_t)M.ncurve * M.ngp * FD_NFIELD);
    FUZZ_CHECK(isfinite(M.inclast) && fabs(M.inclast) <= 1);
    /* the reactions of the restored state (the row the driver would print), then its next load step */
    FUZZ_CHECK(fd_external_force(&M, &err) == 0);
    fd_residual(&M, M.sig_n, &err);
    fdb_macro_state(&M, &syy, &sxx, &ev);
    FUZZ_CHECK(isfinite(syy) && isfinite(sxx) && isfinite(ev));
    err.msg[0] = '\0';
    r = fd_load_step(&M, M.o.inc * M.scale, &iters, &Ed, &Ef, &err);
    FUZZ_CHECK(r == 0 || r == 1 || (r == 2 && err.msg[0] != '\0'));
    if (r == 0) {
        fuzz_all_finite(M.u, n), fuzz_all_finite(M.sig, 9 * (size_t)M.ngp),
            fuzz_all_finite(M.D, 16 * (size_t)M.ngp);
        FUZZ_CHECK(isfinite(Ed) && isfinite(Ef));
    }
    if (r != 2) gk_twoscale_reject(&M.ts); /* fd_load_step rejected on 2 */
    restore();
    FUZZ_CHECK(same_as_pristine());
    return 0;
}

#ifdef FUZZ_MAKE_SEEDS
/* the pristine checkpoint, truncated and bit-flipped copies (in the model's block: the step, a row,
 * a node, a stress; in the driver's part: the last increment, a field), one a step later, and one
 * with the cyclic driver's tag */
int main(int argc, char **argv) {
    unsigned char *b, *c;
    size_t n, k, blk, b0;
    gk_err err;
    if (argc < 2) return 2;
    setup();
    b = fuzz_slurp_checkpoint(ref_dir, &n);
    fuzz_write_seed(argv[1], "ckpt_step1", 0, b, n);
    /* the driver's block starts with its tag; its size: the model's block plus the driver's part */
    for (b0 = 0; b0 + 16 < n && memcmp(b + b0, FDB_TAG, sizeof FDB_TAG); ++b0) continue;
    blk = 16 + 4 * sizeof(int) + sizeof(int) + 2 * sizeof(double) + sizeof(int) + 2 * sizeof(fd_row) +
          (2 * (size_t)M.ndof + 25 * (size_t)M.ngp) * sizeof(double) + sizeof(double) +
          (size_t)M.ndof * sizeof(double) + 2 * (size_t)M.ngp * FD_NFIELD * sizeof(double);
    FUZZ_CHECK(b0 + blk + 8 <= n);
    fuzz_write_seed(argv[1], "ckpt_truncated_block", 0, b, n - blk / 2);
    c = (unsigned char *)malloc(n);
    FUZZ_CHECK(c != NULL);
    for (k = 0; k < 6; ++k) {
        static const char *names[6] = {"ckpt_flip_step",   "ckpt_flip_row",     "ckpt_flip_node",
                                       "ckpt_flip_stress", "ckpt_flip_inclast", "ckpt_flip_field"};
        size_t at[6];
        at[0] = b0 + 16 + 4 * sizeof(int) + 3;
        at[1] = b0 + 16 + 6 * sizeof(int) + 2 * sizeof(double) + 7;
        at[2] = b0 + 16 + 6 * sizeof(int) + 2 * sizeof(double) + 2 * sizeof(fd_row) + 8 * 3 + 7;
        at[3] = at[2] + 2 * (size_t)M.ndof * sizeof(double);
        at[4] =
            b0 + blk - 2 * (size_t)M.ngp * FD_NFIELD * sizeof(double) - (size_t)M.ndof * sizeof(double) - 1;
        at[5] = b0 + blk - 3;
        memcpy(c, b, n);
        c[at[k]] ^= 0x40;
        fuzz_write_seed(argv[1], names[k], 0, c, n);
    }
    free(c), free(b);
    /* a step later */
    M.o.steps = 2, M.o.out = ref_dir;
    FUZZ_CHECK(fdb_loop(&M, gk_wtime(), &err) == 0 && M.ncurve == 3);
    b = fuzz_slurp_checkpoint(ref_dir, &n);
    fuzz_write_seed(argv[1], "ckpt_step2", 0, b, n);
    free(b);
    /* another driver's tag */
    FUZZ_CHECK(fd_ck_save(&M, "GKFEMCYC2", NULL) == 0);
    b = fuzz_slurp_checkpoint(ref_dir, &n);
    fuzz_write_seed(argv[1], "ckpt_other_tag", 0, b, n);
    free(b);
    return 0; /* the model is freed at exit */
}
#endif
