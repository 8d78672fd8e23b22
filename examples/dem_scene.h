/* dem_scene.h - what the single-scale DEM drivers (dem_biaxial.c,
 * dem_collapse.c) share: strict number parsing, the output directory and
 * the VTK / SVG pictures of a gk_scene (gk_scene.h). */
#ifndef DEM_SCENE_H
#define DEM_SCENE_H

#include "gk_scene.h"
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* the whole string must be a finite number */
static int dsc_num(const char *s, double *v) {
    char *end;
    errno = 0;
    *v = strtod(s, &end);
    return !(end != s && *end == '\0' && errno == 0 && isfinite(*v));
}

/* "v1,v2,..." into t (at most cap values, increasing, >= 0; > 0 with
 * positive): the count, or -1 */
static int dsc_list(const char *s, double *t, int cap, int positive) {
    int n = 0;
    const char *p = s;
    while (*p) {
        char buf[64];
        size_t len = strcspn(p, ",");
        double v;
        if (len == 0 || len >= sizeof buf || n == cap) return -1;
        memcpy(buf, p, len);
        buf[len] = '\0';
        if (dsc_num(buf, &v) || v < 0 || (positive && v == 0) || (n > 0 && v <= t[n - 1])) return -1;
        t[n++] = v;
        p += len;
        if (*p == ',') ++p;
    }
    return n;
}

static int dsc_mkdir(const char *prog, const char *d) {
    if (mkdir(d, 0755) && errno != EEXIST) return fprintf(stderr, "%s: cannot create %s\n", prog, d), 1;
    return 0;
}

/* particles_TAG.vtk and walls_TAG.vtk (ParaView), 2D also particles_TAG.svg;
 * non-zero (message on stderr) if a file cannot be written */
static int dsc_pictures(const char *prog, const gk_scene *sc, const char *out, const char *tag,
                        const char *title) {
    char path[1200];
    gk_err err;
    snprintf(path, sizeof path, "%s/particles_%s.vtk", out, tag);
    if (gk_scene_write_vtk(sc, path, &err)) return fprintf(stderr, "%s: %s\n", prog, err.msg), 1;
    snprintf(path, sizeof path, "%s/walls_%s.vtk", out, tag);
    if (gk_scene_write_walls_vtk(sc, path, &err)) return fprintf(stderr, "%s: %s\n", prog, err.msg), 1;
    if (sc->dim == 2) {
        snprintf(path, sizeof path, "%s/particles_%s.svg", out, tag);
        if (gk_scene_write_svg(sc, path, title, "speed [m/s]", NULL, &err))
            return fprintf(stderr, "%s: %s\n", prog, err.msg), 1;
    }
    return 0;
}

/* an x-y plot of up to four series (NULL: absent) plus horizontal reference
 * lines; non-zero if it cannot be written */
static int dsc_plot(const char *prog, const char *path, const char *title, const char *xl, const char *yl,
                    const double *x, int n, const double *const y[4], const char *const lab[4], int nref,
                    const double *ref, const char *const *reflab) {
    gk_plot pl;
    gk_err err;
    double rx[2], ry[8][2];
    int k, s;
    gk_plot_init(&pl, title, xl, yl);
    for (k = 0; k < 4; ++k)
        if (y[k]) gk_plot_add(&pl, x, y[k], n, lab[k]);
    rx[0] = n ? x[0] : 0.0;
    rx[1] = n ? x[n - 1] : 1.0;
    for (k = 0; k < nref && k < 8; ++k) {
        ry[k][0] = ry[k][1] = ref[k];
        s = gk_plot_add(&pl, rx, ry[k], 2, reflab[k]);
        if (s >= 0) pl.s[s].dashed = 1;
    }
    if (gk_plot_svg(&pl, path, &err)) return fprintf(stderr, "%s: %s\n", prog, err.msg), 1;
    return 0;
}

#endif
