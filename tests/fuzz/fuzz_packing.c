/* fuzz_packing.c - libFuzzer harness: gk_packing_parse on arbitrary bytes.
 *
 * Every input must give GK_OK or an error with a message; never a crash,
 * undefined behaviour or a leak. On GK_OK the packing must be what the
 * format promises (dimension 2 or 3, 1 <= n, finite positions, radii > 0, a
 * finite cell with det > 0), and an RVE built from it (small ones) is either
 * refused with a message or deforms a few steps to a finite stress.
 * Build and run: make fuzz (tests/fuzz/replay.c explains the layout). */
#define GK_IMPLEMENTATION
#include "gk_dem.h"
#include "fuzz_check.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    gk_packing pk;
    gk_err e;
    gk_rve rve;
    gk_rve_def def = gk_rve_def_default();
    gk_result r;
    int p;
    e.msg[0] = '\0';
    r = gk_packing_parse((const char *)data, size, &pk, NULL, &e);
    if (r != GK_OK) {
        FUZZ_CHECK(e.msg[0] != '\0' && e.code == r);
        return 0;
    }
    FUZZ_CHECK((pk.dim == 2 || pk.dim == 3) && pk.n >= 1 && (size_t)pk.n <= size);
    FUZZ_CHECK(gk_m3_isfinite(pk.h) && gk_m3_det(pk.h) > 0.0 && isfinite(gk_m3_det(pk.h)));
    for (p = 0; p < pk.n; ++p)
        FUZZ_CHECK(isfinite(pk.x[p]) && isfinite(pk.y[p]) && isfinite(pk.z[p]) && pk.r[p] > 0.0 &&
                   isfinite(pk.r[p]));
    if (pk.n <= 64) { /* the RVE on top: create, deform, stress */
        double dH[9] = {0, 1e-4, 0, 0, 0, 0, 0, 0, 0};
        def.flags = GK_RVE_WRAP;
        memset(&rve, 0, sizeof rve);
        r = gk_rve_create(&rve, &def, &pk);
        if (r != GK_OK) {
            FUZZ_CHECK(gk_rve_error(&rve)[0] != '\0');
        } else {
            r = gk_rve_deform(&rve, dH, 3);
            FUZZ_CHECK(r == GK_OK || gk_rve_error(&rve)[0] != '\0');
            if (r == GK_OK) FUZZ_CHECK(gk_m3_isfinite(rve.stress));
            gk_rve_destroy(&rve);
        }
    }
    gk_packing_free(&pk);
    return 0;
}
