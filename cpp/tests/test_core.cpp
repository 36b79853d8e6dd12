// Plain C++ checks of the core against naive computations; run by ctest and .ci/run.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "wmiltrack/haar.hpp"
#include "wmiltrack/integral.hpp"
#include "wmiltrack/scoring.hpp"

namespace {
int failures = 0;
#define CHECK(cond)                                                            \
  do {                                                                         \
    if (!(cond)) {                                                             \
      std::fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
      ++failures;                                                              \
    }                                                                          \
  } while (0)

using namespace wmiltrack;

struct Frame {
  int rows, cols, channels;
  std::vector<std::uint8_t> pixels;
  ImageView view() const {
    ImageView v;
    v.data = pixels.data();
    v.rows = rows;
    v.cols = cols;
    v.channels = channels;
    v.channel_stride = 1;
    v.col_stride = channels;
    v.row_stride = static_cast<std::ptrdiff_t>(cols) * channels;
    return v;
  }
  int gray(int r, int c) const {
    const std::uint8_t* p = &pixels[(static_cast<std::size_t>(r) * cols + c) * channels];
    return channels == 1 ? p[0] : bgr_to_gray(p[0], p[1], p[2]);
  }
};

Frame random_frame(int rows, int cols, int channels, std::mt19937& rng) {
  Frame f{rows, cols, channels, std::vector<std::uint8_t>(static_cast<std::size_t>(rows) * cols * channels)};
  std::uniform_int_distribution<int> d(0, 255);
  for (auto& p : f.pixels) p = static_cast<std::uint8_t>(d(rng));
  return f;
}

long naive_sum(const Frame& f, int x, int y, int w, int h) {
  long s = 0;
  for (int r = y; r < y + h; ++r)
    for (int c = x; c < x + w; ++c) s += f.gray(r, c);
  return s;
}

void test_integral(std::mt19937& rng) {
  for (int channels : {1, 3, 4}) {
    const Frame f = random_frame(37, 53, channels, rng);
    IntegralImage ii;
    ii.compute(f.view(), Rect{5, 3, 40, 30});
    CHECK(ii.x0() == 5 && ii.y0() == 3 && ii.width() == 40 && ii.height() == 30);
    std::uniform_int_distribution<int> dx(5, 44), dy(3, 32);
    for (int t = 0; t < 200; ++t) {
      const int x = dx(rng), y = dy(rng);
      const int w = std::uniform_int_distribution<int>(0, 45 - x)(rng);
      const int h = std::uniform_int_distribution<int>(0, 33 - y)(rng);
      CHECK(ii.sum(Rect{x, y, w, h}) == static_cast<double>(naive_sum(f, x, y, w, h)));
    }
    // A region hanging off the frame is clipped to it.
    ii.compute(f.view(), Rect{-10, -10, 200, 200});
    CHECK(ii.x0() == 0 && ii.y0() == 0 && ii.width() == 53 && ii.height() == 37);
    CHECK(ii.sum(Rect{0, 0, 53, 37}) == static_cast<double>(naive_sum(f, 0, 0, 53, 37)));
  }
  bool threw = false;
  try {
    IntegralImage ii;
    const Frame f = random_frame(10, 10, 1, rng);
    ii.compute(f.view(), Rect{20, 20, 5, 5});
  } catch (const std::invalid_argument&) {
    threw = true;
  }
  CHECK(threw);
}

void test_projection_and_scoring(std::mt19937& rng) {
  const Frame f = random_frame(120, 160, 3, rng);
  // Two features: (a) one rect with weight 1, (b) two rects with weights 0.5 and -2.
  FeatureBank bank({0, 1, 3}, {Rect{1, 2, 5, 4}, Rect{0, 0, 3, 3}, Rect{4, 4, 6, 2}}, {1.0, 0.5, -2.0});
  CHECK(bank.size() == 2);
  CHECK(bank.extent().x == 0 && bank.extent().w == 10 && bank.extent().h == 6);
  IntegralImage ii;
  ii.compute(f.view(), Rect{0, 0, 160, 120});
  std::vector<std::int32_t> xs{0, 10, 150}, ys{0, 20, 114};
  std::vector<double> out(6);
  project(ii, bank, nullptr, 0, xs.data(), ys.data(), 3, out.data());
  for (int n = 0; n < 3; ++n) {
    const double a = naive_sum(f, xs[n] + 1, ys[n] + 2, 5, 4);
    const double b = 0.5 * naive_sum(f, xs[n], ys[n], 3, 3) - 2.0 * naive_sum(f, xs[n] + 4, ys[n] + 4, 6, 2);
    CHECK(out[n] == a);
    CHECK(std::abs(out[3 + n] - b) < 1e-9);
  }
  // A box whose features leave the table is refused.
  std::vector<std::int32_t> bad_x{151}, bad_y{0};
  bool threw = false;
  try {
    project(ii, bank, nullptr, 0, bad_x.data(), bad_y.data(), 1, out.data());
  } catch (const std::out_of_range&) {
    threw = true;
  }
  CHECK(threw);

  // Scoring: the grid maximum agrees with a naive scan in row-major order.
  const std::vector<std::int32_t> sel{1, 0};
  const double mu1[] = {-100.0, 300.0}, s1[] = {50.0, 80.0}, mu0[] = {20.0, 250.0}, s0[] = {60.0, 90.0};
  const WeakGaussians weak(mu1, s1, mu0, s0, 2, 1e-30);
  const Rect box{70, 50, 12, 8};
  const GridResult r = score_grid(ii, bank, sel.data(), 2, weak, box, 10, 1, 160, 120, nullptr);
  double best = -1e300;
  int bdx = 0, bdy = 0, count = 0;
  for (int dy = -9; dy <= 9; ++dy)
    for (int dx = -9; dx <= 9; ++dx) {
      if (dx * dx + dy * dy >= 100) continue;
      ++count;
      double h = 0;
      const std::int32_t x = box.x + dx, y = box.y + dy;
      double v[2];
      project(ii, bank, sel.data(), 2, &x, &y, 1, v);
      for (int k = 0; k < 2; ++k) {
        const auto p = [&](double m, double s) {
          return std::exp(-(v[k] - m) * (v[k] - m) / (2 * s * s + 1e-30)) / (s + 1e-30);
        };
        h += std::log(p(mu1[k], s1[k]) + 1e-30) - std::log(p(mu0[k], s0[k]) + 1e-30);
      }
      if (h > best + 1e-9) {
        best = h;
        bdx = dx;
        bdy = dy;
      }
    }
  CHECK(r.candidates == count && count == 305);
  CHECK(r.dx == bdx && r.dy == bdy);
  CHECK(std::abs(r.score - best) < 1e-6 * (1 + std::abs(best)));
  // Near a corner only the candidates inside the frame are scored.
  const GridResult c = score_grid(ii, bank, sel.data(), 2, weak, Rect{0, 0, 12, 8}, 10, 1, 160, 120, nullptr);
  CHECK(c.candidates > 0 && c.candidates < 305 && c.dx >= 0 && c.dy >= 0);
  // A frame smaller than the box: nothing fits, nothing moves.
  const GridResult none = score_grid(ii, bank, sel.data(), 2, weak, Rect{0, 0, 200, 8}, 10, 1, 160, 120, nullptr);
  CHECK(none.candidates == 0 && none.dx == 0 && none.dy == 0);
}

// Coordinates near INT_MAX must be refused, not wrap around into out-of-bounds reads
// (x + w used to overflow in covers(), compute(), check_boxes_covered() and score_grid()).
void test_overflow_guards(std::mt19937& rng) {
  constexpr int kMax = std::numeric_limits<int>::max();
  const Frame f = random_frame(20, 30, 1, rng);
  IntegralImage ii;
  ii.compute(f.view(), Rect{0, 0, 30, 20});
  CHECK(!ii.covers(Rect{5, 0, kMax, 1}));
  CHECK(!ii.covers(Rect{0, 5, 1, kMax}));
  CHECK(!ii.covers(Rect{kMax, kMax, 1, 1}));
  CHECK(ii.covers(Rect{0, 0, 30, 20}));
  const auto throws_invalid = [&](Rect roi) {
    try {
      IntegralImage t;
      t.compute(f.view(), roi);
    } catch (const std::invalid_argument&) {
      return true;
    }
    return false;
  };
  CHECK(throws_invalid(Rect{kMax - 5, 0, 100, 10}));
  CHECK(throws_invalid(Rect{0, kMax - 5, 10, 100}));
  // A huge ROI starting inside the frame is clipped, not overflowed.
  ii.compute(f.view(), Rect{3, 2, kMax, kMax});
  CHECK(ii.x0() == 3 && ii.y0() == 2 && ii.width() == 27 && ii.height() == 18);

  FeatureBank bank({0, 1}, {Rect{2, 2, 3, 3}}, {1.0});
  ii.compute(f.view(), Rect{0, 0, 30, 20});
  std::vector<std::int32_t> xs{kMax - 1}, ys{0};
  double out = 0.0;
  bool threw = false;
  try {
    project(ii, bank, nullptr, 0, xs.data(), ys.data(), 1, &out);
  } catch (const std::out_of_range&) {
    threw = true;
  }
  CHECK(threw);
  threw = false;
  try {
    FeatureBank bad({0, 1}, {Rect{kMax - 1, 0, 5, 5}}, {1.0});
  } catch (const std::invalid_argument&) {
    threw = true;
  }
  CHECK(threw);

  const std::int32_t sel[] = {0};
  const double mu1[] = {10.0}, s1[] = {5.0}, mu0[] = {0.0}, s0[] = {5.0};
  const WeakGaussians weak(mu1, s1, mu0, s0, 1, 1e-30);
  const GridResult far = score_grid(ii, bank, sel, 1, weak, Rect{kMax - 3, kMax - 3, 10, 10}, 8, 1, 30, 20, nullptr);
  CHECK(far.candidates == 0 && far.dx == 0 && far.dy == 0);
  const GridResult wide = score_grid(ii, bank, sel, 1, weak, Rect{2, 2, kMax, 5}, 8, 1, 30, 20, nullptr);
  CHECK(wide.candidates == 0);
  threw = false;
  try {
    score_grid(ii, bank, sel, 1, weak, Rect{2, 2, 5, 5}, kMaxSearchRadius + 1, 1, 30, 20, nullptr);
  } catch (const std::invalid_argument&) {
    threw = true;
  }
  CHECK(threw);
  CHECK(grid_half_size(kMax, kMax) == 0);
  // No samples (a box as large as the frame has no negatives): nothing is read or written.
  const double* no_values = nullptr;
  weak.log_ratio(0, no_values, 0, nullptr, false, nullptr);
  std::vector<double> none_out;
  weak.log_ratio(0, none_out.data(), 0, none_out.data(), true, none_out.data());
}
}  // namespace

int main() {
  std::mt19937 rng(1234);
  test_integral(rng);
  test_projection_and_scoring(rng);
  test_overflow_guards(rng);
  if (failures == 0) {
    std::printf("test_core: all checks passed\n");
    return EXIT_SUCCESS;
  }
  std::printf("test_core: %d checks failed\n", failures);
  return EXIT_FAILURE;
}
