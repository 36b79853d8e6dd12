// Plain C++ checks of the core against naive computations; run by ctest and .ci/run.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "wmiltrack/haar.hpp"
#include "wmiltrack/integral.hpp"
#include "wmiltrack/sampling.hpp"
#include "wmiltrack/learning.hpp"
#include "wmiltrack/scoring.hpp"
#include "wmiltrack/vmath.hpp"

#include "check.hpp"

namespace {

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
    // copy_plane gives the true sums.
    std::vector<double> table(static_cast<std::size_t>(ii.plane_size()));
    ii.copy_plane(0, table.data());
    bool same = true;
    for (int y = 0; y <= 37; ++y)
      for (int x = 0; x <= 53; ++x)
        same = same && table[y * ii.stride() + x] == static_cast<double>(naive_sum(f, 0, 0, x, y));
    CHECK(same);
  }
  {
    // Sums past 2^32: the 32-bit entries wrap, rectangles up to kMaxExactRectArea stay exact
    // and larger ones are summed in bands. Every pixel 255 (one byte, strides 0), 4200 x 4100.
    const std::uint8_t white = 255;
    ImageView v;
    v.data = &white;
    v.rows = 4100;
    v.cols = 4200;
    v.row_stride = 0;
    v.col_stride = 0;
    IntegralImage big;
    big.compute(v, Rect{0, 0, 4200, 4100});
    const auto white_sum = [](std::int64_t w, std::int64_t h) { return 255.0 * static_cast<double>(w * h); };
    CHECK(big.sum(Rect{0, 0, 4200, 4100}) == white_sum(4200, 4100));        // 4.39e9 > 2^32
    CHECK(big.sum(Rect{100, 50, 4100, 4000}) == white_sum(4100, 4000));
    CHECK(big.sum(Rect{4000, 4000, 200, 100}) == white_sum(200, 100));    // entries wrapped
    const int side = 4104;  // 4104^2 = 16 842 816 <= kMaxExactRectArea: one band
    CHECK(static_cast<std::int64_t>(side) * side <= kMaxExactRectArea);
    CHECK(big.sum(Rect{50, 0, side, side - 8}) == white_sum(side, side - 8));
    // A feature bank refuses a rectangle whose sum could reach 2^32.
    bool refused = false;
    try {
      FeatureBank({0, 1}, {Rect{0, 0, 4200, 4100}}, {1.0});
    } catch (const std::invalid_argument&) {
      refused = true;
    }
    CHECK(refused);
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

// Channel c of the frame at (r, c0), from the definitions in integral.hpp: luma, gradients
// with the frame's edge replicated, opponent colours.
int naive_channel(const Frame& f, int ch, int r, int c) {
  if (ch == kOppRG || ch == kOppYB) {
    const std::uint8_t* p = &f.pixels[(static_cast<std::size_t>(r) * f.cols + c) * f.channels];
    const int b = p[0], g = p[1], rr = p[2];
    return ch == kOppRG ? (rr - g + 255) / 2 : (rr + g - 2 * b + 510) / 4;
  }
  if (ch == kLuma) return f.gray(r, c);
  const auto at = [&](int y, int x) {
    return f.gray(std::min(std::max(y, 0), f.rows - 1), std::min(std::max(x, 0), f.cols - 1));
  };
  const int gx = at(r, c + 1) - at(r, c - 1), gy = at(r + 1, c) - at(r - 1, c);
  return (std::abs(gx) + std::abs(gy)) / 2;  // kGrad
}

long naive_channel_sum(const Frame& f, int ch, int x, int y, int w, int h) {
  long s = 0;
  for (int r = y; r < y + h; ++r)
    for (int c = x; c < x + w; ++c) s += naive_channel(f, ch, r, c);
  return s;
}

// Every channel's table against naive sums, for every layout and region.
void test_channel_tables(std::mt19937& rng) {
  const std::vector<int> all{kLuma, kGrad, kOppRG, kOppYB};
  const std::vector<int> gray_ok{kGrad, kLuma};
  const Rect rois[] = {{0, 0, 53, 37}, {7, 5, 30, 20}, {-3, -2, 10, 9}, {45, 30, 20, 20},
                       {0, 10, 53, 1}, {20, 0, 1, 37}, {52, 36, 1, 1}, {4, 4, 2, 2},
                       {5, 3, 32, 16}};  // a width of whole SIMD steps
  for (int channels : {1, 3, 4}) {
    const Frame f = random_frame(37, 53, channels, rng);
    const std::vector<int>& chans = channels == 1 ? gray_ok : all;
    for (const Rect& roi : rois) {
      IntegralImage ii;
      ii.compute_channels(f.view(), roi, chans);
      CHECK(ii.num_channels() == static_cast<int>(chans.size()));
      CHECK(ii.plane_size() == (ii.width() + 1) * (ii.height() + 1));
      bool exact = true;
      for (int k = 0; k < ii.num_channels(); ++k) {
        // Every 1x1, every row and the whole region, on every plane.
        for (int y = ii.y0(); y < ii.y0() + ii.height(); ++y) {
          for (int x = ii.x0(); x < ii.x0() + ii.width(); ++x) {
            exact = exact && ii.sum(Rect{x, y, 1, 1}, k) == naive_channel(f, chans[k], y, x);
          }
          exact = exact && ii.sum(Rect{ii.x0(), y, ii.width(), 1}, k) ==
                               naive_channel_sum(f, chans[k], ii.x0(), y, ii.width(), 1);
        }
        exact = exact && ii.sum(Rect{ii.x0(), ii.y0(), ii.width(), ii.height()}, k) ==
                             naive_channel_sum(f, chans[k], ii.x0(), ii.y0(), ii.width(), ii.height());
        const IntegralImage::Entry* p = ii.plane(k);
        for (int c = 0; c <= ii.width(); ++c) exact = exact && p[c] == 0;
        for (int r = 0; r <= ii.height(); ++r) exact = exact && p[r * ii.stride()] == 0;
      }
      CHECK(exact);
    }
    // The luma plane is bit-identical to compute().
    IntegralImage a, b;
    a.compute(f.view(), Rect{3, 2, 40, 30});
    b.compute_channels(f.view(), Rect{3, 2, 40, 30}, {kGrad, kLuma});
    CHECK(a.num_channels() == 1 && b.num_channels() == 2);
    CHECK(std::equal(a.data(), a.data() + a.plane_size(), b.plane(1)));
    // Reusing a larger buffer for a smaller table leaves nothing stale behind.
    b.compute_channels(f.view(), Rect{0, 0, 53, 37}, chans);
    b.compute_channels(f.view(), Rect{10, 10, 5, 4}, {kLuma});
    CHECK(std::equal(b.data(), b.data() + b.plane_size(),
                     [&] { IntegralImage c; c.compute(f.view(), Rect{10, 10, 5, 4}); return c; }().data()));
  }
}

// Channels a frame cannot give, or none, are refused.
void test_channel_refusals(std::mt19937& rng) {
  const auto throws_invalid = [&](const Frame& f, std::vector<int> chans) {
    try {
      IntegralImage t;
      t.compute_channels(f.view(), Rect{0, 0, 5, 5}, chans);
    } catch (const std::invalid_argument&) {
      return true;
    }
    return false;
  };
  const Frame gray = random_frame(10, 10, 1, rng), bgr = random_frame(10, 10, 3, rng);
  CHECK(throws_invalid(gray, {kLuma, kOppRG}));
  CHECK(throws_invalid(gray, {kOppYB}));
  CHECK(!throws_invalid(bgr, {kOppRG, kOppYB}));
  CHECK(throws_invalid(bgr, {}));
  CHECK(throws_invalid(bgr, {kNumChannelKinds}));
  CHECK(throws_invalid(bgr, {-1}));
}

void test_features_on_planes(const Frame& f) {
  // Features on planes: project against naive sums of each plane's channel.
  const std::vector<int> chans{kOppYB, kLuma, kGrad};
  IntegralImage ii;
  ii.compute_channels(f.view(), Rect{0, 0, 70, 60}, chans);
  FeatureBank bank({0, 1, 3}, {Rect{1, 2, 5, 4}, Rect{0, 0, 3, 3}, Rect{4, 4, 6, 2}},
                   {1.0, 0.5, -2.0}, {2, 0, 1});
  CHECK(bank.planes_needed() == 3);
  std::vector<std::int32_t> xs{0, 10, 60}, ys{0, 20, 54};
  std::vector<double> out(6);
  project(ii, bank, nullptr, 0, xs.data(), ys.data(), 3, out.data());
  for (int n = 0; n < 3; ++n) {
    const double a = naive_channel_sum(f, kGrad, xs[n] + 1, ys[n] + 2, 5, 4);
    const double b = 0.5 * naive_channel_sum(f, kOppYB, xs[n], ys[n], 3, 3) -
                     2.0 * naive_channel_sum(f, kLuma, xs[n] + 4, ys[n] + 4, 6, 2);
    CHECK(out[n] == a);
    CHECK(std::abs(out[3 + n] - b) < 1e-9);
  }
  // A plane the integral image lacks is refused (project, score_grid, CompiledFeatures).
  const auto throws_range = [](auto&& fn) {
    try {
      fn();
    } catch (const std::out_of_range&) {
      return true;
    }
    return false;
  };
  IntegralImage two;
  two.compute_channels(f.view(), Rect{0, 0, 70, 60}, {kLuma, kGrad});
  CHECK(throws_range([&] { project(two, bank, nullptr, 0, xs.data(), ys.data(), 3, out.data()); }));
  const std::int32_t only_plane2[] = {0};
  CHECK(throws_range([&] { CompiledFeatures(bank, only_plane2, 1, two); }));
  const std::int32_t only_planes01[] = {1};
  CHECK(!throws_range([&] { CompiledFeatures(bank, only_planes01, 1, two); }));
  const double mu1[] = {10.0}, s1[] = {5.0}, mu0[] = {0.0}, s0[] = {5.0};
  const WeakGaussians weak(mu1, s1, mu0, s0, 1, 1e-30);
  CHECK(throws_range([&] { score_grid(two, bank, only_plane2, 1, weak, Rect{20, 20, 10, 10}, 5, 1, 70, 60, nullptr); }));
  // ... even when no candidate fits in the frame.
  CHECK(throws_range([&] { score_grid(two, bank, only_plane2, 1, weak, Rect{0, 0, 100, 10}, 5, 1, 70, 60, nullptr); }));
  bool threw = false;
  try {
    FeatureBank bad({0, 1}, {Rect{0, 0, 2, 2}}, {1.0}, {-1});
  } catch (const std::invalid_argument&) {
    threw = true;
  }
  CHECK(threw);
  threw = false;
  try {
    FeatureBank bad({0, 1}, {Rect{0, 0, 2, 2}}, {1.0}, {0, 1});
  } catch (const std::invalid_argument&) {
    threw = true;
  }
  CHECK(threw);

}

void test_planeless_banks(const Frame& f) {
  std::vector<std::int32_t> xs{0, 10, 60}, ys{0, 20, 54};
  const double mu1[] = {10.0}, s1[] = {5.0}, mu0[] = {0.0}, s0[] = {5.0};
  const WeakGaussians weak(mu1, s1, mu0, s0, 1, 1e-30);
  // A bank without planes and one with all zeros give bit-identical results on plane 0 of
  // a stacked table and on a luma-only table.
  FeatureBank plain({0, 1, 3}, {Rect{1, 2, 5, 4}, Rect{0, 0, 3, 3}, Rect{4, 4, 6, 2}}, {1.0, 0.5, -2.0});
  FeatureBank zeros({0, 1, 3}, {Rect{1, 2, 5, 4}, Rect{0, 0, 3, 3}, Rect{4, 4, 6, 2}}, {1.0, 0.5, -2.0},
                    {0, 0, 0});
  IntegralImage luma, stacked;
  luma.compute(f.view(), Rect{0, 0, 70, 60});
  stacked.compute_channels(f.view(), Rect{0, 0, 70, 60}, {kLuma, kOppRG});
  std::vector<double> ref(6), got(6);
  project(luma, plain, nullptr, 0, xs.data(), ys.data(), 3, ref.data());
  project(stacked, zeros, nullptr, 0, xs.data(), ys.data(), 3, got.data());
  CHECK(ref == got);
  const std::int32_t sel[] = {1};
  const GridResult g1 = score_grid(luma, plain, sel, 1, weak, Rect{30, 30, 10, 8}, 6, 1, 70, 60, nullptr);
  const GridResult g2 = score_grid(stacked, zeros, sel, 1, weak, Rect{30, 30, 10, 8}, 6, 1, 70, 60, nullptr);
  CHECK(g1.dx == g2.dx && g1.dy == g2.dy && g1.score == g2.score && g1.candidates == g2.candidates);
}

void test_channels(std::mt19937& rng) {
  test_channel_tables(rng);
  test_channel_refusals(rng);
  const Frame f = random_frame(60, 70, 3, rng);
  test_features_on_planes(f);
  test_planeless_banks(f);
}

// Issue 12: an uncomputed image refuses every read; a failed compute leaves the object as it
// was; a log ratio depends on its own value only.
// An uncomputed integral image is refused by project and score_grid.
void test_uncomputed_refused() {
  FeatureBank bank({0, 1}, {Rect{0, 0, 2, 2}}, {1.0});
  IntegralImage empty;
  CHECK(!empty.computed());
  CHECK(!empty.covers(Rect{0, 0, 0, 0}));
  const std::int32_t zero = 0, zero_y = 0;
  double out = 0.0;
  bool threw = false;
  try {
    project(empty, bank, nullptr, 0, &zero, &zero_y, 1, &out);
  } catch (const std::invalid_argument&) {
    threw = true;
  }
  CHECK(threw);
  const double mu[] = {0.0}, sg[] = {1.0};
  const WeakGaussians weak1(mu, sg, mu, sg, 1, 1e-30);
  threw = false;
  try {
    score_grid(empty, bank, &zero, 1, weak1, Rect{0, 0, 2, 2}, 3, 1, 10, 10, nullptr);
  } catch (const std::invalid_argument&) {
    threw = true;
  }
  CHECK(threw);
}

void test_strong_guarantee(std::mt19937& rng) {
  // Strong guarantee: a bad ROI and a failed allocation leave the table untouched.
  const Frame f = random_frame(30, 40, 3, rng);
  IntegralImage ii;
  ii.compute(f.view(), Rect{2, 3, 20, 10});
  const std::vector<IntegralImage::Entry> before(ii.data(), ii.data() + ii.plane_size());
  bool threw = false;
  try {
    ii.compute_channels(f.view(), Rect{100, 100, 5, 5}, {kLuma});
  } catch (const std::invalid_argument&) {
    threw = true;
  }
  CHECK(threw);
  // A view that claims a huge frame: its table (2^60 entries per plane) exceeds the vector's
  // max_size, so resize throws std::length_error before touching the pixels. (A real
  // std::bad_alloc takes the same path; it is tested from Python: ASan's and valgrind's
  // operator new abort instead of throwing.)
  ImageView huge = f.view();
  huge.rows = huge.cols = 1 << 30;
  threw = false;
  try {
    ii.compute_channels(huge, Rect{0, 0, 1 << 30, 1 << 30}, {kLuma, kLuma});
  } catch (const std::bad_alloc&) {
    threw = true;
  } catch (const std::length_error&) {
    threw = true;
  }
  CHECK(threw);
  CHECK(ii.computed() && ii.x0() == 2 && ii.y0() == 3 && ii.width() == 20 && ii.height() == 10);
  CHECK(ii.num_channels() == 1);
  CHECK(std::equal(before.begin(), before.end(), ii.data()));
}

void test_log_ratio_alone(std::mt19937& rng) {
  // log_ratio: value i gives the same bits alone, at any position of any batch, and next to
  // values that take the guarded formula.
  const double m1[] = {10.0}, s1[] = {3.0}, m0[] = {-4.0}, s0[] = {5.0};
  const WeakGaussians weak(m1, s1, m0, s0, 1, 1e-30);
  std::uniform_real_distribution<double> d(-20.0, 30.0);
  std::vector<double> xs(37), batch(37), scratch(2 * 37 + 2);
  for (double& x : xs) x = d(rng);
  xs[5] = 1e6;  // far in both tails: the guarded formula
  weak.log_ratio(0, xs.data(), 37, batch.data(), false, scratch.data());
  for (int i = 0; i < 37; ++i) {
    for (int offset = 0; offset < 9; ++offset) {  // alone, after `offset` other values
      std::vector<double> in(offset + 1, 0.5), o(offset + 1);
      in[offset] = xs[i];
      weak.log_ratio(0, in.data(), offset + 1, o.data(), false, scratch.data());
      CHECK(o[offset] == batch[i]);
    }
  }
}

void test_hardening(std::mt19937& rng) {
  test_uncomputed_refused();
  test_strong_guarantee(rng);
  test_log_ratio_alone(rng);
}

// The learning kernels: numpy's pairwise sums (exact on integers), a Gaussian update against
// the formulas written out, selections that pick distinct features, and the search.
void test_pairwise_sums() {
  // Integers below 2^53 sum exactly whatever the order: the pairwise sum must equal them.
  for (int n : {0, 1, 7, 8, 9, 127, 128, 129, 300}) {
    std::vector<double> a(static_cast<std::size_t>(2 * n) + 1);
    double want = 0.0;
    for (int i = 0; i < n; ++i) {
      a[static_cast<std::size_t>(2 * i)] = static_cast<double>(i % 17);
      want += static_cast<double>(i % 17);
    }
    CHECK(pairwise_sum(a.data(), n, 2) == want);
  }
}

void test_gaussian_update(const std::vector<double>& hp, const MatrixView& vp, int M, int P) {
  // Gaussian update, blend rule, against the formula.
  std::vector<double> mu(M, 1.0), sigma(M, 2.0), nm(M), ns(M), scratch(P);
  GaussianRule rule;
  rule.lam = 0.85;
  gaussian_update(vp, mu.data(), sigma.data(), rule, nm.data(), ns.data(), scratch.data());
  for (int m = 0; m < M; ++m) {
    double mean = 0.0, var = 0.0;
    for (int j = 0; j < P; ++j) mean += hp[static_cast<std::size_t>(m * P + j)];
    mean /= P;
    for (int j = 0; j < P; ++j) var += std::pow(hp[static_cast<std::size_t>(m * P + j)] - mean, 2);
    var /= P;
    const double want_s = std::sqrt(0.85 * 4.0 + 0.15 * var + 0.85 * 0.15 * (1.0 - mean) * (1.0 - mean));
    CHECK(std::fabs(nm[static_cast<std::size_t>(m)] - (0.85 + 0.15 * mean)) < 1e-12);
    CHECK(std::fabs(ns[static_cast<std::size_t>(m)] - want_s) < 1e-12);
  }
  bool threw = false;
  try {
    gaussian_update(MatrixView{hp.data(), M, 0, P, 1}, mu.data(), sigma.data(), rule, nm.data(),
                    ns.data(), scratch.data());
  } catch (const std::invalid_argument&) {
    threw = true;
  }
  CHECK(threw);
}

void test_selections(const std::vector<double>& hp, const std::vector<double>& hn,
                     const MatrixView& vp, const MatrixView& vn, int M, int P, int N) {
  // Selections: k distinct features in range.
  std::vector<double> w(P, 1.0 / P);
  std::vector<std::int32_t> sel(M);
  wmil_select(vp, vn, w.data(), M, false, sel.data());
  std::vector<std::int32_t> sorted = sel;
  std::sort(sorted.begin(), sorted.end());
  for (int m = 0; m < M; ++m) CHECK(sorted[static_cast<std::size_t>(m)] == m);
  std::vector<double> ep(static_cast<std::size_t>(P * M)), en(static_cast<std::size_t>(N * M));
  for (int m = 0; m < M; ++m) {
    for (int j = 0; j < P; ++j) ep[static_cast<std::size_t>(j * M + m)] = std::exp(hp[static_cast<std::size_t>(m * P + j)]);
    for (int j = 0; j < N; ++j) en[static_cast<std::size_t>(j * M + m)] = std::exp(hn[static_cast<std::size_t>(m * N + j)]);
  }
  std::vector<std::int32_t> sel2(5);
  milboost_select(vp, vn, MatrixView{ep.data(), P, M, M, 1}, MatrixView{en.data(), N, M, M, 1}, 5,
                  1e-5, sel2.data());
  for (std::int32_t f : sel2) CHECK(f >= 0 && f < M);
  // The AVX2 and the portable copies of the selections choose the same features.
  std::vector<std::int32_t> sel_portable(M), sel2_portable(5);
  vmath::force_portable(true);
  wmil_select(vp, vn, w.data(), M, false, sel_portable.data());
  milboost_select(vp, vn, MatrixView{ep.data(), P, M, M, 1}, MatrixView{en.data(), N, M, M, 1}, 5,
                  1e-5, sel2_portable.data());
  vmath::force_portable(false);
  CHECK(sel_portable == sel);
  CHECK(sel2_portable == sel2);
  bool threw = false;
  try {
    wmil_select(vp, vn, w.data(), M + 1, false, sel.data());
  } catch (const std::invalid_argument&) {
    threw = true;
  }
  CHECK(threw);
}

void test_learning(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  test_pairwise_sums();
  const int M = 13, P = 9, N = 11;
  std::vector<double> hp(static_cast<std::size_t>(M * P)), hn(static_cast<std::size_t>(M * N));
  for (double& v : hp) v = u(rng);
  for (double& v : hn) v = u(rng);
  MatrixView vp{hp.data(), M, P, P, 1}, vn{hn.data(), M, N, N, 1};
  test_gaussian_update(hp, vp, M, P);
  test_selections(hp, hn, vp, vn, M, P, N);
}

// Distance in units in the last place between two doubles of the same sign (0 for two NaNs).
std::int64_t ulp_distance(double a, double b) {
  if (std::isnan(a) && std::isnan(b)) return 0;
  if (a == b) return 0;
  if (std::isnan(a) || std::isnan(b) || std::signbit(a) != std::signbit(b)) {
    return std::numeric_limits<std::int64_t>::max();
  }
  std::int64_t ia, ib;
  std::memcpy(&ia, &a, sizeof a);
  std::memcpy(&ib, &b, sizeof b);
  return ia > ib ? ia - ib : ib - ia;
}

// vmath against the C library: within 1 ulp on random values over each function's range (and
// the ranges the kernels use), the special values exact, and the same bits on the CPU's best
// path and on the portable one, for every array length (the tail of an array is padded).
void test_vmath_ulps(std::mt19937& rng) {
  using Fn = void (*)(const double*, double*, int);
  struct Case {
    const char* name;
    Fn fn;
    double (*ref)(double);
    double lo, hi;
    bool log_spaced;  // x = exp(uniform(lo, hi))
  };
  const Case cases[] = {
      {"exp", vmath::exp, [](double v) { return std::exp(v); }, -1.0, 1.0, false},
      {"exp", vmath::exp, [](double v) { return std::exp(v); }, -760.0, 720.0, false},
      {"log", vmath::log, [](double v) { return std::log(v); }, -744.0, 709.0, true},
      {"log", vmath::log, [](double v) { return std::log(v); }, 0.5, 2.0, false},
      {"log1p", vmath::log1p, [](double v) { return std::log1p(v); }, -40.0, 0.0, true},
      {"log1p", vmath::log1p, [](double v) { return std::log1p(v); }, -0.999, 10.0, false},
  };
  const int n = 200003;  // odd: a padded tail
  std::vector<double> x(n), y(n), z(n);
  for (const Case& c : cases) {
    std::uniform_real_distribution<double> d(c.lo, c.hi);
    for (double& v : x) v = c.log_spaced ? std::exp(d(rng)) : d(rng);
    c.fn(x.data(), y.data(), n);
    std::int64_t worst = 0;
    for (int i = 0; i < n; ++i) worst = std::max(worst, ulp_distance(y[i], c.ref(x[i])));
    if (worst > 1) std::fprintf(stderr, "vmath::%s on [%g, %g]: %lld ulp\n", c.name, c.lo, c.hi,
                                static_cast<long long>(worst));
    CHECK(worst <= 1);
    vmath::force_portable(true);
    c.fn(x.data(), z.data(), n);
    vmath::force_portable(false);
    CHECK(std::memcmp(y.data(), z.data(), sizeof(double) * static_cast<std::size_t>(n)) == 0);
    for (int len = 0; len <= 9; ++len) {  // short arrays: the same values as in the long one
      std::vector<double> part(x.begin(), x.begin() + len), out(static_cast<std::size_t>(len));
      c.fn(part.data(), out.data(), len);
      for (int i = 0; i < len; ++i) CHECK(std::memcmp(&out[static_cast<std::size_t>(i)], &y[static_cast<std::size_t>(i)], sizeof(double)) == 0);
    }
  }
}

// The special values, within 1 ulp of the C library (or exact).
void test_vmath_specials() {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double specials[] = {0.0, -0.0, 1.0, -1.0, inf, -inf, nan, 5e-324, 1e-310, 2.5e-308,
                             709.78, 709.79, -708.5, -745.1, -745.2, 1e300, -1e300, 1e-20};
  for (const double v : specials) {
    double e, l, l1;
    vmath::exp(&v, &e, 1);
    vmath::log(&v, &l, 1);
    vmath::log1p(&v, &l1, 1);
    CHECK(ulp_distance(e, std::exp(v)) <= 1);
    CHECK(ulp_distance(l, std::log(v)) <= 1);
    CHECK(ulp_distance(l1, std::log1p(v)) <= 1 || (v == 0.0 && l1 == 0.0));
  }
}

void test_vmath_rows(std::mt19937& rng) {
  // In place, and weighted_rows against a plain loop (the same order of summation: same bits).
  std::vector<double> w = {0.5, -1.0, 2.0}, separate(3);
  vmath::exp(w.data(), separate.data(), 3);
  vmath::exp(w.data(), w.data(), 3);
  CHECK(std::memcmp(w.data(), separate.data(), 3 * sizeof(double)) == 0);
  for (const int width : {1, 15, 16, 17, 100}) {
    const int rows = 37;
    std::normal_distribution<double> g(0.0, 3.0);
    std::vector<double> a(static_cast<std::size_t>(rows * width)), gv(static_cast<std::size_t>(rows)),
        out(static_cast<std::size_t>(width)), portable(out.size());
    for (double& v : a) v = g(rng);
    for (double& v : gv) v = g(rng);
    vmath::weighted_rows(a.data(), rows, width, gv.data(), out.data());
    vmath::force_portable(true);
    vmath::weighted_rows(a.data(), rows, width, gv.data(), portable.data());
    vmath::force_portable(false);
    for (int m = 0; m < width; ++m) {
      double acc = 0.0;
      for (int j = 0; j < rows; ++j) acc = acc + a[static_cast<std::size_t>(j * width + m)] * gv[static_cast<std::size_t>(j)];
      CHECK(std::memcmp(&acc, &out[static_cast<std::size_t>(m)], sizeof acc) == 0);
      CHECK(std::memcmp(&acc, &portable[static_cast<std::size_t>(m)], sizeof acc) == 0);
    }
  }
  std::printf("test_core: vmath path %s\n", vmath::isa());
}

void test_vmath(std::mt19937& rng) {
  test_vmath_ulps(rng);
  test_vmath_specials();
  test_vmath_rows(rng);
}

}  // namespace

// One grid's scores against project() and the weak classifiers summed feature by feature:
// -inf off the disc or the frame, else within float rounding.
static bool grid_matches_projection(const IntegralImage& ii, const FeatureBank& bank,
                                    const std::vector<std::int32_t>& sel, const WeakGaussians& weak,
                                    Rect box, int step, int n, const std::vector<double>& scores) {
  const int side = 2 * n + 1;
  bool exact = true;
  for (int j = -n; j <= n; ++j) {
    for (int i = -n; i <= n; ++i) {
      const double got = scores[static_cast<std::size_t>((j + n) * side + i + n)];
      const int x = box.x + i * step, y = box.y + j * step;
      const bool in = (i * step) * (i * step) + (j * step) * (j * step) < 400 && x >= 0 &&
                      y >= 0 && x + box.w <= 110 && y + box.h <= 90;
      if (!in) {
        exact = exact && std::isinf(got);
        continue;
      }
      double values[5], total = 0.0;
      project(ii, bank, sel.data(), 5, &x, &y, 1, values);
      for (int k = 0; k < 5; ++k) {
        double h;
        weak.log_ratio(k, values + k, 1, &h, false, nullptr);
        total += h;
      }
      exact = exact && std::fabs(got - total) <= 1e-4 + 1e-5 * std::fabs(total);
    }
  }
  return exact;
}

// score_grid's scores against project() and the weak classifiers summed feature by feature
// from 0.0, for every step (the vector loops read a phase-split copy for step > 1), on both
// copies of the vector loops and on the frame's edge: within float rounding (the search sums
// the exact-path log ratios in float, issue 28), and bit for bit the same on both copies.
void test_grid_exact(std::mt19937& rng) {
  const Frame f = random_frame(90, 110, 3, rng);
  std::vector<std::int32_t> starts{0};
  std::vector<Rect> rects;
  std::vector<double> weights;
  std::uniform_int_distribution<int> pos(0, 17), size(1, 7), count(1, 4);
  std::uniform_real_distribution<double> weight(-2.0, 2.0);
  for (int k = 0; k < 12; ++k) {
    for (int r = count(rng); r > 0; --r) {
      rects.push_back(Rect{pos(rng), pos(rng), size(rng), size(rng)});
      weights.push_back(weight(rng));
    }
    starts.push_back(static_cast<std::int32_t>(rects.size()));
  }
  const FeatureBank bank(starts, rects, weights);
  const std::vector<std::int32_t> sel{3, 0, 7, 11, 5};
  std::vector<double> mu1(5), s1(5), mu0(5), s0(5);
  std::normal_distribution<double> centre(0.0, 400.0);
  std::uniform_real_distribution<double> spread(20.0, 300.0);
  for (int k = 0; k < 5; ++k) {
    mu1[k] = centre(rng), mu0[k] = centre(rng), s1[k] = spread(rng), s0[k] = spread(rng);
  }
  const WeakGaussians weak(mu1.data(), s1.data(), mu0.data(), s0.data(), 5, 1e-30);
  IntegralImage ii;
  ii.compute(f.view(), Rect{0, 0, 110, 90});
  bool exact = true;
  std::vector<std::vector<double>> first_copy;  // the AVX2 pass's scores, grid by grid
  std::size_t grid_index = 0;
  for (const bool portable : {false, true}) {
    vmath::force_portable(portable);
    grid_index = 0;
    for (const Rect box : {Rect{40, 30, 25, 24}, Rect{3, 60, 25, 24}}) {
      for (int step = 1; step <= 5; ++step) {
        const int n = grid_half_size(20, step), side = 2 * n + 1;
        std::vector<double> scores(static_cast<std::size_t>(side * side));
        score_grid(ii, bank, sel.data(), 5, weak, box, 20, step, 110, 90, scores.data());
        if (!portable) {
          first_copy.push_back(scores);
        } else {
          exact = exact && scores == first_copy[grid_index];
        }
        ++grid_index;
        exact = exact && grid_matches_projection(ii, bank, sel, weak, box, step, n, scores);
      }
    }
  }
  vmath::force_portable(false);
  CHECK(exact);
}

// Bag sampling on a plain bit source: every box inside the frame, the positives in offset
// order, the negatives distinct and in offset order, exactly neg_count of them (exact draw)
// or at most that many (Bernoulli), WMIL weights summing to 1; choice_sorted picks k distinct
// sorted indices below n.
std::uint64_t splitmix(void* st) {
  std::uint64_t& s = *static_cast<std::uint64_t*>(st);
  std::uint64_t z = (s += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}
std::uint32_t splitmix32(void* st) { return static_cast<std::uint32_t>(splitmix(st) >> 32); }
double splitmix_double(void* st) { return static_cast<double>(splitmix(st) >> 11) * 0x1.0p-53; }

void test_sampling() {
  std::uint64_t state = 42;
  BitSource bits{{&state, splitmix, splitmix32, splitmix_double, splitmix}};
  for (int k : {0, 1, 7, 50}) {
    const std::vector<std::int64_t> picks = choice_sorted(bits, 60, k);
    bool ok = static_cast<int>(picks.size()) == k;
    for (std::size_t i = 0; i < picks.size(); ++i) {
      ok = ok && picks[i] >= 0 && picks[i] < 60 && (i == 0 || picks[i] > picks[i - 1]);
    }
    CHECK(ok);
  }
  std::vector<std::int32_t> pos, neg;
  for (int dy = -3; dy <= 3; ++dy)
    for (int dx = -3; dx <= 3; ++dx)
      if (dx * dx + dy * dy < 16) pos.push_back(dx), pos.push_back(dy);
  for (int dy = -20; dy <= 20; ++dy)
    for (int dx = -20; dx <= 20; ++dx)
      if (dx * dx + dy * dy >= 64 && dx * dx + dy * dy < 400) neg.push_back(dx), neg.push_back(dy);
  std::vector<double> terms(pos.size() / 2);
  for (std::size_t i = 0; i < terms.size(); ++i) terms[i] = std::exp(-std::hypot(pos[2 * i], pos[2 * i + 1]));
  for (const bool exact : {true, false}) {
    for (const Rect box : {Rect{50, 40, 20, 16}, Rect{0, 2, 20, 16}, Rect{78, 60, 22, 20}}) {
      BagSpec spec;
      spec.pos = pos.data();
      spec.n_pos_offsets = static_cast<int>(pos.size() / 2);
      spec.pos_terms = terms.data();
      spec.weights = InstanceWeights::kExp;
      spec.neg = neg.data();
      spec.n_neg_offsets = static_cast<int>(neg.size() / 2);
      spec.exact = exact;
      spec.neg_count = 30;
      spec.keep_prob = 0.05;
      const Bags b = sample_bags(spec, box, 100, 80, bits);
      bool ok = b.xs.size() == b.ys.size() && static_cast<int>(b.w_pos.size()) == b.n_pos;
      double wsum = 0.0;
      for (const double w : b.w_pos) wsum += w;
      ok = ok && (b.n_pos == 0 || std::abs(wsum - 1.0) < 1e-12);
      const int n_neg = static_cast<int>(b.xs.size()) - b.n_pos;
      ok = ok && n_neg <= 30 && (!exact || n_neg == 30);
      for (std::size_t i = 0; i < b.xs.size(); ++i) {
        ok = ok && b.xs[i] >= 0 && b.ys[i] >= 0 && b.xs[i] + box.w <= 100 && b.ys[i] + box.h <= 80;
        // offset order (row-major: dy, then dx) within each bag, so no repeats
        if (i > 0 && static_cast<int>(i) != b.n_pos) {
          const std::int64_t a = (static_cast<std::int64_t>(b.ys[i - 1]) << 32) + b.xs[i - 1];
          const std::int64_t c = (static_cast<std::int64_t>(b.ys[i]) << 32) + b.xs[i];
          ok = ok && a < c;
        }
      }
      CHECK(ok);
    }
  }
}

int main() {
  std::mt19937 rng(1234);
  test_sampling();
  test_grid_exact(rng);
  test_integral(rng);
  test_projection_and_scoring(rng);
  test_overflow_guards(rng);
  test_channels(rng);
  test_hardening(rng);
  test_learning(rng);
  test_vmath(rng);
  if (wmiltrack_test::failures == 0) {
    std::printf("test_core: all checks passed\n");
    return EXIT_SUCCESS;
  }
  std::printf("test_core: %d checks failed\n", wmiltrack_test::failures);
  return EXIT_FAILURE;
}
