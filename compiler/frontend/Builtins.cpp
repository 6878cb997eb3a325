// Builtins: the tables themselves.
#include "Builtins.h"

#include "Immortal.h"


namespace facet {

const std::vector<BuiltinFunction>& builtinFunctions() {
    static const std::vector<BuiltinFunction>& table = immortal<std::vector<BuiltinFunction>>(std::vector<BuiltinFunction>{
        {BuiltinFn::Rgb, "rgb", 3, true, "rgb(r, g, b)", 0},
        {BuiltinFn::Sqrt, "sqrt", 1, false, "sqrt(x)", 2},
        {BuiltinFn::Pow, "pow", 2, false, "pow(x, y)", 200},
        {BuiltinFn::Exp, "exp", 1, false, "exp(x)", 100},
        {BuiltinFn::Log, "log", 1, false, "log(x)", 100},
        {BuiltinFn::Abs, "abs", 1, false, "abs(x)", 1},
        {BuiltinFn::Min, "min", 2, false, "min(a, b)", 2},
        {BuiltinFn::Max, "max", 2, false, "max(a, b)", 2},
        {BuiltinFn::Clamp, "clamp", 3, false, "clamp(x, lo, hi)", 4},
        {BuiltinFn::Mix, "mix", 3, false, "mix(a, b, t)", 3},
        {BuiltinFn::PhongExponent, "phong_exponent", 1, false, "phong_exponent(roughness)", 4},
        {BuiltinFn::BeckmannToPhong, "beckmann_to_phong", 1, false, "beckmann_to_phong(alpha)", 3},
    });
    return table;
}

const BuiltinFunction* findBuiltinFunction(std::string_view name) {
    for (const BuiltinFunction& f : builtinFunctions())
        if (name == f.name) return &f;
    return nullptr;
}

}  // namespace facet
