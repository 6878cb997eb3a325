/* consumer_aot.c: a program that ships a material without the JIT. The
   object and test_material.h come from facet_add_material(); nothing of
   Facet is linked. Prints f_r at normal incidence (defaults). */
#include "test_material.h"

#include <stdio.h>

int main(void) {
    float n[3] = {0, 0, 1}, rgb[3];
    test_material_eval(n, n, NULL, rgb);
    printf("%.9g\n", rgb[0]);
    return 0;
}
