/* fuzz_pipe_ckpt.c - libFuzzer harness: the MPMxDEM pipe driver's --restart reader (mpd_load of
 * examples/mpmdem_io.h with the driver's check check_state of examples/mpmdem_pipe.c) on arbitrary
 * bytes. The driver is compiled in (its main renamed); the harness body, its promises and its seeds
 * are those of fuzz_mpd_ckpt.h. The run: a 4 m wide soil of 8 x 3 cells (96 points, their RVEs of 12
 * disks at their depths' pressures), the pipe stopped after 20 steps of its penetration. The next
 * step is the driver's: the pipe's speed (set_velocity), mpd_step, then after_step (rows, the stage,
 * the watched points).
 * Seeds (tests/fuzz/corpus/pipe_ckpt), written by this file compiled with -DFUZZ_MAKE_SEEDS:
 *   cc -O2 -Iinclude -Itests/fuzz -DFUZZ_MAKE_SEEDS tests/fuzz/fuzz_pipe_ckpt.c -lm -o build/seeds && build/seeds DIR
 * Its folders are in $TMPDIR (default /tmp), named by the process id, removed at exit. Build and run:
 * make fuzz (tests/fuzz/replay.c). */
#define _POSIX_C_SOURCE 200809L
#define main mpmdem_pipe_main
#include "../../examples/mpmdem_pipe.c"
#undef main
#include "fuzz_check.h"

#define FZ_NAME "pipe"
#define FZ_CHECK_FN check_state
static const char *const fz_args[] = {
    "mpmdem_pipe", "--width",   "4",    "--nx",        "8",  "--ny",        "3", "--penetration",
    "0.1",         "--lateral", "0.05", "--v-down",    "1",  "--v-lateral", "1", "--ramp",
    "0.02",        "--every",   "0.02", "--max-steps", "20", "--threads",   "1", "--quiet",
    "--dem-dt",    "0",         NULL};
/* the state's stage, next-row time, the row that ends the penetration and a watched point */
static const size_t fz_seed_at[] = {offsetof(pp_state, stage), offsetof(pp_state, next_out) + 7,
                                    offsetof(pp_state, pen_row), offsetof(pp_state, pt) + 2};
static pp X;

/* the driver's main without its exit */
static int fz_run(int argc, char **argv) {
    int k;
    for (k = 0; k < PP_MAX_LEVELS; ++k) gk_rve_state_init(&X.st[k], NULL);
    mpd_begin(&X.run, "mpmdem_pipe", &argc, &argv);
    return run(&X, argc, argv);
}

static void fz_free(void) {
    int k;
    free(X.pick), free(X.fld);
    mpd_free_all(&X.M, &X.P, &X.pts, &X.g, &X.rows, &X.snaps);
    for (k = 0; k < PP_MAX_LEVELS; ++k) gk_rve_state_free(&X.st[k]);
}

/* the step of the driver's loop (run) */
static gk_result fz_step(gk_err *err) {
    double ds;
    gk_result r;
    if (X.S.stage >= 2) return GK_OK; /* the path is done: the driver runs no step */
    ds = set_velocity(&X);
    X.M.t = X.S.t;
    if ((r = mpd_step(&X.g, &X.pts, &X.def, X.S.dt, &X.M, NULL, 0, err)) != GK_OK) return r;
    FUZZ_CHECK(after_step(&X, ds, gk_wtime(), X.S.step, X.S.step + 1) == 0);
    return GK_OK;
}

#include "fuzz_mpd_ckpt.h"
