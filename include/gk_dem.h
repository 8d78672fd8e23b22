/* gk_dem.h - the periodic DEM RVE as a unit of work.             (grainkit v0.1)
 *
 * A gk_rve is a periodic packing of disks (2D) or spheres (3D) in a
 * deformable cell: give it a displacement-gradient increment and a number of
 * steps, get back the homogenised stress (and, through gk_homog.h, the
 * tangent). It is a plain struct the caller can keep in an array of
 * thousands (one per Gauss or material point).
 *
 * Packings (read, write, generate) are in gk_packing.h, included here.
 *
 * DO THIS in one C/C++ file:   #define GK_IMPLEMENTATION
 *                              #include "gk_dem.h"
 *
 *   gk_packing pk;  gk_err e;  gk_rve rve;
 *   gk_rve_def def = gk_rve_def_default();          // Guo & Zhao (2014) material
 *   if (gk_packing_read("rve400.txt", &pk, NULL, &e)) { puts(e.msg); return 1; }
 *   if (gk_rve_create(&rve, &def, &pk)) { puts(gk_rve_error(&rve)); gk_packing_free(&pk); return 1; }
 *   gk_packing_free(&pk);
 *   double dH[9] = {0, 1e-3, 0,  0, 0, 0,  0, 0, 0};  // H01 = du_x/dy
 *   if (gk_rve_deform(&rve, dH, 100)) puts(gk_rve_error(&rve));  // 100 DEM steps
 *   double sig[9]; gk_rve_stress(&rve, sig);        // Love stress, tension +, last step
 *   gk_rve_destroy(&rve);
 *
 * THE RVE CONTRACT
 *   gk_rve_deform(rve, dH, n)  applies the displacement-gradient increment
 *     dH (H_ij = du_i/dx_j) to the cell over n DEM steps. The path
 *     (def.path, gk_pcell.h) decides the end map: GK_PATH_CONSTANT_L (the
 *     default; the Guo & Zhao (2014) authors' code and YADE) runs the
 *     constant velocity gradient L = dH / (n dt) and ends at exp(dH) =
 *     I + dH + dH^2/2 + ...; GK_PATH_OBJECTIVE ends exactly at I + dH.
 *     det(I + dH) <= 0 is refused on both paths (GK_ERR_SINGULAR).
 *   ADMISSIBLE INCREMENT PER DEM STEP. The cell map E of one step (exp(dH/n)
 *     on the constant-L path) may change the overlap of a contact (i, j) by
 *     at most GK_RVE_STEP_OVERLAP_MAX (0.1) times the smaller radius:
 *       s(E) (r_min + r_max) <= 0.1 r_min,  s(E) = max_k |sigma_k(E) - 1|
 *     over the singular values sigma_k of E (a rotation costs nothing). For
 *     the 400-disk Guo & Zhao packing (r 3 to 7 mm) that is a stretch of 0.030 per
 *     step: a shear of 0.5 needs at least 9 steps. A larger increment is
 *     refused before anything moves, GK_ERR_ARG with the step count that
 *     would do; gk_rve_step applies the same bound to exp(L dt) (with a
 *     servo, to its max_rate). Refused rather than split into more steps
 *     because the step count is the loading rate (dt is fixed): sub-steps
 *     would silently change the time and the inertial number the caller
 *     asked for. gk_rve_deform_adaptive (gk_homog.h) picks the count from
 *     the inertial number instead. (The old behaviour, measured on the Guo & Zhao
 *     packing: 50 % shear in one step returned GK_OK with overlaps of 0.7 r.)
 *   gk_rve_stress after gk_rve_deform or gk_rve_step: the Love stress of the
 *     forces of the LAST step, computed at the positions before that step
 *     moved them (with the step's tangential increment): it lags the end
 *     state by about one step's increment, dH/n. With n = 1 that is most of
 *     dH (a shear of 1e-5 on the Guo & Zhao packing: sigma_xy 617 Pa before, 690
 *     after the deform, 782 after gk_rve_refresh). gk_rve_refresh gives the
 *     stress of the end state (one force pass, history unchanged).
 *     gk_rve_step_flags with GK_STEP_NO_STRESS makes none, for a caller
 *     that steps one step at a time and reads the stress seldom (a coupled
 *     scheme): it saves the stress pass (about a third of a 2D step) and,
 *     on one thread, the per-pair force stores. The stress, ncontacts,
 *     fc_mean and the per-pair forces (fc, tci, tcj: what
 *     gk_rve_contact_next, gk_rve_unbalanced, gk_scene_stress and
 *     gk_scene_stress_box read) then stay those of the last step that made
 *     them; the motion is the same to the bit. A servo makes the stress at
 *     every step regardless.
 *   gk_homog_tangent (gk_homog.h): the tangent at the current contacts.
 *   gk_rve_save / gk_rve_restore  the full state (positions, velocities,
 *     spins, cell, pair list with contact history) to and from caller
 *     memory, so an implicit driver can retry an increment bit for bit.
 *     A buffer is untrusted: restore checks every field (reals finite, the
 *     cell invertible and wide enough, pair lists sorted and in range,
 *     counters and flags in range, friction >= 0, the servo valid, and dt
 *     at most the critical step of this RVE at the state's own geometry)
 *     before it changes anything; a bad buffer is refused with a message
 *     and the RVE stays as it was.
 *
 * DRIVING THE CELL. One control yields the cell map of every step; the
 * drivers are thin wrappers around it:
 *   gk_rve_deform(dH, n)     the path I + dH split over n steps (def.path:
 *                            constant velocity gradient or objective)
 *   gk_rve_step(n)           the velocity gradient of gk_rve_set_velocity_
 *                            gradient; with a servo (gk_rve_set_servo) its
 *                            diagonal (and shear) follow the stress each step;
 *                            gk_rve_step_flags(n, GK_STEP_NO_STRESS) the same
 *                            without the stress of the last step
 *   gk_rve_relax(uf, every, max)   L = 0 in runs of `every` steps until the
 *                            unbalanced force ratio is at most uf
 *   gk_rve_consolidate       the isotropic servo until the target pressure
 *                            and balance hold (gk_consolidate_def)
 *   gk_rve_deform_adaptive   gk_rve_deform with the step count chosen by the
 *       physics: n = ceil(I_1 / I_max) clamped to [n_min, n_max], I_1 the
 *       inertial number (Guo & Zhao 2014 eq 20) of dH applied in one step at the
 *       RVE's current pressure (p <= 0: n_max), so the deformation runs at
 *       I <= I_max; then gk_rve_relax to uf_max with the steps left to n_max
 *       (reported as capped if the ratio is still above). Quasi-static by
 *       construction: more steps where p is low (near liquefaction), fewer
 *       where it is high. Bad input (NaN dH, bounds <= 0, n_min > n_max) ->
 *       GK_ERR_ARG before anything runs.
 *
 * KINEMATICS. Positions are stored as reduced coordinates s (double, also in
 * the float build) and x = h s; velocities v and spins w are the
 * FLUCTUATIONS about the affine field of the cell (translational L x and
 * rotational = spin of L). Per step with incremental cell map E (h <- E h):
 *   1. forces at (s_n, h_n) with v_{n-1/2}; the relative velocity of a pair
 *      includes the affine part G d, G = (E - I)/dt, and particles spin with
 *      the cell's spin plus their own fluctuation;
 *   2. h_{n+1} = E h_n (lattice reduction when too skewed);
 *   3. leap-frog: v += dt F/m (after local damping), s += h_{n+1}^-1 v dt.
 * The inertial term -m L v of the SLLOD equations is neglected (it is of
 * order I^2 in the quasi-static regime this code is for), as in YADE.
 *
 * LOCAL (NON-VISCOUS) DAMPING, factor alpha in [0, 1):
 *   GK_DAMP_COMPONENT (default; YADE, PFC, the Guo & Zhao 2014 data): per component
 *     a_k <- a_k (1 - alpha sign(a_k (v_k + a_k dt/2)))   (YADE cundallDamp2nd)
 *   GK_DAMP_VECTOR (Guo & Zhao 2014 eq 18): F_damp = -alpha |F| v/|v|, with the same
 *     mid-step velocity estimate v + a dt/2.
 *   Applied to the fluctuating velocity and spin.
 *
 * TIME STEP. gk_rve_dt_critical() is Guo & Zhao 2014 eq 19, dt_cr = sqrt(m_min /
 * k_n,max) (Hertz: k_n at twice the current largest overlap, at least 1e-3
 * r_min). dt = 0 in the def means 0.5 dt_cr; a dt above dt_cr is an error.
 * Hertz contacts stiffen with load, so the RVE re-checks dt_cr at every
 * list rebuild and stops with GK_ERR_DT when dt has become too large; for
 * loading that raises the stress several-fold choose dt_factor ~ 0.2.
 * Eq 19 is a one-contact estimate, NOT the stability limit of leap-frog on
 * a packing: with Z contacts per particle and rotation the limit is lower.
 * Equal disks on a hexagonal lattice (Z = 6, k_t = 0.8 k_n): 0.816 dt_cr
 * frictionless, 0.703 with friction and no rotation, 0.456 with rotation
 * (every disk spinning alike, omega^2 = 4 Z k_t / m) - so the default 0.5
 * is unstable there, and a consolidated packing of equal frictional disks
 * at 0.5 dt_cr shears 11 % stiff with 400x the kinetic energy; nothing
 * flags it (tests/test_extremes.c). The polydisperse Guo & Zhao packing (Z ~ 4)
 * is stable to 0.9 dt_cr. Equal spheres, face-centred cubic (Z = 12,
 * omega^2 = (10/3) Z k_t / m): 0.354 dt_cr. For equal or nearly equal
 * particles use dt_factor <= 0.4 (2D disks), <= 0.3 (dense 3D packings).
 *
 * MASSES. 3D spheres: m = rho 4/3 pi r^3, I = 2/5 m r^2. 2D disks, default
 * GK_MASS_CYLINDER: cylinders of thickness t (Guo & Zhao 2014: 0.1 m),
 * m = rho t pi r^2, I = m r^2 / 2, stress volume = cell area x t;
 * GK_MASS_SPHERE: sphere masses for the disks (as LAMMPS in 2D), stress volume
 * = area x t (t = 1 if 0: stress in N/m).
 *
 * TWO-LEVEL VERLET LISTS. The skin of the def builds the outer candidate list
 * from the cell grid; the kernels run over an inner list filtered from it
 * with a quarter of that skin (the whole skin with cohesion), so they do not
 * spend their time on pairs that are far from touching. Each list has its
 * own rebuild test (gk_cells.h); history moves between inner lists by pair.
 * Which pairs a list holds never changes a result (a pair outside contact
 * adds exactly zero), only the speed.
 *
 * ORDER AND DETERMINISM. Pairs are kept sorted by (i, j) (gk_cells.h). Each
 * step first computes every pair force (no write conflicts, SIMD), then sums
 * per particle in a fixed order: for particle p, the pairs where p is j in
 * ascending pair order, then the pairs where p is i. The result is identical
 * whatever the thread count, the SIMD width, or when the list is rebuilt.
 * Particles are stored in cell-list order for locality; gk_rve.id[] holds
 * each one's index in the input packing and output packings use input order.
 *
 * ERRORS are values: every call returns gk_result; gk_rve_error(rve) gives
 * the message. Bad input leaves the caller's data unchanged. A step that
 * produces a non-finite value returns GK_ERR_DIVERGED and marks the RVE
 * (restore a saved state to continue).
 *
 * BEYOND THE PERIODIC CELL (the seam gk_scene.h builds on; an RVE never
 * uses it and pays one test of a NULL pointer per step):
 *   gk_rve.hook    called in every step at GK_HOOK_PRE_FORCES (after a list
 *                  rebuild, before the pair forces), GK_HOOK_POST_FORCES (f, t
 *                  hold the contact sums; the hook may add external forces,
 *                  or zero a particle's f, t and set its v, w to prescribe
 *                  its motion: local damping of a zero force is zero) and
 *                  GK_HOOK_POST_STEP (after the leap-frog update). A non-OK
 *                  result stops the step with that result.
 *   gk_rve.hook_pairs  nonzero: every step keeps the per-pair forces and
 *                  torques (fc, tci, tcj) for a hook that reads them at
 *                  GK_HOOK_POST_FORCES; otherwise one thread on a long list
 *                  keeps them only at a step that makes the stress.
 *   gk_rve_reserve / gk_rve_append / gk_rve_remove   change the particle
 *                  count between steps: appended particles get the next
 *                  indices, removal keeps the survivors' order (so the pair
 *                  list stays sorted and every survivor keeps its contact
 *                  history); both force a list rebuild. id[] is the caller's.
 *                  gk_rve_update_totals after changing r[] or minv[] directly.
 *   gk_cells.open  open (non-periodic) axes of the cell lists (gk_cells.h).
 *
 * CONFIG: GK_REAL_FLOAT (see gk_base.h), GK_DEM_PAR_MIN (pairs below which
 * one RVE never uses threads, default 20000), GK_DEM_GATHER_MAX (pairs up to
 * which one thread stores the pair forces and gathers each particle's sum
 * instead of scattering them in the force loop: the same bits, and faster
 * while the pair arrays stay in the core's cache; default 32768; threads
 * gather 2D lists longer than that through a fixed number of branch-free
 * slots per particle, the same bits again), GK_DEM_FREC_MAX (3D particles
 * up to which that scattering loop of an AVX-512 double build adds into one
 * 64-byte record per particle instead of six arrays: the same bits, faster
 * while the records stay in the cache; default 32768), GK_DEM_GATHER_MAX_3D
 * (with those records, the smaller GK_DEM_GATHER_MAX for 3D lists; default
 * 8192 pairs: a 1000-sphere RVE still gathers, a 4096-sphere one scatters),
 * GK_RVE_STEP_OVERLAP_MAX (the admissible overlap change per DEM step as a
 * fraction of the smaller radius, default 0.1), GK_DEM_PHASE(phase, mark)
 * (a timing hook for profilers, empty by default: phase 0 the list rebuild,
 * 1 the pair forces, 2 the per-particle sums when they are gathered, 3 the
 * particle update; mark 0 when the stepping thread enters the phase, 1 when
 * it leaves it, 2 and 3 around each chunk of a threaded loop, called by the
 * thread that runs the chunk; bench_dem_step --phases). An RVE holds at most
 * GK_RVE_MAX_PARTICLES (2^26): its pair lists are int32.
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_DEM_H
#define GK_DEM_H

#include "gk_base.h"
#include "gk_cells.h"
#include "gk_contact.h"
#include "gk_pcell.h"
#include "gk_packing.h"

#ifndef GK_DEM_PAR_MIN
#define GK_DEM_PAR_MIN 20000
#endif
#ifndef GK_DEM_GATHER_MAX
#define GK_DEM_GATHER_MAX 32768
#endif
#ifndef GK_DEM_FREC_MAX
#define GK_DEM_FREC_MAX 32768
#endif
#ifndef GK_DEM_GATHER_MAX_3D
#define GK_DEM_GATHER_MAX_3D 8192
#endif
/* particles of one RVE: int32 pair lists hold up to ~30 candidates each */
#define GK_RVE_MAX_PARTICLES (1 << 26)
#ifndef GK_RVE_STEP_OVERLAP_MAX
#define GK_RVE_STEP_OVERLAP_MAX 0.1
#endif
#ifndef GK_DEM_PHASE
#define GK_DEM_PHASE(phase, mark) ((void)0)
#endif

/* ------------------------------------------------------------- RVE def */
typedef enum gk_damp_form { GK_DAMP_COMPONENT = 0, GK_DAMP_VECTOR = 1 } gk_damp_form;
typedef enum gk_mass_model { GK_MASS_CYLINDER = 0, GK_MASS_SPHERE = 1 } gk_mass_model;

#define GK_RVE_NO_ROTATION 1u    /* particles do not rotate (spin with the cell only) */
#define GK_RVE_SCALAR 2u         /* always use the scalar reference kernels          */
#define GK_RVE_WRAP 4u           /* accept positions outside the cell (wrap them)    */
#define GK_RVE_TRACK_ROTATION 8u /* 3D: accumulate each particle's rotation vector  */
/* flags of gk_rve_step_flags (and gk_scene_step_flags) */
#define GK_STEP_NO_STRESS 1u /* the last step makes no stress (see gk_rve_stress)  */
#define GK_RVE_DEF_COOKIE 0x52564531

typedef struct gk_rve_def {
    int cookie; /* set by gk_rve_def_default()                        */
    gk_material mat;
    double dt;        /* time step [s]; 0 -> dt_factor x critical           */
    double dt_factor; /* used when dt = 0; 0 -> 0.5                          */
    double skin;      /* Verlet skin [m]; 0 -> 0.1 x mean radius            */
    double thickness; /* 2D: disk thickness [m] (Guo & Zhao 2014: 0.1)             */
    gk_mass_model mass2d;
    double damping; /* local non-viscous damping alpha in [0, 1)          */
    gk_damp_form damping_form;
    gk_path_kind path; /* how gk_rve_deform splits dH over the steps         */
    unsigned flags;    /* GK_RVE_*                                           */
    int threads;       /* threads inside this RVE; <= 1: serial              */
    gk_allocator alloc;
} gk_rve_def;

typedef struct gk_rve {
    int dim, n;
    gk_rve_def def;
    gk_law_consts K;
    unsigned phys; /* GK_PHYS_* in use                                   */
    double dt, time, dt_crit;
    long step, rebuilds;
    gk_pcell cell;
    double L[9];          /* prescribed velocity gradient for gk_rve_step      */
    double G[9];          /* affine velocity gradient of the last step (E-I)/dt */
    double volume_factor; /* stress volume = det h x this (2D thickness)       */
    /* particles: n each, stored in cell-list order */
    double *s[3];  /* reduced positions                                  */
    double *s0[3]; /* reduced positions at the last list build           */
    gk_real *v[3]; /* fluctuating velocity [m/s]                         */
    gk_real *w[3]; /* fluctuating spin [rad/s] (2D: w[2] only)           */
    gk_real *f[3]; /* contact force sum of the last step [N]             */
    gk_real *t[3]; /* contact torque sum of the last step (2D: t[2])     */
    double *frec;  /* 3D, AVX-512 double: the scattering force loop's
                      records f0 f1 f2 t0 t1 t2 (8 doubles per particle),
                      all zero between steps                          */
    size_t frec_cap;
    gk_real *r, *minv, *Iinv;
    double *theta; /* 2D: accumulated rotation [rad] (incl. cell spin);
                                 3D with GK_RVE_TRACK_ROTATION: 3 n, the sum of the
                                 rotation increments (w + cell spin) dt per particle */
    int32_t *id;   /* index in the input packing                         */
    double rmin, rmax, mmin, solid_volume, mass_total;
    /* pairs, sorted by (i, j) */
    gk_pairlist pl;
    gk_real *ft[3];           /* tangential history (2D: ft[0] along t = (-ny, nx)) */
    gk_real *mr[3];           /* rolling history (2D: mr[2])                        */
    unsigned char *cs;        /* GK_CS_* state bits                                 */
    gk_real *fc[3];           /* force on j of each pair, last step                 */
    gk_real *tci[3], *tcj[3]; /* torques on i and on j, last step                   */
    int32_t *jstart, *jlist;  /* pairs where p is j: jlist[jstart[p] .. jstart[p+1])*/
    size_t pcap;              /* capacity of the per-pair arrays                    */
    struct {                  /* second set of per-pair arrays: rebuilds fill it and swap */
        gk_real *ft[3], *mr[3], *fc[3], *tci[3], *tcj[3];
        unsigned char *cs;
        size_t cap;
        gk_pairlist pl;
    } spare;
    gk_cells cells;
    double h0[9];      /* cell at the last (inner) build                     */
    double skin;       /* Verlet skin of the outer list [m]                  */
    double skin_in;    /* skin of the inner list the kernels run over        */
    gk_pairlist outer; /* candidates within skin, from the cell grid          */
    double *o0[3];     /* reduced positions at the outer build               */
    double ho0[9];     /* cell at the outer build                            */
    int outer_valid;
    int32_t *outer_in; /* each outer pair's index in pl, or -1 (outer_in_ok)  */
    size_t outer_in_cap;
    int outer_in_ok; /* pl was filtered from this outer list: a rebuild that
                        keeps it looks the old pairs up instead of merging.
                        Cleared by each outer build and by a restore (every
                        other change of pl also clears outer_valid) */
    int need_rebuild, diverged;
    /* results of the last step that computed them (the last step of each call) */
    double stress[9]; /* Love stress, tension-positive [Pa]                 */
    double stiff[3];  /* Voigt stiffness D_kkkk estimate [Pa]               */
    int ncontacts;
    double fc_mean; /* mean |F| over contacts                             */
    int servo_on;
    gk_servo servo;
    gk_err err;
    /* seam for scenes beyond the periodic cell (gk_scene.h); NULL/0 in an RVE */
    gk_result (*hook)(struct gk_rve *rve, int stage, void *user);
    void *hook_user;
    int hook_pairs; /* nonzero: every step keeps the per-pair forces (a hook reads them) */
    int ncap;       /* capacity of the per-particle arrays (0: n)         */
} gk_rve;

/* stages at which gk_rve.hook is called in every step */
#define GK_HOOK_PRE_FORCES 0
#define GK_HOOK_POST_FORCES 1
#define GK_HOOK_POST_STEP 2

/* a growable buffer for gk_rve_save / gk_rve_restore */
typedef struct gk_rve_state {
    unsigned char *buf;
    size_t size, cap;
    gk_allocator alloc;
} gk_rve_state;

/* one contact (a touching pair) of gk_rve_contact_next, read-only */
typedef struct gk_rve_contact {
    int i, j;    /* the two particles as indices of the input packing (gk_rve.id), i < j */
    int sliding; /* 1 if its tangential force was on the Coulomb cap in the last step */
    double f[3]; /* contact force on particle j in the last step [N] (2D: f[2] = 0)   */
    double d[3]; /* branch vector x_j - x_i, nearest image [m] (2D: d[2] = 0)         */
} gk_rve_contact;

typedef struct gk_consolidate_def {
    double pressure;        /* target isotropic stress, compression-positive [Pa] (> 0) */
    double friction;        /* Coulomb coefficient while consolidating (0 = dense)      */
    double stress_tol;      /* relative tolerance on every sigma_kk; 0 -> 1e-3           */
    double unbalanced_tol;  /* unbalanced force ratio to reach; 0 -> 1e-3                */
    double max_strain_rate; /* [1/s]; 0 -> inertial number 1e-2 at the target pressure   */
    long max_steps;         /* 0 -> 2 000 000                                            */
    double damping;         /* local damping while consolidating; 0 -> the RVE's own     */
    double ratio[3];        /* target sigma_kk = -pressure x ratio[k] (anisotropic
                                 consolidation); 0 -> 1                                  */
    int box;                /* 1: the cell stays a box (shear stresses not driven)      */
} gk_consolidate_def;

/* gk_rve_deform_adaptive: zero means default */
typedef struct gk_adapt_def {
    double inertial_max;   /* I bound of the deformation (Guo & Zhao 2014 eq 20); 0 -> 5e-4   */
    double unbalanced_max; /* unbalanced force ratio to reach after it; 0 -> 5e-3     */
    int n_min, n_max;      /* bounds on the total DEM steps; 0 -> 10 and 5000          */
    int every;             /* relaxation steps between checks; 0 -> 20                 */
    int rms;               /* 1: the RMS ratio I_uf (Liu, Sun, Yuan & Fish 2016 eq 57)
                              instead of the mean ratio (gk_rve_unbalanced_rms)        */
} gk_adapt_def;

typedef struct gk_adapt_report {
    int n_deform, n_relax; /* steps of the deformation and of the relaxation         */
    double inertial;       /* I of the deformation (at the pressure before it)       */
    double unbalanced;     /* unbalanced force ratio at the end (mean, or eq 57's RMS) */
    int capped;            /* 1 if n_max stopped the relaxation above uf_max          */
} gk_adapt_report;

typedef struct gk_consolidate_report {
    long steps;
    double stress[9], unbalanced, void_ratio;
} gk_consolidate_report;

#ifdef __cplusplus
extern "C" {
#endif

/* RVE */
GKDEF gk_rve_def gk_rve_def_default(void);
GKDEF gk_result gk_rve_create(gk_rve *rve, const gk_rve_def *def, const gk_packing *pk);
GKDEF void gk_rve_destroy(gk_rve *rve);
GKDEF const char *gk_rve_error(const gk_rve *rve);
GKDEF double gk_rve_dt_critical(const gk_rve *rve);
GKDEF gk_result gk_rve_set_dt(gk_rve *rve, double dt);
GKDEF gk_result gk_rve_set_friction(gk_rve *rve, double mu);
GKDEF gk_result gk_rve_set_damping(gk_rve *rve, double alpha, gk_damp_form form);
/* constant velocity gradient used by gk_rve_step (diagonal overridden by a servo) */
GKDEF gk_result gk_rve_set_velocity_gradient(gk_rve *rve, const double L[9]);
GKDEF gk_result gk_rve_set_servo(gk_rve *rve, const gk_servo *servo); /* NULL switches it off */
GKDEF gk_result gk_rve_step(gk_rve *rve, long nsteps);
/* the same, with GK_STEP_* flags (0: gk_rve_step) */
GKDEF gk_result gk_rve_step_flags(gk_rve *rve, long nsteps, unsigned flags);
GKDEF gk_result gk_rve_deform(gk_rve *rve, const double dH[9], int nsteps);
GKDEF gk_result gk_rve_consolidate(gk_rve *rve, const gk_consolidate_def *cd, gk_consolidate_report *rep);
/* relaxation at a fixed cell (velocity gradient 0, no servo): runs of `every`
 * DEM steps while gk_rve_unbalanced exceeds uf_max, at most max_steps in all;
 * *steps (may be NULL) gets the steps run */
GKDEF gk_result gk_rve_relax(gk_rve *rve, double uf_max, int every, long max_steps, long *steps);
/* gk_rve_deform with the step count chosen by the physics (see DRIVING THE CELL) */
GKDEF gk_result gk_rve_deform_adaptive(gk_rve *rve, const double dH[9], const gk_adapt_def *ad,
                                       gk_adapt_report *rep);
/* unbalanced force ratio (YADE's unbalancedForce): mean |sum of the contact
 * forces on a particle| / mean |contact force|; 0 without contacts */
GKDEF double gk_rve_unbalanced(const gk_rve *rve);
/* the RMS ratio I_uf = sqrt(mean |sum F_p|^2) / sqrt(mean |F_c|^2) of Liu, Sun,
 * Yuan & Fish (2016) eq 57; 0 without contacts */
GKDEF double gk_rve_unbalanced_rms(const gk_rve *rve);
/* inertial number I = 2 gdot r_mean sqrt(rho / p), gdot = sqrt(sym(rate):sym(rate))
 * (Guo & Zhao 2014 eq 20); p <= 0 -> +inf (not NaN) */
GKDEF double gk_inertial_number(const double rate[9], int dim, double r_mean, double density, double p);
/* Love stress of the last step (Guo & Zhao 2014 eq 5), tension-positive, 3x3 */
GKDEF void gk_rve_stress(const gk_rve *rve, double sigma[9]);
/* recompute forces at the current positions without advancing (zero-length
 * step: history and positions unchanged), then stress etc. are current */
GKDEF gk_result gk_rve_refresh(gk_rve *rve);
GKDEF double gk_rve_volume(const gk_rve *rve);         /* stress volume                */
GKDEF double gk_rve_kinetic_energy(const gk_rve *rve); /* of the fluctuations     */
GKDEF void gk_rve_position(const gk_rve *rve, int p, double x[3]);
GKDEF gk_result gk_rve_to_packing(const gk_rve *rve, gk_packing *pk, const gk_allocator *alloc, gk_err *err);
/* the contacts of the last step, one per call, in the RVE's pair order (the same for the same
 * state): `int c = 0; gk_rve_contact k; while (gk_rve_contact_next(rve, &c, &k)) ...` (c is a
 * cursor: start it at 0 and leave it to the call); 0 when there are no more */
GKDEF int gk_rve_contact_next(const gk_rve *rve, int *cursor, gk_rve_contact *out);

/* particle count changes between steps (scenes; see BEYOND THE PERIODIC CELL).
 * reserve: capacity for cap particles. append: k particles at reduced
 * positions s[0..dim-1][k] with radii r and ids id, at rest, masses from the
 * material; refused (nothing changed) for a bad radius or position or one
 * too large for the cell. remove: drops every p with drop[p] != 0. */
GKDEF gk_result gk_rve_reserve(gk_rve *rve, int cap);
GKDEF gk_result gk_rve_append(gk_rve *rve, int k, const double *const s[3], const double *r,
                              const int32_t *id);
GKDEF gk_result gk_rve_remove(gk_rve *rve, const unsigned char *drop);
/* rmin, rmax, mmin, mass_total, solid_volume from r[], minv[] (after the
 * caller changed radii or masses directly) */
GKDEF void gk_rve_update_totals(gk_rve *rve);

/* state */
GKDEF size_t gk_rve_state_size(const gk_rve *rve);
GKDEF gk_result gk_rve_save(const gk_rve *rve, void *buf, size_t cap, size_t *written);
GKDEF gk_result gk_rve_restore(gk_rve *rve, const void *buf, size_t size);
GKDEF void gk_rve_state_init(gk_rve_state *st, const gk_allocator *alloc);
GKDEF void gk_rve_state_free(gk_rve_state *st);
GKDEF gk_result gk_rve_state_save(gk_rve_state *st, const gk_rve *rve);
GKDEF gk_result gk_rve_state_restore(const gk_rve_state *st, gk_rve *rve);

#ifdef __cplusplus
}
#endif
#endif /* GK_DEM_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_DEM_IMPLEMENTATION)) && !defined(GK_DEM_IMPL_ONCE)
#define GK_DEM_IMPL_ONCE

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ================================================================ RVE */
GKDEF gk_rve_def gk_rve_def_default(void) {
    gk_rve_def d;
    memset(&d, 0, sizeof d);
    d.cookie = GK_RVE_DEF_COOKIE;
    d.mat = gk_material_default();
    d.dt = 0.0;
    d.dt_factor = 0.5;
    d.skin = 0.0;
    d.thickness = 0.1;
    d.mass2d = GK_MASS_CYLINDER;
    d.damping = 0.1;
    d.damping_form = GK_DAMP_COMPONENT;
    d.path = GK_PATH_CONSTANT_L;
    d.flags = 0;
    d.threads = 1;
    return d;
}

GKDEF const char *gk_rve_error(const gk_rve *rve) { return rve->err.msg; }

/* ---------------------------------------------------------------- the field table
 * Every per-particle and per-pair array of a gk_rve, in the order of the
 * saved state, with its element size, what it is indexed by and when it
 * exists. Allocation, growth and release, the rebuild's history merge and
 * swap, particle removal, gk_rve_refresh, save, restore and the state size
 * all walk this table: a new array is one line here. */
#define GK__HAS_ROT(rve) (((rve)->phys & GK_PHYS_ROTATION) != 0)
#define GK__HAS_ROLL(rve) (((rve)->phys & GK_PHYS_ROLLING) != 0)

enum { GK__PART, GK__PAIR, GK__OUTER }; /* indexed by: particle, pair, outer-list pair            */
enum {
    GK__ALL,
    GK__DIM,
    GK__ROT,
    GK__ROLL,
    GK__TAN,
    GK__2D,
    GK__TRACK3
};                      /* exists: always, k < dim,
    with rotation (2D: k = 2 only), with rolling (2D: k = 2), 2D k = 0 or 3D, in 2D only, in 3D with
    GK_RVE_TRACK_ROTATION */
#define GK__SAVE 1u     /* in the saved state                                                   */
#define GK__SPARE 2u    /* per-pair with a twin in rve->spare: carried across rebuilds by pair  */
#define GK__HIST 4u     /* contact history: gk_rve_refresh leaves it as it was                  */
#define GK__LIST 8u     /* index array of a gk_pairlist (allocated by it); i, then j            */
#define GK__DERIVED 16u /* rebuilt from the pair list: never copied                             */

typedef struct gk__field {
    size_t off, spare;  /* offsetof the array pointer in gk_rve, of its twin in rve->spare      */
    unsigned char size; /* element bytes                                                         */
    unsigned char set, when, k, flags;
    const char *what; /* named when a restored value is not finite                              */
} gk__field;

#define GK__R ((unsigned char)sizeof(gk_real))
#define GK__F(f, k, size, set, when, fl, what) \
    { offsetof(gk_rve, f), 0, size, set, when, k, fl, what }
#define GK__F3(f, size, when, fl, what)                                                             \
    GK__F(f[0], 0, size, GK__PART, when, fl, what), GK__F(f[1], 1, size, GK__PART, when, fl, what), \
        GK__F(f[2], 2, size, GK__PART, when, fl, what)
#define GK__S(f, k, when, fl, what)                                                     \
    {                                                                                   \
        offsetof(gk_rve, f[k]), offsetof(gk_rve, spare.f[k]), GK__R, GK__PAIR, when, k, \
            GK__SAVE | GK__SPARE | (fl), what                                           \
    }

static const gk__field gk__fields[] = {
    /* per particle: positions, velocities, forces, spins, torques, rotation */
    GK__F3(s, 8, GK__DIM, GK__SAVE, "position"),
    GK__F3(s0, 8, GK__DIM, GK__SAVE, "position"),
    GK__F3(v, GK__R, GK__DIM, GK__SAVE, "velocity"),
    GK__F3(f, GK__R, GK__DIM, GK__SAVE, "force"),
    GK__F(w[0], 0, GK__R, GK__PART, GK__ROT, GK__SAVE, "spin"),
    GK__F(t[0], 0, GK__R, GK__PART, GK__ROT, GK__SAVE, "torque"),
    GK__F(w[1], 1, GK__R, GK__PART, GK__ROT, GK__SAVE, "spin"),
    GK__F(t[1], 1, GK__R, GK__PART, GK__ROT, GK__SAVE, "torque"),
    GK__F(w[2], 2, GK__R, GK__PART, GK__ROT, GK__SAVE, "spin"),
    GK__F(t[2], 2, GK__R, GK__PART, GK__ROT, GK__SAVE, "torque"),
    GK__F(theta, 0, 8, GK__PART, GK__2D, GK__SAVE, "rotation"),
    GK__F(theta, 0, 24, GK__PART, GK__TRACK3, GK__SAVE, "rotation"), /* 3 doubles per particle */
    /* per pair: the list, state bits, history, forces and torques of the last step */
    GK__F(pl.i, 0, 4, GK__PAIR, GK__ALL, GK__SAVE | GK__LIST, "pair"),
    GK__F(pl.j, 0, 4, GK__PAIR, GK__ALL, GK__SAVE | GK__LIST, "pair"),
    {offsetof(gk_rve, cs), offsetof(gk_rve, spare.cs), 1, GK__PAIR, GK__ALL, 0, GK__SAVE | GK__SPARE,
     "state"},
    GK__S(ft, 0, GK__TAN, GK__HIST, "tangential history"),
    GK__S(ft, 1, GK__TAN, GK__HIST, "tangential history"),
    GK__S(ft, 2, GK__TAN, GK__HIST, "tangential history"),
    GK__S(fc, 0, GK__DIM, 0, "contact force"),
    GK__S(fc, 1, GK__DIM, 0, "contact force"),
    GK__S(fc, 2, GK__DIM, 0, "contact force"),
    GK__S(tci, 0, GK__ROT, 0, "contact torque"),
    GK__S(tcj, 0, GK__ROT, 0, "contact torque"),
    GK__S(tci, 1, GK__ROT, 0, "contact torque"),
    GK__S(tcj, 1, GK__ROT, 0, "contact torque"),
    GK__S(tci, 2, GK__ROT, 0, "contact torque"),
    GK__S(tcj, 2, GK__ROT, 0, "contact torque"),
    GK__S(mr, 0, GK__ROLL, GK__HIST, "rolling history"),
    GK__S(mr, 1, GK__ROLL, GK__HIST, "rolling history"),
    GK__S(mr, 2, GK__ROLL, GK__HIST, "rolling history"),
    /* the outer (candidate) list and the positions it was built at */
    GK__F(outer.i, 0, 4, GK__OUTER, GK__ALL, GK__SAVE | GK__LIST, "pair"),
    GK__F(outer.j, 0, 4, GK__OUTER, GK__ALL, GK__SAVE | GK__LIST, "pair"),
    GK__F3(o0, 8, GK__DIM, GK__SAVE, "outer-list reference position"),
    /* not saved: constants of the particles (the RVE's own) and the j index */
    GK__F(r, 0, GK__R, GK__PART, GK__ALL, 0, "radius"),
    GK__F(minv, 0, GK__R, GK__PART, GK__ALL, 0, "mass"),
    GK__F(Iinv, 0, GK__R, GK__PART, GK__ALL, 0, "inertia"),
    GK__F(id, 0, 4, GK__PART, GK__ALL, 0, "id"),
    GK__F(jlist, 0, 4, GK__PAIR, GK__ALL, GK__DERIVED, "pair")};
#define GK__NFIELDS ((int)(sizeof gk__fields / sizeof gk__fields[0]))
#undef GK__F
#undef GK__F3
#undef GK__S

static int gk__field_on(const gk_rve *rve, const gk__field *f) {
    int dim = rve->dim, k = f->k;
    switch (f->when) {
    case GK__DIM: return k < dim;
    case GK__ROT: return GK__HAS_ROT(rve) && (dim == 3 || k == 2);
    case GK__ROLL: return GK__HAS_ROLL(rve) && (dim == 3 || k == 2);
    case GK__TAN: return dim == 3 || k == 0;
    case GK__2D: return dim == 2;
    case GK__TRACK3: return dim == 3 && (rve->def.flags & GK_RVE_TRACK_ROTATION) != 0;
    default: return 1;
    }
}
/* the array of a field (live or its spare twin) */
static void *gk__fget(const gk_rve *rve, size_t off) {
    void *p;
    memcpy(&p, (const char *)rve + off, sizeof p);
    return p;
}
static void gk__fset(gk_rve *rve, size_t off, void *p) { memcpy((char *)rve + off, &p, sizeof p); }
static size_t gk__fcount(const gk_rve *rve, const gk__field *f, size_t npairs, size_t nouter) {
    return f->set == GK__PART ? (size_t)rve->n : (f->set == GK__PAIR ? npairs : nouter);
}

/* grow the arrays of set (GK__PART or GK__PAIR, live ones, or with spare = 1
 * the spare twins) to cap elements, keeping the first ncopy */
static gk_result gk__fields_grow(gk_rve *rve, int set, int spare, size_t cap, size_t ncopy) {
    const gk_allocator *a = &rve->def.alloc;
    int q;
    for (q = 0; q < GK__NFIELDS; ++q) {
        const gk__field *f = &gk__fields[q];
        size_t off = spare ? f->spare : f->off;
        void *p;
        if (f->set != set || (f->flags & GK__LIST) || (spare && !f->spare) || !gk__field_on(rve, f)) continue;
        p = gk__fget(rve, off);
        if (gk_realloc(a, &p, spare || (f->flags & GK__DERIVED) ? 0 : ncopy, cap, f->size))
            return GK_ERR_ALLOC;
        gk__fset(rve, off, p);
    }
    if (set == GK__PART &&
        gk_realloc(a, (void **)&rve->jstart, ncopy ? ncopy + 1 : 0, cap + 1, sizeof(int32_t)))
        return GK_ERR_ALLOC;
    return GK_OK;
}

static void gk__rve_free_arrays(gk_rve *rve) {
    const gk_allocator *a = &rve->def.alloc;
    int q;
    for (q = 0; q < GK__NFIELDS; ++q) {
        const gk__field *f = &gk__fields[q];
        if (f->flags & GK__LIST) continue;
        gk_free(a, gk__fget(rve, f->off));
        gk__fset(rve, f->off, NULL);
        if (f->spare) {
            gk_free(a, gk__fget(rve, f->spare));
            gk__fset(rve, f->spare, NULL);
        }
    }
    gk_free(a, rve->jstart);
    rve->jstart = NULL;
    gk_free(a, rve->frec);
    rve->frec = NULL;
    rve->frec_cap = 0;
    gk_free(a, rve->outer_in);
    rve->outer_in = NULL;
    rve->outer_in_cap = 0;
    rve->outer_in_ok = 0;
    rve->pcap = rve->spare.cap = 0;
    gk_pairlist_free(&rve->spare.pl);
    gk_pairlist_free(&rve->pl);
    gk_pairlist_free(&rve->outer);
    gk_cells_free(&rve->cells);
}

GKDEF void gk_rve_destroy(gk_rve *rve) {
    gk__rve_free_arrays(rve);
    rve->n = 0;
}

/* capacity doubling from 64 */
static size_t gk__grown(size_t have, size_t need) {
    size_t c = have ? have : 64;
    while (c < need) c *= 2;
    return c;
}

/* room kept after the last pair: the gather's padded slots (gk__reduce_kernel) */
#define GK__PAIR_PAD 8

/* per-pair arrays for cap pairs (and GK__PAIR_PAD more), copying the first ncopy */
static gk_result gk__pairs_reserve(gk_rve *rve, size_t cap, size_t ncopy) {
    cap += GK__PAIR_PAD;
    if (cap <= rve->pcap) return GK_OK;
    cap = gk__grown(rve->pcap, cap);
    if (gk__fields_grow(rve, GK__PAIR, 0, cap, ncopy)) return GK_ERR_ALLOC;
    rve->pcap = cap;
    return GK_OK;
}

/* the spare per-pair arrays (same set as the current ones) for cap pairs */
static gk_result gk__spare_reserve(gk_rve *rve, size_t cap) {
    cap += GK__PAIR_PAD;
    if (cap <= rve->spare.cap) return GK_OK;
    cap = gk__grown(rve->spare.cap, cap);
    if (gk__fields_grow(rve, GK__PAIR, 1, cap, 0)) return GK_ERR_ALLOC;
    rve->spare.cap = cap;
    return GK_OK;
}

/* pl.start (CSR by i) and the j index (jstart, jlist: pairs where p is j in
 * ascending pair order) from the pair list */
static void gk__pair_index(gk_rve *rve) {
    int n = rve->n, p, c;
    for (p = 0; p <= n; ++p) rve->pl.start[p] = rve->jstart[p] = 0;
    for (c = 0; c < rve->pl.n; ++c) {
        ++rve->pl.start[rve->pl.i[c] + 1];
        ++rve->jstart[rve->pl.j[c] + 1];
    }
    for (p = 0; p < n; ++p) {
        rve->pl.start[p + 1] += rve->pl.start[p];
        rve->jstart[p + 1] += rve->jstart[p];
    }
    for (c = 0; c < rve->pl.n; ++c) rve->jlist[rve->jstart[rve->pl.j[c]]++] = c;
    for (p = n; p > 0; --p) rve->jstart[p] = rve->jstart[p - 1];
    rve->jstart[0] = 0;
    if (rve->pcap >= (size_t)rve->pl.n + GK__PAIR_PAD)
        for (c = rve->pl.n; c < rve->pl.n + GK__PAIR_PAD; ++c) rve->jlist[c] = rve->pl.n;
    rve->pl.np = n;
}

/* dst[c] = src[map[c]] (0 where map[c] < 0) for elements of size bytes */
static void gk__gather_by(void *dst, const void *src, const int32_t *map, int n, int size) {
    int c;
    if (size == 8) {
        double *d = (double *)dst;
        const double *s = (const double *)src;
        for (c = 0; c < n; ++c) d[c] = map[c] >= 0 ? s[map[c]] : 0.0;
    } else if (size == 4) {
        float *d = (float *)dst;
        const float *s = (const float *)src;
        for (c = 0; c < n; ++c) d[c] = map[c] >= 0 ? s[map[c]] : 0.0f;
    } else {
        unsigned char *d = (unsigned char *)dst;
        const unsigned char *s = (const unsigned char *)src;
        for (c = 0; c < n; ++c) d[c] = map[c] >= 0 ? s[map[c]] : 0;
    }
}

/* every per-pair array carried by pair (GK__SPARE) into its spare twin:
 * pair c of the new list takes old pair map[c], or zero. A rebuild keeps
 * most pairs in order, so map is mostly long runs map[c + 1] = map[c] + 1:
 * up to GK_DEM_GATHER_RUNS of them are copied as blocks (the same bits),
 * more go element by element (tests set it low to take both ways). */
#ifndef GK_DEM_GATHER_RUNS
#define GK_DEM_GATHER_RUNS 256
#endif
static void gk__pairs_gather(gk_rve *rve, const int32_t *map, int n) {
    int32_t at[GK_DEM_GATHER_RUNS], from[GK_DEM_GATHER_RUNS], len[GK_DEM_GATHER_RUNS];
    int q, c, nr = 0;
    /* the runs: new pairs [at, at + len) from old [from, from + len), or zeros */
    for (c = 0; c < n && nr < GK_DEM_GATHER_RUNS; ++nr) {
        int e = c + 1;
        if (map[c] < 0)
            while (e < n && map[e] < 0) ++e;
        else
            while (e < n && map[e] == map[e - 1] + 1) ++e;
        at[nr] = c;
        from[nr] = map[c] < 0 ? -1 : map[c];
        len[nr] = e - c;
        c = e;
    }
    for (q = 0; q < GK__NFIELDS; ++q) {
        const gk__field *f = &gk__fields[q];
        unsigned char *d, *s;
        int r;
        if (!(f->flags & GK__SPARE) || !gk__field_on(rve, f)) continue;
        d = (unsigned char *)gk__fget(rve, f->spare);
        s = (unsigned char *)gk__fget(rve, f->off);
        if (c < n) { /* too many runs */
            gk__gather_by(d, s, map, n, f->size);
            continue;
        }
        for (r = 0; r < nr; ++r) {
            size_t z = f->size;
            if (from[r] < 0)
                memset(d + z * (size_t)at[r], 0, z * (size_t)len[r]);
            else
                memcpy(d + z * (size_t)at[r], s + z * (size_t)from[r], z * (size_t)len[r]);
        }
    }
}

/* zero the per-particle arrays for particles [p0, p1) */
static void gk__fields_zero(gk_rve *rve, int p0, int p1) {
    int q;
    for (q = 0; q < GK__NFIELDS; ++q) {
        const gk__field *f = &gk__fields[q];
        if (f->set != GK__PART || !gk__field_on(rve, f)) continue;
        memset((unsigned char *)gk__fget(rve, f->off) + (size_t)f->size * p0, 0, (size_t)f->size * (p1 - p0));
    }
}

/* keep the elements with keep[e] != 0 of every array of set, in order */
static void gk__fields_compact(gk_rve *rve, int set, const unsigned char *keep, int n) {
    int q, e;
    for (q = 0; q < GK__NFIELDS; ++q) {
        const gk__field *f = &gk__fields[q];
        unsigned char *b;
        size_t m = 0;
        if (f->set != set || (f->flags & (GK__LIST | GK__DERIVED)) || !gk__field_on(rve, f)) continue;
        b = (unsigned char *)gk__fget(rve, f->off);
        for (e = 0; e < n; ++e)
            if (keep[e]) memmove(b + f->size * m++, b + (size_t)f->size * e, f->size);
    }
}

/* mass and moment of inertia of a particle of radius r (see MASSES) */
static void gk__particle_mass(const gk_rve *rve, double r, double *m, double *I) {
    const gk_rve_def *d = &rve->def;
    if (rve->dim == 2 && d->mass2d == GK_MASS_CYLINDER) {
        *m = d->mat.density * d->thickness * GK_PI * r * r;
        *I = 0.5 * *m * r * r;
    } else {
        *m = d->mat.density * 4.0 / 3.0 * GK_PI * r * r * r;
        *I = 0.4 * *m * r * r;
    }
}

/* critical time step, Guo & Zhao 2014 eq 19, at the geometry (h, reduced positions
 * sb[k], pairs ib/jb of np) given as bytes: the live RVE's arrays or a saved
 * state being checked before it is restored */
static double gk__dt_critical_at(const gk_rve *rve, const double h[9], const unsigned char *const sb[3],
                                 const unsigned char *ib, const unsigned char *jb, int np) {
    const gk_material *m = &rve->def.mat;
    double dmax = 1e-3 * rve->rmin;
    int c;
    if (gk_law_stiffens(m->law))
        for (c = 0; c < np; ++c) { /* current largest overlap, from the geometry */
            int32_t i, j;
            int k;
            double ds[3], d[3], dd;
            memcpy(&i, ib + 4 * (size_t)c, 4);
            memcpy(&j, jb + 4 * (size_t)c, 4);
            for (k = 0; k < 3; ++k) {
                double si = 0.0, sj = 0.0;
                if (k < rve->dim) {
                    memcpy(&si, sb[k] + 8 * (size_t)i, 8);
                    memcpy(&sj, sb[k] + 8 * (size_t)j, 8);
                }
                ds[k] = sj - si;
            }
            gk_pcell_image(h, rve->dim, ds, d);
            dd = (double)rve->r[i] + (double)rve->r[j] - sqrt(gk_v3_dot(d, d));
            if (2.0 * dd > dmax) dmax = 2.0 * dd;
        }
    return sqrt(rve->mmin / gk_law_kn_max(m, rve->rmax, dmax));
}

static double gk__dt_critical(const gk_rve *rve) {
    const unsigned char *sb[3];
    int k;
    for (k = 0; k < 3; ++k) sb[k] = (const unsigned char *)rve->s[k];
    return gk__dt_critical_at(rve, rve->cell.h, sb, (const unsigned char *)rve->pl.i,
                              (const unsigned char *)rve->pl.j, rve->pl.n);
}

GKDEF double gk_rve_dt_critical(const gk_rve *rve) { return gk__dt_critical(rve); }

static gk_result gk__rve_rebuild(gk_rve *rve);

GKDEF gk_result gk_rve_create(gk_rve *rve_out, const gk_rve_def *def, const gk_packing *pk) {
    gk_rve R;
    gk_err *err = &rve_out->err;
    gk_result res;
    int dim, n, p, k;
    double hpk[9], rsum = 0.0, w[3], cutoff, dtc;
    int32_t *perm = NULL;
    memset(&R, 0, sizeof R);
    gk_err_clear(err);
    if (!def || def->cookie != GK_RVE_DEF_COOKIE)
        return gk_err_set(err, GK_ERR_ARG, "gk_rve_def not initialised with gk_rve_def_default()");
    if (!pk || !pk->x || !pk->y || !pk->r) return gk_err_set(err, GK_ERR_ARG, "no packing given");
    res = gk_material_check(&def->mat, err);
    if (res) return res;
    dim = pk->dim;
    n = pk->n;
    if (dim != 2 && dim != 3)
        return gk_err_set(err, GK_ERR_ARG, "packing dimension %d (must be 2 or 3)", dim);
    if (n < 1) return gk_err_set(err, GK_ERR_ARG, "packing has %d particles", n);
    if (n > GK_RVE_MAX_PARTICLES)
        return gk_err_set(err, GK_ERR_ARG,
                          "packing has %d particles; an RVE holds at most %d (int32 pair lists)", n,
                          GK_RVE_MAX_PARTICLES);
    if (!(def->damping >= 0.0 && def->damping < 1.0))
        return gk_err_set(err, GK_ERR_ARG, "local damping %g outside [0, 1)", def->damping);
    if (def->damping_form != GK_DAMP_COMPONENT && def->damping_form != GK_DAMP_VECTOR)
        return gk_err_set(err, GK_ERR_ARG, "unknown damping form %d", (int)def->damping_form);
    if (def->path != GK_PATH_CONSTANT_L && def->path != GK_PATH_OBJECTIVE)
        return gk_err_set(err, GK_ERR_ARG, "unknown deformation path %d", (int)def->path);
    if (dim == 2 && def->mass2d == GK_MASS_CYLINDER && !(def->thickness > 0.0))
        return gk_err_set(err, GK_ERR_ARG, "2D cylinder masses need thickness > 0 (got %g)", def->thickness);
    if (!(def->dt >= 0.0) || !isfinite(def->dt))
        return gk_err_set(err, GK_ERR_DT, "time step %g invalid", def->dt);
    if (!(def->skin >= 0.0) || !isfinite(def->skin))
        return gk_err_set(err, GK_ERR_ARG, "skin %g invalid", def->skin);
    if (!(def->dt_factor >= 0.0 && def->dt_factor <= 1.0))
        return gk_err_set(err, GK_ERR_DT, "dt_factor %g outside (0, 1]", def->dt_factor);
    gk_m3_copy(pk->h, hpk);
    if (dim == 2) {
        hpk[2] = hpk[5] = hpk[6] = hpk[7] = 0.0;
        hpk[8] = 1.0;
    }
    res = gk_pcell_init(&R.cell, dim, hpk, err);
    if (res) return res;
    for (p = 0; p < n; ++p) {
        double rp = pk->r[p];
        if (!isfinite(pk->x[p]) || !isfinite(pk->y[p]) || (dim == 3 && (!pk->z || !isfinite(pk->z[p]))))
            return gk_err_set(err, GK_ERR_NAN, "particle %d has a NaN or infinite position", p);
        if (!(rp > 0.0) || !isfinite(rp))
            return gk_err_set(err, GK_ERR_RADIUS, "particle %d has radius %g", p, rp);
        if (!(def->flags & GK_RVE_WRAP)) {
            double x[3], s[3];
            x[0] = pk->x[p];
            x[1] = pk->y[p];
            x[2] = dim == 3 ? pk->z[p] : 0.0;
            gk_m3_matvec(R.cell.hinv, x, s);
            for (k = 0; k < dim; ++k)
                if (s[k] < -1e-9 || s[k] >= 1.0 + 1e-9)
                    return gk_err_set(
                        err, GK_ERR_OUTSIDE,
                        "particle %d at (%g, %g, %g) is outside the cell (set GK_RVE_WRAP to wrap)", p, x[0],
                        x[1], x[2]);
        }
    }
    R.dim = dim;
    R.n = n;
    R.def = *def;
    gk_law_consts_make(&def->mat, &R.K);
    R.phys = gk_material_flags(&def->mat);
    if (!(def->flags & GK_RVE_NO_ROTATION) && (R.phys & (GK_PHYS_TANGENT | GK_PHYS_ROLLING)))
        R.phys |= GK_PHYS_ROTATION;
    if ((R.phys & GK_PHYS_ROLLING) && !(R.phys & GK_PHYS_ROTATION))
        return gk_err_set(err, GK_ERR_ARG,
                          "rolling resistance needs rotating particles (GK_RVE_NO_ROTATION is set)");
    R.volume_factor = dim == 2 ? (def->thickness > 0.0 ? def->thickness : 1.0) : 1.0;
    /* particle order: cell-list order for locality */
    {
        double *tmp[3];
        gk_cells cl;
        double rmax = 0.0;
        for (p = 0; p < n; ++p)
            if (pk->r[p] > rmax) rmax = pk->r[p];
        for (k = 0; k < 3; ++k) tmp[k] = (double *)gk_alloc(&def->alloc, (size_t)n * sizeof(double));
        perm = (int32_t *)gk_alloc(&def->alloc, (size_t)n * sizeof(int32_t));
        gk_cells_init(&cl, &def->alloc);
        res = (tmp[0] && tmp[1] && tmp[2] && perm) ? GK_OK : GK_ERR_ALLOC;
        if (!res) {
            for (p = 0; p < n; ++p) {
                double x[3], s[3];
                x[0] = pk->x[p];
                x[1] = pk->y[p];
                x[2] = dim == 3 ? pk->z[p] : 0.0;
                gk_m3_matvec(R.cell.hinv, x, s);
                for (k = 0; k < 3; ++k) tmp[k][p] = k < dim ? s[k] - floor(s[k]) : 0.0;
            }
            {
                double wmin, wd[3];
                gk_pcell_widths(&R.cell, wd);
                wmin = wd[0] < wd[1] ? wd[0] : wd[1];
                if (dim == 3 && wd[2] < wmin) wmin = wd[2];
                /* binning for ordering only: any bin size below half the cell works */
                cutoff = 2.0 * rmax < 0.49 * wmin ? 2.0 * rmax : 0.49 * wmin;
            }
            res = gk_cells_bin(&cl, dim, R.cell.h, n, (const double *const *)tmp, cutoff, err);
            if (!res) memcpy(perm, cl.order, (size_t)n * sizeof(int32_t));
        } else {
            gk_err_set(err, res, "out of memory ordering %d particles", n);
        }
        gk_cells_free(&cl);
        if (res) {
            for (k = 0; k < 3; ++k) gk_free(&def->alloc, tmp[k]);
            gk_free(&def->alloc, perm);
            return res;
        }
        /* allocate (zeroed) */
        if (!res && gk__fields_grow(&R, GK__PART, 0, (size_t)n, 0)) res = GK_ERR_ALLOC;
        if (!res) gk__fields_zero(&R, 0, n);
        gk_pairlist_init(&R.pl, &def->alloc);
        gk_pairlist_init(&R.outer, &def->alloc);
        gk_pairlist_init(&R.spare.pl, &def->alloc);
        gk_cells_init(&R.cells, &def->alloc);
        if (!res) {
            R.rmin = 1e300;
            R.rmax = 0.0;
            R.mmin = 1e300;
            for (p = 0; p < n; ++p) {
                int q = perm[p];
                double rq = pk->r[q], m, I;
                for (k = 0; k < dim; ++k) R.s[k][p] = R.s0[k][p] = tmp[k][q];
                gk__particle_mass(&R, rq, &m, &I);
                R.r[p] = (gk_real)rq;
                R.minv[p] = (gk_real)(1.0 / m);
                R.Iinv[p] = (gk_real)(1.0 / I);
                if (!(m > 0.0 && isfinite(m) && I > 0.0 && isfinite(I)) || !(R.r[p] > 0) ||
                    !((double)R.minv[p] > 0.0 && isfinite((double)R.minv[p])) ||
                    !((double)R.Iinv[p] > 0.0 && isfinite((double)R.Iinv[p]))) {
                    gk_err_set(err, GK_ERR_MASS,
                               "particle %d (radius %g): mass %g and inertia %g are out of the range of %s "
                               "(rescale the units)",
                               q, rq, m, I, GK_REAL_NAME);
                    res = GK_ERR_MASS;
                    break;
                }
                R.id[p] = q;
                if (rq < R.rmin) R.rmin = rq;
                if (rq > R.rmax) R.rmax = rq;
                if (m < R.mmin) R.mmin = m;
                R.mass_total += m;
                rsum += rq;
                R.solid_volume += gk_particle_volume(dim, rq) * (dim == 2 ? R.volume_factor : 1.0);
            }
        }
        for (k = 0; k < 3; ++k) gk_free(&def->alloc, tmp[k]);
        gk_free(&def->alloc, perm);
        if (res) {
            gk__rve_free_arrays(&R);
            if (res == GK_ERR_ALLOC) gk_err_set(err, res, "out of memory for an RVE of %d particles", n);
            return res;
        }
    }
    R.skin = def->skin > 0.0 ? def->skin : 0.1 * rsum / n;
    R.skin_in = 0.25 * R.skin;
    if (R.phys & GK_PHYS_COHESION) { /* a bond may stretch to coh_n / k_n before breaking */
        double knmin = def->mat.kn > 0 ? def->mat.kn : def->mat.young * R.rmin;
        if (R.skin < 2.0 * def->mat.coh_n / knmin) R.skin = 2.0 * def->mat.coh_n / knmin;
        R.skin_in = R.skin;
    }
    R.outer_valid = 0;
    gk_pcell_widths(&R.cell, w);
    cutoff = 2.0 * R.rmax + R.skin;
    for (k = 0; k < dim; ++k)
        if (!(2.0 * cutoff < w[k])) {
            gk__rve_free_arrays(&R);
            return gk_err_set(err, GK_ERR_CELL,
                              "cell width %g is below twice the interaction distance %g (2 r_max + skin): "
                              "use more particles or a smaller skin",
                              w[k], cutoff);
        }
    gk_m3_zero(R.L);
    gk_m3_zero(R.G);
    R.need_rebuild = 1;
    R.err = rve_out->err;
    R.dt = 0.0; /* set below, from the pairs (Hertz stiffness depends on the overlaps) */
    res = gk__rve_rebuild(&R);
    if (!res) {
        R.dt_crit = gk__dt_critical(&R);
        dtc = R.dt_crit;
        if (!(dtc > 0.0) || !isfinite(dtc) || !(dtc * (def->dt_factor > 0.0 ? def->dt_factor : 0.5) > 0.0))
            res = gk_err_set(
                &R.err, GK_ERR_DT,
                "critical time step %g s (Guo & Zhao 2014, eq 19) is not a positive number: radii %g to %g m "
                "and the stiffness are out of range (rescale the units)",
                dtc, R.rmin, R.rmax);
        else if (def->dt > 0.0) {
            if (def->dt > dtc)
                res = gk_err_set(&R.err, GK_ERR_DT,
                                 "time step %g s is above the critical %g s (Guo & Zhao 2014 eq 19)", def->dt,
                                 dtc);
            R.dt = def->dt;
        } else {
            R.dt = (def->dt_factor > 0.0 ? def->dt_factor : 0.5) * dtc;
        }
    }
    if (res) {
        gk_err e = R.err;
        gk__rve_free_arrays(&R);
        rve_out->err = e;
        return res;
    }
    *rve_out = R;
    return GK_OK;
}

/* inner list: the outer pairs closer than r_i + r_j + skin_in, in outer
 * order, into nl; outer_in[c] := the new index of outer pair c, or -1. With
 * `lookup` (the current list was filtered from this outer list, outer_in its
 * indices) map[m] := the current index of new pair m, or -1, on the way */
GK_FORCE_INLINE void gk__inner_filter(const gk_rve *rve, gk_pairlist *nl, const int dim, const int lookup,
                                      int32_t *GK_RESTRICT oin, int32_t *GK_RESTRICT map, int c0) {
    const double *h = rve->cell.h, skin = rve->skin_in;
    const int32_t *oi = rve->outer.i, *oj = rve->outer.j;
    const gk_real *r = rve->r;
    int c, k, no = rve->outer.n, m = nl->n;
    for (c = c0; c < no; ++c) { /* written always, kept inside the cutoff: no branch */
        int i = oi[c], j = oj[c], keep;
        double ds[3], d[3], cut = (double)r[i] + (double)r[j] + skin;
        for (k = 0; k < dim; ++k) ds[k] = rve->s[k][j] - rve->s[k][i];
        gk_pcell_image(h, dim, ds, d);
        nl->i[m] = i;
        nl->j[m] = j;
        if (lookup) map[m] = oin[c];
        keep = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < cut * cut;
        oin[c] = keep ? m : -1;
        m += keep;
    }
    nl->n = m;
}

/* the inner filter for the rve's dimension, SIMD unless GK_RVE_SCALAR (defined below) */
static void gk__inner_filter_all(const gk_rve *rve, gk_pairlist *nl, int lookup, int32_t *map);

/* the sort key of pair x of a list (i, j): i, then j */
#define GK__KEY(I, J, x) ((uint64_t)(uint32_t)(I)[x] << 32 | (uint32_t)(J)[x])
/* the interleaved merges of a rebuild (the four rounds of its loop are written out) */
#define GK__MERGE_WAYS 4
GK_STATIC_ASSERT(GK__MERGE_WAYS == 4, merge_rounds_written_out);

/* the first of n pairs sorted by key whose key is not below key (n if none) */
static int gk__key_lower_bound(const int32_t *pi, const int32_t *pj, int n, uint64_t key) {
    int lo = 0, hi = n;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (GK__KEY(pi, pj, mid) < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* whether the outer list still holds every pair within skin_in of touching, by
 * the two largest displacements since its build (tighter than twice the largest) */
static int gk__outer_holds(const gk_rve *rve) {
    double t2[2];
    if (!rve->outer_valid) return 0;
    gk_cells_disp2_top2(rve->dim, rve->cell.h, rve->n, (const double *const *)rve->o0,
                        (const double *const *)rve->s, t2);
    return gk_cells_skin_margin2(rve->dim, rve->ho0, rve->cell.h, rve->skin, rve->rmax, t2) > rve->skin_in;
}

/* rebuild the pair list at the current positions, carrying history over by merge */
static gk_result gk__rve_rebuild(gk_rve *rve) {
    gk_pairlist nl;
    if (gk_law_stiffens(rve->def.mat.law) && rve->pl.n > 0) {
        /* k_n grows with the overlap (Hertz): the critical step shrinks as overlaps grow */
        double dtc = gk__dt_critical(rve);
        if (rve->dt > dtc)
            return gk_err_set(
                &rve->err, GK_ERR_DT,
                "time step %g s now exceeds the critical %g s at the current overlaps (Hertz stiffens "
                "with load): restore a saved state and use a smaller dt",
                rve->dt, dtc);
        rve->dt_crit = dtc;
    }
    int dim = rve->dim, n = rve->n, k, c, lookup;
    double w[3];
    gk_result res;
    const double *sp[3];
    /* cell too thin for the nearest image: try a lattice reduction first */
    gk_pcell_widths(&rve->cell, w);
    for (k = 0; k < dim; ++k)
        if (!(2.0 * (2.0 * rve->rmax + rve->skin) < w[k]))
            return gk_err_set(
                &rve->err, GK_ERR_CELL,
                "cell width %g fell below twice the interaction distance %g (cell compressed or sheared "
                "too far for this many particles)",
                w[k], 2.0 * rve->rmax + rve->skin);
    if (!gk__outer_holds(rve)) {
        /* outer list from the cell grid (positions are in [0,1): gk__wrap) */
        for (k = 0; k < 3; ++k) sp[k] = rve->s[k < dim ? k : 0];
        res = gk_cells_bin(&rve->cells, dim, rve->cell.h, n, sp, 2.0 * rve->rmax + rve->skin, &rve->err);
        if (res) return res;
        res = gk_cells_pairs(&rve->cells, rve->cell.h, sp, rve->r, rve->skin, &rve->outer, &rve->err);
        if (res) {
            rve->outer_valid = 0;
            return res;
        }
        for (k = 0; k < dim; ++k) memcpy(rve->o0[k], rve->s[k], (size_t)n * sizeof(double));
        gk_m3_copy(rve->cell.h, rve->ho0);
        rve->outer_valid = 1;
        rve->outer_in_ok = 0;
    }
    /* inner list: outer pairs closer than r_i + r_j + skin_in, in outer order,
     * written into the spare list and spare per-pair arrays */
    nl = rve->spare.pl;
    if (gk_pairlist_reserve(&nl, (size_t)rve->outer.n + 1, (size_t)n) ||
        gk__spare_reserve(rve, (size_t)rve->outer.n + 1) ||
        gk__pairs_reserve(rve, (size_t)rve->outer.n + 1, (size_t)rve->pl.n)) {
        rve->spare.pl = nl;
        return gk_err_set(&rve->err, GK_ERR_ALLOC, "out of memory for %d pairs", rve->outer.n);
    }
    nl.np = n;
    nl.n = 0;
    if ((size_t)rve->outer.n > rve->outer_in_cap) {
        size_t cap = gk__grown(rve->outer_in_cap, (size_t)rve->outer.n);
        rve->outer_in_ok = 0;
        if (gk_realloc(&rve->def.alloc, (void **)&rve->outer_in, 0, cap, sizeof(int32_t))) {
            rve->spare.pl = nl;
            return gk_err_set(&rve->err, GK_ERR_ALLOC, "out of memory for %d pairs", rve->outer.n);
        }
        rve->outer_in_cap = cap;
    }
    /* history into the spare arrays: map[c] = the old index of new pair c, or
     * -1 (jlist is the scratch, rebuilt below). When the current list was
     * filtered from the same outer list, the filter looks each pair up;
     * else a merge of the two lists, both sorted by (i, j) */
    lookup = rve->outer_in_ok;
    gk__inner_filter_all(rve, &nl, lookup, rve->jlist);
    rve->outer_in_ok = 1;
    if (!lookup) {
        int32_t *map = rve->jlist;
        const int32_t *pi = rve->pl.i, *pj = rve->pl.j, *ni = nl.i, *nj = nl.j;
        int no = rve->pl.n, cw[GK__MERGE_WAYS], ce[GK__MERGE_WAYS], ow[GK__MERGE_WAYS], oe[GK__MERGE_WAYS], u;
        /* a merge join on the key (i, j) with no data-dependent branch: each
         * round advances the side(s) with the smaller key; map[c] is written
         * every round, the last write for c being the one where c advanced.
         * A round's loads wait for the last round's comparisons, so one merge
         * runs at the latency of that chain: the lists are cut into
         * GK__MERGE_WAYS key ranges (new pairs in equal parts, the old list at
         * the first key of each part) whose merges run interleaved. The same
         * map: keys are unique, so a new pair's match lies in its own range. */
        for (u = 0; u < GK__MERGE_WAYS; ++u) {
            cw[u] = (int)((long)nl.n * u / GK__MERGE_WAYS);
            ce[u] = (int)((long)nl.n * (u + 1) / GK__MERGE_WAYS);
            ow[u] = u == 0 ? 0 : cw[u] < nl.n ? gk__key_lower_bound(pi, pj, no, GK__KEY(ni, nj, cw[u])) : no;
        }
        for (u = 0; u < GK__MERGE_WAYS; ++u) oe[u] = u + 1 < GK__MERGE_WAYS ? ow[u + 1] : no;
#define GK__MERGE_ROUND(u)                                                   \
    do {                                                                     \
        uint64_t kn_ = GK__KEY(ni, nj, cw[u]), ko_ = GK__KEY(pi, pj, ow[u]); \
        map[cw[u]] = kn_ == ko_ ? ow[u] : -1;                                \
        cw[u] += kn_ <= ko_;                                                 \
        ow[u] += ko_ <= kn_;                                                 \
    } while (0)
        while (cw[0] < ce[0] && ow[0] < oe[0] && cw[1] < ce[1] && ow[1] < oe[1] && cw[2] < ce[2] &&
               ow[2] < oe[2] && cw[3] < ce[3] && ow[3] < oe[3]) {
            GK__MERGE_ROUND(0);
            GK__MERGE_ROUND(1);
            GK__MERGE_ROUND(2);
            GK__MERGE_ROUND(3);
        }
        for (u = 0; u < GK__MERGE_WAYS; ++u) {
            while (cw[u] < ce[u] && ow[u] < oe[u]) GK__MERGE_ROUND(u);
            for (c = cw[u]; c < ce[u]; ++c) map[c] = -1;
        }
#undef GK__MERGE_ROUND
    }
    gk__pairs_gather(rve, rve->jlist, nl.n);
    /* swap the spare set in */
    {
        gk_pairlist t = rve->pl;
        size_t cap = rve->pcap;
        int q;
        for (q = 0; q < GK__NFIELDS; ++q) {
            const gk__field *f = &gk__fields[q];
            void *x;
            if (!f->spare) continue;
            x = gk__fget(rve, f->off);
            gk__fset(rve, f->off, gk__fget(rve, f->spare));
            gk__fset(rve, f->spare, x);
        }
        rve->pcap = rve->spare.cap;
        rve->spare.cap = cap;
        rve->pl = nl;
        rve->spare.pl = t;
        if (rve->pcap > cap &&
            gk_realloc(&rve->def.alloc, (void **)&rve->jlist, 0, rve->pcap, sizeof(int32_t)))
            return gk_err_set(&rve->err, GK_ERR_ALLOC, "out of memory for %d pairs", nl.n);
    }
    gk__pair_index(rve);
    for (k = 0; k < dim; ++k) memcpy(rve->s0[k], rve->s[k], (size_t)n * sizeof(double));
    gk_m3_copy(rve->cell.h, rve->h0);
    rve->need_rebuild = 0;
    ++rve->rebuilds;
    return GK_OK;
}

/* ---------------------------------------------------------------- forces */
typedef struct gk__stepctx {
    double hd[9];  /* cell matrix (positions are double)                   */
    gk_real G[9];  /* affine velocity gradient of this step                 */
    gk_real wa[3]; /* affine spin (2D: wa[2])                               */
    gk_real dt;
    int scatter; /* add pair forces to the particles in the force loop:
                    1 into f and t, 2 into the records frec (3D, GK__FREC)  */
    int store;   /* keep per-pair forces and torques (stress, threads)    */
} gk__stepctx;

/* pair forces, scalar reference: writes fc, tci, tcj, ft, mr, cs for pairs [c0, c1) */
GK_FORCE_INLINE void gk__forces_ref_2d(gk_rve *rve, const gk__stepctx *x, int c0, int c1, gk_law law,
                                       unsigned fl) {
    const int32_t *pi = rve->pl.i, *pj = rve->pl.j;
    const double *sx = rve->s[0], *sy = rve->s[1];
    const gk_real *vx = rve->v[0], *vy = rve->v[1], *r = rve->r, *minv = rve->minv;
    const gk_real *wz = rve->w[2];
    gk_real *ft = rve->ft[0], *mr = rve->mr[2], *fcx = rve->fc[0], *fcy = rve->fc[1];
    gk_real *tci = rve->tci[2], *tcj = rve->tcj[2];
    unsigned char *cs = rve->cs;
    gk_real dummy = 0;
    int c;
    for (c = c0; c < c1; ++c) {
        int i = pi[c], j = pj[c];
        double ds[3], dd[3];
        gk_real dx, dy, rvx, rvy, wi, wj;
        gk_contact_out o;
        ds[0] = sx[j] - sx[i];
        ds[1] = sy[j] - sy[i];
        gk_pcell_image(x->hd, 2, ds, dd);
        dx = (gk_real)dd[0];
        dy = (gk_real)dd[1];
        rvx = (vx[j] - vx[i]) + (x->G[0] * dx + x->G[1] * dy);
        rvy = (vy[j] - vy[i]) + (x->G[3] * dx + x->G[4] * dy);
        wi = (fl & GK_PHYS_ROTATION) ? x->wa[2] + wz[i] : x->wa[2];
        wj = (fl & GK_PHYS_ROTATION) ? x->wa[2] + wz[j] : x->wa[2];
        gk_contact_2d(&rve->K, law, fl, dx, dy, r[i], r[j], (gk_real)1 / minv[i], (gk_real)1 / minv[j], rvx,
                      rvy, wi, wj, x->dt, ft + c, (fl & GK_PHYS_ROLLING) ? mr + c : &dummy, cs + c, &o);
        if (x->store) {
            fcx[c] = o.f[0];
            fcy[c] = o.f[1];
            if (fl & GK_PHYS_ROTATION) {
                tci[c] = o.ti[2];
                tcj[c] = o.tj[2];
            }
        }
        if (x->scatter) { /* pair order: same sums as gk__reduce_kernel */
            rve->f[0][j] += o.f[0];
            rve->f[1][j] += o.f[1];
            rve->f[0][i] -= o.f[0];
            rve->f[1][i] -= o.f[1];
            if (fl & GK_PHYS_ROTATION) {
                rve->t[2][j] += o.tj[2];
                rve->t[2][i] += o.ti[2];
            }
        }
    }
}

GK_FORCE_INLINE void gk__forces_ref_3d(gk_rve *rve, const gk__stepctx *x, int c0, int c1, gk_law law,
                                       unsigned fl) {
    const int32_t *pi = rve->pl.i, *pj = rve->pl.j;
    const gk_real *r = rve->r, *minv = rve->minv;
    gk_real dummy[3] = {0, 0, 0};
    int c, k;
    for (c = c0; c < c1; ++c) {
        int i = pi[c], j = pj[c];
        double ds[3], dd[3];
        gk_real d[3], vr[3], wi[3], wj[3], hist[3], mh[3];
        gk_contact_out o;
        GK_UNROLL
        for (k = 0; k < 3; ++k) ds[k] = rve->s[k][j] - rve->s[k][i];
        gk_pcell_image(x->hd, 3, ds, dd);
        GK_UNROLL
        for (k = 0; k < 3; ++k) d[k] = (gk_real)dd[k];
        GK_UNROLL
        for (k = 0; k < 3; ++k)
            vr[k] = (rve->v[k][j] - rve->v[k][i]) +
                    (x->G[3 * k] * d[0] + x->G[3 * k + 1] * d[1] + x->G[3 * k + 2] * d[2]);
        GK_UNROLL
        for (k = 0; k < 3; ++k) {
            wi[k] = (fl & GK_PHYS_ROTATION) ? x->wa[k] + rve->w[k][i] : x->wa[k];
            wj[k] = (fl & GK_PHYS_ROTATION) ? x->wa[k] + rve->w[k][j] : x->wa[k];
            hist[k] = rve->ft[k][c];
            mh[k] = (fl & GK_PHYS_ROLLING) ? rve->mr[k][c] : dummy[k];
        }
        gk_contact_3d(&rve->K, law, fl, d, r[i], r[j], (gk_real)1 / minv[i], (gk_real)1 / minv[j], vr, wi, wj,
                      x->dt, hist, mh, rve->cs + c, &o);
        GK_UNROLL
        for (k = 0; k < 3; ++k) {
            rve->ft[k][c] = hist[k];
            if (fl & GK_PHYS_ROLLING) rve->mr[k][c] = mh[k];
            if (x->store) {
                rve->fc[k][c] = o.f[k];
                if (fl & GK_PHYS_ROTATION) {
                    rve->tci[k][c] = o.ti[k];
                    rve->tcj[k][c] = o.tj[k];
                }
            }
        }
        if (x->scatter) {
            GK_UNROLL
            for (k = 0; k < 3; ++k) {
                rve->f[k][j] += o.f[k];
                rve->f[k][i] -= o.f[k];
                if (fl & GK_PHYS_ROTATION) {
                    rve->t[k][j] += o.tj[k];
                    rve->t[k][i] += o.ti[k];
                }
            }
        }
    }
}

/* The scattering force loop (one thread, lists above GK_DEM_GATHER_MAX pairs)
 * of a 3D AVX-512 double build, up to GK_DEM_FREC_MAX particles, adds each
 * pair's force and torques to one 64-byte record per particle (f0 f1 f2 t0 t1
 * t2, two pads): a block of 8 pairs is one 8 x 8 transpose, 8 permutations
 * and 16 vector read-modify-writes instead of 96 scalar ones; after the loop
 * the records become f and t. The same additions in the same order (pair
 * order), so the same bits. Above GK_DEM_FREC_MAX particles the records leave
 * the cache and copying them costs more than they save (bench/README.md). */
#if GK_SIMD_WIDTH == 512 && !defined(GK_REAL_FLOAT)
#define GK__FREC 1
#else
#define GK__FREC 0
#endif

/* ---------------------------------------------------------------- SIMD forces
 * GK_VR_W pairs at a time: gather, the wide twin of the law
 * (gk_contact_2d_w / _3d_w, bit-identical lanes), store and scatter. The
 * remainder of a range (fewer than GK_VR_W pairs) and cohesive contacts go
 * through the scalar reference. */
#if GK_VR_W > 1
/* The i side of a block of pairs (pl.i ascending) mostly spans fewer
 * particles than lanes: its gathers are then one load and a permutation each
 * (gk_vd_win, gk_vf_win in gk_base.h), the same values. Positions are double:
 * in a float build a block's positions are two double vectors, each with its
 * own window, and the float arrays have theirs. */
typedef struct gk__iwin {
    gk_vd_win d[GK_VR_DHALVES]; /* positions */
#ifdef GK_REAL_FLOAT
    gk_vr_win r; /* the gk_real arrays */
#endif
} gk__iwin;
GK_FORCE_INLINE void gk__iwin_make(const int32_t *ii, int32_t n, gk__iwin *w) {
    int hf;
    for (hf = 0; hf < GK_VR_DHALVES; ++hf) gk_vd_win_make(ii + hf * GK_VD_W, n, &w->d[hf]);
#ifdef GK_REAL_FLOAT
    gk_vr_win_make(ii, n, &w->r);
#endif
}
#ifdef GK_REAL_FLOAT
#define GK__GI(base, ii, w) gk_vr_gather_win(base, ii, &(w)->r)
#else
#define GK__GI(base, ii, w) gk_vr_gather_win(base, ii, &(w)->d[0])
#endif

/* branch vectors d = h (ds - round(ds)) of GK_VR_W pairs, from double
 * positions (the wide twin of gk_pcell_image); H = the cell matrix broadcast
 * once per call; wi the window of the i side */
GK_FORCE_INLINE void gk__simd_branch(const gk_rve *rve, const gk_vd H[9], const int32_t *ii,
                                     const int32_t *jj, const gk__iwin *wi, int dim, gk_vr d[3]) {
    gk_vd dd[2][3];
    int hf, k;
    for (hf = 0; hf < GK_VR_DHALVES; ++hf) {
        /* written out per axis: as a loop over k, gcc kept the loop and sent ds through the stack */
        const int32_t *i4 = ii + hf * GK_VD_W, *j4 = jj + hf * GK_VD_W;
        gk_vd ds0 = gk_vd_sub(gk_vd_gather(rve->s[0], j4), gk_vd_gather_win(rve->s[0], i4, &wi->d[hf])),
              ds1 = gk_vd_sub(gk_vd_gather(rve->s[1], j4), gk_vd_gather_win(rve->s[1], i4, &wi->d[hf]));
        ds0 = gk_vd_sub(ds0, gk_vd_round(ds0));
        ds1 = gk_vd_sub(ds1, gk_vd_round(ds1));
        if (dim == 3) {
            gk_vd ds2 = gk_vd_sub(gk_vd_gather(rve->s[2], j4), gk_vd_gather_win(rve->s[2], i4, &wi->d[hf]));
            ds2 = gk_vd_sub(ds2, gk_vd_round(ds2));
            GK_UNROLL
            for (k = 0; k < 3; ++k)
                dd[hf][k] = gk_vd_add(gk_vd_add(gk_vd_mul(H[3 * k], ds0), gk_vd_mul(H[3 * k + 1], ds1)),
                                      gk_vd_mul(H[3 * k + 2], ds2));
        } else {
            dd[hf][0] = gk_vd_add(gk_vd_mul(H[0], ds0), gk_vd_mul(H[1], ds1));
            dd[hf][1] = gk_vd_add(gk_vd_mul(H[3], ds0), gk_vd_mul(H[4], ds1));
        }
    }
    for (k = 0; k < dim; ++k) {
#ifdef GK_REAL_FLOAT
        d[k] = gk_vf_from_vd2(dd[0][k], dd[GK_VR_DHALVES - 1][k]);
#else
        d[k] = dd[0][k];
#endif
    }
}

#if GK_SIMD_WIDTH == 512 && !defined(GK_REAL_FLOAT)
#define GK__FILTER_SIMD 1
/* gk__inner_filter GK_VR_W outer pairs at a time: the same branch vectors
 * (gk__simd_branch, the twin of gk_pcell_image), cutoffs and comparisons, lane
 * by lane; the kept pairs written as there. The rest of the list goes through
 * gk__inner_filter; returns where it stopped. Only with 512-bit vectors: with
 * AVX2's 4 lanes the rebuilds were slower than with the scalar filter
 * (measured); a float build filters in double through gk__inner_filter. */
GK_FORCE_INLINE int gk__inner_filter_simd(const gk_rve *rve, gk_pairlist *nl, const int dim, const int lookup,
                                          int32_t *GK_RESTRICT oin, int32_t *GK_RESTRICT map) {
    const int32_t *oi = rve->outer.i, *oj = rve->outer.j, n = rve->n;
    const gk_vr skin = gk_vr_set1(rve->skin_in);
    gk_vd H[9];
    int c, k, no = rve->outer.n, m = nl->n;
    for (k = 0; k < 9; ++k) H[k] = gk_vd_set1(rve->cell.h[k]);
    for (c = 0; c + GK_VR_W <= no; c += GK_VR_W) {
        const int32_t *ii = oi + c, *jj = oj + c;
        gk__iwin win;
        gk_vr d[3], cut, d2;
        unsigned keep;
        gk__iwin_make(ii, n, &win);
        gk__simd_branch(rve, H, ii, jj, &win, dim, d);
        cut = gk_vr_add(gk_vr_add(GK__GI(rve->r, ii, &win), gk_vr_gather(rve->r, jj)), skin);
        d2 = gk_vr_add(gk_vr_mul(d[0], d[0]), gk_vr_mul(d[1], d[1]));
        if (dim == 3) d2 = gk_vr_add(d2, gk_vr_mul(d[2], d[2]));
        keep = gk_vrm_bits(gk_vr_lt(d2, gk_vr_mul(cut, cut)));
        gk_i32_compress(keep, ii, nl->i + m);
        gk_i32_compress(keep, jj, nl->j + m);
        if (lookup) gk_i32_compress(keep, oin + c, map + m);
        m += gk_i32_ranks(keep, m, oin + c);
    }
    nl->n = m;
    return c;
}
#endif

/* 8 mask bits -> 8 bytes of 0/1 (bit l -> byte l): a constant table */
#define GK__E(b)                                                                                        \
    ((uint64_t)((b) >> 0 & 1) | (uint64_t)((b) >> 1 & 1) << 8 | (uint64_t)((b) >> 2 & 1) << 16 |        \
     (uint64_t)((b) >> 3 & 1) << 24 | (uint64_t)((b) >> 4 & 1) << 32 | (uint64_t)((b) >> 5 & 1) << 40 | \
     (uint64_t)((b) >> 6 & 1) << 48 | (uint64_t)((b) >> 7 & 1) << 56)
#define GK__R4(b) GK__E(b), GK__E((b) + 1), GK__E((b) + 2), GK__E((b) + 3)
#define GK__R16(b) GK__R4(b), GK__R4((b) + 4), GK__R4((b) + 8), GK__R4((b) + 12)
#define GK__R64(b) GK__R16(b), GK__R16((b) + 16), GK__R16((b) + 32), GK__R16((b) + 48)
static const uint64_t gk__bitbytes[256] = {GK__R64(0), GK__R64(64), GK__R64(128), GK__R64(192)};
#undef GK__R64
#undef GK__R16
#undef GK__R4
#undef GK__E

/* contact state bytes of GK_VR_W lanes: CONTACT where in, SLIDING where also slide */
GK_FORCE_INLINE void gk__simd_state(unsigned char *cs, gk_vrm in, gk_vrm slide, const uint64_t *lut) {
    unsigned bi = gk_vrm_bits(in), bs = gk_vrm_bits(gk_vrm_and(in, slide));
    int l;
    for (l = 0; l < GK_VR_W; l += 8) {
        uint64_t v = lut[(bi >> l) & 0xffu] * GK_CS_CONTACT | lut[(bs >> l) & 0xffu] * GK_CS_SLIDING;
        int m, nb = GK_VR_W - l < 8 ? GK_VR_W - l : 8;
        if (nb == 8) {
            memcpy(cs + l, &v, 8);
        } else if (nb == 4) { /* AVX2 doubles: one 4-byte store, not four */
            uint32_t v4 = (uint32_t)v;
            memcpy(cs + l, &v4, 4);
        } else {
            for (m = 0; m < nb; ++m) cs[l + m] = (unsigned char)(v >> (8 * m));
        }
    }
}

/* b[0], b[1]: force on j (x, y); b[2], b[3]: torque on i, on j. One array
 * on the stack, so the scatter needs no pointer of its own for each buffer
 * (with four, gcc kept their addresses in spilled registers) */
GK_FORCE_INLINE void gk__scatter_buf_2d(gk_rve *rve, const int32_t *ii, const int32_t *jj,
                                        gk_real b[4][GK_VR_W], unsigned rot) {
    gk_real *f0 = rve->f[0], *f1 = rve->f[1], *t2 = rve->t[2];
    int l;
    for (l = 0; l < GK_VR_W; ++l) {
        int i = ii[l], j = jj[l];
        f0[j] += b[0][l];
        f1[j] += b[1][l];
        f0[i] -= b[0][l];
        f1[i] -= b[1][l];
        if (rot) {
            t2[j] += b[3][l];
            t2[i] += b[2][l];
        }
    }
}

/* b[k]: force on j along k; b[3 + k], b[6 + k]: torque on i, on j (one array, as in 2D) */
GK_FORCE_INLINE void gk__scatter_buf_3d(gk_rve *rve, const int32_t *ii, const int32_t *jj,
                                        gk_real b[9][GK_VR_W], unsigned rot) {
    gk_real *f0 = rve->f[0], *f1 = rve->f[1], *f2 = rve->f[2], *t0 = rve->t[0], *t1 = rve->t[1],
            *t2 = rve->t[2];
    int l;
    for (l = 0; l < GK_VR_W; ++l) {
        int i = ii[l], j = jj[l];
        f0[j] += b[0][l];
        f0[i] -= b[0][l];
        f1[j] += b[1][l];
        f1[i] -= b[1][l];
        f2[j] += b[2][l];
        f2[i] -= b[2][l];
        if (rot) {
            t0[j] += b[6][l];
            t0[i] += b[3][l];
            t1[j] += b[7][l];
            t1[i] += b[4][l];
            t2[j] += b[8][l];
            t2[i] += b[5][l];
        }
    }
}

#if GK__FREC
/* a block's forces and torques added to the particles' records (GK__FREC):
 * lane l's record for j is (f, tj), for i (-f, ti), lane after lane, j before
 * i, as gk__scatter_buf_3d adds them component by component. One 8 x 8
 * transpose of (f, tj, ti0, ti1) gives each lane's j record; its i record is
 * a two-source permutation of that row and ti2 (a second transpose cost more:
 * the shuffles were a sixth of the 3D force loop) */
GK_FORCE_INLINE void gk__scatter_rec_3d(double *GK_RESTRICT frec, const int32_t *ii, const int32_t *jj,
                                        const gk_contact_out_w *o, unsigned rot) {
    const gk_vd zero = gk_vd_zero();
    /* -0.0 in lanes 0-2: the i record's -f, exactly */
    const gk_vd neg = _mm512_set_pd(0.0, 0.0, 0.0, 0.0, 0.0, -0.0, -0.0, -0.0);
    gk_vd r[8], ti2 = rot ? o->ti[2] : zero;
    int k, l;
    GK_UNROLL
    for (k = 0; k < 3; ++k) {
        r[k] = o->f[k];
        r[3 + k] = rot ? o->tj[k] : zero;
    }
    r[6] = rot ? o->ti[0] : zero;
    r[7] = rot ? o->ti[1] : zero;
    gk_vd_transpose8(r); /* r[l] = (f, tj, ti0, ti1) of lane l */
    GK_UNROLL
    for (l = 0; l < 8; ++l) {
        double *aj = frec + 8 * (size_t)jj[l], *ai = frec + 8 * (size_t)ii[l];
        /* (f, tj, 0, 0) and (-f, ti0, ti1, ti2 of lane l, 0, 0) */
        const __m512i idx = _mm512_set_epi64(0, 0, 8 + l, 7, 6, 2, 1, 0);
        gk_vd rj = _mm512_maskz_mov_pd(0x3f, r[l]);
        gk_vd ri = _mm512_xor_pd(_mm512_maskz_permutex2var_pd(0x3f, r[l], idx, ti2), neg);
        gk_vd_store(aj, gk_vd_add(gk_vd_load(aj), rj));
        gk_vd_store(ai, gk_vd_add(gk_vd_load(ai), ri));
    }
}

/* records for n particles, all zero; 0 if they cannot be had (the loop then
 * scatters into f and t as without them: the same bits) */
static int gk__frec_ready(gk_rve *rve) {
    size_t n = (size_t)rve->n;
    if (rve->frec_cap < n) { /* nothing to keep: the old records are all zero */
        if (gk_realloc(&rve->def.alloc, (void **)&rve->frec, 0, n, 8 * sizeof(double))) return 0;
        memset(rve->frec, 0, n * 8 * sizeof(double));
        rve->frec_cap = n;
    }
    return 1;
}

/* f, t of particles [0, n) from the records, zeroing them for the next step */
static void gk__frec_unpack(gk_rve *rve, int rot) {
    double *rec = rve->frec;
    const gk_vd zero = gk_vd_zero();
    int n = rve->n, p, k;
    for (p = 0; p + 8 <= n; p += 8) {
        gk_vd r[8];
        GK_UNROLL
        for (k = 0; k < 8; ++k) {
            r[k] = gk_vd_load(rec + 8 * (size_t)(p + k));
            gk_vd_store(rec + 8 * (size_t)(p + k), zero);
        }
        gk_vd_transpose8(r);
        GK_UNROLL
        for (k = 0; k < 3; ++k) {
            gk_vd_store(rve->f[k] + p, r[k]);
            if (rot) gk_vd_store(rve->t[k] + p, r[3 + k]);
        }
    }
    for (; p < n; ++p) {
        double *a = rec + 8 * (size_t)p;
        for (k = 0; k < 3; ++k) {
            rve->f[k][p] = a[k];
            if (rot) rve->t[k][p] = a[3 + k];
        }
        memset(a, 0, 8 * sizeof *a);
    }
}
#endif

GK_FORCE_INLINE void gk__forces_simd_2d(gk_rve *rve, const gk__stepctx *x, int c0, int c1, gk_law law,
                                        unsigned fl) {
    const gk_law_consts K = rve->K; /* a local copy: its broadcasts stay out of the loop */
    const int32_t *pi = rve->pl.i, *pj = rve->pl.j, n = rve->n;
    const gk_vr zero = gk_vr_zero(), one = gk_vr_set1(1), dt = gk_vr_set1(x->dt);
    const gk_vr G0 = gk_vr_set1(x->G[0]), G1 = gk_vr_set1(x->G[1]), G3 = gk_vr_set1(x->G[3]),
                G4 = gk_vr_set1(x->G[4]);
    const gk_vr wa = gk_vr_set1(x->wa[2]);
    gk_real b[4][GK_VR_W];
    gk_vd H[9];
    const uint64_t *lut = gk__bitbytes;
    int c = c0, pend = -1, k;
    for (k = 0; k < 9; ++k) H[k] = gk_vd_set1(x->hd[k]); /* hoisted: stores to doubles could alias x->hd */
    for (; c + GK_VR_W <= c1; c += GK_VR_W) {
        const int32_t *ii = pi + c, *jj = pj + c;
        gk_vr d[3], ri, rj, vx, vy, mi = zero, mj = zero, wi = wa, wj = wa, fh = zero, m = zero;
        gk_vrm in, slide;
        gk_contact_out_w o;
        gk__iwin win;
        gk__iwin_make(ii, n, &win);
        gk__simd_branch(rve, H, ii, jj, &win, 2, d);
        ri = GK__GI(rve->r, ii, &win);
        rj = gk_vr_gather(rve->r, jj);
        vx = gk_vr_add(gk_vr_sub(gk_vr_gather(rve->v[0], jj), GK__GI(rve->v[0], ii, &win)),
                       gk_vr_add(gk_vr_mul(G0, d[0]), gk_vr_mul(G1, d[1])));
        vy = gk_vr_add(gk_vr_sub(gk_vr_gather(rve->v[1], jj), GK__GI(rve->v[1], ii, &win)),
                       gk_vr_add(gk_vr_mul(G3, d[0]), gk_vr_mul(G4, d[1])));
        if (fl & GK_PHYS_VISCOUS) {
            mi = gk_vr_div(one, GK__GI(rve->minv, ii, &win));
            mj = gk_vr_div(one, gk_vr_gather(rve->minv, jj));
        }
        if (fl & GK_PHYS_ROTATION) {
            wi = gk_vr_add(wa, GK__GI(rve->w[2], ii, &win));
            wj = gk_vr_add(wa, gk_vr_gather(rve->w[2], jj));
        }
        if (fl & GK_PHYS_TANGENT) fh = gk_vr_load(rve->ft[0] + c);
        if (fl & GK_PHYS_ROLLING) m = gk_vr_load(rve->mr[2] + c);
        in =
            gk_contact_2d_w(&K, law, fl, d[0], d[1], ri, rj, mi, mj, vx, vy, wi, wj, dt, &fh, &m, &slide, &o);
        if (fl & GK_PHYS_TANGENT) gk_vr_store(rve->ft[0] + c, fh);
        if (fl & GK_PHYS_ROLLING) gk_vr_store(rve->mr[2] + c, m);
        gk__simd_state(rve->cs + c, in, slide, lut);
        if (x->store) {
            gk_vr_store(rve->fc[0] + c, o.f[0]);
            gk_vr_store(rve->fc[1] + c, o.f[1]);
            if (fl & GK_PHYS_ROTATION) {
                gk_vr_store(rve->tci[2] + c, o.ti[2]);
                gk_vr_store(rve->tcj[2] + c, o.tj[2]);
            }
        }
        if (x->scatter) {
            /* scatter the previous block now (its buffer stores have retired: no
             * store-forwarding stall) and buffer this one; pair order is kept */
            if (pend >= 0) gk__scatter_buf_2d(rve, pi + pend, pj + pend, b, fl & GK_PHYS_ROTATION);
            gk_vr_storeu(b[0], o.f[0]);
            gk_vr_storeu(b[1], o.f[1]);
            if (fl & GK_PHYS_ROTATION) {
                gk_vr_storeu(b[2], o.ti[2]);
                gk_vr_storeu(b[3], o.tj[2]);
            }
            pend = c;
        }
    }
    if (pend >= 0) gk__scatter_buf_2d(rve, pi + pend, pj + pend, b, fl & GK_PHYS_ROTATION);
    gk__forces_ref_2d(rve, x, c, c1, law, fl);
}

GK_FORCE_INLINE void gk__forces_simd_3d(gk_rve *rve, const gk__stepctx *x, int c0, int c1, gk_law law,
                                        unsigned fl) {
    const gk_law_consts K = rve->K; /* a local copy: its broadcasts stay out of the loop */
    const int32_t *pi = rve->pl.i, *pj = rve->pl.j, n = rve->n;
    const gk_vr zero = gk_vr_zero(), one = gk_vr_set1(1), dt = gk_vr_set1(x->dt);
    gk_vr G[9], wa[3];
    gk_vd H[9];
    gk_real b[9][GK_VR_W];
    const uint64_t *lut = gk__bitbytes;
    int c = c0, k, pend = -1;
    GK_UNROLL
    for (k = 0; k < 9; ++k) {
        G[k] = gk_vr_set1(x->G[k]);
        H[k] = gk_vd_set1(x->hd[k]);
    }
    GK_UNROLL
    for (k = 0; k < 3; ++k) wa[k] = gk_vr_set1(x->wa[k]);
    for (; c + GK_VR_W <= c1; c += GK_VR_W) {
        const int32_t *ii = pi + c, *jj = pj + c;
        gk_vr d[3], v[3], wi[3], wj[3], fh[3], mh[3], ri, rj, mi = zero, mj = zero;
        gk_vrm in, slide;
        gk_contact_out_w o;
        gk__iwin win;
        gk__iwin_make(ii, n, &win);
        gk__simd_branch(rve, H, ii, jj, &win, 3, d);
        ri = GK__GI(rve->r, ii, &win);
        rj = gk_vr_gather(rve->r, jj);
        GK_UNROLL
        for (k = 0; k < 3; ++k) {
            v[k] = gk_vr_add(gk_vr_sub(gk_vr_gather(rve->v[k], jj), GK__GI(rve->v[k], ii, &win)),
                             gk_vr_add(gk_vr_add(gk_vr_mul(G[3 * k], d[0]), gk_vr_mul(G[3 * k + 1], d[1])),
                                       gk_vr_mul(G[3 * k + 2], d[2])));
            wi[k] = (fl & GK_PHYS_ROTATION) ? gk_vr_add(wa[k], GK__GI(rve->w[k], ii, &win)) : wa[k];
            wj[k] = (fl & GK_PHYS_ROTATION) ? gk_vr_add(wa[k], gk_vr_gather(rve->w[k], jj)) : wa[k];
            fh[k] = (fl & GK_PHYS_TANGENT) ? gk_vr_load(rve->ft[k] + c) : zero;
            mh[k] = (fl & GK_PHYS_ROLLING) ? gk_vr_load(rve->mr[k] + c) : zero;
        }
        if (fl & GK_PHYS_VISCOUS) {
            mi = gk_vr_div(one, GK__GI(rve->minv, ii, &win));
            mj = gk_vr_div(one, gk_vr_gather(rve->minv, jj));
        }
        in = gk_contact_3d_w(&K, law, fl, d, ri, rj, mi, mj, v, wi, wj, dt, fh, mh, &slide, &o);
        GK_UNROLL
        for (k = 0; k < 3; ++k) {
            if (fl & GK_PHYS_TANGENT) gk_vr_store(rve->ft[k] + c, fh[k]);
            if (fl & GK_PHYS_ROLLING) gk_vr_store(rve->mr[k] + c, mh[k]);
            if (x->store) {
                gk_vr_store(rve->fc[k] + c, o.f[k]);
                if (fl & GK_PHYS_ROTATION) {
                    gk_vr_store(rve->tci[k] + c, o.ti[k]);
                    gk_vr_store(rve->tcj[k] + c, o.tj[k]);
                }
            }
        }
        gk__simd_state(rve->cs + c, in, slide, lut);
#if GK__FREC
        if (x->scatter == 2) { /* into the records (gk__forces leaves no tail) */
            gk__scatter_rec_3d(rve->frec, ii, jj, &o, fl & GK_PHYS_ROTATION);
            continue;
        }
#endif
        if (x->scatter) { /* pipelined as in 2D */
            if (pend >= 0) gk__scatter_buf_3d(rve, pi + pend, pj + pend, b, fl & GK_PHYS_ROTATION);
            GK_UNROLL
            for (k = 0; k < 3; ++k) {
                gk_vr_storeu(b[k], o.f[k]);
                if (fl & GK_PHYS_ROTATION) {
                    gk_vr_storeu(b[3 + k], o.ti[k]);
                    gk_vr_storeu(b[6 + k], o.tj[k]);
                }
            }
            pend = c;
        }
    }
    if (pend >= 0) gk__scatter_buf_3d(rve, pi + pend, pj + pend, b, fl & GK_PHYS_ROTATION);
    gk__forces_ref_3d(rve, x, c, c1, law, fl);
}
#undef GK__GI
#endif /* GK_VR_W > 1 */

static void gk__inner_filter_all(const gk_rve *rve, gk_pairlist *nl, int lookup, int32_t *map) {
    int32_t *oin = rve->outer_in;
    int c0 = 0;
#ifdef GK__FILTER_SIMD
    if (!(rve->def.flags & GK_RVE_SCALAR)) {
        if (rve->dim == 2)
            c0 = lookup ? gk__inner_filter_simd(rve, nl, 2, 1, oin, map)
                        : gk__inner_filter_simd(rve, nl, 2, 0, oin, map);
        else
            c0 = lookup ? gk__inner_filter_simd(rve, nl, 3, 1, oin, map)
                        : gk__inner_filter_simd(rve, nl, 3, 0, oin, map);
    }
#endif
    if (rve->dim == 2 && lookup)
        gk__inner_filter(rve, nl, 2, 1, oin, map, c0);
    else if (rve->dim == 2)
        gk__inner_filter(rve, nl, 2, 0, oin, map, c0);
    else if (lookup)
        gk__inner_filter(rve, nl, 3, 1, oin, map, c0);
    else
        gk__inner_filter(rve, nl, 3, 0, oin, map, c0);
}

/* instantiate a kernel with constant law and flags (pay only for what is on):
 * the common flag sets get their own copy, the rest share one with fl */
#define GK__FLAG_SETS(fn, rve, x, c0, c1, LAW, fl)                       \
    do {                                                                 \
        if ((fl) == 0u)                                                  \
            fn(rve, x, c0, c1, LAW, 0u);                                 \
        else if ((fl) == GK_PHYS_TANGENT)                                \
            fn(rve, x, c0, c1, LAW, GK_PHYS_TANGENT);                    \
        else if ((fl) == (GK_PHYS_TANGENT | GK_PHYS_ROTATION))           \
            fn(rve, x, c0, c1, LAW, GK_PHYS_TANGENT | GK_PHYS_ROTATION); \
        else                                                             \
            fn(rve, x, c0, c1, LAW, fl);                                 \
    } while (0)

/* one kernel of each law of GK_LAW_TABLE (gk_contact.h) for the dimension and path */
#if GK_VR_W > 1
#define GK__WIDE(rve, x, c0, c1, LAW, fl)                               \
    if (wide) {                                                         \
        if ((rve)->dim == 2)                                            \
            GK__FLAG_SETS(gk__forces_simd_2d, rve, x, c0, c1, LAW, fl); \
        else                                                            \
            GK__FLAG_SETS(gk__forces_simd_3d, rve, x, c0, c1, LAW, fl); \
    } else
#else
#define GK__WIDE(rve, x, c0, c1, LAW, fl)
#endif
#define GK__LAW_KERNELS(E, name)                                     \
    case E:                                                          \
        GK__WIDE(rve, x, c0, c1, E, fl)                              \
        if (rve->dim == 2)                                           \
            GK__FLAG_SETS(gk__forces_ref_2d, rve, x, c0, c1, E, fl); \
        else                                                         \
            GK__FLAG_SETS(gk__forces_ref_3d, rve, x, c0, c1, E, fl); \
        break;

/* the wide kernels run unless GK_RVE_SCALAR or cohesion */
static int gk__wide(const gk_rve *rve) {
    return !(rve->def.flags & GK_RVE_SCALAR) && !(rve->phys & GK_PHYS_COHESION);
}

/* whether the scattering loop may use the force records (GK__FREC): a 3D RVE
 * of at most GK_DEM_FREC_MAX particles on the wide kernels */
static int gk__frec_usable(const gk_rve *rve) {
    return GK__FREC && rve->dim == 3 && rve->n <= GK_DEM_FREC_MAX && gk__wide(rve);
}

/* pair forces of [c0, c1) */
static void gk__forces_range(gk_rve *rve, const gk__stepctx *x, int c0, int c1) {
    unsigned fl = rve->phys;
    int wide = gk__wide(rve);
    (void)wide;
    switch (rve->def.mat.law) {
        GK_LAW_TABLE(GK__LAW_KERNELS)
    default: break;
    }
}
#undef GK__LAW_KERNELS
#undef GK__WIDE
#undef GK__FLAG_SETS

static int gk__nthreads(const gk_rve *rve);

static void gk__reduce_range(gk_rve *rve, int p0, int p1, int pad);
static int gk__reduce_pad(gk_rve *rve);

/* pair forces and their per-particle sums (f, t) for this step. Threads, and
 * one thread on up to GK_DEM_GATHER_MAX pairs, store per-pair forces and
 * gather each particle's sum; one thread on more pairs scatters in the force
 * loop (the gather's reads then miss the cache). The same sums in the same
 * order either way. want_store keeps per-pair forces and torques (stress,
 * tangent). Where the force records can be used, scattering wins from
 * GK_DEM_GATHER_MAX_3D pairs on. */
static void gk__forces(gk_rve *rve, gk__stepctx *x, int want_store) {
    int nc = rve->pl.n, nth = gk__nthreads(rve), k, rec = gk__frec_usable(rve), gmax = GK_DEM_GATHER_MAX;
    if (rec && GK_DEM_GATHER_MAX_3D < gmax) gmax = GK_DEM_GATHER_MAX_3D;
    if (nth <= 1 && nc <= gmax) {
        x->scatter = 0;
        x->store = 1;
        GK_DEM_PHASE(1, 0);
        gk__forces_range(rve, x, 0, nc);
        GK_DEM_PHASE(1, 1);
        GK_DEM_PHASE(2, 0);
        gk__reduce_range(rve, 0, rve->n, 0);
        GK_DEM_PHASE(2, 1);
    } else if (nth <= 1) {
        x->scatter = 1;
        x->store = want_store;
        GK_DEM_PHASE(1, 0);
#if GK__FREC
        if (rec && gk__frec_ready(rve)) {
            /* whole blocks into the records, which become f and t; then the
             * last pairs (the last in pair order) added to f and t */
            int cb = nc - nc % GK_VR_W;
            x->scatter = 2;
            gk__forces_range(rve, x, 0, cb);
            gk__frec_unpack(rve, GK__HAS_ROT(rve));
            x->scatter = 1;
            gk__forces_range(rve, x, cb, nc);
            GK_DEM_PHASE(1, 1);
            return;
        }
#endif
        for (k = 0; k < 3; ++k) {
            if (rve->f[k]) memset(rve->f[k], 0, (size_t)rve->n * sizeof(gk_real));
            if (rve->t[k]) memset(rve->t[k], 0, (size_t)rve->n * sizeof(gk_real));
        }
        gk__forces_range(rve, x, 0, nc);
        GK_DEM_PHASE(1, 1);
    } else {
        int b, n = rve->n, pad = gk__reduce_pad(rve);
        x->scatter = 0;
        x->store = 1;
        GK_DEM_PHASE(1, 0);
        GK_OMP(parallel for num_threads(nth) schedule(static))
        for (b = 0; b < nth * 4; ++b) {
            /* chunk starts on a multiple of 16 pairs: aligned SIMD loads, same lanes as serial */
            long c0 = ((long)nc * b / (nth * 4)) & ~15L,
                 c1 = b + 1 == nth * 4 ? nc : ((long)nc * (b + 1) / (nth * 4)) & ~15L;
            GK_DEM_PHASE(1, 2);
            gk__forces_range(rve, x, (int)c0, (int)c1);
            GK_DEM_PHASE(1, 3);
        }
        GK_DEM_PHASE(1, 1);
        GK_DEM_PHASE(2, 0);
        GK_OMP(parallel for num_threads(nth) schedule(static))
        for (b = 0; b < nth * 4; ++b) {
            long p0 = (long)n * b / (nth * 4), p1 = (long)n * (b + 1) / (nth * 4);
            GK_DEM_PHASE(2, 2);
            gk__reduce_range(rve, (int)p0, (int)p1, pad);
            GK_DEM_PHASE(2, 3);
        }
        GK_DEM_PHASE(2, 1);
    }
}

/* ---------------------------------------------------------------- sums and integration */
/* 3D: the pairs where p is j lie far apart in the pair arrays (a plane of
 * cells away); fetching them this many entries ahead made a 10^5-sphere
 * step on 2 threads about 10 % faster (bench/README.md). 2D gained nothing. */
#define GK__REDUCE_AHEAD 16
/* 2D lists above GK_DEM_GATHER_MAX pairs: the slots per side (pairs where p
 * is j, where it is i) that a particle's gather reads without a branch on its
 * pair count; beyond them a loop. On such lists the branch predictor cannot
 * learn every particle's count, and a mispredicted loop exit costs more than
 * reading the padding (bench/README.md). */
#define GK__GATHER_SLOTS_2D 3

/* Per-particle sums of the pair forces in the fixed order (pairs where p is j,
 * ascending; then pairs where p is i, ascending), by gathering: used with
 * threads and for small lists. A single thread on a large list scatters inside
 * the force loop instead (gk__scatter_*), in pair order, which is the same
 * order and so gives the same bits. K > 0: the first K pairs of each side
 * are read without a branch on the particle's count (gk__reduce_pad must
 * have said yes); K = 0: plain loops. */
GK_FORCE_INLINE void gk__reduce_kernel(gk_rve *rve, int p0, int p1, const int dim, const int rot,
                                       const int K) {
    const int32_t *GK_RESTRICT start = rve->pl.start, *GK_RESTRICT jst = rve->jstart,
                               *GK_RESTRICT jl = rve->jlist;
    const gk_real *fc0 = rve->fc[0], *fc1 = rve->fc[1], *fc2 = dim == 3 ? rve->fc[2] : NULL;
    gk_real *f0 = rve->f[0], *f1 = rve->f[1], *f2 = dim == 3 ? rve->f[2] : NULL;
    const int32_t jend = jst[rve->n], nc = rve->pl.n;
    int p, e, k, q;
/* pair c into the sums: the force with OP (+= where p is j, -= where it is i), the torque tc on p */
#define GK__RSUM(c, OP, tc)                                    \
    do {                                                       \
        a0 OP fc0[c];                                          \
        a1 OP fc1[c];                                          \
        if (dim == 3) a2 OP fc2[c];                            \
        if (rot) {                                             \
            if (dim == 2)                                      \
                t[2] += rve->tc[2][c];                         \
            else {                                             \
                GK_UNROLL                                      \
                for (k = 0; k < 3; ++k) t[k] += rve->tc[k][c]; \
            }                                                  \
        }                                                      \
    } while (0)
    for (p = p0; p < p1; ++p) {
        gk_real a0 = 0, a1 = 0, a2 = 0, t[3] = {0, 0, 0};
        const int e0 = jst[p], e1 = jst[p + 1], s0 = start[p], s1 = start[p + 1];
        /* a slot past the particle's pairs reads pair nc, whose force and
         * torques are +0: a sum started at +0 is never -0, so adding or
         * subtracting +0 changes no bit */
        for (q = 0; q < K; ++q) {
            const int32_t cj = jl[e0 + q], c = e0 + q < e1 ? cj : nc;
            GK__RSUM(c, +=, tcj);
        }
        for (e = e0 + K; e < e1; ++e) {
            int c = jl[e];
            if (dim == 3 && e + GK__REDUCE_AHEAD < jend) {
                int r = jl[e + GK__REDUCE_AHEAD];
                GK_PREFETCH(fc0 + r);
                GK_PREFETCH(fc1 + r);
                GK_PREFETCH(fc2 + r);
                if (rot) {
                    GK_UNROLL
                    for (k = 0; k < 3; ++k) GK_PREFETCH(rve->tcj[k] + r);
                }
            }
            GK__RSUM(c, +=, tcj);
        }
        for (q = 0; q < K; ++q) {
            const int32_t c = s0 + q < s1 ? s0 + q : nc;
            GK__RSUM(c, -=, tci);
        }
        for (e = s0 + K; e < s1; ++e) GK__RSUM(e, -=, tci);
        f0[p] = a0;
        f1[p] = a1;
        if (dim == 3) f2[p] = a2;
        if (rot) {
            if (dim == 2)
                rve->t[2][p] = t[2];
            else {
                GK_UNROLL
                for (k = 0; k < 3; ++k) rve->t[k][p] = t[k];
            }
        }
    }
#undef GK__RSUM
}

/* whether the gather reads padded slots (2D lists above GK_DEM_GATHER_MAX
 * pairs); if so the pair nc (one past the last) is made its zero pair */
static int gk__reduce_pad(gk_rve *rve) {
    int nc = rve->pl.n;
    if (rve->dim != 2 || nc <= GK_DEM_GATHER_MAX || rve->pcap < (size_t)nc + GK__PAIR_PAD) return 0;
    rve->fc[0][nc] = rve->fc[1][nc] = 0;
    if (GK__HAS_ROT(rve)) rve->tci[2][nc] = rve->tcj[2][nc] = 0;
    return 1;
}

/* pad: gk__reduce_pad's answer */
static void gk__reduce_range(gk_rve *rve, int p0, int p1, int pad) {
    int rot = GK__HAS_ROT(rve);
    if (rve->dim == 2 && pad) {
        if (rot)
            gk__reduce_kernel(rve, p0, p1, 2, 1, GK__GATHER_SLOTS_2D);
        else
            gk__reduce_kernel(rve, p0, p1, 2, 0, GK__GATHER_SLOTS_2D);
    } else if (rve->dim == 2) {
        if (rot)
            gk__reduce_kernel(rve, p0, p1, 2, 1, 0);
        else
            gk__reduce_kernel(rve, p0, p1, 2, 0, 0);
    } else {
        if (rot)
            gk__reduce_kernel(rve, p0, p1, 3, 1, 0);
        else
            gk__reduce_kernel(rve, p0, p1, 3, 0, 0);
    }
}

/* local damping, YADE/PFC component form: a <- a (1 - alpha sign(a (v + a dt/2))).
 * Branch-free (the sign is random: a branch would mispredict half the time);
 * 1 - alpha * s with s in {-1, 0, 1} gives exactly 1 + alpha, 1, 1 - alpha. */
GK_FORCE_INLINE gk_real gk__damp_component(gk_real a, gk_real v, gk_real dt, gk_real alpha) {
    gk_real x = a * (v + (gk_real)0.5 * dt * a);
    gk_real sg = (gk_real)(x > 0) - (gk_real)(x < 0);
    return a * ((gk_real)1 - alpha * sg);
}

/* Keep s in [0, 1) every step, shifting the list references by the same whole
 * period, so that when a position wraps depends on the dynamics only, never
 * on when a list is rebuilt (s_j - s_i rounds differently after a wrap). */
GK_FORCE_INLINE void gk__wrap(gk_rve *rve, int p, int k) {
    double fl = floor(rve->s[k][p]);
    rve->s[k][p] -= fl;
    rve->s0[k][p] -= fl;
    rve->o0[k][p] -= fl;
}

/* leap-frog for particles [p0, p1) with the force sums in f, t; returns the
 * largest squared non-affine displacement since the last build; *bad if a
 * non-finite value appeared. damp: 0 none, 1 component, 2 vector. */
GK_FORCE_INLINE double gk__integrate_kernel(gk_rve *rve, const gk__stepctx *x, const double *hinv,
                                            const double *hnew, int p0, int p1, int *bad, const int dim,
                                            const int rot, const int damp) {
    const gk_real dt = x->dt, alpha = (gk_real)rve->def.damping, hdt = (gk_real)0.5 * dt;
    const gk_real *GK_RESTRICT minv = rve->minv, *GK_RESTRICT Iinv = rve->Iinv;
    double *s0 = rve->s[0], *s1 = rve->s[1], *s2 = dim == 3 ? rve->s[2] : NULL;
    const double *r0 = rve->s0[0], *r1 = rve->s0[1], *r2 = dim == 3 ? rve->s0[2] : NULL;
    gk_real *GK_RESTRICT v0 = rve->v[0], *GK_RESTRICT v1 = rve->v[1],
                         *GK_RESTRICT v2 = dim == 3 ? rve->v[2] : NULL;
    const gk_real *GK_RESTRICT f0 = rve->f[0], *GK_RESTRICT f1 = rve->f[1],
                               *GK_RESTRICT f2 = dim == 3 ? rve->f[2] : NULL;
    const double h00 = hinv[0], h01 = hinv[1], h02 = hinv[2], h10 = hinv[3], h11 = hinv[4], h12 = hinv[5],
                 h20 = hinv[6], h21 = hinv[7], h22 = hinv[8];
    const double g00 = hnew[0], g01 = hnew[1], g02 = hnew[2], g10 = hnew[3], g11 = hnew[4], g12 = hnew[5],
                 g20 = hnew[6], g21 = hnew[7], g22 = hnew[8];
    double m2 = 0.0, chk = 0.0;
    int p;
    for (p = p0; p < p1; ++p) {
        gk_real a0 = f0[p] * minv[p], a1 = f1[p] * minv[p], a2 = dim == 3 ? f2[p] * minv[p] : 0;
        gk_real n0, n1, n2 = 0;
        double e0, e1, e2 = 0.0, u0, u1, u2 = 0.0, u2sum;
        if (damp == 1) {
            a0 = gk__damp_component(a0, v0[p], dt, alpha);
            a1 = gk__damp_component(a1, v1[p], dt, alpha);
            if (dim == 3) a2 = gk__damp_component(a2, v2[p], dt, alpha);
        } else if (damp == 2) {
            gk_real w0 = v0[p] + hdt * a0, w1 = v1[p] + hdt * a1, w2 = dim == 3 ? v2[p] + hdt * a2 : 0;
            gk_real vv = w0 * w0 + w1 * w1 + (dim == 3 ? w2 * w2 : 0),
                    aa = a0 * a0 + a1 * a1 + (dim == 3 ? a2 * a2 : 0);
            if (vv > 0) {
                gk_real sc = alpha * (gk_real)sqrt(aa) / (gk_real)sqrt(vv);
                a0 = a0 - sc * w0;
                a1 = a1 - sc * w1;
                if (dim == 3) a2 = a2 - sc * w2;
            }
        }
        n0 = v0[p] + dt * a0;
        n1 = v1[p] + dt * a1;
        v0[p] = n0;
        v1[p] = n1;
        if (dim == 3) {
            n2 = v2[p] + dt * a2;
            v2[p] = n2;
        }
        chk += (double)(n0 < 0 ? -n0 : n0) + (double)(n1 < 0 ? -n1 : n1) + (double)(n2 < 0 ? -n2 : n2);
        {
            double d0 = (double)(n0 * dt), d1 = (double)(n1 * dt), d2 = (double)(n2 * dt);
            if (dim == 2) {
                s0[p] += h00 * d0 + h01 * d1;
                s1[p] += h10 * d0 + h11 * d1;
                gk__wrap(rve, p, 0);
                gk__wrap(rve, p, 1);
                e0 = s0[p] - r0[p];
                e1 = s1[p] - r1[p];
                u0 = g00 * e0 + g01 * e1;
                u1 = g10 * e0 + g11 * e1;
                u2sum = u0 * u0 + u1 * u1;
            } else {
                s0[p] += h00 * d0 + h01 * d1 + h02 * d2;
                s1[p] += h10 * d0 + h11 * d1 + h12 * d2;
                s2[p] += h20 * d0 + h21 * d1 + h22 * d2;
                gk__wrap(rve, p, 0);
                gk__wrap(rve, p, 1);
                gk__wrap(rve, p, 2);
                e0 = s0[p] - r0[p];
                e1 = s1[p] - r1[p];
                e2 = s2[p] - r2[p];
                u0 = g00 * e0 + g01 * e1 + g02 * e2;
                u1 = g10 * e0 + g11 * e1 + g12 * e2;
                u2 = g20 * e0 + g21 * e1 + g22 * e2;
                u2sum = u0 * u0 + u1 * u1 + u2 * u2;
            }
            m2 = u2sum > m2 ? u2sum : m2;
        }
        if (rot) {
            if (dim == 2) {
                gk_real aw = rve->t[2][p] * Iinv[p], wn;
                if (damp) aw = gk__damp_component(aw, rve->w[2][p], dt, alpha); /* 2D: one component */
                wn = rve->w[2][p] + dt * aw;
                rve->w[2][p] = wn;
                chk += (double)(wn < 0 ? -wn : wn);
                rve->theta[p] += ((double)x->wa[2] + (double)wn) * (double)dt;
            } else {
                gk_real aw[3], wn;
                int k;
                GK_UNROLL
                for (k = 0; k < 3; ++k) aw[k] = rve->t[k][p] * Iinv[p];
                if (damp == 1) {
                    GK_UNROLL
                    for (k = 0; k < 3; ++k) aw[k] = gk__damp_component(aw[k], rve->w[k][p], dt, alpha);
                } else if (damp == 2) {
                    gk_real ve[3], vv = 0, aa = 0;
                    GK_UNROLL
                    for (k = 0; k < 3; ++k) {
                        ve[k] = rve->w[k][p] + hdt * aw[k];
                        vv += ve[k] * ve[k];
                        aa += aw[k] * aw[k];
                    }
                    if (vv > 0) {
                        gk_real sc = alpha * (gk_real)sqrt(aa) / (gk_real)sqrt(vv);
                        GK_UNROLL
                        for (k = 0; k < 3; ++k) aw[k] = aw[k] - sc * ve[k];
                    }
                }
                GK_UNROLL
                for (k = 0; k < 3; ++k) {
                    wn = rve->w[k][p] + dt * aw[k];
                    rve->w[k][p] = wn;
                    chk += (double)(wn < 0 ? -wn : wn);
                }
            }
        } else if (dim == 2) {
            rve->theta[p] += (double)x->wa[2] * (double)dt;
        }
    }
    if (!isfinite(chk) || !isfinite(m2)) *bad = 1;
    return m2;
}

#if GK_VR_W > 1
/* gk__integrate_kernel on GK_VR_W particles at a time: the same arithmetic
 * per lane, selects instead of branches. Velocities in the working precision,
 * positions in double (in the float build, two double vectors per group). */
GK_FORCE_INLINE gk_vr gk__damp_v(gk_vr a, gk_vr v, gk_vr hdt, gk_vr alpha) {
    const gk_vr one = gk_vr_set1(1), zero = gk_vr_zero();
    gk_vr xx = gk_vr_mul(a, gk_vr_add(v, gk_vr_mul(hdt, a)));
    gk_vr sg =
        gk_vr_sub(gk_vr_select(gk_vr_gt(xx, zero), one, zero), gk_vr_select(gk_vr_lt(xx, zero), one, zero));
    return gk_vr_mul(a, gk_vr_sub(one, gk_vr_mul(alpha, sg)));
}

/* double lanes of half hf of a working-precision vector (exact widening) */
GK_FORCE_INLINE gk_vd gk__vr_half(gk_vr a, int hf) {
#ifdef GK_REAL_FLOAT
    return gk_vd_from_vf(a, hf);
#else
    (void)hf;
    return a;
#endif
}

GK_FORCE_INLINE double gk__integrate_simd(gk_rve *rve, const gk__stepctx *x, const double *hinv,
                                          const double *hnew, int p0, int p1, int *bad, const int dim,
                                          const int rot, const int damp) {
    const gk_vr dt = gk_vr_set1(x->dt), alpha = gk_vr_set1((gk_real)rve->def.damping),
                hdt = gk_vr_set1((gk_real)0.5 * x->dt), zero = gk_vr_zero();
    const gk_vd dtd = gk_vd_set1((double)x->dt), wad = gk_vd_set1((double)x->wa[2]), dzero = gk_vd_zero(),
                done = gk_vd_set1(1.0);
    gk_vd H[9], Gn[9], vm2 = gk_vd_zero();
    gk_vr vchk = zero;
    double m2 = 0.0, chk = 0.0, buf[GK_VD_W];
    gk_real bufr[GK_VR_W];
    int p = p0, k, l, hf;
    for (k = 0; k < 9; ++k) {
        H[k] = gk_vd_set1(hinv[k]);
        Gn[k] = gk_vd_set1(hnew[k]);
    }
    for (; p + GK_VR_W <= p1; p += GK_VR_W) {
        gk_vr minv = gk_vr_loadu(rve->minv + p), a[3], v[3], nv[3], d[3];
        GK_UNROLL
        for (k = 0; k < dim; ++k) {
            a[k] = gk_vr_mul(gk_vr_loadu(rve->f[k] + p), minv);
            v[k] = gk_vr_loadu(rve->v[k] + p);
        }
        if (damp == 1) {
            GK_UNROLL
            for (k = 0; k < dim; ++k) a[k] = gk__damp_v(a[k], v[k], hdt, alpha);
        } else if (damp == 2) {
            gk_vr w[3], vv, aa, sc;
            gk_vrm pos;
            GK_UNROLL
            for (k = 0; k < dim; ++k) w[k] = gk_vr_add(v[k], gk_vr_mul(hdt, a[k]));
            vv = gk_vr_add(gk_vr_mul(w[0], w[0]), gk_vr_mul(w[1], w[1]));
            aa = gk_vr_add(gk_vr_mul(a[0], a[0]), gk_vr_mul(a[1], a[1]));
            if (dim == 3) {
                vv = gk_vr_add(vv, gk_vr_mul(w[2], w[2]));
                aa = gk_vr_add(aa, gk_vr_mul(a[2], a[2]));
            }
            pos = gk_vr_gt(vv, zero);
            sc = gk_vr_div(gk_vr_mul(alpha, gk_vr_sqrt(aa)), gk_vr_sqrt(vv));
            GK_UNROLL
            for (k = 0; k < dim; ++k) a[k] = gk_vr_select(pos, gk_vr_sub(a[k], gk_vr_mul(sc, w[k])), a[k]);
        }
        GK_UNROLL
        for (k = 0; k < dim; ++k) {
            nv[k] = gk_vr_add(v[k], gk_vr_mul(dt, a[k]));
            gk_vr_storeu(rve->v[k] + p, nv[k]);
            vchk = gk_vr_add(vchk, gk_vr_abs(nv[k]));
            d[k] = gk_vr_mul(nv[k], dt);
        }
        for (hf = 0; hf < GK_VR_DHALVES; ++hf) {
            int q = p + hf * GK_VD_W;
            gk_vd dd[3], sp[3], r0[3], e[3], u[3], u2;
            GK_UNROLL
            for (k = 0; k < dim; ++k) dd[k] = gk__vr_half(d[k], hf);
            gk_vdm out = gk_vd_lt(dzero, dzero); /* no lane */
            GK_UNROLL
            for (k = 0; k < dim; ++k) {
                gk_vd inc = gk_vd_add(gk_vd_mul(H[3 * k], dd[0]), gk_vd_mul(H[3 * k + 1], dd[1]));
                if (dim == 3) inc = gk_vd_add(inc, gk_vd_mul(H[3 * k + 2], dd[2]));
                sp[k] = gk_vd_add(gk_vd_loadu(rve->s[k] + q), inc);
                out = gk_vdm_or(out, gk_vdm_or(gk_vd_lt(sp[k], dzero), gk_vdm_not(gk_vd_lt(sp[k], done))));
            }
            /* gk__wrap where a lane left [0, 1) (rare); elsewhere floor is 0 and changes nothing */
            if (gk_vdm_any(out)) {
                GK_UNROLL
                for (k = 0; k < dim; ++k) {
                    gk_vd fl = gk_vd_floor(sp[k]);
                    r0[k] = gk_vd_sub(gk_vd_loadu(rve->s0[k] + q), fl);
                    sp[k] = gk_vd_sub(sp[k], fl);
                    gk_vd_storeu(rve->s0[k] + q, r0[k]);
                    gk_vd_storeu(rve->o0[k] + q, gk_vd_sub(gk_vd_loadu(rve->o0[k] + q), fl));
                }
            } else {
                GK_UNROLL
                for (k = 0; k < dim; ++k) r0[k] = gk_vd_loadu(rve->s0[k] + q);
            }
            GK_UNROLL
            for (k = 0; k < dim; ++k) {
                gk_vd_storeu(rve->s[k] + q, sp[k]);
                e[k] = gk_vd_sub(sp[k], r0[k]);
            }
            GK_UNROLL
            for (k = 0; k < dim; ++k) {
                u[k] = gk_vd_add(gk_vd_mul(Gn[3 * k], e[0]), gk_vd_mul(Gn[3 * k + 1], e[1]));
                if (dim == 3) u[k] = gk_vd_add(u[k], gk_vd_mul(Gn[3 * k + 2], e[2]));
            }
            u2 = gk_vd_add(gk_vd_mul(u[0], u[0]), gk_vd_mul(u[1], u[1]));
            if (dim == 3) u2 = gk_vd_add(u2, gk_vd_mul(u[2], u[2]));
            vm2 = gk_vd_max(u2, vm2);
        }
        if (rot && dim == 2) {
            gk_vr aw = gk_vr_mul(gk_vr_loadu(rve->t[2] + p), gk_vr_loadu(rve->Iinv + p)),
                  w = gk_vr_loadu(rve->w[2] + p);
            if (damp) aw = gk__damp_v(aw, w, hdt, alpha);
            w = gk_vr_add(w, gk_vr_mul(dt, aw));
            gk_vr_storeu(rve->w[2] + p, w);
            vchk = gk_vr_add(vchk, gk_vr_abs(w));
            for (hf = 0; hf < GK_VR_DHALVES; ++hf) {
                double *th = rve->theta + p + hf * GK_VD_W;
                gk_vd_storeu(th,
                             gk_vd_add(gk_vd_loadu(th), gk_vd_mul(gk_vd_add(wad, gk__vr_half(w, hf)), dtd)));
            }
        } else if (rot) {
            gk_vr iinv = gk_vr_loadu(rve->Iinv + p), aw[3], w[3];
            for (k = 0; k < 3; ++k) {
                aw[k] = gk_vr_mul(gk_vr_loadu(rve->t[k] + p), iinv);
                w[k] = gk_vr_loadu(rve->w[k] + p);
            }
            if (damp == 1) {
                for (k = 0; k < 3; ++k) aw[k] = gk__damp_v(aw[k], w[k], hdt, alpha);
            } else if (damp == 2) {
                gk_vr ve[3], vv, aa, sc;
                gk_vrm pos;
                for (k = 0; k < 3; ++k) ve[k] = gk_vr_add(w[k], gk_vr_mul(hdt, aw[k]));
                vv = gk_vr_add(gk_vr_add(gk_vr_mul(ve[0], ve[0]), gk_vr_mul(ve[1], ve[1])),
                               gk_vr_mul(ve[2], ve[2]));
                aa = gk_vr_add(gk_vr_add(gk_vr_mul(aw[0], aw[0]), gk_vr_mul(aw[1], aw[1])),
                               gk_vr_mul(aw[2], aw[2]));
                pos = gk_vr_gt(vv, zero);
                sc = gk_vr_div(gk_vr_mul(alpha, gk_vr_sqrt(aa)), gk_vr_sqrt(vv));
                for (k = 0; k < 3; ++k)
                    aw[k] = gk_vr_select(pos, gk_vr_sub(aw[k], gk_vr_mul(sc, ve[k])), aw[k]);
            }
            for (k = 0; k < 3; ++k) {
                w[k] = gk_vr_add(w[k], gk_vr_mul(dt, aw[k]));
                gk_vr_storeu(rve->w[k] + p, w[k]);
                vchk = gk_vr_add(vchk, gk_vr_abs(w[k]));
            }
        } else if (dim == 2) {
            for (hf = 0; hf < GK_VR_DHALVES; ++hf) {
                double *th = rve->theta + p + hf * GK_VD_W;
                gk_vd_storeu(th, gk_vd_add(gk_vd_loadu(th), gk_vd_mul(wad, dtd)));
            }
        }
    }
    gk_vd_storeu(buf, vm2);
    gk_vr_storeu(bufr, vchk);
    for (l = 0; l < GK_VD_W; ++l)
        if (buf[l] > m2) m2 = buf[l];
    for (l = 0; l < GK_VR_W; ++l) chk += (double)bufr[l];
    if (!isfinite(chk) || !isfinite(m2)) *bad = 1;
    if (p < p1) {
        double mt = gk__integrate_kernel(rve, x, hinv, hnew, p, p1, bad, dim, rot, damp);
        if (mt > m2) m2 = mt;
    }
    return m2;
}
#define GK__INTEGRATE_FAST gk__integrate_simd
#else
#define GK__INTEGRATE_FAST gk__integrate_kernel
#endif

static double gk__integrate_range(gk_rve *rve, const gk__stepctx *x, const double hinv[9],
                                  const double hnew[9], int p0, int p1, int *bad) {
    int rot = GK__HAS_ROT(rve),
        damp = rve->def.damping > 0 ? (rve->def.damping_form == GK_DAMP_VECTOR ? 2 : 1) : 0;
#define GK__INT(D, R, M)                                                                                     \
    return (rve->def.flags & GK_RVE_SCALAR) ? gk__integrate_kernel(rve, x, hinv, hnew, p0, p1, bad, D, R, M) \
                                            : GK__INTEGRATE_FAST(rve, x, hinv, hnew, p0, p1, bad, D, R, M)
    if (rve->dim == 2) {
        if (rot) {
            if (damp == 1) GK__INT(2, 1, 1);
            if (damp == 2) GK__INT(2, 1, 2);
            GK__INT(2, 1, 0);
        }
        if (damp == 1) GK__INT(2, 0, 1);
        if (damp == 2) GK__INT(2, 0, 2);
        GK__INT(2, 0, 0);
    }
    if (rot) {
        if (damp == 1) GK__INT(3, 1, 1);
        if (damp == 2) GK__INT(3, 1, 2);
        GK__INT(3, 1, 0);
    }
    if (damp == 1) GK__INT(3, 0, 1);
    if (damp == 2) GK__INT(3, 0, 2);
    GK__INT(3, 0, 0);
#undef GK__INT
}

static int gk__nthreads(const gk_rve *rve) {
    return rve->def.threads > 1 && rve->pl.n >= GK_DEM_PAR_MIN ? rve->def.threads : 1;
}

static double gk__integrate(gk_rve *rve, const gk__stepctx *x, const double hinv[9], const double hnew[9],
                            int *bad) {
    int n = rve->n, nth = gk__nthreads(rve);
    double m2 = 0.0;
    GK_DEM_PHASE(3, 0);
    if (nth <= 1) {
        m2 = gk__integrate_range(rve, x, hinv, hnew, 0, n, bad);
    } else {
        int b, badl = 0;
        GK_OMP(parallel for num_threads(nth) schedule(static) reduction(max : m2) reduction(| : badl))
        for (b = 0; b < nth * 4; ++b) {
            long p0 = (long)n * b / (nth * 4), p1 = (long)n * (b + 1) / (nth * 4);
            int bb = 0;
            double mm;
            GK_DEM_PHASE(3, 2);
            mm = gk__integrate_range(rve, x, hinv, hnew, (int)p0, (int)p1, &bb);
            GK_DEM_PHASE(3, 3);
            if (mm > m2) m2 = mm;
            badl |= bb;
        }
        if (badl) *bad = 1;
    }
    GK_DEM_PHASE(3, 1);
    return m2;
}

/* ---------------------------------------------------------------- stress */
/* Love stress sigma = -(1/V) sum F (x) d (Guo & Zhao 2014 eq 5; F on j, d = x_j - x_i),
 * the Voigt stiffness diagonal and contact statistics, in pair order. */
/* Voigt stiffness estimate D_kkkk = (1/V) sum k_n d_k^4 / |d|^2 over the
 * contacts: only the servo uses it, so it is computed only while a servo is
 * on (and when one is switched on) */
static void gk__stiff_pass(gk_rve *rve) {
    int dim = rve->dim, c, k;
    double st[3] = {0, 0, 0}, V = gk_rve_volume(rve);
    for (c = 0; c < rve->pl.n; ++c) {
        int i, j;
        double ds[3], d[3], dd, R, delta;
        if (!(rve->cs[c] & GK_CS_CONTACT)) continue;
        i = rve->pl.i[c];
        j = rve->pl.j[c];
        for (k = 0; k < 3; ++k) ds[k] = k < dim ? rve->s[k][j] - rve->s[k][i] : 0.0;
        gk_pcell_min_image(&rve->cell, ds, d);
        if (dim == 2) d[2] = 0.0;
        dd = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        R = (double)rve->r[i] + (double)rve->r[j];
        delta = R - dd;
        if (dd > 0.0) {
            gk_real kn, fn, kt;
            gk_contact_stiffness(&rve->K, rve->def.mat.law, rve->r[i], rve->r[j],
                                 (gk_real)(delta > 0 ? delta : 0), &kn, &fn, &kt);
            for (k = 0; k < dim; ++k) st[k] += (double)kn * d[k] * d[k] * d[k] * d[k] / (dd * dd);
        }
    }
    for (k = 0; k < 3; ++k) rve->stiff[k] = st[k] / V;
}

/* Love stress (Guo & Zhao 2014 eq 5) -(1/V) sum F (x) d over the contacts, their
 * number and mean force, in pair order. */
static void gk__stress_pass(gk_rve *rve) {
    int dim = rve->dim, c, k, l, nc = 0;
    double S[9], V = gk_rve_volume(rve), fsum = 0.0;
    gk_m3_zero(S);
    for (c = 0; c < rve->pl.n; ++c) {
        int i = rve->pl.i[c], j = rve->pl.j[c];
        double ds[3], d[3], F[3] = {0.0, 0.0, 0.0};
        if (!(rve->cs[c] & GK_CS_CONTACT)) continue;
        for (k = 0; k < dim; ++k) {
            ds[k] = rve->s[k][j] - rve->s[k][i];
            F[k] = (double)rve->fc[k][c];
        }
        gk_pcell_image(rve->cell.h, dim, ds, d);
        for (k = 0; k < dim; ++k)
            for (l = 0; l < dim; ++l) S[3 * k + l] += F[k] * d[l];
        fsum += sqrt(F[0] * F[0] + F[1] * F[1] + F[2] * F[2]);
        ++nc;
    }
    for (k = 0; k < 9; ++k) rve->stress[k] = -S[k] / V;
    if (rve->servo_on) gk__stiff_pass(rve);
    rve->ncontacts = nc;
    rve->fc_mean = nc ? fsum / nc : 0.0;
}

GKDEF double gk_rve_volume(const gk_rve *rve) { return gk_pcell_volume(&rve->cell) * rve->volume_factor; }

GKDEF void gk_rve_stress(const gk_rve *rve, double sigma[9]) { gk_m3_copy(rve->stress, sigma); }

/* ---------------------------------------------------------------- one step */
static void gk__ctx_make(const gk_rve *rve, const double E[9], gk__stepctx *x) {
    double G[9];
    int k;
    for (k = 0; k < 9; ++k) G[k] = (E[k] - (k % 4 == 0 ? 1.0 : 0.0)) / rve->dt;
    if (rve->dim == 2) G[2] = G[5] = G[6] = G[7] = G[8] = 0.0;
    for (k = 0; k < 9; ++k) {
        x->G[k] = (gk_real)G[k];
        x->hd[k] = rve->cell.h[k];
    }
    x->scatter = 0;
    x->store = 1;
    x->wa[0] = (gk_real)(0.5 * (G[7] - G[5]));
    x->wa[1] = (gk_real)(0.5 * (G[2] - G[6]));
    x->wa[2] = (gk_real)(0.5 * (G[3] - G[1]));
    x->dt = (gk_real)rve->dt;
}

static gk_result gk__step_once(gk_rve *rve, const double E[9], int want_stress) {
    gk__stepctx x;
    double M[9], dispmax2;
    int bad = 0, k;
    gk_result res;
    if (rve->need_rebuild) {
        GK_DEM_PHASE(0, 0);
        res = gk__rve_rebuild(rve);
        GK_DEM_PHASE(0, 1);
        if (res) return res;
    }
    if (rve->hook && (res = rve->hook(rve, GK_HOOK_PRE_FORCES, rve->hook_user)) != GK_OK) return res;
    gk__ctx_make(rve, E, &x);
    for (k = 0; k < 9; ++k) rve->G[k] = (double)x.G[k];
    gk__forces(rve, &x, want_stress || rve->hook_pairs);
    if (rve->hook && (res = rve->hook(rve, GK_HOOK_POST_FORCES, rve->hook_user)) != GK_OK) return res;
    if (want_stress) gk__stress_pass(rve);
    res = gk_pcell_advance(&rve->cell, E, &rve->err);
    if (res) return res;
    if (gk_pcell_reduce(&rve->cell, M)) {
        /* same lattice, new basis: s' = M^-1 s for positions and build references */
        double Mi[9];
        int p;
        gk_m3_inverse(M, Mi);
        gk_pcell_apply_basis(&rve->cell, M);
        for (p = 0; p < rve->n; ++p) {
            double a[3], b[3], a0[3], b0[3];
            for (k = 0; k < 3; ++k) {
                a[k] = k < rve->dim ? rve->s[k][p] : 0.0;
                a0[k] = k < rve->dim ? rve->s0[k][p] : 0.0;
            }
            gk_m3_matvec(Mi, a, b);
            gk_m3_matvec(Mi, a0, b0);
            for (k = 0; k < rve->dim; ++k) {
                rve->s[k][p] = b[k];
                rve->s0[k][p] = b0[k];
                gk__wrap(rve, p, k);
            }
        }
        {
            double h0n[9];
            gk_m3_mul(rve->h0, M, h0n);
            gk_m3_copy(h0n, rve->h0);
        }
        rve->need_rebuild = 1;
        rve->outer_valid = 0;
    }
    dispmax2 = gk__integrate(rve, &x, rve->cell.hinv, rve->cell.h, &bad);
    if (rve->dim == 3 && rve->theta) { /* GK_RVE_TRACK_ROTATION: outside the kernels, paid only when asked */
        int p;
        for (p = 0; p < rve->n; ++p)
            for (k = 0; k < 3; ++k)
                rve->theta[3 * p + k] +=
                    ((double)x.wa[k] + (rve->w[k] ? (double)rve->w[k][p] : 0.0)) * rve->dt;
    }
    rve->time += rve->dt;
    ++rve->step;
    if (bad) {
        rve->diverged = 1;
        return gk_err_set(
            &rve->err, GK_ERR_DIVERGED,
            "non-finite velocity or position at step %ld (time step too large or unstable input?)",
            rve->step);
    }
    /* twice the largest displacement: the kernels keeping the two largest (the
     * outer test's tighter bound) cost the update more than the rebuilds saved */
    if (!rve->need_rebuild &&
        !(gk_cells_skin_margin(rve->dim, rve->h0, rve->cell.h, rve->skin_in, rve->rmax, dispmax2) > 0.0))
        rve->need_rebuild = 1;
    if (rve->hook) return rve->hook(rve, GK_HOOK_POST_STEP, rve->hook_user);
    return GK_OK;
}

static gk_result gk__rve_ready(gk_rve *rve) {
    if (rve->n < 1 || !rve->s[0]) return gk_err_set(&rve->err, GK_ERR_STATE, "RVE not created");
    if (rve->diverged)
        return gk_err_set(&rve->err, GK_ERR_STATE, "RVE diverged at step %ld; restore a saved state",
                          rve->step);
    return GK_OK;
}

GKDEF gk_result gk_rve_set_velocity_gradient(gk_rve *rve, const double L[9]) {
    if (!gk_m3_isfinite(L)) return gk_err_set(&rve->err, GK_ERR_NAN, "velocity gradient has a NaN entry");
    if (rve->dim == 2 && (L[2] != 0 || L[5] != 0 || L[6] != 0 || L[7] != 0 || L[8] != 0))
        return gk_err_set(&rve->err, GK_ERR_ARG, "2D velocity gradient must have zero third row and column");
    gk_m3_copy(L, rve->L);
    return GK_OK;
}

static gk_result gk__servo_check(int dim, const gk_servo *s, gk_err *err) {
    int k;
    if (s->shear &&
        !(isfinite(s->shear_target[0]) && isfinite(s->shear_target[1]) && isfinite(s->shear_target[2])))
        return gk_err_set(err, GK_ERR_NAN, "servo: non-finite shear target");
    for (k = 0; k < dim; ++k) {
        if (s->mode[k] != GK_SERVO_STRAIN && s->mode[k] != GK_SERVO_STRESS)
            return gk_err_set(err, GK_ERR_ARG, "servo axis %d: unknown mode %d", k, (int)s->mode[k]);
        if (!isfinite(s->target[k]) || !isfinite(s->rate[k]))
            return gk_err_set(err, GK_ERR_NAN, "servo axis %d: non-finite target or rate", k);
    }
    if (!(s->max_rate > 0.0) || !isfinite(s->max_rate))
        return gk_err_set(err, GK_ERR_ARG, "servo max_rate %g must be > 0", s->max_rate);
    if (!(s->gain >= 0.0 && s->gain <= 1.0))
        return gk_err_set(err, GK_ERR_ARG, "servo gain %g outside [0, 1]", s->gain);
    return GK_OK;
}

GKDEF gk_result gk_rve_set_servo(gk_rve *rve, const gk_servo *s) {
    gk_result res;
    if (!s) {
        rve->servo_on = 0;
        return GK_OK;
    }
    res = gk__servo_check(rve->dim, s, &rve->err);
    if (res) return res;
    rve->servo = *s;
    rve->servo_on = 1;
    if (rve->pl.i) gk__stiff_pass(rve); /* the stiffness of the current contacts (unused without servo) */
    return GK_OK;
}

/* largest relative change of length the map E gives any vector: max |sigma_k(E) - 1|
 * over its singular values (0 for a rotation) */
static double gk__map_stretch(int dim, const double E[9]) {
    double Et[9], EtE[9], lo, hi;
    gk_m3_transpose(E, Et);
    gk_m3_mul(Et, E, EtE);
    if (dim == 2) {
        double a = EtE[0], b = EtE[1], d = EtE[4], disc = sqrt(0.25 * (a - d) * (a - d) + b * b);
        lo = 0.5 * (a + d) - disc;
        hi = 0.5 * (a + d) + disc;
    } else {
        double val[3], vec[9];
        gk_m3_sym_eigen(EtE, val, vec);
        lo = val[0];
        hi = val[2];
    }
    lo = 1.0 - sqrt(lo > 0.0 ? lo : 0.0);
    hi = sqrt(hi) - 1.0;
    return hi > lo ? hi : lo; /* NaN stays NaN: refused */
}

/* The admissible increment of one DEM step (see THE RVE CONTRACT): a per-step
 * cell map of this stretch changes the overlap of a contact (i, j) by at most
 * stretch (r_i + r_j), which must stay below GK_RVE_STEP_OVERLAP_MAX x the
 * smaller radius for every possible pair. */
static double gk__step_stretch_max(const gk_rve *rve) {
    return GK_RVE_STEP_OVERLAP_MAX * rve->rmin / (rve->rmin + rve->rmax);
}

/* ---------------------------------------------------------------- driving the cell
 * One control drives the cell in every run of steps: it yields the map E of
 * each step (h <- E h) and whether that step computes the stress (the last
 * of a run; every step under a servo, which reads it). The public drivers
 * are thin wrappers (see DRIVING THE CELL in the manual above). */
enum { GK__DRIVE_PATH, GK__DRIVE_RATE, GK__DRIVE_SERVO };
typedef struct gk__drive {
    int kind;     /* PATH: I + dH split by a gk_path; RATE: constant L; SERVO  */
    long n;       /* steps in the run                                          */
    int stress;   /* make the stress (and keep the pair forces) at the last step */
    gk_path path; /* PATH                                                      */
    double L[9];  /* RATE, SERVO (the servo rewrites its diagonal, shear)       */
} gk__drive;

static gk_result gk__drive_run(gk_rve *rve, gk__drive *d) {
    double E[9], A[9];
    long k;
    int i;
    gk_result res;
    if (d->kind == GK__DRIVE_RATE) {
        for (i = 0; i < 9; ++i) A[i] = d->L[i] * rve->dt;
        gk_m3_exp(A, E);
    }
    for (k = 1; k <= d->n; ++k) {
        if (d->kind == GK__DRIVE_PATH) {
            gk_path_step(&d->path, (int)k, E);
        } else if (d->kind == GK__DRIVE_SERVO) {
            if (k == 1 && rve->step == 0) gk_rve_refresh(rve); /* the servo reads the stress */
            gk_servo_rates(&rve->servo, rve->dim, rve->stress, rve->stiff, rve->dt, d->L);
            for (i = 0; i < 9; ++i) A[i] = d->L[i] * rve->dt;
            gk_m3_exp(A, E);
        }
        res = gk__step_once(rve, E, d->kind == GK__DRIVE_SERVO || (k == d->n && d->stress));
        if (res) return res;
    }
    return GK_OK;
}

GKDEF gk_result gk_rve_step(gk_rve *rve, long nsteps) { return gk_rve_step_flags(rve, nsteps, 0); }

GKDEF gk_result gk_rve_step_flags(gk_rve *rve, long nsteps, unsigned flags) {
    gk__drive d;
    gk_result res = gk__rve_ready(rve);
    if (res) return res;
    if (nsteps < 0) return gk_err_set(&rve->err, GK_ERR_ARG, "step count %ld < 0", nsteps);
    if (flags & ~GK_STEP_NO_STRESS)
        return gk_err_set(&rve->err, GK_ERR_ARG, "unknown step flags 0x%x", flags);
    { /* the largest per-step map: the servo's rates are bounded by max_rate */
        double C[9], f = 0.0, lim = gk__step_stretch_max(rve);
        int i, j;
        for (i = 0; i < 3; ++i)
            for (j = 0; j < 3; ++j) {
                int servo =
                    rve->servo_on && i < rve->dim && j < rve->dim &&
                    ((i == j && rve->servo.mode[i] == GK_SERVO_STRESS) || (i != j && rve->servo.shear));
                C[3 * i + j] = servo ? rve->servo.max_rate
                                     : (rve->servo_on && i == j && i < rve->dim ? fabs(rve->servo.rate[i])
                                                                                : fabs(rve->L[3 * i + j]));
                f += C[3 * i + j] * C[3 * i + j];
            }
        f = expm1(sqrt(f) * rve->dt); /* |exp(A) - I| <= exp(|A|) - 1 bounds the stretch */
        if (!(f <= lim))
            return gk_err_set(
                &rve->err, GK_ERR_ARG,
                "the velocity gradient%s moves a contact by up to %.3g of the smaller radius in one "
                "step of %g s (admissible %g, GK_RVE_STEP_OVERLAP_MAX): lower the rates or dt",
                rve->servo_on ? " (with the servo's max_rate)" : "", f * (rve->rmin + rve->rmax) / rve->rmin,
                rve->dt, GK_RVE_STEP_OVERLAP_MAX);
    }
    d.kind = rve->servo_on ? GK__DRIVE_SERVO : GK__DRIVE_RATE;
    d.n = nsteps;
    d.stress = !(flags & GK_STEP_NO_STRESS);
    gk_m3_copy(rve->L, d.L);
    return gk__drive_run(rve, &d);
}

/* the largest per-step stretch of dH carried out in n steps on the RVE's path */
static double gk__deform_stretch(const gk_rve *rve, const double dH[9], int n) {
    gk_path path;
    double E[9], st = 0.0;
    int k;
    if (gk_path_init(&path, rve->dim, rve->def.path, dH, n, NULL)) return NAN;
    for (k = 1; k <= (rve->def.path == GK_PATH_CONSTANT_L ? 1 : n); ++k) { /* constant L: one map */
        double a;
        gk_path_step(&path, k, E);
        a = gk__map_stretch(rve->dim, E);
        if (!(a <= st)) st = a;
    }
    return st;
}

GKDEF gk_result gk_rve_deform(gk_rve *rve, const double dH[9], int nsteps) {
    gk__drive d;
    gk_path path;
    int k;
    gk_result res = gk__rve_ready(rve);
    if (res) return res;
    if (rve->servo_on)
        return gk_err_set(&rve->err, GK_ERR_STATE, "a servo is active: switch it off before deform");
    res = gk_path_init(&path, rve->dim, rve->def.path, dH, nsteps, &rve->err);
    if (res) return res;
    { /* refuse up front an increment too large for one DEM step (the contract) */
        double st = gk__deform_stretch(rve, dH, nsteps), lim = gk__step_stretch_max(rve);
        if (!(st <= lim)) { /* the fewest steps that would do: doubling, then bisection */
            int lo = nsteps, hi = nsteps;
            while (hi < (1 << 29) && !(gk__deform_stretch(rve, dH, hi) <= lim)) lo = hi, hi *= 2;
            while (hi - lo > 1) {
                int mid = lo + (hi - lo) / 2;
                if (gk__deform_stretch(rve, dH, mid) <= lim)
                    hi = mid;
                else
                    lo = mid;
            }
            return gk_err_set(
                &rve->err, GK_ERR_ARG,
                "dH in %d DEM steps changes a contact's overlap by up to %.3g of the smaller radius in "
                "one step (admissible %g, GK_RVE_STEP_OVERLAP_MAX): use at least %d steps",
                nsteps, st * (rve->rmin + rve->rmax) / rve->rmin, GK_RVE_STEP_OVERLAP_MAX, hi);
        }
    }
    { /* refuse up front a map that leaves the cell too thin for the nearest image */
        gk_pcell end = rve->cell;
        double Mend[9], B[9], w[3];
        gk_path_map(&path, nsteps, Mend);
        res = gk_pcell_advance(&end, Mend, &rve->err);
        if (res) return res;
        if (gk_pcell_reduce(&end, B)) gk_pcell_apply_basis(&end, B);
        gk_pcell_widths(&end, w);
        for (k = 0; k < rve->dim; ++k)
            if (!(2.0 * (2.0 * rve->rmax + rve->skin) < w[k]))
                return gk_err_set(&rve->err, GK_ERR_CELL,
                                  "dH would leave a cell %g wide, below twice the interaction distance %g",
                                  w[k], 2.0 * rve->rmax + rve->skin);
    }
    d.kind = GK__DRIVE_PATH;
    d.stress = 1;
    d.n = nsteps;
    d.path = path;
    return gk__drive_run(rve, &d);
}

GKDEF double gk_rve_unbalanced(const gk_rve *rve) {
    double fp = 0.0, fc = 0.0;
    int p, c, k, nc = 0;
    for (p = 0; p < rve->n; ++p) {
        double f2 = 0.0;
        for (k = 0; k < rve->dim; ++k) f2 += (double)rve->f[k][p] * (double)rve->f[k][p];
        fp += sqrt(f2);
    }
    for (c = 0; c < rve->pl.n; ++c) {
        double f2 = 0.0;
        if (!(rve->cs[c] & GK_CS_CONTACT)) continue;
        for (k = 0; k < rve->dim; ++k) f2 += (double)rve->fc[k][c] * (double)rve->fc[k][c];
        fc += sqrt(f2);
        ++nc;
    }
    return (nc && fc > 0.0) ? (fp / rve->n) / (fc / nc) : 0.0; /* nothing to balance: 0, not NaN */
}

GKDEF double gk_rve_unbalanced_rms(const gk_rve *rve) {
    double fp2 = 0.0, fc2 = 0.0;
    int p, c, k, nc = 0;
    for (p = 0; p < rve->n; ++p)
        for (k = 0; k < rve->dim; ++k) fp2 += (double)rve->f[k][p] * (double)rve->f[k][p];
    for (c = 0; c < rve->pl.n; ++c) {
        if (!(rve->cs[c] & GK_CS_CONTACT)) continue;
        for (k = 0; k < rve->dim; ++k) fc2 += (double)rve->fc[k][c] * (double)rve->fc[k][c];
        ++nc;
    }
    return (nc && fc2 > 0.0) ? sqrt(fp2 / rve->n) / sqrt(fc2 / nc) : 0.0; /* nothing to balance: 0 */
}

static gk_result gk__relax(gk_rve *rve, double uf_max, int every, long max_steps, long *steps, int rms,
                           double *uf_end);
GKDEF gk_result gk_rve_relax(gk_rve *rve, double uf_max, int every, long max_steps, long *steps) {
    return gk__relax(rve, uf_max, every, max_steps, steps, 0, NULL);
}
/* gk_rve_relax on the mean (rms = 0) or the RMS (rms = 1) unbalanced ratio; *uf_end (if not NULL)
 * the ratio of the final state when the loop measured it last, else -1 */
static gk_result gk__relax(gk_rve *rve, double uf_max, int every, long max_steps, long *steps, int rms,
                           double *uf_end) {
    gk__drive d;
    double uf = -1.0;
    long done = 0;
    gk_result res = gk__rve_ready(rve);
    if (steps) *steps = 0;
    if (uf_end) *uf_end = -1.0;
    if (res) return res;
    if (rve->servo_on)
        return gk_err_set(&rve->err, GK_ERR_STATE, "a servo is active: switch it off before relax");
    if (!(uf_max > 0.0) || every < 1 || max_steps < 0)
        return gk_err_set(&rve->err, GK_ERR_ARG,
                          "relax: uf_max %g (> 0), every %d (>= 1), max_steps %ld (>= 0)", uf_max, every,
                          max_steps);
    memset(&d, 0, sizeof d);
    d.kind = GK__DRIVE_RATE; /* L = 0: the cell stands still */
    d.stress = 1;
    while (done < max_steps && (uf = rms ? gk_rve_unbalanced_rms(rve) : gk_rve_unbalanced(rve)) > uf_max) {
        d.n = every < max_steps - done ? every : max_steps - done;
        uf = -1.0;
        res = gk__drive_run(rve, &d);
        if (res) break;
        done += d.n;
    }
    if (steps) *steps = done;
    if (uf_end && !res) *uf_end = uf;
    return res;
}

GKDEF double gk_inertial_number(const double rate[9], int dim, double r_mean, double density, double p) {
    double g = 0.0;
    int i, j;
    for (i = 0; i < dim; ++i)
        for (j = 0; j < dim; ++j) {
            double e = 0.5 * (rate[3 * i + j] + rate[3 * j + i]);
            g += e * e;
        }
    g = sqrt(g);
    if (g == 0.0) return 0.0;
    if (!(p > 0.0)) return HUGE_VAL;
    return 2.0 * g * r_mean * sqrt(density / p);
}

GKDEF gk_result gk_rve_deform_adaptive(gk_rve *rve, const double dH[9], const gk_adapt_def *ad_in,
                                       gk_adapt_report *rep) {
    gk_adapt_def ad;
    gk_adapt_report R;
    double rate[9], p, rmean = 0.0, I1, n, uf;
    long nr = 0;
    int k;
    gk_result res;
    memset(&ad, 0, sizeof ad);
    if (ad_in) ad = *ad_in;
    if (ad.inertial_max == 0.0) ad.inertial_max = 5e-4;
    if (ad.unbalanced_max == 0.0) ad.unbalanced_max = 5e-3;
    if (ad.n_min == 0) ad.n_min = 10;
    if (ad.n_max == 0) ad.n_max = 5000;
    if (ad.every == 0) ad.every = 20;
    if (!gk_m3_isfinite(dH)) return gk_err_set(&rve->err, GK_ERR_ARG, "dH has a NaN or infinite entry");
    if (!(ad.inertial_max > 0.0) || !(ad.unbalanced_max > 0.0) || ad.n_min < 1 || ad.n_max < ad.n_min ||
        ad.every < 1)
        return gk_err_set(&rve->err, GK_ERR_ARG,
                          "adaptive bounds: I_max %g, uf_max %g (> 0), n_min %d <= n_max %d, every %d (>= 1)",
                          ad.inertial_max, ad.unbalanced_max, ad.n_min, ad.n_max, ad.every);
    memset(&R, 0, sizeof R);
    for (k = 0; k < rve->n; ++k) rmean += (double)rve->r[k];
    rmean /= rve->n > 0 ? rve->n : 1;
    p = -gk_m3_trace(rve->stress) / rve->dim; /* compression-positive mean stress (gk_stress_p) */
    for (k = 0; k < 9; ++k) rate[k] = dH[k] / rve->dt;
    I1 = gk_inertial_number(rate, rve->dim, rmean, rve->def.mat.density, p);
    n = isfinite(I1) ? ceil(I1 / ad.inertial_max) : (double)ad.n_max;
    if (n < ad.n_min) n = ad.n_min;
    if (n > ad.n_max) n = ad.n_max;
    R.n_deform = (int)n;
    R.inertial = isfinite(I1) ? I1 / n : I1;
    res = gk_rve_deform(rve, dH, R.n_deform);
    if (res) return res;
    res = gk__relax(rve, ad.unbalanced_max, ad.every, ad.n_max - R.n_deform, &nr, ad.rms, &uf);
    if (res) return res;
    R.n_relax = (int)nr;
    /* the relaxation's last measure when it is of this state (no step since), else measured now */
    R.unbalanced = uf >= 0.0 ? uf : ad.rms ? gk_rve_unbalanced_rms(rve) : gk_rve_unbalanced(rve);
    R.capped = R.unbalanced > ad.unbalanced_max;
    if (rep) *rep = R;
    return GK_OK;
}

/* copy the contact history (GK__HIST fields) of np pairs into its spare
 * twin (to = 1) or back (to = 0) */
static void gk__history_copy(gk_rve *rve, int to, size_t np) {
    int q;
    for (q = 0; q < GK__NFIELDS; ++q) {
        const gk__field *f = &gk__fields[q];
        void *live, *spare;
        if (!(f->flags & GK__HIST) || !gk__field_on(rve, f)) continue;
        live = gk__fget(rve, f->off);
        spare = gk__fget(rve, f->spare);
        memcpy(to ? spare : live, to ? live : spare, np * f->size);
    }
}

GKDEF gk_result gk_rve_refresh(gk_rve *rve) {
    /* Forces at the current positions as a zero-length step: with dt = 0 and
     * E = I every history increment vanishes. The tangential and rolling
     * history is copied back afterwards (kept meanwhile in the spare arrays,
     * which hold nothing between list rebuilds) so that a refresh never
     * changes the future (a 3D projection or a cap could otherwise touch it). */
    gk__stepctx x;
    double I[9], dtsave = rve->dt;
    gk_result res = gk__rve_ready(rve);
    if (res) return res;
    if (rve->need_rebuild) {
        res = gk__rve_rebuild(rve);
        if (res) return res;
    }
    if (gk__spare_reserve(rve, (size_t)rve->pl.n + 1))
        return gk_err_set(&rve->err, GK_ERR_ALLOC, "out of memory refreshing forces");
    gk__history_copy(rve, 1, (size_t)rve->pl.n);
    gk_m3_identity(I);
    rve->dt = 1.0; /* G = (E - I)/dt = 0 */
    gk__ctx_make(rve, I, &x);
    rve->dt = dtsave;
    x.dt = 0;
    gk__forces(rve, &x, 1);
    gk__stress_pass(rve);
    gk__history_copy(rve, 0, (size_t)rve->pl.n);
    return GK_OK;
}

GKDEF gk_result gk_rve_set_dt(gk_rve *rve, double dt) {
    double dtc = gk__dt_critical(rve);
    if (!(dt > 0.0) || !isfinite(dt)) return gk_err_set(&rve->err, GK_ERR_DT, "time step %g must be > 0", dt);
    if (dt > dtc)
        return gk_err_set(&rve->err, GK_ERR_DT,
                          "time step %g s is above the critical %g s (Guo & Zhao 2014 eq 19)", dt, dtc);
    rve->dt = dt;
    rve->dt_crit = dtc;
    return GK_OK;
}

GKDEF gk_result gk_rve_set_friction(gk_rve *rve, double mu) {
    gk_material m = rve->def.mat;
    unsigned phys;
    gk_result res;
    m.friction = mu;
    res = gk_material_check(&m, &rve->err);
    if (res) return res;
    phys = gk_material_flags(&m) | (rve->phys & GK_PHYS_ROTATION);
    if ((phys & GK_PHYS_TANGENT) && !(rve->phys & GK_PHYS_TANGENT))
        return gk_err_set(&rve->err, GK_ERR_STATE,
                          "RVE was created frictionless: create it with the friction it will use "
                          "(gk_rve_consolidate switches friction off and on itself)");
    rve->def.mat = m;
    rve->K.mu = (gk_real)mu;
    return GK_OK;
}

GKDEF gk_result gk_rve_set_damping(gk_rve *rve, double alpha, gk_damp_form form) {
    if (!(alpha >= 0.0 && alpha < 1.0))
        return gk_err_set(&rve->err, GK_ERR_ARG, "damping %g outside [0, 1)", alpha);
    if (form != GK_DAMP_COMPONENT && form != GK_DAMP_VECTOR)
        return gk_err_set(&rve->err, GK_ERR_ARG, "unknown damping form %d", (int)form);
    rve->def.damping = alpha;
    rve->def.damping_form = form;
    return GK_OK;
}

GKDEF double gk_rve_kinetic_energy(const gk_rve *rve) {
    double e = 0.0;
    int p, k;
    for (p = 0; p < rve->n; ++p) {
        double m = 1.0 / (double)rve->minv[p], I = 1.0 / (double)rve->Iinv[p];
        for (k = 0; k < rve->dim; ++k) e += 0.5 * m * (double)rve->v[k][p] * (double)rve->v[k][p];
        for (k = 0; k < 3; ++k)
            if (rve->w[k]) e += 0.5 * I * (double)rve->w[k][p] * (double)rve->w[k][p];
    }
    return e;
}

GKDEF void gk_rve_position(const gk_rve *rve, int p, double x[3]) {
    double s[3];
    int k;
    for (k = 0; k < 3; ++k) s[k] = k < rve->dim ? rve->s[k][p] : 0.0;
    gk_m3_matvec(rve->cell.h, s, x);
    if (rve->dim == 2) x[2] = 0.0;
}

GKDEF gk_result gk_rve_to_packing(const gk_rve *rve, gk_packing *out, const gk_allocator *alloc,
                                  gk_err *err) {
    gk_packing pk;
    int p, k;
    gk_result res = gk_packing_init(&pk, rve->dim, rve->n, alloc, err);
    if (res) return res;
    gk_m3_copy(rve->cell.h, pk.h);
    for (p = 0; p < rve->n; ++p) {
        double s[3], x[3];
        int q = rve->id[p];
        for (k = 0; k < 3; ++k) s[k] = k < rve->dim ? rve->s[k][p] - floor(rve->s[k][p]) : 0.0;
        gk_m3_matvec(rve->cell.h, s, x);
        pk.x[q] = x[0];
        pk.y[q] = x[1];
        pk.z[q] = rve->dim == 3 ? x[2] : 0.0;
        pk.r[q] = (double)rve->r[p];
    }
    *out = pk;
    return GK_OK;
}

/* ---------------------------------------------------------------- consolidation */
GKDEF int gk_rve_contact_next(const gk_rve *rve, int *cursor, gk_rve_contact *out) {
    int c = *cursor < 0 ? 0 : *cursor, k;
    for (; c < rve->pl.n; ++c) {
        int a = rve->pl.i[c], b = rve->pl.j[c], swap;
        double ds[3];
        if (!(rve->cs[c] & GK_CS_CONTACT)) continue;
        swap = rve->id[a] > rve->id[b];
        out->i = swap ? rve->id[b] : rve->id[a];
        out->j = swap ? rve->id[a] : rve->id[b];
        out->sliding = (rve->cs[c] & GK_CS_SLIDING) != 0;
        for (k = 0; k < 3; ++k) {
            double fk = k < rve->dim ? (double)rve->fc[k][c] : 0.0;
            ds[k] = k < rve->dim ? rve->s[k][b] - rve->s[k][a] : 0.0;
            out->f[k] = swap ? -fk : fk;
        }
        gk_pcell_min_image(&rve->cell, ds, out->d);
        if (rve->dim == 2) out->d[2] = 0.0;
        if (swap)
            for (k = 0; k < 3; ++k) out->d[k] = -out->d[k];
        *cursor = c + 1;
        return 1;
    }
    *cursor = rve->pl.n;
    return 0;
}

GKDEF gk_result gk_rve_consolidate(gk_rve *rve, const gk_consolidate_def *cd, gk_consolidate_report *rep) {
    gk_servo sv;
    double mu_final = rve->def.mat.friction, alpha_final = rve->def.damping, rmean = 0.0, tol, utol, rate;
    double ratio[3];
    long maxs, st = 0, calm = 0;
    int k, p;
    gk_result res = gk__rve_ready(rve);
    if (res) return res;
    if (!cd || !(cd->pressure > 0.0) || !isfinite(cd->pressure))
        return gk_err_set(&rve->err, GK_ERR_ARG, "consolidation pressure must be > 0");
    if (!(cd->friction >= 0.0) || !isfinite(cd->friction))
        return gk_err_set(&rve->err, GK_ERR_ARG, "consolidation friction %g invalid", cd->friction);
    if (!(cd->damping >= 0.0 && cd->damping < 1.0))
        return gk_err_set(&rve->err, GK_ERR_ARG, "consolidation damping %g outside [0, 1)", cd->damping);
    if (cd->friction > 0.0 && !(rve->phys & GK_PHYS_TANGENT))
        return gk_err_set(&rve->err, GK_ERR_STATE,
                          "consolidating with friction needs an RVE created with friction > 0");
    tol = cd->stress_tol > 0 ? cd->stress_tol : 1e-3;
    utol = cd->unbalanced_tol > 0 ? cd->unbalanced_tol : 1e-3;
    maxs = cd->max_steps > 0 ? cd->max_steps : 2000000;
    for (p = 0; p < rve->n; ++p) rmean += (double)rve->r[p];
    rmean /= rve->n;
    /* inertial number I = 2 rate r sqrt(rho/p) (Guo & Zhao 2014 eq 20) kept at 1e-2 */
    rate = cd->max_strain_rate > 0 ? cd->max_strain_rate
                                   : 1e-2 * sqrt(cd->pressure / rve->def.mat.density) / (2.0 * rmean);
    memset(&sv, 0, sizeof sv);
    for (k = 0; k < 3; ++k) {
        if (!(cd->ratio[k] >= 0.0) || !isfinite(cd->ratio[k]))
            return gk_err_set(&rve->err, GK_ERR_ARG, "consolidation stress ratio %d is %g (must be >= 0)", k,
                              cd->ratio[k]);
        ratio[k] = cd->ratio[k] > 0.0 ? cd->ratio[k] : 1.0;
        sv.mode[k] = GK_SERVO_STRESS;
        sv.target[k] = -cd->pressure * ratio[k];
    }
    sv.max_rate = rate;
    sv.gain = 0.1;       /* of the Taylor stiffness, which overestimates the packing's own */
    sv.shear = !cd->box; /* principal axes along the cell axes: the shear stresses go to zero as well */
    rve->K.mu = (gk_real)cd->friction;
    if (cd->damping > 0.0) rve->def.damping = cd->damping;
    gk_m3_zero(rve->L);
    res = gk_rve_set_servo(rve, &sv);
    if (res) return res;
    while (st < maxs) {
        double un, errmax = 0.0;
        res = gk_rve_step(rve, 100);
        st += 100;
        if (res) break;
        for (k = 0; k < rve->dim; ++k) {
            double e = fabs(rve->stress[4 * k] + cd->pressure * ratio[k]) / (cd->pressure * ratio[k]);
            int l;
            if (e > errmax) errmax = e;
            for (l = k + 1; l < rve->dim && !cd->box; ++l) {
                e = fabs(0.5 * (rve->stress[3 * k + l] + rve->stress[3 * l + k])) / cd->pressure;
                if (e > errmax) errmax = e;
            }
        }
        un = rve->fc_mean > 0 ? gk_rve_unbalanced(rve) : 1.0;
        if (errmax < tol && un < utol) {
            if (++calm >= 3) break;
        } else {
            calm = 0;
        }
    }
    rve->servo_on = 0;
    gk_m3_zero(rve->L);
    rve->K.mu = (gk_real)mu_final;
    rve->def.damping = alpha_final;
    /* friction is switched on with zero tangential history (YADE setContactFriction) */
    if (!res && rve->ft[0]) {
        int c;
        for (k = 0; k < 3; ++k)
            if (rve->ft[k])
                for (c = 0; c < rve->pl.n; ++c) rve->ft[k][c] = 0;
    }
    if (rep) {
        rep->steps = st;
        gk_m3_copy(rve->stress, rep->stress);
        rep->unbalanced = rve->fc_mean > 0 ? gk_rve_unbalanced(rve) : 1.0;
        rep->void_ratio = gk_rve_volume(rve) / rve->solid_volume - 1.0;
    }
    if (res) return res;
    if (st >= maxs)
        return gk_err_set(&rve->err, GK_ERR_NOCONVERGE,
                          "consolidation to %g Pa did not converge in %ld steps (stress %g %g, see report)",
                          cd->pressure, st, -rve->stress[0], -rve->stress[4]);
    return GK_OK;
}

/* ---------------------------------------------------------------- particle count (scenes) */
GKDEF void gk_rve_update_totals(gk_rve *rve) {
    int p;
    rve->rmin = 1e300;
    rve->rmax = 0.0;
    rve->mmin = 1e300;
    rve->mass_total = rve->solid_volume = 0.0;
    for (p = 0; p < rve->n; ++p) {
        double rp = (double)rve->r[p], m = 1.0 / (double)rve->minv[p];
        if (rp < rve->rmin) rve->rmin = rp;
        if (rp > rve->rmax) rve->rmax = rp;
        if (m < rve->mmin) rve->mmin = m;
        rve->mass_total += m;
        rve->solid_volume += gk_particle_volume(rve->dim, rp) * (rve->dim == 2 ? rve->volume_factor : 1.0);
    }
}

GKDEF gk_result gk_rve_reserve(gk_rve *rve, int cap) {
    int have = rve->ncap > rve->n ? rve->ncap : rve->n;
    if (cap <= have) return GK_OK;
    if (gk__fields_grow(rve, GK__PART, 0, (size_t)cap, (size_t)rve->n))
        return gk_err_set(&rve->err, GK_ERR_ALLOC, "out of memory for %d particles", cap);
    rve->ncap = cap;
    return GK_OK;
}

GKDEF gk_result gk_rve_append(gk_rve *rve, int k, const double *const s[3], const double *r,
                              const int32_t *id) {
    int dim = rve->dim, q, a, n0 = rve->n;
    double rmax = rve->rmax, w[3];
    gk_result res;
    if (k < 0 || !s || !r || !id) return gk_err_set(&rve->err, GK_ERR_ARG, "append: bad arguments");
    if (k == 0) return GK_OK;
    for (q = 0; q < k; ++q) {
        if (!(r[q] > 0.0) || !isfinite(r[q]))
            return gk_err_set(&rve->err, GK_ERR_RADIUS, "append: particle %d has radius %g", q, r[q]);
        for (a = 0; a < dim; ++a)
            if (!isfinite(s[a][q]))
                return gk_err_set(&rve->err, GK_ERR_NAN, "append: particle %d has a NaN position", q);
        if (r[q] > rmax) rmax = r[q];
    }
    gk_pcell_widths(&rve->cell, w);
    for (a = 0; a < dim; ++a)
        if (!(2.0 * (2.0 * rmax + rve->skin) < w[a]))
            return gk_err_set(&rve->err, GK_ERR_CELL, "append: radius %g too large for a cell %g wide", rmax,
                              w[a]);
    if (n0 + k > (rve->ncap > n0 ? rve->ncap : n0)) {
        int cap = n0 + n0 / 2 > n0 + k ? n0 + n0 / 2 : n0 + k;
        if ((res = gk_rve_reserve(rve, cap)) != GK_OK) return res;
    }
    for (q = 0; q < k; ++q) {
        int p = n0 + q;
        double rq = r[q], m, I;
        gk__fields_zero(rve, p, p + 1);
        for (a = 0; a < dim; ++a) rve->s[a][p] = rve->s0[a][p] = rve->o0[a][p] = s[a][q] - floor(s[a][q]);
        gk__particle_mass(rve, rq, &m, &I);
        rve->r[p] = (gk_real)rq;
        rve->minv[p] = (gk_real)(1.0 / m);
        rve->Iinv[p] = (gk_real)(1.0 / I);
        rve->id[p] = id[q];
    }
    rve->n = n0 + k;
    gk_rve_update_totals(rve);
    rve->need_rebuild = 1;
    rve->outer_valid = 0;
    return GK_OK;
}

GKDEF gk_result gk_rve_remove(gk_rve *rve, const unsigned char *drop) {
    int n = rve->n, np = rve->pl.n, p, q = 0, c, m = 0;
    int32_t *map;
    unsigned char *keep, *keepc;
    if (!drop) return gk_err_set(&rve->err, GK_ERR_ARG, "remove: no mask");
    for (p = 0; p < n; ++p)
        if (!drop[p]) ++q;
    if (q == n) return GK_OK;
    if (q < 1) return gk_err_set(&rve->err, GK_ERR_ARG, "remove: would leave no particle");
    map = (int32_t *)gk_alloc(&rve->def.alloc, (size_t)n * (sizeof(int32_t) + 1) + (size_t)np);
    if (!map) return gk_err_set(&rve->err, GK_ERR_ALLOC, "out of memory removing particles");
    keep = (unsigned char *)(map + n);
    keepc = keep + n;
    for (p = 0, q = 0; p < n; ++p) {
        keep[p] = !drop[p];
        map[p] = keep[p] ? q++ : -1;
    }
    /* survivors keep their order: the remapped pair list stays sorted by (i, j) */
    for (c = 0; c < np; ++c) {
        int32_t i = map[rve->pl.i[c]], j = map[rve->pl.j[c]];
        keepc[c] = i >= 0 && j >= 0;
        if (!keepc[c]) continue;
        rve->pl.i[m] = i;
        rve->pl.j[m] = j;
        ++m;
    }
    gk__fields_compact(rve, GK__PART, keep, n);
    gk__fields_compact(rve, GK__PAIR, keepc, np);
    gk_free(&rve->def.alloc, map);
    rve->n = q;
    rve->pl.n = m;
    gk__pair_index(rve);
    gk_rve_update_totals(rve);
    rve->need_rebuild = 1;
    rve->outer_valid = 0;
    return GK_OK;
}

/* ---------------------------------------------------------------- save / restore */
#define GK__STATE_MAGIC "GKRVE\001\000\000"
#define GK__STATE_VERSION 1

typedef struct gk__state_hdr {
    char magic[8];
    int32_t version, dim, n, npairs, real_size, phys, endian, rot, roll, pad;
    double dt, time, dt_crit, skin;
    int64_t step, rebuilds, flips;
    double h[9], F[9], h0[9], L[9], G[9], stress[9], stiff[3], fc_mean;
    int32_t ncontacts, need_rebuild, servo_on, pad2;
    gk_servo servo;
    double mu;
    int32_t nouter, outer_valid;
    double ho0[9], skin_in;
} gk__state_hdr;

static size_t gk__state_bytes(const gk_rve *rve, int npairs, int nouter) {
    size_t b = sizeof(gk__state_hdr);
    int q;
    for (q = 0; q < GK__NFIELDS; ++q) {
        const gk__field *f = &gk__fields[q];
        if ((f->flags & GK__SAVE) && gk__field_on(rve, f))
            b += gk__fcount(rve, f, (size_t)npairs, (size_t)nouter) * f->size;
    }
    return b;
}

GKDEF size_t gk_rve_state_size(const gk_rve *rve) { return gk__state_bytes(rve, rve->pl.n, rve->outer.n); }

#define GK__PUT(ptr, bytes)              \
    do {                                 \
        memcpy(o + off, (ptr), (bytes)); \
        off += (bytes);                  \
    } while (0)
#define GK__GET(ptr, bytes)               \
    do {                                  \
        memcpy((ptr), in + off, (bytes)); \
        off += (bytes);                   \
    } while (0)

GKDEF gk_result gk_rve_save(const gk_rve *rve, void *buf, size_t cap, size_t *written) {
    gk__state_hdr hd;
    unsigned char *o = (unsigned char *)buf;
    size_t off = 0, need = gk_rve_state_size(rve), np = (size_t)rve->pl.n, R = sizeof(gk_real);
    int k, q, dim = rve->dim;
    if (written) *written = need;
    if (!buf || cap < need) return GK_ERR_ARG;
    memset(&hd, 0, sizeof hd);
    memcpy(hd.magic, GK__STATE_MAGIC, 8);
    hd.version = GK__STATE_VERSION;
    hd.dim = dim;
    hd.n = rve->n;
    hd.npairs = rve->pl.n;
    hd.real_size = (int32_t)R;
    hd.phys = (int32_t)rve->phys;
    hd.endian = 0x01020304;
    hd.rot = GK__HAS_ROT(rve);
    hd.roll = GK__HAS_ROLL(rve);
    hd.dt = rve->dt;
    hd.time = rve->time;
    hd.dt_crit = rve->dt_crit;
    hd.skin = rve->skin;
    hd.step = rve->step;
    hd.rebuilds = rve->rebuilds;
    hd.flips = rve->cell.flips;
    gk_m3_copy(rve->cell.h, hd.h);
    gk_m3_copy(rve->cell.F, hd.F);
    gk_m3_copy(rve->h0, hd.h0);
    gk_m3_copy(rve->L, hd.L);
    gk_m3_copy(rve->G, hd.G);
    gk_m3_copy(rve->stress, hd.stress);
    for (k = 0; k < 3; ++k) hd.stiff[k] = rve->stiff[k];
    hd.fc_mean = rve->fc_mean;
    hd.ncontacts = rve->ncontacts;
    hd.need_rebuild = rve->need_rebuild;
    hd.servo_on = rve->servo_on;
    hd.servo = rve->servo;
    hd.mu = (double)rve->K.mu;
    hd.nouter = rve->outer.n;
    hd.outer_valid = rve->outer_valid;
    gk_m3_copy(rve->ho0, hd.ho0);
    hd.skin_in = rve->skin_in;
    GK__PUT(&hd, sizeof hd);
    for (q = 0; q < GK__NFIELDS; ++q) {
        const gk__field *f = &gk__fields[q];
        if ((f->flags & GK__SAVE) && gk__field_on(rve, f))
            GK__PUT(gk__fget(rve, f->off), gk__fcount(rve, f, np, (size_t)rve->outer.n) * f->size);
    }
    GK_ASSERT(off == need);
    return GK_OK;
}

/* the largest magnitude a real of a saved state may have: finite values beyond it (a stress of
 * 1e248 Pa, a deformation gradient entry of 1e259) are no physical state, and they overflow in what
 * is computed from them (q from the squares of the stress) */
#define GK__STATE_MAX 1e100
static int gk__state_real(double v) { return fabs(v) <= GK__STATE_MAX; }

/* count values of elem (4 or 8) bytes at b, all finite and at most GK__STATE_MAX in magnitude */
static int gk__finite_bytes(const unsigned char *b, size_t count, size_t elem) {
    size_t k;
    for (k = 0; k < count; ++k) {
        if (elem == 8) {
            double v;
            memcpy(&v, b + 8 * k, 8);
            if (!gk__state_real(v)) return 0;
        } else {
            float v;
            memcpy(&v, b + 4 * k, 4);
            if (!isfinite(v)) return 0;
        }
    }
    return 1;
}

/* a 3x3 matrix of a saved state: every entry finite and at most GK__STATE_MAX in magnitude */
static int gk__state_m3(const double a[9]) {
    int k;
    for (k = 0; k < 9; ++k)
        if (!gk__state_real(a[k])) return 0;
    return 1;
}

/* a pair list of np (i, j) int32 at ib, jb: 0 <= i < j < n, sorted by (i, j) without repeats */
static int gk__pairs_valid(const unsigned char *ib, const unsigned char *jb, int np, int n) {
    int32_t pi = -1, pj = -1;
    int c;
    for (c = 0; c < np; ++c) {
        int32_t a, b;
        memcpy(&a, ib + 4 * (size_t)c, 4);
        memcpy(&b, jb + 4 * (size_t)c, 4);
        if (a < 0 || b <= a || b >= n || a < pi || (a == pi && b <= pj)) return c;
        pi = a, pj = b;
    }
    return -1;
}

/* a 3x3 map of the cell kind: finite, det > 0 and finite, 2D block structure */
static int gk__map_valid(int dim, const double a[9]) {
    double d = gk_m3_det(a);
    if (!gk__state_m3(a) || !(d > 0.0) || !isfinite(d)) return 0;
    return dim == 3 || (a[2] == 0.0 && a[5] == 0.0 && a[6] == 0.0 && a[7] == 0.0 && a[8] == 1.0);
}

/* Every field of a state is checked before anything is changed: header
 * scalars in their ranges, every real finite and at most 1e100 in magnitude
 * (GK__STATE_MAX), the maps invertible, both pair
 * lists sorted and in range, the contact bits known, and the time step at or
 * below the critical one of this RVE at the state's own geometry (the check
 * every list rebuild makes). */
GKDEF gk_result gk_rve_restore(gk_rve *rve, const void *buf, size_t size) {
    gk__state_hdr hd;
    const unsigned char *in = (const unsigned char *)buf;
    size_t off = 0, n, np, R = sizeof(gk_real);
    int k, q, dim = rve->dim, c;
    gk_err *err = &rve->err;
    if (rve->n < 1 || !rve->s[0])
        return gk_err_set(err, GK_ERR_STATE, "restore into an RVE that was not created");
    if (!buf || size < sizeof hd) return gk_err_set(err, GK_ERR_FORMAT, "RVE state buffer too small");
    memcpy(&hd, buf, sizeof hd);
    if (memcmp(hd.magic, GK__STATE_MAGIC, 8) != 0 || hd.endian != 0x01020304)
        return gk_err_set(err, GK_ERR_FORMAT, "not a grainkit RVE state (bad magic or byte order)");
    if (hd.version != GK__STATE_VERSION)
        return gk_err_set(err, GK_ERR_FORMAT, "RVE state version %d (this build reads %d)", hd.version,
                          GK__STATE_VERSION);
    if (hd.dim != rve->dim || hd.n != rve->n || hd.real_size != (int32_t)R || hd.phys != (int32_t)rve->phys ||
        hd.rot != GK__HAS_ROT(rve) || hd.roll != GK__HAS_ROLL(rve))
        return gk_err_set(
            err, GK_ERR_FORMAT,
            "RVE state is for dim %d, %d particles, %d-byte reals, physics %d; this RVE has %d, %d, %d, %d",
            hd.dim, hd.n, hd.real_size, hd.phys, rve->dim, rve->n, (int)R, (int)rve->phys);
    if (hd.npairs < 0 || hd.nouter < 0 || size != gk__state_bytes(rve, hd.npairs, hd.nouter))
        return gk_err_set(err, GK_ERR_FORMAT, "RVE state has the wrong size");
    n = (size_t)rve->n;
    np = (size_t)hd.npairs;
    /* ---- header scalars */
    if (!(hd.dt > 0.0) || !isfinite(hd.dt))
        return gk_err_set(err, GK_ERR_DT, "RVE state time step %g", hd.dt);
    if (!(hd.dt_crit > 0.0) || !isfinite(hd.dt_crit) || !isfinite(hd.time) || hd.step < 0 ||
        hd.rebuilds < 0 || hd.flips < 0)
        return gk_err_set(err, GK_ERR_FORMAT,
                          "RVE state has an invalid time %g, step %ld or critical step %g", hd.time,
                          (long)hd.step, hd.dt_crit);
    if (!(hd.skin > 0.0) || !isfinite(hd.skin) || !(hd.skin_in > 0.0) || !(hd.skin_in <= hd.skin))
        return gk_err_set(err, GK_ERR_FORMAT, "RVE state Verlet skins %g and %g invalid", hd.skin,
                          hd.skin_in);
    if (!gk__map_valid(dim, hd.h) || !gk__map_valid(dim, hd.F) || !gk__map_valid(dim, hd.h0) ||
        !gk__map_valid(dim, hd.ho0))
        return gk_err_set(err, GK_ERR_CELL, "RVE state cell (h %g %g %g %g ...) is not a valid cell matrix",
                          hd.h[0], hd.h[1], hd.h[3], hd.h[4]);
    {
        gk_pcell cell;
        double w[3];
        if (gk_pcell_init(&cell, dim, hd.h, err)) return GK_ERR_CELL;
        gk_pcell_widths(&cell, w);
        for (k = 0; k < dim; ++k)
            if (!(2.0 * (2.0 * rve->rmax + hd.skin) < w[k]))
                return gk_err_set(err, GK_ERR_CELL,
                                  "RVE state cell is %g wide, below twice the interaction distance %g", w[k],
                                  2.0 * rve->rmax + hd.skin);
    }
    if (!gk__state_m3(hd.L) || !gk__state_m3(hd.G) || !gk__state_m3(hd.stress) ||
        !gk__state_real(hd.stiff[0]) || !gk__state_real(hd.stiff[1]) || !gk__state_real(hd.stiff[2]) ||
        !(hd.fc_mean >= 0.0) || !gk__state_real(hd.fc_mean))
        return gk_err_set(err, GK_ERR_NAN,
                          "RVE state has a non-finite or impossible (above 1e100) velocity gradient, stress "
                          "or stiffness");
    if (dim == 2 && (hd.L[2] != 0 || hd.L[5] != 0 || hd.L[6] != 0 || hd.L[7] != 0 || hd.L[8] != 0))
        return gk_err_set(err, GK_ERR_FORMAT, "RVE state: 2D velocity gradient with a third row or column");
    if (hd.ncontacts < 0 || hd.ncontacts > hd.npairs || (hd.need_rebuild != 0 && hd.need_rebuild != 1) ||
        (hd.servo_on != 0 && hd.servo_on != 1) || (hd.outer_valid != 0 && hd.outer_valid != 1))
        return gk_err_set(err, GK_ERR_FORMAT,
                          "RVE state has invalid counters or flags (%d contacts of %d pairs)", hd.ncontacts,
                          hd.npairs);
    {
        gk_material m = rve->def.mat;
        gk_result r = hd.servo_on ? gk__servo_check(dim, &hd.servo, err) : GK_OK;
        if (r) return r;
        m.friction = hd.mu;
        if ((r = gk_material_check(&m, err)) != GK_OK) return r;
        if (hd.mu > 0.0 && !(rve->phys & GK_PHYS_TANGENT))
            return gk_err_set(err, GK_ERR_STATE, "RVE state has friction %g for an RVE created frictionless",
                              hd.mu);
    }
    /* ---- arrays, in the order gk_rve_save writes them: reals finite, pair
     * lists sorted and in range, contact bits known */
    off = sizeof hd;
    {
        const unsigned char *sb[3] = {NULL, NULL, NULL}, *ib = NULL, *pib = NULL, *pjb = NULL;
        double dtc;
        for (q = 0; q < GK__NFIELDS; ++q) {
            const gk__field *f = &gk__fields[q];
            const unsigned char *b = in + off;
            size_t cnt;
            if (!(f->flags & GK__SAVE) || !gk__field_on(rve, f)) continue;
            cnt = gk__fcount(rve, f, np, (size_t)hd.nouter);
            off += cnt * f->size;
            if (f->off == offsetof(gk_rve, s[0]) + f->k * sizeof(double *)) sb[f->k] = b;
            if (f->flags & GK__LIST) {
                if (!ib) {
                    ib = b; /* the i array; j follows */
                    continue;
                }
                if ((c = gk__pairs_valid(ib, b, (int)cnt, rve->n)) >= 0)
                    return gk_err_set(err, GK_ERR_FORMAT, "RVE state %s %d has invalid or unsorted particles",
                                      f->set == GK__OUTER ? "outer pair" : "pair", c);
                if (f->set == GK__PAIR) pib = ib, pjb = b;
                ib = NULL;
            } else if (f->size == 1) {
                for (c = 0; c < (int)cnt; ++c)
                    if (b[c] & ~(GK_CS_CONTACT | GK_CS_SLIDING | GK_CS_BONDED | GK_CS_BROKEN))
                        return gk_err_set(err, GK_ERR_FORMAT,
                                          "RVE state pair %d has unknown contact bits 0x%x", c, b[c]);
            } else if (!gk__finite_bytes(b, cnt * (f->size % 8 ? 1 : f->size / 8),
                                         f->size % 8 ? f->size : 8)) {
                return gk_err_set(err, GK_ERR_NAN,
                                  "RVE state has a non-finite or impossible (above 1e100) %s", f->what);
            }
        }
        dtc = gk__dt_critical_at(rve, hd.h, sb, pib, pjb, hd.npairs);
        if (!(hd.dt <= dtc))
            return gk_err_set(
                err, GK_ERR_DT,
                "RVE state time step %g s is above the critical %g s of this RVE at the state's "
                "geometry (Guo & Zhao 2014, eq 19)",
                hd.dt, dtc);
    }
    /* capacity first, so a failure changes nothing observable */
    if (gk__pairs_reserve(rve, np + 1, (size_t)rve->pl.n) || gk_pairlist_reserve(&rve->pl, np + 1, n) ||
        gk_pairlist_reserve(&rve->outer, (size_t)hd.nouter + 1, n))
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory restoring %d pairs", hd.npairs);
    off = sizeof hd;
    for (q = 0; q < GK__NFIELDS; ++q) {
        const gk__field *f = &gk__fields[q];
        if ((f->flags & GK__SAVE) && gk__field_on(rve, f))
            GK__GET(gk__fget(rve, f->off), gk__fcount(rve, f, np, (size_t)hd.nouter) * f->size);
    }
    rve->outer.n = hd.nouter;
    rve->outer.np = rve->n;
    rve->outer_valid = hd.outer_valid;
    rve->outer_in_ok = 0; /* the lists come from the state */
    gk_m3_copy(hd.ho0, rve->ho0);
    rve->skin_in = hd.skin_in;
    rve->pl.n = hd.npairs;
    gk__pair_index(rve); /* CSR by i and the j index are functions of the pair list */
    rve->dt = hd.dt;
    rve->time = hd.time;
    rve->dt_crit = hd.dt_crit;
    rve->skin = hd.skin;
    rve->step = hd.step;
    rve->rebuilds = hd.rebuilds;
    gk_m3_copy(hd.h, rve->cell.h);
    gk_m3_inverse(rve->cell.h, rve->cell.hinv);
    gk_m3_copy(hd.F, rve->cell.F);
    rve->cell.flips = hd.flips;
    gk_m3_copy(hd.h0, rve->h0);
    gk_m3_copy(hd.L, rve->L);
    gk_m3_copy(hd.G, rve->G);
    gk_m3_copy(hd.stress, rve->stress);
    for (k = 0; k < 3; ++k) rve->stiff[k] = hd.stiff[k];
    rve->fc_mean = hd.fc_mean;
    rve->ncontacts = hd.ncontacts;
    rve->need_rebuild = hd.need_rebuild;
    rve->servo_on = hd.servo_on;
    rve->servo = hd.servo;
    rve->K.mu = (gk_real)hd.mu;
    rve->def.mat.friction = hd.mu;
    rve->diverged = 0;
    return GK_OK;
}

GKDEF void gk_rve_state_init(gk_rve_state *st, const gk_allocator *alloc) {
    st->buf = NULL;
    st->size = st->cap = 0;
    if (alloc)
        st->alloc = *alloc;
    else
        memset(&st->alloc, 0, sizeof st->alloc);
}
GKDEF void gk_rve_state_free(gk_rve_state *st) {
    gk_free(&st->alloc, st->buf);
    gk_rve_state_init(st, &st->alloc);
}
GKDEF gk_result gk_rve_state_save(gk_rve_state *st, const gk_rve *rve) {
    size_t need = gk_rve_state_size(rve);
    if (need > st->cap) {
        unsigned char *b = (unsigned char *)gk_alloc(&st->alloc, need + need / 4);
        if (!b) return GK_ERR_ALLOC;
        gk_free(&st->alloc, st->buf);
        st->buf = b;
        st->cap = need + need / 4;
    }
    st->size = need;
    return gk_rve_save(rve, st->buf, st->cap, NULL);
}
GKDEF gk_result gk_rve_state_restore(const gk_rve_state *st, gk_rve *rve) {
    return gk_rve_restore(rve, st->buf, st->size);
}

#endif /* GK_DEM implementation */
