/* gk_mesh.h - meshes for the macro scale of FEMxDEM.          (grainkit v0.1)
 *
 * The gk_mesh (nodes, one element type, connectivity, physical tags) the
 * finite elements of gk_fem.h work on: structured meshes, the Gmsh reader,
 * geometric queries and the sparsity pattern of its nodal dofs.
 *
 * DO THIS: #define GK_IMPLEMENTATION (or GK_MESH_IMPLEMENTATION) in one file.
 * The mesh is checked and interpolated with the elements of gk_fem.h
 * (shape functions, det J): its implementation includes and implements
 * gk_fem.h (and gk_sparse.h) too.
 *
 * ELEMENT TYPES (node order = Gmsh = VTK; gk_fem.h has the elements and their
 * Gauss rules)
 *   GK_Q4 (4 nodes), GK_Q8 (8-node serendipity), GK_HEX8 (8 nodes); at most
 *   GK_FEM_MAX_NPE nodes per element. A gk_quad (a Gauss rule, gk_quad_rule
 *   of gk_fem.h) holds at most GK_FEM_MAX_GP points.
 *
 * WHAT IS HERE
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
 *   gk_mesh_periodic_pairs  nodes on the plane x_axis = hi paired with the
 *                           nodes on x_axis = lo at the same other coordinates
 *
 * Units as gk_base.h: SI. Node ids are 0-based; dof = dim*node + component.
 *
 * LICENCE: MIT (see gk_base.h).
 */
#ifndef GK_MESH_H
#define GK_MESH_H

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

#ifdef __cplusplus
extern "C" {
#endif

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
GKDEF gk_result gk_mesh_periodic_pairs(const gk_mesh *m, int axis, double lo, double hi, double tol,
                                       int *slave, int *master, int *npair, gk_err *err);

#ifdef __cplusplus
}
#endif

#endif /* GK_MESH_H */

/* ======================================================== IMPLEMENTATION */
/* after the declarations of gk_fem.h (gk_fem_jacobian, gk_fem_shape) and
 * within its implementation: included from gk_fem.h when it is not there yet */
#if (defined(GK_IMPLEMENTATION) || defined(GK_MESH_IMPLEMENTATION) || defined(GK_FEM_IMPLEMENTATION) || \
     defined(GK_DOFMAP_IMPLEMENTATION)) &&                                                              \
    !defined(GK_MESH_IMPL_ONCE)
#ifndef GK_FEM_H
#include "gk_fem.h"
#endif
#if defined(GK__FEM_DECLS) && defined(GK_FEM_IMPL_ONCE) && !defined(GK_MESH_IMPL_ONCE)
#define GK_MESH_IMPL_ONCE

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* ------------------------------------------- periodic node pairs (for gk_dofmap.h) */
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

#endif
#endif /* GK_MESH implementation */
