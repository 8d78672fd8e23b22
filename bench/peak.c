/* bench_peak - this CPU's floating-point peak, to put the DEM kernels'
 * flop rates in proportion: fused multiply-adds on independent accumulators
 * (enough of them to hide the latency), double and float, 1 and 2 threads,
 * with the widest vectors this build uses.
 *
 *   build/bench_peak
 *   BENCH case=peak real=double threads=1 simd=avx512 gflops=... */
#define _POSIX_C_SOURCE 200809L
#define GK_IMPLEMENTATION
#include "gk_base.h"
#include "gk_io.h"
#include <stdio.h>
#include <string.h>

#define NACC 12
#define ITER 20000000L

static double run_double(void) {
#if GK_SIMD_WIDTH == 512
    __m512d acc[NACC], a = _mm512_set1_pd(1.0 + 1e-9), b = _mm512_set1_pd(1e-9);
    double out[8], s = 0;
    long it;
    int k;
    for (k = 0; k < NACC; ++k) acc[k] = _mm512_set1_pd((double)k);
    for (it = 0; it < ITER; ++it)
        for (k = 0; k < NACC; ++k) acc[k] = _mm512_fmadd_pd(acc[k], a, b);
    for (k = 1; k < NACC; ++k) acc[0] = _mm512_add_pd(acc[0], acc[k]);
    _mm512_storeu_pd(out, acc[0]);
    for (k = 0; k < 8; ++k) s += out[k];
    return s;
#elif GK_SIMD_WIDTH == 256
    __m256d acc[NACC], a = _mm256_set1_pd(1.0 + 1e-9), b = _mm256_set1_pd(1e-9);
    double out[4], s = 0;
    long it;
    int k;
    for (k = 0; k < NACC; ++k) acc[k] = _mm256_set1_pd((double)k);
    for (it = 0; it < ITER; ++it)
        for (k = 0; k < NACC; ++k) acc[k] = _mm256_fmadd_pd(acc[k], a, b);
    for (k = 1; k < NACC; ++k) acc[0] = _mm256_add_pd(acc[0], acc[k]);
    _mm256_storeu_pd(out, acc[0]);
    for (k = 0; k < 4; ++k) s += out[k];
    return s;
#else
    double acc[NACC], a = 1.0 + 1e-9, b = 1e-9, s = 0;
    long it;
    int k;
    for (k = 0; k < NACC; ++k) acc[k] = k;
    for (it = 0; it < ITER; ++it)
        for (k = 0; k < NACC; ++k) acc[k] = acc[k] * a + b;
    for (k = 0; k < NACC; ++k) s += acc[k];
    return s;
#endif
}

static double run_float(void) {
#if GK_SIMD_WIDTH == 512
    __m512 acc[NACC], a = _mm512_set1_ps(1.0f + 1e-7f), b = _mm512_set1_ps(1e-7f);
    float out[16];
    double s = 0;
    long it;
    int k;
    for (k = 0; k < NACC; ++k) acc[k] = _mm512_set1_ps((float)k);
    for (it = 0; it < ITER; ++it)
        for (k = 0; k < NACC; ++k) acc[k] = _mm512_fmadd_ps(acc[k], a, b);
    for (k = 1; k < NACC; ++k) acc[0] = _mm512_add_ps(acc[0], acc[k]);
    _mm512_storeu_ps(out, acc[0]);
    for (k = 0; k < 16; ++k) s += out[k];
    return s;
#elif GK_SIMD_WIDTH == 256
    __m256 acc[NACC], a = _mm256_set1_ps(1.0f + 1e-7f), b = _mm256_set1_ps(1e-7f);
    float out[8];
    double s = 0;
    long it;
    int k;
    for (k = 0; k < NACC; ++k) acc[k] = _mm256_set1_ps((float)k);
    for (it = 0; it < ITER; ++it)
        for (k = 0; k < NACC; ++k) acc[k] = _mm256_fmadd_ps(acc[k], a, b);
    for (k = 1; k < NACC; ++k) acc[0] = _mm256_add_ps(acc[0], acc[k]);
    _mm256_storeu_ps(out, acc[0]);
    for (k = 0; k < 8; ++k) s += out[k];
    return s;
#else
    float acc[NACC], a = 1.0f + 1e-7f, b = 1e-7f;
    double s = 0;
    long it;
    int k;
    for (k = 0; k < NACC; ++k) acc[k] = (float)k;
    for (it = 0; it < ITER; ++it)
        for (k = 0; k < NACC; ++k) acc[k] = acc[k] * a + b;
    for (k = 0; k < NACC; ++k) s += acc[k];
    return s;
#endif
}

int main(int argc, char **argv) {
    int real, th;
    double lanes_d = GK_SIMD_WIDTH >= 256 ? GK_SIMD_WIDTH / 64 : 1,
           lanes_f = GK_SIMD_WIDTH >= 256 ? GK_SIMD_WIDTH / 32 : 1;
    if (argc > 1) { /* no options: what it measures */
        int help = !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h");
        fprintf(help ? stdout : stderr,
                "usage: bench_peak (no options)\n"
                "the FMA throughput of one and two threads in double and float (%s), in GFLOP/s:\n"
                "the peak the DEM kernels are compared with in bench/README.md\n",
                GK_SIMD_NAME);
        return help ? 0 : 2;
    }
    printf("peak FMA throughput (%s, %d accumulators)\n", GK_SIMD_NAME, NACC);
    for (real = 0; real < 2; ++real)
        for (th = 1; th <= 2; ++th) {
            double t0 = gk_wtime(), sink = 0, secs, flops;
            int k;
            GK_OMP(parallel for num_threads(th) reduction(+ : sink))
            for (k = 0; k < th; ++k) sink += real ? run_float() : run_double();
            secs = gk_wtime() - t0;
            flops = 2.0 * NACC * (real ? lanes_f : lanes_d) * (double)ITER * th;
            printf("BENCH case=peak real=%s threads=%d simd=%s gflops=%.1f (checksum %.3g)\n",
                   real ? "float" : "double", th, GK_SIMD_NAME, flops / secs / 1e9, sink);
        }
    return 0;
}
