/* test_examples.c - smoke tests of the example drivers and tools: they run,
 * exit 0, and write the documented outputs with sane values. Needs the
 * binaries in build/ (`make test` builds them first). */
#define GK_IMPLEMENTATION
#include "gk_dem.h"
#include "gk_test.h"
#include <stdlib.h>

static int file_has(const char *path, const char *needle) {
    FILE *fp = fopen(path, "r");
    char buf[4096];
    int found = 0;
    if (!fp) return 0;
    while (!found && fgets(buf, sizeof buf, fp))
        if (strstr(buf, needle)) found = 1;
    fclose(fp);
    return found;
}

static int count_lines(const char *path) {
    FILE *fp = fopen(path, "r");
    int c, n = 0;
    if (!fp) return -1;
    while ((c = fgetc(fp)) != EOF)
        if (c == '\n') ++n;
    fclose(fp);
    return n;
}

/* rve_path: documented CSV header, one row per increment plus the initial
 * state, which is the seed packing's YADE stress (p = 99976.38 Pa) */
TEST(rve_path_writes_csv_and_svg) {
    const char *cmd = "build/rve_path --packing examples/data/rve400.txt --dH \"0 0.001 0 0\" --increments 5 "
                      "--steps-per-increment 50 --E 6e8 --kt-ratio 0.8 --friction-angle 0.5 --density 2650 "
                      "--thickness 0.1 --damping 0.1 --damping-form component --out build/t_rve_path.csv "
                      "> build/t_rve_path.out 2>&1";
    FILE *fp;
    char line[1024];
    double p0 = 0;
    CHECK(system(cmd) == 0);
    fp = fopen("build/t_rve_path.csv", "r");
    CHECK(fp != NULL);
    if (!fp) return;
    CHECK(fgets(line, sizeof line, fp) != NULL);
    CHECK(strcmp(line, "inc,H00,H01,H10,H11,sxx,syy,sxy,p,q,e_void,Z\n") == 0);
    CHECK(fgets(line, sizeof line, fp) != NULL);
    {
        double v[12];
        CHECK(sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3],
                     &v[4], &v[5], &v[6], &v[7], &v[8], &v[9], &v[10], &v[11]) == 12);
        p0 = v[8];
        CHECK_NEAR(v[5], 100028.513620, 1e-3); /* compression-positive */
        CHECK_NEAR(v[11], 4.16, 1e-9);
    }
    CHECK_NEAR(p0, 99976.3847, 1e-3);
    fclose(fp);
    CHECK_EQ_INT(count_lines("build/t_rve_path.csv"), 7);
    CHECK(file_has("build/t_rve_path.svg", "<svg"));
    CHECK(file_has("build/t_rve_path.out", "RESULT p="));
    /* bad arguments: a message and a non-zero status */
    CHECK(system("build/rve_path --packing examples/data/rve400.txt --dH \"0 1\" > build/t_bad.out 2>&1") !=
          0);
    CHECK(file_has("build/t_bad.out", "needs 4 numbers"));
    CHECK(system("build/rve_path --packing no_such_file --dH \"0 0 0 0\" > build/t_bad.out 2>&1") != 0);
    CHECK(file_has("build/t_bad.out", "no_such_file"));
    CHECK(system("build/rve_path --help > build/t_bad.out 2>&1") == 0);
    CHECK(file_has("build/t_bad.out", "--steps-per-increment"));
}

/* gk_pack: a small packing, consolidated to 100 kPa, readable back */
TEST(gk_pack_makes_a_consolidated_packing) {
    gk_packing pk;
    gk_err e;
    CHECK(
        system(
            "build/gk_pack --dim 2 --n 120 --pressure 1e5 --out build/t_pack.txt > build/t_pack.out 2>&1") ==
        0);
    CHECK(file_has("build/t_pack.out", "RESULT void_ratio="));
    CHECK(gk_packing_read("build/t_pack.txt", &pk, NULL, &e) == GK_OK);
    CHECK(pk.n == 120 && pk.dim == 2);
    CHECK(file_has("build/t_pack.txt", "RVE state: stress"));
    gk_packing_free(&pk);
}

/* the first `ncol` columns of every data row of two CSV files are identical */
static int csv_same(const char *a, const char *b, int ncol) {
    FILE *fa = fopen(a, "r"), *fb = fopen(b, "r");
    char la[2048], lb[2048];
    int same = fa && fb, rows = 0;
    while (same) {
        char *pa = fgets(la, sizeof la, fa), *pb = fgets(lb, sizeof lb, fb);
        int k, c = 0;
        if (!pa || !pb) {
            same = !pa && !pb;
            break;
        }
        for (k = 0; la[k] && lb[k] && c < ncol; ++k) {
            if (la[k] != lb[k]) same = 0;
            if (la[k] == ',') ++c;
        }
        ++rows;
    }
    if (fa) fclose(fa);
    if (fb) fclose(fb);
    return same && rows > 1;
}

/* femdem_biaxial (seed 000): documented CSV header and RESULT line, VTK and
 * SVG outputs; the same result for 1 and 2 threads; a restart from a
 * checkpoint continues to the identical curve; the initial state carries the
 * confining pressure (sigma_xx = sigma_yy = 100 kPa from the reactions of
 * the seed RVE, whose p = 99976 Pa) */
TEST(femdem_biaxial_runs_restarts_and_is_thread_independent) {
    const char *base = "build/femdem_biaxial --nx 2 --ny 2 --element q4 --vtk-every 1 ";
    char cmd[1024];
    FILE *fp;
    char line[1024];
    snprintf(cmd, sizeof cmd, "%s --steps 4 --threads 2 --out build/t_fdA > build/t_fdA.out 2>&1", base);
    CHECK(system(cmd) == 0);
    snprintf(cmd, sizeof cmd, "%s --steps 4 --threads 1 --out build/t_fd1 > build/t_fd1.out 2>&1", base);
    CHECK(system(cmd) == 0);
    snprintf(cmd, sizeof cmd, "%s --steps 2 --threads 2 --out build/t_fdB > build/t_fdB.out 2>&1", base);
    CHECK(system(cmd) == 0);
    snprintf(cmd, sizeof cmd,
             "%s --steps 4 --threads 2 --out build/t_fdB --restart build/t_fdB > build/t_fdB2.out 2>&1",
             base);
    CHECK(system(cmd) == 0);
    fp = fopen("build/t_fdA/biaxial.csv", "r");
    CHECK(fp != NULL);
    if (!fp) return;
    CHECK(fgets(line, sizeof line, fp) != NULL);
    CHECK(strncmp(line, "step,eps_axial,sigma_yy,sigma_xx,eps_v,iterations,seconds", 57) == 0);
    CHECK(fgets(line, sizeof line, fp) != NULL);
    {
        double v[5];
        CHECK(sscanf(line, "%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4]) == 5);
        CHECK_NEAR(v[2], 1e5, 500.0); /* sigma_yy [Pa] at step 0 */
        CHECK_NEAR(v[3], 1e5, 500.0); /* sigma_xx */
    }
    fclose(fp);
    CHECK_EQ_INT(count_lines("build/t_fdA/biaxial.csv"), 6);
    CHECK(file_has("build/t_fdA.out", "RESULT peak_sigma_yy="));
    CHECK(file_has("build/t_fdA.out", "total_seconds="));
    CHECK(file_has("build/t_fdA/gp_0004.vtk", "eps_q"));
    CHECK(file_has("build/t_fdA/gp_0004.vtk", "fabric_anisotropy"));
    CHECK(file_has("build/t_fdA/mesh_0004.vtk", "displacement"));
    CHECK(file_has("build/t_fdA/biaxial_stress.svg", "<svg"));
    CHECK(file_has("build/t_fdA/eps_q_field.svg", "<svg"));
    /* columns step..iterations identical (seconds differ) */
    CHECK(csv_same("build/t_fdA/biaxial.csv", "build/t_fd1/biaxial.csv", 6));
    CHECK(csv_same("build/t_fdA/biaxial.csv", "build/t_fdB/biaxial.csv", 6));
    CHECK(file_has("build/t_fdB2.out", "restarted from"));
    /* bad input: a message and status 2 */
    CHECK(system("build/femdem_biaxial --element q9 > build/t_bad.out 2>&1") != 0);
    CHECK(file_has("build/t_bad.out", "q4 or q8"));
    CHECK(system("build/femdem_biaxial --help > build/t_bad.out 2>&1") == 0);
    CHECK(file_has("build/t_bad.out", "--restart"));
}

/* single-element test (seed 000 sec 3.3, Fig 6): one Q4 element with 4
 * identical RVEs follows the RVE loaded alone under the same drained path */
TEST(femdem_single_element_matches_rve_alone) {
    double d = 1.0;
    FILE *fp;
    char line[1024];
    CHECK(system("build/femdem_biaxial --test single --steps 6 --threads 2 --vtk-every 0 --out build/t_fds "
                 "> build/t_fds.out 2>&1") == 0);
    fp = fopen("build/t_fds.out", "r");
    while (fp && fgets(line, sizeof line, fp))
        if (!strncmp(line, "SINGLE max_rel_diff_to_peak=", 28)) d = atof(line + 28);
    if (fp) fclose(fp);
    printf("    max relative difference of sigma_yy, FEM element vs RVE alone: %.4f\n", d);
    CHECK(d < 0.01); /* before the peak the curves agree (seed Fig 6) */
    CHECK(file_has("build/t_fds/single_element.csv", "sigma_yy_fem,sigma_yy_rve"));
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(rve_path_writes_csv_and_svg);
    RUN(gk_pack_makes_a_consolidated_packing);
    RUN(femdem_biaxial_runs_restarts_and_is_thread_independent);
    RUN(femdem_single_element_matches_rve_alone);
    return gk_test_done();
}
