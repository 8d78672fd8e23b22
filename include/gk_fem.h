/* gk_fem.h - finite elements for the macro scale of FEMxDEM.   (grainkit v0.1)
 *
 * Small-strain / updated-Lagrangian continuum elements whose material is a
 * tangent D and a stress sigma handed in per Gauss point (e.g. from a DEM RVE
 * through gk_homog.h), sparse assembly and boundary conditions; the linear
 * solvers are in gk_sparse.h, which this header includes. Guo & Zhao (2014)
 * eqs 1-4, 21.
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_FEM_IMPLEMENTATION, which also
 * implements gk_sparse.h) in one file.
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
 *   gk_mesh_faces_on_plane  boundary edges/faces lying on x_axis = value
 *   gk_mesh_nodes_on_plane  nodes lying on x_axis = value
 *   gk_mesh_structured      nx x ny (x nz) mesh of a box, any element type
 *   gk_mesh_read_gmsh       Gmsh .msh ASCII v2.2 and v4.1: quad4/quad8/hex8
 *   gk_mesh_parse_gmsh      the same from len bytes of text in memory (need
 *                           not end in NUL); memory follows what the text
 *                           holds, never the counts or tags it announces
 *   gk_mesh_check           every element has det J > 0 at every Gauss point
 *   gk_mesh_update          updated-Lagrangian node update x += u
 *   gk_csr_from_mesh        sparsity of the nodal-dof graph (dof = dim*node+c)
 *   gk_nonlocal_*           nonlocal averaging over points within a radius
 *                           (bell kernel; see NONLOCAL AVERAGING below)
 *   gk_fem_dirichlet        prescribed dofs by symmetric elimination: row and
 *                           column zeroed, the known values moved to the right-
 *                           hand side, the diagonal KEPT (scaling unchanged)
 *                           and rhs = diag * value, so the solve returns the
 *                           prescribed value exactly.
 *
 * TIED DOFS (periodic boundaries, rigid platens)
 *   A gk_dofmap writes every dof as u = T ur + g: a dof is either independent
 *   or tied to another one, u_s = u_m + g_s (g: a prescribed jump, e.g. the
 *   macro gradient times the period; 0 for a platen). T has a single 1 per
 *   row, so the condensed system T^T K T ur = T^T (f - K g) is an exact
 *   elimination of the slaves: rows and columns of a slave are added to its
 *   master's. Chains (a slave of a slave, the corners of a doubly periodic
 *   mesh) are followed to the independent dof and their jumps added.
 *   gk_mesh_periodic_pairs  nodes on the plane x_axis = hi paired with the
 *                           nodes on x_axis = lo at the same other coordinates
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
 * SPARSE MATRICES AND SOLVERS: gk_sparse.h (included): gk_csr, gk_solver
 *   (RCM + banded LU), gk_pcg. gk_csr_from_mesh (here) builds a mesh's
 *   pattern.
 *
 * Units and signs as gk_base.h: SI, tension-positive stress. 2D is plane
 * strain per unit thickness (forces are N/m).
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_FEM_H
#define GK_FEM_H

#include "gk_sparse.h"

typedef enum gk_elem_type { GK_Q4 = 0, GK_Q8 = 1, GK_HEX8 = 2 } gk_elem_type;

#define GK_FEM_MAX_NPE 8 /* nodes per element          */
#define GK_FEM_MAX_GP 27 /* Gauss points per element   */

typedef struct gk_mesh {
    int dim;           /* 2 or 3                                         */
    gk_elem_type type; /* element type (one per mesh)                   */
    int npe;           /* nodes per element                             */
    int nnode, nelem;
    double *x; /* nnode x dim node coordinates                         */
    int *conn; /* nelem x npe node ids (0-based)                       */
    int *tag;  /* nelem physical tags (Gmsh) or 0                      */
    gk_allocator alloc;
} gk_mesh;

typedef struct gk_quad {
    int n;                       /* number of points                   */
    double xi[GK_FEM_MAX_GP][3]; /* reference coordinates              */
    double w[GK_FEM_MAX_GP];     /* weights                            */
} gk_quad;

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

GKDEF gk_result gk_mesh_structured(gk_mesh *m, gk_elem_type t, const int n[3], const double origin[3],
                                   const double len[3], const gk_allocator *alloc, gk_err *err);
GKDEF gk_result gk_mesh_read_gmsh(const char *path, gk_mesh *m, const gk_allocator *alloc, gk_err *err);
GKDEF gk_result gk_mesh_parse_gmsh(const char *text, size_t len, gk_mesh *m, const gk_allocator *alloc,
                                   gk_err *err);
GKDEF gk_result gk_mesh_check(const gk_mesh *m, const gk_quad *q, gk_err *err);
GKDEF void gk_mesh_free(gk_mesh *m);
GKDEF void gk_mesh_update(gk_mesh *m, const double *u);
GKDEF int gk_mesh_nodes_on_plane(const gk_mesh *m, int axis, double value, double tol, int *out);
GKDEF int gk_mesh_faces_on_plane(const gk_mesh *m, int axis, double value, double tol, int *faces, int *nfn);
GKDEF void gk_mesh_point(const gk_mesh *m, int e, const double *xi, double x[3]);

GKDEF gk_result gk_csr_from_mesh(gk_csr *A, const gk_mesh *m, const gk_allocator *alloc, gk_err *err);
GKDEF gk_result gk_fem_dirichlet(gk_csr *A, double *rhs, int nfix, const int *dofs, const double *vals,
                                 gk_err *err);

GKDEF gk_result gk_mesh_periodic_pairs(const gk_mesh *m, int axis, double lo, double hi, double tol,
                                       int *slave, int *master, int *npair, gk_err *err);
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

#endif /* GK_FEM_H */

#ifndef GK_FEM_NONLOCAL_H
#define GK_FEM_NONLOCAL_H
/* NONLOCAL AVERAGING (Liu, Sun, Yuan & Fish 2016, Appendix A, eqs 58-59,
 * A.3-A.6). A field phi given at n points (Gauss points) is replaced by
 *     <phi>(x_I) = sum_{J in Q_I} a*(x_I, x_J) phi(x_J)                 (A.6)
 *     a*(x_I, x_J) = a(|x_I - x_J|) / sum_{K in Q_I} a(|x_I - x_K|)       (A.4)
 *     a(r) = (1 - r^2/R^2)^2 for r < R, 0 beyond (the bell kernel)        (A.3)
 *     Q_I = {J : |x_I - x_J| < R}, I itself included                      (A.5)
 * exactly as the paper writes the discrete form: the weights are normalised
 * per point and carry NO quadrature weights or volumes (on a uniform mesh the
 * two agree; on a graded one the paper's form weighs a fine region more).
 *   - Periodic directions (period[k] > 0 along axis k): every periodic
 *     image of x_J within R counts, a(x_I, x_J) = sum_images a(|x_J + k P -
 *     x_I|) (I's own images too when a period is below R): the average over
 *     the infinite periodic medium, for any R and period.
 *   - Boundaries: points near a free or fixed boundary have a neighbourhood
 *     cut by it; the renormalisation of A.4 makes the weights still sum to
 *     one (a constant is kept), but the kernel is then one-sided, so a
 *     linear field is reproduced exactly only where Q_I is symmetric about
 *     x_I (interior points of a regular grid, and any point across a
 *     periodic face); near a boundary the average is pulled inward by up to
 *     about R/2 times the gradient. The paper does not say how it treats
 *     boundaries; this is the plain truncation.
 *   - R = 0 switches the operator off (local model: every point averages
 *     itself alone); so does a mesh whose point spacing is at least R.
 *   - Q_I is built once (reference configuration, as the paper precomputes
 *     it) by a direct O(n^2) search: ~0.1 s at 10 000 points.
 * The paper averages the whole strain-increment tensor (eq 58): apply with
 * ncomp = 6 (Voigt) or 9 (3x3) values per point. */
typedef struct gk_nonlocal {
    int n;        /* points                                                    */
    int *start;   /* n + 1: point I's neighbours are nbr[start[I] .. start[I+1]) */
    int *nbr;     /* neighbour ids, ascending, I itself included              */
    double *w;    /* a*(x_I, x_J) of eq A.4, summing to 1 per point           */
    double R;     /* radius [m]; 0: local                                     */
    gk_allocator alloc;
} gk_nonlocal;

/* eq A.3 */
GK_INLINE double gk_nonlocal_bell(double r, double R) {
    double t;
    if (!(r < R)) return 0.0;
    t = 1.0 - (r * r) / (R * R);
    return t * t;
}

#ifdef __cplusplus
extern "C" {
#endif
/* x: n points of dim coordinates; period: NULL or 3 values (> 0: periodic
 * along that axis with this period). Any previous content of nl is ignored
 * (free it first). */
GKDEF gk_result gk_nonlocal_build(gk_nonlocal *nl, int dim, int n, const double *x, double R, const double *period,
                                  const gk_allocator *alloc, gk_err *err);
/* out[ncomp I + c] = sum_J w_IJ in[ncomp J + c]; out must not alias in */
GKDEF void gk_nonlocal_apply(const gk_nonlocal *nl, int ncomp, const double *in, double *out);
GKDEF void gk_nonlocal_free(gk_nonlocal *nl);
#ifdef __cplusplus
}
#endif
#endif /* GK_FEM_NONLOCAL_H */

/* ======================================================== IMPLEMENTATION */
#if (defined(GK_IMPLEMENTATION) || defined(GK_FEM_IMPLEMENTATION)) && !defined(GK_FEM_IMPL_ONCE)
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

/* ------------------------------------------------------------------ mesh */
static gk_result gk__mesh_alloc(gk_mesh *m, gk_elem_type t, int nnode, int nelem, const gk_allocator *alloc,
                                gk_err *err) {
    gk_mesh z;
    memset(&z, 0, sizeof z);
    if (alloc) z.alloc = *alloc;
    z.type = t, z.dim = gk_fem_dim(t), z.npe = gk_fem_npe(t), z.nnode = nnode, z.nelem = nelem;
    z.x = (double *)gk_alloc(&z.alloc, (size_t)nnode * z.dim * sizeof(double));
    z.conn = (int *)gk_alloc(&z.alloc, (size_t)nelem * z.npe * sizeof(int));
    z.tag = (int *)gk_alloc(&z.alloc, (size_t)nelem * sizeof(int) + 1);
    if (!z.x || !z.conn || !z.tag) {
        gk_free(&z.alloc, z.x), gk_free(&z.alloc, z.conn), gk_free(&z.alloc, z.tag);
        return gk_err_set(err, GK_ERR_ALLOC, "mesh of %d nodes, %d elements", nnode, nelem);
    }
    memset(z.tag, 0, (size_t)nelem * sizeof(int));
    *m = z;
    return GK_OK;
}

GKDEF void gk_mesh_free(gk_mesh *m) {
    gk_free(&m->alloc, m->x);
    gk_free(&m->alloc, m->conn);
    gk_free(&m->alloc, m->tag);
    memset(m, 0, sizeof *m);
}

GKDEF gk_result gk_mesh_structured(gk_mesh *m, gk_elem_type t, const int n[3], const double origin[3],
                                   const double len[3], const gk_allocator *alloc, gk_err *err) {
    int dim, i, j, k, e = 0, nx, ny, nz;
    gk_mesh z;
    gk_result r;
    if (t != GK_Q4 && t != GK_Q8 && t != GK_HEX8)
        return gk_err_set(err, GK_ERR_ARG, "unknown element type %d", (int)t);
    dim = gk_fem_dim(t);
    for (k = 0; k < dim; ++k) {
        if (n[k] < 1 || n[k] > 100000)
            return gk_err_set(err, GK_ERR_ARG, "%d elements along axis %d", n[k], k);
        if (!(len[k] > 0.0) || !(len[k] < HUGE_VAL) || !(fabs(origin[k]) < HUGE_VAL))
            return gk_err_set(err, GK_ERR_ARG, "box length %g / origin %g along axis %d", len[k], origin[k],
                              k);
    }
    nx = n[0], ny = n[1], nz = dim == 3 ? n[2] : 1;
    { /* counts as doubles first: node ids, dofs (dim per node) and connectivity entries are int */
        double ne = (double)nx * ny * nz, nn = t == GK_Q8
                                                   ? (2.0 * nx + 1) * (2.0 * ny + 1)
                                                   : (nx + 1.0) * (ny + 1.0) * (dim == 3 ? nz + 1.0 : 1.0);
        if (ne * gk_fem_npe(t) > (double)INT_MAX || nn * dim > (double)INT_MAX)
            return gk_err_set(err, GK_ERR_ARG,
                              "%d x %d x %d mesh: %.0f elements, %.0f nodes exceed int indices", nx, ny, nz,
                              ne, nn);
    }
    if (t == GK_Q4 || t == GK_HEX8) {
        int nn = (nx + 1) * (ny + 1) * (dim == 3 ? nz + 1 : 1);
        r = gk__mesh_alloc(&z, t, nn, nx * ny * nz, alloc, err);
        if (r) return r;
        for (k = 0; k < (dim == 3 ? nz + 1 : 1); ++k)
            for (j = 0; j <= ny; ++j)
                for (i = 0; i <= nx; ++i) {
                    int id = (k * (ny + 1) + j) * (nx + 1) + i;
                    z.x[dim * id] = origin[0] + len[0] * i / nx;
                    z.x[dim * id + 1] = origin[1] + len[1] * j / ny;
                    if (dim == 3) z.x[dim * id + 2] = origin[2] + len[2] * k / nz;
                }
        for (k = 0; k < nz; ++k)
            for (j = 0; j < ny; ++j)
                for (i = 0; i < nx; ++i, ++e) {
                    int *c = z.conn + (size_t)e * z.npe, s = (nx + 1) * (ny + 1);
                    int b = (k * (ny + 1) + j) * (nx + 1) + i;
                    c[0] = b, c[1] = b + 1, c[2] = b + nx + 2, c[3] = b + nx + 1;
                    if (dim == 3) c[4] = c[0] + s, c[5] = c[1] + s, c[6] = c[2] + s, c[7] = c[3] + s;
                }
    } else { /* Q8: a (2nx+1) x (2ny+1) lattice without the element centres */
        int W = 2 * nx + 1, H = 2 * ny + 1, *id, cnt = 0;
        r = gk__mesh_alloc(&z, t, W * H - nx * ny, nx * ny, alloc, err);
        if (r) return r;
        id = (int *)gk_alloc(&z.alloc, (size_t)W * H * sizeof(int));
        if (!id) {
            gk_mesh_free(&z);
            return gk_err_set(err, GK_ERR_ALLOC, "Q8 node map");
        }
        for (j = 0; j < H; ++j)
            for (i = 0; i < W; ++i) {
                if ((i & 1) && (j & 1)) {
                    id[j * W + i] = -1;
                    continue;
                }
                id[j * W + i] = cnt;
                z.x[2 * cnt] = origin[0] + len[0] * i / (2.0 * nx);
                z.x[2 * cnt + 1] = origin[1] + len[1] * j / (2.0 * ny);
                ++cnt;
            }
        for (j = 0; j < ny; ++j)
            for (i = 0; i < nx; ++i, ++e) {
                int *c = z.conn + (size_t)e * 8, I = 2 * i, J = 2 * j;
                c[0] = id[J * W + I], c[1] = id[J * W + I + 2], c[2] = id[(J + 2) * W + I + 2],
                c[3] = id[(J + 2) * W + I];
                c[4] = id[J * W + I + 1], c[5] = id[(J + 1) * W + I + 2], c[6] = id[(J + 2) * W + I + 1];
                c[7] = id[(J + 1) * W + I];
            }
        gk_free(&z.alloc, id);
    }
    *m = z;
    return GK_OK;
}

GKDEF gk_result gk_mesh_check(const gk_mesh *m, const gk_quad *q, gk_err *err) {
    int e, g, a;
    double dNdx[3 * GK_FEM_MAX_NPE], detJ = 0.0, dmax = 0.0;
    for (a = 0; a < m->nnode * m->dim; ++a)
        if (!(fabs(m->x[a]) < HUGE_VAL))
            return gk_err_set(err, GK_ERR_NAN, "node %d has a non-finite coordinate", a / m->dim);
    for (e = 0; e < m->nelem; ++e) {
        for (a = 0; a < m->npe; ++a) {
            int b, id = m->conn[(size_t)e * m->npe + a];
            if (id < 0 || id >= m->nnode)
                return gk_err_set(err, GK_ERR_MESH, "element %d: node id %d out of range", e, id);
            for (b = 0; b < a; ++b)
                if (m->conn[(size_t)e * m->npe + b] == id)
                    return gk_err_set(err, GK_ERR_MESH, "element %d uses node %d twice (degenerate)", e, id);
        }
        for (g = 0; g < q->n; ++g) {
            gk_result r = gk_fem_jacobian(m, e, q->xi[g], NULL, dNdx, &detJ, err);
            if (r) return r;
            if (g == 0 || detJ > dmax) dmax = detJ;
        }
        /* corners too: a quad collapsed to a triangle still has det J > 0 at
         * its Gauss points, but 0 at the collapsed corner */
        for (a = 0; a < (m->dim == 3 ? 8 : 4); ++a) {
            double xi[3];
            xi[0] = gk__h8_xi[a][0], xi[1] = gk__h8_xi[a][1], xi[2] = gk__h8_xi[a][2];
            if (gk_fem_jacobian(m, e, xi, NULL, dNdx, &detJ, NULL) || !(detJ > 1e-8 * dmax))
                return gk_err_set(err, GK_ERR_MESH,
                                  "element %d is degenerate or inverted at its corner %d (det J %g)", e, a,
                                  detJ);
        }
    }
    return GK_OK;
}

GKDEF void gk_mesh_update(gk_mesh *m, const double *u) {
    int k;
    for (k = 0; k < m->nnode * m->dim; ++k) m->x[k] += u[k];
}

GKDEF void gk_mesh_point(const gk_mesh *m, int e, const double *xi, double x[3]) {
    double N[GK_FEM_MAX_NPE], dN[3 * GK_FEM_MAX_NPE];
    int a, i;
    gk_fem_shape(m->type, xi, N, dN);
    x[0] = x[1] = x[2] = 0.0;
    for (a = 0; a < m->npe; ++a)
        for (i = 0; i < m->dim; ++i)
            x[i] += N[a] * m->x[(size_t)m->conn[(size_t)e * m->npe + a] * m->dim + i];
}

GKDEF int gk_mesh_nodes_on_plane(const gk_mesh *m, int axis, double value, double tol, int *out) {
    int a, n = 0;
    for (a = 0; a < m->nnode; ++a)
        if (fabs(m->x[(size_t)a * m->dim + axis] - value) <= tol) {
            if (out) out[n] = a;
            ++n;
        }
    return n;
}

/* local faces: Q4 edges (2 nodes), Q8 edges (end, end, mid), Hex8 quads */
static const int gk__q4_edges[4][3] = {{0, 1, 4}, {1, 2, 5}, {2, 3, 6}, {3, 0, 7}};
static const int gk__h8_faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                       {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};

GKDEF int gk_mesh_faces_on_plane(const gk_mesh *m, int axis, double value, double tol, int *faces,
                                 int *nfn_out) {
    int e, f, a, n = 0, nf = m->type == GK_HEX8 ? 6 : 4;
    int nfn = m->type == GK_HEX8 ? 4 : m->type == GK_Q8 ? 3 : 2;
    if (nfn_out) *nfn_out = nfn;
    for (e = 0; e < m->nelem; ++e)
        for (f = 0; f < nf; ++f) {
            int nodes[4], on = 1;
            for (a = 0; a < nfn; ++a) {
                int loc = m->type == GK_HEX8 ? gk__h8_faces[f][a] : gk__q4_edges[f][a];
                nodes[a] = m->conn[(size_t)e * m->npe + loc];
                if (fabs(m->x[(size_t)nodes[a] * m->dim + axis] - value) > tol) on = 0;
            }
            if (!on) continue;
            if (faces)
                for (a = 0; a < nfn; ++a) faces[n * nfn + a] = nodes[a];
            ++n;
        }
    return n;
}

/* ------------------------------------------------------------------ gmsh */
typedef struct gk__rd {
    const char *p, *end;
} gk__rd;

/* next line into buf: 1, 0 at the end, -1 for a line that does not fit
 * (an error wherever the line is data: never silently cut) */
static int gk__rd_line(gk__rd *r, char *buf, size_t cap) {
    size_t n = 0;
    int cut = 0;
    if (r->p >= r->end) return 0;
    while (r->p < r->end && *r->p != '\n') {
        if (n + 1 < cap)
            buf[n++] = *r->p;
        else
            cut = 1;
        ++r->p;
    }
    if (r->p < r->end) ++r->p;
    while (n && (buf[n - 1] == '\r' || buf[n - 1] == ' ')) --n;
    buf[n] = 0;
    return cut ? -1 : 1;
}

static int gk__rd_find(gk__rd *r, const char *section) {
    char line[256];
    int k;
    while ((k = gk__rd_line(r, line, sizeof line)) != 0)
        if (k == 1 && !strcmp(line, section)) return 1;
    return 0;
}

static int gk__gmsh_npe(long type) { return type == 3 ? 4 : type == 16 ? 8 : type == 5 ? 8 : -1; }

/* node tags sorted for lookup: memory follows the nodes the file lists,
 * never the size of its largest tag */
typedef struct gk__tagidx {
    long tag;
    int idx;
} gk__tagidx;
static int gk__tagidx_cmp(const void *a, const void *b) {
    long x = ((const gk__tagidx *)a)->tag, y = ((const gk__tagidx *)b)->tag;
    return x < y ? -1 : x > y;
}
static int gk__tag_find(const gk__tagidx *t, long n, long tag) {
    long lo = 0, hi = n - 1;
    while (lo <= hi) {
        long mid = lo + (hi - lo) / 2;
        if (t[mid].tag == tag) return t[mid].idx;
        if (t[mid].tag < tag)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return -1;
}

GKDEF gk_result gk_mesh_parse_gmsh(const char *text, size_t len, gk_mesh *out, const gk_allocator *alloc,
                                   gk_err *err) {
    char line[1024];
    gk__rd r;
    double version = 0.0, *nx = NULL;
    long nnodes_file = 0, k;
    gk__tagidx *map = NULL;
    int *econn = NULL, *etag = NULL, etype = -1, nel = 0, cap = 0, nused = 0, i;
    gk_allocator A;
    gk_result res = GK_OK;
    gk_mesh m;
    memset(&A, 0, sizeof A);
    if (alloc) A = *alloc;
    if (!text) return gk_err_set(err, GK_ERR_ARG, "no Gmsh text given");
#define GK__GFAIL(code, ...)                      \
    do {                                          \
        res = gk_err_set(err, code, __VA_ARGS__); \
        goto done;                                \
    } while (0)
/* a node needs at least 8 bytes of text ("1 0 0 0\n"; v4: "1\n" and "0 0 0\n") */
#define GK__GNODES_FIT(n) ((n) <= (long)((size_t)(r.end - r.p) / 8))
    r.p = text, r.end = text + len;
    if (!gk__rd_find(&r, "$MeshFormat") || gk__rd_line(&r, line, sizeof line) != 1 ||
        sscanf(line, "%lf", &version) != 1)
        GK__GFAIL(GK_ERR_FORMAT, "no $MeshFormat section");
    if (strstr(line, " 1 "))
        GK__GFAIL(GK_ERR_UNSUPPORTED, "binary Gmsh files are not supported (ASCII only)");
    if (!(version >= 2.0 && version < 3.0) && !(version >= 4.0 && version < 5.0))
        GK__GFAIL(GK_ERR_UNSUPPORTED, "Gmsh format %g (2.x and 4.x ASCII are read)", version);
    /* ---- nodes: tags and coordinates */
    r.p = text;
    if (!gk__rd_find(&r, "$Nodes") || gk__rd_line(&r, line, sizeof line) != 1)
        GK__GFAIL(GK_ERR_FORMAT, "no $Nodes section");
    if (version < 3.0) {
        if (sscanf(line, "%ld", &nnodes_file) != 1 || nnodes_file <= 0 || !GK__GNODES_FIT(nnodes_file))
            GK__GFAIL(GK_ERR_FORMAT, "bad node count '%.40s' (more than the file can hold?)", line);
        map = (gk__tagidx *)gk_alloc(&A, (size_t)nnodes_file * sizeof *map);
        nx = (double *)gk_alloc(&A, (size_t)nnodes_file * 3 * sizeof(double));
        if (!map || !nx) GK__GFAIL(GK_ERR_ALLOC, "node arrays for %ld nodes", nnodes_file);
        for (k = 0; k < nnodes_file; ++k) {
            if (gk__rd_line(&r, line, sizeof line) != 1 ||
                sscanf(line, "%ld %lf %lf %lf", &map[k].tag, &nx[3 * k], &nx[3 * k + 1], &nx[3 * k + 2]) != 4)
                GK__GFAIL(GK_ERR_FORMAT, "bad node line %ld", k + 1);
        }
    } else {
        long nblocks, minT, maxT, b, got = 0;
        if (sscanf(line, "%ld %ld %ld %ld", &nblocks, &nnodes_file, &minT, &maxT) != 4 || nnodes_file <= 0 ||
            !GK__GNODES_FIT(nnodes_file))
            GK__GFAIL(GK_ERR_FORMAT, "bad $Nodes header '%.40s' (more nodes than the file can hold?)", line);
        map = (gk__tagidx *)gk_alloc(&A, (size_t)nnodes_file * sizeof *map);
        nx = (double *)gk_alloc(&A, (size_t)nnodes_file * 3 * sizeof(double));
        if (!map || !nx) GK__GFAIL(GK_ERR_ALLOC, "node arrays for %ld nodes", nnodes_file);
        for (b = 0; b < nblocks; ++b) {
            int edim, etg, par;
            long nin;
            if (gk__rd_line(&r, line, sizeof line) != 1 ||
                sscanf(line, "%d %d %d %ld", &edim, &etg, &par, &nin) != 4 || nin < 0 ||
                nin > nnodes_file - got)
                GK__GFAIL(GK_ERR_FORMAT, "bad node block %ld", b);
            if (par) GK__GFAIL(GK_ERR_UNSUPPORTED, "parametric node coordinates");
            for (k = 0; k < nin; ++k)
                if (gk__rd_line(&r, line, sizeof line) != 1 || sscanf(line, "%ld", &map[got + k].tag) != 1)
                    GK__GFAIL(GK_ERR_FORMAT, "bad node tag in block %ld", b);
            for (k = 0; k < nin; ++k) {
                double *c = nx + 3 * (got + k);
                if (gk__rd_line(&r, line, sizeof line) != 1 ||
                    sscanf(line, "%lf %lf %lf", &c[0], &c[1], &c[2]) != 3)
                    GK__GFAIL(GK_ERR_FORMAT, "bad node coordinates in block %ld", b);
            }
            got += nin;
        }
        if (got != nnodes_file) GK__GFAIL(GK_ERR_FORMAT, "%ld nodes announced, %ld read", nnodes_file, got);
    }
    for (k = 0; k < nnodes_file; ++k) {
        if (map[k].tag <= 0) GK__GFAIL(GK_ERR_FORMAT, "node tag %ld (must be > 0)", map[k].tag);
        if (!(fabs(nx[3 * k]) < HUGE_VAL && fabs(nx[3 * k + 1]) < HUGE_VAL && fabs(nx[3 * k + 2]) < HUGE_VAL))
            GK__GFAIL(GK_ERR_NAN, "node %ld has a non-finite coordinate", map[k].tag);
        map[k].idx = (int)k; /* file index; renumbered to used nodes below */
    }
    qsort(map, (size_t)nnodes_file, sizeof *map, gk__tagidx_cmp);
    for (k = 1; k < nnodes_file; ++k)
        if (map[k].tag == map[k - 1].tag) GK__GFAIL(GK_ERR_FORMAT, "node tag %ld appears twice", map[k].tag);
    /* ---- elements: keep the highest-dimensional supported type */
    r.p = text;
    if (!gk__rd_find(&r, "$Elements") || gk__rd_line(&r, line, sizeof line) != 1)
        GK__GFAIL(GK_ERR_FORMAT, "no $Elements section");
    {
        long nblocks = 1, nelem_file, b, e;
        if (version < 3.0) {
            if (sscanf(line, "%ld", &nelem_file) != 1) GK__GFAIL(GK_ERR_FORMAT, "bad element count");
        } else {
            long a1, a2;
            if (sscanf(line, "%ld %ld %ld %ld", &nblocks, &nelem_file, &a1, &a2) != 4)
                GK__GFAIL(GK_ERR_FORMAT, "bad $Elements header");
        }
        for (b = 0; b < nblocks; ++b) {
            long nin = nelem_file, btype = -1;
            int bphys = 0;
            if (version >= 3.0) {
                int edim;
                if (gk__rd_line(&r, line, sizeof line) != 1 ||
                    sscanf(line, "%d %d %ld %ld", &edim, &bphys, &btype, &nin) != 4)
                    GK__GFAIL(GK_ERR_FORMAT, "bad element block %ld", b);
            }
            for (e = 0; e < nin; ++e) {
                long v[64], type;
                int nv = 0, off, np, tagv = bphys;
                char *s = line, *q;
                if (gk__rd_line(&r, line, sizeof line) != 1)
                    GK__GFAIL(GK_ERR_FORMAT,
                              "truncated $Elements (element %ld of block %ld, or a line over %d "
                              "characters)",
                              e + 1, b, (int)sizeof line - 1);
                while (nv < 64) {
                    long x = strtol(s, &q, 10);
                    if (q == s) break;
                    v[nv++] = x, s = q;
                }
                if (version < 3.0) {
                    /* id type ntags tag... nodes...: the tag count is data, checked before it indexes */
                    if (nv < 3 || v[2] < 0 || v[2] > nv - 3)
                        GK__GFAIL(GK_ERR_FORMAT, "bad element line (element %ld: %d numbers, tag count %ld)",
                                  e + 1, nv, nv >= 3 ? v[2] : -1L);
                    type = v[1], off = 3 + (int)v[2];
                    tagv = v[2] > 0 && v[3] >= INT_MIN && v[3] <= INT_MAX ? (int)v[3] : 0;
                } else {
                    type = btype, off = 1;
                }
                np = gk__gmsh_npe(type);
                if (np < 0) continue; /* points, lines, triangles...: not volume elements of this module */
                if (nv < off + np) GK__GFAIL(GK_ERR_FORMAT, "element %ld has too few nodes", e + 1);
                if (etype >= 0 && type != etype) {
                    if ((type == 5) == (etype == 5))
                        GK__GFAIL(GK_ERR_UNSUPPORTED, "mixed element types %d and %ld", etype, type);
                    if (etype == 5) continue; /* 3D mesh: skip boundary quads */
                    nel = 0;                  /* a hex appears after quads: restart with hexes */
                }
                etype = (int)type;
                if (nel == cap) {
                    int nc = cap ? 2 * cap : 256;
                    if (cap > INT_MAX / 16) GK__GFAIL(GK_ERR_FORMAT, "more than %d elements", cap);
                    if (gk_realloc(&A, (void **)&econn, (size_t)cap * 8, (size_t)nc * 8, sizeof(int)) ||
                        gk_realloc(&A, (void **)&etag, (size_t)cap, (size_t)nc, sizeof(int)))
                        GK__GFAIL(GK_ERR_ALLOC, "elements");
                    cap = nc;
                }
                for (i = 0; i < np; ++i) {
                    long t = v[off + i];
                    int id = gk__tag_find(map, nnodes_file, t);
                    if (id < 0) GK__GFAIL(GK_ERR_FORMAT, "element %ld refers to unknown node %ld", e + 1, t);
                    econn[nel * 8 + i] = id;
                }
                etag[nel++] = tagv;
            }
        }
    }
    if (etype < 0 || nel == 0) GK__GFAIL(GK_ERR_MESH, "no quad4, quad8 or hex8 elements");
    { /* keep only the nodes the elements use, in file order */
        gk_elem_type t = etype == 3 ? GK_Q4 : etype == 16 ? GK_Q8 : GK_HEX8;
        int npe = gk_fem_npe(t), dim = gk_fem_dim(t), *used;
        used = (int *)gk_alloc(&A, (size_t)nnodes_file * sizeof(int));
        if (!used) GK__GFAIL(GK_ERR_ALLOC, "node renumbering");
        for (k = 0; k < nnodes_file; ++k) used[k] = -1;
        for (k = 0; k < (long)nel * npe; ++k) used[econn[(k / npe) * 8 + k % npe]] = 0;
        for (k = 0; k < nnodes_file; ++k)
            if (!used[k]) used[k] = nused++;
        res = gk__mesh_alloc(&m, t, nused, nel, &A, err);
        if (res) {
            gk_free(&A, used);
            goto done;
        }
        for (k = 0; k < nnodes_file; ++k)
            if (used[k] >= 0)
                for (i = 0; i < dim; ++i) m.x[(size_t)used[k] * dim + i] = nx[3 * k + i];
        for (k = 0; k < nel; ++k) {
            for (i = 0; i < npe; ++i) m.conn[k * npe + i] = used[econn[k * 8 + i]];
            m.tag[k] = etag[k];
        }
        gk_free(&A, used);
        *out = m;
    }
done:
#undef GK__GFAIL
#undef GK__GNODES_FIT
    gk_free(&A, nx), gk_free(&A, map), gk_free(&A, econn), gk_free(&A, etag);
    return res;
}

GKDEF gk_result gk_mesh_read_gmsh(const char *path, gk_mesh *out, const gk_allocator *alloc, gk_err *err) {
    char *text = NULL;
    size_t len = 0;
    gk_result r;
    if (!path) return gk_err_set(err, GK_ERR_ARG, "no mesh path given");
    r = gk_file_read(path, alloc, &text, &len, err);
    if (r) return r;
    r = gk_mesh_parse_gmsh(text, len, out, alloc, err);
    gk_free(alloc, text);
    if (r && err) {
        char msg[GK_ERR_MSG_LEN];
        memcpy(msg, err->msg, sizeof msg);
        gk_err_set(err, r, "%s: %s", path, msg);
    }
    return r;
}

/* ------------------------------------------------------------------- CSR */
GKDEF gk_result gk_csr_from_mesh(gk_csr *A, const gk_mesh *m, const gk_allocator *alloc, gk_err *err) {
    /* node-to-node adjacency through elements, then expanded to dofs */
    int nn = m->nnode, dim = m->dim, npe = m->npe, e, a, b, i, k, *cnt = NULL, *adj = NULL, *start = NULL,
        *mark = NULL;
    gk_csr z;
    size_t cap;
    memset(&z, 0, sizeof z);
    if (alloc) z.alloc = *alloc;
    cap = (size_t)m->nelem * npe * npe;
    cnt = (int *)gk_alloc(&z.alloc, ((size_t)nn + 1) * sizeof(int));
    start = (int *)gk_alloc(&z.alloc, ((size_t)nn + 1) * sizeof(int));
    mark = (int *)gk_alloc(&z.alloc, (size_t)nn * sizeof(int));
    adj = (int *)gk_alloc(&z.alloc, cap * sizeof(int) + 1);
    if (!cnt || !start || !mark || !adj) goto oom;
    /* upper bound per node: sum over its elements of npe, then deduplicate */
    memset(cnt, 0, ((size_t)nn + 1) * sizeof(int));
    for (e = 0; e < m->nelem; ++e)
        for (a = 0; a < npe; ++a) {
            int id = m->conn[(size_t)e * npe + a];
            if (id < 0 || id >= nn) {
                gk_free(&z.alloc, cnt), gk_free(&z.alloc, start), gk_free(&z.alloc, mark),
                    gk_free(&z.alloc, adj);
                return gk_err_set(err, GK_ERR_MESH, "element %d: node id %d out of range", e, id);
            }
            cnt[id] += npe;
        }
    start[0] = 0;
    for (a = 0; a < nn; ++a) start[a + 1] = start[a] + cnt[a], cnt[a] = 0, mark[a] = -1;
    for (e = 0; e < m->nelem; ++e)
        for (a = 0; a < npe; ++a) {
            int ia = m->conn[(size_t)e * npe + a];
            for (b = 0; b < npe; ++b) adj[start[ia] + cnt[ia]++] = m->conn[(size_t)e * npe + b];
        }
    z.n = dim * nn;
    z.rowptr = (int *)gk_alloc(&z.alloc, ((size_t)z.n + 1) * sizeof(int));
    if (!z.rowptr) goto oom;
    /* deduplicate and sort each node's neighbour list (insertion sort: short lists) */
    for (a = 0; a < nn; ++a) {
        int *L = adj + start[a], n = 0;
        for (k = 0; k < cnt[a]; ++k)
            if (mark[L[k]] != a) mark[L[k]] = a, L[n++] = L[k];
        for (k = 1; k < n; ++k) {
            int v = L[k], j = k - 1;
            while (j >= 0 && L[j] > v) L[j + 1] = L[j], --j;
            L[j + 1] = v;
        }
        cnt[a] = n;
    }
    z.rowptr[0] = 0;
    for (a = 0; a < nn; ++a)
        for (i = 0; i < dim; ++i) z.rowptr[dim * a + i + 1] = z.rowptr[dim * a + i] + dim * cnt[a];
    z.nnz = z.rowptr[z.n];
    z.col = (int *)gk_alloc(&z.alloc, (size_t)z.nnz * sizeof(int) + 1);
    z.val = (double *)gk_alloc(&z.alloc, (size_t)z.nnz * sizeof(double) + 1);
    if (!z.col || !z.val) goto oom;
    for (a = 0; a < nn; ++a)
        for (i = 0; i < dim; ++i) {
            int p = z.rowptr[dim * a + i];
            for (k = 0; k < cnt[a]; ++k)
                for (b = 0; b < dim; ++b) z.col[p++] = dim * adj[start[a] + k] + b;
        }
    memset(z.val, 0, (size_t)z.nnz * sizeof(double));
    gk_free(&z.alloc, cnt), gk_free(&z.alloc, start), gk_free(&z.alloc, mark), gk_free(&z.alloc, adj);
    *A = z;
    return GK_OK;
oom:
    gk_free(&z.alloc, cnt), gk_free(&z.alloc, start), gk_free(&z.alloc, mark), gk_free(&z.alloc, adj);
    gk_free(&z.alloc, z.rowptr), gk_free(&z.alloc, z.col), gk_free(&z.alloc, z.val);
    return gk_err_set(err, GK_ERR_ALLOC, "sparse matrix for %d nodes", nn);
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

/* -------------------------------------------------------------- tied dofs */
GKDEF gk_result gk_mesh_periodic_pairs(const gk_mesh *m, int axis, double lo, double hi, double tol,
                                       int *slave, int *master, int *npair, gk_err *err) {
    int dim = m->dim, a, b, k, i, nlo = 0, n = 0, *lon = NULL, *used = NULL, *ts = NULL, *tm = NULL;
    gk_result res = GK_OK;
    if (axis < 0 || axis >= dim) return gk_err_set(err, GK_ERR_ARG, "axis %d of a %dD mesh", axis, dim);
    if (!(tol >= 0.0) || !(fabs(lo) < HUGE_VAL) || !(fabs(hi) < HUGE_VAL) || !(hi - lo > 2.0 * tol))
        return gk_err_set(err, GK_ERR_ARG, "periodic planes x%d = %g and %g with tolerance %g", axis, lo, hi,
                          tol);
    lon = (int *)gk_alloc(&m->alloc, (size_t)m->nnode * sizeof(int) + 1);
    used = (int *)gk_alloc(&m->alloc, (size_t)m->nnode * sizeof(int) + 1);
    ts = (int *)gk_alloc(&m->alloc, (size_t)m->nnode * sizeof(int) + 1);
    tm = (int *)gk_alloc(&m->alloc, (size_t)m->nnode * sizeof(int) + 1);
    if (!lon || !used || !ts || !tm) {
        res = gk_err_set(err, GK_ERR_ALLOC, "periodic pairing of %d nodes", m->nnode);
        goto out;
    }
    for (a = 0; a < m->nnode; ++a)
        if (fabs(m->x[(size_t)a * dim + axis] - lo) <= tol) used[nlo] = 0, lon[nlo++] = a;
    for (a = 0; a < m->nnode; ++a) {
        const double *xa = m->x + (size_t)a * dim;
        int found = -1;
        if (!(fabs(xa[axis] - hi) <= tol)) continue;
        for (k = 0; k < nlo; ++k) {
            const double *xb = m->x + (size_t)lon[k] * dim;
            int same = 1;
            for (i = 0; i < dim; ++i)
                if (i != axis && !(fabs(xb[i] - xa[i]) <= tol)) same = 0;
            if (!same) continue;
            if (found >= 0) {
                res = gk_err_set(err, GK_ERR_MESH,
                                 "nodes %d and %d on x%d = %g both match node %d (duplicates?)", lon[found],
                                 lon[k], axis, lo, a);
                goto out;
            }
            found = k;
        }
        if (found < 0) {
            res =
                gk_err_set(err, GK_ERR_MESH, "node %d on x%d = %g has no partner on x%d = %g (tolerance %g)",
                           a, axis, hi, axis, lo, tol);
            goto out;
        }
        if (used[found]++) {
            res = gk_err_set(err, GK_ERR_MESH, "node %d on x%d = %g is the partner of two nodes", lon[found],
                             axis, lo);
            goto out;
        }
        ts[n] = a, tm[n++] = lon[found];
    }
    for (k = 0; k < nlo; ++k)
        if (!used[k]) {
            res =
                gk_err_set(err, GK_ERR_MESH, "node %d on x%d = %g has no partner on x%d = %g (tolerance %g)",
                           lon[k], axis, lo, axis, hi, tol);
            goto out;
        }
    for (b = 0; b < n; ++b) slave[b] = ts[b], master[b] = tm[b];
    *npair = n;
out:
    gk_free(&m->alloc, lon), gk_free(&m->alloc, used), gk_free(&m->alloc, ts), gk_free(&m->alloc, tm);
    return res;
}

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

/* ---------------------------------------------------------- nonlocal averaging */
GKDEF void gk_nonlocal_free(gk_nonlocal *nl) {
    gk_free(&nl->alloc, nl->start);
    gk_free(&nl->alloc, nl->nbr);
    gk_free(&nl->alloc, nl->w);
    memset(nl, 0, sizeof *nl);
}

/* bell weight of point b (with all its periodic images) seen from a */
static double gk__nl_weight(int dim, const double *xa, const double *xb, const double *period, double R) {
    int k, lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}, i0, i1, i2;
    double d[3] = {0, 0, 0}, w = 0.0;
    for (k = 0; k < dim; ++k) {
        d[k] = xb[k] - xa[k];
        if (period && period[k] > 0.0) { /* images k P with |d + k P| < R */
            lo[k] = (int)floor((-R - d[k]) / period[k]) + 1;
            hi[k] = (int)ceil((R - d[k]) / period[k]) - 1;
        }
    }
    for (i0 = lo[0]; i0 <= hi[0]; ++i0)
        for (i1 = lo[1]; i1 <= hi[1]; ++i1)
            for (i2 = lo[2]; i2 <= hi[2]; ++i2) {
                int im[3] = {i0, i1, i2};
                double r2 = 0.0;
                for (k = 0; k < dim; ++k) {
                    double e = d[k] + (im[k] ? im[k] * period[k] : 0.0);
                    r2 += e * e;
                }
                w += gk_nonlocal_bell(sqrt(r2), R);
            }
    return w;
}

GKDEF gk_result gk_nonlocal_build(gk_nonlocal *nl, int dim, int n, const double *x, double R, const double *period,
                                  const gk_allocator *alloc, gk_err *err) {
    gk_nonlocal z;
    size_t cnt = 0, cap;
    int I, J, k;
    memset(&z, 0, sizeof z);
    if (alloc) z.alloc = *alloc;
    if (dim < 1 || dim > 3 || n < 1 || !x)
        return gk_err_set(err, GK_ERR_ARG, "nonlocal: dimension %d, %d points", dim, n);
    if (!(R >= 0.0) || !isfinite(R)) return gk_err_set(err, GK_ERR_ARG, "nonlocal: radius %g must be >= 0", R);
    for (k = 0; k < n * dim; ++k)
        if (!isfinite(x[k])) return gk_err_set(err, GK_ERR_NAN, "nonlocal: coordinate %d of point %d is %g", k % dim, k / dim, x[k]);
    if (period)
        for (k = 0; k < dim; ++k) {
            if (!(period[k] >= 0.0) || !isfinite(period[k]) || (period[k] > 0.0 && !(R / period[k] < 1000.0)))
                return gk_err_set(err, GK_ERR_ARG, "nonlocal: period %g along axis %d (radius %g)", period[k], k, R);
        }
    /* count, then fill: neighbours in ascending order */
    for (I = 0; I < n; ++I)
        for (J = 0; J < n; ++J)
            if (J == I || gk__nl_weight(dim, x + (size_t)dim * I, x + (size_t)dim * J, period, R) > 0.0) ++cnt;
    cap = cnt;
    z.start = (int *)gk_alloc(&z.alloc, ((size_t)n + 1) * sizeof(int));
    z.nbr = (int *)gk_alloc(&z.alloc, cap * sizeof(int));
    z.w = (double *)gk_alloc(&z.alloc, cap * sizeof(double));
    if (!z.start || !z.nbr || !z.w) {
        gk_nonlocal_free(&z);
        return gk_err_set(err, GK_ERR_ALLOC, "nonlocal: %lu neighbour pairs", (unsigned long)cap);
    }
    cnt = 0;
    for (I = 0; I < n; ++I) {
        double sum = 0.0;
        size_t b = cnt, c;
        z.start[I] = (int)cnt;
        for (J = 0; J < n; ++J) {
            double a = gk__nl_weight(dim, x + (size_t)dim * I, x + (size_t)dim * J, period, R);
            if (J == I && !(a > 0.0)) a = 1.0; /* R = 0: the point alone */
            if (!(a > 0.0)) continue;
            z.nbr[cnt] = J;
            z.w[cnt++] = a;
            sum += a;
        }
        for (c = b; c < cnt; ++c) z.w[c] /= sum; /* eq A.4 */
    }
    z.start[n] = (int)cnt;
    z.n = n;
    z.R = R;
    *nl = z;
    return GK_OK;
}

GKDEF void gk_nonlocal_apply(const gk_nonlocal *nl, int ncomp, const double *in, double *out) {
    int I, c, p;
    for (I = 0; I < nl->n; ++I) {
        double *o = out + (size_t)ncomp * I;
        for (c = 0; c < ncomp; ++c) o[c] = 0.0;
        for (p = nl->start[I]; p < nl->start[I + 1]; ++p) {
            const double *v = in + (size_t)ncomp * nl->nbr[p];
            double w = nl->w[p];
            for (c = 0; c < ncomp; ++c) o[c] += w * v[c];
        }
    }
}

#endif /* GK_FEM implementation */
