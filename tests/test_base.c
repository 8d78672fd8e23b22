/* test_base.c - gk_base.h: tensors, polar decomposition, exponential, eigen,
 * allocator, random numbers, SIMD twin. */
#include "gk_base.h"
#include "gk_test.h"
#include <float.h>
#include <stdlib.h>

static double max_abs_diff(const double *a, const double *b, int n) {
    double m = 0;
    int k;
    for (k = 0; k < n; ++k)
        if (fabs(a[k] - b[k]) > m) m = fabs(a[k] - b[k]);
    return m;
}

TEST(inverse_times_matrix_is_identity) {
    double a[9] = {2, 1, 0.5, -1, 3, 0.2, 0.3, 0.1, 4}, inv[9], p[9], id[9];
    double det = gk_m3_inverse(a, inv);
    CHECK(det != 0);
    gk_m3_mul(a, inv, p);
    gk_m3_identity(id);
    CHECK(max_abs_diff(p, id, 9) < 1e-14);
}

TEST(singular_inverse_leaves_output_untouched) {
    double a[9] = {1, 2, 3, 2, 4, 6, 1, 1, 1}, inv[9] = {7, 7, 7, 7, 7, 7, 7, 7, 7};
    CHECK(gk_m3_inverse(a, inv) == 0.0);
    CHECK(inv[0] == 7 && inv[8] == 7);
}

/* gk_m3_isfinite: 0 when any one entry is +inf, -inf or NaN, 1 for every finite value up to
 * +-DBL_MAX, subnormals and -0 */
TEST(m3_isfinite_finds_each_bad_entry) {
    const double bad[3] = {HUGE_VAL, -HUGE_VAL, NAN}, good[5] = {DBL_MAX, -DBL_MAX, 4.9e-324, -0.0, 1.0};
    double a[9];
    int k, v;
    for (k = 0; k < 9; ++k) {
        int j;
        for (v = 0; v < 5; ++v) {
            for (j = 0; j < 9; ++j) a[j] = 0.5 * j;
            a[k] = good[v];
            CHECK(gk_m3_isfinite(a) == 1);
        }
        for (v = 0; v < 3; ++v) {
            for (j = 0; j < 9; ++j) a[j] = 0.5 * j;
            a[k] = bad[v];
            CHECK(gk_m3_isfinite(a) == 0);
        }
    }
}

/* F = R U with R orthogonal (det +1) and U symmetric positive definite */
TEST(polar_decomposition_2d_and_3d) {
    double F2[9] = {1.1, 0.4, 0, -0.2, 0.9, 0, 0, 0, 1};
    double F3[9] = {1.2, 0.3, -0.1, 0.2, 0.8, 0.4, 0.05, -0.3, 1.1};
    double *Fs[2];
    int dims[2] = {2, 3}, c;
    Fs[0] = F2;
    Fs[1] = F3;
    for (c = 0; c < 2; ++c) {
        double R[9], U[9], RU[9], Rt[9], RtR[9], id[9], val[3], vec[9];
        CHECK(gk_m3_polar(Fs[c], dims[c], R, U) == GK_OK);
        gk_m3_mul(R, U, RU);
        CHECK(max_abs_diff(RU, Fs[c], 9) < 1e-13);
        gk_m3_transpose(R, Rt);
        gk_m3_mul(Rt, R, RtR);
        gk_m3_identity(id);
        CHECK(max_abs_diff(RtR, id, 9) < 1e-13);
        CHECK_NEAR(gk_m3_det(R), 1.0, 1e-13);
        CHECK_NEAR(U[1], U[3], 1e-14);
        gk_m3_sym_eigen(U, val, vec);
        CHECK(val[0] > 0);
    }
}

TEST(polar_rejects_inverted_map) {
    double F[9] = {-1, 0, 0, 0, 1, 0, 0, 0, 1}, R[9], U[9];
    CHECK(gk_m3_polar(F, 2, R, U) == GK_ERR_SINGULAR);
    CHECK(gk_m3_polar(F, 3, R, U) == GK_ERR_SINGULAR);
}

/* exp of a skew matrix is the rotation (Rodrigues); exp(diag) = diag(exp) */
TEST(matrix_exponential) {
    double w[3] = {0.3, -1.2, 2.0}, W[9] = {0, -2.0, -1.2, 2.0, 0, -0.3, 1.2, 0.3, 0}, E[9], R[9];
    double D[9] = {0.5, 0, 0, 0, -2, 0, 0, 0, 7}, ED[9];
    gk_m3_exp(W, E);
    gk_m3_rotation(w, R);
    CHECK(max_abs_diff(E, R, 9) < 1e-13);
    gk_m3_exp(D, ED);
    CHECK_REL(ED[0], exp(0.5), 1e-14);
    CHECK_REL(ED[4], exp(-2.0), 1e-14);
    CHECK_REL(ED[8], exp(7.0), 1e-13);
}

TEST(rotation_vector_roundtrip) {
    double ws[4][3] = {{0.1, 0.2, -0.3}, {0, 0, 3.1}, {1e-10, 0, 0}, {0, GK_PI - 1e-9, 0}};
    int c;
    for (c = 0; c < 4; ++c) {
        double R[9], w[3];
        gk_m3_rotation(ws[c], R);
        gk_m3_rotation_vector(R, w);
        CHECK(max_abs_diff(w, ws[c], 3) < 1e-7);
    }
}

TEST(symmetric_eigen_reconstructs) {
    double a[9] = {4, 1, -2, 1, 2, 0.5, -2, 0.5, 3}, val[3], vec[9], b[9];
    int i, j, k;
    gk_m3_sym_eigen(a, val, vec);
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            b[3 * i + j] = 0;
            for (k = 0; k < 3; ++k) b[3 * i + j] += vec[3 * i + k] * val[k] * vec[3 * j + k];
        }
    CHECK(max_abs_diff(a, b, 9) < 1e-13);
    CHECK(val[0] <= val[1] && val[1] <= val[2]);
}

TEST(allocator_alignment_and_realloc) {
    int k;
    for (k = 1; k < 200; k += 37) {
        double *p = (double *)gk_alloc(NULL, (size_t)k * sizeof(double));
        CHECK(p != NULL);
        CHECK(((uintptr_t)p & (GK_ALIGN - 1)) == 0);
        p[k - 1] = 1.0;
        CHECK(gk_realloc(NULL, (void **)&p, (size_t)k, (size_t)k * 2, sizeof(double)) == GK_OK);
        CHECK(p[k - 1] == 1.0);
        gk_free(NULL, p);
    }
}

/* same seed -> same stream; uniform mean 1/2, normal variance 1 */
TEST(rng_is_deterministic_and_sane) {
    gk_rng a, b;
    double sum = 0, sq = 0;
    int k, n = 200000;
    gk_rng_seed(&a, 42);
    gk_rng_seed(&b, 42);
    for (k = 0; k < 100; ++k) CHECK(gk_rng_u64(&a) == gk_rng_u64(&b));
    for (k = 0; k < n; ++k) sum += gk_rng_uniform(&a);
    CHECK_NEAR(sum / n, 0.5, 0.005);
    sum = 0;
    for (k = 0; k < n; ++k) {
        double x = gk_rng_normal(&a);
        sum += x;
        sq += x * x;
    }
    CHECK_NEAR(sum / n, 0.0, 0.01);
    CHECK_NEAR(sq / n, 1.0, 0.02);
}

TEST(error_messages) {
    gk_err e;
    gk_err_clear(&e);
    CHECK(gk_err_set(&e, GK_ERR_RADIUS, "particle %d has radius %g", 3, -1.0) == GK_ERR_RADIUS);
    CHECK(e.code == GK_ERR_RADIUS);
    CHECK(strstr(e.msg, "particle 3") != NULL);
    CHECK(strcmp(gk_result_string(GK_ERR_DT), "invalid time step") == 0);
    CHECK(gk_err_set(NULL, GK_ERR_ARG, "ignored") == GK_ERR_ARG);
}

/* the wide type computes exactly what scalar code computes, lane by lane */
TEST(simd_lanes_match_scalar) {
    double a[16], b[16], out[16];
    int32_t idx[16];
    int k, l;
    for (k = 0; k < 16; ++k) {
        a[k] = 0.37 * k - 2.5;
        b[k] = 1.0 + 0.11 * k * k;
        idx[k] = (k * 7) % 16;
    }
    for (k = 0; k + GK_VD_W <= 16; k += GK_VD_W) {
        gk_vd va = gk_vd_loadu(a + k), vb = gk_vd_loadu(b + k);
        gk_vd r = gk_vd_div(gk_vd_sqrt(gk_vd_mul(vb, vb)), gk_vd_sub(va, vb));
        r = gk_vd_select(gk_vd_lt(va, gk_vd_zero()), gk_vd_round(r), r);
        r = gk_vd_add(r, gk_vd_gather(a, idx + k));
        gk_vd_storeu(out + k, r);
        for (l = 0; l < GK_VD_W; ++l) {
            double s = sqrt(b[k + l] * b[k + l]) / (a[k + l] - b[k + l]);
            if (a[k + l] < 0) s = rint(s);
            s += a[idx[k + l]];
            CHECK(s == out[k + l]);
        }
    }
}

/* index vectors of w lanes into an array of n for the window gathers' test:
 * kind 0 sorted within a window, 1 sorted and spanning up to twice the lane
 * count, 2 unsorted, 3 sorted from near the array's end */
static void window_indices(gk_rng *rng, int kind, int t, int w, int n, int32_t *idx) {
    int l, at = (int)(gk_rng_uniform(rng) * (n - 1));
    for (l = 0; l < w; ++l) {
        int step = (int)(gk_rng_uniform(rng) * (kind == 0 ? 1.6 : 3.0));
        idx[l] = (int32_t)(kind == 2 ? gk_rng_uniform(rng) * n : (l == 0 ? at : idx[l - 1] + step));
        if (idx[l] >= n) idx[l] = n - 1;
    }
    if (kind == 3) idx[0] = (int32_t)(n - 1 - (t / 4) % w);
}

/* the window gathers return what the gathers do for every index vector, and
 * take their path only where every lane lies in [idx[0], idx[0] + lanes) and
 * the window ends inside the array (here at N) */
TEST(window_gather_equals_gather) {
    enum { N = 40 };
    double a[N];
    float b[N];
    int32_t idx[GK_VF_W];
    gk_rng rng;
    int k, l, t, fast_d = 0, fast_f = 0;
    for (k = 0; k < N; ++k) a[k] = 1.0 / (k + 1.5) - 0.25 * k, b[k] = (float)a[k];
    gk_rng_seed(&rng, 17);
    for (t = 0; t < 4000; ++t) {
        double got[GK_VD_W];
        gk_vd_win w;
        window_indices(&rng, t % 4, t, GK_VD_W, N, idx);
        gk_vd_win_make(idx, N, &w);
        gk_vd_storeu(got, gk_vd_gather_win(a, idx, &w));
        for (l = 0; l < GK_VD_W; ++l) CHECK(got[l] == a[idx[l]]);
        if (w.ok) {
            ++fast_d;
            for (l = 0; l < GK_VD_W; ++l) CHECK(idx[l] >= idx[0] && idx[l] < idx[0] + GK_VD_W);
            CHECK(idx[0] + GK_VD_W <= N);
        }
    }
    for (t = 0; t < 4000; ++t) {
        float got[GK_VF_W];
        gk_vf_win w;
        window_indices(&rng, t % 4, t, GK_VF_W, N, idx);
        gk_vf_win_make(idx, N, &w);
        gk_vf_storeu(got, gk_vf_gather_win(b, idx, &w));
        for (l = 0; l < GK_VF_W; ++l) CHECK(got[l] == b[idx[l]]);
        if (w.ok) {
            ++fast_f;
            for (l = 0; l < GK_VF_W; ++l) CHECK(idx[l] >= idx[0] && idx[l] < idx[0] + GK_VF_W);
            CHECK(idx[0] + GK_VF_W <= N);
        }
    }
#ifdef GK_VD_HAS_WIN
    CHECK(fast_d > 500 && fast_f > 500); /* the windows are taken where they may be */
#else
    CHECK(fast_d == 0 && fast_f == 0);
#endif
}

/* gk_vd_transpose8 (AVX-512 double): row k lane l becomes row l lane k, for
 * distinct values (signed zeros and infinities among them, moved as bits) */
TEST(transpose8_moves_every_lane) {
#ifdef GK_VD_HAS_TRANSPOSE8
    double a[64], got[64];
    gk_vd r[8];
    int k, l;
    for (k = 0; k < 64; ++k) a[k] = k == 5 ? -0.0 : (k == 42 ? -HUGE_VAL : 0.5 * k - 7.25);
    for (k = 0; k < 8; ++k) r[k] = gk_vd_loadu(a + 8 * k);
    gk_vd_transpose8(r);
    for (k = 0; k < 8; ++k) gk_vd_storeu(got + 8 * k, r[k]);
    for (k = 0; k < 8; ++k)
        for (l = 0; l < 8; ++l) CHECK(memcmp(&got[8 * l + k], &a[8 * k + l], sizeof(double)) == 0);
#else
    CHECK(GK_VD_W != 8 || GK_SIMD_WIDTH != 512); /* only the 512-bit build has it */
#endif
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(inverse_times_matrix_is_identity);
    RUN(singular_inverse_leaves_output_untouched);
    RUN(m3_isfinite_finds_each_bad_entry);
    RUN(polar_decomposition_2d_and_3d);
    RUN(polar_rejects_inverted_map);
    RUN(matrix_exponential);
    RUN(rotation_vector_roundtrip);
    RUN(symmetric_eigen_reconstructs);
    RUN(allocator_alignment_and_realloc);
    RUN(rng_is_deterministic_and_sane);
    RUN(error_messages);
    RUN(simd_lanes_match_scalar);
    RUN(window_gather_equals_gather);
    RUN(transpose8_moves_every_lane);
    return gk_test_done();
}
