/* mpmdem_footing.c - the MPMxDEM rigid footing of Liang & Zhao (2019)
 * Sec 3.3: a rigid rough strip footing pushed into a weightless soil with a
 * 20 kPa surcharge; every material point has its own periodic 400-disk RVE.
 * Load-settlement curve, the bearing-capacity factor N_q = p_u / q_s (eq 45)
 * against Prandtl's N_q = tan^2(pi/4 + phi/2) exp(pi tan phi) (eq 46; eq 47
 * phi_r = atan(2/3 tan phi) for local / punching failure), with phi the
 * friction angle of the RVE MEASURED here by single-RVE drained biaxial
 * tests; the failure mode picture (eps_q field). The paper: N_q 14.4 (MPMxDEM)
 * vs 14.8 (eq 46, phi = 28.1 deg) for the dense packing.
 *
 *   build/mpmdem_footing                  # reduced default (about a minute)
 *   build/mpmdem_footing --paper          # 12 x 8 m, 108 x 72 cells, 7776 RVEs
 *   mpirun -np 2 build/mpmdem_footing_mpi --threads 1   # the RVEs on 2 ranks
 *
 * GEOMETRY (half model, x = 0 is the symmetry plane). The paper: soil 12 m
 * wide, 8 m deep, footing "1 m x 2 m (width x height)", d/B = 1.5 at the end.
 * B here is the FULL footing width, B = 1 m: the footing is 2 m tall and
 * must still stick out of the ground at d = 1.5 B, so B <= 1.33 m, and
 * "width" is the physical footing's. The half model therefore carries the
 * half-width b = B/2 = 0.5 m (--B changes it). Loads are per unit length
 * (plane strain) OF THE HALF MODEL: the footing pressure is q = load / b
 * (= full load / B); N_q does not depend on B for a weightless soil, only
 * the resolution b/h and the domain size in footing widths do.
 *
 * BOUNDARIES. Left (x = 0): roller (symmetry plane). Right: smooth rigid
 * wall = roller. Base: fixed. Top: the surcharge q_s as a follower load
 * (mpd_edge, mpmdem.h: the edge turns and stretches with F, its load goes
 * to the nodes with the weights of the edge) on the top edges of the top row
 * of points beyond the footing edge x = b. The footing is a gk_mpm_body box
 * (its ghost part too), STICK contact (rough base and side), prescribed
 * velocity -v ramped up linearly over --ramp seconds; load = -force_y (the
 * reaction, per unit length of the half model), averaged over each output
 * interval. FOOTING EDGE: a nodal rigid body covering the nodes x <= x_k
 * carries a uniform stress over x <= x_k + h/2 (each node's tributary
 * width), so the body covers x <= B/2 - h/2 and b = x_k + h/2 = B/2 exactly
 * when B/2 = (k + 1/2) h (the default h = 0.2 and the paper's h = 1/9 m
 * are; otherwise b is the nearest such width below B/2, printed, and q =
 * load / b). Covering x <= B/2 instead makes the footing half a cell wider
 * than b: +25 % load at b = 2 h.
 *
 * INITIAL STATE. Weightless soil under a uniform 20 kPa surface load is at
 * sigma = -20 kPa I everywhere (roller walls, fixed base): every RVE is the
 * packing consolidated ISOTROPICALLY to q_s by mpd_prepare_rve (one prepared
 * RVE copied to every point), so the model starts in equilibrium and the
 * footing's first reaction is q_s b.
 *
 * MATERIAL = Liang & Zhao Table 2 (--material dense | medium | soft): E, kt/kn
 * (the table's nu), interparticle friction, rolling beta and eta, local
 * damping 0.1. "Medium dense" differs from "dense" only by e0 (0.2314 vs
 * 0.1874): give it a looser packing with --packing (the default one is
 * dense: e ~ 0.18 at 20 kPa; examples/data/rve400_e0223.txt is looser). DEM
 * step: 3.16e-5 s sqrt(6e8 / E), the same
 * fraction of the critical step as Guo & Zhao's (2014) 3.16e-5 s at E = 600 MPa.
 *
 * FRICTION ANGLE (what eq 46 needs), measured before the footing by drained
 * biaxial tests of one RVE per confining pressure (--phi-pressures, default
 * 10, 20, 30 kPa; the paper used 10..30 kPa), prepared like the footing's
 * RVEs and compressed at the rate the MPM's RVEs deform at (mpmdem_phi.h):
 * phi from the Mohr-Coulomb envelope of the peaks through the origin,
 * phi_res from that of the softened ends (not yet a critical state at 8 %):
 * the dense RVE peaks at ~0.7 % and loses ~7 deg, and a footing on it fails
 * progressively, so its N_q lies between eq 46 of phi_res and of phi; the
 * output also gives the phi whose eq 46 is the computed N_q. Nothing is
 * cached: every run measures (or --phi-deg X skips it); --phi-only measures,
 * prepares the RVE at q_s (its e0) and exits: the cheap way to tune a packing.
 *
 * ULTIMATE LOAD (Vesic's rule, as the paper: the first point where the slope
 * of the load-settlement curve reaches zero, or its steady minimum). The
 * curve of an explicit MPM with points crossing cells is noisy, so: (1)
 * centred moving average of q over a window of --smooth (in d/B); (2) a
 * PEAK is the first row whose smoothed q is the largest of everything up to
 * one window after it (zero slope, not a wiggle), at least one window
 * before the end (confirmed); (3) otherwise the curve hardens: slope s by
 * central differences of the smoothed curve, s0 its largest value, s_min
 * its smallest after that; the ultimate is the first row with s <= s_min +
 * 0.1 (s0 - s_min) from which the slope stays inside that band to the end
 * (steady minimum slope), again one window before the end. If neither is
 * found the output says "ultimate load NOT reached" and N_q is the value at
 * the last row (RESULT ultimate_reached=0).
 *
 * MECHANISM (footing_mech.h), at every CSV row from the points: the wedge
 * angle (in each column of cells under the footing, the depth of the largest
 * eps_q; the line through the footing's corner fitted to them), and the
 * heave (the surface row's largest uplift beyond the footing, and the
 * outermost x where it is still 10 % of that); printed and in RESULT at the
 * ultimate load's row and at the end, next to Prandtl's pi/4 + phi/2 and
 * the x where his passive zone meets the ground.
 *
 * TIME STEP, DEM STEPS: mpmdem.h (dt = cfl h / c from the RVE's Taylor
 * tangent; DEM steps per MPM step by its --dem-rule, default adaptive).
 *
 * RATE. The PIC part of the PIC/FLIP blend damps like a viscosity: its
 * shear stress is of order rho alpha c v / cfl (~6 kPa at alpha 0.1, 0.1
 * m/s here), not small next to the strength of a soil at 20 kPa, so N_q
 * grows with alpha v (measured with --dem-rule strain on the 18 x 12 grid:
 * 12.8 at 0.1 m/s, 15.2 at 0.25 m/s, 11.9 at 0.25 m/s with alpha 0; on a
 * 24 x 16 grid 1 m/s gave ~1.5 x the 0.25 m/s value). The default keeps
 * the paper's alpha = 0.1 and 0.1 m/s.
 *
 * SIZE AND COST. The paper's grid (--paper: 12 x 8 m, 108 x 72 cells, h =
 * 0.111 m, 1 point per cell = 7776 RVEs x 400 disks, 0.1 m/s to d/B = 1.5)
 * takes hours. The default is a reduced problem that finishes in about a
 * minute on 2 idle cores and still reaches the ultimate load: a 6 x 3 m
 * domain (the Prandtl mechanism of phi <= 32 deg reaches 5.3 B from the
 * axis and ~1.5 B deep), h = 0.2 m (b = 2.5 cells, 450 RVEs), the paper's
 * 0.1 m/s, to d/B = 0.14 (the dense footing peaks at d/B ~ 0.06). The run
 * prints its memory (VmHWM, per RVE) and projects the paper-size memory and
 * wall time; --max-steps N stops early (e.g. a 5-step run at the paper's
 * size to measure both there).
 *
 * Outputs in --out DIR (default build/mpm_footing): footing.csv
 * (load-settlement), footing_load.svg, rve_biaxial.svg and rve_mohr.svg (phi
 * measurement), eps_q_dB*.svg (stages, one colour scale) and eps_q_end.svg,
 * rotation_end.svg, void_ratio_end.svg, displacement_end.svg (failure mode;
 * the footing, the wall and the base drawn on the points), points_NNNNNN.vtk,
 * checkpoint.bin; a RESULT line.
 */

#define GK_IMPLEMENTATION
#include "mpmdem.h"
#include "mpmdem_phi.h"
#include "footing_mech.h"

#define FT_NSTAGE 6
#define FT_DEM_DT_REF 3.16e-5 /* Guo & Zhao's DEM step at E = 600 MPa */

typedef struct ft_opts {
    int nx, ny, material, paper;
    double width, depth, B, foot_height, surcharge, velocity, ramp, final_dB, every, smooth;
    double phi_deg; /* > 0: skip the measurement */
    double phi_p[FT_MAXPHI];
    int nphi;
    const char *phi_list;
    double phi_strain;   /* largest axial strain of a biaxial RVE test */
    double grid_damping; /* local non-viscous grid damping (0: none, as the paper) */
    int max_steps;       /* 0: no limit */
    int phi_only;        /* 1: measure the angle, prepare one RVE at q_s, print, exit */
} ft_opts;

typedef struct ft_row { /* one CSV row: means over an output interval; the mechanism at its end */
    double t, d, q, load, ek, dem_mean, secs;
    double wedge, heave_x, heave_u; /* footing_mech.h: wedge angle [deg], heave's outer x and top [m] */
} ft_row;

/* what a checkpoint carries besides points and RVEs */
typedef struct ft_state {
    long step;
    double t, disp;
    gk_mpm_body body;
    double acc_load, acc_dt, acc_ek, acc_dem; /* sums since the last row */
    long nacc;
    double next_out; /* settlement d/B of the next row */
    int nstage;
    double wall; /* wall seconds of the runs before this one */
} ft_state;

typedef struct ft { /* the whole model */
    mpd_run run;
    mpd_opts o;
    ft_opts f;
    mpd_proto P;
    gk_rve_state st0;
    mpd_micro M;
    gk_mpm_grid g;
    gk_mpm_points pts;
    gk_mpm_def def;
    mpd_edge *edge;
    int nedge, measured;
    double *x0; /* initial point positions (displacement field) */
    ft_state S;
    mpd_rows rows;
    mpd_snaps snaps;
    double h, b, bnode, dt, c, dot, phi, phi_res, rss_before, rss_after, t_first;
    long long dem_first;
} ft;

static const char *material_names[3] = {"dense", "medium", "soft"};
static const double table2_e0[3] = {0.1874, 0.2314, 0.2299};
static const double paper_phi[3] = {28.1, 20.8, 18.2};
static const double paper_nq[3] = {14.4, 4.8, 3.7};
static const double paper_nq_analytic[3] = {14.8, 3.7, 3.1};
static const double ft_stages[FT_NSTAGE] = {0.05, 0.1, 0.25, 0.5, 1.0, 1.5};

/* Liang & Zhao Table 2 (400 disks, r 3-7 mm, rho 2650, nu = kt/kn 0.5, beta 1.0, alpha 0.1) */
static void apply_material(mpd_opts *o, int m) {
    o->young = m == 2 ? 80e6 : 800e6;
    o->kt_ratio = 0.5;
    o->friction_deg = m == 2 ? 20.0 : 23.0;
    o->roll_beta = 1.0;
    o->roll_eta = m == 2 ? 0.02 : 0.05;
    o->dem_damping = 0.1;
}

/* the defaults, with the presets of --material m and --paper */
static void defaults(ft *X, int material, int paper) {
    ft_opts *f = &X->f;
    memset(f, 0, sizeof *f);
    f->nx = 30, f->ny = 15, f->width = 6.0, f->depth = 3.0, f->B = 1.0, f->foot_height = 2.0;
    f->surcharge = 2e4, f->velocity = 0.1, f->ramp = 0.1, f->final_dB = 0.14, f->every = 0.005;
    f->smooth = 0.04, f->phi_strain = 0.08;
    f->nphi = 3, f->phi_p[0] = 1e4, f->phi_p[1] = 2e4, f->phi_p[2] = 3e4;
    if (paper)
        f->width = 12.0, f->depth = 8.0, f->nx = 108, f->ny = 72, f->velocity = 0.1, f->ramp = 0.5,
        f->final_dB = 1.5, f->every = 0.01, f->smooth = 0.05;
    mpd_opts_default(&X->o, "build/mpm_footing");
    apply_material(&X->o, material);
    X->o.dem_dt = FT_DEM_DT_REF * sqrt(6e8 / X->o.young);
}

static void usage(FILE *fp) {
    ft X;
    defaults(&X, 0, 0);
    fprintf(
        fp,
        "mpmdem_footing - MPMxDEM rigid rough strip footing of Liang & Zhao (2019) Sec 3.3: weightless "
        "soil,\n"
        "surcharge, half model (symmetry plane at x = 0, smooth right wall, fixed base), every material "
        "point\n"
        "a periodic 400-disk RVE; load-settlement curve, N_q vs eqs 45-47 with the RVE's measured friction "
        "angle.\n\n"
        "usage: mpmdem_footing [options]\n"
        "  --nx N --ny N          cells across the width and the depth (default %d x %d; paper 108 x 72)\n"
        "  --width W --depth D    soil domain of the half model [m] (default %g x %g; paper 12 x 8);\n"
        "                         W/nx must equal D/ny\n"
        "  --paper                the paper's size: 12 x 8 m, 108 x 72 cells (7776 RVEs), 0.1 m/s, ramp 0.5 "
        "s,\n"
        "                         to d/B = 1.5, rows every 0.01 (other flags given override it)\n"
        "  --B W                  FULL footing width [m] (default %g: the paper's 1 m x 2 m footing); the\n"
        "                         half model carries b = B/2; q = load / b\n"
        "  --footing-height H     footing height above the ground [m] (default %g)\n"
        "  --surcharge Q          surcharge q_s on the ground outside the footing [Pa] (default %g)\n"
        "  --velocity V           footing speed [m/s] (default %g; the paper's 0.1)\n"
        "  --ramp T               the speed ramps up linearly over T seconds (default %g)\n"
        "  --final X              final settlement d/B (default %g; the paper's 1.5)\n"
        "  --every X              d/B between CSV rows (default %g)\n"
        "  --smooth X             moving-average window in d/B for the ultimate-load rule (default %g)\n",
        X.f.nx, X.f.ny, X.f.width, X.f.depth, X.f.B, X.f.foot_height, X.f.surcharge, X.f.velocity, X.f.ramp,
        X.f.final_dB, X.f.every, X.f.smooth);
    fprintf(
        fp,
        "  --material M           dense | medium | soft: Liang & Zhao Table 2 contact parameters (default\n"
        "                         dense: E 800 MPa, kt/kn 0.5, friction 23 deg, beta 1.0, eta 0.05, damping\n"
        "                         0.1; soft: E 80 MPa, 20 deg, eta 0.02; medium = dense with e0 0.2314:\n"
        "                         give it a looser --packing). --young etc. given too override it.\n"
        "  --phi-deg X            friction angle for eq 46 [deg]; skips the RVE biaxial measurement\n"
        "  --phi-pressures LIST   confining pressures of the measurement [kPa], comma-separated, at most %d\n"
        "                         (default 10,20,30; the paper used 10,15,20,25,30)\n"
        "  --phi-strain E         axial strain a measurement test runs to at least; then on until its peak "
        "lies\n"
        "                         1 %% behind, at most 25 %% (default %g)\n"
        "  --grid-damping A       local non-viscous damping on the grid nodes in [0, 1) (default %g: none,\n"
        "                         as the paper; reactions never include it)\n"
        "  --max-steps N          stop after N MPM steps (timing / memory probe; default: no limit)\n"
        "  --phi-only             only the friction-angle measurement and the RVE at q_s (e0), then exit\n"
        "                         (RESULT phi_deg=... phi_res_deg=... e0=... p0=... seconds=...)\n"
        "  --help                 this text\n",
        FT_MAXPHI, X.f.phi_strain, X.f.grid_damping);
    mpd_usage_common(fp, &X.o);
    fprintf(
        fp,
        "  (footing: --dem-dt defaults to 3.16e-5 s x sqrt(6e8 / E), Guo & Zhao's fraction of the critical "
        "step)\n"
        "\noutputs in --out: footing.csv (time,d,d_over_B,q,q_over_qs,load_half,kinetic_energy,\n"
        "  dem_steps_per_point,seconds,wedge_deg,heave_x_over_B,heave_over_B), footing_load.svg, "
        "rve_biaxial.svg, rve_mohr.svg, eps_q_dB*.svg,\n"
        "  eps_q_end.svg, rotation_end.svg, void_ratio_end.svg, displacement_end.svg, points_*.vtk,\n"
        "  checkpoint.bin\n"
        "ends with: RESULT Nq=... Nq_analytic=... Nq_analytic_local=... phi_deg=... phi_res_deg=...\n"
        "           Nq_analytic_res=... phi_mobilised_deg=... q_ult=... d_ult_over_B=... "
        "ultimate_reached=...\n"
        "           n_rves=... mpm_steps=... dt=... seconds_per_step=... seconds_per_step_per_1000_rves=...\n"
        "           seconds_per_step_per_1000_rves_after_first=... mem_per_rve_kb=... vmhwm_mb=... "
        "total_seconds=...\n"
        "           wedge_deg=... wedge_prandtl_deg=... heave_x_over_B=... heave_width_over_B=... "
        "heave_over_B=...\n"
        "           prandtl_reach_over_B=... wedge_end_deg=... heave_x_end_over_B=...\n");
}

/* the flags, twice: the presets (--material, --paper) first, then every flag given over them */
static int parse(ft *X, int argc, char **argv) {
    ft_opts *f = &X->f;
    const cli_opt mine[] = {
        {"--nx", CLI_INT, &f->nx, 1, 4000, NULL, NULL, 0},
        {"--ny", CLI_INT, &f->ny, 1, 4000, NULL, NULL, 0},
        {"--width", CLI_REAL, &f->width, 0, 1e4, NULL, NULL, CLI_LO_OPEN},
        {"--depth", CLI_REAL, &f->depth, 0, 1e4, NULL, NULL, CLI_LO_OPEN},
        {"--paper", CLI_FLAG, &f->paper, 0, 0, NULL, NULL, 0},
        {"--B", CLI_REAL, &f->B, 0, 1e4, NULL, NULL, CLI_LO_OPEN},
        {"--footing-height", CLI_REAL, &f->foot_height, 0, 1e4, NULL, NULL, CLI_LO_OPEN},
        {"--surcharge", CLI_REAL, &f->surcharge, 0, 1e10, NULL, NULL, CLI_LO_OPEN},
        {"--velocity", CLI_REAL, &f->velocity, 0, 1e3, NULL, NULL, CLI_LO_OPEN},
        {"--ramp", CLI_REAL, &f->ramp, 0, 1e6, NULL, NULL, 0},
        {"--final", CLI_REAL, &f->final_dB, 0, 3, NULL, NULL, CLI_LO_OPEN},
        {"--every", CLI_REAL, &f->every, 0, 3, NULL, NULL, CLI_LO_OPEN},
        {"--smooth", CLI_REAL, &f->smooth, 0, 3, NULL, NULL, CLI_LO_OPEN},
        {"--material", CLI_CHOICE, &f->material, 0, 0, NULL, "dense|medium|soft", 0},
        {"--phi-deg", CLI_REAL, &f->phi_deg, 0, 60, "an angle in (0, 60) deg", NULL,
         CLI_LO_OPEN | CLI_HI_OPEN},
        {"--phi-pressures", CLI_STR, &f->phi_list, 0, 0, NULL, NULL, 0},
        {"--phi-strain", CLI_REAL, &f->phi_strain, 0.01, FT_PHI_STRAIN_MAX, NULL, NULL, 0},
        {"--grid-damping", CLI_REAL, &f->grid_damping, 0, 1, NULL, NULL, CLI_HI_OPEN},
        {"--max-steps", CLI_INT, &f->max_steps, 1, 2000000000, NULL, NULL, 0},
        {"--phi-only", CLI_FLAG, &f->phi_only, 0, 0, NULL, NULL, 0},
        {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    int r, k;
    defaults(X, 0, 0);
    if ((r = mpd_parse(&X->run, argc, argv, &X->o, mine, usage)) != 0) return r;
    r = f->material, k = f->paper;
    defaults(X, r, k);
    X->o.dem_dt = -1.0; /* not given: from E below */
    mpd_parse(&X->run, argc, argv, &X->o, mine, usage);
    if (X->o.dem_dt < 0) X->o.dem_dt = FT_DEM_DT_REF * sqrt(6e8 / X->o.young);
    X->run.out = X->o.out;
    if (mpd_check_opts(&X->run, &X->o)) return 2;
    if (f->phi_list) {
        if ((f->nphi = mpd_list(&X->run, "--phi-pressures", f->phi_list, f->phi_p, FT_MAXPHI, 0, 1, 1e7, 0)) <
            0)
            return 2;
        for (k = 0; k < f->nphi; ++k) f->phi_p[k] *= 1e3;
    }
    if (f->phi_only && f->phi_deg > 0)
        return fprintf(stderr, "mpmdem_footing: --phi-only measures the angle: it cannot take --phi-deg\n"),
               2;
    if (f->phi_only && X->o.restart)
        return fprintf(stderr, "mpmdem_footing: --phi-only starts fresh: it cannot take --restart\n"), 2;
    if (f->every > f->final_dB)
        return fprintf(stderr, "mpmdem_footing: --every %g is out of range: exceeds --final %g\n", f->every,
                       f->final_dB),
               2;
    X->h = f->width / f->nx;
    /* the footing covers the nodes x <= b - h/2; their tributary width (the reach of a uniform stress
     * under them) ends half a cell further: that is the effective half-width, = b when b/h = k + 1/2 */
    X->bnode = floor((0.5 * f->B - 0.5 * X->h) / X->h + 1e-9) * X->h;
    X->b = X->bnode + 0.5 * X->h;
    if (fabs(f->depth / f->ny - X->h) > 1e-9 * X->h)
        return fprintf(stderr, "mpmdem_footing: cells must be square: width/nx = %g, depth/ny = %g\n", X->h,
                       f->depth / f->ny),
               2;
    if (X->bnode < X->h * (1 - 1e-9) || X->b > 0.5 * f->width)
        return fprintf(stderr,
                       "mpmdem_footing: the half footing B/2 = %g m must span at least 1.5 cells (h = %g m) "
                       "and at most half the width\n",
                       0.5 * f->B, X->h),
               2;
    if (f->final_dB * f->B >= 0.9 * f->depth)
        return fprintf(stderr, "mpmdem_footing: --final %g: the footing would reach the base\n", f->final_dB),
               2;
    return 0;
}

/* kB of a /proc/self/status line ("VmHWM", "VmRSS"); -1 if unavailable */
static double proc_kb(const char *key) {
    FILE *fp = fopen("/proc/self/status", "r");
    char line[256];
    double v = -1.0;
    size_t n = strlen(key);
    if (!fp) return -1.0;
    while (fgets(line, sizeof line, fp))
        if (!strncmp(line, key, n) && line[n] == ':') {
            v = atof(line + n + 1);
            break;
        }
    fclose(fp);
    return v;
}

/* the friction angle (given or measured), the RVE at q_s at every point, the grid with its walls and
 * the footing, the points and the surcharge on the ground beyond the footing */
static int setup(ft *X, gk_err *err) {
    const ft_opts *f = &X->f;
    ft_state *S = &X->S;
    double h = X->h, org[3], lo[3] = {0, 0, 0}, hi[3];
    int n[3], i, gl = mpd_ghost_layers(&X->o), up = gl + (int)ceil(fmax(f->final_dB * f->B, 2 * h) / h);
    if (mpd_proto_open(&X->P, &X->o, err)) return 1;
    /* the packing read and the checkpoint there to read: now the output folder (the friction-angle
     * measurement writes into it; the checkpoint is read after it) */
    if (X->o.restart) { /* rank 0 reads the checkpoint: its verdict on every rank */
        char path[MPD_PATH];
        FILE *fp = NULL;
        if (X->run.rank == 0 && !mpd_checkpoint_path(X->o.restart, path)) fp = fopen(path, "rb");
        if (fp) fclose(fp);
        if (mpd_agree(&X->run, X->run.rank == 0 && !fp))
            return gk_err_set(err, GK_ERR_IO, "--restart %s: cannot open %s/checkpoint.bin", X->o.restart,
                              X->o.restart),
                   1;
    }
    if (mpd_out_dir(&X->run)) return gk_err_set(err, GK_ERR_IO, "no output folder (above)"), 1;
    printf("mpmdem_footing: Liang & Zhao Table 2 '%s': E = %g MPa, kt/kn = %g, friction %g deg, beta %g, eta "
           "%g, "
           "damping %g; DEM dt = %.3g s\n",
           material_names[f->material], X->o.young / 1e6, X->o.kt_ratio, X->o.friction_deg, X->o.roll_beta,
           X->o.roll_eta, X->o.dem_damping, X->o.dem_dt);
    if (f->material == 1 && !strcmp(X->o.packing, "examples/data/rve400.txt"))
        printf("note: 'medium' has Table 2's dense contact law; with the shipped dense packing it is the "
               "dense soil "
               "(give a looser --packing for e0 = 0.2314, e.g. examples/data/rve400_e0223.txt)\n");
    X->phi = f->phi_deg, X->phi_res = NAN;
    if (f->phi_deg > 0)
        printf("friction angle: phi = %g deg given (--phi-deg), no measurement\n", X->phi);
    else if (phi_measure(&X->run, &X->P, &X->o, f->phi_p, f->nphi, f->phi_strain, material_names[f->material],
                         paper_phi[f->material], &X->phi, &X->phi_res))
        return gk_err_set(err, GK_ERR_STATE, "the friction angle could not be measured (above)"), 1;
    else
        X->measured = 1;
    if (mpd_prepare_rve(&X->P, f->surcharge, &X->st0, err)) return 1;
    if (f->phi_only) return 0; /* no grid, no points: run() prints and stops */
    X->c = sqrt(X->P.M / X->P.rho);
    X->dt = X->o.cfl * h / X->c;
    /* grid: ghost layers; room above the ground for the heave */
    org[0] = -gl * h, org[1] = -gl * h, org[2] = 0;
    n[0] = f->nx + 2 * gl + 1, n[1] = f->ny + gl + up + 1, n[2] = 1;
    hi[0] = f->width, hi[1] = f->depth, hi[2] = 0;
    if (gk_mpm_grid_create(&X->g, 2, org, h, n, NULL, err) ||
        gk_mpm_grid_set_bc(&X->g, 0, GK_MPM_BC_ROLLER, 0, gl + 1, err) || /* symmetry plane x = 0 */
        gk_mpm_grid_set_bc(&X->g, 1, GK_MPM_BC_ROLLER, 0, gl + 1, err) || /* smooth wall x = W */
        gk_mpm_grid_set_bc(&X->g, 2, GK_MPM_BC_FIXED, 0, gl + 1, err) ||  /* base y = 0 */
        gk_mpm_points_create_box(&X->pts, 2, lo, hi, h, X->o.ppc, X->P.rho, NULL, err))
        return 1;
    X->rss_before = proc_kb("VmRSS");
    if (mpd_micro_create(&X->M, &X->pts, &X->P, &X->st0, 1, NULL, &X->o, err)) return 1;
    X->rss_after = proc_kb("VmRSS");
    X->edge = (mpd_edge *)calloc((size_t)X->pts.n, sizeof *X->edge);
    X->x0 = (double *)malloc(2 * (size_t)X->pts.n * sizeof *X->x0);
    if (!X->edge || !X->x0) return gk_err_set(err, GK_ERR_ALLOC, "out of memory"), 1;
    for (i = 0; i < X->pts.n; ++i) {
        double a = 0.5 * h / X->o.ppc, xl = X->pts.x[0][i] - a, xr = X->pts.x[0][i] + a;
        mpd_edge *E = &X->edge[X->nedge];
        X->x0[2 * i] = X->pts.x[0][i], X->x0[2 * i + 1] = X->pts.x[1][i];
        if (X->pts.x[1][i] < f->depth - 2 * a || xr <= X->b + 1e-9 * h) continue;
        if (xl < X->b) xl = X->b; /* the part of the top edge beyond the footing edge */
        E->p = i, E->pressure = f->surcharge;
        E->off[0] = 0.5 * (xl + xr) - X->pts.x[0][i], E->off[1] = a;
        E->e[0] = -(xr - xl), E->e[1] = 0; /* outward normal (e_y, -e_x) = up */
        ++X->nedge;
    }
    X->def = mpd_mpm_def(&X->o);
    X->def.damping = f->grid_damping;
    X->dot = 0.5 * h / X->o.ppc;
    memset(S, 0, sizeof *S);
    S->body.lo[0] = org[0] - h, S->body.hi[0] = X->bnode + 1e-9 * h;
    S->body.lo[1] = f->depth - 1e-9 * h, S->body.hi[1] = f->depth + f->foot_height;
    S->body.contact = GK_MPM_CONTACT_STICK;
    S->next_out = 0.0; /* a row after the first step (d ~ 0) */
    X->rows.size = sizeof(ft_row);
    if (X->o.restart &&
        mpd_load(X->o.restart, &X->M, &X->pts, "footing", S, sizeof *S, &X->rows, &X->snaps, NULL, err))
        return 1;
    X->g.body = &S->body, X->g.nbody = 1;
    return 0;
}

/* the footing (its base and edge, a stub of its height), the smooth wall and the base */
static void outline(const ft *X, mpd_outline *ol) {
    double W = X->f.width, D = X->f.depth, yb = D - X->S.disp, hs = fmin(X->f.foot_height, 3 * X->h);
    double foot[8], box[6];
    foot[0] = 0, foot[1] = yb + hs, foot[2] = X->b, foot[3] = yb + hs, foot[4] = X->b, foot[5] = yb,
    foot[6] = 0, foot[7] = yb;
    box[0] = 0, box[1] = 0, box[2] = W, box[3] = 0, box[4] = W, box[5] = D + 2 * X->h;
    memset(ol, 0, sizeof *ol);
    mpd_outline_add(ol, 4, foot);
    mpd_outline_add(ol, 3, box);
}

static int snap_field(ft *X, int k, const char *file, const char *title) {
    mpd_outline ol;
    outline(X, &ol);
    return mpd_snap_field(&X->run, &X->snaps, &X->M, &X->pts, k, file, title, X->dot, &ol);
}

/* |u| of the points at the end */
static int displacement_field(ft *X) {
    int n = X->pts.n, p, bad;
    double *u = (double *)malloc((size_t)n * sizeof *u + 1);
    mpd_outline ol;
    if (!u) return fprintf(stderr, "mpmdem_footing: out of memory\n"), 1;
    for (p = 0; p < n; ++p) {
        double dx = X->pts.x[0][p] - X->x0[2 * p], dy = X->pts.x[1][p] - X->x0[2 * p + 1];
        u[p] = sqrt(dx * dx + dy * dy);
    }
    outline(X, &ol);
    bad =
        mpd_snap_add(&X->run, &X->snaps, "displacement_end",
                     "displacement |u| at the end (Liang & Zhao Fig 14)", "|u| [m]", &X->pts, u, X->dot, &ol);
    free(u);
    return bad;
}

static void put_csv(FILE *fp, const void *user) {
    const ft *X = (const ft *)user;
    int k;
    fprintf(fp, "time,d,d_over_B,q,q_over_qs,load_half,kinetic_energy,dem_steps_per_point,seconds,"
                "wedge_deg,heave_x_over_B,heave_over_B\n");
    for (k = 0; k < X->rows.n; ++k) {
        const ft_row *r = (const ft_row *)mpd_row(&X->rows, k);
        fprintf(fp, "%.6g,%.6g,%.6g,%.9g,%.6g,%.9g,%.6g,%.4g,%.3f,%.5g,%.5g,%.5g\n", r->t, r->d,
                r->d / X->f.B, r->q, r->q / X->f.surcharge, r->load, r->ek, r->dem_mean, r->secs, r->wedge,
                r->heave_x / X->f.B, r->heave_u / X->f.B);
    }
}

/* the ultimate load by the rule of the top comment; returns the row index
 * (or the last row if not reached) and sets *reached, *mode */
static int ultimate(const double *x, const double *q, int n, double w, double *qsm, int *reached,
                    const char **mode) {
    int k, j, js = 0, end = n - 1;
    double *s = NULL, s0 = -HUGE_VAL, smin = HUGE_VAL;
    *reached = 0, *mode = "not reached";
    if (n < 3) return n - 1;
    smooth_curve(x, q, n, w, qsm);
    while (end > 0 && x[n - 1] - x[end] < w) --end; /* rows that have a full window after them */
    for (k = 1; k <= end; ++k) {                    /* 1: zero slope = a confirmed maximum */
        int ok = 1;
        for (j = 0; j < n && ok; ++j)
            if (x[j] <= x[k] + w && qsm[j] > qsm[k]) ok = 0;
        if (ok && qsm[k] > qsm[0]) {
            *reached = 1, *mode = "peak (zero slope)";
            return k;
        }
    }
    s = (double *)malloc((size_t)n * sizeof *s);
    if (!s) return n - 1;
    for (k = 1; k < n - 1; ++k) s[k] = (qsm[k + 1] - qsm[k - 1]) / (x[k + 1] - x[k - 1]);
    s[0] = s[1], s[n - 1] = s[n - 2];
    for (k = 0; k < n; ++k)
        if (s[k] > s0) s0 = s[k], js = k;
    for (k = js; k < n; ++k)
        if (s[k] < smin) smin = s[k];
    for (k = js + 1; k <= end; ++k) {
        double band = smin + 0.1 * (s0 - smin);
        int ok = s[k] <= band;
        for (j = k; ok && j < n; ++j)
            if (s[j] > band) ok = 0;
        if (ok) {
            *reached = 1, *mode = "steady minimum slope";
            free(s);
            return k;
        }
    }
    free(s);
    return n - 1;
}

static int load_plot(const ft *X, const double *qsm, int ku, double nq46, double nq47) {
    int n = X->rows.n, k, s, bad;
    double *x = (double *)malloc(3 * (size_t)n * sizeof *x + 1), *y = x + n, *ys = y + n, hx[2], h1[2], h2[2],
           ux[1], uy[1], B = X->f.B, qs = X->f.surcharge;
    char l1[80], l2[80], lu[80];
    gk_plot pl;
    if (!x) return fprintf(stderr, "mpmdem_footing: out of memory\n"), 1;
    for (k = 0; k < n; ++k) {
        const ft_row *r = (const ft_row *)mpd_row(&X->rows, k);
        x[k] = r->d / B, y[k] = r->q / qs, ys[k] = qsm[k] / qs;
    }
    gk_plot_init(&pl, "MPMxDEM rigid footing: load-settlement (Liang & Zhao Fig 16)", "settlement d/B",
                 "footing pressure q / q_s");
    gk_plot_add(&pl, x, y, n, "q / q_s (interval means)");
    gk_plot_add(&pl, x, ys, n, "smoothed (ultimate-load rule)");
    hx[0] = 0, hx[1] = x[n - 1], h1[0] = h1[1] = nq46, h2[0] = h2[1] = nq47;
    snprintf(l1, sizeof l1, "N_q eq 46, phi = %.1f deg: %.2f", X->phi, nq46);
    snprintf(l2, sizeof l2, "N_q eq 47, phi_r = %.1f deg: %.2f", phi_reduced(X->phi), nq47);
    if ((s = gk_plot_add(&pl, hx, h1, 2, l1)) >= 0) pl.s[s].dashed = 1;
    if ((s = gk_plot_add(&pl, hx, h2, 2, l2)) >= 0) pl.s[s].dashed = 1;
    if (ku >= 0) {
        ux[0] = x[ku], uy[0] = ys[ku];
        snprintf(lu, sizeof lu, "ultimate: N_q = %.2f", ys[ku]);
        gk_plot_add(&pl, ux, uy, 1, lu);
    }
    pl.has_ylim = 1, pl.ylim[0] = 0, pl.ylim[1] = 1.15 * nq46;
    for (k = 0; k < n; ++k)
        if (1.1 * y[k] > pl.ylim[1]) pl.ylim[1] = 1.1 * y[k];
    bad = mpd_plot(&X->run, &pl, "footing_load.svg");
    free(x);
    return bad;
}

/* the failure mechanism of the points now (footing_mech.h): wedge angle, heave; 0 or 1 (out of memory) */
static int mechanism(const ft *X, double *wedge, double *hx, double *hu) {
    int n = X->pts.n, p, ns = 0;
    double *eq = (double *)malloc(3 * (size_t)n * sizeof *eq + 1), *xs = eq + n, *uy = xs + n;
    double h = X->h, top = X->f.depth - 0.5 * h;
    *wedge = *hx = *hu = NAN;
    if (!eq) return fprintf(stderr, "mpmdem_footing: out of memory\n"), 1;
    for (p = 0; p < n; ++p) {
        eq[p] = gk_strain_q(X->M.eps + 9 * (size_t)p, 2);
        if (X->x0[2 * p + 1] > top) /* the surface row of points */
            xs[ns] = X->pts.x[0][p], uy[ns] = X->pts.x[1][p] - X->x0[2 * p + 1], ++ns;
    }
    *wedge = fm_wedge_angle(X->pts.x[0], X->pts.x[1], eq, n, h, X->b, X->f.depth - X->S.disp, NULL);
    *hx = fm_heave(xs, uy, ns, X->b, hu);
    free(eq);
    return 0;
}

/* after a step: the interval sums, and a CSV row (with the stage field) when due; 0 or 1 (said) */
static int after_step(ft *X, double vf, double t_start, long step0, long nsteps_total) {
    const ft_opts *f = &X->f;
    ft_state *S = &X->S;
    double ek, m, mom[3];
    long long sum = 0;
    int i, bad;
    ft_row r;
    S->t += X->dt, S->disp += vf * X->dt, ++S->step;
    if (S->step == 1) X->t_first = gk_wtime() - t_start, X->dem_first = X->M.dem_steps; /* fresh runs only */
    S->acc_load += -S->body.force[1] * X->dt, S->acc_dt += X->dt;
    gk_mpm_points_totals(&X->pts, &m, mom, &ek);
    S->acc_ek += ek, ++S->nacc;
    for (i = 0; i < X->pts.n; ++i) sum += X->M.nsub[i];
    S->acc_dem += (double)sum / X->pts.n;
    if (!(S->disp >= S->next_out * f->B * (1 - 1e-9) || S->disp >= f->final_dB * f->B * (1 - 1e-12) ||
          (f->max_steps && S->step - step0 >= f->max_steps)))
        return 0;
    r.t = S->t, r.d = S->disp, r.load = S->acc_load / S->acc_dt, r.q = r.load / X->b;
    r.ek = S->acc_ek / S->nacc, r.dem_mean = S->acc_dem / S->nacc;
    r.secs = S->wall + gk_wtime() - t_start;
    if (mechanism(X, &r.wedge, &r.heave_x, &r.heave_u)) return 1;
    S->acc_load = S->acc_dt = 0, S->acc_ek = S->acc_dem = 0, S->nacc = 0;
    while (S->next_out * f->B <= S->disp * (1 + 1e-9)) S->next_out += f->every;
    bad = mpd_rows_push(&X->run, &X->rows, &r) || mpd_write(&X->run, "footing.csv", put_csv, X);
    while (!bad && S->nstage < FT_NSTAGE && ft_stages[S->nstage] <= f->final_dB &&
           r.d >= ft_stages[S->nstage] * f->B * (1 - 1e-9)) {
        char file[48], title[120];
        snprintf(file, sizeof file, "eps_q_dB%.2f", ft_stages[S->nstage]);
        snprintf(title, sizeof title, "deviatoric strain eps_q at d/B = %.2f", ft_stages[S->nstage]);
        bad = snap_field(X, MPD_EPS_Q, file, title);
        ++S->nstage;
    }
    if (!X->o.quiet) {
        char what[300];
        snprintf(what, sizeof what, "d/B %.4f  q %.1f kPa (q/q_s %.2f)  DEM %.1f/pt", r.d / f->B, r.q / 1e3,
                 r.q / f->surcharge, r.dem_mean);
        gk_progress(stderr, S->step - step0, nsteps_total - step0, t_start, what);
    }
    return bad;
}

/* the checkpoint, with the wall time of this run added */
static int save(ft *X, double t_start) {
    double w0 = X->S.wall;
    int bad;
    X->S.wall += gk_wtime() - t_start;
    bad = mpd_save(&X->run, &X->M, &X->pts, "footing", &X->S, sizeof X->S, &X->rows, &X->snaps);
    X->S.wall = w0;
    return bad;
}

/* the ultimate load, the end fields, and the summary with its RESULT line; 0 or 1 (a write failed) */
static int finish(ft *X, double secs, long steps_run, long long dems, int bad) {
    const ft_opts *f = &X->f;
    int n = X->rows.n, ku = -1, reached = 0, k, excl = X->S.step == steps_run && steps_run > 1, np = X->pts.n;
    double *x = (double *)malloc(3 * (size_t)n * sizeof *x + 1), *q = x + n, *qsm = q + n, nq = NAN, qu = NAN,
           du = NAN;
    double wu = NAN, hxu = NAN, huu = NAN, we = NAN, hxe = NAN;
    double nq46 = nq_prandtl(X->phi), nq47 = nq_prandtl(phi_reduced(X->phi)), hwm, per_rve, ck_mb = 0;
    /* cost per RVE per step without the first step's one-off relaxation of every RVE */
    double per_step_rve = steps_run ? (secs - (excl ? X->t_first : 0)) / (steps_run - excl) / np : 0.0;
    double dem_after_first =
        steps_run ? (double)(dems - (excl ? X->dem_first : 0)) / (steps_run - excl) / np : 0.0;
    const char *mode = "not reached";
    char buf[64], path[MPD_PATH];
    struct stat st;
    if (!x) return fprintf(stderr, "mpmdem_footing: out of memory\n"), 1;
    if (n > 0) {
        for (k = 0; k < n; ++k) {
            const ft_row *r = (const ft_row *)mpd_row(&X->rows, k);
            x[k] = r->d / f->B, q[k] = qsm[k] = r->q;
        }
        ku = ultimate(x, q, n, f->smooth, qsm, &reached, &mode);
        qu = qsm[ku], du = x[ku], nq = qu / f->surcharge;
        if (!bad) bad = load_plot(X, qsm, reached ? ku : -1, nq46, nq47);
    }
    if (!bad)
        bad = snap_field(X, MPD_EPS_Q, "eps_q_end",
                         "deviatoric strain eps_q at the end (failure mode, Liang & Zhao Fig 14)") ||
              snap_field(X, MPD_ROTATION, "rotation_end",
                         "rotation of F = RU at the end (Liang & Zhao Fig 15)") ||
              snap_field(X, MPD_VOID, "void_ratio_end", "void ratio at the end (Liang & Zhao Fig 15)") ||
              displacement_field(X) || mpd_write_vtk(&X->run, X->S.step, &X->M, &X->pts);
    if (!mpd_path(&X->run, path, "checkpoint.bin") && stat(path, &st) == 0) ck_mb = st.st_size / 1048576.0;
    if (!bad)
        printf("wrote %s/footing.csv, footing_load.svg, %seps_q_*.svg, rotation_end.svg, void_ratio_end.svg, "
               "displacement_end.svg, points_*.vtk (ParaView), checkpoint.bin\n",
               X->run.out, X->measured ? "rve_biaxial.svg, rve_mohr.svg, " : "");
    if (n > 0) {
        const ft_row *r0 = (const ft_row *)mpd_row(&X->rows, 0),
                     *rl = (const ft_row *)mpd_row(&X->rows, n - 1);
        printf(
            "load-settlement: q(d/B = %.4f) = %.2f kPa (q_s = %g kPa); at the end d/B = %.4f: q = %.1f kPa\n",
            r0->d / f->B, r0->q / 1e3, f->surcharge / 1e3, rl->d / f->B, rl->q / 1e3);
    }
    if (reached)
        printf("ultimate load (%s, smoothing window d/B %g): p_u = %.1f kPa at d/B = %.4f -> N_q = p_u/q_s = "
               "%.2f\n",
               mode, f->smooth, qu / 1e3, du, nq);
    else
        printf("ultimate load NOT reached by d/B = %.4f (no zero or steady minimum slope confirmed one "
               "window before "
               "the end): N_q below is the last smoothed value, a lower bound; run further (--final)\n",
               n ? x[n - 1] : 0.0);
    printf("N_q: MPMxDEM %.2f; eq 46 (general shear, phi = %.2f deg) %.2f; eq 47 (local/punching, phi_r = "
           "%.2f deg) "
           "%.2f; ratio %.3f to eq 46\n",
           nq, X->phi, nq46, phi_reduced(X->phi), nq47, nq / nq46);
    if (isnan(phi_of_nq(nq)))
        printf("no angle's eq 46 gives the MPMxDEM N_q %.3g (eq 46 spans %.3g at 0 deg to %.4g at 60 deg; "
               "RESULT "
               "phi_mobilised_deg=nan)\n",
               nq, nq_prandtl(0.0), nq_prandtl(60.0));
    else
        printf("the MPMxDEM N_q is eq 46 of phi = %.2f deg (the angle the footing mobilises)\n",
               phi_of_nq(nq));
    if (X->measured)
        printf("N_q of eq 46 with the residual angle phi_res = %.2f deg (the softened end of the RVE tests): "
               "%.2f; "
               "MPMxDEM / that = %.3f\n",
               X->phi_res, nq_prandtl(X->phi_res), nq / nq_prandtl(X->phi_res));
    printf("Liang & Zhao '%s': N_q %.1f (MPMxDEM) vs %.1f (analytic, phi = %.1f deg)\n",
           material_names[f->material], paper_nq[f->material], paper_nq_analytic[f->material],
           paper_phi[f->material]);
    if (n > 0) {
        const ft_row *ru = (const ft_row *)mpd_row(&X->rows, ku),
                     *rl = (const ft_row *)mpd_row(&X->rows, n - 1);
        wu = ru->wedge, hxu = ru->heave_x, huu = ru->heave_u, we = rl->wedge, hxe = rl->heave_x;
        printf(
            "mechanism at the %s (d/B = %.4f): wedge angle %.1f deg (Prandtl pi/4 + phi/2 = %.2f; Liang & "
            "Zhao 54.8 vs 59.05); heave up to %.3g B, reaching x = %.2f B from the axis = %.2f B beyond the "
            "footing edge (Prandtl's passive zone: x = %.2f B; Liang & Zhao: heave about 2.5 B wide)\n",
            reached ? "ultimate load" : "last row", du, wu, fm_prandtl_wedge(X->phi), huu / f->B, hxu / f->B,
            (hxu - X->b) / f->B, fm_prandtl_reach(X->b, X->phi) / f->B);
        printf("mechanism at the end (d/B = %.4f): wedge angle %.1f deg; heave reaching x = %.2f B\n",
               rl->d / f->B, we, hxe / f->B);
    }
    hwm = proc_kb("VmHWM");
    per_rve = X->rss_after > 0 && X->rss_before > 0 ? (X->rss_after - X->rss_before) / np : NAN;
    printf("cost: %s for %ld MPM steps, %lld DEM steps over all RVEs (%.1f per point per MPM step); %.4g s "
           "per MPM "
           "step per 1000 RVEs (%.3g us per RVE DEM step)\n",
           mpd_duration(secs, buf, sizeof buf), steps_run, dems,
           steps_run ? (double)dems / steps_run / np : 0.0, steps_run ? secs / steps_run * 1000.0 / np : 0.0,
           dems ? 1e6 * secs / (double)dems : 0.0);
    mpd_print_traffic(&X->run, &X->M, steps_run, X->o.threads);
    printf(
        "memory (rank 0): VmHWM %.1f MB, %.1f kB per RVE (RSS growth on creation), checkpoint file %.1f MB\n",
        hwm / 1024, per_rve, ck_mb);
    {
        /* the paper's size: 7776 RVEs, h = 12/108, 0.1 m/s to d/B = 1.5 with a 0.5 s ramp */
        double hp = 12.0 / 108.0, dtp = X->o.cfl * hp / X->c, stepsp = (1.5 * f->B / 0.1 + 0.25) / dtp;
        double base = hwm > 0 && isfinite(per_rve) ? hwm - per_rve * np : NAN;
        printf("paper size projection (7776 RVEs, h = %.4g m, dt = %.3g s, %.0f MPM steps at 0.1 m/s to d/B "
               "= 1.5): "
               "memory ~ %.2f GB, checkpoint file %.2f GB; wall ~ %s on these cores at this run's %.3g ms "
               "per RVE per "
               "MPM step (first step excluded; %.1f DEM steps per RVE per MPM step here)\n",
               hp, dtp, stepsp, (base + 7776.0 * per_rve) / 1048576.0, 7776.0 * ck_mb / np / 1024.0,
               mpd_duration(per_step_rve * 7776.0 * stepsp, buf, sizeof buf), 1e3 * per_step_rve,
               dem_after_first);
    }
    printf("RESULT Nq=%.5g Nq_analytic=%.5g Nq_analytic_local=%.5g phi_deg=%.4g phi_res_deg=%.4g "
           "Nq_analytic_res=%.5g "
           "phi_mobilised_deg=%.4g q_ult=%.6g d_ult_over_B=%.4g ultimate_reached=%d n_rves=%d mpm_steps=%ld "
           "dt=%.4g "
           "seconds_per_step=%.4g seconds_per_step_per_1000_rves=%.4g "
           "seconds_per_step_per_1000_rves_after_first=%.4g "
           "mem_per_rve_kb=%.4g vmhwm_mb=%.5g total_seconds=%.2f wedge_deg=%.4g wedge_prandtl_deg=%.4g "
           "heave_x_over_B=%.4g heave_width_over_B=%.4g heave_over_B=%.4g prandtl_reach_over_B=%.4g "
           "wedge_end_deg=%.4g heave_x_end_over_B=%.4g\n",
           nq, nq46, nq47, X->phi, X->phi_res, X->measured ? nq_prandtl(X->phi_res) : NAN, phi_of_nq(nq), qu,
           du, reached, np, steps_run, X->dt, steps_run ? secs / steps_run : 0.0,
           steps_run ? secs / steps_run * 1000.0 / np : 0.0, 1000.0 * per_step_rve, per_rve, hwm / 1024, secs,
           wu, fm_prandtl_wedge(X->phi), hxu / f->B, (hxu - X->b) / f->B, huu / f->B,
           fm_prandtl_reach(X->b, X->phi) / f->B, we, hxe / f->B);
    free(x);
    return bad;
}

static int run(ft *X, int argc, char **argv) {
    const ft_opts *f = &X->f;
    ft_state *S = &X->S;
    double t_start;
    long nsteps_total, step0;
    long long dem0;
    int status = parse(X, argc, argv), bad = 0;
    gk_err err;
    if (status) return status == 1 ? 0 : status;
    t_start = gk_wtime();
    if (setup(X, &err)) return fprintf(stderr, "mpmdem_footing: %s\n", err.msg), 1;
    if (f->phi_only) {
        printf("RVE at q_s = %g kPa: p0 = %.4g kPa, e0 = %.4f (Table 2: %.4f)\n", f->surcharge / 1e3,
               X->P.p0 / 1e3, X->P.e0, table2_e0[f->material]);
        printf("RESULT phi_deg=%.4g phi_res_deg=%.4g Nq_analytic=%.5g e0=%.5g p0=%.6g seconds=%.2f\n", X->phi,
               X->phi_res, nq_prandtl(X->phi), X->P.e0, X->P.p0, gk_wtime() - t_start);
        return 0;
    }
    nsteps_total = (long)ceil((f->final_dB * f->B / f->velocity + 0.5 * f->ramp) / X->dt);
    if (f->max_steps && f->max_steps < nsteps_total) nsteps_total = f->max_steps;
    printf("grid: %d x %d cells over %g x %g m (half model), h = %.4g m; footing B = %g m, half-width b = %g "
           "m = "
           "%.3g cells (nodes x <= %.4g m), rough; surcharge %g kPa\n",
           f->nx, f->ny, f->width, f->depth, X->h, f->B, X->b, X->b / X->h, X->bnode, f->surcharge / 1e3);
    if (fabs(X->b - 0.5 * f->B) > 1e-6 * f->B)
        printf("note: B/2 = %g m is not (k + 1/2) h: the footing's effective half-width is b = %g m (q = "
               "load / b); "
               "choose h = B / (2k + 1) for an exact footing\n",
               0.5 * f->B, X->b);
    printf("%d points (= RVEs of %d disks), basis %d, alpha %g, grid damping %g\n", X->pts.n, X->P.pk.n,
           (int)X->def.basis, X->o.alpha, f->grid_damping);
    printf("RVE at q_s: p0 = %.4g kPa, e0 = %.4f (Table 2: %.4f), rho = %.1f kg/m3, M (Taylor) = %.4g MPa -> "
           "c = %.1f "
           "m/s; MPM dt = %.4g s (cfl %.2f)\n",
           X->P.p0 / 1e3, X->P.e0, table2_e0[f->material], X->P.rho, X->P.M / 1e6, X->c, X->dt, X->o.cfl);
    mpd_print_dem_rule(&X->o);
    printf("memory: %.1f kB per RVE (RSS growth over creating %d RVEs)\n",
           X->rss_after > 0 && X->rss_before > 0 ? (X->rss_after - X->rss_before) / X->pts.n : -1.0,
           X->pts.n);
    printf("footing at %g m/s (ramp %g s) to d/B = %g: about %ld MPM steps%s\n", f->velocity, f->ramp,
           f->final_dB, nsteps_total, f->max_steps ? " (--max-steps)" : "");
    fflush(stdout);
    if (!X->o.restart && mpd_write_vtk(&X->run, 0, &X->M, &X->pts)) return 1;
    t_start = gk_wtime();
    step0 = S->step, dem0 = X->M.dem_steps;
    while (!bad && S->disp < f->final_dB * f->B * (1 - 1e-12) &&
           !(f->max_steps && S->step - step0 >= f->max_steps)) {
        double vf =
            f->velocity * (f->ramp > 0 && S->t < f->ramp ? fmin(1.0, (S->t + 0.5 * X->dt) / f->ramp) : 1.0);
        S->body.v[1] = -vf;
        if (mpd_step(&X->g, &X->pts, &X->def, X->dt, &X->M, X->edge, X->nedge,
                     &err)) { /* also moves the footing */
            fprintf(stderr, "mpmdem_footing: step %ld (d/B = %.4f): %s\n", S->step, S->disp / f->B, err.msg);
            status = 3;
            break;
        }
        bad = after_step(X, vf, t_start, step0, nsteps_total);
        if (!bad && X->o.vtk_every && S->step % X->o.vtk_every == 0)
            bad = mpd_write_vtk(&X->run, S->step, &X->M, &X->pts);
        if (!bad && X->o.checkpoint_every && S->step % X->o.checkpoint_every == 0) bad = save(X, t_start);
    }
    if (!bad && status == 0) bad = save(X, t_start);
    if (!bad) bad = mpd_write(&X->run, "footing.csv", put_csv, X);
    bad = finish(X, gk_wtime() - t_start, S->step - step0, X->M.dem_steps - dem0, bad);
    return status ? status : bad;
}

int main(int argc, char **argv) {
    ft X;
    int status;
    memset(&X, 0, sizeof X);
    gk_rve_state_init(&X.st0, NULL);
    mpd_begin(&X.run, "mpmdem_footing", &argc, &argv);
    status = run(&X, argc, argv);
    free(X.edge), free(X.x0);
    mpd_free_all(&X.M, &X.P, &X.pts, &X.g, &X.rows, &X.snaps);
    gk_rve_state_free(&X.st0);
    return mpd_end(status);
}
