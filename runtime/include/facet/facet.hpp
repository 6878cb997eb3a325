// facet.hpp: the C++ API of Facet -- ownership and exceptions over the C API
// (facet.h), header-only, with no header of LLVM or of Facet's internals.
//
//   facet::api::Kernel k = facet::api::Kernel::compileFile("gold.mat", "math=fast");
//   k.eval(wi, wo, nullptr, rgb);
//   int64_t invalid = k.evalBatch(n, wi3, wo3, nullptr, rgb3);
//   facet::api::Sample s = k.sample(wo, u, nullptr);   // s.wi, s.pdf, s.weight
//
// Link with libfacet (find_package(Facet): Facet::facet). Kernels are
// immutable and may be evaluated from many threads at once; a Kernel owns
// its compiled code and releases it when destroyed. Errors (a material file
// that does not compile, a NULL array in a batch) throw facet::api::Error
// with Facet's diagnostic ("file:line:col: error: ...").
#ifndef FACET_FACET_HPP
#define FACET_FACET_HPP

#include "facet.h"

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

namespace facet::api {

class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// One importance sample (facet_sample): wi, the mixture's pdf at wi, and
// weight = f (n.wi) / pdf; all 0 when `valid` is false (an invalid lane),
// and also for a valid lane without a sample (n.wo <= 0).
struct Sample {
    float wi[3] = {0, 0, 0};
    float pdf = 0;
    float weight[3] = {0, 0, 0};
    bool valid = false;
};

class Kernel {
public:
    // Compiles material `material` ("" = the first) of a file or of source
    // text; `options` as for facet_compile_file ("" = defaults).
    static Kernel compileFile(const std::string& path, const std::string& options = "",
                              const std::string& material = "") {
        char err[2048];
        facet_kernel* k = facet_compile_file(path.c_str(), material.empty() ? nullptr : material.c_str(),
                                             options.c_str(), err, sizeof err);
        if (!k) throw Error(err);
        return Kernel(k);
    }
    static Kernel compileText(const std::string& text, const std::string& name, const std::string& options = "",
                              const std::string& material = "") {
        char err[2048];
        facet_kernel* k = facet_compile_text(text.c_str(), name.c_str(), material.empty() ? nullptr : material.c_str(),
                                             options.c_str(), err, sizeof err);
        if (!k) throw Error(err);
        return Kernel(k);
    }

    // The float input slots (an rgb input takes three: "tint.r", ...).
    int inputCount() const { return facet_input_count(k_.get()); }
    std::string inputName(int slot) const {
        const char* name = facet_input_name(k_.get(), slot);
        if (!name) throw Error("facet::api::Kernel::inputName: slot " + std::to_string(slot) + " out of range");
        return name;
    }

    // One direction pair; `inputs` holds one value per slot or is null
    // (defaults). An invalid lane gives rgb = 0.
    void eval(const float wi[3], const float wo[3], const float* inputs, float rgb[3]) const {
        facet_eval(k_.get(), wi, wo, inputs, rgb);
    }
    // n lanes in SoA (facet.h); returns the number of invalid lanes, and
    // their flags in `status` (n bytes) when it is not null.
    int64_t evalBatch(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                      float* const rgb[3], uint8_t* status = nullptr) const {
        int64_t invalid = facet_eval_batch_status(k_.get(), n, wi, wo, inputs, rgb, status);
        if (invalid < 0) throw Error(facet_last_error());
        return invalid;
    }

    // Importance sampling, with the conventions of facet_sample (facet.h):
    // u holds three uniform numbers in [0, 1).
    Sample sample(const float wo[3], const float u[3], const float* inputs) const {
        Sample s;
        s.valid = facet_sample(k_.get(), wo, u, inputs, s.wi, &s.pdf, s.weight) == 0;
        return s;
    }
    // The density sample() draws wi with; 0 for an invalid lane.
    float pdf(const float wi[3], const float wo[3], const float* inputs) const {
        return facet_pdf(k_.get(), wi, wo, inputs);
    }
    // n lanes in SoA (facet_sample_batch, facet_pdf_batch); return the number
    // of invalid lanes.
    int64_t sampleBatch(int64_t n, const float* const wo[3], const float* const u[3], const float* const* inputs,
                        float* const wi[3], float* pdf, float* const weight[3]) const {
        int64_t invalid = facet_sample_batch(k_.get(), n, wo, u, inputs, wi, pdf, weight);
        if (invalid < 0) throw Error(facet_last_error());
        return invalid;
    }
    int64_t pdfBatch(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                     float* pdf) const {
        int64_t invalid = facet_pdf_batch(k_.get(), n, wi, wo, inputs, pdf);
        if (invalid < 0) throw Error(facet_last_error());
        return invalid;
    }
    // "jit" or "reference" (facet_sampler).
    std::string sampler() const { return facet_sampler(k_.get()); }
    // Why a JIT kernel samples through the reference, or "" (facet_sampler_error).
    std::string samplerError() const { return facet_sampler_error(k_.get()); }

    facet_kernel* get() const { return k_.get(); }  // for the C API

private:
    struct Release {
        void operator()(facet_kernel* k) const { facet_release(k); }
    };
    explicit Kernel(facet_kernel* k) : k_(k) {}
    std::unique_ptr<facet_kernel, Release> k_;
};

}  // namespace facet::api

#endif  // FACET_FACET_HPP
