/* consumer.c: links the installed libfacet.so through find_package(Facet). */
#include <facet/facet.h>
#include <stdio.h>

int main(int argc, char** argv) {
    char err[256];
    facet_kernel* k = facet_compile_file(argc > 1 ? argv[1] : "m.mat", NULL, "cache=off", err, sizeof err);
    if (!k) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    float n[3] = {0, 0, 1}, rgb[3];
    facet_eval(k, n, n, NULL, rgb);
    printf("%.6f\n", rgb[0]);
    facet_release(k);
    return rgb[0] > 0 ? 0 : 1;
}
