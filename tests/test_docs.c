/* test_docs - the manuals say what the code does.
 *
 * README.md's usage snippet is examples/quickstart.c line for line, and that
 * program runs and restores bit for bit; every header and every example
 * driver appears in README.md; no user-facing file points at material users
 * do not have (files outside the project, issue numbers). */
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
        if (strncmp(nm, prefix, strlen(prefix)) || n <= ns || strcmp(nm + n - ns, suffix) ||
            n - ns >= sizeof stem)
            continue;
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

TEST(user_documents_point_at_nothing_users_lack) {
    CHECK(clean("README.md"));
    CHECK(clean("examples/README.md"));
    CHECK(clean("bench/README.md"));
    CHECK(clean("Makefile"));
}

int main(int argc, char **argv) {
    gk_test_init(argc, argv);
    RUN(readme_snippet_is_the_quickstart_program);
    RUN(quickstart_runs_and_restores_bit_for_bit);
    RUN(readme_names_every_header_and_driver);
    RUN(user_documents_point_at_nothing_users_lack);
    return gk_test_done();
}
