/* test_frame.c - gk_frame.h: the RVE of Liu, Bosco & Suiker (2018) with its
 * servo-controlled frame of boundary particles, and the deforming periodic
 * cell, both relaxed to E_kin / E_pot <= tol (eqs 30-32), first
 * Piola-Kirchhoff stress out. On the shipped framed packing
 * (examples/data/frame228_a002.txt, 205 disks, 228 in the framed RVE). */
#include "gk_frame.h"
#include "gk_test.h"

#define PACKING "examples/data/frame228_a002.txt"

static gk_packing pk;
static int have;

static int load(void) {
    gk_err e;
    if (!have) have = gk_packing_read(PACKING, &pk, NULL, &e) == GK_OK;
    return have;
}

/* the contact law of the examples: linear k_n = 1.5e7 N/m, k_s = 0.2 k_n, mu 0.4, damping 0.7 */
static gk_rve_def law(unsigned flags) {
    gk_rve_def d = gk_rve_def_default();
    d.mat.kn = 1.5e7, d.mat.kt_ratio = 0.2, d.mat.friction = 0.4, d.mat.density = 2000;
    d.thickness = 1.0, d.damping = 0.7, d.dt_factor = 0.4, d.flags = flags;
    return d;
}

/* the frame of the packing: 10 + 10 line particles and the corner give P = 184 inner and Q = 44 boundary
 * particles (20 pairs); the pairs are images (X^+ - X^- = L e_k, same radius); eq 5's area vectors close
 * (sum A_q = 0) and sum X_q (x) A_q = V I exactly, so eq 11 returns the imposed F whenever the
 * fluctuations are periodic (here a shear and stretch with random periodic w) */
TEST(frame_geometry_and_eq11) {
    gk_frame fr;
    gk_err e;
    double S[9], sA[2] = {0, 0}, *x, F[9] = {1.02, 0.03, 0, -0.01, 0.97, 0, 0, 0, 1}, G[9];
    int i, k, ok = 1;
    gk_rng rng;
    CHECK(load());
    if (!have) return;
    CHECK(gk_frame_build(&fr, &pk, NULL, &e) == GK_OK);
    CHECK_EQ_INT(fr.n, 228);
    CHECK_EQ_INT(fr.nq, 44);
    CHECK_EQ_INT(fr.npair, 20);
    CHECK_EQ_INT(fr.ninner, 184);
    CHECK_EQ_INT(fr.framed.n, 228);
    printf("    inner particles crossing the boundary lines: %d\n", fr.crossing);
    for (i = 0; i < fr.npair; ++i) {
        int a = fr.pair[2 * i], b = fr.pair[2 * i + 1];
        double dx = fr.X[2 * b] - fr.X[2 * a], dy = fr.X[2 * b + 1] - fr.X[2 * a + 1];
        ok &= fr.R[a] == fr.R[b] && ((dx == fr.L[0] && dy == 0.0) || (dx == 0.0 && dy == fr.L[1]));
    }
    CHECK(ok);
    gk_m3_zero(S);
    for (i = 0; i < fr.nq; ++i) {
        int a, b;
        sA[0] += fr.A[2 * i], sA[1] += fr.A[2 * i + 1];
        for (a = 0; a < 2; ++a)
            for (b = 0; b < 2; ++b) S[3 * a + b] += fr.X[2 * i + a] * fr.A[2 * i + b];
    }
    CHECK_NEAR(sA[0], 0.0, 1e-15);
    CHECK_NEAR(sA[1], 0.0, 1e-15);
    CHECK_NEAR(S[0] / fr.V, 1.0, 1e-12);
    CHECK_NEAR(S[4] / fr.V, 1.0, 1e-12);
    CHECK_NEAR(S[1] / fr.V, 0.0, 1e-12);
    CHECK_NEAR(S[3] / fr.V, 0.0, 1e-12);
    /* eq 11 with periodic fluctuations: w the same for both members of a pair, 0 at the corners */
    x = (double *)malloc(sizeof(double) * 2 * fr.nq);
    gk_rng_seed(&rng, 9);
    for (i = 0; i < fr.nq; ++i)
        for (k = 0; k < 2; ++k) x[2 * i + k] = F[3 * k] * fr.X[2 * i] + F[3 * k + 1] * fr.X[2 * i + 1];
    for (i = 0; i < fr.npair; ++i) {
        double w0 = 1e-4 * (gk_rng_uniform(&rng) - 0.5), w1 = 1e-4 * (gk_rng_uniform(&rng) - 0.5);
        x[2 * fr.pair[2 * i]] += w0, x[2 * fr.pair[2 * i] + 1] += w1;
        x[2 * fr.pair[2 * i + 1]] += w0, x[2 * fr.pair[2 * i + 1] + 1] += w1;
    }
    gk_frame_gradient(&fr, x, G);
    for (k = 0; k < 9; ++k) CHECK_NEAR(G[k], F[k], 1e-12);
    free(x);
    gk_frame_free(&fr);
}

/* eq 32 on two disks pressed together by delta: E_pot = f_n^2 / (2 k_n) = k_n delta^2 / 2 (no shear),
 * k_n constant or E r* */
TEST(energy_of_one_contact_is_eq32) {
    gk_packing two;
    gk_rve r;
    gk_rve_def d = law(0u);
    double ek, ep, delta = 1e-6, rr = 1e-3;
    CHECK(gk_packing_init(&two, 2, 2, NULL, NULL) == GK_OK);
    gk_m3_identity(two.h);
    two.h[0] = two.h[4] = 0.02;
    two.x[0] = 0.005, two.y[0] = 0.01, two.r[0] = rr;
    two.x[1] = 0.005 + 2 * rr - delta, two.y[1] = 0.01, two.r[1] = rr;
    CHECK(gk_rve_create(&r, &d, &two) == GK_OK);
    CHECK(gk_rve_refresh(&r) == GK_OK);
    CHECK(gk_frame_energy(&r, NULL, &ek, &ep) == GK_OK);
    CHECK_NEAR(ek, 0.0, 0.0);
    CHECK_NEAR(ep, 0.5 * 1.5e7 * delta * delta, 1e-9 * 0.5 * 1.5e7 * delta * delta);
    gk_rve_destroy(&r);
    d.mat.kn = 0.0, d.mat.young = 6e8; /* k_n = E r*, r* = 2 r r / (r + r) = r */
    CHECK(gk_rve_create(&r, &d, &two) == GK_OK);
    CHECK(gk_rve_refresh(&r) == GK_OK);
    CHECK(gk_frame_energy(&r, NULL, &ek, &ep) == GK_OK);
    CHECK_NEAR(ep, 0.5 * 6e8 * rr * delta * delta, 1e-9 * 0.5 * 6e8 * rr * delta * delta);
    gk_rve_destroy(&r);
    d.mat.law = GK_LAW_HERTZ; /* eq 32 is the linear law's */
    CHECK(gk_rve_create(&r, &d, &two) == GK_OK);
    CHECK(gk_frame_energy(&r, NULL, &ek, &ep) == GK_ERR_ARG);
    gk_rve_destroy(&r);
    gk_packing_free(&two);
}

/* one run of each RVE under isotropic compression dH = -2e-3 I from the packing: both relax to eq 31;
 * the periodic cell's P is det F sigma F^-T of its own Love stress (to rounding); the servo frame's
 * corrections (eqs 33-36) halve its boundary imbalance r_a at least (20 against 1) and P F^T is
 * symmetric (moment equilibrium, eq 7) within 2 % of the pressure; the two RVEs of one packing agree
 * within 25 % (measured: printed) */
TEST(servo_frame_and_periodic_cell_under_compression) {
    gk_frame fr;
    gk_err e;
    gk_rve a, b;
    gk_rve_def d = law(0u);
    gk_frame_set set;
    gk_frame_stats st[1];
    double H[9] = {0}, dH[9] = {0}, Pa[9], Pb[9], sa[9], sb[9], sl[9], F[9];
    int steps = 0, k;
    CHECK(load());
    if (!have) return;
    CHECK(gk_frame_build(&fr, &pk, NULL, &e) == GK_OK);
    dH[0] = dH[4] = -2e-3;
    gk_m3_identity(F);
    F[0] = F[4] = 1.0 - 2e-3;
    memset(&set, 0, sizeof set);
    set.kind = GK_FRAME_PERIODIC, set.stats = st;
    CHECK(gk_rve_create(&a, &d, &pk) == GK_OK && gk_rve_refresh(&a) == GK_OK);
    CHECK(gk_frame_run(&set, 0, 0, &a, H, dH, 1.0, Pa, &steps) == GK_OK);
    CHECK(st[0].energy_ratio <= 1e-3 && !st[0].capped && steps == st[0].steps);
    gk_rve_stress(&a, sl);
    gk_frame_cauchy(Pa, F, sa);
    for (k = 0; k < 9; ++k) CHECK_NEAR(sa[k], sl[k], 1e-9 * fabs(sl[0]));
    printf("    periodic cell: P11 %.0f P22 %.0f Pa, %ld DEM steps, Z %.2f\n", Pa[0], Pa[4], st[0].steps,
           st[0].coordination);
    set.kind = GK_FRAME_SERVO, set.frames = &fr;
    CHECK(gk_rve_create(&b, &d, &fr.framed) == GK_OK && gk_rve_refresh(&b) == GK_OK);
    CHECK(gk_frame_run(&set, 0, 0, &b, H, dH, 1.0, Pb, &steps) == GK_OK);
    gk_frame_cauchy(Pb, F, sb);
    printf(
        "    servo frame: P11 %.0f P22 %.0f Pa, %ld DEM steps, %d corrections, r_a %.2g (relative %.2g)%s\n",
        Pb[0], Pb[4], st[0].steps, st[0].servo, st[0].residual, st[0].residual_rel,
        st[0].capped ? ", capped" : "");
    CHECK(st[0].energy_ratio <= 1e-3);
    CHECK(st[0].servo > 0);
    { /* the corrections (eqs 33-36) reduce the imbalance: 20 of them against 1 */
        gk_rve c;
        gk_frame_stats one[1];
        gk_frame_set s1 = set;
        double Pc[9];
        s1.def.max_servo = 1, s1.stats = one;
        CHECK(gk_rve_create(&c, &d, &fr.framed) == GK_OK && gk_rve_refresh(&c) == GK_OK);
        CHECK(gk_frame_run(&s1, 0, 0, &c, H, dH, 1.0, Pc, &steps) == GK_OK);
        printf("    after 1 correction r_a %.2g (relative %.2g), after %d: %.2g (%.2g)\n", one[0].residual,
               one[0].residual_rel, st[0].servo, st[0].residual, st[0].residual_rel);
        CHECK(st[0].residual < 0.5 * one[0].residual);
        gk_rve_destroy(&c);
    }
    CHECK(fabs(sb[1] - sb[3]) < 0.02 * fabs(sb[0] + sb[4]) / 2);
    CHECK(Pb[0] < 0.0 && Pb[4] < 0.0);
    CHECK(fabs(Pb[0] + Pb[4] - Pa[0] - Pa[4]) < 0.25 * fabs(Pa[0] + Pa[4]));
    gk_rve_destroy(&a);
    gk_rve_destroy(&b);
    gk_frame_free(&fr);
}

/* the paper's theta_p = 0 (GK_RVE_NO_ROTATION): no particle turns during a servo run under shear */
TEST(locked_rotation_stays_locked) {
    gk_frame fr;
    gk_err e;
    gk_rve r;
    gk_rve_def d = law(GK_RVE_NO_ROTATION);
    gk_frame_set set;
    double H[9] = {0}, dH[9] = {0}, P[9], th = 0.0;
    int steps, p;
    CHECK(load());
    if (!have) return;
    CHECK(gk_frame_build(&fr, &pk, NULL, &e) == GK_OK);
    memset(&set, 0, sizeof set);
    set.kind = GK_FRAME_SERVO, set.frames = &fr;
    set.def.max_servo = 3;
    dH[1] = 2e-3, dH[0] = dH[4] = -1e-3;
    CHECK(gk_rve_create(&r, &d, &fr.framed) == GK_OK && gk_rve_refresh(&r) == GK_OK);
    CHECK(gk_frame_run(&set, 0, 0, &r, H, dH, 1.0, P, &steps) == GK_OK);
    for (p = 0; p < r.n; ++p) th += fabs(r.theta[p]);
    CHECK_NEAR(th, 0.0, 0.0);
    gk_rve_destroy(&r);
    gk_frame_free(&fr);
}

/* the paper's own lock, theta_p = 0 for the inner particles p (def.lock_inner): under shear no inner
 * particle turns while the frame does (the servo corrects its moments); the periodic cell, which has
 * no frame, refuses lock_inner and changes nothing */
TEST(inner_lock_turns_only_the_frame) {
    gk_frame fr;
    gk_err e;
    gk_rve r;
    gk_rve_def d = law(0u);
    gk_frame_set set;
    double H[9] = {0}, dH[9] = {0}, P[9], inner = 0.0, frame = 0.0, th0;
    int steps, p, i;
    CHECK(load());
    if (!have) return;
    CHECK(gk_frame_build(&fr, &pk, NULL, &e) == GK_OK);
    memset(&set, 0, sizeof set);
    set.kind = GK_FRAME_SERVO, set.frames = &fr;
    set.def.max_servo = 3, set.def.lock_inner = 1;
    dH[1] = 2e-3, dH[0] = dH[4] = -1e-3;
    CHECK(gk_rve_create(&r, &d, &fr.framed) == GK_OK && gk_rve_refresh(&r) == GK_OK);
    CHECK(gk_frame_run(&set, 0, 0, &r, H, dH, 1.0, P, &steps) == GK_OK);
    for (p = 0; p < r.n; ++p) {
        int on_frame = 0;
        for (i = 0; i < fr.nq; ++i) on_frame |= r.id[p] == fr.q[i];
        if (on_frame)
            frame += fabs(r.theta[p]);
        else
            inner += fabs(r.theta[p]) + fabs((double)r.w[2][p]);
    }
    printf("    sum |theta|: inner %g, frame %g rad\n", inner, frame);
    CHECK_NEAR(inner, 0.0, 0.0);
    CHECK(frame > 0.0);
    set.kind = GK_FRAME_PERIODIC;
    th0 = r.theta[0];
    CHECK(gk_frame_run(&set, 0, 0, &r, H, dH, 1.0, P, &steps) == GK_ERR_ARG);
    CHECK(r.theta[0] == th0);
    set.kind = GK_FRAME_SERVO, set.def.lock_inner = 2;
    CHECK(gk_frame_run(&set, 0, 0, &r, H, dH, 1.0, P, &steps) == GK_ERR_ARG);
    gk_rve_destroy(&r);
    gk_frame_free(&fr);
}

/* the positions of the frame's boundary particles (by their ids) into x (nq x 3); the number found */
static int frame_positions(const gk_rve *r, const gk_frame *fr, double *x) {
    int i, p, found = 0;
    for (i = 0; i < fr->nq; ++i)
        for (p = 0; p < r->n; ++p)
            if (r->id[p] == fr->q[i]) gk_rve_position(r, p, x + 3 * i), ++found;
    return found;
}

/* no deformation at all (dH = 0: the first run of a load step that starts in equilibrium): the frame
 * is held where it is while the inside relaxes (eq 30 with the boundary particles prescribed), and the
 * run returns the packing's own stress (eq 14). tests/test_femdem_dr.c runs the driver on a packing
 * whose frame has exactly nothing to move. */
TEST(servo_frame_without_deformation_holds_the_frame) {
    gk_frame fr;
    gk_err e;
    gk_rve r;
    gk_rve_def d = law(0u);
    gk_frame_set set;
    gk_frame_stats st[1];
    double H[9] = {0}, dH[9] = {0}, P[9], moved = 0.0;
    double *x0, *x1;
    int steps = 0, i, k;
    CHECK(load());
    if (!have) return;
    CHECK(gk_frame_build(&fr, &pk, NULL, &e) == GK_OK);
    memset(&set, 0, sizeof set);
    set.kind = GK_FRAME_SERVO, set.frames = &fr, set.stats = st;
    CHECK(gk_rve_create(&r, &d, &fr.framed) == GK_OK && gk_rve_refresh(&r) == GK_OK);
    x0 = (double *)calloc(6 * (size_t)fr.nq, sizeof(double));
    CHECK(x0 != NULL);
    if (!x0) {
        gk_rve_destroy(&r), gk_frame_free(&fr);
        return;
    }
    x1 = x0 + 3 * fr.nq;
    CHECK_EQ_INT(frame_positions(&r, &fr, x0), fr.nq);
    CHECK(gk_frame_run(&set, 0, 0, &r, H, dH, 1.0, P, &steps) == GK_OK);
    CHECK_EQ_INT(frame_positions(&r, &fr, x1), fr.nq);
    for (i = 0; i < fr.nq; ++i)
        for (k = 0; k < 2; ++k)
            if (fabs(x1[3 * i + k] - x0[3 * i + k]) > moved) moved = fabs(x1[3 * i + k] - x0[3 * i + k]);
    printf("    dH = 0: P11 %.0f P22 %.0f Pa, %ld DEM steps, %d corrections, frame moved %.3g m\n", P[0],
           P[4], st[0].steps, st[0].servo, moved);
    CHECK(moved <= 1e-6 * r.rmin); /* held, up to the servo's corrections */
    for (k = 0; k < 9; ++k) CHECK(isfinite(P[k]));
    CHECK(P[0] < 0.0 && P[4] < 0.0); /* the packing's compression */
    free(x0);
    gk_rve_destroy(&r);
    gk_frame_free(&fr);
}

/* bad input: no corner particle, a skewed cell, an RVE of another frame, an inverted F, bad settings */
TEST(bad_input_is_refused) {
    gk_frame fr;
    gk_err e;
    gk_packing q;
    gk_rve r;
    gk_rve_def d = law(0u);
    gk_frame_set set;
    double H[9] = {0}, dH[9] = {0}, P[9];
    int steps, p;
    CHECK(load());
    if (!have) return;
    CHECK(gk_packing_init(&q, 2, pk.n, NULL, NULL) == GK_OK);
    gk_m3_copy(pk.h, q.h);
    for (p = 0; p < pk.n; ++p) q.x[p] = pk.x[p] + 1e-6, q.y[p] = pk.y[p] + 1e-6, q.r[p] = pk.r[p];
    CHECK(gk_frame_build(&fr, &q, NULL, &e) == GK_ERR_ARG && strstr(e.msg, "corner"));
    q.h[1] = 1e-3;
    CHECK(gk_frame_build(&fr, &q, NULL, &e) == GK_ERR_ARG && strstr(e.msg, "box"));
    gk_packing_free(&q);
    CHECK(gk_frame_build(&fr, &pk, NULL, &e) == GK_OK);
    memset(&set, 0, sizeof set);
    set.kind = GK_FRAME_SERVO, set.frames = &fr;
    CHECK(gk_rve_create(&r, &d, &pk) == GK_OK); /* the periodic packing: not the framed RVE */
    CHECK(gk_frame_run(&set, 0, 0, &r, H, dH, 1.0, P, &steps) == GK_ERR_ARG);
    gk_rve_destroy(&r);
    CHECK(gk_rve_create(&r, &d, &fr.framed) == GK_OK);
    dH[0] = -1.5;
    CHECK(gk_frame_run(&set, 0, 0, &r, H, dH, 1.0, P, &steps) == GK_ERR_CELL);
    dH[0] = 0.0, set.def.gain_a = -1.0;
    CHECK(gk_frame_run(&set, 0, 0, &r, H, dH, 1.0, P, &steps) == GK_ERR_ARG);
    set.def.gain_a = 0.0, set.kind = (gk_frame_kind)7;
    CHECK(gk_frame_run(&set, 0, 0, &r, H, dH, 1.0, P, &steps) == GK_ERR_ARG);
    gk_rve_destroy(&r);
    gk_frame_free(&fr);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(frame_geometry_and_eq11);
    RUN(energy_of_one_contact_is_eq32);
    RUN(servo_frame_and_periodic_cell_under_compression);
    RUN(locked_rotation_stays_locked);
    RUN(inner_lock_turns_only_the_frame);
    RUN(servo_frame_without_deformation_holds_the_frame);
    RUN(bad_input_is_refused);
    if (have) gk_packing_free(&pk);
    return gk_test_done();
}
