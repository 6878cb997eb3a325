// CompileOptions: the option strings of the C++ and C APIs (SPEC section 4),
// parsed and printed back in the canonical form the cache key uses, and
// their mapping to the lowering's options.
#include "Kernel.h"

#include <cmath>
#include <cstdlib>
#include <fmt/format.h>
#include <initializer_list>
#include <set>
#include <utility>

namespace facet {

const char* backendName(Backend b) {
    switch (b) {
        case Backend::Interp: return "interp";
        case Backend::Scalar: return "scalar";
        case Backend::Simd: return "simd";
    }
    return "?";
}

LoweringOptions loweringOptionsFor(const CompileOptions& options, const EnergyTable* energyTable, bool simd, int width) {
    LoweringOptions lowering;
    lowering.energyTable = energyTable;
    lowering.math = options.math;
    lowering.variant = options.math == MathMode::Fast ? MathVariant::fast() : MathVariant::exact();
    lowering.variant.floatFirst = options.floatFirst;
    lowering.trustInputs = options.assumeUnit;
    lowering.transport = options.transport;
    lowering.width = simd ? width : 4;
    lowering.emitScalar = !simd;
    lowering.emitBatch = simd;
    return lowering;
}

namespace {

std::optional<double> parseDouble(const std::string& s) {
    if (s.empty()) return std::nullopt;
    char* end = nullptr;
    double v = std::strtod(s.c_str(), &end);
    if (end != s.c_str() + s.size()) return std::nullopt;
    return v;
}

// An option that names one of a few values: sets `field` to the value
// `text` names, or returns the message that lists the names, in order
// ("width '7' is not 4, 8 or 16").
template <typename T>
std::string choose(const std::string& key, const std::string& text,
                   std::initializer_list<std::pair<const char*, T>> choices, T& field) {
    std::string names;
    size_t i = 0;
    for (const auto& [name, value] : choices) {
        if (text == name) {
            field = value;
            return "";
        }
        names += i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ";
        names += name;
        ++i;
    }
    return fmt::format("{} '{}' is not {}", key, text, names);
}

}  // namespace

std::string CompileOptions::parse(const std::string& spec, CompileOptions& out) {
    auto trim = [](std::string t) {
        t.erase(0, t.find_first_not_of(" \t"));
        t.erase(t.find_last_not_of(" \t") + 1);
        return t;
    };
    std::set<std::string> seen;
    size_t start = 0;
    while (start <= spec.size()) {
        size_t end = spec.find(';', start);
        std::string item = spec.substr(start, end == std::string::npos ? std::string::npos : end - start);
        start = end == std::string::npos ? spec.size() + 1 : end + 1;
        // Blanks around items, keys and values are allowed: "backend = simd ; math=fast".
        item = trim(item);
        if (item.empty()) continue;
        size_t eq = item.find('=');
        if (eq == std::string::npos) return fmt::format("option '{}' is not key=value", item);
        std::string key = trim(item.substr(0, eq)), value = trim(item.substr(eq + 1));
        // A repeated option is a mistake either way it would be resolved.
        if (!seen.insert(key).second) return fmt::format("option '{}' is given twice", key);
        std::string error;
        if (key == "backend") {
            error = choose(key, value, {{"scalar", Backend::Scalar}, {"simd", Backend::Simd}, {"interp", Backend::Interp}},
                           out.backend);
        } else if (key == "math") {
            error = choose(key, value, {{"exact", MathMode::Exact}, {"fast", MathMode::Fast}}, out.math);
        } else if (key == "tolerance") {
            auto v = parseDouble(value);
            if (!v || !(*v > 0) || !std::isfinite(*v)) return fmt::format("tolerance '{}' is not a positive number", value);
            out.tolerance = *v;
        } else if (key == "width") {
            error = choose(key, value, {{"4", 4}, {"8", 8}, {"16", 16}}, out.width);
        } else if (key == "float_first") {
            error = choose(key, value, {{"on", true}, {"off", false}}, out.floatFirst);
        } else if (key == "assume") {
            error = choose(key, value, {{"unit", true}, {"none", false}}, out.assumeUnit);
        } else if (key == "transport") {
            error = choose(key, value, {{"radiance", Transport::Radiance}, {"importance", Transport::Importance}},
                           out.transport);
        } else if (key == "codegen") {
            error = choose(key, value,
                           {{"tiered", Codegen::Tiered}, {"quick", Codegen::Quick}, {"optimized", Codegen::Optimized}},
                           out.codegen);
        } else if (key == "cache") {
            error = choose(key, value, {{"on", Cache::On}, {"off", Cache::Off}, {"memory", Cache::Memory}}, out.cache);
        } else if (key.rfind("set.", 0) == 0 && key.size() > 4) {
            std::vector<double> values;
            size_t p = 0;
            while (p <= value.size()) {
                size_t comma = value.find(',', p);
                std::string field = value.substr(p, comma == std::string::npos ? std::string::npos : comma - p);
                auto v = parseDouble(field);
                if (!v || !std::isfinite(*v)) return fmt::format("{}: '{}' is not a finite number", key, field);
                values.push_back(*v);
                p = comma == std::string::npos ? value.size() + 1 : comma + 1;
            }
            if (values.size() != 1 && values.size() != 3)
                return fmt::format("{}: expected one value or three (r,g,b)", key);
            out.bindings[key.substr(4)] = values;
        } else {
            return fmt::format("unknown option '{}' (known: backend, math, tolerance, width, cache, float_first, codegen, assume, transport, set.NAME)", key);
        }
        if (!error.empty()) return error;
    }
    return "";
}

std::string CompileOptions::canonical() const {
    std::string s = fmt::format("backend={};math={};width={}", backendName(backend), mathModeName(math), width);
    if (tolerance) s += fmt::format(";tolerance={}", *tolerance);
    if (!floatFirst) s += ";float_first=off";
    if (assumeUnit) s += ";assume=unit";
    if (codegen == Codegen::Quick) s += ";codegen=quick";
    if (transport == Transport::Importance) s += ";transport=importance";
    for (const auto& [name, values] : bindings) {
        s += ";set." + name + "=";
        for (size_t i = 0; i < values.size(); ++i) s += fmt::format("{}{}", i ? "," : "", values[i]);
    }
    return s;
}

}  // namespace facet
