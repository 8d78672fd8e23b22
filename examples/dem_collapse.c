/* dem_collapse.c - the 2D granular column collapse in plain DEM: a column of
 * disks d_0 wide and H_0 = a d_0 high, held by a gate on its right against
 * a smooth symmetry wall on its left, stands on a rough floor (a row of
 * fixed disks); the gate is withdrawn at t = 0 and the column spreads under
 * gravity. The single-scale reference of examples/mpmdem_collapse.c (same
 * column, symmetry plane and base), and the experiments' scaling of the
 * run-out d* = (d_f - d_0) / d_0 (Lube, Huppert, Sparks & Freundt 2005;
 * Lajeunesse, Monnier & Homsy 2005: for a < 3, d* ~ 1.2 a to 1.6 a).
 *
 *   build/dem_collapse                         # a = 1, 24 disks across, ~700 disks
 *   build/dem_collapse --a 2 --diameters 40    # a taller, finer column
 *
 * Preparation. Disks with radii uniform in [0.6, 1] r_max (r_max from
 * --diameters: mean diameter = d_0 / diameters) are placed on a square
 * lattice in [0, d_0] above the floor (twice as high as the column will
 * be) and settle under gravity with local
 * damping 0.3 until their kinetic energy is below 1e-6 of their potential
 * energy; those whose centre lies above H_0 are then removed (so the column
 * is H_0 high), the rest settle again, and local damping is switched off
 * for the collapse (the contact dashpots, --restitution, dissipate).
 *
 * Model (gk_scene.h): linear contacts E r* (--young), k_t / k_n 0.8,
 * Coulomb --mu, optional rolling resistance (--roll-beta, --roll-eta),
 * normal dashpot for --restitution, density 2650, disks of thickness 0.1 m
 * (gk_dem.h GK_MASS_CYLINDER); floor: one row of fixed disks of the mean
 * radius, touching; left: a smooth plane (the symmetry plane); the gate: a
 * smooth segment at x = d_0 from the floor disks' tops up, pulled away at
 * 20 m/s at t = 0. The domain runs to
 * (2 + 2.5 a) d_0; disks thrown beyond it are deleted and counted (lost).
 * dt = 0.2 x the critical step (Guo & Zhao 2014 eq 19).
 *
 * Measures (a CSV row every --every s): the front d_f = the furthest edge
 * x + r of the deposit, scanned from the wall along x and stopped at the
 * first gap wider than one mean diameter (flyers and scattered disks do
 * not count); d* = (d_f - d_0) / d_0; the height of the deposit at the
 * wall; energies over E_p0 (the potential energy of the released column
 * above the floor): E_k, E_p, E_d = E_p0 - E_p - E_k, and the dissipation
 * the scene's books keep (friction, dashpots) with their balance. At rest
 * when E_k < --rest-frac E_p0 after the peak of E_k; the run stops
 * --rest-hold s later (or at --t-end).
 *
 * Outputs in --out DIR: collapse.csv, collapse_front.svg,
 * collapse_energy.svg, particles_NNN.svg/.vtk and walls_NNN.vtk at
 * release, at --snapshots times and at the end; a RESULT line.
 */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_io.h"
#include "gk_scene.h"
#include "dem_scene.h"
#include "cli.h"

#define DC_MAX_SNAP 16

typedef struct dc_opts {
    double a, width, diameters, mu, roll_beta, roll_eta, restitution, young, gravity, t_end, every, rest_frac,
        rest_hold;
    int threads, quiet, nsnap;
    unsigned long seed;
    double snap[DC_MAX_SNAP];
    const char *out;
} dc_opts;

typedef struct dc_row {
    double t, front, height, ek, ep, ed, friction, viscous, balance;
} dc_row;

static void usage(FILE *fp) {
    fprintf(
        fp,
        "dem_collapse - 2D granular column collapse in DEM (gk_scene.h): a column d0 wide and a d0 high\n"
        "on a rough floor (fixed disks), a smooth symmetry wall on its left, the gate on its right pulled\n"
        "away at t = 0; run-out d* = (d_f - d0)/d0 against the experiments (Lube et al. 2005,\n"
        "Lajeunesse et al. 2005: d* ~ 1.2 a to 1.6 a for a < 3) and examples/mpmdem_collapse.c.\n\n"
        "usage: dem_collapse [options]\n"
        "  --a A                  aspect ratio H0/d0 (default 1)\n"
        "  --width D0             column width [m] (default 1, as mpmdem_collapse)\n"
        "  --diameters N          mean disk diameters across the column (default 24)\n"
        "  --mu M                 Coulomb friction of the disks and the floor disks (default 0.5)\n"
        "  --roll-beta B --roll-eta E   rolling resistance (default 0 0: none)\n"
        "  --restitution E        normal restitution of the contact dashpots (default 0.5)\n"
        "  --young E              contact modulus, k_n = E r* [Pa] (default 6e8, Guo & Zhao 2014, Liang & "
        "Zhao 2019)\n"
        "  --gravity G            [m/s^2] (default 9.81)\n"
        "  --t-end T              simulated time after release [s] (default 4)\n"
        "  --every DT             time between CSV rows [s] (default 0.01)\n"
        "  --snapshots T1,T2,...  picture times [s] (default 0.2,0.5,1)\n"
        "  --rest-frac F          at rest when E_k < F E_p0 after its peak (default 5e-3)\n"
        "  --rest-hold T          stop T s after coming to rest (default 0.05)\n"
        "  --seed S               radii and lattice jitter (default 1)\n"
        "  --threads T            threads of the pair forces (default 1; results do not depend on it)\n"
        "  --out DIR              output directory (default build/dem_collapse)\n"
        "  --quiet                no progress lines\n"
        "  --help                 this text\n\n"
        "ends with: RESULT a=... dstar=... dstar_lube=1.2a dstar_lajeunesse_hi=1.6a height_over_H0=...\n"
        "           Ek_peak_over_Ep0=... t_Ek_peak=... Ed_final_over_Ep0=... t_rest=... (-1: not at rest)\n"
        "           energy_balance=... (of E_p0) n=... lost=... steps=... dt=... seconds=...\n"
        "exit status: 0 done, 1 setup, simulation or output failed (message), 2 bad arguments\n");
}

static int parse(int argc, char **argv, dc_opts *o) {
    const char *snaps = "0.2,0.5,1";
    int help = 0, r;
    const cli_opt opts[] = {
        {"--out", CLI_STR, &o->out, 0, 0, NULL, NULL, 0},
        {"--snapshots", CLI_STR, &snaps, 0, 0, NULL, NULL, 0},
        {"--quiet", CLI_FLAG, &o->quiet, 0, 0, NULL, NULL, 0},
        {"--a", CLI_REAL, &o->a, 0.2, 10, "an aspect ratio in [0.2, 10]", NULL, 0},
        {"--width", CLI_REAL, &o->width, 0, HUGE_VAL, "a positive length", NULL, CLI_LO_OPEN | CLI_HI_OPEN},
        {"--diameters", CLI_REAL, &o->diameters, 4, 400, "a number of diameters in [4, 400]", NULL, 0},
        {"--mu", CLI_REAL, &o->mu, 0, HUGE_VAL, "a friction coefficient >= 0", NULL, CLI_HI_OPEN},
        {"--roll-beta", CLI_REAL, &o->roll_beta, 0, HUGE_VAL, "a value >= 0", NULL, CLI_HI_OPEN},
        {"--roll-eta", CLI_REAL, &o->roll_eta, 0, HUGE_VAL, "a value >= 0", NULL, CLI_HI_OPEN},
        {"--restitution", CLI_REAL, &o->restitution, 0, 1, "a value in (0, 1]", NULL, CLI_LO_OPEN},
        {"--young", CLI_REAL, &o->young, 0, HUGE_VAL, "a positive modulus", NULL, CLI_LO_OPEN | CLI_HI_OPEN},
        {"--gravity", CLI_REAL, &o->gravity, 0, HUGE_VAL, "a positive value", NULL,
         CLI_LO_OPEN | CLI_HI_OPEN},
        {"--t-end", CLI_REAL, &o->t_end, 0, HUGE_VAL, "a positive time", NULL, CLI_LO_OPEN | CLI_HI_OPEN},
        {"--every", CLI_REAL, &o->every, 0, HUGE_VAL, "a positive time", NULL, CLI_LO_OPEN | CLI_HI_OPEN},
        {"--rest-frac", CLI_REAL, &o->rest_frac, 0, HUGE_VAL, "a value >= 0", NULL, CLI_HI_OPEN},
        {"--rest-hold", CLI_REAL, &o->rest_hold, 0, HUGE_VAL, "a time >= 0", NULL, CLI_HI_OPEN},
        {"--seed", CLI_ULONG, &o->seed, 0, 0, NULL, NULL, 0},
        {"--threads", CLI_INT, &o->threads, 1, 256, NULL, NULL, 0},
        {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    const cli_opt *const tables[] = {opts, NULL};
    o->a = 1.0, o->width = 1.0, o->diameters = 24, o->mu = 0.5, o->roll_beta = 0.0, o->roll_eta = 0.0;
    o->restitution = 0.5, o->young = 6e8, o->gravity = 9.81, o->t_end = 4.0, o->every = 0.01;
    o->rest_frac = 5e-3, o->rest_hold = 0.05, o->threads = 1, o->quiet = 0, o->seed = 1;
    o->out = "build/dem_collapse";
    if ((r = cli_parse("dem_collapse", argc, argv, tables, &help)) != 0) return r;
    if (help) return usage(stdout), -1;
    if ((o->nsnap = dsc_list(snaps, o->snap, DC_MAX_SNAP, 0)) < 0)
        return fprintf(stderr,
                       "dem_collapse: --snapshots %s: need up to %d increasing times >= 0, comma-separated\n",
                       snaps, DC_MAX_SNAP),
               2;
    return 0;
}

/* the front: disks sorted by x, scanned from the wall while the gaps are
 * below one mean diameter; returns the furthest edge reached */
static double front_of(const gk_scene *sc, double gap, double *xs, double *rs, int *idx) {
    int n = sc->rve.n, m = 0, p, k;
    double f = 0.0;
    for (p = 0; p < n; ++p) {
        double x[3];
        if (sc->flags[p] & GK_PARTICLE_PRESCRIBED) continue; /* the floor */
        gk_scene_position(sc, p, x);
        xs[m] = x[0];
        rs[m] = (double)sc->rve.r[p];
        idx[m] = m;
        ++m;
    }
    /* insertion sort by x (n ~ 1e3, once per row) */
    for (p = 1; p < m; ++p) {
        int v = idx[p];
        k = p - 1;
        while (k >= 0 && xs[idx[k]] > xs[v]) {
            idx[k + 1] = idx[k];
            --k;
        }
        idx[k + 1] = v;
    }
    for (p = 0; p < m; ++p) {
        double lo = xs[idx[p]] - rs[idx[p]];
        if (p > 0 && lo - f > gap) break;
        if (xs[idx[p]] + rs[idx[p]] > f) f = xs[idx[p]] + rs[idx[p]];
    }
    return f;
}

/* potential energy above the floor top and the deposit's height at the wall */
static void measure(const gk_scene *sc, double g, double y0, double dmean, double *ep, double *height) {
    int p;
    *ep = 0.0;
    *height = 0.0;
    for (p = 0; p < sc->rve.n; ++p) {
        double x[3];
        if (sc->flags[p] & GK_PARTICLE_PRESCRIBED) continue;
        gk_scene_position(sc, p, x);
        *ep += sc->mass[p] * g * (x[1] - y0);
        if (x[0] < dmean && x[1] + (double)sc->rve.r[p] - y0 > *height)
            *height = x[1] + (double)sc->rve.r[p] - y0;
    }
}

/* the whole run: the options, the scene and what the collapse measures */
typedef struct dc_run {
    dc_opts o;
    gk_scene sc;
    gk_scene_def d;
    dc_row *rows;
    int nrows, caprows, created, igate;
    double rmax, rmean, rf, W, H, L, Ep0, ek_peak, t_ek_peak, t_rest, t0;
    double *xs, *rs;
    int *idx;
    long steps;
    FILE *csv;
} dc_run;

/* the scene's error, said; 1 */
static int dc_fail(dc_run *R) {
    fprintf(stderr, "dem_collapse: %s\n", gk_scene_error(&R->sc));
    return 1;
}

/* the scene: the column on a lattice, a floor of fixed disks, the symmetry plane and the gate; 0 or 1
 * (said) */
static int dc_setup(dc_run *R) {
    const dc_opts *o = &R->o;
    gk_scene_def *d = &R->d;
    gk_packing pk;
    gk_err err;
    gk_wall_def wall = gk_wall_def_default(), gate = gk_wall_def_default();
    int p;
    double rmax, rf, W = o->width, H = o->a * W, L;
    rmax = W / o->diameters / 1.6; /* mean radius 0.8 r_max */
    R->rmean = 0.8 * rmax;
    rf = R->rmean;
    L = (2.0 + 2.5 * o->a) * W;
    R->W = W, R->H = H, R->L = L, R->rmax = rmax, R->rf = rf;
    {
        /* a square lattice fills about half the area a settled column does */
        int nx = (int)floor(W / (2.2 * rmax)), ny = (int)ceil(2.0 * H / (2.2 * rmax)),
            nf = (int)floor(L / (2.0 * rf));
        gk_rng rng;
        int q = 0, a, b;
        d->dim = 2;
        d->lo[0] = 0.0;
        d->hi[0] = L;
        d->lo[1] = -rf;
        d->hi[1] = rf + (ny + 1) * 2.2 * rmax;
        d->gravity[1] = -o->gravity;
        d->lost = GK_LOST_DELETE;
        d->rve.mat.young = o->young;
        d->rve.mat.friction = o->mu;
        d->rve.mat.roll_beta = o->roll_beta;
        d->rve.mat.roll_eta = o->roll_eta;
        d->rve.mat.zeta_n = gk_restitution_to_zeta(o->restitution);
        d->rve.mat.density = 2650.0;
        d->rve.dt_factor = 0.2;
        d->rve.damping = 0.3; /* preparation only */
        d->rve.threads = o->threads;
        if (gk_packing_init(&pk, 2, nx * ny + nf, NULL, &err))
            return fprintf(stderr, "dem_collapse: %s\n", err.msg), 1;
        gk_rng_seed(&rng, (uint64_t)o->seed);
        for (a = 0; a < nf; ++a, ++q) { /* floor first: ids 0 .. nf-1 */
            pk.x[q] = rf * (2 * a + 1);
            pk.y[q] = 0.0;
            pk.r[q] = rf;
        }
        for (b = 0; b < ny; ++b)
            for (a = 0; a < nx; ++a, ++q) {
                pk.x[q] = 2.2 * rmax * (a + 0.5) + 0.1 * rmax * (2.0 * gk_rng_uniform(&rng) - 1.0);
                pk.y[q] = rf + 2.2 * rmax * (b + 0.5);
                pk.r[q] = rmax * (0.6 + 0.4 * gk_rng_uniform(&rng));
            }
        if (gk_scene_create(&R->sc, d, &pk)) {
            fprintf(stderr, "dem_collapse: %s\n", gk_scene_error(&R->sc));
            gk_packing_free(&pk);
            return 1;
        }
        R->created = 1;
        gk_packing_free(&pk);
        for (p = 0; p < R->sc.rve.n; ++p)
            if (R->sc.rve.id[p] < nf && gk_scene_prescribe(&R->sc, p, NULL, NULL)) return dc_fail(R);
        wall.mat = d->rve.mat;
        wall.mat.friction = 0.0; /* the symmetry plane is smooth */
        wall.mat.roll_beta = wall.mat.roll_eta = 0.0;
        wall.normal[0] = 1.0;
        gate = wall; /* a segment from the floor's top up: the floor disks run on beyond it */
        gate.kind = GK_WALL_SEGMENT;
        gate.point[0] = W;
        gate.point[1] = 1.01 * rf;
        gate.e1[1] = d->hi[1] - gate.point[1];
        gate.normal[0] = 0.0;
        if (gk_scene_add_wall(&R->sc, &wall, NULL) || gk_scene_add_wall(&R->sc, &gate, &R->igate))
            return dc_fail(R);
        if (!o->quiet)
            printf("dem_collapse: %d disks in the column (r %.4g-%.4g m), %d floor disks, dt %.3g s\n",
                   R->sc.rve.n - nf, 0.6 * rmax, rmax, nf, R->sc.rve.dt);
    }
    return 0;
}

/* preparation: settle, cut at H0, settle again; the column's height and E_p0; 0 or 1 (said) */
static int dc_prepare(dc_run *R) {
    const dc_opts *o = &R->o;
    gk_scene *sc = &R->sc;
    int round, p, k;
    for (round = 0; round < 2; ++round) {
        long guard = 0;
        for (;;) {
            double ep, h;
            if (gk_scene_step(sc, 2000)) return dc_fail(R);
            guard += 2000;
            measure(sc, o->gravity, 0.0, R->rmean, &ep, &h);
            if (gk_rve_kinetic_energy(&sc->rve) < 1e-6 * ep || guard > 2000000) break;
        }
        if (round == 0) {
            int32_t *cut = (int32_t *)malloc((size_t)sc->rve.n * sizeof *cut);
            int nc = 0;
            if (!cut) return fprintf(stderr, "dem_collapse: out of memory\n"), 1;
            for (p = 0; p < sc->rve.n; ++p) {
                double x[3];
                gk_scene_position(sc, p, x);
                if (!(sc->flags[p] & GK_PARTICLE_PRESCRIBED) && x[1] > R->H) cut[nc++] = sc->rve.id[p];
            }
            k = gk_scene_remove(sc, nc, cut);
            free(cut);
            if (k) return dc_fail(R);
        }
    }
    measure(sc, o->gravity, 0.0, R->rmean, &R->Ep0, &R->H);
    if (!o->quiet)
        printf("dem_collapse: column of %d disks, %.4g m high (a = %.3g), settled\n",
               sc->rve.n - (int)floor(R->L / (2.0 * R->rf)), R->H, R->H / R->W);
    return 0;
}

/* the release (no damping, the energy books open, the gate lifted) and the collapse: a row of
 * collapse.csv every --every, the pictures at release, at --snapshots and at the end; 0 or 1 (said) */
static int dc_collapse(dc_run *R) {
    const dc_opts *o = &R->o;
    gk_scene *sc = &R->sc;
    double W = R->W, t = 0.0, next = 0.0;
    int isnap = 0, at_rest = 0;
    char path[1200];
    if (gk_rve_set_damping(&sc->rve, 0.0, GK_DAMP_COMPONENT) || gk_scene_energy_track(sc, 1))
        return dc_fail(R);
    sc->walls[R->igate].def.velocity[0] = 20.0;
    R->xs = (double *)malloc((size_t)sc->rve.n * sizeof *R->xs);
    R->rs = (double *)malloc((size_t)sc->rve.n * sizeof *R->rs);
    R->idx = (int *)malloc((size_t)sc->rve.n * sizeof *R->idx);
    snprintf(path, sizeof path, "%s/collapse.csv", o->out);
    R->csv = fopen(path, "w");
    if (!R->xs || !R->rs || !R->idx || !R->csv)
        return fprintf(stderr, "dem_collapse: cannot write %s (or out of memory)\n", path), 1;
    fprintf(R->csv,
            "time,front,dstar,height,Ek_over_Ep0,Ep_over_Ep0,Ed_over_Ep0,friction_over_Ep0,viscous_over_Ep0,"
            "balance_over_Ep0,n,lost\n");
    if (dsc_pictures("dem_collapse", sc, o->out, "000", "column at release")) return 1;
    for (;;) {
        double ep, h, ek = gk_rve_kinetic_energy(&sc->rve),
                      f = front_of(sc, 2.0 * R->rmean, R->xs, R->rs, R->idx);
        gk_energy en;
        dc_row r;
        measure(sc, o->gravity, 0.0, R->rmean, &ep, &h);
        gk_scene_energy(sc, &en);
        r.t = t, r.front = f, r.height = h, r.ek = ek / R->Ep0, r.ep = ep / R->Ep0,
        r.ed = (R->Ep0 - ep - ek) / R->Ep0;
        r.friction = en.friction / R->Ep0, r.viscous = en.viscous / R->Ep0, r.balance = en.balance / R->Ep0;
        if (R->nrows == R->caprows) {
            dc_row *nr =
                (dc_row *)realloc(R->rows, (size_t)(R->caprows ? 2 * R->caprows : 256) * sizeof *R->rows);
            if (!nr) return fprintf(stderr, "dem_collapse: out of memory\n"), 1;
            R->rows = nr;
            R->caprows = R->caprows ? 2 * R->caprows : 256;
        }
        R->rows[R->nrows++] = r;
        fprintf(R->csv, "%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.3g,%d,%ld\n", t, f, (f - W) / W, h,
                r.ek, r.ep, r.ed, r.friction, r.viscous, r.balance, sc->rve.n, sc->lost);
        if (r.ek > R->ek_peak) R->ek_peak = r.ek, R->t_ek_peak = t;
        if (!at_rest && t > R->t_ek_peak && R->ek_peak > 0 && r.ek < o->rest_frac) at_rest = 1, R->t_rest = t;
        if (!o->quiet && R->nrows % 20 == 1)
            printf("t %.3f s  d* %.3f  height %.3f H0  E_k %.4f  E_d %.4f E_p0  (books %.3g)\n", t,
                   (f - W) / W, h / R->H, r.ek, r.ed, r.balance);
        if (isnap < o->nsnap && t >= o->snap[isnap] - 1e-12) {
            char tag[32], title[64];
            snprintf(tag, sizeof tag, "%03d", isnap + 1);
            snprintf(title, sizeof title, "column collapse, t = %.2f s", t);
            if (dsc_pictures("dem_collapse", sc, o->out, tag, title)) return 1;
            ++isnap;
        }
        if (t >= o->t_end - 1e-12 || (at_rest && t >= R->t_rest + o->rest_hold)) break;
        next += o->every;
        {
            long n = (long)ceil((next - t) / sc->rve.dt - 1e-9);
            if (n < 1) n = 1;
            if (gk_scene_step(sc, n)) return dc_fail(R);
            R->steps += n;
            t += n * sc->rve.dt;
        }
        if (sc->walls[R->igate].pos[0] > R->L + W) sc->walls[R->igate].def.velocity[0] = 0.0; /* far enough */
    }
    if (fclose(R->csv)) {
        R->csv = NULL;
        return fprintf(stderr, "dem_collapse: error writing %s/collapse.csv\n", o->out), 1;
    }
    R->csv = NULL;
    return dsc_pictures("dem_collapse", sc, o->out, "end", "column collapse: deposit") ? 1 : 0;
}

/* collapse_front.svg, collapse_energy.svg and the RESULT line; 0 or non-zero (said) */
static int dc_report(dc_run *R) {
    const dc_opts *o = &R->o;
    const dc_row *rows = R->rows;
    double W = R->W, H = R->H;
    int k, nrows = R->nrows, status = 0;
    char path[1200];
    {
        double *x = (double *)malloc((size_t)nrows * sizeof *x), *y[4] = {NULL, NULL, NULL, NULL};
        const char *lab[4];
        double ref[4];
        const char *rl[4];
        for (k = 0; k < 4; ++k) y[k] = (double *)malloc((size_t)nrows * sizeof(double));
        if (!x || !y[0] || !y[1] || !y[2] || !y[3]) status = 1;
        for (k = 0; !status && k < nrows; ++k) {
            x[k] = rows[k].t;
            y[0][k] = (rows[k].front - W) / W;
        }
        if (!status) {
            lab[0] = "DEM: d* = (d_f - d0)/d0";
            lab[1] = lab[2] = lab[3] = NULL;
            ref[0] = 1.2 * o->a, rl[0] = "Lube et al. 2005: 1.2 a";
            ref[1] = 1.6 * o->a, rl[1] = "1.6 a";
            ref[2] = 1.62, rl[2] = "mpmdem_collapse (a = 1): 1.62";
            snprintf(path, sizeof path, "%s/collapse_front.svg", o->out);
            {
                const double *yy[4];
                yy[0] = y[0], yy[1] = yy[2] = yy[3] = NULL;
                status = dsc_plot("dem_collapse", path, "DEM column collapse: run-out",
                                  "time after release [s]", "d* = (d_f - d0) / d0", x, nrows, yy, lab,
                                  fabs(o->a - 1.0) < 1e-9 ? 3 : 2, ref, rl);
            }
        }
        for (k = 0; !status && k < nrows; ++k) {
            y[0][k] = rows[k].ep, y[1][k] = rows[k].ek, y[2][k] = rows[k].ed,
            y[3][k] = rows[k].friction + rows[k].viscous;
        }
        if (!status) {
            const double *yy[4];
            lab[0] = "E_p", lab[1] = "E_k", lab[2] = "E_d = E_p0 - E_p - E_k", lab[3] = "dissipation booked";
            for (k = 0; k < 4; ++k) yy[k] = y[k];
            ref[0] = 1.0 - 0.74 / (2.0 * o->a), rl[0] = "Lajeunesse et al.: E_d = 1 - 0.74/(2a)";
            snprintf(path, sizeof path, "%s/collapse_energy.svg", o->out);
            status = dsc_plot("dem_collapse", path, "DEM column collapse: energies / E_p0",
                              "time after release [s]", "energy / E_p0", x, nrows, yy, lab, 1, ref, rl);
        } else {
            fprintf(stderr, "dem_collapse: out of memory for the plots\n");
        }
        free(x);
        for (k = 0; k < 4; ++k) free(y[k]);
        if (status) return status;
    }
    {
        const dc_row *e = &rows[nrows - 1];
        printf("RESULT a=%.4g dstar=%.4g dstar_lube=%.4g dstar_lajeunesse_hi=%.4g height_over_H0=%.4g "
               "Ek_peak_over_Ep0=%.4g t_Ek_peak=%.4g Ed_final_over_Ep0=%.4g t_rest=%.4g energy_balance=%.3g "
               "n=%d "
               "lost=%ld steps=%ld dt=%.4g seconds=%.2f\n",
               H / W, (e->front - W) / W, 1.2 * H / W, 1.6 * H / W, e->height / H, R->ek_peak, R->t_ek_peak,
               e->ed, R->t_rest, e->balance, R->sc.rve.n, R->sc.lost, R->steps, R->sc.rve.dt,
               gk_wtime() - R->t0);
    }
    return 0;
}

int main(int argc, char **argv) {
    static dc_run run; /* zeroed: nothing created, no rows, no file */
    dc_run *R = &run;
    int k, status;
    R->t0 = gk_wtime();
    R->d = gk_scene_def_default();
    R->t_rest = -1.0;
    k = parse(argc, argv, &R->o);
    if (k) return k < 0 ? 0 : k;
    if (dsc_mkdir("dem_collapse", R->o.out)) return 1;
    status = dc_setup(R);
    if (!status) status = dc_prepare(R);
    if (!status) status = dc_collapse(R);
    if (!status) status = dc_report(R);
    if (R->csv) fclose(R->csv);
    free(R->rows);
    free(R->xs);
    free(R->rs);
    free(R->idx);
    if (R->created) gk_scene_destroy(&R->sc);
    return status;
}
