/* gk_test.h - the tiny test harness used by every tests/test_*.c program.
 *
 *   TEST(name) { CHECK(cond); CHECK_NEAR(a, b, tol); CHECK_REL(a, b, rtol); }
 *   int main(int argc, char **argv) { RUN(name); ...; return gk_test_done(); }
 *
 * Each test prints "ok   <name>" or "FAIL <name>" (with the failed checks and
 * their values). gk_test_done() prints "# <program>: P passed, F failed" and
 * returns non-zero on failure; tests/run_tests.sh sums these lines.
 * A program given a test name as argv[1] runs only the tests whose names
 * contain it. */
#ifndef GK_TEST_H
#define GK_TEST_H
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

static int gk__t_checks_failed;
static int gk__t_passed, gk__t_failed;
static const char *gk__t_filter;
static const char *gk__t_prog = "test";

#define CHECK(c)                                                                  \
    do {                                                                          \
        if (!(c)) {                                                               \
            ++gk__t_checks_failed;                                                \
            printf("    %s:%d: CHECK(%s) failed\n", __FILE__, __LINE__, #c);      \
        }                                                                         \
    } while (0)

/* |a - b| <= tol */
#define CHECK_NEAR(a, b, tol)                                                     \
    do {                                                                          \
        double gk__a = (double)(a), gk__b = (double)(b), gk__tol = (double)(tol); \
        if (!(fabs(gk__a - gk__b) <= gk__tol)) {                                  \
            ++gk__t_checks_failed;                                                \
            printf("    %s:%d: CHECK_NEAR(%s, %s, %s): %.17g vs %.17g (diff %.3g)\n", \
                   __FILE__, __LINE__, #a, #b, #tol, gk__a, gk__b, fabs(gk__a - gk__b)); \
        }                                                                         \
    } while (0)

/* |a - b| <= rtol * max(|a|, |b|) */
#define CHECK_REL(a, b, rtol)                                                     \
    do {                                                                          \
        double gk__a = (double)(a), gk__b = (double)(b), gk__r = (double)(rtol);  \
        double gk__m = fabs(gk__a) > fabs(gk__b) ? fabs(gk__a) : fabs(gk__b);     \
        if (!(fabs(gk__a - gk__b) <= gk__r * gk__m)) {                            \
            ++gk__t_checks_failed;                                                \
            printf("    %s:%d: CHECK_REL(%s, %s, %s): %.17g vs %.17g (rel %.3g)\n", \
                   __FILE__, __LINE__, #a, #b, #rtol, gk__a, gk__b,               \
                   gk__m > 0 ? fabs(gk__a - gk__b) / gk__m : 0.0);                \
        }                                                                         \
    } while (0)

#define CHECK_EQ_INT(a, b)                                                        \
    do {                                                                          \
        long gk__a = (long)(a), gk__b = (long)(b);                                \
        if (gk__a != gk__b) {                                                     \
            ++gk__t_checks_failed;                                                \
            printf("    %s:%d: CHECK_EQ_INT(%s, %s): %ld vs %ld\n", __FILE__,     \
                   __LINE__, #a, #b, gk__a, gk__b);                               \
        }                                                                         \
    } while (0)

#define TEST(name) static void name(void)

static void gk__t_run(const char *name, void (*fn)(void)) {
    clock_t t0;
    if (gk__t_filter && !strstr(name, gk__t_filter)) return;
    gk__t_checks_failed = 0;
    t0 = clock();
    fn();
    if (gk__t_checks_failed == 0) {
        ++gk__t_passed;
        printf("ok   %s (%.2f s)\n", name, (double)(clock() - t0) / CLOCKS_PER_SEC);
    } else {
        ++gk__t_failed;
        printf("FAIL %s (%d checks failed)\n", name, gk__t_checks_failed);
    }
    fflush(stdout);
}
#define RUN(name) gk__t_run(#name, name)

static void gk_test_init(int argc, char **argv) {
    const char *p;
    if (argc > 0 && argv[0]) {
        gk__t_prog = argv[0];
        p = strrchr(gk__t_prog, '/');
        if (p) gk__t_prog = p + 1;
    }
    if (argc > 1) gk__t_filter = argv[1];
}
static int gk_test_done(void) {
    printf("# %s: %d passed, %d failed\n", gk__t_prog, gk__t_passed, gk__t_failed);
    return gk__t_failed ? 1 : 0;
}
#endif
