/* bench_dem_step - the DEM step at the speed limit of this CPU.
 *
 *   build/bench_dem_step                      the whole suite (make bench), the physics-switch
 *                                             table (rve400) and the float-error report
 *   build/bench_dem_step --case NAME [--threads T] [--steps S] [--law linear|hertz]
 *                        [--real double|float] [--scalar] [--repeats R]
 *                        [--packing FILE] [--write-packing FILE]
 *   build/bench_dem_step --case NAME --lists [--repeats R]
 *                                             contact detection alone: one outer-list build (cell
 *                                             binning + candidate pairs within the skin) of the
 *                                             case's starting packing, median of R batches [us]
 *   build/bench_dem_step --case NAME --phases [--threads T] ...
 *                                             where the step's time goes: per phase (list rebuild,
 *                                             pair forces, per-particle sums, particle update, the
 *                                             rest) its wall time and each thread's time inside
 *                                             its chunks, ms per step over the timed steps
 *
 * Cases: rve400 (the Guo & Zhao 2014 400-disk RVE, its own material, simple shear at
 * 1e-5 per step), 2d_10k and 2d_100k (bench/data/bench2d_10k.txt, tiled 5x2),
 * 3d_1k (bench/data/bench3d_1k.txt), 3d_10k (bench/data/bench3d_20k.txt:
 * 20 000 spheres, the packing the peers were measured on) and 3d_100k (that,
 * tiled 5x), all under slow Lees-Edwards shear with the peers' parameters:
 * linear law, constant kn = 2e5 N/m, kt = 0.5 kn, mu = 0.5, no damping,
 * rho = 2650 (sphere masses also in 2D), dt = 2.7e-6 s, shear rate 1.5 /s,
 * skin 0.5 mm. --law hertz: Hertz-Mindlin (E 5e9, nu 0.3) + rolling
 * resistance (beta 1, eta 0.1) at dt 1e-6 s. Each run: warm-up, then R
 * repeats of S steps; rates are medians over the repeats. One line per run:
 * BENCH case=... dim=... n=... threads=... law=... real=... simd=... steps=...
 *       particle_steps_per_s=... contact_steps_per_s=... contacts_per_particle=... */
#include "dem_step.h"
#include "../examples/cli.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *cases[] = {"rve400", "2d_10k", "2d_100k", "3d_1k", "3d_10k", "3d_100k"};

/* --physics: a comma list of known switches (a typo is refused, not ignored) */
static int physics_ok(const char *list) {
    static const char *names = "norot|frictionless|rolling|viscous|cohesion";
    const char *p = list;
    for (;;) {
        const char *e = strchr(p, ',');
        char word[32];
        size_t l = e ? (size_t)(e - p) : strlen(p);
        if (l == 0 || l >= sizeof word) break;
        memcpy(word, p, l), word[l] = 0;
        if (cli_choice_index(names, word) < 0) break;
        if (!e) return 1;
        p = e + 1;
    }
    fprintf(stderr,
            "bench_dem_step: --physics '%s' must be a comma list of norot, frictionless, rolling, viscous, "
            "cohesion\n",
            list);
    return 0;
}

static void usage(FILE *fp) {
    fprintf(fp,
            "usage: bench_dem_step [--case rve400|2d_10k|2d_100k|3d_1k|3d_10k|3d_100k] [--threads T]\n"
            "                      [--steps S] [--law linear|hertz] [--real double|float] [--scalar]\n"
            "                      [--repeats R] [--packing FILE] [--write-packing FILE]\n"
            "                      [--physics norot,frictionless,rolling,viscous,cohesion] [--lists]\n"
            "                      [--phases]\n"
            "       bench_dem_step --float-error   q/p along the rve_path shear, float vs double\n"
            "with no --case, runs the whole suite (1 and 2 threads, both laws, double and float,\n"
            "SIMD and scalar) and prints a table, then the cost of each physics switch on rve400\n"
            "and the float-error report. --lists times the case's cell-list build (bin and\n"
            "candidate pairs) instead of time steps. --phases (with --case, at most %d threads)\n"
            "prints each phase's wall time per step and each thread's time inside its chunks\n"
            "(the clock is read at every mark, a few tens of ns each).\n",
            BENCH_PHASE_THREADS);
}

/* --phases: a table, then one PHASES line (ms per step); 1 if the times do not add up */
static int print_phases(const bench_case *c, const bench_out *o) {
    static const char *const name[BENCH_PHASES] = {"list rebuild", "pair forces", "per-particle sums",
                                                   "particle update"};
    static const char *const key[BENCH_PHASES] = {"rebuild", "forces", "sums", "update"};
    double rest = o->step_ms;
    int ph, t, nth = c->threads, ok = 1;
    printf("phases of %s, %d thread%s, ms per step (busy: inside the chunks of a threaded loop):\n", c->name,
           nth, nth > 1 ? "s" : "");
    printf("  %-18s %8s  %-28s %s\n", "phase", "wall", "busy per thread", "idle in the phase");
    for (ph = 0; ph < BENCH_PHASES; ++ph) {
        char busy[96] = "serial";
        double sum = 0.0;
        rest -= o->phase_ms[ph];
        if (o->phase_threaded[ph]) {
            size_t l = 0;
            busy[0] = 0;
            for (t = 0; t < nth; ++t) {
                sum += o->phase_busy_ms[ph][t];
                if (l + 12 < sizeof busy)
                    l += (size_t)snprintf(busy + l, sizeof busy - l, "%s%.4f", t ? " " : "",
                                          o->phase_busy_ms[ph][t]);
            }
        }
        if (ph == 0) snprintf(busy, sizeof busy, "serial, %ld in %ld steps", o->rebuilds, o->steps * o->nrep);
        if (o->phase_threaded[ph] && o->phase_ms[ph] > 0.0)
            printf("  %-18s %8.4f  %-28s %.1f %%\n", name[ph], o->phase_ms[ph], busy,
                   100.0 * (1.0 - sum / (nth * o->phase_ms[ph])));
        else
            printf("  %-18s %8.4f  %s\n", name[ph], o->phase_ms[ph], busy);
    }
    printf("  %-18s %8.4f  serial (cell update, stress, step loop)\n", "rest", rest);
    /* the phases do not overlap and no thread is busy longer than its phase lasts */
    for (ph = 0; ph < BENCH_PHASES; ++ph)
        for (t = 0; t < nth; ++t)
            if (o->phase_busy_ms[ph][t] > 1.01 * o->phase_ms[ph] + 1e-6) ok = 0;
    if (!(rest > -0.01 * o->step_ms)) ok = 0;
    printf("  %-18s %8.4f\n", "step", o->step_ms);
    printf("PHASES case=%s threads=%d step_ms=%.5g", c->name, nth, o->step_ms);
    for (ph = 0; ph < BENCH_PHASES; ++ph) {
        printf(" %s_ms=%.5g", key[ph], o->phase_ms[ph]);
        if (o->phase_threaded[ph]) { /* forces_busy_ms=a,b: one key per phase */
            printf(" %s_busy_ms=", key[ph]);
            for (t = 0; t < nth; ++t) printf("%s%.5g", t ? "," : "", o->phase_busy_ms[ph][t]);
        }
    }
    printf(" rest_ms=%.5g rebuilds=%ld steps=%ld\n", rest, o->rebuilds, o->steps * o->nrep);
    if (!ok) fprintf(stderr, "bench_dem_step: --phases: the phases overlap or a thread outlasts its phase\n");
    return !ok;
}

static int run_one(const bench_case *c, int use_float, int quiet_header) {
    bench_out o;
    int rc = use_float ? bench_run_float(c, &o) : bench_run_double(c, &o);
    (void)quiet_header;
    if (rc) {
        fprintf(stderr, "bench_dem_step: %s: %s\n", c->name, o.err);
        return rc;
    }
    if (c->lists) {
        printf("%-8s %dD %7d  %-6s %-6s %12.1f %9d\n", c->name, o.dim, o.n, o.real, o.simd, o.list_build_us,
               o.list_pairs);
        printf("BENCH case=%s dim=%d n=%d real=%s simd=%s list_build_us=%.4g list_pairs=%d\n", c->name, o.dim,
               o.n, o.real, o.simd, o.list_build_us, o.list_pairs);
        fflush(stdout);
        return 0;
    }
    if (c->phases && print_phases(c, &o)) return 1;
    printf("%-8s %dD %7d  %2d  %-6s %-6s %-6s %8.2f %9.2f %6.2f %6.2f %s\n", c->name, o.dim, o.n, c->threads,
           c->hertz ? "hertz" : "linear", o.real, o.simd, o.particle_steps_per_s / 1e6,
           o.contact_steps_per_s / 1e6, 2.0 * o.contacts_per_particle, o.pairs_per_particle,
           c->physics ? c->physics : "");
    printf("BENCH case=%s dim=%d n=%d threads=%d law=%s real=%s simd=%s steps=%ld particle_steps_per_s=%.4g "
           "contact_steps_per_s=%.4g contacts_per_particle=%.3f coordination=%.3f pairs_per_particle=%.3f "
           "seconds_median=%.4g physics=%s sxx=%.6g syy=%.6g sxy=%.6g\n",
           c->name, o.dim, o.n, c->threads, c->hertz ? "hertz" : "linear", o.real, o.simd, o.steps,
           o.particle_steps_per_s, o.contact_steps_per_s, o.contacts_per_particle,
           2.0 * o.contacts_per_particle, o.pairs_per_particle, o.seconds_median,
           c->physics ? c->physics : "default", o.sigma[0], o.sigma[4], o.sigma[1]);
    fflush(stdout);
    return 0;
}

static void header(void) {
    printf("%-8s %2s %7s  %2s  %-6s %-6s %-6s %8s %9s %6s %6s\n", "case", "", "n", "th", "law", "real",
           "simd", "Mpart/s", "Mcont/s", "Z", "pairs");
}

static void header_lists(void) {
    printf("%-8s %2s %7s  %-6s %-6s %12s %9s\n", "case", "", "n", "real", "simd", "us/build", "pairs");
}

/* float against double along the Guo & Zhao RVE shear path: what float costs in accuracy */
static int float_error_report(void) {
    enum { NI = 50 };
    double pd[NI], qd[NI], pf[NI], qf[NI], emax = 0, erat = 0;
    int k;
    if (bench_path_double(NI, pd, qd) || bench_path_float(NI, pf, qf)) {
        fprintf(stderr, "bench_dem_step: float-error path failed\n");
        return 1;
    }
    for (k = 0; k < NI; ++k) {
        double e = fabs(pf[k] - pd[k]) / pd[k], r = fabs(qf[k] / pf[k] - qd[k] / pd[k]);
        if (e > emax) emax = e;
        if (r > erat) erat = r;
    }
    printf(
        "float vs double along the Guo & Zhao RVE shear path (50 x dH01 = 1e-3, 100 steps each):\n"
        "  largest relative difference in p: %.3g; largest difference in q/p: %.3g (q/p at the end %.4f)\n",
        emax, erat, qd[NI - 1] / pd[NI - 1]);
    printf("BENCH case=float_error increments=%d max_rel_p=%.4g max_abs_q_over_p=%.4g final_q_over_p=%.4f\n",
           NI, emax, erat, qd[NI - 1] / pd[NI - 1]);
    return 0;
}

int main(int argc, char **argv) {
    bench_case c;
    int ci = -1, use_float = 0, rc = 0, float_error = 0, help = 0, steps = 0, hertz = 0;
    const cli_opt opts[] = {
        {"--case", CLI_CHOICE, &ci, 0, 0, NULL, "rve400|2d_10k|2d_100k|3d_1k|3d_10k|3d_100k", 0},
        {"--threads", CLI_INT, &c.threads, 1, 1024, NULL, NULL, 0},
        {"--steps", CLI_INT, &steps, 1, 1000000000, NULL, NULL, 0},
        {"--repeats", CLI_INT, &c.repeats, 1, 64, NULL, NULL, 0},
        {"--law", CLI_CHOICE, &hertz, 0, 0, NULL, "linear|hertz", 0},
        {"--real", CLI_CHOICE, &use_float, 0, 0, NULL, "double|float", 0},
        {"--scalar", CLI_FLAG, &c.scalar, 0, 0, NULL, NULL, 0},
        {"--float-error", CLI_FLAG, &float_error, 0, 0, NULL, NULL, 0},
        {"--packing", CLI_STR, &c.packing, 0, 0, NULL, NULL, 0},
        {"--write-packing", CLI_STR, &c.write_packing, 0, 0, NULL, NULL, 0},
        {"--physics", CLI_STR, &c.physics, 0, 0, NULL, NULL, 0},
        {"--lists", CLI_FLAG, &c.lists, 0, 0, NULL, NULL, 0},
        {"--phases", CLI_FLAG, &c.phases, 0, 0, NULL, NULL, 0},
        {NULL, CLI_FLAG, NULL, 0, 0, NULL, NULL, 0}};
    const cli_opt *tables[2];
    memset(&c, 0, sizeof c);
    c.threads = 1;
    tables[0] = opts, tables[1] = NULL;
    if (cli_parse("bench_dem_step", argc, argv, tables, &help)) return 2;
    if (help) {
        usage(stdout);
        return 0;
    }
    if (c.physics && !physics_ok(c.physics)) return 2;
    if (c.phases && (ci < 0 || c.lists || c.threads > BENCH_PHASE_THREADS)) {
        fprintf(stderr,
                "bench_dem_step: --phases times the steps of one --case on at most %d threads (not "
                "with --lists)\n",
                BENCH_PHASE_THREADS);
        return 2;
    }
    c.steps = steps, c.hertz = hertz;
    if (ci >= 0) {
        c.name = cases[ci];
        if (c.lists)
            header_lists();
        else
            header();
        return run_one(&c, use_float, 0);
    }
    if (float_error) return float_error_report();
    {
        int k, law, fl, sc, th;
        header();
        for (k = 0; k < 6; ++k)
            for (law = 0; law < 2; ++law)
                for (fl = 0; fl < 2; ++fl)
                    for (th = 1; th <= 2; ++th)
                        for (sc = 0; sc < (th == 1 ? 2 : 1); ++sc) {
                            bench_case b = c;
                            b.name = cases[k];
                            b.hertz = law;
                            b.scalar = sc;
                            b.threads = th;
                            if (run_one(&b, fl, 1)) rc = 1;
                        }
    }
    { /* what each optional physics switch costs, on the 400-disk RVE (1 thread, double) */
        /* the hertz case already has rolling resistance (which needs rotation); cohesion is linear-only */
        static const struct {
            const char *name;
            int linear_only;
        } phys[] = {{NULL, 0},      {"norot", 1},   {"frictionless", 0},
                    {"rolling", 1}, {"viscous", 0}, {"cohesion", 1}};
        int k, law;
        printf(
            "\nphysics switches, rve400, 1 thread, double (linear default: rotation on, Coulomb friction, "
            "no\n"
            "rolling resistance, local damping only, no cohesion; the hertz case has rolling resistance, so\n"
            "no 'norot', and cohesion is linear-only):\n");
        header();
        for (law = 0; law < 2; ++law)
            for (k = 0; k < 6; ++k) {
                bench_case b = c;
                if (law == 1 && phys[k].linear_only) continue;
                b.name = "rve400";
                b.hertz = law;
                b.threads = 1;
                b.physics = phys[k].name;
                if (run_one(&b, 0, 1)) rc = 1;
            }
    }
    { /* contact detection alone: one outer-list build (cell binning + candidate pairs) */
        static const char *const lc[] = {"rve400", "2d_10k", "3d_10k"};
        int k;
        printf("\ncell-list build (bin + candidate pairs within the skin) of each packing, double:\n");
        header_lists();
        for (k = 0; k < 3; ++k) {
            bench_case b = c;
            b.name = lc[k];
            b.lists = 1;
            if (run_one(&b, 0, 1)) rc = 1;
        }
    }
    { /* where one large system's step goes on 2 threads */
        bench_case b = c;
        printf("\nthe step's phases, 10^5 disks on 2 threads, double (--phases --steps 600):\n");
        header();
        b.name = "2d_100k";
        b.threads = 2;
        b.steps = 600; /* a few list rebuilds in every repeat */
        b.phases = 1;
        if (run_one(&b, 0, 1)) rc = 1;
    }
    printf("\n");
    fflush(stdout);
    if (float_error_report()) rc = 1;
    return rc;
}
