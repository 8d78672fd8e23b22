/* fuzz_csv.c - libFuzzer harness: the CSV reader of tools/csv_plot.c on arbitrary bytes.
 *
 * Every input must be read (a curve of at least one point, every value finite: x scaled by 100,
 * y by 1e-3, as a strain in % and a stress in kPa) or refused; never a crash, undefined behaviour
 * or a leak. The tool's own file is compiled in (its main renamed), so the reader fuzzed is the
 * one users run. Build and run: make fuzz (tests/fuzz/replay.c explains the layout). */
#define _POSIX_C_SOURCE 200809L /* fmemopen */
#define main csv_plot_main
#include "../../tools/csv_plot.c"
#undef main
#include "fuzz_check.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    cp_curve c;
    FILE *fp;
    int bad;
    if (size == 0) return 0; /* fmemopen refuses an empty buffer */
    if (!(fp = fmemopen((void *)data, size, "r"))) return 0;
    cp_quiet = 1;
    memset(&c, 0, sizeof c);
    bad = read_curve_fp(fp, "input", "a", "b", 100, 1e-3, &c);
    fclose(fp);
    if (!bad) {
        FUZZ_CHECK(c.n >= 1 && c.n <= c.cap);
        fuzz_all_finite(c.x, (size_t)c.n);
        fuzz_all_finite(c.y, (size_t)c.n);
    }
    free(c.x);
    free(c.y);
    return 0;
}
