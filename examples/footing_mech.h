/* footing_mech.h - the failure mechanism under a strip footing, read from
 * the material points (examples, not library; used by mpmdem_footing.c,
 * tested by tests/test_mpmdem_footing.c). Plain arrays in, numbers out.
 *
 * Half model: the symmetry plane is x = 0, the footing covers 0 <= x <= b
 * with its base at y = yb; the points lie on a grid of spacing h (one point
 * per cell or more).
 *
 *   fm_wedge_angle   the angle of the wedge under the footing (Liang & Zhao
 *                    2019 Fig 14A: 54.8 deg; Prandtl's pi/4 + phi/2 for a
 *                    smooth base): in every column of cells wholly under
 *                    the footing (0 <= x < b), the depth z below the base
 *                    of the largest deviatoric strain eps_q (the slip line
 *                    bounding the wedge; refined by a parabola through the
 *                    point and its neighbours above and below), then the
 *                    line z = (b - x) tan(alpha) through the footing's
 *                    corner (b, yb) fitted by least squares to those
 *                    depths: alpha in degrees, NAN if no column has a
 *                    point below the base.
 *   fm_heave         the heave of the ground beside the footing (Liang &
 *                    Zhao: "as wide as around 2.5 times the footing
 *                    width"): of the surface points (given by the caller)
 *                    beyond the footing edge, the largest upward
 *                    displacement, and the outermost x (from the axis) at
 *                    which the uplift still reaches 10 % of it (linear
 *                    interpolation between neighbouring surface points);
 *                    NAN if no surface point rises.
 *   fm_prandtl_wedge, fm_prandtl_reach   Prandtl's mechanism (smooth base)
 *                    of a footing of half-width b at friction angle phi:
 *                    the wedge angle pi/4 + phi/2 and the x (from the
 *                    axis) where the passive zone meets the ground,
 *                    b + 2 r1 cos(pi/4 - phi/2), r1 = r0 exp(pi/2 tan phi)
 *                    (eq 44 at psi = pi/2), r0 = b / cos(pi/4 + phi/2).
 */
#ifndef FOOTING_MECH_H
#define FOOTING_MECH_H

#include <math.h>
#include <stdlib.h>

#define FM_PI 3.14159265358979323846

static double fm_prandtl_wedge(double phi_deg) { return 45.0 + 0.5 * phi_deg; }

static double fm_prandtl_reach(double b, double phi_deg) {
    double p = phi_deg * FM_PI / 180.0, a = FM_PI / 4 + p / 2, r0 = b / cos(a);
    double r1 = r0 * exp(0.5 * FM_PI * tan(p));
    return b + 2.0 * r1 * cos(FM_PI / 4 - p / 2);
}

/* x, y: current positions of n points; eq: their eps_q; h: column width (the cell size);
 * b, yb: the footing's half-width and base level; *ncol: the columns used. Degrees or NAN. */
static double fm_wedge_angle(const double *x, const double *y, const double *eq, int n, double h, double b,
                             double yb, int *ncol) {
    int ncols = (int)floor(b / h + 1e-9), c, p, used = 0;
    double sxz = 0.0, sxx = 0.0;
    if (ncol) *ncol = 0;
    for (c = 0; c < ncols; ++c) {
        double lo = c * h, hi = (c + 1) * h, best = -HUGE_VAL, yb_ = 0, xbest = 0, up = NAN, dn = NAN;
        double yup = HUGE_VAL, ydn = -HUGE_VAL, z, d;
        int ib = -1;
        for (p = 0; p < n; ++p)
            if (x[p] >= lo && x[p] < hi && y[p] < yb && eq[p] > best) best = eq[p], ib = p;
        if (ib < 0) continue;
        yb_ = y[ib], xbest = x[ib];
        /* the neighbours in the column: the nearest point above and below */
        for (p = 0; p < n; ++p) {
            if (p == ib || !(x[p] >= lo && x[p] < hi) || y[p] >= yb) continue;
            if (y[p] > yb_ && y[p] < yup) yup = y[p], up = eq[p];
            if (y[p] < yb_ && y[p] > ydn) ydn = y[p], dn = eq[p];
        }
        z = yb - yb_;
        if (isfinite(up) && isfinite(dn)) { /* vertex of the parabola through the three */
            double d1 = yup - yb_, d2 = yb_ - ydn, s1 = (up - best) / d1, s2 = (best - dn) / d2;
            double curv = (s1 - s2) / (0.5 * (d1 + d2)); /* second derivative, <= 0 at a maximum */
            if (curv < 0) {
                d = -(0.5 * (s1 + s2)) / curv; /* offset up from y[ib] of the vertex */
                if (d > 0.5 * d1) d = 0.5 * d1;
                if (d < -0.5 * d2) d = -0.5 * d2;
                z -= d;
            }
        }
        sxz += z * (b - xbest), sxx += (b - xbest) * (b - xbest), ++used;
    }
    if (ncol) *ncol = used;
    if (!used || !(sxx > 0)) return NAN;
    return atan(sxz / sxx) * 180.0 / FM_PI;
}

/* xs, uy: x (current) and upward displacement of the ns surface points, in any order; b: the footing's
 * half-width. *umax: the largest uplift beyond x = b (NAN if none rises); returns the outermost x where
 * the uplift is 10 % of it, NAN if none. */
static double fm_heave(const double *xs, const double *uy, int ns, double b, double *umax) {
    double um = 0.0, xo = NAN, th;
    int k, j, found = 0;
    *umax = NAN;
    for (k = 0; k < ns; ++k)
        if (xs[k] > b && uy[k] > um) um = uy[k], found = 1;
    if (!found) return NAN;
    *umax = um, th = 0.1 * um;
    for (k = 0; k < ns; ++k) {
        double xr = HUGE_VAL, ur = 0.0;
        if (!(xs[k] > b && uy[k] >= th)) continue;
        for (j = 0; j < ns; ++j) /* the next surface point outwards */
            if (xs[j] > xs[k] && xs[j] < xr) xr = xs[j], ur = uy[j];
        if (xr == HUGE_VAL || ur >= th) {
            if (!(xs[k] <= xo)) xo = xs[k]; /* the last point still above: at least here */
            continue;
        }
        {
            double xc = xs[k] + (xr - xs[k]) * (uy[k] - th) / (uy[k] - ur);
            if (!(xc <= xo)) xo = xc;
        }
    }
    return xo;
}

#endif /* FOOTING_MECH_H */
