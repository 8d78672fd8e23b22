/* test_simd.c - the SIMD force kernels equal the scalar reference bit for bit
 * (the scalar law is the reference; SIMD is a faster way to the same bits), for every law and physics switch, 2D and 3D.
 * tests/test_simd_float.c compiles this file again with GK_REAL_FLOAT. */
#include "gk_homog.h"
#include "gk_test.h"
#include <stdlib.h>

static int same_state(const gk_rve *a, const gk_rve *b) {
    size_t n = gk_rve_state_size(a);
    unsigned char *x, *y;
    int same;
    if (n != gk_rve_state_size(b)) return 0;
    x = (unsigned char *)malloc(n);
    y = (unsigned char *)malloc(n);
    gk_rve_save(a, x, n, NULL);
    gk_rve_save(b, y, n, NULL);
    same = memcmp(x, y, n) == 0;
    if (!same) {
        size_t k;
        for (k = 0; k < n && x[k] == y[k]; ++k) {
        }
        printf("    states differ from byte %lu of %lu\n", (unsigned long)k, (unsigned long)n);
    }
    free(x);
    free(y);
    return same;
}

typedef struct cfg {
    const char *name;
    gk_law law;
    double mu, beta, eta, zeta;
    unsigned flags;
} cfg;

static const cfg CFGS[] = {
    {"linear, frictionless", GK_LAW_LINEAR, 0.0, 0, 0, 0, 0},
    {"linear, friction, rotation", GK_LAW_LINEAR, 0.5, 0, 0, 0, 0},
    {"linear, friction, no rotation", GK_LAW_LINEAR, 0.5, 0, 0, 0, GK_RVE_NO_ROTATION},
    {"hertz, friction, rolling, viscous", GK_LAW_HERTZ, 0.5, 1.0, 0.1, 0.1, 0},
    {"linear, rolling, viscous", GK_LAW_LINEAR, 0.3, 0.5, 0.05, 0.2, 0},
};

static void run_pair(const gk_packing *pk, const cfg *c, const double dH[9], int nsteps, int nrep) {
    gk_rve a, b;
    gk_rve_def da = gk_rve_def_default(), db;
    int k;
    da.mat.law = c->law;
    da.mat.friction = c->mu;
    da.mat.roll_beta = c->beta;
    da.mat.roll_eta = c->eta;
    da.mat.zeta_n = c->zeta;
    da.mat.zeta_t = c->zeta;
    da.mat.poisson = 0.3;
    da.flags = c->flags;
    da.damping = 0.05;
    db = da;
    db.flags |= GK_RVE_SCALAR;
    if (gk_rve_create(&a, &da, pk) || gk_rve_create(&b, &db, pk)) {
        printf("    %s: %s %s\n", c->name, gk_rve_error(&a), gk_rve_error(&b));
        CHECK(0);
        return;
    }
    for (k = 0; k < nrep; ++k) {
        CHECK(gk_rve_deform(&a, dH, nsteps) == GK_OK);
        CHECK(gk_rve_deform(&b, dH, nsteps) == GK_OK);
    }
    if (!same_state(&a, &b)) {
        printf("    differs: %s (%dD)\n", c->name, pk->dim);
        CHECK(0);
    }
    CHECK(a.ncontacts > 0);
    gk_rve_destroy(&a);
    gk_rve_destroy(&b);
}

TEST(simd_equals_scalar_2d) {
    gk_packing pk;
    gk_err e;
    double dH[9] = {-2e-3, 3e-3, 0, -1e-3, 1e-3, 0, 0, 0, 0};
    int c;
    CHECK(gk_packing_read("examples/data/rve400.txt", &pk, NULL, &e) == GK_OK);
    for (c = 0; c < (int)(sizeof CFGS / sizeof CFGS[0]); ++c) run_pair(&pk, &CFGS[c], dH, 100, 6);
    gk_packing_free(&pk);
}

TEST(simd_equals_scalar_3d) {
    gk_gen_def g;
    gk_packing pk;
    gk_err e;
    double squeeze[9] = {-0.17, 0, 0, 0, -0.17, 0, 0, 0, -0.17};
    double dH[9] = {-1e-3, 2e-3, 0, 1e-3, 0, -1e-3, 0, 5e-4, 1e-3};
    int c;
    memset(&g, 0, sizeof g);
    g.dim = 3;
    g.n = 300;
    g.r_min = 0.003;
    g.r_max = 0.007;
    g.packing_fraction = 0.35;
    g.seed = 5;
    CHECK(gk_packing_generate(&pk, &g, NULL, &e) == GK_OK);
    /* squeeze the cloud into a contact network (one RVE), then compare from there */
    {
        gk_rve r;
        gk_rve_def d = gk_rve_def_default();
        gk_packing dense;
        d.mat.friction = 0;
        CHECK(gk_rve_create(&r, &d, &pk) == GK_OK);
        CHECK(gk_rve_deform(&r, squeeze, 3000) == GK_OK);
        CHECK(gk_rve_to_packing(&r, &dense, NULL, &e) == GK_OK);
        gk_rve_destroy(&r);
        gk_packing_free(&pk);
        pk = dense;
    }
    for (c = 0; c < (int)(sizeof CFGS / sizeof CFGS[0]); ++c) run_pair(&pk, &CFGS[c], dH, 100, 4);
    gk_packing_free(&pk);
}

/* Particles that cross the cell's periodic faces are wrapped back into
 * [0, 1) with their list references shifted by the same whole period
 * (gk__wrap), in the SIMD kernels only for the vectors where a lane left:
 * every particle of an RVE given one drift velocity (about 0.7 of a cell
 * width along x and 0.4 along y in 300 steps; a uniform translation leaves
 * the contacts as they are) ends in [0, 1), most of them wrapped, and the
 * SIMD and scalar runs end in the same state. */
TEST(simd_equals_scalar_across_periodic_faces) {
    gk_packing pk;
    gk_err e;
    gk_rve a, b;
    gk_rve_def da = gk_rve_def_default(), db;
    double dH[9] = {-1e-3, 2e-3, 0, 0, 1e-3, 0, 0, 0, 0}, s0[2][400];
    int p, k, wrapped = 0, inside = 1;
    CHECK(gk_packing_read("examples/data/rve400.txt", &pk, NULL, &e) == GK_OK);
    da.mat.friction = 0.5;
    db = da;
    db.flags |= GK_RVE_SCALAR;
    if (!(gk_rve_create(&a, &da, &pk) == GK_OK && gk_rve_create(&b, &db, &pk) == GK_OK && a.n == 400)) {
        CHECK(0);
        return;
    }
    for (p = 0; p < a.n; ++p) {
        gk_real ux = (gk_real)(0.7 * a.cell.h[0] / (300 * a.dt)),
                uy = (gk_real)(0.4 * a.cell.h[4] / (300 * a.dt));
        a.v[0][p] += ux, b.v[0][p] += ux;
        a.v[1][p] += uy, b.v[1][p] += uy;
        for (k = 0; k < 2; ++k) s0[k][p] = a.s[k][p];
    }
    CHECK(gk_rve_deform(&a, dH, 300) == GK_OK);
    CHECK(gk_rve_deform(&b, dH, 300) == GK_OK);
    for (p = 0; p < a.n; ++p) {
        if (a.s[0][p] < s0[0][p] || a.s[1][p] < s0[1][p]) ++wrapped; /* moved +x, +y: came round */
        for (k = 0; k < 2; ++k)
            if (!(a.s[k][p] >= 0.0 && a.s[k][p] < 1.0)) inside = 0;
    }
    printf("    %d of %d particles wrapped\n", wrapped, a.n);
    CHECK(wrapped > 200);
    CHECK(inside);
    CHECK(same_state(&a, &b));
    CHECK(a.ncontacts > 0);
    gk_rve_destroy(&a);
    gk_rve_destroy(&b);
    gk_packing_free(&pk);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    printf("    SIMD %s, %d lanes of %s\n", GK_SIMD_NAME, GK_VR_W, GK_REAL_NAME);
    RUN(simd_equals_scalar_2d);
    RUN(simd_equals_scalar_3d);
    RUN(simd_equals_scalar_across_periodic_faces);
    return gk_test_done();
}
