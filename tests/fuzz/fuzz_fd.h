/* fuzz_fd.h - what the FEMxDEM checkpoint harnesses (fuzz_femdem_ckpt.c, fuzz_cyclic_ckpt.c) share:
 * the model state the model's block of a checkpoint carries, as bytes, and the checks of an
 * accepted block. Included after the driver (fd_model, fd_gp_fields, FD_NFIELD). */
#ifndef FUZZ_FD_H
#define FUZZ_FD_H
#include "fuzz_driver.h"

/* step, strain, increment scale, rows, mesh, displacements, stresses and tangents, as bytes (malloc'ed) */
static unsigned char *fz_fd_bytes(const fd_model *M, size_t *n) {
    size_t nd = (size_t)M->ndof * sizeof(double), ng = (size_t)M->ngp;
    size_t parts[9];
    const void *src[9];
    src[0] = &M->step, parts[0] = sizeof M->step;
    src[1] = &M->eps_done, parts[1] = sizeof M->eps_done;
    src[2] = &M->scale, parts[2] = sizeof M->scale;
    src[3] = &M->ncurve, parts[3] = sizeof M->ncurve;
    src[4] = M->curve, parts[4] = (size_t)M->ncurve * sizeof(fd_row);
    src[5] = M->mesh.x, parts[5] = nd;
    src[6] = M->utot, parts[6] = nd;
    src[7] = M->sig_n, parts[7] = 9 * ng * sizeof(double);
    src[8] = M->D_n, parts[8] = 16 * ng * sizeof(double);
    return fuzz_concat(src, parts, 9, n);
}

/* an accepted model block: every value in range and finite, the deformed mesh valid (gk_mesh_check),
 * the Gauss-point fields finite */
static void fz_fd_accepted(fd_model *M) {
    size_t n = (size_t)M->ndof, k;
    double *f, L = 0.0;
    gk_mesh m;
    gk_err err;
    int c;
    for (k = 0; k < n; ++k) L = fmax(L, fabs(M->A0x[k]));
    FUZZ_CHECK(M->step >= 0 && M->step <= 1000000000 && M->eps_done >= 0 && M->eps_done < 1);
    FUZZ_CHECK(M->scale >= 1.0 / 64 && M->scale <= 1 && M->ncurve >= 1 && M->ncurve <= M->cap);
    for (c = 0; c < M->ncurve; ++c) {
        const fd_row *w = &M->curve[c];
        double d[9];
        d[0] = w->eps, d[1] = w->syy, d[2] = w->sxx, d[3] = w->ev, d[4] = w->secs, d[5] = w->Ed, d[6] = w->Ef;
        d[7] = w->inc, d[8] = w->dem_mean;
        fuzz_all_finite(d, 9);
        FUZZ_CHECK(w->iters >= 0 && w->failed >= 0 && w->failed <= M->ngp && w->dem_max >= 0);
        FUZZ_CHECK(w->dem_total >= 0 && w->t_reused >= 0 && w->t_computed >= 0);
    }
    fuzz_all_finite(M->mesh.x, n), fuzz_all_finite(M->utot, n);
    for (k = 0; k < n; ++k) FUZZ_CHECK(fabs(M->utot[k]) <= 10 * L);
    fuzz_all_finite(M->sig_n, 9 * (size_t)M->ngp), fuzz_all_finite(M->D_n, 16 * (size_t)M->ngp);
    m = M->mesh;
    FUZZ_CHECK(gk_mesh_check(&m, &M->q, &err) == GK_OK);
    FUZZ_CHECK((f = fd_gp_fields(M)) != NULL);
    fuzz_all_finite(f, (size_t)M->ngp * FD_NFIELD);
    free(f);
}

#endif /* FUZZ_FD_H */
