/* capi_test.c: a plain C host of libfacet.so. Compiles a material, reads
   its input names, evaluates scalar and batch (SIMD and scalar backends),
   checks the values against the interpreter backend and against a closed
   form, checks error reporting, and releases everything. */
#include <facet/facet.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

static int failures = 0;
#define EXPECT(cond, ...)                          \
    do {                                           \
        if (!(cond)) {                             \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__); \
            fprintf(stderr, __VA_ARGS__);          \
            fprintf(stderr, "\n");                 \
            ++failures;                            \
        }                                          \
    } while (0)

static const char* kMaterial =
    "material test {\n"
    "    input roughness = 0.5 in 0 .. 1;\n"
    "    input tint = rgb(1, 1, 1);\n"
    "    ndf = ggx(roughness * roughness);\n"
    "    masking = smith_height_correlated;\n"
    "    fresnel = schlick(f0 = 0.04 * tint);\n"
    "}\n";

int main(void) {
    char err[512];
    facet_kernel* simd = facet_compile_text(kMaterial, "test.mat", NULL, "backend=simd;cache=memory", err, sizeof err);
    EXPECT(simd != NULL, "compile failed: %s", err);
    facet_kernel* scalar = facet_compile_text(kMaterial, "test.mat", "test", "backend=scalar;cache=memory", err, sizeof err);
    EXPECT(scalar != NULL, "compile failed: %s", err);
    facet_kernel* interp = facet_compile_text(kMaterial, "test.mat", NULL, "backend=interp", err, sizeof err);
    EXPECT(interp != NULL, "compile failed: %s", err);
    if (!simd || !scalar || !interp) return 1;

    EXPECT(facet_input_count(simd) == 4, "input count %d", facet_input_count(simd));
    EXPECT(strcmp(facet_input_name(simd, 0), "roughness") == 0, "slot 0 %s", facet_input_name(simd, 0));
    EXPECT(strcmp(facet_input_name(simd, 3), "tint.b") == 0, "slot 3 %s", facet_input_name(simd, 3));
    EXPECT(facet_input_name(simd, 4) == NULL, "slot 4 must be NULL");

    /* Normal incidence, defaults: GGX D(n) = 1/(pi a^2), a = 0.25; G = 1;
       F = f0 = 0.04; f = F D / 4. */
    float n[3] = {0, 0, 1}, rgb[3];
    facet_eval(simd, n, n, NULL, rgb);
    double expected = 0.04 / (3.14159265358979323846 * 0.0625) / 4.0;
    EXPECT(fabs(rgb[0] - expected) < 1e-6 * expected, "simd normal incidence %.9g vs %.9g", rgb[0], expected);
    facet_eval(scalar, n, n, NULL, rgb);
    EXPECT(fabs(rgb[1] - expected) < 1e-6 * expected, "scalar normal incidence %.9g vs %.9g", rgb[1], expected);

    /* Batch of 37 lanes (not a multiple of any width), with per-lane
       roughness, a NULL slot (tint.g default) and two invalid lanes. */
    enum { N = 37 };
    float wix[N], wiy[N], wiz[N], wox[N], woy[N], woz[N], rough[N], tr[N], tb[N], r[N], g[N], b[N];
    for (int i = 0; i < N; ++i) {
        double ti = 0.02 * i, to = 0.03 * i, po = 0.1 * i;
        wix[i] = (float)sin(ti); wiy[i] = 0; wiz[i] = (float)cos(ti);
        wox[i] = (float)(sin(to) * cos(po)); woy[i] = (float)(sin(to) * sin(po)); woz[i] = (float)cos(to);
        rough[i] = 0.1f + 0.02f * i; tr[i] = 0.5f; tb[i] = 1.0f;
    }
    wix[5] = NAN;        /* invalid: not finite */
    wox[9] = 2.0f;       /* invalid: not a unit vector */
    const float* wi[3] = {wix, wiy, wiz};
    const float* wo[3] = {wox, woy, woz};
    const float* inputs[4] = {rough, tr, NULL, tb};
    float* out[3] = {r, g, b};
    int64_t bad = facet_eval_batch(simd, N, wi, wo, inputs, out);
    EXPECT(bad == 2, "simd invalid lanes %lld", (long long)bad);
    EXPECT(r[5] == 0 && g[9] == 0, "invalid lanes must be 0");
    for (int i = 0; i < N; ++i) {
        float a[3] = {wix[i], wiy[i], wiz[i]}, c[3] = {wox[i], woy[i], woz[i]}, ref[3], sc[3];
        float in[4] = {rough[i], tr[i], 1.0f, tb[i]};
        facet_eval(interp, a, c, in, ref);
        facet_eval(scalar, a, c, in, sc);
        float got[3] = {r[i], g[i], b[i]};
        for (int ch = 0; ch < 3; ++ch) {
            double tol = 1e-5 * fabs(ref[ch]) + 1e-30;
            EXPECT(fabs(got[ch] - ref[ch]) <= tol, "lane %d ch %d simd %.9g interp %.9g", i, ch, got[ch], ref[ch]);
            EXPECT(fabs(sc[ch] - ref[ch]) <= tol, "lane %d ch %d scalar %.9g interp %.9g", i, ch, sc[ch], ref[ch]);
        }
    }
    float r2[N], g2[N], b2[N];
    float* out2[3] = {r2, g2, b2};
    EXPECT(facet_eval_batch(scalar, N, wi, wo, inputs, out2) == 2, "scalar backend batch invalid count");
    EXPECT(facet_eval_batch(interp, N, wi, wo, inputs, out2) == 2, "interp backend batch invalid count");

    /* Bound input: set.roughness removes the slot. */
    facet_kernel* bound = facet_compile_text(kMaterial, "test.mat", NULL, "set.roughness=0.5", err, sizeof err);
    EXPECT(bound && facet_input_count(bound) == 3, "bound kernel slots");
    if (bound) {
        facet_eval(bound, n, n, NULL, rgb);
        EXPECT(fabs(rgb[2] - expected) < 1e-6 * expected, "bound normal incidence %.9g", rgb[2]);
        facet_release(bound);
    }

    /* Errors: a diagnostic with file:line:col, and NULL. */
    facet_kernel* broken = facet_compile_text("material m { ndf = ggz(0.1); }", "broken.mat", NULL, NULL, err, sizeof err);
    EXPECT(broken == NULL, "broken material must not compile");
    EXPECT(strcmp(err, "broken.mat:1:20: error: unknown ndf model 'ggz' (did you mean 'ggx'?)") == 0, "err: %s", err);
    EXPECT(facet_compile_file("/nonexistent.mat", NULL, NULL, err, sizeof err) == NULL, "missing file");
    EXPECT(strstr(err, "cannot open file") != NULL, "err: %s", err);
    EXPECT(facet_compile_text(kMaterial, "t", NULL, "backend=gpu", err, sizeof err) == NULL, "bad option");
    EXPECT(strstr(err, "backend 'gpu'") != NULL, "err: %s", err);
    EXPECT(facet_compile_text(kMaterial, "t", "nope", NULL, err, 8) == NULL && strlen(err) == 7, "truncated err");

    facet_release(simd);
    facet_release(scalar);
    facet_release(interp);
    facet_release(NULL);
    printf("capi_test: %d failures\n", failures);
    return failures ? 1 : 0;
}
