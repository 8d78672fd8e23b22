/* test_hybrid_setup.c - parts of the hybrid driver (examples/hybrid_*.h) tested directly: the
 * membranes on the grains' sides of a biaxial specimen, the removal of grains that left it, the
 * side traction on the continuum's points, the coupling of grains beside a point carried into the
 * discrete zone, the planar test's coupling mask and its removal of stray grains, the band
 * measure's --band-grains count. */
#include "gk_test.h"
#include <stdlib.h>

#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-function" /* the header's other helpers and tables */
#pragma GCC diagnostic ignored "-Wunused-variable"
#endif
#include "../examples/hybrid_enrich.h"

/* a biaxial run's state for the tests: options at their defaults, one thread, a W x H specimen */
static void biaxial_state(run *R, double W, double H) {
    memset(R, 0, sizeof *R);
    defaults(&R->o, T_BIAXIAL);
    R->o.threads = 1;
    R->W = W;
    R->H = H;
    R->top_wall = -1;
}

/* membranes on both sides of the specimen, its sides at x = 0 and W in 6 rows */
static int membranes_on_sides(run *R) {
    double l[6], r[6];
    int k;
    for (k = 0; k < 6; ++k) {
        l[k] = 0.0;
        r[k] = R->W;
    }
    return add_membranes(R, l, r, 6, R->H / 6, 1);
}

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
    double ytop = -HUGE_VAL;
    int i, j, n = 0, k, m, top_members = 0;
    biaxial_state(&R, 0.012, 0.012);
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
    CHECK(membranes_on_sides(&R) == 0);
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

/* A column of 1 mm disks on the left side whose top band holds two grains: the outermost (A,
 * x 0.5 mm, top edge 9.55 mm) and one further in but higher (B, top edge 10.45 mm, where the wall
 * is): chained by the outermost grain alone, the chain would end 0.9 mm below the wall, a gap a grain
 * passes through (on the paper-size biaxial hybrid two did); B must end the chain, tied to the wall. */
TEST(membrane_chain_ends_at_the_wall) {
    run R;
    gk_packing pk;
    gk_err e;
    gk_scene_def d;
    int k, n = 0;
    const gk_membrane *M;
    biaxial_state(&R, 0.012, 0.012);
    CHECK(gk_packing_init(&pk, 2, 10, NULL, &e) == GK_OK);
    pk.h[0] = pk.h[4] = 0.012;
    for (k = 1; k <= 8; ++k, ++n) { /* the column, y 1.05 ... 8.05 mm */
        pk.x[n] = 0.5 * DIAM;
        pk.y[n] = (k + 0.05) * DIAM;
        pk.r[n] = 0.5 * DIAM;
    }
    pk.x[n] = 0.5 * DIAM, pk.y[n] = 9.05 * DIAM, pk.r[n++] = 0.5 * DIAM; /* A: id 8 */
    pk.x[n] = 1.5 * DIAM, pk.y[n] = 9.95 * DIAM, pk.r[n++] = 0.5 * DIAM; /* B: id 9 */
    pk.n = n;
    d = scene_def(&R);
    CHECK(gk_scene_create(&R.sc, &d, &pk) == GK_OK);
    CHECK(add_top_wall(&R, 10.45 * DIAM) == 0);
    CHECK(membranes_on_sides(&R) == 0);
    CHECK_EQ_INT(R.sc.nmem, 1); /* the left side only */
    if (R.sc.nmem != 1) return;
    M = &R.sc.mem[0];
    CHECK_EQ_INT(M->n, 10);
    CHECK_EQ_INT(M->ids[0], 9);
    CHECK_EQ_INT(M->ids[1], 8);
    CHECK_EQ_INT(M->anchor[0], R.top_wall);
    gk_scene_destroy(&R.sc);
    gk_packing_free(&pk);
}

/* the grid tests' set-up, R's test, size and options set before: a grid of 10 x 10 cells of 1 mm
 * from (-3, -3) mm (points' half-size lp 0.25 mm), n grains of radii r at xy in a packing cell of
 * width `cell`, grain `fixed` prescribed at rest (as the driver's platen layers), one step for the
 * contacts */
static void grains_on_grid(run *R, gk_packing *pk, int n, const double (*xy)[2], const double *r, double cell,
                           int fixed) {
    static double lp = 0.00025;
    double org[3] = {-0.003, -0.003, 0.0}, z[3] = {0.0, 0.0, 0.0};
    int nn[3] = {11, 11, 1}, k;
    gk_err e;
    gk_scene_def d;
    R->P.lp = &lp;
    CHECK(gk_mpm_grid_create(&R->g, 2, org, 0.001, nn, NULL, &e) == GK_OK); /* nodes -3 .. 7 mm */
    CHECK(gk_packing_init(pk, 2, n, NULL, &e) == GK_OK);
    pk->h[0] = pk->h[4] = cell;
    for (k = 0; k < n; ++k) {
        pk->x[k] = xy[k][0];
        pk->y[k] = xy[k][1];
        pk->r[k] = r[k];
    }
    pk->n = n;
    d = scene_def(R);
    CHECK(gk_scene_create(&R->sc, &d, pk) == GK_OK);
    CHECK(grow_grain_arrays(R, n) == 0);
    CHECK(gk_scene_prescribe(&R->sc, gk_scene_index(&R->sc, fixed), z, z) == GK_OK);
    CHECK(gk_scene_step(&R->sc, 1) == GK_OK);
}

/* frees what grains_on_grid and the tests made (free(NULL) where a test made less) */
static void free_grid_state(run *R, gk_packing *pk) {
    gk_scene_destroy(&R->sc);
    gk_mpm_grid_destroy(&R->g);
    gk_packing_free(pk);
    free(R->dist);
    free(R->nden);
    free(R->xpre[0]);
    free(R->xpre[1]);
    free(R->coupled);
    free(R->cw);
    free(R->drop_ids);
    free(R->deep);
}

/* remove_escaped: on a grid of 10 x 10 cells of 1 mm from (-3, -3) mm with points' half-size lp
 * 0.25 mm, grains are kept whose centres lie within x = -1.5 ... 5.5 mm (ESCAPE_SPARE, 1.25 cells,
 * inside where the uGIMP support, lp around a grain, leaves the grid: -2.75 ... 6.75 mm): grains 0
 * and 1. Outside it, grain 2 touches nothing (squeezed out of the specimen, on its way off the
 * grid): removed and counted with its share of the grains' mass; grains 4 and 5 touch each other
 * (the specimen's material spreading that far): kept; grain 3 (x 5.8 mm) is prescribed (as the
 * driver's platen layers): kept. */
TEST(escaped_grains_are_removed_and_counted) {
    run R;
    gk_packing pk;
    int k;
    const double xy[6][2] = {{0.001, 0.001},  {0.0035, 0.002},   {-0.0019, 0.002},
                             {0.0058, 0.002}, {-0.0022, 0.0035}, {-0.0022, 0.00405}};
    const double r[6] = {0.0003, 0.0006, 0.0003, 0.0003, 0.0003, 0.0003};
    biaxial_state(&R, 0.006, 0.006); /* the scene's domain: -3 to 9 mm */
    R.o.quiet = 1;
    grains_on_grid(&R, &pk, 6, xy, r, 0.01, 3); /* the contacts: 4 with 5 */
    CHECK(remove_escaped(&R) == 0);
    CHECK_EQ_INT(R.sc.rve.n, 5);
    CHECK_EQ_INT(R.lost, 1);
    CHECK(gk_scene_index(&R.sc, 2) < 0);
    for (k = 0; k < 6; ++k)
        if (k != 2) CHECK(gk_scene_index(&R.sc, k) >= 0);
    /* mass share: disk areas 0.09 x 5 and 0.36 (x pi mm^2): 0.09 / 0.81 */
    CHECK_NEAR(R.lost_mass, 0.09 / 0.81, 1e-12);
    CHECK(remove_escaped(&R) == 0); /* nothing more to remove */
    CHECK_EQ_INT(R.lost, 1);
    free_grid_state(&R, &pk);
}

/* coupling_mask, biaxial: the flagged nodes along y = 0 (the distance field |y| on the grid of 10 x
 * 10 cells of 1 mm from (-3, -3) mm), phi0 2 mm: the discrete zone |y| <= 1.5 mm, the overlap to
 * 2.5 mm; a point deeper than DEEP_CELLS (half a cell) inside the discrete zone, |y| < 1 mm, marks
 * its stencil's nodes, and the discrete grains whose stencils share one are coupled, so that the
 * point moves with them. Points: A (1, 0.5) mm deep, B (4, 1.2) in the discrete zone but not deep, C
 * (1, 4) in the continuum. Grains: 0 (1, 0.9) mm and 1 (4, 0.5), discrete; 2 (4, 2), overlap; 3 (1,
 * 3.5), continuum; 4 prescribed (a platen grain). Coupled: 0 (beside A), 2 and 3 (the overlap, and
 * the continuum zone's grains stay coupled in the biaxial test); 1 not (B marks nothing). With A
 * moved to (1, 1.2) no point is deep and grain 0 is not coupled. */
TEST(grains_about_a_deep_point_are_coupled) {
    run R;
    gk_packing pk;
    size_t I;
    double px[3] = {0.001, 0.004, 0.001}, py[3] = {0.0005, 0.0012, 0.004},
           plp[3] = {0.00025, 0.00025, 0.00025};
    const double xy[5][2] = {
        {0.001, 0.0009}, {0.004, 0.0005}, {0.004, 0.002}, {0.001, 0.0035}, {0.0058, -0.002}};
    const double r[5] = {0.0003, 0.0003, 0.0003, 0.0003, 0.0003};
    biaxial_state(&R, 0.006, 0.006); /* the scene's domain: -3 to 9 mm */
    R.o.quiet = 1;
    R.o.phi0 = 0.002;
    R.h = 0.001;
    grains_on_grid(&R, &pk, 5, xy, r, 0.01, 4);
    R.md.basis = GK_MPM_UGIMP;
    R.P.n = 3;
    R.P.x[0] = px;
    R.P.x[1] = py;
    R.P.lp = plp;
    R.dist = (double *)malloc(R.g.nnode * sizeof(double));
    R.nden = (double *)malloc(R.g.nnode * sizeof(double));
    R.deep = (unsigned char *)calloc(R.g.nnode, 1);
    CHECK(R.dist && R.nden && R.deep);
    for (I = 0; I < R.g.nnode; ++I) {
        R.dist[I] = fabs(R.g.origin[1] + R.h * (double)(I / (size_t)R.g.n[0]));
        R.nden[I] = 1.0;
    }
    CHECK_EQ_INT(coupling_mask(&R), 0);
    CHECK_EQ_INT(R.deep_n, 1);
    CHECK(R.coupled[gk_scene_index(&R.sc, 0)]);
    CHECK(!R.coupled[gk_scene_index(&R.sc, 1)]);
    CHECK(R.coupled[gk_scene_index(&R.sc, 2)] && R.coupled[gk_scene_index(&R.sc, 3)]);
    CHECK(!R.coupled[gk_scene_index(&R.sc, 4)]);
    py[0] = 0.0012;
    CHECK_EQ_INT(coupling_mask(&R), 0);
    CHECK_EQ_INT(R.deep_n, 0);
    CHECK(!R.coupled[gk_scene_index(&R.sc, 0)] && !R.coupled[gk_scene_index(&R.sc, 1)]);
    CHECK(R.coupled[gk_scene_index(&R.sc, 2)] && R.coupled[gk_scene_index(&R.sc, 3)]);
    CHECK_EQ_INT(R.deep_max, 1);
    free_grid_state(&R, &pk);
}

/* mpm_traction, biaxial: the confining pressure p on the outer columns of continuum points
 * (gk_hybrid_traction, fext = -p J F^-T N0 dl0; F = I: -p N0 dl0): a point on the left (N0 = -x)
 * is pushed in by p dl0, one on the right by -p dl0, an inner point (side 0) not at all. Overlap
 * points get none: the overlap's grains carry their whole contact forces and get the membrane's
 * whole pressure, so the points' 1 - w share stays unconfined at the side, and the overlap is as
 * strong there as the grains alone. (Given that share of the traction too, the biaxial hybrid's
 * mean shear stress over 2-10.6 % rose by 8-28 % on the reduced and paper-size specimens, away
 * from the all-grain runs', and the paper-size run on 2.5 mm cells still stopped at 3.6 %.) */
TEST(side_traction_acts_on_the_continuum_points) {
    run R;
    double F[4 * 9], fx[4], fy[4], side[4] = {-1.0, 1.0, 1.0, 0.0};
    unsigned char zone[4] = {GK_ZONE_CONTINUUM, GK_ZONE_CONTINUUM, GK_ZONE_OVERLAP, GK_ZONE_OVERLAP};
    const double p = 1e5, dl = 2.5e-3;
    int k;
    biaxial_state(&R, 0.012, 0.012);
    R.o.pressure = p;
    R.dyp = dl;
    memset(F, 0, sizeof F);
    for (k = 0; k < 4; ++k) F[9 * k] = F[9 * k + 4] = F[9 * k + 8] = 1.0;
    R.P.n = 4;
    R.P.F = F;
    R.P.fext[0] = fx;
    R.P.fext[1] = fy;
    R.side = side;
    R.C.zone = zone;
    for (k = 0; k < 4; ++k) fx[k] = fy[k] = 1.0; /* stale forces: cleared first */
    mpm_traction(&R);
    CHECK_NEAR(fx[0], p * dl, 1e-12);
    CHECK_NEAR(fx[1], -p * dl, 1e-12);
    CHECK_NEAR(fx[2], 0.0, 0.0);
    CHECK_NEAR(fx[3], 0.0, 0.0);
    for (k = 0; k < 4; ++k) CHECK_NEAR(fy[k], 0.0, 0.0);
}

/* coupling_mask and drop_loose, planar: flagged nodes along y = 0 (the distance field |y| on a
 * grid of 10 x 10 cells of 1 mm from (-3, -3) mm, every node holding material), phi0 2 mm: the
 * discrete zone y < 1.5 mm, the overlap to 2.5 mm, strays beyond 2.5 + STRAY_CELLS = 3.5 mm or off
 * the grid (above 8 mm the interpolation finds no node). Grain 0 (y 1 mm, discrete) and grain 1
 * (3 mm, continuum, within a cell of the overlap) are neither coupled nor strays; grain 7 (2 mm) is
 * coupled; strays: 2 (4.5 mm, touching nothing: removed), 3 and 4 (5 and 5.55 mm, touching each
 * other: kept), 6 (8.2 mm, off the grid, touching nothing: removed); 5 (5.8 mm) is prescribed (a
 * platen grain): kept and no stray. Removed: 2 of 8 equal disks, a quarter of the mass. With
 * --keep-strays none is a stray. */
TEST(planar_strays_are_removed_and_counted) {
    run R;
    gk_packing pk;
    int k;
    size_t I;
    const double xy[8][2] = {{0.001, 0.001},   {0.002, 0.003},  {0.003, 0.0045}, {0.004, 0.005},
                             {0.004, 0.00555}, {0.005, 0.0058}, {0.001, 0.0082}, {0.005, 0.002}};
    const double r[8] = {0.0003, 0.0003, 0.0003, 0.0003, 0.0003, 0.0003, 0.0003, 0.0003};
    memset(&R, 0, sizeof R);
    defaults(&R.o, T_PLANAR);
    R.o.threads = 1;
    R.o.quiet = 1;
    R.o.phi0 = 0.002;
    R.W = R.H = 0.006; /* the scene's domain: x periodic over 0 .. 6 mm, y -3 .. 9 mm */
    R.h = 0.001;
    grains_on_grid(&R, &pk, 8, xy, r, 0.006, 5); /* the contacts: 3 with 4 */
    R.dist = (double *)malloc(R.g.nnode * sizeof(double));
    R.nden = (double *)malloc(R.g.nnode * sizeof(double));
    CHECK(R.dist && R.nden);
    for (I = 0; I < R.g.nnode; ++I) {
        R.dist[I] = fabs(R.g.origin[1] + R.h * (double)(I / (size_t)R.g.n[0]));
        R.nden[I] = 1.0;
    }
    k = coupling_mask(&R);
    CHECK_EQ_INT(k, 4);
    CHECK(R.coupled[gk_scene_index(&R.sc, 7)]);
    CHECK(!R.coupled[gk_scene_index(&R.sc, 0)] && !R.coupled[gk_scene_index(&R.sc, 1)]);
    CHECK(drop_loose(&R, k, "strayed") == 0);
    CHECK_EQ_INT(R.sc.rve.n, 6);
    CHECK_EQ_INT(R.lost, 2);
    CHECK(gk_scene_index(&R.sc, 2) < 0 && gk_scene_index(&R.sc, 6) < 0);
    for (k = 0; k < 8; ++k)
        if (k != 2 && k != 6) CHECK(gk_scene_index(&R.sc, k) >= 0);
    CHECK_NEAR(R.lost_mass, 0.25, 1e-12);
    k = coupling_mask(&R); /* 3 and 4 again, still touching */
    CHECK_EQ_INT(k, 2);
    CHECK(R.coupled[gk_scene_index(&R.sc, 7)]);
    CHECK(drop_loose(&R, k, "strayed") == 0);
    CHECK_EQ_INT(R.lost, 2);
    CHECK_EQ_INT(R.sc.rve.n, 6);
    R.o.keep_strays = 1; /* --keep-strays: none, the mask the same */
    CHECK_EQ_INT(coupling_mask(&R), 0);
    CHECK(R.coupled[gk_scene_index(&R.sc, 7)] && !R.coupled[gk_scene_index(&R.sc, 1)]);
    free_grid_state(&R, &pk);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(membranes_reach_a_set_back_top_corner);
    RUN(membrane_chain_ends_at_the_wall);
    RUN(escaped_grains_are_removed_and_counted);
    RUN(planar_strays_are_removed_and_counted);
    RUN(side_traction_acts_on_the_continuum_points);
    RUN(grains_about_a_deep_point_are_coupled);
    return gk_test_done();
}
