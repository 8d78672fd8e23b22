/* fuzz_check.h - the one assertion of the fuzz harnesses: a broken promise
 * (a silent wrong result) aborts, so libFuzzer and the replay driver report
 * it as a crash with the condition and the line. */
#ifndef FUZZ_CHECK_H
#define FUZZ_CHECK_H
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
#endif
