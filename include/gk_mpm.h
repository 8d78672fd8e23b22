/* gk_mpm.h - material point method (the macro scale of MPMxDEM).  (grainkit v0.1)
 *
 * An explicit MPM on a regular background grid, 2D (plane, per unit
 * thickness) or 3D: shape functions, particle-to-grid (P2G) and grid-to-
 * particle (G2P) transfers, grid boundary conditions with Coulomb friction,
 * prescribed-velocity rigid bodies that report their load, the deformation
 * gradient, the incremental displacement gradient handed to an RVE, and a
 * point-wise Drucker-Prager return map for continuum regions. Depends only on
 * gk_base.h; the DEM side and this module exchange plain arrays (dH in,
 * sigma out) in a driver.
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_MPM_IMPLEMENTATION) in one file
 * before including; see gk_base.h.
 *
 * WHAT IS HERE (paper equations in brackets: Liang & Zhao 2019, the MPMxDEM
 * model; Chen et al. 2021, the hybrid continuum-grain model)
 *   gk_mpm_grid_create/_destroy   regular grid: origin, spacing h, n[3] nodes;
 *                                 node arrays (struct of arrays) m, p, v, vn,
 *                                 fint, fext through the gk_allocator
 *   gk_mpm_grid_set_bc            fixed / roller / Coulomb-friction face
 *   gk_mpm_points_create/_destroy material points (struct of arrays)
 *   gk_mpm_points_create_box      points filling a box, ppd^dim per cell
 *   gk_mpm_points_totals          mass, momentum, kinetic energy
 *   gk_mpm_grid_node_position     position of a node
 *   gk_mpm_kernel_1d              1D weight and derivative of each basis
 *   gk_mpm_shape                  nodes, weights, gradients of one point
 *   gk_mpm_shape_values           its nodes and weights only, into the caller's arrays
 *   gk_mpm_support_inside         whether gk_mpm_shape (and P2G, G2P) take a point
 *   gk_mpm_p2g                    mass, momentum (PIC/FLIP or APIC), v = p/m,
 *                                 internal force -sum V sigma.grad N, external
 *                                 force sum N (m g + f_p)   [Liang & Zhao 2019 eqs 10-13]
 *   gk_mpm_grid_update            vn = (p + dt f)/m, local damping, face BCs,
 *                                 rigid bodies and their reaction forces
 *   gk_mpm_g2p                    velocity (PIC/FLIP blend or APIC), position,
 *                                 velocity gradient L, F, volume [eqs 16-19]
 *   gk_mpm_def_default            options: basis, transfer, scheme, alpha,
 *                                 gravity, damping, mass threshold, threads
 *   gk_mpm_step                   one step in USF, USL or MUSL order
 *   gk_mpm_bodies_advance         move rigid bodies by v dt
 *   gk_mpm_body_nodes             the grid nodes a rigid body's bounding box covers
 *   gk_mpm_body_covers            whether a rigid body covers a point (box or circle)
 *   gk_mpm_wave_speed             P-wave speed, for the time step
 *   gk_mpm_point_dh               dH = dt L, what an RVE receives [Liang & Zhao 2019 (b)]
 *   gk_mpm_point_polar            F = R U via gk_m3_polar [Liang & Zhao 2019 eqs 36-40]
 *   gk_mpm_elastic_update         hypoelastic increment (objective rotation)
 *   gk_mpm_dp_*                   Drucker-Prager return map with apex return
 *                                 and critical-state softening [Chen et al. 2021 eqs 4-8]
 *
 * GRID. Node (i,j,k) sits at origin + h (i,j,k), index i + n0 (j + n1 k);
 * 0 <= i < n[0]. Cells are the n-1 intervals between nodes. In 2D n[2] = 1
 * and the z arrays are NULL. A point's support must lie inside the grid:
 * xi = (x - origin)/h in [a, n-1-a] per axis with a = 0 (linear), lp/h
 * (uGIMP), 1/2 (quadratic B-spline), 1 (cubic B-spline); P2G and G2P
 * refuse (GK_ERR_OUTSIDE) anything else, so pad the grid with ghost layers
 * (B-splines here are the uniform ones; no boundary-modified splines).
 *
 * BASES (r = (x_p - x_I)/h, nodes per axis s)
 *   GK_MPM_LINEAR     tent 1 - |r|                                      s = 2
 *   GK_MPM_UGIMP      uGIMP: tent convolved with a box of half-size lp
 *                     (lp constant, lp <= h/2; Bardenhagen-Kober)       s = 3
 *   GK_MPM_QUADRATIC  quadratic B-spline                                s = 3
 *   GK_MPM_CUBIC      cubic B-spline                                    s = 4
 * Tensor products; gradients are exact derivatives. The stencil has s^dim
 * entries (at most GK_MPM_MAX_STENCIL = 64), zero weights included.
 *
 * TRANSFERS
 *   PIC/FLIP [Liang & Zhao 2019 eqs 17-19]: v_p <- alpha v_PIC + (1-alpha) v_FLIP,
 *     v_PIC = sum N vn_I, v_FLIP = v_p + sum N (vn_I - v_I); alpha = 1 is
 *     PIC, 0 is FLIP; Liang & Zhao 2019 uses 0.1 (5e-4 for the column collapse).
 *   APIC (Jiang et al. 2015): the point carries C = B D^-1 (field C, the
 *     affine velocity; B D^-1 with D = h^2/4 I (quadratic), h^2/3 I (cubic);
 *     for linear and uGIMP, whose D is not constant, C = sum vn_I (x) grad N,
 *     which is the same matrix for tensor-product linear weights). P2G
 *     momentum m N (v_p + C (x_I - x_p)). An affine velocity field (e.g. a
 *     rigid rotation) survives P2G + G2P exactly, for every basis.
 *   Position [eq 16]: x_p <- x_p + dt sum N vn_I (never the blended v).
 *   L_ij = sum vn_i,I dN_I/dx_j; F <- (I + dt L) F; V = det(F) V0.
 *
 * ORDERINGS (gk_mpm_step does exactly these calls; write them out to
 * interleave a DEM stress update differently)
 *   USF  [Liang & Zhao 2019 Sec 2.3]: p2g(MOMENTUM) -> g2p(GRADIENT_OLD: L from the
 *        P2G velocities v) -> stress -> p2g(FORCE) -> grid_update ->
 *        g2p(VELOCITY | POSITION)
 *   USL: p2g(MOMENTUM | FORCE) -> grid_update -> g2p(GRADIENT_NEW | VELOCITY
 *        | POSITION) (L from vn at the old positions) -> stress
 *   MUSL: p2g(MOMENTUM | FORCE) -> grid_update -> g2p(VELOCITY | POSITION)
 *        -> p2g(MOMENTUM) (remap the new point velocities) ->
 *        g2p(GRADIENT_OLD) -> stress
 *   Rigid bodies then move by v dt (gk_mpm_bodies_advance).
 * A step whose gradient update would invert some point (det F <= 0) is
 * refused (GK_ERR_DIVERGED) with every point as it was before the step:
 * g2p checks all points before it writes any, and the MUSL step puts back
 * the positions and velocities it had moved. (A failing stress function
 * leaves F, L and vol of that step; the grid is scratch.)
 *
 * BOUNDARY CONDITIONS act on the node velocity after the forces, and on the
 * P2G velocity v (then p = m v; no reaction is counted there), faces in the
 * order x-, x+, y-, y+, z-, z+, then rigid bodies in array order:
 *   FIXED     v = 0
 *   ROLLER    normal component v_a = 0 (both directions)
 *   FRICTION  unilateral Coulomb wall: a node moving into the wall loses its
 *             normal velocity dv_n; its tangential speed is reduced by
 *             mu dv_n (impulse ratio = mu), to zero if smaller (stick).
 * A face acts on the `layers` node layers next to it (the wall plane is the
 * innermost one). A rigid body is an axis-aligned box or a circle (a disk
 * in 2D, a cylinder along z in 3D) moving at v; it acts on the active nodes
 * inside it: STICK (rough) v_I = v_body; SMOOTH or FRICTION as the wall
 * above on the velocity relative to the body, normal = outward normal of a
 * chosen face of the box or of the nearest face; of a circle, the radial
 * direction (x_I - centre) / |x_I - centre|. Both shapes share this code. Each
 * face and body records force = sum m_I (v_after - v_before) / dt over the
 * last grid update (v_before without grid damping, so damping never leaks
 * into a load): the force it exerted ON the material. The load on a
 * footing is -force. Nodes with m <= mass_min are inactive (velocity 0, no
 * constraint); the default threshold is 1e-14 x the smallest point mass, so
 * B-spline nodes at the edge of a support (weights ~1e-12) stay active.
 *
 * DAMPING (optional, def.damping in [0,1)): Cundall local non-viscous
 * damping on the grid, f_k -= damping |f_k| sign(v_k) per node (the form of
 * Liang & Zhao 2019 eq 29, applied to nodes) for quasi-static runs.
 *
 * THREADS AND DETERMINISM. P2G scatters without atomics: points are
 * counting-sorted into blocks of 4^dim cells, the blocks are coloured
 * (2^dim colours, same-colour blocks never share a node for any basis) and
 * a colour's blocks run in parallel. Every node therefore receives its sum
 * in the same order - colour by colour, points by ascending index - for any
 * thread count: results are bit-identical with 1, 2 or N threads (tested).
 * G2P and the node update are per point / per node. Face and body
 * reactions are summed serially.
 *
 * STRESS UPDATE. gk_mpm_step calls a user function after L is known; each
 * point's dH = dt L (stretch + spin) goes to its RVE, whose Love-Weber
 * stress (tension-positive) goes back to sigma [Liang & Zhao 2019 (b)]. For continuum
 * points: gk_mpm_elastic_update and gk_mpm_dp_update. Both rotate sigma by
 * R = exp(dt W), W = skew L, then add the small-strain increment of
 * d eps = sym(dH) (hypoelastic; Chen et al. 2021 writes the same law in Hencky
 * strains, identical to first order in dH).
 *
 * DRUCKER-PRAGER [Chen et al. 2021 eqs 4-8], p = tr sigma / dim (tension-positive),
 * s = sigma - p I, q = sqrt(J2) = sqrt(s:s/2):
 *   f = q + eta p - zeta c,  g = q + etabar p (plastic potential)
 *   trial: sigma_tr = sigma + K tr(de) I + 2 G dev(de)
 *   f_tr <= 0 elastic; else dlambda = f_tr / (G + K eta etabar),
 *   s = s_tr (1 - G dlambda / q_tr), p = p_tr - K etabar dlambda;
 *   apex when q_tr < G dlambda: s = 0, p = zeta c / eta.
 *   2D (Chen et al. 2021): eta = sin phi, etabar = sin psi, zeta = cos phi (exactly
 *   Mohr-Coulomb in plane). 3D: the compression-meridian cone,
 *   eta = 6 sin phi / (sqrt3 (3 - sin phi)), zeta = 6 cos phi / (...).
 *   Critical state (chi > 0): tan phi = tan phi_cs + (Phi - Phi_cs) chi,
 *   tan psi = (Phi - Phi_cs) chi [eq 7], Phi += -(Phi - Phi_cs) Phi xi
 *   |de_p| [eq 8], |.| Frobenius. A Phi below Phi_cs - tan phi_cs / chi
 *   (negative friction) is refused (GK_ERR_ARG, nothing written).
 *   K and G are the moduli of the dimension: 2D plane K (p = K tr eps),
 *   P-wave modulus M = K + G (2D), K + 4G/3 (3D).
 *
 * CHOICES. Options are a plain struct with gk_mpm_def_default() (zero also
 * works: linear, pure FLIP, USF). Point tensors are stored 9 per point
 * (array of 3x3 blocks inside the struct of arrays) rather than 9 arrays:
 * they go whole to gk_m3_* and to an RVE, and G2P writes them together.
 * The caller owns the rigid-body array (g->body, g->nbody). P2G keeps each
 * point's per-axis weights in the grid (about 270 bytes a point), and the
 * transfers after it reuse them while the point's position, lp and the basis
 * are bit-for-bit the same: the weights are computed once per step, and the
 * results are those of weights computed afresh.
 *
 * CONVENTIONS: SI units (2D: per unit thickness, volumes are areas, forces
 * N/m); stress tension-positive; L_ij = dv_i/dx_j, H_ij = du_i/dx_j;
 * tensors of a point are contiguous row-major double[9] (F + 9 p, ...) so
 * they pass straight to gk_m3_* and to an RVE; in 2D F_22 = 1, L_22 = 0,
 * sigma_22 = 0 (plane, the out-of-plane stress is not tracked).
 *
 * ERRORS: every function that can fail returns a gk_result with a message in
 * the gk_err it was given. Bad input (NaN, spacing <= 0, a point outside the
 * grid, mass or volume <= 0, dt <= 0) is detected before anything is written.
 * Exceptions, stated: gk_mpm_grid_update returns GK_ERR_DIVERGED after the
 * update if a node velocity became non-finite, and gk_mpm_g2p returns
 * GK_ERR_DIVERGED after the update if some det F <= 0 (the point is named).
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_MPM_H
#define GK_MPM_H

#include "gk_base.h"

#define GK_MPM_MAX_STENCIL 64 /* 4^3 nodes: cubic B-spline in 3D */
#define GK_MPM_BLOCK 4        /* cells per block edge in the coloured P2G */

typedef enum gk_mpm_basis {
    GK_MPM_LINEAR = 0,
    GK_MPM_UGIMP = 1,
    GK_MPM_QUADRATIC = 2,
    GK_MPM_CUBIC = 3
} gk_mpm_basis;

typedef enum gk_mpm_transfer { GK_MPM_PIC_FLIP = 0, GK_MPM_APIC = 1 } gk_mpm_transfer;
typedef enum gk_mpm_scheme { GK_MPM_USF = 0, GK_MPM_USL = 1, GK_MPM_MUSL = 2 } gk_mpm_scheme;

typedef enum gk_mpm_bc_kind {
    GK_MPM_BC_FREE = 0,
    GK_MPM_BC_FIXED = 1,
    GK_MPM_BC_ROLLER = 2,
    GK_MPM_BC_FRICTION = 3
} gk_mpm_bc_kind;

typedef enum gk_mpm_contact {
    GK_MPM_CONTACT_STICK = 0,    /* rough: covered nodes move with the body */
    GK_MPM_CONTACT_FRICTION = 1, /* Coulomb with mu, unilateral */
    GK_MPM_CONTACT_SMOOTH = 2    /* frictionless, unilateral */
} gk_mpm_contact;

/* face index: 0 x-, 1 x+, 2 y-, 3 y+, 4 z-, 5 z+ */
typedef struct gk_mpm_face {
    gk_mpm_bc_kind kind;
    double mu;       /* FRICTION: Coulomb coefficient (>= 0) */
    int layers;      /* node layers the BC acts on, counted from the face (>= 1) */
    double force[3]; /* out: force on the material in the last grid update */
} gk_mpm_face;

/* shape of a rigid body */
typedef enum gk_mpm_body_shape {
    GK_MPM_BOX = 0,   /* axis-aligned box lo..hi */
    GK_MPM_CIRCLE = 1 /* disk of centre, radius (2D); in 3D a cylinder along z through the whole grid */
} gk_mpm_body_shape;

/* A prescribed-velocity rigid body: an axis-aligned box (a footing, a plate)
 * or a circle (a pipe). Zero-initialised except lo, hi: a stick box at rest. */
typedef struct gk_mpm_body {
    double lo[3], hi[3]; /* box corners [m]; nodes with lo <= x_I <= hi are covered */
    double v[3];         /* prescribed velocity [m/s] */
    gk_mpm_contact contact;
    double mu;               /* FRICTION: Coulomb coefficient */
    int face;                /* contact normal of a box for SMOOTH/FRICTION: 0 = outward
                        normal of the box face nearest to each node, 1..6 = that
                        of face x-, x+, y-, y+, z-, z+ for every node (0 for a circle) */
    double force[3];         /* out: force on the material in the last grid update */
    gk_mpm_body_shape shape; /* GK_MPM_BOX (0, uses lo, hi) or GK_MPM_CIRCLE (uses centre, radius;
                           nodes with |x_I - centre| <= radius in x, y are covered, contact
                           normal (x_I - centre) / |x_I - centre|, -e_y at the centre) */
    double centre[3];        /* CIRCLE: centre [m] (centre[2] unused) */
    double radius;           /* CIRCLE: radius [m], finite and > 0 */
} gk_mpm_body;

typedef struct gk_mpm_grid {
    int dim;  /* 2 or 3 */
    int n[3]; /* nodes per axis (n[2] = 1 in 2D) */
    size_t nnode;
    double origin[3]; /* position of node (0,0,0) [m] */
    double h, inv_h;  /* spacing [m] */
    /* node arrays, nnode each; index i + n0 (j + n1 k); [2] NULL in 2D */
    double *m;       /* mass [kg] */
    double *p[3];    /* momentum from P2G [kg m/s] */
    double *v[3];    /* P2G velocity p/m (BCs applied) */
    double *vn[3];   /* updated velocity (after forces and BCs) */
    double *fint[3]; /* internal force -sum V sigma.grad N [N] */
    double *fext[3]; /* external force sum N (m g + f_p) [N]; the caller may add
                        nodal loads between gk_mpm_p2g and gk_mpm_grid_update */
    gk_mpm_face face[6];
    gk_mpm_body *body; /* caller-owned array of rigid bodies (may be NULL) */
    int nbody;
    double mass_min; /* nodes with m <= mass_min are inactive (set by P2G) */
    /* private: coloured block sort of the points */
    int nb[3], nblock, colour_start[9];
    int32_t *slot;   /* block -> position in colour-major order */
    int32_t *bstart; /* nblock + 1 */
    int32_t *order, *bid;
    int cap; /* capacity of order and bid */
    /* private: each point's per-axis weights from the last P2G, reused by the
     * transfers that follow while its position, lp and the basis are the same */
    struct gk__mpm_wc *wc;
    int wc_cap;
    double wc_stamp[4]; /* origin and 1/h the cached weights were made with */
    gk_allocator alloc;
} gk_mpm_grid;

/* Material points: struct of arrays, n entries each ([2] NULL in 2D), and
 * row-major 3x3 tensors stored 9 per point. */
typedef struct gk_mpm_points {
    int dim, n;
    double *x[3];    /* position [m] */
    double *v[3];    /* velocity [m/s] */
    double *fext[3]; /* external point force (traction x area, N or N/m) */
    double *m;       /* mass [kg] */
    double *vol0;    /* initial volume [m^3] (2D: area) */
    double *vol;     /* current volume det(F) vol0 */
    double *lp;      /* uGIMP half-size [m] (constant; <= h/2) */
    double *F;       /* deformation gradient, 9 per point */
    double *L;       /* velocity gradient of the last G2P [1/s], 9 per point */
    double *sigma;   /* Cauchy stress, tension-positive [Pa], 9 per point */
    double *C;       /* APIC affine velocity B D^-1 [1/s], 9 per point */
    gk_allocator alloc;
} gk_mpm_points;

typedef struct gk_mpm_def {
    gk_mpm_basis basis;
    gk_mpm_transfer transfer;
    gk_mpm_scheme scheme; /* for gk_mpm_step */
    double alpha;         /* PIC fraction of the PIC/FLIP blend, [0, 1] */
    double gravity[3];    /* body force per unit mass [m/s^2] */
    double damping;       /* local non-viscous grid damping, [0, 1) */
    double mass_min;      /* node mass threshold; <= 0: 1e-14 x smallest point mass */
    int threads;          /* OpenMP threads for P2G/G2P/update; <= 1 serial */
} gk_mpm_def;

/* one point's stencil: s^dim nodes (zero weights included) */
typedef struct gk_mpm_stencil {
    int n;
    int32_t node[GK_MPM_MAX_STENCIL];
    double w[GK_MPM_MAX_STENCIL];
    double dw[GK_MPM_MAX_STENCIL][3]; /* grad N [1/m] */
} gk_mpm_stencil;

/* flags for gk_mpm_p2g and gk_mpm_g2p */
#define GK_MPM_P2G_MOMENTUM 1     /* m, p, v = p/m (+ BCs on v) */
#define GK_MPM_P2G_FORCE 2        /* fint, fext */
#define GK_MPM_G2P_VELOCITY 1     /* v_p (and C for APIC) from v, vn */
#define GK_MPM_G2P_POSITION 2     /* x_p += dt sum N vn */
#define GK_MPM_G2P_GRADIENT_NEW 4 /* L from vn, then F, vol */
#define GK_MPM_G2P_GRADIENT_OLD 8 /* L from v (the P2G velocity), then F, vol */

typedef struct gk_mpm_dp {
    double K, G;   /* bulk and shear moduli of the dimension [Pa] (> 0) */
    double eta;    /* friction coefficient of f (2D: sin phi) */
    double etabar; /* dilatancy coefficient of g (2D: sin psi) */
    double zeta;   /* cohesion factor (2D: cos phi) */
    double c;      /* cohesion [Pa] (>= 0) */
    /* critical-state softening [Chen et al. 2021 eqs 7-8]; off when chi <= 0 */
    double tan_phi_cs, Phi_cs, chi, xi;
} gk_mpm_dp;

typedef struct gk_mpm_dp_info {
    int status;       /* 0 elastic, 1 return to the cone, 2 return to the apex */
    double f_trial;   /* yield function of the trial stress [Pa] */
    double dlambda;   /* plastic multiplier (cone return) */
    double deps_p[9]; /* plastic strain increment */
} gk_mpm_dp_info;

/* user stress update called by gk_mpm_step once L (and F, vol) are known */
typedef gk_result (*gk_mpm_stress_fn)(gk_mpm_points *pts, double dt, void *user, gk_err *err);

#ifdef __cplusplus
extern "C" {
#endif

/* grid with n[0] x n[1] (x n[2]) nodes, each >= 2; origin and h finite, h > 0 */
GKDEF gk_result gk_mpm_grid_create(gk_mpm_grid *g, int dim, const double origin[3], double h, const int n[3],
                                   const gk_allocator *alloc, gk_err *err);
GKDEF void gk_mpm_grid_destroy(gk_mpm_grid *g);
/* boundary condition on face 0..5 (x-, x+, y-, y+, z-, z+) over `layers` node layers */
GKDEF gk_result gk_mpm_grid_set_bc(gk_mpm_grid *g, int face, gk_mpm_bc_kind kind, double mu, int layers,
                                   gk_err *err);
/* node position */
GKDEF void gk_mpm_grid_node_position(const gk_mpm_grid *g, size_t node, double x[3]);

/* n points, zeroed, F = I, lp = 0 */
GKDEF gk_result gk_mpm_points_create(gk_mpm_points *pts, int dim, int n, const gk_allocator *alloc,
                                     gk_err *err);
/* points filling the box [lo, hi] whose edges are whole multiples of h,
 * ppd points per cell edge (ppd^dim per cell) at the sub-cell centres,
 * density rho, velocity 0, vol0 = (h/ppd)^dim, lp = h / (2 ppd) */
GKDEF gk_result gk_mpm_points_create_box(gk_mpm_points *pts, int dim, const double lo[3], const double hi[3],
                                         double h, int ppd, double rho, const gk_allocator *alloc,
                                         gk_err *err);
GKDEF void gk_mpm_points_destroy(gk_mpm_points *pts);
/* total mass, momentum and kinetic energy of the points (serial, fixed order) */
GKDEF void gk_mpm_points_totals(const gk_mpm_points *pts, double *mass, double mom[3], double *kinetic);

/* nodes, weights and gradients of a point at x (half-size lp, uGIMP only) */
GKDEF gk_result gk_mpm_shape(const gk_mpm_grid *g, gk_mpm_basis basis, const double x[3], double lp,
                             gk_mpm_stencil *st, gk_err *err);
/* the nodes and weights of gk_mpm_shape alone (the same values, no gradients),
 * into node[] and w[] with room for s^dim entries (s = gk_mpm_basis_width;
 * at most GK_MPM_MAX_STENCIL); *n their count. For a caller that keeps many
 * points' stencils: 12 bytes a node instead of gk_mpm_stencil's 36. */
GKDEF gk_result gk_mpm_shape_values(const gk_mpm_grid *g, gk_mpm_basis basis, const double x[3], double lp,
                                    int *n, int32_t *node, double *w, gk_err *err);
/* 1 if gk_mpm_shape takes a point at x (finite, basis known, uGIMP lp in
 * (0, h/2], its support inside the grid: GRID above), else 0; no error is
 * set. A caller that must act before a moving point leaves (remove it, stop
 * a run) asks it at x pushed outward by its own spare */
GKDEF int gk_mpm_support_inside(const gk_mpm_grid *g, gk_mpm_basis basis, const double x[3], double lp);

GKDEF gk_mpm_def gk_mpm_def_default(void); /* linear, PIC/FLIP alpha 0.1, USF, 1 thread */

GKDEF gk_result gk_mpm_p2g(gk_mpm_grid *g, const gk_mpm_points *pts, const gk_mpm_def *def, int what,
                           gk_err *err);
GKDEF gk_result gk_mpm_grid_update(gk_mpm_grid *g, const gk_mpm_def *def, double dt, gk_err *err);
GKDEF gk_result gk_mpm_g2p(const gk_mpm_grid *g, gk_mpm_points *pts, const gk_mpm_def *def, double dt,
                           int what, gk_err *err);
/* one explicit step in def->scheme order; stress may be NULL (sigma kept) */
GKDEF gk_result gk_mpm_step(gk_mpm_grid *g, gk_mpm_points *pts, const gk_mpm_def *def, double dt,
                            gk_mpm_stress_fn stress, void *user, gk_err *err);
GKDEF void gk_mpm_bodies_advance(gk_mpm_body *body, int nbody, double dt);
/* the grid nodes inside body B's box [lo, hi] (1e-9 of a cell of slack), clipped to the grid:
 * nodes lo[k]..hi[k] along each axis (none when hi[k] < lo[k]); lo = hi = 0 on unused axes. For a
 * circle the box is its bounding box centre -+ radius (all of z in 3D); gk_mpm_body_covers tells
 * which of those nodes it covers. */
GKDEF void gk_mpm_body_nodes(const gk_mpm_grid *g, const gk_mpm_body *B, int lo[3], int hi[3]);
/* 1 when body B covers position x (a node's): a box always within its gk_mpm_body_nodes range, a
 * circle when |x - centre| <= radius + 1e-9 h in x, y; 0 otherwise */
GKDEF int gk_mpm_body_covers(const gk_mpm_grid *g, const gk_mpm_body *B, const double x[3]);

/* F = R U of point p [Liang & Zhao 2019 eqs 36-40]; GK_ERR_SINGULAR if det F <= 0 */
GKDEF gk_result gk_mpm_point_polar(const gk_mpm_points *pts, int p, double R[9], double U[9], gk_err *err);

/* hypoelastic update: sigma <- R sigma R^T + K tr(de) I + 2G dev(de) */
GKDEF gk_result gk_mpm_elastic_update(double K, double G, int dim, const double dH[9], double sigma[9],
                                      gk_err *err);
/* Drucker-Prager from Mohr-Coulomb angles [rad] (see the top comment) */
GKDEF gk_result gk_mpm_dp_init(gk_mpm_dp *dp, int dim, double K, double G, double phi, double psi, double c,
                               gk_err *err);
GKDEF double gk_mpm_dp_yield(const gk_mpm_dp *dp, int dim, const double sigma[9]);
/* return map of a trial stress (sig may alias sig_trial); info may be NULL */
GKDEF gk_result gk_mpm_dp_return(const gk_mpm_dp *dp, int dim, const double sig_trial[9], double sig[9],
                                 gk_mpm_dp_info *info, gk_err *err);
/* rotate, elastic trial from dH, return map; Phi (packing fraction) updated
 * by eq 8 and used by eq 7 when dp->chi > 0 (Phi may be NULL otherwise; a Phi
 * whose eq 7 friction is negative is refused) */
GKDEF gk_result gk_mpm_dp_update(const gk_mpm_dp *dp, int dim, const double dH[9], double sigma[9],
                                 double *Phi, gk_mpm_dp_info *info, gk_err *err);
/* gk_mpm_dp_update in two parts, for callers that keep each point's
 * coefficients while its Phi does not change (elastic points: eq 8 moves
 * Phi only on plastic steps), so that they skip eq 7's trigonometry:
 * gk_mpm_dp_at gives dp with eta, etabar, zeta of eq 7 at Phi (a copy of
 * dp when dp->chi <= 0); gk_mpm_dp_update_at is gk_mpm_dp_update with
 * those made for *Phi. Both together give gk_mpm_dp_update's bits. */
GKDEF gk_result gk_mpm_dp_at(const gk_mpm_dp *dp, int dim, double Phi, gk_mpm_dp *out, gk_err *err);
GKDEF gk_result gk_mpm_dp_update_at(const gk_mpm_dp *dp_at, int dim, const double dH[9], double sigma[9],
                                    double *Phi, gk_mpm_dp_info *info, gk_err *err);

#ifdef __cplusplus
}
#endif

/* nodes per axis of a basis */
GK_INLINE int gk_mpm_basis_width(gk_mpm_basis b) {
    return b == GK_MPM_LINEAR ? 2 : (b == GK_MPM_CUBIC ? 4 : 3);
}

/* 1D weight N(r) and, if dN is not NULL, dN/dr, r = (x_p - x_I)/h; l = lp/h
 * (uGIMP only); the library's loops inline this with the basis a constant */
GK_FORCE_INLINE double gk__mpm_kernel(gk_mpm_basis b, double r, double l, double *dN) {
    double a = fabs(r), sg = r < 0.0 ? -1.0 : 1.0;
    switch (b) {
    case GK_MPM_LINEAR:
        if (a < 1.0) {
            if (dN) *dN = -sg;
            return 1.0 - a;
        }
        break;
    case GK_MPM_UGIMP:
        if (a < l) {
            if (dN) *dN = -r / l;
            return 1.0 - (r * r + l * l) / (2.0 * l);
        }
        if (a < 1.0 - l) {
            if (dN) *dN = -sg;
            return 1.0 - a;
        }
        if (a < 1.0 + l) {
            double t = 1.0 + l - a;
            if (dN) *dN = -sg * t / (2.0 * l);
            return t * t / (4.0 * l);
        }
        break;
    case GK_MPM_QUADRATIC:
        if (a < 0.5) {
            if (dN) *dN = -2.0 * r;
            return 0.75 - r * r;
        }
        if (a < 1.5) {
            double t = 1.5 - a;
            if (dN) *dN = -sg * t;
            return 0.5 * t * t;
        }
        break;
    case GK_MPM_CUBIC:
        if (a < 1.0) {
            if (dN) *dN = 1.5 * r * a - 2.0 * r;
            return 0.5 * a * a * a - r * r + 2.0 / 3.0;
        }
        if (a < 2.0) {
            double t = 2.0 - a;
            if (dN) *dN = -sg * 0.5 * t * t;
            return t * t * t / 6.0;
        }
        break;
    }
    if (dN) *dN = 0.0;
    return 0.0;
}

/* 1D weight N(r) and dN/dr (dN may be NULL), r = (x_p - x_I)/h; l = lp/h (uGIMP only) */
GK_INLINE double gk_mpm_kernel_1d(gk_mpm_basis b, double r, double l, double *dN) {
    return gk__mpm_kernel(b, r, l, dN);
}

/* dH = dt L of point p: the incremental displacement gradient (stretch and
 * spin) an RVE receives for this step [Liang & Zhao 2019 step (b)] */
GK_INLINE void gk_mpm_point_dh(const gk_mpm_points *pts, int p, double dt, double dH[9]) {
    int k;
    for (k = 0; k < 9; ++k) dH[k] = dt * pts->L[9 * p + k];
}

/* P-wave speed sqrt(M / rho), M = K + G (2D) or K + 4G/3 (3D): dt <= ~0.3 h / (c + |v|) */
GK_INLINE double gk_mpm_wave_speed(double K, double G, double rho, int dim) {
    return sqrt((K + (dim == 2 ? 1.0 : 4.0 / 3.0) * G) / rho);
}

#endif /* GK_MPM_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_MPM_IMPLEMENTATION)) && !defined(GK_MPM_IMPL_ONCE)
#define GK_MPM_IMPL_ONCE
#include <string.h>

/* ---- grid */
static void gk__mpm_grid_free_arrays(gk_mpm_grid *g) {
    int k;
    gk_free(&g->alloc, g->m);
    for (k = 0; k < 3; ++k) {
        gk_free(&g->alloc, g->p[k]);
        gk_free(&g->alloc, g->v[k]);
        gk_free(&g->alloc, g->vn[k]);
        gk_free(&g->alloc, g->fint[k]);
        gk_free(&g->alloc, g->fext[k]);
    }
    gk_free(&g->alloc, g->slot);
    gk_free(&g->alloc, g->bstart);
    gk_free(&g->alloc, g->order);
    gk_free(&g->alloc, g->bid);
    gk_free(&g->alloc, g->wc);
}

GKDEF gk_result gk_mpm_grid_create(gk_mpm_grid *g_out, int dim, const double origin[3], double h,
                                   const int n[3], const gk_allocator *alloc, gk_err *err) {
    gk_mpm_grid g;
    int k, bad = 0, c, b;
    size_t nn = 1;
    if (!g_out || !origin || !n) return gk_err_set(err, GK_ERR_ARG, "NULL grid, origin or node counts");
    if (dim != 2 && dim != 3) return gk_err_set(err, GK_ERR_ARG, "dimension %d (must be 2 or 3)", dim);
    if (!isfinite(h)) return gk_err_set(err, GK_ERR_NAN, "grid spacing is NaN or infinite");
    if (!(h > 0.0)) return gk_err_set(err, GK_ERR_ARG, "grid spacing h = %g (must be > 0)", h);
    for (k = 0; k < dim; ++k) {
        if (!isfinite(origin[k])) return gk_err_set(err, GK_ERR_NAN, "grid origin[%d] is NaN or infinite", k);
        if (n[k] < 2)
            return gk_err_set(err, GK_ERR_ARG, "grid has %d nodes along axis %d (need >= 2)", n[k], k);
        if (nn > (size_t)INT32_MAX / (size_t)n[k]) bad = 1;
        nn *= (size_t)n[k];
    }
    if (bad) return gk_err_set(err, GK_ERR_ARG, "grid of more than 2^31 nodes");
    memset(&g, 0, sizeof g);
    if (alloc) g.alloc = *alloc;
    g.dim = dim;
    g.h = h;
    g.inv_h = 1.0 / h;
    for (k = 0; k < 3; ++k) {
        g.n[k] = k < dim ? n[k] : 1;
        g.origin[k] = k < dim ? origin[k] : 0.0;
        g.nb[k] = k < dim ? (n[k] - 1 + GK_MPM_BLOCK - 1) / GK_MPM_BLOCK : 1;
        g.face[2 * k].layers = g.face[2 * k + 1].layers = 1;
    }
    g.nnode = nn;
    g.nblock = g.nb[0] * g.nb[1] * g.nb[2];
    g.m = (double *)gk_alloc(&g.alloc, nn * sizeof(double));
    bad = !g.m;
    for (k = 0; k < dim; ++k) {
        g.p[k] = (double *)gk_alloc(&g.alloc, nn * sizeof(double));
        g.v[k] = (double *)gk_alloc(&g.alloc, nn * sizeof(double));
        g.vn[k] = (double *)gk_alloc(&g.alloc, nn * sizeof(double));
        g.fint[k] = (double *)gk_alloc(&g.alloc, nn * sizeof(double));
        g.fext[k] = (double *)gk_alloc(&g.alloc, nn * sizeof(double));
        if (!g.p[k] || !g.v[k] || !g.vn[k] || !g.fint[k] || !g.fext[k]) bad = 1;
    }
    g.slot = (int32_t *)gk_alloc(&g.alloc, (size_t)g.nblock * sizeof(int32_t));
    g.bstart = (int32_t *)gk_alloc(&g.alloc, ((size_t)g.nblock + 1) * sizeof(int32_t));
    if (bad || !g.slot || !g.bstart) {
        gk__mpm_grid_free_arrays(&g);
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for a grid of %lu nodes", (unsigned long)nn);
    }
    memset(g.m, 0, nn * sizeof(double));
    for (k = 0; k < dim; ++k) {
        memset(g.p[k], 0, nn * sizeof(double));
        memset(g.v[k], 0, nn * sizeof(double));
        memset(g.vn[k], 0, nn * sizeof(double));
        memset(g.fint[k], 0, nn * sizeof(double));
        memset(g.fext[k], 0, nn * sizeof(double));
    }
    /* blocks in colour-major order: colour = parity of the block coordinates */
    k = 0;
    for (c = 0; c < (1 << dim); ++c) {
        g.colour_start[c] = k;
        for (b = 0; b < g.nblock; ++b) {
            int bx = b % g.nb[0], by = (b / g.nb[0]) % g.nb[1], bz = b / (g.nb[0] * g.nb[1]);
            if (((bx & 1) | ((by & 1) << 1) | ((bz & 1) << 2)) == c) g.slot[b] = (int32_t)k++;
        }
    }
    for (c = 1 << dim; c < 9; ++c) g.colour_start[c] = k;
    *g_out = g;
    return GK_OK;
}

GKDEF void gk_mpm_grid_destroy(gk_mpm_grid *g) {
    if (!g) return;
    gk__mpm_grid_free_arrays(g);
    memset(g, 0, sizeof *g);
}

GKDEF gk_result gk_mpm_grid_set_bc(gk_mpm_grid *g, int face, gk_mpm_bc_kind kind, double mu, int layers,
                                   gk_err *err) {
    if (face < 0 || face >= 2 * g->dim)
        return gk_err_set(err, GK_ERR_ARG, "face %d (must be 0..%d: x-, x+, y-, y+[, z-, z+])", face,
                          2 * g->dim - 1);
    if ((int)kind < 0 || (int)kind > (int)GK_MPM_BC_FRICTION)
        return gk_err_set(err, GK_ERR_ARG, "unknown boundary condition kind %d", (int)kind);
    if (!isfinite(mu)) return gk_err_set(err, GK_ERR_NAN, "friction coefficient is NaN or infinite");
    if (mu < 0.0) return gk_err_set(err, GK_ERR_ARG, "friction coefficient %g < 0", mu);
    if (layers < 1 || layers > g->n[face / 2])
        return gk_err_set(err, GK_ERR_ARG, "%d node layers on face %d (must be 1..%d)", layers, face,
                          g->n[face / 2]);
    g->face[face].kind = kind;
    g->face[face].mu = mu;
    g->face[face].layers = layers;
    return GK_OK;
}

GKDEF void gk_mpm_grid_node_position(const gk_mpm_grid *g, size_t node, double x[3]) {
    size_t i = node % (size_t)g->n[0], j = (node / (size_t)g->n[0]) % (size_t)g->n[1];
    size_t k = node / ((size_t)g->n[0] * (size_t)g->n[1]);
    x[0] = g->origin[0] + g->h * (double)i;
    x[1] = g->origin[1] + g->h * (double)j;
    x[2] = g->dim == 3 ? g->origin[2] + g->h * (double)k : 0.0;
}

/* ---- points */
static void gk__mpm_points_free_arrays(gk_mpm_points *P) {
    int k;
    for (k = 0; k < 3; ++k) {
        gk_free(&P->alloc, P->x[k]);
        gk_free(&P->alloc, P->v[k]);
        gk_free(&P->alloc, P->fext[k]);
    }
    gk_free(&P->alloc, P->m);
    gk_free(&P->alloc, P->vol0);
    gk_free(&P->alloc, P->vol);
    gk_free(&P->alloc, P->lp);
    gk_free(&P->alloc, P->F);
    gk_free(&P->alloc, P->L);
    gk_free(&P->alloc, P->sigma);
    gk_free(&P->alloc, P->C);
}

GKDEF gk_result gk_mpm_points_create(gk_mpm_points *out, int dim, int n, const gk_allocator *alloc,
                                     gk_err *err) {
    gk_mpm_points P;
    int k, bad = 0, p;
    size_t nn = (size_t)(n > 0 ? n : 1);
    if (!out) return gk_err_set(err, GK_ERR_ARG, "NULL points");
    if (dim != 2 && dim != 3) return gk_err_set(err, GK_ERR_ARG, "dimension %d (must be 2 or 3)", dim);
    if (n < 0 || n > INT32_MAX / 9)
        return gk_err_set(err, GK_ERR_ARG, "%d points (must be 0..%d)", n, INT32_MAX / 9);
    memset(&P, 0, sizeof P);
    if (alloc) P.alloc = *alloc;
    P.dim = dim;
    P.n = n;
    for (k = 0; k < dim; ++k) {
        P.x[k] = (double *)gk_alloc(&P.alloc, nn * sizeof(double));
        P.v[k] = (double *)gk_alloc(&P.alloc, nn * sizeof(double));
        P.fext[k] = (double *)gk_alloc(&P.alloc, nn * sizeof(double));
        if (!P.x[k] || !P.v[k] || !P.fext[k]) bad = 1;
    }
    P.m = (double *)gk_alloc(&P.alloc, nn * sizeof(double));
    P.vol0 = (double *)gk_alloc(&P.alloc, nn * sizeof(double));
    P.vol = (double *)gk_alloc(&P.alloc, nn * sizeof(double));
    P.lp = (double *)gk_alloc(&P.alloc, nn * sizeof(double));
    P.F = (double *)gk_alloc(&P.alloc, 9 * nn * sizeof(double));
    P.L = (double *)gk_alloc(&P.alloc, 9 * nn * sizeof(double));
    P.sigma = (double *)gk_alloc(&P.alloc, 9 * nn * sizeof(double));
    P.C = (double *)gk_alloc(&P.alloc, 9 * nn * sizeof(double));
    if (bad || !P.m || !P.vol0 || !P.vol || !P.lp || !P.F || !P.L || !P.sigma || !P.C) {
        gk__mpm_points_free_arrays(&P);
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for %d material points", n);
    }
    for (k = 0; k < dim; ++k) {
        memset(P.x[k], 0, nn * sizeof(double));
        memset(P.v[k], 0, nn * sizeof(double));
        memset(P.fext[k], 0, nn * sizeof(double));
    }
    memset(P.m, 0, nn * sizeof(double));
    memset(P.vol0, 0, nn * sizeof(double));
    memset(P.vol, 0, nn * sizeof(double));
    memset(P.lp, 0, nn * sizeof(double));
    memset(P.L, 0, 9 * nn * sizeof(double));
    memset(P.sigma, 0, 9 * nn * sizeof(double));
    memset(P.C, 0, 9 * nn * sizeof(double));
    for (p = 0; p < n; ++p) gk_m3_identity(P.F + 9 * p);
    *out = P;
    return GK_OK;
}

GKDEF gk_result gk_mpm_points_create_box(gk_mpm_points *pts, int dim, const double lo[3], const double hi[3],
                                         double h, int ppd, double rho, const gk_allocator *alloc,
                                         gk_err *err) {
    int nc[3] = {1, 1, 1}, k, i, j, l, p = 0, ns[3];
    long total = 1;
    double d, v0;
    gk_result r;
    if (dim != 2 && dim != 3) return gk_err_set(err, GK_ERR_ARG, "dimension %d (must be 2 or 3)", dim);
    if (!isfinite(h) || !isfinite(rho)) return gk_err_set(err, GK_ERR_NAN, "spacing or density is NaN");
    if (!(h > 0.0)) return gk_err_set(err, GK_ERR_ARG, "spacing h = %g (must be > 0)", h);
    if (!(rho > 0.0)) return gk_err_set(err, GK_ERR_MASS, "density %g (must be > 0)", rho);
    if (ppd < 1 || ppd > 16)
        return gk_err_set(err, GK_ERR_ARG, "%d points per cell edge (must be 1..16)", ppd);
    for (k = 0; k < dim; ++k) {
        double c;
        if (!isfinite(lo[k]) || !isfinite(hi[k])) return gk_err_set(err, GK_ERR_NAN, "box corner is NaN");
        c = (hi[k] - lo[k]) / h;
        nc[k] = (int)floor(c + 0.5);
        if (nc[k] < 1 || fabs(c - nc[k]) > 1e-9 * (c > 1.0 ? c : 1.0) || nc[k] > 1000000)
            return gk_err_set(err, GK_ERR_ARG,
                              "box edge %d of %g cells is not a positive whole number of cells", k, c);
        total *= (long)nc[k] * ppd;
        if (total > INT32_MAX / 9) return gk_err_set(err, GK_ERR_ARG, "box holds too many points");
    }
    r = gk_mpm_points_create(pts, dim, (int)total, alloc, err);
    if (r) return r;
    d = h / ppd;
    v0 = dim == 2 ? d * d : d * d * d;
    for (k = 0; k < 3; ++k) ns[k] = k < dim ? nc[k] * ppd : 1;
    for (l = 0; l < ns[2]; ++l)
        for (j = 0; j < ns[1]; ++j)
            for (i = 0; i < ns[0]; ++i, ++p) {
                pts->x[0][p] = lo[0] + (i + 0.5) * d;
                pts->x[1][p] = lo[1] + (j + 0.5) * d;
                if (dim == 3) pts->x[2][p] = lo[2] + (l + 0.5) * d;
                pts->vol0[p] = pts->vol[p] = v0;
                pts->m[p] = rho * v0;
                pts->lp[p] = 0.5 * d;
            }
    return GK_OK;
}

GKDEF void gk_mpm_points_destroy(gk_mpm_points *pts) {
    if (!pts) return;
    gk__mpm_points_free_arrays(pts);
    memset(pts, 0, sizeof *pts);
}

GKDEF void gk_mpm_points_totals(const gk_mpm_points *P, double *mass, double mom[3], double *kinetic) {
    double M = 0.0, mv[3] = {0.0, 0.0, 0.0}, ke = 0.0;
    int p, k;
    for (p = 0; p < P->n; ++p) {
        double v2 = 0.0;
        M += P->m[p];
        for (k = 0; k < P->dim; ++k) {
            mv[k] += P->m[p] * P->v[k][p];
            v2 += P->v[k][p] * P->v[k][p];
        }
        ke += 0.5 * P->m[p] * v2;
    }
    if (mass) *mass = M;
    if (mom)
        for (k = 0; k < 3; ++k) mom[k] = mv[k];
    if (kinetic) *kinetic = ke;
}

GKDEF gk_mpm_def gk_mpm_def_default(void) {
    gk_mpm_def d;
    memset(&d, 0, sizeof d);
    d.basis = GK_MPM_LINEAR;
    d.transfer = GK_MPM_PIC_FLIP;
    d.scheme = GK_MPM_USF;
    d.alpha = 0.1; /* Liang & Zhao 2019 */
    d.threads = 1;
    return d;
}

/* ---- shape functions: per-axis weights, tensor product in the loops */
typedef struct gk__mpm_w {
    int s, base[3];
    double w[3][4], dw[3][4]; /* dw in 1/m */
    double xi[3];             /* position in grid units */
} gk__mpm_w;

/* support margin in grid units (see the top comment) */
static double gk__mpm_margin(gk_mpm_basis b, double l) {
    return b == GK_MPM_LINEAR ? 0.0 : b == GK_MPM_UGIMP ? l : b == GK_MPM_QUADRATIC ? 0.5 : 1.0;
}

/* 0 if the point's support is inside the grid */
GK_FORCE_INLINE int gk__mpm_inside(const gk_mpm_grid *g, gk_mpm_basis b, const double x[3], double l) {
    double a = gk__mpm_margin(b, l);
    int k;
    for (k = 0; k < g->dim; ++k) {
        double xi = (x[k] - g->origin[k]) * g->inv_h;
        if (!(xi >= a && xi <= (double)(g->n[k] - 1) - a)) return 0;
    }
    return 1;
}

/* grad 0: the weights alone (W->dw not written) */
GK_FORCE_INLINE void gk__mpm_weights_b(const gk_mpm_grid *g, gk_mpm_basis basis, const double x[3], double l,
                                       int grad, gk__mpm_w *W) {
    int k, j, s = gk_mpm_basis_width(basis);
    W->s = s;
    for (k = 0; k < 3; ++k) {
        double xi, dN;
        int b;
        if (k >= g->dim) {
            W->base[k] = 0;
            W->xi[k] = 0.0;
            W->w[k][0] = 1.0;
            if (grad) W->dw[k][0] = 0.0;
            continue;
        }
        xi = (x[k] - g->origin[k]) * g->inv_h;
        W->xi[k] = xi;
        if (basis == GK_MPM_LINEAR)
            b = (int)floor(xi);
        else if (basis == GK_MPM_CUBIC)
            b = (int)floor(xi) - 1;
        else
            b = (int)floor(xi - 0.5);
        /* clamping only drops nodes of zero weight and slope (support inside) */
        if (b > g->n[k] - s) b = g->n[k] - s;
        if (b < 0) b = 0;
        W->base[k] = b;
        for (j = 0; j < s; ++j) {
            W->w[k][j] = gk__mpm_kernel(basis, xi - (double)(b + j), l, grad ? &dN : NULL);
            if (grad) W->dw[k][j] = dN * g->inv_h;
        }
    }
}

/* the loops above with the basis (and grad) constants after inlining: the same operations */
GK_FORCE_INLINE void gk__mpm_weights_d(const gk_mpm_grid *g, gk_mpm_basis basis, const double x[3], double l,
                                       int grad, gk__mpm_w *W) {
    switch (basis) {
    case GK_MPM_LINEAR: gk__mpm_weights_b(g, GK_MPM_LINEAR, x, l, grad, W); break;
    case GK_MPM_UGIMP: gk__mpm_weights_b(g, GK_MPM_UGIMP, x, l, grad, W); break;
    case GK_MPM_QUADRATIC: gk__mpm_weights_b(g, GK_MPM_QUADRATIC, x, l, grad, W); break;
    default: gk__mpm_weights_b(g, basis, x, l, grad, W); break;
    }
}

/* the weights and slopes of a point at x (l = lp/h) */
static void gk__mpm_weights(const gk_mpm_grid *g, gk_mpm_basis basis, const double x[3], double l,
                            gk__mpm_w *W) {
    gk__mpm_weights_d(g, basis, x, l, 1, W);
}

/* the same weights without the slopes (W->dw is not written) */
static void gk__mpm_weights_only(const gk_mpm_grid *g, gk_mpm_basis basis, const double x[3], double l,
                                 gk__mpm_w *W) {
    gk__mpm_weights_d(g, basis, x, l, 0, W);
}

/* one point's cached weights: valid for the bits of x and l and the basis they were made with */
struct gk__mpm_wc {
    uint64_t key[4]; /* bits of x[0], x[1], x[2], l */
    int basis;       /* -1: empty */
    gk__mpm_w W;
};

/* whether the cached weights of the grid were made with its present origin and spacing */
static int gk__mpm_wc_fresh(const gk_mpm_grid *g) {
    int k;
    if (!g->wc) return 0;
    for (k = 0; k < 3; ++k)
        if (memcmp(&g->wc_stamp[k], &g->origin[k], sizeof(double))) return 0;
    return !memcmp(&g->wc_stamp[3], &g->inv_h, sizeof(double));
}

/* room for n points' weights, stamped with the grid's origin and spacing; on
 * failure to allocate there is simply no cache (the weights are computed) */
static void gk__mpm_wc_prepare(gk_mpm_grid *g, int n) {
    int p, k, fresh = gk__mpm_wc_fresh(g);
    if (n > g->wc_cap) {
        struct gk__mpm_wc *w = (struct gk__mpm_wc *)gk_alloc(&g->alloc, (size_t)n * sizeof *w);
        gk_free(&g->alloc, g->wc);
        g->wc = w;
        g->wc_cap = w ? n : 0;
        fresh = 0;
    }
    if (!g->wc || fresh) return;
    for (p = 0; p < g->wc_cap; ++p) g->wc[p].basis = -1;
    for (k = 0; k < 3; ++k) g->wc_stamp[k] = g->origin[k];
    g->wc_stamp[3] = g->inv_h;
}

/* the weights of point p at x (l = lp/h): the cached ones when they were made
 * for the same bits of x and l and the same basis; else computed, and stored
 * when `store` (P2G: one writer per point) */
GK_FORCE_INLINE const gk__mpm_w *gk__mpm_wget(const gk_mpm_grid *g, int fresh, gk_mpm_basis basis,
                                              const double x[3], double l, int p, int store, gk__mpm_w *tmp) {
    if (fresh && p < g->wc_cap) {
        struct gk__mpm_wc *e = g->wc + p;
        uint64_t key[4];
        memcpy(key, x, 3 * sizeof(double));
        memcpy(key + 3, &l, sizeof(double));
        if (e->basis == (int)basis && e->key[0] == key[0] && e->key[1] == key[1] && e->key[2] == key[2] &&
            e->key[3] == key[3])
            return &e->W;
        if (store) {
            gk__mpm_weights(g, basis, x, l, &e->W);
            memcpy(e->key, key, sizeof key);
            e->basis = (int)basis;
            return &e->W;
        }
    }
    gk__mpm_weights(g, basis, x, l, tmp);
    return tmp;
}

/* what gk_mpm_shape takes: xx = x with the unused axes 0, *l = lp / h (err may be NULL) */
static gk_result gk__mpm_point_check(const gk_mpm_grid *g, gk_mpm_basis basis, const double x[3], double lp,
                                     double xx[3], double *l, gk_err *err) {
    int k;
    *l = lp * g->inv_h;
    if ((int)basis < 0 || (int)basis > (int)GK_MPM_CUBIC)
        return gk_err_set(err, GK_ERR_ARG, "unknown basis %d", (int)basis);
    for (k = 0; k < 3; ++k) xx[k] = k < g->dim ? x[k] : 0.0;
    for (k = 0; k < g->dim; ++k)
        if (!isfinite(xx[k])) return gk_err_set(err, GK_ERR_NAN, "point position is NaN or infinite");
    if (basis == GK_MPM_UGIMP && !(*l > 0.0 && *l <= 0.5))
        return gk_err_set(err, GK_ERR_ARG, "uGIMP half-size lp = %g (must be in (0, h/2], h = %g)", lp, g->h);
    if (!gk__mpm_inside(g, basis, xx, *l))
        return gk_err_set(err, GK_ERR_OUTSIDE, "point (%g, %g, %g): its support leaves the grid", xx[0],
                          xx[1], xx[2]);
    return GK_OK;
}

GKDEF int gk_mpm_support_inside(const gk_mpm_grid *g, gk_mpm_basis basis, const double x[3], double lp) {
    double xx[3], l;
    return gk__mpm_point_check(g, basis, x, lp, xx, &l, NULL) == GK_OK;
}

/* 2D, s nodes per axis (a constant after inlining): the loop below with the z
 * factor (weight 1, base 0) taken out, exact (x * 1 = x) */
GK_FORCE_INLINE int gk__mpm_stencil_2d(const gk_mpm_grid *g, const gk__mpm_w *W, int s, int32_t *node,
                                       double *w) {
    int a, b, q = 0;
    for (b = 0; b < s; ++b) {
        int32_t row = (int32_t)(W->base[0] + g->n[0] * (W->base[1] + b));
        for (a = 0; a < s; ++a, ++q) {
            node[q] = row + a;
            w[q] = W->w[0][a] * W->w[1][b];
        }
    }
    return q;
}

/* the nodes and weights of the stencil of W; returns their count */
static int gk__mpm_stencil_values(const gk_mpm_grid *g, const gk__mpm_w *W, int32_t *node, double *w) {
    int a, b, c, s = W->s, sz = g->dim == 3 ? W->s : 1, q = 0;
    if (g->dim == 2) {
        if (s == 3) return gk__mpm_stencil_2d(g, W, 3, node, w);
        if (s == 2) return gk__mpm_stencil_2d(g, W, 2, node, w);
        return gk__mpm_stencil_2d(g, W, 4, node, w);
    }
    for (c = 0; c < sz; ++c)
        for (b = 0; b < s; ++b)
            for (a = 0; a < s; ++a, ++q) {
                node[q] =
                    (int32_t)((W->base[0] + a) + g->n[0] * ((W->base[1] + b) + g->n[1] * (W->base[2] + c)));
                w[q] = W->w[0][a] * W->w[1][b] * W->w[2][c];
            }
    return q;
}

GKDEF gk_result gk_mpm_shape(const gk_mpm_grid *g, gk_mpm_basis basis, const double x[3], double lp,
                             gk_mpm_stencil *st, gk_err *err) {
    gk__mpm_w W;
    double xx[3], l;
    int a, b, c, s, sz, q = 0;
    gk_result r = gk__mpm_point_check(g, basis, x, lp, xx, &l, err);
    if (r) return r;
    gk__mpm_weights(g, basis, xx, l, &W);
    st->n = gk__mpm_stencil_values(g, &W, st->node, st->w);
    s = W.s;
    sz = g->dim == 3 ? s : 1;
    for (c = 0; c < sz; ++c)
        for (b = 0; b < s; ++b)
            for (a = 0; a < s; ++a, ++q) {
                st->dw[q][0] = W.dw[0][a] * W.w[1][b] * W.w[2][c];
                st->dw[q][1] = W.w[0][a] * W.dw[1][b] * W.w[2][c];
                st->dw[q][2] = W.w[0][a] * W.w[1][b] * W.dw[2][c];
            }
    return GK_OK;
}

GKDEF gk_result gk_mpm_shape_values(const gk_mpm_grid *g, gk_mpm_basis basis, const double x[3], double lp,
                                    int *n, int32_t *node, double *w, gk_err *err) {
    gk__mpm_w W;
    double xx[3], l;
    gk_result r;
    if (!n || !node || !w) return gk_err_set(err, GK_ERR_ARG, "NULL stencil arrays");
    r = gk__mpm_point_check(g, basis, x, lp, xx, &l, err);
    if (r) return r;
    gk__mpm_weights_only(g, basis, xx, l, &W);
    *n = gk__mpm_stencil_values(g, &W, node, w);
    return GK_OK;
}

static int gk__mpm_nthreads(const gk_mpm_def *d) {
#ifdef _OPENMP
    return d->threads > 1 ? d->threads : 1;
#else
    (void)d;
    return 1;
#endif
}

static gk_result gk__mpm_check_bodies(const gk_mpm_grid *g, gk_err *err) {
    int bi, k;
    if (g->nbody < 0 || (g->nbody > 0 && !g->body))
        return gk_err_set(err, GK_ERR_ARG, "%d rigid bodies with body array %p", g->nbody,
                          (const void *)g->body);
    for (bi = 0; bi < g->nbody; ++bi) {
        const gk_mpm_body *B = &g->body[bi];
        for (k = 0; k < g->dim; ++k)
            if (!isfinite(B->lo[k]) || !isfinite(B->hi[k]) || !isfinite(B->v[k]) || !isfinite(B->mu))
                return gk_err_set(err, GK_ERR_NAN, "rigid body %d has a NaN or infinite entry", bi);
        if ((int)B->contact < 0 || (int)B->contact > (int)GK_MPM_CONTACT_SMOOTH)
            return gk_err_set(err, GK_ERR_ARG, "rigid body %d: unknown contact kind %d", bi, (int)B->contact);
        if ((int)B->shape < 0 || (int)B->shape > (int)GK_MPM_CIRCLE)
            return gk_err_set(err, GK_ERR_ARG, "rigid body %d: unknown shape %d (0 box, 1 circle)", bi,
                              (int)B->shape);
        if (B->shape == GK_MPM_CIRCLE) {
            if (!isfinite(B->centre[0]) || !isfinite(B->centre[1]) || !isfinite(B->radius))
                return gk_err_set(err, GK_ERR_NAN, "rigid body %d: circle centre or radius NaN or infinite",
                                  bi);
            if (!(B->radius > 0.0))
                return gk_err_set(err, GK_ERR_ARG, "rigid body %d: circle radius %g <= 0", bi, B->radius);
            if (B->face != 0)
                return gk_err_set(err, GK_ERR_ARG,
                                  "rigid body %d: face %d given for a circle (its normal is radial: face 0)",
                                  bi, B->face);
        }
        if (B->mu < 0.0)
            return gk_err_set(err, GK_ERR_ARG, "rigid body %d: friction coefficient %g < 0", bi, B->mu);
        if (B->face < 0 || B->face > 2 * g->dim)
            return gk_err_set(err, GK_ERR_ARG, "rigid body %d: face %d (0 = nearest, 1..%d)", bi, B->face,
                              2 * g->dim);
    }
    return GK_OK;
}

static gk_result gk__mpm_check_def(const gk_mpm_def *d, gk_err *err) {
    int k;
    if (!d) return gk_err_set(err, GK_ERR_ARG, "NULL gk_mpm_def");
    if ((int)d->basis < 0 || (int)d->basis > (int)GK_MPM_CUBIC)
        return gk_err_set(err, GK_ERR_ARG, "unknown basis %d", (int)d->basis);
    if ((int)d->transfer < 0 || (int)d->transfer > (int)GK_MPM_APIC)
        return gk_err_set(err, GK_ERR_ARG, "unknown transfer %d", (int)d->transfer);
    if ((int)d->scheme < 0 || (int)d->scheme > (int)GK_MPM_MUSL)
        return gk_err_set(err, GK_ERR_ARG, "unknown scheme %d", (int)d->scheme);
    if (!(d->alpha >= 0.0 && d->alpha <= 1.0))
        return gk_err_set(err, GK_ERR_ARG, "PIC fraction alpha = %g (must be in [0, 1])", d->alpha);
    if (!(d->damping >= 0.0 && d->damping < 1.0))
        return gk_err_set(err, GK_ERR_ARG, "grid damping %g (must be in [0, 1))", d->damping);
    for (k = 0; k < 3; ++k)
        if (!isfinite(d->gravity[k])) return gk_err_set(err, GK_ERR_NAN, "gravity[%d] is NaN or infinite", k);
    if (!isfinite(d->mass_min)) return gk_err_set(err, GK_ERR_NAN, "mass threshold is NaN");
    return GK_OK;
}

/* Validate every point (nothing written on failure), then counting-sort the
 * points into colour-major blocks (stable: ascending index inside a block). */
static gk_result gk__mpm_bin(gk_mpm_grid *g, const gk_mpm_points *P, const gk_mpm_def *d, int what,
                             double *mmin, gk_err *err) {
    int n = P->n, p, k, s;
    double mlow = HUGE_VAL;
    if (P->dim != g->dim) return gk_err_set(err, GK_ERR_ARG, "points are %dD, grid is %dD", P->dim, g->dim);
    for (p = 0; p < n; ++p) {
        double x[3] = {0.0, 0.0, 0.0}, l = d->basis == GK_MPM_UGIMP ? P->lp[p] * g->inv_h : 0.0;
        for (k = 0; k < g->dim; ++k) {
            x[k] = P->x[k][p];
            if (!isfinite(x[k]) || !isfinite(P->v[k][p]))
                return gk_err_set(err, GK_ERR_NAN, "point %d: position or velocity is NaN or infinite", p);
        }
        if (!(P->m[p] > 0.0) || !isfinite(P->m[p]))
            return gk_err_set(err, GK_ERR_MASS, "point %d: mass %g (must be > 0)", p, P->m[p]);
        if (d->basis == GK_MPM_UGIMP && !(l > 0.0 && l <= 0.5))
            return gk_err_set(err, GK_ERR_ARG,
                              "point %d: uGIMP half-size lp = %g (must be in (0, h/2], h = %g)", p, P->lp[p],
                              g->h);
        if (!gk__mpm_inside(g, d->basis, x, l))
            return gk_err_set(err, GK_ERR_OUTSIDE, "point %d at (%g, %g, %g): its support leaves the grid", p,
                              x[0], x[1], x[2]);
        if (d->transfer == GK_MPM_APIC && !gk_m3_isfinite(P->C + 9 * p))
            return gk_err_set(err, GK_ERR_NAN, "point %d: APIC matrix C has a NaN", p);
        if (what & GK_MPM_P2G_FORCE) {
            if (!(P->vol[p] > 0.0) || !isfinite(P->vol[p]))
                return gk_err_set(err, GK_ERR_ARG, "point %d: volume %g (must be > 0)", p, P->vol[p]);
            if (!gk_m3_isfinite(P->sigma + 9 * p))
                return gk_err_set(err, GK_ERR_NAN, "point %d: stress has a NaN or infinite entry", p);
            for (k = 0; k < g->dim; ++k)
                if (!isfinite(P->fext[k][p]))
                    return gk_err_set(err, GK_ERR_NAN, "point %d: external force is NaN or infinite", p);
        }
        if (P->m[p] < mlow) mlow = P->m[p];
    }
    if (n > g->cap) {
        int32_t *o = (int32_t *)gk_alloc(&g->alloc, (size_t)n * sizeof(int32_t));
        int32_t *b = (int32_t *)gk_alloc(&g->alloc, (size_t)n * sizeof(int32_t));
        if (!o || !b) {
            gk_free(&g->alloc, o);
            gk_free(&g->alloc, b);
            return gk_err_set(err, GK_ERR_ALLOC, "out of memory sorting %d points", n);
        }
        gk_free(&g->alloc, g->order);
        gk_free(&g->alloc, g->bid);
        g->order = o;
        g->bid = b;
        g->cap = n;
    }
    for (s = 0; s <= g->nblock; ++s) g->bstart[s] = 0;
    for (p = 0; p < n; ++p) {
        int bc[3] = {0, 0, 0}, blk;
        for (k = 0; k < g->dim; ++k) {
            int c = (int)floor((P->x[k][p] - g->origin[k]) * g->inv_h);
            if (c > g->n[k] - 2) c = g->n[k] - 2;
            if (c < 0) c = 0;
            bc[k] = c / GK_MPM_BLOCK;
        }
        blk = bc[0] + g->nb[0] * (bc[1] + g->nb[1] * bc[2]);
        g->bid[p] = g->slot[blk];
        ++g->bstart[g->bid[p] + 1];
    }
    for (s = 0; s < g->nblock; ++s) g->bstart[s + 1] += g->bstart[s];
    for (p = 0; p < n; ++p) g->order[g->bstart[g->bid[p]]++] = p;
    for (s = g->nblock; s > 0; --s) g->bstart[s] = g->bstart[s - 1];
    g->bstart[0] = 0;
    *mmin = d->mass_min > 0.0 ? d->mass_min : (n > 0 ? 1e-14 * mlow : 0.0);
    gk__mpm_wc_prepare(g, n);
    return GK_OK;
}

/* scatter one point of a 2D grid, s nodes per axis (a constant after inlining): the
 * operations of the general loop below with the z factors (weight 1, slope 0) taken
 * out where that is exact (x * 1 = x; the z slope term S_k2 (w 0) is the same
 * signed zero for every node, since w >= +0) */
GK_FORCE_INLINE void gk__mpm_p2g_2d(gk_mpm_grid *g, const gk__mpm_w *W, int s, int what, int apic, double mp,
                                    const double vp[3], const double fp[3], const double Cm[9],
                                    const double S[9]) {
    const double *w0 = W->w[0], *w1 = W->w[1], *dw0 = W->dw[0], *dw1 = W->dw[1];
    double *gm = g->m, *p0 = g->p[0], *p1 = g->p[1];
    double *fi0 = g->fint[0], *fi1 = g->fint[1], *fe0 = g->fext[0], *fe1 = g->fext[1];
    double mom0 = mp * vp[0], mom1 = mp * vp[1], h = g->h, dz = W->dw[2][0];
    double z0 = S[2] * (0.0 * dz), z1 = S[5] * (0.0 * dz);
    int a, b, n0 = g->n[0];
    for (b = 0; b < s; ++b) {
        size_t row = (size_t)W->base[0] + (size_t)n0 * (size_t)(W->base[1] + b);
        for (a = 0; a < s; ++a) {
            size_t I = row + (size_t)a;
            double w = w0[a] * w1[b];
            if (what & GK_MPM_P2G_MOMENTUM) {
                double m0 = mom0, m1 = mom1;
                if (apic) {
                    double dx0 = h * ((double)(W->base[0] + a) - W->xi[0]);
                    double dx1 = h * ((double)(W->base[1] + b) - W->xi[1]);
                    m0 += Cm[0] * dx0 + Cm[1] * dx1 + Cm[2] * 0.0;
                    m1 += Cm[3] * dx0 + Cm[4] * dx1 + Cm[5] * 0.0;
                }
                gm[I] += w * mp;
                p0[I] += w * m0;
                p1[I] += w * m1;
            }
            if (what & GK_MPM_P2G_FORCE) {
                double gr0 = dw0[a] * w1[b], gr1 = w0[a] * dw1[b];
                fi0[I] -= S[0] * gr0 + S[1] * gr1 + z0;
                fi1[I] -= S[3] * gr0 + S[4] * gr1 + z1;
                fe0[I] += w * fp[0];
                fe1[I] += w * fp[1];
            }
        }
    }
}

/* scatter one point */
static void gk__mpm_p2g_point(gk_mpm_grid *g, const gk_mpm_points *P, const gk_mpm_def *d, int p, int what) {
    gk__mpm_w Wt;
    const gk__mpm_w *W;
    double x[3] = {0.0, 0.0, 0.0}, vp[3] = {0.0, 0.0, 0.0}, fp[3] = {0.0, 0.0, 0.0}, Cm[9], S[9];
    double mp = P->m[p], Vp = P->vol[p], l = d->basis == GK_MPM_UGIMP ? P->lp[p] * g->inv_h : 0.0;
    int a, b, c, k, s, sz, dim = g->dim, apic = d->transfer == GK_MPM_APIC;
    for (k = 0; k < dim; ++k) {
        x[k] = P->x[k][p];
        vp[k] = P->v[k][p];
        fp[k] = mp * d->gravity[k] + P->fext[k][p];
    }
    if (apic)
        for (k = 0; k < 9; ++k) Cm[k] = mp * P->C[9 * p + k];
    else
        for (k = 0; k < 9; ++k) Cm[k] = 0.0;
    if (what & GK_MPM_P2G_FORCE)
        for (k = 0; k < 9; ++k) S[k] = Vp * P->sigma[9 * p + k];
    else
        for (k = 0; k < 9; ++k) S[k] = 0.0;
    W = gk__mpm_wget(g, g->wc != NULL, d->basis, x, l, p, 1, &Wt);
    s = W->s;
    if (dim == 2 && s == 3) { /* uGIMP and quadratic: the flags as constants */
        if (what == GK_MPM_P2G_MOMENTUM && !apic)
            gk__mpm_p2g_2d(g, W, 3, GK_MPM_P2G_MOMENTUM, 0, mp, vp, fp, Cm, S);
        else if (what == GK_MPM_P2G_MOMENTUM)
            gk__mpm_p2g_2d(g, W, 3, GK_MPM_P2G_MOMENTUM, 1, mp, vp, fp, Cm, S);
        else if (what == GK_MPM_P2G_FORCE)
            gk__mpm_p2g_2d(g, W, 3, GK_MPM_P2G_FORCE, apic, mp, vp, fp, Cm, S);
        else
            gk__mpm_p2g_2d(g, W, 3, what, apic, mp, vp, fp, Cm, S);
        return;
    }
    if (dim == 2) {
        gk__mpm_p2g_2d(g, W, s == 2 ? 2 : 4, what, apic, mp, vp, fp, Cm, S);
        return;
    }
    sz = dim == 3 ? s : 1;
    for (c = 0; c < sz; ++c)
        for (b = 0; b < s; ++b)
            for (a = 0; a < s; ++a) {
                size_t I =
                    (size_t)(W->base[0] + a) +
                    (size_t)g->n[0] * ((size_t)(W->base[1] + b) + (size_t)g->n[1] * (size_t)(W->base[2] + c));
                double wyz = W->w[1][b] * W->w[2][c], w = W->w[0][a] * wyz, gr[3];
                if (what & GK_MPM_P2G_MOMENTUM) {
                    double dx[3];
                    dx[0] = g->h * ((double)(W->base[0] + a) - W->xi[0]);
                    dx[1] = g->h * ((double)(W->base[1] + b) - W->xi[1]);
                    dx[2] = dim == 3 ? g->h * ((double)(W->base[2] + c) - W->xi[2]) : 0.0;
                    g->m[I] += w * mp;
                    for (k = 0; k < dim; ++k) {
                        double mom = mp * vp[k];
                        if (apic) mom += Cm[3 * k] * dx[0] + Cm[3 * k + 1] * dx[1] + Cm[3 * k + 2] * dx[2];
                        g->p[k][I] += w * mom;
                    }
                }
                if (what & GK_MPM_P2G_FORCE) {
                    gr[0] = W->dw[0][a] * wyz;
                    gr[1] = W->w[0][a] * W->dw[1][b] * W->w[2][c];
                    gr[2] = W->w[0][a] * W->w[1][b] * W->dw[2][c];
                    for (k = 0; k < dim; ++k) {
                        g->fint[k][I] -= S[3 * k] * gr[0] + S[3 * k + 1] * gr[1] + S[3 * k + 2] * gr[2];
                        g->fext[k][I] += w * fp[k];
                    }
                }
            }
}

/* ---- boundary conditions on one node velocity u (length 3, u[2] = 0 in 2D) */
/* wall with unit normal nrm pointing into the material: remove the approaching
 * normal velocity, reduce the tangential speed by mu times that (Coulomb) */
GK_INLINE void gk__mpm_wall(double u[3], const double nrm[3], double mu, int frictional) {
    double un = u[0] * nrm[0] + u[1] * nrm[1] + u[2] * nrm[2], t2, ut;
    int k;
    if (un >= 0.0) return; /* separating */
    for (k = 0; k < 3; ++k) u[k] -= un * nrm[k];
    if (!frictional) return;
    t2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
    ut = sqrt(t2);
    if (ut <= -mu * un) {
        u[0] = u[1] = u[2] = 0.0;
    } else {
        double f = 1.0 - (-mu * un) / ut;
        for (k = 0; k < 3; ++k) u[k] *= f;
    }
}

/* velocity the node would have had without grid damping (reactions measure
 * the undamped load: damping must not leak into a footing force) */
static void gk__mpm_undamped(const gk_mpm_grid *g, size_t I, double dt, double damp, double u0[3]) {
    int k;
    if (!(damp > 0.0)) return;
    for (k = 0; k < g->dim; ++k) {
        double f = g->fint[k][I] + g->fext[k][I], vk = g->v[k][I];
        if (vk != 0.0) u0[k] += dt * damp * fabs(f) * (vk > 0.0 ? 1.0 : -1.0) / g->m[I];
    }
}

/* apply faces and bodies to velocity arrays vel; with dt > 0 record reactions */
static void gk__mpm_apply_bc(gk_mpm_grid *g, double *vel[3], double dt, double damp) {
    int f, bi, k, dim = g->dim, i, j, l, lo[3], hi[3];
    for (f = 0; f < 2 * dim; ++f) {
        gk_mpm_face *F = &g->face[f];
        int ax = f / 2, side = f % 2;
        double nrm[3] = {0.0, 0.0, 0.0};
        if (dt > 0.0) F->force[0] = F->force[1] = F->force[2] = 0.0;
        if (F->kind == GK_MPM_BC_FREE) continue;
        nrm[ax] = side ? -1.0 : 1.0;
        for (k = 0; k < 3; ++k) {
            lo[k] = 0;
            hi[k] = g->n[k] - 1;
        }
        if (side)
            lo[ax] = g->n[ax] - F->layers;
        else
            hi[ax] = F->layers - 1;
        for (l = lo[2]; l <= hi[2]; ++l)
            for (j = lo[1]; j <= hi[1]; ++j)
                for (i = lo[0]; i <= hi[0]; ++i) {
                    size_t I = (size_t)i + (size_t)g->n[0] * ((size_t)j + (size_t)g->n[1] * (size_t)l);
                    double u[3], u0[3];
                    if (!(g->m[I] > g->mass_min)) continue;
                    for (k = 0; k < 3; ++k) u[k] = u0[k] = k < dim ? vel[k][I] : 0.0;
                    if (dt > 0.0) gk__mpm_undamped(g, I, dt, damp, u0);
                    if (F->kind == GK_MPM_BC_FIXED)
                        u[0] = u[1] = u[2] = 0.0;
                    else if (F->kind == GK_MPM_BC_ROLLER)
                        u[ax] = 0.0;
                    else
                        gk__mpm_wall(u, nrm, F->mu, 1);
                    for (k = 0; k < dim; ++k) {
                        vel[k][I] = u[k];
                        if (dt > 0.0) F->force[k] += g->m[I] * (u[k] - u0[k]) / dt;
                    }
                }
    }
    for (bi = 0; bi < g->nbody; ++bi) {
        gk_mpm_body *B = &g->body[bi];
        if (dt > 0.0) B->force[0] = B->force[1] = B->force[2] = 0.0;
        gk_mpm_body_nodes(g, B, lo, hi);
        for (l = lo[2]; l <= hi[2]; ++l)
            for (j = lo[1]; j <= hi[1]; ++j)
                for (i = lo[0]; i <= hi[0]; ++i) {
                    size_t I = (size_t)i + (size_t)g->n[0] * ((size_t)j + (size_t)g->n[1] * (size_t)l);
                    double u[3], u0[3], vb[3], xI[3];
                    if (!(g->m[I] > g->mass_min)) continue;
                    if (B->shape == GK_MPM_CIRCLE) {
                        gk_mpm_grid_node_position(g, I, xI);
                        if (!gk_mpm_body_covers(g, B, xI)) continue;
                    }
                    for (k = 0; k < 3; ++k) {
                        u0[k] = k < dim ? vel[k][I] : 0.0;
                        vb[k] = k < dim ? B->v[k] : 0.0;
                    }
                    if (B->contact == GK_MPM_CONTACT_STICK) {
                        for (k = 0; k < 3; ++k) u[k] = vb[k];
                        if (dt > 0.0) gk__mpm_undamped(g, I, dt, damp, u0);
                    } else {
                        double nrm[3] = {0.0, 0.0, 0.0};
                        int fc = B->face - 1;
                        if (B->shape == GK_MPM_CIRCLE) { /* radial, outward from the centre */
                            double dx = xI[0] - B->centre[0], dy = xI[1] - B->centre[1],
                                   r = sqrt(dx * dx + dy * dy);
                            if (r > 0.0)
                                nrm[0] = dx / r, nrm[1] = dy / r;
                            else
                                nrm[1] = -1.0;
                        } else if (fc < 0 || fc >= 2 * dim) { /* nearest face of the box */
                            double best = HUGE_VAL;
                            int q;
                            gk_mpm_grid_node_position(g, I, xI);
                            fc = 0;
                            for (q = 0; q < 2 * dim; ++q) {
                                double dd = (q & 1) ? B->hi[q / 2] - xI[q / 2] : xI[q / 2] - B->lo[q / 2];
                                if (dd < best) {
                                    best = dd;
                                    fc = q;
                                }
                            }
                        }
                        if (B->shape != GK_MPM_CIRCLE)
                            nrm[fc / 2] = (fc & 1) ? 1.0 : -1.0; /* outward from the body into the material */
                        for (k = 0; k < 3; ++k) u[k] = u0[k] - vb[k];
                        gk__mpm_wall(u, nrm, B->mu, B->contact == GK_MPM_CONTACT_FRICTION);
                        for (k = 0; k < 3; ++k) u[k] += vb[k];
                        if (dt > 0.0) gk__mpm_undamped(g, I, dt, damp, u0);
                    }
                    for (k = 0; k < dim; ++k) {
                        vel[k][I] = u[k];
                        if (dt > 0.0) B->force[k] += g->m[I] * (u[k] - u0[k]) / dt;
                    }
                }
    }
}

GKDEF gk_result gk_mpm_p2g(gk_mpm_grid *g, const gk_mpm_points *P, const gk_mpm_def *d, int what,
                           gk_err *err) {
    gk_result r;
    double mmin = 0.0;
    long nn = (long)g->nnode, I;
    int nth, c, k, dim = g->dim;
    if (!P) return gk_err_set(err, GK_ERR_ARG, "NULL points");
    r = gk__mpm_check_def(d, err);
    if (r) return r;
    if (what < 1 || what > 3)
        return gk_err_set(err, GK_ERR_ARG, "P2G flags %d (MOMENTUM and/or FORCE)", what);
    r = gk__mpm_check_bodies(g, err);
    if (r) return r;
    r = gk__mpm_bin(g, P, d, what, &mmin, err);
    if (r) return r;
    nth = gk__mpm_nthreads(d);
    (void)nth; /* unused without OpenMP */
    if (what & GK_MPM_P2G_MOMENTUM) {
        g->mass_min = mmin;
        memset(g->m, 0, g->nnode * sizeof(double));
        for (k = 0; k < dim; ++k) memset(g->p[k], 0, g->nnode * sizeof(double));
    }
    if (what & GK_MPM_P2G_FORCE)
        for (k = 0; k < dim; ++k) {
            memset(g->fint[k], 0, g->nnode * sizeof(double));
            memset(g->fext[k], 0, g->nnode * sizeof(double));
        }
    for (c = 0; c < (1 << dim); ++c) {
        int s0 = g->colour_start[c], s1 = g->colour_start[c + 1], s;
        /* same-colour blocks touch disjoint nodes: no atomics, order-free */
        GK_OMP(parallel for num_threads(nth) schedule(dynamic, 1) if (nth > 1))
        for (s = s0; s < s1; ++s) {
            int q;
            for (q = g->bstart[s]; q < g->bstart[s + 1]; ++q) gk__mpm_p2g_point(g, P, d, g->order[q], what);
        }
    }
    if (what & GK_MPM_P2G_MOMENTUM) {
        GK_OMP(parallel for num_threads(nth) schedule(static) if (nth > 1))
        for (I = 0; I < nn; ++I) {
            int q;
            double m = g->m[I];
            for (q = 0; q < dim; ++q) g->v[q][I] = m > mmin ? g->p[q][I] / m : 0.0;
        }
        gk__mpm_apply_bc(g, g->v, 0.0, 0.0);
        /* the constrained velocity is the grid state: p = m v */
        GK_OMP(parallel for num_threads(nth) schedule(static) if (nth > 1))
        for (I = 0; I < nn; ++I) {
            int q;
            for (q = 0; q < dim; ++q) g->p[q][I] = g->m[I] > mmin ? g->m[I] * g->v[q][I] : 0.0;
        }
    }
    return GK_OK;
}

GKDEF gk_result gk_mpm_grid_update(gk_mpm_grid *g, const gk_mpm_def *d, double dt, gk_err *err) {
    gk_result r = gk__mpm_check_def(d, err);
    long nn = (long)g->nnode, I;
    int nth, dim = g->dim, bad = 0;
    double damp, mmin = g->mass_min;
    if (r) return r;
    if (!isfinite(dt)) return gk_err_set(err, GK_ERR_NAN, "time step is NaN or infinite");
    if (!(dt > 0.0)) return gk_err_set(err, GK_ERR_DT, "time step %g (must be > 0)", dt);
    r = gk__mpm_check_bodies(g, err);
    if (r) return r;
    nth = gk__mpm_nthreads(d);
    (void)nth; /* unused without OpenMP */
    damp = d->damping;
    GK_OMP(parallel for num_threads(nth) schedule(static) reduction(| : bad) if (nth > 1))
    for (I = 0; I < nn; ++I) {
        int q;
        double m = g->m[I];
        for (q = 0; q < dim; ++q) {
            double f = g->fint[q][I] + g->fext[q][I], u;
            if (!(m > mmin)) {
                g->vn[q][I] = 0.0;
                continue;
            }
            if (damp > 0.0 && g->v[q][I] != 0.0) f -= damp * fabs(f) * (g->v[q][I] > 0.0 ? 1.0 : -1.0);
            u = (g->p[q][I] + dt * f) / m;
            if (!isfinite(u)) bad |= 1;
            g->vn[q][I] = u;
        }
    }
    gk__mpm_apply_bc(g, g->vn, dt, damp);
    if (bad) return gk_err_set(err, GK_ERR_DIVERGED, "a node velocity became NaN or infinite");
    return GK_OK;
}

/* what one point gathers from the grid */
typedef struct gk__mpm_gath {
    double vpic[3], dv[3]; /* sum N vn, sum N (vn - v) */
    double Bm[9];          /* APIC: sum N vn (x) dx (B-splines) or sum vn (x) grad N */
    double Lg[9];          /* sum vg (x) grad N */
} gk__mpm_gath;

/* 2D gather, s nodes per axis (a constant after inlining): the operations of the
 * general loop with the z factors (weight 1) taken out, exact (x * 1 = x) */
GK_FORCE_INLINE void gk__mpm_gather_2d(const gk_mpm_grid *g, const gk__mpm_w *W, int s, int vel, int grad,
                                       double *const *vg, int apic_b, int apic_g, gk__mpm_gath *o) {
    const double *w0 = W->w[0], *w1 = W->w[1], *dw0 = W->dw[0], *dw1 = W->dw[1];
    const double *vn0 = g->vn[0], *vn1 = g->vn[1], *v0 = g->v[0], *v1 = g->v[1], *g0 = vg[0], *g1 = vg[1];
    double h = g->h;
    int a, b, n0 = g->n[0];
    for (b = 0; b < s; ++b) {
        size_t row = (size_t)W->base[0] + (size_t)n0 * (size_t)(W->base[1] + b);
        for (a = 0; a < s; ++a) {
            size_t I = row + (size_t)a;
            double gr0 = dw0[a] * w1[b], gr1 = w0[a] * dw1[b];
            if (vel) {
                double w = w0[a] * w1[b], un0 = vn0[I], un1 = vn1[I];
                o->vpic[0] += w * un0;
                o->vpic[1] += w * un1;
                o->dv[0] += w * (un0 - v0[I]);
                o->dv[1] += w * (un1 - v1[I]);
                if (apic_b) {
                    double dx0 = h * ((double)(W->base[0] + a) - W->xi[0]);
                    double dx1 = h * ((double)(W->base[1] + b) - W->xi[1]);
                    o->Bm[0] += w * un0 * dx0;
                    o->Bm[1] += w * un0 * dx1;
                    o->Bm[3] += w * un1 * dx0;
                    o->Bm[4] += w * un1 * dx1;
                }
                if (apic_g) {
                    o->Bm[0] += un0 * gr0;
                    o->Bm[1] += un0 * gr1;
                    o->Bm[3] += un1 * gr0;
                    o->Bm[4] += un1 * gr1;
                }
            }
            if (grad) {
                double u0 = g0[I], u1 = g1[I];
                o->Lg[0] += u0 * gr0;
                o->Lg[1] += u0 * gr1;
                o->Lg[3] += u1 * gr0;
                o->Lg[4] += u1 * gr1;
            }
        }
    }
}

/* the velocity (vel) and/or gradient (grad) sums of one point, o zeroed by the caller */
static void gk__mpm_gather(const gk_mpm_grid *g, const gk__mpm_w *W, int vel, int grad, double *const *vg,
                           int apic_b, int apic_g, gk__mpm_gath *o) {
    int a, b, c, k, q, s = W->s, sz, dim = g->dim;
    if (dim == 2 && s == 3 && !apic_b && !apic_g) { /* uGIMP and quadratic, PIC/FLIP: constant flags */
        if (vel && !grad)
            gk__mpm_gather_2d(g, W, 3, 1, 0, vg, 0, 0, o);
        else if (grad && !vel)
            gk__mpm_gather_2d(g, W, 3, 0, 1, vg, 0, 0, o);
        else
            gk__mpm_gather_2d(g, W, 3, vel, grad, vg, 0, 0, o);
        return;
    }
    if (dim == 2) {
        gk__mpm_gather_2d(g, W, s, vel, grad, vg, apic_b, apic_g, o);
        return;
    }
    sz = dim == 3 ? s : 1;
    for (c = 0; c < sz; ++c)
        for (b = 0; b < s; ++b)
            for (a = 0; a < s; ++a) {
                size_t I =
                    (size_t)(W->base[0] + a) +
                    (size_t)g->n[0] * ((size_t)(W->base[1] + b) + (size_t)g->n[1] * (size_t)(W->base[2] + c));
                double wyz = W->w[1][b] * W->w[2][c], w = W->w[0][a] * wyz, gr[3], dx[3];
                gr[0] = W->dw[0][a] * wyz;
                gr[1] = W->w[0][a] * W->dw[1][b] * W->w[2][c];
                gr[2] = W->w[0][a] * W->w[1][b] * W->dw[2][c];
                dx[0] = g->h * ((double)(W->base[0] + a) - W->xi[0]);
                dx[1] = g->h * ((double)(W->base[1] + b) - W->xi[1]);
                dx[2] = dim == 3 ? g->h * ((double)(W->base[2] + c) - W->xi[2]) : 0.0;
                for (k = 0; k < dim; ++k) {
                    double un = g->vn[k][I];
                    if (vel) {
                        o->vpic[k] += w * un;
                        o->dv[k] += w * (un - g->v[k][I]);
                        if (apic_b)
                            for (q = 0; q < dim; ++q) o->Bm[3 * k + q] += w * un * dx[q];
                        if (apic_g)
                            for (q = 0; q < dim; ++q) o->Bm[3 * k + q] += un * gr[q];
                    }
                    if (grad)
                        for (q = 0; q < dim; ++q) o->Lg[3 * k + q] += vg[k][I] * gr[q];
                }
            }
}

/* F_new = (I + dt L) F (2D: the plane block), returns det F_new */
GK_FORCE_INLINE double gk__mpm_f_update_dim(int dim, double dt, const double Lg[9], const double F[9],
                                            double Fn[9]) {
    double E[9];
    int k;
    for (k = 0; k < 9; ++k) E[k] = dt * Lg[k] + 0.0;
    E[0] = dt * Lg[0] + 1.0;
    E[4] = dt * Lg[4] + 1.0;
    E[8] = dim == 2 ? 1.0 : dt * Lg[8] + 1.0;
    gk_m3_mul(E, F, Fn);
    if (dim == 2) {
        Fn[2] = Fn[5] = Fn[6] = Fn[7] = 0.0;
        Fn[8] = 1.0;
    }
    return gk_m3_det(Fn);
}

/* the same with the dimension a constant (the same operations) */
GK_FORCE_INLINE double gk__mpm_f_update(int dim, double dt, const double Lg[9], const double F[9],
                                        double Fn[9]) {
    if (dim == 2) return gk__mpm_f_update_dim(2, dt, Lg, F, Fn);
    return gk__mpm_f_update_dim(3, dt, Lg, F, Fn);
}

#define GK__MPM_SCR 19 /* scratch per point between the G2P passes: L, F_new, det F_new */

/* the gradient update of point p kept by the dry pass (sp): L, F, volume;
 * returns 1 if det F <= 0 */
GK_FORCE_INLINE int gk__mpm_g2p_commit(gk_mpm_points *P, int p, const double *sp) {
    double J = sp[18];
    memcpy(P->L + 9 * p, sp, 9 * sizeof(double));
    memcpy(P->F + 9 * p, sp + 9, 9 * sizeof(double));
    P->vol[p] = J * P->vol0[p];
    return !(J > 0.0);
}

/* gather one point. dry: write nothing, return 1 if the gradient update would
 * invert F (and keep L, F_new, det F_new in scr when scr is not NULL). Else
 * update the point (the gradient from scr when it is not NULL) and return 1 if
 * det F <= 0 afterwards. */
static int gk__mpm_g2p_point(const gk_mpm_grid *g, gk_mpm_points *P, const gk_mpm_def *d, double dt, int what,
                             int p, int dry, int fresh, double *scr) {
    gk__mpm_w Wt;
    const gk__mpm_w *W = NULL;
    gk__mpm_gath o;
    double x[3] = {0.0, 0.0, 0.0};
    double l = d->basis == GK_MPM_UGIMP ? P->lp[p] * g->inv_h : 0.0;
    int k, dim = g->dim, apic = d->transfer == GK_MPM_APIC;
    int grad = what & (GK_MPM_G2P_GRADIENT_NEW | GK_MPM_G2P_GRADIENT_OLD);
    int want_v = what & GK_MPM_G2P_VELOCITY, want_x = what & GK_MPM_G2P_POSITION;
    int apic_b = apic && want_v && (d->basis == GK_MPM_QUADRATIC || d->basis == GK_MPM_CUBIC);
    int apic_g = apic && want_v && !apic_b;
    int gather_grad = grad && (dry || !scr), gather_vel = !dry && (want_v || want_x);
    double *const *vg = (what & GK_MPM_G2P_GRADIENT_OLD) ? g->v : g->vn;
    double *sp = scr ? scr + (size_t)GK__MPM_SCR * (size_t)p : NULL;
    for (k = 0; k < 3; ++k) o.vpic[k] = o.dv[k] = 0.0;
    if (apic)
        for (k = 0; k < 9; ++k) o.Bm[k] = 0.0;
    for (k = 0; k < 9; ++k) o.Lg[k] = 0.0;
    if (gather_grad || gather_vel) {
        for (k = 0; k < dim; ++k) x[k] = P->x[k][p];
        W = gk__mpm_wget(g, fresh, d->basis, x, l, p, 0, &Wt);
        gk__mpm_gather(g, W, gather_vel, gather_grad, vg, apic_b, apic_g, &o);
    }
    if (dry) {
        double Fn[9], J = gk__mpm_f_update(dim, dt, o.Lg, P->F + 9 * p, Fn);
        if (sp) {
            memcpy(sp, o.Lg, 9 * sizeof(double));
            memcpy(sp + 9, Fn, 9 * sizeof(double));
            sp[18] = J;
        }
        return !(J > 0.0);
    }
    if (want_v) {
        if (apic) {
            double Dinv =
                d->basis == GK_MPM_QUADRATIC ? 4.0 * g->inv_h * g->inv_h : 3.0 * g->inv_h * g->inv_h;
            for (k = 0; k < dim; ++k) P->v[k][p] = o.vpic[k];
            for (k = 0; k < 9; ++k) P->C[9 * p + k] = apic_b ? o.Bm[k] * Dinv : o.Bm[k];
        } else {
            for (k = 0; k < dim; ++k)
                P->v[k][p] = d->alpha * o.vpic[k] + (1.0 - d->alpha) * (P->v[k][p] + o.dv[k]);
        }
    }
    if (want_x)
        for (k = 0; k < dim; ++k) P->x[k][p] += dt * o.vpic[k];
    if (grad) {
        double Fn[9], J;
        if (sp) return gk__mpm_g2p_commit(P, p, sp);
        J = gk__mpm_f_update(dim, dt, o.Lg, P->F + 9 * p, Fn);
        memcpy(P->L + 9 * p, o.Lg, 9 * sizeof(double));
        gk_m3_copy(Fn, P->F + 9 * p);
        P->vol[p] = J * P->vol0[p];
        return !(J > 0.0);
    }
    return 0;
}

GKDEF gk_result gk_mpm_g2p(const gk_mpm_grid *g, gk_mpm_points *P, const gk_mpm_def *d, double dt, int what,
                           gk_err *err) {
    gk_result r = gk__mpm_check_def(d, err);
    int n, p, k, nth, bad = 0, fresh;
    double *scr = NULL;
    if (r) return r;
    if (!P) return gk_err_set(err, GK_ERR_ARG, "NULL points");
    if (P->dim != g->dim) return gk_err_set(err, GK_ERR_ARG, "points are %dD, grid is %dD", P->dim, g->dim);
    if (what < 1 || what > 15 || ((what & GK_MPM_G2P_GRADIENT_NEW) && (what & GK_MPM_G2P_GRADIENT_OLD)))
        return gk_err_set(err, GK_ERR_ARG, "G2P flags %d (at most one GRADIENT flag)", what);
    if (!isfinite(dt)) return gk_err_set(err, GK_ERR_NAN, "time step is NaN or infinite");
    if (!(dt > 0.0)) return gk_err_set(err, GK_ERR_DT, "time step %g (must be > 0)", dt);
    n = P->n;
    for (p = 0; p < n; ++p) {
        double x[3] = {0.0, 0.0, 0.0}, l = d->basis == GK_MPM_UGIMP ? P->lp[p] * g->inv_h : 0.0;
        for (k = 0; k < g->dim; ++k) {
            x[k] = P->x[k][p];
            if (!isfinite(x[k]) || !isfinite(P->v[k][p]))
                return gk_err_set(err, GK_ERR_NAN, "point %d: position or velocity is NaN or infinite", p);
        }
        if (d->basis == GK_MPM_UGIMP && !(l > 0.0 && l <= 0.5))
            return gk_err_set(err, GK_ERR_ARG, "point %d: uGIMP half-size lp = %g (must be in (0, h/2])", p,
                              P->lp[p]);
        if (!gk__mpm_inside(g, d->basis, x, l))
            return gk_err_set(err, GK_ERR_OUTSIDE, "point %d at (%g, %g, %g): its support leaves the grid", p,
                              x[0], x[1], x[2]);
    }
    nth = gk__mpm_nthreads(d);
    (void)nth; /* unused without OpenMP */
    fresh = gk__mpm_wc_fresh(g);
    if (what & (GK_MPM_G2P_GRADIENT_NEW | GK_MPM_G2P_GRADIENT_OLD)) {
        /* a dry pass first: an update that inverts some F changes no point; it keeps
         * each point's L and new F for the second pass (recomputed if no memory) */
        if (n > 0) scr = (double *)gk_alloc(&P->alloc, (size_t)GK__MPM_SCR * (size_t)n * sizeof(double));
        GK_OMP(parallel for num_threads(nth) schedule(static) reduction(+ : bad) if (nth > 1))
        for (p = 0; p < n; ++p) bad += gk__mpm_g2p_point(g, P, d, dt, what, p, 1, fresh, scr);
        if (bad) {
            for (p = 0; p < n; ++p)
                if (gk__mpm_g2p_point(g, P, d, dt, what, p, 1, fresh, NULL)) break;
            gk_free(&P->alloc, scr);
            return gk_err_set(err, GK_ERR_DIVERGED,
                              "%d points would invert (det F <= 0), first point %d: nothing was changed", bad,
                              p);
        }
    }
    if (scr && !(what & (GK_MPM_G2P_VELOCITY | GK_MPM_G2P_POSITION))) { /* the gradient alone: kept */
        GK_OMP(parallel for num_threads(nth) schedule(static) reduction(+ : bad) if (nth > 1))
        for (p = 0; p < n; ++p) bad += gk__mpm_g2p_commit(P, p, scr + (size_t)GK__MPM_SCR * (size_t)p);
    } else {
        GK_OMP(parallel for num_threads(nth) schedule(static) reduction(+ : bad) if (nth > 1))
        for (p = 0; p < n; ++p) bad += gk__mpm_g2p_point(g, P, d, dt, what, p, 0, fresh, scr);
    }
    gk_free(&P->alloc, scr);
    if (bad) return gk_err_set(err, GK_ERR_DIVERGED, "%d points inverted (det F <= 0)", bad);
    return GK_OK;
}

GKDEF void gk_mpm_body_nodes(const gk_mpm_grid *g, const gk_mpm_body *B, int lo[3], int hi[3]) {
    int k;
    for (k = 0; k < 3; ++k) {
        if (B->shape == GK_MPM_CIRCLE && k == 2 && g->dim == 3) { /* a cylinder along z */
            lo[k] = 0, hi[k] = g->n[k] - 1;
        } else if (k < g->dim) {
            double blo = B->shape == GK_MPM_CIRCLE ? B->centre[k] - B->radius : B->lo[k],
                   bhi = B->shape == GK_MPM_CIRCLE ? B->centre[k] + B->radius : B->hi[k];
            double a = ceil((blo - g->origin[k]) * g->inv_h - 1e-9);
            double b = floor((bhi - g->origin[k]) * g->inv_h + 1e-9);
            lo[k] = a < 0.0 ? 0 : (a > g->n[k] ? g->n[k] : (int)a);
            hi[k] = b > g->n[k] - 1 ? g->n[k] - 1 : (b < -1.0 ? -1 : (int)b);
        } else {
            lo[k] = hi[k] = 0;
        }
    }
}

GKDEF int gk_mpm_body_covers(const gk_mpm_grid *g, const gk_mpm_body *B, const double x[3]) {
    double dx, dy, r;
    if (B->shape != GK_MPM_CIRCLE) return 1;
    dx = x[0] - B->centre[0], dy = x[1] - B->centre[1], r = B->radius + 1e-9 * g->h;
    return dx * dx + dy * dy <= r * r;
}

GKDEF void gk_mpm_bodies_advance(gk_mpm_body *body, int nbody, double dt) {
    int b, k;
    for (b = 0; b < nbody; ++b)
        for (k = 0; k < 3; ++k) {
            body[b].lo[k] += dt * body[b].v[k];
            body[b].hi[k] += dt * body[b].v[k];
            body[b].centre[k] += dt * body[b].v[k];
        }
}

GKDEF gk_result gk_mpm_step(gk_mpm_grid *g, gk_mpm_points *P, const gk_mpm_def *d, double dt,
                            gk_mpm_stress_fn stress, void *user, gk_err *err) {
    gk_result r = gk__mpm_check_def(d, err);
    if (r) return r;
    if (!isfinite(dt)) return gk_err_set(err, GK_ERR_NAN, "time step is NaN or infinite");
    if (!(dt > 0.0)) return gk_err_set(err, GK_ERR_DT, "time step %g (must be > 0)", dt);
    switch (d->scheme) {
    case GK_MPM_USF:
        if ((r = gk_mpm_p2g(g, P, d, GK_MPM_P2G_MOMENTUM, err))) return r;
        if ((r = gk_mpm_g2p(g, P, d, dt, GK_MPM_G2P_GRADIENT_OLD, err))) return r;
        if (stress && (r = stress(P, dt, user, err))) return r;
        if ((r = gk_mpm_p2g(g, P, d, GK_MPM_P2G_FORCE, err))) return r;
        if ((r = gk_mpm_grid_update(g, d, dt, err))) return r;
        if ((r = gk_mpm_g2p(g, P, d, dt, GK_MPM_G2P_VELOCITY | GK_MPM_G2P_POSITION, err))) return r;
        break;
    case GK_MPM_USL:
        if ((r = gk_mpm_p2g(g, P, d, GK_MPM_P2G_MOMENTUM | GK_MPM_P2G_FORCE, err))) return r;
        if ((r = gk_mpm_grid_update(g, d, dt, err))) return r;
        if ((r = gk_mpm_g2p(g, P, d, dt, GK_MPM_G2P_GRADIENT_NEW | GK_MPM_G2P_VELOCITY | GK_MPM_G2P_POSITION,
                            err)))
            return r;
        if (stress && (r = stress(P, dt, user, err))) return r;
        break;
    case GK_MPM_MUSL: { /* the gradient comes after the move: keep x, v, C to put back if it fails */
        double *keep;
        size_t n = (size_t)P->n, k, nk = 2 * (size_t)P->dim + (P->C ? 9 : 0);
        if ((r = gk_mpm_p2g(g, P, d, GK_MPM_P2G_MOMENTUM | GK_MPM_P2G_FORCE, err))) return r;
        if ((r = gk_mpm_grid_update(g, d, dt, err))) return r;
        keep = (double *)gk_alloc(&P->alloc, nk * n * sizeof(double));
        if (!keep) return gk_err_set(err, GK_ERR_ALLOC, "MUSL step: a copy of %d points", P->n);
        for (k = 0; k < (size_t)P->dim; ++k) {
            memcpy(keep + 2 * k * n, P->x[k], n * sizeof(double));
            memcpy(keep + (2 * k + 1) * n, P->v[k], n * sizeof(double));
        }
        if (P->C) memcpy(keep + 2 * (size_t)P->dim * n, P->C, 9 * n * sizeof(double));
        r = gk_mpm_g2p(g, P, d, dt, GK_MPM_G2P_VELOCITY | GK_MPM_G2P_POSITION, err);
        if (!r) r = gk_mpm_p2g(g, P, d, GK_MPM_P2G_MOMENTUM, err);
        if (!r) r = gk_mpm_g2p(g, P, d, dt, GK_MPM_G2P_GRADIENT_OLD, err);
        if (r) {
            for (k = 0; k < (size_t)P->dim; ++k) {
                memcpy(P->x[k], keep + 2 * k * n, n * sizeof(double));
                memcpy(P->v[k], keep + (2 * k + 1) * n, n * sizeof(double));
            }
            if (P->C) memcpy(P->C, keep + 2 * (size_t)P->dim * n, 9 * n * sizeof(double));
        }
        gk_free(&P->alloc, keep);
        if (r) return r;
        if (stress && (r = stress(P, dt, user, err))) return r;
        break;
    }
    }
    gk_mpm_bodies_advance(g->body, g->nbody, dt);
    return GK_OK;
}

GKDEF gk_result gk_mpm_point_polar(const gk_mpm_points *pts, int p, double R[9], double U[9], gk_err *err) {
    if (p < 0 || p >= pts->n) return gk_err_set(err, GK_ERR_ARG, "point %d (there are %d)", p, pts->n);
    if (!gk_m3_isfinite(pts->F + 9 * p))
        return gk_err_set(err, GK_ERR_NAN, "point %d: F has a NaN or infinite entry", p);
    if (gk_m3_polar(pts->F + 9 * p, pts->dim, R, U) != GK_OK)
        return gk_err_set(err, GK_ERR_SINGULAR, "point %d: det F = %g <= 0", p, gk_m3_det(pts->F + 9 * p));
    return GK_OK;
}

/* ---- constitutive updates */
/* sigma <- R sigma R^T, R = exp(skew dH) (objective rotation of the stress) */
GK_FORCE_INLINE void gk__mpm_rotate(int dim, const double dH[9], double sigma[9]) {
    double W[9], R[9], T[9], Rt[9];
    gk_m3_skew(dH, W);
    if (W[1] == 0.0 && W[2] == 0.0 && W[5] == 0.0) return;
    gk_m3_exp(W, R);
    gk_m3_mul(R, sigma, T);
    gk_m3_transpose(R, Rt);
    gk_m3_mul(T, Rt, sigma);
    if (dim == 2) sigma[2] = sigma[5] = sigma[6] = sigma[7] = sigma[8] = 0.0;
}

static gk_result gk__mpm_check_dH(int dim, const double dH[9], const double sigma[9], gk_err *err) {
    if (dim != 2 && dim != 3) return gk_err_set(err, GK_ERR_ARG, "dimension %d (must be 2 or 3)", dim);
    if (!gk_m3_isfinite(dH)) return gk_err_set(err, GK_ERR_NAN, "dH has a NaN or infinite entry");
    if (!gk_m3_isfinite(sigma)) return gk_err_set(err, GK_ERR_NAN, "stress has a NaN or infinite entry");
    return GK_OK;
}

/* sigma += K tr(de) I + 2 G dev(de), de = sym dH (dimension dim) */
GK_FORCE_INLINE void gk__mpm_elastic_add(double K, double G, int dim, const double dH[9], double sigma[9]) {
    double e[9], tr = 0.0;
    int i, j;
    gk_m3_sym(dH, e);
    for (i = 0; i < dim; ++i) tr += e[4 * i];
    for (i = 0; i < dim; ++i)
        for (j = 0; j < dim; ++j)
            sigma[3 * i + j] += 2.0 * G * e[3 * i + j] + (i == j ? (K - 2.0 * G / dim) * tr : 0.0);
}

GKDEF gk_result gk_mpm_elastic_update(double K, double G, int dim, const double dH[9], double sigma[9],
                                      gk_err *err) {
    gk_result r = gk__mpm_check_dH(dim, dH, sigma, err);
    if (r) return r;
    if (!(K > 0.0) || !(G >= 0.0) || !isfinite(K) || !isfinite(G))
        return gk_err_set(err, GK_ERR_ARG, "elastic moduli K = %g, G = %g (need K > 0, G >= 0)", K, G);
    gk__mpm_rotate(dim, dH, sigma);
    gk__mpm_elastic_add(K, G, dim, dH, sigma);
    return GK_OK;
}

static gk_result gk__mpm_dp_check(const gk_mpm_dp *dp, int dim, gk_err *err) {
    if (dim != 2 && dim != 3) return gk_err_set(err, GK_ERR_ARG, "dimension %d (must be 2 or 3)", dim);
    if (!dp) return gk_err_set(err, GK_ERR_ARG, "NULL Drucker-Prager parameters");
    if (!isfinite(dp->K) || !isfinite(dp->G) || !isfinite(dp->eta) || !isfinite(dp->etabar) ||
        !isfinite(dp->zeta) || !isfinite(dp->c))
        return gk_err_set(err, GK_ERR_NAN, "Drucker-Prager parameter is NaN or infinite");
    if (!(dp->K > 0.0) || !(dp->G > 0.0))
        return gk_err_set(err, GK_ERR_ARG, "Drucker-Prager moduli K = %g, G = %g (must be > 0)", dp->K,
                          dp->G);
    if (dp->eta < 0.0 || dp->c < 0.0 || dp->zeta < 0.0)
        return gk_err_set(err, GK_ERR_ARG, "Drucker-Prager eta = %g, zeta = %g, c = %g (must be >= 0)",
                          dp->eta, dp->zeta, dp->c);
    if (dp->eta == 0.0 && dp->etabar != 0.0)
        return gk_err_set(err, GK_ERR_ARG, "Drucker-Prager etabar = %g with eta = 0", dp->etabar);
    return GK_OK;
}

static void gk__mpm_dp_coeffs(int dim, double phi, double psi, double *eta, double *etabar, double *zeta) {
    if (dim == 2) {
        *eta = sin(phi);
        *etabar = sin(psi);
        *zeta = cos(phi);
    } else {
        double k = 6.0 / sqrt(3.0);
        *eta = k * sin(phi) / (3.0 - sin(phi));
        *etabar = k * sin(psi) / (3.0 - sin(psi));
        *zeta = k * cos(phi) / (3.0 - sin(phi));
    }
}

GKDEF gk_result gk_mpm_dp_init(gk_mpm_dp *dp, int dim, double K, double G, double phi, double psi, double c,
                               gk_err *err) {
    gk_mpm_dp t;
    gk_result r;
    memset(&t, 0, sizeof t);
    if (!isfinite(phi) || !isfinite(psi))
        return gk_err_set(err, GK_ERR_NAN, "friction or dilatancy angle is NaN");
    if (!(phi >= 0.0 && phi < 0.5 * GK_PI) || !(psi > -0.5 * GK_PI && psi <= phi))
        return gk_err_set(err, GK_ERR_ARG, "angles phi = %g, psi = %g rad (need 0 <= phi < pi/2, psi <= phi)",
                          phi, psi);
    t.K = K;
    t.G = G;
    t.c = c;
    gk__mpm_dp_coeffs(dim, phi, psi, &t.eta, &t.etabar, &t.zeta);
    r = gk__mpm_dp_check(&t, dim, err);
    if (r) return r;
    *dp = t;
    return GK_OK;
}

/* p = tr/dim, s = sigma - p I (dim block), q = sqrt(s:s/2) */
GK_FORCE_INLINE double gk__mpm_pq(int dim, const double sig[9], double s[9], double *q) {
    double p = 0.0, ss = 0.0;
    int i, j;
    for (i = 0; i < dim; ++i) p += sig[4 * i];
    p /= dim;
    for (i = 0; i < 9; ++i) s[i] = 0.0;
    for (i = 0; i < dim; ++i)
        for (j = 0; j < dim; ++j) {
            s[3 * i + j] = sig[3 * i + j] - (i == j ? p : 0.0);
            ss += s[3 * i + j] * s[3 * i + j];
        }
    *q = sqrt(0.5 * ss);
    return p;
}

GKDEF double gk_mpm_dp_yield(const gk_mpm_dp *dp, int dim, const double sigma[9]) {
    double s[9], q, p = gk__mpm_pq(dim, sigma, s, &q);
    return q + dp->eta * p - dp->zeta * dp->c;
}

/* gk_mpm_dp_return on a dp already checked */
GK_FORCE_INLINE gk_result gk__mpm_dp_return(const gk_mpm_dp *dp, int dim, const double sig_trial[9],
                                            double sig[9], gk_mpm_dp_info *info, gk_err *err) {
    double s[9], q, p, f, dl = 0.0, out[9];
    int i, j, status = 0;
    if (!gk_m3_isfinite(sig_trial))
        return gk_err_set(err, GK_ERR_NAN, "trial stress has a NaN or infinite entry");
    p = gk__mpm_pq(dim, sig_trial, s, &q);
    f = q + dp->eta * p - dp->zeta * dp->c;
    gk_m3_copy(sig_trial, out);
    if (f > 0.0) {
        double pn, qn;
        dl = f / (dp->G + dp->K * dp->eta * dp->etabar);
        qn = q - dp->G * dl;
        if (qn < 0.0 || q == 0.0) { /* apex: s = 0 and f = eta p - zeta c = 0 */
            status = 2;
            pn = dp->eta > 0.0 ? dp->zeta * dp->c / dp->eta : p;
            qn = 0.0;
        } else {
            status = 1;
            pn = p - dp->K * dp->etabar * dl;
        }
        for (i = 0; i < dim; ++i)
            for (j = 0; j < dim; ++j)
                out[3 * i + j] = (q > 0.0 ? s[3 * i + j] * (qn / q) : 0.0) + (i == j ? pn : 0.0);
    }
    if (info) {
        double sn[9], qq, pn = gk__mpm_pq(dim, out, sn, &qq);
        info->status = status;
        info->f_trial = f;
        info->dlambda = dl;
        /* plastic strain = elastic compliance of the stress drop (cone and apex alike) */
        for (i = 0; i < 9; ++i) info->deps_p[i] = (s[i] - sn[i]) / (2.0 * dp->G);
        for (i = 0; i < dim; ++i) info->deps_p[4 * i] += (p - pn) / (dp->K * dim);
    }
    gk_m3_copy(out, sig);
    return GK_OK;
}

GKDEF gk_result gk_mpm_dp_return(const gk_mpm_dp *dp, int dim, const double sig_trial[9], double sig[9],
                                 gk_mpm_dp_info *info, gk_err *err) {
    gk_result r = gk__mpm_dp_check(dp, dim, err);
    if (r) return r;
    return gk__mpm_dp_return(dp, dim, sig_trial, sig, info, err);
}

/* eq 7: dp with eta, etabar, zeta at Phi (chi > 0); dp itself not checked */
static gk_result gk__mpm_dp_eq7(const gk_mpm_dp *dp, int dim, double Phi, gk_mpm_dp *out, gk_err *err) {
    gk_mpm_dp t = *dp;
    if (t.chi > 0.0) {
        double tphi, tpsi;
        if (!isfinite(Phi) || !isfinite(t.tan_phi_cs) || !isfinite(t.Phi_cs) || !isfinite(t.xi))
            return gk_err_set(err, GK_ERR_ARG,
                              "critical-state Drucker-Prager needs a finite packing fraction");
        tpsi = (Phi - t.Phi_cs) * t.chi; /* eq 7 */
        tphi = t.tan_phi_cs + tpsi;
        if (tphi < 0.0)
            return gk_err_set(
                err, GK_ERR_ARG,
                "critical-state Drucker-Prager: packing fraction %g gives tan phi = %g < 0 (eq 7 "
                "needs Phi >= Phi_cs - tan phi_cs / chi = %g)",
                Phi, tphi, t.Phi_cs - t.tan_phi_cs / t.chi);
        gk__mpm_dp_coeffs(dim, atan(tphi), atan(tpsi), &t.eta, &t.etabar, &t.zeta);
    }
    *out = t;
    return GK_OK;
}

/* rotate, elastic trial, return map, eq 8: dp (with eq 7 made for *Phi),
 * dH, sigma and Phi already checked */
GK_FORCE_INLINE gk_result gk__mpm_dp_step_dim(const gk_mpm_dp *dp, int dim, const double dH[9],
                                              double sigma[9], double *Phi, gk_mpm_dp_info *info_out,
                                              gk_err *err) {
    gk_mpm_dp_info info;
    double trial[9];
    gk_result r;
    gk_m3_copy(sigma, trial);
    gk__mpm_rotate(dim, dH, trial);
    gk__mpm_elastic_add(dp->K, dp->G, dim, dH, trial);
    r = gk__mpm_dp_return(dp, dim, trial, sigma, &info, err);
    if (r) return r;
    if (dp->chi > 0.0 && info.status) {
        double n = gk_m3_norm(info.deps_p);
        *Phi -= (*Phi - dp->Phi_cs) * (*Phi) * dp->xi * n; /* eq 8 */
    }
    if (info_out) *info_out = info;
    return GK_OK;
}

/* the same with the dimension a constant (the loops unrolled; the same operations) */
static gk_result gk__mpm_dp_step(const gk_mpm_dp *dp, int dim, const double dH[9], double sigma[9],
                                 double *Phi, gk_mpm_dp_info *info_out, gk_err *err) {
    if (dim == 2) return gk__mpm_dp_step_dim(dp, 2, dH, sigma, Phi, info_out, err);
    return gk__mpm_dp_step_dim(dp, 3, dH, sigma, Phi, info_out, err);
}

GKDEF gk_result gk_mpm_dp_at(const gk_mpm_dp *dp, int dim, double Phi, gk_mpm_dp *out, gk_err *err) {
    gk_result r = gk__mpm_dp_check(dp, dim, err);
    if (r) return r;
    if (!out) return gk_err_set(err, GK_ERR_ARG, "NULL Drucker-Prager result");
    return gk__mpm_dp_eq7(dp, dim, Phi, out, err);
}

GKDEF gk_result gk_mpm_dp_update_at(const gk_mpm_dp *dp, int dim, const double dH[9], double sigma[9],
                                    double *Phi, gk_mpm_dp_info *info_out, gk_err *err) {
    gk_result r = gk__mpm_dp_check(dp, dim, err);
    if (r) return r;
    r = gk__mpm_check_dH(dim, dH, sigma, err);
    if (r) return r;
    if (dp->chi > 0.0 && (!Phi || !isfinite(*Phi)))
        return gk_err_set(err, GK_ERR_ARG, "critical-state Drucker-Prager needs a finite packing fraction");
    return gk__mpm_dp_step(dp, dim, dH, sigma, Phi, info_out, err);
}

GKDEF gk_result gk_mpm_dp_update(const gk_mpm_dp *dp_in, int dim, const double dH[9], double sigma[9],
                                 double *Phi, gk_mpm_dp_info *info_out, gk_err *err) {
    gk_mpm_dp dp;
    gk_result r = gk__mpm_dp_check(dp_in, dim, err);
    if (r) return r;
    r = gk__mpm_check_dH(dim, dH, sigma, err);
    if (r) return r;
    if (dp_in->chi > 0.0 && !Phi)
        return gk_err_set(err, GK_ERR_ARG, "critical-state Drucker-Prager needs a finite packing fraction");
    r = gk__mpm_dp_eq7(dp_in, dim, Phi ? *Phi : 0.0, &dp, err);
    if (r) return r;
    r = gk__mpm_dp_check(&dp, dim, err); /* the coefficients eq 7 made (eta 0 with etabar != 0) */
    if (r) return r;
    return gk__mpm_dp_step(&dp, dim, dH, sigma, Phi, info_out, err);
}

#endif /* GK_MPM implementation */

/*
MIT License. Copyright (c) 2026 the grainkit authors.
Permission is hereby granted, free of charge, to any person obtaining a copy of
this software and associated documentation files (the "Software"), to deal in
the Software without restriction, including without limitation the rights to
use, copy, modify, merge, publish, distribute, sublicense, and/or sell copies of
the Software, and to permit persons to whom the Software is furnished to do so,
subject to the following conditions: The above copyright notice and this
permission notice shall be included in all copies or substantial portions of the
Software. THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND,
EXPRESS OR IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF
MERCHANTABILITY, FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO
EVENT SHALL THE AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR
OTHER LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING
FROM, OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN
THE SOFTWARE.
*/
