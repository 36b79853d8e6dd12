#include "wmiltrack/colour.hpp"

#include <algorithm>
#include <stdexcept>

namespace wmiltrack {

namespace {

void check(const ImageView& image, const Rect& region, int bits) {
  if (image.data == nullptr || image.channels < 3) {
    throw std::invalid_argument("colour model: needs a BGR or BGRA frame");
  }
  if (bits < 1 || bits > 8) throw std::invalid_argument("colour model: bits must be in 1..8");
  if (region.x < 0 || region.y < 0 || region.w < 0 || region.h < 0 ||
      static_cast<std::int64_t>(region.x) + region.w > image.cols ||
      static_cast<std::int64_t>(region.y) + region.h > image.rows) {
    throw std::invalid_argument("colour model: the region must lie inside the frame");
  }
}

template <class F>
void for_region(const ImageView& image, const Rect& region, int bits, F&& f) {
  const std::ptrdiff_t cs = image.channel_stride;
  for (int r = 0; r < region.h; ++r) {
    const std::uint8_t* p = image.data + static_cast<std::ptrdiff_t>(region.y + r) * image.row_stride +
                            static_cast<std::ptrdiff_t>(region.x) * image.col_stride;
    for (int c = 0; c < region.w; ++c, p += image.col_stride) {
      f(r, c, colour_bin(p[0], p[cs], p[2 * cs], bits));
    }
  }
}

}  // namespace

void colour_map(const ImageView& image, const Rect& region, int bits, const double* likelihood,
                double* out) {
  check(image, region, bits);
  const std::ptrdiff_t w = region.w;
  for_region(image, region, bits,
             [&](int r, int c, std::uint32_t bin) { out[r * w + c] = likelihood[bin]; });
}

void colour_counts(const ImageView& image, const Rect& region, const Span& inside,
                   const Span& core, int bits, double* fg, double* bg) {
  check(image, region, bits);
  for_region(image, region, bits, [&](int r, int c, std::uint32_t bin) {
    if (core.holds(r, c)) fg[bin] += 1.0;
    if (!inside.holds(r, c)) bg[bin] += 1.0;
  });
}

void colour_update(double* fg_model, double* bg_model, double* fg_counts, double* bg_counts,
                   int n, double rate, bool first, double* likelihood) {
  // Sums of whole counts (< 2^53): exact in any order.
  double fg_sum = 0.0, bg_sum = 0.0;
  for (int i = 0; i < n; ++i) {
    fg_sum += fg_counts[i];
    bg_sum += bg_counts[i];
  }
  const double fd = std::max(fg_sum, 1.0), bd = std::max(bg_sum, 1.0);
  const double keep = 1.0 - rate;
  for (int i = 0; i < n; ++i) {
    const double f = fg_counts[i] / fd, b = bg_counts[i] / bd;
    fg_counts[i] = f;
    bg_counts[i] = b;
    fg_model[i] = first ? f : keep * fg_model[i] + rate * f;
    bg_model[i] = first ? b : keep * bg_model[i] + rate * b;
    const double total = fg_model[i] + bg_model[i];
    likelihood[i] = total > 0 ? fg_model[i] / total : 0.5;
  }
}

}  // namespace wmiltrack
