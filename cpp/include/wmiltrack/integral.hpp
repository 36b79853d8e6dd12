// Integral image over a region of interest of an 8-bit frame.
//
// The tracker only ever looks at the target's neighbourhood (search grid plus sampling
// annulus), so the integral image is built over that rectangle alone, converting BGR(A)
// to luma on the fly with the same fixed-point weights as cv::COLOR_BGR2GRAY.
//
// Sums are stored as 32-bit unsigned integers, modulo 2^32: a rectangle's sum
// (br - tr) - (bl - tl) computed in the same modular arithmetic is exact whenever the true
// sum is below 2^32, i.e. for every rectangle of at most kMaxExactRectArea pixels (about
// 4100 x 4100), however large the table. Half the bytes of doubles, and a vector register
// holds twice as many entries: the search's feature sums read and convert 8 candidates a step
// with AVX2. Each table row is the row above plus the row's running sums.
// compute_channels() builds several channels over the same ROI at once, one table per
// channel ("plane"), stacked in one buffer: plane k starts at k * plane_size(). Every channel
// is integer-valued in 0..255, so the tables stay exact like the luma one.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace wmiltrack {

// Channel ids of IntegralImage::compute_channels. Every channel is an integer in 0..255 per
// pixel. L is the luma (kLuma); gx = L(x+1, y) - L(x-1, y), gy = L(x, y+1) - L(x, y-1) are
// central differences in frame coordinates (y grows downwards), taken with the neighbours
// outside the ROI when the frame has them and with the edge pixel replicated at the frame's
// border, so a pixel's value never depends on the ROI.
enum Channel : int {
  kLuma = 0,     // OpenCV BGR2GRAY fixed point (the frame itself for 1-channel frames)
  kGrad = 1,     // (|gx| + |gy|) / 2, rounded down: L1 gradient magnitude halved into 0..255
  kOppRG = 2,    // (R - G + 255) / 2, rounded down (colour frames only)
  kOppYB = 3,    // (R + G - 2B + 510) / 4, rounded down (colour frames only)
};
constexpr int kNumChannelKinds = 4;

// A rectangle in frame pixel coordinates: columns [x, x + w), rows [y, y + h).
struct Rect {
  int x = 0;
  int y = 0;
  int w = 0;
  int h = 0;
};

// A borrowed, possibly strided, 8-bit image with 1, 3 (BGR) or 4 (BGRA) channels.
struct ImageView {
  const std::uint8_t* data = nullptr;
  int rows = 0;
  int cols = 0;
  int channels = 1;
  std::ptrdiff_t row_stride = 0;      // bytes between rows
  std::ptrdiff_t col_stride = 1;      // bytes between columns
  std::ptrdiff_t channel_stride = 1;  // bytes between channels
};

// Largest rectangle (in pixels) whose sum of 0..255 values is below 2^32, so exact in the
// table's 32-bit modular arithmetic. Kernels that read feature rectangles refuse larger ones.
constexpr std::int64_t kMaxExactRectArea = 4294967295LL / 255;  // 16 843 009

class IntegralImage {
 public:
  using Entry = std::uint32_t;  // one table entry: a sum modulo 2^32 (see above)

  // Rebuild over `roi` (clipped to the frame). Throws std::invalid_argument for an empty
  // image, an unsupported channel count or an ROI that does not meet the frame.
  // Strong exception guarantee (for compute_channels() too): the new table is built in a
  // new buffer and swapped in when complete, so a throw (std::bad_alloc included) leaves
  // the object unchanged. Not safe against concurrent readers of the same object: see
  // SharedIntegralImage (shared.hpp) for an object that threads may share.
  void compute(const ImageView& image, Rect roi);

  // Rebuild over `roi` with one plane per entry of `channels` (Channel ids; repeats
  // allowed): plane k holds channel channels[k]. Same ROI rules and errors as compute(),
  // plus std::invalid_argument for no channels, an unknown id, or a colour channel
  // (kOppRG, kOppYB) on a 1-channel frame. Cost: one pass over the ROI (plus a one-pixel
  // border for the gradient channels), independent of the frame's size.
  void compute_channels(const ImageView& image, Rect roi, const std::vector<int>& channels);

  // compute_channels() in place, reusing this table's buffer (no new allocation when the
  // table is no larger than before), with the basic guarantee only: a throw leaves the
  // table not computed.
  void rebuild(const ImageView& image, Rect roi, const std::vector<int>& channels);

  // False until a compute() or compute_channels() succeeded: the table is empty then and
  // nothing may be read from it (sum(), plane(), data()).
  bool computed() const { return !data_.empty(); }

  void swap(IntegralImage& other) noexcept;

  int x0() const { return x0_; }
  int y0() const { return y0_; }
  int width() const { return width_; }
  int height() const { return height_; }
  // Elements between consecutive rows of the (height + 1) x (width + 1) table.
  std::ptrdiff_t stride() const { return static_cast<std::ptrdiff_t>(width_) + 1; }
  // Elements between consecutive planes: (height + 1) * (width + 1).
  std::ptrdiff_t plane_size() const {
    return stride() * (static_cast<std::ptrdiff_t>(height_) + 1);
  }
  // Planes in the table (1 after compute()) and the channel each holds.
  int num_channels() const { return static_cast<int>(channels_.size()); }
  const std::vector<int>& channels() const { return channels_; }
  // Plane 0 (plane k starts at data() + k * plane_size()).
  const Entry* data() const { return data_.data(); }
  // Plane k; the caller guarantees 0 <= k < num_channels().
  const Entry* plane(int k) const { return data_.data() + k * plane_size(); }

  // Plane k as the true sums (not modulo 2^32): (height + 1) x (width + 1) doubles into `out`,
  // row and column 0 zero; exact below 2^53. The caller guarantees 0 <= k < num_channels().
  void copy_plane(int k, double* out) const;

  // True when the frame rectangle lies inside the region the table covers (never before the
  // first compute). The far edges
  // are computed in 64 bits: x + w of two large ints must not wrap around and pass.
  bool covers(const Rect& r) const {
    return computed() && r.x >= x0_ && r.y >= y0_ && r.w >= 0 && r.h >= 0 &&
           static_cast<std::int64_t>(r.x) + r.w <= static_cast<std::int64_t>(x0_) + width_ &&
           static_cast<std::int64_t>(r.y) + r.h <= static_cast<std::int64_t>(y0_) + height_;
  }

  // Exact pixel sum over a frame rectangle on plane k; the caller guarantees covers(r) and
  // 0 <= k < num_channels(). A rectangle larger than kMaxExactRectArea is summed in bands.
  double sum(const Rect& r, int k = 0) const {
    const std::int64_t area = static_cast<std::int64_t>(r.w) * r.h;
    if (area <= kMaxExactRectArea) return static_cast<double>(band_sum(r.x, r.y, r.w, r.h, k));
    const int band = static_cast<int>(std::max<std::int64_t>(1, kMaxExactRectArea / std::max(r.w, 1)));
    double total = 0.0;
    for (int y = r.y; y < r.y + r.h; y += band) {
      const int h = std::min(band, r.y + r.h - y);
      if (static_cast<std::int64_t>(r.w) * h <= kMaxExactRectArea) {
        total += static_cast<double>(band_sum(r.x, y, r.w, h, k));
      } else {  // a single row wider than kMaxExactRectArea: columns in pieces
        for (int x = r.x; x < r.x + r.w; x += static_cast<int>(kMaxExactRectArea)) {
          const int w = static_cast<int>(std::min<std::int64_t>(kMaxExactRectArea, r.x + r.w - x));
          total += static_cast<double>(band_sum(x, y, w, 1, k));
        }
      }
    }
    return total;
  }

 private:
  // The table-building loops, run on a fresh object by compute() / compute_channels().
  void build_channels(const ImageView& image, Rect roi, const std::vector<int>& channels);

  int x0_ = 0;
  int y0_ = 0;
  int width_ = 0;
  int height_ = 0;
  // The modular sum of a rectangle of at most kMaxExactRectArea pixels (then exact).
  std::uint32_t band_sum(int x, int y, int w, int h, int k) const {
    const Entry* top = plane(k) + (y - y0_) * stride() + (x - x0_);
    const Entry* bottom = top + static_cast<std::ptrdiff_t>(h) * stride();
    return (bottom[w] - top[w]) - (bottom[0] - top[0]);
  }

  std::vector<int> channels_;
  std::vector<Entry> data_;
};

// Luma of one BGR pixel, bit-exact with OpenCV's 8-bit BGR2GRAY: ITU-R 601 weights
// 0.114/0.587/0.299 in 15-bit fixed point (summing to 2^15), rounded.
inline std::uint8_t bgr_to_gray(std::uint8_t b, std::uint8_t g, std::uint8_t r) {
  constexpr int kB = 3735;
  constexpr int kG = 19235;
  constexpr int kR = 9798;
  return static_cast<std::uint8_t>((b * kB + g * kG + r * kR + (1 << 14)) >> 15);
}

// bgr_to_gray() of frame row y, columns [xa, xb) (inside the frame), into out[0 .. xb - xa);
// a 1-channel frame's bytes are copied. Packed BGR rows take SSSE3/AVX2 where the CPU has
// them (the same bytes), and so do views of every k-th column of one (k <= 8: the span is
// converted, every k-th value kept). The one conversion the integral image and the
// correlation filters' patches share.
void luma_row(const ImageView& image, int y, int xa, int xb, std::uint8_t* out);

}  // namespace wmiltrack
