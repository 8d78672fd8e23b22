/* gk_io.h - output users expect: SVG plots, legacy VTK, progress lines.
 *                                                               (grainkit v0.1)
 * Dependency-free writers used by the example drivers, usable in your own:
 *
 *   gk_plot / gk_plot_svg      x-y line plot (up to GK_PLOT_MAX series) with
 *                              axes, "nice" ticks, grid, title and a legend
 *                              that never covers data: it goes to the first
 *                              inside corner (top right, top left, bottom
 *                              right, bottom left, then the edge middles)
 *                              that no curve crosses, else outside, right of
 *                              the axes. equal_aspect: one unit is as long
 *                              on both axes (geometry, Mohr circles).
 *   gk_field_svg               a scalar field on polygons (FEM elements, MPM
 *                              cells) or on dots (material points) at equal
 *                              aspect, with axes (ticks, labels with units),
 *                              a perceptually uniform colour map (viridis), a
 *                              colour bar with ticks and the quantity's unit,
 *                              the outline of the geometry (platens, footing,
 *                              walls) drawn on top, and an optional fixed
 *                              colour range so snapshots of a run compare
 *   gk_svg_field               the same with defaults (kept for old callers)
 *   gk_vtk_*                   legacy-VTK (ASCII) unstructured grids with
 *                              point and cell data (scalars, vectors, 3x3
 *                              tensors) for ParaView
 *   gk_progress                one line per step with elapsed time and ETA
 *   gk_progress_since          the same for a run resumed at step0 (a restart):
 *                              the ETA from the steps done since then
 *   gk_file_close (gk_base.h)  closes a file you wrote (a CSV) the way every
 *                              writer here does: fflush + ferror + fclose,
 *                              GK_ERR_IO naming the path and the reason when
 *                              any byte was lost (disk full, /dev/full)
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
    int equal_aspect; /* 1: one data unit spans as many pixels on x as on y */
} gk_plot;

/* A field plot; zero means the default for every member. */
typedef struct gk_field_def {
    const char *title;           /* NULL: none                                          */
    const char *label;           /* the colour bar's quantity with its unit, "eps_q [%]" */
    const char *xlabel, *ylabel; /* axis labels with units; NULL: "x [m]", "y [m]"      */
    double coord_scale;          /* axis values = coordinates x this (1e3: m to mm); 0: 1 */
    double dot;                  /* nv == 1: dot radius in data units; 0: 1 % of width */
    int fixed_range;             /* 1: colours span [vmin, vmax] (the same scale for every
                                    snapshot of a run); values beyond take the end colours */
    double vmin, vmax;
    int nlines;            /* outline polylines drawn on top (platens, walls, ...) */
    const int *line_len;   /* points in each polyline                            */
    const double *line_xy; /* their points, (x, y) pairs, polyline after polyline */
} gk_field_def;

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
 * coordinates xy[2 * (nv * k + v)]; or dots (nv == 1). value[k] per
 * polygon/dot (non-finite values are drawn grey). def may be NULL. */
GKDEF gk_result gk_field_svg(const char *path, const gk_field_def *def, int npoly, int nv, const double *xy,
                             const double *value, gk_err *err);
/* gk_field_svg with title, colour-bar label and dot radius only */
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
/* the same for a run that started (or restarted) at step0 at time t_start:
 * elapsed is since t_start, the ETA elapsed / (step - step0) x (nsteps -
 * step); gk_progress is step0 = 0 */
GKDEF void gk_progress_since(FILE *fp, long step, long step0, long nsteps, double t_start, const char *what);

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

/* Liang-Barsky: does the segment a-b meet the box bx = {xmin, xmax, ymin, ymax}? */
static int gk__seg_hits_box(double ax, double ay, double bx_, double by_, const double bx[4]) {
    double t0 = 0.0, t1 = 1.0, dx = bx_ - ax, dy = by_ - ay;
    double pp[4], qq[4];
    int i;
    pp[0] = -dx, pp[1] = dx, pp[2] = -dy, pp[3] = dy;
    qq[0] = ax - bx[0], qq[1] = bx[1] - ax, qq[2] = ay - bx[2], qq[3] = bx[3] - ay;
    for (i = 0; i < 4; ++i) {
        if (pp[i] == 0.0) {
            if (qq[i] < 0.0) return 0;
        } else {
            double r = qq[i] / pp[i];
            if (pp[i] < 0.0) {
                if (r > t1) return 0;
                if (r > t0) t0 = r;
            } else {
                if (r < t0) return 0;
                if (r < t1) t1 = r;
            }
        }
    }
    return 1;
}

/* the axes of a line plot: pixel margins, data window and scales */
typedef struct gk__frame {
    double W, H, ml, mr, mt, mb, x0, x1, y0, y1, sx, sy;
} gk__frame;

static void gk__frame_scale(gk__frame *f, int equal) {
    f->sx = (f->W - f->ml - f->mr) / (f->x1 - f->x0);
    f->sy = (f->H - f->mt - f->mb) / (f->y1 - f->y0);
    if (equal) { /* widen the window of the axis with the larger scale */
        if (f->sx > f->sy) {
            double c = 0.5 * (f->x0 + f->x1), h = 0.5 * (f->W - f->ml - f->mr) / f->sy;
            f->x0 = c - h, f->x1 = c + h, f->sx = f->sy;
        } else {
            double c = 0.5 * (f->y0 + f->y1), h = 0.5 * (f->H - f->mt - f->mb) / f->sx;
            f->y0 = c - h, f->y1 = c + h, f->sy = f->sx;
        }
    }
}

/* 1 if some drawn segment or single point of the plot meets the pixel box */
static int gk__plot_hits(const gk_plot *p, const gk__frame *f, const double box[4]) {
    int k, i;
    for (k = 0; k < p->ns; ++k) {
        double px = 0.0, py = 0.0;
        int have = 0;
        for (i = 0; i < p->s[k].n; ++i) {
            double x = p->s[k].x[i], y = p->s[k].y[i], X, Y;
            if (!isfinite(x) || !isfinite(y)) continue;
            X = f->ml + (x - f->x0) * f->sx;
            Y = f->H - f->mb - (y - f->y0) * f->sy;
            if (gk__seg_hits_box(have ? px : X, have ? py : Y, X, Y, box)) return 1;
            px = X, py = Y, have = 1;
        }
    }
    return 0;
}

GKDEF gk_result gk_plot_svg(const gk_plot *p, const char *path, gk_err *err) {
    FILE *fp;
    gk__frame f;
    double t, st, lw = 0.0, lh, box[4] = {0, 0, 0, 0}, x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    int k, i, nleg = 0, placed = 0;
    f.W = p->width > 0 ? p->width : 640, f.H = p->height > 0 ? p->height : 420;
    f.ml = 78, f.mr = 20, f.mt = 36, f.mb = 52;
    for (k = 0; k < p->ns; ++k)
        if (p->s[k].label) {
            double w = 30.0 + 6.6 * (double)strlen(p->s[k].label); /* text at ~0.55 em per character */
            if (w > lw) lw = w;
            ++nleg;
        }
    lh = 16.0 * nleg + 6.0;
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
    f.x0 = x0, f.x1 = x1, f.y0 = y0, f.y1 = y1;
    gk__frame_scale(&f, p->equal_aspect);
    if (nleg > 0) { /* the first inside spot that no curve crosses */
        double L = f.ml + 8, R = f.W - f.mr - 8 - lw - 10, T = f.mt + 8, B = f.H - f.mb - 8 - lh;
        double cx[8], cy[8];
        cx[0] = R, cy[0] = T, cx[1] = L, cy[1] = T, cx[2] = R, cy[2] = B, cx[3] = L, cy[3] = B;
        cx[4] = R, cy[4] = 0.5 * (T + B), cx[5] = L, cy[5] = 0.5 * (T + B);
        cx[6] = 0.5 * (L + R), cy[6] = T, cx[7] = 0.5 * (L + R), cy[7] = B;
        for (k = 0; k < 8 && !placed; ++k) {
            box[0] = cx[k], box[1] = cx[k] + lw + 10, box[2] = cy[k], box[3] = cy[k] + lh;
            if (box[0] >= L && box[1] <= f.W - f.mr - 8 && box[3] <= f.H - f.mb - 8 &&
                !gk__plot_hits(p, &f, box))
                placed = 1;
        }
        if (!placed) { /* outside: the axes make room on the right */
            f.mr = 20 + lw + 22;
            f.x0 = x0, f.x1 = x1, f.y0 = y0, f.y1 = y1;
            gk__frame_scale(&f, p->equal_aspect);
            box[0] = f.W - f.mr + 12, box[1] = box[0] + lw + 10, box[2] = f.mt, box[3] = f.mt + lh;
        }
    }
    fp = fopen(path, "w");
    if (!fp) return gk_err_set(err, GK_ERR_IO, "cannot write plot '%s'", path);
#define GK__X(x) (f.ml + ((x)-f.x0) * f.sx)
#define GK__Y(y) (f.H - f.mb - ((y)-f.y0) * f.sy)
    fprintf(
        fp,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" viewBox=\"0 0 %.0f %.0f\" "
        "font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\">\n",
        f.W, f.H, f.W, f.H);
    fprintf(fp, "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n");
    st = gk__nice_step(f.x1 - f.x0, 6);
    for (t = ceil(f.x0 / st) * st; t <= f.x1 + 1e-9 * st; t += st) {
        double tt = fabs(t) < 1e-12 * st ? 0.0 : t;
        fprintf(fp, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#e5e5e5\"/>\n", GK__X(tt),
                f.mt, GK__X(tt), f.H - f.mb);
        fprintf(fp, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%g</text>\n", GK__X(tt),
                f.H - f.mb + 16, tt);
    }
    st = gk__nice_step(f.y1 - f.y0, 6);
    for (t = ceil(f.y0 / st) * st; t <= f.y1 + 1e-9 * st; t += st) {
        double tt = fabs(t) < 1e-12 * st ? 0.0 : t;
        fprintf(fp, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#e5e5e5\"/>\n", f.ml,
                GK__Y(tt), f.W - f.mr, GK__Y(tt));
        fprintf(fp, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%g</text>\n", f.ml - 6, GK__Y(tt) + 4,
                tt);
    }
    fprintf(fp,
            "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#333\"/>\n",
            f.ml, f.mt, f.W - f.ml - f.mr, f.H - f.mt - f.mb);
    if (f.y0 < 0 && f.y1 > 0)
        fprintf(fp, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#999\"/>\n", f.ml,
                GK__Y(0.0), f.W - f.mr, GK__Y(0.0));
    fprintf(
        fp,
        "<clipPath id=\"gkclip\"><rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\"/></clipPath>\n",
        f.ml, f.mt, f.W - f.ml - f.mr, f.H - f.mt - f.mb);
    for (k = 0; k < p->ns; ++k) {
        const char *col = p->s[k].color ? p->s[k].color : gk__cycle[k % GK_PLOT_MAX];
        int started = 0;
        fprintf(fp,
                "<polyline class=\"series\" clip-path=\"url(#gkclip)\" fill=\"none\" stroke=\"%s\" "
                "stroke-width=\"1.8\"%s points=\"",
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
    if (nleg > 0) /* a box, then a line and the label per series */
        fprintf(fp,
                "<rect class=\"legend\" x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"white\" "
                "fill-opacity=\"0.85\" stroke=\"#ccc\"/>\n",
                box[0], box[2], box[1] - box[0], box[3] - box[2]);
    nleg = 0;
    for (k = 0; k < p->ns; ++k) {
        const char *col = p->s[k].color ? p->s[k].color : gk__cycle[k % GK_PLOT_MAX];
        if (p->s[k].label) {
            double lx = box[0] + 6, ly = box[2] + 14 + 16 * nleg++;
            fprintf(fp,
                    "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" "
                    "stroke-width=\"2\"%s/>\n",
                    lx, ly - 4, lx + 24, ly - 4, col, p->s[k].dashed ? " stroke-dasharray=\"6,4\"" : "");
            fprintf(fp, "<text x=\"%.1f\" y=\"%.1f\">", lx + 30, ly);
            gk__xml_text(fp, p->s[k].label);
            fprintf(fp, "</text>\n");
        }
    }
    if (p->title) {
        fprintf(fp, "<text x=\"%.1f\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">", 0.5 * f.W);
        gk__xml_text(fp, p->title);
        fprintf(fp, "</text>\n");
    }
    if (p->xlabel) {
        fprintf(fp, "<text x=\"%.1f\" y=\"%.0f\" text-anchor=\"middle\">", f.ml + 0.5 * (f.W - f.ml - f.mr),
                f.H - 12);
        gk__xml_text(fp, p->xlabel);
        fprintf(fp, "</text>\n");
    }
    if (p->ylabel) {
        fprintf(fp, "<text transform=\"translate(18,%.1f) rotate(-90)\" text-anchor=\"middle\">",
                f.mt + 0.5 * (f.H - f.mt - f.mb));
        gk__xml_text(fp, p->ylabel);
        fprintf(fp, "</text>\n");
    }
    fprintf(fp, "</svg>\n");
#undef GK__X
#undef GK__Y
    return gk_file_close(fp, path, err);
}

/* viridis, 9 control points, linear in between */
static void gk__colormap(double t, int *r, int *g, int *b) {
    static const double c[9][3] = {{68, 1, 84},    {71, 44, 122},  {59, 81, 139},
                                   {44, 113, 142}, {33, 144, 141}, {39, 173, 129},
                                   {92, 200, 99},  {170, 220, 50}, {253, 231, 37}};
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

GKDEF gk_result gk_field_svg(const char *path, const gk_field_def *def_in, int npoly, int nv,
                             const double *xy, const double *value, gk_err *err) {
    gk_field_def d;
    FILE *fp;
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300, v0 = 1e300, v1 = -1e300, sc, cs, dot, st, t;
    double ml = 70, mt = 36, mb = 48, plotw = 440, ploth, W, H, barx, bary0, bary1;
    int k, v;
    if (def_in)
        d = *def_in;
    else
        memset(&d, 0, sizeof d);
    if (npoly < 1 || nv < 1 || !xy || !value) return gk_err_set(err, GK_ERR_ARG, "empty field");
    if (d.fixed_range && !(isfinite(d.vmin) && isfinite(d.vmax) && d.vmax > d.vmin))
        return gk_err_set(err, GK_ERR_ARG, "fixed colour range [%g, %g] is not an interval", d.vmin, d.vmax);
    if (d.nlines < 0 || (d.nlines > 0 && (!d.line_len || !d.line_xy)))
        return gk_err_set(err, GK_ERR_ARG, "outline: %d polylines without their points", d.nlines);
    for (k = 0; k < d.nlines; ++k)
        if (d.line_len[k] < 0)
            return gk_err_set(err, GK_ERR_ARG, "outline polyline %d has %d points", k, d.line_len[k]);
    cs = d.coord_scale > 0 ? d.coord_scale : 1.0;
    for (k = 0; k < npoly * nv; ++k) {
        double x = xy[2 * k], y = xy[2 * k + 1];
        if (!isfinite(x) || !isfinite(y)) continue;
        if (x < x0) x0 = x;
        if (x > x1) x1 = x;
        if (y < y0) y0 = y;
        if (y > y1) y1 = y;
    }
    if (d.nlines > 0) { /* the outline is part of the picture */
        int L, npts = 0;
        for (L = 0; L < d.nlines; ++L) npts += d.line_len[L] > 0 ? d.line_len[L] : 0;
        for (k = 0; k < npts; ++k) {
            double x = d.line_xy[2 * k], y = d.line_xy[2 * k + 1];
            if (!isfinite(x) || !isfinite(y)) continue;
            if (x < x0) x0 = x;
            if (x > x1) x1 = x;
            if (y < y0) y0 = y;
            if (y > y1) y1 = y;
        }
    }
    if (!(x1 >= x0)) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
    if (!(x1 > x0)) x1 = x0 + 1;
    if (!(y1 > y0)) y1 = y0 + 1;
    dot = nv == 1 ? (d.dot > 0 ? d.dot : 0.01 * (x1 - x0)) : 0.0;
    x0 -= dot, x1 += dot, y0 -= dot, y1 += dot;
    if (d.fixed_range) {
        v0 = d.vmin, v1 = d.vmax;
    } else {
        for (k = 0; k < npoly; ++k)
            if (isfinite(value[k])) {
                if (value[k] < v0) v0 = value[k];
                if (value[k] > v1) v1 = value[k];
            }
        if (!(v1 >= v0)) v0 = 0, v1 = 1;
        if (v1 == v0) v1 = v0 + 1e-300 + fabs(v0) * 1e-12;
    }
    /* equal aspect, at most 440 x 600 pixels of field */
    sc = plotw / (x1 - x0);
    if ((y1 - y0) * sc > 600) sc = 600 / (y1 - y0);
    plotw = (x1 - x0) * sc;
    ploth = (y1 - y0) * sc;
    W = ml + plotw + 130;
    if (W < 360) W = 360;
    H = mt + ploth + mb;
    if (H < 240) H = 240;
    fp = fopen(path, "w");
    if (!fp) return gk_err_set(err, GK_ERR_IO, "cannot write field plot '%s'", path);
#define GK__FX(x) (ml + ((x)-x0) * sc)
#define GK__FY(y) (mt + (y1 - (y)) * sc)
    fprintf(
        fp,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" viewBox=\"0 0 %.0f %.0f\" "
        "font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\">\n<rect width=\"100%%\" "
        "height=\"100%%\" "
        "fill=\"white\"/>\n",
        W, H, W, H);
    for (k = 0; k < npoly; ++k) {
        char col[32];
        if (isfinite(value[k])) {
            int r, g, b;
            gk__colormap((value[k] - v0) / (v1 - v0), &r, &g, &b);
            snprintf(col, sizeof col, "rgb(%d,%d,%d)", r, g, b);
        } else {
            snprintf(col, sizeof col, "#bbbbbb"); /* no value */
        }
        if (nv == 1) {
            fprintf(fp, "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"%.2f\" fill=\"%s\"/>\n", GK__FX(xy[2 * k]),
                    GK__FY(xy[2 * k + 1]), dot * sc, col);
        } else {
            fprintf(fp, "<polygon fill=\"%s\" stroke=\"%s\" stroke-width=\"0.5\" points=\"", col, col);
            for (v = 0; v < nv; ++v)
                fprintf(fp, "%s%.2f,%.2f", v ? " " : "", GK__FX(xy[2 * (nv * k + v)]),
                        GK__FY(xy[2 * (nv * k + v) + 1]));
            fprintf(fp, "\"/>\n");
        }
    }
    /* the geometry's outline on top */
    if (d.nlines > 0) {
        const double *q = d.line_xy;
        int L;
        for (L = 0; L < d.nlines; ++L) {
            fprintf(
                fp,
                "<polyline class=\"outline\" fill=\"none\" stroke=\"black\" stroke-width=\"2\" points=\"");
            for (v = 0; v < d.line_len[L]; ++v, q += 2)
                fprintf(fp, "%s%.2f,%.2f", v ? " " : "", GK__FX(q[0]), GK__FY(q[1]));
            fprintf(fp, "\"/>\n");
        }
    }
    /* axes: a frame, ticks and labels in scaled coordinates */
    fprintf(fp,
            "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#333\"/>\n",
            ml, mt, plotw, ploth);
    st = gk__nice_step((x1 - x0) * cs, 5);
    for (t = ceil(x0 * cs / st) * st; t <= x1 * cs + 1e-9 * st; t += st) {
        double tt = fabs(t) < 1e-12 * st ? 0.0 : t, X = GK__FX(tt / cs);
        fprintf(fp, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#333\"/>\n", X,
                mt + ploth, X, mt + ploth + 5);
        fprintf(fp, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%g</text>\n", X, mt + ploth + 18, tt);
    }
    st = gk__nice_step((y1 - y0) * cs, 5);
    for (t = ceil(y0 * cs / st) * st; t <= y1 * cs + 1e-9 * st; t += st) {
        double tt = fabs(t) < 1e-12 * st ? 0.0 : t, Y = GK__FY(tt / cs);
        fprintf(fp, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#333\"/>\n", ml - 5, Y,
                ml, Y);
        fprintf(fp, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%g</text>\n", ml - 8, Y + 4, tt);
    }
    fprintf(fp, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">", ml + 0.5 * plotw, mt + ploth + 38);
    gk__xml_text(fp, d.xlabel ? d.xlabel : "x [m]");
    fprintf(fp, "</text>\n<text transform=\"translate(16,%.1f) rotate(-90)\" text-anchor=\"middle\">",
            mt + 0.5 * ploth);
    gk__xml_text(fp, d.ylabel ? d.ylabel : "y [m]");
    fprintf(fp, "</text>\n");
#undef GK__FX
#undef GK__FY
    /* colour bar with ticks; its label (quantity and unit) above it */
    barx = ml + plotw + 26, bary0 = mt + 22, bary1 = H - mb;
    if (bary1 - bary0 > 300) bary1 = bary0 + 300;
    for (k = 0; k < 64; ++k) {
        int r, g, b;
        double h = (bary1 - bary0) / 64.0;
        gk__colormap(k / 63.0, &r, &g, &b);
        fprintf(fp, "<rect x=\"%.1f\" y=\"%.2f\" width=\"16\" height=\"%.2f\" fill=\"rgb(%d,%d,%d)\"/>\n",
                barx, bary1 - (k + 1) * h, h + 0.5, r, g, b);
    }
    fprintf(fp, "<rect x=\"%.1f\" y=\"%.1f\" width=\"16\" height=\"%.1f\" fill=\"none\" stroke=\"#333\"/>\n",
            barx, bary0, bary1 - bary0);
    st = gk__nice_step(v1 - v0, 5);
    for (t = ceil(v0 / st) * st; t <= v1 + 1e-9 * st; t += st) {
        double tt = fabs(t) < 1e-12 * st ? 0.0 : t, Y = bary1 - (tt - v0) / (v1 - v0) * (bary1 - bary0);
        fprintf(fp, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#333\"/>\n", barx + 16, Y,
                barx + 20, Y);
        fprintf(fp, "<text x=\"%.1f\" y=\"%.1f\">%g</text>\n", barx + 23, Y + 4, tt);
    }
    if (d.label) {
        fprintf(fp, "<text class=\"colorbar-label\" x=\"%.1f\" y=\"%.1f\">", barx - 4, bary0 - 8);
        gk__xml_text(fp, d.label);
        fprintf(fp, "</text>\n");
    }
    if (d.title) {
        fprintf(fp, "<text x=\"%.1f\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">", 0.5 * W);
        gk__xml_text(fp, d.title);
        fprintf(fp, "</text>\n");
    }
    fprintf(fp, "</svg>\n");
    return gk_file_close(fp, path, err);
}

GKDEF gk_result gk_svg_field(const char *path, const char *title, const char *label, int npoly, int nv,
                             const double *xy, const double *value, double dot, gk_err *err) {
    gk_field_def d;
    memset(&d, 0, sizeof d);
    d.title = title;
    d.label = label;
    d.dot = dot;
    return gk_field_svg(path, &d, npoly, nv, xy, value, err);
}

/* a write that already failed (the stream's error flag) is reported at once */
static gk_result gk__vtk_status(gk_vtk *v) {
    if (ferror(v->fp)) return gk_err_set(&v->err, GK_ERR_IO, "error writing VTK file (disk full?)");
    return GK_OK;
}

GKDEF gk_result gk_vtk_open(gk_vtk *v, const char *path, const char *title) {
    memset(v, 0, sizeof *v);
    v->fp = fopen(path, "w");
    if (!v->fp) return gk_err_set(&v->err, GK_ERR_IO, "cannot write VTK file '%s'", path);
    fprintf(v->fp, "# vtk DataFile Version 3.0\n%s\nASCII\nDATASET UNSTRUCTURED_GRID\n",
            title ? title : "grainkit");
    return GK_OK;
}

GKDEF gk_result gk_vtk_points(gk_vtk *v, int n, const double *xyz) {
    int k;
    if (!v->fp) return GK_ERR_STATE;
    v->npoints = n;
    fprintf(v->fp, "POINTS %d double\n", n);
    for (k = 0; k < n; ++k) fprintf(v->fp, "%.9g %.9g %.9g\n", xyz[3 * k], xyz[3 * k + 1], xyz[3 * k + 2]);
    return gk__vtk_status(v);
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
    return gk__vtk_status(v);
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
    return gk__vtk_status(v);
}

static gk_result gk__vtk_tensor(gk_vtk *v, int cell, const char *name, const double *val9) {
    int k, j, n;
    gk_result r = gk__vtk_section(v, cell);
    if (r) return r;
    n = cell ? v->ncells : v->npoints;
    fprintf(v->fp, "TENSORS %s double\n", name);
    for (k = 0; k < n; ++k)
        for (j = 0; j < 3; ++j)
            fprintf(v->fp, "%.9g %.9g %.9g\n", val9[9 * k + 3 * j], val9[9 * k + 3 * j + 1],
                    val9[9 * k + 3 * j + 2]);
    return gk__vtk_status(v);
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
    for (k = 0; k < v->npoints; ++k)
        fprintf(v->fp, "%.9g %.9g %.9g\n", val3[3 * k], val3[3 * k + 1], val3[3 * k + 2]);
    return gk__vtk_status(v);
}

GKDEF gk_result gk_vtk_close(gk_vtk *v) {
    FILE *fp = v->fp;
    if (!fp) return GK_ERR_STATE;
    v->fp = NULL;
    return gk_file_close(fp, "VTK file", &v->err);
}

GKDEF void gk_progress_since(FILE *fp, long step, long step0, long nsteps, double t_start, const char *what) {
    double el = gk_wtime() - t_start,
           eta = step > step0 ? el / (double)(step - step0) * (nsteps - step) : 0.0;
    fprintf(fp ? fp : stderr, "step %ld/%ld  %s | %.1f s elapsed, ETA %.1f s\n", step, nsteps,
            what ? what : "", el, eta);
    fflush(fp ? fp : stderr);
}

GKDEF void gk_progress(FILE *fp, long step, long nsteps, double t_start, const char *what) {
    gk_progress_since(fp, step, 0, nsteps, t_start, what);
}

#endif /* GK_IO implementation */
