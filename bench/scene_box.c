/* bench_scene_box - a 3D scene beyond the periodic cell, timed and measured
 * the same way in LAMMPS (bench/peers/run_box.sh): monodisperse spheres on a
 * jittered lattice fall under gravity into a box (fixed floor and side
 * walls) and settle (the POUR); the settled packing is then compressed by a
 * lid moving down at constant speed (the COMPRESSION).
 *
 *   build/bench_scene_box [--nx 10] [--nz 20] [--pour S] [--compress S] [--threads T]
 *                         [--write-data FILE]      the starting atoms (before the pour)
 *                         [--write-settled FILE]   the settled packing (after the pour)
 *                         [--from FILE]            no pour: compress the packing of FILE
 *   build/bench_scene_box --impact [--write-data FILE]   the law alone (below)
 *   (LAMMPS data files, atom_style sphere: id type diameter density x y z,
 *   as written by the two --write options; --from needs the box of the same
 *   --nx, --nz)
 *
 * The compression starts from the settled packing as a LAMMPS run can read
 * it: positions and radii only, every velocity and spin zero, no contact
 * history (pairs and walls), a new scene built from those positions. With
 * --write-settled the positions are read back from the file (%.17g: the
 * exact doubles; checked) and LAMMPS compresses the very same packing from
 * the same file (bench/peers/lammps_box.in, phase compress), so the two
 * codes' lid forces compare at equal lid travel; the pours themselves
 * diverge chaotically (different integrators and summation orders) and are
 * compared by their packing height.
 *
 * Law (both codes): linear normal spring kn = 1e4 N/m (constant), normal
 * dashpot of restitution 0.5 (g = 2 zeta sqrt(m* kn): LAMMPS pair granular
 * "damping mass_velocity" with eta_n0 = 2 zeta sqrt(kn / m*), m* = m/2 for
 * a pair, m for a wall), history tangential spring kt = 0.5 kn with Coulomb
 * mu = 0.5 and no tangential dashpot, rotation, no rolling resistance;
 * R = 1 mm, rho = 2650, g = 9.81, dt = 5e-6 s, Verlet skin 0.1 mm. Walls:
 * planes x = 0, L; y = 0, L; z = 0 with the same law; the lid: a plane
 * starting 1 mm above the settled bed's mean top 2<z> + R, moving down at
 * 0.02 m/s (3 mm in the default 30 000 steps: ~2 mm into the bed).
 *
 * --impact: the contact law without the packing's chaos. No gravity;
 * sphere 1 hits the floor at (vx, vz) = (0.05, -0.1) m/s, sphere 2, moving
 * at vx = 0.1 m/s, hits sphere 3 at rest 30 degrees off centre; prints
 * "IMPACT vx1=... vz1=... wy1=... (spheres 1..3)" after 4000 steps (LAMMPS:
 * phase impact of bench/peers/lammps_box.in).
 *
 * Prints "SCENE phase=pour ... zmean=... zmax=... particle_steps_per_s=..."
 * and "SCENE phase=compress ... lid_start=... lid_force_k=...
 * particle_steps_per_s=..." (k = 1..20, the lid at lid_start - k (compress
 * / 20) dt v). Exit status 0, 1 on a failed run, write or read, 2 on bad
 * options. */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_io.h"
#include "gk_scene.h"
#include <math.h>
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

/* a LAMMPS data file (atom_style sphere) of packing pk in the box [0,L]^2 x [0,Lz] */
static int write_data(const char *path, const gk_packing *pk, double L, double Lz) {
    FILE *fp = fopen(path, "w");
    int q, bad;
    if (!fp) return fprintf(stderr, "bench_scene_box: cannot write %s\n", path), 1;
    fprintf(fp, "LAMMPS data file from bench_scene_box\n\n%d atoms\n1 atom types\n\n", pk->n);
    fprintf(fp, "0 %.17g xlo xhi\n0 %.17g ylo yhi\n0 %.17g zlo zhi\n\nAtoms # sphere\n\n", L, L, Lz);
    for (q = 0; q < pk->n; ++q)
        fprintf(fp, "%d 1 %.17g %.17g %.17g %.17g %.17g\n", q + 1, 2.0 * pk->r[q], SB_RHO, pk->x[q], pk->y[q],
                pk->z[q]);
    bad = ferror(fp);
    if (fclose(fp) || bad) return fprintf(stderr, "bench_scene_box: error writing %s\n", path), 1;
    return 0;
}

/* the atoms of a data file as written by write_data (ids 1..n in any
 * order; the header's "n atoms" line before the Atoms section) into pk,
 * allocated here */
static int read_data(const char *path, gk_packing *pk) {
    FILE *fp = fopen(path, "r");
    char line[512], word[16];
    int n = 0, got = 0, bad = 0;
    long q;
    unsigned char *seen = NULL;
    gk_err err;
    if (!fp) return fprintf(stderr, "bench_scene_box: cannot read %s\n", path), 1;
    while (fgets(line, sizeof line, fp) && !(sscanf(line, "%15s", word) == 1 && !strcmp(word, "Atoms")))
        if (sscanf(line, "%ld %15s", &q, word) == 2 && !strcmp(word, "atoms"))
            n = q >= 1 && q <= 10000000 ? (int)q : -1;
    if (n < 1 || gk_packing_init(pk, 3, n, NULL, &err)) {
        fclose(fp);
        return fprintf(stderr, "bench_scene_box: %s: no \"N atoms\" line (1 <= N <= 1e7) before Atoms\n",
                       path),
               1;
    }
    seen = (unsigned char *)calloc((size_t)n, 1);
    while (seen && !bad && got < n && fgets(line, sizeof line, fp)) {
        int id, type;
        double dia, rho, x, y, z;
        if (sscanf(line, "%15s", word) != 1) continue; /* blank line */
        if (sscanf(line, "%d %d %lf %lf %lf %lf %lf", &id, &type, &dia, &rho, &x, &y, &z) != 7 || id < 1 ||
            id > n || seen[id - 1] || !(dia > 0.0) || !isfinite(dia) || !isfinite(x) || !isfinite(y) ||
            !isfinite(z)) {
            bad = 1;
            break;
        }
        seen[id - 1] = 1;
        pk->x[id - 1] = x;
        pk->y[id - 1] = y;
        pk->z[id - 1] = z;
        pk->r[id - 1] = 0.5 * dia;
        ++got;
    }
    fclose(fp);
    free(seen);
    if (got != n) {
        gk_packing_free(pk);
        return fprintf(stderr, "bench_scene_box: %s: expected %d atoms (ids 1..%d), found %s\n", path, n, n,
                       bad ? "a malformed or repeated atom line" : "fewer"),
               1;
    }
    return 0;
}

/* a scene of pk in the box (floor and sides, no lid) with the law above */
static int make_scene(gk_scene *sc, const gk_packing *pk, double L, double Lz, double g, int threads,
                      gk_material *wm) {
    gk_scene_def d = gk_scene_def_default();
    d.dim = 3;
    d.hi[0] = d.hi[1] = L;
    d.hi[2] = Lz;
    d.gravity[2] = -g;
    d.rve.mat.law = GK_LAW_LINEAR;
    d.rve.mat.kn = SB_KN;
    d.rve.mat.kt_ratio = 0.5;
    d.rve.mat.friction = 0.5;
    d.rve.mat.zeta_n = gk_restitution_to_zeta(0.5);
    d.rve.mat.density = SB_RHO;
    d.rve.dt = SB_DT;
    d.rve.skin = 0.1 * SB_R;
    d.rve.threads = threads;
    *wm = d.rve.mat; /* a wall contact with constant kn: the same k_n, the dashpot on the particle's mass */
    if (gk_scene_create(sc, &d, pk)) return fprintf(stderr, "bench_scene_box: %s\n", gk_scene_error(sc)), 1;
    if (gk_scene_add_box(sc, wm, GK_BOX_ALL & ~(2u << 4), NULL)) {
        fprintf(stderr, "bench_scene_box: %s\n", gk_scene_error(sc));
        return gk_scene_destroy(sc), 1;
    }
    return 0;
}

/* the pour: the jittered lattice (written to `data` if given) falls into the
 * box; pk gets the settled packing in world coordinates, in index order */
static int pour_bed(gk_packing *pk, int nx, int nz, long steps, int threads, const char *data) {
    double L = nx * 2.4 * SB_R, Lz = 2.0 * (nz + 1) * 2.4 * SB_R, t0, tp, cpu, ke, zmean = 0.0, zmax = -1.0;
    int a, b, c, q = 0, p;
    clock_t c0;
    gk_scene sc;
    gk_material wm;
    gk_err err;
    gk_rng rng;
    if (gk_packing_init(pk, 3, nx * nx * nz, NULL, &err)) return fprintf(stderr, "%s\n", err.msg), 1;
    gk_rng_seed(&rng, 42);
    for (c = 0; c < nz; ++c)
        for (b = 0; b < nx; ++b)
            for (a = 0; a < nx; ++a, ++q) {
                pk->x[q] = 2.4 * SB_R * (a + 0.5) + 0.15 * SB_R * (2.0 * gk_rng_uniform(&rng) - 1.0);
                pk->y[q] = 2.4 * SB_R * (b + 0.5) + 0.15 * SB_R * (2.0 * gk_rng_uniform(&rng) - 1.0);
                pk->z[q] = 2.4 * SB_R * (c + 0.5);
                pk->r[q] = SB_R;
            }
    if ((data && write_data(data, pk, L, Lz)) || make_scene(&sc, pk, L, Lz, 9.81, threads, &wm))
        return gk_packing_free(pk), 1;
    t0 = gk_wtime();
    c0 = clock();
    if (gk_scene_step(&sc, steps)) {
        fprintf(stderr, "bench_scene_box: %s\n", gk_scene_error(&sc));
        return gk_scene_destroy(&sc), gk_packing_free(pk), 1;
    }
    tp = gk_wtime() - t0;
    cpu = (double)(clock() - c0) / CLOCKS_PER_SEC;
    ke = gk_rve_kinetic_energy(&sc.rve);
    for (p = 0; p < sc.rve.n; ++p) {
        double x[3];
        gk_scene_position(&sc, p, x);
        pk->x[p] = x[0];
        pk->y[p] = x[1];
        pk->z[p] = x[2];
        pk->r[p] = (double)sc.rve.r[p];
        zmean += x[2] / sc.rve.n;
        if (x[2] > zmax) zmax = x[2];
    }
    printf(
        "SCENE phase=pour n=%d steps=%ld seconds=%.4g cpu_seconds=%.4g particle_steps_per_s=%.4g zmean=%.8g "
        "zmax=%.8g height_2zmean=%.8g kinetic=%.4g\n",
        sc.rve.n, steps, tp, cpu, sc.rve.n * (double)steps / tp, zmean, zmax, 2.0 * zmean, ke);
    gk_scene_destroy(&sc);
    return 0;
}

/* the law isolated from the packing's chaos: without gravity, sphere 1
 * hits the floor obliquely, (vx, vz) = (0.05, -0.1) m/s, and sphere 2,
 * moving at vx = 0.1 m/s, hits sphere 3 (at rest, 1 mm higher: 30 degrees
 * off centre); after 4000 steps prints each one's velocity and spin */
static int impact(int threads, const char *data) {
    const double L = 24e-3; /* a cube of side L, the floor at z = 0 */
    static const double X[3][3] = {{5e-3, 5e-3, 1.5e-3}, {9.5e-3, 12e-3, 10e-3}, {12e-3, 12e-3, 11e-3}};
    static const double V[3][3] = {{0.05, 0.0, -0.1}, {0.1, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    gk_packing pk;
    gk_scene sc;
    gk_material wm;
    gk_err err;
    int p;
    if (gk_packing_init(&pk, 3, 3, NULL, &err)) return fprintf(stderr, "%s\n", err.msg), 1;
    for (p = 0; p < 3; ++p) {
        pk.x[p] = X[p][0];
        pk.y[p] = X[p][1];
        pk.z[p] = X[p][2];
        pk.r[p] = SB_R;
    }
    if ((data && write_data(data, &pk, L, L)) || make_scene(&sc, &pk, L, L, 0.0, threads, &wm))
        return gk_packing_free(&pk), 1;
    gk_packing_free(&pk);
    for (p = 0; p < 3; ++p) gk_scene_set_velocity(&sc, p, V[p], NULL);
    if (gk_scene_step(&sc, 4000)) {
        fprintf(stderr, "bench_scene_box: %s\n", gk_scene_error(&sc));
        return gk_scene_destroy(&sc), 1;
    }
    printf("IMPACT");
    for (p = 0; p < 3; ++p)
        printf(" vx%d=%.8g vz%d=%.8g wy%d=%.8g", p + 1, (double)sc.rve.v[0][p], p + 1, (double)sc.rve.v[2][p],
               p + 1, (double)sc.rve.w[1][p]);
    printf("\n");
    gk_scene_destroy(&sc);
    return ferror(stdout) ? 1 : 0;
}

int main(int argc, char **argv) {
    int nx = 10, nz = 20, threads = 1, i, q, p, k, imp = 0;
    long pour = 40000, comp = 30000;
    const char *data = NULL, *settled = NULL, *from = NULL;
    double L, H, zmean = 0.0, zmax = -1.0, lid0, t0, tc, force[SB_NF], cpu_c;
    clock_t c0;
    gk_scene sc;
    gk_packing pk;
    gk_material wm;
    gk_wall_def lid = gk_wall_def_default();
    for (i = 1; i < argc; ++i) {
        const char *o = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(o, "--help")) {
            puts("usage: bench_scene_box [--nx N] [--nz N] [--pour S] [--compress S] [--threads T] "
                 "[--write-data FILE] [--write-settled FILE] [--from FILE] [--impact]");
            return 0;
        }
        if (!strcmp(o, "--impact")) {
            imp = 1;
            continue;
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
        else if (!strcmp(o, "--write-settled"))
            settled = v;
        else if (!strcmp(o, "--from"))
            from = v;
        else
            return fprintf(stderr, "bench_scene_box: unknown option %s\n", o), 2;
        ++i;
    }
    if (nx < 2 || nz < 2 || nx > 1000 || nz > 1000 || pour < 1 || comp < SB_NF || threads < 1)
        return fprintf(stderr,
                       "bench_scene_box: need 2 <= --nx, --nz <= 1000, --pour >= 1, --compress >= %d, "
                       "--threads >= 1\n",
                       SB_NF),
               2;
    L = nx * 2.4 * SB_R;
    H = (nz + 1) * 2.4 * SB_R;
    if (imp) return impact(threads, data);
    if (from) {
        if (read_data(from, &pk)) return 1;
    } else if (pour_bed(&pk, nx, nz, pour, threads, data)) {
        return 1;
    }
    for (p = 0; p < pk.n; ++p) {
        zmean += pk.z[p] / pk.n;
        if (pk.z[p] > zmax) zmax = pk.z[p];
    }
    /* the compression, from the settled packing as a data file carries it */
    if (settled) {
        gk_packing back;
        int same = 1;
        if (write_data(settled, &pk, L, 2.0 * H)) return gk_packing_free(&pk), 1;
        if (read_data(settled, &back)) return gk_packing_free(&pk), 1;
        for (q = 0; q < pk.n; ++q)
            same &= back.n == pk.n && back.x[q] == pk.x[q] && back.y[q] == pk.y[q] && back.z[q] == pk.z[q] &&
                    back.r[q] == pk.r[q];
        gk_packing_free(&pk);
        pk = back;
        if (!same) return fprintf(stderr, "bench_scene_box: %s does not read back exactly\n", settled), 1;
    }
    if (make_scene(&sc, &pk, L, 2.0 * H, 9.81, threads, &wm)) return gk_packing_free(&pk), 1;
    gk_packing_free(&pk);
    /* the lid 1 mm above the bed's mean top 2<z> + R (the bulk, not the highest sphere) */
    lid0 = 2.0 * zmean + SB_R + 1e-3;
    lid.point[2] = lid0;
    lid.normal[2] = -1.0;
    lid.mat = wm;
    lid.velocity[2] = -SB_VLID;
    if (gk_scene_add_wall(&sc, &lid, NULL)) {
        fprintf(stderr, "bench_scene_box: %s\n", gk_scene_error(&sc));
        return gk_scene_destroy(&sc), 1;
    }
    t0 = gk_wtime();
    c0 = clock();
    for (k = 0; k < SB_NF; ++k) {
        if (gk_scene_step(&sc, comp / SB_NF)) {
            fprintf(stderr, "bench_scene_box: %s\n", gk_scene_error(&sc));
            return gk_scene_destroy(&sc), 1;
        }
        force[k] = sc.walls[sc.nwalls - 1].resistance;
    }
    tc = gk_wtime() - t0;
    cpu_c = (double)(clock() - c0) / CLOCKS_PER_SEC;
    printf("SCENE phase=compress n=%d steps=%ld seconds=%.4g cpu_seconds=%.4g particle_steps_per_s=%.4g "
           "start=%s lid_start=%.17g lid_end=%.8g",
           sc.rve.n, (comp / SB_NF) * SB_NF, tc, cpu_c, sc.rve.n * (double)((comp / SB_NF) * SB_NF) / tc,
           from ? "file" : "settled", lid0, sc.walls[sc.nwalls - 1].pos[2]);
    for (k = 0; k < SB_NF; ++k) printf(" lid_force_%d=%.8g", k + 1, force[k]);
    printf(" simd=%s\n", GK_SIMD_NAME);
    gk_scene_destroy(&sc);
    return ferror(stdout) ? 1 : 0;
}
