/* mpirun_mpmdem.c - the MPI builds of the MPMxDEM drivers (make mpi: build/mpmdem_*_mpi, the RVEs of
 * the material points spread over the ranks by gk_twoscale.h) give the OpenMP builds' results, bit for
 * bit: 2 ranks x 1 thread against 1 process x 2 threads, every CSV column but the seconds, the VTK of
 * the points (every field, the stress of every point), the RESULT line; and a checkpoint of either
 * build continues in the other to the same rows. Run by `make test` when mpicc is installed, through a
 * script that sets GK_MPIRUN (mpirun and its flags). */
#define GK_TEST_DRIVERS
#include "gk_test.h"

#define BX "--nx 2 --ny 4 --every 0.0005 --quiet "
#define FT                                                                                                 \
    "--width 2 --depth 1.5 --nx 4 --ny 3 --B 1.5 --velocity 0.25 --ramp 0.01 --every 0.005 --smooth 0.01 " \
    "--phi-deg 30 --final 0.01 --quiet "
#define CL "--nx 4 --every 0.01 --snapshots 0.02 --t-end 0.03 --quiet "

/* runs `build/DRIVER ARGS --threads 2 --out build/tests/t_mpiT_NAME` and the MPI build on 2 ranks into
 * build/tests/t_mpiM_NAME; 1 if both succeed */
static int both(const char *mpirun, const char *driver, const char *name, const char *args) {
    char cmd[1024];
    int ok;
    snprintf(cmd, sizeof cmd,
             "rm -rf " BUILD "/tests/t_mpiT_%s " BUILD "/tests/t_mpiM_%s && " BUILD
             "/%s %s --threads 2 --out " BUILD "/tests/t_mpiT_%s "
             "> " BUILD "/tests/t_mpiT_%s.out 2>&1",
             name, name, driver, args, name, name);
    ok = system(cmd) == 0;
    snprintf(cmd, sizeof cmd,
             "%s -np 2 " BUILD "/%s_mpi %s --threads 1 --out " BUILD "/tests/t_mpiM_%s > " BUILD
             "/tests/t_mpiM_%s.out 2>&1",
             mpirun, driver, args, name, name);
    return ok && system(cmd) == 0;
}

/* the CSV of the two builds of test `name` equal in their first ncol columns (all but the seconds) */
static int same_csv(const char *name, const char *csv, int ncol) {
    char cmd[512];
    snprintf(cmd, sizeof cmd,
             "cut -d, -f1-%d " BUILD "/tests/t_mpiT_%s/%s > " BUILD
             "/tests/t_mpiT_%s.c && cut -d, -f1-%d " BUILD "/tests/t_mpiM_%s/%s "
             "> " BUILD "/tests/t_mpiM_%s.c && cmp -s " BUILD "/tests/t_mpiT_%s.c " BUILD
             "/tests/t_mpiM_%s.c && test -s " BUILD "/tests/t_mpiT_%s.c",
             ncol, name, csv, name, ncol, name, csv, name, name, name, name);
    return system(cmd) == 0;
}

static int count_lines(const char *path, const char *start) {
    FILE *fp = fopen(path, "r");
    char line[4096];
    int n = 0;
    while (fp && fgets(line, sizeof line, fp)) n += !strncmp(line, start, strlen(start));
    if (fp) fclose(fp);
    return n;
}

static const char *mpirun(void) {
    const char *m = getenv("GK_MPIRUN");
    if (!m) printf("    GK_MPIRUN is not set (make test sets it when mpicc is installed)\n");
    return m;
}

TEST(biaxial_two_ranks_equal_two_threads) {
    const char *m = mpirun();
    CHECK(m != NULL);
    if (!m) return;
    CHECK(both(m, "mpmdem_biaxial", "bx", BX "--strain 0.002"));
    CHECK(same_csv("bx", "biaxial.csv", 7));
    CHECK(system("cmp -s " BUILD "/tests/t_mpiT_bx/points_ABC.csv " BUILD
                 "/tests/t_mpiM_bx/points_ABC.csv") == 0);
    CHECK(system("cmp -s " BUILD "/tests/t_mpiT_bx/points_000000.vtk " BUILD
                 "/tests/t_mpiM_bx/points_000000.vtk && "
                 "cmp -s " BUILD "/tests/t_mpiT_bx/points_000278.vtk " BUILD
                 "/tests/t_mpiM_bx/points_000278.vtk") == 0);
    CHECK(gk_test_result(BUILD "/tests/t_mpiM_bx.out", "peak_sigma_yy") ==
          gk_test_result(BUILD "/tests/t_mpiT_bx.out", "peak_sigma_yy"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpiM_bx.out", "MPI ranks=2 threads=1 "));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpiT_bx.out", "MPI ranks=1 threads=2 bytes_sent_per_step=0 "));
    CHECK_EQ_INT(count_lines(BUILD "/tests/t_mpiM_bx.out", "RESULT "), 1); /* rank 0 alone speaks */
}

/* the checkpoint is one file whatever the rank count: each build goes on from the other's half-way
 * checkpoint to the rows of the uninterrupted runs */
TEST(biaxial_restart_across_builds) {
    const char *m = mpirun();
    char cmd[1024];
    CHECK(m != NULL);
    if (!m) return;
    CHECK(both(m, "mpmdem_biaxial", "bxh", BX "--strain 0.001"));
    snprintf(cmd, sizeof cmd,
             BUILD "/mpmdem_biaxial " BX "--strain 0.002 --threads 2 --restart " BUILD
                   "/tests/t_mpiM_bxh --out " BUILD "/tests/t_mpiT_bxr "
                   "> " BUILD "/tests/t_mpiT_bxr.out 2>&1 && %s -np 2 " BUILD "/mpmdem_biaxial_mpi " BX
                   "--strain 0.002 --threads 1 --restart " BUILD "/tests/t_mpiT_bxh --out " BUILD
                   "/tests/t_mpiM_bxr > " BUILD "/tests/t_mpiM_bxr.out 2>&1",
             m);
    CHECK(system(cmd) == 0);
    CHECK(system("cut -d, -f1-7 " BUILD "/tests/t_mpiT_bxr/biaxial.csv | cmp -s - " BUILD
                 "/tests/t_mpiT_bx.c && "
                 "cut -d, -f1-7 " BUILD "/tests/t_mpiM_bxr/biaxial.csv | cmp -s - " BUILD
                 "/tests/t_mpiT_bx.c") == 0);
}

/* the footing (one prototype, edge loads, a rigid footing) and the collapse (one prototype per
 * pressure level, gravity, friction base) */
TEST(footing_and_collapse_two_ranks_equal_two_threads) {
    const char *m = mpirun();
    CHECK(m != NULL);
    if (!m) return;
    CHECK(both(m, "mpmdem_footing", "ft", FT));
    CHECK(same_csv("ft", "footing.csv", 8));
    CHECK(gk_test_result(BUILD "/tests/t_mpiM_ft.out", "q_ult") ==
          gk_test_result(BUILD "/tests/t_mpiT_ft.out", "q_ult"));
    CHECK(both(m, "mpmdem_collapse", "cl", CL));
    CHECK(same_csv("cl", "collapse.csv", 14));
    CHECK(system("cmp -s " BUILD "/tests/t_mpiT_cl/points_000000.vtk " BUILD
                 "/tests/t_mpiM_cl/points_000000.vtk") == 0);
    CHECK(gk_test_result(BUILD "/tests/t_mpiM_cl.out", "dstar") ==
          gk_test_result(BUILD "/tests/t_mpiT_cl.out", "dstar"));
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(biaxial_two_ranks_equal_two_threads);
    RUN(biaxial_restart_across_builds);
    RUN(footing_and_collapse_two_ranks_equal_two_threads);
    return gk_test_done();
}
