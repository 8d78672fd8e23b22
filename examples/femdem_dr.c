/* femdem_dr - FEMxDEM by explicit adaptive dynamic relaxation with servo-framed
 * RVEs, and the same specimen as one DEM simulation (Liu, Bosco & Suiker 2018).
 *
 *   build/femdem_dr --out DIR            the reduced run: 1 x 2 mesh (8 RVEs), 10 + 20 steps
 *   build/femdem_dr --paper --out DIR    the paper's parametric mesh 2 x 4 (32 RVEs), 10 + 50 steps
 *   build/femdem_dr --test biaxial --nx N --ny M --threads 2 --out DIR
 *                   [--iso-steps 10 --steps 20 --strain 0.10 --pressure 1.5e5 --friction 0.4]
 *                   [--no-rotation] [--frame servo|periodic] [--packing FILE] [--restart DIR]
 *   build/femdem_dr --test rve ...          the RVE alone on the same stress path
 *   build/femdem_dr --test dns --dns-tiles 1x2|2x4 ...   the specimen as one DEM scene
 *
 * The driver runs the load path; the rest is in four example headers, each with its manual:
 *   examples/femdem_dr_opts.h   the options (on examples/cli.h), their defaults and --help
 *   examples/femdem_dr_model.h  the model, the macro solver (dynamic relaxation), the RVE, --test rve
 *   examples/femdem_dr_io.h     the outputs in DIR, the checkpoint and the RESULT line
 *   examples/femdem_dr_dns.h    --test dns: the specimen as one DEM scene
 *
 * RESULTS (the reduced load path: 10 + 20 steps, 0.5 % per biaxial step, 1 thread; from
 * `build/femdem_dr [--nx N --ny M] [--frame periodic] [--test rve|dns] --vtk-every 0 --out DIR`,
 * the DNS with `--dns-tiles 2x4` or `--packing examples/data/frame820_a002.txt --dns-tiles 1x2`;
 * sigma_bar at axial strain 1, 2, 3, 5 %, its peak, sigma_bar and A at 7.3 %, all DEM steps)
 *   run                 1 %    2 %    3 %    5 %    peak          7.3 %: s_bar  A      DEM steps
 *   servo, RVE alone    0.187  0.294  0.343  0.370  0.377 at 5.5  0.328  0.288  2.6e5
 *   servo, 1 x 1        0.190  0.289  0.336  0.373  0.374 at 5.5  0.307  0.287  2.8e6
 *   servo, 1 x 2        0.192  0.297  0.339  0.373  0.381 at 5.5  0.315  0.296  6.8e6
 *   servo, 2 x 4        0.190  0.291  0.334  0.368  0.375 at 5.5  0.321  0.297  5.6e7
 *     --predictor none  0.170  0.271  0.327  0.360  0.360 at 5.0  0.320  0.257  2.3e7
 *   periodic, RVE alone 0.207  0.314  0.345  0.358  0.370 at 4.5  0.325  0.240  2.1e4
 *   periodic, 1 x 1     0.208  0.312  0.340  0.337  0.363 at 4.5  0.351  0.263  1.5e5
 *   periodic, 1 x 2     0.209  0.312  0.339  0.337  0.361 at 4.5  0.349  0.259  3.2e5
 *   periodic, 2 x 4     0.208  0.311  0.340  0.343  0.357 at 4.5  0.348  0.260  2.3e6
 *   periodic, 4 x 8     0.209  0.312  0.340  0.344  0.356 at 3.5  0.343  0.255  1.0e7
 *     --predictor none  0.191  0.292  0.321  0.340  0.340 at 5.0  0.292  0.197  1.3e7
 *   DNS 1x2 (444 disks) 0.184  0.244  0.194  0.193  0.301 at 6.5  0.239  0.122  (3.1e6 of 444)
 *   DNS 2x4 (1707)      0.194  0.287  0.165  0.334  0.342 at 5.5  0.265  0.154  1.2e6, 27 s
 *   DNS 1704 (two 820s) 0.207  0.307  0.331  0.259  0.349 at 10   0.302  0.111  1.6e5, 4 s
 *   --paper --frame periodic (2 x 4, 10 + 50 steps of 0.2 %): peak 0.361 at 4.4 %, at 7.3 %
 *     0.353 and A 0.263, 3.0e6 DEM steps; --paper (servo): 2.9e7 DEM steps to 2 % (sigma_bar
 *     0.290 there, 0.291 with 0.5 % steps), 6.2e7 to 10 %: peak 0.374 at 5.8 %, 211 s on one core.
 *   periodic 2 x 4, mu 0.2 / 0.6:  peaks 0.266 at 7.0 / 0.428 at 4.5 %; coordination at 7.3 %
 *     4.11 / 3.79 (mu 0.4: 3.88); locked rotation: 0.595 at 10 %, at 7.3 % sigma_bar 0.591,
 *     A 0.308; packings with A0 0.05 / 0.08: peaks 0.357 at 4.5 / 0.363 at 3.5 %.
 *   2 x 4, k_n = 30 sigma0, mu 0.2 / 0.4 / 0.6: periodic peaks 0.254 / 0.348 / 0.406 (at 9.5-10 %),
 *     coordination at 7.3 % 4.65 / 4.60 / 4.50, J_rel down to -0.037 / -0.043 / -0.049, no
 *     dilation to 10 %; servo peaks 0.200 at 4.5 / 0.336 at 7.0 / 0.402 at 9.0 %, coordination
 *     4.08 / 4.10 / 4.05, J_rel down to -0.043 / -0.033 / -0.040, dilation from 10 / 8 / 9 %.
 * Against Liu, Bosco & Suiker (2018), who give numbers only for Figs 10-11 (at 7.3 %: free
 * 0.39, locked 0.48; A 0.27 and 0.33): the locked rotation is stronger and more anisotropic
 * (servo 2 x 4: locked 0.564, A 0.377; A ratio free / locked 0.79 here, 0.82 there) but far
 * stronger here (stress ratio 0.57, there 0.81; the RVE alone: 0.59); the ratio depends on
 * k_n / sigma0, which the paper leaves open: 0.81 at 30 (RVE alone; 2 x 4 servo: free 0.333,
 * locked 0.417, A 0.12 and 0.12), 0.93 at 10, 0.54 at 1000 (tools/dr_rotation_study.sh,
 * examples/README.md); the peak comes earlier (4-6 %, there near 7 %; 7 % at k_n = 30
 * sigma0); higher friction gives a higher stress and a lower coordination as there, but not
 * their larger compaction (at k_n = 30 sigma0 the periodic cells give that too, but no
 * dilation to 10 %; the servo frames dilate from 8-10 %, there from about 8 %); an ensemble of
 * 22 RVEs resolves no effect of the initial anisotropy (there: a lower, earlier peak; below).
 * The meshes agree within 3.0 % to 5 % strain (servo frame, 1 x 1 to 4 x 8, `--strain 0.05
 * --steps 10`) and the periodic cells within 2.4 % to 7.3 % (the paper: "very close"); after
 * the peak they part (servo 1 x 1 to 2 x 4: 4 % at 7.3 %, 32 % at 10 %). The servo frame and
 * the periodic cell differ by at most 7 % (RVE alone) and 8 % (2 x 4) of the servo peak to
 * 5 %, 13 % and 14 % to 10 %. The DNS (a biaxial step relaxed to E_kin / E_pot 1e-5, --dns-tol;
 * femdem_dr_dns.h) follows the meshes to 2 %: the 1707-disk specimen (`--dns-tiles 2x4`, the
 * size of the paper's DNS B) within 1.6 % of the servo 2 x 4 mesh's peak to 2 % (with
 * --paper's 0.2 % steps within 3.9 % of the --paper mesh's to 2.4 %), the 444-disk one within
 * 1.8 % to 1.5 %. Both tile the RVE's one cell, and both then slip (444: from 0.25 at 1.5 %
 * to 0.19 at 3 %; 1707: 0.31 at 2.5 % to 0.17 at 3 %, 0.33 again at 5 %); 3-4 particles
 * escape through their membranes, as in the paper's DNS (removed, counted in `lost`). Four
 * specimens of 1704 disks, each two copies of an 820-disk cell made alike (`--packing
 * examples/data/frame820_a002.txt --dns-tiles 1x2`, and seeds 5-7 of its gk_pack command),
 * do not slip there: their mean lies within 2.1 % of the 2 x 4 mesh's peak to 3 % (each
 * within 1.5-7.0 %); they peak at 0.339-0.361 and fall below the mesh from 3.5 %, by 18 % of
 * its peak at 4.5 % (the mean), while the mesh hardens to 0.368 at 5 %: the specimens
 * localise, the uniform mesh does not (the paper: "very close" to 5 %). A DNS takes 4 s (the
 * 820-disk cells) to 27 s (tiled) on one core, the 2 x 4 mesh 185 s. The packings are
 * looser than the paper's (solid fraction 0.82 against 0.846) and the DEM is stiffer relative
 * to the confinement than Table 3's raw numbers allow (see THE RVE).
 * THE INITIAL ANISOTROPY (Figs 12-14; the RVE alone, `--test rve --packing
 * examples/data/frame228_a00N.txt`, the anisotropy column of dr.csv): the packings hold
 * A0 = 0.016, 0.049, 0.084 at their 1500 Pa; the first isotropic step (sigma0 / 10, ten
 * times that) leaves A = 0.029 in all three (servo frame), the end of the stage 0.027,
 * 0.023, 0.031 (periodic cell: 0.012, 0.017, 0.012). Peaks 0.377 at 5.5 %, 0.379 at 5.5 %,
 * 0.374 at 4.5 % (servo). Packings made at the working stress (gk_pack --pressure 1.5e5
 * --kn 1.5e7, A 0.021 / 0.052 / 0.056) lose it too, whether stage 1 first unloads them (10
 * steps: A 0.20-0.26 at sigma0 / 10, 0.046-0.051 back at sigma0; periodic peaks 0.405 /
 * 0.403 / 0.397) or not (--iso-steps 1: after that one step A 0.015 in the periodic cell,
 * 0.024-0.038 with the servo frame; servo peaks 0.345 / 0.349 / 0.348, all at 3 %). A clue:
 * a packing file keeps positions only, and without the tangential forces of its loading
 * history the normal forces alone carry sigma_yy / sigma_xx = 1.09 where the packing held
 * 1.00 (A 0.056); the first relaxation rearranges it (Z 3.94 to 4.10, A 0.015), at any
 * friction (mu 0.4, 1, 10: A 0.015, 0.010, 0.013). At the packing files' own k_n / p
 * (`--kn-ratio 1e5 --dr-force-tol 1e-2`) the isotropic stage ends near the packing's A
 * (0.014, 0.051, 0.119); without --dr-force-tol, eq 28 alone ends most biaxial steps of
 * these stiff RVEs far from equilibrium (sigma_11 about 430 kPa on the 150 kPa sides; the
 * run warns).
 * Three packings cannot answer the question (two made alike differ by more than the paper's
 * effect), so `tools/dr_anisotropy_study.sh` runs an ensemble: 22 distinct packings (the
 * files' gk_pack command, targets 0.02 / 0.05 / 0.08, seeds 1-10: A0 0.019-0.105), each RVE
 * alone relaxed to a force residual of 1 % in every step, at k_n / sigma0 = 100 and 1e5, and
 * fits the peak, its strain and the mean sigma_bar over 2-10 % against A0, against A at the
 * end of the isotropic stage (0.012-0.090 at 100: not erased in general) and against a_y =
 * phi_yy / phi_xx - 1 of the packing's contacts (-0.051 to 0.081: which way the excess points
 * is not controlled, and A0 says nothing of it). At k_n / sigma0 = 100 no slope is beyond two
 * standard errors (the peak against A0: -0.49 +- 0.30 per unit A0, the paper's sign; the
 * peaks span 0.288-0.389); at 1e5 the peak and the 2-10 % mean rise with a_y (+0.52 +- 0.26,
 * +0.46 +- 0.23: contact normals along the loading make the RVE stronger), at the margin of
 * chance among the 18 slopes fitted. With 11 packings (seeds 1-5) the peak at 100 fell with
 * a_y at 2.4 standard errors; the next 11 took it away. The paper does not say which way its
 * packings lean.
 * WHERE A LOAD STEP STARTS AND ENDS (--predictor, --dr-force-stop; Fig 4: the meshes agree
 * before the peak). The specimen is uniform (smooth platens, the same packing at every Gauss
 * point), so every mesh should give one curve. The paper's scheme as written (--predictor
 * none) starts a step from the last state with only the loads and the platen moved: its first
 * DR iterations compress the top row of elements alone (on 2 x 4 four times the step's strain),
 * an isotropic step's those along the loaded edges, and every iteration's RVE state is kept,
 * so the excursion stays. The finer the mesh the softer it comes out: sigma_bar at 0.5 / 1 /
 * 1.5 % 0.104 / 0.186 / 0.250 (1 x 1), 0.099 / 0.174 / 0.233 (1 x 2), 0.094 / 0.170 / 0.229
 * (2 x 4), 9-10 % apart (servo, `--strain 0.05 --steps 10 --predictor none`); the 32 points of
 * 2 x 4 end the isotropic stage at sigma_22 143.6-154.1 kPa, det F spanning 1.2e-3, and their
 * strain increments over the first biaxial step span 0.0038-0.0076 (gp_NNNN.vtk, --vtk-every
 * 1). Not the RVE's tolerances (--tol-energy 1e-5 --servo-max 200: 141.8-154.7 kPa, the meshes
 * as far apart), nor the macro relaxation's (periodic cell, 2 x 4 at 1 %: 0.2002 with a 100x
 * tighter eq 28 and 4x the DR iterations, against 0.1992; the 1 x 1 mesh 0.2075), nor one
 * RVE's chaos (the RVE alone with sigma0 perturbed by 1e-12 to 9e-12, ten runs, spans 0.9-1.0 %
 * of sigma_bar at 1, 2 and 3 %). By default (--predictor homogeneous) a step of a mesh starts
 * from the uniform specimen's next state: from the third isotropic step the last step's mean
 * stretches repeated, in stage 2 the platen's increment spread over the height (the lateral
 * displacements kept). The points of 2 x 4 then end the isotropic stage at 148.8-151.1 kPa and
 * the first biaxial step's increments span 0.0050-0.0057. Such a step starts near equilibrium,
 * and eq 28 (E_kin at 1e-3 of the step's largest) cannot end it: the largest kinetic energy
 * stays small (the locked-rotation 2 x 4 mesh's first predicted step: 4.5e-7, an unpredicted
 * step's about 4e-4), the servo frames' own jitter (1e-8) holds the ratio at 1-5e-2, and the
 * force residual sits at 1-3e-3 for 10000 iterations and more; with eq 28 alone that mesh did
 * not relax its fifth isotropic step in 20000 iterations, nor the 4 x 8 mesh its third. So a
 * predicted step also ends once |f_ext - f_int| <= 2e-3 max|f| (--dr-force-stop; 0 leaves eq 28
 * alone). The stop's bias is small: sigma_bar at 0.5 % of the periodic 1 x 1 / 2 x 4 meshes
 * 0.1173 / 0.1192 with 5e-3, 0.1157 / 0.1162 with 2e-3, 0.1152 / 0.1154 with 1e-3, 0.1145 /
 * 0.1151 with 5e-4 (the 1 x 1 mesh without the predictor 0.1142, the RVE alone 0.1131); 5e-3
 * put the first biaxial step 1.5-2.5 % high. Servo, `--strain 0.05 --steps 10`, sigma_bar at
 * 0.5 / 1 / 1.5 / 2 / 3 / 5 % and the DEM steps to 5 %:
 *   1 x 1  0.107  0.190  0.246  0.289  0.336  0.373   1.5e6    (none: 1.8e6)
 *   1 x 2  0.106  0.192  0.253  0.297  0.339  0.373   3.6e6    (none: 2.5e6)
 *   2 x 4  0.106  0.190  0.247  0.291  0.334  0.368   3.0e7    (none: 1.5e7)
 *   4 x 8  0.108  0.190  0.248  0.291  0.336  0.369   1.1e8    (414 s on one core)
 * within 1.2, 1.0, 2.7, 3.0, 1.8, 1.5 % of each other (none, 1 x 1 to 2 x 4: 9.9, 8.7, 8.8,
 * 8.2, 3.8, 1.5 %), as the paper's Fig 4 has them. The finer meshes pay for it (2 x 4: twice
 * the DEM steps of --predictor none), and the locked-rotation 2 x 4 mesh relaxes every step (to
 * 10 % in 134 s).
 */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_explicit.h"
#include "gk_fem.h"
#include "gk_frame.h"
#include "gk_io.h"
#include "gk_twoscale.h"
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include "femdem_dr_dns.h"

/* ------------------------------------------------------------------ the load path */
/* --predictor homogeneous (the default; the manual above): where load step `step` of a mesh
 * starts its relaxation, the uniform specimen's next state. Stage 1 from its third step: every
 * node stretched about the fixed corner by the ratios of the mean stretches the last step made
 * (the top's height and J in the rows, which the checkpoint keeps; the first step may unload a
 * packing made at a higher stress, so the second starts where the first ended). Stage 2: every
 * node moved down by the platen's increment in proportion to its height (the platen's own nodes
 * are set after this), the lateral displacements kept. Supports are not moved, and ratios that
 * are not finite or beyond 2x (a damaged restart) leave the state as it is. Without it the first
 * iterations put the whole increment into the loaded edges' elements, whose RVEs (accepted at
 * every iteration, so path-dependent) keep the excursion. */
static void predict(model *m, int stage, int step) {
    double rx, ry;
    int k;
    if (stage == 1) {
        const double *a, *b;
        if (step < 3 || m->nrows < 3) return;
        a = m->rows[m->nrows - 2].v, b = m->rows[m->nrows - 1].v; /* steps step - 2, step - 1 */
        ry = (1.0 - b[2]) / (1.0 - a[2]);                         /* h / h0 = 1 - eps_axial */
        rx = (1.0 + b[6]) / (1.0 + a[6]) / ry;                    /* J = stretch_x stretch_y */
    } else {
        rx = 1.0, ry = 1.0 - m->o.strain * m->h_ic / m->o.steps / mean_top(m, m->u);
    }
    if (!(rx > 0.5 && rx < 2.0 && ry > 0.5 && ry < 2.0)) return;
    for (k = 0; k < m->nnode; ++k) {
        if (!m->fixed[2 * k]) m->u[2 * k] += (rx - 1.0) * (m->mesh.x[2 * k] + m->u[2 * k]);
        if (!m->fixed[2 * k + 1]) m->u[2 * k + 1] += (ry - 1.0) * (m->mesh.x[2 * k + 1] + m->u[2 * k + 1]);
    }
}

static int run_fem(model *m) {
    const opts *o = &m->o;
    int nsteps = o->iso_steps + o->steps, step, step0, rc, k;
    row r;
    long long dem0;
    if (o->restart) {
        if (load_checkpoint(m)) return 1;
    } else {
        make_row(m, 0, 1, 0, 0,
                 &r); /* the unloaded state (no RVE has run: P = 0, as Table 1's first increment) */
        add_row(m, &r);
    }
    step0 = m->step_done;
    for (step = m->step_done + 1; step <= nsteps; ++step) {
        int stage = step <= o->iso_steps ? 1 : 2, iters = 0, g;
        double ps = o->pressure * (stage == 1 ? (double)step / o->iso_steps : 1.0),
               pt = stage == 1 ? ps : 0.0;
        double *Hstart = (double *)xcalloc(9 * (size_t)m->ngp, sizeof(double));
        memcpy(Hstart, m->Hacc, 9 * (size_t)m->ngp * sizeof(double));
        if (o->predictor && !m->single && step > 1) predict(m, stage, step);
        if (stage == 2) { /* the platen: every top node down to d below its height after stage 1 */
            double d = o->strain * m->h_ic * (step - o->iso_steps) / o->steps;
            if (m->single) {
                m->fixed[1] = 1;
                m->u[1] = (m->h_ic - m->h0) - d;
            } else {
                for (k = 0; k < m->ntop; ++k) {
                    int n = m->top[k];
                    m->fixed[2 * n + 1] = 1;
                    m->u[2 * n + 1] = (m->h_ic - m->h0) - d;
                }
            }
        }
        dem0 = m->dem_total;
        if ((rc = dr_step(m, ps, pt, &iters)) != 0) {
            free(Hstart);
            save_checkpoint(m);
            return rc;
        }
        for (g = 0; g < m->ngp; ++g) { /* deq: |dF| over the step */
            double s2 = 0.0;
            for (k = 0; k < 9; ++k)
                s2 += (m->Hacc[9 * g + k] - Hstart[9 * g + k]) * (m->Hacc[9 * g + k] - Hstart[9 * g + k]);
            m->deq[g] = sqrt(s2);
        }
        free(Hstart);
        if (step == o->iso_steps) { /* the end of stage 1: h_ic, det F_ic; the top becomes the platen */
            double J = 0.0, W = 0.0;
            m->h_ic = mean_top(m, m->u);
            for (g = 0; g < m->ngp; ++g) {
                double F[9];
                gk_m3_identity(F);
                for (k = 0; k < 9; ++k) F[k] += m->Hacc[9 * g + k];
                J += m->wgp[g] * gk_m3_det(F), W += m->wgp[g];
            }
            m->J_ic = J / W;
            if (!m->single) /* a rigid platen: the top nodes level at h_ic */
                for (k = 0; k < m->ntop; ++k) m->u[2 * m->top[k] + 1] = m->h_ic - m->h0;
        }
        for (g = 0; g < m->ngp; ++g) /* eq 38 needs contacts along two directions */
            if (!isfinite(m->stats[g].anisotropy)) {
                char whose[64];
                snprintf(whose, sizeof whose, "Gauss point %d's RVE", g);
                return came_apart(step, whose);
            }
        make_row(m, step, stage, iters, m->dem_total - dem0, &r);
        add_row(m, &r);
        m->step_done = step;
        if (m->resid_last > m->resid_max) m->resid_max = m->resid_last, m->resid_step = step;
        if (m->resid_last > RESID_WARN) ++m->resid_over;
        {
            char what[256];
            snprintf(what, sizeof what,
                     "stage %d  eps %.3f %%  sigma_bar %.4f  s11 %.4g s22 %.4g  DR %d  residual %.2g  "
                     "DEM/run %.0f",
                     stage, 100.0 * r.v[2], r.v[3], r.v[4], r.v[5], iters, m->resid_last,
                     (double)(m->dem_total - dem0) / (iters > 0 ? (double)iters * m->ngp : 1.0));
            gk_progress_since(stderr, step, step0, nsteps, m->t0, what);
        }
        if (write_csv(m, "dr.csv")) return 1;
        if ((o->vtk_every > 0 && step % o->vtk_every == 0) || step == nsteps)
            if (write_vtk(m, step)) return 1;
        if (step % o->checkpoint == 0 || step == nsteps || step == o->stop_after)
            if (save_checkpoint(m)) return 1;
        if (step == o->stop_after) {
            printf("stopped after step %d (%s/checkpoint.bin)\n", step, o->out);
            return 0;
        }
    }
    if (m->resid_over > 0)
        fprintf(stderr,
                PROG ": warning: %lld of %d load steps ended with a force residual above %.0f %% (largest "
                     "%.3g, step %lld): eq 28's energy ratio stopped them before equilibrium, their "
                     "stresses are not the load's; --dr-force-tol 1e-2 relaxes every step to 1 %%\n",
                m->resid_over, nsteps, 100.0 * RESID_WARN, m->resid_max, m->resid_step);
    if (write_svgs(m)) return 1;
    result_line(m);
    return 0;
}

/* ------------------------------------------------------------------ main */
int main(int argc, char **argv) {
    model m;
    int rc;
    char kn_txt[32];
    memset(&m, 0, sizeof m);
    dr_opts_default(&m.o);
    if ((rc = parse(argc, argv, &m.o)) != 0) return rc;
    if (mkdir(m.o.out, 0777) != 0 && errno != EEXIST) {
        fprintf(stderr, PROG ": cannot create %s\n", m.o.out);
        return 1;
    }
    m.t0 = gk_wtime();
    if (m.o.test == TEST_DNS) {
        if (m.o.restart) {
            fprintf(stderr, PROG ": --restart is for --test biaxial and rve\n");
            return 2;
        }
        rc = run_dns(&m);
        gk_packing_free(&m.pk);
        free(m.rows);
        return rc;
    }
    m.single = m.o.test == TEST_RVE;
    if (m.single) m.o.nx = m.o.ny = 1;
    if (setup(&m)) return 1;
    if (m.o.material == 1)
        snprintf(kn_txt, sizeof kn_txt, "E r*");
    else
        snprintf(kn_txt, sizeof kn_txt, "%.4g N/m", m.o.kn_ratio * m.o.pressure);
    printf("femdem_dr: %s, %s RVE (%d particles, %d boundary), rotation %s, %d Gauss points, k_n %s, "
           "omega_max %.4g rad/s\n",
           m.single ? "the RVE alone" : "biaxial test",
           m.o.frame == GK_FRAME_SERVO ? "servo-framed" : "periodic-cell",
           m.o.frame == GK_FRAME_SERVO ? m.fr.n : m.pk.n, m.o.frame == GK_FRAME_SERVO ? m.fr.nq : 0,
           rotation_name(&m.o), m.ngp, kn_txt, m.omega_max);
    if (!m.single) {
        char stop_txt[64] = "";
        if (m.o.force_stop > 0.0)
            snprintf(stop_txt, sizeof stop_txt, " or at a force residual %g", m.o.force_stop);
        printf("femdem_dr: a load step starts from %s and ends at E_kin / E_kin,max %g (eq 28)%s\n",
               m.o.predictor ? "the uniform specimen's next state" : "the last state, the platen moved",
               m.o.tol_dr, stop_txt);
    }
    rc = run_fem(&m);
    gk_twoscale_destroy(&m.ts);
    gk_frame_free(&m.fr);
    gk_packing_free(&m.pk);
    if (!m.single) gk_mesh_free(&m.mesh);
    free(m.dNdX), free(m.wgp), free(m.mass), free(m.u), free(m.v), free(m.fint), free(m.fext), free(m.f0),
        free(m.u0);
    free(m.P), free(m.H), free(m.Hacc), free(m.dH), free(m.deq), free(m.fixed), free(m.top), free(m.edge);
    free(m.stats), free(m.rows);
    return rc;
}
