#include "wmiltrack/colour.hpp"

#include <algorithm>
#include <stdexcept>
#include <type_traits>
#include <vector>

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

// The bins of n pixels of frame row y from column x (inside the frame), into out. Packed
// BGR and BGRA rows (the usual numpy layouts) take a loop with constant strides.
void row_bins(const ImageView& image, int y, int x, int n, int bits, std::uint32_t* out) {
  const std::ptrdiff_t cs = image.channel_stride, step = image.col_stride;
  const std::uint8_t* p = image.data + static_cast<std::ptrdiff_t>(y) * image.row_stride +
                          static_cast<std::ptrdiff_t>(x) * step;
  const int sh = 8 - bits;
  const auto packed = [&](auto kStep) {
    for (int c = 0; c < n; ++c, p += kStep.value) {
      out[c] = (static_cast<std::uint32_t>(p[0] >> sh) << (2 * bits)) |
               (static_cast<std::uint32_t>(p[1] >> sh) << bits) |
               static_cast<std::uint32_t>(p[2] >> sh);
    }
  };
  if (cs == 1 && step == 3) {
    packed(std::integral_constant<int, 3>{});
  } else if (cs == 1 && step == 4) {
    packed(std::integral_constant<int, 4>{});
  } else {
    for (int c = 0; c < n; ++c, p += step) out[c] = colour_bin(p[0], p[cs], p[2 * cs], bits);
  }
}

}  // namespace

ColourHistograms::ColourHistograms(int bits, double rate) : bits_(bits), rate_(rate) {
  if (bits < 1 || bits > 8) throw std::invalid_argument("colour model: bits must be in 1..8");
  if (!(rate > 0.0 && rate <= 1.0)) {
    throw std::invalid_argument("colour model: rate must be in (0, 1]");
  }
  const std::size_t n = std::size_t{1} << (3 * bits);
  fg_.assign(n, 0.0);
  bg_.assign(n, 0.0);
  lik_.assign(n, 0.5);
  fg_count_.assign(n, 0);
  bg_count_.assign(n, 0);
  is_counted_.assign(n, 0);
  is_seen_.assign(n, 0);
}

void ColourHistograms::count(const ImageView& image, const Rect& region, const Span& inside,
                             const Span& core) {
  std::vector<std::uint32_t> bins(static_cast<std::size_t>(region.w));
  // Columns [c0, c1) of the row's bins, clipped to the region, into counts.
  const auto run = [&](int c0, int c1, std::vector<std::uint32_t>& counts) {
    c0 = std::max(c0, 0);
    c1 = std::min(c1, region.w);
    for (int c = c0; c < c1; ++c) {
      const std::uint32_t bin = bins[static_cast<std::size_t>(c)];
      if (!is_counted_[bin]) {
        is_counted_[bin] = 1;
        counted_.push_back(bin);
      }
      ++counts[bin];
    }
  };
  for (int r = 0; r < region.h; ++r) {
    row_bins(image, region.y + r, region.x, region.w, bits_, bins.data());
    if (r >= core.r0 && r < core.r1) run(core.c0, core.c1, fg_count_);
    if (r >= inside.r0 && r < inside.r1 && inside.c0 < inside.c1) {
      run(0, inside.c0, bg_count_);  // left and right of the inside span
      run(inside.c1, region.w, bg_count_);
    } else {
      run(0, region.w, bg_count_);
    }
  }
}

void ColourHistograms::blend(std::uint32_t i, double fd, double bd, bool first) {
  const double keep = 1.0 - rate_;
  const double f = static_cast<double>(fg_count_[i]) / fd;
  const double b = static_cast<double>(bg_count_[i]) / bd;
  fg_[i] = first ? f : keep * fg_[i] + rate_ * f;
  bg_[i] = first ? b : keep * bg_[i] + rate_ * b;
  const double total = fg_[i] + bg_[i];
  lik_[i] = total > 0 ? fg_[i] / total : 0.5;
}

void ColourHistograms::learn(const ImageView& image, const Rect& region, const Span& inside,
                             const Span& core) {
  check(image, region, bits_);
  if (static_cast<std::uint64_t>(region.w) * static_cast<std::uint64_t>(region.h) >= (std::uint64_t{1} << 32)) {
    throw std::invalid_argument("colour model: a region of 2^32 pixels or more");  // uint32 counts
  }
  count(image, region, inside, core);
  // Sums of whole counts (< 2^53): exact in any order.
  double fg_sum = 0.0, bg_sum = 0.0;
  for (const std::uint32_t bin : counted_) {
    fg_sum += static_cast<double>(fg_count_[bin]);
    bg_sum += static_cast<double>(bg_count_[bin]);
  }
  const double fd = std::max(fg_sum, 1.0), bd = std::max(bg_sum, 1.0);
  for (const std::uint32_t bin : counted_) {
    if (!is_seen_[bin]) {
      is_seen_[bin] = 1;
      seen_.push_back(bin);
    }
  }
  const bool first = !learnt_;
  for (const std::uint32_t bin : seen_) blend(bin, fd, bd, first);
  for (const std::uint32_t bin : counted_) {
    fg_count_[bin] = bg_count_[bin] = 0;
    is_counted_[bin] = 0;
  }
  counted_.clear();
  learnt_ = true;
}

void ColourHistograms::likelihood_integral(const ImageView& image, const Rect& region,
                                           double* table) const {
  if (!learnt_) throw std::logic_error("colour model: learn() before likelihood_integral()");
  check(image, region, bits_);
  const std::ptrdiff_t stride = static_cast<std::ptrdiff_t>(region.w) + 1;
  std::fill(table, table + stride, 0.0);
  const double* lik = lik_.data();
  // First each row's running sums (rows in groups of four, whose independent sums overlap in
  // the pipeline), then each row plus the row above: table[r + 1][c + 1] = table[r][c + 1] +
  // s, the same additions as one pass would make.
  const std::size_t w = static_cast<std::size_t>(region.w);
  std::vector<std::uint32_t> bins(4 * w);
  int r = 0;
  for (; r + 4 <= region.h; r += 4) {
    double* row[4];
    double s[4] = {0.0, 0.0, 0.0, 0.0};
    for (int i = 0; i < 4; ++i) {
      row_bins(image, region.y + r + i, region.x, region.w, bits_, bins.data() + i * w);
      row[i] = table + (r + i + 1) * stride;
      row[i][0] = 0.0;
    }
    for (std::size_t c = 0; c < w; ++c) {
      for (int i = 0; i < 4; ++i) {
        s[i] += lik[bins[i * w + c]];
        row[i][c + 1] = s[i];
      }
    }
  }
  for (; r < region.h; ++r) {
    row_bins(image, region.y + r, region.x, region.w, bits_, bins.data());
    double* row = table + (r + 1) * stride;
    row[0] = 0.0;
    double s = 0.0;
    for (std::size_t c = 0; c < w; ++c) {
      s += lik[bins[c]];
      row[c + 1] = s;
    }
  }
  for (r = 1; r < region.h; ++r) {
    const double* above = table + r * stride;
    double* row = table + (r + 1) * stride;
    for (std::ptrdiff_t c = 1; c < stride; ++c) row[c] = above[c] + row[c];
  }
}

std::pair<double, double> ColourHistograms::likelihood_sums(const ImageView& image,
                                                           const Rect& region,
                                                           const Span& inner) const {
  if (!learnt_) throw std::logic_error("colour model: learn() before likelihood_sums()");
  check(image, region, bits_);
  const double* lik = lik_.data();
  const int c0 = std::max(inner.c0, 0), c1 = std::min(inner.c1, region.w);
  std::vector<std::uint32_t> bins(static_cast<std::size_t>(region.w));
  double inside = 0.0, outside = 0.0;
  const auto sum = [&](int a, int b) {  // four running sums, for the pipeline
    double s[4] = {0.0, 0.0, 0.0, 0.0};
    int c = a;
    for (; c + 4 <= b; c += 4) {
      for (int i = 0; i < 4; ++i) s[i] += lik[bins[static_cast<std::size_t>(c + i)]];
    }
    for (; c < b; ++c) s[0] += lik[bins[static_cast<std::size_t>(c)]];
    return (s[0] + s[1]) + (s[2] + s[3]);
  };
  for (int r = 0; r < region.h; ++r) {
    row_bins(image, region.y + r, region.x, region.w, bits_, bins.data());
    if (r >= inner.r0 && r < inner.r1 && c0 < c1) {
      outside += sum(0, c0) + sum(c1, region.w);
      inside += sum(c0, c1);
    } else {
      outside += sum(0, region.w);
    }
  }
  return {inside, inside + outside};
}

}  // namespace wmiltrack
