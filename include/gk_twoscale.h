/* gk_twoscale.h - the micro side of a two-scale model: one RVE per
 * integration point, on threads or MPI ranks.                 (grainkit v0.1)
 *
 * A gk_twoscale is a set of N periodic DEM RVEs (gk_dem.h), one behind every
 * Gauss point of a FEM mesh or every material point of an MPM model. The
 * macro side hands it one displacement-gradient increment dH per point and
 * gets back one stress per point (and, on request, one tangent); the set
 * owns every RVE, its last accepted state, its history and its checkpoint.
 * A driver is then the macro model alone.
 *
 * DO THIS in one C/C++ file:   #define GK_IMPLEMENTATION
 *                              #include "gk_twoscale.h"  (gk_homog.h, gk_dem.h)
 *
 *   gk_packing pk;  gk_err e;  gk_twoscale ts;
 *   gk_twoscale_proto proto = {&pk, NULL};        // every point: this packing
 *   gk_twoscale_def def;  memset(&def, 0, sizeof def);   // zero = defaults
 *   gk_packing_read("rve400.txt", &pk, NULL, &e);
 *   def.npoints = 512, def.protos = &proto, def.nprotos = 1, def.threads = 2;
 *   if (gk_twoscale_create(&ts, &def)) puts(gk_twoscale_error(&ts));
 *   ...
 *   gk_twoscale_run(&ts, dH, NULL, sigma, D);     // dH[9 N] in, sigma[9 N], D[dim^4 N] out
 *   gk_twoscale_accept(&ts);                      // or: try another dH (Newton)
 *   gk_twoscale_destroy(&ts); gk_packing_free(&pk);
 *
 * THE CONTRACT
 *   Every run starts each point from its LAST ACCEPTED state, so an implicit
 *   driver runs as many trial iterates of a load step as it likes and keeps
 *   one (gk_twoscale_accept), and an explicit driver runs once per step and
 *   accepts every step. gk_twoscale_reject forgets the trial (the next run
 *   starts from the accepted state anyway; reject says so explicitly).
 *     implicit FEM (Newton):   repeat { run(dH_k, sigma, D); solve } until
 *                              converged; accept   (cut-back: run again with a
 *                              smaller dH and run_def.scale < 1)
 *     explicit MPM / dynamic relaxation: per step run(dt L, sigma, NULL); accept
 *   A point whose run fails keeps its accepted state; its code and message
 *   are in gk_twoscale_points / gk_twoscale_point_error, and every other
 *   point's result is still there (one failure never hides the others).
 *   gk_twoscale_accept takes the points whose run succeeded; a failed point
 *   stays at its accepted state (an explicit driver may so freeze a point
 *   whose RVE refused its dH, e.g. GK_ERR_CELL: the cell would get too thin).
 *
 * FUNCTIONS (each returns a gk_result unless noted; the message: gk_twoscale_error)
 *   gk_twoscale_create(ts, def)          the set; gk_twoscale_destroy(ts) frees it
 *   gk_twoscale_run(ts, dH, rd, sigma, D) every point from its accepted state by its dH
 *   gk_twoscale_accept(ts) / _reject(ts) keep / forget the trial states of the last run
 *   gk_twoscale_points(ts)               what the last run did per point (gk_twoscale_point:
 *                                        code, DEM steps, tangent computed or reused, contacts)
 *   gk_twoscale_point_error(ts, p)       a failed point's message
 *   gk_twoscale_accepted(ts, sigma, D)   stress and homogenised tangent of the accepted states
 *   gk_twoscale_fields(ts, f)            p, q, e, Z, fabric, rotations, strains, DEM steps ...
 *                                        (gk_twoscale_field) of the accepted states
 *   gk_twoscale_save(ts, path, blk, n) / gk_twoscale_load(ts, path, &blk, &n)   checkpoint
 *   gk_twoscale_load_take(ts, path, take, user)   the same, the driver's block checked first
 *   gk_twoscale_draw(n, nprotos, seed, pick)   the per-point draw of prototypes
 *   accepted, fields: of the accepted states, so not while a run is pending (accept or
 *   reject first: GK_ERR_STATE). Under MPI every function is collective.
 *
 * THE DEM STEPS OF A RUN (gk_twoscale_rule; the one implementation)
 *   GK_TWOSCALE_ADAPTIVE (default): gk_rve_deform_adaptive (gk_homog.h) - dH
 *     over n = clamp(ceil(I_1 / I_max), n_min, n_max) steps, I_1 the inertial
 *     number (Guo & Zhao 2014 eq 20) of dH in one DEM step at the RVE's pressure,
 *     then relaxation at fixed cell in chunks of `every` steps while the
 *     unbalanced force ratio exceeds unbalanced_max, n_max steps in all
 *     (the mean ratio, as YADE; unbalanced_rms = 1: the RMS ratio I_uf of
 *     Liu, Sun, Yuan & Fish 2016 eq 57).
 *   GK_TWOSCALE_STRAIN: n = clamp(ceil(max|dH_ij| / strain), n_min, n_max),
 *     no relaxation (Guo & Zhao 2014's scripts: strain = 1e-5).
 *   run_def.scale < 1 marks a cut-back increment: the bound is scaled with it
 *   (strain x scale, I_max x scale), so a cut-back increment keeps the step
 *   count of the full one - a slower ramp, not fewer and noisier steps.
 *
 * THE CALLER'S PROCEDURE (def.proc; boundary conditions other than the
 *   deforming periodic cell, e.g. a frame of prescribed boundary particles
 *   servo-controlled to periodicity: gk_frame.h). Instead of the DEM-steps
 *   rule, every run calls, for each point from its accepted state,
 *       proc(def.proc_user, point, prototype, rve, H, dH, scale, stress, &steps)
 *   H the sum of the dH of its accepted runs, dH this run's; the procedure
 *   moves the RVE as it likes (gk_rve_step, a hook, another cell), writes
 *   the point's stress (whatever its measure: the set returns it, keeps the
 *   accepted one for gk_twoscale_accepted, the fields' stress, p and q, and
 *   the checkpoint, never recomputing it from the RVE) and the DEM steps it
 *   took, and returns GK_OK or a code with its message in rve->err. It is
 *   called concurrently for different points (the set's threads): it may
 *   change only its point's RVE (def.proc_user read-only, or per point).
 *   A point's accepted stress is 0 until its first accepted run. No
 *   tangent: a run or gk_twoscale_accepted asking for D is refused
 *   (GK_ERR_ARG). The fields that come from the RVE itself (void ratio,
 *   volume, coordination, fabric) are those of its whole cell.
 *
 * THE TANGENT (D != NULL in gk_twoscale_run)
 *   GK_TWOSCALE_TANGENT_HOMOG (default): gk_homog_tangent with tangent_opts:
 *     0 = eq 9 of Guo & Zhao 2014 (Taylor, sliding contacts k_t = 0),
 *     GK_TANGENT_SLIDING_KEEP (the authors' YADE form), GK_TANGENT_RELAXED
 *     (the particles relaxed), see gk_homog.h.
 *   GK_TWOSCALE_TANGENT_PERTURBATION: eq 8 of Guo & Zhao (2014), finite
 *     differences D_ijkl = (sigma_ij(dH + xi e_kl) - sigma_ij(dH)) / xi: dim^2
 *     more runs per point. Their DEM step counts are the trial run's (a
 *     changed count would swamp the difference): with the strain rule they
 *     run first, otherwise after the trial run, which is then repeated
 *     (bit-identical) to leave the RVE in its trial state. gk_twoscale_accepted
 *     gives the homogenised tangent (tangent_opts) at the accepted state.
 *   Reuse (def.reuse = X > 0): a point keeps its last computed tangent while
 *     its contact network has changed by less than the fraction X since:
 *     (contacts created + lost + whose sliding state flipped) / contacts then,
 *     a contact named by its two particles' packing ids (gk_rve_contact_next).
 *     The reference lives across runs and load steps (it is not rolled back
 *     by reject) and is in the checkpoint, so a restart reuses exactly where
 *     an uninterrupted run does.
 *
 * CONVENTIONS (as every grainkit header; gk_base.h)
 *   SI units. Stress and the tangent are TENSION-POSITIVE (the seeds are
 *   compression-positive: convert at output). Tensors are 3x3 row-major,
 *   dH[9 p + 3 i + j] = d(u_i)/d(x_j) of point p (stretch AND spin: Guo & Zhao 2014
 *   eq 10); in 2D the out-of-plane entries (2, 5, 6, 7, 8) must be 0 (a dH
 *   with one is refused, not clipped). sigma[9 p + 3 i + j] is the Love
 *   stress (Guo & Zhao 2014 eq 5), D[dim^4 p + ((i dim + j) dim + k) dim + l]
 *   = d sigma_ij / d dH_kl. Fields: p = -tr(sigma)/dim and q (Guo & Zhao 2014 eq 7)
 *   compression-positive, eps_v = tr sym(H) tension-positive, rotations in
 *   radians counter-clockwise.
 *
 * CREATION. Each point starts as a copy of one prototype (gk_twoscale_proto):
 *   a packing, and optionally a saved state of an RVE created from that
 *   packing with def->rve (e.g. consolidated to a pressure); without a state
 *   the RVE as created, forces refreshed. pick[p] names each point's
 *   prototype; without pick, one prototype goes everywhere, or with several
 *   each point draws one uniformly in point order from `seed`
 *   (gk_twoscale_draw: xoshiro256**, the same on every run, thread and rank
 *   count). The set copies the packings and states: the caller may free them.
 *
 * DETERMINISM. Every point's run depends on its own data only, so the
 *   results are identical, bit for bit, for any thread count, any rank count
 *   and any assignment of points to ranks (tested).
 *
 * CHECKPOINT (gk_twoscale_save / gk_twoscale_load). One file for the whole
 *   set, whatever the rank count: a header (magic "GKTWOSC\0", format
 *   version, byte order, real size, dim, N, prototypes, the prototype of
 *   every point), one record per point in point order (its accumulated dH,
 *   accepted stress, DEM steps of its last accepted run, tangent-reuse
 *   reference, accepted RVE state), then the DRIVER'S OWN BLOCK (any bytes: the macro state),
 *   then a 64-bit FNV-1a checksum of all of it. Written to PATH.tmp and
 *   renamed. Loading checks the checksum over the whole file, every size
 *   and count against the file and the set, every value of a record (finite,
 *   |H| <= 1e6, |sigma| <= 1e100 Pa, a finite reference tangent, sorted
 *   contact keys), and restores all points into staging first: a truncated,
 *   corrupted, foreign or other-version file is refused by name and the set
 *   is unchanged. gk_twoscale_load_take gives the driver's block to the
 *   driver's take function before the set takes the staged states, so a
 *   driver that checks its block there and refuses it leaves the set as it
 *   was too (a driver replicated on MPI ranks refuses on all of them alike).
 *
 * MPI (optional, like OpenMP). Define GK_TWOSCALE_MPI (and build with mpicc)
 *   and create the set with gk_twoscale_create_mpi(&ts, &def, comm) (or
 *   gk_twoscale_create: MPI_COMM_WORLD). Every rank calls every function
 *   (they are collective), the driver being replicated on every rank. Each
 *   rank creates and stores only its own points. Per run: the dH of RANK 0
 *   is broadcast (so only rank 0's counts; the others may pass NULL), each
 *   rank runs its points on its threads, and stress, tangent and the point
 *   reports are gathered to EVERY rank (MPI_Allgatherv). Points are
 *   assigned by cost: at first by particle count; then, when the ranks'
 *   costs of the last run ((DEM steps + 1) x particles, summed) are more
 *   than balance_tol (default 5 %) above their mean, points move from the
 *   most to the least loaded rank (each move the point whose cost is
 *   nearest half the gap, until within the tolerance) and their accepted
 *   states migrate (with their tangent-reuse reference). When (def.balance):
 *     GK_TWOSCALE_BALANCE_ACCEPT (default): after every accept, on the
 *       costs of the accepted run - the next load step runs on the last
 *       step's costs;
 *     GK_TWOSCALE_BALANCE_RUN: before every run, on the costs of the
 *       previous run, accepted or not - so every Newton iteration of a
 *       load step after the first runs on the costs of the previous one,
 *       which predict it much better than the last step's (the same
 *       accepted state, nearly the same dH: correlation 0.975 against
 *       0.47-0.85 on the biaxial test). A pending trial state is not moved:
 *       the run recomputes every point from its accepted state anyway, and
 *       an accept takes the trials of the ranks that ran them. A refused
 *       run (bad argument) moves nothing.
 *   No balance beats the spread of the costs it is given: with the adaptive
 *   rule a few points relax far longer than the rest, and at about 8
 *   points per rank the most loaded rank waits on them (about 70 % of the
 *   ideal at 1000 ranks in the scaling model). A fixed step count per run
 *   (rule.n_min = rule.n_max) makes every point cost the same (92 %), at
 *   the price of no relaxation (less softening after a peak).
 *   gk_twoscale_stats counts the moves and their bytes (migrated,
 *   migrated_bytes; under BALANCE_RUN they are also part of run_bytes_*).
 *   The checkpoint is written and read by rank 0. Without GK_TWOSCALE_MPI
 *   nothing here needs MPI.
 *
 * CONFIGURATION: GK_TWOSCALE_MPI (above).
 * REFERENCES: Guo N., Zhao J. (2014) A coupled FEM/DEM approach for
 *   hierarchical multiscale modelling of granular media. Int J Numer Meth
 *   Eng 99:789-818 (Guo & Zhao 2014: eqs 5, 7, 8, 9, 10, 20). Liang W., Zhao J.
 *   (2019) Multiscale modeling of large deformation in geomechanics
 *   (Liang & Zhao 2019: MPMxDEM, the explicit use).
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_TWOSCALE_H
#define GK_TWOSCALE_H

#include "gk_homog.h"
#ifdef GK_TWOSCALE_MPI
#include <mpi.h>
#endif

#define GK_TWOSCALE_CHECKPOINT_VERSION 2

typedef enum gk_twoscale_rule_kind { GK_TWOSCALE_ADAPTIVE = 0, GK_TWOSCALE_STRAIN = 1 } gk_twoscale_rule_kind;

/* the DEM steps of a run (above); zero means the default */
typedef struct gk_twoscale_rule {
    gk_twoscale_rule_kind kind;
    double inertial_max;   /* adaptive: I bound of the deformation; 0 -> 5e-4              */
    double unbalanced_max; /* adaptive: relax until the unbalanced force ratio < this; 0 -> 5e-3 */
    double strain;         /* strain rule: max |dH_ij| per DEM step; 0 -> 1e-5             */
    int n_min, n_max;      /* DEM steps per run, in all; 0 -> 10 and 5000                 */
    int every;             /* adaptive: relaxation steps between checks; 0 -> 20          */
    int unbalanced_rms;    /* adaptive: 1 = the RMS ratio I_uf (Liu et al. 2016 eq 57), not the mean */
} gk_twoscale_rule;

typedef enum gk_twoscale_tangent_kind {
    GK_TWOSCALE_TANGENT_HOMOG = 0,       /* gk_homog_tangent(tangent_opts): eq 9, relaxed     */
    GK_TWOSCALE_TANGENT_PERTURBATION = 1 /* eq 8: finite differences of dim^2 perturbed runs */
} gk_twoscale_tangent_kind;

/* when the points are rebalanced over the MPI ranks (MPI, above) */
typedef enum gk_twoscale_balance_kind {
    GK_TWOSCALE_BALANCE_ACCEPT = 0, /* after every accept, on the costs of the accepted run           */
    GK_TWOSCALE_BALANCE_RUN = 1     /* before every run, on the costs of the previous run (accepted or not) */
} gk_twoscale_balance_kind;

/* a run of one point by the caller's procedure (THE CALLER'S PROCEDURE) */
typedef gk_result (*gk_twoscale_proc_fn)(void *user, int point, int proto, gk_rve *rve, const double H[9],
                                         const double dH[9], double scale, double stress[9], int *steps);

/* what a point starts from: an RVE created from `packing` (with def->rve),
 * then set to `state` (saved from an RVE created the same way) or, when
 * state is NULL, as created with its forces refreshed */
typedef struct gk_twoscale_proto {
    const gk_packing *packing;
    const gk_rve_state *state;
} gk_twoscale_proto;

typedef struct gk_twoscale_def {
    int npoints;                     /* N >= 1                                             */
    const gk_twoscale_proto *protos; /* nprotos prototypes (copied)                        */
    int nprotos;
    const int *pick; /* N prototype indices; NULL: 0 everywhere, or drawn (several) */
    uint64_t seed;   /* of that draw (gk_twoscale_draw)                              */
    gk_rve_def rve;  /* the RVEs' definition; zero (cookie 0) -> gk_rve_def_default() */
    gk_twoscale_rule rule;
    gk_twoscale_tangent_kind tangent;
    unsigned tangent_opts;    /* GK_TANGENT_* of gk_homog_tangent (also eq 8's start tangent)  */
    gk_twoscale_proc_fn proc; /* the caller's procedure instead of the rule (above); NULL: none */
    void *proc_user;          /* its first argument                                          */
    double xi;                /* eq 8 perturbation of dH; 0 -> 5e-5 (Guo & Zhao 2014 Fig 6)          */
    double reuse;             /* tangent reuse bound, 0 <= X < 1; 0: off                      */
    int threads;              /* OpenMP threads over a rank's points; 0 -> 1                  */
    double balance_tol;       /* MPI: accepted load imbalance; 0 -> 0.05                      */
    gk_twoscale_balance_kind balance; /* MPI: when to rebalance; 0: at every accept (above)  */
    gk_allocator alloc;
} gk_twoscale_def;

/* one call of gk_twoscale_run; NULL or zero means the default */
typedef struct gk_twoscale_run_def {
    double scale; /* rate scale of a cut-back increment, in (0, 1]; 0 -> 1 (above) */
} gk_twoscale_run_def;

/* what the last run did at one point */
typedef struct gk_twoscale_point {
    int code;      /* gk_result of the run (GK_OK; the message: gk_twoscale_point_error)  */
    int n_deform;  /* DEM steps of the deformation of its trial run                       */
    int n_relax;   /* ... and of its relaxation at fixed cell (adaptive rule)             */
    int work;      /* every DEM step of the call at this point (eq 8's runs included)     */
    int tangent;   /* 0 not asked (or failed), 1 computed, 2 reused                       */
    int contacts;  /* contacts after the run                                              */
    int particles; /* particles of the RVE                                                */
} gk_twoscale_point;

/* per-point fields of the ACCEPTED state (for VTK and the like); all doubles */
typedef struct gk_twoscale_field {
    double p, q;         /* -tr(sigma)/dim and q of Guo & Zhao 2014 eq 7 [Pa], compression +      */
    double void_ratio;   /* gk_homog_void_ratio                                            */
    double coordination; /* Z = 2 contacts / particles                                     */
    double fabric;       /* |F_a| of the contact normals (gk_homog_fabric)                 */
    double rotation;     /* gk_homog_mean_rotation [rad] (3D: 0 without GK_RVE_TRACK_ROTATION) */
    double spin;         /* rotation of the polar decomposition of I + H [rad]             */
    double eps_v, eps_q; /* of the small strain sym(H): tension-positive eps_v            */
    double volume, mass; /* stress volume [m^3 in 3D, m^2 x thickness in 2D], mass [kg]   */
    double dem_steps;    /* DEM steps of the last accepted run                             */
    double contacts;     /* contacts                                                       */
    double stress[9];    /* Love stress, tension-positive [Pa]                             */
    double H[9];         /* sum of the dH of the accepted runs                             */
} gk_twoscale_field;

/* traffic of this rank (MPI; zero otherwise) since creation */
typedef struct gk_twoscale_stats {
    long long runs;           /* gk_twoscale_run calls                                    */
    long long run_bytes_out;  /* ... bytes this rank sent in them (its part of the results; rank 0:
                                the dH broadcast too)                                    */
    long long run_bytes_in;   /* ... bytes it received in them (dH, the other ranks' results) */
    long long bytes_out;      /* bytes sent in all calls (fields, checkpoints, migrations too) */
    long long bytes_in;       /* bytes received in all calls                              */
    long long collectives;    /* collective calls                                         */
    long long migrated;       /* points that moved to another rank (all ranks counted)    */
    long long migrated_bytes; /* ... the bytes of their records (all ranks counted)       */
    long long balances;       /* rebalances that moved points                             */
} gk_twoscale_stats;

struct gk__tspt; /* one local point (implementation) */

typedef struct gk_twoscale {
    int n, dim, nd4;     /* points, dimension, dim^4 (tangent entries per point)          */
    int rank, nranks;    /* MPI rank and size (0, 1 without MPI)                          */
    int nlocal;          /* points stored on this rank                                    */
    gk_twoscale_def def; /* the definition, defaults filled (protos and pick: NULL)       */
    int nproto;
    gk_packing *pk;               /* copies of the prototypes' packings                            */
    int *pick;                    /* N: prototype of each point                                    */
    int *owner;                   /* N: rank of each point                                         */
    int *slot;                    /* N: index in pt[] on this rank, or -1                          */
    int *order, *counts, *displs; /* points by (owner, id); per rank: count, first        */
    struct gk__tspt **pt;         /* nlocal, ascending point index                                */
    gk_twoscale_point *last;      /* N: the last run (every rank)                              */
    int nfail, *fail_id;          /* failed points of the last run, ascending, and their messages  */
    char *fail_msg;
    double *buf, *buf2; /* scratch: packed results (local; all, in rank order)            */
    size_t bufcap, buf2cap;
    double *hbuf; /* MPI: rank 0's dH, broadcast                                    */
    int pending;  /* a run not yet accepted or rejected                             */
    gk_twoscale_stats stats;
    gk_err err;
#ifdef GK_TWOSCALE_MPI
    MPI_Comm comm;
#endif
} gk_twoscale;

#ifdef __cplusplus
extern "C" {
#endif

GKDEF gk_result gk_twoscale_create(gk_twoscale *ts, const gk_twoscale_def *def);
#ifdef GK_TWOSCALE_MPI
GKDEF gk_result gk_twoscale_create_mpi(gk_twoscale *ts, const gk_twoscale_def *def, MPI_Comm comm);
#endif
GKDEF void gk_twoscale_destroy(gk_twoscale *ts);
GKDEF const char *gk_twoscale_error(const gk_twoscale *ts);
/* every point from its accepted state by its dH (9 N; rank 0's under MPI); stress (9 N) and, when D is
 * not NULL, the tangent (dim^4 N) out on every rank. GK_OK, GK_ERR_ARG / GK_ERR_NAN for a refused
 * argument (nothing ran), or GK_ERR_STATE when one or more points failed (the message names how many
 * and the first; every point's report in gk_twoscale_points; a failed point's stress is its accepted
 * one and its tangent 0) */
GKDEF gk_result gk_twoscale_run(gk_twoscale *ts, const double *dH, const gk_twoscale_run_def *rd,
                                double *stress, double *D);
/* the trial states of the points whose last run succeeded become their accepted states (the
 * others keep theirs); under MPI then rebalances (def.balance 0). GK_ERR_STATE if there is no run to
 * accept. Copies nothing: a point's accepted state is copied out of its RVE when the next run starts
 * to change it (a run's point that cannot get the memory for that copy fails with GK_ERR_ALLOC and
 * keeps its state), or by a checkpoint or a migration */
GKDEF gk_result gk_twoscale_accept(gk_twoscale *ts);
GKDEF void gk_twoscale_reject(gk_twoscale *ts);
/* the reports of the last run (N), and a failed point's message ("" if it did not fail) */
GKDEF const gk_twoscale_point *gk_twoscale_points(const gk_twoscale *ts);
GKDEF const char *gk_twoscale_point_error(const gk_twoscale *ts, int p);
/* stress (9 N) and, when D is not NULL, the tangent_opts tangent (dim^4 N) of the accepted states */
GKDEF gk_result gk_twoscale_accepted(gk_twoscale *ts, double *stress, double *D);
GKDEF gk_result gk_twoscale_fields(gk_twoscale *ts, gk_twoscale_field *f);
/* the whole set and the driver's block (nblock bytes, rank 0's) into one file */
GKDEF gk_result gk_twoscale_save(gk_twoscale *ts, const char *path, const void *block, size_t nblock);
/* ... and back; *block (allocated with def.alloc, free with gk_twoscale_free_block) on every rank */
GKDEF gk_result gk_twoscale_load(gk_twoscale *ts, const char *path, void **block, size_t *nblock);
/* the driver's part of a load: its block (nblock bytes, read and checksummed) checked and, when it is
 * taken, applied to the driver's model (user); 0 to take it, else a reason in why (nwhy bytes) */
typedef int (*gk_twoscale_take_fn)(const void *block, size_t nblock, void *user, char *why, size_t nwhy);
/* gk_twoscale_load with the driver's block taken by take (on every rank) before the set takes the
 * file's states: when take refuses it (on any rank) the set is left as it was, GK_ERR_FORMAT with
 * take's reason; when it takes it, the set takes the states (which can no longer fail) */
GKDEF gk_result gk_twoscale_load_take(gk_twoscale *ts, const char *path, gk_twoscale_take_fn take,
                                      void *user);
GKDEF void gk_twoscale_free_block(const gk_twoscale *ts, void *block);
/* the uniform draw of prototypes per point used when def.pick is NULL and nprotos > 1 */
GKDEF void gk_twoscale_draw(int npoints, int nprotos, uint64_t seed, int *pick);

#ifdef __cplusplus
}
#endif
#endif /* GK_TWOSCALE_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_TWOSCALE_IMPLEMENTATION)) && !defined(GK_TWOSCALE_IMPL_ONCE)
#define GK_TWOSCALE_IMPL_ONCE

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GK__TS_MAGIC "GKTWOSC" /* 8 bytes with its terminating zero */
#define GK__TS_NREP 7          /* ints of a gk_twoscale_point      */
#define GK__TS_NFIELD ((int)(sizeof(gk_twoscale_field) / sizeof(double)))
#define GK__TS_MAXKEYS (1 << 28) /* contacts of one RVE, for range checks */
GK_STATIC_ASSERT(sizeof(gk_twoscale_point) == GK__TS_NREP * sizeof(int), ts_point_ints);
GK_STATIC_ASSERT(sizeof(gk_twoscale_field) % sizeof(double) == 0, ts_field_doubles);

typedef struct gk__tspt {
    int id;
    gk_rve rve;
    gk_rve_state acc;   /* the accepted state, unless stale                        */
    int live;           /* 1: rve holds the accepted state                         */
    int stale;          /* 1: only rve holds it (accepted since the last copy)      */
    int trial_ok;       /* the last run succeeded and was not accepted yet          */
    double H[9], dH[9]; /* accumulated dH of accepted runs; dH of the last run      */
    double sacc[9];     /* stress of the accepted state                             */
    double strial[9];   /* the procedure's stress of the last run (def.proc)        */
    int steps_acc, steps_trial;
    /* tangent reuse: reference tangent, its network (sorted keys), the current network */
    double *Dref;
    unsigned long long *key, *cur;
    int nkey, ncur, cap, valid;
    gk_err err; /* the first failure of the last run                        */
} gk__tspt;

GKDEF const char *gk_twoscale_error(const gk_twoscale *ts) { return ts->err.msg; }

GKDEF void gk_twoscale_draw(int npoints, int nprotos, uint64_t seed, int *pick) {
    gk_rng rng;
    int p;
    gk_rng_seed(&rng, seed);
    for (p = 0; p < npoints; ++p) pick[p] = nprotos > 1 ? (int)(gk_rng_u64(&rng) % (uint64_t)nprotos) : 0;
}

/* ------------------------------------------------------------ MPI plumbing */
/* Without GK_TWOSCALE_MPI these are the one-rank identities. */
static int gk__ts_allok(gk_twoscale *ts, int ok) {
#ifdef GK_TWOSCALE_MPI
    int all = ok;
    if (ts->nranks > 1) {
        MPI_Allreduce(&ok, &all, 1, MPI_INT, MPI_MIN, ts->comm);
        ++ts->stats.collectives;
    }
    return all;
#else
    (void)ts;
    return ok;
#endif
}

/* rank 0's error (code and message) on every rank; returns the code */
static gk_result gk__ts_share_err(gk_twoscale *ts) {
#ifdef GK_TWOSCALE_MPI
    if (ts->nranks > 1) {
        MPI_Bcast(&ts->err, (int)sizeof ts->err, MPI_BYTE, 0, ts->comm);
        ++ts->stats.collectives;
    }
#endif
    return ts->err.code;
}

/* on failure of some rank: the lowest failing rank's message everywhere */
static gk_result gk__ts_agree(gk_twoscale *ts, gk_result local) {
#ifdef GK_TWOSCALE_MPI
    if (ts->nranks > 1) {
        int mine = local ? ts->rank : ts->nranks, first;
        MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, ts->comm);
        ++ts->stats.collectives;
        if (first == ts->nranks) return GK_OK;
        if (!local) ts->err.code = GK_OK;
        MPI_Bcast(&ts->err, (int)sizeof ts->err, MPI_BYTE, first, ts->comm);
        return ts->err.code ? ts->err.code : GK_ERR_STATE;
    }
#else
    (void)ts;
#endif
    return local;
}

/* points by (owner, point index) and the per-rank counts and offsets */
static void gk__ts_layout(gk_twoscale *ts) {
    int r, p, nl = 0;
    for (r = 0; r < ts->nranks; ++r) ts->counts[r] = 0;
    for (p = 0; p < ts->n; ++p) ++ts->counts[ts->owner[p]];
    ts->displs[0] = 0;
    for (r = 1; r < ts->nranks; ++r) ts->displs[r] = ts->displs[r - 1] + ts->counts[r - 1];
    for (r = 0; r < ts->nranks; ++r) ts->counts[r] = 0;
    for (p = 0; p < ts->n; ++p) {
        int o = ts->owner[p];
        ts->order[ts->displs[o] + ts->counts[o]++] = p;
        ts->slot[p] = o == ts->rank ? nl++ : -1;
    }
    ts->nlocal = nl;
}

/* the local results (nlocal records of nrec doubles, ascending point order, at ts->buf) of every rank:
 * the records of all points in (owner, point) order, record j being point ts->order[j] */
static const double *gk__ts_gather(gk_twoscale *ts, int nrec) {
#ifdef GK_TWOSCALE_MPI
    if (ts->nranks > 1) {
        int r, *cnt = ts->counts + ts->nranks, *dis = ts->displs + ts->nranks;
        for (r = 0; r < ts->nranks; ++r) cnt[r] = ts->counts[r] * nrec, dis[r] = ts->displs[r] * nrec;
        MPI_Allgatherv(ts->buf, cnt[ts->rank], MPI_DOUBLE, ts->buf2, cnt, dis, MPI_DOUBLE, ts->comm);
        ++ts->stats.collectives;
        ts->stats.bytes_out += (long long)cnt[ts->rank] * 8;
        ts->stats.bytes_in += ((long long)ts->n * nrec - cnt[ts->rank]) * 8;
        return ts->buf2;
    }
#else
    (void)nrec;
#endif
    return ts->buf;
}

/* room for the packed records of a gather (ts->buf local, ts->buf2 all) */
static gk_result gk__ts_bufs(gk_twoscale *ts, int nrec) {
    size_t need = (size_t)ts->n * (size_t)nrec + 1;
    if (need > ts->bufcap) {
        if (gk_realloc(&ts->def.alloc, (void **)&ts->buf, 0, need, sizeof(double)))
            return gk_err_set(&ts->err, GK_ERR_ALLOC, "out of memory for %d points' results", ts->n);
        ts->bufcap = need;
    }
    if (ts->nranks > 1 && need > ts->buf2cap) {
        if (gk_realloc(&ts->def.alloc, (void **)&ts->buf2, 0, need, sizeof(double)))
            return gk_err_set(&ts->err, GK_ERR_ALLOC, "out of memory for %d points' results", ts->n);
        ts->buf2cap = need;
    }
    return GK_OK;
}

/* ------------------------------------------------------------------ points */
static void gk__ts_pt_free(gk_twoscale *ts, gk__tspt *pt) {
    const gk_allocator *a = &ts->def.alloc;
    if (!pt) return;
    gk_rve_destroy(&pt->rve);
    gk_rve_state_free(&pt->acc);
    gk_free(a, pt->Dref);
    gk_free(a, pt->key);
    gk_free(a, pt->cur);
    gk_free(a, pt);
}

/* a point of prototype k: the RVE created from its packing and set to `state` (size bytes) */
static gk_result gk__ts_pt_new(gk_twoscale *ts, int id, int k, const void *state, size_t size,
                               gk__tspt **out) {
    gk__tspt *pt = (gk__tspt *)gk_alloc(&ts->def.alloc, sizeof *pt);
    gk_result res;
    *out = NULL;
    if (!pt) return gk_err_set(&ts->err, GK_ERR_ALLOC, "out of memory for point %d", id);
    memset(pt, 0, sizeof *pt);
    pt->id = id;
    gk_rve_state_init(&pt->acc, &ts->def.alloc);
    if (ts->def.reuse > 0 &&
        !(pt->Dref = (double *)gk_alloc(&ts->def.alloc, (size_t)ts->nd4 * sizeof(double)))) {
        gk_free(&ts->def.alloc, pt);
        return gk_err_set(&ts->err, GK_ERR_ALLOC, "out of memory for point %d", id);
    }
    res = gk_rve_create(&pt->rve, &ts->def.rve, &ts->pk[k]);
    if (res) {
        gk_err_set(&ts->err, res, "point %d (prototype %d): %s", id, k, gk_rve_error(&pt->rve));
        gk_free(&ts->def.alloc, pt->Dref);
        gk_free(&ts->def.alloc, pt);
        return res;
    }
    res = gk_rve_restore(&pt->rve, state, size);
    if (!res) res = gk_rve_state_save(&pt->acc, &pt->rve);
    if (res) {
        gk_err_set(&ts->err, res, "point %d (prototype %d): %s", id, k,
                   res == GK_ERR_ALLOC ? "out of memory for its state" : gk_rve_error(&pt->rve));
        gk__ts_pt_free(ts, pt);
        return res;
    }
    pt->live = 1;
    if (!ts->def.proc) gk_rve_stress(&pt->rve, pt->sacc);
    *out = pt;
    return GK_OK;
}

/* the accepted state copied out of the RVE where only the RVE holds it (before a run changes the
 * RVE, and for a record: checkpoint, migration): GK_OK, or GK_ERR_ALLOC and the point as it was */
static gk_result gk__ts_sync(gk__tspt *pt) {
    if (!pt->stale) return GK_OK;
    if (gk_rve_state_save(&pt->acc, &pt->rve)) return GK_ERR_ALLOC;
    pt->stale = 0;
    return GK_OK;
}

/* the RVE back to the accepted state when it holds another; and before a run changes it (change =
 * 1), its accepted state copied out when only the RVE holds it. The copy is taken here rather than
 * at accept: the run that follows finds the RVE in cache, and a point that does not run again is
 * never copied. A point whose copy fails is left as it was. */
static gk_result gk__ts_reset(gk__tspt *pt, int change) {
    gk_result res;
    if (!pt->live) { /* (stale implies live) */
        res = gk_rve_state_restore(&pt->acc, &pt->rve);
        if (res) return res;
        pt->live = 1;
    }
    if (change && gk__ts_sync(pt))
        return gk_err_set(&pt->rve.err, GK_ERR_ALLOC, "out of memory for the copy of its accepted state");
    return GK_OK;
}

/* the strain rule's step count for H at rate scale `scale` */
static int gk__ts_strain_steps(const gk_twoscale_rule *r, double scale, const double H[9]) {
    double mx = 0.0, n;
    int k;
    for (k = 0; k < 9; ++k)
        if (fabs(H[k]) > mx) mx = fabs(H[k]);
    n = ceil(mx / (r->strain * scale));
    if (n < r->n_min) n = r->n_min;
    if (n > r->n_max) n = r->n_max;
    return (int)n;
}

/* the trial run by the rule: *nd deformation and *nr relaxation steps */
static gk_result gk__ts_trial(const gk_twoscale *ts, gk__tspt *pt, const double H[9], double scale, int *nd,
                              int *nr) {
    const gk_twoscale_rule *r = &ts->def.rule;
    pt->live = 0;
    if (r->kind == GK_TWOSCALE_ADAPTIVE) {
        gk_adapt_def ad;
        gk_adapt_report rep;
        gk_result res;
        memset(&ad, 0, sizeof ad);
        memset(&rep, 0, sizeof rep);
        ad.inertial_max = r->inertial_max * scale, ad.unbalanced_max = r->unbalanced_max;
        ad.n_min = r->n_min, ad.n_max = r->n_max, ad.every = r->every, ad.rms = r->unbalanced_rms;
        res = gk_rve_deform_adaptive(&pt->rve, H, &ad, &rep);
        *nd = rep.n_deform, *nr = rep.n_relax;
        return res;
    }
    *nd = gk__ts_strain_steps(r, scale, H), *nr = 0;
    return gk_rve_deform(&pt->rve, H, *nd);
}

/* the same procedure with given counts: nd steps of deformation, then nr at fixed cell in chunks of
 * `every` (as gk_rve_deform_adaptive relaxes) */
static gk_result gk__ts_replay(gk__tspt *pt, const double H[9], int nd, int nr, int every) {
    gk_rve *r = &pt->rve;
    double L0[9], Lsave[9];
    int done = 0;
    gk_result res;
    pt->live = 0;
    if ((res = gk_rve_deform(r, H, nd)) != GK_OK || nr <= 0) return res;
    gk_m3_copy(r->L, Lsave);
    gk_m3_zero(L0);
    gk_rve_set_velocity_gradient(r, L0);
    while (done < nr) {
        int m = nr - done < every ? nr - done : every;
        if ((res = gk_rve_step(r, m)) != GK_OK) return res;
        done += m;
    }
    return gk_rve_set_velocity_gradient(r, Lsave);
}

/* tangent reuse: the contact network as sorted keys ((id_lo << 32 | id_hi) << 1 | sliding) in pt->cur;
 * the count, or -1 out of memory */
static int gk__ts_cmp_u64(const void *a, const void *b) {
    unsigned long long x = *(const unsigned long long *)a, y = *(const unsigned long long *)b;
    return x < y ? -1 : x > y;
}
static int gk__ts_reserve_keys(const gk_allocator *a, gk__tspt *pt, int cap) {
    if (cap <= pt->cap) return 0;
    if (gk_realloc(a, (void **)&pt->key, (size_t)pt->cap, (size_t)cap, sizeof *pt->key) ||
        gk_realloc(a, (void **)&pt->cur, (size_t)pt->cap, (size_t)cap,
                   sizeof *pt->cur)) /* cur may be filling */
        return -1;
    pt->cap = cap;
    return 0;
}
static int gk__ts_keys(const gk_allocator *a, gk__tspt *pt) {
    int c = 0, n = 0;
    gk_rve_contact k;
    while (gk_rve_contact_next(&pt->rve, &c, &k)) {
        if (n == pt->cap && gk__ts_reserve_keys(a, pt, 2 * pt->cap + 64)) return -1;
        pt->cur[n++] = (((unsigned long long)k.i << 32 | (unsigned long long)k.j) << 1) | (unsigned)k.sliding;
    }
    if (n > 1) qsort(pt->cur, (size_t)n, sizeof *pt->cur, gk__ts_cmp_u64); /* cur: NULL without contacts */
    pt->ncur = n;
    return n;
}
/* (created + lost + sliding flipped) / contacts of the reference */
static double gk__ts_change(const gk__tspt *pt) {
    int i = 0, j = 0, ch = 0;
    while (i < pt->nkey || j < pt->ncur) {
        unsigned long long a = i < pt->nkey ? pt->key[i] >> 1 : ~0ull,
                           b = j < pt->ncur ? pt->cur[j] >> 1 : ~0ull;
        if (i < pt->nkey && j < pt->ncur && a == b) {
            ch += (pt->key[i] & 1u) != (pt->cur[j] & 1u);
            ++i, ++j;
        } else if (j >= pt->ncur || (i < pt->nkey && a < b))
            ++ch, ++i; /* lost */
        else
            ++ch, ++j; /* created */
    }
    return (double)ch / (pt->nkey > 0 ? pt->nkey : 1);
}

/* a report as GK__TS_NREP doubles of a gathered record, and back */
static void gk__ts_put_rep(double *v, const gk_twoscale_point *rp) {
    v[0] = rp->code, v[1] = rp->n_deform, v[2] = rp->n_relax, v[3] = rp->work, v[4] = rp->tangent;
    v[5] = rp->contacts, v[6] = rp->particles;
}
static void gk__ts_get_rep(const double *v, gk_twoscale_point *rp) {
    rp->code = (int)v[0], rp->n_deform = (int)v[1], rp->n_relax = (int)v[2], rp->work = (int)v[3];
    rp->tangent = (int)v[4], rp->contacts = (int)v[5], rp->particles = (int)v[6];
}

/* the first failure of a point's call is the one reported */
static void gk__ts_fail(gk__tspt *pt, gk_twoscale_point *rp, gk_result res) {
    if (rp->code) return;
    rp->code = (int)res;
    gk_err_set(&pt->err, res, "%s", gk_rve_error(&pt->rve));
}

/* one point's call: perturbed runs (eq 8) first when their step count is known beforehand (strain
 * rule, no reuse test); the trial run; the tangent (reused, homogenised, or eq 8 after the trial run,
 * which is then re-run to leave the trial state). Out: rec = stress[9], D[nd4] (want_D), report. */
static void gk__ts_point(const gk_twoscale *ts, gk__tspt *pt, const double H[9], double scale, int want_D,
                         double *rec) {
    const gk_twoscale_def *d = &ts->def;
    int dim = ts->dim, nk = dim * dim, nd4 = ts->nd4, nd = 0, nr = 0, k, i, j, keys = 0, reuse = 0;
    int pert = want_D && d->tangent == GK_TWOSCALE_TANGENT_PERTURBATION;
    int before = pert && d->rule.kind == GK_TWOSCALE_STRAIN && !(d->reuse > 0);
    double *s_out = rec, *D = rec + 9, s0[9], sp[9][9];
    gk_twoscale_point rp;
    gk_result res;
    memset(&rp, 0, sizeof rp);
    gk_err_clear(&pt->err);
    memcpy(pt->dH, H, sizeof pt->dH);
    pt->trial_ok = 0;
    rp.particles = pt->rve.n;
    if (d->proc) {
        res = gk__ts_reset(pt, 1);
        if (!res) {
            pt->live = 0;
            res = d->proc(d->proc_user, pt->id, ts->pick[pt->id], &pt->rve, pt->H, H, scale, s0, &nd);
            if (!res && !gk_m3_isfinite(s0))
                res = gk_err_set(&pt->rve.err, GK_ERR_NAN, "the procedure's stress is not finite");
        }
        if (res) {
            gk__ts_fail(pt, &rp, res);
            goto failed;
        }
        rp.work = rp.n_deform = pt->steps_trial = nd;
        rp.contacts = pt->rve.ncontacts;
        memcpy(s_out, s0, sizeof s0);
        memcpy(pt->strial, s0, sizeof s0);
        pt->trial_ok = 1;
        gk__ts_put_rep(rec + 9, &rp);
        return;
    }
    if (before) {
        nd = gk__ts_strain_steps(&d->rule, scale, H);
        for (k = 0; k < nk; ++k) {
            double Hp[9];
            memcpy(Hp, H, sizeof Hp);
            Hp[3 * (k / dim) + k % dim] += d->xi;
            res = gk__ts_reset(pt, 1);
            if (!res) pt->live = 0, res = gk_rve_deform(&pt->rve, Hp, nd);
            if (res) gk__ts_fail(pt, &rp, res);
            gk_rve_stress(&pt->rve, sp[k]);
            rp.work += nd;
        }
    }
    res = gk__ts_reset(pt, 1);
    if (!res) res = gk__ts_trial(ts, pt, H, scale, &nd, &nr);
    if (res) {
        gk__ts_fail(pt, &rp, res);
        goto failed;
    }
    rp.work += nd + nr, rp.n_deform = nd, rp.n_relax = nr;
    pt->steps_trial = nd + nr;
    gk_rve_stress(&pt->rve, s0);
    memcpy(s_out, s0, sizeof s0);
    rp.contacts = pt->rve.ncontacts;
    if (want_D) {
        if (d->reuse > 0) {
            keys = gk__ts_keys(&d->alloc, pt) >= 0;
            if (!keys)
                pt->valid = 0; /* out of memory: no reuse at this point */
            else if (pt->valid && gk__ts_change(pt) < d->reuse)
                reuse = 1;
        }
        if (reuse) {
            memcpy(D, pt->Dref, (size_t)nd4 * sizeof(double));
            rp.tangent = 2;
        } else {
            rp.tangent = 1;
            if (pert) {
                if (!before) {
                    for (k = 0; k < nk; ++k) {
                        double Hp[9];
                        memcpy(Hp, H, sizeof Hp);
                        Hp[3 * (k / dim) + k % dim] += d->xi;
                        res = gk__ts_reset(pt, 1);
                        if (!res) res = gk__ts_replay(pt, Hp, nd, nr, d->rule.every);
                        if (res) gk__ts_fail(pt, &rp, res);
                        gk_rve_stress(&pt->rve, sp[k]);
                        rp.work += nd + nr;
                    }
                    res = gk__ts_reset(pt, 1); /* the trial state again (the same run: bit-identical) */
                    if (!res) res = gk__ts_replay(pt, H, nd, nr, d->rule.every);
                    if (res) {
                        gk__ts_fail(pt, &rp, res);
                        goto failed;
                    }
                    rp.work += nd + nr;
                }
                for (i = 0; i < dim; ++i)
                    for (j = 0; j < dim; ++j)
                        for (k = 0; k < nk; ++k) /* k = dim kk + ll */
                            D[(i * dim + j) * nk + k] = (sp[k][3 * i + j] - s0[3 * i + j]) / d->xi;
            } else if ((res = gk_homog_tangent(&pt->rve, d->tangent_opts, D)) != GK_OK)
                gk__ts_fail(pt, &rp, res);
            if (keys && !rp.code) { /* this tangent and its network become the reference */
                unsigned long long *t = pt->key;
                memcpy(pt->Dref, D, (size_t)nd4 * sizeof(double));
                pt->key = pt->cur, pt->cur = t, pt->nkey = pt->ncur;
                pt->valid = 1;
            }
        }
    }
    if (!rp.code) {
        pt->trial_ok = 1;
        gk__ts_put_rep(rec + 9 + (want_D ? nd4 : 0), &rp);
        return;
    }
failed: /* its accepted stress, a zero tangent */
    rp.tangent = 0;
    memcpy(s_out, pt->sacc, sizeof pt->sacc);
    if (want_D) memset(D, 0, (size_t)nd4 * sizeof(double));
    gk__ts_put_rep(rec + 9 + (want_D ? nd4 : 0), &rp);
}

/* ------------------------------------------------------------ create / destroy */
static void gk__ts_free_all(gk_twoscale *ts) {
    const gk_allocator *a = &ts->def.alloc;
    int k;
    if (ts->pt)
        for (k = 0; k < ts->nlocal; ++k) gk__ts_pt_free(ts, ts->pt[k]);
    if (ts->pk)
        for (k = 0; k < ts->nproto; ++k) gk_packing_free(&ts->pk[k]);
    gk_free(a, ts->pk), gk_free(a, ts->pick), gk_free(a, ts->owner), gk_free(a, ts->slot);
    gk_free(a, ts->order), gk_free(a, ts->counts), gk_free(a, ts->displs), gk_free(a, ts->pt);
    gk_free(a, ts->last), gk_free(a, ts->fail_id), gk_free(a, ts->fail_msg);
    gk_free(a, ts->buf), gk_free(a, ts->buf2), gk_free(a, ts->hbuf);
    ts->pk = NULL, ts->pick = ts->owner = ts->slot = ts->order = ts->counts = ts->displs = NULL;
    ts->pt = NULL, ts->last = NULL, ts->fail_id = NULL, ts->fail_msg = NULL;
    ts->buf = ts->buf2 = ts->hbuf = NULL;
    ts->bufcap = ts->buf2cap = 0;
    ts->nlocal = ts->nfail = ts->nproto = 0;
}

GKDEF void gk_twoscale_destroy(gk_twoscale *ts) {
    gk__ts_free_all(ts);
    ts->n = 0;
}

/* the definition with its defaults, or a message naming what is out of range */
static gk_result gk__ts_check(gk_twoscale *ts, const gk_twoscale_def *def, gk_twoscale_def *d) {
    gk_err *e = &ts->err;
    gk_twoscale_rule *r = &d->rule;
    int k, dim = 0;
    if (!def) return gk_err_set(e, GK_ERR_ARG, "no gk_twoscale_def given");
    *d = *def;
    if (d->npoints < 1 || d->npoints > (1 << 26))
        return gk_err_set(e, GK_ERR_ARG, "npoints %d outside [1, 2^26]", d->npoints);
    if (!d->protos || d->nprotos < 1 || d->nprotos > 65536)
        return gk_err_set(e, GK_ERR_ARG, "nprotos %d outside [1, 65536] (or no protos given)", d->nprotos);
    for (k = 0; k < d->nprotos; ++k) {
        const gk_packing *pk = d->protos[k].packing;
        if (!pk || !pk->x || !pk->y || !pk->r || pk->n < 1)
            return gk_err_set(e, GK_ERR_ARG, "prototype %d has no packing", k);
        if (pk->dim != 2 && pk->dim != 3)
            return gk_err_set(e, GK_ERR_ARG, "prototype %d: packing dimension %d", k, pk->dim);
        if (k > 0 && pk->dim != dim)
            return gk_err_set(e, GK_ERR_ARG, "prototype %d is %dD, prototype 0 %dD: one dimension per set", k,
                              pk->dim, dim);
        dim = pk->dim;
        if (d->protos[k].state && (!d->protos[k].state->buf || d->protos[k].state->size == 0))
            return gk_err_set(e, GK_ERR_ARG, "prototype %d has an empty state", k);
    }
    if (d->pick)
        for (k = 0; k < d->npoints; ++k)
            if (d->pick[k] < 0 || d->pick[k] >= d->nprotos)
                return gk_err_set(e, GK_ERR_ARG, "pick[%d] = %d is not a prototype (0 .. %d)", k, d->pick[k],
                                  d->nprotos - 1);
    if (d->rve.cookie == 0) {
        gk_allocator al = d->rve.alloc;
        d->rve = gk_rve_def_default();
        d->rve.alloc = al;
    }
    if (r->kind != GK_TWOSCALE_ADAPTIVE && r->kind != GK_TWOSCALE_STRAIN)
        return gk_err_set(e, GK_ERR_ARG, "unknown DEM step rule %d", (int)r->kind);
    if (!(r->inertial_max >= 0 && isfinite(r->inertial_max)) ||
        !(r->unbalanced_max >= 0 && isfinite(r->unbalanced_max)) ||
        !(r->strain >= 0 && isfinite(r->strain)) || r->n_min < 0 || r->n_max < 0 || r->every < 0)
        return gk_err_set(
            e, GK_ERR_ARG,
            "DEM step rule: inertial_max %g, unbalanced_max %g, strain %g must be finite and >= 0; "
            "n_min %d, n_max %d, every %d >= 0",
            r->inertial_max, r->unbalanced_max, r->strain, r->n_min, r->n_max, r->every);
    if (r->inertial_max == 0) r->inertial_max = 5e-4;
    if (r->unbalanced_max == 0) r->unbalanced_max = 5e-3;
    if (r->strain == 0) r->strain = 1e-5;
    if (r->n_min == 0) r->n_min = 10;
    if (r->n_max == 0) r->n_max = 5000;
    if (r->every == 0) r->every = 20;
    if (r->n_min > r->n_max)
        return gk_err_set(e, GK_ERR_ARG, "DEM step rule: n_min %d exceeds n_max %d", r->n_min, r->n_max);
    if (d->tangent != GK_TWOSCALE_TANGENT_HOMOG && d->tangent != GK_TWOSCALE_TANGENT_PERTURBATION)
        return gk_err_set(e, GK_ERR_ARG, "unknown tangent kind %d", (int)d->tangent);
    if (!(d->xi >= 0 && isfinite(d->xi))) return gk_err_set(e, GK_ERR_ARG, "eq 8 perturbation xi %g", d->xi);
    if (d->xi == 0) d->xi = 5e-5;
    if (!(d->reuse >= 0 && d->reuse < 1))
        return gk_err_set(e, GK_ERR_ARG, "tangent reuse bound %g outside [0, 1)", d->reuse);
    if (d->threads < 0 || d->threads > 4096) return gk_err_set(e, GK_ERR_ARG, "threads %d", d->threads);
    if (d->threads == 0) d->threads = 1;
    if (!(d->balance_tol >= 0 && isfinite(d->balance_tol)))
        return gk_err_set(e, GK_ERR_ARG, "balance tolerance %g", d->balance_tol);
    if (d->balance_tol == 0) d->balance_tol = 0.05;
    if (d->balance != GK_TWOSCALE_BALANCE_ACCEPT && d->balance != GK_TWOSCALE_BALANCE_RUN)
        return gk_err_set(e, GK_ERR_ARG, "unknown balance rule %d", (int)d->balance);
    ts->dim = dim;
    return GK_OK;
}

static gk_result gk__ts_create(gk_twoscale *ts, const gk_twoscale_def *def) {
    gk_twoscale_def d;
    gk_rve_state *ps = NULL;
    const gk_allocator *a;
    gk_result res;
    int k, p, np, R = ts->nranks;
    double W = 0.0, cum = 0.0;
    res = gk__ts_check(ts, def, &d);
    if (res) return res;
    ts->def = d;
    ts->def.protos = NULL, ts->def.pick = NULL;
    a = &ts->def.alloc;
    ts->n = np = d.npoints;
    ts->nd4 = ts->dim * ts->dim * ts->dim * ts->dim;
    ts->nproto = d.nprotos;
    ts->pk = (gk_packing *)gk_alloc(a, (size_t)d.nprotos * sizeof *ts->pk);
    ps = (gk_rve_state *)gk_alloc(a, (size_t)d.nprotos * sizeof *ps);
    ts->pick = (int *)gk_alloc(a, (size_t)np * sizeof(int));
    ts->owner = (int *)gk_alloc(a, (size_t)np * sizeof(int));
    ts->slot = (int *)gk_alloc(a, (size_t)np * sizeof(int));
    ts->order = (int *)gk_alloc(a, (size_t)np * sizeof(int));
    ts->counts = (int *)gk_alloc(a, 2 * (size_t)R * sizeof(int));
    ts->displs = (int *)gk_alloc(a, 2 * (size_t)R * sizeof(int));
    ts->pt = (gk__tspt **)gk_alloc(a, (size_t)np * sizeof *ts->pt);
    ts->last = (gk_twoscale_point *)gk_alloc(a, (size_t)np * sizeof *ts->last);
    if (!ts->pk || !ps || !ts->pick || !ts->owner || !ts->slot || !ts->order || !ts->counts || !ts->displs ||
        !ts->pt || !ts->last) {
        gk_free(a, ps);
        ts->nproto = 0;
        return gk_err_set(&ts->err, GK_ERR_ALLOC, "out of memory for a set of %d points", np);
    }
    memset(ts->pk, 0, (size_t)d.nprotos * sizeof *ts->pk);
    memset(ts->last, 0, (size_t)np * sizeof *ts->last);
    for (k = 0; k < d.nprotos; ++k) gk_rve_state_init(&ps[k], a);
    /* the packings (copied), and each prototype's state: given, or the RVE as created, refreshed */
    for (k = 0; k < d.nprotos && !res; ++k) {
        const gk_packing *src = d.protos[k].packing;
        gk_packing *dst = &ts->pk[k];
        res = gk_packing_init(dst, src->dim, src->n, a, &ts->err);
        if (res) break;
        gk_m3_copy(src->h, dst->h);
        memcpy(dst->x, src->x, (size_t)src->n * sizeof(double));
        memcpy(dst->y, src->y, (size_t)src->n * sizeof(double));
        if (src->z) memcpy(dst->z, src->z, (size_t)src->n * sizeof(double));
        memcpy(dst->r, src->r, (size_t)src->n * sizeof(double));
        if (d.protos[k].state) {
            const gk_rve_state *st = d.protos[k].state;
            ps[k].buf = (unsigned char *)gk_alloc(a, st->size);
            if (!ps[k].buf)
                res = gk_err_set(&ts->err, GK_ERR_ALLOC, "out of memory for prototype %d", k);
            else
                memcpy(ps[k].buf, st->buf, st->size), ps[k].size = ps[k].cap = st->size;
        } else {
            gk_rve rve;
            res = gk_rve_create(&rve, &ts->def.rve, dst);
            if (res) {
                gk_err_set(&ts->err, res, "prototype %d: %s", k, gk_rve_error(&rve));
                break;
            }
            res = gk_rve_refresh(&rve);
            if (!res) res = gk_rve_state_save(&ps[k], &rve);
            if (res) gk_err_set(&ts->err, res, "prototype %d: %s", k, gk_rve_error(&rve));
            gk_rve_destroy(&rve);
        }
    }
    ts->nproto = d.nprotos;
    if (!res) {
        if (d.pick)
            memcpy(ts->pick, d.pick, (size_t)np * sizeof(int));
        else
            gk_twoscale_draw(np, d.nprotos, d.seed, ts->pick);
        /* first assignment: contiguous ranges of about equal particle counts */
        for (p = 0; p < np; ++p) W += ts->pk[ts->pick[p]].n;
        for (p = 0; p < np; ++p) {
            double w = ts->pk[ts->pick[p]].n;
            int o = (int)((cum + 0.5 * w) * R / W);
            ts->owner[p] = o < R ? o : R - 1;
            cum += w;
        }
        gk__ts_layout(ts);
        for (k = 0; k < ts->nlocal; ++k) ts->pt[k] = NULL;
        for (k = 0, p = 0; p < np && !res; ++p) {
            int q = ts->pick[p];
            if (ts->slot[p] < 0) continue;
            res = gk__ts_pt_new(ts, p, q, ps[q].buf, ps[q].size, &ts->pt[k++]);
        }
    }
    for (k = 0; k < d.nprotos; ++k) gk_rve_state_free(&ps[k]);
    gk_free(a, ps);
    return res;
}

/* a failed creation leaves only its message */
static gk_result gk__ts_created(gk_twoscale *ts, gk_result res) {
    if (res) {
        gk_err e = ts->err;
        gk__ts_free_all(ts);
        ts->n = 0, ts->err = e;
    }
    return res;
}

GKDEF gk_result gk_twoscale_create(gk_twoscale *ts, const gk_twoscale_def *def) {
#ifdef GK_TWOSCALE_MPI
    return gk_twoscale_create_mpi(ts, def, MPI_COMM_WORLD);
#else
    memset(ts, 0, sizeof *ts);
    ts->nranks = 1;
    return gk__ts_created(ts, gk__ts_create(ts, def));
#endif
}

#ifdef GK_TWOSCALE_MPI
GKDEF gk_result gk_twoscale_create_mpi(gk_twoscale *ts, const gk_twoscale_def *def, MPI_Comm comm) {
    gk_result res;
    memset(ts, 0, sizeof *ts);
    ts->comm = comm;
    MPI_Comm_rank(comm, &ts->rank);
    MPI_Comm_size(comm, &ts->nranks);
    res = gk__ts_agree(ts, gk__ts_create(ts, def));
    if (!res && ts->nranks > 1 &&
        !(ts->hbuf = (double *)gk_alloc(&ts->def.alloc, ((size_t)ts->n * 9 + 2) * sizeof(double))))
        res = gk_err_set(&ts->err, GK_ERR_ALLOC, "out of memory for %d points' dH", ts->n);
    return gk__ts_created(ts, gk__ts_agree(ts, res));
}
#endif

/* ------------------------------------------------------------------- run */
/* failed points of the last run (reports in ts->last) with their messages, on every rank */
typedef struct gk__tsfail {
    int id;
    char msg[GK_ERR_MSG_LEN];
} gk__tsfail;
static int gk__ts_cmp_fail(const void *a, const void *b) {
    int x = ((const gk__tsfail *)a)->id, y = ((const gk__tsfail *)b)->id;
    return x < y ? -1 : x > y;
}
static gk_result gk__ts_failures(gk_twoscale *ts) {
    const gk_allocator *a = &ts->def.alloc;
    gk__tsfail *all, *mine;
    int p, j, nf = 0, nmine = 0, k;
    for (p = 0; p < ts->n; ++p) nf += ts->last[p].code != 0;
    gk_free(a, ts->fail_id), gk_free(a, ts->fail_msg);
    ts->fail_id = NULL, ts->fail_msg = NULL, ts->nfail = 0;
    if (!nf) return GK_OK;
    all = (gk__tsfail *)gk_alloc(a, (size_t)nf * sizeof *all);
    mine = (gk__tsfail *)gk_alloc(a, (size_t)nf * sizeof *mine);
    ts->fail_id = (int *)gk_alloc(a, (size_t)nf * sizeof(int));
    ts->fail_msg = (char *)gk_alloc(a, (size_t)nf * GK_ERR_MSG_LEN);
    if (!all || !mine || !ts->fail_id || !ts->fail_msg) { /* the codes are still in the reports */
        gk_free(a, all), gk_free(a, mine), gk_free(a, ts->fail_id), gk_free(a, ts->fail_msg);
        ts->fail_id = NULL, ts->fail_msg = NULL;
        return GK_ERR_ALLOC;
    }
    for (j = 0; j < ts->nlocal; ++j)
        if (ts->last[ts->pt[j]->id].code) {
            mine[nmine].id = ts->pt[j]->id;
            memcpy(mine[nmine++].msg, ts->pt[j]->err.msg, GK_ERR_MSG_LEN);
        }
#ifdef GK_TWOSCALE_MPI
    if (ts->nranks > 1) {
        int r, *cnt = ts->counts + ts->nranks, *dis = ts->displs + ts->nranks, off = 0;
        for (r = 0; r < ts->nranks; ++r) cnt[r] = 0;
        for (p = 0; p < ts->n; ++p) cnt[ts->owner[p]] += ts->last[p].code != 0;
        for (r = 0; r < ts->nranks; ++r) cnt[r] *= (int)sizeof(gk__tsfail), dis[r] = off, off += cnt[r];
        MPI_Allgatherv(mine, nmine * (int)sizeof(gk__tsfail), MPI_BYTE, all, cnt, dis, MPI_BYTE, ts->comm);
        ++ts->stats.collectives;
        ts->stats.bytes_out += (long long)nmine * (long long)sizeof(gk__tsfail);
        ts->stats.bytes_in += (long long)(nf - nmine) * (long long)sizeof(gk__tsfail);
    } else
#endif
        memcpy(all, mine, (size_t)nf * sizeof *all);
    qsort(all, (size_t)nf, sizeof *all, gk__ts_cmp_fail);
    for (k = 0; k < nf; ++k) {
        ts->fail_id[k] = all[k].id;
        memcpy(ts->fail_msg + (size_t)k * GK_ERR_MSG_LEN, all[k].msg, GK_ERR_MSG_LEN);
        ts->fail_msg[(size_t)k * GK_ERR_MSG_LEN + GK_ERR_MSG_LEN - 1] = 0;
    }
    ts->nfail = nf;
    gk_free(a, all), gk_free(a, mine);
    return GK_OK;
}

GKDEF const gk_twoscale_point *gk_twoscale_points(const gk_twoscale *ts) { return ts->last; }

GKDEF const char *gk_twoscale_point_error(const gk_twoscale *ts, int p) {
    int k;
    for (k = 0; k < ts->nfail; ++k)
        if (ts->fail_id[k] == p) return ts->fail_msg + (size_t)k * GK_ERR_MSG_LEN;
    return "";
}

/* dH of every point: finite, and in 2D without out-of-plane entries */
static gk_result gk__ts_check_dH(gk_twoscale *ts, const double *dH) {
    int p, k;
    if (!dH) return gk_err_set(&ts->err, GK_ERR_ARG, "no dH given");
    for (p = 0; p < ts->n; ++p)
        for (k = 0; k < 9; ++k) {
            double v = dH[9 * (size_t)p + k];
            if (!isfinite(v))
                return gk_err_set(&ts->err, GK_ERR_NAN, "dH of point %d has %g at (%d, %d)", p, v, k / 3,
                                  k % 3);
            if (ts->dim == 2 && v != 0.0 && (k == 2 || k >= 5))
                return gk_err_set(&ts->err, GK_ERR_ARG,
                                  "dH of point %d has %g at (%d, %d): a 2D set takes the in-plane block only",
                                  p, v, k / 3, k % 3);
        }
    return GK_OK;
}

#ifdef GK_TWOSCALE_MPI
static gk_result gk__ts_balance(gk_twoscale *ts);
#endif

GKDEF gk_result gk_twoscale_run(gk_twoscale *ts, const double *dH, const gk_twoscale_run_def *rd,
                                double *stress, double *D) {
    double scale = rd && rd->scale != 0.0 ? rd->scale : 1.0;
    const double *H = dH, *all;
    int want_D = D != NULL, nrec, j, nf;
    long long bin = ts->stats.bytes_in, bout = ts->stats.bytes_out;
    gk_result res;
    gk_err_clear(&ts->err);
    if (ts->n < 1) return gk_err_set(&ts->err, GK_ERR_STATE, "the set was not created");
#ifdef GK_TWOSCALE_MPI
    if (ts->nranks > 1) { /* rank 0's call: its dH, whether it wants D, its scale */
        double *hb = ts->hbuf;
        hb[0] = want_D, hb[1] = scale;
        if (ts->rank == 0) {
            if (dH)
                memcpy(hb + 2, dH, (size_t)ts->n * 9 * sizeof(double));
            else
                hb[0] = -1.0;
        }
        MPI_Bcast(hb, ts->n * 9 + 2, MPI_DOUBLE, 0, ts->comm);
        ++ts->stats.collectives;
        if (ts->rank == 0)
            ts->stats.bytes_out += ((long long)ts->n * 9 + 2) * 8;
        else
            ts->stats.bytes_in += ((long long)ts->n * 9 + 2) * 8;
        want_D = hb[0] > 0, scale = hb[1], H = hb[0] < 0 ? NULL : hb + 2;
    }
#endif
    if (!(scale > 0.0 && scale <= 1.0))
        return gk_err_set(&ts->err, GK_ERR_ARG, "run scale %g outside (0, 1]", scale);
    if (want_D && ts->def.proc)
        return gk_err_set(&ts->err, GK_ERR_ARG,
                          "a set run by the caller's procedure has no tangent: D must be NULL");
    if ((res = gk__ts_check_dH(ts, H)) != GK_OK) return res;
    nrec = 9 + (want_D ? ts->nd4 : 0) + GK__TS_NREP;
    if (gk__ts_agree(ts, gk__ts_bufs(ts, nrec))) return ts->err.code;
#ifdef GK_TWOSCALE_MPI
    /* GK_TWOSCALE_BALANCE_RUN: the accepted states move by the costs of the previous run (the trial
     * states of a pending run are dropped: this run recomputes every point from its accepted state).
     * Here, after every check, so that a run that moves points always runs. A failed move changes
     * nothing: this run on the old assignment. */
    if (ts->nranks > 1 && ts->def.balance == GK_TWOSCALE_BALANCE_RUN && ts->stats.runs > 0 &&
        gk__ts_balance(ts))
        gk_err_clear(&ts->err);
#endif
    {
        int nth = ts->def.threads;
        GK_OMP(parallel for num_threads(nth) schedule(dynamic, 1))
        for (j = 0; j < ts->nlocal; ++j)
            gk__ts_point(ts, ts->pt[j], H + 9 * (size_t)ts->pt[j]->id, scale, want_D,
                         ts->buf + (size_t)nrec * j);
        (void)nth;
    }
    all = gk__ts_gather(ts, nrec);
    for (j = 0; j < ts->n; ++j) {
        int p = ts->order[j];
        const double *rec = all + (size_t)nrec * j;
        if (stress) memcpy(stress + 9 * (size_t)p, rec, 9 * sizeof(double));
        if (want_D && D) memcpy(D + (size_t)ts->nd4 * p, rec + 9, (size_t)ts->nd4 * sizeof(double));
        gk__ts_get_rep(rec + 9 + (want_D ? ts->nd4 : 0), &ts->last[p]);
    }
    ++ts->stats.runs;
    ts->pending = 1;
    res = gk__ts_failures(ts);
    ts->stats.run_bytes_in += ts->stats.bytes_in - bin, ts->stats.run_bytes_out += ts->stats.bytes_out - bout;
    for (nf = 0, j = 0; j < ts->n; ++j) nf += ts->last[j].code != 0;
    if (!nf) return GK_OK;
    {
        int first = -1, k, len;
        for (j = 0; j < ts->n && first < 0; ++j)
            if (ts->last[j].code) first = j;
        len = snprintf(
            ts->err.msg, sizeof ts->err.msg, "%d of %d points failed; point %d: %s", nf, ts->n, first,
            res ? gk_result_string((gk_result)ts->last[first].code) : gk_twoscale_point_error(ts, first));
        for (k = 0, j = first + 1; j < ts->n && len > 0 && len < (int)sizeof ts->err.msg - 16; ++j)
            if (ts->last[j].code) {
                if (k == 8) {
                    len += snprintf(ts->err.msg + len, sizeof ts->err.msg - len, ", ...");
                    break;
                }
                len += snprintf(ts->err.msg + len, sizeof ts->err.msg - len, "%s%d",
                                k ? ", " : " (also points ", j);
                ++k;
            }
        if (k > 0 && len > 0 && len < (int)sizeof ts->err.msg - 2)
            snprintf(ts->err.msg + len, sizeof ts->err.msg - len, ")");
        ts->err.code = GK_ERR_STATE;
    }
    return GK_ERR_STATE;
}

GKDEF void gk_twoscale_reject(gk_twoscale *ts) {
    int j;
    for (j = 0; j < ts->nlocal; ++j) ts->pt[j]->trial_ok = 0;
    ts->pending = 0;
}

/* ------------------------------------------------ point records (checkpoint, migration) */
/* int32 id, prototype, DEM steps of the last accepted run, reference keys (-1: no tangent reference);
 * double H[9], accepted stress[9]; [reference tangent (nd4 doubles), keys (uint64)]; uint64 state size;
 * the accepted state */
typedef void (*gk__ts_sink)(void *ctx, const void *p, size_t n);
#define GK__TS_REC_MIN (4 * 4 + 18 * 8 + 8)

static int gk__ts_has_ref(const gk__tspt *pt) { return pt->Dref && pt->valid; }

static size_t gk__ts_rec_size(const gk_twoscale *ts, const gk__tspt *pt) {
    size_t s = GK__TS_REC_MIN + pt->acc.size;
    if (gk__ts_has_ref(pt)) s += (size_t)ts->nd4 * 8 + (size_t)pt->nkey * 8;
    return s;
}

static void gk__ts_rec_emit(const gk_twoscale *ts, const gk__tspt *pt, gk__ts_sink put, void *ctx) {
    int32_t v[4];
    uint64_t ss = pt->acc.size;
    v[0] = pt->id, v[1] = ts->pick[pt->id], v[2] = pt->steps_acc, v[3] = gk__ts_has_ref(pt) ? pt->nkey : -1;
    put(ctx, v, sizeof v);
    put(ctx, pt->H, sizeof pt->H);
    put(ctx, pt->sacc, sizeof pt->sacc);
    if (v[3] >= 0) {
        put(ctx, pt->Dref, (size_t)ts->nd4 * sizeof(double));
        put(ctx, pt->key, (size_t)pt->nkey * sizeof *pt->key);
    }
    put(ctx, &ss, sizeof ss);
    put(ctx, pt->acc.buf, pt->acc.size);
}

/* a new point from the record of point id (b, n bytes): every size and value checked first */
static gk_result gk__ts_rec_parse(gk_twoscale *ts, int id, const unsigned char *b, size_t n, gk__tspt **out) {
    int32_t v[4];
    uint64_t ss;
    double H[9], S[9];
    size_t off = 4 * 4 + 18 * 8, ref;
    gk__tspt *pt;
    gk_result res;
    int k;
    *out = NULL;
    if (!b || n < GK__TS_REC_MIN)
        return gk_err_set(&ts->err, GK_ERR_FORMAT, "the record of point %d is %lu bytes", id,
                          (unsigned long)n);
    memcpy(v, b, sizeof v);
    memcpy(H, b + 16, sizeof H);
    memcpy(S, b + 16 + sizeof H, sizeof S);
    if (v[0] != id || v[1] != ts->pick[id] || v[2] < 0 || v[3] < -1 || v[3] > GK__TS_MAXKEYS)
        return gk_err_set(
            &ts->err, GK_ERR_FORMAT,
            "the record of point %d names point %d, prototype %d (expected %d), %d DEM steps, %d "
            "contact keys",
            id, (int)v[0], (int)v[1], ts->pick[id], (int)v[2], (int)v[3]);
    for (k = 0; k < 9; ++k) /* finite, and small enough for the fields' squares (eps_q, q) to stay finite */
        if (!(fabs(H[k]) <= 1e6) || !(fabs(S[k]) <= 1e100))
            return gk_err_set(
                &ts->err, GK_ERR_FORMAT,
                "the record of point %d has a NaN or impossible accumulated dH (|H| > 1e6) or stress "
                "(|sigma| > 1e100 Pa)",
                id);
    ref = v[3] >= 0 ? (size_t)ts->nd4 * 8 + (size_t)v[3] * 8 : 0;
    if (ref > n - GK__TS_REC_MIN)
        return gk_err_set(&ts->err, GK_ERR_FORMAT,
                          "the record of point %d is shorter than its %d contact keys", id, (int)v[3]);
    if (v[3] >=
        0) { /* the reference: a finite tangent, keys as gk__ts_keys makes them (sorted, ids i <= j) */
        unsigned long long key, prev = 0, lo, hi;
        double d;
        for (k = 0; k < ts->nd4; ++k) {
            memcpy(&d, b + off + (size_t)k * 8, 8);
            if (!isfinite(d))
                return gk_err_set(&ts->err, GK_ERR_FORMAT,
                                  "the record of point %d has a NaN reference tangent", id);
        }
        for (k = 0; k < v[3]; ++k, prev = key) {
            memcpy(&key, b + off + (size_t)ts->nd4 * 8 + (size_t)k * 8, 8);
            lo = key >> 33, hi = (key >> 1) & 0xffffffffu;
            if (key < prev || lo > hi || hi > 0x7fffffffu)
                return gk_err_set(
                    &ts->err, GK_ERR_FORMAT,
                    "the record of point %d: contact key %d is out of order or not a particle pair", id, k);
        }
    }
    memcpy(&ss, b + off + ref, sizeof ss);
    if (ss != n - GK__TS_REC_MIN - ref)
        return gk_err_set(&ts->err, GK_ERR_FORMAT,
                          "the record of point %d holds a state of %llu bytes in %lu", id,
                          (unsigned long long)ss, (unsigned long)(n - GK__TS_REC_MIN - ref));
    res = gk__ts_pt_new(ts, id, v[1], b + off + ref + 8, (size_t)ss, &pt);
    if (res) return res;
    memcpy(pt->H, H, sizeof H);
    memcpy(pt->sacc, S, sizeof S);
    pt->steps_acc = v[2];
    if (v[3] >= 0 && pt->Dref) { /* without reuse in this set the reference is not needed */
        if (gk__ts_reserve_keys(&ts->def.alloc, pt, v[3] + 1)) {
            gk__ts_pt_free(ts, pt);
            return gk_err_set(&ts->err, GK_ERR_ALLOC, "out of memory for point %d's contact keys", id);
        }
        memcpy(pt->Dref, b + off, (size_t)ts->nd4 * 8);
        memcpy(pt->key, b + off + (size_t)ts->nd4 * 8, (size_t)v[3] * 8);
        pt->nkey = v[3], pt->valid = 1;
    }
    *out = pt;
    return GK_OK;
}

#ifdef GK_TWOSCALE_MPI
static void gk__ts_bsink(void *ctx, const void *p, size_t n) {
    unsigned char **o = (unsigned char **)ctx;
    if (n) memcpy(*o, p, n);
    *o += n;
}

/* a local point's record in a buffer of the set's allocator (NULL: out of memory) */
static unsigned char *gk__ts_rec_pack(const gk_twoscale *ts, const gk__tspt *pt, size_t *n) {
    unsigned char *b, *o;
    *n = gk__ts_rec_size(ts, pt);
    b = (unsigned char *)gk_alloc(&ts->def.alloc, *n);
    if (!b) return NULL;
    o = b;
    gk__ts_rec_emit(ts, pt, gk__ts_bsink, &o);
    return b;
}

static int gk__ts_cmp_pt(const void *a, const void *b) {
    int x = (*(gk__tspt *const *)a)->id, y = (*(gk__tspt *const *)b)->id;
    return x < y ? -1 : x > y;
}

/* point to point, in three messages (size, the receiver's go, payload) so that either side may fail
 * (out of memory) without leaving the other blocked; a size of ~0 says the sender failed */
static int gk__ts_xsend(gk_twoscale *ts, int to, const void *b, unsigned long long n) {
    int go = 0;
    if (!b) n = ~0ull;
    MPI_Send(&n, 8, MPI_BYTE, to, 31, ts->comm);
    MPI_Recv(&go, 1, MPI_INT, to, 32, ts->comm, MPI_STATUS_IGNORE);
    if (go) {
        MPI_Send((void *)b, (int)n, MPI_BYTE, to, 33, ts->comm);
        ts->stats.bytes_out += (long long)n;
    }
    return go;
}
static int gk__ts_xrecv(gk_twoscale *ts, int from, unsigned char **buf, size_t *cap, unsigned long long *n,
                        int want) {
    int go;
    MPI_Recv(n, 8, MPI_BYTE, from, 31, ts->comm, MPI_STATUS_IGNORE);
    go = want && *n < ((unsigned long long)1 << 31);
    if (go && *n + 1 > *cap) {
        go = gk_realloc(&ts->def.alloc, (void **)buf, 0, (size_t)*n + 1, 1) == GK_OK;
        if (go) *cap = (size_t)*n + 1;
    }
    MPI_Send(&go, 1, MPI_INT, from, 32, ts->comm);
    if (go) {
        MPI_Recv(*buf, (int)*n, MPI_BYTE, from, 33, ts->comm, MPI_STATUS_IGNORE);
        ts->stats.bytes_in += (long long)*n;
    }
    return go;
}

/* move the points whose owner changes to nown[]: their records pass in point order (each transfer
 * involves two ranks and every rank walks the same order, so the lowest pending transfer always has
 * both sides at it: no deadlock); the incoming points are built first, and only when every rank has
 * all of its own does any rank drop its outgoing ones */
static gk_result gk__ts_migrate(gk_twoscale *ts, const int *nown) {
    const gk_allocator *a = &ts->def.alloc;
    int p, nin = 0, k = 0, ok = 1, moved = 0, j, nl;
    gk__tspt **in;
    unsigned char *rb = NULL;
    size_t rcap = 0;
    long long sent = ts->stats.bytes_out, all;
    for (p = 0; p < ts->n; ++p) {
        nin += ts->owner[p] != ts->rank && nown[p] == ts->rank;
        moved += ts->owner[p] != nown[p];
    }
    in = (gk__tspt **)gk_alloc(a, ((size_t)nin + 1) * sizeof *in);
    if (!gk__ts_allok(ts, in != NULL)) {
        gk_free(a, in);
        return gk_err_set(&ts->err, GK_ERR_ALLOC, "out of memory to rebalance");
    }
    for (p = 0; p < ts->n; ++p) {
        if (ts->owner[p] == nown[p]) continue;
        if (ts->owner[p] == ts->rank) {
            size_t n = 0;
            gk__tspt *q = ts->pt[ts->slot[p]];
            unsigned char *b = gk__ts_sync(q) ? NULL : gk__ts_rec_pack(ts, q, &n);
            ok &= gk__ts_xsend(ts, nown[p], b, n);
            gk_free(a, b);
        } else if (nown[p] == ts->rank) {
            unsigned long long n;
            in[k] = NULL;
            if (gk__ts_xrecv(ts, ts->owner[p], &rb, &rcap, &n, ok) && ok)
                ok = gk__ts_rec_parse(ts, p, rb, (size_t)n, &in[k]) == GK_OK;
            else
                ok = 0;
            ++k;
        }
    }
    gk_free(a, rb);
    if (!gk__ts_allok(ts, ok)) { /* nothing changes */
        for (j = 0; j < k; ++j) gk__ts_pt_free(ts, in[j]);
        gk_free(a, in);
        return gk_err_set(&ts->err, GK_ERR_ALLOC, "a point could not move to another rank: no rebalance");
    }
    for (nl = 0, j = 0; j < ts->nlocal; ++j)
        if (nown[ts->pt[j]->id] == ts->rank)
            ts->pt[nl++] = ts->pt[j];
        else
            gk__ts_pt_free(ts, ts->pt[j]);
    for (j = 0; j < k; ++j) ts->pt[nl++] = in[j];
    qsort(ts->pt, (size_t)nl, sizeof *ts->pt, gk__ts_cmp_pt);
    gk_free(a, in);
    memcpy(ts->owner, nown, (size_t)ts->n * sizeof(int));
    gk__ts_layout(ts);
    sent = ts->stats.bytes_out - sent;
    MPI_Allreduce(&sent, &all, 1, MPI_LONG_LONG, MPI_SUM, ts->comm);
    ++ts->stats.collectives;
    ts->stats.migrated += moved, ts->stats.migrated_bytes += all, ++ts->stats.balances;
    return GK_OK;
}

/* the cost of the last run per rank; when the most loaded is above (1 + tol) x the mean, moves from
 * the most to the least loaded rank (the point whose cost is nearest half their gap, lowest index on
 * ties) until it is not; the same decision on every rank (the reports are everywhere) */
static gk_result gk__ts_balance(gk_twoscale *ts) {
    const gk_allocator *a = &ts->def.alloc;
    int R = ts->nranks, p, r, it, *nown;
    double *L, *cost, mean = 0.0;
    gk_result res = GK_OK;
    L = (double *)gk_alloc(a, (size_t)R * sizeof *L);
    cost = (double *)gk_alloc(a, (size_t)ts->n * sizeof *cost);
    nown = (int *)gk_alloc(a, (size_t)ts->n * sizeof *nown);
    if (!gk__ts_allok(ts, L && cost && nown)) { /* no room on some rank: no rebalance this time */
        gk_free(a, L), gk_free(a, cost), gk_free(a, nown);
        return GK_OK;
    }
    for (r = 0; r < R; ++r) L[r] = 0.0;
    for (p = 0; p < ts->n; ++p) {
        cost[p] = ((double)ts->last[p].work + 1.0) * (double)ts->last[p].particles;
        L[ts->owner[p]] += cost[p];
        mean += cost[p];
        nown[p] = ts->owner[p];
    }
    mean /= R;
    for (it = 0; it < ts->n; ++it) {
        int rmax = 0, rmin = 0, best = -1;
        double gap, bestv = -1.0;
        for (r = 1; r < R; ++r) {
            if (L[r] > L[rmax]) rmax = r;
            if (L[r] < L[rmin]) rmin = r;
        }
        if (L[rmax] <= (1.0 + ts->def.balance_tol) * mean) break;
        gap = L[rmax] - L[rmin];
        for (p = 0; p < ts->n; ++p)
            if (nown[p] == rmax && cost[p] < gap) {
                double v = cost[p] < gap - cost[p] ? cost[p] : gap - cost[p];
                if (v > bestv) bestv = v, best = p;
            }
        if (best < 0) break;
        nown[best] = rmin, L[rmax] -= cost[best], L[rmin] += cost[best];
    }
    for (p = 0; p < ts->n && nown[p] == ts->owner[p]; ++p) continue;
    if (p < ts->n) res = gk__ts_migrate(ts, nown);
    gk_free(a, L), gk_free(a, cost), gk_free(a, nown);
    return res;
}
#endif

GKDEF gk_result gk_twoscale_accept(gk_twoscale *ts) {
    int j;
    gk_err_clear(&ts->err);
    if (!ts->pending) return gk_err_set(&ts->err, GK_ERR_STATE, "no run to accept (gk_twoscale_run first)");
    /* no copy of the state here: the next change of the RVE copies it (gk__ts_reset) */
    GK_OMP(parallel for num_threads(ts->def.threads) schedule(dynamic, 16))
    for (j = 0; j < ts->nlocal; ++j) {
        gk__tspt *pt = ts->pt[j];
        int k;
        if (!pt->trial_ok) continue;
        for (k = 0; k < 9; ++k) pt->H[k] += pt->dH[k];
        pt->steps_acc = pt->steps_trial;
        if (ts->def.proc)
            memcpy(pt->sacc, pt->strial, sizeof pt->sacc);
        else
            gk_rve_stress(&pt->rve, pt->sacc);
        pt->live = 1, pt->stale = 1, pt->trial_ok = 0;
    }
    ts->pending = 0;
#ifdef GK_TWOSCALE_MPI
    if (ts->nranks > 1 && ts->def.balance == GK_TWOSCALE_BALANCE_ACCEPT) return gk__ts_balance(ts);
#endif
    return GK_OK;
}

/* ------------------------------------------------------- accepted state, fields */
/* every local point at its accepted state through fill(ts, pt, rec) (nrec doubles, the last one the
 * point's code), gathered; the first failing point named */
typedef gk_result (*gk__ts_fill)(const gk_twoscale *ts, gk__tspt *pt, int want_D, double *rec);

static const double *gk__ts_collect(gk_twoscale *ts, int nrec, int want_D, gk__ts_fill fill) {
    const double *all;
    int j, nth = ts->def.threads;
    gk_err_clear(&ts->err);
    if (ts->n < 1) return gk_err_set(&ts->err, GK_ERR_STATE, "the set was not created"), (const double *)NULL;
    if (ts->pending)
        return gk_err_set(&ts->err, GK_ERR_STATE, "a run is pending: accept or reject it first"),
               (const double *)NULL;
    if (gk__ts_agree(ts, gk__ts_bufs(ts, nrec))) return NULL;
    GK_OMP(parallel for num_threads(nth) schedule(dynamic, 1))
    for (j = 0; j < ts->nlocal; ++j) {
        gk__tspt *pt = ts->pt[j];
        double *rec = ts->buf + (size_t)nrec * j;
        gk_result res = gk__ts_reset(pt, 0);
        if (!res) res = fill(ts, pt, want_D, rec);
        rec[nrec - 1] = (double)res;
    }
    (void)nth;
    all = gk__ts_gather(ts, nrec);
    for (j = 0; j < ts->n; ++j)
        if (all[(size_t)nrec * j + nrec - 1] != 0.0) {
            gk_err_set(&ts->err, (gk_result)(int)all[(size_t)nrec * j + nrec - 1], "point %d: %s",
                       ts->order[j], gk_result_string((gk_result)(int)all[(size_t)nrec * j + nrec - 1]));
            return NULL;
        }
    return all;
}

static gk_result gk__ts_fill_acc(const gk_twoscale *ts, gk__tspt *pt, int want_D, double *rec) {
    if (ts->def.proc) {
        memcpy(rec, pt->sacc, sizeof pt->sacc);
        return GK_OK;
    }
    gk_rve_stress(&pt->rve, rec);
    return want_D ? gk_homog_tangent(&pt->rve, ts->def.tangent_opts, rec + 9) : GK_OK;
}

GKDEF gk_result gk_twoscale_accepted(gk_twoscale *ts, double *stress, double *D) {
    int want_D = D != NULL, nrec, j;
    const double *all;
#ifdef GK_TWOSCALE_MPI
    if (ts->nranks > 1) {
        MPI_Bcast(&want_D, 1, MPI_INT, 0, ts->comm);
        ++ts->stats.collectives;
    }
#endif
    if (want_D && ts->def.proc)
        return gk_err_set(&ts->err, GK_ERR_ARG,
                          "a set run by the caller's procedure has no tangent: D must be NULL");
    nrec = 9 + (want_D ? ts->nd4 : 0) + 1;
    if (!(all = gk__ts_collect(ts, nrec, want_D, gk__ts_fill_acc))) return ts->err.code;
    for (j = 0; j < ts->n; ++j) {
        int p = ts->order[j];
        if (stress) memcpy(stress + 9 * (size_t)p, all + (size_t)nrec * j, 9 * sizeof(double));
        if (want_D && D)
            memcpy(D + (size_t)ts->nd4 * p, all + (size_t)nrec * j + 9, (size_t)ts->nd4 * sizeof(double));
    }
    return GK_OK;
}

static gk_result gk__ts_fill_field(const gk_twoscale *ts, gk__tspt *pt, int want_D, double *rec) {
    const gk_rve *r = &pt->rve;
    gk_twoscale_field f;
    double eps[9], F[9], phi[9], Fa[9];
    int k, dim = ts->dim;
    (void)want_D;
    for (k = 0; k < 9; ++k) eps[k] = 0.5 * (pt->H[k] + pt->H[3 * (k % 3) + k / 3]);
    gk_m3_identity(F);
    for (k = 0; k < 9; ++k) F[k] += pt->H[k];
    if (ts->def.proc)
        memcpy(f.stress, pt->sacc, sizeof f.stress);
    else
        gk_rve_stress(r, f.stress);
    f.p = gk_stress_p(f.stress, dim);
    f.q = gk_stress_q(f.stress, dim);
    f.void_ratio = gk_homog_void_ratio(r);
    f.coordination = r->n > 0 ? 2.0 * r->ncontacts / r->n : 0.0;
    f.fabric = gk_homog_fabric(r, phi, Fa);
    f.rotation = gk_homog_mean_rotation(r);
    f.spin = gk_rotation_angle(F, dim);
    f.eps_v = gk_strain_v(eps, dim);
    f.eps_q = gk_strain_q(eps, dim);
    f.volume = gk_rve_volume(r);
    f.mass = r->mass_total;
    f.dem_steps = pt->steps_acc;
    f.contacts = r->ncontacts;
    gk_m3_copy(pt->H, f.H);
    memcpy(rec, &f, sizeof f);
    return GK_OK;
}

GKDEF gk_result gk_twoscale_fields(gk_twoscale *ts, gk_twoscale_field *f) {
    int nrec = GK__TS_NFIELD + 1, j;
    const double *all;
    if (!(all = gk__ts_collect(ts, nrec, 0, gk__ts_fill_field))) return ts->err.code;
    if (f)
        for (j = 0; j < ts->n; ++j) memcpy(&f[ts->order[j]], all + (size_t)nrec * j, sizeof *f);
    return GK_OK;
}

/* ------------------------------------------------------------ checkpoint */
/* a file read or written with a running 64-bit FNV-1a hash of every byte */
typedef struct gk__ckf {
    FILE *fp;
    uint64_t h;
    unsigned long long pos, size; /* bytes so far; the file's size (reading) */
    int bad;
} gk__ckf;

static void gk__ck_hash(uint64_t *h, const void *p, size_t n) {
    const unsigned char *b = (const unsigned char *)p;
    uint64_t x = *h;
    while (n--) {
        x ^= *b++;
        x *= UINT64_C(0x100000001b3);
    }
    *h = x;
}
static void gk__ck_put(void *ctx, const void *p, size_t n) {
    gk__ckf *c = (gk__ckf *)ctx;
    if (!n) return;
    gk__ck_hash(&c->h, p, n);
    if (!c->bad && fwrite(p, 1, n, c->fp) != n) c->bad = 1;
    c->pos += n;
}
/* n bytes into p (NULL: read and drop); 0, or 1 when the file ends first */
static int gk__ck_get(gk__ckf *c, void *p, unsigned long long n) {
    unsigned char tmp[4096];
    while (n > 0) {
        size_t m = p ? (size_t)n : (n < sizeof tmp ? (size_t)n : sizeof tmp);
        unsigned char *dst = p ? (unsigned char *)p : tmp;
        if (fread(dst, 1, m, c->fp) != m) return 1;
        gk__ck_hash(&c->h, dst, m);
        c->pos += m, n -= m;
        if (p) p = (void *)(dst + m);
    }
    return 0;
}

static void gk__ts_header(const gk_twoscale *ts, uint32_t hd[8]) {
    hd[0] = GK_TWOSCALE_CHECKPOINT_VERSION, hd[1] = 0x01020304u, hd[2] = (uint32_t)sizeof(gk_real);
    hd[3] = (uint32_t)ts->dim, hd[4] = (uint32_t)ts->n, hd[5] = (uint32_t)ts->nproto,
    hd[6] = (uint32_t)ts->nd4;
    hd[7] = 0;
}

GKDEF gk_result gk_twoscale_save(gk_twoscale *ts, const char *path, const void *block, size_t nblock) {
    const gk_allocator *a = &ts->def.alloc;
    gk__ckf c;
    char *tmp = NULL;
    int j, p;
    memset(&c, 0, sizeof c);
    c.h = UINT64_C(0xcbf29ce484222325);
    gk_err_clear(&ts->err);
    if (ts->n < 1) return gk_err_set(&ts->err, GK_ERR_STATE, "the set was not created");
    { /* the accepted states into the records' buffers (on the set's threads, as a run copies) */
        int ok = 1;
        GK_OMP(parallel for num_threads(ts->def.threads) schedule(dynamic, 4) reduction(& : ok))
        for (j = 0; j < ts->nlocal; ++j) ok &= gk__ts_sync(ts->pt[j]) == GK_OK;
        if (!gk__ts_allok(ts, ok))
            return gk_err_set(&ts->err, GK_ERR_ALLOC, "checkpoint: out of memory for the accepted states");
    }
    if (ts->rank == 0) {
        if (!path || (!block && nblock))
            gk_err_set(&ts->err, GK_ERR_ARG, "checkpoint: no path, or a driver block of %lu bytes at NULL",
                       (unsigned long)nblock);
        else if (!(tmp = (char *)gk_alloc(a, strlen(path) + 5)))
            gk_err_set(&ts->err, GK_ERR_ALLOC, "out of memory");
        else {
            sprintf(tmp, "%s.tmp", path);
            if (!(c.fp = fopen(tmp, "wb"))) gk_err_set(&ts->err, GK_ERR_IO, "cannot write %s", tmp);
        }
    }
    if (gk__ts_share_err(ts)) {
        gk_free(a, tmp);
        return ts->err.code;
    }
    if (ts->rank == 0) {
        uint32_t hd[8], u;
        uint64_t nb = nblock, sum;
        gk__ts_header(ts, hd);
        gk__ck_put(&c, GK__TS_MAGIC, 8);
        gk__ck_put(&c, hd, sizeof hd);
        for (j = 0; j < ts->nproto; ++j) u = (uint32_t)ts->pk[j].n, gk__ck_put(&c, &u, 4);
        for (p = 0; p < ts->n; ++p) u = (uint32_t)ts->pick[p], gk__ck_put(&c, &u, 4);
        for (p = 0; p < ts->n; ++p) {
            uint64_t n;
            if (ts->owner[p] == 0) {
                const gk__tspt *pt = ts->pt[ts->slot[p]];
                n = gk__ts_rec_size(ts, pt);
                gk__ck_put(&c, &n, 8);
                gk__ts_rec_emit(ts, pt, gk__ck_put, &c);
            }
#ifdef GK_TWOSCALE_MPI
            else {
                static const unsigned char zero[8] = {0, 0, 0, 0, 0, 0, 0, 0};
                unsigned char *rb = NULL;
                unsigned long long m;
                size_t cap = 0;
                if (gk__ts_xrecv(ts, ts->owner[p], &rb, &cap, &m, 1)) {
                    n = m;
                    gk__ck_put(&c, &n, 8);
                    gk__ck_put(&c, rb, (size_t)m);
                } else {
                    c.bad = 1;
                    gk__ck_put(&c, zero, 8);
                }
                gk_free(a, rb);
            }
#endif
        }
        gk__ck_put(&c, &nb, 8);
        gk__ck_put(&c, block, nblock);
        sum = c.h;
        gk__ck_put(&c, &sum, 8);
        if (fflush(c.fp) != 0) c.bad = 1;
        if (fclose(c.fp) != 0) c.bad = 1;
        if (c.bad || rename(tmp, path) != 0) {
            remove(tmp);
            gk_err_set(&ts->err, GK_ERR_IO, "cannot write %s", path);
        }
    }
#ifdef GK_TWOSCALE_MPI
    else
        for (j = 0; j < ts->nlocal; ++j) {
            size_t n;
            unsigned char *b = gk__ts_rec_pack(ts, ts->pt[j], &n);
            gk__ts_xsend(ts, 0, b, n);
            gk_free(a, b);
        }
#endif
    gk_free(a, tmp);
    return gk__ts_share_err(ts);
}

/* pass 1 (rank 0): the whole file against the set and its checksum; on success the file is open at
 * its first record, c->h reset */
static gk_result gk__ts_check_file(gk_twoscale *ts, const char *path, gk__ckf *c) {
    uint32_t hd[8], want[8], u;
    char magic[8];
    uint64_t n, sum;
    long end;
    int p, k;
    const unsigned long long tail = 16; /* block size and checksum */
    if (!(c->fp = fopen(path, "rb"))) return gk_err_set(&ts->err, GK_ERR_IO, "cannot open %s", path);
    if (fseek(c->fp, 0, SEEK_END) != 0 || (end = ftell(c->fp)) < 0 || fseek(c->fp, 0, SEEK_SET) != 0)
        return gk_err_set(&ts->err, GK_ERR_IO, "cannot read %s", path);
    c->size = (unsigned long long)end;
    c->h = UINT64_C(0xcbf29ce484222325), c->pos = 0;
    gk__ts_header(ts, want);
    if (gk__ck_get(c, magic, 8) || memcmp(magic, GK__TS_MAGIC, 8) != 0)
        return gk_err_set(&ts->err, GK_ERR_FORMAT, "%s is not a grainkit two-scale checkpoint", path);
    if (gk__ck_get(c, hd, sizeof hd))
        return gk_err_set(&ts->err, GK_ERR_FORMAT, "%s is truncated (header)", path);
    if (hd[1] != want[1])
        return gk_err_set(&ts->err, GK_ERR_FORMAT, "%s was written with the other byte order", path);
    if (hd[0] != want[0])
        return gk_err_set(&ts->err, GK_ERR_FORMAT, "%s has checkpoint format version %u; this build reads %u",
                          path, (unsigned)hd[0], (unsigned)want[0]);
    if (hd[2] != want[2] || hd[3] != want[3] || hd[4] != want[4] || hd[5] != want[5] || hd[6] != want[6])
        return gk_err_set(
            &ts->err, GK_ERR_FORMAT,
            "%s holds %u points of dimension %u, %u prototypes, %u-byte reals; this set has %d, %d, %d, "
            "%d",
            path, (unsigned)hd[4], (unsigned)hd[3], (unsigned)hd[5], (unsigned)hd[2], ts->n, ts->dim,
            ts->nproto, (int)sizeof(gk_real));
    for (k = 0; k < ts->nproto; ++k)
        if (gk__ck_get(c, &u, 4) || u != (uint32_t)ts->pk[k].n)
            return gk_err_set(&ts->err, GK_ERR_FORMAT,
                              "%s: prototype %d has another particle count (or truncated)", path, k);
    for (p = 0; p < ts->n; ++p)
        if (gk__ck_get(c, &u, 4) || u != (uint32_t)ts->pick[p])
            return gk_err_set(
                &ts->err, GK_ERR_FORMAT,
                "%s: point %d has another prototype (another packing draw?) or the file is truncated", path,
                p);
    for (p = 0; p < ts->n; ++p) {
        if (gk__ck_get(c, &n, 8))
            return gk_err_set(&ts->err, GK_ERR_FORMAT, "%s is truncated at point %d", path, p);
        if (n < GK__TS_REC_MIN || n > c->size - c->pos || c->size - c->pos - n < tail ||
            n >= ((uint64_t)1 << 31))
            return gk_err_set(&ts->err, GK_ERR_FORMAT,
                              "%s: the record of point %d has an impossible size %llu", path, p,
                              (unsigned long long)n);
        if (gk__ck_get(c, NULL, n))
            return gk_err_set(&ts->err, GK_ERR_FORMAT, "%s is truncated at point %d", path, p);
    }
    if (gk__ck_get(c, &n, 8) || n > c->size - c->pos || c->size - c->pos - n != 8 || n >= ((uint64_t)1 << 31))
        return gk_err_set(&ts->err, GK_ERR_FORMAT,
                          "%s: the driver block is truncated or has an impossible size", path);
    if (gk__ck_get(c, NULL, n)) return gk_err_set(&ts->err, GK_ERR_FORMAT, "%s is truncated", path);
    {
        uint64_t h = c->h;
        if (fread(&sum, 1, 8, c->fp) != 8 || sum != h)
            return gk_err_set(&ts->err, GK_ERR_FORMAT, "%s: checksum mismatch (the file is corrupt)", path);
    }
    if (fseek(c->fp, 0, SEEK_SET) != 0) return gk_err_set(&ts->err, GK_ERR_IO, "cannot read %s", path);
    c->h = UINT64_C(0xcbf29ce484222325), c->pos = 0;
    return GK_OK;
}

/* a refused record: its message prefixed with the file's name; returns 0 (not ok) */
static int gk__ts_rec_refused(gk_twoscale *ts, const char *path) {
    gk_err e = ts->err;
    gk_err_set(&ts->err, e.code ? e.code : GK_ERR_FORMAT, "%s: %s", path, e.msg);
    return 0;
}

/* gk_twoscale_load, and gk_twoscale_load_take when take is not NULL (block and nblock unused then) */
static gk_result gk__ts_load(gk_twoscale *ts, const char *path, gk_twoscale_take_fn take, void *user,
                             void **block, size_t *nblock) {
    const gk_allocator *a = &ts->def.alloc;
    gk__ckf c;
    gk__tspt **stage = NULL;
    unsigned char *rb = NULL, *blk = NULL;
    size_t rcap = 0;
    uint64_t nb = 0;
    int p, k = 0, ok = 1, j;
    memset(&c, 0, sizeof c);
    gk_err_clear(&ts->err);
    if (ts->n < 1) return gk_err_set(&ts->err, GK_ERR_STATE, "the set was not created");
    if (!path || (!take && (!block || !nblock)))
        return gk_err_set(&ts->err, GK_ERR_ARG, "checkpoint: no path or block pointer");
    if (ts->rank == 0) gk__ts_check_file(ts, path, &c);
    if (gk__ts_share_err(ts)) {
        if (c.fp) fclose(c.fp);
        return ts->err.code;
    }
    stage = (gk__tspt **)gk_alloc(a, ((size_t)ts->nlocal + 1) * sizeof *stage);
    if (!stage) ok = 0, gk_err_set(&ts->err, GK_ERR_ALLOC, "out of memory reading %s", path);
    if (ts->rank == 0) { /* pass 2: the records to their owners */
        gk__ck_get(&c, NULL, 8 + 32 + 4 * ((unsigned long long)ts->nproto + (unsigned long long)ts->n));
        for (p = 0; p < ts->n; ++p) {
            uint64_t n = 0;
            int got = !gk__ck_get(&c, &n, 8) && n < ((uint64_t)1 << 31);
            if (got && n + 1 > rcap) {
                got = gk_realloc(a, (void **)&rb, 0, (size_t)n + 1, 1) == GK_OK;
                if (got) rcap = (size_t)n + 1;
            }
            got = got && !gk__ck_get(&c, rb, n);
            if (!got && ok) ok = 0, gk_err_set(&ts->err, GK_ERR_IO, "%s changed while it was read", path);
            if (ts->owner[p] == 0) {
                stage[k] = NULL;
                if (ok && gk__ts_rec_parse(ts, p, rb, (size_t)n, &stage[k]))
                    ok = gk__ts_rec_refused(ts, path);
                ++k;
            }
#ifdef GK_TWOSCALE_MPI
            else
                gk__ts_xsend(ts, ts->owner[p], got ? rb : NULL, n);
#endif
        }
        if (ok) {
            uint64_t h, sum = 0;
            ok = !gk__ck_get(&c, &nb, 8) && nb < ((uint64_t)1 << 31) &&
                 (blk = (unsigned char *)gk_alloc(a, (size_t)nb + 1)) != NULL && !gk__ck_get(&c, blk, nb);
            h = c.h;
            if (ok) ok = fread(&sum, 1, 8, c.fp) == 8 && sum == h;
            if (!ok) gk_err_set(&ts->err, GK_ERR_IO, "%s changed while it was read", path);
        }
        fclose(c.fp);
    }
#ifdef GK_TWOSCALE_MPI
    else
        for (j = 0; j < ts->nlocal; ++j) {
            unsigned long long n;
            stage[k] = NULL;
            if (gk__ts_xrecv(ts, 0, &rb, &rcap, &n, stage != NULL) && ok) {
                if (gk__ts_rec_parse(ts, ts->pt[j]->id, rb, (size_t)n, &stage[k]))
                    ok = gk__ts_rec_refused(ts, path);
            } else
                ok = 0;
            ++k;
        }
#endif
    gk_free(a, rb);
    if (gk__ts_agree(ts, ok ? GK_OK : (ts->err.code ? ts->err.code : GK_ERR_FORMAT))) { /* nothing changes */
        for (j = 0; j < k; ++j) gk__ts_pt_free(ts, stage[j]);
        gk_free(a, stage), gk_free(a, blk);
        return ts->err.code;
    }
#ifdef GK_TWOSCALE_MPI
    if (ts->nranks > 1) { /* the driver block to every rank */
        MPI_Bcast(&nb, 8, MPI_BYTE, 0, ts->comm);
        if (ts->rank != 0) blk = (unsigned char *)gk_alloc(a, (size_t)nb + 1);
        ok = gk__ts_allok(ts, blk != NULL);
        if (ok) MPI_Bcast(blk, (int)nb, MPI_BYTE, 0, ts->comm);
        ts->stats.collectives += 2;
        if (!ok) {
            for (j = 0; j < k; ++j) gk__ts_pt_free(ts, stage[j]);
            gk_free(a, stage), gk_free(a, blk);
            return gk_err_set(&ts->err, GK_ERR_ALLOC, "out of memory for the driver block of %s", path);
        }
    }
#endif
    if (take) { /* the driver's block first: refused on any rank, nothing changes */
        char why[sizeof ts->err.msg];
        why[0] = '\0';
        ok = take(blk, (size_t)nb, user, why, sizeof why) == 0;
        gk_free(a, blk), blk = NULL;
        if (!ok)
            gk_err_set(&ts->err, GK_ERR_FORMAT, "%s: %s", path, why[0] ? why : "its driver block is refused");
        if (gk__ts_agree(ts, ok ? GK_OK : GK_ERR_FORMAT)) {
            for (j = 0; j < k; ++j) gk__ts_pt_free(ts, stage[j]);
            gk_free(a, stage);
            return ts->err.code;
        }
    }
    for (j = 0; j < ts->nlocal; ++j) {
        gk__ts_pt_free(ts, ts->pt[j]);
        ts->pt[j] = stage[j];
    }
    gk_free(a, stage);
    ts->pending = 0;
    if (!take) *block = blk, *nblock = (size_t)nb;
    return GK_OK;
}

GKDEF gk_result gk_twoscale_load(gk_twoscale *ts, const char *path, void **block, size_t *nblock) {
    return gk__ts_load(ts, path, NULL, NULL, block, nblock);
}

GKDEF gk_result gk_twoscale_load_take(gk_twoscale *ts, const char *path, gk_twoscale_take_fn take,
                                      void *user) {
    if (!take) return gk_err_set(&ts->err, GK_ERR_ARG, "checkpoint: no function to take the driver block");
    return gk__ts_load(ts, path, take, user, NULL, NULL);
}

GKDEF void gk_twoscale_free_block(const gk_twoscale *ts, void *block) { gk_free(&ts->def.alloc, block); }

#endif /* GK_TWOSCALE implementation */
