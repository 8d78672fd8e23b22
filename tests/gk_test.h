/* gk_test.h - the tiny test harness used by every tests/test_*.c program.
 *
 *   TEST(name) { CHECK(cond); CHECK_NEAR(a, b, tol); CHECK_REL(a, b, rtol); }
 *   int main(int argc, char **argv) { RUN(name); ...; return gk_test_done(); }
 *
 * Each test prints "ok   <name>" or "FAIL <name>" (with the failed checks and
 * their values). gk_test_done() prints "# <program>: P passed, F failed" and
 * returns non-zero on failure; tests/run_tests.sh sums these lines.
 * A program given a test name as argv[1] runs only the tests whose names
 * contain it (none matching: a message and a non-zero exit); --help says so.
 *
 * Tests run from the repository's root and write only under BUILD/tests/
 * (gk_test_init creates it; `make test` leaves nothing else behind). BUILD is
 * the build folder, where the tests also find the programs they launch: the
 * Makefile passes its $(BUILD) (default "build"), e.g. `make BUILD=out test`. */
#ifndef GK_TEST_H
#define GK_TEST_H
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/times.h>
#include <unistd.h>

#ifndef BUILD
#define BUILD "build"
#endif

static int gk__t_checks_failed;
static int gk__t_passed, gk__t_failed;
static const char *gk__t_filter;
static const char *gk__t_prog = "test";

#define CHECK(c)                                                             \
    do {                                                                     \
        if (!(c)) {                                                          \
            ++gk__t_checks_failed;                                           \
            printf("    %s:%d: CHECK(%s) failed\n", __FILE__, __LINE__, #c); \
        }                                                                    \
    } while (0)

/* |a - b| <= tol */
#define CHECK_NEAR(a, b, tol)                                                                             \
    do {                                                                                                  \
        double gk__a = (double)(a), gk__b = (double)(b), gk__tol = (double)(tol);                         \
        if (!(fabs(gk__a - gk__b) <= gk__tol)) {                                                          \
            ++gk__t_checks_failed;                                                                        \
            printf("    %s:%d: CHECK_NEAR(%s, %s, %s): %.17g vs %.17g (diff %.3g)\n", __FILE__, __LINE__, \
                   #a, #b, #tol, gk__a, gk__b, fabs(gk__a - gk__b));                                      \
        }                                                                                                 \
    } while (0)

/* |a - b| <= rtol * max(|a|, |b|) */
#define CHECK_REL(a, b, rtol)                                                                               \
    do {                                                                                                    \
        double gk__a = (double)(a), gk__b = (double)(b), gk__r = (double)(rtol);                            \
        double gk__m = fabs(gk__a) > fabs(gk__b) ? fabs(gk__a) : fabs(gk__b);                               \
        if (!(fabs(gk__a - gk__b) <= gk__r * gk__m)) {                                                      \
            ++gk__t_checks_failed;                                                                          \
            printf("    %s:%d: CHECK_REL(%s, %s, %s): %.17g vs %.17g (rel %.3g)\n", __FILE__, __LINE__, #a, \
                   #b, #rtol, gk__a, gk__b, gk__m > 0 ? fabs(gk__a - gk__b) / gk__m : 0.0);                 \
        }                                                                                                   \
    } while (0)

#define CHECK_EQ_INT(a, b)                                                                             \
    do {                                                                                               \
        long gk__a = (long)(a), gk__b = (long)(b);                                                     \
        if (gk__a != gk__b) {                                                                          \
            ++gk__t_checks_failed;                                                                     \
            printf("    %s:%d: CHECK_EQ_INT(%s, %s): %ld vs %ld\n", __FILE__, __LINE__, #a, #b, gk__a, \
                   gk__b);                                                                             \
        }                                                                                              \
    } while (0)

#define TEST(name) static void name(void)

/* seconds for the per-test times: wall clock (a test that waits for a
 * driver it launched counts that wait), in every build, with or without
 * OpenMP. POSIX times() is declared in strict C99 mode too; 10 ms steps. */
static double gk__t_now(void) {
    struct tms t;
    return (double)times(&t) / (double)sysconf(_SC_CLK_TCK);
}

static void gk__t_run(const char *name, void (*fn)(void)) {
    double t0;
    if (gk__t_filter && !strstr(name, gk__t_filter)) return;
    gk__t_checks_failed = 0;
    t0 = gk__t_now();
    fn();
    if (gk__t_checks_failed == 0) {
        ++gk__t_passed;
        printf("ok   %s (%.2f s)\n", name, gk__t_now() - t0);
    } else {
        ++gk__t_failed;
        printf("FAIL %s (%d checks failed)\n", name, gk__t_checks_failed);
    }
    fflush(stdout);
}
#define RUN(name) gk__t_run(#name, name)

#if defined(__GNUC__) || defined(__clang__)
#define GK__T_UNUSED __attribute__((unused))
#else
#define GK__T_UNUSED
#endif

/* the whole file in a NUL-terminated buffer to free (NULL if unreadable) */
GK__T_UNUSED static char *gk_test_slurp(const char *path) {
    FILE *fp = fopen(path, "rb");
    char *buf = NULL;
    long n;
    if (!fp) return NULL;
    if (fseek(fp, 0, SEEK_END) == 0 && (n = ftell(fp)) >= 0 && fseek(fp, 0, SEEK_SET) == 0 &&
        (buf = (char *)malloc((size_t)n + 1)) != NULL) {
        if (fread(buf, 1, (size_t)n, fp) != (size_t)n) {
            free(buf);
            buf = NULL;
        } else {
            buf[n] = 0;
        }
    }
    fclose(fp);
    return buf;
}

/* ---- for smoke tests of the example drivers: #define GK_TEST_DRIVERS
 * before including this file */
#ifdef GK_TEST_DRIVERS
/* 1 if the file exists and some line contains needle */
static int gk_test_file_has(const char *path, const char *needle) {
    FILE *fp = fopen(path, "r");
    char buf[4096];
    int found = 0;
    if (!fp) return 0;
    while (!found && fgets(buf, sizeof buf, fp))
        if (strstr(buf, needle)) found = 1;
    fclose(fp);
    return found;
}
/* value of "key=" on the last line of path starting with "RESULT ", or NAN */
static double gk_test_result(const char *path, const char *key) {
    FILE *fp = fopen(path, "r");
    char buf[4096], last[4096], pat[128];
    const char *q;
    last[0] = 0;
    if (!fp) return NAN;
    while (fgets(buf, sizeof buf, fp))
        if (!strncmp(buf, "RESULT ", 7)) memcpy(last, buf, sizeof buf);
    fclose(fp);
    snprintf(pat, sizeof pat, " %s=", key);
    q = strstr(last, pat);
    return q ? atof(q + strlen(pat)) : NAN;
}
/* 1 if two CSV files have the same lines, at least min_lines of them (the
 * header counts), in their first ncol columns (e.g. all but a trailing
 * `seconds` column) */
GK__T_UNUSED static int gk_test_csv_same(const char *a, const char *b, int ncol, int min_lines) {
    FILE *fa = fopen(a, "r"), *fb = fopen(b, "r");
    char la[4096], lb[4096];
    int same = fa && fb, rows = 0;
    while (same) {
        char *pa = fgets(la, sizeof la, fa), *pb = fgets(lb, sizeof lb, fb);
        int k, c = 0;
        if (!pa || !pb) {
            same = !pa && !pb;
            break;
        }
        for (k = 0; la[k] && lb[k] && c < ncol; ++k) {
            if (la[k] != lb[k]) same = 0;
            if (la[k] == ',') ++c;
        }
        ++rows;
    }
    if (fa) fclose(fa);
    if (fb) fclose(fb);
    return same && rows >= min_lines;
}
#endif

static void gk_test_init(int argc, char **argv) {
    const char *p;
    if (argc > 0 && argv[0]) {
        gk__t_prog = argv[0];
        p = strrchr(gk__t_prog, '/');
        if (p) gk__t_prog = p + 1;
    }
    if (argc > 1 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        printf("usage: %s [PART]   run every test of this program, or those whose names contain PART\n"
               "(from the repository's root; outputs under %s/tests/)\n",
               gk__t_prog, BUILD);
        exit(0);
    }
    if (argc > 1) gk__t_filter = argv[1];
    mkdir(BUILD, 0755); /* where the outputs go (already there under make test) */
    mkdir(BUILD "/tests", 0755);
}
static int gk_test_done(void) {
    printf("# %s: %d passed, %d failed\n", gk__t_prog, gk__t_passed, gk__t_failed);
    if (gk__t_filter && gk__t_passed + gk__t_failed == 0) {
        printf("# %s: no test name contains \"%s\" (--help)\n", gk__t_prog, gk__t_filter);
        return 1;
    }
    return gk__t_failed ? 1 : 0;
}
#endif
