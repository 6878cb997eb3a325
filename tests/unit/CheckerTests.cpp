// Checker unit tests: types and promotion, input slots and their names,
// lets that use lets, the material rules, exact diagnostics, and
// independence of two compilations in one process.
//
// Slots are the ABI between the compiler and its callers (the C API's
// facet_input_count / facet_input_name and the CSV columns of `facet eval`),
// so their order and names ("tint.r") are pinned here exactly.
#include "Checker.h"
#include "ComputeCost.h"
#include "Interpreter.h"
#include "TestUtil.h"

#include <doctest/doctest.h>

#include <atomic>
#include <cmath>
#include <fmt/format.h>
#include <string>
#include <thread>
#include <vector>

using namespace facet;
using namespace facet::test;

namespace {

// Checks `source`; fails the test with the diagnostics if there are any.
CheckedProgram mustCheck(const std::string& source) {
    DiagnosticEngine diags;
    CheckedProgram prog = loadProgramText(source, "t.mat", diags);
    REQUIRE_MESSAGE(!diags.hasErrors(), diags.str());
    REQUIRE(!prog.materials.empty());
    return prog;
}

const CheckedLet& letNamed(const CheckedMaterial& m, const std::string& name) {
    for (const CheckedLet& l : m.lets)
        if (l.name == name) return l;
    FAIL("no let named " << name);
    return m.lets.front();
}

}  // namespace

TEST_SUITE("checker") {

TEST_CASE("expression types: float, rgb, and float promoting to rgb") {
    CheckedProgram prog = mustCheck(inMaterial(
        "input t = rgb(0.1, 0.2, 0.3);\n"
        "let f = 2 * 3 - 1;\n"
        "let c = t * 2;\n"             // rgb * float -> rgb
        "let d = 0.5 + c;\n"           // float + rgb -> rgb
        "let s = sqrt(f);\n"           // float function of a float
        "let m = max(t, 0.5);\n"       // channel-wise function, one rgb argument
        "let k = rgb(f, f, 1);\n"      // rgb from floats
        "let p = f ^ 2;\n"
        "ndf = ggx(f / 10);\n"
        "fresnel = schlick(f0 = 0.04);\n"  // float where rgb is expected
        "diffuse = lambert(0.5);"));
    const CheckedMaterial& m = prog.materials[0];
    CHECK(letNamed(m, "f").value->type == ValueType::Float);
    CHECK(letNamed(m, "c").value->type == ValueType::Rgb);
    CHECK(letNamed(m, "d").value->type == ValueType::Rgb);
    CHECK(letNamed(m, "s").value->type == ValueType::Float);
    CHECK(letNamed(m, "m").value->type == ValueType::Rgb);
    CHECK(letNamed(m, "k").value->type == ValueType::Rgb);
    CHECK(letNamed(m, "p").value->type == ValueType::Float);
    CHECK(m.inputs[0].type == ValueType::Rgb);
    CHECK(std::string(m.singleLobe().fresnel.model->name) == "schlick");
    CHECK(std::string(m.singleLobe().diffuse.model->name) == "lambert");
}

TEST_CASE("rgb where a float is required is a type error") {
    CHECK(checkErrors(inMaterial("input t = rgb(1, 1, 1);\nndf = ggx(t);")) ==
          std::vector<std::string>{"t.mat:3:11: error: argument 'alpha' of ndf 'ggx' must be float, got rgb"});
    CHECK(checkErrors(inMaterial("let a = rgb(rgb(1, 1, 1), 1, 1);\nndf = ggx(1);")) ==
          std::vector<std::string>{"t.mat:2:13: error: argument 1 of rgb(r, g, b) must be float, got rgb"});
    CHECK(checkErrors(inMaterial("input t = rgb(1, 1, 1);\nndf = blinn_phong(exponent = t * 2);")) ==
          std::vector<std::string>{
              "t.mat:3:32: error: argument 'exponent' of ndf 'blinn_phong' must be float, got rgb"});
}

TEST_CASE("slots: a float input takes one, an rgb input three, named name.r/.g/.b") {
    CheckedProgram prog = mustCheck(inMaterial(
        "input roughness = 0.35 in 0 .. 1;\n"
        "input tint = rgb(0.9, 0.8, 0.7);\n"
        "input gain = 2;\n"
        "ndf = ggx(roughness * gain);\n"
        "diffuse = lambert(tint);"));
    const CheckedMaterial& m = prog.materials[0];
    CHECK(m.slotCount == 5);
    REQUIRE(m.inputs.size() == 3);
    CHECK(m.inputs[0].firstSlot == 0);
    CHECK(m.inputs[0].slotCount() == 1);
    CHECK(m.inputs[1].firstSlot == 1);
    CHECK(m.inputs[1].slotCount() == 3);
    CHECK(m.inputs[2].firstSlot == 4);
    std::vector<std::string> names;
    for (int s = 0; s < m.slotCount; ++s) names.push_back(m.slotName(s));
    CHECK(names == std::vector<std::string>{"roughness", "tint.r", "tint.g", "tint.b", "gain"});
    CHECK(m.defaultSlots() == std::vector<double>{0.35, 0.9, 0.8, 0.7, 2});
    CHECK(m.inputs[0].hasRange);
    CHECK(m.inputs[0].lo == 0);
    CHECK(m.inputs[0].hi == 1);
    CHECK(!m.inputs[2].hasRange);
    CHECK(m.findInput("tint") == &m.inputs[1]);
    CHECK(m.findInput("tint.r") == nullptr);  // a slot name, not an input name
    CHECK(m.slotName(5).empty());
}

TEST_CASE("a float default fills all three channels of the value; rgb defaults keep theirs") {
    CheckedProgram prog = mustCheck(inMaterial("input a = 0.25;\ninput c = rgb(1, 2 * 2, 3^2);\nndf = ggx(a);"));
    const CheckedMaterial& m = prog.materials[0];
    CHECK(m.inputs[0].defaultValue == std::array<double, 3>{0.25, 0.25, 0.25});
    CHECK(m.inputs[1].defaultValue == std::array<double, 3>{1, 4, 9});
}

TEST_CASE("lets may use earlier lets and inputs; the interpreter sees the right one") {
    // alpha = (r * r + r) / 2 = 0.375 for r = 0.5; each let refers back by
    // index, so a wrong binding index would change the value.
    CheckedProgram prog = mustCheck(inMaterial(
        "input r = 0.5;\n"
        "let unused = 100;\n"
        "let sq = r * r;\n"
        "let sum = sq + r;\n"
        "let alpha = sum / 2;\n"
        "ndf = ggx(alpha);"));
    const CheckedMaterial& m = prog.materials[0];
    REQUIRE(m.lets.size() == 4);
    Interpreter<double> interp(m);
    ResolvedMaterial<double> r = interp.resolve(nullptr);
    CHECK(r.ndfArgs[0] == doctest::Approx(0.375).epsilon(1e-15));
    CHECK(r.ndfArgs[1] == doctest::Approx(0.375).epsilon(1e-15));
    double slots[1] = {0.2};  // per-evaluation input: (0.04 + 0.2) / 2
    CHECK(interp.resolve(slots).ndfArgs[0] == doctest::Approx(0.12).epsilon(1e-15));
}

TEST_CASE("names: used before definition, undefined with a suggestion, functions as names") {
    CHECK(checkErrors(inMaterial("let x = y;\nlet y = 1;\nndf = ggx(x);")) ==
          std::vector<std::string>{"t.mat:2:9: error: 'y' is used before its definition at t.mat:3:5"});
    CHECK(checkErrors(inMaterial("input roughness = 0.5;\nndf = ggx(rougness);")) ==
          std::vector<std::string>{"t.mat:3:11: error: undefined name 'rougness' (did you mean 'roughness'?)"});
    CHECK(checkErrors(inMaterial("let a = sqrt;\nndf = ggx(a);")) ==
          std::vector<std::string>{
              "t.mat:2:9: error: undefined name 'sqrt' ('sqrt' is a function; call it with arguments)"});
    CHECK(checkErrors(inMaterial("let a = a;\nndf = ggx(1);")) ==
          std::vector<std::string>{"t.mat:2:9: error: 'a' is used before its definition at t.mat:2:5"});
}

TEST_CASE("input defaults and bounds must be finite constants inside the range") {
    CHECK(checkErrors(inMaterial("input a = 0.5;\ninput b = a;\nndf = ggx(b);")) ==
          std::vector<std::string>{
              "t.mat:3:11: error: the default value of input 'b' must be a constant expression; it uses 'a'"});
    CHECK(checkErrors(inMaterial("input a = 2 in 0 .. 1;\nndf = ggx(a);")) ==
          std::vector<std::string>{"t.mat:2:11: error: default value 2 of input 'a' is outside its range 0 .. 1"});
    CHECK(checkErrors(inMaterial("input a = 0.5 in 1 .. 0;\nndf = ggx(a);")) ==
          std::vector<std::string>{
              "t.mat:2:18: error: empty range 1 .. 0 for input 'a' (lower bound is above the upper bound)"});
    CHECK(checkErrors(inMaterial("input a = 1 / 0;\nndf = ggx(a);")) ==
          std::vector<std::string>{"t.mat:2:13: error: the default value of input 'a' is not a finite number ((1 / 0))"});
    CHECK(checkErrors(inMaterial("input c = rgb(0.5, 0.5, 0.5) in rgb(0, 0, 0) .. 1;\nndf = ggx(1);")) ==
          std::vector<std::string>{"t.mat:2:33: error: range bound of input 'c' must be float, got rgb"});
    // An rgb default is checked channel by channel against a float range.
    CHECK(checkErrors(inMaterial("input c = rgb(0.5, 1.5, 0.5) in 0 .. 1;\nndf = ggx(1);")) ==
          std::vector<std::string>{
              "t.mat:2:11: error: default value 1.5 of input 'c' is outside its range 0 .. 1"});
}

TEST_CASE("material rules: ndf required, no duplicates, masking the NDF supports") {
    CHECK(checkErrors(inMaterial("masking = none;")) ==
          std::vector<std::string>{"t.mat:1:10: error: material 'm' has no 'ndf' statement; every material needs one, "
                                   "e.g. 'ndf = ggx(0.3);'"});
    CHECK(checkErrors(inMaterial("ndf = ggx(0.1);\nndf = beckmann(0.1);")) ==
          std::vector<std::string>{"t.mat:3:1: error: duplicate 'ndf' statement; first given at t.mat:2:1"});
    CHECK(checkErrors(inMaterial("input a = 1;\nlet a = 2;\nndf = ggx(a);")) ==
          std::vector<std::string>{"t.mat:3:5: error: duplicate definition of 'a'; first defined at t.mat:2:7"});
    CHECK(checkErrors("material m { ndf = ggx(1); }\nmaterial m { ndf = ggx(1); }") ==
          std::vector<std::string>{"t.mat:2:10: error: duplicate material 'm'; first defined at t.mat:1:10"});
    CHECK(checkErrors(inMaterial("ndf = ward(0.1, 0.2);\nmasking = smith_height_correlated;")) ==
          std::vector<std::string>{"t.mat:3:11: error: ndf 'ward' is a whole BRDF lobe with its own normalization; it "
                                   "requires 'masking = none', not 'smith_height_correlated'"});
    // Every other NDF has a Smith Lambda, closed-form or tabulated.
    mustCheck(inMaterial("ndf = gaussian(0.1);\nmasking = smith_separable;"));
    // Any NDF with a non-Smith masking is fine.
    mustCheck(inMaterial("ndf = gtr(0.1, 2);\nmasking = cook_torrance;"));
    mustCheck(inMaterial("ndf = gaussian(0.3);\nmasking = schlick_smith(0.2);"));
}

TEST_CASE("model arguments: unknown models and arguments, arity, named forms") {
    CHECK(checkErrors(inMaterial("ndf = ggz(0.1);")) ==
          std::vector<std::string>{"t.mat:2:7: error: unknown ndf model 'ggz' (did you mean 'ggx'?)"});
    CHECK(checkErrors(inMaterial("ndf = ggx(alhpa = 0.1);")) ==
          std::vector<std::string>{"t.mat:2:11: error: unknown argument 'alhpa' for ndf 'ggx' (did you mean 'alpha'?)"});
    CHECK(checkErrors(inMaterial("ndf = ggx(0.1, 0.2, 0.3);")) ==
          std::vector<std::string>{
              "t.mat:2:11: error: ndf 'ggx' takes (alpha) or (alpha_x and alpha_y), got 3 arguments"});
    CHECK(checkErrors(inMaterial("ndf = ggx(0.1);\nfresnel = conductor(k = 1);")) ==
          std::vector<std::string>{"t.mat:3:11: error: missing argument 'eta' for fresnel 'conductor'"});
    CHECK(checkErrors(inMaterial("ndf = ggx(alpha_x = 0.1, 0.2);")) ==
          std::vector<std::string>{"t.mat:2:26: error: positional argument after a named argument in ndf 'ggx'"});
    CHECK(checkErrors(inMaterial("ndf = ggx(0.1);\ndiffuse = lambert(albedo = 0.5, albedo = 0.5);")) ==
          std::vector<std::string>{"t.mat:3:33: error: argument 'albedo' of diffuse 'lambert' given twice"});
    CHECK(checkErrors(inMaterial("let a = sqrt(1, 2);\nndf = ggx(a);")) ==
          std::vector<std::string>{"t.mat:2:9: error: function sqrt(x) takes 1 argument, got 2"});
    // Named arguments in any order land in canonical order.
    CheckedProgram prog = mustCheck(inMaterial("ndf = ggx(alpha_y = 0.2, alpha_x = 0.1);"));
    const CheckedMaterial& m = prog.materials[0];
    CHECK(!m.singleLobe().ndf.isotropic);
    ResolvedMaterial<double> r = Interpreter<double>(m).resolve(nullptr);
    CHECK(r.ndfArgs[0] == 0.1);
    CHECK(r.ndfArgs[1] == 0.2);
    // One alpha fills both and marks the NDF isotropic; the alias resolves to ggx.
    CheckedProgram iso = mustCheck(inMaterial("ndf = trowbridge_reitz(alpha = 0.3);"));
    CHECK(iso.materials[0].singleLobe().ndf.isotropic);
    CHECK(std::string(iso.materials[0].singleLobe().ndf.model->name) == "ggx");
}

TEST_CASE("omitted slots default to none") {
    CheckedProgram prog = mustCheck("material m { ndf = beckmann(0.2); }");
    const CheckedMaterial& m = prog.materials[0];
    CHECK(std::string(m.singleLobe().masking.model->name) == "none");
    CHECK(std::string(m.singleLobe().fresnel.model->name) == "none");
    CHECK(std::string(m.singleLobe().energy.model->name) == "none");
    CHECK(std::string(m.singleLobe().diffuse.model->name) == "none");
}

TEST_CASE("diagnostics: rendering, ordering, the error limit, the whole-file form") {
    // Rendering is exactly "file:line:col: error: message".
    // (Built field by field: gcc 12 warns falsely on the nested aggregate form.)
    Diagnostic d;
    d.loc.file = std::make_shared<const std::string>("a/b.mat");
    d.loc.line = 3;
    d.loc.col = 7;
    d.message = "bad thing";
    CHECK(d.str() == "a/b.mat:3:7: error: bad thing");
    d.loc.line = d.loc.col = 0;  // line 0: no location, a whole-file problem
    d.message = "cannot open file";
    CHECK(d.str() == "a/b.mat: error: cannot open file");

    // str() lists errors top to bottom even though checker errors (line 2)
    // are found after parser errors (line 3).
    DiagnosticEngine diags;
    loadProgramText("material m {\n ndf = ggx(nope);\n}\nmaterial n { let = 1; }\n", "t.mat", diags);
    CHECK(diags.str() ==
          "t.mat:2:12: error: undefined name 'nope'\n"
          "t.mat:4:18: error: expected a name after 'let', found '='\n");

    // 60 independent mistakes: 50 reported, then one note, then silence.
    std::string body;
    for (int i = 0; i < 60; ++i) body += "let a" + std::to_string(i) + " = undefined_" + std::to_string(i) + ";\n";
    auto errors = checkErrors(inMaterial(body + "ndf = ggx(1);"));
    REQUIRE(errors.size() == DiagnosticEngine::kMaxErrors + 1);
    CHECK(errors.back().find("too many errors (50), stopping") != std::string::npos);

    // Too large a file is one whole-file diagnostic, without a location.
    std::string big(kMaxSourceBytes + 1, ' ');
    CHECK(checkErrors(big) ==
          std::vector<std::string>{fmt::format("t.mat: error: file is too large ({} bytes; the limit is {})",
                                               kMaxSourceBytes + 1, kMaxSourceBytes)});
    // A file that does not exist.
    DiagnosticEngine missing;
    loadProgramFile("/nonexistent/dir/x.mat", missing);
    CHECK(rendered(missing) == std::vector<std::string>{"/nonexistent/dir/x.mat: error: cannot open file"});
}

TEST_CASE("CompileError carries the diagnostics it was made from") {
    DiagnosticEngine diags;
    loadProgramText(inMaterial("ndf = ggz(1);"), "t.mat", diags);
    CompileError e(diags);
    CHECK(std::string(e.what()) == diags.str());
    REQUIRE(e.diagnostics.size() == 1);
    CHECK(e.diagnostics[0].loc.line == 2);
}

TEST_CASE("two compilations in one process do not interfere") {
    // Interleaved: a bad file and a good file, each with its own engine.
    DiagnosticEngine badDiags, goodDiags;
    CheckedProgram bad = loadProgramText(inMaterial("ndf = ggz(1);"), "bad.mat", badDiags);
    CheckedProgram good = loadProgramText(inMaterial("input r = 0.5;\nndf = ggx(r);"), "good.mat", goodDiags);
    CheckedProgram bad2 = loadProgramText(inMaterial("ndf = ggx(1);\nndf = ggx(1);"), "bad2.mat", badDiags);
    CHECK(!goodDiags.hasErrors());
    CHECK(rendered(badDiags) ==
          std::vector<std::string>{"bad.mat:2:7: error: unknown ndf model 'ggz' (did you mean 'ggx'?)",
                                   "bad2.mat:3:1: error: duplicate 'ndf' statement; first given at bad2.mat:2:1"});
    CHECK(bad.materials.empty());
    REQUIRE(good.materials.size() == 1);
    CHECK(*good.materials[0].loc.file == "good.mat");
    CHECK(good.materials[0].slotCount == 1);

    // Concurrently: each thread compiles its own text many times and must
    // always see exactly its own diagnostics (no shared mutable state).
    std::atomic<int> mismatches{0};
    auto worker = [&](int id) {
        std::string file = "thread" + std::to_string(id) + ".mat";
        std::string src = id % 2 ? inMaterial("ndf = ggx(x" + std::to_string(id) + ");")
                                 : inMaterial("input r = 0." + std::to_string(id + 1) + ";\nndf = ggx(r);");
        std::string expected =
            id % 2 ? file + ":2:11: error: undefined name 'x" + std::to_string(id) + "'\n" : std::string();
        for (int i = 0; i < 200; ++i) {
            DiagnosticEngine diags;
            CheckedProgram p = loadProgramText(src, file, diags);
            if (diags.str() != expected) ++mismatches;
            if (!(id % 2) && (p.materials.size() != 1 || p.materials[0].defaultSlots()[0] != (id + 1) / 10.0))
                ++mismatches;
        }
    };
    std::vector<std::thread> threads;
    for (int id = 0; id < 4; ++id) threads.emplace_back(worker, id);
    for (auto& t : threads) t.join();
    CHECK(mismatches == 0);
}

}  // TEST_SUITE

TEST_CASE("compute budget: what a material computes is bounded, at the statement that passes it") {
    // A let chain: 20 for reading r, then one addition per let.
    auto chain = [](int lets) {
        std::string body = "input r = 0.5 in 0 .. 1;\nlet a0 = r;\n";
        for (int i = 1; i < lets; ++i) body += fmt::format("let a{} = a{} + 1e-6;\n", i, i - 1);
        return inMaterial(body + fmt::format("ndf = ggx(a{});", lets - 1));
    };
    CHECK(checkErrors(chain(3900)).empty());
    std::vector<std::string> errors = checkErrors(chain(100000));
    REQUIRE(errors.size() == 1);
    // 20 + 3980 = 4000 at a3980; a3981 passes it (inMaterial puts the body on line 2).
    CHECK(errors[0].rfind("t.mat:3984:", 0) == 0);
    CHECK(errors[0].find("material 'm' computes too much to compile: at let 'a3981' its inputs, lets and model "
                         "arguments already cost more than 4000 float operations") != std::string::npos);

    // An rgb mix costs three per channel; exp 100, pow 200, x^k with a small integer k 8.
    CHECK(computeCost(*mustCheck(inMaterial("let c = mix(rgb(1, 2, 3), rgb(0, 0, 0), 0.5); ndf = ggx(0.3);"))
                           .materials[0].lets[0].value) == 9);
    const CheckedMaterial costs =
        mustCheck(inMaterial("input t = 0.5; let e = exp(t); let p = pow(t, 1.5); let q = t ^ 3; let s = -t;"
                             "ndf = ggx(0.3);"))
            .materials[0];
    CHECK(computeCost(*costs.lets[0].value) == 100);
    CHECK(computeCost(*costs.lets[1].value) == 200);
    CHECK(computeCost(*costs.lets[2].value) == 8);
    CHECK(computeCost(*costs.lets[3].value) == 1);

    // Each input read counts 20: 201 inputs read are refused at the 201st.
    std::string many, sums = "let s0 = u0;\n";
    for (int i = 0; i < 201; ++i) many += fmt::format("input u{} = 0.5;\n", i);
    for (int i = 1; i < 201; ++i) sums += fmt::format("let s{} = s{} + u{};\n", i, i - 1, i);
    errors = checkErrors(inMaterial(many + sums + "ndf = ggx(clamp(s200, 0.01, 1));"));
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].find("at input 'u200'") != std::string::npos);

    // What the models do not read costs nothing: 10000 unused inputs and a
    // dead let chain past the budget are accepted.
    std::string unused;
    for (int i = 0; i < 10000; ++i) unused += fmt::format("input u{} = 0.5;\n", i);
    CHECK(checkErrors(inMaterial(unused + "ndf = ggx(0.3);")).empty());
    std::string dead = "input r = 0.5;\nlet d0 = r;\n";
    for (int i = 1; i < 5000; ++i) dead += fmt::format("let d{} = d{} * 2;\n", i, i - 1);
    CHECK(checkErrors(inMaterial(dead + "ndf = ggx(0.3);")).empty());
}

TEST_CASE("readByModels: the inputs and lets the model arguments reach, through lets") {
    const CheckedMaterial m = mustCheck(inMaterial("input a = 0.5; input b = rgb(1, 1, 1); input unused = 1;\n"
                                                   "let x = a * 2; let y = x + b; let dead = unused + a;\n"
                                                   "ndf = ggx(0.3); diffuse = lambert(y);"))
                                  .materials[0];
    CheckedMaterial::Reads reads = m.readByModels();
    CHECK(reads.inputs == std::vector<bool>{true, true, false});
    CHECK(reads.lets == std::vector<bool>{true, true, false});
    // The interpreter agrees: a NaN in the unread input leaves the lane valid,
    // a NaN in a read one does not.
    Interpreter<double> interp(m);
    const double wi[3] = {0, 0, 1}, wo[3] = {0.6, 0, 0.8};
    double slots[5] = {0.5, 1, 1, 1, std::nan("")};
    CHECK(interp.eval(wi, wo, slots).valid);
    slots[0] = std::nan("");
    slots[4] = 1;
    CHECK(!interp.eval(wi, wo, slots).valid);
}
