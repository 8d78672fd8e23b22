/* bench_scene_box - a 3D scene beyond the periodic cell, timed and measured
 * the same way in LAMMPS (bench/peers/run_box.sh): monodisperse spheres on a
 * jittered lattice fall under gravity into a box (fixed floor and side
 * walls), settle, and are then compressed by a lid moving down at constant
 * speed.
 *
 *   build/bench_scene_box [--nx 10] [--nz 20] [--pour S] [--compress S] [--threads T]
 *                         [--write-data FILE]   (the starting atoms as a LAMMPS data file)
 *
 * Law (both codes): linear normal spring kn = 1e4 N/m (constant), normal
 * dashpot of restitution 0.5 (g = 2 zeta sqrt(m* kn): LAMMPS pair granular
 * "damping mass_velocity" with eta_n0 = 2 zeta sqrt(kn / m*), m* = m/2 for
 * a pair, m for a wall), history tangential spring kt = 0.5 kn with Coulomb
 * mu = 0.5 and no tangential dashpot, rotation, no rolling resistance;
 * R = 1 mm, rho = 2650, g = 9.81, dt = 5e-6 s, Verlet skin 0.1 mm. Walls:
 * planes x = 0, L; y = 0, L; z = 0 with the same law; the lid: a plane
 * starting 1 mm above the bed's mean top 2<z> + R (each code its own, so
 * the force compares at the same compression of the bed), moving down at
 * 0.02 m/s (3 mm in the default 30 000 steps: ~2 mm into the bed).
 *
 * Prints "SCENE phase=pour ... zmean=... zmax=... particle_steps_per_s=..."
 * and "SCENE phase=compress ... lid_force_k=... particle_steps_per_s=..." (k = 1..20,
 * the lid at lid_start - k (compress / 20) dt v). */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_io.h"
#include "gk_scene.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define SB_R 1e-3
#define SB_KN 1e4
#define SB_RHO 2650.0
#define SB_DT 5e-6
#define SB_VLID 0.02
#define SB_NF 20 /* lid force checkpoints */

int main(int argc, char **argv) {
    int nx = 10, nz = 20, threads = 1, i, a, b, c, q = 0, p, k;
    long pour = 40000, comp = 30000;
    const char *data = NULL;
    double L, H, e = 0.5, zeta, zmean = 0.0, zmax = -1.0, lid0, t0, tp, tc, force[SB_NF], ke;
    clock_t c0;
    double cpu_p, cpu_c;
    gk_scene_def d = gk_scene_def_default();
    gk_scene sc;
    gk_packing pk;
    gk_err err;
    gk_material wm;
    gk_wall_def lid = gk_wall_def_default();
    gk_rng rng;
    for (i = 1; i < argc; ++i) {
        const char *o = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(o, "--help")) {
            puts("usage: bench_scene_box [--nx N] [--nz N] [--pour S] [--compress S] [--threads T] "
                 "[--write-data FILE]");
            return 0;
        }
        if (!v) return fprintf(stderr, "bench_scene_box: %s needs a value\n", o), 2;
        if (!strcmp(o, "--nx"))
            nx = atoi(v);
        else if (!strcmp(o, "--nz"))
            nz = atoi(v);
        else if (!strcmp(o, "--pour"))
            pour = atol(v);
        else if (!strcmp(o, "--compress"))
            comp = atol(v);
        else if (!strcmp(o, "--threads"))
            threads = atoi(v);
        else if (!strcmp(o, "--write-data"))
            data = v;
        else
            return fprintf(stderr, "bench_scene_box: unknown option %s\n", o), 2;
        ++i;
    }
    if (nx < 2 || nz < 2 || pour < 1 || comp < SB_NF || threads < 1)
        return fprintf(
                   stderr,
                   "bench_scene_box: need --nx, --nz >= 2, --pour >= 1, --compress >= %d, --threads >= 1\n",
                   SB_NF),
               2;
    L = nx * 2.4 * SB_R;
    H = (nz + 1) * 2.4 * SB_R;
    zeta = gk_restitution_to_zeta(e);
    if (gk_packing_alloc(&pk, 3, nx * nx * nz, NULL, &err)) return fprintf(stderr, "%s\n", err.msg), 1;
    gk_rng_seed(&rng, 42);
    for (c = 0; c < nz; ++c)
        for (b = 0; b < nx; ++b)
            for (a = 0; a < nx; ++a, ++q) {
                pk.x[q] = 2.4 * SB_R * (a + 0.5) + 0.15 * SB_R * (2.0 * gk_rng_uniform(&rng) - 1.0);
                pk.y[q] = 2.4 * SB_R * (b + 0.5) + 0.15 * SB_R * (2.0 * gk_rng_uniform(&rng) - 1.0);
                pk.z[q] = 2.4 * SB_R * (c + 0.5);
                pk.r[q] = SB_R;
            }
    if (data) {
        FILE *fp = fopen(data, "w");
        if (!fp) return fprintf(stderr, "bench_scene_box: cannot write %s\n", data), 1;
        fprintf(fp, "LAMMPS data file from bench_scene_box\n\n%d atoms\n1 atom types\n\n", pk.n);
        fprintf(fp, "0 %.17g xlo xhi\n0 %.17g ylo yhi\n0 %.17g zlo zhi\n\nAtoms # sphere\n\n", L, L, 2.0 * H);
        for (q = 0; q < pk.n; ++q)
            fprintf(fp, "%d 1 %.17g %.17g %.17g %.17g %.17g\n", q + 1, 2.0 * SB_R, SB_RHO, pk.x[q], pk.y[q],
                    pk.z[q]);
        if (fclose(fp)) return fprintf(stderr, "bench_scene_box: error writing %s\n", data), 1;
    }
    d.dim = 3;
    d.hi[0] = d.hi[1] = L;
    d.hi[2] = 2.0 * H;
    d.gravity[2] = -9.81;
    d.rve.mat.law = GK_LAW_LINEAR;
    d.rve.mat.kn = SB_KN;
    d.rve.mat.kt_ratio = 0.5;
    d.rve.mat.friction = 0.5;
    d.rve.mat.zeta_n = zeta;
    d.rve.mat.density = SB_RHO;
    d.rve.dt = SB_DT;
    d.rve.skin = 0.1 * SB_R;
    d.rve.threads = threads;
    if (gk_scene_create(&sc, &d, &pk))
        return fprintf(stderr, "bench_scene_box: %s\n", gk_scene_error(&sc)), 1;
    gk_packing_free(&pk);
    wm = d.rve.mat; /* a wall contact with constant kn: the same k_n, the dashpot on the particle's mass */
    if (gk_scene_add_box(&sc, &wm, GK_BOX_ALL & ~(2u << 4), NULL))
        return fprintf(stderr, "bench_scene_box: %s\n", gk_scene_error(&sc)), 1;
    t0 = gk_wtime();
    c0 = clock();
    if (gk_scene_step(&sc, pour)) return fprintf(stderr, "bench_scene_box: %s\n", gk_scene_error(&sc)), 1;
    tp = gk_wtime() - t0;
    cpu_p = (double)(clock() - c0) / CLOCKS_PER_SEC;
    ke = gk_rve_kinetic_energy(&sc.rve);
    for (p = 0; p < sc.rve.n; ++p) {
        double x[3];
        gk_scene_position(&sc, p, x);
        zmean += x[2] / sc.rve.n;
        if (x[2] > zmax) zmax = x[2];
    }
    printf(
        "SCENE phase=pour n=%d steps=%ld seconds=%.4g cpu_seconds=%.4g particle_steps_per_s=%.4g zmean=%.8g "
        "zmax=%.8g height_2zmean=%.8g kinetic=%.4g\n",
        sc.rve.n, pour, tp, cpu_p, sc.rve.n * (double)pour / tp, zmean, zmax, 2.0 * zmean, ke);
    lid0 = 2.0 * zmean + SB_R +
           1e-3; /* 1 mm above the bed's mean top (2<z> + R): bulk, not the highest sphere */
    lid.point[2] = lid0;
    lid.normal[2] = -1.0;
    lid.mat = wm;
    lid.velocity[2] = -SB_VLID;
    if (gk_scene_add_wall(&sc, &lid, NULL))
        return fprintf(stderr, "bench_scene_box: %s\n", gk_scene_error(&sc)), 1;
    t0 = gk_wtime();
    c0 = clock();
    for (k = 0; k < SB_NF; ++k) {
        if (gk_scene_step(&sc, comp / SB_NF))
            return fprintf(stderr, "bench_scene_box: %s\n", gk_scene_error(&sc)), 1;
        force[k] = sc.walls[sc.nwalls - 1].resistance;
    }
    tc = gk_wtime() - t0;
    cpu_c = (double)(clock() - c0) / CLOCKS_PER_SEC;
    printf("SCENE phase=compress n=%d steps=%ld seconds=%.4g cpu_seconds=%.4g particle_steps_per_s=%.4g "
           "lid_start=%.8g "
           "lid_end=%.8g",
           sc.rve.n, (comp / SB_NF) * SB_NF, tc, cpu_c, sc.rve.n * (double)((comp / SB_NF) * SB_NF) / tc,
           lid0, sc.walls[sc.nwalls - 1].pos[2]);
    for (k = 0; k < SB_NF; ++k) printf(" lid_force_%d=%.8g", k + 1, force[k]);
    printf(" simd=%s\n", GK_SIMD_NAME);
    gk_scene_destroy(&sc);
    return 0;
}
