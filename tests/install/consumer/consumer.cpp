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
        // One importance sample, and its density through pdf().
        float wo[3] = {0.6f, 0, 0.8f}, u[3] = {0.25f, 0.5f, 0.75f};
        facet::api::Sample s = kernel.sample(wo, u, nullptr);
        float back = kernel.pdf(s.wi, wo, nullptr);
        if (!s.valid || !(s.pdf > 0) || !(back > 0.99f * s.pdf && back < 1.01f * s.pdf)) {
            std::fprintf(stderr, "sample: valid %d pdf %g pdf(wi) %g\n", int(s.valid), s.pdf, back);
            return 1;
        }
        float bad[3] = {1, 0, 0};  // u0 = 1: an invalid lane
        if (kernel.sample(wo, bad, nullptr).valid) {
            std::fputs("u = 1 was accepted\n", stderr);
            return 1;
        }
        return rgb[0] > 0 ? 0 : 1;
    } catch (const facet::api::Error& e) {
        std::fputs(e.what(), stderr);
        return 1;
    }
}
