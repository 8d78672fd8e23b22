/* bench_twoscale - gk_twoscale.h per Newton iteration: N RVEs (default 512, the 8 x 16 Q8 mesh of the
 * Guo & Zhao (2014) model, the authors' 400-disk RVE), each run from its accepted state by its dH with the adaptive DEM step
 * rule and asked for stress and eq 9 tangent; and a scaling model from what it measures.
 *
 *   build/bench_twoscale [--points 512] [--steps 3] [--iterations 3] [--threads T] [--band 0.1]
 *                        [--balance accept|run]
 *                        [--model [--cost-log FILE | --costs FILE]] [--alpha 2e-6] [--bandwidth 1e10]
 *                        [--rate2d R] [--rate3d 1.05e7] [--tol 0.05] [--steal-answer run|now]
 *                        [--steal-order own|global]
 *   mpirun -np R build/mpi/bench_twoscale_mpi ...      (make mpi: the same on R ranks)
 *
 * The dH of point p at a step is an increment of the biaxial test (0.1 % axial compression, 0.05 %
 * lateral expansion, a little shear and spin) varied by +-20 % over the points, and 3x larger in a
 * "band" of --band of the points (a shear band: more DEM steps where the adaptive rule relaxes):
 * --steps load steps of --iterations Newton iterations each (each iteration's dH 0.3 % apart), the
 * last iteration accepted. --balance: gk_twoscale_def.balance (at every accept, or before every
 * run). Prints the wall time per iteration (median over the iterations after the first step), the
 * DEM steps per RVE run (min, median, mean, p90, max over points and iterations), the bytes a rank
 * sends and receives per iteration and the points moved (gk_twoscale_stats), and
 *   BENCH case=twoscale ranks=R threads=T points=N ms_per_iteration=... rve_runs_per_s=...
 *         particle_steps_per_s=... bytes_in_per_iteration=... bytes_out_per_iteration=...
 * With --model (one rank): the scaling model of bench/README.md from the measured cost distribution
 * and rate (--rate2d: this 2D rate instead of the measured one, for a reproducible table): the FEM
 * part of an iteration measured here (assembly, factorisation, solve of a Q4 mesh of the same number
 * of Gauss points, 2D; hex8 with 8 points per element, 3D), the balance of gk_twoscale (first
 * assignment by particle count, then moves from the most to the least loaded rank until within --tol
 * of the mean) simulated on costs drawn from measured pairs under both rules (ACCEPT: every iteration
 * of a load step on the assignment made from the last step's costs; RUN: the first iteration so,
 * the others on the previous iteration's), and a third rule simulated on top of RUN's assignments, STEAL
 * (work stealing during a run, below), the migrations (a point record per move), the messages
 * (rank 0's dH broadcast, the results allgathered) at latency --alpha [s] and --bandwidth [bytes/s],
 * for 64, 1000 and 10 000 ranks: the paper-size 2D case (7776 RVEs of 400 disks) and a 3D case (1000
 * RVEs of 4096 spheres at --rate3d particle-steps/s per core, bench_dem_step's 3d_10k).
 * The pairs come from this run's synthetic load path, or from a real run:
 *   --cost-log FILE  femdem_biaxial --cost-log FILE: every run's DEM steps per Gauss point; pairs
 *                    across steps (the accepted run of a step and every run of the next, or its
 *                    first run), within a step (one Newton iteration, the next) and the runs per
 *                    step;
 *   --costs FILE     "w0 w1" per line across steps only (tools/gp_costs.sh, from gp_NNNN.vtk): rules
 *                    RUN and STEAL not evaluated.
 * STEAL (a model only; gk_twoscale.h does not implement it): each rank starts from RUN's assignment and
 * runs its points in decreasing predicted cost, at their realised costs (the second cost of each pair);
 * a rank that runs out sends a request (--alpha) to the rank with the most predicted work not yet
 * started, which answers between its RVE runs (--steal-answer run, default: the thief waits for the
 * run in progress to end) or on arrival (now: as if it polled during its runs) with its last unstarted
 * point, whose record (one migration: --alpha + record / --bandwidth) and result stay with the thief,
 * or with "none", after which the thief asks again. --steal-order global (with --steal-answer now): a
 * free rank takes the largest predicted unstarted point of any rank (its own unless another's is
 * larger; list scheduling in predicted order). The thieves know every rank's unstarted work exactly
 * (optimistic). Columns st1 and st_it (a step's first and later runs: the time of the last rank to finish
 * over the mean, steals included), Em_STL, E_STL,
 * stl/step (points stolen per load step).
 */
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
        double f = (1.0 + 0.2 * sin(0.7 * p + s)) * (1.0 + 0.003 * it) *
                   ((p * 7919 % 1000) < band * 1000 ? 3.0 : 1.0);
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
        if (gk_mesh_structured(&m, GK_Q4, n, org, len, NULL, &err) || gk_quad_rule(&q, GK_Q4, 2, &err))
            return -1;
    } else {
        n[0] = n[1] = n[2] = (int)ceil(cbrt(ngp / 8.0));
        if (gk_mesh_structured(&m, GK_HEX8, n, org, len, NULL, &err) || gk_quad_rule(&q, GK_HEX8, 2, &err))
            return -1;
    }
    ne = m.nelem * q.n, nd = dim * m.nnode;
    D = (double *)calloc((size_t)ne * dim * dim * dim * dim, sizeof(double));
    sig = (double *)calloc((size_t)ne * 9, sizeof(double));
    f = (double *)calloc((size_t)nd, sizeof(double)), x = (double *)calloc((size_t)nd, sizeof(double));
    if (!D || !sig || !f || !x || gk_csr_from_mesh(&K, &m, NULL, &err)) return -1;
    for (k = 0; k < ne; ++k) gk_fem_elastic_tangent(dim, 1e8, 0.2, D + (size_t)k * dim * dim * dim * dim);
    { /* the bottom face clamped */
        int *nodes = (int *)malloc((size_t)m.nnode * sizeof(int)), nb, a, c;
        fix = (int *)malloc((size_t)nd * sizeof(int)), v = (double *)calloc((size_t)nd, sizeof(double));
        if (!nodes || !fix || !v) return -1;
        nb = gk_mesh_nodes_on_plane(&m, 1, 0.0, 1e-9, nodes);
        for (a = 0; a < nb; ++a)
            for (c = 0; c < dim; ++c) fix[nfix++] = dim * nodes[a] + c;
        free(nodes);
    }
    for (k = 0; k < reps && best > 0; ++k) {
        int bad;
        gk_solver_init(&s);
        t = gk_wtime();
        bad = gk_fem_assemble(&m, &q, D, NULL, &K, NULL, &err) ||
              gk_fem_assemble(&m, &q, NULL, sig, NULL, f, &err);
        f[nd - 1] = 1.0;
        bad = bad || gk_fem_dirichlet(&K, f, nfix, fix, v, &err) || gk_solver_factor(&s, &K, NULL, &err);
        if (!bad && gk_solver_solve(&s, f, x)) bad = 1, err = s.err;
        if (bad) {
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

/* measured cost pairs: a[k] a Gauss point's DEM steps at one run, b[k] at a later one */
typedef struct pairs {
    double *a, *b;
    int n, cap;
} pairs;

static int pairs_add(pairs *P, double a, double b) {
    if (P->n == P->cap) {
        int cap = 2 * P->cap + 1024;
        double *na = (double *)realloc(P->a, (size_t)cap * sizeof *na), *nb;
        if (!na) return 1;
        P->a = na;
        if (!(nb = (double *)realloc(P->b, (size_t)cap * sizeof *nb))) return 1;
        P->b = nb, P->cap = cap;
    }
    P->a[P->n] = a, P->b[P->n++] = b;
    return 0;
}

/* how well the first cost of the pairs predicts the second: Pearson's r, and the median and 90th
 * percentile of |b - a| / (a + 1) */
static void pair_stats(const char *what, const pairs *P) {
    double ma = 0, mb = 0, sab = 0, saa = 0, sbb = 0,
           *rel = (double *)malloc(((size_t)P->n + 1) * sizeof(double));
    int k;
    if (!rel || P->n < 2) {
        free(rel);
        return;
    }
    for (k = 0; k < P->n; ++k) ma += P->a[k] / P->n, mb += P->b[k] / P->n;
    for (k = 0; k < P->n; ++k) {
        sab += (P->a[k] - ma) * (P->b[k] - mb), saa += (P->a[k] - ma) * (P->a[k] - ma);
        sbb += (P->b[k] - mb) * (P->b[k] - mb), rel[k] = fabs(P->b[k] - P->a[k]) / (P->a[k] + 1.0);
    }
    qsort(rel, (size_t)P->n, sizeof *rel, cmp_d);
    printf("  %-44s %7d pairs: r = %.3f, |w1 - w0| / (w0 + 1) median %.3f, p90 %.3f\n", what, P->n,
           saa > 0 && sbb > 0 ? sab / sqrt(saa * sbb) : 1.0, rel[P->n / 2], rel[(int)(0.9 * P->n)]);
    free(rel);
}

/* gk_twoscale's balance (gk__ts_balance) of cost c[0..n) over R ranks from the assignment own
 * (changed): moves from the most to the least loaded rank, each the point whose cost is nearest half
 * their gap, until within tol of the mean (or no move helps) */
static void balance(const double *c, int *own, int n, int R, double tol) {
    double *L = (double *)calloc((size_t)R, sizeof(double)), mean = 0.0;
    int p, r, it;
    for (p = 0; p < n; ++p) L[own[p]] += c[p], mean += c[p];
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
    free(L);
}

/* the most loaded rank's cost over the mean */
static double max_over_mean(const double *c, const int *own, int n, int R) {
    double *L = (double *)calloc((size_t)R, sizeof(double)), mean = 0.0, mx = 0.0;
    int p, r;
    for (p = 0; p < n; ++p) L[own[p]] += c[p], mean += c[p];
    for (r = 0; r < R; ++r)
        if (L[r] > mx) mx = L[r];
    free(L);
    return mx * R / mean;
}

/* a balance that runs on other costs than it was made from: the assignment balanced on c (from the
 * first one, contiguous ranges of equal particle counts), run on `next`; out: the imbalance then,
 * and the rebalance on `next` that follows (its moves, the busiest rank's records in and out) */
typedef struct verdict {
    double imb;
    int moves, busiest;
} verdict;
static verdict predict(const double *c, const double *next, int n, int R, double tol) {
    int *own = (int *)malloc((size_t)n * sizeof(int)), *was = (int *)malloc((size_t)n * sizeof(int));
    int *mv = (int *)calloc((size_t)R, sizeof(int)), p, r;
    verdict v;
    for (p = 0; p < n; ++p) own[p] = (int)((p + 0.5) * R / n);
    balance(c, own, n, R, tol);
    v.imb = max_over_mean(next, own, n, R);
    memcpy(was, own, (size_t)n * sizeof(int));
    balance(next, own, n, R, tol);
    for (v.moves = 0, p = 0; p < n; ++p) /* a point moves once, whatever the balance's steps */
        if (own[p] != was[p]) ++v.moves, ++mv[was[p]], ++mv[own[p]];
    for (v.busiest = 0, r = 0; r < R; ++r)
        if (mv[r] > v.busiest) v.busiest = mv[r];
    free(own), free(was), free(mv);
    return v;
}

/* rule STEAL, simulated: the assignment balanced on the predicted costs c (as predict() makes it),
 * each rank running its points in decreasing predicted cost at their realised costs `real`; a rank
 * that runs out asks the rank with the most predicted work not yet started (a request, alpha), which
 * answers when it next polls (between its RVE runs: at the end of the run in progress, or at once if
 * it runs none) by sending its last unstarted point (its smallest predicted cost; the record, alpha +
 * rec / bw, and the thief keeps the point), or "none" (alpha), after which the thief asks again; a
 * rank done when no rank has unstarted points. Out: the time of the last rank to finish, and the
 * points stolen (*steals). Events in time order, ties by rank: deterministic. */
typedef struct steal_sim {
    double *busy,
        *left; /* a rank's next event (end of its run, or a reply's arrival), predicted work not started */
    int *own, *q, *head, *tail, *reqh, *reqn, *reqt, *heap, nheap;
    double *reqa; /* a request's arrival at its victim */
} steal_sim;

static int ss_less(const steal_sim *S, int a, int b) {
    return S->busy[a] < S->busy[b] || (S->busy[a] == S->busy[b] && a < b);
}
static void ss_push(steal_sim *S, int r) {
    int i = S->nheap++;
    while (i > 0 && ss_less(S, r, S->heap[(i - 1) / 2])) S->heap[i] = S->heap[(i - 1) / 2], i = (i - 1) / 2;
    S->heap[i] = r;
}
static int ss_pop(steal_sim *S) {
    int top = S->heap[0], last = S->heap[--S->nheap], i = 0;
    for (;;) {
        int c = 2 * i + 1;
        if (c >= S->nheap) break;
        if (c + 1 < S->nheap && ss_less(S, S->heap[c + 1], S->heap[c])) ++c;
        if (!ss_less(S, S->heap[c], last)) break;
        S->heap[i] = S->heap[c], i = c;
    }
    if (S->nheap > 0) S->heap[i] = last;
    return top;
}

static const double *ss_key; /* qsort: a rank's points by decreasing predicted cost, ties by index */
static int cmp_pred(const void *a, const void *b) {
    int x = *(const int *)a, y = *(const int *)b;
    if (ss_key[x] != ss_key[y]) return ss_key[x] > ss_key[y] ? -1 : 1;
    return x < y ? -1 : x > y;
}

/* --steal-answer now (1: a victim answers a request on arrival, as if it polled during its RVE runs;
 * 0: between its runs), --steal-order global (1: a free rank takes the largest predicted unstarted point of
 * any rank, its own unless another's is larger; 0: its own points first, then the last of the rank with
 * the most predicted work not started) */
static int steal_now, steal_global;
static double steal_run(const double *c, const double *real, int n, int R, double tol, double alpha,
                        double rec, double bw, int *steals) {
    steal_sim S;
    int p, r, k, *cnt;
    double tend = 0.0, tsend = rec / bw;
    S.busy = (double *)calloc((size_t)R, sizeof(double)),
    S.left = (double *)calloc((size_t)R, sizeof(double));
    S.own = (int *)malloc((size_t)n * sizeof(int)), S.q = (int *)malloc((size_t)n * sizeof(int));
    S.head = (int *)calloc((size_t)R + 1, sizeof(int)), S.tail = (int *)calloc((size_t)R, sizeof(int));
    S.reqh = (int *)malloc((size_t)R * sizeof(int)), S.reqt = (int *)malloc((size_t)R * sizeof(int));
    S.reqn = (int *)malloc((size_t)R * sizeof(int)), S.reqa = (double *)malloc((size_t)R * sizeof(double));
    S.heap = (int *)malloc((size_t)R * sizeof(int)), S.nheap = 0;
    cnt = (int *)calloc((size_t)R + 1, sizeof(int));
    *steals = 0;
    for (p = 0; p < n; ++p) S.own[p] = (int)((p + 0.5) * R / n);
    balance(c, S.own, n, R, tol);
    for (p = 0; p < n; ++p) ++cnt[S.own[p] + 1], S.left[S.own[p]] += c[p];
    for (r = 0; r < R; ++r) cnt[r + 1] += cnt[r];
    for (r = 0; r < R; ++r) S.head[r] = S.tail[r] = cnt[r], S.reqh[r] = S.reqt[r] = -1;
    for (p = 0; p < n; ++p) S.q[S.tail[S.own[p]]++] = p;
    for (ss_key = c, r = 0; r < R; ++r) {
        qsort(S.q + S.head[r], (size_t)(S.tail[r] - S.head[r]), sizeof(int), cmp_pred);
        S.busy[r] = 0.0, ss_push(&S, r);
    }
    /* a rank's event: it answers the requests that have reached it, then runs its next point, or asks
     * for one, or is done */
    while (S.nheap > 0) {
        int rr = ss_pop(&S);
        double t = S.busy[rr];
        while (S.reqh[rr] >= 0 && S.reqa[S.reqh[rr]] <= t) { /* the requests in arrival order */
            int th = S.reqh[rr];
            S.reqh[rr] = S.reqn[th];
            if (S.reqh[rr] < 0) S.reqt[rr] = -1;
            if (S.head[rr] < S.tail[rr]) {
                p = steal_global ? S.q[S.head[rr]++] : S.q[--S.tail[rr]], S.left[rr] -= c[p], ++*steals;
                t += tsend; /* the victim sends the record */
                S.busy[th] = t + alpha + tsend + real[p];
            } else
                S.busy[th] = t + alpha; /* "none": it asks again on arrival */
            ss_push(&S, th);
        }
        if (S.head[rr] == S.tail[rr]) /* nothing left to give: the requests still on their way get "none" */
            while (S.reqh[rr] >= 0) {
                int th = S.reqh[rr];
                S.reqh[rr] = S.reqn[th], S.busy[th] = (S.reqa[th] > t ? S.reqa[th] : t) + alpha;
                ss_push(&S, th);
            }
        S.reqt[rr] = S.reqh[rr] < 0 ? -1 : S.reqt[rr];
        { /* v: the rank to take the next point from */
            int v = S.head[rr] < S.tail[rr] ? rr : -1;
            for (k = 0; k < R && (steal_global || v != rr); ++k)
                if (k != rr && S.head[k] < S.tail[k] &&
                    (v < 0 || (steal_global ? c[S.q[S.head[k]]] > c[S.q[S.head[v]]] : S.left[k] > S.left[v])))
                    v = k;
            if (v < 0) { /* no unstarted point anywhere: done */
                if (t > tend) tend = t;
            } else if (v == rr) { /* its own */
                p = S.q[S.head[rr]++], S.left[rr] -= c[p];
                S.busy[rr] = t + real[p], ss_push(&S, rr);
            } else if (steal_now) { /* answered on arrival */
                p = steal_global ? S.q[S.head[v]++] : S.q[--S.tail[v]], S.left[v] -= c[p], ++*steals;
                S.busy[rr] = t + 2.0 * alpha + tsend + real[p], ss_push(&S, rr);
            } else { /* answered at v's next event; the reply brings rr back */
                S.reqa[rr] = t + alpha, S.reqn[rr] = -1;
                if (S.reqt[v] >= 0)
                    S.reqn[S.reqt[v]] = rr;
                else
                    S.reqh[v] = rr;
                S.reqt[v] = rr;
            }
        }
    }
    free(S.busy), free(S.left), free(S.own), free(S.q), free(S.head), free(S.tail), free(S.reqh),
        free(S.reqt);
    free(S.reqn), free(S.reqa), free(S.heap), free(cnt);
    return tend;
}

/* n costs [s] drawn (deterministically, from `seed`) from the pairs: c0 what the balance sees, c1
 * what the ranks then run; their sum */
static double draw(const pairs *P, int n, double per_step, uint64_t seed, double *c0, double *c1) {
    gk_rng rng;
    double tot = 0.0;
    int p;
    gk_rng_seed(&rng, seed);
    for (p = 0; p < n; ++p) {
        int i = (int)(gk_rng_u64(&rng) % (uint64_t)P->n);
        c0[p] = (P->a[i] + 1.0) * per_step, c1[p] = (P->b[i] + 1.0) * per_step;
        tot += c1[p];
    }
    return tot;
}

/* the measured cost pairs: A, a point's work at the accepted run of a load step and at every run of
 * the next (what rule ACCEPT balances on and then runs); B, at the accepted run and the first run of
 * the next step; W, at one Newton iteration of a step and the next; m runs per step */
typedef struct cost_data {
    pairs A, B, W;
    double m;
} cost_data;

/* one case at R ranks under both rules. Rule ACCEPT (gk_twoscale's default) runs every iteration of
 * a load step on the assignment made from the last step's costs (imbalance imb_acc, pairs A) and
 * rebalances once per step; rule RUN runs the first iteration so (imb1, pairs B) and the m - 1 others
 * on the previous iteration's costs (imb_it, pairs W), rebalancing before every run. Each rebalance
 * costs the busiest rank 3 messages and a record of rec bytes per point it sends or receives. Out:
 * E_micro (RVEs, messages, migrations) and E (with the FEM replicated on every rank) of both rules,
 * and the records moved per step (RUN). */
typedef struct outcome {
    double same, same_it, imb_acc, imb1, imb_it, Em_acc, Em_run, E_acc, E_run, t_rve_acc, moved_step;
    double st1, st_it, Em_steal, E_steal,
        steals_step; /* rule STEAL: RUN's assignments, stealing during the runs */
} outcome;
static outcome evaluate(const cost_data *C, int n, int R, double per_step, double rec, double tfem,
                        double tol, double alpha, double bytes, double bw) {
    double *c0 = (double *)malloc((size_t)n * sizeof(double)),
           *c1 = (double *)malloc((size_t)n * sizeof(double));
    double totA, totB, totW = 0.0, lg = ceil(log2((double)R > 1 ? R : 2)), tmsg, tmig1, tmig_it = 0.0,
                       m = C->m;
    double work, t, t1s, tis = 0.0;
    int s1 = 0, sit = 0;
    verdict vA, v1, vi = {1.0, 0, 0}, vs, vsi = {1.0, 0, 0};
    outcome o;
    /* a broadcast (dH) and an allgather (results) by recursive doubling: log2 R latencies each; every
     * rank receives every point's dH and results once */
    tmsg = 2.0 * lg * alpha + bytes / bw;
    totA = draw(&C->A, n, per_step, 5, c0, c1);
    vA = predict(c0, c1, n, R, tol);
    vs = predict(c1, c1, n, R, tol);
    totB = draw(&C->B, n, per_step, 7, c0, c1);
    v1 = predict(c0, c1, n, R, tol);
    t1s = steal_run(c0, c1, n, R, tol, alpha, rec, bw, &s1);
    tmig1 = v1.busiest * (3.0 * alpha + rec / bw);
    if (C->W.n > 0) {
        totW = draw(&C->W, n, per_step, 11, c0, c1);
        vi = predict(c0, c1, n, R, tol);
        vsi = predict(c1, c1, n, R, tol);
        tis = steal_run(c0, c1, n, R, tol, alpha, rec, bw, &sit);
        tmig_it = vi.busiest * (3.0 * alpha + rec / bw);
    }
    o.same = vs.imb, o.same_it = vsi.imb, o.imb_acc = vA.imb, o.imb1 = v1.imb, o.imb_it = vi.imb;
    o.t_rve_acc = vA.imb * totA / R;
    o.Em_acc = totA / (R * (o.t_rve_acc + tmsg + tmig1 / m));
    o.E_acc = (totA + tfem) / (R * (o.t_rve_acc + tmsg + tmig1 / m + tfem));
    work = totB + (m - 1.0) * totW; /* a load step under RUN */
    t = (v1.imb * totB + (m - 1.0) * vi.imb * totW) / R + m * tmsg + tmig1 + (m - 1.0) * tmig_it;
    o.Em_run = work / (R * t);
    o.E_run = (work + m * tfem) / (R * (t + m * tfem));
    o.moved_step = v1.moves + (m - 1.0) * vi.moves;
    /* STEAL: RUN's rebalances and messages; each run ends when its last rank does (the steals' latencies
     * and records inside) */
    o.st1 = t1s * R / totB, o.st_it = totW > 0 ? tis * R / totW : 1.0;
    t = t1s + (m - 1.0) * tis + m * tmsg + tmig1 + (m - 1.0) * tmig_it;
    o.Em_steal = work / (R * t);
    o.E_steal = (work + m * tfem) / (R * (t + m * tfem));
    o.steals_step = s1 + (m - 1.0) * sit;
    free(c0), free(c1);
    return o;
}

/* the table: per case and rank count the RVE time per iteration of the most loaded rank (rule
 * ACCEPT), the FEM time (replicated on every rank), the message time, the imbalances (most loaded rank
 * / mean): imb= when the balance knows the costs of the runs, ACC when it knows the last step's
 * (rule ACCEPT, every run of the step), first: the first run of a step so (rule RUN), it= and imb_it:
 * the other runs when the balance knows their costs and the previous iteration's (RUN); E_micro
 * (RVEs, messages, migrations) and E (with the replicated FEM) of both rules, the bytes that move per
 * load step under RUN; then, per rule, E_micro at 8 RVEs per rank and the fewest RVEs per rank for
 * E_micro >= 90 %. No pairs W: RUN is not evaluated. rec2d: a 400-disk point's record (migrations). */
static void model(const cost_data *C, double rate2d, double rate3d, double alpha, double bw, double tol,
                  double rec2d) {
    static const int ranks[3] = {64, 1000, 10000}, per[12] = {1, 2, 4, 6, 8, 10, 12, 16, 24, 32, 64, 128};
    struct {
        const char *name;
        int dim, n, particles;
        double rate, rec;
    } cs[2];
    int k, j, rule;
    cs[0].name = "2D 7776 x 400 disks", cs[0].dim = 2, cs[0].n = 7776, cs[0].particles = 400,
    cs[0].rate = rate2d;
    cs[1].name = "3D 1000 x 4096 spheres", cs[1].dim = 3, cs[1].n = 1000, cs[1].particles = 4096,
    cs[1].rate = rate3d;
    /* a 3D record: assumed twice the 2D bytes per particle (3 components instead of 2, 3 rotations
     * instead of 1, more contacts per particle) */
    cs[0].rec = rec2d, cs[1].rec = 2.0 * rec2d / 400.0 * 4096.0;
    printf("\nscaling model (rates %.3g and %.3g particle-steps/s per core, alpha %.1e s, bandwidth %.2g "
           "B/s, balance "
           "tolerance %.2f,\n  %.2f runs per load step, point records %.0f and %.0f bytes; ACCEPT: balance "
           "at every "
           "accept, RUN: before every run):\n",
           rate2d, rate3d, alpha, bw, tol, C->m, cs[0].rec, cs[1].rec);
    printf("how a point's DEM steps w1 at a run follow its w0 at the run the balance knew:\n");
    pair_stats("last step's accepted run -> each run (ACCEPT)", &C->A);
    pair_stats("last step's accepted run -> first run", &C->B);
    pair_stats("Newton iteration -> the next (RUN)", &C->W);
    printf("%-23s %6s %7s %9s %9s %8s %6s %6s %6s %6s %6s %6s %6s %7s %7s %7s %6s %6s %6s %8s %8s\n", "case",
           "ranks", "rve/rk", "T_rve ms", "T_fem ms", "T_msg ms", "imb=", "ACC", "first", "it=", "imb_it",
           "st1", "st_it", "Em_ACC", "Em_RUN", "Em_STL", "E_ACC", "E_RUN", "E_STL", "MB/step", "stl/step");
    for (k = 0; k < 2; ++k) {
        int n = cs[k].n, nd4 = cs[k].dim * cs[k].dim * cs[k].dim * cs[k].dim;
        double tfem = fem_seconds(cs[k].dim, n), bytes = 8.0 * n * (9 + 9 + nd4 + 7),
               ps = cs[k].particles / cs[k].rate;
        for (j = 0; j < 3; ++j) {
            int R = ranks[j];
            double lg = ceil(log2((double)R));
            outcome o = evaluate(C, n, R, ps, cs[k].rec, tfem, tol, alpha, bytes, bw);
            printf("%-23s %6d %7.2f %9.2f %9.2f %8.3f %6.3f %6.3f %6.3f ", cs[k].name, R, (double)n / R,
                   1e3 * o.t_rve_acc, 1e3 * tfem, 1e3 * (2.0 * lg * alpha + bytes / bw), o.same, o.imb_acc,
                   o.imb1);
            if (C->W.n > 0)
                printf(
                    "%6.3f %6.3f %6.3f %6.3f %6.1f%% %6.1f%% %6.1f%% %5.1f%% %5.1f%% %5.1f%% %8.2f %8.0f\n",
                    o.same_it, o.imb_it, o.st1, o.st_it, 100 * o.Em_acc, 100 * o.Em_run, 100 * o.Em_steal,
                    100 * o.E_acc, 100 * o.E_run, 100 * o.E_steal, 1e-6 * o.moved_step * cs[k].rec,
                    o.steals_step);
            else
                printf("%6s %6s %6s %6s %6.1f%% %7s %7s %5.1f%% %6s %6s %8s %8s\n", "-", "-", "-", "-",
                       100 * o.Em_acc, "-", "-", 100 * o.E_acc, "-", "-", "-", "-");
        }
        for (rule = 0; rule < (C->W.n > 0 ? 3 : 1); ++rule) {
            static const char *rname[3] = {"ACCEPT", "RUN", "STEAL"};
            outcome o = evaluate(C, n, n / 8, ps, cs[k].rec, tfem, tol, alpha, bytes, bw);
            double em = rule == 0 ? o.Em_acc : rule == 1 ? o.Em_run : o.Em_steal;
            printf("%-23s %-6s: E_micro %.1f %% at 8 RVEs per rank (%d ranks); ", cs[k].name, rname[rule],
                   100 * em, n / 8);
            for (j = 0; j < 12; ++j) {
                int R = n / per[j] > 1 ? n / per[j] : 2;
                o = evaluate(C, n, R, ps, cs[k].rec, tfem, tol, alpha, bytes, bw);
                em = rule == 0 ? o.Em_acc : rule == 1 ? o.Em_run : o.Em_steal;
                if (em >= 0.9) break;
            }
            if (j < 12)
                printf(">= 90 %% from %d RVEs per rank (%d ranks: %.1f %%)\n", per[j],
                       n / per[j] > 1 ? n / per[j] : 2, 100 * em);
            else
                printf("below 90 %% up to %d RVEs per rank\n", per[11]);
        }
    }
}

/* femdem_biaxial --cost-log FILE: a line per run "STEP SCALE W_0 ... W_n-1". Pairs across steps (B:
 * the last run of a step, the accepted one, and the first run of the next), within a step (W:
 * consecutive runs of one step and scale, i.e. Newton iterations) and the runs per attempt of a step
 * (*m). 0, or 1 after a message naming the line */
static int read_cost_log(const char *path, cost_data *C) {
    FILE *fp = fopen(path, "r");
    char *line = NULL;
    size_t cap = 0;
    double *prev = NULL, *cur = NULL, *acc = NULL, pscale = 0.0;
    int npt = 0, room = 0, lines = 0, attempts = 0, pstep = 0, bad = 0;
    if (!fp) return fprintf(stderr, "bench_twoscale: cannot open %s\n", path), 1;
    while (!bad && getline(&line, &cap, fp) > 0) {
        char *s = line, *end;
        long step = strtol(s, &end, 10);
        double scale = 0.0, *t;
        int k = 0;
        bad = end == s || step < 1 || step > 100000000 || (lines > 0 && (step < pstep || step > pstep + 1));
        if (!bad) s = end, scale = strtod(s, &end), bad = end == s || !(scale > 0 && scale <= 1);
        for (s = end; !bad; s = end) { /* the points' work */
            double w = strtod(s, &end);
            if (end == s) break;
            bad = !(w >= 0 && w < 1e12) || (lines > 0 && k == npt);
            if (!bad && k == room) {
                bad = !(t = (double *)realloc(cur, (size_t)(room + 1024) * sizeof *t));
                if (!bad) cur = t, room += 1024;
            }
            if (!bad) cur[k++] = w;
        }
        while (!bad && (*s == ' ' || *s == '\t' || *s == '\r' || *s == '\n')) ++s;
        bad = bad || *s || k == 0 || (lines > 0 && k != npt);
        if (bad) break;
        if (lines == 0) npt = k;
        if (lines > 0 && step == pstep + 1) { /* prev: the accepted run of the last step */
            if (!acc && !(acc = (double *)malloc((size_t)npt * sizeof *acc))) bad = 1;
            if (!bad) memcpy(acc, prev, (size_t)npt * sizeof *acc);
        }
        if (lines > 0 && step == pstep && scale == pscale) /* the next iteration of the same step */
            for (k = 0; k < npt && !bad; ++k) bad = pairs_add(&C->W, prev[k], cur[k]);
        else { /* a new attempt at a step: the first run of the next step, or of a cut-back */
            ++attempts;
            if (lines > 0 && step == pstep + 1)
                for (k = 0; k < npt && !bad; ++k) bad = pairs_add(&C->B, prev[k], cur[k]);
        }
        for (k = 0; acc && k < npt && !bad; ++k) bad = pairs_add(&C->A, acc[k], cur[k]);
        if (!prev && !(prev = (double *)malloc((size_t)room * sizeof *prev))) bad = 1;
        if (!bad) t = prev, prev = cur, cur = t;
        pstep = (int)step, pscale = scale, ++lines;
    }
    bad = bad || ferror(fp) || C->B.n == 0;
    if (bad)
        fprintf(stderr,
                "bench_twoscale: %s, line %d: not a femdem_biaxial --cost-log line (\"STEP SCALE W_0 ... "
                "W_n-1\", "
                "steps 1, 2, ... and the same point count on every line), or no two load steps\n",
                path, lines + 1);
    C->m = attempts > 0 ? (double)lines / attempts : 1.0;
    fclose(fp);
    free(line), free(prev), free(cur), free(acc);
    return bad;
}

int main(int argc, char **argv) {
    int n = 512, steps = 3, iters = 3, threads = 1, do_model = 0, balance_rule = 0, s, it, p, rank = 0,
        nranks = 1, help = 0, nt = 0;
    double band = 0.1, alpha = 2e-6, bw = 1e10, rate3d = 1.05e7, tol = 0.05, rate2d = 0;
    const char *costs = NULL, *cost_log = NULL;
    const cli_opt opts[] = {
        {"--points", CLI_INT, &n, 1, 1000000, NULL, NULL, 0},
        {"--steps", CLI_INT, &steps, 2, 1000, NULL, NULL, 0},
        {"--iterations", CLI_INT, &iters, 1, 1000, NULL, NULL, 0},
        {"--threads", CLI_INT, &threads, 1, 1024, NULL, NULL, 0},
        {"--band", CLI_REAL, &band, 0, 1, NULL, NULL, 0},
        {"--model", CLI_FLAG, &do_model, 0, 0, NULL, NULL, 0},
        {"--alpha", CLI_REAL, &alpha, 0, 1, NULL, NULL, 0},
        {"--bandwidth", CLI_REAL, &bw, 0, HUGE_VAL, NULL, NULL, CLI_LO_OPEN | CLI_HI_OPEN},
        {"--rate3d", CLI_REAL, &rate3d, 0, HUGE_VAL, NULL, NULL, CLI_LO_OPEN | CLI_HI_OPEN},
        {"--rate2d", CLI_REAL, &rate2d, 0, HUGE_VAL, NULL, NULL, CLI_HI_OPEN},
        {"--tol", CLI_REAL, &tol, 0, 1, NULL, NULL, CLI_LO_OPEN},
        {"--costs", CLI_STR, &costs, 0, 0, NULL, NULL, 0},
        {"--cost-log", CLI_STR, &cost_log, 0, 0, NULL, NULL, 0},
        {"--balance", CLI_CHOICE, &balance_rule, 0, 0, NULL, "accept|run", 0},
        {"--steal-answer", CLI_CHOICE, &steal_now, 0, 0, NULL, "run|now", 0},
        {"--steal-order", CLI_CHOICE, &steal_global, 0, 0, NULL, "own|global", 0},
        {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    const cli_opt *tables[2];
    gk_packing pk;
    gk_err err;
    gk_twoscale ts;
    gk_twoscale_proto pr;
    gk_twoscale_def d;
    double *dH, *sig, *D, *times, *work, work_ps = 0.0, t0;
    cost_data C;
    long long b_in = 0, b_out = 0;
    gk_twoscale_stats st0;
#ifdef GK_TWOSCALE_MPI
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &nranks);
#endif
    tables[0] = opts, tables[1] = NULL;
    if (cli_parse(rank == 0 ? "bench_twoscale" : NULL, argc, argv, tables, &help) || help) {
        if (help && rank == 0)
            printf("usage: bench_twoscale [--points 512] [--steps 3] [--iterations 3] [--threads T]\n"
                   "         [--band 0.1] [--balance accept|run]\n"
                   "         [--model [--cost-log FILE | --costs FILE]] [--alpha 2e-6] [--bandwidth 1e10]\n"
                   "         [--rate2d R] [--rate3d 1.05e7] [--tol 0.05]\n"
                   "         [--steal-answer run|now] [--steal-order own|global]\n"
                   "       mpirun -np R build/mpi/bench_twoscale_mpi ... (the same on R ranks)\n"
                   "N RVEs of the Guo & Zhao (2014) 400-disk packing, one Newton iteration after another;\n"
                   "prints ms per iteration and a BENCH line; --model adds the scaling model of\n"
                   "bench/README.md. What each option does: the top of bench/twoscale.c.\n");
#ifdef GK_TWOSCALE_MPI
        MPI_Finalize();
#endif
        return help ? 0 : 2;
    }
    if (steal_global &&
        !steal_now) { /* simulated, every free rank asking in turn: too slow at 10 000 ranks */
        if (rank == 0) fprintf(stderr, "bench_twoscale: --steal-order global needs --steal-answer now\n");
#ifdef GK_TWOSCALE_MPI
        MPI_Finalize();
#endif
        return 2;
    }
    if (gk_packing_read("examples/data/rve400.txt", &pk, NULL, &err)) {
        fprintf(stderr, "bench_twoscale: %s\n", err.msg);
        return 1;
    }
    memset(&d, 0, sizeof d);
    memset(&st0, 0, sizeof st0);
    memset(&C, 0, sizeof C);
    C.m = iters;
    pr.packing = &pk, pr.state = NULL;
    d.npoints = n, d.protos = &pr, d.nprotos = 1, d.threads = threads;
    d.balance = balance_rule ? GK_TWOSCALE_BALANCE_RUN : GK_TWOSCALE_BALANCE_ACCEPT;
    d.rve = gk_rve_def_default();
    d.rve.dt = 3.1602315723728926e-05;
    d.rule.n_min = 2, d.rule.n_max = 400, d.rule.unbalanced_max = 2e-2; /* femdem_biaxial's defaults */
    dH = (double *)malloc((size_t)n * 9 * sizeof(double)),
    sig = (double *)malloc((size_t)n * 9 * sizeof(double));
    D = (double *)malloc((size_t)n * 16 * sizeof(double));
    times = (double *)malloc((size_t)steps * iters * sizeof(double));
    work = (double *)malloc((size_t)steps * iters * n * sizeof(double));
    if (!dH || !sig || !D || !times || !work || gk_twoscale_create(&ts, &d)) {
        fprintf(stderr, "bench_twoscale: %s\n", gk_twoscale_error(&ts));
        return 1;
    }
    if (do_model && rank == 0 && nranks == 1 && cost_log) { /* femdem_biaxial --cost-log (bench/README.md) */
        if (read_cost_log(cost_log, &C)) return 1;
        printf("cost pairs from %s: %d across load steps, %d within (%.2f runs per step)\n", cost_log, C.B.n,
               C.W.n, C.m);
    } else if (do_model && rank == 0 && nranks == 1 &&
               costs) { /* "w0 w1" per line across steps; none within */
        FILE *fp = fopen(costs, "r");
        double x, y;
        int bad = 0;
        while (fp && !bad && fscanf(fp, "%lf %lf", &x, &y) == 2)
            bad =
                !(x >= 0 && y >= 0 && x < 1e12 && y < 1e12) || pairs_add(&C.A, x, y) || pairs_add(&C.B, x, y);
        if (!fp || bad || !feof(fp) || ferror(fp) || C.B.n == 0)
            return fprintf(stderr,
                           "bench_twoscale: %s: not a file of cost pairs \"w0 w1\" (non-negative) per line\n",
                           costs),
                   1;
        fclose(fp);
        printf("cost pairs: %d from %s (across steps only: rule RUN not evaluated)\n", C.B.n, costs);
    }
    if (rank == 0)
        printf("bench_twoscale: %d RVEs of %d disks, %d rank(s) x %d thread(s), %d steps x %d iterations\n",
               n, pk.n, nranks, threads, steps, iters);
    for (s = 0; s < steps; ++s)
        for (it = 0; it < iters; ++it) {
            const gk_twoscale_point *pts;
            double dt;
            field(n, s, it, band, dH);
            if (s == 1 && it == 0)
                st0 = ts.stats; /* traffic from the second step on (after a first balance) */
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
        int nw = (steps - 1) * iters * n, k;
        double med, tsum = 0, q[5], *wa = (double *)malloc((size_t)nw * sizeof(double));
        if (!wa) return 1;
        memcpy(wa, work + (size_t)iters * n, (size_t)nw * sizeof(double));
        for (k = 0; k < nt; ++k) tsum += times[k];
        qsort(times, (size_t)nt, sizeof *times, cmp_d);
        med = times[nt / 2];
        qsort(wa, (size_t)nw, sizeof *wa, cmp_d);
        q[0] = wa[0], q[1] = wa[nw / 2], q[3] = wa[(int)(0.9 * nw)], q[4] = wa[nw - 1], q[2] = 0;
        for (k = 0; k < nw; ++k) q[2] += wa[k] / nw;
        free(wa);
        printf("wall per iteration: median %.1f ms (min %.1f, max %.1f) over %d iterations\n", 1e3 * med,
               1e3 * times[0], 1e3 * times[nt - 1], nt);
        printf(
            "DEM steps per RVE run: min %.0f  median %.0f  mean %.1f  p90 %.0f  max %.0f (max/mean %.2f)\n",
            q[0], q[1], q[2], q[3], q[4], q[4] / q[2]);
        printf("per iteration, rank 0: %.0f bytes in, %.0f bytes out; %lld point moves in %lld rebalances "
               "(balance at "
               "%s), %lld bytes moved in all\n",
               (double)b_in / nt, (double)b_out / nt, ts.stats.migrated, ts.stats.balances,
               balance_rule ? "every run" : "every accept", ts.stats.migrated_bytes);
        printf("BENCH case=twoscale ranks=%d threads=%d points=%d ms_per_iteration=%.2f rve_runs_per_s=%.1f "
               "particle_steps_per_s=%.4g bytes_in_per_iteration=%.0f bytes_out_per_iteration=%.0f\n",
               nranks, threads, n, 1e3 * med, n / med, work_ps / tsum, (double)b_in / nt, (double)b_out / nt);
        if (do_model && nranks == 1) {
            /* cost pairs of this run unless read from a file: across steps (B), a point's work at the
             * last iteration of a step (what the balance at accept sees) and at the first iteration of
             * the next (what the ranks then run); within a step (W), at one iteration and the next. The
             * 2D rate per core from this run (or --rate2d) */
            double rec = (double)gk__ts_rec_size(&ts, ts.pt[0]); /* a point's record (one rank) */
            int bad = 0;
            for (s = 0; s + 1 < steps && !cost_log && !costs; ++s)
                for (p = 0; p < n; ++p) {
                    double wacc = work[((size_t)s * iters + iters - 1) * n + p];
                    bad |= pairs_add(&C.B, wacc, work[((size_t)(s + 1) * iters) * n + p]);
                    for (it = 0; it < iters; ++it)
                        bad |= pairs_add(&C.A, wacc, work[((size_t)(s + 1) * iters + it) * n + p]);
                    for (it = 0; it + 1 < iters; ++it)
                        bad |= pairs_add(&C.W, work[((size_t)(s + 1) * iters + it) * n + p],
                                         work[((size_t)(s + 1) * iters + it + 1) * n + p]);
                }
            if (bad) return fprintf(stderr, "bench_twoscale: out of memory\n"), 1;
            model(&C, rate2d > 0 ? rate2d : work_ps / tsum / threads, rate3d, alpha, bw, tol, rec);
        }
    }
    free(C.A.a), free(C.A.b), free(C.B.a), free(C.B.b), free(C.W.a), free(C.W.b);
    gk_twoscale_destroy(&ts);
    gk_packing_free(&pk);
    free(dH), free(sig), free(D), free(times), free(work);
#ifdef GK_TWOSCALE_MPI
    MPI_Finalize();
#endif
    return 0;
}
