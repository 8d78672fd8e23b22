/* hybrid_setup.h - the set-up of the hybrid continuum-grain driver (examples/hybrid.c; examples, not
 * library): the packing (generated and consolidated, or read), the run's state (struct run) and the
 * specimen's geometry: top platen, membranes, the bin and intruder, extent per row, band window. The
 * tests, modes, material and options are in hybrid_opts.h.
 */
#ifndef HYBRID_SETUP_H
#define HYBRID_SETUP_H

#include "hybrid_opts.h"
#include <sys/stat.h>

/* ------------------------------------------------------------------ packing */
static int make_dir(const char *d) {
    char buf[1024];
    size_t k, n = strlen(d);
    struct stat st;
    if (n + 1 > sizeof buf) return fprintf(stderr, "error: --out %s: path too long\n", d), 1;
    memcpy(buf, d, n + 1);
    for (k = 1; k <= n; ++k)
        if (buf[k] == '/' || buf[k] == '\0') {
            char c = buf[k];
            buf[k] = '\0';
            if (mkdir(buf, 0755) && errno != EEXIST)
                return fprintf(stderr, "error: cannot create %s\n", buf), 1;
            buf[k] = c;
        }
    if (stat(d, &st) || !S_ISDIR(st.st_mode))
        return fprintf(stderr, "error: --out %s: not a directory\n", d), 1;
    return 0;
}

/* the servo of gk_rve at fixed shape (the cell stays a rectangle, so the
 * specimen stays periodic) to the isotropic stress p with friction mu:
 * until every sigma_kk is within 0.2 % and the unbalanced force ratio is
 * below 1e-3 for three checks in a row */
static int consolidate(gk_rve *rve, double p, double mu) {
    gk_servo sv;
    long st, calm = 0;
    int k, q;
    memset(&sv, 0, sizeof sv);
    for (k = 0; k < 2; ++k) {
        sv.mode[k] = GK_SERVO_STRESS;
        sv.target[k] = -p;
    }
    sv.max_rate = 1e-2 * sqrt(p / RHO_S) / DIAM; /* inertial number 1e-2 */
    sv.gain = 0.5;
    if (gk_rve_set_friction(rve, mu) || gk_rve_set_servo(rve, &sv))
        return fprintf(stderr, "error: consolidation: %s\n", gk_rve_error(rve)), 1;
    for (st = 0; st < 4000000; st += 1000) {
        double fs = 0.0, un, e0, e1;
        if (gk_rve_step(rve, 1000))
            return fprintf(stderr, "error: consolidation: %s\n", gk_rve_error(rve)), 1;
        for (q = 0; q < rve->n; ++q)
            fs += sqrt((double)rve->f[0][q] * rve->f[0][q] + (double)rve->f[1][q] * rve->f[1][q]);
        un = rve->fc_mean > 0.0 ? fs / rve->n / rve->fc_mean : 1.0;
        e0 = fabs(rve->stress[0] + p) / p;
        e1 = fabs(rve->stress[4] + p) / p;
        calm = (e0 < 2e-3 && e1 < 2e-3 && un < 1e-3) ? calm + 1 : 0;
        if (calm >= 3) break;
    }
    gk_rve_set_servo(rve, NULL);
    if (calm < 3) return fprintf(stderr, "error: consolidation to %g Pa (mu %g) did not settle\n", p, mu), 1;
    /* friction is switched on with zero tangential history */
    for (q = 0; rve->ft[0] && q < rve->pl.n; ++q) rve->ft[0][q] = 0;
    return 0;
}

/* the specimen: generated (or read), consolidated to the pressure with the paper's contact law */
static int make_packing(const opts *o, gk_packing *out, double *phi) {
    gk_packing pk;
    gk_err e;
    gk_rve rve;
    gk_rve_def d = gk_rve_def_default();
    double tr[41], tc[41], s[9];
    int k;
    if (o->packing) {
        if (gk_packing_read(o->packing, out, NULL, &e)) return fprintf(stderr, "error: %s\n", e.msg), 1;
        if (out->dim != 2) return fprintf(stderr, "error: %s is not a 2D packing\n", o->packing), 1;
    } else {
        gk_gen_def g;
        double amean = GK_PI * 0.25 * DIAM * DIAM * (1.0 + 0.08 * 0.08);
        for (k = 0; k < 41; ++k) { /* diameters normal (1 mm, 0.08 mm) cut at 2 sd, by number */
            double z = -2.0 + 4.0 * k / 40.0;
            tr[k] = 0.5 * (DIAM + 8e-5 * z);
            tc[k] = 0.5 * (1.0 + erf(z / sqrt(2.0)));
        }
        for (k = 40; k >= 0; --k) tc[k] = (tc[k] - tc[0]) / (tc[40] - tc[0]);
        tc[40] = 1.0;
        memset(&g, 0, sizeof g);
        g.dim = 2;
        g.n = o->grains > 0 ? (int)o->grains : (int)floor(0.85 * o->width * o->height / amean + 0.5);
        g.psd = GK_PSD_TABLE_NUMBER;
        g.ntable = 41;
        g.table_r = tr;
        g.table_cum = tc;
        g.aspect[0] = 1.0;
        g.aspect[1] = o->height / o->width;
        g.seed = o->seed;
        if (gk_packing_generate(&pk, &g, NULL, &e)) return fprintf(stderr, "error: packing: %s\n", e.msg), 1;
        d.mat = grain_material(0.2, 0.0); /* light damping while consolidating (see the header) */
        d.thickness = THICK;
        d.dt = DT;
        d.damping = 0.2;
        d.threads = o->threads;
        if (gk_rve_create(&rve, &d, &pk))
            return fprintf(stderr, "error: packing: %s\n", gk_rve_error(&rve)), 1;
        gk_packing_free(&pk);
        if (consolidate(&rve, o->pressure, 0.0) || consolidate(&rve, o->pressure, 0.5)) {
            gk_rve_destroy(&rve);
            return 1;
        }
        gk_rve_stress(&rve, s);
        if (!o->quiet)
            printf("packing: %d grains consolidated to %.4g, %.4g Pa in a %.4g x %.4g m cell\n", rve.n, -s[0],
                   -s[4], rve.cell.h[0], rve.cell.h[4]);
        if (gk_rve_to_packing(&rve, out, NULL, &e)) return fprintf(stderr, "error: %s\n", e.msg), 1;
        gk_rve_destroy(&rve);
    }
    *phi = 0.0;
    for (k = 0; k < out->n; ++k) *phi += GK_PI * out->r[k] * out->r[k];
    *phi /= out->h[0] * out->h[4];
    {
        char path[1100];
        snprintf(path, sizeof path, "%s/packing.txt", o->out);
        if (gk_packing_write(path, out, "hybrid.c specimen", &e))
            return fprintf(stderr, "error: cannot write %s\n", path), 1;
    }
    /* positions into [0, W) x [0, H) */
    for (k = 0; k < out->n; ++k) {
        out->x[k] -= out->h[0] * floor(out->x[k] / out->h[0]);
        out->y[k] -= out->h[4] * floor(out->y[k] / out->h[4]);
    }
    return 0;
}

/* ------------------------------------------------------------------ the run */
typedef struct run {
    opts o;
    double W, H, phi_pack, rho, M, c, t, strain, dt;
    long step;
    gk_packing pk; /* the specimen's reference packing, positions in [0, W) x [0, H) */
    /* grains */
    gk_scene sc;
    int have_sc, top_wall;
    unsigned char *role; /* by stable id: 0 free, 1 bottom layer, 2 top layer */
    int nrole;
    /* platen: top displacement and velocity */
    double plate_x, plate_y, plate_vy, y_plate0;
    double tau, sig_n; /* last measured, compression-positive [Pa] */
    /* indent: the intruder's depth [m], the grains' intruder (4 segment walls) and its start */
    double depth, y_intr0;
    int intr[4], nintr, bin_bottom;
    double qsum[2]; /* indent: sums of tau and sigma_n since the last CSV row (its mean is written) */
    long qn;
    /* continuum */
    int have_mpm;
    gk_mpm_grid g;
    gk_hybrid_periodic per;
    gk_mpm_points P;
    gk_hybrid_cont C;
    gk_mpm_def md;
    gk_mpm_body body;
    double h, dxp, dyp;
    double *side; /* per point: -1 left column, +1 right column, 0 (biaxial traction) */
    double *Fw;   /* per point: F at the window start (9) */
    unsigned char *bcmask;
    /* oracle */
    gk_hybrid_oracle orc;
    gk_hybrid_history hist;
    double *past, *pval, *nnum, *nden, *nrate, *nrec, t_push;
    unsigned char *active;
    int triggered;
    double strain_trigger;
    /* hybrid */
    int enriched;
    double strain_enrich, *dist, *xpre[2];
    unsigned char *coupled;
    double *wid, *cw;        /* --weigh-overlap: partition weight by stable id, by index (the scene's) */
    unsigned char *deep;     /* per node: in a stencil of a point carried into the discrete zone */
    int deep_n, deep_max;    /* those points, at the last coupling_mask and at most */
    int32_t *drop_ids;       /* scratch: grains to remove (coupling_mask, remove_escaped) */
    int cap_g, mask_n, lost; /* lost: loose grains removed (drop_loose) */
    double lost_mass;        /* their share of the grains' mass when removed, summed */
    double grain_scale;      /* the enrichment's grain mass factor */
    gk_hybrid_coupling cpl;
    /* measurements */
    double phi0_band, A0, peak_tau, win_c[2], win_e[2], win_a;
    double packing_tau; /* hybrid: the trained packing's mean shear stress; dem: --probe's [Pa] */
    int window_taken, nw, band_on_grains;
    double *Xw[2];
    int32_t *idw;
    FILE *csv;
    double t_start, next_out;
    /* cost counters */
    double sec_dem, sec_mpm, sec_cpl;
    long steps_dem, grain_steps, point_steps;
} run;

static double wtime(void) { return gk_wtime(); }

static gk_scene_def scene_def(const run *R) {
    gk_scene_def d = gk_scene_def_default();
    d.dim = 2;
    if (R->o.test == T_PLANAR) {
        d.periodic = 1u;
        d.lo[0] = 0.0;
        d.hi[0] = R->W;
    } else {
        d.lo[0] = -0.5 * R->W;
        d.hi[0] = 1.5 * R->W;
    }
    d.lo[1] = -0.5 * R->H;
    d.hi[1] = 1.5 * R->H;
    if (R->o.test == T_INDENT) d.gravity[1] = -GRAV;
    d.rve.mat = grain_material(zeta_paper(), 0.4);
    d.rve.thickness = THICK;
    d.rve.dt = DT;
    d.rve.damping = 0.0;
    d.rve.threads = R->o.threads;
    return d;
}

/* the grains' role by stable id, from their reference positions */
static int role_of(const run *R, double y) {
    if (R->o.test == T_INDENT) return 0; /* the bin's walls hold the bed */
    if (y < 1.5 * DIAM) return 1;
    if (y > R->H - 1.5 * DIAM) return 2;
    return 0;
}

/* The planar top platen under a constant normal stress: a rigid platen of
 * the specimen's mass M_p pressed by p W t, its vertical velocity from
 * M_p dv/dt = F - p W t - c v (F the specimen's push on it; c = 2 zeta
 * sqrt(k M_p), k = (K + G) W t / H, zeta = --platen-damping), the same
 * law for the grains and the continuum. A dilating specimen lifts it with
 * a force error c v (1-3 % of p W t at the dilation rates of these tests). */
static double platen_velocity(run *R, double F, double dt) {
    double A = R->W * THICK, Mp = R->rho * R->W * R->H * THICK, k = R->M * A / R->H;
    double c = 2.0 * R->o.platen_zeta * sqrt(k * Mp);
    R->plate_vy += dt * (F - R->o.pressure * A - c * R->plate_vy) / Mp;
    return R->plate_vy;
}

/* the platen speed at time t: a linear rise over --ramp wave transits (a
 * sudden start sends a stress wave rho c_s V through the specimen) */
static double platen_speed(const run *R, double t) {
    double tr = R->o.ramp * R->H / R->c;
    return t >= tr ? R->o.speed : R->o.speed * t / tr;
}

/* ---- indent: the bin and the intruder of the grains */
/* the bin: a rough bottom (the grains' friction) and smooth sides, planes at
 * y = 0, x = 0 and x = W (the continuum's: no-slip bottom, roller sides) */
static int add_bin_walls(run *R) {
    int k;
    for (k = 0; k < 3; ++k) {
        gk_wall_def w = gk_wall_def_default();
        w.kind = GK_WALL_PLANE;
        w.mat = grain_material(zeta_paper(), 0.4);
        if (k == 0)
            w.normal[1] = 1.0;
        else {
            w.point[0] = k == 1 ? 0.0 : R->W;
            w.normal[0] = k == 1 ? 1.0 : -1.0;
            w.mat.friction = 0.0;
        }
        if (gk_scene_add_wall(&R->sc, &w, k == 0 ? &R->bin_bottom : NULL))
            return fprintf(stderr, "error: %s\n", gk_scene_error(&R->sc)), 1;
    }
    return 0;
}

/* the intruder: a rigid B x 0.4 B rectangle of four segments (rough: the
 * grains' friction) centred on the bin, its bottom at y, moving at (0, -v) */
static int add_intruder(run *R, double y, double v) {
    double B = R->o.intruder, Hi = 0.4 * B, x0 = 0.5 * (R->W - B);
    double a[4][2] = {{x0, y}, {x0, y}, {x0 + B, y}, {x0, y + Hi}},
           e[4][2] = {{B, 0}, {0, Hi}, {0, Hi}, {B, 0}};
    int k;
    for (k = 0; k < 4; ++k) {
        gk_wall_def w = gk_wall_def_default();
        w.kind = GK_WALL_SEGMENT;
        w.point[0] = a[k][0];
        w.point[1] = a[k][1];
        w.e1[0] = e[k][0];
        w.e1[1] = e[k][1];
        w.normal[1] = -1.0;
        w.mat = grain_material(zeta_paper(), 0.4);
        w.drive = GK_DRIVE_VELOCITY;
        w.velocity[1] = -v;
        if (gk_scene_add_wall(&R->sc, &w, &R->intr[k]))
            return fprintf(stderr, "error: %s\n", gk_scene_error(&R->sc)), 1;
    }
    R->nintr = 4;
    return 0;
}

/* the grains' intruder moves down at v [m/s] from the next step on */
static void intruder_velocity(run *R, double v) {
    int k;
    for (k = 0; k < R->nintr; ++k) R->sc.walls[R->intr[k]].def.velocity[1] = -v;
}

/* the grains' push on the intruder [N] (x, y): the sum over its four walls */
static void intruder_force(const run *R, double f[2]) {
    int k;
    f[0] = f[1] = 0.0;
    for (k = 0; k < R->nintr; ++k) {
        f[0] += R->sc.walls[R->intr[k]].force[0];
        f[1] += R->sc.walls[R->intr[k]].force[1];
    }
}

/* ---- membranes on the grains at the specimen's sides (biaxial) */
/* On each side, the outermost free grain of every band of D50 along y whose
 * outer edge lies within 1.5 D50 of the side (left[row], right[row]
 * for rows of row_h; within 3 D50 in the 3 D50 below the top wall, so that
 * the chain reaches the wall where a discrete zone's top corner is set
 * back from the side: a chain ending below the wall let the grains between
 * its end and the wall be squeezed out along it), chained in height order
 * (the material on the chain's left: down the left side, up the right
 * side), split where a gap of 3 D50 opens; a chain end within 2 D50 of the
 * top wall is tied to it. With close_top (the hybrid's enrichment), where
 * the top member leaves more than 0.5 D50 between itself and the wall
 * (another grain of its band sits higher), the candidate nearest the wall
 * ends the chain too: a tied end slides along the wall, and on the
 * paper-size biaxial hybrid grains passed through such gaps and out. (The
 * all-grain run keeps its chains: no grain left its specimen, paper size
 * included.) */
static int add_membranes(run *R, const double *left, const double *right, int nrow, double row_h,
                         int close_top) {
    gk_scene *sc = &R->sc;
    int n = sc->rve.n, s, p, k, nb = (int)ceil(2.0 * R->H / DIAM) + 1, nsel;
    int32_t *ids = (int32_t *)malloc((size_t)n * sizeof(int32_t));
    int *best = (int *)malloc((size_t)nb * sizeof(int)), *ord = (int *)malloc((size_t)(nb + 1) * sizeof(int));
    double *bx = (double *)malloc((size_t)nb * sizeof(double)),
           *yy = (double *)malloc((size_t)(nb + 1) * sizeof(double));
    double ytop = R->top_wall >= 0 ? sc->walls[R->top_wall].pos[1] : HUGE_VAL;
    if (!ids || !best || !ord || !bx || !yy) {
        free(ids), free(best), free(ord), free(bx), free(yy);
        return fprintf(stderr, "error: out of memory\n"), 1;
    }
    for (s = -1; s <= 1; s += 2) {
        int hi = -1; /* the candidate nearest the top wall */
        double hiy = -HUGE_VAL;
        for (k = 0; k < nb; ++k) best[k] = -1;
        for (p = 0; p < n; ++p) {
            double x[3], r = (double)sc->rve.r[p], edge, tol;
            int row, band;
            if (sc->flags[p] & GK_PARTICLE_PRESCRIBED) continue;
            gk_scene_position(sc, p, x);
            row = (int)floor(x[1] / row_h);
            band = (int)floor(x[1] / DIAM);
            if (row < 0 || row >= nrow || band < 0 || band >= nb) continue;
            edge = s < 0 ? left[row] : right[row];
            if (!isfinite(edge)) continue;
            tol = ytop - x[1] < 3.0 * DIAM ? 3.0 * DIAM : 1.5 * DIAM;
            if (s < 0 ? x[0] - r < edge + tol : x[0] + r > edge - tol) {
                double out = s < 0 ? -(x[0] - r) : x[0] + r;
                if (x[1] + r > hiy) {
                    hi = p;
                    hiy = x[1] + r;
                }
                if (best[band] < 0 || out > bx[band]) {
                    best[band] = p;
                    bx[band] = out;
                }
            }
        }
        nsel = 0;
        for (k = 0; k < nb; ++k) {
            int kk = s < 0 ? nb - 1 - k : k; /* left: top to bottom; right: bottom to top */
            if (best[kk] >= 0) {
                double x[3];
                gk_scene_position(sc, best[kk], x);
                ord[nsel] = best[kk];
                yy[nsel++] = x[1];
            }
        }
        if (close_top && nsel > 0 && hi >= 0 && isfinite(ytop)) { /* a gap a grain could pass */
            int t = s < 0 ? 0 : nsel - 1, in = 0;
            double top = yy[t] + (double)sc->rve.r[ord[t]];
            for (k = 0; k < nsel; ++k) in |= ord[k] == hi;
            if (!in && hiy > top && ytop - top > 0.5 * DIAM) { /* closed by the nearest grain */
                double x[3];
                gk_scene_position(sc, hi, x);
                if (s < 0) {
                    memmove(ord + 1, ord, (size_t)nsel * sizeof(int));
                    memmove(yy + 1, yy, (size_t)nsel * sizeof(double));
                }
                ord[s < 0 ? 0 : nsel] = hi;
                yy[s < 0 ? 0 : nsel] = x[1];
                ++nsel;
            }
        }
        for (p = 0; p < nsel;) {
            int q = p + 1, m, a0 = -1, a1 = -1;
            while (q < nsel && fabs(yy[q] - yy[q - 1]) < 3.0 * DIAM) ++q;
            m = q - p;
            if (m >= 2) {
                for (k = 0; k < m; ++k) ids[k] = sc->rve.id[ord[p + k]];
                if (s < 0 && ytop - yy[p] < 2.0 * DIAM) a0 = R->top_wall;
                if (s > 0 && ytop - yy[q - 1] < 2.0 * DIAM) a1 = R->top_wall;
                if (gk_scene_add_membrane(sc, m, ids, R->o.pressure, 1e4, a0, a1, NULL)) {
                    fprintf(stderr, "error: membrane: %s\n", gk_scene_error(sc));
                    free(ids), free(best), free(ord), free(bx), free(yy);
                    return 1;
                }
            }
            p = q;
        }
    }
    free(ids);
    free(best);
    free(ord);
    free(bx);
    free(yy);
    return 0;
}

/* ---- biaxial: the grains' top wall */
/* a frictionless plane facing down at height y (R->top_wall), velocity-driven, at rest */
static int add_top_wall(run *R, double y) {
    gk_wall_def w = gk_wall_def_default();
    w.kind = GK_WALL_PLANE;
    w.point[1] = y;
    w.normal[1] = -1.0;
    w.mat = grain_material(zeta_paper(), 0.4);
    w.mat.friction = 0.0;
    w.drive = GK_DRIVE_VELOCITY;
    return gk_scene_add_wall(&R->sc, &w, &R->top_wall) != GK_OK;
}

/* the top wall's servo presses it on the grains until the stress over area is within 1 % of target
 * (after at least 10 x 500 steps, at most 200 x 500), then it stops (velocity drive, at rest); the
 * steps taken, -1 on a scene error (gk_scene_error); the stress reached in *s */
static long seat_top_wall(run *R, double target, double area, double *s) {
    gk_wall_def *d = &R->sc.walls[R->top_wall].def;
    int k;
    d->drive = GK_DRIVE_STRESS;
    d->target = target;
    d->area = area;
    d->gain = 0.05;
    d->max_speed = R->o.speed;
    for (k = 0; k < 200; ++k) {
        if (gk_scene_step(&R->sc, 500)) return -1;
        *s = R->sc.walls[R->top_wall].force[1] / area;
        if (k >= 10 && fabs(*s - target) < 0.01 * target) break;
    }
    d->drive = GK_DRIVE_VELOCITY;
    d->velocity[1] = 0.0;
    return 500L * (k < 200 ? k + 1 : k);
}

/* the material's extent per row (grains: x -+ r; points: x -+ half their size) */
static void extent_rows(const run *R, int nrow, double row_h, double *left, double *right) {
    int k, p;
    for (k = 0; k < nrow; ++k) {
        left[k] = HUGE_VAL;
        right[k] = -HUGE_VAL;
    }
    if (R->have_sc)
        for (p = 0; p < R->sc.rve.n; ++p) {
            double x[3], r = (double)R->sc.rve.r[p];
            gk_scene_position(&R->sc, p, x);
            k = (int)floor(x[1] / row_h);
            if (k < 0 || k >= nrow) continue;
            if (x[0] - r < left[k]) left[k] = x[0] - r;
            if (x[0] + r > right[k]) right[k] = x[0] + r;
        }
    if (R->have_mpm)
        for (p = 0; p < R->P.n; ++p) {
            double x = R->P.x[0][p], half = 0.5 * R->dxp * sqrt(R->P.vol[p] / R->P.vol0[p]);
            k = (int)floor(R->P.x[1][p] / row_h);
            if (k < 0 || k >= nrow) continue;
            if (x - half < left[k]) left[k] = x - half;
            if (x + half > right[k]) right[k] = x + half;
        }
}

static double specimen_height(const run *R) { return R->H + R->plate_y; }

/* rows for the specimen's extent: one MPM cell (two rows of points, a few grains) */
static int extent_nrow(const run *R) {
    int n = (int)floor(R->H / R->o.cell);
    return n > 1 ? n : 1;
}

/* biaxial: area from the material's extent per row */
static double specimen_area(const run *R) {
    int nrow = extent_nrow(R), k;
    double Hc = specimen_height(R), row_h = Hc / nrow, A = 0.0, *l, *r;
    l = (double *)malloc((size_t)nrow * sizeof(double));
    r = (double *)malloc((size_t)nrow * sizeof(double));
    if (!l || !r) {
        free(l);
        free(r);
        return NAN;
    }
    extent_rows(R, nrow, row_h, l, r);
    for (k = 0; k < nrow; ++k)
        if (r[k] > l[k]) A += (r[k] - l[k]) * row_h;
    free(l);
    free(r);
    return A;
}

/* overlap of [x - d/2, x + d/2] with [-b, b], as a fraction of d */
static double overlap1(double x, double d, double b) {
    double lo = x - 0.5 * d, hi = x + 0.5 * d, a = lo > -b ? lo : -b, c = hi < b ? hi : b;
    return c > a ? (c - a) / d : 0.0;
}

/* solid fraction inside the band window: grains by their disk area (an
 * overlap grain, which carries w of its mass, by w of it), points by
 * their solid area vol0 Phi0 (overlap points carry 1 - w of it); each
 * counted by its overlap with the window (grains as squares of their
 * area, points as their cell) */
static double band_solid_fraction(const run *R) {
    double S = 0.0, area, b = R->o.band_window, phi0 = R->o.phi_init > 0.0 ? R->o.phi_init : R->phi_pack;
    int p, planar = R->o.test == T_PLANAR;
    area = planar ? R->W * 2.0 * b : 2.0 * R->win_a * 2.0 * b;
#define WIN_ADD(x, y, d, a)                                                            \
    do {                                                                               \
        double u = ((x)-R->win_c[0]) * R->win_e[0] + ((y)-R->win_c[1]) * R->win_e[1];  \
        double w = -((x)-R->win_c[0]) * R->win_e[1] + ((y)-R->win_c[1]) * R->win_e[0]; \
        S += (a)*overlap1(w, (d), b) * (planar ? 1.0 : overlap1(u, (d), R->win_a));    \
    } while (0)
    if (R->have_sc)
        for (p = 0; p < R->sc.rve.n; ++p) {
            double x[3], r = (double)R->sc.rve.r[p], a = GK_PI * r * r;
            if (R->sc.flags[p] & GK_PARTICLE_PRESCRIBED) continue;
            if (R->enriched) a *= R->sc.mass[p] / (R->grain_scale * RHO_S * THICK * a); /* 1 or w */
            gk_scene_position(&R->sc, p, x);
            WIN_ADD(x[0], x[1], sqrt(GK_PI) * r, a);
        }
    if (R->have_mpm)
        for (p = 0; p < R->P.n; ++p)
            WIN_ADD(R->P.x[0][p], R->P.x[1][p], sqrt(R->P.vol[p]), R->P.vol0[p] * phi0);
#undef WIN_ADD
    return S / area;
}

#endif /* HYBRID_SETUP_H */
