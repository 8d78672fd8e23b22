/* fuzz_check.h - the one assertion of the fuzz harnesses: a broken promise
 * (a silent wrong result) aborts, so libFuzzer and the replay driver report
 * it as a crash with the condition and the line. */
#ifndef FUZZ_CHECK_H
#define FUZZ_CHECK_H
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FUZZ_CHECK(c)                                                                  \
    do {                                                                               \
        if (!(c)) {                                                                    \
            fprintf(stderr, "%s:%d: FUZZ_CHECK(%s) failed\n", __FILE__, __LINE__, #c); \
            abort();                                                                   \
        }                                                                              \
    } while (0)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* every value finite, or abort */
static inline void fuzz_all_finite(const double *v, size_t n) {
    size_t k;
    for (k = 0; k < n; ++k) FUZZ_CHECK(isfinite(v[k]));
}

/* the bytes of a file (malloc'd, one spare byte), or abort */
static inline unsigned char *fuzz_slurp(const char *path, size_t *n) {
    FILE *fp = fopen(path, "rb");
    unsigned char *b = NULL;
    long end;
    FUZZ_CHECK(fp && fseek(fp, 0, SEEK_END) == 0 && (end = ftell(fp)) >= 0 && fseek(fp, 0, SEEK_SET) == 0);
    FUZZ_CHECK((b = (unsigned char *)malloc((size_t)end + 1)) != NULL);
    FUZZ_CHECK(fread(b, 1, (size_t)end, fp) == (size_t)end);
    fclose(fp);
    *n = (size_t)end;
    return b;
}

/* The checkpoint harnesses' input: byte 0 is a mode, the rest is the file.
 * An even mode writes the right checksum into the file (gk_twoscale's: the
 * last 8 bytes are the FNV-1a hash of the rest), so that the fuzzer gets past
 * the checksum to the header and field checks. */
static inline uint64_t fuzz_fnv1a(const unsigned char *b, size_t n) {
    uint64_t h = UINT64_C(0xcbf29ce484222325);
    while (n--) h = (h ^ *b++) * UINT64_C(0x100000001b3);
    return h;
}

static inline void fuzz_write_checkpoint(const char *path, const uint8_t *data, size_t size) {
    size_t len = size - 1;
    unsigned char *file = (unsigned char *)malloc(len + 1);
    FILE *fp;
    FUZZ_CHECK(size >= 1 && file != NULL);
    memcpy(file, data + 1, len);
    if (!(data[0] & 1) && len >= 8) {
        uint64_t h = fuzz_fnv1a(file, len - 8);
        memcpy(file + len - 8, &h, 8);
    }
    FUZZ_CHECK((fp = fopen(path, "wb")) != NULL && fwrite(file, 1, len, fp) == len && fclose(fp) == 0);
    free(file);
}

/* The driver harnesses' checkpoint: the file checkpoint.bin of a run folder,
 * as the drivers write and read it. */
static inline void fuzz_checkpoint_path(char *path, size_t cap, const char *dir) {
    int len = snprintf(path, cap, "%s/checkpoint.bin", dir);
    FUZZ_CHECK(len > 0 && (size_t)len < cap);
}

/* the input as DIR/checkpoint.bin (fuzz_write_checkpoint) */
static inline void fuzz_write_checkpoint_in(const char *dir, const uint8_t *data, size_t size) {
    char path[1024];
    fuzz_checkpoint_path(path, sizeof path, dir);
    fuzz_write_checkpoint(path, data, size);
}

/* the bytes of DIR/checkpoint.bin (fuzz_slurp) */
static inline unsigned char *fuzz_slurp_checkpoint(const char *dir, size_t *n) {
    char path[1024];
    fuzz_checkpoint_path(path, sizeof path, dir);
    return fuzz_slurp(path, n);
}

/* a seed file for a checkpoint harness: the mode byte, then the bytes */
static inline void fuzz_write_seed(const char *dir, const char *name, unsigned char mode,
                                   const unsigned char *b, size_t n) {
    char path[1024];
    FILE *fp;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    fp = fopen(path, "wb");
    FUZZ_CHECK(fp && fwrite(&mode, 1, 1, fp) == 1 && fwrite(b, 1, n, fp) == n && fclose(fp) == 0);
}
#endif
