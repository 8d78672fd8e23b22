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

#endif /* MPMDEM_WATCH_H */
