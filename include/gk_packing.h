/* gk_packing.h - packings as data: read, write, generate.      (grainkit v0.1)
 *
 * A gk_packing is a plain list of disks (2D) or spheres (3D) in a periodic
 * cell: what a DEM scene or an RVE (gk_dem.h) is created from and written
 * back to. This header reads and writes the text format below and generates
 * random loose packings to be consolidated by gk_rve_consolidate.
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_PACKING_IMPLEMENTATION) in one file.
 *
 *   gk_packing pk; gk_err e;
 *   if (gk_packing_read("rve400.txt", &pk, NULL, &e)) { puts(e.msg); return 1; }
 *   ...
 *   gk_packing_free(&pk);
 *
 * WHAT IS HERE
 *   gk_packing_init / gk_packing_free   arrays for n particles (allocator hooks)
 *   gk_packing_read / gk_packing_parse   the text format, from a file or memory
 *   gk_packing_write                     the same format (round-trips exactly)
 *   gk_packing_generate                  a random loose (non-overlapping) cloud
 *   gk_packing_tile                      nx x ny (x nz) copies of a periodic packing
 *   gk_packing_subset                    the particles inside a box (a specimen cut
 *                                        from a packing, e.g. for gk_scene.h)
 *   gk_particle_volume                   pi r^2 (2D) or 4/3 pi r^3 (3D)
 *
 * ERRORS are values: every fallible call returns gk_result and writes its
 * message into the gk_err you pass (may be NULL); on error the output packing
 * is left untouched.
 *
 * Units: SI (lengths in m). LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_PACKING_H
#define GK_PACKING_H

#include "gk_base.h"

/* ------------------------------------------------------------- packing */
/* A packing: particles in a periodic cell, in the text format below:
 *   line 1:  "2 N Lx Ly" or "3 N Lx Ly Lz"
 *   lines starting with '#': comments; grainkit writes and reads an optional
 *            "# cell h00 h01 ... " line holding the full (skewed) cell matrix
 *   N lines: "x y r" or "x y z r" (SI units), positions in the cell.
 * The text is untrusted: the particle lines are counted before anything is
 * allocated (memory follows what the text holds, never the N it announces);
 * a data or '# cell' line longer than 1023 characters, a NUL byte, a
 * non-finite number, a radius <= 0 or a cell whose volume is not a finite
 * positive number is refused, the message naming the line. */
typedef struct gk_packing {
    int dim, n;
    double h[9]; /* cell matrix (a box is diag(Lx, Ly, Lz)); 2D: h22 = 1 */
    double *x, *y, *z, *r;
    gk_allocator alloc;
} gk_packing;

typedef enum gk_psd_kind { GK_PSD_UNIFORM = 0, GK_PSD_TABLE_NUMBER = 1, GK_PSD_TABLE_MASS = 2 } gk_psd_kind;

/* Random loose packing (no overlaps) to be consolidated by gk_rve_consolidate. */
typedef struct gk_gen_def {
    int dim, n;
    gk_psd_kind psd;
    double r_min, r_max;     /* GK_PSD_UNIFORM: radii uniform in [r_min, r_max]     */
    int ntable;              /* table kinds: ntable points (radius, cumulative     */
    const double *table_r;   /*   fraction passing, by number or by mass), radii   */
    const double *table_cum; /*   increasing, cum from 0 to 1                       */
    double packing_fraction; /* of the initial cloud; 0 -> 0.5 (2D), 0.3 (3D)      */
    double aspect[3];        /* cell edge ratios; 0 -> cube/square                  */
    uint64_t seed;
} gk_gen_def;

/* pi r^2 (a disk, 2D) or 4/3 pi r^3 (a sphere, 3D) */
static inline double gk_particle_volume(int dim, double r) {
    return dim == 2 ? GK_PI * r * r : 4.0 / 3.0 * GK_PI * r * r * r;
}

#ifdef __cplusplus
extern "C" {
#endif

GKDEF gk_result gk_packing_init(gk_packing *pk, int dim, int n, const gk_allocator *alloc, gk_err *err);
GKDEF void gk_packing_free(gk_packing *pk);
GKDEF gk_result gk_packing_read(const char *path, gk_packing *pk, const gk_allocator *alloc, gk_err *err);
GKDEF gk_result gk_packing_parse(const char *text, size_t len, gk_packing *pk, const gk_allocator *alloc,
                                 gk_err *err);
GKDEF gk_result gk_packing_write(const char *path, const gk_packing *pk, const char *comment, gk_err *err);
GKDEF gk_result gk_packing_generate(gk_packing *pk, const gk_gen_def *def, const gk_allocator *alloc,
                                    gk_err *err);
/* A periodic packing repeated nx x ny (x nz in 3D; nz ignored in 2D) times:
 * cell h diag(nx, ny, nz), copy (a, b, c) at a e1 + b e2 + c e3 (e_k the cell
 * edges, positions wrapped into the cell first); copies follow each other,
 * a fastest, each in pk's order. Still periodic: the copies match across
 * every face. */
GKDEF gk_result gk_packing_tile(const gk_packing *pk, int nx, int ny, int nz, gk_packing *out,
                                const gk_allocator *alloc, gk_err *err);
/* The particles whose centre lies in the box [lo, hi] (whole != 0: the
 * whole disk or sphere, centre -+ r), in pk's order, shifted by -lo; the
 * result's cell is the box diag(hi - lo). Positions are taken as given
 * (not wrapped). GK_ERR_ARG if the box holds none. */
GKDEF gk_result gk_packing_subset(const gk_packing *pk, const double lo[3], const double hi[3], int whole,
                                  gk_packing *out, const gk_allocator *alloc, gk_err *err);

#ifdef __cplusplus
}
#endif
#endif /* GK_PACKING_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_PACKING_IMPLEMENTATION)) && !defined(GK_PACKING_IMPL_ONCE)
#define GK_PACKING_IMPL_ONCE

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ================================================================ packing */
GKDEF gk_result gk_packing_init(gk_packing *pk, int dim, int n, const gk_allocator *alloc, gk_err *err) {
    gk_packing p;
    if (dim != 2 && dim != 3) return gk_err_set(err, GK_ERR_ARG, "dimension %d (must be 2 or 3)", dim);
    if (n < 1) return gk_err_set(err, GK_ERR_ARG, "particle count %d (must be >= 1)", n);
    memset(&p, 0, sizeof p);
    if (alloc) p.alloc = *alloc;
    p.dim = dim;
    p.n = n;
    gk_m3_identity(p.h);
    p.x = (double *)gk_alloc(&p.alloc, (size_t)n * sizeof(double));
    p.y = (double *)gk_alloc(&p.alloc, (size_t)n * sizeof(double));
    p.z = (double *)gk_alloc(&p.alloc, (size_t)n * sizeof(double));
    p.r = (double *)gk_alloc(&p.alloc, (size_t)n * sizeof(double));
    if (!p.x || !p.y || !p.z || !p.r) {
        gk_packing_free(&p);
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for %d particles", n);
    }
    memset(p.z, 0, (size_t)n * sizeof(double));
    *pk = p;
    return GK_OK;
}

GKDEF void gk_packing_free(gk_packing *pk) {
    gk_free(&pk->alloc, pk->x);
    gk_free(&pk->alloc, pk->y);
    gk_free(&pk->alloc, pk->z);
    gk_free(&pk->alloc, pk->r);
    pk->x = pk->y = pk->z = pk->r = NULL;
    pk->n = 0;
}

/* line reader over a memory buffer; a line longer than the buffer or
 * holding a NUL byte is flagged, never silently cut */
typedef struct gk__lines {
    const char *p, *end;
    long lineno;
    int toolong, nul;
    char line[1024];
} gk__lines;

static int gk__next_line(gk__lines *L) {
    size_t k = 0;
    if (L->p >= L->end) return 0;
    L->toolong = L->nul = 0;
    while (L->p < L->end && *L->p != '\n') {
        if (*L->p == '\0') L->nul = 1;
        if (k + 1 < sizeof L->line)
            L->line[k++] = *L->p;
        else
            L->toolong = 1;
        ++L->p;
    }
    if (L->p < L->end) ++L->p;
    L->line[k] = '\0';
    ++L->lineno;
    return 1;
}

static int gk__blank(const char *s) {
    while (*s == ' ' || *s == '\t' || *s == '\r') ++s;
    return *s == '\0';
}

/* parse up to max doubles; returns the count; sets *bad if a token is not a number */
static int gk__parse_doubles(const char *s, double *out, int max, int *bad) {
    int k = 0;
    char *e;
    *bad = 0;
    for (;;) {
        double v;
        while (*s == ' ' || *s == '\t' || *s == '\r' || *s == ',') ++s;
        if (*s == '\0' || *s == '#') break;
        v = strtod(s, &e);
        if (e == s) {
            *bad = 1;
            break;
        }
        if (k < max) out[k] = v;
        ++k;
        s = e;
    }
    return k;
}

/* 0: blank; 1: a comment; 2: the '# cell' line; 3: a particle line */
static int gk__line_kind(const char *s) {
    while (*s == ' ' || *s == '\t') ++s;
    if (*s == '#') return strncmp(s, "# cell ", 7) == 0 ? 2 : 1;
    return gk__blank(s) ? 0 : 3;
}

/* a line that cannot be read whole is an error; only a plain comment may be cut */
static gk_result gk__line_ok(const gk__lines *L, int kind, gk_err *err) {
    if (L->nul)
        return gk_err_set(err, GK_ERR_FORMAT, "line %ld holds a NUL byte (not a text packing?)", L->lineno);
    if (L->toolong && kind != 1)
        return gk_err_set(err, GK_ERR_FORMAT, "line %ld is longer than %d characters", L->lineno,
                          (int)sizeof L->line - 1);
    return GK_OK;
}

GKDEF gk_result gk_packing_parse(const char *text, size_t len, gk_packing *out, const gk_allocator *alloc,
                                 gk_err *err) {
    gk__lines L;
    double hd[5], h[9], vals[8];
    int nh, bad, dim, n, k = 0;
    long body, lines = 0;
    const char *first;
    gk_packing pk;
    gk_result r;
    if (!text) return gk_err_set(err, GK_ERR_ARG, "no packing text given");
    L.p = text;
    L.end = text + len;
    L.lineno = 0;
    do {
        if (!gk__next_line(&L)) return gk_err_set(err, GK_ERR_FORMAT, "empty packing: no header line");
        if ((r = gk__line_ok(&L, 3, err)) != GK_OK) return r;
    } while (gk__blank(L.line));
    nh = gk__parse_doubles(L.line, hd, 5, &bad);
    if (bad || nh < 4)
        return gk_err_set(err, GK_ERR_FORMAT, "line %ld: header must be 'dim N Lx Ly [Lz]'", L.lineno);
    if (hd[0] != 2.0 && hd[0] != 3.0)
        return gk_err_set(err, GK_ERR_FORMAT, "line %ld: dimension %g (must be 2 or 3)", L.lineno, hd[0]);
    dim = (int)hd[0];
    if (nh != dim + 2)
        return gk_err_set(err, GK_ERR_FORMAT, "line %ld: a %dD header has %d numbers, found %d", L.lineno,
                          dim, dim + 2, nh);
    if (!(hd[1] >= 1 && hd[1] <= 2e9) || (double)(int)hd[1] != hd[1])
        return gk_err_set(err, GK_ERR_FORMAT, "line %ld: particle count %g invalid", L.lineno, hd[1]);
    n = (int)hd[1];
    gk_m3_identity(h);
    for (k = 0; k < dim; ++k) {
        if (!(hd[2 + k] > 0.0) || !isfinite(hd[2 + k]))
            return gk_err_set(err, GK_ERR_CELL, "line %ld: cell length %g must be > 0", L.lineno, hd[2 + k]);
        h[4 * k] = hd[2 + k];
    }
    /* count the particle lines before allocating: memory follows what the
     * text holds, never what its header announces */
    first = L.p;
    body = L.lineno;
    while (gk__next_line(&L)) {
        int kind = gk__line_kind(L.line);
        if ((r = gk__line_ok(&L, kind, err)) != GK_OK) return r;
        if (kind == 3 && ++lines > n)
            return gk_err_set(err, GK_ERR_FORMAT, "line %ld: more particle lines than the %d announced",
                              L.lineno, n);
    }
    if (lines != n)
        return gk_err_set(err, GK_ERR_FORMAT, "packing announces %d particles but lists %ld", n, lines);
    r = gk_packing_init(&pk, dim, n, alloc, err);
    if (r) return r;
    L.p = first;
    L.lineno = body;
    k = 0;
    while (gk__next_line(&L)) {
        const char *s = L.line;
        int nv, kind = gk__line_kind(s);
        if (kind == 2) {
            double hc[9];
            int nc = gk__parse_doubles(s + strspn(s, " \t") + 7, hc, 9, &bad), a, b;
            if (bad || nc != dim * dim) {
                gk_packing_free(&pk);
                return gk_err_set(err, GK_ERR_FORMAT, "line %ld: '# cell' needs %d numbers", L.lineno,
                                  dim * dim);
            }
            for (a = 0; a < nc; ++a)
                if (!isfinite(hc[a])) {
                    gk_packing_free(&pk);
                    return gk_err_set(err, GK_ERR_CELL, "line %ld: '# cell' entry %d is %g (must be finite)",
                                      L.lineno, a + 1, hc[a]);
                }
            gk_m3_identity(h);
            for (a = 0; a < dim; ++a)
                for (b = 0; b < dim; ++b) h[3 * a + b] = hc[dim * a + b];
        }
        if (kind != 3) continue;
        nv = gk__parse_doubles(s, vals, 8, &bad);
        if (bad || nv != dim + 1) {
            gk_packing_free(&pk);
            return gk_err_set(err, GK_ERR_FORMAT, "line %ld: expected %d numbers (%s r), found %s", L.lineno,
                              dim + 1, dim == 2 ? "x y" : "x y z",
                              bad ? "a non-number" : "a different count");
        }
        for (nv = 0; nv <= dim; ++nv)
            if (!isfinite(vals[nv])) {
                gk_packing_free(&pk);
                return gk_err_set(err, GK_ERR_NAN, "line %ld: particle %d has a non-finite value", L.lineno,
                                  k);
            }
        if (!(vals[dim] > 0.0)) {
            gk_packing_free(&pk);
            return gk_err_set(err, GK_ERR_RADIUS, "line %ld: particle %d has radius %g <= 0", L.lineno, k,
                              vals[dim]);
        }
        pk.x[k] = vals[0];
        pk.y[k] = vals[1];
        pk.z[k] = dim == 3 ? vals[2] : 0.0;
        pk.r[k] = vals[dim];
        ++k;
    }
    if (!(gk_m3_det(h) > 0.0) || !isfinite(gk_m3_det(h))) {
        gk_packing_free(&pk);
        return gk_err_set(err, GK_ERR_CELL, "cell matrix has det %g (must be finite and > 0)", gk_m3_det(h));
    }
    gk_m3_copy(h, pk.h);
    *out = pk;
    return GK_OK;
}

GKDEF gk_result gk_packing_read(const char *path, gk_packing *pk, const gk_allocator *alloc, gk_err *err) {
    char *buf = NULL;
    size_t len = 0;
    gk_result r;
    if (!path) return gk_err_set(err, GK_ERR_ARG, "no packing path given");
    r = gk_file_read(path, alloc, &buf, &len, err);
    if (r) return r;
    r = gk_packing_parse(buf, len, pk, alloc, err);
    gk_free(alloc, buf);
    if (r && err) {
        char msg[GK_ERR_MSG_LEN];
        memcpy(msg, err->msg, sizeof msg);
        gk_err_set(err, r, "%s: %s", path, msg);
    }
    return r;
}

GKDEF gk_result gk_packing_write(const char *path, const gk_packing *pk, const char *comment, gk_err *err) {
    FILE *fp;
    int k, skew = 0, a, b;
    if (!pk || !pk->x || pk->n < 1) return gk_err_set(err, GK_ERR_ARG, "empty packing");
    for (a = 0; a < pk->dim; ++a)
        for (b = 0; b < pk->dim; ++b)
            if (a != b && pk->h[3 * a + b] != 0.0) skew = 1;
    fp = fopen(path, "w");
    if (!fp) return gk_err_set(err, GK_ERR_IO, "cannot write packing '%s'", path);
    if (pk->dim == 2)
        fprintf(fp, "2 %d %.17g %.17g\n", pk->n, pk->h[0], pk->h[4]);
    else
        fprintf(fp, "3 %d %.17g %.17g %.17g\n", pk->n, pk->h[0], pk->h[4], pk->h[8]);
    fprintf(fp, "# written by grainkit %s\n", GK_VERSION_STRING);
    if (comment && comment[0]) {
        const char *c = comment;
        fputs("# ", fp);
        for (; *c; ++c) {
            fputc(*c, fp);
            if (*c == '\n' && c[1]) fputs("# ", fp);
        }
        if (c[-1] != '\n') fputc('\n', fp);
    }
    if (skew) {
        fputs("# cell", fp);
        for (a = 0; a < pk->dim; ++a)
            for (b = 0; b < pk->dim; ++b) fprintf(fp, " %.17g", pk->h[3 * a + b]);
        fputc('\n', fp);
    }
    for (k = 0; k < pk->n; ++k) {
        if (pk->dim == 2)
            fprintf(fp, "%.17g %.17g %.17g\n", pk->x[k], pk->y[k], pk->r[k]);
        else
            fprintf(fp, "%.17g %.17g %.17g %.17g\n", pk->x[k], pk->y[k], pk->z[k], pk->r[k]);
    }
    return gk_file_close(fp, path, err);
}

GKDEF gk_result gk_packing_generate(gk_packing *out, const gk_gen_def *def, const gk_allocator *alloc,
                                    gk_err *err) {
    gk_packing pk;
    gk_rng rng;
    double vs = 0.0, phi, side, asp[3], V, *rr;
    int k, dim = def->dim, n = def->n;
    gk_result res;
    if (dim != 2 && dim != 3) return gk_err_set(err, GK_ERR_ARG, "dimension %d (must be 2 or 3)", dim);
    if (n < 1) return gk_err_set(err, GK_ERR_ARG, "particle count %d (must be >= 1)", n);
    phi = def->packing_fraction > 0 ? def->packing_fraction : (dim == 2 ? 0.5 : 0.3);
    if (!(phi < (dim == 2 ? 0.7 : 0.45)))
        return gk_err_set(err, GK_ERR_ARG, "initial packing fraction %g too dense for random addition", phi);
    if (def->psd == GK_PSD_UNIFORM) {
        if (!(def->r_min > 0.0) || !(def->r_max >= def->r_min) || !isfinite(def->r_max))
            return gk_err_set(err, GK_ERR_RADIUS, "radius range [%g, %g] invalid", def->r_min, def->r_max);
    } else if (def->psd == GK_PSD_TABLE_NUMBER || def->psd == GK_PSD_TABLE_MASS) {
        if (def->ntable < 2 || !def->table_r || !def->table_cum)
            return gk_err_set(err, GK_ERR_ARG, "size-distribution table needs >= 2 points");
        for (k = 0; k < def->ntable; ++k) {
            if (!(def->table_r[k] > 0.0) || (k && !(def->table_r[k] > def->table_r[k - 1])))
                return gk_err_set(err, GK_ERR_RADIUS, "table radius %d (%g) must be > 0 and increasing", k,
                                  def->table_r[k]);
            if (!(def->table_cum[k] >= 0.0 && def->table_cum[k] <= 1.0) ||
                (k && def->table_cum[k] < def->table_cum[k - 1]))
                return gk_err_set(err, GK_ERR_ARG, "table cumulative fraction %d (%g) must rise from 0 to 1",
                                  k, def->table_cum[k]);
        }
        if (def->table_cum[0] != 0.0 || def->table_cum[def->ntable - 1] != 1.0)
            return gk_err_set(err, GK_ERR_ARG, "table cumulative fractions must start at 0 and end at 1");
    } else {
        return gk_err_set(err, GK_ERR_ARG, "unknown size-distribution kind %d", (int)def->psd);
    }
    res = gk_packing_init(&pk, dim, n, alloc, err);
    if (res) return res;
    gk_rng_seed(&rng, def->seed);
    rr = pk.r;
    if (def->psd == GK_PSD_UNIFORM) {
        for (k = 0; k < n; ++k) rr[k] = def->r_min + (def->r_max - def->r_min) * gk_rng_uniform(&rng);
    } else {
        /* number fractions per table interval (radii uniform inside an interval) */
        double w[256], tot = 0.0;
        int nt = def->ntable, b;
        if (nt > 257) nt = 257;
        for (b = 0; b + 1 < nt; ++b) {
            double frac = def->table_cum[b + 1] - def->table_cum[b];
            if (def->psd == GK_PSD_TABLE_MASS) { /* number ~ mass / mean particle volume */
                double r0 = def->table_r[b], r1 = def->table_r[b + 1], mv;
                mv = dim == 2 ? GK_PI * (r1 * r1 + r0 * r1 + r0 * r0) / 3.0
                              : GK_PI * (r1 + r0) * (r1 * r1 + r0 * r0) / 3.0; /* mean of r^dim volume */
                frac = frac / mv;
            }
            w[b] = frac;
            tot += frac;
        }
        for (k = 0; k < n; ++k) {
            double u = gk_rng_uniform(&rng) * tot, acc = 0.0;
            for (b = 0; b + 2 < nt; ++b) {
                acc += w[b];
                if (u < acc) break;
            }
            rr[k] = def->table_r[b] + (def->table_r[b + 1] - def->table_r[b]) * gk_rng_uniform(&rng);
        }
    }
    /* largest first for random sequential addition */
    for (k = 1; k < n; ++k) {
        double v = rr[k];
        int t = k - 1;
        while (t >= 0 && rr[t] < v) {
            rr[t + 1] = rr[t];
            --t;
        }
        rr[t + 1] = v;
    }
    for (k = 0; k < n; ++k) vs += gk_particle_volume(dim, rr[k]);
    for (k = 0; k < 3; ++k) asp[k] = def->aspect[k] > 0 ? def->aspect[k] : 1.0;
    V = vs / phi;
    side = pow(V / (asp[0] * asp[1] * (dim == 3 ? asp[2] : 1.0)), 1.0 / dim);
    gk_m3_identity(pk.h);
    for (k = 0; k < dim; ++k) pk.h[4 * k] = side * asp[k];
    if (!(vs > 0.0) || !isfinite(gk_m3_det(pk.h)) || !(gk_m3_det(pk.h) > 0.0)) {
        gk_packing_free(&pk);
        return gk_err_set(err, GK_ERR_ARG,
                          "radii (largest %g) and cell aspect give a cell volume %g out of range", rr[0],
                          gk_m3_det(pk.h));
    }
    /* random sequential addition with a linked-cell grid updated as particles land */
    {
        double *sx = (double *)gk_alloc(alloc, (size_t)n * sizeof(double));
        double *sy = (double *)gk_alloc(alloc, (size_t)n * sizeof(double));
        double *sz = (double *)gk_alloc(alloc, (size_t)n * sizeof(double));
        int placed = 0, nbin[3], b;
        int32_t *head = NULL, *next = NULL;
        double cut = 2.0 * rr[0];
        for (k = 0; k < 3; ++k) {
            nbin[k] = k < dim ? (pk.h[4 * k] / cut < 1024.0 ? (int)(pk.h[4 * k] / cut) : 1024) : 1;
            if (nbin[k] < 1) nbin[k] = 1;
        }
        head = (int32_t *)gk_alloc(alloc, (size_t)nbin[0] * nbin[1] * nbin[2] * sizeof(int32_t));
        next = (int32_t *)gk_alloc(alloc, (size_t)n * sizeof(int32_t));
        res = (sx && sy && sz && head && next) ? GK_OK : GK_ERR_ALLOC;
        if (res) gk_err_set(err, res, "out of memory generating %d particles", n);
        for (b = 0; !res && b < nbin[0] * nbin[1] * nbin[2]; ++b) head[b] = -1;
        while (!res && placed < n) {
            int attempt, ok = 0;
            for (attempt = 0; attempt < 20000 && !ok; ++attempt) {
                double s[3];
                int bi[3], o0, o1, o2, clash = 0;
                for (k = 0; k < 3; ++k) s[k] = k < dim ? gk_rng_uniform(&rng) : 0.0;
                for (k = 0; k < 3; ++k) bi[k] = (int)(s[k] * nbin[k]) % nbin[k];
                for (o2 = (dim == 3 ? -1 : 0); o2 <= (dim == 3 ? 1 : 0) && !clash; ++o2)
                    for (o1 = -1; o1 <= 1 && !clash; ++o1)
                        for (o0 = -1; o0 <= 1 && !clash; ++o0) {
                            int cx = (bi[0] + o0 + nbin[0]) % nbin[0], cy = (bi[1] + o1 + nbin[1]) % nbin[1];
                            int cz = (bi[2] + o2 + nbin[2]) % nbin[2], q;
                            for (q = head[cx + nbin[0] * (cy + nbin[1] * cz)]; q >= 0 && !clash;
                                 q = next[q]) {
                                double ds[3], d[3], R = rr[q] + rr[placed];
                                ds[0] = sx[q] - s[0];
                                ds[1] = sy[q] - s[1];
                                ds[2] = dim == 3 ? sz[q] - s[2] : 0.0;
                                for (k = 0; k < 3; ++k) ds[k] -= rint(ds[k]);
                                gk_m3_matvec(pk.h, ds, d);
                                if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < R * R) clash = 1;
                            }
                            /* with few bins the same bin can be visited twice: harmless */
                        }
                if (!clash) {
                    int bb = bi[0] + nbin[0] * (bi[1] + nbin[1] * bi[2]);
                    sx[placed] = s[0];
                    sy[placed] = s[1];
                    sz[placed] = s[2];
                    next[placed] = head[bb];
                    head[bb] = placed;
                    ok = 1;
                }
            }
            if (!ok) {
                res = gk_err_set(
                    err, GK_ERR_ARG,
                    "could not place particle %d of %d without overlap: lower packing_fraction (%g)", placed,
                    n, phi);
                break;
            }
            ++placed;
        }
        if (!res)
            for (k = 0; k < n; ++k) {
                double s[3], x[3];
                s[0] = sx[k];
                s[1] = sy[k];
                s[2] = sz[k];
                gk_m3_matvec(pk.h, s, x);
                pk.x[k] = x[0];
                pk.y[k] = x[1];
                pk.z[k] = dim == 3 ? x[2] : 0.0;
            }
        gk_free(alloc, sx);
        gk_free(alloc, sy);
        gk_free(alloc, sz);
        gk_free(alloc, head);
        gk_free(alloc, next);
    }
    if (res) {
        gk_packing_free(&pk);
        return res;
    }
    *out = pk;
    return GK_OK;
}

GKDEF gk_result gk_packing_tile(const gk_packing *pk, int nx, int ny, int nz, gk_packing *out,
                                const gk_allocator *alloc, gk_err *err) {
    gk_packing t;
    double hi[9];
    int dim, rep[3], a, b, c, p, k, q = 0;
    long total;
    gk_result res;
    if (!pk || !pk->x || !pk->y || !pk->r || pk->n < 1)
        return gk_err_set(err, GK_ERR_ARG, "tile: empty packing");
    dim = pk->dim;
    rep[0] = nx;
    rep[1] = ny;
    rep[2] = dim == 3 ? nz : 1;
    if (rep[0] < 1 || rep[1] < 1 || rep[2] < 1)
        return gk_err_set(err, GK_ERR_ARG, "tile: copies %d x %d x %d must be >= 1", nx, ny,
                          dim == 3 ? nz : 1);
    total = (long)pk->n * rep[0] * rep[1] * rep[2];
    if (total > 2000000000L) return gk_err_set(err, GK_ERR_ARG, "tile: %ld particles are too many", total);
    if (!(gk_m3_inverse(pk->h, hi) > 0.0)) return gk_err_set(err, GK_ERR_CELL, "tile: singular cell");
    if ((res = gk_packing_init(&t, dim, (int)total, alloc, err)) != GK_OK) return res;
    gk_m3_copy(pk->h, t.h);
    for (k = 0; k < 3; ++k) /* column k of h scaled by rep[k] */
        for (a = 0; a < 3; ++a) t.h[3 * a + k] *= rep[k];
    if (dim == 2) t.h[8] = 1.0;
    for (c = 0; c < rep[2]; ++c)
        for (b = 0; b < rep[1]; ++b)
            for (a = 0; a < rep[0]; ++a)
                for (p = 0; p < pk->n; ++p) {
                    double x[3], s[3], y[3];
                    x[0] = pk->x[p];
                    x[1] = pk->y[p];
                    x[2] = dim == 3 && pk->z ? pk->z[p] : 0.0;
                    gk_m3_matvec(hi, x, s);
                    for (k = 0; k < 3; ++k) s[k] = k < dim ? s[k] - floor(s[k]) : 0.0;
                    s[0] += a;
                    s[1] += b;
                    s[2] += c;
                    gk_m3_matvec(pk->h, s, y);
                    t.x[q] = y[0];
                    t.y[q] = y[1];
                    t.z[q] = dim == 3 ? y[2] : 0.0;
                    t.r[q] = pk->r[p];
                    ++q;
                }
    *out = t;
    return GK_OK;
}

GKDEF gk_result gk_packing_subset(const gk_packing *pk, const double lo[3], const double hi[3], int whole,
                                  gk_packing *out, const gk_allocator *alloc, gk_err *err) {
    gk_packing t;
    int dim, p, k, cnt = 0, q = 0;
    gk_result res;
    if (!pk || !pk->x || !pk->y || !pk->r || pk->n < 1)
        return gk_err_set(err, GK_ERR_ARG, "subset: empty packing");
    if (!lo || !hi) return gk_err_set(err, GK_ERR_ARG, "subset: no box given");
    dim = pk->dim;
    for (k = 0; k < dim; ++k)
        if (!isfinite(lo[k]) || !isfinite(hi[k]) || !(hi[k] > lo[k]))
            return gk_err_set(err, GK_ERR_ARG, "subset: box axis %d [%g, %g] is not an interval", k, lo[k],
                              hi[k]);
    for (q = 0; q < 2; ++q) { /* count, then copy */
        for (p = 0; p < pk->n; ++p) {
            double x[3], m = whole ? pk->r[p] : 0.0;
            int in = 1;
            x[0] = pk->x[p];
            x[1] = pk->y[p];
            x[2] = dim == 3 && pk->z ? pk->z[p] : 0.0;
            for (k = 0; k < dim; ++k)
                if (!(x[k] - m >= lo[k] && x[k] + m <= hi[k])) in = 0;
            if (!in) continue;
            if (q == 1) {
                t.x[cnt] = x[0] - lo[0];
                t.y[cnt] = x[1] - lo[1];
                t.z[cnt] = dim == 3 ? x[2] - lo[2] : 0.0;
                t.r[cnt] = pk->r[p];
            }
            ++cnt;
        }
        if (q == 0) {
            if (cnt < 1) return gk_err_set(err, GK_ERR_ARG, "subset: no particle inside the box");
            if ((res = gk_packing_init(&t, dim, cnt, alloc, err)) != GK_OK) return res;
            gk_m3_identity(t.h);
            for (k = 0; k < dim; ++k) t.h[4 * k] = hi[k] - lo[k];
            cnt = 0;
        }
    }
    *out = t;
    return GK_OK;
}

#endif /* GK_PACKING_IMPLEMENTATION */
