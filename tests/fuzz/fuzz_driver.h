/* fuzz_driver.h - what the harnesses that run a driver share: naming, making and removing their
 * temporary folders and files (fuzz_twoscale's files too), the driver's output off around a call
 * (stdout to /dev/null, stderr to a file whose length then says whether the driver gave a message),
 * the RVE set's accepted stresses (a refused checkpoint must leave them as they were), their small
 * packing and their model's bytes. Include after the driver (gk_twoscale.h), with _POSIX_C_SOURCE
 * defined. */
#ifndef FUZZ_DRIVER_H
#define FUZZ_DRIVER_H
#include "fuzz_check.h"
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

/* $TMPDIR, default /tmp */
static inline const char *fuzz_tmp_root(void) {
    const char *tmp = getenv("TMPDIR");
    return tmp && *tmp ? tmp : "/tmp";
}

/* dir (cap bytes) = $TMPDIR/gk_fuzz_NAME_PID_WHAT, made */
static inline void fuzz_temp_dir(char *dir, size_t cap, const char *name, const char *what) {
    snprintf(dir, cap, "%s/gk_fuzz_%s_%ld_%s", fuzz_tmp_root(), name, (long)getpid(), what);
    FUZZ_CHECK(mkdir(dir, 0777) == 0 || errno == EEXIST);
}

/* path (cap bytes) = $TMPDIR/gk_fuzz_NAME_PID.EXT (a file; not made) */
static inline void fuzz_temp_path(char *path, size_t cap, const char *name, const char *ext) {
    snprintf(path, cap, "%s/gk_fuzz_%s_%ld.%s", fuzz_tmp_root(), name, (long)getpid(), ext);
}

/* every file of dir, then dir */
static inline void fuzz_remove_dir(const char *dir) {
    DIR *d = opendir(dir);
    struct dirent *de;
    char p[700];
    while (d && (de = readdir(d)) != NULL)
        if (de->d_name[0] != '.') snprintf(p, sizeof p, "%s/%s", dir, de->d_name), remove(p);
    if (d) closedir(d);
    rmdir(dir);
}

static int fuzz_cap_fd = -1, fuzz_null_fd = -1, fuzz_saved_fd[2] = {-1, -1};

/* the file the driver's stderr goes to while it is quiet, and /dev/null for its stdout */
static inline void fuzz_quiet_open(const char *cap_path) {
    FUZZ_CHECK((fuzz_cap_fd = open(cap_path, O_RDWR | O_CREAT | O_TRUNC, 0600)) >= 0);
    FUZZ_CHECK((fuzz_null_fd = open("/dev/null", O_WRONLY)) >= 0);
}

/* the driver's output off around a call; quiet_end gives the bytes it wrote to stderr. FUZZ_VERBOSE
 * in the environment: nothing redirected, -1 */
static inline void fuzz_quiet_begin(void) {
    if (getenv("FUZZ_VERBOSE")) return;
    fflush(stdout), fflush(stderr);
    FUZZ_CHECK(ftruncate(fuzz_cap_fd, 0) == 0 && lseek(fuzz_cap_fd, 0, SEEK_SET) == 0);
    FUZZ_CHECK((fuzz_saved_fd[0] = dup(1)) >= 0 && (fuzz_saved_fd[1] = dup(2)) >= 0);
    FUZZ_CHECK(dup2(fuzz_null_fd, 1) >= 0 && dup2(fuzz_cap_fd, 2) >= 0);
}

static inline long fuzz_quiet_end(void) {
    if (getenv("FUZZ_VERBOSE")) return -1;
    fflush(stdout), fflush(stderr);
    FUZZ_CHECK(dup2(fuzz_saved_fd[0], 1) >= 0 && dup2(fuzz_saved_fd[1], 2) >= 0);
    close(fuzz_saved_fd[0]), close(fuzz_saved_fd[1]);
    return (long)lseek(fuzz_cap_fd, 0, SEEK_END);
}
/* the parts (np of them: addresses and sizes) one after another in one buffer (malloc'ed, n bytes) */
static inline unsigned char *fuzz_concat(const void *const *src, const size_t *parts, int np, size_t *n) {
    unsigned char *b;
    size_t at = 0;
    int k;
    for (*n = 0, k = 0; k < np; ++k) *n += parts[k];
    FUZZ_CHECK((b = (unsigned char *)malloc(*n + 1)) != NULL);
    for (k = 0; k < np; ++k) memcpy(b + at, src[k], parts[k]), at += parts[k];
    return b;
}

/* the drivers' small packing, written to path with comment: 12 disks of radius 0.4-0.6 mm (seed 11),
 * consolidated to pressure [Pa] with def's contact law first when pressure > 0 */
static inline void fuzz_small_packing(const char *path, const char *comment, double pressure,
                                      const gk_rve_def *def) {
    gk_packing pk, out;
    gk_gen_def g;
    gk_rve rve;
    gk_consolidate_def cd;
    gk_err err;
    memset(&g, 0, sizeof g);
    g.dim = 2, g.n = 12, g.r_min = 0.4e-3, g.r_max = 0.6e-3, g.seed = 11;
    FUZZ_CHECK(gk_packing_generate(&pk, &g, NULL, &err) == GK_OK);
    if (pressure > 0.0) {
        FUZZ_CHECK(gk_rve_create(&rve, def, &pk) == GK_OK);
        memset(&cd, 0, sizeof cd);
        cd.pressure = pressure, cd.max_steps = 200000;
        FUZZ_CHECK(gk_rve_consolidate(&rve, &cd, NULL) == GK_OK);
        FUZZ_CHECK(gk_rve_to_packing(&rve, &out, NULL, &err) == GK_OK);
        gk_rve_destroy(&rve), gk_packing_free(&pk), pk = out;
    }
    FUZZ_CHECK(gk_packing_write(path, &pk, comment, &err) == GK_OK);
    gk_packing_free(&pk);
}

/* the set's accepted stresses (malloc'ed, 9 per point) */
static inline double *fuzz_set_stresses(gk_twoscale *ts) {
    double *s = (double *)malloc(9 * (size_t)ts->n * sizeof *s);
    FUZZ_CHECK(s != NULL && gk_twoscale_accepted(ts, s, NULL) == GK_OK);
    return s;
}

/* whether the set's accepted stresses are still ref's */
static inline int fuzz_same_set(gk_twoscale *ts, const double *ref) {
    double *s = fuzz_set_stresses(ts);
    int same = memcmp(s, ref, 9 * (size_t)ts->n * sizeof *s) == 0;
    free(s);
    return same;
}
#endif /* FUZZ_DRIVER_H */
