/* test_mpmdem_biaxial.c - smoke tests of examples/mpmdem_biaxial.c (the
 * MPMxDEM biaxial test of Liang & Zhao 2019): it runs, writes its documented
 * outputs (with the points A, B, C), starts in equilibrium, loads the specimen, does not depend on the
 * thread count, restarts to the identical result,
 * refuses a corrupted or foreign checkpoint, bad arguments and an --out that
 * is a file, and ends with status 1 when a result cannot be written. Needs
 * build/mpmdem_biaxial (`make test` builds examples first); the MPI build's
 * test is tests/mpirun_mpmdem.c. */
#define GK_TEST_DRIVERS
#include "gk_test.h"
#include <stdlib.h>
#include <string.h>

/* a 2 x 4 cell specimen (8 RVEs): tiny but the whole path */
#define BX BUILD "/mpmdem_biaxial --nx 2 --ny 4 --strain 0.002 --every 0.0005 --quiet "

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
    CHECK(system(BX "--threads 2 --out " BUILD "/tests/t_mpmbx > " BUILD "/tests/t_mpmbx.out 2>&1") == 0);
    CHECK(gk_test_file_has(
        BUILD "/tests/t_mpmbx/biaxial.csv",
        "time,eps_axial,sigma_yy,sigma_yy_base,eps_v,kinetic_energy,dem_steps_per_point,seconds"));
    n = read_rows(BUILD "/tests/t_mpmbx/biaxial.csv", r, 16);
    CHECK_EQ_INT(n, 4);
    if (n != 4) return;
    for (k = 0; k < n; ++k) {
        CHECK_NEAR(r[k][1], 0.0005 * (k + 1), 1e-5);
        CHECK_REL(r[k][2], r[k][3], 0.03); /* top vs base reaction */
    }
    CHECK(r[0][2] > 0.95e5 && r[0][2] < 1.2e5);
    for (k = 1; k < n; ++k) CHECK(r[k][2] > r[k - 1][2]);
    CHECK(r[n - 1][4] > 0.0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx/biaxial_stress.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx/rotation_end.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx/points_000000.vtk", "SCALARS eps_q"));
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_mpmbx.out", "n_rves"), 8, 0);
    CHECK_REL(gk_test_result(BUILD "/tests/t_mpmbx.out", "peak_sigma_yy"), r[n - 1][2],
              1e-5); /* printed with 6 digits */
}

/* the points A, B, C: points_ABC.csv has the start and one line per biaxial.csv row (same times and
 * strains); each point is the material point nearest to its asked position (0.5, 0.1), (0.5, 0.45),
 * (0.85, 0.8) of the 1 x 2 m specimen: on this 2 x 4 grid (one point per 0.5 m cell) the centres
 * (0.25, 0.25), (0.25, 0.75), (0.75, 1.75), the first of equals on a tie; the start is the consolidated
 * RVE (p = 100 kPa, eps_q = 0); B's p and q then rise with the load, and the RESULT's B_p_peak_kPa is
 * the largest p of the file */
TEST(biaxial_points_abc) {
    static const double at[3][2] = {{0.25, 0.25}, {0.25, 0.75}, {0.75, 1.75}};
    double a[8][35], r[16][8], pmax = 0;
    char line[4096];
    int n = 0, k, i;
    FILE *fp = fopen(BUILD "/tests/t_mpmbx/points_ABC.csv", "r");
    CHECK(fp != NULL);
    if (!fp) return;
    CHECK(fgets(line, sizeof line, fp) != NULL);
    CHECK(strncmp(line,
                  "time,eps_axial,A_x,A_y,A_p_kPa,A_q_kPa,A_eps_q,A_eps_v,A_rotation_deg,A_void_ratio,"
                  "A_fabric_anisotropy,A_coordination,A_dem_steps,B_x",
                  124) == 0);
    while (n < 8 && fgets(line, sizeof line, fp)) {
        char *s = line, *e;
        for (k = 0; k < 35; ++k, s = e + (*e == ',')) {
            a[n][k] = strtod(s, &e);
            if (e == s) break;
        }
        CHECK_EQ_INT(k, 35);
        ++n;
    }
    fclose(fp);
    CHECK_EQ_INT(n, 5);
    CHECK_EQ_INT(read_rows(BUILD "/tests/t_mpmbx/biaxial.csv", r, 16), 4);
    if (n != 5) return;
    CHECK(a[0][0] == 0 && a[0][1] == 0);
    for (k = 1; k < n; ++k) CHECK_REL(a[k][1], r[k - 1][1], 1e-5);
    for (i = 0; i < 3; ++i) {
        const double *v = a[0] + 2 + 11 * i;
        CHECK_NEAR(v[0], at[i][0], 1e-12);
        CHECK_NEAR(v[1], at[i][1], 1e-12);
        CHECK_REL(v[2], 100.0, 0.05); /* p [kPa] */
        CHECK(v[4] == 0.0);           /* eps_q */
    }
    for (k = 1; k < n; ++k) {
        CHECK(a[k][2 + 11 + 2] > a[k - 1][2 + 11 + 2]); /* B: p */
        CHECK(a[k][2 + 11 + 3] > a[k - 1][2 + 11 + 3]); /* B: q */
        pmax = a[k][2 + 11 + 2] > pmax ? a[k][2 + 11 + 2] : pmax;
    }
    CHECK_REL(gk_test_result(BUILD "/tests/t_mpmbx.out", "B_p_peak_kPa"), pmax, 1e-3);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx/points_ABC_pq.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx/points_ABC_fabric.svg", "<svg"));
}

/* RVEs run in parallel: one thread gives the same curve to the last digit */
TEST(biaxial_thread_independent) {
    CHECK(system(BX "--threads 1 --out " BUILD "/tests/t_mpmbx1 > " BUILD "/tests/t_mpmbx1.out 2>&1") == 0);
    CHECK(system("cmp -s " BUILD "/tests/t_mpmbx1/points_000000.vtk " BUILD
                 "/tests/t_mpmbx/points_000000.vtk") == 0);
    CHECK(gk_test_result(BUILD "/tests/t_mpmbx1.out", "peak_sigma_yy") ==
          gk_test_result(BUILD "/tests/t_mpmbx.out", "peak_sigma_yy"));
    CHECK(system("cmp -s " BUILD "/tests/t_mpmbx1/points_ABC.csv " BUILD "/tests/t_mpmbx/points_ABC.csv") ==
          0);
    CHECK(system("cut -d, -f1-7 " BUILD "/tests/t_mpmbx1/biaxial.csv > " BUILD "/tests/t_mpmbx1.c && "
                 "cut -d, -f1-7 " BUILD "/tests/t_mpmbx/biaxial.csv > " BUILD "/tests/t_mpmbx2.c && "
                 "cmp -s " BUILD "/tests/t_mpmbx1.c " BUILD "/tests/t_mpmbx2.c") == 0);
}

/* a checkpoint half-way, then --restart: the same final state (every point
 * array and RVE state is in the checkpoint) */
TEST(biaxial_restart_identical) {
    int rc =
        system(BUILD "/mpmdem_biaxial --nx 2 --ny 4 --strain 0.001 --every 0.0005 --quiet --out " BUILD
                     "/tests/t_mpmbx_a "
                     "> " BUILD "/tests/t_mpmbx_a.out 2>&1 && " BX "--restart " BUILD
                     "/tests/t_mpmbx_a --out " BUILD "/tests/t_mpmbx_b > " BUILD "/tests/t_mpmbx_b.out 2>&1");
    CHECK(rc == 0);
    CHECK(gk_test_result(BUILD "/tests/t_mpmbx_b.out", "peak_sigma_yy") ==
          gk_test_result(BUILD "/tests/t_mpmbx.out", "peak_sigma_yy"));
    CHECK(system("cmp -s " BUILD "/tests/t_mpmbx_b/points_ABC.csv " BUILD "/tests/t_mpmbx/points_ABC.csv") ==
          0);
    CHECK(system("cut -d, -f1-7 " BUILD "/tests/t_mpmbx_b/biaxial.csv > " BUILD "/tests/t_mpmbx_b.c && "
                 "cmp -s " BUILD "/tests/t_mpmbx_b.c " BUILD "/tests/t_mpmbx2.c") == 0);
}

/* bad input: a message and a non-zero exit, nothing run */
TEST(biaxial_bad_arguments) {
    CHECK(system(BUILD "/mpmdem_biaxial --nx 0 > " BUILD "/tests/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "out of range"));
    CHECK(system(BUILD "/mpmdem_biaxial --nx 3 --ny 4 > " BUILD "/tests/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "square"));
    CHECK(system(BUILD "/mpmdem_biaxial --alpha 2 > " BUILD "/tests/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "--alpha"));
    /* bad input changes nothing: no output folder is made before the inputs are read */
    CHECK(system("rm -rf " BUILD "/tests/t_mpmbx_bad") == 0);
    CHECK(system(BUILD "/mpmdem_biaxial --out " BUILD "/tests/t_mpmbx_bad --packing /nonexistent > " BUILD
                       "/tests/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "nonexistent"));
    CHECK(system(BUILD "/mpmdem_biaxial --out " BUILD
                       "/tests/t_mpmbx_bad --restart /nonexistent --nx 2 --ny 4 > " BUILD
                       "/tests/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "cannot open"));
    CHECK(system("test -e " BUILD "/tests/t_mpmbx_bad") != 0);
    CHECK(system(BUILD "/mpmdem_biaxial --help > " BUILD "/tests/t_mpmbx_bad.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "--dem-strain"));
    /* the driver's default folder is build/mpm_biaxial, whatever folder the tests build in */
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "(default build/mpm_biaxial)"));
    /* values parsed strictly; the message names the option */
    CHECK(system(BUILD "/mpmdem_biaxial --nx -1 > " BUILD "/tests/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "--nx -1 is out of range"));
    CHECK(system(BUILD "/mpmdem_biaxial --nx=8 > " BUILD "/tests/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "--nx=8: write the value after the option"));
    CHECK(system(BUILD "/mpmdem_biaxial --nx 99999999999 > " BUILD "/tests/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "--nx 99999999999 is out of range"));
    CHECK(system(BUILD "/mpmdem_biaxial --nx 8x > " BUILD "/tests/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "--nx '8x' is not a whole number"));
    CHECK(system(BUILD "/mpmdem_biaxial --strain 1e999 > " BUILD "/tests/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "--strain '1e999' is not a finite number"));
    /* the DEM-rule flags of mpmdem.h are taken (they were listed in --help but refused), bad ones not */
    CHECK(system(BUILD "/mpmdem_biaxial --dem-rule foo > " BUILD "/tests/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "adaptive or strain"));
    CHECK(system(BUILD "/mpmdem_biaxial --dem-inertial -1 > " BUILD "/tests/t_mpmbx_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_bad.out", "--dem-inertial"));
    CHECK(system(BX "--strain 0.0005 --dem-rule strain --dem-strain 2e-5 --out " BUILD "/tests/t_mpmbx_rule "
                    "> " BUILD "/tests/t_mpmbx_rule.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_rule.out",
                           "DEM steps per MPM step: <= 2e-05 strain per DEM step"));
    CHECK(system(BX "--strain 0.0005 --dem-inertial 1e-3 --dem-unbalanced 1e-2 --out " BUILD
                    "/tests/t_mpmbx_rule "
                    "> " BUILD "/tests/t_mpmbx_rule.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_rule.out",
                           "adaptive, I <= 0.001 then relaxation to an unbalanced force "
                           "ratio < 0.01"));
}

/* lines of a file containing needle */
static int count_lines(const char *path, const char *needle) {
    FILE *fp = fopen(path, "r");
    char buf[4096];
    int n = 0;
    if (!fp) return -1;
    while (fgets(buf, sizeof buf, fp)) n += strstr(buf, needle) != NULL;
    fclose(fp);
    return n;
}

/* a copy of src at dst: the first `keep` bytes (all if < 0), byte `flip` (if >= 0) inverted */
static int copy_damaged(const char *src, const char *dst, long keep, long flip) {
    FILE *in = fopen(src, "rb"), *out = in ? fopen(dst, "wb") : NULL;
    long k = 0;
    int c, ok = in && out;
    while (ok && (c = fgetc(in)) != EOF && (keep < 0 || k < keep))
        ok = fputc(k == flip ? c ^ 0xff : c, out) != EOF, ++k;
    if (in) fclose(in);
    if (out) ok = fclose(out) == 0 && ok;
    return ok && k > flip;
}

/* a checkpoint that is corrupt (one byte of its middle), truncated, of another model or of the old
 * format is refused by name with status 1, before anything is run or written */
TEST(biaxial_bad_checkpoint_refused) {
    long size;
    FILE *fp = fopen(BUILD "/tests/t_mpmbx_a/checkpoint.bin", "rb");
    CHECK(fp != NULL);
    if (!fp) return;
    fseek(fp, 0, SEEK_END), size = ftell(fp), fclose(fp);
    CHECK(system("rm -rf " BUILD "/tests/t_mpmbx_ck " BUILD "/tests/t_mpmbx_ckout && mkdir -p " BUILD
                 "/tests/t_mpmbx_ck") == 0);
    CHECK(copy_damaged(BUILD "/tests/t_mpmbx_a/checkpoint.bin", BUILD "/tests/t_mpmbx_ck/checkpoint.bin", -1,
                       size / 2));
    CHECK(system(BX "--restart " BUILD "/tests/t_mpmbx_ck --out " BUILD "/tests/t_mpmbx_ckout > " BUILD
                    "/tests/t_mpmbx_ck.out 2>&1; "
                    "test $? -eq 1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_ck.out",
                           "checkpoint.bin: checksum mismatch (the file is corrupt)"));
    CHECK(!gk_test_file_has(BUILD "/tests/t_mpmbx_ckout/biaxial.csv", "time")); /* nothing ran */
    CHECK(copy_damaged(BUILD "/tests/t_mpmbx_a/checkpoint.bin", BUILD "/tests/t_mpmbx_ck/checkpoint.bin",
                       size - 100, -1));
    CHECK(system(BX "--restart " BUILD "/tests/t_mpmbx_ck --out " BUILD "/tests/t_mpmbx_ckout > " BUILD
                    "/tests/t_mpmbx_ck.out 2>&1; "
                    "test $? -eq 1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_ck.out", "truncated"));
    CHECK(system(BUILD "/mpmdem_biaxial --nx 2 --ny 2 --height 1 --quiet --restart " BUILD "/tests/t_mpmbx_a "
                       "--out " BUILD "/tests/t_mpmbx_ckout > " BUILD
                       "/tests/t_mpmbx_ck.out 2>&1; test $? -eq 1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_ck.out", "holds 8 points"));
    CHECK(system("printf 'GKMPMDEM1biaxial' > " BUILD "/tests/t_mpmbx_ck/checkpoint.bin && " BX
                 "--restart " BUILD "/tests/t_mpmbx_ck --out " BUILD "/tests/t_mpmbx_ckout > " BUILD
                 "/tests/t_mpmbx_ck.out 2>&1; test $? "
                 "-eq 1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_ck.out", "is not a grainkit two-scale checkpoint"));
}

/* a result that cannot be written (its path taken by a folder, or a full disk: /dev/full) ends the
 * run with status 1, said once, naming the file */
TEST(biaxial_failed_write_exits) {
    static const char *cases[][2] = {
        {"mkdir -p " BUILD "/tests/t_mpmbx_w/biaxial.csv", BUILD "/tests/t_mpmbx_w/biaxial.csv"},
        {"mkdir -p " BUILD "/tests/t_mpmbx_w && ln -s /dev/full " BUILD "/tests/t_mpmbx_w/biaxial.csv",
         BUILD "/tests/t_mpmbx_w/biaxial.csv"},
        {"mkdir -p " BUILD "/tests/t_mpmbx_w/checkpoint.bin.tmp", BUILD "/tests/t_mpmbx_w/checkpoint.bin"},
        {"mkdir -p " BUILD "/tests/t_mpmbx_w && ln -s /dev/full " BUILD "/tests/t_mpmbx_w/rotation_end.svg",
         BUILD "/tests/t_mpmbx_w/rotation_end.svg"},
        {"mkdir -p " BUILD "/tests/t_mpmbx_w/points_000000.vtk", BUILD "/tests/t_mpmbx_w/points_000000.vtk"}};
    char cmd[1024], msg[256];
    int k;
    for (k = 0; k < (int)(sizeof cases / sizeof *cases); ++k) {
        snprintf(cmd, sizeof cmd,
                 "rm -rf " BUILD "/tests/t_mpmbx_w && %s && " BX "--strain 0.0005 --out " BUILD
                 "/tests/t_mpmbx_w > " BUILD "/tests/t_mpmbx_w.out "
                 "2>&1; test $? -eq 1",
                 cases[k][0]);
        CHECK(system(cmd) == 0);
        snprintf(msg, sizeof msg, "mpmdem_biaxial: cannot write %s", cases[k][1]);
        CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_w.out", msg));
        CHECK(count_lines(BUILD "/tests/t_mpmbx_w.out", "cannot write") == 1);
        CHECK(
            !gk_test_file_has(BUILD "/tests/t_mpmbx_w.out", "wrote ")); /* no claim of what was not written */
    }
}

/* --out must be a folder (created with its parents): a file there is refused, and the default
 * (no --out) is build/mpm_biaxial under the working directory, where the results land (run from
 * build/tests/t_mpmbx_cwd, so that the test writes only under build/tests) */
TEST(biaxial_out_folder) {
    CHECK(system("rm -rf " BUILD "/tests/t_mpmbx_f && echo x > " BUILD "/tests/t_mpmbx_file && " BX
                 "--out " BUILD "/tests/t_mpmbx_file > " BUILD
                 "/tests/t_mpmbx_f.out 2>&1; test $? -eq 1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_f.out", "--out " BUILD "/tests/t_mpmbx_file: " BUILD
                                                         "/tests/t_mpmbx_file is a file, not a folder"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_file", "x")); /* untouched */
    CHECK(system(BX "--out " BUILD "/tests/t_mpmbx_file/sub > " BUILD
                    "/tests/t_mpmbx_f.out 2>&1; test $? -eq 1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_f.out", "is a file, not a folder"));
    CHECK(system(
              "rm -rf " BUILD "/tests/t_mpmbx_cwd && mkdir " BUILD "/tests/t_mpmbx_cwd && cd " BUILD
              "/tests/t_mpmbx_cwd "
              "&& "
              "../../mpmdem_biaxial --packing ../../../examples/data/rve400.txt --nx 2 --ny 4 --every 0.0005 "
              "--quiet --strain 0.0005 > ../t_mpmbx_f.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_cwd/build/mpm_biaxial/biaxial.csv", "time,eps_axial"));
    CHECK(system(BX "--strain 0.0005 --out " BUILD "/tests/t_mpmbx_f/a/b > " BUILD
                    "/tests/t_mpmbx_f.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmbx_f/a/b/biaxial.csv", "time,eps_axial"));
}

/* examples/mpmdem_single.c, Liang & Zhao (2019) Sec 3.1: one MPM cell, 2 x 2 points, smooth rollers
 * left and bottom, a smooth plate on top, a follower pressure on the right, against the RVE alone in
 * a drained biaxial test at the same lateral stress. With smooth walls all around the velocity field
 * of the cell is bilinear with equal right-node velocities, so every point receives the same dH and
 * the element is homogeneous ("the global response measured from the element should match the local
 * responses extracted from the pure DEM simulations", Sec 3.1): the element and the RVE alone may
 * differ only by the MPM's dynamics (the cell's inertia, the ramp, the PIC/FLIP transfer) and by the
 * DEM's noise. A 60-disk packing to 1 % axial strain (a fraction of a second). Tolerances:
 * - sigma_yy within 2 %: the DEM noise of a 60-disk RVE on this path is what the 4 points' own
 *   sigma_yy spread shows (max - min <= 3 % of their mean, asserted below: about +-1.5 % of one RVE
 *   about the mean); the element measured 0.9 %. A dynamic error fails it: pure PIC (--alpha 1),
 *   whose transfer damps the lateral expansion, gives 3.9 %;
 * - eps_v within 2e-4 (4 % of the 4.7e-3 reached): measured 6e-5; pure PIC gives 1.0e-3;
 * - homogeneity: F of the 4 points equal within 1e-3 (the strain is 1e-2; they differ only as
 *   their RVEs' noise feeds back into the internal forces); the work-conjugate plate reaction R h / V
 *   equals the points' mean stress within 1 % (quasi-static: the cell's inertia is small);
 * - the start: sigma_yy of the first row (0.1 % strain) between the consolidation pressure and 1.2 x
 *   it, sigma_xx of the RVE alone held at the lateral 100 kPa within 1 % by its servo. */
#define SG BUILD "/mpmdem_single --strain 0.01 --packing " BUILD "/tests/t_sg_pack.txt --quiet "
TEST(single_element_follows_the_rve_alone) {
    double r[16][13];
    int n = 0, k;
    FILE *fp;
    char line[1024];
    CHECK(system(BUILD "/gk_pack --dim 2 --n 60 --pressure 1e5 --out " BUILD "/tests/t_sg_pack.txt > " BUILD
                       "/tests/t_sg_pack.out 2>&1") == 0);
    CHECK(system(SG "--threads 2 --out " BUILD "/tests/t_sg > " BUILD "/tests/t_sg.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_sg/single.csv",
                           "time,plate_displacement,eps_axial,sigma_yy,sigma_yy_points,point_spread,eps_v,"
                           "eps_axial_dem,sigma_yy_dem,sigma_xx_dem,eps_v_dem,dem_steps_per_point,seconds"));
    CHECK(gk_test_file_has(BUILD "/tests/t_sg/single_stress.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_sg/single_volume.svg", "<svg"));
    CHECK((fp = fopen(BUILD "/tests/t_sg/single.csv", "r")) != NULL);
    if (!fp) return;
    if (fgets(line, sizeof line, fp))
        while (n < 16 && fgets(line, sizeof line, fp)) {
            double *q = r[n];
            if (sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &q[0], &q[1], &q[2],
                       &q[3], &q[4], &q[5], &q[6], &q[7], &q[8], &q[9], &q[10], &q[11], &q[12]) != 13)
                break;
            ++n;
        }
    fclose(fp);
    CHECK_EQ_INT(n, 10);
    if (n != 10) return;
    CHECK(r[0][3] > 1e5 && r[0][3] < 1.2e5);
    for (k = 0; k < n; ++k) {
        CHECK_NEAR(r[k][2], 0.001 * (k + 1), 5e-5); /* a row every 0.1 % */
        CHECK_NEAR(r[k][7], r[k][2], 2e-5);         /* the RVE alone at the element's strain */
        CHECK_REL(r[k][3], r[k][8], 0.02);          /* sigma_yy: element vs RVE alone */
        CHECK_NEAR(r[k][6], r[k][10], 2e-4);        /* eps_v */
        CHECK_REL(r[k][3], r[k][4], 0.01);          /* plate reaction vs the points */
        CHECK(r[k][5] < 0.03);                      /* the 4 points' sigma_yy spread */
        CHECK_REL(r[k][9], 1e5, 0.01);              /* the servo's lateral stress */
        if (k) CHECK(r[k][3] > r[k - 1][3]);        /* hardening before the peak */
    }
    CHECK(r[n - 1][6] > 0.0); /* the dense packing contracts first */
    CHECK(gk_test_result(BUILD "/tests/t_sg.out", "f_spread") < 1e-3);
    CHECK(gk_test_result(BUILD "/tests/t_sg.out", "max_rel_diff_sigma_yy") < 0.02);
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_sg.out", "n_rves"), 4, 0);
    /* the same curves with one thread (the time column aside) */
    CHECK(system(SG "--threads 1 --out " BUILD "/tests/t_sg1 > " BUILD "/tests/t_sg1.out 2>&1") == 0);
    CHECK(system("cut -d, -f1-12 " BUILD "/tests/t_sg/single.csv > " BUILD "/tests/t_sg.c && "
                 "cut -d, -f1-12 " BUILD "/tests/t_sg1/single.csv > " BUILD "/tests/t_sg1.c && "
                 "cmp -s " BUILD "/tests/t_sg.c " BUILD "/tests/t_sg1.c") == 0);
    /* bad input: refused with a message, no output folder */
    CHECK(system("rm -rf " BUILD "/tests/t_sg_bad && " BUILD "/mpmdem_single --margin -1 --out " BUILD
                 "/tests/t_sg_bad > " BUILD "/tests/t_sg_bad.out 2>&1") == 2 * 256);
    CHECK(gk_test_file_has(BUILD "/tests/t_sg_bad.out", "--margin -1 is out of range"));
    CHECK(system(BUILD "/mpmdem_single --packing /nonexistent --out " BUILD "/tests/t_sg_bad > " BUILD
                       "/tests/t_sg_bad.out 2>&1") != 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_sg_bad.out", "nonexistent"));
    CHECK(system("test -e " BUILD "/tests/t_sg_bad") != 0);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(biaxial_runs_and_loads);
    RUN(biaxial_points_abc);
    RUN(biaxial_thread_independent);
    RUN(biaxial_restart_identical);
    RUN(biaxial_bad_arguments);
    RUN(biaxial_bad_checkpoint_refused);
    RUN(biaxial_failed_write_exits);
    RUN(biaxial_out_folder);
    RUN(single_element_follows_the_rve_alone);
    return gk_test_done();
}
