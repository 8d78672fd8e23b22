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
#include "cli.h"
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *fp) {
    fprintf(
        fp,
        "usage: rve_path --packing FILE --dH \"H00 H01 H10 H11\" --increments N --steps-per-increment S\n"
        "                [--E 6e8] [--kt-ratio 0.8] [--friction-deg 28.65] [--density 2650]\n"
        "                [--thickness 0.1] [--damping 0.1] [--damping-form component|vector]\n"
        "                [--dt DT] [--law linear|hertz] [--poisson 0.25] [--path constant-L|objective]\n"
        "                [--threads T] [--out FILE.csv] [--svg FILE.svg]\n"
        "\n"
        "  --packing FILE           packing file (gk_packing.h's format; 2D: 'x y r', 3D: 'x y z r')\n"
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
        "  --path                   constant-L (default, the paper authors') or objective (ends exactly at I "
        "+ dH)\n"
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

/* the options, with their defaults */
typedef struct rp_opts {
    const char *packing, *dhs, *out, *svg, *law, *form, *path;
    double E, ktr, phi, phi_deg, rho, thick, damp, dt, poisson, dHin[9];
    long ninc, nsteps;
    int threads, nd, law_k, form_k, path_k;
} rp_opts;

static const char *const rp_law[] = {"linear", "hertz"};
static const char *const rp_form[] = {"component", "vector"};
static const char *const rp_path[] = {"constant-L", "objective"};

/* the options, strictly (examples/cli.h): 0 to run, -1 after --help, 2 after saying what is wrong */
static int rp_parse(int argc, char **argv, rp_opts *o) {
    int help = 0, ninc = 10, nsteps = 100;
    double phi_rad = NAN; /* --friction-angle: the old radian option, kept for old scripts */
    const cli_opt opts[] = {
        {"--packing", CLI_STR, &o->packing, 0, 0, NULL, NULL, 0},
        {"--dH", CLI_STR, &o->dhs, 0, 0, NULL, NULL, 0},
        {"--increments", CLI_INT, &ninc, 1, 100000000.0, NULL, NULL, 0},
        {"--steps-per-increment", CLI_INT, &nsteps, 1, 2000000000.0, NULL, NULL, 0},
        {"--E", CLI_REAL, &o->E, -HUGE_VAL, HUGE_VAL, "a number", NULL, 0},
        {"--kt-ratio", CLI_REAL, &o->ktr, -HUGE_VAL, HUGE_VAL, "a number", NULL, 0},
        {"--friction-deg", CLI_REAL, &o->phi_deg, -HUGE_VAL, HUGE_VAL, "a number", NULL, 0},
        {"--friction-angle", CLI_REAL, &phi_rad, -HUGE_VAL, HUGE_VAL, "a number", NULL, 0},
        {"--density", CLI_REAL, &o->rho, -HUGE_VAL, HUGE_VAL, "a number", NULL, 0},
        {"--thickness", CLI_REAL, &o->thick, -HUGE_VAL, HUGE_VAL, "a number", NULL, 0},
        {"--damping", CLI_REAL, &o->damp, -HUGE_VAL, HUGE_VAL, "a number", NULL, 0},
        {"--damping-form", CLI_CHOICE, &o->form_k, 0, 0, NULL, "component|vector", 0},
        {"--dt", CLI_REAL, &o->dt, -HUGE_VAL, HUGE_VAL, "a number", NULL, 0},
        {"--law", CLI_CHOICE, &o->law_k, 0, 0, NULL, "linear|hertz", 0},
        {"--poisson", CLI_REAL, &o->poisson, -HUGE_VAL, HUGE_VAL, "a number", NULL, 0},
        {"--path", CLI_CHOICE, &o->path_k, 0, 0, NULL, "constant-L|objective", 0},
        {"--threads", CLI_INT, &o->threads, 1, 4096, NULL, NULL, 0},
        {"--out", CLI_STR, &o->out, 0, 0, NULL, NULL, 0},
        {"--svg", CLI_STR, &o->svg, 0, 0, NULL, NULL, 0},
        {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    const cli_opt *const tables[] = {opts, NULL};
    o->packing = o->dhs = o->svg = NULL;
    o->out = "rve_path.csv";
    o->law_k = o->form_k = o->path_k = 0; /* linear, component, constant-L */
    o->E = 6e8, o->ktr = 0.8, o->phi = 0.5, o->phi_deg = -1.0, o->rho = 2650, o->thick = 0.1, o->damp = 0.1;
    o->dt = 0, o->poisson = 0.25;
    o->threads = 1;
    if (cli_parse("rve_path", argc, argv, tables, &help)) return 2;
    if (help) {
        usage(stdout);
        return -1;
    }
    o->ninc = ninc, o->nsteps = nsteps;
    o->law = rp_law[o->law_k], o->form = rp_form[o->form_k], o->path = rp_path[o->path_k];
    if (!isnan(phi_rad)) {
        fprintf(stderr, "rve_path: --friction-angle (radians) is deprecated: use --friction-deg\n");
        o->phi = phi_rad;
    }
    if (!o->packing || !o->dhs) {
        fprintf(stderr, "rve_path: --packing and --dH are required (see --help)\n");
        return 2;
    }
    if (o->phi_deg != -1.0) o->phi = o->phi_deg * GK_PI / 180.0;
    if (!(o->phi >= 0.0 && o->phi <= 85.0 * GK_PI / 180.0)) { /* 35 meant as radians is refused */
        fprintf(stderr, "rve_path: friction angle %g degrees: a contact friction angle is 0 to 85 degrees\n",
                o->phi * 180.0 / GK_PI);
        return 2;
    }
    o->nd = parse_numbers(o->dhs, o->dHin, 9);
    if (o->nd < 0) {
        fprintf(stderr, "rve_path: --dH '%s' is not a list of finite numbers\n", o->dhs);
        return 2;
    }
    return 0;
}

/* the material and the loading from the options, the packing read, dH checked against its dimension
 * and the RVE created: 0, or the exit status (2 bad options, 1 a failure) after saying why */
static int rp_setup(const rp_opts *o, gk_rve *rve, double dH[9], int *dimp) {
    gk_rve_def def = gk_rve_def_default();
    gk_packing pk;
    gk_err err;
    gk_result res;
    int i, k, dim;
    def.mat.young = o->E;
    def.mat.kt_ratio = o->ktr;
    def.mat.friction = tan(o->phi);
    def.mat.density = o->rho;
    def.mat.poisson = o->poisson;
    def.mat.law = o->law_k == 0 ? GK_LAW_LINEAR : GK_LAW_HERTZ;
    def.damping_form = o->form_k == 0 ? GK_DAMP_COMPONENT : GK_DAMP_VECTOR;
    def.path = o->path_k == 0 ? GK_PATH_CONSTANT_L : GK_PATH_OBJECTIVE;
    def.thickness = o->thick;
    def.damping = o->damp;
    def.dt = o->dt;
    def.threads = o->threads;
    if (gk_packing_read(o->packing, &pk, NULL, &err)) {
        fprintf(stderr, "rve_path: %s\n", err.msg);
        return 1;
    }
    dim = pk.dim;
    if (o->nd != dim * dim) {
        fprintf(stderr, "rve_path: --dH needs %d numbers for a %dD packing, got %d\n", dim * dim, dim, o->nd);
        gk_packing_free(&pk);
        return 2;
    }
    gk_m3_zero(dH);
    for (i = 0; i < dim; ++i)
        for (k = 0; k < dim; ++k) dH[3 * i + k] = o->dHin[dim * i + k];
    res = gk_rve_create(rve, &def, &pk);
    gk_packing_free(&pk);
    if (res) {
        fprintf(stderr, "rve_path: %s\n", gk_rve_error(rve));
        return 1;
    }
    *dimp = dim;
    return 0;
}

/* the increments: a CSV row after each (and one before the first), eps_q and q/p kept in xs, qp for
 * the plot; *t0 the wall clock at the start; 0 or 1 (said) */
static int rp_run(const rp_opts *o, gk_rve *rve, const double dH[9], int dim, double *xs, double *qp,
                  double *t0) {
    double Hacc[9];
    gk_err err;
    gk_result res;
    int i, k;
    FILE *fp = fopen(o->out, "w");
    if (!fp || !xs || !qp) {
        if (fp)
            fprintf(stderr, "rve_path: out of memory\n");
        else
            fprintf(stderr, "rve_path: cannot write %s\n", o->out);
        if (fp) fclose(fp);
        return 1;
    }
    if (dim == 2)
        fprintf(fp, "inc,H00,H01,H10,H11,sxx,syy,sxy,p,q,e_void,Z\n");
    else
        fprintf(fp, "inc,H00,H01,H02,H10,H11,H12,H20,H21,H22,sxx,syy,szz,syz,sxz,sxy,p,q,e_void,Z\n");
    fprintf(stderr, "rve_path: %d %s, %s law, dt %.4g s (critical %.4g s), %ld x %ld steps\n", rve->n,
            dim == 2 ? "disks" : "spheres", o->law, rve->dt, rve->dt_crit, o->ninc, o->nsteps);
    gk_m3_zero(Hacc);
    *t0 = gk_wtime();
    if (gk_rve_refresh(rve)) {
        fprintf(stderr, "rve_path: %s\n", gk_rve_error(rve));
        fclose(fp);
        return 1;
    }
    for (i = 0; i <= o->ninc; ++i) {
        double s[9], p, q, Z;
        if (i > 0) {
            if (gk_rve_deform(rve, dH, (int)o->nsteps)) {
                fprintf(stderr, "rve_path: increment %d: %s\n", i, gk_rve_error(rve));
                fclose(fp);
                return 1;
            }
            for (k = 0; k < 9; ++k) Hacc[k] += dH[k];
        }
        gk_rve_stress(rve, s);
        p = gk_stress_p(s, dim);
        q = gk_stress_q(s, dim);
        Z = 2.0 * rve->ncontacts / rve->n;
        fprintf(fp, "%d", i);
        for (k = 0; k < dim * dim; ++k) fprintf(fp, ",%.9g", Hacc[3 * (k / dim) + k % dim]);
        if (dim == 2)
            fprintf(fp, ",%.9g,%.9g,%.9g", -s[0], -s[4], -0.5 * (s[1] + s[3]));
        else
            fprintf(fp, ",%.9g,%.9g,%.9g,%.9g,%.9g,%.9g", -s[0], -s[4], -s[8], -0.5 * (s[5] + s[7]),
                    -0.5 * (s[2] + s[6]), -0.5 * (s[1] + s[3]));
        fprintf(fp, ",%.9g,%.9g,%.9g,%.9g\n", p, q, gk_homog_void_ratio(rve), Z);
        xs[i] = gk_strain_q(Hacc, dim);
        qp[i] = p > 0 ? q / p : 0.0;
    }
    res = gk_file_close(fp, o->out, &err);
    if (res) {
        fprintf(stderr, "rve_path: %s\n", err.msg);
        return 1;
    }
    return 0;
}

/* the q/p plot (--svg, or the CSV's name with .svg) and the RESULT line; 0 or 1 (said) */
static int rp_report(const rp_opts *o, gk_rve *rve, int dim, const double *xs, const double *qp, double t0) {
    const char *svg = o->svg;
    char svgname[1024];
    gk_err err;
    {
        gk_plot pl;
        size_t L = strlen(o->out);
        if (!svg) {
            if (L > 4 && !strcmp(o->out + L - 4, ".csv") && L < sizeof svgname) {
                memcpy(svgname, o->out, L - 4);
                strcpy(svgname + L - 4, ".svg");
            } else {
                snprintf(svgname, sizeof svgname, "%s.svg", o->out);
            }
            svg = svgname;
        }
        gk_plot_init(&pl, "RVE stress ratio along the applied path",
                     "deviatoric strain eps_q (Guo & Zhao 2014 eq 13)", "q / p");
        gk_plot_add(&pl, xs, qp, (int)o->ninc + 1, NULL);
        if (gk_plot_svg(&pl, svg, &err)) {
            fprintf(stderr, "rve_path: %s\n", err.msg);
            return 1;
        }
    }
    {
        double s[9];
        gk_rve_stress(rve, s);
        printf("RESULT p=%.6g q=%.6g q_over_p=%.6g e_void=%.6g Z=%.4g steps=%ld seconds=%.3f\n",
               gk_stress_p(s, dim), gk_stress_q(s, dim),
               gk_stress_p(s, dim) > 0 ? gk_stress_q(s, dim) / gk_stress_p(s, dim) : 0.0,
               gk_homog_void_ratio(rve), 2.0 * rve->ncontacts / rve->n, rve->step, gk_wtime() - t0);
    }
    fprintf(stderr, "rve_path: wrote %s and %s\n", o->out, svg);
    return 0;
}

int main(int argc, char **argv) {
    rp_opts o;
    gk_rve rve;
    double dH[9], t0 = 0.0, *xs, *qp;
    int dim = 0, rc = rp_parse(argc, argv, &o);
    if (rc) return rc < 0 ? 0 : rc;
    rc = rp_setup(&o, &rve, dH, &dim);
    if (rc) return rc;
    /* from here every exit frees what it holds (rc 1: a failed step or a result not written) */
    xs = (double *)malloc((size_t)(o.ninc + 1) * sizeof(double));
    qp = (double *)malloc((size_t)(o.ninc + 1) * sizeof(double));
    rc = rp_run(&o, &rve, dH, dim, xs, qp, &t0);
    if (!rc) rc = rp_report(&o, &rve, dim, xs, qp, t0);
    free(xs);
    free(qp);
    gk_rve_destroy(&rve);
    return rc;
}
