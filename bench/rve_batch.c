/* bench_rve_batch - the Guo & Zhao 2014 workload per Newton iteration: 512 copies of
 * the 400-disk RVE, each restored to its last converged state, deformed by
 * one increment dH = 1e-3 over 100 DEM steps, then asked for its Love stress
 * and Taylor tangent. RVEs run in parallel (OpenMP, one RVE per task).
 *
 *   build/bench_rve_batch [--rves 512] [--steps 100] [--repeats 5] [--threads T]
 *
 * Prints, per thread count (1 and 2 unless --threads), the median wall time
 * per batch and one line
 *   BENCH case=rve_batch threads=T rves=N steps=S ms_per_rve_increment=...
 *         rve_increments_per_s=... efficiency=... */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_homog.h"
#include "gk_io.h"
#include "../examples/cli.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

int main(int argc, char **argv) {
    int nrve = 512, steps = 100, reps = 5, only_threads = 0, help = 0, i, t;
    gk_packing pk;
    gk_err e;
    gk_rve *rves;
    gk_rve_state *saved;
    gk_rve_def def = gk_rve_def_default();
    double dH[9] = {5e-4, 0, 0, 0, -1e-3, 0, 0, 0, 0}, ms1 = 0.0;
    const cli_opt opts[] = {{"--rves", CLI_INT, &nrve, 1, 1000000, NULL, NULL, 0},
                            {"--steps", CLI_INT, &steps, 1, 100000000, NULL, NULL, 0},
                            {"--repeats", CLI_INT, &reps, 1, 99, NULL, NULL, 0},
                            {"--threads", CLI_INT, &only_threads, 1, 2, NULL, NULL, 0},
                            {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    const cli_opt *tables[2];
    tables[0] = opts, tables[1] = NULL;
    if (cli_parse("bench_rve_batch", argc, argv, tables, &help)) return 2;
    if (help) {
        printf("usage: bench_rve_batch [--rves N] [--steps S] [--repeats R (1..99)] [--threads 1|2]\n");
        return 0;
    }
    if (gk_packing_read("examples/data/rve400.txt", &pk, NULL, &e)) {
        fprintf(stderr, "bench_rve_batch: %s\n", e.msg);
        return 1;
    }
    rves = (gk_rve *)malloc((size_t)nrve * sizeof *rves);
    saved = (gk_rve_state *)malloc((size_t)nrve * sizeof *saved);
    if (!rves || !saved) return 1;
    /* the Guo & Zhao 2014 RVE and material; dt = YADE's 3.16e-5 s */
    def.dt = 3.1602315723728926e-05;
    for (i = 0; i < nrve; ++i) {
        if (gk_rve_create(&rves[i], &def, &pk)) {
            fprintf(stderr, "bench_rve_batch: %s\n", gk_rve_error(&rves[i]));
            return 1;
        }
        gk_rve_state_init(&saved[i], NULL);
        gk_rve_state_save(&saved[i], &rves[i]);
    }
    printf("rve_batch: %d RVEs x 400 disks, dH = (%g, %g; %g, %g) over %d steps, restore + deform + stress + "
           "tangent\n",
           nrve, dH[0], dH[1], dH[3], dH[4], steps);
    printf("%8s %14s %16s %12s\n", "threads", "ms/batch", "ms/RVE incr.", "efficiency");
    for (t = 1; t <= 2; ++t) {
        double secs[100], med;
        int r, fail = 0;
        if (only_threads && t != only_threads) continue;
        for (r = 0; r < reps; ++r) {
            double t0 = gk_wtime();
            GK_OMP(parallel for num_threads(t) schedule(dynamic, 4) reduction(| : fail))
            for (i = 0; i < nrve; ++i) {
                double D[16], s[9];
                if (gk_rve_state_restore(&saved[i], &rves[i]) || gk_rve_deform(&rves[i], dH, steps) ||
                    gk_homog_tangent(&rves[i], 0, D))
                    fail = 1;
                gk_rve_stress(&rves[i], s);
            }
            secs[r] = gk_wtime() - t0;
        }
        if (fail) {
            fprintf(stderr, "bench_rve_batch: an RVE failed\n");
            return 1;
        }
        qsort(secs, (size_t)reps, sizeof secs[0], cmp_double);
        med = reps % 2 ? secs[reps / 2] : 0.5 * (secs[reps / 2 - 1] + secs[reps / 2]);
        if (t == 1) ms1 = 1e3 * med / nrve;
        printf("%8d %14.2f %16.4f %12s\n", t, 1e3 * med, 1e3 * med / nrve, t == 1 ? "-" : "");
        if (t > 1 && ms1 > 0)
            printf("%8s %14s %16s %11.1f%%\n", "", "", "", 100.0 * ms1 / (t * 1e3 * med / nrve));
        printf("BENCH case=rve_batch threads=%d rves=%d steps=%d ms_per_rve_increment=%.4f "
               "rve_increments_per_s=%.1f "
               "efficiency=%.3f\n",
               t, nrve, steps, 1e3 * med / nrve, nrve / med,
               t == 1 || ms1 <= 0 ? 1.0 : ms1 / (t * 1e3 * med / nrve));
        fflush(stdout);
    }
    for (i = 0; i < nrve; ++i) {
        gk_rve_destroy(&rves[i]);
        gk_rve_state_free(&saved[i]);
    }
    free(rves);
    free(saved);
    gk_packing_free(&pk);
    return 0;
}
