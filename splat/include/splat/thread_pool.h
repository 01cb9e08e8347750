#pragma once
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace splat {

// A fixed set of worker threads that run index ranges. Work items must write disjoint memory;
// results then do not depend on the number of threads.
class ThreadPool {
 public:
  // threads = 0 uses std::thread::hardware_concurrency(). The calling thread also works.
  explicit ThreadPool(int threads = 0);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int size() const { return static_cast<int>(workers_.size()) + 1; }
  // Calls fn(i) for every i in [0, n), blocking until all are done; rethrows the first exception.
  void parallel_for(std::size_t n, const std::function<void(std::size_t)>& fn);

 private:
  void worker_loop();
  // Runs items of the job until none is left to claim.
  void run_items(const std::function<void(std::size_t)>& fn, std::size_t size);
  // Polls `ready` until it holds, for up to a few milliseconds, before the caller blocks: a
  // mapping step hands the pool dozens of short jobs, and sleeping and waking between them
  // costs more than the gaps.
  static void spin_until(const std::function<bool()>& ready);

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  // The job: set under the mutex while no worker is busy; items are claimed through next_.
  const std::function<void(std::size_t)>* job_ = nullptr;
  std::size_t job_size_ = 0;
  std::atomic<std::size_t> next_{0}, finished_{0};
  std::atomic<uint64_t> generation_{0};
  std::atomic<int> busy_{0};  // workers that took the current job and have not left it
  std::atomic<bool> stop_{false};
  std::exception_ptr error_;  // under the mutex
};

// fn(i) for every i in [0, n): on the pool where there is one, else in order on this thread.
inline void parallel_for(ThreadPool* pool, std::size_t n, const std::function<void(std::size_t)>& fn) {
  if (pool != nullptr) {
    pool->parallel_for(n, fn);
  } else {
    for (std::size_t i = 0; i < n; ++i) fn(i);
  }
}

}  // namespace splat
