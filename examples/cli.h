/* cli.h - strict command-line options for the example drivers (examples, not library).
 *
 * A driver lists its options in a table and calls cli_parse once:
 *
 *   static const cli_opt opts[] = {
 *       {"--nx", CLI_INT, &o.nx, 1, 1000, NULL, NULL},                 // whole number in [1, 1000]
 *       {"--tol", CLI_REAL, &o.tol, 0, 1, "a number in (0, 1]", NULL}, // range (lo, hi]: see flags
 *       {"--out", CLI_STR, &o.out, 0, 0, NULL, NULL},
 *       {"--element", CLI_CHOICE, &o.elem, 0, 0, NULL, "q8|q4"},       // index of the word
 *       {"--verbose", CLI_FLAG, &o.verbose, 0, 0, NULL, NULL},
 *       {NULL}};
 *   int r = cli_parse("femdem_biaxial", argc, argv, opts, &help);  // 0 ok, 2 refused (said)
 *
 * Every value is parsed strictly: the whole string must be the number ('8x', '', '2.5' for a
 * whole number, 'nan', '1e999' are refused), whole numbers must fit their range before any
 * arithmetic (so --steps 2147483647 cannot overflow a count), and every message names the
 * option and the value: "femdem_biaxial: --nx '8x' is not a whole number",
 * "femdem_biaxial: --nx -1 is out of range: needs a whole number in [1, 1000]".
 * "--nx=8" is refused with a hint (values follow the option after a space), as is an option
 * given without its value, and an unknown option. A refused option ends the parse: nothing
 * has been written and the driver exits with status 2. A NULL prog parses silently (the
 * other ranks of an MPI run).
 *
 * CLI_REAL ranges: [lo, hi] by default; CLI_LO_OPEN / CLI_HI_OPEN in `flags` open an end
 * (hi = HUGE_VAL: no upper bound); `what` describes the range in messages. CLI_FUNC: a value
 * in a format of the driver's own, parsed by its function (struct cli_func below).
 */
#ifndef CLI_H
#define CLI_H

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef enum cli_kind { CLI_INT, CLI_REAL, CLI_STR, CLI_CHOICE, CLI_FLAG, CLI_ULONG, CLI_FUNC } cli_kind;
#define CLI_LO_OPEN 1u
#define CLI_HI_OPEN 2u

typedef struct cli_opt {
    const char *name; /* "--nx" */
    cli_kind kind;
    void *dst;           /* int*, double*, const char**, int* (choice index, flag), unsigned long*,
                            cli_func* */
    double lo, hi;       /* CLI_INT / CLI_REAL range                                          */
    const char *what;    /* CLI_REAL: the range in words ("a positive number"); NULL: [lo, hi] */
    const char *choices; /* CLI_CHOICE: "a|b|c" (dst gets the index)                          */
    unsigned flags;      /* CLI_LO_OPEN, CLI_HI_OPEN                                          */
} cli_opt;

/* CLI_FUNC: a value with its own format ("2x3x1"), parsed by fn where it stands on the command
 * line (so a refused one ends the parse like any other): fn(prog, option name, value, dst)
 * returns 0, or 2 after a message through cli_say */
typedef struct cli_func {
    int (*fn)(const char *prog, const char *name, const char *v, void *dst);
    void *dst;
} cli_func;

/* a message on stderr, unless prog is NULL (a driver's other MPI ranks stay quiet) */
static void cli_say(const char *prog, const char *fmt, ...) {
    va_list ap;
    if (!prog) return;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
}

/* "a|b|c" -> "a, b or c" */
static void cli_choices_text(const char *c, char *out, size_t cap) {
    size_t n = 0, k, bars = 0, seen = 0;
    for (k = 0; c[k]; ++k) bars += c[k] == '|';
    for (k = 0; c[k] && n + 8 < cap; ++k) {
        if (c[k] != '|') {
            out[n++] = c[k];
            continue;
        }
        ++seen;
        if (seen == bars)
            memcpy(out + n, " or ", 4), n += 4;
        else
            memcpy(out + n, ", ", 2), n += 2;
    }
    out[n] = 0;
}

/* index of word v in "a|b|c", or -1 */
static int cli_choice_index(const char *choices, const char *v) {
    const char *p = choices;
    int idx = 0;
    size_t lv = strlen(v);
    while (*p) {
        const char *e = strchr(p, '|');
        size_t l = e ? (size_t)(e - p) : strlen(p);
        if (l == lv && !strncmp(p, v, l)) return idx;
        if (!e) break;
        p = e + 1, ++idx;
    }
    return -1;
}

/* one option's value into its destination; 0, or 2 after a message */
static int cli_value(const char *prog, const cli_opt *o, const char *v) {
    char *end;
    if (o->kind == CLI_STR) {
        *(const char **)o->dst = v;
        return 0;
    }
    if (o->kind == CLI_FUNC) {
        const cli_func *f = (const cli_func *)o->dst;
        return f->fn(prog, o->name, v, f->dst) ? 2 : 0;
    }
    if (o->kind == CLI_CHOICE) {
        int k = cli_choice_index(o->choices, v);
        char txt[256];
        if (k < 0) {
            cli_choices_text(o->choices, txt, sizeof txt);
            cli_say(prog, "%s: %s '%s' must be %s\n", prog, o->name, v, txt);
            return 2;
        }
        *(int *)o->dst = k;
        return 0;
    }
    if (o->kind == CLI_ULONG) {
        unsigned long x;
        errno = 0;
        x = strtoul(v, &end, 10);
        if (end == v || *end || errno == ERANGE || v[0] == '-' || v[0] == '+' || v[0] == ' ') {
            cli_say(prog, "%s: %s '%s' is not a non-negative whole number\n", prog, o->name, v);
            return 2;
        }
        *(unsigned long *)o->dst = x;
        return 0;
    }
    if (o->kind == CLI_INT) {
        long x;
        errno = 0;
        x = strtol(v, &end, 10);
        if (end == v || *end || (errno == ERANGE && x != LONG_MIN && x != LONG_MAX)) {
            cli_say(prog, "%s: %s '%s' is not a whole number\n", prog, o->name, v);
            return 2;
        }
        if (errno == ERANGE || (double)x < o->lo || (double)x > o->hi) {
            cli_say(prog, "%s: %s %s is out of range: needs a whole number in [%.0f, %.0f]\n", prog, o->name,
                    v, o->lo, o->hi);
            return 2;
        }
        *(int *)o->dst = (int)x;
        return 0;
    }
    {
        double x;
        char range[160];
        if (o->what)
            snprintf(range, sizeof range, "%s", o->what);
        else
            snprintf(range, sizeof range, "a number in %c%g, %g%c", (o->flags & CLI_LO_OPEN) ? '(' : '[',
                     o->lo, o->hi, (o->flags & CLI_HI_OPEN) ? ')' : ']');
        errno = 0;
        x = strtod(v, &end);
        if (end == v || *end || errno == ERANGE || !isfinite(x)) {
            cli_say(prog, "%s: %s '%s' is not a finite number (needs %s)\n", prog, o->name, v, range);
            return 2;
        }
        if ((o->flags & CLI_LO_OPEN ? !(x > o->lo) : !(x >= o->lo)) ||
            (o->flags & CLI_HI_OPEN ? !(x < o->hi) : !(x <= o->hi))) {
            cli_say(prog, "%s: %s %s is out of range: needs %s\n", prog, o->name, v, range);
            return 2;
        }
        *(double *)o->dst = x;
        return 0;
    }
}

/* parse argv against the tables (a NULL-name-terminated list of tables, so that a driver can
 * add its own options to a shared set); *help = 1 for --help / -h. 0, or 2 after a message. */
static int cli_parse(const char *prog, int argc, char **argv, const cli_opt *const *tables, int *help) {
    int i;
    *help = 0;
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const cli_opt *o = NULL;
        int t, k;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            *help = 1;
            return 0;
        }
        for (t = 0; tables[t] && !o; ++t)
            for (k = 0; tables[t][k].name; ++k)
                if (!strcmp(a, tables[t][k].name)) {
                    o = &tables[t][k];
                    break;
                }
        if (!o) {
            const char *eq = strchr(a, '=');
            if (a[0] == '-' && a[1] == '-' && eq)
                cli_say(prog, "%s: %s: write the value after the option, separated by a space (%.*s %s)\n",
                        prog, a, (int)(eq - a), a, eq + 1);
            else
                cli_say(prog, "%s: unknown option %s (see --help)\n", prog, a);
            return 2;
        }
        if (o->kind == CLI_FLAG) {
            *(int *)o->dst = 1;
            continue;
        }
        if (i + 1 >= argc) {
            cli_say(prog, "%s: %s needs a value (see --help)\n", prog, a);
            return 2;
        }
        if (cli_value(prog, o, argv[++i])) return 2;
    }
    return 0;
}

#endif /* CLI_H */
