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

    /* Per-lane status: 1 exactly for the two invalid lanes, on every backend. */
    facet_kernel* kernels[3] = {simd, scalar, interp};
    for (int kk = 0; kk < 3; ++kk) {
        uint8_t status[N];
        memset(status, 9, sizeof status);
        EXPECT(facet_eval_batch_status(kernels[kk], N, wi, wo, inputs, out2, status) == 2, "status count %d", kk);
        for (int i = 0; i < N; ++i)
            EXPECT(status[i] == (i == 5 || i == 9), "kernel %d lane %d status %d", kk, i, status[i]);
    }

    /* Misuse: -1 and a message, never a lane count; n = 0 is 0. */
    const float* wiBroken[3] = {wix, NULL, wiz};
    EXPECT(facet_eval_batch(NULL, N, wi, wo, inputs, out2) == -1, "NULL kernel");
    EXPECT(strcmp(facet_last_error(), "facet_eval_batch: error: the kernel is NULL") == 0, "msg: %s", facet_last_error());
    EXPECT(facet_eval_batch(simd, -3, wi, wo, inputs, out2) == -1, "n < 0");
    EXPECT(strcmp(facet_last_error(), "facet_eval_batch: error: n is negative (-3)") == 0, "msg: %s", facet_last_error());
    EXPECT(facet_eval_batch(simd, N, NULL, wo, inputs, out2) == -1, "NULL wi");
    EXPECT(strcmp(facet_last_error(), "facet_eval_batch: error: wi is NULL") == 0, "msg: %s", facet_last_error());
    EXPECT(facet_eval_batch(scalar, N, wiBroken, wo, inputs, out2) == -1, "NULL wi[1]");
    EXPECT(strcmp(facet_last_error(), "facet_eval_batch: error: wi[1] is NULL") == 0, "msg: %s", facet_last_error());
    EXPECT(facet_eval_batch(interp, N, wi, wo, inputs, NULL) == -1, "NULL rgb");
    EXPECT(facet_eval_batch(simd, 0, NULL, NULL, NULL, NULL) == 0, "n = 0");

    /* The interp backend counts a lane whose double value float cannot hold
       (plastic at wi = (1,0,1e-40), wo = (-1,0,1e-40): about 1.9e41) as
       invalid, as the compiled backends do; never +Inf. */
    {
        static const char* kPlastic =
            "material plastic {\n"
            "    input roughness = 0.4 in 0 .. 1;\n"
            "    ndf = ggx(roughness * roughness);\n"
            "    masking = smith_height_correlated;\n"
            "    fresnel = schlick(eta = 1.49);\n"
            "    diffuse = lambert(0.5);\n"
            "}\n";
        float gx[1] = {1}, gy[1] = {0}, gz[1] = {1e-40f}, hx[1] = {-1}, hz[1] = {1e-40f}, o[3][1];
        const float* gwi[3] = {gx, gy, gz};
        const float* gwo[3] = {hx, gy, hz};
        float* gout[3] = {o[0], o[1], o[2]};
        const char* backends[3] = {"backend=interp", "backend=scalar;cache=memory", "backend=simd;cache=memory"};
        for (int kk = 0; kk < 3; ++kk) {
            facet_kernel* k = facet_compile_text(kPlastic, "plastic.mat", NULL, backends[kk], err, sizeof err);
            EXPECT(k != NULL, "compile %s: %s", backends[kk], err);
            if (!k) continue;
            uint8_t st = 9;
            EXPECT(facet_eval_batch_status(k, 1, gwi, gwo, NULL, gout, &st) == 1, "%s: grazing lane counted", backends[kk]);
            EXPECT(st == 1 && o[0][0] == 0 && o[1][0] == 0 && o[2][0] == 0, "%s: grazing lane %g status %d",
                   backends[kk], o[0][0], st);
            facet_release(k);
        }
    }

    /* Options: blanks around '=' and ';' are fine, a repeated option is not. */
    facet_kernel* spaced = facet_compile_text(kMaterial, "t", NULL, " backend = scalar ; math = exact ;cache=memory", err, sizeof err);
    EXPECT(spaced != NULL, "spaced options: %s", err);
    if (spaced) facet_release(spaced);
    EXPECT(facet_compile_text(kMaterial, "t", NULL, "backend=simd;backend=scalar", err, sizeof err) == NULL, "repeated option");
    EXPECT(strcmp(err, "options: error: option 'backend' is given twice") == 0, "err: %s", err);
    EXPECT(facet_compile_text(kMaterial, "t", NULL, "set.roughness=0.1;set.roughness=0.2", err, sizeof err) == NULL, "repeated set");
    EXPECT(facet_compile_file("/", NULL, NULL, err, sizeof err) == NULL, "a directory");
    EXPECT(strcmp(err, "/: error: is a directory, not a file") == 0, "err: %s", err);

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

    /* Sampling: the same u through the SIMD, scalar and interpreter kernels;
       the pdf of the sample; invalid lanes (u = 1, a non-unit wo) counted
       and zeroed; NULL arrays rejected. */
    {
        const float wo[3] = {0.6f, 0.0f, 0.8f}, u[3] = {0.25f, 0.5f, 0.75f};
        float wi[3][3], pdf[3], weight[3][3];
        facet_kernel* kernels[3] = {simd, scalar, interp};
        for (int b = 0; b < 3; ++b)
            EXPECT(facet_sample(kernels[b], wo, u, NULL, wi[b], &pdf[b], weight[b]) == 0, "sample %d invalid", b);
        for (int b = 1; b < 3; ++b) {
            EXPECT(fabsf(wi[b][2] - wi[0][2]) < 1e-5f, "wi.z %d: %g vs %g", b, wi[b][2], wi[0][2]);
            EXPECT(fabsf(pdf[b] - pdf[0]) <= 1e-5f * pdf[0], "pdf %d: %g vs %g", b, pdf[b], pdf[0]);
            EXPECT(fabsf(weight[b][0] - weight[0][0]) <= 1e-5f * weight[0][0] + 1e-7f, "weight %d", b);
        }
        EXPECT(pdf[0] > 0 && weight[0][0] > 0, "sample: pdf %g weight %g", pdf[0], weight[0][0]);
        float back = facet_pdf(simd, wi[0], wo, NULL);
        EXPECT(fabsf(back - pdf[0]) <= 1e-5f * pdf[0], "facet_pdf %g vs sampled %g", back, pdf[0]);

        float woX[3] = {0.6f, 0.6f, 0.5f}, woY[3] = {0, 0, 0}, woZ[3] = {0.8f, 0.8f, 0.5f};
        float u0[3] = {0.25f, 1.0f, 0.25f}, u1[3] = {0.5f, 0.5f, 0.5f}, u2[3] = {0.75f, 0.75f, 0.75f};
        float wiX[3], wiY[3], wiZ[3], p[3], wr[3], wg[3], wb[3];
        const float* woA[3] = {woX, woY, woZ};
        const float* uA[3] = {u0, u1, u2};
        float* wiA[3] = {wiX, wiY, wiZ};
        float* wA[3] = {wr, wg, wb};
        EXPECT(facet_sample_batch(simd, 3, woA, uA, NULL, wiA, p, wA) == 2, "two invalid lanes");
        EXPECT(p[0] == pdf[0] && p[1] == 0 && p[2] == 0 && wiZ[1] == 0 && wr[2] == 0, "invalid lanes zeroed");
        EXPECT(facet_sample_batch(simd, 3, woA, NULL, NULL, wiA, p, wA) == -1, "NULL u accepted");
        EXPECT(strcmp(facet_last_error(), "facet_sample_batch: error: u is NULL") == 0, "message: %s",
               facet_last_error());
        /* wi of the invalid lanes is 0, not unit: both lanes are invalid for pdf. */
        EXPECT(facet_pdf_batch(simd, 3, (const float* const*)wiA, woA, NULL, p) == 2, "pdf batch: two invalid lanes");
        EXPECT(fabsf(p[0] - pdf[0]) <= 1e-5f * pdf[0] && p[1] == 0 && p[2] == 0, "pdf batch values");
    }

    facet_release(simd);
    facet_release(scalar);
    facet_release(interp);
    facet_release(NULL);
    printf("capi_test: %d failures\n", failures);
    return failures ? 1 : 0;
}
