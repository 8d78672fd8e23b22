/* dem_step_part.c - one benchmark case, compiled once per precision (see
 * Makefile: -DGK_REAL_FLOAT for the float copy). Every grainkit function is
 * static here (GK_STATIC), so both copies live in one program. */
#define _POSIX_C_SOURCE 200809L
#define GK_STATIC
#define GK_IMPLEMENTATION
/* --phases: gk_dem.h's timing hook, a flag test per mark while it is off */
static int bench_ph_on;
static void bench_phase(int phase, int mark);
#define GK_DEM_PHASE(phase, mark) (bench_ph_on ? bench_phase(phase, mark) : (void)0)
#include "gk_homog.h"
#include "gk_io.h"
#include "dem_step.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* per thread (64 bytes): the start of its open chunk and its busy time, per phase */
static struct { double t0[BENCH_PHASES], busy[BENCH_PHASES]; } bench_ph_thread[BENCH_PHASE_THREADS];
static double bench_ph_enter[BENCH_PHASES], bench_ph_wall[BENCH_PHASES];
static int bench_ph_chunks[BENCH_PHASES];

static void bench_phase(int phase, int mark) {
    double t = gk_wtime();
    int th = 0;
#ifdef _OPENMP
    th = omp_get_thread_num();
#endif
    if (phase < 0 || phase >= BENCH_PHASES || th >= BENCH_PHASE_THREADS) return;
    if (mark == 0) bench_ph_enter[phase] = t;
    if (mark == 1) bench_ph_wall[phase] += t - bench_ph_enter[phase];
    if (mark == 2) bench_ph_thread[th].t0[phase] = t;
    if (mark == 3) {
        bench_ph_thread[th].busy[phase] += t - bench_ph_thread[th].t0[phase];
        if (th == 0) bench_ph_chunks[phase] = 1;
    }
}

#ifdef GK_REAL_FLOAT
#define BENCH_RUN bench_run_float
#define BENCH_PATH bench_path_float
#else
#define BENCH_RUN bench_run_double
#define BENCH_PATH bench_path_double
#endif

int BENCH_PATH(int nincr, double *p, double *q) {
    gk_packing pk;
    gk_err e;
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    double dH[9] = {0, 1e-3, 0, 0, 0, 0, 0, 0, 0}, s[9];
    int k;
    if (gk_packing_read("examples/data/rve400.txt", &pk, NULL, &e)) return 1;
    if (gk_rve_create(&rve, &def, &pk)) return 1;
    gk_packing_free(&pk);
    for (k = 0; k < nincr; ++k) {
        if (gk_rve_deform(&rve, dH, 100)) return 1;
        gk_rve_stress(&rve, s);
        p[k] = gk_stress_p(s, 2);
        q[k] = gk_stress_q(s, 2);
    }
    gk_rve_destroy(&rve);
    return 0;
}

/* tile a periodic packing nx x ny x nz times (still periodic and dense) */
static int tile(const gk_packing *in, int nx, int ny, int nz, gk_packing *out, gk_err *e) {
    int a, b, c, p, q = 0, n = in->n * nx * ny * nz;
    if (gk_packing_init(out, in->dim, n, NULL, e)) return 1;
    gk_m3_identity(out->h);
    out->h[0] = in->h[0] * nx;
    out->h[4] = in->h[4] * ny;
    if (in->dim == 3) out->h[8] = in->h[8] * nz;
    for (c = 0; c < nz; ++c)
        for (b = 0; b < ny; ++b)
            for (a = 0; a < nx; ++a)
                for (p = 0; p < in->n; ++p) {
                    out->x[q] = in->x[p] + a * in->h[0];
                    out->y[q] = in->y[p] + b * in->h[4];
                    out->z[q] = in->dim == 3 ? in->z[p] + c * in->h[8] : 0.0;
                    out->r[q] = in->r[p];
                    ++q;
                }
    return 0;
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* median of n values (sorts them) */
static double median(double *v, int n) {
    qsort(v, (size_t)n, sizeof v[0], cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int BENCH_RUN(const bench_case *bc, bench_out *o) {
    gk_packing base, pk;
    gk_err e;
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    const char *path = bc->packing;
    int tx = 1, ty = 1, tz = 1, rve400 = !strcmp(bc->name, "rve400"), dim_want, r;
    /* repeats (batches of list builds with --lists) */
    int nrep = bc->repeats > 0 ? (bc->repeats > 64 ? 64 : bc->repeats) : bc->lists ? 5 : 3;
    double L[9], secs[64], rate;
    long steps = bc->steps, rebuilds0;
    memset(o, 0, sizeof *o);
    snprintf(o->simd, sizeof o->simd, "%s", bc->scalar ? "scalar" : GK_SIMD_NAME);
    snprintf(o->real, sizeof o->real, "%s", GK_REAL_NAME);
    if (rve400) {
        dim_want = 2;
        if (!path) path = "examples/data/rve400.txt";
        if (!steps) steps = 20000;
    } else if (!strcmp(bc->name, "2d_10k") || !strcmp(bc->name, "2d_100k")) {
        dim_want = 2;
        if (!path) {
            path = "bench/data/bench2d_10k.txt";
            if (!strcmp(bc->name, "2d_100k")) tx = 5, ty = 2;
        }
        if (!steps) steps = tx * ty > 1 ? 60 : 600;
    } else if (!strcmp(bc->name, "3d_1k") || !strcmp(bc->name, "3d_10k") || !strcmp(bc->name, "3d_100k")) {
        dim_want = 3;
        if (!path) {
            if (!strcmp(bc->name, "3d_1k"))
                path = "bench/data/bench3d_1k.txt";
            else
                path = "bench/data/bench3d_20k.txt";
            if (!strcmp(bc->name, "3d_100k")) tx = 5;
        }
        if (!steps) steps = !strcmp(bc->name, "3d_1k") ? 4000 : (tx > 1 ? 30 : 150);
    } else {
        snprintf(o->err, sizeof o->err, "unknown case '%s' (rve400, 2d_10k, 2d_100k, 3d_1k, 3d_10k, 3d_100k)",
                 bc->name);
        return 2;
    }
    if (gk_packing_read(path, &base, NULL, &e)) {
        snprintf(o->err, sizeof o->err, "%s", e.msg);
        return 1;
    }
    if (base.dim != dim_want) {
        snprintf(o->err, sizeof o->err, "case %s is %dD but %s is %dD", bc->name, dim_want, path, base.dim);
        gk_packing_free(&base);
        return 2;
    }
    if (tx * ty * tz > 1) {
        if (tile(&base, tx, ty, tz, &pk, &e)) {
            snprintf(o->err, sizeof o->err, "%s", e.msg);
            return 1;
        }
        gk_packing_free(&base);
    } else {
        pk = base;
    }
    if (bc->write_packing &&
        gk_packing_write(bc->write_packing, &pk, "grainkit bench_dem_step starting packing", &e)) {
        snprintf(o->err, sizeof o->err, "%s", e.msg);
        return 1;
    }
    if (rve400) { /* the Guo & Zhao 2014 RVE and material (YADE FEMxDEM prepareRVE.py) */
        def.mat.young = 6e8;
        def.mat.kt_ratio = 0.8;
        def.mat.friction = tan(0.5);
        def.damping = 0.1;
        def.thickness = 0.1;
        def.dt = bc->hertz ? 0 : 3.1602315723728926e-05; /* YADE's PWaveTimeStep for this packing */
    } else { /* the parameters the peer codes ran with (bench/data/README.md) */
        def.mat.kn = 2e5;
        def.mat.kt_ratio = 0.5;
        def.mat.friction = 0.5;
        def.mass2d = GK_MASS_SPHERE;
        def.thickness = 0;
        def.damping = 0.0;
        def.dt = 2.7e-6;
        def.skin = 5e-4;
    }
    if (bc->hertz) {
        /* Hertz-Mindlin + rolling resistance, with the modulus that gives the
         * linear law's k_n at the packing's overlaps (delta ~ 1e-5 m for the
         * RVE, 1e-6 m for the peers' packings): G = (1 - nu) k_n / sqrt(2 r* delta) */
        def.mat.law = GK_LAW_HERTZ;
        def.mat.kn = 0;
        def.mat.young = rve400 ? 1.7e10 : 5e9;
        def.mat.poisson = 0.3;
        def.mat.roll_beta = 1.0;
        def.mat.roll_eta = 0.1;
        if (!rve400) def.dt = 1.0e-6;
        /* Hertz stiffens as the shear raises the stress (ten-fold here): 0.2 of
         * the initial critical step keeps the RVE quasi-static */
        if (rve400) def.dt_factor = 0.2;
    }
    if (bc->physics) { /* optional physics switches, to measure what each costs */
        if (strstr(bc->physics, "norot")) def.flags |= GK_RVE_NO_ROTATION;
        if (strstr(bc->physics, "frictionless")) def.mat.friction = 0.0;
        if (strstr(bc->physics, "rolling")) {
            def.mat.roll_beta = 1.0;
            def.mat.roll_eta = 0.1;
        }
        if (strstr(bc->physics, "viscous")) def.mat.zeta_n = def.mat.zeta_t = 0.05;
        if (strstr(bc->physics, "cohesion")) def.mat.coh_n = def.mat.coh_t = 1.0;
    }
    def.threads = bc->threads;
    if (bc->scalar) def.flags |= GK_RVE_SCALAR;
    if (gk_rve_create(&rve, &def, &pk)) {
        snprintf(o->err, sizeof o->err, "%s", gk_rve_error(&rve));
        gk_packing_free(&pk);
        return 1;
    }
    gk_packing_free(&pk);
    if (bc->lists) { /* the RVE's outer-list build alone: bin + candidate pairs within its skin */
        gk_cells cl;
        gk_pairlist pl;
        const double *sp[3];
        int k, b;
        long reps = rve.n <= 1000 ? 2000 : rve.n <= 20000 ? 20 : 4, q;
        gk_cells_init(&cl, NULL);
        gk_pairlist_init(&pl, NULL);
        for (k = 0; k < 3; ++k) sp[k] = rve.s[k < rve.dim ? k : 0];
        for (b = 0; b <= nrep; ++b) { /* batch 0 warms up */
            double t0 = gk_wtime();
            for (q = 0; q < reps; ++q)
                if (gk_cells_bin(&cl, rve.dim, rve.cell.h, rve.n, sp, 2.0 * rve.rmax + rve.skin, &e) ||
                    gk_cells_pairs(&cl, rve.cell.h, sp, rve.r, rve.skin, &pl, &e)) {
                    snprintf(o->err, sizeof o->err, "%s", e.msg);
                    return 1;
                }
            if (b > 0) secs[b - 1] = (gk_wtime() - t0) / (double)reps;
        }
        o->dim = rve.dim;
        o->n = rve.n;
        o->list_build_us = 1e6 * median(secs, nrep);
        o->list_pairs = pl.n;
        gk_cells_free(&cl);
        gk_pairlist_free(&pl);
        gk_rve_destroy(&rve);
        return 0;
    }
    /* slow simple shear (Lees-Edwards): Guo & Zhao's 1e-5 strain per step for the
     * RVE, the peers' 1.5 /s for the large packings */
    gk_m3_zero(L);
    rate = rve400 ? 1e-5 / rve.dt : 1.5;
    L[1] = rate;
    gk_rve_set_velocity_gradient(&rve, L);
    if (gk_rve_step(&rve, steps / 10 + 10)) { /* warm-up */
        snprintf(o->err, sizeof o->err, "%s", gk_rve_error(&rve));
        return 1;
    }
    rebuilds0 = rve.rebuilds;
    if (bc->phases) {
        memset(bench_ph_thread, 0, sizeof bench_ph_thread);
        memset(bench_ph_wall, 0, sizeof bench_ph_wall);
        memset(bench_ph_chunks, 0, sizeof bench_ph_chunks);
        bench_ph_on = 1;
    }
    for (r = 0; r < nrep; ++r) {
        double t0 = gk_wtime();
        if (gk_rve_step(&rve, steps)) {
            bench_ph_on = 0;
            snprintf(o->err, sizeof o->err, "%s", gk_rve_error(&rve));
            return 1;
        }
        secs[r] = gk_wtime() - t0;
    }
    bench_ph_on = 0;
    o->rebuilds = rve.rebuilds - rebuilds0;
    if (bc->phases) {
        double total = 0.0, per = 1e3 / ((double)steps * nrep);
        int ph, t;
        for (r = 0; r < nrep; ++r) total += secs[r];
        o->step_ms = total * per;
        for (ph = 0; ph < BENCH_PHASES; ++ph) {
            o->phase_ms[ph] = bench_ph_wall[ph] * per;
            o->phase_threaded[ph] = bench_ph_chunks[ph];
            for (t = 0; t < BENCH_PHASE_THREADS; ++t)
                o->phase_busy_ms[ph][t] = bench_ph_thread[t].busy[ph] * per;
        }
    }
    o->dim = rve.dim;
    o->n = rve.n;
    o->steps = steps;
    o->nrep = nrep;
    o->seconds_median = median(secs, nrep); /* sorts secs */
    o->seconds_min = secs[0];
    o->particle_steps_per_s = (double)rve.n * steps / o->seconds_median;
    o->contacts_per_particle = (double)rve.ncontacts / rve.n;
    o->pairs_per_particle = (double)rve.pl.n / rve.n;
    o->contact_steps_per_s = (double)rve.ncontacts * steps / o->seconds_median;
    gk_rve_stress(&rve, o->sigma);
    gk_rve_destroy(&rve);
    return 0;
}
