// CombinationEmitter: one lane body of a material that combines lobes
// (SPEC 10) -- each lobe by the one-lobe LaneEmitter over the lobe alone
// (LoweringPlan::lobes), then the tree of CheckedMaterial::bsdf over their
// values: weights, sums, mixes and layers, a layer's g(mu_i) g(mu_o) read
// from the table the plan baked (LoweringPlan::layerG).
//
// The reference's counterpart is compiler/reference/LobeCombination.h;
// the two are written independently (the reference bakes its own tables on
// demand, per resolved parameter set).
#pragma once

#include "LayerAlbedo.h"
#include "Lowering.h"

#include <llvm/IR/IRBuilder.h>

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace facet {

struct CombinationLanes {
    std::array<llvm::Value*, 3> rgb;  // float lanes, 0 where invalid
    llvm::Value* invalid;
    llvm::Value* untrusted;  // `guarded`: lanes to recompute in the plain bodies (includes invalid ones)
};

// f of the combination at (wi, wo) for lanes of type `laneType`, in each
// lobe's plain body or (`guarded`) each lobe's batch body, which may be a
// guarded body (LoweringPlan::batchBodies of the combination). Tables are named
// `tablePrefix`.layerN (covered by the cache key through the material's
// text and the codegen sources).
CombinationLanes emitCombination(const CheckedMaterial& material, const LoweringPlan& plan,
                                 const LoweringOptions& options, bool guarded, llvm::IRBuilder<>& builder,
                                 llvm::Type* laneType, llvm::Module& module, const std::array<llvm::Value*, 3>& wi,
                                 const std::array<llvm::Value*, 3>& wo, const std::vector<llvm::Value*>& slots,
                                 const std::string& tablePrefix);

class LaneEmitter;

// The emitter of a combination's weights and table reads, shared by eval
// and the sampler: a LaneEmitter of lobe 0's plain body whose plan reads
// what the whole combination reads (the inputs are checked there too),
// expressions in double, inputs and lets lowered. Not movable: the
// LaneEmitter refers to the plan and body held here.
class CombinationExpressions {
public:
    CombinationExpressions(const LoweringPlan& combination, llvm::IRBuilder<>& builder, llvm::Type* laneType,
                           llvm::Module& module, const std::vector<llvm::Value*>& slots);
    CombinationExpressions(const CombinationExpressions&) = delete;
    CombinationExpressions& operator=(const CombinationExpressions&) = delete;
    ~CombinationExpressions();
    LaneEmitter& lanes() { return *lanes_; }

private:
    LoweringPlan plan_;
    BodyPlan body_;
    std::unique_ptr<LaneEmitter> lanes_;
};

// The Kulla-Conty table of lobe `lobe` (null without one).
const EnergyTable* lobeEnergyTable(const LoweringOptions& options, size_t lobe);

// n.w of the unit w (float lanes), in double.
llvm::Value* unitCosine(LaneEmitter& lanes, const std::array<llvm::Value*, 3>& w);
// A MuTable (LayerAlbedo.h) embedded as the table `name` (one channel when
// gray; its nodes rounded to float, in pairs), read at the cosine mu (double
// lanes) as the reference reads it: linear in x = log(1 + mu (e^6 - 1)) / 6,
// mu clamped to [1e-4, 1].
std::array<llvm::Value*, 3> lookUpMuTable(LaneEmitter& lanes, const MuTable& table, const std::string& name,
                                          llvm::Value* mu);

// The combination's mixture sampler (CombinationSampling.cpp; SPEC 10): one
// lobe per lane drawn with probabilities from the lobes' albedo estimates
// (LoweringPlan::nodeAlbedo) and the weights the tree gives them, its
// one-lobe sampler, pdf = the whole mixture's density, weight = f cos / pdf.
struct CombinationSampleLanes {
    std::array<llvm::Value*, 3> wi;
    llvm::Value* pdf;
    std::array<llvm::Value*, 3> weight;
    llvm::Value* invalid;
};
CombinationSampleLanes emitCombinationSample(const CheckedMaterial& material, const LoweringPlan& plan,
                                             const LoweringOptions& options, llvm::IRBuilder<>& builder,
                                             llvm::Type* laneType, llvm::Module& module,
                                             const std::array<llvm::Value*, 3>& wo, const std::array<llvm::Value*, 3>& u,
                                             const std::vector<llvm::Value*>& slots, const std::string& tablePrefix);
struct CombinationPdfLanes {
    llvm::Value* pdf;
    llvm::Value* invalid;
};
CombinationPdfLanes emitCombinationPdf(const CheckedMaterial& material, const LoweringPlan& plan,
                                       const LoweringOptions& options, llvm::IRBuilder<>& builder,
                                       llvm::Type* laneType, llvm::Module& module,
                                       const std::array<llvm::Value*, 3>& wi, const std::array<llvm::Value*, 3>& wo,
                                       const std::vector<llvm::Value*>& slots, const std::string& tablePrefix);

}  // namespace facet
