/* femdem_biaxial.h - the biaxial test of the FEMxDEM model (examples, not library): its options, its
 * loading loop, its outputs and its checkpoint; shared by femdem_biaxial.c (which adds the
 * single-element test) and femdem_probe.c (which adds the Newton diagnostics). See femdem_biaxial.c
 * for the test and its outputs.
 */
#ifndef FEMDEM_BIAXIAL_H
#define FEMDEM_BIAXIAL_H

#include "femdem_io.h"
#include "femdem_newton.h"

#define FDB_TAG "GKFEMDEM5" /* checkpoint block of the biaxial and single-element tests */
#define FDB_MAX_FIELDS_AT 16
#define FDB_FABRIC_LABEL "F_a [-]"

/* the biaxial defaults (Guo & Zhao 2014: 50 x 100 mm, 100 kPa, the authors' 8 x 16 Q8 mesh and RVE) */
static void fdb_defaults(fd_model *M) {
    fd_opts *o = &M->o;
    fd_opts_default(o);
    o->nx = 8, o->ny = 16, o->width = 0.05, o->height = 0.1, o->pressure = 1e5, o->vtk_every = 1;
    o->packing = "examples/data/rve400.txt", o->test = "biaxial";
}

/* the biaxial test's own options */
static const cli_opt *fdb_opts(fd_opts *o) {
    static cli_opt t[5];
    const cli_opt src[] = {{"--steps", CLI_INT, &o->steps, 1, 1000000, NULL, NULL, 0},
                           {"--test", CLI_STR, &o->test, 0, 0, NULL, NULL, 0},
                           {"--fields-at", CLI_STR, &o->fields_at, 0, 0, NULL, NULL, 0},
                           {"--cost-log", CLI_STR, &o->cost_log, 0, 0, NULL, NULL, 0},
                           {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    memcpy(t, src, sizeof src);
    return t;
}

/* --fields-at A,B,...: axial strains [%] into v (at most FDB_MAX_FIELDS_AT); their number, or -1 when
 * the list is not one of positive finite numbers */
static int fdb_fields_at(const char *list, double *v) {
    const char *p = list;
    int n = 0;
    if (!list || !*list) return 0;
    for (;;) {
        char *end;
        double x;
        errno = 0;
        x = strtod(p, &end);
        if (end == p || errno || !isfinite(x) || !(x > 0) || n == FDB_MAX_FIELDS_AT) return -1;
        v[n++] = x;
        if (*end == '\0') return n;
        if (*end != ',') return -1;
        p = end + 1;
    }
}

/* after parsing: --test biaxial|single (single: one Q4 element, 2 x 2 Gauss points). 0, or 2 */
static int fdb_check(fd_model *M) {
    fd_opts *o = &M->o;
    if (!strncmp(o->test, "cyclic", 6)) {
        fd_say(M, "%s: the cyclic simple-shear tests are build/femdem_cyclic --test %s\n", M->prog, o->test);
        return 2;
    }
    if (!strcmp(o->test, "single"))
        o->nx = 1, o->ny = 1, o->elem_kind = 0 /* q4 */, o->quad = 2;
    else if (strcmp(o->test, "biaxial")) {
        fd_say(M, "%s: --test '%s' must be biaxial or single\n", M->prog, o->test);
        return 2;
    }
    {
        double v[FDB_MAX_FIELDS_AT];
        if (fdb_fields_at(o->fields_at, v) < 0) {
            fd_say(M,
                   "%s: --fields-at '%s' is not a list of at most %d positive axial strains in %% (4,4.8)\n",
                   M->prog, o->fields_at, FDB_MAX_FIELDS_AT);
            return 2;
        }
    }
    if (strchr(o->packing, ',') && !strcmp(o->test, "single")) {
        fd_say(M, "%s: --test single compares the mesh with one RVE alone: give one --packing\n", M->prog);
        return 2;
    }
    return fd_opts_finish(M->root ? M->prog : NULL, o);
}

static void fdb_csv_row(FILE *fp, const fd_model *M, int k, const void *user) {
    const fd_row *c = &M->curve[k];
    (void)user;
    fprintf(fp, "%d,%.9g,%.9g,%.9g,%.9g,%d,%.4f,%.4g,%.4g,%.6g,%d,", k, c->eps, c->syy, c->sxx, c->ev,
            c->iters, c->secs, c->Ed, c->Ef, c->inc, c->failed);
    fd_csv_work(fp, c);
}

static int fdb_write_csv(const fd_model *M) {
    return fd_write_csv(
        M, "biaxial.csv",
        "step,eps_axial,sigma_yy,sigma_xx,eps_v,iterations,seconds,E_d,E_f,increment,failed_gp," FD_WORK_COLS
        "\n",
        fdb_csv_row, NULL);
}

static int fdb_checkpoint(fd_model *M) {
    fd_buf x;
    int bad;
    memset(&x, 0, sizeof x);
    fd_put(&x, &M->inclast, sizeof(double)); /* the extrapolated predictor's last increment (always kept) */
    fd_put(&x, M->ulast, (size_t)M->ndof * sizeof(double));
    fd_put(&x, M->hist, (size_t)M->ncurve * M->ngp * FD_NFIELD * sizeof(double));
    bad = x.bad || fd_ck_save(M, FDB_TAG, &x);
    free(x.b);
    return bad;
}

/* the driver's part of a checkpoint (fd_ck_load's part): the predictor's last increment (at most 1,
 * and zero or above 1e-12), its displacements (within 10 x the specimen) and the fields of every row
 * (within 1e100), the exact length first (no allocation from a row count the file does not hold) */
typedef struct fdb_part {
    double inclast, *ulast, *hist;
} fdb_part;

static int fdb_part_read(fd_model *M, fd_buf *B, const fd_ck *ck, void *user, char *why, size_t nwhy) {
    fdb_part *p = (fdb_part *)user;
    size_t nh = (size_t)M->ngp * FD_NFIELD, n = (size_t)M->ndof, k;
    double L = 0.0;
    for (k = 0; k < n; ++k) L = fmax(L, fabs(M->A0x[k]));
    if ((B->n - B->pos) / sizeof(double) != 1 + n + (size_t)ck->nc * nh || (B->n - B->pos) % sizeof(double))
        return snprintf(why, nwhy, "the driver's block has the wrong length"), 1;
    if (!(p->ulast = (double *)malloc(n * sizeof(double) + 1)) ||
        !(p->hist = (double *)malloc((size_t)ck->nc * nh * sizeof(double) + 1)))
        return snprintf(why, nwhy, "out of memory"), 2;
    fd_get(B, &p->inclast, sizeof(double)), fd_get(B, p->ulast, n * sizeof(double));
    fd_get(B, p->hist, (size_t)ck->nc * nh * sizeof(double));
    if (!(fabs(p->inclast) <= 1.0) || (p->inclast != 0.0 && !(fabs(p->inclast) >= 1e-12)) ||
        !fd_ck_bounded(p->ulast, n, 10 * L) || !fd_ck_bounded(p->hist, (size_t)ck->nc * nh, 1e100))
        return snprintf(why, nwhy,
                        "the last increment, its displacements or a row's fields are out of range"),
               1;
    return 0;
}

/* --restart DIR: the checkpoint into the set and the model, or neither (fd_ck_load with the driver's
 * part above). 0, or 1 with err set. */
static int fdb_restart(fd_model *M, gk_err *err) {
    fdb_part p;
    memset(&p, 0, sizeof p);
    if (fd_ck_load(M, M->o.restart, FDB_TAG, fdb_part_read, &p, err)) {
        free(p.ulast), free(p.hist);
        return 1;
    }
    M->inclast = p.inclast;
    memcpy(M->ulast, p.ulast, (size_t)M->ndof * sizeof(double));
    free(p.ulast), free(M->hist);
    M->hist = p.hist;
    fd_say(M, "%s: restarted from %s/checkpoint.bin at step %d (axial strain %.3f %%)\n", M->prog,
           M->o.restart, M->step, 100 * M->eps_done);
    return 0;
}

/* boundary stresses (compression positive) and volumetric strain */
static void fdb_macro_state(const fd_model *M, double *syy, double *sxx, double *ev) {
    double fy = 0, fx = 0, w, h, area = 0.0, xr = 0, xl = 0, yt = 0;
    int a, e, g, nl = 0;
    for (a = 0; a < M->ntop; ++a) fy += M->fint[2 * M->top[a] + 1];
    for (a = 0; a < M->nright; ++a) fx += M->fint[2 * M->right[a]];
    /* current width and height: mean over the top and right node sets */
    for (a = 0; a < M->nright; ++a) xr += M->mesh.x[2 * M->right[a]];
    for (a = 0; a < M->mesh.nnode; ++a)
        if (fabs(M->A0x[2 * a]) < 1e-12) xl += M->mesh.x[2 * a], ++nl;
    for (a = 0; a < M->ntop; ++a) yt += M->mesh.x[2 * M->top[a] + 1];
    w = xr / M->nright - xl / nl;
    h = yt / M->ntop;
    *syy = -fy / w;
    *sxx = -fx / h;
    for (e = 0; e < M->mesh.nelem; ++e)
        for (g = 0; g < M->q.n; ++g) {
            double dN[16], dJ;
            gk_fem_jacobian(&M->mesh, e, M->q.xi[g], NULL, dN, &dJ, NULL);
            area += M->q.w[g] * dJ;
        }
    *ev = -(area - M->area0) / M->area0;
}

/* shear band from the eps_q field: points above the median + half the range; angle of their principal
 * axis from the horizontal (weighted by excess eps_q), width = sqrt(12 var) of the perpendicular
 * distances (a uniform band of width W has variance W^2/12); *mid: the band point nearest their
 * weighted centroid. No band (NAN, *mid = -1) if max eps_q < 1.5 x median. */
static int fdb_cmp_d(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}
static void fdb_band(fd_model *M, double *angle, double *width, int *mid) {
    double *all = fd_gp_fields(M), *v = (double *)malloc((size_t)M->ngp * sizeof(double)),
           *s = (double *)malloc((size_t)M->ngp * sizeof(double));
    double med, mx, thr, sw = 0, cx = 0, cy = 0, sxx = 0, syy = 0, sxy = 0, th, nx, ny, var = 0,
                         dmin = HUGE_VAL;
    int g;
    *angle = *width = NAN, *mid = -1;
    if (!all || !v || !s) goto out;
    for (g = 0; g < M->ngp; ++g) v[g] = s[g] = all[FD_NFIELD * g];
    qsort(s, (size_t)M->ngp, sizeof(double), fdb_cmp_d);
    med = s[M->ngp / 2], mx = s[M->ngp - 1];
    if (M->ngp < 8 || !(mx > 1.5 * med)) goto out;
    thr = med + 0.5 * (mx - med);
    for (g = 0; g < M->ngp; ++g) {
        double x[3], w = v[g] - thr;
        if (w <= 0) continue;
        gk_mesh_point(&M->mesh, g / M->q.n, M->q.xi[g % M->q.n], x);
        sw += w, cx += w * x[0], cy += w * x[1];
    }
    cx /= sw, cy /= sw;
    for (g = 0; g < M->ngp; ++g) {
        double x[3], w = v[g] - thr;
        if (w <= 0) continue;
        gk_mesh_point(&M->mesh, g / M->q.n, M->q.xi[g % M->q.n], x);
        sxx += w * (x[0] - cx) * (x[0] - cx), syy += w * (x[1] - cy) * (x[1] - cy),
            sxy += w * (x[0] - cx) * (x[1] - cy);
    }
    th = 0.5 * atan2(2 * sxy, sxx - syy); /* major axis */
    nx = -sin(th), ny = cos(th);
    for (g = 0; g < M->ngp; ++g) {
        double x[3], w = v[g] - thr, d;
        if (w <= 0) continue;
        gk_mesh_point(&M->mesh, g / M->q.n, M->q.xi[g % M->q.n], x);
        d = (x[0] - cx) * nx + (x[1] - cy) * ny;
        var += w * d * d;
        if ((x[0] - cx) * (x[0] - cx) + (x[1] - cy) * (x[1] - cy) < dmin)
            dmin = (x[0] - cx) * (x[0] - cx) + (x[1] - cy) * (x[1] - cy), *mid = g;
    }
    *angle = fabs(th * 180.0 / FD_PI);
    if (*angle > 90) *angle = 180 - *angle;
    *width = sqrt(12.0 * var / sw);
out:
    free(all), free(v), free(s);
}

/* the Gauss-point fields of the last row (M->ncurve - 1) into M->hist; 0, or 1 (out of memory, said) */
static int fdb_record(fd_model *M) {
    size_t nh = (size_t)M->ngp * FD_NFIELD;
    double *f = fd_gp_fields(M),
           *h = f ? (double *)realloc(M->hist, (size_t)M->ncurve * nh * sizeof(double)) : NULL;
    if (h) M->hist = h, memcpy(h + (size_t)(M->ncurve - 1) * nh, f, nh * sizeof(double));
    free(f);
    return h ? 0 : (fd_say(M, "%s: out of memory\n", M->prog), 1);
}

/* the initial row: the reactions of the confined specimen */
static void fdb_first_row(fd_model *M, gk_err *err) {
    double syy, sxx, ev;
    fd_external_force(M, err);
    fd_residual(M, M->sig_n, err);
    fdb_macro_state(M, &syy, &sxx, &ev);
    memset(&M->curve[0], 0, sizeof M->curve[0]);
    M->curve[0].syy = syy, M->curve[0].sxx = sxx;
    M->ncurve = 1;
}

/* --fields-at: the fabric map when this row is the first at or past one of the strains. 0, or 1 */
static int fdb_fields_now(fd_model *M) {
    double v[FDB_MAX_FIELDS_AT], e1 = M->curve[M->ncurve - 1].eps, e0 = M->curve[M->ncurve - 2].eps,
                                 tiny = 1e-9;
    int n = fdb_fields_at(M->o.fields_at, v), k;
    char file[64], title[200];
    for (k = 0; k < n; ++k)
        if (e0 < 1e-2 * v[k] - tiny && e1 >= 1e-2 * v[k] - tiny) {
            snprintf(file, sizeof file, "fabric_field_%04d.svg", M->step);
            snprintf(title, sizeof title, "fabric anisotropy F_a (eq 25) at axial strain %.2f %% (range 0-1)",
                     100 * e1);
            return fd_write_field_svg(M, 7, 1.0, file, title, FDB_FABRIC_LABEL, 0.0, 1.0);
        }
    return 0;
}

/* the loading loop to --steps x --increment: load steps, cut-backs, rows, VTK and checkpoints.
 * 0, 1 (an error: said), or 3 (gave up after cut-backs) */
static int fdb_loop(fd_model *M, double t_start, gk_err *err) {
    const fd_opts *o = &M->o;
    double target = o->steps * o->inc;
    int good_in_row = 0;
    while (M->eps_done < target - 1e-12 * target) {
        double inc = o->inc * M->scale, t0 = gk_wtime(), Ed = 0, Ef = 0, syy, sxx, ev;
        int iters = 0, r, g, nf = 0;
        fd_row *c;
        char what[200];
        if (M->eps_done + inc > target) inc = target - M->eps_done;
        if ((r = fd_load_step(M, inc, &iters, &Ed, &Ef, err)) == 2) return 1;
        if (r == 1) {
            good_in_row = 0;
            if (fd_cut_back(M, "axial strain", M->eps_done, o->inc, iters, Ed, err)) return 3;
            continue;
        }
        if (fd_commit(M, err)) return fd_say(M, "%s: %s\n", M->prog, err->msg), 1;
        memcpy(M->ulast, M->u, (size_t)M->ndof * sizeof(double));
        M->inclast = inc;
        M->eps_done += inc;
        ++M->step;
        fd_residual(M, M->sig_n, err);
        fdb_macro_state(M, &syy, &sxx, &ev);
        for (g = 0; g < M->ngp; ++g) nf += M->failed[g];
        if (fd_row_room(M)) return fd_say(M, "%s: out of memory\n", M->prog), 1;
        c = &M->curve[M->ncurve++];
        c->eps = M->eps_done, c->syy = syy, c->sxx = sxx, c->ev = ev, c->iters = iters;
        c->secs = gk_wtime() - t0, c->Ed = Ed, c->Ef = Ef, c->inc = inc, c->failed = nf;
        fd_row_work(M, c);
        if (fdb_record(M) || fdb_fields_now(M)) return 1;
        if (++good_in_row >= 2 && M->scale < 1.0) M->scale *= 2, good_in_row = 0;
        if (fdb_write_csv(M)) return 1;
        if (o->vtk_every && M->step % o->vtk_every == 0 && fd_write_vtk(M, M->step)) return 1;
        if (o->checkpoint && M->step % o->checkpoint == 0 && fdb_checkpoint(M)) return 1;
        snprintf(what, sizeof what,
                 "eps %.2f %%  sigma_yy %.1f kPa  sigma_xx %.1f kPa  eps_v %.3f %%  %d iter  DEM steps/RVE "
                 "%.0f (max %d)  "
                 "%.2f s",
                 100 * M->eps_done, syy / 1e3, sxx / 1e3, 100 * ev, iters, c->dem_mean, c->dem_max,
                 gk_wtime() - t0);
        if (M->root) gk_progress(stderr, (long)floor(M->eps_done / o->inc + 0.5), o->steps, t_start, what);
    }
    return 0;
}

/* ---------------------------------------------- local histories (Guo & Zhao 2014 Figs 15, 17, 18) */
/* the three Gauss points of gp_history.csv, from the last row: inside the band (mid: the band point
 * nearest the band's centre, fdb_band; without a band the largest eps_q), at its edge (largest void
 * ratio, where points fail: Guo & Zhao 2014 Fig 17) and outside (smallest eps_q) */
static const char *fdb_point_names[3] = {"inside", "edge", "outside"};
static void fdb_points(const fd_model *M, int mid, int pt[3]) {
    const double *h = M->hist + (size_t)(M->ncurve - 1) * M->ngp * FD_NFIELD;
    int g;
    pt[0] = pt[1] = pt[2] = 0;
    for (g = 1; g < M->ngp; ++g) {
        if (h[FD_NFIELD * g] > h[FD_NFIELD * pt[0]]) pt[0] = g;
        if (h[FD_NFIELD * g + 2] > h[FD_NFIELD * pt[1] + 2]) pt[1] = g;
        if (h[FD_NFIELD * g] < h[FD_NFIELD * pt[2]]) pt[2] = g;
    }
    if (mid >= 0) pt[0] = mid;
}

/* field k of Gauss point g at row r */
static double fdb_h(const fd_model *M, int r, int g, int k) {
    return M->hist[((size_t)r * M->ngp + g) * FD_NFIELD + k];
}

static void fdb_history_row(FILE *fp, const fd_model *M, int k, const void *user) {
    const int *pt = (const int *)user;
    int i, f;
    for (i = 0; i < 3; ++i) {
        double x[3];
        gk_mesh_point(&M->mesh, pt[i] / M->q.n, M->q.xi[pt[i] % M->q.n], x);
        fprintf(fp, "%s,%d,%.6g,%.6g,%d,%.9g", fdb_point_names[i], pt[i], 1e3 * x[0], 1e3 * x[1], k,
                M->curve[k].eps);
        for (f = 0; f < FD_NFIELD - 1; ++f) fprintf(fp, ",%.9g", fdb_h(M, k, pt[i], f) + 0.0); /* no -0 */
        fprintf(fp, "\n");
    }
}

/* one plot of the three points: field fy against field fx, each times its scale */
static int fdb_history_plot(const fd_model *M, const int pt[3], int fx, double sx, int fy, double sy,
                            const char *title, const char *xl, const char *yl, const char *file) {
    int n = M->ncurve, i, k, bad;
    double *v = (double *)malloc((size_t)6 * n * sizeof(double));
    char lab[3][80];
    gk_plot pl;
    if (!v) return fd_say(M, "%s: out of memory\n", M->prog), fd_agree(M, 1);
    gk_plot_init(&pl, title, xl, yl);
    for (i = 0; i < 3; ++i) {
        for (k = 0; k < n; ++k)
            v[2 * i * n + k] = sx * fdb_h(M, k, pt[i], fx),
                          v[(2 * i + 1) * n + k] = sy * fdb_h(M, k, pt[i], fy);
        snprintf(lab[i], sizeof lab[i], "Gauss point %d, %s", pt[i], fdb_point_names[i]);
        gk_plot_add(&pl, v + 2 * i * n, v + (2 * i + 1) * n, n, lab[i]);
    }
    bad = fd_plot(M, &pl, file);
    free(v);
    return bad;
}

/* gp_history.csv and its plots, failed_fraction.svg, fabric_field.svg and the LOCAL line. 0, or 1 */
static int fdb_local(fd_model *M, int mid) {
    int pt[3], n = M->ncurve, k, g, bad, first = -1, nafter = 0;
    double *x = (double *)malloc((size_t)2 * n * sizeof(double)), fsum = 0, famax = 0, outmax = 0;
    gk_plot pl;
    char title[200];
    fdb_points(M, mid, pt);
    bad = fd_write_csv(M, "gp_history.csv",
                       "point,gp,x_mm,y_mm,step,eps_axial,eps_q,eps_v,void_ratio,rotation_deg,spin_deg,p,q,"
                       "fabric_anisotropy,coordination\n",
                       fdb_history_row, pt);
    bad = bad || fdb_history_plot(M, pt, 0, 100, 6, 1e-3,
                                  "Gauss-point histories (Guo & Zhao 2014 Fig 15): deviatoric stress",
                                  "eps_q [%]", "q [kPa] (eq 7)", "gp_history_q.svg");
    bad = bad ||
          fdb_history_plot(M, pt, 0, 100, 1, 100, "Gauss-point histories (Guo & Zhao 2014 Fig 15): volume",
                           "eps_q [%]", "eps_v [%] (contraction positive)", "gp_history_volume.svg");
    bad =
        bad || fdb_history_plot(M, pt, 5, 1e-3, 6, 1e-3, "Gauss-point stress paths (Guo & Zhao 2014 Fig 15)",
                                "p [kPa] (eq 6)", "q [kPa] (eq 7)", "gp_history_path.svg");
    bad =
        bad || fdb_history_plot(M, pt, 0, 100, 7, 1, "Gauss-point histories (Guo & Zhao 2014 Fig 15): fabric",
                                "eps_q [%]", "fabric anisotropy F_a (eq 25)", "gp_history_fabric.svg");
    if (!x) return fd_say(M, "%s: out of memory\n", M->prog), 1;
    for (k = 0; k < n; ++k) {
        x[k] = 100 * M->curve[k].eps, x[n + k] = 100.0 * M->curve[k].failed / M->ngp;
        if (first < 0 && M->curve[k].failed > 0) first = k;
        if (first >= 0) fsum += x[n + k], ++nafter;
        for (g = 0; g < M->ngp; ++g)
            if (fdb_h(M, k, g, 7) > famax) famax = fdb_h(M, k, g, 7);
        if (fdb_h(M, k, pt[2], 0) > outmax) outmax = fdb_h(M, k, pt[2], 0);
    }
    gk_plot_init(&pl, "Failed Gauss points (fewer contacts than half the particles; Guo & Zhao 2014 Fig 17)",
                 "axial strain [%]", "failed Gauss points [% of all]");
    gk_plot_add(&pl, x, x + n, n, NULL);
    bad = bad || fd_plot(M, &pl, "failed_fraction.svg");
    free(x);
    snprintf(title, sizeof title, "fabric anisotropy F_a (eq 25) at axial strain %.2f %% (range 0-1)",
             100 * M->eps_done);
    bad = bad || fd_write_field_svg(M, 7, 1.0, "fabric_field.svg", title, FDB_FABRIC_LABEL, 0.0, 1.0);
    if (bad || !M->root) return bad;
    printf("LOCAL inside_gp=%d inside_eps_q=%.4g edge_gp=%d edge_void_ratio=%.4g outside_gp=%d "
           "outside_eps_q=%.4g "
           "outside_eps_q_max=%.4g first_failed_eps=%.4g failed_fraction_mean=%.4g fabric_max=%.4g\n",
           pt[0], fdb_h(M, n - 1, pt[0], 0), pt[1], fdb_h(M, n - 1, pt[1], 2), pt[2],
           fdb_h(M, n - 1, pt[2], 0), outmax, first >= 0 ? M->curve[first].eps : NAN,
           nafter ? 1e-2 * fsum / nafter : 0.0, famax);
    return 0;
}

/* after the loop (status 0 or 3): the CSV, the plots, the eps_q map, the checkpoint (status 0: a
 * give-up has written the converged state already), the band and the RESULT line. The status, or 1
 * when an output failed. */
static int fdb_finish(fd_model *M, int status) {
    const fd_opts *o = &M->o;
    double *x = (double *)malloc((size_t)M->ncurve * sizeof(double)),
           *y1 = (double *)malloc((size_t)M->ncurve * sizeof(double)),
           *y2 = (double *)malloc((size_t)M->ncurve * sizeof(double)), peak = 0, epk = 0, ang, wid, tot = 0;
    int k, itmax = 0, itsum = 0, bad = !x || !y1 || !y2, mid;
    char title[200];
    gk_plot pl;
    bad = bad || fdb_write_csv(M);
    for (k = 0; k < M->ncurve && !bad; ++k)
        x[k] = 100 * M->curve[k].eps, y1[k] = M->curve[k].syy / 1e3, y2[k] = M->curve[k].sxx / 1e3;
    if (!bad) {
        gk_plot_init(&pl, "FEMxDEM biaxial test (Guo & Zhao 2014)", "axial strain [%]",
                     "stress [kPa] (compression positive)");
        gk_plot_add(&pl, x, y1, M->ncurve, "sigma_yy (top reaction / width)");
        gk_plot_add(&pl, x, y2, M->ncurve, "sigma_xx (side reaction / height)");
        bad = fd_plot(M, &pl, "biaxial_stress.svg");
    }
    for (k = 0; k < M->ncurve && !bad; ++k) y1[k] = 100 * M->curve[k].ev;
    if (!bad) {
        gk_plot_init(&pl, "FEMxDEM biaxial test: volume", "axial strain [%]",
                     "volumetric strain [%] (contraction positive)");
        gk_plot_add(&pl, x, y1, M->ncurve, NULL);
        bad = fd_plot(M, &pl, "biaxial_volume.svg");
    }
    free(x), free(y1), free(y2);
    snprintf(title, sizeof title, "eps_q at axial strain %.2f %%", 100 * M->eps_done);
    bad = bad || fd_write_field_svg(M, 0, 100.0, "eps_q_field.svg", title, "eps_q [%]", 0, 0);
    fdb_band(M, &ang, &wid, &mid);
    bad = bad || fdb_local(M, mid);
    bad = bad || (status != 3 && fdb_checkpoint(M));
    if (bad) return 1;
    for (k = 0; k < M->ncurve; ++k) {
        if (M->curve[k].syy > peak) peak = M->curve[k].syy, epk = M->curve[k].eps;
        if (M->curve[k].iters > itmax) itmax = M->curve[k].iters;
        if (k > 0) itsum += M->curve[k].iters, tot += M->curve[k].secs;
    }
    if (!M->root) return status;
    printf("wrote %s/biaxial.csv, %s/gp_*.vtk and mesh_*.vtk (ParaView), %s/biaxial_stress.svg, "
           "biaxial_volume.svg, "
           "eps_q_field.svg, checkpoint.bin\n",
           o->out, o->out, o->out);
    if (ang == ang)
        printf("shear band: angle %.1f deg from the horizontal, width %.1f mm\n", ang, 1e3 * wid);
    else
        printf("shear band: none (max eps_q < 1.5 x median)\n");
#ifdef GK_TWOSCALE_MPI
    printf("MPI ranks=%d rve_runs=%lld rank0_bytes_in_per_run=%.0f rank0_bytes_out_per_run=%.0f "
           "point_moves=%lld "
           "bytes_moved=%lld rank0_bytes_in_all=%lld balance=%s\n",
           M->ts.nranks, M->ts.stats.runs,
           (double)M->ts.stats.run_bytes_in / (M->ts.stats.runs ? M->ts.stats.runs : 1),
           (double)M->ts.stats.run_bytes_out / (M->ts.stats.runs ? M->ts.stats.runs : 1),
           M->ts.stats.migrated, M->ts.stats.migrated_bytes, M->ts.stats.bytes_in,
           o->balance_run ? "run" : "accept");
#endif
    printf(
        "RESULT peak_sigma_yy=%.6g eps_at_peak=%.5g band_angle_deg=%.3g band_width_mm=%.3g max_iterations=%d "
        "steps=%d seconds_per_step=%.3f total_seconds=%.2f mean_iterations=%.2f",
        peak, epk, ang, 1e3 * wid, itmax, M->ncurve - 1, M->ncurve > 1 ? tot / (M->ncurve - 1) : 0.0, tot,
        M->ncurve > 1 ? (double)itsum / (M->ncurve - 1) : 0.0);
    fd_print_work_totals(M);
    return status;
}

/* setup, restart or initial row, the header line, the loop: the status so far (0, 1, 3) */
static int fdb_run(fd_model *M) {
    gk_err err;
    int status;
    M->checkpoint = fdb_checkpoint;
    if (fd_mkdir_out(M)) return 1;
    if (fd_setup(M, &err)) return fd_say(M, "%s: %s\n", M->prog, err.msg), 1;
    if (M->o.restart ? fdb_restart(M, &err) : (fdb_first_row(M, &err), 0))
        return fd_say(M, "%s: %s\n", M->prog, err.msg), 1;
    if (!M->o.restart && fdb_record(M)) return 1;
    if (M->root) {
        printf("%s: %s test, %d x %d %s elements, %d Gauss points x %d disks, tangent %s, %d threads\n",
               M->prog, M->o.test, M->o.nx, M->o.ny, M->o.elem == GK_Q8 ? "Q8" : "Q4", M->ngp, M->ts.pk[0].n,
               M->o.tangent, M->o.threads);
        if (M->o.extrapolate) printf("%s: predictor: the last converged increment, scaled\n", M->prog);
        fflush(stdout);
    }
    if (M->o.cost_log) { /* rank 0 writes it */
        int bad = M->root && !(M->cost_log = fopen(M->o.cost_log, "w"));
        if (bad) fd_say(M, "%s: --cost-log %s: cannot write that file\n", M->prog, M->o.cost_log);
        if (fd_agree(M, bad)) return 1;
    }
    status = fdb_loop(M, gk_wtime(), &err);
    if (M->cost_log) {
        int bad = ferror(M->cost_log) != 0;
        bad |= fclose(M->cost_log) != 0;
        M->cost_log = NULL;
        if (bad) fd_say(M, "%s: cannot write %s\n", M->prog, M->o.cost_log), status = 1;
    }
    if (M->o.cost_log && fd_agree(M, status == 1)) return 1;
    return status == 1 ? 1 : fdb_finish(M, status);
}

#endif /* FEMDEM_BIAXIAL_H */
