// Checker: resolution, typing and material rules (see Checker.h).
#include "Checker.h"

#include "BsdfCombination.h"
#include "ComputeCost.h"
#include "ExprEval.h"
#include "KullaConty.h"
#include "LambdaTable.h"
#include "Parser.h"
#include "ScatterRules.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <optional>
#include <sys/stat.h>
#include <unistd.h>
#include <map>
#include <sstream>

namespace facet {

const CheckedMaterial* CheckedProgram::find(std::string_view name) const {
    if (materials.empty()) return nullptr;
    if (name.empty()) return &materials.front();
    for (const CheckedMaterial& m : materials)
        if (m.name == name) return &m;
    return nullptr;
}

namespace {

size_t editDistance(std::string_view a, std::string_view b) {
    std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        cur[0] = i;
        for (size_t j = 1; j <= b.size(); ++j)
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

// " (did you mean 'x'?)" for the closest candidate within 2 edits, or "".
// Names longer than 64 bytes get no suggestion: edit distance is quadratic in
// the length, and no one misspells a name that long.
std::string suggestion(std::string_view name, const std::vector<std::string>& candidates) {
    constexpr size_t kMaxSuggestLength = 64;
    if (name.size() > kMaxSuggestLength) return "";
    size_t best = 3;
    std::string bestName;
    for (const std::string& c : candidates) {
        if (c.size() > name.size() + 2 || c.size() + 2 < name.size()) continue;  // > 2 edits apart
        size_t d = editDistance(name, c);
        if (d < best) {
            best = d;
            bestName = c;
        }
    }
    return bestName.empty() ? "" : fmt::format(" (did you mean '{}'?)", bestName);
}

std::string joinNames(const std::vector<std::string>& names) {
    std::string out;
    for (size_t i = 0; i < names.size(); ++i) {
        if (i) out += i + 1 == names.size() ? " or " : ", ";
        out += names[i];
    }
    return out;
}

// "alpha", or "alpha_x and alpha_y"
std::string describeForm(const ModelForm& form) {
    std::string out;
    for (size_t i = 0; i < form.params.size(); ++i) {
        if (i) out += i + 1 == form.params.size() ? " and " : ", ";
        out += form.params[i].name;
    }
    return out.empty() ? "no arguments" : out;
}

struct NameInfo {
    BindingKind kind;
    int index;
    SourceLoc loc;
    size_t statement;  // index of the defining statement
};

class MaterialChecker {
public:
    MaterialChecker(const MaterialDecl& decl, DiagnosticEngine& diags) : decl_(decl), diags_(diags) {}

    CheckedMaterial run() {
        const size_t errorsBefore = diags_.diagnostics().size();
        out_.loc = decl_.loc;
        out_.name = decl_.name;
        collectNames();
        // Without lobe blocks the model statements form one implicit lobe,
        // named after the material, and the combination is that lobe.
        CheckedLobe implicit;
        implicit.loc = decl_.loc;
        implicit.name = decl_.name;
        implicit.implicit = true;
        std::array<const ModelStmt*, kModelSlotCount> seen{};
        const BsdfStmt* bsdf = nullptr;
        for (current_ = 0; current_ < decl_.statements.size(); ++current_) {
            const Stmt& s = decl_.statements[current_];
            if (auto* in = std::get_if<InputDecl>(&s)) checkInput(*in);
            else if (auto* let = std::get_if<LetDecl>(&s)) checkLet(*let);
            else if (auto* lobe = std::get_if<LobeDecl>(&s)) checkLobe(*lobe);
            else if (auto* b = std::get_if<BsdfStmt>(&s)) checkBsdf(*b, bsdf);
            else if (auto* o = std::get_if<LobeOptionStmt>(&s)) {
                if (lobes_.empty()) checkLobeOption(*o, implicit);
                else
                    diags_.error(o->loc, fmt::format("'{}' statement outside a lobe: material '{}' has lobe blocks, "
                                                     "so it belongs in the lobe it applies to",
                                                     o->option, decl_.name));
            } else if (lobes_.empty()) checkModelStmt(std::get<ModelStmt>(s), seen, implicit);
            else
                diags_.error(std::get<ModelStmt>(s).loc,
                             fmt::format("'{}' statement outside a lobe: material '{}' has lobe blocks, so every "
                                         "model statement belongs in one of them",
                                         modelSlotName(std::get<ModelStmt>(s).slot), decl_.name));
        }
        if (lobes_.empty()) {
            if (!seen[int(ModelSlot::Ndf)])
                diags_.error(decl_.loc, fmt::format("material '{}' has no 'ndf' statement; every material needs "
                                                    "one, e.g. 'ndf = ggx(0.3);'",
                                                    decl_.name));
            if (bsdf)
                diags_.error(bsdf->loc, fmt::format("'bsdf' combines lobes, and material '{}' has no lobe blocks "
                                                    "(write 'lobe NAME {{ ... }}')",
                                                    decl_.name));
            finishLobe(implicit, seen, errorsBefore);
            out_.lobes.push_back(std::move(implicit));
            out_.bsdf = {BsdfNode{BsdfKind::Lobe, decl_.loc, 0, -1, -1, nullptr}};
        } else if (!bsdf) {
            diags_.error(decl_.loc, fmt::format("material '{}' has lobes but no 'bsdf = ...;' statement to "
                                                "combine them (e.g. 'bsdf = {};')",
                                                decl_.name, lobeNames_.front()));
        } else if (!out_.bsdf.empty()) {
            std::vector<bool> used(out_.lobes.size(), false);
            for (const BsdfNode& node : out_.bsdf)
                if (node.kind == BsdfKind::Lobe) used.at(size_t(node.lobe)) = true;
            for (size_t i = 0; i < used.size(); ++i)
                if (!used[i])
                    diags_.error(out_.lobes[i].loc, fmt::format("lobe '{}' is not used in the bsdf statement at {}",
                                                                out_.lobes[i].name, bsdf->loc.str()));
        }
        if (diags_.diagnostics().size() == errorsBefore && !diags_.full() && !out_.bsdf.empty())
            if (auto why = wholeSphereCombinationUnsupported(out_)) diags_.error(why->loc, why->message);
        if (diags_.diagnostics().size() == errorsBefore && !diags_.full())
            if (auto why = exceedsComputeBudget(out_)) diags_.error(why->loc, why->message);
        return std::move(out_);
    }

private:
    // First pass: where every input and let is defined, so that a use before
    // the definition gets a precise message, and duplicates are reported once.
    void collectNames() {
        int inputs = 0, lets = 0;
        for (size_t i = 0; i < decl_.statements.size(); ++i) {
            const Stmt& s = decl_.statements[i];
            const std::string* name = nullptr;
            SourceLoc loc;
            NameInfo info;
            if (auto* in = std::get_if<InputDecl>(&s)) {
                name = &in->name;
                loc = in->loc;
                info = {BindingKind::Input, inputs++, loc, i};
            } else if (auto* let = std::get_if<LetDecl>(&s)) {
                name = &let->name;
                loc = let->loc;
                info = {BindingKind::Let, lets++, loc, i};
            } else if (auto* lobe = std::get_if<LobeDecl>(&s)) {
                collectLobe(*lobe, i);
                continue;
            } else {
                continue;
            }
            if (const NameInfo* first = definedName(*name)) {
                diags_.error(loc, fmt::format("duplicate definition of '{}'; first defined at {}", *name,
                                              first->loc.str()));
                duplicateStatements_.resize(decl_.statements.size());
                duplicateStatements_[i] = true;
                continue;
            }
            names_.emplace(*name, info);
        }
    }

    // A lobe's name shares the material's namespace with inputs and lets
    // (a weight and a lobe must never be spelled alike).
    void collectLobe(const LobeDecl& lobe, size_t statement) {
        if (const NameInfo* first = definedName(lobe.name)) {
            diags_.error(lobe.loc, fmt::format("duplicate definition of '{}'; first defined at {}", lobe.name,
                                               first->loc.str()));
            duplicateStatements_.resize(decl_.statements.size());
            duplicateStatements_[statement] = true;
            return;
        }
        lobes_.emplace(lobe.name, NameInfo{BindingKind::Unresolved, int(lobes_.size()), lobe.loc, statement});
        lobeNames_.push_back(lobe.name);
    }

    // The input, let or lobe already called `name`, or null.
    const NameInfo* definedName(const std::string& name) const {
        if (auto it = names_.find(name); it != names_.end()) return &it->second;
        if (auto it = lobes_.find(name); it != lobes_.end()) return &it->second;
        return nullptr;
    }

    void checkLobe(const LobeDecl& decl) {
        if (isDuplicate(current_)) return;
        const size_t errorsBefore = diags_.diagnostics().size();
        CheckedLobe lobe;
        lobe.loc = decl.loc;
        lobe.name = decl.name;
        std::array<const ModelStmt*, kModelSlotCount> seen{};
        for (const ModelStmt& stmt : decl.statements) checkModelStmt(stmt, seen, lobe);
        for (const LobeOptionStmt& option : decl.options) checkLobeOption(option, lobe);
        if (!seen[int(ModelSlot::Ndf)]) {
            if (!seen[int(ModelSlot::Diffuse)])
                diags_.error(decl.loc, fmt::format("lobe '{}' has neither an 'ndf' nor a 'diffuse' statement; a "
                                                   "lobe needs one, e.g. 'ndf = ggx(0.3);' or 'diffuse = lambert(0.5);'",
                                                   decl.name));
            for (ModelSlot slot : {ModelSlot::Masking, ModelSlot::Fresnel, ModelSlot::Energy})
                if (seen[int(slot)])
                    diags_.error(seen[int(slot)]->loc,
                                 fmt::format("'{}' in lobe '{}', which has no 'ndf': a lobe without an ndf is a "
                                             "diffuse lobe and takes only 'diffuse'",
                                             modelSlotName(slot), decl.name));
        }
        finishLobe(lobe, seen, errorsBefore);
        out_.lobes.push_back(std::move(lobe));
    }

    // The defaults (`none`) of the slots a lobe leaves out, then the rules
    // that need the whole lobe: masking against the NDF, the Kulla-Conty
    // and tabulated-Lambda tables (only when the lobe is otherwise clean).
    void finishLobe(CheckedLobe& lobe, const std::array<const ModelStmt*, kModelSlotCount>& seen,
                    size_t errorsBefore) {
        for (int s = 0; s < kModelSlotCount; ++s) {
            ModelUse& use = lobe.use(ModelSlot(s));
            if (!use.model && s != int(ModelSlot::Ndf)) {
                use.model = findModel(ModelSlot(s), "none");
                use.loc = lobe.loc;
            }
        }
        if (lobe.wholeSphere() && !lobe.ndf.model && seen[int(ModelSlot::Diffuse)])  // a diffuse lobe
            if (auto why = wholeSphereLobeUnsupported(lobe)) diags_.error(why->loc, why->message);
        if (!seen[int(ModelSlot::Ndf)] || !lobe.ndf.model) return;
        checkCombination(lobe, seen);
        auto clean = [&] { return diags_.diagnostics().size() == errorsBefore && !diags_.full(); };
        if (lobe.compensatesEnergy() && clean())
            if (auto why = kullaContyUnsupported(out_, lobe)) diags_.error(why->loc, why->message);  // KullaConty.h
        if (lobe.walksMicrosurface() && clean()) checkRandomWalk(lobe);
        if (lobe.wholeSphere() && clean())
            if (auto why = wholeSphereLobeUnsupported(lobe)) diags_.error(why->loc, why->message);  // ScatterRules.h
        if (lobe.masking.model && lobe.masking.model->smith && ndfEntry(*lobe.ndf.model).tabulatedLambda && clean()) {
            SourceLoc loc = lobe.masking.loc;
            std::string why = tabulatedLambdaUnsupported(out_, lobe, loc);  // LambdaTable.h
            if (!why.empty()) diags_.error(loc, why);
        }
    }

    // energy = random_walk: the kernels walk the Smith microsurface of the
    // lobe's NDF with its Fresnel term at every facet, and sample by the
    // walk. What that needs of the rest of the lobe, each with its reason.
    void checkRandomWalk(const CheckedLobe& lobe) {
        const ModelUse& energy = lobe.energy;
        const NdfEntry& ndf = ndfEntry(*lobe.ndf.model);
        if (!lobe.implicit)
            diags_.error(energy.loc, fmt::format("energy 'random_walk' in lobe '{}': the walk's sampler has no density "
                                                 "in closed form, which a combination's one-sample mixture needs; "
                                                 "write it as a material of one lobe, or use 'energy = kulla_conty'",
                                                 lobe.name));
        else if (!ndf.compiledWalk)
            diags_.error(lobe.ndf.loc, fmt::format("energy 'random_walk' needs an NDF whose compiled visible-normal "
                                                   "sampler also takes views below the horizon (the walk's rays go "
                                                   "up as well as down); ndf '{}' has none; use ggx",
                                                   ndf.name));
        else if (!maskingEntry(*lobe.masking.model).heightCorrelated)
            diags_.error(lobe.masking.loc, fmt::format("energy 'random_walk' needs 'masking = smith_height_correlated': "
                                                       "the walk's first bounce is the single scattering of that "
                                                       "masking, and eval and the sampler must describe one BRDF; got "
                                                       "'{}'",
                                                       lobe.masking.model->name));
        else if (fresnelEntry(*lobe.fresnel.model).refractiveIndexParam >= 0)
            diags_.error(lobe.fresnel.loc, fmt::format("energy 'random_walk' with fresnel '{}': a walk on a dielectric "
                                                       "microsurface refracts into the medium below, which the compiled "
                                                       "walk does not follow; use a conductor or Schlick Fresnel term, "
                                                       "or 'energy = kulla_conty'",
                                                       lobe.fresnel.model->name));
        else if (diffuseEntry(*lobe.diffuse.model).present)
            diags_.error(lobe.diffuse.loc, "energy 'random_walk' with a diffuse term: the walk's sampler has no "
                                           "density to mix with the diffuse lobe's; put the diffuse base in a lobe "
                                           "of its own with 'energy = kulla_conty', or leave it out");
    }

    // `scatter = ...;` or `thin = ...;` in `lobe` (once each).
    void checkLobeOption(const LobeOptionStmt& stmt, CheckedLobe& lobe) {
        const SourceLoc& earlier = stmt.option == "scatter" ? lobe.scatterLoc : lobe.thinLoc;
        if (earlier.line > 0) {
            diags_.error(stmt.loc, fmt::format("duplicate '{}' statement in lobe '{}'; first given at {}", stmt.option,
                                               lobe.name, earlier.str()));
            return;
        }
        if (auto why = applyLobeOption(stmt, lobe)) diags_.error(why->loc, why->message);
    }

    void checkBsdf(const BsdfStmt& stmt, const BsdfStmt*& first) {
        if (first) {
            diags_.error(stmt.loc, fmt::format("duplicate 'bsdf' statement; first given at {}", first->loc.str()));
            return;
        }
        first = &stmt;
        if (lobes_.empty()) return;  // reported once all statements are seen
        BsdfCheckContext context{
            [this](std::string_view name) {
                auto it = lobes_.find(std::string(name));
                return it == lobes_.end() || isDuplicate(it->second.statement) ? -1 : it->second.index;
            },
            [this](Expr& weight) { return typeOf(weight); }, lobeNames_, diags_};
        std::vector<BsdfNode> nodes;
        if (buildBsdfTree(*stmt.value, context, nodes) >= 0) out_.bsdf = std::move(nodes);
    }

    bool isDuplicate(size_t statement) const {
        return statement < duplicateStatements_.size() && duplicateStatements_[statement];
    }

    void checkInput(const InputDecl& in) {
        CheckedInput ci;
        ci.loc = in.loc;
        ci.name = in.name;
        ci.firstSlot = out_.slotCount;
        bool ok = true;
        auto def = constant(*in.defaultValue, fmt::format("the default value of input '{}'", in.name));
        if (def) {
            ci.type = in.defaultValue->type;
            ci.defaultValue = def->c;
            if (!def->rgb) ci.defaultValue = {def->c[0], def->c[0], def->c[0]};
        } else {
            ok = false;
            ci.type = in.defaultValue->type == ValueType::Rgb ? ValueType::Rgb : ValueType::Float;
        }
        if (in.lo) {
            auto lo = constant(*in.lo, fmt::format("the lower bound of input '{}'", in.name));
            auto hi = constant(*in.hi, fmt::format("the upper bound of input '{}'", in.name));
            for (auto [v, e] : {std::pair{&lo, in.lo.get()}, std::pair{&hi, in.hi.get()}}) {
                if (*v && (*v)->rgb) {
                    diags_.error(e->loc, fmt::format("range bound of input '{}' must be float, got rgb", in.name));
                    v->reset();
                }
            }
            if (lo && hi) {
                ci.hasRange = true;
                ci.lo = lo->c[0];
                ci.hi = hi->c[0];
                if (ci.lo > ci.hi) {
                    diags_.error(in.lo->loc, fmt::format("empty range {} .. {} for input '{}' (lower bound is "
                                                         "above the upper bound)",
                                                         ci.lo, ci.hi, in.name));
                } else if (def) {
                    for (int i = 0; i < ci.slotCount(); ++i) {
                        double v = ci.defaultValue[i];
                        if (v < ci.lo || v > ci.hi) {
                            diags_.error(in.defaultValue->loc,
                                         fmt::format("default value {} of input '{}' is outside its range {} .. {}",
                                                     v, in.name, ci.lo, ci.hi));
                            break;
                        }
                    }
                }
            }
        }
        (void)ok;
        if (isDuplicate(current_)) return;
        out_.slotCount += ci.slotCount();
        out_.inputs.push_back(std::move(ci));
    }

    // Types `e` (which must not use names) and evaluates it in double.
    std::optional<Value<double>> constant(Expr& e, const std::string& what) {
        constantContext_ = &what;
        ValueType t = typeOf(e);
        constantContext_ = nullptr;
        if (t == ValueType::Unknown) return std::nullopt;
        Value<double> v = evaluateExpr<double>(e, [](const NameExpr&) -> Value<double> {
            internal_error << "name in a constant expression";
        });
        for (int i = 0; i < (v.rgb ? 3 : 1); ++i) {
            if (!std::isfinite(v.c[i])) {
                diags_.error(e.loc, fmt::format("{} is not a finite number ({})", what, printExpr(e)));
                return std::nullopt;
            }
        }
        return v;
    }

    void checkLet(const LetDecl& let) {
        typeOf(*let.value);
        if (isDuplicate(current_)) return;
        out_.lets.push_back({let.loc, let.name, let.value});
    }


    void checkModelStmt(const ModelStmt& stmt, std::array<const ModelStmt*, kModelSlotCount>& seen, CheckedLobe& lobe) {
        const char* slotName = modelSlotName(stmt.slot);
        if (const ModelStmt* first = seen[int(stmt.slot)]) {
            diags_.error(stmt.loc, fmt::format("duplicate '{}' statement; first given at {}", slotName,
                                               first->loc.str()));
            return;
        }
        seen[int(stmt.slot)] = &stmt;
        const ModelInfo* model = findModel(stmt.slot, stmt.model);
        if (!model) {
            std::vector<std::string> candidates;
            for (const ModelInfo* m : catalogSlot(stmt.slot)) {
                candidates.push_back(m->name);
                for (const char* a : m->aliases) candidates.push_back(a);
            }
            std::string hint = suggestion(stmt.model, candidates);
            if (hint.empty()) hint = fmt::format(" (expected {})", joinNames(candidates));
            diags_.error(stmt.modelLoc, fmt::format("unknown {} model '{}'{}", slotName, stmt.model, hint));
            return;
        }
        ModelUse use;
        use.loc = stmt.modelLoc;
        use.model = model;
        use.args.assign(model->canonical.size(), nullptr);
        if (matchArguments(stmt, *model, use)) lobe.use(stmt.slot) = std::move(use);
    }

    // Picks the form of `model` that the written arguments fit and fills the
    // canonical argument list. Reports and returns false when none fits.
    bool matchArguments(const ModelStmt& stmt, const ModelInfo& model, ModelUse& use) {
        const char* slotName = modelSlotName(stmt.slot);
        std::string modelName = fmt::format("{} '{}'", slotName, model.name);
        // No form has more than a few parameters: reject absurdly long lists
        // before the per-argument checks below (the duplicate-name check is
        // quadratic in the list), with the count message they would end in.
        constexpr size_t kMaxCheckedArguments = 64;
        if (stmt.args.size() > kMaxCheckedArguments) {
            std::vector<std::string> forms;
            for (const ModelForm& f : model.forms) forms.push_back(fmt::format("({})", describeForm(f)));
            diags_.error(stmt.args.front().value->loc,
                         fmt::format("{} takes {}, got {} argument{}", modelName, joinNames(forms), stmt.args.size(),
                                     stmt.args.size() == 1 ? "" : "s"));
            return false;
        }
        // Named arguments must each exist in some form, and appear once.
        bool seenNamed = false;
        for (size_t i = 0; i < stmt.args.size(); ++i) {
            const Argument& a = stmt.args[i];
            if (a.name.empty()) {
                if (seenNamed) {
                    diags_.error(a.value->loc, fmt::format("positional argument after a named argument in {}", modelName));
                    return false;
                }
                continue;
            }
            seenNamed = true;
            bool known = false;
            std::vector<std::string> all;
            for (const ModelForm& f : model.forms)
                for (const auto& p : f.params) {
                    known |= a.name == p.name;
                    if (std::find(all.begin(), all.end(), p.name) == all.end()) all.push_back(p.name);
                }
            if (!known) {
                std::string expected = all.empty() ? std::string(" (it takes no arguments)")
                                                   : fmt::format(" (expected {})", joinNames(all));
                std::string hint = suggestion(a.name, all);
                diags_.error(a.nameLoc, fmt::format("unknown argument '{}' for {}{}", a.name, modelName,
                                                    hint.empty() ? expected : hint));
                return false;
            }
            for (size_t j = 0; j < i; ++j)
                if (stmt.args[j].name == a.name) {
                    diags_.error(a.nameLoc, fmt::format("argument '{}' of {} given twice", a.name, modelName));
                    return false;
                }
        }
        // Try each form with the right number of parameters.
        const ModelForm* chosen = nullptr;
        std::vector<const ModelForm::Param*> bound;
        for (const ModelForm& form : model.forms) {
            if (form.params.size() != stmt.args.size()) continue;
            std::vector<const ModelForm::Param*> assign(stmt.args.size(), nullptr);
            bool fits = true;
            for (size_t i = 0; i < stmt.args.size() && fits; ++i) {
                const Argument& a = stmt.args[i];
                if (a.name.empty()) {
                    assign[i] = &form.params[i];
                } else {
                    auto it = std::find_if(form.params.begin(), form.params.end(),
                                           [&](const ModelForm::Param& p) { return a.name == p.name; });
                    if (it == form.params.end()) fits = false;
                    else assign[i] = &*it;
                }
            }
            // A named argument may not land on a parameter already filled positionally.
            for (size_t i = 0; fits && i < assign.size(); ++i)
                for (size_t j = 0; j < i; ++j)
                    if (assign[i] == assign[j]) fits = false;
            if (fits) {
                chosen = &form;
                bound = assign;
                break;
            }
        }
        if (!chosen) {
            std::vector<std::string> forms;
            for (const ModelForm& f : model.forms) forms.push_back(fmt::format("({})", describeForm(f)));
            SourceLoc where = stmt.args.empty() ? stmt.modelLoc : stmt.args.front().value->loc;
            // Report the most useful thing: a missing parameter when the
            // count is short of the only form, a count mismatch otherwise.
            if (model.forms.size() == 1 && stmt.args.size() < model.forms[0].params.size()) {
                for (const auto& p : model.forms[0].params) {
                    bool given = false;
                    for (size_t i = 0; i < stmt.args.size(); ++i)
                        given |= stmt.args[i].name.empty() ? &model.forms[0].params[i] == &p : stmt.args[i].name == p.name;
                    if (!given) {
                        diags_.error(stmt.modelLoc, fmt::format("missing argument '{}' for {}", p.name, modelName));
                        return false;
                    }
                }
            }
            diags_.error(where, fmt::format("{} takes {}, got {} argument{}", modelName, joinNames(forms),
                                            stmt.args.size(), stmt.args.size() == 1 ? "" : "s"));
            return false;
        }
        bool ok = true;
        for (size_t i = 0; i < stmt.args.size(); ++i) {
            const Argument& a = stmt.args[i];
            const ModelForm::Param& p = *bound[i];
            ValueType t = typeOf(*a.value);
            if (t == ValueType::Unknown) {
                ok = false;
                continue;
            }
            if (p.type == ValueType::Float && t == ValueType::Rgb) {
                diags_.error(a.value->loc, fmt::format("argument '{}' of {} must be float, got rgb", p.name, modelName));
                ok = false;
                continue;
            }
            for (int target : p.targets) use.args[target] = a.value;
        }
        use.isotropic = stmt.slot == ModelSlot::Ndf && chosen->params.size() == 1 && chosen->params[0].targets.size() == 2;
        return ok;
    }

    void checkCombination(const CheckedLobe& lobe, const std::array<const ModelStmt*, kModelSlotCount>& seen) {
        const NdfEntry& ndf = ndfEntry(*lobe.ndf.model);
        const ModelInfo& masking = *lobe.masking.model;
        SourceLoc maskingLoc = seen[int(ModelSlot::Masking)] ? lobe.masking.loc : lobe.ndf.loc;
        if (ndf.wholeLobe) {
            if (std::string_view(masking.name) != "none")
                diags_.error(maskingLoc, fmt::format("ndf '{}' is a whole BRDF lobe with its own normalization; it "
                                                     "requires 'masking = none', not '{}'",
                                                     ndf.name, masking.name));
        } else if (masking.smith && !hasSmithLambda(ndf)) {
            std::vector<std::string> smithNdfs;
            for (const ModelInfo* m : catalogSlot(ModelSlot::Ndf))
                if (hasSmithLambda(ndfEntry(*m))) smithNdfs.push_back(m->name);
            diags_.error(maskingLoc,
                         fmt::format("masking '{}' needs the Smith Lambda of the NDF, and ndf '{}' has neither a "
                                     "closed-form nor a tabulated Lambda; use {}, or a non-Smith masking such as "
                                     "cook_torrance or schlick_smith",
                                     masking.name, ndf.name, joinNames(smithNdfs)));
        }
    }

    // ---- expressions ----

    ValueType typeOf(Expr& e) {
        e.type = computeType(e);
        return e.type;
    }

    static ValueType promote(ValueType a, ValueType b) {
        if (a == ValueType::Unknown || b == ValueType::Unknown) return ValueType::Unknown;
        return a == ValueType::Rgb || b == ValueType::Rgb ? ValueType::Rgb : ValueType::Float;
    }

    ValueType computeType(Expr& e) {
        switch (e.kind) {
            case ExprKind::Number: return ValueType::Float;
            case ExprKind::Name: return resolveName(static_cast<NameExpr&>(e));
            case ExprKind::Unary: return typeOf(*static_cast<UnaryExpr&>(e).operand);
            case ExprKind::Binary: {
                auto& b = static_cast<BinaryExpr&>(e);
                ValueType l = typeOf(*b.lhs), r = typeOf(*b.rhs);
                return promote(l, r);
            }
            case ExprKind::Call: return typeCall(static_cast<CallExpr&>(e));
        }
        internal_error << "unknown expression kind";
    }

    ValueType resolveName(NameExpr& n) {
        if (constantContext_) {
            diags_.error(n.loc, fmt::format("{} must be a constant expression; it uses '{}'", *constantContext_, n.name));
            return ValueType::Unknown;
        }
        auto it = names_.find(n.name);
        if (it == names_.end() && lobes_.count(n.name)) {
            diags_.error(n.loc, fmt::format("'{}' is a lobe, not a number; lobes appear only in 'bsdf = ...;'", n.name));
            return ValueType::Unknown;
        }
        if (it == names_.end()) {
            if (diags_.full()) return ValueType::Unknown;  // not reported anyway: skip the suggestion search
            std::vector<std::string> candidates;
            for (const auto& [name, info] : names_) candidates.push_back(name);
            std::string hint = suggestion(n.name, candidates);
            if (findBuiltinFunction(n.name))
                hint = fmt::format(" ('{}' is a function; call it with arguments)", n.name);
            diags_.error(n.loc, fmt::format("undefined name '{}'{}", n.name, hint));
            return ValueType::Unknown;
        }
        const NameInfo& info = it->second;
        if (info.statement >= current_) {
            diags_.error(n.loc, fmt::format("'{}' is used before its definition at {}", n.name, info.loc.str()));
            return ValueType::Unknown;
        }
        n.binding = info.kind;
        n.index = info.index;
        if (info.kind == BindingKind::Input) {
            if (info.index >= int(out_.inputs.size())) return ValueType::Unknown;  // its declaration failed
            return out_.inputs[info.index].type;
        }
        if (info.index >= int(out_.lets.size())) return ValueType::Unknown;
        return out_.lets[info.index].value->type;
    }

    ValueType typeCall(CallExpr& call) {
        const BuiltinFunction* fn = findBuiltinFunction(call.callee);
        if (!fn) {
            for (int s = 0; s < kModelSlotCount; ++s)
                if (findModel(ModelSlot(s), call.callee)) {
                    diags_.error(call.loc, fmt::format("'{}' is a {} model, not a function; write '{} = {}(...);'",
                                                       call.callee, modelSlotName(ModelSlot(s)),
                                                       modelSlotName(ModelSlot(s)), call.callee));
                    return ValueType::Unknown;
                }
            std::vector<std::string> candidates;
            for (const BuiltinFunction& f : builtinFunctions()) candidates.push_back(f.name);
            diags_.error(call.loc, fmt::format("unknown function '{}'{}", call.callee, suggestion(call.callee, candidates)));
            return ValueType::Unknown;
        }
        for (const Argument& a : call.args)
            if (!a.name.empty()) {
                diags_.error(a.nameLoc, fmt::format("function '{}' takes no named arguments", fn->name));
                return ValueType::Unknown;
            }
        if (int(call.args.size()) != fn->arity) {
            diags_.error(call.loc, fmt::format("function {} takes {} argument{}, got {}", fn->signature, fn->arity,
                                               fn->arity == 1 ? "" : "s", call.args.size()));
            return ValueType::Unknown;
        }
        ValueType result = ValueType::Float;
        for (size_t i = 0; i < call.args.size(); ++i) {
            ValueType t = typeOf(*call.args[i].value);
            if (fn->makesRgb && t == ValueType::Rgb) {
                diags_.error(call.args[i].value->loc,
                             fmt::format("argument {} of {} must be float, got rgb", i + 1, fn->signature));
                result = ValueType::Unknown;
            }
            result = promote(result, t);
        }
        call.function = fn;
        if (result == ValueType::Unknown) return result;
        return fn->makesRgb ? ValueType::Rgb : result;
    }

    const MaterialDecl& decl_;
    DiagnosticEngine& diags_;
    CheckedMaterial out_;
    std::map<std::string, NameInfo> names_;
    std::map<std::string, NameInfo> lobes_;  // index: into CheckedMaterial::lobes
    std::vector<std::string> lobeNames_;      // in source order
    std::vector<bool> duplicateStatements_;  // by statement index
    size_t current_ = 0;
    const std::string* constantContext_ = nullptr;
};

}  // namespace

CheckedProgram checkProgram(const Program& program, DiagnosticEngine& diags) {
    CheckedProgram out;
    out.file = program.file;
    std::map<std::string, SourceLoc> seen;
    for (const MaterialDecl& decl : program.materials) {
        auto [it, fresh] = seen.emplace(decl.name, decl.loc);
        if (!fresh)
            diags.error(decl.loc, fmt::format("duplicate material '{}'; first defined at {}", decl.name, it->second.str()));
        // A material that lost statements to syntax errors would only produce
        // follow-on errors (e.g. a missing ndf that was merely misspelled).
        if (decl.hasSyntaxErrors) continue;
        out.materials.push_back(MaterialChecker(decl, diags).run());
    }
    return out;
}

CheckedProgram loadProgramText(std::string_view text, const std::string& path, DiagnosticEngine& diags) {
    if (text.size() > kMaxSourceBytes) {
        diags.error({std::make_shared<const std::string>(path), 0, 0},
                    fmt::format("file is too large ({} bytes; the limit is {})", text.size(), kMaxSourceBytes));
        return {};
    }
    Program program = parseProgram(text, path, diags);
    CheckedProgram checked = checkProgram(program, diags);
    if (diags.hasErrors()) return {};
    return checked;
}

std::optional<std::string> readSourceFile(const std::string& path, std::string& error) {
    // O_NONBLOCK: opening a FIFO nobody writes to must not hang; reads
    // block again below, so a pipe (`facet check <(...)`) is read to its end.
    int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        error = errno == ENOENT ? "cannot open file" : fmt::format("cannot open file: {}", std::strerror(errno));
        return std::nullopt;
    }
    struct stat st;
    if (::fstat(fd, &st) != 0 || S_ISDIR(st.st_mode) || !(S_ISREG(st.st_mode) || S_ISFIFO(st.st_mode))) {
        error = S_ISDIR(st.st_mode) ? "is a directory, not a file"
                                    : "is a device or socket, not a file";
        ::close(fd);
        return std::nullopt;
    }
    ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    std::string text;
    char buffer[65536];
    for (;;) {
        ssize_t got = ::read(fd, buffer, sizeof buffer);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) {
            error = fmt::format("cannot read file: {}", std::strerror(errno));
            ::close(fd);
            return std::nullopt;
        }
        if (got == 0) break;
        if (text.size() + size_t(got) > kMaxSourceBytes) {
            error = fmt::format("file is too large (more than {} bytes)", kMaxSourceBytes);
            ::close(fd);
            return std::nullopt;
        }
        text.append(buffer, size_t(got));
    }
    ::close(fd);
    // A FIFO with no writer reads as empty at once (opened without
    // blocking, so that it cannot hang): say so rather than "no material".
    if (text.empty() && S_ISFIFO(st.st_mode)) {
        error = "is a FIFO (named pipe) and nothing was written to it";
        return std::nullopt;
    }
    return text;
}

CheckedProgram loadProgramFile(const std::string& path, DiagnosticEngine& diags) {
    std::string error;
    std::optional<std::string> text = readSourceFile(path, error);
    if (!text) {
        diags.error({std::make_shared<const std::string>(path), 0, 0}, error);
        return {};
    }
    return loadProgramText(*text, path, diags);
}

}  // namespace facet
