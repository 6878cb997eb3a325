// MaterialFile: what every `facet` subcommand does first with its FILE
// argument: load and check the material file, print its diagnostics, and
// find the material the command names, with one message for a name that is
// not there. Also the exit codes the subcommands share.
#pragma once

#include "Material.h"

#include <string>

namespace facet {

// The exit codes of every subcommand (listed in `facet`'s usage text).
constexpr int kExitOk = 0, kExitFailed = 1, kExitUsage = 2, kExitMaterialError = 65;

struct NamedMaterial {
    CheckedProgram program;
    // The material asked for; null when the file had errors or the name is
    // not in it.
    const CheckedMaterial* material = nullptr;
    // The file did not load or check (its diagnostics are on stderr).
    bool fileErrors = false;
    // Where the name is missing: "no material named 'x' in f.mat
    // (materials: a, b)"; the command decides whether that is a usage error.
    std::string missing;
};

// Loads `file`, printing its diagnostics on stderr, and finds `name` in it
// (the first material when `name` is empty).
NamedMaterial loadNamedMaterial(const std::string& file, const std::string& name);

// The material's lobe scatters below the surface (SPEC 11; the checker
// makes such a lobe the material's only one): the commands that handle it
// apart (verify on the reference, render lit through, either side of wo).
inline bool scattersBelowSurface(const CheckedMaterial& m) {
    return !m.combinesLobes() && m.singleLobe().wholeSphere();
}

}  // namespace facet
