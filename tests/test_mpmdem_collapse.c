/* test_mpmdem_collapse.c - smoke tests of examples/mpmdem_collapse.c (the
 * MPMxDEM column collapse of Liang & Zhao 2019 Sec 3.5): it runs, writes its
 * documented outputs, keeps the energy balance and the mass, spreads the
 * column outward, does not depend on the thread count, restarts to the
 * identical result, takes the paper's size as a preset, refuses bad arguments and a
 * corrupted checkpoint, and ends with status 1 when a result cannot be written. Needs
 * build/mpmdem_collapse (`make test` builds examples first). */
#define GK_TEST_DRIVERS
#include "gk_test.h"
#include <stdlib.h>

/* a 4 x 4 cell column (16 RVEs, 4 pressure levels): tiny but the whole path */
#ifdef GK_TEST_QUICK
#define CL_T_END "0.1"
#define CL_T_HALF "0.05"
#define CL_ROWS 5
#else
#define CL_T_END "0.15"
#define CL_T_HALF "0.075"
#define CL_ROWS 7
#endif
#define CL BUILD "/mpmdem_collapse --nx 4 --every 0.025 --snapshots 0.05 --quiet "
#define NCOL 15

static int read_rows(const char *path, double rows[][NCOL], int max) {
    FILE *fp = fopen(path, "r");
    char line[2048];
    int n = 0;
    if (!fp) return -1;
    if (!fgets(line, sizeof line, fp)) n = -1;
    while (n >= 0 && n < max && fgets(line, sizeof line, fp)) {
        double *r = rows[n];
        char *s = line, *end;
        int k;
        for (k = 0; k < NCOL; ++k) {
            r[k] = strtod(s, &end);
            if (end == s) break;
            s = *end == ',' ? end + 1 : end;
        }
        if (k < NCOL) break;
        ++n;
    }
    fclose(fp);
    return n;
}

/* outputs and physics. Columns: 0 time, 1 front, 2 dstar, 3 front_box,
 * 4 front_raw, 5 height, 6 Ek, 7 Ep, 8 Ed (over E_p0), 9 mass, 10 mass_grid,
 * 11 loose_rves, 12 frozen_rves, 13 dem_steps_per_point, 14 seconds.
 * The column starts at rest at its full size (front = d_0 = 1 m, height 1 m,
 * E_p = E_p0); energy is not created (E_d >= 0 and E_k + E_p <= E_p0 within
 * the noise of the initial elastic release); the front moves outward and
 * the column loses height; the points carry the mass (the grid receives all
 * of it: every support inside the grid); the kinetic energy grows under
 * gravity in this early phase; the RESULT line repeats the last row. */
TEST(collapse_runs_and_conserves) {
    double r[32][NCOL];
    int n, k;
    CHECK(system(CL "--t-end " CL_T_END " --threads 2 --out " BUILD "/tests/t_mpmcl > " BUILD
                    "/tests/t_mpmcl.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl/collapse.csv",
                           "time,front,dstar,front_box,front_raw,height,Ek_over_Ep0,Ep_over_Ep0,Ed_over_Ep0,"
                           "mass,mass_grid,loose_rves,frozen_rves,dem_steps_per_point,seconds"));
    n = read_rows(BUILD "/tests/t_mpmcl/collapse.csv", r, 32);
    CHECK_EQ_INT(n, CL_ROWS);
    if (n != CL_ROWS) return;
    CHECK_NEAR(r[0][0], 0.0, 0.0);
    CHECK_NEAR(r[0][1], 1.0, 1e-12);
    CHECK_NEAR(r[0][5], 1.0, 1e-12);
    CHECK_NEAR(r[0][7], 1.0, 1e-12);
    CHECK_NEAR(r[0][6], 0.0, 0.0);
    for (k = 1; k < n; ++k) {
        CHECK_NEAR(r[k][0], 0.025 * k, 0.002);
        CHECK(r[k][8] >= -2e-3);              /* E_d >= 0 within noise */
        CHECK(r[k][6] + r[k][7] <= 1 + 2e-3); /* E_k + E_p <= E_p0 */
        CHECK(r[k][1] >= r[k - 1][1] - 1e-3); /* the front does not retreat */
        CHECK(r[k][5] <= 1.0 + 1e-3);
        CHECK_REL(r[k][9], r[0][9], 1e-12); /* mass of the points */
        CHECK_REL(r[k][10], r[0][9], 1e-9); /* all of it on the grid */
        CHECK_NEAR(r[k][2], r[k][1] - 1.0, 1e-5);
        CHECK(r[k][13] >= 1.0);
    }
    CHECK(r[n - 1][1] > 1.005);      /* spreading */
    CHECK(r[n - 1][6] > r[1][6]);    /* accelerating under gravity */
    CHECK(r[n - 1][7] < 1.0 - 1e-3); /* the centre of mass falls */
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_mpmcl.out", "n_rves"), 16, 0);
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_mpmcl.out", "dstar_paper"), 1.8, 0);
    CHECK_REL(gk_test_result(BUILD "/tests/t_mpmcl.out", "dstar"), r[n - 1][2], 1e-3);
    CHECK_REL(gk_test_result(BUILD "/tests/t_mpmcl.out", "Ed_final_over_Ep0"), r[n - 1][8], 1e-3);
    CHECK(gk_test_result(BUILD "/tests/t_mpmcl.out", "Ek_peak_over_Ep0") >= r[n - 1][6] * (1 - 1e-3));
    CHECK(gk_test_result(BUILD "/tests/t_mpmcl.out", "seconds_per_step_per_1000_rves") > 0);
    CHECK(gk_test_result(BUILD "/tests/t_mpmcl.out", "mpm_steps") > 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl.out", "total_seconds="));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl/collapse_energy.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl/collapse_front.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl/eps_q_0.05.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl/velocity_0.05.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl/velocity_end.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl/points_000000.vtk", "SCALARS eps_q"));
    /* geostatic levels: 4 pressures printed, the deepest ~ rho g 7/8 m */
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl.out", "level 3: depth 0.750-1.000 m"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl.out", "real-time count"));
}

/* RVEs run in parallel: one thread gives the same history to the last digit.
 * This run also takes the other thin-cell policy (--thin-cell stop instead of
 * freeze), identical while no RVE cell gets too thin. */
TEST(collapse_thread_independent) {
    CHECK(system(CL "--t-end " CL_T_END " --threads 1 --thin-cell stop --out " BUILD "/tests/t_mpmcl1 "
                    "> " BUILD "/tests/t_mpmcl1.out 2>&1") == 0);
    CHECK(system("cmp -s " BUILD "/tests/t_mpmcl1/points_000000.vtk " BUILD
                 "/tests/t_mpmcl/points_000000.vtk") == 0);
    CHECK(gk_test_result(BUILD "/tests/t_mpmcl1.out", "dstar") ==
          gk_test_result(BUILD "/tests/t_mpmcl.out", "dstar"));
    CHECK(system("cut -d, -f1-14 " BUILD "/tests/t_mpmcl1/collapse.csv > " BUILD "/tests/t_mpmcl1.c && "
                 "cut -d, -f1-14 " BUILD "/tests/t_mpmcl/collapse.csv > " BUILD "/tests/t_mpmcl2.c && "
                 "cmp -s " BUILD "/tests/t_mpmcl1.c " BUILD "/tests/t_mpmcl2.c") == 0);
}

/* half-way, then --restart: the same history and final state (every point
 * array, RVE state and row is in the checkpoint) */
TEST(collapse_restart_identical) {
    int rc = system(CL "--t-end " CL_T_HALF " --out " BUILD "/tests/t_mpmcl_a > " BUILD
                       "/tests/t_mpmcl_a.out 2>&1 && " CL "--t-end " CL_T_END " --restart " BUILD
                       "/tests/t_mpmcl_a --out " BUILD "/tests/t_mpmcl_b "
                       "> " BUILD "/tests/t_mpmcl_b.out 2>&1");
    CHECK(rc == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_b.out", "restarted from"));
    CHECK(gk_test_result(BUILD "/tests/t_mpmcl_b.out", "dstar") ==
          gk_test_result(BUILD "/tests/t_mpmcl.out", "dstar"));
    CHECK(gk_test_result(BUILD "/tests/t_mpmcl_b.out", "Ed_final_over_Ep0") ==
          gk_test_result(BUILD "/tests/t_mpmcl.out", "Ed_final_over_Ep0"));
    CHECK(system("cut -d, -f1-14 " BUILD "/tests/t_mpmcl_b/collapse.csv > " BUILD "/tests/t_mpmcl_b.c && "
                 "cmp -s " BUILD "/tests/t_mpmcl_b.c " BUILD "/tests/t_mpmcl2.c") == 0);
}

/* bad input: a message and a non-zero exit, nothing run */
TEST(collapse_bad_arguments) {
    CHECK(system(BUILD "/mpmdem_collapse --nx 0 > " BUILD "/tests/t_mpmcl_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "--nx"));
    CHECK(system(BUILD "/mpmdem_collapse --nx 3 --height 0.5 > " BUILD "/tests/t_mpmcl_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "whole number of cells"));
    CHECK(system(BUILD "/mpmdem_collapse --alpha 2 > " BUILD "/tests/t_mpmcl_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "--alpha"));
    CHECK(system(BUILD "/mpmdem_collapse --mu -1 > " BUILD "/tests/t_mpmcl_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "--mu"));
    CHECK(system(BUILD "/mpmdem_collapse --t-end abc > " BUILD "/tests/t_mpmcl_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "not a finite number"));
    CHECK(system(BUILD "/mpmdem_collapse --snapshots 0.5,0.2 > " BUILD "/tests/t_mpmcl_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "--snapshots"));
    CHECK(system(BUILD "/mpmdem_collapse --thin-cell maybe > " BUILD "/tests/t_mpmcl_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "stop or freeze"));
    CHECK(system(BUILD "/mpmdem_collapse --bogus 1 > " BUILD "/tests/t_mpmcl_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "unknown option --bogus"));
    CHECK(system(BUILD "/mpmdem_collapse --levels > " BUILD "/tests/t_mpmcl_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "needs a value"));
    /* bad input changes nothing: no output folder is made before the inputs are read */
    CHECK(system("rm -rf " BUILD "/tests/t_mpmcl_bad") == 0);
    CHECK(system(BUILD "/mpmdem_collapse --out " BUILD "/tests/t_mpmcl_bad --packing /nonexistent > " BUILD
                       "/tests/t_mpmcl_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "nonexistent"));
    CHECK(system(BUILD "/mpmdem_collapse --out " BUILD
                       "/tests/t_mpmcl_bad --nx 4 --restart /nonexistent > " BUILD
                       "/tests/t_mpmcl_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "cannot open"));
    CHECK(system("test -e " BUILD "/tests/t_mpmcl_bad") != 0);
    CHECK(system(BUILD "/mpmdem_collapse --help > " BUILD "/tests/t_mpmcl_bad.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "--thin-cell"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "--rest-frac"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_bad.out", "--dem-max"));
}

/* --paper is the paper's 1000-disk RVEs on 16 x 16 cells with 4 points each; a flag given with it
 * overrides the preset (here the grid, so that the run stays short) */
TEST(collapse_paper_preset) {
    CHECK(system(BUILD "/mpmdem_collapse --paper --nx 4 --ppc 1 --levels 1 --t-end 0.01 --every 0.005 "
                       "--snapshots 0.005 --threads 1 --quiet --out " BUILD "/tests/t_mpmcl_paper > " BUILD
                       "/tests/t_mpmcl_paper.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_paper.out", "4 x 4 cells"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_paper.out", "16 points (= RVEs of 1000 disks)"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_paper.out", "RESULT dstar="));
    CHECK(system(BUILD "/mpmdem_collapse --paper --ppc 1 --packing /nonexistent > " BUILD
                       "/tests/t_mpmcl_paper.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_paper.out", "nonexistent"));
    CHECK(system(BUILD "/mpmdem_collapse --help > " BUILD "/tests/t_mpmcl_paper.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_paper.out", "--paper"));
}

/* a corrupted checkpoint is refused by name (status 1); a result that cannot be written (the CSV's
 * path taken by a folder) ends the run with status 1, said once; --out onto a file is refused */
TEST(collapse_bad_files) {
    CHECK(system("rm -rf " BUILD "/tests/t_mpmcl_k && mkdir -p " BUILD "/tests/t_mpmcl_k && "
                 "cp " BUILD "/tests/t_mpmcl_a/checkpoint.bin " BUILD "/tests/t_mpmcl_k/ && "
                 "printf 'X' | dd of=" BUILD
                 "/tests/t_mpmcl_k/checkpoint.bin bs=1 seek=5000 conv=notrunc 2>/dev/null "
                 "&& " CL "--t-end " CL_T_END " --restart " BUILD "/tests/t_mpmcl_k --out " BUILD
                 "/tests/t_mpmcl_k2 > " BUILD "/tests/t_mpmcl_k.out 2>&1; "
                 "test $? -eq 1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_k.out", "checksum mismatch"));
    CHECK(system("rm -rf " BUILD "/tests/t_mpmcl_w && mkdir -p " BUILD "/tests/t_mpmcl_w/collapse.csv && " CL
                 "--t-end 0.03 --out " BUILD "/tests/t_mpmcl_w > " BUILD
                 "/tests/t_mpmcl_w.out 2>&1; test $? -eq 1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_w.out",
                           "mpmdem_collapse: cannot write " BUILD "/tests/t_mpmcl_w/collapse.csv"));
    CHECK(system("grep -c 'cannot write' " BUILD "/tests/t_mpmcl_w.out | grep -qx 1") == 0);
    CHECK(system("echo x > " BUILD "/tests/t_mpmcl_file && " CL "--out " BUILD "/tests/t_mpmcl_file > " BUILD
                 "/tests/t_mpmcl_f.out 2>&1; "
                 "test $? -eq 1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmcl_f.out", "is a file, not a folder"));
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(collapse_runs_and_conserves);
    RUN(collapse_thread_independent);
    RUN(collapse_restart_identical);
    RUN(collapse_bad_arguments);
    RUN(collapse_bad_files);
    RUN(collapse_paper_preset);
    return gk_test_done();
}
