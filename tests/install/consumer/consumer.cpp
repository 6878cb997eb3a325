// consumer.cpp: uses the installed C++ API (Facet::facet_runtime).
#include <Kernel.h>  // from <prefix>/include/facet/cxx

#include <cstdio>

int main(int argc, char** argv) {
    facet::Compiler compiler;
    facet::CompileOptions options;
    options.backend = facet::Backend::Scalar;
    options.cache = facet::CompileOptions::Cache::Off;
    facet::DiagnosticEngine diags;
    auto kernel = compiler.compileFile(argc > 1 ? argv[1] : "m.mat", "", options, diags);
    if (!kernel) {
        std::fputs(diags.str().c_str(), stderr);
        return 1;
    }
    float n[3] = {0, 0, 1}, rgb[3];
    kernel->eval(n, n, nullptr, rgb);
    std::printf("%.6f\n", rgb[0]);
    return rgb[0] > 0 ? 0 : 1;
}
