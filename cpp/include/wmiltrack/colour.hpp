// rcwmil-plus's colour model (Staple-style foreground/background colour histograms;
// wmiltrack.engine.colour wraps it and the search merges the cue): the histograms, their
// update from a frame, and the integral image of the per-pixel foreground probability.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "wmiltrack/integral.hpp"

namespace wmiltrack {

// Bin of a BGR pixel with `bits` bits per channel: (b >> s) << 2 bits | (g >> s) << bits |
// (r >> s), s = 8 - bits; 2^(3 bits) bins.
inline std::uint32_t colour_bin(std::uint8_t b, std::uint8_t g, std::uint8_t r, int bits) {
  const int s = 8 - bits;
  return (static_cast<std::uint32_t>(b >> s) << (2 * bits)) |
         (static_cast<std::uint32_t>(g >> s) << bits) | static_cast<std::uint32_t>(r >> s);
}

// A rectangle of rows [r0, r1) and columns [c0, c1) of a region (empty when r1 <= r0 or
// c1 <= c0).
struct Span {
  int r0 = 0, r1 = 0, c0 = 0, c1 = 0;
  bool holds(int r, int c) const { return r >= r0 && r < r1 && c >= c0 && c < c1; }
};

// The colour model's state: foreground and background histograms of 2^(3 bits) bins blended
// over frames, and P(target | bin) = fg / (fg + bg) (0.5 where both are 0).
//
// With `intensity`, a pixel's bin is that of its luma repeated in the three channels
// (bgr_to_gray, OpenCV's BGR2GRAY; a 1-channel frame's value as it is): a histogram of
// intensities that takes gray frames too. With a `step` > 1, learn() and likelihood_sums() look
// at the pixels whose frame column and row are multiples of `step` only (a sample of 1 in
// step^2, on a grid fixed to the frame): histograms and means of a large region for a fraction
// of the work. likelihood_integral() always reads every pixel.
//
// A frame's work is proportional to the pixels it looks at and the bins seen so far, not to
// all 32 768 bins of the default 5 bits: a bin never counted holds 0 in both histograms and
// 0.5 in the likelihood for ever (its blend, (1 - rate) 0 + rate 0, stays 0), so only the
// bins seen are blended. The arithmetic per bin is that of a pass over every bin: count /
// sum, (1 - rate) model + rate normalised count, then fg / (fg + bg), in that order.
class ColourHistograms {
 public:
  // bits in 1..8, rate in (0, 1]; std::invalid_argument otherwise.
  ColourHistograms(int bits, double rate, bool intensity = false);

  int bits() const { return bits_; }
  double rate() const { return rate_; }
  int bins() const { return static_cast<int>(fg_.size()); }
  bool learnt() const { return learnt_; }
  bool intensity() const { return intensity_; }

  // Folds in one frame: every pixel of `core` (rows/columns relative to `region`) counts for
  // the foreground, every pixel of the region outside `inside` for the background; each
  // histogram of counts is divided by its sum (at least 1) and blended in at the rate (taken
  // as it is on the first frame). Throws std::invalid_argument for a gray frame (fewer than 3
  // channels) without `intensity`, or a region outside the frame.
  // step >= 1 (std::invalid_argument otherwise): see above.
  void learn(const ImageView& image, const Rect& region, const Span& inside, const Span& core,
             int step = 1);

  // The (region.h + 1) x (region.w + 1) integral image (row-major, zero first row and column)
  // of the likelihood of every pixel of `region`: table[r + 1][c + 1] = table[r][c + 1] + the
  // row's running sum up to column c (the order of cv::integral). Needs learn() first
  // (std::logic_error); the same errors as learn() otherwise.
  void likelihood_integral(const ImageView& image, const Rect& region, double* table) const;

  // The likelihood summed over the (sampled, see `step`) pixels of `region` (inside the
  // frame) and over those of its part `inner` (rows and columns relative to the region,
  // clipped to it), with the number of pixels of each. One pass, no table: what a contrast
  // between a box and its ring needs.
  struct Sums {
    double inner = 0.0, region = 0.0;
    std::int64_t inner_pixels = 0, region_pixels = 0;
  };
  Sums likelihood_sums(const ImageView& image, const Rect& region, const Span& inner,
                       int step = 1) const;

  const std::vector<double>& foreground() const { return fg_; }
  const std::vector<double>& background() const { return bg_; }
  const std::vector<double>& likelihood() const { return lik_; }

 private:
  void count(const ImageView& image, const Rect& region, const Span& inside, const Span& core,
             int step);
  void blend(std::uint32_t bin, double fd, double bd, bool first);

  int bits_;
  double rate_;
  bool intensity_;
  bool learnt_ = false;
  std::vector<double> fg_, bg_, lik_;       // the model
  std::vector<std::uint32_t> fg_count_, bg_count_;  // this frame's counts; zero between frames
  std::vector<std::uint8_t> is_counted_;             // 1 for the bins of counted_
  std::vector<std::uint32_t> counted_;               // bins with a count this frame
  std::vector<std::uint32_t> seen_;          // bins ever counted
  std::vector<std::uint8_t> is_seen_;
};

}  // namespace wmiltrack
