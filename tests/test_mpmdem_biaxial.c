/* test_mpmdem_biaxial.c - smoke tests of examples/mpmdem_biaxial.c (the
 * MPMxDEM biaxial test of seed 003): it runs, writes its documented outputs,
 * starts in equilibrium, loads the specimen, does not depend on the thread
 * count, restarts to the identical result, and refuses bad arguments. Needs
 * build/mpmdem_biaxial (`make test` builds examples first). */
#define GK_TEST_DRIVERS
#include "gk_test.h"
#include <stdlib.h>

/* a 2 x 4 cell specimen (8 RVEs): tiny but the whole path */
#define BX "build/mpmdem_biaxial --nx 2 --ny 4 --strain 0.002 --every 0.0005 --quiet "

static int read_rows(const char *path, double rows[][8], int max) {
    FILE *fp = fopen(path, "r");
    char line[1024];
    int n = 0;
    if (!fp) return -1;
    if (!fgets(line, sizeof line, fp)) n = -1;
    while (n >= 0 && n < max && fgets(line, sizeof line, fp)) {
        double *r = rows[n];
        if (sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &r[0], &r[1], &r[2], &r[3], &r[4], &r[5], &r[6],
                   &r[7]) != 8)
            break;
        ++n;
    }
    fclose(fp);
    return n;
}

/* outputs and physics: sigma_yy starts at the confining pressure (the RVEs
 * are consolidated to it: initial equilibrium, no jump) and rises with the
 * axial strain; the top and base reactions agree (quasi-static: no net
 * inertia force, the specimen's momentum balance); compression shrinks the
 * specimen at first (eps_v > 0, the dense packing's initial contraction). */
TEST(biaxial_runs_and_loads) {
    double r[16][8];
    int n, k;
    CHECK(system(BX "--threads 2 --out build/t_mpmbx > build/t_mpmbx.out 2>&1") == 0);
    CHECK(gk_test_file_has(
        "build/t_mpmbx/biaxial.csv",
        "time,eps_axial,sigma_yy,sigma_yy_base,eps_v,kinetic_energy,dem_steps_per_point,seconds"));
    n = read_rows("build/t_mpmbx/biaxial.csv", r, 16);
    CHECK_EQ_INT(n, 4);
    if (n != 4) return;
    for (k = 0; k < n; ++k) {
        CHECK_NEAR(r[k][1], 0.0005 * (k + 1), 1e-5);
        CHECK_REL(r[k][2], r[k][3], 0.03); /* top vs base reaction */
    }
    CHECK(r[0][2] > 0.95e5 && r[0][2] < 1.2e5);
    for (k = 1; k < n; ++k) CHECK(r[k][2] > r[k - 1][2]);
    CHECK(r[n - 1][4] > 0.0);
    CHECK(gk_test_file_has("build/t_mpmbx/biaxial_stress.svg", "<svg"));
    CHECK(gk_test_file_has("build/t_mpmbx/rotation_end.svg", "<svg"));
    CHECK(gk_test_file_has("build/t_mpmbx/points_000000.vtk", "SCALARS eps_q"));
    CHECK_NEAR(gk_test_result("build/t_mpmbx.out", "n_rves"), 8, 0);
    CHECK_REL(gk_test_result("build/t_mpmbx.out", "peak_sigma_yy"), r[n - 1][2],
              1e-5); /* printed with 6 digits */
}

/* RVEs run in parallel: one thread gives the same curve to the last digit */
TEST(biaxial_thread_independent) {
    CHECK(system(BX "--threads 1 --out build/t_mpmbx1 > build/t_mpmbx1.out 2>&1") == 0);
    CHECK(system("cmp -s build/t_mpmbx1/points_000000.vtk build/t_mpmbx/points_000000.vtk") == 0);
    CHECK(gk_test_result("build/t_mpmbx1.out", "peak_sigma_yy") ==
          gk_test_result("build/t_mpmbx.out", "peak_sigma_yy"));
    CHECK(system("cut -d, -f1-7 build/t_mpmbx1/biaxial.csv > build/t_mpmbx1.c && "
                 "cut -d, -f1-7 build/t_mpmbx/biaxial.csv > build/t_mpmbx2.c && "
                 "cmp -s build/t_mpmbx1.c build/t_mpmbx2.c") == 0);
}

/* a checkpoint half-way, then --restart: the same final state (every point
 * array and RVE state is in the checkpoint) */
TEST(biaxial_restart_identical) {
    int rc = system(
        "build/mpmdem_biaxial --nx 2 --ny 4 --strain 0.001 --every 0.0005 --quiet --out build/t_mpmbx_a "
        "> build/t_mpmbx_a.out 2>&1 && " BX
        "--restart build/t_mpmbx_a --out build/t_mpmbx_b > build/t_mpmbx_b.out 2>&1");
    CHECK(rc == 0);
    CHECK(gk_test_result("build/t_mpmbx_b.out", "peak_sigma_yy") ==
          gk_test_result("build/t_mpmbx.out", "peak_sigma_yy"));
    CHECK(system("cut -d, -f1-7 build/t_mpmbx_b/biaxial.csv > build/t_mpmbx_b.c && "
                 "cmp -s build/t_mpmbx_b.c build/t_mpmbx2.c") == 0);
}

/* bad input: a message and a non-zero exit, nothing run */
TEST(biaxial_bad_arguments) {
    CHECK(system("build/mpmdem_biaxial --nx 0 > build/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has("build/t_mpmbx_bad.out", "out of range"));
    CHECK(system("build/mpmdem_biaxial --nx 3 --ny 4 > build/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has("build/t_mpmbx_bad.out", "square"));
    CHECK(system("build/mpmdem_biaxial --alpha 2 > build/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has("build/t_mpmbx_bad.out", "--alpha"));
    CHECK(system("build/mpmdem_biaxial --packing /nonexistent > build/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has("build/t_mpmbx_bad.out", "nonexistent"));
    CHECK(system("build/mpmdem_biaxial --restart /nonexistent --nx 2 --ny 4 > build/t_mpmbx_bad.out 2>&1") !=
          0);
    CHECK(gk_test_file_has("build/t_mpmbx_bad.out", "cannot open"));
    CHECK(system("build/mpmdem_biaxial --help > build/t_mpmbx_bad.out 2>&1") == 0);
    CHECK(gk_test_file_has("build/t_mpmbx_bad.out", "--dem-strain"));
    /* the DEM-rule flags of mpmdem.h are taken (they were listed in --help but refused), bad ones not */
    CHECK(system("build/mpmdem_biaxial --dem-rule foo > build/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has("build/t_mpmbx_bad.out", "use adaptive or strain"));
    CHECK(system("build/mpmdem_biaxial --dem-inertial -1 > build/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has("build/t_mpmbx_bad.out", "--dem-inertial"));
    CHECK(system(BX "--strain 0.0005 --dem-rule strain --dem-strain 2e-5 --out build/t_mpmbx_rule "
                    "> build/t_mpmbx_rule.out 2>&1") == 0);
    CHECK(gk_test_file_has("build/t_mpmbx_rule.out", "DEM steps per MPM step: <= 2e-05 strain per DEM step"));
    CHECK(system(BX "--strain 0.0005 --dem-inertial 1e-3 --dem-unbalanced 1e-2 --out build/t_mpmbx_rule "
                    "> build/t_mpmbx_rule.out 2>&1") == 0);
    CHECK(gk_test_file_has("build/t_mpmbx_rule.out",
                           "adaptive, I <= 0.001 then relaxation to an unbalanced force "
                           "ratio < 0.01"));
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(biaxial_runs_and_loads);
    RUN(biaxial_thread_independent);
    RUN(biaxial_restart_identical);
    RUN(biaxial_bad_arguments);
    return gk_test_done();
}
