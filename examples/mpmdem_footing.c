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
 * THE CODE. This file: the options, the set-up, the loop of steps (with
 * the checkpoint) and main. footing_io.h: the model's state and every
 * output, its manual: the ultimate load, the mechanism, the output files.
 */

#define GK_IMPLEMENTATION
#include "footing_io.h"

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
        "  dem_steps_per_point,seconds,wedge_deg,heave_x_over_B,heave_over_B,spiral_phi_deg,\n"
        "  spiral_r0_over_B,spiral_rms_over_B,spiral_rays; spiral_rays: the rays with an eps_q ridge,\n"
        "  a spiral needs half of those searched; the other spiral_* nan when none is found),\n"
        "  footing_load.svg, rve_biaxial.svg, rve_mohr.svg, eps_q_dB*.svg,\n"
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
        "           prandtl_reach_over_B=... wedge_end_deg=... heave_x_end_over_B=...\n"
        "           spiral_found=... spiral_phi_deg=... spiral_r0_over_B=... spiral_rms_over_B=... "
        "spiral_rays=...\n"
        "           spiral_rays_searched=... spiral_phi_end_deg=... spiral_rays_end=...\n");
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

/* a checkpoint's state and rows as read (mpd_load's driver check, ctx the model): every value finite
 * and within MPD_MAX_VALUE (the spiral fit's NaN, "none found", allowed), the settlement between 0 and
 * the soil's depth, the footing the run's box moved down by it, counters and the stage index in range,
 * the next row not behind the settlement by more than one interval */
static int ft_check(const void *vS, const mpd_rows *R, const void *ctx, char *why, size_t nwhy) {
    const ft_state *S = (const ft_state *)vS;
    const ft *X = (const ft *)ctx;
    const gk_mpm_body *B = &S->body, *B0 = &X->body_run;
    const ft_opts *f = &X->f;
    double v[8];
    int k, j;
    v[0] = S->t, v[1] = S->disp, v[2] = S->acc_load, v[3] = S->acc_dt, v[4] = S->acc_ek, v[5] = S->acc_dem;
    v[6] = S->next_out, v[7] = S->wall;
    for (k = 0; k < 8; ++k)
        if (!mpd_sane(v[k])) return snprintf(why, nwhy, "footing state: a non-finite value"), 1;
    if (S->step < 0 || S->step > 1000000000000L || S->nacc < 0 || S->nacc > S->step || S->nstage < 0 ||
        S->nstage > FT_NSTAGE || !(S->t >= 0) || !(S->wall >= 0) || !(S->disp >= 0 && S->disp <= f->depth) ||
        S->next_out < S->disp / f->B - 2 * f->every)
        return snprintf(why, nwhy, "footing state: a step, stage, settlement or output counter out of range"),
               1;
    for (k = 0; k < 3; ++k)
        if (!mpd_sane(B->lo[k]) || !mpd_sane(B->hi[k]) || !mpd_sane(B->v[k]) || !mpd_sane(B->force[k]))
            return snprintf(why, nwhy, "the footing is not a finite box"), 1;
    if (B->shape != B0->shape || B->contact != B0->contact || B->face != B0->face || B->mu != B0->mu ||
        B->lo[0] != B0->lo[0] || B->hi[0] != B0->hi[0] ||
        !(fabs(B0->lo[1] - B->lo[1] - S->disp) <= 1e-6 * f->B) ||
        !(fabs(B0->hi[1] - B->hi[1] - S->disp) <= 1e-6 * f->B))
        return snprintf(why, nwhy, "the footing is not this run's, moved down by the settlement"), 1;
    for (k = 0; k < R->n; ++k) {
        const ft_row *r = (const ft_row *)mpd_row(R, k);
        double w[13];
        w[0] = r->t, w[1] = r->d, w[2] = r->q, w[3] = r->load, w[4] = r->ek, w[5] = r->dem_mean,
        w[6] = r->secs;
        w[7] = r->wedge, w[8] = r->heave_x, w[9] = r->heave_u, w[10] = r->sp_phi, w[11] = r->sp_r0;
        w[12] = r->sp_rms;
        for (j = 0; j < 13; ++j)
            if (!mpd_sane(w[j]) && !(j >= 7 && isnan(w[j])))
                return snprintf(why, nwhy, "row %d: a non-finite value", k), 1;
        if (r->sp_rays < 0) return snprintf(why, nwhy, "row %d: a negative count", k), 1;
    }
    return 0;
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
    X->body_run = S->body;
    if (X->o.restart && mpd_load(X->o.restart, &X->M, &X->pts, "footing", S, sizeof *S, &X->rows, &X->snaps,
                                 ft_check, X, err))
        return 1;
    X->g.body = &S->body, X->g.nbody = 1;
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
    fm_spiral_fit sp;
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
    if (mechanism(X, &r.wedge, &r.heave_x, &r.heave_u, &sp)) return 1;
    r.sp_phi = sp.phi, r.sp_r0 = sp.r0, r.sp_rms = sp.rms, r.sp_rays = sp.nrays;
    S->acc_load = S->acc_dt = 0, S->acc_ek = S->acc_dem = 0, S->nacc = 0;
    while (S->next_out * f->B <= S->disp * (1 + 1e-9)) S->next_out += f->every;
    bad = mpd_rows_push(&X->run, &X->rows, &r) || mpd_write(&X->run, "footing.csv", put_csv, X);
    while (!bad && S->nstage < FT_NSTAGE && ft_stages[S->nstage] <= f->final_dB &&
           r.d >= ft_stages[S->nstage] * f->B * (1 - 1e-9)) {
        char file[48], title[120];
        snprintf(file, sizeof file, "eps_q_dB%.2f", ft_stages[S->nstage]);
        snprintf(title, sizeof title, "deviatoric strain eps_q at d/B = %.2f", ft_stages[S->nstage]);
        bad = snap_field(X, MPD_EPS_Q, file, title, r.sp_phi, r.sp_r0);
        ++S->nstage;
    }
    if (!X->o.quiet) {
        char what[300];
        snprintf(what, sizeof what, "d/B %.4f  q %.1f kPa (q/q_s %.2f)  DEM %.1f/pt", r.d / f->B, r.q / 1e3,
                 r.q / f->surcharge, r.dem_mean);
        gk_progress_since(stderr, S->step, step0, nsteps_total, t_start, what);
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
