/* mpmdem_io.h - what the MPMxDEM drivers write (examples, not library;
 * included by mpmdem.h, which the drivers include).
 *
 *   mpd_write, mpd_plot    a text file / a gk_plot into the output folder
 *   mpd_write_vtk          the points with every field for ParaView
 *   mpd_snap_add, mpd_snap_field   field pictures on one colour scale per
 *                          quantity (top comment of mpmdem.h)
 *   mpd_rows               the CSV rows of a driver
 *   mpd_save, mpd_load     the checkpoint: gk_twoscale's file and the driver
 *                          block (points, strains, state, rows, snapshots)
 *
 * Rank 0 alone writes (under MPI); every function returns 0, or 1 after
 * saying what could not be written, on every rank.
 */
#include "mpmdem.h" /* included alone: mpmdem.h, which includes this file where it needs it */
#ifndef MPMDEM_IO_H
#define MPMDEM_IO_H

/* ------------------------------------------------------------- files */
/* rank 0 writes DIR/name by put(fp, user); 0 or 1 (said) */
static int mpd_write(const mpd_run *run, const char *name, void (*put)(FILE *fp, const void *user),
                     const void *user) {
    char path[MPD_PATH];
    FILE *fp;
    int bad = 0;
    if (run->rank == 0) {
        if (mpd_path(run, path, name))
            bad = 1;
        else if (!(fp = fopen(path, "w")))
            bad = mpd_write_failed(run, path, strerror(errno));
        else {
            put(fp, user);
            if (ferror(fp) | fclose(fp)) bad = mpd_write_failed(run, path, NULL);
        }
    }
    return mpd_agree(run, bad);
}

/* a gk_plot into DIR/name; 0 or 1 (said) */
static int mpd_plot(const mpd_run *run, const gk_plot *pl, const char *name) {
    char path[MPD_PATH];
    gk_err err;
    int bad = 0;
    if (run->rank == 0) {
        if (mpd_path(run, path, name))
            bad = 1;
        else if (gk_plot_svg(pl, path, &err))
            bad = mpd_write_failed(run, path, NULL);
    }
    return mpd_agree(run, bad);
}

/* ------------------------------------------------------------- VTK */
/* the points as VTK vertices: the fields above, velocity, stress; 0 or 1 (said) */
GK_INLINE int mpd_write_vtk(const mpd_run *run, long step, mpd_micro *m, const gk_mpm_points *pts) {
    char path[MPD_PATH], name[64];
    gk_vtk v;
    gk_err err;
    int n = pts->n, p, k, ok, bad = 0;
    double *xyz = (double *)malloc(3 * (size_t)n * sizeof *xyz),
           *vel = (double *)malloc(3 * (size_t)n * sizeof *vel);
    double *fld = (double *)malloc((size_t)MPD_NFIELD * n * sizeof *fld);
    int *conn = (int *)malloc((size_t)n * sizeof *conn);
    snprintf(name, sizeof name, "points_%06ld.vtk", step);
    ok = xyz && vel && conn && fld && mpd_fields(m, pts, fld, &err) == GK_OK;
    if (run->rank == 0) {
        if (mpd_path(run, path, name))
            bad = 1;
        else if (!ok)
            bad = mpd_write_failed(run, path, "out of memory or a field failed");
        else {
            for (p = 0; p < n; ++p) {
                xyz[3 * p] = pts->x[0][p], xyz[3 * p + 1] = pts->x[1][p], xyz[3 * p + 2] = 0.0;
                vel[3 * p] = pts->v[0][p], vel[3 * p + 1] = pts->v[1][p], vel[3 * p + 2] = 0.0;
                conn[p] = p;
            }
            ok = !gk_vtk_open(&v, path, "grainkit MPMxDEM material points") && !gk_vtk_points(&v, n, xyz) &&
                 !gk_vtk_cells(&v, n, 1, conn, GK_VTK_VERTEX);
            for (k = 0; ok && k < MPD_NFIELD; ++k)
                ok = !gk_vtk_point_scalar(&v, mpd_field_names[k], fld + (size_t)k * n);
            ok = ok && !gk_vtk_point_vector(&v, "velocity", vel) &&
                 !gk_vtk_point_tensor(&v, "stress", pts->sigma);
            if (v.fp) ok = !gk_vtk_close(&v) && ok;
            if (!ok) bad = mpd_write_failed(run, path, NULL);
        }
    }
    free(xyz), free(vel), free(conn), free(fld);
    return mpd_agree(run, bad);
}

/* ------------------------------------------------------- field pictures */
#define MPD_MAXLINE 4 /* outline polylines of a picture */
#define MPD_MAXLPT 6  /* points of one */
typedef struct mpd_outline {
    int nlines, len[MPD_MAXLINE];
    double xy[2 * MPD_MAXLINE * MPD_MAXLPT];
} mpd_outline;

/* a polyline of npts (x, y) points added to the outline */
GK_INLINE void mpd_outline_add(mpd_outline *o, int npts, const double *xy) {
    int used = 0, k;
    if (o->nlines == MPD_MAXLINE || npts > MPD_MAXLPT) return;
    for (k = 0; k < o->nlines; ++k) used += o->len[k];
    memcpy(o->xy + 2 * used, xy, 2 * (size_t)npts * sizeof(double));
    o->len[o->nlines++] = npts;
}

typedef struct mpd_snap {
    char file[48], title[160], label[48]; /* file name without .svg; the colour bar's quantity */
    int n;
    double dot, *xy, *v; /* dot radius [m]; the points and the values */
    mpd_outline ol;
} mpd_snap;

typedef struct mpd_snaps {
    int n, cap;
    mpd_snap *s;
} mpd_snaps;

static void mpd_snaps_free(mpd_snaps *S) {
    int k;
    for (k = 0; k < S->n; ++k) free(S->s[k].xy), free(S->s[k].v);
    free(S->s);
    S->n = S->cap = 0, S->s = NULL;
}

/* a new snapshot slot with room for n points (NULL: out of memory) */
static mpd_snap *mpd_snap_new(mpd_snaps *S, int n) {
    mpd_snap *s;
    if (S->n == S->cap) {
        int cap = S->cap ? 2 * S->cap : 16;
        mpd_snap *g = (mpd_snap *)realloc(S->s, (size_t)cap * sizeof *g);
        if (!g) return NULL;
        S->s = g, S->cap = cap;
    }
    s = &S->s[S->n];
    memset(s, 0, sizeof *s);
    s->n = n;
    s->xy = (double *)malloc(2 * (size_t)n * sizeof(double) + 1);
    s->v = (double *)malloc((size_t)n * sizeof(double) + 1);
    if (!s->xy || !s->v) {
        free(s->xy), free(s->v);
        return NULL;
    }
    ++S->n;
    return s;
}

/* every snapshot with this label (the quantity) on the colour range of all of them; 0 or 1 (said) */
static int mpd_snap_write_all(const mpd_run *run, const mpd_snaps *S, const char *label) {
    gk_field_def d;
    gk_err err;
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    char path[MPD_PATH], name[64];
    int k, p;
    for (k = 0; k < S->n; ++k)
        if (!strcmp(S->s[k].label, label))
            for (p = 0; p < S->s[k].n; ++p)
                if (isfinite(S->s[k].v[p])) lo = fmin(lo, S->s[k].v[p]), hi = fmax(hi, S->s[k].v[p]);
    for (k = 0; k < S->n; ++k) {
        const mpd_snap *s = &S->s[k];
        if (strcmp(s->label, label)) continue;
        memset(&d, 0, sizeof d);
        d.title = s->title, d.label = s->label, d.dot = s->dot;
        d.fixed_range = hi > lo, d.vmin = lo, d.vmax = hi; /* one value everywhere: the plot's own */
        d.nlines = s->ol.nlines, d.line_len = s->ol.len, d.line_xy = s->ol.xy;
        snprintf(name, sizeof name, "%s.svg", s->file);
        if (mpd_path(run, path, name)) return 1;
        if (gk_field_svg(path, &d, s->n, 1, s->xy, s->v, &err)) return mpd_write_failed(run, path, NULL);
    }
    return 0;
}

/* a snapshot of v[n] on the points (file DIR/file.svg, colour bar `label`), kept so that every
 * snapshot of the quantity shares one scale; 0 or 1 (said) */
static int mpd_snap_add(const mpd_run *run, mpd_snaps *S, const char *file, const char *title,
                        const char *label, const gk_mpm_points *pts, const double *v, double dot,
                        const mpd_outline *ol) {
    int bad = 0, p;
    mpd_snap *s = mpd_snap_new(S, pts->n);
    if (!s)
        bad = 1, fprintf(stderr, "%s: out of memory for the snapshot %s\n", run->prog, file);
    else {
        snprintf(s->file, sizeof s->file, "%s", file);
        snprintf(s->title, sizeof s->title, "%s", title);
        snprintf(s->label, sizeof s->label, "%s", label);
        s->dot = dot, s->ol = *ol;
        for (p = 0; p < pts->n; ++p)
            s->xy[2 * p] = pts->x[0][p], s->xy[2 * p + 1] = pts->x[1][p], s->v[p] = v[p];
        if (run->rank == 0) bad = mpd_snap_write_all(run, S, label);
    }
    return mpd_agree(run, bad);
}

/* one field of mpd_fields as a snapshot, strains in % */
GK_INLINE int mpd_snap_field(const mpd_run *run, mpd_snaps *S, mpd_micro *m, const gk_mpm_points *pts, int k,
                             const char *file, const char *title, double dot, const mpd_outline *ol) {
    static const char *labels[MPD_NFIELD] = {
        "eps_q [%]",      "eps_v [%]",        "rotation [deg]",     "p [Pa]",       "q [Pa]",
        "void ratio [-]", "fabric |F_a| [-]", "coordination Z [-]", "DEM steps [-]"};
    double *f = (double *)malloc((size_t)MPD_NFIELD * pts->n * sizeof *f + 1), *v;
    gk_err err;
    int bad, p;
    if (!f || mpd_fields(m, pts, f, &err)) {
        free(f);
        fprintf(stderr, "%s: the fields of %s: %s\n", run->prog, file, f ? err.msg : "out of memory");
        return 1;
    }
    v = f + (size_t)k * pts->n;
    if (k == MPD_EPS_Q || k == MPD_EPS_V)
        for (p = 0; p < pts->n; ++p) v[p] *= 100.0;
    bad = mpd_snap_add(run, S, file, title, labels[k], pts, v, dot, ol);
    free(f);
    return bad;
}

/* ------------------------------------------------------------- CSV rows */
typedef struct mpd_rows {
    unsigned char *r;
    size_t size; /* bytes of one row */
    int n, cap;
} mpd_rows;

static void *mpd_row(const mpd_rows *R, int k) { return R->r + (size_t)k * R->size; }

/* appends a row; 0, or 1 out of memory (said) */
static int mpd_rows_push(const mpd_run *run, mpd_rows *R, const void *row) {
    if (R->n == R->cap) {
        int cap = R->cap ? 2 * R->cap : 64;
        unsigned char *g = (unsigned char *)realloc(R->r, (size_t)cap * R->size);
        if (!g) return fprintf(stderr, "%s: out of memory for %d CSV rows\n", run->prog, cap), 1;
        R->r = g, R->cap = cap;
    }
    memcpy(mpd_row(R, R->n++), row, R->size);
    return 0;
}

/* ------------------------------------------------------------ checkpoint */
/* gk_twoscale_save's file with the driver block: a tag, the point count, every point array of gk_mpm,
 * the point strains, DEM-step counters, frozen-point counts, the driver's state struct, its rows and
 * the snapshots, each variable part preceded by its size. */
#define MPD_BLOCK_TAG "GKMPMDEM2"
typedef struct mpd_buf {
    unsigned char *b;
    size_t n, cap;
    int bad;
} mpd_buf;

static void mpd_put(mpd_buf *B, const void *p, size_t n) {
    if (B->bad || !n) return;
    if (B->n + n > B->cap) {
        size_t cap = 2 * (B->n + n) + 1024;
        unsigned char *g = (unsigned char *)realloc(B->b, cap);
        if (!g) {
            B->bad = 1;
            return;
        }
        B->b = g, B->cap = cap;
    }
    memcpy(B->b + B->n, p, n);
    B->n += n;
}
/* reading: the same calls; B->bad once past the end */
static void mpd_get(mpd_buf *B, void *p, size_t n) {
    if (B->bad || n > B->cap - B->n) {
        B->bad = 1;
        return;
    }
    if (n) memcpy(p, B->b + B->n, n);
    B->n += n;
}
static void mpd_io(mpd_buf *B, void *p, size_t n, int wr) {
    if (wr)
        mpd_put(B, p, n);
    else
        mpd_get(B, p, n);
}
/* a variable part: its size, then its bytes (allocated when reading; at most `max` bytes) */
static void mpd_io_var(mpd_buf *B, void **p, size_t *n, size_t max, int wr) {
    uint64_t u = *n;
    mpd_io(B, &u, 8, wr);
    if (wr) {
        mpd_put(B, *p, *n);
        return;
    }
    if (B->bad || u > max || u > B->cap - B->n || !(*p = malloc((size_t)u + 1))) {
        B->bad = 1;
        return;
    }
    *n = (size_t)u;
    mpd_get(B, *p, *n);
}

/* the block both ways (wr: into B; else from B into the driver's memory) */
static void mpd_block(mpd_buf *B, const char *tag, mpd_micro *m, gk_mpm_points *pts, void *S, size_t nS,
                      mpd_rows *R, mpd_snaps *sn, int wr) {
    char t[32], want[32];
    int32_t np = pts->n, k, ns = sn->n;
    uint64_t us = nS;
    double *a1[10];
    double *a9[4];
    void *rows = R->r;
    size_t nrows = (size_t)R->n * R->size;
    a1[0] = pts->x[0], a1[1] = pts->x[1], a1[2] = pts->v[0], a1[3] = pts->v[1], a1[4] = pts->fext[0];
    a1[5] = pts->fext[1], a1[6] = pts->m, a1[7] = pts->vol0, a1[8] = pts->vol, a1[9] = pts->lp;
    a9[0] = pts->F, a9[1] = pts->L, a9[2] = pts->sigma, a9[3] = pts->C;
    memset(want, 0, sizeof want);
    snprintf(want, sizeof want, "%s %s", MPD_BLOCK_TAG, tag);
    memcpy(t, want, sizeof t);
    mpd_io(B, t, sizeof t, wr);
    mpd_io(B, &np, 4, wr);
    mpd_io(B, &us, 8, wr);
    if (!wr && (memcmp(t, want, sizeof t) || np != pts->n || us != nS)) B->bad = 1;
    for (k = 0; k < 10; ++k) mpd_io(B, a1[k], (size_t)np * sizeof(double), wr);
    for (k = 0; k < 4; ++k) mpd_io(B, a9[k], 9 * (size_t)np * sizeof(double), wr);
    mpd_io(B, m->eps, 9 * (size_t)np * sizeof(double), wr);
    mpd_io(B, m->thin, (size_t)np * sizeof(int), wr);
    mpd_io(B, &m->dem_steps, sizeof m->dem_steps, wr);
    mpd_io(B, S, nS, wr);
    mpd_io_var(B, &rows, &nrows, (size_t)1 << 31, wr);
    if (!wr && !B->bad) {
        if (nrows % R->size || nrows / R->size > (1u << 30)) B->bad = 1;
        R->r = (unsigned char *)rows, R->n = R->cap = (int)(nrows / R->size);
    }
    mpd_io(B, &ns, 4, wr);
    if (ns < 0 || ns > 100000) B->bad = 1;
    for (k = 0; k < ns && !B->bad; ++k) {
        int32_t n = wr ? sn->s[k].n : 0;
        mpd_snap *s;
        mpd_io(B, &n, 4, wr);
        if (!wr && (n < 1 || n > (1 << 26) || !mpd_snap_new(sn, n))) B->bad = 1;
        if (B->bad) break;
        s = &sn->s[k];
        mpd_io(B, s->file, sizeof s->file, wr), mpd_io(B, s->title, sizeof s->title, wr);
        mpd_io(B, s->label, sizeof s->label, wr), mpd_io(B, &s->dot, sizeof s->dot, wr);
        mpd_io(B, &s->ol, sizeof s->ol, wr);
        mpd_io(B, s->xy, 2 * (size_t)n * sizeof(double), wr), mpd_io(B, s->v, (size_t)n * sizeof(double), wr);
        s->file[sizeof s->file - 1] = s->title[sizeof s->title - 1] = s->label[sizeof s->label - 1] = 0;
        if (s->ol.nlines < 0 || s->ol.nlines > MPD_MAXLINE) B->bad = 1;
    }
    if (!wr && B->n != B->cap) B->bad = 1; /* nothing may follow */
}

/* DIR/checkpoint.bin: the RVEs and the driver's block; 0 or 1 (said) */
GK_INLINE int mpd_save(const mpd_run *run, mpd_micro *m, gk_mpm_points *pts, const char *tag, void *S,
                       size_t nS, mpd_rows *R, mpd_snaps *sn) {
    mpd_buf B;
    char path[MPD_PATH];
    int bad = mpd_path(run, path, "checkpoint.bin");
    memset(&B, 0, sizeof B);
    if (!bad) mpd_block(&B, tag, m, pts, S, nS, R, sn, 1);
    bad = mpd_agree(run, bad || B.bad);
    if (!bad && gk_twoscale_save(&m->ts, path, B.b, B.n))
        bad = mpd_write_failed(run, path, gk_twoscale_error(&m->ts));
    free(B.b);
    return bad;
}

/* DIR/checkpoint.bin back into the set, the points and the driver's state, rows and snapshots */
/* DIR/checkpoint.bin into path (MPD_PATH bytes); 1 if it does not fit */
static int mpd_checkpoint_path(const char *dir, char *path) {
    return snprintf(path, MPD_PATH, "%s/checkpoint.bin", dir) >= MPD_PATH;
}

/* the largest magnitude a value read from a checkpoint may have: a finite strain of 1e178 is no state,
 * and its squares overflow (eps_q came out Inf); so values beyond it are refused as non-finite ones */
#define MPD_MAX_VALUE 1e100
static int mpd_sane(double v) { return fabs(v) <= MPD_MAX_VALUE; }

/* the driver's own check of its state and rows as read, against its run (ctx: the driver's model, as
 * given to mpd_load): 0 in range, or 1 with the reason in why */
typedef int (*mpd_check_fn)(const void *S, const mpd_rows *R, const void *ctx, char *why, size_t nwhy);

/* the block as read, checked: every point value finite and within MPD_MAX_VALUE, mass, volumes,
 * half-size >= 0 (mass and volume > 0), det F > 0 and vol = det(F) vol0 (to 1e-9 relative: gk_mpm
 * keeps them so), refusal counts and DEM steps >= 0; every snapshot's points finite, its dot > 0 and
 * its outline's polylines within MPD_MAXLPT points. 0, or 1 with the reason in why. */
static int mpd_block_check(const mpd_micro *m, const gk_mpm_points *pts, const mpd_snaps *sn, char *why,
                           size_t nwhy) {
    int n = pts->n, p, k, j;
    for (p = 0; p < n; ++p) {
        const double *F = pts->F + 9 * (size_t)p;
        double v[10], det;
        v[0] = pts->x[0][p], v[1] = pts->x[1][p], v[2] = pts->v[0][p], v[3] = pts->v[1][p];
        v[4] = pts->fext[0][p], v[5] = pts->fext[1][p], v[6] = pts->m[p], v[7] = pts->vol0[p];
        v[8] = pts->vol[p], v[9] = pts->lp[p];
        for (k = 0; k < 10; ++k)
            if (!mpd_sane(v[k]))
                return snprintf(why, nwhy, "point %d: a non-finite value (or one above 1e100)", p), 1;
        for (k = 0; k < 9; ++k)
            if (!mpd_sane(F[k]) || !mpd_sane(pts->L[9 * (size_t)p + k]) ||
                !mpd_sane(pts->sigma[9 * (size_t)p + k]) || !mpd_sane(pts->C[9 * (size_t)p + k]) ||
                !mpd_sane(m->eps[9 * (size_t)p + k]))
                return snprintf(why, nwhy, "point %d: a non-finite tensor (or an entry above 1e100)", p), 1;
        det = F[0] * F[4] - F[1] * F[3];
        if (!(v[6] > 0) || !(v[7] > 0) || !(v[8] > 0) || v[9] < 0 || !(det > 0) ||
            !(fabs(v[8] - det * v[7]) <= 1e-9 * v[8]) || m->thin[p] < 0)
            return snprintf(why, nwhy, "point %d: mass, volume, det F or half-size out of range", p), 1;
    }
    if (m->dem_steps < 0) return snprintf(why, nwhy, "a negative DEM-step count"), 1;
    for (k = 0; k < sn->n; ++k) {
        const mpd_snap *s = &sn->s[k];
        int used = 0;
        if (!(s->dot > 0) || !mpd_sane(s->dot)) return snprintf(why, nwhy, "snapshot %d: dot size", k), 1;
        for (j = 0; j < s->ol.nlines; ++j) {
            if (s->ol.len[j] < 0 || s->ol.len[j] > MPD_MAXLPT)
                return snprintf(why, nwhy, "snapshot %d: outline", k), 1;
            used += s->ol.len[j];
        }
        for (j = 0; j < 2 * used; ++j)
            if (!mpd_sane(s->ol.xy[j])) return snprintf(why, nwhy, "snapshot %d: outline", k), 1;
        for (j = 0; j < 2 * s->n; ++j)
            if (!mpd_sane(s->xy[j])) return snprintf(why, nwhy, "snapshot %d: a non-finite point", k), 1;
    }
    return 0;
}

/* mpd_load's driver part (gk_twoscale_load_take's take): the block read into the model over a kept
 * copy, checked, and put back when refused */
typedef struct mpd_take {
    mpd_micro *m;
    gk_mpm_points *pts;
    const char *tag;
    void *S;
    size_t nS;
    mpd_rows *R;
    mpd_snaps *sn;
    mpd_check_fn check;
    const void *ctx;
    int oom;
} mpd_take;

static int mpd_take_block(const void *blk, size_t nblk, void *user, char *why, size_t nwhy) {
    mpd_take *t = (mpd_take *)user;
    mpd_buf B, K;
    mpd_rows R2 = *t->R, Rk = *t->R;
    mpd_snaps sn2, snk;
    /* what the block overwrites, kept (the same format, without rows and snapshots) */
    memset(&K, 0, sizeof K), memset(&sn2, 0, sizeof sn2), memset(&snk, 0, sizeof snk);
    R2.r = NULL, R2.n = R2.cap = 0, Rk.r = NULL, Rk.n = Rk.cap = 0;
    mpd_block(&K, t->tag, t->m, t->pts, t->S, t->nS, &Rk, &snk, 1);
    if (K.bad) {
        free(K.b), t->oom = 1;
        return snprintf(why, nwhy, "out of memory"), 1;
    }
    memset(&B, 0, sizeof B);
    B.b = (unsigned char *)(uintptr_t)blk, B.cap = nblk; /* read only (wr = 0) */
    mpd_block(&B, t->tag, t->m, t->pts, t->S, t->nS, &R2, &sn2, 0);
    if (B.bad)
        snprintf(why, nwhy, "its driver block is not that of an mpmdem_%s run of %d points with these flags",
                 t->tag, t->pts->n);
    if (B.bad || mpd_block_check(t->m, t->pts, &sn2, why, nwhy) || t->check(t->S, &R2, t->ctx, why, nwhy)) {
        K.cap = K.n, K.n = 0; /* read back what was there */
        mpd_block(&K, t->tag, t->m, t->pts, t->S, t->nS, &Rk, &snk, 0);
        free(K.b), free(R2.r), free(Rk.r), mpd_snaps_free(&sn2), mpd_snaps_free(&snk);
        return 1;
    }
    free(K.b), free(t->R->r), mpd_snaps_free(t->sn);
    *t->R = R2, *t->sn = sn2;
    return 0;
}

/* DIR/checkpoint.bin into the set, the points, the driver's state S, its rows and snapshots (the
 * rows and snapshots it had are freed). The block is read and checked (mpd_block_check, then the
 * driver's check with ctx) before it replaces anything (gk_twoscale_load_take): a refused block
 * leaves the set, the points, the strains, S, the rows and the snapshots as they were. */
GK_INLINE gk_result mpd_load(const char *dir, mpd_micro *m, gk_mpm_points *pts, const char *tag, void *S,
                             size_t nS, mpd_rows *R, mpd_snaps *sn, mpd_check_fn check, const void *ctx,
                             gk_err *err) {
    char path[MPD_PATH];
    mpd_take t;
    if (mpd_checkpoint_path(dir, path))
        return gk_err_set(err, GK_ERR_ARG, "--restart %s: path too long", dir);
    t.m = m, t.pts = pts, t.tag = tag, t.S = S, t.nS = nS, t.R = R, t.sn = sn, t.check = check, t.ctx = ctx;
    t.oom = 0;
    if (gk_twoscale_load_take(&m->ts, path, mpd_take_block, &t))
        return gk_err_set(err, t.oom ? GK_ERR_ALLOC : m->ts.err.code, "%s", gk_twoscale_error(&m->ts));
    return GK_OK;
}

/* "12.3 s" / "4.5 min" / "2.1 h" */
static const char *mpd_duration(double s, char *buf, size_t cap) {
    if (s < 120.0)
        snprintf(buf, cap, "%.1f s", s);
    else if (s < 7200.0)
        snprintf(buf, cap, "%.1f min", s / 60.0);
    else
        snprintf(buf, cap, "%.1f h", s / 3600.0);
    return buf;
}

/* what every driver frees at its end (whatever exists of it) */
static void mpd_free_all(mpd_micro *m, mpd_proto *P, gk_mpm_points *pts, gk_mpm_grid *g, mpd_rows *R,
                         mpd_snaps *sn) {
    free(R->r);
    R->r = NULL, R->n = R->cap = 0;
    mpd_snaps_free(sn);
    mpd_micro_free(m);
    mpd_proto_close(P);
    gk_mpm_points_destroy(pts);
    gk_mpm_grid_destroy(g);
}

/* the line of the RVEs' traffic over the ranks (collective): bytes sent per MPM step by all ranks
 * together in this run's steps (checkpoints left out), migrations of accepted RVE states by the load
 * balance (zeros without MPI) */
GK_INLINE void mpd_print_traffic(const mpd_run *run, const mpd_micro *m, long steps, int threads) {
    long long b = m->bytes, all = b;
#ifdef GK_TWOSCALE_MPI
    MPI_Allreduce(&b, &all, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
#endif
    printf(
        "MPI ranks=%d threads=%d bytes_sent_per_step=%.6g point_moves=%lld (all ranks, in the MPM steps)\n",
        run->nranks, threads, steps > 0 ? (double)all / steps : 0.0, m->ts.stats.migrated);
}

#endif /* MPMDEM_IO_H */
