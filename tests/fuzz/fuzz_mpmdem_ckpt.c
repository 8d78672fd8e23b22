/* fuzz_mpmdem_ckpt.c - libFuzzer harness: the MPMxDEM biaxial driver's --restart reader (mpd_load of
 * examples/mpmdem_io.h: gk_twoscale_load, then the driver block, mpd_block and mpd_block_check, then
 * the driver's own check bx_check of examples/mpmdem_biaxial.c) on arbitrary bytes. The driver is
 * compiled in (its main renamed); the harness body, its promises and its seeds are those of
 * fuzz_mpd_ckpt.h. The run: 1 x 2 cells of 1 x 1 m, one point per cell, each with an RVE of a 12-disk
 * packing (consolidated to 100 kPa by the driver), plate speed 1 m/s without ramp, to 1.6 % axial
 * strain with a row every 0.8 % (and the field pictures of the 1.5 % stage, kept as snapshots). The
 * next step is the driver's: the plate's speed, mpd_step, then after_step (rows, the points A, B, C,
 * the stage index and its pictures).
 * Seeds (tests/fuzz/corpus/mpmdem_ckpt), written by this file compiled with -DFUZZ_MAKE_SEEDS:
 *   cc -O2 -Iinclude -Itests/fuzz -DFUZZ_MAKE_SEEDS tests/fuzz/fuzz_mpmdem_ckpt.c -lm -o build/seeds && build/seeds DIR
 * (the corpus also keeps ckpt_flip_plate and ckpt_outline_1000_points, seeds of an earlier version of
 * this harness: a plate's contact law flipped, a snapshot's outline said to hold 1000 points).
 * Its folders are in $TMPDIR (default /tmp), named by the process id, removed at exit. Build and run:
 * make fuzz (tests/fuzz/replay.c). */
#define _POSIX_C_SOURCE 200809L
#define main mpmdem_biaxial_main
#include "../../examples/mpmdem_biaxial.c"
#undef main
#include "fuzz_check.h"

#define FZ_NAME "biaxial"
#define FZ_CHECK_FN bx_check
static const char *const fz_args[] = {
    "mpmdem_biaxial", "--nx",    "1",          "--ny",      "2",      "--width",   "1",
    "--height",       "2",       "--velocity", "1",         "--ramp", "0",         "--strain",
    "0.016",          "--every", "0.008",      "--threads", "1",      "--dem-max", "50",
    "--dem-dt",       "0",       "--quiet",    NULL};
/* the state's stage index, the top plate's contact law and a watched point */
static const size_t fz_seed_at[] = {offsetof(bx_state, nstage),
                                    offsetof(bx_state, body) + sizeof(gk_mpm_body) +
                                        offsetof(gk_mpm_body, contact),
                                    offsetof(bx_state, pt) + 2};
static bx X;

/* the driver's main without its exit */
static int fz_run(int argc, char **argv) {
    gk_rve_state_init(&X.st0, NULL);
    mpd_begin(&X.run, "mpmdem_biaxial", &argc, &argv);
    return run(&X, argc, argv);
}

static void fz_free(void) {
    free(X.edge), free(X.fld);
    mpd_free_all(&X.M, &X.P, &X.pts, &X.g, &X.rows, &X.snaps);
    gk_rve_state_free(&X.st0);
}

/* the step of the driver's loop (run) */
static gk_result fz_step(gk_err *err) {
    const bx_opts *b = &X.b;
    double vplate = b->velocity * (b->ramp > 0 && X.S.t < b->ramp ? (X.S.t + 0.5 * X.dt) / b->ramp : 1.0);
    gk_result r;
    X.S.body[1].v[1] = -vplate;
    if ((r = mpd_step(&X.g, &X.pts, &X.def, X.dt, &X.M, X.edge, X.nedge, err)) != GK_OK) return r;
    FUZZ_CHECK(after_step(&X, vplate, gk_wtime(), gk_wtime(), X.S.step, X.S.step + 1) == 0);
    return GK_OK;
}

#include "fuzz_mpd_ckpt.h"
