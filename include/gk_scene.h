/* gk_scene.h - DEM beyond the periodic cell: walls, bodies, gravity,
 * prescribed particles, flexible membranes, insertion and deletion, energy.
 *                                                               (grainkit v0.1)
 *
 * A gk_scene is a DEM system of disks (2D) or spheres (3D) in a domain box
 * that is periodic along some axes (or none, or all) and open along the
 * others, with rigid walls, gravity, external forces, particles whose motion
 * is imposed, a follower-pressure membrane, and particles that come and go.
 * It is the single-scale reference a two-scale model is compared with (the
 * whole specimen in DEM) and the place where packings are poured, trained
 * and cut. It runs the very same particle machinery as the RVE of gk_dem.h
 * (cell lists, contact laws, SIMD kernels, leap-frog, fixed-order sums,
 * save/restore): a gk_scene holds a gk_rve and hooks into its step.
 *
 * DO THIS in one C/C++ file:   #define GK_IMPLEMENTATION
 *                              #include "gk_scene.h"   (pulls in gk_dem.h, gk_io.h)
 *
 *   gk_scene_def d = gk_scene_def_default();
 *   d.dim = 2;  d.hi[0] = 1.0;  d.hi[1] = 2.0;        // domain [0,1] x [0,2], open
 *   d.gravity[1] = -9.81;
 *   gk_scene sc;
 *   gk_scene_create(&sc, &d, &packing);              // positions in world coords
 *   gk_scene_add_box(&sc, &wall_material, GK_BOX_ALL, NULL);
 *   gk_scene_step(&sc, 10000);
 *   printf("floor force %g N\n", sc.walls[2].force[1]);
 *   gk_scene_destroy(&sc);
 *
 * WHAT IS HERE
 *   gk_scene_def_default / gk_scene_create / gk_scene_destroy / gk_scene_step (_flags)
 *   gk_scene_add_wall, gk_scene_add_box, gk_wall_def_default, gk_scene_pair_material
 *   gk_scene_set_external, gk_scene_prescribe / gk_scene_release,
 *   gk_scene_lock_rotation, gk_scene_set_velocity, gk_scene_set_mass
 *                                                  per particle (index p)
 *   gk_scene_add_membrane, gk_scene_side_chain      flexible 2D boundary
 *   gk_scene_insert / gk_scene_remove / gk_scene_index   stable ids
 *   gk_scene_weight_contacts                       contact forces weighted per particle
 *   gk_scene_energy_track / gk_scene_energy        the energy books
 *   gk_scene_stress, gk_scene_stress_box           mean stress of the particles, of a region
 *   gk_scene_save / gk_scene_restore / gk_scene_state_size   bitwise state
 *   gk_scene_write_vtk / _walls_vtk / _svg           pictures
 *   gk_scene_position, gk_scene_dt_critical
 *
 * TIME STEP. def.rve.dt = 0: dt_factor (0 -> 0.5) x the smallest critical
 * step (Guo & Zhao 2014 eq 19) of the pair and the wall contacts, lowered as walls
 * are added; an explicit dt is checked against both and refused if above.
 * Hertz contacts are re-checked at every list rebuild (GK_ERR_DT when the
 * overlaps have grown too much; choose dt explicitly for Hertz scenes).
 *
 * DOMAIN. def.lo, def.hi bound the domain; bit k of def.periodic makes axis k
 * periodic with period hi[k] - lo[k] (positions wrap, contacts take the
 * nearest image, as in the RVE). Along an OPEN axis the particles stay in
 * the domain, held by walls or by the user: the underlying cell is four
 * domains long so that the nearest image is always the particle itself,
 * and the cell lists bin only the particles' own extent (gk_cells.h, OPEN
 * AXES). A particle more than half a domain length minus the interaction
 * range (2 r_max + skin) beyond an open face is LOST: an error
 * (GK_ERR_OUTSIDE, def.lost = GK_LOST_ERROR, the default) or deleted and
 * counted in sc.lost (GK_LOST_DELETE). World coordinates are x = origin +
 * h s (gk_scene_position).
 *
 * WALLS (gk_scene_add_wall; gk_wall_def, zero means default):
 *   GK_WALL_PLANE     half-space {(x - point).normal >= 0} (particles on the
 *                     normal's side; one-sided)
 *   GK_WALL_SEGMENT   2D segment point .. point + e1 (two-sided, round ends)
 *   GK_WALL_RECT      3D rectangle point + [0,1] e1 + [0,1] e2, e1 _|_ e2
 *                     (two-sided, edges and corners by the nearest point)
 *   GK_WALL_DISK      2D rigid disk, GK_WALL_CYLINDER 3D infinite cylinder
 *                     (axis through point), particles outside (a pipe) or,
 *                     with def.inside, inside (a drum)
 *   gk_scene_add_box  planes on the faces of the domain's open axes.
 * Each wall has its own contact material: the particle-wall pair written as
 * a pair of identical bodies of that material (a pair of bodies (E, nu)
 * has E* = E / (2 (1 - nu^2)) in gk_contact.h; gk_scene_pair_material
 * converts two real materials, or a material and a rigid wall). The contact
 * is the gk_contact.h law itself, evaluated against a virtual twin of the
 * particle (same radius and mass, placed so that the overlap is the wall's,
 * moving with the wall surface) with the constants rescaled so that the
 * wall behaves as the rigid surface it is: effective radius R* = r (plane),
 * r R / (R + r) (outside a disk or cylinder of radius R), r R / (R - r)
 * (inside); effective mass m (the twin's m/2 is compensated by sqrt 2 in
 * the dashpots); linear k_n = E x 2 R* (or the constant kn); rolling
 * stiffness beta k_t r^2, cap eta r F_n. So a sphere of radius r, mass m
 * hitting a rigid plane follows Hertz theory with R* = r, m* = m, E* of the
 * pair (tests/test_scene.c: Chung & Ooi 2011 tests 2-6).
 * Drive (def.drive): GK_DRIVE_VELOCITY (def.velocity, and def.spin for a
 * disk or cylinder, about point; zero = fixed), GK_DRIVE_FORCE or
 * GK_DRIVE_STRESS: a servo moves the wall along the unit direction
 * def.normal (planes: towards the particles) so that the resistance
 * R = -F.normal (F the force the particles exert on the wall) reaches
 * def.target [N], or def.target x def.area [Pa x m^2; 2D: m x thickness]:
 * v = gain (target - R) / (K dt), K the sum of the wall's contact normal
 * stiffnesses, capped at max_speed (which the servo moves at when K = 0);
 * the wall moves with def.velocity's part across that direction as well
 * (a shear box under constant normal load).
 * A wall reports each step force[3], moment[3] (about its point, both
 * exerted BY the particles ON the wall), resistance, ncontacts, stiffness,
 * and its current position pos (vel, angle). The fields of sc.walls[w].def may be changed between
 * gk_scene_step calls (drive, velocity, target, area, gain): they are
 * checked at the next call.
 *
 * GRAVITY AND EXTERNAL LOADS. def.gravity [m/s^2] acts on every particle
 * (F = m g); gk_scene_set_external(sc, p, f, t) adds a constant force and
 * moment to particle p.
 *
 * PRESCRIBED PARTICLES. gk_scene_prescribe(sc, p, v, w) imposes the velocity
 * (and spin) of particle p from the next step on; its load (the sum of every
 * force and moment on it except the constraint's: contacts, walls, gravity,
 * external) is in sc.load[k][p], sc.loadt[k][p] after each step;
 * gk_scene_release frees it. (Liu, Bosco & Suiker 2018's frame of boundary particles and
 * Chen et al. 2021's trained grains are prescribed particles.)
 * gk_scene_lock_rotation(sc, p, 1) holds the spin of particle p at zero
 * (its orientation stays, it translates freely; its contact moments act on
 * nothing) until it is called with 0: one particle's share of
 * GK_RVE_NO_ROTATION, e.g. Liu, Bosco & Suiker 2018's theta_p = 0 for the
 * inner particles while the frame turns. A prescribed spin overrides it.
 *
 * MEMBRANE (2D). gk_scene_add_membrane(sc, k, ids, pressure, stiffness,
 * anchor_first, anchor_last): a chain of particles (stable ids, the
 * material on the chain's LEFT, i.e. a counter-clockwise boundary) loaded
 * by a follower pressure: every segment a-b between consecutive centres
 * receives p t |x_b - x_a| along its inward normal, half on each end (t the
 * 2D thickness of gk_rve: the same t the stress is divided by). With
 * stiffness > 0, consecutive members are also tied by tension-only springs
 * of that stiffness and rest length their initial distance (the mass-spring
 * membrane of Chen et al. 2021 App. B), so the chain cannot open gaps an inner
 * particle could escape through. An anchor (a wall index, -1 for none)
 * closes the chain at that end on a platen, as the rubber sleeve of a
 * biaxial cell is clamped to it: the end member is tied (same spring) to
 * its nearest point on that wall - it slides along the wall freely but
 * cannot leave it by more than its initial distance, so no inner particle
 * can pass round the chain end - and the segment member-wall carries the
 * pressure too (its half on the wall is not applied). Without anchors the
 * strips between the end members and the platens are unloaded and an inner
 * particle can escape round a chain end. This is the follower-pressure flexible boundary of
 * Cheung & O'Sullivan (2008) with a fixed chain (members chosen once, e.g.
 * by gk_scene_side_chain).
 *
 * A SCENE AROUND AN RVE THE CALLER OWNS (gk_scene_wrap / gk_scene_unwrap),
 * e.g. the RVE of one point of gk_twoscale.h run under boundary conditions
 * of its own (a frame of prescribed particles: gk_frame.h). wrap moves the
 * RVE's struct into a scene whose domain is the RVE's cell (a box, every
 * axis periodic, no gravity, nothing prescribed); the RVE's state
 * (positions, velocities, contact history, ids) is the scene's particles.
 * unwrap frees what the scene added (walls, prescribed motion, loads,
 * membranes, energy) and moves the RVE back, its hook cleared: the RVE is
 * then as if stepped by itself with those forces. Between the two calls
 * use only the scene (the caller's gk_rve is zeroed meanwhile).
 *
 * INSERTION AND DELETION. gk_scene_insert adds particles (world positions,
 * optional velocities) and returns their stable ids; gk_scene_remove
 * deletes by id. Survivors keep their ids, contact histories (pairs and
 * walls), prescribed motion and loads. Indices p (0..n-1, the order of the
 * arrays) change at every insertion or deletion; gk_scene_index maps an id
 * to its index (-1 if gone): a table lookup while the largest id is within
 * 4 n + 1024, a binary search over the n ids beyond (ids are never reused,
 * so a long run of insertions and deletions, or a saved state, can name
 * ids far above n; the index stays O(n) either way). gk_packing_tile /
 * gk_packing_subset (gk_packing.h) build a scene's packing from a periodic
 * one.
 *
 * CONTACT WEIGHTS (gk_scene_weight_contacts). With a weight w_p in (0, 1]
 * per particle, the force and moments of every particle-particle contact
 * are scaled by s = (w_i + w_j) / 2 before the particles move: equal and
 * opposite still, so momentum is kept. This is the partition of unity of
 * a region shared with another model, Chen et al.'s eq 9 (w rho dv/dt =
 * w f + f_coupling, after Yue et al. 2018): particles of weight w hold w
 * of their mass (gk_scene_set_mass) and carry w of their contacts' forces.
 * Walls, membranes, gravity and external loads act whole. The array is
 * the caller's, read at every step and not copied or saved: it holds rve.n
 * values in index order, checked at every gk_scene_step (a value outside
 * (0, 1] is refused before anything moves). Whatever changes the indices
 * forgets it (gk_scene_insert, gk_scene_remove, a lost particle's deletion,
 * a gk_scene_restore that changes the particle count): set it again. The
 * per-pair forces (gk_scene_stress, gk_scene_stress_box) stay the contact
 * law's. Every step then keeps the per-pair forces (gk_rve.hook_pairs),
 * which one thread on a long list otherwise stores only with the stress.
 * Not with energy tracking (refused both ways: the books would not know
 * the scaling).
 *
 * ENERGY (gk_scene_energy_track, gk_scene_energy). From the moment tracking
 * starts, each step books: kinetic energy (translation + rotation, at the
 * half steps of the leap-frog), elastic energy (the springs of every pair
 * and wall contact - normal: k_n delta^2 / 2 linear, 2/5 F_n delta Hertz;
 * tangential |F_t|^2 / (2 k_t); rolling |M_r|^2 / (2 k_r) - and the
 * membrane springs), the work done on the particles by gravity, walls
 * (force times the wall's surface velocity), external loads, the membrane
 * pressure and the constraints of prescribed particles, and the energy
 * dissipated by contact dashpots, Coulomb sliding (and rolling slip) and
 * local damping. The work of a force F over a step is F . v_bar dt with
 * v_bar = (v_{n-1/2} + v_{n+1/2}) / 2 (with torques and spins likewise),
 * the leap-frog's own measure, which makes the kinetic part exact: damping
 * is what the applied forces did beyond the kinetic energy change; the
 * dashpots' dissipation is the work of their forces; friction is what the
 * tangential forces and the torques took out of the particles beyond the
 * change of the tangential and rolling springs' energy (the slip energy of
 * PFC), so the incremental Hertz-Mindlin spring, whose stiffness follows
 * the overlap, is booked exactly too; `slip` estimates the same friction
 * from the slips (F_t (F_trial - F_t) / k_t per sliding contact) as a
 * check. The contacts are evaluated again with the law itself for the
 * books (each pair once more, sliding ones twice: tracking costs about two
 * to three times the contact time; pay for it only when needed).
 * balance = kinetic + elastic - (initial + works - dissipation) is then
 * the time integration's own energy error: the normal springs' energy at
 * the steps against the kinetic energy at the half steps, and contacts
 * that open or close between two steps (tests: 2e-4 of the energy moved at
 * dt = 0.1 dt_crit, shrinking with dt). Particles removed or
 * inserted carry their kinetic energy (and removed ones their contacts'
 * elastic energy) in `removed` / `inserted`; an inserted particle that
 * overlaps another brings elastic energy the balance does not book.
 *
 * DETERMINISM. Walls, gravity, membranes and prescribed particles are
 * applied in the step hook in a fixed (index) order, serially; the pair
 * forces are gk_dem.h's. Results do not depend on the thread count
 * (def.rve.threads) and gk_scene_save / gk_scene_restore continue a run
 * bit for bit (tests/test_scene.c).
 *
 * CONVENTIONS: SI units; 2D quantities per the gk_rve thickness t (masses
 * and the membrane pressure use it: GK_MASS_CYLINDER, the default, has
 * disks of thickness def.rve.thickness). Forces on walls are exerted by the
 * particles; a plane's "resistance" -F.normal is compression-positive.
 *
 * LIMITS. Contacts with a wall of a periodic axis see the particle's own
 * position only (no image): keep bodies away from periodic faces. No
 * velocity gradient (gk_rve.L must stay zero): the cell is a fixed frame.
 * Membranes are 2D. Energy tracking books bonds of cohesive contacts as
 * springs only (no bond-breaking energy).
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_SCENE_H
#define GK_SCENE_H

#include "gk_base.h"
#include "gk_dem.h"
#include "gk_io.h"

#define GK_SCENE_DEF_COOKIE 0x53434e31

typedef enum gk_lost_policy { GK_LOST_ERROR = 0, GK_LOST_DELETE = 1 } gk_lost_policy;

typedef struct gk_scene_def {
    int cookie;          /* set by gk_scene_def_default()                         */
    int dim;             /* 2 or 3                                                */
    double lo[3], hi[3]; /* domain box [m]                                        */
    unsigned periodic;   /* bit k: axis k periodic (period hi - lo); 0: all open */
    double gravity[3];   /* [m/s^2]                                               */
    gk_lost_policy lost; /* a particle leaving an open domain                     */
    gk_rve_def rve;      /* material, dt, skin, damping (default 0 here), thickness,
                              mass model, flags, threads, allocator                 */
} gk_scene_def;

typedef enum gk_wall_kind {
    GK_WALL_PLANE = 0,
    GK_WALL_SEGMENT = 1, /* 2D */
    GK_WALL_RECT = 2,    /* 3D */
    GK_WALL_DISK = 3,    /* 2D */
    GK_WALL_CYLINDER = 4 /* 3D */
} gk_wall_kind;

typedef enum gk_wall_drive { GK_DRIVE_VELOCITY = 0, GK_DRIVE_FORCE = 1, GK_DRIVE_STRESS = 2 } gk_wall_drive;

typedef struct gk_wall_def {
    gk_wall_kind kind;
    double point[3];     /* plane: a point on it; segment, rect: first corner; disk, cylinder: centre */
    double normal[3];    /* plane: unit normal towards the particles; servo direction of every kind */
    double e1[3], e2[3]; /* segment: e1 = b - a; rect: the two (orthogonal) edges                   */
    double axis[3];      /* cylinder: unit axis                                                       */
    double radius;       /* disk, cylinder [m]                                                        */
    int inside;          /* disk, cylinder: particles inside (a drum)                                 */
    gk_material mat;     /* contact material of the particle-wall pair (see WALLS)                    */
    gk_wall_drive drive;
    double velocity[3]; /* GK_DRIVE_VELOCITY [m/s]                                                    */
    double spin[3];     /* disk, cylinder: angular velocity about point (2D: spin[2]) [rad/s]         */
    double target;      /* GK_DRIVE_FORCE [N] or GK_DRIVE_STRESS [Pa], compression positive           */
    double area;        /* GK_DRIVE_STRESS: area the stress acts on [m^2] (2D: length x thickness)    */
    double gain;        /* servo gain in (0, 1]; 0 -> 0.05                                            */
    double max_speed;   /* servo speed cap [m/s] (> 0 for a servo)                                   */
} gk_wall_def;

typedef struct gk_wall {
    gk_wall_def def;   /* as given; def.point is the position at creation    */
    double pos[3];     /* current point (def.point + displacement)            */
    double vel[3];     /* translation velocity of the current step            */
    double angle;      /* rotation about the axis since creation [rad]        */
    double force[3];   /* exerted by the particles on the wall, last step [N] */
    double moment[3];  /* about pos, same [N m]                               */
    double stiffness;  /* sum of the contact normal stiffnesses [N/m]         */
    double resistance; /* -force . normal (the servo's measure) [N]           */
    int ncontacts;
    /* internal */
    gk_law_consts K; /* the material's constants, rescaled for a plane      */
    unsigned phys;   /* GK_PHYS_* of its contacts                           */
    gk_real *ft[3], *mr[3];
    unsigned char *cs; /* history per particle index                          */
    int32_t *cand;     /* candidate particles (ascending)                     */
    int ncand, capcand;
    double built[3]; /* pos at the candidate build                          */
    long built_rebuilds;
    int need_build;
    double dmax; /* largest overlap of the last step                    */
} gk_wall;

typedef struct gk_membrane {
    int n, cap;       /* members, capacity                                   */
    int32_t *ids;     /* stable ids, the material on the chain's left        */
    double *rest;     /* rest length of each link (n - 1)                    */
    int anchor[2];    /* wall of the first / last member's anchor, or -1     */
    double arest[2];  /* rest length of the anchor links                     */
    double af[2][2];  /* anchor link force on the first / last member, last step */
    double pressure;  /* [Pa]                                                */
    double stiffness; /* link springs [N/m]; 0: none                         */
    double *fx, *fy;  /* pressure force on each member, last step (energy)   */
} gk_membrane;

typedef struct gk_energy {
    double kinetic; /* now (half step) [J]                                          */
    double elastic; /* contact and membrane springs, last step [J]                  */
    double gravity, walls, external, pressure, prescribed; /* work on the particles [J]  */
    double friction, viscous, damping;                     /* dissipated, >= 0 [J]      */
    double slip;              /* friction estimated from the Coulomb and rolling slips (a check) */
    double removed, inserted; /* carried out, in [J]       */
    double initial;           /* kinetic + elastic when tracking started                      */
    double balance;           /* kinetic + elastic - (initial + works - dissipation + in - out) */
    double scale;             /* |initial| + sum of |works| + dissipation: balance's yardstick */
    long steps;
} gk_energy;

/* particle flags */
#define GK_PARTICLE_PRESCRIBED 1u
#define GK_PARTICLE_LOCKED_ROTATION 2u
#define GK__PARTICLE_FLAGS 3u

/* gk_scene_add_box faces: bit 2k lower face of axis k, bit 2k+1 upper */
#define GK_BOX_ALL 0x3fu

typedef struct gk_scene {
    gk_rve rve; /* the particles: rve.n, rve.id[] (stable ids), rve.v, ... */
    gk_scene_def def;
    int dim;
    unsigned open;    /* open axes                                              */
    double origin[3]; /* world x = origin + h s                                 */
    gk_wall *walls;
    int nwalls, capwalls;
    gk_membrane *mem;
    int nmem, capmem;
    int cap;                    /* capacity of the per-particle arrays below               */
    double *mass;               /* 1 / minv                                                */
    unsigned char *flags;       /* GK_PARTICLE_*                                           */
    double *vp[3], *wp[3];      /* prescribed velocity and spin                            */
    double *load[3], *loadt[3]; /* load on prescribed particles, last step              */
    double *fext[3], *text[3];  /* constant external force and moment                   */
    int nprescribed, nlocked;   /* particles with GK_PARTICLE_PRESCRIBED, _LOCKED_ROTATION */
    const double *cw;           /* contact weights, the caller's (NULL: none)              */
    int32_t next_id, *index_of; /* id -> index (-1: gone), capacity cap_ids; sparse ids:  */
    int cap_ids, sparse_ids;    /* (id, index) pairs sorted by id, n of them (below)      */
    long lost;                  /* particles deleted as lost                               */
    long seen_rebuilds;
    /* energy */
    int energy_on, energy_pending;
    gk_energy en;
    double *vold[3], *wold[3], *ftot[3], *ttot[3];
    gk_real *hft[3], *hmr[3];
    unsigned char *hcs;
    size_t hcap;
    double wall_love[9]; /* wall contacts' f (x) (x_c - x_p) and membrane links' f L u (x) u, last step */
    double el_step;      /* elastic energy summed during the current step           */
    double erest_now, erest_prev, slip_step; /* tangential + rolling spring energy, slip     */
    void *rec;                               /* gk__erec: the step's contact forces for the books        */
    size_t nrec, caprec;
    int rec_failed;
    long energy_mismatch; /* pairs whose re-evaluation differed from the kernel (0)  */
    gk_err err;
} gk_scene;

#ifdef __cplusplus
extern "C" {
#endif

GKDEF gk_scene_def gk_scene_def_default(void);
GKDEF gk_wall_def gk_wall_def_default(void);
/* the particle-wall (or particle-particle) contact material of bodies a and
 * b as a pair of identical bodies (see WALLS): Hertz E*, G* and linear
 * 2 E_a E_b / (E_a + E_b); b = NULL: a rigid body. friction and damping of a;
 * the law of a. */
GKDEF gk_result gk_scene_pair_material(const gk_material *a, const gk_material *b, gk_material *out,
                                       gk_err *err);

GKDEF gk_result gk_scene_create(gk_scene *sc, const gk_scene_def *def, const gk_packing *pk);
GKDEF void gk_scene_destroy(gk_scene *sc);
/* a scene around an RVE (its cell a box, no velocity gradient or servo), and back (see above) */
GKDEF gk_result gk_scene_wrap(gk_scene *sc, gk_rve *rve);
GKDEF void gk_scene_unwrap(gk_scene *sc, gk_rve *rve);
GKDEF const char *gk_scene_error(const gk_scene *sc);
GKDEF gk_result gk_scene_step(gk_scene *sc, long nsteps);
/* the same with GK_STEP_* flags (gk_dem.h: GK_STEP_NO_STRESS for one-step calls of a coupled scheme) */
GKDEF gk_result gk_scene_step_flags(gk_scene *sc, long nsteps, unsigned flags);
GKDEF void gk_scene_position(const gk_scene *sc, int p, double x[3]);
GKDEF int gk_scene_index(const gk_scene *sc, int32_t id);
GKDEF double gk_scene_dt_critical(const gk_scene *sc);
/* mean stress of the particles over `volume` (2D: an area; the thickness t
 * is applied), tension-positive, at the last step of the last call:
 * (1/V) sum over particles of f (x) (x_c - x_p) over their contact forces
 * with each other (the Love form -F (x) d of gk_dem.h) and with walls
 * (forces applied at particle centres - gravity, membrane, external - add
 * nothing). In equilibrium it is the stress the boundary applies. */
GKDEF void gk_scene_stress(const gk_scene *sc, double volume, double sigma[9]);
/* mean stress of a region: the Love sum -F (x) d of the particle-particle
 * contacts whose midpoint x_i + d/2 lies in the box lo <= x < hi (world
 * coordinates; along a periodic axis the midpoint is wrapped into the
 * domain first), over the box's volume (2D: its area x the thickness t; the
 * box's z range is ignored), tension-positive, from the last step's forces
 * and the positions at its end (gk_scene_stress takes the branch vectors at
 * force time: over a box holding every contact the two differ by one step's
 * relative motion). Wall contacts are left out. In a homogeneous region in
 * equilibrium it is the stress carried across the region (Chen et al.
 * 2021's "mean shear stress of the corresponding region"). GK_ERR_ARG
 * (sigma untouched) for a box that is not finite with lo < hi. */
GKDEF gk_result gk_scene_stress_box(gk_scene *sc, const double lo[3], const double hi[3], double sigma[9]);

GKDEF gk_result gk_scene_add_wall(gk_scene *sc, const gk_wall_def *wd, int *index);
GKDEF gk_result gk_scene_add_box(gk_scene *sc, const gk_material *m, unsigned faces, int *first);

GKDEF gk_result gk_scene_set_external(gk_scene *sc, int p, const double f[3], const double t[3]);
GKDEF gk_result gk_scene_prescribe(gk_scene *sc, int p, const double v[3], const double w[3]);
GKDEF gk_result gk_scene_release(gk_scene *sc, int p);
/* locked 1: the spin of particle p is held at zero from the next step on; 0: free again */
GKDEF gk_result gk_scene_lock_rotation(gk_scene *sc, int p, int locked);
/* mass and moment of inertia of particle p (e.g. another density); a lighter particle lowers an
 * automatic time step as a new wall does, and is refused (GK_ERR_DT, nothing changed) when an
 * explicit def.rve.dt is above the critical step it gives */
GKDEF gk_result gk_scene_set_mass(gk_scene *sc, int p, double m, double I);
/* velocity and spin of particle p (NULL: unchanged), e.g. the initial state */
GKDEF gk_result gk_scene_set_velocity(gk_scene *sc, int p, const double v[3], const double w[3]);

GKDEF gk_result gk_scene_add_membrane(gk_scene *sc, int k, const int32_t *ids, double pressure,
                                      double stiffness, int anchor_first, int anchor_last, int *index);
/* 2D: the outermost particle of every band of width `band` along the other
 * axis, on side (-1 low, +1 high) of axis `axis`, ordered with the material
 * on the chain's left; ids written to ids (capacity cap), count to *k */
GKDEF gk_result gk_scene_side_chain(gk_scene *sc, int axis, int side, double band, int32_t *ids, int cap,
                                    int *k);

GKDEF gk_result gk_scene_insert(gk_scene *sc, int k, const double *const x[3], const double *r,
                                const double *const v[3], int32_t *ids);
GKDEF gk_result gk_scene_remove(gk_scene *sc, int k, const int32_t *ids);

GKDEF gk_result gk_scene_energy_track(gk_scene *sc, int on);
/* contact forces scaled by the pair's mean weight; w: rve.n values in (0, 1], borrowed; NULL: none */
GKDEF gk_result gk_scene_weight_contacts(gk_scene *sc, const double *w);
GKDEF void gk_scene_energy(const gk_scene *sc, gk_energy *e);

GKDEF size_t gk_scene_state_size(const gk_scene *sc);
GKDEF gk_result gk_scene_save(const gk_scene *sc, void *buf, size_t cap, size_t *written);
/* a state of this scene (same dim, walls, membranes, domain; any particle count): a buffer from
 * anywhere is untrusted, and one refused (GK_ERR_FORMAT with a message, GK_ERR_DT for a time step
 * above its particles' critical one) leaves the scene exactly as it was */
GKDEF gk_result gk_scene_restore(gk_scene *sc, const void *buf, size_t size);

/* output: particles (points with radius, velocity, spin, id) and walls
 * (lines in 2D, quads in 3D, clipped to the domain) as legacy VTK; 2D
 * particles as polygons coloured by value[p] (NULL: speed) in an SVG */
GKDEF gk_result gk_scene_write_vtk(const gk_scene *sc, const char *path, gk_err *err);
GKDEF gk_result gk_scene_write_walls_vtk(const gk_scene *sc, const char *path, gk_err *err);
GKDEF gk_result gk_scene_write_svg(const gk_scene *sc, const char *path, const char *title, const char *label,
                                   const double *value, gk_err *err);

#ifdef __cplusplus
}
#endif
#endif /* GK_SCENE_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_SCENE_IMPLEMENTATION)) && !defined(GK_SCENE_IMPL_ONCE)
#define GK_SCENE_IMPL_ONCE

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

GKDEF gk_scene_def gk_scene_def_default(void) {
    gk_scene_def d;
    memset(&d, 0, sizeof d);
    d.cookie = GK_SCENE_DEF_COOKIE;
    d.rve = gk_rve_def_default();
    d.rve.damping = 0.0; /* a scene is dynamics unless asked otherwise */
    d.lost = GK_LOST_ERROR;
    return d;
}

GKDEF gk_wall_def gk_wall_def_default(void) {
    gk_wall_def w;
    memset(&w, 0, sizeof w);
    w.kind = GK_WALL_PLANE;
    w.mat = gk_material_default();
    w.drive = GK_DRIVE_VELOCITY;
    return w;
}

GKDEF gk_result gk_scene_pair_material(const gk_material *a, const gk_material *b, gk_material *out,
                                       gk_err *err) {
    gk_material m;
    gk_result r;
    if (!a || !out) return gk_err_set(err, GK_ERR_ARG, "pair material: no material given");
    if ((r = gk_material_check(a, err)) != GK_OK) return r;
    if (b && (r = gk_material_check(b, err)) != GK_OK) return r;
    m = *a;
    if (a->law == GK_LAW_HERTZ) {
        double Ga = a->young / (2.0 * (1.0 + a->poisson)), Es, Gs, hn, ht, q, nu;
        if (b && b->law != GK_LAW_HERTZ) return gk_err_set(err, GK_ERR_ARG, "pair material: laws differ");
        Es = (1.0 - a->poisson * a->poisson) / a->young;
        Gs = (2.0 - a->poisson) / Ga;
        if (b) {
            double Gb = b->young / (2.0 * (1.0 + b->poisson));
            Es += (1.0 - b->poisson * b->poisson) / b->young;
            Gs += (2.0 - b->poisson) / Gb;
        }
        /* gk_contact.h: hn = G/(1-nu) must be E*, ht = 2G/(2-nu) must be 4 G* */
        hn = 1.0 / Es;
        ht = 4.0 / Gs;
        q = ht / hn;
        nu = (2.0 - 2.0 * q) / (2.0 - q);
        if (!(nu > -1.0 && nu < 0.5))
            return gk_err_set(err, GK_ERR_ARG, "pair material: equivalent Poisson ratio %g outside (-1, 0.5)",
                              nu);
        m.poisson = nu;
        m.young = 2.0 * hn * (1.0 - nu * nu);
    } else {
        if (b && b->law != GK_LAW_LINEAR) return gk_err_set(err, GK_ERR_ARG, "pair material: laws differ");
        if (b) {
            m.young = 2.0 * a->young * b->young / (a->young + b->young);
            if (a->kn > 0 && b->kn > 0) m.kn = 2.0 * a->kn * b->kn / (a->kn + b->kn);
        } else {
            m.young = 2.0 * a->young;
            if (a->kn > 0) m.kn = 2.0 * a->kn;
        }
    }
    *out = m;
    return GK_OK;
}

GKDEF const char *gk_scene_error(const gk_scene *sc) { return sc->err.msg; }

/* the RVE's message into the scene's */
static gk_result gk__scene_rve_err(gk_scene *sc, gk_result r) {
    if (r) {
        sc->err.code = r;
        memcpy(sc->err.msg, sc->rve.err.msg, sizeof sc->err.msg);
    }
    return r;
}

GKDEF void gk_scene_position(const gk_scene *sc, int p, double x[3]) {
    int k;
    gk_rve_position(&sc->rve, p, x);
    for (k = 0; k < sc->dim; ++k) x[k] += sc->origin[k];
}

GKDEF int gk_scene_index(const gk_scene *sc, int32_t id) {
    if (id < 0 || id >= sc->next_id) return -1;
    if (sc->sparse_ids) { /* binary search of the (id, index) pairs */
        int lo = 0, hi = sc->rve.n - 1;
        while (lo <= hi) {
            int mid = lo + (hi - lo) / 2;
            int32_t m = sc->index_of[2 * mid];
            if (m == id) return sc->index_of[2 * mid + 1];
            if (m < id)
                lo = mid + 1;
            else
                hi = mid - 1;
        }
        return -1;
    }
    if (id >= sc->cap_ids) return -1;
    return sc->index_of[id];
}

/* ------------------------------------------------------------- storage */
static const gk_allocator *gk__sc_alloc(const gk_scene *sc) { return &sc->def.rve.alloc; }

/* grow a per-particle array of n used elements to cap (NULL stays NULL) */
static int gk__sc_grow(const gk_scene *sc, void **p, size_t n, size_t cap, size_t sz) {
    if (!*p) return 0;
    return gk_realloc(gk__sc_alloc(sc), p, n, cap, sz) != GK_OK;
}

/* every per-particle array of the scene (walls too) to capacity cap */
static gk_result gk__scene_reserve(gk_scene *sc, int cap) {
    size_t n = (size_t)sc->rve.n, c = (size_t)cap, D = sizeof(double), R = sizeof(gk_real);
    int k, w, bad = 0;
    if (cap <= sc->cap) return GK_OK;
    bad |= gk__sc_grow(sc, (void **)&sc->mass, n, c, D);
    bad |= gk__sc_grow(sc, (void **)&sc->flags, n, c, 1);
    for (k = 0; k < 3; ++k) {
        bad |= gk__sc_grow(sc, (void **)&sc->vp[k], n, c, D);
        bad |= gk__sc_grow(sc, (void **)&sc->wp[k], n, c, D);
        bad |= gk__sc_grow(sc, (void **)&sc->load[k], n, c, D);
        bad |= gk__sc_grow(sc, (void **)&sc->loadt[k], n, c, D);
        bad |= gk__sc_grow(sc, (void **)&sc->fext[k], n, c, D);
        bad |= gk__sc_grow(sc, (void **)&sc->text[k], n, c, D);
        bad |= gk__sc_grow(sc, (void **)&sc->vold[k], n, c, D);
        bad |= gk__sc_grow(sc, (void **)&sc->wold[k], n, c, D);
        bad |= gk__sc_grow(sc, (void **)&sc->ftot[k], n, c, D);
        bad |= gk__sc_grow(sc, (void **)&sc->ttot[k], n, c, D);
    }
    for (w = 0; w < sc->nwalls; ++w) {
        gk_wall *W = &sc->walls[w];
        for (k = 0; k < 3; ++k) {
            bad |= gk__sc_grow(sc, (void **)&W->ft[k], n, c, R);
            bad |= gk__sc_grow(sc, (void **)&W->mr[k], n, c, R);
        }
        bad |= gk__sc_grow(sc, (void **)&W->cs, n, c, 1);
    }
    if (bad) return gk_err_set(&sc->err, GK_ERR_ALLOC, "out of memory for %d particles", cap);
    sc->cap = cap;
    return GK_OK;
}

/* allocate a zeroed per-particle double array at the current capacity */
static gk_result gk__sc_new(gk_scene *sc, double **p) {
    if (*p) return GK_OK;
    *p = (double *)gk_alloc(gk__sc_alloc(sc), (size_t)sc->cap * sizeof(double));
    if (!*p) return gk_err_set(&sc->err, GK_ERR_ALLOC, "out of memory");
    memset(*p, 0, (size_t)sc->cap * sizeof(double));
    return GK_OK;
}

static void gk__sc_free(gk_scene *sc, void *p) { gk_free(gk__sc_alloc(sc), p); }

/* ids above this many per particle (plus GK__SCENE_IDS_SLACK) are looked up
 * by binary search instead of in a table as long as the largest id: the
 * index then stays O(n) however many particles were inserted and deleted
 * before, or a saved state claims (a 20 kB state claiming a next id of
 * 4.5e8 asked for a table of 2.7 GB) */
#define GK__SCENE_IDS_PER_PARTICLE 4
#define GK__SCENE_IDS_SLACK 1024

static int gk__scene_pair_cmp(const void *a, const void *b) {
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

/* id -> index for every particle (ids in [0, next_id), each at most once): a
 * table as long as the largest id + 1 when the ids are dense enough, else the
 * (id, index) pairs sorted by id */
static gk_result gk__scene_index(gk_scene *sc) {
    int p, n = sc->rve.n, top = 0, need;
    for (p = 0; p < n; ++p)
        if (sc->rve.id[p] >= top) top = sc->rve.id[p] + 1;
    sc->sparse_ids = (double)top > (double)GK__SCENE_IDS_PER_PARTICLE * n + GK__SCENE_IDS_SLACK;
    need = sc->sparse_ids ? 2 * n : top;
    if (need > sc->cap_ids) {
        int cap = need + need / 2 + 16;
        if (gk_realloc(gk__sc_alloc(sc), (void **)&sc->index_of, 0, (size_t)cap, sizeof(int32_t))) {
            sc->sparse_ids = 0, sc->cap_ids = 0; /* no index: gk_scene_index says -1 */
            return gk_err_set(&sc->err, GK_ERR_ALLOC, "out of memory for %d ids", cap);
        }
        sc->cap_ids = cap;
    }
    if (sc->sparse_ids) {
        for (p = 0; p < n; ++p) sc->index_of[2 * p] = sc->rve.id[p], sc->index_of[2 * p + 1] = p;
        qsort(sc->index_of, (size_t)n, 2 * sizeof(int32_t), gk__scene_pair_cmp); /* unique ids: one order */
        for (p = 1; p < n; ++p)
            if (sc->index_of[2 * p] == sc->index_of[2 * p - 2])
                return gk_err_set(&sc->err, GK_ERR_FORMAT, "particles %d and %d have the same id %d",
                                  (int)sc->index_of[2 * p - 1], (int)sc->index_of[2 * p + 1],
                                  (int)sc->index_of[2 * p]);
        return GK_OK;
    }
    for (p = 0; p < sc->cap_ids; ++p) sc->index_of[p] = -1;
    for (p = 0; p < n; ++p) {
        if (sc->index_of[sc->rve.id[p]] >= 0)
            return gk_err_set(&sc->err, GK_ERR_FORMAT, "particles %d and %d have the same id %d",
                              (int)sc->index_of[sc->rve.id[p]], p, (int)sc->rve.id[p]);
        sc->index_of[sc->rve.id[p]] = p;
    }
    return GK_OK;
}

static void gk__wall_free(gk_scene *sc, gk_wall *W) {
    int k;
    for (k = 0; k < 3; ++k) {
        gk__sc_free(sc, W->ft[k]);
        gk__sc_free(sc, W->mr[k]);
    }
    gk__sc_free(sc, W->cs);
    gk__sc_free(sc, W->cand);
}

/* everything but the RVE */
static void gk__scene_free_own(gk_scene *sc) {
    int k, w;
    for (w = 0; w < sc->nwalls; ++w) gk__wall_free(sc, &sc->walls[w]);
    for (w = 0; w < sc->nmem; ++w) {
        gk__sc_free(sc, sc->mem[w].ids);
        gk__sc_free(sc, sc->mem[w].rest);
        gk__sc_free(sc, sc->mem[w].fx);
        gk__sc_free(sc, sc->mem[w].fy);
    }
    gk__sc_free(sc, sc->walls);
    gk__sc_free(sc, sc->mem);
    gk__sc_free(sc, sc->mass);
    gk__sc_free(sc, sc->flags);
    gk__sc_free(sc, sc->index_of);
    for (k = 0; k < 3; ++k) {
        gk__sc_free(sc, sc->vp[k]);
        gk__sc_free(sc, sc->wp[k]);
        gk__sc_free(sc, sc->load[k]);
        gk__sc_free(sc, sc->loadt[k]);
        gk__sc_free(sc, sc->fext[k]);
        gk__sc_free(sc, sc->text[k]);
        gk__sc_free(sc, sc->vold[k]);
        gk__sc_free(sc, sc->wold[k]);
        gk__sc_free(sc, sc->ftot[k]);
        gk__sc_free(sc, sc->ttot[k]);
        gk__sc_free(sc, sc->hft[k]);
        gk__sc_free(sc, sc->hmr[k]);
    }
    gk__sc_free(sc, sc->hcs);
    gk__sc_free(sc, sc->rec);
    sc->walls = NULL;
    sc->mem = NULL;
    sc->nwalls = sc->nmem = 0;
    sc->mass = NULL;
    sc->flags = NULL;
    sc->index_of = NULL;
    for (k = 0; k < 3; ++k) {
        sc->vp[k] = sc->wp[k] = sc->load[k] = sc->loadt[k] = sc->fext[k] = sc->text[k] = NULL;
        sc->vold[k] = sc->wold[k] = sc->ftot[k] = sc->ttot[k] = NULL;
        sc->hft[k] = sc->hmr[k] = NULL;
    }
    sc->hcs = NULL;
    sc->rec = NULL;
    sc->nrec = sc->caprec = 0;
}

GKDEF void gk_scene_destroy(gk_scene *sc) {
    gk__scene_free_own(sc);
    gk_rve_destroy(&sc->rve);
}

GKDEF gk_result gk_scene_wrap(gk_scene *out, gk_rve *rve) {
    gk_scene S;
    gk_result res = GK_OK;
    int k, p;
    gk_err_clear(&out->err);
    if (!rve || rve->n < 1 || (rve->dim != 2 && rve->dim != 3))
        return gk_err_set(&out->err, GK_ERR_ARG, "wrap: no RVE (or an empty one)");
    for (k = 0; k < 9; ++k)
        if ((k % 4 != 0 && rve->cell.h[k] != 0.0) || rve->L[k] != 0.0 || rve->servo_on)
            return gk_err_set(&out->err, GK_ERR_STATE,
                              "wrap: the RVE's cell must be a box with no velocity gradient or servo");
    memset(&S, 0, sizeof S);
    S.def = gk_scene_def_default();
    S.def.dim = S.dim = rve->dim;
    S.def.periodic = (1u << rve->dim) - 1u;
    for (k = 0; k < rve->dim; ++k) S.def.hi[k] = rve->cell.h[4 * k];
    S.def.rve = rve->def;
    S.rve = *rve;
    S.seen_rebuilds = -1;
    for (p = 0; p < rve->n; ++p)
        if (rve->id[p] >= S.next_id) S.next_id = rve->id[p] + 1;
    S.mass = (double *)gk_alloc(&rve->def.alloc, (size_t)rve->n * sizeof(double));
    S.flags = (unsigned char *)gk_alloc(&rve->def.alloc, (size_t)rve->n);
    S.cap = rve->n;
    if (!S.mass || !S.flags)
        res = gk_err_set(&S.err, GK_ERR_ALLOC, "wrap: out of memory for %d particles", rve->n);
    for (p = 0; !res && p < rve->n; ++p) {
        S.mass[p] = 1.0 / (double)rve->minv[p];
        S.flags[p] = 0;
    }
    if (!res) res = gk__scene_index(&S);
    if (res) { /* the RVE stays the caller's, untouched */
        gk_err e = S.err;
        gk__scene_free_own(&S);
        out->err = e;
        return res;
    }
    memset(rve, 0, sizeof *rve);
    *out = S;
    return GK_OK;
}

GKDEF void gk_scene_unwrap(gk_scene *sc, gk_rve *rve) {
    gk__scene_free_own(sc);
    *rve = sc->rve;
    rve->hook = NULL;
    rve->hook_user = NULL;
    rve->hook_pairs = 0;
    memset(&sc->rve, 0, sizeof sc->rve);
}

/* ------------------------------------------------------------- create */
static gk_result gk__scene_hook(gk_rve *rve, int stage, void *user);
static void gk__forget_weights(gk_scene *sc);
static gk_result gk__check_weights(gk_scene *sc, const double *w);

/* interaction range of the cell lists: 2 r_max + skin */
static double gk__scene_cutoff(const gk_scene *sc) { return 2.0 * sc->rve.rmax + sc->rve.skin; }

/* u brought into [lo, hi) along a periodic axis */
static double gk__sc_wrap(double lo, double hi, double u) {
    return lo + (u - lo) - (hi - lo) * floor((u - lo) / (hi - lo));
}

GKDEF gk_result gk_scene_create(gk_scene *out, const gk_scene_def *def, const gk_packing *pk) {
    gk_scene S;
    gk_packing fr;
    gk_err *err = &out->err;
    gk_result res;
    int dim, k, p;
    double L[3];
    memset(&S, 0, sizeof S);
    gk_err_clear(err);
    if (!def || def->cookie != GK_SCENE_DEF_COOKIE)
        return gk_err_set(err, GK_ERR_ARG, "gk_scene_def not initialised with gk_scene_def_default()");
    if (!pk || !pk->x || !pk->y || !pk->r || pk->n < 1)
        return gk_err_set(err, GK_ERR_ARG, "no particles given");
    dim = def->dim;
    if (dim != 2 && dim != 3) return gk_err_set(err, GK_ERR_ARG, "scene dimension %d (must be 2 or 3)", dim);
    if (pk->dim != dim) return gk_err_set(err, GK_ERR_ARG, "packing is %dD, scene %dD", pk->dim, dim);
    if (def->lost != GK_LOST_ERROR && def->lost != GK_LOST_DELETE)
        return gk_err_set(err, GK_ERR_ARG, "unknown lost-particle policy %d", (int)def->lost);
    for (k = 0; k < 3; ++k)
        if (!isfinite(def->gravity[k]))
            return gk_err_set(err, GK_ERR_NAN, "gravity has a non-finite component");
    if (def->periodic & ~((1u << dim) - 1u))
        return gk_err_set(err, GK_ERR_ARG, "periodic mask 0x%x names an axis beyond %dD", def->periodic, dim);
    for (k = 0; k < dim; ++k) {
        double D = def->hi[k] - def->lo[k];
        if (!isfinite(def->lo[k]) || !isfinite(def->hi[k]) || !(D > 0.0))
            return gk_err_set(err, GK_ERR_CELL, "domain axis %d: [%g, %g] is not an interval", k, def->lo[k],
                              def->hi[k]);
        /* open axis: a cell four domains long, the domain in its middle half */
        L[k] = (def->periodic & (1u << k)) ? D : 4.0 * D;
        S.origin[k] = (def->periodic & (1u << k)) ? def->lo[k] : def->lo[k] - 1.5 * D;
    }
    S.def = *def;
    S.dim = dim;
    S.open = ~def->periodic & ((1u << dim) - 1u);
    /* the packing in cell coordinates */
    if ((res = gk_packing_init(&fr, dim, pk->n, &def->rve.alloc, err)) != GK_OK) return res;
    gk_m3_identity(fr.h);
    for (k = 0; k < dim; ++k) fr.h[4 * k] = L[k];
    for (p = 0; p < pk->n && !res; ++p) {
        double x[3];
        x[0] = pk->x[p];
        x[1] = pk->y[p];
        x[2] = dim == 3 ? (pk->z ? pk->z[p] : 0.0) : 0.0;
        for (k = 0; k < dim; ++k) {
            double u = x[k];
            if (!isfinite(u)) {
                res = gk_err_set(err, GK_ERR_NAN, "particle %d has a non-finite position", p);
                break;
            }
            if (def->periodic & (1u << k)) {
                u = gk__sc_wrap(def->lo[k], def->hi[k], u);
            } else if (u < def->lo[k] || u > def->hi[k]) {
                res = gk_err_set(err, GK_ERR_OUTSIDE,
                                 "particle %d at %g on axis %d is outside the domain [%g, %g]", p, u, k,
                                 def->lo[k], def->hi[k]);
                break;
            }
            x[k] = u - S.origin[k];
        }
        fr.x[p] = x[0];
        fr.y[p] = x[1];
        fr.z[p] = x[2];
        fr.r[p] = pk->r[p];
    }
    if (!res) {
        res = gk_rve_create(&S.rve, &def->rve, &fr);
        if (res) gk_err_set(err, res, "%s", S.rve.err.msg);
    }
    gk_packing_free(&fr);
    if (res) return res;
    for (k = 0; k < dim; ++k)
        if (!(def->periodic & (1u << k)) &&
            !(0.5 * (def->hi[k] - def->lo[k]) > gk__scene_cutoff(&S) + S.rve.skin)) {
            gk_rve_destroy(&S.rve);
            return gk_err_set(
                err, GK_ERR_CELL,
                "open axis %d: the domain (%g) must be longer than twice the interaction range plus "
                "the skin, %g",
                k, def->hi[k] - def->lo[k], gk__scene_cutoff(&S) + S.rve.skin);
        }
    S.rve.cells.open = S.open;
    S.rve.outer_valid = 0;
    S.rve.need_rebuild = 1;
    S.rve.hook = gk__scene_hook;
    S.next_id = S.rve.n;
    S.seen_rebuilds = -1;
    S.err = *err;
    gk_rve_update_totals(&S.rve); /* from the arrays, as after every count change */
    S.mass = (double *)gk_alloc(&def->rve.alloc, (size_t)S.rve.n * sizeof(double));
    S.flags = (unsigned char *)gk_alloc(&def->rve.alloc, (size_t)S.rve.n);
    if (!S.mass || !S.flags) res = gk_err_set(err, GK_ERR_ALLOC, "out of memory for %d particles", S.rve.n);
    S.cap = S.rve.n;
    if (!res) {
        for (p = 0; p < S.rve.n; ++p) {
            S.mass[p] = 1.0 / (double)S.rve.minv[p];
            S.flags[p] = 0;
        }
        res = gk__scene_index(&S);
    }
    if (res) {
        gk_err e = S.err.code ? S.err : *err;
        gk_scene_destroy(&S);
        *err = e;
        return res;
    }
    *out = S;
    return GK_OK;
}

/* ------------------------------------------------------------- walls */
static double gk__dot3(const double a[3], const double b[3]) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* nearest surface point c of wall W to x; n (unit) from the surface towards
 * x; returns the distance from the surface to x (signed for a plane) */
static double gk__wall_geom(const gk_wall *W, int dim, const double x[3], double c[3], double n[3]) {
    const gk_wall_def *d = &W->def;
    double u[3], dist = 0.0, l2;
    int k;
    GK_UNROLL
    for (k = 0; k < 3; ++k) u[k] = k < dim ? x[k] - W->pos[k] : 0.0;
    switch (d->kind) {
    case GK_WALL_PLANE:
        dist = gk__dot3(u, d->normal);
        GK_UNROLL
        for (k = 0; k < 3; ++k) {
            n[k] = d->normal[k];
            c[k] = x[k] - dist * n[k];
        }
        return dist;
    case GK_WALL_SEGMENT:
    case GK_WALL_RECT: {
        double t1 = gk__dot3(u, d->e1) / gk__dot3(d->e1, d->e1), t2 = 0.0;
        t1 = gk_clamp(t1, 0.0, 1.0);
        if (d->kind == GK_WALL_RECT) t2 = gk_clamp(gk__dot3(u, d->e2) / gk__dot3(d->e2, d->e2), 0.0, 1.0);
        GK_UNROLL
        for (k = 0; k < 3; ++k) {
            c[k] = W->pos[k] + t1 * d->e1[k] + t2 * d->e2[k];
            n[k] = k < dim ? x[k] - c[k] : 0.0;
        }
        break;
    }
    default: { /* disk, cylinder */
        double a = d->kind == GK_WALL_CYLINDER ? gk__dot3(u, d->axis) : 0.0, rho;
        GK_UNROLL
        for (k = 0; k < 3; ++k) n[k] = u[k] - (d->kind == GK_WALL_CYLINDER ? a * d->axis[k] : 0.0);
        rho = sqrt(gk__dot3(n, n));
        if (!(rho > 0.0)) { /* on the axis: any radial direction */
            n[0] = 1.0;
            n[1] = n[2] = 0.0;
            if (d->kind == GK_WALL_CYLINDER && fabs(d->axis[0]) > 0.9) {
                n[0] = 0.0;
                n[1] = 1.0;
            }
            rho = 0.0;
        } else {
            GK_UNROLL
            for (k = 0; k < 3; ++k) n[k] /= rho;
        }
        GK_UNROLL
        for (k = 0; k < 3; ++k) c[k] = x[k] - (rho - d->radius) * n[k];
        if (d->inside) {
            GK_UNROLL
            for (k = 0; k < 3; ++k) n[k] = -n[k];
            return d->radius - rho;
        }
        return rho - d->radius;
    }
    }
    l2 = gk__dot3(n, n);
    dist = sqrt(l2);
    if (dist > 0.0) {
        GK_UNROLL
        for (k = 0; k < 3; ++k) n[k] /= dist;
    } else { /* centre on the wall: normal of the wall's plane */
        double e[3];
        if (d->kind == GK_WALL_RECT) {
            gk_v3_cross(d->e1, d->e2, e);
        } else {
            e[0] = -d->e1[1];
            e[1] = d->e1[0];
            e[2] = 0.0;
        }
        l2 = sqrt(gk__dot3(e, e));
        GK_UNROLL
        for (k = 0; k < 3; ++k) n[k] = e[k] / l2;
    }
    return dist;
}

/* constants of a contact with wall W for a particle of radius r: the twin
 * (radius r, mass m) stands for a rigid surface of effective radius R* */
static void gk__wall_consts(const gk_wall *W, double r, gk_law_consts *K) {
    double s = 2.0; /* R* / (r / 2): plane, segment, rectangle */
    *K = W->K;
    if (W->def.kind == GK_WALL_DISK || W->def.kind == GK_WALL_CYLINDER) {
        double R = W->def.radius;
        s = W->def.inside ? 2.0 * R / (R - r) : 2.0 * R / (R + r);
        if (W->def.mat.law == GK_LAW_LINEAR) {
            K->young = (gk_real)(W->def.mat.young * s);
        } else {
            double q = sqrt(s / 2.0); /* W->K already holds the plane's sqrt(2) */
            K->hn = (gk_real)((double)W->K.hn * q);
            K->ht = (gk_real)((double)W->K.ht * q);
        }
    }
}

static gk_result gk__wall_check(gk_scene *sc, const gk_wall_def *d) {
    int dim = sc->dim, k;
    gk_err *e = &sc->err;
    gk_result r;
    double nn;
    for (k = 0; k < 3; ++k)
        if (!isfinite(d->point[k]) || !isfinite(d->normal[k]) || !isfinite(d->e1[k]) || !isfinite(d->e2[k]) ||
            !isfinite(d->axis[k]) || !isfinite(d->velocity[k]) || !isfinite(d->spin[k]))
            return gk_err_set(e, GK_ERR_NAN, "wall: a non-finite vector");
    if ((r = gk_material_check(&d->mat, e)) != GK_OK) return r;
    if ((d->mat.coh_n > 0.0 || d->mat.coh_t > 0.0))
        return gk_err_set(e, GK_ERR_UNSUPPORTED, "wall: cohesive wall contacts are not implemented");
    if ((gk_material_flags(&d->mat) & GK_PHYS_ROLLING) && !(sc->rve.phys & GK_PHYS_ROTATION))
        return gk_err_set(e, GK_ERR_ARG, "wall: rolling resistance needs rotating particles");
    switch (d->kind) {
    case GK_WALL_PLANE:
        nn = gk__dot3(d->normal, d->normal);
        if (fabs(nn - 1.0) > 1e-9)
            return gk_err_set(e, GK_ERR_ARG, "wall: plane normal must be a unit vector");
        break;
    case GK_WALL_SEGMENT:
        if (dim != 2) return gk_err_set(e, GK_ERR_ARG, "wall: a segment is 2D (use a rectangle in 3D)");
        if (!(gk__dot3(d->e1, d->e1) > 0.0)) return gk_err_set(e, GK_ERR_ARG, "wall: segment of zero length");
        break;
    case GK_WALL_RECT:
        if (dim != 3) return gk_err_set(e, GK_ERR_ARG, "wall: a rectangle is 3D (use a segment in 2D)");
        if (!(gk__dot3(d->e1, d->e1) > 0.0) || !(gk__dot3(d->e2, d->e2) > 0.0) ||
            fabs(gk__dot3(d->e1, d->e2)) > 1e-9 * sqrt(gk__dot3(d->e1, d->e1) * gk__dot3(d->e2, d->e2)))
            return gk_err_set(e, GK_ERR_ARG, "wall: rectangle edges must be non-zero and orthogonal");
        break;
    case GK_WALL_DISK:
    case GK_WALL_CYLINDER:
        if ((d->kind == GK_WALL_DISK) != (dim == 2))
            return gk_err_set(e, GK_ERR_ARG, "wall: a disk is 2D, a cylinder 3D");
        if (!(d->radius > 0.0) || !isfinite(d->radius))
            return gk_err_set(e, GK_ERR_ARG, "wall: radius %g must be > 0", d->radius);
        if (d->inside && !(d->radius > sc->rve.rmax))
            return gk_err_set(e, GK_ERR_ARG, "wall: a drum of radius %g cannot hold particles of radius %g",
                              d->radius, sc->rve.rmax);
        if (d->kind == GK_WALL_CYLINDER && fabs(gk__dot3(d->axis, d->axis) - 1.0) > 1e-9)
            return gk_err_set(e, GK_ERR_ARG, "wall: cylinder axis must be a unit vector");
        break;
    default: return gk_err_set(e, GK_ERR_ARG, "wall: unknown kind %d", (int)d->kind);
    }
    if (d->kind != GK_WALL_DISK && d->kind != GK_WALL_CYLINDER && (d->spin[0] || d->spin[1] || d->spin[2]))
        return gk_err_set(e, GK_ERR_ARG, "wall: only a disk or a cylinder spins");
    if (dim == 2 && (d->velocity[2] != 0.0 || d->spin[0] != 0.0 || d->spin[1] != 0.0 || d->normal[2] != 0.0))
        return gk_err_set(e, GK_ERR_ARG, "wall: 2D vectors must have zero z (spin: only z)");
    if (d->drive == GK_DRIVE_FORCE || d->drive == GK_DRIVE_STRESS) {
        if (!isfinite(d->target)) return gk_err_set(e, GK_ERR_NAN, "wall servo: non-finite target");
        if (!(d->max_speed > 0.0) || !isfinite(d->max_speed))
            return gk_err_set(e, GK_ERR_ARG, "wall servo: max_speed %g must be > 0", d->max_speed);
        if (!(d->gain >= 0.0 && d->gain <= 1.0))
            return gk_err_set(e, GK_ERR_ARG, "wall servo: gain %g outside [0, 1]", d->gain);
        if (fabs(gk__dot3(d->normal, d->normal) - 1.0) > 1e-9)
            return gk_err_set(e, GK_ERR_ARG,
                              "wall servo: normal (the servo direction) must be a unit vector");
        if (d->drive == GK_DRIVE_STRESS && (!(d->area > 0.0) || !isfinite(d->area)))
            return gk_err_set(e, GK_ERR_ARG, "wall servo: stress target needs area > 0 (got %g)", d->area);
    } else if (d->drive != GK_DRIVE_VELOCITY) {
        return gk_err_set(e, GK_ERR_ARG, "wall: unknown drive %d", (int)d->drive);
    }
    return GK_OK;
}

/* critical time step of the stiffest wall contact (Guo & Zhao 2014 eq 19 with the
 * wall's k_n; Hertz at twice the largest current overlap, >= 1e-3 r_min) */
static double gk__walls_dt_critical(const gk_scene *sc) {
    double dtc = 1e300;
    int w;
    for (w = 0; w < sc->nwalls; ++w) {
        const gk_wall *W = &sc->walls[w];
        gk_law_consts K;
        gk_real kn, fn, kt;
        double d = 2.0 * W->dmax, r = sc->rve.rmax;
        if (d < 1e-3 * sc->rve.rmin) d = 1e-3 * sc->rve.rmin;
        gk__wall_consts(W, W->def.inside ? r : 0.0,
                        &K); /* outside: the flattest is a plane; inside: the tightest */
        gk_contact_stiffness(&K, W->def.mat.law, (gk_real)r, (gk_real)r, (gk_real)d, &kn, &fn, &kt);
        if (kn > 0 && sqrt(sc->rve.mmin / (double)kn) < dtc) dtc = sqrt(sc->rve.mmin / (double)kn);
    }
    return dtc;
}

GKDEF void gk_scene_stress(const gk_scene *sc, double volume, double sigma[9]) {
    double V = volume * (sc->dim == 2 ? sc->rve.volume_factor : 1.0), Vc = gk_rve_volume(&sc->rve);
    int k;
    for (k = 0; k < 9; ++k) sigma[k] = (sc->rve.stress[k] * Vc + sc->wall_love[k]) / V;
}

GKDEF gk_result gk_scene_stress_box(gk_scene *sc, const double lo[3], const double hi[3], double sigma[9]) {
    double acc[9] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}, V = 1.0;
    int k, c = 0, dim = sc->dim;
    gk_rve_contact ct;
    if (!lo || !hi || !sigma) return gk_err_set(&sc->err, GK_ERR_ARG, "stress box: NULL argument");
    for (k = 0; k < dim; ++k) {
        if (!(isfinite(lo[k]) && isfinite(hi[k]) && lo[k] < hi[k]))
            return gk_err_set(&sc->err, GK_ERR_ARG, "stress box: axis %d: need finite lo < hi (lo %g, hi %g)",
                              k, lo[k], hi[k]);
        V *= hi[k] - lo[k];
    }
    if (dim == 2) V *= sc->rve.volume_factor;
    while (gk_rve_contact_next(&sc->rve, &c, &ct)) {
        double x[3];
        int p = gk_scene_index(sc, ct.i), inside = 1, a, b;
        if (p < 0) continue;
        gk_scene_position(sc, p, x);
        for (k = 0; k < dim; ++k) {
            double m = x[k] + 0.5 * ct.d[k];
            if (sc->def.periodic & (1u << k)) m = gk__sc_wrap(sc->def.lo[k], sc->def.hi[k], m);
            if (!(m >= lo[k] && m < hi[k])) inside = 0;
        }
        if (!inside) continue;
        for (a = 0; a < 3; ++a)
            for (b = 0; b < 3; ++b) acc[3 * a + b] -= ct.f[a] * ct.d[b];
    }
    for (k = 0; k < 9; ++k) sigma[k] = acc[k] / V;
    return GK_OK;
}

/* after a change that can lower the critical step (a stiffer wall, a lighter particle): an
 * automatic dt (def.rve.dt = 0) follows it down to dt_factor x the critical step; 0 if an explicit
 * dt is above it (the caller undoes its change), and *dtc that critical step */
static int gk__scene_dt_holds(gk_scene *sc, double *dtc) {
    *dtc = gk_scene_dt_critical(sc);
    if (sc->def.rve.dt > 0.0) return !(sc->rve.dt > *dtc);
    {
        double f = sc->def.rve.dt_factor > 0.0 ? sc->def.rve.dt_factor : 0.5;
        if (f * *dtc < sc->rve.dt) sc->rve.dt = f * *dtc;
    }
    return 1;
}

GKDEF double gk_scene_dt_critical(const gk_scene *sc) {
    double a = gk_rve_dt_critical(&sc->rve), b = gk__walls_dt_critical(sc);
    return a < b ? a : b;
}

GKDEF gk_result gk_scene_add_wall(gk_scene *sc, const gk_wall_def *wd, int *index) {
    gk_wall W;
    gk_result r;
    int k;
    size_t n = (size_t)sc->cap, R = sizeof(gk_real);
    double dtc;
    if (!wd) return gk_err_set(&sc->err, GK_ERR_ARG, "no wall given");
    if ((r = gk__wall_check(sc, wd)) != GK_OK) return r;
    memset(&W, 0, sizeof W);
    W.def = *wd;
    for (k = 0; k < 3; ++k) W.pos[k] = wd->point[k];
    gk_law_consts_make(&wd->mat, &W.K);
    /* a plane: R* = r for the twin's r/2 */
    if (wd->mat.law == GK_LAW_LINEAR) {
        W.K.young = (gk_real)(2.0 * wd->mat.young);
    } else {
        W.K.hn = (gk_real)(sqrt(2.0) * (double)W.K.hn);
        W.K.ht = (gk_real)(sqrt(2.0) * (double)W.K.ht);
    }
    W.K.zn2 = (gk_real)(sqrt(2.0) * 2.0 * wd->mat.zeta_n);
    W.K.zt2 = (gk_real)(sqrt(2.0) * 2.0 * wd->mat.zeta_t);
    W.phys = gk_material_flags(&wd->mat) | (sc->rve.phys & GK_PHYS_ROTATION);
    W.need_build = 1;
    for (k = 0; k < 3; ++k) {
        if (k < (sc->dim == 2 ? 1 : 3) && (W.phys & GK_PHYS_TANGENT)) {
            W.ft[k] = (gk_real *)gk_alloc(gk__sc_alloc(sc), n * R);
            if (!W.ft[k])
                r = GK_ERR_ALLOC;
            else
                memset(W.ft[k], 0, n * R);
        }
        if ((sc->dim == 3 || k == 0) && (W.phys & GK_PHYS_ROLLING)) {
            W.mr[k] = (gk_real *)gk_alloc(gk__sc_alloc(sc), n * R);
            if (!W.mr[k])
                r = GK_ERR_ALLOC;
            else
                memset(W.mr[k], 0, n * R);
        }
    }
    W.cs = (unsigned char *)gk_alloc(gk__sc_alloc(sc), n);
    if (!W.cs)
        r = GK_ERR_ALLOC;
    else
        memset(W.cs, 0, n);
    if (!r && sc->nwalls == sc->capwalls) {
        int cap = sc->capwalls ? 2 * sc->capwalls : 8;
        if (gk_realloc(gk__sc_alloc(sc), (void **)&sc->walls, (size_t)sc->nwalls, (size_t)cap,
                       sizeof(gk_wall)))
            r = GK_ERR_ALLOC;
        else
            sc->capwalls = cap;
    }
    if (r) {
        gk__wall_free(sc, &W);
        return gk_err_set(&sc->err, GK_ERR_ALLOC, "out of memory for a wall");
    }
    sc->walls[sc->nwalls++] = W;
    /* the time step must hold for the wall's contacts too */
    if (!gk__scene_dt_holds(sc, &dtc)) {
        gk__wall_free(sc, &sc->walls[--sc->nwalls]);
        return gk_err_set(
            &sc->err, GK_ERR_DT,
            "time step %g s is above the critical %g s of this wall's contacts (Guo & Zhao 2014 eq 19)",
            sc->rve.dt, dtc);
    }
    if (index) *index = sc->nwalls - 1;
    return GK_OK;
}

GKDEF gk_result gk_scene_add_box(gk_scene *sc, const gk_material *m, unsigned faces, int *first) {
    int k, side, f0 = sc->nwalls;
    gk_result r;
    if (!m) return gk_err_set(&sc->err, GK_ERR_ARG, "box: no material given");
    for (k = 0; k < sc->dim; ++k)
        for (side = 0; side < 2; ++side) {
            gk_wall_def d = gk_wall_def_default();
            if (!(faces & (1u << (2 * k + side))) || !(sc->open & (1u << k))) continue;
            d.mat = *m;
            d.point[k] = side ? sc->def.hi[k] : sc->def.lo[k];
            d.normal[k] = side ? -1.0 : 1.0;
            if ((r = gk_scene_add_wall(sc, &d, NULL)) != GK_OK) return r;
        }
    if (first) *first = f0;
    return GK_OK;
}

/* candidate particles of wall W: within 2 skin_in of its surface */
static gk_result gk__wall_build(gk_scene *sc, gk_wall *W) {
    int p, n = sc->rve.n, k;
    double margin = 2.0 * sc->rve.skin_in;
    W->ncand = 0;
    for (p = 0; p < n; ++p) {
        double x[3], c[3], nn[3];
        gk_scene_position(sc, p, x);
        if (gk__wall_geom(W, sc->dim, x, c, nn) - (double)sc->rve.r[p] < margin ||
            (W->cs[p] & GK_CS_CONTACT)) {
            if (W->ncand == W->capcand) {
                int cap = W->capcand ? 2 * W->capcand : 64;
                if (gk_realloc(gk__sc_alloc(sc), (void **)&W->cand, (size_t)W->ncand, (size_t)cap,
                               sizeof(int32_t)))
                    return gk_err_set(&sc->err, GK_ERR_ALLOC, "out of memory for wall contacts");
                W->capcand = cap;
            }
            W->cand[W->ncand++] = p;
        }
    }
    for (k = 0; k < 3; ++k) W->built[k] = W->pos[k];
    W->built_rebuilds = sc->rve.rebuilds;
    W->need_build = 0;
    return GK_OK;
}

/* ------------------------------------------------------------- energy helpers */
/* elastic energy of one contact: normal spring (overlap delta) returned,
 * tangential spring ft and rolling spring mr in *rest, with the law's
 * current stiffnesses */
static double gk__contact_elastic(const gk_law_consts *K, gk_law law, unsigned fl, int dim, gk_real ri,
                                  gk_real rj, gk_real delta, const gk_real *ft, const gk_real *mr,
                                  double *rest) {
    gk_real kn, fn, kt;
    double e, t2 = 0.0, m2 = 0.0;
    int k, nh = dim == 2 ? 1 : 3;
    gk_contact_stiffness(K, law, ri, rj, delta, &kn, &fn, &kt);
    e = law == GK_LAW_LINEAR ? 0.5 * (double)fn * (double)delta : 0.4 * (double)fn * (double)delta;
    *rest = 0.0;
    if ((fl & GK_PHYS_TANGENT) && kt > 0) {
        for (k = 0; k < nh; ++k) t2 += (double)ft[k] * (double)ft[k];
        *rest += t2 / (2.0 * (double)kt);
    }
    if ((fl & GK_PHYS_ROLLING) && mr) {
        double kr = (double)K->beta * (double)kt * (double)ri * (double)rj;
        for (k = 0; k < nh; ++k) m2 += (double)mr[k] * (double)mr[k];
        if (kr > 0) *rest += m2 / (2.0 * kr);
    }
    return e;
}

/* One contact evaluated with the law from its old history (writes the new
 * history to ft, mr, cs: what the kernel wrote) and, with `energy`, its
 * books: elastic energy after the step (normal; tangential + rolling in
 * rest), and for the step's dissipation the forces it applied (kept in a
 * record and priced at the mean velocities once the leap-frog update is
 * known), the tangential dashpot's work at the old velocities and the slip
 * estimate of Coulomb sliding (F_t times (F_trial - F_t) / k_t: the check
 * on the friction the records give). */
typedef struct gk__cterm {
    double elastic, rest, visc_t, slip, fvn, n[3];
    gk_contact_out o;
} gk__cterm;

/* the forces of one contact for the books: i, j particles (i < 0: wall
 * -1 - i, moving at vs at the contact), normal n (i to j), normal dashpot
 * force fvn (on j, along n), tangential force ft (on j), torques ti, tj */
typedef struct gk__erec {
    int32_t i, j;
    double n[3], fvn, ft[3], ti[3], tj[3], vs[3];
} gk__erec;

static void gk__contact_terms(const gk_law_consts *K, gk_law law, unsigned fl, int dim, const gk_real d[3],
                              gk_real ri, gk_real rj, gk_real mi, gk_real mj, const gk_real v[3],
                              const gk_real wi[3], const gk_real wj[3], gk_real dt, int energy, gk_real *ft,
                              gk_real *mr, unsigned char *cs, gk__cterm *t) {
    gk_real ft0[3], mr0[3], dummy[3] = {0, 0, 0}, kn, fn, kt;
    unsigned char cs0 = *cs;
    int k, nh = dim == 2 ? 1 : 3, in;
    double dist;
    for (k = 0; k < 3; ++k) {
        ft0[k] = ft[k];
        mr0[k] = mr ? mr[k] : 0;
    }
    t->elastic = t->rest = t->visc_t = t->slip = t->fvn = 0.0;
    if (dim == 2)
        in = gk_contact_2d(K, law, fl, d[0], d[1], ri, rj, mi, mj, v[0], v[1], wi[2], wj[2], dt, ft,
                           (fl & GK_PHYS_ROLLING) ? mr : dummy, cs, &t->o);
    else
        in = gk_contact_3d(K, law, fl, d, ri, rj, mi, mj, v, wi, wj, dt, ft,
                           (fl & GK_PHYS_ROLLING) ? mr : dummy, cs, &t->o);
    if (!in || !energy) return;
    gk_contact_stiffness(K, law, ri, rj, t->o.delta, &kn, &fn, &kt);
    t->elastic = gk__contact_elastic(K, law, fl, dim, ri, rj, t->o.delta, ft, mr, &t->rest);
    dist = (double)(ri + rj) - (double)t->o.delta;
    for (k = 0; k < 3; ++k) t->n[k] = k < dim ? (double)d[k] / dist : 0.0;
    t->fvn = (double)t->o.fn - (double)fn;
    if ((fl & GK_PHYS_VISCOUS) && (fl & GK_PHYS_TANGENT) && kt > 0) {
        double mstar = (double)((mi * mj) / (mi + mj)), gt = (double)K->zt2 * sqrt(mstar * (double)kt),
               tot[3], q = 0.0;
        for (k = 0; k < 3; ++k) tot[k] = (double)t->o.f[k] - (double)t->o.fn * t->n[k];
        if (dim == 2) { /* spring minus total along t = (-ny, nx) */
            double fv2 = (double)ft[0] - (-tot[0] * t->n[1] + tot[1] * t->n[0]);
            q = fv2 * fv2;
        } else {
            for (k = 0; k < 3; ++k) q += ((double)ft[k] - tot[k]) * ((double)ft[k] - tot[k]);
        }
        if (gt > 0) t->visc_t = q / gt * (double)dt;
    }
    if (((fl & GK_PHYS_TANGENT) && (*cs & GK_CS_SLIDING)) || (fl & GK_PHYS_ROLLING)) {
        /* the trial springs without the Coulomb caps: slip = (trial - new) / k */
        gk_law_consts Kf = *K;
        gk_real tf[3], tm[3];
        unsigned char tcs = cs0;
        gk_contact_out o2;
        double s2 = 0.0, f2 = 0.0;
        Kf.mu = (gk_real)INFINITY;
        Kf.eta = (gk_real)INFINITY;
        for (k = 0; k < 3; ++k) {
            tf[k] = ft0[k];
            tm[k] = mr0[k];
        }
        if (dim == 2)
            gk_contact_2d(&Kf, law, fl, d[0], d[1], ri, rj, mi, mj, v[0], v[1], wi[2], wj[2], dt, tf, tm,
                          &tcs, &o2);
        else
            gk_contact_3d(&Kf, law, fl, d, ri, rj, mi, mj, v, wi, wj, dt, tf, tm, &tcs, &o2);
        if ((fl & GK_PHYS_TANGENT) && (*cs & GK_CS_SLIDING) && kt > 0) {
            double tot[3];
            for (k = 0; k < 3; ++k) tot[k] = (double)t->o.f[k] - (double)t->o.fn * t->n[k];
            for (k = 0; k < nh; ++k) s2 += ((double)tf[k] - (double)ft[k]) * ((double)tf[k] - (double)ft[k]);
            for (k = 0; k < 3; ++k) f2 += tot[k] * tot[k];
            t->slip += sqrt(f2) * sqrt(s2) / (double)kt;
        }
        if (fl & GK_PHYS_ROLLING) {
            double kr = (double)K->beta * (double)kt * (double)ri * (double)rj, m2 = 0.0, ds2 = 0.0;
            for (k = 0; k < nh; ++k) {
                m2 += (double)mr[k] * (double)mr[k];
                ds2 += ((double)tm[k] - (double)mr[k]) * ((double)tm[k] - (double)mr[k]);
            }
            if (kr > 0) t->slip += sqrt(m2) * sqrt(ds2) / kr;
        }
    }
}

/* book one evaluated contact: energies now, and its forces for the step's dissipation */
static void gk__book(gk_scene *sc, int32_t i, int32_t j, const gk__cterm *t, const double vs[3]) {
    gk__erec *e;
    int k;
    sc->el_step += t->elastic + t->rest;
    sc->erest_now += t->rest;
    sc->en.viscous += t->visc_t;
    sc->en.friction -= t->visc_t; /* the records price both dashpot and slip; see gk__price_records */
    sc->slip_step += t->slip;
    if (sc->nrec == sc->caprec) {
        size_t cap = sc->caprec ? 2 * sc->caprec : 256;
        if (gk_realloc(gk__sc_alloc(sc), (void **)&sc->rec, sc->nrec, cap, sizeof(gk__erec))) {
            sc->rec_failed = 1;
            return;
        }
        sc->caprec = cap;
    }
    e = (gk__erec *)sc->rec + sc->nrec++;
    e->i = i;
    e->j = j;
    e->fvn = t->fvn;
    for (k = 0; k < 3; ++k) {
        e->n[k] = t->n[k];
        e->ft[k] = (double)t->o.f[k] - (double)t->o.fn * t->n[k];
        e->ti[k] = (double)t->o.ti[k];
        e->tj[k] = (double)t->o.tj[k];
        e->vs[k] = vs ? vs[k] : 0.0;
    }
}

/* the step's contact dissipation from the records, at the mean velocities
 * v_bar = (v_{n-1/2} + v_{n+1/2}) / 2 (the leap-frog's own work): the normal
 * dashpots' work is viscous; what the tangential forces and the torques
 * took out of the particles beyond the change of the tangential and rolling
 * springs' energy is friction (Coulomb and rolling slip, plus the
 * tangential dashpots, moved to viscous at their old-velocity estimate) */
static void gk__price_records(gk_scene *sc) {
    gk_rve *rve = &sc->rve;
    double dt = rve->dt, dvn = 0.0, prest = 0.0;
    size_t c;
    int k;
    for (c = 0; c < sc->nrec; ++c) {
        const gk__erec *e = (const gk__erec *)sc->rec + c;
        double vj[3], vi[3], wj[3], wi[3], dv[3];
        for (k = 0; k < 3; ++k) {
            int j = e->j, i = e->i;
            vj[k] = k < sc->dim ? 0.5 * ((double)rve->v[k][j] + sc->vold[k][j]) : 0.0;
            wj[k] = rve->w[k] ? 0.5 * ((double)rve->w[k][j] + sc->wold[k][j]) : 0.0;
            vi[k] = i >= 0 ? (k < sc->dim ? 0.5 * ((double)rve->v[k][i] + sc->vold[k][i]) : 0.0) : e->vs[k];
            wi[k] = i >= 0 && rve->w[k] ? 0.5 * ((double)rve->w[k][i] + sc->wold[k][i]) : 0.0;
            dv[k] = vj[k] - vi[k];
        }
        dvn += e->fvn * gk__dot3(e->n, dv);
        prest += gk__dot3(e->ft, dv) + gk__dot3(e->ti, wi) + gk__dot3(e->tj, wj);
    }
    sc->en.viscous -= dvn * dt;
    sc->en.friction += -prest * dt - (sc->erest_now - sc->erest_prev);
    sc->erest_prev = sc->erest_now;
}

/* branch vector and relative kinematics of pair c, exactly as the kernels
 * build them (no affine field in a scene) */
static void gk__pair_inputs(const gk_rve *rve, int c, gk_real d[3], gk_real v[3], gk_real wi[3],
                            gk_real wj[3]) {
    int i = rve->pl.i[c], j = rve->pl.j[c], k, dim = rve->dim;
    const double *h = rve->cell.h;
    double ds[3];
    for (k = 0; k < 3; ++k) {
        ds[k] = k < dim ? rve->s[k][j] - rve->s[k][i] : 0.0;
        ds[k] -= rint(ds[k]);
    }
    for (k = 0; k < 3; ++k) {
        d[k] = dim == 2 ? (k < 2 ? (gk_real)(h[3 * k] * ds[0] + h[3 * k + 1] * ds[1]) : 0)
                        : (gk_real)(h[3 * k] * ds[0] + h[3 * k + 1] * ds[1] + h[3 * k + 2] * ds[2]);
        v[k] = k < dim ? rve->v[k][j] - rve->v[k][i] : 0;
        wi[k] = rve->w[k] ? rve->w[k][i] : 0;
        wj[k] = rve->w[k] ? rve->w[k][j] : 0;
    }
}

/* pair contacts: energy terms of this step from the history copied before it */
static void gk__energy_pairs(gk_scene *sc) {
    gk_rve *rve = &sc->rve;
    int c, k, dim = rve->dim, nh = dim == 2 ? 1 : 3;
    gk_real dt = (gk_real)rve->dt;
    for (c = 0; c < rve->pl.n; ++c) {
        gk_real d[3], v[3], wi[3], wj[3], ft[3] = {0, 0, 0}, mr[3] = {0, 0, 0};
        unsigned char cs = sc->hcs[c];
        int i = rve->pl.i[c], j = rve->pl.j[c], same = 1;
        gk__cterm t;
        if (!(cs & GK_CS_CONTACT) && !(rve->cs[c] & GK_CS_CONTACT)) continue;
        for (k = 0; k < nh; ++k) { /* 2D: ft[0], mr[2] of the RVE */
            int mk = dim == 2 ? 2 : k;
            if (sc->hft[k]) ft[k] = sc->hft[k][c];
            if (sc->hmr[mk]) mr[k] = sc->hmr[mk][c];
        }
        gk__pair_inputs(rve, c, d, v, wi, wj);
        gk__contact_terms(&rve->K, rve->def.mat.law, rve->phys, dim, d, rve->r[i], rve->r[j],
                          (gk_real)1 / rve->minv[i], (gk_real)1 / rve->minv[j], v, wi, wj, dt, 1, ft, mr, &cs,
                          &t);
        if (cs != rve->cs[c]) same = 0;
        for (k = 0; k < nh; ++k) {
            if (rve->ft[k] && ft[k] != rve->ft[k][c]) same = 0;
            if ((rve->phys & GK_PHYS_ROLLING) && mr[k] != rve->mr[dim == 2 ? 2 : k][c]) same = 0;
        }
        if (!same) ++sc->energy_mismatch;
        if (cs & GK_CS_CONTACT) gk__book(sc, i, j, &t, NULL);
    }
}

/* ------------------------------------------------------------- wall contacts */
static void gk__wall_contacts(gk_scene *sc, gk_wall *W) {
    gk_rve *rve = &sc->rve;
    int e, k, dim = sc->dim, rot = (rve->phys & GK_PHYS_ROTATION) != 0, nh = dim == 2 ? 1 : 3;
    gk_law law = W->def.mat.law;
    gk_real dt = (gk_real)rve->dt, zero3[3] = {0, 0, 0};
    double F[3] = {0, 0, 0}, M[3] = {0, 0, 0}, K = 0.0, dmax = 0.0, work = 0.0;
    int nc = 0;
    for (e = 0; e < W->ncand; ++e) {
        int p = W->cand[e];
        double x[3], c[3], n[3], dist, r = (double)rve->r[p], vs[3], rel[3];
        gk_law_consts Kc;
        gk_real d[3], v[3], wj[3], ft[3] = {0, 0, 0}, mr[3] = {0, 0, 0}, m = (gk_real)sc->mass[p];
        unsigned char cs = W->cs[p];
        gk__cterm t;
        gk_scene_position(sc, p, x);
        dist = gk__wall_geom(W, dim, x, c, n);
        if (!(dist < r) && !(cs & GK_CS_CONTACT)) continue;
        if (r + dist < 1e-3 * r) dist = 1e-3 * r - r; /* centre through the wall: keep the branch defined */
        /* surface velocity at the contact: translation + spin x (c - centre) */
        GK_UNROLL
        for (k = 0; k < 3; ++k) rel[k] = c[k] - W->pos[k];
        gk_v3_cross(W->def.spin, rel, vs);
        GK_UNROLL
        for (k = 0; k < 3; ++k) {
            vs[k] += W->vel[k];
            if (k >= dim) vs[k] = 0.0;
            d[k] = (gk_real)(n[k] * (r + dist));
            v[k] = k < dim ? (gk_real)((double)rve->v[k][p] - vs[k]) : 0;
            wj[k] = (rot && rve->w[k]) ? rve->w[k][p] : 0;
        }
        GK_UNROLL
        for (k = 0; k < nh; ++k) {
            if (W->ft[k]) ft[dim == 2 ? 0 : k] = W->ft[k][p];
            if (W->mr[k]) mr[dim == 2 ? 0 : k] = W->mr[k][p];
        }
        gk__wall_consts(W, r, &Kc);
        gk__contact_terms(&Kc, law, W->phys, dim, d, (gk_real)r, (gk_real)r, m, m, v, zero3, wj, dt,
                          sc->energy_on, ft, mr, &cs, &t);
        GK_UNROLL
        for (k = 0; k < nh; ++k) {
            if (W->ft[k]) W->ft[k][p] = ft[dim == 2 ? 0 : k];
            if (W->mr[k]) W->mr[k][p] = mr[dim == 2 ? 0 : k];
        }
        W->cs[p] = cs;
        if (!(cs & GK_CS_CONTACT)) continue;
        {
            gk_real kn, fn, kt;
            double arm[3], mp[3], f[3];
            gk_contact_stiffness(&Kc, law, (gk_real)r, (gk_real)r, t.o.delta, &kn, &fn, &kt);
            K += (double)kn;
            if ((double)t.o.delta > dmax) dmax = (double)t.o.delta;
            GK_UNROLL
            for (k = 0; k < 3; ++k) f[k] = k < dim ? (double)t.o.f[k] : 0.0;
            GK_UNROLL
            for (k = 0; k < dim; ++k) rve->f[k][p] += t.o.f[k];
            if (rot) {
                if (dim == 2)
                    rve->t[2][p] += t.o.tj[2];
                else {
                    GK_UNROLL
                    for (k = 0; k < 3; ++k) rve->t[k][p] += t.o.tj[k];
                }
            }
            /* the wall receives -(force) and -(moment of the particle's load about pos) */
            GK_UNROLL
            for (k = 0; k < 3; ++k) arm[k] = x[k] - W->pos[k];
            if (dim == 2) arm[2] = 0.0;
            gk_v3_cross(arm, f, mp);
            GK_UNROLL
            for (k = 0; k < 3; ++k) {
                F[k] -= f[k];
                M[k] -= mp[k] + (dim == 3 || k == 2 ? (double)t.o.tj[k] : 0.0);
            }
            { /* stress: f (x) (x_c - x_p), the contact point at r - delta/2 towards the wall */
                double l = r - 0.5 * (double)t.o.delta;
                int a, b;
                for (a = 0; a < dim; ++a)
                    for (b = 0; b < dim; ++b) sc->wall_love[3 * a + b] += f[a] * (-n[b] * l);
            }
            work += gk__dot3(f, vs) * (double)dt;
            if (sc->energy_on) gk__book(sc, (int32_t)(-1 - (W - sc->walls)), p, &t, vs);
            ++nc;
        }
    }
    GK_UNROLL
    for (k = 0; k < 3; ++k) {
        W->force[k] = F[k];
        W->moment[k] = M[k];
    }
    W->stiffness = K;
    W->ncontacts = nc;
    W->dmax = dmax;
    W->resistance = -gk__dot3(F, W->def.normal);
    if (sc->energy_on) sc->en.walls += work;
}

/* the wall's velocity for the next step: prescribed, or the servo's */
static void gk__wall_drive(gk_scene *sc, gk_wall *W) {
    const gk_wall_def *d = &W->def;
    int k;
    if (d->drive == GK_DRIVE_VELOCITY) {
        for (k = 0; k < 3; ++k) W->vel[k] = d->velocity[k];
    } else {
        double target = d->drive == GK_DRIVE_STRESS ? d->target * d->area : d->target, sp, vn;
        double gain = d->gain > 0.0 ? d->gain : 0.05;
        if (W->stiffness > 0.0)
            sp = gain * (target - W->resistance) / (W->stiffness * sc->rve.dt);
        else
            sp = target > W->resistance ? d->max_speed : -d->max_speed;
        sp = gk_clamp(sp, -d->max_speed, d->max_speed);
        /* plus def.velocity's part across the servo direction (shear under a constant normal load) */
        vn = gk__dot3(d->velocity, d->normal);
        for (k = 0; k < 3; ++k) W->vel[k] = sp * d->normal[k] + d->velocity[k] - vn * d->normal[k];
    }
    if (sc->dim == 2) W->vel[2] = 0.0;
}

/* ------------------------------------------------------------- membranes */
static void gk__membranes(gk_scene *sc) {
    gk_rve *rve = &sc->rve;
    double t = rve->volume_factor, el = 0.0;
    int m, e;
    for (m = 0; m < sc->nmem; ++m) {
        gk_membrane *M = &sc->mem[m];
        for (e = 0; e < M->n; ++e) M->fx[e] = M->fy[e] = 0.0;
        for (e = 0; e + 1 < M->n; ++e) {
            int a = gk_scene_index(sc, M->ids[e]), b = gk_scene_index(sc, M->ids[e + 1]);
            double xa[3], xb[3], ex, ey, L, px, py;
            if (a < 0 || b < 0) continue;
            gk_scene_position(sc, a, xa);
            gk_scene_position(sc, b, xb);
            ex = xb[0] - xa[0];
            ey = xb[1] - xa[1];
            /* follower pressure p t |e| along the inward normal (-ey, ex)/|e|, half on each end */
            px = 0.5 * M->pressure * t * -ey;
            py = 0.5 * M->pressure * t * ex;
            M->fx[e] += px;
            M->fy[e] += py;
            M->fx[e + 1] += px;
            M->fy[e + 1] += py;
            L = sqrt(ex * ex + ey * ey);
            if (M->stiffness > 0.0 && L > M->rest[e]) { /* tension-only link */
                double f = M->stiffness * (L - M->rest[e]), ux = ex / L, uy = ey / L;
                rve->f[0][a] += (gk_real)(f * ux);
                rve->f[1][a] += (gk_real)(f * uy);
                rve->f[0][b] -= (gk_real)(f * ux);
                rve->f[1][b] -= (gk_real)(f * uy);
                el += 0.5 * M->stiffness * (L - M->rest[e]) * (L - M->rest[e]);
                /* stress: an inner force of the particles, f L u (x) u (tension) */
                sc->wall_love[0] += f * L * ux * ux;
                sc->wall_love[1] += f * L * ux * uy;
                sc->wall_love[3] += f * L * uy * ux;
                sc->wall_love[4] += f * L * uy * uy;
            }
        }
        for (e = 0; e < 2 && M->n > 0; ++e) { /* anchors: the segment to the platen and its link */
            int end = e ? M->n - 1 : 0, a = gk_scene_index(sc, M->ids[end]);
            double xa[3], A[3], nw[3], ex, ey, L;
            gk_wall *W;
            M->af[e][0] = M->af[e][1] = 0.0;
            if (M->anchor[e] < 0 || a < 0) continue;
            W = &sc->walls[M->anchor[e]];
            gk_scene_position(sc, a, xa);
            L = gk__wall_geom(W, sc->dim, xa, A, nw); /* A: the member's foot on the wall */
            /* chain order: anchor -> first member, last member -> anchor */
            ex = e ? A[0] - xa[0] : xa[0] - A[0];
            ey = e ? A[1] - xa[1] : xa[1] - A[1];
            M->fx[end] += 0.5 * M->pressure * t * -ey;
            M->fy[end] += 0.5 * M->pressure * t * ex;
            if (M->stiffness > 0.0 && L > M->arest[e]) {
                double f = M->stiffness * (L - M->arest[e]), ux = -nw[0], uy = -nw[1];
                rve->f[0][a] += (gk_real)(f * ux);
                rve->f[1][a] += (gk_real)(f * uy);
                M->af[e][0] = f * ux; /* the wall holds it; not in W->force (its contacts only) */
                M->af[e][1] = f * uy;
                el += 0.5 * M->stiffness * (L - M->arest[e]) * (L - M->arest[e]);
                if (sc->energy_on) sc->en.walls += f * (ux * W->vel[0] + uy * W->vel[1]) * rve->dt;
            }
        }
        for (e = 0; e < M->n; ++e) {
            int a = gk_scene_index(sc, M->ids[e]);
            if (a < 0) continue;
            rve->f[0][a] += (gk_real)M->fx[e];
            rve->f[1][a] += (gk_real)M->fy[e];
        }
    }
    sc->el_step += el;
}

/* ------------------------------------------------------------- the hook */
static gk_result gk__scene_lost(gk_scene *sc) {
    int p, k, nlost = 0;
    double cut = gk__scene_cutoff(sc) + sc->rve.skin;
    for (p = 0; p < sc->rve.n; ++p) {
        double x[3];
        gk_scene_position(sc, p, x);
        for (k = 0; k < sc->dim; ++k) {
            double D = sc->def.hi[k] - sc->def.lo[k], m = 0.5 * D - cut;
            if ((sc->open & (1u << k)) && (x[k] < sc->def.lo[k] - m || x[k] > sc->def.hi[k] + m)) {
                ++nlost;
                break;
            }
        }
    }
    if (nlost) {
        gk_err_set(&sc->rve.err, GK_ERR_OUTSIDE,
                   "%d particle(s) left the open domain at step %ld (def.lost = GK_LOST_DELETE deletes them)",
                   nlost, sc->rve.step);
        return GK_ERR_OUTSIDE;
    }
    return GK_OK;
}

static void gk__copy_history(gk_scene *sc) {
    gk_rve *rve = &sc->rve;
    size_t np = (size_t)rve->pl.n, R = sizeof(gk_real);
    int k;
    if (np + 1 > sc->hcap) {
        size_t cap = np + np / 2 + 64;
        int bad = 0;
        for (k = 0; k < 3; ++k) {
            if (rve->ft[k]) bad |= gk_realloc(gk__sc_alloc(sc), (void **)&sc->hft[k], 0, cap, R) != GK_OK;
            if (rve->mr[k]) bad |= gk_realloc(gk__sc_alloc(sc), (void **)&sc->hmr[k], 0, cap, R) != GK_OK;
        }
        bad |= gk_realloc(gk__sc_alloc(sc), (void **)&sc->hcs, 0, cap, 1) != GK_OK;
        if (bad) return; /* caught by the caller through hcap */
        sc->hcap = cap;
    }
    for (k = 0; k < 3; ++k) {
        /* hft[k] mirrors ft[k]; hmr: 2D mr[2] -> hmr[0] */
        if (rve->ft[k]) memcpy(sc->hft[k], rve->ft[k], np * R);
        if (rve->mr[k] && sc->hmr[k]) memcpy(sc->hmr[k], rve->mr[k], np * R);
    }
    memcpy(sc->hcs, rve->cs, np);
}

static gk_result gk__hook_pre(gk_scene *sc) {
    gk_rve *rve = &sc->rve;
    int w, k;
    gk_result r;
    if (rve->rebuilds != sc->seen_rebuilds) {
        if (sc->open && (r = gk__scene_lost(sc)) != GK_OK) return r;
        sc->seen_rebuilds = rve->rebuilds;
        if (sc->nwalls && gk__walls_dt_critical(sc) < rve->dt)
            return gk_err_set(
                &rve->err, GK_ERR_DT,
                "time step %g s now exceeds the critical %g s of the wall contacts at their current "
                "overlaps: restore a saved state and use a smaller dt",
                rve->dt, gk__walls_dt_critical(sc));
    }
    for (w = 0; w < sc->nwalls; ++w) {
        gk_wall *W = &sc->walls[w];
        double m2 = 0.0;
        for (k = 0; k < 3; ++k) m2 += (W->pos[k] - W->built[k]) * (W->pos[k] - W->built[k]);
        if (W->need_build || W->built_rebuilds != rve->rebuilds || !(m2 < rve->skin_in * rve->skin_in))
            if ((r = gk__wall_build(sc, W)) != GK_OK) return gk_err_set(&rve->err, r, "%s", sc->err.msg);
    }
    if (sc->energy_on) {
        gk__copy_history(sc);
        if (sc->hcap < (size_t)rve->pl.n + 1)
            return gk_err_set(&rve->err, GK_ERR_ALLOC, "out of memory for the energy bookkeeping");
    }
    return GK_OK;
}

/* contact weights: take (1 - s) of each pair's force and moments back off
 * the sums, pair by pair in list order (fixed, whatever the threads) */
static void gk__weigh_contacts(gk_scene *sc) {
    gk_rve *rve = &sc->rve;
    const double *w = sc->cw;
    int c, k, dim = sc->dim, rot = GK__HAS_ROT(rve);
    for (c = 0; c < rve->pl.n; ++c) {
        int i = rve->pl.i[c], j = rve->pl.j[c];
        double d = 1.0 - 0.5 * (w[i] + w[j]);
        if (d == 0.0) continue;
        for (k = 0; k < dim; ++k) { /* fc is the force on j */
            double f = d * (double)rve->fc[k][c];
            rve->f[k][i] = (gk_real)((double)rve->f[k][i] + f);
            rve->f[k][j] = (gk_real)((double)rve->f[k][j] - f);
        }
        if (rot)
            for (k = 0; k < 3; ++k)
                if (rve->t[k]) {
                    rve->t[k][i] = (gk_real)((double)rve->t[k][i] - d * (double)rve->tci[k][c]);
                    rve->t[k][j] = (gk_real)((double)rve->t[k][j] - d * (double)rve->tcj[k][c]);
                }
    }
}

static void gk__hook_post_forces(gk_scene *sc) {
    gk_rve *rve = &sc->rve;
    int n = rve->n, dim = sc->dim, p, k, w, rot = (rve->phys & GK_PHYS_ROTATION) != 0;
    const double *g = sc->def.gravity;
    if (sc->energy_on) {
        for (k = 0; k < dim; ++k)
            for (p = 0; p < n; ++p) sc->vold[k][p] = (double)rve->v[k][p];
        for (k = 0; k < 3; ++k)
            if (rve->w[k])
                for (p = 0; p < n; ++p) sc->wold[k][p] = (double)rve->w[k][p];
        sc->el_step = sc->erest_now = sc->slip_step = 0.0;
        sc->nrec = 0;
        gk__energy_pairs(sc);
    }
    if (sc->cw) gk__weigh_contacts(sc);
    for (k = 0; k < 9; ++k) sc->wall_love[k] = 0.0;
    for (w = 0; w < sc->nwalls; ++w) gk__wall_contacts(sc, &sc->walls[w]);
    if (g[0] != 0.0 || g[1] != 0.0 || g[2] != 0.0)
        for (k = 0; k < dim; ++k)
            if (g[k] != 0.0)
                for (p = 0; p < n; ++p) rve->f[k][p] += (gk_real)(sc->mass[p] * g[k]);
    if (sc->fext[0])
        for (p = 0; p < n; ++p) {
            for (k = 0; k < dim; ++k) rve->f[k][p] += (gk_real)sc->fext[k][p];
            if (rot)
                for (k = 0; k < 3; ++k)
                    if (rve->t[k]) rve->t[k][p] += (gk_real)sc->text[k][p];
        }
    if (sc->nmem) gk__membranes(sc);
    if (sc->energy_on) {
        for (k = 0; k < dim; ++k)
            for (p = 0; p < n; ++p) sc->ftot[k][p] = (double)rve->f[k][p];
        for (k = 0; k < 3; ++k)
            if (rve->t[k])
                for (p = 0; p < n; ++p) sc->ttot[k][p] = (double)rve->t[k][p];
        sc->en.elastic = sc->el_step;
        sc->en.slip += sc->slip_step;
        if (sc->energy_pending) { /* the springs' energy when tracking started */
            sc->en.initial += sc->el_step;
            sc->erest_prev = sc->erest_now;
            sc->energy_pending = 0;
        }
    }
    if (sc->nprescribed)
        for (p = 0; p < n; ++p) {
            if (!(sc->flags[p] & GK_PARTICLE_PRESCRIBED)) continue;
            for (k = 0; k < 3; ++k) {
                sc->load[k][p] = k < dim ? (double)rve->f[k][p] : 0.0;
                sc->loadt[k][p] = rve->t[k] ? (double)rve->t[k][p] : 0.0;
                if (k < dim) {
                    rve->f[k][p] = 0;
                    rve->v[k][p] = (gk_real)sc->vp[k][p];
                }
                if (rve->t[k]) {
                    rve->t[k][p] = 0;
                    rve->w[k][p] = (gk_real)sc->wp[k][p];
                }
            }
        }
    if (sc->nlocked) /* a prescribed spin overrides the lock */
        for (p = 0; p < n; ++p)
            if ((sc->flags[p] & (GK_PARTICLE_LOCKED_ROTATION | GK_PARTICLE_PRESCRIBED)) ==
                GK_PARTICLE_LOCKED_ROTATION)
                for (k = 0; k < 3; ++k)
                    if (rve->t[k]) rve->t[k][p] = rve->w[k][p] = 0;
}

/* kinetic energy at the current (half-step) velocities */
static double gk__kinetic(const gk_scene *sc) { return gk_rve_kinetic_energy(&sc->rve); }

static void gk__hook_post_step(gk_scene *sc) {
    gk_rve *rve = &sc->rve;
    int n = rve->n, dim = sc->dim, p, k, w, m, e;
    double dt = rve->dt;
    if (sc->energy_on) {
        double wg = 0.0, wx = 0.0, wpr = 0.0, dmp = 0.0, wm = 0.0;
        const double *g = sc->def.gravity;
        for (p = 0; p < n; ++p) {
            double mass = sc->mass[p], I = 1.0 / (double)rve->Iinv[p], dke = 0.0, ftv = 0.0, vb[3], wb[3];
            for (k = 0; k < 3; ++k) {
                double vn = k < dim ? (double)rve->v[k][p] : 0.0, vo = k < dim ? sc->vold[k][p] : 0.0;
                double wn = rve->w[k] ? (double)rve->w[k][p] : 0.0, wo = rve->w[k] ? sc->wold[k][p] : 0.0;
                vb[k] = 0.5 * (vn + vo);
                wb[k] = 0.5 * (wn + wo);
                dke += 0.5 * mass * (vn * vn - vo * vo) + 0.5 * I * (wn * wn - wo * wo);
                if (k < dim) ftv += sc->ftot[k][p] * vb[k];
                if (rve->t[k]) ftv += sc->ttot[k][p] * wb[k];
                if (k < dim) wg += mass * g[k] * vb[k] * dt;
                if (sc->fext[0]) wx += (sc->fext[k][p] * vb[k] + sc->text[k][p] * wb[k]) * dt;
            }
            if (sc->flags[p] & GK_PARTICLE_PRESCRIBED)
                wpr += dke - ftv * dt; /* the constraint supplies what the forces do not */
            else
                dmp += ftv * dt - dke; /* local damping: applied force minus effective force */
        }
        for (m = 0; m < sc->nmem; ++m)
            for (e = 0; e < sc->mem[m].n; ++e) {
                int a = gk_scene_index(sc, sc->mem[m].ids[e]);
                if (a >= 0)
                    wm += (sc->mem[m].fx[e] * 0.5 * ((double)rve->v[0][a] + sc->vold[0][a]) +
                           sc->mem[m].fy[e] * 0.5 * ((double)rve->v[1][a] + sc->vold[1][a])) *
                          dt;
            }
        sc->en.gravity += wg;
        sc->en.external += wx;
        sc->en.prescribed += wpr;
        sc->en.damping += dmp;
        sc->en.pressure += wm;
        gk__price_records(sc);
        sc->en.kinetic = gk__kinetic(sc);
        ++sc->en.steps;
    }
    for (w = 0; w < sc->nwalls; ++w) {
        gk_wall *W = &sc->walls[w];
        for (k = 0; k < 3; ++k) W->pos[k] += W->vel[k] * dt;
        W->angle += (sc->dim == 2 ? W->def.spin[2] : sqrt(gk__dot3(W->def.spin, W->def.spin))) * dt;
        gk__wall_drive(sc, W);
    }
}

static gk_result gk__scene_hook(gk_rve *rve, int stage, void *user) {
    gk_scene *sc = (gk_scene *)user;
    if (stage == GK_HOOK_PRE_FORCES) return gk__hook_pre(sc);
    if (stage == GK_HOOK_POST_FORCES)
        gk__hook_post_forces(sc);
    else
        gk__hook_post_step(sc);
    if (sc->rec_failed) {
        sc->rec_failed = 0;
        return gk_err_set(&rve->err, GK_ERR_ALLOC, "out of memory for the energy bookkeeping");
    }
    return GK_OK;
}

/* ------------------------------------------------------------- stepping */
static gk_result gk__scene_delete(gk_scene *sc, const unsigned char *drop);

GKDEF gk_result gk_scene_step(gk_scene *sc, long nsteps) { return gk_scene_step_flags(sc, nsteps, 0); }

GKDEF gk_result gk_scene_step_flags(gk_scene *sc, long nsteps, unsigned flags) {
    gk_result r;
    int w, k;
    long done0;
    if (nsteps < 0) return gk_err_set(&sc->err, GK_ERR_ARG, "step count %ld < 0", nsteps);
    if (flags & ~GK_STEP_NO_STRESS) return gk_err_set(&sc->err, GK_ERR_ARG, "unknown step flags 0x%x", flags);
    for (k = 0; k < 9; ++k)
        if (sc->rve.L[k] != 0.0 || sc->rve.servo_on)
            return gk_err_set(&sc->err, GK_ERR_STATE,
                              "a scene's cell is a fixed frame: no velocity gradient or servo");
    for (w = 0; w < sc->nwalls; ++w) {
        gk_wall *W = &sc->walls[w];
        if ((r = gk__wall_check(sc, &W->def)) != GK_OK) return r;
        if (sc->rve.step == 0 || W->def.drive == GK_DRIVE_VELOCITY) gk__wall_drive(sc, W);
    }
    for (w = 0; w < sc->nmem; ++w)
        if (!isfinite(sc->mem[w].pressure) || !(sc->mem[w].stiffness >= 0.0) ||
            !isfinite(sc->mem[w].stiffness))
            return gk_err_set(&sc->err, GK_ERR_ARG, "membrane %d: pressure %g / stiffness %g invalid", w,
                              sc->mem[w].pressure, sc->mem[w].stiffness);
    if (sc->cw && (r = gk__check_weights(sc, sc->cw)) != GK_OK) return r;
    sc->rve.hook = gk__scene_hook;
    sc->rve.hook_user = sc; /* the scene may have moved since the last call */
    sc->rve.hook_pairs = sc->cw != NULL;
    done0 = sc->rve.step;
    while (sc->rve.step - done0 < nsteps) {
        r = gk_rve_step_flags(&sc->rve, nsteps - (sc->rve.step - done0), flags);
        if (r == GK_ERR_OUTSIDE && sc->def.lost == GK_LOST_DELETE) {
            /* delete what left the domain and redo the step (nothing else moved) */
            unsigned char *drop = (unsigned char *)gk_alloc(gk__sc_alloc(sc), (size_t)sc->rve.n);
            double cut = gk__scene_cutoff(sc) + sc->rve.skin;
            int p, nd = 0;
            if (!drop) return gk_err_set(&sc->err, GK_ERR_ALLOC, "out of memory deleting lost particles");
            for (p = 0; p < sc->rve.n; ++p) {
                double x[3];
                gk_scene_position(sc, p, x);
                drop[p] = 0;
                for (k = 0; k < sc->dim; ++k) {
                    double D = sc->def.hi[k] - sc->def.lo[k], m = 0.5 * D - cut;
                    if ((sc->open & (1u << k)) && (x[k] < sc->def.lo[k] - m || x[k] > sc->def.hi[k] + m))
                        drop[p] = 1;
                }
                nd += drop[p];
            }
            r = nd ? gk__scene_delete(sc, drop) : gk__scene_rve_err(sc, GK_ERR_OUTSIDE);
            gk__sc_free(sc, drop);
            if (r) return r;
            sc->lost += nd;
            sc->seen_rebuilds = -1;
            continue;
        }
        if (r) return gk__scene_rve_err(sc, r);
    }
    return GK_OK;
}

/* ------------------------------------------------------------- per particle */
static gk_result gk__scene_p(gk_scene *sc, int p) {
    if (p < 0 || p >= sc->rve.n)
        return gk_err_set(&sc->err, GK_ERR_ARG, "particle index %d outside [0, %d)", p, sc->rve.n);
    return GK_OK;
}

static int gk__finite3(const double *a) { return !a || (isfinite(a[0]) && isfinite(a[1]) && isfinite(a[2])); }

GKDEF gk_result gk_scene_set_external(gk_scene *sc, int p, const double f[3], const double t[3]) {
    int k;
    gk_result r;
    if ((r = gk__scene_p(sc, p)) != GK_OK) return r;
    if (!gk__finite3(f) || !gk__finite3(t))
        return gk_err_set(&sc->err, GK_ERR_NAN, "external load: non-finite value");
    for (k = 0; k < 3; ++k)
        if ((r = gk__sc_new(sc, &sc->fext[k])) != GK_OK || (r = gk__sc_new(sc, &sc->text[k])) != GK_OK)
            return r;
    for (k = 0; k < 3; ++k) {
        sc->fext[k][p] = f && k < sc->dim ? f[k] : 0.0;
        sc->text[k][p] = t && (sc->dim == 3 || k == 2) ? t[k] : 0.0;
    }
    return GK_OK;
}

GKDEF gk_result gk_scene_prescribe(gk_scene *sc, int p, const double v[3], const double w[3]) {
    int k;
    gk_result r;
    if ((r = gk__scene_p(sc, p)) != GK_OK) return r;
    if (!gk__finite3(v) || !gk__finite3(w))
        return gk_err_set(&sc->err, GK_ERR_NAN, "prescribed motion: non-finite value");
    for (k = 0; k < 3; ++k)
        if ((r = gk__sc_new(sc, &sc->vp[k])) != GK_OK || (r = gk__sc_new(sc, &sc->wp[k])) != GK_OK ||
            (r = gk__sc_new(sc, &sc->load[k])) != GK_OK || (r = gk__sc_new(sc, &sc->loadt[k])) != GK_OK)
            return r;
    for (k = 0; k < 3; ++k) {
        sc->vp[k][p] = v && k < sc->dim ? v[k] : 0.0;
        sc->wp[k][p] = w && (sc->dim == 3 || k == 2) ? w[k] : 0.0;
    }
    if (!(sc->flags[p] & GK_PARTICLE_PRESCRIBED)) ++sc->nprescribed;
    sc->flags[p] |= GK_PARTICLE_PRESCRIBED;
    return GK_OK;
}

GKDEF gk_result gk_scene_release(gk_scene *sc, int p) {
    gk_result r;
    if ((r = gk__scene_p(sc, p)) != GK_OK) return r;
    if (sc->flags[p] & GK_PARTICLE_PRESCRIBED) --sc->nprescribed;
    sc->flags[p] &= (unsigned char)~GK_PARTICLE_PRESCRIBED;
    return GK_OK;
}

GKDEF gk_result gk_scene_lock_rotation(gk_scene *sc, int p, int locked) {
    gk_result r;
    if ((r = gk__scene_p(sc, p)) != GK_OK) return r;
    if (locked != 0 && locked != 1)
        return gk_err_set(&sc->err, GK_ERR_ARG, "lock_rotation: locked %d is not 0 or 1", locked);
    if (locked && !(sc->flags[p] & GK_PARTICLE_LOCKED_ROTATION)) ++sc->nlocked;
    if (!locked && (sc->flags[p] & GK_PARTICLE_LOCKED_ROTATION)) --sc->nlocked;
    if (locked)
        sc->flags[p] |= GK_PARTICLE_LOCKED_ROTATION;
    else
        sc->flags[p] &= (unsigned char)~GK_PARTICLE_LOCKED_ROTATION;
    return GK_OK;
}

GKDEF gk_result gk_scene_set_mass(gk_scene *sc, int p, double m, double I) {
    gk_result r;
    gk_real minv0, Iinv0;
    double mass0, dtc;
    if ((r = gk__scene_p(sc, p)) != GK_OK) return r;
    minv0 = sc->rve.minv[p], Iinv0 = sc->rve.Iinv[p], mass0 = sc->mass[p];
    if (!(m > 0.0) || !(I > 0.0) || !isfinite(m) || !isfinite(I))
        return gk_err_set(&sc->err, GK_ERR_MASS, "mass %g and inertia %g must be > 0", m, I);
    sc->rve.minv[p] = (gk_real)(1.0 / m);
    sc->rve.Iinv[p] = (gk_real)(1.0 / I);
    sc->mass[p] = 1.0 / (double)sc->rve.minv[p];
    gk_rve_update_totals(&sc->rve);
    /* the time step must hold for the lighter particle too (as for a new wall) */
    if (!gk__scene_dt_holds(sc, &dtc)) {
        sc->rve.minv[p] = minv0, sc->rve.Iinv[p] = Iinv0, sc->mass[p] = mass0;
        gk_rve_update_totals(&sc->rve);
        return gk_err_set(&sc->err, GK_ERR_DT,
                          "mass %g: the time step %g s is above the critical %g s it gives (Guo & Zhao "
                          "2014 eq 19)",
                          m, sc->rve.dt, dtc);
    }
    return GK_OK;
}

GKDEF gk_result gk_scene_set_velocity(gk_scene *sc, int p, const double v[3], const double w[3]) {
    int k;
    gk_result r;
    if ((r = gk__scene_p(sc, p)) != GK_OK) return r;
    if (!gk__finite3(v) || !gk__finite3(w))
        return gk_err_set(&sc->err, GK_ERR_NAN, "velocity: non-finite value");
    for (k = 0; k < 3; ++k) {
        if (v && k < sc->dim) sc->rve.v[k][p] = (gk_real)v[k];
        if (w && sc->rve.w[k]) sc->rve.w[k][p] = (gk_real)w[k];
    }
    return GK_OK;
}

/* ------------------------------------------------------------- membranes */
GKDEF gk_result gk_scene_add_membrane(gk_scene *sc, int k, const int32_t *ids, double pressure,
                                      double stiffness, int anchor_first, int anchor_last, int *index) {
    gk_membrane M;
    int e, a;
    if (sc->dim != 2) return gk_err_set(&sc->err, GK_ERR_UNSUPPORTED, "membranes are 2D");
    if (k < 2 || !ids) return gk_err_set(&sc->err, GK_ERR_ARG, "a membrane needs at least 2 members");
    if (!isfinite(pressure) || !(stiffness >= 0.0) || !isfinite(stiffness))
        return gk_err_set(&sc->err, GK_ERR_ARG, "membrane pressure %g / stiffness %g invalid", pressure,
                          stiffness);
    for (e = 0; e < k; ++e)
        if (gk_scene_index(sc, ids[e]) < 0)
            return gk_err_set(&sc->err, GK_ERR_ARG, "membrane member %d: no particle with id %d", e,
                              (int)ids[e]);
    if (anchor_first < -1 || anchor_first >= sc->nwalls || anchor_last < -1 || anchor_last >= sc->nwalls)
        return gk_err_set(&sc->err, GK_ERR_ARG, "membrane anchors %d, %d: not walls of this scene",
                          anchor_first, anchor_last);
    memset(&M, 0, sizeof M);
    M.anchor[0] = anchor_first;
    M.anchor[1] = anchor_last;
    for (a = 0; a < 2; ++a)
        if (M.anchor[a] >= 0) {
            gk_wall *W = &sc->walls[M.anchor[a]];
            double x[3], c[3], nn[3];
            gk_scene_position(sc, gk_scene_index(sc, ids[a ? k - 1 : 0]), x);
            M.arest[a] = gk__wall_geom(W, sc->dim, x, c, nn);
        }
    M.n = M.cap = k;
    M.pressure = pressure;
    M.stiffness = stiffness;
    M.ids = (int32_t *)gk_alloc(gk__sc_alloc(sc), (size_t)k * sizeof(int32_t));
    M.rest = (double *)gk_alloc(gk__sc_alloc(sc), (size_t)k * sizeof(double));
    M.fx = (double *)gk_alloc(gk__sc_alloc(sc), (size_t)k * sizeof(double));
    M.fy = (double *)gk_alloc(gk__sc_alloc(sc), (size_t)k * sizeof(double));
    if (!M.ids || !M.rest || !M.fx || !M.fy ||
        (sc->nmem == sc->capmem &&
         gk_realloc(gk__sc_alloc(sc), (void **)&sc->mem, (size_t)sc->nmem,
                    (size_t)(sc->capmem ? 2 * sc->capmem : 4), sizeof(gk_membrane)))) {
        gk__sc_free(sc, M.ids);
        gk__sc_free(sc, M.rest);
        gk__sc_free(sc, M.fx);
        gk__sc_free(sc, M.fy);
        return gk_err_set(&sc->err, GK_ERR_ALLOC, "out of memory for a membrane");
    }
    if (sc->nmem == sc->capmem) sc->capmem = sc->capmem ? 2 * sc->capmem : 4;
    for (e = 0; e < k; ++e) {
        M.ids[e] = ids[e];
        M.fx[e] = M.fy[e] = 0.0;
        M.rest[e] = 0.0;
        if (e + 1 < k) {
            double xa[3], xb[3];
            gk_scene_position(sc, gk_scene_index(sc, ids[e]), xa);
            gk_scene_position(sc, gk_scene_index(sc, ids[e + 1]), xb);
            M.rest[e] = sqrt((xb[0] - xa[0]) * (xb[0] - xa[0]) + (xb[1] - xa[1]) * (xb[1] - xa[1]));
        }
    }
    sc->mem[sc->nmem++] = M;
    if (index) *index = sc->nmem - 1;
    return GK_OK;
}

GKDEF gk_result gk_scene_side_chain(gk_scene *sc, int axis, int side, double band, int32_t *ids, int cap,
                                    int *k) {
    int other = 1 - axis, nb, b, p, cnt = 0;
    double lo = 1e300, hi = -1e300;
    int32_t *best;
    double *bx;
    if (sc->dim != 2) return gk_err_set(&sc->err, GK_ERR_UNSUPPORTED, "side chains are 2D");
    if ((axis != 0 && axis != 1) || (side != -1 && side != 1) || !(band > 0.0) || !ids || !k)
        return gk_err_set(&sc->err, GK_ERR_ARG, "side chain: axis 0|1, side -1|1, band > 0 and output");
    for (p = 0; p < sc->rve.n; ++p) {
        double x[3];
        gk_scene_position(sc, p, x);
        if (x[other] < lo) lo = x[other];
        if (x[other] > hi) hi = x[other];
    }
    nb = (int)((hi - lo) / band + 0.5) + 1; /* bands centred on lo + k band */
    best = (int32_t *)gk_alloc(&sc->def.rve.alloc, (size_t)nb * sizeof(int32_t));
    bx = (double *)gk_alloc(&sc->def.rve.alloc, (size_t)nb * sizeof(double));
    if (!best || !bx) {
        gk_free(&sc->def.rve.alloc, best);
        gk_free(&sc->def.rve.alloc, bx);
        return gk_err_set(&sc->err, GK_ERR_ALLOC, "out of memory for a side chain");
    }
    for (b = 0; b < nb; ++b) best[b] = -1;
    for (p = 0; p < sc->rve.n; ++p) {
        double x[3], e;
        gk_scene_position(sc, p, x);
        b = (int)((x[other] - lo) / band + 0.5);
        if (b >= nb) b = nb - 1;
        e = side * (x[axis] + side * (double)sc->rve.r[p]); /* outer edge, larger is further out */
        if (best[b] < 0 || e > bx[b]) {
            best[b] = p;
            bx[b] = e;
        }
    }
    /* material on the left: x-sides run +y on the right (side +1), -y on the left;
     * y-sides run -x on top, +x at the bottom */
    for (b = 0; b < nb; ++b) {
        int q = ((axis == 0) == (side == 1)) ? b : nb - 1 - b;
        if (best[q] < 0) continue;
        if (cnt >= cap) {
            gk_free(&sc->def.rve.alloc, best);
            gk_free(&sc->def.rve.alloc, bx);
            return gk_err_set(&sc->err, GK_ERR_ARG, "side chain: more than %d members", cap);
        }
        ids[cnt++] = sc->rve.id[best[q]];
    }
    gk_free(&sc->def.rve.alloc, best);
    gk_free(&sc->def.rve.alloc, bx);
    *k = cnt;
    return GK_OK;
}

/* ------------------------------------------------------------- insertion, deletion */
GKDEF gk_result gk_scene_insert(gk_scene *sc, int k, const double *const x[3], const double *r,
                                const double *const v[3], int32_t *ids) {
    gk_rve *rve = &sc->rve;
    double *s[3] = {NULL, NULL, NULL};
    int32_t *nid = NULL;
    int q, a, n0 = rve->n, dim = sc->dim;
    gk_result res = GK_OK;
    if (k < 0 || (k > 0 && (!x || !r || !x[0] || !x[1] || (dim == 3 && !x[2]))))
        return gk_err_set(&sc->err, GK_ERR_ARG, "insert: bad arguments");
    if (k == 0) return GK_OK;
    for (a = 0; a < dim; ++a) {
        s[a] = (double *)gk_alloc(gk__sc_alloc(sc), (size_t)k * sizeof(double));
        if (!s[a]) res = GK_ERR_ALLOC;
    }
    nid = (int32_t *)gk_alloc(gk__sc_alloc(sc), (size_t)k * sizeof(int32_t));
    if (!nid) res = GK_ERR_ALLOC;
    if (res) {
        gk_err_set(&sc->err, GK_ERR_ALLOC, "out of memory inserting %d particles", k);
        goto out;
    }
    for (q = 0; q < k && !res; ++q) {
        for (a = 0; a < dim; ++a) {
            double u = x[a][q];
            if (!isfinite(u) || (v && v[a] && !isfinite(v[a][q]))) {
                res = gk_err_set(&sc->err, GK_ERR_NAN, "insert: particle %d has a non-finite value", q);
                break;
            }
            if (!(sc->open & (1u << a))) {
                u = gk__sc_wrap(sc->def.lo[a], sc->def.hi[a], u);
            } else if (u < sc->def.lo[a] || u > sc->def.hi[a]) {
                res = gk_err_set(&sc->err, GK_ERR_OUTSIDE,
                                 "insert: particle %d at %g on axis %d is outside [%g, %g]", q, u, a,
                                 sc->def.lo[a], sc->def.hi[a]);
                break;
            }
            s[a][q] = (u - sc->origin[a]) / rve->cell.h[4 * a];
        }
        nid[q] = sc->next_id + q;
    }
    if (res) goto out;
    if ((res = gk_rve_append(rve, k, (const double *const *)s, r, nid)) != GK_OK) {
        gk__scene_rve_err(sc, res);
        goto out;
    }
    if ((res = gk__scene_reserve(sc, rve->ncap > rve->n ? rve->ncap : rve->n)) != GK_OK) {
        unsigned char *drop = (unsigned char *)gk_alloc(gk__sc_alloc(sc), (size_t)rve->n);
        if (drop) { /* undo */
            for (q = 0; q < rve->n; ++q) drop[q] = (unsigned char)(q >= n0);
            gk_rve_remove(rve, drop);
            gk__sc_free(sc, drop);
        }
        goto out;
    }
    sc->next_id += k;
    gk__forget_weights(sc); /* the array is n0 long */
    for (q = n0; q < rve->n; ++q) {
        int w;
        sc->mass[q] = 1.0 / (double)rve->minv[q];
        sc->flags[q] = 0;
        for (a = 0; a < 3; ++a) {
            double *arr[10];
            int z;
            arr[0] = sc->vp[a], arr[1] = sc->wp[a], arr[2] = sc->load[a], arr[3] = sc->loadt[a];
            arr[4] = sc->fext[a], arr[5] = sc->text[a], arr[6] = sc->vold[a], arr[7] = sc->wold[a];
            arr[8] = sc->ftot[a], arr[9] = sc->ttot[a];
            for (z = 0; z < 10; ++z)
                if (arr[z]) arr[z][q] = 0.0;
            if (v && v[a] && a < dim) rve->v[a][q] = (gk_real)v[a][q - n0];
        }
        for (w = 0; w < sc->nwalls; ++w) {
            gk_wall *W = &sc->walls[w];
            for (a = 0; a < 3; ++a) {
                if (W->ft[a]) W->ft[a][q] = 0;
                if (W->mr[a]) W->mr[a][q] = 0;
            }
            W->cs[q] = 0;
            W->need_build = 1;
        }
        if (sc->energy_on) {
            double ke = 0.0;
            for (a = 0; a < dim; ++a) ke += 0.5 * sc->mass[q] * (double)rve->v[a][q] * (double)rve->v[a][q];
            sc->en.inserted += ke;
        }
    }
    res = gk__scene_index(sc);
    if (!res && ids)
        for (q = 0; q < k; ++q) ids[q] = nid[q];
    if (sc->energy_on) sc->en.kinetic = gk__kinetic(sc);
out:
    for (a = 0; a < 3; ++a) gk__sc_free(sc, s[a]);
    gk__sc_free(sc, nid);
    return res;
}

/* elastic energy stored in the contacts of the particles marked in drop */
static double gk__dropped_elastic(gk_scene *sc, const unsigned char *drop, double *erest) {
    gk_rve *rve = &sc->rve;
    int c, k, w, e, dim = sc->dim, nh = dim == 2 ? 1 : 3;
    double el = 0.0, rest;
    *erest = 0.0;
    for (c = 0; c < rve->pl.n; ++c) {
        int i = rve->pl.i[c], j = rve->pl.j[c];
        gk_real d[3], v[3], wi[3], wj[3], ft[3] = {0, 0, 0}, mr[3] = {0, 0, 0}, dist;
        if (!(rve->cs[c] & GK_CS_CONTACT) || (!drop[i] && !drop[j])) continue;
        gk__pair_inputs(rve, c, d, v, wi, wj);
        dist = (gk_real)sqrt((double)(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
        for (k = 0; k < nh; ++k) {
            if (rve->ft[dim == 2 ? 0 : k]) ft[dim == 2 ? 0 : k] = rve->ft[dim == 2 ? 0 : k][c];
            if (rve->mr[dim == 2 ? 2 : k]) mr[dim == 2 ? 0 : k] = rve->mr[dim == 2 ? 2 : k][c];
        }
        el += gk__contact_elastic(&rve->K, rve->def.mat.law, rve->phys, dim, rve->r[i], rve->r[j],
                                  rve->r[i] + rve->r[j] - dist, ft, mr, &rest);
        el += rest;
        *erest += rest;
    }
    for (w = 0; w < sc->nwalls; ++w) {
        gk_wall *W = &sc->walls[w];
        for (e = 0; e < W->ncand; ++e) {
            int p = W->cand[e];
            double x[3], cc[3], n[3], dist;
            gk_law_consts K;
            gk_real ft[3] = {0, 0, 0}, mr[3] = {0, 0, 0};
            if (!drop[p] || !(W->cs[p] & GK_CS_CONTACT)) continue;
            gk_scene_position(sc, p, x);
            dist = gk__wall_geom(W, dim, x, cc, n);
            for (k = 0; k < nh; ++k) {
                if (W->ft[k]) ft[dim == 2 ? 0 : k] = W->ft[k][p];
                if (W->mr[k]) mr[dim == 2 ? 0 : k] = W->mr[k][p];
            }
            gk__wall_consts(W, (double)rve->r[p], &K);
            el += gk__contact_elastic(&K, W->def.mat.law, W->phys, dim, rve->r[p], rve->r[p],
                                      (gk_real)((double)rve->r[p] - dist), ft, mr, &rest);
            el += rest;
            *erest += rest;
        }
    }
    return el;
}

static gk_result gk__scene_delete(gk_scene *sc, const unsigned char *drop) {
    gk_rve *rve = &sc->rve;
    int n = rve->n, p, q, k, w, m, e;
    gk_result r;
    double ke = 0.0, el = 0.0, erest = 0.0;
    for (p = 0, q = 0; p < n; ++p) q += !drop[p];
    if (q == n) return GK_OK;
    if (q < 1) return gk_err_set(&sc->err, GK_ERR_ARG, "cannot remove every particle");
    gk__forget_weights(sc); /* the indices change */
    if (sc->energy_on) {
        for (p = 0; p < n; ++p)
            if (drop[p]) {
                double I = 1.0 / (double)rve->Iinv[p];
                for (k = 0; k < 3; ++k) {
                    if (k < sc->dim) ke += 0.5 * sc->mass[p] * (double)rve->v[k][p] * (double)rve->v[k][p];
                    if (rve->w[k]) ke += 0.5 * I * (double)rve->w[k][p] * (double)rve->w[k][p];
                }
            }
        el = gk__dropped_elastic(sc, drop, &erest);
        sc->erest_prev -= erest; /* their springs leave the books, not as dissipation */
    }
    /* the scene's arrays first (the RVE's compaction keeps the same order) */
    for (p = 0, q = 0; p < n; ++p) {
        if (drop[p]) {
            if (sc->flags[p] & GK_PARTICLE_PRESCRIBED) --sc->nprescribed;
            if (sc->flags[p] & GK_PARTICLE_LOCKED_ROTATION) --sc->nlocked;
            continue;
        }
        sc->mass[q] = sc->mass[p];
        sc->flags[q] = sc->flags[p];
        for (k = 0; k < 3; ++k) {
            double *arr[10];
            int z;
            arr[0] = sc->vp[k], arr[1] = sc->wp[k], arr[2] = sc->load[k], arr[3] = sc->loadt[k];
            arr[4] = sc->fext[k], arr[5] = sc->text[k], arr[6] = sc->vold[k], arr[7] = sc->wold[k];
            arr[8] = sc->ftot[k], arr[9] = sc->ttot[k];
            for (z = 0; z < 10; ++z)
                if (arr[z]) arr[z][q] = arr[z][p];
        }
        for (w = 0; w < sc->nwalls; ++w) {
            gk_wall *W = &sc->walls[w];
            for (k = 0; k < 3; ++k) {
                if (W->ft[k]) W->ft[k][q] = W->ft[k][p];
                if (W->mr[k]) W->mr[k][q] = W->mr[k][p];
            }
            W->cs[q] = W->cs[p];
        }
        ++q;
    }
    for (w = 0; w < sc->nwalls; ++w) sc->walls[w].need_build = 1;
    if ((r = gk_rve_remove(rve, drop)) != GK_OK) return gk__scene_rve_err(sc, r);
    if ((r = gk__scene_index(sc)) != GK_OK) return r;
    /* membrane members that are gone leave their chain */
    for (m = 0; m < sc->nmem; ++m) {
        gk_membrane *M = &sc->mem[m];
        int kept = 0;
        for (e = 0; e < M->n; ++e) {
            if (gk_scene_index(sc, M->ids[e]) < 0) continue;
            M->ids[kept] = M->ids[e];
            M->rest[kept] = M->rest[e]; /* the link to the next survivor keeps the first rest length */
            ++kept;
        }
        M->n = kept;
    }
    if (sc->energy_on) {
        sc->en.removed += ke + el;
        sc->en.kinetic = gk__kinetic(sc);
    }
    return GK_OK;
}

GKDEF gk_result gk_scene_remove(gk_scene *sc, int k, const int32_t *ids) {
    unsigned char *drop;
    int q;
    gk_result r;
    if (k < 0 || (k > 0 && !ids)) return gk_err_set(&sc->err, GK_ERR_ARG, "remove: bad arguments");
    for (q = 0; q < k; ++q)
        if (gk_scene_index(sc, ids[q]) < 0)
            return gk_err_set(&sc->err, GK_ERR_ARG, "remove: no particle with id %d", (int)ids[q]);
    if (k == 0) return GK_OK;
    drop = (unsigned char *)gk_alloc(gk__sc_alloc(sc), (size_t)sc->rve.n);
    if (!drop) return gk_err_set(&sc->err, GK_ERR_ALLOC, "out of memory removing particles");
    memset(drop, 0, (size_t)sc->rve.n);
    for (q = 0; q < k; ++q) drop[gk_scene_index(sc, ids[q])] = 1;
    r = gk__scene_delete(sc, drop);
    gk__sc_free(sc, drop);
    return r;
}

/* ------------------------------------------------------------- contact weights */
static gk_result gk__check_weights(gk_scene *sc, const double *w) {
    int p;
    for (p = 0; p < sc->rve.n; ++p)
        if (!(w[p] > 0.0 && w[p] <= 1.0))
            return gk_err_set(&sc->err, GK_ERR_ARG, "contact weight %g of particle %d (must be in (0, 1])",
                              w[p], p);
    return GK_OK;
}

static void gk__forget_weights(gk_scene *sc) {
    sc->cw = NULL;
    sc->rve.hook_pairs = 0;
}

GKDEF gk_result gk_scene_weight_contacts(gk_scene *sc, const double *w) {
    gk_result r;
    if (!w) {
        gk__forget_weights(sc);
        return GK_OK;
    }
    if (sc->energy_on)
        return gk_err_set(&sc->err, GK_ERR_STATE,
                          "contact weights with energy tracking on (the books do not know the scaling)");
    if ((r = gk__check_weights(sc, w)) != GK_OK) return r;
    sc->cw = w;
    return GK_OK;
}

/* ------------------------------------------------------------- energy */
GKDEF gk_result gk_scene_energy_track(gk_scene *sc, int on) {
    int k;
    gk_result r;
    if (!on) {
        sc->energy_on = 0;
        return GK_OK;
    }
    if (sc->cw)
        return gk_err_set(&sc->err, GK_ERR_STATE,
                          "energy tracking with contact weights set (the books do not know the scaling)");
    for (k = 0; k < 3; ++k)
        if ((r = gk__sc_new(sc, &sc->vold[k])) != GK_OK || (r = gk__sc_new(sc, &sc->wold[k])) != GK_OK ||
            (r = gk__sc_new(sc, &sc->ftot[k])) != GK_OK || (r = gk__sc_new(sc, &sc->ttot[k])) != GK_OK)
            return r;
    memset(&sc->en, 0, sizeof sc->en);
    sc->en.kinetic = gk__kinetic(sc);
    sc->en.initial = sc->en.kinetic; /* + the elastic energy of the first step */
    sc->energy_pending = 1;
    sc->energy_on = 1;
    sc->energy_mismatch = 0;
    return GK_OK;
}

GKDEF void gk_scene_energy(const gk_scene *sc, gk_energy *e) {
    const gk_energy *a = &sc->en;
    double in = a->gravity + a->walls + a->external + a->pressure + a->prescribed,
           out = a->friction + a->viscous + a->damping;
    *e = *a;
    e->balance = a->kinetic + a->elastic - (a->initial + in - out + a->inserted - a->removed);
    e->scale = fabs(a->initial) + fabs(a->gravity) + fabs(a->walls) + fabs(a->external) + fabs(a->pressure) +
               fabs(a->prescribed) + out + a->inserted + a->removed;
}

/* ------------------------------------------------------------- save / restore */
#define GK__SCENE_MAGIC "GKSCENE\001"
#define GK__SCENE_VERSION 1

typedef struct gk__scene_hdr {
    char magic[8];
    int32_t version, dim, n, nwalls, nmem, next_id, real_size, energy_on, energy_pending, nprescribed, endian;
    int32_t have_presc, have_ext, pad0, pad1;
    int64_t lost;
    gk_energy en;
    double wall_love[9], erest_prev;
    uint64_t rve_bytes;
} gk__scene_hdr;

typedef struct gk__wall_rec {
    gk_wall_def def;
    double pos[3], vel[3], angle, force[3], moment[3], stiffness, resistance, dmax;
    int32_t ncontacts, pad;
} gk__wall_rec;

static size_t gk__scene_bytes(const gk_scene *sc, size_t rve_bytes) {
    size_t n = (size_t)sc->rve.n, R = sizeof(gk_real), b = sizeof(gk__scene_hdr) + rve_bytes;
    int w, m, nh = sc->dim == 2 ? 1 : 3;
    b += n * (3 * R + sizeof(int32_t) + sizeof(double) + 1);
    if (sc->vp[0]) b += n * 12 * sizeof(double);
    if (sc->fext[0]) b += n * 6 * sizeof(double);
    for (w = 0; w < sc->nwalls; ++w) {
        const gk_wall *W = &sc->walls[w];
        b += sizeof(gk__wall_rec) + n;
        if (W->ft[0]) b += n * R * (size_t)nh;
        if (W->mr[0]) b += n * R * (size_t)nh;
    }
    for (m = 0; m < sc->nmem; ++m)
        b += 4 * sizeof(double) + 2 * sizeof(int) + sizeof(int32_t) +
             (size_t)sc->mem[m].n * (sizeof(int32_t) + 3 * sizeof(double));
    return b;
}

GKDEF size_t gk_scene_state_size(const gk_scene *sc) {
    return gk__scene_bytes(sc, gk_rve_state_size(&sc->rve));
}

#define GK__SPUT(ptr, bytes)             \
    do {                                 \
        memcpy(o + off, (ptr), (bytes)); \
        off += (bytes);                  \
    } while (0)
#define GK__SGET(ptr, bytes)                \
    do {                                    \
        if (off + (bytes) > size) goto bad; \
        memcpy((ptr), in + off, (bytes));   \
        off += (bytes);                     \
    } while (0)

GKDEF gk_result gk_scene_save(const gk_scene *sc, void *buf, size_t cap, size_t *written) {
    gk__scene_hdr hd;
    unsigned char *o = (unsigned char *)buf;
    size_t rb = gk_rve_state_size(&sc->rve), need = gk__scene_bytes(sc, rb), off = 0, n = (size_t)sc->rve.n,
           R = sizeof(gk_real);
    int k, w, m, nh = sc->dim == 2 ? 1 : 3;
    if (written) *written = need;
    if (!buf || cap < need) return GK_ERR_ARG;
    memset(&hd, 0, sizeof hd);
    memcpy(hd.magic, GK__SCENE_MAGIC, 8);
    hd.version = GK__SCENE_VERSION;
    hd.dim = sc->dim;
    hd.n = sc->rve.n;
    hd.nwalls = sc->nwalls;
    hd.nmem = sc->nmem;
    hd.next_id = sc->next_id;
    hd.real_size = (int32_t)R;
    hd.energy_on = sc->energy_on;
    hd.energy_pending = sc->energy_pending;
    hd.nprescribed = sc->nprescribed;
    hd.endian = 0x01020304;
    hd.have_presc = sc->vp[0] != NULL;
    hd.have_ext = sc->fext[0] != NULL;
    hd.lost = sc->lost;
    hd.en = sc->en;
    for (k = 0; k < 9; ++k) hd.wall_love[k] = sc->wall_love[k];
    hd.erest_prev = sc->erest_prev;
    hd.rve_bytes = rb;
    GK__SPUT(&hd, sizeof hd);
    GK__SPUT(sc->rve.r, n * R);
    GK__SPUT(sc->rve.minv, n * R);
    GK__SPUT(sc->rve.Iinv, n * R);
    GK__SPUT(sc->rve.id, n * sizeof(int32_t));
    GK__SPUT(sc->mass, n * sizeof(double));
    GK__SPUT(sc->flags, n);
    if (hd.have_presc)
        for (k = 0; k < 3; ++k) {
            GK__SPUT(sc->vp[k], n * sizeof(double));
            GK__SPUT(sc->wp[k], n * sizeof(double));
            GK__SPUT(sc->load[k], n * sizeof(double));
            GK__SPUT(sc->loadt[k], n * sizeof(double));
        }
    if (hd.have_ext)
        for (k = 0; k < 3; ++k) {
            GK__SPUT(sc->fext[k], n * sizeof(double));
            GK__SPUT(sc->text[k], n * sizeof(double));
        }
    for (w = 0; w < sc->nwalls; ++w) {
        const gk_wall *W = &sc->walls[w];
        gk__wall_rec rec;
        memset(&rec, 0, sizeof rec);
        rec.def = W->def;
        for (k = 0; k < 3; ++k) {
            rec.pos[k] = W->pos[k];
            rec.vel[k] = W->vel[k];
            rec.force[k] = W->force[k];
            rec.moment[k] = W->moment[k];
        }
        rec.angle = W->angle;
        rec.stiffness = W->stiffness;
        rec.resistance = W->resistance;
        rec.dmax = W->dmax;
        rec.ncontacts = W->ncontacts;
        GK__SPUT(&rec, sizeof rec);
        GK__SPUT(W->cs, n);
        for (k = 0; k < nh; ++k)
            if (W->ft[0]) GK__SPUT(W->ft[k], n * R);
        for (k = 0; k < nh; ++k)
            if (W->mr[0]) GK__SPUT(W->mr[k], n * R);
    }
    for (m = 0; m < sc->nmem; ++m) {
        const gk_membrane *M = &sc->mem[m];
        int32_t nm = M->n;
        GK__SPUT(&nm, sizeof nm);
        GK__SPUT(&M->pressure, sizeof(double));
        GK__SPUT(&M->stiffness, sizeof(double));
        GK__SPUT(M->arest, 2 * sizeof(double));
        GK__SPUT(M->anchor, 2 * sizeof(int));
        GK__SPUT(M->ids, (size_t)M->n * sizeof(int32_t));
        GK__SPUT(M->rest, (size_t)M->n * sizeof(double));
        GK__SPUT(M->fx, (size_t)M->n * sizeof(double));
        GK__SPUT(M->fy, (size_t)M->n * sizeof(double));
    }
    if (gk_rve_save(&sc->rve, o + off, rb, NULL) != GK_OK) return GK_ERR_ARG;
    off += rb;
    GK_ASSERT(off == need);
    return GK_OK;
}

/* every value finite and at most 1e100 in magnitude (what a state can hold) */
static int gk__sc_sane(const double *a, size_t n) {
    size_t i;
    for (i = 0; i < n; ++i)
        if (!(fabs(a[i]) <= 1e100)) return 0;
    return 1;
}
static int gk__sc_sane_real(const gk_real *a, size_t n) {
    size_t i;
    for (i = 0; i < n; ++i)
        if (!(fabs((double)a[i]) <= 1e100)) return 0;
    return 1;
}

/* reads a state into sc, checking as it goes: a refused state may leave sc half-written
 * (gk_scene_restore puts it back) */
static gk_result gk__scene_restore_raw(gk_scene *sc, const void *buf, size_t size) {
    gk__scene_hdr hd;
    const unsigned char *in = (const unsigned char *)buf;
    size_t off = 0, n, R = sizeof(gk_real);
    int k, w, m, p, np, nl, nh = sc->dim == 2 ? 1 : 3;
    double hkeep[9];
    gk_result r;
    if (!buf || size < sizeof hd) return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state buffer too small");
    memcpy(&hd, buf, sizeof hd);
    if (memcmp(hd.magic, GK__SCENE_MAGIC, 8) != 0 || hd.endian != 0x01020304 ||
        hd.version != GK__SCENE_VERSION)
        return gk_err_set(&sc->err, GK_ERR_FORMAT, "not a grainkit scene state of this version");
    if (hd.dim != sc->dim || hd.real_size != (int32_t)R || hd.nwalls != sc->nwalls || hd.nmem != sc->nmem ||
        hd.n < 1 || hd.next_id < hd.n)
        return gk_err_set(
            &sc->err, GK_ERR_FORMAT,
            "scene state is for dim %d, %d-byte reals, %d walls, %d membranes; this scene has %d, %d, "
            "%d, %d",
            hd.dim, hd.real_size, hd.nwalls, hd.nmem, sc->dim, (int)R, sc->nwalls, sc->nmem);
    if (hd.rve_bytes > size) return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state has the wrong size");
    {
        const gk_energy *E = &hd.en;
        double hv[17];
        hv[0] = E->kinetic, hv[1] = E->elastic, hv[2] = E->gravity, hv[3] = E->walls, hv[4] = E->external;
        hv[5] = E->pressure, hv[6] = E->prescribed, hv[7] = E->friction, hv[8] = E->viscous;
        hv[9] = E->damping, hv[10] = E->slip, hv[11] = E->removed, hv[12] = E->inserted, hv[13] = E->initial;
        hv[14] = E->balance, hv[15] = E->scale, hv[16] = hd.erest_prev;
        if ((unsigned)hd.energy_on > 1u || (unsigned)hd.energy_pending > 1u || (unsigned)hd.have_presc > 1u ||
            (unsigned)hd.have_ext > 1u || hd.lost < 0 || hd.en.steps < 0 || !gk__sc_sane(hv, 17) ||
            !gk__sc_sane(hd.wall_love, 9))
            return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state header holds an impossible value");
    }
    n = (size_t)hd.n;
    { /* the whole layout before anything changes: walk it (membrane lengths are inside) */
        size_t want = sizeof hd + n * (3 * R + sizeof(int32_t) + sizeof(double) + 1);
        if (hd.have_presc) want += n * 12 * sizeof(double);
        if (hd.have_ext) want += n * 6 * sizeof(double);
        for (w = 0; w < sc->nwalls; ++w) {
            const gk_wall *W = &sc->walls[w];
            want += sizeof(gk__wall_rec) + n;
            if (W->ft[0]) want += n * R * (size_t)nh;
            if (W->mr[0]) want += n * R * (size_t)nh;
        }
        for (m = 0; m < sc->nmem; ++m) {
            int32_t nm;
            if (want + sizeof nm > size) goto bad;
            memcpy(&nm, in + want, sizeof nm);
            if (nm < 0 || nm > sc->mem[m].cap) goto bad;
            want += 4 * sizeof(double) + 2 * sizeof(int) + sizeof(int32_t) +
                    (size_t)nm * (sizeof(int32_t) + 3 * sizeof(double));
        }
        if (want + hd.rve_bytes != size) goto bad;
    }
    /* particle count of the state: append or drop at the end, then overwrite everything */
    if (hd.n > sc->rve.n) {
        int add = hd.n - sc->rve.n, a;
        double *s[3] = {NULL, NULL, NULL}, *rr;
        int32_t *ids;
        size_t roff = sizeof hd;
        r = GK_OK;
        rr = (double *)gk_alloc(gk__sc_alloc(sc), (size_t)add * sizeof(double));
        ids = (int32_t *)gk_alloc(gk__sc_alloc(sc), (size_t)add * sizeof(int32_t));
        for (a = 0; a < 3; ++a) s[a] = (double *)gk_alloc(gk__sc_alloc(sc), (size_t)add * sizeof(double));
        if (!rr || !ids || !s[0] || !s[1] || !s[2])
            r = gk_err_set(&sc->err, GK_ERR_ALLOC, "out of memory restoring");
        for (p = 0; !r && p < add; ++p) {
            gk_real rv;
            if (roff + (size_t)(sc->rve.n + p + 1) * R > size) {
                r = gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state truncated");
                break;
            }
            memcpy(&rv, in + roff + (size_t)(sc->rve.n + p) * R, R);
            rr[p] = (double)rv > 0.0 && (double)rv < sc->rve.rmax * 1e3 ? (double)rv : sc->rve.rmin;
            ids[p] = sc->next_id + p;
            for (a = 0; a < 3; ++a) s[a][p] = 0.5;
        }
        if (!r && (r = gk_rve_append(&sc->rve, add, (const double *const *)s, rr, ids)) != GK_OK)
            gk__scene_rve_err(sc, r);
        if (!r) r = gk__scene_reserve(sc, sc->rve.ncap > sc->rve.n ? sc->rve.ncap : sc->rve.n);
        gk__sc_free(sc, rr);
        gk__sc_free(sc, ids);
        for (a = 0; a < 3; ++a) gk__sc_free(sc, s[a]);
        if (r) return r;
    } else if (hd.n < sc->rve.n) {
        unsigned char *drop = (unsigned char *)gk_alloc(gk__sc_alloc(sc), (size_t)sc->rve.n);
        if (!drop) return gk_err_set(&sc->err, GK_ERR_ALLOC, "out of memory restoring");
        for (p = 0; p < sc->rve.n; ++p) drop[p] = (unsigned char)(p >= hd.n);
        r = gk_rve_remove(&sc->rve, drop);
        gk__sc_free(sc, drop);
        if (r) return gk__scene_rve_err(sc, r);
    }
    off = sizeof hd;
    GK__SGET(sc->rve.r, n * R);
    GK__SGET(sc->rve.minv, n * R);
    GK__SGET(sc->rve.Iinv, n * R);
    GK__SGET(sc->rve.id, n * sizeof(int32_t));
    for (p = 0; p < hd.n; ++p)
        if (sc->rve.id[p] < 0 || sc->rve.id[p] >= hd.next_id || !((double)sc->rve.r[p] > 0.0) ||
            !((double)sc->rve.minv[p] > 0.0) || !((double)sc->rve.Iinv[p] > 0.0))
            return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state particle %d is invalid", p);
    gk_rve_update_totals(&sc->rve); /* gk_rve_restore checks the time step with these particles */
    GK__SGET(sc->mass, n * sizeof(double));
    for (p = 0; p < hd.n; ++p)
        if (!(sc->mass[p] > 0.0) || !(sc->mass[p] <= 1e100))
            return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state particle %d has mass %g", p, sc->mass[p]);
    GK__SGET(sc->flags, n);
    for (p = 0, np = nl = 0; p < hd.n; ++p) {
        if ((sc->flags[p] & ~GK__PARTICLE_FLAGS) ||
            ((sc->flags[p] & GK_PARTICLE_PRESCRIBED) && !hd.have_presc))
            return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state particle %d has invalid flags %u", p,
                              (unsigned)sc->flags[p]);
        np += (sc->flags[p] & GK_PARTICLE_PRESCRIBED) != 0;
        nl += (sc->flags[p] & GK_PARTICLE_LOCKED_ROTATION) != 0;
    }
    if (np != hd.nprescribed)
        return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state: %d prescribed particles, the header says %d",
                          np, (int)hd.nprescribed);
    if (hd.have_presc)
        for (k = 0; k < 3; ++k) {
            if ((r = gk__sc_new(sc, &sc->vp[k])) || (r = gk__sc_new(sc, &sc->wp[k])) ||
                (r = gk__sc_new(sc, &sc->load[k])) || (r = gk__sc_new(sc, &sc->loadt[k])))
                return r;
            GK__SGET(sc->vp[k], n * sizeof(double));
            GK__SGET(sc->wp[k], n * sizeof(double));
            GK__SGET(sc->load[k], n * sizeof(double));
            GK__SGET(sc->loadt[k], n * sizeof(double));
            if (!gk__sc_sane(sc->vp[k], n) || !gk__sc_sane(sc->wp[k], n) || !gk__sc_sane(sc->load[k], n) ||
                !gk__sc_sane(sc->loadt[k], n))
                return gk_err_set(&sc->err, GK_ERR_FORMAT,
                                  "scene state: a prescribed motion or load is not finite");
        }
    if (hd.have_ext)
        for (k = 0; k < 3; ++k) {
            if ((r = gk__sc_new(sc, &sc->fext[k])) || (r = gk__sc_new(sc, &sc->text[k]))) return r;
            GK__SGET(sc->fext[k], n * sizeof(double));
            GK__SGET(sc->text[k], n * sizeof(double));
            if (!gk__sc_sane(sc->fext[k], n) || !gk__sc_sane(sc->text[k], n))
                return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state: an external load is not finite");
        }
    for (w = 0; w < sc->nwalls; ++w) {
        gk_wall *W = &sc->walls[w];
        gk__wall_rec rec;
        GK__SGET(&rec, sizeof rec);
        if ((r = gk__wall_check(sc, &rec.def)) != GK_OK) return r;
        if (!gk__sc_sane(rec.pos, 3) || !gk__sc_sane(rec.vel, 3) || !gk__sc_sane(rec.force, 3) ||
            !gk__sc_sane(rec.moment, 3) || !gk__sc_sane(&rec.angle, 1) || !gk__sc_sane(&rec.stiffness, 1) ||
            !gk__sc_sane(&rec.resistance, 1) || !gk__sc_sane(&rec.dmax, 1) || rec.ncontacts < 0 ||
            rec.ncontacts > hd.n)
            return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state wall %d holds an impossible value", w);
        if (gk_material_flags(&rec.def.mat) != gk_material_flags(&W->def.mat))
            return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state wall %d has other contact physics", w);
        W->def = rec.def;
        for (k = 0; k < 3; ++k) {
            W->pos[k] = rec.pos[k];
            W->vel[k] = rec.vel[k];
            W->force[k] = rec.force[k];
            W->moment[k] = rec.moment[k];
        }
        W->angle = rec.angle;
        W->stiffness = rec.stiffness;
        W->resistance = rec.resistance;
        W->dmax = rec.dmax;
        W->ncontacts = rec.ncontacts;
        W->need_build = 1;
        GK__SGET(W->cs, n);
        for (k = 0; k < nh; ++k)
            if (W->ft[0]) GK__SGET(W->ft[k], n * R);
        for (k = 0; k < nh; ++k)
            if (W->mr[0]) GK__SGET(W->mr[k], n * R);
        for (k = 0; k < nh; ++k)
            if ((W->ft[0] && !gk__sc_sane_real(W->ft[k], n)) || (W->mr[0] && !gk__sc_sane_real(W->mr[k], n)))
                return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state wall %d has a non-finite history", w);
    }
    for (m = 0; m < sc->nmem; ++m) {
        gk_membrane *M = &sc->mem[m];
        int32_t nm;
        int anc[2];
        GK__SGET(&nm, sizeof nm);
        if (nm < 0 || nm > M->cap)
            return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state membrane %d is invalid", m);
        M->n = nm;
        GK__SGET(&M->pressure, sizeof(double));
        GK__SGET(&M->stiffness, sizeof(double));
        GK__SGET(M->arest, 2 * sizeof(double));
        GK__SGET(anc, 2 * sizeof(int));
        if (anc[0] != M->anchor[0] || anc[1] != M->anchor[1])
            return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state membrane %d has other anchors", m);
        GK__SGET(M->ids, (size_t)nm * sizeof(int32_t));
        GK__SGET(M->rest, (size_t)nm * sizeof(double));
        GK__SGET(M->fx, (size_t)nm * sizeof(double));
        GK__SGET(M->fy, (size_t)nm * sizeof(double));
        for (p = 0; p < nm; ++p)
            if (M->ids[p] < 0 || M->ids[p] >= hd.next_id)
                return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state membrane %d names id %d", m,
                                  (int)M->ids[p]);
        if (!gk__sc_sane(&M->pressure, 1) || !gk__sc_sane(&M->stiffness, 1) || M->stiffness < 0.0 ||
            !gk__sc_sane(M->arest, 2) || !gk__sc_sane(M->rest, (size_t)nm) ||
            !gk__sc_sane(M->fx, (size_t)nm) || !gk__sc_sane(M->fy, (size_t)nm))
            return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state membrane %d holds an impossible value",
                              m);
    }
    if (off + hd.rve_bytes != size) goto bad;
    gk_m3_copy(sc->rve.cell.h, hkeep);
    if ((r = gk_rve_restore(&sc->rve, in + off, (size_t)hd.rve_bytes)) != GK_OK)
        return gk__scene_rve_err(sc, r);
    for (k = 0; k < 9; ++k) /* the scene's cell is its domain: fixed, never driven */
        if (sc->rve.cell.h[k] != hkeep[k] || sc->rve.L[k] != 0.0 || sc->rve.servo_on)
            return gk_err_set(&sc->err, GK_ERR_FORMAT,
                              "scene state: its cell is not this scene's domain (or is driven)");
    sc->next_id = hd.next_id;
    if ((r = gk__scene_index(sc)) != GK_OK) return r;
    sc->nprescribed = np;
    sc->nlocked = nl;
    sc->lost = hd.lost;
    sc->en = hd.en;
    for (k = 0; k < 9; ++k) sc->wall_love[k] = hd.wall_love[k];
    sc->erest_prev = hd.erest_prev;
    sc->energy_pending = hd.energy_pending;
    if (hd.energy_on && !sc->energy_on) {
        gk_energy keep = sc->en;
        if ((r = gk_scene_energy_track(sc, 1)) != GK_OK) return r;
        sc->en = keep;
        sc->energy_pending = hd.energy_pending;
    }
    sc->energy_on = hd.energy_on;
    sc->seen_rebuilds = -1;
    return GK_OK;
bad:
    return gk_err_set(&sc->err, GK_ERR_FORMAT, "scene state has the wrong size");
}

/* a refused state changes nothing: the scene's own state is kept aside first and put back */
GKDEF gk_result gk_scene_restore(gk_scene *sc, const void *buf, size_t size) {
    int n0 = sc->rve.n;
    size_t nb = gk_scene_state_size(sc);
    void *keep = gk_alloc(gk__sc_alloc(sc), nb);
    gk_result r, back;
    gk_err e;
    if (!keep) return gk_err_set(&sc->err, GK_ERR_ALLOC, "restore: out of memory for the scene's own state");
    if (gk_scene_save(sc, keep, nb, NULL) != GK_OK) {
        gk__sc_free(sc, keep);
        return gk_err_set(&sc->err, GK_ERR_STATE, "restore: the scene's own state could not be kept");
    }
    r = gk__scene_restore_raw(sc, buf, size);
    if (r == GK_OK && sc->cw && sc->rve.n != n0) gk__forget_weights(sc);
    if (r != GK_OK) {
        e = sc->err;
        back = gk__scene_restore_raw(sc, keep, nb);
        sc->err = e;
        if (back != GK_OK) /* only running out of memory can get here */
            gk_err_set(&sc->err, r, "%s; putting the scene back failed too, it is unusable", e.msg);
    }
    gk__sc_free(sc, keep);
    return r;
}

/* ------------------------------------------------------------- output */
GKDEF gk_result gk_scene_write_vtk(const gk_scene *sc, const char *path, gk_err *err) {
    gk_vtk v;
    int n = sc->rve.n, p, k;
    double *xyz = NULL, *rad = NULL, *vel = NULL, *spin = NULL, *id = NULL;
    int *conn = NULL;
    gk_result r = GK_OK;
    const gk_allocator *a = &sc->def.rve.alloc;
    xyz = (double *)gk_alloc(a, (size_t)n * 3 * sizeof(double));
    vel = (double *)gk_alloc(a, (size_t)n * 3 * sizeof(double));
    rad = (double *)gk_alloc(a, (size_t)n * sizeof(double));
    spin = (double *)gk_alloc(a, (size_t)n * sizeof(double));
    id = (double *)gk_alloc(a, (size_t)n * sizeof(double));
    conn = (int *)gk_alloc(a, (size_t)n * sizeof(int));
    if (!xyz || !vel || !rad || !spin || !id || !conn)
        r = gk_err_set(err, GK_ERR_ALLOC, "out of memory writing %s", path);
    for (p = 0; !r && p < n; ++p) {
        double w2 = 0.0;
        gk_scene_position(sc, p, xyz + 3 * p);
        for (k = 0; k < 3; ++k) {
            vel[3 * p + k] = k < sc->dim ? (double)sc->rve.v[k][p] : 0.0;
            if (sc->rve.w[k]) w2 += (double)sc->rve.w[k][p] * (double)sc->rve.w[k][p];
        }
        spin[p] = sc->dim == 2 && sc->rve.w[2] ? (double)sc->rve.w[2][p] : sqrt(w2);
        rad[p] = (double)sc->rve.r[p];
        id[p] = (double)sc->rve.id[p];
        conn[p] = p;
    }
    if (!r) {
        r = gk_vtk_open(&v, path, "grainkit scene particles");
        if (!r) r = gk_vtk_points(&v, n, xyz);
        if (!r) r = gk_vtk_cells(&v, n, 1, conn, GK_VTK_VERTEX);
        if (!r) r = gk_vtk_point_scalar(&v, "radius", rad);
        if (!r) r = gk_vtk_point_vector(&v, "velocity", vel);
        if (!r) r = gk_vtk_point_scalar(&v, "spin", spin);
        if (!r) r = gk_vtk_point_scalar(&v, "id", id);
        if (v.fp) {
            gk_result rc = gk_vtk_close(&v);
            if (!r) r = rc;
        }
        if (r) gk_err_set(err, r, "cannot write %s", path);
    }
    gk_free(a, xyz);
    gk_free(a, vel);
    gk_free(a, rad);
    gk_free(a, spin);
    gk_free(a, id);
    gk_free(a, conn);
    return r;
}

/* outline of a wall clipped to the domain: 2D line segments (2 points each),
 * 3D quads (4 points each); returns the count written (at most cap) */
static int gk__wall_outline(const gk_scene *sc, const gk_wall *W, double *pts, int cap) {
    const gk_wall_def *d = &W->def;
    int dim = sc->dim, k, cnt = 0, np = dim == 2 ? 2 : 4, s;
    double span = 0.0, c[3];
    for (k = 0; k < dim; ++k) span += (sc->def.hi[k] - sc->def.lo[k]) * (sc->def.hi[k] - sc->def.lo[k]);
    span = sqrt(span);
    for (k = 0; k < 3; ++k) c[k] = W->pos[k];
    if (d->kind == GK_WALL_PLANE || d->kind == GK_WALL_SEGMENT || d->kind == GK_WALL_RECT) {
        double t1[3], t2[3], o[3];
        if (cap < 1) return 0;
        if (d->kind == GK_WALL_PLANE) {
            /* the domain's centre projected on the plane, tangents of length span */
            double mid[3], h;
            for (k = 0; k < 3; ++k) mid[k] = k < dim ? 0.5 * (sc->def.lo[k] + sc->def.hi[k]) : 0.0;
            h = 0.0;
            for (k = 0; k < 3; ++k) h += (mid[k] - c[k]) * d->normal[k];
            for (k = 0; k < 3; ++k) o[k] = mid[k] - h * d->normal[k];
            if (dim == 2) {
                t1[0] = -d->normal[1] * span;
                t1[1] = d->normal[0] * span;
                t1[2] = 0.0;
                for (k = 0; k < 3; ++k) t2[k] = 0.0;
            } else {
                double a[3] = {1, 0, 0}, l;
                if (fabs(d->normal[0]) > 0.9) a[0] = 0, a[1] = 1;
                gk_v3_cross(d->normal, a, t1);
                l = sqrt(gk__dot3(t1, t1));
                for (k = 0; k < 3; ++k) t1[k] *= span / l;
                gk_v3_cross(d->normal, t1, t2);
            }
            for (k = 0; k < 3; ++k) o[k] -= 0.5 * (t1[k] + t2[k]);
        } else {
            for (k = 0; k < 3; ++k) {
                o[k] = c[k];
                t1[k] = d->e1[k];
                t2[k] = d->kind == GK_WALL_RECT ? d->e2[k] : 0.0;
            }
        }
        for (k = 0; k < 3; ++k) {
            pts[k] = o[k];
            pts[3 + k] = o[k] + t1[k];
            if (dim == 3) {
                pts[6 + k] = o[k] + t1[k] + t2[k];
                pts[9 + k] = o[k] + t2[k];
            }
        }
        return 1;
    }
    /* disk: 32 chords; cylinder: 16 quads along the axis over the domain span */
    {
        int ns = dim == 2 ? 32 : 16;
        double u[3], v[3], len = dim == 3 ? span : 0.0;
        if (dim == 2) {
            u[0] = 1, u[1] = 0, u[2] = 0;
            v[0] = 0, v[1] = 1, v[2] = 0;
        } else {
            double a[3] = {1, 0, 0}, l;
            if (fabs(d->axis[0]) > 0.9) a[0] = 0, a[1] = 1;
            gk_v3_cross(d->axis, a, u);
            l = sqrt(gk__dot3(u, u));
            for (k = 0; k < 3; ++k) u[k] /= l;
            gk_v3_cross(d->axis, u, v);
        }
        for (s = 0; s < ns && cnt < cap; ++s, ++cnt) {
            double a0 = 2.0 * GK_PI * s / ns + W->angle, a1 = 2.0 * GK_PI * (s + 1) / ns + W->angle;
            double *q = pts + 3 * np * cnt;
            for (k = 0; k < 3; ++k) {
                double p0 = c[k] + d->radius * (cos(a0) * u[k] + sin(a0) * v[k]);
                double p1 = c[k] + d->radius * (cos(a1) * u[k] + sin(a1) * v[k]);
                if (dim == 2) {
                    q[k] = p0;
                    q[3 + k] = p1;
                } else {
                    q[k] = p0 - 0.5 * len * d->axis[k];
                    q[3 + k] = p1 - 0.5 * len * d->axis[k];
                    q[6 + k] = p1 + 0.5 * len * d->axis[k];
                    q[9 + k] = p0 + 0.5 * len * d->axis[k];
                }
            }
        }
        return cnt;
    }
}

GKDEF gk_result gk_scene_write_walls_vtk(const gk_scene *sc, const char *path, gk_err *err) {
    gk_vtk v;
    int np = sc->dim == 2 ? 2 : 4, w, cnt = 0, maxc = 0, c;
    double *pts, *wid, *fn;
    int *conn;
    gk_result r = GK_OK;
    const gk_allocator *a = &sc->def.rve.alloc;
    for (w = 0; w < sc->nwalls; ++w) maxc += 32;
    if (maxc == 0) maxc = 1;
    pts = (double *)gk_alloc(a, (size_t)maxc * (size_t)np * 3 * sizeof(double));
    wid = (double *)gk_alloc(a, (size_t)maxc * sizeof(double));
    fn = (double *)gk_alloc(a, (size_t)maxc * sizeof(double));
    conn = (int *)gk_alloc(a, (size_t)maxc * (size_t)np * sizeof(int));
    if (!pts || !wid || !fn || !conn) r = gk_err_set(err, GK_ERR_ALLOC, "out of memory writing %s", path);
    for (w = 0; !r && w < sc->nwalls; ++w) {
        int got = gk__wall_outline(sc, &sc->walls[w], pts + (size_t)cnt * np * 3, maxc - cnt);
        for (c = 0; c < got; ++c) {
            wid[cnt + c] = (double)w;
            fn[cnt + c] = sc->walls[w].resistance;
        }
        cnt += got;
    }
    for (c = 0; c < cnt * np; ++c) conn[c] = c;
    if (!r) {
        r = gk_vtk_open(&v, path, "grainkit scene walls");
        if (!r) r = gk_vtk_points(&v, cnt * np, pts);
        if (!r) r = gk_vtk_cells(&v, cnt, np, conn, sc->dim == 2 ? 3 /* VTK_LINE */ : GK_VTK_QUAD);
        if (!r) r = gk_vtk_cell_scalar(&v, "wall", wid);
        if (!r) r = gk_vtk_cell_scalar(&v, "resistance", fn);
        if (v.fp) {
            gk_result rc = gk_vtk_close(&v);
            if (!r) r = rc;
        }
        if (r) gk_err_set(err, r, "cannot write %s", path);
    }
    gk_free(a, pts);
    gk_free(a, wid);
    gk_free(a, fn);
    gk_free(a, conn);
    return r;
}

GKDEF gk_result gk_scene_write_svg(const gk_scene *sc, const char *path, const char *title, const char *label,
                                   const double *value, gk_err *err) {
    enum { NV = 12 };
    int n = sc->rve.n, p, q;
    double *xy, *val;
    gk_result r;
    const gk_allocator *a = &sc->def.rve.alloc;
    if (sc->dim != 2) return gk_err_set(err, GK_ERR_UNSUPPORTED, "the SVG picture is 2D");
    xy = (double *)gk_alloc(a, (size_t)n * NV * 2 * sizeof(double));
    val = (double *)gk_alloc(a, (size_t)n * sizeof(double));
    if (!xy || !val) {
        gk_free(a, xy);
        gk_free(a, val);
        return gk_err_set(err, GK_ERR_ALLOC, "out of memory writing %s", path);
    }
    for (p = 0; p < n; ++p) {
        double x[3], rr = (double)sc->rve.r[p];
        gk_scene_position(sc, p, x);
        for (q = 0; q < NV; ++q) {
            xy[2 * (NV * p + q)] = x[0] + rr * cos(2.0 * GK_PI * q / NV);
            xy[2 * (NV * p + q) + 1] = x[1] + rr * sin(2.0 * GK_PI * q / NV);
        }
        val[p] = value ? value[p]
                       : sqrt((double)sc->rve.v[0][p] * (double)sc->rve.v[0][p] +
                              (double)sc->rve.v[1][p] * (double)sc->rve.v[1][p]);
    }
    r = gk_svg_field(path, title, label ? label : (value ? "value" : "speed [m/s]"), n, NV, xy, val, 0.0,
                     err);
    gk_free(a, xy);
    gk_free(a, val);
    return r;
}

#endif /* GK_SCENE implementation */
