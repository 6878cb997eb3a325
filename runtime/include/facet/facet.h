/* facet.h: the C API of Facet (libfacet.so), for C, Rust or Python hosts.
 *
 * Compile a material once, then evaluate its BRDF (1/sr, rgb, without the
 * cosine factor) per direction pair or in SoA batches. Kernels are immutable
 * and may be evaluated from many threads at once. All kernels share one
 * compiler (one JIT and one kernel cache) per process, created on first use.
 */
#ifndef FACET_FACET_H
#define FACET_FACET_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct facet_kernel facet_kernel;

/* options: "key=value" pairs separated by ';' -- backend=scalar|simd|interp,
   math=exact|fast, tolerance=1e-4, width=4|8|16, set.NAME=VALUE (rgb:
   set.NAME=r,g,b), cache=on|off|memory, float_first=on|off (exact SIMD:
   float where the lane is well-conditioned, double elsewhere; default on),
   codegen=tiered|quick|optimized (default tiered: the kernel returned runs
   quickly emitted code, and a background thread of the library swaps in
   the optimized code, which computes the same values, about 5-15 ms
   later; optimized: compile returns only once that code is linked; fork()
   waits for a tier-up that is running, and in the child the kernels whose
   tier-up had not run keep their quick code),
   assume=unit|none (unit: the host promises finite directions with |w|
   within 1e-3 of 1, finite inputs and u in [0, 1);
   compiled kernels then skip the work that only detects invalid lanes,
   give the default's bits on such inputs, return 0 from the batch calls
   and report every lane valid; other inputs give undefined values, never a
   crash. default none).
   NULL or "" = defaults (simd, exact,
   the host's width). NULL material = the first in the file. On failure
   returns NULL and writes the diagnostic ("file:line:col: error: ...") into
   err (truncated to err_len, always NUL-terminated when err_len > 0). */
facet_kernel* facet_compile_file(const char* path, const char* material, const char* options, char* err,
                                 size_t err_len);
/* The same from material source text; `name` is used in diagnostics. */
facet_kernel* facet_compile_text(const char* text, const char* name, const char* material, const char* options,
                                 char* err, size_t err_len);

/* Float input slots (an rgb input takes 3: "tint.r", "tint.g", "tint.b").
   Inputs bound with set.NAME are not slots. */
int facet_input_count(const facet_kernel* k);
/* NULL when slot is out of range. The string lives as long as the kernel. */
const char* facet_input_name(const facet_kernel* k, int slot);

/* inputs holds one value per slot, or is NULL (all defaults). */
void facet_eval(const facet_kernel* k, const float wi[3], const float wo[3], const float* inputs, float rgb[3]);

/* SoA: wi[0..2], wo[0..2], rgb[0..2] each point to n floats; inputs is NULL
   (all defaults) or inputs[s] points to n floats (or is NULL: that slot's
   default). Inputs are clamped to their declared ranges in the kernel; a
   caller holding a value beyond float (say 1e39 for an input in 0 .. 1)
   clamps it in double before converting it to float.
   Returns the number of invalid lanes (non-finite or non-unit directions,
   non-finite inputs the material reads, a model parameter not finite in
   float, or a result float cannot hold); their rgb is 0, on every backend
   alike. An input the material never reads is never loaded: its value,
   finite or not, changes nothing.
   Returns -1 -- never a lane count -- for a NULL kernel, n < 0, or a NULL
   wi, wo or rgb (or a NULL entry of one); facet_last_error() then says
   which. n = 0 returns 0 (the pointers are not read). */
int64_t facet_eval_batch(const facet_kernel* k, int64_t n, const float* const wi[3], const float* const wo[3],
                         const float* const* inputs, float* const rgb[3]);
/* facet_eval_batch, and status[i] (status points to n bytes) set to 1 for
   each invalid lane and 0 for each valid one. status may be NULL. */
int64_t facet_eval_batch_status(const facet_kernel* k, int64_t n, const float* const wi[3],
                                const float* const wo[3], const float* const* inputs, float* const rgb[3],
                                uint8_t* status);
/* Importance sampling (one sample of a one-sample mixture of the specular
   lobe and, where the material has a diffuse base or energy compensation, a
   cosine lobe). Conventions as eval: n = +z, wo and wi point away from the
   surface, inputs as facet_eval / facet_eval_batch.
   u holds three uniform numbers in [0, 1): u[0] picks the lobe, u[1] and
   u[2] place the direction. Outputs: wi (unit), pdf = the whole mixture's
   density of wi per solid angle (what multiple importance sampling needs),
   weight = f(wi, wo) (n.wi) / pdf per channel.
   - n.wo <= 0: no sample (wi = 0, pdf = 0, weight = 0), a valid lane.
   - a sample below the horizon (n.wi <= 0) is valid: weight 0, its pdf
     reported (the density over the whole sphere integrates to 1).
   - a density below float's range (the far tail of a narrow lobe) is
     pdf = 0, and then weight = 0: no sample a renderer would divide by 0.
   - pdf is the density of the direction drawn; facet_pdf of the returned
     wi (rounded to float) agrees with it within the math mode's bound
     (1e-5 exact, 2e-3 fast), except where the half vector of wi and wo is
     ill-conditioned (wi nearly -wo: grazing wo with a narrow lobe, a
     normal near the horizon), where it differs by as much as the exact
     density moves under the rounding of wi to float.
   - invalid lanes (a non-finite or non-unit wo, u outside [0, 1) or NaN, a
     non-finite input, a result float cannot hold): wi = 0, pdf = 0,
     weight = 0, counted in the return value.
   - a material with energy = random_walk (docs/models.md): u seeds a walk
     on the microsurface; weight = f (n.wi) / p for the walk's own density
     p, which has no closed form, and pdf is a density for MIS only; its
     eval is a Monte Carlo estimate seeded by the directions.
   - a lobe that scatters below the surface (scatter = transmit | both,
     thin = true; backend=interp only so far): wo and wi may lie on either
     side (the inside is -z); wi is a reflection on wo's side or a
     refraction across, weight = f |n.wi| / pdf; a draw that leaves no
     direction (a reflection past the horizon, no refraction past the
     critical angle with scatter = transmit) is no sample (wi = 0, pdf = 0,
     weight = 0, a valid lane). eval follows the transport option
     (radiance: f carries 1/eta^2 of the transmitted radiance).
   facet_sample returns 1 for an invalid lane, else 0 (NULL k, wo or u count
   as invalid; NULL outputs are not written). */
int facet_sample(const facet_kernel* k, const float wo[3], const float u[3], const float* inputs, float wi_out[3],
                 float* pdf_out, float weight_out[3]);
/* The density facet_sample draws wi with, for any unit wi and wo; 0 for an
   invalid lane (or a NULL k, wi or wo). */
float facet_pdf(const facet_kernel* k, const float wi[3], const float wo[3], const float* inputs);
/* SoA: wo[0..2], u[0..2], wi[0..2], weight[0..2] each point to n floats, pdf
   to n floats; inputs as facet_eval_batch. Returns the number of invalid
   lanes, or -1 (facet_last_error() says why) for a NULL kernel, n < 0, or a
   NULL wo, u, wi, pdf or weight (or a NULL entry of one); n = 0 returns 0. */
int64_t facet_sample_batch(const facet_kernel* k, int64_t n, const float* const wo[3], const float* const u[3],
                           const float* const* inputs, float* const wi[3], float* pdf, float* const weight[3]);
/* pdf[i] = facet_pdf of lane i; the return value as facet_sample_batch. */
int64_t facet_pdf_batch(const facet_kernel* k, int64_t n, const float* const wi[3], const float* const wo[3],
                        const float* const* inputs, float* pdf);
/* Which code samples: "jit" (the kernel's own compiled sampler, scalar or
   SIMD as its eval), or "reference" (the interpreter's sampler in double,
   one lane at a time: backend=interp, or a compiled sampler that failed,
   see facet_sampler_error); "" for a NULL kernel. A kernel gets its sampler on the first call of any
   sampling function (this one included), once, thread-safely: from the
   kernel caches (memory and disk, as its eval code, option cache=), else
   compiled and stored there. Objects of `facet build` carry the same
   sampler as PREFIX_sample / PREFIX_sample_batch / PREFIX_pdf /
   PREFIX_pdf_batch, where their header says PREFIX_HAS_SAMPLER 1. */
const char* facet_sampler(const facet_kernel* k);

/* Why a JIT kernel samples through the reference: its compiled sampler did
   not compile, link or resolve (e.g. "the sampler from the disk cache
   failed: looking up ..."); "" when it did, for an interp kernel and for a
   NULL kernel. Gets the sampler first, as facet_sampler. Valid while the
   kernel lives. */
const char* facet_sampler_error(const facet_kernel* k);

/* The message of the last batch call that returned -1 in this thread
   ("facet_eval_batch: error: wi[2] is NULL"); "" before any. Valid until
   the next failing call in this thread. */
const char* facet_last_error(void);

void facet_release(facet_kernel* k);

#ifdef __cplusplus
}
#endif

#endif /* FACET_FACET_H */
