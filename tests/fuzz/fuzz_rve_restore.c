/* fuzz_rve_restore.c - libFuzzer harness: gk_rve_restore on arbitrary bytes.
 *
 * Two small RVEs are built once, deterministically: A, 2D linear law with
 * friction and rotation (30 disks), and B, 3D Hertz-Mindlin with rolling
 * resistance (40 spheres), both consolidated to 100 kPa. The first input
 * byte picks the RVE (even: A, odd: B), the rest is the state buffer. Each
 * input starts from the RVE's consolidated state, then:
 *   - a refused buffer must come with a message and leave the RVE exactly
 *     as it was (gk_rve_save byte for byte);
 *   - an accepted one must run 3 DEM steps of a small shear to GK_OK with
 *     a finite state, or be stopped with a message (GK_ERR_DT at a list
 *     rebuild, GK_ERR_CELL, ...), never GK_OK with a NaN.
 * Seeds (tests/fuzz/corpus/rve_restore): states of A and B saved at several
 * points of a shear, written by this file compiled with -DFUZZ_MAKE_SEEDS:
 *   cc -O2 -Iinclude -DFUZZ_MAKE_SEEDS tests/fuzz/fuzz_rve_restore.c -lm -o build/seeds && build/seeds DIR
 * Build and run: make fuzz (tests/fuzz/replay.c explains the layout). */
#define GK_IMPLEMENTATION
#include "gk_dem.h"
#include "fuzz_check.h"

static gk_rve rves[2];
static gk_rve_state pristine[2];
static int ready;

static void build(int which) {
    gk_gen_def g;
    gk_packing pk;
    gk_err e;
    gk_rve_def def = gk_rve_def_default();
    gk_consolidate_def cd;
    memset(&g, 0, sizeof g);
    g.dim = which ? 3 : 2;
    g.n = which ? 40 : 30;
    g.r_min = 0.4e-3;
    g.r_max = 0.6e-3;
    g.seed = 7;
    FUZZ_CHECK(gk_packing_generate(&pk, &g, NULL, &e) == GK_OK);
    if (which) {
        def.mat.law = GK_LAW_HERTZ;
        def.mat.roll_beta = 0.5;
        def.mat.roll_eta = 0.5;
        def.dt_factor = 0.2;
    }
    FUZZ_CHECK(gk_rve_create(&rves[which], &def, &pk) == GK_OK);
    gk_packing_free(&pk);
    memset(&cd, 0, sizeof cd);
    cd.pressure = 1e5;
    cd.max_steps = 200000;
    FUZZ_CHECK(gk_rve_consolidate(&rves[which], &cd, NULL) == GK_OK);
    FUZZ_CHECK(gk_rve_refresh(&rves[which]) == GK_OK);
    gk_rve_state_init(&pristine[which], NULL);
    FUZZ_CHECK(gk_rve_state_save(&pristine[which], &rves[which]) == GK_OK);
}

static void setup(void) {
    if (ready) return;
    build(0);
    build(1);
    ready = 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    gk_rve *r;
    gk_rve_state now;
    gk_result res;
    int w;
    double dH[9] = {0, 1e-5, 0, 0, 0, 0, 0, 0, 0};
    if (size < 1) return 0;
    setup();
    w = data[0] & 1;
    r = &rves[w];
    FUZZ_CHECK(gk_rve_state_restore(&pristine[w], r) == GK_OK);
    r->err.msg[0] = '\0';
    res = gk_rve_restore(r, data + 1, size - 1);
    if (res != GK_OK) {
        FUZZ_CHECK(gk_rve_error(r)[0] != '\0');
        gk_rve_state_init(&now, NULL);
        FUZZ_CHECK(gk_rve_state_save(&now, r) == GK_OK);
        FUZZ_CHECK(now.size == pristine[w].size && memcmp(now.buf, pristine[w].buf, now.size) == 0);
        gk_rve_state_free(&now);
        return 0;
    }
    res = gk_rve_deform(r, dH, 3);
    if (res != GK_OK) {
        FUZZ_CHECK(gk_rve_error(r)[0] != '\0');
        return 0;
    }
    {
        int k, p;
        FUZZ_CHECK(gk_m3_isfinite(r->stress) && gk_m3_isfinite(r->cell.h));
        for (k = 0; k < r->dim; ++k)
            for (p = 0; p < r->n; ++p) FUZZ_CHECK(isfinite(r->s[k][p]) && isfinite((double)r->v[k][p]));
    }
    return 0;
}

#ifdef FUZZ_MAKE_SEEDS
/* states of both RVEs at 0, 1, 10 and 100 steps of shear, each prefixed with its selector byte */
int main(int argc, char **argv) {
    int w, k;
    char name[64];
    if (argc < 2) return 2;
    setup();
    for (w = 0; w < 2; ++w)
        for (k = 0; k < 4; ++k) {
            static const int steps[4] = {0, 1, 10, 100};
            double dH[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
            gk_rve_state st;
            dH[1] = 1e-5 * steps[k];
            FUZZ_CHECK(gk_rve_state_restore(&pristine[w], &rves[w]) == GK_OK);
            if (steps[k]) FUZZ_CHECK(gk_rve_deform(&rves[w], dH, steps[k]) == GK_OK);
            gk_rve_state_init(&st, NULL);
            FUZZ_CHECK(gk_rve_state_save(&st, &rves[w]) == GK_OK);
            snprintf(name, sizeof name, "state_%s_%03d", w ? "3d_hertz_rolling" : "2d_linear", steps[k]);
            fuzz_write_seed(argv[1], name, (unsigned char)w, (const unsigned char *)st.buf, st.size);
            gk_rve_state_free(&st);
        }
    return 0;
}
#endif
