// CompileStack: running LLVM's stages on a large stack (CompileStack.h).
#include "CompileStack.h"

#include <exception>
#include <pthread.h>

namespace facet {

namespace {

struct StackJob {
    const std::function<void()>* work;
    std::exception_ptr error;
};

void* runJob(void* arg) {
    auto* job = static_cast<StackJob*>(arg);
    try {
        (*job->work)();
    } catch (...) {
        job->error = std::current_exception();
    }
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
    if (job.error) std::rethrow_exception(job.error);
}

}  // namespace facet
