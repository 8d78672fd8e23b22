/* test_cells.c - gk_cells.h and gk_pcell.h: candidate pairs against an O(N^2)
 * search over explicit periodic images, lattice re-mapping, Verlet criterion,
 * deformation paths and the servo. */
#include "gk_cells.h"
#include "gk_pcell.h"
#include "gk_test.h"
#include <stdlib.h>

#define MAXN 400

typedef struct pset {
    int dim, n;
    double h[9];
    double s[3][MAXN];
    gk_real r[MAXN];
} pset;

/* random polydisperse particles (radius ratio up to `ratio`) in a box */
static void make_set(pset *ps, int dim, int n, double ratio, uint64_t seed) {
    gk_rng rng;
    int p, k;
    double L = dim == 2 ? 1.0 : 1.0;
    gk_rng_seed(&rng, seed);
    ps->dim = dim;
    ps->n = n;
    gk_m3_identity(ps->h);
    ps->h[0] = L;
    ps->h[4] = 0.8 * L;
    if (dim == 3) ps->h[8] = 0.9 * L;
    for (p = 0; p < n; ++p) {
        for (k = 0; k < 3; ++k) ps->s[k][p] = k < dim ? gk_rng_uniform(&rng) : 0.0;
        /* log-uniform radii between rmax/ratio and rmax */
        ps->r[p] = (gk_real)(0.04 * pow(ratio, -gk_rng_uniform(&rng)));
    }
}

/* brute force: nearest image over explicit lattice vectors h k, |k_a| <= K[a] */
static int brute_pairs(const pset *ps, const double h[9], const int K[3], double skin, int *bi, int *bj,
                       int cap) {
    int i, j, m = 0, a0, a1, a2;
    for (i = 0; i < ps->n; ++i)
        for (j = i + 1; j < ps->n; ++j) {
            double best = 1e300, cut = (double)ps->r[i] + (double)ps->r[j] + skin;
            for (a0 = -K[0]; a0 <= K[0]; ++a0)
                for (a1 = -K[1]; a1 <= K[1]; ++a1)
                    for (a2 = -K[2]; a2 <= K[2]; ++a2) {
                        double ds[3], d[3];
                        ds[0] = ps->s[0][j] - ps->s[0][i] + a0;
                        ds[1] = ps->s[1][j] - ps->s[1][i] + a1;
                        ds[2] = ps->dim == 3 ? ps->s[2][j] - ps->s[2][i] + a2 : 0.0;
                        gk_m3_matvec(h, ds, d);
                        if (ps->dim == 2) d[2] = 0.0;
                        if (gk_v3_dot(d, d) < best) best = gk_v3_dot(d, d);
                    }
            if (best < cut * cut) {
                if (m < cap) {
                    bi[m] = i;
                    bj[m] = j;
                }
                ++m;
            }
        }
    return m;
}

/* cell-list pairs of ps in cell h (after reducing it: s' = M^-1 s) vs brute force in the unreduced cell */
static void compare_with_brute(pset *ps, const double h[9], const int K[3], double skin) {
    gk_pcell pc;
    gk_cells cl;
    gk_pairlist pl;
    gk_err e;
    double M[9], Mi[9], s2[3][MAXN];
    const double *sp[3];
    static int bi[MAXN * MAXN / 2], bj[MAXN * MAXN / 2];
    int nb, p, k, c;
    CHECK(gk_pcell_init(&pc, ps->dim, h, &e) == GK_OK);
    gk_m3_identity(M);
    if (gk_pcell_reduce(&pc, M)) gk_pcell_apply_basis(&pc, M);
    gk_m3_inverse(M, Mi);
    for (p = 0; p < ps->n; ++p) {
        double a[3], b[3];
        for (k = 0; k < 3; ++k) a[k] = ps->s[k][p];
        gk_m3_matvec(Mi, a, b);
        for (k = 0; k < 3; ++k) s2[k][p] = b[k];
    }
    for (k = 0; k < 3; ++k) sp[k] = s2[k];
    gk_cells_init(&cl, NULL);
    gk_pairlist_init(&pl, NULL);
    {
        double rmax = 0;
        for (p = 0; p < ps->n; ++p)
            if (ps->r[p] > rmax) rmax = ps->r[p];
        CHECK(gk_cells_bin(&cl, ps->dim, pc.h, ps->n, sp, 2 * rmax + skin, &e) == GK_OK);
    }
    CHECK(gk_cells_pairs(&cl, pc.h, sp, ps->r, skin, &pl, &e) == GK_OK);
    nb = brute_pairs(ps, h, K, skin, bi, bj, MAXN * MAXN / 2);
    CHECK_EQ_INT(pl.n, nb);
    /* same pairs, and in (i, j) order */
    for (c = 0; c < pl.n && c < nb; ++c) {
        if (pl.i[c] != bi[c] || pl.j[c] != bj[c]) {
            CHECK(pl.i[c] == bi[c] && pl.j[c] == bj[c]);
            break;
        }
    }
    for (p = 0; p < ps->n; ++p) CHECK(pl.start[p] <= pl.start[p + 1]);
    gk_cells_free(&cl);
    gk_pairlist_free(&pl);
}

/* Cell lists equal an O(N^2) search over explicit images, 2D, box and sheared
 * (Lees-Edwards) cells up to gamma = 10, radius ratio 10. */
TEST(cells_match_brute_force_2d_sheared) {
    static pset ps;
    double gammas[5] = {0.0, 0.3, 0.5, 2.7, 10.0};
    int g;
    for (g = 0; g < 5; ++g) {
        double h[9];
        int K[3];
        make_set(&ps, 2, 300, 10.0, 11 + g);
        gk_m3_copy(ps.h, h);
        h[1] = gammas[g] * h[4]; /* h01 = gamma Ly */
        K[0] = (int)gammas[g] + 2;
        K[1] = 2;
        K[2] = 0;
        compare_with_brute(&ps, h, K, 0.01);
    }
}

TEST(cells_match_brute_force_3d_sheared_and_rotated) {
    static pset ps;
    double gammas[3] = {0.0, 1.7, 10.0};
    int g;
    for (g = 0; g < 3; ++g) {
        double h[9], R[9], hr[9], w[3] = {0.3, -0.5, 1.1};
        int K[3];
        make_set(&ps, 3, 250, 10.0, 100 + g);
        gk_m3_copy(ps.h, h);
        h[1] = gammas[g] * h[4];
        h[5] = 0.4 * h[8];    /* also shear yz */
        gk_m3_rotation(w, R); /* and rotate the whole lattice */
        gk_m3_mul(R, h, hr);
        K[0] = (int)gammas[g] + 2;
        K[1] = 2;
        K[2] = 2;
        compare_with_brute(&ps, hr, K, 0.005);
    }
}

/* size ratio 1 and a dense monodisperse set: many candidates per bin */
TEST(cells_monodisperse_dense) {
    static pset ps;
    int K[3] = {2, 2, 0};
    make_set(&ps, 2, 400, 1.0, 7);
    compare_with_brute(&ps, ps.h, K, 0.02);
}

/* Open axes (no wrap; particles kept within half the cell along them, see
 * OPEN AXES in gk_cells.h) and coarse grids (1 to 3 bins along an axis, where
 * the stencil's bins coincide or wrap onto each other; the bin-count cap for
 * few particles in 3D): the pairs equal an O(N^2) search over the periodic
 * axes' images only, in (i, j) order. */
TEST(cells_open_axes_and_coarse_grids_match_brute_force) {
    static pset ps;
    static int bi[MAXN * MAXN / 2], bj[MAXN * MAXN / 2];
    const double skins[5] = {0.01, 0.06, 0.1, 0.15, 0.3};
    const int counts[2] = {30, 300};
    int dim, mask, si, ni, two_open = 0;
    for (dim = 2; dim <= 3; ++dim)
        for (mask = 0; mask < (1 << dim); ++mask)
            for (si = 0; si < 5; ++si)
                for (ni = 0; ni < 2; ++ni) {
                    gk_cells cl;
                    gk_pairlist pl;
                    gk_err e;
                    const double *sp[3];
                    double rmax = 0.0;
                    int K[3], k, p, c, nb;
                    make_set(&ps, dim, counts[ni], 4.0,
                             (uint64_t)(1000 + 100 * dim + 10 * mask + 3 * si + ni));
                    for (k = 0; k < 3; ++k) {
                        K[k] = k < dim && !(mask & (1 << k)) ? 2 : 0;
                        if (mask & (1 << k))
                            for (p = 0; p < ps.n; ++p) ps.s[k][p] = 0.05 + 0.4 * ps.s[k][p];
                        sp[k] = ps.s[k];
                    }
                    for (p = 0; p < ps.n; ++p)
                        if (ps.r[p] > rmax) rmax = ps.r[p];
                    gk_cells_init(&cl, NULL);
                    gk_pairlist_init(&pl, NULL);
                    cl.open = (unsigned)mask;
                    CHECK(gk_cells_bin(&cl, dim, ps.h, ps.n, sp, 2 * rmax + skins[si], &e) == GK_OK);
                    for (k = 0; k < dim; ++k) two_open |= (mask & (1 << k)) && cl.nbin[k] == 2;
                    CHECK(gk_cells_pairs(&cl, ps.h, sp, ps.r, skins[si], &pl, &e) == GK_OK);
                    nb = brute_pairs(&ps, ps.h, K, skins[si], bi, bj, MAXN * MAXN / 2);
                    CHECK_EQ_INT(pl.n, nb);
                    for (c = 0; c < pl.n && c < nb; ++c)
                        if (pl.i[c] != bi[c] || pl.j[c] != bj[c]) {
                            CHECK(pl.i[c] == bi[c] && pl.j[c] == bj[c]);
                            break;
                        }
                    for (p = 0; p < ps.n; ++p)
                        for (c = pl.start[p]; c < pl.start[p + 1]; ++c) CHECK_EQ_INT(pl.i[c], p);
                    gk_cells_free(&cl);
                    gk_pairlist_free(&pl);
                }
    CHECK(two_open); /* the coarsest open grid was reached (its -1 and +1 bins must not wrap) */
}

/* an open axis whose particles span a denormal extent (a monolayer on z = 0, one particle at z =
 * 1.6e-319: the bin scale nbin / extent overflows) bins them all in one layer: no NaN reaches the
 * conversion to a bin index (UBSan in make check stops at it), and the pairs are the brute-force
 * ones */
TEST(cells_open_axis_of_denormal_extent) {
    static pset ps;
    static int bi[MAXN * MAXN / 2], bj[MAXN * MAXN / 2];
    gk_cells cl;
    gk_pairlist pl;
    gk_err e;
    const double *sp[3];
    double rmax = 0.0;
    int K[3] = {2, 2, 0}, p, c, nb, ok;
    make_set(&ps, 3, 200, 4.0, 77);
    for (p = 0; p < ps.n; ++p) {
        ps.s[2][p] = 0.0;
        if (ps.r[p] > rmax) rmax = ps.r[p];
    }
    ps.s[2][7] = 1.61895e-319;
    for (c = 0; c < 3; ++c) sp[c] = ps.s[c];
    gk_cells_init(&cl, NULL);
    gk_pairlist_init(&pl, NULL);
    cl.open = 4u;
    ok = gk_cells_bin(&cl, 3, ps.h, ps.n, sp, 2 * rmax + 0.05, &e) == GK_OK;
    CHECK(ok);
    if (ok) {
        CHECK(isfinite(cl.inv[2]));
        for (p = 0; p < ps.n; ++p) CHECK(cl.bin_of[p] >= 0 && cl.bin_of[p] < cl.nbins);
        CHECK(gk_cells_pairs(&cl, ps.h, sp, ps.r, 0.05, &pl, &e) == GK_OK);
        nb = brute_pairs(&ps, ps.h, K, 0.05, bi, bj, MAXN * MAXN / 2);
        printf("    %d pairs (brute force %d)\n", pl.n, nb);
        CHECK_EQ_INT(pl.n, nb);
    }
    gk_cells_free(&cl);
    gk_pairlist_free(&pl);
}

/* a cell thinner than twice the interaction distance is refused, not miscounted */
TEST(cells_refuse_ambiguous_nearest_image) {
    gk_cells cl;
    gk_err e;
    double h[9], s0[2] = {0.1, 0.6}, s1[2] = {0.5, 0.5};
    const double *sp[3];
    sp[0] = s0;
    sp[1] = s1;
    sp[2] = s0;
    gk_m3_identity(h);
    h[0] = 1.0;
    h[4] = 0.1;
    gk_cells_init(&cl, NULL);
    CHECK(gk_cells_bin(&cl, 2, h, 2, sp, 0.06, &e) == GK_ERR_CELL);
    CHECK(strstr(e.msg, "nearest image") != NULL);
    gk_cells_free(&cl);
}

/* Re-mapping (lattice reduction) changes the basis, never the lattice: every
 * nearest-image pair distance is unchanged. */
TEST(remap_preserves_pair_distances) {
    static pset ps;
    gk_pcell pc;
    gk_err e;
    double h[9], M[9], Mi[9];
    int i, j, k, checked = 0;
    make_set(&ps, 2, 120, 3.0, 5);
    gk_m3_copy(ps.h, h);
    h[1] = 0.73 * h[4]; /* past the flip threshold */
    CHECK(gk_pcell_init(&pc, 2, h, &e) == GK_OK);
    CHECK(gk_pcell_reduce(&pc, M) == 1);
    CHECK(fabs(gk_m3_det(M) - 1.0) < 1e-15);
    gk_pcell_apply_basis(&pc, M);
    CHECK(pc.flips == 1);
    /* Lees-Edwards remap: the first edge is kept, h01 -> h01 - Lx */
    CHECK(pc.h[0] == h[0] && pc.h[3] == 0.0);
    CHECK_NEAR(pc.h[1], h[1] - h[0], 1e-15);
    gk_m3_inverse(M, Mi);
    for (i = 0; i < ps.n; ++i)
        for (j = i + 1; j < ps.n; ++j) {
            double a[3], b[3], a2[3], b2[3], d0[3], d1[3], ds[3];
            for (k = 0; k < 3; ++k) {
                a[k] = ps.s[k][i];
                b[k] = ps.s[k][j];
            }
            gk_m3_matvec(Mi, a, a2);
            gk_m3_matvec(Mi, b, b2);
            for (k = 0; k < 3; ++k) ds[k] = b[k] - a[k];
            {
                gk_pcell old;
                CHECK(gk_pcell_init(&old, 2, h, &e) == GK_OK);
                gk_pcell_min_image(&old, ds, d0);
            }
            for (k = 0; k < 3; ++k) ds[k] = b2[k] - a2[k];
            gk_pcell_min_image(&pc, ds, d1);
            /* only pairs closer than half the smallest width have a unique nearest image */
            if (gk_v3_dot(d0, d0) < 0.04) {
                CHECK_NEAR(sqrt(gk_v3_dot(d0, d0)), sqrt(gk_v3_dot(d1, d1)), 1e-13);
                ++checked;
            }
        }
    CHECK(checked > 100);
}

/* nearest-image branch vector d from particle i to j of a 2D set in cell h (d[2] = 0) */
static void image2d(const pset *ps, const double h[9], int i, int j, double d[3]) {
    double ds[3];
    int k;
    for (k = 0; k < 3; ++k) ds[k] = k < 2 ? ps->s[k][j] - ps->s[k][i] : 0.0;
    for (k = 0; k < 2; ++k) ds[k] -= rint(ds[k]);
    gk_m3_matvec(h, ds, d);
    d[2] = 0.0;
}

static double dist2d(const pset *ps, const double h[9], int i, int j) {
    double d[3];
    image2d(ps, h, i, j, d);
    return sqrt(d[0] * d[0] + d[1] * d[1]);
}

/* whether the list holds the pair (i, j), i < j */
static int listed(const gk_pairlist *pl, int i, int j) {
    int c;
    for (c = pl->start[i]; c < pl->start[i + 1]; ++c)
        if (pl->j[c] == j) return 1;
    return 0;
}

/* the touching pairs (closer than r_i + r_j) of a 2D set in cell h that the list misses */
static int unlisted_contacts(const pset *ps, const double h[9], const gk_pairlist *pl) {
    int i, j, missing = 0;
    for (i = 0; i < ps->n; ++i)
        for (j = i + 1; j < ps->n; ++j) {
            double d[3], R = (double)ps->r[i] + (double)ps->r[j];
            image2d(ps, h, i, j, d);
            if (d[0] * d[0] + d[1] * d[1] < R * R && !listed(pl, i, j)) ++missing;
        }
    return missing;
}

/* the 2D set of the skin tests (300 particles, seed 9), its positions kept in
 * s0 (sp: the moving ones, sp0: the kept), and its list with this skin built
 * at s0 in the set's cell; returns the largest radius */
static double skin_test_list(pset *ps, double s0[3][MAXN], const double *sp[3], const double *sp0[3],
                             double skin, gk_cells *cl, gk_pairlist *pl) {
    gk_err e;
    double rmax = 0.0;
    int p, k;
    make_set(ps, 2, 300, 2.0, 9);
    for (p = 0; p < ps->n; ++p)
        if (ps->r[p] > rmax) rmax = ps->r[p];
    for (k = 0; k < 3; ++k) {
        memcpy(s0[k], ps->s[k], sizeof s0[k]);
        sp[k] = ps->s[k];
        sp0[k] = s0[k];
    }
    gk_cells_init(cl, NULL);
    gk_pairlist_init(pl, NULL);
    CHECK(gk_cells_bin(cl, 2, ps->h, ps->n, sp0, 2 * rmax + skin, &e) == GK_OK);
    CHECK(gk_cells_pairs(cl, ps->h, sp0, ps->r, skin, pl, &e) == GK_OK);
    return rmax;
}

/* Verlet criterion: while gk_cells_skin_ok says yes, every pair closer than
 * r_i + r_j is in the list built earlier (random walks + affine shear). */
TEST(verlet_skin_criterion_is_safe) {
    static pset ps;
    gk_cells cl;
    gk_pairlist pl;
    gk_rng rng;
    double h0[9], h[9], s0[3][MAXN], skin = 0.01, rmax;
    const double *sp[3], *sp0[3];
    int step, p, k, accepted = 0, missing = 0;
    rmax = skin_test_list(&ps, s0, sp, sp0, skin, &cl, &pl);
    gk_m3_copy(ps.h, h0);
    gk_m3_copy(h0, h);
    gk_rng_seed(&rng, 3);
    for (step = 0; step < 400; ++step) {
        double dm2;
        for (p = 0; p < ps.n; ++p)
            for (k = 0; k < 2; ++k) ps.s[k][p] += 2e-5 * (gk_rng_uniform(&rng) - 0.5);
        h[1] += 5e-4 * h[4]; /* shear */
        h[0] *= 1.0 - 1e-4;  /* and compression */
        if (!gk_cells_skin_ok(2, h0, h, ps.n, sp0, sp, skin, rmax, &dm2)) break;
        ++accepted;
        missing += unlisted_contacts(&ps, h, &pl); /* every touching pair must be listed */
    }
    CHECK(accepted > 10);  /* the criterion is not trivially false */
    CHECK(accepted < 400); /* and it does trigger */
    CHECK_EQ_INT(missing, 0);
    gk_cells_free(&cl);
    gk_pairlist_free(&pl);
}

/* Two particles move apart from the affine map by at most the sum of their
 * displacements, |e_j - e_i| <= |e_i| + |e_j|, so the two largest of distinct
 * particles bound every pair (gk_cells_skin_margin2), where twice the largest
 * (gk_cells_skin_margin) is looser. Checked: the two largest against a full
 * scan, the two margins equal for {d, d}, a lone particle, a NaN; and one
 * particle moved 0.9 skin straight at its nearest unlisted neighbour: twice
 * the largest refuses the list, the two largest keep it, and every touching
 * pair is still listed. */
TEST(skin_two_largest_displacements) {
    static pset ps;
    static double s0[3][MAXN];
    gk_cells cl;
    gk_pairlist pl;
    gk_rng rng;
    const double *sp[3], *sp0[3];
    double t2[2], a = 0.0, b = 0.0, skin = 0.01, rmax, best = 1e300, dd[2];
    int p, k, q = -1, i, j;
    make_set(&ps, 3, 200, 2.0, 5);
    for (k = 0; k < 3; ++k) {
        memcpy(s0[k], ps.s[k], sizeof s0[k]);
        sp[k] = ps.s[k];
        sp0[k] = s0[k];
    }
    gk_rng_seed(&rng, 11);
    for (p = 0; p < ps.n; ++p) {
        double ds[3], u[3], d2;
        for (k = 0; k < 3; ++k) ps.s[k][p] += 1e-3 * (gk_rng_uniform(&rng) - 0.5);
        for (k = 0; k < 3; ++k) ds[k] = ps.s[k][p] - s0[k][p];
        gk_m3_matvec(ps.h, ds, u);
        d2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
        if (d2 > a) {
            b = a;
            a = d2;
        } else if (d2 > b) {
            b = d2;
        }
    }
    gk_cells_disp2_top2(3, ps.h, ps.n, sp0, sp, t2);
    CHECK(t2[0] == a && t2[1] == b && b > 0.0 && b < a);
    CHECK(gk_cells_disp2_max(3, ps.h, ps.n, sp0, sp) == a);
    dd[0] = dd[1] = a;
    CHECK(gk_cells_skin_margin2(3, ps.h, ps.h, skin, 0.04, dd) ==
          gk_cells_skin_margin(3, ps.h, ps.h, skin, 0.04, a));
    CHECK(gk_cells_skin_margin2(3, ps.h, ps.h, skin, 0.04, t2) >
          gk_cells_skin_margin(3, ps.h, ps.h, skin, 0.04, a));
    gk_cells_disp2_top2(3, ps.h, 1, sp0, sp, t2);
    CHECK(t2[1] == 0.0 && t2[0] > 0.0);
    ps.s[1][7] = NAN;
    gk_cells_disp2_top2(3, ps.h, ps.n, sp0, sp, t2);
    CHECK(t2[0] != t2[0] && !(gk_cells_skin_margin2(3, ps.h, ps.h, skin, 0.04, t2) > 0.0));

    /* 2D: the nearest unlisted pair, one of its particles moved 0.9 skin at the other */
    rmax = skin_test_list(&ps, s0, sp, sp0, skin, &cl, &pl);
    for (i = 0; i < ps.n; ++i)
        for (j = i + 1; j < ps.n; ++j) {
            double gap = dist2d(&ps, ps.h, i, j) - (double)ps.r[i] - (double)ps.r[j];
            if (!listed(&pl, i, j) && gap < best) best = gap, q = i, p = j;
        }
    CHECK(q >= 0 && best >= skin);
    if (q >= 0) {
        double ds[3], dv[3], hi[9], L;
        image2d(&ps, ps.h, q, p, dv);
        L = sqrt(dv[0] * dv[0] + dv[1] * dv[1]);
        for (k = 0; k < 2; ++k) dv[k] *= 0.9 * skin / L; /* 0.9 skin along the line of centres */
        CHECK(gk_m3_inverse(ps.h, hi) > 0.0);
        gk_m3_matvec(hi, dv, ds);
        ps.s[0][q] += ds[0];
        ps.s[1][q] += ds[1];
        CHECK(fabs(dist2d(&ps, ps.h, q, p) - (L - 0.9 * skin)) < 1e-12);
        CHECK(!(gk_cells_skin_margin(2, ps.h, ps.h, skin, rmax, gk_cells_disp2_max(2, ps.h, ps.n, sp0, sp)) >
                0.0));
        CHECK(gk_cells_skin_ok(2, ps.h, ps.h, ps.n, sp0, sp, skin, rmax, NULL));
        CHECK_EQ_INT(unlisted_contacts(&ps, ps.h, &pl), 0);
    }
    gk_cells_free(&cl);
    gk_pairlist_free(&pl);
}

/* GK_PATH_OBJECTIVE ends exactly at I + dH, also for a 90 degree spin or a
 * shear of 10; GK_PATH_CONSTANT_L ends at exp(dH) (constant L, YADE). */
TEST(deformation_paths_end_maps) {
    double cases[3][9] = {{0, -1, 0, 1, -1, 0, 0, 0, 0}, /* R(90) - I in 2D: [[0,-1],[1,0]] - I */
                          {0, 10, 0, 0, 0, 0, 0, 0, 0},
                          {1e-3, 2e-3, 0, -1e-3, -2e-3, 0, 0, 0, 0}};
    int c, k, s;
    cases[0][0] = -1.0; /* cos 90 - 1 */
    for (c = 0; c < 3; ++c) {
        gk_path p;
        gk_err e;
        double M[9], acc[9], E[9], t[9], target[9];
        CHECK(gk_path_init(&p, 2, GK_PATH_OBJECTIVE, cases[c], 37, &e) == GK_OK);
        gk_m3_identity(acc);
        for (s = 1; s <= 37; ++s) {
            gk_path_step(&p, s, E);
            gk_m3_mul(E, acc, t);
            gk_m3_copy(t, acc);
        }
        gk_path_map(&p, 37, M);
        gk_m3_identity(target);
        for (k = 0; k < 9; ++k) target[k] += cases[c][k];
        for (k = 0; k < 9; ++k) {
            CHECK_NEAR(M[k], target[k], 1e-13);
            CHECK_NEAR(acc[k], target[k], 1e-12);
        }
        /* the spin case stays a rotation all along (no volume change) */
        if (c == 0)
            for (s = 0; s <= 37; ++s) {
                gk_path_map(&p, s, M);
                CHECK_NEAR(gk_m3_det(M), 1.0, 1e-13);
            }
        CHECK(gk_path_init(&p, 2, GK_PATH_CONSTANT_L, cases[c], 10, &e) == GK_OK);
        gk_m3_identity(acc);
        for (s = 1; s <= 10; ++s) {
            gk_path_step(&p, s, E);
            gk_m3_mul(E, acc, t);
            gk_m3_copy(t, acc);
        }
        gk_m3_exp(cases[c], target);
        for (k = 0; k < 9; ++k) CHECK_NEAR(acc[k], target[k], 1e-12 * (1 + fabs(target[k])));
    }
}

TEST(path_rejects_bad_increments) {
    gk_path p;
    gk_err e;
    double inv[9] = {-2, 0, 0, 0, 0, 0, 0, 0, 0}, nan9[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    nan9[1] = NAN;
    CHECK(gk_path_init(&p, 2, GK_PATH_OBJECTIVE, inv, 10, &e) == GK_ERR_SINGULAR);
    CHECK(gk_path_init(&p, 2, GK_PATH_OBJECTIVE, nan9, 10, &e) == GK_ERR_NAN);
    CHECK(gk_path_init(&p, 2, GK_PATH_CONSTANT_L, inv, 0, &e) == GK_ERR_ARG);
}

TEST(pcell_rejects_bad_cells) {
    gk_pcell c;
    gk_err e;
    double h[9] = {1, 0, 0, 0, -1, 0, 0, 0, 1}, E[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    CHECK(gk_pcell_init(&c, 2, h, &e) == GK_ERR_CELL);
    h[4] = 1.0;
    CHECK(gk_pcell_init(&c, 2, h, &e) == GK_OK);
    E[4] = -1.0; /* would invert the cell */
    CHECK(gk_pcell_advance(&c, E, &e) == GK_ERR_CELL);
    CHECK(c.h[4] == 1.0); /* unchanged */
    E[4] = NAN;
    CHECK(gk_pcell_advance(&c, E, &e) == GK_ERR_NAN);
    CHECK(gk_pcell_init_box(&c, 3, 1, 1, 0, &e) == GK_ERR_CELL);
}

/* servo: a stress-controlled axis moves towards its target, capped; a
 * strain-controlled axis takes its prescribed rate */
TEST(servo_rates) {
    gk_servo s;
    double sig[9] = {-90e3, 0, 0, 0, -120e3, 0, 0, 0, 0}, st[3] = {1e8, 1e8, 0}, L[9];
    memset(&s, 0, sizeof s);
    s.mode[0] = GK_SERVO_STRESS;
    s.mode[1] = GK_SERVO_STRAIN;
    s.target[0] = -100e3;
    s.rate[1] = -0.01;
    s.max_rate = 1.0;
    s.gain = 0.1;
    gk_m3_zero(L);
    gk_servo_rates(&s, 2, sig, st, 1e-5, L);
    /* sigma_xx = -90 kPa is less compressed than -100 kPa: compress (L00 < 0):
     * 0.1 * (-10e3) / (1e8 * 1e-5) = -1 (at the cap) */
    CHECK_NEAR(L[0], -1.0, 1e-12);
    CHECK_NEAR(L[4], -0.01, 1e-15);
    s.max_rate = 0.5;
    gk_servo_rates(&s, 2, sig, st, 1e-5, L);
    CHECK_NEAR(L[0], -0.5, 1e-12);
    sig[0] = -100e3;
    gk_servo_rates(&s, 2, sig, st, 1e-5, L);
    CHECK_NEAR(L[0], 0.0, 1e-15);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(cells_match_brute_force_2d_sheared);
    RUN(cells_match_brute_force_3d_sheared_and_rotated);
    RUN(cells_monodisperse_dense);
    RUN(cells_open_axes_and_coarse_grids_match_brute_force);
    RUN(cells_open_axis_of_denormal_extent);
    RUN(cells_refuse_ambiguous_nearest_image);
    RUN(remap_preserves_pair_distances);
    RUN(verlet_skin_criterion_is_safe);
    RUN(skin_two_largest_displacements);
    RUN(deformation_paths_end_maps);
    RUN(path_rejects_bad_increments);
    RUN(pcell_rejects_bad_cells);
    RUN(servo_rates);
    return gk_test_done();
}
