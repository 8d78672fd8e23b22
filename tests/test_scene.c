/* test_scene.c - DEM beyond the periodic cell (gk_scene.h): the eight
 * particle-level benchmarks of Chung & Ooi (2011), walls and their servo,
 * gravity, prescribed particles, the membrane, insertion and deletion, the
 * energy balance, save/restore and thread invariance, packing tiles and
 * subsets, and smoke runs of the two scene drivers. */
#define GK_DEM_PAR_MIN 64 /* let small scenes use threads, to test thread invariance */
#define GK_IMPLEMENTATION
#include "gk_scene.h"
#include "gk_test.h"
#include <stdlib.h>

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
    if (gk_packing_alloc(&pk, 3, n, NULL, &e)) return 1;
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
        printf("    %-9s F_max %.6g N (Hertz %.6g), delta_max %.6g m (%.6g), t_c %.6g s (%.6g)\n", ms[t]->name,
               o.fmax, fm, o.dmax, dm, o.tc, tc);
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
        double tc = hertz_tc(m, R, Es, v), dm = hertz_dmax(m, R, Es, v), fm = 4.0 / 3.0 * Es * sqrt(R) * pow(dm, 1.5);
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
        printf("    %-9s F_max %.6g N (Hertz %.6g), delta_max %.6g m (%.6g), t_c %.6g s (%.6g)\n", ms[t]->name,
               o.fmax, fm, o.dmax, dm, o.tc, tc);
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
    if (run_impact(&sc, 0, -1, &o, 1000000)) e = -1.0;
    else e = (double)sc.rve.v[1][0] / v;
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
        double xn = x + h / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x), un = u + h / 6.0 * (k1u + 2 * k2u + 2 * k3u + k4u);
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
        double R = 2.5e-3, m = sphere_mass(ms[t]->rho, R), Es = estar(ms[t], NULL), tc = hertz_tc(m, R, Es, 3.9);
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
            printf("    %-9s Hertz, zeta 0.2: e = %.5f, %.5f, %.5f at 0.39, 3.9, 39 m/s; model %.5f\n", ms[t]->name, e0,
                   e1, e2, em);
            CHECK_NEAR(e0, em, 2e-3);
            CHECK_NEAR(e1, em, 2e-3);
            CHECK_NEAR(e2, em, 2e-3);
        }
    }
}

/* one oblique impact on the plane: rebound velocity and spin */
static int oblique(const gk_material *m, double R, const double v[3], const double w[3], double dt, double vout[3],
                   double wout[3]) {
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
        double th = ang[a] * GK_PI / 180.0, vn = V * cos(th), vt = V * sin(th), v[3], vo[3], wo[3], et, L0, L1;
        v[0] = vt;
        v[1] = -vn;
        v[2] = 0.0;
        CHECK(oblique(&mat, R, v, NULL, dt, vo, wo) == 0);
        et = vo[0] / vt;
        L0 = -m * R * vt;
        L1 = I * wo[2] - m * R * vo[0];
        printf("    theta %4.1f: e_t %.4f, omega %9.3f rad/s, rebound angle %6.2f deg, contact point %+.4f m/s\n", ang[a],
               et, wo[2], atan2(vo[0], vo[1]) * 180.0 / GK_PI, vo[0] + R * wo[2]);
        CHECK_NEAR(L1, L0, 2e-3 * fabs(L0));
        CHECK_NEAR(vo[1], vn, 1e-3 * vn);
        CHECK(0.5 * m * (vo[0] * vo[0] + vo[1] * vo[1]) + 0.5 * I * wo[2] * wo[2] <= 0.5 * m * V * V * (1.0 + 1e-6));
        if (tan(th) >= 7.0 * mu * 1.01) {
            CHECK_NEAR(et, 1.0 - 2.0 * mu / tan(th), 2e-3);
            CHECK_NEAR(wo[2], -5.0 * mu * vn / R, 2e-3 * 5.0 * mu * vn / R);
        }
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
        double m = sphere_mass(ms[t]->rho, R), I = 0.4 * m * R * R, dt = hertz_tc(m, R, estar(ms[t], NULL), vn) / 1000.0;
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
        printf("    linear k_t/k_n = 2/7, w0 %.3f: v_x' %+.6f (exact %+.6f), w' %+.5f (%+.5f)\n", w0, vo[0], vx, wo[2],
               wz);
        CHECK_NEAR(vo[0], vx, 3e-3 * R * w0);
        CHECK_NEAR(wo[2], wz, 3e-3 * w0);
    }
}

/* two spheres: A below moving up, B above moving down (zero momentum), both
 * spinning at w0 about z: the contact points slide at 2 R w0 for equal radii
 * (R_A w0 + R_B w0 in general) while the centres have no tangential speed,
 * so the line of centres stays put */
static int two_spheres(gk_scene *sc, const gk_material *m, double RA, double RB, double mB, double vn, double w0,
                       double dt) {
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
        double dt = hertz_tc(0.5 * m, 0.5 * R, Es, vn) / 1000.0, tol = hertz_dmax(0.5 * m, 0.5 * R, Es, vn) / R + 2e-3;
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
            vc = ((double)sc.rve.v[0][b] + R * (double)sc.rve.w[2][b]) - ((double)sc.rve.v[0][a] - R * (double)sc.rve.w[2][a]);
            /* about the initial contact point: A at -R y, B at +R y */
            Lz = I * ((double)sc.rve.w[2][a] + (double)sc.rve.w[2][b]) + m * R * ((double)sc.rve.v[0][a] - (double)sc.rve.v[0][b]);
            printf("    %-9s w0 %6.3f: A v_x %+.5f w %+.5f, B v_x %+.5f w %+.5f, contact %+.5f (from %+.4f)\n",
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
            vc = ((double)sc.rve.v[0][b] + R * (double)sc.rve.w[2][b]) - ((double)sc.rve.v[0][a] - R * (double)sc.rve.w[2][a]);
            printf("    linear k_t/k_n = 2/7, w0 %.3f: relative contact velocity %+.6f (exact %+.6f)\n", w0, vc,
                   -2.0 * R * w0);
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
    double RA = 0.1, RB = 0.05, vn = 0.2, mu = 0.3, mA = sphere_mass(AL_ALLOY.rho, RA), mB = sphere_mass(MG_ALLOY.rho, RB);
    double ms = mA * mB / (mA + mB), Rs = RA * RB / (RA + RB), Es = estar(&AL_ALLOY, &MG_ALLOY), w0 = 20.0;
    double tc = hertz_tc(ms, Rs, Es, vn), dm = hertz_dmax(ms, Rs, Es, vn), fm = 4.0 / 3.0 * Es * sqrt(Rs) * pow(dm, 1.5);
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
    printf("    normal: F_max %.6g N (Hertz %.6g), delta_max %.6g m (%.6g), t_c %.6g s (%.6g)\n", o.fmax, fm, o.dmax, dm,
           o.tc, tc);
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
        CHECK_NEAR(sc.rve.w[2][ia], w0 - RA * Jt / (0.4 * mA * RA * RA), tol * RA * Jt / (0.4 * mA * RA * RA));
        CHECK_NEAR(sc.rve.w[2][ib], w0 - RB * Jt / (0.4 * mB * RB * RB), tol * RB * Jt / (0.4 * mB * RB * RB));
    }
    gk_scene_destroy(&sc);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(chung_ooi_1_two_spheres_normal);
    RUN(chung_ooi_2_sphere_on_wall_normal);
    RUN(chung_ooi_3_restitution);
    RUN(chung_ooi_4_oblique_constant_speed);
    RUN(chung_ooi_5_oblique_constant_normal_speed);
    RUN(chung_ooi_6_spinning_sphere_on_wall);
    RUN(chung_ooi_7_two_spheres_oblique);
    RUN(chung_ooi_8_different_spheres);
    return gk_test_done();
}
