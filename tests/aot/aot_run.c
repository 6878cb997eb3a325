/* aot_run.c: a plain C99 host of one ahead-of-time compiled material, linked
   only against the object `facet build` wrote and libm. Compiled once per
   object with -DAOT_PREFIX=name -DAOT_MACRO=NAME -include name.h.

     aot_run INPUTS.bin OUTPUTS.bin

   Reads the lanes facet_aot_reference wrote (SoA directions and input
   slots), evaluates them through PREFIX_eval_batch (one call over all lanes)
   and PREFIX_eval (lane by lane), finds each lane's invalid status with a
   one-lane batch call where the output is all zero, and writes everything
   for facet_aot_reference to compare. It also checks the argument
   conventions of the two entry points itself. Exit 0, or 1 on a failed
   check or an I/O error. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define AOT_CAT2(a, b) a##b
#define AOT_CAT(a, b) AOT_CAT2(a, b)
#define AOT_EVAL AOT_CAT(AOT_PREFIX, _eval)
#define AOT_EVAL_BATCH AOT_CAT(AOT_PREFIX, _eval_batch)
#define AOT_INPUT_COUNT_OF(p) AOT_CAT(p, _INPUT_COUNT)

static int failures = 0;
#define EXPECT(cond, ...)                                        \
    do {                                                         \
        if (!(cond)) {                                           \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__); \
            fprintf(stderr, __VA_ARGS__);                        \
            fprintf(stderr, "\n");                               \
            ++failures;                                          \
        }                                                        \
    } while (0)

static int readAll(FILE* f, void* data, size_t bytes) { return fread(data, 1, bytes, f) == bytes; }
static int writeAll(FILE* f, const void* data, size_t bytes) { return fwrite(data, 1, bytes, f) == bytes; }

int main(int argc, char** argv) {
    FILE* in;
    FILE* out;
    char magic[8];
    int32_t slots;
    int64_t n, i, batchCount, nullCount;
    int c, s;
    float* lanes; /* 6 + slots streams of n floats */
    float* results; /* 6 streams: batch rgb, eval rgb */
    char* invalid;
    const float* wi[3];
    const float* wo[3];
    const float** inputs;
    float* rgb[3];

    if (argc != 3) {
        fprintf(stderr, "usage: %s INPUTS.bin OUTPUTS.bin\n", argv[0]);
        return 1;
    }
    in = fopen(argv[1], "rb");
    if (!in || !readAll(in, magic, 8) || memcmp(magic, "FACETAOT", 8) != 0 || !readAll(in, &slots, 4) ||
        !readAll(in, &n, 8) || n < 1 || slots < 0 || slots > 64) {
        fprintf(stderr, "%s: not an input file of facet_aot_reference\n", argv[1]);
        return 1;
    }
    if (slots != AOT_INPUT_COUNT_OF(AOT_MACRO)) {
        fprintf(stderr, "%s: %d input slots, the header says %d\n", argv[1], (int)slots,
                AOT_INPUT_COUNT_OF(AOT_MACRO));
        return 1;
    }
    lanes = malloc(sizeof(float) * (size_t)n * (size_t)(6 + slots));
    results = malloc(sizeof(float) * (size_t)n * 6);
    invalid = malloc((size_t)n);
    inputs = malloc(sizeof(const float*) * (size_t)(slots + 1));
    if (!lanes || !results || !invalid || !inputs) return 1;
    if (!readAll(in, lanes, sizeof(float) * (size_t)n * (size_t)(6 + slots)) || fgetc(in) != EOF) {
        fprintf(stderr, "%s: truncated or too long\n", argv[1]);
        return 1;
    }
    fclose(in);
    for (c = 0; c < 3; ++c) {
        wi[c] = lanes + (size_t)c * (size_t)n;
        wo[c] = lanes + (size_t)(3 + c) * (size_t)n;
        rgb[c] = results + (size_t)c * (size_t)n;
    }
    for (s = 0; s < slots; ++s) inputs[s] = lanes + (size_t)(6 + s) * (size_t)n;

    batchCount = AOT_EVAL_BATCH(n, wi, wo, slots ? inputs : NULL, rgb);

    /* One lane at a time through the scalar-convention entry point. */
    for (i = 0; i < n; ++i) {
        float a[3], b[3], o[3], lane[64];
        for (c = 0; c < 3; ++c) {
            a[c] = wi[c][i];
            b[c] = wo[c][i];
        }
        for (s = 0; s < slots && s < 64; ++s) lane[s] = inputs[s][i];
        AOT_EVAL(a, b, slots ? lane : NULL, o);
        for (c = 0; c < 3; ++c) results[(size_t)(3 + c) * (size_t)n + (size_t)i] = o[c];
    }

    /* Per-lane status: only a lane whose output is all zero can be invalid. */
    for (i = 0; i < n; ++i) {
        const float* a[3];
        const float* b[3];
        const float* ip[64];
        float r[3] = {-1, -1, -1};
        float* rp[3];
        invalid[i] = 0;
        if (!(rgb[0][i] == 0 && rgb[1][i] == 0 && rgb[2][i] == 0)) continue;
        for (c = 0; c < 3; ++c) {
            a[c] = &wi[c][i];
            b[c] = &wo[c][i];
            rp[c] = &r[c];
        }
        for (s = 0; s < slots && s < 64; ++s) ip[s] = &inputs[s][i];
        invalid[i] = (char)AOT_EVAL_BATCH(1, a, b, slots ? ip : NULL, rp);
    }

    /* The argument conventions (SPEC section 4). */
    EXPECT(AOT_EVAL_BATCH(0, wi, wo, NULL, rgb) == 0, "n = 0 must return 0");
    EXPECT(AOT_EVAL_BATCH(-1, wi, wo, NULL, rgb) == -1, "n < 0 must return -1");
    EXPECT(AOT_EVAL_BATCH(n, NULL, wo, NULL, rgb) == -1, "NULL wi must return -1");
    EXPECT(AOT_EVAL_BATCH(n, wi, NULL, NULL, rgb) == -1, "NULL wo must return -1");
    EXPECT(AOT_EVAL_BATCH(n, wi, wo, NULL, NULL) == -1, "NULL rgb must return -1");
    {
        float o[3] = {7, 7, 7};
        float n3[3] = {0, 0, 1};
        AOT_EVAL(NULL, n3, NULL, o);
        EXPECT(o[0] == 0 && o[1] == 0 && o[2] == 0, "eval with NULL wi must give 0");
        AOT_EVAL(n3, n3, NULL, NULL); /* must not crash */
    }
    /* NULL inputs and per-slot NULL inputs both mean the defaults. */
    if (slots > 0) {
        int64_t m = n < 1000 ? n : 1000;
        float* d1 = malloc(sizeof(float) * (size_t)m * 6);
        float* r1[3];
        float* r2[3];
        const float** nulls = calloc((size_t)slots, sizeof(const float*));
        if (!d1 || !nulls) return 1;
        for (c = 0; c < 3; ++c) {
            r1[c] = d1 + (size_t)c * (size_t)m;
            r2[c] = d1 + (size_t)(3 + c) * (size_t)m;
        }
        nullCount = AOT_EVAL_BATCH(m, wi, wo, NULL, r1);
        EXPECT(AOT_EVAL_BATCH(m, wi, wo, nulls, r2) == nullCount, "NULL slots and NULL inputs count differently");
        EXPECT(memcmp(d1, d1 + 3 * m, sizeof(float) * (size_t)m * 3) == 0,
               "NULL slots and NULL inputs give different values");
        free(d1);
        free((void*)nulls);
    }

    out = fopen(argv[2], "wb");
    if (!out || !writeAll(out, "FACETRUN", 8) || !writeAll(out, &n, 8) ||
        !writeAll(out, results, sizeof(float) * (size_t)n * 6) || !writeAll(out, &batchCount, 8) ||
        !writeAll(out, invalid, (size_t)n) || fclose(out) != 0) {
        fprintf(stderr, "%s: cannot write\n", argv[2]);
        return 1;
    }
    free(lanes);
    free(results);
    free(invalid);
    free((void*)inputs);
    printf("%s: %lld lanes, %lld invalid\n", argv[1], (long long)n, (long long)batchCount);
    return failures ? 1 : 0;
}
