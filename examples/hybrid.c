/* hybrid.c - hybrid continuum-grain simulation of shear bands: an MPM
 * continuum everywhere until an oracle finds the band, then grains in the
 * band (Chen, Chantharayukhonthorn, Yue, Grinspun & Kamrin 2021).
 *
 *   build/hybrid --test planar|biaxial|indent --mode dem|continuum|hybrid [options]
 *
 * TESTS (2D; compression-positive stresses in every output)
 *   planar   planar shear (Sec 6.1, Table 3): a W x H specimen, periodic
 *            left-right, bottom fixed, a rough top platen moving sideways
 *            at --speed while a servo holds the normal stress --pressure.
 *            tau = platen shear force / W, strain = platen displacement / W
 *            (the paper's definitions), sigma_n = platen normal force / W,
 *            eps_v = (H - H0) / H0.
 *   biaxial  the 2D analogue of the triaxial test (Sec 6.2, Table 5): a
 *            W x H specimen, confined by --pressure through a membrane
 *            (grains: a chain of the outermost grains, pressure plus
 *            tension-only springs of 1e4 N/m, App. B; continuum: a follower
 *            traction on its outer points), bottom rough, top platen
 *            frictionless moving down at --speed. strain = axial strain,
 *            sigma_n = axial stress, tau = (sigma_n - pressure) / 2,
 *            eps_v = area / area0 - 1 (from the material's extent per row).
 *   indent   plate indentation (Sec 6.3, Tables 7-9): a W x H bed under
 *            gravity (9.81 m/s^2) in a bin (rough bottom, smooth sides),
 *            settled from the consolidated packing; a rough rigid
 *            intruder B x 0.4 B (--intruder B) centred on it, driven down
 *            at --speed from where it touches the bed. strain = depth / B,
 *            tau = q = the intruder's vertical load / B, sigma_n = its
 *            horizontal load / B (zero but for noise), both the mean
 *            since the previous CSV row (the grains' load is
 *            intermittent; the paper smooths its Fig 23 too); eps_v and
 *            eps_v_band nan (an open bed), no band thickness (the bands
 *            are curved; band.svg maps the incremental shear strain).
 *            Continuum: geostatic stress
 *            (sigma_yy = -rho g depth, sigma_xx = K0 sigma_yy, Jaky's
 *            K0 = 1 - sin phi with eq 7's phi), rollers at the sides, the
 *            intruder in contact with the points (not the grid nodes);
 *            the grains' intruder: four segment walls.
 * MODES
 *   dem        grains everywhere (the ground truth)
 *   continuum  MPM everywhere: Hencky-like hypoelastic Drucker-Prager with
 *              critical-state softening [eqs 4-8]; the oracle runs and
 *              reports, nothing is enriched
 *   hybrid     MPM until the oracle triggers (Alg. 1), then the region
 *              within --phi0 of the flagged nodes becomes grains from the
 *              same packing as dem mode, kinematically trained (Sec 4.1.1),
 *              coupled through a one-cell overlap (eq 9); gk_hybrid.h has
 *              the method. Biaxial: the held boundary grains' training
 *              targets are corrected so that no two overlap more than in
 *              the packing (the continuum's affine compression would press
 *              them together, and released they flung grains out); a zone
 *              that reaches the top platen gets the grains' frictionless
 *              top wall, seated by a servo on the trained grains at the
 *              continuum's axial stress; grains that leave the overlap for
 *              the continuum zone stay coupled (as under gravity); the
 *              membrane chains on the grains' sides reach the top wall; a
 *              grain squeezed out that flies off, touching no grain and on
 *              no membrane, is removed before its coupling would leave the
 *              grid (printed, and counted in a warning at the end).
 *              Biaxial and indent: the zone is fixed on the grid and the
 *              material moves through it; a point carried more than half a
 *              cell into the discrete zone couples the grains whose
 *              stencils share its nodes, so it moves with them (uncoupled,
 *              nothing held it: one rode along the top platen over the
 *              grains and off the grid); the run prints how many at most.
 *              Planar: grains that leave the overlap stay free (coupled,
 *              they stiffen the band); one that strays more than a cell
 *              beyond the overlap touching no grain is removed (the same;
 *              --keep-strays keeps it).
 *              Overlap grains hold w = 1/2 of their mass and carry their
 *              whole contact forces; --weigh-overlap scales each contact
 *              by its grains' mean w (eq 9's w f; a grain's w is its share
 *              at the swap); on the reduced specimens that moves bands
 *              and stresses less than another packing does, in no
 *              consistent direction, and lowers the intruder's load
 *              (examples/README.md).
 *   band       App. A on the grains over --window: Cundall's best-fit
 *              strain over the grains within 1.6 D50 of each, or over its
 *              Delaunay neighbours as the paper (--delaunay; the reduced
 *              bands move by up to 6.4 D50, in no consistent direction:
 *              examples/README.md), then the top --percentile (or the
 *              --band-grains N largest) in a minimum-area box;
 *              --interior ranks only grains whose Voronoi cell closes (not
 *              the one-sided fits at the membranes, platens or the zone's
 *              edge).
 *
 * THE CODE. This file holds the manual and main (set-up, the loop of
 * steps, the outputs). The rest is in five headers, each including the one
 * before:
 *   hybrid_opts.h    tests, modes, material (Chen et al. Tables 1-2), the
 *                    options
 *   hybrid_setup.h   the packing, the run's state and geometry
 *   hybrid_model.h   the grains (DEM), the continuum (MPM) and the oracle
 *   hybrid_enrich.h  the enrichment (on the oracle's trigger), the coupled steps
 *   hybrid_output.h  VTK, hybrid.csv, the band measurement, the plots; its
 *                    manual lists every output file and the RESULT line
 *   RESULT mode=M peak_tau=Pa band_thickness_D50=X strain_at_enrichment=S
 *          seconds=T speedup_vs_dem=R packing_tau=Pa band_count=N
 *
 * COST. The defaults are reduced (3 x 6 cm planar, 1778 grains; 3 x 4.71
 * cm biaxial, 1435 grains; 5x the paper's platen speed; indent: a 12 x 4
 * cm bed of about 5000 grains, a 1 cm intruder at 2x the paper's speed):
 * one thread, about 25 CPU s for dem and 35-75 CPU s for continuum or
 * hybrid (indent: 5 minutes for dem, most of it the consolidation of the
 * packing, which --packing skips). --paper runs
 * the paper's sizes (Tables 3, 5: 7640 and 5910 grains at 0.02 m/s): about
 * 40x the grain-steps of the reduced runs (4 x the grains, 10 x the steps):
 * the planar dem run to 57 % took 30 min of wall time on one core (2.7e10
 * grain-steps, 0.059 us each).
 *
 * KNOWN LIMITS. The continuum's cost per MPM point-step is far above the
 * paper's relative to a grain-step, so the hybrid is slower than dem at
 * these sizes (see the cost: line). Indent: the discrete zone is made once
 * (as in the paper); the far-field variant (Fig 25, a moving side wall) is
 * not implemented. Biaxial at the paper's size: the discrete zone is a
 * slab under the top platen, not the band; 19 grains squeezed out of its
 * sides are removed (0.6 % of the grains' mass); the hybrid's mean shear
 * stress is 28 % above the all-grain run's, and on 2.5 mm cells the oracle
 * flags the platen's two corners, not the slab; the continuum alone stops
 * at 8.9 %, when its band, the layer under the platen, has slid out
 * along the platen past the grid's side (examples/README.md). The points
 * carried into the discrete zone and the grains they couple are material
 * twice over there, as are the grains that leave the overlap for the
 * continuum zone. Planar: the stray grains' mass leaves the model (1.6 %
 * at the paper's size). A failed step leaves the state it stopped in as
 * points_stopped.vtk and grains_stopped.vtk.
 */
#define GK_IMPLEMENTATION
#define _POSIX_C_SOURCE 200809L
#include "hybrid_output.h"

int main(int argc, char **argv) {
    static run Rs;
    run *R = &Rs;
    opts *o = &R->o;
    hist_t h;
    char path[1200];
    double thick = NAN, secs, hg;
    int band_count = 0;
    int band_done = 0; /* the band is measured once, when the strain reaches --window's end (at the
                        * latest on the last step: parse() keeps it within --strain) */
    int rc = parse(argc, argv, o), status = 0, step_failed = 0;
    if (rc) return rc == 2 ? 0 : 2;
    memset(&h, 0, sizeof h);
    R->top_wall = -1;
    R->dt = DT;
    R->packing_tau = NAN;
    if (make_dir(o->out)) return 1;
    R->t_start = wtime();
    if (make_packing(o, &R->pk, &R->phi_pack)) return 1;
    R->W = R->pk.h[0];
    /* the specimen: the packing's width (periodic, planar) and a whole number of
     * MPM cells of height (the continuum's top surface on a node row, where its
     * platen acts): the packing is cut there, for every mode alike; indent: the
     * grains that cross the bin's walls (x = 0, x = W, y = 0) are left out */
    hg = R->W / floor(R->W / o->cell + 0.5);
    if (o->test == T_INDENT) { /* the intruder centred, its edges on node lines (as the bin's walls) */
        double B = R->W - 2.0 * floor(0.5 * (R->W - o->intruder) / hg + 0.5) * hg;
        if (B < 1.5 * hg)
            return fprintf(stderr, "error: --intruder %g: narrower than two MPM cells (%g m)\n", o->intruder,
                           hg),
                   1;
        if (fabs(B - o->intruder) > 1e-9 && !o->quiet)
            printf("intruder: %.4g m wide (--intruder %g to the cells' node lines)\n", B, o->intruder);
        o->intruder = B;
    }
    R->H = floor(R->pk.h[4] / hg + 1e-9) * hg;
    {
        int k, q = 0;
        for (k = 0; k < R->pk.n; ++k)
            if (R->pk.y[k] < R->H &&
                (o->test != T_INDENT || (R->pk.x[k] - R->pk.r[k] >= 0.0 && R->pk.x[k] + R->pk.r[k] <= R->W &&
                                         R->pk.y[k] - R->pk.r[k] >= 0.0))) {
                R->pk.x[q] = R->pk.x[k];
                R->pk.y[q] = R->pk.y[k];
                R->pk.r[q] = R->pk.r[k];
                ++q;
            }
        R->pk.n = q;
        R->pk.h[4] = R->H;
    }
    R->rho = R->phi_pack * RHO_S;
    R->M = K_C + G_C;
    R->c = sqrt(R->M / R->rho);
    R->role = (unsigned char *)calloc((size_t)R->pk.n, 1);
    if (!R->role) return fprintf(stderr, "error: out of memory\n"), 1;
    if (!o->quiet)
        printf("%s %s: specimen %.4g x %.4g m, %d grains, packing fraction %.4f, pressure %g Pa, speed %g "
               "m/s, dt %g s\n",
               test_name[o->test], mode_name[o->mode], R->W, R->H, R->pk.n, R->phi_pack, o->pressure,
               o->speed, R->dt);
    if (o->test == T_INDENT && indent_settle(R)) return 1;
    if (o->mode == M_DEM) {
        if (setup_dem(R)) return 1;
    } else {
        if (setup_mpm(R) || oracle_setup(R)) return 1;
        if (!o->quiet)
            printf("continuum: %.4g x %.4g m, cells of %.4g m, %d points, c = %.4g m/s (0.3 h/c = %.3g s)\n",
                   R->W, R->H, R->h, R->P.n, R->c, 0.3 * R->h / R->c);
    }
    /* the band window: planar, the mid-height strip; biaxial, the line from the weak cell through the centre */
    R->win_c[0] = 0.5 * R->W;
    R->win_c[1] = 0.5 * R->H;
    R->win_e[0] = 1.0;
    R->win_e[1] = 0.0;
    if (o->test == T_BIAXIAL) {
        double dx = 0.5 * R->W - (R->W - 1.5 * hg), dy = 0.5 * R->H - 1.5 * hg, L = sqrt(dx * dx + dy * dy);
        R->win_e[0] = dx / L;
        R->win_e[1] = dy / L;
        R->win_a = 0.3 * (fabs(R->W / R->win_e[0]) < fabs(R->H / R->win_e[1]) ? fabs(R->W / R->win_e[0])
                                                                              : fabs(R->H / R->win_e[1]));
    }
    R->A0 = o->test == T_INDENT ? NAN : specimen_area(R);
    R->phi0_band = o->test == T_INDENT ? NAN : band_solid_fraction(R);
    R->sig_n = o->test == T_INDENT ? 0.0 : o->pressure; /* the consolidated state, before the first step */
    snprintf(path, sizeof path, "%s/hybrid.csv", o->out);
    R->csv = fopen(path, "w");
    if (!R->csv) return fprintf(stderr, "error: cannot write %s\n", path), 1;
    fprintf(R->csv,
            "time,strain,tau,sigma_n,eps_v,eps_v_band,grains,points,enriched,flagged_nodes,seconds\n");
    if (write_vtk(R, "start") || csv_row(R, &h)) return 1;
    R->next_out = o->out_every;
    while (R->strain < o->strain_end - 1e-12) {
        int was = R->enriched;
        if (o->mode == M_DEM) {
            if (dem_steps(R, 10)) {
                status = step_failed = 1;
                break;
            }
            if (o->probe_on && isnan(R->packing_tau) && R->strain >= o->probe[0]) {
                double sn;
                if (strip_stress(R, o->probe[1], o->probe[2], &R->packing_tau, &sn)) {
                    status = 1;
                    break;
                }
                if (!o->quiet)
                    printf("probe at strain %.6g: grains in y %.4g-%.4g m: tau %.4g kPa, sigma_n %.4g kPa\n",
                           R->strain, o->probe[1], o->probe[2], 1e-3 * R->packing_tau, 1e-3 * sn);
            }
        } else if (continuum_step(R)) {
            status = step_failed = 1;
            break;
        }
        if (o->test == T_INDENT) { /* the intruder's load, averaged into the next CSV row */
            R->qsum[0] += R->tau;
            R->qsum[1] += R->sig_n;
            ++R->qn;
        }
        if (R->enriched && !was && write_vtk(R, "enrichment")) status = 1;
        if (!R->window_taken && R->strain >= o->win0 && take_window(R)) status = 1;
        if (R->window_taken && !band_done && R->strain >= o->win1 - 1e-12) {
            band_done = 1;
            if (band_measure(R, &thick, &band_count)) status = 1;
        }
        if (R->strain >= R->next_out - 1e-12) {
            if (csv_row(R, &h)) {
                status = 1;
                break;
            }
            while (R->next_out <= R->strain + 1e-12) R->next_out += o->out_every;
        }
        if (status) break;
    }
    secs = wtime() - R->t_start;
    if (step_failed) write_vtk(R, "stopped"); /* the state a failed step left, to see why */
    if (!status) {
        if (write_vtk(R, "end") || write_plots(R, &h)) status = 1;
    }
    if (fclose(R->csv)) {
        fprintf(stderr, "error: cannot write %s/hybrid.csv\n", o->out);
        status = 1;
    }
    if (!o->quiet && R->grain_steps > 0)
        printf("cost: %.3g s in the grains (%.3g grain-steps, %.3g us each), %.3g s in the continuum (%.3g "
               "point-steps, "
               "%.3g us each), %.3g s coupling\n",
               R->sec_dem, (double)R->grain_steps, 1e6 * R->sec_dem / (double)R->grain_steps, R->sec_mpm,
               (double)R->point_steps, R->point_steps ? 1e6 * R->sec_mpm / (double)R->point_steps : 0.0,
               R->sec_cpl);
    if (!o->quiet && R->deep_max)
        printf("points carried into the discrete zone: at most %d at once (the grains about them coupled)\n",
               R->deep_max);
    if (R->lost) /* said even with --quiet: the grains' mass is not what it was */
        fprintf(stderr,
                "warning: %d grains touching no other %s and were removed (%.3g %% of the grains' mass)\n",
                R->lost, o->test == T_PLANAR ? "strayed into the continuum zone" : "left the specimen",
                100.0 * R->lost_mass);
    printf("RESULT mode=%s peak_tau=%.6g band_thickness_D50=%.4g strain_at_enrichment=%.4g seconds=%.2f "
           "speedup_vs_dem=%.3g packing_tau=%.6g band_count=%d\n",
           mode_name[o->mode], R->peak_tau, thick,
           o->mode == M_HYBRID ? (R->enriched ? R->strain_enrich : NAN)
                               : (R->triggered ? R->strain_trigger : NAN),
           secs, o->dem_seconds > 0.0 ? o->dem_seconds / secs : NAN, R->packing_tau, band_count);
    free(h.s);
    free(h.tau);
    free(h.sn);
    free(h.ev);
    free(h.evb);
    run_free(R);
    return status;
}
