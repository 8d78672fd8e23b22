/* test_untrusted.c - every file, flag and state buffer is untrusted input.
 *
 * One named test per defect: each feeds the library (or a tool) the input
 * that used to crash it, allocate what a header announced, or finish with
 * GK_OK / exit 0 and a wrong or missing result, and checks the promise of
 * gk_base.h instead: a result code with a message that names the problem,
 * the caller's data unchanged, and memory that follows what the input holds.
 * The same inputs are kept for the fuzz harnesses in tests/fuzz/crashers/.
 * The tool tests run build/gk_pack, build/rve_path and build/bench_tradeoff
 * (`make test` builds them first). Every test takes well under a second.
 */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#define GK_TEST_DRIVERS
#include "gk_fem.h"
#include "gk_homog.h"
#include "gk_io.h"
#include "gk_mpm.h"
#include "gk_test.h"
#include "gk_twoscale.h"
#include <stddef.h>
#include <sys/stat.h>
#include <sys/wait.h>

static const char *RVE400 = "examples/data/rve400.txt";
#define LOG(name) " > " BUILD "/tests/t_untrusted_" name ".out 2>&1"
#define OUT(name) BUILD "/tests/t_untrusted_" name

/* ------------------------------------------------------------- helpers */
/* an allocator that records the largest request and refuses anything above cap */
typedef struct counting {
    size_t largest, cap;
} counting;
static void *counting_alloc(size_t size, size_t align, void *user) {
    counting *c = (counting *)user;
    void *p = NULL;
    if (size > c->largest) c->largest = size;
    if (size > c->cap || posix_memalign(&p, align < sizeof(void *) ? sizeof(void *) : align, size))
        return NULL;
    return p;
}
static void counting_free(void *p, void *user) {
    (void)user;
    free(p);
}
static gk_allocator counting_allocator(counting *c, size_t cap) {
    gk_allocator a;
    c->largest = 0;
    c->cap = cap;
    a.alloc = counting_alloc;
    a.free = counting_free;
    a.user = c;
    return a;
}

static int run_status(const char *cmd) {
    int st = system(cmd);
    return st != -1 && WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static int exists(const char *path) {
    struct stat sb;
    return stat(path, &sb) == 0;
}

static gk_result seed_rve(gk_rve *rve) {
    gk_packing pk;
    gk_err e;
    gk_rve_def def = gk_rve_def_default();
    gk_result r = gk_packing_read(RVE400, &pk, NULL, &e);
    if (r) return r;
    r = gk_rve_create(rve, &def, &pk);
    gk_packing_free(&pk);
    return r;
}

/* the RVE's whole state, to check that a refused call changed nothing */
static unsigned char *snapshot(const gk_rve *rve, size_t *n) {
    unsigned char *b;
    *n = gk_rve_state_size(rve);
    b = (unsigned char *)malloc(*n);
    if (b) gk_rve_save(rve, b, *n, NULL);
    return b;
}
static int unchanged(const gk_rve *rve, const unsigned char *snap, size_t n) {
    size_t m;
    unsigned char *now = snapshot(rve, &m);
    int same = now && m == n && memcmp(now, snap, n) == 0;
    free(now);
    return same;
}

/* =========================================================== packings */
/* A 17-byte header announcing 2e9 particles: refused from the text (it
 * lists none) before anything is allocated; the old reader asked for
 * 4 x 16 GB first. The largest request must stay at the size of the text. */
TEST(packing_header_of_2e9_particles_allocates_nothing) {
    const char *txt = "2 2000000000 1 1\n";
    counting c;
    gk_allocator a = counting_allocator(&c, (size_t)1 << 20);
    gk_packing pk;
    gk_err e;
    CHECK_EQ_INT(strlen(txt), 17);
    CHECK_EQ_INT(gk_packing_parse(txt, strlen(txt), &pk, &a, &e), GK_ERR_FORMAT);
    CHECK(strstr(e.msg, "lists 0") != NULL);
    CHECK(c.largest <= 64);
    printf("    %s (largest allocation %lu bytes)\n", e.msg, (unsigned long)c.largest);
}

/* Two-line packings with huge cells (one disk in a 2e9, 3e9 or 1e12 m box):
 * valid, if odd, inputs. The bins are sized in double and capped, so the
 * RVE is created and deforms, with no contact and a zero stress. The old
 * cell list cast w / cutoff to int (undefined beyond 2^31), grew
 * nbin * 3 / 4 in int, and reported 'could not order' or asked for 2e18
 * bins. A cell whose volume overflows a double (1e300 x 1e300) is refused
 * by the reader. */
TEST(packing_huge_cells_bin_without_overflow) {
    const char *L[3] = {"2e9", "3e9", "1e12"};
    int k;
    for (k = 0; k < 3; ++k) {
        char txt[128];
        gk_packing pk;
        gk_err e;
        gk_rve rve;
        gk_rve_def def = gk_rve_def_default();
        double dH[9] = {0, 1e-4, 0, 0, 0, 0, 0, 0, 0};
        snprintf(txt, sizeof txt, "2 1 %s %s\n0 0 1\n", L[k], L[k]);
        CHECK(gk_packing_parse(txt, strlen(txt), &pk, NULL, &e) == GK_OK);
        if (gk_rve_create(&rve, &def, &pk) != GK_OK) {
            printf("    cell %s: %s\n", L[k], gk_rve_error(&rve));
            CHECK(0);
            gk_packing_free(&pk);
            continue;
        }
        CHECK(gk_rve_deform(&rve, dH, 2) == GK_OK);
        CHECK(rve.ncontacts == 0 && rve.stress[0] == 0.0 && rve.cells.nbins <= 2 * 1 + 27);
        gk_rve_destroy(&rve);
        gk_packing_free(&pk);
    }
    {
        const char *inf = "2 1 1e300 1e300\n0 0 1\n";
        gk_packing pk;
        gk_err e;
        CHECK_EQ_INT(gk_packing_parse(inf, strlen(inf), &pk, NULL, &e), GK_ERR_CELL);
        printf("    1e300 x 1e300: %s\n", e.msg);
    }
}

/* The cell list itself: a cutoff of 1e-12 in a unit cell bins (w / cutoff
 * = 1e12 bins per axis asked, capped, then shrunk to <= 2n + 27), and
 * finds the one close pair; a NaN or infinite reduced coordinate is
 * GK_ERR_NAN (it was cast to int: undefined). */
TEST(cells_tiny_cutoff_and_nan_positions) {
    double h[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, sx[3] = {0.1, 0.1 + 1e-13, 0.7}, sy[3] = {0.5, 0.5, 0.2};
    gk_real r[3] = {1e-13, 1e-13, 1e-13};
    const double *s[3];
    gk_cells c;
    gk_pairlist pl;
    gk_err e;
    s[0] = sx, s[1] = sy, s[2] = NULL;
    gk_cells_init(&c, NULL);
    gk_pairlist_init(&pl, NULL);
    CHECK(gk_cells_bin(&c, 2, h, 3, s, 1e-12, &e) == GK_OK);
    CHECK(c.nbins >= 1 && c.nbins <= 2 * 3 + 27);
    CHECK(gk_cells_pairs(&c, h, s, r, 0.0, &pl, &e) == GK_OK);
    CHECK(pl.n == 1 && pl.i[0] == 0 && pl.j[0] == 1);
    sy[2] = NAN;
    CHECK_EQ_INT(gk_cells_bin(&c, 2, h, 3, s, 0.1, &e), GK_ERR_NAN);
    CHECK(strstr(e.msg, "particle 2") != NULL);
    sy[2] = INFINITY;
    CHECK_EQ_INT(gk_cells_bin(&c, 2, h, 3, s, 0.1, &e), GK_ERR_NAN);
    gk_pairlist_free(&pl);
    gk_cells_free(&c);
}

/* '# cell inf ...' (or nan) used to become the cell matrix */
TEST(packing_cell_line_must_be_finite) {
    const char *bad[2] = {"2 1 10 10\n# cell inf 0 0 10\n5 5 1\n", "2 1 10 10\n# cell 10 nan 0 10\n5 5 1\n"};
    int k;
    for (k = 0; k < 2; ++k) {
        gk_packing pk;
        gk_err e;
        pk.n = -7;
        CHECK_EQ_INT(gk_packing_parse(bad[k], strlen(bad[k]), &pk, NULL, &e), GK_ERR_CELL);
        CHECK(pk.n == -7 && strstr(e.msg, "line 2") != NULL);
    }
}

/* A particle line of 1100 characters was cut at 1023 without a word: here
 * the cut drops its fourth number (a wrong count read as right). Now any
 * data line that does not fit is refused by number; a long comment is
 * still only a comment. A NUL byte is refused too (it hid the rest of the
 * line from the number parser). */
TEST(packing_long_lines_and_nul_bytes_are_refused) {
    char txt[2048];
    gk_packing pk;
    gk_err e;
    snprintf(txt, sizeof txt, "2 1 1 1\n0.5 0.5 0.01%*s 7\n", 1100, "");
    CHECK_EQ_INT(gk_packing_parse(txt, strlen(txt), &pk, NULL, &e), GK_ERR_FORMAT);
    CHECK(strstr(e.msg, "line 2 is longer") != NULL);
    snprintf(txt, sizeof txt, "2 1 1 1\n#%*s\n0.5 0.5 0.01\n", 1500, "x");
    CHECK(gk_packing_parse(txt, strlen(txt), &pk, NULL, &e) == GK_OK);
    if (pk.n == 1) gk_packing_free(&pk);
    memcpy(txt, "2 1 1 1\n0.5 0.5\0 0.01 9\n", 24);
    CHECK_EQ_INT(gk_packing_parse(txt, 24, &pk, NULL, &e), GK_ERR_FORMAT);
    CHECK(strstr(e.msg, "NUL") != NULL);
}

/* a directory given as the packing: 'out of memory' (ftell of a directory)
 * before; now the reader says what happened */
TEST(packing_directory_is_an_io_error) {
    gk_packing pk;
    gk_err e;
    CHECK_EQ_INT(gk_packing_read("tests", &pk, NULL, &e), GK_ERR_IO);
    CHECK(strstr(e.msg, "tests") != NULL && strstr(e.msg, "irectory") != NULL);
    printf("    %s\n", e.msg);
}

/* Radii far out of range give a mass or inertia of 0 or inf (1e-200 m:
 * m = 0, dt_crit = 0, and the first step diverged); gk_rve_create refuses
 * them with GK_ERR_MASS naming the particle, the caller's struct untouched. */
TEST(rve_create_refuses_radii_out_of_range) {
    const char *txt[2] = {"2 2 10 10\n5 5 1e-200\n2 2 1\n", "3 1 1e90 1e90 1e90\n0 0 0 1e80\n"};
    int k;
    for (k = 0; k < 2; ++k) {
        gk_packing pk;
        gk_err e;
        gk_rve rve, before;
        gk_rve_def def = gk_rve_def_default();
        CHECK(gk_packing_parse(txt[k], strlen(txt[k]), &pk, NULL, &e) == GK_OK);
        memset(&rve, 0x5a, sizeof rve);
        memcpy(&before, &rve, sizeof rve);
        CHECK_EQ_INT(gk_rve_create(&rve, &def, &pk), GK_ERR_MASS);
        CHECK(strstr(gk_rve_error(&rve), "particle") != NULL);
        CHECK(memcmp(&rve, &before, offsetof(gk_rve, err)) == 0);
        printf("    %s\n", gk_rve_error(&rve));
        gk_packing_free(&pk);
    }
}

/* ============================================================== Gmsh */
static const char *GMSH_HEAD = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";

/* Node counts that wrap (size_t) n x 24 to 8 bytes, v2.2 and v4.1: the old
 * reader allocated from the announced count (and wrote past a wrapped
 * buffer); now the count must fit the text. A node tag of 99999999 made a
 * 400 MB tag map; tags are now looked up sorted, in memory of the node
 * count. Checked with an allocator that records the largest request. */
TEST(gmsh_counts_and_tags_allocate_from_the_text) {
    const char *v41 =
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 768614336404564651 1 1\n0 1 0 1\n1\n0 0 "
        "0\n$EndNodes\n";
    char v22[256], tag[512];
    const char *in[3];
    gk_result want[3] = {GK_ERR_FORMAT, GK_ERR_FORMAT, GK_ERR_MESH};
    int k;
    snprintf(v22, sizeof v22, "%s$Nodes\n768614336404564651\n1 0 0 0\n$EndNodes\n", GMSH_HEAD);
    snprintf(tag, sizeof tag,
             "%s$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 1 1 0\n99999999 0 1 0\n$EndNodes\n$Elements\n1\n1 15 2 0 1 1\n"
             "$EndElements\n",
             GMSH_HEAD);
    in[0] = v22, in[1] = v41, in[2] = tag;
    for (k = 0; k < 3; ++k) {
        counting c;
        gk_allocator a = counting_allocator(&c, (size_t)1 << 20);
        gk_mesh m;
        gk_err e;
        CHECK_EQ_INT(gk_mesh_parse_gmsh(in[k], strlen(in[k]), &m, &a, &e), want[k]);
        CHECK(c.largest <= 64 * strlen(in[k]));
        printf("    %s (largest allocation %lu bytes)\n", e.msg, (unsigned long)c.largest);
    }
}

/* A v2.2 element line 'id type ntags tags... nodes...' with ntags = -9
 * indexed the stack array of its numbers at -6; 100000 read past it. */
TEST(gmsh_v22_tag_count_is_checked_before_it_indexes) {
    const char *ntags[2] = {"-9", "100000"};
    int k;
    for (k = 0; k < 2; ++k) {
        char txt[512];
        gk_mesh m;
        gk_err e;
        snprintf(txt, sizeof txt,
                 "%s$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n$EndNodes\n$Elements\n1\n1 3 %s 1 2 3 "
                 "4\n$EndElements\n",
                 GMSH_HEAD, ntags[k]);
        CHECK_EQ_INT(gk_mesh_parse_gmsh(txt, strlen(txt), &m, NULL, &e), GK_ERR_FORMAT);
        CHECK(strstr(e.msg, "tag count") != NULL);
    }
}

/* A tag listed twice (the old map kept the last) and a NaN coordinate (read
 * by sscanf, then checked only by gk_mesh_check if the caller ran it) */
TEST(gmsh_duplicate_tags_and_nan_coordinates_are_refused) {
    char dup[512], nan_[512];
    gk_mesh m;
    gk_err e;
    snprintf(dup, sizeof dup,
             "%s$Nodes\n4\n1 0 0 0\n2 1 0 0\n2 1 1 0\n4 0 1 0\n$EndNodes\n$Elements\n1\n1 3 2 0 1 1 2 3 "
             "4\n$EndElements\n",
             GMSH_HEAD);
    snprintf(nan_, sizeof nan_,
             "%s$Nodes\n4\n1 0 0 0\n2 nan 0 0\n3 1 1 0\n4 0 1 0\n$EndNodes\n$Elements\n1\n1 3 2 0 1 1 2 3 "
             "4\n$EndElements\n",
             GMSH_HEAD);
    CHECK_EQ_INT(gk_mesh_parse_gmsh(dup, strlen(dup), &m, NULL, &e), GK_ERR_FORMAT);
    CHECK(strstr(e.msg, "twice") != NULL);
    CHECK_EQ_INT(gk_mesh_parse_gmsh(nan_, strlen(nan_), &m, NULL, &e), GK_ERR_NAN);
    CHECK(strstr(e.msg, "node 2") != NULL);
}

/* ======================================================= RVE states */
/* offset of the first particle velocity and of the first pair in a state */
static size_t off_v(const gk_rve *r) {
    return sizeof(gk__state_hdr) + (size_t)r->n * 2 * r->dim * sizeof(double);
}
static size_t off_pairs(const gk_rve *r) {
    int nr = r->w[2] ? (r->dim == 2 ? 1 : 3) : 0;
    return off_v(r) + (size_t)r->n * sizeof(gk_real) * (2 * r->dim + 2 * nr) +
           (r->dim == 2 ? (size_t)r->n * sizeof(double) : 0);
}

/* Each buffer below is a valid saved state with one field made physically
 * or structurally impossible. The old gk_rve_restore checked the header's
 * identity and the pair indices only, so a state with dt 10 x the critical
 * step restored, and the next deform returned GK_OK with a stress 50 x off.
 * Now every field is checked first; each is refused with a message and the
 * RVE is byte for byte as before; the valid buffer still restores. */
TEST(rve_restore_refuses_invalid_states_and_changes_nothing) {
    gk_rve rve;
    gk_rve_state st;
    unsigned char *good, *bad, *snap;
    size_t n, ns;
    int c, ncase = 19;
    if (seed_rve(&rve)) {
        CHECK(0);
        return;
    }
    CHECK(gk_rve_refresh(&rve) == GK_OK);
    gk_rve_state_init(&st, NULL);
    CHECK(gk_rve_state_save(&st, &rve) == GK_OK);
    n = st.size;
    good = st.buf;
    bad = (unsigned char *)malloc(n);
    { /* a state where the RVE has moved on, so that 'unchanged' means something */
        double dH[9] = {0, 1e-4, 0, 0, 0, 0, 0, 0, 0};
        CHECK(gk_rve_deform(&rve, dH, 20) == GK_OK);
    }
    snap = snapshot(&rve, &ns);
    for (c = 0; c < ncase; ++c) {
        gk__state_hdr hd;
        gk_result r;
        gk_real xr = (gk_real)NAN;
        int32_t i32;
        const char *what = "";
        memcpy(bad, good, n);
        memcpy(&hd, good, sizeof hd);
        switch (c) {
        case 0: hd.dt *= 10.0, what = "dt 10 x critical"; break;
        case 1: hd.dt = -hd.dt, what = "dt < 0"; break;
        case 2: hd.dt = NAN, what = "dt NaN"; break;
        case 3: hd.mu = -0.5, what = "friction < 0"; break;
        case 4: hd.h[1] = NAN, what = "NaN cell"; break;
        case 5: hd.h[0] = -hd.h[0], what = "inverted cell"; break;
        case 6: hd.h[0] *= 0.05, hd.h[3] *= 0.05, what = "cell thinner than the interaction range"; break;
        case 7: hd.ncontacts = hd.npairs + 1, what = "more contacts than pairs"; break;
        case 8: hd.need_rebuild = 7, what = "flag 7"; break;
        case 9: hd.skin = 0.0, what = "skin 0"; break;
        case 10: hd.servo_on = 1, hd.servo.max_rate = 0.0, what = "servo without max_rate"; break;
        case 11: hd.step = -1, what = "step -1"; break;
        case 12: memcpy(bad + off_v(&rve) + 5 * sizeof xr, &xr, sizeof xr), what = "NaN velocity"; break;
        case 13: /* the first two pairs swapped: the list must stay sorted */
            memcpy(bad + off_pairs(&rve), good + off_pairs(&rve) + 4, 4);
            memcpy(bad + off_pairs(&rve) + 4, good + off_pairs(&rve), 4);
            memcpy(bad + off_pairs(&rve) + 4 * (size_t)hd.npairs,
                   good + off_pairs(&rve) + 4 * (size_t)hd.npairs + 4, 4);
            memcpy(bad + off_pairs(&rve) + 4 * (size_t)hd.npairs + 4,
                   good + off_pairs(&rve) + 4 * (size_t)hd.npairs, 4);
            what = "unsorted pairs";
            break;
        case 14:
            i32 = rve.n, memcpy(bad + off_pairs(&rve) + 4 * (size_t)hd.npairs, &i32, 4), what = "j = n";
            break;
        case 15: bad[off_pairs(&rve) + 8 * (size_t)hd.npairs] = 0x80, what = "unknown contact bits"; break;
        /* finite but impossible (found by fuzz_mpmdem_ckpt: a saved stress of 1e248 Pa gave an infinite q) */
        case 16: hd.stress[0] = 1.15e248, what = "stress 1e248 Pa"; break;
        case 17: hd.F[1] = 5.76e259, what = "deformation gradient entry 1e259"; break;
        case 18:
            xr = (gk_real)1e30, xr = xr * xr * xr * xr; /* 1e120, or Inf in float */
            memcpy(bad + off_v(&rve) + 5 * sizeof xr, &xr, sizeof xr), what = "velocity 1e120";
            break;
        }
        if (c < 12 || c == 16 || c == 17) memcpy(bad, &hd, sizeof hd);
        rve.err.msg[0] = '\0';
        r = gk_rve_restore(&rve, bad, n);
        CHECK(r != GK_OK);
        CHECK(strlen(gk_rve_error(&rve)) > 10);
        CHECK(unchanged(&rve, snap, ns));
        printf("    %-40s %s: %s\n", what, gk_result_string(r), gk_rve_error(&rve));
    }
    CHECK(gk_rve_restore(&rve, good, n) == GK_OK);
    free(snap);
    free(bad);
    gk_rve_state_free(&st);
    gk_rve_destroy(&rve);
}

/* =================================================== deform and step */
/* 50 % shear in one DEM step moved touching disks by 2.3 r_min and
 * returned GK_OK (overlaps 0.7 r). The admissible increment per step
 * (gk_dem.h: no overlap may change by more than 0.1 of the smaller radius)
 * refuses it, naming the step count that would do, and that count works.
 * On the constant-L path det(I + dH) = 0 (dH_xx = -1) was accepted because
 * exp(dH) is invertible; it is an inverting increment on both paths. */
TEST(rve_deform_refuses_inadmissible_increments) {
    gk_rve rve;
    unsigned char *snap;
    size_t ns;
    double shear[9] = {0, 0.5, 0, 0, 0, 0, 0, 0, 0}, flat[9] = {-1, 0, 0, 0, 0, 0, 0, 0, 0};
    const char *p;
    long need;
    if (seed_rve(&rve)) {
        CHECK(0);
        return;
    }
    snap = snapshot(&rve, &ns);
    CHECK_EQ_INT(gk_rve_deform(&rve, shear, 1), GK_ERR_ARG);
    printf("    %s\n", gk_rve_error(&rve));
    CHECK(unchanged(&rve, snap, ns));
    p = strstr(gk_rve_error(&rve), "at least ");
    need = p ? atol(p + 9) : 0;
    CHECK(need > 1 && need < 100);
    CHECK_EQ_INT(gk_rve_deform(&rve, flat, 200), GK_ERR_SINGULAR);
    CHECK(unchanged(&rve, snap, ns));
    if (need > 1) {
        CHECK(gk_rve_deform(&rve, shear, (int)need - 1) == GK_ERR_ARG);
        CHECK(gk_rve_deform(&rve, shear, (int)need) == GK_OK);
    }
    free(snap);
    gk_rve_destroy(&rve);
}

/* gk_rve_step with a velocity gradient that moves contacts by more than the
 * admissible increment per step (L dt = 0.1): refused before a step */
TEST(rve_step_refuses_a_velocity_gradient_too_large_for_one_step) {
    gk_rve rve;
    double L[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    unsigned char *snap;
    size_t ns;
    if (seed_rve(&rve)) {
        CHECK(0);
        return;
    }
    L[1] = 0.1 / rve.dt;
    CHECK(gk_rve_set_velocity_gradient(&rve, L) == GK_OK);
    snap = snapshot(&rve, &ns);
    CHECK_EQ_INT(gk_rve_step(&rve, 10), GK_ERR_ARG);
    CHECK(unchanged(&rve, snap, ns));
    L[1] = 1e-4 / rve.dt;
    CHECK(gk_rve_set_velocity_gradient(&rve, L) == GK_OK);
    CHECK(gk_rve_step(&rve, 10) == GK_OK);
    free(snap);
    gk_rve_destroy(&rve);
}

/* The stress after gk_rve_deform is documented (gk_dem.h, THE RVE CONTRACT)
 * as the Love stress of the forces of the last step, computed before that
 * step moved the particles: it lags the end state by about one step's
 * increment. With one step (a shear of 1e-5 on the seed packing) most of
 * sigma_xy's change is missing until gk_rve_refresh; with ten steps the lag
 * is about a tenth of it (checked below 0.3). */
static double stress_lag(gk_rve *rve, const gk_rve_state *st, int n, double *total) {
    double dH[9] = {0, 1e-5, 0, 0, 0, 0, 0, 0, 0}, s0[9], s1[9], s2[9];
    CHECK(gk_rve_state_restore(st, rve) == GK_OK);
    gk_rve_stress(rve, s0);
    CHECK(gk_rve_deform(rve, dH, n) == GK_OK);
    gk_rve_stress(rve, s1);
    CHECK(gk_rve_refresh(rve) == GK_OK);
    gk_rve_stress(rve, s2);
    *total = fabs(s2[1] - s0[1]);
    printf("    %2d steps: sigma_xy %.2f before, %.2f after deform, %.2f after refresh\n", n, s0[1], s1[1],
           s2[1]);
    return fabs(s2[1] - s1[1]);
}

TEST(rve_stress_after_deform_lags_one_step) {
    gk_rve rve;
    gk_rve_state st;
    double lag1, lag10, tot1, tot10;
    if (seed_rve(&rve)) {
        CHECK(0);
        return;
    }
    CHECK(gk_rve_refresh(&rve) == GK_OK);
    gk_rve_state_init(&st, NULL);
    CHECK(gk_rve_state_save(&st, &rve) == GK_OK);
    lag1 = stress_lag(&rve, &st, 1, &tot1);
    lag10 = stress_lag(&rve, &st, 10, &tot10);
    CHECK(lag1 > 0.25 * tot1);
    CHECK(lag10 < 0.3 * lag1);
    gk_rve_state_free(&st);
    gk_rve_destroy(&rve);
}

/* ================================================================ FEM */
static gk_result unit_mesh(gk_mesh *m, int nx, int ny) {
    int n[3] = {nx, ny, 1};
    double o[3] = {0, 0, 0}, len[3] = {1, 1, 1};
    gk_err e;
    return gk_mesh_structured(m, GK_Q4, n, o, len, NULL, &e);
}

/* a NaN tangent gave a NaN element matrix and GK_OK; an element index past
 * the mesh read past its connectivity */
TEST(fem_element_stiffness_checks_tangent_and_index) {
    gk_mesh m;
    gk_quad q;
    gk_err e;
    double D[4 * 16], Ke[64];
    int g;
    CHECK(unit_mesh(&m, 2, 2) == GK_OK);
    CHECK(gk_quad_rule(&q, GK_Q4, 2, &e) == GK_OK);
    for (g = 0; g < 4; ++g) gk_fem_elastic_tangent(2, 1e7, 0.3, D + 16 * g);
    CHECK(gk_fem_elem_stiffness(&m, 0, &q, D, Ke, &e) == GK_OK);
    D[16 * 2 + 5] = NAN;
    CHECK_EQ_INT(gk_fem_elem_stiffness(&m, 0, &q, D, Ke, &e), GK_ERR_NAN);
    CHECK(strstr(e.msg, "Gauss point 2") != NULL);
    D[16 * 2 + 5] = 1.0;
    CHECK_EQ_INT(gk_fem_elem_stiffness(&m, m.nelem, &q, D, Ke, &e), GK_ERR_ARG);
    CHECK_EQ_INT(gk_fem_elem_stiffness(&m, -1, &q, D, Ke, &e), GK_ERR_ARG);
    gk_mesh_free(&m);
}

/* gk_fem_assemble zeroed K and fint, then stopped at the first inverted
 * element with both half assembled: now it checks every element first */
TEST(fem_assemble_with_an_inverted_element_changes_nothing) {
    gk_mesh m;
    gk_quad q;
    gk_err e;
    gk_csr K;
    double *D, *sig, fint[2 * 16];
    int k, t;
    CHECK(unit_mesh(&m, 3, 3) == GK_OK);
    CHECK(gk_quad_rule(&q, GK_Q4, 2, &e) == GK_OK);
    CHECK(gk_csr_from_mesh(&K, &m, NULL, &e) == GK_OK);
    D = (double *)malloc((size_t)m.nelem * q.n * 16 * sizeof(double));
    sig = (double *)calloc((size_t)m.nelem * q.n * 9, sizeof(double));
    for (k = 0; k < m.nelem * q.n; ++k) gk_fem_elastic_tangent(2, 1e7, 0.3, D + 16 * k);
    t = m.conn[4 * 5 + 1], m.conn[4 * 5 + 1] = m.conn[4 * 5 + 3],
    m.conn[4 * 5 + 3] = t; /* element 5 inverted */
    for (k = 0; k < K.nnz; ++k) K.val[k] = 42.0;
    for (k = 0; k < 2 * m.nnode; ++k) fint[k] = 42.0;
    CHECK_EQ_INT(gk_fem_assemble(&m, &q, D, sig, &K, fint, &e), GK_ERR_MESH);
    CHECK(strstr(e.msg, "element 5") != NULL);
    for (k = 0; k < K.nnz; ++k) CHECK(K.val[k] == 42.0);
    for (k = 0; k < 2 * m.nnode; ++k) CHECK(fint[k] == 42.0);
    free(D);
    free(sig);
    gk_csr_free(&K);
    gk_mesh_free(&m);
}

/* 1e5 x 1e5 quads: node and element counts overflowed int ('-1 elements') */
TEST(fem_structured_mesh_refuses_int_overflow) {
    gk_mesh m;
    gk_err e;
    int n[3] = {100000, 100000, 1};
    double o[3] = {0, 0, 0}, len[3] = {1, 1, 1};
    CHECK_EQ_INT(gk_mesh_structured(&m, GK_Q4, n, o, len, NULL, &e), GK_ERR_ARG);
    CHECK(strstr(e.msg, "10000000000 elements") != NULL);
    printf("    %s\n", e.msg);
}

/* the 2 x 2 elastic mesh clamped at y = 0: a nonsingular system */
static void clamped_system(gk_mesh *m, gk_csr *K) {
    gk_quad q;
    gk_err e;
    double D[4 * 4 * 16], rhs[18], zero[6] = {0, 0, 0, 0, 0, 0};
    int fix[6], k, nf;
    CHECK(unit_mesh(m, 2, 2) == GK_OK);
    CHECK(gk_quad_rule(&q, GK_Q4, 2, &e) == GK_OK);
    CHECK(gk_csr_from_mesh(K, m, NULL, &e) == GK_OK);
    for (k = 0; k < 16; ++k) gk_fem_elastic_tangent(2, 1e7, 0.3, D + 16 * k);
    CHECK(gk_fem_assemble(m, &q, D, NULL, K, NULL, &e) == GK_OK);
    nf = gk_mesh_nodes_on_plane(m, 1, 0.0, 1e-9, fix);
    for (k = 0; k < nf; ++k) fix[nf + k] = 2 * fix[k] + 1, fix[k] = 2 * fix[k];
    memset(rhs, 0, sizeof rhs);
    CHECK(nf == 3 && gk_fem_dirichlet(K, rhs, 2 * nf, fix, zero, &e) == GK_OK);
}

/* gk_solver_solve had no error channel: a NaN right-hand side gave a NaN x
 * and GK_OK. gk_solver_factor freed whatever the struct held, so an
 * uninitialised solver crashed it; now gk_solver_init is required (a
 * cookie), and a failed factorisation keeps the old one. */
TEST(fem_solver_init_nan_rhs_and_failed_factor) {
    gk_mesh m;
    gk_csr K, Z;
    gk_solver s;
    gk_err e;
    double b[18], x[18], x2[18];
    int k;
    clamped_system(&m, &K);
    memset(&s, 0x5a, sizeof s); /* as an uninitialised automatic variable */
    CHECK_EQ_INT(gk_solver_factor(&s, &K, NULL, &e), GK_ERR_ARG);
    CHECK(strstr(e.msg, "gk_solver_init") != NULL);
    gk_solver_init(&s);
    CHECK(gk_solver_factor(&s, &K, NULL, &e) == GK_OK);
    for (k = 0; k < 18; ++k) b[k] = k % 2 ? 1.0 : 0.0, x[k] = -7.0;
    CHECK(gk_solver_solve(&s, b, x2) == GK_OK);
    b[9] = NAN;
    CHECK_EQ_INT(gk_solver_solve(&s, b, x), GK_ERR_NAN);
    CHECK(strstr(s.err.msg, "right-hand side 9") != NULL);
    for (k = 0; k < 18; ++k) CHECK(x[k] == -7.0);
    b[9] = 1.0;
    /* a zero matrix cannot be factored: the old factorisation stays */
    Z = K;
    Z.val = (double *)calloc((size_t)K.nnz, sizeof(double));
    CHECK_EQ_INT(gk_solver_factor(&s, &Z, NULL, &e), GK_ERR_SINGULAR);
    CHECK(gk_solver_solve(&s, b, x) == GK_OK);
    for (k = 0; k < 18; ++k) CHECK(x[k] == x2[k]);
    free(Z.val);
    gk_solver_free(&s);
    CHECK_EQ_INT(gk_solver_solve(&s, b, x), GK_ERR_STATE);
    gk_csr_free(&K);
    gk_mesh_free(&m);
}

/* gk_pcg(rtol = Inf) returned GK_OK at once with x = the start value */
TEST(fem_pcg_refuses_infinite_tolerance_and_nan) {
    gk_mesh m;
    gk_csr K;
    gk_err e;
    double b[18], x[18];
    int k, it = -1;
    clamped_system(&m, &K);
    for (k = 0; k < 18; ++k) b[k] = 1.0, x[k] = 0.0;
    CHECK_EQ_INT(gk_pcg(&K, b, x, INFINITY, 100, &it, NULL, &e), GK_ERR_ARG);
    CHECK_EQ_INT(gk_pcg(&K, b, x, NAN, 100, &it, NULL, &e), GK_ERR_ARG);
    CHECK_EQ_INT(gk_pcg(&K, b, x, 1.0, 100, &it, NULL, &e), GK_ERR_ARG);
    b[3] = NAN;
    CHECK_EQ_INT(gk_pcg(&K, b, x, 1e-10, 100, &it, NULL, &e), GK_ERR_NAN);
    for (k = 0; k < 18; ++k) CHECK(x[k] == 0.0);
    b[3] = 1.0;
    CHECK(gk_pcg(&K, b, x, 1e-10, 100, &it, NULL, &e) == GK_OK);
    CHECK(it > 0);
    gk_csr_free(&K);
    gk_mesh_free(&m);
}

/* ================================================================ MPM */
/* Points compressed along x at a rate a with dt a = 1.5: I + dt L has
 * det < 0. gk_mpm_step used to fail after it had moved the points (MUSL) or
 * written F, L and the volumes (USF); now the points are as before. */
static void mpm_copy(const gk_mpm_points *P, double *buf) {
    size_t n = (size_t)P->n, o = 0;
    int k;
    for (k = 0; k < 2; ++k) {
        memcpy(buf + o, P->x[k], n * sizeof(double)), o += n;
        memcpy(buf + o, P->v[k], n * sizeof(double)), o += n;
    }
    memcpy(buf + o, P->F, 9 * n * sizeof(double)), o += 9 * n;
    memcpy(buf + o, P->L, 9 * n * sizeof(double)), o += 9 * n;
    memcpy(buf + o, P->vol, n * sizeof(double));
}

TEST(mpm_step_refusing_det_F_leaves_the_points) {
    int sc;
    for (sc = 0; sc < 3; ++sc) { /* USF, USL, MUSL */
        gk_mpm_grid g;
        gk_mpm_points P;
        gk_mpm_def d = gk_mpm_def_default();
        gk_err e;
        /* USF, USL: L = -a from the start velocities, dt a = 1.5; MUSL: the points move
         * first (by 1 - dt a), then L from the remapped velocities, dt a = 0.8; grid h/4
         * so that the linear basis resolves the compressed field */
        double o[3] = {0, 0, 0}, lo[3] = {2, 2, 0}, hi[3] = {6, 6, 0}, a = 1.0, dt = sc == 2 ? 0.8 : 1.5;
        double *before, *after;
        int n[3] = {33, 33, 1}, p;
        size_t len;
        CHECK(gk_mpm_grid_create(&g, 2, o, 0.25, n, NULL, &e) == GK_OK);
        CHECK(gk_mpm_points_create_box(&P, 2, lo, hi, 0.25, 2, 1000.0, NULL, &e) == GK_OK);
        for (p = 0; p < P.n; ++p) P.v[0][p] = -a * (P.x[0][p] - 4.0);
        d.scheme = (gk_mpm_scheme)sc;
        d.alpha = 1.0;
        len = (size_t)P.n * 23;
        before = (double *)malloc(len * sizeof(double));
        after = (double *)malloc(len * sizeof(double));
        mpm_copy(&P, before);
        CHECK_EQ_INT(gk_mpm_step(&g, &P, &d, dt, NULL, NULL, &e), GK_ERR_DIVERGED);
        CHECK(strstr(e.msg, "det F") != NULL);
        mpm_copy(&P, after);
        CHECK(memcmp(before, after, len * sizeof(double)) == 0);
        printf("    %s: %s\n", sc == 0 ? "USF" : sc == 1 ? "USL" : "MUSL", e.msg);
        free(before);
        free(after);
        gk_mpm_points_destroy(&P);
        gk_mpm_grid_destroy(&g);
    }
}

/* ================================================================= I/O */
/* /dev/full accepts the open and loses every byte: each writer must say so */
TEST(writers_report_a_full_disk) {
    gk_err e;
    gk_plot pl;
    double xs[3] = {0, 1, 2}, ys[3] = {1, 2, 1}, xyz[3 * 2000], val[2000];
    gk_vtk v;
    gk_packing pk;
    FILE *fp;
    int k;
    if (!exists("/dev/full")) {
        printf("    no /dev/full on this system\n");
        CHECK(0);
        return;
    }
    gk_plot_init(&pl, "t", "x", "y");
    gk_plot_add(&pl, xs, ys, 3, "a");
    CHECK_EQ_INT(gk_plot_svg(&pl, "/dev/full", &e), GK_ERR_IO);
    CHECK(strstr(e.msg, "/dev/full") != NULL);
    for (k = 0; k < 3 * 2000; ++k) xyz[k] = 1e-3 * k;
    for (k = 0; k < 2000; ++k) val[k] = k;
    CHECK_EQ_INT(gk_svg_field("/dev/full", "t", "l", 3, 1, xyz, val, 0.1, &e), GK_ERR_IO);
    CHECK(gk_vtk_open(&v, "/dev/full", "t") == GK_OK);
    CHECK_EQ_INT(gk_vtk_points(&v, 2000, xyz), GK_ERR_IO); /* 60 kB: the stream has failed by now */
    CHECK_EQ_INT(gk_vtk_close(&v), GK_ERR_IO);
    CHECK(gk_packing_parse("2 1 1 1\n0.5 0.5 0.1\n", 20, &pk, NULL, &e) == GK_OK);
    CHECK_EQ_INT(gk_packing_write("/dev/full", &pk, "c", &e), GK_ERR_IO);
    gk_packing_free(&pk);
    fp = fopen("/dev/full", "w");
    CHECK(fp != NULL);
    if (fp) {
        fprintf(fp, "a,b\n1,2\n");
        CHECK_EQ_INT(gk_file_close(fp, "/dev/full", &e), GK_ERR_IO);
        CHECK(strstr(e.msg, "No space") != NULL);
    }
}

/* ========================================================= checkpoints */
/* bytes of a file (malloc'd), or NULL */
static unsigned char *file_image(const char *path, size_t *n) {
    FILE *fp = fopen(path, "rb");
    unsigned char *b = NULL;
    long end;
    *n = 0;
    if (!fp) return NULL;
    if (fseek(fp, 0, SEEK_END) == 0 && (end = ftell(fp)) > 0 && fseek(fp, 0, SEEK_SET) == 0 &&
        (b = (unsigned char *)malloc((size_t)end)) != NULL && fread(b, 1, (size_t)end, fp) == (size_t)end)
        *n = (size_t)end;
    fclose(fp);
    return b;
}

/* the file's last 8 bytes: the FNV-1a hash of the rest (the checkpoint's checksum, made right) */
static void spill_resealed(const char *path, unsigned char *b, size_t n) {
    uint64_t h = UINT64_C(0xcbf29ce484222325);
    size_t k;
    FILE *fp;
    for (k = 0; k + 8 < n; ++k) h = (h ^ b[k]) * UINT64_C(0x100000001b3);
    memcpy(b + n - 8, &h, 8);
    fp = fopen(path, "wb");
    if (fp) fwrite(b, 1, n, fp), fclose(fp);
}

/* a two-scale checkpoint with a valid checksum but a NaN reference tangent
 * (the tangent-reuse reference of a point) was accepted, and the next run
 * returned GK_OK with that NaN as the point's tangent; an accumulated dH of
 * 1e300 was accepted and gave an infinite eps_q field; contact keys out of
 * order (the reference network) were accepted and gave a wrong reuse
 * decision. Both refused by name now, the set unchanged. A point without
 * contacts (a loose packing) with reuse on passed NULL to qsort (UBSan). */
TEST(twoscale_checkpoint_reference_is_checked) {
    gk_gen_def g;
    gk_packing pk;
    gk_err e;
    gk_twoscale ts;
    gk_twoscale_def def;
    gk_twoscale_proto proto;
    double dH[18] = {0, 1e-5, 0, 0, 0, 0, 0, 0, 0, 0, 1e-5, 0, 0, 0, 0, 0, 0, 0}, S[18], D[32];
    const char *ck = OUT("ck.bin"), *bad = OUT("ck_bad.bin"), *again = OUT("ck_again.bin");
    unsigned char *img, *x, *y;
    size_t n, nx, ny, rec, ref;
    void *blk = NULL;
    size_t nb = 0;
    uint64_t key;
    int32_t nkey;
    memset(&g, 0, sizeof g);
    g.dim = 2, g.n = 12, g.r_min = 0.4e-3, g.r_max = 0.6e-3, g.seed = 11;
    CHECK(gk_packing_generate(&pk, &g, NULL, &e) == GK_OK);
    memset(&def, 0, sizeof def);
    proto.packing = &pk, proto.state = NULL;
    def.npoints = 2, def.protos = &proto, def.nprotos = 1, def.reuse = 0.3;
    def.rule.kind = GK_TWOSCALE_STRAIN, def.rule.n_min = 2, def.rule.n_max = 4;
    CHECK(gk_twoscale_create(&ts, &def) == GK_OK);
    /* the loose cloud: no contacts, reuse on (the NULL qsort) */
    CHECK(gk_twoscale_run(&ts, dH, NULL, S, D) == GK_OK && gk_twoscale_accept(&ts) == GK_OK);
    CHECK(gk_twoscale_save(&ts, ck, NULL, 0) == GK_OK);
    img = file_image(ck, &n);
    x = (unsigned char *)malloc(n);
    CHECK(img != NULL && x != NULL && n > 200);
    if (!img || !x || n <= 200) return;
    rec = 8 + 32 + 4 + 2 * 4 + 8; /* magic, header, 1 prototype, 2 picks, record size: point 0's record */
    ref = rec + 16 + 2 * 9 * 8;   /* its reference tangent */
    memcpy(&nkey, img + rec + 12, 4);
    CHECK_EQ_INT(nkey, 0); /* a reference with no contacts */
    memcpy(x, img, n);     /* a NaN in the reference tangent */
    memset(x + ref + 8 * 5, 0xff, 8);
    spill_resealed(bad, x, n);
    CHECK_EQ_INT(gk_twoscale_load(&ts, bad, &blk, &nb), GK_ERR_FORMAT);
    CHECK(strstr(gk_twoscale_error(&ts), bad) && strstr(gk_twoscale_error(&ts), "NaN reference tangent"));
    CHECK(gk_twoscale_save(&ts, again, NULL, 0) == GK_OK);
    y = file_image(again, &ny);
    CHECK(y && ny == n && memcmp(y, img, n) == 0); /* unchanged */
    free(y);
    memcpy(x, img, n); /* a finite but impossible accumulated dH: its field eps_q was Inf */
    {
        double huge = 1e300;
        memcpy(x + rec + 16 + 8, &huge, 8);
        spill_resealed(bad, x, n);
        CHECK_EQ_INT(gk_twoscale_load(&ts, bad, &blk, &nb), GK_ERR_FORMAT);
        CHECK(strstr(gk_twoscale_error(&ts), "impossible accumulated dH"));
    }
    /* contact keys: one record with two keys out of order (the record grown by 16 bytes) */
    nx = n + 16;
    free(x);
    x = (unsigned char *)malloc(nx);
    CHECK(x != NULL);
    if (!x) return;
    {
        size_t keys = ref + 16 * 8; /* after the 2D tangent's 16 entries */
        uint64_t sz;
        memcpy(x, img, keys);
        memcpy(x + keys + 16, img + keys, n - keys);
        memcpy(&sz, x + rec - 8, 8), sz += 16, memcpy(x + rec - 8, &sz, 8);
        nkey = 2, memcpy(x + rec + 12, &nkey, 4);
        key = ((uint64_t)3 << 32 | 7) << 1, memcpy(x + keys, &key, 8);
        key = ((uint64_t)1 << 32 | 2) << 1, memcpy(x + keys + 8, &key, 8);
        spill_resealed(bad, x, nx);
        CHECK_EQ_INT(gk_twoscale_load(&ts, bad, &blk, &nb), GK_ERR_FORMAT);
        CHECK(strstr(gk_twoscale_error(&ts), "contact key 1 is out of order"));
        key = ((uint64_t)5 << 32 | 7) << 1, memcpy(x + keys + 8, &key, 8); /* in order: accepted */
        spill_resealed(bad, x, nx);
        CHECK_EQ_INT(gk_twoscale_load(&ts, bad, &blk, &nb), GK_OK);
        gk_twoscale_free_block(&ts, blk);
    }
    free(x), free(img);
    gk_twoscale_destroy(&ts);
    gk_packing_free(&pk);
}

/* offset of the first occurrence of tag in b[n], or n */
static size_t find_tag(const unsigned char *b, size_t n, const char *tag) {
    size_t k, len = strlen(tag);
    for (k = 0; k + len <= n; ++k)
        if (!memcmp(b + k, tag, len)) return k;
    return n;
}

/* the drivers' blocks inside a checkpoint (after gk_twoscale_load accepted the file) were not
 * checked: the FEMxDEM biaxial driver accepted a negative step count (the step counter of its
 * rows), a mesh whose nodes no longer were the initial ones plus the displacements, and read them
 * into the model before refusing anything; the MPMxDEM biaxial driver accepted a point at a NaN
 * position and one of negative mass and ran on them. Refused now, by name, before the run starts
 * (the seeds of fuzz_femdem_ckpt and fuzz_mpmdem_ckpt found the FEMxDEM ones). */
TEST(driver_checkpoint_blocks_are_checked) {
#define FD_CK                                                                                      \
    BUILD "/femdem_biaxial --test single --steps 1 --increment 1e-4 --checkpoint 1 --vtk-every 0 " \
          "--threads 1 --packing " OUT("ck_pk.txt") " "
#define MP_CK                                                                                       \
    BUILD "/mpmdem_biaxial --nx 1 --ny 2 --width 1 --height 2 --velocity 1 --ramp 0 --every 0.008 " \
          "--threads 1 --dem-max 50 --quiet --packing " OUT("ck_pk.txt") " "
    unsigned char *b;
    size_t n, at;
    int32_t step = -5;
    double v;
    remove(OUT("fd_b/biaxial.csv")), remove(OUT("mp_b/biaxial.csv")); /* of an earlier run */
    CHECK_EQ_INT(run_status(BUILD "/gk_pack --n 60 --out " OUT("ck_pk.txt") LOG("ck_pk")), 0);
    /* FEMxDEM: the block starts with its tag, 4 ints of the mesh options, then the step */
    CHECK_EQ_INT(run_status(FD_CK "--out " OUT("fd_a") LOG("fd_a")), 0);
    b = file_image(OUT("fd_a/checkpoint.bin"), &n);
    CHECK(b != NULL && (at = find_tag(b, n, "GKFEMDEM5")) < n);
    if (!b || at == n) return;
    mkdir(OUT("fd_bad"), 0755);
    memcpy(b + at + 16 + 4 * sizeof(int), &step, 4);
    spill_resealed(OUT("fd_bad/checkpoint.bin"), b, n);
    CHECK_EQ_INT(run_status(FD_CK "--steps 2 --restart " OUT("fd_bad") " --out " OUT("fd_b") LOG("fd_b")), 1);
    CHECK(gk_test_file_has(OUT("fd_b.out"), "step -5"));
    CHECK(!exists(OUT("fd_b/biaxial.csv")));
    free(b);
    b = file_image(OUT("fd_a/checkpoint.bin"), &n);
    /* the first node's y: after the step, the axial strain, the increment scale, the row count, two
     * rows (112 bytes each) and the node's x */
    at += 16 + 4 * sizeof(int) + sizeof(int) + 2 * sizeof(double) + sizeof(int) + 2 * 112 + 8;
    CHECK(at + 8 < n);
    memcpy(&v, b + at, 8);
    CHECK(v == 0.0); /* the bottom-left node, on the fixed base */
    v = 1e-3;
    memcpy(b + at, &v, 8);
    spill_resealed(OUT("fd_bad/checkpoint.bin"), b, n);
    CHECK_EQ_INT(run_status(FD_CK "--steps 2 --restart " OUT("fd_bad") " --out " OUT("fd_b") LOG("fd_b")), 1);
    CHECK(gk_test_file_has(OUT("fd_b.out"), "does not match its displacements"));
    free(b);
    /* MPMxDEM: the block's tag (32 bytes), the point count, the state size, then x of every point, ...
     * the masses sixth */
    CHECK_EQ_INT(run_status(MP_CK "--strain 0.008 --out " OUT("mp_a") LOG("mp_a")), 0);
    b = file_image(OUT("mp_a/checkpoint.bin"), &n);
    CHECK(b != NULL && (at = find_tag(b, n, "GKMPMDEM2 biaxial")) < n);
    if (!b || at == n) return;
    mkdir(OUT("mp_bad"), 0755);
    v = NAN;
    memcpy(b + at + 44, &v, 8);
    spill_resealed(OUT("mp_bad/checkpoint.bin"), b, n);
    CHECK_EQ_INT(
        run_status(MP_CK "--strain 0.016 --restart " OUT("mp_bad") " --out " OUT("mp_b") LOG("mp_b")), 1);
    CHECK(gk_test_file_has(OUT("mp_b.out"), "point 0: a non-finite value"));
    free(b);
    b = file_image(OUT("mp_a/checkpoint.bin"), &n);
    v = -1.0;
    memcpy(b + at + 44 + 6 * 2 * 8, &v, 8);
    spill_resealed(OUT("mp_bad/checkpoint.bin"), b, n);
    CHECK_EQ_INT(
        run_status(MP_CK "--strain 0.016 --restart " OUT("mp_bad") " --out " OUT("mp_b") LOG("mp_b")), 1);
    CHECK(gk_test_file_has(OUT("mp_b.out"), "point 0: mass, volume"));
    CHECK(!exists(OUT("mp_b/biaxial.csv")));
    free(b);
#undef FD_CK
#undef MP_CK
}

/* the dynamic-relaxation and nonlocal drivers checked their checkpoint's
 * structure (tag, sizes, options, mesh) but took every real in their own
 * block on trust: a NaN written under a valid checksum was restarted from.
 * Refused now by name, with exit 1 and no new rows. */
TEST(dr_and_nonlocal_checkpoints_refuse_non_finite_values) {
#define DR_CK                                                                                               \
    BUILD "/femdem_dr --nx 1 --ny 2 --iso-steps 2 --strain 0.01 --dr-tol 1e-2 --servo-max 3 --vtk-every 0 " \
          "--steps 2 --threads 1 "
#define NL_CK                                                                                      \
    BUILD "/femdem_nonlocal --test element-shear --packing examples/data/rve160_hm.txt --steps 4 " \
          "--strain 0.0004 --lone-increments 2 --threads 1 "
    unsigned char *b;
    size_t n, at;
    double v = NAN;
    remove(OUT("dr_b/dr.csv")), remove(OUT("nl_b/element-shear.csv")); /* of an earlier run */
    /* femdem_dr: tag "FDR2", 8 ints, then h_ic, the first of its reals */
    CHECK_EQ_INT(run_status(DR_CK "--stop-after 1 --out " OUT("dr_a") LOG("dr_a")), 0);
    b = file_image(OUT("dr_a/checkpoint.bin"), &n);
    CHECK(b != NULL && (at = find_tag(b, n, "FDR2")) < n);
    if (!b || at == n) return;
    CHECK_EQ_INT(run_status(DR_CK "--restart " OUT("dr_a") " --out " OUT("dr_ok") LOG("dr_ok")), 0);
    mkdir(OUT("dr_bad"), 0755);
    memcpy(b + at + 4 + 8 * 4, &v, 8);
    spill_resealed(OUT("dr_bad/checkpoint.bin"), b, n);
    CHECK_EQ_INT(run_status(DR_CK "--restart " OUT("dr_bad") " --out " OUT("dr_b") LOG("dr_b")), 1);
    CHECK(gk_test_file_has(OUT("dr_b.out"), "non-finite or out-of-range value"));
    CHECK(!exists(OUT("dr_b/dr.csv")));
    free(b);
    /* femdem_nonlocal: tag "GKFNL02" (8 bytes), 10 ints, 3 int64, the fingerprint, then the time */
    CHECK_EQ_INT(run_status(NL_CK "--stop-after 2 --out " OUT("nl_a") LOG("nl_a")), 0);
    b = file_image(OUT("nl_a/checkpoint.bin"), &n);
    CHECK(b != NULL && (at = find_tag(b, n, "GKFNL02")) < n);
    if (!b || at == n) return;
    CHECK_EQ_INT(run_status(NL_CK "--restart " OUT("nl_a") " --out " OUT("nl_ok") LOG("nl_ok")), 0);
    mkdir(OUT("nl_bad"), 0755);
    memcpy(b + at + 8 + 10 * 4 + 4 * 8, &v, 8);
    spill_resealed(OUT("nl_bad/checkpoint.bin"), b, n);
    CHECK_EQ_INT(run_status(NL_CK "--restart " OUT("nl_bad") " --out " OUT("nl_b") LOG("nl_b")), 1);
    CHECK(gk_test_file_has(OUT("nl_b.out"), "non-finite or out-of-range value"));
    CHECK(!exists(OUT("nl_b/element-shear.csv")));
    free(b);
#undef DR_CK
#undef NL_CK
}

/* where the driver state of a checkpoint image lies (after the block's tag, point count, state size,
 * the points and the DEM-step count), or n */
static size_t state_at(const unsigned char *b, size_t n, const char *tag) {
    size_t at = find_tag(b, n, tag);
    int32_t np = 0;
    if (at >= n || n - at < 52) return n;
    memcpy(&np, b + at + 32, 4);
    if (np <= 0 || (n - at - 52) / 444 < (size_t)np) return n;
    return at + 52 + 444 * (size_t)np;
}

/* the checkpoint from, with nv bytes of v written at off into its driver state, resealed into to */
static void patch_state(const char *from, const char *to, const char *tag, size_t off, const void *v,
                        size_t nv) {
    size_t n, at;
    unsigned char *b = file_image(from, &n);
    CHECK(b != NULL && (at = state_at(b, n, tag)) < n && n - at >= off + nv + 8);
    if (b && (at = state_at(b, n, tag)) < n && n - at >= off + nv + 8)
        memcpy(b + at + off, v, nv), spill_resealed(to, b, n);
    free(b);
}

/* the MPMxDEM collapse and footing drivers read their own state from a checkpoint unchecked, and
 * the pipe driver its rows and the watched points' start: a snapshot index of -1e8 (collapse) made
 * the run read far outside its list of snapshot times (SIGSEGV), a stage index of -5 (footing)
 * before its list of stages, and the pipe restarted with a NaN in a watched point's start. Each now
 * refused by name, exit 1, no rows written; a time step other than the run's too. */
TEST(mpmdem_driver_states_are_checked) {
#define CL_CK BUILD "/mpmdem_collapse --nx 4 --every 0.025 --snapshots 0.05 --quiet --t-end 0.1 "
#define FT_CK                                                                                        \
    BUILD "/mpmdem_footing --width 2 --depth 1.5 --nx 4 --ny 3 --B 1.5 --velocity 0.25 --ramp 0.01 " \
          "--every 0.005 --smooth 0.01 --phi-deg 30 --threads 1 --quiet "
#define PP_CK                                                                                              \
    BUILD "/mpmdem_pipe --width 3 --nx 12 --ny 5 --penetration 0.1 --lateral 0.05 --v-down 1 --v-lateral " \
          "1 --ramp 0.02 --every 0.02 --threads 1 --quiet "
    int32_t i = -100000000;
    double v = NAN;
    size_t n, at;
    unsigned char *b;
    CHECK_EQ_INT(run_status("rm -rf " OUT("cl_b") " " OUT("ft_b") " " OUT("pp_b")), 0);
    mkdir(OUT("cl_bad"), 0755), mkdir(OUT("ft_bad"), 0755), mkdir(OUT("pp_bad"), 0755);
    /* collapse: cl_state's snapshot index (offset 44), then its time step (16) doubled */
    CHECK_EQ_INT(run_status(CL_CK "--t-end 0.05 --checkpoint 10 --out " OUT("cl_a") LOG("cl_a")), 0);
    patch_state(OUT("cl_a/checkpoint.bin"), OUT("cl_bad/checkpoint.bin"), "GKMPMDEM2 collapse", 44, &i, 4);
    CHECK_EQ_INT(run_status(CL_CK "--restart " OUT("cl_bad") " --out " OUT("cl_b") LOG("cl_b")), 1);
    CHECK(gk_test_file_has(OUT("cl_b.out"), "snapshot or output counter out of range"));
    CHECK(!exists(OUT("cl_b/collapse.csv")));
    b = file_image(OUT("cl_a/checkpoint.bin"), &n);
    if (b && (at = state_at(b, n, "GKMPMDEM2 collapse")) < n && n - at >= 24) memcpy(&v, b + at + 16, 8);
    free(b);
    CHECK(v > 0.0);
    v *= 2;
    patch_state(OUT("cl_a/checkpoint.bin"), OUT("cl_bad/checkpoint.bin"), "GKMPMDEM2 collapse", 16, &v, 8);
    CHECK_EQ_INT(run_status(CL_CK "--restart " OUT("cl_bad") " --out " OUT("cl_b") LOG("cl_b")), 1);
    CHECK(gk_test_file_has(OUT("cl_b.out"), "written by another run"));
    CHECK(!exists(OUT("cl_b/collapse.csv")));
    /* footing: ft_state's stage index (offset 232) */
    i = -5;
    CHECK_EQ_INT(run_status(FT_CK "--final 0.01 --out " OUT("ft_a") LOG("ft_a")), 0);
    patch_state(OUT("ft_a/checkpoint.bin"), OUT("ft_bad/checkpoint.bin"), "GKMPMDEM2 footing", 232, &i, 4);
    CHECK_EQ_INT(run_status(FT_CK "--final 0.02 --restart " OUT("ft_bad") " --out " OUT("ft_b") LOG("ft_b")),
                 1);
    CHECK(gk_test_file_has(OUT("ft_b.out"), "stage, settlement or output counter out of range"));
    CHECK(!exists(OUT("ft_b/footing.csv")));
    /* pipe: the first watched point's start (pp_state's pt0, offset 304) */
    v = NAN;
    CHECK_EQ_INT(run_status(PP_CK "--max-steps 100 --out " OUT("pp_a") LOG("pp_a")), 0);
    patch_state(OUT("pp_a/checkpoint.bin"), OUT("pp_bad/checkpoint.bin"), "GKMPMDEM2 pipe", 304, &v, 8);
    CHECK_EQ_INT(run_status(PP_CK "--restart " OUT("pp_bad") " --out " OUT("pp_b") LOG("pp_b")), 1);
    CHECK(gk_test_file_has(OUT("pp_b.out"), "a non-finite start of point D"));
    CHECK(!exists(OUT("pp_b/pipe.csv")));
#undef CL_CK
#undef FT_CK
#undef PP_CK
}

/* femdem_cyclic checked its cyclic state for finite reals and a direction of +-1 only: a branch
 * counter of INT_MAX (its next reversal would overflow) was restarted from with exit 0, the run
 * taking its cycles as done without a step. Now refused, exit 1, no new rows. The state lies before
 * the rows' extras (5 doubles each) and the checksum; its ints: dir, branch, good, bsteps. */
TEST(cyclic_checkpoint_counters_are_checked) {
#define CY_CK \
    BUILD "/femdem_cyclic --test cyclic-strain --nx 2 --ny 1 --element q4 --increment 0.002 --threads 1 "
    unsigned char *b;
    size_t n, nc = 3; /* the initial row and two steps of 0.2 % (0.1 cycle of 1 %) */
    int32_t big = INT32_MAX;
    remove(OUT("cy_b/cyclic.csv"));
    CHECK_EQ_INT(run_status(CY_CK "--cycles 0.1 --out " OUT("cy_a") LOG("cy_a")), 0);
    b = file_image(OUT("cy_a/checkpoint.bin"), &n);
    CHECK(b != NULL && n > 8 + 40 * nc + 96);
    if (!b || n <= 8 + 40 * nc + 96) {
        free(b);
        return;
    }
    mkdir(OUT("cy_bad"), 0755);
    memcpy(b + n - 8 - 40 * nc - 96 + 4, &big, 4);
    spill_resealed(OUT("cy_bad/checkpoint.bin"), b, n);
    CHECK_EQ_INT(run_status(CY_CK "--cycles 0.2 --restart " OUT("cy_bad") " --out " OUT("cy_b") LOG("cy_b")),
                 1);
    CHECK(gk_test_file_has(OUT("cy_b.out"), "the cyclic state is out of range"));
    CHECK(!exists(OUT("cy_b/cyclic.csv")));
    CHECK_EQ_INT(run_status(CY_CK "--cycles 0.2 --restart " OUT("cy_a") " --out " OUT("cy_c") LOG("cy_c")),
                 0);
    free(b);
#undef CY_CK
}

/* femdem_dr took any finite value of its block (found by fuzz_dr_ckpt): a
 * bottom node lifted off its support, a row numbered as another step, a row
 * of negative seconds, h_ic other than the specimen's before the end of the
 * isotropic stage, a DR iteration count of 1e300 (converted to a long: undefined
 * behaviour). Each refused by exit 1 with the message, no new rows. */
TEST(dr_checkpoint_values_are_checked_in_range) {
#define DR_CK                                                                                               \
    BUILD "/femdem_dr --nx 1 --ny 2 --iso-steps 2 --strain 0.01 --dr-tol 1e-2 --servo-max 3 --vtk-every 0 " \
          "--steps 2 --threads 1 "
    /* the block (1 x 2 mesh: 12 dofs, 8 Gauss points, stopped after step 1: 2 rows): tag "FDR2", 8
     * ints, 19 reals (h_ic first, the DR's iteration count fourth), u, v, f0, H, P, the rows */
    const size_t reals = 4 + 8 * 4, u = reals + 19 * 8, rows = u + 8 * (3 * 12 + 18 * 8);
    const size_t at[5] = {u + 3 * 8, rows + 12 * 8, rows + 12 * 8 + 11 * 8, reals, reals + 3 * 8};
    const double val[5] = {1e-3, 0.0, -1.0, 0.019, 1e300};
    unsigned char *b;
    size_t n, tag;
    int k;
    CHECK_EQ_INT(run_status(DR_CK "--stop-after 1 --out " OUT("drr_a") LOG("drr_a")), 0);
    mkdir(OUT("drr_bad"), 0755);
    for (k = 0; k < 5; ++k) {
        double was;
        b = file_image(OUT("drr_a/checkpoint.bin"), &n);
        CHECK(b != NULL && (tag = find_tag(b, n, "FDR2")) < n && tag + rows + 2 * 12 * 8 + 8 == n);
        if (!b || tag + rows + 2 * 12 * 8 + 8 != n) return;
        memcpy(&was, b + tag + at[k], 8);
        CHECK(was != val[k]);
        memcpy(b + tag + at[k], &val[k], 8);
        spill_resealed(OUT("drr_bad/checkpoint.bin"), b, n);
        free(b);
        remove(OUT("drr_b/dr.csv"));
        CHECK_EQ_INT(run_status(DR_CK "--restart " OUT("drr_bad") " --out " OUT("drr_b") LOG("drr_b")), 1);
        CHECK(gk_test_file_has(OUT("drr_b.out"), "non-finite or out-of-range value"));
        CHECK(!exists(OUT("drr_b/dr.csv")));
    }
#undef DR_CK
}

/* femdem_nonlocal took any finite value of its block (found by
 * fuzz_nonlocal_ckpt): rows numbered out of order, a row of negative
 * seconds (the restart's clock goes back by it), a time or a peak of 1e300,
 * an arrival time of -5 (-1 means none). Each refused by exit 1 with the
 * message, no new rows. (Its reader also wrote the block into the model
 * before an inverted element refused it, and leaked the rows it replaced:
 * tests/fuzz/crashers/nonlocal_ckpt, replayed by `make test` and `make check`.) */
TEST(nonlocal_checkpoint_values_are_checked_in_range) {
#define NL_CK                                                                                      \
    BUILD "/femdem_nonlocal --test element-shear --packing examples/data/rve160_hm.txt --steps 4 " \
          "--strain 0.0004 --lone-increments 2 --threads 1 "
    /* the block: tag "GKFNL02" (8 bytes), 10 ints (the reduced dof count sixth), step, row count,
     * DEM steps, fingerprint, time, peak; then u and v (reduced), sigma (one point), the rows (17
     * columns; stopped after step 2: rows of steps 0, 1, 2), the band profiles (one row of elements:
     * 3 reals), the arrival time and the work of the one element */
    unsigned char *b;
    size_t n, tag, at[5], rows;
    int32_t nr = 0;
    int64_t nrow = 0;
    const double val[5] = {0.0, -1.0, 1e300, 1e300, -5.0};
    int k;
    CHECK_EQ_INT(run_status(NL_CK "--stop-after 2 --out " OUT("nlr_a") LOG("nlr_a")), 0);
    mkdir(OUT("nlr_bad"), 0755);
    for (k = 0; k < 5; ++k) {
        double was;
        b = file_image(OUT("nlr_a/checkpoint.bin"), &n);
        CHECK(b != NULL && (tag = find_tag(b, n, "GKFNL02")) < n);
        if (!b || tag == n) return;
        memcpy(&nr, b + tag + 8 + 5 * 4, 4), memcpy(&nrow, b + tag + 56, 8);
        CHECK_EQ_INT((int)nrow, 3);
        rows = tag + 96 + 8 * (2 * (size_t)nr + 9);
        CHECK(rows + 8 * (17 * 3 + 5) + 8 == n);
        if (nrow != 3 || rows + 8 * (17 * 3 + 5) + 8 != n) return;
        at[0] = rows + 17 * 8, at[1] = rows + 8 * (2 * 17 + 16), at[2] = tag + 80, at[3] = tag + 88;
        at[4] = rows + 8 * (17 * 3 + 3);
        memcpy(&was, b + at[k], 8);
        CHECK(was != val[k]);
        memcpy(b + at[k], &val[k], 8);
        spill_resealed(OUT("nlr_bad/checkpoint.bin"), b, n);
        free(b);
        remove(OUT("nlr_b/element-shear.csv"));
        CHECK_EQ_INT(run_status(NL_CK "--restart " OUT("nlr_bad") " --out " OUT("nlr_b") LOG("nlr_b")), 1);
        CHECK(gk_test_file_has(OUT("nlr_b.out"), "non-finite or out-of-range value"));
        CHECK(!exists(OUT("nlr_b/element-shear.csv")));
    }
#undef NL_CK
}

/* =============================================================== tools */
#define RVE_PATH BUILD "/rve_path --packing examples/data/rve400.txt --dH \"0 0.001 0 0\" "
#define GK_PACK BUILD "/gk_pack --n 60 "

/* gk_pack --target-void-ratio 2.5 (no 2D disk packing gets there) ended
 * with exit 0 and e = 0.24; now exit 1 and no file */
TEST(gk_pack_fails_on_a_void_ratio_it_cannot_reach) {
    remove(OUT("pack.txt"));
    CHECK_EQ_INT(run_status(GK_PACK "--target-void-ratio 2.5 --out " OUT("pack.txt") LOG("pack")), 1);
    CHECK(!exists(OUT("pack.txt")));
    CHECK(gk_test_file_has(OUT("pack.out"), "not reached"));
}

/* --friction-deg everywhere (degrees); 35 meant as radians is refused */
TEST(friction_angle_in_degrees_with_a_plausible_range) {
    CHECK_EQ_INT(run_status(GK_PACK "--friction-deg 35 --out " OUT("deg.txt") LOG("deg")), 0);
    CHECK(gk_test_file_has(OUT("deg.txt"), "friction angle 35 deg"));
    CHECK(gk_test_result(OUT("deg.out"), "void_ratio") > 0.0);
    CHECK_EQ_INT(run_status(GK_PACK "--friction-deg 95 --out " OUT("deg.txt") LOG("deg")), 2);
    CHECK_EQ_INT(run_status(RVE_PATH "--increments 1 --steps-per-increment 5 --friction-deg 35 --out " OUT(
                     "deg.csv") LOG("deg")),
                 0);
    CHECK_EQ_INT(run_status(RVE_PATH "--friction-angle 35" LOG("deg")), 2);
    CHECK(gk_test_file_has(OUT("deg.out"), "0 to 85 degrees"));
}

/* rve_path --out /dev/full wrote nothing and said 'wrote' with exit 0 */
TEST(rve_path_exits_nonzero_when_its_result_is_lost) {
    CHECK_EQ_INT(run_status(RVE_PATH "--increments 1 --steps-per-increment 5 --out /dev/full" LOG("full")),
                 1);
    CHECK(gk_test_file_has(OUT("full.out"), "error writing '/dev/full'"));
    CHECK(!gk_test_file_has(OUT("full.out"), "wrote"));
}

/* bench_tradeoff exited 0 when a configuration failed (only a failed
 * reference counted). Drivers replaced by a script that fails the adaptive
 * runs and writes a 3-row curve otherwise: exit 1, the run named. */
TEST(bench_tradeoff_fails_when_a_run_fails) {
    const char *dir = OUT("fakebin");
    const char *script = "#!/bin/sh\n"
                         "case \"$*\" in *adaptive*) exit 1;; esac\n"
                         "while [ $# -gt 0 ]; do [ \"$1\" = --out ] && out=$2; shift; done\n"
                         "mkdir -p \"$out\" && printf 'step,eps_axial,sigma_yy,sigma_xx,eps_v,iterations\\n"
                         "0,0,1e5,1e5,0,0\\n1,0.001,1.1e5,1e5,0.0001,2\\n2,0.002,1.2e5,1e5,0.0002,2\\n' > "
                         "\"$out/biaxial.csv\"\n";
    const char *names[3] = {"femdem_biaxial", "femdem_biaxial_float", "mpmdem_biaxial"};
    char path[256];
    int k;
    if (!exists(BUILD "/bench_tradeoff")) {
        printf("    " BUILD "/bench_tradeoff missing: `make test` builds it\n");
        CHECK(0);
        return;
    }
    mkdir(dir, 0755);
    for (k = 0; k < 3; ++k) {
        FILE *fp;
        snprintf(path, sizeof path, "%s/%s", dir, names[k]);
        fp = fopen(path, "w");
        CHECK(fp != NULL);
        if (!fp) return;
        fputs(script, fp);
        fclose(fp);
        chmod(path, 0755);
    }
    CHECK_EQ_INT(run_status(BUILD "/bench_tradeoff --bin " OUT("fakebin") " --out " OUT(
                     "tradeoff") " --steps 2" LOG("tradeoff")),
                 1);
    CHECK(gk_test_file_has(OUT("tradeoff.out"), "400d adaptive) failed: see"));
    CHECK(gk_test_file_has(OUT("tradeoff/tradeoff.csv"), "group,sweep"));
}

/* README: "every other call writes it to the gk_err * you pass (NULL: no message)" - bad input
 * with a NULL gk_err is still refused, without a crash */
TEST(a_null_gk_err_is_allowed) {
    gk_packing pk;
    gk_mesh m;
    gk_mpm_grid g;
    gk_pcell c;
    const int n0[3] = {0, 0, 0}, n2[3] = {2, 2, 1};
    const double o[3] = {0.0, 0.0, 0.0}, len[3] = {1.0, 1.0, 1.0}, hbad[9] = {0};
    CHECK(gk_packing_read(BUILD "/tests/no_such_packing.txt", &pk, NULL, NULL) != GK_OK);
    CHECK(gk_packing_init(&pk, 5, 10, NULL, NULL) != GK_OK);
    CHECK(gk_mesh_read_gmsh(BUILD "/tests/no_such_mesh.msh", &m, NULL, NULL) != GK_OK);
    CHECK(gk_mesh_structured(&m, GK_Q4, n0, o, len, NULL, NULL) != GK_OK);
    CHECK(gk_mpm_grid_create(&g, 2, o, -1.0, n2, NULL, NULL) != GK_OK);
    CHECK(gk_pcell_init(&c, 2, hbad, NULL) != GK_OK);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    mkdir(BUILD "/tests", 0755);
    RUN(packing_header_of_2e9_particles_allocates_nothing);
    RUN(packing_huge_cells_bin_without_overflow);
    RUN(cells_tiny_cutoff_and_nan_positions);
    RUN(packing_cell_line_must_be_finite);
    RUN(packing_long_lines_and_nul_bytes_are_refused);
    RUN(packing_directory_is_an_io_error);
    RUN(rve_create_refuses_radii_out_of_range);
    RUN(gmsh_counts_and_tags_allocate_from_the_text);
    RUN(gmsh_v22_tag_count_is_checked_before_it_indexes);
    RUN(gmsh_duplicate_tags_and_nan_coordinates_are_refused);
    RUN(rve_restore_refuses_invalid_states_and_changes_nothing);
    RUN(rve_deform_refuses_inadmissible_increments);
    RUN(rve_step_refuses_a_velocity_gradient_too_large_for_one_step);
    RUN(rve_stress_after_deform_lags_one_step);
    RUN(fem_element_stiffness_checks_tangent_and_index);
    RUN(fem_assemble_with_an_inverted_element_changes_nothing);
    RUN(fem_structured_mesh_refuses_int_overflow);
    RUN(fem_solver_init_nan_rhs_and_failed_factor);
    RUN(fem_pcg_refuses_infinite_tolerance_and_nan);
    RUN(mpm_step_refusing_det_F_leaves_the_points);
    RUN(writers_report_a_full_disk);
    RUN(twoscale_checkpoint_reference_is_checked);
    RUN(driver_checkpoint_blocks_are_checked);
    RUN(dr_and_nonlocal_checkpoints_refuse_non_finite_values);
    RUN(mpmdem_driver_states_are_checked);
    RUN(cyclic_checkpoint_counters_are_checked);
    RUN(dr_checkpoint_values_are_checked_in_range);
    RUN(nonlocal_checkpoint_values_are_checked_in_range);
    RUN(gk_pack_fails_on_a_void_ratio_it_cannot_reach);
    RUN(friction_angle_in_degrees_with_a_plausible_range);
    RUN(rve_path_exits_nonzero_when_its_result_is_lost);
    RUN(bench_tradeoff_fails_when_a_run_fails);
    RUN(a_null_gk_err_is_allowed);
    return gk_test_done();
}
