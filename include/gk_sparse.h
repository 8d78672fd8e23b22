/* gk_sparse.h - sparse matrices and linear solvers.          (grainkit v0.1)
 *
 * Compressed sparse rows (CSR) and the solvers the macro scale needs, on
 * plain arrays: a FEM or any other caller assembles into a gk_csr (whose
 * pattern it builds, e.g. gk_csr_from_mesh in gk_mesh.h) and solves.
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_SPARSE_IMPLEMENTATION, or the
 * GK_FEM_, GK_MESH_ or GK_DOFMAP_IMPLEMENTATION of a header that includes
 * this one) in one file.
 *
 * MATRICES
 *   gk_csr                  n x n, rows sorted by column; owns its arrays
 *   gk_csr_at               the entry (i, j) inside the pattern, NULL outside
 *   gk_csr_zero / matvec / free
 *   gk_rcm_order            reverse Cuthill-McKee ordering of A's graph
 *
 * SOLVERS
 *   gk_solver_init          an empty solver (every gk_solver starts here:
 *                           factor refuses one that did not, GK_ERR_ARG)
 *   gk_solver_factor/solve  direct: reverse Cuthill-McKee ordering, then a
 *                           banded LU with partial pivoting (robust for the
 *                           non-symmetric perturbation tangent). A pivot below
 *                           1e-12 x max|A| -> GK_ERR_SINGULAR naming the dof
 *                           (typically an unconstrained rigid-body mode).
 *                           A new factorisation replaces (frees) the one the
 *                           solver held only on success; on failure the old
 *                           one is kept. gk_solver_free returns it to the
 *                           gk_solver_init state. solve: a non-finite b ->
 *                           GK_ERR_NAN, a non-finite solution (overflow) ->
 *                           GK_ERR_DIVERGED; x is then unchanged and the
 *                           message is in s->err.
 *   gk_pcg                  Jacobi-preconditioned conjugate gradients for large
 *                           symmetric positive definite systems; rtol in
 *                           (0, 1), b and the start x finite. x is changed
 *                           on success and on GK_ERR_NOCONVERGE (the last
 *                           iterate) only.
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_SPARSE_H
#define GK_SPARSE_H

#include "gk_base.h"

typedef struct gk_csr {
    int n, nnz;
    int *rowptr; /* n + 1                     */
    int *col;    /* nnz, sorted within a row  */
    double *val; /* nnz                       */
    gk_allocator alloc;
} gk_csr;

typedef struct gk_solver {
    int cookie;       /* set by gk_solver_init                              */
    int n, kl, ku, w; /* band: kl below, ku above (+kl fill from pivoting)  */
    int *perm;        /* perm[new] = old dof (reverse Cuthill-McKee)        */
    int *ipiv;        /* row interchanges                                   */
    double *ab;       /* n x w row-band: A(i,j) at ab[i*w + j - i + kl]     */
    double *tmp;      /* n                                                  */
    gk_allocator alloc;
    gk_err err; /* message of the last failed gk_solver_solve         */
} gk_solver;

#define GK_SOLVER_COOKIE 0x534f4c56

#ifdef __cplusplus
extern "C" {
#endif

GKDEF void gk_csr_free(gk_csr *A);
GKDEF void gk_csr_zero(gk_csr *A);
GKDEF double *gk_csr_at(gk_csr *A, int i, int j); /* NULL outside the pattern */
GKDEF void gk_csr_matvec(const gk_csr *A, const double *x, double *y);
GKDEF void gk_solver_init(gk_solver *s);
GKDEF gk_result gk_solver_factor(gk_solver *s, const gk_csr *A, const gk_allocator *alloc, gk_err *err);
GKDEF gk_result gk_solver_solve(gk_solver *s, const double *b, double *x);
GKDEF void gk_solver_free(gk_solver *s);
GKDEF gk_result gk_rcm_order(const gk_csr *A, int *perm, const gk_allocator *alloc, gk_err *err);
GKDEF gk_result gk_pcg(const gk_csr *A, const double *b, double *x, double rtol, int maxit, int *iters,
                       const gk_allocator *alloc, gk_err *err);

#ifdef __cplusplus
}
#endif

#endif /* GK_SPARSE_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_SPARSE_IMPLEMENTATION) || defined(GK_FEM_IMPLEMENTATION) || \
     defined(GK_MESH_IMPLEMENTATION) || defined(GK_DOFMAP_IMPLEMENTATION)) &&                             \
    !defined(GK_SPARSE_IMPL_ONCE)
#define GK_SPARSE_IMPL_ONCE

#include <math.h>
#include <stdlib.h>
#include <string.h>

GKDEF void gk_csr_free(gk_csr *A) {
    gk_free(&A->alloc, A->rowptr), gk_free(&A->alloc, A->col), gk_free(&A->alloc, A->val);
    memset(A, 0, sizeof *A);
}

GKDEF void gk_csr_zero(gk_csr *A) { memset(A->val, 0, (size_t)A->nnz * sizeof(double)); }

GKDEF double *gk_csr_at(gk_csr *A, int i, int j) {
    int lo = A->rowptr[i], hi = A->rowptr[i + 1] - 1;
    while (lo <= hi) {
        int mid = (lo + hi) >> 1;
        if (A->col[mid] == j) return A->val + mid;
        if (A->col[mid] < j)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return NULL;
}

GKDEF void gk_csr_matvec(const gk_csr *A, const double *x, double *y) {
    int i, p;
    for (i = 0; i < A->n; ++i) {
        double s = 0.0;
        for (p = A->rowptr[i]; p < A->rowptr[i + 1]; ++p) s += A->val[p] * x[A->col[p]];
        y[i] = s;
    }
}

/* ---------------------------------------------------------------- solvers */
GKDEF gk_result gk_rcm_order(const gk_csr *A, int *perm, const gk_allocator *alloc, gk_err *err) {
    int n = A->n, *deg, *lvl, *queue, head, tail, nout = 0, i, p, it;
    gk_allocator al;
    memset(&al, 0, sizeof al);
    if (alloc) al = *alloc;
    deg = (int *)gk_alloc(&al, (size_t)n * sizeof(int) + 1);
    lvl = (int *)gk_alloc(&al, (size_t)n * sizeof(int) + 1);
    queue = (int *)gk_alloc(&al, (size_t)n * sizeof(int) + 1);
    if (!deg || !lvl || !queue) {
        gk_free(&al, deg), gk_free(&al, lvl), gk_free(&al, queue);
        return gk_err_set(err, GK_ERR_ALLOC, "RCM work arrays");
    }
    for (i = 0; i < n; ++i) deg[i] = A->rowptr[i + 1] - A->rowptr[i], lvl[i] = -1;
    while (nout < n) {
        /* start: lowest-degree unvisited vertex, refined twice towards a
         * pseudo-peripheral one (last vertex of a BFS, lowest degree) */
        int s = -1, last;
        for (i = 0; i < n; ++i)
            if (lvl[i] < 0 && (s < 0 || deg[i] < deg[s])) s = i;
        for (it = 0; it < 2; ++it) {
            int maxl;
            head = tail = 0, queue[tail++] = s, lvl[s] = 0;
            while (head < tail) {
                int v = queue[head++];
                for (p = A->rowptr[v]; p < A->rowptr[v + 1]; ++p)
                    if (lvl[A->col[p]] < 0) lvl[A->col[p]] = lvl[v] + 1, queue[tail++] = A->col[p];
            }
            maxl = lvl[queue[tail - 1]];
            last = queue[tail - 1];
            for (i = 0; i < tail; ++i)
                if (lvl[queue[i]] == maxl && deg[queue[i]] < deg[last]) last = queue[i];
            for (i = 0; i < tail; ++i) lvl[queue[i]] = -1;
            s = last;
        }
        /* Cuthill-McKee BFS from s, neighbours by increasing degree */
        head = tail = 0, queue[tail++] = s, lvl[s] = 0;
        while (head < tail) {
            int v = queue[head++], t0 = tail, a, b;
            perm[nout++] = v;
            for (p = A->rowptr[v]; p < A->rowptr[v + 1]; ++p)
                if (lvl[A->col[p]] < 0) lvl[A->col[p]] = 0, queue[tail++] = A->col[p];
            for (a = t0 + 1; a < tail; ++a) { /* insertion sort by degree (ties: index) */
                int x = queue[a];
                b = a - 1;
                while (b >= t0 && (deg[queue[b]] > deg[x] || (deg[queue[b]] == deg[x] && queue[b] > x)))
                    queue[b + 1] = queue[b], --b;
                queue[b + 1] = x;
            }
        }
    }
    for (i = 0; i < n / 2; ++i) { /* reverse */
        int t = perm[i];
        perm[i] = perm[n - 1 - i], perm[n - 1 - i] = t;
    }
    gk_free(&al, deg), gk_free(&al, lvl), gk_free(&al, queue);
    return GK_OK;
}

GKDEF void gk_solver_init(gk_solver *s) {
    memset(s, 0, sizeof *s);
    s->cookie = GK_SOLVER_COOKIE;
}

GKDEF void gk_solver_free(gk_solver *s) {
    if (s->cookie == GK_SOLVER_COOKIE)
        gk_free(&s->alloc, s->perm), gk_free(&s->alloc, s->ipiv), gk_free(&s->alloc, s->ab),
            gk_free(&s->alloc, s->tmp);
    gk_solver_init(s);
}

GKDEF gk_result gk_solver_factor(gk_solver *s, const gk_csr *A, const gk_allocator *alloc, gk_err *err) {
    gk_solver z;
    int n, i, p, k, *inv = NULL, kl = 0, ku = 0;
    double amax = 0.0, tiny;
    gk_result res;
    if (!s || s->cookie != GK_SOLVER_COOKIE)
        return gk_err_set(err, GK_ERR_ARG, "gk_solver not initialised with gk_solver_init()");
    if (!A || !A->rowptr) return gk_err_set(err, GK_ERR_ARG, "no matrix given");
    gk_solver_init(&z);
    if (alloc) z.alloc = *alloc;
    n = A->n;
    if (n < 1) return gk_err_set(err, GK_ERR_ARG, "empty system");
    for (p = 0; p < A->nnz; ++p) {
        if (!(fabs(A->val[p]) < HUGE_VAL))
            return gk_err_set(err, GK_ERR_NAN, "matrix entry %d is not finite", p);
        if (fabs(A->val[p]) > amax) amax = fabs(A->val[p]);
    }
    if (!(amax > 0.0)) return gk_err_set(err, GK_ERR_SINGULAR, "matrix is zero");
    z.n = n;
    z.perm = (int *)gk_alloc(&z.alloc, (size_t)n * sizeof(int));
    z.ipiv = (int *)gk_alloc(&z.alloc, (size_t)n * sizeof(int));
    z.tmp = (double *)gk_alloc(&z.alloc, (size_t)n * sizeof(double));
    inv = (int *)gk_alloc(&z.alloc, (size_t)n * sizeof(int));
    if (!z.perm || !z.ipiv || !z.tmp || !inv) {
        res = gk_err_set(err, GK_ERR_ALLOC, "solver arrays for %d unknowns", n);
        goto fail;
    }
    res = gk_rcm_order(A, z.perm, &z.alloc, err);
    if (res) goto fail;
    for (i = 0; i < n; ++i) inv[z.perm[i]] = i;
    for (i = 0; i < n; ++i)
        for (p = A->rowptr[i]; p < A->rowptr[i + 1]; ++p) {
            int d = inv[A->col[p]] - inv[i];
            if (A->val[p] == 0.0) continue;
            if (-d > kl) kl = -d;
            if (d > ku) ku = d;
        }
    z.kl = kl, z.ku = ku, z.w = 2 * kl + ku + 1;
    z.ab = (double *)gk_alloc(&z.alloc, (size_t)n * z.w * sizeof(double));
    if (!z.ab) {
        res = gk_err_set(err, GK_ERR_ALLOC, "band of %d x %d for the direct solver", n, z.w);
        goto fail;
    }
    memset(z.ab, 0, (size_t)n * z.w * sizeof(double));
#define GK__AB(r, c) z.ab[(size_t)(r)*z.w + (c) - (r) + kl]
    for (i = 0; i < n; ++i)
        for (p = A->rowptr[i]; p < A->rowptr[i + 1]; ++p)
            if (A->val[p] != 0.0) GK__AB(inv[i], inv[A->col[p]]) = A->val[p];
    tiny = 1e-12 * amax;
    for (k = 0; k < n; ++k) { /* LU with partial pivoting within the band (LAPACK dgbtf2) */
        int pr = k, last = k + kl < n - 1 ? k + kl : n - 1, jend = k + ku + kl < n - 1 ? k + ku + kl : n - 1,
            j;
        double piv;
        for (i = k + 1; i <= last; ++i)
            if (fabs(GK__AB(i, k)) > fabs(GK__AB(pr, k))) pr = i;
        z.ipiv[k] = pr;
        if (!(fabs(GK__AB(pr, k)) > tiny)) {
            res = gk_err_set(err, GK_ERR_SINGULAR,
                             "singular system: pivot %g at unknown %d (dof %d) below 1e-12 x max|A| = %g; "
                             "is every rigid-body mode constrained?",
                             GK__AB(pr, k), k, z.perm[k], amax);
            goto fail;
        }
        if (pr != k)
            for (j = k; j <= jend; ++j) {
                double t = GK__AB(k, j);
                GK__AB(k, j) = GK__AB(pr, j), GK__AB(pr, j) = t;
            }
        piv = GK__AB(k, k);
        for (i = k + 1; i <= last; ++i) {
            double l = GK__AB(i, k) / piv;
            GK__AB(i, k) = l;
            if (l != 0.0)
                for (j = k + 1; j <= jend; ++j) GK__AB(i, j) -= l * GK__AB(k, j);
        }
    }
#undef GK__AB
    gk_free(&z.alloc, inv);
    gk_solver_free(s);
    *s = z;
    return GK_OK;
fail:
    gk_free(&z.alloc, inv);
    gk_solver_free(&z);
    return res;
}

GKDEF gk_result gk_solver_solve(gk_solver *s, const double *b, double *x) {
    int n, kl, k, i, j;
    double *y;
    if (s->cookie != GK_SOLVER_COOKIE || !s->ab)
        return gk_err_set(&s->err, GK_ERR_STATE, "solve before a successful gk_solver_factor");
    n = s->n, kl = s->kl, y = s->tmp;
    for (i = 0; i < n; ++i)
        if (!(fabs(b[i]) < HUGE_VAL))
            return gk_err_set(&s->err, GK_ERR_NAN, "right-hand side %d is %g", i, b[i]);
#define GK__AB(r, c) s->ab[(size_t)(r)*s->w + (c) - (r) + kl]
    for (i = 0; i < n; ++i) y[i] = b[s->perm[i]];
    for (k = 0; k < n; ++k) {
        int last = k + kl < n - 1 ? k + kl : n - 1;
        if (s->ipiv[k] != k) {
            double t = y[k];
            y[k] = y[s->ipiv[k]], y[s->ipiv[k]] = t;
        }
        for (i = k + 1; i <= last; ++i) y[i] -= GK__AB(i, k) * y[k];
    }
    for (k = n - 1; k >= 0; --k) {
        int jend = k + s->ku + kl < n - 1 ? k + s->ku + kl : n - 1;
        double acc = y[k];
        for (j = k + 1; j <= jend; ++j) acc -= GK__AB(k, j) * y[j];
        y[k] = acc / GK__AB(k, k);
    }
#undef GK__AB
    for (i = 0; i < n; ++i)
        if (!(fabs(y[i]) < HUGE_VAL))
            return gk_err_set(&s->err, GK_ERR_DIVERGED,
                              "solution entry %d is %g (overflow: a near-singular system?)", s->perm[i],
                              y[i]);
    for (i = 0; i < n; ++i) x[s->perm[i]] = y[i];
    return GK_OK;
}

GKDEF gk_result gk_pcg(const gk_csr *A, const double *b, double *x_out, double rtol, int maxit, int *iters,
                       const gk_allocator *alloc, gk_err *err) {
    double *x = x_out;
    int n = A->n, i, it, p;
    double *r, *z, *d, *q, *Mi, *xw, rz, bn = 0.0;
    gk_allocator al;
    memset(&al, 0, sizeof al);
    if (alloc) al = *alloc;
    if (!(rtol > 0.0 && rtol < 1.0) || maxit < 1)
        return gk_err_set(err, GK_ERR_ARG, "PCG tolerance %g (must be in (0, 1)), max iterations %d (>= 1)",
                          rtol, maxit);
    for (i = 0; i < n; ++i)
        if (!(fabs(b[i]) < HUGE_VAL) || !(fabs(x[i]) < HUGE_VAL))
            return gk_err_set(err, GK_ERR_NAN, "PCG: right-hand side or start value %d is not finite", i);
    r = (double *)gk_alloc(&al, 6 * (size_t)n * sizeof(double));
    if (!r) return gk_err_set(err, GK_ERR_ALLOC, "PCG work arrays");
    z = r + n, d = z + n, q = d + n, Mi = q + n, xw = Mi + n;
    memcpy(xw, x, (size_t)n * sizeof(double)); /* x changes only on success or GK_ERR_NOCONVERGE */
    x = xw;
    for (i = 0; i < n; ++i) {
        double dg = 0.0;
        for (p = A->rowptr[i]; p < A->rowptr[i + 1]; ++p)
            if (A->col[p] == i) dg = A->val[p];
        if (!(dg > 0.0)) {
            gk_free(&al, r);
            return gk_err_set(err, GK_ERR_SINGULAR, "PCG needs a positive diagonal; row %d has %g", i, dg);
        }
        Mi[i] = 1.0 / dg;
        bn += b[i] * b[i];
    }
    bn = sqrt(bn);
    gk_csr_matvec(A, x, q);
    rz = 0.0;
    for (i = 0; i < n; ++i) r[i] = b[i] - q[i], z[i] = Mi[i] * r[i], d[i] = z[i], rz += r[i] * z[i];
    for (it = 0; it < maxit; ++it) {
        double rn = 0.0, dq = 0.0, alpha, rz1 = 0.0, beta;
        for (i = 0; i < n; ++i) rn += r[i] * r[i];
        if (sqrt(rn) <= rtol * bn) break;
        gk_csr_matvec(A, d, q);
        for (i = 0; i < n; ++i) dq += d[i] * q[i];
        if (!(dq > 0.0)) {
            gk_free(&al, r);
            return gk_err_set(err, GK_ERR_SINGULAR, "PCG: matrix not positive definite (d.Ad = %g)", dq);
        }
        alpha = rz / dq;
        for (i = 0; i < n; ++i)
            x[i] += alpha * d[i], r[i] -= alpha * q[i], z[i] = Mi[i] * r[i], rz1 += r[i] * z[i];
        beta = rz1 / rz, rz = rz1;
        for (i = 0; i < n; ++i) d[i] = z[i] + beta * d[i];
    }
    if (iters) *iters = it;
    for (i = 0; i < n; ++i)
        if (!(fabs(x[i]) < HUGE_VAL)) {
            gk_free(&al, r);
            return gk_err_set(err, GK_ERR_DIVERGED, "PCG iterate %d is not finite", i);
        }
    memcpy(x_out, x, (size_t)n * sizeof(double));
    gk_free(&al, r);
    if (it == maxit)
        return gk_err_set(err, GK_ERR_NOCONVERGE, "PCG did not reach %g in %d iterations", rtol, maxit);
    return GK_OK;
}

#endif /* GK_SPARSE implementation */

/*
MIT License. Copyright (c) 2026 the grainkit authors.
Permission is hereby granted, free of charge, to any person obtaining a copy of
this software and associated documentation files (the "Software"), to deal in
the Software without restriction, including without limitation the rights to
use, copy, modify, merge, publish, distribute, sublicense, and/or sell copies of
the Software, and to permit persons to whom the Software is furnished to do so,
subject to the following conditions: The above copyright notice and this
permission notice shall be included in all copies or substantial portions of the
Software. THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND,
EXPRESS OR IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF
MERCHANTABILITY, FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO
EVENT SHALL THE AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR
OTHER LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING
FROM, OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN
THE SOFTWARE.
*/
