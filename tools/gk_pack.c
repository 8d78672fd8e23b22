/* gk_pack - generate a periodic packing and consolidate it to a target stress.
 *
 *   build/gk_pack --dim 2 --n 400 --rmin 0.003 --rmax 0.007 --pressure 1e5 \
 *                 [--consolidation-friction 0 | --target-void-ratio E] --out FILE
 *
 * A random loose cloud (no overlaps) is compressed by a stress servo until
 * every normal stress is within the tolerance of the target and the
 * unbalanced-force ratio is small (as YADE's PeriTriaxController in the seed
 * 000 authors' prepareRVE.py). Friction while consolidating selects the
 * density: 0 gives the densest state; larger values give looser ones.
 * --target-void-ratio searches that friction by bisection (each trial is a
 * full consolidation from the same cloud); a target it cannot reach within
 * 2e-3 is a failure (exit status 1, no packing written). The packing is
 * written in the gk_packing.h text format; the comment lines record
 * material, state and command. A packing that cannot be written completely
 * is an error (exit status 1). */
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
            "  --E, --kt-ratio, --density, --thickness, --damping   material (seed 000 defaults)\n"
            "  --seed S                   random seed (1)\n"
            "  --tol T                    relative stress tolerance (1e-3)\n"
            "  --out FILE                 output packing\n");
}

typedef struct opts {
    int dim, n;
    double rmin, rmax, pressure, mu_cons, target_e, phi, phi_deg, E, ktr, rho, thick, damp, tol;
    unsigned long seed;
    const char *psd, *psd_by, *out;
} opts;

static gk_result consolidate_once(const opts *o, const gk_packing *cloud, double mu_cons, gk_rve *rve,
                                  gk_consolidate_report *rep) {
    gk_rve_def def = gk_rve_def_default();
    gk_consolidate_def cd;
    gk_result r;
    def.mat.young = o->E;
    def.mat.kt_ratio = o->ktr;
    def.mat.density = o->rho;
    def.mat.friction = tan(o->phi) > mu_cons ? tan(o->phi) : mu_cons;
    def.thickness = o->thick;
    def.damping = o->damp;
    r = gk_rve_create(rve, &def, cloud);
    if (r) return r;
    memset(&cd, 0, sizeof cd);
    cd.pressure = o->pressure;
    cd.friction = mu_cons;
    cd.stress_tol = o->tol;
    r = gk_rve_consolidate(rve, &cd, rep);
    if (!r) r = gk_rve_set_friction(rve, tan(o->phi));
    return r;
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
    char comment[2048];
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
    o.psd_by = "mass";
    for (i = 1; i < argc; ++i) {
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
        if (!strcmp(a, "--dim")) bad = int_opt(a, v, &o.dim);
        else if (!strcmp(a, "--n")) bad = int_opt(a, v, &o.n);
        else if (!strcmp(a, "--rmin")) bad = real_opt(a, v, &o.rmin);
        else if (!strcmp(a, "--rmax")) bad = real_opt(a, v, &o.rmax);
        else if (!strcmp(a, "--psd")) o.psd = v;
        else if (!strcmp(a, "--psd-by")) o.psd_by = v;
        else if (!strcmp(a, "--pressure")) bad = real_opt(a, v, &o.pressure);
        else if (!strcmp(a, "--consolidation-friction")) bad = real_opt(a, v, &o.mu_cons);
        else if (!strcmp(a, "--target-void-ratio")) bad = real_opt(a, v, &o.target_e);
        else if (!strcmp(a, "--friction-deg")) bad = real_opt(a, v, &o.phi_deg);
        else if (!strcmp(a, "--friction-angle")) { /* the old radian option, kept for old scripts */
            fprintf(stderr, "gk_pack: --friction-angle (radians) is deprecated: use --friction-deg\n");
            bad = real_opt(a, v, &o.phi);
        }
        else if (!strcmp(a, "--E")) bad = real_opt(a, v, &o.E);
        else if (!strcmp(a, "--kt-ratio")) bad = real_opt(a, v, &o.ktr);
        else if (!strcmp(a, "--density")) bad = real_opt(a, v, &o.rho);
        else if (!strcmp(a, "--thickness")) bad = real_opt(a, v, &o.thick);
        else if (!strcmp(a, "--damping")) bad = real_opt(a, v, &o.damp);
        else if (!strcmp(a, "--seed")) {
            char *e;
            errno = 0;
            o.seed = strtoul(v, &e, 10);
            if (e == v || *e || errno == ERANGE || v[0] == '-') {
                fprintf(stderr, "gk_pack: --seed '%s' is not a non-negative whole number\n", v);
                bad = 1;
            }
        }
        else if (!strcmp(a, "--tol")) bad = real_opt(a, v, &o.tol);
        else if (!strcmp(a, "--out")) o.out = v;
        else {
            fprintf(stderr, "gk_pack: unknown option %s (see --help)\n", a);
            return 2;
        }
        if (bad) return 2;
        ++i;
    }
    if (!o.out) {
        fprintf(stderr, "gk_pack: --out is required (see --help)\n");
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
    if (o.target_e != -1) {
        /* void ratio grows with the consolidation friction: bisect on mu */
        double lo = 0.0, hi = 1.0, best = 1e9, emin = 0.0, emax = 0.0;
        int it;
        for (it = 0; it < 12; ++it) {
            double m = it == 0 ? 0.0 : 0.5 * (lo + hi), e;
            if (consolidate_once(&o, &cloud, m, &rve, &rep)) {
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
                    "gk_pack: void ratio %g not reached: consolidation friction 0 to 1 gave %.4f to %.4f (closest "
                    "%.4f at %.4f); no packing written\n",
                    o.target_e, emin, emax, best, mu);
            gk_packing_free(&cloud);
            return 1;
        }
    } else {
        mu = o.mu_cons;
    }
    if (consolidate_once(&o, &cloud, mu, &rve, &rep)) {
        fprintf(stderr, "gk_pack: %s\n", gk_rve_error(&rve));
        gk_rve_destroy(&rve);
        gk_packing_free(&cloud);
        return 1;
    }
    {
        gk_coordination z;
        gk_homog_coordination(&rve, &z);
        snprintf(comment, sizeof comment,
                 "consolidated by gk_pack: %dD, %d particles, radii %g-%g m, seed %lu\n"
                 "material: linear kn = E r*, E=%g Pa, kt/kn=%g, friction angle %.17g deg (mu %.6g); density %g; "
                 "2D thickness %g; local damping %g\n"
                 "consolidation friction %.6g; target %g Pa isotropic; %ld steps\n"
                 "RVE state: stress (Pa, tension +) sxx=%.6f syy=%.6f%s%.6f sxy=%.6f ; void ratio %.6f ; Z=%.4f "
                 "(YADE skipFree %.6f, mechanical %.4f) ; contacts=%d ; unbalanced=%.3e",
                 o.dim, o.n, o.rmin, o.rmax, o.seed, o.E, o.ktr, o.phi * 180.0 / GK_PI, tan(o.phi), o.rho, o.thick,
                 o.damp, mu,
                 o.pressure, rep.steps, rep.stress[0], rep.stress[4], o.dim == 3 ? " szz=" : " (2D) ",
                 o.dim == 3 ? rep.stress[8] : 0.0, rep.stress[1], rep.void_ratio, z.z, z.z_nofree, z.z_mech,
                 z.contacts, rep.unbalanced);
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
        printf("RESULT void_ratio=%.6f Z=%.4f consolidation_friction=%.6g p=%.6g steps=%ld seconds=%.2f\n",
               rep.void_ratio, z.z, mu, gk_stress_p(rep.stress, o.dim), rep.steps, gk_wtime() - t0);
    }
    gk_packing_free(&pk);
    gk_packing_free(&cloud);
    gk_rve_destroy(&rve);
    return 0;
}
