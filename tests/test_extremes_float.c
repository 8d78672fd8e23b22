/* test_extremes_float.c - test_extremes.c in the float build (GK_REAL_FLOAT):
 * a packing 2e6 m from the origin, shear strain 50 and p -> 0 with float
 * velocities and forces (positions stay double, in reduced coordinates). */
#define GK_IMPLEMENTATION /* its own implementation: float reals */
#define GK_REAL_FLOAT
#include "test_extremes.c"
