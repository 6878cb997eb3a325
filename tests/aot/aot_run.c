/* aot_run.c: a plain C99 host of one ahead-of-time compiled material, linked
   only against the object `facet build` wrote and libm. Compiled once per
   object with -DAOT_PREFIX=name -include name.h (the header's macros are
   name_INPUT_COUNT, name_HAS_SAMPLER: the prefix as given).

     aot_run INPUTS.bin OUTPUTS.bin

   Reads the lanes facet_aot_reference wrote (SoA directions, input slots
   and three uniform numbers), evaluates them through PREFIX_eval_batch (one
   call over all lanes) and PREFIX_eval (lane by lane), finds each lane's
   invalid status with a one-lane batch call where the output is all zero,
   and where the header says PREFIX_HAS_SAMPLER 1 samples wi for each lane's
   wo and u and evaluates the pdf of each lane's (wi, wo), through the batch
   and the one-lane entry points; it writes everything for
   facet_aot_reference to compare. It also checks the argument and
   invalid-lane conventions of the entry points itself. Exit 0, or 1 on a
   failed check or an I/O error. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define AOT_CAT2(a, b) a##b
#define AOT_CAT(a, b) AOT_CAT2(a, b)
#define AOT_EVAL AOT_CAT(AOT_PREFIX, _eval)
#define AOT_EVAL_BATCH AOT_CAT(AOT_PREFIX, _eval_batch)
#define AOT_INPUT_COUNT AOT_CAT(AOT_PREFIX, _INPUT_COUNT)
#define AOT_SAMPLE AOT_CAT(AOT_PREFIX, _sample)
#define AOT_SAMPLE_BATCH AOT_CAT(AOT_PREFIX, _sample_batch)
#define AOT_PDF AOT_CAT(AOT_PREFIX, _pdf)
#define AOT_PDF_BATCH AOT_CAT(AOT_PREFIX, _pdf_batch)
#define AOT_HAS_SAMPLER AOT_CAT(AOT_PREFIX, _HAS_SAMPLER)

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

#if AOT_HAS_SAMPLER
/* The sampler's part: sample and pdf through the batch and the one-lane
   entry points, their conventions, and the results appended to `out`.
   u[0..2] are the lanes' uniform numbers. */
static int runSampler(FILE* out, int64_t n, int slots, const float* const wi[3], const float* const wo[3],
                      const float* const u[3], const float** inputs) {
    float* sb = malloc(sizeof(float) * (size_t)n * 7); /* batch: wi, pdf, weight */
    float* ss = malloc(sizeof(float) * (size_t)n * 7); /* one lane at a time */
    float* pb = malloc(sizeof(float) * (size_t)n * 2); /* pdf batch, one-lane pdf */
    char* sInvalid = malloc((size_t)n);
    const float** nulls = calloc((size_t)slots + 1, sizeof(const float*));
    float* swi[3];
    float* sweight[3];
    int64_t sampleCount, pdfCount, scalarInvalid = 0, i;
    int c, s, ok;
    if (!sb || !ss || !pb || !sInvalid || !nulls) return 0;
    for (c = 0; c < 3; ++c) {
        swi[c] = sb + (size_t)c * (size_t)n;
        sweight[c] = sb + (size_t)(4 + c) * (size_t)n;
    }
    sampleCount = AOT_SAMPLE_BATCH(n, wo, u, slots ? inputs : NULL, swi, sb + 3 * n, sweight);
    pdfCount = AOT_PDF_BATCH(n, wi, wo, slots ? inputs : NULL, pb);
    for (i = 0; i < n; ++i) {
        float a[3], b[3], uu[3], lane[64], w[3], p, weight[3], w2[3] = {7, 7, 7}, p2 = 7;
        for (c = 0; c < 3; ++c) {
            a[c] = wi[c][i];
            b[c] = wo[c][i];
            uu[c] = u[c][i];
        }
        for (s = 0; s < slots && s < 64; ++s) lane[s] = inputs[s][i];
        sInvalid[i] = (char)AOT_SAMPLE(b, uu, slots ? lane : NULL, w, &p, weight);
        scalarInvalid += sInvalid[i];
        for (c = 0; c < 3; ++c) {
            ss[(size_t)c * (size_t)n + (size_t)i] = w[c];
            ss[(size_t)(4 + c) * (size_t)n + (size_t)i] = weight[c];
        }
        ss[3 * (size_t)n + (size_t)i] = p;
        pb[(size_t)n + (size_t)i] = AOT_PDF(a, b, slots ? lane : NULL);
        /* Invalid lanes give zeros; NULL outputs are skipped, the others written as before. */
        if (sInvalid[i])
            EXPECT(w[0] == 0 && w[1] == 0 && w[2] == 0 && p == 0 && weight[0] == 0 && weight[1] == 0 &&
                       weight[2] == 0,
                   "lane %lld: an invalid sample must give zeros", (long long)i);
        if (i % 97 == 0) {
            EXPECT(AOT_SAMPLE(b, uu, slots ? lane : NULL, NULL, &p2, NULL) == sInvalid[i] && p2 == p,
                   "lane %lld: a sample with NULL wi and weight differs", (long long)i);
            EXPECT(AOT_SAMPLE(b, uu, slots ? lane : NULL, w2, NULL, NULL) == sInvalid[i] && w2[0] == w[0] &&
                       w2[1] == w[1] && w2[2] == w[2],
                   "lane %lld: a sample with NULL pdf and weight differs", (long long)i);
        }
    }
    EXPECT(scalarInvalid == sampleCount, "sample: %lld invalid lanes one at a time, %lld in the batch",
           (long long)scalarInvalid, (long long)sampleCount);

    /* The argument conventions (facet_sample_batch, facet_pdf_batch, facet_sample, facet_pdf). */
    EXPECT(AOT_SAMPLE_BATCH(0, wo, u, NULL, swi, sb + 3 * n, sweight) == 0, "sample: n = 0 must return 0");
    EXPECT(AOT_SAMPLE_BATCH(0, NULL, NULL, NULL, NULL, NULL, NULL) == 0, "sample: n = 0 with NULL arrays must return 0");
    EXPECT(AOT_SAMPLE_BATCH(-1, wo, u, NULL, swi, sb + 3 * n, sweight) == -1, "sample: n < 0 must return -1");
    EXPECT(AOT_SAMPLE_BATCH(n, NULL, u, NULL, swi, sb + 3 * n, sweight) == -1, "sample: NULL wo must return -1");
    EXPECT(AOT_SAMPLE_BATCH(n, wo, NULL, NULL, swi, sb + 3 * n, sweight) == -1, "sample: NULL u must return -1");
    EXPECT(AOT_SAMPLE_BATCH(n, wo, u, NULL, NULL, sb + 3 * n, sweight) == -1, "sample: NULL wi must return -1");
    EXPECT(AOT_SAMPLE_BATCH(n, wo, u, NULL, swi, NULL, sweight) == -1, "sample: NULL pdf must return -1");
    EXPECT(AOT_SAMPLE_BATCH(n, wo, u, NULL, swi, sb + 3 * n, NULL) == -1, "sample: NULL weight must return -1");
    {
        const float* holed[3];
        float* holedOut[3];
        holed[0] = u[0], holed[1] = NULL, holed[2] = u[2];
        holedOut[0] = swi[0], holedOut[1] = swi[1], holedOut[2] = NULL;
        EXPECT(AOT_SAMPLE_BATCH(n, wo, holed, NULL, swi, sb + 3 * n, sweight) == -1,
               "sample: a NULL entry of u must return -1");
        EXPECT(AOT_SAMPLE_BATCH(n, wo, u, NULL, holedOut, sb + 3 * n, sweight) == -1,
               "sample: a NULL entry of wi must return -1");
        holed[0] = wi[0], holed[1] = wi[1], holed[2] = NULL;
        EXPECT(AOT_PDF_BATCH(n, holed, wo, NULL, pb) == -1, "pdf: a NULL entry of wi must return -1");
    }
    EXPECT(AOT_PDF_BATCH(0, wi, wo, NULL, pb) == 0, "pdf: n = 0 must return 0");
    EXPECT(AOT_PDF_BATCH(0, NULL, NULL, NULL, NULL) == 0, "pdf: n = 0 with NULL arrays must return 0");
    EXPECT(AOT_PDF_BATCH(-1, wi, wo, NULL, pb) == -1, "pdf: n < 0 must return -1");
    EXPECT(AOT_PDF_BATCH(n, NULL, wo, NULL, pb) == -1, "pdf: NULL wi must return -1");
    EXPECT(AOT_PDF_BATCH(n, wi, NULL, NULL, pb) == -1, "pdf: NULL wo must return -1");
    EXPECT(AOT_PDF_BATCH(n, wi, wo, NULL, NULL) == -1, "pdf: NULL pdf must return -1");
    {
        float n3[3] = {0, 0, 1}, half[3] = {0.5f, 0.5f, 0.5f}, w[3] = {7, 7, 7}, p = 7, weight[3] = {7, 7, 7};
        EXPECT(AOT_SAMPLE(NULL, half, NULL, w, &p, weight) == 1 && w[0] == 0 && w[1] == 0 && w[2] == 0 && p == 0 &&
                   weight[0] == 0 && weight[1] == 0 && weight[2] == 0,
               "sample with NULL wo must return 1 and zeros");
        EXPECT(AOT_SAMPLE(n3, NULL, NULL, w, &p, weight) == 1 && p == 0, "sample with NULL u must return 1");
        EXPECT(AOT_SAMPLE(n3, half, NULL, NULL, NULL, NULL) == 0, "sample with NULL outputs must still run");
        EXPECT(AOT_PDF(NULL, n3, NULL) == 0 && AOT_PDF(n3, NULL, NULL) == 0, "pdf with a NULL direction must be 0");
    }
    /* NULL inputs and per-slot NULL inputs both mean the defaults. */
    if (slots > 0) {
        int64_t m = n < 1000 ? n : 1000;
        float* d = malloc(sizeof(float) * (size_t)m * 14);
        float *wiA[3], *wtA[3], *wiB[3], *wtB[3];
        if (!d) return 0;
        for (c = 0; c < 3; ++c) {
            wiA[c] = d + (size_t)c * (size_t)m, wtA[c] = d + (size_t)(4 + c) * (size_t)m;
            wiB[c] = d + (size_t)(7 + c) * (size_t)m, wtB[c] = d + (size_t)(11 + c) * (size_t)m;
        }
        EXPECT(AOT_SAMPLE_BATCH(m, wo, u, NULL, wiA, d + 3 * m, wtA) ==
                   AOT_SAMPLE_BATCH(m, wo, u, nulls, wiB, d + 10 * m, wtB),
               "sample: NULL slots and NULL inputs count differently");
        EXPECT(memcmp(d, d + 7 * m, sizeof(float) * (size_t)m * 7) == 0,
               "sample: NULL slots and NULL inputs give different values");
        free(d);
    }
    ok = writeAll(out, &sampleCount, 8) && writeAll(out, sb, sizeof(float) * (size_t)n * 7) &&
         writeAll(out, ss, sizeof(float) * (size_t)n * 7) && writeAll(out, sInvalid, (size_t)n) &&
         writeAll(out, &pdfCount, 8) && writeAll(out, pb, sizeof(float) * (size_t)n * 2);
    free(sb);
    free(ss);
    free(pb);
    free(sInvalid);
    free((void*)nulls);
    return ok;
}
#endif

int main(int argc, char** argv) {
    FILE* in;
    FILE* out;
    char magic[8];
    int32_t slots;
    int64_t n, i, batchCount, nullCount;
    int c, s;
    float* lanes; /* 6 + slots + 3 streams of n floats: wi, wo, the slots, u */
    float* results; /* 6 streams: batch rgb, eval rgb */
    char* invalid;
    const float* wi[3];
    const float* wo[3];
    const float* u[3];
    const float** inputs;
    int32_t hasSampler = AOT_HAS_SAMPLER;
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
    if (slots != AOT_INPUT_COUNT) {
        fprintf(stderr, "%s: %d input slots, the header says %d\n", argv[1], (int)slots,
                AOT_INPUT_COUNT);
        return 1;
    }
    lanes = malloc(sizeof(float) * (size_t)n * (size_t)(9 + slots));
    results = malloc(sizeof(float) * (size_t)n * 6);
    invalid = malloc((size_t)n);
    inputs = malloc(sizeof(const float*) * (size_t)(slots + 1));
    if (!lanes || !results || !invalid || !inputs) return 1;
    if (!readAll(in, lanes, sizeof(float) * (size_t)n * (size_t)(9 + slots)) || fgetc(in) != EOF) {
        fprintf(stderr, "%s: truncated or too long\n", argv[1]);
        return 1;
    }
    fclose(in);
    for (c = 0; c < 3; ++c) {
        wi[c] = lanes + (size_t)c * (size_t)n;
        wo[c] = lanes + (size_t)(3 + c) * (size_t)n;
        rgb[c] = results + (size_t)c * (size_t)n;
        u[c] = lanes + (size_t)(6 + slots + c) * (size_t)n;
    }
    for (s = 0; s < slots; ++s) inputs[s] = lanes + (size_t)(6 + s) * (size_t)n;
#if !AOT_HAS_SAMPLER
    (void)u; /* read, not used: the object has no sampler */
#endif

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
    EXPECT(AOT_EVAL_BATCH(0, NULL, NULL, NULL, NULL) == 0, "n = 0 with NULL arrays must return 0");
    {
        const float* holed[3];
        holed[0] = wi[0], holed[1] = NULL, holed[2] = wi[2];
        EXPECT(AOT_EVAL_BATCH(0, holed, wo, NULL, rgb) == 0, "n = 0 with a NULL entry of wi must return 0");
        EXPECT(AOT_EVAL_BATCH(n, holed, wo, NULL, rgb) == -1, "a NULL entry of wi must return -1");
    }
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
        !writeAll(out, invalid, (size_t)n) || !writeAll(out, &hasSampler, 4)
#if AOT_HAS_SAMPLER
        || !runSampler(out, n, slots, wi, wo, u, inputs)
#endif
        || fclose(out) != 0) {
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
