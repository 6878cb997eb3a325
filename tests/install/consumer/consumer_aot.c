/* consumer_aot.c: a program that ships a material without the JIT. The
   object and test_material.h come from facet_add_material(); nothing of
   Facet is linked. Prints f_r at normal incidence (defaults), and checks the
   sampler's functions: for GGX with wi = wo = n, pdf = D(n) / 4 =
   1 / (4 pi alpha^2), the same value as f_r there (F = 1, G = 1), and a
   sample's pdf is the pdf of the direction it drew. */
#include "test_material.h"

#include <math.h>
#include <stdio.h>

int main(void) {
    float n[3] = {0, 0, 1}, rgb[3], wo[3] = {0.6f, 0, 0.8f}, u[3] = {0.25f, 0.5f, 0.75f}, wi[3], pdf, weight[3];
    float atNormal, back;
    test_material_eval(n, n, NULL, rgb);
    printf("%.9g\n", rgb[0]);
#if !test_material_HAS_SAMPLER
    fputs("test_material.h says the object has no sampler\n", stderr);
    return 1;
#else
    atNormal = test_material_pdf(n, n, NULL);
    if (!(fabsf(atNormal - rgb[0]) <= 1e-5f * rgb[0])) {
        fprintf(stderr, "pdf(n, n) = %.9g, expected %.9g\n", atNormal, rgb[0]);
        return 1;
    }
    if (test_material_sample(wo, u, NULL, wi, &pdf, weight) != 0 || !(pdf > 0)) {
        fprintf(stderr, "sample: invalid, or pdf %g\n", pdf);
        return 1;
    }
    back = test_material_pdf(wi, wo, NULL);
    if (!(back > 0.99f * pdf && back < 1.01f * pdf)) {
        fprintf(stderr, "sample: pdf %g, pdf(wi) %g\n", pdf, back);
        return 1;
    }
    return 0;
#endif
}
