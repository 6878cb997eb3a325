// CoveringMaterials: of the generated hard-case materials (HardCases.h),
// the few that together exercise every model's code: each one is kept when
// it brings a model (or an NDF under a Smith masking, or energy
// compensation with and without one) that the ones before it did not.
// Shared by the tests that compile one kernel per material and cannot
// afford all of them.
#pragma once

#include "Checker.h"
#include "HardCases.h"

#include <set>
#include <string>
#include <vector>

namespace facet::test {

inline std::vector<HardCaseMaterial> coveringMaterials(const std::vector<HardCaseMaterial>& all) {
    std::set<std::string> seen;
    std::vector<HardCaseMaterial> out;
    for (const HardCaseMaterial& hm : all) {
        DiagnosticEngine diags;
        CheckedProgram program = loadProgramText(hm.text, hm.name + ".mat", diags);
        if (program.materials.empty()) continue;
        const CheckedMaterial& m = program.materials.front();
        std::vector<std::string> keys = {"ndf " + hm.ndf, "masking " + hm.masking, "fresnel " + hm.fresnel};
        if (m.singleLobe().masking.model->smith) keys.push_back("smith " + hm.ndf);
        if (m.singleLobe().compensatesEnergy()) keys.push_back(m.singleLobe().masking.model->smith ? "energy smith" : "energy");
        bool adds = false;
        for (const std::string& k : keys) adds |= seen.insert(k).second;
        if (adds) out.push_back(hm);
    }
    return out;
}

}  // namespace facet::test
