/* nonlocal_io.h - the outputs and the checkpoint of build/femdem_nonlocal
 * (examples/femdem_nonlocal.c; examples, not library): the CSV, VTK and SVG writers, the
 * checkpoint with its fingerprint of the options, the RESULT line, the rve test and the outputs
 * written at the end of a mesh test.
 *
 * OUTPUTS in DIR (a write that fails is an error: exit status 1)
 *   <test>.csv       one row per --every steps (steps / 200; element tests
 *                    steps / 1000): step,time,strain,stress,stress_2,p,q,
 *                    porosity,Z,u_probe,dem_steps_mean,dem_steps_max,dem_capped,
 *                    kinetic,work_int,hourglass,seconds. strain, stress:
 *                    axial (biaxial tests), u_top / h and base shear
 *                    stress (shear tests), element
 *                    9's shear strain and stress (wave); stress_2: lateral
 *                    (biaxial), normal (shear), axial (wave) stress; p, q,
 *                    porosity, Z: means over the Gauss points (wave: element
 *                    9); u_probe: right face u_x (biaxial), platen u_y
 *                    (shear), driven end u_y (wave); dem_steps of the last
 *                    run per point, dem_capped = points that stopped at
 *                    --dem-max above --iuf; kinetic = macro kinetic energy [J];
 *                    work_int = the stress work sum_e int sigma : d eps V
 *                    since step 0 [J] (trapezoidal in time, the prestress's
 *                    included), hourglass = the hourglass control's stored
 *                    energy [J] (small against the work even where the
 *                    elements deform much in their hourglass modes: see
 *                    the VTK's hourglass_strain); seconds = wall time
 *                    since the run's start, a restart going on from the
 *                    last row before its checkpoint
 *   rve_alone.csv    (element tests) strain,stress,stress_2,p,q,porosity,Z,runs
 *   rve.csv          (rve test) eps_v,p,K_MPa,gamma,tau,G_MPa,porosity_iso,
 *                    Z_iso,porosity_shear,Z_shear,dem_steps
 *   profile.csv      (simple-shear) per row of elements: y_mm, shear strain
 *                    at the step of the largest base stress (one step's, with
 *                    the column's ringing: not the peak below), shear strain
 *                    and porosity at 12 % and at the end
 *   simple-shear_profile.svg  the rows' porosity over the height at 12 %
 *                    and at the end (Fig 14a)
 *   wave_arrival.csv (wave) per element: distance from the driven end,
 *                    arrival multiscale / elastic / distance over sqrt(G/rho)
 *   mesh_NNNNNN.vtk  the deformed mesh, displacement, and per element (with
 *                    --gauss 8 the means of its eight points) stress, p, q,
 *                    porosity, coordination, particle_rotation
 *                    (mean |accumulated rotation vector| of its particles),
 *                    dem_steps, shear_strain, eps_v, eps_q, work_int,
 *                    hourglass_energy and hourglass_share = hourglass /
 *                    (hourglass + |work_int|) per element, hourglass_strain
 *                    (the amplitude of its hourglass modes over half its
 *                    size: nonlocal_macro.h); every
 *                    --vtk-every steps and at the end
 *   <test>_curve.svg (stress-strain, with the RVE alone for element tests),
 *   <test>_state.svg (porosity, Z / 10), <test>_field.svg (the deformed x-y
 *                    section coloured by shear strain, or eps_q)
 *   checkpoint.bin   every --checkpoint steps, at the end and when a step
 *                    fails: gk_twoscale's checksummed checkpoint with the
 *                    macro state (velocities, displacements, stresses, the
 *                    CSV rows, the band profiles) as its driver block and a
 *                    fingerprint of every option that changes the result, so
 *                    --restart DIR continues exactly (tested) and refuses
 *                    another run's file; --stop-after N ends early with one
 *   stdout: RESULT K_MPa= G_MPa= porosity0= Z0= peak_stress= eps_at_peak=
 *           band_center_mm= band_width_mm= seconds= (then test-specific
 *           keys; nan where a key does not apply); the mesh tests end with
 *           dem_steps_total= dt= hourglass_pct= (the hourglass energy in %
 *           of the stress work, the CSV's last row; nan while the work is
 *           not positive)
 *   Peak (simple-shear): the largest mean of the rows' stress over one period
 *   of the column's first shear mode (smoothed_peak below).
 *   Band (simple-shear): over the rows of elements, the shear strain's excess
 *   over the least row's, w_j; the band is the row of the largest w and its
 *   neighbours, contiguous, with w at least a tenth of that (a second band
 *   elsewhere is not part of it); centre = sum y w / sum w, width = sum w h
 *   / max w over them (the rectangle of the same area and height), and
 *   band_share = their share of the column's shear displacement (sum of
 *   their shear strain over all rows'), at 12 % strain (the paper's Fig 14)
 *   or at the end if it is never reached.
 *   band_porosity_center_mm, band_porosity_width_mm (simple-shear): the band
 *   as the paper reads it from its 12 row porosities (Fig 14a, "13-16 mm"):
 *   at the same strain, the rows' porosity linear between the row centres
 *   (flat over the half rows at the faces), its peak's width at half its
 *   height above the rows' median and the midpoint of the two crossings. One
 *   row above the others' level measures one row (9.8 mm on 5x12x1), one
 *   neighbour at half its excess 1.5 rows, both 2 rows. Stdout has the same
 *   measure of the shear strain's profile.
 *
 */
#ifndef NONLOCAL_IO_H
#define NONLOCAL_IO_H

#include "nonlocal_macro.h"

/* ------------------------------------------------------------ outputs */
static int write_rows(const char *path, const char *head, const double *rows, long nrow, int ncol,
                      int real0) {
    FILE *fp = fopen(path, "w");
    long r;
    int c, bad;
    if (!fp) return fprintf(stderr, "femdem_nonlocal: cannot write %s\n", path), 1;
    fprintf(fp, "%s\n", head);
    for (r = 0; r < nrow; ++r) {
        for (c = 0; c < ncol; ++c)
            fprintf(fp, c == 0 ? (real0 ? "%.9g" : "%.0f") : ",%.9g", rows[(size_t)r * ncol + c]);
        fputc('\n', fp);
    }
    bad = ferror(fp);
    if (fclose(fp) || bad) return fprintf(stderr, "femdem_nonlocal: error writing %s\n", path), 1;
    return 0;
}

static int write_vtk(model *md, const char *path) {
    gk_vtk vk;
    int e, n = md->ne, ok = 1;
    double *val = (double *)xcalloc((size_t)n, sizeof(double));
    elem_fields(md); /* cell fields: the means of an element's points (the point's own with one) */
    ok &= !gk_vtk_open(&vk, path, "femdem_nonlocal: mesh and Gauss-point fields (stress tension-positive)");
    ok &= ok && !gk_vtk_points(&vk, md->nn, md->cur.x);
    ok &= ok && !gk_vtk_cells(&vk, n, 8, md->ref.conn, GK_VTK_HEX);
    ok &= ok && !gk_vtk_point_vector(&vk, "displacement", md->u);
    ok &= ok && !gk_vtk_cell_tensor(&vk, "stress", md->sige);
#define FIELD(name, expr)                         \
    for (e = 0; e < n; ++e) {                     \
        const gk_twoscale_field *f = md->fle + e; \
        const double *H = md->He + 9 * e;         \
        (void)f, (void)H;                         \
        val[e] = (expr);                          \
    }                                             \
    ok &= ok && !gk_vtk_cell_scalar(&vk, name, val);
    FIELD("p", f->p)
    FIELD("q", f->q)
    FIELD("porosity", f->void_ratio / (1.0 + f->void_ratio))
    FIELD("coordination", f->coordination)
    FIELD("particle_rotation", f->rotation)
    FIELD("dem_steps", f->dem_steps)
    FIELD("shear_strain", H[1] + H[3])
    FIELD("eps_v", H[0] + H[4] + H[8]) {
        double eps[9];
        for (e = 0; e < n; ++e) {
            gk_m3_sym(md->He + 9 * e, eps);
            val[e] = gk_strain_q(eps, 3);
        }
        ok &= ok && !gk_vtk_cell_scalar(&vk, "eps_q", val);
    }
    FIELD("work_int", md->wint[e])
    FIELD("hourglass_energy", md->ehg[e])
    FIELD("hourglass_share", md->ehg[e] > 0.0 ? md->ehg[e] / (md->ehg[e] + fabs(md->wint[e])) : 0.0)
    FIELD("hourglass_strain", hourglass_strain(md, e))
#undef FIELD
    if (vk.fp) ok &= !gk_vtk_close(&vk);
    free(val);
    if (!ok) return fprintf(stderr, "femdem_nonlocal: error writing %s\n", path), 1;
    return 0;
}

/* the x-y section (front faces) coloured by a Gauss-point value */
static int write_field(model *md, const char *path, const char *title, const char *label, const double *val) {
    int e, a;
    double *xy = (double *)xcalloc((size_t)md->ne * 8, sizeof(double));
    gk_err err;
    gk_result r;
    for (e = 0; e < md->ne; ++e)
        for (a = 0; a < 4; ++a) { /* nodes 0-3: the z = lo face, counter-clockwise in x-y */
            int nd = md->ref.conn[8 * e + a];
            xy[8 * e + 2 * a] = 1e3 * md->cur.x[3 * nd], xy[8 * e + 2 * a + 1] = 1e3 * md->cur.x[3 * nd + 1];
        }
    r = gk_svg_field(path, title, label, md->ne, 4, xy, val, 0.0, &err);
    free(xy);
    if (r) return fprintf(stderr, "femdem_nonlocal: %s\n", err.msg), 1;
    return 0;
}

static int plot2(const char *path, const char *title, const char *xl, const char *yl, const double *x1,
                 const double *y1, int n1, const char *l1, const double *x2, const double *y2, int n2,
                 const char *l2) {
    gk_plot p;
    gk_err err;
    gk_plot_init(&p, title, xl, yl);
    gk_plot_add(&p, x1, y1, n1, l1);
    if (x2 && n2 > 0) gk_plot_add(&p, x2, y2, n2, l2);
    if (gk_plot_svg(&p, path, &err)) return fprintf(stderr, "femdem_nonlocal: %s\n", err.msg), 1;
    return 0;
}

/* ------------------------------------------------------------ checkpoint */
typedef struct ckhead {
    char magic[8];
    int32_t test, mesh[3], nd, nr, ne, ny, have12, ncol;
    int64_t step, nrow, dem_total;
    uint64_t fingerprint;
    double time, peak;
} ckhead;

static uint64_t fingerprint(const opts *o, const gk_packing *pk) {
    char buf[1024];
    uint64_t h = 1469598103934665603ull;
    size_t k;
    double sx = 0.0;
    int i;
    for (i = 0; i < pk->n; ++i) sx += pk->x[i] + 2.0 * pk->y[i] + 3.0 * pk->z[i] + 5.0 * pk->r[i];
    snprintf(buf, sizeof buf,
             "%d %d %d %d %.17g %.17g %.17g %d %d %.17g %d %d %.17g %.17g %.17g %.17g %.17g %.17g %.17g "
             "%.17g %.17g %.17g %.17g %d %d %d %.17g %.17g",
             o->test, o->mesh[0], o->mesh[1], o->mesh[2], o->R, o->pressure, o->strain, o->steps,
             o->imperfection, o->iuf, o->dem_min, o->dem_max, o->dem_damping, o->contact_damping, o->density,
             o->xi, o->mass_scale, o->kappa, o->dt, o->dt_safety, o->amplitude, o->frequency, o->duration,
             o->every, pk->n, 3, sx, o->dem_inertial);
    if (o->mix != 1.0) /* appended only when used: the fingerprints of earlier runs stay valid */
        snprintf(buf + strlen(buf), sizeof buf - strlen(buf), " mix %.17g", o->mix);
    if (o->gauss != 1) snprintf(buf + strlen(buf), sizeof buf - strlen(buf), " gauss %d", o->gauss);
    if (o->front != 1e-3) snprintf(buf + strlen(buf), sizeof buf - strlen(buf), " front %.17g", o->front);
    if (o->imperfect_row) snprintf(buf + strlen(buf), sizeof buf - strlen(buf), " imperfect-row");
    for (k = 0; buf[k]; ++k) h = (h ^ (unsigned char)buf[k]) * 1099511628211ull;
    return h;
}

static int save_checkpoint(model *md, uint64_t fp) {
    ckhead hd;
    size_t ny = (size_t)md->o->mesh[1],
           nb = sizeof hd + sizeof(double) * (2 * (size_t)md->nr + 9 * (size_t)md->np +
                                              NCOL * (size_t)md->nrow + 3 * ny + 2 * (size_t)md->ne);
    unsigned char *b = (unsigned char *)xcalloc(nb, 1), *q = b;
    char path[1024];
    int k;
    memset(&hd, 0, sizeof hd);
    memcpy(hd.magic, "GKFNL02", 8);
    hd.test = md->test;
    for (k = 0; k < 3; ++k) hd.mesh[k] = md->o->mesh[k];
    hd.nd = md->nd, hd.nr = md->nr, hd.ne = md->ne, hd.ny = (int32_t)ny, hd.have12 = md->have12,
    hd.ncol = NCOL;
    hd.step = md->step, hd.nrow = md->nrow, hd.dem_total = md->dem_total, hd.fingerprint = fp;
    hd.time = md->time, hd.peak = md->peak;
#define PUT(p, n)            \
    do {                     \
        memcpy(q, (p), (n)); \
        q += (n);            \
    } while (0)
    PUT(&hd, sizeof hd);
    PUT(md->ur, sizeof(double) * md->nr);
    PUT(md->vr, sizeof(double) * md->nr);
    PUT(md->sig, sizeof(double) * 9 * md->np);
    PUT(md->rows, sizeof(double) * NCOL * md->nrow);
    PUT(md->gam_peak, sizeof(double) * ny);
    PUT(md->prof12, sizeof(double) * 2 * ny);
    PUT(md->arrival, sizeof(double) * md->ne);
    PUT(md->wint, sizeof(double) * md->ne);
#undef PUT
    snprintf(path, sizeof path, "%s/checkpoint.bin", md->o->out);
    k = gk_twoscale_save(&md->ts, path, b, nb) != GK_OK;
    free(b);
    if (k) return fprintf(stderr, "femdem_nonlocal: %s\n", gk_twoscale_error(&md->ts)), 1;
    return 0;
}

/* what the reader writes into the model (the block and what it derives from it), kept to be put
 * back when it is refused after all: n parts, their addresses and sizes */
#define CK_NPART 24
static void ck_parts(model *md, void **p, size_t *n) {
    size_t nd = sizeof(double) * md->nd, np9 = sizeof(double) * 9 * md->np, ne = sizeof(double) * md->ne,
           ny = sizeof(double) * md->o->mesh[1];
    void *a[CK_NPART];
    size_t s[CK_NPART];
    int k = 0;
#define PART(ptr, size) a[k] = (void *)(ptr), s[k++] = (size)
    PART(&md->step, sizeof md->step), PART(&md->time, sizeof md->time), PART(&md->peak, sizeof md->peak);
    PART(&md->have12, sizeof md->have12), PART(&md->dem_total, sizeof md->dem_total);
    PART(&md->kin, sizeof md->kin), PART(md->ur, sizeof(double) * md->nr),
        PART(md->vr, sizeof(double) * md->nr);
    PART(md->sig, np9), PART(md->gam_peak, ny), PART(md->prof12, 2 * ny), PART(md->arrival, ne);
    PART(md->wint, ne), PART(md->u, nd), PART(md->v, nd), PART(md->cur.x, nd), PART(md->Hn, np9);
    PART(md->H, np9), PART(md->He, 9 * ne), PART(md->sige, 9 * ne), PART(md->fext, nd), PART(md->fint, nd);
    PART(md->fe, 24 * ne), PART(md->ehg, ne);
#undef PART
    memcpy(p, a, sizeof a), memcpy(n, s, sizeof s);
}

/* the block's values against what the run can hold (hd checked for its sizes, q its arrays): the
 * time >= 0, the peak finite or -inf, whole counters, |u| <= 10 x the specimen, arrival times -1 or
 * >= 0, rows of whole ascending steps from 0 to at most the step and seconds >= 0, every real
 * within 1e100; 0 if all hold, else what is wrong */
#define CK_MAX 1e100
static const char *ck_check(const model *md, const ckhead *hd, const unsigned char *q) {
    size_t nr = (size_t)md->nr, np = (size_t)md->np, ne = (size_t)md->ne, ny = (size_t)md->o->mesh[1], k;
    size_t rows = 2 * nr + 9 * np, prof = rows + NCOL * (size_t)hd->nrow, arr = prof + 3 * ny,
           end = arr + 2 * ne;
    double L = fmax(md->L[0], fmax(md->L[1], md->L[2])), prev = -1.0;
    if (!(hd->time >= 0.0 && hd->time <= CK_MAX) || !(fabs(hd->peak) <= CK_MAX || hd->peak == -HUGE_VAL) ||
        hd->dem_total < 0 || hd->dem_total > LONG_MAX || (hd->have12 != 0 && hd->have12 != 1))
        return "its time, peak, DEM step count or 12 % flag";
    for (k = 0; k < end; ++k) {
        double x;
        memcpy(&x, q + sizeof(double) * k, sizeof x);
        if (!(fabs(x) <= (k < nr ? 10 * L : CK_MAX)))
            return k < nr ? "a displacement" : "a non-finite or huge value";
        if (k >= arr && k < arr + ne && x != -1.0 && !(x >= 0.0)) return "an arrival time";
        if (k >= rows && k < prof && (k - rows) % NCOL == 0) { /* 0 first, then ascending */
            if (x != floor(x) || (prev < 0.0 ? x != 0.0 : x <= prev) || x > (double)hd->step)
                return "a row's step";
            prev = x;
        }
        if (k >= rows && k < prof && (k - rows) % NCOL == NCOL - 1 && x < 0.0) return "a row's seconds";
    }
    return NULL;
}

/* load_checkpoint's take (gk_twoscale_load_take): the block checked against the run, written into
 * the model over a kept copy, and the copy put back when the derived state refuses it */
typedef struct ck_take {
    model *md;
    uint64_t fp;
} ck_take;

static int take_checkpoint(const void *blk, size_t nb, void *user, char *why, size_t nwhy) {
    model *md = ((ck_take *)user)->md;
    void *part[CK_NPART];
    size_t ny = (size_t)md->o->mesh[1], need, npart[CK_NPART], nkeep = 0, k;
    ckhead hd;
    const unsigned char *q;
    const char *bad;
    unsigned char *keep;
    double *rows;
    int e;
    if (nb < sizeof hd) goto other;
    memcpy(&hd, blk, sizeof hd);
    need =
        sizeof hd + sizeof(double) * (2 * (size_t)md->nr + 9 * (size_t)md->np + 3 * ny + 2 * (size_t)md->ne);
    if (memcmp(hd.magic, "GKFNL02", 8) || hd.test != md->test || hd.nd != md->nd || hd.nr != md->nr ||
        hd.ne != md->ne || hd.ny != (int32_t)ny || hd.ncol != NCOL ||
        hd.fingerprint != ((ck_take *)user)->fp || hd.nrow < 1 || hd.step < 0 || hd.step > md->o->steps ||
        need > nb ||
        (uint64_t)hd.nrow > (nb - need) / (sizeof(double) * NCOL)) /* the row count within the file */
        goto other;
    need += sizeof(double) * NCOL * (size_t)hd.nrow;
    if (nb != need) goto other;
    /* a checksum only proves the file is what some writer wrote: check what
     * this run will trust (every value in range), all of it before anything is written */
    if ((bad = ck_check(md, &hd, (const unsigned char *)blk + sizeof hd)) != NULL)
        return snprintf(why, nwhy,
                        "the run's block holds a non-finite or out-of-range value (%s); not restarted", bad),
               1;
    /* what the model holds now, kept: the derived state below may still refuse it */
    ck_parts(md, part, npart);
    for (k = 0; k < CK_NPART; ++k) nkeep += npart[k];
    keep = (unsigned char *)xcalloc(nkeep, 1);
    for (nkeep = 0, k = 0; k < CK_NPART; ++k) memcpy(keep + nkeep, part[k], npart[k]), nkeep += npart[k];
    rows = (double *)xcalloc((size_t)hd.nrow * NCOL, sizeof(double));
    q = (const unsigned char *)blk + sizeof hd;
#define GET(p, n)            \
    do {                     \
        memcpy((p), q, (n)); \
        q += (n);            \
    } while (0)
    GET(md->ur, sizeof(double) * md->nr);
    GET(md->vr, sizeof(double) * md->nr);
    GET(md->sig, sizeof(double) * 9 * md->np);
    GET(rows, sizeof(double) * NCOL * hd.nrow);
    GET(md->gam_peak, sizeof(double) * ny);
    GET(md->prof12, sizeof(double) * 2 * ny);
    GET(md->arrival, sizeof(double) * md->ne);
    GET(md->wint, sizeof(double) * md->ne);
#undef GET
    md->step = hd.step, md->time = hd.time, md->peak = hd.peak, md->have12 = hd.have12,
    md->dem_total = (long)hd.dem_total;
    gk_dofmap_expand(&md->dm, md->ur, 0, md->u);
    gk_dofmap_expand(&md->dm, md->vr, 0, md->v);
    for (e = 0; e < md->nd; ++e) md->cur.x[e] = md->ref.x[e] + md->u[e];
    for (e = 0; e < md->np; ++e) point_grad(md, md->u, e, md->Hn + 9 * e);
    memcpy(md->H, md->Hn, sizeof(double) * 9 * md->np);
    elem_means(md);
    external_force(md);
    if (internal_force(md)) { /* an element the displacements invert: put back what was there */
        for (nkeep = 0, k = 0; k < CK_NPART; ++k) memcpy(part[k], keep + nkeep, npart[k]), nkeep += npart[k];
        free(keep), free(rows);
        return snprintf(why, nwhy, "its displacements are not a valid mesh; not restarted"), 1;
    }
    free(keep), free(md->rows);
    md->rows = rows, md->caprow = md->nrow = hd.nrow;
    md->kin = gk_explicit_kinetic_energy(md->nd, md->mass, NULL, md->v);
    return 0;
other:
    return snprintf(why, nwhy,
                    "was written by another run (test, mesh, options or packing differ), by an earlier "
                    "version of this program, or is damaged"),
           1;
}

/* DIR/checkpoint.bin (--restart): the set and the model, or neither (the reason said) */
static int load_checkpoint(model *md, uint64_t fp) {
    char path[1024];
    ck_take t;
    snprintf(path, sizeof path, "%s/checkpoint.bin", md->o->restart);
    t.md = md, t.fp = fp;
    if (gk_twoscale_load_take(&md->ts, path, take_checkpoint, &t))
        return fprintf(stderr, "femdem_nonlocal: restart: %s\n", gk_twoscale_error(&md->ts)), 1;
    printf("restarted from %s at step %ld\n", path, md->step);
    return 0;
}

static void result_line(const micro *mi, const char *extra, double pk, double epk, double bc, double bw,
                        double secs) {
    printf("RESULT K_MPa=%.2f G_MPa=%.2f porosity0=%.4f Z0=%.3f peak_stress=%.6g eps_at_peak=%.5g "
           "band_center_mm=%.3g "
           "band_width_mm=%.3g seconds=%.1f%s%s\n",
           mi->K / 1e6, mi->G / 1e6, mi->porosity0, mi->Z0, pk, epk, bc, bw, secs, extra ? " " : "",
           extra ? extra : "");
}

static int run_rve_test(const opts *o, micro *mi, double t0) {
    char path[1024];
    int n = o->steps + 11, k, r;
    double *rows = (double *)xcalloc((size_t)RVE_NCOL * n, sizeof(double));
    double *x1 = (double *)xcalloc((size_t)n, sizeof(double)),
           *y1 = (double *)xcalloc((size_t)n, sizeof(double));
    double *x2 = (double *)xcalloc((size_t)n, sizeof(double)),
           *y2 = (double *)xcalloc((size_t)n, sizeof(double));
    snprintf(path, sizeof path, "%s/rve.csv", o->out);
    r = rve_moduli(o, mi, rows) ||
        write_rows(path, "eps_v,p,K_MPa,gamma,tau,G_MPa,porosity_iso,Z_iso,porosity_shear,Z_shear,dem_steps",
                   rows, n, RVE_NCOL, 1);
    if (!r) {
        for (k = 0; k < n; ++k) {
            const double *rw = rows + RVE_NCOL * k;
            x1[k] = rw[0], y1[k] = (rw[1] - mi->p0) / 1e3, x2[k] = rw[3], y2[k] = rw[4] / 1e3;
        }
        snprintf(path, sizeof path, "%s/rve_curve.svg", o->out);
        r = plot2(path, "RVE alone: isotropic compression and simple shear", "strain (eps_v, gamma)",
                  "stress change (p - p0, tau) [kPa]", x1, y1, n, "p - p0 vs eps_v", x2, y2, n,
                  "tau vs gamma");
    }
    free(rows), free(x1), free(y1), free(x2), free(y2);
    if (r) return 1;
    printf("RVE: initial p %.0f Pa, porosity %.4f, Z %.3f, density %.1f kg/m^3; K %.1f MPa, G %.1f MPa "
           "(secants at "
           "1e-4; Table II: 335, 241)\n",
           mi->p0, mi->porosity0, mi->Z0, mi->rho, mi->K / 1e6, mi->G / 1e6);
    result_line(mi, NULL, NAN, NAN, NAN, NAN, gk_wtime() - t0);
    return 0;
}

/* a curve (x ascending in rows of `stride` values, x at 0 and y at `yc`)
 * linearly interpolated at x; NAN outside it */
static double interp(const double *c, long n, int stride, int yc, double x) {
    long k;
    for (k = 0; k + 1 < n; ++k) {
        double x0 = c[stride * k], x1 = c[stride * (k + 1)];
        if (x0 <= x && x <= x1 && x1 > x0)
            return c[stride * k + yc] +
                   (x - x0) / (x1 - x0) * (c[stride * (k + 1) + yc] - c[stride * k + yc]);
    }
    return NAN;
}

/* the element's curve against the RVE alone: both interpolated on 1000
 * strains, the mean gap over each of ten equal strain windows (DEM noise
 * averages out; both curves fluctuate by several % at critical state), the
 * largest of the ten relative to the RVE's peak; and the ratio of the peaks */
static double curve_deviation(const double *rows, long nrow, const double *lone, int nl, double S,
                              double *peak_ratio) {
    double dmax = 0.0, pl = -HUGE_VAL, pe = -HUGE_VAL;
    long r;
    int k, w;
    for (k = 0; k <= nl; ++k)
        if (lone[8 * k + 1] > pl) pl = lone[8 * k + 1];
    for (r = 0; r < nrow; ++r)
        if (rows[NCOL * r + 3] > pe) pe = rows[NCOL * r + 3];
    for (w = 0; w < 10; ++w) {
        double sum = 0.0, n = 0.0;
        for (k = 0; k < 100; ++k) {
            double x = S * (w * 100 + k + 0.5) / 1000.0;
            double ye = interp(rows + 2, nrow, NCOL, 1, x), yl = interp(lone, nl + 1, 8, 1, x);
            if (isfinite(ye) && isfinite(yl)) sum += ye - yl, n += 1;
        }
        if (n > 0 && fabs(sum / n) > dmax) dmax = fabs(sum / n);
    }
    *peak_ratio = pe / pl;
    return pl > 0 ? dmax / pl : NAN;
}

/* The simple shear's peak: the base reaction carries the column's inertia, whose first shear mode
 * (md->omega1, the frequency the macro damping is set from) rings at a period of 4 H / sqrt(G /
 * rho) (1.05 ms, about 1 % of shear strain at the default rate; with eq 57's rule the RVEs damp it
 * little and the stress of one step swings by a hundred kPa or more), so the peak is the largest
 * mean of the CSV rows' stress over one such period centred on a row (windows that fit in the
 * run), and eps_at_peak that row's strain; a run shorter than one period takes its largest row. */
static void smoothed_peak(const model *md, double period, double *pk, double *epk) {
    long r, q, n = md->nrow, lo = 0, hi = 0;
    double t0 = n ? md->rows[1] : 0.0, t1 = n ? md->rows[NCOL * (n - 1) + 1] : 0.0;
    *pk = -HUGE_VAL, *epk = NAN;
    if (t1 - t0 < period) { /* a run shorter than one period: its largest row */
        for (r = 0; r < n; ++r)
            if (md->rows[NCOL * r + 3] > *pk) *pk = md->rows[NCOL * r + 3], *epk = md->rows[NCOL * r + 2];
        return;
    }
    for (r = 0; r < n; ++r) { /* the rows within period / 2 of row r: [lo, hi), lo <= r < hi */
        double t = md->rows[NCOL * r + 1], sum = 0.0;
        while (hi < n && md->rows[NCOL * hi + 1] <= t + 0.5 * period) ++hi;
        while (md->rows[NCOL * lo + 1] < t - 0.5 * period) ++lo;
        if (t - 0.5 * period < t0 || t + 0.5 * period > t1) continue; /* the window is not whole */
        for (q = lo; q < hi; ++q) sum += md->rows[NCOL * q + 3];
        if (sum / (double)(hi - lo) > *pk) *pk = sum / (double)(hi - lo), *epk = md->rows[NCOL * r + 2];
    }
}

/* the outputs at the end of a mesh test: the last VTK, the test's own files and plots (the RVE
 * alone, the wave front, the shear profile), the state and field plots, the RESULT line; every
 * failure goes to the one exit that frees the buffers */
static int final_outputs(const opts *o, micro *mi, model *md, double t0) {
    char path[1024];
    int e, k;
    long r, n = md->nrow;
    double *x = (double *)xcalloc((size_t)n, sizeof(double)),
           *y = (double *)xcalloc((size_t)n, sizeof(double));
    double *y2 = (double *)xcalloc((size_t)n, sizeof(double)),
           *val = (double *)xcalloc((size_t)md->ne, sizeof(double));
    double *lone = NULL, *lx = NULL, *ly = NULL, *ae = NULL, *pe = NULL;
    double pk = -HUGE_VAL, epk = NAN, bc = NAN, bw = NAN;
    char extra[1024], svg[1024];
    int rc = 1;
    extra[0] = 0;
    for (r = 0; r < n; ++r) {
        const double *row = md->rows + NCOL * r;
        x[r] = o->test == T_WAVE ? row[1] * 1e3 : row[2];
        y[r] = row[3] / 1e3;
        if (row[3] > pk) pk = row[3], epk = row[2];
    }
    snprintf(path, sizeof path, "%s/mesh_%06ld.vtk", o->out, md->step);
    if (write_vtk(md, path)) goto done;
    if (o->test == T_EBIAX || o->test == T_ESHEAR) {
        int nl = o->lone;
        double dev, pkr;
        lone = (double *)xcalloc((size_t)8 * (nl + 1), sizeof(double));
        printf("the RVE alone on the same path (%d increments)...\n", nl);
        if (rve_alone(o, mi, nl, lone)) goto done;
        snprintf(path, sizeof path, "%s/rve_alone.csv", o->out);
        {
            FILE *fp = fopen(path, "w");
            int k2, bad;
            if (!fp) {
                fprintf(stderr, "femdem_nonlocal: cannot write %s\n", path);
                goto done;
            }
            fprintf(fp, "strain,stress,stress_2,p,q,porosity,Z,runs\n");
            for (k2 = 0; k2 <= nl; ++k2)
                fprintf(fp, "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.0f\n", lone[8 * k2], lone[8 * k2 + 1],
                        lone[8 * k2 + 2], lone[8 * k2 + 3], lone[8 * k2 + 4], lone[8 * k2 + 5],
                        lone[8 * k2 + 6], lone[8 * k2 + 7]);
            bad = ferror(fp);
            if (fclose(fp) || bad) {
                fprintf(stderr, "femdem_nonlocal: error writing %s\n", path);
                goto done;
            }
        }
        dev = curve_deviation(md->rows, md->nrow, lone, nl, o->strain, &pkr);
        lx = (double *)xcalloc((size_t)nl + 1, sizeof(double)),
        ly = (double *)xcalloc((size_t)nl + 1, sizeof(double));
        for (k = 0; k <= nl; ++k) lx[k] = lone[8 * k], ly[k] = lone[8 * k + 1] / 1e3;
        snprintf(svg, sizeof svg, "%s/%s_curve.svg", o->out, test_name[o->test]);
        if (plot2(svg,
                  o->test == T_EBIAX ? "one element, biaxial (Fig 6a)" : "one element, simple shear (Fig 6b)",
                  o->test == T_EBIAX ? "axial strain" : "shear strain u_top / h",
                  o->test == T_EBIAX ? "axial stress [kPa]" : "shear stress [kPa]", x, y, (int)n,
                  "FEMxDEM, 1 element", lx, ly, nl + 1, "RVE alone"))
            goto done;
        snprintf(extra, sizeof extra, "rve_alone_dev_pct=%.3f peak_ratio=%.4f", 100.0 * dev, pkr);
        printf("one element against the RVE alone: largest gap of the 10 strain-window means %.2f %% of the "
               "peak; peaks %.4f\n",
               100.0 * dev, pkr);
    } else if (o->test == T_WAVE) {
        double cm, ce, cs;
        FILE *fp;
        int bad;
        ae = (double *)xcalloc((size_t)md->ne, sizeof(double));
        wave_elastic(md, ae);
        cm = front_speed(md, md->arrival), ce = front_speed(md, ae),
        cs = sqrt(mi->G / (mi->rho * o->mass_scale));
        snprintf(path, sizeof path, "%s/wave_arrival.csv", o->out);
        fp = fopen(path, "w");
        if (!fp) {
            fprintf(stderr, "femdem_nonlocal: cannot write %s\n", path);
            goto done;
        }
        fprintf(fp, "element,distance_mm,arrival_us,arrival_elastic_us,arrival_sqrtGrho_us\n");
        for (e = 0; e < md->ne; ++e) {
            double dd = md->L[0] - (e + 0.5) * md->L[0] / md->ne;
            fprintf(fp, "%d,%.6g,%.6g,%.6g,%.6g\n", e + 1, 1e3 * dd, 1e6 * md->arrival[e], 1e6 * ae[e],
                    1e6 * dd / cs);
        }
        bad = ferror(fp);
        if (fclose(fp) || bad) {
            fprintf(stderr, "femdem_nonlocal: error writing %s\n", path);
            goto done;
        }
        snprintf(extra, sizeof extra, "wave_speed_ms=%.2f wave_speed_elastic_ms=%.2f sqrtGrho_ms=%.2f", cm,
                 ce, cs);
        printf("shear-wave front: %.1f m/s (multiscale), %.1f m/s (elastic, same mesh), sqrt(G/rho) = "
               "%.1f m/s\n",
               cm, ce, cs);
        for (r = 0; r < n; ++r) x[r] = md->rows[NCOL * r + 2], y[r] = md->rows[NCOL * r + 3] / 1e3;
        snprintf(svg, sizeof svg, "%s/wave_curve.svg", o->out);
        if (plot2(svg, "wave column: element 9 (Fig 8a)", "shear strain", "shear stress [kPa]", x, y, (int)n,
                  "element 9", NULL, NULL, 0, NULL))
            goto done;
    } else {
        if (o->test == T_SSHEAR) {
            int ny = o->mesh[1], j, bad;
            FILE *fp;
            double *yv, share, pc, pw, gc, gw;
            const double *pr;
            /* pe: the end's profile (shear strain, porosity), then the rows' heights [mm] */
            pe = (double *)xcalloc((size_t)3 * ny, sizeof(double)), yv = pe + 2 * ny;
            smoothed_peak(md, 2.0 * GK_PI / md->omega1, &pk, &epk);
            elem_fields(md);
            row_profile(md, pe);
            for (j = 0; j < ny; ++j) yv[j] = 1e3 * (j + 0.5) * md->L[1] / ny;
            pr = md->have12 ? md->prof12 : pe;
            band(md, pr, &bc, &bw, &share);
            peak_fwhm(md, pr + ny, &pc, &pw);
            peak_fwhm(md, pr, &gc, &gw);
            snprintf(extra, sizeof extra,
                     "band_share=%.3f band_porosity_center_mm=%.4g band_porosity_width_mm=%.4g", share, pc,
                     pw);
            snprintf(path, sizeof path, "%s/profile.csv", o->out);
            fp = fopen(path, "w");
            if (!fp) {
                fprintf(stderr, "femdem_nonlocal: cannot write %s\n", path);
                goto done;
            }
            fprintf(fp, "row,y_mm,gamma_max_stress_step,gamma_12,porosity_12,gamma_end,porosity_end\n");
            for (j = 0; j < ny; ++j)
                fprintf(fp, "%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", j, yv[j], md->gam_peak[j],
                        md->have12 ? md->prof12[j] : NAN, md->have12 ? md->prof12[ny + j] : NAN, pe[j],
                        pe[ny + j]);
            bad = ferror(fp);
            if (fclose(fp) || bad) {
                fprintf(stderr, "femdem_nonlocal: error writing %s\n", path);
                goto done;
            }
            printf("band (shear strain above the least row's, at %s): centre %.1f mm, width %.1f mm, %.0f %% "
                   "of the shear displacement\n",
                   md->have12 ? "12 %" : "the end", bc, bw, 100.0 * share);
            printf(
                "the rows' peak at half its height above their median (Fig 14a's reading): porosity centre "
                "%.1f mm, width %.1f mm; shear strain centre %.1f mm, width %.1f mm\n",
                pc, pw, gc, gw);
            snprintf(svg, sizeof svg, "%s/simple-shear_profile.svg", o->out);
            if (plot2(svg, "porosity over the height (Fig 14a)", "porosity of the row", "height [mm]",
                      pr + ny, yv, ny, md->have12 ? "at 12 %" : "at the end", md->have12 ? pe + ny : NULL, yv,
                      ny, "at the end"))
                goto done;
        }
        snprintf(svg, sizeof svg, "%s/%s_curve.svg", o->out, test_name[o->test]);
        if (plot2(svg, o->test == T_SSHEAR ? "simple shear (Fig 10)" : "plane-strain biaxial (Figs 16, 18)",
                  o->test == T_SSHEAR ? "shear strain u_top / h" : "axial strain",
                  o->test == T_SSHEAR ? "shear stress [kPa]" : "axial stress [kPa]", x, y, (int)n, "FEMxDEM",
                  NULL, NULL, 0, NULL))
            goto done;
    }
    /* state curves: porosity and Z */
    for (r = 0; r < n; ++r) y[r] = md->rows[NCOL * r + 7], y2[r] = md->rows[NCOL * r + 8] / 10.0;
    snprintf(svg, sizeof svg, "%s/%s_state.svg", o->out, test_name[o->test]);
    if (plot2(svg, "porosity and coordination (Figs 8b, 12, 13)", o->test == T_WAVE ? "time [ms]" : "strain",
              "porosity, Z / 10", x, y, (int)n, "porosity", x, y2, (int)n, "Z / 10"))
        goto done;
    for (e = 0; e < md->ne; ++e) val[e] = md->He[9 * e + 1] + md->He[9 * e + 3];
    if (o->test == T_BIAX || o->test == T_EBIAX)
        for (e = 0; e < md->ne; ++e) {
            double eps[9];
            gk_m3_sym(md->He + 9 * e, eps);
            val[e] = gk_strain_q(eps, 3);
        }
    snprintf(svg, sizeof svg, "%s/%s_field.svg", o->out, test_name[o->test]);
    if (write_field(md, svg, "deformed mesh",
                    o->test == T_BIAX || o->test == T_EBIAX ? "eps_q" : "shear strain", val))
        goto done;
    {
        char ex2[1200];
        const double *last = md->rows + NCOL * (n - 1), w = last[14], h = last[15]; /* this step's row */
        snprintf(ex2, sizeof ex2, "%s%sdem_steps_total=%ld dt=%.4g hourglass_pct=%.3g", extra,
                 extra[0] ? " " : "", md->dem_total, md->dt, w > 0.0 ? 100.0 * h / w : NAN);
        result_line(mi, ex2, pk, epk, bc, bw, gk_wtime() - t0);
    }
    rc = 0;
done:
    free(x), free(y), free(y2), free(val), free(lone), free(lx), free(ly), free(ae), free(pe);
    return rc;
}

#endif /* NONLOCAL_IO_H */
