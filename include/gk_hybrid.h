/* gk_hybrid.h - concurrent hybrid continuum-grain MPM-DEM: an oracle finds
 * where a shear band forms, that region is replaced once by grains, and the
 * two media are coupled through an overlap.                 (grainkit v0.1)
 *
 * Chen, Chantharayukhonthorn, Yue, Grinspun & Kamrin, "Hybrid discrete-
 * continuum modeling of shear localization in granular media", J. Mech.
 * Phys. Solids (2021), with the coupling of Yue, Zhang, Stomakhin, Kamrin,
 * Grinspun & Jiang, "Hybrid grains", ACM Trans. Graph. 37 (2018). An
 * explicit MPM continuum (gk_mpm.h, Drucker-Prager with critical-state
 * softening, eqs 4-8) runs everywhere until the oracle (Alg. 1) has flagged
 * the same grid nodes for a while; the region within phi_0 of them becomes
 * grains (gk_scene.h), kinematically trained on the continuum's motion, and
 * the grains and the continuum share an overlap one cell thick where their
 * grid velocities are made equal (eq 9). 2D (disks, plane MPM) throughout.
 *
 * DO THIS in one C/C++ file:   #define GK_IMPLEMENTATION
 *                              #include "gk_hybrid.h"  (pulls in gk_mpm.h, gk_scene.h)
 * examples/hybrid.c is a complete driver (planar shear, biaxial test).
 *
 * WHAT IS HERE
 *   gk_hybrid_periodic      a grid axis that wraps: node i is node
 *                           ghost + (i - ghost) mod period ("home" nodes);
 *                           gk_mpm.h has no periodic grid, so a step folds
 *                           the ghost copies into their home nodes after
 *                           each P2G (sums; the copy is left without mass,
 *                           hence inactive, so a face or body reaction is
 *                           counted once) and copies the home velocities
 *                           back before each G2P
 *     gk_hybrid_fold / _sync / _fold_momentum / _fold_force / _sync_velocity
 *     gk_hybrid_wrap_points  points back into the home range
 *   gk_hybrid_mpm_predict / gk_hybrid_mpm_finish   one USF step of
 *                           gk_mpm.h split where the coupling acts:
 *                           P2G, L, stress, forces, grid update (vn) |
 *                           [coupling] | G2P, positions, bodies
 *   gk_hybrid_cont          per-point continuum state next to gk_mpm_points
 *                           (reference position, packing fraction Phi,
 *                           accumulated plastic strain, plastic strain
 *                           rate, zone); gk_hybrid_dp_stress is the
 *                           gk_mpm_stress_fn of the Drucker-Prager
 *                           continuum [eqs 4-8]; gk_hybrid_points_keep
 *                           deletes points (and their state)
 *   gk_hybrid_rasterize     Sum N m q and Sum N m on the nodes (any
 *                           positions: current, reference, grains)
 *   gk_hybrid_interp        a node field at a position (linear, over nodes
 *                           that hold data)
 *   gk_hybrid_history       the plastic strain of every point at past times
 *                           (a ring of snapshots), for the recent strain
 *                           Delta^{tau_l} eps^p of Alg. 1
 *   gk_hybrid_oracle_flag   Alg. 1 line 3 on the grid nodes (pure function)
 *   gk_hybrid_oracle_*      the persistence test (Alg. 1 line 7)
 *   gk_hybrid_distance / gk_hybrid_zone   distance to the flagged nodes and
 *                           the zone it puts a position in (Sec 4)
 *   gk_hybrid_train         kinematic training of a packing (Sec 4.1.1)
 *   gk_hybrid_enrich        the swap: points of the discrete zone deleted,
 *                           overlap points and grains weighted, grain mass
 *                           and momentum matched to what left the continuum
 *   gk_hybrid_couple        the overlap coupling (eq 9)
 *   gk_hybrid_cundall       Cundall's best-fit strain of every grain (App. A)
 *                           over the grains within a cutoff
 *   gk_hybrid_cundall_delaunay  the same over Delaunay neighbours (App. A's)
 *   gk_hybrid_band          band thickness: top percentile, outliers out,
 *                           minimum-area bounding box (App. A)
 *   gk_hybrid_band_top      the same on the count largest values
 *   gk_hybrid_bc_mask       nodes a face or body of the grid constrains
 *   gk_hybrid_traction      follower pressure on a boundary point (Nanson)
 *
 * THE ORACLE (Alg. 1), evaluated on grid nodes. e = ||epsdot^p|| (Frobenius
 * norm of the plastic strain rate of the points, mass-weighted onto the
 * nodes), e_max = the largest e over the nodes of the cells incident to the
 * node, R = ||Delta^{tau_l} eps^p|| (the plastic strain accumulated over the
 * last tau_l, same rasterisation). A node is flagged when
 *     e_max > 0  and  R > c1  and  |lap e| / e_max > min(c0/D50^2, c0/dX^2),
 * lap the 5-point Laplacian (7-point in 3D), evaluated only where the node
 * and its neighbours are active (periodic axes wrap). The flagged set
 * triggers the enrichment when it is non-empty and has not changed for
 * tau_g; tau_l = c_l / gdot_max, tau_g = c_g / gdot_max with gdot_max the
 * largest equivalent shear rate sqrt(2 D':D') over the points at that
 * time (Sec 3.2). The oracle is told nothing else: in particular not where
 * the "weak" points that seed a band are (the paper's rule).
 *
 * ZONES (Sec 4). phi_d = distance to the nearest flagged node (periodic
 * axes: nearest image); with t_h the overlap thickness (one cell):
 *     discrete only   phi_d <= phi_0 - t_h/2
 *     overlap         phi_0 - t_h/2 < phi_d <= phi_0 + t_h/2
 *     continuum only  phi_d >  phi_0 + t_h/2.
 *
 * ENRICHMENT. Points in the discrete zone are deleted. Overlap points keep
 * (1 - w) of their mass and volume (so of their stress's force) and overlap
 * grains w of their mass (the partition w = 1/2 of eq 9, as the public
 * Hybrid Grains code weights them). Their contact forces are the caller's
 * choice: whole, or w f as eq 9 writes it, each contact scaled by its
 * grains' mean w (gk_scene_weight_contacts, gk_scene.h); the paper does
 * not say how w enters. The grain masses are then scaled by one
 * factor and their velocities (the continuum's, interpolated) shifted by one
 * vector so that the total mass and momentum equal those before the swap
 * (the factor is 1 +- a few % for a packing cut from the continuum's own
 * material). 2D grain masses are per the disk thickness t, continuum
 * masses per unit thickness: grain mass / t enters every sum.
 *
 * COUPLING (eq 9, operator split as in Yue et al. 2018). After the
 * continuum's grid update (nodes hold m_c, vn) and the grains' own DEM step
 * (from pre-step positions x^n to x^{n+1} with v^{n+1/2}), the coupled
 * grains (the caller's mask: overlap, not prescribed) are rasterised at x^n:
 * m_d = Sum N m_g / t, p_d = Sum N m_g v_g / t. At every node with m_c > 0
 * and m_d > 0 (not constrained by a face or body):
 *     Lambda = (m_d p_c - m_c p_d) / (m_c + m_d),  p_c -= Lambda,  p_d += Lambda
 * so both take v* = (p_c + p_d) / (m_c + m_d): the overlap velocities are
 * equal and the momentum p_c + p_d is unchanged. Each coupled grain then
 * gets the FLIP correction dv = Sum N Lambda / m_d (its share of the
 * exchange: Sum_g m_g dv / t = Sum Lambda exactly) and its position the
 * same correction, x^{n+1} += dt dv. Then the continuum's G2P.
 *
 * KINEMATIC TRAINING (Sec 4.1.1). The grains of the band region, taken
 * from the reference (initial) packing, are run alone in a temporary scene
 * while the continuum waits: the boundary grains (a caller mask, e.g. those
 * in the overlap and those on the specimen's surface) move at constant
 * velocity by the continuum's displacement at their reference positions
 * (times a fraction F, Fig 14), the others are free; then the boundary
 * holds still for a relaxation period. Only the boundary is driven:
 * imposing the continuum's motion on every grain gives the wrong stress
 * (the paper's "early attempts").
 *
 * CUNDALL STRAIN (App. A). grad u = (Sum du dX^T)(Sum dX dX^T)^-1 over the
 * neighbours of a grain in the reference positions: its Delaunay
 * neighbours as in the paper (gk_hybrid_cundall_delaunay, the edges of its
 * Voronoi cell, each found by clipping a square around the grain with the
 * bisectors of the grains within reach; nearest images on a periodic axis)
 * or every grain within a cutoff distance (gk_hybrid_cundall, which takes
 * in the second shell as the cutoff grows), du = dx - dX; eps = sym grad u
 * and the equivalent shear strain gamma = sqrt(2 dev eps : dev eps) (= the
 * engineering shear strain of simple shear). Exact for any affine motion
 * when a grain has two non-collinear neighbours (else NaN).
 *
 * BAND THICKNESS (App. A): the grains (or points) whose value is at or
 * above the given percentile (98: the top 2 %); outliers dropped - first
 * those farther than nsd times the RMS distance from the centroid
 * (repeated until none), then those farther than nsd standard deviations
 * from the principal line of the rest; the thickness is the width of the
 * minimum-area rectangle around what remains (one side on an edge of the
 * convex hull). The selection is the values at or above the one of rank
 * floor(Q / 100 (nv - 1)) of the nv finite ones in ascending order;
 * gk_hybrid_band_top selects the N largest instead (at or above the one of
 * rank nv - N: more only on ties). Fewer values make a thinner box:
 * compare two measures (a zone's grains against a whole specimen's) on as
 * many values, not at one percentile.
 *
 * CONVENTIONS: SI units, 2D; stress tension-positive (gk_mpm.h); zones
 * GK_ZONE_*; continuum masses per unit thickness, grain masses for the disk
 * thickness t. Every function that can fail returns a gk_result with its
 * message in the gk_err given; bad input changes nothing.
 *
 * DETERMINISM: every sum runs in a fixed (index) order, serially; the
 * thread count of gk_mpm.h and gk_scene.h does not change a result.
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_HYBRID_H
#define GK_HYBRID_H

#include "gk_base.h"
#include "gk_mpm.h"
#include "gk_scene.h"

#define GK_ZONE_CONTINUUM 0
#define GK_ZONE_OVERLAP 1
#define GK_ZONE_DISCRETE 2

/* A grid axis k with period[k] > 0 wraps: nodes ghost[k] .. ghost[k] +
 * period[k] - 1 are the home nodes (positions origin + h (ghost .. ghost +
 * period)), every other node is the copy of ghost + (i - ghost) mod period.
 * Zero-initialised: no periodic axis. */
typedef struct gk_hybrid_periodic {
    int ghost[3], period[3];
} gk_hybrid_periodic;

/* Per-point continuum state, parallel to a gk_mpm_points (same n, same
 * order). */
typedef struct gk_hybrid_cont {
    int n, cap;
    double *X0[3];       /* reference (initial) position [m]                       */
    double *Phi;         /* packing fraction (eqs 7-8)                             */
    double *ep;          /* accumulated plastic strain, 3 per point (xx, yy, xy)   */
    double *rate;        /* ||plastic strain rate|| of the last update [1/s]      */
    unsigned char *zone; /* GK_ZONE_* (after enrichment; CONTINUUM before)         */
    gk_mpm_dp dp;        /* the Drucker-Prager continuum [eqs 4-8], chi > 0        */
    double gdot_max;     /* largest sqrt(2 D':D') of the last update [1/s]         */
    /* eq 7's coefficients per point, kept while its Phi (and dp) stay: 4 per
     * point, the Phi they were made at (NaN: not yet made), eta, etabar, zeta */
    double *dpk;
    gk_mpm_dp dpk_of; /* the dp they were made with */
    gk_allocator alloc;
} gk_hybrid_cont;

/* Snapshots of a per-point vector (ncomp values per point) at past times. */
typedef struct gk_hybrid_history {
    int n, ncomp, cap, count, head; /* head: slot of the newest snapshot */
    double *t;                      /* cap times                         */
    double *val;                    /* cap x n x ncomp                   */
    gk_allocator alloc;
} gk_hybrid_history;

typedef struct gk_hybrid_oracle_def {
    double c0;  /* Laplacian threshold factor (Alg. 1; Tables 4, 6, 9: 1e-6) */
    double c1;  /* recent plastic strain threshold                          */
    double cl;  /* tau_l = cl / gdot_max                                     */
    double cg;  /* tau_g = cg / gdot_max                                     */
    double D50; /* median grain diameter [m]                                 */
} gk_hybrid_oracle_def;

typedef struct gk_hybrid_oracle {
    gk_hybrid_oracle_def def;
    size_t nnode;
    unsigned char *flag, *prev; /* flags of this and of the last evaluation   */
    double *H;                  /* |lap e| / e_max of the last evaluation     */
    int nflag;
    double since; /* time the flagged set last changed         */
    int evaluated;
    gk_allocator alloc;
} gk_hybrid_oracle;

/* a coupled grain's nodes and weights (a 2D basis: at most 4 x 4 nodes);
 * the coupling keeps these, not the gradients, so they stay in cache */
typedef struct gk_hybrid_stencil {
    int n;
    int32_t node[16];
    double w[16];
} gk_hybrid_stencil;

/* scratch of the coupling, nnode entries each */
typedef struct gk_hybrid_coupling {
    size_t nnode;
    double *md, *pd[2], *dv[2];
    gk_hybrid_stencil *st; /* the stencils of the coupled grains of a step */
    int cap;
    gk_allocator alloc;
} gk_hybrid_coupling;

typedef struct gk_hybrid_couple_report {
    int grains;         /* grains coupled                                  */
    int nodes;          /* nodes where both media have mass                */
    double dv_max;      /* largest |v_c - v_d| before the correction [m/s] */
    double exchange[2]; /* Sum Lambda: momentum moved to the grains [kg m/s per m] */
} gk_hybrid_couple_report;

typedef struct gk_hybrid_enrich_report {
    int points_deleted, points_overlap, grains_discrete, grains_overlap;
    double mass_before, mass_after;     /* per unit thickness [kg/m]     */
    double mom_before[2], mom_after[2]; /* per unit thickness [kg/s]     */
    double mass_scale;                  /* grain mass factor              */
    double dv[2];                       /* velocity shift of the grains  */
} gk_hybrid_enrich_report;

typedef struct gk_hybrid_band_result {
    double thickness; /* width of the minimum-area rectangle [m]        */
    double length;    /* its other side [m]                             */
    double angle;     /* direction of the long side, rad from the x axis */
    double centre[2];
    int selected, kept; /* above the percentile (or the count largest); after the outlier cut */
    int finite;         /* the values measured: finite, at finite positions */
} gk_hybrid_band_result;

#ifdef __cplusplus
extern "C" {
#endif

/* ---- periodic grid axes */
/* home node of node I */
GKDEF size_t gk_hybrid_home(const gk_mpm_grid *g, const gk_hybrid_periodic *per, size_t I);
/* a[home] += a[copy], a[copy] = 0 for every copy (fixed order) */
GKDEF void gk_hybrid_fold(const gk_mpm_grid *g, const gk_hybrid_periodic *per, double *a);
/* a[copy] = a[home] */
GKDEF void gk_hybrid_sync(const gk_mpm_grid *g, const gk_hybrid_periodic *per, double *a);
/* after P2G(MOMENTUM): fold m and p, v = p/m at the home nodes, copies
 * keep v (synced) and no mass */
GKDEF void gk_hybrid_fold_momentum(gk_mpm_grid *g, const gk_hybrid_periodic *per);
/* after P2G(FORCE): fold fint, fext */
GKDEF void gk_hybrid_fold_force(gk_mpm_grid *g, const gk_hybrid_periodic *per);
/* copy v and vn of the home nodes to their copies */
GKDEF void gk_hybrid_sync_velocity(gk_mpm_grid *g, const gk_hybrid_periodic *per);
/* wrap positions along periodic axes into [origin + h ghost, + h period);
 * follow (may be NULL) are per-point arrays shifted by the same amount (the
 * reference positions, so that x - X0 stays the displacement) */
GKDEF void gk_hybrid_wrap_points(const gk_mpm_grid *g, const gk_hybrid_periodic *per, gk_mpm_points *pts,
                                 double *const follow[3]);
/* validation of a periodic description against a grid and basis */
GKDEF gk_result gk_hybrid_periodic_check(const gk_mpm_grid *g, const gk_hybrid_periodic *per, gk_mpm_basis b,
                                         gk_err *err);

/* ---- one USF step of the continuum, split for the coupling */
GKDEF gk_result gk_hybrid_mpm_predict(gk_mpm_grid *g, const gk_hybrid_periodic *per, gk_mpm_points *pts,
                                      const gk_mpm_def *d, double dt, gk_mpm_stress_fn stress, void *user,
                                      gk_err *err);
/* c may be NULL; with it, reference positions follow the periodic wraps */
GKDEF gk_result gk_hybrid_mpm_finish(gk_mpm_grid *g, const gk_hybrid_periodic *per, gk_mpm_points *pts,
                                     gk_hybrid_cont *c, const gk_mpm_def *d, double dt, gk_err *err);

/* ---- continuum state */
/* n points, X0 = the points' positions, Phi = Phi0, dp the continuum */
GKDEF gk_result gk_hybrid_cont_init(gk_hybrid_cont *c, const gk_mpm_points *pts, const gk_mpm_dp *dp,
                                    double Phi0, const gk_allocator *alloc, gk_err *err);
GKDEF void gk_hybrid_cont_free(gk_hybrid_cont *c);
/* gk_mpm_stress_fn (user = gk_hybrid_cont *): rotate, elastic trial, return
 * map with Phi by eqs 7-8 (gk_mpm_dp_update's bits; eq 7 made anew only for
 * the points whose Phi or model changed); accumulates ep, sets rate and
 * gdot_max */
GKDEF gk_result gk_hybrid_dp_stress(gk_mpm_points *pts, double dt, void *user, gk_err *err);
/* keep the points with keep[p] != 0 (pts and c together, order kept);
 * also compacts the caller's per-point arrays extra[e] (stride[e] doubles
 * per point); returns the new count */
GKDEF int gk_hybrid_points_keep(gk_mpm_points *pts, gk_hybrid_cont *c, const unsigned char *keep, int nextra,
                                double *const *extra, const int *stride);

/* ---- node fields */
/* num[c * nnode + I] = Sum_p N_I(x_p) m_p val[ncomp p + c], den[I] = Sum N m
 * over the points with skip[p] == 0 (skip may be NULL; val may be NULL:
 * den only); lp the uGIMP half-size (one for all); folded on periodic axes
 * and synced to the copies */
GKDEF gk_result gk_hybrid_rasterize(const gk_mpm_grid *g, const gk_hybrid_periodic *per, gk_mpm_basis basis,
                                    double lp, int n, const double *const x[3], const double *m,
                                    const double *val, int ncomp, const unsigned char *skip, double *num,
                                    double *den, gk_err *err);
/* field value at x: Sum N f / Sum N (linear weights) over the nodes with
 * den > 0; returns 0 when none holds data (out untouched) */
GKDEF int gk_hybrid_interp(const gk_mpm_grid *g, const gk_hybrid_periodic *per, const double *field,
                           int ncomp, const double *den, const double x[3], double *out);

/* ---- history of a per-point vector */
GKDEF gk_result gk_hybrid_history_init(gk_hybrid_history *h, int n, int ncomp, int cap,
                                       const gk_allocator *alloc, gk_err *err);
GKDEF void gk_hybrid_history_free(gk_hybrid_history *h);
/* store a snapshot at time t (t above the newest; the oldest is dropped when full) */
GKDEF gk_result gk_hybrid_history_push(gk_hybrid_history *h, double t, const double *val, gk_err *err);
/* the values at time t by linear interpolation between snapshots (before
 * the oldest: the oldest); returns 1 if t was before the oldest snapshot
 * (the window was cut), 0 otherwise, -1 if empty */
GKDEF int gk_hybrid_history_at(const gk_hybrid_history *h, double t, double *out);
/* drop the points with keep[p] == 0 from every snapshot */
GKDEF void gk_hybrid_history_keep(gk_hybrid_history *h, const unsigned char *keep);

/* ---- oracle */
/* Alg. 1 line 3 at every node: rate = e, recent = R on the nodes, active =
 * nodes that hold material (and are not constrained), dX the grid spacing.
 * Writes flag[I] (0/1) and, if H is not NULL, H[I]; returns the count. */
GKDEF int gk_hybrid_oracle_flag(const gk_mpm_grid *g, const gk_hybrid_periodic *per,
                                const gk_hybrid_oracle_def *d, const double *rate, const double *recent,
                                const unsigned char *active, unsigned char *flag, double *H);
GKDEF gk_result gk_hybrid_oracle_init(gk_hybrid_oracle *o, const gk_hybrid_oracle_def *d, size_t nnode,
                                      const gk_allocator *alloc, gk_err *err);
GKDEF void gk_hybrid_oracle_free(gk_hybrid_oracle *o);
/* evaluate the flags at time t and the persistence test with tau_g:
 * returns 1 when the flagged set is non-empty and unchanged for tau_g */
GKDEF int gk_hybrid_oracle_step(gk_hybrid_oracle *o, const gk_mpm_grid *g, const gk_hybrid_periodic *per,
                                const double *rate, const double *recent, const unsigned char *active,
                                double t, double tau_g);

/* ---- zones */
/* distance from x to the nearest flagged node (HUGE_VAL if none) */
GKDEF double gk_hybrid_distance(const gk_mpm_grid *g, const gk_hybrid_periodic *per,
                                const unsigned char *flag, const double x[3]);
GK_INLINE int gk_hybrid_zone(double dist, double phi0, double th) {
    if (dist <= phi0 - 0.5 * th) return GK_ZONE_DISCRETE;
    if (dist <= phi0 + 0.5 * th) return GK_ZONE_OVERLAP;
    return GK_ZONE_CONTINUUM;
}

/* ---- enrichment */
/* kinematic training: grains with boundary[p] move by (u[0][p], u[1][p])
 * at constant velocity over nsteps, then hold still for relax steps; then
 * every trained grain is released */
GKDEF gk_result gk_hybrid_train(gk_scene *sc, const unsigned char *boundary, const double *const u[2],
                                long nsteps, long relax, gk_err *err);
/* the swap (see ENRICHMENT): pzone / gzone are the zones of the points and
 * grains; vg the continuum velocity at each grain (2 arrays) or NULL (zero);
 * w the partition (0.5); t the disk thickness. Deletes the DISCRETE points
 * (with c and the caller's extra arrays, as gk_hybrid_points_keep), weights
 * OVERLAP points and grains, sets grain masses and velocities. Grains in
 * the CONTINUUM zone must have been removed before. */
GKDEF gk_result gk_hybrid_enrich(gk_mpm_points *pts, gk_hybrid_cont *c, gk_scene *sc,
                                 const unsigned char *gzone, const double *const vg[2], double w, double t,
                                 int nextra, double *const *extra, const int *stride,
                                 gk_hybrid_enrich_report *rep, gk_err *err);

/* ---- coupling */
GKDEF gk_result gk_hybrid_coupling_init(gk_hybrid_coupling *c, const gk_mpm_grid *g,
                                        const gk_allocator *alloc, gk_err *err);
GKDEF void gk_hybrid_coupling_free(gk_hybrid_coupling *c);
/* eq 9 after the continuum's grid update and the grains' step: xpre the
 * grains' positions before their step (world coordinates, by particle
 * index; only the coupled grains' are read), coupled[p] != 0 for the
 * grains to couple, skip[I] != 0 for nodes
 * left alone (constrained; may be NULL); basis and lp of the grains'
 * stencil; t the disk thickness; dt the step. Changes g->vn and the grains'
 * velocities and positions. */
GKDEF gk_result gk_hybrid_couple(gk_hybrid_coupling *c, gk_mpm_grid *g, const gk_hybrid_periodic *per,
                                 gk_mpm_basis basis, double lp, gk_scene *sc, const double *const xpre[2],
                                 const unsigned char *coupled, const unsigned char *skip, double t, double dt,
                                 gk_hybrid_couple_report *rep, gk_err *err);

/* ---- measurements */
/* Cundall best-fit strain of n grains from reference X to current x, over
 * neighbours within cutoff in X; period[k] > 0: axis k periodic with that
 * length (nearest images); eps[4 p ..] = exx, eyy, exy, gamma (NaN when
 * fewer than two non-collinear neighbours) */
GKDEF gk_result gk_hybrid_cundall(int n, const double *const X[2], const double *const x[2],
                                  const double period[2], double cutoff, double *eps,
                                  const gk_allocator *alloc, gk_err *err);
/* the same over each grain's Delaunay neighbours in X (App. A), found as
 * the edges of its Voronoi cell among the grains within reach: exact where
 * the cell closes inside the square of half-width reach / (2 sqrt 2)
 * around the grain (inside a dense packing, reach 4 D50 is ample); a grain
 * whose cell does not (on a free surface, beside a void) gets the
 * neighbours whose cell edges lie in the square, and open[p] = 1 (else 0;
 * optional, n entries: a caller may leave such one-sided fits out).
 * neighbours[p] (optional) = grain p's count. On an error nothing is
 * written. */
GKDEF gk_result gk_hybrid_cundall_delaunay(int n, const double *const X[2], const double *const x[2],
                                           const double period[2], double reach, double *eps, int *neighbours,
                                           unsigned char *open, const gk_allocator *alloc, gk_err *err);
/* band thickness of the n positions (x, y) by value (see BAND THICKNESS);
 * values that are not finite are ignored */
GKDEF gk_result gk_hybrid_band(int n, const double *x, const double *y, const double *value,
                               double percentile, double nsd, gk_hybrid_band_result *out,
                               const gk_allocator *alloc, gk_err *err);
/* the same on the count >= 3 largest values (more only on ties); a count
 * above the finite values is an error */
GKDEF gk_result gk_hybrid_band_top(int n, const double *x, const double *y, const double *value, int count,
                                   double nsd, gk_hybrid_band_result *out, const gk_allocator *alloc,
                                   gk_err *err);

/* ---- boundaries */
/* mask[I] = 1 for the nodes a face (not FREE) or a rigid body of g acts on */
GKDEF void gk_hybrid_bc_mask(const gk_mpm_grid *g, unsigned char *mask);
/* follower pressure on point p whose face had outward normal N0 and
 * length dl0 in the reference configuration (2D): fext = -pressure J F^-T N0
 * dl0 (Nanson), added to pts->fext */
GKDEF void gk_hybrid_traction(gk_mpm_points *pts, int p, const double N0[2], double dl0, double pressure);

#ifdef __cplusplus
}
#endif
#endif /* GK_HYBRID_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_HYBRID_IMPLEMENTATION)) && !defined(GK_HYBRID_IMPL_ONCE)
#define GK_HYBRID_IMPL_ONCE

#include <stdlib.h>
#include <string.h>

/* err's message prefixed with "what index: " (copied first: vsnprintf must not read the buffer it
 * writes); nothing when err is NULL */
static gk_result gk__hybrid_prefix(gk_err *err, gk_result r, const char *what, int index) {
    char msg[GK_ERR_MSG_LEN];
    if (!err) return r;
    memcpy(msg, err->msg, sizeof msg);
    return gk_err_set(err, r, "%s %d: %s", what, index, msg);
}

/* ---------------------------------------------------------- periodic axes */
static int gk__hy_wrap_index(int i, int ghost, int period) {
    int r = (i - ghost) % period;
    if (r < 0) r += period;
    return ghost + r;
}

GKDEF size_t gk_hybrid_home(const gk_mpm_grid *g, const gk_hybrid_periodic *per, size_t I) {
    int ijk[3], k;
    size_t n0 = (size_t)g->n[0], n1 = (size_t)g->n[1];
    if (!per) return I;
    ijk[0] = (int)(I % n0);
    ijk[1] = (int)((I / n0) % n1);
    ijk[2] = (int)(I / (n0 * n1));
    for (k = 0; k < g->dim; ++k)
        if (per->period[k] > 0) ijk[k] = gk__hy_wrap_index(ijk[k], per->ghost[k], per->period[k]);
    return (size_t)ijk[0] + n0 * ((size_t)ijk[1] + n1 * (size_t)ijk[2]);
}

static int gk__hy_has_period(const gk_hybrid_periodic *per) {
    return per && (per->period[0] > 0 || per->period[1] > 0 || per->period[2] > 0);
}

/* when only x wraps and it has at most GK__HY_MAXCOPY copy columns: those
 * columns, ascending, and their home columns (the same in every row) */
#define GK__HY_MAXCOPY 64
static int gk__hy_x_copies(const gk_mpm_grid *g, const gk_hybrid_periodic *per, int *col, int *hom, int *nc) {
    int i, a;
    if (per->period[0] <= 0) return 0;
    for (a = 1; a < g->dim; ++a)
        if (per->period[a] > 0) return 0;
    *nc = 0;
    for (i = 0; i < g->n[0]; ++i) {
        int w;
        if (i >= per->ghost[0] && i - per->ghost[0] < per->period[0]) continue; /* a home column */
        w = gk__hy_wrap_index(i, per->ghost[0], per->period[0]);
        if (w == i) continue;
        if (*nc == GK__HY_MAXCOPY) return 0;
        col[*nc] = i;
        hom[*nc] = w;
        ++*nc;
    }
    return 1;
}

/* visit every copy node I with its home H, in index order */
#define GK__HY_FOR_COPIES(g, per, BODY)                                                                     \
    do {                                                                                                    \
        int gk__i, gk__j, gk__k, gk__q, gk__nc = 0, gk__col[GK__HY_MAXCOPY], gk__hom[GK__HY_MAXCOPY];       \
        if (gk__hy_x_copies(g, per, gk__col, gk__hom, &gk__nc)) {                                           \
            for (gk__k = 0; gk__k < (g)->n[2]; ++gk__k)                                                     \
                for (gk__j = 0; gk__j < (g)->n[1]; ++gk__j) {                                               \
                    size_t gk__row =                                                                        \
                        (size_t)(g)->n[0] * ((size_t)gk__j + (size_t)(g)->n[1] * (size_t)gk__k);            \
                    for (gk__q = 0; gk__q < gk__nc; ++gk__q) {                                              \
                        size_t I = gk__row + (size_t)gk__col[gk__q], H = gk__row + (size_t)gk__hom[gk__q];  \
                        BODY;                                                                               \
                    }                                                                                       \
                }                                                                                           \
            break;                                                                                          \
        }                                                                                                   \
        for (gk__k = 0; gk__k < (g)->n[2]; ++gk__k)                                                         \
            for (gk__j = 0; gk__j < (g)->n[1]; ++gk__j)                                                     \
                for (gk__i = 0; gk__i < (g)->n[0]; ++gk__i) {                                               \
                    int gk__c[3], gk__a, gk__copy = 0;                                                      \
                    size_t I, H;                                                                            \
                    gk__c[0] = gk__i;                                                                       \
                    gk__c[1] = gk__j;                                                                       \
                    gk__c[2] = gk__k;                                                                       \
                    for (gk__a = 0; gk__a < (g)->dim; ++gk__a)                                              \
                        if ((per)->period[gk__a] > 0) {                                                     \
                            int gk__w =                                                                     \
                                gk__hy_wrap_index(gk__c[gk__a], (per)->ghost[gk__a], (per)->period[gk__a]); \
                            gk__copy |= gk__w != gk__c[gk__a];                                              \
                            gk__c[gk__a] = gk__w;                                                           \
                        }                                                                                   \
                    if (!gk__copy) continue;                                                                \
                    I = (size_t)gk__i +                                                                     \
                        (size_t)(g)->n[0] * ((size_t)gk__j + (size_t)(g)->n[1] * (size_t)gk__k);            \
                    H = (size_t)gk__c[0] +                                                                  \
                        (size_t)(g)->n[0] * ((size_t)gk__c[1] + (size_t)(g)->n[1] * (size_t)gk__c[2]);      \
                    BODY;                                                                                   \
                }                                                                                           \
    } while (0)

GKDEF void gk_hybrid_fold(const gk_mpm_grid *g, const gk_hybrid_periodic *per, double *a) {
    if (!gk__hy_has_period(per)) return;
    GK__HY_FOR_COPIES(g, per, {
        a[H] += a[I];
        a[I] = 0.0;
    });
}

GKDEF void gk_hybrid_sync(const gk_mpm_grid *g, const gk_hybrid_periodic *per, double *a) {
    if (!gk__hy_has_period(per)) return;
    GK__HY_FOR_COPIES(g, per, a[I] = a[H]);
}

GKDEF void gk_hybrid_fold_momentum(gk_mpm_grid *g, const gk_hybrid_periodic *per) {
    size_t I;
    int k;
    if (!gk__hy_has_period(per)) return;
    gk_hybrid_fold(g, per, g->m);
    for (k = 0; k < g->dim; ++k) {
        gk_hybrid_fold(g, per, g->p[k]);
        for (I = 0; I < g->nnode; ++I) g->v[k][I] = g->m[I] > g->mass_min ? g->p[k][I] / g->m[I] : 0.0;
        gk_hybrid_sync(g, per, g->v[k]);
    }
}

GKDEF void gk_hybrid_fold_force(gk_mpm_grid *g, const gk_hybrid_periodic *per) {
    int k;
    if (!gk__hy_has_period(per)) return;
    for (k = 0; k < g->dim; ++k) {
        gk_hybrid_fold(g, per, g->fint[k]);
        gk_hybrid_fold(g, per, g->fext[k]);
    }
}

GKDEF void gk_hybrid_sync_velocity(gk_mpm_grid *g, const gk_hybrid_periodic *per) {
    int k;
    if (!gk__hy_has_period(per)) return;
    for (k = 0; k < g->dim; ++k) {
        gk_hybrid_sync(g, per, g->v[k]);
        gk_hybrid_sync(g, per, g->vn[k]);
    }
}

GKDEF void gk_hybrid_wrap_points(const gk_mpm_grid *g, const gk_hybrid_periodic *per, gk_mpm_points *pts,
                                 double *const follow[3]) {
    int k, p;
    if (!gk__hy_has_period(per)) return;
    for (k = 0; k < g->dim; ++k) {
        double lo, L;
        if (per->period[k] <= 0) continue;
        lo = g->origin[k] + g->h * per->ghost[k];
        L = g->h * per->period[k];
        for (p = 0; p < pts->n; ++p) {
            double x = pts->x[k][p];
            if (x < lo || x >= lo + L) {
                double x0 = x;
                x -= L * floor((x - lo) / L);
                if (x >= lo + L) x -= L; /* rounding of floor at the edge */
                pts->x[k][p] = x;
                if (follow && follow[k]) follow[k][p] += x - x0;
            }
        }
    }
}

GKDEF gk_result gk_hybrid_periodic_check(const gk_mpm_grid *g, const gk_hybrid_periodic *per, gk_mpm_basis b,
                                         gk_err *err) {
    /* node layers a support reaches beyond the home range on each side */
    int k, need = b == GK_MPM_LINEAR ? 0 : (b == GK_MPM_CUBIC ? 2 : 1);
    if (!per) return GK_OK;
    for (k = 0; k < 3; ++k) {
        if (per->period[k] <= 0) continue;
        if (k >= g->dim) return gk_err_set(err, GK_ERR_ARG, "periodic axis %d of a %dD grid", k, g->dim);
        if (per->ghost[k] < need || per->ghost[k] + per->period[k] + need > g->n[k] - 1)
            return gk_err_set(
                err, GK_ERR_ARG,
                "periodic axis %d: %d home nodes from node %d leave fewer than the %d ghost layers "
                "the basis needs inside the %d nodes",
                k, per->period[k], per->ghost[k], need, g->n[k]);
    }
    return GK_OK;
}

/* ---------------------------------------------------------- USF, split */
GKDEF gk_result gk_hybrid_mpm_predict(gk_mpm_grid *g, const gk_hybrid_periodic *per, gk_mpm_points *pts,
                                      const gk_mpm_def *d, double dt, gk_mpm_stress_fn stress, void *user,
                                      gk_err *err) {
    gk_result r;
    if (d && d->scheme != GK_MPM_USF)
        return gk_err_set(err, GK_ERR_UNSUPPORTED, "the hybrid step is USF (scheme %d given)",
                          (int)d->scheme);
    if ((r = gk_mpm_p2g(g, pts, d, GK_MPM_P2G_MOMENTUM, err))) return r;
    gk_hybrid_fold_momentum(g, per);
    if ((r = gk_mpm_g2p(g, pts, d, dt, GK_MPM_G2P_GRADIENT_OLD, err))) return r;
    if (stress && (r = stress(pts, dt, user, err))) return r;
    if ((r = gk_mpm_p2g(g, pts, d, GK_MPM_P2G_FORCE, err))) return r;
    gk_hybrid_fold_force(g, per);
    if ((r = gk_mpm_grid_update(g, d, dt, err))) return r;
    gk_hybrid_sync_velocity(g, per);
    return GK_OK;
}

GKDEF gk_result gk_hybrid_mpm_finish(gk_mpm_grid *g, const gk_hybrid_periodic *per, gk_mpm_points *pts,
                                     gk_hybrid_cont *c, const gk_mpm_def *d, double dt, gk_err *err) {
    gk_result r;
    double *follow[3] = {NULL, NULL, NULL};
    if (c && c->n == pts->n) {
        follow[0] = c->X0[0];
        follow[1] = c->X0[1];
    }
    gk_hybrid_sync_velocity(g, per);
    if ((r = gk_mpm_g2p(g, pts, d, dt, GK_MPM_G2P_VELOCITY | GK_MPM_G2P_POSITION, err))) return r;
    gk_hybrid_wrap_points(g, per, pts, follow);
    gk_mpm_bodies_advance(g->body, g->nbody, dt);
    return GK_OK;
}

/* ---------------------------------------------------------- continuum */
static void gk__hy_cont_free_arrays(gk_hybrid_cont *c) {
    int k;
    for (k = 0; k < 3; ++k) gk_free(&c->alloc, c->X0[k]);
    gk_free(&c->alloc, c->Phi);
    gk_free(&c->alloc, c->ep);
    gk_free(&c->alloc, c->rate);
    gk_free(&c->alloc, c->zone);
    gk_free(&c->alloc, c->dpk);
}

GKDEF gk_result gk_hybrid_cont_init(gk_hybrid_cont *out, const gk_mpm_points *pts, const gk_mpm_dp *dp,
                                    double Phi0, const gk_allocator *alloc, gk_err *err) {
    gk_hybrid_cont c;
    int p, k, n = pts ? pts->n : 0, bad = 0;
    size_t nn;
    if (!out || !pts || !dp)
        return gk_err_set(err, GK_ERR_ARG, "NULL continuum, points or Drucker-Prager def");
    if (pts->dim != 2)
        return gk_err_set(err, GK_ERR_UNSUPPORTED, "the hybrid continuum is 2D (points are %dD)", pts->dim);
    if (!(Phi0 > 0.0 && Phi0 < 1.0))
        return gk_err_set(err, GK_ERR_ARG, "packing fraction %g (must be in (0, 1))", Phi0);
    if (!(dp->chi > 0.0) || !(dp->xi >= 0.0) || !(dp->Phi_cs > 0.0 && dp->Phi_cs < 1.0) ||
        !isfinite(dp->tan_phi_cs))
        return gk_err_set(
            err, GK_ERR_ARG,
            "critical-state parameters chi = %g, xi = %g, Phi_cs = %g, tan phi_cs = %g (need chi > 0, "
            "xi >= 0, 0 < Phi_cs < 1)",
            dp->chi, dp->xi, dp->Phi_cs, dp->tan_phi_cs);
    if (dp->tan_phi_cs + (Phi0 - dp->Phi_cs) * dp->chi < 0.0) /* eq 7, as gk_mpm_dp_update */
        return gk_err_set(err, GK_ERR_ARG,
                          "packing fraction %g: eq 7 gives a negative friction angle below Phi_cs - tan "
                          "phi_cs / chi = %g",
                          Phi0, dp->Phi_cs - dp->tan_phi_cs / dp->chi);
    memset(&c, 0, sizeof c);
    if (alloc) c.alloc = *alloc;
    nn = (size_t)(n > 0 ? n : 1);
    for (k = 0; k < 2; ++k)
        if (!(c.X0[k] = (double *)gk_alloc(&c.alloc, nn * sizeof(double)))) bad = 1;
    c.Phi = (double *)gk_alloc(&c.alloc, nn * sizeof(double));
    c.ep = (double *)gk_alloc(&c.alloc, 3 * nn * sizeof(double));
    c.rate = (double *)gk_alloc(&c.alloc, nn * sizeof(double));
    c.zone = (unsigned char *)gk_alloc(&c.alloc, nn);
    c.dpk = (double *)gk_alloc(&c.alloc, 4 * nn * sizeof(double));
    if (bad || !c.Phi || !c.ep || !c.rate || !c.zone || !c.dpk) {
        gk__hy_cont_free_arrays(&c);
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for the state of %d points", n);
    }
    for (p = 0; p < n; ++p) {
        c.X0[0][p] = pts->x[0][p];
        c.X0[1][p] = pts->x[1][p];
        c.Phi[p] = Phi0;
        c.ep[3 * p] = c.ep[3 * p + 1] = c.ep[3 * p + 2] = 0.0;
        c.rate[p] = 0.0;
        c.zone[p] = GK_ZONE_CONTINUUM;
        c.dpk[4 * p] = NAN;
    }
    c.n = c.cap = n;
    c.dp = *dp;
    *out = c;
    return GK_OK;
}

GKDEF void gk_hybrid_cont_free(gk_hybrid_cont *c) {
    if (!c) return;
    gk__hy_cont_free_arrays(c);
    memset(c, 0, sizeof *c);
}

GKDEF gk_result gk_hybrid_dp_stress(gk_mpm_points *pts, double dt, void *user, gk_err *err) {
    gk_hybrid_cont *c = (gk_hybrid_cont *)user;
    int p;
    double gmax = 0.0;
    if (!c || c->n != pts->n)
        return gk_err_set(err, GK_ERR_STATE, "continuum state has %d points, the MPM %d", c ? c->n : -1,
                          pts->n);
    if (memcmp(&c->dpk_of, &c->dp, sizeof c->dp)) { /* the model changed: every point's eq 7 anew */
        for (p = 0; p < pts->n; ++p) c->dpk[4 * p] = NAN;
        c->dpk_of = c->dp;
    }
    for (p = 0; p < pts->n; ++p) {
        double dH[9], D[9], tr, dd = 0.0;
        gk_mpm_dp_info info;
        gk_result r;
        int i, j;
        gk_mpm_point_dh(pts, p, dt, dH);
        {
            /* the objective rotation R = exp(dt W) in closed form (2D), then the
             * symmetric dH alone to the return map (whose own rotation then has
             * nothing to do): the same update without a general exponential */
            double th = 0.5 * (dH[3] - dH[1]), cs = cos(th), sn = sin(th), *sg = pts->sigma + 9 * p;
            double a = sg[0], b = 0.5 * (sg[1] + sg[3]), d = sg[4];
            if (th != 0.0) {
                sg[0] = cs * cs * a - 2.0 * cs * sn * b + sn * sn * d;
                sg[4] = sn * sn * a + 2.0 * cs * sn * b + cs * cs * d;
                sg[1] = sg[3] = cs * sn * (a - d) + (cs * cs - sn * sn) * b;
            }
            dH[1] = dH[3] = 0.5 * (dH[1] + dH[3]);
        }
        gk_m3_sym(pts->L + 9 * p, D);
        tr = 0.5 * (D[0] + D[4]);
        for (i = 0; i < 2; ++i)
            for (j = 0; j < 2; ++j) {
                double e = D[3 * i + j] - (i == j ? tr : 0.0);
                dd += e * e;
            }
        if (sqrt(2.0 * dd) > gmax) gmax = sqrt(2.0 * dd);
        {
            double *k = c->dpk + 4 * p;
            gk_mpm_dp at = c->dp;
            if (memcmp(k, &c->Phi[p], sizeof(double))) { /* eq 7 anew: Phi moved (a plastic step) */
                r = gk_mpm_dp_at(&c->dp, 2, c->Phi[p], &at, err);
                if (r) return gk__hybrid_prefix(err, r, "point", p);
                k[0] = c->Phi[p];
                k[1] = at.eta;
                k[2] = at.etabar;
                k[3] = at.zeta;
            }
            at.eta = k[1];
            at.etabar = k[2];
            at.zeta = k[3];
            r = gk_mpm_dp_update_at(&at, 2, dH, pts->sigma + 9 * p, &c->Phi[p], &info, err);
        }
        if (r) return gk__hybrid_prefix(err, r, "point", p);
        c->ep[3 * p] += info.deps_p[0];
        c->ep[3 * p + 1] += info.deps_p[4];
        c->ep[3 * p + 2] += info.deps_p[1];
        c->rate[p] = gk_m3_norm(info.deps_p) / dt;
    }
    c->gdot_max = gmax;
    return GK_OK;
}

static void gk__hy_compact(double *a, int stride, int n, const unsigned char *keep) {
    int p, q = 0, k;
    if (!a) return;
    for (p = 0; p < n; ++p)
        if (keep[p]) {
            if (q != p)
                for (k = 0; k < stride; ++k) a[(size_t)stride * q + k] = a[(size_t)stride * p + k];
            ++q;
        }
}

static void gk__hy_compact_u8(unsigned char *a, int n, const unsigned char *keep) {
    int p, q = 0;
    if (!a) return;
    for (p = 0; p < n; ++p)
        if (keep[p]) a[q++] = a[p];
}

GKDEF int gk_hybrid_points_keep(gk_mpm_points *P, gk_hybrid_cont *c, const unsigned char *keep, int nextra,
                                double *const *extra, const int *stride) {
    int n = P->n, q = 0, p, k, e;
    for (k = 0; k < P->dim; ++k) {
        gk__hy_compact(P->x[k], 1, n, keep);
        gk__hy_compact(P->v[k], 1, n, keep);
        gk__hy_compact(P->fext[k], 1, n, keep);
    }
    gk__hy_compact(P->m, 1, n, keep);
    gk__hy_compact(P->vol0, 1, n, keep);
    gk__hy_compact(P->vol, 1, n, keep);
    gk__hy_compact(P->lp, 1, n, keep);
    gk__hy_compact(P->F, 9, n, keep);
    gk__hy_compact(P->L, 9, n, keep);
    gk__hy_compact(P->sigma, 9, n, keep);
    gk__hy_compact(P->C, 9, n, keep);
    if (c && c->n == n) {
        for (k = 0; k < 2; ++k) gk__hy_compact(c->X0[k], 1, n, keep);
        gk__hy_compact(c->Phi, 1, n, keep);
        gk__hy_compact(c->ep, 3, n, keep);
        gk__hy_compact(c->rate, 1, n, keep);
        gk__hy_compact_u8(c->zone, n, keep);
        gk__hy_compact(c->dpk, 4, n, keep);
    }
    for (e = 0; e < nextra; ++e) gk__hy_compact(extra[e], stride[e], n, keep);
    for (p = 0; p < n; ++p) q += keep[p] != 0;
    P->n = q;
    if (c && c->n == n) c->n = q;
    return q;
}

/* ---------------------------------------------------------- node fields */
GKDEF gk_result gk_hybrid_rasterize(const gk_mpm_grid *g, const gk_hybrid_periodic *per, gk_mpm_basis basis,
                                    double lp, int n, const double *const x[3], const double *m,
                                    const double *val, int ncomp, const unsigned char *skip, double *num,
                                    double *den, gk_err *err) {
    size_t nn = g->nnode;
    int p, q, c, ns;
    int32_t node[GK_MPM_MAX_STENCIL];
    double w[GK_MPM_MAX_STENCIL];
    if (ncomp < 0 || ncomp > 9) return gk_err_set(err, GK_ERR_ARG, "%d components (0..9)", ncomp);
    /* validate every position first: nothing is written on failure */
    for (p = 0; p < n; ++p) {
        double xx[3];
        gk_result r;
        if (skip && skip[p]) continue;
        xx[0] = x[0][p];
        xx[1] = x[1][p];
        xx[2] = g->dim == 3 ? x[2][p] : 0.0;
        if (!(m[p] >= 0.0) || !isfinite(m[p]))
            return gk_err_set(err, GK_ERR_MASS, "entry %d: mass %g", p, m[p]);
        if ((r = gk_mpm_shape_values(g, basis, xx, lp, &ns, node, w, err)))
            return gk__hybrid_prefix(err, r, "entry", p);
    }
    memset(den, 0, nn * sizeof(double));
    if (val) memset(num, 0, (size_t)ncomp * nn * sizeof(double));
    for (p = 0; p < n; ++p) {
        double xx[3];
        if (skip && skip[p]) continue;
        xx[0] = x[0][p];
        xx[1] = x[1][p];
        xx[2] = g->dim == 3 ? x[2][p] : 0.0;
        gk_mpm_shape_values(g, basis, xx, lp, &ns, node, w, NULL);
        for (q = 0; q < ns; ++q) {
            double wm = w[q] * m[p];
            if (w[q] == 0.0) continue;
            den[node[q]] += wm;
            if (val)
                for (c = 0; c < ncomp; ++c)
                    num[(size_t)c * nn + (size_t)node[q]] += wm * val[(size_t)ncomp * p + c];
        }
    }
    gk_hybrid_fold(g, per, den);
    gk_hybrid_sync(g, per, den);
    if (val)
        for (c = 0; c < ncomp; ++c) {
            gk_hybrid_fold(g, per, num + (size_t)c * nn);
            gk_hybrid_sync(g, per, num + (size_t)c * nn);
        }
    return GK_OK;
}

GKDEF int gk_hybrid_interp(const gk_mpm_grid *g, const gk_hybrid_periodic *per, const double *field,
                           int ncomp, const double *den, const double x[3], double *out) {
    double xi[2], wsum = 0.0, acc[9];
    int b[2], a, bb, c, k;
    size_t nn = g->nnode;
    if (g->dim != 2) return 0;
    for (k = 0; k < 2; ++k) {
        xi[k] = (x[k] - g->origin[k]) * g->inv_h;
        b[k] = (int)floor(xi[k]);
        if (per && per->period[k] > 0) continue;
        if (b[k] < 0) b[k] = 0;
        if (b[k] > g->n[k] - 2) b[k] = g->n[k] - 2;
    }
    for (c = 0; c < ncomp; ++c) acc[c] = 0.0;
    for (bb = 0; bb < 2; ++bb)
        for (a = 0; a < 2; ++a) {
            int ij[2] = {b[0] + a, b[1] + bb};
            double w = (1.0 - fabs(xi[0] - ij[0])) * (1.0 - fabs(xi[1] - ij[1]));
            size_t I;
            for (k = 0; k < 2; ++k)
                if (per && per->period[k] > 0)
                    ij[k] = gk__hy_wrap_index(ij[k], per->ghost[k], per->period[k]);
            if (ij[0] < 0 || ij[0] >= g->n[0] || ij[1] < 0 || ij[1] >= g->n[1]) continue;
            if (w < 0.0) w = 0.0;
            I = (size_t)ij[0] + (size_t)g->n[0] * (size_t)ij[1];
            if (!(den[I] > 0.0) || w == 0.0) continue;
            wsum += w;
            for (c = 0; c < ncomp; ++c) acc[c] += w * field[(size_t)c * nn + I];
        }
    if (!(wsum > 0.0)) return 0;
    for (c = 0; c < ncomp; ++c) out[c] = acc[c] / wsum;
    return 1;
}

/* ---------------------------------------------------------- history */
GKDEF gk_result gk_hybrid_history_init(gk_hybrid_history *out, int n, int ncomp, int cap,
                                       const gk_allocator *alloc, gk_err *err) {
    gk_hybrid_history h;
    if (!out) return gk_err_set(err, GK_ERR_ARG, "NULL history");
    if (n < 0 || ncomp < 1 || cap < 2 || (double)n * ncomp * cap > 2e9)
        return gk_err_set(err, GK_ERR_ARG,
                          "history of %d x %d values, %d snapshots (need n >= 0, ncomp >= 1, cap >= 2)", n,
                          ncomp, cap);
    memset(&h, 0, sizeof h);
    if (alloc) h.alloc = *alloc;
    h.n = n;
    h.ncomp = ncomp;
    h.cap = cap;
    h.head = -1;
    h.t = (double *)gk_alloc(&h.alloc, (size_t)cap * sizeof(double));
    h.val =
        (double *)gk_alloc(&h.alloc, (size_t)cap * (size_t)(n > 0 ? n : 1) * (size_t)ncomp * sizeof(double));
    if (!h.t || !h.val) {
        gk_free(&h.alloc, h.t);
        gk_free(&h.alloc, h.val);
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for %d snapshots of %d values", cap, n * ncomp);
    }
    *out = h;
    return GK_OK;
}

GKDEF void gk_hybrid_history_free(gk_hybrid_history *h) {
    if (!h) return;
    gk_free(&h->alloc, h->t);
    gk_free(&h->alloc, h->val);
    memset(h, 0, sizeof *h);
}

GKDEF gk_result gk_hybrid_history_push(gk_hybrid_history *h, double t, const double *val, gk_err *err) {
    size_t sz = (size_t)h->n * (size_t)h->ncomp;
    if (!isfinite(t)) return gk_err_set(err, GK_ERR_NAN, "snapshot time is NaN");
    if (h->count > 0 && !(t > h->t[h->head]))
        return gk_err_set(err, GK_ERR_ARG, "snapshot time %g not after the newest %g", t, h->t[h->head]);
    h->head = (h->head + 1) % h->cap;
    h->t[h->head] = t;
    memcpy(h->val + (size_t)h->head * sz, val, sz * sizeof(double));
    if (h->count < h->cap) ++h->count;
    return GK_OK;
}

GKDEF int gk_hybrid_history_at(const gk_hybrid_history *h, double t, double *out) {
    size_t sz = (size_t)h->n * (size_t)h->ncomp, i;
    int lo, hi, oldest;
    if (h->count == 0) return -1;
    oldest = (h->head - h->count + 1 + h->cap) % h->cap;
    if (t <= h->t[oldest]) {
        memcpy(out, h->val + (size_t)oldest * sz, sz * sizeof(double));
        return t < h->t[oldest] ? 1 : 0;
    }
    if (t >= h->t[h->head]) {
        memcpy(out, h->val + (size_t)h->head * sz, sz * sizeof(double));
        return 0;
    }
    /* binary search over the age order 0 (oldest) .. count-1 (newest) */
    lo = 0;
    hi = h->count - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (h->t[(oldest + mid) % h->cap] <= t)
            lo = mid;
        else
            hi = mid;
    }
    {
        int a = (oldest + lo) % h->cap, b = (oldest + hi) % h->cap;
        double s = (t - h->t[a]) / (h->t[b] - h->t[a]);
        const double *va = h->val + (size_t)a * sz, *vb = h->val + (size_t)b * sz;
        for (i = 0; i < sz; ++i) out[i] = va[i] + s * (vb[i] - va[i]);
    }
    return 0;
}

GKDEF void gk_hybrid_history_keep(gk_hybrid_history *h, const unsigned char *keep) {
    int s, q = 0, p;
    for (s = 0; s < h->cap; ++s)
        gk__hy_compact(h->val + (size_t)s * (size_t)h->n * (size_t)h->ncomp, h->ncomp, h->n, keep);
    for (p = 0; p < h->n; ++p) q += keep[p] != 0;
    /* the snapshots are now packed with the new count: move each slot to its new place */
    if (q != h->n) {
        size_t oldsz = (size_t)h->n * (size_t)h->ncomp, newsz = (size_t)q * (size_t)h->ncomp;
        for (s = 1; s < h->cap; ++s)
            memmove(h->val + (size_t)s * newsz, h->val + (size_t)s * oldsz, newsz * sizeof(double));
    }
    h->n = q;
}

/* ---------------------------------------------------------- oracle */
/* neighbour of (i,j,k) along axis a by step s, wrapped; -1 if off the grid */
static long gk__hy_neighbour(const gk_mpm_grid *g, const gk_hybrid_periodic *per, const int ijk[3], int a,
                             int s) {
    int c[3], k;
    for (k = 0; k < 3; ++k) c[k] = ijk[k];
    c[a] += s;
    if (per && per->period[a] > 0) c[a] = gk__hy_wrap_index(c[a], per->ghost[a], per->period[a]);
    if (c[a] < 0 || c[a] >= g->n[a]) return -1;
    return (long)c[0] + (long)g->n[0] * ((long)c[1] + (long)g->n[1] * (long)c[2]);
}

GKDEF int gk_hybrid_oracle_flag(const gk_mpm_grid *g, const gk_hybrid_periodic *per,
                                const gk_hybrid_oracle_def *d, const double *rate, const double *recent,
                                const unsigned char *active, unsigned char *flag, double *H) {
    size_t I;
    int count = 0, dim = g->dim;
    double L = d->D50 > g->h ? d->D50 : g->h, thr = d->c0 / (L * L); /* min(c0/D50^2, c0/dX^2) */
    double ih2 = g->inv_h * g->inv_h;
    for (I = 0; I < g->nnode; ++I) {
        int ijk[3], a, ok = 1, di, dj, dk;
        double lap = 0.0, emax = 0.0, h = 0.0;
        flag[I] = 0;
        if (H) H[I] = 0.0;
        if (!active[I] || gk_hybrid_home(g, per, I) != I) continue;
        ijk[0] = (int)(I % (size_t)g->n[0]);
        ijk[1] = (int)((I / (size_t)g->n[0]) % (size_t)g->n[1]);
        ijk[2] = (int)(I / ((size_t)g->n[0] * (size_t)g->n[1]));
        for (a = 0; a < dim && ok; ++a) {
            long m = gk__hy_neighbour(g, per, ijk, a, -1), p = gk__hy_neighbour(g, per, ijk, a, +1);
            if (m < 0 || p < 0 || !active[m] || !active[p]) {
                ok = 0;
                break;
            }
            lap += (rate[m] + rate[p] - 2.0 * rate[I]) * ih2;
        }
        if (!ok) continue;
        /* the nodes of the cells incident to I: the 3^dim block around it */
        for (dk = (dim == 3 ? -1 : 0); dk <= (dim == 3 ? 1 : 0); ++dk)
            for (dj = -1; dj <= 1; ++dj)
                for (di = -1; di <= 1; ++di) {
                    int c[3] = {ijk[0] + di, ijk[1] + dj, ijk[2] + dk}, k;
                    size_t J;
                    for (k = 0; k < dim; ++k)
                        if (per && per->period[k] > 0)
                            c[k] = gk__hy_wrap_index(c[k], per->ghost[k], per->period[k]);
                    if (c[0] < 0 || c[0] >= g->n[0] || c[1] < 0 || c[1] >= g->n[1] || c[2] < 0 ||
                        c[2] >= g->n[2])
                        continue;
                    J = (size_t)c[0] + (size_t)g->n[0] * ((size_t)c[1] + (size_t)g->n[1] * (size_t)c[2]);
                    if (active[J] && rate[J] > emax) emax = rate[J];
                }
        if (emax > 0.0 && recent[I] > d->c1) h = fabs(lap) / emax;
        if (H) H[I] = h;
        if (h > thr) {
            flag[I] = 1;
            ++count;
        }
    }
    return count;
}

GKDEF gk_result gk_hybrid_oracle_init(gk_hybrid_oracle *out, const gk_hybrid_oracle_def *d, size_t nnode,
                                      const gk_allocator *alloc, gk_err *err) {
    gk_hybrid_oracle o;
    if (!out || !d) return gk_err_set(err, GK_ERR_ARG, "NULL oracle or def");
    if (!(d->c0 >= 0.0) || !(d->c1 >= 0.0) || !(d->cl > 0.0) || !(d->cg > 0.0) || !(d->D50 > 0.0) ||
        !isfinite(d->c0 + d->c1 + d->cl + d->cg + d->D50))
        return gk_err_set(
            err, GK_ERR_ARG,
            "oracle constants c0 = %g, c1 = %g, c_l = %g, c_g = %g, D50 = %g (need c0, c1 >= 0; c_l, "
            "c_g, D50 > 0)",
            d->c0, d->c1, d->cl, d->cg, d->D50);
    memset(&o, 0, sizeof o);
    if (alloc) o.alloc = *alloc;
    o.def = *d;
    o.nnode = nnode;
    o.flag = (unsigned char *)gk_alloc(&o.alloc, nnode ? nnode : 1);
    o.prev = (unsigned char *)gk_alloc(&o.alloc, nnode ? nnode : 1);
    o.H = (double *)gk_alloc(&o.alloc, (nnode ? nnode : 1) * sizeof(double));
    if (!o.flag || !o.prev || !o.H) {
        gk_free(&o.alloc, o.flag);
        gk_free(&o.alloc, o.prev);
        gk_free(&o.alloc, o.H);
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for an oracle of %lu nodes",
                          (unsigned long)nnode);
    }
    memset(o.flag, 0, nnode);
    memset(o.prev, 0, nnode);
    *out = o;
    return GK_OK;
}

GKDEF void gk_hybrid_oracle_free(gk_hybrid_oracle *o) {
    if (!o) return;
    gk_free(&o->alloc, o->flag);
    gk_free(&o->alloc, o->prev);
    gk_free(&o->alloc, o->H);
    memset(o, 0, sizeof *o);
}

GKDEF int gk_hybrid_oracle_step(gk_hybrid_oracle *o, const gk_mpm_grid *g, const gk_hybrid_periodic *per,
                                const double *rate, const double *recent, const unsigned char *active,
                                double t, double tau_g) {
    o->nflag = gk_hybrid_oracle_flag(g, per, &o->def, rate, recent, active, o->flag, o->H);
    if (!o->evaluated || memcmp(o->flag, o->prev, o->nnode) != 0) {
        memcpy(o->prev, o->flag, o->nnode);
        o->since = t;
        o->evaluated = 1;
    }
    return o->nflag > 0 && isfinite(tau_g) && t - o->since >= tau_g;
}

/* ---------------------------------------------------------- zones */
GKDEF double gk_hybrid_distance(const gk_mpm_grid *g, const gk_hybrid_periodic *per,
                                const unsigned char *flag, const double x[3]) {
    size_t I;
    double best = HUGE_VAL;
    for (I = 0; I < g->nnode; ++I) {
        double xi[3], d2 = 0.0;
        int k;
        if (!flag[I]) continue;
        gk_mpm_grid_node_position(g, I, xi);
        for (k = 0; k < g->dim; ++k) {
            double dx = x[k] - xi[k];
            if (per && per->period[k] > 0) {
                double L = g->h * per->period[k];
                dx -= L * floor(dx / L + 0.5);
            }
            d2 += dx * dx;
        }
        if (d2 < best) best = d2;
    }
    return best < HUGE_VAL ? sqrt(best) : HUGE_VAL;
}

/* ---------------------------------------------------------- training */
GKDEF gk_result gk_hybrid_train(gk_scene *sc, const unsigned char *boundary, const double *const u[2],
                                long nsteps, long relax, gk_err *err) {
    int p, n = sc->rve.n;
    double dt = sc->rve.dt, zero[3] = {0.0, 0.0, 0.0};
    gk_result r;
    if (sc->dim != 2) return gk_err_set(err, GK_ERR_UNSUPPORTED, "training is 2D");
    if (nsteps < 1 || relax < 0)
        return gk_err_set(err, GK_ERR_ARG, "training of %ld steps and %ld relaxation steps (need >= 1, >= 0)",
                          nsteps, relax);
    for (p = 0; p < n; ++p)
        if (boundary[p] && (!isfinite(u[0][p]) || !isfinite(u[1][p])))
            return gk_err_set(err, GK_ERR_NAN, "training displacement of grain %d is NaN", p);
    for (p = 0; p < n; ++p)
        if (boundary[p]) {
            double v[3];
            v[0] = u[0][p] / ((double)nsteps * dt);
            v[1] = u[1][p] / ((double)nsteps * dt);
            v[2] = 0.0;
            if ((r = gk_scene_prescribe(sc, p, v, zero)) != GK_OK)
                return gk_err_set(err, r, "training: %s", gk_scene_error(sc));
        }
    if ((r = gk_scene_step(sc, nsteps)) != GK_OK)
        return gk_err_set(err, r, "training: %s", gk_scene_error(sc));
    for (p = 0; p < n; ++p)
        if (boundary[p] && (r = gk_scene_prescribe(sc, p, zero, zero)) != GK_OK)
            return gk_err_set(err, r, "training: %s", gk_scene_error(sc));
    if (relax > 0 && (r = gk_scene_step(sc, relax)) != GK_OK)
        return gk_err_set(err, r, "training relaxation: %s", gk_scene_error(sc));
    for (p = 0; p < n; ++p)
        if (boundary[p] && (r = gk_scene_release(sc, p)) != GK_OK)
            return gk_err_set(err, r, "training: %s", gk_scene_error(sc));
    return GK_OK;
}

/* ---------------------------------------------------------- enrichment */
GKDEF gk_result gk_hybrid_enrich(gk_mpm_points *pts, gk_hybrid_cont *c, gk_scene *sc,
                                 const unsigned char *gzone, const double *const vg[2], double w, double t,
                                 int nextra, double *const *extra, const int *stride,
                                 gk_hybrid_enrich_report *rep_out, gk_err *err) {
    gk_hybrid_enrich_report rep;
    unsigned char *keep;
    int p, k, n = pts->n, ng = sc->rve.n;
    double md = 0.0, pdel[2] = {0.0, 0.0}, mg = 0.0, pg[2] = {0.0, 0.0}, s, msum = 0.0;
    gk_result r;
    if (pts->dim != 2 || sc->dim != 2) return gk_err_set(err, GK_ERR_UNSUPPORTED, "enrichment is 2D");
    if (!c || c->n != n) return gk_err_set(err, GK_ERR_STATE, "continuum state does not match the points");
    if (!(w > 0.0 && w < 1.0))
        return gk_err_set(err, GK_ERR_ARG, "partition weight %g (must be in (0, 1))", w);
    if (!(t > 0.0) || !isfinite(t)) return gk_err_set(err, GK_ERR_ARG, "disk thickness %g (must be > 0)", t);
    memset(&rep, 0, sizeof rep);
    for (p = 0; p < ng; ++p) {
        if (gzone[p] != GK_ZONE_DISCRETE && gzone[p] != GK_ZONE_OVERLAP)
            return gk_err_set(err, GK_ERR_ARG, "grain %d is in zone %d (only discrete or overlap grains)", p,
                              (int)gzone[p]);
        if (vg && (!isfinite(vg[0][p]) || !isfinite(vg[1][p])))
            return gk_err_set(err, GK_ERR_NAN, "continuum velocity at grain %d is NaN", p);
    }
    for (p = 0; p < n; ++p)
        if (c->zone[p] > GK_ZONE_DISCRETE)
            return gk_err_set(err, GK_ERR_ARG, "point %d has zone %d", p, (int)c->zone[p]);
    /* what leaves the continuum */
    for (p = 0; p < n; ++p) {
        double f = c->zone[p] == GK_ZONE_DISCRETE ? 1.0 : (c->zone[p] == GK_ZONE_OVERLAP ? w : 0.0);
        rep.mass_before += pts->m[p];
        for (k = 0; k < 2; ++k) rep.mom_before[k] += pts->m[p] * pts->v[k][p];
        md += f * pts->m[p];
        for (k = 0; k < 2; ++k) pdel[k] += f * pts->m[p] * pts->v[k][p];
    }
    for (p = 0; p < ng; ++p) {
        double f = gzone[p] == GK_ZONE_OVERLAP ? w : 1.0, m = sc->mass[p] / t;
        mg += f * m;
        for (k = 0; k < 2; ++k) pg[k] += f * m * (vg ? vg[k][p] : 0.0);
    }
    if (!(md > 0.0) || !(mg > 0.0))
        return gk_err_set(err, GK_ERR_STATE,
                          "nothing to swap: continuum mass %g, grain mass %g in the discrete zone", md, mg);
    s = md / mg;
    keep = (unsigned char *)gk_alloc(&pts->alloc, (size_t)(n > 0 ? n : 1));
    if (!keep) return gk_err_set(err, GK_ERR_ALLOC, "out of memory");
    /* grains: one mass factor, one velocity shift */
    rep.mass_scale = s;
    for (k = 0; k < 2; ++k) rep.dv[k] = (pdel[k] - s * pg[k]) / md;
    for (p = 0; p < ng; ++p) {
        double f = gzone[p] == GK_ZONE_OVERLAP ? w : 1.0, m = sc->mass[p], I = 1.0 / (double)sc->rve.Iinv[p];
        double v[3], wz[3];
        v[0] = (vg ? vg[0][p] : 0.0) + rep.dv[0];
        v[1] = (vg ? vg[1][p] : 0.0) + rep.dv[1];
        v[2] = 0.0;
        wz[0] = wz[1] = 0.0;
        wz[2] = sc->rve.w[2] ? (double)sc->rve.w[2][p] : 0.0;
        if ((r = gk_scene_set_mass(sc, p, f * s * m, f * s * I)) != GK_OK ||
            (r = gk_scene_set_velocity(sc, p, v, wz)) != GK_OK) {
            gk_free(&pts->alloc, keep);
            return gk_err_set(err, r, "enrichment: %s", gk_scene_error(sc));
        }
        if (gzone[p] == GK_ZONE_OVERLAP)
            ++rep.grains_overlap;
        else
            ++rep.grains_discrete;
    }
    /* points: overlap weighted, discrete deleted */
    for (p = 0; p < n; ++p) {
        keep[p] = c->zone[p] != GK_ZONE_DISCRETE;
        if (c->zone[p] == GK_ZONE_OVERLAP) {
            pts->m[p] *= 1.0 - w;
            pts->vol0[p] *= 1.0 - w;
            pts->vol[p] *= 1.0 - w;
            ++rep.points_overlap;
        }
        rep.points_deleted += !keep[p];
    }
    gk_hybrid_points_keep(pts, c, keep, nextra, extra, stride);
    gk_free(&pts->alloc, keep);
    /* totals after, in a fixed order */
    for (p = 0; p < pts->n; ++p) {
        msum += pts->m[p];
        for (k = 0; k < 2; ++k) rep.mom_after[k] += pts->m[p] * pts->v[k][p];
    }
    for (p = 0; p < ng; ++p) {
        double m = sc->mass[p] / t;
        msum += m;
        for (k = 0; k < 2; ++k) rep.mom_after[k] += m * (double)sc->rve.v[k][p];
    }
    rep.mass_after = msum;
    if (rep_out) *rep_out = rep;
    return GK_OK;
}

/* ---------------------------------------------------------- coupling */
GKDEF gk_result gk_hybrid_coupling_init(gk_hybrid_coupling *out, const gk_mpm_grid *g,
                                        const gk_allocator *alloc, gk_err *err) {
    gk_hybrid_coupling c;
    int k, bad = 0;
    size_t nn = g->nnode;
    if (g->dim != 2) return gk_err_set(err, GK_ERR_UNSUPPORTED, "the coupling is 2D");
    memset(&c, 0, sizeof c);
    if (alloc) c.alloc = *alloc;
    c.nnode = nn;
    c.md = (double *)gk_alloc(&c.alloc, nn * sizeof(double));
    for (k = 0; k < 2; ++k) {
        c.pd[k] = (double *)gk_alloc(&c.alloc, nn * sizeof(double));
        c.dv[k] = (double *)gk_alloc(&c.alloc, nn * sizeof(double));
        if (!c.pd[k] || !c.dv[k]) bad = 1;
    }
    if (bad || !c.md) {
        gk_hybrid_coupling_free(&c);
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for the coupling of %lu nodes",
                          (unsigned long)nn);
    }
    *out = c;
    return GK_OK;
}

GKDEF void gk_hybrid_coupling_free(gk_hybrid_coupling *c) {
    int k;
    if (!c) return;
    gk_free(&c->alloc, c->st);
    gk_free(&c->alloc, c->md);
    for (k = 0; k < 2; ++k) {
        gk_free(&c->alloc, c->pd[k]);
        gk_free(&c->alloc, c->dv[k]);
    }
    memset(c, 0, sizeof *c);
}

GKDEF gk_result gk_hybrid_couple(gk_hybrid_coupling *c, gk_mpm_grid *g, const gk_hybrid_periodic *per,
                                 gk_mpm_basis basis, double lp, gk_scene *sc, const double *const xpre[2],
                                 const unsigned char *coupled, const unsigned char *skip, double t, double dt,
                                 gk_hybrid_couple_report *rep_out, gk_err *err) {
    gk_hybrid_couple_report rep;
    size_t I, nn = g->nnode;
    int p, q, k, ng = sc->rve.n, nc = 0, i;
    double inv_t;
    if (c->nnode != nn || g->dim != 2 || sc->dim != 2)
        return gk_err_set(err, GK_ERR_ARG, "coupling scratch of %lu nodes for a grid of %lu (2D only)",
                          (unsigned long)c->nnode, (unsigned long)nn);
    if (!(t > 0.0) || !(dt > 0.0) || !isfinite(t + dt))
        return gk_err_set(err, GK_ERR_ARG, "thickness %g, time step %g (must be > 0)", t, dt);
    inv_t = 1.0 / t;
    memset(&rep, 0, sizeof rep);
    for (p = 0; p < ng; ++p) nc += coupled[p] != 0;
    if (nc > c->cap) {
        gk_hybrid_stencil *s2 =
            (gk_hybrid_stencil *)gk_alloc(&c->alloc, (size_t)nc * sizeof(gk_hybrid_stencil));
        if (!s2) return gk_err_set(err, GK_ERR_ALLOC, "out of memory for %d grain stencils", nc);
        gk_free(&c->alloc, c->st);
        c->st = s2;
        c->cap = nc;
    }
    /* every stencil first (nothing is written if a grain is off the grid) */
    for (p = 0, i = 0; p < ng; ++p) {
        double x[3];
        gk_hybrid_stencil *h;
        gk_result r;
        if (!coupled[p]) continue;
        x[0] = xpre[0][p];
        x[1] = xpre[1][p];
        x[2] = 0.0;
        h = &c->st[i++]; /* 2D: at most 4 x 4 nodes */
        if ((r = gk_mpm_shape_values(g, basis, x, lp, &h->n, h->node, h->w, err)))
            return gk__hybrid_prefix(err, r, "coupled grain", p);
    }
    memset(c->md, 0, nn * sizeof(double));
    for (k = 0; k < 2; ++k) {
        memset(c->pd[k], 0, nn * sizeof(double));
        memset(c->dv[k], 0, nn * sizeof(double));
    }
    /* grains to the nodes: mass at x^n, momentum with v^{n+1/2} */
    for (p = 0, i = 0; p < ng; ++p) {
        const gk_hybrid_stencil *st;
        double m, v0, v1, *md = c->md, *pd0 = c->pd[0], *pd1 = c->pd[1];
        if (!coupled[p]) continue;
        st = &c->st[i++];
        m = sc->mass[p] * inv_t;
        v0 = (double)sc->rve.v[0][p];
        v1 = (double)sc->rve.v[1][p];
        for (q = 0; q < st->n; ++q) {
            double wm = st->w[q] * m;
            int32_t J = st->node[q];
            if (st->w[q] == 0.0) continue;
            md[J] += wm;
            pd0[J] += wm * v0;
            pd1[J] += wm * v1;
        }
    }
    rep.grains = nc;
    gk_hybrid_fold(g, per, c->md);
    gk_hybrid_fold(g, per, c->pd[0]);
    gk_hybrid_fold(g, per, c->pd[1]);
    /* equalise the node velocities (home nodes only: copies hold no mass) */
    for (I = 0; I < nn; ++I) {
        double mc = g->m[I], md = c->md[I], dvm = 0.0;
        if (!(mc > g->mass_min) || !(md > 0.0) || (skip && skip[I])) continue;
        for (k = 0; k < 2; ++k) {
            double pc = mc * g->vn[k][I], pd = c->pd[k][I];
            double lam = (md * pc - mc * pd) / (mc + md), d = g->vn[k][I] - pd / md;
            dvm += d * d;
            g->vn[k][I] = (pc - lam) / mc;
            c->dv[k][I] = lam / md;
            rep.exchange[k] += lam;
        }
        if (sqrt(dvm) > rep.dv_max) rep.dv_max = sqrt(dvm);
        ++rep.nodes;
    }
    gk_hybrid_sync(g, per, c->dv[0]);
    gk_hybrid_sync(g, per, c->dv[1]);
    gk_hybrid_sync_velocity(g, per);
    /* FLIP correction of the grains and of their new positions */
    for (p = 0, i = 0; p < ng; ++p) {
        const gk_hybrid_stencil *st;
        const double *dv0 = c->dv[0], *dv1 = c->dv[1];
        double dv[2], a0 = 0.0, a1 = 0.0;
        if (!coupled[p]) continue;
        st = &c->st[i++];
        for (q = 0; q < st->n; ++q) {
            a0 += st->w[q] * dv0[st->node[q]];
            a1 += st->w[q] * dv1[st->node[q]];
        }
        dv[0] = a0;
        dv[1] = a1;
        for (k = 0; k < 2; ++k) {
            sc->rve.v[k][p] = (gk_real)((double)sc->rve.v[k][p] + dv[k]);
            sc->rve.s[k][p] += dt * dv[k] * sc->rve.cell.hinv[4 * k];
        }
    }
    if (rep_out) *rep_out = rep;
    return GK_OK;
}

/* ---------------------------------------------------------- Cundall strain */
/* the bin of v on axis k: wrapped on a periodic axis, clamped on another */
static int gk__hy_bin(const double *lo, const double *hi, const int *nb, const double *period, int k,
                      double v) {
    if (period && period[k] > 0.0)
        return ((int)floor((v - lo[k]) / period[k] * nb[k]) % nb[k] + nb[k]) % nb[k];
    return (int)gk_clamp(floor((v - lo[k]) / (hi[k] - lo[k] > 0.0 ? hi[k] - lo[k] : 1.0) * nb[k]), 0.0,
                         nb[k] - 1.0);
}

/* clips the convex polygon v (m vertices; edge k, from v[k] to v[k + 1],
 * labelled lab[k]) to the half-plane y . d <= |d|^2 / 2, the origin's side
 * of the bisector with a grain at d; the new edge is labelled c. Returns
 * the new vertex count, written to w and wl. */
static int gk__hy_clip(const double *v, const int *lab, int m, const double d[2], int c, double *w, int *wl) {
    double h = 0.5 * (d[0] * d[0] + d[1] * d[1]);
    int k, o = 0;
    for (k = 0; k < m; ++k) {
        const double *a = v + 2 * k, *b = v + 2 * ((k + 1) % m);
        double fa = a[0] * d[0] + a[1] * d[1] - h, fb = b[0] * d[0] + b[1] * d[1] - h;
        if (fa <= 0.0) {
            w[2 * o] = a[0], w[2 * o + 1] = a[1], wl[o++] = lab[k];
            if (fb > 0.0) { /* leaves: the clip line runs to where the polygon comes back */
                double t = fa / (fa - fb);
                w[2 * o] = a[0] + t * (b[0] - a[0]), w[2 * o + 1] = a[1] + t * (b[1] - a[1]), wl[o++] = c;
            }
        } else if (fb <= 0.0) { /* comes back on edge k */
            double t = fa / (fa - fb);
            w[2 * o] = a[0] + t * (b[0] - a[0]), w[2 * o + 1] = a[1] + t * (b[1] - a[1]), wl[o++] = lab[k];
        }
    }
    return o;
}

/* both Cundall strains: delaunay 0, the neighbours within radius; 1, the
 * Delaunay neighbours among those (Voronoi cell edges) */
static gk_result gk__hy_cundall(int n, const double *const X[2], const double *const x[2],
                                const double period[2], double radius, int delaunay, double *eps, int *nnb,
                                unsigned char *open_out, const gk_allocator *alloc, gk_err *err) {
    double lo[2] = {HUGE_VAL, HUGE_VAL}, hi[2] = {-HUGE_VAL, -HUGE_VAL}, c2 = radius * radius,
           half = radius / (2.0 * sqrt(2.0)), *cand = NULL, *poly = NULL;
    int nb[2], k, p, nbin, cap = 0, *lab = NULL;
    int32_t *head, *next;
    unsigned char *use = NULL;
    gk_allocator al;
    memset(&al, 0, sizeof al);
    if (alloc) al = *alloc;
    if (n < 1) return gk_err_set(err, GK_ERR_ARG, "%d grains", n);
    if (!(radius > 0.0) || !isfinite(radius))
        return gk_err_set(err, GK_ERR_ARG, "neighbour %s %g (must be > 0)", delaunay ? "reach" : "cutoff",
                          radius);
    for (p = 0; p < n; ++p)
        for (k = 0; k < 2; ++k) {
            if (!isfinite(X[k][p]) || !isfinite(x[k][p]))
                return gk_err_set(err, GK_ERR_NAN, "grain %d: position is NaN", p);
            if (X[k][p] < lo[k]) lo[k] = X[k][p];
            if (X[k][p] > hi[k]) hi[k] = X[k][p];
        }
    for (k = 0; k < 2; ++k) {
        double span = hi[k] - lo[k];
        if (period && period[k] > 0.0) {
            if (period[k] < 3.0 * radius)
                return gk_err_set(err, GK_ERR_ARG, "period %g below three times the neighbour %s %g",
                                  period[k], delaunay ? "reach" : "cutoff", radius);
            span = period[k];
        }
        nb[k] = (int)(span / radius);
        if (nb[k] < 1) nb[k] = 1;
        if (nb[k] > 4096) nb[k] = 4096;
    }
    nbin = nb[0] * nb[1];
    head = (int32_t *)gk_alloc(&al, (size_t)nbin * sizeof(int32_t));
    next = (int32_t *)gk_alloc(&al, (size_t)n * sizeof(int32_t));
    if (head && next) {
        int most = 0;
        for (k = 0; k < nbin; ++k) head[k] = -1;
        /* insert in descending order so each bin lists ascending indices */
        for (p = n - 1; p >= 0; --p) {
            int b = gk__hy_bin(lo, hi, nb, period, 0, X[0][p]) +
                    nb[0] * gk__hy_bin(lo, hi, nb, period, 1, X[1][p]);
            next[p] = head[b];
            head[b] = p;
        }
        for (k = 0; k < nbin; ++k) { /* the largest bin bounds a grain's candidates: nine bins */
            int cnt = 0, q;
            for (q = head[k]; q >= 0; q = next[q]) ++cnt;
            if (cnt > most) most = cnt;
        }
        cap = 9 * most;
        cand = (double *)gk_alloc(&al, 4 * (size_t)cap * sizeof(double));
        use = (unsigned char *)gk_alloc(&al, (size_t)cap);
        if (delaunay) {
            poly = (double *)gk_alloc(&al, 4 * ((size_t)cap + 5) * sizeof(double));
            lab = (int *)gk_alloc(&al, 2 * ((size_t)cap + 5) * sizeof(int));
        }
    }
    if (!head || !next || !cand || !use || (delaunay && (!poly || !lab))) {
        gk_free(&al, head);
        gk_free(&al, next);
        gk_free(&al, cand);
        gk_free(&al, use);
        gk_free(&al, poly);
        gk_free(&al, lab);
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory for %d grains", n);
    }
    for (p = 0; p < n; ++p) {
        int bx = gk__hy_bin(lo, hi, nb, period, 0, X[0][p]), by = gk__hy_bin(lo, hi, nb, period, 1, X[1][p]),
            dx, dy, cnt = 0, nc = 0, c;
        double AA[3] = {0.0, 0.0, 0.0}, B[4] = {0.0, 0.0, 0.0, 0.0}, det;
        /* the candidates within radius in the reference positions, bin by bin */
        for (dy = -1; dy <= 1; ++dy)
            for (dx = -1; dx <= 1; ++dx) {
                int cx = bx + dx, cy = by + dy, q;
                if (period && period[0] > 0.0) cx = (cx + nb[0]) % nb[0];
                if (period && period[1] > 0.0) cy = (cy + nb[1]) % nb[1];
                if (cx < 0 || cx >= nb[0] || cy < 0 || cy >= nb[1]) continue;
                /* a wrapped axis with fewer than 3 bins would visit a bin twice */
                if (nb[0] < 3 && dx != 0 && (period && period[0] > 0.0)) continue;
                if (nb[1] < 3 && dy != 0 && (period && period[1] > 0.0)) continue;
                for (q = head[cx + nb[0] * cy]; q >= 0; q = next[q]) {
                    double *o = cand + 4 * nc;
                    if (q == p) continue;
                    for (k = 0; k < 2; ++k) {
                        double a = X[k][q] - X[k][p], b = x[k][q] - x[k][p];
                        if (period && period[k] > 0.0) {
                            a -= period[k] * floor(a / period[k] + 0.5);
                            b -= period[k] * floor(b / period[k] + 0.5);
                        }
                        o[k] = a;         /* dX */
                        o[2 + k] = b - a; /* du */
                    }
                    if (o[0] * o[0] + o[1] * o[1] > c2) continue;
                    use[nc++] = (unsigned char)!delaunay;
                }
            }
        if (delaunay) {
            /* the Voronoi cell in a square of half-diagonal radius / 2: no grain beyond radius cuts it,
               so the clipped cell is exact; its edges of positive length are the Delaunay neighbours */
            double *v = poly, *w = poly + 2 * (cap + 5), *t, tol = 1e-9 * radius;
            int *vl = lab, *wl = lab + cap + 5, *tl, m = 4, open = 0;
            v[0] = -half, v[1] = -half, v[2] = half, v[3] = -half, v[4] = half, v[5] = half, v[6] = -half,
            v[7] = half;
            vl[0] = vl[1] = vl[2] = vl[3] = -1;
            for (c = 0; c < nc && m > 0; ++c) {
                m = gk__hy_clip(v, vl, m, cand + 4 * c, c, w, wl);
                t = v, v = w, w = t;
                tl = vl, vl = wl, wl = tl;
            }
            for (k = 0; k < m; ++k) {
                const double *a = v + 2 * k, *b = v + 2 * ((k + 1) % m);
                if (hypot(b[0] - a[0], b[1] - a[1]) <= tol) continue;
                if (vl[k] >= 0)
                    use[vl[k]] = 1;
                else
                    open = 1;
            }
            if (open_out) open_out[p] = (unsigned char)open;
        }
        for (c = 0; c < nc; ++c) {
            const double *dX = cand + 4 * c, *du = dX + 2;
            if (!use[c]) continue;
            AA[0] += dX[0] * dX[0];
            AA[1] += dX[0] * dX[1];
            AA[2] += dX[1] * dX[1];
            B[0] += du[0] * dX[0];
            B[1] += du[0] * dX[1];
            B[2] += du[1] * dX[0];
            B[3] += du[1] * dX[1];
            ++cnt;
        }
        if (nnb) nnb[p] = cnt;
        det = AA[0] * AA[2] - AA[1] * AA[1];
        if (cnt < 2 || !(det > 1e-12 * (AA[0] + AA[2]) * (AA[0] + AA[2]))) {
            for (k = 0; k < 4; ++k) eps[4 * p + k] = NAN;
            continue;
        }
        {
            /* grad u = B A^-1, A symmetric */
            double i00 = AA[2] / det, i01 = -AA[1] / det, i11 = AA[0] / det;
            double g00 = B[0] * i00 + B[1] * i01, g01 = B[0] * i01 + B[1] * i11;
            double g10 = B[2] * i00 + B[3] * i01, g11 = B[2] * i01 + B[3] * i11;
            double exy = 0.5 * (g01 + g10), mm = 0.5 * (g00 + g11), d0 = g00 - mm, d1 = g11 - mm;
            eps[4 * p] = g00;
            eps[4 * p + 1] = g11;
            eps[4 * p + 2] = exy;
            eps[4 * p + 3] = sqrt(2.0 * (d0 * d0 + d1 * d1 + 2.0 * exy * exy));
        }
    }
    gk_free(&al, head);
    gk_free(&al, next);
    gk_free(&al, cand);
    gk_free(&al, use);
    gk_free(&al, poly);
    gk_free(&al, lab);
    return GK_OK;
}

GKDEF gk_result gk_hybrid_cundall(int n, const double *const X[2], const double *const x[2],
                                  const double period[2], double cutoff, double *eps,
                                  const gk_allocator *alloc, gk_err *err) {
    return gk__hy_cundall(n, X, x, period, cutoff, 0, eps, NULL, NULL, alloc, err);
}

GKDEF gk_result gk_hybrid_cundall_delaunay(int n, const double *const X[2], const double *const x[2],
                                           const double period[2], double reach, double *eps, int *neighbours,
                                           unsigned char *open, const gk_allocator *alloc, gk_err *err) {
    return gk__hy_cundall(n, X, x, period, reach, 1, eps, neighbours, open, alloc, err);
}

/* ---------------------------------------------------------- band thickness */
static int gk__hy_cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : (x > y ? 1 : 0);
}

static double gk__hy_cross(const double *o, const double *a, const double *b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

static int gk__hy_cmp_xy(const void *a, const void *b) {
    const double *p = (const double *)a, *q = (const double *)b;
    if (p[0] != q[0]) return p[0] < q[0] ? -1 : 1;
    return p[1] < q[1] ? -1 : (p[1] > q[1] ? 1 : 0);
}

/* the band of the values at or above a percentile (count 0) or of the count largest */
static gk_result gk__hy_band(int n, const double *x, const double *y, const double *value, double percentile,
                             int count, double nsd, gk_hybrid_band_result *out, const gk_allocator *alloc,
                             gk_err *err) {
    gk_hybrid_band_result res;
    gk_allocator al;
    double *v, *pt, *hull, thr, c[2] = {0.0, 0.0}, sxx = 0.0, sxy = 0.0, syy = 0.0, dir[2], mean = 0.0,
                                sd = 0.0;
    int p, nv = 0, ns = 0, nk = 0, nh = 0, i, kk;
    memset(&al, 0, sizeof al);
    if (alloc) al = *alloc;
    if (!(percentile >= 0.0 && percentile < 100.0) || !(nsd > 0.0))
        return gk_err_set(err, GK_ERR_ARG,
                          "percentile %g (must be in [0, 100)), outlier cut %g sd (must be > 0)", percentile,
                          nsd);
    memset(&res, 0, sizeof res);
    v = (double *)gk_alloc(&al, (size_t)(n > 0 ? n : 1) * sizeof(double));
    pt = (double *)gk_alloc(&al, 2 * (size_t)(n > 0 ? n : 1) * sizeof(double));
    hull = (double *)gk_alloc(&al, 4 * (size_t)(n > 0 ? n : 1) * sizeof(double) + 4 * sizeof(double));
    if (!v || !pt || !hull) {
        gk_free(&al, v);
        gk_free(&al, pt);
        gk_free(&al, hull);
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory");
    }
    for (p = 0; p < n; ++p)
        if (isfinite(value[p]) && isfinite(x[p]) && isfinite(y[p])) v[nv++] = value[p];
    if (nv < 3 || count > nv) {
        gk_free(&al, v);
        gk_free(&al, pt);
        gk_free(&al, hull);
        if (nv < 3) return gk_err_set(err, GK_ERR_ARG, "%d finite values: too few for a band", nv);
        return gk_err_set(err, GK_ERR_ARG, "count %d above the %d finite values", count, nv);
    }
    qsort(v, (size_t)nv, sizeof(double), gk__hy_cmp_double);
    i = count > 0 ? nv - count : (int)floor(percentile / 100.0 * (nv - 1));
    thr = v[i];
    res.finite = nv;
    for (p = 0; p < n; ++p)
        if (isfinite(value[p]) && isfinite(x[p]) && isfinite(y[p]) && value[p] >= thr) {
            pt[2 * ns] = x[p];
            pt[2 * ns + 1] = y[p];
            ++ns;
        }
    res.selected = ns;
    /* far outliers first: beyond nsd times the RMS distance from the centroid
     * (a uniform band of length L has RMS L / sqrt 12: its ends stay) */
    for (;;) {
        double r2 = 0.0, lim;
        int m = 0;
        c[0] = c[1] = 0.0;
        for (i = 0; i < ns; ++i) {
            c[0] += pt[2 * i];
            c[1] += pt[2 * i + 1];
        }
        c[0] /= ns;
        c[1] /= ns;
        for (i = 0; i < ns; ++i)
            r2 += (pt[2 * i] - c[0]) * (pt[2 * i] - c[0]) + (pt[2 * i + 1] - c[1]) * (pt[2 * i + 1] - c[1]);
        lim = nsd * nsd * r2 / ns;
        for (i = 0; i < ns; ++i) {
            double d2 =
                (pt[2 * i] - c[0]) * (pt[2 * i] - c[0]) + (pt[2 * i + 1] - c[1]) * (pt[2 * i + 1] - c[1]);
            if (d2 <= lim) {
                pt[2 * m] = pt[2 * i];
                pt[2 * m + 1] = pt[2 * i + 1];
                ++m;
            }
        }
        if (m == ns || m < 3) break;
        ns = m;
    }
    /* principal direction of the rest */
    for (i = 0; i < ns; ++i) {
        double a = pt[2 * i] - c[0], b = pt[2 * i + 1] - c[1];
        sxx += a * a;
        sxy += a * b;
        syy += b * b;
    }
    {
        double ang = 0.5 * atan2(2.0 * sxy, sxx - syy);
        dir[0] = cos(ang);
        dir[1] = sin(ang);
    }
    /* signed distances from the principal line; drop beyond nsd sd */
    for (i = 0; i < ns; ++i) {
        double d = -(pt[2 * i] - c[0]) * dir[1] + (pt[2 * i + 1] - c[1]) * dir[0];
        v[i] = d;
        mean += d;
    }
    mean /= ns;
    for (i = 0; i < ns; ++i) sd += (v[i] - mean) * (v[i] - mean);
    sd = ns > 1 ? sqrt(sd / (ns - 1)) : 0.0;
    for (i = 0; i < ns; ++i)
        if (fabs(v[i] - mean) <= nsd * sd || sd == 0.0) {
            pt[2 * nk] = pt[2 * i];
            pt[2 * nk + 1] = pt[2 * i + 1];
            ++nk;
        }
    res.kept = nk;
    /* convex hull (monotone chain) */
    qsort(pt, (size_t)nk, 2 * sizeof(double), gk__hy_cmp_xy);
    for (i = 0; i < nk; ++i) {
        while (nh >= 2 && gk__hy_cross(hull + 2 * (nh - 2), hull + 2 * (nh - 1), pt + 2 * i) <= 0.0) --nh;
        hull[2 * nh] = pt[2 * i];
        hull[2 * nh + 1] = pt[2 * i + 1];
        ++nh;
    }
    for (i = nk - 2, kk = nh + 1; i >= 0; --i) {
        while (nh >= kk && gk__hy_cross(hull + 2 * (nh - 2), hull + 2 * (nh - 1), pt + 2 * i) <= 0.0) --nh;
        hull[2 * nh] = pt[2 * i];
        hull[2 * nh + 1] = pt[2 * i + 1];
        ++nh;
    }
    if (nh > 1) --nh; /* the last point repeats the first */
    /* minimum-area rectangle: one side on a hull edge */
    {
        double best = HUGE_VAL;
        res.thickness = 0.0;
        for (i = 0; i < nh; ++i) {
            const double *a = hull + 2 * i, *b = hull + 2 * ((i + 1) % nh);
            double ex = b[0] - a[0], ey = b[1] - a[1], L = sqrt(ex * ex + ey * ey), umin = HUGE_VAL,
                   umax = -HUGE_VAL, wmin = HUGE_VAL, wmax = -HUGE_VAL;
            int j;
            if (!(L > 0.0)) continue;
            ex /= L;
            ey /= L;
            for (j = 0; j < nh; ++j) {
                double u = (hull[2 * j] - a[0]) * ex + (hull[2 * j + 1] - a[1]) * ey;
                double w = -(hull[2 * j] - a[0]) * ey + (hull[2 * j + 1] - a[1]) * ex;
                if (u < umin) umin = u;
                if (u > umax) umax = u;
                if (w < wmin) wmin = w;
                if (w > wmax) wmax = w;
            }
            if ((umax - umin) * (wmax - wmin) < best) {
                double s1 = umax - umin, s2 = wmax - wmin;
                best = s1 * s2;
                res.thickness = s1 < s2 ? s1 : s2;
                res.length = s1 < s2 ? s2 : s1;
                res.angle = s1 >= s2 ? atan2(ey, ex) : atan2(ex, -ey);
                if (res.angle > 0.5 * GK_PI) res.angle -= GK_PI; /* a direction: (-pi/2, pi/2] */
                if (res.angle <= -0.5 * GK_PI) res.angle += GK_PI;
            }
        }
    }
    res.centre[0] = c[0];
    res.centre[1] = c[1];
    gk_free(&al, v);
    gk_free(&al, pt);
    gk_free(&al, hull);
    if (out) *out = res;
    return GK_OK;
}

GKDEF gk_result gk_hybrid_band(int n, const double *x, const double *y, const double *value,
                               double percentile, double nsd, gk_hybrid_band_result *out,
                               const gk_allocator *alloc, gk_err *err) {
    return gk__hy_band(n, x, y, value, percentile, 0, nsd, out, alloc, err);
}

GKDEF gk_result gk_hybrid_band_top(int n, const double *x, const double *y, const double *value, int count,
                                   double nsd, gk_hybrid_band_result *out, const gk_allocator *alloc,
                                   gk_err *err) {
    if (count < 3) return gk_err_set(err, GK_ERR_ARG, "count %d: a band needs at least 3 values", count);
    return gk__hy_band(n, x, y, value, 0.0, count, nsd, out, alloc, err);
}

/* ---------------------------------------------------------- boundaries */
GKDEF void gk_hybrid_bc_mask(const gk_mpm_grid *g, unsigned char *mask) {
    int f, bi, k, i, j, l, lo[3], hi[3];
    memset(mask, 0, g->nnode);
    for (f = 0; f < 2 * g->dim; ++f) {
        const gk_mpm_face *F = &g->face[f];
        int ax = f / 2;
        if (F->kind == GK_MPM_BC_FREE) continue;
        for (k = 0; k < 3; ++k) {
            lo[k] = 0;
            hi[k] = g->n[k] - 1;
        }
        if (f % 2)
            lo[ax] = g->n[ax] - F->layers;
        else
            hi[ax] = F->layers - 1;
        for (l = lo[2]; l <= hi[2]; ++l)
            for (j = lo[1]; j <= hi[1]; ++j)
                for (i = lo[0]; i <= hi[0]; ++i)
                    mask[(size_t)i + (size_t)g->n[0] * ((size_t)j + (size_t)g->n[1] * (size_t)l)] = 1;
    }
    for (bi = 0; bi < g->nbody; ++bi) {
        const gk_mpm_body *B = &g->body[bi];
        gk_mpm_body_nodes(g, B, lo, hi);
        for (l = lo[2]; l <= hi[2]; ++l)
            for (j = lo[1]; j <= hi[1]; ++j)
                for (i = lo[0]; i <= hi[0]; ++i) {
                    size_t I = (size_t)i + (size_t)g->n[0] * ((size_t)j + (size_t)g->n[1] * (size_t)l);
                    double x[3];
                    gk_mpm_grid_node_position(g, I, x);
                    if (gk_mpm_body_covers(g, B, x)) mask[I] = 1;
                }
    }
}

GKDEF void gk_hybrid_traction(gk_mpm_points *pts, int p, const double N0[2], double dl0, double pressure) {
    const double *F = pts->F + 9 * p;
    /* J F^-T N0 in 2D: cofactor of F applied to N0 */
    double n0 = F[4] * N0[0] - F[3] * N0[1], n1 = -F[1] * N0[0] + F[0] * N0[1];
    pts->fext[0][p] += -pressure * n0 * dl0;
    pts->fext[1][p] += -pressure * n1 * dl0;
}

#endif /* GK_HYBRID implementation */
