// TierUp: the background thread on which a Compiler swaps optimized code into
// its tiered kernels (codegen=tiered), and what that thread does across
// fork().
//
// fork() copies only the calling thread. Had the child inherited a worker
// caught in the middle of a job, it would also inherit the locks that job
// held (the JIT's codegen and linking mutexes, a kernel's own), locked
// forever, and its first compile or sampler would deadlock. So a
// pthread_atfork handler waits until every worker is between jobs and holds
// each worker's queue lock across the fork: the child then starts with no
// worker thread and no LLVM lock taken. Jobs still queued in the child are
// abandoned (their kernels keep their quick code and report why they were
// not optimized); a later tiered compile in the child starts a new thread.
// The cost is that fork() waits for a tier-up already running (a few
// milliseconds to a few hundred for a large material).
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

namespace facet {

class TierUpWorker {
public:
    // How a job is run: normally; while the Compiler is being destroyed (do
    // only what outlives it, see Compiler::tierUp); or not at all, in a
    // forked child (settle the kernel without optimizing it).
    enum class Run { Normal, Closing, Abandoned };
    using Job = std::function<void(Run)>;

    TierUpWorker();
    ~TierUpWorker();  // runs what is queued with Run::Closing, then stops
    TierUpWorker(const TierUpWorker&) = delete;
    TierUpWorker& operator=(const TierUpWorker&) = delete;

    void post(Job job);
    // Blocks until every job posted so far has finished.
    void drain();

private:
    friend struct TierUpForkHooks;
    void loop();
    void holdForFork();     // prepare: waits until idle, keeps mutex_ locked
    void releaseAfterFork(bool child);

    std::mutex mutex_;
    std::condition_variable wake_, idle_;
    std::deque<Job> jobs_;
    bool busy_ = false, closing_ = false;
    // A pointer, so that a forked child can let go of a thread it does not
    // have (a joinable std::thread may be neither destroyed nor joined there).
    std::unique_ptr<std::thread> thread_;
};

}  // namespace facet
