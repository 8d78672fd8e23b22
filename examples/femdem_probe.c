/* femdem_probe - the femdem_biaxial run with Newton diagnostics at one iteration of every step.
 *
 *   build/femdem_probe [femdem_biaxial's options] --noise-probe K | --krylov-probe K [--krylov-scale X]
 *
 * The same biaxial test as build/femdem_biaxial (the same CSV, bit for bit: a probe's RVE runs are
 * not counted and the iterate is evaluated again after it, which gives the same stresses and
 * tangents), with one of two probes at Newton iteration K of every load step:
 *   --noise-probe K    re-runs every RVE at u (1 + eps), eps = 1e-6 ... 1e-2, and prints the change of
 *                      the residual |R(u (1+eps)) - R(u)| / |f_int| next to E_f. Where the change grows
 *                      in proportion to eps it is the RVE map's response; where it grows much more
 *                      slowly (tiny eps) it is DEM noise: a residual far above that floor is not noise
 *                      (on the 8 x 16 mesh at most 3e-4 of |f_int| at eps = 1e-3, while the iterates'
 *                      E_f is 2e-3 to 1e-2; examples/README.md, "FEMxDEM convergence study").
 *   --krylov-probe K   asks whether any deformation near the iterate reduces the residual at all:
 *                      GMRES on J d = -R with J the RVEs' own directional derivatives
 *                      (R(u + h z) - R(u)) / h, |h z| = X |u| (--krylov-scale X, default 0.05), right-
 *                      preconditioned by the iterate's tangent. For 1-6 directions it prints the linear
 *                      model's |R + J d| / |R| (the GMRES minimum: it cannot grow with the directions)
 *                      and the E_f found at u + d; 1 direction is the best step along the Newton
 *                      correction. Near 1: no deformation in that space reduces the residual, whatever
 *                      the tangent (12 extra RVE evaluations).
 * Neither goes with --tangent-reuse (the probe's runs would move the reuse references).
 */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_fem.h"
#include "gk_io.h"
#include "gk_twoscale.h"
#include "femdem_biaxial.h"

#define KRYLOV_M 6

typedef struct probe_model {
    fd_model m; /* first: a probe_model is an fd_model */
    int noise, krylov;
    double kscale;
} probe_model;

/* the end of a probe: the iterate at u0 again (deterministic: the same stresses, tangents and
 * residual) and the work counters as before the probe, its RVE runs uncounted. The failed RVE runs. */
static int probe_end(fd_model *M, const double *u0, long long pd, long long pr, long long pc, gk_err *err) {
    int nbad;
    memcpy(M->u, u0, (size_t)M->ndof * sizeof(double));
    nbad = fd_eval(M, M->u, err);
    if (!nbad) fd_residual(M, M->sig, err);
    M->pend_dem = pd, M->pend_reused = pr, M->pend_computed = pc;
    return nbad;
}

/* --noise-probe: the change of the residual under u -> u (1 + eps) relative to |f_int| */
static int noise_probe(fd_model *M, int it, double Ef, gk_err *err) {
    double *R0 = (double *)malloc((size_t)M->ndof * sizeof(double)),
           *u0 = (double *)malloc((size_t)M->ndof * sizeof(double)), eps;
    long long pd = M->pend_dem, pr = M->pend_reused, pc = M->pend_computed;
    int k, nbad = 0;
    if (!R0 || !u0) {
        free(R0), free(u0);
        fd_say(M, "    noise probe: out of memory, skipped\n");
        return 0;
    }
    memcpy(R0, M->R, (size_t)M->ndof * sizeof(double));
    memcpy(u0, M->u, (size_t)M->ndof * sizeof(double));
    fd_say(M, "    noise probe at iteration %d (E_f %.3e): |R(u(1+eps)) - R(u)| / |f_int| =", it, Ef);
    for (eps = 1e-6; eps < 2e-2 && !nbad; eps *= 10) {
        double d = 0.0, fn;
        for (k = 0; k < M->ndof; ++k) M->u[k] = u0[k] * (1.0 + eps);
        if ((nbad = fd_eval(M, M->u, err)) != 0) break;
        fd_residual(M, M->sig, err);
        fn = fd_norm(M->fint, M->ndof);
        for (k = 0; k < M->ndof; ++k) d += (M->R[k] - R0[k]) * (M->R[k] - R0[k]);
        fd_say(M, " %.0e: %.2e", eps, fn > 0 ? sqrt(d) / fn : 0.0);
    }
    fd_say(M, nbad ? " (an RVE run failed)\n" : "\n");
    nbad = probe_end(M, u0, pd, pr, pc, err);
    free(R0), free(u0);
    return nbad;
}

/* --krylov-probe: GMRES on J d = -R with the RVE map's own directional derivatives */
static int krylov_probe(probe_model *P, int it, double Ef, gk_err *err) {
    fd_model *M = &P->m;
    int n = M->ndof, j, i, k, nbad = 0, m;
    long long pd = M->pend_dem, pr = M->pend_reused, pc = M->pend_computed;
    double *Dp = (double *)malloc((size_t)M->ngp * 16 * sizeof(double)),
           *u0 = (double *)malloc((size_t)n * sizeof(double)),
           *R0 = (double *)malloc((size_t)n * sizeof(double)),
           *V = (double *)malloc((size_t)(KRYLOV_M + 1) * n * sizeof(double)),
           *Z = (double *)malloc((size_t)KRYLOV_M * n * sizeof(double)),
           *w = (double *)malloc((size_t)n * sizeof(double));
    double Hh[KRYLOV_M + 1][KRYLOV_M], cs[KRYLOV_M], sn[KRYLOV_M], gv[KRYLOV_M + 1], beta, un;
    if (!Dp || !u0 || !R0 || !V || !Z || !w) {
        free(Dp), free(u0), free(R0), free(V), free(Z), free(w);
        fd_say(M, "    krylov probe: out of memory, skipped\n");
        return 0;
    }
    memcpy(Dp, M->D, (size_t)M->ngp * 16 * sizeof(double));
    fd_floor_tangents(M, Dp);
    memcpy(u0, M->u, (size_t)n * sizeof(double));
    memcpy(R0, M->R, (size_t)n * sizeof(double));
    un = fd_norm(u0, n), beta = fd_norm(R0, n);
    fd_say(M,
           "    krylov probe at iteration %d (E_f %.3e, |h z| = %g |u|): m, |R + J d|/|R| (model), E_f at u "
           "+ d:\n",
           it, Ef, P->kscale);
    memset(Hh, 0, sizeof Hh);
    for (k = 0; k < n; ++k) V[k] = beta > 0 ? -R0[k] / beta : 0.0;
    gv[0] = beta;
    for (j = 0; j < KRYLOV_M && beta > 0; ++j) {
        double *z = Z + (size_t)j * n, *vn = V + (size_t)(j + 1) * n, h, zn, y[KRYLOV_M], Efm, t;
        if (fd_solve(M, Dp, V + (size_t)j * n, 0.0, z, err)) break;
        zn = fd_norm(z, n);
        if (!(zn > 0)) break;
        h = P->kscale * un / zn;
        for (k = 0; k < n; ++k) M->u[k] = u0[k] + h * z[k];
        if ((nbad = fd_eval(M, M->u, err)) != 0) break;
        fd_residual(M, M->sig, err);
        for (k = 0; k < n; ++k) w[k] = (M->R[k] - R0[k]) / h;
        for (i = 0; i <= j; ++i) { /* modified Gram-Schmidt */
            const double *vi = V + (size_t)i * n;
            double d = 0.0;
            for (k = 0; k < n; ++k) d += w[k] * vi[k];
            Hh[i][j] = d;
            for (k = 0; k < n; ++k) w[k] -= d * vi[k];
        }
        Hh[j + 1][j] = fd_norm(w, n);
        for (k = 0; k < n; ++k) vn[k] = Hh[j + 1][j] > 0 ? w[k] / Hh[j + 1][j] : 0.0;
        for (i = 0; i < j; ++i) { /* the earlier Givens rotations, then a new one for row j + 1 */
            t = cs[i] * Hh[i][j] + sn[i] * Hh[i + 1][j];
            Hh[i + 1][j] = -sn[i] * Hh[i][j] + cs[i] * Hh[i + 1][j], Hh[i][j] = t;
        }
        t = sqrt(Hh[j][j] * Hh[j][j] + Hh[j + 1][j] * Hh[j + 1][j]);
        cs[j] = t > 0 ? Hh[j][j] / t : 1.0, sn[j] = t > 0 ? Hh[j + 1][j] / t : 0.0;
        Hh[j][j] = t, Hh[j + 1][j] = 0.0;
        gv[j + 1] = -sn[j] * gv[j], gv[j] = cs[j] * gv[j];
        m = j + 1;
        for (i = m - 1; i >= 0; --i) { /* back substitution: the rotated triangle */
            double acc = gv[i];
            for (k = i + 1; k < m; ++k) acc -= Hh[i][k] * y[k];
            y[i] = Hh[i][i] != 0 ? acc / Hh[i][i] : 0.0;
        }
        for (k = 0; k < n; ++k) {
            double d = 0.0;
            for (i = 0; i < m; ++i) d += y[i] * Z[(size_t)i * n + k];
            M->u[k] = u0[k] + d;
        }
        if ((nbad = fd_eval(M, M->u, err)) != 0) break;
        Efm = fd_residual(M, M->sig, err);
        fd_say(M, "      m %d: %.3e  E_f %.3e\n", m, fabs(gv[m]) / beta, Efm);
    }
    if (nbad) fd_say(M, "      (an RVE run failed; probe stopped)\n");
    nbad = probe_end(M, u0, pd, pr, pc, err);
    free(Dp), free(u0), free(R0), free(V), free(Z), free(w);
    return nbad;
}

/* the hook of fd_load_step */
static int probe(fd_model *M, int it, double Ef, gk_err *err) {
    probe_model *P = (probe_model *)M;
    if (it == P->noise && noise_probe(M, it, Ef, err))
        return gk_err_set(err, GK_ERR_STATE, "an RVE run failed again at the iterate after the noise probe"),
               1;
    if (it == P->krylov && krylov_probe(P, it, Ef, err))
        return gk_err_set(err, GK_ERR_STATE, "an RVE run failed again at the iterate after the Krylov probe"),
               1;
    return 0;
}

static void usage(FILE *fp) {
    fprintf(
        fp,
        "usage: femdem_probe [femdem_biaxial's options] --noise-probe K | --krylov-probe K [--krylov-scale "
        "X]\n\n"
        "  --noise-probe K        at Newton iteration K of every step, re-run all RVEs at u (1 + eps),\n"
        "                         eps = 1e-6 ... 1e-2, and print |R(u (1+eps)) - R(u)| / |f_int| next to "
        "E_f\n"
        "  --krylov-probe K       at Newton iteration K of every step, GMRES on J d = -R with J the RVEs'\n"
        "                         own responses (R(u + h z) - R(u)) / h, |h z| = X |u| (--krylov-scale X,\n"
        "                         default 0.05), preconditioned by the iterate's tangent: for 1-6\n"
        "                         directions, the model's |R + J d| / |R| and the E_f found at u + d\n"
        "  The run is femdem_biaxial's, its CSV unchanged (the probes' RVE runs are not counted; the\n"
        "  iterate is evaluated again after them). Not with --tangent-reuse.\n\n");
    fd_usage_common(fp);
}

int main(int argc, char **argv) {
    probe_model P;
    fd_model *M = &P.m;
    const cli_opt *tables[4];
    const cli_opt own[] = {{"--noise-probe", CLI_INT, &P.noise, 0, 100000, NULL, NULL, 0},
                           {"--krylov-probe", CLI_INT, &P.krylov, 0, 100000, NULL, NULL, 0},
                           {"--krylov-scale", CLI_REAL, &P.kscale, 0, 1, NULL, NULL, CLI_LO_OPEN},
                           {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    int status, help = 0;
    memset(&P, 0, sizeof P);
    M->prog = "femdem_probe", M->root = fd_start(&argc, &argv), M->probe = probe;
    P.kscale = 0.05;
    fdb_defaults(M);
    tables[0] = fd_common_opts(&M->o), tables[1] = fdb_opts(&M->o), tables[2] = own, tables[3] = NULL;
    status = cli_parse(M->prog, argc, argv, tables, &help);
    if (!status && help)
        usage(stdout);
    else if (!status && (P.noise > 0 || P.krylov > 0) && M->o.tangent_reuse > 0) {
        fprintf(stderr,
                "%s: --%s-probe re-runs the RVEs and would move the reference of --tangent-reuse: use one of "
                "them\n",
                M->prog, P.noise > 0 ? "noise" : "krylov");
        status = 2;
    } else if (!status && !(status = fdb_check(M)))
        status = fdb_run(M);
    fd_free(M);
    fd_stop();
    return status;
}
