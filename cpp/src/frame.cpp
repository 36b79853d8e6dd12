#include "wmiltrack/frame.hpp"

#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include "wmiltrack/scoring.hpp"

namespace wmiltrack {

void learn_step(const IntegralImage& ii, const FeatureBank& bank, const LearnStep& step,
                double* mu1, double* sigma1, double* mu0, double* sigma0,
                std::int32_t* selected, double* h) {
  const int M = bank.size(), P = step.n_pos, E = step.n_extra, N = step.n_neg + E;
  const int boxes = P + step.n_neg, B = P + N;
  if (P < 0 || step.n_neg < 0 || E < 0) throw std::invalid_argument("learn_step: negative bag size");
  if (E > 0 && step.extra_neg == nullptr) {
    throw std::invalid_argument("learn_step: n_extra values need their array");
  }
  if (step.select == LearnSelect::kWmil && (P == 0 || step.w_pos == nullptr)) {
    throw std::invalid_argument("learn_step: WMIL selection needs positives and their weights");
  }
  // values: M x B, the projected boxes' columns then the extra negatives'. Every entry is
  // written below, so the buffers are not cleared first (std::vector would: 76 KB a frame).
  const std::size_t n_values = static_cast<std::size_t>(M) * static_cast<std::size_t>(B);
  const std::unique_ptr<double[]> values(new double[n_values]);
  if (E == 0) {
    project(ii, bank, nullptr, M, step.xs, step.ys, boxes, values.get());
  } else {
    std::vector<double> projected(static_cast<std::size_t>(M) * static_cast<std::size_t>(boxes));
    project(ii, bank, nullptr, M, step.xs, step.ys, boxes, projected.data());
    for (int m = 0; m < M; ++m) {
      double* row = values.get() + static_cast<std::ptrdiff_t>(m) * B;
      std::copy_n(projected.data() + static_cast<std::ptrdiff_t>(m) * boxes, boxes, row);
      std::copy_n(step.extra_neg + static_cast<std::ptrdiff_t>(m) * E, E, row + boxes);
    }
  }
  // The Gaussian update of each class that has samples, into fresh arrays then copied back
  // (the update reads the old model).
  std::vector<double> new_mu(static_cast<std::size_t>(M)), new_sigma(new_mu.size()),
      scratch(static_cast<std::size_t>(std::max(B, 1)));
  const auto update = [&](int first_col, int n, bool first, double* mu, double* sigma,
                          const GaussianRule& given) {
    if (n == 0) return;
    GaussianRule rule = given;
    rule.first = first;
    const MatrixView v{values.get() + first_col, M, n, B, 1};
    gaussian_update(v, mu, sigma, rule, new_mu.data(), new_sigma.data(), scratch.data());
    std::copy(new_mu.begin(), new_mu.end(), mu);
    std::copy(new_sigma.begin(), new_sigma.end(), sigma);
  };
  update(0, P, step.first_pos, mu1, sigma1, step.rule);
  update(P, N, step.first_neg, mu0, sigma0, step.rule);
  if (step.second_mu != nullptr && step.second_sigma != nullptr) {
    update(0, P, step.second_rule.first, step.second_mu, step.second_sigma, step.second_rule);
  }
  if (step.select == LearnSelect::kNone) return;
  // Log ratios of every feature on both bags under the updated model.
  std::unique_ptr<double[]> own;
  double* hr = h;
  if (step.select != LearnSelect::kRatios) {
    own.reset(new double[n_values]);
    hr = own.get();
  }
  const WeakGaussians weak(mu1, sigma1, mu0, sigma0, M, step.guard);
  for (int m = 0; m < M; ++m) {
    const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(m) * B;
    weak.log_ratio(m, values.get() + row, B, hr + row, false, nullptr);
  }
  if (step.select == LearnSelect::kWmil) {
    const MatrixView h_pos{hr, M, P, B, 1}, h_neg{hr + P, M, N, B, 1};
    wmil_select(h_pos, h_neg, step.w_pos, step.k, step.code_gradient, selected);
  }
}

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
