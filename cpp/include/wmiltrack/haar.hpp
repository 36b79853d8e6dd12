// Haar-like feature bank: each feature is a weighted sum of a few rectangle sums taken at
// fixed offsets from a sample box's top-left corner.
#pragma once

#include <cstdint>
#include <vector>

#include "wmiltrack/integral.hpp"

namespace wmiltrack {

class FeatureBank {
 public:
  // `starts` has one entry per feature plus a final one: feature f owns rectangles
  // starts[f] .. starts[f+1]-1. Rectangles are relative to the box's top-left corner.
  // `planes` (empty = all 0) gives each rectangle the integral-image plane it sums over
  // (IntegralImage::compute_channels); plane indices must be >= 0. A rectangle may hold at
  // most kMaxExactRectArea pixels (its sum must be exact in the table's 32-bit entries).
  FeatureBank(std::vector<std::int32_t> starts, std::vector<Rect> rects,
              std::vector<double> weights, std::vector<std::int32_t> planes = {});

  int size() const { return static_cast<int>(starts_.size()) - 1; }
  int num_rects() const { return static_cast<int>(rects_.size()); }
  const std::vector<std::int32_t>& starts() const { return starts_; }
  const std::vector<Rect>& rects() const { return rects_; }
  const std::vector<double>& weights() const { return weights_; }
  // Plane of each rectangle (one entry per rectangle, 0 when none were given).
  const std::vector<std::int32_t>& planes() const { return planes_; }
  // 1 + the largest plane any rectangle uses: the planes an integral image needs.
  int planes_needed() const { return planes_needed_; }
  // The smallest rectangle, relative to the box corner, that holds every feature's rectangles.
  const Rect& extent() const { return extent_; }

 private:
  std::vector<std::int32_t> starts_;
  std::vector<Rect> rects_;
  std::vector<double> weights_;
  std::vector<std::int32_t> planes_;
  int planes_needed_ = 1;
  Rect extent_;
};

// The rectangles of a chosen subset of features, turned into flat offsets into one integral
// image, so that evaluating a feature at a box is four loads per rectangle from a base pointer
// (the base pointing into plane 0; a rectangle on plane p carries p * plane_size in its offsets).
class CompiledFeatures {
 public:
  // `features` indexes the bank (nullptr/0 = every feature, in order). Throws
  // std::out_of_range for a feature index outside the bank or a rectangle on a plane
  // >= num_planes.
  CompiledFeatures(const FeatureBank& bank, const std::int32_t* features, int n_features,
                   std::ptrdiff_t stride, std::ptrdiff_t plane_size = 0, int num_planes = 1);
  // The same for the layout of `ii` (its stride, plane size and number of planes).
  CompiledFeatures(const FeatureBank& bank, const std::int32_t* features, int n_features,
                   const IntegralImage& ii)
      : CompiledFeatures(bank, features, n_features, ii.stride(), ii.plane_size(),
                         ii.num_channels()) {}

  int size() const { return static_cast<int>(starts_.size()) - 1; }

  // Value of feature k for the box whose top-left table entry is `base`: the weighted sum of
  // its rectangles' exact sums, added in order from 0.0.
  double value(const IntegralImage::Entry* base, int k) const {
    return value_of(base, corners_.data() + starts_[k], starts_[k + 1] - starts_[k]);
  }

  // Rectangle r's sum at the box whose top-left table entry is `base` (modular, then exact:
  // FeatureBank keeps every rectangle within kMaxExactRectArea).
  double rect_sum(const IntegralImage::Entry* base, int r) const { return sum_of(base, corners_[r]); }

  // Table offsets of one rectangle's four corners, relative to the box's top-left entry.
  struct Corners {
    std::ptrdiff_t tl, tr, bl, br;
    double weight;
  };
  // The same for any corners laid out like these (the search's phase-split copy of the table
  // has its own offsets): rectangles c[0..n) weighted and added in order from 0.0.
  static double value_of(const IntegralImage::Entry* base, const Corners* c, int n) {
    double v = 0.0;
    for (int r = 0; r < n; ++r) v += c[r].weight * sum_of(base, c[r]);
    return v;
  }
  static double sum_of(const IntegralImage::Entry* base, const Corners& c) {
    return static_cast<double>((base[c.br] - base[c.tr]) - (base[c.bl] - base[c.tl]));
  }

  int first_rect(int k) const { return starts_[k]; }
  int num_rects() const { return static_cast<int>(corners_.size()); }
  // The largest rectangle's area in pixels (0 for no rectangle).
  std::int64_t max_rect_area() const { return max_rect_area_; }
  int end_rect(int k) const { return starts_[k + 1]; }
  const Corners& corners(int r) const { return corners_[r]; }

 private:
  std::vector<std::int32_t> starts_;
  std::vector<Corners> corners_;
  std::int64_t max_rect_area_ = 0;
};

// Checks that features at every box lie inside the integral image's region and that the
// image has every plane the bank uses; throws std::out_of_range (std::invalid_argument for
// an integral image that was never computed).
void check_boxes_covered(const IntegralImage& ii, const FeatureBank& bank, const std::int32_t* xs,
                         const std::int32_t* ys, int n_boxes);

// out[k * n_boxes + n] = value of feature features[k] (or k) at box n, whose top-left corner
// is (xs[n], ys[n]) in frame coordinates. Same checks and errors as check_boxes_covered(),
// made box by box on the value that is then used (each coordinate is read once).
void project(const IntegralImage& ii, const FeatureBank& bank, const std::int32_t* features,
             int n_features, const std::int32_t* xs, const std::int32_t* ys, int n_boxes,
             double* out);

}  // namespace wmiltrack
