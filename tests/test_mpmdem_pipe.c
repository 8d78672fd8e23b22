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
#include <string.h>

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

/* points_DEF.csv of that run: the paper's points D, E, F (Liang & Zhao Figs 22-24) as the material
 * points nearest to (x0 - 1.1, 0.6 m deep), (x0 + 0.1, 1.05 m deep), (x0 + 1.1, 0.6 m deep) with x0 =
 * 1.5 m the pipe's start: on this grid (h = 0.25 m, points at cell centres, ground y = 1.25 m) the
 * points at (0.375, 0.625), (1.625, 0.125), (2.625, 0.625); a row at t = 0, then one per row of pipe.csv
 * at the same time; finite values; the points named in the output; E, under the pipe, is compressed as
 * the pipe comes down (its p rises above the geostatic start) */
#define NDEF 35
TEST(pipe_points_def) {
    static const double at[3][2] = {{0.375, 0.625}, {1.625, 0.125}, {2.625, 0.625}};
    static const char head[] =
        "time,stage,pipe_x,pipe_bottom_y,travel,D_x,D_y,D_p_kPa,D_q_kPa,D_eps_q,D_eps_v,"
        "D_rotation_deg,D_void_ratio,D_coordination,D_dem_steps,E_x,";
    double d[64][NDEF], r[64][NCOL], pmax = 0;
    char line[4096];
    int n = 0, m, k, j, i;
    FILE *fp = fopen(BUILD "/tests/t_pipe1/points_DEF.csv", "r");
    CHECK(fp != NULL);
    if (!fp) return;
    CHECK(fgets(line, sizeof line, fp) != NULL);
    CHECK(strncmp(line, head, strlen(head)) == 0);
    CHECK(strstr(line, ",F_x,F_y,F_p_kPa,F_q_kPa,F_eps_q,F_eps_v,F_rotation_deg,F_void_ratio,F_coordination,"
                       "F_dem_steps\n") != NULL);
    while (n < 64 && fgets(line, sizeof line, fp)) {
        char *c = line, *e;
        for (j = 0; j < NDEF; ++j, c = e + (*e == ',')) {
            d[n][j] = strtod(c, &e);
            if (e == c) break;
        }
        CHECK(j == NDEF);
        if (j < NDEF) break;
        ++n;
    }
    fclose(fp);
    m = read_rows(BUILD "/tests/t_pipe1/pipe.csv", r, 64);
    CHECK(m >= 8 && n == m + 1);
    if (m < 8 || n != m + 1) return;
    CHECK(d[0][0] == 0 && d[0][1] == 1 && d[0][4] == 0);
    for (i = 0; i < 3; ++i) {
        CHECK_NEAR(d[0][5 + 10 * i], at[i][0], 1e-9);
        CHECK_NEAR(d[0][6 + 10 * i], at[i][1], 1e-9);
        CHECK(d[0][7 + 10 * i] > 0);                            /* geostatic p */
        CHECK(d[0][9 + 10 * i] == 0 && d[0][11 + 10 * i] == 0); /* no strain, no rotation yet */
    }
    for (k = 0; k < n; ++k) {
        for (j = 0; j < NDEF; ++j) CHECK(isfinite(d[k][j]));
        if (k > 0) {
            CHECK_NEAR(d[k][0], r[k - 1][0], 1e-6 * (1 + r[k - 1][0]));
            CHECK(d[k][1] == r[k - 1][5]);
            CHECK_NEAR(d[k][4], r[k - 1][3] + r[k - 1][4], 1e-5);
            for (i = 0; i < 3; ++i) CHECK(d[k][14 + 10 * i] >= 1); /* DEM steps */
        }
        for (i = 0; i < 3; ++i) {
            CHECK(d[k][9 + 10 * i] >= 0);                              /* eps_q */
            CHECK(d[k][12 + 10 * i] > 0.1 && d[k][12 + 10 * i] < 0.3); /* void ratio of the dense packing */
            CHECK(d[k][13 + 10 * i] >= 0 && d[k][13 + 10 * i] <= 6);   /* coordination 2 N_c / N_p of disks */
        }
        if (d[k][1] == 1 && d[k][17] > pmax) pmax = d[k][17];
    }
    CHECK(pmax > 2 * d[0][17]);
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe1.out", "point D: material point"));
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe1.out", "point E: material point"));
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe1.out", "point F: material point"));
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_pipe1.out", "E_p_max_kPa"), pmax, 1e-3 * pmax);
    CHECK(isfinite(gk_test_result(BUILD "/tests/t_pipe1.out", "D_eps_q_onset")));
    CHECK(isfinite(gk_test_result(BUILD "/tests/t_pipe1.out", "F_q_end_kPa")));
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe1/points_DEF.svg", "point E"));
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe1/points_DEF_rotation.svg", "point F"));
    CHECK(gk_test_file_has(BUILD "/tests/t_pipe1/points_DEF_pq.svg", "point D"));
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
    /* the points' histories too: the checkpoint carries them */
    CHECK(system("cmp -s " BUILD "/tests/t_pipe_b/points_DEF.csv " BUILD "/tests/t_pipe1/points_DEF.csv") ==
          0);
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
    BAD("--width 0", "--width 0 is out of range");
    BAD("--width -9", "--width -9 is out of range");
    BAD("--width 2e4", "--width 2e4 is out of range");
    BAD("--width nine", "--width 'nine' is not a finite number");
    BAD("--width nan", "--width 'nan' is not a finite number");
    BAD("--width", "needs a value");
    BAD("--width 2.5 --nx 20", "to the wall");
    BAD("--restart " BUILD "/tests/no_such_run", "checkpoint");
#undef BAD
    CHECK(system("test -e " BUILD "/tests/t_pipe_bad") != 0);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(pipe_runs_both_stages);
    RUN(pipe_points_def);
    RUN(pipe_restart_and_threads_identical);
    RUN(pipe_bad_arguments);
    return gk_test_done();
}
