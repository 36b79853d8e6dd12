// The core's worker threads: parallel_for over threads kept between calls (worker_pool.hpp).
#include "wmiltrack/worker_pool.hpp"

#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace wmiltrack {

namespace {

// Threads that stay between calls of parallel_for: starting and joining a thread costs about
// 18 us on the 2-core VM of the benchmarks, and waking one that sleeps on a condition variable
// costs 20-40 us there when its core has gone idle, which is the usual case between two frames
// of a MultiTracker (one to three such calls a frame, with the Python part of the frame in
// between). So a waiting thread (a worker between calls, the caller waiting for the workers'
// last jobs) first spins for up to kSpin, watching an atomic, and only then sleeps. One pool
// serves the process; a caller that finds it busy (parallel_for from two threads at once)
// starts its own threads, as before. The pool is never destroyed (its threads wait on it
// until the process ends), and a forked child starts a new one: the parent's threads do not
// exist there.
class WorkerPool {
 public:
  // `work` on `extra` pool threads and the caller; returns once all have finished. False (and
  // nothing run) when another caller is using the pool.
  bool run(int extra, const std::function<void()>& work) {
    std::unique_lock<std::mutex> use(busy_, std::try_to_lock);
    if (!use) return false;
    {
      std::lock_guard<std::mutex> lock(m_);
      while (static_cast<int>(started_) < extra) {
        std::thread(&WorkerPool::loop, this).detach();
        ++started_;
      }
      job_ = &work;
      wanted_ = extra;
      running_.store(extra, std::memory_order_relaxed);
      ++generation_;
      published_.store(generation_, std::memory_order_release);
    }
    wake_.notify_all();
    work();
    if (!spin_until([this] { return running_.load(std::memory_order_acquire) == 0; })) {
      std::unique_lock<std::mutex> lock(m_);
      done_.wait(lock, [this] { return running_.load(std::memory_order_acquire) == 0; });
    }
    const std::lock_guard<std::mutex> lock(m_);
    job_ = nullptr;
    return true;
  }

 private:
  static constexpr auto kSpin = std::chrono::microseconds(200);

  // Whether done() became true within kSpin.
  template <class Done>
  static bool spin_until(const Done& done) {
    const auto until = std::chrono::steady_clock::now() + kSpin;
    for (;;) {
      for (int i = 0; i < 64; ++i) {
        if (done()) return true;
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
      }
      if (std::chrono::steady_clock::now() > until) return done();
    }
  }

  void loop() {
    std::uint64_t seen = 0;
    for (;;) {
      spin_until([&] { return published_.load(std::memory_order_acquire) != seen; });
      std::unique_lock<std::mutex> lock(m_);
      wake_.wait(lock, [&] { return generation_ != seen; });
      seen = generation_;
      if (wanted_ == 0) continue;  // enough threads took this call's work
      --wanted_;
      const std::function<void()>* job = job_;
      lock.unlock();
      (*job)();
      if (running_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
        const std::lock_guard<std::mutex> done_lock(m_);  // the caller may be about to sleep
        done_.notify_one();
      }
    }
  }

  std::mutex busy_;  // held by the one caller using the pool
  std::mutex m_;
  std::condition_variable wake_, done_;
  const std::function<void()>* job_ = nullptr;
  std::uint64_t generation_ = 0;               // under m_
  std::atomic<std::uint64_t> published_{0};    // generation_, for the spinning workers
  int wanted_ = 0;                             // under m_
  std::atomic<int> running_{0};
  unsigned started_ = 0;
};

std::atomic<WorkerPool*> g_pool{nullptr};
std::once_flag g_pool_fork_hook;

WorkerPool& worker_pool() {
  std::call_once(g_pool_fork_hook, [] {
    // In a forked child the pool's threads are gone: forget it (leaked) and start another.
    pthread_atfork(nullptr, nullptr, [] { g_pool.store(nullptr); });
  });
  WorkerPool* pool = g_pool.load();
  if (pool == nullptr) {
    auto* fresh = new WorkerPool();
    if (g_pool.compare_exchange_strong(pool, fresh)) {
      pool = fresh;
    } else {
      delete fresh;  // another thread made it first
    }
  }
  return *pool;
}

}  // namespace

void parallel_for(int n, int threads, const std::function<void(int)>& fn) {
  if (n <= 0) return;
  const int workers = std::max(1, std::min(threads, n));
  std::atomic<int> next{0};
  std::exception_ptr first_error;
  std::mutex error_mutex;
  const std::function<void()> work = [&] {
    for (int i = next++; i < n; i = next++) {
      try {
        fn(i);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (!first_error) first_error = std::current_exception();
      }
    }
  };
  if (workers == 1) {
    work();
  } else if (!worker_pool().run(workers - 1, work)) {
    std::vector<std::thread> pool;
    pool.reserve(static_cast<std::size_t>(workers - 1));
    for (int t = 1; t < workers; ++t) pool.emplace_back(work);
    work();
    for (std::thread& t : pool) t.join();
  }
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace wmiltrack
