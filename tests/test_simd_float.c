/* test_simd_float.c - test_simd.c in the float build (GK_REAL_FLOAT): the
 * float SIMD kernels equal the float scalar reference bit for bit. */
#define GK_IMPLEMENTATION /* its own implementation: float reals */
#define GK_REAL_FLOAT
#include "test_simd.c"
