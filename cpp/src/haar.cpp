#include "wmiltrack/haar.hpp"

#include "grid_runs.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace wmiltrack {

FeatureBank::FeatureBank(std::vector<std::int32_t> starts, std::vector<Rect> rects,
                         std::vector<double> weights, std::vector<std::int32_t> planes)
    : starts_(std::move(starts)),
      rects_(std::move(rects)),
      weights_(std::move(weights)),
      planes_(std::move(planes)) {
  if (starts_.size() < 2 || starts_.front() != 0) {
    throw std::invalid_argument("feature bank: starts must begin with 0 and hold >= 1 feature");
  }
  if (rects_.size() != weights_.size() ||
      static_cast<std::size_t>(starts_.back()) != rects_.size()) {
    throw std::invalid_argument("feature bank: starts, rects and weights disagree in length");
  }
  if (planes_.empty()) {
    planes_.assign(rects_.size(), 0);
  } else if (planes_.size() != rects_.size()) {
    throw std::invalid_argument("feature bank: planes must have one entry per rectangle");
  }
  for (std::int32_t p : planes_) {
    if (p < 0) throw std::invalid_argument("feature bank: plane indices must be >= 0");
    planes_needed_ = std::max(planes_needed_, p + 1);
  }
  for (std::size_t f = 0; f + 1 < starts_.size(); ++f) {
    if (starts_[f + 1] <= starts_[f]) {
      throw std::invalid_argument("feature bank: every feature needs at least one rectangle");
    }
  }
  int x0 = std::numeric_limits<int>::max(), y0 = x0;
  int x1 = std::numeric_limits<int>::min(), y1 = x1;
  for (const Rect& r : rects_) {
    if (r.x < 0 || r.y < 0 || r.w <= 0 || r.h <= 0) {
      throw std::invalid_argument("feature bank: rectangles need x, y >= 0 and w, h > 0");
    }
    if (r.x > std::numeric_limits<int>::max() - r.w || r.y > std::numeric_limits<int>::max() - r.h) {
      throw std::invalid_argument("feature bank: a rectangle's far edge overflows an int");
    }
    if (static_cast<std::int64_t>(r.w) * r.h > kMaxExactRectArea) {
      throw std::invalid_argument(
          "feature bank: a rectangle of " + std::to_string(static_cast<std::int64_t>(r.w) * r.h) +
          " pixels; at most " + std::to_string(kMaxExactRectArea) +
          " (the integral image sums in 32 bits)");
    }
    x0 = std::min(x0, r.x);
    y0 = std::min(y0, r.y);
    x1 = std::max(x1, r.x + r.w);
    y1 = std::max(y1, r.y + r.h);
  }
  extent_ = Rect{x0, y0, x1 - x0, y1 - y0};
}

CompiledFeatures::CompiledFeatures(const FeatureBank& bank, const std::int32_t* features,
                                   int n_features, std::ptrdiff_t stride,
                                   std::ptrdiff_t plane_size, int num_planes) {
  const bool all = features == nullptr;
  const int n = all ? bank.size() : n_features;
  starts_.reserve(static_cast<std::size_t>(n) + 1);
  starts_.push_back(0);
  std::size_t rects = 0;  // (room for every rectangle at once; a wrong index is refused below)
  for (int k = 0; k < n; ++k) {
    const int f = all ? k : features[k];
    if (f >= 0 && f < bank.size()) rects += static_cast<std::size_t>(bank.starts()[f + 1] - bank.starts()[f]);
  }
  corners_.reserve(rects);
  for (int k = 0; k < n; ++k) {
    const int f = all ? k : features[k];
    if (f < 0 || f >= bank.size()) {
      throw std::out_of_range("feature index " + std::to_string(f) + " outside the bank of " +
                              std::to_string(bank.size()));
    }
    for (int r = bank.starts()[f]; r < bank.starts()[f + 1]; ++r) {
      const Rect& q = bank.rects()[r];
      const std::int32_t p = bank.planes()[r];
      if (p >= num_planes) {
        throw std::out_of_range("feature " + std::to_string(f) + " sums over plane " +
                                std::to_string(p) + " but the integral image has " +
                                std::to_string(num_planes) + " plane(s)");
      }
      const std::ptrdiff_t top = p * plane_size + q.y * stride + q.x;
      const std::ptrdiff_t bottom = top + q.h * stride;
      corners_.push_back(Corners{top, top + q.w, bottom, bottom + q.w, bank.weights()[r]});
      max_rect_area_ = std::max(max_rect_area_, static_cast<std::int64_t>(q.w) * q.h);
    }
    starts_.push_back(static_cast<std::int32_t>(corners_.size()));
  }
}

namespace {

void check_planes(const IntegralImage& ii, const FeatureBank& bank) {
  if (!ii.computed()) throw std::invalid_argument("the integral image has not been computed");
  if (bank.planes_needed() > ii.num_channels()) {
    throw std::out_of_range("the feature bank uses " + std::to_string(bank.planes_needed()) +
                            " plane(s) but the integral image has " +
                            std::to_string(ii.num_channels()));
  }
}

void check_box(const IntegralImage& ii, const Rect& e, std::int32_t bx, std::int32_t by) {
  constexpr std::int64_t kIntMax = std::numeric_limits<int>::max();
  // In 64 bits: a corner near INT_MAX plus the extent's offset must not wrap around.
  const std::int64_t x = static_cast<std::int64_t>(bx) + e.x;
  const std::int64_t y = static_cast<std::int64_t>(by) + e.y;
  if (x > kIntMax || y > kIntMax ||
      !ii.covers(Rect{static_cast<int>(x), static_cast<int>(y), e.w, e.h})) {
    throw std::out_of_range("box at (" + std::to_string(bx) + ", " + std::to_string(by) +
                            ") reaches outside the integral image's region");
  }
}

}  // namespace

void check_boxes_covered(const IntegralImage& ii, const FeatureBank& bank, const std::int32_t* xs,
                         const std::int32_t* ys, int n_boxes) {
  check_planes(ii, bank);
  for (int n = 0; n < n_boxes; ++n) check_box(ii, bank.extent(), xs[n], ys[n]);
}

void project(const IntegralImage& ii, const FeatureBank& bank, const std::int32_t* features,
             int n_features, const std::int32_t* xs, const std::int32_t* ys, int n_boxes,
             double* out) {
  check_planes(ii, bank);
  const CompiledFeatures compiled(bank, features, n_features, ii);
  const int n_out = compiled.size();
  const std::ptrdiff_t s = ii.stride();
  // Each coordinate is read once, checked, and the checked copy used: a caller that changes
  // xs/ys meanwhile gets values for some box, never a read outside the table.
  std::vector<std::ptrdiff_t> base(static_cast<std::size_t>(n_boxes));
  for (int n = 0; n < n_boxes; ++n) {
    const std::int32_t x = xs[n], y = ys[n];
    check_box(ii, bank.extent(), x, y);
    base[static_cast<std::size_t>(n)] = (static_cast<std::ptrdiff_t>(y) - ii.y0()) * s +
                                        (static_cast<std::ptrdiff_t>(x) - ii.x0());
  }
  // The boxes as runs of consecutive columns of one row (a bag's positives are rows of a
  // disc), then feature by feature over the runs: several boxes of a run a step, each value
  // summing its rectangles in order from 0.0, as CompiledFeatures::value does.
  std::vector<GridRun> runs;
  for (int n = 0; n < n_boxes; ++n) {
    const std::size_t i = static_cast<std::size_t>(n);
    if (n > 0 && base[i] == base[i - 1] + 1 && runs.back().first + runs.back().count == n) {
      ++runs.back().count;
    } else {
      runs.push_back(GridRun{n, 1, base[i]});
    }
  }
  const bool vector = compiled.max_rect_area() <= kMaxSignedRectArea;
  const IntegralImage::Entry* table = ii.data();
  for (int k = 0; k < n_out; ++k) {
    const int r0 = compiled.first_rect(k);
    run_values(table, runs, &compiled.corners(r0), compiled.end_rect(k) - r0, vector,
               out + static_cast<std::ptrdiff_t>(k) * n_boxes);
  }
}

}  // namespace wmiltrack
