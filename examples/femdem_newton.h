/* femdem_newton.h - the Newton iteration of the FEMxDEM drivers (examples, not library).
 *
 * fd_load_step solves one load (sub)step of the model of femdem.h: full Newton-Raphson (Guo & Zhao 2014
 * sec 2.3) on the RVEs' stresses and tangents, converged when E_d = |du| / |u| < --tol (eq 21) or
 * E_f = |R_free| / |f_int| < --ftol:
 *   - predictor: the tangent solve K(D_n) u = f_ext - f_int(sigma_n) with the prescribed platen
 *     increment, or (--predictor extrapolate) the last converged increment scaled to this one
 *     (ABAQUS's default: a shear band, once formed, is carried into the next step);
 *   - relaxation of the Newton corrections: Aitken (Irons & Tuck 1969; the affine tangent makes
 *     Newton converge linearly with a nearly constant ratio): d_k scaled by
 *     w_k = -w_(k-1) d_(k-1).(d_k - d_(k-1)) / |d_k - d_(k-1)|^2, clamped to [0.25, 4]; or
 *     Anderson mixing of the Newton map u + d(u) over the last FD_AND_M iterates; or none;
 *   - line search: when the residual norm grows by > 25 % the correction is halved once and the
 *     RVEs re-run (counted as an iteration);
 *   - cyclic tests: a predictor already in equilibrium (E_f < --ftol) is accepted at iteration 1.
 * fd_cut_back is the cut-back rule: a step that does not converge in --max-iter iterations, or
 * whose RVEs fail, is retried from the converged state with half the increment, down to 1/16; then
 * the driver writes a checkpoint of the last converged state, says so, and exits with status 3.
 */
#ifndef FEMDEM_NEWTON_H
#define FEMDEM_NEWTON_H

#include "femdem.h"

/* Anderson mixing: the correction M->du of iterate u becomes the mixed one (history in M->andF,
 * andG, fprev, Gprev; *hist differences stored, *it_and calls so far) */
static void fd_anderson(fd_model *M, int *hist, int *it_and) {
    int n = M->ndof, mm = *hist < FD_AND_M ? *hist : FD_AND_M, a, b, k;
    double *G = M->rhs; /* free here: the solve is done */
    for (k = 0; k < n; ++k) G[k] = M->u[k] + M->du[k];
    if (*it_and > 0) { /* newest difference into the ring slot */
        int slot = *hist % FD_AND_M;
        for (k = 0; k < n; ++k) {
            M->andF[(size_t)slot * n + k] = M->du[k] - M->fprev[k];
            M->andG[(size_t)slot * n + k] = G[k] - M->Gprev[k];
        }
        ++*hist;
        mm = *hist < FD_AND_M ? *hist : FD_AND_M;
    }
    memcpy(M->fprev, M->du, (size_t)n * sizeof(double));
    memcpy(M->Gprev, G, (size_t)n * sizeof(double));
    ++*it_and;
    if (mm > 0) { /* gamma = argmin |d_k - dF gamma| (normal equations, tiny ridge) */
        double A[FD_AND_M * FD_AND_M], rb[FD_AND_M], gam[FD_AND_M], tr = 0.0;
        for (a = 0; a < mm; ++a) {
            const double *Fa = M->andF + (size_t)a * n;
            rb[a] = 0.0;
            for (k = 0; k < n; ++k) rb[a] += Fa[k] * M->du[k];
            for (b = 0; b <= a; ++b) {
                const double *Fb = M->andF + (size_t)b * n;
                double acc = 0.0;
                for (k = 0; k < n; ++k) acc += Fa[k] * Fb[k];
                A[a * FD_AND_M + b] = A[b * FD_AND_M + a] = acc;
            }
            tr += A[a * FD_AND_M + a];
        }
        for (a = 0; a < mm; ++a) A[a * FD_AND_M + a] += 1e-8 * tr / mm;
        for (a = 0; a < mm; ++a) /* Gaussian elimination (SPD) */
            for (b = a + 1; b < mm; ++b) {
                double l = A[b * FD_AND_M + a] / A[a * FD_AND_M + a];
                int c2;
                for (c2 = a; c2 < mm; ++c2) A[b * FD_AND_M + c2] -= l * A[a * FD_AND_M + c2];
                rb[b] -= l * rb[a];
            }
        for (a = mm - 1; a >= 0; --a) {
            double acc = rb[a];
            for (b = a + 1; b < mm; ++b) acc -= A[a * FD_AND_M + b] * gam[b];
            gam[a] = acc / A[a * FD_AND_M + a];
        }
        for (k = 0; k < n; ++k) {
            double v = G[k];
            for (a = 0; a < mm; ++a) v -= M->andG[(size_t)a * n + k] * gam[a];
            M->du[k] = v - M->u[k];
        }
    }
}

/* Aitken (Irons-Tuck) relaxation of the Newton correction M->du (previous one in M->dprev) */
static void fd_aitken(fd_model *M, int *have_prev, double *omega) {
    int k;
    if (*have_prev) {
        double num = 0.0, den = 0.0;
        for (k = 0; k < M->ndof; ++k) {
            double dd = M->du[k] - M->dprev[k];
            num += M->dprev[k] * dd, den += dd * dd;
        }
        if (den > 0.0) *omega = -*omega * num / den;
        if (!(*omega >= 0.25)) *omega = 0.25; /* also catches NaN */
        if (*omega > 4.0) *omega = 4.0;
    }
    memcpy(M->dprev, M->du, (size_t)M->ndof * sizeof(double));
    *have_prev = 1;
    for (k = 0; k < M->ndof; ++k) M->du[k] *= *omega;
}

/* one load (sub)step of platen increment inc (biaxial: axial strain, the top moves down by inc H;
 * cyclic: shear strain, the top moves by inc H in x); 0 = converged, 1 = not converged, 2 = hard
 * error (said; the trial states rejected) */
static int fd_newton(fd_model *M, double inc, int *iters, double *Ed_out, double *Ef_out, gk_err *err);
static int fd_load_step(fd_model *M, double inc, int *iters, double *Ed_out, double *Ef_out, gk_err *err) {
    int r = fd_newton(M, inc, iters, Ed_out, Ef_out, err);
    if (r == 2) {
        fd_say(M, "%s: %s\n", M->prog, err->msg);
        gk_twoscale_reject(&M->ts);
    }
    return r;
}
static int fd_newton(fd_model *M, double inc, int *iters, double *Ed_out, double *Ef_out, gk_err *err) {
    int it, k, nbad, have_prev = 0, hist = 0, it_and = 0;
    double Ed = 1.0, Ef = 0.0, Rprev = HUGE_VAL, top = (M->o.cyclic ? inc : -inc) * M->o.height, omega = 1.0,
           dnewton = 0.0;
    fd_gradients(M);
    if (fd_external_force(M, err)) return 2;
    if (M->o.extrapolate && M->inclast != 0.0) { /* predictor: the last converged increment, scaled */
        double f = inc / M->inclast;
        for (k = 0; k < M->ndof; ++k) M->u[k] = f * M->ulast[k];
        if (M->o.verbose) fd_say(M, "    predictor: the last increment x %.4g\n", f);
    } else { /* predictor: K(D_n) u = f_ext - f_int(sig_n) with the prescribed increment */
        fd_residual(M, M->sig_n, err);
        for (k = 0; k < M->ndof; ++k) M->du[k] = -M->R[k];
        if (fd_solve(M, M->D_n, M->du, top, M->u, err)) return 1;
    }
    for (it = 1; it <= M->o.max_iter; ++it) {
        double t0 = gk_wtime(), Rn;
        nbad = fd_eval(M, M->u, err);
        if (nbad) {
            if (M->o.verbose) fd_say(M, "    iter %2d: %d RVEs failed -> cut back\n", it, nbad);
            gk_err_set(err, GK_ERR_STATE, "iteration %d: %.200s", it, gk_twoscale_error(&M->ts));
            *iters = it, *Ed_out = Ed, *Ef_out = Ef;
            return 1;
        }
        Ef = fd_residual(M, M->sig, err);
        Rn = fd_norm(M->R, M->ndof);
        if (M->probe && M->probe(M, it, Ef, err)) {
            *iters = it, *Ed_out = Ed, *Ef_out = Ef;
            return 1;
        }
        if (M->o.verbose) {
            double nmean;
            int nmax;
            fd_dem_stats(M, &nmean, &nmax);
            fd_say(M, "    iter %2d: E_d %.3e  E_f %.3e  DEM steps per RVE mean %.1f max %d  %.2f s\n", it,
                   Ed, Ef, nmean, nmax, gk_wtime() - t0);
        }
        /* cyclic: a predictor already in equilibrium is accepted at the first iteration (displacement-
         * driven shear of a uniform specimen: the predictor is exact until the RVEs drift apart) */
        if ((it > 1 || M->o.cyclic) && (Ed < M->o.tol || Ef < M->o.ftol)) {
            *iters = it, *Ed_out = Ed, *Ef_out = Ef;
            return 0;
        }
        if (it >= M->o.max_iter) break;
        if (M->o.aitken != 2 && it > 2 && Rn > 1.25 * Rprev) { /* line search: the last correction overshot */
            for (k = 0; k < M->ndof; ++k) M->du[k] *= 0.5, M->u[k] -= M->du[k];
            /* --ed newton: a backtrack is not a Newton correction; no E_d acceptance before the next one */
            Ed = M->o.ed_newton ? 1.0 : fd_norm(M->du, M->ndof) / (fd_norm(M->u, M->ndof) + 1e-300);
            Rprev = HUGE_VAL; /* accept whatever the halved step gives */
            have_prev = 0, omega = 1.0;
            if (M->o.verbose) fd_say(M, "    iter %2d: residual grew, correction halved\n", it);
            continue;
        }
        Rprev = Rn;
        fd_floor_tangents(M, M->D);
        for (k = 0; k < M->ndof; ++k) M->R[k] = -M->R[k];
        if (fd_solve(M, M->D, M->R, 0.0, M->du, err)) return 1;
        dnewton = fd_norm(M->du, M->ndof); /* the Newton correction before relaxation */
        if (M->o.aitken == 2)
            fd_anderson(M, &hist, &it_and);
        else if (M->o.aitken)
            fd_aitken(M, &have_prev, &omega);
        for (k = 0; k < M->ndof; ++k) M->u[k] += M->du[k];
        Ed = (M->o.ed_newton ? dnewton : fd_norm(M->du, M->ndof)) / (fd_norm(M->u, M->ndof) + 1e-300);
    }
    *iters = M->o.max_iter, *Ed_out = Ed, *Ef_out = Ef;
    return 1;
}

/* a load step that did not converge: halve the increment (the caller retries); below 1/16 of it give
 * up with the last converged state in checkpoint.bin (the driver's M->checkpoint). 1 when giving up. */
static int fd_cut_back(fd_model *M, const char *what, double strain, double nominal, int iters, double Ed,
                       gk_err *err) {
    gk_twoscale_reject(&M->ts); /* the next try starts from the converged states */
    M->scale *= 0.5;
    fd_say(M,
           "%s: step at %.3f %% did not converge in %d iterations (E_d %.3g)%s%s; increment cut to %.4g %%\n",
           M->prog, 100 * strain, iters, Ed, err->msg[0] ? ": " : "", err->msg, 100 * nominal * M->scale);
    err->msg[0] = 0;
    if (M->scale >= 1.0 / 16) return 0;
    fd_say(M, "%s: giving up at %s %.3f %%; last converged state in %s/checkpoint.bin\n", M->prog, what,
           100 * strain, M->o.out);
    if (M->checkpoint) M->checkpoint(M);
    return 1;
}

#endif /* FEMDEM_NEWTON_H */
