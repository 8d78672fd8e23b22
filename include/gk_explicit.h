/* gk_explicit.h - explicit macro solvers: central differences, adaptive
 * dynamic relaxation, the corotational update.            (grainkit v0.1)
 *
 * The macro side of an explicit two-scale model, on plain arrays: any
 * dimension, any element, any material. The caller computes the internal
 * force f_int(u) (e.g. gk_fem_elem_force over a mesh, stresses from RVEs)
 * and hands it in; this header moves the nodes. Depends on gk_base.h only.
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_EXPLICIT_IMPLEMENTATION) in one file.
 *
 * DOFS. n degrees of freedom, nodal masses m (lumped: gk_fem_lumped_mass
 * gives the HRZ lumping of Liu, Bosco & Suiker 2018 eq 24, one value per
 * node; repeat it per component), an optional flag per dof `fixed`: a fixed
 * dof's velocity is prescribed by the caller (0 for a support, the platen
 * speed for a moving one) and is never changed here; its displacement still
 * advances by dt v. Forces f = f_ext - f_int in N, masses in kg.
 *
 * CENTRAL DIFFERENCES (Liu, Bosco & Suiker 2018 eqs 20-23; Liu, Sun, Yuan &
 * Fish 2016 eq 51) with mass-proportional damping C = alpha M:
 *     v_{n+1/2} = [(2 - dt alpha) v_{n-1/2} + 2 dt M^-1 (f_ext - f_int(u_n))]
 *                 / (2 + dt alpha)                                    eq 22
 *     u_{n+1}   = u_n + dt v_{n+1/2}                                  eq 23
 *   gk_explicit_step        one step of eqs 22-23 on the free dofs
 *   gk_explicit_dt_critical (2 / omega)(sqrt(1 + xi^2) - xi): the stable step
 *                           of a damped oscillator (2016 eqs 63, 65; 2018
 *                           eq 27 without its factor gamma). Eq 22 treats the
 *                           damping with the average velocity, which makes
 *                           the scheme stable up to 2 / omega_max for any
 *                           alpha >= 0 (a z-transform of the mode equation);
 *                           the formula is the papers' conservative limit.
 *   gk_explicit_substeps    the fine/coarse step ratio of 2016 eq 66,
 *                           alpha = psi omega^f_max / omega^c_max
 *   gk_explicit_elem_omega  an upper bound on the highest frequency of an
 *                           element with stiffness K_e and lumped masses m_e:
 *                           omega^2 <= max_a sum_b |K_ab| / m_a (Gershgorin).
 *                           The largest over the elements bounds the whole
 *                           mesh (element eigenvalue theorem: the assembled
 *                           lambda_max of M^-1 K never exceeds the largest
 *                           element one). Mass scaling: scale m.
 *   gk_explicit_kinetic_energy   (1/2) v^T M v over the free dofs (eq 29)
 *
 * ADAPTIVE DYNAMIC RELAXATION (Liu, Bosco & Suiker 2018 eqs 20-29, Table 1).
 * For a load step the caller prescribes the boundary values, then iterates
 * j = 1, 2, ...: f_int(U^j) -> gk_dr_iterate, which
 *   1. estimates omega from the Rayleigh quotient (eq 26)
 *          omega^2 = (U - U0)^T (f_int - f0) / (U - U0)^T M (U - U0)
 *      over the free dofs, U0 = f0 = 0 as printed unless the caller gives a
 *      reference (gk_dr_reference: e.g. the initial state of a pre-stressed
 *      body, whose f_int(0) is not 0);
 *   2. alpha = 2 xi omega (eq 25), dt = gamma (2 / omega)(sqrt(xi^2 + 1) - xi)
 *      (eq 27; xi = 1, gamma = 0.5 by default: dt = 0.414 / omega);
 *   3. one step of eqs 22-23;
 *   4. E_kin = (1/2) v^T M v (eq 29), E_kin,max over the load step, and
 *      converged when E_kin <= tol E_kin,max (eq 28, tol 1e-3) - optionally
 *      also a force residual |f_ext - f_int|_inf <= force_tol x
 *      max(|f_ext|_inf, |f_int|_inf) (the energy ratio alone bounds the
 *      velocity, not the error: use it for tight solutions). And optionally
 *      converged on the force residual alone, |r|_inf <= force_stop x
 *      max(|f_ext|_inf, |f_int|_inf), whatever eq 28 says: for a step that
 *      starts near equilibrium (a predicted step), whose E_kin,max is
 *      itself of the size of the noise of the forces (an RVE's stress
 *      fluctuates), so that eq 28's ratio hovers above tol and never ends
 *      the step.
 * GUARDS the paper leaves out (flagged in gk_dr.guards of the iteration):
 *   GK_DR_OMEGA_UNDEFINED  (U - U0)^T M (U - U0) = 0 (at U = U0, e.g. the
 *                          first iteration from rest): eq 26 is 0/0; the
 *                          previous omega is kept, at the first iteration
 *                          omega_max (heavy damping, smallest step) or, with
 *                          no bound given, omega_start.
 *   GK_DR_OMEGA_IMAGINARY  (U - U0)^T (f_int - f0) < 0 (softening, a load
 *                          reversal): omega^2 < 0; handled as above.
 *   GK_DR_OMEGA_CAPPED     eq 26 above def.omega_cap (opt-in; e.g. omega_max):
 *                          with the total U of eq 26 as printed, a free dof
 *                          whose displacement passes through 0 while its
 *                          force does not (a pre-stressed body, lateral
 *                          expansion after compression) sends the quotient
 *                          to infinity, dt to 0 and alpha dt to a constant:
 *                          the velocities then decay geometrically, E_kin
 *                          falls below tol E_kin,max and the step "converges"
 *                          wherever it stands (tests/test_explicit.c). The
 *                          cap keeps omega no higher than the mesh can ring.
 *   GK_DR_DT_BOUNDED       the Rayleigh quotient of eq 26 estimates the
 *                          LOWEST active mode: eq 27 with it can exceed the
 *                          stability limit of the highest one. With
 *                          omega_max (gk_explicit_elem_omega) given, dt is
 *                          also at most eq 27 at omega_max with that mode's
 *                          own damping ratio alpha / (2 omega_max).
 *   A NaN force or a step that makes u non-finite -> GK_ERR_NAN /
 *   GK_ERR_DIVERGED, u and v unchanged.
 *   gk_dr_init / gk_dr_reference / gk_dr_begin / gk_dr_iterate   the stage API
 *   gk_dr_solve    the loop over a callback f_int(u) until converged or
 *                  max_iter (GK_ERR_NOCONVERGE naming the ratios)
 *
 * COROTATIONAL UPDATE (Liu, Sun, Yuan & Fish 2016 eqs 60-62). The paper's
 * Appendix B (the algorithm) is missing from the available text; what it
 * leaves open is fixed here as follows (Hughes & Winget 1980; ABAQUS/Explicit):
 *   - F_{n+1/2} = dx_{n+1/2}/dX = I + (H_n + H_{n+1}) / 2 (eq 61 exactly,
 *     since x_{n+1/2} = (x_n + x_{n+1}) / 2), H = du/dX on the reference mesh;
 *   - the strain increment is the symmetric gradient of du = u_{n+1} - u_n on
 *     the mid-step configuration, deps = sym(dF F_{n+1/2}^-1), dF = H_{n+1} -
 *     H_n. For a rigid rotation dF F^-1 is exactly skew (a Cayley transform),
 *     so a rigid motion of any size gives deps = 0;
 *   - R_{n+1/2} and R_{n+1} from the polar decompositions of F_{n+1/2} and
 *     F_{n+1} (gk_m3_polar); deps (or its nonlocal average) is rotated in
 *     with R_{n+1/2}^T deps R_{n+1/2} (eq 60); the micro model receives this
 *     symmetric increment only (no spin: the RVE never rotates), and returns
 *     sigma^R; sigma_{n+1} = R_{n+1} sigma^R R_{n+1}^T (eq 62);
 *   - f_int is then assembled with sigma_{n+1} on the current configuration
 *     x_{n+1} (updated Lagrangian).
 *   gk_corot_increment  H_n, H_{n+1} -> deps (spatial), R_{n+1/2}, R_{n+1}
 *   gk_corot_rotate_in  R^T a R   (eq 60)
 *   gk_corot_rotate_out R a R^T   (eq 62)
 *
 * Tensors 3x3 row-major (gk_base.h); 2D uses the upper-left block. Stress
 * tension-positive, SI units.
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_EXPLICIT_H
#define GK_EXPLICIT_H

#include "gk_base.h"

/* guards that acted in the last gk_dr_iterate */
#define GK_DR_OMEGA_UNDEFINED 1u
#define GK_DR_OMEGA_IMAGINARY 2u
#define GK_DR_DT_BOUNDED 4u
#define GK_DR_OMEGA_CAPPED 8u

typedef struct gk_dr_def {
    double xi;          /* damping ratio of eqs 25, 27; 0 -> 1                         */
    double gamma;       /* safety factor of eq 27; 0 -> 0.5                            */
    double tol;         /* eq 28: E_kin / E_kin,max; 0 -> 1e-3                         */
    double force_tol;   /* also |r|_inf <= force_tol max(|f_ext|, |f_int|); 0 -> off   */
    double force_stop;  /* or |r|_inf <= force_stop max(|f_ext|, |f_int|) alone; 0 -> off */
    double omega_max;   /* bound on the highest frequency [rad/s]; 0 -> no dt guard    */
    double omega_start; /* omega before eq 26 is defined, when omega_max = 0; 0 -> 1   */
    double omega_cap;   /* upper bound on eq 26's omega [rad/s]; 0 -> none             */
    long max_iter;      /* gk_dr_solve's cap per load step; 0 -> 1 000 000            */
} gk_dr_def;

typedef struct gk_dr {
    gk_dr_def def;
    int n;
    const double *mass;         /* n, caller's memory                                 */
    const unsigned char *fixed; /* n or NULL, caller's memory                         */
    const double *u0, *f0;      /* reference of eq 26 (NULL: 0), caller's memory      */
    double omega, alpha, dt;    /* of the last iteration                              */
    double ekin, ekin_max;      /* eq 29 after the last iteration; max of the step    */
    double resid;               /* relative force residual before the last iteration  */
    long iter, total;           /* iterations of this load step; since init           */
    unsigned guards;            /* GK_DR_* of the last iteration                      */
    int converged;
    gk_err err;
} gk_dr;

/* f_int(u) for gk_dr_solve: fill f_int (n) and return GK_OK or an error */
typedef gk_result (*gk_dr_force_fn)(void *user, const double *u, double *f_int);

#ifdef __cplusplus
extern "C" {
#endif

GKDEF gk_result gk_explicit_step(int n, const double *mass, const unsigned char *fixed, const double *force,
                                 double alpha, double dt, double *v, double *u, gk_err *err);
GKDEF double gk_explicit_dt_critical(double omega, double xi);
GKDEF double gk_explicit_substeps(double omega_coarse, double xi_coarse, double omega_fine, double xi_fine);
GKDEF double gk_explicit_elem_omega(int nd, const double *Ke, const double *me);
GKDEF double gk_explicit_kinetic_energy(int n, const double *mass, const unsigned char *fixed,
                                        const double *v);

GKDEF gk_result gk_dr_init(gk_dr *dr, const gk_dr_def *def, int n, const double *mass,
                           const unsigned char *fixed, gk_err *err);
GKDEF void gk_dr_reference(gk_dr *dr, const double *u0, const double *f0);
GKDEF void gk_dr_begin(gk_dr *dr);
GKDEF gk_result gk_dr_iterate(gk_dr *dr, const double *f_int, const double *f_ext, double *u, double *v);
GKDEF gk_result gk_dr_solve(gk_dr *dr, gk_dr_force_fn fint, void *user, const double *f_ext, double *u,
                            double *v, double *f_int_work);

GKDEF gk_result gk_corot_increment(int dim, const double Hn[9], const double Hn1[9], double deps[9],
                                   double R_half[9], double R_new[9], gk_err *err);

#ifdef __cplusplus
}
#endif

/* R^T a R (eq 60: spatial -> corotational) */
GK_INLINE void gk_corot_rotate_in(const double R[9], const double a[9], double out[9]) {
    double t[9], Rt[9];
    gk_m3_transpose(R, Rt);
    gk_m3_mul(Rt, a, t);
    gk_m3_mul(t, R, out);
}
/* R a R^T (eq 62: corotational -> spatial) */
GK_INLINE void gk_corot_rotate_out(const double R[9], const double a[9], double out[9]) {
    double t[9], Rt[9];
    gk_m3_transpose(R, Rt);
    gk_m3_mul(R, a, t);
    gk_m3_mul(t, Rt, out);
}

#endif /* GK_EXPLICIT_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_EXPLICIT_IMPLEMENTATION)) && !defined(GK_EXPLICIT_IMPL_ONCE)
#define GK_EXPLICIT_IMPL_ONCE

#include <string.h>

GKDEF gk_result gk_explicit_step(int n, const double *mass, const unsigned char *fixed, const double *force,
                                 double alpha, double dt, double *v, double *u, gk_err *err) {
    int i;
    double a, b;
    if (n < 0 || (n > 0 && (!mass || !force || !v || !u)))
        return gk_err_set(err, GK_ERR_ARG, "explicit step: %d dofs or a NULL array", n);
    if (!(dt > 0.0) || !isfinite(dt))
        return gk_err_set(err, GK_ERR_DT, "explicit step: dt %g must be > 0", dt);
    if (!(alpha >= 0.0) || !isfinite(alpha))
        return gk_err_set(err, GK_ERR_ARG, "explicit step: damping alpha %g must be >= 0", alpha);
    for (i = 0; i < n; ++i) { /* validate everything before touching u, v */
        if (fixed && fixed[i]) {
            if (!isfinite(v[i]))
                return gk_err_set(err, GK_ERR_NAN, "explicit step: prescribed velocity of dof %d is %g", i,
                                  v[i]);
            continue;
        }
        if (!(mass[i] > 0.0) || !isfinite(mass[i]))
            return gk_err_set(err, GK_ERR_MASS, "explicit step: mass of dof %d is %g", i, mass[i]);
        if (!isfinite(force[i]))
            return gk_err_set(err, GK_ERR_NAN, "explicit step: force on dof %d is %g", i, force[i]);
    }
    a = (2.0 - dt * alpha) / (2.0 + dt * alpha);
    b = 2.0 * dt / (2.0 + dt * alpha);
    for (i = 0; i < n; ++i) {
        if (!(fixed && fixed[i])) v[i] = a * v[i] + b * force[i] / mass[i];
        u[i] += dt * v[i];
    }
    return GK_OK;
}

GKDEF double gk_explicit_dt_critical(double omega, double xi) {
    if (!(omega > 0.0)) return HUGE_VAL;
    if (!(xi > 0.0)) xi = 0.0;
    return 2.0 / omega * (sqrt(1.0 + xi * xi) - xi);
}

GKDEF double gk_explicit_substeps(double omega_coarse, double xi_coarse, double omega_fine, double xi_fine) {
    double xc = xi_coarse > 0.0 ? xi_coarse : 0.0, xf = xi_fine > 0.0 ? xi_fine : 0.0;
    double psi = (sqrt(1.0 + xc * xc) - xc) / (sqrt(1.0 + xf * xf) - xf);
    if (!(omega_coarse > 0.0)) return HUGE_VAL;
    return psi * omega_fine / omega_coarse;
}

GKDEF double gk_explicit_elem_omega(int nd, const double *Ke, const double *me) {
    double lmax = 0.0;
    int a, b;
    for (a = 0; a < nd; ++a) {
        double s = 0.0;
        for (b = 0; b < nd; ++b) s += fabs(Ke[(size_t)a * nd + b]);
        if (!(me[a] > 0.0)) return HUGE_VAL;
        if (s / me[a] > lmax) lmax = s / me[a];
    }
    return sqrt(lmax);
}

GKDEF double gk_explicit_kinetic_energy(int n, const double *mass, const unsigned char *fixed,
                                        const double *v) {
    double e = 0.0;
    int i;
    for (i = 0; i < n; ++i)
        if (!(fixed && fixed[i])) e += mass[i] * v[i] * v[i];
    return 0.5 * e;
}

/* ------------------------------------------------------------ dynamic relaxation */
GKDEF gk_result gk_dr_init(gk_dr *dr, const gk_dr_def *def, int n, const double *mass,
                           const unsigned char *fixed, gk_err *err) {
    gk_dr z;
    int i;
    memset(&z, 0, sizeof z);
    if (def) z.def = *def;
    if (n < 1 || !mass) return gk_err_set(err, GK_ERR_ARG, "dynamic relaxation: %d dofs or no masses", n);
    if (z.def.xi == 0.0) z.def.xi = 1.0;
    if (z.def.gamma == 0.0) z.def.gamma = 0.5;
    if (z.def.tol == 0.0) z.def.tol = 1e-3;
    if (z.def.omega_start == 0.0) z.def.omega_start = 1.0;
    if (z.def.max_iter == 0) z.def.max_iter = 1000000;
    if (!(z.def.xi > 0.0) || !isfinite(z.def.xi))
        return gk_err_set(err, GK_ERR_ARG, "dynamic relaxation: xi %g must be > 0", z.def.xi);
    if (!(z.def.gamma > 0.0 && z.def.gamma <= 1.0))
        return gk_err_set(err, GK_ERR_ARG, "dynamic relaxation: gamma %g outside (0, 1]", z.def.gamma);
    if (!(z.def.tol > 0.0 && z.def.tol < 1.0))
        return gk_err_set(err, GK_ERR_ARG, "dynamic relaxation: tol %g outside (0, 1)", z.def.tol);
    if (!(z.def.force_tol >= 0.0) || !isfinite(z.def.force_tol))
        return gk_err_set(err, GK_ERR_ARG, "dynamic relaxation: force_tol %g must be >= 0", z.def.force_tol);
    if (!(z.def.force_stop >= 0.0) || !isfinite(z.def.force_stop))
        return gk_err_set(err, GK_ERR_ARG, "dynamic relaxation: force_stop %g must be >= 0",
                          z.def.force_stop);
    if (!(z.def.omega_max >= 0.0) || !isfinite(z.def.omega_max))
        return gk_err_set(err, GK_ERR_ARG, "dynamic relaxation: omega_max %g must be >= 0", z.def.omega_max);
    if (!(z.def.omega_cap >= 0.0) || !isfinite(z.def.omega_cap))
        return gk_err_set(err, GK_ERR_ARG, "dynamic relaxation: omega_cap %g must be >= 0", z.def.omega_cap);
    if (!(z.def.omega_start > 0.0) || !isfinite(z.def.omega_start))
        return gk_err_set(err, GK_ERR_ARG, "dynamic relaxation: omega_start %g must be > 0",
                          z.def.omega_start);
    if (z.def.max_iter < 1)
        return gk_err_set(err, GK_ERR_ARG, "dynamic relaxation: max_iter %ld < 1", z.def.max_iter);
    for (i = 0; i < n; ++i)
        if (!(fixed && fixed[i]) && (!(mass[i] > 0.0) || !isfinite(mass[i])))
            return gk_err_set(err, GK_ERR_MASS, "dynamic relaxation: mass of dof %d is %g", i, mass[i]);
    z.n = n;
    z.mass = mass;
    z.fixed = fixed;
    *dr = z;
    return GK_OK;
}

GKDEF void gk_dr_reference(gk_dr *dr, const double *u0, const double *f0) {
    dr->u0 = u0;
    dr->f0 = f0;
}

GKDEF void gk_dr_begin(gk_dr *dr) {
    dr->iter = 0;
    dr->ekin_max = 0.0;
    dr->converged = 0;
}

GKDEF gk_result gk_dr_iterate(gk_dr *dr, const double *f_int, const double *f_ext, double *u, double *v) {
    const double *m = dr->mass;
    const unsigned char *fx = dr->fixed;
    double num = 0.0, den = 0.0, rmax = 0.0, fmax = 0.0, omega, alpha, dt, ek, a, b;
    unsigned guards = 0;
    int i, n = dr->n;
    for (i = 0; i < n; ++i) {
        double fe = f_ext ? f_ext[i] : 0.0, fi = f_int[i];
        if (!isfinite(fi) || !isfinite(fe))
            return gk_err_set(&dr->err, GK_ERR_NAN,
                              "dynamic relaxation: force on dof %d is not finite (f_int %g, f_ext %g)", i, fi,
                              fe);
        if (fabs(fe) > fmax) fmax = fabs(fe);
        if (fabs(fi) > fmax) fmax = fabs(fi);
        if (fx && fx[i]) continue;
        {
            double du = u[i] - (dr->u0 ? dr->u0[i] : 0.0), df = fi - (dr->f0 ? dr->f0[i] : 0.0);
            num += du * df;
            den += m[i] * du * du;
            if (fabs(fe - fi) > rmax) rmax = fabs(fe - fi);
        }
    }
    /* eq 26 with its guards */
    if (!(den > 0.0)) {
        guards |= GK_DR_OMEGA_UNDEFINED;
    } else if (num < 0.0) {
        guards |= GK_DR_OMEGA_IMAGINARY;
    }
    if (guards || !(num > 0.0)) {
        if (!guards)
            guards |= GK_DR_OMEGA_UNDEFINED; /* num = 0: omega = 0 would stop the damping and blow dt up */
        omega =
            dr->omega > 0.0 ? dr->omega : (dr->def.omega_max > 0.0 ? dr->def.omega_max : dr->def.omega_start);
    } else {
        omega = sqrt(num / den);
        if (dr->def.omega_cap > 0.0 && omega > dr->def.omega_cap) {
            omega = dr->def.omega_cap;
            guards |= GK_DR_OMEGA_CAPPED;
        }
    }
    alpha = 2.0 * dr->def.xi * omega;                                /* eq 25 */
    dt = dr->def.gamma * gk_explicit_dt_critical(omega, dr->def.xi); /* eq 27 */
    if (dr->def.omega_max > 0.0) {
        double xim = alpha / (2.0 * dr->def.omega_max);
        double dtm = dr->def.gamma * gk_explicit_dt_critical(dr->def.omega_max, xim);
        if (dtm < dt) {
            dt = dtm;
            guards |= GK_DR_DT_BOUNDED;
        }
    }
    if (!(dt > 0.0) || !isfinite(dt) || !isfinite(alpha))
        return gk_err_set(&dr->err, GK_ERR_DIVERGED, "dynamic relaxation: step %g, damping %g from omega %g",
                          dt, alpha, omega);
    /* eqs 22-23, checked before anything is written */
    a = (2.0 - dt * alpha) / (2.0 + dt * alpha);
    b = 2.0 * dt / (2.0 + dt * alpha);
    ek = 0.0;
    for (i = 0; i < n; ++i) {
        double vi = v[i];
        if (!(fx && fx[i])) {
            vi = a * v[i] + b * ((f_ext ? f_ext[i] : 0.0) - f_int[i]) / m[i];
            ek += m[i] * vi * vi;
        }
        if (!isfinite(u[i] + dt * vi))
            return gk_err_set(&dr->err, GK_ERR_DIVERGED, "dynamic relaxation: dof %d would become %g", i,
                              u[i] + dt * vi);
    }
    for (i = 0; i < n; ++i) {
        if (!(fx && fx[i])) v[i] = a * v[i] + b * ((f_ext ? f_ext[i] : 0.0) - f_int[i]) / m[i];
        u[i] += dt * v[i];
    }
    ek *= 0.5;
    dr->omega = omega;
    dr->alpha = alpha;
    dr->dt = dt;
    dr->guards = guards;
    dr->ekin = ek;
    if (ek > dr->ekin_max) dr->ekin_max = ek;
    dr->resid = fmax > 0.0 ? rmax / fmax : 0.0;
    ++dr->iter;
    ++dr->total;
    /* eq 28 (not at the first iteration, where E_kin = E_kin,max by definition) */
    dr->converged = ((dr->ekin_max == 0.0 || (dr->iter > 1 && ek <= dr->def.tol * dr->ekin_max)) &&
                     (dr->def.force_tol == 0.0 || dr->resid <= dr->def.force_tol)) ||
                    (dr->def.force_stop > 0.0 && dr->resid <= dr->def.force_stop);
    return GK_OK;
}

GKDEF gk_result gk_dr_solve(gk_dr *dr, gk_dr_force_fn fint, void *user, const double *f_ext, double *u,
                            double *v, double *f_int_work) {
    gk_result r;
    gk_dr_begin(dr);
    while (dr->iter < dr->def.max_iter) {
        r = fint(user, u, f_int_work);
        if (r)
            return gk_err_set(&dr->err, r, "dynamic relaxation: the internal force failed at iteration %ld",
                              dr->iter);
        r = gk_dr_iterate(dr, f_int_work, f_ext, u, v);
        if (r) return r;
        if (dr->converged) return GK_OK;
    }
    return gk_err_set(
        &dr->err, GK_ERR_NOCONVERGE,
        "dynamic relaxation: not converged in %ld iterations (E_kin / E_kin,max %.3g, tol %.3g; force "
        "residual %.3g, tol %.3g, alone %.3g)",
        dr->iter, dr->ekin_max > 0 ? dr->ekin / dr->ekin_max : 0.0, dr->def.tol, dr->resid, dr->def.force_tol,
        dr->def.force_stop);
}

/* ------------------------------------------------------------ corotational */
GKDEF gk_result gk_corot_increment(int dim, const double Hn[9], const double Hn1[9], double deps[9],
                                   double R_half[9], double R_new[9], gk_err *err) {
    double Fh[9], Fh_inv[9], F1[9], dF[9], L[9], U[9], Rh[9], R1[9];
    int k;
    gk_result r;
    if (dim != 2 && dim != 3) return gk_err_set(err, GK_ERR_ARG, "corotational update: dimension %d", dim);
    if (!gk_m3_isfinite(Hn) || !gk_m3_isfinite(Hn1))
        return gk_err_set(err, GK_ERR_NAN, "corotational update: a displacement gradient is not finite");
    for (k = 0; k < 9; ++k) {
        Fh[k] = 0.5 * (Hn[k] + Hn1[k]);
        F1[k] = Hn1[k];
        dF[k] = Hn1[k] - Hn[k];
    }
    Fh[0] += 1.0, Fh[4] += 1.0, Fh[8] += 1.0;
    F1[0] += 1.0, F1[4] += 1.0, F1[8] += 1.0;
    if (dim == 2) { /* plane: the out-of-plane row and column are the identity */
        Fh[2] = Fh[5] = Fh[6] = Fh[7] = F1[2] = F1[5] = F1[6] = F1[7] = 0.0;
        Fh[8] = F1[8] = 1.0;
        dF[2] = dF[5] = dF[6] = dF[7] = dF[8] = 0.0;
    }
    if (!(gk_m3_det(Fh) > 0.0) || !(gk_m3_det(F1) > 0.0))
        return gk_err_set(err, GK_ERR_SINGULAR,
                          "corotational update: det F %g at mid-step, %g at the end (inverted)",
                          gk_m3_det(Fh), gk_m3_det(F1));
    gk_m3_inverse(Fh, Fh_inv);
    r = gk_m3_polar(Fh, dim, Rh, U);
    if (!r) r = gk_m3_polar(F1, dim, R1, U);
    if (r) return gk_err_set(err, r, "corotational update: polar decomposition failed");
    gk_m3_mul(dF, Fh_inv, L); /* d(du)/dx_{n+1/2} */
    gk_m3_sym(L, deps);
    gk_m3_copy(Rh, R_half);
    gk_m3_copy(R1, R_new);
    return GK_OK;
}

#endif /* GK_EXPLICIT implementation */
