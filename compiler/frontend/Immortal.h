// Immortal: process-wide state that exit() never destroys.
//
// A Compiler may itself be a static (the C API's, a renderer plugin's, a
// test runner's). exit() destroys statics in the reverse order of their
// construction, so every function-local static Facet creates lazily after
// that Compiler (the model catalog and its emitters, the builtin table, the
// table caches in memory, the quadrature rules, ...) would be destroyed
// before it, while the Compiler's tier-up thread may still be running the
// pipeline on them: the Compiler's destructor, which joins that thread and
// finishes the tier-ups that fill the disk cache, runs last.
//
// So such state is created with immortal<T>(args...) and held by reference:
//
//   static const NdfEntry& entry = immortal<NdfEntry>(makeEntry());
//
// The object is allocated once and never freed; the static is a reference,
// which has nothing to destroy. It stays reachable, so leak checkers do not
// report it. Statics of trivially destructible types (pointers, numbers,
// std::once_flag, std::atomic) need none of this.
#pragma once

#include <utility>

namespace facet {

template <typename T, typename... Args>
T& immortal(Args&&... args) {
    return *new T(std::forward<Args>(args)...);
}

}  // namespace facet
