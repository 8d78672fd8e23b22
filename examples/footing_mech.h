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
 *   fm_spiral        the log-spiral zone (Liang & Zhao eq 44, r = r0
 *                    exp(psi tan phi), "agrees perfectly" at phi = 28.1
 *                    deg): the pole is the footing's corner (b, yb), as in
 *                    Prandtl's mechanism; psi is the angle from the wedge
 *                    side (the ray from the pole down to the axis at the
 *                    wedge angle alpha given by the caller) towards the
 *                    passive zone's boundary (the ray 45 - phi/2 below the
 *                    horizontal, outwards): the fan is 135 + phi/2 - alpha
 *                    deg (90 at Prandtl's alpha). The CHOICES: (1) rays every
 *                    FM_SP_DPSI deg, leaving out FM_SP_MARGIN deg at each
 *                    end of the fan (there the ray runs along the wedge's
 *                    or the passive zone's own slip line, whose strain is
 *                    high all along it); (2) eps_q along a ray is the
 *                    Gaussian-weighted mean of the points' (sigma = half
 *                    the points' spacing s, cut off at 2 s; the points
 *                    mirrored in the symmetry plane x = 0 count too),
 *                    sampled every s/8 from r = b outwards (the fan's
 *                    shear concentrates at the pole, ~1/r, and Prandtl's
 *                    spiral starts at r0 = b / cos(alpha) > b) until the
 *                    weights fall below FM_SP_WMIN (out of the soil); (3)
 *                    the ridge on a ray is its largest local maximum that
 *                    stands FM_SP_DROP (10 %) above the lowest value on
 *                    either side of it along the ray (a shoulder or the
 *                    pole's decay is no ridge), its radius refined by the
 *                    parabola through the three samples; (4) a ridge on
 *                    at least half of the rays searched (and on at least
 *                    FM_SP_MINRAYS), spanning at least half of the
 *                    searched fan, else NOT FOUND (found = 0, every number
 *                    NAN: a bump on a few rays is no spiral); (5) the fit is least squares of
 *                    ln r = ln r0 + psi tan(phi_fit) (psi in radians):
 *                    phi_fit, r0 (on the wedge side, psi = 0); the misfit
 *                    against eq 44 at the caller's phi is the RMS of r -
 *                    r0' exp(psi tan phi) over the ridge points, r0' fitted
 *                    (least squares in ln r) with that slope: the shape,
 *                    not where the spiral starts. nrays counts the
 *                    rays with a ridge whether found or not.
 *   fm_spiral_nsearch  the number of rays fm_spiral searches (36 over
 *                    Prandtl's 90 deg fan).
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

#define FM_SP_DPSI 2.0    /* deg between rays */
#define FM_SP_MARGIN 10.0 /* deg left out at each end of the fan */
#define FM_SP_WMIN 0.5    /* kernel weight sum (points of spacing s) below which a ray has left the soil */
#define FM_SP_DROP 0.1    /* a ridge stands 10 % above the lowest value on either side along its ray */
#define FM_SP_MINRAYS 5   /* rays with a ridge needed for a fit */
#define FM_SP_MAXRAY 91   /* 180 deg / FM_SP_DPSI + 1 */

typedef struct fm_spiral_fit {
    int found, nrays;       /* nrays: rays with a ridge (their psi and r below) */
    double phi, r0, rms;    /* phi_fit [deg], r0 [m] at psi = 0, RMS misfit to eq 44 [m]; NAN if not found */
    double r0_44;           /* the r0' of that misfit (eq 44 at the caller's phi fitted to the ridge) */
    double alpha, th0, fan; /* the wedge angle used, the wedge side's direction (deg ccw from +x), the fan */
    double psi[FM_SP_MAXRAY]; /* [rad] from the wedge side */
    double r[FM_SP_MAXRAY];   /* the ridge's distance from the pole [m] */
} fm_spiral_fit;

/* the Gaussian-weighted eps_q at distance t along the ray (ux, uy) from the pole, over the m candidate
 * points (ct: their distance along the ray, cd2: squared distance from it, cv: eps_q); *w: weight sum */
static double fm_ray_value(const double *ct, const double *cd2, const double *cv, int m, double t, double s,
                           double *w) {
    double sw = 0.0, swv = 0.0, is2 = 1.0 / (2.0 * 0.25 * s * s), cut2 = 4.0 * s * s;
    int k;
    for (k = 0; k < m; ++k) {
        double dt = ct[k] - t, d2 = dt * dt + cd2[k], wk;
        if (d2 >= cut2) continue;
        wk = exp(-d2 * is2);
        sw += wk, swv += wk * cv[k];
    }
    *w = sw;
    return sw > 0 ? swv / sw : 0.0;
}

/* the fan fm_spiral searches [deg]: from the wedge side (alpha_deg) to the passive zone's boundary 45 -
 * phi_deg/2 below the horizontal */
static double fm_spiral_fan(double alpha_deg, double phi_deg) { return 135.0 + 0.5 * phi_deg - alpha_deg; }

/* the number of rays fm_spiral searches for a wedge angle alpha_deg and a friction angle phi_deg (0: the fan
 * is too narrow or an angle is not finite); a spiral is found only with a ridge on half of them */
static int fm_spiral_nsearch(double alpha_deg, double phi_deg) {
    double hi = fm_spiral_fan(alpha_deg, phi_deg) - FM_SP_MARGIN, lo = FM_SP_MARGIN;
    int nray;
    if (!(isfinite(alpha_deg) && isfinite(phi_deg) && hi >= lo)) return 0;
    nray = (int)floor((hi - lo) / FM_SP_DPSI + 1e-9) + 1;
    return nray > FM_SP_MAXRAY ? FM_SP_MAXRAY : nray;
}

/* x, y, eq: the n points (current positions, eps_q); s: their spacing; (b, yb): the pole (the footing's
 * corner); alpha_deg: the wedge angle (the fan's first side); phi_deg: the friction angle (the fan's last
 * side, and eq 44's). Fills *F; returns F->found (1) or 0 (not found: no ridge, or out of memory). */
static int fm_spiral(const double *x, const double *y, const double *eq, int n, double s, double b, double yb,
                     double alpha_deg, double phi_deg, fm_spiral_fit *F) {
    double *ct, *cd2, *cv, *v, rmax = 0.0, lo, hi, sx = 0, sy = 0, sxx = 0, sxy = 0, tp, c44 = 0, e2 = 0;
    double d2r = FM_PI / 180.0, psi_min = HUGE_VAL, psi_max = -HUGE_VAL;
    int p, k, j, nray, nsmax, nr = 0;
    F->found = 0, F->nrays = 0, F->phi = F->r0 = F->rms = F->r0_44 = NAN;
    F->alpha = alpha_deg, F->th0 = 180.0 + alpha_deg, F->fan = fm_spiral_fan(alpha_deg, phi_deg);
    if (!(n > 0 && s > 0 && b > 0 && isfinite(alpha_deg) && isfinite(phi_deg))) return 0;
    lo = FM_SP_MARGIN, hi = F->fan - FM_SP_MARGIN;
    if ((nray = fm_spiral_nsearch(alpha_deg, phi_deg)) == 0) return 0;
    for (p = 0; p < n; ++p) { /* the farthest point (or its mirror image) from the pole */
        double dx = fabs(x[p]) + b, dy = y[p] - yb, d = sqrt(dx * dx + dy * dy);
        if (d > rmax) rmax = d;
    }
    nsmax = (int)ceil((rmax + 2 * s - b) / (s / 8.0)) + 2;
    if (nsmax < 3) return 0;
    ct = (double *)malloc((3 * 2 * (size_t)n + (size_t)nsmax) * sizeof *ct);
    if (!ct) return 0;
    cd2 = ct + 2 * (size_t)n, cv = cd2 + 2 * (size_t)n, v = cv + 2 * (size_t)n;
    for (k = 0; k < nray; ++k) {
        double psi = lo + k * FM_SP_DPSI, th = (F->th0 + psi) * d2r, ux = cos(th), uy = sin(th), t, w;
        int m = 0, ns = 0, best = -1;
        for (p = 0; p < 2 * n; ++p) { /* the candidates: within 2 s of the ray beyond r = b - 2 s */
            double px = p < n ? x[p] : -x[p - n], dx = px - b, dy = y[p % n] - yb;
            double along = dx * ux + dy * uy, across = -dx * uy + dy * ux;
            if (fabs(across) >= 2 * s || along < b - 2 * s) continue;
            ct[m] = along, cd2[m] = across * across, cv[m] = eq[p % n], ++m;
        }
        for (t = b; ns < nsmax; t += s / 8.0) { /* sample until the ray leaves the soil */
            double val = fm_ray_value(ct, cd2, cv, m, t, s, &w);
            if (w < FM_SP_WMIN) break;
            v[ns++] = val;
        }
        for (j = 1; j < ns - 1; ++j) { /* the largest local maximum standing out on both sides */
            double mn_in = v[j], mn_out = v[j];
            int i;
            if (!(v[j] > v[j - 1] && v[j] >= v[j + 1] && v[j] > 0)) continue;
            for (i = 0; i < j; ++i) mn_in = fmin(mn_in, v[i]);
            for (i = j + 1; i < ns; ++i) mn_out = fmin(mn_out, v[i]);
            if (mn_in > (1.0 - FM_SP_DROP) * v[j] || mn_out > (1.0 - FM_SP_DROP) * v[j]) continue;
            if (best < 0 || v[j] > v[best]) best = j;
        }
        if (best < 0) continue;
        {
            double c = v[best - 1] - 2.0 * v[best] + v[best + 1], off = 0.0, r;
            if (c < 0) off = 0.5 * (v[best - 1] - v[best + 1]) / c; /* in samples, within +-1/2 */
            r = b + (best + off) * (s / 8.0);
            F->psi[nr] = psi * d2r, F->r[nr] = r, ++nr;
            if (psi < psi_min) psi_min = psi;
            if (psi > psi_max) psi_max = psi;
        }
    }
    free(ct);
    F->nrays = nr;
    if (nr < FM_SP_MINRAYS || 2 * nr < nray || psi_max - psi_min < 0.5 * (hi - lo)) return 0;
    for (k = 0; k < nr; ++k) {
        double ly = log(F->r[k]);
        sx += F->psi[k], sy += ly, sxx += F->psi[k] * F->psi[k], sxy += F->psi[k] * ly;
    }
    {
        double den = nr * sxx - sx * sx, slope, icpt;
        if (!(den > 0)) return 0;
        slope = (nr * sxy - sx * sy) / den, icpt = (sy - slope * sx) / nr;
        F->phi = atan(slope) / d2r, F->r0 = exp(icpt);
    }
    tp = tan(phi_deg * d2r);
    for (k = 0; k < nr; ++k) c44 += log(F->r[k]) - F->psi[k] * tp;
    c44 /= nr, F->r0_44 = exp(c44);
    for (k = 0; k < nr; ++k) {
        double d = F->r[k] - F->r0_44 * exp(F->psi[k] * tp);
        e2 += d * d;
    }
    F->rms = sqrt(e2 / nr);
    F->found = 1;
    return 1;
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
