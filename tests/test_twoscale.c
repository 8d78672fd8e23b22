/* test_twoscale.c - gk_twoscale.h: a set of RVEs, one per integration point.
 *
 * The contract is checked against gk_dem.h / gk_homog.h called by hand on one
 * RVE (a run starts from the accepted state; the DEM step rules; eq 8 of Guo &
 * Zhao 2014 by finite differences), then what the set adds: thread-count
 * independence bit for bit, a failed point reported without hiding the
 * others, the checkpoint round trip bit for bit, corrupt checkpoints and bad
 * arguments refused with nothing changed; a set run by the caller's procedure
 * (another micro model on the same RVEs). Small packings (100 and 200
 * disks) keep it to seconds. The MPI build has its own program
 * (tests/mpi_twoscale.c, run by `make test` with mpirun -np 2). */
#define _POSIX_C_SOURCE 200809L /* posix_memalign */
#include "gk_twoscale.h"
#include "gk_test.h"

#define P100 "bench/data/tradeoff/rve100.txt"
#define P200 "bench/data/tradeoff/rve200.txt"
#define DT 2e-5

static gk_packing pk100, pk200;
static int have_packings;

static int load_packings(void) {
    gk_err e;
    if (!have_packings)
        have_packings = gk_packing_read(P100, &pk100, NULL, &e) == GK_OK &&
                        gk_packing_read(P200, &pk200, NULL, &e) == GK_OK;
    return have_packings;
}

/* a set of n points over the two packings (drawn from seed 3) with the given rule and tangent */
static gk_result make_set(gk_twoscale *ts, int n, int threads, gk_twoscale_rule_kind rule,
                          gk_twoscale_tangent_kind tan, double reuse) {
    gk_twoscale_proto pr[2];
    gk_twoscale_def d;
    pr[0].packing = &pk100, pr[0].state = NULL;
    pr[1].packing = &pk200, pr[1].state = NULL;
    memset(&d, 0, sizeof d);
    d.npoints = n, d.protos = pr, d.nprotos = 2, d.seed = 3, d.threads = threads;
    d.rve = gk_rve_def_default();
    d.rve.dt = DT;
    d.rule.kind = rule, d.rule.n_min = 20, d.rule.n_max = 300, d.rule.unbalanced_max = 2e-2;
    d.tangent = tan, d.reuse = reuse;
    return gk_twoscale_create(ts, &d);
}

/* a deterministic, point-dependent dH of step k: compression along y, some shear and spin */
static void step_dH(int n, int k, double amp, double *dH) {
    int p;
    memset(dH, 0, (size_t)n * 9 * sizeof(double));
    for (p = 0; p < n; ++p) {
        double f = 1.0 + 0.1 * ((p * 7 + k * 3) % 5);
        dH[9 * p + 0] = 0.3 * amp * f;
        dH[9 * p + 4] = -amp * f;
        dH[9 * p + 1] = 0.2 * amp * ((p + k) % 3 - 1);
        dH[9 * p + 3] = -0.1 * amp * ((p + 2 * k) % 3 - 1);
    }
}

static int same(const double *a, const double *b, size_t n) { return memcmp(a, b, n * sizeof(double)) == 0; }

/* the public contact iterator: every contact once, ids ordered, and the Love stress rebuilt from its
 * forces and branch vectors, sigma = -(1/V) sum f (x) d (Guo & Zhao 2014 eq 5), is the RVE's own */
TEST(contact_iterator_gives_the_love_stress) {
    gk_rve r;
    gk_rve_def d = gk_rve_def_default();
    gk_rve_contact k;
    double S[9], s[9], V, dH[9] = {1e-4, 2e-4, 0, 0, -5e-4, 0, 0, 0, 0};
    int c = 0, n = 0, ordered = 1, i, j, sl = 0;
    CHECK(load_packings());
    if (!have_packings) return;
    d.dt = DT;
    CHECK(gk_rve_create(&r, &d, &pk200) == GK_OK);
    CHECK(gk_rve_deform(&r, dH, 200) == GK_OK);
    CHECK(gk_rve_refresh(&r) == GK_OK); /* forces at the current positions, as the branch vectors */
    gk_rve_stress(&r, s);
    V = gk_rve_volume(&r);
    gk_m3_zero(S);
    while (gk_rve_contact_next(&r, &c, &k)) {
        ordered &= k.i < k.j && k.i >= 0 && k.j < r.n;
        sl += k.sliding;
        for (i = 0; i < 3; ++i)
            for (j = 0; j < 3; ++j) S[3 * i + j] -= k.f[i] * k.d[j] / V;
        ++n;
    }
    CHECK_EQ_INT(n, r.ncontacts);
    CHECK(n > 100);
    CHECK(ordered);
    CHECK(sl > 0); /* after a shear some contacts slide */
    for (i = 0; i < 9; ++i) CHECK_NEAR(S[i], s[i], 1e-9 * fabs(s[4]));
    CHECK(gk_rve_contact_next(&r, &c, &k) == 0); /* stays at the end */
    gk_rve_destroy(&r);
}

/* a run starts every point from its accepted state: the set's stress and eq 9 tangent are those of
 * gk_rve_deform_adaptive and gk_homog_tangent on a hand-made copy of the RVE; a second trial, a
 * reject and the first dH again give the first result bit for bit; after accept the next run goes on
 * from the accepted trial */
TEST(run_is_the_rve_contract) {
    gk_twoscale ts;
    gk_rve r;
    gk_rve_def rd = gk_rve_def_default();
    gk_adapt_def ad;
    gk_adapt_report rep;
    double dH[9 * 4], dH2[9 * 4], s1[9 * 4], s2[9 * 4], s3[9 * 4], D[16 * 4], sr[9], Dr[16];
    const gk_twoscale_point *pts;
    int k;
    CHECK(load_packings());
    if (!have_packings) return;
    CHECK(make_set(&ts, 4, 1, GK_TWOSCALE_ADAPTIVE, GK_TWOSCALE_TANGENT_HOMOG, 0) == GK_OK);
    step_dH(4, 0, 1e-3, dH);
    step_dH(4, 1, 2e-3, dH2);
    CHECK(gk_twoscale_run(&ts, dH, NULL, s1, D) == GK_OK);
    CHECK(gk_twoscale_run(&ts, dH2, NULL, s2, NULL) == GK_OK);
    CHECK(!same(s1, s2, 36));
    gk_twoscale_reject(&ts);
    CHECK(gk_twoscale_run(&ts, dH, NULL, s3, NULL) == GK_OK);
    CHECK(same(s1, s3, 36));
    /* point 2 by hand: its prototype, refreshed, deformed by the same rule */
    rd.dt = DT;
    CHECK(gk_rve_create(&r, &rd, ts.pick[2] ? &pk200 : &pk100) == GK_OK);
    gk_rve_refresh(&r);
    memset(&ad, 0, sizeof ad);
    ad.unbalanced_max = 2e-2, ad.n_min = 20, ad.n_max = 300;
    CHECK(gk_rve_deform_adaptive(&r, dH + 18, &ad, &rep) == GK_OK);
    gk_rve_stress(&r, sr);
    gk_homog_tangent(&r, 0u, Dr);
    CHECK(same(sr, s1 + 18, 9));
    CHECK(same(Dr, D + 32, 16));
    pts = gk_twoscale_points(&ts);
    CHECK_EQ_INT(pts[2].n_deform, rep.n_deform);
    CHECK_EQ_INT(pts[2].n_relax, rep.n_relax);
    CHECK_EQ_INT(pts[2].tangent, 0); /* the last run asked for none */
    CHECK_EQ_INT(pts[2].particles, r.n);
    CHECK(gk_twoscale_accept(&ts) == GK_OK);
    /* accept copies nothing; the trial below copies the accepted state out of the RVE before it
     * changes it, and reject goes back to that copy: the next run is the by-hand RVE's again */
    CHECK(gk_twoscale_run(&ts, dH, NULL, s3, NULL) == GK_OK);
    gk_twoscale_reject(&ts);
    CHECK(gk_twoscale_run(&ts, dH2, NULL, s2, NULL) == GK_OK);
    CHECK(gk_rve_deform_adaptive(&r, dH2 + 18, &ad, &rep) == GK_OK);
    gk_rve_stress(&r, sr);
    CHECK(same(sr, s2 + 18, 9));
    /* the fields are of the accepted state: after accept, this run's H is the sum */
    CHECK(gk_twoscale_accept(&ts) == GK_OK);
    {
        gk_twoscale_field f[4];
        CHECK(gk_twoscale_fields(&ts, f) == GK_OK);
        for (k = 0; k < 4; ++k) CHECK(f[k].H[4] == dH[9 * k + 4] + dH2[9 * k + 4]);
        CHECK(same(f[2].stress, sr, 9));
        CHECK_NEAR(f[2].p, gk_stress_p(sr, 2), 0);
        CHECK_NEAR(f[2].void_ratio, gk_homog_void_ratio(&r), 0);
        CHECK_EQ_INT((int)f[2].dem_steps, rep.n_deform + rep.n_relax);
    }
    gk_rve_destroy(&r);
    gk_twoscale_destroy(&ts);
}

/* the strain rule: n = ceil(max|dH| / strain) clamped (Guo & Zhao 2014's scripts: 1e-5 per step); a cut-back
 * run (scale 1/4) keeps the full increment's count */
TEST(strain_rule_counts_and_cut_back_scale) {
    gk_twoscale ts;
    gk_twoscale_run_def rd;
    double dH[9 * 2], s[9 * 2];
    const gk_twoscale_point *pts;
    CHECK(load_packings());
    if (!have_packings) return;
    CHECK(make_set(&ts, 2, 1, GK_TWOSCALE_STRAIN, GK_TWOSCALE_TANGENT_HOMOG, 0) == GK_OK);
    memset(dH, 0, sizeof dH);
    dH[4] = -1.234e-3, dH[9 + 4] = -1e-2; /* 124 steps; 1000 clamped to n_max = 300 */
    CHECK(gk_twoscale_run(&ts, dH, NULL, s, NULL) == GK_OK);
    pts = gk_twoscale_points(&ts);
    CHECK_EQ_INT(pts[0].n_deform, 124);
    CHECK_EQ_INT(pts[0].n_relax, 0);
    CHECK_EQ_INT(pts[1].n_deform, 300);
    dH[4] = -1.234e-3 / 4, dH[9 + 4] = -1e-2 / 4;
    rd.scale = 0.25;
    CHECK(gk_twoscale_run(&ts, dH, &rd, s, NULL) == GK_OK);
    CHECK_EQ_INT(pts[0].n_deform, 124);
    CHECK_EQ_INT(pts[0].work, 124);
    gk_twoscale_destroy(&ts);
}

/* eq 8 (Guo & Zhao 2014): D_ijkl = (sigma_ij(dH + xi e_kl) - sigma_ij(dH)) / xi with the trial run's
 * DEM step counts. Strain rule: from four more runs of a set with that count fixed; adaptive rule
 * (the trial run relaxes too; its perturbed runs run after it and replay its deformation and
 * relaxation counts): from gk_rve_deform and gk_rve_step by hand. Equal bit for bit. */
TEST(perturbation_tangent_is_eq8) {
    int rule;
    CHECK(load_packings());
    if (!have_packings) return;
    for (rule = 0; rule < 2; ++rule) {
        gk_twoscale ts;
        double dH[9], Hp[9], s0[9], sp[9], D[16], Dh[16], xi = 5e-5;
        const gk_twoscale_point *pts;
        int k, i, j, nd, nr;
        gk_twoscale_proto pr;
        gk_twoscale_def d;
        pr.packing = &pk100, pr.state = NULL;
        memset(&d, 0, sizeof d);
        d.npoints = 1, d.protos = &pr, d.nprotos = 1;
        d.rve = gk_rve_def_default();
        d.rve.dt = DT;
        d.rule.kind = (gk_twoscale_rule_kind)rule, d.rule.n_min = 20, d.rule.n_max = 300;
        d.rule.unbalanced_max = 1e-3; /* the adaptive rule relaxes too */
        d.tangent = GK_TWOSCALE_TANGENT_PERTURBATION;
        CHECK(gk_twoscale_create(&ts, &d) == GK_OK);
        step_dH(1, 0, 1e-3, dH);
        CHECK(gk_twoscale_run(&ts, dH, NULL, s0, D) == GK_OK);
        pts = gk_twoscale_points(&ts);
        nd = pts[0].n_deform, nr = pts[0].n_relax;
        CHECK_EQ_INT(pts[0].tangent, 1);
        CHECK_EQ_INT(pts[0].work, (rule ? 5 : 6) * (nd + nr)); /* adaptive: trial, 4 perturbed, trial again */
        gk_twoscale_destroy(&ts);
        if (rule == GK_TWOSCALE_ADAPTIVE) {
            gk_rve r;
            gk_rve_state st;
            double L0[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
            CHECK(nr > 0);
            CHECK(gk_rve_create(&r, &d.rve, &pk100) == GK_OK);
            gk_rve_refresh(&r);
            gk_rve_state_init(&st, NULL);
            gk_rve_state_save(&st, &r);
            for (k = 0; k < 4; ++k) {
                int done = 0;
                memcpy(Hp, dH, sizeof Hp);
                Hp[3 * (k / 2) + k % 2] += xi;
                gk_rve_state_restore(&st, &r);
                CHECK(gk_rve_deform(&r, Hp, nd) == GK_OK);
                gk_rve_set_velocity_gradient(&r, L0);
                for (; done < nr; done += 20)
                    CHECK(gk_rve_step(&r, nr - done < 20 ? nr - done : 20) == GK_OK);
                gk_rve_stress(&r, sp);
                for (i = 0; i < 2; ++i)
                    for (j = 0; j < 2; ++j) Dh[(i * 2 + j) * 4 + k] = (sp[3 * i + j] - s0[3 * i + j]) / xi;
            }
            gk_rve_state_free(&st);
            gk_rve_destroy(&r);
        } else {
            d.tangent = GK_TWOSCALE_TANGENT_HOMOG;
            d.rule.n_min = d.rule.n_max = nd;
            CHECK(gk_twoscale_create(&ts, &d) == GK_OK);
            for (k = 0; k < 4; ++k) {
                memcpy(Hp, dH, sizeof Hp);
                Hp[3 * (k / 2) + k % 2] += xi;
                CHECK(gk_twoscale_run(&ts, Hp, NULL, sp, NULL) == GK_OK);
                for (i = 0; i < 2; ++i)
                    for (j = 0; j < 2; ++j) Dh[(i * 2 + j) * 4 + k] = (sp[3 * i + j] - s0[3 * i + j]) / xi;
            }
            gk_twoscale_destroy(&ts);
        }
        CHECK(same(D, Dh, 16));
        CHECK(D[0] > 0 && D[15] > 0); /* a stretch along x or y makes sigma less compressive */
    }
}

/* results independent of the thread count, bit for bit: 1 and 2 threads, over accepted steps, with
 * the eq 9 tangent and with eq 8 and tangent reuse (which also reuses) */
TEST(thread_count_does_not_change_a_bit) {
    int mode;
    CHECK(load_packings());
    if (!have_packings) return;
    for (mode = 0; mode < 2; ++mode) {
        gk_twoscale a, b;
        double dH[9 * 6], sa[9 * 6], sb[9 * 6], Da[16 * 6], Db[16 * 6];
        gk_twoscale_field fa[6], fb[6];
        int k, reused = 0, ok = 1;
        gk_twoscale_tangent_kind t = mode ? GK_TWOSCALE_TANGENT_PERTURBATION : GK_TWOSCALE_TANGENT_HOMOG;
        CHECK(make_set(&a, 6, 1, GK_TWOSCALE_ADAPTIVE, t, mode ? 0.5 : 0) == GK_OK);
        CHECK(make_set(&b, 6, 2, GK_TWOSCALE_ADAPTIVE, t, mode ? 0.5 : 0) == GK_OK);
        for (k = 0; k < 3; ++k) {
            step_dH(6, k, 5e-4, dH);
            ok &= gk_twoscale_run(&a, dH, NULL, sa, Da) == GK_OK &&
                  gk_twoscale_run(&b, dH, NULL, sb, Db) == GK_OK;
            ok &= same(sa, sb, 54) && same(Da, Db, 96);
            ok &= !memcmp(gk_twoscale_points(&a), gk_twoscale_points(&b), 6 * sizeof(gk_twoscale_point));
            reused += gk_twoscale_points(&a)[0].tangent == 2;
            gk_twoscale_accept(&a), gk_twoscale_accept(&b);
        }
        CHECK(ok);
        CHECK(gk_twoscale_fields(&a, fa) == GK_OK && gk_twoscale_fields(&b, fb) == GK_OK);
        CHECK(memcmp(fa, fb, sizeof fa) == 0);
        if (mode) CHECK(reused > 0); /* small steps: the network changes little, the tangent is kept */
        gk_twoscale_destroy(&a), gk_twoscale_destroy(&b);
    }
}

/* a point whose RVE fails (dH inverts its cell: GK_ERR_SINGULAR from gk_rve_deform) is
 * named with its message; every other point's result is the one it has without the failure; a second
 * failing point is named too; accept keeps the failed points at their accepted state */
TEST(one_failed_point_does_not_hide_the_others) {
    gk_twoscale ts;
    double dH[9 * 6], good[9 * 6], s[9 * 6], D[16 * 6], Dg[16 * 6];
    gk_twoscale_field f0[6], f1[6];
    const gk_twoscale_point *pts;
    int k;
    CHECK(load_packings());
    if (!have_packings) return;
    CHECK(make_set(&ts, 6, 2, GK_TWOSCALE_ADAPTIVE, GK_TWOSCALE_TANGENT_HOMOG, 0) == GK_OK);
    CHECK(gk_twoscale_fields(&ts, f0) == GK_OK);
    step_dH(6, 0, 5e-4, good);
    CHECK(gk_twoscale_run(&ts, good, NULL, s, Dg) == GK_OK);
    memcpy(dH, good, sizeof dH);
    dH[9 * 3 + 4] = -3.0; /* point 3: det(I + dH) = -2 inverts the cell, refused (gk_pcell.h) */
    CHECK(gk_twoscale_run(&ts, dH, NULL, s, D) == GK_ERR_STATE);
    pts = gk_twoscale_points(&ts);
    CHECK_EQ_INT(pts[3].code, GK_ERR_SINGULAR);
    CHECK(strstr(gk_twoscale_error(&ts), "1 of 6 points failed; point 3:") != NULL);
    CHECK(strstr(gk_twoscale_point_error(&ts, 3), "cell") != NULL);
    CHECK(gk_twoscale_point_error(&ts, 2)[0] == 0);
    for (k = 0; k < 6; ++k)
        if (k != 3) CHECK_EQ_INT(pts[k].code, GK_OK);
    {
        double sg[9 * 6];
        gk_twoscale_reject(&ts);
        CHECK(gk_twoscale_run(&ts, good, NULL, sg, NULL) == GK_OK);
        gk_twoscale_reject(&ts);
        CHECK(gk_twoscale_run(&ts, dH, NULL, s, D) == GK_ERR_STATE);
        for (k = 0; k < 6; ++k)
            if (k != 3) CHECK(same(s + 9 * k, sg + 9 * k, 9) && same(D + 16 * k, Dg + 16 * k, 16));
        CHECK(same(s + 27, f0[3].stress, 9)); /* the failed point: its accepted stress, a zero tangent */
        for (k = 0; k < 16; ++k) CHECK(D[48 + k] == 0.0);
    }
    dH[9 * 5 + 4] = -3.0; /* and point 5 */
    CHECK(gk_twoscale_run(&ts, dH, NULL, s, NULL) == GK_ERR_STATE);
    CHECK(strstr(gk_twoscale_error(&ts), "2 of 6 points failed; point 3:") != NULL);
    CHECK(strstr(gk_twoscale_error(&ts), "(also points 5)") != NULL);
    CHECK(gk_twoscale_point_error(&ts, 5)[0] != 0);
    CHECK(gk_twoscale_accept(&ts) == GK_OK);
    CHECK(gk_twoscale_fields(&ts, f1) == GK_OK);
    CHECK(same(f1[3].stress, f0[3].stress, 9) && same(f1[5].stress, f0[5].stress, 9));
    CHECK(f1[3].H[4] == 0.0 && f1[0].H[4] == dH[4]);
    CHECK(!same(f1[0].stress, f0[0].stress, 9));
    gk_twoscale_destroy(&ts);
}

/* save after two accepted steps (with tangent reuse on, so the references matter), go on two steps;
 * a fresh set loaded from the file goes on to the same bits, and gets the driver's block back */
TEST(checkpoint_round_trip_is_bit_identical) {
    gk_twoscale a, b;
    double dH[9 * 8], sa[9 * 8], sb[9 * 8], Da[16 * 8], Db[16 * 8];
    gk_twoscale_field fa[8], fb[8];
    const char blk[] = "driver block: step 2";
    void *got = NULL;
    size_t ng = 0;
    int k, j, ok = 1, reused = 0;
    CHECK(load_packings());
    if (!have_packings) return;
    CHECK(make_set(&a, 8, 2, GK_TWOSCALE_ADAPTIVE, GK_TWOSCALE_TANGENT_HOMOG, 0.3) == GK_OK);
    for (k = 0; k < 2; ++k) {
        step_dH(8, k, 2e-3, dH);
        ok &= gk_twoscale_run(&a, dH, NULL, sa, Da) == GK_OK && gk_twoscale_accept(&a) == GK_OK;
    }
    CHECK(gk_twoscale_save(&a, BUILD "/tests/t_ts_ck.bin", blk, sizeof blk) == GK_OK);
    CHECK(make_set(&b, 8, 1, GK_TWOSCALE_ADAPTIVE, GK_TWOSCALE_TANGENT_HOMOG, 0.3) == GK_OK);
    CHECK(gk_twoscale_load(&b, BUILD "/tests/t_ts_ck.bin", &got, &ng) == GK_OK);
    CHECK(ng == sizeof blk && got && memcmp(got, blk, ng) == 0);
    gk_twoscale_free_block(&b, got);
    for (k = 2; k < 5; ++k) { /* large steps: the networks outgrow the loaded key arrays */
        step_dH(8, k, 2e-3, dH);
        ok &=
            gk_twoscale_run(&a, dH, NULL, sa, Da) == GK_OK && gk_twoscale_run(&b, dH, NULL, sb, Db) == GK_OK;
        ok &= same(sa, sb, 72) && same(Da, Db, 128);
        ok &= !memcmp(gk_twoscale_points(&a), gk_twoscale_points(&b), 8 * sizeof(gk_twoscale_point));
        for (j = 0; j < 8; ++j) reused += gk_twoscale_points(&a)[j].tangent == 2;
        gk_twoscale_accept(&a), gk_twoscale_accept(&b);
    }
    CHECK(ok);
    CHECK(reused > 0); /* the loaded references were used */
    CHECK(gk_twoscale_fields(&a, fa) == GK_OK && gk_twoscale_fields(&b, fb) == GK_OK);
    CHECK(memcmp(fa, fb, sizeof fa) == 0);
    gk_twoscale_destroy(&a), gk_twoscale_destroy(&b);
}

static long file_bytes(const char *path, unsigned char **out) {
    FILE *fp = fopen(path, "rb");
    long n;
    if (!fp) return -1;
    fseek(fp, 0, SEEK_END);
    n = ftell(fp);
    fseek(fp, 0, SEEK_SET);
    *out = (unsigned char *)malloc((size_t)n);
    if (!*out || fread(*out, 1, (size_t)n, fp) != (size_t)n) n = -1;
    fclose(fp);
    return n;
}
static void put_bytes(const char *path, const unsigned char *b, long n) {
    FILE *fp = fopen(path, "wb");
    if (!fp) return;
    fwrite(b, 1, (size_t)n, fp);
    fclose(fp);
}
/* the file's checksum made right again after an edit (to reach the checks behind it) */
static void reseal(unsigned char *b, long n) {
    uint64_t h = UINT64_C(0xcbf29ce484222325);
    long i;
    for (i = 0; i < n - 8; ++i) h ^= b[i], h *= UINT64_C(0x100000001b3);
    memcpy(b + n - 8, &h, 8);
}

/* a load that must be refused by name and change nothing: the fields and the next run are as before */
static int refused(gk_twoscale *ts, const char *path, const char *msg, const double *dH,
                   const double *s_before) {
    void *blk = NULL;
    size_t nb = 7;
    double s[9 * 4];
    int ok = gk_twoscale_load(ts, path, &blk, &nb) != GK_OK;
    ok &= strstr(gk_twoscale_error(ts), msg) != NULL && strstr(gk_twoscale_error(ts), path) != NULL;
    ok &= blk == NULL && nb == 7;
    ok &= gk_twoscale_run(ts, dH, NULL, s, NULL) == GK_OK && same(s, s_before, 36);
    gk_twoscale_reject(ts);
    if (!ok) printf("    not refused as expected (%s): %s\n", msg, gk_twoscale_error(ts));
    return ok;
}

/* truncation anywhere, bit flips anywhere, another format version, another set, absurd sizes: each
 * refused with the path and the reason, and the set unchanged */
TEST(corrupt_checkpoints_are_refused_and_change_nothing) {
    gk_twoscale a, b;
    double dH[9 * 4], s[9 * 4], sb[9 * 4];
    unsigned char *img = NULL, *x;
    long n, cut;
    int k, ok;
    const char *bad = BUILD "/tests/t_ts_bad.bin";
    CHECK(load_packings());
    if (!have_packings) return;
    CHECK(make_set(&a, 4, 1, GK_TWOSCALE_ADAPTIVE, GK_TWOSCALE_TANGENT_HOMOG, 0) == GK_OK);
    step_dH(4, 0, 5e-4, dH);
    CHECK(gk_twoscale_run(&a, dH, NULL, s, NULL) == GK_OK && gk_twoscale_accept(&a) == GK_OK);
    CHECK(gk_twoscale_save(&a, BUILD "/tests/t_ts_ck2.bin", "xyz", 3) == GK_OK);
    n = file_bytes(BUILD "/tests/t_ts_ck2.bin", &img);
    CHECK(n > 1000);
    if (n <= 1000) return;
    x = (unsigned char *)malloc((size_t)n);
    /* the set that must not change: b, one step further than the file */
    CHECK(make_set(&b, 4, 2, GK_TWOSCALE_ADAPTIVE, GK_TWOSCALE_TANGENT_HOMOG, 0) == GK_OK);
    CHECK(gk_twoscale_run(&b, dH, NULL, s, NULL) == GK_OK && gk_twoscale_accept(&b) == GK_OK);
    CHECK(gk_twoscale_run(&b, dH, NULL, s, NULL) == GK_OK && gk_twoscale_accept(&b) == GK_OK);
    CHECK(gk_twoscale_run(&b, dH, NULL, sb, NULL) == GK_OK);
    gk_twoscale_reject(&b);
    for (ok = 1, k = 0; k < 12; ++k) { /* truncated: at 12 places from the magic to the checksum */
        cut = k < 11 ? (long)((double)n * k / 11) : n - 1;
        put_bytes(bad, img, cut);
        ok &= refused(&b, bad, cut < 8 ? "not a grainkit" : "", dH, sb);
    }
    CHECK(ok);
    for (ok = 1, k = 0; k < 16; ++k) { /* one bit flipped: header, picks, records, block, checksum */
        long at = k < 15 ? 8 + (long)((double)(n - 9) * k / 15) : n - 3;
        memcpy(x, img, (size_t)n);
        x[at] ^= (unsigned char)(1u << (k % 8));
        put_bytes(bad, x, n);
        ok &= refused(&b, bad, "", dH, sb);
    }
    CHECK(ok);
    memcpy(x, img, (size_t)n); /* format version 3 */
    x[8] = 3;
    reseal(x, n);
    put_bytes(bad, x, n);
    CHECK(refused(&b, bad, "format version 3; this build reads 2", dH, sb));
    memcpy(x, img, (size_t)n); /* this version but a bad checksum */
    x[n / 2] ^= 0x10;
    put_bytes(bad, x, n);
    CHECK(refused(&b, bad, "checksum mismatch", dH, sb));
    memcpy(x, img, (size_t)n); /* an absurd record size (2^40), checksum made right */
    {
        long rec0 = 8 + 32 + 4 * 2 + 4 * 4; /* magic, header, 2 prototypes, 4 picks */
        uint64_t big = (uint64_t)1 << 40;
        memcpy(x + rec0, &big, 8);
        reseal(x, n);
        put_bytes(bad, x, n);
        CHECK(refused(&b, bad, "impossible size", dH, sb));
    }
    memcpy(x, img, (size_t)n); /* another point count in the header, checksum made right */
    x[8 + 16] = 5;
    reseal(x, n);
    put_bytes(bad, x, n);
    CHECK(refused(&b, bad, "holds 5 points", dH, sb));
    put_bytes(bad, (const unsigned char *)"hello", 5);
    CHECK(refused(&b, bad, "not a grainkit two-scale checkpoint", dH, sb));
    CHECK(refused(&b, BUILD "/tests/no_such_dir/ck.bin", "cannot open", dH, sb));
    /* and the intact file still loads */
    {
        void *blk = NULL;
        size_t nb = 0;
        CHECK(gk_twoscale_load(&b, BUILD "/tests/t_ts_ck2.bin", &blk, &nb) == GK_OK && nb == 3);
        gk_twoscale_free_block(&b, blk);
    }
    free(img), free(x);
    gk_twoscale_destroy(&a), gk_twoscale_destroy(&b);
}

/* what a driver's take function saw, and whether it takes the block */
typedef struct take_log {
    int calls, takes;
    size_t n;
    char b[8];
} take_log;
static int take_block(const void *block, size_t nblock, void *user, char *why, size_t nwhy) {
    take_log *t = (take_log *)user;
    ++t->calls, t->n = nblock;
    if (nblock <= sizeof t->b) memcpy(t->b, block, nblock);
    if (!t->takes) return snprintf(why, nwhy, "the driver's step count is out of range"), 1;
    return 0;
}

/* gk_twoscale_load_take: a driver block its take function refuses leaves the set as it was (the next
 * run as before, the error naming the file and take's reason); a block it takes is given to it once,
 * byte for byte, and the set then holds the file's states (the next run is the file's set's) */
TEST(a_refused_driver_block_leaves_the_set_as_it_was) {
    gk_twoscale a, b;
    double dH[9 * 4], s[9 * 4], sa[9 * 4], sb[9 * 4];
    take_log t;
    const char *path = BUILD "/tests/t_ts_take.bin";
    CHECK(load_packings());
    if (!have_packings) return;
    CHECK(make_set(&a, 4, 1, GK_TWOSCALE_ADAPTIVE, GK_TWOSCALE_TANGENT_HOMOG, 0) == GK_OK);
    step_dH(4, 0, 5e-4, dH);
    CHECK(gk_twoscale_run(&a, dH, NULL, s, NULL) == GK_OK && gk_twoscale_accept(&a) == GK_OK);
    CHECK(gk_twoscale_save(&a, path, "xyz", 3) == GK_OK);
    CHECK(gk_twoscale_run(&a, dH, NULL, sa, NULL) == GK_OK); /* the file's set, one run on */
    gk_twoscale_reject(&a);
    /* b: two steps further than the file */
    CHECK(make_set(&b, 4, 2, GK_TWOSCALE_ADAPTIVE, GK_TWOSCALE_TANGENT_HOMOG, 0) == GK_OK);
    CHECK(gk_twoscale_run(&b, dH, NULL, s, NULL) == GK_OK && gk_twoscale_accept(&b) == GK_OK);
    CHECK(gk_twoscale_run(&b, dH, NULL, s, NULL) == GK_OK && gk_twoscale_accept(&b) == GK_OK);
    CHECK(gk_twoscale_run(&b, dH, NULL, sb, NULL) == GK_OK);
    gk_twoscale_reject(&b);
    CHECK(!same(sa, sb, 36));
    memset(&t, 0, sizeof t);
    CHECK_EQ_INT(gk_twoscale_load_take(&b, path, take_block, &t), GK_ERR_FORMAT);
    CHECK(t.calls == 1 && t.n == 3 && memcmp(t.b, "xyz", 3) == 0);
    CHECK(strstr(gk_twoscale_error(&b), path) && strstr(gk_twoscale_error(&b), "step count is out of range"));
    CHECK(gk_twoscale_run(&b, dH, NULL, s, NULL) == GK_OK && same(s, sb, 36)); /* unchanged */
    gk_twoscale_reject(&b);
    t.takes = 1, t.calls = 0;
    CHECK_EQ_INT(gk_twoscale_load_take(&b, path, take_block, &t), GK_OK);
    CHECK(t.calls == 1 && t.n == 3 && memcmp(t.b, "xyz", 3) == 0);
    CHECK(gk_twoscale_run(&b, dH, NULL, s, NULL) == GK_OK && same(s, sa, 36)); /* the file's states */
    gk_twoscale_reject(&b);
    CHECK_EQ_INT(gk_twoscale_load_take(&b, path, NULL, &t), GK_ERR_ARG);
    gk_twoscale_destroy(&a), gk_twoscale_destroy(&b);
}

/* the caller's procedure: a stand-in that deforms the RVE by dH over 40 DEM steps (gk_rve_deform) and
 * returns twice the Love stress (another measure than the set's own); it records what it was given,
 * and fails at a point asked to */
typedef struct proc_log {
    int point[8], proto[8], fail_at;
    double H4[8];
} proc_log;
static gk_result double_love(void *user, int point, int proto, gk_rve *rve, const double H[9],
                             const double dH[9], double scale, double stress[9], int *steps) {
    proc_log *lg = (proc_log *)user;
    gk_result r;
    int k;
    (void)scale;
    lg->point[point] = point, lg->proto[point] = proto, lg->H4[point] = H[4]; /* its own slot only */
    if (point == lg->fail_at)
        return gk_err_set(&rve->err, GK_ERR_NOCONVERGE, "stand-in failure at %d", point);
    if ((r = gk_rve_deform(rve, dH, 40)) != GK_OK) return r;
    gk_rve_stress(rve, stress);
    for (k = 0; k < 9; ++k) stress[k] *= 2.0;
    *steps = 40;
    return GK_OK;
}

static gk_result make_proc_set(gk_twoscale *ts, int threads, proc_log *lg) {
    gk_twoscale_proto pr[2];
    gk_twoscale_def d;
    pr[0].packing = &pk100, pr[0].state = NULL;
    pr[1].packing = &pk200, pr[1].state = NULL;
    memset(&d, 0, sizeof d);
    d.npoints = 4, d.protos = pr, d.nprotos = 2, d.seed = 3, d.threads = threads;
    d.rve = gk_rve_def_default();
    d.rve.dt = DT;
    d.proc = double_love, d.proc_user = lg;
    return gk_twoscale_create(ts, &d);
}

/* with a procedure every point runs it from its accepted state (given H and dH): the set returns, keeps
 * (accepted, fields, checkpoint) and restores exactly the procedure's stress, not the RVE's Love stress;
 * 0 before the first accepted run; no tangent; a failing point reports the procedure's message */
TEST(caller_procedure_runs_every_point) {
    gk_twoscale a, b;
    gk_rve r;
    gk_rve_def rd = gk_rve_def_default();
    proc_log lg, lgb;
    gk_twoscale_field f[4];
    double dH[9 * 4], dH2[9 * 4], s[9 * 4], s2[9 * 4], sb[9 * 4], acc[9 * 4], D[16 * 4], sr[9];
    const gk_twoscale_point *pts;
    void *blk = NULL;
    size_t nb = 0;
    int k;
    CHECK(load_packings());
    if (!have_packings) return;
    memset(&lg, 0, sizeof lg), memset(&lgb, 0, sizeof lgb);
    lg.fail_at = lgb.fail_at = -1;
    CHECK(make_proc_set(&a, 2, &lg) == GK_OK);
    CHECK(gk_twoscale_accepted(&a, acc, NULL) == GK_OK);
    for (k = 0; k < 36; ++k) CHECK(acc[k] == 0.0);
    step_dH(4, 0, 1e-3, dH);
    step_dH(4, 1, 1e-3, dH2);
    CHECK(gk_twoscale_run(&a, dH, NULL, s, D) == GK_ERR_ARG && strstr(gk_twoscale_error(&a), "no tangent"));
    CHECK(gk_twoscale_run(&a, dH, NULL, s, NULL) == GK_OK);
    for (k = 0; k < 4; ++k) CHECK(lg.point[k] == k && lg.proto[k] == a.pick[k] && lg.H4[k] == 0.0);
    /* point 3 by hand: its prototype refreshed, the same 40 steps, twice the Love stress */
    rd.dt = DT;
    CHECK(gk_rve_create(&r, &rd, a.pick[3] ? &pk200 : &pk100) == GK_OK);
    gk_rve_refresh(&r);
    CHECK(gk_rve_deform(&r, dH + 27, 40) == GK_OK);
    gk_rve_stress(&r, sr);
    for (k = 0; k < 9; ++k) CHECK(s[27 + k] == 2.0 * sr[k]);
    gk_rve_destroy(&r);
    pts = gk_twoscale_points(&a);
    CHECK(pts[1].work == 40 && pts[1].code == GK_OK && pts[1].tangent == 0);
    CHECK(gk_twoscale_accept(&a) == GK_OK);
    CHECK(gk_twoscale_accepted(&a, acc, NULL) == GK_OK && same(acc, s, 36));
    CHECK(gk_twoscale_accepted(&a, acc, D) == GK_ERR_ARG);
    CHECK(gk_twoscale_fields(&a, f) == GK_OK && same(f[2].stress, s + 18, 9) &&
          f[2].p == gk_stress_p(s + 18, 2));
    CHECK(gk_twoscale_save(&a, BUILD "/tests/t_ts_proc.bin", "x", 1) == GK_OK);
    CHECK(gk_twoscale_run(&a, dH2, NULL, s2, NULL) == GK_OK);
    for (k = 0; k < 4; ++k) CHECK(lg.H4[k] == dH[9 * k + 4]); /* the accepted H */
    /* a fresh set from the checkpoint (one thread): the accepted stress and the next run, bit for bit */
    CHECK(make_proc_set(&b, 1, &lgb) == GK_OK);
    CHECK(gk_twoscale_load(&b, BUILD "/tests/t_ts_proc.bin", &blk, &nb) == GK_OK && nb == 1);
    gk_twoscale_free_block(&b, blk);
    CHECK(gk_twoscale_accepted(&b, acc, NULL) == GK_OK && same(acc, s, 36));
    CHECK(gk_twoscale_run(&b, dH2, NULL, sb, NULL) == GK_OK && same(sb, s2, 36));
    gk_twoscale_reject(&b);
    lgb.fail_at = 2; /* one failing point: its message, its accepted stress, the others untouched */
    CHECK(gk_twoscale_run(&b, dH2, NULL, sb, NULL) == GK_ERR_STATE);
    CHECK(strstr(gk_twoscale_point_error(&b, 2), "stand-in failure at 2") != NULL);
    CHECK(same(sb + 18, s + 18, 9) && same(sb, s2, 18) && same(sb + 27, s2 + 27, 9));
    gk_twoscale_destroy(&a), gk_twoscale_destroy(&b);
}

/* an allocator that refuses requests of 16 KiB and more while refuse is set (an RVE's state, not a
 * message) */
typedef struct gate {
    int refuse;
} gate;
static void *gate_alloc(size_t size, size_t align, void *user) {
    void *p = NULL;
    if ((((gate *)user)->refuse && size >= 16384) ||
        posix_memalign(&p, align < sizeof(void *) ? sizeof(void *) : align, size))
        return NULL;
    return p;
}
static void gate_free(void *p, void *user) {
    (void)user;
    free(p);
}

/* a procedure that, while *grow, first adds 256 small disks on a grid (the RVE's state then outgrows
 * the room of the copy made at creation), then deforms by dH over 40 DEM steps */
static gk_result grow_then_deform(void *user, int point, int proto, gk_rve *rve, const double H[9],
                                  const double dH[9], double scale, double stress[9], int *steps) {
    gk_result res;
    (void)point, (void)proto, (void)H, (void)scale;
    if (*(const int *)user) {
        double sx[256], sy[256], r[256];
        const double *sp[3];
        int32_t id[256];
        int q;
        for (q = 0; q < 256; ++q)
            sx[q] = (q % 16 + 0.5) / 16, sy[q] = (q / 16 + 0.5) / 16, r[q] = 0.3 * rve->rmin,
            id[q] = 100000 + q;
        sp[0] = sx, sp[1] = sy, sp[2] = NULL;
        if ((res = gk_rve_append(rve, 256, sp, r, id)) != GK_OK) return res;
    }
    if ((res = gk_rve_deform(rve, dH, 40)) != GK_OK) return res;
    gk_rve_stress(rve, stress);
    *steps = 40;
    return GK_OK;
}

/* accept copies no state: a run copies it out of the RVE before changing it. A point whose copy
 * finds no memory fails with GK_ERR_ALLOC and keeps its accepted state: once memory is back, the
 * run gives the bits of a set that never ran short */
TEST(a_copy_of_the_accepted_state_without_memory_changes_nothing) {
    gk_twoscale a, b;
    gk_twoscale_proto pr;
    gk_twoscale_def d;
    gate g = {0};
    int grow = 1, k;
    double dH[9 * 4], dH2[9 * 4], sa[9 * 4], sb[9 * 4];
    gk_twoscale_field fa[4], fb[4];
    const gk_twoscale_point *pts;
    CHECK(load_packings());
    if (!have_packings) return;
    pr.packing = &pk200, pr.state = NULL;
    memset(&d, 0, sizeof d);
    d.npoints = 4, d.protos = &pr, d.nprotos = 1, d.threads = 2;
    d.rve = gk_rve_def_default();
    d.rve.dt = DT;
    d.proc = grow_then_deform, d.proc_user = &grow;
    CHECK(gk_twoscale_create(&b, &d) == GK_OK);
    d.alloc.alloc = gate_alloc, d.alloc.free = gate_free, d.alloc.user = &g;
    d.rve.alloc = d.alloc;
    CHECK(gk_twoscale_create(&a, &d) == GK_OK);
    step_dH(4, 0, 1e-3, dH);
    step_dH(4, 1, 1e-3, dH2);
    CHECK(gk_twoscale_run(&a, dH, NULL, sa, NULL) == GK_OK && gk_twoscale_accept(&a) == GK_OK);
    CHECK(gk_twoscale_run(&b, dH, NULL, sb, NULL) == GK_OK && gk_twoscale_accept(&b) == GK_OK);
    CHECK(same(sa, sb, 36));
    grow = 0;
    g.refuse = 1;
    CHECK(gk_twoscale_run(&a, dH2, NULL, sa, NULL) == GK_ERR_STATE);
    g.refuse = 0;
    pts = gk_twoscale_points(&a);
    for (k = 0; k < 4; ++k) CHECK_EQ_INT(pts[k].code, GK_ERR_ALLOC);
    CHECK(strstr(gk_twoscale_point_error(&a, 1), "out of memory for the copy of its accepted state") != NULL);
    CHECK(gk_twoscale_run(&a, dH2, NULL, sa, NULL) == GK_OK && gk_twoscale_accept(&a) == GK_OK);
    CHECK(gk_twoscale_run(&b, dH2, NULL, sb, NULL) == GK_OK && gk_twoscale_accept(&b) == GK_OK);
    CHECK(same(sa, sb, 36));
    CHECK(gk_twoscale_fields(&a, fa) == GK_OK && gk_twoscale_fields(&b, fb) == GK_OK);
    CHECK(memcmp(fa, fb, sizeof fa) == 0 && gk_twoscale_points(&a)[0].particles == 456);
    gk_twoscale_destroy(&a), gk_twoscale_destroy(&b);
}

/* bad arguments: a message naming the value, and nothing changed */
TEST(bad_arguments_are_refused) {
    gk_twoscale ts;
    gk_twoscale_proto pr = {NULL, NULL};
    gk_twoscale_def d;
    gk_twoscale_run_def rd;
    double dH[9 * 3], s[9 * 3], s0[9 * 3], keep[9 * 3], x;
    int pick[3] = {0, 2, 0}, k;
    CHECK(load_packings());
    if (!have_packings) return;
    memset(&d, 0, sizeof d);
    CHECK(gk_twoscale_create(&ts, &d) == GK_ERR_ARG);
    CHECK(strstr(gk_twoscale_error(&ts), "npoints 0") != NULL);
    d.npoints = 3;
    CHECK(gk_twoscale_create(&ts, &d) == GK_ERR_ARG); /* no prototypes */
    d.protos = &pr, d.nprotos = 1;
    CHECK(gk_twoscale_create(&ts, &d) == GK_ERR_ARG && strstr(gk_twoscale_error(&ts), "no packing"));
    pr.packing = &pk100;
    d.pick = pick;
    CHECK(gk_twoscale_create(&ts, &d) == GK_ERR_ARG && strstr(gk_twoscale_error(&ts), "pick[1] = 2"));
    d.pick = NULL;
    d.rule.n_min = 50, d.rule.n_max = 40;
    CHECK(gk_twoscale_create(&ts, &d) == GK_ERR_ARG && strstr(gk_twoscale_error(&ts), "n_min 50 exceeds"));
    d.rule.n_min = 0, d.rule.n_max = 0, d.reuse = 1.0;
    CHECK(gk_twoscale_create(&ts, &d) == GK_ERR_ARG && strstr(gk_twoscale_error(&ts), "reuse"));
    d.reuse = 0, d.rule.inertial_max = NAN;
    CHECK(gk_twoscale_create(&ts, &d) == GK_ERR_ARG);
    d.rule.inertial_max = 0, d.balance = (gk_twoscale_balance_kind)2; /* neither ACCEPT nor RUN */
    CHECK(gk_twoscale_create(&ts, &d) == GK_ERR_ARG && strstr(gk_twoscale_error(&ts), "balance rule 2"));
    d.balance = GK_TWOSCALE_BALANCE_ACCEPT;
    d.rule.inertial_max = 0, d.rve = gk_rve_def_default(), d.rve.dt = 1.0; /* above the critical step */
    CHECK(gk_twoscale_create(&ts, &d) == GK_ERR_DT && strstr(gk_twoscale_error(&ts), "prototype 0"));
    d.rve.dt = DT;
    CHECK(gk_twoscale_create(&ts, &d) == GK_OK);
    CHECK(gk_twoscale_accept(&ts) == GK_ERR_STATE); /* nothing to accept */
    step_dH(3, 0, 5e-4, dH);
    CHECK(gk_twoscale_run(&ts, dH, NULL, s0, NULL) == GK_OK);
    CHECK(gk_twoscale_fields(&ts, NULL) == GK_ERR_STATE); /* a run is pending */
    gk_twoscale_reject(&ts);
    for (k = 0; k < 27; ++k) s[k] = keep[k] = -1.0;
    x = dH[9 * 2 + 1], dH[9 * 2 + 1] = NAN;
    CHECK(gk_twoscale_run(&ts, dH, NULL, s, NULL) == GK_ERR_NAN && strstr(gk_twoscale_error(&ts), "point 2"));
    dH[9 * 2 + 1] = x, dH[9 * 1 + 8] = 1e-3; /* out of plane in 2D */
    CHECK(gk_twoscale_run(&ts, dH, NULL, s, NULL) == GK_ERR_ARG &&
          strstr(gk_twoscale_error(&ts), "in-plane"));
    dH[9 * 1 + 8] = 0;
    rd.scale = 2.0;
    CHECK(gk_twoscale_run(&ts, dH, &rd, s, NULL) == GK_ERR_ARG && strstr(gk_twoscale_error(&ts), "scale 2"));
    CHECK(gk_twoscale_run(&ts, NULL, NULL, s, NULL) == GK_ERR_ARG);
    CHECK(same(s, keep, 27));                       /* outputs untouched */
    CHECK(gk_twoscale_accept(&ts) == GK_ERR_STATE); /* refused runs leave nothing to accept */
    CHECK(gk_twoscale_save(&ts, NULL, NULL, 0) == GK_ERR_ARG);
    CHECK(gk_twoscale_save(&ts, BUILD "/tests/no_such_dir/ck.bin", NULL, 0) == GK_ERR_IO);
    CHECK(gk_twoscale_run(&ts, dH, NULL, s, NULL) == GK_OK && same(s, s0, 27)); /* still the same set */
    gk_twoscale_destroy(&ts);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(contact_iterator_gives_the_love_stress);
    RUN(run_is_the_rve_contract);
    RUN(strain_rule_counts_and_cut_back_scale);
    RUN(perturbation_tangent_is_eq8);
    RUN(thread_count_does_not_change_a_bit);
    RUN(one_failed_point_does_not_hide_the_others);
    RUN(checkpoint_round_trip_is_bit_identical);
    RUN(corrupt_checkpoints_are_refused_and_change_nothing);
    RUN(a_refused_driver_block_leaves_the_set_as_it_was);
    RUN(caller_procedure_runs_every_point);
    RUN(a_copy_of_the_accepted_state_without_memory_changes_nothing);
    RUN(bad_arguments_are_refused);
    if (have_packings) gk_packing_free(&pk100), gk_packing_free(&pk200);
    return gk_test_done();
}
