/* mpirun_femdem.c - the MPI build of femdem_biaxial (make mpi: build/femdem_biaxial_mpi, the RVEs spread
 * over the ranks by gk_twoscale.h) gives the threaded build's results, bit for bit. Run by `make test`
 * when mpicc is installed, through a script that sets GK_MPIRUN (mpirun and its flags). */
#define GK_TEST_DRIVERS
#include "gk_test.h"

/* two CSV files equal in every column but the seconds (column 7 of biaxial.csv), with `rows` data rows */
static int same_but_seconds(const char *a, const char *b, int rows) {
    FILE *fa = fopen(a, "r"), *fb = fopen(b, "r");
    char la[4096], lb[4096];
    int n = 0, same = fa && fb;
    while (same) {
        char *pa = fgets(la, sizeof la, fa), *pb = fgets(lb, sizeof lb, fb), *ca, *cb;
        int k;
        if (!pa || !pb) {
            same = !pa && !pb;
            break;
        }
        ca = la, cb = lb;
        for (k = 0; k < 6 && ca && cb; ++k) ca = strchr(ca + 1, ','), cb = strchr(cb + 1, ',');
        if (!ca || !cb || strncmp(la, lb, (size_t)(ca - la)) || (ca - la) != (cb - lb)) same = 0;
        ca = ca ? strchr(ca + 1, ',') : NULL, cb = cb ? strchr(cb + 1, ',') : NULL; /* skip the seconds */
        if (!ca || !cb || strcmp(ca, cb)) same = 0;
        ++n;
    }
    if (fa) fclose(fa);
    if (fb) fclose(fb);
    return same && n == rows + 1;
}

/* make run's mesh, 4 x 8 Q8, 128 RVEs, 10 steps, on 2 ranks x 1 thread and on 1 process x 2 threads;
 * then each run's checkpoint continued one step by the other build (the MPI one rebalancing before
 * every Newton iteration, --balance run): the same rows again */
TEST(femdem_biaxial_two_ranks_equal_two_threads) {
    const char *mpirun = getenv("GK_MPIRUN"), *args = "--nx 4 --ny 8 --element q8 --steps 10";
    char cmd[1024];
    if (!mpirun) {
        printf("    GK_MPIRUN is not set (make test sets it when mpicc is installed)\n");
        CHECK(mpirun != NULL);
        return;
    }
    system("rm -rf " BUILD "/tests/t_fmT " BUILD "/tests/t_fmM");
    snprintf(cmd, sizeof cmd,
             BUILD "/femdem_biaxial %s --threads 2 --out " BUILD "/tests/t_fmT > " BUILD "/tests/t_fmT.out 2>&1",
             args);
    CHECK(system(cmd) == 0);
    snprintf(cmd, sizeof cmd,
             "%s -np 2 " BUILD "/femdem_biaxial_mpi %s --threads 1 --out " BUILD "/tests/t_fmM > "
             BUILD "/tests/t_fmM.out 2>&1",
             mpirun, args);
    CHECK(system(cmd) == 0);
    CHECK(same_but_seconds(BUILD "/tests/t_fmT/biaxial.csv", BUILD "/tests/t_fmM/biaxial.csv",
                           11)); /* rows 0-10 */
    CHECK(gk_test_file_has(BUILD "/tests/t_fmM.out", "RESULT peak_sigma_yy="));
    CHECK(gk_test_result(BUILD "/tests/t_fmM.out", "peak_sigma_yy") ==
          gk_test_result(BUILD "/tests/t_fmT.out", "peak_sigma_yy"));
    CHECK(gk_test_file_has(BUILD "/tests/t_fmM.out", "MPI ranks=2 ")); /* the traffic line of the MPI build */
    /* rank 0 alone prints: one RESULT line, the last (README: a driver ends with it) */
    {
        FILE *fp = fopen(BUILD "/tests/t_fmM.out", "r");
        char line[4096];
        int n = 0, last = 0;
        while (fp && fgets(line, sizeof line, fp)) n += last = !strncmp(line, "RESULT ", 7);
        if (fp) fclose(fp);
        CHECK_EQ_INT(n, 1);
        CHECK(last);
    }
    /* the checkpoint is the same file for any rank count: each build goes on from the other's */
    snprintf(cmd, sizeof cmd,
             BUILD "/femdem_biaxial --nx 4 --ny 8 --element q8 --steps 11 --threads 2 --restart "
             BUILD "/tests/t_fmM --out " BUILD "/tests/t_fmMT "
             "> " BUILD "/tests/t_fmMT.out 2>&1");
    CHECK(system(cmd) == 0);
    snprintf(cmd, sizeof cmd,
             "%s -np 2 " BUILD "/femdem_biaxial_mpi --nx 4 --ny 8 --element q8 --steps 11 --threads 1 --restart "
             BUILD "/tests/t_fmT --balance run --out " BUILD "/tests/t_fmTM > " BUILD "/tests/t_fmTM.out 2>&1",
             mpirun);
    CHECK(system(cmd) == 0);
    CHECK(same_but_seconds(BUILD "/tests/t_fmMT/biaxial.csv", BUILD "/tests/t_fmTM/biaxial.csv", 12));
    CHECK(gk_test_file_has(BUILD "/tests/t_fmTM.out", "balance=run"));
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(femdem_biaxial_two_ranks_equal_two_threads);
    return gk_test_done();
}
