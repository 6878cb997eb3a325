/* aot_vs_jit.c: ns/eval of an ahead-of-time object (`facet build`) next to
   the JIT kernel of the same material and options (libfacet.so), on the
   same batch of lanes, runs interleaved; also checks that both give the
   same bits. Built and run by scripts/aot-bench.sh, which compiles it once
   per object with -D_POSIX_C_SOURCE=200112L -DAOT_PREFIX=name -include name.h.

     aot_vs_jit FILE.mat OPTIONS [LANES] [RUNS]

   Directions cosine-distributed over the hemisphere, inputs at their
   defaults. Prints the fastest and the median of RUNS batch calls of LANES
   lanes each: on a shared machine the median of either side sometimes
   jumps several-fold for a whole process, the fastest run does not. */
#include <facet/facet.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define AOT_CAT2(a, b) a##b
#define AOT_CAT(a, b) AOT_CAT2(a, b)
#define AOT_EVAL_BATCH AOT_CAT(AOT_PREFIX, _eval_batch)
#define AOT_STRING2(a) #a
#define AOT_STRING(a) AOT_STRING2(a)

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int compareDoubles(const void* a, const void* b) {
    double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

static void direction(float* x, float* y, float* z, unsigned* seed) {
    double u1 = (double)rand_r(seed) / RAND_MAX, u2 = (double)rand_r(seed) / RAND_MAX;
    double c = sqrt(u1), r = sqrt(1 - c * c), phi = 6.283185307179586 * u2;
    *x = (float)(r * cos(phi));
    *y = (float)(r * sin(phi));
    *z = (float)c;
}

int main(int argc, char** argv) {
    char err[1024];
    long lanes = argc > 3 ? atol(argv[3]) : 65536, runs = argc > 4 ? atol(argv[4]) : 31, i, r;
    float* data;
    const float* wi[3];
    const float* wo[3];
    float* jitOut[3];
    float* aotOut[3];
    double* jitTimes;
    double* aotTimes;
    unsigned seed = 12345;
    int c;
    facet_kernel* kernel;
    if (argc < 3 || lanes < 1 || runs < 1) {
        fprintf(stderr, "usage: %s FILE.mat OPTIONS [LANES] [RUNS]\n", argv[0]);
        return 2;
    }
    kernel = facet_compile_file(argv[1], NULL, argv[2], err, sizeof err);
    if (!kernel) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    data = malloc(sizeof(float) * (size_t)lanes * 12);
    jitTimes = malloc(sizeof(double) * (size_t)runs);
    aotTimes = malloc(sizeof(double) * (size_t)runs);
    if (!data || !jitTimes || !aotTimes) return 1;
    for (c = 0; c < 3; ++c) {
        wi[c] = data + (size_t)c * (size_t)lanes;
        wo[c] = data + (size_t)(3 + c) * (size_t)lanes;
        jitOut[c] = data + (size_t)(6 + c) * (size_t)lanes;
        aotOut[c] = data + (size_t)(9 + c) * (size_t)lanes;
    }
    for (i = 0; i < lanes; ++i) {
        direction(&data[i], &data[lanes + i], &data[2 * lanes + i], &seed);
        direction(&data[3 * lanes + i], &data[4 * lanes + i], &data[5 * lanes + i], &seed);
    }
    for (r = 0; r < runs; ++r) {
        double t0 = now();
        facet_eval_batch(kernel, lanes, wi, wo, NULL, jitOut);
        double t1 = now();
        AOT_EVAL_BATCH(lanes, wi, wo, NULL, aotOut);
        double t2 = now();
        jitTimes[r] = (t1 - t0) * 1e9 / (double)lanes;
        aotTimes[r] = (t2 - t1) * 1e9 / (double)lanes;
    }
    qsort(jitTimes, (size_t)runs, sizeof(double), compareDoubles);
    qsort(aotTimes, (size_t)runs, sizeof(double), compareDoubles);
    printf("%-26s %-24s ns/eval fastest: JIT %6.2f AOT %6.2f (AOT/JIT %.3f); median: JIT %6.2f AOT %6.2f; outputs %s\n",
           AOT_STRING(AOT_PREFIX), argv[2], jitTimes[0], aotTimes[0], aotTimes[0] / jitTimes[0], jitTimes[runs / 2],
           aotTimes[runs / 2],
           memcmp(data + 6 * lanes, data + 9 * lanes, sizeof(float) * 3 * (size_t)lanes) == 0 ? "identical" : "DIFFER");
    facet_release(kernel);
    free(data);
    free(jitTimes);
    free(aotTimes);
    return 0;
}
