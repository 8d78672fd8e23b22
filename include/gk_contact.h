/* gk_contact.h - contact laws and their history for grainkit.    (grainkit v0.1)
 *
 * Pointwise laws for one contact between spheres (3D) or disks (2D). These
 * scalar functions are the REFERENCE: gk_dem.h's SIMD kernels perform the
 * same operations in the same order and are tested bit for bit against them.
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
 * LAWS (choose with gk_material.law)
 *   GK_LAW_LINEAR  seed 000 eqs 14-17: k_n = E r* (or a constant k_n),
 *                  r* = 2 r_i r_j / (r_i + r_j); k_t = kt_ratio k_n;
 *                  F_n = k_n delta; F_t incremental: F_t <- F_t - k_t v_t dt,
 *                  Coulomb cap |F_t| <= mu F_n (Cundall-Strack, as YADE's
 *                  Law2_ScGeom_FrictPhys_CundallStrack).
 *   GK_LAW_HERTZ   seed 004 eqs 53-55 (incremental Hertz-Mindlin), with
 *                  G = E / (2 (1 + nu)), R_e = r*:
 *                  k_n = G/(1-nu) sqrt(2 R_e delta)  = dF_n/d delta,
 *                  F_n = (2/3) k_n delta            (exact Hertz force),
 *                  k_t = 2G/(2-nu) sqrt(2 R_e delta) (Mindlin, no-slip),
 *                  F_t incremental with the current k_t; same Coulomb cap.
 *                  (seed 000 sec 2.2 gives the same k_n, k_t.)
 *   Rolling        seed 003 eqs 24-25, 28: moment on j
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
 *   Cohesion       seed 002 (Jiang et al.): a bond forms when a contact starts
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

typedef enum gk_law { GK_LAW_LINEAR = 0, GK_LAW_HERTZ = 1 } gk_law;

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
    int cookie;        /* set by gk_material_default(); catches uninitialised structs */
    gk_law law;
    double young;      /* E [Pa]: linear k_n = E r*; Hertz G = E / (2 (1 + poisson))  */
    double kn;         /* > 0: linear law with this constant k_n [N/m] instead of E r* */
    double kt_ratio;   /* linear: k_t = kt_ratio k_n (seed 000 nu_c = 0.8)            */
    double poisson;    /* Hertz-Mindlin Poisson ratio nu                               */
    double friction;   /* Coulomb coefficient mu = tan(phi) (0: frictionless)          */
    double roll_beta;  /* rolling stiffness factor beta: k_r = beta k_t r_i r_j        */
    double roll_eta;   /* rolling cap factor eta: |M_r| <= eta min(r_i, r_j) F_n       */
    double zeta_n;     /* normal viscous damping, fraction of critical                 */
    double zeta_t;     /* tangential viscous damping, fraction of critical             */
    double coh_n;      /* cohesion: largest tensile normal force of a bond [N]         */
    double coh_t;      /* cohesion: shear strength added to the Coulomb cap [N]        */
    double density;    /* particle density [kg/m^3]                                    */
} gk_material;

/* Per-law constants in the working precision, derived once from a material. */
typedef struct gk_law_consts {
    gk_real young, kn_const, kt_ratio; /* linear                                */
    gk_real hn, ht;                    /* Hertz: G/(1-nu), 2G/(2-nu)            */
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

#ifdef __cplusplus
extern "C" {
#endif

/* seed 000 material (YADE FEMxDEM prepareRVE.py): linear, E = 6e8 Pa,
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

/* ---- the reference laws (inline; `flags` and `law` are constants in the kernels) */

/* normal stiffness, force and tangential stiffness for overlap delta (>0) */
GK_FORCE_INLINE void gk_contact_stiffness(const gk_law_consts *K, gk_law law, gk_real ri, gk_real rj,
                                          gk_real delta, gk_real *kn, gk_real *fn, gk_real *kt) {
    gk_real rr = ri * rj, rs = (rr + rr) / (ri + rj); /* r* = 2 ri rj / (ri + rj) */
    if (law == GK_LAW_LINEAR) {
        gk_real k = K->kn_const > 0 ? K->kn_const : K->young * rs;
        *kn = k;
        *fn = k * delta;
        *kt = K->kt_ratio * k;
    } else {
        gk_real a = (rs + rs) * delta, sq = a > 0 ? (gk_real)sqrt(a) : (gk_real)0;
        gk_real k = K->hn * sq;
        *kn = k;
        *fn = (gk_real)(2.0 / 3.0) * (k * delta);
        *kt = K->ht * sq;
    }
}

/* 2D law. d: branch (i -> j); v: relative centre velocity of j w.r.t. i
 * (affine part included); wi, wj: total spins; ft, mr, st: history in/out.
 * Returns 1 if the pair is in contact (or bonded). */
GK_FORCE_INLINE int gk_contact_2d(const gk_law_consts *K, gk_law law, unsigned flags, gk_real dx, gk_real dy,
                                  gk_real ri, gk_real rj, gk_real mi, gk_real mj, gk_real vx, gk_real vy,
                                  gk_real wi, gk_real wj, gk_real dt, gk_real *ft, gk_real *mr, unsigned char *st,
                                  gk_contact_out *o) {
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
        gk_real vn = vx * nx + vy * ny, gn = 0, mstar = 0, ftot = 0, li = 0, lj = 0, half = (gk_real)0.5 * delta;
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

/* 3D law; same conventions; w*: spin vectors; ft, mr: 3-vectors. */
GK_FORCE_INLINE int gk_contact_3d(const gk_law_consts *K, gk_law law, unsigned flags, const gk_real d[3], gk_real ri,
                                  gk_real rj, gk_real mi, gk_real mj, const gk_real v[3], const gk_real wi[3],
                                  const gk_real wj[3], gk_real dt, gk_real *ft, gk_real *mr, unsigned char *st,
                                  gk_contact_out *o) {
    gk_real R = ri + rj, d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], dist, inv, n[3], delta, kn, fn, kt;
    unsigned char s = *st;
    int bonded = (flags & GK_PHYS_COHESION) && (s & GK_CS_BONDED), k;
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
            twist = (gk_real)0.5 * dt * ((wi[0] + wj[0]) * n[0] + (wi[1] + wj[1]) * n[1] + (wi[2] + wj[2]) * n[2]);
        if (flags & GK_PHYS_TANGENT) {
            gk_real sw[3], vc[3], vcn, vt[3], f[3], tot[3], c[3], cap, fnp = fn > 0 ? fn : (gk_real)0, gt = 0, m2;
            for (k = 0; k < 3; ++k) sw[k] = li * wi[k] + lj * wj[k];
            /* v_c = v - sw x n */
            vc[0] = v[0] - (sw[1] * n[2] - sw[2] * n[1]);
            vc[1] = v[1] - (sw[2] * n[0] - sw[0] * n[2]);
            vc[2] = v[2] - (sw[0] * n[1] - sw[1] * n[0]);
            vcn = vc[0] * n[0] + vc[1] * n[1] + vc[2] * n[2];
            for (k = 0; k < 3; ++k) vt[k] = vc[k] - vcn * n[k];
            gk_contact_rotate_history(n[0], n[1], n[2], twist, ft);
            for (k = 0; k < 3; ++k) {
                f[k] = ft[k] - (kt * vt[k]) * dt;
                tot[k] = f[k];
            }
            if (flags & GK_PHYS_VISCOUS) {
                gt = K->zt2 * (gk_real)sqrt(mstar * kt);
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
                    for (k = 0; k < 3; ++k) {
                        tot[k] = tot[k] * sc;
                        f[k] = (flags & GK_PHYS_VISCOUS) ? tot[k] + gt * vt[k] : tot[k];
                    }
                    s |= GK_CS_SLIDING;
                }
            }
            for (k = 0; k < 3; ++k) {
                ft[k] = f[k];
                o->f[k] = fn * n[k] + tot[k];
            }
            /* c = n x F_t */
            c[0] = n[1] * tot[2] - n[2] * tot[1];
            c[1] = n[2] * tot[0] - n[0] * tot[2];
            c[2] = n[0] * tot[1] - n[1] * tot[0];
            for (k = 0; k < 3; ++k) {
                o->ti[k] = -li * c[k];
                o->tj[k] = -lj * c[k];
            }
        } else {
            for (k = 0; k < 3; ++k) o->f[k] = fn * n[k];
        }
        if (flags & GK_PHYS_ROLLING) {
            gk_real wr[3], wrn, kr = (K->beta * kt) * (ri * rj), fnp = fn > 0 ? fn : (gk_real)0, capr, m2;
            capr = (K->eta * (ri < rj ? ri : rj)) * fnp;
            for (k = 0; k < 3; ++k) wr[k] = wj[k] - wi[k];
            wrn = wr[0] * n[0] + wr[1] * n[1] + wr[2] * n[2];
            gk_contact_rotate_history(n[0], n[1], n[2], twist, mr);
            for (k = 0; k < 3; ++k) mr[k] = mr[k] - (kr * (wr[k] - wrn * n[k])) * dt;
            m2 = mr[0] * mr[0] + mr[1] * mr[1] + mr[2] * mr[2];
            if (m2 > capr * capr) {
                gk_real sc = capr / (gk_real)sqrt(m2);
                for (k = 0; k < 3; ++k) mr[k] = mr[k] * sc;
            }
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

#endif /* GK_CONTACT_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_CONTACT_IMPLEMENTATION)) && !defined(GK_CONTACT_IMPL_ONCE)
#define GK_CONTACT_IMPL_ONCE

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
    if (m->law != GK_LAW_LINEAR && m->law != GK_LAW_HERTZ)
        return gk_err_set(err, GK_ERR_ARG, "unknown contact law %d", (int)m->law);
    if (m->law == GK_LAW_LINEAR && !(m->kn > 0.0) && !(m->young > 0.0))
        return gk_err_set(err, GK_ERR_ARG, "linear law needs young > 0 or kn > 0 (young %g, kn %g)", m->young,
                          m->kn);
    if (m->kn < 0.0) return gk_err_set(err, GK_ERR_ARG, "kn %g < 0", m->kn);
    if (m->law == GK_LAW_HERTZ && !(m->young > 0.0))
        return gk_err_set(err, GK_ERR_ARG, "Hertz law needs young > 0 (got %g)", m->young);
    if (m->law == GK_LAW_HERTZ && !(m->poisson > -1.0 && m->poisson < 0.5))
        return gk_err_set(err, GK_ERR_ARG, "Poisson ratio %g outside (-1, 0.5)", m->poisson);
    if (m->kt_ratio < 0.0) return gk_err_set(err, GK_ERR_ARG, "kt_ratio %g < 0", m->kt_ratio);
    if (m->friction < 0.0) return gk_err_set(err, GK_ERR_ARG, "friction %g < 0", m->friction);
    if (m->roll_beta < 0.0 || m->roll_eta < 0.0)
        return gk_err_set(err, GK_ERR_ARG, "rolling beta %g, eta %g must be >= 0", m->roll_beta, m->roll_eta);
    if (m->zeta_n < 0.0 || m->zeta_n >= 1.0 || m->zeta_t < 0.0 || m->zeta_t >= 1.0)
        return gk_err_set(err, GK_ERR_ARG, "viscous damping ratios %g, %g must be in [0, 1)", m->zeta_n, m->zeta_t);
    if (m->coh_n < 0.0 || m->coh_t < 0.0)
        return gk_err_set(err, GK_ERR_ARG, "cohesion %g, %g must be >= 0", m->coh_n, m->coh_t);
    if ((m->coh_n > 0.0 || m->coh_t > 0.0) && m->law != GK_LAW_LINEAR)
        return gk_err_set(err, GK_ERR_UNSUPPORTED, "cohesion is implemented for the linear law only");
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
    double G = m->young / (2.0 * (1.0 + m->poisson));
    k->young = (gk_real)m->young;
    k->kn_const = (gk_real)m->kn;
    k->kt_ratio = (gk_real)m->kt_ratio;
    k->hn = (gk_real)(G / (1.0 - m->poisson));
    k->ht = (gk_real)(2.0 * G / (2.0 - m->poisson));
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
