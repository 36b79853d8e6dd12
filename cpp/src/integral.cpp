#include "wmiltrack/integral.hpp"

#include <algorithm>
#include <stdexcept>

namespace wmiltrack {

void IntegralImage::compute(const ImageView& image, Rect roi) {
  if (image.data == nullptr || image.rows <= 0 || image.cols <= 0) {
    throw std::invalid_argument("integral image: the frame is empty");
  }
  if (image.channels != 1 && image.channels != 3 && image.channels != 4) {
    throw std::invalid_argument("integral image: frames need 1, 3 (BGR) or 4 (BGRA) channels");
  }
  const int x_begin = std::max(roi.x, 0);
  const int y_begin = std::max(roi.y, 0);
  // 64-bit far edges: roi.x + roi.w must not overflow for any pair of ints.
  const int x_end = static_cast<int>(
      std::min<std::int64_t>(static_cast<std::int64_t>(roi.x) + roi.w, image.cols));
  const int y_end = static_cast<int>(
      std::min<std::int64_t>(static_cast<std::int64_t>(roi.y) + roi.h, image.rows));
  if (x_end <= x_begin || y_end <= y_begin) {
    throw std::invalid_argument("integral image: the region does not meet the frame");
  }
  x0_ = x_begin;
  y0_ = y_begin;
  width_ = x_end - x_begin;
  height_ = y_end - y_begin;
  const std::ptrdiff_t s = stride();
  data_.assign(static_cast<std::size_t>(s) * static_cast<std::size_t>(height_ + 1), 0.0);
  std::vector<std::int64_t> column(static_cast<std::size_t>(width_) + 1, 0);  // exact running sums

  for (int r = 0; r < height_; ++r) {
    const std::uint8_t* src = image.data + (y0_ + r) * image.row_stride + x0_ * image.col_stride;
    double* out = data_.data() + (r + 1) * s;
    std::int64_t row_sum = 0;
    if (image.channels == 1) {
      for (int c = 0; c < width_; ++c, src += image.col_stride) {
        row_sum += *src;
        column[c + 1] += row_sum;
        out[c + 1] = static_cast<double>(column[c + 1]);
      }
    } else {
      const std::ptrdiff_t cs = image.channel_stride;
      for (int c = 0; c < width_; ++c, src += image.col_stride) {
        row_sum += bgr_to_gray(src[0], src[cs], src[2 * cs]);
        column[c + 1] += row_sum;
        out[c + 1] = static_cast<double>(column[c + 1]);
      }
    }
  }
}

}  // namespace wmiltrack
