/* gk_contact.h - contact laws and their history for grainkit.    (grainkit v0.1)
 *
 * Pointwise laws for one contact between spheres (3D) or disks (2D). The
 * scalar functions are the REFERENCE; each has its wide twin next to it
 * (suffix _w, GK_VR_W contacts at a time on the SIMD type of gk_base.h),
 * which performs the same operations in the same order and is tested bit for
 * bit against it (tests/test_contact.c). gk_dem.h gathers, calls the twins
 * and scatters; it holds no contact law of its own.
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_CONTACT_IMPLEMENTATION) in one file.
 *
 * GEOMETRY AND SIGNS
 *   Contact (i, j): branch vector d = x_j - x_i (nearest image), n = d/|d|,
 *   overlap delta = r_i + r_j - |d| (> 0 in contact). The force F returned is
 *   the force ON j FROM i; i receives -F. A repulsive normal force has
 *   F.n > 0. Lever arms l_i = r_i - delta/2, l_j = r_j - delta/2 (contact
 *   point at the middle of the overlap, as YADE's ScGeom): with them a rigid
 *   rotation of the pair produces no sliding at all.
 *   Relative velocity of the contact point (j with respect to i):
 *       v_c = v_rel - (l_i w_i + l_j w_j) x n,
 *   where v_rel = v_j - v_i is the relative centre velocity INCLUDING the
 *   affine (cell) part, and w are total angular velocities.
 *   Torques: t_i = -l_i n x F_t, t_j = -l_j n x F_t (+/- rolling moment).
 *   2D: vectors in the xy plane, angular velocities and torques are scalars
 *   about z, the tangent is t = (-n_y, n_x) and the tangential history is the
 *   scalar F_t along t (it turns with n exactly).
 *
 * LAWS (choose with gk_material.law; each is one line of GK_LAW_TABLE and
 * one block of gk_law_<name>_* functions, see LAWS below)
 *   GK_LAW_LINEAR  Guo & Zhao 2014 eqs 14-17: k_n = E r* (or a constant k_n),
 *                  r* = 2 r_i r_j / (r_i + r_j); k_t = kt_ratio k_n;
 *                  F_n = k_n delta; F_t incremental: F_t <- F_t - k_t v_t dt,
 *                  Coulomb cap |F_t| <= mu F_n (Cundall-Strack, as YADE's
 *                  Law2_ScGeom_FrictPhys_CundallStrack).
 *   GK_LAW_HERTZ   Liu et al. 2016 eqs 53-55 (incremental Hertz-Mindlin), with
 *                  G = E / (2 (1 + nu)), R_e = r*:
 *                  k_n = G/(1-nu) sqrt(2 R_e delta)  = dF_n/d delta,
 *                  F_n = (2/3) k_n delta            (exact Hertz force),
 *                  k_t = 2G/(2-nu) sqrt(2 R_e delta) (Mindlin, no-slip),
 *                  F_t incremental with the current k_t; same Coulomb cap.
 *                  (Guo & Zhao 2014 sec 2.2 gives the same k_n, k_t.)
 *   Rolling        Liang & Zhao 2019 eqs 24-25, 28: moment on j
 *                  M_r <- M_r - k_r w_roll dt, k_r = beta k_t r_i r_j,
 *                  |M_r| <= eta min(r_i, r_j) F_n; w_roll = w_j - w_i
 *                  (its part normal to n in 3D). Spring-slider, history kept.
 *   Viscous        F_n -= g_n v_n, F_t -= g_t v_t with
 *                  g = 2 zeta sqrt(m* k), m* = m_i m_j / (m_i + m_j):
 *                  zeta is the fraction of critical damping of the pair
 *                  (zeta_n = -ln e / sqrt(pi^2 + ln^2 e) for restitution e,
 *                  gk_restitution_to_zeta). The total normal force is not
 *                  clipped at zero (as LAMMPS gran/hooke): the linear
 *                  dashpot then has the analytic restitution. The Coulomb
 *                  cap uses max(F_n, 0) and caps spring + dashpot, keeping
 *                  the spring so that their sum sits on the cap.
 *   Cohesion       Chen et al. 2021 (Jiang et al.): a bond forms when a contact starts
 *                  (delta > 0 after being apart); while bonded the normal
 *                  spring also pulls, down to F_n = -coh_n, and the cap is
 *                  mu max(F_n, 0) + coh_t. The bond breaks when the tension
 *                  or the shear exceeds its limit; a broken contact is purely
 *                  frictional until the particles separate. Linear law only.
 *
 * HISTORY IN 3D. Each step the stored F_t (and M_r) is first twisted about n
 * by dt (w_i + w_j)/2 . n (YADE's twist), then projected onto the plane
 * normal to the current n and rescaled to its former magnitude (LAMMPS),
 * then incremented. History survives neighbour-list rebuilds (gk_dem.h
 * merges it by pair) and is zeroed when the pair separates.
 *
 * PAY FOR WHAT YOU USE. gk_dem.h derives physics flags from the material
 * (GK_PHYS_TANGENT if mu > 0 or coh_t > 0, ROLLING if beta, eta > 0, VISCOUS
 * if zeta > 0, COHESION if coh_n or coh_t > 0) and instantiates the law with
 * those flags as compile-time constants: a switched-off term costs nothing.
 *
 * UNITS: SI. E, G [Pa]; k [N/m]; k_r [N m/rad]; coh [N]; zeta dimensionless.
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_CONTACT_H
#define GK_CONTACT_H

#include "gk_base.h"

/* THE LAW TABLE: one line per contact law, X(enum, name). Everything
 * law-specific in the DEM is the law's block further down (LAWS): the check
 * of its material, its constants, the stiffness (scalar reference and wide
 * twin) and the stiffness bound of the critical time step. The enum, the
 * dispatchers, gk_material_check, gk_law_consts_make and the kernel
 * instantiation in gk_dem.h are all generated from this table, so a new law
 * is one line here, one block, and its test. */
#define GK_LAW_TABLE(X)                \
    X(GK_LAW_LINEAR, linear) /* = 0 */ \
    X(GK_LAW_HERTZ, hertz)   /* = 1 */

typedef enum gk_law {
#define GK__LAW_ENUM(E, name) E,
    GK_LAW_TABLE(GK__LAW_ENUM)
#undef GK__LAW_ENUM
        GK_LAW_COUNT
} gk_law;

/* physics flags (compile-time constants inside the kernels) */
#define GK_PHYS_TANGENT 1u  /* tangential spring + Coulomb (friction or shear cohesion) */
#define GK_PHYS_ROTATION 2u /* particles rotate (torques integrated)                    */
#define GK_PHYS_ROLLING 4u  /* rolling resistance (needs ROTATION)                      */
#define GK_PHYS_VISCOUS 8u  /* normal/tangential dashpots                               */
#define GK_PHYS_COHESION 16u

/* contact state bits (one byte per pair) */
#define GK_CS_CONTACT 1u /* touching (or bonded) at the last evaluation */
#define GK_CS_SLIDING 2u /* tangential force on the Coulomb cap         */
#define GK_CS_BONDED 4u  /* cohesive bond intact                         */
#define GK_CS_BROKEN 8u  /* bond broken; no new bond until separation    */

#define GK_MATERIAL_COOKIE 0x6b4d4154 /* set by gk_material_default() */

typedef struct gk_material {
    int cookie; /* set by gk_material_default(); catches uninitialised structs */
    gk_law law;
    double young;     /* E [Pa]: linear k_n = E r*; Hertz G = E / (2 (1 + poisson))  */
    double kn;        /* > 0: linear law with this constant k_n [N/m] instead of E r* */
    double kt_ratio;  /* linear: k_t = kt_ratio k_n (Guo & Zhao 2014 nu_c = 0.8)            */
    double poisson;   /* Hertz-Mindlin Poisson ratio nu                               */
    double friction;  /* Coulomb coefficient mu = tan(phi) (0: frictionless)          */
    double roll_beta; /* rolling stiffness factor beta: k_r = beta k_t r_i r_j        */
    double roll_eta;  /* rolling cap factor eta: |M_r| <= eta min(r_i, r_j) F_n       */
    double zeta_n;    /* normal viscous damping, fraction of critical                 */
    double zeta_t;    /* tangential viscous damping, fraction of critical             */
    double coh_n;     /* cohesion: largest tensile normal force of a bond [N]         */
    double coh_t;     /* cohesion: shear strength added to the Coulomb cap [N]        */
    double density;   /* particle density [kg/m^3]                                    */
} gk_material;

/* Contact constants in the working precision, derived once from a material
 * (gk_law_consts_make): each law's own (set by its block) and the shared ones. */
typedef struct gk_law_consts {
    gk_real young, kn_const, kt_ratio; /* GK_LAW_LINEAR                          */
    gk_real hn, ht;                    /* GK_LAW_HERTZ: G/(1-nu), 2G/(2-nu)      */
    gk_real mu, beta, eta;
    gk_real zn2, zt2; /* 2 zeta_n, 2 zeta_t */
    gk_real cn, ct;
} gk_law_consts;

/* Result of one contact evaluation. */
typedef struct gk_contact_out {
    gk_real f[3];  /* force on j from i (2D: f[2] = 0)                     */
    gk_real ti[3]; /* torque on i (2D: ti[2] only)                         */
    gk_real tj[3]; /* torque on j                                          */
    gk_real fn;    /* normal force magnitude (signed: < 0 in bond tension) */
    gk_real delta; /* overlap                                              */
} gk_contact_out;

/* The same for GK_VR_W contacts (the wide twins gk_contact_2d_w, _3d_w). */
typedef struct gk_contact_out_w {
    gk_vr f[3], ti[3], tj[3];
} gk_contact_out_w;

#ifdef __cplusplus
extern "C" {
#endif

/* Guo & Zhao 2014 material (YADE FEMxDEM prepareRVE.py): linear, E = 6e8 Pa,
 * kt/kn = 0.8, mu = tan(0.5 rad), density 2650, no rolling/viscous/cohesion */
GKDEF gk_material gk_material_default(void);
GKDEF gk_result gk_material_check(const gk_material *m, gk_err *err);
/* physics flags a material needs (without ROTATION, which is a scene choice) */
GKDEF unsigned gk_material_flags(const gk_material *m);
GKDEF void gk_law_consts_make(const gk_material *m, gk_law_consts *k);
/* zeta for a coefficient of restitution e of the linear spring-dashpot */
GKDEF double gk_restitution_to_zeta(double e);

#ifdef __cplusplus
}
#endif

/* ================================================================ LAWS
 * One block per line of GK_LAW_TABLE, all functions named gk_law_<name>_*:
 *   _check(m, err)        the law's own material checks (gk_material_check)
 *   _consts(m, K)         its fields of gk_law_consts (gk_law_consts_make)
 *   _stiffness(K, ri, rj, delta, kn, fn, kt)    k_n, F_n and k_t at overlap
 *                         delta > 0: the scalar reference
 *   _stiffness_w(...)     its wide twin, GK_VR_W contacts, bit-identical lanes
 *   _kn_max(m, rmax, dmax) the largest k_n of two particles of radius <= rmax
 *                         at overlap <= dmax (critical time step, Guo & Zhao 2014 eq 19)
 *   _stiffens()           1 if k_n grows with the overlap: the RVE re-checks
 *                         its time step at every list rebuild
 * `law` and `flags` are compile-time constants in the kernels, so a switch on
 * the law costs nothing. */

/* ---- GK_LAW_LINEAR: Guo & Zhao 2014 eqs 14-17, k_n = E r* (or a constant), k_t = kt_ratio k_n */
GK_INLINE gk_result gk_law_linear_check(const gk_material *m, gk_err *err) {
    if (!(m->kn > 0.0) && !(m->young > 0.0))
        return gk_err_set(err, GK_ERR_ARG, "linear law needs young > 0 or kn > 0 (young %g, kn %g)", m->young,
                          m->kn);
    return GK_OK;
}
GK_INLINE void gk_law_linear_consts(const gk_material *m, gk_law_consts *k) {
    k->young = (gk_real)m->young;
    k->kn_const = (gk_real)m->kn;
    k->kt_ratio = (gk_real)m->kt_ratio;
}
GK_FORCE_INLINE void gk_law_linear_stiffness(const gk_law_consts *K, gk_real ri, gk_real rj, gk_real delta,
                                             gk_real *kn, gk_real *fn, gk_real *kt) {
    gk_real rr = ri * rj, rs = (rr + rr) / (ri + rj); /* r* = 2 ri rj / (ri + rj) */
    gk_real k = K->kn_const > 0 ? K->kn_const : K->young * rs;
    *kn = k;
    *fn = k * delta;
    *kt = K->kt_ratio * k;
}
GK_FORCE_INLINE void gk_law_linear_stiffness_w(const gk_law_consts *K, gk_vr ri, gk_vr rj, gk_vr delta,
                                               gk_vr *kn, gk_vr *fn, gk_vr *kt) {
    gk_vr rr = gk_vr_mul(ri, rj), rs = gk_vr_div(gk_vr_add(rr, rr), gk_vr_add(ri, rj));
    gk_vr k = K->kn_const > 0 ? gk_vr_set1(K->kn_const) : gk_vr_mul(gk_vr_set1(K->young), rs);
    *kn = k;
    *fn = gk_vr_mul(k, delta);
    *kt = gk_vr_mul(gk_vr_set1(K->kt_ratio), k);
}
GK_INLINE double gk_law_linear_kn_max(const gk_material *m, double rmax, double dmax) {
    (void)dmax;
    return m->kn > 0 ? m->kn : m->young * rmax; /* r* <= r_max */
}
GK_INLINE int gk_law_linear_stiffens(void) { return 0; }

/* ---- GK_LAW_HERTZ: Liu et al. 2016 eqs 53-55, incremental Hertz-Mindlin (see LAWS above) */
GK_INLINE gk_result gk_law_hertz_check(const gk_material *m, gk_err *err) {
    if (!(m->young > 0.0)) return gk_err_set(err, GK_ERR_ARG, "Hertz law needs young > 0 (got %g)", m->young);
    if (!(m->poisson > -1.0 && m->poisson < 0.5))
        return gk_err_set(err, GK_ERR_ARG, "Poisson ratio %g outside (-1, 0.5)", m->poisson);
    if (m->coh_n > 0.0 || m->coh_t > 0.0)
        return gk_err_set(err, GK_ERR_UNSUPPORTED, "cohesion is implemented for the linear law only");
    return GK_OK;
}
GK_INLINE void gk_law_hertz_consts(const gk_material *m, gk_law_consts *k) {
    double G = m->young / (2.0 * (1.0 + m->poisson));
    k->hn = (gk_real)(G / (1.0 - m->poisson));
    k->ht = (gk_real)(2.0 * G / (2.0 - m->poisson));
}
GK_FORCE_INLINE void gk_law_hertz_stiffness(const gk_law_consts *K, gk_real ri, gk_real rj, gk_real delta,
                                            gk_real *kn, gk_real *fn, gk_real *kt) {
    gk_real rr = ri * rj, rs = (rr + rr) / (ri + rj); /* R_e = r* */
    gk_real a = (rs + rs) * delta, sq = a > 0 ? (gk_real)sqrt(a) : (gk_real)0;
    gk_real k = K->hn * sq;
    *kn = k;
    *fn = (gk_real)(2.0 / 3.0) * (k * delta);
    *kt = K->ht * sq;
}
GK_FORCE_INLINE void gk_law_hertz_stiffness_w(const gk_law_consts *K, gk_vr ri, gk_vr rj, gk_vr delta,
                                              gk_vr *kn, gk_vr *fn, gk_vr *kt) {
    gk_vr rr = gk_vr_mul(ri, rj), rs = gk_vr_div(gk_vr_add(rr, rr), gk_vr_add(ri, rj));
    gk_vr a = gk_vr_mul(gk_vr_add(rs, rs), delta);
    gk_vr sq = gk_vr_select(gk_vr_gt(a, gk_vr_zero()), gk_vr_sqrt(a), gk_vr_zero());
    gk_vr k = gk_vr_mul(gk_vr_set1(K->hn), sq);
    *kn = k;
    *fn = gk_vr_mul(gk_vr_set1((gk_real)(2.0 / 3.0)), gk_vr_mul(k, delta));
    *kt = gk_vr_mul(gk_vr_set1(K->ht), sq);
}
GK_INLINE double gk_law_hertz_kn_max(const gk_material *m, double rmax, double dmax) {
    double G = m->young / (2.0 * (1.0 + m->poisson));
    return G / (1.0 - m->poisson) * sqrt(2.0 * rmax * dmax); /* R_e <= r_max */
}
GK_INLINE int gk_law_hertz_stiffens(void) { return 1; }

/* ---- the dispatchers, generated from GK_LAW_TABLE */
GK_INLINE const char *gk_law_name(gk_law law) {
    switch (law) {
#define GK__LAW_CASE(E, name) \
    case E: return #name;
        GK_LAW_TABLE(GK__LAW_CASE)
#undef GK__LAW_CASE
    default: return "unknown";
    }
}
GK_INLINE int gk_law_stiffens(gk_law law) {
    switch (law) {
#define GK__LAW_CASE(E, name) \
    case E: return gk_law_##name##_stiffens();
        GK_LAW_TABLE(GK__LAW_CASE)
#undef GK__LAW_CASE
    default: return 0;
    }
}
GK_INLINE double gk_law_kn_max(const gk_material *m, double rmax, double dmax) {
    switch (m->law) {
#define GK__LAW_CASE(E, name) \
    case E: return gk_law_##name##_kn_max(m, rmax, dmax);
        GK_LAW_TABLE(GK__LAW_CASE)
#undef GK__LAW_CASE
    default: return 0.0;
    }
}
/* normal stiffness, force and tangential stiffness for overlap delta (> 0) */
GK_FORCE_INLINE void gk_contact_stiffness(const gk_law_consts *K, gk_law law, gk_real ri, gk_real rj,
                                          gk_real delta, gk_real *kn, gk_real *fn, gk_real *kt) {
    switch (law) {
#define GK__LAW_CASE(E, name) \
    case E: gk_law_##name##_stiffness(K, ri, rj, delta, kn, fn, kt); return;
        GK_LAW_TABLE(GK__LAW_CASE)
#undef GK__LAW_CASE
    default: *kn = *fn = *kt = 0;
    }
}
GK_FORCE_INLINE void gk_contact_stiffness_w(const gk_law_consts *K, gk_law law, gk_vr ri, gk_vr rj,
                                            gk_vr delta, gk_vr *kn, gk_vr *fn, gk_vr *kt) {
    switch (law) {
#define GK__LAW_CASE(E, name) \
    case E: gk_law_##name##_stiffness_w(K, ri, rj, delta, kn, fn, kt); return;
        GK_LAW_TABLE(GK__LAW_CASE)
#undef GK__LAW_CASE
    default: *kn = *fn = *kt = gk_vr_zero();
    }
}

/* ================================================================ THE PAIR LAW
 * Shared by every law: normal force (+ dashpot), tangential spring with its
 * history and the Coulomb cap, rolling resistance, cohesion. Each scalar
 * reference is followed by its wide twin (GK_VR_W pairs at a time, every
 * operation in the same order, no FMA, correctly rounded sqrt and division,
 * exact negation: each lane is bit-identical to the reference; cohesion has
 * no wide twin and runs through the reference). */

/* 2D law. d: branch (i -> j); v: relative centre velocity of j w.r.t. i
 * (affine part included); wi, wj: total spins; ft, mr, st: history in/out.
 * Returns 1 if the pair is in contact (or bonded). */
GK_FORCE_INLINE int gk_contact_2d(const gk_law_consts *K, gk_law law, unsigned flags, gk_real dx, gk_real dy,
                                  gk_real ri, gk_real rj, gk_real mi, gk_real mj, gk_real vx, gk_real vy,
                                  gk_real wi, gk_real wj, gk_real dt, gk_real *ft, gk_real *mr,
                                  unsigned char *st, gk_contact_out *o) {
    gk_real R = ri + rj, d2 = dx * dx + dy * dy, dist, inv, nx, ny, delta, kn, fn, kt;
    unsigned char s = *st;
    int bonded = (flags & GK_PHYS_COHESION) && (s & GK_CS_BONDED);
    o->f[0] = o->f[1] = o->f[2] = 0;
    o->ti[0] = o->ti[1] = o->ti[2] = o->tj[0] = o->tj[1] = o->tj[2] = 0;
    o->fn = o->delta = 0;
    if (!(d2 < R * R) && !bonded) {
        *ft = 0;
        if (flags & GK_PHYS_ROLLING) *mr = 0;
        *st = 0;
        return 0;
    }
    dist = (gk_real)sqrt(d2);
    inv = (gk_real)1 / dist;
    nx = dx * inv;
    ny = dy * inv;
    delta = R - dist;
    gk_contact_stiffness(K, law, ri, rj, delta, &kn, &fn, &kt);
    if (flags & GK_PHYS_COHESION) {
        if (!(s & GK_CS_CONTACT) && delta > 0 && !(s & GK_CS_BROKEN)) { /* new contact: bond */
            s |= GK_CS_BONDED;
            bonded = 1;
        }
        if (bonded && fn < -K->cn) { /* tensile failure */
            s = (unsigned char)((s & ~GK_CS_BONDED) | GK_CS_BROKEN);
            bonded = 0;
        }
        if (!bonded && !(delta > 0)) { /* apart and unbonded: no contact */
            *ft = 0;
            if (flags & GK_PHYS_ROLLING) *mr = 0;
            *st = 0;
            return 0;
        }
    }
    {
        gk_real vn = vx * nx + vy * ny, gn = 0, mstar = 0, ftot = 0, li = 0, lj = 0,
                half = (gk_real)0.5 * delta;
        if (flags & GK_PHYS_VISCOUS) {
            mstar = (mi * mj) / (mi + mj);
            gn = K->zn2 * (gk_real)sqrt(mstar * kn);
            fn = fn - gn * vn;
        }
        li = ri - half;
        lj = rj - half;
        if (flags & GK_PHYS_TANGENT) {
            gk_real tx = -ny, ty = nx, vt, f, cap, fnp = fn > 0 ? fn : (gk_real)0, gt = 0;
            vt = (vx * tx + vy * ty) - (li * wi + lj * wj);
            f = *ft - (kt * vt) * dt;
            ftot = f;
            if (flags & GK_PHYS_VISCOUS) {
                gt = K->zt2 * (gk_real)sqrt(mstar * kt);
                ftot = f - gt * vt;
            }
            cap = K->mu * fnp;
            if (bonded) cap = cap + K->ct;
            s = (unsigned char)(s & ~GK_CS_SLIDING);
            if (fabs(ftot) > cap) {
                if (bonded) { /* shear failure of the bond */
                    s = (unsigned char)((s & ~GK_CS_BONDED) | GK_CS_BROKEN);
                    bonded = 0;
                    cap = K->mu * fnp;
                }
                if (fabs(ftot) > cap) {
                    ftot = ftot > 0 ? cap : -cap;
                    f = (flags & GK_PHYS_VISCOUS) ? ftot + gt * vt : ftot;
                    s |= GK_CS_SLIDING;
                }
            }
            *ft = f;
            o->f[0] = fn * nx + ftot * tx;
            o->f[1] = fn * ny + ftot * ty;
            o->ti[2] = -li * ftot;
            o->tj[2] = -lj * ftot;
        } else {
            o->f[0] = fn * nx;
            o->f[1] = fn * ny;
        }
        if (flags & GK_PHYS_ROLLING) {
            gk_real kr = (K->beta * kt) * (ri * rj), m = *mr - (kr * (wj - wi)) * dt;
            gk_real fnp = fn > 0 ? fn : (gk_real)0, capr = (K->eta * (ri < rj ? ri : rj)) * fnp;
            if (fabs(m) > capr) m = m > 0 ? capr : -capr;
            *mr = m;
            o->ti[2] -= m;
            o->tj[2] += m;
        }
        o->fn = fn;
        o->delta = delta;
    }
    *st = (unsigned char)(s | GK_CS_CONTACT);
    return 1;
}

/* Wide twin of gk_contact_2d (no cohesion): GK_VR_W pairs. mi, mj are read
 * only with GK_PHYS_VISCOUS, ft and mr (history in, out; zero where apart)
 * only with TANGENT and ROLLING. Returns the lanes in contact; *slide gets
 * those on the Coulomb cap. The caller broadcasts K from a local copy so
 * that its constants stay in registers. */
GK_FORCE_INLINE gk_vrm gk_contact_2d_w(const gk_law_consts *K, gk_law law, unsigned flags, gk_vr dx, gk_vr dy,
                                       gk_vr ri, gk_vr rj, gk_vr mi, gk_vr mj, gk_vr vx, gk_vr vy, gk_vr wi,
                                       gk_vr wj, gk_vr dt, gk_vr *ft, gk_vr *mr, gk_vrm *slide,
                                       gk_contact_out_w *o) {
    const gk_vr zero = gk_vr_zero(), one = gk_vr_set1(1), half = gk_vr_set1((gk_real)0.5);
    gk_vr R = gk_vr_add(ri, rj), d2 = gk_vr_add(gk_vr_mul(dx, dx), gk_vr_mul(dy, dy)), dist, inv, nx, ny,
          delta;
    gk_vr kn, fn, kt, vn, mstar = zero, hd, li, lj, fx, fy, ti = zero, tj = zero;
    gk_vrm in = gk_vr_lt(d2, gk_vr_mul(R, R));
    *slide = gk_vr_lt(one, zero);
    dist = gk_vr_sqrt(d2);
    inv = gk_vr_div(one, dist);
    nx = gk_vr_mul(dx, inv);
    ny = gk_vr_mul(dy, inv);
    delta = gk_vr_sub(R, dist);
    gk_contact_stiffness_w(K, law, ri, rj, delta, &kn, &fn, &kt);
    vn = gk_vr_add(gk_vr_mul(vx, nx), gk_vr_mul(vy, ny));
    if (flags & GK_PHYS_VISCOUS) {
        mstar = gk_vr_div(gk_vr_mul(mi, mj), gk_vr_add(mi, mj));
        fn = gk_vr_sub(fn, gk_vr_mul(gk_vr_mul(gk_vr_set1(K->zn2), gk_vr_sqrt(gk_vr_mul(mstar, kn))), vn));
    }
    hd = gk_vr_mul(half, delta);
    li = gk_vr_sub(ri, hd);
    lj = gk_vr_sub(rj, hd);
    if (flags & GK_PHYS_TANGENT) {
        gk_vr tx = gk_vr_neg(ny), ty = nx, vt, f, cap, gt = zero, ftot;
        vt = gk_vr_sub(gk_vr_add(gk_vr_mul(vx, tx), gk_vr_mul(vy, ty)),
                       gk_vr_add(gk_vr_mul(li, wi), gk_vr_mul(lj, wj)));
        f = gk_vr_sub(*ft, gk_vr_mul(gk_vr_mul(kt, vt), dt));
        ftot = f;
        if (flags & GK_PHYS_VISCOUS) {
            gt = gk_vr_mul(gk_vr_set1(K->zt2), gk_vr_sqrt(gk_vr_mul(mstar, kt)));
            ftot = gk_vr_sub(f, gk_vr_mul(gt, vt));
        }
        cap = gk_vr_mul(gk_vr_set1(K->mu), gk_vr_max(fn, zero));
        *slide = gk_vr_gt(gk_vr_abs(ftot), cap);
        ftot = gk_vr_select(*slide, gk_vr_select(gk_vr_gt(ftot, zero), cap, gk_vr_neg(cap)), ftot);
        if (flags & GK_PHYS_VISCOUS)
            f = gk_vr_select(*slide, gk_vr_add(ftot, gk_vr_mul(gt, vt)), f);
        else
            f = gk_vr_select(*slide, ftot, f);
        *ft = gk_vr_select(in, f, zero);
        fx = gk_vr_add(gk_vr_mul(fn, nx), gk_vr_mul(ftot, tx));
        fy = gk_vr_add(gk_vr_mul(fn, ny), gk_vr_mul(ftot, ty));
        ti = gk_vr_mul(gk_vr_neg(li), ftot);
        tj = gk_vr_mul(gk_vr_neg(lj), ftot);
    } else {
        fx = gk_vr_mul(fn, nx);
        fy = gk_vr_mul(fn, ny);
    }
    if (flags & GK_PHYS_ROLLING) {
        gk_vr kr = gk_vr_mul(gk_vr_mul(gk_vr_set1(K->beta), kt), gk_vr_mul(ri, rj)), capr, m;
        gk_vrm over;
        m = gk_vr_sub(*mr, gk_vr_mul(gk_vr_mul(kr, gk_vr_sub(wj, wi)), dt));
        capr = gk_vr_mul(gk_vr_mul(gk_vr_set1(K->eta), gk_vr_min(ri, rj)), gk_vr_max(fn, zero));
        over = gk_vr_gt(gk_vr_abs(m), capr);
        m = gk_vr_select(over, gk_vr_select(gk_vr_gt(m, zero), capr, gk_vr_neg(capr)), m);
        *mr = gk_vr_select(in, m, zero);
        ti = gk_vr_sub(ti, m);
        tj = gk_vr_add(tj, m);
    }
    o->f[0] = gk_vr_select(in, fx, zero);
    o->f[1] = gk_vr_select(in, fy, zero);
    o->f[2] = zero;
    o->ti[0] = o->ti[1] = o->tj[0] = o->tj[1] = zero;
    o->ti[2] = gk_vr_select(in, ti, zero);
    o->tj[2] = gk_vr_select(in, tj, zero);
    return in;
}

/* rotate a 3D history vector: twist about n by angle a, project onto the
 * plane normal to n, rescale to the magnitude it had before */
GK_FORCE_INLINE void gk_contact_rotate_history(gk_real nx, gk_real ny, gk_real nz, gk_real a, gk_real *h) {
    gk_real x = h[0], y = h[1], z = h[2], m2 = x * x + y * y + z * z, px, py, pz, dn, p2;
    if (!(m2 > 0)) return;
    /* h += a (n x h) */
    px = x + a * (ny * z - nz * y);
    py = y + a * (nz * x - nx * z);
    pz = z + a * (nx * y - ny * x);
    dn = px * nx + py * ny + pz * nz;
    px = px - dn * nx;
    py = py - dn * ny;
    pz = pz - dn * nz;
    p2 = px * px + py * py + pz * pz;
    if (p2 > 0) {
        gk_real sc = (gk_real)sqrt(m2 / p2);
        h[0] = px * sc;
        h[1] = py * sc;
        h[2] = pz * sc;
    } else {
        h[0] = h[1] = h[2] = 0;
    }
}

/* wide twin of gk_contact_rotate_history */
GK_FORCE_INLINE void gk_contact_rotate_history_w(const gk_vr n[3], gk_vr a, gk_vr h[3]) {
    const gk_vr zero = gk_vr_zero();
    gk_vr m2, p[3], dn, p2, sc;
    gk_vrm has, pos;
    int k;
    m2 = gk_vr_add(gk_vr_add(gk_vr_mul(h[0], h[0]), gk_vr_mul(h[1], h[1])), gk_vr_mul(h[2], h[2]));
    p[0] = gk_vr_add(h[0], gk_vr_mul(a, gk_vr_sub(gk_vr_mul(n[1], h[2]), gk_vr_mul(n[2], h[1]))));
    p[1] = gk_vr_add(h[1], gk_vr_mul(a, gk_vr_sub(gk_vr_mul(n[2], h[0]), gk_vr_mul(n[0], h[2]))));
    p[2] = gk_vr_add(h[2], gk_vr_mul(a, gk_vr_sub(gk_vr_mul(n[0], h[1]), gk_vr_mul(n[1], h[0]))));
    dn = gk_vr_add(gk_vr_add(gk_vr_mul(p[0], n[0]), gk_vr_mul(p[1], n[1])), gk_vr_mul(p[2], n[2]));
    GK_UNROLL
    for (k = 0; k < 3; ++k) p[k] = gk_vr_sub(p[k], gk_vr_mul(dn, n[k]));
    p2 = gk_vr_add(gk_vr_add(gk_vr_mul(p[0], p[0]), gk_vr_mul(p[1], p[1])), gk_vr_mul(p[2], p[2]));
    sc = gk_vr_sqrt(gk_vr_div(m2, p2));
    has = gk_vr_gt(m2, zero);
    pos = gk_vr_gt(p2, zero);
    GK_UNROLL
    for (k = 0; k < 3; ++k) h[k] = gk_vr_select(has, gk_vr_select(pos, gk_vr_mul(p[k], sc), zero), h[k]);
}

/* 3D law; same conventions; w*: spin vectors; ft, mr: 3-vectors. */
GK_FORCE_INLINE int gk_contact_3d(const gk_law_consts *K, gk_law law, unsigned flags, const gk_real d[3],
                                  gk_real ri, gk_real rj, gk_real mi, gk_real mj, const gk_real v[3],
                                  const gk_real wi[3], const gk_real wj[3], gk_real dt, gk_real *ft,
                                  gk_real *mr, unsigned char *st, gk_contact_out *o) {
    gk_real R = ri + rj, d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], dist, inv, n[3], delta, kn, fn, kt;
    unsigned char s = *st;
    int bonded = (flags & GK_PHYS_COHESION) && (s & GK_CS_BONDED), k;
    GK_UNROLL
    for (k = 0; k < 3; ++k) o->f[k] = o->ti[k] = o->tj[k] = 0;
    o->fn = o->delta = 0;
    if (!(d2 < R * R) && !bonded) {
        ft[0] = ft[1] = ft[2] = 0;
        if (flags & GK_PHYS_ROLLING) mr[0] = mr[1] = mr[2] = 0;
        *st = 0;
        return 0;
    }
    dist = (gk_real)sqrt(d2);
    inv = (gk_real)1 / dist;
    n[0] = d[0] * inv;
    n[1] = d[1] * inv;
    n[2] = d[2] * inv;
    delta = R - dist;
    gk_contact_stiffness(K, law, ri, rj, delta, &kn, &fn, &kt);
    if (flags & GK_PHYS_COHESION) {
        if (!(s & GK_CS_CONTACT) && delta > 0 && !(s & GK_CS_BROKEN)) {
            s |= GK_CS_BONDED;
            bonded = 1;
        }
        if (bonded && fn < -K->cn) {
            s = (unsigned char)((s & ~GK_CS_BONDED) | GK_CS_BROKEN);
            bonded = 0;
        }
        if (!bonded && !(delta > 0)) {
            ft[0] = ft[1] = ft[2] = 0;
            if (flags & GK_PHYS_ROLLING) mr[0] = mr[1] = mr[2] = 0;
            *st = 0;
            return 0;
        }
    }
    {
        gk_real vn = v[0] * n[0] + v[1] * n[1] + v[2] * n[2], gn = 0, mstar = 0, half = (gk_real)0.5 * delta;
        gk_real li = ri - half, lj = rj - half, twist = 0;
        if (flags & GK_PHYS_VISCOUS) {
            mstar = (mi * mj) / (mi + mj);
            gn = K->zn2 * (gk_real)sqrt(mstar * kn);
            fn = fn - gn * vn;
        }
        if (flags & (GK_PHYS_TANGENT | GK_PHYS_ROLLING))
            twist = (gk_real)0.5 * dt *
                    ((wi[0] + wj[0]) * n[0] + (wi[1] + wj[1]) * n[1] + (wi[2] + wj[2]) * n[2]);
        if (flags & GK_PHYS_TANGENT) {
            gk_real sw[3], vc[3], vcn, vt[3], f[3], tot[3], c[3], cap, fnp = fn > 0 ? fn : (gk_real)0, gt = 0,
                                                                       m2;
            GK_UNROLL
            for (k = 0; k < 3; ++k) sw[k] = li * wi[k] + lj * wj[k];
            /* v_c = v - sw x n */
            vc[0] = v[0] - (sw[1] * n[2] - sw[2] * n[1]);
            vc[1] = v[1] - (sw[2] * n[0] - sw[0] * n[2]);
            vc[2] = v[2] - (sw[0] * n[1] - sw[1] * n[0]);
            vcn = vc[0] * n[0] + vc[1] * n[1] + vc[2] * n[2];
            GK_UNROLL
            for (k = 0; k < 3; ++k) vt[k] = vc[k] - vcn * n[k];
            gk_contact_rotate_history(n[0], n[1], n[2], twist, ft);
            GK_UNROLL
            for (k = 0; k < 3; ++k) {
                f[k] = ft[k] - (kt * vt[k]) * dt;
                tot[k] = f[k];
            }
            if (flags & GK_PHYS_VISCOUS) {
                gt = K->zt2 * (gk_real)sqrt(mstar * kt);
                GK_UNROLL
                for (k = 0; k < 3; ++k) tot[k] = f[k] - gt * vt[k];
            }
            cap = K->mu * fnp;
            if (bonded) cap = cap + K->ct;
            s = (unsigned char)(s & ~GK_CS_SLIDING);
            m2 = tot[0] * tot[0] + tot[1] * tot[1] + tot[2] * tot[2];
            if (m2 > cap * cap) {
                if (bonded) {
                    s = (unsigned char)((s & ~GK_CS_BONDED) | GK_CS_BROKEN);
                    bonded = 0;
                    cap = K->mu * fnp;
                }
                if (m2 > cap * cap) {
                    gk_real sc = cap / (gk_real)sqrt(m2);
                    GK_UNROLL
                    for (k = 0; k < 3; ++k) {
                        tot[k] = tot[k] * sc;
                        f[k] = (flags & GK_PHYS_VISCOUS) ? tot[k] + gt * vt[k] : tot[k];
                    }
                    s |= GK_CS_SLIDING;
                }
            }
            GK_UNROLL
            for (k = 0; k < 3; ++k) {
                ft[k] = f[k];
                o->f[k] = fn * n[k] + tot[k];
            }
            /* c = n x F_t */
            c[0] = n[1] * tot[2] - n[2] * tot[1];
            c[1] = n[2] * tot[0] - n[0] * tot[2];
            c[2] = n[0] * tot[1] - n[1] * tot[0];
            GK_UNROLL
            for (k = 0; k < 3; ++k) {
                o->ti[k] = -li * c[k];
                o->tj[k] = -lj * c[k];
            }
        } else {
            GK_UNROLL
            for (k = 0; k < 3; ++k) o->f[k] = fn * n[k];
        }
        if (flags & GK_PHYS_ROLLING) {
            gk_real wr[3], wrn, kr = (K->beta * kt) * (ri * rj), fnp = fn > 0 ? fn : (gk_real)0, capr, m2;
            capr = (K->eta * (ri < rj ? ri : rj)) * fnp;
            GK_UNROLL
            for (k = 0; k < 3; ++k) wr[k] = wj[k] - wi[k];
            wrn = wr[0] * n[0] + wr[1] * n[1] + wr[2] * n[2];
            gk_contact_rotate_history(n[0], n[1], n[2], twist, mr);
            GK_UNROLL
            for (k = 0; k < 3; ++k) mr[k] = mr[k] - (kr * (wr[k] - wrn * n[k])) * dt;
            m2 = mr[0] * mr[0] + mr[1] * mr[1] + mr[2] * mr[2];
            if (m2 > capr * capr) {
                gk_real sc = capr / (gk_real)sqrt(m2);
                GK_UNROLL
                for (k = 0; k < 3; ++k) mr[k] = mr[k] * sc;
            }
            GK_UNROLL
            for (k = 0; k < 3; ++k) {
                o->ti[k] -= mr[k];
                o->tj[k] += mr[k];
            }
        }
        o->fn = fn;
        o->delta = delta;
    }
    *st = (unsigned char)(s | GK_CS_CONTACT);
    return 1;
}

/* Wide twin of gk_contact_3d (no cohesion); conventions as gk_contact_2d_w,
 * d, v, wi, wj, ft and mr are 3-vectors of lanes. */
GK_FORCE_INLINE gk_vrm gk_contact_3d_w(const gk_law_consts *K, gk_law law, unsigned flags, const gk_vr d[3],
                                       gk_vr ri, gk_vr rj, gk_vr mi, gk_vr mj, const gk_vr v[3],
                                       const gk_vr wi[3], const gk_vr wj[3], gk_vr dt, gk_vr ft[3],
                                       gk_vr mr[3], gk_vrm *slide, gk_contact_out_w *o) {
    const gk_vr zero = gk_vr_zero(), one = gk_vr_set1(1), half = gk_vr_set1((gk_real)0.5);
    gk_vr n[3], F[3], R, d2, dist, inv, delta, kn, fn, kt, vn, mstar = zero, hd, li, lj, twist = zero;
    gk_vrm in;
    int k;
    R = gk_vr_add(ri, rj);
    d2 = gk_vr_add(gk_vr_add(gk_vr_mul(d[0], d[0]), gk_vr_mul(d[1], d[1])), gk_vr_mul(d[2], d[2]));
    in = gk_vr_lt(d2, gk_vr_mul(R, R));
    *slide = gk_vr_lt(one, zero);
    dist = gk_vr_sqrt(d2);
    inv = gk_vr_div(one, dist);
    GK_UNROLL
    for (k = 0; k < 3; ++k) n[k] = gk_vr_mul(d[k], inv);
    delta = gk_vr_sub(R, dist);
    gk_contact_stiffness_w(K, law, ri, rj, delta, &kn, &fn, &kt);
    GK_UNROLL
    for (k = 0; k < 3; ++k) o->ti[k] = o->tj[k] = zero;
    vn = gk_vr_add(gk_vr_add(gk_vr_mul(v[0], n[0]), gk_vr_mul(v[1], n[1])), gk_vr_mul(v[2], n[2]));
    if (flags & GK_PHYS_VISCOUS) {
        mstar = gk_vr_div(gk_vr_mul(mi, mj), gk_vr_add(mi, mj));
        fn = gk_vr_sub(fn, gk_vr_mul(gk_vr_mul(gk_vr_set1(K->zn2), gk_vr_sqrt(gk_vr_mul(mstar, kn))), vn));
    }
    hd = gk_vr_mul(half, delta);
    li = gk_vr_sub(ri, hd);
    lj = gk_vr_sub(rj, hd);
    if (flags & (GK_PHYS_TANGENT | GK_PHYS_ROLLING))
        twist = gk_vr_mul(gk_vr_mul(half, dt), gk_vr_add(gk_vr_add(gk_vr_mul(gk_vr_add(wi[0], wj[0]), n[0]),
                                                                   gk_vr_mul(gk_vr_add(wi[1], wj[1]), n[1])),
                                                         gk_vr_mul(gk_vr_add(wi[2], wj[2]), n[2])));
    if (flags & GK_PHYS_TANGENT) {
        gk_vr sw[3], vc[3], vcn, vt[3], f[3], tot[3], cc[3], cap, gt = zero, m2;
        GK_UNROLL
        for (k = 0; k < 3; ++k) sw[k] = gk_vr_add(gk_vr_mul(li, wi[k]), gk_vr_mul(lj, wj[k]));
        vc[0] = gk_vr_sub(v[0], gk_vr_sub(gk_vr_mul(sw[1], n[2]), gk_vr_mul(sw[2], n[1])));
        vc[1] = gk_vr_sub(v[1], gk_vr_sub(gk_vr_mul(sw[2], n[0]), gk_vr_mul(sw[0], n[2])));
        vc[2] = gk_vr_sub(v[2], gk_vr_sub(gk_vr_mul(sw[0], n[1]), gk_vr_mul(sw[1], n[0])));
        vcn = gk_vr_add(gk_vr_add(gk_vr_mul(vc[0], n[0]), gk_vr_mul(vc[1], n[1])), gk_vr_mul(vc[2], n[2]));
        GK_UNROLL
        for (k = 0; k < 3; ++k) vt[k] = gk_vr_sub(vc[k], gk_vr_mul(vcn, n[k]));
        gk_contact_rotate_history_w(n, twist, ft);
        GK_UNROLL
        for (k = 0; k < 3; ++k) {
            f[k] = gk_vr_sub(ft[k], gk_vr_mul(gk_vr_mul(kt, vt[k]), dt));
            tot[k] = f[k];
        }
        if (flags & GK_PHYS_VISCOUS) {
            gt = gk_vr_mul(gk_vr_set1(K->zt2), gk_vr_sqrt(gk_vr_mul(mstar, kt)));
            GK_UNROLL
            for (k = 0; k < 3; ++k) tot[k] = gk_vr_sub(f[k], gk_vr_mul(gt, vt[k]));
        }
        cap = gk_vr_mul(gk_vr_set1(K->mu), gk_vr_max(fn, zero));
        m2 = gk_vr_add(gk_vr_add(gk_vr_mul(tot[0], tot[0]), gk_vr_mul(tot[1], tot[1])),
                       gk_vr_mul(tot[2], tot[2]));
        *slide = gk_vr_gt(m2, gk_vr_mul(cap, cap));
        /* the Coulomb rescale for every block, not behind a test of any
         * sliding lane: in a sheared packing that branch mispredicts, and a
         * misprediction discards the next block's loads begun out of order
         * (3D, 10^4 spheres: 1.04x); lanes that do not slide keep tot */
        {
            gk_vr sc = gk_vr_div(cap, gk_vr_sqrt(m2));
            GK_UNROLL
            for (k = 0; k < 3; ++k) {
                gk_vr t = gk_vr_mul(tot[k], sc);
                tot[k] = gk_vr_select(*slide, t, tot[k]);
                f[k] = gk_vr_select(
                    *slide, (flags & GK_PHYS_VISCOUS) ? gk_vr_add(tot[k], gk_vr_mul(gt, vt[k])) : tot[k],
                    f[k]);
            }
        }
        GK_UNROLL
        for (k = 0; k < 3; ++k) {
            ft[k] = gk_vr_select(in, f[k], zero);
            F[k] = gk_vr_add(gk_vr_mul(fn, n[k]), tot[k]);
        }
        cc[0] = gk_vr_sub(gk_vr_mul(n[1], tot[2]), gk_vr_mul(n[2], tot[1]));
        cc[1] = gk_vr_sub(gk_vr_mul(n[2], tot[0]), gk_vr_mul(n[0], tot[2]));
        cc[2] = gk_vr_sub(gk_vr_mul(n[0], tot[1]), gk_vr_mul(n[1], tot[0]));
        GK_UNROLL
        for (k = 0; k < 3; ++k) {
            o->ti[k] = gk_vr_mul(gk_vr_neg(li), cc[k]);
            o->tj[k] = gk_vr_mul(gk_vr_neg(lj), cc[k]);
        }
    } else {
        GK_UNROLL
        for (k = 0; k < 3; ++k) F[k] = gk_vr_mul(fn, n[k]);
    }
    if (flags & GK_PHYS_ROLLING) {
        gk_vr wr[3], wrn, kr = gk_vr_mul(gk_vr_mul(gk_vr_set1(K->beta), kt), gk_vr_mul(ri, rj)), capr, m2;
        gk_vrm over;
        capr = gk_vr_mul(gk_vr_mul(gk_vr_set1(K->eta), gk_vr_min(ri, rj)), gk_vr_max(fn, zero));
        GK_UNROLL
        for (k = 0; k < 3; ++k) wr[k] = gk_vr_sub(wj[k], wi[k]);
        wrn = gk_vr_add(gk_vr_add(gk_vr_mul(wr[0], n[0]), gk_vr_mul(wr[1], n[1])), gk_vr_mul(wr[2], n[2]));
        gk_contact_rotate_history_w(n, twist, mr);
        GK_UNROLL
        for (k = 0; k < 3; ++k)
            mr[k] = gk_vr_sub(mr[k], gk_vr_mul(gk_vr_mul(kr, gk_vr_sub(wr[k], gk_vr_mul(wrn, n[k]))), dt));
        m2 = gk_vr_add(gk_vr_add(gk_vr_mul(mr[0], mr[0]), gk_vr_mul(mr[1], mr[1])), gk_vr_mul(mr[2], mr[2]));
        over = gk_vr_gt(m2, gk_vr_mul(capr, capr));
        if (gk_vrm_any(over)) {
            gk_vr sc = gk_vr_div(capr, gk_vr_sqrt(m2));
            GK_UNROLL
            for (k = 0; k < 3; ++k) mr[k] = gk_vr_select(over, gk_vr_mul(mr[k], sc), mr[k]);
        }
        GK_UNROLL
        for (k = 0; k < 3; ++k) {
            o->ti[k] = gk_vr_sub(o->ti[k], mr[k]);
            o->tj[k] = gk_vr_add(o->tj[k], mr[k]);
            mr[k] = gk_vr_select(in, mr[k], zero);
        }
    }
    GK_UNROLL
    for (k = 0; k < 3; ++k) {
        o->f[k] = gk_vr_select(in, F[k], zero);
        o->ti[k] = gk_vr_select(in, o->ti[k], zero);
        o->tj[k] = gk_vr_select(in, o->tj[k], zero);
    }
    return in;
}

#endif /* GK_CONTACT_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_CONTACT_IMPLEMENTATION)) && !defined(GK_CONTACT_IMPL_ONCE)
#define GK_CONTACT_IMPL_ONCE

#include <string.h>

GKDEF gk_material gk_material_default(void) {
    gk_material m;
    m.cookie = GK_MATERIAL_COOKIE;
    m.law = GK_LAW_LINEAR;
    m.young = 6e8;
    m.kn = 0.0;
    m.kt_ratio = 0.8;
    m.poisson = 0.25;
    m.friction = tan(0.5);
    m.roll_beta = 0.0;
    m.roll_eta = 0.0;
    m.zeta_n = 0.0;
    m.zeta_t = 0.0;
    m.coh_n = 0.0;
    m.coh_t = 0.0;
    m.density = 2650.0;
    return m;
}

GKDEF gk_result gk_material_check(const gk_material *m, gk_err *err) {
#define GK__FIN(x) \
    if (!isfinite(m->x)) return gk_err_set(err, GK_ERR_NAN, "material." #x " is %g (not finite)", m->x)
    if (m->cookie != GK_MATERIAL_COOKIE)
        return gk_err_set(err, GK_ERR_ARG, "gk_material not initialised with gk_material_default()");
    GK__FIN(young);
    GK__FIN(kn);
    GK__FIN(kt_ratio);
    GK__FIN(poisson);
    GK__FIN(friction);
    GK__FIN(roll_beta);
    GK__FIN(roll_eta);
    GK__FIN(zeta_n);
    GK__FIN(zeta_t);
    GK__FIN(coh_n);
    GK__FIN(coh_t);
    GK__FIN(density);
#undef GK__FIN
    switch (m->law) {
#define GK__LAW_CASE(E, name)                         \
    case E: {                                         \
        gk_result r_ = gk_law_##name##_check(m, err); \
        if (r_) return r_;                            \
        break;                                        \
    }
        GK_LAW_TABLE(GK__LAW_CASE)
#undef GK__LAW_CASE
    default: return gk_err_set(err, GK_ERR_ARG, "unknown contact law %d", (int)m->law);
    }
    if (m->kn < 0.0) return gk_err_set(err, GK_ERR_ARG, "kn %g < 0", m->kn);
    if (m->kt_ratio < 0.0) return gk_err_set(err, GK_ERR_ARG, "kt_ratio %g < 0", m->kt_ratio);
    if (m->friction < 0.0) return gk_err_set(err, GK_ERR_ARG, "friction %g < 0", m->friction);
    if (m->roll_beta < 0.0 || m->roll_eta < 0.0)
        return gk_err_set(err, GK_ERR_ARG, "rolling beta %g, eta %g must be >= 0", m->roll_beta, m->roll_eta);
    if (m->zeta_n < 0.0 || m->zeta_n >= 1.0 || m->zeta_t < 0.0 || m->zeta_t >= 1.0)
        return gk_err_set(err, GK_ERR_ARG, "viscous damping ratios %g, %g must be in [0, 1)", m->zeta_n,
                          m->zeta_t);
    if (m->coh_n < 0.0 || m->coh_t < 0.0)
        return gk_err_set(err, GK_ERR_ARG, "cohesion %g, %g must be >= 0", m->coh_n, m->coh_t);
    if (!(m->density > 0.0)) return gk_err_set(err, GK_ERR_MASS, "density %g must be > 0", m->density);
    return GK_OK;
}

GKDEF unsigned gk_material_flags(const gk_material *m) {
    unsigned f = 0;
    if (m->friction > 0.0 || m->coh_t > 0.0) f |= GK_PHYS_TANGENT;
    if (m->roll_beta > 0.0 && m->roll_eta > 0.0) f |= GK_PHYS_ROLLING;
    if (m->zeta_n > 0.0 || m->zeta_t > 0.0) f |= GK_PHYS_VISCOUS;
    if (m->coh_n > 0.0 || m->coh_t > 0.0) f |= GK_PHYS_COHESION;
    return f;
}

GKDEF void gk_law_consts_make(const gk_material *m, gk_law_consts *k) {
    memset(k, 0, sizeof *k);
    switch (m->law) {
#define GK__LAW_CASE(E, name) \
    case E: gk_law_##name##_consts(m, k); break;
        GK_LAW_TABLE(GK__LAW_CASE)
#undef GK__LAW_CASE
    default: break;
    }
    k->mu = (gk_real)m->friction;
    k->beta = (gk_real)m->roll_beta;
    k->eta = (gk_real)m->roll_eta;
    k->zn2 = (gk_real)(2.0 * m->zeta_n);
    k->zt2 = (gk_real)(2.0 * m->zeta_t);
    k->cn = (gk_real)m->coh_n;
    k->ct = (gk_real)m->coh_t;
}

GKDEF double gk_restitution_to_zeta(double e) {
    double l;
    if (!(e > 0.0)) return 1.0;
    if (e >= 1.0) return 0.0;
    l = log(e);
    return -l / sqrt(GK_PI * GK_PI + l * l);
}

#endif /* GK_CONTACT implementation */
