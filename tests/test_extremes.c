/* test_extremes.c - stability at the extremes.
 *
 * One named test per extreme. Each states the behaviour it expects (with the
 * analytic result where there is one) and checks it. Sizes shrink under
 * GK_TEST_QUICK (the sanitizer build).
 */
#define _POSIX_C_SOURCE 200809L /* WIFEXITED for the driver run (test 11) */
#include "gk_homog.h"
#include "gk_test.h"
#include <float.h>
#include <stdlib.h>
#include <sys/wait.h>

#ifdef GK_TEST_QUICK
#define QUICK(full, quick) (quick)
#else
#define QUICK(full, quick) (full)
#endif

static const char *RVE400 = "examples/data/rve400.txt";

/* ------------------------------------------------------------- helpers */
static gk_result load_seed(gk_rve *rve, const gk_rve_def *def) {
    gk_packing pk;
    gk_err e;
    gk_result r = gk_packing_read(RVE400, &pk, NULL, &e);
    if (r) {
        printf("    cannot read %s: %s\n", RVE400, e.msg);
        return r;
    }
    r = gk_rve_create(rve, def, &pk);
    if (r) printf("    create: %s\n", gk_rve_error(rve));
    gk_packing_free(&pk);
    return r;
}

/* hexagonal lattice of equal disks, spacing a = 2r - delta (6 contacts each) */
static gk_result hex_lattice(gk_rve *rve, const gk_rve_def *def, int nx, int ny, double r, double delta) {
    gk_packing pk;
    gk_err e;
    gk_result res;
    double a = 2 * r - delta;
    int ix, iy, p = 0;
    res = gk_packing_init(&pk, 2, nx * ny, NULL, &e);
    if (res) return res;
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

static gk_result generate(gk_packing *pk, int dim, int n, double rmin, double rmax, uint64_t seed) {
    gk_gen_def g;
    gk_err e;
    gk_result r;
    memset(&g, 0, sizeof g);
    g.dim = dim;
    g.n = n;
    g.r_min = rmin;
    g.r_max = rmax;
    g.seed = seed;
    r = gk_packing_generate(pk, &g, NULL, &e);
    if (r) printf("    generate: %s\n", e.msg);
    return r;
}

/* every particle and pair quantity and the stress are finite */
static int state_finite(const gk_rve *rve) {
    int k, p, c;
    for (k = 0; k < 9; ++k)
        if (!isfinite(rve->stress[k])) return 0;
    for (k = 0; k < 3; ++k) {
        for (p = 0; p < rve->n; ++p) {
            if (k < rve->dim && (!isfinite(rve->s[k][p]) || !isfinite((double)rve->v[k][p]) ||
                                 !isfinite((double)rve->f[k][p])))
                return 0;
            if (rve->w[k] && !isfinite((double)rve->w[k][p])) return 0;
        }
        for (c = 0; c < rve->pl.n; ++c) {
            if (k < rve->dim && !isfinite((double)rve->fc[k][c])) return 0;
            if (rve->ft[k] && !isfinite((double)rve->ft[k][c])) return 0;
        }
    }
    return 1;
}

/* branch vector of pair c at the current positions; returns |d| */
static double branch(const gk_rve *rve, int c, double d[3]) {
    int i = rve->pl.i[c], j = rve->pl.j[c], k;
    double ds[3];
    for (k = 0; k < 3; ++k) ds[k] = k < rve->dim ? rve->s[k][j] - rve->s[k][i] : 0.0;
    gk_pcell_min_image(&rve->cell, ds, d);
    if (rve->dim == 2) d[2] = 0.0;
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* largest |F_t| / |F| over the contacts (forces of the last evaluation,
 * geometry now: call gk_rve_refresh first so that the two agree) */
static double max_tangential_ratio(const gk_rve *rve) {
    double m = 0.0;
    int c, k;
    for (c = 0; c < rve->pl.n; ++c) {
        double d[3], F[3], dd, fn, ft2 = 0.0, f2 = 0.0;
        if (!(rve->cs[c] & GK_CS_CONTACT)) continue;
        dd = branch(rve, c, d);
        for (k = 0; k < 3; ++k) F[k] = k < rve->dim ? (double)rve->fc[k][c] : 0.0;
        fn = (F[0] * d[0] + F[1] * d[1] + F[2] * d[2]) / dd;
        for (k = 0; k < 3; ++k) {
            double t = F[k] - fn * d[k] / dd;
            ft2 += t * t;
            f2 += F[k] * F[k];
        }
        if (f2 > 0.0 && sqrt(ft2 / f2) > m) m = sqrt(ft2 / f2);
    }
    return m;
}

/* elastic energy stored in the contacts (linear law): k_n delta^2/2 + F_t^2/(2 k_t) */
static double contact_energy(const gk_rve *rve) {
    double e = 0.0;
    int c;
    for (c = 0; c < rve->pl.n; ++c) {
        double d[3], delta;
        gk_real kn, fn, kt;
        int i = rve->pl.i[c], j = rve->pl.j[c];
        if (!(rve->cs[c] & GK_CS_CONTACT)) continue;
        delta = (double)rve->r[i] + (double)rve->r[j] - branch(rve, c, d);
        if (delta <= 0) continue;
        gk_contact_stiffness(&rve->K, GK_LAW_LINEAR, rve->r[i], rve->r[j], (gk_real)delta, &kn, &fn, &kt);
        e += 0.5 * (double)kn * delta * delta;
        if (rve->ft[0] && kt > 0) {
            double f2 = 0.0;
            int k;
            for (k = 0; k < (rve->dim == 2 ? 1 : 3); ++k) f2 += (double)rve->ft[k][c] * (double)rve->ft[k][c];
            e += 0.5 * f2 / (double)kt;
        }
    }
    return e;
}

/* a byte snapshot of the whole RVE state (gk_rve_save) */
static unsigned char *snapshot(const gk_rve *rve, size_t *n) {
    unsigned char *b;
    *n = gk_rve_state_size(rve);
    b = (unsigned char *)malloc(*n);
    if (b) gk_rve_save(rve, b, *n, NULL);
    return b;
}
static int same_as(const gk_rve *rve, const unsigned char *snap, size_t n) {
    size_t m;
    unsigned char *now = snapshot(rve, &m);
    int same = now && m == n && memcmp(now, snap, n) == 0;
    free(now);
    return same;
}

static void m3_rot2(double th, double R[9]) {
    gk_m3_identity(R);
    R[0] = cos(th);
    R[1] = -sin(th);
    R[3] = sin(th);
    R[4] = cos(th);
}

/* ===================================================== 1. time step
 * dt from 0.1 to 0.95 of gk_rve_dt_critical() (Guo & Zhao 2014 eq 19,
 * dt_cr = sqrt(m_min / k_n,max)), then beyond it.
 *
 * (a) Seed packing (400 disks, radii 3-7 mm, friction, rotating), no
 *     damping, a free run of the same physical time at every dt. Leap-frog
 *     conserves energy to O(dt^2) and Coulomb sliding only dissipates, so the
 *     kinetic energy stays below the elastic energy E0 stored in the
 *     contacts and p stays where it is (the packing is in equilibrium, p
 *     within 1 %). Up to 0.9 dt_cr the packing stays at rest (KE < 1e-5 E0;
 *     measured 1.5e-7 E0 at every dt); at 0.95 dt_cr its rotational mode
 *     (see (b)) grows but is contained by sliding (measured KE 3e-3 E0):
 *     bounded, finite, no error. */
TEST(dt_0_1_to_0_95_critical_seed_packing) {
    double fr[6] = {0.1, 0.25, 0.5, 0.75, 0.9, 0.95};
    double T = QUICK(2000.0, 500.0); /* run length in units of dt_cr */
    int c;
    for (c = 0; c < 6; ++c) {
        gk_rve rve;
        gk_rve_def def = gk_rve_def_default();
        double e0, p0, s[9], ke_max = 0.0;
        long k, n;
        def.damping = 0.0;
        if (load_seed(&rve, &def)) {
            CHECK(0);
            return;
        }
        CHECK(gk_rve_set_dt(&rve, fr[c] * gk_rve_dt_critical(&rve)) == GK_OK);
        CHECK(gk_rve_refresh(&rve) == GK_OK);
        e0 = contact_energy(&rve);
        gk_rve_stress(&rve, s);
        p0 = gk_stress_p(s, 2);
        n = (long)(T / fr[c]);
        for (k = 0; k < n; k += 100) {
            gk_result r = gk_rve_step(&rve, 100);
            double ke = gk_rve_kinetic_energy(&rve);
            CHECK(r == GK_OK);
            if (r) break;
            if (ke > ke_max) ke_max = ke;
        }
        CHECK(state_finite(&rve));
        gk_rve_stress(&rve, s);
        CHECK(ke_max < 1e-2 * e0);
        if (fr[c] <= 0.9) CHECK(ke_max < 1e-5 * e0);
        CHECK_NEAR(gk_stress_p(s, 2), p0, 0.01 * p0);
        printf("    dt = %.2f dt_cr: %6ld steps, max KE / E0 = %.2e, p / p0 - 1 = %+.1e\n", fr[c], n,
               ke_max / e0, gk_stress_p(s, 2) / p0 - 1.0);
        gk_rve_destroy(&rve);
    }
}

/* (b) Eq 19 is the one-contact estimate, not the stability limit of
 *     leap-frog on a packing. Hexagonal lattice of equal disks (Z = 6
 *     contacts each, k = k_n = E r, disk mass m), no damping; leap-frog is
 *     stable iff dt < 2 / omega_max, with (analytic, lattice dynamics):
 *       frictionless: omega^2 = 6 k/m at the M point   -> dt* = 0.816 sqrt(m/k)
 *       friction, no rotation (k_t = 0.8 k): 4.5 (k + k_t)/m at the K point
 *                                                       -> dt* = 0.703 sqrt(m/k)
 *       friction and rotation (I = m r^2/2): all disks spinning alike slip
 *         2 r w at every contact, torque 2 k_t r^2 theta per contact:
 *         omega^2 = 4 Z k_t / m = 19.2 k/m              -> dt* = 0.456 sqrt(m/k)
 *     and for the face-centred cubic lattice of equal spheres (Z = 12,
 *     I = 2/5 m r^2) with friction and rotation, the same mode with the
 *     slip 2 r w |e x n| (e: spin axis; mean |e x n|^2 = 2/3):
 *         omega^2 = (10/3) Z k_t / m = 32 k/m           -> dt* = 0.354 sqrt(m/k)
 *     From a 1e-9 J velocity perturbation, at 0.97 dt* the kinetic energy
 *     stays at the perturbation's level (leap-frog's shadow energy allows
 *     at most 1/(1 - 0.97^2) = 17x), at 1.03 dt* it grows by
 *     more than 1e3 within 2000 steps (1000 for fcc). Either way the state
 *     stays finite.
 *
 *     KNOWN LIMITATION (found by this suite): on this lattice
 *     gk_rve_dt_critical() is exactly sqrt(m/k), so the API accepts (GK_OK)
 *     a dt up to 2.2 x the
 *     rotational limit; the default dt_factor 0.5 is above it. Such a run is
 *     not flagged (no GK_ERR_*, no NaN); its energy is the symptom. The seed
 *     packing (polydisperse, Z ~ 4) is stable to 0.9 dt_cr, see (a). If
 *     dt_cr becomes a true bound, the last CHECK below flips. */
/* face-centred cubic lattice of equal spheres, n^3 cells, spacing 2r - delta (12 contacts each) */
static gk_result fcc_lattice(gk_rve *rve, const gk_rve_def *def, int n, double r, double delta) {
    double basis[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}},
           a = (2 * r - delta) * sqrt(2.0);
    gk_packing pk;
    gk_err e;
    gk_result res;
    int i, j, k, b, p = 0;
    res = gk_packing_init(&pk, 3, 4 * n * n * n, NULL, &e);
    if (res) return res;
    pk.h[0] = pk.h[4] = pk.h[8] = n * a;
    for (i = 0; i < n; ++i)
        for (j = 0; j < n; ++j)
            for (k = 0; k < n; ++k)
                for (b = 0; b < 4; ++b) {
                    pk.x[p] = (i + basis[b][0] + 0.25) * a;
                    pk.y[p] = (j + basis[b][1] + 0.25) * a;
                    pk.z[p] = (k + basis[b][2] + 0.25) * a;
                    pk.r[p] = r;
                    ++p;
                }
    res = gk_rve_create(rve, def, &pk);
    gk_packing_free(&pk);
    return res;
}

/* lattice 0: 2D hexagonal (64 disks), 1: 3D face-centred cubic (256 spheres) */
static double lattice_energy_growth(int lattice, double f, int friction, int rotation, int nsteps,
                                    int *finite) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    double ke0, ke_max = 0.0, m, k;
    int p, st, q;
    def.damping = 0.0;
    def.mat.friction = friction ? 0.5 : 0.0;
    if (!rotation) def.flags |= GK_RVE_NO_ROTATION;
    if ((lattice == 0 ? hex_lattice(&rve, &def, 8, 8, 0.005, 1e-5)
                      : fcc_lattice(&rve, &def, 4, 0.005, 1e-5)) != GK_OK)
        return -1.0;
    CHECK(gk_rve_refresh(&rve) == GK_OK);
    CHECK_EQ_INT(rve.ncontacts, (lattice == 0 ? 3 : 6) * rve.n);
    m = 1.0 / (double)rve.minv[0];
    k = def.mat.young * 0.005;
    CHECK_REL(gk_rve_dt_critical(&rve), sqrt(m / k), 1e-12); /* eq 19 */
    CHECK(gk_rve_set_dt(&rve, f * sqrt(m / k)) == GK_OK);
    srand(7);
    for (p = 0; p < rve.n; ++p)
        for (q = 0; q < 3; ++q) {
            if (q < rve.dim) rve.v[q][p] = (gk_real)(1e-4 * (rand() / (double)RAND_MAX - 0.5));
            if (rve.w[q]) rve.w[q][p] = (gk_real)(1e-2 * (rand() / (double)RAND_MAX - 0.5));
        }
    ke0 = gk_rve_kinetic_energy(&rve);
    for (st = 0; st < nsteps; st += 10) {
        double ke;
        CHECK(gk_rve_step(&rve, 10) == GK_OK);
        ke = gk_rve_kinetic_energy(&rve);
        if (ke > ke_max) ke_max = ke;
    }
    *finite = state_finite(&rve);
    gk_rve_destroy(&rve);
    return ke_max / ke0;
}

TEST(dt_stability_limit_lattices) {
    /* hexagonal: frictionless, friction without rotation, friction with rotation; fcc: friction with rotation */
    double lim[4] = {2.0 / sqrt(6.0), 2.0 / sqrt(4.5 * 1.8), 2.0 / sqrt(4.0 * 6.0 * 0.8),
                     2.0 / sqrt(10.0 / 3.0 * 12.0 * 0.8)};
    const char *what[4] = {"hex, frictionless", "hex, friction, no rotation", "hex, friction and rotation",
                           "fcc, friction and rotation"};
    int c;
    for (c = 0; c < 4; ++c) {
        int fin1 = 0, fin2 = 0, lat = c == 3, n = c == 3 ? 1000 : 2000;
        double g1 = lattice_energy_growth(lat, 0.97 * lim[c], c > 0, c >= 2, n, &fin1);
        double g2 = lattice_energy_growth(lat, 1.03 * lim[c], c > 0, c >= 2, n, &fin2);
        printf("    %-27s dt* = %.3f sqrt(m/k): KE growth %.1e at 0.97 dt*, %.1e at 1.03 dt*\n", what[c],
               lim[c], g1, g2);
        CHECK(g1 > 0 && g1 < 20.0); /* shadow energy: <= 1/(1 - 0.97^2) = 17 */
        CHECK(g2 > 1e3);
        CHECK(fin1 && fin2);
    }
    /* the limitation: eq 19 admits dt = 0.95 sqrt(m/k) > 0.456 sqrt(m/k) */
    {
        gk_rve rve;
        gk_rve_def def = gk_rve_def_default();
        CHECK(hex_lattice(&rve, &def, 8, 8, 0.005, 1e-5) == GK_OK);
        CHECK(gk_rve_set_dt(&rve, 0.95 * gk_rve_dt_critical(&rve)) == GK_OK);
        CHECK(rve.dt > lim[2] * sqrt(1.0 / ((double)rve.minv[0] * def.mat.young * 0.005)));
        gk_rve_destroy(&rve);
    }
}

/* (c) Beyond critical. The documented behaviour is refusal: a dt above
 *     dt_cr gets GK_ERR_DT with a message from gk_rve_set_dt (state
 *     unchanged) and from gk_rve_create. Hertz contacts stiffen with load so
 *     dt_cr shrinks (k_n ~ sqrt(delta): dt_cr ~ delta_max^-1/4); the RVE
 *     re-checks at every list rebuild and stops with GK_ERR_DT, finite and
 *     not marked diverged; restore + a smaller dt continues. A step that does
 *     produce a non-finite value returns GK_ERR_DIVERGED and marks the RVE
 *     (GK_ERR_STATE until a restore). A dt forced past the check (written
 *     into the struct, unsupported) never returns NaN: either
 *     GK_ERR_DIVERGED or a finite (but energetic: KE >> E0) state. */
TEST(dt_beyond_critical_is_refused_or_reported) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    unsigned char *snap;
    size_t ns;
    double dtc;
    if (load_seed(&rve, &def)) {
        CHECK(0);
        return;
    }
    dtc = gk_rve_dt_critical(&rve);
    snap = snapshot(&rve, &ns);
    CHECK(gk_rve_set_dt(&rve, 2.0 * dtc) == GK_ERR_DT);
    CHECK(strstr(gk_rve_error(&rve), "critical") != NULL);
    CHECK(same_as(&rve, snap, ns));
    free(snap);
    gk_rve_destroy(&rve);
    {
        gk_rve r2;
        gk_packing pk;
        gk_err e;
        CHECK(gk_packing_read(RVE400, &pk, NULL, &e) == GK_OK);
        def.dt = 2.0 * dtc;
        CHECK(gk_rve_create(&r2, &def, &pk) == GK_ERR_DT);
        CHECK(strstr(gk_rve_error(&r2), "above the critical") != NULL);
        def.dt = 0.0;
        gk_packing_free(&pk);
    }
    /* Hertz: load until the critical step falls below dt */
    {
        gk_rve_state st;
        double dH[9] = {-2e-3, 0, 0, 0, -2e-3, 0, 0, 0, 0}, s[9];
        gk_result r = GK_OK;
        int inc;
        def = gk_rve_def_default();
        def.mat.law = GK_LAW_HERTZ;
        def.dt_factor = 0.9;
        if (load_seed(&rve, &def)) {
            CHECK(0);
            return;
        }
        gk_rve_state_init(&st, NULL);
        for (inc = 0; inc < 30; ++inc) {
            CHECK(gk_rve_state_save(&st, &rve) == GK_OK);
            r = gk_rve_deform(&rve, dH, 100);
            if (r) break;
        }
        printf("    Hertz at 0.9 dt_cr, compressed in steps of 0.2 %%: %s after %d increments (%s)\n",
               r == GK_ERR_DT ? "GK_ERR_DT" : "no error", inc, gk_rve_error(&rve));
        CHECK(r == GK_ERR_DT);
        CHECK(strstr(gk_rve_error(&rve), "exceeds the critical") != NULL);
        CHECK(!rve.diverged);
        CHECK(state_finite(&rve));
        CHECK(gk_rve_state_restore(&st, &rve) == GK_OK);
        CHECK(gk_rve_set_dt(&rve, 0.5 * gk_rve_dt_critical(&rve)) == GK_OK);
        CHECK(gk_rve_deform(&rve, dH, 200) == GK_OK);
        gk_rve_stress(&rve, s);
        CHECK(state_finite(&rve) && s[0] < 0 && s[4] < 0);
        gk_rve_state_free(&st);
        gk_rve_destroy(&rve);
    }
    /* a non-finite value -> GK_ERR_DIVERGED, the RVE refuses work until restored */
    {
        gk_rve_state st;
        def = gk_rve_def_default();
        if (load_seed(&rve, &def)) {
            CHECK(0);
            return;
        }
        gk_rve_state_init(&st, NULL);
        CHECK(gk_rve_state_save(&st, &rve) == GK_OK);
        rve.v[0][17] = (gk_real)NAN;
        CHECK(gk_rve_step(&rve, 10) == GK_ERR_DIVERGED);
        CHECK(strstr(gk_rve_error(&rve), "non-finite") != NULL);
        CHECK(gk_rve_step(&rve, 10) == GK_ERR_STATE);
        {
            double dH[9] = {0, 1e-4, 0, 0, 0, 0, 0, 0, 0};
            CHECK(gk_rve_deform(&rve, dH, 10) == GK_ERR_STATE);
        }
        CHECK(gk_rve_state_restore(&st, &rve) == GK_OK);
        CHECK(gk_rve_step(&rve, 10) == GK_OK);
        CHECK(state_finite(&rve));
        gk_rve_state_free(&st);
        gk_rve_destroy(&rve);
    }
    /* forced past the check */
    {
        double e0, ke;
        gk_result r;
        def = gk_rve_def_default();
        if (load_seed(&rve, &def)) {
            CHECK(0);
            return;
        }
        gk_rve_refresh(&rve);
        e0 = contact_energy(&rve);
        rve.dt = 2.0 * gk_rve_dt_critical(&rve);
        r = gk_rve_step(&rve, QUICK(2000, 500));
        ke = gk_rve_kinetic_energy(&rve);
        printf("    dt forced to 2 dt_cr: %s, KE / E0 = %.1e\n", r == GK_OK ? "GK_OK" : gk_result_string(r),
               ke / e0);
        CHECK(r == GK_OK || r == GK_ERR_DIVERGED);
        if (r == GK_OK) CHECK(state_finite(&rve));
        gk_rve_destroy(&rve);
    }
}

/* ===================================================== 2. k_t / k_n
 * k_t / k_n from 0 to 1 (linear law, seed packing, mu = tan 0.5), simple
 * shear dH_xy = 2e-4 over 200 steps. Expected: finite stress, p unchanged
 * to 2 % (a small shear of a packing at equilibrium), shear stress
 * sigma_xy > 0 (du_x/dy > 0, tension-positive), growing with k_t/k_n (a
 * stiffer tangential spring stiffens the packing), and below the Taylor
 * bound D:dH (Guo & Zhao 2014 eq 9, affine: an upper bound on a relaxed response).
 * k_t = 0: the tangential spring never loads, so every contact force is
 * exactly normal (F = F_n n: |F_t| / |F| at rounding level), the stored
 * tangential history is exactly 0, and no torque acts (fluctuating spins
 * stay exactly 0). */
TEST(stiffness_ratio_kt_kn_0_to_1) {
    double ratios[5] = {0.0, 0.25, 0.5, 0.8, 1.0}, prev = -1.0;
    int c, k;
    for (c = 0; c < 5; ++c) {
        gk_rve rve;
        gk_rve_def def = gk_rve_def_default();
        double dH[9] = {0, 2e-4, 0, 0, 0, 0, 0, 0, 0}, s0[9], s[9], D[16], taylor, dsxy;
        def.mat.kt_ratio = ratios[c];
        if (load_seed(&rve, &def)) {
            CHECK(0);
            return;
        }
        CHECK(gk_rve_refresh(&rve) == GK_OK);
        gk_rve_stress(&rve, s0);
        CHECK(gk_homog_tangent(&rve, 0, D) == GK_OK);
        taylor = D[(0 * 2 + 1) * 4 + 0 * 2 + 1] * dH[1]; /* D_xyxy dH_xy */
        CHECK(gk_rve_deform(&rve, dH, 200) == GK_OK);
        CHECK(gk_rve_refresh(&rve) == GK_OK);
        gk_rve_stress(&rve, s);
        CHECK(state_finite(&rve));
        dsxy = s[1] - s0[1];
        printf(
            "    k_t/k_n = %.2f: d sigma_xy = %8.1f Pa (Taylor %8.1f), p = %.1f Pa, max |F_t|/|F| = %.3g\n",
            ratios[c], dsxy, taylor, gk_stress_p(s, 2), max_tangential_ratio(&rve));
        CHECK_NEAR(gk_stress_p(s, 2), gk_stress_p(s0, 2), 0.02 * gk_stress_p(s0, 2));
        CHECK(dsxy > 0.0);
        CHECK(dsxy < taylor);
        CHECK(dsxy > prev);
        prev = dsxy;
        if (ratios[c] == 0.0) {
            int nz = 0;
            CHECK(max_tangential_ratio(&rve) < 1e-12);
            for (k = 0; k < rve.pl.n; ++k) nz += rve.ft[0][k] != 0;
            for (k = 0; k < rve.n; ++k) nz += rve.w[2][k] != 0;
            CHECK_EQ_INT(nz, 0);
        } else {
            CHECK(max_tangential_ratio(&rve) > 1e-3);
        }
        gk_rve_destroy(&rve);
    }
}

/* ===================================================== 3. friction
 * mu = 0 and mu = 10 against the seed's mu = tan 0.5, simple shear to
 * gamma = 5 % in 5000 steps.
 * mu = 0: the RVE runs without tangential springs or rotation at all; every
 * contact force is normal (|F_t| / |F| at rounding level), none is marked
 * sliding; the packing is weaker (smaller q) than with friction.
 * mu = 10: the Coulomb cap is ~20x further than with mu = tan 0.5: the
 * contacts stick - fewer than 1 % of them are on the cap (measured: none;
 * a new contact with a vanishing normal force could be), against > 2 % with
 * mu = tan 0.5 (measured 5 %) - and no |F_t| / F_n reaches 10 (measured
 * 5.8: mobilised friction grows, it does not slide); the packing is stronger.
 * All finite. */
TEST(friction_0_and_10) {
    double mus[3] = {0.0, tan(0.5), 10.0}, q[3] = {0, 0, 0}, slide[3] = {0, 0, 0}, ftmax[3] = {0, 0, 0};
    int c, k;
    for (c = 0; c < 3; ++c) {
        gk_rve rve;
        gk_rve_def def = gk_rve_def_default();
        double dH[9] = {0, 5e-3, 0, 0, 0, 0, 0, 0, 0}, s[9];
        int nsl = 0, inc;
        def.mat.friction = mus[c];
        if (load_seed(&rve, &def)) {
            CHECK(0);
            return;
        }
        for (inc = 0; inc < 10; ++inc) CHECK(gk_rve_deform(&rve, dH, 500) == GK_OK);
        CHECK(gk_rve_refresh(&rve) == GK_OK);
        gk_rve_stress(&rve, s);
        CHECK(state_finite(&rve));
        for (k = 0; k < rve.pl.n; ++k) nsl += (rve.cs[k] & GK_CS_SLIDING) != 0;
        q[c] = gk_stress_q(s, 2);
        slide[c] = (double)nsl / rve.ncontacts;
        for (k = 0; k < rve.pl.n; ++k) {
            double d[3], dd, fn, ft;
            if (!(rve.cs[k] & GK_CS_CONTACT)) continue;
            dd = branch(&rve, k, d);
            fn = ((double)rve.fc[0][k] * d[0] + (double)rve.fc[1][k] * d[1]) / dd;
            ft = fabs(((double)rve.fc[1][k] * d[0] - (double)rve.fc[0][k] * d[1]) / dd);
            if (fn > 0 && ft / fn > ftmax[c]) ftmax[c] = ft / fn;
        }
        printf("    mu = %5.3f: q = %8.1f Pa, p = %8.1f Pa, %d contacts, %d sliding, max |F_t|/F_n = %.3g\n",
               mus[c], q[c], gk_stress_p(s, 2), rve.ncontacts, nsl, ftmax[c]);
        if (c == 0) {
            CHECK(rve.phys == 0u); /* no tangential spring, no rotation: nothing to pay for */
            CHECK(rve.w[2] == NULL);
            CHECK_EQ_INT(nsl, 0);
            for (k = 0; k < rve.pl.n; ++k) nsl += rve.ft[0][k] != 0; /* history stays exactly zero */
            CHECK_EQ_INT(nsl, 0);
            CHECK(max_tangential_ratio(&rve) < 1e-12);
        }
        gk_rve_destroy(&rve);
    }
    CHECK(q[0] < q[1] && q[1] < q[2]);
    CHECK(slide[1] > 0.02);
    CHECK(slide[2] < 0.01);
    CHECK(ftmax[1] <= tan(0.5) * (1 + 1e-9)); /* the cap holds */
    CHECK(ftmax[2] < 10.0);                   /* nowhere on the cap */
}

/* ===================================================== 4. size ratio
 * Radius ratio r_max / r_min = 1, 2, 5, 10 (uniform radii, 2D, generated
 * with gk_packing_generate, consolidated to 100 kPa with
 * gk_rve_consolidate). Expected: consolidation reaches sigma_xx = sigma_yy
 * = -100 kPa within its tolerance (0.2 %) and balance (unbalanced < 1e-2),
 * and the RVE stays finite through a 1 % shear; the critical step is eq 19
 * with the smallest particle's mass and the largest stiffness,
 *   dt_cr = sqrt(rho t pi r_min^2 / (E r_max))   (linear law, k_n <= E r_max),
 * so it falls as r_min (10x smaller at ratio 10 than at ratio 1 with the
 * same r_max), and the default dt is 0.5 dt_cr. The shear response at the
 * default dt equals (1 %) the one at dt = 0.25 dt_cr, at the same strain
 * rate: the default step is converged -
 * KNOWN LIMITATION (see dt_stability_limit_lattices)
 * except at ratio 1: equal frictional disks crystallise (Z up to 6), their
 * rotational mode is unstable at 0.5 dt_cr: the kinetic energy is 400x the
 * converged run's and sigma_xy 11 % high (measured with these 150 disks;
 * 130x and 1 % with 80). The CHECK on the kinetic energy documents the
 * defect; it flips when the critical step accounts for rotation. The
 * particle count is the same in the quick build for that reason. */
static double shear_1pc(gk_rve *rve, double f, double *ke_ratio) {
    double dH[9] = {0, 1e-2, 0, 0, 0, 0, 0, 0, 0}, s[9];
    CHECK(gk_rve_set_dt(rve, f * gk_rve_dt_critical(rve)) == GK_OK);
    CHECK(gk_rve_deform(rve, dH, (int)(1000.0 / f)) == GK_OK);
    CHECK(gk_rve_refresh(rve) == GK_OK);
    gk_rve_stress(rve, s);
    CHECK(state_finite(rve));
    *ke_ratio = gk_rve_kinetic_energy(rve) / contact_energy(rve);
    return s[1];
}

TEST(size_ratio_1_to_10) {
    double ratios[4] = {1.0, 2.0, 5.0, 10.0}, rmax = 0.005;
    int c, n = 150;
    for (c = 0; c < 4; ++c) {
        gk_packing pk;
        gk_rve rve;
        gk_rve_def def = gk_rve_def_default();
        gk_consolidate_def cd;
        gk_consolidate_report rep;
        gk_rve_state st;
        double rmin_pk = 1e300, rmax_pk = 0.0, mmin, sd, sr, ked, ker;
        int p, k;
        if (generate(&pk, 2, n, rmax / ratios[c], rmax, 11 + c)) {
            CHECK(0);
            return;
        }
        for (p = 0; p < pk.n; ++p) {
            if (pk.r[p] < rmin_pk) rmin_pk = pk.r[p];
            if (pk.r[p] > rmax_pk) rmax_pk = pk.r[p];
        }
        CHECK(rmax_pk / rmin_pk <= ratios[c] * (1 + 1e-12));
        CHECK(gk_rve_create(&rve, &def, &pk) == GK_OK);
        gk_packing_free(&pk);
        mmin = def.mat.density * def.thickness * GK_PI * rmin_pk * rmin_pk;
        CHECK_REL(gk_rve_dt_critical(&rve), sqrt(mmin / (def.mat.young * rmax_pk)), 1e-12);
        CHECK_REL(rve.dt, 0.5 * gk_rve_dt_critical(&rve), 1e-12);
        memset(&cd, 0, sizeof cd);
        cd.pressure = 1e5;
        cd.stress_tol = 2e-3;
        cd.unbalanced_tol = 1e-2;
        cd.damping = 0.5;
        CHECK(gk_rve_consolidate(&rve, &cd, &rep) == GK_OK);
        for (k = 0; k < 2; ++k) CHECK_NEAR(-rep.stress[4 * k], 1e5, 2e-3 * 1e5);
        CHECK(fabs(rep.stress[1]) < 2e-3 * 1e5);
        CHECK(rep.unbalanced < 1e-2);
        CHECK(rep.void_ratio > 0.0);
        CHECK(state_finite(&rve));
        gk_rve_state_init(&st, NULL);
        CHECK(gk_rve_state_save(&st, &rve) == GK_OK);
        sd = shear_1pc(&rve, 0.5, &ked);
        CHECK(gk_rve_state_restore(&st, &rve) == GK_OK);
        sr = shear_1pc(&rve, 0.25, &ker);
        printf("    r_max/r_min = %4.1f (%.2f): dt_cr = %.3e s, %6ld steps to 100 kPa, e = %.3f; 1 %% shear: "
               "sigma_xy %.0f Pa at 0.5 dt_cr (KE/E %.1e), %.0f Pa at 0.25 dt_cr (KE/E %.1e)\n",
               ratios[c], rmax_pk / rmin_pk, gk_rve_dt_critical(&rve), rep.steps, rep.void_ratio, sd, ked, sr,
               ker);
        CHECK(sd > 0.0 && sr > 0.0);
        if (ratios[c] > 1.0)
            CHECK_REL(sd, sr, 0.01);
        else
            CHECK(ked > 10.0 * ker); /* KNOWN LIMITATION, see above */
        gk_rve_state_free(&st);
        gk_rve_destroy(&rve);
    }
}

/* ===================================================== 5. confinement
 * Confining pressure from 100 MPa down to 1 Pa, decade by decade
 * (gk_rve_consolidate at each; 2D, 100 disks, radii 3-7 mm, quartz-like
 * E = 70 GPa so that 100 MPa is a physical state: with the seed's
 * E = 0.6 GPa the same pressure needs overlaps larger than the radii - the
 * consolidation then still converges, to a void ratio of -0.7, unflagged).
 * Expected at every level: the target is reached (sigma_xx, sigma_yy within
 * the 0.2 % tolerance, sigma_xy within 0.2 % of p, unbalanced < 1e-2), the
 * state is finite, and the void ratio does not decrease as p falls
 * (unloading). Overlaps: the contact forces equal the law at the current
 * geometry, p = (1/2V) sum k_n delta |d| (2D trace of the Love stress,
 * F_n = k_n delta, F_t . d = 0) to 1e-5 - at 1 Pa the overlaps are 1e-9 r
 * (3e-12 m) and must still be resolved (double branch vectors: 1.7e-18 m
 * resolution); below 100 kPa the contact network is unchanged, so the mean
 * overlap scales with p (linear law): delta_mean / p constant to 5 %; at
 * 100 MPa the mean overlap is a few % of the radius (< 10 %) and no overlap
 * reaches half a radius (no centre inside a neighbour).
 *
 * Two things the low end needs, both measured here (limitations):
 * - velocities are zeroed before each level. Local damping acts through the
 *   contact forces, so a particle without contacts (a rattler) keeps the
 *   kinetic energy it picked up at 100 MPa for ever; at 1 Pa that energy is
 *   1e7 x the elastic energy of the network, and each rattler impact
 *   knocks the network apart (consolidation then takes 1e4 to 1e6 steps,
 *   chaotically).
 * - near p/E -> 0 the frictionless packing is at jamming, its shear modulus
 *   vanishes and the servo, which sizes its steps with the Taylor
 *   stiffness, barely corrects a deviatoric error: with some packings
 *   (generator seed 2 here) 1 Pa stalls at a 1 % deviator for 2e6 steps.
 *   This seed reaches every level in 2000-7000 steps; the step cap makes a
 *   regression fail fast instead of running for minutes. */
TEST(confinement_1_Pa_to_100_MPa) {
    gk_packing pk;
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    double p, e_prev = -1.0, ratio_low = 0.0;
    int level = 0;
    if (generate(&pk, 2, 100, 0.003, 0.007, 1)) {
        CHECK(0);
        return;
    }
    def.mat.young = 7e10;
    CHECK(gk_rve_create(&rve, &def, &pk) == GK_OK);
    gk_packing_free(&pk);
    for (p = 1e8; p > 0.5; p /= 10, ++level) {
        gk_consolidate_def cd;
        gk_consolidate_report rep;
        gk_result r;
        double sum = 0.0, dmean = 0.0, dmax = 0.0, s[9], e;
        int c, nc = 0, q;
        memset(&cd, 0, sizeof cd);
        cd.pressure = p;
        cd.stress_tol = 2e-3;
        cd.unbalanced_tol = 1e-2;
        cd.damping = 0.5;
        cd.max_steps = 200000;
        for (q = 0; q < rve.n; ++q) {
            rve.v[0][q] = rve.v[1][q] = 0;
            if (rve.w[2]) rve.w[2][q] = 0;
        }
        r = gk_rve_consolidate(&rve, &cd, &rep);
        CHECK(r == GK_OK);
        if (r) {
            printf("    %s\n", gk_rve_error(&rve));
            break;
        }
        CHECK_NEAR(-rep.stress[0], p, 2e-3 * p);
        CHECK_NEAR(-rep.stress[4], p, 2e-3 * p);
        CHECK(fabs(rep.stress[1]) < 2e-3 * p);
        CHECK(rep.unbalanced < 1e-2);
        CHECK(gk_rve_refresh(&rve) == GK_OK);
        CHECK(state_finite(&rve));
        gk_rve_stress(&rve, s);
        for (c = 0; c < rve.pl.n; ++c) {
            double d[3], dd, delta, rm;
            gk_real kn, fn, kt;
            int i = rve.pl.i[c], j = rve.pl.j[c];
            if (!(rve.cs[c] & GK_CS_CONTACT)) continue;
            dd = branch(&rve, c, d);
            delta = (double)rve.r[i] + (double)rve.r[j] - dd;
            rm = rve.r[i] < rve.r[j] ? (double)rve.r[i] : (double)rve.r[j];
            gk_contact_stiffness(&rve.K, GK_LAW_LINEAR, rve.r[i], rve.r[j], (gk_real)delta, &kn, &fn, &kt);
            sum += (double)kn * delta * dd;
            dmean += delta / rm;
            if (delta / rm > dmax) dmax = delta / rm;
            ++nc;
        }
        dmean /= nc;
        e = gk_homog_void_ratio(&rve);
        printf("    p = %7.0e Pa: %6ld steps, sigma = (%.5g, %.5g, %.2g) Pa, e = %.4f, %d contacts, overlap "
               "/ r mean "
               "%.2e max %.2e\n",
               p, rep.steps, -rep.stress[0], -rep.stress[4], -rep.stress[1], e, nc, dmean, dmax);
        CHECK_REL(sum / (2.0 * gk_rve_volume(&rve)), gk_stress_p(s, 2), 1e-5);
        CHECK(e >= e_prev - 1e-6);
        e_prev = e;
        if (level == 0) {
            CHECK(dmean < 0.1 && dmax < 0.5);
            CHECK(e > 0.0);
        }
        if (p <= 1e5) {
            if (ratio_low == 0.0) ratio_low = dmean / p;
            CHECK_REL(dmean / p, ratio_low, 0.05);
        }
    }
    CHECK_EQ_INT(level, 9);
    gk_rve_destroy(&rve);
}

/* ===================================================== 6. p -> 0
 * The seed packing dilated isotropically (dH = 1e-3 I per increment of 100
 * steps) until no contact is left (free surface / liquefied state).
 * Expected on the way: p >= 0 at every increment (no cohesion: every
 * contact pushes, p = (1/2V) sum F_n |d| >= 0), p falling while the
 * network carries it (down to 1e-3 p0; below, a few particles collide and p
 * fluctuates at the Pa level), the tangent finite with D_xxxx >= 0. With no contact: every stress component exactly
 * 0, the tangent exactly 0 with and without the geometric terms
 * (gk_homog_tangent returns D = 0, never NaN and no floor: a macro solver
 * must add its own floor - femdem_biaxial adds 1e-4 x the mesh-mean
 * stiffness), fabric and unbalanced ratio 0, Z = 0, inertial number +inf.
 * Compressed back to the original cell the contacts re-form and p > 0,
 * and gk_rve_consolidate brings it back to 100 kPa within 0.2 %. */
TEST(p_to_zero_gives_zero_stress_and_recovers) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    double dH[9] = {1e-3, 0, 0, 0, 1e-3, 0, 0, 0, 0}, s[9], D[16], Dg[16], p_prev = 1e300, p0;
    int inc, k;
    if (load_seed(&rve, &def)) {
        CHECK(0);
        return;
    }
    CHECK(gk_rve_refresh(&rve) == GK_OK);
    gk_rve_stress(&rve, s);
    p0 = gk_stress_p(s, 2);
    for (inc = 0; inc < 40 && rve.ncontacts > 0; ++inc) {
        double p;
        CHECK(gk_rve_deform(&rve, dH, 100) == GK_OK);
        CHECK(gk_rve_refresh(&rve) == GK_OK);
        gk_rve_stress(&rve, s);
        p = gk_stress_p(s, 2);
        CHECK(state_finite(&rve));
        CHECK(p >= 0.0);
        if (p_prev > 1e-3 * p0) CHECK(p < p_prev); /* below: a few colliding particles, p fluctuates */
        p_prev = p;
        CHECK(gk_homog_tangent(&rve, 0, D) == GK_OK);
        CHECK(gk_homog_tangent(&rve, GK_TANGENT_GEOMETRIC, Dg) == GK_OK);
        for (k = 0; k < 16; ++k) CHECK(isfinite(D[k]) && isfinite(Dg[k]));
        CHECK(D[0] >= 0.0 && D[15] >= 0.0);
        if (inc % 4 == 0 || rve.ncontacts == 0)
            printf("    volumetric strain %.3f: p = %10.3f Pa, %3d contacts, D_xxxx = %.3e Pa\n",
                   2.0 * (inc + 1) * 1e-3, p + 0.0, rve.ncontacts, D[0]);
    }
    CHECK_EQ_INT(rve.ncontacts, 0);
    {
        gk_coordination z;
        double phi[9], um, ur, rate[9] = {1e-3, 0, 0, 0, 1e-3, 0, 0, 0, 0};
        for (k = 0; k < 9; ++k) CHECK(s[k] == 0.0);
        for (k = 0; k < 16; ++k) CHECK(D[k] == 0.0 && Dg[k] == 0.0);
        CHECK(gk_homog_fabric(&rve, phi, NULL) == 0.0);
        gk_homog_unbalanced(&rve, &um, &ur);
        CHECK(um == 0.0 && ur == 0.0);
        CHECK(gk_homog_coordination(&rve, &z) == GK_OK);
        CHECK(z.z == 0.0 && z.z_mech == 0.0);
        CHECK(isinf(gk_inertial_number(rate, 2, 0.005, 2650, gk_stress_p(s, 2))));
        CHECK(gk_rve_step(&rve, 500) == GK_OK); /* a free gas: still fine */
        CHECK(state_finite(&rve));
    }
    /* back to the original cell (constant L: exactly the inverse map) */
    {
        double back[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
        gk_consolidate_def cd;
        gk_consolidate_report rep;
        back[0] = back[4] = -1e-3 * inc;
        CHECK(gk_rve_deform(&rve, back, 100 * inc) == GK_OK);
        CHECK_NEAR(rve.cell.F[0], 1.0, 1e-12);
        CHECK(gk_rve_step(&rve, 2000) == GK_OK);
        CHECK(gk_rve_refresh(&rve) == GK_OK);
        gk_rve_stress(&rve, s);
        printf("    back at the original cell: p = %.0f Pa (p0 = %.0f), %d contacts\n", gk_stress_p(s, 2), p0,
               rve.ncontacts);
        CHECK(rve.ncontacts > 100);
        CHECK(gk_stress_p(s, 2) > 0.0 && s[0] < 0.0 && s[4] < 0.0);
        memset(&cd, 0, sizeof cd);
        cd.pressure = 1e5;
        cd.stress_tol = 2e-3;
        cd.unbalanced_tol = 1e-2;
        CHECK(gk_rve_consolidate(&rve, &cd, &rep) == GK_OK);
        CHECK_NEAR(-rep.stress[0], 1e5, 2e-3 * 1e5);
        CHECK_NEAR(-rep.stress[4], 1e5, 2e-3 * 1e5);
        CHECK(state_finite(&rve));
    }
    gk_rve_destroy(&rve);
}

/* ===================================================== 7. strain increments
 * Increments of 1e-8 to 1e-1 per DEM step (gk_rve_deform(dH, 1)).
 * Small: the one-step response is the affine one, whose exact derivative is
 * the tangent with initial-stress terms (GK_TANGENT_GEOMETRIC | RAW; the
 * seed packing's tangential history is zero, nothing slides):
 *   d sigma = D : dH + O(|dH|^2),
 * up to one more first-order term: the tangential force increments of the
 * step already accelerate the particles within that step, a non-affine
 * relaxation of relative size ~ (dt omega)^2 (measured 8.7e-3 at the
 * default 0.5 dt_cr). So: at dt = 0.01 dt_cr, |d sigma - D:dH| / |D:dH|
 * < 1e-5 for |dH| = 1e-8, 1e-7, 1e-6 (relaxation 3.5e-6; rounding: sigma ~
 * 1e5 Pa to 1e-16 against D:dH ~ 0.04 Pa at 1e-8), and the relaxation term
 * scales as dt^2: 100x smaller at 0.05 dt_cr than at 0.5 dt_cr (to 5 %).
 * The motion from the packing's own small unbalance is removed by
 * differencing with the same step at dH = 0 (saved state).
 * From 1e-5 the weakest contacts (normal force near 0) slide within the
 * step and the response leaves the tangent (measured 4e-4 at 1e-5, 7e-3 at
 * 1e-4): still within 2 % there.
 * Large (1e-3, 1e-2 in one step, shear and compression): within the
 * admissible increment per step (gk_dem.h: no overlap may change by more
 * than 0.1 of the smaller radius in one step; for this packing a stretch
 * of 0.1 x 3.0 / 10.0 = 0.030 per step) and run: the state is finite
 * afterwards and after 2000 relaxation steps. 1e-1 in one step (overlaps
 * would jump by 23 % of a radius and the packing explode) is refused, and
 * so is gamma = 1 in 10 steps; in 100 steps it runs, through a flip.
 * Increments that cannot be honoured are refused before anything moves,
 * with a code and a message, and the state is unchanged byte for byte:
 * NaN or Inf (GK_ERR_NAN), a 2D dH with a z entry, 0 steps or more than
 * the admissible increment per step (GK_ERR_ARG), and on either path an
 * inverting I + dH (GK_ERR_SINGULAR). (A compression leaving the cell
 * thinner than twice the interaction range, GK_ERR_CELL, takes several
 * admissible calls: tests/test_dem.c.) */
static double one_step_vs_tangent(gk_rve *rve, const gk_rve_state *st, double a, double dtf) {
    double D[16], shape[9] = {1.0, 0.4, 0, 0.4, -0.7, 0, 0, 0, 0}, dH[9], zero[9], s1[9], s0[9], err2 = 0.0,
                  ref2 = 0.0;
    int i, j, k;
    CHECK(gk_rve_state_restore(st, rve) == GK_OK);
    CHECK(gk_rve_set_dt(rve, dtf * gk_rve_dt_critical(rve)) == GK_OK);
    CHECK(gk_rve_refresh(rve) == GK_OK);
    CHECK(gk_homog_tangent(rve, GK_TANGENT_GEOMETRIC | GK_TANGENT_RAW, D) == GK_OK);
    for (k = 0; k < 9; ++k) {
        dH[k] = a * shape[k];
        zero[k] = 0.0;
    }
    CHECK(gk_rve_deform(rve, dH, 1) == GK_OK);
    CHECK(gk_rve_refresh(rve) == GK_OK);
    gk_rve_stress(rve, s1);
    CHECK(gk_rve_state_restore(st, rve) == GK_OK);
    CHECK(gk_rve_set_dt(rve, dtf * gk_rve_dt_critical(rve)) == GK_OK);
    CHECK(gk_rve_deform(rve, zero, 1) == GK_OK);
    CHECK(gk_rve_refresh(rve) == GK_OK);
    gk_rve_stress(rve, s0);
    for (i = 0; i < 2; ++i)
        for (j = 0; j < 2; ++j) {
            double lin = 0.0, dif;
            int kk, ll;
            for (kk = 0; kk < 2; ++kk)
                for (ll = 0; ll < 2; ++ll) lin += D[((i * 2 + j) * 2 + kk) * 2 + ll] * dH[3 * kk + ll];
            dif = (s1[3 * i + j] - s0[3 * i + j]) - lin;
            err2 += dif * dif;
            ref2 += lin * lin;
        }
    printf("    |dH| %.0e at %.2f dt_cr: |D:dH| = %.3e Pa, |d sigma - D:dH| / |D:dH| = %.2e\n", a, dtf,
           sqrt(ref2), sqrt(err2 / ref2));
    return sqrt(err2 / ref2);
}

TEST(strain_increments_1e_8_to_1e_1_per_step) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    gk_rve_state st;
    double a;
    if (load_seed(&rve, &def)) {
        CHECK(0);
        return;
    }
    gk_rve_state_init(&st, NULL);
    CHECK(gk_rve_state_save(&st, &rve) == GK_OK);
    for (a = 1e-8; a < 2e-6; a *= 10) CHECK(one_step_vs_tangent(&rve, &st, a, 0.01) < 1e-5);
    CHECK_REL(one_step_vs_tangent(&rve, &st, 1e-7, 0.5) / one_step_vs_tangent(&rve, &st, 1e-7, 0.05), 100.0,
              0.05);
    for (a = 1e-5; a < 2e-4; a *= 10) CHECK(one_step_vs_tangent(&rve, &st, a, 0.01) < 0.02);
    /* large increments, one step each */
    for (a = 1e-3; a < 0.02; a *= 10) {
        int kind;
        for (kind = 0; kind < 2; ++kind) {
            double dH[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}, ke;
            if (kind == 0)
                dH[1] = a;
            else
                dH[0] = dH[4] = -a;
            CHECK(gk_rve_state_restore(&st, &rve) == GK_OK);
            CHECK(gk_rve_deform(&rve, dH, 1) == GK_OK);
            CHECK(state_finite(&rve));
            CHECK(gk_rve_step(&rve, 2000) == GK_OK);
            CHECK(state_finite(&rve));
            ke = gk_rve_kinetic_energy(&rve);
            printf("    |dH| %.0e in one step (%s): then 2000 steps, p = %.3g Pa, KE = %.2e J, %d contacts\n",
                   a, kind ? "compression" : "shear", gk_stress_p(rve.stress, 2), ke, rve.ncontacts);
        }
    }
    {
        double dH[9] = {0, 1.0, 0, 0, 0, 0, 0, 0, 0};
        CHECK(gk_rve_state_restore(&st, &rve) == GK_OK);
        CHECK(gk_rve_deform(&rve, dH, 100) == GK_OK);
        CHECK(state_finite(&rve) && rve.cell.flips >= 1);
    }
    /* refused */
    {
        double bad[9][9] = {
            {0, 0, 0, 0, 0, 0, 0, 0, 0},       {0, 0, 0, 0, 0, 0, 0, 0, 0},   {0, 0, 0, 0, 0, 0, 0, 0, 0.1},
            {1e-3, 0, 0, 0, 0, 0, 0, 0, 0},    {-2, 0, 0, 0, 0, 0, 0, 0, 0},  {0, 0.1, 0, 0, 0, 0, 0, 0, 0},
            {-0.1, 0, 0, 0, -0.1, 0, 0, 0, 0}, {0, 1.0, 0, 0, 0, 0, 0, 0, 0}, {-1, 0, 0, 0, 0, 0, 0, 0, 0}};
        gk_result want[9] = {GK_ERR_NAN, GK_ERR_NAN, GK_ERR_ARG, GK_ERR_ARG,     GK_ERR_SINGULAR,
                             GK_ERR_ARG, GK_ERR_ARG, GK_ERR_ARG, GK_ERR_SINGULAR};
        int nst[9] = {1, 1, 1, 0, 1, 1, 1, 10, 100}, c;
        unsigned char *snap;
        size_t ns;
        bad[0][1] = NAN;
        bad[1][4] = INFINITY;
        CHECK(gk_rve_state_restore(&st, &rve) == GK_OK);
        snap = snapshot(&rve, &ns);
        for (c = 0; c < 9; ++c) {
            gk_result r;
            rve.err.msg[0] = '\0';
            if (c == 4) rve.def.path = GK_PATH_OBJECTIVE;
            r = gk_rve_deform(&rve, bad[c], nst[c]);
            rve.def.path = GK_PATH_CONSTANT_L;
            CHECK_EQ_INT(r, want[c]);
            CHECK(strlen(gk_rve_error(&rve)) > 10);
            CHECK(same_as(&rve, snap, ns));
            printf("    refused (%s): %s\n", gk_result_string(r), gk_rve_error(&rve));
        }
        free(snap);
    }
    gk_rve_state_free(&st);
    gk_rve_destroy(&rve);
}

/* ===================================================== 8. shear strain 50
 * Simple shear of the seed packing (Lees-Edwards, dH_xy) to gamma = 50 in
 * 100 increments of 0.5 (1e-3 per step; 5e-3 in the quick build). The
 * cell is re-mapped (h <- h M, gk_pcell_reduce) whenever its skew passes
 * half a period. Expected: every increment succeeds with a finite stress;
 * the accumulated map is exactly F_xy = 50; simple shear keeps the volume
 * (det h = Lx Ly to 1e-12) and the edge lengths Lx, Ly; each flip
 * subtracts exactly one period, so h_xy = 50 Ly - flips Lx and
 * |h_xy| <= (1/2 + 1e-3) Lx (the reduction's margin), i.e. flips =
 * round(50 Ly / Lx) = 50 (Ly / Lx = 0.9926); reduced positions stay in
 * [0, 1); the particles are all still there (id[] a permutation of the
 * input); contacts stay sane: 0 < Z < 6 (disks), no centre inside a
 * neighbour (overlap < the smaller radius), and p saturates: constant-
 * volume shear of this dense packing raises p eight-fold by dilatancy
 * within gamma ~ 1, then stays at that critical state - p over gamma =
 * 25..50 no more than 1.5x its value at gamma = 12.5, and below 20 p0
 * throughout. (Measured: p ~ 8e5 Pa, 1.3e6 Pa at the quick build's rate;
 * with the soft seed material (E = 0.6 GPa) at that pressure in a dense
 * flow, overlaps reach a third of a radius, 0.6 at the quick rate.) */
TEST(shear_strain_50_through_remapping) {
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    double dH[9] = {0, 0.5, 0, 0, 0, 0, 0, 0, 0}, Lx, Ly, p0, pmax = 0.0, dmax = 0.0, p12 = 0.0, plate = 0.0;
    int inc, k, nst = QUICK(500, 100), ok = 1;
    if (load_seed(&rve, &def)) {
        CHECK(0);
        return;
    }
    Lx = rve.cell.h[0];
    Ly = rve.cell.h[4];
    CHECK(gk_rve_refresh(&rve) == GK_OK);
    p0 = gk_stress_p(rve.stress, 2);
    for (inc = 0; inc < 100 && ok; ++inc) {
        gk_result r = gk_rve_deform(&rve, dH, nst);
        double p = gk_stress_p(rve.stress, 2);
        if (r != GK_OK || !state_finite(&rve)) {
            printf("    increment %d: %s\n", inc, gk_rve_error(&rve));
            ok = 0;
        }
        if (p > pmax) pmax = p;
        if (inc + 1 == 25) p12 = p;
        if (inc + 1 > 50 && p > plate) plate = p;
        if ((inc + 1) % 25 == 0)
            printf("    gamma = %4.1f: p = %.0f Pa, q = %.0f Pa, %d contacts, %ld flips\n", 0.5 * (inc + 1),
                   p, gk_stress_q(rve.stress, 2), rve.ncontacts, rve.cell.flips);
    }
    CHECK(ok);
    CHECK_NEAR(rve.cell.F[1], 50.0, 1e-9);
    CHECK_NEAR(rve.cell.F[0], 1.0, 1e-12);
    CHECK_NEAR(rve.cell.F[4], 1.0, 1e-12);
    CHECK_REL(gk_pcell_volume(&rve.cell), Lx * Ly, 1e-12);
    CHECK_REL(rve.cell.h[0], Lx, 1e-12);
    CHECK_REL(rve.cell.h[4], Ly, 1e-12);
    CHECK_EQ_INT(rve.cell.flips, (long)floor(50.0 * Ly / Lx + 0.5));
    CHECK_NEAR(rve.cell.h[1], 50.0 * Ly - (double)rve.cell.flips * Lx, 1e-9 * Lx);
    CHECK(fabs(rve.cell.h[1]) <= (0.5 + 1e-3) * Lx);
    {
        char *seen = (char *)calloc((size_t)rve.n, 1);
        int dup = 0, out = 0;
        for (k = 0; k < rve.n; ++k) {
            if (rve.id[k] < 0 || rve.id[k] >= rve.n || seen[rve.id[k]]) ++dup;
            if (rve.id[k] >= 0 && rve.id[k] < rve.n) seen[rve.id[k]] = 1;
            if (!(rve.s[0][k] >= 0.0 && rve.s[0][k] < 1.0 && rve.s[1][k] >= 0.0 && rve.s[1][k] < 1.0)) ++out;
        }
        CHECK_EQ_INT(rve.n, 400);
        CHECK_EQ_INT(dup, 0);
        CHECK_EQ_INT(out, 0);
        free(seen);
    }
    CHECK(gk_rve_refresh(&rve) == GK_OK);
    for (k = 0; k < rve.pl.n; ++k) {
        double d[3], delta;
        int i = rve.pl.i[k], j = rve.pl.j[k];
        if (!(rve.cs[k] & GK_CS_CONTACT)) continue;
        delta = (double)rve.r[i] + (double)rve.r[j] - branch(&rve, k, d);
        if (delta / (rve.r[i] < rve.r[j] ? (double)rve.r[i] : (double)rve.r[j]) > dmax)
            dmax = delta / (rve.r[i] < rve.r[j] ? (double)rve.r[i] : (double)rve.r[j]);
    }
    CHECK(rve.ncontacts > 0 && 2.0 * rve.ncontacts / rve.n < 6.0);
    CHECK(dmax < 1.0);
    CHECK(pmax < 20.0 * p0);
    CHECK(plate < 1.5 * p12);
    printf("    after gamma = 50: %ld flips, %d contacts (Z = %.2f), max overlap %.3f r, max p %.0f Pa\n",
           rve.cell.flips, rve.ncontacts, 2.0 * rve.ncontacts / rve.n, dmax, pmax);
    gk_rve_destroy(&rve);
}

/* ===================================================== 9. spin 360 degrees
 * A rigid rotation of the cell by 360 degrees in 36 increments of 10
 * degrees (dH = W dtheta, W = [[0, -1], [1, 0]]; on the constant-L path
 * E = exp(W dtheta) is an exact rotation), 100 steps each, compared with
 * the same RVE run for the same steps without spin. Objectivity: after
 * rotating by theta the stress must be R(theta) sigma_ref R(theta)^T.
 * In grainkit's kinematics the contact forces are objective step by step:
 * h <- R h keeps every overlap, the particles spin with the cell
 * (w = (G10 - G01)/2 = sin(w dt)/dt) and the contact slip
 * (G d).t - (l_i + l_j) w = sin(w dt)/dt |d| - |d| sin(w dt)/dt = 0,
 * because the lever arms l = r - delta/2 add up to |d|. What is not
 * rotated is the fluctuating velocity of each particle (the -m L v term of
 * the SLLOD equations, neglected as documented in gk_dem.h), so the error
 * is proportional to the fluctuations: after 5000 relaxing steps
 * (KE ~ 1e-12 J) it is measured at 5e-9 p to 2e-8 p - tolerance 1e-7 p at
 * every 10 degrees; straight from the seed state, whose small unbalance
 * sets particles moving (KE ~ 1e-7 J), it is 1e-6 p - checked to be more
 * than 10x the relaxed one (that is the identified cause) and below 1e-5 p.
 * Either way the cell returns to h0 (F = I to 1e-12, no flip: a rotated
 * rectangle is never skewed) and the state is finite. */
static double spin_run(long relax, double tol) {
    gk_rve a, b;
    gk_rve_def def = gk_rve_def_default();
    double W[9] = {0, -1, 0, 1, 0, 0, 0, 0, 0}, dH[9], zero[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0},
           th = 2 * GK_PI / 36, p0, maxdiff = 0.0;
    int inc, k;
    if (load_seed(&a, &def) || load_seed(&b, &def)) return 1.0;
    for (k = 0; k < 9; ++k) dH[k] = W[k] * th;
    CHECK(gk_rve_step(&a, relax) == GK_OK);
    CHECK(gk_rve_step(&b, relax) == GK_OK);
    CHECK(gk_rve_refresh(&a) == GK_OK);
    p0 = gk_stress_p(a.stress, 2);
    for (inc = 1; inc <= 36; ++inc) {
        double R[9], Rt[9], T[9], rot[9];
        CHECK(gk_rve_deform(&a, dH, 100) == GK_OK);
        CHECK(gk_rve_deform(&b, zero, 100) == GK_OK);
        CHECK(gk_rve_refresh(&a) == GK_OK);
        CHECK(gk_rve_refresh(&b) == GK_OK);
        m3_rot2(inc * th, R);
        gk_m3_transpose(R, Rt);
        gk_m3_mul(R, b.stress, T);
        gk_m3_mul(T, Rt, rot);
        for (k = 0; k < 9; ++k) {
            if (fabs(a.stress[k] - rot[k]) > maxdiff) maxdiff = fabs(a.stress[k] - rot[k]);
            CHECK_NEAR(a.stress[k], rot[k], tol * p0);
        }
    }
    CHECK(state_finite(&a));
    for (k = 0; k < 9; ++k) CHECK_NEAR(a.cell.F[k], k % 4 == 0 ? 1.0 : 0.0, 1e-12);
    for (k = 0; k < 9; ++k) CHECK_NEAR(a.cell.h[k], b.cell.h[k], 1e-12 * b.cell.h[0]);
    CHECK_EQ_INT(a.cell.flips, 0);
    printf("    %5ld relaxing steps first: after 360 degrees sigma = (%.4f, %.4f, %.4f) Pa, unrotated (%.4f, "
           "%.4f, "
           "%.4f); max |sigma - R sigma_ref R^T| = %.1e p\n",
           relax, a.stress[0], a.stress[4], a.stress[1], b.stress[0], b.stress[4], b.stress[1], maxdiff / p0);
    gk_rve_destroy(&a);
    gk_rve_destroy(&b);
    return maxdiff / p0;
}

TEST(spin_360_degrees_is_objective) {
    double relaxed = spin_run(5000, 1e-7), raw = spin_run(0, 1e-5);
    CHECK(raw > 10.0 * relaxed);
}

/* ===================================================== 10. far from the origin
 * The seed packing translated by T = (1e6 + 0.3141, -2e6 + 0.2718) m. Positions
 * are kept as reduced cell coordinates s in [0, 1) (double, also in the
 * float build), so the translation is gone once the RVE is built: without
 * GK_RVE_WRAP it is refused (GK_ERR_OUTSIDE, with a message naming the
 * flag); with it every s is in [0, 1), positions come back inside the cell,
 * and the stress equals the untranslated packing's up to the rounding of
 * the input itself: a coordinate near 2e6 m carries an error of
 * |x| 2^-53 ~ 2e-10 m, s = h^-1 x another ~2e-10 m, so with
 * e = 4 |T| eps_double every contact force moves by at most k_n 2e and
 *   |d sigma_ij| <= (1/V) sum_c k_n 2e |d_c|            (~1e-4 p here).
 * In the float build (tests/test_extremes_float.c) the branch vectors and
 * overlaps are floats: e gains 2 ulp(2 r_max) (float) and each force a
 * relative 1e-6, in both runs. (A worst case: all errors aligned. Measured
 * 6e-8 p apart in double, 5e-7 p in float, against bounds of 2.4e-4 p and
 * 7e-4 p. Absolute float coordinates at 2e6 m would have a resolution of
 * 0.25 m: no stress at all.) The translated RVE then runs a shear (1e-3
 * over 200 steps) finitely, staying in [0, 1), and ends within the same
 * bound of the untranslated run (quasi-static: the input rounding is not
 * amplified; measured 1e-6 p apart). */
TEST(far_from_origin_reduced_coordinates) {
    gk_packing pk, far;
    gk_err e;
    gk_rve a, b;
    gk_rve_def def = gk_rve_def_default();
    double T[2] = {1e6 + 0.3141, -2e6 + 0.2718}, eps, bound = 0.0, sa[9], sb[9], p0;
    double dH[9] = {0, 1e-3, 0, 0, 0, 0, 0, 0, 0};
    int k, c, out = 0;
    CHECK(gk_packing_read(RVE400, &pk, NULL, &e) == GK_OK);
    CHECK(gk_packing_read(RVE400, &far, NULL, &e) == GK_OK);
    for (k = 0; k < far.n; ++k) {
        far.x[k] += T[0];
        far.y[k] += T[1];
    }
    CHECK(gk_rve_create(&b, &def, &far) == GK_ERR_OUTSIDE);
    CHECK(strstr(gk_rve_error(&b), "GK_RVE_WRAP") != NULL);
    def.flags |= GK_RVE_WRAP;
    CHECK(gk_rve_create(&a, &def, &pk) == GK_OK);
    CHECK(gk_rve_create(&b, &def, &far) == GK_OK);
    gk_packing_free(&pk);
    gk_packing_free(&far);
    for (k = 0; k < b.n; ++k) {
        double x[3];
        gk_rve_position(&b, k, x);
        if (!(b.s[0][k] >= 0 && b.s[0][k] < 1 && b.s[1][k] >= 0 && b.s[1][k] < 1)) ++out;
        if (!(fabs(x[0]) < 1.0 && fabs(x[1]) < 1.0)) ++out;
    }
    CHECK_EQ_INT(out, 0);
    CHECK(gk_rve_refresh(&a) == GK_OK);
    CHECK(gk_rve_refresh(&b) == GK_OK);
    gk_rve_stress(&a, sa);
    gk_rve_stress(&b, sb);
    p0 = gk_stress_p(sa, 2);
    eps = 4.0 * 2e6 * DBL_EPSILON;
    if (sizeof(gk_real) == sizeof(float)) eps += 2.0 * 2.0 * a.rmax * FLT_EPSILON;
    for (c = 0; c < a.pl.n; ++c) {
        double d[3], dd;
        gk_real kn, fn, kt;
        if (!(a.cs[c] & GK_CS_CONTACT)) continue;
        dd = branch(&a, c, d);
        gk_contact_stiffness(&a.K, GK_LAW_LINEAR, a.r[a.pl.i[c]], a.r[a.pl.j[c]], 0, &kn, &fn, &kt);
        bound +=
            ((double)kn * 2.0 * eps + (sizeof(gk_real) == sizeof(float)
                                           ? 1e-6 * fabs((double)a.fc[0][c]) + 1e-6 * fabs((double)a.fc[1][c])
                                           : 0.0)) *
            dd;
    }
    bound /= gk_rve_volume(&a);
    printf("    translated vs original: sigma_xx %.6f vs %.6f Pa, sigma_xy %.6f vs %.6f Pa; bound %.3g Pa "
           "(%.1e p)\n",
           sb[0], sa[0], sb[1], sa[1], bound, bound / p0);
    for (k = 0; k < 9; ++k) CHECK_NEAR(sb[k], sa[k], bound);
#ifdef GK_REAL_FLOAT
    /* and the float build agrees with the double stress YADE reports (test_dem) */
    CHECK_NEAR(sb[0], -100028.513620, bound);
    CHECK_NEAR(sb[4], -99924.255780, bound);
#endif
    CHECK(gk_rve_deform(&a, dH, 200) == GK_OK);
    CHECK(gk_rve_deform(&b, dH, 200) == GK_OK);
    CHECK(state_finite(&b));
    for (k = 0; k < b.n; ++k)
        if (!(b.s[0][k] >= 0 && b.s[0][k] < 1 && b.s[1][k] >= 0 && b.s[1][k] < 1)) ++out;
    CHECK_EQ_INT(out, 0);
    gk_rve_stress(&a, sa);
    gk_rve_stress(&b, sb);
    printf("    after a 0.1 %% shear in 200 steps: sigma_xy %.4f vs %.4f Pa (%.1e p apart)\n", sb[1], sa[1],
           fabs(sb[1] - sa[1]) / p0);
    for (k = 0; k < 9; ++k) CHECK_NEAR(sb[k], sa[k], bound);
    gk_rve_destroy(&a);
    gk_rve_destroy(&b);
}

/* ===================================================== 11. Newton cut-back
 * A macro Newton iteration that cannot converge is cut back (increment
 * halving) rather than producing NaN. examples/femdem_biaxial (Guo & Zhao 2014
 * FEMxDEM driver; `make test` builds it first) documents: a load step not
 * converged in --max-iter iterations (or with failed RVEs) restarts from
 * the last converged state with half the increment, down to 1/16; the
 * increment regrows x2 after two converged sub-steps; if even 1/16 fails
 * it writes a checkpoint, says so and exits with status 3. One Q4 element
 * (4 RVEs of 400 disks), few DEM steps (--dem-max) to keep it fast:
 * (a) one step of 9.9 % axial strain (the option's limit is 10 %) with 6
 *     iterations allowed: measured, it fails at 9.9 % and 4.95 %,
 *     converges at 2.475 %, regrows and reaches 9.9 % in 5 sub-steps -
 *     exit 0, the target reached exactly, a cut-back message, increments
 *     below the requested one in the CSV;
 * (b) 9 % with only 2 iterations allowed: never converges (E_d stays
 *     0.06 - 0.1 at every halving) - exit 3 after the 1/16 attempt, a
 *     "giving up" message naming the checkpoint, which exists, and no
 *     converged step in the CSV.
 * In both, every field of the CSV is a finite number (no nan/inf). */
static int csv_all_finite(const char *path, int *rows, double *last_eps, double *min_inc) {
    FILE *fp = fopen(path, "r");
    char line[4096];
    int ok = fp != NULL, first = 1;
    *rows = 0;
    *last_eps = -1.0;
    *min_inc = 1e300;
    while (ok && fgets(line, sizeof line, fp)) {
        char *q = line, *end;
        int col = 0;
        if (first) { /* header */
            first = 0;
            continue;
        }
        for (;;) {
            double v = strtod(q, &end);
            if (end == q || !isfinite(v)) {
                printf("    %s: row %d column %d not a finite number: %s", path, *rows + 1, col, line);
                ok = 0;
                break;
            }
            if (col == 1) *last_eps = v;
            if (col == 9 && v > 0.0 && v < *min_inc) *min_inc = v; /* increment */
            q = end;
            while (*q == ' ') ++q;
            if (*q != ',') break;
            ++q;
            ++col;
        }
        ++*rows;
    }
    if (fp) fclose(fp);
    return ok;
}

static int text_has(const char *path, const char *needle) {
    FILE *fp = fopen(path, "r");
    char buf[4096];
    int found = 0;
    if (!fp) return 0;
    while (!found && fgets(buf, sizeof buf, fp))
        if (strstr(buf, needle)) found = 1;
    fclose(fp);
    return found;
}

TEST(newton_divergence_is_cut_back) {
    const char *exe = BUILD "/femdem_biaxial";
    const char *base = "--nx 1 --ny 1 --element q4 --steps 1 --threads 1 --vtk-every 0";
    char cmd[1024];
    int st, rows;
    double last, minc;
    FILE *fp = fopen(exe, "rb");
    if (!fp) {
        printf("    %s missing: `make test` builds the examples before the tests\n", exe);
        CHECK(0);
        return;
    }
    fclose(fp);
    /* (a) cut back, then converge */
    snprintf(cmd, sizeof cmd,
             "%s %s --increment 0.099 --max-iter 6 --dem-max 50 --out " BUILD "/tests/t_ext_cutA > " BUILD
             "/tests/t_ext_cutA.out 2>&1",
             exe, base);
    st = system(cmd);
    CHECK(st != -1 && WIFEXITED(st) && WEXITSTATUS(st) == 0);
    CHECK(text_has(BUILD "/tests/t_ext_cutA.out", "increment cut to"));
    CHECK(csv_all_finite(BUILD "/tests/t_ext_cutA/biaxial.csv", &rows, &last, &minc));
    printf(
        "    (a) 9.9 %% in one step, 6 iterations: exit %d, %d rows, reached %.4f, smallest increment %.4f\n",
        WIFEXITED(st) ? WEXITSTATUS(st) : -1, rows, last, minc);
    CHECK_NEAR(last, 0.099, 1e-12);
    CHECK(minc < 0.099 && rows > 2);
    /* (b) cut back to 1/16, then stop cleanly */
    snprintf(cmd, sizeof cmd,
             "%s %s --increment 0.09 --max-iter 2 --dem-max 500 --out " BUILD "/tests/t_ext_cutB > " BUILD
             "/tests/t_ext_cutB.out 2>&1",
             exe, base);
    st = system(cmd);
    CHECK(st != -1 && WIFEXITED(st) && WEXITSTATUS(st) == 3);
    CHECK(text_has(BUILD "/tests/t_ext_cutB.out", "increment cut to"));
    CHECK(text_has(BUILD "/tests/t_ext_cutB.out", "giving up"));
    CHECK(text_has(BUILD "/tests/t_ext_cutB.out", "checkpoint.bin"));
    fp = fopen(BUILD "/tests/t_ext_cutB/checkpoint.bin", "rb");
    CHECK(fp != NULL);
    if (fp) fclose(fp);
    CHECK(csv_all_finite(BUILD "/tests/t_ext_cutB/biaxial.csv", &rows, &last, &minc));
    printf("    (b) 9 %% in one step, 2 iterations: exit %d, %d rows, reached %.4f\n",
           WIFEXITED(st) ? WEXITSTATUS(st) : -1, rows, last);
    CHECK(last < 0.09);
}

/* The float build (tests/test_extremes_float.c) runs the extremes where
 * float differs - positions stay double in reduced coordinates; velocities,
 * forces and radii are float - and skips those whose checks are set at
 * double precision (1e-12 identities, 1e-7 p objectivity, ...). */
#ifdef GK_REAL_FLOAT
#define RUN_DOUBLE(name) (void)name
#else
#define RUN_DOUBLE(name) RUN(name)
#endif

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN_DOUBLE(dt_0_1_to_0_95_critical_seed_packing);
    RUN_DOUBLE(dt_stability_limit_lattices);
    RUN_DOUBLE(dt_beyond_critical_is_refused_or_reported);
    RUN_DOUBLE(stiffness_ratio_kt_kn_0_to_1);
    RUN_DOUBLE(friction_0_and_10);
    RUN_DOUBLE(size_ratio_1_to_10);
    RUN_DOUBLE(confinement_1_Pa_to_100_MPa);
    RUN(p_to_zero_gives_zero_stress_and_recovers);
    RUN_DOUBLE(strain_increments_1e_8_to_1e_1_per_step);
    RUN(shear_strain_50_through_remapping);
    RUN_DOUBLE(spin_360_degrees_is_objective);
    RUN(far_from_origin_reduced_coordinates);
    RUN_DOUBLE(newton_divergence_is_cut_back);
    return gk_test_done();
}
