/* test_mpmdem_pipe.c - smoke tests of examples/mpmdem_pipe.c (the MPMxDEM
 * pipe-soil interaction of Liang & Zhao 2019 Sec 3.4): it runs the two
 * stages, writes its documented outputs with finite values, the soil pushes
 * back on the penetrating pipe (V > 0, larger deeper), a checkpoint half-way
 * and --restart on 2 threads give the 1-thread run's rows to the last digit,
 * and bad arguments are refused without an output folder. A 3 x 1.25 m soil
 * of 12 x 5 cells (60 RVEs), the pipe (D = 4 cells) 0.1 m down and 0.05 m
 * left at 1 m/s: ~10 s. Needs build/mpmdem_pipe (`make test` builds
 * examples first). */
#define GK_TEST_DRIVERS
#include "gk_test.h"
#include <stdlib.h>

#define PT                                                                                                   \
    BUILD "/mpmdem_pipe --width 3 --nx 12 --ny 5 --penetration 0.1 --lateral 0.05 --v-down 1 --v-lateral 1 " \
          "--ramp 0.02 --every 0.02 --quiet "

#define NCOL 10
static int read_rows(const char *path, double rows[][NCOL], int max) {
    FILE *fp = fopen(path, "r");
    char line[1024];
    int n = 0;
    if (!fp) return -1;
    if (!fgets(line, sizeof line, fp)) n = -1;
    while (n >= 0 && n < max && fgets(line, sizeof line, fp)) {
        double *r = rows[n];
        if (sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &r[0], &r[1], &r[2], &r[3], &r[4], &r[5],
                   &r[6], &r[7], &r[8], &r[9]) != NCOL)
            break;
        ++n;
    }
    fclose(fp);
    return n;
}

/* the path (stage 1 down to 0.1 m, stage 2 left by 0.05 m, the pipe bottom
 * starting on the ground y = 1.25 m at x = 1.5 m), the columns, finite
 * values; during the penetration the soil's reaction V is positive and the
 * second half of the stage carries more than its first row (bearing grows
 * with depth: the N_gamma and N_q terms of a strip, and the pipe's contact
 * width grows as 2 sqrt(D d - d^2)); the lateral stage resists the motion
 * (mean H > 0) */
TEST(pipe_runs_both_stages) {
    double r[64][NCOL], vfirst = 0, vlate = 0, hl = 0;
    int n, k, nlate = 0, nl = 0, np = 0;
    CHECK(system("rm -rf " BUILD "/tests/t_pipe1 && " PT "--threads 1 --out " BUILD "/tests/t_pipe1 "
                 "> " BUILD "/tests/t_pipe1.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe1/pipe.csv",
                           "time,pipe_x,pipe_bottom_y,penetration,lateral,stage,H_kN_per_m,V_kN_per_m,"
                           "dem_steps_per_point,seconds"));
    n = read_rows(BUILD "/tests/t_pipe1/pipe.csv", r, 64);
    CHECK(n >= 8);
    if (n < 8) return;
    for (k = 0; k < n; ++k) {
        int j;
        for (j = 0; j < NCOL; ++j) CHECK(isfinite(r[k][j]));
        CHECK(r[k][5] == 1 || r[k][5] == 2);
        CHECK(r[k][8] >= 1); /* DEM steps per point */
        if (r[k][5] == 1) {
            CHECK(r[k][7] > 0);
            CHECK_NEAR(r[k][1], 1.5, 1e-12);
            CHECK_NEAR(r[k][2], 1.25 - r[k][3], 1e-5);
            if (np++ == 0) vfirst = r[k][7];
            if (r[k][3] > 0.05) vlate += r[k][7], ++nlate;
        } else {
            CHECK_NEAR(r[k][3], 0.1, 1e-9);
            CHECK_NEAR(r[k][1], 1.5 - r[k][4], 1e-5);
            hl += r[k][6], ++nl;
        }
    }
    CHECK(nlate > 0 && nl > 0);
    CHECK(vlate / nlate > vfirst);
    CHECK(hl / nl > 0);
    CHECK_NEAR(r[n - 1][4], 0.05, 1e-9); /* the whole path */
    CHECK(gk_test_result(BUILD "/tests/t_pipe1.out", "V_peak_kN") > 0);
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_pipe1.out", "penetration"), 0.1, 1e-9);
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_pipe1.out", "lateral"), 0.05, 1e-9);
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_pipe1.out", "n_rves"), 60, 0);
    CHECK(gk_test_result(BUILD "/tests/t_pipe1.out", "seconds_per_step_per_1000_rves") > 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe1/pipe_force.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe1/eps_q_pen.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe1/rotation_pen.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe1/eps_q_end.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe1/rotation_end.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe1/points_000000.vtk", "SCALARS eps_q"));
}

/* stopped after 100 steps on 2 threads, then --restart on 2 threads: the
 * rows of the uninterrupted 1-thread run to the last digit (restart and
 * thread count change nothing) */
TEST(pipe_restart_and_threads_identical) {
    int rc = system("rm -rf " BUILD "/tests/t_pipe_a " BUILD "/tests/t_pipe_b && OMP_WAIT_POLICY=passive " PT
                    "--threads 2 --max-steps 100 --out " BUILD "/tests/t_pipe_a > " BUILD
                    "/tests/t_pipe_a.out 2>&1 && "
                    "OMP_WAIT_POLICY=passive " PT "--threads 2 --restart " BUILD "/tests/t_pipe_a "
                    "--out " BUILD "/tests/t_pipe_b > " BUILD "/tests/t_pipe_b.out 2>&1");
    CHECK(rc == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe_a.out", "stopped before the end of the path"));
    CHECK(gk_test_result(BUILD "/tests/t_pipe_b.out", "V_peak_kN") ==
          gk_test_result(BUILD "/tests/t_pipe1.out", "V_peak_kN"));
    CHECK(system("cut -d, -f1-9 " BUILD "/tests/t_pipe_b/pipe.csv > " BUILD "/tests/t_pipe_b.c && "
                 "cut -d, -f1-9 " BUILD "/tests/t_pipe1/pipe.csv > " BUILD "/tests/t_pipe1.c && "
                 "cmp -s " BUILD "/tests/t_pipe_b.c " BUILD "/tests/t_pipe1.c") == 0);
}

/* bad input: a message and a non-zero exit, no output folder */
TEST(pipe_bad_arguments) {
    const char *o = " > " BUILD "/tests/t_pipe_bad.out 2>&1";
    char cmd[512];
    CHECK(system("rm -rf " BUILD "/tests/t_pipe_bad") == 0);
#define BAD(args, msg)                                                                              \
    snprintf(cmd, sizeof cmd, BUILD "/mpmdem_pipe --out " BUILD "/tests/t_pipe_bad %s%s", args, o); \
    CHECK(system(cmd) != 0);                                                                        \
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe_bad.out", msg))
    BAD("--nx 0", "out of range");
    BAD("--diameter 0.3", "less than 2 cells");
    BAD("--diameter 0", "--diameter");
    BAD("--penetration 2.4", "reaches the base");
    BAD("--lateral 2.6", "to the wall");
    BAD("--ramp 5", "--ramp");
    BAD("--contact glue", "stick, friction or smooth");
    BAD("--v-down -1", "--v-down");
    BAD("--max-steps 2.5", "--max-steps");
    BAD("--mu", "needs a value");
    BAD("--bogus 1", "unknown option");
    BAD("--restart " BUILD "/tests/no_such_run", "checkpoint");
#undef BAD
    CHECK(system("test -e " BUILD "/tests/t_pipe_bad") != 0);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(pipe_runs_both_stages);
    RUN(pipe_restart_and_threads_identical);
    RUN(pipe_bad_arguments);
    return gk_test_done();
}
