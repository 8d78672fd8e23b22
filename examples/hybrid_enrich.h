/* hybrid_enrich.h - the enrichment and the coupled steps of the hybrid driver (examples/hybrid.c;
 * examples, not library), on the models of hybrid_model.h.
 *
 * ORACLE AND ENRICHMENT (gk_hybrid.h): every --oracle-every steps the
 * plastic strain rate and the plastic strain of the last tau_l go to the
 * nodes; Alg. 1 with --c0, --c1, --cl, --cg (Tables 4, 6). On the trigger
 * (hybrid mode) the packing's grains whose reference positions lie in the
 * discrete zone (by the continuum's reference configuration) are trained:
 * the overlap grains (and, biaxial, those on the specimen's surface and
 * the bottom layer) are moved by --train times the continuum displacement
 * at --train-speed, then held for a tenth of that time; the grains that end
 * in the continuum zone are dropped, the discrete points deleted, mass and
 * momentum matched.
 *
 * A step of the run: hybrid_step (grains and continuum coupled through the one-cell overlap, eq 9)
 * and continuum_step (the continuum alone, the oracle, and the enrichment when it triggers).
 */
#ifndef HYBRID_ENRICH_H
#define HYBRID_ENRICH_H

#include "hybrid_model.h"

/* ------------------------------------------------------------------ enrichment */
/* the grains' mean stress in the strip y0 <= y < y1 across the (periodic)
 * width, compression-positive: tau = sigma_xy as the platen's (positive when
 * the top drags the grains along +x), sigma_n = -sigma_yy (gk_scene_stress_box) */
static int strip_stress(run *R, double y0, double y1, double *tau, double *sig_n) {
    double lo[3] = {0.0, 0.0, 0.0}, hi[3] = {0.0, 0.0, 0.0}, s[9];
    lo[1] = y0;
    hi[0] = R->W;
    hi[1] = y1;
    if (gk_scene_stress_box(&R->sc, lo, hi, s))
        return fprintf(stderr, "error: strip stress: %s\n", gk_scene_error(&R->sc)), 1;
    *tau = s[1];
    *sig_n = -s[4];
    return 0;
}

/* the nodes (periodic axes: their home) carrying a weight in the stencil at x with half-size lp, into
 * node[] (room for GK_MPM_MAX_STENCIL); returns their count, 0 for a stencil off the grid */
static int stencil_nodes(const run *R, const double x[3], double lp, size_t *node) {
    int32_t nd[GK_MPM_MAX_STENCIL];
    double w[GK_MPM_MAX_STENCIL];
    int n, k, m = 0;
    if (gk_mpm_shape_values(&R->g, R->md.basis, x, lp, &n, nd, w, NULL)) return 0;
    for (k = 0; k < n; ++k)
        if (w[k] > 0.0) node[m++] = gk_hybrid_home(&R->g, &R->per, (size_t)nd[k]);
    return m;
}

/* biaxial and indent (under gravity): the zone stays where it was made on the grid while material
 * moves through it, so grains that leave the overlap for the continuum zone stay coupled and points
 * carried into the discrete zone couple the grains about them (coupling_mask, mark_deep_points) */
static int zone_fixed_on_grid(const run *R) { return R->md.gravity[1] != 0.0 || R->o.test == T_BIAXIAL; }

/* 1 if one of the nodes of the stencil at x (with half-size lp) is marked in R->deep */
static int touches_deep(const run *R, const double x[3], double lp) {
    size_t node[GK_MPM_MAX_STENCIL];
    int k, n = stencil_nodes(R, x, lp, node);
    for (k = 0; k < n; ++k)
        if (R->deep[node[k]]) return 1;
    return 0;
}

/* Biaxial and indent: the points carried more than DEEP_CELLS into the discrete zone; their
 * stencils' nodes are marked in R->deep (their count in R->deep_n). The discrete zone's grains
 * are not coupled, so nothing held such a point: on the paper-size biaxial hybrid on 2.5 mm cells
 * one rode along the top platen over a corner's grains and out of the grid. The grains whose
 * stencils share those nodes are coupled (coupling_mask), so the point moves with them, as a grain
 * that leaves the overlap for the continuum zone stays coupled. */
static void mark_deep_points(run *R) {
    const double deep = R->o.phi0 - (0.5 + DEEP_CELLS) * R->h;
    int p, k;
    R->deep_n = 0;
    if (!zone_fixed_on_grid(R)) return;
    memset(R->deep, 0, R->g.nnode);
    for (p = 0; p < R->P.n; ++p) {
        size_t node[GK_MPM_MAX_STENCIL];
        double x[3] = {R->P.x[0][p], R->P.x[1][p], 0.0}, d;
        int n;
        if (!gk_hybrid_interp(&R->g, &R->per, R->dist, 1, R->nden, x, &d) || d >= deep) continue;
        n = stencil_nodes(R, x, R->P.lp[p], node);
        for (k = 0; k < n; ++k) R->deep[node[k]] = 1;
        ++R->deep_n;
    }
    if (R->deep_n > R->deep_max) R->deep_max = R->deep_n;
}

/* grain p of the hybrid scene: free and in the overlap (coupled this step)? Under gravity (indent) a
 * grain that has left the overlap for the continuum zone stays coupled too: the continuum's points
 * do not touch grains, so it would fall through the material (in the indentation 27 of 397 grains
 * did, one by 2 cm, and the intruder's mean load over depth 5-30 % was 8.4 kPa instead of 11.2).
 * So in the biaxial test, where a zone that reaches the sides leaves thin strips of continuum at
 * its corners: free, the grains pushed into them were squeezed out of the specimen along the top
 * wall and below the membranes' ends (on the paper-size specimen the specimen's eps_v reached 36 %
 * at 3 % strain against the band's 2 %; coupled, 2.9 % at 3.4 %).
 * In the planar test such grains stay free: coupled, they stiffen its band (mean shear stress
 * 184 kPa instead of 128, the all-grain DEM's 146). A few squeezed out of the discrete zone then
 * cross the continuum and fly on (at the paper's size one left the grains' domain at 42.5 % strain,
 * which stopped the run): the planar test's free grains more than STRAY_CELLS beyond the overlap
 * (or off the grid) are put in R->drop_ids, to be removed if they touch no grain (drop_loose).
 * Biaxial and indent: a discrete grain beside a point carried into the discrete zone is coupled
 * as well (mark_deep_points). Returns the count of strays (0 in the other tests and with
 * --keep-strays). */
static int coupling_mask(run *R) {
    gk_scene *sc = &R->sc;
    const int stray = R->o.test == T_PLANAR && R->md.gravity[1] == 0.0 && !R->o.keep_strays;
    const double far = R->o.phi0 + (0.5 + STRAY_CELLS) * R->h;
    int p, z, k = 0;
    mark_deep_points(R);
    for (p = 0; p < sc->rve.n; ++p) {
        double x[3], d;
        R->coupled[p] = 0;
        if (sc->flags[p] & GK_PARTICLE_PRESCRIBED) continue;
        gk_scene_position(sc, p, x);
        if (!gk_hybrid_interp(&R->g, &R->per, R->dist, 1, R->nden, x, &d)) {
            if (stray) R->drop_ids[k++] = sc->rve.id[p];
            continue;
        }
        z = gk_hybrid_zone(d, R->o.phi0, R->h);
        R->coupled[p] = z == GK_ZONE_OVERLAP || (z == GK_ZONE_CONTINUUM && zone_fixed_on_grid(R)) ||
                        (z == GK_ZONE_DISCRETE && R->deep_n && touches_deep(R, x, R->P.lp[0]));
        if (stray && d > far) R->drop_ids[k++] = sc->rve.id[p];
    }
    return k;
}

static int grow_grain_arrays(run *R, int n) {
    if (n <= R->cap_g) return 0;
    gk_scene_weight_contacts(&R->sc, NULL); /* the scene reads R->cw */
    free(R->xpre[0]);
    free(R->xpre[1]);
    free(R->coupled);
    free(R->cw);
    R->xpre[0] = (double *)malloc((size_t)n * sizeof(double));
    R->xpre[1] = (double *)malloc((size_t)n * sizeof(double));
    free(R->drop_ids);
    R->coupled = (unsigned char *)malloc((size_t)n);
    R->cw = (double *)malloc((size_t)n * sizeof(double));
    R->drop_ids = (int32_t *)malloc((size_t)n * sizeof(int32_t));
    if (!R->xpre[0] || !R->xpre[1] || !R->coupled || !R->cw || !R->drop_ids)
        return fprintf(stderr, "error: out of memory\n"), 1;
    R->cap_g = n;
    return 0;
}

/* of the k grains in R->drop_ids, those that touch no grain and are no membrane's member are
 * removed, each said on stdout ("grain ID <what> at ..."), and counted in R->lost with their share
 * of the grains' mass in R->lost_mass. Returns 1 on error. */
static int drop_loose(run *R, int k, const char *what) {
    gk_scene *sc = &R->sc;
    int p, q, c = 0;
    double m = 0.0, mall = 0.0;
    gk_rve_contact ct;
    if (!k) return 0;
    while (gk_rve_contact_next(&sc->rve, &c, &ct)) /* those that touch a grain stay */
        for (q = 0; q < k; ++q)
            if (R->drop_ids[q] == ct.i || R->drop_ids[q] == ct.j) R->drop_ids[q--] = R->drop_ids[--k];
    for (c = 0; c < sc->nmem; ++c) /* so do the membranes' members (a chain may part from its grains) */
        for (p = 0; p < sc->mem[c].n; ++p)
            for (q = 0; q < k; ++q)
                if (R->drop_ids[q] == sc->mem[c].ids[p]) R->drop_ids[q--] = R->drop_ids[--k];
    if (!k) return 0;
    for (p = 0; p < sc->rve.n; ++p) mall += sc->mass[p];
    for (q = 0; q < k; ++q) {
        double x[3];
        p = gk_scene_index(sc, R->drop_ids[q]);
        gk_scene_position(sc, p, x);
        m += sc->mass[p];
        if (!R->o.quiet)
            printf("grain %d %s at (%.4g, %.4g) m, %.3g m/s: removed\n", (int)R->drop_ids[q], what, x[0],
                   x[1], hypot((double)sc->rve.v[0][p], (double)sc->rve.v[1][p]));
    }
    if (gk_scene_remove(sc, k, R->drop_ids))
        return fprintf(stderr, "error: removing grains: %s\n", gk_scene_error(sc)), 1;
    R->lost += k;
    R->lost_mass += m / mall;
    if (!R->o.quiet)
        printf("grains removed so far: %d (%.3g %% of the grains' mass)\n", R->lost, 100.0 * R->lost_mass);
    return 0;
}

/* indent: the training of Sec 4.1.1 with the bin's walls and the intruder in the scene: the intruder
 * starts on the settled reference bed (as in the dem run) and travels the continuum's depth with the
 * boundary grains, then both are held for the relaxation (gk_hybrid_train's own relaxation would
 * keep the intruder moving: here a second training of zero displacement, after the intruder stops) */
static int indent_train(run *R, const unsigned char *bnd, double *const u[2], long ntrain, long nrelax,
                        gk_err *e) {
    gk_scene *sc = &R->sc;
    double *zero = (double *)calloc((size_t)sc->rve.n + 1, sizeof(double));
    const double *const u0[2] = {zero, zero};
    int bad;
    if (!zero) return gk_err_set(e, GK_ERR_ALLOC, "out of memory"), 1;
    bad = add_bin_walls(R) || add_intruder(R, R->y_intr0, R->depth / ((double)ntrain * R->dt));
    if (bad)
        gk_err_set(e, GK_ERR_STATE, "indent: the bin or the intruder could not be added");
    else if (gk_hybrid_train(sc, bnd, (const double *const *)u, ntrain, 0, e))
        bad = 1;
    else {
        intruder_velocity(R, 0.0);
        bad = gk_hybrid_train(sc, bnd, u0, nrelax, 0, e) != GK_OK;
    }
    free(zero);
    return bad;
}

/* biaxial: the training of a discrete zone that reaches the top platen. There the grains' top is a
 * frictionless wall that moves with the platen; placed where the highest trained grain touches it,
 * it would carry almost nothing (the top grains sit at heights that differ by up to a radius, and
 * the contact overlaps are a thousandth of it). So after the move the trained grains are held, all
 * but the top layer's away from the sides (bnd 2; the corners stay held: free, they were squeezed
 * out sideways), while the wall's servo seats it on them at the continuum's axial stress (as the
 * all-grain run's preload does with the confining pressure); it then stops for the relaxation,
 * after which the held grains are released (as gk_hybrid_train does). 1 ms after the swap on a
 * 2.4 x 3.6 cm specimen the axial stress is 94 % of the continuum's, 7 % with the wall placed
 * unseated (test_hybrid_driver). A zone below the top layer trains as before. */
static int biaxial_train(run *R, const unsigned char *bnd, double *const u[2], long ntrain, long nrelax,
                         gk_err *e) {
    gk_scene *sc = &R->sc;
    int p, n = sc->rve.n, top = 0;
    long steps = 0;
    double z[3] = {0.0, 0.0, 0.0}, gmax = -HUGE_VAL, xlo = HUGE_VAL, xhi = -HUGE_VAL, s = 0.0, area;
    for (p = 0; p < n; ++p) top += bnd[p] == 2;
    if (!top) return gk_hybrid_train(sc, bnd, (const double *const *)u, ntrain, nrelax, e) != GK_OK;
    if (gk_hybrid_train(sc, bnd, (const double *const *)u, ntrain, 0, e)) return 1;
    for (p = 0; p < n; ++p) {
        double x[3], r = (double)sc->rve.r[p];
        if (bnd[p] == 1 && gk_scene_prescribe(sc, p, z, z))
            return gk_err_set(e, GK_ERR_STATE, "training: %s", gk_scene_error(sc)), 1;
        if (R->role[sc->rve.id[p]] != 2) continue; /* the wall's extent: the whole top layer */
        gk_scene_position(sc, p, x);
        if (x[1] + r > gmax) gmax = x[1] + r;
        if (x[0] - r < xlo) xlo = x[0] - r;
        if (x[0] + r > xhi) xhi = x[0] + r;
    }
    area = (xhi - xlo) * THICK;
    if (add_top_wall(R, gmax) || (steps = seat_top_wall(R, R->sig_n, area, &s)) < 0)
        return gk_err_set(e, GK_ERR_STATE, "top wall: %s", gk_scene_error(sc)), 1;
    if (!R->o.quiet)
        printf("top wall seated on the trained grains at %.4g kPa (the continuum's axial stress %.4g kPa) "
               "in %ld steps\n",
               1e-3 * s, 1e-3 * R->sig_n, steps);
    if (nrelax > 0 && gk_scene_step(sc, nrelax))
        return gk_err_set(e, GK_ERR_STATE, "training relaxation: %s", gk_scene_error(sc)), 1;
    for (p = 0; p < n; ++p)
        if (bnd[p] == 1 && gk_scene_release(sc, p))
            return gk_err_set(e, GK_ERR_STATE, "training: %s", gk_scene_error(sc)), 1;
    return 0;
}

/* biaxial: the training displacements u of the held boundary grains (bnd != 0) corrected so that no
 * two of them overlap more than they do in the reference packing. The continuum's displacement is
 * affine at the grains' scale; moved by it, two held neighbours approach by the strain times D50
 * (about 10 um at the biaxial's 1 % at enrichment), a hundred times the overlap of a contact at the
 * confining pressure, and cannot rearrange while held: released at the swap, such pairs flung grains
 * at 1-2 m/s in the first step (66 contacts over 2 um, up to 12 um, on a 2.4 x 3.6 cm specimen) and
 * grains left the specimen at its corners. Each excess is taken off half on each grain along the
 * pair's normal, repeated (in a fixed order) until no excess is above 1e-3 um or 100 sweeps. The
 * largest correction is returned (m), -1 when out of memory. */
static double limit_boundary_overlaps(const gk_packing *sub, const unsigned char *bnd, double *const u[2]) {
    int n = sub->n, nb = 0, np = 0, cap = 0, a, b, k, sweep;
    int *ib = (int *)malloc((size_t)(n > 0 ? n : 1) * sizeof(int)), *pa = NULL;
    double *d0 = NULL, *u0[2], dmax = -1.0;
    u0[0] = (double *)malloc((size_t)(n > 0 ? n : 1) * sizeof(double));
    u0[1] = (double *)malloc((size_t)(n > 0 ? n : 1) * sizeof(double));
    if (!ib || !u0[0] || !u0[1]) goto out;
    for (a = 0; a < n; ++a) {
        u0[0][a] = u[0][a];
        u0[1][a] = u[1][a];
        if (bnd[a]) ib[nb++] = a;
    }
    for (a = 0; a < nb; ++a) /* the held pairs that touch, or nearly, at the targets */
        for (b = a + 1; b < nb; ++b) {
            int i = ib[a], j = ib[b];
            double dx = sub->x[j] + u[0][j] - sub->x[i] - u[0][i],
                   dy = sub->y[j] + u[1][j] - sub->y[i] - u[1][i];
            double rs = sub->r[i] + sub->r[j], ex, ey, ov;
            if (dx * dx + dy * dy >= rs * rs) continue;
            if (np == cap) {
                int *p2;
                double *d2;
                cap = cap ? 2 * cap : 256;
                p2 = (int *)realloc(pa, 2 * (size_t)cap * sizeof(int));
                if (!p2) goto out;
                pa = p2;
                d2 = (double *)realloc(d0, (size_t)cap * sizeof(double));
                if (!d2) goto out;
                d0 = d2;
            }
            ex = sub->x[j] - sub->x[i];
            ey = sub->y[j] - sub->y[i];
            pa[2 * np] = i;
            pa[2 * np + 1] = j;
            ov = rs - sqrt(ex * ex + ey * ey); /* in the reference packing */
            d0[np++] = ov > 0.0 ? ov : 0.0;
        }
    for (sweep = 0; sweep < 100; ++sweep) {
        double worst = 0.0;
        for (k = 0; k < np; ++k) {
            int i = pa[2 * k], j = pa[2 * k + 1];
            double dx = sub->x[j] + u[0][j] - sub->x[i] - u[0][i],
                   dy = sub->y[j] + u[1][j] - sub->y[i] - u[1][i];
            double dist = sqrt(dx * dx + dy * dy), ex = dist > 0.0 ? dx / dist : 1.0,
                   ey = dist > 0.0 ? dy / dist : 0.0;
            double excess = sub->r[i] + sub->r[j] - dist - d0[k];
            if (excess <= 0.0) continue;
            if (excess > worst) worst = excess;
            u[0][i] -= 0.5 * excess * ex;
            u[1][i] -= 0.5 * excess * ey;
            u[0][j] += 0.5 * excess * ex;
            u[1][j] += 0.5 * excess * ey;
        }
        if (worst < 1e-9) break;
    }
    for (dmax = 0.0, a = 0; a < nb; ++a) {
        int i = ib[a];
        double c = hypot(u[0][i] - u0[0][i], u[1][i] - u0[1][i]);
        if (c > dmax) dmax = c;
    }
out:
    free(ib);
    free(pa);
    free(d0);
    free(u0[0]);
    free(u0[1]);
    return dmax;
}

/* Sec 4: zones from the flagged nodes, the reference packing's grains of the
 * discrete zone trained (Sec 4.1.1), the swap (gk_hybrid_enrich) */
static int enrich(run *R) {
    const opts *o = &R->o;
    gk_mpm_grid *g = &R->g;
    gk_err e;
    size_t I, nn = g->nnode;
    int p, k, n = R->P.n, ng, nsel = 0, ndrop = 0, nb = 0, status = 1;
    double *num = NULL, *val = NULL, *X0w[3] = {NULL, NULL, NULL}, *xs[3], umax = 0.0, *u[2] = {NULL, NULL},
           *vg[2] = {NULL, NULL};
    unsigned char *bnd = NULL, *gz = NULL;
    int32_t *drop = NULL;
    gk_packing sub;
    gk_scene_def sd = scene_def(R);
    gk_hybrid_enrich_report rep;
    long ntrain, nrelax;
    double t0 = wtime(), ylo = HUGE_VAL, yhi = -HUGE_VAL;
    memset(&sub, 0, sizeof sub);
    /* the distance to the flagged nodes on every node, zones of the points */
    R->dist = (double *)malloc(nn * sizeof(double));
    num = (double *)malloc(4 * nn * sizeof(double));
    val = (double *)malloc(4 * (size_t)n * sizeof(double));
    X0w[0] = (double *)malloc((size_t)n * sizeof(double));
    X0w[1] = (double *)malloc((size_t)n * sizeof(double));
    X0w[2] = NULL;
    if (!R->dist || !num || !val || !X0w[0] || !X0w[1]) {
        fprintf(stderr, "error: out of memory\n");
        goto done;
    }
    {
        for (I = 0; I < nn; ++I) {
            double x[3];
            gk_mpm_grid_node_position(g, I, x);
            R->dist[I] = gk_hybrid_distance(g, &R->per, R->orc.flag, x);
            if (R->orc.flag[I]) {
                if (x[1] < ylo) ylo = x[1];
                if (x[1] > yhi) yhi = x[1];
            }
        }
        if (!o->quiet) printf("flagged nodes between y = %.4g and %.4g m\n", ylo, yhi);
    }
    for (p = 0; p < n; ++p) {
        double x[3] = {R->P.x[0][p], R->P.x[1][p], 0.0};
        R->C.zone[p] =
            (unsigned char)gk_hybrid_zone(gk_hybrid_distance(g, &R->per, R->orc.flag, x), o->phi0, R->h);
    }
    /* the continuum's reference configuration on the nodes: displacement and zone fractions */
    for (p = 0; p < n; ++p) {
        val[4 * p] = R->P.x[0][p] - R->C.X0[0][p];
        val[4 * p + 1] = R->P.x[1][p] - R->C.X0[1][p];
        val[4 * p + 2] = R->C.zone[p] == GK_ZONE_DISCRETE;
        val[4 * p + 3] = R->C.zone[p] == GK_ZONE_OVERLAP;
        X0w[0][p] = R->C.X0[0][p];
        X0w[1][p] = R->C.X0[1][p];
        if (o->test == T_PLANAR) X0w[0][p] -= R->W * floor(X0w[0][p] / R->W);
    }
    if (gk_hybrid_rasterize(g, &R->per, R->md.basis, R->P.lp[0], n, (const double *const *)X0w, R->P.m, val,
                            4, NULL, num, R->nden, &e)) {
        fprintf(stderr, "error: enrichment: %s\n", e.msg);
        goto done;
    }
    for (k = 0; k < 4; ++k)
        for (I = 0; I < nn; ++I)
            num[(size_t)k * nn + I] = R->nden[I] > 0.0 ? num[(size_t)k * nn + I] / R->nden[I] : 0.0;
    /* the reference packing's grains that go to the discrete zone */
    if (gk_packing_init(&sub, 2, R->pk.n, NULL, &e)) {
        fprintf(stderr, "error: %s\n", e.msg);
        goto done;
    }
    sub.h[0] = R->pk.h[0];
    sub.h[4] = R->pk.h[4];
    u[0] = (double *)malloc((size_t)R->pk.n * sizeof(double));
    u[1] = (double *)malloc((size_t)R->pk.n * sizeof(double));
    bnd = (unsigned char *)malloc((size_t)R->pk.n);
    if (!u[0] || !u[1] || !bnd) {
        fprintf(stderr, "error: out of memory\n");
        goto done;
    }
    for (k = 0; k < R->pk.n; ++k) {
        double X[3] = {R->pk.x[k], R->pk.y[k], 0.0}, f[4];
        int surface;
        if (!gk_hybrid_interp(g, &R->per, num, 4, R->nden, X, f)) continue;
        if (f[2] + f[3] < 0.5) continue;
        surface =
            o->test == T_BIAXIAL && (X[0] < 1.5 * DIAM || X[0] > R->W - 1.5 * DIAM || role_of(R, X[1]) != 0);
        sub.x[nsel] = X[0];
        sub.y[nsel] = X[1];
        sub.r[nsel] = R->pk.r[k];
        u[0][nsel] = o->train * f[0];
        u[1][nsel] = o->train * f[1];
        bnd[nsel] = f[3] >= f[2] || surface;
        if (o->test == T_BIAXIAL && role_of(R, X[1]) == 2 && X[0] >= 1.5 * DIAM && X[0] <= R->W - 1.5 * DIAM)
            bnd[nsel] = 2; /* the top layer off the sides: seated on by the top wall (biaxial_train) */
        if (bnd[nsel] && fabs(u[0][nsel]) > umax) umax = fabs(u[0][nsel]);
        if (bnd[nsel] && fabs(u[1][nsel]) > umax) umax = fabs(u[1][nsel]);
        nb += bnd[nsel] != 0;
        ++nsel;
    }
    if (nsel < 10) {
        fprintf(stderr, "error: enrichment: only %d grains in the discrete zone\n", nsel);
        goto done;
    }
    sub.n = nsel;
    if (o->test == T_BIAXIAL) {
        double c = limit_boundary_overlaps(&sub, bnd, u);
        if (c < 0.0) {
            fprintf(stderr, "error: out of memory\n");
            goto done;
        }
        if (!o->quiet)
            printf("training targets: held neighbours kept at their reference overlaps (largest correction "
                   "%.3g um)\n",
                   1e6 * c);
    }
    /* the training scene (the hybrid's scene from now on) */
    if (gk_scene_create(&R->sc, &sd, &sub)) {
        fprintf(stderr, "error: scene: %s\n", gk_scene_error(&R->sc));
        goto done;
    }
    R->have_sc = 1;
    ng = R->sc.rve.n;
    {
        /* the scene stores the grains in its own order: id = index in sub */
        double *ua[2];
        int bad;
        unsigned char *bm = (unsigned char *)malloc((size_t)ng);
        ua[0] = (double *)malloc((size_t)ng * sizeof(double));
        ua[1] = (double *)malloc((size_t)ng * sizeof(double));
        if (!bm || !ua[0] || !ua[1]) {
            fprintf(stderr, "error: out of memory\n");
            free(bm), free(ua[0]), free(ua[1]);
            goto done;
        }
        for (p = 0; p < ng; ++p) {
            int q = R->sc.rve.id[p];
            bm[p] = bnd[q];
            ua[0][p] = u[0][q];
            ua[1][p] = u[1][q];
            R->role[q] = (unsigned char)role_of(R, sub.y[q]);
        }
        if (o->test == T_INDENT && R->depth > umax) umax = R->depth;
        ntrain = (long)ceil(umax / (o->train_speed * R->dt));
        if (ntrain < 1000) ntrain = 1000;
        nrelax = ntrain / 10 > 500 ? ntrain / 10 : 500;
        if (!o->quiet)
            printf("enrichment at strain %.4g: %d flagged nodes, %d grains (%d on the trained boundary), "
                   "training "
                   "%ld + %ld steps (largest boundary displacement %.3g mm)\n",
                   R->strain, R->orc.nflag, ng, nb, ntrain, nrelax, 1e3 * umax);
        if (o->test == T_INDENT)
            bad = indent_train(R, bm, ua, ntrain, nrelax, &e);
        else if (o->test == T_BIAXIAL)
            bad = biaxial_train(R, bm, ua, ntrain, nrelax, &e);
        else
            bad = gk_hybrid_train(&R->sc, bm, (const double *const *)ua, ntrain, nrelax, &e) != GK_OK;
        free(bm);
        free(ua[0]);
        free(ua[1]);
        if (bad) {
            fprintf(stderr, "error: %s\n", e.msg);
            goto done;
        }
        R->grain_steps += (long)ng * (ntrain + nrelax);
    }
    /* Chen et al. Fig 13: the trained (--train 0: untrained) packing's mean shear stress in the
     * discrete zone of a planar band (the strip within phi_0 - h/2 of the flagged rows) */
    if (o->test == T_PLANAR) {
        double y0 = ylo - (o->phi0 - 0.5 * R->h), y1 = yhi + (o->phi0 - 0.5 * R->h), sn;
        if (y0 < 0.0) y0 = 0.0;
        if (y1 > R->H) y1 = R->H;
        if (y1 <= y0) {
            fprintf(stderr, "error: enrichment: an empty discrete zone\n");
            goto done;
        }
        if (strip_stress(R, y0, y1, &R->packing_tau, &sn)) goto done;
        if (!o->quiet)
            printf("packing (%s) in the discrete zone y %.4g-%.4g m: tau %.4g kPa, sigma_n %.4g kPa; the dem "
                   "run's: --mode dem --probe %.6g %.6g %.6g\n",
                   o->train > 0.0 ? "trained" : "untrained", y0, y1, 1e-3 * R->packing_tau, 1e-3 * sn,
                   R->strain, y0, y1);
    }
    /* the grains that ended in the continuum zone leave */
    drop = (int32_t *)malloc((size_t)ng * sizeof(int32_t));
    if (!drop) {
        fprintf(stderr, "error: out of memory\n");
        goto done;
    }
    for (p = 0; p < ng; ++p) {
        double x[3];
        gk_scene_position(&R->sc, p, x);
        if (gk_hybrid_zone(gk_hybrid_distance(g, &R->per, R->orc.flag, x), o->phi0, R->h) ==
            GK_ZONE_CONTINUUM)
            drop[ndrop++] = R->sc.rve.id[p];
    }
    if (ndrop && gk_scene_remove(&R->sc, ndrop, drop)) {
        fprintf(stderr, "error: %s\n", gk_scene_error(&R->sc));
        goto done;
    }
    ng = R->sc.rve.n;
    /* the continuum's velocity at the grains; their zones */
    gz = (unsigned char *)malloc((size_t)ng);
    vg[0] = (double *)malloc((size_t)ng * sizeof(double));
    vg[1] = (double *)malloc((size_t)ng * sizeof(double));
    if (!gz || !vg[0] || !vg[1]) {
        fprintf(stderr, "error: out of memory\n");
        goto done;
    }
    for (p = 0; p < n; ++p) {
        val[2 * p] = R->P.v[0][p];
        val[2 * p + 1] = R->P.v[1][p];
    }
    xs[0] = R->P.x[0];
    xs[1] = R->P.x[1];
    xs[2] = NULL;
    if (gk_hybrid_rasterize(g, &R->per, R->md.basis, R->P.lp[0], n, (const double *const *)xs, R->P.m, val, 2,
                            NULL, num, R->nden, &e)) {
        fprintf(stderr, "error: enrichment: %s\n", e.msg);
        goto done;
    }
    for (k = 0; k < 2; ++k)
        for (I = 0; I < nn; ++I)
            num[(size_t)k * nn + I] = R->nden[I] > 0.0 ? num[(size_t)k * nn + I] / R->nden[I] : 0.0;
    for (p = 0; p < ng; ++p) {
        double x[3], v[2] = {0.0, 0.0};
        gk_scene_position(&R->sc, p, x);
        gk_hybrid_interp(g, &R->per, num, 2, R->nden, x, v);
        vg[0][p] = v[0];
        vg[1][p] = v[1];
        gz[p] = (unsigned char)gk_hybrid_zone(gk_hybrid_distance(g, &R->per, R->orc.flag, x), o->phi0, R->h);
    }
    {
        double *extra[2];
        int stride[2] = {1, 9};
        extra[0] = R->side;
        extra[1] = R->Fw;
        if (gk_hybrid_enrich(&R->P, &R->C, &R->sc, gz, (const double *const *)vg, PARTITION, THICK, 2, extra,
                             stride, &rep, &e)) {
            fprintf(stderr, "error: %s\n", e.msg);
            goto done;
        }
        R->grain_scale = rep.mass_scale;
        if (o->weigh_overlap) { /* a grain's share of the contacts is its share of the mass */
            int idmax = 0;
            for (p = 0; p < ng; ++p)
                if (R->sc.rve.id[p] > idmax) idmax = R->sc.rve.id[p];
            R->wid = (double *)malloc(((size_t)idmax + 1) * sizeof(double));
            if (!R->wid) {
                fprintf(stderr, "error: out of memory\n");
                goto done;
            }
            for (p = 0; p < ng; ++p) R->wid[R->sc.rve.id[p]] = gz[p] == GK_ZONE_OVERLAP ? PARTITION : 1.0;
        }
    }
    if (!o->quiet)
        printf("swap: %d points deleted, %d in the overlap; %d grains (%d in the overlap, %d left the zone); "
               "mass "
               "%.6g -> %.6g kg/m (grain mass x %.4f)\n",
               rep.points_deleted, rep.points_overlap, ng, rep.grains_overlap, ndrop, rep.mass_before,
               rep.mass_after, rep.mass_scale);
    /* the boundary of the grains: platen layers, top wall, membranes */
    for (p = 0; p < ng; ++p) {
        int role = R->role[R->sc.rve.id[p]];
        double z[3] = {0.0, 0.0, 0.0};
        if (role && o->test == T_PLANAR) {
            fprintf(stderr,
                    "error: the discrete zone reaches a platen (--phi0 %g m too large for a %g m specimen)\n",
                    o->phi0, R->H);
            goto done;
        }
        if (role == 1 && gk_scene_prescribe(&R->sc, p, z, z)) {
            fprintf(stderr, "error: %s\n", gk_scene_error(&R->sc));
            goto done;
        }
    }
    if (o->test == T_BIAXIAL) {
        int nrow = extent_nrow(R);
        double row_h = specimen_height(R) / nrow, ytop = R->H + R->plate_y, *l, *r, gmax = -HUGE_VAL;
        for (p = 0; p < ng; ++p) {
            double x[3];
            gk_scene_position(&R->sc, p, x);
            if (x[1] + (double)R->sc.rve.r[p] > gmax) gmax = x[1] + (double)R->sc.rve.r[p];
        }
        if (R->top_wall < 0 && ytop - gmax < 2.0 * DIAM) { /* grains near the platen (not its layer): the
                                                              frictionless wall, moving with it */
            if (add_top_wall(R, gmax > ytop ? gmax : ytop)) {
                fprintf(stderr, "error: %s\n", gk_scene_error(&R->sc));
                goto done;
            }
        }
        /* the specimen's sides at enrichment: the extent of the continuum's outer points per row */
        l = (double *)malloc((size_t)nrow * sizeof(double));
        r = (double *)malloc((size_t)nrow * sizeof(double));
        if (!l || !r) {
            fprintf(stderr, "error: out of memory\n");
            goto done;
        }
        extent_rows(R, nrow, row_h, l, r);
        if (add_membranes(R, l, r, nrow, row_h, 1)) {
            free(l), free(r);
            goto done;
        }
        free(l);
        free(r);
    }
    /* the coupling */
    if (gk_hybrid_coupling_init(&R->cpl, g, NULL, &e)) {
        fprintf(stderr, "error: %s\n", e.msg);
        goto done;
    }
    for (I = 0; I < nn; ++I) R->nden[I] = 1.0; /* every node carries a distance */
    R->deep = (unsigned char *)calloc(nn, 1);
    if (!R->deep) {
        fprintf(stderr, "error: out of memory\n");
        goto done;
    }
    if (grow_grain_arrays(R, ng)) goto done;
    R->enriched = 1;
    R->strain_enrich = R->strain;
    gk_hybrid_history_free(&R->hist);
    status = 0;
done: /* every exit: the scratch freed */
    gk_packing_free(&sub);
    free(num);
    free(val);
    free(X0w[0]);
    free(X0w[1]);
    free(u[0]);
    free(u[1]);
    free(bnd);
    free(gz);
    free(vg[0]);
    free(vg[1]);
    free(drop);
    R->sec_dem += wtime() - t0;
    return status;
}

/* Grains squeezed out of the discrete zone's side (at the paper's size of the biaxial test, a few
 * of 1900, where a membrane chain ends or at the swap) fly off; one whose coupling support would
 * leave the grid (gk_mpm_support_inside, the test that stops the run) if it moved ESCAPE_SPARE
 * further out sideways (the platens hold the grains above and below), touching no other grain and
 * not on a membrane, has left the specimen: it is removed, and said so, with the running count and
 * the share of the grains' mass lost (R->lost, R->lost_mass). A grain there that touches others or
 * is a membrane's member (one may part from the grains for a moment) is the specimen's own material
 * spreading that far: it stays (and the run stops when it leaves the grid). Returns 1 on error. */
static int remove_escaped(run *R) {
    const gk_mpm_grid *g = &R->g;
    gk_scene *sc = &R->sc;
    int p, k = 0;
    for (p = 0; p < sc->rve.n; ++p) { /* the candidates: free grains near the grid's sides */
        double x[3], xl[3], xr[3];
        if (sc->flags[p] & GK_PARTICLE_PRESCRIBED) continue;
        gk_scene_position(sc, p, x);
        memcpy(xl, x, sizeof x);
        memcpy(xr, x, sizeof x);
        xl[0] -= ESCAPE_SPARE * g->h;
        xr[0] += ESCAPE_SPARE * g->h;
        if (!gk_mpm_support_inside(g, R->md.basis, xl, R->P.lp[0]) ||
            !gk_mpm_support_inside(g, R->md.basis, xr, R->P.lp[0]))
            R->drop_ids[k++] = sc->rve.id[p];
    }
    return drop_loose(R, k, "left the specimen");
}

/* one step of the hybrid: continuum to vn, grains one step, coupling, continuum G2P */
static int hybrid_step(run *R) {
    gk_scene *sc = &R->sc;
    gk_err e;
    gk_hybrid_couple_report rep;
    int p, ng = sc->rve.n;
    double t0;
    if (R->o.test == T_BIAXIAL && R->step % REFRESH_EVERY == 0) { /* free sides */
        if (remove_escaped(R)) return 1;
        ng = sc->rve.n;
    }
    if (grow_grain_arrays(R, ng)) return 1;
    /* which grains lie in the overlap; planar: strays removed */
    if (R->step % REFRESH_EVERY == 0 || R->mask_n != ng) {
        if (drop_loose(R, coupling_mask(R), "strayed into the continuum zone")) return 1;
        if (sc->rve.n != ng) {
            ng = sc->rve.n;
            coupling_mask(R); /* the indices have moved */
        }
        R->mask_n = ng;
    }
    if (R->o.weigh_overlap && !sc->cw) { /* set again after every removal (the indices moved) */
        for (p = 0; p < ng; ++p) R->cw[p] = R->wid[sc->rve.id[p]];
        if (gk_scene_weight_contacts(sc, R->cw)) return fprintf(stderr, "error: %s\n", gk_scene_error(sc)), 1;
    }
    for (p = 0; p < ng; ++p) { /* the coupling reads the coupled grains' only */
        double x[3];
        if (!R->coupled[p]) continue;
        gk_scene_position(sc, p, x);
        R->xpre[0][p] = x[0];
        R->xpre[1][p] = x[1];
    }
    if (mpm_predict(R)) return 1;
    t0 = wtime();
    /* one step at a time: the Love stress is read nowhere here, so it is not made */
    if (gk_scene_step_flags(sc, 1, GK_STEP_NO_STRESS))
        return fprintf(stderr, "error: DEM at t = %g s: %s\n", R->t, gk_scene_error(sc)), 1;
    R->sec_dem += wtime() - t0;
    R->grain_steps += ng;
    t0 = wtime();
    gk_hybrid_bc_mask(&R->g, R->bcmask);
    if (gk_hybrid_couple(&R->cpl, &R->g, &R->per, R->md.basis, R->P.lp[0], sc, (const double *const *)R->xpre,
                         R->coupled, R->bcmask, THICK, R->dt, &rep, &e))
        return fprintf(stderr, "error: coupling at t = %g s: %s\n", R->t, e.msg), 1;
    R->sec_cpl += wtime() - t0;
    return mpm_finish(R);
}

/* one step of the continuum (continuum and hybrid modes), with the oracle */
static int continuum_step(run *R) {
    if (R->enriched) {
        if (hybrid_step(R)) return 1;
    } else {
        if (mpm_predict(R) || mpm_finish(R)) return 1;
    }
    R->t += R->dt;
    ++R->step;
    mpm_measure(R);
    if (!R->enriched && R->step % R->o.oracle_every == 0) {
        int trig = oracle_eval(R);
        if (trig < 0) return 1;
        if (trig && !R->triggered) {
            R->triggered = 1;
            R->strain_trigger = R->strain;
            if (!R->o.quiet)
                printf("oracle: %d nodes flagged and unchanged for tau_g at strain %.4g\n", R->orc.nflag,
                       R->strain);
        }
        if (trig && R->o.mode == M_HYBRID && enrich(R)) return 1;
    }
    return 0;
}
#endif /* HYBRID_ENRICH_H */
