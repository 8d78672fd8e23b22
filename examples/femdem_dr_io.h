/* femdem_dr_io.h - the outputs and the checkpoint of build/femdem_dr (examples/femdem_dr.c;
 * examples, not library): the rows of dr.csv, the VTK and SVG files, the checkpoint and the RESULT
 * line.
 *
 * OUTPUTS in DIR (every failed write: exit status 1)
 *   dr.csv       step,stage,eps_axial,sigma_bar,sigma_11,sigma_22,J,coordination,anisotropy,
 *                dr_iterations,dem_steps,seconds
 *                one row per load step (step 0: the unloaded state). stage 1 isotropic, 2
 *                biaxial. eps_axial = (h_ref - h) / h_ref (h_ref = h_0 in stage 1, h_ic in
 *                stage 2, eq 41); sigma_11, sigma_22: mean Cauchy stress over the Gauss
 *                points (eq 16; dns: the side pressure and the platen force / width),
 *                COMPRESSION POSITIVE [Pa = N/m per m]; sigma_bar = |(s11 - s22) / (s11 +
 *                s22)| (eq 40) averaged over the Gauss points; J = J_rel = (det F - det F_ic) /
 *                det F_ic in stage 2, det F - 1 in stage 1 (mean over the Gauss points);
 *                coordination 2 C / (P + Q) and anisotropy Pi_1 / Pi_2 - 1 (eqs 38-39) of the
 *                RVEs, averaged; dr_iterations of the step; dem_steps: all DEM steps of the
 *                step (every Gauss point, every iteration)
 *   mesh_NNNN.vtk, gp_NNNN.vtk   every --vtk-every steps: the deformed mesh (displacement;
 *                per element sigma_bar, J, deq) and the Gauss points (sigma_11, sigma_22,
 *                sigma_bar, J, coordination, anisotropy, deq = |dF| of the last step,
 *                dem_steps)
 *   dr_stress.svg (sigma_bar vs eps), dr_volume.svg (J_rel vs eps), dr_fabric.svg
 *                (coordination and 10 x anisotropy vs eps), deq_field.svg (the incremental
 *                equivalent strain of the last step on the deformed mesh, Fig 7)
 *   checkpoint.bin  every --checkpoint steps, at --stop-after K and at the end
 *                (gk_twoscale_save; the macro state in its driver block); --restart DIR
 *                continues from DIR/checkpoint.bin to the same rows (only the seconds differ)
 *   RESULT peak_sigma_bar=... eps_at_peak=... sigma_bar_0073=... anisotropy_0073=...
 *          eps_dilation=... dr_iterations_mean=... seconds=... (+ dem_steps_per_run,
 *          rve_capped_runs: RVE runs stopped by --servo-max or --rve-max-steps before their
 *          tolerance, dr_unconverged_steps: load steps stopped by --max-dr,
 *          dr_residual_max: the largest relative force residual |f_ext - f_int|_inf /
 *          max(|f_ext|_inf, |f_int|_inf) a load step ended with, nan for the dns)
 *          A load step that ends above 5 % was ended by eq 28 (the kinetic energy
 *          ratio) before equilibrium: stiff or jumpy RVEs (a large --kn-ratio) do that; the run
 *          then warns on stderr with the count and the largest residual, and --dr-force-tol
 *          1e-2 makes every step relax to 1 %.
 *          eps_dilation: the strain of the smallest J_rel (compaction turns to dilation).
 */
#ifndef FEMDEM_DR_IO_H
#define FEMDEM_DR_IO_H

#include "femdem_dr_model.h"
#include <limits.h>

#define CK_MAGIC 0x32524446u /* "FDR2" */

/* ------------------------------------------------------------------ rows, outputs */
/* the macro state as a row of dr.csv */
/* 1 after a message: the contacts of `whose` (a Gauss point's RVE, the DNS specimen) no longer span
 * the plane at this step, their fabric tensor is singular and eq 38's anisotropy unbounded
 * (gk_fabric_ratio: +inf); the run stops rather than write it */
static int came_apart(int step, const char *whose) {
    fprintf(stderr,
            PROG ": step %d: the contacts of %s no longer span the plane (its fabric tensor is singular, "
                 "eq 38's anisotropy unbounded): the specimen has come apart; stopping\n",
            step, whose);
    return 1;
}

static void make_row(model *m, int step, int stage, int iters, long long dem, row *r) {
    double s11 = 0.0, s22 = 0.0, sb = 0.0, J = 0.0, W = 0.0, Z = 0.0, A = 0.0, h = mean_top(m, m->u);
    int g;
    for (g = 0; g < m->ngp; ++g) {
        double F[9], s[9], w = m->wgp[g];
        int k;
        gk_m3_identity(F);
        for (k = 0; k < 9; ++k) F[k] += m->Hacc[9 * g + k];
        gk_frame_cauchy(m->P + 9 * (size_t)g, F, s);
        s11 -= w * s[0], s22 -= w * s[4], J += w * gk_m3_det(F), W += w;
        sb += fabs(s[0] + s[4]) > 0.0 ? fabs((s[0] - s[4]) / (s[0] + s[4])) : 0.0;
        Z += m->stats[g].coordination, A += m->stats[g].anisotropy;
    }
    J /= W;
    r->v[0] = step, r->v[1] = stage;
    r->v[2] = stage == 2 ? (m->h_ic - h) / m->h_ic : (m->h0 - h) / m->h0;
    r->v[3] = sb / m->ngp, r->v[4] = s11 / W, r->v[5] = s22 / W;
    r->v[6] = stage == 2 ? (J - m->J_ic) / m->J_ic : J - 1.0;
    r->v[7] = Z / m->ngp, r->v[8] = A / m->ngp;
    r->v[9] = iters, r->v[10] = (double)dem, r->v[11] = gk_wtime() - m->t0;
}

static void add_row(model *m, const row *r) {
    if (m->nrows == m->caprows) {
        m->caprows = 2 * m->caprows + 64;
        m->rows = (row *)realloc(m->rows, (size_t)m->caprows * sizeof(row));
        if (!m->rows) die_alloc();
    }
    m->rows[m->nrows++] = *r;
}

static int write_csv(const model *m, const char *name) {
    char path[1024];
    FILE *fp;
    int i, ok;
    snprintf(path, sizeof path, "%s/%s", m->o.out, name);
    fp = fopen(path, "w");
    if (!fp) {
        fprintf(stderr, PROG ": cannot write %s\n", path);
        return 1;
    }
    fprintf(
        fp,
        "step,stage,eps_axial,sigma_bar,sigma_11,sigma_22,J,coordination,anisotropy,dr_iterations,dem_steps,"
        "seconds\n");
    for (i = 0; i < m->nrows; ++i) {
        const double *v = m->rows[i].v;
        fprintf(fp, "%d,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%.6g,%d,%.0f,%.3f\n", (int)v[0], (int)v[1], v[2],
                v[3], v[4], v[5], v[6], v[7], v[8], (int)v[9], v[10], v[11]);
    }
    ok = !ferror(fp);
    if (fclose(fp) != 0) ok = 0;
    if (!ok) fprintf(stderr, PROG ": cannot write %s\n", path);
    return !ok;
}

static int write_vtk(const model *m, int step) {
    char path[1024];
    gk_vtk v;
    gk_result r = GK_OK;
    double *xyz, *s11, *s22, *sb, *J, *Z, *A, *dem, *cell;
    int g, k, nn = m->nnode, ne = m->mesh.nelem;
    if (m->single) return 0;
    xyz = (double *)xcalloc(3 * (size_t)(nn > m->ngp ? nn : m->ngp), sizeof(double));
    s11 = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    s22 = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    sb = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    J = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    Z = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    A = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    dem = (double *)xcalloc((size_t)m->ngp, sizeof(double));
    cell = (double *)xcalloc(3 * (size_t)ne, sizeof(double));
    for (g = 0; g < m->ngp; ++g) {
        double F[9], s[9];
        gk_m3_identity(F);
        for (k = 0; k < 9; ++k) F[k] += m->Hacc[9 * g + k];
        gk_frame_cauchy(m->P + 9 * (size_t)g, F, s);
        s11[g] = -s[0], s22[g] = -s[4];
        sb[g] = fabs(s[0] + s[4]) > 0.0 ? fabs((s[0] - s[4]) / (s[0] + s[4])) : 0.0;
        J[g] = gk_m3_det(F), Z[g] = m->stats[g].coordination, A[g] = m->stats[g].anisotropy;
        dem[g] = (double)m->stats[g].steps;
        cell[g / 4] += sb[g] / 4, cell[ne + g / 4] += J[g] / 4, cell[2 * ne + g / 4] += m->deq[g] / 4;
    }
    snprintf(path, sizeof path, "%s/mesh_%04d.vtk", m->o.out, step);
    for (k = 0; k < nn; ++k) {
        xyz[3 * k] = m->mesh.x[2 * k] + m->u[2 * k], xyz[3 * k + 1] = m->mesh.x[2 * k + 1] + m->u[2 * k + 1];
        xyz[3 * k + 2] = 0.0;
    }
    r = gk_vtk_open(&v, path, "femdem_dr deformed mesh");
    if (!r) r = gk_vtk_points(&v, nn, xyz);
    if (!r) r = gk_vtk_cells(&v, ne, 4, m->mesh.conn, GK_VTK_QUAD);
    if (!r) {
        double *d3 = (double *)xcalloc(3 * (size_t)nn, sizeof(double));
        for (k = 0; k < nn; ++k) d3[3 * k] = m->u[2 * k], d3[3 * k + 1] = m->u[2 * k + 1];
        r = gk_vtk_point_vector(&v, "displacement", d3);
        free(d3);
    }
    if (!r) r = gk_vtk_cell_scalar(&v, "sigma_bar", cell);
    if (!r) r = gk_vtk_cell_scalar(&v, "J", cell + ne);
    if (!r) r = gk_vtk_cell_scalar(&v, "deq", cell + 2 * ne);
    if (!r)
        r = gk_vtk_close(&v);
    else if (v.fp)
        fclose(v.fp);
    if (!r) {
        int *conn = (int *)xcalloc((size_t)m->ngp, sizeof(int));
        snprintf(path, sizeof path, "%s/gp_%04d.vtk", m->o.out, step);
        for (g = 0; g < m->ngp; ++g) {
            double x[3], X[3], N[4], dN[8], uu[2] = {0, 0};
            int e = g / 4, a;
            gk_fem_shape(GK_Q4, m->q.xi[g % 4], N, dN);
            gk_mesh_point(&m->mesh, e, m->q.xi[g % 4], X);
            for (a = 0; a < 4; ++a) {
                int n = m->mesh.conn[4 * e + a];
                uu[0] += N[a] * m->u[2 * n], uu[1] += N[a] * m->u[2 * n + 1];
            }
            x[0] = X[0] + uu[0], x[1] = X[1] + uu[1], x[2] = 0.0;
            memcpy(xyz + 3 * g, x, sizeof x);
            conn[g] = g;
        }
        r = gk_vtk_open(&v, path, "femdem_dr Gauss points");
        if (!r) r = gk_vtk_points(&v, m->ngp, xyz);
        if (!r) r = gk_vtk_cells(&v, m->ngp, 1, conn, GK_VTK_VERTEX);
        if (!r) r = gk_vtk_point_scalar(&v, "sigma_11", s11);
        if (!r) r = gk_vtk_point_scalar(&v, "sigma_22", s22);
        if (!r) r = gk_vtk_point_scalar(&v, "sigma_bar", sb);
        if (!r) r = gk_vtk_point_scalar(&v, "J", J);
        if (!r) r = gk_vtk_point_scalar(&v, "coordination", Z);
        if (!r) r = gk_vtk_point_scalar(&v, "anisotropy", A);
        if (!r) r = gk_vtk_point_scalar(&v, "deq", m->deq);
        if (!r) r = gk_vtk_point_scalar(&v, "dem_steps", dem);
        if (!r)
            r = gk_vtk_close(&v);
        else if (v.fp)
            fclose(v.fp);
        free(conn);
    }
    if (r) fprintf(stderr, PROG ": %s\n", v.err.msg[0] ? v.err.msg : "cannot write the VTK files");
    free(xyz), free(s11), free(s22), free(sb), free(J), free(Z), free(A), free(dem), free(cell);
    return r != GK_OK;
}

static int write_svgs(const model *m) {
    char path[1024];
    gk_plot p;
    gk_err err;
    double *x = (double *)xcalloc((size_t)m->nrows + 1, sizeof(double)),
           *y = (double *)xcalloc((size_t)m->nrows + 1, sizeof(double));
    double *z = (double *)xcalloc((size_t)m->nrows + 1, sizeof(double)),
           *a = (double *)xcalloc((size_t)m->nrows + 1, sizeof(double));
    double *jj = (double *)xcalloc((size_t)m->nrows + 1, sizeof(double));
    int i, n = 0, bad = 0;
    for (i = 0; i < m->nrows; ++i) {
        const double *v = m->rows[i].v;
        if (v[1] != 2 && !(i + 1 < m->nrows && m->rows[i + 1].v[1] == 2)) continue; /* the start of stage 2 */
        x[n] = 100.0 * (v[1] == 2 ? v[2] : 0.0), y[n] = v[3], jj[n] = 100.0 * (v[1] == 2 ? v[6] : 0.0);
        z[n] = v[7], a[n] = 10.0 * v[8], ++n;
    }
    gk_plot_init(&p, "FEMxDEM by dynamic relaxation: stress ratio", "axial strain eps = d / h_ic [%]",
                 "sigma_bar = |s11 - s22| / |s11 + s22|");
    gk_plot_add(&p, x, y, n,
                m->o.test == TEST_DNS ? "DNS"
                                      : (m->o.frame == GK_FRAME_SERVO ? "servo frame" : "periodic cell"));
    snprintf(path, sizeof path, "%s/dr_stress.svg", m->o.out);
    bad |= gk_plot_svg(&p, path, &err) != GK_OK;
    gk_plot_init(&p, "volumetric deformation", "axial strain [%]",
                 "J_rel = (det F - det F_ic) / det F_ic [%]");
    gk_plot_add(&p, x, jj, n, "J_rel");
    snprintf(path, sizeof path, "%s/dr_volume.svg", m->o.out);
    bad |= gk_plot_svg(&p, path, &err) != GK_OK;
    gk_plot_init(&p, "micro-structure", "axial strain [%]", "coordination 2C/(P+Q); 10 x anisotropy");
    gk_plot_add(&p, x, z, n, "coordination");
    gk_plot_add(&p, x, a, n, "10 x anisotropy (eq 38)");
    snprintf(path, sizeof path, "%s/dr_fabric.svg", m->o.out);
    bad |= gk_plot_svg(&p, path, &err) != GK_OK;
    if (!m->single &&
        m->o.test != TEST_DNS) { /* Fig 7: the incremental equivalent strain on the deformed mesh */
        int ne = m->mesh.nelem, e, k;
        double *xy = (double *)xcalloc(8 * (size_t)ne, sizeof(double)),
               *val = (double *)xcalloc((size_t)ne, sizeof(double));
        double ol[10];
        int ollen = 5;
        gk_field_def fd;
        for (e = 0; e < ne; ++e)
            for (k = 0; k < 4; ++k) {
                int nd = m->mesh.conn[4 * e + k];
                xy[8 * e + 2 * k] = m->mesh.x[2 * nd] + m->u[2 * nd];
                xy[8 * e + 2 * k + 1] = m->mesh.x[2 * nd + 1] + m->u[2 * nd + 1];
                val[e] += 0.25 * 100.0 * m->deq[4 * e + k];
            }
        { /* the specimen's corners as the outline */
            int c[5];
            c[0] = 0, c[1] = m->o.nx, c[2] = m->nnode - 1, c[3] = m->nnode - 1 - m->o.nx, c[4] = 0;
            for (k = 0; k < 5; ++k)
                ol[2 * k] = m->mesh.x[2 * c[k]] + m->u[2 * c[k]],
                       ol[2 * k + 1] = m->mesh.x[2 * c[k] + 1] + m->u[2 * c[k] + 1];
        }
        memset(&fd, 0, sizeof fd);
        fd.title = "incremental equivalent strain of the last step";
        fd.label = "deq = |dF| [%]";
        fd.xlabel = "x [mm]", fd.ylabel = "y [mm]", fd.coord_scale = 1e3;
        fd.nlines = 1, fd.line_len = &ollen, fd.line_xy = ol;
        snprintf(path, sizeof path, "%s/deq_field.svg", m->o.out);
        bad |= gk_field_svg(path, &fd, ne, 4, xy, val, &err) != GK_OK;
        free(xy), free(val);
    }
    if (bad) fprintf(stderr, PROG ": cannot write the SVG plots in %s\n", m->o.out);
    free(x), free(y), free(z), free(a), free(jj);
    return bad;
}

/* ------------------------------------------------------------------ checkpoint */
/* driver block: uint32 magic, int32 ngp, ndof, frame, rotation_lock, test, step_done, nrows, have_f0;
 * double h_ic, J_ic, omega, dr_total, dem_total, runs_total, capped_total, unconverged, resid_max,
 * resid_step, resid_over, 8 option values;
 * u, v, f0 (ndof each), Hacc (9 ngp), P (9 ngp), rows */
#define CK_NI 9
#define CK_ND 19
#define CK_OPT 11 /* the first option value of the reals */
static void ck_opts(const model *m, double *d) {
    const opts *o = &m->o;
    d[CK_OPT] = o->strain, d[CK_OPT + 1] = o->pressure, d[CK_OPT + 2] = o->friction;
    d[CK_OPT + 3] = o->iso_steps, d[CK_OPT + 4] = o->steps, d[CK_OPT + 5] = o->kn_ratio;
    d[CK_OPT + 6] = o->nx * 1000.0 + o->ny, d[CK_OPT + 7] = o->width * o->height;
}

static int save_checkpoint(model *m) {
    size_t n = 4 + 4 * (CK_NI - 1) +
               8 * (CK_ND + 3 * (size_t)m->ndof + 18 * (size_t)m->ngp + (size_t)NCOL * m->nrows);
    unsigned char *b = (unsigned char *)xcalloc(n, 1), *o = b;
    int32_t iv[CK_NI - 1];
    double dv[CK_ND];
    uint32_t magic = CK_MAGIC;
    char path[1024];
    int i, bad;
    iv[0] = m->ngp, iv[1] = m->ndof, iv[2] = m->o.frame, iv[3] = rotation_lock(&m->o), iv[4] = m->o.test;
    iv[5] = m->step_done, iv[6] = m->nrows, iv[7] = m->have_f0;
    dv[0] = m->h_ic, dv[1] = m->J_ic, dv[2] = m->dr.omega, dv[3] = (double)m->dr.total,
    dv[4] = (double)m->dem_total;
    dv[5] = (double)m->runs_total, dv[6] = (double)m->capped_total, dv[7] = (double)m->unconverged;
    dv[8] = m->resid_max, dv[9] = (double)m->resid_step, dv[10] = (double)m->resid_over;
    ck_opts(m, dv);
    memcpy(o, &magic, 4), o += 4;
    memcpy(o, iv, sizeof iv), o += sizeof iv;
    memcpy(o, dv, sizeof dv), o += sizeof dv;
    memcpy(o, m->u, 8 * (size_t)m->ndof), o += 8 * (size_t)m->ndof;
    memcpy(o, m->v, 8 * (size_t)m->ndof), o += 8 * (size_t)m->ndof;
    memcpy(o, m->f0, 8 * (size_t)m->ndof), o += 8 * (size_t)m->ndof;
    memcpy(o, m->Hacc, 72 * (size_t)m->ngp), o += 72 * (size_t)m->ngp;
    memcpy(o, m->P, 72 * (size_t)m->ngp), o += 72 * (size_t)m->ngp;
    for (i = 0; i < m->nrows; ++i) memcpy(o, m->rows[i].v, 8 * NCOL), o += 8 * NCOL;
    snprintf(path, sizeof path, "%s/checkpoint.bin", m->o.out);
    bad = gk_twoscale_save(&m->ts, path, b, (size_t)(o - b)) != GK_OK;
    if (bad) fprintf(stderr, PROG ": %s\n", gk_twoscale_error(&m->ts));
    free(b);
    return bad;
}

/* the block's values (iv, dv and the arrays from a) against what the run can hold: the step within
 * the run, one row per step with its step and stage, h_ic and J_ic > 0 (the setup's before the end of
 * stage 1), omega within the DR's bound, counters whole and >= 0, |u| <= 10 x the specimen, |H| <=
 * 1e6 with det(I + H) > 0, every other real within CK_MAX; 0 if all hold */
#define CK_MAX 1e100
static int ck_in(double x, double lo, double hi) { return x >= lo && x <= hi; }
static int ck_check(const model *m, const int32_t *iv, const double *dv, const unsigned char *a) {
    const opts *o = &m->o;
    size_t nd = (size_t)m->ndof, ng = (size_t)m->ngp, k;
    double L = o->width > o->height ? o->width : o->height, cap = m->dr.def.omega_cap, F[9];
    int i, g, step = iv[5], nrows = iv[6];
    if (step < 0 || step > o->iso_steps + o->steps || nrows != step + 1 || (iv[7] != 0 && iv[7] != 1))
        return 1;
    if (!(dv[0] > 0.0 && dv[0] <= o->height + 10 * L) || !(dv[1] > 0.0 && dv[1] <= CK_MAX) ||
        !ck_in(dv[2], 0.0, cap > 0.0 ? cap : CK_MAX) || !ck_in(dv[8], 0.0, 2.0))
        return 1;
    if (step < o->iso_steps && (dv[0] != o->height || dv[1] != 1.0)) return 1; /* set at its end */
    for (i = 3; i < CK_OPT; ++i) /* the counters: whole, >= 0, exact in a double */
        if (i != 8 && (!ck_in(dv[i], 0.0, 9007199254740992.0) || dv[i] != floor(dv[i]))) return 1;
    if (dv[9] > step || dv[10] > step || dv[7] > step) return 1;
    for (k = 0; k < 3 * nd + 18 * ng + (size_t)NCOL * nrows; ++k) {
        double x, lim = k < nd ? 10 * L : (k >= 3 * nd && k < 3 * nd + 9 * ng ? 1e6 : CK_MAX);
        memcpy(&x, a + 8 * k, 8);
        if (!ck_in(x, -lim, lim)) return 1;
    }
    if (!m->single) /* the supports of setup: the bottom's u_y and the first node's u_x are 0 */
        for (k = 0; k < nd; ++k) {
            double x;
            memcpy(&x, a + 8 * k, 8);
            if (x != 0.0 && (k == 0 || (k % 2 == 1 && m->mesh.x[k] <= 1e-12 * o->height))) return 1;
        }
    for (g = 0; g < (int)ng; ++g) { /* det(I + H) > 0 */
        gk_m3_identity(F);
        for (i = 0; i < 9; ++i) {
            double h;
            memcpy(&h, a + 8 * (3 * nd + 9 * (size_t)g + i), 8);
            F[i] += h;
        }
        if (!(gk_m3_det(F) > 0.0)) return 1;
    }
    for (i = 0; i < nrows; ++i) { /* step, stage, DR iterations, DEM steps, seconds */
        double v[NCOL];
        memcpy(v, a + 8 * (3 * nd + 18 * ng + (size_t)NCOL * i), sizeof v);
        if (v[0] != i || v[1] != (i > o->iso_steps ? 2 : 1) || !ck_in(v[9], 0.0, INT_MAX) || v[10] < 0.0 ||
            v[11] < 0.0)
            return 1;
    }
    return 0;
}

/* load_checkpoint's take (gk_twoscale_load_take): the block checked against the run, then written
 * into the model; refused: nothing written, the reason in why */
static int take_checkpoint(const void *blk, size_t nb, void *user, char *why, size_t nwhy) {
    model *m = (model *)user;
    const unsigned char *b = (const unsigned char *)blk;
    size_t need = 4 + (CK_NI - 1) * sizeof(int32_t) + CK_ND * sizeof(double);
    int32_t iv[CK_NI - 1];
    double dv[CK_ND], want[CK_ND];
    uint32_t magic;
    int i;
    if (nb < need) goto other;
    memcpy(&magic, b, 4), memcpy(iv, b + 4, sizeof iv), memcpy(dv, b + 4 + sizeof iv, sizeof dv);
    ck_opts(m, want);
    if (magic != CK_MAGIC || iv[0] != m->ngp || iv[1] != m->ndof || iv[2] != m->o.frame ||
        iv[3] != rotation_lock(&m->o) || iv[4] != m->o.test || iv[6] < 0 || iv[5] < 0)
        goto other;
    for (i = CK_OPT; i < CK_ND; ++i)
        if (dv[i] != want[i])
            return snprintf(
                       why, nwhy,
                       "written with other options (strain, pressure, friction, steps, stiffness or mesh)"),
                   1;
    need += 8 * (3 * (size_t)m->ndof + 18 * (size_t)m->ngp + (size_t)NCOL * iv[6]);
    if (nb != need) goto other;
    /* a checksum only proves the file is what some writer wrote: check what
     * this run will trust (every value in range), all of it before anything is written */
    if (ck_check(m, iv, dv, b + 4 + sizeof iv + sizeof dv))
        return snprintf(why, nwhy, "the run's block holds a non-finite or out-of-range value; not restarted"),
               1;
    b += 4 + sizeof iv + sizeof dv;
    memcpy(m->u, b, 8 * (size_t)m->ndof), b += 8 * (size_t)m->ndof;
    memcpy(m->v, b, 8 * (size_t)m->ndof), b += 8 * (size_t)m->ndof;
    memcpy(m->f0, b, 8 * (size_t)m->ndof), b += 8 * (size_t)m->ndof;
    memcpy(m->Hacc, b, 72 * (size_t)m->ngp), b += 72 * (size_t)m->ngp;
    memcpy(m->P, b, 72 * (size_t)m->ngp), b += 72 * (size_t)m->ngp;
    m->nrows = 0;
    for (i = 0; i < iv[6]; ++i) {
        row r;
        memcpy(r.v, b, 8 * NCOL), b += 8 * NCOL;
        add_row(m, &r);
    }
    m->step_done = iv[5], m->have_f0 = iv[7];
    m->h_ic = dv[0], m->J_ic = dv[1], m->dr.omega = dv[2], m->dr.total = (long)dv[3];
    m->dem_total = (long long)dv[4], m->runs_total = (long long)dv[5], m->capped_total = (long long)dv[6];
    m->unconverged = (long long)dv[7];
    m->resid_max = dv[8], m->resid_step = (long long)dv[9], m->resid_over = (long long)dv[10];
    if (m->have_f0) gk_dr_reference(&m->dr, NULL, m->f0);
    return 0;
other:
    return snprintf(why, nwhy, "not a checkpoint of this run (another test, mesh, frame or rotation)"), 1;
}

/* DIR/checkpoint.bin (--restart): the set and the model, or neither (the reason said) */
static int load_checkpoint(model *m) {
    char path[1024];
    snprintf(path, sizeof path, "%s/checkpoint.bin", m->o.restart);
    if (gk_twoscale_load_take(&m->ts, path, take_checkpoint, m)) {
        fprintf(stderr, PROG ": %s\n", gk_twoscale_error(&m->ts));
        return 1;
    }
    printf("restarted from %s at step %d\n", path, m->step_done);
    return 0;
}

static double interp(const model *m, int col, double eps) {
    int i;
    for (i = 1; i < m->nrows; ++i) {
        const double *a = m->rows[i - 1].v, *b = m->rows[i].v;
        if (a[1] == 2 && b[1] == 2 && a[2] <= eps && b[2] >= eps && b[2] > a[2])
            return a[col] + (b[col] - a[col]) * (eps - a[2]) / (b[2] - a[2]);
    }
    return NAN;
}

static void result_line(const model *m) {
    double peak = 0.0, epk = 0.0, jmin = HUGE_VAL, edil = NAN, iters = 0.0;
    int i, nst = 0;
    for (i = 0; i < m->nrows; ++i) {
        const double *v = m->rows[i].v;
        if (v[0] > 0) iters += v[9], ++nst;
        if (v[1] != 2) continue;
        if (v[3] > peak) peak = v[3], epk = v[2];
        if (v[6] < jmin) jmin = v[6], edil = v[2];
    }
    printf("RESULT peak_sigma_bar=%.4f eps_at_peak=%.4f sigma_bar_0073=%.4f anisotropy_0073=%.4f "
           "eps_dilation=%.4f "
           "dr_iterations_mean=%.1f seconds=%.1f dem_steps_per_run=%.1f rve_capped_runs=%lld "
           "dr_unconverged_steps=%lld dr_residual_max=%.3g "
           "frame=%s rotation=%s\n",
           peak, epk, interp(m, 3, 0.073), interp(m, 8, 0.073), edil, nst ? iters / nst : 0.0,
           gk_wtime() - m->t0, m->runs_total ? (double)m->dem_total / (double)m->runs_total : 0.0,
           m->capped_total, m->unconverged, m->o.test == TEST_DNS ? NAN : m->resid_max,
           m->o.frame == GK_FRAME_SERVO ? "servo" : "periodic", rotation_name(&m->o));
}

#endif /* FEMDEM_DR_IO_H */
