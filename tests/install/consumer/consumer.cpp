// consumer.cpp: uses the installed C++ API (facet/facet.hpp over Facet::facet).
#include <facet/facet.hpp>

#include <cstdio>

int main(int argc, char** argv) {
    try {
        facet::api::Kernel kernel =
            facet::api::Kernel::compileFile(argc > 1 ? argv[1] : "m.mat", "backend=scalar;cache=off");
        float n[3] = {0, 0, 1}, rgb[3];
        kernel.eval(n, n, nullptr, rgb);
        std::printf("%.6f\n", rgb[0]);
        // A batch with a NULL direction array is the caller's error: it throws.
        const float* none[3] = {nullptr, nullptr, nullptr};
        float* out[3] = {rgb, rgb + 1, rgb + 2};
        try {
            kernel.evalBatch(1, none, none, nullptr, out);
            std::fputs("a NULL batch array was accepted\n", stderr);
            return 1;
        } catch (const facet::api::Error&) {
        }
        return rgb[0] > 0 ? 0 : 1;
    } catch (const facet::api::Error& e) {
        std::fputs(e.what(), stderr);
        return 1;
    }
}
