/* fuzz_collapse_ckpt.c - libFuzzer harness: the MPMxDEM column-collapse driver's --restart reader
 * (mpd_load of examples/mpmdem_io.h with the driver's check cl_check of examples/mpmdem_collapse.c)
 * on arbitrary bytes. The driver is compiled in (its main renamed); the harness body, its promises and
 * its seeds are those of fuzz_mpd_ckpt.h. The run: 2 cells across (4 points, their RVEs of 12
 * disks pre-consolidated at two depths), to t = 0.05 s with a row every 0.025 s and a snapshot at 0.05 s. The next step is the
 * driver's: mpd_step, then after_step (rows, the snapshot index, the rest detection).
 * Seeds (tests/fuzz/corpus/collapse_ckpt), written by this file compiled with -DFUZZ_MAKE_SEEDS:
 *   cc -O2 -Iinclude -Itests/fuzz -DFUZZ_MAKE_SEEDS tests/fuzz/fuzz_collapse_ckpt.c -lm -o build/seeds && build/seeds DIR
 * Its folders are in $TMPDIR (default /tmp), named by the process id, removed at exit. Build and run:
 * make fuzz (tests/fuzz/replay.c). */
#define _POSIX_C_SOURCE 200809L
#define main mpmdem_collapse_main
#include "../../examples/mpmdem_collapse.c"
#undef main
#include "fuzz_check.h"

#define FZ_NAME "collapse"
#define FZ_CHECK_FN cl_check
static const char *const fz_args[] = {
    "mpmdem_collapse", "--nx", "2",       "--every",  "0.025", "--snapshots", "0.05", "--t-end", "0.05",
    "--threads",       "1",    "--quiet", "--dem-dt", "0",     NULL};
/* the state's snapshot index, time step and next-row time (offsets into cl_state) */
static const size_t fz_seed_at[] = {offsetof(cl_state, nsnap), offsetof(cl_state, dt) + 7,
                                    offsetof(cl_state, next_out) + 7};
static cl X;

/* the driver's main without its exit */
static int fz_run(int argc, char **argv) {
    int k;
    for (k = 0; k < CL_MAX_LEVELS; ++k) gk_rve_state_init(&X.st[k], NULL);
    mpd_begin(&X.run, "mpmdem_collapse", &argc, &argv);
    return run(&X, argc, argv);
}

static void fz_free(void) {
    int k;
    free(X.work), free(X.pick);
    mpd_free_all(&X.M, &X.P, &X.pts, &X.g, &X.rows, &X.snaps);
    for (k = 0; k < CL_MAX_LEVELS; ++k) gk_rve_state_free(&X.st[k]);
}

static gk_result fz_step(gk_err *err) {
    gk_result r;
    X.M.t = X.S.t;
    if ((r = mpd_step(&X.g, &X.pts, &X.def, X.S.dt, &X.M, NULL, 0, err)) != GK_OK) return r;
    FUZZ_CHECK(after_step(&X, gk_wtime(), X.S.step, X.S.step + 1) == 0);
    return GK_OK;
}

#include "fuzz_mpd_ckpt.h"
