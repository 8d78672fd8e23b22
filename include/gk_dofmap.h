/* gk_dofmap.h - tied dofs: periodic boundaries, rigid platens. (grainkit v0.1)
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_DOFMAP_IMPLEMENTATION) in one file.
 * gk_dofmap_periodic pairs the nodes of a gk_mesh: the implementation includes
 * and implements gk_mesh.h, gk_fem.h and gk_sparse.h too.
 *
 * TIED DOFS (periodic boundaries, rigid platens)
 *   A gk_dofmap writes every dof as u = T ur + g: a dof is either independent
 *   or tied to another one, u_s = u_m + g_s (g: a prescribed jump, e.g. the
 *   macro gradient times the period; 0 for a platen). T has a single 1 per
 *   row, so the condensed system T^T K T ur = T^T (f - K g) is an exact
 *   elimination of the slaves: rows and columns of a slave are added to its
 *   master's. Chains (a slave of a slave, the corners of a doubly periodic
 *   mesh) are followed to the independent dof and their jumps added.
 *   gk_dofmap_ties          a map from (slave, master, jump) triples (the
 *                           map is overwritten: free an old one first); the
 *                           same tie twice counts once; a dof tied to two
 *                           masters, a cycle, an index out of range ->
 *                           GK_ERR_ARG naming the dof (nothing is changed)
 *   gk_dofmap_periodic      every component of every node of the hi faces of
 *                           the mesh's bounding box tied to its partner on the
 *                           lo face, along the axes in a bit mask (1 x, 2 y,
 *                           4 z), jump g = G (x_s - x_m) (G NULL: no jump).
 *                           A node on several hi faces is tied along its
 *                           first axis only; the chain does the rest. Node
 *                           ids, not coordinates, are kept: build the map once
 *                           and keep it through gk_mesh_update.
 *   gk_dofmap_csr           the sparsity of T^T A T (once)
 *   gk_dofmap_condense      its values Ar = T^T A T (deterministic order)
 *   gk_dofmap_restrict      fr = T^T f, or T^T (f - A g) with A
 *   gk_dofmap_expand        u = T ur (+ g)
 *   gk_dofmap_dirichlet     prescribed dofs -> prescribed reduced dofs for
 *                           gk_fem_dirichlet on Ar: value - g; the same value
 *                           given to tied dofs is merged, different values
 *                           -> GK_ERR_ARG naming both dofs
 *   Typical Newton step: gk_fem_assemble(K) ; gk_dofmap_condense(K -> Kr) ;
 *   gk_dofmap_restrict(R -> Rr) ; gk_dofmap_dirichlet ; gk_fem_dirichlet(Kr) ;
 *   gk_solver_factor/solve(Kr) ; gk_dofmap_expand(dur -> du, no jump).
 *   Used by femdem_biaxial --test cyclic-strain|cyclic-stress (periodic
 *   simple shear); tests/test_fem.c has periodic patch tests.
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_DOFMAP_H
#define GK_DOFMAP_H

#include "gk_mesh.h"

typedef struct gk_dofmap {
    int n, nred; /* dofs of the full and of the reduced system            */
    int *red;    /* n: reduced index of every dof                        */
    int *rep;    /* nred: the independent dof behind every reduced one   */
    double *off; /* n: jump g (u = ur[red] + g), NULL when every g is 0   */
    gk_allocator alloc;
} gk_dofmap;

#ifdef __cplusplus
extern "C" {
#endif

GKDEF gk_result gk_dofmap_ties(gk_dofmap *dm, int n, int ntie, const int *slave, const int *master,
                               const double *jump, const gk_allocator *alloc, gk_err *err);
GKDEF gk_result gk_dofmap_periodic(gk_dofmap *dm, const gk_mesh *m, unsigned axes, const double G[9],
                                   double tol, const gk_allocator *alloc, gk_err *err);
GKDEF void gk_dofmap_free(gk_dofmap *dm);
GKDEF gk_result gk_dofmap_csr(const gk_dofmap *dm, const gk_csr *A, gk_csr *Ar, const gk_allocator *alloc,
                              gk_err *err);
GKDEF gk_result gk_dofmap_condense(const gk_dofmap *dm, const gk_csr *A, gk_csr *Ar, gk_err *err);
GKDEF gk_result gk_dofmap_restrict(const gk_dofmap *dm, const gk_csr *A, const double *f, double *fr,
                                   gk_err *err);
GKDEF void gk_dofmap_expand(const gk_dofmap *dm, const double *ur, int with_jump, double *u);
GKDEF gk_result gk_dofmap_dirichlet(const gk_dofmap *dm, int nfix, const int *dofs, const double *vals,
                                    int *rdofs, double *rvals, int *nrfix, gk_err *err);

#ifdef __cplusplus
}
#endif

#define GK__DOFMAP_DECLS
#endif /* GK_DOFMAP_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_DOFMAP_IMPLEMENTATION) || defined(GK_FEM_IMPLEMENTATION)) && \
    !defined(GK_DOFMAP_IMPL_ONCE)
#ifndef GK_FEM_H
#include "gk_fem.h"
#endif
#if defined(GK__DOFMAP_DECLS) && defined(GK__FEM_DECLS) && defined(GK_FEM_IMPL_ONCE) && \
    !defined(GK_DOFMAP_IMPL_ONCE)
#define GK_DOFMAP_IMPL_ONCE

#include <stdlib.h>
#include <string.h>

/* -------------------------------------------------------------- tied dofs */
GKDEF void gk_dofmap_free(gk_dofmap *dm) {
    gk_free(&dm->alloc, dm->red), gk_free(&dm->alloc, dm->rep), gk_free(&dm->alloc, dm->off);
    memset(dm, 0, sizeof *dm);
}

GKDEF gk_result gk_dofmap_ties(gk_dofmap *dm, int n, int ntie, const int *slave, const int *master,
                               const double *jump, const gk_allocator *alloc, gk_err *err) {
    gk_dofmap z;
    int i, j, k, depth, *par = NULL, *state = NULL, *stack = NULL, *root = NULL;
    double *gpar = NULL;
    gk_result res = GK_OK;
    memset(&z, 0, sizeof z);
    if (alloc) z.alloc = *alloc;
    if (n < 1 || ntie < 0 || ntie > n || (ntie > 0 && (!slave || !master)))
        return gk_err_set(err, GK_ERR_ARG, "%d ties among %d dofs", ntie, n);
    par = (int *)gk_alloc(&z.alloc, (size_t)n * sizeof(int));
    state = (int *)gk_alloc(&z.alloc, (size_t)n * sizeof(int));
    stack = (int *)gk_alloc(&z.alloc, (size_t)n * sizeof(int));
    root = (int *)gk_alloc(&z.alloc, (size_t)n * sizeof(int));
    gpar = (double *)gk_alloc(&z.alloc, (size_t)n * sizeof(double));
    z.red = (int *)gk_alloc(&z.alloc, (size_t)n * sizeof(int));
    if (jump) z.off = (double *)gk_alloc(&z.alloc, (size_t)n * sizeof(double));
    if (!par || !state || !stack || !root || !gpar || !z.red || (jump && !z.off)) {
        res = gk_err_set(err, GK_ERR_ALLOC, "dof map of %d dofs", n);
        goto fail;
    }
    for (i = 0; i < n; ++i) par[i] = -1, state[i] = 0, gpar[i] = 0.0;
    for (k = 0; k < ntie; ++k) {
        int s = slave[k], m = master[k];
        if (s < 0 || s >= n || m < 0 || m >= n) {
            res = gk_err_set(err, GK_ERR_ARG, "tie %d: dof %d to dof %d, outside [0, %d)", k, s, m, n);
            goto fail;
        }
        if (s == m) {
            res = gk_err_set(err, GK_ERR_ARG, "tie %d: dof %d tied to itself", k, s);
            goto fail;
        }
        if (jump && !(fabs(jump[k]) < HUGE_VAL)) {
            res = gk_err_set(err, GK_ERR_NAN, "tie %d: the jump of dof %d is not finite", k, s);
            goto fail;
        }
        if (par[s] == m && gpar[s] == (jump ? jump[k] : 0.0)) continue; /* the same tie again */
        if (par[s] >= 0) {
            res = gk_err_set(err, GK_ERR_ARG, "dof %d is tied twice (to dof %d and to dof %d)", s, par[s], m);
            goto fail;
        }
        par[s] = m, gpar[s] = jump ? jump[k] : 0.0;
    }
    /* follow every chain to its independent dof; the jumps add up from the root */
    for (i = 0; i < n; ++i) {
        if (state[i] == 2) continue;
        depth = 0, j = i;
        while (state[j] == 0 && par[j] >= 0) state[j] = 1, stack[depth++] = j, j = par[j];
        if (state[j] == 1) {
            res = gk_err_set(err, GK_ERR_ARG, "the ties form a cycle through dof %d", j);
            goto fail;
        }
        if (state[j] == 0) state[j] = 2, root[j] = j, gpar[j] = 0.0; /* an independent dof */
        while (depth > 0) {
            k = stack[--depth];
            root[k] = root[par[k]], gpar[k] += gpar[par[k]], state[k] = 2;
        }
    }
    /* reduced numbering: independent dofs in increasing order */
    for (i = 0; i < n; ++i)
        if (par[i] < 0) state[i] = z.nred++;
    z.rep = (int *)gk_alloc(&z.alloc, (size_t)z.nred * sizeof(int));
    if (!z.rep) {
        res = gk_err_set(err, GK_ERR_ALLOC, "dof map of %d dofs", n);
        goto fail;
    }
    for (i = 0; i < n; ++i) {
        z.red[i] = state[root[i]];
        if (par[i] < 0) z.rep[z.red[i]] = i;
        if (z.off) z.off[i] = gpar[i];
    }
    z.n = n;
    gk_free(&z.alloc, par), gk_free(&z.alloc, state), gk_free(&z.alloc, stack), gk_free(&z.alloc, root),
        gk_free(&z.alloc, gpar);
    *dm = z;
    return GK_OK;
fail:
    gk_free(&z.alloc, par), gk_free(&z.alloc, state), gk_free(&z.alloc, stack), gk_free(&z.alloc, root),
        gk_free(&z.alloc, gpar);
    gk_dofmap_free(&z);
    return res;
}

GKDEF gk_result gk_dofmap_periodic(gk_dofmap *dm, const gk_mesh *m, unsigned axes, const double G[9],
                                   double tol, const gk_allocator *alloc, gk_err *err) {
    int dim = m->dim, nn = m->nnode, ax, a, i, j, nt = 0, np, *ps, *pm, *slave, *master, *tied;
    double lo[3], hi[3], *jump = NULL;
    gk_allocator al;
    gk_result res = GK_OK;
    memset(&al, 0, sizeof al);
    if (alloc) al = *alloc;
    if (axes >> dim) return gk_err_set(err, GK_ERR_ARG, "periodic axes 0x%x of a %dD mesh", axes, dim);
    if (G)
        for (i = 0; i < 9; ++i)
            if (!(fabs(G[i]) < HUGE_VAL)) return gk_err_set(err, GK_ERR_NAN, "macro gradient is not finite");
    ps = (int *)gk_alloc(&al, (size_t)nn * sizeof(int) + 1);
    pm = (int *)gk_alloc(&al, (size_t)nn * sizeof(int) + 1);
    tied = (int *)gk_alloc(&al, (size_t)nn * sizeof(int) + 1);
    slave = (int *)gk_alloc(&al, (size_t)nn * dim * sizeof(int) + 1);
    master = (int *)gk_alloc(&al, (size_t)nn * dim * sizeof(int) + 1);
    if (G) jump = (double *)gk_alloc(&al, (size_t)nn * dim * sizeof(double) + 1);
    if (!ps || !pm || !tied || !slave || !master || (G && !jump)) {
        res = gk_err_set(err, GK_ERR_ALLOC, "periodic ties of %d nodes", nn);
        goto out;
    }
    for (i = 0; i < dim; ++i) lo[i] = HUGE_VAL, hi[i] = -HUGE_VAL;
    for (a = 0; a < nn; ++a) {
        tied[a] = 0;
        for (i = 0; i < dim; ++i) {
            double v = m->x[(size_t)a * dim + i];
            if (v < lo[i]) lo[i] = v;
            if (v > hi[i]) hi[i] = v;
        }
    }
    for (ax = 0; ax < dim; ++ax) {
        int k;
        if (!(axes & (1u << ax))) continue;
        res = gk_mesh_periodic_pairs(m, ax, lo[ax], hi[ax], tol, ps, pm, &np, err);
        if (res) goto out;
        for (k = 0; k < np; ++k) {
            const double *xs = m->x + (size_t)ps[k] * dim, *xm = m->x + (size_t)pm[k] * dim;
            if (tied[ps[k]]) continue; /* an edge/corner node already tied along an earlier axis */
            tied[ps[k]] = 1;
            for (i = 0; i < dim; ++i, ++nt) {
                slave[nt] = dim * ps[k] + i, master[nt] = dim * pm[k] + i;
                if (jump) {
                    double g = 0.0;
                    for (j = 0; j < dim; ++j) g += G[3 * i + j] * (xs[j] - xm[j]);
                    jump[nt] = g;
                }
            }
        }
    }
    res = gk_dofmap_ties(dm, dim * nn, nt, slave, master, jump, alloc, err);
out:
    gk_free(&al, ps), gk_free(&al, pm), gk_free(&al, tied), gk_free(&al, slave), gk_free(&al, master),
        gk_free(&al, jump);
    return res;
}

static int gk__cmp_int(const void *a, const void *b) {
    int x = *(const int *)a, y = *(const int *)b;
    return x < y ? -1 : x > y;
}

GKDEF gk_result gk_dofmap_csr(const gk_dofmap *dm, const gk_csr *A, gk_csr *Ar, const gk_allocator *alloc,
                              gk_err *err) {
    gk_csr z;
    int n = dm->n, nr = dm->nred, i, p, r, k, *start = NULL, *rows = NULL, *mark = NULL;
    memset(&z, 0, sizeof z);
    if (alloc) z.alloc = *alloc;
    if (!dm->red || A->n != n)
        return gk_err_set(err, GK_ERR_ARG, "matrix of %d rows, dof map of %d dofs", A->n, n);
    start = (int *)gk_alloc(&z.alloc, ((size_t)nr + 1) * sizeof(int));
    rows = (int *)gk_alloc(&z.alloc, (size_t)n * sizeof(int));
    mark = (int *)gk_alloc(&z.alloc, (size_t)nr * sizeof(int));
    z.rowptr = (int *)gk_alloc(&z.alloc, ((size_t)nr + 1) * sizeof(int));
    if (!start || !rows || !mark || !z.rowptr) goto oom;
    /* the full rows of every reduced row (counting sort, in increasing order) */
    for (r = 0; r <= nr; ++r) start[r] = 0;
    for (i = 0; i < n; ++i) ++start[dm->red[i] + 1];
    for (r = 0; r < nr; ++r) start[r + 1] += start[r], mark[r] = -1;
    for (i = 0; i < n; ++i) rows[start[dm->red[i]]++] = i;
    for (r = nr; r > 0; --r) start[r] = start[r - 1];
    start[0] = 0;
    z.rowptr[0] = 0;
    for (r = 0; r < nr; ++r) { /* count the distinct reduced columns */
        int cnt = 0;
        for (k = start[r]; k < start[r + 1]; ++k)
            for (p = A->rowptr[rows[k]]; p < A->rowptr[rows[k] + 1]; ++p) {
                int c = dm->red[A->col[p]];
                if (mark[c] != r) mark[c] = r, ++cnt;
            }
        z.rowptr[r + 1] = z.rowptr[r] + cnt;
    }
    z.n = nr, z.nnz = z.rowptr[nr];
    z.col = (int *)gk_alloc(&z.alloc, (size_t)z.nnz * sizeof(int) + 1);
    z.val = (double *)gk_alloc(&z.alloc, (size_t)z.nnz * sizeof(double) + 1);
    if (!z.col || !z.val) goto oom;
    for (r = 0; r < nr; ++r) mark[r] = -1;
    for (r = 0; r < nr; ++r) {
        int q = z.rowptr[r];
        for (k = start[r]; k < start[r + 1]; ++k)
            for (p = A->rowptr[rows[k]]; p < A->rowptr[rows[k] + 1]; ++p) {
                int c = dm->red[A->col[p]];
                if (mark[c] != r) mark[c] = r, z.col[q++] = c;
            }
        qsort(z.col + z.rowptr[r], (size_t)(q - z.rowptr[r]), sizeof(int), gk__cmp_int);
    }
    memset(z.val, 0, (size_t)z.nnz * sizeof(double));
    gk_free(&z.alloc, start), gk_free(&z.alloc, rows), gk_free(&z.alloc, mark);
    *Ar = z;
    return GK_OK;
oom:
    gk_free(&z.alloc, start), gk_free(&z.alloc, rows), gk_free(&z.alloc, mark);
    gk_free(&z.alloc, z.rowptr), gk_free(&z.alloc, z.col), gk_free(&z.alloc, z.val);
    return gk_err_set(err, GK_ERR_ALLOC, "condensed matrix of %d rows", nr);
}

GKDEF gk_result gk_dofmap_condense(const gk_dofmap *dm, const gk_csr *A, gk_csr *Ar, gk_err *err) {
    int i, p;
    if (!dm->red || A->n != dm->n || Ar->n != dm->nred)
        return gk_err_set(err, GK_ERR_ARG, "matrices of %d and %d rows, dof map %d -> %d", A->n, Ar->n, dm->n,
                          dm->nred);
    for (i = 0; i < A->n; ++i) /* first check the pattern: bad input changes nothing */
        for (p = A->rowptr[i]; p < A->rowptr[i + 1]; ++p)
            if (!gk_csr_at(Ar, dm->red[i], dm->red[A->col[p]]))
                return gk_err_set(err, GK_ERR_ARG,
                                  "reduced matrix lacks entry (%d, %d): build its pattern with gk_dofmap_csr",
                                  dm->red[i], dm->red[A->col[p]]);
    gk_csr_zero(Ar);
    for (i = 0; i < A->n; ++i)
        for (p = A->rowptr[i]; p < A->rowptr[i + 1]; ++p)
            *gk_csr_at(Ar, dm->red[i], dm->red[A->col[p]]) += A->val[p];
    return GK_OK;
}

GKDEF gk_result gk_dofmap_restrict(const gk_dofmap *dm, const gk_csr *A, const double *f, double *fr,
                                   gk_err *err) {
    int i, p;
    if (!dm->red || (A && A->n != dm->n))
        return gk_err_set(err, GK_ERR_ARG, "matrix of %d rows, dof map of %d dofs", A ? A->n : 0, dm->n);
    for (i = 0; i < dm->nred; ++i) fr[i] = 0.0;
    for (i = 0; i < dm->n; ++i) {
        double v = f[i];
        if (A && dm->off) {
            double s = 0.0;
            for (p = A->rowptr[i]; p < A->rowptr[i + 1]; ++p) s += A->val[p] * dm->off[A->col[p]];
            v -= s;
        }
        fr[dm->red[i]] += v;
    }
    return GK_OK;
}

GKDEF void gk_dofmap_expand(const gk_dofmap *dm, const double *ur, int with_jump, double *u) {
    int i;
    for (i = 0; i < dm->n; ++i) u[i] = ur[dm->red[i]] + (with_jump && dm->off ? dm->off[i] : 0.0);
}

GKDEF gk_result gk_dofmap_dirichlet(const gk_dofmap *dm, int nfix, const int *dofs, const double *vals,
                                    int *rdofs, double *rvals, int *nrfix, gk_err *err) {
    double *v, scale = 0.0;
    int *who, k, pass, nr = 0;
    gk_result res = GK_OK;
    if (!dm->red || nfix < 0) return gk_err_set(err, GK_ERR_ARG, "%d prescribed dofs", nfix);
    for (k = 0; k < nfix; ++k) {
        if (dofs[k] < 0 || dofs[k] >= dm->n)
            return gk_err_set(err, GK_ERR_ARG, "prescribed dof %d out of range", dofs[k]);
        if (!(fabs(vals[k]) < HUGE_VAL))
            return gk_err_set(err, GK_ERR_NAN, "prescribed value of dof %d", dofs[k]);
        if (fabs(vals[k]) > scale) scale = fabs(vals[k]);
        if (dm->off && fabs(dm->off[dofs[k]]) > scale) scale = fabs(dm->off[dofs[k]]);
    }
    v = (double *)gk_alloc(&dm->alloc, (size_t)dm->nred * sizeof(double) + 1);
    who = (int *)gk_alloc(&dm->alloc, (size_t)dm->nred * sizeof(int) + 1);
    if (!v || !who) {
        gk_free(&dm->alloc, v), gk_free(&dm->alloc, who);
        return gk_err_set(err, GK_ERR_ALLOC, "Dirichlet map of %d dofs", dm->nred);
    }
    /* pass 0: check that tied dofs get the same value; pass 1: write */
    for (pass = 0; pass < 2 && !res; ++pass) {
        for (k = 0; k < dm->nred; ++k) who[k] = -1;
        for (k = 0; k < nfix; ++k) {
            int r = dm->red[dofs[k]];
            double x = vals[k] - (dm->off ? dm->off[dofs[k]] : 0.0);
            if (who[r] < 0) {
                who[r] = dofs[k], v[r] = x;
                if (pass) rdofs[nr] = r, rvals[nr++] = x;
            } else if (!(fabs(x - v[r]) <= 1e-9 * (fabs(x) + fabs(v[r])) + 1e-12 * scale)) {
                res = gk_err_set(
                    err, GK_ERR_ARG,
                    "dofs %d and %d are tied but prescribed inconsistently (%g and %g after the jump)",
                    who[r], dofs[k], v[r], x);
                break;
            }
        }
    }
    if (!res) *nrfix = nr;
    gk_free(&dm->alloc, v), gk_free(&dm->alloc, who);
    return res;
}

#endif
#endif /* GK_DOFMAP implementation */
