/* gk_io.h - output users expect: SVG plots, legacy VTK, progress lines.
 *                                                               (grainkit v0.1)
 * Dependency-free writers used by the example drivers, usable in your own:
 *
 *   gk_plot / gk_plot_svg      x-y line plot (up to GK_PLOT_MAX series) with
 *                              axes, "nice" ticks, grid, legend, title
 *   gk_svg_field               a scalar field on polygons (FEM elements, MPM
 *                              cells) or on dots (material points), with a
 *                              perceptually uniform colour map and colour bar
 *   gk_vtk_*                   legacy-VTK (ASCII) unstructured grids with
 *                              point and cell data (scalars, vectors, 3x3
 *                              tensors) for ParaView
 *   gk_progress                one line per step with elapsed time and ETA
 *   gk_wtime                   wall-clock seconds (clock_gettime when the
 *                              includer defines _POSIX_C_SOURCE >= 199309L,
 *                              else omp_get_wtime with OpenMP, else time())
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_IO_IMPLEMENTATION) in one file.
 * Every writer returns a gk_result (GK_ERR_IO with the path on failure).
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_IO_H
#define GK_IO_H

#include "gk_base.h"
#include <stdio.h>

#define GK_PLOT_MAX 8

typedef struct gk_series {
    const double *x, *y;
    int n;
    const char *label; /* legend text (NULL: no legend entry)      */
    const char *color; /* SVG colour, NULL: from the default cycle */
    int dashed;
} gk_series;

typedef struct gk_plot {
    const char *title, *xlabel, *ylabel;
    gk_series s[GK_PLOT_MAX];
    int ns;
    int width, height; /* pixels; 0 -> 640 x 420 */
    int has_xlim, has_ylim;
    double xlim[2], ylim[2];
} gk_plot;

typedef struct gk_vtk {
    FILE *fp;
    int npoints, ncells;
    int in_point_data, in_cell_data;
    gk_err err;
} gk_vtk;

/* VTK cell types used by grainkit */
#define GK_VTK_VERTEX 1
#define GK_VTK_QUAD 9
#define GK_VTK_HEX 12
#define GK_VTK_QUAD8 23

#ifdef __cplusplus
extern "C" {
#endif

GKDEF double gk_wtime(void);
GKDEF void gk_plot_init(gk_plot *p, const char *title, const char *xlabel, const char *ylabel);
GKDEF int gk_plot_add(gk_plot *p, const double *x, const double *y, int n, const char *label);
GKDEF gk_result gk_plot_svg(const gk_plot *p, const char *path, gk_err *err);

/* Scalar field. Polygons: npoly polygons of nv vertices each, vertex
 * coordinates xy[2 * (nv * k + v)]; or dots (nv == 1) of radius `dot` in
 * data units. value[k] per polygon/dot. */
GKDEF gk_result gk_svg_field(const char *path, const char *title, const char *label, int npoly, int nv,
                             const double *xy, const double *value, double dot, gk_err *err);

/* Legacy VTK: open, points (xyz, 3 per point), cells (conn: nv per cell,
 * same type for all), then any number of point-data and cell-data arrays. */
GKDEF gk_result gk_vtk_open(gk_vtk *v, const char *path, const char *title);
GKDEF gk_result gk_vtk_points(gk_vtk *v, int n, const double *xyz);
GKDEF gk_result gk_vtk_cells(gk_vtk *v, int ncells, int nv, const int *conn, int vtk_type);
GKDEF gk_result gk_vtk_point_scalar(gk_vtk *v, const char *name, const double *val);
GKDEF gk_result gk_vtk_point_vector(gk_vtk *v, const char *name, const double *val3);
GKDEF gk_result gk_vtk_point_tensor(gk_vtk *v, const char *name, const double *val9);
GKDEF gk_result gk_vtk_cell_scalar(gk_vtk *v, const char *name, const double *val);
GKDEF gk_result gk_vtk_cell_tensor(gk_vtk *v, const char *name, const double *val9);
GKDEF gk_result gk_vtk_close(gk_vtk *v);

/* "step 12/100  eps 1.20 %  ... | 3.4 s elapsed, ETA 25.1 s" on stderr
 * (or fp); `what` is any extra text. */
GKDEF void gk_progress(FILE *fp, long step, long nsteps, double t_start, const char *what);

#ifdef __cplusplus
}
#endif
#endif /* GK_IO_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_IO_IMPLEMENTATION)) && !defined(GK_IO_IMPL_ONCE)
#define GK_IO_IMPL_ONCE

#include <string.h>
#include <time.h>

GKDEF double gk_wtime(void) {
#if defined(_POSIX_C_SOURCE) && _POSIX_C_SOURCE >= 199309L
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
#elif defined(_OPENMP)
    return omp_get_wtime();
#else
    return (double)time(NULL);
#endif
}

GKDEF void gk_plot_init(gk_plot *p, const char *title, const char *xlabel, const char *ylabel) {
    memset(p, 0, sizeof *p);
    p->title = title;
    p->xlabel = xlabel;
    p->ylabel = ylabel;
}

GKDEF int gk_plot_add(gk_plot *p, const double *x, const double *y, int n, const char *label) {
    if (p->ns >= GK_PLOT_MAX) return -1;
    p->s[p->ns].x = x;
    p->s[p->ns].y = y;
    p->s[p->ns].n = n;
    p->s[p->ns].label = label;
    p->s[p->ns].color = NULL;
    p->s[p->ns].dashed = 0;
    return p->ns++;
}

/* tick step: 1, 2 or 5 times a power of ten, about n ticks over the span */
static double gk__nice_step(double span, int n) {
    double raw = span / n, mag, f;
    if (!(raw > 0.0) || !isfinite(raw)) return 1.0;
    mag = pow(10.0, floor(log10(raw)));
    f = raw / mag;
    return (f < 1.5 ? 1.0 : f < 3.5 ? 2.0 : f < 7.5 ? 5.0 : 10.0) * mag;
}

static void gk__xml_text(FILE *fp, const char *s) {
    for (; s && *s; ++s) {
        if (*s == '<')
            fputs("&lt;", fp);
        else if (*s == '>')
            fputs("&gt;", fp);
        else if (*s == '&')
            fputs("&amp;", fp);
        else
            fputc(*s, fp);
    }
}

static const char *gk__cycle[GK_PLOT_MAX] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                                             "#9467bd", "#8c564b", "#e377c2", "#17becf"};

GKDEF gk_result gk_plot_svg(const gk_plot *p, const char *path, gk_err *err) {
    FILE *fp;
    int W = p->width > 0 ? p->width : 640, H = p->height > 0 ? p->height : 420;
    double ml = 78, mr = 20, mt = 36, mb = 52, x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300, sx, sy, t, st;
    double lx, lw = 0.0; /* legend: left edge and width (text at ~0.55 em per character) */
    int k, i, nleg = 0;
    for (k = 0; k < p->ns; ++k)
        if (p->s[k].label) {
            double w = 30.0 + 6.6 * (double)strlen(p->s[k].label);
            if (w > lw) lw = w;
            ++nleg;
        }
    lx = W - mr - 8 - lw;
    if (lx < ml + 8) lx = ml + 8;
    for (k = 0; k < p->ns; ++k)
        for (i = 0; i < p->s[k].n; ++i) {
            double x = p->s[k].x[i], y = p->s[k].y[i];
            if (!isfinite(x) || !isfinite(y)) continue;
            if (x < x0) x0 = x;
            if (x > x1) x1 = x;
            if (y < y0) y0 = y;
            if (y > y1) y1 = y;
        }
    if (p->has_xlim) {
        x0 = p->xlim[0];
        x1 = p->xlim[1];
    }
    if (p->has_ylim) {
        y0 = p->ylim[0];
        y1 = p->ylim[1];
    }
    if (!(x1 >= x0)) x0 = 0, x1 = 1;
    if (!(y1 >= y0)) y0 = 0, y1 = 1;
    if (x1 == x0) x0 -= 0.5, x1 += 0.5;
    if (y1 == y0) y0 -= 0.5 * (fabs(y0) + 1), y1 += 0.5 * (fabs(y1) + 1);
    if (!p->has_ylim) { /* a little head room */
        double d = 0.05 * (y1 - y0);
        y0 -= d;
        y1 += d;
    }
    fp = fopen(path, "w");
    if (!fp) return gk_err_set(err, GK_ERR_IO, "cannot write plot '%s'", path);
    sx = (W - ml - mr) / (x1 - x0);
    sy = (H - mt - mb) / (y1 - y0);
#define GK__X(x) (ml + ((x)-x0) * sx)
#define GK__Y(y) (H - mb - ((y)-y0) * sy)
    fprintf(fp,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\" "
            "font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\">\n",
            W, H, W, H);
    fprintf(fp, "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n");
    st = gk__nice_step(x1 - x0, 6);
    for (t = ceil(x0 / st) * st; t <= x1 + 1e-9 * st; t += st) {
        double tt = fabs(t) < 1e-12 * st ? 0.0 : t;
        fprintf(fp, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#e5e5e5\"/>\n", GK__X(tt), mt,
                GK__X(tt), H - mb);
        fprintf(fp, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%g</text>\n", GK__X(tt), H - mb + 16, tt);
    }
    st = gk__nice_step(y1 - y0, 6);
    for (t = ceil(y0 / st) * st; t <= y1 + 1e-9 * st; t += st) {
        double tt = fabs(t) < 1e-12 * st ? 0.0 : t;
        fprintf(fp, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#e5e5e5\"/>\n", ml, GK__Y(tt),
                W - mr, GK__Y(tt));
        fprintf(fp, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%g</text>\n", ml - 6, GK__Y(tt) + 4, tt);
    }
    fprintf(fp, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#333\"/>\n", ml, mt,
            W - ml - mr, H - mt - mb);
    if (y0 < 0 && y1 > 0)
        fprintf(fp, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#999\"/>\n", ml, GK__Y(0.0), W - mr,
                GK__Y(0.0));
    fprintf(fp, "<clipPath id=\"gkclip\"><rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\"/></clipPath>\n", ml,
            mt, W - ml - mr, H - mt - mb);
    for (k = 0; k < p->ns; ++k) {
        const char *col = p->s[k].color ? p->s[k].color : gk__cycle[k % GK_PLOT_MAX];
        int started = 0;
        fprintf(fp, "<polyline clip-path=\"url(#gkclip)\" fill=\"none\" stroke=\"%s\" stroke-width=\"1.8\"%s points=\"",
                col, p->s[k].dashed ? " stroke-dasharray=\"6,4\"" : "");
        for (i = 0; i < p->s[k].n; ++i) {
            double x = p->s[k].x[i], y = p->s[k].y[i];
            if (!isfinite(x) || !isfinite(y)) continue;
            fprintf(fp, "%s%.2f,%.2f", started ? " " : "", GK__X(x), GK__Y(y));
            started = 1;
        }
        fprintf(fp, "\"/>\n");
        if (p->s[k].n == 1 && isfinite(p->s[k].x[0]) && isfinite(p->s[k].y[0]))
            fprintf(fp, "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"3\" fill=\"%s\"/>\n", GK__X(p->s[k].x[0]),
                    GK__Y(p->s[k].y[0]), col);
    }
    if (nleg > 0) /* legend over the curves: a box, then a line and the label per series */
        fprintf(fp,
                "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"white\" fill-opacity=\"0.85\" "
                "stroke=\"#ccc\"/>\n",
                lx - 6, mt + 4, lw + 10, 16.0 * nleg + 6);
    nleg = 0;
    for (k = 0; k < p->ns; ++k) {
        const char *col = p->s[k].color ? p->s[k].color : gk__cycle[k % GK_PLOT_MAX];
        if (p->s[k].label) {
            double ly = mt + 14 + 16 * nleg++;
            fprintf(fp, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" stroke-width=\"2\"%s/>\n",
                    lx, ly - 4, lx + 24, ly - 4, col, p->s[k].dashed ? " stroke-dasharray=\"6,4\"" : "");
            fprintf(fp, "<text x=\"%.1f\" y=\"%.1f\">", lx + 30, ly);
            gk__xml_text(fp, p->s[k].label);
            fprintf(fp, "</text>\n");
        }
    }
    if (p->title) {
        fprintf(fp, "<text x=\"%.1f\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">", 0.5 * W);
        gk__xml_text(fp, p->title);
        fprintf(fp, "</text>\n");
    }
    if (p->xlabel) {
        fprintf(fp, "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">", ml + 0.5 * (W - ml - mr), H - 12);
        gk__xml_text(fp, p->xlabel);
        fprintf(fp, "</text>\n");
    }
    if (p->ylabel) {
        fprintf(fp, "<text transform=\"translate(18,%.1f) rotate(-90)\" text-anchor=\"middle\">", mt + 0.5 * (H - mt - mb));
        gk__xml_text(fp, p->ylabel);
        fprintf(fp, "</text>\n");
    }
    fprintf(fp, "</svg>\n");
#undef GK__X
#undef GK__Y
    if (fclose(fp) != 0) return gk_err_set(err, GK_ERR_IO, "error writing plot '%s'", path);
    return GK_OK;
}

/* viridis, 9 control points, linear in between */
static void gk__colormap(double t, int *r, int *g, int *b) {
    static const double c[9][3] = {{68, 1, 84},    {71, 44, 122},  {59, 81, 139},   {44, 113, 142}, {33, 144, 141},
                                   {39, 173, 129}, {92, 200, 99},  {170, 220, 50},  {253, 231, 37}};
    double u;
    int k;
    if (!(t >= 0.0)) t = 0.0;
    if (t > 1.0) t = 1.0;
    u = t * 8.0;
    k = (int)u;
    if (k > 7) k = 7;
    u -= k;
    *r = (int)(c[k][0] + u * (c[k + 1][0] - c[k][0]) + 0.5);
    *g = (int)(c[k][1] + u * (c[k + 1][1] - c[k][1]) + 0.5);
    *b = (int)(c[k][2] + u * (c[k + 1][2] - c[k][2]) + 0.5);
}

GKDEF gk_result gk_svg_field(const char *path, const char *title, const char *label, int npoly, int nv,
                             const double *xy, const double *value, double dot, gk_err *err) {
    FILE *fp;
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300, v0 = 1e300, v1 = -1e300, sc, W = 560, Hh, ml = 20,
           mt = 36, plotw = 440;
    int k, v, nval = npoly;
    if (npoly < 1 || nv < 1) return gk_err_set(err, GK_ERR_ARG, "empty field");
    for (k = 0; k < npoly * nv; ++k) {
        double x = xy[2 * k], y = xy[2 * k + 1];
        if (x - dot < x0) x0 = x - dot;
        if (x + dot > x1) x1 = x + dot;
        if (y - dot < y0) y0 = y - dot;
        if (y + dot > y1) y1 = y + dot;
    }
    for (k = 0; k < nval; ++k)
        if (isfinite(value[k])) {
            if (value[k] < v0) v0 = value[k];
            if (value[k] > v1) v1 = value[k];
        }
    if (!(v1 >= v0)) v0 = 0, v1 = 1;
    if (v1 == v0) v1 = v0 + 1e-300 + fabs(v0) * 1e-12;
    if (!(x1 > x0)) x1 = x0 + 1;
    if (!(y1 > y0)) y1 = y0 + 1;
    sc = plotw / (x1 - x0);
    Hh = (y1 - y0) * sc + mt + 30;
    if (Hh < 260) Hh = 260;
    fp = fopen(path, "w");
    if (!fp) return gk_err_set(err, GK_ERR_IO, "cannot write field plot '%s'", path);
    fprintf(fp,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" viewBox=\"0 0 %.0f %.0f\" "
            "font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\">\n<rect width=\"100%%\" height=\"100%%\" "
            "fill=\"white\"/>\n",
            W, Hh, W, Hh);
    for (k = 0; k < npoly; ++k) {
        int r, g, b;
        double t = isfinite(value[k]) ? (value[k] - v0) / (v1 - v0) : 0.0;
        gk__colormap(t, &r, &g, &b);
        if (nv == 1) {
            fprintf(fp, "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"%.2f\" fill=\"rgb(%d,%d,%d)\"/>\n",
                    ml + (xy[2 * k] - x0) * sc, mt + (y1 - xy[2 * k + 1]) * sc, dot * sc, r, g, b);
        } else {
            fprintf(fp, "<polygon fill=\"rgb(%d,%d,%d)\" stroke=\"rgb(%d,%d,%d)\" stroke-width=\"0.5\" points=\"", r, g, b,
                    r, g, b);
            for (v = 0; v < nv; ++v)
                fprintf(fp, "%s%.2f,%.2f", v ? " " : "", ml + (xy[2 * (nv * k + v)] - x0) * sc,
                        mt + (y1 - xy[2 * (nv * k + v) + 1]) * sc);
            fprintf(fp, "\"/>\n");
        }
    }
    /* colour bar */
    for (k = 0; k < 64; ++k) {
        int r, g, b;
        double h = (Hh - mt - 40) / 64.0;
        gk__colormap(k / 63.0, &r, &g, &b);
        fprintf(fp, "<rect x=\"%.1f\" y=\"%.2f\" width=\"16\" height=\"%.2f\" fill=\"rgb(%d,%d,%d)\"/>\n", ml + plotw + 24,
                Hh - 30 - (k + 1) * h, h + 0.5, r, g, b);
    }
    fprintf(fp, "<text x=\"%.1f\" y=\"%.1f\">%.4g</text>\n", ml + plotw + 44, mt + 10, v1);
    fprintf(fp, "<text x=\"%.1f\" y=\"%.1f\">%.4g</text>\n", ml + plotw + 44, Hh - 30, v0);
    if (label) {
        fprintf(fp, "<text x=\"%.1f\" y=\"%.1f\">", ml + plotw + 20, Hh - 10);
        gk__xml_text(fp, label);
        fprintf(fp, "</text>\n");
    }
    if (title) {
        fprintf(fp, "<text x=\"%.1f\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">", 0.5 * W);
        gk__xml_text(fp, title);
        fprintf(fp, "</text>\n");
    }
    fprintf(fp, "</svg>\n");
    if (fclose(fp) != 0) return gk_err_set(err, GK_ERR_IO, "error writing '%s'", path);
    return GK_OK;
}

GKDEF gk_result gk_vtk_open(gk_vtk *v, const char *path, const char *title) {
    memset(v, 0, sizeof *v);
    v->fp = fopen(path, "w");
    if (!v->fp) return gk_err_set(&v->err, GK_ERR_IO, "cannot write VTK file '%s'", path);
    fprintf(v->fp, "# vtk DataFile Version 3.0\n%s\nASCII\nDATASET UNSTRUCTURED_GRID\n", title ? title : "grainkit");
    return GK_OK;
}

GKDEF gk_result gk_vtk_points(gk_vtk *v, int n, const double *xyz) {
    int k;
    if (!v->fp) return GK_ERR_STATE;
    v->npoints = n;
    fprintf(v->fp, "POINTS %d double\n", n);
    for (k = 0; k < n; ++k) fprintf(v->fp, "%.9g %.9g %.9g\n", xyz[3 * k], xyz[3 * k + 1], xyz[3 * k + 2]);
    return GK_OK;
}

GKDEF gk_result gk_vtk_cells(gk_vtk *v, int ncells, int nv, const int *conn, int vtk_type) {
    int k, j;
    if (!v->fp) return GK_ERR_STATE;
    v->ncells = ncells;
    fprintf(v->fp, "CELLS %d %d\n", ncells, ncells * (nv + 1));
    for (k = 0; k < ncells; ++k) {
        fprintf(v->fp, "%d", nv);
        for (j = 0; j < nv; ++j) fprintf(v->fp, " %d", conn ? conn[nv * k + j] : k);
        fputc('\n', v->fp);
    }
    fprintf(v->fp, "CELL_TYPES %d\n", ncells);
    for (k = 0; k < ncells; ++k) fprintf(v->fp, "%d\n", vtk_type);
    return GK_OK;
}

static gk_result gk__vtk_section(gk_vtk *v, int cell) {
    if (!v->fp) return GK_ERR_STATE;
    if (cell && !v->in_cell_data) {
        fprintf(v->fp, "CELL_DATA %d\n", v->ncells);
        v->in_cell_data = 1;
        v->in_point_data = 0;
    } else if (!cell && !v->in_point_data) {
        fprintf(v->fp, "POINT_DATA %d\n", v->npoints);
        v->in_point_data = 1;
        v->in_cell_data = 0;
    }
    return GK_OK;
}

static gk_result gk__vtk_scalar(gk_vtk *v, int cell, const char *name, const double *val) {
    int k, n;
    gk_result r = gk__vtk_section(v, cell);
    if (r) return r;
    n = cell ? v->ncells : v->npoints;
    fprintf(v->fp, "SCALARS %s double 1\nLOOKUP_TABLE default\n", name);
    for (k = 0; k < n; ++k) fprintf(v->fp, "%.9g\n", isfinite(val[k]) ? val[k] : 0.0);
    return GK_OK;
}

static gk_result gk__vtk_tensor(gk_vtk *v, int cell, const char *name, const double *val9) {
    int k, j, n;
    gk_result r = gk__vtk_section(v, cell);
    if (r) return r;
    n = cell ? v->ncells : v->npoints;
    fprintf(v->fp, "TENSORS %s double\n", name);
    for (k = 0; k < n; ++k)
        for (j = 0; j < 3; ++j)
            fprintf(v->fp, "%.9g %.9g %.9g\n", val9[9 * k + 3 * j], val9[9 * k + 3 * j + 1], val9[9 * k + 3 * j + 2]);
    return GK_OK;
}

GKDEF gk_result gk_vtk_point_scalar(gk_vtk *v, const char *name, const double *val) {
    return gk__vtk_scalar(v, 0, name, val);
}
GKDEF gk_result gk_vtk_cell_scalar(gk_vtk *v, const char *name, const double *val) {
    return gk__vtk_scalar(v, 1, name, val);
}
GKDEF gk_result gk_vtk_point_tensor(gk_vtk *v, const char *name, const double *val9) {
    return gk__vtk_tensor(v, 0, name, val9);
}
GKDEF gk_result gk_vtk_cell_tensor(gk_vtk *v, const char *name, const double *val9) {
    return gk__vtk_tensor(v, 1, name, val9);
}
GKDEF gk_result gk_vtk_point_vector(gk_vtk *v, const char *name, const double *val3) {
    int k;
    gk_result r = gk__vtk_section(v, 0);
    if (r) return r;
    fprintf(v->fp, "VECTORS %s double\n", name);
    for (k = 0; k < v->npoints; ++k) fprintf(v->fp, "%.9g %.9g %.9g\n", val3[3 * k], val3[3 * k + 1], val3[3 * k + 2]);
    return GK_OK;
}

GKDEF gk_result gk_vtk_close(gk_vtk *v) {
    int bad;
    if (!v->fp) return GK_ERR_STATE;
    bad = ferror(v->fp);
    if (fclose(v->fp) != 0 || bad) {
        v->fp = NULL;
        return gk_err_set(&v->err, GK_ERR_IO, "error writing VTK file");
    }
    v->fp = NULL;
    return GK_OK;
}

GKDEF void gk_progress(FILE *fp, long step, long nsteps, double t_start, const char *what) {
    double el = gk_wtime() - t_start, eta = step > 0 ? el / step * (nsteps - step) : 0.0;
    fprintf(fp ? fp : stderr, "step %ld/%ld  %s | %.1f s elapsed, ETA %.1f s\n", step, nsteps, what ? what : "", el,
            eta);
    fflush(fp ? fp : stderr);
}

#endif /* GK_IO implementation */
