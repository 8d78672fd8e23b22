/* gk_pack - generate a periodic packing and consolidate it to a target stress.
 *
 *   build/gk_pack --dim 2 --n 400 --rmin 0.003 --rmax 0.007 --pressure 1e5 \
 *                 [--consolidation-friction 0 | --target-void-ratio E] --out FILE
 *   build/gk_pack --dim 3 --n 1000 --rmin 2.15e-4 --rmax 5.9e-4 --pressure 4.16e5 \
 *                 --law hertz --G 2.9e10 --poisson 0.15 --friction-deg 26.565 \
 *                 --density 2492 --dt-factor 0.2 --out FILE     (Hertz-Mindlin)
 *
 * A random loose cloud (no overlaps) is compressed by a stress servo until
 * every normal stress is within the tolerance of the target and the
 * unbalanced-force ratio is small (as YADE's PeriTriaxController in the Guo &
 * Zhao (2014) authors' prepareRVE.py). Friction while consolidating selects the
 * density: 0 gives the densest state; larger values give looser ones.
 * --target-void-ratio searches that friction by bisection (each trial is a
 * full consolidation from the same cloud); a target it cannot reach within
 * 2e-3 is a failure (exit status 1, no packing written). The packing is
 * written in the gk_packing.h text format; the comment lines record
 * material, state and command. A packing that cannot be written completely
 * is an error (exit status 1).
 *
 * ANISOTROPIC PACKINGS (--stress-ratio R, --target-anisotropy A): once
 * consolidated, the packing is loaded with its final friction to
 * sigma_yy = R p (sigma_xx = p) and back to p isotropic: contacts open
 * across the minor stress and friction keeps the network that the deviator
 * made (a frictionless unloading would give the deviator's fabric back).
 * Which way the excess of contact normals points is not controlled: in the
 * framed packings of examples/data (A = 0.016, 0.049, 0.084) the major axis
 * of the fabric lies 8, 128 and 125 degrees from x (phi_yy / phi_xx - 1 =
 * -0.015, 0.011, 0.028). --target-anisotropy searches R
 * (bisection in [1, 2.1], below failure at mu 0.4) for the fabric anisotropy A = Pi_1 / Pi_2 - 1 (Liu,
 * Bosco & Suiker 2018 eq 38) of the final state; with --target-void-ratio
 * the consolidation friction is searched first, then R.
 *
 * FRAMED PACKINGS (--frame K; 2D): one particle is put at the cell corner
 * (0, 0) and K on each of the lines y = 0 and x = 0, evenly spaced, and held
 * on their lines while the cloud is consolidated (they slide along them; the
 * cell stays a box). The result is "geometrically periodic" (Liu, Bosco &
 * Suiker 2018 sec 4.1): cut along the lines, every particle crossing the
 * cell boundary is centred on it and has its image on the opposite side -
 * the frame of boundary particles of their RVE (gk_frame.h builds it from
 * the particles with x = 0 or y = 0 exactly). --kn sets a constant normal
 * stiffness (linear law, N/m) instead of E r*. */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_homog.h"
#include "gk_io.h"
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *fp) {
    fprintf(fp,
            "usage: gk_pack --dim 2|3 --n N --rmin R --rmax R --pressure P --out FILE [options]\n"
            "  --dim, --n                 dimension and particle count (2, 400)\n"
            "  --rmin, --rmax             radius range [m], uniform (0.003, 0.007)\n"
            "  --psd FILE                 size table instead: lines 'radius cumulative_fraction' (0..1)\n"
            "  --psd-by number|mass       what the table's fractions count (mass)\n"
            "  --pressure P               target isotropic stress [Pa], compression positive (1e5)\n"
            "  --consolidation-friction M Coulomb coefficient while consolidating (0: densest)\n"
            "  --target-void-ratio E      search the consolidation friction that gives void ratio E\n"
            "  --friction-deg A           contact friction angle after consolidation [degrees, 0 to 85]\n"
            "                             (28.65 = 0.5 rad, Guo & Zhao 2014)\n"
            "  --E, --kt-ratio, --density, --thickness, --damping   material (Guo & Zhao 2014 defaults)\n"
            "  --law linear|hertz         contact law (linear); hertz: Hertz-Mindlin from --G and --poisson\n"
            "  --G, --poisson             Hertz-Mindlin grain shear modulus [Pa] and Poisson ratio (sets E = "
            "2G(1+nu))\n"
            "  --contact-damping Z        tangential viscous damping, fraction of critical (0)\n"
            "  --max-strain-rate R        consolidation strain-rate cap [1/s] (0: inertial number 1e-2)\n"
            "  --dt-factor F              DEM step as a fraction of the critical step (0.5; Hertz: use 0.2)\n"
            "  --kn K                     linear law with a constant normal stiffness K [N/m] (0: E r*)\n"
            "  --stress-ratio R           then sigma_yy to R sigma_xx and back, with friction (1)\n"
            "  --target-anisotropy A      search the stress ratio that gives fabric anisotropy A (eq 38)\n"
            "  --frame K                  2D: a corner particle and K particles on each of the lines x = 0,\n"
            "                             y = 0, held on their lines while consolidating (a frame)\n"
            "  --seed S                   random seed (1)\n"
            "  --tol T                    relative stress tolerance (1e-3)\n"
            "  --out FILE                 output packing\n");
}

typedef struct opts {
    int dim, n, frame;
    double rmin, rmax, pressure, mu_cons, target_e, phi, phi_deg, E, ktr, rho, thick, damp, tol, G, nu,
        zeta_t, dtf, rate;
    double kn, ratio, target_a;
    int hertz;
    unsigned long seed;
    const char *psd, *psd_by, *out;
} opts;

/* the frame: role of each packing particle, bit 0 on the line x = 0 (slides along y), bit 1 on y = 0 */
static unsigned char *frame_role;

/* holds the frame particles on their lines (gk_dem.h hook; the cell is a box) */
static gk_result frame_hook(gk_rve *rve, int stage, void *user) {
    int p, k;
    (void)user;
    for (p = 0; p < rve->n; ++p) {
        unsigned role = frame_role[rve->id[p]];
        for (k = 0; k < 2; ++k) {
            if (!(role & (1u << k))) continue;
            if (stage == GK_HOOK_POST_FORCES)
                rve->f[k][p] = 0, rve->v[k][p] = 0;
            else if (stage == GK_HOOK_POST_STEP)
                rve->s[k][p] = 0.0;
        }
    }
    return GK_OK;
}

/* fabric anisotropy A = Pi_1 / Pi_2 - 1 (eq 38) of an RVE */
static double anisotropy(const gk_rve *rve) {
    double phi[9], Fa[9];
    gk_homog_fabric(rve, phi, Fa);
    return gk_fabric_ratio(phi, rve->dim);
}

static gk_result consolidate_once(const opts *o, const gk_packing *cloud, double mu_cons, double ratio,
                                  gk_rve *rve, gk_consolidate_report *rep) {
    gk_rve_def def = gk_rve_def_default();
    gk_consolidate_def cd;
    gk_result r;
    long steps = 0;
    def.mat.kn = o->kn;
    def.mat.young = o->hertz ? 2.0 * o->G * (1.0 + o->nu) : o->E;
    def.mat.law = o->hertz ? GK_LAW_HERTZ : GK_LAW_LINEAR;
    def.mat.poisson = o->nu;
    def.mat.zeta_t = o->zeta_t;
    def.dt_factor = o->dtf;
    def.mat.kt_ratio = o->ktr;
    def.mat.density = o->rho;
    def.mat.friction = tan(o->phi) > mu_cons ? tan(o->phi) : mu_cons;
    def.thickness = o->thick;
    def.damping = o->damp;
    r = gk_rve_create(rve, &def, cloud);
    if (r) return r;
    if (o->frame) rve->hook = frame_hook;
    memset(&cd, 0, sizeof cd);
    cd.pressure = o->pressure;
    cd.friction = mu_cons;
    cd.stress_tol = o->tol;
    cd.max_strain_rate = o->rate;
    cd.box = o->frame > 0;
    r = gk_rve_consolidate(rve, &cd, rep);
    if (!r && ratio != 1.0) { /* a frictional deviator cycle: sigma_yy to R p and back */
        steps = rep->steps;
        cd.friction = tan(o->phi);
        cd.ratio[1] = ratio;
        r = gk_rve_consolidate(rve, &cd, rep);
        steps += rep->steps;
        cd.ratio[1] = 1.0;
        if (!r) r = gk_rve_consolidate(rve, &cd, rep);
        rep->steps += steps;
    }
    if (!r) r = gk_rve_set_friction(rve, tan(o->phi));
    rve->hook = NULL;
    return r;
}

/* --frame K: the corner particle and K particles on each line, chosen at random and spaced evenly; every
 * other particle they overlap is moved to a free random place */
static int make_frame(const opts *o, gk_packing *pk) {
    gk_rng rng;
    int n = pk->n, nf = 2 * o->frame + 1, k, p, q, tries;
    double L[2];
    L[0] = pk->h[0], L[1] = pk->h[4];
    if (pk->dim != 2 || pk->h[1] != 0.0 || pk->h[3] != 0.0) {
        fprintf(stderr, "gk_pack: --frame needs a 2D box cell\n");
        return 1;
    }
    if (nf > n / 2) {
        fprintf(stderr, "gk_pack: --frame %d needs more than %d particles (--n %d)\n", o->frame, 2 * nf, n);
        return 1;
    }
    frame_role = (unsigned char *)calloc((size_t)n, 1);
    if (!frame_role) return 1;
    gk_rng_seed(&rng, (uint64_t)o->seed * 7919u + 17u);
    for (k = 0; k < nf; ++k) {
        do p = (int)(gk_rng_u64(&rng) % (uint64_t)n);
        while (frame_role[p]);
        if (k == 0) { /* the corner */
            frame_role[p] = 3, pk->x[p] = 0.0, pk->y[p] = 0.0;
        } else if (k <= o->frame) { /* on y = 0, sliding along x */
            frame_role[p] = 2, pk->x[p] = L[0] * k / (o->frame + 1), pk->y[p] = 0.0;
        } else { /* on x = 0, sliding along y */
            frame_role[p] = 1, pk->x[p] = 0.0, pk->y[p] = L[1] * (k - o->frame) / (o->frame + 1);
        }
    }
    for (p = 0; p < n; ++p) /* what overlaps a frame particle moves to a free place (frames never move) */
        for (tries = 0;; ++tries) {
            int clash = 0;
            for (q = 0; q < n && !clash; ++q) {
                double dx = pk->x[q] - pk->x[p], dy = pk->y[q] - pk->y[p], R = pk->r[p] + pk->r[q];
                if (q == p || (frame_role[p] && !frame_role[q])) continue; /* the other one moves */
                dx -= L[0] * rint(dx / L[0]), dy -= L[1] * rint(dy / L[1]);
                clash = dx * dx + dy * dy < R * R;
            }
            if (!clash) break;
            if (frame_role[p] || tries == 1000000) {
                fprintf(stderr,
                        "gk_pack: no room for particle %d next to the frame (fewer frame particles?)\n", p);
                return 1;
            }
            pk->x[p] = L[0] * gk_rng_uniform(&rng), pk->y[p] = L[1] * gk_rng_uniform(&rng);
        }
    return 0;
}

/* a real or whole-number option value, strictly ('1e5x', '', 'nan', out of range: refused by name) */
static int real_opt(const char *a, const char *v, double *out) {
    char *e;
    errno = 0;
    *out = strtod(v, &e);
    if (e == v || *e || errno == ERANGE || !isfinite(*out)) {
        fprintf(stderr, "gk_pack: %s '%s' is not a finite number\n", a, v);
        return 1;
    }
    return 0;
}
static int int_opt(const char *a, const char *v, int *out) {
    char *e;
    long x;
    errno = 0;
    x = strtol(v, &e, 10);
    if (e == v || *e || errno == ERANGE || x < INT_MIN || x > INT_MAX) {
        fprintf(stderr, "gk_pack: %s '%s' is not a whole number\n", a, v);
        return 1;
    }
    *out = (int)x;
    return 0;
}

int main(int argc, char **argv) {
    opts o;
    gk_gen_def g;
    gk_packing cloud, pk;
    gk_err err;
    gk_rve rve;
    gk_consolidate_report rep;
    double tab_r[256], tab_c[256], t0 = gk_wtime(), mu = 0.0;
    int i, ntab = 0;
    char comment[4096];
    memset(&o, 0, sizeof o);
    memset(&rve, 0, sizeof rve); /* gk_rve_destroy is safe on it before a create and after a failed one */
    o.dim = 2;
    o.n = 400;
    o.rmin = 0.003;
    o.rmax = 0.007;
    o.pressure = 1e5;
    o.target_e = -1; /* not given */
    o.phi = 0.5;
    o.phi_deg = -1; /* not given */
    o.E = 6e8;
    o.ktr = 0.8;
    o.rho = 2650;
    o.thick = 0.1;
    o.damp = 0.1;
    o.tol = 1e-3;
    o.seed = 1;
    o.nu = 0.25;
    o.dtf = 0.5;
    o.psd_by = "mass";
    o.ratio = 1.0;
    o.target_a = -1;
    for (i = 1; i < argc; i += 2) { /* every option takes a value */
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int bad = 0;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        }
        if (!v) {
            fprintf(stderr, "gk_pack: %s needs a value\n", a);
            return 2;
        }
        if (!strcmp(a, "--dim"))
            bad = int_opt(a, v, &o.dim);
        else if (!strcmp(a, "--n"))
            bad = int_opt(a, v, &o.n);
        else if (!strcmp(a, "--rmin"))
            bad = real_opt(a, v, &o.rmin);
        else if (!strcmp(a, "--rmax"))
            bad = real_opt(a, v, &o.rmax);
        else if (!strcmp(a, "--psd"))
            o.psd = v;
        else if (!strcmp(a, "--psd-by"))
            o.psd_by = v;
        else if (!strcmp(a, "--pressure"))
            bad = real_opt(a, v, &o.pressure);
        else if (!strcmp(a, "--consolidation-friction"))
            bad = real_opt(a, v, &o.mu_cons);
        else if (!strcmp(a, "--target-void-ratio"))
            bad = real_opt(a, v, &o.target_e);
        else if (!strcmp(a, "--friction-deg"))
            bad = real_opt(a, v, &o.phi_deg);
        else if (!strcmp(a, "--friction-angle")) { /* the old radian option, kept for old scripts */
            fprintf(stderr, "gk_pack: --friction-angle (radians) is deprecated: use --friction-deg\n");
            bad = real_opt(a, v, &o.phi);
        } else if (!strcmp(a, "--E"))
            bad = real_opt(a, v, &o.E);
        else if (!strcmp(a, "--kt-ratio"))
            bad = real_opt(a, v, &o.ktr);
        else if (!strcmp(a, "--density"))
            bad = real_opt(a, v, &o.rho);
        else if (!strcmp(a, "--thickness"))
            bad = real_opt(a, v, &o.thick);
        else if (!strcmp(a, "--damping"))
            bad = real_opt(a, v, &o.damp);
        else if (!strcmp(a, "--G"))
            bad = real_opt(a, v, &o.G);
        else if (!strcmp(a, "--poisson"))
            bad = real_opt(a, v, &o.nu);
        else if (!strcmp(a, "--contact-damping"))
            bad = real_opt(a, v, &o.zeta_t);
        else if (!strcmp(a, "--dt-factor"))
            bad = real_opt(a, v, &o.dtf);
        else if (!strcmp(a, "--max-strain-rate"))
            bad = real_opt(a, v, &o.rate);
        else if (!strcmp(a, "--law")) {
            if (!strcmp(v, "hertz"))
                o.hertz = 1;
            else if (strcmp(v, "linear")) {
                fprintf(stderr, "gk_pack: --law '%s' is neither linear nor hertz\n", v);
                bad = 1;
            }
        } else if (!strcmp(a, "--seed")) {
            char *e;
            errno = 0;
            o.seed = strtoul(v, &e, 10);
            if (e == v || *e || errno == ERANGE || v[0] == '-') {
                fprintf(stderr, "gk_pack: --seed '%s' is not a non-negative whole number\n", v);
                bad = 1;
            }
        } else if (!strcmp(a, "--tol"))
            bad = real_opt(a, v, &o.tol);
        else if (!strcmp(a, "--kn"))
            bad = real_opt(a, v, &o.kn);
        else if (!strcmp(a, "--stress-ratio"))
            bad = real_opt(a, v, &o.ratio);
        else if (!strcmp(a, "--target-anisotropy"))
            bad = real_opt(a, v, &o.target_a);
        else if (!strcmp(a, "--frame"))
            bad = int_opt(a, v, &o.frame);
        else if (!strcmp(a, "--out"))
            o.out = v;
        else {
            fprintf(stderr, "gk_pack: unknown option %s (see --help)\n", a);
            return 2;
        }
        if (bad) return 2;
    }
    if (o.hertz && !(o.G > 0.0)) {
        fprintf(stderr, "gk_pack: --law hertz needs --G > 0 (grain shear modulus)\n");
        return 2;
    }
    if (!o.out) {
        fprintf(stderr, "gk_pack: --out is required (see --help)\n");
        return 2;
    }
    if (o.kn < 0 || !(o.ratio > 0)) {
        fprintf(stderr, "gk_pack: --kn %g must be >= 0, --stress-ratio %g > 0\n", o.kn, o.ratio);
        return 2;
    }
    if (o.frame < 0 || (o.frame > 0 && o.dim != 2)) {
        fprintf(stderr, "gk_pack: --frame %d: a whole number >= 0, 2D only\n", o.frame);
        return 2;
    }
    if (o.phi_deg != -1) o.phi = o.phi_deg * GK_PI / 180.0;
    if (!(o.phi >= 0.0 && o.phi <= 85.0 * GK_PI / 180.0)) { /* 35 meant as radians is refused */
        fprintf(stderr, "gk_pack: friction angle %g degrees: a contact friction angle is 0 to 85 degrees\n",
                o.phi * 180.0 / GK_PI);
        return 2;
    }
    if (o.target_e != -1 && !(o.target_e > 0.0)) {
        fprintf(stderr, "gk_pack: --target-void-ratio %g must be > 0\n", o.target_e);
        return 2;
    }
    memset(&g, 0, sizeof g);
    g.dim = o.dim;
    g.n = o.n;
    g.seed = o.seed;
    g.r_min = o.rmin;
    g.r_max = o.rmax;
    if (o.psd) {
        FILE *fp = fopen(o.psd, "r");
        char line[256];
        int lineno = 0;
        if (!fp) {
            fprintf(stderr, "gk_pack: cannot open %s\n", o.psd);
            return 1;
        }
        /* strictly: 'radius fraction' per line, '#' comments and blank lines, at most 256 rows */
        while (fgets(line, sizeof line, fp)) {
            char extra[2];
            ++lineno;
            if (!strchr(line, '\n') && !feof(fp)) {
                fprintf(stderr, "gk_pack: %s line %d is longer than %d characters\n", o.psd, lineno,
                        (int)sizeof line - 2);
                fclose(fp);
                return 1;
            }
            if (line[strspn(line, " \t\r\n")] == '\0' || line[strspn(line, " \t")] == '#') continue;
            if (ntab == 256 || sscanf(line, "%lf %lf %1s", &tab_r[ntab], &tab_c[ntab], extra) != 2) {
                fprintf(stderr, "gk_pack: %s line %d: %s\n", o.psd, lineno,
                        ntab == 256 ? "more than 256 rows" : "expected 'radius cumulative_fraction'");
                fclose(fp);
                return 1;
            }
            ++ntab;
        }
        if (ferror(fp)) {
            fprintf(stderr, "gk_pack: cannot read %s\n", o.psd);
            fclose(fp);
            return 1;
        }
        fclose(fp);
        g.psd = !strcmp(o.psd_by, "number") ? GK_PSD_TABLE_NUMBER : GK_PSD_TABLE_MASS;
        g.ntable = ntab;
        g.table_r = tab_r;
        g.table_cum = tab_c;
    }
    if (gk_packing_generate(&cloud, &g, NULL, &err)) {
        fprintf(stderr, "gk_pack: %s\n", err.msg);
        return 1;
    }
    if (o.frame && make_frame(&o, &cloud)) return 1;
    if (o.target_e != -1) {
        /* void ratio grows with the consolidation friction: bisect on mu */
        double lo = 0.0, hi = 1.0, best = 1e9, emin = 0.0, emax = 0.0;
        int it;
        for (it = 0; it < 12; ++it) {
            double m = it == 0 ? 0.0 : 0.5 * (lo + hi), e;
            if (consolidate_once(&o, &cloud, m, o.target_a >= 0 ? 1.0 : o.ratio, &rve, &rep)) {
                fprintf(stderr, "gk_pack: %s\n", gk_rve_error(&rve));
                gk_rve_destroy(&rve);
                gk_packing_free(&cloud);
                return 1;
            }
            e = rep.void_ratio;
            if (it == 0 || e < emin) emin = e;
            if (it == 0 || e > emax) emax = e;
            fprintf(stderr, "gk_pack: consolidation friction %.4f -> void ratio %.4f\n", m, e);
            gk_rve_destroy(&rve);
            if (fabs(e - o.target_e) < fabs(best - o.target_e)) {
                best = e;
                mu = m;
            }
            if (it == 0 && e >= o.target_e) break; /* densest state is already looser than asked */
            if (fabs(e - o.target_e) < 2e-4) break;
            if (e < o.target_e)
                lo = m;
            else
                hi = m;
        }
        if (fabs(best - o.target_e) > 2e-3) {
            fprintf(stderr,
                    "gk_pack: void ratio %g not reached: consolidation friction 0 to 1 gave %.4f to %.4f "
                    "(closest "
                    "%.4f at %.4f); no packing written\n",
                    o.target_e, emin, emax, best, mu);
            gk_packing_free(&cloud);
            return 1;
        }
    } else {
        mu = o.mu_cons;
    }
    if (o.target_a >= 0) {
        /* the anisotropy kept grows with the stress ratio of the first consolidation: bisect on R */
        double lo = 1.0, hi = 2.1, best = 1e9; /* above ~2.3 the packing fails in shear (mu 0.4) */
        int it;
        for (it = 0; it < 14; ++it) {
            double R = it == 0 ? 1.0 : 0.5 * (lo + hi), A;
            if (consolidate_once(&o, &cloud, mu, R, &rve, &rep)) {
                fprintf(stderr, "gk_pack: %s\n", gk_rve_error(&rve));
                return 1;
            }
            A = anisotropy(&rve);
            fprintf(stderr, "gk_pack: stress ratio %.4f -> anisotropy %.4f, void ratio %.4f\n", R, A,
                    rep.void_ratio);
            gk_rve_destroy(&rve);
            if (fabs(A - o.target_a) < fabs(best - o.target_a)) best = A, o.ratio = R;
            if (fabs(A - o.target_a) < 2e-3) break;
            if (A < o.target_a)
                lo = R;
            else
                hi = R;
        }
        if (fabs(best - o.target_a) > 5e-3)
            fprintf(stderr, "gk_pack: warning: closest anisotropy %.4f is %.4f from the target %.4f\n", best,
                    fabs(best - o.target_a), o.target_a);
    }
    if (consolidate_once(&o, &cloud, mu, o.ratio, &rve, &rep)) {
        fprintf(stderr, "gk_pack: %s\n", gk_rve_error(&rve));
        gk_rve_destroy(&rve);
        gk_packing_free(&cloud);
        return 1;
    }
    {
        gk_coordination z;
        gk_homog_coordination(&rve, &z);
        char law[256], cmd[768], ratio_txt[128] = "", frame_txt[256] = "", fabric_txt[192];
        double phi[9], Fa[9], A;
        size_t len = 0;
        int a;
        gk_homog_fabric(&rve, phi, Fa); /* the contact-normal fabric, written with its A (eq 38) */
        A = gk_fabric_ratio(phi, o.dim);
        snprintf(fabric_txt, sizeof fabric_txt, "xx %.6f yy %.6f zz %.6f xy %.6f yz %.6f xz %.6f", phi[0],
                 phi[4], phi[8], phi[1], phi[5], phi[2]);
        if (o.ratio != 1.0)
            snprintf(ratio_txt, sizeof ratio_txt,
                     ", then sigma_yy to %.6g sigma_xx and back with friction %.6g", o.ratio, tan(o.phi));
        if (o.frame)
            snprintf(frame_txt, sizeof frame_txt,
                     "\nframe: %d particles at the corner and on the lines x = 0, y = 0 (held there while "
                     "consolidating): x = 0 or y = 0 exactly",
                     2 * o.frame + 1);
        if (o.hertz)
            snprintf(law, sizeof law,
                     "Hertz-Mindlin G=%g Pa, nu=%g (E=%g Pa), tangential damping %g of critical", o.G, o.nu,
                     2.0 * o.G * (1.0 + o.nu), o.zeta_t);
        else if (o.kn > 0)
            snprintf(law, sizeof law, "linear kn = %g N/m, kt/kn=%g", o.kn, o.ktr);
        else
            snprintf(law, sizeof law, "linear kn = E r*, E=%g Pa, kt/kn=%g", o.E, o.ktr);
        cmd[0] = 0;
        for (a = 0; a < argc && len + 2 < sizeof cmd; ++a) { /* the command, truncated if very long */
            int w = snprintf(cmd + len, sizeof cmd - len, "%s%s", a ? " " : "", argv[a]);
            if (w < 0) break;
            len += (size_t)w;
        }
        snprintf(
            comment, sizeof comment,
            "consolidated by gk_pack: %dD, %d particles, radii %g-%g m, seed %lu\n"
            "command: %s\n"
            "material: %s, friction angle %.17g deg (mu %.6g); density %g; "
            "2D thickness %g; local damping %g\n"
            "consolidation friction %.6g; target %g Pa isotropic%s; %ld steps\n"
            "fabric anisotropy A = Pi_1/Pi_2 - 1 = %.4f (Liu, Bosco & Suiker 2018 eq 38)\n"
            "fabric tensor phi = sum n n / N_c: %s%s\n"
            "RVE state: stress (Pa, tension +) sxx=%.6f syy=%.6f%s%.6f sxy=%.6f ; void ratio %.6f "
            "(porosity %.6f) ; Z=%.4f (YADE skipFree %.6f, mechanical %.4f) ; contacts=%d ; unbalanced=%.3e",
            o.dim, o.n, o.rmin, o.rmax, o.seed, cmd, law, o.phi * 180.0 / GK_PI, tan(o.phi), o.rho, o.thick,
            o.damp, mu, o.pressure, ratio_txt, rep.steps, A, fabric_txt, frame_txt, rep.stress[0],
            rep.stress[4], o.dim == 3 ? " szz=" : " (2D) ", o.dim == 3 ? rep.stress[8] : 0.0, rep.stress[1],
            rep.void_ratio, rep.void_ratio / (1.0 + rep.void_ratio), z.z, z.z_nofree, z.z_mech, z.contacts,
            rep.unbalanced);
        if (gk_rve_to_packing(&rve, &pk, NULL, &err)) {
            fprintf(stderr, "gk_pack: %s\n", err.msg);
            gk_rve_destroy(&rve);
            gk_packing_free(&cloud);
            return 1;
        }
        if (gk_packing_write(o.out, &pk, comment, &err)) {
            fprintf(stderr, "gk_pack: %s\n", err.msg);
            gk_packing_free(&pk);
            gk_rve_destroy(&rve);
            gk_packing_free(&cloud);
            return 1;
        }
        printf("RESULT void_ratio=%.6f porosity=%.6f Z=%.4f Z_mech=%.4f consolidation_friction=%.6g p=%.6g "
               "anisotropy=%.4f stress_ratio=%.6g steps=%ld seconds=%.2f\n",
               rep.void_ratio, rep.void_ratio / (1.0 + rep.void_ratio), z.z, z.z_mech, mu,
               gk_stress_p(rep.stress, o.dim), A, o.ratio, rep.steps, gk_wtime() - t0);
    }
    gk_packing_free(&pk);
    gk_packing_free(&cloud);
    gk_rve_destroy(&rve);
    free(frame_role);
    return 0;
}
