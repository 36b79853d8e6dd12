#include "wmiltrack/integral.hpp"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace wmiltrack {

namespace {

// The ROI clipped to the frame; throws for an empty frame, a bad channel count or an ROI
// that misses the frame.
Rect clip_roi(const ImageView& image, const Rect& roi) {
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
  return Rect{x_begin, y_begin, x_end - x_begin, y_end - y_begin};
}

// Luma of frame row y, columns [xa, xb), into out[0 .. xb - xa).
void luma_row(const ImageView& image, int y, int xa, int xb, std::uint8_t* out) {
  const std::uint8_t* src = image.data + y * image.row_stride + xa * image.col_stride;
  const int n = xb - xa;
  if (image.channels == 1) {
    if (image.col_stride == 1) {
      std::copy(src, src + n, out);
    } else {
      for (int c = 0; c < n; ++c, src += image.col_stride) out[c] = *src;
    }
  } else {
    const std::ptrdiff_t cs = image.channel_stride;
    for (int c = 0; c < n; ++c, src += image.col_stride) out[c] = bgr_to_gray(src[0], src[cs], src[2 * cs]);
  }
}

// Luma of frame row y over the ROI's columns plus one on each side: ext[j] is the luma at
// column x0 - 1 + j (j = 0 .. w + 1), the frame's edge column replicated outside the frame.
void luma_row_ext(const ImageView& image, int y, int x0, int w, std::uint8_t* ext) {
  const int xa = std::max(x0 - 1, 0);
  const int xb = std::min(x0 + w + 1, image.cols);
  luma_row(image, y, xa, xb, ext + (xa - (x0 - 1)));
  if (xa == x0) ext[0] = ext[1];
  if (xb == x0 + w) ext[w + 1] = ext[w];
}

// One table row from one row of channel values: out[c + 1] = prev[c + 1] + sum(v[0..c]).
// Every partial sum is an integer below 2^53, so the doubles are exact.
void accumulate_row(const std::uint8_t* v, int w, const double* prev, double* out) {
  std::int64_t row_sum = 0;
  out[0] = 0.0;
  for (int c = 0; c < w; ++c) {
    row_sum += v[c];
    out[c + 1] = prev[c + 1] + static_cast<double>(row_sum);
  }
}

}  // namespace

// compute() and compute_channels() build a new table in a fresh object and swap it in only
// when complete: an exception (a bad argument, std::bad_alloc) leaves *this as it was.
void IntegralImage::compute(const ImageView& image, Rect roi) {
  IntegralImage next;
  next.build(image, roi);
  swap(next);
}

void IntegralImage::compute_channels(const ImageView& image, Rect roi,
                                     const std::vector<int>& channels) {
  IntegralImage next;
  next.build_channels(image, roi, channels);
  swap(next);
}

void IntegralImage::swap(IntegralImage& other) noexcept {
  std::swap(x0_, other.x0_);
  std::swap(y0_, other.y0_);
  std::swap(width_, other.width_);
  std::swap(height_, other.height_);
  channels_.swap(other.channels_);
  data_.swap(other.data_);
}

void IntegralImage::build(const ImageView& image, Rect roi) {
  const Rect r0 = clip_roi(image, roi);
  x0_ = r0.x;
  y0_ = r0.y;
  width_ = r0.w;
  height_ = r0.h;
  channels_.assign(1, kLuma);
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

void IntegralImage::build_channels(const ImageView& image, Rect roi,
                                   const std::vector<int>& channels) {
  if (channels.empty()) throw std::invalid_argument("integral image: no channels requested");
  bool need_luma = false, need_grad = false, need_orient = false, need_colour = false;
  for (int ch : channels) {
    if (ch < 0 || ch >= kNumChannelKinds) {
      throw std::invalid_argument("integral image: unknown channel id " + std::to_string(ch) +
                                  " (valid: 0 .. " + std::to_string(kNumChannelKinds - 1) + ")");
    }
    need_luma = need_luma || ch == kLuma;
    need_grad = need_grad || ch == kGrad;
    need_orient = need_orient || ch >= kOrient0;
    need_colour = need_colour || ch == kOppRG || ch == kOppYB;
  }
  const Rect r0 = clip_roi(image, roi);
  if (need_colour && image.channels == 1) {
    throw std::invalid_argument(
        "integral image: colour channels (OPP_RG, OPP_YB) need a BGR or BGRA frame, got a "
        "1-channel (gray) frame");
  }
  x0_ = r0.x;
  y0_ = r0.y;
  width_ = r0.w;
  height_ = r0.h;
  channels_ = channels;
  const int w = width_;
  const int n_planes = static_cast<int>(channels.size());
  const std::ptrdiff_t s = stride();
  const std::ptrdiff_t ps = plane_size();
  // Every entry but row 0 is written below: no need to clear the whole buffer.
  data_.resize(static_cast<std::size_t>(ps) * static_cast<std::size_t>(n_planes));
  for (int k = 0; k < n_planes; ++k) std::fill_n(data_.data() + k * ps, s, 0.0);

  const bool gradients = need_grad || need_orient;
  const std::size_t ext = static_cast<std::size_t>(w) + 2;
  // Three luma rows (above, at, below the current row) with one extra column on each side.
  std::vector<std::uint8_t> lum(3 * ext);
  std::uint8_t* above = lum.data();
  std::uint8_t* here = above + ext;
  std::uint8_t* below = here + ext;
  std::vector<std::uint8_t> grad(gradients ? w : 0), bin(need_orient ? w : 0),
      values(static_cast<std::size_t>(w));
  const int last_row = image.rows - 1;
  if (gradients) {
    luma_row_ext(image, std::max(y0_ - 1, 0), x0_, w, above);
    luma_row_ext(image, std::min(y0_ + 1, last_row), x0_, w, below);
  }

  for (int r = 0; r < height_; ++r) {
    const int y = y0_ + r;
    if (gradients) {
      if (r > 0) {
        std::swap(above, here);  // the old current row is now above
        std::swap(here, below);  // the old lower row is now current
        luma_row_ext(image, std::min(y + 1, last_row), x0_, w, below);
      } else {
        luma_row_ext(image, y, x0_, w, here);
      }
      for (int c = 0; c < w; ++c) {
        const int gx = here[c + 2] - here[c];
        const int gy = below[c + 1] - above[c + 1];
        grad[c] = static_cast<std::uint8_t>((std::abs(gx) + std::abs(gy)) >> 1);
        if (need_orient) bin[c] = static_cast<std::uint8_t>(orientation_bin(gx, gy));
      }
    } else if (need_luma) {
      luma_row(image, y, x0_, x0_ + w, here + 1);
    }
    const std::uint8_t* px = image.data + y * image.row_stride + x0_ * image.col_stride;
    const std::ptrdiff_t cols = image.col_stride, cs = image.channel_stride;
    for (int k = 0; k < n_planes; ++k) {
      const int ch = channels[static_cast<std::size_t>(k)];
      const std::uint8_t* v = values.data();
      switch (ch) {
        case kLuma:
          v = here + 1;
          break;
        case kGrad:
          v = grad.data();
          break;
        case kOppRG: {
          const std::uint8_t* p = px;
          for (int c = 0; c < w; ++c, p += cols) {
            values[c] = static_cast<std::uint8_t>((p[2 * cs] - p[cs] + 255) >> 1);
          }
          break;
        }
        case kOppYB: {
          const std::uint8_t* p = px;
          for (int c = 0; c < w; ++c, p += cols) {
            values[c] = static_cast<std::uint8_t>((p[2 * cs] + p[cs] - 2 * p[0] + 510) >> 2);
          }
          break;
        }
        default: {  // kOrient0 .. kOrient3
          const std::uint8_t b = static_cast<std::uint8_t>(ch - kOrient0);
          for (int c = 0; c < w; ++c) values[c] = bin[c] == b ? grad[c] : 0;
          break;
        }
      }
      double* plane_k = data_.data() + k * ps;
      accumulate_row(v, w, plane_k + r * s, plane_k + (r + 1) * s);
    }
  }
}

}  // namespace wmiltrack
