/* csv_plot - one x-y line plot (SVG) of a column against another from one or more CSV files: the
 * curves of several runs on one figure (a mesh study, a parameter sweep).
 *
 *   build/csv_plot --x eps_axial --y sigma_yy --x-scale 100 --y-scale 1e-3 \
 *                  --title "biaxial" --xlabel "axial strain [%]" --ylabel "sigma_yy [kPa]" \
 *                  --out curves.svg C4/biaxial.csv=C4 M4/biaxial.csv=M4 F4/biaxial.csv=F4
 *
 * Each FILE[=LABEL] is one curve (legend: LABEL, or the file name), at most 8. The first line of
 * a file names its columns (comma-separated, as every driver writes them); the other lines are
 * numbers. --x-scale / --y-scale multiply the values (100: a strain in %, 1e-3: Pa to kPa);
 * --xlim A,B / --ylim A,B fix the axes. --dashed K draws the K-th curve (from 1) dashed.
 *
 * Every input is checked: a missing column, a field that is not a finite number, a short row, a
 * file without data lines, or more curves than fit is an error naming the file and the line
 * (exit status 1, nothing written); a bad option exits with status 2; an SVG that cannot be
 * written completely is exit status 1.
 */
#define GK_IMPLEMENTATION
#include "gk_io.h"

#include <errno.h>
#include <stdarg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CP_LINE 65536 /* the longest line read */

static int cp_quiet; /* 1: the readers say nothing (the fuzz harness) */

/* a message of the readers, on stderr */
static void cp_say(const char *fmt, ...) {
    va_list ap;
    if (cp_quiet) return;
    va_start(ap, fmt);
    fputs("csv_plot: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

typedef struct cp_curve {
    double *x, *y;
    int n, cap;
} cp_curve;

static void usage(FILE *fp) {
    fprintf(fp,
            "usage: csv_plot --x COL --y COL --out FILE.svg [options] FILE[=LABEL] ...\n"
            "  --x COL, --y COL        columns (names from the first line) on the axes\n"
            "  --x-scale S --y-scale S multiply the values (default 1)\n"
            "  --title T --xlabel L --ylabel L   texts (default: none, the column names)\n"
            "  --xlim A,B --ylim A,B   axis ranges (default: the data's)\n"
            "  --dashed K              draw curve K (from 1) dashed\n"
            "  --help                  this text\n"
            "Each FILE is one curve (at most %d), labelled LABEL or the file name.\n",
            GK_PLOT_MAX);
}

/* a whole finite number, or 1 */
static int number(const char *s, double *v) {
    char *e;
    errno = 0;
    *v = strtod(s, &e);
    return e == s || *e != '\0' || errno == ERANGE || !isfinite(*v);
}

/* "A,B" with A < B, or 1 */
static int range(const char *s, double lim[2]) {
    char buf[128], *c;
    if (strlen(s) >= sizeof buf || !(c = strchr(strcpy(buf, s), ','))) return 1;
    *c = '\0';
    return number(buf, &lim[0]) || number(c + 1, &lim[1]) || !(lim[0] < lim[1]);
}

/* the index of column `name` in the header line (cut at the newline), or -1 */
static int column(char *head, const char *name) {
    char *tok = head;
    int k = 0;
    head[strcspn(head, "\r\n")] = '\0';
    for (;;) {
        char *c = strchr(tok, ',');
        size_t len = c ? (size_t)(c - tok) : strlen(tok);
        if (len == strlen(name) && !strncmp(tok, name, len)) return k;
        if (!c) return -1;
        tok = c + 1, ++k;
    }
}

/* field k of a data line, as a finite number; 0, or 1 (said) */
static int field(const char *line, int k, double *v, const char *path, long lno, const char *col) {
    char buf[128];
    const char *s = line;
    size_t len;
    int i;
    for (i = 0; i < k && s; ++i) s = strchr(s, ','), s = s ? s + 1 : NULL;
    if (!s) return cp_say("%s line %ld: no column '%s' (the row is short)", path, lno, col), 1;
    len = strcspn(s, ",\r\n");
    if (len >= sizeof buf)
        return cp_say("%s line %ld: column '%s' is longer than a number", path, lno, col), 1;
    memcpy(buf, s, len), buf[len] = '\0';
    if (number(buf, v))
        return cp_say("%s line %ld: column '%s' is '%s', not a finite number", path, lno, col, buf), 1;
    return 0;
}

/* one curve from the open stream fp (named path in messages); 0, or 1 (said) */
static int read_curve_fp(FILE *fp, const char *path, const char *xc, const char *yc, double sx, double sy,
                         cp_curve *c) {
    char *line = (char *)malloc(CP_LINE);
    int kx, ky, bad = 1;
    long lno = 1;
    if (!line) {
        cp_say("out of memory reading %s", path);
        return 1;
    }
    if (!fgets(line, CP_LINE, fp)) {
        cp_say("%s is empty", path);
        goto out;
    }
    if ((kx = column(line, xc)) < 0 || (ky = column(line, yc)) < 0) {
        cp_say("%s has no column '%s' (its columns: %s)", path, kx < 0 ? xc : yc, line);
        goto out;
    }
    while (fgets(line, CP_LINE, fp)) {
        double x, y;
        ++lno;
        if (!strchr(line, '\n') && !feof(fp)) {
            cp_say("%s line %ld is longer than %d characters", path, lno, CP_LINE - 1);
            goto out;
        }
        if (line[strspn(line, " \t\r\n")] == '\0') continue; /* a blank line */
        if (field(line, kx, &x, path, lno, xc) || field(line, ky, &y, path, lno, yc)) goto out;
        if (!isfinite(sx * x) || !isfinite(sy * y)) {
            cp_say("%s line %ld: a value overflows when scaled", path, lno);
            goto out;
        }
        if (c->n == c->cap) {
            int cap = c->cap ? 2 * c->cap : 256;
            double *nx, *ny;
            if (c->cap > (1 << 27)) goto oom;
            if (!(nx = (double *)realloc(c->x, (size_t)cap * sizeof *nx))) goto oom;
            c->x = nx;
            if (!(ny = (double *)realloc(c->y, (size_t)cap * sizeof *ny))) goto oom;
            c->y = ny, c->cap = cap;
        }
        c->x[c->n] = sx * x, c->y[c->n] = sy * y, ++c->n;
    }
    if (ferror(fp)) {
        cp_say("cannot read '%s'", path);
        goto out;
    }
    if (c->n == 0) {
        cp_say("%s has no data lines", path);
        goto out;
    }
    bad = 0;
    goto out;
oom:
    cp_say("out of memory reading %s", path);
out:
    free(line);
    return bad;
}

/* one curve from the file `path`; 0, or 1 (said) */
static int read_curve(const char *path, const char *xc, const char *yc, double sx, double sy, cp_curve *c) {
    FILE *fp = fopen(path, "r");
    int bad;
    if (!fp) return cp_say("cannot open '%s': %s", path, strerror(errno)), 1;
    bad = read_curve_fp(fp, path, xc, yc, sx, sy, c);
    fclose(fp);
    return bad;
}

int main(int argc, char **argv) {
    const char *xc = NULL, *yc = NULL, *out = NULL, *title = NULL, *xl = NULL, *yl = NULL;
    const char *files[GK_PLOT_MAX];
    double sx = 1, sy = 1, xlim[2], ylim[2];
    int nf = 0, i, k, dashed = 0, hx = 0, hy = 0, status = 0;
    cp_curve cv[GK_PLOT_MAX];
    gk_plot pl;
    gk_err err;
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help")) return usage(stdout), 0;
        if (a[0] != '-' || a[1] != '-') {
            if (nf == GK_PLOT_MAX) {
                fprintf(stderr, "csv_plot: more than %d curves ('%s')\n", GK_PLOT_MAX, a);
                return 2;
            }
            files[nf++] = a;
            continue;
        }
        if (!v) {
            fprintf(stderr, "csv_plot: %s needs a value\n", a);
            return 2;
        }
        ++i;
        if (!strcmp(a, "--x"))
            xc = v;
        else if (!strcmp(a, "--y"))
            yc = v;
        else if (!strcmp(a, "--out"))
            out = v;
        else if (!strcmp(a, "--title"))
            title = v;
        else if (!strcmp(a, "--xlabel"))
            xl = v;
        else if (!strcmp(a, "--ylabel"))
            yl = v;
        else if (!strcmp(a, "--x-scale") || !strcmp(a, "--y-scale")) {
            double *s = a[2] == 'x' ? &sx : &sy;
            if (number(v, s) || *s == 0) {
                fprintf(stderr, "csv_plot: %s '%s' is not a finite non-zero number\n", a, v);
                return 2;
            }
        } else if (!strcmp(a, "--xlim") || !strcmp(a, "--ylim")) {
            if (range(v, a[2] == 'x' ? xlim : ylim)) {
                fprintf(stderr, "csv_plot: %s '%s' is not A,B with A < B\n", a, v);
                return 2;
            }
            *(a[2] == 'x' ? &hx : &hy) = 1;
        } else if (!strcmp(a, "--dashed")) {
            double d;
            if (number(v, &d) || d != floor(d) || d < 1 || d > GK_PLOT_MAX) {
                fprintf(stderr, "csv_plot: --dashed '%s' is not a curve number 1..%d\n", v, GK_PLOT_MAX);
                return 2;
            }
            dashed = (int)d;
        } else {
            fprintf(stderr, "csv_plot: unknown option '%s' (--help lists them)\n", a);
            return 2;
        }
    }
    if (!xc || !yc || !out || nf == 0) {
        fprintf(stderr, "csv_plot: needs --x, --y, --out and at least one FILE\n");
        usage(stderr);
        return 2;
    }
    if (dashed > nf) {
        fprintf(stderr, "csv_plot: --dashed %d but %d curve(s)\n", dashed, nf);
        return 2;
    }
    memset(cv, 0, sizeof cv);
    gk_plot_init(&pl, title, xl ? xl : xc, yl ? yl : yc);
    for (k = 0; k < nf && !status; ++k) {
        const char *eq = strrchr(files[k], '=');
        char path[4096];
        size_t len = eq ? (size_t)(eq - files[k]) : strlen(files[k]);
        if (len >= sizeof path || len == 0) {
            fprintf(stderr, "csv_plot: '%s' is not FILE or FILE=LABEL\n", files[k]);
            status = 2;
            break;
        }
        memcpy(path, files[k], len), path[len] = '\0';
        if (read_curve(path, xc, yc, sx, sy, &cv[k]))
            status = 1;
        else if (gk_plot_add(&pl, cv[k].x, cv[k].y, cv[k].n, eq ? eq + 1 : files[k]) == dashed - 1 && dashed)
            pl.s[k].dashed = 1;
    }
    if (!status) {
        pl.has_xlim = hx, pl.has_ylim = hy;
        if (hx) pl.xlim[0] = xlim[0], pl.xlim[1] = xlim[1];
        if (hy) pl.ylim[0] = ylim[0], pl.ylim[1] = ylim[1];
        if (gk_plot_svg(&pl, out, &err)) {
            fprintf(stderr, "csv_plot: %s\n", err.msg);
            status = 1;
        } else {
            printf("csv_plot: wrote %s (%d curve%s)\n", out, nf, nf > 1 ? "s" : "");
        }
    }
    for (k = 0; k < GK_PLOT_MAX; ++k) free(cv[k].x), free(cv[k].y);
    return status;
}
