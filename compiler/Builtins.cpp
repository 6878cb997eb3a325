// Builtins: the tables themselves.
#include "Builtins.h"

#include "Immortal.h"


namespace facet {

const std::vector<BuiltinFunction>& builtinFunctions() {
    static const std::vector<BuiltinFunction>& table = immortal<std::vector<BuiltinFunction>>(std::vector<BuiltinFunction>{
        {BuiltinFn::Rgb, "rgb", 3, true, "rgb(r, g, b)"},
        {BuiltinFn::Sqrt, "sqrt", 1, false, "sqrt(x)"},
        {BuiltinFn::Pow, "pow", 2, false, "pow(x, y)"},
        {BuiltinFn::Exp, "exp", 1, false, "exp(x)"},
        {BuiltinFn::Log, "log", 1, false, "log(x)"},
        {BuiltinFn::Abs, "abs", 1, false, "abs(x)"},
        {BuiltinFn::Min, "min", 2, false, "min(a, b)"},
        {BuiltinFn::Max, "max", 2, false, "max(a, b)"},
        {BuiltinFn::Clamp, "clamp", 3, false, "clamp(x, lo, hi)"},
        {BuiltinFn::Mix, "mix", 3, false, "mix(a, b, t)"},
        {BuiltinFn::PhongExponent, "phong_exponent", 1, false, "phong_exponent(roughness)"},
        {BuiltinFn::BeckmannToPhong, "beckmann_to_phong", 1, false, "beckmann_to_phong(alpha)"},
    });
    return table;
}

const BuiltinFunction* findBuiltinFunction(std::string_view name) {
    for (const BuiltinFunction& f : builtinFunctions())
        if (name == f.name) return &f;
    return nullptr;
}

}  // namespace facet
