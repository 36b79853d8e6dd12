#include "wmiltrack/colour.hpp"

#include "wmiltrack/vmath.hpp"

#include <algorithm>
#include <stdexcept>
#include <type_traits>
#include <vector>

#if defined(WMILTRACK_AVX2_COPIES)
#include <immintrin.h>
#endif

namespace wmiltrack {

#if defined(WMILTRACK_AVX2_COPIES)
namespace detail {
// row_bins' packed-BGR loop (below), 8 pixels a step: each pixel's three bytes spread into a
// 32-bit lane, each shifted down to `bits` and the three packed, as the scalar loop does. Reads
// 32 bytes for 8 pixels' 24, so it stops 3 pixels before n (the rest: the scalar loop). Returns
// the pixels done. Run only where vmath::avx2() says so; named so that the portable-build test
// finds it (see vmath.hpp).
__attribute__((target("avx2"))) int row_bins_bgr_avx2(const std::uint8_t* p, int n, int bits,
                                                       std::uint32_t* out) {
  // Dwords 0-2 (pixels 0-3) to the low lane and 3-5 (pixels 4-7) to the high lane, then each
  // pixel's bytes to bytes 0-2 of its own dword.
  const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 0, 3, 4, 5, 0);
  const __m256i spread = _mm256_setr_epi8(0, 1, 2, -1, 3, 4, 5, -1, 6, 7, 8, -1, 9, 10, 11, -1,
                                          0, 1, 2, -1, 3, 4, 5, -1, 6, 7, 8, -1, 9, 10, 11, -1);
  const __m256i byte = _mm256_set1_epi32(0xFF);
  const __m128i down = _mm_cvtsi32_si128(8 - bits);
  const __m128i up1 = _mm_cvtsi32_si128(bits), up2 = _mm_cvtsi32_si128(2 * bits);
  int c = 0;
  for (; c + 11 <= n; c += 8) {
    __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + 3 * c));
    v = _mm256_shuffle_epi8(_mm256_permutevar8x32_epi32(v, lanes), spread);
    const __m256i b = _mm256_srl_epi32(_mm256_and_si256(v, byte), down);
    const __m256i g = _mm256_srl_epi32(_mm256_and_si256(_mm256_srli_epi32(v, 8), byte), down);
    const __m256i r = _mm256_srl_epi32(_mm256_srli_epi32(v, 16), down);
    const __m256i bin =
        _mm256_or_si256(_mm256_or_si256(_mm256_sll_epi32(b, up2), _mm256_sll_epi32(g, up1)), r);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + c), bin);
  }
  return c;
}
}  // namespace detail
#endif

namespace {

void check(const ImageView& image, const Rect& region, int bits, bool intensity) {
  if (image.data == nullptr || (image.channels < 3 && !intensity)) {
    throw std::invalid_argument("colour model: needs a BGR or BGRA frame");
  }
  if (image.channels != 1 && image.channels < 3) {
    throw std::invalid_argument("colour model: needs a gray, BGR or BGRA frame");
  }
  if (bits < 1 || bits > 8) throw std::invalid_argument("colour model: bits must be in 1..8");
  if (region.x < 0 || region.y < 0 || region.w < 0 || region.h < 0 ||
      static_cast<std::int64_t>(region.x) + region.w > image.cols ||
      static_cast<std::int64_t>(region.y) + region.h > image.rows) {
    throw std::invalid_argument("colour model: the region must lie inside the frame");
  }
}

// The bins of n pixels of frame row y, columns x, x + step, ... (inside the frame), into out;
// with `intensity` the bin of each pixel's luma. Packed BGR and BGRA rows (the usual numpy
// layouts) take a loop with constant strides.
void row_bins(const ImageView& image, int y, int x, int n, int step, int bits, bool intensity,
              std::uint32_t* out) {
  const std::ptrdiff_t cs = image.channel_stride, col = image.col_stride;
  const std::ptrdiff_t jump = col * step;
  const std::uint8_t* p = image.data + static_cast<std::ptrdiff_t>(y) * image.row_stride +
                          static_cast<std::ptrdiff_t>(x) * col;
  const int sh = 8 - bits;
  if (intensity) {
    const auto gray_bin = [&](std::uint8_t l) {
      const std::uint32_t v = static_cast<std::uint32_t>(l >> sh);
      return (v << (2 * bits)) | (v << bits) | v;
    };
    if (image.channels == 1) {
      for (int c = 0; c < n; ++c, p += jump) out[c] = gray_bin(p[0]);
    } else {
      for (int c = 0; c < n; ++c, p += jump) out[c] = gray_bin(bgr_to_gray(p[0], p[cs], p[2 * cs]));
    }
    return;
  }
  const auto packed = [&](auto kStep) {
    for (int c = 0; c < n; ++c, p += kStep.value) {
      out[c] = (static_cast<std::uint32_t>(p[0] >> sh) << (2 * bits)) |
               (static_cast<std::uint32_t>(p[1] >> sh) << bits) |
               static_cast<std::uint32_t>(p[2] >> sh);
    }
  };
  if (cs == 1 && jump == 3) {
#if defined(WMILTRACK_AVX2_COPIES)
    if (vmath::avx2()) {
      const int done = detail::row_bins_bgr_avx2(p, n, bits, out);
      p += 3 * done;
      out += done;
      n -= done;
    }
#endif
    packed(std::integral_constant<int, 3>{});
  } else if (cs == 1 && jump == 4) {
    packed(std::integral_constant<int, 4>{});
  } else {
    for (int c = 0; c < n; ++c, p += jump) out[c] = colour_bin(p[0], p[cs], p[2 * cs], bits);
  }
}

// The pixels of a region's row or column range that a step of `step` samples: those at
// offsets first, first + step, ... below `size` (frame coordinate origin + offset a multiple of
// step); index(o) counts the samples at offsets below o.
struct Samples {
  int first, count, step;
  Samples(int origin, int size, int step_) : step(step_) {
    first = (step - origin % step) % step;
    count = size > first ? (size - first + step - 1) / step : 0;
  }
  int index(int o) const {
    if (o <= first) return 0;
    return std::min(count, (o - first + step - 1) / step);
  }
};

}  // namespace

ColourHistograms::ColourHistograms(int bits, double rate, bool intensity)
    : bits_(bits), rate_(rate), intensity_(intensity) {
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
                             const Span& core, int step) {
  const Samples cols(region.x, region.w, step), rows(region.y, region.h, step);
  std::vector<std::uint32_t> bins(static_cast<std::size_t>(cols.count));
  // The row's samples in columns [c0, c1) of the region, into counts.
  const auto run = [&](int c0, int c1, std::vector<std::uint32_t>& counts) {
    const int k1 = cols.index(c1);
    for (int k = cols.index(c0); k < k1; ++k) {
      const std::uint32_t bin = bins[static_cast<std::size_t>(k)];
      if (!is_counted_[bin]) {
        is_counted_[bin] = 1;
        counted_.push_back(bin);
      }
      ++counts[bin];
    }
  };
  for (int r = rows.first; r < region.h; r += step) {
    row_bins(image, region.y + r, region.x + cols.first, cols.count, step, bits_, intensity_,
             bins.data());
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
                             const Span& core, int step) {
  check(image, region, bits_, intensity_);
  if (step < 1) throw std::invalid_argument("colour model: step must be at least 1");
  if (static_cast<std::uint64_t>(region.w) * static_cast<std::uint64_t>(region.h) >= (std::uint64_t{1} << 32)) {
    throw std::invalid_argument("colour model: a region of 2^32 pixels or more");  // uint32 counts
  }
  count(image, region, inside, core, step);
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
  check(image, region, bits_, intensity_);
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
      row_bins(image, region.y + r + i, region.x, region.w, 1, bits_, intensity_,
               bins.data() + i * w);
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
    row_bins(image, region.y + r, region.x, region.w, 1, bits_, intensity_, bins.data());
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

ColourHistograms::Sums ColourHistograms::likelihood_sums(const ImageView& image,
                                                        const Rect& region,
                                                        const Span& inner, int step) const {
  if (!learnt_) throw std::logic_error("colour model: learn() before likelihood_sums()");
  check(image, region, bits_, intensity_);
  if (step < 1) throw std::invalid_argument("colour model: step must be at least 1");
  const double* lik = lik_.data();
  const Samples cols(region.x, region.w, step), rows(region.y, region.h, step);
  const int c0 = cols.index(std::max(inner.c0, 0)), c1 = cols.index(std::min(inner.c1, region.w));
  std::vector<std::uint32_t> bins(static_cast<std::size_t>(cols.count));
  Sums out;
  double outside = 0.0;
  const auto sum = [&](int a, int b) {  // four running sums, for the pipeline
    double s[4] = {0.0, 0.0, 0.0, 0.0};
    int c = a;
    for (; c + 4 <= b; c += 4) {
      for (int i = 0; i < 4; ++i) s[i] += lik[bins[static_cast<std::size_t>(c + i)]];
    }
    for (; c < b; ++c) s[0] += lik[bins[static_cast<std::size_t>(c)]];
    return (s[0] + s[1]) + (s[2] + s[3]);
  };
  for (int r = rows.first; r < region.h; r += step) {
    row_bins(image, region.y + r, region.x + cols.first, cols.count, step, bits_, intensity_,
             bins.data());
    out.region_pixels += cols.count;
    if (r >= inner.r0 && r < inner.r1 && c0 < c1) {
      outside += sum(0, c0) + sum(c1, cols.count);
      out.inner += sum(c0, c1);
      out.inner_pixels += c1 - c0;
    } else {
      outside += sum(0, cols.count);
    }
  }
  out.region = out.inner + outside;
  return out;
}

}  // namespace wmiltrack
