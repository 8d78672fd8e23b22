/* test_docs - the manuals say what the code does.
 *
 * README.md's usage snippet is examples/quickstart.c line for line, and that
 * program runs and restores bit for bit; every header and every example
 * driver appears in README.md; no user-facing file points at material users
 * do not have (files outside the project, issue numbers); no two test
 * programs write the same file (tests/run_tests.sh runs them side by side). */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gk_test.h"

/* the text between two markers (exclusive), as a new string; NULL if absent */
static char *between(const char *text, const char *from, const char *to) {
    const char *a = strstr(text, from), *b;
    char *out;
    if (!a) return NULL;
    a += strlen(from);
    b = strstr(a, to);
    if (!b) return NULL;
    out = (char *)malloc((size_t)(b - a) + 1);
    if (!out) return NULL;
    memcpy(out, a, (size_t)(b - a));
    out[b - a] = 0;
    return out;
}

TEST(readme_snippet_is_the_quickstart_program) {
    char *readme = gk_test_slurp("README.md"), *prog = gk_test_slurp("examples/quickstart.c");
    char *snip = NULL, *body = NULL, *head = NULL;
    CHECK(readme && prog);
    if (readme && prog) {
        /* README: the first ```c block after "## Using it" */
        const char *use = strstr(readme, "## Using it");
        CHECK(use != NULL);
        if (use) snip = between(use, "```c\n", "```");
        /* program: the includes, then the part between the snippet markers */
        head = between(prog, "*/\n", "/* README snippet begins */\n");
        body = between(prog, "/* README snippet begins */\n", "/* README snippet ends */");
        CHECK(snip && head && body);
        if (snip && head && body) {
            size_t nh = strlen(head);
            CHECK(strncmp(snip, head, nh) == 0);
            CHECK(strcmp(snip + (strncmp(snip, head, nh) == 0 ? nh : 0), body) == 0);
        }
    }
    free(readme), free(prog), free(snip), free(body), free(head);
}

TEST(quickstart_runs_and_restores_bit_for_bit) {
    char *out;
    int rc = system(BUILD "/quickstart > " BUILD "/tests/quickstart.out 2>&1");
    CHECK(rc == 0);
    out = gk_test_slurp(BUILD "/tests/quickstart.out");
    CHECK(out != NULL);
    if (out) {
        CHECK(strstr(out, "initial  sxx -100028.5") != NULL); /* YADE's getStress() of the packing */
        CHECK(strstr(out, "retried  bit-identical") != NULL);
    }
    free(out);
}

/* whether name ends in suffix (and is longer) */
static int ends_with(const char *name, const char *suffix) {
    size_t n = strlen(name), ns = strlen(suffix);
    return n > ns && strcmp(name + n - ns, suffix) == 0;
}

/* every include/gk_*.h named in README.md's module table, every example
 * driver named in README.md */
static int listed_in(const char *dir, const char *prefix, const char *suffix, const char *readme,
                     const char *fmt) {
    DIR *d = opendir(dir);
    struct dirent *e;
    int missing = 0, seen = 0;
    if (!d) return -1;
    while ((e = readdir(d)) != NULL) {
        const char *nm = e->d_name;
        size_t n = strlen(nm), ns = strlen(suffix);
        char want[256], stem[200];
        if (strncmp(nm, prefix, strlen(prefix)) || !ends_with(nm, suffix) || n - ns >= sizeof stem) continue;
        memcpy(stem, nm, n - ns);
        stem[n - ns] = 0;
        snprintf(want, sizeof want, fmt, stem);
        ++seen;
        if (!strstr(readme, want)) {
            printf("    README.md does not name %s\n", want);
            ++missing;
        }
    }
    closedir(d);
    return seen ? missing : -1;
}

TEST(readme_names_every_header_and_driver) {
    char *readme = gk_test_slurp("README.md");
    CHECK(readme != NULL);
    if (readme) {
        CHECK_EQ_INT(listed_in("include", "gk_", ".h", readme, "| `%s.h` |"), 0);
        CHECK_EQ_INT(listed_in("examples", "", ".c", readme, "`%s`"), 0);
        CHECK_EQ_INT(listed_in("tools", "", ".c", readme, "`%s`"), 0);
    }
    free(readme);
}

/* what a user of the project never has: the developers' shared folder, the
 * design brief, issue numbers (the first two split in the source so that
 * this file does not name them either) */
static int clean(const char *path) {
    static const char *bad[] = {"../sha"
                                "red",
                                "shared/da"
                                "ta",
                                "DESI"
                                "GN.md",
                                "issue 1",
                                "issue 2",
                                "issue 3",
                                "issue 4",
                                "issue 5",
                                "issue 6",
                                "issue 7",
                                "issue 8",
                                "issue 9",
                                "the issue's",
                                "seed 00"};
    char *t = gk_test_slurp(path);
    int k, found = 0;
    if (!t) return 1; /* a missing file is not dirty */
    for (k = 0; k < (int)(sizeof bad / sizeof bad[0]); ++k)
        if (strstr(t, bad[k])) {
            printf("    %s mentions \"%s\"\n", path, bad[k]);
            found = 1;
        }
    free(t);
    return !found;
}

/* clean() over the files of a folder whose names end in one of the suffixes; the count of unclean ones */
static int unclean_in(const char *dir, const char *const *suffix, int nsuffix) {
    DIR *d = opendir(dir);
    struct dirent *e;
    int bad = 0, k;
    if (!d) return 1;
    while ((e = readdir(d)) != NULL) {
        char path[600];
        for (k = 0; k < nsuffix && !ends_with(e->d_name, suffix[k]); ++k) continue;
        if (k == nsuffix || strcmp(e->d_name, "test_docs.c") == 0) continue; /* this file names them */
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        bad += !clean(path);
    }
    closedir(d);
    return bad;
}

TEST(user_documents_point_at_nothing_users_lack) {
    static const char *const code[] = {".c", ".h", ".sh", ".md", ".py", ".in"};
    static const char *const dirs[] = {"include", "examples",   "examples/data",       "tools",
                                       "bench",   "bench/data", "bench/data/tradeoff", "bench/peers",
                                       "tests",   "tests/fuzz"};
    int k;
    CHECK(clean("README.md"));
    CHECK(clean("Makefile"));
    for (k = 0; k < (int)(sizeof dirs / sizeof dirs[0]); ++k) {
        int bad = unclean_in(dirs[k], code, 6);
        if (bad) printf("    %s: %d files\n", dirs[k], bad);
        CHECK_EQ_INT(bad, 0);
    }
}

/* bench/README.md's account of what bounds the 3D force loop comes from
 * bench/knockout.sh, which patches copies of the headers line by line: every
 * patch must still find its line (the script fails when one changes nothing) */
TEST(knockout_patches_still_apply) {
    CHECK_EQ_INT(system("sh bench/knockout.sh --patch-only " BUILD "/tests/knockout > /dev/null"), 0);
}

/* Every name written as a literal BUILD "/tests/NAME..." in a test program
 * belongs to that program alone: `make -j2 test` runs two at a time
 * (tests/run_tests.sh), and two programs writing one file would race. Names
 * of files that must not exist (no_such_...) may be shared. Names made at run
 * time ("/tests/%sA") are not seen here: give them a prefix of the program. */
#define NAMES_MAX 4096
TEST(test_programs_write_files_of_their_own) {
    static char name[NAMES_MAX][64], owner[NAMES_MAX][64];
    int n = 0, files = 0, clashes = 0, i;
    DIR *d = opendir("tests");
    struct dirent *e;
    CHECK(d != NULL);
    while (d && (e = readdir(d)) != NULL) {
        size_t l = strlen(e->d_name);
        char path[300], *text;
        const char *p;
        if (!ends_with(e->d_name, ".c") || l >= 64) continue;
        snprintf(path, sizeof path, "tests/%s", e->d_name);
        text = gk_test_slurp(path);
        CHECK(text != NULL);
        if (!text) continue;
        ++files;
        for (p = strstr(text, "\"/tests/"); p; p = strstr(p + 1, "\"/tests/")) {
            const char *a = p + 8, *b = a;
            char nm[64];
            int seen = 0, other = -1;
            while ((*b >= 'a' && *b <= 'z') || (*b >= 'A' && *b <= 'Z') || (*b >= '0' && *b <= '9') ||
                   *b == '_' || *b == '.' || *b == '-')
                ++b;
            if (b == a || b - a >= 64 || strncmp(a, "no_such", 7) == 0) continue;
            memcpy(nm, a, (size_t)(b - a)), nm[b - a] = 0;
            for (i = 0; i < n; ++i)
                if (strcmp(name[i], nm) == 0) {
                    if (strcmp(owner[i], e->d_name) == 0)
                        seen = 1;
                    else
                        other = i;
                }
            if (seen) continue;
            if (other >= 0) {
                printf("    %s writes BUILD/tests/%s, as %s does\n", e->d_name, nm, owner[other]);
                ++clashes;
            }
            if (n < NAMES_MAX) strcpy(name[n], nm), strcpy(owner[n], e->d_name), ++n;
        }
        free(text);
    }
    if (d) closedir(d);
    CHECK(files >= 10);   /* the scan found the test programs */
    CHECK(n >= 100);      /* and their names */
    CHECK(n < NAMES_MAX); /* all of them */
    CHECK_EQ_INT(clashes, 0);
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(readme_snippet_is_the_quickstart_program);
    RUN(quickstart_runs_and_restores_bit_for_bit);
    RUN(readme_names_every_header_and_driver);
    RUN(user_documents_point_at_nothing_users_lack);
    RUN(test_programs_write_files_of_their_own);
    RUN(knockout_patches_still_apply);
    return gk_test_done();
}
