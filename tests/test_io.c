/* test_io - plots a researcher can trust (gk_io.h).
 *
 * The legend never covers data (no drawn segment meets its box, checked by
 * sampling every segment of the written SVG), equal aspect gives a circle
 * as wide as it is tall, field plots have axes in the requested unit, the
 * outline on top, a colour bar with its label, and a fixed colour range that
 * maps the same value to the same colour in every snapshot. */
#include "gk_io.h"
#include "gk_test.h"

#define OUT BUILD "/tests/"

static double attr(const char *tag, const char *name) {
    char pat[64];
    const char *q;
    snprintf(pat, sizeof pat, " %s=\"", name);
    q = strstr(tag, pat);
    return q ? atof(q + strlen(pat)) : NAN;
}

/* number of sampled points of the drawn series that fall inside the legend
 * box (-1 if the file has no legend) */
static int points_under_legend(const char *path) {
    char *svg = gk_test_slurp(path);
    const char *r, *s;
    double bx, by, bw, bh;
    int inside = 0;
    if (!svg) return -2;
    r = strstr(svg, "<rect class=\"legend\"");
    if (!r) {
        free(svg);
        return -1;
    }
    bx = attr(r, "x"), by = attr(r, "y"), bw = attr(r, "width"), bh = attr(r, "height");
    for (s = strstr(svg, "<polyline class=\"series\""); s; s = strstr(s + 1, "<polyline class=\"series\"")) {
        const char *q = strstr(s, "points=\"");
        double px = 0, py = 0, x, y;
        int have = 0, nc;
        if (!q) break;
        q += 8;
        while (sscanf(q, "%lf,%lf%n", &x, &y, &nc) == 2) {
            int k;
            for (k = 0; k <= 50; ++k) { /* sample the segment from the previous point */
                double u = k / 50.0, X = have ? px + u * (x - px) : x, Y = have ? py + u * (y - py) : y;
                if (X >= bx && X <= bx + bw && Y >= by && Y <= by + bh) ++inside;
            }
            px = x, py = y, have = 1;
            q += nc;
            while (*q == ' ') ++q;
        }
    }
    free(svg);
    return inside;
}

TEST(legend_never_covers_data) {
    static double x[200], up[200], cap[200], wave[8][200];
    gk_plot p;
    gk_err e;
    int i, k;
    for (i = 0; i < 200; ++i) {
        x[i] = i / 199.0;
        up[i] = x[i];                                                        /* fills the diagonal */
        cap[i] = 1.0 - 4.0 * (x[i] - 0.5) * (x[i] - 0.5);                    /* top middle, low ends */
        for (k = 0; k < 8; ++k) wave[k][i] = sin(6.0 * x[i] + k) + 0.25 * k; /* everywhere */
    }
    /* rising curve: the top-right corner holds data, the top left does not */
    gk_plot_init(&p, "rising", "x", "y");
    gk_plot_add(&p, x, up, 200, "a rather long legend label");
    CHECK(gk_plot_svg(&p, OUT "io_rising.svg", &e) == GK_OK);
    CHECK_EQ_INT(points_under_legend(OUT "io_rising.svg"), 0);
    /* a cap and its mirror: both top corners and the bottom middle taken */
    gk_plot_init(&p, "caps", "x", "y");
    gk_plot_add(&p, x, cap, 200, "cap");
    gk_plot_add(&p, x, up, 200, "diagonal");
    CHECK(gk_plot_svg(&p, OUT "io_caps.svg", &e) == GK_OK);
    CHECK_EQ_INT(points_under_legend(OUT "io_caps.svg"), 0);
    /* eight waves fill the axes: the legend goes outside */
    gk_plot_init(&p, "waves", "x", "y");
    for (k = 0; k < 8; ++k) gk_plot_add(&p, x, wave[k], 200, "wave");
    CHECK(gk_plot_svg(&p, OUT "io_waves.svg", &e) == GK_OK);
    CHECK_EQ_INT(points_under_legend(OUT "io_waves.svg"), 0);
    /* and with no label there is no legend */
    gk_plot_init(&p, "none", "x", "y");
    gk_plot_add(&p, x, up, 200, NULL);
    CHECK(gk_plot_svg(&p, OUT "io_nolegend.svg", &e) == GK_OK);
    CHECK_EQ_INT(points_under_legend(OUT "io_nolegend.svg"), -1);
}

TEST(equal_aspect_draws_a_round_circle) {
    static double cx[361], cy[361];
    gk_plot p;
    gk_err e;
    char *svg;
    int i;
    for (i = 0; i <= 360; ++i) cx[i] = 3.0 + cos(i * GK_PI / 180), cy[i] = sin(i * GK_PI / 180);
    gk_plot_init(&p, "Mohr circle", "sigma [kPa]", "tau [kPa]");
    p.equal_aspect = 1;
    gk_plot_add(&p, cx, cy, 361, NULL);
    CHECK(gk_plot_svg(&p, OUT "io_circle.svg", &e) == GK_OK);
    svg = gk_test_slurp(OUT "io_circle.svg");
    CHECK(svg != NULL);
    if (svg) {
        const char *q = strstr(svg, "points=\"");
        double x, y, xmin = 1e9, xmax = -1e9, ymin = 1e9, ymax = -1e9;
        int nc;
        CHECK(q != NULL);
        for (q = q ? q + 8 : NULL; q && sscanf(q, "%lf,%lf%n", &x, &y, &nc) == 2;) {
            if (x < xmin) xmin = x;
            if (x > xmax) xmax = x;
            if (y < ymin) ymin = y;
            if (y > ymax) ymax = y;
            q += nc;
            while (*q == ' ') ++q;
        }
        CHECK(xmax - xmin > 50);
        CHECK_NEAR(xmax - xmin, ymax - ymin, 0.05); /* the printed coordinates have 2 decimals */
        free(svg);
    }
}

TEST(field_plot_axes_outline_colorbar_and_fixed_range) {
    /* four unit squares of a 2 x 2 mesh of a 50 x 50 mm block */
    static const double xy[4 * 8] = {0, 0,    0.025, 0,     0.025, 0.025, 0,     0.025, 0.025, 0,     0.05,
                                     0, 0.05, 0.025, 0.025, 0.025, 0,     0.025, 0.025, 0.025, 0.025, 0.05,
                                     0, 0.05, 0.025, 0.025, 0.05,  0.025, 0.05,  0.05,  0.025, 0.05};
    double val[4] = {0.0, 10.0, 20.0, NAN}; /* below, at the top of, beyond the range; none */
    static const int len[1] = {2};
    static const double platen[4] = {-0.005, 0.05, 0.055, 0.05};
    gk_field_def d;
    gk_err e;
    char *svg;
    memset(&d, 0, sizeof d);
    d.title = "eps_q at 10 %";
    d.label = "eps_q [%]";
    d.xlabel = "x [mm]", d.ylabel = "y [mm]";
    d.coord_scale = 1e3;
    d.fixed_range = 1, d.vmin = 0.0, d.vmax = 10.0;
    d.nlines = 1, d.line_len = len, d.line_xy = platen;
    CHECK(gk_field_svg(OUT "io_field.svg", &d, 4, 4, xy, val, &e) == GK_OK);
    svg = gk_test_slurp(OUT "io_field.svg");
    CHECK(svg != NULL);
    if (svg) {
        CHECK(strstr(svg, "fill=\"rgb(68,1,84)\" stroke") != NULL);    /* vmin: viridis' first colour */
        CHECK(strstr(svg, "fill=\"rgb(253,231,37)\" stroke") != NULL); /* vmax and beyond: its last  */
        CHECK(strstr(svg, "fill=\"#bbbbbb\"") != NULL);                /* no value: grey             */
        CHECK(strstr(svg, "class=\"outline\"") != NULL);
        CHECK(strstr(svg, ">eps_q [%]</text>") != NULL);
        CHECK(strstr(svg, ">x [mm]</text>") != NULL);
        CHECK(strstr(svg, ">50</text>") != NULL); /* the axes count millimetres */
        CHECK(strstr(svg, ">10</text>") != NULL); /* and the colour bar its fixed top */
        free(svg);
    }
    /* a colour range that is not an interval is refused, and no file is written */
    d.vmin = 5.0, d.vmax = 5.0;
    remove(OUT "io_field_bad.svg");
    CHECK(gk_field_svg(OUT "io_field_bad.svg", &d, 4, 4, xy, val, &e) == GK_ERR_ARG);
    CHECK(strstr(e.msg, "colour range") != NULL);
    svg = gk_test_slurp(OUT "io_field_bad.svg");
    CHECK(svg == NULL);
    free(svg);
}

/* the progress line's ETA: elapsed / steps done x steps left; a run resumed
 * at step 50 that did 10 steps in 10 s has 40 s left at step 60 of 100
 * (gk_progress, counting from step 0, would say 6.7 s) */
TEST(progress_eta_counts_the_steps_since_a_restart) {
    char line[256];
    double el = NAN, eta = NAN;
    FILE *fp = fopen(OUT "io_progress.txt", "w+");
    CHECK(fp != NULL);
    if (!fp) return;
    gk_progress_since(fp, 60, 50, 100, gk_wtime() - 10.0, "eps 1 %");
    gk_progress(fp, 60, 100, gk_wtime() - 10.0, NULL);
    rewind(fp);
    CHECK(fgets(line, sizeof line, fp) != NULL);
    CHECK(sscanf(line, "step 60/100  eps 1 %% | %lf s elapsed, ETA %lf s", &el, &eta) == 2);
    CHECK(fabs(el - 10.0) < 0.5 && fabs(eta - 40.0) < 2.0);
    CHECK(fgets(line, sizeof line, fp) != NULL);
    CHECK(sscanf(line, "step 60/100   | %lf s elapsed, ETA %lf s", &el, &eta) == 2);
    CHECK(fabs(eta - 10.0 / 60.0 * 40.0) < 0.5);
    fclose(fp);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(legend_never_covers_data);
    RUN(equal_aspect_draws_a_round_circle);
    RUN(field_plot_axes_outline_colorbar_and_fixed_range);
    RUN(progress_eta_counts_the_steps_since_a_restart);
    return gk_test_done();
}
