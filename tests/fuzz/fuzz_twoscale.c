/* fuzz_twoscale.c - libFuzzer harness: gk_twoscale_load (the two-scale
 * checkpoint reader behind the FEMxDEM and MPMxDEM drivers' --restart) on
 * arbitrary bytes.
 *
 * One small set is built once, deterministically: 2 points of a 2D linear
 * law with friction, prototypes a 12-disk and a 10-disk packing consolidated
 * to 100 kPa (point 0 the first, point 1 the second), tangent reuse on
 * (so the records carry a reference tangent and contact keys), the strain
 * rule with 2 to 6 DEM steps per run. One run with tangent is accepted and
 * that state is saved: the pristine checkpoint every input starts from.
 *
 * Input: one mode byte, then the file. The reader refuses any file whose
 * FNV-1a checksum does not match, so with an even mode byte the harness
 * writes the right checksum into the file's last 8 bytes first (the fuzzer
 * then reaches the header and record checks behind it); an odd mode byte
 * gives the bytes as they are. Each input:
 *   - a refused file must come with a message and leave the set exactly as
 *     it was (its checkpoint byte for byte the pristine one);
 *   - an accepted one must give finite accepted stresses, tangents and
 *     fields, be saved and read back, and run one small increment to GK_OK
 *     with finite stress and tangent, or stop with a message per failed
 *     point (never GK_OK with a NaN). The set then returns to the pristine
 *     checkpoint.
 * Seeds (tests/fuzz/corpus/twoscale): the pristine checkpoint, one without
 * tangent reference (before any run), one after two more runs, and
 * truncated and bit-flipped variants of the first, written by this file
 * compiled with -DFUZZ_MAKE_SEEDS:
 *   cc -O2 -Iinclude -Itests/fuzz -DFUZZ_MAKE_SEEDS tests/fuzz/fuzz_twoscale.c -lm -o build/seeds && build/seeds DIR
 * The files it reads and writes are in $TMPDIR (default /tmp), named by the
 * process id, removed at exit.
 * Build and run: make fuzz (tests/fuzz/replay.c explains the layout). */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_twoscale.h"
#include "fuzz_driver.h"

#define NPT 2
static gk_twoscale ts;
static unsigned char *pristine; /* the pristine checkpoint's bytes */
static size_t npristine;
static char in_path[512], out_path[512], ref_path[512];
static int ready;
static const double dH0[9] = {0, 1e-5, 0, -0.5e-5, 0, 0, 0, 0, 0};

static void cleanup(void) { remove(in_path), remove(out_path), remove(ref_path); }

/* the set's whole state as its checkpoint (with an empty driver block) equals the pristine one */
static int same_as_pristine(void) {
    unsigned char *b;
    size_t n;
    int same;
    FUZZ_CHECK(gk_twoscale_save(&ts, out_path, NULL, 0) == GK_OK);
    b = fuzz_slurp(out_path, &n);
    same = n == npristine && memcmp(b, pristine, n) == 0;
    free(b);
    return same;
}

static void setup(void) {
    static gk_packing pk[2];
    static gk_rve_state st[2];
    gk_twoscale_proto proto[2];
    gk_twoscale_def def;
    static const int pick[NPT] = {0, 1};
    double dH[9 * NPT], S[9 * NPT], D[16 * NPT];
    int k;
    if (ready) return;
    fuzz_temp_path(in_path, sizeof in_path, "twoscale", "in");
    fuzz_temp_path(out_path, sizeof out_path, "twoscale", "out");
    fuzz_temp_path(ref_path, sizeof ref_path, "twoscale", "ref");
    atexit(cleanup);
    memset(&def, 0, sizeof def);
    def.rve = gk_rve_def_default();
    for (k = 0; k < 2; ++k) {
        gk_gen_def g;
        gk_rve rve;
        gk_consolidate_def cd;
        gk_err e;
        memset(&g, 0, sizeof g);
        g.dim = 2, g.n = k ? 10 : 12, g.r_min = 0.4e-3, g.r_max = 0.6e-3, g.seed = 11 + (uint64_t)k;
        FUZZ_CHECK(gk_packing_generate(&pk[k], &g, NULL, &e) == GK_OK);
        memset(&rve, 0, sizeof rve);
        FUZZ_CHECK(gk_rve_create(&rve, &def.rve, &pk[k]) == GK_OK);
        memset(&cd, 0, sizeof cd);
        cd.pressure = 1e5, cd.max_steps = 200000;
        FUZZ_CHECK(gk_rve_consolidate(&rve, &cd, NULL) == GK_OK);
        gk_rve_state_init(&st[k], NULL);
        FUZZ_CHECK(gk_rve_state_save(&st[k], &rve) == GK_OK);
        gk_rve_destroy(&rve);
        proto[k].packing = &pk[k], proto[k].state = &st[k];
    }
    def.npoints = NPT, def.protos = proto, def.nprotos = 2, def.pick = pick;
    def.rule.kind = GK_TWOSCALE_STRAIN, def.rule.n_min = 2, def.rule.n_max = 6;
    def.reuse = 0.3, def.threads = 1;
    FUZZ_CHECK(gk_twoscale_create(&ts, &def) == GK_OK);
    for (k = 0; k < 9 * NPT; ++k) dH[k] = dH0[k % 9];
    FUZZ_CHECK(gk_twoscale_run(&ts, dH, NULL, S, D) == GK_OK && gk_twoscale_accept(&ts) == GK_OK);
    FUZZ_CHECK(gk_twoscale_save(&ts, ref_path, NULL, 0) == GK_OK);
    pristine = fuzz_slurp(ref_path, &npristine);
    ready = 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    size_t nb = 0;
    void *blk = NULL;
    gk_result r;
    double dH[9 * NPT], S[9 * NPT], D[16 * NPT];
    gk_twoscale_field f[NPT];
    double fv[NPT * (sizeof(gk_twoscale_field) / sizeof(double))];
    int k;
    if (size < 1) return 0;
    setup();
    fuzz_write_checkpoint(in_path, data, size);
    ts.err.msg[0] = '\0';
    r = gk_twoscale_load(&ts, in_path, &blk, &nb);
    if (r != GK_OK) {
        FUZZ_CHECK(gk_twoscale_error(&ts)[0] != '\0' && ts.err.code == r && blk == NULL);
        FUZZ_CHECK(same_as_pristine());
        return 0;
    }
    FUZZ_CHECK(blk != NULL && nb < size);
    /* the accepted states: finite stress, tangent and fields; written and read back */
    FUZZ_CHECK(gk_twoscale_accepted(&ts, S, D) == GK_OK);
    fuzz_all_finite(S, 9 * NPT), fuzz_all_finite(D, 16 * NPT);
    FUZZ_CHECK(gk_twoscale_fields(&ts, f) == GK_OK);
    memcpy(fv, f, sizeof fv);
    fuzz_all_finite(fv, sizeof fv / sizeof fv[0]);
    FUZZ_CHECK(gk_twoscale_save(&ts, out_path, blk, nb) == GK_OK);
    gk_twoscale_free_block(&ts, blk);
    blk = NULL;
    FUZZ_CHECK(gk_twoscale_load(&ts, out_path, &blk, &nb) == GK_OK);
    gk_twoscale_free_block(&ts, blk);
    /* one increment from them */
    for (k = 0; k < 9 * NPT; ++k) dH[k] = dH0[k % 9];
    r = gk_twoscale_run(&ts, dH, NULL, S, D);
    if (r == GK_OK) {
        fuzz_all_finite(S, 9 * NPT), fuzz_all_finite(D, 16 * NPT);
    } else {
        const gk_twoscale_point *pts = gk_twoscale_points(&ts);
        FUZZ_CHECK(r == GK_ERR_STATE && gk_twoscale_error(&ts)[0] != '\0');
        for (k = 0; k < NPT; ++k)
            FUZZ_CHECK(pts[k].code == GK_OK || gk_twoscale_point_error(&ts, k)[0] != '\0');
    }
    FUZZ_CHECK(gk_twoscale_accept(&ts) == GK_OK);
    FUZZ_CHECK(gk_twoscale_accepted(&ts, S, D) == GK_OK);
    fuzz_all_finite(S, 9 * NPT), fuzz_all_finite(D, 16 * NPT);
    /* back to the pristine set for the next input */
    FUZZ_CHECK(gk_twoscale_load(&ts, ref_path, &blk, &nb) == GK_OK);
    gk_twoscale_free_block(&ts, blk);
    FUZZ_CHECK(same_as_pristine());
    return 0;
}

#ifdef FUZZ_MAKE_SEEDS
/* the pristine checkpoint (with a driver block), one without tangent references (a fresh set), one
 * after two more runs, and truncated and bit-flipped copies of the first */
int main(int argc, char **argv) {
    static const char block[] = "driver block: step 1";
    unsigned char *b, *c;
    size_t n, k;
    double dH[9 * NPT], S[9 * NPT], D[16 * NPT];
    gk_twoscale_def def;
    gk_twoscale fresh;
    if (argc < 2) return 2;
    setup();
    FUZZ_CHECK(gk_twoscale_save(&ts, out_path, block, sizeof block) == GK_OK);
    b = fuzz_slurp(out_path, &n);
    fuzz_write_seed(argv[1], "ckpt_accepted", 0, b, n);
    fuzz_write_seed(argv[1], "ckpt_truncated_header", 0, b, 24);
    fuzz_write_seed(argv[1], "ckpt_truncated_record", 0, b, n / 2);
    fuzz_write_seed(argv[1], "ckpt_truncated_checksum", 1, b, n - 3);
    c = (unsigned char *)malloc(n);
    FUZZ_CHECK(c != NULL);
    for (k = 0; k < 4; ++k) { /* one bit flipped: in the header, the first record, a state, the block */
        static const char *names[4] = {"ckpt_flip_header", "ckpt_flip_record", "ckpt_flip_state",
                                       "ckpt_flip_block"};
        size_t at[4];
        at[0] = 20, at[1] = 8 + 32 + 4 * (2 + NPT) + 8 + 5, at[2] = n / 3, at[3] = n - 8 - sizeof block + 3;
        memcpy(c, b, n);
        c[at[k]] ^= 0x10;
        fuzz_write_seed(argv[1], names[k], (unsigned char)(k & 1), c,
                        n); /* header and state: checksum mended */
    }
    free(c);
    free(b);
    /* a fresh set: no tangent reference yet */
    def = ts.def;
    {
        gk_twoscale_proto proto[2];
        static const int pick[NPT] = {0, 1};
        proto[0].packing = &ts.pk[0], proto[1].packing = &ts.pk[1];
        proto[0].state = proto[1].state = NULL;
        def.protos = proto, def.nprotos = 2, def.pick = pick;
        FUZZ_CHECK(gk_twoscale_create(&fresh, &def) == GK_OK);
        FUZZ_CHECK(gk_twoscale_save(&fresh, out_path, NULL, 0) == GK_OK);
        gk_twoscale_destroy(&fresh);
    }
    b = fuzz_slurp(out_path, &n);
    fuzz_write_seed(argv[1], "ckpt_fresh", 0, b, n);
    free(b);
    for (k = 0; k < 9 * NPT; ++k) dH[k] = 3.0 * dH0[k % 9];
    for (k = 0; k < 2; ++k)
        FUZZ_CHECK(gk_twoscale_run(&ts, dH, NULL, S, D) == GK_OK && gk_twoscale_accept(&ts) == GK_OK);
    FUZZ_CHECK(gk_twoscale_save(&ts, out_path, NULL, 0) == GK_OK);
    b = fuzz_slurp(out_path, &n);
    fuzz_write_seed(argv[1], "ckpt_three_runs", 0, b, n);
    free(b);
    gk_twoscale_destroy(&ts);
    return 0;
}
#endif
