/* test_mpm.c - gk_mpm.h: shape functions, transfers, conservation, APIC,
 * elastic wave, geostatic column, Coulomb boundary, rigid plate reaction,
 * circle (pipe) bodies,
 * Drucker-Prager return map, thread determinism, bad input. */
#include "gk_mpm.h"
#include "gk_test.h"
#include <stdlib.h>
#include <string.h>

#ifdef GK_TEST_QUICK
#define QUICK 1
#else
#define QUICK 0
#endif

static const gk_mpm_basis all_bases[4] = {GK_MPM_LINEAR, GK_MPM_UGIMP, GK_MPM_QUADRATIC, GK_MPM_CUBIC};
static const char *basis_name[4] = {"linear", "uGIMP", "quadratic", "cubic"};

typedef struct elastic_law {
    double K, G;
} elastic_law;

/* stress update for every point: hypoelastic with dH = dt L */
static gk_result elastic_cb(gk_mpm_points *P, double dt, void *user, gk_err *err) {
    const elastic_law *e = (const elastic_law *)user;
    int p;
    for (p = 0; p < P->n; ++p) {
        double dH[9];
        gk_result r;
        gk_mpm_point_dh(P, p, dt, dH);
        r = gk_mpm_elastic_update(e->K, e->G, P->dim, dH, P->sigma + 9 * p, err);
        if (r) return r;
    }
    return GK_OK;
}

static gk_mpm_grid make_grid(int dim, double ox, double oy, double oz, double h, int nx, int ny, int nz) {
    gk_mpm_grid g;
    double o[3];
    int n[3];
    gk_err e;
    o[0] = ox;
    o[1] = oy;
    o[2] = oz;
    n[0] = nx;
    n[1] = ny;
    n[2] = nz;
    if (gk_mpm_grid_create(&g, dim, o, h, n, NULL, &e) != GK_OK) {
        printf("grid_create failed: %s\n", e.msg);
        exit(1);
    }
    return g;
}

/* random points whose support (any basis, lp = h/4) is inside the grid */
static void random_points(gk_mpm_points *P, const gk_mpm_grid *g, int n,
                          uint64_t seed) { /* in [1.5h, (n-2.5)h] */
    gk_rng rng;
    int p, k;
    gk_err e;
    if (gk_mpm_points_create(P, g->dim, n, NULL, &e) != GK_OK) {
        printf("points_create failed: %s\n", e.msg);
        exit(1);
    }
    gk_rng_seed(&rng, seed);
    for (p = 0; p < n; ++p) {
        for (k = 0; k < g->dim; ++k) {
            double lo = g->origin[k] + 1.5 * g->h, hi = g->origin[k] + (g->n[k] - 2.5) * g->h;
            P->x[k][p] = lo + (hi - lo) * gk_rng_uniform(&rng);
            P->v[k][p] = 2.0 * gk_rng_uniform(&rng) - 1.0;
        }
        P->m[p] = 0.5 + gk_rng_uniform(&rng);
        P->vol0[p] = P->vol[p] = 1e-3 * (0.5 + gk_rng_uniform(&rng));
        P->lp[p] = 0.25 * g->h;
    }
}

/* every basis, 2D and 3D, random points: sum N = 1 (partition of unity),
 * sum grad N = 0, and linear completeness sum N x_I = x_p,
 * sum x_I (x) grad N = I (what makes APIC and L exact for affine fields) */
TEST(shape_partition_of_unity) {
    int dim, bi, t;
    gk_rng rng;
    gk_rng_seed(&rng, 7);
    for (dim = 2; dim <= 3; ++dim) {
        gk_mpm_grid g = make_grid(dim, -1.0, 0.5, 2.0, 0.37, 9, 8, 7);
        for (bi = 0; bi < 4; ++bi) {
            double worst_w = 0, worst_g = 0, worst_x = 0, worst_c = 0;
            for (t = 0; t < 200; ++t) {
                gk_mpm_stencil st;
                gk_err e;
                double x[3] = {0, 0, 0}, sw = 0, sg[3] = {0, 0, 0}, sx[3] = {0, 0, 0}, cx[9];
                int k, q, i, j;
                for (k = 0; k < dim; ++k)
                    x[k] = g.origin[k] + g.h * (1.0 + (g.n[k] - 3.0) * gk_rng_uniform(&rng));
                if (t == 0)
                    for (k = 0; k < dim; ++k) x[k] = g.origin[k] + g.h * 3.0; /* exactly on a node */
                CHECK_EQ_INT(gk_mpm_shape(&g, all_bases[bi], x, 0.3 * g.h, &st, &e), GK_OK);
                CHECK_EQ_INT(
                    st.n, dim == 3 ? gk_mpm_basis_width(all_bases[bi]) * gk_mpm_basis_width(all_bases[bi]) *
                                         gk_mpm_basis_width(all_bases[bi])
                                   : gk_mpm_basis_width(all_bases[bi]) * gk_mpm_basis_width(all_bases[bi]));
                for (i = 0; i < 9; ++i) cx[i] = 0;
                for (q = 0; q < st.n; ++q) {
                    double xI[3];
                    gk_mpm_grid_node_position(&g, (size_t)st.node[q], xI);
                    sw += st.w[q];
                    for (i = 0; i < 3; ++i) {
                        sg[i] += st.dw[q][i];
                        sx[i] += st.w[q] * xI[i];
                        for (j = 0; j < 3; ++j) cx[3 * i + j] += xI[i] * st.dw[q][j];
                    }
                }
                if (fabs(sw - 1) > worst_w) worst_w = fabs(sw - 1);
                for (i = 0; i < dim; ++i) {
                    if (fabs(sg[i]) * g.h > worst_g) worst_g = fabs(sg[i]) * g.h;
                    if (fabs(sx[i] - x[i]) > worst_x) worst_x = fabs(sx[i] - x[i]);
                    for (j = 0; j < dim; ++j)
                        if (fabs(cx[3 * i + j] - (i == j)) > worst_c)
                            worst_c = fabs(cx[3 * i + j] - (i == j));
                }
            }
            if (worst_w > 1e-14 || worst_g > 1e-13 || worst_x > 1e-13 || worst_c > 1e-12)
                printf("    %dD %s: |sum N - 1| %.2e, |sum grad N| h %.2e, |sum N x - x| %.2e, |sum x grad N "
                       "- I| %.2e\n",
                       dim, basis_name[bi], worst_w, worst_g, worst_x, worst_c);
            CHECK(worst_w <= 1e-14);
            CHECK(worst_g <= 1e-13);
            CHECK(worst_x <= 1e-13);
            CHECK(worst_c <= 1e-12);
        }
        gk_mpm_grid_destroy(&g);
    }
}

/* gk_mpm_support_inside: true exactly where gk_mpm_shape takes the point, which (GRID in gk_mpm.h) is
 * xi = (x - origin) / h in [a, n - 1 - a] per axis, a = 0 / lp/h / 1/2 / 1 for linear / uGIMP /
 * quadratic / cubic; checked on both sides of each bound of a 2D and a 3D grid, on random points
 * in and around the grid, and false for NaN, an unknown basis and a uGIMP lp outside (0, h/2]. */
TEST(support_inside_agrees_with_shape) {
    int dim, bi, t, k, side;
    gk_rng rng;
    gk_mpm_stencil st;
    gk_err e;
    gk_rng_seed(&rng, 11);
    for (dim = 2; dim <= 3; ++dim) {
        gk_mpm_grid g = make_grid(dim, -1.0, 0.5, 2.0, 0.37, 9, 8, 7);
        const double lp = 0.3 * g.h;
        for (bi = 0; bi < 4; ++bi) {
            /* the support margin a of each basis, in cells; lp = 0.3 h */
            const double margin[4] = {0.0, 0.3, 0.5, 1.0}, a = margin[bi];
            for (k = 0; k < dim; ++k)
                for (side = 0; side < 2; ++side) {
                    /* just inside and just outside the bound of axis k, the other axes mid-grid */
                    double x[3] = {0, 0, 0}, bound;
                    int j;
                    for (j = 0; j < dim; ++j) x[j] = g.origin[j] + 0.5 * (g.n[j] - 1) * g.h;
                    bound = g.origin[k] + (side ? (g.n[k] - 1 - a) : a) * g.h;
                    x[k] = bound + (side ? -1e-9 : 1e-9);
                    CHECK(gk_mpm_support_inside(&g, all_bases[bi], x, lp));
                    x[k] = bound + (side ? 1e-9 : -1e-9);
                    CHECK(!gk_mpm_support_inside(&g, all_bases[bi], x, lp));
                    CHECK_EQ_INT(gk_mpm_shape(&g, all_bases[bi], x, lp, &st, &e), GK_ERR_OUTSIDE);
                }
            for (t = 0; t < 400; ++t) {
                double x[3] = {0, 0, 0};
                int in;
                for (k = 0; k < dim; ++k)
                    x[k] = g.origin[k] + g.h * (-1.0 + (g.n[k] + 1.0) * gk_rng_uniform(&rng));
                in = gk_mpm_support_inside(&g, all_bases[bi], x, lp);
                CHECK_EQ_INT(in, gk_mpm_shape(&g, all_bases[bi], x, lp, &st, &e) == GK_OK);
            }
        }
        {
            double x[3];
            for (k = 0; k < 3; ++k) x[k] = g.origin[k] + 3.0 * g.h;
            CHECK(gk_mpm_support_inside(&g, GK_MPM_UGIMP, x, lp));
            CHECK(!gk_mpm_support_inside(&g, GK_MPM_UGIMP, x, 0.0));
            CHECK(!gk_mpm_support_inside(&g, GK_MPM_UGIMP, x, 0.51 * g.h));
            CHECK(!gk_mpm_support_inside(&g, (gk_mpm_basis)7, x, lp));
            x[1] = NAN;
            CHECK(!gk_mpm_support_inside(&g, GK_MPM_LINEAR, x, lp));
        }
        gk_mpm_grid_destroy(&g);
    }
}

/* gk_mpm_shape_values: the nodes and weights of gk_mpm_shape bit for bit, and its result code, on
 * random points in and around a 2D and a 3D grid for every basis (and NaN, an unknown basis, a bad
 * uGIMP lp); it writes n entries and nothing beyond them, and nothing at all when it refuses */
TEST(shape_values_equal_shape) {
    int dim, bi, t, k, q;
    gk_rng rng;
    gk_rng_seed(&rng, 13);
    for (dim = 2; dim <= 3; ++dim) {
        gk_mpm_grid g = make_grid(dim, -1.0, 0.5, 2.0, 0.37, 9, 8, 7);
        for (bi = 0; bi < 6; ++bi) {
            gk_mpm_basis b = bi < 4 ? all_bases[bi] : (gk_mpm_basis)(bi == 4 ? 7 : -1);
            for (t = 0; t < 300; ++t) {
                gk_mpm_stencil st;
                gk_err e1, e2;
                int32_t node[GK_MPM_MAX_STENCIL + 1];
                double w[GK_MPM_MAX_STENCIL + 1], x[3] = {0, 0, 0}, lp = 0.3 * g.h;
                int n = -7;
                gk_result r1, r2;
                for (k = 0; k < dim; ++k)
                    x[k] = g.origin[k] + g.h * (-1.0 + (g.n[k] + 1.0) * gk_rng_uniform(&rng));
                if (t % 50 == 1) x[t % dim] = NAN;
                if (t % 50 == 2) lp = 0.6 * g.h;
                for (q = 0; q <= GK_MPM_MAX_STENCIL; ++q) {
                    node[q] = -99;
                    w[q] = -99.0;
                }
                r1 = gk_mpm_shape(&g, b, x, lp, &st, &e1);
                r2 = gk_mpm_shape_values(&g, b, x, lp, &n, node, w, &e2);
                CHECK_EQ_INT(r2, r1);
                if (r1 == GK_OK) {
                    CHECK_EQ_INT(n, st.n);
                    CHECK(!memcmp(node, st.node, (size_t)st.n * sizeof(int32_t)));
                    CHECK(!memcmp(w, st.w, (size_t)st.n * sizeof(double)));
                } else {
                    CHECK_EQ_INT(n, -7);
                    CHECK(!strcmp(e1.msg, e2.msg));
                }
                for (q = r1 == GK_OK ? st.n : 0; q <= GK_MPM_MAX_STENCIL; ++q)
                    CHECK(node[q] == -99 && w[q] == -99.0);
            }
        }
        {
            int32_t node[GK_MPM_MAX_STENCIL];
            double w[GK_MPM_MAX_STENCIL], x[3];
            int n;
            gk_err e;
            for (k = 0; k < 3; ++k) x[k] = g.origin[k] + 3.0 * g.h;
            CHECK_EQ_INT(gk_mpm_shape_values(&g, GK_MPM_LINEAR, x, 0.0, NULL, node, w, &e), GK_ERR_ARG);
            CHECK_EQ_INT(gk_mpm_shape_values(&g, GK_MPM_LINEAR, x, 0.0, &n, NULL, w, &e), GK_ERR_ARG);
            CHECK_EQ_INT(gk_mpm_shape_values(&g, GK_MPM_LINEAR, x, 0.0, &n, node, NULL, &e), GK_ERR_ARG);
        }
        gk_mpm_grid_destroy(&g);
    }
}

/* dN/dr of every 1D kernel equals the central difference of N; asked for N alone (dN NULL), the same N */
TEST(kernel_derivative_matches_finite_difference) {
    int bi, t;
    for (bi = 0; bi < 4; ++bi)
        for (t = 0; t < 400; ++t) {
            double r = -2.2 + 4.4 * (t + 0.37) / 400.0, d, dm, dp, eps = 1e-6, l = 0.3;
            double Np = gk_mpm_kernel_1d(all_bases[bi], r + eps, l, &dp);
            double Nm = gk_mpm_kernel_1d(all_bases[bi], r - eps, l, &dm);
            double N = gk_mpm_kernel_1d(all_bases[bi], r, l, &d);
            CHECK_NEAR(d, (Np - Nm) / (2 * eps), 1e-5);
            CHECK(gk_mpm_kernel_1d(all_bases[bi], r, l, NULL) == N); /* the weight alone: the same */
        }
}

/* P2G: sum m_I = sum m_p and sum p_I = sum m_p v_p (also for APIC, because
 * sum_I N (x_I - x_p) = 0); G2P: PIC and APIC give sum m_p v_p = sum p_I,
 * FLIP with no force leaves v_p unchanged. */
TEST(p2g_g2p_conserve_mass_and_momentum) {
    int dim, bi, tr;
    for (dim = 2; dim <= 3; ++dim)
        for (bi = 0; bi < 4; ++bi)
            for (tr = 0; tr < 3; ++tr) { /* 0 PIC, 1 FLIP, 2 APIC */
                gk_mpm_grid g = make_grid(dim, 0.0, 0.0, 0.0, 0.1, 10, 9, 8);
                gk_mpm_points P;
                gk_mpm_def d = gk_mpm_def_default();
                gk_err e;
                double M, mom[3], M2, mom2[3], gm = 0, gp[3] = {0, 0, 0};
                int k, p;
                size_t I;
                random_points(&P, &g, 300, 11 + dim);
                d.basis = all_bases[bi];
                d.transfer = tr == 2 ? GK_MPM_APIC : GK_MPM_PIC_FLIP;
                d.alpha = tr == 0 ? 1.0 : 0.0;
                if (tr == 2)
                    for (p = 0; p < P.n; ++p)
                        for (k = 0; k < 9; ++k)
                            P.C[9 * p + k] = (k % 3 < dim && k / 3 < dim) ? sin(1.0 + p + 3.0 * k) : 0.0;
                gk_mpm_points_totals(&P, &M, mom, NULL);
                CHECK_EQ_INT(gk_mpm_p2g(&g, &P, &d, GK_MPM_P2G_MOMENTUM | GK_MPM_P2G_FORCE, &e), GK_OK);
                for (I = 0; I < g.nnode; ++I) {
                    gm += g.m[I];
                    for (k = 0; k < dim; ++k) gp[k] += g.p[k][I];
                }
                CHECK_REL(gm, M, 1e-13);
                for (k = 0; k < dim; ++k) CHECK_NEAR(gp[k], mom[k], 1e-12 * M);
                CHECK_EQ_INT(gk_mpm_grid_update(&g, &d, 1e-3, &e), GK_OK);
                if (tr == 1) {
                    double v0 = P.v[0][17];
                    CHECK_EQ_INT(gk_mpm_g2p(&g, &P, &d, 1e-3, GK_MPM_G2P_VELOCITY, &e), GK_OK);
                    CHECK_NEAR(P.v[0][17], v0, 1e-15);
                } else {
                    CHECK_EQ_INT(gk_mpm_g2p(&g, &P, &d, 1e-3, GK_MPM_G2P_VELOCITY, &e), GK_OK);
                }
                gk_mpm_points_totals(&P, &M2, mom2, NULL);
                CHECK_REL(M2, M, 1e-15);
                for (k = 0; k < dim; ++k) CHECK_NEAR(mom2[k], mom[k], 1e-12 * M);
                gk_mpm_points_destroy(&P);
                gk_mpm_grid_destroy(&g);
            }
}

/* APIC (Jiang et al. 2015): an affine velocity v = W (x - c) + v0 with C = W
 * survives P2G + G2P exactly; here W is a rigid rotation (2D: about z; 3D:
 * about an oblique axis). Checked for every basis. */
TEST(apic_preserves_rigid_rotation) {
    int dim, bi;
    for (dim = 2; dim <= 3; ++dim)
        for (bi = 0; bi < 4; ++bi) {
            gk_mpm_grid g = make_grid(dim, 0.0, 0.0, 0.0, 0.1, 12, 11, 10);
            gk_mpm_points P;
            gk_mpm_def d = gk_mpm_def_default();
            gk_err e;
            double w[3] = {0.0, 0.0, 2.0}, c[3] = {0.55, 0.5, 0.45}, W[9], v0[3] = {0.3, -0.2, 0.1};
            double errv = 0, errc = 0;
            int p, i, j;
            if (dim == 3) {
                w[0] = 0.7;
                w[1] = -1.1;
            }
            gk_m3_zero(W); /* W x = w cross x */
            W[1] = -w[2];
            W[3] = w[2];
            W[2] = w[1];
            W[6] = -w[1];
            W[5] = -w[0];
            W[7] = w[0];
            random_points(&P, &g, 400, 5);
            for (p = 0; p < P.n; ++p) {
                for (i = 0; i < dim; ++i) {
                    P.v[i][p] = v0[i];
                    for (j = 0; j < dim; ++j) P.v[i][p] += W[3 * i + j] * (P.x[j][p] - c[j]);
                }
                gk_m3_copy(W, P.C + 9 * p);
            }
            d.basis = all_bases[bi];
            d.transfer = GK_MPM_APIC;
            CHECK_EQ_INT(gk_mpm_p2g(&g, &P, &d, 3, &e), GK_OK);
            CHECK_EQ_INT(gk_mpm_grid_update(&g, &d, 1e-3, &e), GK_OK);
            CHECK_EQ_INT(gk_mpm_g2p(&g, &P, &d, 1e-3, GK_MPM_G2P_VELOCITY, &e), GK_OK);
            for (p = 0; p < P.n; ++p)
                for (i = 0; i < dim; ++i) {
                    double ve = v0[i];
                    for (j = 0; j < dim; ++j) {
                        ve += W[3 * i + j] * (P.x[j][p] - c[j]);
                        if (fabs(P.C[9 * p + 3 * i + j] - W[3 * i + j]) > errc)
                            errc = fabs(P.C[9 * p + 3 * i + j] - W[3 * i + j]);
                    }
                    if (fabs(P.v[i][p] - ve) > errv) errv = fabs(P.v[i][p] - ve);
                }
            if (errv > 1e-13 || errc > 1e-12)
                printf("    %dD %s: |dv| %.2e |dC| %.2e\n", dim, basis_name[bi], errv, errc);
            CHECK(errv <= 1e-13);
            CHECK(errc <= 1e-12);
            gk_mpm_points_destroy(&P);
            gk_mpm_grid_destroy(&g);
        }
}

/* Fixed-free elastic bar in uniaxial strain (rollers on the top and bottom
 * rows, roller wall at x = x0): first mode omega = pi c / (2 L), period
 * T = 4 L / c, c = sqrt((K + G) / rho) (2D P-wave modulus M = K + G).
 * Initial velocity v0 sin(pi x / 2L) excites mode 1 only; total momentum
 * goes as cos(omega t): zero crossings at T/4 and 3T/4. */
TEST(elastic_bar_first_mode_frequency) {
    const double h = 0.05, Lb = 1.0, rho = 1000.0;
    elastic_law law;
    int sc;
    law.K = 6e5;
    law.G = 4e5;
    /* runs 0-2: linear in USF, USL, MUSL; 3-5: uGIMP, quadratic, cubic B-spline in MUSL */
    for (sc = 0; sc < 6; ++sc) {
        gk_mpm_grid g = make_grid(2, 0.0, 0.0, 0.0, h, 27, 6, 1);
        gk_mpm_points P;
        gk_mpm_def d = gk_mpm_def_default();
        gk_err e;
        double lo[3] = {2 * h, 2 * h, 0}, hi[3] = {2 * h + Lb, 3 * h, 0},
               c = gk_mpm_wave_speed(law.K, law.G, rho, 2);
        double T = 4 * Lb / c, dt = 0.1 * h / c, t = 0, prev, mom0[3], cross[2] = {0, 0};
        int p, ncross = 0, step;
        CHECK_EQ_INT(gk_mpm_points_create_box(&P, 2, lo, hi, h, 2, rho, NULL, &e), GK_OK);
        for (p = 0; p < P.n; ++p) P.v[0][p] = 0.01 * sin(GK_PI * (P.x[0][p] - lo[0]) / (2 * Lb));
        gk_mpm_grid_set_bc(&g, 0, GK_MPM_BC_ROLLER, 0, 3, &e);
        gk_mpm_grid_set_bc(&g, 2, GK_MPM_BC_ROLLER, 0, 3, &e);
        gk_mpm_grid_set_bc(&g, 3, GK_MPM_BC_ROLLER, 0, 3, &e);
        d.scheme = sc < 3 ? (gk_mpm_scheme)sc : GK_MPM_MUSL;
        d.basis = sc < 3 ? GK_MPM_LINEAR : all_bases[sc - 2];
        d.alpha = 0.0;
        gk_mpm_points_totals(&P, NULL, mom0, NULL);
        prev = mom0[0];
        for (step = 0; step < (int)(1.0 * T / dt) && ncross < 2; ++step) {
            double mom[3];
            gk_result r = gk_mpm_step(&g, &P, &d, dt, elastic_cb, &law, &e);
            if (r) {
                printf("    step failed: %s\n", e.msg);
                CHECK(0);
                break;
            }
            gk_mpm_points_totals(&P, NULL, mom, NULL);
            if ((prev > 0) != (mom[0] > 0)) cross[ncross++] = t + dt * prev / (prev - mom[0]);
            prev = mom[0];
            t += dt;
        }
        CHECK_EQ_INT(ncross, 2);
        if (ncross == 2) {
            if (fabs(2 * (cross[1] - cross[0]) / T - 1) > 0.03)
                printf("    run %d: period %.5f s, analytic %.5f s\n", sc, 2 * (cross[1] - cross[0]), T);
            /* uniform B-splines (no boundary-modified splines) smear the free
             * end over about h/2: effective length ~ L + h/2, period +2.5 % */
            double tol = sc >= 4 ? 0.03 : 0.01;
            CHECK_REL(2 * (cross[1] - cross[0]), T, tol);
            CHECK_REL(cross[0], T / 4, tol);
        }
        gk_mpm_points_destroy(&P);
        gk_mpm_grid_destroy(&g);
    }
}

/* Elastic column under gravity, rollers on the sides, fixed base, local grid
 * damping: at rest sigma_yy = -rho g (H - Y) (Y = initial height above the
 * base: the weight of the material above a point, per unit area), and the
 * base carries the whole weight rho g H w. */
TEST(column_settles_to_geostatic_stress) {
    const double h = 1.0 / 16, H = 1.0, rho = 1000.0, grav = 10.0;
    gk_mpm_grid g = make_grid(2, 0.0, 0.0, 0.0, h, 7, 21, 1);
    gk_mpm_points P;
    gk_mpm_def d = gk_mpm_def_default();
    gk_err e;
    elastic_law law;
    double lo[3] = {2 * h, 2 * h, 0}, hi[3] = {4 * h, 2 * h + H, 0}, *Y, c, dt, worst = 0, ke = 0,
           mean_err = 0;
    int p, step, nsteps;
    law.K = 6e6; /* settlement 0.1 %: small against the cell size */
    law.G = 4e6;
    c = gk_mpm_wave_speed(law.K, law.G, rho, 2);
    dt = 0.25 * h / c;
    nsteps = (int)(0.5 / dt);
    CHECK_EQ_INT(gk_mpm_points_create_box(&P, 2, lo, hi, h, 2, rho, NULL, &e), GK_OK);
    Y = (double *)malloc(sizeof(double) * P.n);
    for (p = 0; p < P.n; ++p) Y[p] = P.x[1][p] - lo[1];
    gk_mpm_grid_set_bc(&g, 0, GK_MPM_BC_ROLLER, 0, 3, &e);
    gk_mpm_grid_set_bc(&g, 1, GK_MPM_BC_ROLLER, 0, 3, &e);
    gk_mpm_grid_set_bc(&g, 2, GK_MPM_BC_FIXED, 0, 3, &e);
    d.gravity[1] = -grav;
    d.damping = 0.3;
    d.alpha = 0.0;
    d.scheme = GK_MPM_USF;
    for (step = 0; step < nsteps; ++step)
        if (gk_mpm_step(&g, &P, &d, dt, elastic_cb, &law, &e)) {
            printf("    %s\n", e.msg);
            CHECK(0);
            break;
        }
    for (p = 0; p < P.n; ++p) {
        double ex = -rho * grav * (H - Y[p]), err = P.sigma[9 * p + 4] - ex;
        if (fabs(err) > worst) worst = fabs(err);
        mean_err += err / P.n;
    }
    gk_mpm_points_totals(&P, NULL, NULL, &ke);
    /* piecewise-linear velocity: stress is constant per cell, so a point may
     * be off by up to rho g h / 4 from the pointwise line */
    if (worst > 0.3 * rho * grav * h)
        printf("    worst sigma_yy error %.1f Pa (rho g h = %.1f)\n", worst, rho * grav * h);
    CHECK(worst <= 0.3 * rho * grav * h);
    CHECK_NEAR(mean_err, 0.0, 0.005 * rho * grav * H);
    CHECK_REL(g.face[2].force[1], rho * grav * H * 2 * h, 1e-3);
    CHECK(ke < 1e-6 * rho * grav * H * H * 2 * h);
    free(Y);
    gk_mpm_points_destroy(&P);
    gk_mpm_grid_destroy(&g);
}

/* A block sliding on a Coulomb floor (mu) under gravity decelerates at
 * mu g: the floor's tangential impulses are mu times its normal impulses,
 * which carry the weight. v(t) = v0 - mu g t while sliding; mu = 0 keeps v0. */
TEST(block_on_frictional_floor_decelerates_at_mu_g) {
    const double h = 0.05, rho = 1000.0, grav = 10.0, v0 = 1.0, T = 0.2;
    double mus[2] = {0.3, 0.0};
    int c;
    for (c = 0; c < 2; ++c) {
        gk_mpm_grid g = make_grid(2, 0.0, 0.0, 0.0, h, 16, 8, 1);
        gk_mpm_points P;
        gk_mpm_def d = gk_mpm_def_default();
        gk_err e;
        elastic_law law;
        double lo[3] = {2 * h, 2 * h, 0}, hi[3] = {6 * h, 4 * h, 0}, dt, t = 0, M, mom[3], fx = 0, fy = 0;
        int p, nsteps, step;
        law.K = 6e6;
        law.G = 4e6;
        dt = 0.2 * h / gk_mpm_wave_speed(law.K, law.G, rho, 2);
        nsteps = (int)(T / dt + 0.5);
        CHECK_EQ_INT(gk_mpm_points_create_box(&P, 2, lo, hi, h, 2, rho, NULL, &e), GK_OK);
        for (p = 0; p < P.n; ++p) P.v[0][p] = v0;
        CHECK_EQ_INT(gk_mpm_grid_set_bc(&g, 2, GK_MPM_BC_FRICTION, mus[c], 3, &e), GK_OK);
        d.gravity[1] = -grav;
        d.alpha = 0.0;
        d.scheme = GK_MPM_MUSL;
        for (step = 0; step < nsteps; ++step) {
            if (gk_mpm_step(&g, &P, &d, dt, elastic_cb, &law, &e)) {
                printf("    %s\n", e.msg);
                CHECK(0);
                break;
            }
            fx += g.face[2].force[0] * dt;
            fy += g.face[2].force[1] * dt;
            t += dt;
        }
        gk_mpm_points_totals(&P, &M, mom, NULL);
        if (mus[c] > 0) {
            CHECK_REL(mom[0] / M, v0 - mus[c] * grav * t, 0.01);
            /* the floor's impulses: tangential = mu x normal where sliding */
            CHECK(fx <= 0 && -fx <= mus[c] * fy * (1 + 1e-12)); /* Coulomb: |T| <= mu N */
            CHECK(-fx >= 0.95 * mus[c] * fy);                   /* sliding nearly everywhere */
            CHECK_REL(fy, M * grav * t, 0.01);
        } else {
            CHECK_REL(mom[0] / M, v0, 1e-9);
        }
        gk_mpm_points_destroy(&P);
        gk_mpm_grid_destroy(&g);
    }
}

/* A rough rigid plate moving down slowly onto an elastic layer (rollers on
 * the sides, fixed base) compresses it in uniaxial strain: the force the
 * plate exerts is sigma_yy w = -(K + G) (delta / H) w (quasi-static). */
TEST(rigid_plate_reaction_matches_confined_compression) {
    const double h = 0.05, H = 0.5, rho = 1000.0, V = 0.01, tramp = 0.1, tend = 0.5;
    gk_mpm_grid g = make_grid(2, 0.0, 0.0, 0.0, h, 7, 16, 1);
    gk_mpm_points P;
    gk_mpm_def d = gk_mpm_def_default();
    gk_mpm_body plate;
    gk_err e;
    elastic_law law;
    double lo[3] = {2 * h, 2 * h, 0}, hi[3] = {4 * h, 2 * h + H, 0}, dt, t = 0, ytop0, favg = 0, delta;
    int nsteps, step, navg = 0;
    law.K = 6e5;
    law.G = 4e5;
    dt = 0.2 * h / gk_mpm_wave_speed(law.K, law.G, rho, 2);
    nsteps = (int)(tend / dt);
    CHECK_EQ_INT(gk_mpm_points_create_box(&P, 2, lo, hi, h, 2, rho, NULL, &e), GK_OK);
    memset(&plate, 0, sizeof plate);
    plate.lo[0] = -1;
    plate.hi[0] = 1;
    plate.lo[1] = hi[1] - 0.1 * h; /* covers the node row at the layer top */
    plate.hi[1] = 10;
    plate.contact = GK_MPM_CONTACT_STICK;
    ytop0 = plate.lo[1];
    g.body = &plate;
    g.nbody = 1;
    gk_mpm_grid_set_bc(&g, 0, GK_MPM_BC_ROLLER, 0, 3, &e);
    gk_mpm_grid_set_bc(&g, 1, GK_MPM_BC_ROLLER, 0, 3, &e);
    gk_mpm_grid_set_bc(&g, 2, GK_MPM_BC_FIXED, 0, 3, &e);
    d.damping = 0.1;
    d.alpha = 0.0;
    for (step = 0; step < nsteps; ++step) {
        plate.v[1] = -V * (t < tramp ? t / tramp : 1.0);
        if (gk_mpm_step(&g, &P, &d, dt, elastic_cb, &law, &e)) {
            printf("    %s\n", e.msg);
            CHECK(0);
            break;
        }
        t += dt;
        if (step >= nsteps - 40) {
            favg += plate.force[1];
            ++navg;
        }
    }
    favg /= navg;
    delta = ytop0 - plate.lo[1] - 20 * dt * V; /* displacement at the middle of the averaging window */
    CHECK_REL(favg, -(law.K + law.G) * delta / H * 2 * h, 0.02);
    /* the base carries the same load */
    CHECK_REL(g.face[2].force[1], -favg, 0.03);
    gk_mpm_points_destroy(&P);
    gk_mpm_grid_destroy(&g);
}

/* Node-level contact laws, checked on hand-set node states (m = 2, no
 * force): Coulomb wall removes the approaching normal velocity dv_n and
 * cuts the tangential speed by mu dv_n (or sticks); separating nodes are
 * free; roller zeroes the normal component both ways; fixed zeroes all.
 * Rigid body: the same laws on the velocity relative to the body; the
 * reported force is sum m dv / dt. */
TEST(wall_and_body_contact_laws) {
    const double dt = 0.5, m = 2.0;
    int kind;
    for (kind = 0; kind < 4; ++kind) { /* body: stick, friction, smooth, friction with explicit face */
        gk_mpm_grid g = make_grid(2, 0.0, 0.0, 0.0, 1.0, 6, 6, 1);
        gk_mpm_def d = gk_mpm_def_default();
        gk_mpm_body body;
        gk_err e;
        int nodes[7][2] = {{2, 0}, {3, 0}, {4, 0}, {0, 2}, {0, 3}, {5, 3}, {2, 3}};
        double vel[7][2] = {{3, -1}, {0.2, -1}, {1, 1}, {-1, 0.5}, {1, 0.5}, {1, 2}, {1, 0}};
        double want[7][2] = {{2.5, 0}, {0, 0}, {1, 1}, {0, 0.5}, {0, 0.5}, {0, 0}, {0, 0}};
        int q;
        memset(&body, 0, sizeof body);
        body.lo[0] = 1.4; /* node (2,3): nearest face is y- (0.5 away; x- is 0.6) */
        body.lo[1] = 2.5;
        body.hi[0] = 3.5;
        body.hi[1] = 10;
        body.v[1] = -1;
        body.mu = 0.5;
        body.contact = kind == 0   ? GK_MPM_CONTACT_STICK
                       : kind == 2 ? GK_MPM_CONTACT_SMOOTH
                                   : GK_MPM_CONTACT_FRICTION;
        body.face = kind == 3 ? 3 : 0;
        /* relative velocity (1, 1) into the body face y- (outward normal -y) */
        want[6][0] = kind == 0 ? 0.0 : kind == 2 ? 1.0 : 0.5;
        want[6][1] = -1.0;
        g.body = &body;
        g.nbody = 1;
        CHECK_EQ_INT(gk_mpm_grid_set_bc(&g, 2, GK_MPM_BC_FRICTION, 0.5, 1, &e), GK_OK);
        CHECK_EQ_INT(gk_mpm_grid_set_bc(&g, 0, GK_MPM_BC_ROLLER, 0, 1, &e), GK_OK);
        CHECK_EQ_INT(gk_mpm_grid_set_bc(&g, 1, GK_MPM_BC_FIXED, 0, 1, &e), GK_OK);
        for (q = 0; q < 7; ++q) {
            size_t I = (size_t)(nodes[q][0] + 6 * nodes[q][1]);
            g.m[I] = m;
            g.v[0][I] = vel[q][0];
            g.v[1][I] = vel[q][1];
            g.p[0][I] = m * vel[q][0];
            g.p[1][I] = m * vel[q][1];
        }
        CHECK_EQ_INT(gk_mpm_grid_update(&g, &d, dt, &e), GK_OK);
        for (q = 0; q < 7; ++q) {
            size_t I = (size_t)(nodes[q][0] + 6 * nodes[q][1]);
            CHECK_NEAR(g.vn[0][I], want[q][0], 1e-15);
            CHECK_NEAR(g.vn[1][I], want[q][1], 1e-15);
        }
        /* y- face acts on nodes 0..2: reaction m dv / dt */
        CHECK_NEAR(g.face[2].force[0], m * ((2.5 - 3) + (0 - 0.2)) / dt, 1e-13);
        CHECK_NEAR(g.face[2].force[1], m * (1 + 1) / dt, 1e-13);
        CHECK_NEAR(body.force[0], m * (want[6][0] - 1) / dt, 1e-13);
        CHECK_NEAR(body.force[1], m * (want[6][1] - 0) / dt, 1e-13);
        gk_mpm_grid_destroy(&g);
    }
}

/* Circle bodies (a pipe), on hand-set node states (mass 2, no force):
 * STICK - the nodes inside the circle (|x_I - c| <= r) take the body's
 * velocity, every other node of its bounding box keeps its own (here at
 * rest); SMOOTH - the unilateral law of the wall on the velocity relative
 * to the body with the radial normal n = (x_I - c)/|x_I - c|: an approaching
 * node loses its normal component, keeps its tangential one, a separating
 * node is free. Both: the reaction is the momentum change of the grid,
 * force = sum m (v_after - v_before) / dt (Newton's third law, as for
 * boxes), and the centre moves by v dt. 2D disk and 3D cylinder along z. */
TEST(circle_body_contact) {
    const double dt = 0.25, m = 2.0, c[2] = {5.3, 5.6}, r = 2.2;
    int dim, kind;
    for (dim = 2; dim <= 3; ++dim)
        for (kind = 0; kind < 2; ++kind) { /* stick, smooth */
            gk_mpm_grid g = make_grid(dim, 0.0, 0.0, 0.0, 1.0, 12, 12, dim == 3 ? 3 : 1);
            gk_mpm_def d = gk_mpm_def_default();
            gk_mpm_body body;
            gk_err e;
            double mom[3] = {0, 0, 0}, u[2] = {0.4, -0.9};
            size_t I;
            int k, ncov = 0, nbox_out = 0, lo[3], hi[3];
            memset(&body, 0, sizeof body);
            body.shape = GK_MPM_CIRCLE;
            body.centre[0] = c[0], body.centre[1] = c[1], body.radius = r;
            body.v[0] = 0.7, body.v[1] = -1.3;
            body.contact = kind == 0 ? GK_MPM_CONTACT_STICK : GK_MPM_CONTACT_SMOOTH;
            g.body = &body;
            g.nbody = 1;
            for (I = 0; I < g.nnode; ++I) { /* stick: the block at rest; smooth: moving at u */
                g.m[I] = m;
                for (k = 0; k < 2; ++k) g.v[k][I] = kind == 0 ? 0.0 : u[k], g.p[k][I] = m * g.v[k][I];
            }
            CHECK_EQ_INT(gk_mpm_grid_update(&g, &d, dt, &e), GK_OK);
            gk_mpm_body_nodes(&g, &body, lo, hi);
            for (I = 0; I < g.nnode; ++I) {
                double x[3], dx, dy, dist, nrm[2], rel[2], want[2];
                int i = (int)(I % 12), j = (int)(I / 12 % 12);
                gk_mpm_grid_node_position(&g, I, x);
                dx = x[0] - c[0], dy = x[1] - c[1], dist = sqrt(dx * dx + dy * dy);
                for (k = 0; k < dim; ++k) mom[k] += m * (g.vn[k][I] - g.v[k][I]);
                if (dist > r) { /* outside: unchanged, also inside the bounding box */
                    nbox_out += i >= lo[0] && i <= hi[0] && j >= lo[1] && j <= hi[1];
                    CHECK(g.vn[0][I] == g.v[0][I] && g.vn[1][I] == g.v[1][I]);
                    continue;
                }
                ++ncov;
                if (kind == 0) {
                    CHECK(g.vn[0][I] == body.v[0] && g.vn[1][I] == body.v[1]);
                    continue;
                }
                nrm[0] = dx / dist, nrm[1] = dy / dist;
                rel[0] = u[0] - body.v[0], rel[1] = u[1] - body.v[1];
                {
                    double vn = rel[0] * nrm[0] + rel[1] * nrm[1], cut = vn < 0 ? vn : 0.0;
                    want[0] = u[0] - cut * nrm[0], want[1] = u[1] - cut * nrm[1];
                }
                CHECK_NEAR(g.vn[0][I], want[0], 1e-14);
                CHECK_NEAR(g.vn[1][I], want[1], 1e-14);
                /* tangential relative velocity kept */
                CHECK_NEAR((g.vn[0][I] - body.v[0]) * -nrm[1] + (g.vn[1][I] - body.v[1]) * nrm[0],
                           rel[0] * -nrm[1] + rel[1] * nrm[0], 1e-14);
            }
            CHECK_EQ_INT(ncov, (dim == 3 ? 3 : 1) * 14); /* 14 nodes of the unit lattice in this circle */
            CHECK(nbox_out > 0);
            for (k = 0; k < dim; ++k) CHECK_NEAR(body.force[k], mom[k] / dt, 1e-12 * ncov);
            if (kind == 0) CHECK_NEAR(body.force[0], ncov * m * 0.7 / dt, 1e-12 * ncov);
            gk_mpm_bodies_advance(&body, 1, dt);
            CHECK_NEAR(body.centre[0], c[0] + 0.7 * dt, 1e-15);
            CHECK_NEAR(body.centre[1], c[1] - 1.3 * dt, 1e-15);
            gk_mpm_grid_destroy(&g);
        }
}

/* a bad circle (radius <= 0, NaN, infinite centre, a face, an unknown shape) is refused with a
 * message; the grid velocities and the body are unchanged */
TEST(circle_body_bad_input_refused) {
    gk_mpm_grid g = make_grid(2, 0.0, 0.0, 0.0, 1.0, 8, 8, 1);
    gk_mpm_def d = gk_mpm_def_default();
    gk_mpm_body body, saved;
    gk_err e;
    double *vn0 = (double *)malloc(2 * g.nnode * sizeof(double));
    size_t I;
    int q;
    for (I = 0; I < g.nnode; ++I) g.m[I] = 1.0, g.v[0][I] = g.p[0][I] = 0.5, g.vn[0][I] = 7.0;
    memcpy(vn0, g.vn[0], g.nnode * sizeof(double));
    memcpy(vn0 + g.nnode, g.vn[1], g.nnode * sizeof(double));
    for (q = 0; q < 6; ++q) {
        memset(&body, 0, sizeof body);
        body.shape = GK_MPM_CIRCLE;
        body.centre[0] = body.centre[1] = 4.0;
        body.radius = q == 0 ? 0.0 : q == 1 ? -1.0 : q == 2 ? NAN : 1.5;
        if (q == 3) body.centre[1] = INFINITY;
        if (q == 4) body.face = 2;
        if (q == 5) body.shape = (gk_mpm_body_shape)7;
        body.v[1] = -1.0;
        body.force[0] = 3.0;
        saved = body;
        g.body = &body;
        g.nbody = 1;
        CHECK(gk_mpm_grid_update(&g, &d, 0.1, &e) != GK_OK);
        CHECK(strstr(e.msg, "rigid body 0") != NULL);
        CHECK(memcmp(&body, &saved, sizeof body) == 0);
        CHECK(memcmp(vn0, g.vn[0], g.nnode * sizeof(double)) == 0);
        CHECK(memcmp(vn0 + g.nnode, g.vn[1], g.nnode * sizeof(double)) == 0);
    }
    free(vn0);
    gk_mpm_grid_destroy(&g);
}

/* Drucker-Prager [Chen et al. 2021 eqs 5-6, return map of its Sec 2.2]: an elastic
 * trial is untouched; a cone return lands on f = 0, keeps the direction of
 * s and moves p by -K etabar dlambda; a tensile trial goes to the apex
 * p = zeta c / eta, s = 0. 2D and 3D. */
TEST(drucker_prager_return_map) {
    int dim;
    for (dim = 2; dim <= 3; ++dim) {
        gk_mpm_dp dp;
        gk_mpm_dp_info info;
        gk_err e;
        double sig[9], tr[9], out[9], phi = 30 * GK_PI / 180, psi = 10 * GK_PI / 180;
        int k;
        CHECK_EQ_INT(gk_mpm_dp_init(&dp, dim, 1e7, 5e6, phi, psi, 0.0, &e), GK_OK);
        if (dim == 2) {
            CHECK_NEAR(dp.eta, 0.5, 1e-15);
            CHECK_NEAR(dp.zeta, cos(phi), 1e-15);
        }
        /* elastic: p = -100 kPa, q = 10 kPa */
        gk_m3_zero(tr);
        for (k = 0; k < dim; ++k) tr[4 * k] = -1e5;
        tr[1] = tr[3] = 1e4;
        CHECK_EQ_INT(gk_mpm_dp_return(&dp, dim, tr, out, &info, &e), GK_OK);
        CHECK_EQ_INT(info.status, 0);
        CHECK(memcmp(tr, out, sizeof tr) == 0);
        /* cone: q = 80 kPa (> eta |p| = 50 kPa in 2D) */
        tr[1] = tr[3] = 8e4;
        tr[0] = -1.2e5;
        tr[4] = -0.8e5;
        CHECK_EQ_INT(gk_mpm_dp_return(&dp, dim, tr, sig, &info, &e), GK_OK);
        CHECK_EQ_INT(info.status, 1);
        CHECK_NEAR(gk_mpm_dp_yield(&dp, dim, sig), 0.0, 1e-9 * 1e5);
        CHECK(info.f_trial > 0);
        {
            double ptr = 0, pn = 0;
            for (k = 0; k < dim; ++k) {
                ptr += tr[4 * k] / dim;
                pn += sig[4 * k] / dim;
            }
            CHECK_REL(pn, ptr - dp.K * dp.etabar * info.dlambda, 1e-12);
            /* s keeps its direction: s_xy / (s_xx - s_yy) unchanged */
            CHECK_REL(sig[1] / (sig[0] - sig[4]), tr[1] / (tr[0] - tr[4]), 1e-12);
            /* plastic strain: volumetric part etabar dlambda (dilatant, psi > 0) */
            CHECK_REL(info.deps_p[0] + info.deps_p[4] + info.deps_p[8], dp.etabar * info.dlambda, 1e-9);
        }
        /* apex, no cohesion: tensile trial -> zero stress */
        gk_m3_zero(tr);
        for (k = 0; k < dim; ++k) tr[4 * k] = 5e4;
        tr[1] = tr[3] = 1e3;
        CHECK_EQ_INT(gk_mpm_dp_return(&dp, dim, tr, sig, &info, &e), GK_OK);
        CHECK_EQ_INT(info.status, 2);
        for (k = 0; k < 9; ++k) CHECK_NEAR(sig[k], 0.0, 1e-9);
        /* apex with cohesion: p = zeta c / eta, s = 0 */
        dp.c = 2e4;
        CHECK_EQ_INT(gk_mpm_dp_return(&dp, dim, tr, sig, &info, &e), GK_OK);
        CHECK_EQ_INT(info.status, 2);
        CHECK_REL(sig[0], dp.zeta * dp.c / dp.eta, 1e-12);
        CHECK_NEAR(sig[1], 0.0, 1e-9);
        CHECK_NEAR(gk_mpm_dp_yield(&dp, dim, sig), 0.0, 1e-9 * 1e5);
    }
}

/* dp_update: a pure spin rotates the stress (sigma' = R sigma R^T, no yield
 * change); shearing a dense packing (Phi > Phi_cs) at yield dilates it:
 * Phi decreases towards Phi_cs [Chen et al. 2021 eq 8] and the stress stays on f = 0. */
TEST(drucker_prager_update_spin_and_critical_state) {
    gk_mpm_dp dp;
    gk_err e;
    double sig[9] = {-2e5, 3e4, 0, 3e4, -1e5, 0, 0, 0, 0}, dH[9], R[9], W[9], T[9], Rt[9], ex[9], Phi = 0.84;
    int k, step;
    CHECK_EQ_INT(gk_mpm_dp_init(&dp, 2, 1e7, 5e6, 0.5, 0.1, 0.0, &e), GK_OK);
    gk_m3_zero(dH);
    dH[1] = -0.01;
    dH[3] = 0.01;
    gk_m3_skew(dH, W);
    gk_m3_exp(W, R);
    gk_m3_mul(R, sig, T);
    gk_m3_transpose(R, Rt);
    gk_m3_mul(T, Rt, ex);
    CHECK_EQ_INT(gk_mpm_dp_update(&dp, 2, dH, sig, NULL, NULL, &e), GK_OK);
    for (k = 0; k < 9; ++k) CHECK_NEAR(sig[k], ex[k], 1e-9);
    dp.tan_phi_cs = tan(0.27);
    dp.Phi_cs = 0.815;
    dp.chi = 7;
    dp.xi = 0.5;
    gk_m3_zero(sig);
    sig[0] = sig[4] = -1e5;
    gk_m3_zero(dH);
    dH[1] = 2e-4; /* simple shear increments */
    for (step = 0; step < 400; ++step) {
        double prev = Phi;
        gk_mpm_dp_info info;
        CHECK_EQ_INT(gk_mpm_dp_update(&dp, 2, dH, sig, &Phi, &info, &e), GK_OK);
        if (info.status) CHECK(Phi <= prev);
    }
    CHECK(Phi < 0.84);
    CHECK(Phi > dp.Phi_cs);
}

/* eq 7 below Phi_cs - tan phi_cs / chi gives tan phi < 0: refused with nothing written (the update
 * once clamped phi to 0, kept psi < 0, failed its own parameter check inside and returned GK_OK with
 * the stress unchanged and the info uninitialised); just above the bound it updates */
TEST(drucker_prager_update_refuses_a_negative_friction) {
    gk_mpm_dp dp;
    gk_mpm_dp_info info;
    gk_err e;
    double sig[9] = {-1e5, 0, 0, 0, -1e5, 0, 0, 0, 0}, dH[9], keep[9], bound, Phi;
    int k;
    CHECK_EQ_INT(gk_mpm_dp_init(&dp, 2, 630e6, 460e6, 0.27, 0.0, 0.0, &e), GK_OK);
    dp.tan_phi_cs = tan(0.27);
    dp.Phi_cs = 0.815;
    dp.chi = 7;
    dp.xi = 0.01;
    bound = dp.Phi_cs - dp.tan_phi_cs / dp.chi; /* 0.7755 */
    gk_m3_zero(dH);
    dH[0] = -1e-3;
    dH[4] = 1e-3;
    memcpy(keep, sig, sizeof sig);
    Phi = bound - 1e-3;
    info.status = -7;
    CHECK_EQ_INT(gk_mpm_dp_update(&dp, 2, dH, sig, &Phi, &info, &e), GK_ERR_ARG);
    CHECK(strstr(e.msg, "tan phi") != NULL);
    CHECK(Phi == bound - 1e-3);
    CHECK_EQ_INT(info.status, -7);
    for (k = 0; k < 9; ++k) CHECK(sig[k] == keep[k]);
    Phi = bound + 1e-3;
    CHECK_EQ_INT(gk_mpm_dp_update(&dp, 2, dH, sig, &Phi, &info, &e), GK_OK);
    CHECK(info.status > 0); /* this shear yields the nearly frictionless, cohesionless material */
    CHECK(sig[0] != keep[0]);
    { /* the two parts: gk_mpm_dp_at refuses the same packing fraction; together they give the bits */
        gk_mpm_dp at, at0;
        double sig2[9], Phi2, Phi3, notnum = NAN;
        memset(&at, 0x5a, sizeof at);
        at0 = at;
        CHECK_EQ_INT(gk_mpm_dp_at(&dp, 2, bound - 1e-3, &at, &e), GK_ERR_ARG);
        CHECK(strstr(e.msg, "tan phi") != NULL);
        CHECK_EQ_INT(gk_mpm_dp_at(&dp, 2, notnum, &at, &e), GK_ERR_ARG);
        CHECK_EQ_INT(gk_mpm_dp_at(&dp, 2, Phi, NULL, &e), GK_ERR_ARG);
        CHECK(memcmp(&at, &at0, sizeof at) == 0);
        memcpy(keep, sig, sizeof sig);
        memcpy(sig2, sig, sizeof sig);
        Phi2 = Phi3 = Phi;
        CHECK_EQ_INT(gk_mpm_dp_at(&dp, 2, Phi, &at, &e), GK_OK);
        CHECK(at.eta != dp.eta && at.etabar < 0.0); /* below Phi_cs: contractant, tan psi < 0 (eq 7) */
        CHECK_EQ_INT(gk_mpm_dp_update_at(&at, 2, dH, sig2, NULL, &info, &e), GK_ERR_ARG);
        CHECK_EQ_INT(gk_mpm_dp_update_at(&at, 2, dH, sig2, &notnum, &info, &e), GK_ERR_ARG);
        CHECK(memcmp(sig2, keep, sizeof keep) == 0);
        CHECK_EQ_INT(gk_mpm_dp_update_at(&at, 2, dH, sig2, &Phi2, &info, &e), GK_OK);
        CHECK_EQ_INT(gk_mpm_dp_update(&dp, 2, dH, sig, &Phi3, &info, &e), GK_OK);
        CHECK(memcmp(sig2, sig, sizeof sig) == 0 && memcmp(&Phi2, &Phi3, sizeof Phi2) == 0);
        CHECK(Phi3 != Phi); /* a plastic step: eq 8 moved it */
    }
}

/* Bitwise determinism: the coloured P2G gives every node its sum in one
 * fixed order, so 1 and 2 threads produce identical bits (whole steps,
 * 2D quadratic PIC/FLIP and 3D cubic APIC). */
TEST(threads_give_identical_bits) {
    int dim;
    for (dim = 2; dim <= 3; ++dim) {
        gk_mpm_grid g1 = make_grid(dim, 0.0, 0.0, 0.0, 0.1, 22, 21, 20),
                    g2 = make_grid(dim, 0.0, 0.0, 0.0, 0.1, 22, 21, 20);
        gk_mpm_points A, B;
        gk_mpm_def d = gk_mpm_def_default();
        elastic_law law;
        gk_err e;
        int n = dim == 2 ? 3000 : (QUICK ? 1500 : 6000), step, k, p, same = 1, nst = 3;
        size_t nn = g1.nnode;
        law.K = 1e4;
        law.G = 5e3;
        random_points(&A, &g1, n, 99);
        random_points(&B, &g2, n, 99);
        for (p = 0; p < n; ++p)
            for (k = 0; k < 9; ++k) {
                A.sigma[9 * p + k] = B.sigma[9 * p + k] =
                    (k % 3 < dim && k / 3 < dim) ? 100.0 * cos(p + 2.0 * k) : 0;
                A.C[9 * p + k] = B.C[9 * p + k] = (k % 3 < dim && k / 3 < dim) ? sin(p + 3.0 * k) : 0;
            }
        d.basis = dim == 2 ? GK_MPM_QUADRATIC : GK_MPM_CUBIC;
        d.transfer = dim == 2 ? GK_MPM_PIC_FLIP : GK_MPM_APIC;
        d.scheme = dim == 2 ? GK_MPM_MUSL : GK_MPM_USL;
        d.gravity[1] = -9.81;
        gk_mpm_grid_set_bc(&g1, 2, GK_MPM_BC_FRICTION, 0.4, 2, &e);
        gk_mpm_grid_set_bc(&g2, 2, GK_MPM_BC_FRICTION, 0.4, 2, &e);
        for (step = 0; step < nst; ++step) {
            d.threads = 1;
            CHECK_EQ_INT(gk_mpm_step(&g1, &A, &d, 1e-4, elastic_cb, &law, &e), GK_OK);
            d.threads = 2;
            CHECK_EQ_INT(gk_mpm_step(&g2, &B, &d, 1e-4, elastic_cb, &law, &e), GK_OK);
        }
        for (k = 0; k < dim; ++k) {
            same &= memcmp(A.x[k], B.x[k], n * sizeof(double)) == 0;
            same &= memcmp(A.v[k], B.v[k], n * sizeof(double)) == 0;
            same &= memcmp(g1.p[k], g2.p[k], nn * sizeof(double)) == 0;
            same &= memcmp(g1.vn[k], g2.vn[k], nn * sizeof(double)) == 0;
            same &= memcmp(g1.fint[k], g2.fint[k], nn * sizeof(double)) == 0;
        }
        same &= memcmp(g1.m, g2.m, nn * sizeof(double)) == 0;
        same &= memcmp(A.F, B.F, 9 * n * sizeof(double)) == 0;
        same &= memcmp(A.sigma, B.sigma, 9 * n * sizeof(double)) == 0;
        same &= memcmp(A.C, B.C, 9 * n * sizeof(double)) == 0;
        same &= memcmp(g1.face[2].force, g2.face[2].force, sizeof g1.face[2].force) == 0;
        CHECK(same);
#ifndef _OPENMP
        if (dim == 2) printf("    (built without OpenMP: both runs are serial)\n");
#endif
        gk_mpm_points_destroy(&A);
        gk_mpm_points_destroy(&B);
        gk_mpm_grid_destroy(&g1);
        gk_mpm_grid_destroy(&g2);
    }
}

/* L from an affine grid velocity is exact; F = (I + dt L) F, V = det F V0;
 * polar decomposition of F [Liang & Zhao 2019 eqs 36-40] recovers the rotation. */
TEST(velocity_gradient_F_and_polar) {
    gk_mpm_grid g = make_grid(2, 0.0, 0.0, 0.0, 0.1, 12, 12, 1);
    gk_mpm_points P;
    gk_mpm_def d = gk_mpm_def_default();
    gk_err e;
    double Lx[9] = {0.1, 0.4, 0, -0.2, -0.05, 0, 0, 0, 0}, dt = 0.01, R[9], U[9], dH[9];
    int p, k;
    random_points(&P, &g, 50, 3);
    for (p = 0; p < P.n; ++p)
        for (k = 0; k < 2; ++k) P.v[k][p] = Lx[3 * k] * P.x[0][p] + Lx[3 * k + 1] * P.x[1][p];
    d.transfer = GK_MPM_APIC;
    for (p = 0; p < P.n; ++p) gk_m3_copy(Lx, P.C + 9 * p);
    CHECK_EQ_INT(gk_mpm_p2g(&g, &P, &d, GK_MPM_P2G_MOMENTUM, &e), GK_OK);
    CHECK_EQ_INT(gk_mpm_g2p(&g, &P, &d, dt, GK_MPM_G2P_GRADIENT_OLD, &e), GK_OK);
    for (p = 0; p < P.n; ++p) {
        for (k = 0; k < 9; ++k) CHECK_NEAR(P.L[9 * p + k], Lx[k], 1e-12);
        CHECK_NEAR(P.F[9 * p + 0], 1 + dt * Lx[0], 1e-14);
        CHECK_NEAR(P.F[9 * p + 8], 1.0, 0);
        CHECK_REL(P.vol[p], gk_m3_det(P.F + 9 * p) * P.vol0[p], 1e-15);
    }
    gk_mpm_point_dh(&P, 0, dt, dH);
    CHECK_NEAR(dH[1], dt * Lx[1], 1e-14);
    /* a pure rotation by 0.3 rad */
    gk_m3_identity(P.F);
    P.F[0] = P.F[4] = cos(0.3);
    P.F[1] = -sin(0.3);
    P.F[3] = sin(0.3);
    CHECK_EQ_INT(gk_mpm_point_polar(&P, 0, R, U, &e), GK_OK);
    CHECK_NEAR(atan2(R[3], R[0]), 0.3, 1e-14);
    CHECK_NEAR(U[0], 1.0, 1e-14);
    P.F[0] = -P.F[0]; /* det F < 0: refused */
    P.F[1] = -P.F[1];
    CHECK_EQ_INT(gk_mpm_point_polar(&P, 0, R, U, &e), GK_ERR_SINGULAR);
    CHECK_EQ_INT(gk_mpm_point_polar(&P, P.n, R, U, &e), GK_ERR_ARG);
    gk_mpm_points_destroy(&P);
    gk_mpm_grid_destroy(&g);
}

/* Bad input: clear codes, messages, and nothing changed. */
TEST(bad_input_is_refused_and_changes_nothing) {
    gk_mpm_grid g;
    gk_mpm_points P;
    gk_mpm_def d = gk_mpm_def_default();
    gk_err e;
    double o[3] = {0, 0, 0}, *msave, x0, sig[9] = {1, 2, 0, 2, 3, 0, 0, 0, 0}, sig0[9], dH[9];
    int n[3] = {10, 10, 1}, k;
    gk_mpm_dp dp;
    CHECK_EQ_INT(gk_mpm_grid_create(&g, 2, o, 0.0, n, NULL, &e), GK_ERR_ARG);
    CHECK(strstr(e.msg, "spacing") != NULL);
    CHECK_EQ_INT(gk_mpm_grid_create(&g, 2, o, -1.0, n, NULL, &e), GK_ERR_ARG);
    CHECK_EQ_INT(gk_mpm_grid_create(&g, 2, o, NAN, n, NULL, &e), GK_ERR_NAN);
    CHECK_EQ_INT(gk_mpm_grid_create(&g, 4, o, 0.1, n, NULL, &e), GK_ERR_ARG);
    n[1] = 1;
    CHECK_EQ_INT(gk_mpm_grid_create(&g, 2, o, 0.1, n, NULL, &e), GK_ERR_ARG);
    n[1] = 10;
    o[0] = NAN;
    CHECK_EQ_INT(gk_mpm_grid_create(&g, 2, o, 0.1, n, NULL, &e), GK_ERR_NAN);
    g = make_grid(2, 0, 0, 0, 0.1, 10, 10, 1);
    CHECK_EQ_INT(gk_mpm_grid_set_bc(&g, 4, GK_MPM_BC_FIXED, 0, 1, &e), GK_ERR_ARG); /* z face in 2D */
    CHECK_EQ_INT(gk_mpm_grid_set_bc(&g, 2, GK_MPM_BC_FRICTION, -0.1, 1, &e), GK_ERR_ARG);
    CHECK_EQ_INT(gk_mpm_grid_set_bc(&g, 2, GK_MPM_BC_FRICTION, 0.1, 0, &e), GK_ERR_ARG);
    random_points(&P, &g, 20, 1);
    CHECK_EQ_INT(gk_mpm_p2g(&g, &P, &d, 3, &e), GK_OK);
    msave = (double *)malloc(g.nnode * sizeof(double));
    memcpy(msave, g.m, g.nnode * sizeof(double));
    /* a point outside the grid */
    x0 = P.x[0][5];
    P.x[0][5] = 5.0;
    CHECK_EQ_INT(gk_mpm_p2g(&g, &P, &d, 3, &e), GK_ERR_OUTSIDE);
    CHECK(strstr(e.msg, "point 5") != NULL);
    CHECK(memcmp(msave, g.m, g.nnode * sizeof(double)) == 0);
    /* on the last node is fine for linear, not for a B-spline */
    P.x[0][5] = 0.9;
    CHECK_EQ_INT(gk_mpm_g2p(&g, &P, &d, 1e-3, GK_MPM_G2P_GRADIENT_OLD, &e), GK_OK);
    d.basis = GK_MPM_QUADRATIC;
    CHECK_EQ_INT(gk_mpm_p2g(&g, &P, &d, 3, &e), GK_ERR_OUTSIDE);
    d.basis = GK_MPM_LINEAR;
    P.x[0][5] = x0;
    /* NaN velocity, zero mass, NaN stress */
    P.v[1][3] = NAN;
    CHECK_EQ_INT(gk_mpm_p2g(&g, &P, &d, 3, &e), GK_ERR_NAN);
    P.v[1][3] = 0;
    P.m[2] = 0;
    CHECK_EQ_INT(gk_mpm_p2g(&g, &P, &d, 3, &e), GK_ERR_MASS);
    P.m[2] = 1;
    P.sigma[9 * 4] = NAN;
    CHECK_EQ_INT(gk_mpm_p2g(&g, &P, &d, GK_MPM_P2G_FORCE, &e), GK_ERR_NAN);
    P.sigma[9 * 4] = 0;
    CHECK(memcmp(msave, g.m, g.nnode * sizeof(double)) == 0);
    /* uGIMP half-size beyond h/2 */
    d.basis = GK_MPM_UGIMP;
    P.lp[0] = 0.06;
    CHECK_EQ_INT(gk_mpm_p2g(&g, &P, &d, 3, &e), GK_ERR_ARG);
    d.basis = GK_MPM_LINEAR;
    /* bad def, bad dt: points unchanged */
    d.alpha = 1.5;
    CHECK_EQ_INT(gk_mpm_p2g(&g, &P, &d, 3, &e), GK_ERR_ARG);
    d.alpha = 0.1;
    x0 = P.x[0][0];
    CHECK_EQ_INT(gk_mpm_g2p(&g, &P, &d, 0.0, GK_MPM_G2P_POSITION, &e), GK_ERR_DT);
    CHECK_EQ_INT(gk_mpm_g2p(&g, &P, &d, NAN, GK_MPM_G2P_POSITION, &e), GK_ERR_NAN);
    CHECK_EQ_INT(gk_mpm_grid_update(&g, &d, -1.0, &e), GK_ERR_DT);
    CHECK_EQ_INT(gk_mpm_step(&g, &P, &d, 0.0, NULL, NULL, &e), GK_ERR_DT);
    CHECK(P.x[0][0] == x0);
    CHECK(memcmp(msave, g.m, g.nnode * sizeof(double)) == 0);
    /* constitutive functions */
    CHECK_EQ_INT(gk_mpm_dp_init(&dp, 2, 1e7, -1.0, 0.5, 0.1, 0, &e), GK_ERR_ARG);
    CHECK_EQ_INT(gk_mpm_dp_init(&dp, 2, 1e7, 1e6, 0.5, 0.7, 0, &e), GK_ERR_ARG); /* psi > phi */
    CHECK_EQ_INT(gk_mpm_dp_init(&dp, 2, 1e7, 1e6, 0.5, 0.1, 0, &e), GK_OK);
    memcpy(sig0, sig, sizeof sig);
    gk_m3_zero(dH);
    dH[0] = NAN;
    CHECK_EQ_INT(gk_mpm_dp_update(&dp, 2, dH, sig, NULL, NULL, &e), GK_ERR_NAN);
    CHECK_EQ_INT(gk_mpm_elastic_update(1e6, 1e5, 2, dH, sig, &e), GK_ERR_NAN);
    dH[0] = 0;
    CHECK_EQ_INT(gk_mpm_elastic_update(-1e6, 1e5, 2, dH, sig, &e), GK_ERR_ARG);
    CHECK(memcmp(sig, sig0, sizeof sig) == 0);
    for (k = 0; k < 9; ++k) sig0[k] = NAN;
    CHECK_EQ_INT(gk_mpm_dp_return(&dp, 2, sig0, sig, NULL, &e), GK_ERR_NAN);
    CHECK(sig[0] == 1);
    CHECK_EQ_INT(gk_mpm_points_create_box(&P, 2, o, o, 0.1, 2, 1000, NULL, &e), GK_ERR_NAN); /* o[0] is NaN */
    free(msave);
    gk_mpm_points_destroy(&P);
    gk_mpm_grid_destroy(&g);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(shape_partition_of_unity);
    RUN(shape_values_equal_shape);
    RUN(support_inside_agrees_with_shape);
    RUN(kernel_derivative_matches_finite_difference);
    RUN(p2g_g2p_conserve_mass_and_momentum);
    RUN(apic_preserves_rigid_rotation);
    RUN(velocity_gradient_F_and_polar);
    RUN(elastic_bar_first_mode_frequency);
    RUN(column_settles_to_geostatic_stress);
    RUN(block_on_frictional_floor_decelerates_at_mu_g);
    RUN(rigid_plate_reaction_matches_confined_compression);
    RUN(wall_and_body_contact_laws);
    RUN(circle_body_contact);
    RUN(circle_body_bad_input_refused);
    RUN(drucker_prager_return_map);
    RUN(drucker_prager_update_spin_and_critical_state);
    RUN(drucker_prager_update_refuses_a_negative_friction);
    RUN(threads_give_identical_bits);
    RUN(bad_input_is_refused_and_changes_nothing);
    return gk_test_done();
}
