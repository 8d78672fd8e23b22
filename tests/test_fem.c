/* test_fem.c - gk_fem.h, gk_mesh.h and gk_dofmap.h: shape functions, patch
 * tests, convergence, assembly, boundary conditions, tied dofs, solvers, Gmsh
 * reading and bad meshes. */
#define _POSIX_C_SOURCE 200809L
#include "gk_dofmap.h"
#include "gk_fem.h"
#include "gk_mesh.h"
#include "gk_test.h"
#include <stdlib.h>

static const gk_elem_type all_types[3] = {GK_Q4, GK_Q8, GK_HEX8};

/* partition of unity, sum of gradients zero, N_a(x_b) = delta_ab */
TEST(shape_functions_partition_of_unity_and_kronecker) {
    int t, a, b, k;
    gk_rng rng;
    gk_rng_seed(&rng, 3);
    for (t = 0; t < 3; ++t) {
        gk_elem_type ty = all_types[t];
        int npe = gk_fem_npe(ty), dim = gk_fem_dim(ty);
        double N[8], dN[24], xi[3];
        for (k = 0; k < 20; ++k) {
            double s = 0, g[3] = {0, 0, 0};
            for (a = 0; a < 3; ++a) xi[a] = 2 * gk_rng_uniform(&rng) - 1;
            gk_fem_shape(ty, xi, N, dN);
            for (a = 0; a < npe; ++a) {
                s += N[a];
                for (b = 0; b < dim; ++b) g[b] += dN[dim * a + b];
            }
            CHECK_NEAR(s, 1.0, 1e-14);
            for (b = 0; b < dim; ++b) CHECK_NEAR(g[b], 0.0, 1e-14);
        }
        /* nodes of a unit reference mesh: Q8 nodes of a structured 1-element mesh */
        {
            gk_mesh m;
            int n[3] = {1, 1, 1};
            double o[3] = {-1, -1, -1}, L[3] = {2, 2, 2};
            CHECK(gk_mesh_structured(&m, ty, n, o, L, NULL, NULL) == GK_OK);
            for (b = 0; b < npe; ++b) {
                const double *xb = m.x + (size_t)m.conn[b] * dim;
                for (a = 0; a < 3; ++a) xi[a] = a < dim ? xb[a] : 0.0;
                gk_fem_shape(ty, xi, N, dN);
                for (a = 0; a < npe; ++a) CHECK_NEAR(N[a], a == b ? 1.0 : 0.0, 1e-14);
            }
            gk_mesh_free(&m);
        }
    }
}

/* distort interior nodes of a structured mesh (keeps every det J > 0) */
static void distort(gk_mesh *m, double amp, unsigned seed) {
    gk_rng rng;
    double lo[3] = {1e30, 1e30, 1e30}, hi[3] = {-1e30, -1e30, -1e30};
    int a, i;
    gk_rng_seed(&rng, seed);
    for (a = 0; a < m->nnode; ++a)
        for (i = 0; i < m->dim; ++i) {
            double v = m->x[a * m->dim + i];
            if (v < lo[i]) lo[i] = v;
            if (v > hi[i]) hi[i] = v;
        }
    for (a = 0; a < m->nnode; ++a) {
        int interior = 1;
        for (i = 0; i < m->dim; ++i) {
            double v = m->x[a * m->dim + i];
            if (fabs(v - lo[i]) < 1e-12 || fabs(v - hi[i]) < 1e-12) interior = 0;
        }
        if (interior)
            for (i = 0; i < m->dim; ++i) m->x[a * m->dim + i] += amp * (2 * gk_rng_uniform(&rng) - 1);
    }
}

/* Patch test (Irons): under a linear displacement prescribed on the boundary
 * the FE solution is the same linear field everywhere, and the stress is the
 * constant D:grad u - for any element shape. */
TEST(patch_test_q4_q8_hex8_reproduce_linear_field) {
    int t;
    for (t = 0; t < 3; ++t) {
        gk_elem_type ty = all_types[t];
        int dim = gk_fem_dim(ty), n[3] = {3, 3, 2}, nfix = 0, a, i, e, g, *fix;
        double o[3] = {0, 0, 0}, L[3] = {1.0, 1.2, 0.9},
               G[9] = {1e-3, 2e-4, -3e-4, -5e-4, 2e-3, 1e-4, 3e-4, -2e-4, 7e-4};
        double D[81], *Dall, *rhs, *u, *vals, maxerr = 0, lo[3] = {0, 0, 0};
        gk_mesh m;
        gk_quad q;
        gk_csr K;
        gk_solver s;
        gk_err err;
        gk_solver_init(&s);
        CHECK(gk_mesh_structured(&m, ty, n, o, L, NULL, &err) == GK_OK);
        distort(&m, ty == GK_Q8 ? 0.03 : 0.08, 11u + (unsigned)t); /* Q8: mid-nodes in the middle half */
        CHECK(gk_quad_rule(&q, ty, 2, &err) == GK_OK);
        CHECK(gk_mesh_check(&m, &q, &err) == GK_OK);
        gk_fem_elastic_tangent(dim, 1e7, 0.3, D);
        Dall = (double *)malloc((size_t)m.nelem * q.n * 81 * sizeof(double));
        for (e = 0; e < m.nelem * q.n; ++e)
            memcpy(Dall + (size_t)e * dim * dim * dim * dim, D, sizeof(double) * dim * dim * dim * dim);
        CHECK(gk_csr_from_mesh(&K, &m, NULL, &err) == GK_OK);
        CHECK(gk_fem_assemble(&m, &q, Dall, NULL, &K, NULL, &err) == GK_OK);
        rhs = (double *)calloc((size_t)K.n, sizeof(double));
        u = (double *)calloc((size_t)K.n, sizeof(double));
        fix = (int *)malloc((size_t)K.n * sizeof(int));
        vals = (double *)malloc((size_t)K.n * sizeof(double));
        for (a = 0; a < m.nnode; ++a) {
            int bnd = 0;
            for (i = 0; i < dim; ++i)
                if (fabs(m.x[a * dim + i] - lo[i]) < 1e-12 || fabs(m.x[a * dim + i] - L[i]) < 1e-12) bnd = 1;
            if (!bnd) continue;
            for (i = 0; i < dim; ++i) {
                int j;
                double v = 1e-4 * (i + 1);
                for (j = 0; j < dim; ++j) v += G[3 * i + j] * m.x[a * dim + j];
                fix[nfix] = dim * a + i, vals[nfix++] = v;
            }
        }
        CHECK(gk_fem_dirichlet(&K, rhs, nfix, fix, vals, &err) == GK_OK);
        CHECK(gk_solver_factor(&s, &K, NULL, &err) == GK_OK);
        CHECK(gk_solver_solve(&s, rhs, u) == GK_OK);
        for (a = 0; a < m.nnode; ++a)
            for (i = 0; i < dim; ++i) {
                int j;
                double v = 1e-4 * (i + 1);
                for (j = 0; j < dim; ++j) v += G[3 * i + j] * m.x[a * dim + j];
                if (fabs(u[a * dim + i] - v) > maxerr) maxerr = fabs(u[a * dim + i] - v);
            }
        CHECK(maxerr < 1e-13);
        /* gradients at every Gauss point are the prescribed G */
        for (e = 0; e < m.nelem; ++e)
            for (g = 0; g < q.n; ++g) {
                double dNdx[24], dJ, H[9];
                int j;
                CHECK(gk_fem_jacobian(&m, e, q.xi[g], NULL, dNdx, &dJ, &err) == GK_OK);
                gk_fem_grad(&m, e, dNdx, u, H);
                for (i = 0; i < dim; ++i)
                    for (j = 0; j < dim; ++j) CHECK_NEAR(H[3 * i + j], G[3 * i + j], 1e-12);
            }
        printf("    %s patch: max nodal error %.2e\n",
               ty == GK_Q4   ? "Q4"
               : ty == GK_Q8 ? "Q8"
                             : "Hex8",
               maxerr);
        free(Dall), free(rhs), free(u), free(fix), free(vals);
        gk_solver_free(&s), gk_csr_free(&K), gk_mesh_free(&m);
    }
}

/* A constant stress gives zero internal force at interior nodes (the
 * equilibrium half of the patch test), and at a boundary node the force of
 * the traction sigma.n. K u = f_int(D:grad u) for a linear u with a
 * non-symmetric D checks the index convention of the stiffness. */
TEST(constant_stress_balances_and_stiffness_matches_force) {
    int t;
    for (t = 0; t < 3; ++t) {
        gk_elem_type ty = all_types[t];
        int dim = gk_fem_dim(ty), n[3] = {2, 3, 2}, e, a, i, j, k, l, n4 = dim * dim * dim * dim;
        double o[3] = {0, 0, 0}, L[3] = {1, 1, 1}, sig[9] = {3, 1, 0.5, 1, -2, 0.2, 0.5, 0.2, 1};
        double *S, *f, D[81], *Dall, *u, *Ku, H[9], s2[9], *f2, lo = 0, hi = 1;
        gk_rng rng;
        gk_mesh m;
        gk_quad q;
        gk_csr K;
        gk_err err;
        gk_rng_seed(&rng, 5);
        gk_mesh_structured(&m, ty, n, o, L, NULL, &err);
        distort(&m, 0.06, 2u);
        gk_quad_rule(&q, ty, ty == GK_Q8 ? 3 : 2, &err);
        S = (double *)malloc((size_t)m.nelem * q.n * 9 * sizeof(double));
        f = (double *)malloc((size_t)m.nnode * dim * sizeof(double));
        for (e = 0; e < m.nelem * q.n; ++e) memcpy(S + 9 * e, sig, sizeof sig);
        CHECK(gk_fem_assemble(&m, &q, NULL, S, NULL, f, &err) == GK_OK);
        for (a = 0; a < m.nnode; ++a) {
            int interior = 1;
            for (i = 0; i < dim; ++i)
                if (fabs(m.x[a * dim + i] - lo) < 1e-12 || fabs(m.x[a * dim + i] - hi) < 1e-12) interior = 0;
            if (interior)
                for (i = 0; i < dim; ++i) CHECK_NEAR(f[a * dim + i], 0.0, 1e-12);
        }
        /* non-symmetric D, linear u */
        for (k = 0; k < n4; ++k) D[k] = gk_rng_uniform(&rng) - 0.3;
        Dall = (double *)malloc((size_t)m.nelem * q.n * n4 * sizeof(double));
        for (e = 0; e < m.nelem * q.n; ++e) memcpy(Dall + (size_t)e * n4, D, (size_t)n4 * sizeof(double));
        for (k = 0; k < 9; ++k) H[k] = gk_rng_uniform(&rng) - 0.5;
        gk_m3_zero(s2);
        for (i = 0; i < dim; ++i)
            for (j = 0; j < dim; ++j)
                for (k = 0; k < dim; ++k)
                    for (l = 0; l < dim; ++l)
                        s2[3 * i + j] += D[((i * dim + j) * dim + k) * dim + l] * H[3 * k + l];
        for (e = 0; e < m.nelem * q.n; ++e) memcpy(S + 9 * e, s2, sizeof s2);
        u = (double *)malloc((size_t)m.nnode * dim * sizeof(double));
        Ku = (double *)malloc((size_t)m.nnode * dim * sizeof(double));
        f2 = (double *)malloc((size_t)m.nnode * dim * sizeof(double));
        for (a = 0; a < m.nnode; ++a)
            for (i = 0; i < dim; ++i) {
                u[a * dim + i] = 0.0;
                for (j = 0; j < dim; ++j) u[a * dim + i] += H[3 * i + j] * m.x[a * dim + j];
            }
        CHECK(gk_csr_from_mesh(&K, &m, NULL, &err) == GK_OK);
        CHECK(gk_fem_assemble(&m, &q, Dall, S, &K, f2, &err) == GK_OK);
        gk_csr_matvec(&K, u, Ku);
        for (k = 0; k < m.nnode * dim; ++k) CHECK_NEAR(Ku[k], f2[k], 1e-12 * (1 + fabs(f2[k])));
        free(S), free(f), free(Dall), free(u), free(Ku), free(f2);
        gk_csr_free(&K), gk_mesh_free(&m);
    }
}

/* Cantilever, exact plane elasticity solution (Timoshenko & Goodier 1951,
 * sec. 21; plane strain via E' = E/(1-nu^2), nu' = nu/(1-nu)) prescribed on
 * the whole boundary: the L2 displacement error falls as h^2 for Q4 and h^3
 * for Q8 (standard a-priori estimates, p + 1 for degree p). */
static void cantilever_exact(const double *x, double E, double nu, double P, double Lb, double Dh,
                             double *u) {
    double Ep = E / (1 - nu * nu), nup = nu / (1 - nu), I = Dh * Dh * Dh / 12.0, X = x[0],
           Y = x[1] - 0.5 * Dh;
    u[0] = -P * Y / (6 * Ep * I) * ((6 * Lb - 3 * X) * X + (2 + nup) * (Y * Y - Dh * Dh / 4));
    u[1] = P / (6 * Ep * I) *
           (3 * nup * Y * Y * (Lb - X) + (4 + 5 * nup) * Dh * Dh * X / 4 + (3 * Lb - X) * X * X);
}

static double cantilever_error(gk_elem_type ty, int nx, int ny) {
    double E = 1e3, nu = 0.25, P = 1.0, Lb = 4.0, Dh = 1.0, o[3] = {0, 0, 0}, L[3] = {4.0, 1.0, 0}, D[16],
           *Dall, *rhs, *u, *vals, err2 = 0, norm2 = 0;
    int n[3], nfix = 0, a, i, e, g, *fix;
    gk_mesh m;
    gk_quad q, q3;
    gk_csr K;
    gk_solver s;
    gk_err err;
    gk_solver_init(&s);
    n[0] = nx, n[1] = ny, n[2] = 1;
    gk_mesh_structured(&m, ty, n, o, L, NULL, &err);
    gk_quad_rule(&q, ty, ty == GK_Q8 ? 3 : 2, &err);
    gk_quad_rule(&q3, ty, 3, &err);
    gk_fem_elastic_tangent(2, E, nu, D);
    Dall = (double *)malloc((size_t)m.nelem * q.n * 16 * sizeof(double));
    for (e = 0; e < m.nelem * q.n; ++e) memcpy(Dall + 16 * e, D, sizeof D);
    gk_csr_from_mesh(&K, &m, NULL, &err);
    gk_fem_assemble(&m, &q, Dall, NULL, &K, NULL, &err);
    rhs = (double *)calloc((size_t)K.n, sizeof(double));
    u = (double *)calloc((size_t)K.n, sizeof(double));
    fix = (int *)malloc((size_t)K.n * sizeof(int));
    vals = (double *)malloc((size_t)K.n * sizeof(double));
    for (a = 0; a < m.nnode; ++a) {
        const double *xa = m.x + 2 * a;
        double ue[2];
        if (!(fabs(xa[0]) < 1e-12 || fabs(xa[0] - Lb) < 1e-12 || fabs(xa[1]) < 1e-12 ||
              fabs(xa[1] - Dh) < 1e-12))
            continue;
        cantilever_exact(xa, E, nu, P, Lb, Dh, ue);
        for (i = 0; i < 2; ++i) fix[nfix] = 2 * a + i, vals[nfix++] = ue[i];
    }
    gk_fem_dirichlet(&K, rhs, nfix, fix, vals, &err);
    if (gk_solver_factor(&s, &K, NULL, &err)) return 1e30;
    gk_solver_solve(&s, rhs, u);
    for (e = 0; e < m.nelem; ++e)
        for (g = 0; g < q3.n; ++g) {
            double N[8], dNdx[16], dJ, uh[2] = {0, 0}, x[3], ue[2];
            gk_fem_jacobian(&m, e, q3.xi[g], N, dNdx, &dJ, &err);
            for (a = 0; a < m.npe; ++a)
                for (i = 0; i < 2; ++i) uh[i] += N[a] * u[2 * m.conn[e * m.npe + a] + i];
            gk_mesh_point(&m, e, q3.xi[g], x);
            cantilever_exact(x, E, nu, P, Lb, Dh, ue);
            for (i = 0; i < 2; ++i)
                err2 += q3.w[g] * dJ * (uh[i] - ue[i]) * (uh[i] - ue[i]),
                    norm2 += q3.w[g] * dJ * ue[i] * ue[i];
        }
    free(Dall), free(rhs), free(u), free(fix), free(vals);
    gk_solver_free(&s), gk_csr_free(&K), gk_mesh_free(&m);
    return sqrt(err2 / norm2);
}

TEST(cantilever_converges_at_expected_rate) {
    int t;
    for (t = 0; t < 2; ++t) {
        gk_elem_type ty = all_types[t];
        double e1 = cantilever_error(ty, 4, 1), e2 = cantilever_error(ty, 8, 2),
               e3 = cantilever_error(ty, 16, 4);
        double r1 = log(e1 / e2) / log(2.0), r2 = log(e2 / e3) / log(2.0), expect = ty == GK_Q4 ? 2.0 : 3.0;
        printf("    %s: L2 errors %.3e %.3e %.3e, rates %.2f %.2f (expected %.0f)\n",
               ty == GK_Q4 ? "Q4" : "Q8", e1, e2, e3, r1, r2, expect);
        CHECK(e3 < e2 && e2 < e1);
        CHECK(fabs(r2 - expect) < 0.25);
    }
}

static void dense_solve(int n, double *A, double *b) { /* Gaussian elimination, partial pivoting */
    int k, i, j;
    for (k = 0; k < n; ++k) {
        int p = k;
        for (i = k + 1; i < n; ++i)
            if (fabs(A[i * n + k]) > fabs(A[p * n + k])) p = i;
        if (p != k) {
            for (j = 0; j < n; ++j) {
                double t = A[k * n + j];
                A[k * n + j] = A[p * n + j], A[p * n + j] = t;
            }
            {
                double t = b[k];
                b[k] = b[p], b[p] = t;
            }
        }
        for (i = k + 1; i < n; ++i) {
            double l = A[i * n + k] / A[k * n + k];
            for (j = k; j < n; ++j) A[i * n + j] -= l * A[k * n + j];
            b[i] -= l * b[k];
        }
    }
    for (k = n - 1; k >= 0; --k) {
        for (j = k + 1; j < n; ++j) b[k] -= A[k * n + j] * b[j];
        b[k] /= A[k * n + k];
    }
}

/* banded LU after RCM = dense Gaussian elimination, on a non-symmetric matrix
 * with zero diagonal entries (needs pivoting) */
TEST(direct_solver_matches_dense_reference) {
    gk_mesh m;
    gk_csr K;
    gk_solver s;
    gk_err err;
    gk_rng rng;
    int n[3] = {3, 4, 1}, i, p;
    double o[3] = {0, 0, 0}, L[3] = {1, 1, 1}, *Ad, *b, *x, *bd, maxd = 0;
    gk_solver_init(&s);
    gk_rng_seed(&rng, 9);
    gk_mesh_structured(&m, GK_Q8, n, o, L, NULL, &err);
    gk_csr_from_mesh(&K, &m, NULL, &err);
    Ad = (double *)calloc((size_t)K.n * K.n, sizeof(double));
    b = (double *)malloc((size_t)K.n * sizeof(double));
    bd = (double *)malloc((size_t)K.n * sizeof(double));
    x = (double *)malloc((size_t)K.n * sizeof(double));
    for (i = 0; i < K.n; ++i) {
        for (p = K.rowptr[i]; p < K.rowptr[i + 1]; ++p) {
            double v = K.col[p] == i && i % 3 == 0 ? 0.0 : 2 * gk_rng_uniform(&rng) - 1;
            K.val[p] = v;
            Ad[i * K.n + K.col[p]] = v;
        }
        b[i] = bd[i] = gk_rng_uniform(&rng);
    }
    CHECK(gk_solver_factor(&s, &K, NULL, &err) == GK_OK);
    CHECK(gk_solver_solve(&s, b, x) == GK_OK);
    dense_solve(K.n, Ad, bd);
    for (i = 0; i < K.n; ++i)
        if (fabs(x[i] - bd[i]) > maxd) maxd = fabs(x[i] - bd[i]);
    printf("    n = %d, band kl = %d ku = %d, max |x - x_dense| = %.2e\n", K.n, s.kl, s.ku, maxd);
    CHECK(maxd < 1e-9);
    free(Ad), free(b), free(bd), free(x);
    gk_solver_free(&s), gk_csr_free(&K), gk_mesh_free(&m);
    { /* RCM narrows the band of a long mesh numbered along its long side */
        int nn[3] = {30, 2, 1}, *perm, *inv, bw0 = 0, bw1 = 0;
        double LL[3] = {30, 2, 1};
        gk_mesh_structured(&m, GK_Q4, nn, o, LL, NULL, &err);
        gk_csr_from_mesh(&K, &m, NULL, &err);
        perm = (int *)malloc((size_t)K.n * sizeof(int));
        inv = (int *)malloc((size_t)K.n * sizeof(int));
        CHECK(gk_rcm_order(&K, perm, NULL, &err) == GK_OK);
        for (i = 0; i < K.n; ++i) inv[perm[i]] = i;
        for (i = 0; i < K.n; ++i)
            for (p = K.rowptr[i]; p < K.rowptr[i + 1]; ++p) {
                if (abs(K.col[p] - i) > bw0) bw0 = abs(K.col[p] - i);
                if (abs(inv[K.col[p]] - inv[i]) > bw1) bw1 = abs(inv[K.col[p]] - inv[i]);
            }
        printf("    30 x 2 Q4 mesh: bandwidth %d natural, %d after RCM\n", bw0, bw1);
        CHECK(bw1 * 3 < bw0);
        free(perm), free(inv);
        gk_csr_free(&K), gk_mesh_free(&m);
    }
}

/* PCG and the direct solver agree on an SPD elastic system */
TEST(pcg_matches_direct_on_elastic_system) {
    gk_mesh m;
    gk_csr K;
    gk_solver s;
    gk_quad q;
    gk_err err;
    int n[3] = {4, 3, 3}, nfix = 0, a, i, e, it = 0, *fix;
    double o[3] = {0, 0, 0}, L[3] = {2, 1, 1}, D[81], *Dall, *rhs, *x1, *x2, *vals, md = 0, mx = 0;
    gk_solver_init(&s);
    gk_mesh_structured(&m, GK_HEX8, n, o, L, NULL, &err);
    gk_quad_rule(&q, GK_HEX8, 2, &err);
    gk_fem_elastic_tangent(3, 2e5, 0.3, D);
    Dall = (double *)malloc((size_t)m.nelem * q.n * 81 * sizeof(double));
    for (e = 0; e < m.nelem * q.n; ++e) memcpy(Dall + 81 * e, D, sizeof D);
    gk_csr_from_mesh(&K, &m, NULL, &err);
    gk_fem_assemble(&m, &q, Dall, NULL, &K, NULL, &err);
    rhs = (double *)calloc((size_t)K.n, sizeof(double));
    x1 = (double *)calloc((size_t)K.n, sizeof(double));
    x2 = (double *)calloc((size_t)K.n, sizeof(double));
    fix = (int *)malloc((size_t)K.n * sizeof(int));
    vals = (double *)malloc((size_t)K.n * sizeof(double));
    for (a = 0; a < m.nnode; ++a) {
        if (fabs(m.x[3 * a]) < 1e-12)
            for (i = 0; i < 3; ++i) fix[nfix] = 3 * a + i, vals[nfix++] = 0.0;
        if (fabs(m.x[3 * a] - 2) < 1e-12) rhs[3 * a + 2] = -1.0; /* end load */
    }
    CHECK(gk_fem_dirichlet(&K, rhs, nfix, fix, vals, &err) == GK_OK);
    CHECK(gk_solver_factor(&s, &K, NULL, &err) == GK_OK);
    gk_solver_solve(&s, rhs, x1);
    CHECK(gk_pcg(&K, rhs, x2, 1e-12, 5000, &it, NULL, &err) == GK_OK);
    for (i = 0; i < K.n; ++i) {
        if (fabs(x1[i] - x2[i]) > md) md = fabs(x1[i] - x2[i]);
        if (fabs(x1[i]) > mx) mx = fabs(x1[i]);
    }
    printf("    PCG %d iterations, max |x_pcg - x_lu| / max|x| = %.2e\n", it, md / mx);
    CHECK(md < 1e-9 * mx);
    free(Dall), free(rhs), free(x1), free(x2), free(fix), free(vals);
    gk_solver_free(&s), gk_csr_free(&K), gk_mesh_free(&m);
}

/* consistent edge loads: total = traction x length; a Q8 edge splits a
 * uniform load 1/6, 1/6, 2/3 (Simpson), a Q4 edge 1/2, 1/2 */
TEST(edge_and_face_loads_are_consistent) {
    gk_mesh m;
    gk_err err;
    int n[3] = {2, 2, 2}, faces[64], nfn, nf, k, a;
    double o[3] = {0, 0, 0}, L[3] = {2.0, 3.0, 1.5}, t[3] = {0.0, -5.0, 2.0}, *f, sum[3];
    gk_elem_type tys[3] = {GK_Q4, GK_Q8, GK_HEX8};
    for (k = 0; k < 3; ++k) {
        int dim = gk_fem_dim(tys[k]);
        double area = dim == 2 ? L[0] : L[0] * L[2];
        gk_mesh_structured(&m, tys[k], n, o, L, NULL, &err);
        nf = gk_mesh_faces_on_plane(&m, 1, 3.0, 1e-9, faces, &nfn);
        CHECK(nf == (dim == 2 ? 2 : 4));
        f = (double *)calloc((size_t)m.nnode * dim, sizeof(double));
        for (a = 0; a < nf; ++a) CHECK(gk_fem_face_load(&m, nfn, faces + a * nfn, t, f, &err) == GK_OK);
        sum[0] = sum[1] = sum[2] = 0;
        for (a = 0; a < m.nnode * dim; ++a) sum[a % dim] += f[a];
        CHECK_NEAR(sum[1], t[1] * area, 1e-12);
        if (dim == 3) CHECK_NEAR(sum[2], t[2] * area, 1e-12);
        if (dim == 2) { /* the corner at x = 0 belongs to one edge of length 1 */
            int c0 = -1;
            for (a = 0; a < m.nnode; ++a)
                if (m.x[2 * a] == 0.0 && m.x[2 * a + 1] == 3.0) c0 = a;
            CHECK(c0 >= 0);
            if (c0 >= 0) CHECK_NEAR(f[2 * c0 + 1], tys[k] == GK_Q8 ? t[1] / 6 : t[1] / 2, 1e-12);
            if (tys[k] == GK_Q8) CHECK_NEAR(f[2 * faces[2] + 1], 2 * t[1] / 3, 1e-12); /* mid-side node */
        }
        CHECK(gk_fem_face_load(&m, 5, faces, t, f, &err) == GK_ERR_ARG);
        free(f);
        gk_mesh_free(&m);
    }
}

/* HRZ lumping: masses positive (also Q8 corners) and sum to rho x volume */
TEST(lumped_mass_positive_and_total) {
    int t;
    for (t = 0; t < 3; ++t) {
        gk_mesh m;
        gk_quad q;
        gk_err err;
        int n[3] = {3, 2, 2}, a;
        double o[3] = {0, 0, 0}, L[3] = {1.5, 1.0, 0.5}, *ms, tot = 0, vol;
        gk_mesh_structured(&m, all_types[t], n, o, L, NULL, &err);
        distort(&m, 0.05, 3u);
        gk_quad_rule(&q, all_types[t], 3, &err);
        ms = (double *)malloc((size_t)m.nnode * sizeof(double));
        CHECK(gk_fem_lumped_mass(&m, &q, 2000.0, ms, &err) == GK_OK);
        for (a = 0; a < m.nnode; ++a) {
            CHECK(ms[a] > 0);
            tot += ms[a];
        }
        vol = m.dim == 2 ? 1.5 : 0.75;
        CHECK_NEAR(tot, 2000.0 * vol, 1e-9);
        CHECK(gk_fem_lumped_mass(&m, &q, -1.0, ms, &err) == GK_ERR_MASS);
        free(ms);
        gk_mesh_free(&m);
    }
}

/* Flanagan-Belytschko: no hourglass force for a linear field, a restoring
 * one (f.u < 0) for the hourglass mode u_x = h1 */
TEST(hex8_hourglass_zero_for_linear_field) {
    gk_mesh m;
    gk_err err;
    int n[3] = {1, 1, 1}, a, i;
    double o[3] = {0.1, 0.2, 0.3}, L[3] = {1.0, 0.8, 1.3}, xe[24], ue[24], f[24],
           G[9] = {1, 2, 3, -1, 0.5, 0.2, 0.3, -0.4, 2}, fu = 0, fmax = 0;
    gk_mesh_structured(&m, GK_HEX8, n, o, L, NULL, &err);
    for (a = 0; a < 8; ++a)
        for (i = 0; i < 3; ++i) xe[3 * a + i] = m.x[3 * m.conn[a] + i] + (a == 6 ? 0.05 * (i + 1) : 0.0);
    for (a = 0; a < 8; ++a)
        for (i = 0; i < 3; ++i)
            ue[3 * a + i] =
                0.01 + G[3 * i] * xe[3 * a] + G[3 * i + 1] * xe[3 * a + 1] + G[3 * i + 2] * xe[3 * a + 2];
    gk_fem_hex8_hourglass(xe, ue, 1e3, f);
    for (a = 0; a < 24; ++a)
        if (fabs(f[a]) > fmax) fmax = fabs(f[a]);
    CHECK(fmax < 1e-10);
    for (a = 0; a < 24; ++a) ue[a] = 0;
    ue[0] = 1, ue[3] = 1, ue[6] = -1, ue[9] = -1, ue[12] = -1, ue[15] = -1, ue[18] = 1, ue[21] = 1;
    gk_fem_hex8_hourglass(xe, ue, 1e3, f);
    for (a = 0; a < 24; ++a) fu += f[a] * ue[a];
    CHECK(fu < -1.0);
    gk_mesh_free(&m);
}

static int write_text(const char *path, const char *text) {
    FILE *fp = fopen(path, "w");
    if (!fp) return 0;
    fputs(text, fp);
    fclose(fp);
    return 1;
}

/* the same 2 x 1 Q4 mesh written as Gmsh v2.2 and v4.1 (with a point and
 * line elements to skip and unused node tags) reads identically */
TEST(gmsh_v2_and_v4_read) {
    const char *v2 =
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n7\n"
        "1 0 0 0\n2 1 0 0\n3 2 0 0\n4 0 1 0\n5 1 1 0\n6 2 1 0\n9 5 5 0\n$EndNodes\n"
        "$Elements\n4\n1 15 2 0 1 1\n2 1 2 0 1 1 2\n3 3 2 7 1 1 2 5 4\n4 3 2 7 1 2 3 6 5\n$EndElements\n";
    const char *v4 = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                     "$Nodes\n2 6 1 6\n0 1 0 1\n1\n0 0 0\n2 1 0 5\n2\n3\n4\n5\n6\n1 0 0\n2 0 0\n0 1 0\n1 1 "
                     "0\n2 1 0\n$EndNodes\n"
                     "$Elements\n2 3 1 3\n1 5 1 1\n1 1 2\n2 1 3 2\n2 1 2 5 4\n3 2 3 6 5\n$EndElements\n";
    const char *bad = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n$Elements\n1\n1 "
                      "3 0 1 2 3 4\n$EndElements\n";
    gk_mesh a, b;
    gk_err err;
    int k;
    CHECK(write_text(BUILD "/tests/test_fem_v2.msh", v2) && write_text(BUILD "/tests/test_fem_v4.msh", v4) &&
          write_text(BUILD "/tests/test_fem_bad.msh", bad));
    CHECK(gk_mesh_read_gmsh(BUILD "/tests/test_fem_v2.msh", &a, NULL, &err) == GK_OK);
    CHECK(gk_mesh_read_gmsh(BUILD "/tests/test_fem_v4.msh", &b, NULL, &err) == GK_OK);
    CHECK(a.type == GK_Q4 && a.nelem == 2 && a.nnode == 6 && a.tag[0] == 7);
    CHECK(b.type == GK_Q4 && b.nelem == 2 && b.nnode == 6 && b.tag[1] == 1);
    for (k = 0; k < 12; ++k) CHECK(a.x[k] == b.x[k]);
    for (k = 0; k < 8; ++k) CHECK(a.conn[k] == b.conn[k]);
    CHECK_NEAR(a.x[2 * a.conn[6]], 2.0, 0);
    gk_mesh_free(&a), gk_mesh_free(&b);
    CHECK(gk_mesh_read_gmsh(BUILD "/tests/test_fem_bad.msh", &a, NULL, &err) == GK_ERR_FORMAT);
    printf("    bad file: %s\n", err.msg);
    CHECK(gk_mesh_read_gmsh(BUILD "/tests/does_not_exist.msh", &a, NULL, &err) == GK_ERR_IO);
}

/* bad meshes and systems give clear errors and change nothing */
TEST(bad_meshes_and_unconstrained_system_errors) {
    gk_mesh m;
    gk_quad q;
    gk_err err;
    gk_csr K;
    gk_solver s;
    int n[3] = {2, 2, 1}, e;
    double o[3] = {0, 0, 0}, L[3] = {1, 1, 1}, D[16], Dall[4 * 4 * 16], x5;
    gk_solver_init(&s);
    gk_mesh_structured(&m, GK_Q4, n, o, L, NULL, &err);
    gk_quad_rule(&q, GK_Q4, 2, &err);
    CHECK(gk_mesh_check(&m, &q, &err) == GK_OK);
    /* inverted: swap two corners of element 0 */
    e = m.conn[1], m.conn[1] = m.conn[3], m.conn[3] = e;
    CHECK(gk_mesh_check(&m, &q, &err) == GK_ERR_MESH);
    printf("    inverted: %s\n", err.msg);
    e = m.conn[1], m.conn[1] = m.conn[3], m.conn[3] = e;
    /* degenerate: a repeated node, then a collapsed node */
    e = m.conn[2], m.conn[2] = m.conn[1];
    CHECK(gk_mesh_check(&m, &q, &err) == GK_ERR_MESH);
    printf("    degenerate: %s\n", err.msg);
    m.conn[2] = e;
    x5 = m.x[2 * 4];
    m.x[2 * 4] = m.x[2 * 3], m.x[2 * 4 + 1] = m.x[2 * 3 + 1]; /* centre node onto its neighbour */
    CHECK(gk_mesh_check(&m, &q, &err) == GK_ERR_MESH);
    m.x[2 * 4] = x5, m.x[2 * 4 + 1] = 0.5;
    CHECK(gk_mesh_check(&m, &q, &err) == GK_OK);
    CHECK(gk_quad_rule(&q, GK_Q4, 4, &err) == GK_ERR_ARG);
    gk_quad_rule(&q, GK_Q4, 2, &err);
    /* unconstrained elastic system: rigid-body modes make it singular */
    gk_fem_elastic_tangent(2, 1e6, 0.3, D);
    for (e = 0; e < 16; ++e) memcpy(Dall + 16 * e, D, sizeof D);
    gk_csr_from_mesh(&K, &m, NULL, &err);
    CHECK(gk_fem_assemble(&m, &q, Dall, NULL, &K, NULL, &err) == GK_OK);
    CHECK(gk_solver_factor(&s, &K, NULL, &err) == GK_ERR_SINGULAR);
    printf("    unconstrained: %s\n", err.msg);
    CHECK(s.ab == NULL);
    /* NaN in a tangent */
    Dall[5] = NAN;
    CHECK(gk_fem_assemble(&m, &q, Dall, NULL, &K, NULL, &err) == GK_ERR_NAN);
    {
        int nn[3] = {0, 2, 1};
        gk_mesh z;
        CHECK(gk_mesh_structured(&z, GK_Q4, nn, o, L, NULL, &err) == GK_ERR_ARG);
    }
    gk_csr_free(&K), gk_mesh_free(&m);
}

/* K u = f with tied dofs and prescribed dofs: condense, restrict (with the
 * jumps), Dirichlet on the reduced system, solve, expand */
static gk_result solve_tied(const gk_mesh *m, const gk_quad *q, const double *D, const gk_dofmap *dm,
                            const double *f, int nfix, const int *fix, const double *vals, double *u,
                            gk_err *err) {
    gk_csr K, Kr;
    gk_solver s;
    int nr = 0, *rfix = (int *)malloc((size_t)nfix * sizeof(int) + 1);
    double *fr = (double *)calloc((size_t)dm->nred, sizeof(double)),
           *ur = (double *)calloc((size_t)dm->nred, sizeof(double)),
           *rv = (double *)malloc((size_t)nfix * sizeof(double) + 1);
    gk_result r;
    gk_solver_init(&s);
    memset(&K, 0, sizeof K), memset(&Kr, 0, sizeof Kr);
    r = gk_csr_from_mesh(&K, m, NULL, err);
    if (!r) r = gk_fem_assemble(m, q, D, NULL, &K, NULL, err);
    if (!r) r = gk_dofmap_csr(dm, &K, &Kr, NULL, err);
    if (!r) r = gk_dofmap_condense(dm, &K, &Kr, err);
    if (!r) r = gk_dofmap_restrict(dm, &K, f, fr, err);
    if (!r) r = gk_dofmap_dirichlet(dm, nfix, fix, vals, rfix, rv, &nr, err);
    if (!r) r = gk_fem_dirichlet(&Kr, fr, nr, rfix, rv, err);
    if (!r) r = gk_solver_factor(&s, &Kr, NULL, err);
    if (!r) r = gk_solver_solve(&s, fr, ur);
    if (!r) gk_dofmap_expand(dm, ur, 1, u);
    gk_solver_free(&s), gk_csr_free(&K), gk_csr_free(&Kr);
    free(rfix), free(fr), free(ur), free(rv);
    return r;
}

static double *uniform_tangent(const gk_mesh *m, const gk_quad *q, double E, double nu) {
    int dim = m->dim, n4 = dim * dim * dim * dim, e;
    double D[81], *Dall = (double *)malloc((size_t)m->nelem * q->n * n4 * sizeof(double));
    gk_fem_elastic_tangent(dim, E, nu, D);
    for (e = 0; e < m->nelem * q->n; ++e) memcpy(Dall + (size_t)e * n4, D, (size_t)n4 * sizeof(double));
    return Dall;
}

/* Periodic simple shear (Guo & Zhao 2014 sec 5 boundary conditions): left/right
 * tied, bottom fixed, top moved by gamma H with u_y = 0. On a distorted mesh
 * the solution is the homogeneous simple shear u_x = gamma y, u_y = 0 to
 * round-off, and the top reaction is mu gamma W. With free sides instead the
 * field is not homogeneous (so the check can fail). Corner nodes are both
 * tied and prescribed (same value: merged). */
TEST(periodic_simple_shear_patch_test) {
    int t;
    for (t = 0; t < 2; ++t) {
        gk_elem_type ty = all_types[t];
        int n[3] = {4, 3, 1}, a, nfix = 0, *fix, e, g, nright;
        double o[3] = {0, 0, 0}, L[3] = {2.0, 1.0, 1}, gam = 0.01, E = 1e7, nu = 0.3, mu = E / (2 * (1 + nu));
        double *D, *u, *f, *vals, err_tied = 0, err_free = 0, ftop = 0;
        gk_mesh m;
        gk_quad q;
        gk_dofmap dm, id;
        gk_err err;
        CHECK(gk_mesh_structured(&m, ty, n, o, L, NULL, &err) == GK_OK);
        distort(&m, ty == GK_Q8 ? 0.03 : 0.08, 21u + (unsigned)t);
        gk_quad_rule(&q, ty, 2, &err);
        D = uniform_tangent(&m, &q, E, nu);
        u = (double *)calloc((size_t)2 * m.nnode, sizeof(double));
        f = (double *)calloc((size_t)2 * m.nnode, sizeof(double));
        fix = (int *)malloc((size_t)2 * m.nnode * sizeof(int));
        vals = (double *)malloc((size_t)2 * m.nnode * sizeof(double));
        for (a = 0; a < m.nnode; ++a) {
            double y = m.x[2 * a + 1];
            if (fabs(y) < 1e-12 || fabs(y - L[1]) < 1e-12) {
                fix[nfix] = 2 * a, vals[nfix++] = y > 0.5 ? gam * L[1] : 0.0;
                fix[nfix] = 2 * a + 1, vals[nfix++] = 0.0;
            }
        }
        CHECK(gk_dofmap_periodic(&dm, &m, 1u, NULL, 1e-9, NULL, &err) == GK_OK);
        nright = gk_mesh_nodes_on_plane(&m, 0, L[0], 1e-9, NULL);
        CHECK_EQ_INT(dm.nred, 2 * (m.nnode - nright));
        CHECK(dm.off == NULL);
        CHECK(solve_tied(&m, &q, D, &dm, f, nfix, fix, vals, u, &err) == GK_OK);
        for (a = 0; a < m.nnode; ++a) {
            double ex = fabs(u[2 * a] - gam * m.x[2 * a + 1]), ey = fabs(u[2 * a + 1]);
            if (ex > err_tied) err_tied = ex;
            if (ey > err_tied) err_tied = ey;
        }
        CHECK(err_tied < 1e-15);
        for (e = 0; e < m.nelem; ++e)
            for (g = 0; g < q.n; ++g) {
                double dNdx[16], dJ, H[9];
                gk_fem_jacobian(&m, e, q.xi[g], NULL, dNdx, &dJ, &err);
                gk_fem_grad(&m, e, dNdx, u, H);
                CHECK_NEAR(H[1], gam, 1e-13);
                CHECK_NEAR(H[0], 0.0, 1e-13);
                CHECK_NEAR(H[4], 0.0, 1e-13);
            }
        { /* top reaction from the internal force of the uniform stress */
            double *S = (double *)calloc((size_t)m.nelem * q.n * 9, sizeof(double)), *fi = f;
            for (e = 0; e < m.nelem * q.n; ++e) S[9 * e + 1] = S[9 * e + 3] = mu * gam;
            CHECK(gk_fem_assemble(&m, &q, NULL, S, NULL, fi, &err) == GK_OK);
            for (a = 0; a < m.nnode; ++a)
                if (fabs(m.x[2 * a + 1] - L[1]) < 1e-12) ftop += fi[2 * a];
            CHECK_REL(ftop, mu * gam * L[0], 1e-12);
            memset(f, 0, (size_t)2 * m.nnode * sizeof(double));
            free(S);
        }
        /* the same problem without the ties (free sides): not homogeneous */
        CHECK(gk_dofmap_ties(&id, 2 * m.nnode, 0, NULL, NULL, NULL, NULL, &err) == GK_OK);
        CHECK_EQ_INT(id.nred, 2 * m.nnode);
        CHECK(solve_tied(&m, &q, D, &id, f, nfix, fix, vals, u, &err) == GK_OK);
        for (a = 0; a < m.nnode; ++a)
            if (fabs(u[2 * a + 1]) > err_free) err_free = fabs(u[2 * a + 1]);
        CHECK(err_free > 1e-5 * gam);
        printf(
            "    %s: periodic max error %.1e; free sides max |u_y| %.1e; top force %.6g (mu gamma W %.6g)\n",
            ty == GK_Q4 ? "Q4" : "Q8", err_tied, err_free, ftop, mu * gam * L[0]);
        gk_dofmap_free(&dm), gk_dofmap_free(&id);
        free(D), free(u), free(f), free(fix), free(vals);
        gk_mesh_free(&m);
    }
}

/* Fully periodic mesh with a macro gradient in the jumps, u_s = u_m + G
 * (x_s - x_m), one node pinned: the solution is u = G x to round-off (a
 * periodic patch test). The corner/edge nodes of the Hex8 mesh are tied
 * through chains of up to three ties. */
TEST(periodic_jump_patch_test_with_chains) {
    int t;
    for (t = 0; t < 3; ++t) {
        gk_elem_type ty = all_types[t];
        int dim = gk_fem_dim(ty), n[3] = {3, 2, 2}, a, i, j, fix[3], nint = 0, k;
        double o[3] = {0, 0, 0}, L[3] = {1.5, 1.0, 0.8},
               G[9] = {1e-3, 4e-3, -2e-3, -1e-3, 2e-3, 1e-3, 3e-3, -2e-3, 5e-4};
        double *D, *u, *f, vals[3] = {0, 0, 0}, maxerr = 0;
        gk_mesh m;
        gk_quad q;
        gk_dofmap dm;
        gk_err err;
        CHECK(gk_mesh_structured(&m, ty, n, o, L, NULL, &err) == GK_OK);
        distort(&m, ty == GK_Q8 ? 0.02 : 0.05, 31u + (unsigned)t);
        gk_quad_rule(&q, ty, 2, &err);
        D = uniform_tangent(&m, &q, 5e6, 0.25);
        u = (double *)calloc((size_t)dim * m.nnode, sizeof(double));
        f = (double *)calloc((size_t)dim * m.nnode, sizeof(double));
        CHECK(gk_dofmap_periodic(&dm, &m, dim == 3 ? 7u : 3u, G, 1e-9, NULL, &err) == GK_OK);
        for (a = 0; a < m.nnode; ++a) { /* independent nodes: on no hi face */
            int hi = 0;
            for (i = 0; i < dim; ++i)
                if (fabs(m.x[dim * a + i] - L[i]) < 1e-9) hi = 1;
            nint += !hi;
        }
        CHECK_EQ_INT(dm.nred, dim * nint);
        for (i = 0; i < dim; ++i) fix[i] = i; /* node 0 sits at the origin */
        CHECK(solve_tied(&m, &q, D, &dm, f, dim, fix, vals, u, &err) == GK_OK);
        for (a = 0; a < m.nnode; ++a)
            for (i = 0; i < dim; ++i) {
                double v = 0;
                for (j = 0; j < dim; ++j) v += G[3 * i + j] * m.x[dim * a + j];
                if (fabs(u[dim * a + i] - v) > maxerr) maxerr = fabs(u[dim * a + i] - v);
            }
        CHECK(maxerr < 1e-14);
        /* the far corner is tied through dim ties; its jump is G L */
        for (a = 0; a < m.nnode; ++a) {
            int corner = 1;
            for (i = 0; i < dim; ++i)
                if (fabs(m.x[dim * a + i] - L[i]) > 1e-9) corner = 0;
            if (corner)
                for (i = 0; i < dim; ++i) {
                    double v = 0;
                    for (k = 0; k < dim; ++k) v += G[3 * i + k] * L[k];
                    CHECK_EQ_INT(dm.red[dim * a + i], i);
                    CHECK_NEAR(dm.off[dim * a + i], v, 1e-15);
                }
        }
        printf("    %s: fully periodic, %d -> %d dofs, max |u - G x| %.1e\n",
               ty == GK_Q4   ? "Q4"
               : ty == GK_Q8 ? "Q8"
                             : "Hex8",
               dm.n, dm.nred, maxerr);
        gk_dofmap_free(&dm);
        free(D), free(u), free(f);
        gk_mesh_free(&m);
    }
}

/* Stress control by a rough platen: every top x dof tied to one, the shear
 * force F applied there, sides periodic (the ties combined with
 * gk_mesh_periodic_pairs; the top-right corner is tied twice identically,
 * which is accepted). Exact: u_x = F / (mu W) y. */
TEST(tied_platen_under_shear_force) {
    int n[3] = {3, 2, 1}, np, a, k, nt = 0, nfix = 0, *ps, *pm, *sl, *ms, *fix, master = -1;
    double o[3] = {0, 0, 0}, L[3] = {1.0, 0.5, 1}, E = 2e7, nu = 0.2, mu = E / (2 * (1 + nu)), F = 300.0, *D,
           *u, *f, *vals, maxerr = 0;
    gk_mesh m;
    gk_quad q;
    gk_dofmap dm;
    gk_err err;
    CHECK(gk_mesh_structured(&m, GK_Q8, n, o, L, NULL, &err) == GK_OK);
    distort(&m, 0.02, 41u);
    gk_quad_rule(&q, GK_Q8, 2, &err);
    D = uniform_tangent(&m, &q, E, nu);
    ps = (int *)malloc((size_t)m.nnode * sizeof(int)), pm = (int *)malloc((size_t)m.nnode * sizeof(int));
    sl = (int *)malloc((size_t)4 * m.nnode * sizeof(int)),
    ms = (int *)malloc((size_t)4 * m.nnode * sizeof(int));
    fix = (int *)malloc((size_t)2 * m.nnode * sizeof(int));
    vals = (double *)calloc((size_t)2 * m.nnode, sizeof(double));
    u = (double *)calloc((size_t)2 * m.nnode, sizeof(double));
    f = (double *)calloc((size_t)2 * m.nnode, sizeof(double));
    CHECK(gk_mesh_periodic_pairs(&m, 0, 0.0, L[0], 1e-9, ps, pm, &np, &err) == GK_OK);
    CHECK_EQ_INT(np, 2 * n[1] + 1);
    for (k = 0; k < np; ++k)
        for (a = 0; a < 2; ++a) sl[nt] = 2 * ps[k] + a, ms[nt++] = 2 * pm[k] + a;
    for (a = 0; a < m.nnode; ++a)
        if (fabs(m.x[2 * a + 1] - L[1]) < 1e-12 && fabs(m.x[2 * a]) < 1e-12) master = a;
    CHECK(master >= 0);
    for (a = 0; a < m.nnode; ++a) {
        double y = m.x[2 * a + 1];
        if (fabs(y - L[1]) < 1e-12) {
            if (a != master) sl[nt] = 2 * a, ms[nt++] = 2 * master;
            fix[nfix++] = 2 * a + 1;
        } else if (fabs(y) < 1e-12)
            fix[nfix++] = 2 * a, fix[nfix++] = 2 * a + 1;
    }
    CHECK(gk_dofmap_ties(&dm, 2 * m.nnode, nt, sl, ms, NULL, NULL, &err) == GK_OK);
    f[2 * master] = F;
    CHECK(solve_tied(&m, &q, D, &dm, f, nfix, fix, vals, u, &err) == GK_OK);
    for (a = 0; a < m.nnode; ++a) {
        double ex = fabs(u[2 * a] - F / (mu * L[0]) * m.x[2 * a + 1]);
        if (ex > maxerr) maxerr = ex;
        if (fabs(u[2 * a + 1]) > maxerr) maxerr = fabs(u[2 * a + 1]);
    }
    printf("    platen displacement %.6g (exact %.6g), max error %.1e\n", u[2 * master], F / mu * L[1] / L[0],
           maxerr);
    CHECK(maxerr < 1e-15);
    gk_dofmap_free(&dm);
    free(D), free(u), free(f), free(vals), free(fix), free(ps), free(pm), free(sl), free(ms);
    gk_mesh_free(&m);
}

/* bad ties, non-periodic meshes and inconsistent prescribed values give
 * clear errors and change nothing */
TEST(bad_ties_give_clear_errors) {
    gk_dofmap dm, keep;
    gk_err err;
    gk_mesh m;
    gk_csr K, Kr, Kr2;
    int n[3] = {2, 2, 1}, s1[3] = {0, 1, 2}, m1[3] = {1, 2, 0}, rd[4] = {-7, -7, -7, -7}, nr = -7, np = -7;
    int fx[2] = {1, 3}, ps[8], pm[8];
    double o[3] = {0, 0, 0}, L[3] = {1, 1, 1}, j1[3] = {0, NAN, 0}, fv[2] = {0.0, 1.0},
           rv[4] = {-7, -7, -7, -7};
    double fr[20];
    memset(&dm, 0x5a, sizeof dm);
    keep = dm;
    CHECK(gk_dofmap_ties(&dm, 4, 1, s1, (const int[]){7}, NULL, NULL, &err) == GK_ERR_ARG);
    printf("    out of range: %s\n", err.msg);
    CHECK(gk_dofmap_ties(&dm, 4, 1, s1, s1, NULL, NULL, &err) == GK_ERR_ARG);
    printf("    self: %s\n", err.msg);
    CHECK(gk_dofmap_ties(&dm, 4, 2, (const int[]){3, 3}, (const int[]){0, 1}, NULL, NULL, &err) ==
          GK_ERR_ARG);
    printf("    twice: %s\n", err.msg);
    CHECK(strstr(err.msg, "tied twice") != NULL);
    CHECK(gk_dofmap_ties(&dm, 4, 3, s1, m1, NULL, NULL, &err) == GK_ERR_ARG);
    printf("    cycle: %s\n", err.msg);
    CHECK(strstr(err.msg, "cycle") != NULL);
    CHECK(gk_dofmap_ties(&dm, 4, 2, s1, m1, j1, NULL, &err) == GK_ERR_NAN);
    CHECK(gk_dofmap_ties(&dm, 0, 0, NULL, NULL, NULL, NULL, &err) == GK_ERR_ARG);
    CHECK(memcmp(&dm, &keep, sizeof dm) == 0);
    /* a mesh whose right side does not match its left side */
    gk_mesh_structured(&m, GK_Q4, n, o, L, NULL, &err);
    m.x[2 * 5 + 1] += 0.01; /* node 5 = (1, 0.5) */
    CHECK(gk_dofmap_periodic(&dm, &m, 1u, NULL, 1e-9, NULL, &err) == GK_ERR_MESH);
    printf("    not periodic: %s\n", err.msg);
    CHECK(strstr(err.msg, "node 5") != NULL);
    CHECK(gk_mesh_periodic_pairs(&m, 0, 0.0, 1.0, 1e-9, ps, pm, &np, &err) == GK_ERR_MESH && np == -7);
    CHECK(gk_dofmap_periodic(&dm, &m, 4u, NULL, 1e-9, NULL, &err) == GK_ERR_ARG); /* z in 2D */
    CHECK(memcmp(&dm, &keep, sizeof dm) == 0);
    m.x[2 * 5 + 1] -= 0.01;
    /* tied dofs prescribed inconsistently */
    CHECK(gk_dofmap_ties(&dm, 4, 1, (const int[]){3}, (const int[]){1}, NULL, NULL, &err) == GK_OK);
    CHECK(gk_dofmap_dirichlet(&dm, 2, fx, fv, rd, rv, &nr, &err) == GK_ERR_ARG);
    printf("    inconsistent: %s\n", err.msg);
    CHECK(nr == -7 && rd[0] == -7 && rv[0] == -7);
    fv[1] = 0.0; /* consistent: merged into one reduced dof */
    CHECK(gk_dofmap_dirichlet(&dm, 2, fx, fv, rd, rv, &nr, &err) == GK_OK);
    CHECK(nr == 1 && rd[0] == 1 && rv[0] == 0.0);
    gk_dofmap_free(&dm);
    /* condensing into a matrix of the wrong pattern, restricting with the wrong size */
    CHECK(gk_dofmap_periodic(&dm, &m, 1u, NULL, 1e-9, NULL, &err) == GK_OK);
    gk_csr_from_mesh(&K, &m, NULL, &err);
    CHECK(gk_dofmap_csr(&dm, &K, &Kr, NULL, &err) == GK_OK);
    CHECK(Kr.n == dm.nred && Kr.n == 12);
    gk_csr_from_mesh(&Kr2, &m, NULL, &err);
    CHECK(gk_dofmap_condense(&dm, &K, &Kr2, &err) == GK_ERR_ARG);
    Kr2.n = Kr.n; /* the right size, a different pattern */
    Kr2.val[0] = 42.0;
    CHECK(gk_dofmap_condense(&dm, &K, &Kr2, &err) == GK_ERR_ARG);
    printf("    wrong pattern: %s\n", err.msg);
    CHECK(Kr2.val[0] == 42.0);
    CHECK(gk_dofmap_restrict(&dm, &Kr, fr, fr, &err) == GK_ERR_ARG);
    Kr2.n = K.n;
    gk_csr_free(&K), gk_csr_free(&Kr), gk_csr_free(&Kr2);
    gk_dofmap_free(&dm);
    gk_mesh_free(&m);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(shape_functions_partition_of_unity_and_kronecker);
    RUN(patch_test_q4_q8_hex8_reproduce_linear_field);
    RUN(constant_stress_balances_and_stiffness_matches_force);
    RUN(cantilever_converges_at_expected_rate);
    RUN(direct_solver_matches_dense_reference);
    RUN(pcg_matches_direct_on_elastic_system);
    RUN(edge_and_face_loads_are_consistent);
    RUN(lumped_mass_positive_and_total);
    RUN(hex8_hourglass_zero_for_linear_field);
    RUN(gmsh_v2_and_v4_read);
    RUN(bad_meshes_and_unconstrained_system_errors);
    RUN(periodic_simple_shear_patch_test);
    RUN(periodic_jump_patch_test_with_chains);
    RUN(tied_platen_under_shear_force);
    RUN(bad_ties_give_clear_errors);
    return gk_test_done();
}
