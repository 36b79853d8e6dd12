// The shared-object rules of issue 12 under threads: one SharedIntegralImage recomputed by
// writer threads while reader threads project and score on snapshots. Every reader result
// must equal the result on one of the complete tables. Then parallel_for, whose threads stay
// between calls, called from several threads at once: every index runs exactly once per call
// and a job's exception reaches its caller. Run under ThreadSanitizer by scripts/sanitize.sh
// tsan (any data race is a report and a failure there).
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

#include "wmiltrack/worker_pool.hpp"
#include "wmiltrack/haar.hpp"
#include "wmiltrack/scoring.hpp"
#include "wmiltrack/shared.hpp"

using namespace wmiltrack;

namespace {

struct Frame {
  int rows, cols;
  std::vector<std::uint8_t> pixels;
  ImageView view() const {
    ImageView v;
    v.data = pixels.data();
    v.rows = rows;
    v.cols = cols;
    v.channels = 1;
    v.row_stride = cols;
    return v;
  }
};

Frame random_frame(int rows, int cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> d(0, 255);
  Frame f{rows, cols, std::vector<std::uint8_t>(static_cast<std::size_t>(rows) * cols)};
  for (auto& p : f.pixels) p = static_cast<std::uint8_t>(d(rng));
  return f;
}

// Three threads each make 200 calls of parallel_for (n = 1..40 jobs on 1..4 threads): each call
// must run each of its jobs once, and rethrow the exception of the job that throws. Returns the
// number of calls that went wrong.
int parallel_for_from_several_threads() {
  std::atomic<int> errors{0};
  const auto caller = [&](unsigned seed) {
    std::mt19937 rng(seed);
    for (int call = 0; call < 200; ++call) {
      const int n = 1 + static_cast<int>(rng() % 40), threads = 1 + static_cast<int>(rng() % 4);
      const int throwing = call % 7 == 0 ? static_cast<int>(rng() % static_cast<unsigned>(n)) : -1;
      std::vector<std::atomic<int>> runs(static_cast<std::size_t>(n));
      bool caught = false;
      try {
        parallel_for(n, threads, [&](int i) {
          runs[static_cast<std::size_t>(i)]++;
          if (i == throwing) throw std::runtime_error("job");
        });
      } catch (const std::runtime_error&) {
        caught = true;
      }
      bool once = caught == (throwing >= 0);
      for (const auto& r : runs) once = once && r.load() == 1;
      if (!once) ++errors;
    }
  };
  std::thread a(caller, 1u), b(caller, 2u), c(caller, 3u);
  a.join();
  b.join();
  c.join();
  return errors.load();
}

}  // namespace

int main() {
  const Frame a = random_frame(90, 120, 1), b = random_frame(90, 120, 2);
  // Different ROIs (sizes and origins), so a reader mixing two tables would read garbage.
  const Rect roi_a{0, 0, 120, 90}, roi_b{10, 5, 70, 60};
  FeatureBank bank({0, 1, 3}, {Rect{1, 2, 5, 4}, Rect{0, 0, 3, 3}, Rect{4, 4, 6, 2}},
                   {1.0, 0.5, -2.0});
  const std::vector<std::int32_t> xs{12, 20, 40}, ys{8, 30, 25};
  const double mu1[] = {100.0, 20.0}, s1[] = {50.0, 30.0}, mu0[] = {-50.0, 0.0}, s0[] = {60.0, 20.0};
  const WeakGaussians weak(mu1, s1, mu0, s0, 2, 1e-30);
  const std::int32_t sel[] = {0, 1};
  const Rect box{30, 30, 10, 6};

  auto expected = [&](const Frame& f, const Rect& roi, std::vector<double>& proj, GridResult& g) {
    IntegralImage ii;
    ii.compute(f.view(), roi);
    proj.assign(6, 0.0);
    project(ii, bank, nullptr, 0, xs.data(), ys.data(), 3, proj.data());
    g = score_grid(ii, bank, sel, 2, weak, box, 8, 1, 120, 90, nullptr);
  };
  std::vector<double> pa, pb;
  GridResult ga, gb;
  expected(a, roi_a, pa, ga);
  expected(b, roi_b, pb, gb);

  SharedIntegralImage shared;
  shared.compute(a.view(), roi_a);
  std::atomic<bool> stop{false};
  std::atomic<int> bad{0}, reads{0};
  auto writer = [&](int phase) {
    for (int i = 0; i < 400; ++i) {
      if ((i + phase) % 2 == 0) shared.compute(a.view(), roi_a);
      else shared.compute_channels(b.view(), roi_b, {kLuma});
    }
  };
  auto reader = [&] {
    std::vector<double> out(6);
    while (!stop.load()) {
      const auto ii = shared.snapshot();
      project(*ii, bank, nullptr, 0, xs.data(), ys.data(), 3, out.data());
      const GridResult g = score_grid(*ii, bank, sel, 2, weak, box, 8, 1, 120, 90, nullptr);
      const bool is_a = out == pa && g.dx == ga.dx && g.dy == ga.dy && g.score == ga.score;
      const bool is_b = out == pb && g.dx == gb.dx && g.dy == gb.dy && g.score == gb.score;
      if (!is_a && !is_b) ++bad;
      ++reads;
    }
  };
  std::vector<std::thread> threads;
  threads.emplace_back(reader);
  threads.emplace_back(reader);
  std::thread w1(writer, 0), w2(writer, 1);
  w1.join();
  w2.join();
  stop = true;
  for (auto& t : threads) t.join();
  std::printf("test_threads: %d reads, %d inconsistent\n", reads.load(), bad.load());
  const int pool_errors = parallel_for_from_several_threads();
  std::printf("test_threads: parallel_for from 3 threads, %d errors\n", pool_errors);
  return bad.load() == 0 && reads.load() > 0 && pool_errors == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
