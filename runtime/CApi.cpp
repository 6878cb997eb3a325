// CApi: the C API of facet.h over the C++ Compiler/Kernel classes.
//
// The C API has no compiler object in its signatures, so it keeps one
// Compiler (one JIT, one kernel cache) per process, created on first use.
// The C++ API has no such hidden state: C++ hosts create their own.
#include "facet/facet.h"

#include "Kernel.h"

#include <cstring>
#include <string>
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

// The message of the last failed batch call in this thread (facet_last_error).
std::string& lastError() {
    thread_local std::string message;
    return message;
}

[[gnu::noinline, gnu::cold]] int64_t callError(const char* fn, const std::string& what) {
    lastError() = std::string(fn) + ": error: " + what;
    return -1;
}

// Whether a required array and its three entries are all there: plain pointer
// tests, inlined into every batch call.
template <typename T>
inline bool complete(T* const* array) {
    return array && array[0] && array[1] && array[2];
}

// Which part of an incomplete array is missing: the pointer array itself or
// one of its three entries. Only the failing call pays for the text (and for
// the thread-local string behind facet_last_error).
template <typename T>
[[gnu::noinline, gnu::cold]] int64_t missingArray(const char* fn, T* const* array, const char* name) {
    if (!array) return callError(fn, std::string(name) + " is NULL");
    return callError(fn, std::string(name) + "[" + std::to_string(!array[0] ? 0 : !array[1] ? 1 : 2) + "] is NULL");
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
    return facet_eval_batch_status(k, n, wi, wo, inputs, rgb, nullptr);
}

int64_t facet_eval_batch_status(const facet_kernel* k, int64_t n, const float* const wi[3],
                                const float* const wo[3], const float* const* inputs, float* const rgb[3],
                                uint8_t* status) {
    const char* fn = status ? "facet_eval_batch_status" : "facet_eval_batch";
    if (!k) return callError(fn, "the kernel is NULL");
    if (n < 0) return callError(fn, "n is negative (" + std::to_string(n) + ")");
    if (n == 0) return 0;
    if (!complete(wi)) return missingArray(fn, wi, "wi");
    if (!complete(wo)) return missingArray(fn, wo, "wo");
    if (!complete(rgb)) return missingArray(fn, rgb, "rgb");
    return k->kernel->evalBatch(n, wi, wo, inputs, rgb, status);
}

int facet_sample(const facet_kernel* k, const float wo[3], const float u[3], const float* inputs, float wi_out[3],
                 float* pdf_out, float weight_out[3]) {
    float wi[3] = {0, 0, 0}, pdf = 0, weight[3] = {0, 0, 0};
    bool valid = k && wo && u && k->kernel->sample(wo, u, inputs, wi, &pdf, weight);
    if (wi_out) wi_out[0] = wi[0], wi_out[1] = wi[1], wi_out[2] = wi[2];
    if (pdf_out) *pdf_out = pdf;
    if (weight_out) weight_out[0] = weight[0], weight_out[1] = weight[1], weight_out[2] = weight[2];
    return valid ? 0 : 1;
}

float facet_pdf(const facet_kernel* k, const float wi[3], const float wo[3], const float* inputs) {
    if (!k || !wi || !wo) return 0.0f;
    return k->kernel->pdf(wi, wo, inputs);
}

int64_t facet_sample_batch(const facet_kernel* k, int64_t n, const float* const wo[3], const float* const u[3],
                           const float* const* inputs, float* const wi[3], float* pdf, float* const weight[3]) {
    const char* fn = "facet_sample_batch";
    if (!k) return callError(fn, "the kernel is NULL");
    if (n < 0) return callError(fn, "n is negative (" + std::to_string(n) + ")");
    if (n == 0) return 0;
    if (!complete(wo)) return missingArray(fn, wo, "wo");
    if (!complete(u)) return missingArray(fn, u, "u");
    if (!complete(wi)) return missingArray(fn, wi, "wi");
    if (!pdf) return callError(fn, "pdf is NULL");
    if (!complete(weight)) return missingArray(fn, weight, "weight");
    return k->kernel->sampleBatch(n, wo, u, inputs, wi, pdf, weight);
}

int64_t facet_pdf_batch(const facet_kernel* k, int64_t n, const float* const wi[3], const float* const wo[3],
                        const float* const* inputs, float* pdf) {
    const char* fn = "facet_pdf_batch";
    if (!k) return callError(fn, "the kernel is NULL");
    if (n < 0) return callError(fn, "n is negative (" + std::to_string(n) + ")");
    if (n == 0) return 0;
    if (!complete(wi)) return missingArray(fn, wi, "wi");
    if (!complete(wo)) return missingArray(fn, wo, "wo");
    if (!pdf) return callError(fn, "pdf is NULL");
    return k->kernel->pdfBatch(n, wi, wo, inputs, pdf);
}

const char* facet_sampler(const facet_kernel* k) {
    static const char* const names[] = {"jit", "reference"};
    if (!k) return "";
    return k->kernel->samplerTier() == "jit" ? names[0] : names[1];
}

const char* facet_sampler_error(const facet_kernel* k) { return k ? k->kernel->samplerError().c_str() : ""; }

const char* facet_last_error(void) { return lastError().c_str(); }

void facet_release(facet_kernel* k) { delete k; }

}  // extern "C"
