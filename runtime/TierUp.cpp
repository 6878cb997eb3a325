// TierUp: the tier-up worker and its fork handlers (TierUp.h).
#include "TierUp.h"

#include "Immortal.h"

#include <pthread.h>
#include <set>

namespace facet {

// Every live worker, for the fork handlers, which are process-wide. Immortal:
// a worker may be destroyed during exit(), after static destructors ran.
struct TierUpForkHooks {
    std::mutex mutex;
    std::set<TierUpWorker*> workers;

    static TierUpForkHooks& get() {
        static TierUpForkHooks& hooks = immortal<TierUpForkHooks>();
        static std::once_flag registered;
        std::call_once(registered, [] { ::pthread_atfork(&prepare, &parent, &child); });
        return hooks;
    }
    // Lock order: the registry, then each worker's mutex_ (registration takes
    // only the registry, and no worker takes the registry under mutex_).
    static void prepare() {
        TierUpForkHooks& h = get();
        h.mutex.lock();
        for (TierUpWorker* w : h.workers) w->holdForFork();
    }
    static void parent() {
        TierUpForkHooks& h = get();
        for (TierUpWorker* w : h.workers) w->releaseAfterFork(false);
        h.mutex.unlock();
    }
    static void child() {
        TierUpForkHooks& h = get();
        for (TierUpWorker* w : h.workers) w->releaseAfterFork(true);
        h.mutex.unlock();
    }
};

TierUpWorker::TierUpWorker() {
    TierUpForkHooks& hooks = TierUpForkHooks::get();
    std::lock_guard<std::mutex> lock(hooks.mutex);
    hooks.workers.insert(this);
}

TierUpWorker::~TierUpWorker() {
    {
        TierUpForkHooks& hooks = TierUpForkHooks::get();
        std::lock_guard<std::mutex> lock(hooks.mutex);
        hooks.workers.erase(this);
    }
    {
        std::lock_guard<std::mutex> lock(mutex_);
        closing_ = true;
        wake_.notify_one();
    }
    if (thread_ && thread_->joinable()) thread_->join();
    // A forked child whose worker never restarted has its queue abandoned
    // already; nothing is left to run.
}

void TierUpWorker::post(Job job) {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs_.push_back(std::move(job));
    if (!thread_) thread_ = std::make_unique<std::thread>([this] { loop(); });
    wake_.notify_one();
}

void TierUpWorker::drain() {
    std::unique_lock<std::mutex> lock(mutex_);
    idle_.wait(lock, [this] { return jobs_.empty() && !busy_; });
}

void TierUpWorker::loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
        wake_.wait(lock, [this] { return closing_ || !jobs_.empty(); });
        if (jobs_.empty()) return;  // closing, and nothing left
        Job job = std::move(jobs_.front());
        jobs_.pop_front();
        busy_ = true;
        Run run = closing_ ? Run::Closing : Run::Normal;
        lock.unlock();
        job(run);
        job = nullptr;  // what the job holds goes before the worker says it is idle
        lock.lock();
        busy_ = false;
        idle_.notify_all();
    }
}

void TierUpWorker::holdForFork() {
    std::unique_lock<std::mutex> lock(mutex_);
    idle_.wait(lock, [this] { return !busy_; });
    lock.release();  // stays locked until releaseAfterFork
}

void TierUpWorker::releaseAfterFork(bool child) {
    std::deque<Job> abandoned;
    if (child) {
        // The thread was not copied; its handle names a thread of the
        // parent's. Let go of it without joining: the next post() starts one.
        (void)thread_.release();
        abandoned.swap(jobs_);
    }
    mutex_.unlock();
    for (Job& job : abandoned) job(Run::Abandoned);
}

}  // namespace facet
