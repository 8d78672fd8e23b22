/* bench_twoscale - gk_twoscale.h per Newton iteration: N RVEs (default 512, the 8 x 16 Q8 mesh of the
 * Guo & Zhao (2014) model, the authors' 400-disk RVE), each run from its accepted state by its dH with the adaptive DEM step
 * rule and asked for stress and eq 9 tangent; and a scaling model from what it measures.
 *
 *   build/bench_twoscale [--points 512] [--steps 3] [--iterations 3] [--threads T] [--band 0.1]
 *                        [--model [--costs FILE]] [--alpha 2e-6] [--bandwidth 1e10] [--rate3d 1.05e7] [--tol 0.05]
 *   mpirun -np R build/mpi/bench_twoscale_mpi ...      (make mpi: the same on R ranks)
 *
 * The dH of point p at a step is an increment of the biaxial test (0.1 % axial compression, 0.05 %
 * lateral expansion, a little shear and spin) varied by +-20 % over the points, and 3x larger in a
 * "band" of --band of the points (a shear band: more DEM steps where the adaptive rule relaxes):
 * --steps load steps of --iterations Newton iterations each (each iteration's dH 0.3 % apart), the
 * last iteration accepted. Prints the wall time per iteration (median over the iterations after the
 * first step), the DEM steps per RVE run (min, median, mean, p90, max over points and iterations),
 * the bytes a rank sends and receives per iteration (gk_twoscale_stats), and
 *   BENCH case=twoscale ranks=R threads=T points=N ms_per_iteration=... rve_runs_per_s=...
 *         particle_steps_per_s=... bytes_in_per_iteration=... bytes_out_per_iteration=...
 * With --model (one rank): the scaling model of bench/README.md from the measured cost distribution
 * and rate: the FEM part of an iteration measured here (assembly, factorisation, solve of a Q4 mesh of
 * the same number of Gauss points, 2D; hex8 with 8 points per element, 3D), the balance of
 * gk_twoscale (first assignment by particle count, then moves from the most to the least loaded rank
 * until within --tol of the mean) simulated on costs drawn from the measured distribution, the
 * messages (rank 0's dH broadcast, the results allgathered) at latency --alpha [s] and --bandwidth
 * [bytes/s], for 64, 1000 and 10 000 ranks: the paper-size 2D case (7776 RVEs of 400 disks) and a 3D
 * case (1000 RVEs of 4096 spheres at --rate3d particle-steps/s per core, bench_dem_step's 3d_10k).
 * --costs FILE takes the cost pairs from a file instead: "w0 w1" per line, a Gauss point's DEM steps at
 * one load step and at the next (bench/README.md: from femdem_biaxial's gp_NNNN.vtk). */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_fem.h"
#include "gk_io.h"
#include "gk_twoscale.h"
#include "../examples/cli.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int cmp_d(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double now(void) {
#ifdef GK_TWOSCALE_MPI
    return MPI_Wtime();
#else
    return gk_wtime();
#endif
}

/* the dH of every point at step s, iteration it */
static void field(int n, int s, int it, double band, double *dH) {
    int p;
    for (p = 0; p < n; ++p) {
        double f = (1.0 + 0.2 * sin(0.7 * p + s)) * (1.0 + 0.003 * it) * ((p * 7919 % 1000) < band * 1000 ? 3.0 : 1.0);
        double *H = dH + 9 * (size_t)p;
        memset(H, 0, 9 * sizeof(double));
        H[0] = 5e-4 * f, H[4] = -1e-3 * f, H[1] = 2e-4 * f * sin(0.3 * p), H[3] = -1e-4 * f * cos(0.3 * p);
    }
}

/* ------------------------------------------------------------ the model */
/* seconds of the FEM part of one Newton iteration for about ngp Gauss points: K from the tangents,
 * factorisation and solve, the internal force (what every rank does, replicated, in femdem_biaxial) */
static double fem_seconds(int dim, int ngp) {
    gk_mesh m;
    gk_quad q;
    gk_csr K;
    gk_solver s;
    gk_err err;
    int n[3], k, reps = 3, nd, ne, *fix, nfix = 0;
    double org[3] = {0, 0, 0}, len[3] = {1, 1, 1}, *D, *sig, *f, *x, *v, t, best = 1e30;
    if (dim == 2) {
        n[0] = n[1] = (int)ceil(sqrt(ngp / 4.0)), n[2] = 1;
        if (gk_mesh_structured(&m, GK_Q4, n, org, len, NULL, &err) || gk_quad_rule(&q, GK_Q4, 2, &err)) return -1;
    } else {
        n[0] = n[1] = n[2] = (int)ceil(cbrt(ngp / 8.0));
        if (gk_mesh_structured(&m, GK_HEX8, n, org, len, NULL, &err) || gk_quad_rule(&q, GK_HEX8, 2, &err)) return -1;
    }
    ne = m.nelem * q.n, nd = dim * m.nnode;
    D = (double *)calloc((size_t)ne * dim * dim * dim * dim, sizeof(double));
    sig = (double *)calloc((size_t)ne * 9, sizeof(double));
    f = (double *)calloc((size_t)nd, sizeof(double)), x = (double *)calloc((size_t)nd, sizeof(double));
    if (!D || !sig || !f || !x || gk_csr_from_mesh(&K, &m, NULL, &err)) return -1;
    for (k = 0; k < ne; ++k) gk_fem_elastic_tangent(dim, 1e8, 0.2, D + (size_t)k * dim * dim * dim * dim);
    {   /* the bottom face clamped */
        int *nodes = (int *)malloc((size_t)m.nnode * sizeof(int)), nb, a, c;
        fix = (int *)malloc((size_t)nd * sizeof(int)), v = (double *)calloc((size_t)nd, sizeof(double));
        if (!nodes || !fix || !v) return -1;
        nb = gk_mesh_nodes_on_plane(&m, 1, 0.0, 1e-9, nodes);
        for (a = 0; a < nb; ++a)
            for (c = 0; c < dim; ++c) fix[nfix++] = dim * nodes[a] + c;
        free(nodes);
    }
    for (k = 0; k < reps; ++k) {
        gk_solver_init(&s);
        t = gk_wtime();
        gk_fem_assemble(&m, &q, D, NULL, &K, NULL, &err);
        gk_fem_assemble(&m, &q, NULL, sig, NULL, f, &err);
        f[nd - 1] = 1.0;
        gk_fem_dirichlet(&K, f, nfix, fix, v, &err);
        if (gk_solver_factor(&s, &K, NULL, &err) || gk_solver_solve(&s, f, x)) {
            fprintf(stderr, "bench_twoscale: the FEM solve of the model failed: %s\n", err.msg);
            best = -1;
        }
        gk_solver_free(&s);
        t = gk_wtime() - t;
        if (best > 0 && t < best) best = t;
    }
    free(D), free(sig), free(f), free(x), free(fix), free(v);
    gk_csr_free(&K);
    gk_mesh_free(&m);
    return best;
}

/* gk_twoscale's balance on cost c[0..n) over R ranks: first contiguous ranges of equal particle
 * counts (all equal here), then moves from the most to the least loaded rank, each the point whose
 * cost is nearest half their gap, until within tol of the mean (or no move helps); the most loaded
 * rank's load over the mean, with the costs `next` of the following iteration (the balance only
 * knows the last ones) */
static double imbalance(const double *c, const double *next, int n, int R, double tol) {
    int *own = (int *)malloc((size_t)n * sizeof(int)), p, r, it;
    double *L = (double *)calloc((size_t)R, sizeof(double)), mean = 0.0, mx = 0.0, out;
    for (p = 0; p < n; ++p) own[p] = (int)((p + 0.5) * R / n), L[own[p]] += c[p], mean += c[p];
    mean /= R;
    for (it = 0; it < n; ++it) {
        int rmax = 0, rmin = 0, best = -1;
        double gap, bestv = -1;
        for (r = 1; r < R; ++r) {
            if (L[r] > L[rmax]) rmax = r;
            if (L[r] < L[rmin]) rmin = r;
        }
        if (L[rmax] <= (1 + tol) * mean) break;
        gap = L[rmax] - L[rmin];
        for (p = 0; p < n; ++p)
            if (own[p] == rmax && c[p] < gap) {
                double v = c[p] < gap - c[p] ? c[p] : gap - c[p];
                if (v > bestv) bestv = v, best = p;
            }
        if (best < 0) break;
        own[best] = rmin, L[rmax] -= c[best], L[rmin] += c[best];
    }
    for (r = 0; r < R; ++r) L[r] = 0;
    mean = 0;
    for (p = 0; p < n; ++p) L[own[p]] += next[p], mean += next[p];
    mean /= R;
    for (r = 0; r < R; ++r)
        if (L[r] > mx) mx = L[r];
    out = mx / mean;
    free(own), free(L);
    return out;
}

/* the table: costs drawn (deterministically) from the measured pairs of consecutive per-point work
 * (w0: a step's, w1: the next step's, nw pairs). Per case and rank count: the RVE time per iteration of
 * the most loaded rank, the FEM time (replicated on every rank), the message time, the imbalance
 * (most loaded rank / mean) when the balance knows the costs (same) and when it knows only the last
 * step's (next), the efficiency of the micro side alone (E_micro: RVEs and messages) and of the
 * whole iteration (E: with the replicated FEM); then the fewest RVEs per rank for E_micro >= 90 %. */
static double micro_eff(const double *c, const double *c1, int n, int R, double tot, double tol, double alpha,
                        double bytes, double bw, double *imb_out) {
    double imb = imbalance(c, c1, n, R, tol), lg = ceil(log2((double)R > 1 ? R : 2));
    /* a broadcast (dH) and an allgather (results) by recursive doubling: log2 R latencies each; every
     * rank receives every point's dH and results once */
    double tmsg = 2.0 * lg * alpha + bytes / bw;
    if (imb_out) *imb_out = imb;
    return tot / (R * (imb * tot / R + tmsg));
}

static void model(const double *w0, const double *w1, int nw, double rate2d, double rate3d, double alpha,
                  double bw, double tol) {
    static const int ranks[3] = {64, 1000, 10000}, per[10] = {1, 2, 4, 6, 8, 12, 16, 24, 32, 64};
    struct {
        const char *name;
        int dim, n, particles;
        double rate;
    } cs[2];
    int k, j, p;
    cs[0].name = "2D 7776 x 400 disks", cs[0].dim = 2, cs[0].n = 7776, cs[0].particles = 400, cs[0].rate = rate2d;
    cs[1].name = "3D 1000 x 4096 spheres", cs[1].dim = 3, cs[1].n = 1000, cs[1].particles = 4096, cs[1].rate = rate3d;
    printf("\nscaling model (rates %.3g and %.3g particle-steps/s per core, alpha %.1e s, bandwidth %.2g B/s, balance "
           "tolerance %.2f):\n",
           rate2d, rate3d, alpha, bw, tol);
    printf("%-23s %6s %7s %9s %9s %8s %6s %6s %9s %8s %6s\n", "case", "ranks", "rve/rk", "T_rve ms", "T_fem ms",
           "T_msg ms", "imb=", "imb+1", "bytes/it", "E_micro", "E");
    for (k = 0; k < 2; ++k) {
        int n = cs[k].n, nd4 = cs[k].dim * cs[k].dim * cs[k].dim * cs[k].dim;
        double *c = (double *)malloc((size_t)n * sizeof(double)), *c1 = (double *)malloc((size_t)n * sizeof(double));
        double tot = 0.0, tfem = fem_seconds(cs[k].dim, n), bytes = 8.0 * n * (9 + 9 + nd4 + 7);
        gk_rng rng;
        gk_rng_seed(&rng, 7);
        for (p = 0; p < n; ++p) {
            int i = (int)(gk_rng_u64(&rng) % (uint64_t)nw);
            c[p] = (w0[i] + 1.0) * cs[k].particles / cs[k].rate;
            c1[p] = (w1[i] + 1.0) * cs[k].particles / cs[k].rate;
            tot += c1[p];
        }
        for (j = 0; j < 3; ++j) {
            int R = ranks[j];
            double same, imb, Em = micro_eff(c, c1, n, R, tot, tol, alpha, bytes, bw, &imb), lg = ceil(log2((double)R));
            double tmsg = 2.0 * lg * alpha + bytes / bw, trve = imb * tot / R;
            same = imbalance(c, c, n, R, tol);
            printf("%-23s %6d %7.2f %9.2f %9.2f %8.3f %6.3f %6.3f %9.0f %7.1f%% %5.1f%%\n", cs[k].name, R, (double)n / R,
                   1e3 * trve, 1e3 * tfem, 1e3 * tmsg, same, imb, bytes, 100 * Em,
                   100 * (tot + tfem) / (R * (trve + tfem + tmsg)));
        }
        for (j = 0; j < 10; ++j) {
            int R = n / per[j] > 1 ? n / per[j] : 2;
            if (micro_eff(c, c1, n, R, tot, tol, alpha, bytes, bw, NULL) >= 0.9) {
                printf("%-23s E_micro >= 90 %% from %d RVEs per rank (%d ranks); the FEM replicated on every rank "
                       "keeps E >= 90 %% while T_fem <= %.1f ms, i.e. up to %d ranks\n",
                       cs[k].name, per[j], R, 1e3 * 0.1 * tot / R,
                       (int)(0.1 * tot / (tfem > 0 ? tfem : 1e-30)) < n ? (int)(0.1 * tot / (tfem > 0 ? tfem : 1e-30)) : n);
                break;
            }
        }
        free(c), free(c1);
    }
}

int main(int argc, char **argv) {
    int n = 512, steps = 3, iters = 3, threads = 1, do_model = 0, s, it, p, rank = 0, nranks = 1, help = 0, nt = 0;
    double band = 0.1, alpha = 2e-6, bw = 1e10, rate3d = 1.05e7, tol = 0.05;
    const char *costs = NULL;
    const cli_opt opts[] = {{"--points", CLI_INT, &n, 1, 1000000, NULL, NULL, 0},
                            {"--steps", CLI_INT, &steps, 2, 1000, NULL, NULL, 0},
                            {"--iterations", CLI_INT, &iters, 1, 1000, NULL, NULL, 0},
                            {"--threads", CLI_INT, &threads, 1, 1024, NULL, NULL, 0},
                            {"--band", CLI_REAL, &band, 0, 1, NULL, NULL, 0},
                            {"--model", CLI_FLAG, &do_model, 0, 0, NULL, NULL, 0},
                            {"--alpha", CLI_REAL, &alpha, 0, 1, NULL, NULL, 0},
                            {"--bandwidth", CLI_REAL, &bw, 0, HUGE_VAL, NULL, NULL, CLI_LO_OPEN | CLI_HI_OPEN},
                            {"--rate3d", CLI_REAL, &rate3d, 0, HUGE_VAL, NULL, NULL, CLI_LO_OPEN | CLI_HI_OPEN},
                            {"--tol", CLI_REAL, &tol, 0, 1, NULL, NULL, CLI_LO_OPEN},
                            {"--costs", CLI_STR, &costs, 0, 0, NULL, NULL, 0},
                            {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    const cli_opt *tables[2];
    gk_packing pk;
    gk_err err;
    gk_twoscale ts;
    gk_twoscale_proto pr;
    gk_twoscale_def d;
    double *dH, *sig, *D, *times, *work, work_ps = 0.0, t0;
    long long b_in = 0, b_out = 0;
    gk_twoscale_stats st0 = {0, 0, 0, 0, 0, 0, 0};
#ifdef GK_TWOSCALE_MPI
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &nranks);
#endif
    tables[0] = opts, tables[1] = NULL;
    if (cli_parse(rank == 0 ? "bench_twoscale" : NULL, argc, argv, tables, &help) || help) {
        if (help && rank == 0) printf("usage: see the top of bench/twoscale.c\n");
#ifdef GK_TWOSCALE_MPI
        MPI_Finalize();
#endif
        return help ? 0 : 2;
    }
    if (gk_packing_read("examples/data/rve400.txt", &pk, NULL, &err)) {
        fprintf(stderr, "bench_twoscale: %s\n", err.msg);
        return 1;
    }
    memset(&d, 0, sizeof d);
    pr.packing = &pk, pr.state = NULL;
    d.npoints = n, d.protos = &pr, d.nprotos = 1, d.threads = threads;
    d.rve = gk_rve_def_default();
    d.rve.dt = 3.1602315723728926e-05;
    d.rule.n_min = 2, d.rule.n_max = 400, d.rule.unbalanced_max = 2e-2; /* femdem_biaxial's defaults */
    dH = (double *)malloc((size_t)n * 9 * sizeof(double)), sig = (double *)malloc((size_t)n * 9 * sizeof(double));
    D = (double *)malloc((size_t)n * 16 * sizeof(double));
    times = (double *)malloc((size_t)steps * iters * sizeof(double));
    work = (double *)malloc((size_t)steps * iters * n * sizeof(double));
    if (!dH || !sig || !D || !times || !work || gk_twoscale_create(&ts, &d)) {
        fprintf(stderr, "bench_twoscale: %s\n", gk_twoscale_error(&ts));
        return 1;
    }
    if (rank == 0)
        printf("bench_twoscale: %d RVEs of %d disks, %d rank(s) x %d thread(s), %d steps x %d iterations\n", n, pk.n,
               nranks, threads, steps, iters);
    for (s = 0; s < steps; ++s)
        for (it = 0; it < iters; ++it) {
            const gk_twoscale_point *pts;
            double dt;
            field(n, s, it, band, dH);
            if (s == 1 && it == 0) st0 = ts.stats; /* traffic from the second step on (after a first balance) */
#ifdef GK_TWOSCALE_MPI
            MPI_Barrier(MPI_COMM_WORLD);
#endif
            t0 = now();
            if (gk_twoscale_run(&ts, dH, NULL, sig, D)) {
                fprintf(stderr, "bench_twoscale: %s\n", gk_twoscale_error(&ts));
                return 1;
            }
            dt = now() - t0;
#ifdef GK_TWOSCALE_MPI
            MPI_Allreduce(MPI_IN_PLACE, &dt, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
#endif
            pts = gk_twoscale_points(&ts);
            for (p = 0; p < n; ++p) {
                work[((size_t)s * iters + it) * n + p] = pts[p].work;
                if (s > 0) work_ps += (double)pts[p].work * pts[p].particles;
            }
            if (s > 0) times[nt++] = dt;
            if (it == iters - 1 && gk_twoscale_accept(&ts)) {
                fprintf(stderr, "bench_twoscale: %s\n", gk_twoscale_error(&ts));
                return 1;
            }
        }
    b_in = ts.stats.run_bytes_in - st0.run_bytes_in, b_out = ts.stats.run_bytes_out - st0.run_bytes_out;
    if (rank == 0) {
        int m = (steps - 1) * iters * n, k, npair = 0;
        double med, tsum = 0, q[5], *wa = (double *)malloc((size_t)m * sizeof(double));
        if (!wa) return 1;
        memcpy(wa, work + (size_t)iters * n, (size_t)m * sizeof(double));
        for (k = 0; k < nt; ++k) tsum += times[k];
        qsort(times, (size_t)nt, sizeof *times, cmp_d);
        med = times[nt / 2];
        qsort(wa, (size_t)m, sizeof *wa, cmp_d);
        q[0] = wa[0], q[1] = wa[m / 2], q[3] = wa[(int)(0.9 * m)], q[4] = wa[m - 1], q[2] = 0;
        for (k = 0; k < m; ++k) q[2] += wa[k] / m;
        free(wa);
        printf("wall per iteration: median %.1f ms (min %.1f, max %.1f) over %d iterations\n", 1e3 * med, 1e3 * times[0],
               1e3 * times[nt - 1], nt);
        printf("DEM steps per RVE run: min %.0f  median %.0f  mean %.1f  p90 %.0f  max %.0f (max/mean %.2f)\n", q[0], q[1],
               q[2], q[3], q[4], q[4] / q[2]);
        printf("per iteration, rank 0: %.0f bytes in, %.0f bytes out; %lld point moves in all\n", (double)b_in / nt,
               (double)b_out / nt, ts.stats.migrated);
        printf("BENCH case=twoscale ranks=%d threads=%d points=%d ms_per_iteration=%.2f rve_runs_per_s=%.1f "
               "particle_steps_per_s=%.4g bytes_in_per_iteration=%.0f bytes_out_per_iteration=%.0f\n",
               nranks, threads, n, 1e3 * med, n / med, work_ps / tsum, (double)b_in / nt, (double)b_out / nt);
        if (do_model && nranks == 1) {
            /* cost pairs: a point's work at the last iteration of a step (what the balance sees) and at the
             * first iteration of the next (what the ranks then run); the 2D rate per core from this run */
            double *a = (double *)malloc((size_t)(steps - 1) * n * sizeof(double)),
                   *b = (double *)malloc((size_t)(steps - 1) * n * sizeof(double));
            if (!a || !b) return 1;
            for (s = 0; s + 1 < steps; ++s)
                for (p = 0; p < n; ++p, ++npair) {
                    a[npair] = work[((size_t)s * iters + iters - 1) * n + p];
                    b[npair] = work[((size_t)(s + 1) * iters) * n + p];
                }
            if (costs) { /* measured elsewhere: pairs "w0 w1" per line (bench/README.md) */
                FILE *fp = fopen(costs, "r");
                double x, y;
                double *a2 = NULL, *b2 = NULL;
                int cap = 0;
                npair = 0;
                while (fp && fscanf(fp, "%lf %lf", &x, &y) == 2) {
                    if (npair == cap) {
                        cap = 2 * cap + 1024;
                        a2 = (double *)realloc(a2, (size_t)cap * sizeof *a2), b2 = (double *)realloc(b2, (size_t)cap * sizeof *b2);
                        if (!a2 || !b2) return 1;
                    }
                    a2[npair] = x, b2[npair++] = y;
                }
                if (fp) fclose(fp);
                if (npair == 0) return fprintf(stderr, "bench_twoscale: no cost pairs in %s\n", costs), 1;
                free(a), free(b);
                a = a2, b = b2;
                printf("cost pairs: %d from %s\n", npair, costs);
            }
            model(a, b, npair, work_ps / tsum / threads, rate3d, alpha, bw, tol);
            free(a), free(b);
        }
    }
    gk_twoscale_destroy(&ts);
    gk_packing_free(&pk);
    free(dH), free(sig), free(D), free(times), free(work);
#ifdef GK_TWOSCALE_MPI
    MPI_Finalize();
#endif
    return 0;
}
