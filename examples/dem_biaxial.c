/* dem_biaxial.c - the 2D biaxial test as a direct numerical simulation
 * (DNS) in plain DEM: the whole specimen, a tiling of a periodic packing
 * opened up, between rigid platens, confined laterally by flexible
 * membranes (chains of boundary disks loaded by a follower pressure), no
 * gravity. The single-scale reference the two-scale biaxial drivers
 * (femdem_biaxial, mpmdem_biaxial) are compared with; Liu, Bosco & Suiker
 * (2018, Sect. 4.1) run the same test as DNS with 441 and 1681 disks
 * (tilings 2L x L and 4L x 2L of their 228-disk RVE).
 *
 *   build/dem_biaxial                            # rve400 tiled 1 x 2: 800 disks, to 4 %
 *   build/dem_biaxial --generate 228 --tiles 1x2 # a 456-disk DNS like the paper's 441
 *   build/dem_biaxial --generate 228 --tiles 2x4 --strain 0.1   # 1824 disks, like its 1681
 *
 * Specimen. --packing FILE (default examples/data/rve400.txt, the Guo & Zhao 2014
 * RVE consolidated at 100 kPa) or --generate N (a periodic packing of N
 * disks with R_max / R_min = 1.5, the Liu, Bosco & Suiker 2018 size ratio, generated and
 * consolidated isotropically to --pressure frictionless, gk_rve_consolidate)
 * is tiled --tiles NXxNY times (gk_packing_tile) and opened: the tiled
 * cell's box, dilated by 1 % to open the contacts of the stressed packing
 * (opened under load its edge disks would shoot out), becomes the
 * specimen, W wide and H high.
 *
 * Boundary conditions (gk_scene.h). Bottom platen: a fixed plane; top
 * platen: a plane, servo-controlled to the stress --pressure over the
 * specimen's current width during consolidation, then moved down at
 * constant speed; both with the disks' friction (rough; --platen-mu).
 * Sides: membranes (gk_scene_add_membrane) on the outermost disk of every
 * band one mean diameter high (gk_scene_side_chain), anchored to both
 * platens, loaded by the follower pressure --pressure and tied by
 * tension-only links (--link-stiffness, default 0.05 k_n of the mean
 * contact): the stress a rubber sleeve applies, the membrane of Chen et al. 2021
 * App. B. Local damping --damping (quasi-static loading).
 *
 * Stages. 1: consolidation at the confining pressure until the lid's stress
 * is within 1 % of it and the kinetic energy is below 1e-7 of the work
 * done (or --max-consolidation steps). 2: biaxial compression at the axial
 * strain rate --rate (default: inertial number 1e-3 at the confining
 * pressure) to --strain.
 *
 * Measures (a CSV row every --every of axial strain): axial strain
 * eps = (H0 - H) / H0 (compression positive); the area A enclosed by the
 * membranes' centre lines and the platens; sigma_yy = lid force / (A / H)
 * and the mean stress of the particles over A (gk_scene_stress: sigma_xx,
 * sigma_yy from the contacts, compression positive); volumetric strain
 * (A0 - A) / A0; the stress ratio sigma_bar = |s_yy - s_xx| / (s_yy + s_xx)
 * of Liu, Bosco & Suiker 2018 eq 40 and the mobilised friction angle asin(sigma_bar); the
 * coordination number 2 C / n.
 *
 * Outputs in --out DIR: biaxial.csv, biaxial_stress.svg (stress ratio and
 * volumetric strain against axial strain), particles_NNN.svg/.vtk and
 * walls_NNN.vtk after consolidation, at --pictures strains and at the end;
 * a RESULT line.
 */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_io.h"
#include "gk_scene.h"
#include "dem_scene.h"
#include "cli.h"

typedef struct db_opts {
    const char *packing, *out;
    int generate, tx, ty, threads, quiet, npic;
    double pressure, strain, rate, every, damping, platen_mu, link_k, max_cons, pic[8];
    unsigned long seed;
} db_opts;

typedef struct db_row {
    double eps, syy_lid, sxx, syy, ev, ratio, z;
} db_row;

static void usage(FILE *fp) {
    fprintf(
        fp,
        "dem_biaxial - 2D biaxial DNS in DEM (gk_scene.h): a tiled periodic packing opened between rigid\n"
        "platens, confined by follower-pressure membranes, consolidated then compressed (Liu, Bosco &\n"
        "Suiker 2018, DNS of 441 and 1681 disks).\n\n"
        "usage: dem_biaxial [options]\n"
        "  --packing FILE         periodic 2D packing (default examples/data/rve400.txt)\n"
        "  --generate N           instead: generate and consolidate N disks, R_max/R_min = 1.5\n"
        "  --tiles NXxNY          copies of the packing across x and y (default 1x2)\n"
        "  --pressure P           confining pressure [Pa] (default 1e5)\n"
        "  --strain E             final axial strain (default 0.04; the paper goes to 0.1)\n"
        "  --rate R               axial strain rate [1/s] (default: inertial number 1e-3)\n"
        "  --every E              axial strain between CSV rows (default 0.001)\n"
        "  --pictures E1,E2,...   strains of the pictures (default 0.02)\n"
        "  --damping A            local damping (default 0.3)\n"
        "  --platen-mu M          platen friction (default: the disks')\n"
        "  --link-stiffness K     membrane links [N/m] (default 0.05 k_n of the mean contact)\n"
        "  --max-consolidation N  steps of stage 1 at most (default 200000)\n"
        "  --seed S               generated packing (default 1)\n"
        "  --threads T            threads of the pair forces (default 1; results do not depend on it)\n"
        "  --out DIR              output directory (default build/dem_biaxial)\n"
        "  --quiet                no progress lines\n"
        "  --help                 this text\n\n"
        "ends with: RESULT n=... W=... H0=... peak_ratio=... eps_peak=... phi_peak_deg=... ratio_final=...\n"
        "           syy_peak=... ev_final=... z0=... steps=... dt=... seconds=...\n"
        "exit status: 0 done, 1 setup, simulation or output failed (message), 2 bad arguments\n");
}

static int parse(int argc, char **argv, db_opts *o) {
    const char *tiles = "1x2", *pics = "0.02";
    int help = 0, r;
    char c;
    const cli_opt opts[] = {
        {"--packing", CLI_STR, &o->packing, 0, 0, NULL, NULL, 0},
        {"--out", CLI_STR, &o->out, 0, 0, NULL, NULL, 0},
        {"--tiles", CLI_STR, &tiles, 0, 0, NULL, NULL, 0},
        {"--pictures", CLI_STR, &pics, 0, 0, NULL, NULL, 0},
        {"--quiet", CLI_FLAG, &o->quiet, 0, 0, NULL, NULL, 0},
        {"--generate", CLI_INT, &o->generate, 16, 1000000, NULL, NULL, 0},
        {"--pressure", CLI_REAL, &o->pressure, 0, HUGE_VAL, "a positive stress", NULL,
         CLI_LO_OPEN | CLI_HI_OPEN},
        {"--strain", CLI_REAL, &o->strain, 0, 0.5, "a strain in (0, 0.5]", NULL, CLI_LO_OPEN},
        {"--rate", CLI_REAL, &o->rate, 0, HUGE_VAL, "a rate >= 0 (0: automatic)", NULL, CLI_HI_OPEN},
        {"--every", CLI_REAL, &o->every, 0, 0.5, "a strain in (0, --strain]", NULL, CLI_LO_OPEN},
        {"--damping", CLI_REAL, &o->damping, 0, 1, "a value in [0, 1)", NULL, CLI_HI_OPEN},
        {"--platen-mu", CLI_REAL, &o->platen_mu, 0, HUGE_VAL, "a friction coefficient >= 0", NULL,
         CLI_HI_OPEN},
        {"--link-stiffness", CLI_REAL, &o->link_k, 0, HUGE_VAL, "a stiffness >= 0 (0: automatic)", NULL,
         CLI_HI_OPEN},
        {"--max-consolidation", CLI_REAL, &o->max_cons, 1000, HUGE_VAL, "a step count >= 1000", NULL,
         CLI_HI_OPEN},
        {"--seed", CLI_ULONG, &o->seed, 0, 0, NULL, NULL, 0},
        {"--threads", CLI_INT, &o->threads, 1, 256, NULL, NULL, 0},
        {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    const cli_opt *const tables[] = {opts, NULL};
    memset(o, 0, sizeof *o);
    o->packing = "examples/data/rve400.txt";
    o->out = "build/dem_biaxial";
    o->threads = 1, o->seed = 1;
    o->pressure = 1e5, o->strain = 0.04, o->rate = 0.0, o->every = 0.001, o->damping = 0.3,
    o->platen_mu = -1.0; /* -1: the disks' friction */
    o->link_k = 0.0, o->max_cons = 200000;
    if ((r = cli_parse("dem_biaxial", argc, argv, tables, &help)) != 0) return r;
    if (help) return usage(stdout), -1;
    if (sscanf(tiles, "%dx%d%c", &o->tx, &o->ty, &c) != 2 || o->tx < 1 || o->ty < 1 || o->tx > 64 ||
        o->ty > 64)
        return fprintf(stderr, "dem_biaxial: --tiles %s: need NXxNY with 1 <= NX, NY <= 64\n", tiles), 2;
    if ((o->npic = dsc_list(pics, o->pic, 8, 1)) < 0)
        return fprintf(stderr, "dem_biaxial: --pictures %s: need up to 8 increasing strains > 0\n", pics), 2;
    if (o->every > o->strain)
        return fprintf(stderr, "dem_biaxial: --every %g: need a strain in (0, --strain] (--strain %g)\n",
                       o->every, o->strain),
               2;
    return 0;
}

/* a periodic packing of n disks, R_max / R_min = 1.5, consolidated
 * isotropically to p (frictionless, dense) */
static int generate(const db_opts *o, const gk_rve_def *base, gk_packing *out) {
    gk_gen_def g;
    gk_packing cloud;
    gk_rve rve;
    gk_rve_def def = *base;
    gk_consolidate_def cd;
    gk_consolidate_report rep;
    gk_err err;
    int r;
    memset(&g, 0, sizeof g);
    g.dim = 2;
    g.n = o->generate;
    g.psd = GK_PSD_UNIFORM;
    g.r_min = 0.002;
    g.r_max = 0.003;
    g.seed = (uint64_t)o->seed;
    if (gk_packing_generate(&cloud, &g, NULL, &err)) return fprintf(stderr, "dem_biaxial: %s\n", err.msg), 1;
    def.flags |= GK_RVE_WRAP;
    r = gk_rve_create(&rve, &def, &cloud);
    gk_packing_free(&cloud);
    if (r) return fprintf(stderr, "dem_biaxial: %s\n", gk_rve_error(&rve)), 1;
    memset(&cd, 0, sizeof cd);
    cd.pressure = o->pressure;
    cd.friction = 0.0;
    cd.box = 1; /* the cell stays a rectangle: the specimen is cut from it between flat platens */
    r = gk_rve_consolidate(&rve, &cd, &rep);
    if (!r) r = gk_rve_to_packing(&rve, out, NULL, &err);
    if (r)
        fprintf(stderr, "dem_biaxial: consolidation: %s\n", gk_rve_error(&rve));
    else if (!o->quiet)
        printf("dem_biaxial: generated %d disks, consolidated to %.4g Pa in %ld steps (void ratio %.4f)\n",
               o->generate, o->pressure, rep.steps, rep.void_ratio);
    gk_rve_destroy(&rve);
    return r != 0;
}

/* area enclosed by the two chains' centre lines and the platens (shoelace) */
static double enclosed_area(const gk_scene *sc, double H) {
    double xs[4096], ys[4096], x[3], A = 0.0;
    int m = 0, k, e, c;
    for (c = 1; c >= 0; --c) { /* right chain (bottom to top), then left (top to bottom) */
        const gk_membrane *M = &sc->mem[c];
        for (e = 0; e < M->n && m < 4094; ++e) {
            gk_scene_position(sc, gk_scene_index(sc, M->ids[e]), x);
            if (e == 0) xs[m] = x[0], ys[m++] = c ? 0.0 : H;
            xs[m] = x[0], ys[m++] = x[1];
            if (e == M->n - 1) xs[m] = x[0], ys[m++] = c ? H : 0.0;
        }
    }
    for (k = 0; k < m; ++k) A += 0.5 * (xs[k] * ys[(k + 1) % m] - xs[(k + 1) % m] * ys[k]);
    return A;
}

/* the whole run: the options, the scene and what the stages measure */
typedef struct db_run {
    db_opts o;
    gk_scene sc;
    gk_scene_def d;
    int created, nrows, caprows;
    db_row *rows;
    int32_t *chain;
    double W, H0, A0, rmean, peak, eps_peak, syy_peak, z0, t0;
    long steps;
    FILE *csv;
} db_run;

/* the scene's error, said; 1 */
static int db_fail(db_run *R) {
    fprintf(stderr, "dem_biaxial: %s\n", gk_scene_error(&R->sc));
    return 1;
}

/* the specimen: the packing (read or generated) tiled and opened in a box, the scene, the platens on
 * its extreme disks and the membranes on its sides; 0 or 1 (said) */
static int db_setup(db_run *R) {
    const db_opts *o = &R->o;
    gk_scene_def *d = &R->d;
    gk_packing base, tiled;
    gk_err err;
    gk_wall_def flo = gk_wall_def_default(), lid = gk_wall_def_default();
    double W, H0;
    int p, nl, nr;
    d->rve =
        gk_rve_def_default(); /* the Guo & Zhao 2014 material (linear, E 6e8, kt/kn 0.8, mu tan 0.5, 2D t = 0.1) */
    d->rve.damping = o->damping;
    d->rve.threads = o->threads;
    if (o->generate) {
        if (generate(o, &d->rve, &base)) return 1;
    } else if (gk_packing_read(o->packing, &base, NULL, &err)) {
        return fprintf(stderr, "dem_biaxial: %s\n", err.msg), 1;
    }
    if (base.dim != 2 || base.h[1] != 0.0 || base.h[3] != 0.0) {
        gk_packing_free(&base);
        return fprintf(stderr, "dem_biaxial: the packing must be 2D in a rectangular cell\n"), 1;
    }
    if (gk_packing_tile(&base, o->tx, o->ty, 1, &tiled, NULL, &err)) {
        gk_packing_free(&base);
        return fprintf(stderr, "dem_biaxial: %s\n", err.msg), 1;
    }
    gk_packing_free(&base);
    W = 1.01 * tiled.h[0];
    H0 = 1.01 * tiled.h[4];
    for (p = 0; p < tiled.n; ++p) {
        double s;
        R->rmean += tiled.r[p] / tiled.n;
        /* positions in the box, dilated by 1 %: the packing is relieved of its
         * stress (its contacts open) before the platens and membranes reload
         * it; opened under load, its edge disks would shoot out */
        s = tiled.x[p] / tiled.h[0];
        tiled.x[p] = W * (s - floor(s));
        s = tiled.y[p] / tiled.h[4];
        tiled.y[p] = H0 * (s - floor(s));
    }
    d->dim = 2;
    d->lo[0] = -0.5 * W;
    d->hi[0] = 1.5 * W;
    d->lo[1] = -0.1 * H0;
    d->hi[1] = 1.1 * H0;
    if (gk_scene_create(&R->sc, d, &tiled)) {
        gk_packing_free(&tiled);
        return fprintf(stderr, "dem_biaxial: %s\n", gk_scene_error(&R->sc)), 1;
    }
    R->created = 1;
    gk_packing_free(&tiled);
    /* platens on the extreme particles' edges */
    {
        double ylo = 1e300, yhi = -1e300, x[3];
        for (p = 0; p < R->sc.rve.n; ++p) {
            gk_scene_position(&R->sc, p, x);
            if (x[1] - R->sc.rve.r[p] < ylo) ylo = x[1] - R->sc.rve.r[p];
            if (x[1] + R->sc.rve.r[p] > yhi) yhi = x[1] + R->sc.rve.r[p];
        }
        flo.point[1] = ylo;
        flo.normal[1] = 1.0;
        flo.mat = d->rve.mat;
        if (o->platen_mu >= 0) flo.mat.friction = o->platen_mu;
        lid = flo;
        lid.point[1] = yhi;
        lid.normal[1] = -1.0;
        lid.drive = GK_DRIVE_STRESS;
        lid.target = o->pressure;
        lid.area = W * R->sc.rve.volume_factor;
        lid.max_speed = 0.01 * H0; /* 1 % of the height per second at most */
        if (gk_scene_add_wall(&R->sc, &flo, NULL) || gk_scene_add_wall(&R->sc, &lid, NULL)) return db_fail(R);
        H0 = yhi - ylo;
    }
    R->W = W;
    R->H0 = H0;
    /* membranes */
    R->chain = (int32_t *)malloc((size_t)R->sc.rve.n * sizeof *R->chain);
    if (!R->chain) return fprintf(stderr, "dem_biaxial: out of memory\n"), 1;
    {
        double kn = d->rve.mat.young * R->rmean, km = o->link_k > 0 ? o->link_k : 0.05 * kn;
        if (gk_scene_side_chain(&R->sc, 0, -1, 2.0 * R->rmean, R->chain, R->sc.rve.n, &nl) ||
            gk_scene_add_membrane(&R->sc, nl, R->chain, o->pressure, km, 1, 0, NULL) ||
            gk_scene_side_chain(&R->sc, 0, 1, 2.0 * R->rmean, R->chain, R->sc.rve.n, &nr) ||
            gk_scene_add_membrane(&R->sc, nr, R->chain, o->pressure, km, 0, 1, NULL))
            return db_fail(R);
        if (!o->quiet)
            printf("dem_biaxial: %d disks, %.4g x %.4g m, membranes of %d and %d disks, dt %.3g s\n",
                   R->sc.rve.n, W, H0, nl, nr, R->sc.rve.dt);
    }
    return 0;
}

/* stage 1: consolidation at the confining pressure, then the specimen's height and area and its
 * pictures; 0 or 1 (said) */
static int db_consolidate(db_run *R) {
    const db_opts *o = &R->o;
    gk_scene *sc = &R->sc;
    double H;
    long st = 0, chunk = 1000;
    int calm = 0;
    for (;;) {
        double a, err1;
        if (gk_scene_step(sc, chunk)) return db_fail(R);
        st += chunk;
        H = sc->walls[1].pos[1] - sc->walls[0].pos[1];
        a = enclosed_area(sc, H);
        sc->walls[1].def.area = a / H * sc->rve.volume_factor; /* the lid's stress over the current width */
        err1 = fabs(sc->walls[1].resistance / sc->walls[1].def.area - o->pressure) / o->pressure;
        calm =
            (err1 < 0.01 && gk_rve_kinetic_energy(&sc->rve) < 1e-7 * o->pressure * a * sc->rve.volume_factor)
                ? calm + 1
                : 0;
        if (calm >= 3 || st >= (long)o->max_cons) break;
    }
    if (!o->quiet)
        printf("dem_biaxial: consolidated in %ld steps: lid %.5g Pa, height %.5g m\n", st,
               sc->walls[1].resistance / sc->walls[1].def.area, H);
    R->steps += st;
    R->H0 = sc->walls[1].pos[1] - sc->walls[0].pos[1];
    R->A0 = enclosed_area(sc, R->H0);
    return dsc_pictures("dem_biaxial", sc, o->out, "000", "biaxial specimen, consolidated") ? 1 : 0;
}

/* stage 2: compression at constant axial strain rate to --strain, a row of biaxial.csv every --every
 * and the pictures at --pictures; 0 or 1 (said) */
static int db_compress(db_run *R) {
    const db_opts *o = &R->o;
    gk_scene *sc = &R->sc;
    double rate, v, t, H;
    int k, p, ipic = 0;
    char path[1200];
    {
        double rho = R->d.rve.mat.density;
        rate = o->rate > 0 ? o->rate
                           : 1e-3 * sqrt(o->pressure / rho) / (2.0 * R->rmean); /* I = rate 2r sqrt(rho/p) */
        v = rate * R->H0;
        sc->walls[1].def.drive = GK_DRIVE_VELOCITY;
        sc->walls[1].def.velocity[1] = -v;
        if (!o->quiet) printf("dem_biaxial: compression at %.4g /s (lid at %.4g m/s)\n", rate, v);
    }
    snprintf(path, sizeof path, "%s/biaxial.csv", o->out);
    R->csv = fopen(path, "w");
    if (!R->csv) return fprintf(stderr, "dem_biaxial: cannot write %s\n", path), 1;
    fprintf(
        R->csv,
        "eps_axial,sigma_yy_lid,sigma_xx,sigma_yy,eps_vol,stress_ratio,phi_deg,coordination,n_contacts\n");
    t = 0.0;
    for (k = 0;; ++k) {
        double eps = k * o->every, s[9], a, sxx, syy, ratio, z;
        long n;
        int nc = 0;
        db_row *row;
        if (eps > o->strain + 1e-12) break;
        n = (long)floor((eps * R->H0 / v - t) / sc->rve.dt + 0.5);
        if (n > 0) {
            if (gk_scene_step(sc, n)) return db_fail(R);
            R->steps += n;
            t += n * sc->rve.dt;
        }
        H = sc->walls[1].pos[1] - sc->walls[0].pos[1];
        a = enclosed_area(sc, H);
        gk_scene_stress(sc, a, s);
        sxx = -s[0], syy = -s[4];
        ratio = fabs(syy - sxx) / (syy + sxx);
        for (p = 0; p < sc->rve.pl.n; ++p) nc += (sc->rve.cs[p] & GK_CS_CONTACT) != 0;
        z = 2.0 * nc / sc->rve.n;
        if (k == 0) R->z0 = z;
        if (R->nrows == R->caprows) {
            db_row *nrw =
                (db_row *)realloc(R->rows, (size_t)(R->caprows ? 2 * R->caprows : 128) * sizeof *R->rows);
            if (!nrw) return fprintf(stderr, "dem_biaxial: out of memory\n"), 1;
            R->rows = nrw;
            R->caprows = R->caprows ? 2 * R->caprows : 128;
        }
        row = &R->rows[R->nrows];
        row->eps = (R->H0 - H) / R->H0;
        row->syy_lid = sc->walls[1].resistance / (a / H * sc->rve.volume_factor);
        row->sxx = sxx, row->syy = syy, row->ev = (R->A0 - a) / R->A0, row->ratio = ratio;
        row->z = z;
        fprintf(R->csv, "%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.4f,%.4f,%d\n", row->eps, row->syy_lid, sxx, syy,
                row->ev, ratio, asin(ratio < 1 ? ratio : 1) * 180.0 / GK_PI, z, nc);
        if (ratio > R->peak) R->peak = ratio, R->eps_peak = row->eps, R->syy_peak = syy;
        if (!o->quiet && k % 5 == 0)
            printf("eps %.4f  sigma_yy %.5g (lid %.5g)  sigma_xx %.5g Pa  ratio %.4f  eps_v %+.5f  Z %.3f\n",
                   row->eps, syy, row->syy_lid, sxx, ratio, row->ev, z);
        ++R->nrows;
        if (ipic < o->npic && eps >= o->pic[ipic] - 1e-12) {
            char tag[32], title[64];
            snprintf(tag, sizeof tag, "%03d", ipic + 1);
            snprintf(title, sizeof title, "biaxial DNS at %.1f %% axial strain", 100.0 * eps);
            if (dsc_pictures("dem_biaxial", sc, o->out, tag, title)) return 1;
            ++ipic;
        }
    }
    if (fclose(R->csv)) {
        R->csv = NULL;
        return fprintf(stderr, "dem_biaxial: error writing %s/biaxial.csv\n", o->out), 1;
    }
    R->csv = NULL;
    return 0;
}

/* the end pictures, biaxial_stress.svg and the RESULT line; 0 or non-zero (said) */
static int db_report(db_run *R) {
    const db_opts *o = &R->o;
    const db_row *rows = R->rows;
    int k, nrows = R->nrows, status = 0;
    char path[1200];
    if (dsc_pictures("dem_biaxial", &R->sc, o->out, "end", "biaxial DNS, end")) return 1;
    {
        double *x = (double *)malloc((size_t)nrows * sizeof *x),
               *y0 = (double *)malloc((size_t)nrows * sizeof *y0),
               *y1 = (double *)malloc((size_t)nrows * sizeof *y1);
        const double *yy[4];
        const char *lab[4], *rl[1] = {""};
        double ref[1] = {0.0};
        if (!x || !y0 || !y1) {
            fprintf(stderr, "dem_biaxial: out of memory for the plot\n");
            status = 1;
        }
        for (k = 0; !status && k < nrows; ++k)
            x[k] = rows[k].eps, y0[k] = rows[k].ratio, y1[k] = 10.0 * rows[k].ev;
        if (!status) {
            yy[0] = y0, yy[1] = y1, yy[2] = yy[3] = NULL;
            lab[0] = "stress ratio |s_yy - s_xx| / (s_yy + s_xx) (Liu, Bosco & Suiker 2018 eq 40)";
            lab[1] = "10 x volumetric strain (compaction +)";
            lab[2] = lab[3] = NULL;
            snprintf(path, sizeof path, "%s/biaxial_stress.svg", o->out);
            status = dsc_plot("dem_biaxial", path, "DEM biaxial DNS", "axial strain", "", x, nrows, yy, lab,
                              0, ref, rl);
        }
        free(x), free(y0), free(y1);
        if (status) return status;
    }
    printf("RESULT n=%d W=%.5g H0=%.5g peak_ratio=%.4f eps_peak=%.4f phi_peak_deg=%.2f ratio_final=%.4f "
           "syy_peak=%.5g "
           "ev_final=%.5f z0=%.3f steps=%ld dt=%.4g seconds=%.2f\n",
           R->sc.rve.n, R->W, R->H0, R->peak, R->eps_peak, asin(R->peak < 1 ? R->peak : 1) * 180.0 / GK_PI,
           rows[nrows - 1].ratio, R->syy_peak, rows[nrows - 1].ev, R->z0, R->steps, R->sc.rve.dt,
           gk_wtime() - R->t0);
    return 0;
}

int main(int argc, char **argv) {
    static db_run run; /* zeroed: nothing created, no rows, no file */
    db_run *R = &run;
    int k, status;
    R->t0 = gk_wtime();
    R->d = gk_scene_def_default();
    k = parse(argc, argv, &R->o);
    if (k) return k < 0 ? 0 : k;
    if (dsc_mkdir("dem_biaxial", R->o.out)) return 1;
    status = db_setup(R);
    if (!status) status = db_consolidate(R);
    if (!status) status = db_compress(R);
    if (!status) status = db_report(R);
    if (R->csv) fclose(R->csv);
    free(R->rows);
    free(R->chain);
    if (R->created) gk_scene_destroy(&R->sc);
    return status;
}
