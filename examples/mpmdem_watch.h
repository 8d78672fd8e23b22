/* mpmdem_watch.h - watched material points of the MPMxDEM drivers (examples, not library): the
 * paper's points A, B, C of the biaxial test and D, E, F of the pipe are the material points nearest
 * to chosen positions, followed through the run. */
#ifndef MPMDEM_WATCH_H
#define MPMDEM_WATCH_H

#include "mpmdem.h"

/* the material point nearest to (x, y) (the first of equals): a watched point of a driver */
static int mpd_nearest(const gk_mpm_points *pts, double x, double y) {
    double best = HUGE_VAL;
    int i, k = 0;
    for (i = 0; i < pts->n; ++i) {
        double dx = pts->x[0][i] - x, dy = pts->x[1][i] - y, d2 = dx * dx + dy * dy;
        if (d2 < best) best = d2, k = i;
    }
    return k;
}

/* a watched point's state from what mpd_fields wrote into fld: its position (x, y), then the fields
 * f[0..nf-1], p and q in kPa, no negative zero */
static void mpd_point_state(const gk_mpm_points *pts, const double *fld, int i, const int *f, int nf,
                            double *out) {
    int j;
    out[0] = pts->x[0][i], out[1] = pts->x[1][i];
    for (j = 0; j < nf; ++j) {
        double v = fld[(size_t)f[j] * pts->n + i] + 0.0;
        out[2 + j] = f[j] == MPD_P || f[j] == MPD_Q ? v / 1e3 : v;
    }
}

/* the watched points' indices as a checkpoint holds them (a driver's mpd_load check): each a point of
 * the run; 0, or 1 with the point named in why */
static int mpd_watch_check(const int *pt, const char *const *name, int npt, int n, char *why, size_t nwhy) {
    int k;
    for (k = 0; k < npt; ++k)
        if (pt[k] < 0 || pt[k] >= n) return snprintf(why, nwhy, "point %s out of range", name[k]), 1;
    return 0;
}

/* the CSV header cells of the watched points: ",NAME_QUANTITY" for each point and quantity */
static void mpd_watch_csv_head(FILE *fp, const char *const *name, int npt, const char *const *q, int nq) {
    int i, j;
    for (i = 0; i < npt; ++i)
        for (j = 0; j < nq; ++j) fprintf(fp, ",%s_%s", name[i], q[j]);
}

/* the CSV cells of npt watched points' states, nq values each (v: npt x nq) */
static void mpd_watch_csv_row(FILE *fp, const double *v, int npt, int nq) {
    int k;
    for (k = 0; k < npt * nq; ++k) fprintf(fp, ",%.6g", v[k]);
}

#endif /* MPMDEM_WATCH_H */
