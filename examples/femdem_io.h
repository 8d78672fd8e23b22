/* femdem_io.h - the outputs and the checkpoint of the FEMxDEM drivers (examples, not library).
 *
 * For the model of femdem.h: the Gauss-point fields (fd_gp_fields, from gk_twoscale_fields), the VTK of
 * the Gauss points and of the deformed mesh, SVG maps and plots, the CSV writer of the drivers' rows,
 * and the checkpoint: the RVE set's own file (gk_twoscale_save: versioned, checksummed) carrying this
 * model's block (fd_ck_save / fd_ck_load; a driver appends its own bytes). Rank 0 writes (M->root);
 * every function returns non-zero after saying once that a write failed, on every rank.
 */
#ifndef FEMDEM_IO_H
#define FEMDEM_IO_H

#include "femdem.h"

/* ------------------------------------------------------------- outputs */
static const char *fd_field_names[FD_NFIELD] = {"eps_q",        "eps_v",    "void_ratio", "rotation_deg",
                                                "spin_deg",     "p",        "q",          "fabric_anisotropy",
                                                "coordination", "dem_steps"};

/* the Gauss-point fields of the converged state, FD_NFIELD per point (all ranks call it): eps_q,
 * eps_v compression-positive as the paper, void ratio, particle rotation and spin [deg], p, q,
 * |F_a|, Z, DEM steps. NULL when out of memory. */
static double *fd_gp_fields(fd_model *M) {
    gk_twoscale_field *f = (gk_twoscale_field *)malloc((size_t)M->ngp * sizeof *f);
    double *v = (double *)malloc((size_t)M->ngp * FD_NFIELD * sizeof *v);
    int g, bad = !f || !v;
    if (gk_twoscale_fields(&M->ts, bad ? NULL : f)) bad = 1;
    for (g = 0; g < M->ngp && !bad; ++g) {
        double *x = v + FD_NFIELD * (size_t)g;
        x[0] = f[g].eps_q, x[1] = -f[g].eps_v, x[2] = f[g].void_ratio;
        x[3] = f[g].rotation * 180.0 / FD_PI, x[4] = f[g].spin * 180.0 / FD_PI;
        x[5] = f[g].p, x[6] = f[g].q, x[7] = f[g].fabric, x[8] = f[g].coordination, x[9] = f[g].dem_steps;
    }
    free(f);
    if (bad) free(v), v = NULL;
    return v;
}

/* gp_NNNN.vtk (the fields at the Gauss points) and mesh_NNNN.vtk (the deformed mesh, displacement) */
static int fd_write_vtk(fd_model *M, int step) {
    char path[1200];
    gk_vtk v;
    int nn = M->mesh.nnode, big = M->ngp > nn ? M->ngp : nn, g, k, a, bad = 0;
    double *all = fd_gp_fields(M), *xyz = (double *)malloc((size_t)big * 3 * sizeof(double)),
           *val = (double *)malloc((size_t)M->ngp * sizeof(double)),
           *d3 = (double *)malloc((size_t)nn * 3 * sizeof(double));
    int *conn = (int *)malloc((size_t)M->ngp * sizeof(int));
    if (!all || !xyz || !val || !d3 || !conn) {
        fd_say(M, "%s: out of memory writing VTK\n", M->prog);
        bad = 1;
    }
    if (!bad && M->root) {
        for (g = 0; g < M->ngp; ++g) {
            gk_mesh_point(&M->mesh, g / M->q.n, M->q.xi[g % M->q.n], xyz + 3 * g);
            conn[g] = g;
        }
        snprintf(path, sizeof path, "%s/gp_%04d.vtk", M->o.out, step);
        bad = gk_vtk_open(&v, path, "grainkit FEMxDEM Gauss points") != GK_OK ||
              gk_vtk_points(&v, M->ngp, xyz) || gk_vtk_cells(&v, M->ngp, 1, conn, GK_VTK_VERTEX);
        for (k = 0; k < FD_NFIELD && !bad; ++k) {
            for (g = 0; g < M->ngp; ++g) val[g] = all[FD_NFIELD * g + k];
            bad = gk_vtk_point_scalar(&v, fd_field_names[k], val) != GK_OK;
        }
        if (v.fp) bad |= gk_vtk_close(&v) != GK_OK;
        if (!bad) {
            for (a = 0; a < nn; ++a) {
                xyz[3 * a] = M->mesh.x[2 * a], xyz[3 * a + 1] = M->mesh.x[2 * a + 1], xyz[3 * a + 2] = 0.0;
                d3[3 * a] = M->utot[2 * a], d3[3 * a + 1] = M->utot[2 * a + 1], d3[3 * a + 2] = 0.0;
            }
            snprintf(path, sizeof path, "%s/mesh_%04d.vtk", M->o.out, step);
            bad = gk_vtk_open(&v, path, "grainkit FEMxDEM mesh") || gk_vtk_points(&v, nn, xyz) ||
                  gk_vtk_cells(&v, M->mesh.nelem, M->npe, M->mesh.conn,
                               M->npe == 8 ? GK_VTK_QUAD8 : GK_VTK_QUAD) ||
                  gk_vtk_point_vector(&v, "displacement", d3);
            if (v.fp) bad |= gk_vtk_close(&v) != GK_OK;
        }
        if (bad) fprintf(stderr, "%s: cannot write %s\n", M->prog, path);
    }
    free(all), free(xyz), free(val), free(d3), free(conn);
    return fd_agree(M, bad);
}

/* a Gauss-point field (fd_gp_fields index) times `scale` (100: a strain in %) as a map in mm: each
 * Gauss point owns the sub-quad of its element around it; the platens (the bottom and top node rows)
 * drawn on top; label: the colour bar's quantity with its unit; range [vmin, vmax] fixed when
 * vmax > vmin (values beyond take the end colours), else the field's own */
static int fd_write_field_svg(fd_model *M, int field, double scale, const char *file, const char *title,
                              const char *label, double vmin, double vmax) {
    int per = M->o.quad, e, i, j, c, a, g = 0, bad = 0, len[2] = {2, 2};
    double *all = fd_gp_fields(M), *xy = (double *)malloc((size_t)M->ngp * 8 * sizeof(double)),
           *val = (double *)malloc((size_t)M->ngp * sizeof(double)), line[8], lo = HUGE_VAL, hi = -HUGE_VAL,
           yt = 0;
    char path[1200];
    gk_err err;
    gk_field_def d;
    if (!all || !xy || !val) bad = 1;
    if (!bad && M->root) {
        for (e = 0; e < M->mesh.nelem; ++e)
            for (j = 0; j < per; ++j)
                for (i = 0; i < per; ++i, ++g) {
                    static const int ci[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
                    for (c = 0; c < 4; ++c) {
                        double xi[3], x[3];
                        xi[0] = -1 + 2.0 * (i + ci[c][0]) / per, xi[1] = -1 + 2.0 * (j + ci[c][1]) / per,
                        xi[2] = 0;
                        gk_mesh_point(&M->mesh, e, xi, x);
                        xy[8 * g + 2 * c] = x[0], xy[8 * g + 2 * c + 1] = x[1];
                    }
                    val[g] = scale * all[FD_NFIELD * g + field];
                }
        for (a = 0; a < M->mesh.nnode; ++a) { /* the platens span the specimen's extent in x */
            if (M->mesh.x[2 * a] < lo) lo = M->mesh.x[2 * a];
            if (M->mesh.x[2 * a] > hi) hi = M->mesh.x[2 * a];
        }
        for (a = 0; a < M->ntop; ++a) yt += M->mesh.x[2 * M->top[a] + 1] / M->ntop;
        line[0] = lo, line[1] = 0.0, line[2] = hi, line[3] = 0.0, line[4] = lo, line[5] = yt, line[6] = hi,
        line[7] = yt;
        memset(&d, 0, sizeof d);
        d.title = title, d.label = label, d.xlabel = "x [mm]", d.ylabel = "y [mm]", d.coord_scale = 1e3;
        d.fixed_range = vmax > vmin, d.vmin = vmin, d.vmax = vmax;
        d.nlines = 2, d.line_len = len, d.line_xy = line;
        snprintf(path, sizeof path, "%s/%s", M->o.out, file);
        bad = gk_field_svg(path, &d, M->ngp, 4, xy, val, &err) != GK_OK;
    }
    if (bad) fd_say(M, "%s: cannot write %s/%s\n", M->prog, M->o.out, file);
    free(all), free(xy), free(val);
    return fd_agree(M, bad);
}

/* an x-y plot, said once when it cannot be written */
static int fd_plot(const fd_model *M, const gk_plot *pl, const char *file) {
    char path[1200];
    gk_err err;
    int bad = 0;
    if (M->root) {
        snprintf(path, sizeof path, "%s/%s", M->o.out, file);
        bad = gk_plot_svg(pl, path, &err) != GK_OK;
        if (bad) fprintf(stderr, "%s: cannot write %s\n", M->prog, path);
    }
    return fd_agree(M, bad);
}

/* the columns both CSVs end with, and their values */
#define FD_WORK_COLS "dem_steps_mean,dem_steps_max,dem_steps,tangents_reused,tangents_computed"
static void fd_csv_work(FILE *fp, const fd_row *c) {
    fprintf(fp, "%.2f,%d,%lld,%lld,%lld\n", c->dem_mean, c->dem_max, c->dem_total, c->t_reused,
            c->t_computed);
}

/* a CSV written by rank 0 through row(fp, M, k, user) after its header; said once when it fails */
static int fd_write_csv(const fd_model *M, const char *file, const char *header,
                        void (*row)(FILE *fp, const fd_model *M, int k, const void *user), const void *user) {
    char path[1200];
    FILE *fp;
    int k, bad = 0;
    if (M->root) {
        snprintf(path, sizeof path, "%s/%s", M->o.out, file);
        fp = fopen(path, "w");
        bad = !fp;
        if (fp) {
            fputs(header, fp);
            for (k = 0; k < M->ncurve; ++k) row(fp, M, k, user);
            bad = ferror(fp) != 0;
            bad |= fclose(fp) != 0;
        }
        if (bad) fprintf(stderr, "%s: cannot write %s\n", M->prog, path);
    }
    return fd_agree(M, bad);
}

/* ---------------------------------------------------------- checkpoint */
/* DIR/checkpoint.bin: the set's file (every RVE's converged state, accumulated dH, tangent-reuse
 * reference; gk_twoscale_save) with this model's block: a tag naming the test and its format, the mesh
 * options, the step counters, the rows, the mesh, the displacements, the converged stresses and
 * tangents, the driver's own bytes (cyclic state, predictor increment). A block of another test or
 * mesh is refused by name. */
typedef struct fd_buf {
    unsigned char *b;
    size_t n, cap, pos;
    int bad;
} fd_buf;

static void fd_put(fd_buf *B, const void *p, size_t n) {
    if (B->bad || !n) return;
    if (B->n + n > B->cap) {
        size_t c = 2 * (B->n + n) + 256;
        unsigned char *x = (unsigned char *)realloc(B->b, c);
        if (!x) {
            B->bad = 1;
            return;
        }
        B->b = x, B->cap = c;
    }
    memcpy(B->b + B->n, p, n);
    B->n += n;
}
static int fd_get(fd_buf *B, void *p, size_t n) {
    if (B->bad || n > B->n - B->pos) return B->bad = 1, 1;
    memcpy(p, B->b + B->pos, n);
    B->pos += n;
    return 0;
}

static int fd_ck_save(fd_model *M, const char *tag, const fd_buf *extra) {
    char path[1200];
    char tg[16];
    fd_buf B;
    int bad;
    size_t n = (size_t)M->ndof, g9 = 9 * (size_t)M->ngp, g16 = 16 * (size_t)M->ngp;
    memset(&B, 0, sizeof B);
    memset(tg, 0, sizeof tg);
    strncpy(tg, tag, sizeof tg - 1);
    fd_put(&B, tg, 16);
    fd_put(&B, &M->o.nx, sizeof(int)), fd_put(&B, &M->o.ny, sizeof(int));
    fd_put(&B, &M->o.elem, sizeof M->o.elem), fd_put(&B, &M->o.quad, sizeof(int));
    fd_put(&B, &M->step, sizeof(int)), fd_put(&B, &M->eps_done, sizeof(double));
    fd_put(&B, &M->scale, sizeof(double)), fd_put(&B, &M->ncurve, sizeof(int));
    fd_put(&B, M->curve, (size_t)M->ncurve * sizeof(fd_row));
    fd_put(&B, M->mesh.x, n * sizeof(double)), fd_put(&B, M->utot, n * sizeof(double));
    fd_put(&B, M->sig_n, g9 * sizeof(double)), fd_put(&B, M->D_n, g16 * sizeof(double));
    if (extra) fd_put(&B, extra->b, extra->n);
    snprintf(path, sizeof path, "%s/checkpoint.bin", M->o.out);
    bad = B.bad;
    if (!bad && gk_twoscale_save(&M->ts, path, B.b, B.n)) bad = 1;
    if (bad && B.bad)
        fd_say(M, "%s: cannot write %s: out of memory\n", M->prog, path);
    else if (bad)
        fd_say(M, "%s: %s\n", M->prog, gk_twoscale_error(&M->ts)); /* names the file */
    free(B.b);
    return bad;
}

/* every entry of v[n] finite and within lim */
static int fd_ck_bounded(const double *v, size_t n, double lim) {
    size_t k;
    for (k = 0; k < n; ++k)
        if (!(fabs(v[k]) <= lim)) return 0;
    return 1;
}

/* the model's block of a checkpoint, read and checked, not yet in the model */
typedef struct fd_ck {
    int step, nc;
    double eps, scale;
    fd_row *rows;
    double *v; /* the node coordinates, the displacements (ndof each), sig_n (9 ngp), D_n (16 ngp) */
} fd_ck;

static void fd_ck_free(fd_ck *ck) {
    free(ck->rows), free(ck->v);
    ck->rows = NULL, ck->v = NULL;
}

/* the block's values checked: the step counters and rows in range (their sums without overflow),
 * the nodes where the initial ones plus the displacements put them (at most 10 specimen sizes away;
 * the two sums of the same increments differ by rounding only) with every element's det J > 0, the
 * stresses and tangents finite within 1e100. 0, or 1 with the reason in why. */
static int fd_ck_check(const fd_model *M, const fd_ck *ck, char *why, size_t nwhy) {
    size_t n = (size_t)M->ndof, k;
    const double *x = ck->v, *u = ck->v + n;
    double L = 0.0;
    long long sum[3] = {0, 0, 0};
    int c;
    gk_mesh m;
    gk_err e;
    /* the loop adds 1 to the step and runs from eps to --steps x --increment; the cut-back scale
     * halves from 1 and the driver gives up below 1/16 */
    if (ck->step < 0 || ck->step > 1000000000 || !(ck->eps >= 0.0 && ck->eps < 1.0) ||
        !(ck->scale >= 1.0 / 64 && ck->scale <= 1.0))
        return snprintf(why, nwhy, "step %d, axial strain %g or increment scale %g out of range", ck->step,
                        ck->eps, ck->scale),
               1;
    for (c = 0; c < ck->nc; ++c) {
        const fd_row *r = &ck->rows[c];
        double d[9];
        long long w[3];
        int bad;
        d[0] = r->eps, d[1] = r->syy, d[2] = r->sxx, d[3] = r->ev, d[4] = r->secs, d[5] = r->Ed, d[6] = r->Ef;
        d[7] = r->inc, d[8] = r->dem_mean;
        w[0] = r->dem_total, w[1] = r->t_reused, w[2] = r->t_computed;
        bad = !fd_ck_bounded(d, 9, 1e100) || r->iters < 0 || r->failed < 0 || r->failed > M->ngp ||
              r->dem_max < 0;
        for (k = 0; k < 3 && !bad; ++k) { /* the run's totals are their sums */
            bad = w[k] < 0 || w[k] > LLONG_MAX / 2 - sum[k];
            sum[k] += bad ? 0 : w[k];
        }
        if (bad) return snprintf(why, nwhy, "row %d is out of range", c), 1;
    }
    for (k = 0; k < n; ++k) L = fmax(L, fabs(M->A0x[k]));
    for (k = 0; k < n; ++k)
        if (!(fabs(u[k]) <= 10 * L) || !(fabs(x[k] - (M->A0x[k] + u[k])) <= 1e-8 * L))
            return snprintf(why, nwhy, "the mesh does not match its displacements (dof %d)", (int)k), 1;
    m = M->mesh, m.x = ck->v;
    if (gk_mesh_check(&m, &M->q, &e) != GK_OK)
        return snprintf(why, nwhy, "the deformed mesh: %.150s", e.msg), 1;
    if (!fd_ck_bounded(ck->v + 2 * n, 25 * (size_t)M->ngp, 1e100))
        return snprintf(why, nwhy, "a stress or tangent is not finite or beyond 1e100"), 1;
    return 0;
}

/* rows of room in the curve after a restart (fd_ck_apply; a driver's per-row arrays take as many) */
#define FD_CK_ROOM 16

/* ck into the model (and freed); 0, or 1 (out of memory: the model as it was, err set) */
static int fd_ck_apply(fd_model *M, fd_ck *ck, gk_err *err) {
    size_t n = (size_t)M->ndof, g9 = 9 * (size_t)M->ngp;
    fd_row *c = (fd_row *)realloc(M->curve, ((size_t)ck->nc + FD_CK_ROOM) * sizeof *c);
    if (!c) return fd_ck_free(ck), gk_err_set(err, GK_ERR_ALLOC, "out of memory"), 1;
    M->curve = c, M->cap = ck->nc + FD_CK_ROOM, M->ncurve = ck->nc;
    memcpy(M->curve, ck->rows, (size_t)ck->nc * sizeof(fd_row));
    M->step = ck->step, M->eps_done = ck->eps, M->scale = ck->scale;
    memcpy(M->mesh.x, ck->v, n * sizeof(double)), memcpy(M->utot, ck->v + n, n * sizeof(double));
    memcpy(M->sig_n, ck->v + 2 * n, g9 * sizeof(double));
    memcpy(M->D_n, ck->v + 2 * n + g9, 16 * (size_t)M->ngp * sizeof(double));
    fd_ck_free(ck);
    return 0;
}

/* the driver's own part of its block (after the model's), read from B, checked, and kept in user: 0,
 * or 1 (refused) or 2 (out of memory) with the reason in why; nothing of the model written (fd_ck_load) */
typedef int (*fd_part_fn)(fd_model *M, fd_buf *B, const fd_ck *ck, void *user, char *why, size_t nwhy);

typedef struct fd_take {
    fd_model *M;
    const char *tag;
    fd_part_fn part;
    void *user;
    int oom;
} fd_take;

/* fd_ck_load's take (gk_twoscale_load_take): the model's block read and checked into ck, the driver's
 * part checked, then the model written (fd_ck_apply) */
static int fd_take_block(const void *blk, size_t nb, void *user, char *why, size_t nwhy) {
    fd_take *t = (fd_take *)user;
    fd_model *M = t->M;
    size_t n = (size_t)M->ndof, nv = 2 * n + 25 * (size_t)M->ngp;
    fd_buf B;
    fd_ck ck;
    char tg[16];
    int nx, ny, quad, ok, pr = 0;
    gk_elem_type el;
    gk_err e;
    memset(&B, 0, sizeof B);
    memset(&ck, 0, sizeof ck);
    B.b = (unsigned char *)malloc(nb + 1), B.n = B.cap = nb;
    if (!B.b) return t->oom = 1, snprintf(why, nwhy, "out of memory"), 1;
    memcpy(B.b, blk, nb);
    ok = !fd_get(&B, tg, 16) && !memcmp(tg, t->tag, strlen(t->tag) + 1);
    ok = ok && !fd_get(&B, &nx, sizeof nx) && !fd_get(&B, &ny, sizeof ny) && !fd_get(&B, &el, sizeof el) &&
         !fd_get(&B, &quad, sizeof quad);
    if (!ok || nx != M->o.nx || ny != M->o.ny || el != M->o.elem || quad != M->o.quad) {
        free(B.b);
        return snprintf(why, nwhy,
                        "not a checkpoint of this test and mesh (%s %dx%d, element, quad must match)", t->tag,
                        M->o.nx, M->o.ny),
               1;
    }
    ok = !fd_get(&B, &ck.step, sizeof(int)) && !fd_get(&B, &ck.eps, sizeof(double)) &&
         !fd_get(&B, &ck.scale, sizeof(double)) && !fd_get(&B, &ck.nc, sizeof(int)) && ck.nc >= 1 &&
         (size_t)ck.nc <= (B.n - B.pos) / sizeof(fd_row) &&
         nv <= (B.n - B.pos - (size_t)ck.nc * sizeof(fd_row)) / sizeof(double);
    if (ok && (!(ck.rows = (fd_row *)malloc((size_t)ck.nc * sizeof(fd_row))) ||
               !(ck.v = (double *)malloc(nv * sizeof(double))))) {
        fd_ck_free(&ck), free(B.b);
        return t->oom = 1, snprintf(why, nwhy, "out of memory"), 1;
    }
    ok = ok && !fd_get(&B, ck.rows, (size_t)ck.nc * sizeof(fd_row)) && !fd_get(&B, ck.v, nv * sizeof(double));
    if (!ok) snprintf(why, nwhy, "the driver's block is truncated");
    if (!ok || fd_ck_check(M, &ck, why, nwhy) || (pr = t->part(M, &B, &ck, t->user, why, nwhy)) != 0) {
        fd_ck_free(&ck), free(B.b);
        if (pr == 2) t->oom = 1;
        return 1;
    }
    free(B.b);
    if (fd_ck_apply(M, &ck, &e)) return t->oom = 1, snprintf(why, nwhy, "out of memory"), 1;
    return 0;
}

/* the checkpoint of DIR into the set and the model, or neither: the model's block read and checked
 * (fd_ck_check), the driver's part read, checked and kept in user (part), then the model written, all
 * before the set takes the file's states (gk_twoscale_load_take). The driver then puts its part into
 * its model. 0, or 1 with err set naming the file (what part kept in user is the caller's to free). */
static int fd_ck_load(fd_model *M, const char *dir, const char *tag, fd_part_fn part, void *user,
                      gk_err *err) {
    char path[1200];
    fd_take t;
    snprintf(path, sizeof path, "%s/checkpoint.bin", dir);
    t.M = M, t.tag = tag, t.part = part, t.user = user, t.oom = 0;
    if (gk_twoscale_load_take(&M->ts, path, fd_take_block, &t))
        return gk_err_set(err, t.oom ? GK_ERR_ALLOC : GK_ERR_FORMAT, "%s", gk_twoscale_error(&M->ts)), 1;
    return 0;
}

#endif /* FEMDEM_IO_H */
