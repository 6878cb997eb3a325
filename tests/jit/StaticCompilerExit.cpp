// A Compiler held in a static and destroyed by exit() while its tier-up
// thread still has work queued: the way a renderer's plugin or a test runner
// keeps one. Facet's own state that the tier-ups use (the model catalog, the
// emitters, the table caches, ...) is created lazily, after such a Compiler,
// so exit() would destroy it first; the Compiler's destructor then runs the
// queued tier-ups that fill the disk cache on it. Built with the sanitizers,
// this program fails on any use of destroyed state.
//
//   facet_static_compiler_exit compile MATERIALS_DIR CACHE_DIR
//       compiles every *.mat of MATERIALS_DIR and, so that every model's
//       code runs, the hard-case materials that cover the catalog
//       (CoveringMaterials.h), tiered, with the disk cache CACHE_DIR
//       (emptied first); writes how many it compiled to CACHE_DIR/compiled
//       and returns from main with the tier-ups pending
//   facet_static_compiler_exit count CACHE_DIR
//       exits 0 when CACHE_DIR holds one kernel object per material
//       compiled: the tier-ups that ran during exit() completed their work
#include "HardCases.h"
#include "Kernel.h"

#include "../CoveringMaterials.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

int compileAll(const std::string& materials, const std::string& cacheDir) {
    static facet::Compiler compiler;  // before anything else of Facet's is touched
    std::error_code ec;
    fs::remove_all(cacheDir, ec);
    if (!fs::create_directories(cacheDir, ec) && ec) {
        std::fprintf(stderr, "cannot create %s: %s\n", cacheDir.c_str(), ec.message().c_str());
        return 1;
    }
    compiler.setCacheDir(cacheDir);
    std::vector<std::string> files;
    for (const auto& entry : fs::directory_iterator(materials))
        if (entry.path().extension() == ".mat") files.push_back(entry.path().string());
    std::sort(files.begin(), files.end());
    facet::CompileOptions options;
    std::string err = facet::CompileOptions::parse("backend=simd;width=8;codegen=tiered;cache=on", options);
    if (!err.empty()) {
        std::fprintf(stderr, "options: %s\n", err.c_str());
        return 1;
    }
    int compiled = 0;
    auto check = [&](std::unique_ptr<facet::Kernel> kernel, const std::string& what,
                     const facet::DiagnosticEngine& diags) {
        if (!kernel) std::fprintf(stderr, "%s: %s\n", what.c_str(), diags.str().c_str());
        compiled += kernel != nullptr;
        return kernel != nullptr;
    };
    for (const std::string& path : files) {
        facet::DiagnosticEngine diags;
        if (!check(compiler.compileFile(path, "", options, diags), path, diags)) return 1;
    }
    for (const facet::HardCaseMaterial& m : facet::test::coveringMaterials(facet::hardCaseMaterials())) {
        facet::DiagnosticEngine diags;
        if (!check(compiler.compileText(m.text, "<" + m.name + ">", m.name, options, diags), m.name, diags)) return 1;
    }
    std::ofstream(cacheDir + "/compiled") << compiled << "\n";
    std::printf("compiled %d materials; exiting with their tier-ups queued\n", compiled);
    std::fflush(stdout);
    return 0;
}

int countObjects(const std::string& cacheDir) {
    int want = -1, objects = 0;
    std::ifstream(cacheDir + "/compiled") >> want;
    std::error_code ec;
    for (const auto& entry : fs::recursive_directory_iterator(cacheDir, ec))
        if (entry.path().extension() == ".fko") ++objects;
    std::printf("%s holds %d kernel objects (want %d)\n", cacheDir.c_str(), objects, want);
    return objects == want ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.size() == 3 && args[0] == "compile") return compileAll(args[1], args[2]);
    if (args.size() == 2 && args[0] == "count") return countObjects(args[1]);
    std::fprintf(stderr,
                 "usage: facet_static_compiler_exit compile MATERIALS_DIR CACHE_DIR\n"
                 "       facet_static_compiler_exit count CACHE_DIR\n");
    return 2;
}
