/* knockout.c - what bounds the 3D force loop: the loop of bench_dem_step's
 * 3d_10k case timed alone, built by bench/knockout.sh from copies of the
 * headers with parts of the loop removed (not grainkit: a measurement).
 *
 *   knockout --make STATE   bench_dem_step's 3d_10k case (20 000 spheres,
 *                           bench/data/bench3d_20k.txt, its material and time
 *                           step) sheared for 30 steps, saved to STATE
 *   knockout STATE [REPS]   restore STATE and time REPS passes of the pair
 *                           forces (default 50), seven times; prints the
 *                           fastest, in ns per pair
 *
 * The knockouts (GK_KO_* in bench/knockout.sh) change what the loop computes,
 * so its forces are wrong: each pass starts from the same state and nothing
 * is integrated, which keeps every variant on the same pairs. The outputs a
 * knockout no longer scatters are summed into ko_sink so that they are still
 * computed. */
#define _POSIX_C_SOURCE 200809L
#include <immintrin.h>
#include <stdint.h>
/* what bench/knockout.sh puts in place of the parts it removes */
static __m512d ko_sink; /* the sum of what is no longer scattered */
static inline __m512d gk__ko_load(const double *base, const int32_t *j, int32_t n) {
    return _mm512_loadu_pd(base + (j[0] <= n - 8 ? j[0] : n - 8));
}
#define GK_KO_SINK(o)                                                                                       \
    do {                                                                                                    \
        int q_;                                                                                             \
        for (q_ = 0; q_ < 3; ++q_)                                                                          \
            ko_sink =                                                                                       \
                _mm512_add_pd(ko_sink, _mm512_add_pd((o)->f[q_], _mm512_add_pd((o)->ti[q_], (o)->tj[q_]))); \
    } while (0)
#define GK_KO_SQRT(x) (x)
#define GK_KO_DIV(a, b) gk_vr_mul(a, b)
#define GK_IMPLEMENTATION
#include "gk_dem.h"
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv) {
    gk_packing pk;
    gk_err e;
    gk_rve rve;
    gk_rve_def d = gk_rve_def_default();
    double L[9] = {0}, E[9], best = HUGE_VAL, sink[8];
    gk__stepctx x;
    size_t need = 0;
    void *buf = NULL;
    FILE *fp = NULL;
    int r, k, rc = 1, have_rve = 0, make = argc == 3 && !strcmp(argv[1], "--make"),
              reps = !make && argc > 2 ? atoi(argv[2]) : 50;
    const char *path = make ? argv[2] : argc > 1 ? argv[1] : NULL;
    if (!path || reps < 1) {
        fprintf(stderr, "usage: knockout --make STATE | knockout STATE [REPS]\n");
        return 2;
    }
    if (gk_packing_read("bench/data/bench3d_20k.txt", &pk, NULL, &e))
        return fprintf(stderr, "knockout: %s (run from the project's top folder)\n", e.msg), 1;
    /* bench_dem_step's 3d_10k case: the peer codes' parameters (bench/data/README.md) */
    d.mat.kn = 2e5;
    d.mat.kt_ratio = 0.5;
    d.mat.friction = 0.5;
    d.damping = 0.0;
    d.dt = 2.7e-6;
    d.skin = 5e-4;
    if (gk_rve_create(&rve, &d, &pk)) {
        fprintf(stderr, "knockout: %s\n", gk_rve_error(&rve));
        goto done;
    }
    have_rve = 1;
    L[1] = 1.5;
    if (gk_rve_set_velocity_gradient(&rve, L)) {
        fprintf(stderr, "knockout: %s\n", gk_rve_error(&rve));
        goto done;
    }
    if (make) {
        int bad;
        if (gk_rve_step(&rve, 30)) {
            fprintf(stderr, "knockout: %s\n", gk_rve_error(&rve));
            goto done;
        }
        gk_rve_save(&rve, NULL, 0, &need);
        buf = malloc(need);
        if (!buf || gk_rve_save(&rve, buf, need, &need)) {
            fprintf(stderr, "knockout: cannot save\n");
            goto done;
        }
        fp = fopen(path, "wb");
        bad = !fp || fwrite(buf, 1, need, fp) != need;
        if (fp && fclose(fp)) bad = 1;
        fp = NULL;
        if (bad) {
            fprintf(stderr, "knockout: cannot write %s\n", path);
            goto done;
        }
        rc = 0;
        goto done;
    }
    fp = fopen(path, "rb");
    if (!fp || fseek(fp, 0, SEEK_END) || (need = (size_t)ftell(fp)) == 0 || fseek(fp, 0, SEEK_SET) ||
        !(buf = malloc(need)) || fread(buf, 1, need, fp) != need) {
        fprintf(stderr, "knockout: cannot read %s\n", path);
        goto done;
    }
    if (gk_rve_restore(&rve, buf, need)) {
        fprintf(stderr, "knockout: %s\n", gk_rve_error(&rve));
        goto done;
    }
    for (k = 0; k < 9; ++k) E[k] = k % 4 == 0 ? 1.0 : 0.0;
    E[1] = L[1] * rve.dt;
    gk__ctx_make(&rve, E, &x);
    for (r = 0; r < 7; ++r) {
        double t0 = now(), t;
        for (k = 0; k < reps; ++k) gk__forces(&rve, &x, 0);
        t = (now() - t0) / reps;
        if (t < best) best = t;
    }
    _mm512_storeu_pd(sink, ko_sink);
    printf("%d pairs: %.2f ns per pair (the fastest of 7 x %d passes; sink %g)\n", rve.pl.n,
           1e9 * best / rve.pl.n, reps, sink[0]);
    rc = 0;
done:
    if (fp) fclose(fp);
    free(buf);
    if (have_rve) gk_rve_destroy(&rve);
    gk_packing_free(&pk);
    return rc;
}
