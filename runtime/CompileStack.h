// CompileStack: LLVM's work on a stack of Facet's own size.
//
// LLVM's passes recurse over the IR (Reassociate over expression trees, the
// DAG scheduler over dependence chains), so how deep they go grows with the
// material: a let chain of 3900 additions, which the checker accepts
// (ComputeCost.h), needs more than the 256 KiB a host's worker thread may
// have. A kernel compile is called on whatever thread the host uses, so the
// pipeline's LLVM stages run on a thread of their own with kCompileStackBytes
// of stack (address space; only the pages touched are committed), and the
// calling thread waits for it. Thread creation costs tens of microseconds
// against milliseconds of compile.
//
// Because the work moves to another thread, a per-thread CPU clock of the
// caller would not see it (the caller sleeps in pthread_join): callerCpuNanos
// counts the compile-stack threads a thread waited for as its own time, and
// every compile time Facet reports (the tier-up time, `facet bench`) reads it.
#pragma once

#include <cstddef>
#include <functional>

namespace facet {

constexpr size_t kCompileStackBytes = size_t(64) << 20;

// Runs `work` on a fresh thread with kCompileStackBytes of stack and waits
// for it; an exception `work` throws is rethrown here. If no such thread can
// be created, runs `work` on the calling thread.
void onCompileStack(const std::function<void()>& work);

// CPU time of the calling thread in nanoseconds (CLOCK_THREAD_CPUTIME_ID)
// plus the CPU time of every compile-stack thread it has waited for.
double callerCpuNanos();

}  // namespace facet
