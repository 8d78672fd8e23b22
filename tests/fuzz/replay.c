/* replay.c - the fuzz corpora as a plain test program (no libFuzzer).
 *
 * LAYOUT
 *   tests/fuzz/fuzz_NAME.c        a harness: LLVMFuzzerTestOneInput(data, size)
 *                                 on one reader; a broken promise aborts
 *                                 (fuzz_check.h)
 *   tests/fuzz/corpus/NAME/       its seed inputs (small valid files, named) and
 *                                 the inputs of past runs that reached new code,
 *                                 minimised by libFuzzer (SHA-1 names):
 *                                   build/fuzz/fuzz_NAME -merge=1 tests/fuzz/corpus/NAME build/fuzz/NAME
 *   tests/fuzz/crashers/NAME/     every input that ever crashed it or broke a
 *                                 promise, kept after the fix
 * `make test` builds build/fuzz_replay_NAME = this file + fuzz_NAME.c with
 * the normal flags (and `make check` under ASan + UBSan): it feeds every
 * file of both directories to the harness and prints one ok line per
 * directory, so a regression on any of them fails the test run. `make fuzz`
 * builds the same harness with clang -fsanitize=fuzzer,address,undefined and
 * runs it for FUZZ_SECONDS (default 60) per harness, new inputs going to
 * build/fuzz/NAME/; a finding is written as build/fuzz/NAME-crash-* and
 * belongs in tests/fuzz/crashers/NAME/ once fixed.
 * A new harness is one file, tests/fuzz/fuzz_NAME.c, plus its seed files in
 * tests/fuzz/corpus/NAME/: the Makefile finds both by name.
 *
 * Run from the repository root (the directories are relative to it). */
#define _POSIX_C_SOURCE 200809L
#include "fuzz_check.h"
#include <dirent.h>
#include <sys/stat.h>

/* feeds every regular file of dir to the harness; returns the count, -1 if dir is missing */
static long replay_dir(const char *dir) {
    DIR *d = opendir(dir);
    struct dirent *de;
    long n = 0;
    if (!d) return -1;
    while ((de = readdir(d)) != NULL) {
        char path[4096];
        struct stat sb;
        FILE *fp;
        unsigned char *buf;
        size_t len;
        if (de->d_name[0] == '.') continue;
        snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
        if (stat(path, &sb) != 0 || !S_ISREG(sb.st_mode)) continue;
        len = (size_t)sb.st_size;
        buf = (unsigned char *)malloc(len + 1);
        fp = fopen(path, "rb");
        if (!buf || !fp || fread(buf, 1, len, fp) != len) {
            fprintf(stderr, "replay: cannot read %s\n", path);
            exit(1);
        }
        fclose(fp);
        LLVMFuzzerTestOneInput(buf, len); /* an abort here is the failure */
        free(buf);
        ++n;
    }
    closedir(d);
    return n;
}

int main(int argc, char **argv) {
    const char *prog = argc > 0 && argv[0] ? argv[0] : "fuzz_replay_", *name = strrchr(prog, '/');
    const char *kinds[2] = {"corpus", "crashers"};
    char dir[1024];
    int k, passed = 0, failed = 0;
    name = name ? name + 1 : prog;
    if (strncmp(name, "fuzz_replay_", 12) != 0) {
        fprintf(stderr, "replay: the program must be named fuzz_replay_NAME\n");
        return 2;
    }
    for (k = 0; k < 2; ++k) {
        long n;
        snprintf(dir, sizeof dir, "tests/fuzz/%s/%s", kinds[k], name + 12);
        n = replay_dir(dir);
        if (n < 0 && k == 1) continue; /* no crasher yet */
        if (n <= 0) {
            printf("FAIL %s: no inputs (run from the repository root)\n", dir);
            ++failed;
        } else {
            printf("ok   %s (%ld inputs)\n", dir, n);
            ++passed;
        }
    }
    printf("# %s: %d passed, %d failed\n", name, passed, failed);
    return failed ? 1 : 0;
}
