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
        CHECK(sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5],
                     &v[6], &v[7], &v[8], &v[9], &v[10], &v[11]) == 12);
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
    CHECK(system("build/rve_path --packing examples/data/rve400.txt --dH \"0 1\" > build/t_bad.out 2>&1") != 0);
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
    CHECK(system("build/gk_pack --dim 2 --n 120 --pressure 1e5 --out build/t_pack.txt > build/t_pack.out 2>&1") == 0);
    CHECK(file_has("build/t_pack.out", "RESULT void_ratio="));
    CHECK(gk_packing_read("build/t_pack.txt", &pk, NULL, &e) == GK_OK);
    CHECK(pk.n == 120 && pk.dim == 2);
    CHECK(file_has("build/t_pack.txt", "RVE state: stress"));
    gk_packing_free(&pk);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(rve_path_writes_csv_and_svg);
    RUN(gk_pack_makes_a_consolidated_packing);
    return gk_test_done();
}
