// Integral image over a region of interest of an 8-bit frame.
//
// The tracker only ever looks at the target's neighbourhood (search grid plus sampling
// annulus), so the integral image is built over that rectangle alone, converting BGR(A)
// to luma on the fly with the same fixed-point weights as cv::COLOR_BGR2GRAY.
//
// Sums are accumulated in 64-bit integers and stored as doubles: every value is an integer
// below 255 * rows * cols, exact in a double for any frame under 3.5e13 pixels, and doubles
// let the scoring loops vectorise (SSE2 has no int64 -> double conversion).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace wmiltrack {

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

class IntegralImage {
 public:
  // Rebuild over `roi` (clipped to the frame). Reuses the buffer when the size allows.
  // Throws std::invalid_argument for an empty image, an unsupported channel count or an
  // ROI that does not meet the frame.
  void compute(const ImageView& image, Rect roi);

  int x0() const { return x0_; }
  int y0() const { return y0_; }
  int width() const { return width_; }
  int height() const { return height_; }
  // Elements between consecutive rows of the (height + 1) x (width + 1) table.
  std::ptrdiff_t stride() const { return static_cast<std::ptrdiff_t>(width_) + 1; }
  const double* data() const { return data_.data(); }

  // True when the frame rectangle lies inside the region the table covers. The far edges
  // are computed in 64 bits: x + w of two large ints must not wrap around and pass.
  bool covers(const Rect& r) const {
    return r.x >= x0_ && r.y >= y0_ && r.w >= 0 && r.h >= 0 &&
           static_cast<std::int64_t>(r.x) + r.w <= static_cast<std::int64_t>(x0_) + width_ &&
           static_cast<std::int64_t>(r.y) + r.h <= static_cast<std::int64_t>(y0_) + height_;
  }

  // Exact pixel sum over a frame rectangle; the caller guarantees covers(r).
  double sum(const Rect& r) const {
    const double* top = data_.data() + (r.y - y0_) * stride() + (r.x - x0_);
    const double* bottom = top + r.h * stride();
    return bottom[r.w] - bottom[0] - top[r.w] + top[0];
  }

 private:
  int x0_ = 0;
  int y0_ = 0;
  int width_ = 0;
  int height_ = 0;
  std::vector<double> data_;
};

// Luma of one BGR pixel, bit-exact with OpenCV's 8-bit BGR2GRAY: ITU-R 601 weights
// 0.114/0.587/0.299 in 15-bit fixed point (summing to 2^15), rounded.
inline std::uint8_t bgr_to_gray(std::uint8_t b, std::uint8_t g, std::uint8_t r) {
  constexpr int kB = 3735;
  constexpr int kG = 19235;
  constexpr int kR = 9798;
  return static_cast<std::uint8_t>((b * kB + g * kG + r * kR + (1 << 14)) >> 15);
}

}  // namespace wmiltrack
