/* mpi_twoscale.c - gk_twoscale.h with its MPI backend (GK_TWOSCALE_MPI), run by `make test` as
 * `mpirun -np 2 build/mpi/mpi_twoscale` when mpicc is installed.
 *
 * Every rank holds the same set twice: spread over MPI_COMM_WORLD (each rank stores only its own
 * points; a balance tolerance of 1e-9 makes the points migrate at every accept) and whole on
 * MPI_COMM_SELF (one rank, the threaded build's path). Their stresses, tangents, reports and fields
 * must agree bit for bit on every rank, across migrations, a failed point on the other rank, a
 * checkpoint written by 2 ranks and read by 1 (and back), and a refused corrupt one; and with the
 * balance before every run (GK_TWOSCALE_BALANCE_RUN), across the Newton iterations of a load step,
 * a reject and a refused run. */
#define GK_IMPLEMENTATION
#define GK_TWOSCALE_MPI
#include "gk_twoscale.h"
#include "gk_test.h"

#define NP 10
#define DT 2e-5

static gk_packing pk100, pk200;
static int rank;

static gk_result make_set_b(gk_twoscale *ts, MPI_Comm comm, gk_twoscale_tangent_kind tan, double reuse,
                            gk_twoscale_balance_kind bal) {
    gk_twoscale_proto pr[2];
    gk_twoscale_def d;
    pr[0].packing = &pk100, pr[0].state = NULL;
    pr[1].packing = &pk200, pr[1].state = NULL;
    memset(&d, 0, sizeof d);
    d.npoints = NP, d.protos = pr, d.nprotos = 2, d.seed = 5, d.threads = 1;
    d.rve = gk_rve_def_default();
    d.rve.dt = DT;
    d.rule.n_min = 20, d.rule.n_max = 300, d.rule.unbalanced_max = 2e-2;
    d.tangent = tan, d.reuse = reuse, d.balance_tol = 1e-9, d.balance = bal;
    return gk_twoscale_create_mpi(ts, &d, comm);
}
static gk_result make_set(gk_twoscale *ts, MPI_Comm comm, gk_twoscale_tangent_kind tan, double reuse) {
    return make_set_b(ts, comm, tan, reuse, GK_TWOSCALE_BALANCE_ACCEPT);
}

/* the first points (rank 0's at first) deform 3x more: more DEM steps, so the ranks' costs differ and
 * points migrate */
static void step_dH(int k, double amp, double *dH) {
    int p;
    memset(dH, 0, NP * 9 * sizeof(double));
    for (p = 0; p < NP; ++p) {
        double f = 1.0 + 0.15 * ((p * 7 + k * 3) % 5) + (p < NP / 2 ? 2.0 : 0.0);
        dH[9 * p + 0] = 0.3 * amp * f, dH[9 * p + 4] = -amp * f;
        dH[9 * p + 1] = 0.2 * amp * ((p + k) % 3 - 1), dH[9 * p + 3] = -0.1 * amp * ((p + 2 * k) % 3 - 1);
    }
}

static int same(const double *a, const double *b, size_t n) { return memcmp(a, b, n * sizeof(double)) == 0; }

/* one run of both sets (rank 1 gives no dH to the spread set: rank 0's is the one used); 1 if equal */
static int run_both(gk_twoscale *w, gk_twoscale *s, const double *dH, gk_result want) {
    double sw[9 * NP], ss[9 * NP], Dw[16 * NP], Ds[16 * NP];
    int ok = gk_twoscale_run(w, rank == 0 ? dH : NULL, NULL, sw, Dw) == want;
    ok &= gk_twoscale_run(s, dH, NULL, ss, Ds) == want;
    ok &= same(sw, ss, 9 * NP) && same(Dw, Ds, 16 * NP);
    ok &= !memcmp(gk_twoscale_points(w), gk_twoscale_points(s), NP * sizeof(gk_twoscale_point));
    return ok;
}

static int fields_same(gk_twoscale *w, gk_twoscale *s) {
    gk_twoscale_field fw[NP], fs[NP];
    return gk_twoscale_fields(w, fw) == GK_OK && gk_twoscale_fields(s, fs) == GK_OK &&
           !memcmp(fw, fs, sizeof fw);
}

/* 2 ranks = 1 rank, bit for bit, over steps with migrations; eq 9 and eq 8 with reuse */
TEST(two_ranks_equal_one_rank) {
    int mode;
    for (mode = 0; mode < 2; ++mode) {
        gk_twoscale w, s;
        double dH[9 * NP];
        int k, ok = 1, n0;
        gk_twoscale_tangent_kind t = mode ? GK_TWOSCALE_TANGENT_PERTURBATION : GK_TWOSCALE_TANGENT_HOMOG;
        CHECK(make_set(&w, MPI_COMM_WORLD, t, mode ? 0.5 : 0) == GK_OK);
        CHECK(make_set(&s, MPI_COMM_SELF, t, mode ? 0.5 : 0) == GK_OK);
        CHECK(w.nranks == 2 && s.nranks == 1 && w.nlocal < NP && s.nlocal == NP);
        n0 = w.nlocal;
        for (k = 0; k < 4; ++k) {
            step_dH(k, 5e-4, dH);
            ok &= run_both(&w, &s, dH, GK_OK);
            ok &= gk_twoscale_accept(&w) == GK_OK && gk_twoscale_accept(&s) == GK_OK;
        }
        CHECK(ok);
        CHECK(fields_same(&w, &s));
        CHECK(w.stats.migrated > 0); /* the points did move */
        CHECK(w.stats.bytes_in > 0 && w.stats.collectives > 0);
        if (rank == 0)
            printf("    %s: %lld point moves, %d -> %d points on rank 0, %lld bytes in, %lld out\n",
                   mode ? "eq 8 + reuse" : "eq 9", w.stats.migrated, n0, w.nlocal, w.stats.bytes_in,
                   w.stats.bytes_out);
        gk_twoscale_destroy(&w), gk_twoscale_destroy(&s);
    }
}

/* a point of the other rank fails: every rank gets its code and message, every other point's result */
TEST(a_failed_point_on_another_rank_is_reported_everywhere) {
    gk_twoscale w, s;
    double dH[9 * NP];
    int p1;
    CHECK(make_set(&w, MPI_COMM_WORLD, GK_TWOSCALE_TANGENT_HOMOG, 0) == GK_OK);
    CHECK(make_set(&s, MPI_COMM_SELF, GK_TWOSCALE_TANGENT_HOMOG, 0) == GK_OK);
    for (p1 = NP - 1; p1 > 0 && w.owner[p1] != 1; --p1) continue;
    CHECK(w.owner[p1] == 1);
    step_dH(0, 5e-4, dH);
    dH[9 * p1 + 4] = -3.0;
    CHECK(run_both(&w, &s, dH, GK_ERR_STATE));
    CHECK_EQ_INT(gk_twoscale_points(&w)[p1].code, GK_ERR_SINGULAR);
    CHECK(strstr(gk_twoscale_point_error(&w, p1), "cell") != NULL);
    CHECK(strcmp(gk_twoscale_error(&w), gk_twoscale_error(&s)) == 0);
    CHECK(gk_twoscale_accept(&w) == GK_OK && gk_twoscale_accept(&s) == GK_OK);
    CHECK(fields_same(&w, &s));
    dH[9 * p1 + 1] = NAN; /* rank 0's dH is refused on every rank */
    CHECK(gk_twoscale_run(&w, rank == 0 ? dH : NULL, NULL, NULL, NULL) == GK_ERR_NAN);
    gk_twoscale_destroy(&w), gk_twoscale_destroy(&s);
}

/* a checkpoint written by 2 ranks goes on in 1, one written by 1 in 2: the same bits; a truncated one
 * is refused on every rank and changes nothing */
TEST(checkpoints_move_between_rank_counts) {
    gk_twoscale w, s, w2, s2;
    double dH[9 * NP];
    void *b = NULL;
    size_t nb = 0;
    int k, ok = 1;
    CHECK(make_set(&w, MPI_COMM_WORLD, GK_TWOSCALE_TANGENT_HOMOG, 0.3) == GK_OK);
    CHECK(make_set(&s, MPI_COMM_SELF, GK_TWOSCALE_TANGENT_HOMOG, 0.3) == GK_OK);
    for (k = 0; k < 2; ++k) {
        step_dH(k, 5e-4, dH);
        ok &= run_both(&w, &s, dH, GK_OK);
        ok &= gk_twoscale_accept(&w) == GK_OK && gk_twoscale_accept(&s) == GK_OK;
    }
    CHECK(ok);
    CHECK(gk_twoscale_save(&w, BUILD "/tests/t_tsm_w.bin", "w", 1) == GK_OK);
    if (rank == 0) CHECK(gk_twoscale_save(&s, BUILD "/tests/t_tsm_s.bin", "s", 1) == GK_OK);
    MPI_Barrier(MPI_COMM_WORLD);
    CHECK(make_set(&w2, MPI_COMM_WORLD, GK_TWOSCALE_TANGENT_HOMOG, 0.3) == GK_OK);
    CHECK(make_set(&s2, MPI_COMM_SELF, GK_TWOSCALE_TANGENT_HOMOG, 0.3) == GK_OK);
    CHECK(gk_twoscale_load(&w2, BUILD "/tests/t_tsm_s.bin", &b, &nb) == GK_OK && nb == 1 &&
          ((char *)b)[0] == 's');
    gk_twoscale_free_block(&w2, b);
    CHECK(gk_twoscale_load(&s2, BUILD "/tests/t_tsm_w.bin", &b, &nb) == GK_OK && nb == 1 &&
          ((char *)b)[0] == 'w');
    gk_twoscale_free_block(&s2, b);
    if (rank == 0) { /* a truncated copy */
        FILE *in = fopen(BUILD "/tests/t_tsm_w.bin", "rb"), *out = fopen(BUILD "/tests/t_tsm_bad.bin", "wb");
        char buf[1000];
        size_t n = in ? fread(buf, 1, sizeof buf, in) : 0;
        if (out) fwrite(buf, 1, n, out), fclose(out);
        if (in) fclose(in);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    b = NULL;
    CHECK(gk_twoscale_load(&w, BUILD "/tests/t_tsm_bad.bin", &b, &nb) == GK_ERR_FORMAT && b == NULL);
    CHECK(strstr(gk_twoscale_error(&w), "t_tsm_bad.bin") != NULL);
    for (k = 2; k < 4; ++k) { /* each set runs once per step: a run moves its tangent-reuse reference */
        double sg[4][9 * NP], Dg[4][16 * NP];
        gk_twoscale *all4[4];
        int m;
        all4[0] = &w, all4[1] = &s, all4[2] = &w2, all4[3] = &s2;
        step_dH(k, 5e-4, dH);
        for (m = 0; m < 4; ++m) {
            ok &= gk_twoscale_run(all4[m], rank == 0 || all4[m]->nranks == 1 ? dH : NULL, NULL, sg[m],
                                  Dg[m]) == GK_OK;
            ok &= same(sg[m], sg[0], 9 * NP) && same(Dg[m], Dg[0], 16 * NP);
            ok &=
                !memcmp(gk_twoscale_points(all4[m]), gk_twoscale_points(&w), NP * sizeof(gk_twoscale_point));
        }
        for (m = 0; m < 4; ++m) ok &= gk_twoscale_accept(all4[m]) == GK_OK;
    }
    CHECK(ok);
    CHECK(fields_same(&w2, &s) && fields_same(&w, &s2));
    gk_twoscale_destroy(&w), gk_twoscale_destroy(&s), gk_twoscale_destroy(&w2), gk_twoscale_destroy(&s2);
}

/* GK_TWOSCALE_BALANCE_RUN: points move before every run on the previous run's costs, also between
 * the iterations of a step (the trial states of the pending run dropped, then recomputed): 2 ranks =
 * 1 rank bit for bit through iterations, a reject, a refused run (which must move nothing: the
 * pending trial is then accepted) and eq 8 with tangent reuse (the reference moves with its point) */
TEST(balance_before_every_run) {
    int mode;
    for (mode = 0; mode < 2; ++mode) {
        gk_twoscale w, s;
        double dH[9 * NP];
        int k, it, ok = 1, ok_refused = 1, moves_in_step = 0;
        long long bal0, mig0;
        gk_twoscale_tangent_kind t = mode ? GK_TWOSCALE_TANGENT_PERTURBATION : GK_TWOSCALE_TANGENT_HOMOG;
        CHECK(make_set_b(&w, MPI_COMM_WORLD, t, mode ? 0.5 : 0, GK_TWOSCALE_BALANCE_RUN) == GK_OK);
        CHECK(make_set_b(&s, MPI_COMM_SELF, t, mode ? 0.5 : 0, GK_TWOSCALE_BALANCE_RUN) == GK_OK);
        for (k = 0; k < 3; ++k) {
            for (it = 0; it < 3; ++it) { /* the iterations of a step: the heavy half alternates */
                int p, c;
                step_dH(k + 2 * it, 5e-4 * (1.0 + 0.1 * it), dH);
                if (it % 2) /* the second half heavy: the first half's dH / 3, the second's x 3 */
                    for (p = 0; p < NP; ++p)
                        for (c = 0; c < 9; ++c) dH[9 * p + c] *= p < NP / 2 ? 1.0 / 3.0 : 3.0;
                bal0 = w.stats.balances;
                ok &= run_both(&w, &s, dH, GK_OK);
                if (it > 0) moves_in_step += w.stats.balances > bal0;
            }
            if (k == 1) { /* a reject: the step again from the accepted states, points moving */
                gk_twoscale_reject(&w), gk_twoscale_reject(&s);
                step_dH(k, 4e-4, dH);
                ok &= run_both(&w, &s, dH, GK_OK);
            }
            if (k == 2) { /* a refused run (rank 0's dH has a NaN) moves nothing; the pending trial stays */
                double bad[9 * NP];
                memcpy(bad, dH, sizeof bad);
                bad[9 * 3 + 4] = NAN;
                bal0 = w.stats.balances, mig0 = w.stats.migrated;
                ok_refused &= gk_twoscale_run(&w, rank == 0 ? bad : NULL, NULL, NULL, NULL) == GK_ERR_NAN;
                ok_refused &= w.stats.balances == bal0 && w.stats.migrated == mig0;
            }
            ok &= gk_twoscale_accept(&w) == GK_OK && gk_twoscale_accept(&s) == GK_OK;
        }
        CHECK(ok);
        CHECK(ok_refused);
        CHECK(fields_same(&w, &s));
        CHECK(moves_in_step > 0); /* points moved between the iterations of a step */
        CHECK(w.stats.migrated > 0 && w.stats.migrated_bytes > 0);
        if (rank == 0)
            printf("    %s: %lld rebalances (%d within a step), %lld point moves, %lld bytes moved\n",
                   mode ? "eq 8 + reuse" : "eq 9", w.stats.balances, moves_in_step, w.stats.migrated,
                   w.stats.migrated_bytes);
        gk_twoscale_destroy(&w), gk_twoscale_destroy(&s);
    }
}

/* the checks of every rank count */
static void run_all(const char *name, void (*fn)(void)) {
    int mine, all;
    gk__t_checks_failed = 0;
    fn();
    mine = gk__t_checks_failed;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    if (all)
        ++gk__t_failed;
    else
        ++gk__t_passed;
    if (rank == 0) printf("%s %s\n", all ? "FAIL" : "ok  ", name), fflush(stdout);
}

int main(int argc, char **argv) {
    gk_err e;
    int size, have, all, status;
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    gk_test_init(argc, argv);
    (void)gk__t_run; /* its per-rank verdicts would not add up: run_all instead */
    have = gk_packing_read("bench/data/tradeoff/rve100.txt", &pk100, NULL, &e) == GK_OK &&
           gk_packing_read("bench/data/tradeoff/rve200.txt", &pk200, NULL, &e) == GK_OK;
    MPI_Allreduce(&have, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (size != 2 || !all) {
        if (rank == 0)
            printf("FAIL mpi_twoscale needs 2 ranks (mpirun -np 2) and the packings\n# mpi_twoscale: 0 "
                   "passed, 1 failed\n");
        MPI_Finalize();
        return 1;
    }
    run_all("two_ranks_equal_one_rank", two_ranks_equal_one_rank);
    run_all("a_failed_point_on_another_rank_is_reported_everywhere",
            a_failed_point_on_another_rank_is_reported_everywhere);
    run_all("checkpoints_move_between_rank_counts", checkpoints_move_between_rank_counts);
    run_all("balance_before_every_run", balance_before_every_run);
    gk_packing_free(&pk100), gk_packing_free(&pk200);
    status = gk__t_failed ? 1 : 0;
    if (rank == 0) status = gk_test_done();
    MPI_Finalize();
    return status;
}
