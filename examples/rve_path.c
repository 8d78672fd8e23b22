/* rve_path - load one periodic RVE along a displacement-gradient path.
 *
 *   build/rve_path --packing FILE --dH "H00 H01 H10 H11" --increments N \
 *       --steps-per-increment S [--E 6e8] [--kt-ratio 0.8] [--friction-deg 28.65] \
 *       [--density 2650] [--thickness 0.1] [--damping 0.1] [--damping-form component|vector] \
 *       [--dt DT] [--law linear|hertz] [--poisson 0.25] [--path constant-L|objective] \
 *       [--threads T] [--out FILE.csv] [--svg FILE.svg]
 *
 * Applies dH (row-major, H01 = du_x/dy; 9 numbers for a 3D packing) N times,
 * each over S DEM steps as a constant velocity gradient L = dH / (S dt) -
 * exactly how the Guo & Zhao 2014 authors' code (YADE FEMxDEM) loads an RVE - and
 * writes after every increment one CSV row:
 *   2D: inc,H00,H01,H10,H11,sxx,syy,sxy,p,q,e_void,Z
 *   3D: inc,H00,...,H22,sxx,syy,szz,syz,sxz,sxy,p,q,e_void,Z
 * H is the accumulated applied gradient (sum of the increments, the paper's
 * convention); stresses in Pa, COMPRESSION POSITIVE (grainkit is tension-
 * positive inside; the sign is flipped here); p = -tr(sigma)/dim, q as Guo & Zhao 2014
 * eq 7 (2D) or sqrt(3/2 s:s) (3D); Z = 2 contacts / particles.
 * Defaults are the Guo & Zhao 2014 material; with no --dt it uses 0.5 x the critical
 * step of Guo & Zhao 2014 eq 19. It also writes an SVG plot of q/p against the
 * deviatoric strain eps_q of the accumulated H (Guo & Zhao 2014 eq 13).
 * A result that cannot be written completely (--out /dev/full, a full disk)
 * is an error: exit status 1. */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_homog.h"
#include "gk_io.h"
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *fp) {
    fprintf(fp,
            "usage: rve_path --packing FILE --dH \"H00 H01 H10 H11\" --increments N --steps-per-increment S\n"
            "                [--E 6e8] [--kt-ratio 0.8] [--friction-deg 28.65] [--density 2650]\n"
            "                [--thickness 0.1] [--damping 0.1] [--damping-form component|vector]\n"
            "                [--dt DT] [--law linear|hertz] [--poisson 0.25] [--path constant-L|objective]\n"
            "                [--threads T] [--out FILE.csv] [--svg FILE.svg]\n"
            "\n"
            "  --packing FILE           packing in the shared/data format (2D: 'x y r', 3D: 'x y z r')\n"
            "  --dH \"...\"               displacement-gradient increment, row-major, H01 = du_x/dy\n"
            "                           (4 numbers in 2D, 9 in 3D)\n"
            "  --increments N           how many times dH is applied (default 10)\n"
            "  --steps-per-increment S  DEM steps per increment (default 100)\n"
            "  --E                      contact modulus [Pa]: linear kn = E r*, r* = 2 r1 r2/(r1 + r2) (6e8)\n"
            "  --kt-ratio               kt / kn of the linear law (0.8)\n"
            "  --friction-deg           contact friction angle [degrees, 0 to 85], mu = tan(angle)\n"
            "                           (28.65 = 0.5 rad, Guo & Zhao 2014)\n"
            "  --density                particle density [kg/m^3] (2650)\n"
            "  --thickness              2D disk thickness [m]: m = rho t pi r^2, volume = area t (0.1)\n"
            "  --damping                local non-viscous damping alpha (0.1)\n"
            "  --damping-form           component (YADE/PFC, default) or vector (Guo & Zhao 2014 eq 18)\n"
            "  --dt                     time step [s] (default 0.5 x critical, Guo & Zhao 2014 eq 19)\n"
            "  --law                    linear (Guo & Zhao 2014) or hertz (Hertz-Mindlin, G = E/(2(1+poisson)))\n"
            "  --poisson                Poisson ratio for the Hertz law (0.25)\n"
            "  --path                   constant-L (default, the paper authors') or objective (ends exactly at I + dH)\n"
            "  --threads T              threads inside the RVE (results identical for any T)\n"
            "  --out FILE.csv           CSV output (default rve_path.csv)\n"
            "  --svg FILE.svg           q/p plot (default: the CSV name with .svg)\n");
}

static int parse_numbers(const char *s, double *out, int max) {
    int n = 0;
    char *e;
    while (*s) {
        double v;
        while (*s == ' ' || *s == ',' || *s == '\t') ++s;
        if (!*s) break;
        v = strtod(s, &e);
        if (e == s || !isfinite(v)) return -1;
        if (n < max) out[n] = v;
        ++n;
        s = e;
    }
    return n;
}

/* a real or whole-number option value, strictly ('1e9x', '', 'nan', out of range: refused by name) */
static int real_opt(const char *a, const char *v, double *out) {
    char *e;
    errno = 0;
    *out = strtod(v, &e);
    if (e == v || *e || errno == ERANGE || !isfinite(*out)) {
        fprintf(stderr, "rve_path: %s '%s' is not a finite number\n", a, v);
        return 1;
    }
    return 0;
}
static int long_opt(const char *a, const char *v, long *out) {
    char *e;
    errno = 0;
    *out = strtol(v, &e, 10);
    if (e == v || *e || errno == ERANGE) {
        fprintf(stderr, "rve_path: %s '%s' is not a whole number\n", a, v);
        return 1;
    }
    return 0;
}

int main(int argc, char **argv) {
    const char *packing = NULL, *dhs = NULL, *out = "rve_path.csv", *svg = NULL, *law = "linear", *form = "component",
               *path = "constant-L";
    double E = 6e8, ktr = 0.8, phi = 0.5, phi_deg = -1.0, rho = 2650, thick = 0.1, damp = 0.1, dt = 0, poisson = 0.25, dHin[9],
           dH[9], Hacc[9], t0;
    long ninc = 10, nsteps = 100;
    int threads = 1, i, nd, dim, k;
    gk_packing pk;
    gk_err err;
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    FILE *fp = NULL;
    double *xs = NULL, *qp = NULL;
    gk_result res;
    int rc = 1;
    char svgname[1024];
    for (i = 1; i < argc; i += 2) { /* an option and its value */
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        int bad = 0;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        }
        if (!v) {
            fprintf(stderr, "rve_path: %s needs a value (see --help)\n", a);
            return 2;
        }
        if (!strcmp(a, "--packing")) packing = v;
        else if (!strcmp(a, "--dH")) dhs = v;
        else if (!strcmp(a, "--increments")) bad = long_opt(a, v, &ninc);
        else if (!strcmp(a, "--steps-per-increment")) bad = long_opt(a, v, &nsteps);
        else if (!strcmp(a, "--E")) bad = real_opt(a, v, &E);
        else if (!strcmp(a, "--kt-ratio")) bad = real_opt(a, v, &ktr);
        else if (!strcmp(a, "--friction-deg")) bad = real_opt(a, v, &phi_deg);
        else if (!strcmp(a, "--friction-angle")) { /* the old radian option, kept for old scripts */
            fprintf(stderr, "rve_path: --friction-angle (radians) is deprecated: use --friction-deg\n");
            bad = real_opt(a, v, &phi);
        }
        else if (!strcmp(a, "--density")) bad = real_opt(a, v, &rho);
        else if (!strcmp(a, "--thickness")) bad = real_opt(a, v, &thick);
        else if (!strcmp(a, "--damping")) bad = real_opt(a, v, &damp);
        else if (!strcmp(a, "--damping-form")) form = v;
        else if (!strcmp(a, "--dt")) bad = real_opt(a, v, &dt);
        else if (!strcmp(a, "--law")) law = v;
        else if (!strcmp(a, "--poisson")) bad = real_opt(a, v, &poisson);
        else if (!strcmp(a, "--path")) path = v;
        else if (!strcmp(a, "--threads")) {
            long t = 0;
            bad = long_opt(a, v, &t);
            if (!bad && (t < 1 || t > 4096)) {
                fprintf(stderr, "rve_path: --threads %ld: needs 1 to 4096\n", t);
                bad = 1;
            }
            threads = (int)t;
        }
        else if (!strcmp(a, "--out")) out = v;
        else if (!strcmp(a, "--svg")) svg = v;
        else {
            fprintf(stderr, "rve_path: unknown option %s (see --help)\n", a);
            return 2;
        }
        if (bad) return 2;
    }
    if (!packing || !dhs) {
        fprintf(stderr, "rve_path: --packing and --dH are required (see --help)\n");
        return 2;
    }
    if (ninc < 1 || ninc > 100000000L || nsteps < 1 || nsteps > 2000000000L) {
        fprintf(stderr, "rve_path: --increments (1 to 1e8) and --steps-per-increment (1 to 2e9) out of range\n");
        return 2;
    }
    if (phi_deg != -1.0) phi = phi_deg * GK_PI / 180.0;
    if (!(phi >= 0.0 && phi <= 85.0 * GK_PI / 180.0)) { /* 35 meant as radians is refused */
        fprintf(stderr, "rve_path: friction angle %g degrees: a contact friction angle is 0 to 85 degrees\n",
                phi * 180.0 / GK_PI);
        return 2;
    }
    nd = parse_numbers(dhs, dHin, 9);
    if (nd < 0) {
        fprintf(stderr, "rve_path: --dH '%s' is not a list of finite numbers\n", dhs);
        return 2;
    }
    def.mat.young = E;
    def.mat.kt_ratio = ktr;
    def.mat.friction = tan(phi);
    def.mat.density = rho;
    def.mat.poisson = poisson;
    if (!strcmp(law, "linear")) def.mat.law = GK_LAW_LINEAR;
    else if (!strcmp(law, "hertz")) def.mat.law = GK_LAW_HERTZ;
    else {
        fprintf(stderr, "rve_path: --law must be linear or hertz\n");
        return 2;
    }
    if (!strcmp(form, "component")) def.damping_form = GK_DAMP_COMPONENT;
    else if (!strcmp(form, "vector")) def.damping_form = GK_DAMP_VECTOR;
    else {
        fprintf(stderr, "rve_path: --damping-form must be component or vector\n");
        return 2;
    }
    if (!strcmp(path, "constant-L")) def.path = GK_PATH_CONSTANT_L;
    else if (!strcmp(path, "objective")) def.path = GK_PATH_OBJECTIVE;
    else {
        fprintf(stderr, "rve_path: --path must be constant-L or objective\n");
        return 2;
    }
    def.thickness = thick;
    def.damping = damp;
    def.dt = dt;
    def.threads = threads;
    if (gk_packing_read(packing, &pk, NULL, &err)) {
        fprintf(stderr, "rve_path: %s\n", err.msg);
        return 1;
    }
    dim = pk.dim;
    if (nd != dim * dim) {
        fprintf(stderr, "rve_path: --dH needs %d numbers for a %dD packing, got %d\n", dim * dim, dim, nd);
        gk_packing_free(&pk);
        return 2;
    }
    gk_m3_zero(dH);
    for (i = 0; i < dim; ++i)
        for (k = 0; k < dim; ++k) dH[3 * i + k] = dHin[dim * i + k];
    res = gk_rve_create(&rve, &def, &pk);
    gk_packing_free(&pk);
    if (res) {
        fprintf(stderr, "rve_path: %s\n", gk_rve_error(&rve));
        return 1;
    }
    /* from here every exit frees what it holds (rc 1: a failed step or a result not written) */
    xs = (double *)malloc((size_t)(ninc + 1) * sizeof(double));
    qp = (double *)malloc((size_t)(ninc + 1) * sizeof(double));
    fp = fopen(out, "w");
    if (!fp || !xs || !qp) {
        if (fp)
            fprintf(stderr, "rve_path: out of memory\n");
        else
            fprintf(stderr, "rve_path: cannot write %s\n", out);
        goto done;
    }
    if (dim == 2)
        fprintf(fp, "inc,H00,H01,H10,H11,sxx,syy,sxy,p,q,e_void,Z\n");
    else
        fprintf(fp, "inc,H00,H01,H02,H10,H11,H12,H20,H21,H22,sxx,syy,szz,syz,sxz,sxy,p,q,e_void,Z\n");
    fprintf(stderr, "rve_path: %d %s, %s law, dt %.4g s (critical %.4g s), %ld x %ld steps\n", rve.n,
            dim == 2 ? "disks" : "spheres", law, rve.dt, rve.dt_crit, ninc, nsteps);
    gk_m3_zero(Hacc);
    t0 = gk_wtime();
    if (gk_rve_refresh(&rve)) {
        fprintf(stderr, "rve_path: %s\n", gk_rve_error(&rve));
        goto done;
    }
    for (i = 0; i <= ninc; ++i) {
        double s[9], p, q, Z;
        if (i > 0) {
            if (gk_rve_deform(&rve, dH, (int)nsteps)) {
                fprintf(stderr, "rve_path: increment %d: %s\n", i, gk_rve_error(&rve));
                goto done;
            }
            for (k = 0; k < 9; ++k) Hacc[k] += dH[k];
        }
        gk_rve_stress(&rve, s);
        p = gk_stress_p(s, dim);
        q = gk_stress_q(s, dim);
        Z = 2.0 * rve.ncontacts / rve.n;
        fprintf(fp, "%d", i);
        for (k = 0; k < dim * dim; ++k) fprintf(fp, ",%.9g", Hacc[3 * (k / dim) + k % dim]);
        if (dim == 2)
            fprintf(fp, ",%.9g,%.9g,%.9g", -s[0], -s[4], -0.5 * (s[1] + s[3]));
        else
            fprintf(fp, ",%.9g,%.9g,%.9g,%.9g,%.9g,%.9g", -s[0], -s[4], -s[8], -0.5 * (s[5] + s[7]),
                    -0.5 * (s[2] + s[6]), -0.5 * (s[1] + s[3]));
        fprintf(fp, ",%.9g,%.9g,%.9g,%.9g\n", p, q, gk_homog_void_ratio(&rve), Z);
        xs[i] = gk_strain_q(Hacc, dim);
        qp[i] = p > 0 ? q / p : 0.0;
    }
    res = gk_file_close(fp, out, &err);
    fp = NULL;
    if (res) {
        fprintf(stderr, "rve_path: %s\n", err.msg);
        goto done;
    }
    {
        gk_plot pl;
        size_t L = strlen(out);
        if (!svg) {
            if (L > 4 && !strcmp(out + L - 4, ".csv") && L < sizeof svgname) {
                memcpy(svgname, out, L - 4);
                strcpy(svgname + L - 4, ".svg");
            } else {
                snprintf(svgname, sizeof svgname, "%s.svg", out);
            }
            svg = svgname;
        }
        gk_plot_init(&pl, "RVE stress ratio along the applied path", "deviatoric strain eps_q (Guo & Zhao 2014 eq 13)",
                     "q / p");
        gk_plot_add(&pl, xs, qp, (int)ninc + 1, NULL);
        if (gk_plot_svg(&pl, svg, &err)) {
            fprintf(stderr, "rve_path: %s\n", err.msg);
            goto done;
        }
    }
    {
        double s[9];
        gk_rve_stress(&rve, s);
        printf("RESULT p=%.6g q=%.6g q_over_p=%.6g e_void=%.6g Z=%.4g steps=%ld seconds=%.3f\n", gk_stress_p(s, dim),
               gk_stress_q(s, dim), gk_stress_p(s, dim) > 0 ? gk_stress_q(s, dim) / gk_stress_p(s, dim) : 0.0,
               gk_homog_void_ratio(&rve), 2.0 * rve.ncontacts / rve.n, rve.step, gk_wtime() - t0);
    }
    fprintf(stderr, "rve_path: wrote %s and %s\n", out, svg);
    rc = 0;
done:
    if (fp) fclose(fp);
    free(xs);
    free(qp);
    gk_rve_destroy(&rve);
    return rc;
}
