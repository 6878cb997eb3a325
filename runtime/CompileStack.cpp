// CompileStack: running LLVM's stages on a large stack (CompileStack.h).
#include "CompileStack.h"

#include <ctime>
#include <exception>
#include <pthread.h>

namespace facet {

namespace {

struct StackJob {
    const std::function<void()>* work;
    std::exception_ptr error;
    double cpuNanos = 0;  // the job thread's CPU time, read as it ends
};

double threadCpuNanos() {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) * 1e9 + double(ts.tv_nsec);
}

// CPU time of the compile-stack threads this thread has waited for.
thread_local double tWaitedForNanos = 0;

void* runJob(void* arg) {
    auto* job = static_cast<StackJob*>(arg);
    try {
        (*job->work)();
    } catch (...) {
        job->error = std::current_exception();
    }
    job->cpuNanos = threadCpuNanos();
    return nullptr;
}

}  // namespace

void onCompileStack(const std::function<void()>& work) {
    StackJob job{&work, nullptr};
    pthread_attr_t attr;
    bool started = false;
    pthread_t thread;
    if (::pthread_attr_init(&attr) == 0) {
        started = ::pthread_attr_setstacksize(&attr, kCompileStackBytes) == 0 &&
                  ::pthread_create(&thread, &attr, &runJob, &job) == 0;
        ::pthread_attr_destroy(&attr);
    }
    if (!started) {
        // Out of threads or address space: the caller's stack is all there is.
        work();
        return;
    }
    ::pthread_join(thread, nullptr);
    tWaitedForNanos += job.cpuNanos;
    if (job.error) std::rethrow_exception(job.error);
}

double callerCpuNanos() { return threadCpuNanos() + tWaitedForNanos; }

}  // namespace facet
