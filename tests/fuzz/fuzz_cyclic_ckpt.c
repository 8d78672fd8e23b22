/* fuzz_cyclic_ckpt.c - libFuzzer harness: the cyclic FEMxDEM driver's --restart reader (restart of
 * examples/femdem_cyclic.c: fd_ck_load of examples/femdem_io.h within gk_twoscale_load_take, with the
 * driver's part cyc_part_read: the cyclic state and one row extra per row) on arbitrary bytes. The
 * driver is compiled in (its main renamed).
 *
 * One small model is built once, deterministically: the cyclic-strain test on one Q4 element (2 x 2
 * Gauss points) with RVEs of a 12-disk 2D packing consolidated to 100 kPa, increment 1e-4 and
 * amplitude 2e-4 (the next step reaches it and reverses), at most 2 Newton iterations; the driver's
 * loop (run_cyclic) runs one step and writes the pristine checkpoint.
 *
 * Input: one mode byte, then the file, as fuzz_femdem_ckpt.c. Each input:
 *   - refused: a message, and the model (fz_fd_bytes of fuzz_fd.h), the cyclic state and the rows'
 *     extras byte for byte as before, the set's accepted stresses the same;
 *   - accepted: the model's block in range (fz_fd_accepted), the cyclic state in range (direction
 *     +-1, counters, finite reals, the stress-control increment in (0, 1]) and every row's extras
 *     finite; then the driver's next step (its increment as run_cyclic makes it, fd_load_step, and
 *     after_step when it converged) ends converged with finite displacements and stresses, or not
 *     converged, or with a message. The model then returns to the pristine checkpoint.
 * Seeds (tests/fuzz/corpus/cyclic_ckpt): the pristine checkpoint, one a step later (after the
 * reversal), a truncated copy and bit-flipped ones in the cyclic part (direction, branch counter,
 * increment, a row's extra; checksum mended), written by this file compiled with -DFUZZ_MAKE_SEEDS:
 *   cc -O2 -Iinclude -Itests/fuzz -DFUZZ_MAKE_SEEDS tests/fuzz/fuzz_cyclic_ckpt.c -lm -o build/seeds && build/seeds DIR
 * Its folders are in $TMPDIR (default /tmp), named by the process id, removed at exit. Build and run:
 * make fuzz (tests/fuzz/replay.c). */
#define _POSIX_C_SOURCE 200809L
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-function" /* the driver's headers have more than this uses */
#endif
#define main femdem_cyclic_main
#include "../../examples/femdem_cyclic.c"
#undef main
#include "fuzz_check.h"
#include "fuzz_fd.h"

static cyc_model C;
static char in_dir[400], ref_dir[400], out_dir[400], pk_path[400];
static unsigned char *snap0; /* the pristine model's and cyclic state */
static size_t nsnap;
static double *acc0; /* the pristine set's accepted stresses */
static int ready;

static void cleanup(void) {
    fuzz_remove_dir(in_dir), fuzz_remove_dir(ref_dir), fuzz_remove_dir(out_dir), remove(pk_path);
    if (ready) free(C.cx), fd_free(&C.m), free(snap0), free(acc0);
}

/* the model's block, the cyclic state and the rows' extras, as bytes (malloc'ed) */
static unsigned char *state_bytes(size_t *n) {
    size_t nb, parts[3];
    unsigned char *b = fz_fd_bytes(&C.m, &nb), *all;
    const void *src[3];
    src[0] = b, parts[0] = nb;
    src[1] = &C.cs, parts[1] = sizeof C.cs;
    src[2] = C.cx, parts[2] = (size_t)C.m.ncurve * sizeof(cyc_extra);
    all = fuzz_concat(src, parts, 3, n);
    free(b);
    return all;
}

static int same_as_pristine(void) {
    size_t n;
    unsigned char *b = state_bytes(&n);
    int same = n == nsnap && memcmp(b, snap0, n) == 0 && fuzz_same_set(&C.m.ts, acc0);
    free(b);
    return same;
}

/* back to the pristine checkpoint */
static void restore(void) {
    gk_err err;
    C.m.o.restart = ref_dir;
    FUZZ_CHECK(restart(&C, &err) == 0);
    C.m.pend_dem = C.m.pend_reused = C.m.pend_computed = 0;
}

static void setup(void) {
    gk_rve_def def = gk_rve_def_default();
    gk_err err;
    int help = 0;
    if (ready) return;
    fuzz_temp_dir(in_dir, sizeof in_dir, "cyclic", "in");
    fuzz_temp_dir(ref_dir, sizeof ref_dir, "cyclic", "ref");
    fuzz_temp_dir(out_dir, sizeof out_dir, "cyclic", "out");
    fuzz_temp_path(pk_path, sizeof pk_path, "cyclic", "pk");
    atexit(cleanup);
    fuzz_small_packing(pk_path, "fuzz_cyclic_ckpt", 1e5, &def); /* 12 disks consolidated to 100 kPa */
    {
        char *argv[] = {"fuzz_cyclic_ckpt",
                        "--nx",
                        "1",
                        "--ny",
                        "1",
                        "--packing",
                        pk_path,
                        "--increment",
                        "1e-4",
                        "--amplitude",
                        "2e-4",
                        "--cycles",
                        "0.1",
                        "--max-iter",
                        "2",
                        "--checkpoint",
                        "1",
                        "--threads",
                        "1",
                        "--out",
                        ref_dir,
                        NULL};
        memset(&C, 0, sizeof C);
        C.m.prog = "fuzz_cyclic_ckpt", C.m.root = 1, C.m.checkpoint = checkpoint;
        FUZZ_CHECK(parse(&C, (int)(sizeof argv / sizeof argv[0]) - 1, argv, &help) == 0 && !help);
        C.m.o.dt = def.dt; /* the packing's DEM time step, as fuzz_femdem_ckpt.c */
    }
    FUZZ_CHECK(fd_setup(&C.m, &err) == 0 && cx_room(&C) == 0 && first_row(&C, &err) == 0);
    C.m.root = 0; /* quiet from here on (fd_say; no writes depend on it without MPI) */
    FUZZ_CHECK(run_cyclic(&C, gk_wtime(), &err) == 0 && C.m.ncurve == 2 && C.m.step == 1);
    C.m.o.out = out_dir;
    restore();
    snap0 = state_bytes(&nsnap);
    acc0 = fuzz_set_stresses(&C.m.ts);
    ready = 1;
}

/* the driver's next step, once: its increment as run_cyclic makes it, the load step, and after_step
 * when it converged */
static void next_step(void) {
    fd_model *M = &C.m;
    cyc_state *c = &C.cs;
    double target = c->dir * C.amp, inc = c->dir * M->o.inc * M->scale, Ed = 0, Ef = 0;
    int r, iters = 0;
    gk_err err;
    if (c->dir * (c->gamma + inc - target) > -1e-9 * C.amp) inc = target - c->gamma;
    err.msg[0] = '\0';
    r = fd_load_step(M, inc, &iters, &Ed, &Ef, &err);
    FUZZ_CHECK(r == 0 || r == 1 || (r == 2 && err.msg[0] != '\0'));
    if (r == 1) gk_twoscale_reject(&M->ts); /* fd_load_step rejected on 2 */
    if (r != 0) return;
    fuzz_all_finite(M->u, (size_t)M->ndof), fuzz_all_finite(M->sig, 9 * (size_t)M->ngp);
    FUZZ_CHECK(isfinite(Ed) && isfinite(Ef));
    err.msg[0] = '\0';
    r = after_step(&C, inc, iters, Ed, Ef, gk_wtime(), gk_wtime(), &err);
    FUZZ_CHECK(r == 0 || r == 1 || r == 4);
    if (r == 0 || r == 4) {
        const cyc_extra *x = &C.cx[M->ncurve - 1];
        double d[5];
        d[0] = x->cycle, d[1] = x->tau, d[2] = x->p, d[3] = x->q, d[4] = x->top_uy;
        fuzz_all_finite(d, 5);
        FUZZ_CHECK(c->dir == 1 || c->dir == -1);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    gk_err err;
    const cyc_state *c = &C.cs;
    double d[10];
    int k;
    if (size < 1) return 0;
    setup();
    fuzz_write_checkpoint_in(in_dir, data, size);
    err.msg[0] = '\0';
    C.m.o.restart = in_dir;
    if (restart(&C, &err)) {
        FUZZ_CHECK(err.msg[0] != '\0');
        FUZZ_CHECK(same_as_pristine());
        restore();
        return 0;
    }
    /* accepted: every value in range and finite */
    fz_fd_accepted(&C.m);
    d[0] = c->gamma, d[1] = c->g_start, d[2] = c->t_start, d[3] = c->tau, d[4] = c->h, d[5] = c->p0;
    d[6] = c->cyc_liq, d[7] = c->cyc_gamma, d[8] = c->G0, d[9] = c->Gu;
    fuzz_all_finite(d, 10);
    FUZZ_CHECK((c->dir == 1 || c->dir == -1) && c->branch >= 0 && c->branch <= 100000000);
    FUZZ_CHECK(c->bsteps >= 0 && c->good >= 0 && c->h > 0.0 && c->h <= 1.0 && c->G0 >= 0 && c->Gu >= 0);
    FUZZ_CHECK(C.cxcap >= C.m.ncurve);
    for (k = 0; k < C.m.ncurve; ++k) {
        double e[5];
        e[0] = C.cx[k].cycle, e[1] = C.cx[k].tau, e[2] = C.cx[k].p, e[3] = C.cx[k].q, e[4] = C.cx[k].top_uy;
        fuzz_all_finite(e, 5);
    }
    next_step();
    restore();
    FUZZ_CHECK(same_as_pristine());
    return 0;
}

#ifdef FUZZ_MAKE_SEEDS
/* the pristine checkpoint, a truncated copy, bit flips in the cyclic part (the direction, the branch
 * counter, the stress-control increment, a row's extra) and one a step later */
int main(int argc, char **argv) {
    unsigned char *b, *c;
    size_t n, k, cs0, cx0;
    gk_err err;
    if (argc < 2) return 2;
    setup();
    b = fuzz_slurp_checkpoint(ref_dir, &n);
    fuzz_write_seed(argv[1], "ckpt_step1", 0, b, n);
    fuzz_write_seed(argv[1], "ckpt_truncated", 0, b, n - 60);
    /* the driver's block ends 8 bytes (the checksum) before the file's end, with the cyclic state
     * and one extra per row */
    cx0 = n - 8 - (size_t)C.m.ncurve * sizeof(cyc_extra);
    cs0 = cx0 - sizeof(cyc_state);
    c = (unsigned char *)malloc(n);
    FUZZ_CHECK(c != NULL);
    for (k = 0; k < 4; ++k) {
        static const char *names[4] = {"ckpt_flip_dir", "ckpt_flip_branch", "ckpt_flip_h", "ckpt_flip_extra"};
        size_t at[4];
        at[0] = cs0 + offsetof(cyc_state, dir) + 3;
        at[1] = cs0 + offsetof(cyc_state, branch) + 3;
        at[2] = cs0 + offsetof(cyc_state, h) + 7;
        at[3] = cx0 + sizeof(cyc_extra) + offsetof(cyc_extra, tau) + 7;
        memcpy(c, b, n);
        c[at[k]] ^= 0x40;
        fuzz_write_seed(argv[1], names[k], 0, c, n);
    }
    free(c), free(b);
    /* a step later: the reversal */
    C.m.o.out = ref_dir, C.cycles = 0.25;
    FUZZ_CHECK(run_cyclic(&C, gk_wtime(), &err) == 0 && C.m.ncurve == 3 && C.cs.branch == 1);
    b = fuzz_slurp_checkpoint(ref_dir, &n);
    fuzz_write_seed(argv[1], "ckpt_step2", 0, b, n);
    free(b);
    return 0; /* the model is freed at exit */
}
#endif
