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
  FeatureBank(std::vector<std::int32_t> starts, std::vector<Rect> rects,
              std::vector<double> weights);

  int size() const { return static_cast<int>(starts_.size()) - 1; }
  int num_rects() const { return static_cast<int>(rects_.size()); }
  const std::vector<std::int32_t>& starts() const { return starts_; }
  const std::vector<Rect>& rects() const { return rects_; }
  const std::vector<double>& weights() const { return weights_; }
  // The smallest rectangle, relative to the box corner, that holds every feature's rectangles.
  const Rect& extent() const { return extent_; }

 private:
  std::vector<std::int32_t> starts_;
  std::vector<Rect> rects_;
  std::vector<double> weights_;
  Rect extent_;
};

// The rectangles of a chosen subset of features, turned into flat offsets into one integral
// image, so that evaluating a feature at a box is four loads per rectangle from a base pointer.
class CompiledFeatures {
 public:
  // `features` indexes the bank (nullptr/0 = every feature, in order).
  CompiledFeatures(const FeatureBank& bank, const std::int32_t* features, int n_features,
                   std::ptrdiff_t stride);

  int size() const { return static_cast<int>(starts_.size()) - 1; }

  // Value of feature k for the box whose top-left table entry is `base`.
  double value(const double* base, int k) const {
    double v = 0.0;
    for (int r = starts_[k]; r < starts_[k + 1]; ++r) {
      const Corners& c = corners_[r];
      v += c.weight * ((base[c.br] - base[c.tr]) - (base[c.bl] - base[c.tl]));
    }
    return v;
  }

  // Table offsets of one rectangle's four corners, relative to the box's top-left entry.
  struct Corners {
    std::ptrdiff_t tl, tr, bl, br;
    double weight;
  };
  int first_rect(int k) const { return starts_[k]; }
  int end_rect(int k) const { return starts_[k + 1]; }
  const Corners& corners(int r) const { return corners_[r]; }

 private:
  std::vector<std::int32_t> starts_;
  std::vector<Corners> corners_;
};

// Checks that features at every box lie inside the integral image; throws std::out_of_range.
void check_boxes_covered(const IntegralImage& ii, const FeatureBank& bank, const std::int32_t* xs,
                         const std::int32_t* ys, int n_boxes);

// out[k * n_boxes + n] = value of feature features[k] (or k) at box n, whose top-left corner
// is (xs[n], ys[n]) in frame coordinates.
void project(const IntegralImage& ii, const FeatureBank& bank, const std::int32_t* features,
             int n_features, const std::int32_t* xs, const std::int32_t* ys, int n_boxes,
             double* out);

}  // namespace wmiltrack
