/* fuzz_nonlocal_ckpt.c - libFuzzer harness: the --restart reader of the
 * nonlocal FEMxDEM driver (load_checkpoint of examples/nonlocal_io.h:
 * gk_twoscale_load_take with its take_checkpoint) on arbitrary bytes. The driver
 * itself is compiled in (its main renamed): its own run() makes the run, and
 * the harness calls its reader and its step (macro_step, track, record).
 *
 * One small run is made once, deterministically: the element-shear test (one
 * Hex8 element, one Gauss point) with a Hertz-Mindlin RVE of a 24-sphere 3D
 * packing (generated and consolidated to the test's 416 kPa here), 6 coarse
 * steps to a shear strain of 6e-4, DEM runs of 2 to 20 steps, the RVE alone
 * on 2 increments, stopped after step 3 (--stop-after): its checkpoint is
 * the pristine one every input starts from.
 *
 * Input: one mode byte, then the file (DIR/checkpoint.bin); an even mode
 * byte makes the harness write the right FNV-1a checksum into the last 8
 * bytes (as fuzz_twoscale.c), an odd one gives the bytes as they are. Each
 * input:
 *   - refused: a message on stderr, and the model (step, time, peak, the
 *     DEM count, the rows, displacements, velocities, stresses, the band
 *     profiles, arrival times, work per element, and what the reader derives
 *     from them: the current mesh, H, the element means, the forces, the
 *     hourglass energy, the kinetic energy) byte for byte as before;
 *   - accepted: every one of those finite and in range (the step within the
 *     run, rows with whole ascending steps up to it, time >= 0, |u| <= 10 x
 *     the specimen, the others within 1e100, arrival -1 or >= 0), then the
 *     driver's next coarse step (macro_step, then track and record as its
 *     loop does) either gives finite displacements, velocities, stresses and
 *     rows or stops with a message. The run then returns to the pristine
 *     checkpoint.
 * The driver's output is silenced during each call and its stderr captured
 * (to check that a refusal says something); FUZZ_VERBOSE=1 in the
 * environment lets it through (and skips that check).
 * Seeds (tests/fuzz/corpus/nonlocal_ckpt): the pristine checkpoint, one a
 * step later, truncated copies, bit flips in the block (the step, the time,
 * a displacement, a stress, a row) with the checksum mended, and one with
 * another version's tag, written by this file compiled with
 * -DFUZZ_MAKE_SEEDS:
 *   cc -O2 -Iinclude -Itests/fuzz -DFUZZ_MAKE_SEEDS tests/fuzz/fuzz_nonlocal_ckpt.c -lm -o build/seeds && build/seeds DIR
 * Its folders are in $TMPDIR (default /tmp), named by the process id,
 * removed at exit. Build and run: make fuzz (tests/fuzz/replay.c). */
#define _POSIX_C_SOURCE 200809L
#define main femdem_nonlocal_main
#include "../../examples/femdem_nonlocal.c"
#undef main
#include "fuzz_driver.h"

static opts O;
static micro MI;
static model MD;
static int *pick;
static uint64_t fpr;
static char in_dir[400], ref_dir[400], pk_path[400], cap_path[400];
static unsigned char *snap0; /* the pristine model's state */
static size_t nsnap;
static double *acc0; /* the pristine set's accepted stresses */
static int ready;

static void cleanup(void) {
    fuzz_remove_dir(in_dir), fuzz_remove_dir(ref_dir), remove(pk_path), remove(cap_path);
}

/* the model's state a checkpoint carries and what the reader derives from it, as bytes (malloc'ed) */
static unsigned char *model_bytes(size_t *n) {
    size_t nd = (size_t)MD.nd * 8, np9 = 9 * (size_t)MD.np * 8, ne = (size_t)MD.ne * 8,
           ny = (size_t)O.mesh[1] * 8;
    size_t parts[26];
    const void *src[26];
    src[0] = &MD.step, parts[0] = sizeof MD.step;
    src[1] = &MD.time, parts[1] = sizeof MD.time;
    src[2] = &MD.peak, parts[2] = sizeof MD.peak;
    src[3] = &MD.have12, parts[3] = sizeof MD.have12;
    src[4] = &MD.dem_total, parts[4] = sizeof MD.dem_total;
    src[5] = &MD.nrow, parts[5] = sizeof MD.nrow;
    src[6] = MD.rows, parts[6] = (size_t)MD.nrow * NCOL * 8;
    src[7] = &MD.kin, parts[7] = sizeof MD.kin;
    src[8] = MD.ur, parts[8] = (size_t)MD.nr * 8;
    src[9] = MD.vr, parts[9] = (size_t)MD.nr * 8;
    src[10] = MD.sig, parts[10] = np9;
    src[11] = MD.gam_peak, parts[11] = ny;
    src[12] = MD.prof12, parts[12] = 2 * ny;
    src[13] = MD.arrival, parts[13] = ne;
    src[14] = MD.wint, parts[14] = ne;
    src[15] = MD.u, parts[15] = nd;
    src[16] = MD.v, parts[16] = nd;
    src[17] = MD.cur.x, parts[17] = nd;
    src[18] = MD.Hn, parts[18] = np9;
    src[19] = MD.H, parts[19] = np9;
    src[20] = MD.He, parts[20] = 9 * ne;
    src[21] = MD.sige, parts[21] = 9 * ne;
    src[22] = MD.fext, parts[22] = nd;
    src[23] = MD.fint, parts[23] = nd;
    src[24] = MD.fe, parts[24] = 24 * ne;
    src[25] = MD.ehg, parts[25] = ne;
    return fuzz_concat(src, parts, 26, n);
}

/* the model and the set as the pristine checkpoint left them */
static int same_as_pristine(void) {
    size_t n;
    unsigned char *b = model_bytes(&n);
    int same = n == nsnap && memcmp(b, snap0, n) == 0 && fuzz_same_set(&MD.ts, acc0);
    free(b);
    return same;
}

static int load(const char *dir) {
    int bad;
    O.restart = dir;
    fuzz_quiet_begin();
    bad = load_checkpoint(&MD, fpr);
    fuzz_quiet_end();
    return bad;
}

static void free_all(void) {
    if (ready) free(pick), model_free(&MD), micro_free(&MI), free(snap0), free(acc0);
}

static void fuzz_setup(void) {
    gk_packing pk, out;
    gk_gen_def g;
    gk_rve rve;
    gk_consolidate_def cd;
    gk_rve_def def;
    gk_err err;
    char *argv[48];
    int argc, rc;
    if (ready) return;
    fuzz_temp_dir(in_dir, sizeof in_dir, "nonlocal", "in");
    fuzz_temp_dir(ref_dir, sizeof ref_dir, "nonlocal", "ref");
    fuzz_temp_path(pk_path, sizeof pk_path, "nonlocal", "pk");
    fuzz_temp_path(cap_path, sizeof cap_path, "nonlocal", "stderr");
    atexit(cleanup);
    fuzz_quiet_open(cap_path);
    {
        const char *a[] = {"femdem_nonlocal",
                           "--test",
                           "element-shear",
                           "--packing",
                           pk_path,
                           "--steps",
                           "6",
                           "--strain",
                           "6e-4",
                           "--dem-min",
                           "2",
                           "--dem-max",
                           "20",
                           "--lone-increments",
                           "2",
                           "--threads",
                           "1",
                           "--stop-after",
                           "3",
                           "--out",
                           ref_dir};
        for (argc = 0; argc < (int)(sizeof a / sizeof *a); ++argc) argv[argc] = (char *)a[argc];
        argv[argc] = NULL;
    }
    FUZZ_CHECK(parse(argc, argv, &O) == 0);
    /* the packing: 24 spheres of the driver's material, consolidated to the test's pressure */
    rve_def_make(&O, &def);
    memset(&g, 0, sizeof g);
    g.dim = 3, g.n = 24, g.r_min = 0.3e-3, g.r_max = 0.5e-3, g.seed = 7;
    FUZZ_CHECK(gk_packing_generate(&pk, &g, NULL, &err) == GK_OK);
    FUZZ_CHECK(gk_rve_create(&rve, &def, &pk) == GK_OK);
    memset(&cd, 0, sizeof cd);
    cd.pressure = O.pressure, cd.max_steps = 400000;
    FUZZ_CHECK(gk_rve_consolidate(&rve, &cd, NULL) == GK_OK);
    FUZZ_CHECK(gk_rve_to_packing(&rve, &out, NULL, &err) == GK_OK);
    FUZZ_CHECK(gk_packing_write(pk_path, &out, "fuzz_nonlocal_ckpt", &err) == GK_OK);
    gk_rve_destroy(&rve), gk_packing_free(&pk), gk_packing_free(&out);
    /* the run, as main makes it */
    memset(&MI, 0, sizeof MI), memset(&MD, 0, sizeof MD);
    gk_rve_state_init(&MI.st_imp, NULL);
    atexit(free_all);
    fuzz_quiet_begin();
    rc = run(&O, &MI, &MD, &pick, gk_wtime());
    fuzz_quiet_end();
    ready = 1;
    FUZZ_CHECK(rc == 0 && MD.step == 3 && MD.nrow == 4);
    fpr = fingerprint(&O, &MI.pk);
    FUZZ_CHECK(load(ref_dir) == 0);
    snap0 = model_bytes(&nsnap);
    acc0 = fuzz_set_stresses(&MD.ts);
}

/* the accepted model: every value finite and in range */
static void check_model(void) {
    size_t k, ny = (size_t)O.mesh[1];
    double L = fmax(MD.L[0], fmax(MD.L[1], MD.L[2]));
    long r;
    FUZZ_CHECK(MD.step >= 0 && MD.step <= MD.nsteps && MD.nrow >= 1 && MD.nrow <= MD.step + 2);
    FUZZ_CHECK(MD.time >= 0 && MD.time <= 1e100 && (fabs(MD.peak) <= 1e100 || MD.peak == -HUGE_VAL));
    FUZZ_CHECK((MD.have12 == 0 || MD.have12 == 1) && MD.dem_total >= 0 && isfinite(MD.kin));
    for (r = 0; r < MD.nrow; ++r) {
        const double *w = MD.rows + NCOL * r;
        for (k = 0; k < NCOL; ++k) FUZZ_CHECK(fabs(w[k]) <= 1e100);
        FUZZ_CHECK(w[0] == floor(w[0]) && w[0] >= (r ? w[-NCOL] + 1 : 0) && w[0] <= MD.step &&
                   w[NCOL - 1] >= 0);
    }
    for (k = 0; k < (size_t)MD.nd; ++k) FUZZ_CHECK(fabs(MD.u[k]) <= 10 * L && fabs(MD.v[k]) <= 1e100);
    for (k = 0; k < 9 * (size_t)MD.np; ++k) FUZZ_CHECK(fabs(MD.sig[k]) <= 1e100);
    for (k = 0; k < 3 * ny; ++k) FUZZ_CHECK(fabs(k < ny ? MD.gam_peak[k] : MD.prof12[k - ny]) <= 1e100);
    for (k = 0; k < (size_t)MD.ne; ++k)
        FUZZ_CHECK(fabs(MD.wint[k]) <= 1e100 &&
                   (MD.arrival[k] == -1.0 || (MD.arrival[k] >= 0 && MD.arrival[k] <= 1e100)));
    fuzz_all_finite(MD.H, 9 * (size_t)MD.np), fuzz_all_finite(MD.ehg, (size_t)MD.ne);
    fuzz_all_finite(MD.fint, (size_t)MD.nd), fuzz_all_finite(MD.fext, (size_t)MD.nd);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    int rc;
    long said;
    if (size < 1) return 0;
    fuzz_setup();
    fuzz_write_checkpoint_in(in_dir, data, size);
    O.restart = in_dir;
    fuzz_quiet_begin();
    rc = load_checkpoint(&MD, fpr);
    said = fuzz_quiet_end();
    if (rc) {
        FUZZ_CHECK(said != 0);
        FUZZ_CHECK(same_as_pristine());
        FUZZ_CHECK(load(ref_dir) == 0);
        return 0;
    }
    check_model();
    /* the driver's next coarse step, as its loop makes it (none after the last) */
    if (MD.step < MD.nsteps) {
        fuzz_quiet_begin();
        rc = macro_step(&MD);
        if (!rc) track(&MD), rc = record(&MD, 0.0);
        said = fuzz_quiet_end();
        if (rc == 0) {
            fuzz_all_finite(MD.u, (size_t)MD.nd), fuzz_all_finite(MD.v, (size_t)MD.nd);
            fuzz_all_finite(MD.sig, 9 * (size_t)MD.np), fuzz_all_finite(MD.fint, (size_t)MD.nd);
            fuzz_all_finite(MD.rows + NCOL * (MD.nrow - 1), NCOL);
        } else
            FUZZ_CHECK(said != 0);
    }
    FUZZ_CHECK(load(ref_dir) == 0);
    FUZZ_CHECK(same_as_pristine());
    return 0;
}

#ifdef FUZZ_MAKE_SEEDS
/* the pristine checkpoint, truncated copies, bit flips in the driver's block (checksum mended), one a
 * step later, one with another version's tag */
int main(int argc, char **argv) {
    unsigned char *b, *c;
    size_t n, b0, k;
    if (argc < 2) return 2;
    fuzz_setup();
    b = fuzz_slurp_checkpoint(ref_dir, &n);
    fuzz_write_seed(argv[1], "ckpt_step3", 0, b, n);
    for (b0 = 0; b0 + 16 < n && memcmp(b + b0, "GKFNL02", 8); ++b0) continue;
    FUZZ_CHECK(b0 + 16 < n);
    fuzz_write_seed(argv[1], "ckpt_truncated_block", 0, b, b0 + (n - b0) / 2);
    fuzz_write_seed(argv[1], "ckpt_truncated_records", 0, b, b0 / 2);
    FUZZ_CHECK((c = (unsigned char *)malloc(n)) != NULL);
    for (k = 0; k < 5; ++k) {
        static const char *names[5] = {"ckpt_flip_step", "ckpt_flip_time", "ckpt_flip_u", "ckpt_flip_stress",
                                       "ckpt_flip_row"};
        size_t a0 = b0 + sizeof(ckhead), at[5];
        at[0] = b0 + offsetof(ckhead, step) + 2;                                 /* the step: + 65536 */
        at[1] = b0 + offsetof(ckhead, time) + 7;                                 /* the time: its exponent */
        at[2] = a0 + 8 * 10 + 7;                                                 /* a displacement */
        at[3] = a0 + 8 * (2 * (size_t)MD.nr + 4) + 7;                            /* sigma_22 */
        at[4] = a0 + 8 * (2 * (size_t)MD.nr + 9 * (size_t)MD.np + NCOL * 2) + 7; /* row 2: its step */
        memcpy(c, b, n);
        c[at[k]] ^= 0x40;
        fuzz_write_seed(argv[1], names[k], 0, c, n);
    }
    memcpy(c, b, n);
    memcpy(c + b0, "GKFNL01", 8);
    fuzz_write_seed(argv[1], "ckpt_other_version", 0, c, n);
    free(c), free(b);
    /* a step later */
    O.stop_after = 4, O.restart = ref_dir, O.out = in_dir;
    FUZZ_CHECK(load(ref_dir) == 0);
    fuzz_quiet_begin();
    FUZZ_CHECK(macro_step(&MD) == 0 && record(&MD, 0.0) == 0 && save_checkpoint(&MD, fpr) == 0);
    fuzz_quiet_end();
    b = fuzz_slurp_checkpoint(in_dir, &n);
    fuzz_write_seed(argv[1], "ckpt_step4", 0, b, n);
    free(b);
    return 0;
}
#endif
