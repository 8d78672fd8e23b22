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

#include "../examples/footing_mech.h"

#define FT                                                                                                   \
    BUILD "/mpmdem_footing --width 2 --depth 1.5 --nx 4 --ny 3 --B 1.5 --velocity 0.25 --ramp 0.01 --every " \
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
    CHECK(system(FT "--final 0.02 --phi-pressures 20 --phi-strain 0.025 --threads 1 --out " BUILD
                    "/tests/t_mpmft "
                    "> " BUILD "/tests/t_mpmft.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft/footing.csv",
                           "time,d,d_over_B,q,q_over_qs,load_half,kinetic_energy,dem_steps_per_point,seconds,"
                           "wedge_deg,heave_x_over_B,heave_over_B,spiral_phi_deg,spiral_r0_over_B,"
                           "spiral_rms_over_B,spiral_rays"));
    n = read_rows(BUILD "/tests/t_mpmft/footing.csv", r, 16);
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
    phi = gk_test_result(BUILD "/tests/t_mpmft.out", "phi_deg");
    CHECK(phi > 25.0 && phi < 40.0);
    t = tan(pi / 4 + phi * pi / 360.0);
    nqa = gk_test_result(BUILD "/tests/t_mpmft.out", "Nq_analytic");
    CHECK_REL(nqa, t * t * exp(pi * tan(phi * pi / 180.0)), 2e-4);
    nq = gk_test_result(BUILD "/tests/t_mpmft.out", "Nq");
    CHECK(nq > 1.0 && nq < 100.0);
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_mpmft.out", "n_rves"), 12, 0);
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_mpmft.out", "ultimate_reached"), 0, 0); /* 0.02 B: too early */
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft.out", "ultimate load NOT reached"));
    CHECK(gk_test_result(BUILD "/tests/t_mpmft.out", "mpm_steps") > 10);
    CHECK(gk_test_result(BUILD "/tests/t_mpmft.out", "seconds_per_step_per_1000_rves") > 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft/footing_load.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft/rve_mohr.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft/rve_biaxial.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft/eps_q_end.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft/displacement_end.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft/points_000000.vtk", "SCALARS eps_q"));
    /* the mechanism is measured: a wedge angle (this footing has one column under it: coarse) and
     * Prandtl's pi/4 + phi/2 of the measured angle next to it */
    t = gk_test_result(BUILD "/tests/t_mpmft.out", "wedge_deg");
    CHECK(t > 30.0 && t < 80.0);
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_mpmft.out", "wedge_prandtl_deg"), 45.0 + 0.5 * phi,
               0.01); /* both printed to 4 digits */
    /* the heave: the surface row of points (at depth - h/2, exactly the old threshold: missed) rises
     * beyond the footing edge x = b = 0.5 B */
    t = gk_test_result(BUILD "/tests/t_mpmft.out", "heave_x_end_over_B");
    CHECK(t > 0.5 && t <= 2.0 / 1.5);
    CHECK(gk_test_result(BUILD "/tests/t_mpmft.out", "heave_over_B") > 0);
    /* the log spiral: this footing (b = 1.5 cells, 0.02 B) has no ridge to fit; said in words, and
     * RESULT says not found, the numbers nan (never a number made of a NaN) */
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft.out", "log spiral (eq 44) at the last row: not found"));
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_mpmft.out", "spiral_found"), 0, 0);
    /* Prandtl's fan of 90 deg less 10 deg at each end, a ray every 2 deg: 36 searched; the rays with a
     * ridge are counted found or not (here fewer than half, or no spiral would be "not found") */
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_mpmft.out", "spiral_rays_searched"), 36, 0);
    t = gk_test_result(BUILD "/tests/t_mpmft.out", "spiral_rays");
    CHECK(t >= 0 && t <= 36);
    t = gk_test_result(BUILD "/tests/t_mpmft.out", "spiral_rays_end");
    CHECK(t >= 0 && t <= 36);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft.out", "of the 36 rays"));
    CHECK(isnan(gk_test_result(BUILD "/tests/t_mpmft.out", "spiral_phi_deg")));
}

/* --phi-only: the same measurement as the full run above (same options), then the RVE at q_s, and
 * exit before the footing (no footing.csv) */
TEST(footing_phi_only) {
    double phi, e0;
    CHECK(system("rm -rf " BUILD "/tests/t_mpmft_phi && " BUILD
                 "/mpmdem_footing --phi-only --phi-pressures 20 "
                 "--phi-strain 0.025 --threads 1 --out " BUILD "/tests/t_mpmft_phi > " BUILD
                 "/tests/t_mpmft_phi.out "
                 "2>&1") == 0);
    phi = gk_test_result(BUILD "/tests/t_mpmft_phi.out", "phi_deg");
    CHECK(phi == gk_test_result(BUILD "/tests/t_mpmft.out", "phi_deg"));
    CHECK(gk_test_result(BUILD "/tests/t_mpmft_phi.out", "phi_res_deg") ==
          gk_test_result(BUILD "/tests/t_mpmft.out", "phi_res_deg"));
    e0 = gk_test_result(BUILD "/tests/t_mpmft_phi.out", "e0");
    CHECK(e0 > 0.15 && e0 < 0.25); /* the dense packing at 20 kPa */
    CHECK_REL(gk_test_result(BUILD "/tests/t_mpmft_phi.out", "p0"), 2e4, 5e-3);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft_phi/rve_mohr.svg", "<svg"));
    CHECK(system("test -e " BUILD "/tests/t_mpmft_phi/footing.csv") != 0);
    CHECK(system("test -e " BUILD "/tests/t_mpmft_phi/checkpoint.bin") != 0);
}

/* footing_mech.h on synthetic fields with known answers */
TEST(footing_mechanism_synthetic) {
    enum { NX = 30, NY = 20 };
    static double x[NX * NY], y[NX * NY], eq[NX * NY];
    double h = 0.1, b = 0.45, yb = 2.0, xs[NX], uy[NX], pi = 3.14159265358979323846, umax, a, xo;
    int i, j, n = 0, nc, k;
    const double angles[3] = {45.0, 54.8, 62.0};
    /* a band of eps_q along the line from the corner (b, yb) down to the axis at angle alpha: the fitted
     * wedge is alpha (the parabola refinement recovers the depth between the points) */
    for (k = 0; k < 3; ++k) {
        double ta = tan(angles[k] * pi / 180.0);
        n = 0;
        for (j = 0; j < NY; ++j)
            for (i = 0; i < NX; ++i) {
                double px = (i + 0.5) * h, py = yb - (j + 0.5) * h, z = yb - py, zl = (b - px) * ta;
                double dist = (z - zl) * cos(angles[k] * pi / 180.0); /* normal distance to the line */
                x[n] = px, y[n] = py, eq[n] = 0.01 + exp(-dist * dist / (2 * 0.08 * 0.08)), ++n;
            }
        a = fm_wedge_angle(x, y, eq, n, h, b, yb, &nc);
        CHECK_EQ_INT(nc, 4); /* the 4 columns wholly under b = 4.5 h */
        CHECK_NEAR(a, angles[k], 1.0);
    }
    /* no point below the footing: no wedge */
    CHECK(isnan(fm_wedge_angle(x, y, eq, n, h, b, -1.0, &nc)));
    CHECK_EQ_INT(nc, 0);
    /* heave: uplift falling linearly from 10 mm at the edge to 0 at x = 2.5 m; the largest sampled
     * (at x = 0.55) is 9.75 mm: 10 % of that at x = 0.5 + 2 (1 - 0.0975) = 2.305 m (exact: linear) */
    for (i = 0; i < NX; ++i) {
        xs[i] = (NX - 1 - i) * 0.1 + 0.05; /* any order */
        uy[i] = xs[i] <= b ? -0.02 : fmax(0.0, 0.01 * (1.0 - (xs[i] - 0.5) / 2.0));
    }
    xo = fm_heave(xs, uy, NX, b, &umax);
    CHECK_NEAR(xo, 2.305, 1e-9);
    CHECK_NEAR(umax, 0.01 * (1.0 - 0.05 / 2.0), 1e-12);
    for (i = 0; i < NX; ++i) uy[i] = -0.001;
    CHECK(isnan(fm_heave(xs, uy, NX, b, &umax)) && isnan(umax));
    /* Prandtl at phi = 0: the wedge at 45 deg, the passive triangle's base = B: reach 3 b from the axis */
    CHECK_NEAR(fm_prandtl_wedge(0.0), 45.0, 1e-12);
    CHECK_NEAR(fm_prandtl_reach(0.5, 0.0), 1.5, 1e-12);
    CHECK_NEAR(fm_prandtl_wedge(28.1), 59.05, 1e-12); /* Liang & Zhao's 59.05 deg */
}

/* a synthetic eps_q field on points of spacing s: a ridge of half-width 0.08 m along the log spiral
 * r = r0 exp(psi tan phi) (eq 44) about the footing's corner (b, yb), r0 = b / cos(alpha) (the wedge
 * side of angle alpha), over the whole half space below yb; plus, if pole > 0, a 1/r concentration at
 * the corner (the fan's radial shear) */
static int spiral_field(double *x, double *y, double *eq, int nx, int ny, double s, double b, double yb,
                        double alpha, double phi, double pole, int ridge) {
    double d2r = 3.14159265358979323846 / 180.0, r0 = b / cos(alpha * d2r), th0 = 180.0 + alpha;
    int i, j, n = 0;
    for (j = 0; j < ny; ++j)
        for (i = 0; i < nx; ++i) {
            double px = (i + 0.5) * s, py = yb - (j + 0.5) * s, dx = px - b, dy = py - yb;
            double r = sqrt(dx * dx + dy * dy), th = atan2(dy, dx) / d2r, psi, dn;
            psi = th - th0;
            while (psi < -90.0) psi += 360.0; /* the fan and 90 deg either side of it */
            while (psi > 270.0) psi -= 360.0;
            dn = (r - r0 * exp(psi * d2r * tan(phi * d2r))) * cos(phi * d2r); /* normal distance */
            x[n] = px, y[n] = py;
            eq[n] =
                0.01 + (ridge ? 0.3 * exp(-dn * dn / (2 * 0.08 * 0.08)) : 0.0) + pole * b / fmax(r, 0.5 * s);
            ++n;
        }
    return n;
}

/* fm_spiral: a ridge drawn along an exact log spiral gives its angle back within 1 deg (with and
 * without the pole's concentration, at the wedge of Prandtl's mechanism and at a steeper one); no ridge
 * (uniform, or only the pole's 1/r decay, or no points) is NOT FOUND, every number NAN */
TEST(footing_spiral_synthetic) {
    enum { NX = 70, NY = 40 };
    static double x[NX * NY], y[NX * NY], eq[NX * NY];
    const double phis[3] = {20.0, 28.1, 35.0};
    double s = 0.1, b = 0.5, yb = 4.0, a;
    int k, n;
    fm_spiral_fit F;
    for (k = 0; k < 3; ++k) {
        a = 45.0 + 0.5 * phis[k];
        n = spiral_field(x, y, eq, NX, NY, s, b, yb, a, phis[k], 0.0, 1);
        CHECK_EQ_INT(fm_spiral(x, y, eq, n, s, b, yb, a, phis[k], &F), 1);
        CHECK_NEAR(F.phi, phis[k], 1.0);
        CHECK_REL(F.r0, b / cos(a * 3.14159265358979323846 / 180.0), 0.05);
        CHECK(F.rms < 0.02);  /* the spiral of eq 44 at the same angle: within a fifth of a point spacing */
        CHECK(F.nrays >= 30); /* the fan of 90 deg less 2 x 10, every 2 deg: 36 rays */
        /* the pole's 1/r concentration on top: the ridge is still the spiral */
        n = spiral_field(x, y, eq, NX, NY, s, b, yb, a, phis[k], 0.2, 1);
        CHECK_EQ_INT(fm_spiral(x, y, eq, n, s, b, yb, a, phis[k], &F), 1);
        CHECK_NEAR(F.phi, phis[k], 1.0);
        /* the misfit grows when eq 44 is asked at another angle */
        CHECK_EQ_INT(fm_spiral(x, y, eq, n, s, b, yb, a, phis[k] + 8.0, &F), 1);
        CHECK_NEAR(F.phi, phis[k], 1.0);
        CHECK(F.rms > 0.05);
    }
    /* a steeper wedge (rough base): the spiral from its tip, fan 135 + phi/2 - alpha */
    n = spiral_field(x, y, eq, NX, NY, s, b, yb, 66.0, 28.1, 0.1, 1);
    CHECK_EQ_INT(fm_spiral(x, y, eq, n, s, b, yb, 66.0, 28.1, &F), 1);
    CHECK_NEAR(F.phi, 28.1, 1.0);
    CHECK_NEAR(F.fan, 135.0 + 14.05 - 66.0, 1e-12);
    /* the rays searched: every 2 deg over the fan less 10 deg at each end (36 over Prandtl's 90 deg, 32
     * over 83.05); none when the fan is narrower than the two margins or an angle is not finite */
    CHECK_EQ_INT(fm_spiral_nsearch(59.05, 28.1), 36);
    CHECK_EQ_INT(fm_spiral_nsearch(66.0, 28.1), 32);
    CHECK_EQ_INT(fm_spiral_nsearch(140.0, 28.1), 0);
    CHECK_EQ_INT(fm_spiral_nsearch(NAN, 28.1), 0);
    /* a ridge on two short stretches of the fan only (psi 13-17 and 71-75 deg of 90; with the kernel's
     * reach, ridges on fewer than half of the 36 rays, spanning more than half of the fan): bumps, no
     * spiral */
    n = spiral_field(x, y, eq, NX, NY, s, b, yb, 59.05, 28.1, 0.0, 1);
    for (k = 0; k < n; ++k) {
        double psi = atan2(y[k] - yb, x[k] - b) * 180.0 / 3.14159265358979323846 - 239.05;
        while (psi < -90.0) psi += 360.0;
        while (psi > 270.0) psi -= 360.0;
        if (!((psi > 13.0 && psi < 17.0) || (psi > 71.0 && psi < 75.0))) eq[k] = 0.01;
    }
    CHECK_EQ_INT(fm_spiral(x, y, eq, n, s, b, yb, 59.05, 28.1, &F), 0);
    CHECK(F.nrays >= 10 && F.nrays < 18 && isnan(F.phi));
    /* no ridge: uniform, the pole's decay alone, no points */
    n = spiral_field(x, y, eq, NX, NY, s, b, yb, 59.05, 28.1, 0.0, 0);
    CHECK_EQ_INT(fm_spiral(x, y, eq, n, s, b, yb, 59.05, 28.1, &F), 0);
    CHECK(!F.found && isnan(F.phi) && isnan(F.r0) && isnan(F.rms));
    n = spiral_field(x, y, eq, NX, NY, s, b, yb, 59.05, 28.1, 0.2, 0);
    CHECK_EQ_INT(fm_spiral(x, y, eq, n, s, b, yb, 59.05, 28.1, &F), 0);
    CHECK(!F.found && isnan(F.phi) && F.nrays < FM_SP_MINRAYS);
    CHECK_EQ_INT(fm_spiral(x, y, eq, 0, s, b, yb, 59.05, 28.1, &F), 0);
    CHECK(isnan(F.phi));
}

/* the ultimate-load rule on a curve that peaks: a longer run of the same
 * model reaches a peak (this coarse footing at d/B ~ 0.04) and reports it */
TEST(footing_ultimate_found) {
    double du, nq, qu;
    CHECK(system(FT "--final 0.08 --smooth 0.02 --phi-deg 30 --threads 1 --out " BUILD "/tests/t_mpmft_u "
                    "> " BUILD "/tests/t_mpmft_u.out 2>&1") == 0);
    CHECK_NEAR(gk_test_result(BUILD "/tests/t_mpmft_u.out", "ultimate_reached"), 1, 0);
    du = gk_test_result(BUILD "/tests/t_mpmft_u.out", "d_ult_over_B");
    nq = gk_test_result(BUILD "/tests/t_mpmft_u.out", "Nq");
    qu = gk_test_result(BUILD "/tests/t_mpmft_u.out", "q_ult");
    CHECK(du > 0.0 && du < 0.08 - 0.02);
    CHECK_REL(nq, qu / 2e4, 1e-4);
    CHECK(nq > 3.0 && nq < 60.0);
}

/* RVEs and the MPM run in parallel: one and two threads give the same curve */
TEST(footing_thread_independent) {
    /* passive waiting: spinning OpenMP threads crawl on a machine busy with other jobs */
    CHECK(system("OMP_WAIT_POLICY=passive " FT "--final 0.02 --phi-deg 30 --threads 2 --out " BUILD
                 "/tests/t_mpmft2 "
                 "> " BUILD "/tests/t_mpmft2.out 2>&1") == 0);
    CHECK(system(FT "--final 0.02 --phi-deg 30 --threads 1 --out " BUILD "/tests/t_mpmft1 > " BUILD
                    "/tests/t_mpmft1.out 2>&1") == 0);
    CHECK(gk_test_result(BUILD "/tests/t_mpmft1.out", "Nq") ==
          gk_test_result(BUILD "/tests/t_mpmft2.out", "Nq"));
    CHECK(system("cut -d, -f1-8,10- " BUILD "/tests/t_mpmft1/footing.csv > " BUILD "/tests/t_mpmft1.c && "
                 "cut -d, -f1-8,10- " BUILD "/tests/t_mpmft2/footing.csv > " BUILD "/tests/t_mpmft2.c && "
                 "cmp -s " BUILD "/tests/t_mpmft1.c " BUILD "/tests/t_mpmft2.c") == 0);
}

/* a checkpoint half-way, then --restart: the same curve to the last digit */
TEST(footing_restart_identical) {
    int rc = system(FT "--final 0.01 --phi-deg 30 --threads 1 --out " BUILD "/tests/t_mpmft_a > " BUILD
                       "/tests/t_mpmft_a.out 2>&1 "
                       "&& " FT "--final 0.02 --phi-deg 30 --threads 1 --restart " BUILD
                       "/tests/t_mpmft_a --out " BUILD "/tests/t_mpmft_b "
                       "> " BUILD "/tests/t_mpmft_b.out 2>&1");
    CHECK(rc == 0);
    CHECK(gk_test_result(BUILD "/tests/t_mpmft_b.out", "Nq") ==
          gk_test_result(BUILD "/tests/t_mpmft1.out", "Nq"));
    CHECK(system("cut -d, -f1-8,10- " BUILD "/tests/t_mpmft_b/footing.csv > " BUILD "/tests/t_mpmft_b.c && "
                 "cmp -s " BUILD "/tests/t_mpmft_b.c " BUILD "/tests/t_mpmft1.c") == 0);
}

/* bad input: a message and a non-zero exit, nothing run */
TEST(footing_bad_arguments) {
    const char *o = " > " BUILD "/tests/t_mpmft_bad.out 2>&1";
    char cmd[512];
#define BAD(args, msg)                                                                                  \
    snprintf(cmd, sizeof cmd, BUILD "/mpmdem_footing --out " BUILD "/tests/t_mpmft_bad %s%s", args, o); \
    CHECK(system(cmd) != 0);                                                                            \
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft_bad.out", msg))
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
    BAD("--phi-only --phi-deg 30", "cannot take --phi-deg");
    /* bad input changes nothing: no output folder is made before the inputs are read */
    CHECK(system("rm -rf " BUILD "/tests/t_mpmft_bad") == 0);
    BAD("--packing /nonexistent", "nonexistent");
    BAD("--phi-deg 30 --restart /nonexistent", "cannot open");
    CHECK(system("test -e " BUILD "/tests/t_mpmft_bad") != 0);
    BAD("--phi-pressures 10,,20", "--phi-pressures");
    BAD("--phi-pressures 10,20,", "--phi-pressures");
    BAD("--every 0.5 --final 0.2", "--every 0.5 is out of range");
    BAD("--out " BUILD "/tests/t_mpmft_bad.out", "is a file, not a folder");
#undef BAD
    CHECK(system(BUILD "/mpmdem_footing --help > " BUILD "/tests/t_mpmft_bad.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft_bad.out", "--phi-pressures"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft_bad.out", "--paper"));
    CHECK(gk_test_file_has(BUILD "/tests/t_mpmft_bad.out", "--dem-rule"));
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(footing_runs_and_loads);
    RUN(footing_phi_only);
    RUN(footing_mechanism_synthetic);
    RUN(footing_spiral_synthetic);
    RUN(footing_ultimate_found);
    RUN(footing_thread_independent);
    RUN(footing_restart_identical);
    RUN(footing_bad_arguments);
    return gk_test_done();
}
