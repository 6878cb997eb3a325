// CApi: the C API of facet.h over the C++ Compiler/Kernel classes.
//
// The C API has no compiler object in its signatures, so it keeps one
// Compiler (one JIT, one kernel cache) per process, created on first use.
// The C++ API has no such hidden state: C++ hosts create their own.
#include "facet/facet.h"

#include "Kernel.h"

#include <cstring>
#include <mutex>
#include <new>

struct facet_kernel {
    std::unique_ptr<facet::Kernel> kernel;
};

namespace {

facet::Compiler& sharedCompiler() {
    static facet::Compiler compiler;  // thread-safe initialization
    return compiler;
}

void writeError(char* err, size_t len, const std::string& message) {
    if (!err || len == 0) return;
    size_t n = std::min(len - 1, message.size());
    std::memcpy(err, message.data(), n);
    err[n] = '\0';
}

template <typename CompileFn>
facet_kernel* compileWith(const char* options, char* err, size_t errLen, CompileFn compile) {
    try {
        facet::CompileOptions opts;
        std::string problem = facet::CompileOptions::parse(options ? options : "", opts);
        if (!problem.empty()) {
            writeError(err, errLen, "options: error: " + problem);
            return nullptr;
        }
        facet::DiagnosticEngine diags;
        std::unique_ptr<facet::Kernel> kernel = compile(opts, diags);
        if (!kernel) {
            std::string text = diags.str();
            if (!text.empty() && text.back() == '\n') text.pop_back();
            writeError(err, errLen, text);
            return nullptr;
        }
        writeError(err, errLen, "");
        return new facet_kernel{std::move(kernel)};
    } catch (const std::exception& e) {
        writeError(err, errLen, std::string("facet: error: ") + e.what());
        return nullptr;
    }
}

}  // namespace

extern "C" {

facet_kernel* facet_compile_file(const char* path, const char* material, const char* options, char* err,
                                 size_t err_len) {
    if (!path) {
        writeError(err, err_len, "facet_compile_file: error: path is NULL");
        return nullptr;
    }
    return compileWith(options, err, err_len, [&](const facet::CompileOptions& o, facet::DiagnosticEngine& d) {
        return sharedCompiler().compileFile(path, material ? material : "", o, d);
    });
}

facet_kernel* facet_compile_text(const char* text, const char* name, const char* material, const char* options,
                                 char* err, size_t err_len) {
    if (!text) {
        writeError(err, err_len, "facet_compile_text: error: text is NULL");
        return nullptr;
    }
    return compileWith(options, err, err_len, [&](const facet::CompileOptions& o, facet::DiagnosticEngine& d) {
        return sharedCompiler().compileText(text, name ? name : "<text>", material ? material : "", o, d);
    });
}

int facet_input_count(const facet_kernel* k) { return k ? k->kernel->inputCount() : 0; }

const char* facet_input_name(const facet_kernel* k, int slot) {
    if (!k || slot < 0 || slot >= k->kernel->inputCount()) return nullptr;
    return k->kernel->inputName(slot).c_str();
}

void facet_eval(const facet_kernel* k, const float wi[3], const float wo[3], const float* inputs, float rgb[3]) {
    if (!k || !wi || !wo || !rgb) {
        if (rgb) rgb[0] = rgb[1] = rgb[2] = 0.0f;
        return;
    }
    k->kernel->eval(wi, wo, inputs, rgb);
}

int64_t facet_eval_batch(const facet_kernel* k, int64_t n, const float* const wi[3], const float* const wo[3],
                         const float* const* inputs, float* const rgb[3]) {
    if (!k || n <= 0 || !wi || !wo || !rgb) return 0;
    return k->kernel->evalBatch(n, wi, wo, inputs, rgb);
}

void facet_release(facet_kernel* k) { delete k; }

}  // extern "C"
