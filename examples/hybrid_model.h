/* hybrid_model.h - the two models of the hybrid driver (examples/hybrid.c; examples, not library), on
 * the run of hybrid_setup.h: the grains (the all-grain specimen as a gk_scene with its platens and
 * membranes, DEM steps, the measured stresses), the MPM continuum (grid, points, the hypoelastic
 * Drucker-Prager of gk_hybrid.h, its platen and side traction) and the oracle that flags the band
 * (Chen et al. 2021 Alg. 1).
 */
#ifndef HYBRID_MODEL_H
#define HYBRID_MODEL_H

#include "hybrid_setup.h"

/* ------------------------------------------------------------------ grains */
/* indent, every mode: the bed in its bin settles under gravity (the cut
 * periodic packing, consolidated to --pressure, relaxes to its own weight
 * and its loose top grains drop) until its kinetic energy is below 1e-6 of
 * N m g D50; the settled positions become the reference packing (the
 * hybrid's grains come from it) and the intruder's start is the highest
 * grain under it (each model's intruder starts on its own surface: the
 * grains' here, the continuum's at y = H). The dem mode keeps the scene. */
static int indent_settle(run *R) {
    gk_scene_def d = scene_def(R);
    gk_scene *sc = &R->sc;
    double m = RHO_S * THICK * GK_PI * 0.25 * DIAM * DIAM, x0 = 0.5 * (R->W - R->o.intruder), ytop = 0.0,
           ke = 0.0, lim;
    long st;
    int p;
    if (gk_scene_create(sc, &d, &R->pk)) return fprintf(stderr, "error: scene: %s\n", gk_scene_error(sc)), 1;
    R->have_sc = 1;
    lim = 1e-6 * sc->rve.n * m * GRAV * DIAM;
    if (add_bin_walls(R)) return 1;
    for (st = 0; st < 2000000; st += 2000) {
        if (gk_scene_step(sc, 2000)) return fprintf(stderr, "error: settling: %s\n", gk_scene_error(sc)), 1;
        ke = gk_rve_kinetic_energy(&sc->rve);
        if (st >= 10000 && ke < lim) break;
    }
    if (!(ke < lim)) return fprintf(stderr, "error: the bed did not settle (kinetic energy %g J)\n", ke), 1;
    for (p = 0; p < sc->rve.n; ++p) {
        double x[3], r = (double)sc->rve.r[p];
        int k = sc->rve.id[p]; /* the scene's ids are the packing's indices */
        gk_scene_position(sc, p, x);
        R->pk.x[k] = x[0];
        R->pk.y[k] = x[1];
        if (x[0] + r > x0 && x[0] - r < x0 + R->o.intruder && x[1] + r > ytop) ytop = x[1] + r;
    }
    if (!R->o.quiet) {
        double wt = 0.0; /* at rest between smooth sides the bottom carries the whole weight */
        for (p = 0; p < sc->rve.n; ++p) wt += sc->mass[p] * GRAV;
        printf("bed settled under gravity in %ld steps: the bottom carries %.6g N of the grains' weight %.6g "
               "N; the grains' intruder starts at y = %.5g m\n",
               st + 2000, -sc->walls[R->bin_bottom].force[1], wt, ytop);
    }
    R->y_intr0 = ytop;
    sc->rve.time = 0.0;
    if (R->o.mode != M_DEM) {
        gk_scene_destroy(sc);
        R->have_sc = 0;
    }
    return 0;
}

/* the all-grain specimen: the packing with its top and bottom layers as
 * platens (planar: rough, prescribed grains) or bottom layer and a
 * frictionless wall (biaxial), membranes on the sides (biaxial) */
static int setup_dem(run *R) {
    gk_scene_def d = scene_def(R);
    gk_scene *sc = &R->sc;
    int p, n;
    double z[3] = {0.0, 0.0, 0.0};
    if (R->o.test == T_INDENT) return add_intruder(R, R->y_intr0, platen_speed(R, 0.0)); /* indent_settle */
    if (gk_scene_create(sc, &d, &R->pk)) return fprintf(stderr, "error: scene: %s\n", gk_scene_error(sc)), 1;
    R->have_sc = 1;
    n = sc->rve.n;
    for (p = 0; p < n; ++p) {
        double x[3];
        int role;
        gk_scene_position(sc, p, x);
        role = role_of(R, x[1]);
        R->role[sc->rve.id[p]] = (unsigned char)role;
        if (role == 1 || (role == 2 && R->o.test == T_PLANAR)) {
            double v[3] = {0.0, 0.0, 0.0};
            if (role == 2) v[0] = platen_speed(R, 0.0);
            if (gk_scene_prescribe(sc, p, v, z)) return fprintf(stderr, "error: %s\n", gk_scene_error(sc)), 1;
        }
    }
    if (R->o.test == T_BIAXIAL) {
        double ytop = -HUGE_VAL, s;
        int nrow = (int)floor(R->H / (2.0 * DIAM)), k;
        double *l = (double *)malloc((size_t)nrow * sizeof(double)),
               *r = (double *)malloc((size_t)nrow * sizeof(double));
        for (p = 0; p < n; ++p) {
            double x[3];
            gk_scene_position(sc, p, x);
            if (x[1] + (double)sc->rve.r[p] > ytop) ytop = x[1] + (double)sc->rve.r[p];
        }
        if (add_top_wall(R, ytop)) return fprintf(stderr, "error: %s\n", gk_scene_error(sc)), 1;
        R->y_plate0 = ytop;
        if (!l || !r) return fprintf(stderr, "error: out of memory\n"), 1;
        for (k = 0; k < nrow; ++k) { /* the packing's sides */
            l[k] = 0.0;
            r[k] = R->W;
        }
        if (add_membranes(R, l, r, nrow, R->H / nrow, 0)) return 1;
        free(l);
        free(r);
        /* preload: the cut-open top reloaded to the confining pressure by the wall's servo */
        if (seat_top_wall(R, R->o.pressure, R->W * THICK, &s) < 0)
            return fprintf(stderr, "error: preload: %s\n", gk_scene_error(sc)), 1;
        sc->walls[R->top_wall].def.velocity[1] = -platen_speed(R, 0.0);
        R->y_plate0 = sc->walls[R->top_wall].pos[1];
        sc->rve.time = 0.0;
    }
    return 0;
}

/* the platen loads of the grains (compression-positive, per the specimen width) */
static void dem_measure(run *R) {
    gk_scene *sc = &R->sc;
    if (R->o.test == T_INDENT) {
        double f[2];
        intruder_force(R, f);
        R->tau = f[1] / (R->o.intruder * THICK);
        R->sig_n = f[0] / (R->o.intruder * THICK);
    } else if (R->o.test == T_PLANAR) {
        double fx = 0.0, fy = 0.0;
        int p;
        for (p = 0; p < sc->rve.n; ++p)
            if (R->role[sc->rve.id[p]] == 2) {
                fx += sc->load[0][p];
                fy += sc->load[1][p];
            }
        R->tau = -fx / (R->W * THICK);
        R->sig_n = fy / (R->W * THICK);
    }
}

/* K steps of the all-grain specimen */
static int dem_steps(run *R, long K) {
    gk_scene *sc = &R->sc;
    double t0 = wtime(), V = platen_speed(R, R->t);
    int p;
    if (R->o.test == T_PLANAR) {
        double z[3] = {0.0, 0.0, 0.0}, v[3];
        v[0] = V;
        v[1] = R->plate_vy;
        v[2] = 0.0;
        for (p = 0; p < sc->rve.n; ++p)
            if (R->role[sc->rve.id[p]] == 2) gk_scene_prescribe(sc, p, v, z);
    } else if (R->o.test == T_INDENT) {
        intruder_velocity(R, V);
    } else {
        sc->walls[R->top_wall].def.velocity[1] = -V;
    }
    if (gk_scene_step(sc, K)) return fprintf(stderr, "error: DEM: %s\n", gk_scene_error(sc)), 1;
    R->sec_dem += wtime() - t0;
    R->grain_steps += (long)sc->rve.n * K;
    R->t += K * R->dt;
    R->step += K;
    if (R->o.test == T_PLANAR) {
        R->plate_x += V * K * R->dt;
        R->plate_y += R->plate_vy * K * R->dt;
        dem_measure(R);
        platen_velocity(R, R->sig_n * R->W * THICK, K * R->dt);
        R->strain = R->plate_x / R->W;
    } else if (R->o.test == T_INDENT) {
        R->depth = R->y_intr0 - R->sc.walls[R->intr[0]].pos[1];
        dem_measure(R);
        R->strain = R->depth / R->o.intruder;
    } else {
        double A = specimen_area(R);
        R->plate_y = sc->walls[R->top_wall].pos[1] - R->y_plate0;
        R->sig_n = sc->walls[R->top_wall].force[1] / THICK / (A / specimen_height(R));
        R->tau = 0.5 * (R->sig_n - R->o.pressure);
        R->strain = -R->plate_y / R->H;
    }
    return 0;
}

/* ------------------------------------------------------------------ continuum */
static int setup_mpm(run *R) {
    const opts *o = &R->o;
    gk_mpm_dp dp;
    gk_err e;
    double org[3] = {0.0, 0.0, 0.0}, Phi0, K0 = 1.0;
    int n[3] = {1, 1, 1}, ncx = (int)floor(R->W / o->cell + 0.5), nxp, nyp, i, j, p, margin;
    if (ncx < 3)
        return fprintf(stderr, "error: --cell %g: fewer than 3 cells across %g m\n", o->cell, R->W), 1;
    R->h = R->W / ncx;
    if (R->dt > 0.3 * R->h / R->c)
        return fprintf(stderr, "error: the MPM step %g s is above 0.3 h / c = %g s\n", R->dt,
                       0.3 * R->h / R->c),
               1;
    /* biaxial: at least 15 mm of grid beyond the free sides (the reduced
     * continuum's sliding block bulges 7 mm out by 9.5 % strain on 2.5 mm cells) */
    margin = o->test == T_PLANAR ? 1 : 3;
    if (o->test == T_BIAXIAL && margin * R->h < 0.015 - 1e-12) margin = (int)ceil(0.015 / R->h - 1e-9);
    org[0] = -margin * R->h;
    org[1] = -R->h;
    n[0] = ncx + 2 * margin + (o->test == T_PLANAR ? 1 : 1);
    n[1] = (int)ceil(R->H / R->h) + 5;
    if (gk_mpm_grid_create(&R->g, 2, org, R->h, n, NULL, &e))
        return fprintf(stderr, "error: grid: %s\n", e.msg), 1;
    memset(&R->per, 0, sizeof R->per);
    if (o->test == T_PLANAR) {
        R->per.ghost[0] = 1;
        R->per.period[0] = ncx;
    }
    R->md = gk_mpm_def_default();
    R->md.basis = GK_MPM_UGIMP;
    R->md.alpha = o->alpha;
    R->md.threads = o->threads;
    if (gk_hybrid_periodic_check(&R->g, &R->per, R->md.basis, &e))
        return fprintf(stderr, "error: %s\n", e.msg), 1;
    gk_mpm_grid_set_bc(&R->g, 2, GK_MPM_BC_FIXED, 0.0, 2, &e); /* bottom: no slip */
    if (o->test == T_INDENT) {                                 /* the bin's sides: rollers */
        gk_mpm_grid_set_bc(&R->g, 0, GK_MPM_BC_ROLLER, 0.0, 2, &e);
        gk_mpm_grid_set_bc(&R->g, 1, GK_MPM_BC_ROLLER, 0.0, 2, &e);
        R->md.gravity[1] = -GRAV;
    }
    /* points: ppd per cell edge on the cells' lattice (a point row that straddled
     * a cell boundary would tie a band to its neighbours); the continuum's
     * height is the whole number of cells nearest the packing's (its top
     * surface on a node row, where the platen acts) */
    nxp = ncx * o->ppd;
    nyp = (int)floor(R->H / R->h + 0.5) * o->ppd;
    R->dxp = R->dyp = R->h / o->ppd;
    if (gk_mpm_points_create(&R->P, 2, nxp * nyp, NULL, &e)) return fprintf(stderr, "error: %s\n", e.msg), 1;
    Phi0 = o->phi_init > 0.0 ? o->phi_init : R->phi_pack;
    if (o->test == T_INDENT) { /* Jaky's K0 = 1 - sin(phi) with the friction angle of eq 7 at Phi0 */
        double tphi = tan(0.27) + (Phi0 - PHI_CS) * 7.0;
        K0 = 1.0 - tphi / sqrt(1.0 + tphi * tphi);
    }
    R->side = (double *)calloc((size_t)nxp * nyp, sizeof(double));
    R->Fw = (double *)calloc(9 * (size_t)nxp * nyp, sizeof(double));
    if (!R->side || !R->Fw) return fprintf(stderr, "error: out of memory\n"), 1;
    for (j = 0, p = 0; j < nyp; ++j)
        for (i = 0; i < nxp; ++i, ++p) {
            R->P.x[0][p] = (i + 0.5) * R->dxp;
            R->P.x[1][p] = (j + 0.5) * R->dyp;
            R->P.vol0[p] = R->P.vol[p] = R->dxp * R->dyp;
            R->P.m[p] = R->rho * R->dxp * R->dyp;
            R->P.lp[p] = 0.5 * (R->dxp < R->dyp ? R->dxp : R->dyp);
            if (o->test == T_INDENT) { /* geostatic: sigma_yy = -rho g depth, sigma_xx = K0 sigma_yy */
                R->P.sigma[9 * p + 4] = -R->rho * GRAV * (nyp * R->dyp - R->P.x[1][p]);
                R->P.sigma[9 * p] = K0 * R->P.sigma[9 * p + 4];
            } else {
                R->P.sigma[9 * p] = R->P.sigma[9 * p + 4] = -o->pressure;
            }
            if (o->test == T_BIAXIAL) R->side[p] = i == 0 ? -1.0 : (i == nxp - 1 ? 1.0 : 0.0);
        }
    if (gk_mpm_dp_init(&dp, 2, K_C, G_C, 0.27, 0.0, 0.0, &e)) return fprintf(stderr, "error: %s\n", e.msg), 1;
    dp.tan_phi_cs = tan(0.27);
    dp.Phi_cs = PHI_CS;
    dp.chi = 7.0;
    dp.xi = o->xi;
    if (gk_hybrid_cont_init(&R->C, &R->P, &dp, Phi0, NULL, &e))
        return fprintf(stderr, "error: %s\n", e.msg), 1;
    /* the weak points that seed the band */
    for (p = 0; p < R->P.n; ++p) {
        double x = R->P.x[0][p], y = R->P.x[1][p];
        /* a whole cell row (planar) or cell (biaxial): a band of weak points that
         * shares its cells with strong ones could not slip alone */
        int weak = o->test == T_PLANAR
                       ? (int)floor(y / R->h) == (int)floor(0.5 * R->H / R->h)
                       : (o->test == T_BIAXIAL && x > R->W - 2.0 * R->h && x < R->W - R->h && y > R->h &&
                          y < 2.0 * R->h); /* indent: none (the intruder's corners seed the bands) */
        if (weak) R->C.Phi[p] = Phi0 - o->weak_dphi;
    }
    /* the top platen: rough and servo-controlled (planar) or frictionless (biaxial). The body
     * moves with its velocity (gk_mpm_bodies_advance): planar, it starts as far to the left
     * as it will travel, so that it covers the whole top row to the end of the run */
    memset(&R->body, 0, sizeof R->body);
    if (o->test == T_INDENT) { /* the intruder acts on the points (indent_contact), not on the grid */
        R->body.v[1] = -platen_speed(R, 0.0);
    } else {
        R->body.lo[0] = org[0] - R->h - (o->test == T_PLANAR ? o->strain_end * R->W : 0.0);
        R->body.hi[0] = org[0] + (n[0] + 1) * R->h;
        R->body.lo[1] = R->H - 1e-9; /* the nodes at and above the material's top surface */
        R->body.hi[1] = org[1] + (n[1] + 1) * R->h;
        if (o->test == T_PLANAR) {
            R->body.contact = GK_MPM_CONTACT_STICK;
            R->body.v[0] = o->speed;
        } else {
            R->body.contact = GK_MPM_CONTACT_SMOOTH;
            R->body.face = 3; /* its y- face: normal -y into the material */
            R->body.v[1] = -o->speed;
        }
    }
    R->g.body = &R->body;
    R->g.nbody = o->test == T_INDENT ? 0 : 1;
    R->have_mpm = 1;
    R->bcmask = (unsigned char *)malloc(R->g.nnode);
    if (!R->bcmask) return fprintf(stderr, "error: out of memory\n"), 1;
    return 0;
}

/* indent: the intruder on the continuum, a rough rigid rectangle [x0, x0 + B] x [yb, yb + 0.4 B]
 * (yb = H - depth) in contact with the points as squares of their current size: a point that
 * overlaps it is pushed out across the face of least overlap by k pen + c v_n (k = K + G per unit
 * thickness, c at half the critical damping of the point's mass), with Coulomb friction (mu 0.5,
 * viscously regularised) against the intruder's motion. A grid node that a box body covers would
 * take the material's velocity only at whole rows of nodes: the load would vanish while the
 * intruder lies between two rows and jump when it reaches the next. body.force holds the sum (the
 * force on the material, per unit thickness). */
static void indent_contact(run *R) {
    double B = R->o.intruder, x0 = 0.5 * (R->W - B), yb = R->H - R->depth, k = R->M, vy = R->body.v[1];
    int p;
    R->body.force[0] = R->body.force[1] = 0.0;
    for (p = 0; p < R->P.n; ++p) {
        double a = 0.5 * R->dxp * sqrt(R->P.vol[p] / R->P.vol0[p]), x = R->P.x[0][p], y = R->P.x[1][p];
        double pen[4], n[4][2] = {{-1.0, 0.0}, {1.0, 0.0}, {0.0, -1.0}, {0.0, 1.0}}, m = R->P.m[p];
        double c = sqrt(k * m), vn, vt, fn, ft, t[2], rv[2];
        int f, q;
        if (R->C.zone[p] == GK_ZONE_DISCRETE) continue;
        pen[0] = x + a - x0;
        pen[1] = x0 + B - (x - a);
        pen[2] = y + a - yb;
        pen[3] = yb + 0.4 * B - (y - a);
        if (pen[0] <= 0.0 || pen[1] <= 0.0 || pen[2] <= 0.0 || pen[3] <= 0.0) continue;
        for (f = 0, q = 1; q < 4; ++q)
            if (pen[q] < pen[f]) f = q;
        rv[0] = R->P.v[0][p];
        rv[1] = R->P.v[1][p] - vy; /* the point's velocity relative to the intruder */
        vn = rv[0] * n[f][0] + rv[1] * n[f][1];
        fn = k * pen[f] - c * vn; /* along n (out of the intruder), compressive only */
        if (fn <= 0.0) continue;
        t[0] = -n[f][1];
        t[1] = n[f][0];
        vt = rv[0] * t[0] + rv[1] * t[1];
        ft = -vt * m / R->dt; /* what would stop the slip in one step, capped by Coulomb */
        if (fabs(ft) > 0.5 * fn) ft = ft > 0.0 ? 0.5 * fn : -0.5 * fn;
        R->P.fext[0][p] += fn * n[f][0] + ft * t[0];
        R->P.fext[1][p] += fn * n[f][1] + ft * t[1];
        R->body.force[0] += fn * n[f][0] + ft * t[0];
        R->body.force[1] += fn * n[f][1] + ft * t[1];
    }
}

/* biaxial: the confining pressure as a follower traction on the outer columns
 * of continuum points; none on overlap points: the overlap's grains carry
 * their whole contact forces and get the membrane's whole pressure, and a
 * confined 1 - w share of the points on top of them would make the overlap
 * stronger than the material (tests/test_hybrid_setup.c); indent: the
 * intruder's push */
static void mpm_traction(run *R) {
    int p, k;
    for (k = 0; k < 2; ++k) memset(R->P.fext[k], 0, (size_t)R->P.n * sizeof(double));
    if (R->o.test == T_INDENT) indent_contact(R);
    if (R->o.test != T_BIAXIAL) return;
    for (p = 0; p < R->P.n; ++p)
        if (R->side[p] != 0.0 && R->C.zone[p] == GK_ZONE_CONTINUUM) {
            double N0[2] = {R->side[p], 0.0};
            gk_hybrid_traction(&R->P, p, N0, R->dyp, R->o.pressure);
        }
}

static int mpm_predict(run *R) {
    gk_err e;
    double t0 = wtime();
    if (R->o.test == T_PLANAR) {
        R->body.v[0] = platen_speed(R, R->t);
        R->body.v[1] = R->plate_vy;
    } else {
        R->body.v[1] = -platen_speed(R, R->t);
    }
    if (R->have_sc && R->top_wall >= 0) R->sc.walls[R->top_wall].def.velocity[1] = R->body.v[1];
    if (R->have_sc && R->nintr) intruder_velocity(R, -R->body.v[1]);
    mpm_traction(R);
    if (gk_hybrid_mpm_predict(&R->g, &R->per, &R->P, &R->md, R->dt, gk_hybrid_dp_stress, &R->C, &e))
        return fprintf(stderr, "error: MPM at t = %g s: %s\n", R->t, e.msg), 1;
    R->sec_mpm += wtime() - t0;
    return 0;
}

static int mpm_finish(run *R) {
    gk_err e;
    double t0 = wtime();
    if (gk_hybrid_mpm_finish(&R->g, &R->per, &R->P, &R->C, &R->md, R->dt, &e))
        return fprintf(stderr, "error: MPM at t = %g s: %s\n", R->t, e.msg), 1;
    R->sec_mpm += wtime() - t0;
    R->point_steps += R->P.n;
    return 0;
}

/* platen loads after a continuum step (plus the grains' wall in a hybrid biaxial test) */
static void mpm_measure(run *R) {
    double W = R->W;
    if (R->o.test == T_PLANAR) {
        R->plate_x += R->body.v[0] * R->dt;
        R->plate_y += R->body.v[1] * R->dt;
        R->tau = R->body.force[0] / W;
        R->sig_n = -R->body.force[1] / W;
        platen_velocity(R, R->sig_n * R->W * THICK, R->dt);
        R->strain = R->plate_x / R->W;
    } else if (R->o.test == T_INDENT) { /* the continuum's and the grains' push on the intruder */
        double f[2] = {0.0, 0.0};
        if (R->have_sc && R->nintr) intruder_force(R, f);
        R->depth -= R->body.v[1] * R->dt;
        R->tau = (-R->body.force[1] + f[1] / THICK) / R->o.intruder;
        R->sig_n = (-R->body.force[0] + f[0] / THICK) / R->o.intruder;
        R->strain = R->depth / R->o.intruder;
    } else {
        double F = -R->body.force[1];
        R->plate_y += R->body.v[1] * R->dt;
        if (R->have_sc && R->top_wall >= 0) F += R->sc.walls[R->top_wall].force[1] / THICK;
        W = specimen_area(R) / specimen_height(R);
        R->sig_n = F / W;
        R->tau = 0.5 * (R->sig_n - R->o.pressure);
        R->strain = -R->plate_y / R->H;
    }
}

/* ------------------------------------------------------------------ oracle */
static int oracle_setup(run *R) {
    gk_hybrid_oracle_def d;
    gk_err e;
    size_t nn = R->g.nnode;
    int n = R->P.n;
    d.c0 = R->o.c0;
    d.c1 = R->o.c1;
    d.cl = R->o.cl;
    d.cg = R->o.cg;
    d.D50 = DIAM;
    if (gk_hybrid_oracle_init(&R->orc, &d, nn, NULL, &e) ||
        gk_hybrid_history_init(&R->hist, n, 3, 512, NULL, &e))
        return fprintf(stderr, "error: %s\n", e.msg), 1;
    R->past = (double *)malloc(3 * (size_t)n * sizeof(double));
    R->pval = (double *)malloc(2 * (size_t)n * sizeof(double));
    R->nnum = (double *)malloc(2 * nn * sizeof(double));
    R->nden = (double *)malloc(nn * sizeof(double));
    R->nrate = (double *)malloc(nn * sizeof(double));
    R->nrec = (double *)malloc(nn * sizeof(double));
    R->active = (unsigned char *)malloc(nn);
    if (!R->past || !R->pval || !R->nnum || !R->nden || !R->nrate || !R->nrec || !R->active)
        return fprintf(stderr, "error: out of memory\n"), 1;
    R->t_push = -HUGE_VAL;
    return 0;
}

/* Alg. 1 at time t: returns 1 on the trigger */
static int oracle_eval(run *R) {
    gk_err e;
    double gd = R->C.gdot_max, tau_l, tau_g, *xs[3];
    size_t I, nn = R->g.nnode;
    int p, n = R->P.n;
    if (!(gd > 0.0)) return 0;
    tau_l = R->o.cl / gd;
    tau_g = R->o.cg / gd;
    if (R->t - R->t_push >= tau_l / 256.0) {
        if (gk_hybrid_history_push(&R->hist, R->t, R->C.ep, &e))
            return fprintf(stderr, "error: %s\n", e.msg), -1;
        R->t_push = R->t;
    }
    gk_hybrid_history_at(&R->hist, R->t - tau_l, R->past);
    for (p = 0; p < n; ++p) {
        double a = R->C.ep[3 * p] - R->past[3 * p], b = R->C.ep[3 * p + 1] - R->past[3 * p + 1],
               c = R->C.ep[3 * p + 2] - R->past[3 * p + 2];
        R->pval[2 * p] = R->C.rate[p];
        R->pval[2 * p + 1] = sqrt(a * a + b * b + 2.0 * c * c);
    }
    xs[0] = R->P.x[0];
    xs[1] = R->P.x[1];
    xs[2] = NULL;
    if (gk_hybrid_rasterize(&R->g, &R->per, R->md.basis, R->P.lp[0], n, (const double *const *)xs, R->P.m,
                            R->pval, 2, NULL, R->nnum, R->nden, &e))
        return fprintf(stderr, "error: oracle: %s\n", e.msg), -1;
    gk_hybrid_bc_mask(&R->g, R->bcmask);
    for (I = 0; I < nn; ++I) {
        R->active[I] = R->nden[I] > 0.0 && !R->bcmask[I];
        R->nrate[I] = R->nden[I] > 0.0 ? R->nnum[I] / R->nden[I] : 0.0;
        R->nrec[I] = R->nden[I] > 0.0 ? R->nnum[nn + I] / R->nden[I] : 0.0;
    }
    return gk_hybrid_oracle_step(&R->orc, &R->g, &R->per, R->nrate, R->nrec, R->active, R->t, tau_g);
}

#endif /* HYBRID_MODEL_H */
