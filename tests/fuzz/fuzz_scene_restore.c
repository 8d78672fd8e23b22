/* fuzz_scene_restore.c - libFuzzer harness: gk_scene_restore on arbitrary bytes.
 *
 * Two small scenes are built once, deterministically, with every part a state
 * can hold: A, 2D (25 disks in a box of four walls, gravity, a membrane along
 * the left column, one prescribed particle, two with locked rotation, an
 * external load, energy tracking); B, 3D (27 spheres with rolling resistance
 * in a box of six walls, gravity, one prescribed, one locked). Each runs 200
 * steps; that state is the pristine one. The first input byte picks the
 * scene (even: A, odd: B), the rest is the state buffer. Each input starts
 * from the pristine state, then:
 *   - a refused buffer must come with a message and leave the scene exactly
 *     as it was (gk_scene_save byte for byte);
 *   - an accepted one must run 3 steps to GK_OK with finite positions,
 *     velocities and wall forces, or be stopped with a message.
 * Seeds (tests/fuzz/corpus/scene_restore): states of A and B at 0, 1, 20 and
 * 200 steps, written by this file compiled with -DFUZZ_MAKE_SEEDS:
 *   cc -O2 -Iinclude -Itests/fuzz -DFUZZ_MAKE_SEEDS tests/fuzz/fuzz_scene_restore.c -lm -o build/seeds && build/seeds DIR
 * Build and run: make fuzz (tests/fuzz/replay.c explains the layout). */
#define GK_IMPLEMENTATION
#include "gk_scene.h"
#include "fuzz_check.h"

static gk_scene scenes[2];
static unsigned char *pristine[2];
static size_t npristine[2];
static int ready;

/* the state of sc (malloc'd) */
static unsigned char *state_of(const gk_scene *sc, size_t *n) {
    unsigned char *b;
    *n = gk_scene_state_size(sc);
    b = (unsigned char *)malloc(*n);
    FUZZ_CHECK(b && gk_scene_save(sc, b, *n, NULL) == GK_OK);
    return b;
}

/* scene which (0: 2D, 1: 3D) before any step */
static void create(int which) {
    gk_scene_def d = gk_scene_def_default();
    gk_packing pk;
    gk_err e;
    gk_scene *sc = &scenes[which];
    int m = which ? 3 : 5, dim = which ? 3 : 2, a, b, c, p = 0;
    double r = 1e-3, L = m * 2.2 * r, v[3] = {0.01, 0, 0}, zero[3] = {0, 0, 0}, f[3] = {1e-3, 0, 0};
    FUZZ_CHECK(gk_packing_init(&pk, dim, which ? 27 : 25, NULL, &e) == GK_OK);
    for (a = 0; a < m; ++a)
        for (b = 0; b < m; ++b)
            for (c = 0; c < (which ? m : 1); ++c, ++p) {
                pk.x[p] = (a + 0.5) * 2.2 * r;
                pk.y[p] = (b + 0.5) * 2.2 * r;
                if (which) pk.z[p] = (c + 0.5) * 2.2 * r;
                pk.r[p] = r * (1.0 + 0.05 * (double)(p % 3));
            }
    d.dim = dim;
    for (a = 0; a < dim; ++a) d.hi[a] = L;
    d.gravity[1] = -9.81;
    d.rve.mat.young = 1e7;
    d.rve.mat.friction = 0.4;
    d.rve.damping = 0.2;
    if (which) d.rve.mat.roll_beta = 0.3, d.rve.mat.roll_eta = 0.3;
    FUZZ_CHECK(gk_scene_create(sc, &d, &pk) == GK_OK);
    gk_packing_free(&pk);
    FUZZ_CHECK(gk_scene_add_box(sc, &d.rve.mat, GK_BOX_ALL, NULL) == GK_OK);
    FUZZ_CHECK(gk_scene_prescribe(sc, gk_scene_index(sc, 0), v, zero) == GK_OK);
    FUZZ_CHECK(gk_scene_lock_rotation(sc, gk_scene_index(sc, 1), 1) == GK_OK);
    if (!which) {
        int32_t left[5] = {4, 3, 2, 1, 0};
        FUZZ_CHECK(gk_scene_lock_rotation(sc, gk_scene_index(sc, 7), 1) == GK_OK);
        FUZZ_CHECK(gk_scene_set_external(sc, gk_scene_index(sc, 12), f, NULL) == GK_OK);
        FUZZ_CHECK(gk_scene_add_membrane(sc, 5, left, 1e3, 1e3, -1, -1, NULL) == GK_OK);
        FUZZ_CHECK(gk_scene_energy_track(sc, 1) == GK_OK);
    }
}

static void setup(void) {
    int w;
    if (ready) return;
    for (w = 0; w < 2; ++w) {
        create(w);
        FUZZ_CHECK(gk_scene_step(&scenes[w], 200) == GK_OK);
        pristine[w] = state_of(&scenes[w], &npristine[w]);
    }
    ready = 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    gk_scene *sc;
    gk_result res;
    int w, k, p;
    if (size < 1) return 0;
    setup();
    w = data[0] & 1;
    sc = &scenes[w];
    res = gk_scene_restore(sc, pristine[w], npristine[w]);
    if (res != GK_OK) fprintf(stderr, "the pristine state refused: %s\n", gk_scene_error(sc));
    FUZZ_CHECK(res == GK_OK);
    sc->err.msg[0] = '\0';
    res = gk_scene_restore(sc, data + 1, size - 1);
    if (res != GK_OK) {
        size_t n;
        unsigned char *now;
        FUZZ_CHECK(gk_scene_error(sc)[0] != '\0');
        now = state_of(sc, &n);
        FUZZ_CHECK(n == npristine[w] && memcmp(now, pristine[w], n) == 0);
        free(now);
        return 0;
    }
    /* every particle found by its id, by an index of O(n) entries whatever ids the state claims
     * (a table as long as its next id let a 20 kB state ask for 2.7 GB) */
    {
        static int nmax;
        if (sc->rve.n > nmax) nmax = sc->rve.n;
        for (p = 0; p < sc->rve.n; ++p) FUZZ_CHECK(gk_scene_index(sc, sc->rve.id[p]) == p);
        FUZZ_CHECK(sc->cap_ids <= 8 * nmax + 2048); /* gk_scene.h: at most 1.5 (4 n + 1024) + 16 */
    }
    res = gk_scene_step(sc, 3);
    if (res != GK_OK) {
        FUZZ_CHECK(gk_scene_error(sc)[0] != '\0');
        return 0;
    }
    for (p = 0; p < sc->rve.n; ++p) {
        double x[3];
        gk_scene_position(sc, p, x);
        fuzz_all_finite(x, 3);
        for (k = 0; k < sc->dim; ++k) FUZZ_CHECK(isfinite((double)sc->rve.v[k][p]));
    }
    for (k = 0; k < sc->nwalls; ++k) fuzz_all_finite(sc->walls[k].force, 3);
    return 0;
}

#ifdef FUZZ_MAKE_SEEDS
/* states of both scenes at 0, 1, 20 and 200 steps, each prefixed with its selector byte */
int main(int argc, char **argv) {
    int w, k;
    char name[64];
    if (argc < 2) return 2;
    for (w = 0; w < 2; ++w) {
        static const int steps[4] = {0, 1, 20, 200};
        create(w);
        for (k = 0; k < 4; ++k) {
            size_t n;
            unsigned char *b;
            if (steps[k])
                FUZZ_CHECK(gk_scene_step(&scenes[w], steps[k] - (k > 1 ? steps[k - 1] : 0)) == GK_OK);
            b = state_of(&scenes[w], &n);
            snprintf(name, sizeof name, "state_%s_%03d", w ? "3d_box_rolling" : "2d_box_membrane", steps[k]);
            fuzz_write_seed(argv[1], name, (unsigned char)w, b, n);
            free(b);
        }
    }
    return 0;
}
#endif
