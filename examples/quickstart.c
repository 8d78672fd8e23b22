/* quickstart - one RVE: load it, shear it, read its stress and tangent, retry.
 *
 *   build/quickstart [PACKING]      (default examples/data/rve400.txt)
 *
 * The program README.md shows under "Using it", line for line: a test keeps
 * the two identical. It loads a packing, shears the RVE by 0.1 % over 100
 * DEM steps, prints the Love stress (tension-positive inside grainkit) and
 * the Taylor tangent, restores the state saved before the shear and shears
 * again: the second stress is bit-identical to the first.
 */
#define GK_IMPLEMENTATION /* in exactly one .c file */
#include "gk_homog.h"     /* pulls in base, cells, contact, pcell, packing, dem */

#include <stdio.h>
#include <string.h>

/* README snippet begins */
int main(int argc, char **argv) {
    const char *path = argc > 1 ? argv[1] : "examples/data/rve400.txt";
    gk_packing pk;
    gk_rve rve;
    gk_rve_state saved;
    gk_err e;
    gk_rve_def def = gk_rve_def_default();         /* linear + Coulomb, Guo & Zhao 2014 */
    double dH[9] = {0, 1e-3, 0, 0, 0, 0, 0, 0, 0}; /* H01 = du_x/dy: simple shear */
    double sig[9], sig2[9], D[81];                 /* the tangent: dim^4 entries, 81 in 3D */
    int rc = 1;

    if (gk_packing_read(path, &pk, NULL, &e)) {
        fprintf(stderr, "%s\n", e.msg);
        return 1;
    }
    if (gk_rve_create(&rve, &def, &pk)) { /* copies the packing: free it now */
        fprintf(stderr, "%s\n", gk_rve_error(&rve));
        gk_packing_free(&pk);
        return 1;
    }
    gk_packing_free(&pk);
    gk_rve_state_init(&saved, NULL);
    /* a new RVE has no forces yet: refresh computes them (and the stress)
     * at the current positions without moving anything */
    if (gk_rve_refresh(&rve) || gk_rve_state_save(&saved, &rve)) goto done;
    gk_rve_stress(&rve, sig);
    printf("initial  sxx %.1f  syy %.1f  sxy %.1f Pa\n", sig[0], sig[4], sig[1]);

    if (gk_rve_deform(&rve, dH, 100)) goto done; /* 100 DEM steps */
    gk_rve_stress(&rve, sig);                    /* Love stress, tension-positive */
    if (gk_homog_tangent(&rve, 0, D)) goto done; /* Taylor tangent, D[((i d + j) d + k) d + l] */
    printf("sheared  sxx %.1f  syy %.1f  sxy %.1f Pa   D_xyxy %.4g Pa\n", sig[0], sig[4], sig[1],
           D[rve.dim * rve.dim + 1]); /* i = k = x, j = l = y */

    /* an implicit driver retries an increment from the last converged state */
    if (gk_rve_state_restore(&saved, &rve) || gk_rve_deform(&rve, dH, 100)) goto done;
    gk_rve_stress(&rve, sig2);
    printf("retried  %s\n", memcmp(sig, sig2, sizeof sig) == 0 ? "bit-identical" : "DIFFERENT");
    rc = memcmp(sig, sig2, sizeof sig) != 0;
done:
    if (rc && gk_rve_error(&rve)[0]) fprintf(stderr, "%s\n", gk_rve_error(&rve));
    gk_rve_state_free(&saved);
    gk_rve_destroy(&rve);
    return rc;
}
/* README snippet ends */
