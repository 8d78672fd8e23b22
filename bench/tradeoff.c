/* bench_tradeoff - accuracy against cost of the two-scale drivers.
 *
 *   build/bench_tradeoff            short version (make bench): about a minute on 2 cores
 *   build/bench_tradeoff --full     the whole sweep (make tradeoff)
 *   build/bench_tradeoff [--threads T] [--bin DIR] [--data DIR] [--out DIR]
 *                        [--sweep NAME,NAME,...] [--steps N] [--dry-run]
 *
 * Runs the drivers as child processes, one configuration at a time, each with
 * --threads T (default 2), reads their CSV and RESULT lines, and compares each
 * curve with the reference run of its group at equal axial strain (linear
 * interpolation). Every configuration runs once: a trade table, not a timing
 * benchmark, so no repeats and no median. Wall times mean something only on
 * otherwise idle cores: with other 2-thread jobs on the same 2 cores a run
 * can be several-fold slower, probably OpenMP threads spinning at barriers
 * (not verified; seen while writing this: the 4 x 8 cells, 2 x 2 points MPM
 * run took 182 s, the 3 x 3 one 117 s, with about 4 other busy threads).
 *
 * Groups, references and sweeps (--full; the short version in brackets):
 *
 *   single   femdem_biaxial --test single: one Q4 element, 4 RVEs, 100 load
 *            steps of 0.1 % axial strain (to 10 %), the RVE-alone check the
 *            driver also runs is part of the cost. Packings
 *            bench/data/tradeoff/rveN.txt (gk_pack, one procedure for every N,
 *            see the README there).
 *            reference: 1600 disks, double, Taylor tangent, 400 DEM steps per
 *            increment [short: 800 disks, 200 steps].
 *            sweeps rve_size  N = 100 200 400 800 1600 disks, 100 DEM steps, and
 *                             the authors' examples/data/rve400.txt [100 200 400 800]
 *                   dem_steps 25 50 100 200 400 fixed steps per increment and the
 *                             adaptive rule, on 400 and 1600 disks [25 50 adaptive, 400 disks]
 *                   real      float build (femdem_biaxial_float), 400 and 1600 disks [400]
 *                   tangent   yade, perturbation (eq 8), and perturbation with
 *                             --tangent-reuse 0.1 (when the driver has it), vs taylor,
 *                             400 and 1600 disks [yade, 400]
 *   biaxial  femdem_biaxial biaxial test, the authors' 400-disk RVE, 100 DEM
 *            steps per increment, to 10 % [short: not run].
 *            reference: the finest of the sweep, 4 x 8 Q8 (a mesh/element
 *            discretisation error, same RVE and DEM steps; after the peak the
 *            strain localises and no mesh is "converged").
 *            sweep  mesh  2x4 Q4, 2x4 Q8, 4x8 Q4, 4x8 Q8
 *   mpm      mpmdem_biaxial, 4 x 8 cells (1 x 2 m), to 3 % axial strain, default
 *            (adaptive) DEM rule [short: not run; --sweep mpm without --full: 2 x 4
 *            cells]. After the peak the adaptive rule needs tens to hundreds of DEM
 *            steps per point per MPM step (measured on 2 x 4 cells, 2 x 2 points:
 *            5-8 at 2-3 %, 300+ at 9 %), hence 3 %, past the peak (about 2 %).
 *            reference: 3 x 3 points per cell (288 RVEs).
 *            sweep  mpm_ppc  1 and 2 points per cell edge (32, 128 RVEs)
 *
 * The short version runs the single-element group only (about a minute on 2
 * idle cores); --sweep biaxial or --sweep mpm adds a group to it.
 *
 * Error metrics (each row against its group's reference; NaN when the run did
 * not reach the strain the metric needs):
 *   err_peak   |R - R_ref| / R_ref, R = max over the curve of sigma_yy / sigma_xx
 *              (MPM: sigma_yy / the applied lateral pressure)
 *   err_sa     |sigma_yy(5 %) - ref| / ref,   err_sb the same at 10 %
 *   ev_rms     RMS over the reference's rows (0 < eps_axial <= the shorter curve's
 *              end) of eps_v - eps_v_ref, both interpolated at eps_axial
 *              (strain units); err_ev = ev_rms / max |eps_v_ref|
 *   err_max    max(err_peak, err_sa, err_sb, err_ev): the y axis of the Pareto plot
 *   err_twin   (single group; CSV err_max_vs_100_steps_double_taylor_same_rve) err_max
 *              against the run with the same packing, 100 DEM steps, double and Taylor:
 *              the swept factor alone, without the RVE-sample difference. For float it
 *              measures how far round-off alone moves a chaotic DEM curve, i.e. the
 *              noise floor of single-run comparisons.
 * Cost: wall seconds of the child process (start-up, packing read and output
 * included) and the total Newton iterations (sum of the CSV's iterations
 * column, converged steps and sub-steps; none for the explicit MPM, which
 * reports its step count instead).
 *
 * Fixed DEM step counts N are asked as --dem-rule strain --dem-strain inc/N
 * --dem-min N --dem-max N; the adaptive rows as --dem-rule adaptive.
 *
 * Exit status: 0 only if every run completed and both files were written
 * completely; a failed run still gets its row (completed=no) and is named
 * on stderr, then the program exits 1, so `make bench` fails.
 *
 * Output: OUT/tradeoff.csv (one row per configuration), OUT/tradeoff.svg
 * (error against seconds, log axes, Pareto front of each group), OUT/runs/ID
 * (each child's output and log), a table on stdout and one line per row:
 *   BENCH case=tradeoff group=... sweep=... config=... completed=... seconds=...
 *         newton_iterations=... err_peak=... err_sa=... err_sb=... ev_rms=... err_max=... */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>

#define MAXCFG 64

/* fclose of a file we wrote, reporting any lost byte (full disk, /dev/full) */
static int close_written(FILE *fp, const char *path) {
    int bad = fflush(fp) != 0 || ferror(fp);
    if (fclose(fp) != 0) bad = 1;
    if (bad) fprintf(stderr, "bench_tradeoff: error writing %s: %s\n", path, strerror(errno));
    return bad;
}
#define INC 0.001 /* femdem_biaxial's default axial strain per load step */

typedef struct curve {
    int n, cap;
    double *eps, *syy, *sxx, *ev;
} curve;

typedef enum { K_SINGLE, K_BIAXIAL, K_MPM } kind_t;

typedef struct cfg {
    const char *group, *sweep;
    char label[64], id[48];
    kind_t kind;
    char packing[256];
    int disks;     /* 0: the authors' rve400.txt */
    int dem_steps; /* fixed steps per increment; 0: adaptive rule */
    int use_float;
    const char *tangent;
    double reuse; /* --tangent-reuse X (0: off) */
    int nx, ny;
    const char *element;
    int ppc;
    int steps;     /* FEM load steps */
    double strain; /* MPM final strain */
    int is_ref;
    char cmd[4096];
    /* results */
    int ran, completed, same_as;
    double seconds;
    long newton, mpm_steps;
    curve c;
    double eps_a, eps_b; /* axial strains of the two stress points (5 and 10 %; MPM 1 and 3 %) */
    double err_peak, err_sa, err_sb, ev_rms, err_ev, err_max;
    double err_base; /* err_max against the same RVE with 100 DEM steps, double, Taylor */
} cfg;

typedef struct opts {
    int full, threads, dry, steps;
    const char *bin, *data, *out, *only;
} opts;

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int mkdirs(const char *path) {
    char buf[512];
    size_t k, n = strlen(path);
    if (n >= sizeof buf) return -1;
    memcpy(buf, path, n + 1);
    for (k = 1; k <= n; ++k)
        if (buf[k] == '/' || buf[k] == '\0') {
            char c = buf[k];
            buf[k] = '\0';
            if (mkdir(buf, 0777) && errno != EEXIST) return -1;
            buf[k] = c;
        }
    return 0;
}

static int file_exists(const char *p) {
    struct stat st;
    return stat(p, &st) == 0;
}

/* ------------------------------------------------------------ curves */
static void curve_push(curve *c, double e, double syy, double sxx, double ev) {
    if (c->n == c->cap) {
        int cap = c->cap ? 2 * c->cap : 128;
        double *a = realloc(c->eps, cap * sizeof(double)), *b, *d, *f;
        if (!a) return;
        c->eps = a;
        if (!(b = realloc(c->syy, cap * sizeof(double)))) return;
        c->syy = b;
        if (!(d = realloc(c->sxx, cap * sizeof(double)))) return;
        c->sxx = d;
        if (!(f = realloc(c->ev, cap * sizeof(double)))) return;
        c->ev = f;
        c->cap = cap;
    }
    c->eps[c->n] = e, c->syy[c->n] = syy, c->sxx[c->n] = sxx, c->ev[c->n] = ev;
    ++c->n;
}

static void curve_free(curve *c) {
    free(c->eps), free(c->syy), free(c->sxx), free(c->ev);
    memset(c, 0, sizeof *c);
}

static int col_index(char *header, const char *name) {
    int k = 0;
    char *tok, *save = NULL;
    for (tok = strtok_r(header, ",\r\n", &save); tok; tok = strtok_r(NULL, ",\r\n", &save), ++k)
        if (!strcmp(tok, name)) return k;
    return -1;
}

/* reads eps_axial, sigma_yy, sigma_xx (or the constant lateral pressure when
 * the CSV has none, MPM) and eps_v; iterations summed into *iters when present */
static int read_curve(const char *path, double pressure, curve *c, long *iters) {
    FILE *fp = fopen(path, "r");
    char line[4096], hdr[4096];
    int ie, iy, ix, iv, ii;
    if (!fp) return -1;
    if (!fgets(line, sizeof line, fp)) {
        fclose(fp);
        return -1;
    }
    strcpy(hdr, line), ie = col_index(hdr, "eps_axial");
    strcpy(hdr, line), iy = col_index(hdr, "sigma_yy");
    strcpy(hdr, line), ix = col_index(hdr, "sigma_xx");
    strcpy(hdr, line), iv = col_index(hdr, "eps_v");
    strcpy(hdr, line), ii = col_index(hdr, "iterations");
    if (ie < 0 || iy < 0 || iv < 0) {
        fclose(fp);
        return -1;
    }
    *iters = ii >= 0 ? 0 : -1;
    while (fgets(line, sizeof line, fp)) {
        double v[64];
        int k = 0;
        char *p = line, *end;
        while (k < 64) {
            v[k] = strtod(p, &end);
            if (end == p) break;
            ++k;
            if (*end != ',') break;
            p = end + 1;
        }
        if (k <= ie || k <= iy || k <= iv || (ix >= 0 && k <= ix)) continue;
        curve_push(c, v[ie], v[iy], ix >= 0 ? v[ix] : pressure, v[iv]);
        if (ii >= 0 && k > ii) *iters += (long)v[ii];
    }
    fclose(fp);
    return c->n > 1 ? 0 : -1;
}

/* value of column y at axial strain x by linear interpolation; NaN outside */
static double interp(const curve *c, const double *y, double x) {
    int k;
    double tol = 1e-9;
    if (c->n < 2 || x < c->eps[0] - tol || x > c->eps[c->n - 1] + tol) return NAN;
    if (x >= c->eps[c->n - 1]) return y[c->n - 1];
    for (k = 1; k < c->n; ++k)
        if (c->eps[k] >= x) {
            double d = c->eps[k] - c->eps[k - 1];
            double t = d > 0 ? (x - c->eps[k - 1]) / d : 1.0;
            return y[k - 1] + t * (y[k] - y[k - 1]);
        }
    return NAN;
}

static double peak_ratio(const curve *c, double *eps_at) {
    int k;
    double r = -1.0;
    *eps_at = NAN;
    for (k = 0; k < c->n; ++k)
        if (c->sxx[k] > 0 && c->syy[k] / c->sxx[k] > r) r = c->syy[k] / c->sxx[k], *eps_at = c->eps[k];
    return r > 0 ? r : NAN;
}

static void compute_errors(cfg *r, const cfg *ref) {
    const curve *a = &r->c, *b = &ref->c;
    double ea, eb, Ra, Rb, end, s = 0.0, evmax = 0.0, m;
    int k, n = 0;
    r->err_peak = r->err_sa = r->err_sb = r->ev_rms = r->err_ev = r->err_max = NAN;
    if (a->n < 2 || b->n < 2) return;
    Ra = peak_ratio(a, &ea);
    Rb = peak_ratio(b, &eb);
    /* a peak means something only when the run got past the reference's peak */
    if (a->eps[a->n - 1] >= eb && Rb > 0) r->err_peak = fabs(Ra - Rb) / Rb;
    m = interp(b, b->syy, r->eps_a);
    r->err_sa = fabs(interp(a, a->syy, r->eps_a) - m) / m;
    m = interp(b, b->syy, r->eps_b);
    r->err_sb = fabs(interp(a, a->syy, r->eps_b) - m) / m;
    end = a->eps[a->n - 1] < b->eps[b->n - 1] ? a->eps[a->n - 1] : b->eps[b->n - 1];
    for (k = 0; k < b->n; ++k) {
        if (fabs(b->ev[k]) > evmax) evmax = fabs(b->ev[k]);
        if (b->eps[k] > 0 && b->eps[k] <= end + 1e-12) {
            double d = interp(a, a->ev, b->eps[k]) - b->ev[k];
            if (d == d) s += d * d, ++n;
        }
    }
    if (n > 0) r->ev_rms = sqrt(s / n);
    if (evmax > 0) r->err_ev = r->ev_rms / evmax;
    {
        double e[4];
        e[0] = r->err_peak, e[1] = r->err_sa, e[2] = r->err_sb, e[3] = r->err_ev;
        r->err_max = 0.0;
        for (k = 0; k < 4; ++k)
            r->err_max = e[k] != e[k] || r->err_max != r->err_max ? NAN
                         : e[k] > r->err_max                      ? e[k]
                                                                  : r->err_max;
    }
}

/* ------------------------------------------------------------ configurations */
static cfg *add(cfg *list, int *n, const char *group, const char *sweep, kind_t kind) {
    cfg *c;
    if (*n >= MAXCFG) {
        fprintf(stderr, "bench_tradeoff: too many configurations\n");
        exit(1);
    }
    c = &list[(*n)++];
    memset(c, 0, sizeof *c);
    c->group = group, c->sweep = sweep, c->kind = kind;
    c->dem_steps = 100, c->tangent = "taylor", c->element = "q4", c->nx = c->ny = 1, c->steps = 100;
    c->same_as = -1, c->eps_a = 0.05, c->eps_b = 0.10;
    return c;
}

static void set_packing(cfg *c, const opts *o, int disks) {
    c->disks = disks;
    if (disks)
        snprintf(c->packing, sizeof c->packing, "%s/rve%d.txt", o->data, disks);
    else
        snprintf(c->packing, sizeof c->packing, "examples/data/rve400.txt");
}

static void single(cfg *L, int *n, const opts *o, const char *sweep, int disks, int steps, int use_float,
                   const char *tangent, double reuse, int is_ref) {
    cfg *c = add(L, n, "single", sweep, K_SINGLE);
    set_packing(c, o, disks);
    c->dem_steps = steps, c->use_float = use_float, c->tangent = tangent, c->reuse = reuse,
    c->is_ref = is_ref;
    if (disks)
        snprintf(c->label, sizeof c->label, "%dd ", disks);
    else
        snprintf(c->label, sizeof c->label, "rve400-authors ");
    if (steps)
        snprintf(c->label + strlen(c->label), sizeof c->label - strlen(c->label), "%dst", steps);
    else
        snprintf(c->label + strlen(c->label), sizeof c->label - strlen(c->label), "adaptive");
    if (use_float) strcat(c->label, " float");
    if (strcmp(tangent, "taylor"))
        snprintf(c->label + strlen(c->label), sizeof c->label - strlen(c->label), " %s", tangent);
    if (reuse > 0)
        snprintf(c->label + strlen(c->label), sizeof c->label - strlen(c->label), " reuse%g", reuse);
}

static int wanted(const opts *o, const char *group, const char *sweep) {
    const char *p = o->only;
    size_t lg = strlen(group), ls = strlen(sweep);
    if (!p) return 1;
    while (*p) {
        size_t l = strcspn(p, ",");
        if ((l == lg && !strncmp(p, group, l)) || (l == ls && !strncmp(p, sweep, l))) return 1;
        p += l;
        if (*p == ',') ++p;
    }
    return 0;
}

static int build_list(cfg *L, const opts *o) {
    int n = 0, k, j;
    static const int sizes_full[] = {100, 200, 400, 800, 1600}, sizes_short[] = {100, 200, 400, 800};
    static const int steps_full[] = {25, 50, 100, 200, 400, 0}, steps_short[] = {25, 50, 0};
    static const int dsk_full[] = {400, 1600}, dsk_short[] = {400};
    const int *sz = o->full ? sizes_full : sizes_short, *st = o->full ? steps_full : steps_short;
    const int *dk = o->full ? dsk_full : dsk_short;
    int nsz = o->full ? 5 : 4, nst = o->full ? 6 : 3, ndk = o->full ? 2 : 1;
    if (wanted(o, "single", "rve_size") || wanted(o, "single", "dem_steps") || wanted(o, "single", "real") ||
        wanted(o, "single", "tangent")) {
        if (o->full)
            single(L, &n, o, "reference", 1600, 400, 0, "taylor", 0, 1);
        else
            single(L, &n, o, "reference", 800, 200, 0, "taylor", 0, 1);
        if (wanted(o, "single", "rve_size")) {
            for (k = 0; k < nsz; ++k) single(L, &n, o, "rve_size", sz[k], 100, 0, "taylor", 0, 0);
            if (o->full) single(L, &n, o, "rve_size", 0, 100, 0, "taylor", 0, 0);
        }
        if (wanted(o, "single", "dem_steps"))
            for (j = 0; j < ndk; ++j)
                for (k = 0; k < nst; ++k) single(L, &n, o, "dem_steps", dk[j], st[k], 0, "taylor", 0, 0);
        if (wanted(o, "single", "real"))
            for (j = 0; j < ndk; ++j) single(L, &n, o, "real", dk[j], 100, 1, "taylor", 0, 0);
        if (wanted(o, "single", "tangent"))
            for (j = 0; j < ndk; ++j) {
                single(L, &n, o, "tangent", dk[j], 100, 0, "yade", 0, 0);
                if (o->full) single(L, &n, o, "tangent", dk[j], 100, 0, "perturbation", 0, 0);
                if (o->full) single(L, &n, o, "tangent", dk[j], 100, 0, "perturbation", 0.1, 0);
            }
    }
    if ((o->full || o->only) && wanted(o, "biaxial", "mesh")) { /* short: only when asked */
        static const int mesh[4][2] = {{4, 8}, {2, 4}, {2, 4}, {4, 8}};
        static const char *el[4] = {"q8", "q4", "q8", "q4"};
        for (k = 0; k < 4; ++k) {
            cfg *c = add(L, &n, "biaxial", k == 0 ? "reference" : "mesh", K_BIAXIAL);
            set_packing(c, o, 0);
            c->nx = mesh[k][0], c->ny = mesh[k][1], c->element = el[k], c->is_ref = k == 0;
            snprintf(c->label, sizeof c->label, "%dx%d %s", c->nx, c->ny, c->element);
        }
    }
    if ((o->full || o->only) && wanted(o, "mpm", "mpm_ppc")) { /* short: only when asked */
        int top = 3;
        for (k = top; k >= 1; --k) {
            cfg *c = add(L, &n, "mpm", k == top ? "reference" : "mpm_ppc", K_MPM);
            set_packing(c, o, 0);
            c->nx = o->full ? 4 : 2, c->ny = 2 * c->nx, c->ppc = k, c->is_ref = k == top;
            c->strain = 0.0305; /* a little past 3 %: the 3 % point lies inside the curve */
            c->eps_a = 0.01, c->eps_b = 0.03;
            c->dem_steps = 0;
            snprintf(c->label, sizeof c->label, "%dx%d ppc%d", c->nx, c->ny, k);
        }
    }
    for (k = 0; k < n; ++k) {
        snprintf(L[k].id, sizeof L[k].id, "%02d_%s_%s", k, L[k].group, L[k].sweep);
        if (o->steps && L[k].kind != K_MPM) L[k].steps = o->steps;
        if (o->steps && L[k].kind == K_MPM && INC * (o->steps + 0.5) < L[k].strain)
            L[k].strain = INC * (o->steps + 0.5);
    }
    return n;
}

static int make_cmd(cfg *c, const opts *o, const char *dir) {
    char dem[160] = "";
    int w = 0;
    if (c->kind == K_MPM) {
        w = snprintf(
            c->cmd, sizeof c->cmd,
            "%s/mpmdem_biaxial --nx %d --ny %d --ppc %d --strain %g --threads %d --packing %s --quiet "
            "--out %s > %s/log.txt 2>&1",
            o->bin, c->nx, c->ny, c->ppc, c->strain, o->threads, c->packing, dir, dir);
        return w < 0 || w >= (int)sizeof c->cmd;
    }
    if (c->dem_steps > 0) {
        /* n_s = ceil(|dH| / S) clamped to [N, N]; S a hair above inc/N so that the
         * single test's RVE-alone check, ceil(inc / S), is also N */
        double S = INC / c->dem_steps * (1.0 + 1e-6);
        w = snprintf(dem, sizeof dem, "--dem-rule strain --dem-strain %.9g --dem-min %d --dem-max %d", S,
                     c->dem_steps, c->dem_steps);
    } else
        w = snprintf(dem, sizeof dem, "--dem-rule adaptive");
    if (c->reuse > 0) snprintf(dem + strlen(dem), sizeof dem - strlen(dem), " --tangent-reuse %g", c->reuse);
    w = snprintf(
        c->cmd, sizeof c->cmd,
        "%s/%s --test %s --nx %d --ny %d --element %s --steps %d --threads %d --tangent %s --packing %s %s "
        "--vtk-every 0 --checkpoint 1000000 --out %s > %s/log.txt 2>&1",
        o->bin, c->use_float ? "femdem_biaxial_float" : "femdem_biaxial",
        c->kind == K_SINGLE ? "single" : "biaxial", c->nx, c->ny, c->element, c->steps, o->threads,
        c->tangent, c->packing, dem, dir, dir);
    return w < 0 || w >= (int)sizeof c->cmd;
}

static void read_result_line(const char *log, cfg *c) {
    FILE *fp = fopen(log, "r");
    char line[2048];
    if (!fp) return;
    while (fgets(line, sizeof line, fp))
        if (!strncmp(line, "RESULT ", 7)) {
            const char *p = strstr(line, "mpm_steps=");
            if (p) c->mpm_steps = atol(p + 10);
        }
    fclose(fp);
}

static void run_one(cfg *L, int i, const opts *o) {
    cfg *c = &L[i];
    char dir[512], path[600];
    int k, rc;
    double t0;
    snprintf(dir, sizeof dir, "%s/runs/%s", o->out, c->id);
    if (make_cmd(c, o, dir)) {
        fprintf(stderr, "bench_tradeoff: command line too long for %s (shorter --bin/--out/--data)\n", c->id);
        return;
    }
    c->newton = -1, c->mpm_steps = -1;
    for (k = 0; k < i; ++k) /* same command line (up to the directory): reuse that run */
        if (L[k].ran && !strcmp(L[k].packing, c->packing) && L[k].kind == c->kind &&
            L[k].dem_steps == c->dem_steps && L[k].use_float == c->use_float &&
            !strcmp(L[k].tangent, c->tangent) && L[k].reuse == c->reuse && L[k].nx == c->nx &&
            L[k].ny == c->ny && !strcmp(L[k].element, c->element) && L[k].ppc == c->ppc &&
            L[k].steps == c->steps && L[k].strain == c->strain) {
            c->same_as = k;
            c->ran = 1, c->completed = L[k].completed, c->seconds = L[k].seconds, c->newton = L[k].newton;
            c->mpm_steps = L[k].mpm_steps;
            for (k = 0; k < L[c->same_as].c.n; ++k)
                curve_push(&c->c, L[c->same_as].c.eps[k], L[c->same_as].c.syy[k], L[c->same_as].c.sxx[k],
                           L[c->same_as].c.ev[k]);
            printf("same %-34s as %s\n", c->id, L[c->same_as].id);
            return;
        }
    if (o->dry) {
        printf("%s\n", c->cmd);
        return;
    }
    if (mkdirs(dir)) {
        fprintf(stderr, "bench_tradeoff: cannot create %s\n", dir);
        return;
    }
    printf("run  %-34s ", c->id);
    fflush(stdout);
    t0 = now();
    rc = system(c->cmd);
    c->seconds = now() - t0;
    if (rc != -1 && ((WIFSIGNALED(rc) && (WTERMSIG(rc) == SIGINT || WTERMSIG(rc) == SIGQUIT)) ||
                     (WIFEXITED(rc) && WEXITSTATUS(rc) == 128 + SIGINT))) { /* ^C: stop the sweep */
        fprintf(stderr, "\nbench_tradeoff: interrupted\n");
        exit(130);
    }
    c->ran = 1;
    c->completed = rc != -1 && WIFEXITED(rc) && WEXITSTATUS(rc) == 0;
    snprintf(path, sizeof path, "%s/biaxial.csv", dir);
    if (read_curve(path, 1e5, &c->c, &c->newton)) c->completed = 0;
    if (c->kind == K_MPM) c->newton = -1;
    snprintf(path, sizeof path, "%s/log.txt", dir);
    read_result_line(path, c);
    printf("%7.1f s  %s%s\n", c->seconds, c->completed ? "ok" : "FAILED, see ", c->completed ? "" : path);
    fflush(stdout);
}

/* ------------------------------------------------------------ output */
static void fmt(char *b, size_t n, double v, double scale, const char *f) {
    if (v != v)
        snprintf(b, n, "NaN");
    else
        snprintf(b, n, f, v * scale);
}

static const char *sweep_color(const char *s) {
    if (!strcmp(s, "rve_size")) return "#1f77b4";
    if (!strcmp(s, "dem_steps")) return "#ff7f0e";
    if (!strcmp(s, "real")) return "#2ca02c";
    if (!strcmp(s, "tangent")) return "#d62728";
    if (!strcmp(s, "mesh")) return "#9467bd";
    if (!strcmp(s, "mpm_ppc")) return "#8c564b";
    return "#000000";
}

static void marker(FILE *fp, kind_t k, double x, double y, const char *col) {
    if (k == K_SINGLE)
        fprintf(fp, "<circle cx='%.1f' cy='%.1f' r='4.5' fill='%s' fill-opacity='0.8'/>\n", x, y, col);
    else if (k == K_BIAXIAL)
        fprintf(fp, "<rect x='%.1f' y='%.1f' width='9' height='9' fill='%s' fill-opacity='0.8'/>\n", x - 4.5,
                y - 4.5, col);
    else
        fprintf(fp, "<path d='M%.1f %.1f l5 9 h-10 z' fill='%s' fill-opacity='0.8'/>\n", x, y - 5.5, col);
}

static int write_svg(const char *path, cfg *L, int n) {
    FILE *fp = fopen(path, "w");
    const double W = 1180, H = 660, x0 = 80, x1 = 680, y0 = 50, y1 = 570;
    double lx0 = 1e300, lx1 = -1e300, ly0 = 1e300, ly1 = -1e300, d, ky;
    int k, j, ng = 0;
    const char *groups[3] = {"single", "biaxial", "mpm"};
    const char *sweeps[6] = {"rve_size", "dem_steps", "real", "tangent", "mesh", "mpm_ppc"};
    if (!fp) return -1;
    for (k = 0; k < n; ++k) /* the range of what is plotted: repeats of a run (same_as) are not */
        if (L[k].ran && L[k].seconds > 0) {
            double lx = log10(L[k].seconds),
                   ly = !L[k].is_ref && L[k].same_as < 0 && L[k].err_max > 0 ? log10(L[k].err_max) : NAN;
            if (lx < lx0) lx0 = lx;
            if (lx > lx1) lx1 = lx;
            if (ly == ly && ly < ly0) ly0 = ly;
            if (ly == ly && ly > ly1) ly1 = ly;
        }
    if (lx0 > lx1) lx0 = -1, lx1 = 1;
    if (ly0 > ly1) ly0 = -3, ly1 = 0;
    lx0 = floor(lx0), lx1 = ceil(lx1 + 1e-9), ly0 = floor(ly0 - 0.3), ly1 = ceil(ly1 + 1e-9);
#define PX(v) (x0 + (log10(v) - lx0) / (lx1 - lx0) * (x1 - x0))
#define PY(v) (y1 - (log10(v) - ly0) / (ly1 - ly0) * (y1 - y0))
    fprintf(fp,
            "<svg xmlns='http://www.w3.org/2000/svg' width='%g' height='%g' font-family='sans-serif' "
            "font-size='12'>\n",
            W, H);
    fprintf(fp, "<rect width='100%%' height='100%%' fill='white'/>\n");
    fprintf(
        fp,
        "<text x='%g' y='25' font-size='15' text-anchor='middle'>grainkit trade-off: error against wall time "
        "(each group against its own reference)</text>\n",
        (x0 + x1) / 2);
    for (d = lx0; d <= lx1 + 1e-9; d += 1) { /* decades, with 2 and 5 in between */
        int m;
        for (m = 1; m <= 5; m += m == 1 ? 1 : 3) {
            double v = log10(m) + d, x = x0 + (v - lx0) / (lx1 - lx0) * (x1 - x0);
            if (v > lx1 + 1e-9) break;
            fprintf(fp, "<line x1='%.1f' y1='%g' x2='%.1f' y2='%g' stroke='%s'/>\n", x, y0, x, y1,
                    m == 1 ? "#ccc" : "#eee");
            fprintf(fp, "<text x='%.1f' y='%g' text-anchor='middle'>%g</text>\n", x, y1 + 16, pow(10, v));
        }
    }
    for (d = ly0; d <= ly1 + 1e-9; d += 1) {
        int m;
        for (m = 1; m <= 5; m += m == 1 ? 1 : 3) {
            double v = log10(m) + d, y = y1 - (v - ly0) / (ly1 - ly0) * (y1 - y0);
            if (v > ly1 + 1e-9) break;
            fprintf(fp, "<line x1='%g' y1='%.1f' x2='%g' y2='%.1f' stroke='%s'/>\n", x0, y, x1, y,
                    m == 1 ? "#ccc" : "#eee");
            fprintf(fp, "<text x='%g' y='%.1f' text-anchor='end'>%g %%</text>\n", x0 - 5, y + 4,
                    100 * pow(10, v));
        }
    }
    fprintf(fp, "<rect x='%g' y='%g' width='%g' height='%g' fill='none' stroke='black'/>\n", x0, y0, x1 - x0,
            y1 - y0);
    fprintf(fp,
            "<text x='%g' y='%g' text-anchor='middle'>wall seconds per run (2 cores, one run each)</text>\n",
            (x0 + x1) / 2, y1 + 36);
    fprintf(
        fp,
        "<text transform='translate(22 %g) rotate(-90)' text-anchor='middle'>err_max: largest relative error "
        "of peak ratio, sigma_yy at eps_a and eps_b, eps_v</text>\n",
        (y0 + y1) / 2);
    fprintf(fp,
            "<text x='%g' y='%g' font-size='10' fill='#555'>numbers: run ids (table order, "
            "build/tradeoff/runs/NN_*); references "
            "on the bottom edge; single runs of chaotic DEM: differences of a few %% after the peak are "
            "noise</text>\n",
            x0, y1 + 56);
    /* Pareto front per group: points no cheaper point beats */
    for (j = 0; j < 3; ++j) {
        int idx[MAXCFG], m = 0, a, b;
        double best = 1e300;
        for (k = 0; k < n; ++k)
            if (!strcmp(L[k].group, groups[j]) && L[k].ran && L[k].completed && !L[k].is_ref &&
                L[k].err_max > 0 && L[k].same_as < 0)
                idx[m++] = k;
        for (a = 1; a < m; ++a)
            for (b = a; b > 0 && L[idx[b]].seconds < L[idx[b - 1]].seconds; --b) {
                int t = idx[b];
                idx[b] = idx[b - 1], idx[b - 1] = t;
            }
        if (m == 0) continue;
        fprintf(fp, "<polyline fill='none' stroke='#555' stroke-dasharray='5,4' points='");
        for (a = 0; a < m; ++a)
            if (L[idx[a]].err_max < best) {
                if (best < 1e300) fprintf(fp, "%.1f,%.1f ", PX(L[idx[a]].seconds), PY(best));
                best = L[idx[a]].err_max;
                fprintf(fp, "%.1f,%.1f ", PX(L[idx[a]].seconds), PY(best));
            }
        fprintf(fp, "'/>\n");
        ++ng;
    }
    for (k = 0; k < n; ++k) {
        cfg *c = &L[k];
        double x, y;
        if (!c->ran || c->same_as >= 0 || !(c->seconds > 0)) continue;
        x = PX(c->seconds);
        if (c->is_ref)
            y = y1 - 8, marker(fp, c->kind, x, y, "#000");
        else if (c->err_max > 0)
            y = PY(c->err_max), marker(fp, c->kind, x, y, sweep_color(c->sweep));
        else
            continue;
        fprintf(fp, "<text x='%.1f' y='%.1f' font-size='9' fill='#333'>%d</text>\n", x + 5, y - 4, k);
    }
    /* legend */
    ky = y0 + 10;
    fprintf(fp, "<text x='700' y='%.1f' font-weight='bold'>sweep</text>\n", ky);
    for (j = 0; j < 6; ++j) {
        ky += 17;
        fprintf(fp,
                "<rect x='700' y='%.1f' width='11' height='11' fill='%s'/><text x='716' y='%.1f'>%s</text>\n",
                ky - 10, sweep_color(sweeps[j]), ky, sweeps[j]);
    }
    ky += 26;
    fprintf(fp, "<text x='700' y='%.1f' font-weight='bold'>test (marker)</text>\n", ky);
    ky += 17, marker(fp, K_SINGLE, 706, ky - 4, "#777");
    fprintf(fp, "<text x='716' y='%.1f'>single element</text>\n", ky);
    ky += 17, marker(fp, K_BIAXIAL, 706, ky - 4, "#777");
    fprintf(fp, "<text x='716' y='%.1f'>FEMxDEM biaxial</text>\n", ky);
    ky += 17, marker(fp, K_MPM, 706, ky - 4, "#777");
    fprintf(fp, "<text x='716' y='%.1f'>MPMxDEM biaxial</text>\n", ky);
    ky += 26;
    fprintf(fp,
            "<line x1='700' y1='%.1f' x2='730' y2='%.1f' stroke='#555' stroke-dasharray='5,4'/>"
            "<text x='736' y='%.1f'>Pareto front of each group (%d)</text>\n",
            ky - 4, ky - 4, ky, ng);
    /* key: row number, group, configuration; two columns */
    ky = y0 + 10;
    fprintf(fp, "<text x='900' y='%.1f' font-weight='bold'>rows</text>\n", ky);
    for (k = 0, j = 0; k < n; ++k) {
        const cfg *c = &L[k];
        double x = j < 36 ? 900 : 1040, y = y0 + 26 + 15 * (j < 36 ? j : j - 36);
        const char *state = !c->ran             ? " (not run)"
                            : c->same_as >= 0   ? " (=row)"
                            : !c->completed     ? " (FAILED)"
                            : c->is_ref         ? " REF"
                            : !(c->err_max > 0) ? " (NaN)"
                                                : "";
        fprintf(fp, "<text x='%.0f' y='%.1f' font-size='10'>%d %s %s%s</text>\n", x, y, k,
                c->kind == K_SINGLE    ? "S"
                : c->kind == K_BIAXIAL ? "B"
                                       : "M",
                c->label, state);
        ++j;
    }
    fprintf(fp, "</svg>\n");
#undef PX
#undef PY
    return close_written(fp, path);
}

static void usage(FILE *fp) {
    fprintf(
        fp,
        "usage: bench_tradeoff [--full] [--threads T] [--bin DIR] [--data DIR] [--out DIR]\n"
        "                      [--sweep NAME,...] [--steps N] [--dry-run]\n"
        "  (no option)     short version: the single-element group, about a minute on 2 cores (make bench)\n"
        "  --full          the whole sweep (make tradeoff), about 10-15 minutes on 2 idle cores\n"
        "  --threads T     threads given to every driver run (2)\n"
        "  --bin DIR       where the driver binaries are (build)\n"
        "  --data DIR      packings rveN.txt of the RVE-size series (bench/data/tradeoff)\n"
        "  --out DIR       output directory (build/tradeoff)\n"
        "  --sweep LIST    only these groups or sweeps: single, biaxial, mpm, rve_size, dem_steps,\n"
        "                  real, tangent, mesh, mpm_ppc (a group's reference always runs)\n"
        "  --steps N       quick check of the machinery: every run stops at N x 0.1 %% strain\n"
        "                  (metrics past that are NaN; default 100 = 10 %%)\n"
        "  --dry-run       print the command lines, run nothing\n");
}

int main(int argc, char **argv) {
    static cfg L[MAXCFG];
    opts o;
    int n, i, k;
    char path[600];
    FILE *fp;
    double t0 = now();
    memset(&o, 0, sizeof o);
    o.threads = 2, o.bin = "build", o.data = "bench/data/tradeoff", o.out = "build/tradeoff";
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--full"))
            o.full = 1;
        else if (!strcmp(a, "--dry-run"))
            o.dry = 1;
        else if (!strcmp(a, "--threads") || !strcmp(a, "--bin") || !strcmp(a, "--data") ||
                 !strcmp(a, "--out") || !strcmp(a, "--sweep") || !strcmp(a, "--steps")) {
            if (!v) {
                fprintf(stderr, "bench_tradeoff: %s needs a value\n", a);
                return 2;
            }
            if (!strcmp(a, "--threads")) {
                char *end;
                long t = strtol(v, &end, 10);
                if (*end || t < 1 || t > 256) {
                    fprintf(stderr, "bench_tradeoff: --threads must be an integer in [1, 256], got '%s'\n",
                            v);
                    return 2;
                }
                o.threads = (int)t;
            } else if (!strcmp(a, "--steps")) {
                char *end;
                long t = strtol(v, &end, 10);
                if (*end || t < 1 || t > 1000) {
                    fprintf(stderr, "bench_tradeoff: --steps must be an integer in [1, 1000], got '%s'\n", v);
                    return 2;
                }
                o.steps = (int)t;
            } else if (!strcmp(a, "--bin"))
                o.bin = v;
            else if (!strcmp(a, "--data"))
                o.data = v;
            else if (!strcmp(a, "--out"))
                o.out = v;
            else {
                const char *names = ",single,biaxial,mpm,rve_size,dem_steps,real,tangent,mesh,mpm_ppc,",
                           *p = v;
                while (*p) {
                    size_t l = strcspn(p, ",");
                    char buf[64];
                    if (l == 0 || l > 60) {
                        fprintf(stderr, "bench_tradeoff: bad --sweep list '%s'\n", v);
                        return 2;
                    }
                    snprintf(buf, sizeof buf, ",%.*s,", (int)l, p);
                    if (!strstr(names, buf)) {
                        fprintf(stderr, "bench_tradeoff: unknown sweep '%.*s' (see --help)\n", (int)l, p);
                        return 2;
                    }
                    p += l;
                    if (*p == ',') ++p;
                }
                o.only = v;
            }
            ++i;
        } else {
            fprintf(stderr, "bench_tradeoff: unknown option %s (see --help)\n", a);
            return 2;
        }
    }
    /* the drivers and packings must be there */
    {
        const char *need[3] = {"femdem_biaxial", "femdem_biaxial_float", "mpmdem_biaxial"};
        for (k = 0; k < 3; ++k) {
            snprintf(path, sizeof path, "%s/%s", o.bin, need[k]);
            if (!file_exists(path)) {
                fprintf(stderr, "bench_tradeoff: %s not found (make %s; run from the repository root)\n",
                        path, path);
                return 1;
            }
        }
        snprintf(path, sizeof path, "%s/rve100.txt", o.data);
        if (!file_exists(path) || !file_exists("examples/data/rve400.txt")) {
            fprintf(stderr,
                    "bench_tradeoff: packings not found (%s, examples/data/rve400.txt); run from the "
                    "repository root or give --data\n",
                    path);
            return 1;
        }
    }
    n = build_list(L, &o);
    printf("bench_tradeoff: %s version, %d configurations, %d threads per run\n", o.full ? "full" : "short",
           n, o.threads);
    if (!o.dry && mkdirs(o.out)) {
        fprintf(stderr, "bench_tradeoff: cannot create %s\n", o.out);
        return 1;
    }
    for (i = 0; i < n; ++i) run_one(L, i, &o);
    if (o.dry) return 0;
    /* errors against each group's reference */
    for (i = 0; i < n; ++i) {
        int ref = -1;
        for (k = 0; k < n; ++k)
            if (L[k].is_ref && !strcmp(L[k].group, L[i].group)) ref = k;
        L[i].err_peak = L[i].err_sa = L[i].err_sb = L[i].ev_rms = L[i].err_ev = L[i].err_max = NAN;
        if (ref >= 0 && L[ref].ran && L[ref].c.n > 1 && L[i].ran && L[i].c.n > 1)
            compute_errors(&L[i], &L[ref]);
        if (L[i].is_ref && L[i].ran && L[i].c.n > 1) /* exactly zero, not an interpolation round-off */
            L[i].err_peak = L[i].err_sa = L[i].err_sb = L[i].ev_rms = L[i].err_ev = L[i].err_max = 0.0;
    }
    /* the swept factor alone: against the twin with the same RVE and 100 DEM steps, double, Taylor */
    for (i = 0; i < n; ++i) {
        L[i].err_base = NAN;
        if (L[i].kind != K_SINGLE || !L[i].ran || L[i].c.n < 2) continue;
        for (k = 0; k < n; ++k)
            if (L[k].kind == K_SINGLE && L[k].ran && L[k].c.n > 1 && !strcmp(L[k].packing, L[i].packing) &&
                L[k].dem_steps == 100 && !L[k].use_float && !strcmp(L[k].tangent, "taylor") &&
                L[k].reuse == 0) {
                cfg tmp = L[i];
                compute_errors(&tmp, &L[k]);
                L[i].err_base = k == i || L[k].c.eps == L[i].c.eps ? 0.0 : tmp.err_max;
                break;
            }
    }
    snprintf(path, sizeof path, "%s/tradeoff.csv", o.out);
    fp = fopen(path, "w");
    if (!fp) {
        fprintf(stderr, "bench_tradeoff: cannot write %s\n", path);
        return 1;
    }
    fprintf(
        fp,
        "group,sweep,config,test,disks,packing,dem_steps_per_increment,real,tangent,tangent_reuse,nx,ny,"
        "element,ppc,threads,"
        "completed,seconds,newton_iterations,mpm_steps,end_strain,peak_ratio,eps_at_peak,err_peak,eps_a,err_"
        "sa,"
        "eps_b,err_sb,ev_rms,err_ev,err_max,err_max_vs_100_steps_double_taylor_same_rve,reference,run_dir\n");
    printf("\n%-8s %-10s %-34s %3s %8s %7s %8s %8s %8s %9s %8s %8s\n", "group", "sweep", "config", "ok",
           "seconds", "newton", "peak%", "sA%", "sB%", "ev_rms", "max%", "twin%");
    for (i = 0; i < n; ++i) {
        cfg *c = &L[i];
        char b[6][32], refl[64] = "", nit[24] = "", nmpm[24] = ""; /* empty: not applicable */
        double ep = NAN, R = c->c.n > 1 ? peak_ratio(&c->c, &ep) : NAN;
        for (k = 0; k < n; ++k)
            if (L[k].is_ref && !strcmp(L[k].group, c->group)) snprintf(refl, sizeof refl, "%s", L[k].label);
        if (c->newton >= 0) snprintf(nit, sizeof nit, "%ld", c->newton);
        if (c->mpm_steps >= 0) snprintf(nmpm, sizeof nmpm, "%ld", c->mpm_steps);
        fprintf(fp,
                "%s,%s,%s,%s,%d,%s,%s%d,%s,%s,%g,%d,%d,%s,%d,%d,%s,%.3f,%s,%s,%.6g,%.6g,%.6g,%.6g,%g,%.6g,%g,"
                "%.6g,%.6g,"
                "%.6g,%.6g,%.6g,%s,%s/runs/%s\n",
                c->group, c->sweep, c->label,
                c->kind == K_SINGLE    ? "single"
                : c->kind == K_BIAXIAL ? "biaxial"
                                       : "mpm",
                c->disks ? c->disks : 400, c->packing, c->dem_steps ? "" : "adaptive", c->dem_steps,
                c->use_float ? "float" : "double", c->tangent, c->reuse, c->nx, c->ny,
                c->kind == K_MPM ? "" : c->element, c->ppc, o.threads, c->completed ? "yes" : "no",
                c->seconds, nit, nmpm, c->c.n ? c->c.eps[c->c.n - 1] : NAN, R, ep, c->err_peak, c->eps_a,
                c->err_sa, c->eps_b, c->err_sb, c->ev_rms, c->err_ev, c->err_max, c->err_base, refl, o.out,
                c->same_as >= 0 ? L[c->same_as].id : c->id);
        fmt(b[0], 32, c->err_peak, 100, "%.2f");
        fmt(b[1], 32, c->err_sa, 100, "%.2f");
        fmt(b[2], 32, c->err_sb, 100, "%.2f");
        fmt(b[3], 32, c->ev_rms, 1, "%.2e");
        fmt(b[4], 32, c->err_max, 100, "%.2f");
        fmt(b[5], 32, c->err_base, 100, "%.2f");
        printf("%-8s %-10s %-34s %3s %8.1f %7ld %8s %8s %8s %9s %8s %8s%s\n", c->group, c->sweep, c->label,
               c->completed ? "yes" : "NO", c->seconds, c->newton, b[0], b[1], b[2], b[3], b[4], b[5],
               c->is_ref         ? "  (reference)"
               : c->same_as >= 0 ? "  (same run as above)"
                                 : "");
    }
    k = close_written(fp, path);
    printf("\n");
    for (i = 0; i < n; ++i) {
        cfg *c = &L[i];
        printf("BENCH case=tradeoff group=%s sweep=%s config=\"%s\" completed=%d seconds=%.3f "
               "newton_iterations=%ld mpm_steps=%ld err_peak=%.4g eps_a=%g err_sa=%.4g eps_b=%g err_sb=%.4g "
               "ev_rms=%.4g err_max=%.4g "
               "err_twin=%.4g reference=%d\n",
               c->group, c->sweep, c->label, c->completed, c->seconds, c->newton, c->mpm_steps, c->err_peak,
               c->eps_a, c->err_sa, c->eps_b, c->err_sb, c->ev_rms, c->err_max, c->err_base, c->is_ref);
    }
    snprintf(path, sizeof path, "%s/tradeoff.svg", o.out);
    if (write_svg(path, L, n)) {
        fprintf(stderr, "bench_tradeoff: cannot write %s\n", path);
        k = 1;
    }
    if (!k)
        printf("wrote %s/tradeoff.csv and %s/tradeoff.svg (runs in %s/runs/); %.0f s in all\n", o.out, o.out,
               o.out, now() - t0);
    for (i = 0; i < n; ++i) {
        if (!L[i].completed && L[i].same_as < 0) {
            snprintf(path, sizeof path, "%s/runs/%s/log.txt", o.out, L[i].id);
            fprintf(stderr, "bench_tradeoff: run %d (%s, %s%s) failed: see %s\n", i, L[i].id, L[i].label,
                    L[i].is_ref ? ", the reference: no errors for its group" : "", path);
            k = 1;
        }
        curve_free(&L[i].c);
    }
    return k; /* every run must complete: a failed run fails `make bench` (its row says completed=no) */
}
