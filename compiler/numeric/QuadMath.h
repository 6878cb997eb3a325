// QuadMath: __float128 (libquadmath) as a Real of the reference interpreter.
//
// The interpreter and the builtin semantics are templates written against
// std:: math (`using std::exp; exp(x)`), std::numeric_limits and
// std::complex. GCC 12's libstdc++ provides none of that for __float128
// (only std::abs), and a fundamental type has no associated namespace, so
// argument-dependent lookup cannot find overloads elsewhere. This header
// therefore declares, in namespace std:
//   - numeric_limits<__float128> (without it, infinity() would be 0 and the
//     interpreter would clamp every parameter to 0);
//   - the elementary functions the templates call, forwarding to libquadmath;
// and it must be included BEFORE any header that defines such a template
// (Builtins.h, Interpreter.h, <complex>): an unqualified call in a template
// sees only the overloads declared before the template's definition.
//
// std::complex<__float128> then works through libstdc++'s generic complex
// template (it is not one of the float/double/long double specializations,
// so sqrt and norm use the generic formulas built from the std::sqrt / abs
// declared here).
//
// Adding declarations to namespace std is formally reserved to the
// implementation; it is the only way to make the existing std-based
// templates work for __float128 on this toolchain, and it is confined to the
// translation units that include this header (Interpreter.cpp and the tools
// that need quad helpers). Link with libquadmath.
#pragma once

#include <quadmath.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace std {

template <>
struct numeric_limits<__float128> {
    static constexpr bool is_specialized = true;
    static constexpr bool is_signed = true;
    static constexpr bool is_integer = false;
    static constexpr bool is_exact = false;
    static constexpr bool has_infinity = true;
    static constexpr bool has_quiet_NaN = true;
    static constexpr bool has_signaling_NaN = true;
    static constexpr bool is_iec559 = true;
    static constexpr bool is_bounded = true;
    static constexpr bool is_modulo = false;
    static constexpr int digits = FLT128_MANT_DIG;  // 113
    static constexpr int digits10 = FLT128_DIG;     // 33
    static constexpr int max_digits10 = 36;
    static constexpr int radix = 2;
    static constexpr int min_exponent = FLT128_MIN_EXP;
    static constexpr int max_exponent = FLT128_MAX_EXP;
    static constexpr int min_exponent10 = FLT128_MIN_10_EXP;
    static constexpr int max_exponent10 = FLT128_MAX_10_EXP;
    static constexpr float_round_style round_style = round_to_nearest;
    static __float128 min() noexcept { return FLT128_MIN; }
    static __float128 max() noexcept { return FLT128_MAX; }
    static __float128 lowest() noexcept { return -FLT128_MAX; }
    static __float128 epsilon() noexcept { return FLT128_EPSILON; }
    static __float128 round_error() noexcept { return 0.5Q; }
    static __float128 denorm_min() noexcept { return FLT128_DENORM_MIN; }
    static __float128 infinity() noexcept { return __builtin_infq(); }
    static __float128 quiet_NaN() noexcept { return __builtin_nanq(""); }
    static __float128 signaling_NaN() noexcept { return __builtin_nansq(""); }
};

inline __float128 exp(__float128 x) { return expq(x); }
inline __float128 expm1(__float128 x) { return expm1q(x); }
inline __float128 log(__float128 x) { return logq(x); }
inline __float128 log1p(__float128 x) { return log1pq(x); }
inline __float128 sqrt(__float128 x) { return sqrtq(x); }
inline __float128 pow(__float128 x, __float128 y) { return powq(x, y); }
inline __float128 erf(__float128 x) { return erfq(x); }
inline __float128 erfc(__float128 x) { return erfcq(x); }
inline __float128 lgamma(__float128 x) { return lgammaq(x); }
inline __float128 sin(__float128 x) { return sinq(x); }
inline __float128 cos(__float128 x) { return cosq(x); }
inline __float128 tan(__float128 x) { return tanq(x); }
inline __float128 acos(__float128 x) { return acosq(x); }
inline __float128 asin(__float128 x) { return asinq(x); }
inline __float128 atan(__float128 x) { return atanq(x); }
inline __float128 atan2(__float128 y, __float128 x) { return atan2q(y, x); }
inline __float128 hypot(__float128 x, __float128 y) { return hypotq(x, y); }
inline __float128 fabs(__float128 x) { return fabsq(x); }
inline __float128 floor(__float128 x) { return floorq(x); }
inline __float128 fma(__float128 x, __float128 y, __float128 z) { return fmaq(x, y, z); }
inline __float128 ceil(__float128 x) { return ceilq(x); }
inline __float128 fmod(__float128 x, __float128 y) { return fmodq(x, y); }
inline __float128 ldexp(__float128 x, int e) { return ldexpq(x, e); }
inline __float128 copysign(__float128 x, __float128 y) { return copysignq(x, y); }
inline __float128 fmin(__float128 x, __float128 y) { return fminq(x, y); }
inline __float128 fmax(__float128 x, __float128 y) { return fmaxq(x, y); }
inline bool isnan(__float128 x) { return isnanq(x) != 0; }
inline bool isinf(__float128 x) { return isinfq(x) != 0; }
inline bool isfinite(__float128 x) { return finiteq(x) != 0; }
inline bool signbit(__float128 x) { return signbitq(x) != 0; }
// std::abs(__float128) is already provided by libstdc++ (bits/std_abs.h).

}  // namespace std

namespace facet {

// Decimal text of a __float128 (for reports and test messages).
inline std::string quadToString(__float128 x, int digits = 36) {
    char buf[64];
    quadmath_snprintf(buf, sizeof buf, "%.*Qg", digits, x);
    return buf;
}

}  // namespace facet

// After the declarations above, so that std::complex's generic formulas see them.
#include <complex>
