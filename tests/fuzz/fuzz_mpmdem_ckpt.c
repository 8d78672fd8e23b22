/* fuzz_mpmdem_ckpt.c - libFuzzer harness: the MPMxDEM biaxial driver's
 * --restart reader (mpd_load of examples/mpmdem_io.h: gk_twoscale_load, then
 * the driver block, mpd_block and mpd_block_check, then the driver's own
 * check bx_check of examples/mpmdem_biaxial.c) on arbitrary bytes. The driver
 * itself is compiled in (its main renamed), so the harness calls the very
 * functions and arguments the driver's setup uses.
 *
 * One small run is made once, deterministically, by the driver's own run():
 * 1 x 2 cells of 1 x 1 m, one point per cell, each with an RVE of a 12-disk
 * 2D packing (consolidated to 100 kPa by the driver), plate speed 1 m/s
 * without ramp, to 1.6 % axial strain with a row every 0.8 % (and the field
 * pictures of the 1.5 % stage, kept as snapshots); its final
 * checkpoint is the pristine one every input starts from.
 *
 * Input: one mode byte, then the file (DIR/checkpoint.bin); an even mode byte
 * makes the harness write the right FNV-1a checksum into the last 8 bytes (as
 * fuzz_twoscale.c), an odd one gives the bytes as they are. Each input:
 *   - refused: a message, and the points, strains, driver state, rows and
 *     snapshots byte for byte as before (the block the driver would write);
 *   - accepted: every point value finite, masses and volumes > 0, det F > 0,
 *     the plates finite boxes with a known contact law, every row finite, the
 *     fields finite; then the driver's next MPM step (mpd_step) either runs
 *     with finite positions, velocities and stresses, or stops with a
 *     message. The run then returns to the pristine checkpoint.
 * Seeds (tests/fuzz/corpus/mpmdem_ckpt): the pristine checkpoint, one of
 * another driver tag and truncated copies, written by this file compiled
 * with -DFUZZ_MAKE_SEEDS:
 *   cc -O2 -Iinclude -Itests/fuzz -DFUZZ_MAKE_SEEDS tests/fuzz/fuzz_mpmdem_ckpt.c -lm -o build/seeds && build/seeds DIR
 * Its folders are in $TMPDIR (default /tmp), named by the process id,
 * removed at exit. Build and run: make fuzz (tests/fuzz/replay.c). */
#define _POSIX_C_SOURCE 200809L
#define main mpmdem_biaxial_main
#include "../../examples/mpmdem_biaxial.c"
#undef main
#include "fuzz_driver.h"
#include <sys/stat.h>

static bx X;
static char in_dir[400], ref_dir[400], pk_path[400];
static unsigned char *snap0; /* the pristine run's block */
static size_t nsnap;
static int ready;

static void cleanup(void) {
    fuzz_remove_dir(in_dir), fuzz_remove_dir(ref_dir), remove(pk_path);
    if (ready) mpd_free_all(&X.M, &X.P, &X.pts, &X.g, &X.rows, &X.snaps), free(X.edge), free(X.fld), free(snap0);
}

/* the run's state a checkpoint carries, as the driver writes it (malloc'ed) */
static unsigned char *model_bytes(size_t *n) {
    mpd_buf B;
    memset(&B, 0, sizeof B);
    mpd_block(&B, "biaxial", &X.M, &X.pts, &X.S, sizeof X.S, &X.rows, &X.snaps, 1);
    FUZZ_CHECK(!B.bad);
    *n = B.n;
    return B.b;
}

static int same_as_pristine(void) {
    size_t n;
    unsigned char *b = model_bytes(&n);
    int same = n == nsnap && memcmp(b, snap0, n) == 0;
    free(b);
    return same;
}

/* the driver's call (setup) on DIR */
static gk_result load(const char *dir, gk_err *err) {
    return mpd_load(dir, &X.M, &X.pts, "biaxial", &X.S, sizeof X.S, &X.rows, &X.snaps, bx_check, &X, err);
}

static void restore(void) {
    gk_err err;
    FUZZ_CHECK(load(ref_dir, &err) == GK_OK);
}

static void fuzz_setup(void) {
    const char *tmp = getenv("TMPDIR");
    gk_packing pk;
    gk_gen_def g;
    gk_err err;
    char *argv[32];
    int argc = 0;
    if (ready) return;
    if (!tmp || !*tmp) tmp = "/tmp";
    snprintf(in_dir, sizeof in_dir, "%s/gk_fuzz_mpmdem_%ld_in", tmp, (long)getpid());
    snprintf(ref_dir, sizeof ref_dir, "%s/gk_fuzz_mpmdem_%ld_ref", tmp, (long)getpid());
    snprintf(pk_path, sizeof pk_path, "%s/gk_fuzz_mpmdem_%ld.pk", tmp, (long)getpid());
    FUZZ_CHECK(mkdir(in_dir, 0777) == 0 || errno == EEXIST);
    atexit(cleanup);
    memset(&g, 0, sizeof g);
    g.dim = 2, g.n = 12, g.r_min = 0.4e-3, g.r_max = 0.6e-3, g.seed = 11;
    FUZZ_CHECK(gk_packing_generate(&pk, &g, NULL, &err) == GK_OK);
    FUZZ_CHECK(gk_packing_write(pk_path, &pk, "fuzz_mpmdem_ckpt", &err) == GK_OK);
    gk_packing_free(&pk);
    {
        const char *a[] = {
            "mpmdem_biaxial", "--nx",    "1",          "--ny",      "2",       "--width",   "1",
            "--height",       "2",       "--velocity", "1",         "--ramp",  "0",         "--strain",
            "0.016",          "--every", "0.008",      "--threads", "1",       "--dem-max", "50",
            "--dem-dt",       "0",       "--packing",  pk_path,     "--quiet", "--out",     ref_dir};
        for (argc = 0; argc < (int)(sizeof a / sizeof *a); ++argc) argv[argc] = (char *)a[argc];
        argv[argc] = NULL;
    }
    memset(&X, 0, sizeof X);
    FUZZ_CHECK(run(&X, argc, argv) == 0 && X.rows.n >= 1);
    ready = 1;
    restore();
    snap0 = model_bytes(&nsnap);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    char path[600], why[200];
    size_t k;
    gk_err err;
    double *f;
    int n, r;
    if (size < 1) return 0;
    fuzz_setup();
    snprintf(path, sizeof path, "%s/checkpoint.bin", in_dir);
    fuzz_write_checkpoint(path, data, size);
    err.msg[0] = '\0';
    if (load(in_dir, &err) != GK_OK) {
        FUZZ_CHECK(err.msg[0] != '\0');
        FUZZ_CHECK(same_as_pristine());
        restore();
        return 0;
    }
    /* accepted: the driver's own checks hold, the points are finite, the fields too */
    n = X.pts.n;
    FUZZ_CHECK(bx_check(&X.S, &X.rows, &X, why, sizeof why) == 0);
    FUZZ_CHECK(mpd_block_check(&X.M, &X.pts, &X.snaps, why, sizeof why) == 0);
    for (k = 0; k < 2; ++k) fuzz_all_finite(X.pts.x[k], (size_t)n), fuzz_all_finite(X.pts.v[k], (size_t)n);
    fuzz_all_finite(X.pts.sigma, 9 * (size_t)n), fuzz_all_finite(X.pts.F, 9 * (size_t)n),
        fuzz_all_finite(X.M.eps, 9 * (size_t)n);
    FUZZ_CHECK((f = (double *)malloc((size_t)MPD_NFIELD * n * sizeof *f)) != NULL);
    FUZZ_CHECK(mpd_fields(&X.M, &X.pts, f, &err) == GK_OK);
    fuzz_all_finite(f, (size_t)MPD_NFIELD * n);
    free(f);
    /* the driver's next MPM step */
    err.msg[0] = '\0';
    X.S.body[1].v[1] = -X.b.velocity;
    r = mpd_step(&X.g, &X.pts, &X.def, X.dt, &X.M, X.edge, X.nedge, &err);
    if (r == GK_OK) {
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
/* the pristine checkpoint, truncated copies, bit flips in the block (a position, the mass, the plate's
 * contact law, a row), and one with another driver's tag */
int main(int argc, char **argv) {
    char p[600];
    unsigned char *b, *c;
    size_t n, b0, k;
    FILE *fp;
    long end;
    if (argc < 2) return 2;
    fuzz_setup();
    snprintf(p, sizeof p, "%s/checkpoint.bin", ref_dir);
    FUZZ_CHECK((fp = fopen(p, "rb")) && fseek(fp, 0, SEEK_END) == 0 && (end = ftell(fp)) > 0);
    n = (size_t)end;
    FUZZ_CHECK((b = (unsigned char *)malloc(n)) && (c = (unsigned char *)malloc(n)));
    rewind(fp);
    FUZZ_CHECK(fread(b, 1, n, fp) == n && fclose(fp) == 0);
    fuzz_write_seed(argv[1], "ckpt_biaxial", 0, b, n);
    fuzz_write_seed(argv[1], "ckpt_truncated", 0, b, n / 2);
    for (b0 = 0; b0 + 16 < n && memcmp(b + b0, MPD_BLOCK_TAG, sizeof MPD_BLOCK_TAG - 1); ++b0) continue;
    FUZZ_CHECK(b0 + 16 < n);
    for (k = 0; k < 4; ++k) {
        static const char *names[4] = {"ckpt_flip_position", "ckpt_flip_mass", "ckpt_flip_plate",
                                       "ckpt_flip_row"};
        size_t np = (size_t)X.pts.n, at[4],
               pts_end = b0 + 44 + 10 * np * 8 + 36 * np * 8 + 9 * np * 8 + 4 * np + 8;
        at[0] = b0 + 44 + 7;
        at[1] = b0 + 44 + 6 * np * 8 + 7;
        at[2] = pts_end + offsetof(bx_state, body) + sizeof(gk_mpm_body) + offsetof(gk_mpm_body, contact);
        at[3] = pts_end + sizeof(bx_state) + 8 + 8 + 7;
        memcpy(c, b, n);
        c[at[k]] ^= 0x40;
        fuzz_write_seed(argv[1], names[k], 0, c, n);
    }
    { /* the first snapshot's first outline polyline said to have 1000 points */
        size_t np = (size_t)X.pts.n, at = b0 + 44 + 10 * np * 8 + 36 * np * 8 + 9 * np * 8 + 4 * np + 8 +
                                          sizeof(bx_state) + 8 + (size_t)X.rows.n * sizeof(bx_row) + 4 + 4 +
                                          48 + 160 + 48 + 8 + offsetof(mpd_outline, len);
        int32_t big = 1000;
        FUZZ_CHECK(X.snaps.n >= 1 && at + 4 < n);
        memcpy(c, b, n);
        memcpy(c + at, &big, 4);
        fuzz_write_seed(argv[1], "ckpt_outline_1000_points", 0, c, n);
    }
    memcpy(c, b, n);
    memcpy(c + b0 + 10, "footing\0", 8);
    fuzz_write_seed(argv[1], "ckpt_other_tag", 0, c, n);
    free(b), free(c);
    return 0;
}
#endif
