/* test_dem.c - the RVE (gk_dem.h) and homogenisation (gk_homog.h). */
#define GK_DEM_PAR_MIN 64   /* let the 400-disk RVE use threads, to test thread invariance */
#define GK_DEM_GATHER_MAX 0 /* one thread scatters: its thread tests compare that with the threads' gather */
#define GK_DEM_FREC_MAX 600 /* 3D: 512 spheres scatter through the force records, 1000 without */
#define GK_IMPLEMENTATION
#include "gk_homog.h"
#include "gk_test.h"
#include <stdlib.h>

#ifdef GK_TEST_QUICK /* sanitizer builds: fewer steps */
#define QUICK(full, quick) (quick)
#else
#define QUICK(full, quick) (full)
#endif

static const char *RVE400 = "examples/data/rve400.txt";

static gk_result load_rve(gk_rve *rve, gk_rve_def *def, const char *path) {
    gk_packing pk;
    gk_err e;
    gk_result r = gk_packing_read(path, &pk, NULL, &e);
    if (r) {
        printf("    cannot read %s: %s\n", path, e.msg);
        return r;
    }
    r = gk_rve_create(rve, def, &pk);
    if (r) printf("    create: %s\n", gk_rve_error(rve));
    gk_packing_free(&pk);
    return r;
}

static int same_state(const gk_rve *a, const gk_rve *b) {
    size_t na = gk_rve_state_size(a), nb = gk_rve_state_size(b);
    unsigned char *ba, *bb;
    int same;
    if (na != nb) return 0;
    ba = (unsigned char *)malloc(na);
    bb = (unsigned char *)malloc(nb);
    gk_rve_save(a, ba, na, NULL);
    gk_rve_save(b, bb, nb, NULL);
    same = memcmp(ba, bb, na) == 0;
    free(ba);
    free(bb);
    return same;
}

/* The Guo & Zhao 2014 packing: its Love stress (Guo & Zhao 2014 eq 5), void ratio and
 * coordination equal what YADE's getStress(), voidratio and
 * avgNumInteractions report in the file header, to the printed digits. */
TEST(seed_packing_reproduces_yade) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    gk_coordination z;
    double s[9];
    if (load_rve(&rve, &def, RVE400)) {
        CHECK(0);
        return;
    }
    CHECK(gk_rve_refresh(&rve) == GK_OK);
    gk_rve_stress(&rve, s);
    CHECK_NEAR(s[0], -100028.513620, 2e-6);
    CHECK_NEAR(s[4], -99924.255780, 2e-6);
    CHECK_NEAR(s[1], 617.394902, 2e-6);
    CHECK_NEAR(s[3], 617.394902, 2e-6);
    CHECK_NEAR(gk_homog_void_ratio(&rve), 0.175001, 1e-6);
    CHECK(gk_homog_coordination(&rve, &z) == GK_OK);
    CHECK_EQ_INT(z.contacts, 832);
    CHECK_NEAR(z.z, 4.16, 1e-12);
    CHECK_NEAR(z.z_nofree, 4.286082, 1e-6);
    CHECK(z.z_mech >= z.z);
    /* the seed's time step 3.16e-5 s is below our eq-19 critical step */
    CHECK(rve.dt_crit > 3.1602e-5);
    /* p and q (Guo & Zhao 2014 eqs 6, 7): compression-positive p, q = |s1 - s2| / 2 */
    CHECK_NEAR(gk_stress_p(s, 2), 0.5 * (100028.513620 + 99924.255780), 1e-5);
    {
        double a = -100028.513620, b = -99924.255780, c = 617.394902;
        CHECK_NEAR(gk_stress_q(s, 2), sqrt(0.25 * (a - b) * (a - b) + c * c), 1e-5);
    }
    gk_rve_destroy(&rve);
}

/* hexagonal lattice of equal disks, spacing a = 2r - delta, in a periodic cell */
static gk_result hex_lattice(gk_rve *rve, gk_rve_def *def, int nx, int ny, double r, double delta) {
    gk_packing pk;
    gk_err e;
    gk_result res;
    double a = 2 * r - delta;
    int ix, iy, p = 0;
    res = gk_packing_init(&pk, 2, nx * ny, NULL, &e);
    if (res) return res;
    gk_m3_identity(pk.h);
    pk.h[0] = nx * a;
    pk.h[4] = ny * a * sqrt(3.0) / 2;
    for (iy = 0; iy < ny; ++iy)
        for (ix = 0; ix < nx; ++ix) {
            pk.x[p] = (ix + 0.5 * (iy % 2) + 0.25) * a;
            pk.y[p] = (iy + 0.5) * a * sqrt(3.0) / 2;
            pk.r[p] = r;
            ++p;
        }
    res = gk_rve_create(rve, def, &pk);
    gk_packing_free(&pk);
    return res;
}

/* Love stress of a hexagonal lattice (3 contacts per particle at 0, 60, 120
 * degrees, sum n (x) n = 3/2 I, area a^2 sqrt(3)/2 per particle):
 *   sigma = -sqrt(3) k_n delta / (a t) I. */
TEST(love_stress_hexagonal_lattice) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    double r = 0.005, delta = 2e-6, a = 2 * r - delta, s[9], kn;
    def.mat.friction = 0.3;
    CHECK(hex_lattice(&rve, &def, 8, 8, r, delta) == GK_OK);
    CHECK(gk_rve_refresh(&rve) == GK_OK);
    gk_rve_stress(&rve, s);
    kn = def.mat.young * r;
    CHECK_EQ_INT(rve.ncontacts, 3 * 64);
    CHECK_REL(s[0], -sqrt(3.0) * kn * delta / (a * def.thickness), 1e-9);
    CHECK_REL(s[4], -sqrt(3.0) * kn * delta / (a * def.thickness), 1e-9);
    CHECK_NEAR(s[1], 0.0, 1e-9 * fabs(s[0]));
    /* a perfect lattice is balanced and isotropic in fabric */
    {
        double phi[9], Fa[9];
        CHECK_NEAR(gk_homog_fabric(&rve, phi, Fa), 0.0, 1e-12);
        CHECK_NEAR(phi[0], 0.5, 1e-12);
    }
    gk_rve_destroy(&rve);
}

/* simple cubic lattice of spheres: sigma = -k_n delta / a^2 I (3 contacts per
 * particle along the axes, volume a^3 per particle) */
TEST(love_stress_cubic_lattice_3d) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    gk_packing pk;
    gk_err e;
    double r = 0.005, delta = 3e-6, a = 2 * r - delta, s[9];
    int n = 6, i, j, k, p = 0;
    def.mat.kn = 3e5;
    CHECK(gk_packing_init(&pk, 3, n * n * n, NULL, &e) == GK_OK);
    gk_m3_identity(pk.h);
    pk.h[0] = pk.h[4] = pk.h[8] = n * a;
    for (i = 0; i < n; ++i)
        for (j = 0; j < n; ++j)
            for (k = 0; k < n; ++k) {
                pk.x[p] = (i + 0.5) * a;
                pk.y[p] = (j + 0.5) * a;
                pk.z[p] = (k + 0.5) * a;
                pk.r[p] = r;
                ++p;
            }
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_OK);
    gk_packing_free(&pk);
    CHECK(gk_rve_refresh(&rve) == GK_OK);
    gk_rve_stress(&rve, s);
    CHECK_EQ_INT(rve.ncontacts, 3 * n * n * n);
    for (i = 0; i < 3; ++i) CHECK_REL(s[4 * i], -3e5 * delta / (a * a), 1e-9);
    CHECK_NEAR(s[1] + s[2] + s[5], 0.0, 1e-9 * fabs(s[0]));
    gk_rve_destroy(&rve);
}

/* finite difference of the Love stress under an affine map I + eps H (no
 * particle motion: huge masses; no slip: huge friction) */
static void fd_stress(gk_rve *rve, const double H[9], double eps, double dsig[9]) {
    gk_rve_state st;
    double dH[9], sp[9], sm[9];
    int k;
    gk_rve_state_init(&st, NULL);
    gk_rve_state_save(&st, rve);
    for (k = 0; k < 9; ++k) dH[k] = eps * H[k];
    gk_rve_deform(rve, dH, 1);
    gk_rve_refresh(rve);
    gk_rve_stress(rve, sp);
    gk_rve_state_restore(&st, rve);
    for (k = 0; k < 9; ++k) dH[k] = -eps * H[k];
    gk_rve_deform(rve, dH, 1);
    gk_rve_refresh(rve);
    gk_rve_stress(rve, sm);
    gk_rve_state_restore(&st, rve);
    for (k = 0; k < 9; ++k) dsig[k] = (sp[k] - sm[k]) / (2 * eps);
    gk_rve_state_free(&st);
}

static double contract(const double *D, int dim, const double H[9], int i, int j) {
    double s = 0;
    int k, l;
    for (k = 0; k < dim; ++k)
        for (l = 0; l < dim; ++l) s += D[((i * dim + j) * dim + k) * dim + l] * H[3 * k + l];
    return s;
}

/* Taylor tangent, Guo & Zhao 2014 eq 9: at vanishing preload it IS the derivative of
 * the Love stress under an affine, no-slip map (hexagonal lattice, overlap
 * 1e-7 r: the initial-stress terms are 1e-7 of k_n). */
TEST(taylor_tangent_is_fd_tangent_at_vanishing_preload) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    double D[16], Hs[3][9] = {{1, 0, 0, 0, 0, 0, 0, 0, 0},
                              {0, 0, 0, 0, 1, 0, 0, 0, 0},
                              {0, 0.5, 0, 0.5, 0, 0, 0, 0, 0}};
    int c, i, j;
    def.mat.density = 1e20; /* particles do not move within one step */
    def.dt = 1e-6;          /* (an automatic dt would grow with sqrt(m)) */
    def.mat.friction = 1e3; /* and never slip */
    def.damping = 0;
    CHECK(hex_lattice(&rve, &def, 8, 8, 0.005, 0.005e-7) == GK_OK);
    CHECK(gk_rve_refresh(&rve) == GK_OK);
    CHECK(gk_homog_tangent(&rve, 0, D) == GK_OK);
    for (c = 0; c < 3; ++c) {
        double ds[9];
        fd_stress(&rve, Hs[c], 1e-10, ds);
        for (i = 0; i < 2; ++i)
            for (j = 0; j < 2; ++j) CHECK_NEAR(ds[3 * i + j], contract(D, 2, Hs[c], i, j), 1e-5 * fabs(D[0]));
    }
    /* hexagonal lattice: isotropic, D_xxxx = D_yyyy */
    CHECK_REL(D[0], D[15], 1e-9);
    gk_rve_destroy(&rve);
}

/* With GK_TANGENT_GEOMETRIC the tangent is the exact derivative of the Love
 * stress of a prestressed random packing (seed packing at 100 kPa) under any
 * symmetric affine no-slip map, to finite-difference accuracy. */
TEST(full_tangent_is_fd_tangent_prestressed) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    double D[16], De[16],
        Hs[4][9] = {{1, 0, 0, 0, 0, 0, 0, 0, 0},
                    {0, 0, 0, 0, 1, 0, 0, 0, 0},
                    {0, 1, 0, 1, 0, 0, 0, 0, 0},
                    {0.3, -0.7, 0, -0.7, -1.1, 0, 0, 0, 0}};
    double maxerr = 0, maxerr_e = 0, scale;
    int c, i, j;
    def.mat.density = 1e20; /* no particle motion in one step of 1 us */
    def.dt = 1e-6;
    def.mat.friction = 1e3;
    def.damping = 0;
    if (load_rve(&rve, &def, RVE400)) {
        CHECK(0);
        return;
    }
    CHECK(gk_rve_refresh(&rve) == GK_OK);
    CHECK(gk_homog_tangent(&rve, GK_TANGENT_GEOMETRIC | GK_TANGENT_RAW, D) == GK_OK);
    CHECK(gk_homog_tangent(&rve, GK_TANGENT_RAW, De) == GK_OK);
    scale = fabs(D[0]);
    for (c = 0; c < 4; ++c) {
        double ds[9];
        fd_stress(&rve, Hs[c], 1e-8, ds);
        for (i = 0; i < 2; ++i)
            for (j = 0; j < 2; ++j) {
                double e1 = fabs(ds[3 * i + j] - contract(D, 2, Hs[c], i, j));
                double e2 = fabs(ds[3 * i + j] - contract(De, 2, Hs[c], i, j));
                if (e1 > maxerr) maxerr = e1;
                if (e2 > maxerr_e) maxerr_e = e2;
            }
    }
    printf("    |D:H - FD| max %.3e (full), %.3e (eq 9 only); D_xxxx %.3e Pa\n", maxerr, maxerr_e, scale);
    CHECK(maxerr < 1e-6 * scale);
    /* and eq 9 alone misses the initial-stress terms, of order sigma: visible here */
    CHECK(maxerr_e > 1e3 * maxerr);
    CHECK(maxerr_e < 2e-2 * scale);
    gk_rve_destroy(&rve);
}

static double h_d_h(const double *D, int dim, const double H[9]) {
    double s = 0;
    int i, j;
    for (i = 0; i < dim; ++i)
        for (j = 0; j < dim; ++j) s += H[3 * i + j] * contract(D, dim, H, i, j);
    return s;
}

/* the relaxed tangent against the DEM: from equilibrium (L = 0, damped steps),
 * an affine dH = 1e-7 H without slip, then damped steps at a fixed cell until
 * the particles are in equilibrium again: d sigma : H / 1e-7 vs H:D:H */
static void relaxed_vs_dem(gk_rve *rve, int nh, const double (*Hs)[9], double rtol) {
    gk_rve_state st;
    double Dt[81], Dr[81], s0[9], s1[9], L0[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    int c, k, dim = rve->dim;
    CHECK(gk_rve_set_friction(rve, 1e3) == GK_OK); /* no slip */
    CHECK(gk_rve_set_velocity_gradient(rve, L0) == GK_OK);
    CHECK(gk_rve_step(rve, 2000) == GK_OK);
    CHECK(gk_rve_refresh(rve) == GK_OK);
    CHECK(gk_homog_tangent(rve, 0, Dt) == GK_OK);
    CHECK(gk_homog_tangent(rve, GK_TANGENT_RELAXED, Dr) == GK_OK);
    gk_rve_stress(rve, s0);
    gk_rve_state_init(&st, NULL);
    CHECK(gk_rve_state_save(&st, rve) == GK_OK);
    for (c = 0; c < nh; ++c) {
        double dH[9], dem = 0.0, um, ur;
        for (k = 0; k < 9; ++k) dH[k] = 1e-7 * Hs[c][k];
        CHECK(gk_rve_state_restore(&st, rve) == GK_OK);
        CHECK(gk_rve_deform(rve, dH, 1) == GK_OK);
        CHECK(gk_rve_set_velocity_gradient(rve, L0) == GK_OK);
        CHECK(gk_rve_step(rve, 2000) == GK_OK);
        CHECK(gk_rve_refresh(rve) == GK_OK);
        gk_homog_unbalanced(rve, &um, &ur);
        gk_rve_stress(rve, s1);
        for (k = 0; k < 9; ++k) dem += (s1[k] - s0[k]) / 1e-7 * Hs[c][k];
        printf("    %dD H%d: d sigma:H / 1e-7 DEM %.4e, relaxed %.4e, eq 9 %.4e Pa (unbalanced %.1e)\n", dim,
               c, dem, h_d_h(Dr, dim, Hs[c]), h_d_h(Dt, dim, Hs[c]), um);
        CHECK(um < 1e-9);
        CHECK_REL(h_d_h(Dr, dim, Hs[c]), dem, rtol);
        CHECK(h_d_h(Dt, dim, Hs[c]) > 1.1 * dem);
        CHECK(h_d_h(Dr, dim, Hs[c]) > 0.0 && h_d_h(Dr, dim, Hs[c]) < h_d_h(Dt, dim, Hs[c]));
    }
    gk_rve_state_free(&st);
}

/* GK_TANGENT_RELAXED on a Bravais lattice (one particle per primitive cell):
 * every particle sees the same surroundings, the affine map is already in
 * equilibrium and the relaxed tangent is eq 9 itself. */
TEST(relaxed_tangent_of_a_bravais_lattice_is_taylor) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    double Dt[16], Dr[16];
    int k;
    def.mat.friction = 0.5;
    CHECK(hex_lattice(&rve, &def, 8, 8, 0.005, 0.005e-3) == GK_OK);
    CHECK(gk_rve_refresh(&rve) == GK_OK);
    CHECK(gk_homog_tangent(&rve, 0, Dt) == GK_OK);
    CHECK(gk_homog_tangent(&rve, GK_TANGENT_RELAXED, Dr) == GK_OK);
    for (k = 0; k < 16; ++k) CHECK_NEAR(Dr[k], Dt[k], 1e-8 * Dt[0]);
    CHECK(gk_homog_tangent(&rve, GK_TANGENT_RELAXED | GK_TANGENT_GEOMETRIC, Dr) == GK_ERR_ARG);
    for (k = 0; k < 16; ++k) CHECK(Dr[k] == 0.0);
    gk_rve_destroy(&rve);
}

/* A chain of disks along x (radii a, a, b repeated 4 times; no contact in y):
 * under dH_xx the springs are in series, so the relaxed D_xxxx is
 *   L^2 / (V sum_c 1/k_c)   (L the chain length, V the cell volume)
 * while eq 9 gives sum_c k_c l_c^2 / V (Cauchy-Schwarz: larger unless every
 * k_c l_c is the same). Under shear the chain rolls: the relaxed D_xyxy is 0. */
TEST(relaxed_tangent_of_a_chain_is_springs_in_series) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    gk_packing pk;
    gk_err e;
    double ra = 0.005, rb = 0.008, ov = 1e-5, x = 0.0, L, V, flex = 0.0, taylor = 0.0, Dt[16], Dr[16];
    double rad[12], len[12];
    int p;
    def.mat.friction = 0.5;
    for (p = 0; p < 12; ++p) rad[p] = p % 3 == 2 ? rb : ra;
    CHECK(gk_packing_init(&pk, 2, 12, NULL, &e) == GK_OK);
    for (p = 0; p < 12; ++p) {
        len[p] = rad[p] + rad[(p + 1) % 12] - ov; /* contact p -> p + 1 */
        pk.x[p] = x, pk.y[p] = 0.025, pk.r[p] = rad[p];
        x += len[p];
    }
    L = x;
    gk_m3_identity(pk.h);
    pk.h[0] = L, pk.h[4] = 0.05;
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_OK);
    gk_packing_free(&pk);
    CHECK(gk_rve_refresh(&rve) == GK_OK);
    CHECK_EQ_INT(rve.ncontacts, 12);
    V = gk_rve_volume(&rve);
    for (p = 0; p < 12; ++p) {
        gk_real kn, fn, kt;
        gk_contact_stiffness(&rve.K, rve.def.mat.law, (gk_real)rad[p], (gk_real)rad[(p + 1) % 12],
                             (gk_real)ov, &kn, &fn, &kt);
        flex += 1.0 / kn, taylor += kn * len[p] * len[p];
    }
    CHECK(gk_homog_tangent(&rve, 0, Dt) == GK_OK);
    CHECK(gk_homog_tangent(&rve, GK_TANGENT_RELAXED, Dr) == GK_OK);
    printf("    D_xxxx: eq 9 %.6e, relaxed %.6e, springs in series %.6e Pa\n", Dt[0], Dr[0],
           L * L / (V * flex));
    CHECK_REL(Dt[0], taylor / V, 1e-6);
    CHECK_REL(Dr[0], L * L / (V * flex), 1e-6);
    CHECK(Dr[0] < 0.97 * Dt[0]);       /* the two differ by 4 % here */
    CHECK(Dt[5] > 0.1 * Dt[0]);        /* eq 9 resists shear with k_t ... */
    CHECK(fabs(Dr[5]) < 1e-6 * Dt[5]); /* ... the relaxed chain rolls */
    gk_rve_destroy(&rve);
}

/* GK_TANGENT_RELAXED is the quasi-static response of the seed packing
 * (relaxed_vs_dem) to the initial-stress terms (order sigma / D_xxxx ~ 1e-3,
 * not in the spring model). Eq 9 is 14-35 % stiffer; the relaxed tangent lies
 * between 0 and it (H:D:H, a Schur complement of a positive semi-definite
 * energy). */
TEST(relaxed_tangent_is_the_quasistatic_dem_response) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    const double Hs[4][9] = {{1, 0, 0, 0, -1, 0, 0, 0, 0},
                             {0, 1, 0, 1, 0, 0, 0, 0, 0},
                             {1, 0, 0, 0, 1, 0, 0, 0, 0},
                             {0.3, -0.7, 0, -0.7, -1.1, 0, 0, 0, 0}};
    def.damping = 0.7;
    if (load_rve(&rve, &def, RVE400)) {
        CHECK(0);
        return;
    }
    relaxed_vs_dem(&rve, 4, Hs, 1.5e-2);
    gk_rve_destroy(&rve);
}

/* save -> run -> restore -> run gives bit-identical states (friction, history,
 * rebuilds and cell flips included) */
TEST(save_restore_is_bitwise) {
    gk_rve a, b;
    gk_rve_def def = gk_rve_def_default();
    gk_rve_state st;
    double dH[9] = {1e-3, 4e-3, 0, 1e-3, -2e-3, 0, 0, 0, 0};
    int k;
    if (load_rve(&a, &def, RVE400) || load_rve(&b, &def, RVE400)) {
        CHECK(0);
        return;
    }
    for (k = 0; k < 3; ++k) CHECK(gk_rve_deform(&a, dH, 100) == GK_OK);
    gk_rve_state_init(&st, NULL);
    CHECK(gk_rve_state_save(&st, &a) == GK_OK);
    for (k = 0; k < 5; ++k) CHECK(gk_rve_deform(&a, dH, 100) == GK_OK);
    CHECK(gk_rve_state_restore(&st, &b) == GK_OK); /* into a different RVE object */
    for (k = 0; k < 5; ++k) CHECK(gk_rve_deform(&b, dH, 100) == GK_OK);
    CHECK(a.rebuilds > 1);
    CHECK(same_state(&a, &b));
    /* and restoring into the same object works too */
    CHECK(gk_rve_state_restore(&st, &a) == GK_OK);
    for (k = 0; k < 5; ++k) CHECK(gk_rve_deform(&a, dH, 100) == GK_OK);
    CHECK(same_state(&a, &b));
    gk_rve_state_free(&st);
    gk_rve_destroy(&a);
    gk_rve_destroy(&b);
}

/* positions, velocities, forces, spins and torques bit for bit (not the stress) */
static int same_physics_motion(const gk_rve *a, const gk_rve *b) {
    int k, p;
    for (k = 0; k < 3; ++k)
        for (p = 0; p < a->n; ++p) {
            if (k < a->dim &&
                (a->s[k][p] != b->s[k][p] || a->v[k][p] != b->v[k][p] || a->f[k][p] != b->f[k][p]))
                return 0;
            if (a->w[k] && (a->w[k][p] != b->w[k][p] || a->t[k][p] != b->t[k][p])) return 0;
        }
    return 1;
}

/* physical state (not the lists): positions, velocities, spins, forces, stress */
static int same_physics(const gk_rve *a, const gk_rve *b) {
    int k;
    if (!same_physics_motion(a, b)) return 0;
    for (k = 0; k < 9; ++k)
        if (a->stress[k] != b->stress[k]) return 0;
    return 1;
}

/* The Verlet skin (so the lists and when they are rebuilt) changes no result
 * bit: a pair out of contact contributes exactly zero and positions wrap
 * every step, independently of the lists. */
TEST(skin_does_not_change_results) {
    gk_rve a, b;
    gk_rve_def da = gk_rve_def_default(), db = gk_rve_def_default();
    double dH[9] = {-2e-3, 3e-3, 0, 0, 1e-3, 0, 0, 0, 0};
    int k;
    db.skin = 3.0 * 0.1 * 0.005; /* three times the default */
    if (load_rve(&a, &da, RVE400) || load_rve(&b, &db, RVE400)) {
        CHECK(0);
        return;
    }
    for (k = 0; k < 8; ++k) {
        CHECK(gk_rve_deform(&a, dH, 100) == GK_OK);
        CHECK(gk_rve_deform(&b, dH, 100) == GK_OK);
    }
    CHECK(a.rebuilds != b.rebuilds || a.pl.n != b.pl.n); /* the lists really differ */
    CHECK(same_physics(&a, &b));
    gk_rve_destroy(&a);
    gk_rve_destroy(&b);
}

/* A rebuild carries the contact history over from the old list to the new
 * one. When the outer list is the one the old list was filtered from, each
 * pair's old index is looked up (outer_in); otherwise the two lists are
 * merged on (i, j). Both give the same map: b merges at every rebuild, a looks
 * up wherever it can, and their states stay equal bit for bit. */
TEST(rebuild_lookup_equals_merge) {
    gk_rve a, b;
    gk_rve_def def = gk_rve_def_default();
    double L[9] = {0, 40.0, 0, 20.0, -30.0, 0, 0, 0, 0};
    int k, lookups = 0;
    if (load_rve(&a, &def, RVE400) || load_rve(&b, &def, RVE400)) {
        CHECK(0);
        return;
    }
    CHECK(gk_rve_set_velocity_gradient(&a, L) == GK_OK);
    CHECK(gk_rve_set_velocity_gradient(&b, L) == GK_OK);
    for (k = 0; k < 3000; ++k) {
        long r0 = a.rebuilds;
        int ok = a.outer_in_ok;
        double ho = a.ho0[1]; /* the cell at the last outer build: it shears every step */
        b.outer_in_ok = 0;
        CHECK(gk_rve_step(&a, 1) == GK_OK);
        CHECK(gk_rve_step(&b, 1) == GK_OK);
        /* a rebuilt its inner list from an outer list it kept: a lookup */
        lookups += a.rebuilds > r0 && ok && a.ho0[1] == ho;
    }
    CHECK(lookups > 50);
    CHECK(b.rebuilds == a.rebuilds);
    CHECK(same_state(&a, &b));
    gk_rve_destroy(&a);
    gk_rve_destroy(&b);
}

/* a restore from a corrupted or foreign buffer fails and changes nothing */
TEST(restore_rejects_bad_buffers) {
    gk_rve a;
    gk_rve_def def = gk_rve_def_default();
    gk_rve_state st;
    unsigned char *copy;
    size_t n;
    if (load_rve(&a, &def, RVE400)) {
        CHECK(0);
        return;
    }
    gk_rve_state_init(&st, NULL);
    gk_rve_state_save(&st, &a);
    n = st.size;
    copy = (unsigned char *)malloc(n);
    memcpy(copy, st.buf, n);
    copy[0] ^= 0xff;
    CHECK(gk_rve_restore(&a, copy, n) == GK_ERR_FORMAT);
    memcpy(copy, st.buf, n);
    CHECK(gk_rve_restore(&a, copy, n - 1) == GK_ERR_FORMAT);
    /* an invalid pair index inside the buffer */
    {
        /* layout tail: pairs i, j (int32), cs (byte), ft, fc x 2, tci, tcj (reals);
         * then the outer list i, j and the outer reference positions */
        size_t off = n - (size_t)a.pl.n * (4 + 4 + 1 + 5 * sizeof(gk_real)) - (size_t)a.outer.n * 8 -
                     (size_t)a.n * 2 * sizeof(double);
        int32_t bad = 1000;
        memcpy(copy + off, &bad, 4);
        CHECK(gk_rve_restore(&a, copy, n) == GK_ERR_FORMAT);
    }
    {
        unsigned char *now = (unsigned char *)malloc(n);
        gk_rve_save(&a, now, n, NULL);
        CHECK(memcmp(now, st.buf, n) == 0);
        free(now);
    }
    free(copy);
    gk_rve_state_free(&st);
    gk_rve_destroy(&a);
}

/* 1 vs 2 threads: identical to the last bit (fixed-order reduction) */
TEST(threads_do_not_change_results) {
    gk_rve a, b;
    gk_rve_def d1 = gk_rve_def_default(), d2 = gk_rve_def_default();
    double dH[9] = {0, 2e-3, 0, 0, 0, 0, 0, 0, 0};
    int k;
    d2.threads = 2;
    if (load_rve(&a, &d1, RVE400) || load_rve(&b, &d2, RVE400)) {
        CHECK(0);
        return;
    }
    for (k = 0; k < 4; ++k) {
        CHECK(gk_rve_deform(&a, dH, 100) == GK_OK);
        CHECK(gk_rve_deform(&b, dH, 100) == GK_OK);
    }
    CHECK(same_state(&a, &b));
#ifndef _OPENMP
    printf("    (built without OpenMP: both runs are serial)\n");
#endif
    gk_rve_destroy(&a);
    gk_rve_destroy(&b);
}

/* The threads' gather of a 2D list above GK_DEM_GATHER_MAX (0 here) reads the
 * first pairs of each side of a particle without a branch on its count,
 * through a zero pair past the list: without rotation (no torques), and with
 * rolling resistance and viscous damping (every per-pair term), 1 and 2
 * threads end in the same state bit for bit, with particles that have more
 * pairs on a side than those slots (the loop after them runs too) */
TEST(threads_do_not_change_results_2d_without_and_with_every_torque) {
    int v;
    for (v = 0; v < 2; ++v) {
        gk_rve a, b;
        gk_rve_def d1 = gk_rve_def_default(), d2;
        double dH[9] = {0, 2e-3, 0, 0, -1e-3, 0, 0, 0, 0};
        int k, p, most_i = 0, most_j = 0;
        if (v == 0)
            d1.flags |= GK_RVE_NO_ROTATION;
        else {
            d1.mat.roll_beta = 1.0;
            d1.mat.roll_eta = 0.1;
            d1.mat.zeta_n = d1.mat.zeta_t = 0.05;
        }
        d2 = d1;
        d2.threads = 2;
        if (load_rve(&a, &d1, RVE400) || load_rve(&b, &d2, RVE400)) {
            CHECK(0);
            return;
        }
        for (k = 0; k < 3; ++k) {
            CHECK(gk_rve_deform(&a, dH, 100) == GK_OK);
            CHECK(gk_rve_deform(&b, dH, 100) == GK_OK);
        }
        CHECK(b.pl.n >= GK_DEM_PAR_MIN); /* b's pair forces run on 2 threads */
        for (p = 0; p < b.n; ++p) {
            if (b.pl.start[p + 1] - b.pl.start[p] > most_i) most_i = b.pl.start[p + 1] - b.pl.start[p];
            if (b.jstart[p + 1] - b.jstart[p] > most_j) most_j = b.jstart[p + 1] - b.jstart[p];
        }
        CHECK(most_i > 3 && most_j > 3);
        CHECK((a.phys & GK_PHYS_ROTATION) == (v ? GK_PHYS_ROTATION : 0u));
        CHECK(same_state(&a, &b));
        gk_rve_destroy(&a);
        gk_rve_destroy(&b);
    }
}

/* gk_rve_step_flags with GK_STEP_NO_STRESS: the motion is that of gk_rve_step to
 * the bit (positions, velocities, forces, history; on 1 and 2 threads), the
 * stress stays that of the last step that made it, and a final plain step
 * gives the same whole state; unknown flags are refused, nothing moving. */
TEST(steps_without_stress_move_the_same) {
    gk_rve a, b, c;
    gk_rve_def d1 = gk_rve_def_default(), d2 = gk_rve_def_default();
    double L[9] = {0, 5.0, 0, 0, 0, 0, 0, 0, 0}, s0[9], x0;
    long st;
    int k;
    d2.threads = 2;
    if (load_rve(&a, &d1, RVE400) || load_rve(&b, &d1, RVE400) || load_rve(&c, &d2, RVE400)) {
        CHECK(0);
        return;
    }
    CHECK(gk_rve_set_velocity_gradient(&a, L) == GK_OK);
    CHECK(gk_rve_set_velocity_gradient(&b, L) == GK_OK);
    CHECK(gk_rve_set_velocity_gradient(&c, L) == GK_OK);
    CHECK(gk_rve_step(&b, 1) == GK_OK);
    memcpy(s0, b.stress, sizeof s0);
    x0 = b.s[0][7];
    CHECK(gk_rve_step_flags(&b, 1, GK_STEP_NO_STRESS) == GK_OK);
    CHECK(memcmp(s0, b.stress, sizeof s0) == 0); /* not made */
    CHECK(b.s[0][7] != x0);                      /* but it moved */
    CHECK(gk_rve_step(&a, 2) == GK_OK);
    for (k = 0; k < 300; ++k) {
        CHECK(gk_rve_step(&a, 1) == GK_OK);
        CHECK(gk_rve_step_flags(&b, 1, GK_STEP_NO_STRESS) == GK_OK);
    }
    CHECK(gk_rve_step_flags(&c, 302, GK_STEP_NO_STRESS) == GK_OK);
    CHECK(same_physics_motion(&a, &b));
    CHECK(same_physics_motion(&a, &c));
    CHECK(a.rebuilds > 0); /* the lists were rebuilt on the way */
    CHECK(gk_rve_step(&a, 1) == GK_OK && gk_rve_step(&b, 1) == GK_OK && gk_rve_step(&c, 1) == GK_OK);
    CHECK(same_state(&a, &b));
    CHECK(same_state(&a, &c));
    st = b.step;
    CHECK(gk_rve_step_flags(&b, 1, 2u) == GK_ERR_ARG && b.step == st && same_state(&a, &b));
    gk_rve_destroy(&a);
    gk_rve_destroy(&b);
    gk_rve_destroy(&c);
}

/* The same in 3D, for each law, with every per-pair torque on (rotation,
 * rolling resistance, viscous damping), and without rotation: the
 * 1000-sphere packing of the benchmarks and a 512-sphere one sheared by 1 and
 * by 2 threads end in the same state bit for bit. One thread scatters
 * (GK_DEM_GATHER_MAX 0); with AVX-512 in double the 512 spheres through the
 * per-particle force records (up to GK_DEM_FREC_MAX, 600 here), whole blocks
 * of pairs first and the list's last pairs after them (lists whose length is
 * not a multiple of a block are among those stepped), the 1000 into f and t. */
TEST(threads_do_not_change_results_3d) {
    const char *packing[2] = {"bench/data/bench3d_1k.txt", "examples/data/rve512_hm.txt"};
    int v, tails = 0;
    for (v = 0; v < 6; ++v) {
        gk_rve a, b;
        gk_rve_def d1 = gk_rve_def_default(), d2;
        double dH[9] = {0, 2e-3, 0, 0, 0, 0, 0, 0, -1e-3};
        int k, law = v % 3 == 1, pk = v / 3;
        if (v % 3 == 2) d1.flags |= GK_RVE_NO_ROTATION;
        d1.mat.kn = 2e5;
        d1.mat.kt_ratio = 0.5;
        d1.mat.friction = 0.5;
        if (v % 3 < 2) { /* rolling resistance needs rotation */
            d1.mat.roll_beta = 1.0;
            d1.mat.roll_eta = 0.1;
        }
        d1.mat.zeta_n = d1.mat.zeta_t = 0.05;
        if (pk == 0) d1.skin = 5e-4;
        if (law) {
            d1.mat.law = GK_LAW_HERTZ;
            d1.mat.kn = 0;
            d1.mat.young = 5e9;
            d1.mat.poisson = 0.3;
        }
        d2 = d1;
        d2.threads = 2;
        if (load_rve(&a, &d1, packing[pk]) || load_rve(&b, &d2, packing[pk])) {
            CHECK(0);
            return;
        }
        CHECK(b.pl.n >= GK_DEM_PAR_MIN); /* b's pair forces run on 2 threads */
        for (k = 0; k < 3; ++k) {
            CHECK(gk_rve_deform(&a, dH, 100) == GK_OK);
            CHECK(gk_rve_deform(&b, dH, 100) == GK_OK);
            tails += a.pl.n % 8 != 0;
        }
        CHECK(a.ncontacts > a.n); /* a dense packing: the sums have many terms */
        CHECK((a.phys & GK_PHYS_ROTATION) == (v % 3 == 2 ? 0u : GK_PHYS_ROTATION));
#if GK_SIMD_WIDTH == 512 && !defined(GK_REAL_FLOAT)
        CHECK((a.frec != NULL) == (pk == 1)); /* records: 512 spheres, not 1000 */
#endif
        CHECK(same_state(&a, &b));
        gk_rve_destroy(&a);
        gk_rve_destroy(&b);
    }
    CHECK(tails > 0);
}

static gk_result gen_consolidate(gk_rve *rve, int dim, int n, double mu_cons, double damping, uint64_t seed,
                                 gk_consolidate_report *rep) {
    gk_gen_def g;
    gk_packing pk;
    gk_err e;
    gk_rve_def def = gk_rve_def_default();
    gk_consolidate_def cd;
    gk_result r;
    memset(&g, 0, sizeof g);
    g.dim = dim;
    g.n = n;
    g.r_min = 0.003;
    g.r_max = 0.007;
    g.seed = seed;
    r = gk_packing_generate(&pk, &g, NULL, &e);
    if (r) {
        printf("    generate: %s\n", e.msg);
        return r;
    }
    r = gk_rve_create(rve, &def, &pk);
    gk_packing_free(&pk);
    if (r) {
        printf("    create: %s\n", gk_rve_error(rve));
        return r;
    }
    memset(&cd, 0, sizeof cd);
    cd.pressure = 1e5;
    cd.friction = mu_cons;
    cd.stress_tol = 2e-3;
    cd.unbalanced_tol = 2e-3;
    cd.damping = damping;
    r = gk_rve_consolidate(rve, &cd, rep);
    if (r) printf("    consolidate: %s\n", gk_rve_error(rve));
    return r;
}

/* anisotropic consolidation (gk_consolidate_def.ratio), frictional (a frictionless packing flows under
 * a deviator): sigma_yy = 1.5 sigma_xx within 1 % with the cell kept a box (box = 1: no shear stress
 * driven, the cell's off-diagonal stays 0) */
TEST(consolidation_to_a_stress_ratio) {
    gk_gen_def g;
    gk_packing pk;
    gk_err e;
    gk_rve r;
    gk_rve_def def = gk_rve_def_default();
    gk_consolidate_def cd;
    gk_consolidate_report rep;
    memset(&g, 0, sizeof g);
    g.dim = 2, g.n = 120, g.r_min = 0.003, g.r_max = 0.007, g.seed = 2;
    CHECK(gk_packing_generate(&pk, &g, NULL, &e) == GK_OK);
    CHECK(gk_rve_create(&r, &def, &pk) == GK_OK);
    gk_packing_free(&pk);
    memset(&cd, 0, sizeof cd);
    cd.pressure = 1e5, cd.ratio[1] = 1.5, cd.box = 1, cd.stress_tol = 2e-3, cd.unbalanced_tol = 2e-3;
    cd.friction = 0.5;
    if (gk_rve_consolidate(&r, &cd, &rep) != GK_OK) {
        printf("    %s\n", gk_rve_error(&r));
        CHECK(0);
    }
    CHECK_REL(-rep.stress[0], 1e5, 0.01);
    CHECK_REL(-rep.stress[4], 1.5e5, 0.01);
    CHECK(r.cell.h[1] == 0.0 && r.cell.h[3] == 0.0);
    cd.ratio[0] = -1.0; /* refused, nothing run */
    CHECK(gk_rve_consolidate(&r, &cd, &rep) == GK_ERR_ARG);
    gk_rve_destroy(&r);
}

/* consolidation reaches 100 kPa isotropic within 1 %, and the friction used
 * while consolidating selects dense (mu = 0) or looser (mu = 0.5) states */
TEST(consolidation_reaches_target_stress) {
    gk_rve dense, loose;
    gk_consolidate_report rd, rl;
    int k;
    CHECK(gen_consolidate(&dense, 2, 150, 0.0, 0.0, 1, &rd) == GK_OK);
    CHECK(gen_consolidate(&loose, 2, 150, 0.5, 0.0, 1, &rl) == GK_OK);
    for (k = 0; k < 2; ++k) {
        CHECK_REL(-rd.stress[4 * k], 1e5, 0.01);
        CHECK_REL(-rl.stress[4 * k], 1e5, 0.01);
    }
    CHECK(fabs(rd.stress[1]) < 0.01 * 1e5); /* isotropic: shear stress driven to zero too */
    CHECK(fabs(rl.stress[1]) < 0.01 * 1e5);
    CHECK(rd.unbalanced < 2e-3);
    CHECK(rl.void_ratio > rd.void_ratio + 0.01);
    printf("    dense e = %.4f (%ld steps), loose e = %.4f (%ld steps)\n", rd.void_ratio, rd.steps,
           rl.void_ratio, rl.steps);
    gk_rve_destroy(&dense);
    gk_rve_destroy(&loose);
}

/* 3D: generate, consolidate, deform, save/restore */
TEST(rve_3d_pipeline) {
    gk_rve a;
    gk_consolidate_report rep;
    gk_rve_state st;
    double dH[9] = {0, 1e-3, 0, 0, 0, 0, 0, 0, -5e-4}, s1[9], s2[9];
    int k;
    if (gen_consolidate(&a, 3, 150, 0.0, 0.5, 7, &rep) != GK_OK) {
        CHECK(0);
        return;
    }
    for (k = 0; k < 3; ++k) CHECK_REL(-rep.stress[4 * k], 1e5, 0.01);
    gk_rve_state_init(&st, NULL);
    gk_rve_state_save(&st, &a);
    CHECK(gk_rve_deform(&a, dH, 200) == GK_OK);
    gk_rve_stress(&a, s1);
    CHECK(s1[1] > 0); /* du_x/dy > 0 loads sigma_xy > 0 (tension-positive convention) */
    CHECK(gk_rve_state_restore(&st, &a) == GK_OK);
    CHECK(gk_rve_deform(&a, dH, 200) == GK_OK);
    gk_rve_stress(&a, s2);
    for (k = 0; k < 9; ++k) CHECK(s1[k] == s2[k]);
    gk_rve_state_free(&st);
    gk_rve_destroy(&a);
}

/* 3D (three rotations per particle): the relaxed tangent of a consolidated
 * 150-sphere packing is its quasi-static DEM response (relaxed_vs_dem) */
TEST(relaxed_tangent_3d_is_the_quasistatic_dem_response) {
    gk_rve a;
    gk_consolidate_report rep;
    const double Hs[3][9] = {{1, 0, 0, 0, -0.5, 0, 0, 0, -0.5},
                             {0, 0.5, 0, 0.5, 0, 0, 0, 0, 0},
                             {0.2, 0.1, -0.4, 0.1, 0.5, 0.3, -0.4, 0.3, -0.6}};
    if (gen_consolidate(&a, 3, 150, 0.0, 0.5, 7, &rep) != GK_OK) {
        CHECK(0);
        return;
    }
    CHECK(gk_rve_set_damping(&a, 0.7, a.def.damping_form) == GK_OK);
    relaxed_vs_dem(&a, 3, Hs, 1.5e-2);
    gk_rve_destroy(&a);
}

/* potential energy stored in the contacts (linear law): sum k_n d^2/2 + F_t^2/(2 k_t) */
static double contact_energy(const gk_rve *rve) {
    double e = 0;
    int c;
    for (c = 0; c < rve->pl.n; ++c) {
        double d[3], ds[3], dd, delta;
        gk_real kn, fn, kt;
        int i = rve->pl.i[c], j = rve->pl.j[c], k;
        if (!(rve->cs[c] & GK_CS_CONTACT)) continue;
        for (k = 0; k < 3; ++k) ds[k] = k < 2 ? rve->s[k][j] - rve->s[k][i] : 0;
        gk_pcell_min_image(&rve->cell, ds, d);
        dd = sqrt(d[0] * d[0] + d[1] * d[1]);
        delta = (double)rve->r[i] + (double)rve->r[j] - dd;
        if (delta <= 0) continue;
        gk_contact_stiffness(&rve->K, GK_LAW_LINEAR, rve->r[i], rve->r[j], (gk_real)delta, &kn, &fn, &kt);
        e += 0.5 * (double)kn * delta * delta;
        if (kt > 0) e += 0.5 * (double)rve->ft[0][c] * (double)rve->ft[0][c] / (double)kt;
    }
    return e;
}

/* dt = 0.9 dt_crit (Guo & Zhao 2014 eq 19), no damping: leap-frog stays stable; the
 * kinetic energy never exceeds the elastic energy stored at the start. */
TEST(dt_at_0_9_critical_stays_bounded) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    double e0, ke_max = 0;
    long k, n = QUICK(100000, 20000);
    def.damping = 0.0;
    if (load_rve(&rve, &def, RVE400)) {
        CHECK(0);
        return;
    }
    CHECK(gk_rve_set_dt(&rve, 0.9 * gk_rve_dt_critical(&rve)) == GK_OK);
    gk_rve_refresh(&rve);
    e0 = contact_energy(&rve);
    for (k = 0; k < n; k += 1000) {
        double ke;
        CHECK(gk_rve_step(&rve, 1000) == GK_OK);
        ke = gk_rve_kinetic_energy(&rve);
        if (ke > ke_max) ke_max = ke;
    }
    CHECK(ke_max < e0);
    CHECK(isfinite(rve.stress[0]));
    printf("    stored %.3e J, largest kinetic %.3e J over %ld steps\n", e0, ke_max, n);
    gk_rve_destroy(&rve);
}

/* An RVE pulled apart until no contact is left returns zero stress, zero
 * tangent, zero fabric, zero unbalanced ratio, an infinite inertial number -
 * never NaN - and recovers when compressed back. */
TEST(rve_without_contacts_is_zero_not_nan) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    double dH[9] = {0.05, 0, 0, 0, 0.05, 0, 0, 0, 0}, back[9] = {-0.055, 0, 0, 0, -0.055, 0, 0, 0, 0}, s[9],
           D[16], phi[9], um, ur;
    int k;
    if (load_rve(&rve, &def, RVE400)) {
        CHECK(0);
        return;
    }
    CHECK(gk_rve_deform(&rve, dH, 200) == GK_OK);
    CHECK_EQ_INT(rve.ncontacts, 0);
    gk_rve_stress(&rve, s);
    for (k = 0; k < 9; ++k) CHECK(s[k] == 0.0);
    CHECK(gk_homog_tangent(&rve, GK_TANGENT_GEOMETRIC, D) == GK_OK);
    for (k = 0; k < 16; ++k) CHECK(D[k] == 0.0);
    CHECK(gk_homog_fabric(&rve, phi, NULL) == 0.0);
    gk_homog_unbalanced(&rve, &um, &ur);
    CHECK(um == 0.0 && ur == 0.0);
    CHECK(gk_stress_p(s, 2) == 0.0 && gk_stress_q(s, 2) == 0.0);
    {
        double rate[9] = {1, 0, 0, 0, 1, 0, 0, 0, 0};
        CHECK(isinf(gk_inertial_number(rate, 2, 0.005, 2650, 0.0)));
    }
    CHECK(gk_rve_deform(&rve, back, 400) == GK_OK);
    CHECK(gk_rve_step(&rve, 2000) == GK_OK);
    CHECK(rve.ncontacts > 100);
    gk_rve_stress(&rve, s);
    CHECK(isfinite(s[0]) && s[0] < 0 && s[4] < 0);
    gk_rve_destroy(&rve);
}

/* E = 1e3 and 1e12: same geometry, stress scales with E exactly (linear law),
 * and the RVE runs stably at its own critical step */
TEST(extreme_stiffness_scales) {
    double Es[2] = {1e3, 1e12}, s0[9];
    int c, k;
    gk_rve ref;
    gk_rve_def d0 = gk_rve_def_default();
    if (load_rve(&ref, &d0, RVE400)) {
        CHECK(0);
        return;
    }
    gk_rve_refresh(&ref);
    gk_rve_stress(&ref, s0);
    for (c = 0; c < 2; ++c) {
        gk_rve rve;
        gk_rve_def def = gk_rve_def_default();
        double s[9], dH[9] = {0, 1e-4, 0, 0, 0, 0, 0, 0, 0};
        def.mat.young = Es[c];
        if (load_rve(&rve, &def, RVE400)) {
            CHECK(0);
            continue;
        }
        gk_rve_refresh(&rve);
        gk_rve_stress(&rve, s);
        for (k = 0; k < 9; ++k) CHECK_NEAR(s[k], s0[k] * Es[c] / 6e8, 1e-12 * fabs(s0[0]) * Es[c] / 6e8);
        CHECK_REL(rve.dt, 0.5 * sqrt(rve.mmin / (Es[c] * rve.rmax)), 1e-12);
        CHECK(gk_rve_deform(&rve, dH, 500) == GK_OK);
        gk_rve_stress(&rve, s);
        for (k = 0; k < 9; ++k) CHECK(isfinite(s[k]));
        gk_rve_destroy(&rve);
    }
    gk_rve_destroy(&ref);
}

/* A 90 degree spin in one increment (objective path: the cell ends at R h):
 * particles co-rotate with the cell, lever arms r - delta/2 make the rigid
 * rotation slip-free, so the stress rotates: sigma' = R sigma R^T. Also the
 * constant-L path with dH = log R = (pi/2) [[0,-1],[1,0]]. */
TEST(spin_90_degrees_in_one_increment) {
    int path;
    for (path = 0; path < 2; ++path) {
        gk_rve rve;
        gk_rve_def def = gk_rve_def_default();
        double s0[9], s1[9], dH[9], p0;
        int k;
        def.path = path == 0 ? GK_PATH_OBJECTIVE : GK_PATH_CONSTANT_L;
        if (load_rve(&rve, &def, RVE400)) {
            CHECK(0);
            continue;
        }
        /* give it a deviatoric stress first */
        {
            double pre[9] = {-1e-3, 0, 0, 0, 0.5e-3, 0, 0, 0, 0};
            CHECK(gk_rve_deform(&rve, pre, 200) == GK_OK);
            CHECK(gk_rve_step(&rve, 500) == GK_OK);
        }
        gk_rve_refresh(&rve);
        gk_rve_stress(&rve, s0);
        p0 = gk_stress_p(s0, 2);
        gk_m3_zero(dH);
        if (path == 0) {
            dH[0] = -1;
            dH[1] = -1;
            dH[3] = 1;
            dH[4] = -1; /* R(90) - I */
        } else {
            dH[1] = -GK_PI / 2;
            dH[3] = GK_PI / 2;
        }
        CHECK(gk_rve_deform(&rve, dH, 2000) == GK_OK);
        gk_rve_refresh(&rve);
        gk_rve_stress(&rve, s1);
        /* R sigma R^T for 90 degrees: xx <-> yy, xy -> -xy */
        CHECK_NEAR(s1[0], s0[4], 2e-3 * p0);
        CHECK_NEAR(s1[4], s0[0], 2e-3 * p0);
        CHECK_NEAR(s1[1], -s0[1], 2e-3 * p0);
        CHECK(fabs(s0[0] - s0[4]) > 0.05 * p0); /* the test has a deviator to rotate */
        CHECK_NEAR(gk_rotation_angle(rve.cell.F, 2), GK_PI / 2, 1e-9);
        for (k = 0; k < 9; ++k) CHECK(isfinite(s1[k]));
        gk_rve_destroy(&rve);
    }
}

/* shear strain 10 through Lees-Edwards re-mapping: flips happen, the RVE
 * keeps running with finite stress and contacts */
TEST(shear_strain_10_by_remapping) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    double dH[9] = {0, 0.1, 0, 0, 0, 0, 0, 0, 0}, s[9];
    int k, nin = QUICK(100, 30);
    if (load_rve(&rve, &def, RVE400)) {
        CHECK(0);
        return;
    }
    for (k = 0; k < nin; ++k) {
        gk_result r = gk_rve_deform(&rve, dH, 100);
        CHECK(r == GK_OK);
        if (r) {
            printf("    %s\n", gk_rve_error(&rve));
            break;
        }
    }
    CHECK(rve.cell.flips >= (nin / 10) - 1);
    CHECK_NEAR(rve.cell.F[1], 0.1 * nin, 1e-9);
    gk_rve_stress(&rve, s);
    for (k = 0; k < 9; ++k) CHECK(isfinite(s[k]));
    CHECK(rve.ncontacts > 50);
    CHECK(fabs(rve.cell.h[1]) <= 0.51 * rve.cell.h[0]);
    gk_rve_destroy(&rve);
}

/* a particle crossing the periodic boundary many times keeps an exact
 * trajectory (free flight: x = x0 + v t modulo the cell) */
TEST(particles_leaving_the_cell) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    gk_packing pk;
    gk_err e;
    double x[3], L = 1.0, v = 37.0, t;
    int p, q = -1;
    def.mat.friction = 0;
    def.damping = 0;
    CHECK(gk_packing_init(&pk, 2, 2, NULL, &e) == GK_OK);
    pk.h[0] = pk.h[4] = L;
    pk.x[0] = 0.2;
    pk.y[0] = 0.25;
    pk.x[1] = 0.7;
    pk.y[1] = 0.75;
    pk.r[0] = pk.r[1] = 0.01;
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_OK);
    for (p = 0; p < 2; ++p)
        if (rve.id[p] == 0) q = p;
    rve.v[0][q] = (gk_real)v;
    CHECK(gk_rve_step(&rve, 100000) == GK_OK);
    t = rve.time;
    gk_rve_position(&rve, q, x);
    CHECK(v * t > 50 * L); /* crossed the cell many times */
    CHECK_NEAR(x[0] - floor(x[0] / L) * L, fmod(0.2 + v * t, L), 1e-9);
    CHECK_NEAR(x[1], 0.25, 1e-15);
    CHECK(rve.rebuilds > 10);
    gk_rve_destroy(&rve);
    gk_packing_free(&pk);
}

/* bad input: a clear result code and message; the caller's data unchanged */
TEST(bad_input_is_rejected_cleanly) {
    gk_packing pk;
    gk_err e;
    gk_rve rve, before;
    gk_rve_def def = gk_rve_def_default();
    CHECK(gk_packing_read(RVE400, &pk, NULL, &e) == GK_OK);
    memset(&rve, 0x5a, sizeof rve);
    memcpy(&before, &rve, sizeof rve);
    pk.x[3] = NAN;
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_ERR_NAN);
    CHECK(strstr(gk_rve_error(&rve), "particle 3") != NULL);
    CHECK(memcmp((char *)&rve, (char *)&before, offsetof(gk_rve, err)) == 0);
    pk.x[3] = INFINITY;
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_ERR_NAN);
    pk.x[3] = 0.1;
    pk.r[5] = 0.0;
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_ERR_RADIUS);
    pk.r[5] = -1e-3;
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_ERR_RADIUS);
    pk.r[5] = 0.005;
    pk.x[7] = 5.0;
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_ERR_OUTSIDE);
    pk.x[7] = 0.1;
    def.dt = 1.0; /* far above critical */
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_ERR_DT);
    CHECK(strstr(gk_rve_error(&rve), "critical") != NULL);
    def.dt = 0;
    def.damping = 1.5;
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_ERR_ARG);
    def = gk_rve_def_default();
    def.cookie = 0;
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_ERR_ARG);
    def = gk_rve_def_default();
    def.mat.density = -1;
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_ERR_MASS);
    CHECK(memcmp((char *)&rve, (char *)&before, offsetof(gk_rve, err)) == 0);
    /* a valid RVE refuses bad calls without changing state */
    def = gk_rve_def_default();
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_OK);
    {
        gk_rve_state st;
        double nan9[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}, thin[9] = {-4, 0, 0, 0, 0, 0, 0, 0, 0};
        unsigned char *now;
        gk_rve_state_init(&st, NULL);
        gk_rve_state_save(&st, &rve);
        nan9[1] = NAN;
        CHECK(gk_rve_deform(&rve, nan9, 10) == GK_ERR_NAN);
        /* both paths: I + dH with det <= 0 would invert the material (constant L: exp(-4) would not) */
        CHECK(gk_rve_deform(&rve, thin, 10) == GK_ERR_SINGULAR);
        rve.def.path = GK_PATH_OBJECTIVE;
        thin[0] = -2;
        CHECK(gk_rve_deform(&rve, thin, 10) == GK_ERR_SINGULAR);
        rve.def.path = GK_PATH_CONSTANT_L;
        /* 50 % compression in one step: beyond the admissible increment per step */
        thin[0] = -0.5;
        CHECK(gk_rve_deform(&rve, thin, 1) == GK_ERR_ARG);
        CHECK(strstr(gk_rve_error(&rve), "steps") != NULL);
        CHECK(gk_rve_set_dt(&rve, 1.0) == GK_ERR_DT);
        CHECK(gk_rve_set_dt(&rve, -1.0) == GK_ERR_DT);
        CHECK(gk_rve_step(&rve, -5) == GK_ERR_ARG);
        now = (unsigned char *)malloc(st.size);
        gk_rve_save(&rve, now, st.size, NULL);
        CHECK(memcmp(now, st.buf, st.size) == 0);
        free(now);
        /* compressed in admissible calls until the cell would be thinner than twice the
         * interaction distance: that call is refused and changes nothing */
        {
            gk_result r = GK_OK;
            int calls = 0;
            while (r == GK_OK && calls < 20) {
                CHECK(gk_rve_state_save(&st, &rve) == GK_OK);
                r = gk_rve_deform(&rve, thin, 200);
                ++calls;
            }
            CHECK(r == GK_ERR_CELL && calls > 1);
            now = (unsigned char *)malloc(st.size);
            gk_rve_save(&rve, now, st.size, NULL);
            CHECK(memcmp(now, st.buf, st.size) == 0);
            free(now);
        }
        gk_rve_state_free(&st);
    }
    gk_rve_destroy(&rve);
    gk_packing_free(&pk);
}

/* malformed packing files: each a clear GK_ERR_* with the line number */
TEST(malformed_packings_are_rejected) {
    const char *bad[][2] = {
        {"", "empty"},
        {"4 2 1 1\n0.1 0.1 0.01\n0.5 0.5 0.01\n", "dimension"},
        {"2 2 1\n0.1 0.1 0.01\n0.5 0.5 0.01\n", "header"},
        {"2 3 1 1\n0.1 0.1 0.01\n0.5 0.5 0.01\n", "lists 2"},
        {"2 1 1 1\n0.1 0.1 0.01\n0.5 0.5 0.01\n", "more particle"},
        {"2 2 1 1\n0.1 0.1 0.01\n0.5 abc 0.01\n", "line 3"},
        {"2 2 1 1\n0.1 0.1 0.01\n0.5 0.5\n", "line 3"},
        {"2 2 1 -1\n0.1 0.1 0.01\n0.5 0.5 0.01\n", "cell length"},
        {"2 2 1 1\n0.1 0.1 0.01\n0.5 0.5 -0.01\n", "radius"},
        {"2 2 1 1\n0.1 nan 0.01\n0.5 0.5 0.01\n", "non-finite"},
        {"2 2.5 1 1\n0.1 0.1 0.01\n0.5 0.5 0.01\n", "count"},
    };
    int c;
    for (c = 0; c < (int)(sizeof bad / sizeof bad[0]); ++c) {
        gk_packing pk;
        gk_err e;
        gk_result r;
        pk.n = -7;
        r = gk_packing_parse(bad[c][0], strlen(bad[c][0]), &pk, NULL, &e);
        CHECK(r != GK_OK);
        CHECK(pk.n == -7); /* untouched */
        if (!strstr(e.msg, bad[c][1])) {
            printf("    case %d: message '%s' lacks '%s'\n", c, e.msg, bad[c][1]);
            CHECK(0);
        }
    }
    {
        gk_packing pk;
        gk_err e;
        CHECK(gk_packing_read("no/such/file.txt", &pk, NULL, &e) == GK_ERR_IO);
        CHECK(strstr(e.msg, "no/such/file.txt") != NULL);
    }
}

/* write -> read is exact (17 digits), skewed cells included; the RVE hands
 * particles back in input order */
TEST(packing_roundtrip_and_input_order) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    gk_packing pk, in, back;
    gk_err e;
    double dH[9] = {0, 0.3, 0, 0, 0, 0, 0, 0, 0};
    int p;
    CHECK(gk_packing_read(RVE400, &in, NULL, &e) == GK_OK);
    CHECK(gk_rve_create(&rve, &def, &in) == GK_OK);
    CHECK(gk_rve_to_packing(&rve, &pk, NULL, &e) == GK_OK);
    for (p = 0; p < in.n; ++p) { /* positions only move by the wrap */
        CHECK_NEAR(pk.x[p], in.x[p], 1e-15);
        CHECK(pk.r[p] == in.r[p]);
    }
    gk_packing_free(&pk);
    def.path = GK_PATH_OBJECTIVE;
    CHECK(gk_rve_deform(&rve, dH, 300) == GK_OK);
    CHECK(gk_rve_to_packing(&rve, &pk, NULL, &e) == GK_OK);
    CHECK(pk.h[1] != 0.0);
    CHECK(gk_packing_write(BUILD "/tests/test_roundtrip.txt", &pk, "sheared\nby test_dem", &e) == GK_OK);
    CHECK(gk_packing_read(BUILD "/tests/test_roundtrip.txt", &back, NULL, &e) == GK_OK);
    CHECK(back.n == pk.n);
    for (p = 0; p < 9; ++p) CHECK(back.h[p] == pk.h[p]);
    for (p = 0; p < pk.n; ++p) CHECK(back.x[p] == pk.x[p] && back.y[p] == pk.y[p] && back.r[p] == pk.r[p]);
    gk_packing_free(&pk);
    gk_packing_free(&back);
    gk_packing_free(&in);
    gk_rve_destroy(&rve);
}

/* generation from a size-distribution table by mass: the sampled radii follow
 * the table (median by mass between the right table points) */
TEST(generate_from_size_table) {
    gk_gen_def g;
    gk_packing pk;
    gk_err e;
    double tr[3] = {0.002, 0.004, 0.008}, tc[3] = {0.0, 0.5, 1.0}, m_small = 0, m_tot = 0;
    int p;
    memset(&g, 0, sizeof g);
    g.dim = 2;
    g.n = 2000;
    g.psd = GK_PSD_TABLE_MASS;
    g.ntable = 3;
    g.table_r = tr;
    g.table_cum = tc;
    g.packing_fraction = 0.4;
    g.seed = 3;
    CHECK(gk_packing_generate(&pk, &g, NULL, &e) == GK_OK);
    for (p = 0; p < pk.n; ++p) {
        double m = pk.r[p] * pk.r[p];
        CHECK(pk.r[p] >= 0.002 && pk.r[p] <= 0.008);
        if (pk.r[p] < 0.004) m_small += m;
        m_tot += m;
    }
    CHECK_NEAR(m_small / m_tot, 0.5, 0.04);
    gk_packing_free(&pk);
    tc[1] = 1.2;
    CHECK(gk_packing_generate(&pk, &g, NULL, &e) == GK_ERR_ARG);
    g.psd = GK_PSD_UNIFORM;
    g.r_min = -1;
    CHECK(gk_packing_generate(&pk, &g, NULL, &e) == GK_ERR_RADIUS);
}

/* Hertz-Mindlin with rolling resistance and viscous damping runs the seed
 * packing stably and is deterministic */
TEST(hertz_rolling_rve_runs) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    double dH[9] = {0, 1e-3, 0, 0, 0, 0, 0, 0, 0}, s[9];
    int k;
    def.mat.law = GK_LAW_HERTZ;
    def.mat.young = 6e8;
    def.mat.poisson = 0.3;
    def.mat.roll_beta = 1.0;
    def.mat.roll_eta = 0.1;
    def.mat.zeta_n = 0.05;
    if (load_rve(&rve, &def, RVE400)) {
        CHECK(0);
        return;
    }
    CHECK(rve.phys == (GK_PHYS_TANGENT | GK_PHYS_ROTATION | GK_PHYS_ROLLING | GK_PHYS_VISCOUS));
    for (k = 0; k < 5; ++k) CHECK(gk_rve_deform(&rve, dH, 100) == GK_OK);
    gk_rve_stress(&rve, s);
    CHECK(s[0] < 0 && s[4] < 0 && isfinite(s[1]));
    CHECK(s[1] > 0); /* du_x/dy > 0 loads sigma_xy > 0 (tension-positive convention) */
    gk_rve_destroy(&rve);
}

/* gk_rve_relax: runs of `every` steps at a fixed cell (the cell matrix does
 * not change) until the unbalanced force ratio is at most uf_max or max_steps
 * ran; the same state bit for bit as gk_rve_step with L = 0 in the same runs;
 * bad arguments and an active servo are refused. */
TEST(relax_holds_the_cell_until_balanced) {
    gk_rve a, b;
    gk_rve_def def = gk_rve_def_default();
    double dH[9] = {0, 2e-3, 0, 0, 0, 0, 0, 0, 0}, L0[9] = {0}, h[9], uf = 2e-3;
    long steps = -1, done = 0;
    gk_servo sv;
    if (load_rve(&a, &def, RVE400) || load_rve(&b, &def, RVE400)) {
        CHECK(0);
        return;
    }
    CHECK(gk_rve_deform(&a, dH, 20) == GK_OK); /* fast: far from balance */
    CHECK(gk_rve_deform(&b, dH, 20) == GK_OK);
    CHECK(gk_rve_unbalanced(&a) > uf);
    gk_m3_copy(a.cell.h, h);
    CHECK(gk_rve_relax(&a, uf, 20, 3000, &steps) == GK_OK);
    printf("    %ld relaxation steps, unbalanced ratio %.3g\n", steps, gk_rve_unbalanced(&a));
    CHECK(steps > 0 && (steps % 20 == 0 || steps == 3000));
    CHECK(gk_rve_unbalanced(&a) <= uf || steps == 3000);
    CHECK(memcmp(h, a.cell.h, sizeof h) == 0);
    CHECK(gk_rve_set_velocity_gradient(&b, L0) == GK_OK);
    while (done < 3000 && gk_rve_unbalanced(&b) > uf) {
        CHECK(gk_rve_step(&b, 20) == GK_OK);
        done += 20;
    }
    CHECK(done == steps);
    CHECK(same_state(&a, &b));
    CHECK(gk_rve_relax(&a, uf, 20, 3000, &steps) == GK_OK && steps == 0); /* already balanced */
    CHECK(gk_rve_relax(&a, 0.0, 20, 100, &steps) == GK_ERR_ARG);
    CHECK(gk_rve_relax(&a, uf, 0, 100, &steps) == GK_ERR_ARG);
    memset(&sv, 0, sizeof sv);
    sv.max_rate = 1.0;
    CHECK(gk_rve_set_servo(&a, &sv) == GK_OK);
    CHECK(gk_rve_relax(&a, uf, 20, 100, &steps) == GK_ERR_STATE && steps == 0);
    gk_rve_destroy(&a);
    gk_rve_destroy(&b);
}

/* gk_rve_deform_adaptive (gk_homog.h): the deformation runs n = ceil(I_1 /
 * I_max) steps, I_1 = 2 |sym dH / dt| r_mean sqrt(rho / p) (Guo & Zhao 2014 eq 20)
 * of the whole dH in one step, so n doubles with |dH| and with 1/sqrt(p);
 * then relaxation at fixed cell until the unbalanced ratio is below uf_max
 * (which it must then be) or n_max is reached (then reported as capped). */
TEST(adaptive_deform_follows_the_inertial_number) {
    gk_rve a, b;
    gk_rve_def def = gk_rve_def_default();
    gk_adapt_def ad;
    gk_adapt_report ra, rb;
    double dH[9] = {0}, rate[9] = {0}, s[9], rmean = 0, I1, ub;
    int k;
    def.dt = 3.16e-5;
    if (load_rve(&a, &def, RVE400) || load_rve(&b, &def, RVE400)) {
        CHECK(0);
        return;
    }
    gk_rve_refresh(&a);
    gk_rve_refresh(&b);
    for (k = 0; k < a.n; ++k) rmean += a.r[k];
    rmean /= a.n;
    gk_rve_stress(&a, s);
    dH[4] = -2e-4;
    rate[4] = dH[4] / a.dt;
    I1 = gk_inertial_number(rate, 2, rmean, a.def.mat.density, gk_stress_p(s, 2));
    memset(&ad, 0, sizeof ad);
    ad.inertial_max = 2e-4, ad.unbalanced_max = 1.0, ad.n_min = 1, ad.n_max = 100000;
    CHECK(gk_rve_deform_adaptive(&a, dH, &ad, &ra) == GK_OK);
    CHECK_EQ_INT(ra.n_deform, (long)ceil(I1 / 2e-4));
    CHECK_EQ_INT(ra.n_relax, 0);
    CHECK(ra.unbalanced == gk_rve_unbalanced(&a)); /* the relaxation's own measure of this state */
    CHECK(ra.inertial <= 2e-4 && ra.inertial > 1e-4);
    dH[4] = -4e-4; /* twice the increment: twice the steps (to the rounding) */
    CHECK(gk_rve_deform_adaptive(&b, dH, &ad, &rb) == GK_OK);
    CHECK(abs(rb.n_deform - 2 * ra.n_deform) <= 1);
    /* relaxation: a strict bound is reached, or the cap is reported */
    ad.unbalanced_max = 2e-4, ad.n_max = ra.n_deform + 2000;
    dH[4] = -2e-4;
    CHECK(gk_rve_deform_adaptive(&a, dH, &ad, &ra) == GK_OK);
    gk_homog_unbalanced(&a, &ub, NULL);
    CHECK_NEAR(ub, ra.unbalanced, 0);
    CHECK(ra.n_relax > 0);
    CHECK(ra.capped ? ra.n_deform + ra.n_relax == ad.n_max : ra.unbalanced <= 2e-4);
    /* bad input: an error, and the RVE is untouched */
    {
        gk_rve_state st;
        gk_rve c;
        gk_rve_state_init(&st, NULL);
        CHECK(gk_rve_state_save(&st, &a) == GK_OK);
        dH[4] = NAN;
        CHECK(gk_rve_deform_adaptive(&a, dH, &ad, &ra) == GK_ERR_ARG);
        dH[4] = -1e-4;
        ad.n_min = 10, ad.n_max = 5;
        CHECK(gk_rve_deform_adaptive(&a, dH, &ad, &ra) == GK_ERR_ARG);
        CHECK(strstr(gk_rve_error(&a), "n_min") != NULL);
        if (load_rve(&c, &def, RVE400) == GK_OK) {
            CHECK(gk_rve_state_restore(&st, &c) == GK_OK);
            CHECK(same_state(&a, &c));
            gk_rve_destroy(&c);
        }
        gk_rve_state_free(&st);
    }
    gk_rve_destroy(&a);
    gk_rve_destroy(&b);
}

/* The Love stress of a step (Guo & Zhao 2014 eq 5), sigma = -(1/V) sum_c f_c (x) d_c, and the mean
 * contact force are sums in pair order, bit for bit (what a faster pass must keep): rebuilt here from
 * the public contact iterator (its d by gk_pcell_image), in 2D (400 disks) and 3D (1000 spheres),
 * after a shear and a refresh (forces and branch vectors at the same positions). */
TEST(stress_pass_is_the_pair_order_sum) {
    const char *path[2] = {RVE400, "bench/data/bench3d_1k.txt"};
    int t;
    for (t = 0; t < 2; ++t) {
        gk_rve r;
        gk_rve_def def = gk_rve_def_default();
        gk_rve_contact k;
        double S[9] = {0}, want[9], got[9], V, fsum = 0.0, dH[9] = {2e-4, 1e-3, 0, 0, -1e-3, 0, 0, 0, 0};
        int c = 0, n = 0, i, j;
        if (t == 1) def.skin = 5e-4, dH[8] = 3e-4;
        if (load_rve(&r, &def, path[t])) {
            CHECK(0);
            return;
        }
        CHECK(gk_rve_deform(&r, dH, 50) == GK_OK && gk_rve_refresh(&r) == GK_OK);
        V = gk_rve_volume(&r);
        while (gk_rve_contact_next(&r, &c, &k)) {
            for (i = 0; i < r.dim; ++i)
                for (j = 0; j < r.dim; ++j) S[3 * i + j] += k.f[i] * k.d[j];
            fsum += sqrt(k.f[0] * k.f[0] + k.f[1] * k.f[1] + k.f[2] * k.f[2]);
            ++n;
        }
        for (i = 0; i < 9; ++i) want[i] = -S[i] / V;
        gk_rve_stress(&r, got);
        CHECK(n == r.ncontacts && n > r.n);
        CHECK(memcmp(got, want, sizeof got) == 0);
        CHECK(r.fc_mean == fsum / n);
        gk_rve_destroy(&r);
    }
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(seed_packing_reproduces_yade);
    RUN(love_stress_hexagonal_lattice);
    RUN(love_stress_cubic_lattice_3d);
    RUN(taylor_tangent_is_fd_tangent_at_vanishing_preload);
    RUN(full_tangent_is_fd_tangent_prestressed);
    RUN(relaxed_tangent_of_a_bravais_lattice_is_taylor);
    RUN(relaxed_tangent_of_a_chain_is_springs_in_series);
    RUN(relaxed_tangent_is_the_quasistatic_dem_response);
    RUN(save_restore_is_bitwise);
    RUN(restore_rejects_bad_buffers);
    RUN(skin_does_not_change_results);
    RUN(rebuild_lookup_equals_merge);
    RUN(threads_do_not_change_results);
    RUN(threads_do_not_change_results_2d_without_and_with_every_torque);
    RUN(steps_without_stress_move_the_same);
    RUN(threads_do_not_change_results_3d);
    RUN(consolidation_reaches_target_stress);
    RUN(consolidation_to_a_stress_ratio);
    RUN(rve_3d_pipeline);
    RUN(relaxed_tangent_3d_is_the_quasistatic_dem_response);
    RUN(dt_at_0_9_critical_stays_bounded);
    RUN(rve_without_contacts_is_zero_not_nan);
    RUN(extreme_stiffness_scales);
    RUN(spin_90_degrees_in_one_increment);
    RUN(shear_strain_10_by_remapping);
    RUN(particles_leaving_the_cell);
    RUN(bad_input_is_rejected_cleanly);
    RUN(malformed_packings_are_rejected);
    RUN(packing_roundtrip_and_input_order);
    RUN(generate_from_size_table);
    RUN(hertz_rolling_rve_runs);
    RUN(adaptive_deform_follows_the_inertial_number);
    RUN(relax_holds_the_cell_until_balanced);
    RUN(stress_pass_is_the_pair_order_sum);
    return gk_test_done();
}
