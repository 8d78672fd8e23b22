/* test_scene.c - DEM beyond the periodic cell (gk_scene.h): the eight
 * particle-level benchmarks of Chung & Ooi (2011), walls and their servo,
 * gravity, prescribed particles, the membrane, insertion and deletion, the
 * energy balance, save/restore and thread invariance, packing tiles and
 * subsets, and smoke runs of the two scene drivers (build/dem_biaxial,
 * build/dem_collapse: `make test` builds the examples first). */
#define GK_DEM_PAR_MIN 64   /* let small scenes use threads, to test thread invariance */
#define GK_DEM_GATHER_MAX 0 /* one thread scatters: its thread tests compare that with the threads' gather */
#define GK_IMPLEMENTATION
#define GK_TEST_DRIVERS
#include "gk_scene.h"
#include "gk_test.h"
#include <stdlib.h>
#include <sys/wait.h>

#ifdef GK_TEST_QUICK /* sanitizer builds: fewer steps */
#define QUICK(full, quick) (quick)
#else
#define QUICK(full, quick) (full)
#endif

/* ================================================================ impacts
 * Chung, Y. C. & Ooi, J. Y. (2011), Benchmark tests for verifying discrete
 * element modelling codes at particle impact level, Granular Matter 13,
 * 643-656. Materials (their Table 1 as used by the public YADE scripts of
 * these tests): glass E 4.8e10 Pa, nu 0.20, rho 2800; limestone 2.0e10,
 * 0.25, 2500; aluminium alloy 7.0e10, 0.30 (0.33 in the oblique tests),
 * 2700; magnesium alloy 4.0e10, 0.35, 1800; aluminium oxide 3.8e11, 0.23,
 * 4000; cast iron 1.0e11, 0.25, 7000; nylon 2.5e9, 0.40, 1000. Spheres are
 * solid (I = 2/5 m R^2, chi = 1 + m R^2 / I = 7/2). Walls are rigid.
 *
 * Hertz theory (Johnson 1985, sec 11.1) for a normal impact at approach
 * speed v of bodies with effective modulus E*, radius R*, mass m*:
 *   F = 4/3 E* sqrt(R*) delta^(3/2)
 *   delta_max = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5)
 *   t_c = 2 (delta_max / v) int_0^1 (1 - x^(5/2))^(-1/2) dx
 *       = (4/5) sqrt(pi) Gamma(2/5) / Gamma(9/10) delta_max / v
 *       = 2.868 (m*^2 / (R* E*^2 v))^(1/5).
 * Oblique impacts (Maw, Barber & Fawcett 1976; Chung & Ooi sec 3.4-3.8):
 * with the contact point's tangential velocity v_c and normal speed v_n,
 * in gross sliding (the contact slides all through the impact) the
 * tangential impulse is mu times the normal one, so
 *   v_t' = v_t - mu (1 + e) v_n,  omega' = omega - (5/2) mu (1 + e) v_n / R,
 *   v_c' = v_c - chi mu (1 + e) v_n,
 * which holds when tan(theta) = v_c / v_n >= chi mu (1 + e) (the contact
 * point does not reverse). When the tangential and normal contact
 * oscillations have the same period (k_t / k_n = 1 / chi for a linear
 * spring, Maw et al.'s limit), a contact that starts stuck (k_t v_c <=
 * mu k_n v_n) stays stuck and its tangential velocity is exactly reversed:
 * v_c' = -v_c (the normalised recoil angle Psi2 = -Psi1). */
typedef struct mat_t {
    const char *name;
    double E, nu, rho;
} mat_t;
static const mat_t GLASS = {"glass", 4.8e10, 0.20, 2800}, LIMESTONE = {"limestone", 2.0e10, 0.25, 2500},
                   AL_ALLOY = {"Al alloy", 7.0e10, 0.30, 2700}, MG_ALLOY = {"Mg alloy", 4.0e10, 0.35, 1800},
                   AL_OXIDE = {"Al oxide", 3.8e11, 0.23, 4000}, CAST_IRON = {"cast iron", 1.0e11, 0.25, 7000},
                   AL_ALLOY_O = {"Al alloy", 7.0e10, 0.33, 2700}, NYLON = {"nylon", 2.5e9, 0.40, 1000};

static gk_material hertz_mat(const mat_t *m, double mu) {
    gk_material g = gk_material_default();
    g.law = GK_LAW_HERTZ;
    g.young = m->E;
    g.poisson = m->nu;
    g.density = m->rho;
    g.friction = mu;
    return g;
}

/* Hertz impact: contact modulus of two bodies (b NULL: rigid) */
static double estar(const mat_t *a, const mat_t *b) {
    return 1.0 / ((1.0 - a->nu * a->nu) / a->E + (b ? (1.0 - b->nu * b->nu) / b->E : 0.0));
}
static double hertz_dmax(double ms, double Rs, double Es, double v) {
    return pow(15.0 * ms * v * v / (16.0 * Es * sqrt(Rs)), 0.4);
}
static double hertz_tc(double ms, double Rs, double Es, double v) {
    return 0.8 * sqrt(GK_PI) * tgamma(0.4) / tgamma(0.9) * hertz_dmax(ms, Rs, Es, v) / v;
}
static double sphere_mass(double rho, double R) { return rho * 4.0 / 3.0 * GK_PI * R * R * R; }

/* a scene of n spheres in an open cube [-L, L]^3 with the given material and dt */
static int impact_scene(gk_scene *sc, int n, double (*x)[3], const double *r, const gk_material *m, double dt,
                        double L) {
    gk_scene_def d = gk_scene_def_default();
    gk_packing pk;
    gk_err e;
    int p, k;
    d.dim = 3;
    for (k = 0; k < 3; ++k) {
        d.lo[k] = -L;
        d.hi[k] = L;
    }
    d.rve.mat = *m;
    d.rve.dt = dt;
    if (gk_packing_init(&pk, 3, n, NULL, &e)) return 1;
    for (p = 0; p < n; ++p) {
        pk.x[p] = x[p][0];
        pk.y[p] = x[p][1];
        pk.z[p] = x[p][2];
        pk.r[p] = r[p];
    }
    if (gk_scene_create(sc, &d, &pk)) {
        printf("    create: %s\n", gk_scene_error(sc));
        gk_packing_free(&pk);
        return 1;
    }
    gk_packing_free(&pk);
    return 0;
}

/* step until contact has come and gone; records the largest contact force
 * on particle p (norm of rve.f), the largest overlap (from the positions the
 * force was computed at) and the contact duration */
typedef struct impact_rec {
    double fmax, dmax, tc;
    long steps;
} impact_rec;
static int run_impact(gk_scene *sc, int p, int q_or_wall, impact_rec *o, long maxsteps) {
    int started = 0, k;
    long st, ncont = 0;
    o->fmax = o->dmax = o->tc = 0.0;
    for (st = 0; st < maxsteps; ++st) {
        double xp[3], xq[3], d2 = 0.0, f2 = 0.0, delta;
        gk_scene_position(sc, p, xp);
        if (q_or_wall >= 0) {
            gk_scene_position(sc, q_or_wall, xq);
            for (k = 0; k < 3; ++k) d2 += (xp[k] - xq[k]) * (xp[k] - xq[k]);
            delta = (double)(sc->rve.r[p] + sc->rve.r[q_or_wall]) - sqrt(d2);
        } else { /* plane y = wall position */
            delta = (double)sc->rve.r[p] - (xp[1] - sc->walls[0].pos[1]);
        }
        if (gk_scene_step(sc, 1)) {
            printf("    step: %s\n", gk_scene_error(sc));
            return 1;
        }
        for (k = 0; k < 3; ++k) f2 += (double)sc->rve.f[k][p] * (double)sc->rve.f[k][p];
        if (f2 > 0.0) {
            started = 1;
            ++ncont;
            if (sqrt(f2) > o->fmax) o->fmax = sqrt(f2);
            if (delta > o->dmax) o->dmax = delta;
        } else if (started) {
            break;
        }
    }
    o->tc = (double)ncont * sc->rve.dt;
    o->steps = st;
    return !started || st == maxsteps;
}

/* Test 1: elastic normal impact of two identical spheres (R = 0.01 m, each
 * at 10 m/s): peak force, peak overlap and duration against Hertz, and the
 * force-overlap curve F = 4/3 E* sqrt(R*) delta^(3/2) at every step. */
TEST(chung_ooi_1_two_spheres_normal) {
    const mat_t *ms[2] = {&GLASS, &LIMESTONE};
    int t;
    for (t = 0; t < 2; ++t) {
        double R = 0.01, v = 10.0, x[2][3] = {{-R - 1e-5, 0, 0}, {R + 1e-5, 0, 0}}, r[2] = {R, R};
        double m = sphere_mass(ms[t]->rho, R), Es = estar(ms[t], ms[t]), Rs = 0.5 * R, mst = 0.5 * m;
        double tc = hertz_tc(mst, Rs, Es, 2 * v), dm = hertz_dmax(mst, Rs, Es, 2 * v);
        double fm = 4.0 / 3.0 * Es * sqrt(Rs) * pow(dm, 1.5), vel[3] = {v, 0, 0}, vel2[3] = {-v, 0, 0};
        gk_material mat = hertz_mat(ms[t], 0.35);
        gk_scene sc;
        impact_rec o;
        if (impact_scene(&sc, 2, x, r, &mat, tc / 1000.0, 0.05)) {
            CHECK(0);
            continue;
        }
        gk_scene_set_velocity(&sc, gk_scene_index(&sc, 0), vel, NULL);
        gk_scene_set_velocity(&sc, gk_scene_index(&sc, 1), vel2, NULL);
        CHECK(run_impact(&sc, gk_scene_index(&sc, 0), gk_scene_index(&sc, 1), &o, 100000) == 0);
        printf("    %-9s F_max %.6g N (Hertz %.6g), delta_max %.6g m (%.6g), t_c %.6g s (%.6g)\n",
               ms[t]->name, o.fmax, fm, o.dmax, dm, o.tc, tc);
        CHECK_REL(o.fmax, fm, 2e-3);
        CHECK_REL(o.dmax, dm, 2e-3);
        CHECK_REL(o.tc, tc, 2e-3);
        /* elastic: both rebound at 10 m/s */
        CHECK_REL(-sc.rve.v[0][gk_scene_index(&sc, 0)], v, 1e-4);
        CHECK_REL(sc.rve.v[0][gk_scene_index(&sc, 1)], v, 1e-4);
        gk_scene_destroy(&sc);
    }
}

/* a sphere of radius R above the rigid plane y = 0 (wall material: the
 * sphere's against a rigid body), moving at v, spinning at w */
static int sphere_on_plane(gk_scene *sc, const gk_material *m, double R, const double v[3], const double w[3],
                           double dt) {
    double x[1][3] = {{0, 0, 0}}, r[1];
    gk_wall_def wd = gk_wall_def_default();
    gk_err e;
    x[0][1] = R * (1.0 + 1e-4);
    r[0] = R;
    if (impact_scene(sc, 1, x, r, m, dt, 10 * R)) return 1;
    wd.normal[1] = 1.0;
    if (gk_scene_pair_material(m, NULL, &wd.mat, &e)) {
        printf("    pair material: %s\n", e.msg);
        return 1;
    }
    if (gk_scene_add_wall(sc, &wd, NULL) || gk_scene_set_velocity(sc, 0, v, w)) {
        printf("    wall: %s\n", gk_scene_error(sc));
        return 1;
    }
    return 0;
}

/* Test 2: elastic normal impact of a sphere (R = 0.1 m, 0.2 m/s) on a rigid
 * plane: Hertz with R* = R, m* = m, E* = E / (1 - nu^2); the wall reports
 * the force the sphere exerts (equal and opposite). */
TEST(chung_ooi_2_sphere_on_wall_normal) {
    const mat_t *ms[2] = {&AL_ALLOY, &MG_ALLOY};
    int t;
    for (t = 0; t < 2; ++t) {
        double R = 0.1, v = 0.2, m = sphere_mass(ms[t]->rho, R), Es = estar(ms[t], NULL);
        double tc = hertz_tc(m, R, Es, v), dm = hertz_dmax(m, R, Es, v),
               fm = 4.0 / 3.0 * Es * sqrt(R) * pow(dm, 1.5);
        double vel[3] = {0, -0.2, 0}, fwall = 0.0;
        gk_material mat = hertz_mat(ms[t], 0.0);
        gk_scene sc;
        impact_rec o;
        long st;
        if (sphere_on_plane(&sc, &mat, R, vel, NULL, tc / 1000.0)) {
            CHECK(0);
            continue;
        }
        CHECK(run_impact(&sc, 0, -1, &o, 100000) == 0);
        printf("    %-9s F_max %.6g N (Hertz %.6g), delta_max %.6g m (%.6g), t_c %.6g s (%.6g)\n",
               ms[t]->name, o.fmax, fm, o.dmax, dm, o.tc, tc);
        CHECK_REL(o.fmax, fm, 2e-3);
        CHECK_REL(o.dmax, dm, 2e-3);
        CHECK_REL(o.tc, tc, 2e-3);
        CHECK_REL(sc.rve.v[1][0], v, 1e-4);
        gk_scene_destroy(&sc);
        /* the wall's reaction, step by step, is minus the sphere's contact force */
        if (sphere_on_plane(&sc, &mat, R, vel, NULL, tc / 1000.0)) continue;
        for (st = 0; st < 3000; ++st) {
            gk_scene_step(&sc, 1);
            if (fabs(sc.walls[0].force[1] + (double)sc.rve.f[1][0]) > 1e-9 * fm) fwall = 1.0;
        }
        CHECK(fwall == 0.0);
        gk_scene_destroy(&sc);
    }
}

/* restitution of a sphere dropped on the wall at v (normal), measured as the
 * rebound speed over v */
static double restitution(const gk_material *m, double R, double v, double dt) {
    gk_scene sc;
    impact_rec o;
    double vel[3] = {0, 0, 0}, e;
    vel[1] = -v;
    if (sphere_on_plane(&sc, m, R, vel, NULL, dt)) return -1.0;
    if (run_impact(&sc, 0, -1, &o, 1000000))
        e = -1.0;
    else
        e = (double)sc.rve.v[1][0] / v;
    gk_scene_destroy(&sc);
    return e;
}

/* restitution of the Hertz spring with gk_contact.h's dashpot g = 2 zeta
 * sqrt(m k_n(delta)): scaled by delta_0 = (m v^2 / K)^(2/5) and delta_0 / v
 * the impact is x'' = -x^(3/2) - 2 zeta sqrt(3/2) x^(1/4) x', x(0) = 0,
 * x'(0) = 1, whatever v (so e does not depend on the speed); e = -x' when x
 * returns to 0. RK4 with 2e5 steps of the scaled time. */
static double hertz_dashpot_e(double zeta) {
    double c = 2.0 * zeta * sqrt(1.5), x = 0.0, u = 1.0, h = 1e-5;
    int it;
    for (it = 0; it < 10000000; ++it) {
#define GK_T_ACC(X, U) (-pow((X) > 0 ? (X) : 0, 1.5) - c * pow((X) > 0 ? (X) : 0, 0.25) * (U))
        double k1x = u, k1u = GK_T_ACC(x, u);
        double k2x = u + 0.5 * h * k1u, k2u = GK_T_ACC(x + 0.5 * h * k1x, u + 0.5 * h * k1u);
        double k3x = u + 0.5 * h * k2u, k3u = GK_T_ACC(x + 0.5 * h * k2x, u + 0.5 * h * k2u);
        double k4x = u + h * k3u, k4u = GK_T_ACC(x + h * k3x, u + h * k3u);
#undef GK_T_ACC
        double xn = x + h / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x),
               un = u + h / 6.0 * (k1u + 2 * k2u + 2 * k3u + k4u);
        if (it > 10 && xn <= 0.0) return -(u + (un - u) * x / (x - xn)); /* interpolate the crossing */
        x = xn;
        u = un;
    }
    return -1.0;
}

/* Test 3: normal impact with damping. Linear spring-dashpot: the measured
 * restitution equals the requested one, e = exp(-pi zeta / sqrt(1 -
 * zeta^2)) (zeta from gk_restitution_to_zeta); Hertz with gk_contact.h's
 * dashpot: e is the same at 0.39, 3.9 and 39 m/s and equals the solution
 * of the scaled damped Hertz equation (hertz_dashpot_e). Aluminium oxide and
 * cast iron, R = 2.5 mm, 3.9 m/s. */
TEST(chung_ooi_3_restitution) {
    const mat_t *ms[2] = {&AL_OXIDE, &CAST_IRON};
    const double es[5] = {0.2, 0.4, 0.6, 0.8, 1.0};
    int t, i;
    for (t = 0; t < 2; ++t) {
        double R = 2.5e-3, m = sphere_mass(ms[t]->rho, R), Es = estar(ms[t], NULL),
               tc = hertz_tc(m, R, Es, 3.9);
        for (i = 0; i < 5; ++i) {
            gk_material lin = gk_material_default();
            double e, kn = 4.0 * ms[t]->E * R; /* the wall's linear k_n = E x 2 R* with the pair's 2 E */
            lin.friction = 0.0;
            lin.young = ms[t]->E;
            lin.density = ms[t]->rho;
            lin.zeta_n = gk_restitution_to_zeta(es[i]);
            e = restitution(&lin, R, 3.9, GK_PI * sqrt(m / kn) / 1000.0);
            printf("    %-9s linear: requested e %.2f, measured %.5f\n", ms[t]->name, es[i], e);
            CHECK_NEAR(e, es[i], 2e-3);
        }
        {
            gk_material hz = hertz_mat(ms[t], 0.0);
            double e0, e1, e2, em;
            hz.zeta_n = 0.2;
            e0 = restitution(&hz, R, 0.39, hertz_tc(m, R, Es, 0.39) / 1000.0);
            e1 = restitution(&hz, R, 3.9, tc / 1000.0);
            e2 = restitution(&hz, R, 39.0, hertz_tc(m, R, Es, 39.0) / 1000.0);
            em = hertz_dashpot_e(0.2);
            printf("    %-9s Hertz, zeta 0.2: e = %.5f, %.5f, %.5f at 0.39, 3.9, 39 m/s; model %.5f\n",
                   ms[t]->name, e0, e1, e2, em);
            CHECK_NEAR(e0, em, 2e-3);
            CHECK_NEAR(e1, em, 2e-3);
            CHECK_NEAR(e2, em, 2e-3);
        }
    }
}

/* one oblique impact on the plane: rebound velocity and spin */
static int oblique(const gk_material *m, double R, const double v[3], const double w[3], double dt,
                   double vout[3], double wout[3]) {
    gk_scene sc;
    impact_rec o;
    int k, bad;
    if (sphere_on_plane(&sc, m, R, v, w, dt)) return 1;
    bad = run_impact(&sc, 0, -1, &o, 2000000);
    for (k = 0; k < 3; ++k) {
        vout[k] = (double)sc.rve.v[k][0];
        wout[k] = (double)sc.rve.w[k][0];
    }
    gk_scene_destroy(&sc);
    return bad;
}

/* Test 4: oblique impacts at 3.9 m/s and incidence 5-85 degrees (from the
 * normal) of an aluminium oxide sphere (R = 2.5 mm, mu = 0.092, elastic).
 * Gross sliding for tan(theta) >= 2 chi mu (theta >= 32.8 deg): tangential
 * restitution e_t = 1 - 2 mu / tan(theta), spin -5 mu v_n / R (Chung & Ooi
 * eqs for test 4). Every angle: angular momentum about the contact point,
 * I w_z - m R v_x, is conserved (the contact force acts there) and the
 * kinetic energy does not grow (elastic contact, passive friction). The
 * impulse theory takes the lever arm as R; the law's is R - delta/2, so
 * it holds to delta_max / R (here 2e-3). */
TEST(chung_ooi_4_oblique_constant_speed) {
    const double ang[7] = {5, 15, 30, 40, 50, 65, 85};
    double R = 2.5e-3, mu = 0.092, V = 3.9, m = sphere_mass(AL_OXIDE.rho, R), I = 0.4 * m * R * R;
    double dt = hertz_tc(m, R, estar(&AL_OXIDE, NULL), V) / 1000.0;
    gk_material mat = hertz_mat(&AL_OXIDE, mu);
    int a;
    for (a = 0; a < 7; ++a) {
        double th = ang[a] * GK_PI / 180.0, vn = V * cos(th), vt = V * sin(th), v[3], vo[3], wo[3], et, L0,
               L1;
        v[0] = vt;
        v[1] = -vn;
        v[2] = 0.0;
        CHECK(oblique(&mat, R, v, NULL, dt, vo, wo) == 0);
        et = vo[0] / vt;
        L0 = -m * R * vt;
        L1 = I * wo[2] - m * R * vo[0];
        printf("    theta %4.1f: e_t %.4f, omega %9.3f rad/s, rebound angle %6.2f deg, contact point %+.4f "
               "m/s\n",
               ang[a], et, wo[2], atan2(vo[0], vo[1]) * 180.0 / GK_PI, vo[0] + R * wo[2]);
        CHECK_NEAR(L1, L0, 2e-3 * fabs(L0));
        CHECK_NEAR(vo[1], vn, 1e-3 * vn);
        CHECK(0.5 * m * (vo[0] * vo[0] + vo[1] * vo[1]) + 0.5 * I * wo[2] * wo[2] <=
              0.5 * m * V * V * (1.0 + 1e-6));
        if (tan(th) >= 7.0 * mu * 1.01) {
            CHECK_NEAR(et, 1.0 - 2.0 * mu / tan(th), 2e-3);
            CHECK_NEAR(wo[2], -5.0 * mu * vn / R, 2e-3 * 5.0 * mu * vn / R);
        }
    }
}

/* gk_scene_lock_rotation: test 4's sphere that cannot turn. Its moment of
 * inertia is in effect infinite, chi = 1 + m R^2 / I = 1, so it slides
 * throughout the impact from tan(theta) >= 2 chi mu on (theta >= 10.4 deg,
 * where the free sphere still sticks), with Chung & Ooi's gross-sliding
 * result e_t = 1 - 2 mu / tan(theta) and no spin at all (w = 0 exactly at
 * every step). A prescribed spin overrides the lock; the lock survives a
 * save and restore; bad arguments and a damaged flag are refused. */
static unsigned char *state_of(const gk_scene *sc, size_t *n);
TEST(locked_rotation_slides_without_turning) {
    const double ang[3] = {15, 30, 50};
    double R = 2.5e-3, mu = 0.092, V = 3.9, m = sphere_mass(AL_OXIDE.rho, R);
    double dt = hertz_tc(m, R, estar(&AL_OXIDE, NULL), V) / 1000.0;
    gk_material mat = hertz_mat(&AL_OXIDE, mu);
    int a, k;
    for (a = 0; a < 3; ++a) {
        double th = ang[a] * GK_PI / 180.0, vn = V * cos(th), vt = V * sin(th), v[3] = {0, 0, 0}, wmax = 0.0,
               free_et = 0.0;
        gk_scene sc;
        long st;
        int pass;
        v[0] = vt, v[1] = -vn;
        for (pass = 0; pass < 2; ++pass) { /* 0: free, 1: locked */
            int started = 0;
            if (sphere_on_plane(&sc, &mat, R, v, NULL, dt)) {
                CHECK(0);
                return;
            }
            if (pass) CHECK(gk_scene_lock_rotation(&sc, 0, 1) == GK_OK && sc.nlocked == 1);
            for (st = 0; st < 2000000; ++st) {
                double f;
                CHECK(gk_scene_step(&sc, 1) == GK_OK);
                if (pass)
                    for (k = 0; k < 3; ++k)
                        if (fabs((double)sc.rve.w[k][0]) > wmax) wmax = fabs((double)sc.rve.w[k][0]);
                f = fabs((double)sc.rve.f[1][0]);
                if (f > 0.0)
                    started = 1;
                else if (started)
                    break;
            }
            if (!pass) {
                free_et = (double)sc.rve.v[0][0] / vt;
                gk_scene_destroy(&sc);
            }
        }
        printf("    theta %4.1f: locked e_t %.4f (1 - 2 mu / tan theta = %.4f; free %.4f), |w| max %g\n",
               ang[a], (double)sc.rve.v[0][0] / vt, 1.0 - 2.0 * mu / tan(th), free_et, wmax);
        CHECK(wmax == 0.0);
        CHECK_NEAR((double)sc.rve.v[0][0] / vt, 1.0 - 2.0 * mu / tan(th), 2e-3);
        CHECK_NEAR((double)sc.rve.v[1][0], vn, 1e-3 * vn);
        if (a == 0) CHECK(free_et - (1.0 - 2.0 * mu / tan(th)) > 0.05); /* the free sphere rolls part of it */
        if (a == 0) {
            double w5[3] = {0, 0, 5}, zero[3] = {0, 0, 0};
            unsigned char *s0, *s1;
            size_t n0, n1, i, at = 0, ndiff = 0;
            gk_scene B;
            /* the lock survives save and restore; its byte is the only difference from an unlocked state */
            s1 = state_of(&sc, &n1);
            CHECK(gk_scene_lock_rotation(&sc, 0, 0) == GK_OK && sc.nlocked == 0);
            s0 = state_of(&sc, &n0);
            CHECK(s0 && s1 && n0 == n1);
            for (i = 0; s0 && s1 && i < n0 && n0 == n1; ++i)
                if (s0[i] != s1[i]) at = i, ++ndiff;
            CHECK(ndiff == 1);
            CHECK(sphere_on_plane(&B, &mat, R, v, NULL, dt) == 0);
            CHECK(gk_scene_restore(&B, s1, n1) == GK_OK && B.nlocked == 1 &&
                  (B.flags[0] & GK_PARTICLE_LOCKED_ROTATION));
            if (s1 && ndiff == 1) {
                s1[at] = 0x80; /* no such flag */
                CHECK(gk_scene_restore(&B, s1, n1) == GK_ERR_FORMAT);
                printf("    %s\n", gk_scene_error(&B));
            }
            gk_scene_destroy(&B);
            free(s0), free(s1);
            /* bad arguments change nothing */
            CHECK(gk_scene_lock_rotation(&sc, 0, 1) == GK_OK);
            CHECK(gk_scene_lock_rotation(&sc, 1, 1) == GK_ERR_ARG);
            CHECK(gk_scene_lock_rotation(&sc, 0, 2) == GK_ERR_ARG);
            CHECK(sc.nlocked == 1 && sc.flags[0] == GK_PARTICLE_LOCKED_ROTATION);
            /* a prescribed spin overrides the lock; released, the lock holds the spin at zero again */
            CHECK(gk_scene_prescribe(&sc, 0, zero, w5) == GK_OK && gk_scene_step(&sc, 3) == GK_OK);
            CHECK((double)sc.rve.w[2][0] == 5.0);
            CHECK(gk_scene_release(&sc, 0) == GK_OK && gk_scene_step(&sc, 1) == GK_OK);
            CHECK((double)sc.rve.w[2][0] == 0.0);
        }
        gk_scene_destroy(&sc);
    }
}

/* Test 5: constant normal speed 5 m/s, tangential speed varied (aluminium
 * alloy and nylon, R = 0.1 m, mu = 0.4), in Maw et al.'s normalised
 * angles Psi1 = kappa v_c / (mu v_n), Psi2 = kappa v_c' / (mu v_n), kappa =
 * k_t / k_n = 2 (1 - nu) / (2 - nu) for Hertz-Mindlin: gross sliding Psi2
 * = Psi1 - 2 kappa chi and R w' / (mu v_n) = -5 for Psi1 >= 2 kappa chi,
 * to delta_max / R (the lever arm, see test 4: nylon 1.6 %); at every
 * Psi1 |Psi2| <= Psi1 (kinetic energy cannot grow while the angular
 * momentum about the contact point is kept). And Maw et al.'s
 * equal-period limit with a linear spring (k_t / k_n = 1 / chi): Psi2 =
 * -Psi1 exactly while Psi1 <= 1. */
TEST(chung_ooi_5_oblique_constant_normal_speed) {
    const mat_t *ms[2] = {&AL_ALLOY_O, &NYLON};
    const double psi[6] = {0.3, 0.7, 2.0, 8.0, 12.0, 20.0};
    double R = 0.1, mu = 0.4, vn = 5.0;
    int t, i;
    for (t = 0; t < 2; ++t) {
        double m = sphere_mass(ms[t]->rho, R), kap = 2.0 * (1.0 - ms[t]->nu) / (2.0 - ms[t]->nu);
        double dt = hertz_tc(m, R, estar(ms[t], NULL), vn) / 1000.0;
        double tol = hertz_dmax(m, R, estar(ms[t], NULL), vn) / R + 2e-3;
        gk_material mat = hertz_mat(ms[t], mu);
        for (i = 0; i < 6; ++i) {
            double v[3], vo[3], wo[3], p2, sp;
            v[0] = psi[i] * mu * vn / kap;
            v[1] = -vn;
            v[2] = 0.0;
            CHECK(oblique(&mat, R, v, NULL, dt, vo, wo) == 0);
            p2 = kap * (vo[0] + R * wo[2]) / (mu * vn);
            sp = R * wo[2] / (mu * vn);
            printf("    %-9s Psi1 %5.2f: Psi2 %+8.4f, R w'/(mu v_n) %+.4f\n", ms[t]->name, psi[i], p2, sp);
            CHECK(fabs(p2) <= psi[i] * (1.0 + 1e-3));
            if (psi[i] >= 2.0 * kap * 3.5 * 1.01) {
                CHECK_NEAR(p2, psi[i] - 7.0 * kap, tol * 7.0 * kap);
                CHECK_NEAR(sp, -5.0, tol * 5.0);
            }
        }
    }
    { /* the equal-period linear spring: exact reversal while stuck */
        gk_material lin = gk_material_default();
        double m = sphere_mass(AL_ALLOY_O.rho, R), kn = 4.0 * AL_ALLOY_O.E * R;
        lin.young = AL_ALLOY_O.E;
        lin.kt_ratio = 2.0 / 7.0;
        lin.friction = mu;
        lin.density = AL_ALLOY_O.rho;
        for (i = 0; i < 2; ++i) {
            double v[3], vo[3], wo[3], p2, kap = 2.0 / 7.0;
            v[0] = psi[i] * mu * vn / kap;
            v[1] = -vn;
            v[2] = 0.0;
            CHECK(oblique(&lin, R, v, NULL, GK_PI * sqrt(m / kn) / 2000.0, vo, wo) == 0);
            p2 = kap * (vo[0] + R * wo[2]) / (mu * vn);
            printf("    linear k_t/k_n = 2/7, Psi1 %.2f: Psi2 %+.5f (exact %+.2f)\n", psi[i], p2, -psi[i]);
            CHECK_NEAR(p2, -psi[i], 3e-3 * psi[i]);
        }
    }
}

/* Test 6: normal speed 0.2 m/s and an initial spin of 0.175 to 21 rad/s
 * (aluminium alloy and nylon, R = 0.1 m, mu = 0.4). Gross sliding (R w0 >=
 * 2 chi mu v_n): v_x' = -2 mu v_n sign(w0), w' = w0 - 5 mu v_n / R sign(w0);
 * every spin: I w_z - m R v_x conserved; the equal-period linear spring
 * reverses the contact point exactly when stuck (R w0 <= mu v_n / kappa). */
TEST(chung_ooi_6_spinning_sphere_on_wall) {
    const mat_t *ms[2] = {&AL_ALLOY_O, &NYLON};
    const double w0s[5] = {0.175, 1.0, 6.0, 12.0, 21.0};
    double R = 0.1, mu = 0.4, vn = 0.2;
    int t, i;
    for (t = 0; t < 2; ++t) {
        double m = sphere_mass(ms[t]->rho, R), I = 0.4 * m * R * R,
               dt = hertz_tc(m, R, estar(ms[t], NULL), vn) / 1000.0;
        gk_material mat = hertz_mat(ms[t], mu);
        for (i = 0; i < 5; ++i) {
            double v[3] = {0, 0, 0}, w[3] = {0, 0, 0}, vo[3], wo[3];
            v[1] = -vn;
            w[2] = w0s[i];
            CHECK(oblique(&mat, R, v, w, dt, vo, wo) == 0);
            printf("    %-9s w0 %6.3f: v_x' %+.5f m/s, w' %+.4f rad/s\n", ms[t]->name, w0s[i], vo[0], wo[2]);
            CHECK_NEAR(I * wo[2] - m * R * vo[0], I * w0s[i], 2e-3 * I * w0s[i]);
            if (R * w0s[i] >= 7.0 * mu * vn * 1.01) {
                CHECK_NEAR(vo[0], -2.0 * mu * vn, 2e-3 * 2.0 * mu * vn);
                CHECK_NEAR(wo[2], w0s[i] - 5.0 * mu * vn / R, 2e-3 * 5.0 * mu * vn / R);
            }
        }
    }
    { /* equal-period linear spring, stuck: v_c' = -R w0, with I w - m R v conserved */
        gk_material lin = gk_material_default();
        double m = sphere_mass(AL_ALLOY_O.rho, R), I = 0.4 * m * R * R, kn = 4.0 * AL_ALLOY_O.E * R;
        double v[3] = {0, 0, 0}, w[3] = {0, 0, 0}, vo[3], wo[3], w0 = 0.175, vx, wz;
        lin.young = AL_ALLOY_O.E;
        lin.kt_ratio = 2.0 / 7.0;
        lin.friction = mu;
        lin.density = AL_ALLOY_O.rho;
        v[1] = -vn;
        w[2] = w0;
        CHECK(oblique(&lin, R, v, w, GK_PI * sqrt(m / kn) / 2000.0, vo, wo) == 0);
        /* vx + R wz = -R w0 and I wz - m R vx = I w0 */
        wz = (I * w0 - m * R * R * w0) / (I + m * R * R);
        vx = -R * w0 - R * wz;
        printf("    linear k_t/k_n = 2/7, w0 %.3f: v_x' %+.6f (exact %+.6f), w' %+.5f (%+.5f)\n", w0, vo[0],
               vx, wo[2], wz);
        CHECK_NEAR(vo[0], vx, 3e-3 * R * w0);
        CHECK_NEAR(wo[2], wz, 3e-3 * w0);
    }
}

/* two spheres: A below moving up, B above moving down (zero momentum), both
 * spinning at w0 about z: the contact points slide at 2 R w0 for equal radii
 * (R_A w0 + R_B w0 in general) while the centres have no tangential speed,
 * so the line of centres stays put */
static int two_spheres(gk_scene *sc, const gk_material *m, double RA, double RB, double mB, double vn,
                       double w0, double dt) {
    double x[2][3] = {{0, 0, 0}, {0, 0, 0}}, r[2];
    double mA, vA[3] = {0, 0, 0}, vB[3] = {0, 0, 0}, w[3] = {0, 0, 0};
    x[0][1] = -RA * (1.0 + 1e-4);
    x[1][1] = RB * (1.0 + 1e-4);
    r[0] = RA;
    r[1] = RB;
    w[2] = w0;
    if (impact_scene(sc, 2, x, r, m, dt, 10 * (RA > RB ? RA : RB))) return 1;
    if (mB > 0 && gk_scene_set_mass(sc, gk_scene_index(sc, 1), mB, 0.4 * mB * RB * RB)) return 1;
    mA = sc->mass[gk_scene_index(sc, 0)];
    mB = sc->mass[gk_scene_index(sc, 1)];
    vA[1] = vn * mB / (mA + mB);
    vB[1] = -vn * mA / (mA + mB);
    return gk_scene_set_velocity(sc, gk_scene_index(sc, 0), vA, w) ||
           gk_scene_set_velocity(sc, gk_scene_index(sc, 1), vB, w);
}

/* Test 7: two identical spheres (aluminium alloy and nylon, R = 0.1 m, mu =
 * 0.4), relative normal speed 0.2 m/s, both spinning at w0 = 0.175 to 21
 * rad/s. For the pair chi = 1 + m* (R^2 / I + R^2 / I) = 7/2 as for a sphere
 * on a wall; in gross sliding (2 R w0 >= 2 chi mu v_n) each sphere leaves
 * with tangential speed mu v_n (J_n = m* 2 v_n = m v_n) and its spin
 * reduced by 5/2 mu v_n / R (to delta_max / R); at every spin the total
 * angular momentum is kept and the relative contact velocity does not grow;
 * the pair law with k_t / k_n = 2/7 reverses it exactly when stuck. */
TEST(chung_ooi_7_two_spheres_oblique) {
    const mat_t *ms[2] = {&AL_ALLOY_O, &NYLON};
    const double w0s[4] = {0.175, 1.0, 6.0, 21.0};
    double R = 0.1, mu = 0.4, vn = 0.2;
    int t, i;
    for (t = 0; t < 2; ++t) {
        double m = sphere_mass(ms[t]->rho, R), I = 0.4 * m * R * R, Es = estar(ms[t], ms[t]);
        double dt = hertz_tc(0.5 * m, 0.5 * R, Es, vn) / 1000.0,
               tol = hertz_dmax(0.5 * m, 0.5 * R, Es, vn) / R + 2e-3;
        gk_material mat = hertz_mat(ms[t], mu);
        for (i = 0; i < 4; ++i) {
            gk_scene sc;
            impact_rec o;
            int a, b;
            double vc0 = 2.0 * R * w0s[i], vc, Lz;
            if (two_spheres(&sc, &mat, R, R, 0.0, vn, w0s[i], dt)) {
                CHECK(0);
                continue;
            }
            a = gk_scene_index(&sc, 0);
            b = gk_scene_index(&sc, 1);
            CHECK(run_impact(&sc, a, b, &o, 1000000) == 0);
            /* B's contact point (at -R y) relative to A's (at +R y) */
            vc = ((double)sc.rve.v[0][b] + R * (double)sc.rve.w[2][b]) -
                 ((double)sc.rve.v[0][a] - R * (double)sc.rve.w[2][a]);
            /* about the initial contact point: A at -R y, B at +R y */
            Lz = I * ((double)sc.rve.w[2][a] + (double)sc.rve.w[2][b]) +
                 m * R * ((double)sc.rve.v[0][a] - (double)sc.rve.v[0][b]);
            printf(
                "    %-9s w0 %6.3f: A v_x %+.5f w %+.5f, B v_x %+.5f w %+.5f, contact %+.5f (from %+.4f)\n",
                ms[t]->name, w0s[i], sc.rve.v[0][a], sc.rve.w[2][a], sc.rve.v[0][b], sc.rve.w[2][b], vc, vc0);
            CHECK_NEAR(Lz, 2.0 * I * w0s[i], 2e-3 * 2.0 * I * w0s[i]);
            CHECK(fabs(vc) <= vc0 * (1.0 + 1e-3));
            /* normal rebound along y, to the turn of the line of centres (tangential travel / 2R) */
            CHECK_NEAR(sc.rve.v[1][b] - sc.rve.v[1][a], vn, 5e-4 * vn);
            if (vc0 >= 7.0 * mu * vn * 1.01) {
                CHECK_NEAR(sc.rve.v[0][a], mu * vn, tol * mu * vn);
                CHECK_NEAR(sc.rve.v[0][b], -mu * vn, tol * mu * vn);
                CHECK_NEAR(sc.rve.w[2][a], w0s[i] - 2.5 * mu * vn / R, tol * 2.5 * mu * vn / R);
                CHECK_NEAR(sc.rve.w[2][b], w0s[i] - 2.5 * mu * vn / R, tol * 2.5 * mu * vn / R);
            }
            gk_scene_destroy(&sc);
        }
    }
    { /* stuck, equal periods: the relative contact velocity 2 R w0 is reversed */
        gk_material lin = gk_material_default();
        gk_scene sc;
        impact_rec o;
        double m = sphere_mass(AL_ALLOY_O.rho, R), kn = AL_ALLOY_O.E * R, w0 = 0.175, vc;
        int a, b;
        lin.young = AL_ALLOY_O.E;
        lin.kt_ratio = 2.0 / 7.0;
        lin.friction = mu;
        lin.density = AL_ALLOY_O.rho;
        if (two_spheres(&sc, &lin, R, R, 0.0, vn, w0, GK_PI * sqrt(0.5 * m / kn) / 2000.0) == 0) {
            a = gk_scene_index(&sc, 0);
            b = gk_scene_index(&sc, 1);
            CHECK(run_impact(&sc, a, b, &o, 1000000) == 0);
            vc = ((double)sc.rve.v[0][b] + R * (double)sc.rve.w[2][b]) -
                 ((double)sc.rve.v[0][a] - R * (double)sc.rve.w[2][a]);
            printf("    linear k_t/k_n = 2/7, w0 %.3f: relative contact velocity %+.6f (exact %+.6f)\n", w0,
                   vc, -2.0 * R * w0);
            CHECK_NEAR(vc, -2.0 * R * w0, 3e-3 * 2.0 * R * w0);
            gk_scene_destroy(&sc);
        } else {
            CHECK(0);
        }
    }
}

/* Test 8: two spheres of different sizes and materials: aluminium alloy
 * R_A = 0.1 m and magnesium alloy R_B = 0.05 m (pair material from
 * gk_scene_pair_material, B's mass from its own density). Normal impact at
 * 0.2 m/s: Hertz with E* of the two materials, R* = R_A R_B / (R_A + R_B),
 * m* = m_A m_B / (m_A + m_B); both spinning at 20 rad/s (contact sliding at
 * (R_A + R_B) w0): gross sliding, each sphere receives the tangential
 * impulse mu J_n = mu m* 2 v_n and spins down by R J_t / I (to delta_max /
 * R_B). */
TEST(chung_ooi_8_different_spheres) {
    double RA = 0.1, RB = 0.05, vn = 0.2, mu = 0.3, mA = sphere_mass(AL_ALLOY.rho, RA),
           mB = sphere_mass(MG_ALLOY.rho, RB);
    double ms = mA * mB / (mA + mB), Rs = RA * RB / (RA + RB), Es = estar(&AL_ALLOY, &MG_ALLOY), w0 = 20.0;
    double tc = hertz_tc(ms, Rs, Es, vn), dm = hertz_dmax(ms, Rs, Es, vn),
           fm = 4.0 / 3.0 * Es * sqrt(Rs) * pow(dm, 1.5);
    double tol = dm / RB + 2e-3;
    gk_material a = hertz_mat(&AL_ALLOY, mu), b = hertz_mat(&MG_ALLOY, mu), pair;
    gk_scene sc;
    impact_rec o;
    gk_err e;
    int ia, ib;
    CHECK(gk_scene_pair_material(&a, &b, &pair, &e) == GK_OK);
    if (two_spheres(&sc, &pair, RA, RB, mB, vn, 0.0, tc / 1000.0)) {
        CHECK(0);
        return;
    }
    ia = gk_scene_index(&sc, 0);
    ib = gk_scene_index(&sc, 1);
    CHECK(run_impact(&sc, ia, ib, &o, 1000000) == 0);
    printf("    normal: F_max %.6g N (Hertz %.6g), delta_max %.6g m (%.6g), t_c %.6g s (%.6g)\n", o.fmax, fm,
           o.dmax, dm, o.tc, tc);
    CHECK_REL(o.fmax, fm, 2e-3);
    CHECK_REL(o.dmax, dm, 2e-3);
    CHECK_REL(o.tc, tc, 2e-3);
    CHECK_NEAR(sc.rve.v[1][ib] - sc.rve.v[1][ia], vn, 1e-4 * vn); /* elastic */
    gk_scene_destroy(&sc);
    if (two_spheres(&sc, &pair, RA, RB, mB, vn, w0, tc / 1000.0)) {
        CHECK(0);
        return;
    }
    ia = gk_scene_index(&sc, 0);
    ib = gk_scene_index(&sc, 1);
    CHECK(run_impact(&sc, ia, ib, &o, 1000000) == 0);
    {
        double Jt = mu * ms * 2.0 * vn;
        printf("    oblique: A v_x %+.5f w %+.5f, B v_x %+.5f w %+.5f\n", sc.rve.v[0][ia], sc.rve.w[2][ia],
               sc.rve.v[0][ib], sc.rve.w[2][ib]);
        CHECK_NEAR(sc.rve.v[0][ia], Jt / mA, tol * Jt / mA);
        CHECK_NEAR(sc.rve.v[0][ib], -Jt / mB, tol * Jt / mB);
        CHECK_NEAR(sc.rve.w[2][ia], w0 - RA * Jt / (0.4 * mA * RA * RA),
                   tol * RA * Jt / (0.4 * mA * RA * RA));
        CHECK_NEAR(sc.rve.w[2][ib], w0 - RB * Jt / (0.4 * mB * RB * RB),
                   tol * RB * Jt / (0.4 * mB * RB * RB));
    }
    gk_scene_destroy(&sc);
}

/* ================================================================ scenes */
/* nx x ny (x nz) polydisperse particles (radii uniform in [0.8, 1] r) on a
 * square lattice of spacing 2.2 r starting at (x0, y0, z0), shifted
 * sideways by up to jitter r (0.1: the columns do not stand) */
static int lattice(gk_packing *pk, int dim, int nx, int ny, int nz, double r, double x0, double y0, double z0,
                   double jitter, uint64_t seed) {
    gk_rng rng;
    gk_err e;
    int a, b, c, q = 0, n = nx * ny * (dim == 3 ? nz : 1);
    if (gk_packing_init(pk, dim, n, NULL, &e)) return 1;
    gk_rng_seed(&rng, seed);
    for (c = 0; c < (dim == 3 ? nz : 1); ++c)
        for (b = 0; b < ny; ++b)
            for (a = 0; a < nx; ++a) {
                pk->x[q] = x0 + 2.2 * r * (a + 0.5) + jitter * r * (2.0 * gk_rng_uniform(&rng) - 1.0);
                pk->y[q] = y0 + 2.2 * r * (b + 0.5);
                pk->z[q] = dim == 3
                               ? z0 + 2.2 * r * (c + 0.5) + jitter * r * (2.0 * gk_rng_uniform(&rng) - 1.0)
                               : 0.0;
                pk->r[q] = r * (0.8 + 0.2 * gk_rng_uniform(&rng));
                ++q;
            }
    return 0;
}

/* a 2D (or 3D) box [0, W] x [0, H] (x [0, W]) of particles settling under
 * gravity on a frictional floor and walls; linear law, viscous damping */
static int box_scene(gk_scene *sc, int dim, int nx, int ny, double W, double H, double damping,
                     unsigned periodic) {
    gk_scene_def d = gk_scene_def_default();
    gk_packing pk;
    gk_material wm;
    int k;
    double r = W / (2.2 * nx);
    d.dim = dim;
    d.hi[0] = W;
    d.hi[1] = H;
    d.hi[2] = W;
    d.periodic = periodic;
    d.gravity[1] = -9.81;
    d.rve.mat.friction = 0.5;
    d.rve.mat.zeta_n = 0.3;
    d.rve.mat.density = 2650;
    d.rve.mat.young = 5e7; /* soft: a larger time step */
    d.rve.damping = damping;
    d.rve.dt_factor = 0.2;
    if (lattice(&pk, dim, nx, ny, dim == 3 ? nx : 1, r, 0.0, 0.0, 0.0, 0.1, 7)) return 1;
    k = gk_scene_create(sc, &d, &pk);
    gk_packing_free(&pk);
    if (k) {
        printf("    create: %s\n", gk_scene_error(sc));
        return 1;
    }
    wm = d.rve.mat;
    if (gk_scene_add_box(sc, &wm, GK_BOX_ALL & ~(2u << 2), NULL)) { /* no lid */
        printf("    box: %s\n", gk_scene_error(sc));
        gk_scene_destroy(sc);
        return 1;
    }
    return 0;
}

static double total_weight(const gk_scene *sc) {
    double w = 0.0;
    int p;
    for (p = 0; p < sc->rve.n; ++p) w += sc->mass[p] * 9.81;
    return w;
}

/* Statics: particles poured into a box come to rest; the walls together
 * carry their whole weight (sum of the wall forces = -sum m g e_y, to 1e-3:
 * the floor most of it, the frictional side walls the rest, as in a
 * silo) and the side walls' pushes cancel (2D and 3D). */
TEST(gravity_floor_carries_the_weight) {
    int dim;
    for (dim = 2; dim <= 3; ++dim) {
        gk_scene sc;
        double wt;
        if (box_scene(&sc, dim, dim == 2 ? 12 : 4, dim == 2 ? 12 : 4, 0.12, 0.3, 0.6, 0)) {
            CHECK(0);
            continue;
        }
        CHECK(gk_scene_step(&sc, dim == 2 ? 40000 : 100000) ==
              GK_OK); /* to rest (also in the quick builds) */
        wt = total_weight(&sc);
        {
            double F[3] = {0, 0, 0};
            int w, k;
            for (w = 0; w < sc.nwalls; ++w)
                for (k = 0; k < 3; ++k) F[k] += sc.walls[w].force[k];
            printf("    %dD: walls carry %.6g N (floor %.6g N), weight %.6g N, side walls %.4g / %.4g N, "
                   "kinetic %.3g J\n",
                   dim, -F[1], sc.walls[2].resistance, wt, sc.walls[0].resistance, sc.walls[1].resistance,
                   gk_rve_kinetic_energy(&sc.rve));
            CHECK_REL(-F[1], wt, 1e-3);
            CHECK_NEAR(F[0], 0.0, 1e-3 * wt);
            CHECK_NEAR(F[2], 0.0, 1e-3 * wt);
            CHECK(sc.walls[2].resistance > 0.8 * wt && sc.walls[0].resistance > 0.0);
        }
        gk_scene_destroy(&sc);
    }
}

/* A servo lid: a plane driven to a target force settles on it (to 1e-3),
 * and the floor then carries the lid force plus the weight minus what the
 * side walls hold (vertical balance of the walls' forces, to 1e-3). */
TEST(servo_wall_reaches_its_target) {
    gk_scene sc;
    gk_wall_def lid = gk_wall_def_default();
    double target, F = 0.0;
    int w, iw;
    if (box_scene(&sc, 2, 10, 10, 0.1, 0.3, 0.3, 0)) {
        CHECK(0);
        return;
    }
    CHECK(gk_scene_step(&sc, QUICK(20000, 10000)) == GK_OK); /* settle */
    target = 5.0 * total_weight(&sc);
    lid.point[1] = 0.3;
    lid.normal[1] = -1.0;
    lid.mat = sc.def.rve.mat;
    lid.drive = GK_DRIVE_FORCE;
    lid.target = target;
    lid.max_speed = 0.5;
    lid.gain = 0.02;
    CHECK(gk_scene_add_wall(&sc, &lid, &iw) == GK_OK);
    CHECK(gk_scene_step(&sc, QUICK(40000, 30000)) == GK_OK);
    for (w = 0; w < sc.nwalls; ++w) F += sc.walls[w].force[1];
    printf("    lid %.6g N (target %.6g N) at y = %.5f m; walls' vertical sum %.6g N, weight %.6g N\n",
           sc.walls[iw].resistance, target, sc.walls[iw].pos[1], -F, total_weight(&sc));
    CHECK_REL(sc.walls[iw].resistance, target, 1e-3);
    CHECK_REL(-F, total_weight(&sc), 1e-3);
    CHECK(sc.walls[iw].pos[1] < 0.3);
    /* a stress target over an area is the same servo */
    sc.walls[iw].def.drive = GK_DRIVE_STRESS;
    sc.walls[iw].def.area = 0.1 * sc.rve.volume_factor;
    sc.walls[iw].def.target = 2.0 * target / sc.walls[iw].def.area;
    CHECK(gk_scene_step(&sc, QUICK(40000, 30000)) == GK_OK);
    CHECK_REL(sc.walls[iw].resistance, 2.0 * target, 1e-3);
    gk_scene_destroy(&sc);
}

/* Prescribed particles: the bottom row is held fixed and the top row moves
 * down at 5 mm/s (no walls, no gravity): after n steps the top row has
 * moved exactly n dt v, the bottom row not at all, and in the slow
 * compression the loads on the two rows balance (to 2 %) and push back
 * (the top row's load points up). */
TEST(prescribed_particles_move_and_report_their_load) {
    gk_scene_def d = gk_scene_def_default();
    gk_scene sc;
    gk_packing pk;
    int p, nx = 8, ny = 8;
    double r = 0.005, y0[64], v[3] = {0, -0.005, 0}, zero[3] = {0, 0, 0}, top = 0.0, bot = 0.0;
    long n = 16000;
    d.dim = 2;
    d.hi[0] = d.hi[1] = 0.2;
    d.rve.mat.young = 5e7;
    d.rve.mat.zeta_n = 0.3;
    d.rve.damping = 0.3;
    d.rve.dt_factor = 0.2;
    CHECK(lattice(&pk, 2, nx, ny, 1, r, 0.02, 0.02, 0.0, 0.0, 11) == 0);
    for (p = 0; p < pk.n; ++p) pk.r[p] = 1.09 * r; /* gaps of 0.02 r */
    CHECK(gk_scene_create(&sc, &d, &pk) == GK_OK);
    gk_packing_free(&pk);
    for (p = 0; p < sc.rve.n; ++p) {
        int row = sc.rve.id[p] / nx;
        double x[3];
        gk_scene_position(&sc, p, x);
        y0[sc.rve.id[p]] = x[1];
        if (row == 0) gk_scene_prescribe(&sc, p, zero, zero);
        if (row == ny - 1) gk_scene_prescribe(&sc, p, v, zero);
    }
    CHECK(sc.nprescribed == 2 * nx);
    if (gk_scene_step(&sc, n)) {
        printf("    step: %s\n", gk_scene_error(&sc));
        CHECK(0);
    }
    for (p = 0; p < sc.rve.n; ++p) {
        int row = sc.rve.id[p] / nx;
        double x[3];
        gk_scene_position(&sc, p, x);
        if (row == 0) {
            CHECK(x[1] == y0[sc.rve.id[p]]);
            bot += sc.load[1][p];
        }
        if (row == ny - 1) {
            CHECK_NEAR(x[1], y0[sc.rve.id[p]] + n * sc.rve.dt * v[1], 1e-12);
            top += sc.load[1][p];
        }
    }
    printf("    load on the moving row %.5g N, on the fixed row %.5g N\n", top, bot);
    CHECK(top > 0.0);
    CHECK_NEAR(top, -bot, 0.02 * top);
    /* released, a particle moves freely again */
    gk_scene_release(&sc, gk_scene_index(&sc, (ny - 1) * nx));
    CHECK(sc.nprescribed == 2 * nx - 1);
    gk_scene_destroy(&sc);
}

/* The follower-pressure membrane (2D biaxial cell: smooth rigid floor and
 * servo lid at stress p, membranes on both sides at pressure p, loaded in ten
 * stages): once in equilibrium the mean stress of the particles
 * (gk_scene_stress over the area A the chains' centre lines and the walls
 * enclose) is what the boundary applies, (1/A) sum load (x) position over
 * the membrane loads (pressure and anchor links), the lid and the one
 * particle held in place (smooth platens), to 1 % (static equilibrium:
 * Love-Weber; the chains' tension-only links count as inner forces);
 * sigma_xx is -p to 3 % (the anchored chains carry the pressure from
 * platen to platen) and within 10 % of sigma_yy (isotropic loading; the
 * lid pushes on the full width W, the chains act on their centre lines, a
 * radius further in); the lid holds p W; no particle leaks. */
TEST(membrane_confines_at_its_pressure) {
    gk_scene_def d = gk_scene_def_default();
    gk_scene sc;
    gk_packing pk;
    gk_wall_def lid = gk_wall_def_default(), flo = gk_wall_def_default();
    int32_t left[64], right[64];
    int nl, nr, p, e, bad = 0;
    double pr = 2e4, W = 0.1, H = 0.2, sig[9], area = 0.0, r = 0.0025, hchain = 0.0;
    d.dim = 2;
    d.lo[0] = -0.1;
    d.hi[0] = 0.2;
    d.hi[1] = 0.25;
    d.rve.mat.young = 5e7;
    d.rve.mat.friction = 0.3;
    d.rve.damping = 0.5;
    d.rve.dt_factor = 0.2;
    CHECK(lattice(&pk, 2, 18, 36, 1, r, 0.0, 0.0, 0.0, 0.0, 3) == 0);
    for (p = 0; p < pk.n; ++p) pk.r[p] = 1.05 * r + 0.04 * r * (double)(p % 3); /* nearly touching */
    CHECK(gk_scene_create(&sc, &d, &pk) == GK_OK);
    gk_packing_free(&pk);
    flo.normal[1] = 1.0;
    flo.mat = d.rve.mat;
    flo.mat.friction = 0.0; /* lubricated platens */
    lid.point[1] = 36 * 2.2 * r;
    lid.normal[1] = -1.0;
    lid.mat = flo.mat;
    lid.drive = GK_DRIVE_STRESS;
    lid.target = pr;
    lid.area = W * sc.rve.volume_factor;
    lid.max_speed = 0.05;
    CHECK(gk_scene_add_wall(&sc, &flo, NULL) == GK_OK);
    CHECK(gk_scene_add_wall(&sc, &lid, NULL) == GK_OK);
    CHECK(gk_scene_side_chain(&sc, 0, -1, 2.2 * r, left, 64, &nl) == GK_OK);
    CHECK(gk_scene_side_chain(&sc, 0, 1, 2.2 * r, right, 64, &nr) == GK_OK);
    CHECK(nl == 36 && nr == 36);
    /* the left chain runs top to bottom (lid to floor), the right one bottom to top */
    CHECK(gk_scene_add_membrane(&sc, nl, left, pr, 1e5, 1, 0, NULL) == GK_OK);
    CHECK(gk_scene_add_membrane(&sc, nr, right, pr, 1e5, 0, 1, NULL) == GK_OK);
    /* smooth platens leave the specimen free to slide: hold one particle of the bottom row */
    CHECK(gk_scene_prescribe(&sc, gk_scene_index(&sc, 9), NULL, NULL) == GK_OK);
    for (e = 1; e <= 20; ++e) { /* load in 10 stages, then hold */
        sc.mem[0].pressure = sc.mem[1].pressure = pr * (e < 10 ? e : 10) / 10.0;
        sc.walls[1].def.target = pr * (e < 10 ? e : 10) / 10.0;
        if (gk_scene_step(&sc, QUICK(3000, 2000))) {
            printf("    step: %s\n", gk_scene_error(&sc));
            CHECK(0);
            break;
        }
    }
    /* the boundary the loads act on: the chains' centre lines, closed along
     * the floor and the lid; the membranes load only the chain's height */
    {
        double xs[200], ys[200], x[3], yb, yt;
        int m = 0, k;
        H = sc.walls[1].pos[1];
        gk_scene_position(&sc, gk_scene_index(&sc, right[0]), x);
        xs[m] = x[0], ys[m++] = 0.0;
        yb = x[1];
        for (e = 0; e < nr; ++e) {
            gk_scene_position(&sc, gk_scene_index(&sc, right[e]), x);
            xs[m] = x[0], ys[m++] = x[1];
        }
        yt = x[1];
        xs[m] = x[0], ys[m++] = H;
        gk_scene_position(&sc, gk_scene_index(&sc, left[0]), x);
        xs[m] = x[0], ys[m++] = H;
        for (e = 0; e < nl; ++e) {
            gk_scene_position(&sc, gk_scene_index(&sc, left[e]), x);
            xs[m] = x[0], ys[m++] = x[1];
        }
        xs[m] = x[0], ys[m++] = 0.0;
        for (k = 0; k < m; ++k) area += 0.5 * (xs[k] * ys[(k + 1) % m] - xs[(k + 1) % m] * ys[k]);
        hchain = yt - yb;
    }
    /* what the boundary applies: sum of load (x) position over the membrane
     * loads (at the chain centres) and the lid (at y = H; the floor's lever is 0) */
    {
        double bx = 0.0, by = -sc.walls[1].force[1] * H, x[3];
        int m, q = gk_scene_index(&sc, 9);
        gk_scene_position(&sc, q, x); /* the hold: minus its load, at its centre */
        bx -= sc.load[0][q] * x[0];
        by -= sc.load[1][q] * x[1];
        for (m = 0; m < 2; ++m)
            for (e = 0; e < sc.mem[m].n; ++e) {
                int end = e == 0 ? 0 : (e == sc.mem[m].n - 1 ? 1 : -1);
                gk_scene_position(&sc, gk_scene_index(&sc, sc.mem[m].ids[e]), x);
                bx += (sc.mem[m].fx[e] + (end >= 0 ? sc.mem[m].af[end][0] : 0.0)) * x[0];
                by += (sc.mem[m].fy[e] + (end >= 0 ? sc.mem[m].af[end][1] : 0.0)) * x[1];
            }
        gk_scene_stress(&sc, area, sig);
        bx /= area * sc.rve.volume_factor;
        by /= area * sc.rve.volume_factor;
        printf("    sigma_xx %.5g (boundary %.5g), sigma_yy %.5g (%.5g), sigma_xy %.3g Pa over %.5g m^2; p = "
               "%g Pa, chain "
               "height %.4f of %.4f m\n",
               sig[0], bx, sig[4], by, sig[1], area, pr, hchain, H);
        CHECK_REL(sig[0], bx, 0.01);
        CHECK_REL(sig[4], by, 0.01);
        CHECK_REL(sig[0], -pr, 0.03);
        CHECK(sig[0] / sig[4] > 0.9 && sig[0] / sig[4] < 1.1);
    }
    CHECK_REL(sc.walls[1].resistance, pr * W * sc.rve.volume_factor, 1e-3);
    for (p = 0; p < sc.rve.n; ++p) {
        double x[3];
        gk_scene_position(&sc, p, x);
        if (!(x[0] > -0.02 && x[0] < 0.12)) ++bad;
    }
    CHECK(bad == 0);
    gk_scene_destroy(&sc);
}

/* A scene around an RVE the caller owns (gk_scene_wrap): the same particles
 * with one of them prescribed move bit for bit as in a scene created from the
 * same packing with every axis periodic; unwrap gives the RVE back, hook
 * cleared, and it steps on by itself; a sheared cell is refused, the RVE
 * untouched. */
TEST(wrap_runs_an_rve_as_a_scene) {
    gk_scene_def d = gk_scene_def_default();
    gk_scene a, b;
    gk_gen_def g;
    gk_packing pk;
    gk_rve rve;
    gk_err e;
    double v[3] = {0.3, -0.2, 0}, w[3] = {0, 0, 5.0}, L[9] = {0, 1e-3, 0, 0, 0, 0, 0, 0, 0};
    int p, same = 1, n, moved = 0;
    memset(&g, 0, sizeof g);
    g.dim = 2, g.n = 60, g.r_min = 0.004, g.r_max = 0.006, g.seed = 5, g.packing_fraction = 0.5;
    CHECK(gk_packing_generate(&pk, &g, NULL, &e) == GK_OK);
    d.dim = 2, d.hi[0] = pk.h[0], d.hi[1] = pk.h[4], d.periodic = 3u;
    d.rve.damping = 0.3;
    CHECK(gk_scene_create(&a, &d, &pk) == GK_OK);
    CHECK(gk_rve_create(&rve, &d.rve, &pk) == GK_OK);
    n = rve.n;
    CHECK(gk_scene_wrap(&b, &rve) == GK_OK);
    CHECK(rve.n == 0 && b.rve.n == n);
    CHECK(gk_scene_prescribe(&a, gk_scene_index(&a, 7), v, w) == GK_OK);
    CHECK(gk_scene_prescribe(&b, gk_scene_index(&b, 7), v, w) == GK_OK);
    CHECK(gk_scene_step(&a, 3000) == GK_OK && gk_scene_step(&b, 3000) == GK_OK);
    for (p = 0; p < n; ++p) {
        double xa[3], xb[3];
        gk_scene_position(&a, gk_scene_index(&a, p), xa);
        gk_scene_position(&b, gk_scene_index(&b, p), xb);
        same &= xa[0] == xb[0] && xa[1] == xb[1];
        moved += b.rve.v[0][gk_scene_index(&b, p)] != 0; /* pushed by the prescribed one */
    }
    CHECK(same);
    CHECK(moved > 3);
    CHECK(b.load[0][gk_scene_index(&b, 7)] == a.load[0][gk_scene_index(&a, 7)]);
    gk_scene_unwrap(&b, &rve);
    CHECK(rve.n == n && rve.hook == NULL && b.mass == NULL);
    CHECK(gk_rve_step(&rve, 10) == GK_OK);
    CHECK(gk_rve_set_velocity_gradient(&rve, L) == GK_OK);
    CHECK(gk_scene_wrap(&b, &rve) == GK_ERR_STATE && rve.n == n);
    CHECK(strstr(gk_scene_error(&b), "box") != NULL);
    gk_rve_destroy(&rve);
    gk_scene_destroy(&a);
    gk_packing_free(&pk);
}

/* position of the particle with stable id `id` */
static void pos_of(const gk_scene *sc, int32_t id, double x[3]) {
    gk_scene_position(sc, gk_scene_index(sc, id), x);
}

/* Insertion and deletion leave the others alone: a pile with one extra,
 * held, far-away particle (A) and the same pile from which that particle is
 * removed after 3000 steps (B), or into which it is inserted then (C), run
 * on to the same bits for every other particle (survivors keep their ids,
 * their pair and wall contact histories and their order, so every sum is
 * the same); ids are never reused. */
TEST(insert_and_remove_leave_the_others_alone) {
    gk_scene A, B, C;
    double far[3] = {0.01, 0.28, 0.0}, zero[3] = {0, 0, 0}, xa[3], xb[3], xc[3];
    int32_t idx, newid = -1;
    int p, diffB = 0, diffC = 0;
    if (box_scene(&A, 2, 8, 8, 0.1, 0.3, 0.2, 0) || box_scene(&B, 2, 8, 8, 0.1, 0.3, 0.2, 0) ||
        box_scene(&C, 2, 8, 8, 0.1, 0.3, 0.2, 0)) {
        CHECK(0);
        return;
    }
    {
        const double *xs[3];
        double rr = 0.004, X = far[0], Y = far[1], Z = 0.0;
        xs[0] = &X;
        xs[1] = &Y;
        xs[2] = &Z;
        CHECK(gk_scene_insert(&A, 1, xs, &rr, NULL, &idx) == GK_OK);
        CHECK(gk_scene_insert(&B, 1, xs, &rr, NULL, &idx) == GK_OK);
        CHECK(idx == 64 && A.rve.n == 65);
        CHECK(gk_scene_prescribe(&A, gk_scene_index(&A, idx), zero, zero) == GK_OK);
        CHECK(gk_scene_prescribe(&B, gk_scene_index(&B, idx), zero, zero) == GK_OK);
        CHECK(gk_scene_step(&A, 3000) == GK_OK && gk_scene_step(&B, 3000) == GK_OK &&
              gk_scene_step(&C, 3000) == GK_OK);
        CHECK(gk_scene_remove(&B, 1, &idx) == GK_OK);
        CHECK(B.rve.n == 64 && gk_scene_index(&B, idx) == -1 && B.nprescribed == 0);
        CHECK(gk_scene_insert(&C, 1, xs, &rr, NULL, &newid) == GK_OK);
        CHECK(newid == 64);
        CHECK(gk_scene_prescribe(&C, gk_scene_index(&C, newid), zero, zero) == GK_OK);
    }
    CHECK(gk_scene_step(&A, 3000) == GK_OK && gk_scene_step(&B, 3000) == GK_OK &&
          gk_scene_step(&C, 3000) == GK_OK);
    for (p = 0; p < 64; ++p) {
        pos_of(&A, p, xa);
        pos_of(&B, p, xb);
        pos_of(&C, p, xc);
        if (memcmp(xa, xb, sizeof xa)) ++diffB;
        if (memcmp(xa, xc, sizeof xa)) ++diffC;
    }
    printf("    particles differing from the run with the extra particle: %d (removed), %d (inserted)\n",
           diffB, diffC);
    CHECK(diffB == 0 && diffC == 0);
    CHECK(A.walls[2].force[1] == B.walls[2].force[1] && A.walls[2].force[1] == C.walls[2].force[1]);
    /* an unknown id is refused and changes nothing */
    CHECK(gk_scene_remove(&B, 1, &idx) == GK_ERR_ARG && B.rve.n == 64);
    /* ids are not reused: the next insertion into B gets 65 */
    {
        const double *xs[3];
        double rr = 0.004, X = 0.09, Y = 0.28, Z = 0.0;
        xs[0] = &X;
        xs[1] = &Y;
        xs[2] = &Z;
        CHECK(gk_scene_insert(&B, 1, xs, &rr, NULL, &newid) == GK_OK && newid == 65);
        Y = 0.5; /* outside the open domain: refused, nothing changed */
        CHECK(gk_scene_insert(&B, 1, xs, &rr, NULL, &newid) == GK_ERR_OUTSIDE && B.rve.n == 65);
    }
    gk_scene_destroy(&A);
    gk_scene_destroy(&B);
    gk_scene_destroy(&C);
}

/* Ids far apart: a pile into which one particle was inserted and removed
 * 2000 times has ids 0-63 and, once one more is inserted, id 2064 with 65
 * particles. Its id index stays O(n) (sorted (id, index) pairs once the
 * largest id exceeds 4 n + 1024: a table as long as the next id is what
 * let a 20 kB saved state ask for 2.7 GB) and finds every particle; the run
 * is the same, bit for bit, as that of the pile with the particle inserted
 * once (id 64). */
TEST(ids_far_apart_keep_the_index_small) {
    gk_scene A, B;
    const double *xs[3];
    double rr = 0.004, X = 0.01, Y = 0.28, Z = 0.0, xa[3], xb[3];
    int32_t id = -1, idb = -1;
    int k, p, diff = 0, found = 0;
    if (box_scene(&A, 2, 8, 8, 0.1, 0.3, 0.2, 0) || box_scene(&B, 2, 8, 8, 0.1, 0.3, 0.2, 0)) {
        CHECK(0);
        return;
    }
    xs[0] = &X, xs[1] = &Y, xs[2] = &Z;
    for (k = 0; k < 2000; ++k)
        if (gk_scene_insert(&A, 1, xs, &rr, NULL, &id) != GK_OK || gk_scene_remove(&A, 1, &id) != GK_OK)
            break;
    CHECK_EQ_INT(k, 2000);
    CHECK(A.sparse_ids == 0); /* ids 0-63 present: a table */
    CHECK(gk_scene_insert(&A, 1, xs, &rr, NULL, &id) == GK_OK && id == 2064);
    CHECK(gk_scene_insert(&B, 1, xs, &rr, NULL, &idb) == GK_OK && idb == 64);
    printf("    next id %d, 65 particles: index of %d entries (%s)\n", (int)A.next_id, A.cap_ids,
           A.sparse_ids ? "sorted pairs" : "table");
    /* at most 1.5 (4 n + 1024) + 16 entries whatever the next id (the table grew to that while the
     * churned ids were within 4 n + 1024); a table as long as the next id: 3113 */
    CHECK(A.sparse_ids == 1 && A.cap_ids <= 3 * (4 * 65 + 1024) / 2 + 16);
    for (p = 0; p < A.rve.n; ++p) found += gk_scene_index(&A, A.rve.id[p]) == p;
    CHECK_EQ_INT(found, 65);
    CHECK(gk_scene_index(&A, 64) == -1 && gk_scene_index(&A, 2063) == -1 && gk_scene_index(&A, 2065) == -1 &&
          gk_scene_index(&A, -1) == -1 && gk_scene_index(&A, 2064) == gk_scene_index(&B, 64));
    CHECK(gk_scene_step(&A, 500) == GK_OK && gk_scene_step(&B, 500) == GK_OK);
    for (p = 0; p < 65; ++p) {
        pos_of(&A, p < 64 ? p : 2064, xa);
        pos_of(&B, p, xb);
        diff += memcmp(xa, xb, sizeof xa) != 0;
    }
    CHECK_EQ_INT(diff, 0);
    /* removing it again: the ids are dense enough for a table */
    CHECK(gk_scene_remove(&A, 1, &id) == GK_OK && A.sparse_ids == 0 && gk_scene_index(&A, 2064) == -1);
    gk_scene_destroy(&A);
    gk_scene_destroy(&B);
}

/* the energy balance of a scene run, printed */
static double report_energy(const gk_scene *sc, const char *what) {
    gk_energy e;
    gk_scene_energy(sc, &e);
    printf("    %s: kinetic %.5g, elastic %.5g | gravity %.5g, walls %.5g, external %.5g, pressure %.5g, "
           "prescribed %.5g | friction %.5g (slips %.5g), viscous %.5g, damping %.5g | balance %.3g of %.5g "
           "J (%.2e)\n",
           what, e.kinetic, e.elastic, e.gravity, e.walls, e.external, e.pressure, e.prescribed, e.friction,
           e.slip, e.viscous, e.damping, e.balance, e.scale, fabs(e.balance) / e.scale);
    return fabs(e.balance) / e.scale;
}

/* Energy bookkeeping: particles fall into a box (gravity), collide
 * (Coulomb friction, dashpots, local damping; Hertz-Mindlin also with
 * rolling resistance and tangential dashpots), a lid then comes down at
 * constant speed, one particle is pushed by an external force and one is
 * dragged at a prescribed velocity. kinetic + elastic - initial = works -
 * dissipation to 1e-3 of the energy moved (what is left is the leap-frog's
 * own energy error: dt = 0.1 dt_crit linear, 2e-5 s Hertz), 2D and 3D;
 * with the linear law the friction booked agrees with the slip estimate to
 * 5 % (Hertz-Mindlin's friction also holds the energy its tangential
 * spring gains or loses as its stiffness follows the overlap); every pair
 * re-evaluated for the books gives the kernel's bits. */
TEST(energy_balance_closes) {
    int dim, hz;
    for (hz = 0; hz < 2; ++hz)
        for (dim = 2; dim <= 3; ++dim) {
            gk_scene sc;
            gk_wall_def lid = gk_wall_def_default();
            double f[3] = {0.5, 0, 0}, v[3] = {0.02, 0, 0}, rel;
            gk_scene_def dummy = gk_scene_def_default();
            char what[64];
            int n = dim == 2 ? 10 : 4;
            (void)dummy;
            if (box_scene(&sc, dim, n, n, 0.1, 0.25, 0.1, 0)) {
                CHECK(0);
                continue;
            }
            if (hz) { /* the same scene with Hertz-Mindlin contacts (pairs and walls) */
                gk_scene_destroy(&sc);
                {
                    gk_scene_def d = gk_scene_def_default();
                    gk_packing pk;
                    gk_material wm;
                    double r = 0.1 / (2.2 * n);
                    d.dim = dim;
                    d.hi[0] = d.hi[2] = 0.1;
                    d.hi[1] = 0.25;
                    d.gravity[1] = -9.81;
                    d.rve.mat.law = GK_LAW_HERTZ;
                    d.rve.mat.young = 5e7;
                    d.rve.mat.poisson = 0.3;
                    d.rve.mat.friction = 0.5;
                    d.rve.mat.zeta_n = 0.3;
                    d.rve.mat.zeta_t = 0.1;
                    d.rve.mat.roll_beta = 0.5;
                    d.rve.mat.roll_eta = 0.2;
                    d.rve.damping = 0.1;
                    d.rve.dt = 2e-5;
                    CHECK(lattice(&pk, dim, n, n, n, r, 0, 0, 0, 0.1, 5) == 0);
                    CHECK(gk_scene_create(&sc, &d, &pk) == GK_OK);
                    gk_packing_free(&pk);
                    wm = d.rve.mat;
                    CHECK(gk_scene_add_box(&sc, &wm, GK_BOX_ALL & ~(2u << 2), NULL) == GK_OK);
                }
            }
            if (!hz) CHECK(gk_rve_set_dt(&sc.rve, 0.5 * sc.rve.dt) == GK_OK); /* 0.1 dt_crit */
            CHECK(gk_scene_energy_track(&sc, 1) == GK_OK);
            CHECK(gk_scene_set_external(&sc, 3, f, NULL) == GK_OK);
            CHECK(gk_scene_prescribe(&sc, 5, v, NULL) == GK_OK);
            CHECK(gk_scene_step(&sc, 15000) == GK_OK);
            {
                double top = 0.0, x[3];
                int p;
                for (p = 0; p < sc.rve.n; ++p) {
                    gk_scene_position(&sc, p, x);
                    if (x[1] + (double)sc.rve.r[p] > top) top = x[1] + (double)sc.rve.r[p];
                }
                lid.point[1] = top + 0.002;
            }
            lid.normal[1] = -1.0;
            lid.mat = sc.def.rve.mat;
            lid.velocity[1] = -0.05;
            CHECK(gk_scene_add_wall(&sc, &lid, NULL) == GK_OK);
            CHECK(gk_scene_step(&sc, 15000) == GK_OK);
            snprintf(what, sizeof what, "%dD %s", dim, hz ? "Hertz" : "linear");
            rel = report_energy(&sc, what);
            CHECK(rel < 1e-3);
            CHECK(sc.energy_mismatch == 0);
            CHECK(sc.en.friction > 0 && sc.en.viscous > 0 && sc.en.damping > 0 && sc.en.walls > 0);
            if (!hz) CHECK_REL(sc.en.slip, sc.en.friction, 0.05);
            gk_scene_destroy(&sc);
        }
}

/* a scene with every moving part: 2D biaxial cell (floor, servo lid),
 * anchored membranes, one held particle, one pushed one, energy books */
static int full_scene(gk_scene *sc, int threads) {
    gk_scene_def d = gk_scene_def_default();
    gk_packing pk;
    gk_wall_def lid = gk_wall_def_default(), flo = gk_wall_def_default();
    int32_t left[64], right[64];
    int nl, nr, p;
    double r = 0.0025, f[3] = {0.3, 0.0, 0.0};
    d.dim = 2;
    d.lo[0] = -0.1;
    d.hi[0] = 0.2;
    d.hi[1] = 0.25;
    d.gravity[1] = -9.81;
    d.rve.mat.young = 5e7;
    d.rve.mat.friction = 0.3;
    d.rve.mat.zeta_n = 0.2;
    d.rve.damping = 0.2;
    d.rve.dt_factor = 0.2;
    d.rve.threads = threads;
    if (lattice(&pk, 2, 16, 24, 1, r, 0.0, 0.0, 0.0, 0.0, 3)) return 1;
    for (p = 0; p < pk.n; ++p) pk.r[p] = 1.05 * r + 0.04 * r * (double)(p % 3);
    if (gk_scene_create(sc, &d, &pk)) {
        gk_packing_free(&pk);
        return 1;
    }
    gk_packing_free(&pk);
    flo.normal[1] = 1.0;
    flo.mat = d.rve.mat;
    lid.point[1] = 24 * 2.2 * r;
    lid.normal[1] = -1.0;
    lid.mat = d.rve.mat;
    lid.drive = GK_DRIVE_STRESS;
    lid.target = 2e4;
    lid.area = 16 * 2.2 * r * sc->rve.volume_factor;
    lid.max_speed = 0.05;
    if (gk_scene_add_wall(sc, &flo, NULL) || gk_scene_add_wall(sc, &lid, NULL) ||
        gk_scene_side_chain(sc, 0, -1, 2.2 * r, left, 64, &nl) ||
        gk_scene_side_chain(sc, 0, 1, 2.2 * r, right, 64, &nr) ||
        gk_scene_add_membrane(sc, nl, left, 1e4, 1e5, 1, 0, NULL) ||
        gk_scene_add_membrane(sc, nr, right, 1e4, 1e5, 0, 1, NULL) || gk_scene_prescribe(sc, 8, NULL, NULL) ||
        gk_scene_set_external(sc, 100, f, NULL) || gk_scene_energy_track(sc, 1))
        return 1;
    return 0;
}

static unsigned char *state_of(const gk_scene *sc, size_t *n) {
    unsigned char *b;
    *n = gk_scene_state_size(sc);
    b = (unsigned char *)malloc(*n);
    if (b && gk_scene_save(sc, b, *n, NULL)) {
        free(b);
        return NULL;
    }
    return b;
}

/* gk_scene_save / gk_scene_restore continue a run bit for bit (walls,
 * servo, membranes, prescribed and pushed particles, energy books), also
 * across a change of the particle count (a state saved before a deletion
 * restored after it); 1 and 2 threads give the same bits. */
TEST(save_restore_and_threads_are_bitwise) {
    gk_scene A, B;
    unsigned char *s0, *s1, *s2;
    size_t n0, n1, n2;
    long st = QUICK(3000, 1500);
    int32_t gone[2] = {40, 41};
    /* threads: a short run (OpenMP on a shared machine is slow, not different) */
    if (full_scene(&A, 1) || full_scene(&B, 2)) {
        CHECK(0);
        return;
    }
    CHECK(gk_scene_step(&A, 600) == GK_OK && gk_scene_step(&B, 600) == GK_OK);
    CHECK(B.rve.pl.n >= GK_DEM_PAR_MIN); /* B's pair forces did run on 2 threads */
    s1 = state_of(&A, &n1);
    s2 = state_of(&B, &n2);
    CHECK(s1 && s2 && n1 == n2 && memcmp(s1, s2, n1) == 0);
    printf("    1 vs 2 threads after 600 steps: %s\n",
           s1 && s2 && n1 == n2 && !memcmp(s1, s2, n1) ? "identical" : "DIFFER");
    free(s1);
    free(s2);
    gk_scene_destroy(&B);
    if (full_scene(&B, 1)) {
        CHECK(0);
        gk_scene_destroy(&A);
        return;
    }
    CHECK(gk_scene_step(&A, st) == GK_OK && gk_scene_step(&B, st + 600) == GK_OK);
    s0 = state_of(&A, &n0);
    CHECK(s0 != NULL);
    CHECK(gk_scene_step(&A, st) == GK_OK);
    s1 = state_of(&A, &n1);
    /* restore in B (remove two particles first: the count changes back) and run on */
    CHECK(gk_scene_remove(&B, 2, gone) == GK_OK && B.rve.n == A.rve.n - 2);
    CHECK(gk_scene_restore(&B, s0, n0) == GK_OK);
    CHECK(B.rve.n == A.rve.n && gk_scene_index(&B, 40) >= 0);
    CHECK(gk_scene_step(&B, st) == GK_OK);
    s2 = state_of(&B, &n2);
    CHECK(s2 && n1 == n2 && memcmp(s1, s2, n1) == 0);
    printf("    state %zu bytes; the restored run %s the uninterrupted one\n", n1,
           s2 && n1 == n2 && !memcmp(s1, s2, n1) ? "matches" : "DIFFERS from");
    /* a damaged state is refused */
    s0[0] ^= 1;
    CHECK(gk_scene_restore(&B, s0, n0) == GK_ERR_FORMAT);
    CHECK(gk_scene_restore(&B, s0, 10) == GK_ERR_FORMAT);
    free(s0);
    free(s1);
    free(s2);
    gk_scene_destroy(&A);
    gk_scene_destroy(&B);
}

/* a refused state changes nothing, even one refused after its particles were read: particle 0 with a
 * thousandth of its mass (the time step is then above the critical one: GK_ERR_DT), particle 1 given
 * particle 0's id (found only after gk_rve_restore accepted the RVE part: GK_ERR_FORMAT), and both.
 * Each time the scene's state is byte for byte what it was, and it runs on. (The time step was once
 * checked against the masses of the state before, so the lighter state with the duplicate id was
 * refused only at the id, and putting the scene back then failed against the lighter masses.) The
 * offsets are found by difference: a state with particle 0 twice as heavy (gk_scene_set_mass)
 * differs first in its inverse mass, at header + n R; ids follow at header + 3 n R, masses at header
 * + 3 n R + 4 n. */
TEST(a_refused_state_changes_nothing) {
    gk_scene A;
    unsigned char *s0, *s1, *bad[3], *now;
    size_t n0, n1, nn, d = 0, H, R = sizeof(gk_real), n;
    int32_t id0;
    int b;
    const gk_result want[3] = {GK_ERR_DT, GK_ERR_FORMAT, GK_ERR_DT};
    if (full_scene(&A, 1)) {
        CHECK(0);
        return;
    }
    CHECK(gk_scene_step(&A, 200) == GK_OK);
    n = (size_t)A.rve.n;
    s0 = state_of(&A, &n0);
    CHECK(gk_scene_set_mass(&A, 0, 2.0 * A.mass[0], 2.0 / (double)A.rve.Iinv[0]) == GK_OK);
    s1 = state_of(&A, &n1);
    CHECK(s0 && s1 && n0 == n1);
    if (!s0 || !s1 || n0 != n1) return;
    while (d < n0 && s0[d] == s1[d]) ++d;
    CHECK(d >= n * R);
    H = (d - n * R) / 8 * 8; /* the header: minv[0] starts at H + n R */
    CHECK(gk_scene_restore(&A, s0, n0) == GK_OK);
    for (b = 0; b < 3; ++b) {
        bad[b] = (unsigned char *)malloc(n0);
        CHECK(bad[b] != NULL);
        if (!bad[b]) return;
        memcpy(bad[b], s0, n0);
        if (b != 1) { /* particle 0 a thousand times lighter */
            gk_real minv;
            double mass;
            memcpy(&minv, bad[b] + H + n * R, R);
            memcpy(&mass, bad[b] + H + 3 * n * R + 4 * n, sizeof mass);
            minv = (gk_real)(1e3 * (double)minv), mass *= 1e-3;
            memcpy(bad[b] + H + n * R, &minv, R);
            memcpy(bad[b] + H + 3 * n * R + 4 * n, &mass, sizeof mass);
        }
        if (b != 0) { /* particle 1 gets particle 0's id */
            memcpy(&id0, bad[b] + H + 3 * n * R, sizeof id0);
            memcpy(bad[b] + H + 3 * n * R + sizeof id0, &id0, sizeof id0);
        }
        CHECK(gk_scene_restore(&A, bad[b], n0) == want[b]);
        printf("    %s\n", gk_scene_error(&A));
        now = state_of(&A, &nn);
        CHECK(now && nn == n0 && !memcmp(now, s0, n0));
        free(now);
        free(bad[b]);
    }
    CHECK(gk_scene_restore(&A, s1, n1) == GK_OK && gk_scene_step(&A, 10) == GK_OK);
    free(s0), free(s1);
    gk_scene_destroy(&A);
}

/* Contact weights (Chen et al. eq 9: w rho dv/dt = w f + f_coupling): with
 * no damping one leap-frog step from v0 gives m (v - v0) / dt = sum over the
 * particle's pairs of s_c F_c, s_c = (w_i + w_j) / 2 and F_c the pair's
 * force in the same scene unweighted (and the moments likewise), with the
 * stress skipped (one thread scatters then and keeps no pair forces of its
 * own); momentum is kept (the scaled pair forces are equal and opposite);
 * weights of 1 change no bit; a weight outside (0, 1], now or changed in the
 * caller's array later, is refused before anything moves; energy tracking
 * and weights exclude each other; a removal forgets the weights. */
static int weighted_scene(gk_scene *sc) {
    gk_scene_def d = gk_scene_def_default();
    gk_packing pk;
    gk_rng rng;
    int p;
    d.dim = 2;
    d.periodic = 3u;
    d.hi[0] = d.hi[1] = 12 * 2.2 * 0.005;
    d.rve.mat.young = 5e7;
    d.rve.mat.friction = 0.4;
    d.rve.damping = 0.0;
    d.rve.dt_factor = 0.2;
    if (lattice(&pk, 2, 12, 12, 1, 0.005, 0.0, 0.0, 0.0, 0.3, 5)) return 1;
    for (p = 0; p < pk.n; ++p) pk.r[p] *= 1.3; /* overlapping neighbours */
    if (gk_scene_create(sc, &d, &pk) != GK_OK) return gk_packing_free(&pk), 1;
    gk_packing_free(&pk);
    gk_rng_seed(&rng, 17);
    for (p = 0; p < sc->rve.n; ++p) {
        double v[3] = {0.02 * (2.0 * gk_rng_uniform(&rng) - 1.0), 0.02 * (2.0 * gk_rng_uniform(&rng) - 1.0),
                       0},
               w[3] = {0, 0, 5.0 * (2.0 * gk_rng_uniform(&rng) - 1.0)};
        if (gk_scene_set_velocity(sc, p, v, w) != GK_OK) return 1;
    }
    return 0;
}

TEST(contact_weights_scale_pair_forces) {
    gk_scene A, B;
    gk_rng rng;
    double w[144], ones[144], v0[2][144], w0[144], fx = 0.0, fy = 0.0, fmax = 0.0, tmax = 0.0, ferr = 0.0,
                                                   terr = 0.0, px = 0.0, py = 0.0;
    int p, c, k, n;
    CHECK(weighted_scene(&A) == 0 && weighted_scene(&B) == 0);
    n = A.rve.n;
    CHECK(n == 144 && B.rve.n == n);
    gk_rng_seed(&rng, 3);
    for (p = 0; p < n; ++p) {
        w[p] = p % 3 == 0 ? 1.0 : 0.3 + 0.7 * gk_rng_uniform(&rng);
        ones[p] = 1.0;
        for (k = 0; k < 2; ++k) v0[k][p] = (double)A.rve.v[k][p];
        w0[p] = (double)A.rve.w[2][p];
    }
    CHECK(gk_scene_weight_contacts(&A, w) == GK_OK && A.cw == w);
    CHECK(gk_scene_step_flags(&A, 1, GK_STEP_NO_STRESS) == GK_OK);
    CHECK(gk_scene_step(&B, 1) == GK_OK); /* B keeps its pair forces F_c */
    CHECK(A.rve.pl.n == B.rve.pl.n && B.rve.ncontacts > 100);
    {
        double *fe[3], *te = (double *)calloc((size_t)n, sizeof(double));
        for (k = 0; k < 2; ++k) fe[k] = (double *)calloc((size_t)n, sizeof(double));
        for (c = 0; c < B.rve.pl.n; ++c) {
            int i = B.rve.pl.i[c], j = B.rve.pl.j[c];
            double s = 0.5 * (w[i] + w[j]);
            CHECK(A.rve.pl.i[c] == i && A.rve.pl.j[c] == j);
            for (k = 0; k < 2; ++k) {
                fe[k][i] -= s * (double)B.rve.fc[k][c];
                fe[k][j] += s * (double)B.rve.fc[k][c];
            }
            te[i] += s * (double)B.rve.tci[2][c];
            te[j] += s * (double)B.rve.tcj[2][c];
        }
        for (p = 0; p < n; ++p) {
            double m = A.mass[p], I = 1.0 / (double)A.rve.Iinv[p], dt = A.rve.dt;
            double ax = m * ((double)A.rve.v[0][p] - v0[0][p]) / dt,
                   ay = m * ((double)A.rve.v[1][p] - v0[1][p]) / dt;
            double at = I * ((double)A.rve.w[2][p] - w0[p]) / dt;
            fmax = fmax > fabs(fe[0][p]) + fabs(fe[1][p]) ? fmax : fabs(fe[0][p]) + fabs(fe[1][p]);
            tmax = tmax > fabs(te[p]) ? tmax : fabs(te[p]);
            ferr = ferr > fabs(ax - fe[0][p]) + fabs(ay - fe[1][p])
                       ? ferr
                       : fabs(ax - fe[0][p]) + fabs(ay - fe[1][p]);
            terr = terr > fabs(at - te[p]) ? terr : fabs(at - te[p]);
            fx += fabs(ax), fy += fabs(ay);
            px += m * ((double)A.rve.v[0][p] - v0[0][p]);
            py += m * ((double)A.rve.v[1][p] - v0[1][p]);
        }
        free(te), free(fe[0]), free(fe[1]);
    }
    printf("    largest force %.4g N, error %.3g N; largest moment %.4g N m, error %.3g N m; net impulse "
           "%.3g, %.3g\n",
           fmax, ferr, tmax, terr, px, py);
    CHECK(fmax > 0.0 && tmax > 0.0);
    CHECK(ferr <= 1e-9 * fmax && terr <= 1e-9 * tmax);
    CHECK(fabs(px) + fabs(py) <= 1e-12 * (fx + fy) * A.rve.dt);
    gk_scene_destroy(&A);
    gk_scene_destroy(&B);
    /* weights of 1: the same bits as none */
    CHECK(weighted_scene(&A) == 0 && weighted_scene(&B) == 0);
    CHECK(gk_scene_weight_contacts(&A, ones) == GK_OK);
    CHECK(gk_scene_step_flags(&A, 20, GK_STEP_NO_STRESS) == GK_OK &&
          gk_scene_step_flags(&B, 20, GK_STEP_NO_STRESS) == GK_OK);
    for (p = 0, c = 0; p < n; ++p)
        for (k = 0; k < 2; ++k) c += A.rve.s[k][p] != B.rve.s[k][p] || A.rve.v[k][p] != B.rve.v[k][p];
    CHECK(c == 0);
    /* refused: nothing moves */
    {
        double keep = ones[7], x0[3], x1[3];
        long step = A.rve.step;
        const double bad[3] = {0.0, 1.5, NAN};
        for (k = 0; k < 3; ++k) {
            ones[7] = bad[k];
            CHECK(gk_scene_weight_contacts(&A, w) == GK_OK);
            CHECK(gk_scene_weight_contacts(&A, ones) == GK_ERR_ARG && A.cw == w);
            printf("    %s\n", gk_scene_error(&A));
        }
        ones[7] = keep;
        CHECK(gk_scene_weight_contacts(&A, ones) == GK_OK);
        ones[7] = 2.0; /* the caller's array changed after it was given */
        gk_scene_position(&A, 7, x0);
        CHECK(gk_scene_step(&A, 5) == GK_ERR_ARG && A.rve.step == step);
        gk_scene_position(&A, 7, x1);
        CHECK(x0[0] == x1[0] && x0[1] == x1[1]);
        ones[7] = keep;
        CHECK(gk_scene_energy_track(&A, 1) == GK_ERR_STATE && !A.energy_on);
        CHECK(gk_scene_weight_contacts(&B, ones) == GK_OK && gk_scene_weight_contacts(&B, NULL) == GK_OK &&
              B.cw == NULL && gk_scene_energy_track(&B, 1) == GK_OK);
        CHECK(gk_scene_weight_contacts(&B, ones) == GK_ERR_STATE && B.cw == NULL);
        /* a removal changes the indices: the weights are forgotten; so does a restore to another
         * particle count, and one to the same count keeps them */
        {
            int32_t id = A.rve.id[3];
            size_t n0, n1;
            unsigned char *s0 = state_of(&A, &n0), *s1;
            CHECK(gk_scene_remove(&A, 1, &id) == GK_OK && A.cw == NULL && !A.rve.hook_pairs);
            CHECK(gk_scene_step(&A, 1) == GK_OK);
            s1 = state_of(&A, &n1);
            CHECK(s0 && s1 && gk_scene_weight_contacts(&A, ones) == GK_OK);
            CHECK(gk_scene_restore(&A, s1, n1) == GK_OK && A.cw == ones);
            CHECK(gk_scene_restore(&A, s0, n0) == GK_OK && A.cw == NULL && A.rve.n == n);
            free(s0), free(s1);
        }
    }
    gk_scene_destroy(&A);
    gk_scene_destroy(&B);
}

/* gk_scene_set_mass: a lighter particle lowers an automatic time step (as a new wall does) and
 * is refused with an explicit one above the critical step it gives, nothing changed (Guo & Zhao
 * 2014 eq 19: dt_cr = sqrt(m_min / k_n)) */
TEST(set_mass_keeps_the_time_step_stable) {
    gk_scene A;
    double dt0, m0, dtc;
    gk_real minv0;
    if (full_scene(&A, 1)) {
        CHECK(0);
        return;
    }
    dt0 = A.rve.dt, m0 = A.mass[3], minv0 = A.rve.minv[3];
    CHECK(gk_scene_set_mass(&A, 3, 1e-4 * m0, 1e-4 / (double)A.rve.Iinv[3]) == GK_OK);
    dtc = gk_scene_dt_critical(&A);
    printf("    automatic dt %g s -> %g s (0.2 of the critical %g s)\n", dt0, A.rve.dt, dtc);
    CHECK(A.rve.dt < dt0 && A.rve.dt <= 0.2 * dtc * (1.0 + 1e-12));
    CHECK(gk_scene_step(&A, 100) == GK_OK);
    CHECK(gk_scene_set_mass(&A, 3, m0, 1.0 / (double)minv0) == GK_OK);
    A.def.rve.dt = A.rve.dt;                                                   /* now explicit */
    CHECK(gk_scene_set_mass(&A, 3, 1e-4 * m0, 1e-4 / (double)minv0) == GK_OK); /* the same dt holds */
    CHECK(gk_scene_set_mass(&A, 3, 1e-6 * m0, 1e-6 / (double)minv0) == GK_ERR_DT);
    printf("    %s\n", gk_scene_error(&A));
    CHECK(A.mass[3] == 1e-4 * m0 || fabs(A.mass[3] / (1e-4 * m0) - 1.0) < 1e-12);
    gk_scene_destroy(&A);
}

/* mean height of row b of a lattice() packing of nx per row (ids b nx .. b nx + nx - 1) */
static double row_height(const gk_scene *sc, int nx, int b) {
    double x[3], y = 0.0;
    int a;
    for (a = 0; a < nx; ++a) {
        gk_scene_position(sc, gk_scene_index(sc, b * nx + a), x);
        y += x[1];
    }
    return y / nx;
}

/* Periodic in x, walls in y: a layer sheared between a fixed rough floor
 * and a rough lid moving along x (servo in y to a normal force): particles
 * wrap in x and stay in the period; in steady shear the floor and the lid
 * hold equal and opposite shear forces (means over 20 000 steps, 5 %), the
 * servo holds the normal force (2 %), the shear resistance is
 * frictional (between 0.05 and the contact friction 0.5 times the normal
 * force); gk_scene_stress_box against gk_scene_stress and the lid (below). */
TEST(periodic_shear_between_walls) {
    gk_scene_def d = gk_scene_def_default();
    gk_scene sc;
    gk_packing pk;
    gk_wall_def lid = gk_wall_def_default(), flo = gk_wall_def_default();
    double r = 0.0025, W = 20 * 2.2 * r, N = 200.0, ratio, shear, floor_shear, normal, s[9], strip_xy = 0.0;
    double shear_stress;
    double mid_lo[3] = {0.0, 0.0, 0.0}, mid_hi[3] = {0.0, 0.0, 0.0};
    int p, bad = 0;
    d.dim = 2;
    d.hi[0] = W;
    d.hi[1] = 0.1;
    d.periodic = 1u;
    d.rve.mat.young = 5e7;
    d.rve.mat.friction = 0.5;
    d.rve.mat.zeta_n = 0.2;
    d.rve.damping = 0.1;
    d.rve.dt_factor = 0.2;
    CHECK(lattice(&pk, 2, 20, 12, 1, r, 0.0, 0.0, 0.0, 0.1, 13) == 0);
    CHECK(gk_scene_create(&sc, &d, &pk) == GK_OK);
    gk_packing_free(&pk);
    flo.normal[1] = 1.0;
    flo.mat = d.rve.mat;
    flo.mat.friction = 1.0;
    lid = flo;
    lid.point[1] = 12 * 2.2 * r + 0.002;
    lid.normal[1] = -1.0;
    lid.drive = GK_DRIVE_FORCE;
    lid.target = N;
    lid.max_speed = 0.05;
    CHECK(gk_scene_add_wall(&sc, &flo, NULL) == GK_OK && gk_scene_add_wall(&sc, &lid, NULL) == GK_OK);
    CHECK(gk_scene_step(&sc, 10000) == GK_OK); /* consolidate */
    sc.walls[1].def.velocity[0] = 0.05;        /* servo in y, sliding at 5 cm/s in x */
    CHECK(gk_scene_step(&sc, 15000) == GK_OK);
    mid_hi[0] = W; /* from the centre line of row 3 to that of row 8 (below) */
    mid_lo[1] = row_height(&sc, 20, 3);
    mid_hi[1] = row_height(&sc, 20, 8);
    { /* averages over the next 20000 steps (the forces fluctuate) */
        int k;
        double sl = 0.0, sf = 0.0, sn = 0.0;
        for (k = 0; k < 100; ++k) {
            CHECK(gk_scene_step(&sc, 200) == GK_OK);
            sl -= sc.walls[1].force[0]; /* the particles resist the lid's motion */
            sf += sc.walls[0].force[0];
            sn += sc.walls[1].resistance;
            gk_scene_stress_box(&sc, mid_lo, mid_hi, s);
            strip_xy += s[1];
        }
        shear = sl / 100;
        floor_shear = sf / 100;
        normal = sn / 100;
        strip_xy /= 100;
    }
    ratio = shear / normal;
    printf("    lid normal %.4g N (target %g), shear %.4g N, floor shear %.4g N, ratio %.3f (means)\n",
           normal, N, shear, floor_shear, ratio);
    CHECK_NEAR(floor_shear, shear, 0.05 * fabs(shear));
    /* gk_scene_stress_box. (a) The box holding every contact is the pair
     * part of gk_scene_stress (its wall part left out) over the box's area,
     * but for the branch vectors: the step sums its stress with those at
     * force time, the box with those after the step's move, which changes a
     * branch by the relative motion of one step, at most the lid's speed x
     * dt (4e-5 of a diameter here): 10 x that share of |sigma_yy|. */
    {
        double all_lo[3] = {0.0, -0.1, 0.0}, all_hi[3] = {W, 0.2, 0.0}, A = W * 0.3, pair[9];
        double tol = 10.0 * 0.05 * sc.rve.dt / (1.6 * r);
        int k;
        CHECK(gk_scene_stress_box(&sc, all_lo, all_hi, s) == GK_OK);
        for (k = 0; k < 9; ++k)
            pair[k] = sc.rve.stress[k] * gk_rve_volume(&sc.rve) / (A * sc.rve.volume_factor);
        printf(
            "    box of everything: sigma_xy %.6g, sigma_yy %.6g Pa; the pair part of gk_scene_stress %.6g, "
            "%.6g Pa\n",
            s[1], s[4], pair[1], pair[4]);
        for (k = 0; k < 9; ++k) CHECK_NEAR(s[k], pair[k], tol * fabs(pair[4]));
    }
    /* (b) Equilibrium of the layer above any horizontal section: the mean
     * sigma_xy (tension-positive; the lid drags the top along +x) of the
     * strip between the centre lines of rows 3 and 8 (its five layers of
     * row-to-row contacts whole) is the lid's shear force over W t (Cauchy,
     * t_x = sigma_xy n_y on the lid), within the 10 % that a contact-midpoint
     * average over five rows of 20 disks leaves. */
    shear_stress = shear / (W * sc.rve.volume_factor);
    printf("    strip y %.4g-%.4g m: sigma_xy %.4g Pa (mean of 100), lid shear / W t %.4g Pa\n", mid_lo[1],
           mid_hi[1], strip_xy, shear_stress);
    CHECK_NEAR(strip_xy, shear_stress, 0.10 * shear_stress);
    { /* (c) a box that is empty or not finite is refused, sigma untouched */
        double bad_hi[3] = {W, 0.0, 0.0}, nan_lo[3] = {0.0, 0.0, 0.0};
        bad_hi[1] = mid_lo[1];
        s[0] = 42.0;
        CHECK(gk_scene_stress_box(&sc, mid_lo, bad_hi, s) == GK_ERR_ARG);
        nan_lo[1] = NAN;
        CHECK(gk_scene_stress_box(&sc, nan_lo, mid_hi, s) == GK_ERR_ARG);
        CHECK(s[0] == 42.0);
    }
    { /* (d) unknown step flags are refused before anything moves */
        long st = sc.rve.step;
        CHECK(gk_scene_step_flags(&sc, 1, 4u) == GK_ERR_ARG && sc.rve.step == st);
    }
    CHECK_REL(normal, N, 0.02);
    CHECK(ratio > 0.05 && ratio < 0.5);
    for (p = 0; p < sc.rve.n; ++p) {
        double x[3];
        gk_scene_position(&sc, p, x);
        if (!(x[0] >= 0.0 && x[0] < W)) ++bad;
    }
    CHECK(bad == 0);
    gk_scene_destroy(&sc);
}

/* gk_packing_tile: the Guo & Zhao 2014 RVE repeated 2 x 1 is the same periodic
 * material - its Love stress (after a force refresh) is the original's to
 * 1e-9 - with twice the particles and cell; gk_packing_subset: exactly the
 * particles (wholly) inside the box, in order, shifted to its corner. */
TEST(packing_tile_and_subset) {
    gk_packing pk, t, sub;
    gk_err e;
    gk_rve a, b;
    gk_rve_def def = gk_rve_def_default();
    double sa[9], sb[9], lo[3] = {0.02, 0.03, 0}, hi[3] = {0.15, 0.12, 0};
    int p, cnt = 0, q = 0, ok = 1;
    if (gk_packing_read("examples/data/rve400.txt", &pk, NULL, &e)) {
        printf("    %s\n", e.msg);
        CHECK(0);
        return;
    }
    CHECK(gk_packing_tile(&pk, 2, 1, 1, &t, NULL, &e) == GK_OK);
    CHECK(t.n == 800 && t.h[0] == 2.0 * pk.h[0] && t.h[4] == pk.h[4]);
    CHECK(gk_rve_create(&a, &def, &pk) == GK_OK && gk_rve_create(&b, &def, &t) == GK_OK);
    CHECK(gk_rve_refresh(&a) == GK_OK && gk_rve_refresh(&b) == GK_OK);
    gk_rve_stress(&a, sa);
    gk_rve_stress(&b, sb);
    printf("    sigma_xx %.10g vs tiled %.10g Pa, sigma_xy %.6g vs %.6g\n", sa[0], sb[0], sa[1], sb[1]);
    CHECK_REL(sb[0], sa[0], 1e-9);
    CHECK_REL(sb[4], sa[4], 1e-9);
    CHECK_NEAR(sb[1], sa[1], 1e-9 * fabs(sa[0]));
    gk_rve_destroy(&a);
    gk_rve_destroy(&b);
    CHECK(gk_packing_subset(&t, lo, hi, 1, &sub, NULL, &e) == GK_OK);
    for (p = 0; p < t.n; ++p)
        if (t.x[p] - t.r[p] >= lo[0] && t.x[p] + t.r[p] <= hi[0] && t.y[p] - t.r[p] >= lo[1] &&
            t.y[p] + t.r[p] <= hi[1]) {
            ++cnt;
            if (q < sub.n && (sub.x[q] != t.x[p] - lo[0] || sub.y[q] != t.y[p] - lo[1] || sub.r[q] != t.r[p]))
                ok = 0;
            ++q;
        }
    CHECK(sub.n == cnt && ok);
    CHECK(sub.h[0] == hi[0] - lo[0] && sub.h[4] == hi[1] - lo[1]);
    printf("    subset: %d of %d particles in the box\n", sub.n, t.n);
    /* bad boxes and counts are refused */
    CHECK(gk_packing_subset(&t, hi, lo, 1, &sub, NULL, &e) == GK_ERR_ARG);
    CHECK(gk_packing_tile(&pk, 0, 1, 1, &t, NULL, &e) == GK_ERR_ARG);
    gk_packing_free(&sub);
    gk_packing_free(&t);
    gk_packing_free(&pk);
}

/* Bodies: a disk (2D pipe) pushed down at constant speed into a settled bed
 * meets a resistance that grows with its depth (means over 3000 steps); a drum (particles inside a
 * disk) turning counter-clockwise drags its bed up on its right (centre of
 * mass to +x) and the bed's moment on it opposes the turn; a sphere resting
 * on a 3D rectangle or inside a horizontal cylinder presses on it with its
 * weight; one beyond the rectangle's edge falls past it. */
TEST(bodies_pipe_drum_rectangle_cylinder) {
    gk_scene sc;
    gk_wall_def pipe = gk_wall_def_default(), drum = gk_wall_def_default();
    int ip, k, p;
    double f1, f2;
    /* pipe */
    if (box_scene(&sc, 2, 16, 10, 0.16, 0.3, 0.3, 0)) {
        CHECK(0);
        return;
    }
    CHECK(gk_scene_step(&sc, QUICK(15000, 8000)) == GK_OK);
    pipe.kind = GK_WALL_DISK;
    pipe.radius = 0.02;
    pipe.point[0] = 0.08;
    for (p = 0; p < sc.rve.n; ++p) { /* just above the bed */
        double x[3];
        gk_scene_position(&sc, p, x);
        if (x[1] + (double)sc.rve.r[p] + pipe.radius + 0.001 > pipe.point[1])
            pipe.point[1] = x[1] + (double)sc.rve.r[p] + pipe.radius + 0.001;
    }
    pipe.mat = sc.def.rve.mat;
    pipe.velocity[1] = -0.2;
    CHECK(gk_scene_add_wall(&sc, &pipe, &ip) == GK_OK);
    f1 = f2 = 0.0;
    for (k = 0; k < 60; ++k) { /* mean uplift over the first and the second 3000 steps */
        CHECK(gk_scene_step(&sc, 100) == GK_OK);
        if (k < 30)
            f1 += sc.walls[ip].force[1] / 30;
        else
            f2 += sc.walls[ip].force[1] / 30;
    }
    printf("    pipe: mean uplift %.4g N, then %.4g N (now at y = %.4f m)\n", f1, f2, sc.walls[ip].pos[1]);
    CHECK(f1 > 0.0 && f2 > f1);
    gk_scene_destroy(&sc);
    /* drum */
    {
        gk_scene_def d = gk_scene_def_default();
        gk_packing pk;
        double cm = 0.0, M = 0.0;
        d.dim = 2;
        d.lo[0] = d.lo[1] = -0.1;
        d.hi[0] = d.hi[1] = 0.1;
        d.gravity[1] = -9.81;
        d.rve.mat.young = 5e7;
        d.rve.mat.friction = 0.5;
        d.rve.mat.zeta_n = 0.3;
        d.rve.dt_factor = 0.2;
        CHECK(lattice(&pk, 2, 10, 5, 1, 0.004, -0.044, -0.07, 0, 0.1, 17) == 0);
        CHECK(gk_scene_create(&sc, &d, &pk) == GK_OK);
        gk_packing_free(&pk);
        drum.kind = GK_WALL_DISK;
        drum.inside = 1;
        drum.radius = 0.09;
        drum.mat = d.rve.mat;
        drum.mat.friction = 0.8;
        drum.spin[2] = 2.0;
        CHECK(gk_scene_add_wall(&sc, &drum, &ip) == GK_OK);
        CHECK(gk_scene_step(&sc, QUICK(20000, 12000)) == GK_OK);
        for (p = 0; p < sc.rve.n; ++p) {
            double x[3];
            gk_scene_position(&sc, p, x);
            cm += sc.mass[p] * x[0];
            M += sc.mass[p];
        }
        printf("    drum: centre of mass x = %.4f m, moment on the drum %.4g N m\n", cm / M,
               sc.walls[ip].moment[2]);
        CHECK(cm / M > 0.005);
        CHECK(sc.walls[ip].moment[2] < 0.0);
        for (p = 0; p < sc.rve.n; ++p) {
            double x[3];
            gk_scene_position(&sc, p, x);
            CHECK(x[0] * x[0] + x[1] * x[1] < 0.09 * 0.09);
        }
        gk_scene_destroy(&sc);
    }
    /* 3D: a rectangle and a cylinder */
    for (k = 0; k < 3; ++k) {
        gk_scene_def d = gk_scene_def_default();
        gk_packing pk;
        gk_err e;
        gk_wall_def w = gk_wall_def_default();
        double m;
        d.dim = 3;
        for (p = 0; p < 3; ++p) {
            d.lo[p] = -0.2;
            d.hi[p] = 0.2;
        }
        d.gravity[1] = -9.81;
        d.rve.mat.young = 5e7;
        d.rve.mat.zeta_n = 0.5;
        d.rve.damping = 0.3;
        d.rve.dt_factor = 0.2;
        CHECK(gk_packing_init(&pk, 3, 1, NULL, &e) == GK_OK);
        pk.r[0] = 0.01;
        pk.x[0] = k == 1 ? 0.06 : 0.0; /* k = 1: beyond the rectangle's edge */
        pk.y[0] = k == 2 ? -0.05 : 0.012;
        CHECK(gk_scene_create(&sc, &d, &pk) == GK_OK);
        gk_packing_free(&pk);
        w.mat = d.rve.mat;
        if (k < 2) {
            w.kind = GK_WALL_RECT;
            w.point[0] = -0.05;
            w.point[2] = -0.05;
            w.e1[0] = 0.1;
            w.e2[2] = 0.1;
        } else {
            w.kind = GK_WALL_CYLINDER;
            w.inside = 1;
            w.radius = 0.08;
            w.axis[2] = 1.0;
        }
        CHECK(gk_scene_add_wall(&sc, &w, NULL) == GK_OK);
        CHECK(gk_scene_step(&sc, k == 1 ? 6000 : QUICK(20000, 10000)) == GK_OK);
        m = sc.mass[0];
        if (k == 1) {
            double x[3];
            gk_scene_position(&sc, 0, x);
            CHECK(sc.walls[0].ncontacts == 0 && x[1] < -0.02);
        } else {
            printf("    sphere on a %s: force %.6g N, weight %.6g N\n", k ? "cylinder" : "rectangle",
                   -sc.walls[0].force[1], m * 9.81);
            CHECK_REL(-sc.walls[0].force[1], m * 9.81, 1e-3);
        }
        gk_scene_destroy(&sc);
    }
}

/* A particle thrown out of an open domain is an error (nothing moves on)
 * or, with GK_LOST_DELETE, is deleted and counted; the run goes on. */
TEST(lost_particles) {
    int pol;
    for (pol = 0; pol < 2; ++pol) {
        gk_scene sc;
        double v[3] = {0, 30.0, 0};
        gk_result r;
        if (box_scene(&sc, 2, 6, 6, 0.1, 0.3, 0.0, 0)) {
            CHECK(0);
            continue;
        }
        sc.def.lost = pol ? GK_LOST_DELETE : GK_LOST_ERROR;
        CHECK(gk_scene_set_velocity(&sc, gk_scene_index(&sc, 35), v, NULL) == GK_OK);
        r = gk_scene_step(&sc, 5000);
        if (pol == 0) {
            printf("    error: %s\n", gk_scene_error(&sc));
            CHECK(r == GK_ERR_OUTSIDE && strstr(gk_scene_error(&sc), "left the open domain") != NULL);
            CHECK(sc.rve.n == 36);
        } else {
            CHECK(r == GK_OK && sc.lost == 1 && sc.rve.n == 35 && gk_scene_index(&sc, 35) == -1);
        }
        gk_scene_destroy(&sc);
    }
}

/* Bad input gets a clear error and changes nothing. */
TEST(bad_input_is_refused) {
    gk_scene sc;
    gk_scene_def d = gk_scene_def_default();
    gk_wall_def w = gk_wall_def_default();
    gk_packing pk;
    gk_material m = gk_material_default(), out;
    gk_err e;
    int nw;
    double nanv[3] = {NAN, 0, 0};
    CHECK(lattice(&pk, 2, 4, 4, 1, 0.005, 0.0, 0.0, 0.0, 0.0, 1) == 0);
    d.dim = 2;
    d.hi[0] = d.hi[1] = 0.1;
    {
        gk_scene_def b = d;
        b.cookie = 0;
        CHECK(gk_scene_create(&sc, &b, &pk) == GK_ERR_ARG);
        b = d;
        b.hi[0] = -1.0;
        CHECK(gk_scene_create(&sc, &b, &pk) == GK_ERR_CELL);
        b = d;
        b.hi[0] = 0.03; /* particles beyond the open domain */
        CHECK(gk_scene_create(&sc, &b, &pk) == GK_ERR_OUTSIDE);
        b = d;
        b.dim = 3;
        CHECK(gk_scene_create(&sc, &b, &pk) == GK_ERR_ARG);
        b = d;
        b.gravity[1] = NAN;
        CHECK(gk_scene_create(&sc, &b, &pk) == GK_ERR_NAN);
        b = d;
        b.periodic = 4u;
        CHECK(gk_scene_create(&sc, &b, &pk) == GK_ERR_ARG);
    }
    CHECK(gk_scene_create(&sc, &d, &pk) == GK_OK);
    gk_packing_free(&pk);
    nw = sc.nwalls;
    w.normal[1] = 2.0; /* not a unit vector */
    CHECK(gk_scene_add_wall(&sc, &w, NULL) == GK_ERR_ARG);
    w.normal[1] = 1.0;
    w.kind = GK_WALL_RECT; /* 3D only */
    CHECK(gk_scene_add_wall(&sc, &w, NULL) == GK_ERR_ARG);
    w.kind = GK_WALL_PLANE;
    w.drive = GK_DRIVE_FORCE; /* no max_speed */
    CHECK(gk_scene_add_wall(&sc, &w, NULL) == GK_ERR_ARG);
    w.drive = GK_DRIVE_VELOCITY;
    w.point[0] = NAN;
    CHECK(gk_scene_add_wall(&sc, &w, NULL) == GK_ERR_NAN);
    w.point[0] = 0.0;
    w.mat.young = 6e12; /* far stiffer than the time step allows */
    d.rve.dt = sc.rve.dt;
    sc.def.rve.dt = sc.rve.dt; /* an explicit dt is checked, not reduced */
    CHECK(gk_scene_add_wall(&sc, &w, NULL) == GK_ERR_DT);
    printf("    %s\n", gk_scene_error(&sc));
    CHECK(sc.nwalls == nw);
    CHECK(gk_scene_prescribe(&sc, 99, NULL, NULL) == GK_ERR_ARG);
    CHECK(gk_scene_set_external(&sc, 0, nanv, NULL) == GK_ERR_NAN);
    CHECK(gk_scene_set_mass(&sc, 0, -1.0, 1.0) == GK_ERR_MASS);
    {
        int32_t ids[2] = {0, 1};
        CHECK(gk_scene_add_membrane(&sc, 1, ids, 1e4, 0.0, -1, -1, NULL) == GK_ERR_ARG);
        CHECK(gk_scene_add_membrane(&sc, 2, ids, 1e4, 0.0, 5, -1, NULL) == GK_ERR_ARG);
        ids[1] = 99;
        CHECK(gk_scene_add_membrane(&sc, 2, ids, 1e4, 0.0, -1, -1, NULL) == GK_ERR_ARG);
    }
    CHECK(gk_scene_step(&sc, -1) == GK_ERR_ARG);
    m.law = GK_LAW_HERTZ;
    m.poisson = 0.3;
    CHECK(gk_scene_pair_material(&m, &sc.def.rve.mat, &out, &e) == GK_ERR_ARG); /* laws differ */
    CHECK(sc.rve.n == 16 && sc.nwalls == nw && sc.nmem == 0 && sc.nprescribed == 0);
    gk_scene_destroy(&sc);
}

/* the lid stress and sigma_xx of dem_biaxial's first CSV row (the
 * consolidated state); 0 if the file or the row is missing, lid = sxx = NaN */
static int dembx_consolidated(const char *csv, double *lid, double *sxx) {
    FILE *fp = fopen(csv, "r");
    char line[512];
    double e;
    int ok = fp && fgets(line, sizeof line, fp) && fgets(line, sizeof line, fp) &&
             sscanf(line, "%lf,%lf,%lf", &e, lid, sxx) == 3;
    if (fp) fclose(fp);
    if (!ok) *lid = *sxx = NAN;
    return ok;
}

/* examples/dem_biaxial.c on one 400-disk tile to 1 % strain: it writes its
 * documented outputs and RESULT; the platen stress at consolidation is the
 * confining pressure (2 %) and the membranes hold sigma_xx there (10 % in
 * this 400-disk specimen); the
 * specimen hardens (sigma_yy grows, the stress ratio mobilises friction:
 * 0.1 to 0.8); bad arguments are refused by name, a failed write exits 1. */
TEST(dem_biaxial_smoke) {
    double ratio, n;
    int rc;
    rc = system(BUILD "/dem_biaxial --tiles 1x1 --strain 0.01 --every 0.002 --pictures 0.004 --quiet "
                      "--out " BUILD "/tests/t_dembx > " BUILD "/tests/t_dembx.out 2>&1");
    CHECK(rc == 0);
    CHECK(gk_test_file_has(
        BUILD "/tests/t_dembx/biaxial.csv",
        "eps_axial,sigma_yy_lid,sigma_xx,sigma_yy,eps_vol,stress_ratio,phi_deg,coordination"));
    CHECK(gk_test_file_has(BUILD "/tests/t_dembx/particles_001.vtk", "POINT_DATA"));
    CHECK(gk_test_file_has(BUILD "/tests/t_dembx/walls_end.vtk", "CELL_DATA"));
    CHECK(gk_test_file_has(BUILD "/tests/t_dembx/particles_000.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_dembx/biaxial_stress.svg", "<svg"));
    ratio = gk_test_result(BUILD "/tests/t_dembx.out", "peak_ratio");
    n = gk_test_result(BUILD "/tests/t_dembx.out", "n");
    printf("    n %g, peak stress ratio %.4f at %.4f, sigma_yy peak %.4g Pa\n", n, ratio,
           gk_test_result(BUILD "/tests/t_dembx.out", "eps_peak"),
           gk_test_result(BUILD "/tests/t_dembx.out", "syy_peak"));
    CHECK(n == 400);
    CHECK(ratio > 0.1 && ratio < 0.8);
    CHECK(gk_test_result(BUILD "/tests/t_dembx.out", "syy_peak") > 1.2e5);
    {
        double lid, sxx;
        CHECK(dembx_consolidated(BUILD "/tests/t_dembx/biaxial.csv", &lid, &sxx));
        CHECK_REL(lid, 1e5, 0.02);
        CHECK_REL(sxx, 1e5, 0.1);
    }
    CHECK(WEXITSTATUS(system(BUILD "/dem_biaxial --strain abc > " BUILD "/tests/t_dembx.err 2>&1")) == 2);
    CHECK(gk_test_file_has(BUILD "/tests/t_dembx.err", "--strain 'abc' is not a finite number"));
    CHECK(WEXITSTATUS(system(BUILD "/dem_biaxial --strain 0.01 --every 0.02 > " BUILD
                                   "/tests/t_dembx.err 2>&1")) == 2);
    CHECK(gk_test_file_has(BUILD "/tests/t_dembx.err", "--every 0.02: need a strain in (0, --strain]"));
    CHECK(WEXITSTATUS(system(BUILD "/dem_biaxial --tiles 0x2 > " BUILD "/tests/t_dembx.err 2>&1")) == 2);
    CHECK(gk_test_file_has(BUILD "/tests/t_dembx.err", "--tiles"));
    CHECK(WEXITSTATUS(system(BUILD "/dem_biaxial --bogus 1 > " BUILD "/tests/t_dembx.err 2>&1")) == 2);
    CHECK(gk_test_file_has(BUILD "/tests/t_dembx.err", "unknown option --bogus"));
    CHECK(WEXITSTATUS(system(BUILD "/dem_biaxial --tiles 1x1 --strain 0.002 --every 0.001 --quiet "
                                   "--out /proc/no_such_dir > " BUILD "/tests/t_dembx.err 2>&1")) == 1);
    CHECK(system(BUILD "/dem_biaxial --help > " BUILD "/tests/t_dembx.err 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_dembx.err", "RESULT"));
}

/* dem_biaxial --generate: a generated packing is consolidated in a box
 * (gk_consolidate_def.box), so it is a rectangular cell the driver can cut
 * between flat platens; a sheared cell was refused ("the packing must be 2D
 * in a rectangular cell") on every --generate run. 228 disks, 0.2 % strain:
 * the run completes with all its disks and the lid carries the confining
 * pressure at consolidation (2 %). */
TEST(dem_biaxial_generate) {
    CHECK(system(BUILD
                 "/dem_biaxial --generate 228 --tiles 1x1 --strain 0.002 --every 0.001 --pictures 0.001 "
                 "--quiet --out " BUILD "/tests/t_dembx_gen > " BUILD "/tests/t_dembx_gen.out 2>&1") == 0);
    CHECK(gk_test_result(BUILD "/tests/t_dembx_gen.out", "n") == 228);
    {
        double lid, sxx;
        CHECK(dembx_consolidated(BUILD "/tests/t_dembx_gen/biaxial.csv", &lid, &sxx));
        CHECK_REL(lid, 1e5, 0.02);
    }
}

/* examples/dem_collapse.c on a small column (8 disks across, 0.6 s): the
 * outputs and RESULT; the column spreads (d* > 0.3) and loses height,
 * energy is dissipated, not created (0 < E_d <= 1), the scene's books
 * close (balance below 1e-3 of E_p0); bad arguments are refused by name. */
TEST(dem_collapse_smoke) {
    double ds, ed, bal, h;
    CHECK(system(BUILD "/dem_collapse --diameters 8 --t-end 0.6 --every 0.02 --snapshots 0.3 --quiet "
                       "--out " BUILD "/tests/t_demcl > " BUILD "/tests/t_demcl.out 2>&1") == 0);
    CHECK(gk_test_file_has(BUILD "/tests/t_demcl/collapse.csv",
                           "time,front,dstar,height,Ek_over_Ep0,Ep_over_Ep0,Ed_over_Ep0"));
    CHECK(gk_test_file_has(BUILD "/tests/t_demcl/particles_001.vtk", "POINT_DATA"));
    CHECK(gk_test_file_has(BUILD "/tests/t_demcl/walls_000.vtk", "CELL_DATA"));
    CHECK(gk_test_file_has(BUILD "/tests/t_demcl/collapse_front.svg", "<svg"));
    CHECK(gk_test_file_has(BUILD "/tests/t_demcl/collapse_energy.svg", "<svg"));
    ds = gk_test_result(BUILD "/tests/t_demcl.out", "dstar");
    ed = gk_test_result(BUILD "/tests/t_demcl.out", "Ed_final_over_Ep0");
    bal = gk_test_result(BUILD "/tests/t_demcl.out", "energy_balance");
    h = gk_test_result(BUILD "/tests/t_demcl.out", "height_over_H0");
    printf("    d* %.4f, E_d %.4f E_p0, height %.4f H0, balance %.2e E_p0\n", ds, ed, h, bal);
    CHECK(ds > 0.3);
    CHECK(ed > 0.0 && ed <= 1.0);
    CHECK(h < 1.0);
    CHECK(fabs(bal) < 1e-3);
    CHECK(WEXITSTATUS(system(BUILD "/dem_collapse --a 20 > " BUILD "/tests/t_demcl.err 2>&1")) == 2);
    CHECK(gk_test_file_has(BUILD "/tests/t_demcl.err",
                           "--a 20 is out of range: needs an aspect ratio in [0.2, 10]"));
    CHECK(WEXITSTATUS(system(BUILD "/dem_collapse --snapshots 1,0.5 > " BUILD "/tests/t_demcl.err 2>&1")) ==
          2);
    CHECK(gk_test_file_has(BUILD "/tests/t_demcl.err", "--snapshots"));
    CHECK(WEXITSTATUS(system(BUILD "/dem_collapse --diameters 8 --t-end 0.02 --quiet --out /proc/no_such_dir "
                                   "> " BUILD "/tests/t_demcl.err 2>&1")) == 1);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(chung_ooi_1_two_spheres_normal);
    RUN(chung_ooi_2_sphere_on_wall_normal);
    RUN(chung_ooi_3_restitution);
    RUN(chung_ooi_4_oblique_constant_speed);
    RUN(locked_rotation_slides_without_turning);
    RUN(chung_ooi_5_oblique_constant_normal_speed);
    RUN(chung_ooi_6_spinning_sphere_on_wall);
    RUN(chung_ooi_7_two_spheres_oblique);
    RUN(chung_ooi_8_different_spheres);
    RUN(gravity_floor_carries_the_weight);
    RUN(servo_wall_reaches_its_target);
    RUN(prescribed_particles_move_and_report_their_load);
    RUN(membrane_confines_at_its_pressure);
    RUN(wrap_runs_an_rve_as_a_scene);
    RUN(insert_and_remove_leave_the_others_alone);
    RUN(ids_far_apart_keep_the_index_small);
    RUN(energy_balance_closes);
    RUN(save_restore_and_threads_are_bitwise);
    RUN(a_refused_state_changes_nothing);
    RUN(contact_weights_scale_pair_forces);
    RUN(set_mass_keeps_the_time_step_stable);
    RUN(periodic_shear_between_walls);
    RUN(packing_tile_and_subset);
    RUN(bodies_pipe_drum_rectangle_cylinder);
    RUN(lost_particles);
    RUN(bad_input_is_refused);
    RUN(dem_biaxial_smoke);
    RUN(dem_biaxial_generate);
    RUN(dem_collapse_smoke);
    return gk_test_done();
}
