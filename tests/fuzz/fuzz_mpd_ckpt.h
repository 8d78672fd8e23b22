/* fuzz_mpd_ckpt.h - the body of the harnesses of the MPMxDEM drivers' --restart reader (mpd_load of
 * examples/mpmdem_io.h with the driver's own check), for drivers whose model has the fields M, pts,
 * S, rows, snaps and run (fuzz_collapse_ckpt.c, fuzz_footing_ckpt.c). The harness file includes the
 * driver (its main renamed), then defines, before including this file:
 *   FZ_NAME               the driver's tag ("collapse") and the folders' name
 *   FZ_CHECK_FN           the driver's mpd_check_fn
 *   static MODEL X;                                   the driver's model (zeroed before fz_run)
 *   static const char *const fz_args[]                the tiny run's arguments (without --out)
 *   static const size_t fz_seed_at[]                  offsets into the state for the seeds' bit flips
 *   static int fz_run(int argc, char **argv)          the driver's run on X
 *   static gk_result fz_step(gk_err *err)             the driver's next step on X (after it, the
 *                                                      driver's row and snapshot bookkeeping)
 *   static void fz_free(void)                         what the driver's main frees
 * One tiny run is made once by the driver's own run, its RVEs of a 12-disk packing; its final checkpoint is the pristine one every
 * input starts from; the outputs of the steps the harness runs go to a third folder. Input: one mode
 * byte, then the file (an even mode byte writes the right checksum, fuzz_check.h). Each input:
 *   - refused: a message, and the points, strains, state, rows and snapshots byte for byte as before,
 *     the set's accepted stresses too (the set does not take the file's states);
 *   - accepted: the driver's check and mpd_block_check hold again, every point value and field is
 *     finite; then the driver's next step either gives finite positions, velocities and stresses, or
 *     stops with a message. The run then returns to the pristine checkpoint.
 * Seeds (FUZZ_MAKE_SEEDS): the pristine checkpoint, a truncated copy, a bit flipped in a point's
 * position, in its mass, in each byte of the state named by fz_seed_at (offsets into the state), in
 * the first row, and one with a tag no driver writes. */
#ifndef FUZZ_MPD_CKPT_H
#define FUZZ_MPD_CKPT_H
#include "fuzz_driver.h"
#include <stddef.h>

static char in_dir[400], ref_dir[400], out_dir[400], pk_path[400];
static unsigned char *snap0; /* the pristine run's block */
static size_t nsnap;
static double *acc0; /* the pristine set's accepted stresses */
static int ready;

static void cleanup(void) {
    fuzz_remove_dir(in_dir), fuzz_remove_dir(ref_dir), fuzz_remove_dir(out_dir), remove(pk_path);
    if (ready) fz_free(), free(snap0), free(acc0);
}

/* the run's state a checkpoint carries, as the driver writes it (malloc'ed) */
static unsigned char *model_bytes(size_t *n) {
    mpd_buf B;
    memset(&B, 0, sizeof B);
    mpd_block(&B, FZ_NAME, &X.M, &X.pts, &X.S, sizeof X.S, &X.rows, &X.snaps, 1);
    FUZZ_CHECK(!B.bad);
    *n = B.n;
    return B.b;
}

/* the model and the set as the pristine checkpoint left them */
static int same_as_pristine(void) {
    size_t n;
    unsigned char *b = model_bytes(&n);
    int same = n == nsnap && memcmp(b, snap0, n) == 0 && fuzz_same_set(&X.M.ts, acc0);
    free(b);
    return same;
}

/* the driver's call (setup) on DIR */
static gk_result load(const char *dir, gk_err *err) {
    return mpd_load(dir, &X.M, &X.pts, FZ_NAME, &X.S, sizeof X.S, &X.rows, &X.snaps, FZ_CHECK_FN, &X, err);
}

static void restore(void) {
    gk_err err;
    FUZZ_CHECK(load(ref_dir, &err) == GK_OK);
}

static void fuzz_setup(void) {
    char *argv[64];
    int argc = 0;
    (void)fz_seed_at; /* the seeds' (FUZZ_MAKE_SEEDS) */
    if (ready) return;
    fuzz_temp_dir(in_dir, sizeof in_dir, FZ_NAME, "in");
    fuzz_temp_dir(ref_dir, sizeof ref_dir, FZ_NAME, "ref");
    fuzz_temp_dir(out_dir, sizeof out_dir, FZ_NAME, "out");
    fuzz_temp_path(pk_path, sizeof pk_path, FZ_NAME, "pk");
    atexit(cleanup);
    fuzz_small_packing(pk_path, "fuzz_" FZ_NAME "_ckpt", 0.0, NULL); /* RVEs of 12 disks: small, fast */
    for (argc = 0; fz_args[argc]; ++argc) argv[argc] = (char *)fz_args[argc];
    argv[argc++] = (char *)"--packing", argv[argc++] = pk_path;
    argv[argc++] = (char *)"--out", argv[argc++] = ref_dir, argv[argc] = NULL;
    FUZZ_CHECK(argc < 64);
    memset(&X, 0, sizeof X);
    FUZZ_CHECK(fz_run(argc, argv) == 0 && X.rows.n >= 1);
    ready = 1;
    restore();
    X.run.out = out_dir; /* what the harness's steps write */
    snap0 = model_bytes(&nsnap);
    acc0 = fuzz_set_stresses(&X.M.ts);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    char why[200];
    size_t k;
    gk_err err;
    double *f;
    int n;
    if (size < 1) return 0;
    fuzz_setup();
    fuzz_write_checkpoint_in(in_dir, data, size);
    err.msg[0] = '\0';
    if (load(in_dir, &err) != GK_OK) {
        FUZZ_CHECK(err.msg[0] != '\0');
        FUZZ_CHECK(same_as_pristine());
        restore();
        return 0;
    }
    /* accepted: the checks hold, the points are finite, the fields too */
    n = X.pts.n;
    FUZZ_CHECK(FZ_CHECK_FN(&X.S, &X.rows, &X, why, sizeof why) == 0);
    FUZZ_CHECK(mpd_block_check(&X.M, &X.pts, &X.snaps, why, sizeof why) == 0);
    for (k = 0; k < 2; ++k) fuzz_all_finite(X.pts.x[k], (size_t)n), fuzz_all_finite(X.pts.v[k], (size_t)n);
    fuzz_all_finite(X.pts.sigma, 9 * (size_t)n), fuzz_all_finite(X.pts.F, 9 * (size_t)n),
        fuzz_all_finite(X.M.eps, 9 * (size_t)n);
    FUZZ_CHECK((f = (double *)malloc((size_t)MPD_NFIELD * n * sizeof *f)) != NULL);
    FUZZ_CHECK(mpd_fields(&X.M, &X.pts, f, &err) == GK_OK);
    fuzz_all_finite(f, (size_t)MPD_NFIELD * n);
    free(f);
    /* the driver's next step */
    err.msg[0] = '\0';
    if (fz_step(&err) == GK_OK) {
        for (k = 0; k < 2; ++k)
            fuzz_all_finite(X.pts.x[k], (size_t)n), fuzz_all_finite(X.pts.v[k], (size_t)n);
        fuzz_all_finite(X.pts.sigma, 9 * (size_t)n);
    } else
        FUZZ_CHECK(err.msg[0] != '\0');
    restore();
    FUZZ_CHECK(same_as_pristine());
    return 0;
}

#ifdef FUZZ_MAKE_SEEDS
int main(int argc, char **argv) {
    char name[64];
    unsigned char *b, *c;
    size_t n, b0, k, np, pts_end;
    if (argc < 2) return 2;
    fuzz_setup();
    b = fuzz_slurp_checkpoint(ref_dir, &n);
    FUZZ_CHECK((c = (unsigned char *)malloc(n)) != NULL);
    fuzz_write_seed(argv[1], "ckpt_" FZ_NAME, 0, b, n);
    fuzz_write_seed(argv[1], "ckpt_truncated", 0, b, n / 2);
    for (b0 = 0; b0 + 16 < n && memcmp(b + b0, MPD_BLOCK_TAG, sizeof MPD_BLOCK_TAG - 1); ++b0) continue;
    FUZZ_CHECK(b0 + 16 < n);
    np = (size_t)X.pts.n;
    pts_end = b0 + 44 + 10 * np * 8 + 36 * np * 8 + 9 * np * 8 + 4 * np + 8; /* the state */
    for (k = 0; k < sizeof fz_seed_at / sizeof *fz_seed_at + 3; ++k) {
        size_t at, m = sizeof fz_seed_at / sizeof *fz_seed_at;
        if (k < m)
            at = pts_end + fz_seed_at[k], snprintf(name, sizeof name, "ckpt_flip_state_%zu", fz_seed_at[k]);
        else if (k == m)
            at = b0 + 44 + 7, snprintf(name, sizeof name, "ckpt_flip_position");
        else if (k == m + 1)
            at = b0 + 44 + 6 * np * 8 + 7, snprintf(name, sizeof name, "ckpt_flip_mass");
        else
            at = pts_end + sizeof X.S + 8 + 7, snprintf(name, sizeof name, "ckpt_flip_row");
        FUZZ_CHECK(at < n);
        memcpy(c, b, n);
        c[at] ^= 0x40;
        fuzz_write_seed(argv[1], name, 0, c, n);
    }
    memcpy(c, b, n);
    memcpy(c + b0 + 10, "nothing\0", 8); /* a tag no driver writes */
    fuzz_write_seed(argv[1], "ckpt_other_tag", 0, c, n);
    free(b), free(c);
    return 0;
}
#endif
#endif /* FUZZ_MPD_CKPT_H */
