/* test_contact.c - gk_contact.h laws, alone and through a two-particle RVE. */
#include "gk_homog.h"
#include "gk_test.h"

static gk_law_consts consts_of(const gk_material *m) {
    gk_law_consts k;
    gk_law_consts_make(m, &k);
    return k;
}

/* two particles of radius r in a big box, moving towards each other */
static gk_result two_body(gk_rve *rve, gk_rve_def *def, int dim, double r, double gap, double v) {
    gk_packing pk;
    gk_err e;
    gk_result res;
    int p;
    res = gk_packing_init(&pk, dim, 2, NULL, &e);
    if (res) return res;
    gk_m3_identity(pk.h);
    pk.h[0] = pk.h[4] = 1.0;
    if (dim == 3) pk.h[8] = 1.0;
    pk.x[0] = 0.5 - r - 0.5 * gap;
    pk.x[1] = 0.5 + r + 0.5 * gap;
    pk.y[0] = pk.y[1] = 0.5;
    pk.z[0] = pk.z[1] = dim == 3 ? 0.5 : 0.0;
    pk.r[0] = pk.r[1] = r;
    res = gk_rve_create(rve, def, &pk);
    gk_packing_free(&pk);
    if (res) return res;
    for (p = 0; p < 2; ++p) rve->v[0][p] = (gk_real)(rve->id[p] == 0 ? v : -v);
    return GK_OK;
}

static double rel_speed(const gk_rve *rve) {
    int a = rve->id[0] == 0 ? 0 : 1, b = 1 - a;
    return (double)rve->v[0][b] - (double)rve->v[0][a];
}

/* Linear spring, no damping: a head-on collision is elastic. Leap-frog is
 * symplectic, so the rebound speed equals the approach speed up to O((w dt)^2). */
TEST(impact_conserves_energy_without_damping) {
    int dim;
    for (dim = 2; dim <= 3; ++dim) {
        gk_rve rve;
        gk_rve_def def = gk_rve_def_default();
        double v0 = 0.1, e0, e1;
        def.mat.kn = 1e5;
        def.mat.friction = 0.0;
        def.damping = 0.0;
        def.mass2d = GK_MASS_SPHERE;
        def.dt_factor = 0.02;
        CHECK(two_body(&rve, &def, dim, 0.05, 1e-3, v0) == GK_OK);
        e0 = gk_rve_kinetic_energy(&rve);
        CHECK(gk_rve_step(&rve, 400) == GK_OK);
        e1 = gk_rve_kinetic_energy(&rve);
        CHECK(rve.ncontacts == 0); /* apart again */
        CHECK_REL(e1, e0, 1e-3);
        CHECK(rel_speed(&rve) > 0); /* separating */
        gk_rve_destroy(&rve);
    }
}

/* Linear spring-dashpot with zeta from gk_restitution_to_zeta(e): the
 * rebound/approach speed ratio is e = exp(-pi zeta / sqrt(1 - zeta^2)). */
TEST(impact_restitution_matches_analytic) {
    double es[3] = {0.9, 0.5, 0.2};
    int c;
    for (c = 0; c < 3; ++c) {
        gk_rve rve;
        gk_rve_def def = gk_rve_def_default();
        double v0 = 0.1, ratio;
        def.mat.kn = 1e5;
        def.mat.friction = 0.0;
        def.mat.zeta_n = gk_restitution_to_zeta(es[c]);
        def.damping = 0.0;
        def.mass2d = GK_MASS_SPHERE;
        def.dt_factor = 0.001; /* the dashpot sees v_{n-1/2}: first-order error in dt */
        CHECK(two_body(&rve, &def, 2, 0.05, 1e-4, v0) == GK_OK);
        CHECK(gk_rve_step(&rve, 5000) == GK_OK);
        CHECK(rve.ncontacts == 0);
        ratio = rel_speed(&rve) / (2 * v0);
        CHECK_REL(ratio, es[c], 5e-3);
        gk_rve_destroy(&rve);
    }
    CHECK_NEAR(gk_restitution_to_zeta(1.0), 0.0, 0);
    CHECK_NEAR(exp(-GK_PI * gk_restitution_to_zeta(0.3) / sqrt(1 - pow(gk_restitution_to_zeta(0.3), 2))), 0.3,
               1e-14);
}

/* Coulomb stick and slip (Guo & Zhao 2014 eq 17, incremental form): F_t grows by
 * -k_t v_t dt while |F_t| < mu F_n, then stays on the cap; reversing the
 * motion unloads elastically with k_t. 2D law called directly. */
TEST(coulomb_stick_and_slip_2d) {
    gk_material m = gk_material_default();
    gk_law_consts K;
    gk_contact_out o;
    gk_real ft = 0, mr = 0, kn, fn, kt;
    unsigned char st = 0;
    double dt = 1e-5, vt = 0.01, delta = 1e-4, r = 0.005, cap;
    int k, slid_at = -1;
    m.kt_ratio = 0.8;
    m.friction = 0.5;
    K = consts_of(&m);
    gk_contact_stiffness(&K, GK_LAW_LINEAR, (gk_real)r, (gk_real)r, (gk_real)delta, &kn, &fn, &kt);
    cap = 0.5 * (double)fn;
    /* particle j at +x, moving +y relative to i: t = (0, 1), v_t = vt */
    for (k = 1; k <= 2000; ++k) {
        gk_contact_2d(&K, GK_LAW_LINEAR, GK_PHYS_TANGENT, (gk_real)(2 * r - delta), 0, (gk_real)r, (gk_real)r,
                      1, 1, 0, (gk_real)vt, 0, 0, (gk_real)dt, &ft, &mr, &st, &o);
        if (!(st & GK_CS_SLIDING)) {
            CHECK_REL(ft, -(double)kt * vt * dt * k, 1e-12); /* stick: exact linear growth */
        } else if (slid_at < 0) {
            slid_at = k;
        }
    }
    CHECK(slid_at > 0);
    CHECK_NEAR(slid_at, ceil(cap / ((double)kt * vt * dt)), 1.0);
    CHECK_REL(ft, -cap, 1e-12); /* on the cap, opposing the motion */
    CHECK_REL(o.f[1], -cap, 1e-12);
    CHECK_REL(o.f[0], fn, 1e-12);
    /* reverse: elastic unloading by k_t v dt per step, no longer sliding */
    gk_contact_2d(&K, GK_LAW_LINEAR, GK_PHYS_TANGENT, (gk_real)(2 * r - delta), 0, (gk_real)r, (gk_real)r, 1,
                  1, 0, (gk_real)-vt, 0, 0, (gk_real)dt, &ft, &mr, &st, &o);
    CHECK(!(st & GK_CS_SLIDING));
    CHECK_REL(ft, -cap + (double)kt * vt * dt, 1e-10);
    /* torques: t_i = t_j = -l F_t with l = r - delta/2 (equal radii) */
    CHECK_REL(o.ti[2], -(r - 0.5 * delta) * (double)ft, 1e-12);
    CHECK_REL(o.tj[2], o.ti[2], 1e-15);
}

/* 3D: same law in the tangent plane; the cap acts on the vector magnitude */
TEST(coulomb_stick_and_slip_3d) {
    gk_material m = gk_material_default();
    gk_law_consts K;
    gk_contact_out o;
    gk_real ft[3] = {0, 0, 0}, mr[3] = {0, 0, 0}, d[3], v[3], w0[3] = {0, 0, 0}, kn, fn, kt;
    unsigned char st = 0;
    double dt = 1e-5, delta = 1e-4, r = 0.005, cap, mag;
    int k;
    m.friction = 0.3;
    K = consts_of(&m);
    d[0] = (gk_real)(2 * r - delta);
    d[1] = d[2] = 0;
    v[0] = 0;
    v[1] = (gk_real)0.006;
    v[2] = (gk_real)-0.008; /* |v_t| = 0.01 */
    gk_contact_stiffness(&K, GK_LAW_LINEAR, (gk_real)r, (gk_real)r, (gk_real)delta, &kn, &fn, &kt);
    cap = 0.3 * (double)fn;
    for (k = 1; k <= 10; ++k) {
        gk_contact_3d(&K, GK_LAW_LINEAR, GK_PHYS_TANGENT, d, (gk_real)r, (gk_real)r, 1, 1, v, w0, w0,
                      (gk_real)dt, ft, mr, &st, &o);
        CHECK_REL(ft[1], -(double)kt * 0.006 * dt * k, 1e-12);
        CHECK_REL(ft[2], (double)kt * 0.008 * dt * k, 1e-12);
        CHECK(ft[0] == 0);
    }
    for (k = 0; k < 3000; ++k)
        gk_contact_3d(&K, GK_LAW_LINEAR, GK_PHYS_TANGENT, d, (gk_real)r, (gk_real)r, 1, 1, v, w0, w0,
                      (gk_real)dt, ft, mr, &st, &o);
    mag = sqrt((double)ft[1] * ft[1] + (double)ft[2] * ft[2]);
    CHECK(st & GK_CS_SLIDING);
    CHECK_REL(mag, cap, 1e-12);
    CHECK_REL((double)ft[1] / mag, -0.6, 1e-12); /* opposite to the slip direction */
    CHECK_REL((double)ft[2] / mag, 0.8, 1e-12);
}

/* Rolling resistance (Liang & Zhao 2019 eqs 24-25): M_r = -k_r theta_r with
 * k_r = beta k_t r_i r_j, capped at eta min(r_i, r_j) F_n. */
TEST(rolling_moment_cap) {
    gk_material m = gk_material_default();
    gk_law_consts K;
    gk_contact_out o;
    gk_real ft = 0, mr = 0, kn, fn, kt;
    unsigned char st = 0;
    double dt = 1e-5, wrel = 2.0, delta = 1e-4, ri = 0.004, rj = 0.006, cap, kr;
    int k, capped = 0;
    unsigned fl = GK_PHYS_TANGENT | GK_PHYS_ROTATION | GK_PHYS_ROLLING;
    m.roll_beta = 1.0;
    m.roll_eta = 0.05;
    K = consts_of(&m);
    gk_contact_stiffness(&K, GK_LAW_LINEAR, (gk_real)ri, (gk_real)rj, (gk_real)delta, &kn, &fn, &kt);
    kr = (double)kt * ri * rj;
    cap = 0.05 * ri * (double)fn;
    for (k = 1; k <= 5000; ++k) {
        /* pure relative rolling: w_j = +wrel, w_i = 0; no translation */
        gk_contact_2d(&K, GK_LAW_LINEAR, fl, (gk_real)(ri + rj - delta), 0, (gk_real)ri, (gk_real)rj, 1, 1, 0,
                      0, 0, (gk_real)wrel, (gk_real)dt, &ft, &mr, &st, &o);
        if (!capped && fabs((double)mr) < cap * (1 - 1e-12)) CHECK_REL(mr, -kr * wrel * dt * k, 1e-10);
        if (fabs((double)mr) >= cap * (1 - 1e-12)) capped = 1;
    }
    CHECK(capped);
    CHECK_REL(mr, -cap, 1e-12);
    /* the rolling moment acts on j as M_r and on i as -M_r (on top of the friction torque) */
    CHECK_REL((double)o.tj[2] - (-(rj - 0.5 * delta) * (double)ft), (double)mr, 1e-9);
    CHECK_REL((double)o.ti[2] - (-(ri - 0.5 * delta) * (double)ft), -(double)mr, 1e-9);
}

/* Hertz-Mindlin (Liu et al. 2016 eqs 53-55): F_n = (2/3) k_n delta and
 * k_n = dF_n/d delta = G/(1-nu) sqrt(2 R_e delta), k_t = 2G/(2-nu) sqrt(2 R_e delta). */
TEST(hertz_force_is_integral_of_stiffness) {
    gk_material m = gk_material_default();
    gk_law_consts K;
    gk_real kn, fn, kt, kn2, fn2, kt2;
    double G, nu = 0.2, ri = 0.003, rj = 0.007, Re = 2 * ri * rj / (ri + rj), delta = 2e-5, h = 1e-9;
    m.law = GK_LAW_HERTZ;
    m.young = 7e10;
    m.poisson = nu;
    G = m.young / (2 * (1 + nu));
    K = consts_of(&m);
    gk_contact_stiffness(&K, GK_LAW_HERTZ, (gk_real)ri, (gk_real)rj, (gk_real)(delta + h), &kn, &fn, &kt);
    gk_contact_stiffness(&K, GK_LAW_HERTZ, (gk_real)ri, (gk_real)rj, (gk_real)(delta - h), &kn2, &fn2, &kt2);
    CHECK_REL(((double)fn - (double)fn2) / (2 * h), G / (1 - nu) * sqrt(2 * Re * delta), 1e-6);
    gk_contact_stiffness(&K, GK_LAW_HERTZ, (gk_real)ri, (gk_real)rj, (gk_real)delta, &kn, &fn, &kt);
    CHECK_REL(kn, G / (1 - nu) * sqrt(2 * Re * delta), 1e-14);
    CHECK_REL(kt, 2 * G / (2 - nu) * sqrt(2 * Re * delta), 1e-14);
    /* classical Hertz: F = 4/3 E* sqrt(R) delta^1.5, E* = E / (2 (1 - nu^2)), R = Re / 2 */
    CHECK_REL(fn, 4.0 / 3.0 * m.young / (2 * (1 - nu * nu)) * sqrt(Re / 2) * pow(delta, 1.5), 1e-13);
}

/* Cohesion (Chen et al. 2021): a bond forms on contact, holds tension up to coh_n,
 * then breaks; the broken pair is cohesionless until it separates. */
TEST(cohesion_tension_limit) {
    gk_material m = gk_material_default();
    gk_law_consts K;
    gk_contact_out o;
    gk_real ft = 0, mr = 0;
    unsigned char st = 0;
    double r = 0.005, kn, d;
    unsigned fl = GK_PHYS_TANGENT | GK_PHYS_COHESION;
    m.coh_n = 50.0;
    m.coh_t = 20.0;
    K = consts_of(&m);
    kn = m.young * r; /* r* = r for equal radii */
    /* touch */
    CHECK(gk_contact_2d(&K, GK_LAW_LINEAR, fl, (gk_real)(2 * r - 1e-6), 0, (gk_real)r, (gk_real)r, 1, 1, 0, 0,
                        0, 0, (gk_real)1e-5, &ft, &mr, &st, &o) == 1);
    CHECK(st & GK_CS_BONDED);
    /* pulled apart to a tension below the limit: attractive normal force */
    d = 2 * r + 0.5 * m.coh_n / kn;
    CHECK(gk_contact_2d(&K, GK_LAW_LINEAR, fl, (gk_real)d, 0, (gk_real)r, (gk_real)r, 1, 1, 0, 0, 0, 0,
                        (gk_real)1e-5, &ft, &mr, &st, &o) == 1);
    CHECK_REL(o.fn, -0.5 * m.coh_n, 1e-9);
    CHECK(o.f[0] < 0); /* force on j points back to i */
    /* beyond the limit: the bond breaks, no force */
    d = 2 * r + 1.5 * m.coh_n / kn;
    CHECK(gk_contact_2d(&K, GK_LAW_LINEAR, fl, (gk_real)d, 0, (gk_real)r, (gk_real)r, 1, 1, 0, 0, 0, 0,
                        (gk_real)1e-5, &ft, &mr, &st, &o) == 0);
    CHECK(o.f[0] == 0 && st == 0);
    /* shear strength adds coh_t to the Coulomb cap while bonded */
    st = 0;
    ft = 0;
    CHECK(gk_contact_2d(&K, GK_LAW_LINEAR, fl, (gk_real)(2 * r - 1e-6), 0, (gk_real)r, (gk_real)r, 1, 1, 0,
                        10.0, 0, 0, (gk_real)1e-3, &ft, &mr, &st, &o) == 1);
    /* 10 m/s for 1 ms is a huge shear: the bond fails in shear, leaving mu F_n */
    CHECK(!(st & GK_CS_BONDED) && (st & GK_CS_BROKEN));
    CHECK_REL(fabs((double)ft), m.friction * kn * 1e-6, 1e-9);
}

/* A rigid rotation of a loaded 3D contact (both particles spinning with the
 * rotation, lever arms r - delta/2) rotates F_t with it and keeps |F_t|. */
TEST(history_rotates_with_rigid_spin_3d) {
    gk_material m = gk_material_default();
    gk_law_consts K;
    gk_contact_out o;
    gk_real ft[3] = {0, 2.0, 0}, mr[3] = {0, 0, 0}, d[3], v[3], w[3];
    unsigned char st = GK_CS_CONTACT;
    double r = 0.005, delta = 1e-5, omega = 3.0, dt = 1e-6, ang = 0.0, last = 0.0;
    int k;
    m.friction = 1e6; /* no sliding */
    K = consts_of(&m);
    for (k = 0; k < 20000; ++k) {
        /* branch along (cos a, sin a, 0), spin omega about z: v = omega x d */
        double dist = 2 * r - delta, ca = cos(ang), sa = sin(ang);
        d[0] = (gk_real)(dist * ca);
        d[1] = (gk_real)(dist * sa);
        d[2] = 0;
        v[0] = (gk_real)(-omega * dist * sa);
        v[1] = (gk_real)(omega * dist * ca);
        v[2] = 0;
        w[0] = w[1] = 0;
        w[2] = (gk_real)omega;
        gk_contact_3d(&K, GK_LAW_LINEAR, GK_PHYS_TANGENT | GK_PHYS_ROTATION, d, (gk_real)r, (gk_real)r, 1, 1,
                      v, w, w, (gk_real)dt, ft, mr, &st, &o);
        last = ang;
        ang += omega * dt;
    }
    /* F_t follows the normal of the last evaluation: 2 (-sin a, cos a, 0) */
    CHECK_NEAR(ft[0], -2.0 * sin(last), 1e-9);
    CHECK_NEAR(ft[1], 2.0 * cos(last), 1e-9);
    CHECK(ft[2] == 0);
    /* |F_t| is kept by the rescale; 2e4 steps of rounding allow ~1e-12 drift */
    CHECK_NEAR(sqrt((double)ft[0] * ft[0] + (double)ft[1] * ft[1]), 2.0, 1e-10);
    /* twist: both particles spin about the normal itself (YADE's twist term):
     * F_t = 2 e_y turns about n = e_x by omega t */
    ft[0] = 0;
    ft[1] = 2.0;
    ft[2] = 0;
    d[0] = (gk_real)(2 * r - delta);
    d[1] = d[2] = 0;
    v[0] = v[1] = v[2] = 0;
    w[0] = (gk_real)omega;
    w[1] = w[2] = 0;
    for (k = 0; k < 20000; ++k)
        gk_contact_3d(&K, GK_LAW_LINEAR, GK_PHYS_TANGENT | GK_PHYS_ROTATION, d, (gk_real)r, (gk_real)r, 1, 1,
                      v, w, w, (gk_real)dt, ft, mr, &st, &o);
    CHECK(ft[0] == 0);
    CHECK_NEAR(ft[1], 2.0 * cos(20000 * omega * dt), 1e-9);
    CHECK_NEAR(ft[2], 2.0 * sin(20000 * omega * dt), 1e-9);
}

TEST(material_checks) {
    gk_material m = gk_material_default();
    gk_err e;
    gk_material bad;
    CHECK(gk_material_check(&m, &e) == GK_OK);
    bad = m;
    bad.cookie = 0;
    CHECK(gk_material_check(&bad, &e) == GK_ERR_ARG);
    bad = m;
    bad.young = NAN;
    CHECK(gk_material_check(&bad, &e) == GK_ERR_NAN);
    bad = m;
    bad.density = 0;
    CHECK(gk_material_check(&bad, &e) == GK_ERR_MASS);
    bad = m;
    bad.friction = -1;
    CHECK(gk_material_check(&bad, &e) == GK_ERR_ARG);
    bad = m;
    bad.law = GK_LAW_HERTZ;
    bad.coh_n = 1;
    CHECK(gk_material_check(&bad, &e) == GK_ERR_UNSUPPORTED);
    bad = m;
    bad.zeta_n = 1.0;
    CHECK(gk_material_check(&bad, &e) == GK_ERR_ARG);
    CHECK(gk_material_flags(&m) == GK_PHYS_TANGENT);
    bad = m;
    bad.friction = 0;
    CHECK(gk_material_flags(&bad) == 0u);
}

/* a material of each law with every optional term on (cohesion is linear-only
 * and has no wide twin: it is tested through the RVE) */
static gk_material law_material(gk_law law) {
    gk_material m = gk_material_default();
    m.law = law;
    m.young = 5e8;
    m.poisson = 0.3;
    m.friction = 0.4;
    m.roll_beta = 0.8;
    m.roll_eta = 0.2;
    m.zeta_n = 0.1;
    m.zeta_t = 0.05;
    return m;
}

/* The wide twins gk_contact_2d_w / _3d_w (GK_VR_W pairs at a time) give every
 * lane exactly the bits of the scalar reference gk_contact_2d / _3d: forces,
 * torques, history and the contact/sliding state, for every law of
 * GK_LAW_TABLE and the flag sets the kernels instantiate, on random pairs
 * that are apart, touching, sticking and sliding. */
TEST(wide_twins_equal_scalar_reference_bitwise) {
    static const unsigned FL[] = {0u, GK_PHYS_TANGENT, GK_PHYS_TANGENT | GK_PHYS_ROTATION,
                                  GK_PHYS_TANGENT | GK_PHYS_VISCOUS,
                                  GK_PHYS_TANGENT | GK_PHYS_ROTATION | GK_PHYS_ROLLING | GK_PHYS_VISCOUS};
    gk_rng rng;
    int law, f, it, l, k, bad = 0, sliding = 0, apart = 0, total = 0;
    gk_rng_seed(&rng, 7);
    for (law = 0; law < GK_LAW_COUNT; ++law) {
        gk_material m = law_material((gk_law)law);
        gk_law_consts K = consts_of(&m);
        CHECK(gk_material_check(&m, NULL) == GK_OK);
        for (f = 0; f < (int)(sizeof FL / sizeof FL[0]); ++f)
            for (it = 0; it < 200; ++it) {
                unsigned fl = FL[f];
                int dim = 2 + (it & 1);
                gk_real d[3][GK_VR_W], v[3][GK_VR_W], wi[3][GK_VR_W], wj[3][GK_VR_W], ft[3][GK_VR_W],
                    mr[3][GK_VR_W], ri[GK_VR_W], rj[GK_VR_W], mi[GK_VR_W], mj[GK_VR_W], out[9][GK_VR_W];
                gk_vr D[3], V[3], WI[3], WJ[3], FT[3], MR[3], dt = gk_vr_set1((gk_real)2e-5);
                gk_vrm in, slide;
                gk_contact_out_w o;
                unsigned bin, bsl;
                for (l = 0; l < GK_VR_W; ++l) {
                    double a = 1e-3 * (0.5 + gk_rng_uniform(&rng)), b = 1e-3 * (0.5 + gk_rng_uniform(&rng));
                    double gap = (a + b) * (0.97 + 0.05 * gk_rng_uniform(&rng)), n[3], nn = 0.0;
                    for (k = 0; k < 3; ++k) n[k] = k < dim ? gk_rng_normal(&rng) : 0.0;
                    for (k = 0; k < 3; ++k) nn += n[k] * n[k];
                    ri[l] = (gk_real)a;
                    rj[l] = (gk_real)b;
                    mi[l] = (gk_real)(2650.0 * a * a * a * 4.19);
                    mj[l] = (gk_real)(2650.0 * b * b * b * 4.19);
                    for (k = 0; k < 3; ++k) {
                        d[k][l] = (gk_real)(gap * n[k] / sqrt(nn));
                        v[k][l] = (gk_real)(k < dim ? 0.05 * gk_rng_normal(&rng) : 0.0);
                        wi[k][l] = (gk_real)(k == 2 || dim == 3 ? 50.0 * gk_rng_normal(&rng) : 0.0);
                        wj[k][l] = (gk_real)(k == 2 || dim == 3 ? 50.0 * gk_rng_normal(&rng) : 0.0);
                        ft[k][l] = (gk_real)(k < dim ? 2.0 * gk_rng_normal(&rng) : 0.0);
                        mr[k][l] = (gk_real)(k == 2 || dim == 3 ? 1e-3 * gk_rng_normal(&rng) : 0.0);
                    }
                }
                for (k = 0; k < 3; ++k) {
                    D[k] = gk_vr_loadu(d[k]);
                    V[k] = gk_vr_loadu(v[k]);
                    WI[k] = gk_vr_loadu(wi[k]);
                    WJ[k] = gk_vr_loadu(wj[k]);
                    FT[k] = gk_vr_loadu(ft[k]);
                    MR[k] = gk_vr_loadu(mr[k]);
                }
                if (dim == 2)
                    in = gk_contact_2d_w(&K, (gk_law)law, fl, D[0], D[1], gk_vr_loadu(ri), gk_vr_loadu(rj),
                                         gk_vr_loadu(mi), gk_vr_loadu(mj), V[0], V[1], WI[2], WJ[2], dt,
                                         &FT[0], &MR[2], &slide, &o);
                else
                    in = gk_contact_3d_w(&K, (gk_law)law, fl, D, gk_vr_loadu(ri), gk_vr_loadu(rj),
                                         gk_vr_loadu(mi), gk_vr_loadu(mj), V, WI, WJ, dt, FT, MR, &slide, &o);
                for (k = 0; k < 3; ++k) {
                    gk_vr_storeu(out[k], o.f[k]);
                    gk_vr_storeu(out[3 + k], o.ti[k]);
                    gk_vr_storeu(out[6 + k], o.tj[k]);
                }
                bin = gk_vrm_bits(in);
                bsl = gk_vrm_bits(gk_vrm_and(in, slide));
                for (l = 0; l < GK_VR_W; ++l) {
                    gk_real hf[3], hm[3], wf[GK_VR_W], wm[GK_VR_W];
                    unsigned char st = GK_CS_CONTACT;
                    gk_contact_out so;
                    int kk, ok = 1;
                    for (k = 0; k < 3; ++k) {
                        hf[k] = ft[k][l];
                        hm[k] = mr[k][l];
                    }
                    if (dim == 2) {
                        gk_contact_2d(&K, (gk_law)law, fl, d[0][l], d[1][l], ri[l], rj[l], mi[l], mj[l],
                                      v[0][l], v[1][l], wi[2][l], wj[2][l], (gk_real)2e-5, &hf[0], &hm[2],
                                      &st, &so);
                        so.f[2] = so.ti[0] = so.ti[1] = so.tj[0] = so.tj[1] = 0; /* the twin's zero lanes */
                    } else {
                        gk_real dl[3], vl[3], wil[3], wjl[3];
                        for (k = 0; k < 3; ++k) {
                            dl[k] = d[k][l];
                            vl[k] = v[k][l];
                            wil[k] = wi[k][l];
                            wjl[k] = wj[k][l];
                        }
                        gk_contact_3d(&K, (gk_law)law, fl, dl, ri[l], rj[l], mi[l], mj[l], vl, wil, wjl,
                                      (gk_real)2e-5, hf, hm, &st, &so);
                    }
                    for (k = 0; k < 3; ++k) {
                        ok &= memcmp(&so.f[k], &out[k][l], sizeof(gk_real)) == 0;
                        ok &= memcmp(&so.ti[k], &out[3 + k][l], sizeof(gk_real)) == 0;
                        ok &= memcmp(&so.tj[k], &out[6 + k][l], sizeof(gk_real)) == 0;
                    }
                    for (k = 0; k < 3; ++k) {
                        kk = dim == 2 ? (k == 0 ? 0 : 2) : k; /* 2D: ft[0] and mr[2] */
                        if (dim == 2 && k == 1) continue;
                        gk_vr_storeu(wf, FT[kk]);
                        gk_vr_storeu(wm, MR[kk]);
                        if (fl & GK_PHYS_TANGENT) ok &= memcmp(&hf[kk], &wf[l], sizeof(gk_real)) == 0;
                        if (fl & GK_PHYS_ROLLING) ok &= memcmp(&hm[kk], &wm[l], sizeof(gk_real)) == 0;
                    }
                    ok &= st == (unsigned char)((((bin >> l) & 1u) ? GK_CS_CONTACT : 0u) |
                                                (((bsl >> l) & 1u) ? GK_CS_SLIDING : 0u));
                    bad += !ok;
                    sliding += (st & GK_CS_SLIDING) != 0;
                    apart += !(st & GK_CS_CONTACT);
                    ++total;
                }
            }
    }
    printf("    %d pairs (%d apart, %d sliding), %d lanes differ\n", total, apart, sliding, bad);
    CHECK(bad == 0);
    CHECK(apart > total / 10 && sliding > total / 10);
}

/* gk_law_kn_max bounds the normal stiffness of every law for radii up to
 * r_max and overlaps up to d_max (the critical time step of Guo & Zhao 2014 eq 19
 * rests on it), and a law that stiffens says so. */
TEST(law_kn_max_bounds_the_stiffness) {
    gk_rng rng;
    int law, it;
    gk_rng_seed(&rng, 11);
    for (law = 0; law < GK_LAW_COUNT; ++law) {
        gk_material m = law_material((gk_law)law);
        gk_law_consts K = consts_of(&m);
        double rmax = 2e-3, dmax = 4e-5, bound = gk_law_kn_max(&m, rmax, dmax), worst = 0.0;
        gk_real kn0, kn1, fn, kt;
        for (it = 0; it < 1000; ++it) {
            double ri = rmax * (0.1 + 0.9 * gk_rng_uniform(&rng)),
                   rj = rmax * (0.1 + 0.9 * gk_rng_uniform(&rng));
            gk_contact_stiffness(&K, (gk_law)law, (gk_real)ri, (gk_real)rj,
                                 (gk_real)(dmax * gk_rng_uniform(&rng)), &kn0, &fn, &kt);
            if ((double)kn0 > worst) worst = (double)kn0;
        }
        gk_contact_stiffness(&K, (gk_law)law, (gk_real)rmax, (gk_real)rmax, (gk_real)dmax, &kn1, &fn, &kt);
        printf("    %s: largest k_n %.6g, bound %.6g, at r_max and d_max %.6g\n", gk_law_name((gk_law)law),
               worst, bound, (double)kn1);
        CHECK(worst <= bound * (1.0 + 1e-6));
        CHECK_REL((double)kn1, bound, 1e-6); /* the bound is reached */
        gk_contact_stiffness(&K, (gk_law)law, (gk_real)rmax, (gk_real)rmax, (gk_real)(0.5 * dmax), &kn0, &fn,
                             &kt);
        CHECK(gk_law_stiffens((gk_law)law) == ((double)kn0 < (double)kn1));
    }
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(impact_conserves_energy_without_damping);
    RUN(impact_restitution_matches_analytic);
    RUN(coulomb_stick_and_slip_2d);
    RUN(coulomb_stick_and_slip_3d);
    RUN(rolling_moment_cap);
    RUN(hertz_force_is_integral_of_stiffness);
    RUN(cohesion_tension_limit);
    RUN(history_rotates_with_rigid_spin_3d);
    RUN(material_checks);
    RUN(wide_twins_equal_scalar_reference_bitwise);
    RUN(law_kn_max_bounds_the_stiffness);
    return gk_test_done();
}
