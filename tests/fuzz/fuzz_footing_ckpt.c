/* fuzz_footing_ckpt.c - libFuzzer harness: the MPMxDEM strip-footing driver's --restart reader
 * (mpd_load of examples/mpmdem_io.h with the driver's check ft_check of examples/mpmdem_footing.c)
 * on arbitrary bytes. The driver is compiled in (its main renamed); the harness body, its promises and
 * its seeds are those of fuzz_mpd_ckpt.h. The run: a 2 x 1.5 m half model of 4 x 3 cells (48
 * points, their RVEs of 12 disks), the friction angle given (no measurement), the footing to d/B =
 * 0.01 with a row every 0.005. The next step is the driver's: the footing's speed, mpd_step, then
 * after_step (rows, the mechanism, the stage index).
 * Seeds (tests/fuzz/corpus/footing_ckpt), written by this file compiled with -DFUZZ_MAKE_SEEDS:
 *   cc -O2 -Iinclude -Itests/fuzz -DFUZZ_MAKE_SEEDS tests/fuzz/fuzz_footing_ckpt.c -lm -o build/seeds && build/seeds DIR
 * Its folders are in $TMPDIR (default /tmp), named by the process id, removed at exit. Build and run:
 * make fuzz (tests/fuzz/replay.c). */
#define _POSIX_C_SOURCE 200809L
#define main mpmdem_footing_main
#include "../../examples/mpmdem_footing.c"
#undef main
#include "fuzz_check.h"

#define FZ_NAME "footing"
#define FZ_CHECK_FN ft_check
static const char *const fz_args[] = {"mpmdem_footing",
                                      "--width",
                                      "2",
                                      "--depth",
                                      "1.5",
                                      "--nx",
                                      "4",
                                      "--ny",
                                      "3",
                                      "--B",
                                      "1.5",
                                      "--velocity",
                                      "0.25",
                                      "--ramp",
                                      "0.01",
                                      "--every",
                                      "0.005",
                                      "--smooth",
                                      "0.01",
                                      "--phi-deg",
                                      "30",
                                      "--final",
                                      "0.01",
                                      "--threads",
                                      "1",
                                      "--quiet",
                                      "--dem-dt",
                                      "0",
                                      NULL};
/* the state's stage index, settlement, next-row settlement and the footing's lower side */
static const size_t fz_seed_at[] = {offsetof(ft_state, nstage), offsetof(ft_state, disp) + 7,
                                    offsetof(ft_state, next_out) + 7,
                                    offsetof(ft_state, body) + offsetof(gk_mpm_body, lo) + 8 + 7};
static ft X;

/* the driver's main without its exit */
static int fz_run(int argc, char **argv) {
    gk_rve_state_init(&X.st0, NULL);
    mpd_begin(&X.run, "mpmdem_footing", &argc, &argv);
    return run(&X, argc, argv);
}

static void fz_free(void) {
    free(X.edge), free(X.x0);
    mpd_free_all(&X.M, &X.P, &X.pts, &X.g, &X.rows, &X.snaps);
    gk_rve_state_free(&X.st0);
}

/* the step of the driver's loop (run) */
static gk_result fz_step(gk_err *err) {
    const ft_opts *f = &X.f;
    double vf =
        f->velocity * (f->ramp > 0 && X.S.t < f->ramp ? fmin(1.0, (X.S.t + 0.5 * X.dt) / f->ramp) : 1.0);
    gk_result r;
    X.S.body.v[1] = -vf;
    if ((r = mpd_step(&X.g, &X.pts, &X.def, X.dt, &X.M, X.edge, X.nedge, err)) != GK_OK) return r;
    FUZZ_CHECK(after_step(&X, vf, gk_wtime(), X.S.step, X.S.step + 1) == 0);
    return GK_OK;
}

#include "fuzz_mpd_ckpt.h"
