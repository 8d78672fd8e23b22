/* test_hybrid_setup.c - the hybrid driver's specimen set-up (examples/hybrid_setup.h), tested
 * directly: the membranes on the grains' sides of a biaxial specimen. */
#include "gk_test.h"
#include <stdlib.h>

#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-function" /* the header's other helpers and tables */
#pragma GCC diagnostic ignored "-Wunused-variable"
#endif
#include "../examples/hybrid_setup.h"

/* A 12 x 12 mm block of 1 mm disks on a square lattice whose top two rows
 * stop 2 mm short of both sides, as the corners of a discrete zone that
 * reaches the top platen while the continuum keeps the specimen's corners:
 * each side's membrane chain must reach the top wall and be tied to it
 * (gk_scene.h: a tied end slides along the wall but cannot leave it, so no
 * grain passes round it). Chained only at 1.5 D50 from the side, the chains
 * ended 2.5 mm below the wall, untied, and on the paper-size biaxial hybrid
 * the grains between a chain's end and the wall were squeezed out along the
 * wall. */
TEST(membranes_reach_a_set_back_top_corner) {
    run R;
    gk_packing pk;
    gk_err e;
    gk_scene_def d;
    double l[6], r[6], ytop = -HUGE_VAL;
    int i, j, n = 0, k, m, top_members = 0;
    memset(&R, 0, sizeof R);
    defaults(&R.o, T_BIAXIAL);
    R.o.threads = 1;
    R.W = 0.012;
    R.H = 0.012;
    R.top_wall = -1;
    CHECK(gk_packing_init(&pk, 2, 144, NULL, &e) == GK_OK);
    pk.h[0] = pk.h[4] = 0.012;
    for (j = 0; j < 12; ++j)
        for (i = 0; i < 12; ++i) {
            if (j >= 10 && (i < 2 || i > 9)) continue; /* the set-back corners */
            pk.x[n] = (i + 0.5) * DIAM;
            pk.y[n] = (j + 0.5) * DIAM;
            pk.r[n] = 0.5 * DIAM;
            ++n;
        }
    pk.n = n;
    d = scene_def(&R);
    CHECK(gk_scene_create(&R.sc, &d, &pk) == GK_OK);
    for (k = 0; k < pk.n; ++k)
        if (pk.y[k] + pk.r[k] > ytop) ytop = pk.y[k] + pk.r[k];
    CHECK(add_top_wall(&R, ytop) == 0);
    for (k = 0; k < 6; ++k) {
        l[k] = 0.0;
        r[k] = R.W;
    }
    CHECK(add_membranes(&R, l, r, 6, R.H / 6) == 0);
    CHECK_EQ_INT(R.sc.nmem, 2);
    for (m = 0; m < R.sc.nmem; ++m) {
        const gk_membrane *M = &R.sc.mem[m];
        int left = m == 0, top = left ? 0 : M->n - 1; /* left: down from the top; right: up to it */
        double x[3];
        CHECK_EQ_INT(M->anchor[left ? 0 : 1], R.top_wall);
        CHECK_EQ_INT(M->anchor[left ? 1 : 0], -1);
        gk_scene_position(&R.sc, gk_scene_index(&R.sc, M->ids[top]), x);
        top_members += x[1] > 11.0 * DIAM; /* a grain of the top row ends the chain */
        CHECK(left ? x[0] < 3.0 * DIAM : x[0] > 9.0 * DIAM);
    }
    CHECK_EQ_INT(top_members, 2);
    gk_scene_destroy(&R.sc);
    gk_packing_free(&pk);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(membranes_reach_a_set_back_top_corner);
    return gk_test_done();
}
