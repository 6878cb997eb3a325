// facet verify FILE... : hard cases, backend agreement and physics (SPEC section 7).
//
// Per material:
//   1. the hard-case sample (compiler/hardcases/HardCases.h) on the double interpreter
//      and on the JIT kernels (scalar and SIMD at the host width, math exact
//      and fast): every output finite and >= 0, invalid inputs give 0 and are
//      counted (the batch return value), JIT against the interpreter within
//      the stated bound (apps/verify/Verify.h) on valid finite lanes;
//   2. the double interpreter against the __float128 one on the same
//      sample: within 1e-12 relative, or within 16 kappa u where the input is
//      ill-conditioned (kappa: condition number estimated in __float128);
//   3. the physics checks by quadrature (apps/verify/PhysicsChecks.h);
//   4. each lobe the random walk supports against its stochastic reference
//      (compiler/reference/WalkComparison.h), at the default inputs:
//      directional albedo and BRDF-shaped error of the single-scattering
//      lobe and of the lobe with its energy compensation; and a layer of two
//      lobes against the layered walk. A report, not a check: only a walk
//      that is abandoned fails it.
// Prints one table per material and the worst cases with their inputs.
// Exit: 0 all passed, 1 a check failed, 2 usage, 65 a material file error.
#include "Commands.h"

#include "Checker.h"
#include "HardCases.h"
#include "Interpreter.h"
#include "Kernel.h"
#include "MaterialFile.h"
#include "PhysicsChecks.h"
#include "Verify.h"
#include "WalkComparison.h"
#include "WholeSphereChecks.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <map>
#include <stdexcept>

namespace facet {

namespace {

constexpr double kQuadTolerance = 1e-12;
constexpr double kConditionFactor = 16;  // allowed error: 16 kappa u
constexpr double kUnitRoundoff = 0x1p-53;

struct VerifyOptions {
    std::vector<std::string> files;
    std::string material;
    bool verbose = false;
    bool physics = true, jit = true, quad = true, walk = true;
};

const char* kVerifyUsage =
    "usage: facet verify FILE... [--material NAME] [--verbose] [--no-physics] [--no-jit] [--no-quad] [--no-walk]\n";

std::string shortCase(const CheckedMaterial& m, const HardCase& c) { return describeCase(m, c); }

// The furnace table per alpha and side, and the checks (WholeSphereChecks.h).
bool printWholeSphereChecks(const CheckedMaterial& m, const Interpreter<double>& interp) {
    WholeSphereReport report = wholeSphereChecks(m, interp);
    std::printf("  white furnace, R + T over the sphere (importance transport), theta_o in {0, 30, 60, 80, 89}:\n");
    std::printf("    %5s %7s %-8s %-20s %-20s\n", "alpha", "eta", "wo", "single scattering", "compensated");
    for (const FurnaceRow& r : report.furnace) {
        std::string comp = r.compensated ? fmt::format("{:.4f} .. {:.4f}", r.compensatedMin, r.compensatedMax) : "-";
        std::printf("    %5.2f %7.4g %-8s %-20s %-20s\n", r.alpha, r.eta, r.inside ? "inside" : "outside",
                    fmt::format("{:.4f} .. {:.4f}", r.plainMin, r.plainMax).c_str(), comp.c_str());
    }
    if (!report.compensationNote.empty()) std::printf("    (no compensated column: %s)\n", report.compensationNote.c_str());
    bool ok = true;
    std::map<std::string, const PhysicsCheck*> worst;
    for (const PhysicsCheck& c : report.checks) {
        const PhysicsCheck*& w = worst[c.name];
        if (!w || c.error > w->error || (c.failed() && !w->failed())) w = &c;
        ok &= !c.failed();
    }
    for (const auto& [name, c] : worst)
        std::printf("    %-26s worst error %.3g (tol %.0e)  %-4s %s\n", name.c_str(), c->error, c->tolerance,
                    c->failed() ? "FAIL" : "ok", c->where.c_str());
    return ok;
}

void printSample(const SampleStats& s, const CheckedMaterial& m, const std::vector<HardCase>& cases, bool verbose) {
    std::string err = s.bound > 0 ? fmt::format("{:.3g}", s.maxRel) : "-";
    std::string bound = s.bound > 0 ? fmt::format("{:.0e}", s.bound) : "-";
    std::printf("    %-14s %7zu %7zu %5zu %5zu %5zu %11s %7s  %s\n", s.backend.c_str(), s.invalid, s.expectedInvalid,
                s.nan, s.inf, s.negative, err.c_str(), bound.c_str(),
                !s.ok() ? "FAIL" : s.accurate() ? "ok" : "ok (safe; accuracy info only in fast mode)");
    if (s.bound > 0 && s.worstCase < cases.size() && (verbose || !s.ok()))
        std::printf("        worst: ch %d got %.9g want %.17g at %s\n", s.worstChannel, s.worstGot, s.worstWant,
                    shortCase(m, cases[s.worstCase]).c_str());
    if (s.illConditioned)
        std::printf("        %zu values beyond the bound at ill-conditioned inputs (within %g kappa u, max kappa %.3g)\n",
                    s.illConditioned, kConditionAllowance, s.maxKappa);
    if (!s.ok() || !s.accurate()) {
        std::printf("        %s\n", s.summary().c_str());
        // The first few failures of each kind (the reason up to its first ':' or number).
        std::map<std::string, int> shown;
        for (const auto& [i, why] : s.failures) {
            std::string kind = why.substr(0, why.find_first_of(":0123456789"));
            if (shown[kind]++ >= (verbose ? 8 : 3)) continue;
            std::printf("        %s: %s\n", why.c_str(), shortCase(m, cases[i]).c_str());
        }
    }
}

// Returns true if everything passed.
double channelMean(const std::array<double, 3>& v) { return (v[0] + v[1] + v[2]) / 3; }

// Section 4: one table per lobe the walk supports, at the default inputs.
// The albedos are the channels' mean.
bool printWalkComparison(const CheckedMaterial& m, const Interpreter<double>& interp) {
    ResolvedBsdf<double> r = interp.resolveAll(nullptr);
    if (!r.valid) return true;
    bool ok = true;
    for (size_t i = 0; i < r.lobes.size(); ++i) {
        const ResolvedMaterial<double>& lobe = r.lobes[i];
        std::string why = MicrosurfaceWalk::unsupported(lobe);
        std::string name = m.combinesLobes() ? fmt::format(" '{}'", m.lobes[i].name) : "";
        if (!why.empty()) {
            if (lobe.ndf) std::printf("  multiple scattering of lobe%s: no random walk (%s)\n", name.c_str(), why.c_str());
            continue;
        }
        bool compensated = lobe.energy->compensates;
        std::printf("  multiple scattering of lobe%s against the random walk on its microsurface (default inputs; "
                    "albedo: rgb mean; shape: relative RMS of f over n.wi-weighted cells):\n",
                    name.c_str());
        std::printf("    %7s %9s %9s %17s %10s %10s %8s\n", "theta_o", "single", compensated ? "+ms model" : "-",
                    "walk +- se", "shape 1x", compensated ? "shape +ms" : "-", "noise");
        for (const WalkComparisonRow& row : compareWithWalk(lobe)) {
            std::string model = compensated ? fmt::format("{:.4f}", channelMean(row.modelAlbedo)) : "-";
            std::string modelShape = compensated ? fmt::format("{:.4f}", row.modelShapeError) : "-";
            std::printf("    %7.0f %9.4f %9s %9.4f +- %.4f %10.4f %10s %8.4f\n", row.thetaO, channelMean(row.singleAlbedo),
                        model.c_str(), channelMean(row.walkAlbedo), channelMean(row.walkAlbedoError),
                        row.singleShapeError, modelShape.c_str(), row.shapeNoise);
            if (row.abandoned > 0) {
                std::printf("    FAIL: %lld walks abandoned at theta_o = %g\n", (long long)row.abandoned, row.thetaO);
                ok = false;
            }
        }
    }
    if (m.combinesLobes() && m.bsdfRoot().kind == BsdfKind::Layer) {
        std::string why = layerWalkUnsupported(m, r);
        if (!why.empty()) {
            std::printf("  layer: no layered walk (%s)\n", why.c_str());
            return ok;
        }
        std::printf("  %s against the layered random walk (its top a rough dielectric interface over its base; "
                    "default inputs):\n",
                    printBsdf(m, m.bsdfRoot()).c_str());
        std::printf("    %7s %9s %17s %10s %8s\n", "theta_o", "layer", "walk +- se", "shape", "noise");
        for (const WalkComparisonRow& row : compareLayerWithWalk(interp, r)) {
            std::printf("    %7.0f %9.4f %9.4f +- %.4f %10.4f %8.4f\n", row.thetaO, channelMean(row.modelAlbedo),
                        channelMean(row.walkAlbedo), channelMean(row.walkAlbedoError), row.modelShapeError,
                        row.shapeNoise);
            if (row.abandoned > 0) {
                std::printf("    FAIL: %lld walks abandoned at theta_o = %g\n", (long long)row.abandoned, row.thetaO);
                ok = false;
            }
        }
    }
    return ok;
}

bool verifyMaterial(const CheckedMaterial& m, const std::string& path, Compiler& compiler, const VerifyOptions& opt) {
    auto start = std::chrono::steady_clock::now();
    bool ok = true;
    // energy and diffuse only where the material has one.
    std::string optional;
    if (m.combinesLobes()) {
        std::printf("material %s (%s): %s\n", m.name.c_str(), path.c_str(), printBsdf(m, m.bsdfRoot()).c_str());
    } else {
        const CheckedLobe& lobe = m.singleLobe();
        for (const ModelUse* use : {&lobe.energy, &lobe.diffuse})
            if (std::string_view(use->model->name) != "none")
                optional += fmt::format(", {} {}", modelSlotName(use->model->slot), use->model->name);
        std::printf("material %s (%s): ndf %s, masking %s, fresnel %s%s\n", m.name.c_str(), path.c_str(),
                    lobe.hasNdf() ? lobe.ndf.model->name : "none", lobe.masking.model->name,
                    lobe.fresnel.model->name, optional.c_str());
    }

    // ---- 1. hard cases on the interpreter and the kernels ----
    std::vector<HardCase> cases = hardCases(m);
    std::shared_ptr<const EnergyTable> table;  // (a combination's lobes build theirs in the interpreter)
    if (!m.combinesLobes() && m.singleLobe().compensatesEnergy()) table = buildEnergyTable(energyTableKey(m));
    Interpreter<double> interp(m, table);
    HardCaseReference ref = evaluateHardCaseReference(interp, cases);
    size_t byInput = 0;
    for (const HardCase& c : cases) byInput += c.invalidInput;
    std::printf("  hard cases: %zu (%zu with a non-finite or non-unit input: must give 0 and be counted)\n",
                cases.size(), byInput);
    std::printf("    %-14s %7s %7s %5s %5s %5s %11s %7s\n", "backend", "invalid", "byinput", "NaN", "Inf", "neg",
                "max relerr", "bound");
    // Condition numbers (in __float128), computed on demand and shared by the
    // JIT and the reference checks.
    QuadReference quad(m, table);
    std::map<size_t, double> kappas;
    auto condition = [&](size_t i) {
        auto it = kappas.find(i);
        return it != kappas.end() ? it->second : kappas[i] = quad.condition(cases[i]);
    };
    SampleStats refStats = checkReference(cases, ref);
    printSample(refStats, m, cases, opt.verbose);
    ok &= refStats.ok();

    // A whole-sphere lobe (SPEC 11) the compiled backends do not lower
    // (compiledBackendsRefuse: a compensated sheet whose index is an input)
    // has no kernels to compare; any other material that reaches here compiles.
    const bool wholeSphere = scattersBelowSurface(m);
    const std::string notLowered = compiledBackendsRefuse(m);
    if (opt.jit && !notLowered.empty()) std::printf("    %-14s not compiled: %s\n", "kernels", notLowered.c_str());
    if (opt.jit && notLowered.empty()) {
        struct Variant {
            const char* name;
            const char* options;
        };
        const Variant variants[] = {{"scalar exact", "backend=scalar;math=exact"},
                                    {"simd exact", "backend=simd;math=exact"},
                                    {"scalar fast", "backend=scalar;math=fast"},
                                    {"simd fast", "backend=simd;math=fast"}};
        for (const Variant& v : variants) {
            CompileOptions o;
            std::string error = CompileOptions::parse(v.options, o);
            if (!error.empty()) throw std::runtime_error(error);
            DiagnosticEngine diags;
            std::unique_ptr<Kernel> kernel = compiler.compileMaterial(m, o, diags);
            if (!kernel) {
                std::printf("    %-14s compile failed:\n%s", v.name, diags.str().c_str());
                ok = false;
                continue;
            }
            std::string name = v.name;
            if (kernel->backend() == Backend::Simd) name = fmt::format("simd{} {}", kernel->width(), mathModeName(o.math));
            KernelRun run = runKernel(*kernel, cases);
            SampleStats s = checkKernel(name, run, cases, ref, hardCaseBound(o.math), condition, hardCaseRoundoff(o.math));
            s.accuracyEnforced = o.math == MathMode::Exact;
            printSample(s, m, cases, opt.verbose);
            ok &= s.ok();
        }
    }

    // ---- 2. double against __float128 ----
    if (opt.quad) {
        double worstWell = 0, worstKappa = 0;
        size_t worstWellCase = SIZE_MAX, illConditioned = 0, unexplained = 0, mismatches = 0;
        std::vector<std::pair<size_t, std::string>> notes;
        for (size_t i = 0; i < cases.size(); ++i) {
            QuadComparison c = quad.compare(cases[i]);
            if (c.validMismatch) {
                ++mismatches;
                notes.push_back({i, fmt::format("validity differs: double {} quad {}", c.doubleValid ? "valid" : "invalid",
                                                c.quadValid ? "valid" : "invalid")});
                continue;
            }
            if (c.relError <= kQuadTolerance) {
                if (c.relError >= worstWell) {
                    worstWell = c.relError;
                    worstWellCase = i;
                }
                continue;
            }
            double kappa = condition(i);
            if (c.relError <= kConditionFactor * kappa * kUnitRoundoff) {
                ++illConditioned;
                worstKappa = std::max(worstKappa, kappa);
                if (opt.verbose)
                    notes.push_back({i, fmt::format("ill-conditioned: rel err {:.3g}, kappa {:.3g}", c.relError, kappa)});
            } else {
                ++unexplained;
                notes.push_back({i, fmt::format("rel err {:.3g} with kappa {:.3g} (ch {}: double {:.17g} quad {:.17g})",
                                                c.relError, kappa, c.channel, c.d[c.channel], c.q[c.channel])});
            }
        }
        bool quadOk = unexplained == 0 && mismatches == 0;
        ok &= quadOk;
        std::printf("    %-14s max rel err %.3g on well-conditioned cases (bound %.0e); %zu ill-conditioned "
                    "(within %g kappa u, max kappa %.3g); %s\n",
                    "interp vs quad", worstWell, kQuadTolerance, illConditioned, kConditionFactor, worstKappa,
                    quadOk ? "ok" : "FAIL");
        if (opt.verbose && worstWellCase < cases.size())
            std::printf("        worst well-conditioned: %s\n", shortCase(m, cases[worstWellCase]).c_str());
        size_t shown = 0;
        for (const auto& [i, why] : notes) {
            if (shown++ >= (opt.verbose ? 20u : 6u)) break;
            std::printf("        %s: %s\n", why.c_str(), shortCase(m, cases[i]).c_str());
        }
    }

    // ---- 3. physics ----
    if (opt.physics && wholeSphere) ok &= printWholeSphereChecks(m, interp);
    if (opt.physics && !wholeSphere) {
        std::vector<PhysicsCheck> checks = physicsChecks(m);
        // Worst per (check, enforced), and every failure.
        std::map<std::pair<std::string, bool>, const PhysicsCheck*> worst;
        for (const PhysicsCheck& c : checks) {
            auto key = std::make_pair(c.name, c.enforced);
            auto it = worst.find(key);
            if (it == worst.end() || c.error > it->second->error || (c.failed() && !it->second->failed()))
                worst[key] = &c;
        }
        std::printf("  physics (quadrature, reference interpreter):\n");
        std::printf("    %-26s %12s %9s %10s %8s  %-6s %s\n", "check", "value", "expected", "error", "tol", "status",
                    "where");
        auto row = [&](const PhysicsCheck& c) {
            std::string status = c.failed() ? "FAIL" : c.enforced ? "ok" : "info";
            std::string expected = c.name.rfind("energy", 0) == 0 ? "<= 1" : fmt::format("{:.6g}", c.expected);
            std::printf("    %-26s %12.9g %9s %10.3g %8.0e  %-6s %s\n", c.name.c_str(), c.value, expected.c_str(),
                        c.error, c.tolerance, status.c_str(), c.where.c_str());
            if (!c.enforced && !c.note.empty()) std::printf("        (not enforced: %s)\n", c.note.c_str());
        };
        for (const auto& [key, c] : worst) row(*c);
        for (const PhysicsCheck& c : checks)
            if (c.failed() && worst[{c.name, c.enforced}] != &c) row(c);
        for (const PhysicsCheck& c : checks) ok &= !c.failed();
    }
    if (opt.walk && !wholeSphere) ok &= printWalkComparison(m, interp);
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("  %s: %s (%.1f s)\n\n", m.name.c_str(), ok ? "PASS" : "FAIL", seconds);
    return ok;
}

}  // namespace

int cmdVerify(const std::vector<std::string>& args) {
    VerifyOptions opt;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (a == "--material") {
            if (i + 1 >= args.size()) {
                std::fputs(kVerifyUsage, stderr);
                return kExitUsage;
            }
            opt.material = args[++i];
        } else if (a == "--verbose") opt.verbose = true;
        else if (a == "--no-physics") opt.physics = false;
        else if (a == "--no-walk") opt.walk = false;
        else if (a == "--no-jit") opt.jit = false;
        else if (a == "--no-quad") opt.quad = false;
        else if (!a.empty() && a[0] == '-') {
            std::fprintf(stderr, "facet verify: unknown option '%s'\n%s", a.c_str(), kVerifyUsage);
            return kExitUsage;
        } else opt.files.push_back(a);
    }
    if (opt.files.empty()) {
        std::fprintf(stderr, "facet verify: no files given\n%s", kVerifyUsage);
        return kExitUsage;
    }
    bool materialError = false, failed = false;
    int passed = 0, total = 0;
    std::vector<std::string> failedNames;
    Compiler compiler;
    for (const std::string& path : opt.files) {
        DiagnosticEngine diags;
        CheckedProgram program = loadProgramFile(path, diags);
        if (diags.hasErrors()) {
            std::fputs(diags.str().c_str(), stderr);
            materialError = true;
            continue;
        }
        for (const CheckedMaterial& m : program.materials) {
            if (!opt.material.empty() && m.name != opt.material) continue;
            // A whole-sphere lobe is verified on the reference alone (no kernels).
            const bool wholeSphere = scattersBelowSurface(m);
            if (std::string why = compiledBackendsRefuse(m); !why.empty() && !wholeSphere) {
                DiagnosticEngine refused;
                refused.error(m.loc, why);
                std::fputs(refused.str().c_str(), stderr);
                materialError = true;
                continue;
            }
            ++total;
            if (verifyMaterial(m, path, compiler, opt)) ++passed;
            else {
                failed = true;
                failedNames.push_back(m.name);
            }
        }
    }
    std::printf("verify: %d of %d materials passed", passed, total);
    if (!failedNames.empty()) {
        std::printf("; failed:");
        for (const std::string& n : failedNames) std::printf(" %s", n.c_str());
    }
    std::printf("\n");
    if (materialError) return kExitMaterialError;
    if (!opt.material.empty() && total == 0) {
        std::fprintf(stderr, "facet verify: no material named '%s'\n", opt.material.c_str());
        return kExitUsage;
    }
    return failed ? kExitFailed : kExitOk;
}

}  // namespace facet
