// facet lut FILE [--material NAME] -o TABLES.exr [--threads N]
//
// Integrates the Kulla-Conty E / E_avg table of the material's NDF x masking
// pair (compiler/reference/KullaConty.h) and writes it as EXR with its metadata
// (compiler/tables/TableCache.h). Reports the grid, the build time of the
// pair, E_avg at a few roughnesses and F_avg of the material's Fresnel at its
// default inputs. The material need not use energy = kulla_conty, but its
// pair must be one a table exists for (not ward; constant gtr gamma and
// schlick_smith k).
#include "Commands.h"
#include "OutputFile.h"

#include "Checker.h"
#include "Interpreter.h"
#include "KullaContyEval.h"
#include "MaterialFile.h"
#include "TableCache.h"

#include <cstdio>
#include <fmt/format.h>
#include <thread>

namespace facet {

namespace {
constexpr const char* kLutUsage = "usage: facet lut FILE [--material NAME] -o TABLES.exr [--threads N]\n";
}

int cmdLut(const std::vector<std::string>& args) {
    std::string file, material, out;
    int threads = 0;
    auto usage = [](const std::string& msg) {
        std::fprintf(stderr, "facet: lut: %s\n%s", msg.c_str(), kLutUsage);
        return kExitUsage;
    };
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        bool hasValue = i + 1 < args.size();
        if (a == "--material" || a == "-o" || a == "--out" || a == "--threads") {
            if (!hasValue) return usage(a + " needs a value");
            const std::string& v = args[++i];
            if (a == "--material") material = v;
            else if (a == "--threads") {
                char* end = nullptr;
                long n = std::strtol(v.c_str(), &end, 10);
                if (end == v.c_str() || *end || n < 1 || n > 256) return usage("--threads expects 1 .. 256");
                threads = int(n);
            } else out = v;
        } else if (!a.empty() && a[0] == '-') {
            return usage(fmt::format("unknown option '{}'", a));
        } else if (file.empty()) {
            file = a;
        } else {
            return usage(fmt::format("more than one material file ('{}' and '{}')", file, a));
        }
    }
    if (file.empty()) return usage("no material file given");
    if (out.empty()) return usage("-o TABLES.exr is required");
    if (std::string why = sameFileProblem("facet lut", out, {{file, "the material file"}}); !why.empty())
        return usage(why);

    NamedMaterial named = loadNamedMaterial(file, material);
    if (named.fileErrors) return kExitMaterialError;
    if (!named.material) return usage(named.missing);
    const CheckedMaterial* m = named.material;
    if (m->combinesLobes()) {
        std::fprintf(stderr, "%s: error: material '%s' combines lobes; 'facet lut' writes the table of one lobe\n",
                     m->loc.str().c_str(), m->name.c_str());
        return kExitMaterialError;
    }
    if (!m->singleLobe().hasNdf()) {
        std::fprintf(stderr, "%s: error: material '%s' is a diffuse lobe (no ndf); it has no E table\n",
                     m->loc.str().c_str(), m->name.c_str());
        return kExitMaterialError;
    }
    if (auto why = kullaContyUnsupported(*m, m->singleLobe())) {
        std::fprintf(stderr, "%s: error: material '%s': %s\n", why->loc.str().c_str(), m->name.c_str(),
                     why->message.c_str());
        return kExitMaterialError;
    }
    EnergyTableKey key = energyTableKey(*m);
    int nt = threads ? threads : int(std::max(1u, std::thread::hardware_concurrency()));
    std::shared_ptr<EnergyTable> table = buildEnergyTable(key, EnergyQuadrature{}, nt);
    std::string err = writeEnergyTableExr(*table, out);
    if (!err.empty()) {
        std::fprintf(stderr, "facet: lut: %s\n", err.c_str());
        return kExitFailed;
    }
    std::printf("material %s: table %s, %d x %d (mu x alpha), alpha in [%g, %g], built in %.1f ms (%d threads)\n",
                m->name.c_str(), key.name().c_str(), table->muCount, table->alphaCount, table->alphaMin,
                table->alphaMax, table->buildMillis, nt);
    std::printf("  E_avg:");
    for (double a : {0.01, 0.05, 0.1, 0.25, 0.5, 1.0}) std::printf("  alpha %g: %.6f", a, 1 - table->ecAvgAt(a));
    std::printf("\n");
    if (!m->singleLobe().compensatesEnergy())
        std::printf("  (material uses energy = none; the table is the one kulla_conty would use)\n");
    Interpreter<double> interp(*m, table);
    ResolvedMaterial<double> r = interp.resolve(nullptr);
    if (r.valid) {
        double alpha = energyAlpha(r);
        std::printf("  at default inputs: alpha %.6g, E_avg %.6f, F_avg (%.6f, %.6f, %.6f)\n", alpha,
                    1 - table->ecAvgAt(alpha), fresnelAverage(r, 0), fresnelAverage(r, 1), fresnelAverage(r, 2));
    }
    std::printf("wrote %s\n", out.c_str());
    return kExitOk;
}

}  // namespace facet
