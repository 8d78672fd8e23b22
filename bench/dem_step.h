/* dem_step.h - interface between bench/dem_step.c and bench/dem_step_part.c,
 * which is compiled twice (double and float grainkit, GK_STATIC) into one
 * program. Plain C types only. */
#ifndef BENCH_DEM_STEP_H
#define BENCH_DEM_STEP_H

typedef struct bench_case {
    const char *name;          /* rve400, 2d_10k, 2d_100k, 3d_1k, 3d_10k, 3d_100k */
    const char *packing;       /* NULL: the case's default packing                 */
    const char *write_packing; /* write the exact starting packing here            */
    int threads, hertz, scalar, repeats;
    const char *physics; /* comma list: norot, frictionless, rolling, viscous, cohesion */
    long steps;          /* timed steps per repeat; 0: case default          */
    int lists;           /* time the cell-list build instead of steps        */
    int phases;          /* time each phase of the step in each thread       */
} bench_case;

/* --phases: the step's phases (gk_dem.h's GK_DEM_PHASE hook) */
enum { BENCH_PHASES = 4, BENCH_PHASE_THREADS = 16 };

typedef struct bench_out {
    int dim, n;
    long steps;                  /* per repeat */
    int nrep;                    /* repeats */
    double particle_steps_per_s; /* median over repeats */
    double contact_steps_per_s;  /* median */
    double contacts_per_particle;
    double pairs_per_particle;
    double seconds_min, seconds_median;
    double list_build_us; /* lists: median time of one outer-list build [us] */
    int list_pairs;       /* lists: candidate pairs it found                 */
    double sigma[9];      /* final Love stress (tension +) */
    /* phases: mean milliseconds per step over the timed steps. wall: from the
     * stepping thread's entry into the phase to its exit; busy: inside the
     * chunks each thread ran (threaded loops only; 0 for a serial phase) */
    double step_ms, phase_ms[BENCH_PHASES], phase_busy_ms[BENCH_PHASES][BENCH_PHASE_THREADS];
    int phase_threaded[BENCH_PHASES]; /* the phase ran as chunks on threads */
    long rebuilds;                    /* list rebuilds in the timed steps */
    char simd[16], real[8], err[256];
} bench_out;

int bench_run_double(const bench_case *c, bench_out *o);
int bench_run_float(const bench_case *c, bench_out *o);

/* the Guo & Zhao 2014 RVE sheared along the rve_path loading (nincr increments of
 * dH01 = 1e-3 over 100 steps): compression-positive p and q after each */
int bench_path_double(int nincr, double *p, double *q);
int bench_path_float(int nincr, double *p, double *q);

#endif
