/* fuzz_driver.h - what the harnesses that run a driver share: removing their temporary folders, and
 * the driver's output off around a call (stdout to /dev/null, stderr to a file whose length then says
 * whether the driver gave a message). Include after fuzz_check.h, with _POSIX_C_SOURCE defined. */
#ifndef FUZZ_DRIVER_H
#define FUZZ_DRIVER_H
#include "fuzz_check.h"
#include <dirent.h>
#include <fcntl.h>
#include <unistd.h>

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
#endif /* FUZZ_DRIVER_H */
