/* gk_fem.h - finite elements for the macro scale of FEMxDEM.   (grainkit v0.1)
 *
 * Small-strain / updated-Lagrangian continuum elements whose material is a
 * tangent D and a stress sigma handed in per Gauss point (e.g. from a DEM RVE
 * through gk_homog.h), sparse assembly and boundary conditions. Guo & Zhao
 * (2014) eqs 1-4, 21. This header includes the ones it builds on:
 *   gk_mesh.h      the gk_mesh (element types, structured meshes, Gmsh reader,
 *                  nodes/faces on planes, periodic node pairs, CSR pattern)
 *   gk_dofmap.h    tied dofs: periodic boundaries, rigid platens
 *   gk_nonlocal.h  nonlocal averaging over points within a radius
 *   gk_sparse.h    sparse matrices and linear solvers (through gk_mesh.h)
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_FEM_IMPLEMENTATION, which also
 * implements the four headers above) in one file.
 *
 * ELEMENTS (node order = Gmsh = VTK)
 *   GK_Q4    4-node bilinear quad, plane strain. Corners counter-clockwise
 *            from (-1,-1). Gauss 2x2 (default) or 1, 3.
 *   GK_Q8    8-node serendipity quad: corners as Q4, then mid-side nodes of
 *            edges 0-1, 1-2, 2-3, 3-0. Gauss 2x2 (reduced; the Guo & Zhao 2014
 *            authors' escript setting: 4 RVEs per element) or 3x3 (full).
 *   GK_HEX8  8-node trilinear hexahedron: the Q4 corners at zeta = -1, then at
 *            zeta = +1. Gauss 2x2x2, or 1 point with gk_fem_hex8_hourglass
 *            (Flanagan-Belytschko stiffness-form hourglass control) for
 *            explicit runs.
 *
 * WHAT IS HERE
 *   gk_quad_rule            tensor Gauss-Legendre rule (1, 2 or 3 per direction)
 *   gk_fem_shape            N and dN/dxi of an element at a reference point
 *   gk_fem_jacobian         dN/dx and det J at a point of a mesh element;
 *                           det J <= 0 -> GK_ERR_MESH (inverted/degenerate)
 *   gk_fem_grad             H_ij = du_i/dx_j at a point (Guo & Zhao 2014 eq 10 input)
 *   gk_fem_elem_stiffness   K_e = int B^T D B dV with D a full 4th-order
 *                           tangent D_ijkl (NOT assumed symmetric), layout
 *                           D[((i*dim+j)*dim+k)*dim+l] as gk_homog_tangent:
 *                           K_(a i)(b k) = int dN_a/dx_j D_ijkl dN_b/dx_l [eq 3]
 *   gk_fem_elem_force       f_(a i) = int sigma_ij dN_a/dx_j dV        [eq 4]
 *   gk_fem_assemble         all elements into a CSR matrix and/or a force
 *                           vector, in element order (deterministic). Every
 *                           tangent, stress, element (det J > 0 at each
 *                           Gauss point) and pattern entry is checked before
 *                           K or fint is touched: an error changes neither.
 *   (Element functions refuse an element index outside the mesh, GK_ERR_ARG,
 *   a node id outside it, GK_ERR_MESH, and a non-finite tangent or stress,
 *   GK_ERR_NAN.)
 *   gk_fem_elastic_tangent  isotropic D_ijkl = lambda d_ij d_kl + mu (d_ik d_jl
 *                           + d_il d_jk); 2D = plane strain
 *   gk_fem_lumped_mass      HRZ-lumped nodal masses (positive for Q8 too)
 *   gk_fem_face_load        consistent nodal forces of a traction on an edge
 *                           (2 or 3 nodes) or a quad face (4 nodes)
 *   gk_fem_dirichlet        prescribed dofs by symmetric elimination: row and
 *                           column zeroed, the known values moved to the right-
 *                           hand side, the diagonal KEPT (scaling unchanged)
 *                           and rhs = diag * value, so the solve returns the
 *                           prescribed value exactly.
 *
 * MESHES (gk_mesh.h): gk_mesh, gk_mesh_structured, gk_mesh_read_gmsh, ...;
 * gk_csr_from_mesh builds a mesh's pattern for gk_fem_assemble.
 * TIED DOFS (gk_dofmap.h): a typical Newton step with periodic boundaries:
 *   gk_fem_assemble(K) ; gk_dofmap_condense(K -> Kr) ; gk_dofmap_restrict(R
 *   -> Rr) ; gk_dofmap_dirichlet ; gk_fem_dirichlet(Kr) ;
 *   gk_solver_factor/solve(Kr) ; gk_dofmap_expand(dur -> du, no jump).
 * SPARSE MATRICES AND SOLVERS (gk_sparse.h): gk_csr, gk_solver (RCM + banded
 * LU), gk_pcg.
 *
 * Units and signs as gk_base.h: SI, tension-positive stress. 2D is plane
 * strain per unit thickness (forces are N/m).
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_FEM_H
#define GK_FEM_H

#include "gk_mesh.h"
#include "gk_dofmap.h"
#include "gk_nonlocal.h"

#ifdef __cplusplus
extern "C" {
#endif

GKDEF int gk_fem_npe(gk_elem_type t);
GKDEF int gk_fem_dim(gk_elem_type t);
GKDEF gk_result gk_quad_rule(gk_quad *q, gk_elem_type t, int per_dir, gk_err *err);
GKDEF void gk_fem_shape(gk_elem_type t, const double *xi, double *N, double *dN);
GKDEF gk_result gk_fem_jacobian(const gk_mesh *m, int e, const double *xi, double *N, double *dNdx,
                                double *detJ, gk_err *err);
GKDEF void gk_fem_grad(const gk_mesh *m, int e, const double *dNdx, const double *u, double H[9]);
GKDEF gk_result gk_fem_elem_stiffness(const gk_mesh *m, int e, const gk_quad *q, const double *D, double *Ke,
                                      gk_err *err);
GKDEF gk_result gk_fem_elem_force(const gk_mesh *m, int e, const gk_quad *q, const double *sigma, double *fe,
                                  gk_err *err);
GKDEF gk_result gk_fem_assemble(const gk_mesh *m, const gk_quad *q, const double *D, const double *sigma,
                                gk_csr *K, double *fint, gk_err *err);
GKDEF void gk_fem_elastic_tangent(int dim, double E, double nu, double *D);
GKDEF gk_result gk_fem_lumped_mass(const gk_mesh *m, const gk_quad *q, double density, double *mass,
                                   gk_err *err);
GKDEF gk_result gk_fem_face_load(const gk_mesh *m, int nfn, const int *face, const double traction[3],
                                 double *f, gk_err *err);
GKDEF void gk_fem_hex8_hourglass(const double *xe, const double *ue, double k, double *f);

GKDEF gk_result gk_fem_dirichlet(gk_csr *A, double *rhs, int nfix, const int *dofs, const double *vals,
                                 gk_err *err);

#ifdef __cplusplus
}
#endif

#define GK__FEM_DECLS /* every declaration of the FEM headers is seen */

#endif /* GK_FEM_H */

/* ======================================================== IMPLEMENTATION */
/* also for GK_MESH_IMPLEMENTATION and GK_DOFMAP_IMPLEMENTATION: the mesh is
 * checked and interpolated with these elements (gk_mesh_check, gk_mesh_point) */
#if (defined(GK_IMPLEMENTATION) || defined(GK_FEM_IMPLEMENTATION) || defined(GK_MESH_IMPLEMENTATION) || \
     defined(GK_DOFMAP_IMPLEMENTATION)) &&                                                              \
    !defined(GK_FEM_IMPL_ONCE)
#define GK_FEM_IMPL_ONCE

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

GKDEF int gk_fem_npe(gk_elem_type t) { return t == GK_Q4 ? 4 : 8; }
GKDEF int gk_fem_dim(gk_elem_type t) { return t == GK_HEX8 ? 3 : 2; }

GKDEF gk_result gk_quad_rule(gk_quad *q, gk_elem_type t, int per_dir, gk_err *err) {
    static const double g1[1] = {0.0}, w1[1] = {2.0};
    static const double g2[2] = {-0.57735026918962576451, 0.57735026918962576451}, w2[2] = {1.0, 1.0};
    static const double g3[3] = {-0.77459666924148337704, 0.0, 0.77459666924148337704};
    static const double w3[3] = {0.55555555555555555556, 0.88888888888888888889, 0.55555555555555555556};
    const double *g, *w;
    int dim, i, j, k, n = 0;
    if (t != GK_Q4 && t != GK_Q8 && t != GK_HEX8)
        return gk_err_set(err, GK_ERR_ARG, "unknown element type %d", (int)t);
    if (per_dir < 1 || per_dir > 3)
        return gk_err_set(err, GK_ERR_ARG, "Gauss rule with %d points per direction (1, 2 or 3)", per_dir);
    g = per_dir == 1 ? g1 : per_dir == 2 ? g2 : g3;
    w = per_dir == 1 ? w1 : per_dir == 2 ? w2 : w3;
    dim = gk_fem_dim(t);
    for (k = 0; k < (dim == 3 ? per_dir : 1); ++k)
        for (j = 0; j < per_dir; ++j)
            for (i = 0; i < per_dir; ++i) {
                q->xi[n][0] = g[i];
                q->xi[n][1] = g[j];
                q->xi[n][2] = dim == 3 ? g[k] : 0.0;
                q->w[n] = w[i] * w[j] * (dim == 3 ? w[k] : 1.0);
                ++n;
            }
    q->n = n;
    return GK_OK;
}

/* reference corner coordinates (Q4 / Hex8 corners, Q8 all nodes) */
static const double gk__q8_xi[8][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}, {0, -1}, {1, 0}, {0, 1}, {-1, 0}};
static const double gk__h8_xi[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                       {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};

GKDEF void gk_fem_shape(gk_elem_type t, const double *xi, double *N, double *dN) {
    int a;
    double x = xi[0], y = xi[1];
    if (t == GK_Q4) {
        for (a = 0; a < 4; ++a) {
            double xa = gk__q8_xi[a][0], ya = gk__q8_xi[a][1];
            N[a] = 0.25 * (1 + x * xa) * (1 + y * ya);
            dN[2 * a] = 0.25 * xa * (1 + y * ya);
            dN[2 * a + 1] = 0.25 * ya * (1 + x * xa);
        }
    } else if (t == GK_Q8) {
        for (a = 0; a < 8; ++a) {
            double xa = gk__q8_xi[a][0], ya = gk__q8_xi[a][1];
            if (a < 4) {
                N[a] = 0.25 * (1 + x * xa) * (1 + y * ya) * (x * xa + y * ya - 1);
                dN[2 * a] = 0.25 * xa * (1 + y * ya) * (2 * x * xa + y * ya);
                dN[2 * a + 1] = 0.25 * ya * (1 + x * xa) * (x * xa + 2 * y * ya);
            } else if (xa == 0.0) {
                N[a] = 0.5 * (1 - x * x) * (1 + y * ya);
                dN[2 * a] = -x * (1 + y * ya);
                dN[2 * a + 1] = 0.5 * ya * (1 - x * x);
            } else {
                N[a] = 0.5 * (1 + x * xa) * (1 - y * y);
                dN[2 * a] = 0.5 * xa * (1 - y * y);
                dN[2 * a + 1] = -y * (1 + x * xa);
            }
        }
    } else {
        double z = xi[2];
        for (a = 0; a < 8; ++a) {
            double xa = gk__h8_xi[a][0], ya = gk__h8_xi[a][1], za = gk__h8_xi[a][2];
            N[a] = 0.125 * (1 + x * xa) * (1 + y * ya) * (1 + z * za);
            dN[3 * a] = 0.125 * xa * (1 + y * ya) * (1 + z * za);
            dN[3 * a + 1] = 0.125 * ya * (1 + x * xa) * (1 + z * za);
            dN[3 * a + 2] = 0.125 * za * (1 + x * xa) * (1 + y * ya);
        }
    }
}

GKDEF gk_result gk_fem_jacobian(const gk_mesh *m, int e, const double *xi, double *N, double *dNdx,
                                double *detJ, gk_err *err) {
    double Nl[GK_FEM_MAX_NPE], dN[3 * GK_FEM_MAX_NPE], J[9], Ji[9], det;
    int a, i, j, dim = m->dim, npe = m->npe;
    const int *c;
    if (e < 0 || e >= m->nelem) return gk_err_set(err, GK_ERR_ARG, "element %d of %d", e, m->nelem);
    c = m->conn + (size_t)e * npe;
    for (a = 0; a < npe; ++a)
        if (c[a] < 0 || c[a] >= m->nnode)
            return gk_err_set(err, GK_ERR_MESH, "element %d: node id %d out of range", e, c[a]);
    gk_fem_shape(m->type, xi, Nl, dN);
    gk_m3_identity(J);
    for (i = 0; i < dim; ++i)
        for (j = 0; j < dim; ++j) {
            double s = 0.0;
            for (a = 0; a < npe; ++a) s += m->x[(size_t)c[a] * dim + i] * dN[dim * a + j];
            J[3 * i + j] = s; /* J_ij = dx_i / dxi_j */
        }
    det = gk_m3_det(J);
    if (!(det > 0.0) || !(det < HUGE_VAL))
        return gk_err_set(err, GK_ERR_MESH, "element %d has det J = %g at (%g, %g%s): inverted or degenerate",
                          e, det, xi[0], xi[1], dim == 3 ? ", ..." : "");
    gk_m3_inverse(J, Ji);
    if (N)
        for (a = 0; a < npe; ++a) N[a] = Nl[a];
    for (a = 0; a < npe; ++a)
        for (j = 0; j < dim; ++j) { /* dN/dx_j = dN/dxi_k dxi_k/dx_j */
            double s = 0.0;
            for (i = 0; i < dim; ++i) s += dN[dim * a + i] * Ji[3 * i + j];
            dNdx[dim * a + j] = s;
        }
    *detJ = det;
    return GK_OK;
}

GKDEF void gk_fem_grad(const gk_mesh *m, int e, const double *dNdx, const double *u, double H[9]) {
    int a, i, j, dim = m->dim;
    const int *c = m->conn + (size_t)e * m->npe;
    gk_m3_zero(H);
    for (a = 0; a < m->npe; ++a)
        for (i = 0; i < dim; ++i)
            for (j = 0; j < dim; ++j) H[3 * i + j] += u[(size_t)c[a] * dim + i] * dNdx[dim * a + j];
}

GKDEF gk_result gk_fem_elem_stiffness(const gk_mesh *m, int e, const gk_quad *q, const double *D, double *Ke,
                                      gk_err *err) {
    int dim = m->dim, npe = m->npe, nd = dim * npe, n4 = dim * dim * dim * dim, g, a, b, i, j, k, l;
    double dNdx[3 * GK_FEM_MAX_NPE], detJ;
    if (e < 0 || e >= m->nelem) return gk_err_set(err, GK_ERR_ARG, "element %d of %d", e, m->nelem);
    for (k = 0; k < q->n * n4; ++k)
        if (!(fabs(D[k]) < HUGE_VAL))
            return gk_err_set(err, GK_ERR_NAN, "tangent of element %d, Gauss point %d is not finite", e,
                              k / n4);
    for (k = 0; k < nd * nd; ++k) Ke[k] = 0.0;
    for (g = 0; g < q->n; ++g) {
        const double *Dg = D + (size_t)g * n4;
        double DB[81 * GK_FEM_MAX_NPE / 3]; /* (i j) x (b k): dim^2 x nd */
        gk_result r = gk_fem_jacobian(m, e, q->xi[g], NULL, dNdx, &detJ, err);
        if (r) return r;
        /* DB_(ij),(bk) = D_ijkl dN_b/dx_l */
        for (i = 0; i < dim; ++i)
            for (j = 0; j < dim; ++j)
                for (b = 0; b < npe; ++b)
                    for (k = 0; k < dim; ++k) {
                        double s = 0.0;
                        for (l = 0; l < dim; ++l)
                            s += Dg[((i * dim + j) * dim + k) * dim + l] * dNdx[dim * b + l];
                        DB[(i * dim + j) * nd + dim * b + k] = s;
                    }
        for (a = 0; a < npe; ++a)
            for (i = 0; i < dim; ++i) {
                double *row = Ke + (size_t)(dim * a + i) * nd;
                for (j = 0; j < dim; ++j) {
                    double c = q->w[g] * detJ * dNdx[dim * a + j];
                    const double *src = DB + (i * dim + j) * nd;
                    for (k = 0; k < nd; ++k) row[k] += c * src[k];
                }
            }
    }
    return GK_OK;
}

GKDEF gk_result gk_fem_elem_force(const gk_mesh *m, int e, const gk_quad *q, const double *sigma, double *fe,
                                  gk_err *err) {
    int dim = m->dim, npe = m->npe, g, a, i, j;
    double dNdx[3 * GK_FEM_MAX_NPE], detJ;
    if (e < 0 || e >= m->nelem) return gk_err_set(err, GK_ERR_ARG, "element %d of %d", e, m->nelem);
    for (a = 0; a < 9 * q->n; ++a)
        if (!(fabs(sigma[a]) < HUGE_VAL))
            return gk_err_set(err, GK_ERR_NAN, "stress of element %d, Gauss point %d is not finite", e,
                              a / 9);
    for (a = 0; a < dim * npe; ++a) fe[a] = 0.0;
    for (g = 0; g < q->n; ++g) {
        const double *s = sigma + 9 * (size_t)g;
        gk_result r = gk_fem_jacobian(m, e, q->xi[g], NULL, dNdx, &detJ, err);
        if (r) return r;
        for (a = 0; a < npe; ++a)
            for (i = 0; i < dim; ++i) {
                double acc = 0.0;
                for (j = 0; j < dim; ++j) acc += s[3 * i + j] * dNdx[dim * a + j];
                fe[dim * a + i] += q->w[g] * detJ * acc;
            }
    }
    return GK_OK;
}

GKDEF gk_result gk_fem_assemble(const gk_mesh *m, const gk_quad *q, const double *D, const double *sigma,
                                gk_csr *K, double *fint, gk_err *err) {
    int dim = m->dim, npe = m->npe, nd = dim * npe, n4 = dim * dim * dim * dim, e, a, b, i, k, g;
    double Ke[24 * 24], fe[24], dNdx[3 * GK_FEM_MAX_NPE], detJ;
    /* every check before K or fint is touched: bad input changes nothing */
    if (K) {
        size_t t, nt = (size_t)m->nelem * q->n * n4;
        if (K->n != dim * m->nnode)
            return gk_err_set(err, GK_ERR_ARG, "matrix has %d rows, mesh %d dofs", K->n, dim * m->nnode);
        if (!D) return gk_err_set(err, GK_ERR_ARG, "a matrix needs tangents D");
        for (t = 0; t < nt; ++t)
            if (!(fabs(D[t]) < HUGE_VAL))
                return gk_err_set(err, GK_ERR_NAN, "tangent of element %d, Gauss point %d is not finite",
                                  (int)(t / ((size_t)q->n * n4)), (int)(t / n4) % q->n);
    }
    if (fint) {
        size_t t, nt = (size_t)m->nelem * q->n * 9;
        if (!sigma) return gk_err_set(err, GK_ERR_ARG, "an internal force needs stresses");
        for (t = 0; t < nt; ++t)
            if (!(fabs(sigma[t]) < HUGE_VAL))
                return gk_err_set(err, GK_ERR_NAN, "stress of element %d, Gauss point %d is not finite",
                                  (int)(t / ((size_t)q->n * 9)), (int)(t / 9) % q->n);
    }
    for (e = 0; e < m->nelem; ++e) {
        const int *c = m->conn + (size_t)e * npe;
        for (g = 0; g < q->n; ++g) {
            gk_result r = gk_fem_jacobian(m, e, q->xi[g], NULL, dNdx, &detJ, err);
            if (r) return r;
        }
        if (K)
            for (a = 0; a < npe * dim; ++a)
                for (b = 0; b < npe * dim; ++b)
                    if (!gk_csr_at(K, dim * c[a / dim] + a % dim, dim * c[b / dim] + b % dim))
                        return gk_err_set(err, GK_ERR_ARG,
                                          "matrix pattern lacks nodes %d-%d of element %d (build it with "
                                          "gk_csr_from_mesh of this mesh)",
                                          c[a / dim], c[b / dim], e);
    }
    if (K) gk_csr_zero(K);
    if (fint)
        for (k = 0; k < dim * m->nnode; ++k) fint[k] = 0.0;
    for (e = 0; e < m->nelem; ++e) {
        const int *c = m->conn + (size_t)e * npe;
        gk_result r;
        if (K) {
            r = gk_fem_elem_stiffness(m, e, q, D + (size_t)e * q->n * n4, Ke, err);
            if (r) return r;
            for (a = 0; a < npe; ++a)
                for (i = 0; i < dim; ++i) {
                    int row = dim * c[a] + i;
                    for (b = 0; b < npe; ++b) /* the pattern came from this mesh: every entry exists */
                        for (k = 0; k < dim; ++k)
                            *gk_csr_at(K, row, dim * c[b] + k) += Ke[(dim * a + i) * nd + dim * b + k];
                }
        }
        if (fint) {
            r = gk_fem_elem_force(m, e, q, sigma + (size_t)e * q->n * 9, fe, err);
            if (r) return r;
            for (a = 0; a < npe; ++a)
                for (i = 0; i < dim; ++i) fint[dim * c[a] + i] += fe[dim * a + i];
        }
    }
    return GK_OK;
}

GKDEF void gk_fem_elastic_tangent(int dim, double E, double nu, double *D) {
    double lam = E * nu / ((1 + nu) * (1 - 2 * nu)), mu = E / (2 * (1 + nu));
    int i, j, k, l;
    for (i = 0; i < dim; ++i)
        for (j = 0; j < dim; ++j)
            for (k = 0; k < dim; ++k)
                for (l = 0; l < dim; ++l)
                    D[((i * dim + j) * dim + k) * dim + l] =
                        lam * (i == j && k == l) + mu * ((i == k && j == l) + (i == l && j == k));
}

GKDEF gk_result gk_fem_lumped_mass(const gk_mesh *m, const gk_quad *q, double density, double *mass,
                                   gk_err *err) {
    int e, g, a, npe = m->npe;
    double N[GK_FEM_MAX_NPE], dNdx[3 * GK_FEM_MAX_NPE], detJ;
    if (!(density > 0.0) || !(density < HUGE_VAL)) return gk_err_set(err, GK_ERR_MASS, "density %g", density);
    for (a = 0; a < m->nnode; ++a) mass[a] = 0.0;
    for (e = 0; e < m->nelem; ++e) {
        double diag[GK_FEM_MAX_NPE] = {0}, total = 0.0, sd = 0.0;
        const int *c = m->conn + (size_t)e * npe;
        for (g = 0; g < q->n; ++g) {
            gk_result r = gk_fem_jacobian(m, e, q->xi[g], N, dNdx, &detJ, err);
            if (r) return r;
            total += q->w[g] * detJ * density;
            for (a = 0; a < npe; ++a) diag[a] += q->w[g] * detJ * density * N[a] * N[a];
        }
        for (a = 0; a < npe; ++a) sd += diag[a];
        for (a = 0; a < npe; ++a) mass[c[a]] += diag[a] * total / sd; /* Hinton-Rock-Zienkiewicz */
    }
    return GK_OK;
}

GKDEF gk_result gk_fem_face_load(const gk_mesh *m, int nfn, const int *face, const double traction[3],
                                 double *f, gk_err *err) {
    static const double g3[3] = {-0.77459666924148337704, 0.0, 0.77459666924148337704};
    static const double w3[3] = {0.55555555555555555556, 0.88888888888888888889, 0.55555555555555555556};
    int dim = m->dim, a, i, gi, gj;
    for (a = 0; a < nfn; ++a)
        if (face[a] < 0 || face[a] >= m->nnode)
            return gk_err_set(err, GK_ERR_ARG, "face node %d out of range", face[a]);
    for (i = 0; i < dim; ++i)
        if (!(fabs(traction[i]) < HUGE_VAL)) return gk_err_set(err, GK_ERR_NAN, "traction is not finite");
    if (dim == 2 && (nfn == 2 || nfn == 3)) {
        for (gi = 0; gi < 3; ++gi) { /* line: nodes (end, end[, mid]) */
            double s = g3[gi], N[3], dN[3], t[2] = {0, 0}, len;
            if (nfn == 2) {
                N[0] = 0.5 * (1 - s), N[1] = 0.5 * (1 + s), dN[0] = -0.5, dN[1] = 0.5;
            } else {
                N[0] = 0.5 * s * (s - 1), N[1] = 0.5 * s * (s + 1), N[2] = 1 - s * s;
                dN[0] = s - 0.5, dN[1] = s + 0.5, dN[2] = -2 * s;
            }
            for (a = 0; a < nfn; ++a)
                for (i = 0; i < 2; ++i) t[i] += dN[a] * m->x[2 * (size_t)face[a] + i];
            len = sqrt(t[0] * t[0] + t[1] * t[1]);
            for (a = 0; a < nfn; ++a)
                for (i = 0; i < 2; ++i) f[2 * face[a] + i] += w3[gi] * len * N[a] * traction[i];
        }
        return GK_OK;
    }
    if (dim == 3 && nfn == 4) {
        for (gi = 0; gi < 3; ++gi)
            for (gj = 0; gj < 3; ++gj) {
                double xi[2], N[4], dN[8], t1[3] = {0, 0, 0}, t2[3] = {0, 0, 0}, n[3], area;
                xi[0] = g3[gi], xi[1] = g3[gj];
                gk_fem_shape(GK_Q4, xi, N, dN);
                for (a = 0; a < 4; ++a)
                    for (i = 0; i < 3; ++i) {
                        t1[i] += dN[2 * a] * m->x[3 * (size_t)face[a] + i];
                        t2[i] += dN[2 * a + 1] * m->x[3 * (size_t)face[a] + i];
                    }
                gk_v3_cross(t1, t2, n);
                area = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                for (a = 0; a < 4; ++a)
                    for (i = 0; i < 3; ++i) f[3 * face[a] + i] += w3[gi] * w3[gj] * area * N[a] * traction[i];
            }
        return GK_OK;
    }
    return gk_err_set(err, GK_ERR_ARG, "a %dD face with %d nodes (2D: 2 or 3; 3D: 4)", dim, nfn);
}

/* Flanagan & Belytschko (1981) hourglass control for the 1-point Hex8:
 * gamma_a^alpha = h_a^alpha - (h^alpha . x_i) b_ai with b_ai = dN_a/dx_i at the
 * centre; f_ai = -k sum_alpha gamma_a^alpha (gamma^alpha . u_i). Zero for any
 * linear field, so it never stiffens a patch test. */
GKDEF void gk_fem_hex8_hourglass(const double *xe, const double *ue, double k, double *f) {
    double N[8], dN[24], J[9], Ji[9], b[24], h[4][8], g[4][8];
    double zero[3] = {0, 0, 0};
    int a, i, j, al;
    gk_fem_shape(GK_HEX8, zero, N, dN);
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            double s = 0.0;
            for (a = 0; a < 8; ++a) s += xe[3 * a + i] * dN[3 * a + j];
            J[3 * i + j] = s;
        }
    gk_m3_inverse(J, Ji);
    for (a = 0; a < 8; ++a)
        for (j = 0; j < 3; ++j)
            b[3 * a + j] = dN[3 * a] * Ji[j] + dN[3 * a + 1] * Ji[3 + j] + dN[3 * a + 2] * Ji[6 + j];
    for (a = 0; a < 8; ++a) {
        const double *r = gk__h8_xi[a];
        h[0][a] = r[1] * r[2], h[1][a] = r[0] * r[2], h[2][a] = r[0] * r[1], h[3][a] = r[0] * r[1] * r[2];
    }
    for (al = 0; al < 4; ++al) {
        double hx[3] = {0, 0, 0};
        for (a = 0; a < 8; ++a)
            for (i = 0; i < 3; ++i) hx[i] += h[al][a] * xe[3 * a + i];
        for (a = 0; a < 8; ++a)
            g[al][a] = h[al][a] - (hx[0] * b[3 * a] + hx[1] * b[3 * a + 1] + hx[2] * b[3 * a + 2]);
    }
    for (a = 0; a < 24; ++a) f[a] = 0.0;
    for (al = 0; al < 4; ++al)
        for (i = 0; i < 3; ++i) {
            double qv = 0.0;
            for (a = 0; a < 8; ++a) qv += g[al][a] * ue[3 * a + i];
            for (a = 0; a < 8; ++a) f[3 * a + i] -= k * g[al][a] * qv;
        }
}

GKDEF gk_result gk_fem_dirichlet(gk_csr *A, double *rhs, int nfix, const int *dofs, const double *vals,
                                 gk_err *err) {
    double *fixv;
    int k, i, p;
    for (k = 0; k < nfix; ++k) {
        if (dofs[k] < 0 || dofs[k] >= A->n)
            return gk_err_set(err, GK_ERR_ARG, "prescribed dof %d out of range", dofs[k]);
        if (!(fabs(vals[k]) < HUGE_VAL))
            return gk_err_set(err, GK_ERR_NAN, "prescribed value of dof %d", dofs[k]);
    }
    fixv = (double *)gk_alloc(&A->alloc, (size_t)A->n * sizeof(double) + 1);
    if (!fixv) return gk_err_set(err, GK_ERR_ALLOC, "Dirichlet work array");
    /* NaN marks a free dof (prescribed values were checked finite above) */
    for (i = 0; i < A->n; ++i) fixv[i] = NAN;
    for (k = 0; k < nfix; ++k) fixv[dofs[k]] = vals[k];
    for (i = 0; i < A->n; ++i) {
        if (fixv[i] == fixv[i]) {
            double d = 0.0;
            for (p = A->rowptr[i]; p < A->rowptr[i + 1]; ++p) {
                if (A->col[p] == i) d = A->val[p];
                A->val[p] = 0.0;
            }
            if (!(fabs(d) > 0.0)) d = 1.0;
            for (p = A->rowptr[i]; p < A->rowptr[i + 1]; ++p)
                if (A->col[p] == i) A->val[p] = d;
            rhs[i] = d * fixv[i];
        } else {
            for (p = A->rowptr[i]; p < A->rowptr[i + 1]; ++p)
                if (fixv[A->col[p]] == fixv[A->col[p]]) {
                    rhs[i] -= A->val[p] * fixv[A->col[p]];
                    A->val[p] = 0.0;
                }
        }
    }
    gk_free(&A->alloc, fixv);
    return GK_OK;
}

/* the implementations of the headers included above that call these elements */
#include "gk_mesh.h"
#include "gk_dofmap.h"

#endif /* GK_FEM implementation */
