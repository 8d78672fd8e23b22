/* test_mpmdem_footing.c - smoke tests of examples/mpmdem_footing.c (the
 * MPMxDEM rigid footing of Liang & Zhao 2019 Sec 3.3): it runs, writes its documented
 * outputs, starts in equilibrium (footing pressure = surcharge at d = 0),
 * loads the footing, measures a sane friction angle of the RVE, does not
 * depend on the thread count, restarts to the identical result, and refuses
 * bad arguments. A 4 x 3 cell half model (12 RVEs) with a 1.5 m footing
 * (b = 1.5 cells): a few seconds. Needs build/mpmdem_footing (`make test`
 * builds examples first). */
#define GK_TEST_DRIVERS
#include "gk_test.h"
#include <stdlib.h>

#define FT                                                                                                  \
    "build/mpmdem_footing --width 2 --depth 1.5 --nx 4 --ny 3 --B 1.5 --velocity 0.25 --ramp 0.01 --every " \
    "0.005 --smooth 0.01 --quiet "

#define NCOL 9
static int read_rows(const char *path, double rows[][NCOL], int max) {
    FILE *fp = fopen(path, "r");
    char line[1024];
    int n = 0;
    if (!fp) return -1;
    if (!fgets(line, sizeof line, fp)) n = -1;
    while (n >= 0 && n < max && fgets(line, sizeof line, fp)) {
        double *r = rows[n];
        if (sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &r[0], &r[1], &r[2], &r[3], &r[4], &r[5],
                   &r[6], &r[7], &r[8]) != NCOL)
            break;
        ++n;
    }
    fclose(fp);
    return n;
}

/* outputs and physics: the CSV has a row at d ~ 0 and one every 0.005 B;
 * at d = 0 the footing carries the surcharge (the RVEs are consolidated to
 * q_s: initial equilibrium); then q grows with the settlement; the measured
 * friction angle of the dense Table 2 RVE is that of a dense granular
 * material; N_q analytic is eq 46 of the measured angle */
TEST(footing_runs_and_loads) {
    double r[16][NCOL], phi, nq, nqa, pi = 3.14159265358979323846, t;
    int n, k;
    CHECK(system(FT
                 "--final 0.02 --phi-pressures 20 --phi-strain 0.025 --threads 1 --out build/tests/t_mpmft "
                 "> build/tests/t_mpmft.out 2>&1") == 0);
    CHECK(
        gk_test_file_has("build/tests/t_mpmft/footing.csv",
                         "time,d,d_over_B,q,q_over_qs,load_half,kinetic_energy,dem_steps_per_point,seconds"));
    n = read_rows("build/tests/t_mpmft/footing.csv", r, 16);
    CHECK_EQ_INT(n, 5);
    if (n != 5) return;
    CHECK(r[0][2] < 1e-3);                               /* first row: d ~ 0 */
    CHECK(r[0][4] > 0.85 && r[0][4] < 1.15);             /* q = q_s there */
    CHECK_NEAR(r[0][3], r[0][5] / 0.75, 1e-6 * r[0][3]); /* q = load of the half model / b */
    for (k = 1; k < n; ++k) {
        CHECK(r[k][2] >= 0.005 * k - 1e-9 && r[k][2] < 0.005 * k + 5e-4); /* the first step past it */
        CHECK(r[k][3] > r[k - 1][3]); /* the load grows with the settlement at first */
    }
    CHECK(r[n - 1][4] > 5.0);
    phi = gk_test_result("build/tests/t_mpmft.out", "phi_deg");
    CHECK(phi > 25.0 && phi < 40.0);
    t = tan(pi / 4 + phi * pi / 360.0);
    nqa = gk_test_result("build/tests/t_mpmft.out", "Nq_analytic");
    CHECK_REL(nqa, t * t * exp(pi * tan(phi * pi / 180.0)), 2e-4);
    nq = gk_test_result("build/tests/t_mpmft.out", "Nq");
    CHECK(nq > 1.0 && nq < 100.0);
    CHECK_NEAR(gk_test_result("build/tests/t_mpmft.out", "n_rves"), 12, 0);
    CHECK_NEAR(gk_test_result("build/tests/t_mpmft.out", "ultimate_reached"), 0, 0); /* 0.02 B: too early */
    CHECK(gk_test_file_has("build/tests/t_mpmft.out", "ultimate load NOT reached"));
    CHECK(gk_test_result("build/tests/t_mpmft.out", "mpm_steps") > 10);
    CHECK(gk_test_result("build/tests/t_mpmft.out", "seconds_per_step_per_1000_rves") > 0);
    CHECK(gk_test_file_has("build/tests/t_mpmft/footing_load.svg", "<svg"));
    CHECK(gk_test_file_has("build/tests/t_mpmft/rve_mohr.svg", "<svg"));
    CHECK(gk_test_file_has("build/tests/t_mpmft/rve_biaxial.svg", "<svg"));
    CHECK(gk_test_file_has("build/tests/t_mpmft/eps_q_end.svg", "<svg"));
    CHECK(gk_test_file_has("build/tests/t_mpmft/displacement_end.svg", "<svg"));
    CHECK(gk_test_file_has("build/tests/t_mpmft/points_000000.vtk", "SCALARS eps_q"));
}

/* the ultimate-load rule on a curve that peaks: a longer run of the same
 * model reaches a peak (this coarse footing at d/B ~ 0.04) and reports it */
TEST(footing_ultimate_found) {
    double du, nq, qu;
    CHECK(system(FT "--final 0.08 --smooth 0.02 --phi-deg 30 --threads 1 --out build/tests/t_mpmft_u "
                    "> build/tests/t_mpmft_u.out 2>&1") == 0);
    CHECK_NEAR(gk_test_result("build/tests/t_mpmft_u.out", "ultimate_reached"), 1, 0);
    du = gk_test_result("build/tests/t_mpmft_u.out", "d_ult_over_B");
    nq = gk_test_result("build/tests/t_mpmft_u.out", "Nq");
    qu = gk_test_result("build/tests/t_mpmft_u.out", "q_ult");
    CHECK(du > 0.0 && du < 0.08 - 0.02);
    CHECK_REL(nq, qu / 2e4, 1e-4);
    CHECK(nq > 3.0 && nq < 60.0);
}

/* RVEs and the MPM run in parallel: one and two threads give the same curve */
TEST(footing_thread_independent) {
    /* passive waiting: spinning OpenMP threads crawl on a machine busy with other jobs */
    CHECK(system("OMP_WAIT_POLICY=passive " FT
                 "--final 0.02 --phi-deg 30 --threads 2 --out build/tests/t_mpmft2 "
                 "> build/tests/t_mpmft2.out 2>&1") == 0);
    CHECK(system(FT "--final 0.02 --phi-deg 30 --threads 1 --out build/tests/t_mpmft1 > "
                    "build/tests/t_mpmft1.out 2>&1") == 0);
    CHECK(gk_test_result("build/tests/t_mpmft1.out", "Nq") ==
          gk_test_result("build/tests/t_mpmft2.out", "Nq"));
    CHECK(system("cut -d, -f1-8 build/tests/t_mpmft1/footing.csv > build/tests/t_mpmft1.c && "
                 "cut -d, -f1-8 build/tests/t_mpmft2/footing.csv > build/tests/t_mpmft2.c && "
                 "cmp -s build/tests/t_mpmft1.c build/tests/t_mpmft2.c") == 0);
}

/* a checkpoint half-way, then --restart: the same curve to the last digit */
TEST(footing_restart_identical) {
    int rc = system(
        FT
        "--final 0.01 --phi-deg 30 --threads 1 --out build/tests/t_mpmft_a > build/tests/t_mpmft_a.out 2>&1 "
        "&& " FT
        "--final 0.02 --phi-deg 30 --threads 1 --restart build/tests/t_mpmft_a --out build/tests/t_mpmft_b "
        "> build/tests/t_mpmft_b.out 2>&1");
    CHECK(rc == 0);
    CHECK(gk_test_result("build/tests/t_mpmft_b.out", "Nq") ==
          gk_test_result("build/tests/t_mpmft1.out", "Nq"));
    CHECK(system("cut -d, -f1-8 build/tests/t_mpmft_b/footing.csv > build/tests/t_mpmft_b.c && "
                 "cmp -s build/tests/t_mpmft_b.c build/tests/t_mpmft1.c") == 0);
}

/* bad input: a message and a non-zero exit, nothing run */
TEST(footing_bad_arguments) {
    const char *o = " > build/tests/t_mpmft_bad.out 2>&1";
    char cmd[512];
#define BAD(args, msg)                                                                             \
    snprintf(cmd, sizeof cmd, "build/mpmdem_footing --out build/tests/t_mpmft_bad %s%s", args, o); \
    CHECK(system(cmd) != 0);                                                                       \
    CHECK(gk_test_file_has("build/tests/t_mpmft_bad.out", msg))
    BAD("--nx 0", "out of range");
    BAD("--nx 31 --ny 15", "square");
    BAD("--material wet", "dense, medium or soft");
    BAD("--phi-pressures 10,x", "--phi-pressures");
    BAD("--phi-deg 75", "--phi-deg");
    BAD("--B 0.3", "1.5 cells");
    BAD("--final 5", "out of range");
    BAD("--max-steps 2.5", "--max-steps");
    BAD("--velocity", "needs a value");
    BAD("--bogus 1", "unknown option");
    BAD("--alpha 2", "--alpha");
    /* bad input changes nothing: no output folder is made before the inputs are read */
    CHECK(system("rm -rf build/tests/t_mpmft_bad") == 0);
    BAD("--packing /nonexistent", "nonexistent");
    BAD("--phi-deg 30 --restart /nonexistent", "cannot open");
    CHECK(system("test -e build/tests/t_mpmft_bad") != 0);
    BAD("--phi-pressures 10,,20", "--phi-pressures");
    BAD("--phi-pressures 10,20,", "--phi-pressures");
    BAD("--every 0.5 --final 0.2", "--every 0.5 is out of range");
    BAD("--out build/tests/t_mpmft_bad.out", "is a file, not a folder");
#undef BAD
    CHECK(system("build/mpmdem_footing --help > build/tests/t_mpmft_bad.out 2>&1") == 0);
    CHECK(gk_test_file_has("build/tests/t_mpmft_bad.out", "--phi-pressures"));
    CHECK(gk_test_file_has("build/tests/t_mpmft_bad.out", "--paper"));
    CHECK(gk_test_file_has("build/tests/t_mpmft_bad.out", "--dem-rule"));
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(footing_runs_and_loads);
    RUN(footing_ultimate_found);
    RUN(footing_thread_independent);
    RUN(footing_restart_identical);
    RUN(footing_bad_arguments);
    return gk_test_done();
}
