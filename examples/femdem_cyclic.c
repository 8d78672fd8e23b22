/* femdem_cyclic - the Guo & Zhao 2014 FEMxDEM cyclic simple-shear tests (Guo & Zhao 2014, sec 5).
 *
 *   build/femdem_cyclic --test cyclic-strain|cyclic-stress [--nx 15 --ny 10] [--amplitude 0.01 |
 *                       --tau-amplitude 3e4] [--cycles 20] [--threads 2] --out DIR
 *
 * A 100 x 50 mm specimen (the paper's mesh: --nx 15 --ny 10, Q8, 600 Gauss points; default 2 x 2, 16
 * RVEs), bottom fixed, the top moved horizontally by a rough platen whose vertical displacement is
 * held, left and right sides PERIODIC (every right node tied to the left node at the same height
 * through a gk_dofmap; the Newton system is condensed, K_r = T^T K T). Height and width are fixed, so
 * the specimen volume is constant: the "undrained" test of dry sand. The RVEs, their DEM step rule,
 * the tangents, the Newton iteration and cut-back are femdem_biaxial's (examples/femdem.h,
 * femdem_newton.h), except that a predictor already in equilibrium, E_f < --ftol, is accepted at the
 * first iteration: under displacement-driven shear of a uniform specimen it often is, until the RVEs
 * drift apart. The load step is a platen displacement d gamma x H.
 *   - cyclic-strain: gamma = u_top / H goes 0 -> +A -> -A -> +A ... in steps of --increment
 *     (A = --amplitude, default 1 %).
 *   - cyclic-stress: the platen moves until the shear stress on the top reaches +-tau_A
 *     (--tau-amplitude, default 30 kPa), then reverses. The step landing on tau_A is repeated with a
 *     secant-corrected increment until |tau - tau_A| < 2 % tau_A (Newton on the platen displacement);
 *     other steps are sized from the last secant modulus so that a quarter cycle takes about
 *     --stress-steps steps (at most --increment).
 * Liquefaction: p' (mean stress of the volume-averaged RVE stress) below --liq-ratio (0.1) x its
 * initial value. cyclic-strain stops there; cyclic-stress stops when |gamma| reaches --gamma-limit (5
 * %, the paper's criterion) and also reports when p' first collapsed. Both stop after --cycles cycles. A
 * cycle is 0 -> +A -> 0 -> -A -> 0 (fractional values interpolate within the current loading branch).
 *
 * OUTPUTS in DIR (a failed write is an error: status 1)
 *   cyclic.csv    step,cycle,gamma,tau,sigma_yy,sigma_xx,p,q,eps_v_rve,top_uy,iterations,seconds,E_d,E_f,
 *                 increment,failed_gp,dem_steps_mean,dem_steps_max,dem_steps,tangents_reused,
 *                 tangents_computed - tau = sigma_xy from the top reaction [Pa] (positive with gamma),
 *                 sigma_yy from the top reaction, sigma_xx, p, q (eq 7) from the volume-averaged RVE
 *                 stress, normal stresses COMPRESSION POSITIVE; eps_v_rve the area-weighted mean RVE
 *                 volume change (contraction positive, ~0 at constant volume); top_uy the mean platen
 *                 lift (0)
 *   cyclic_stress_path.svg (tau vs sigma_yy and q vs p), cyclic_stress_strain.svg (tau vs gamma),
 *   cyclic_pressure.svg (p and sigma_yy vs cycles), void_ratio_field.svg, gp/mesh VTK, checkpoint.bin
 *   RESULT test=... liquefied=... cycles=... cycles_to_liquefaction=... cycles_to_gamma_limit=... p0=...
 *          p_final=... sigma_yy_final=... tau_final=... gamma_final=... e_min=... e_max=... ...
 *          total_seconds=... dem_rule=... dem_steps_total=... dem_steps_max=... tangents_reused=...
 *          tangents_computed=...
 */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_fem.h"
#include "gk_io.h"
#include "gk_twoscale.h"
#include "femdem_io.h"
#include "femdem_newton.h"

/* what a row of cyclic.csv has besides fd_row (eps = gamma, syy = sigma_yy, sxx = sigma_xx, ev = eps_v_rve) */
typedef struct cyc_extra {
    double cycle, tau, p, q, top_uy;
} cyc_extra;

/* loading branch 0 = 0 -> +A, then -A, +A, ...; state at its start */
typedef struct cyc_state {
    int dir, branch, good, bsteps; /* bsteps: steps done in this branch */
    double gamma, g_start, t_start, tau, h, p0, cyc_liq, cyc_gamma;
    double G0, Gu; /* stress control: secant moduli of the first step and of the last unloading */
} cyc_state;

typedef struct cyc_model {
    fd_model m; /* first: a cyc_model is an fd_model */
    int test;   /* 0 strain-, 1 stress-controlled */
    int stress_steps;
    double amp, tau_amp, cycles, gamma_stop, liq_ratio;
    cyc_state cs;
    cyc_extra *cx; /* one per row of m.curve                          */
    int cxcap;
} cyc_model;

static void usage(FILE *fp) {
    fprintf(
        fp,
        "usage: femdem_cyclic --test cyclic-strain|cyclic-stress [--amplitude 0.01 | --tau-amplitude 3e4]\n"
        "                     [--cycles 20] [--nx 2 --ny 2] [--threads 2] [--out DIR]\n\n"
        "cyclic simple shear: 100 x 50 mm, bottom fixed, rough top platen moved horizontally with its\n"
        "vertical displacement held, left/right sides periodic. Defaults: --nx 2 --ny 2 (Q8, 16 RVEs; the\n"
        "paper's mesh is --nx 15 --ny 10, 600 RVEs), --width 0.1 --height 0.05, --increment 0.001 (shear\n"
        "strain per step), --vtk-every 0 (VTK of the final state only), --packing\n"
        "examples/data/rve400_e0223.txt (cyclic-strain) or rve400_e0209.txt (cyclic-stress), the paper's\n"
        "void ratios.\n"
        "  --test KIND            cyclic-strain (default) or cyclic-stress\n"
        "  --amplitude A          cyclic-strain: shear strain amplitude gamma_A (default 0.01 = 1 %%)\n"
        "  --tau-amplitude T      cyclic-stress: shear stress amplitude [Pa] (default 3e4)\n"
        "  --stress-steps N       cyclic-stress: about N steps per quarter cycle (default 6); the\n"
        "                         strain increment is then at most --increment and at least 1/64 of it\n"
        "  --cycles N             stop after N cycles (default 20)\n"
        "  --liq-ratio R          liquefaction when p' < R x p'_0 (default 0.1); cyclic-strain stops there\n"
        "  --gamma-limit G        cyclic-stress: stop when |gamma| >= G (default 0.05, the paper's 5 %%)\n"
        "  --paper-mesh           Guo & Zhao 2014's mesh: 15 x 10 Q4 elements, 2 x 2 Gauss points (600 "
        "RVEs;\n"
        "                         its cost: examples/README.md, cyclic simple shear)\n"
        "  --pressure P           initial isotropic stress [Pa]: when it differs from the packing's own by\n"
        "                         more than 0.5 %% the RVE is first re-consolidated to P with its contact\n"
        "                         friction (default: the packing as it is, 100 kPa for the shipped ones)\n"
        "  --width, --height M    specimen size [m]\n");
    fd_usage_common(fp);
}

/* ------------------------------------------------------------ state and rows */
/* shear stress on the top platen from the internal force in fint (the reaction), positive with gamma */
static double top_tau(const fd_model *M) {
    double fx = 0.0;
    int a;
    for (a = 0; a < M->ntop; ++a) fx += M->fint[2 * M->top[a]];
    return fx / M->o.width;
}

/* state after a committed step (fint from fd_residual(sig_n)): the top reaction, the volume average of
 * the RVE stresses (compression positive), the area-weighted mean RVE volume change and the mean
 * platen lift. 0, or 1 (the fields could not be gathered) */
static int cyclic_state(cyc_model *C, fd_row *c, cyc_extra *x) {
    fd_model *M = &C->m;
    gk_twoscale_field *f = (gk_twoscale_field *)malloc((size_t)M->ngp * sizeof *f);
    double fy = 0, uy = 0, area = 0, sa[3] = {0, 0, 0}, ev = 0, sxx, syy, sxy;
    int a, e, g;
    if (!f || gk_twoscale_fields(&M->ts, f)) return free(f), 1;
    for (a = 0; a < M->ntop; ++a) fy += M->fint[2 * M->top[a] + 1], uy += M->utot[2 * M->top[a] + 1];
    for (e = 0; e < M->mesh.nelem; ++e)
        for (g = 0; g < M->q.n; ++g) {
            double dN[16], dJ, w;
            int id = e * M->q.n + g;
            gk_fem_jacobian(&M->mesh, e, M->q.xi[g], NULL, dN, &dJ, NULL);
            w = M->q.w[g] * dJ;
            sa[0] += w * M->sig_n[9 * id], sa[1] += w * M->sig_n[9 * id + 4],
                sa[2] += w * M->sig_n[9 * id + 1];
            ev += w * (1.0 - f[id].volume / M->v0[id]);
            area += w;
        }
    free(f);
    sxx = -sa[0] / area, syy = -sa[1] / area, sxy = sa[2] / area;
    c->eps = C->cs.gamma, c->syy = -fy / M->o.width, c->sxx = sxx, c->ev = ev / area;
    x->tau = top_tau(M), x->p = 0.5 * (sxx + syy);
    x->q = sqrt(0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy); /* Guo & Zhao 2014 eq 7 */
    x->top_uy = uy / M->ntop;
    return 0;
}

/* cycles so far: branch 0 (0 -> +A) is the first quarter, every later branch (+A -> -A or back) a half;
 * within a branch, progress in gamma (strain control) or tau (stress control) */
static double cycles_at(const cyc_model *C, double gamma, double tau) {
    const cyc_state *c = &C->cs;
    double f, q0 = c->branch == 0 ? 0.0 : 2.0 * c->branch - 1, ql = c->branch == 0 ? 1.0 : 2.0;
    if (C->test == 0)
        f = (gamma - c->g_start) / (c->dir * C->amp - c->g_start);
    else
        f = (tau - c->t_start) / (c->dir * C->tau_amp - c->t_start);
    if (!(f > 0.0)) f = 0.0;
    if (f > 1.0) f = 1.0;
    return (q0 + f * ql) / 4.0;
}

static void csv_row(FILE *fp, const fd_model *M, int k, const void *user) {
    const fd_row *c = &M->curve[k];
    const cyc_extra *x = &((const cyc_extra *)user)[k];
    fprintf(fp, "%d,%.6f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%.3g,%d,%.4f,%.4g,%.4g,%.6g,%d,", k, x->cycle,
            c->eps, x->tau, c->syy, c->sxx, x->p, x->q, c->ev, x->top_uy, c->iters, c->secs, c->Ed, c->Ef,
            c->inc, c->failed);
    fd_csv_work(fp, c);
}

static int write_csv(const cyc_model *C) {
    return fd_write_csv(
        &C->m, "cyclic.csv",
        "step,cycle,gamma,tau,sigma_yy,sigma_xx,p,q,eps_v_rve,top_uy,iterations,seconds,E_d,E_f,"
        "increment,failed_gp," FD_WORK_COLS "\n",
        csv_row, C->cx);
}

/* room for the rows of curve in cx */
static int cx_room(cyc_model *C) {
    cyc_extra *x;
    if (C->cxcap >= C->m.cap) return 0;
    if (!(x = (cyc_extra *)realloc(C->cx, (size_t)C->m.cap * sizeof *x))) return 1;
    C->cx = x, C->cxcap = C->m.cap;
    return 0;
}

/* ------------------------------------------------------------ checkpoint */
static const char *ck_tag(const cyc_model *C) { return C->test ? "GKFEMCYC6" : "GKFEMCYC5"; }

static int checkpoint(fd_model *M) {
    cyc_model *C = (cyc_model *)M;
    fd_buf x;
    int bad;
    memset(&x, 0, sizeof x);
    fd_put(&x, &C->cs, sizeof C->cs);
    fd_put(&x, C->cx, (size_t)M->ncurve * sizeof(cyc_extra));
    bad = x.bad || fd_ck_save(M, ck_tag(C), &x);
    free(x.b);
    return bad;
}

/* this driver's part of a checkpoint (fd_ck_load's part): the cyclic state and a cyc_extra per row,
 * the exact length, every real finite, the direction +-1, the branch and step counters >= 0 and far
 * from overflowing, the stress-control increment in (0, 1], the moduli >= 0 */
typedef struct cyc_part {
    cyc_state cs;
    cyc_extra *cx;
    int cap;
} cyc_part;

static int cyc_part_read(fd_model *M, fd_buf *B, const fd_ck *ck, void *user, char *why, size_t nwhy) {
    cyc_part *p = (cyc_part *)user;
    cyc_state cs;
    double d[10];
    int k;
    (void)M;
    if (B->n - B->pos != sizeof cs + (size_t)ck->nc * sizeof(cyc_extra))
        return snprintf(why, nwhy, "the driver's block has the wrong length"), 1;
    p->cap = ck->nc + FD_CK_ROOM; /* the model's curve capacity after fd_ck_apply */
    if (!(p->cx = (cyc_extra *)malloc((size_t)p->cap * sizeof *p->cx)))
        return snprintf(why, nwhy, "out of memory"), 2;
    fd_get(B, &cs, sizeof cs), fd_get(B, p->cx, (size_t)ck->nc * sizeof *p->cx);
    d[0] = cs.gamma, d[1] = cs.g_start, d[2] = cs.t_start, d[3] = cs.tau, d[4] = cs.h, d[5] = cs.p0;
    d[6] = cs.cyc_liq, d[7] = cs.cyc_gamma, d[8] = cs.G0, d[9] = cs.Gu;
    if (!fd_ck_bounded(d, 10, 1e100) || (cs.dir != 1 && cs.dir != -1) || cs.branch < 0 ||
        cs.branch > 100000000 || cs.bsteps < 0 || cs.bsteps > 1000000000 || cs.good < 0 ||
        cs.good > 1000000000 || !(cs.h > 0.0 && cs.h <= 1.0) || cs.G0 < 0.0 || cs.Gu < 0.0)
        return snprintf(why, nwhy, "the cyclic state is out of range"), 1;
    for (k = 0; k < ck->nc; ++k) {
        double e[5];
        e[0] = p->cx[k].cycle, e[1] = p->cx[k].tau, e[2] = p->cx[k].p, e[3] = p->cx[k].q,
        e[4] = p->cx[k].top_uy;
        if (!fd_ck_bounded(e, 5, 1e100)) return snprintf(why, nwhy, "the cyclic state is out of range"), 1;
    }
    p->cs = cs;
    return 0;
}

/* --restart DIR: the checkpoint into the set and the model, or neither (fd_ck_load with the driver's
 * part above) */
static int restart(cyc_model *C, gk_err *err) {
    fd_model *M = &C->m;
    cyc_part p;
    memset(&p, 0, sizeof p);
    if (fd_ck_load(M, M->o.restart, ck_tag(C), cyc_part_read, &p, err)) {
        free(p.cx);
        return 1;
    }
    C->cs = p.cs;
    free(C->cx), C->cx = p.cx, C->cxcap = p.cap;
    fd_say(M, "%s: restarted from %s/checkpoint.bin at step %d (shear strain %.3f %%, %.2f cycles)\n",
           M->prog, M->o.restart, M->step, 100 * C->cs.gamma, C->cx[M->ncurve - 1].cycle);
    return 0;
}

/* ------------------------------------------------------------ the loading loop */
/* stress control: strain increment for a shear-stress change of tau_A / stress_steps at secant
 * modulus G, within [inc / 64, inc] */
static double stress_increment(const cyc_model *C, double G, double h) {
    double inc = C->m.o.inc, hn = G > 0.0 ? C->tau_amp / C->stress_steps / G : 2.0 * h;
    if (hn > 2.0 * h) hn = 2.0 * h;
    if (hn > inc) hn = inc;
    if (!(hn >= inc / 64)) hn = inc / 64;
    return hn;
}

/* after a converged step: rows, stress-control sizing, reversal, liquefaction; the status of the
 * step's outputs, 4 when a stop criterion is met */
static int after_step(cyc_model *C, double inc, int iters, double Ed, double Ef, double t0, double t_start,
                      gk_err *err) {
    fd_model *M = &C->m;
    cyc_state *c = &C->cs;
    const fd_opts *o = &M->o;
    fd_row *row;
    cyc_extra *x;
    double cyc;
    int g, nf = 0, reversed = 0;
    if (fd_commit(M, err)) return fd_say(M, "%s: %s\n", M->prog, err->msg), 1;
    c->gamma += inc;
    ++M->step;
    fd_residual(M, M->sig_n, err);
    for (g = 0; g < M->ngp; ++g) nf += M->failed[g];
    if (fd_row_room(M) || cx_room(C)) return fd_say(M, "%s: out of memory\n", M->prog), 1;
    row = &M->curve[M->ncurve], x = &C->cx[M->ncurve++];
    if (cyclic_state(C, row, x)) return fd_say(M, "%s: %s\n", M->prog, gk_twoscale_error(&M->ts)), 1;
    row->iters = iters, row->secs = gk_wtime() - t0, row->Ed = Ed, row->Ef = Ef, row->inc = inc,
    row->failed = nf;
    fd_row_work(M, row);
    x->cycle = cyc = cycles_at(C, c->gamma, x->tau);
    ++c->bsteps;
    if (C->test == 1) { /* next increment from the secant modulus of this step */
        double G = (x->tau - c->tau) / inc;
        if (!(c->G0 > 0.0) && G > 0.0) c->G0 = G;
        if (c->branch > 0 && c->bsteps == 1 && G > 0.0) c->Gu = G;
        c->h = stress_increment(C, G, c->h);
    }
    c->tau = x->tau;
    if (C->test == 0 ? fabs(c->gamma - c->dir * C->amp) <= 1e-9 * C->amp
                     : c->dir * x->tau >= 0.98 * C->tau_amp) {
        if (C->test == 0) c->gamma = c->dir * C->amp; /* no drift of the turning points */
        c->dir = -c->dir, ++c->branch, c->bsteps = 0, c->g_start = c->gamma, c->t_start = x->tau,
        reversed = 1;
        if (C->test == 1) /* unloading: as stiff as the last unloading (the first time: the first step) */
            c->h = stress_increment(C, c->Gu > 0.0 ? c->Gu : c->G0, o->inc);
    }
    if (c->cyc_liq < 0 && x->p <= C->liq_ratio * c->p0) c->cyc_liq = cyc;
    if (C->test == 1 && c->cyc_gamma < 0 && fabs(c->gamma) >= C->gamma_stop) c->cyc_gamma = cyc;
    if (++c->good >= 2 && M->scale < 1.0) M->scale *= 2, c->good = 0;
    if (write_csv(C)) return 1;
    if (o->vtk_every && M->step % o->vtk_every == 0 && fd_write_vtk(M, M->step)) return 1;
    if (o->checkpoint && M->step % o->checkpoint == 0 && checkpoint(M)) return 1;
    fd_say(M,
           "step %d  cycle %.2f  gamma %.3f %%  tau %.2f kPa  sigma_yy %.2f kPa  p %.2f kPa  %d iter  DEM "
           "steps/RVE %.0f "
           "(max %d)  %.2f s%s | %.1f s elapsed\n",
           M->step, cyc, 100 * c->gamma, x->tau / 1e3, row->syy / 1e3, x->p / 1e3, iters, row->dem_mean,
           row->dem_max, row->secs, reversed ? "  (reversal)" : "", gk_wtime() - t_start);
    if (C->test == 0 && c->cyc_liq >= 0) {
        fd_say(M, "%s: liquefied (p < %.3g x p0) after %.2f cycles\n", M->prog, C->liq_ratio, cyc);
        return 4;
    }
    if (C->test == 1 && c->cyc_gamma >= 0) {
        fd_say(M, "%s: |gamma| reached %.3g %% after %.2f cycles\n", M->prog, 100 * C->gamma_stop, cyc);
        return 4;
    }
    return 0;
}

/* the cyclic loading loop (Guo & Zhao 2014 sec 5); 0, 1 (an error, said) or 3 (gave up after cut-backs) */
static int run_cyclic(cyc_model *C, double t_start, gk_err *err) {
    fd_model *M = &C->m;
    const fd_opts *o = &M->o;
    cyc_state *c = &C->cs;
    int tries = 0, r;
    double forced = 0.0; /* stress control: the increment of a repeated step */
    while (cycles_at(C, c->gamma, c->tau) < C->cycles - 1e-9) {
        double inc, t0 = gk_wtime(), Ed = 0, Ef = 0;
        int iters = 0;
        if (C->test == 0) { /* the next increment; the last one of a branch lands on the amplitude */
            double target = c->dir * C->amp;
            inc = c->dir * o->inc * M->scale;
            if (c->dir * (c->gamma + inc - target) > -1e-9 * C->amp) inc = target - c->gamma;
        } else
            inc = forced != 0.0 ? forced : c->dir * c->h * M->scale;
        if ((r = fd_load_step(M, inc, &iters, &Ed, &Ef, err)) == 2) return 1;
        if (r == 1) {
            forced = 0.0, tries = 0, c->good = 0;
            if (fd_cut_back(M, "shear strain", c->gamma, C->test == 0 ? o->inc : c->h, iters, Ed, err))
                return 3;
            continue;
        }
        if (C->test == 1) { /* overshoot of the amplitude: repeat with the secant increment */
            double tt = top_tau(M), goal = c->dir * C->tau_amp;
            if (c->dir * tt > 1.02 * C->tau_amp && tries < 4) {
                double ratio = (goal - c->tau) / (tt - c->tau);
                if (!(ratio > 0.05 && ratio < 1.0)) ratio = 0.5;
                if (o->verbose)
                    fd_say(M,
                           "    tau %.2f kPa overshoots %.2f kPa: step repeated with %.3g x the increment\n",
                           tt / 1e3, goal / 1e3, ratio);
                forced = inc * ratio, ++tries;
                gk_twoscale_reject(&M->ts);
                continue;
            }
        }
        forced = 0.0, tries = 0;
        r = after_step(C, inc, iters, Ed, Ef, t0, t_start, err);
        if (r) return r == 4 ? 0 : r;
    }
    return 0;
}

/* final outputs, a summary and the RESULT line; the status, or 1 when an output failed */
static int cyclic_summary(cyc_model *C, int status) {
    fd_model *M = &C->m;
    const fd_opts *o = &M->o;
    const cyc_state *c = &C->cs;
    const fd_row *last = &M->curve[M->ncurve - 1];
    const cyc_extra *xl = &C->cx[M->ncurve - 1];
    double emin = HUGE_VAL, emax = -HUGE_VAL, tot = 0, evmax = 0, uymax = 0, pmin = HUGE_VAL,
           *all = fd_gp_fields(M);
    int g, k, itmax = 0, itsum = 0, n = M->ncurve - 1, bad = !all;
    char title[200];
    for (g = 0; g < M->ngp && !bad; ++g) {
        double e = all[FD_NFIELD * g + 2];
        if (e < emin) emin = e;
        if (e > emax) emax = e;
    }
    free(all);
    for (k = 0; k < M->ncurve; ++k) {
        if (fabs(M->curve[k].ev) > evmax) evmax = fabs(M->curve[k].ev);
        if (fabs(C->cx[k].top_uy) > uymax) uymax = fabs(C->cx[k].top_uy);
        if (C->cx[k].p < pmin) pmin = C->cx[k].p;
        if (k == 0) continue;
        tot += M->curve[k].secs, itsum += M->curve[k].iters;
        if (M->curve[k].iters > itmax) itmax = M->curve[k].iters;
    }
    bad = bad || write_csv(C);
    if (!bad) { /* the plots */
        double *v = (double *)malloc((size_t)M->ncurve * 6 * sizeof(double)), *gm, *t, *sy, *p, *q, *cy;
        gk_plot pl;
        if (!v) return fd_say(M, "%s: out of memory\n", M->prog), 1;
        gm = v, t = v + M->ncurve, sy = t + M->ncurve, p = sy + M->ncurve, q = p + M->ncurve,
        cy = q + M->ncurve;
        for (k = 0; k < M->ncurve; ++k) {
            gm[k] = 100 * M->curve[k].eps, t[k] = C->cx[k].tau / 1e3, sy[k] = M->curve[k].syy / 1e3;
            p[k] = C->cx[k].p / 1e3, q[k] = C->cx[k].q / 1e3, cy[k] = C->cx[k].cycle;
        }
        if (C->test == 0)
            snprintf(title, sizeof title,
                     "Cyclic simple shear, constant volume, gamma = +-%.2g %% (Guo & Zhao 2014 Fig 20)",
                     100 * C->amp);
        else
            snprintf(title, sizeof title,
                     "Cyclic simple shear, constant volume, tau = +-%.3g kPa (Guo & Zhao 2014 Fig 22)",
                     C->tau_amp / 1e3);
        gk_plot_init(&pl, title, "sigma_yy or p [kPa] (compression positive)", "tau or q [kPa]");
        gk_plot_add(&pl, sy, t, M->ncurve, "tau vs sigma_yy (top platen reaction)");
        gk_plot_add(&pl, p, q, M->ncurve, "q vs p (volume-averaged RVE stress)");
        bad = fd_plot(M, &pl, "cyclic_stress_path.svg");
        gk_plot_init(&pl, title, "shear strain gamma [%]", "tau = sigma_xy [kPa]");
        gk_plot_add(&pl, gm, t, M->ncurve, NULL);
        bad = bad || fd_plot(M, &pl, "cyclic_stress_strain.svg");
        gk_plot_init(&pl, title, "cycles", "stress [kPa] (compression positive)");
        gk_plot_add(&pl, cy, p, M->ncurve, "p (volume average)");
        gk_plot_add(&pl, cy, sy, M->ncurve, "sigma_yy (top platen)");
        gk_plot_add(&pl, cy, t, M->ncurve, "tau (top platen)");
        bad = bad || fd_plot(M, &pl, "cyclic_pressure.svg");
        free(v);
    }
    snprintf(title, sizeof title, "void ratio after %.2f cycles, gamma = %.2f %%", xl->cycle, 100 * c->gamma);
    bad = bad || fd_write_field_svg(M, 2, 1.0, "void_ratio_field.svg", title, "void ratio e [-]", 0, 0);
    bad = bad || ((!o->vtk_every || M->step % o->vtk_every) && fd_write_vtk(M, M->step));
    bad = bad || (status != 3 && checkpoint(M));
    if (bad) return 1;
    if (!M->root) return status;
    printf("wrote %s/cyclic.csv, cyclic_stress_path.svg, cyclic_stress_strain.svg, cyclic_pressure.svg, "
           "void_ratio_field.svg, gp_%04d.vtk and mesh_%04d.vtk (ParaView), checkpoint.bin\n",
           o->out, M->step, M->step);
    if (c->cyc_liq >= 0)
        printf("liquefaction (p < %.3g x p0 = %.2f kPa) after %.2f cycles\n", C->liq_ratio,
               C->liq_ratio * c->p0 / 1e3, c->cyc_liq);
    else
        printf("no liquefaction: p from %.2f kPa to %.2f kPa (lowest %.2f kPa) in %.2f cycles\n", c->p0 / 1e3,
               xl->p / 1e3, pmin / 1e3, xl->cycle);
    if (C->test == 1)
        printf("|gamma| %s %.3g %%%s\n", c->cyc_gamma >= 0 ? "reached" : "stayed below", 100 * C->gamma_stop,
               c->cyc_gamma >= 0 ? "" : " (cycle limit)");
    printf("local void ratio %.4f - %.4f; max |mean RVE eps_v| %.2e; max |top u_y| %.1e m\n", emin, emax,
           evmax, uymax);
    printf(
        "RESULT test=%s liquefied=%d cycles=%.3f cycles_to_liquefaction=%.3f cycles_to_gamma_limit=%.3f "
        "p0=%.6g "
        "p_final=%.6g p_min=%.6g sigma_yy_final=%.6g tau_final=%.6g gamma_final=%.6g e_min=%.5f e_max=%.5f "
        "max_eps_v_rve=%.3g max_iterations=%d mean_iterations=%.2f steps=%d seconds_per_step=%.3f "
        "total_seconds=%.2f",
        o->test, c->cyc_liq >= 0, xl->cycle, c->cyc_liq, c->cyc_gamma, c->p0, xl->p, pmin, last->syy, xl->tau,
        c->gamma, emin, emax, evmax, itmax, n > 0 ? (double)itsum / n : 0.0, n, n > 0 ? tot / n : 0.0, tot);
    fd_print_work_totals(M);
    return status;
}

/* the initial state: the RVEs under the platens, row 0 */
static int first_row(cyc_model *C, gk_err *err) {
    fd_model *M = &C->m;
    cyc_state *c = &C->cs;
    fd_external_force(M, err);
    fd_residual(M, M->sig_n, err);
    memset(&M->curve[0], 0, sizeof M->curve[0]);
    memset(&C->cx[0], 0, sizeof C->cx[0]);
    if (cyclic_state(C, &M->curve[0], &C->cx[0]))
        return gk_err_set(err, GK_ERR_STATE, "%s", gk_twoscale_error(&M->ts)), 1;
    M->ncurve = 1;
    c->dir = 1, c->branch = 0, c->good = 0, c->bsteps = 0, c->gamma = c->g_start = 0.0, c->G0 = c->Gu = 0.0;
    c->tau = c->t_start = C->cx[0].tau, c->p0 = C->cx[0].p, c->h = M->o.inc / 8;
    c->cyc_liq = c->cyc_gamma = -1.0;
    return 0;
}

/* options, defaults by test, the checks between options; 0, or 2 after a message (help: 0, *help) */
static int parse(cyc_model *C, int argc, char **argv, int *help) {
    fd_model *M = &C->m;
    fd_opts *o = &M->o;
    const char *prog = M->root ? M->prog : NULL;
    int paper = 0;
    const cli_opt own[] = {
        {"--test", CLI_CHOICE, &C->test, 0, 0, NULL, "cyclic-strain|cyclic-stress", 0},
        {"--amplitude", CLI_REAL, &C->amp, 0, 0.5, "a shear strain in (0, 0.5)", NULL,
         CLI_LO_OPEN | CLI_HI_OPEN},
        {"--tau-amplitude", CLI_REAL, &C->tau_amp, 0, HUGE_VAL, "a positive stress", NULL,
         CLI_LO_OPEN | CLI_HI_OPEN},
        {"--stress-steps", CLI_INT, &C->stress_steps, 1, 1000000, NULL, NULL, 0},
        {"--cycles", CLI_REAL, &C->cycles, 0, 1e5, "a number of cycles in (0, 1e5]", NULL, CLI_LO_OPEN},
        {"--liq-ratio", CLI_REAL, &C->liq_ratio, 0, 1, "a fraction in (0, 1)", NULL,
         CLI_LO_OPEN | CLI_HI_OPEN},
        {"--gamma-limit", CLI_REAL, &C->gamma_stop, 0, HUGE_VAL, "a positive shear strain", NULL,
         CLI_LO_OPEN | CLI_HI_OPEN},
        {"--paper-mesh", CLI_FLAG, &paper, 0, 0, NULL, NULL, 0},
        {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    const cli_opt *tables[3];
    fd_opts_default(o);
    o->nx = 2, o->ny = 2, o->width = 0.1, o->height = 0.05, o->pressure = 0.0 /* the packing's own */;
    o->vtk_every = 0, o->packing = NULL;
    C->amp = 0.01, C->tau_amp = 3e4, C->stress_steps = 6, C->cycles = 20, C->gamma_stop = 0.05,
    C->liq_ratio = 0.1;
    tables[0] = fd_common_opts(o), tables[1] = own, tables[2] = NULL;
    if (cli_parse(prog, argc, argv, tables, help) || *help) return *help ? 0 : 2;
    if (paper) { /* Guo & Zhao 2014 Sec 5: 15 x 10 elements, 600 Gauss points */
        if (o->nx != 2 || o->ny != 2 || o->elem_kind != 1 || o->quad != 2) {
            cli_say(prog,
                    "%s: --paper-mesh is 15 x 10 Q4 elements with 2 x 2 Gauss points: give it or --nx, --ny, "
                    "--element, --quad\n",
                    prog);
            return 2;
        }
        o->nx = 15, o->ny = 10, o->elem_kind = 0, o->quad = 2;
    }
    o->cyclic = C->test + 1;
    o->test = C->test ? "cyclic-stress" : "cyclic-strain";
    if (!o->packing)
        o->packing = C->test ? "examples/data/rve400_e0209.txt" : "examples/data/rve400_e0223.txt";
    if (o->extrapolate) {
        cli_say(prog,
                "%s: --predictor extrapolate is for the biaxial and single tests (a cyclic reversal would "
                "extrapolate the wrong way)\n",
                prog);
        return 2;
    }
    if (strchr(o->packing, ',') && o->pressure > 0) {
        cli_say(prog,
                "%s: --pressure re-consolidates one packing; with a list of packings give them at their own "
                "stress\n",
                prog);
        return 2;
    }
    return fd_opts_finish(prog, o);
}

int main(int argc, char **argv) {
    cyc_model C;
    fd_model *M = &C.m;
    gk_err err;
    gk_twoscale_field *f0 = NULL;
    int status, help = 0;
    memset(&C, 0, sizeof C);
    M->prog = "femdem_cyclic", M->root = fd_start(&argc, &argv), M->checkpoint = checkpoint;
    status = parse(&C, argc, argv, &help);
    if (!status && help) {
        if (M->root) usage(stdout);
    } else if (!status) {
        status = 1;
        if (fd_mkdir_out(M))
            ;
        else if (fd_setup(M, &err) || cx_room(&C) || (M->o.restart ? restart(&C, &err) : first_row(&C, &err)))
            fd_say(M, "%s: %s\n", M->prog, C.cx ? err.msg : "out of memory");
        else if (!(f0 = (gk_twoscale_field *)malloc((size_t)M->ngp * sizeof *f0)) ||
                 gk_twoscale_fields(&M->ts, f0))
            fd_say(M, "%s: %s\n", M->prog, f0 ? gk_twoscale_error(&M->ts) : "out of memory");
        else {
            if (M->root) {
                printf(
                    "%s: %s test, %d x %d %s elements, %d Gauss points x %d disks, tangent %s, %d threads\n",
                    M->prog, M->o.test, M->o.nx, M->o.ny, M->o.elem == GK_Q8 ? "Q8" : "Q4", M->ngp,
                    M->ts.pk[0].n, M->o.tangent, M->o.threads);
                printf("%s: %s, void ratio %.4f, p0 = %.2f kPa, sigma_yy0 = %.2f kPa; left/right periodic: "
                       "%d -> %d "
                       "dofs; %s amplitude %.4g%s, at most %.4g cycles\n",
                       M->prog, M->o.packing, f0[0].void_ratio, C.cs.p0 / 1e3, M->curve[0].syy / 1e3, M->dm.n,
                       M->dm.nred, C.test == 0 ? "shear strain" : "shear stress",
                       C.test == 0 ? 100 * C.amp : C.tau_amp / 1e3, C.test == 0 ? " %" : " kPa", C.cycles);
                fflush(stdout);
            }
            status = run_cyclic(&C, gk_wtime(), &err);
            if (status != 1) status = cyclic_summary(&C, status);
        }
    }
    free(C.cx), free(f0);
    fd_free(M);
    fd_stop();
    return status;
}
