// RandomMaterial: a generator of random, valid materials for differential
// testing. Covers every NDF x masking of the model catalog the checker
// accepts (a new catalog entry is included without an edit here), x Fresnel
// value ranges x diffuse, with constant and input-driven parameters built from
// random well-conditioned expressions (so that float-vs-double differences
// measure the kernels, not cancellation in the user's arithmetic).
#pragma once

#include <cstdint>
#include <random>
#include <string>

namespace facet::test {

struct RandomMaterial {
    std::string text;  // the material source
    std::string combination;  // "ndf/masking/fresnel/diffuse"
};

// The i-th material of the stream for `seed`; `i` also steers the
// combination so that consecutive indices cycle through all of them.
RandomMaterial randomMaterial(uint64_t seed, int i);
int randomMaterialCombinationCount();
// The i-th material of 2 or 3 lobes (SPEC 10) for `seed`: lobes drawn from
// the same combinations, combined by a sum, weighted sum, mix or layer, and a
// third lobe added or mixed in.
RandomMaterial randomMultiLobeMaterial(uint64_t seed, int i);

}  // namespace facet::test
