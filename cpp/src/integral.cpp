#include "wmiltrack/integral.hpp"

#include "wmiltrack/vmath.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

// SSE2 (every x86-64) for the running row sums; WMILTRACK_NO_SIMD forces the scalar loops.
#if (defined(__SSE2__) || defined(_M_X64)) && !defined(WMILTRACK_NO_SIMD)
#define WMILTRACK_SSE2_SCAN 1
#include <emmintrin.h>
#endif
// SSSE3 for the BGR -> luma conversion, chosen at run time (the build stays portable: the
// function is compiled for SSSE3 alone and called only on a CPU that has it). GCC/Clang only.
#if defined(WMILTRACK_SSE2_SCAN) && (defined(__GNUC__) || defined(__clang__)) && \
    (defined(__x86_64__) || defined(__i386__))
#define WMILTRACK_SSSE3_LUMA 1
#include <immintrin.h>
#endif

namespace wmiltrack {

namespace {

// Asks for the cache line holding p to be brought into L2 (a hint: never faults). An asm
// statement on x86-64, because GCC 12 deleted a loop of plain __builtin_prefetch calls in
// build_channels as dead code: the module had no prefetch instruction left.
inline void prefetch_l2(const void* p) {
#if (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__)
  asm volatile("prefetcht1 %0" : : "m"(*static_cast<const char*>(p)));
#elif defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(p, 0, 2);
#else
  (void)p;
#endif
}

}  // namespace

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
  // 64-bit far edges, compared before any narrowing: roi.x + roi.w neither overflows nor,
  // when far below zero, wraps around to a large int.
  const std::int64_t x_end =
      std::min<std::int64_t>(static_cast<std::int64_t>(roi.x) + roi.w, image.cols);
  const std::int64_t y_end =
      std::min<std::int64_t>(static_cast<std::int64_t>(roi.y) + roi.h, image.rows);
  if (x_end <= x_begin || y_end <= y_begin) {
    throw std::invalid_argument("integral image: the region does not meet the frame");
  }
  return Rect{x_begin, y_begin, static_cast<int>(x_end - x_begin), static_cast<int>(y_end - y_begin)};
}

// Per-pixel loops over a row of `n` pixels starting at `src`, with the column stride fixed
// at compile time for the common contiguous layouts (gray 1, BGR 3, BGRA 4; channel stride
// 1) so that the compiler can vectorise them, and a run-time stride otherwise (kCols = 0).
template <int kCols, class F>
void for_pixels(const ImageView& image, const std::uint8_t* src, int n, F&& f) {
  const std::ptrdiff_t cols = kCols > 0 ? kCols : image.col_stride;
  const std::ptrdiff_t cs = kCols > 0 ? 1 : image.channel_stride;
  for (int c = 0; c < n; ++c) f(c, src + c * cols, cs);
}

template <class F>
void dispatch_pixels(const ImageView& image, const std::uint8_t* src, int n, F&& f) {
  if (image.channel_stride == 1 || image.channels == 1) {
    switch (image.col_stride) {
      case 1:
        if (image.channels == 1) return for_pixels<1>(image, src, n, f);
        break;
      case 3:
        if (image.channels == 3) return for_pixels<3>(image, src, n, f);
        break;
      case 4:
        if (image.channels == 4) return for_pixels<4>(image, src, n, f);
        break;
      default:
        break;
    }
  }
  for_pixels<0>(image, src, n, f);
}

#ifdef WMILTRACK_SSSE3_LUMA
// Byte k of a 48-byte block of 16 BGR pixels is pixel k / 3, channel k % 3. For each channel
// (b, g, r), three pshufb masks pick its bytes from the block's three 16-byte loads (-1: none
// from this load).
alignas(16) constexpr std::int8_t kBgrMasks[9][16] = {
    {0, 3, 6, 9, 12, 15, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1},
    {-1, -1, -1, -1, -1, -1, 2, 5, 8, 11, 14, -1, -1, -1, -1, -1},
    {-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, 1, 4, 7, 10, 13},
    {1, 4, 7, 10, 13, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1},
    {-1, -1, -1, -1, -1, 0, 3, 6, 9, 12, 15, -1, -1, -1, -1, -1},
    {-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, 2, 5, 8, 11, 14},
    {2, 5, 8, 11, 14, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1},
    {-1, -1, -1, -1, -1, 1, 4, 7, 10, 13, -1, -1, -1, -1, -1, -1},
    {-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, 0, 3, 6, 9, 12, 15},
};

// bgr_to_gray() of n packed BGR pixels, 16 at a time: the same integer formula (exact, so the
// same bytes as the scalar loop), with the channels gathered by byte shuffles and the
// weighted sums made by pmaddwd on (b, g) and (r, 1) pairs. Returns the pixels done.
__attribute__((target("ssse3"))) int luma_bgr_ssse3(const std::uint8_t* src, int n,
                                                    std::uint8_t* out) {
  const auto mask = [](int k) {
    return _mm_load_si128(reinterpret_cast<const __m128i*>(kBgrMasks[k]));
  };
  const __m128i b0 = mask(0), b1 = mask(1), b2 = mask(2);
  const __m128i g0 = mask(3), g1 = mask(4), g2 = mask(5);
  const __m128i r0 = mask(6), r1 = mask(7), r2 = mask(8);
  const __m128i zero = _mm_setzero_si128();
  const __m128i w_bg = _mm_set1_epi32(3735 | (19235 << 16));  // (kB, kG) pairs
  const __m128i w_r1 = _mm_set1_epi32(9798 | (16384 << 16));  // (kR, rounding) pairs
  const __m128i one = _mm_set1_epi16(1);
  int c = 0;
  for (; c + 16 <= n; c += 16) {
    const std::uint8_t* p = src + 3 * c;
    const __m128i v0 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
    const __m128i v1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16));
    const __m128i v2 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 32));
    const __m128i b = _mm_or_si128(_mm_or_si128(_mm_shuffle_epi8(v0, b0), _mm_shuffle_epi8(v1, b1)),
                                   _mm_shuffle_epi8(v2, b2));
    const __m128i g = _mm_or_si128(_mm_or_si128(_mm_shuffle_epi8(v0, g0), _mm_shuffle_epi8(v1, g1)),
                                   _mm_shuffle_epi8(v2, g2));
    const __m128i r = _mm_or_si128(_mm_or_si128(_mm_shuffle_epi8(v0, r0), _mm_shuffle_epi8(v1, r1)),
                                   _mm_shuffle_epi8(v2, r2));
    __m128i half[2];
    for (int h = 0; h < 2; ++h) {
      const __m128i b16 = h == 0 ? _mm_unpacklo_epi8(b, zero) : _mm_unpackhi_epi8(b, zero);
      const __m128i g16 = h == 0 ? _mm_unpacklo_epi8(g, zero) : _mm_unpackhi_epi8(g, zero);
      const __m128i r16 = h == 0 ? _mm_unpacklo_epi8(r, zero) : _mm_unpackhi_epi8(r, zero);
      // 32-bit b*kB + g*kG + r*kR + 2^14 for 4 + 4 pixels, then >> 15 (all positive).
      const __m128i lo = _mm_add_epi32(_mm_madd_epi16(_mm_unpacklo_epi16(b16, g16), w_bg),
                                       _mm_madd_epi16(_mm_unpacklo_epi16(r16, one), w_r1));
      const __m128i hi = _mm_add_epi32(_mm_madd_epi16(_mm_unpackhi_epi16(b16, g16), w_bg),
                                       _mm_madd_epi16(_mm_unpackhi_epi16(r16, one), w_r1));
      half[h] = _mm_packs_epi32(_mm_srai_epi32(lo, 15), _mm_srai_epi32(hi, 15));
    }
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + c), _mm_packus_epi16(half[0], half[1]));
  }
  return c;
}

// Helpers of luma_bgr_avx2, always inlined into it (so that its AVX2 code stays in the one
// named function).
#define WMILTRACK_AVX2_INLINE inline __attribute__((target("avx2"), always_inline))
// Mask k of kBgrMasks in both lanes.
WMILTRACK_AVX2_INLINE __m256i avx2_mask(int k) {
  return _mm256_broadcastsi128_si256(_mm_load_si128(reinterpret_cast<const __m128i*>(kBgrMasks[k])));
}
// The 16-byte load k of pixels c .. c+15 (at p) in the low lane, of pixels c+16 .. c+31 in the
// high lane.
WMILTRACK_AVX2_INLINE __m256i avx2_load(const std::uint8_t* p, int k) {
  const __m128i lo = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16 * k));
  const __m128i hi = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 48 + 16 * k));
  return _mm256_inserti128_si256(_mm256_castsi128_si256(lo), hi, 1);
}
// One channel's bytes from the three loads.
WMILTRACK_AVX2_INLINE __m256i avx2_channel(__m256i v0, __m256i v1, __m256i v2, __m256i m0,
                                           __m256i m1, __m256i m2) {
  return _mm256_or_si256(_mm256_or_si256(_mm256_shuffle_epi8(v0, m0), _mm256_shuffle_epi8(v1, m1)),
                         _mm256_shuffle_epi8(v2, m2));
}
#undef WMILTRACK_AVX2_INLINE

}  // namespace

namespace detail {
// luma_bgr_ssse3 for 32 pixels a step: two 16-pixel blocks, one in each 128-bit lane, through
// the same in-lane shuffles and integer arithmetic (so the same bytes). Run only where
// vmath::avx2() says so; named so that the portable-build test finds it (see vmath.hpp).
__attribute__((target("avx2"))) int luma_bgr_avx2(const std::uint8_t* src, int n,
                                                   std::uint8_t* out) {
  const __m256i b0 = avx2_mask(0), b1 = avx2_mask(1), b2 = avx2_mask(2);
  const __m256i g0 = avx2_mask(3), g1 = avx2_mask(4), g2 = avx2_mask(5);
  const __m256i r0 = avx2_mask(6), r1 = avx2_mask(7), r2 = avx2_mask(8);
  const __m256i zero = _mm256_setzero_si256();
  const __m256i w_bg = _mm256_set1_epi32(3735 | (19235 << 16));  // (kB, kG) pairs
  const __m256i w_r1 = _mm256_set1_epi32(9798 | (16384 << 16));  // (kR, rounding) pairs
  const __m256i one = _mm256_set1_epi16(1);
  int c = 0;
  for (; c + 32 <= n; c += 32) {
    const std::uint8_t* p = src + 3 * c;
    const __m256i v0 = avx2_load(p, 0), v1 = avx2_load(p, 1), v2 = avx2_load(p, 2);
    const __m256i b = avx2_channel(v0, v1, v2, b0, b1, b2);
    const __m256i g = avx2_channel(v0, v1, v2, g0, g1, g2);
    const __m256i r = avx2_channel(v0, v1, v2, r0, r1, r2);
    __m256i half[2];
    for (int h = 0; h < 2; ++h) {
      const __m256i b16 = h == 0 ? _mm256_unpacklo_epi8(b, zero) : _mm256_unpackhi_epi8(b, zero);
      const __m256i g16 = h == 0 ? _mm256_unpacklo_epi8(g, zero) : _mm256_unpackhi_epi8(g, zero);
      const __m256i r16 = h == 0 ? _mm256_unpacklo_epi8(r, zero) : _mm256_unpackhi_epi8(r, zero);
      const __m256i lo = _mm256_add_epi32(_mm256_madd_epi16(_mm256_unpacklo_epi16(b16, g16), w_bg),
                                          _mm256_madd_epi16(_mm256_unpacklo_epi16(r16, one), w_r1));
      const __m256i hi = _mm256_add_epi32(_mm256_madd_epi16(_mm256_unpackhi_epi16(b16, g16), w_bg),
                                          _mm256_madd_epi16(_mm256_unpackhi_epi16(r16, one), w_r1));
      half[h] = _mm256_packs_epi32(_mm256_srai_epi32(lo, 15), _mm256_srai_epi32(hi, 15));
    }
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + c), _mm256_packus_epi16(half[0], half[1]));
  }
  return c;
}

// accumulate_row's running sums (below), 32 pixels a step in 8-lane blocks: each block's
// in-register prefix scan (within each 128-bit half, then the low half's total added to the
// high half) plus the running sum, which grows by each block's total in a chain of one
// addition a block. Returns the pixels done (a multiple of 32) and the running sum in
// *row_sum. Integer sums modulo 2^32: the same entries as the other paths.
__attribute__((target("avx2"))) int accumulate_row_avx2(const std::uint8_t* v, int w,
                                                         const std::uint32_t* prev,
                                                         std::uint32_t* out,
                                                         std::uint32_t* row_sum) {
  const __m256i last = _mm256_set1_epi32(7);
  __m256i carry = _mm256_setzero_si256();
  int c = 0;
  for (; c + 32 <= w; c += 32) {
    for (int j = 0; j < 4; ++j) {
      const int at = c + 8 * j;
      __m256i x = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(v + at)));
      x = _mm256_add_epi32(x, _mm256_slli_si256(x, 4));
      x = _mm256_add_epi32(x, _mm256_slli_si256(x, 8));
      const __m256i low_total = _mm256_shuffle_epi32(x, 0xFF);
      x = _mm256_add_epi32(x, _mm256_permute2x128_si256(low_total, low_total, 0x08));
      const __m256i total = _mm256_permutevar8x32_epi32(x, last);
      x = _mm256_add_epi32(x, carry);
      carry = _mm256_add_epi32(carry, total);
      const __m256i above = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(prev + at + 1));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + at + 1), _mm256_add_epi32(above, x));
    }
  }
  *row_sum = static_cast<std::uint32_t>(_mm256_cvtsi256_si32(carry));
  return c;
}
}  // namespace detail

namespace {

// Whether the CPU runs luma_bgr_ssse3 (asked once).
bool have_ssse3() {
  static const bool yes = __builtin_cpu_supports("ssse3");
  return yes;
}
#endif

}  // namespace

void luma_row(const ImageView& image, int y, int xa, int xb, std::uint8_t* out) {
  const std::uint8_t* src = image.data + y * image.row_stride + xa * image.col_stride;
#ifdef WMILTRACK_SSSE3_LUMA
  // Every k-th pixel of a packed BGR row (a lattice view of it, 2 <= k <= 8): the whole span
  // through the vector loop below, every k-th value kept. That is about ten times faster a
  // pixel than the strided loop, so cheaper up to k = 8; the same bytes.
  const std::ptrdiff_t k = image.col_stride / 3;
  if (image.channels == 3 && image.channel_stride == 1 && image.col_stride % 3 == 0 && k >= 2 &&
      k <= 8 && xb - xa > 1) {
    thread_local std::vector<std::uint8_t> span;
    const int width = static_cast<int>((xb - xa - 1) * k + 1);
    span.resize(static_cast<std::size_t>(width));
    const std::uint8_t* const full = span.data();  // (read once: a thread_local costs a call)
    ImageView packed = image;  // the frame's own columns
    packed.col_stride = 3;
    packed.cols = static_cast<int>(xa * k) + width;
    luma_row(packed, y, static_cast<int>(xa * k), static_cast<int>(xa * k) + width, span.data());
    for (int c = 0; c < xb - xa; ++c) out[c] = full[static_cast<std::ptrdiff_t>(c) * k];
    return;
  }
  // Packed BGR: 32 pixels a step with AVX2, then 16 with SSSE3, then the loops below.
  if (image.channels == 3 && image.col_stride == 3 && image.channel_stride == 1) {
    const auto advance = [&](int done) {
      src += 3 * done;
      out += done;
      xa += done;
    };
    if (vmath::avx2()) advance(detail::luma_bgr_avx2(src, xb - xa, out));
    if (have_ssse3()) advance(luma_bgr_ssse3(src, xb - xa, out));
  }
#endif
  if (image.channels == 1) {
    dispatch_pixels(image, src, xb - xa,
                    [out](int c, const std::uint8_t* p, std::ptrdiff_t) { out[c] = p[0]; });
  } else {
    dispatch_pixels(image, src, xb - xa, [out](int c, const std::uint8_t* p, std::ptrdiff_t cs) {
      out[c] = bgr_to_gray(p[0], p[cs], p[2 * cs]);
    });
  }
}

namespace {

// Luma of frame row y over the ROI's columns plus one on each side: ext[j] is the luma at
// column x0 - 1 + j (j = 0 .. w + 1), the frame's edge column replicated outside the frame.
void luma_row_ext(const ImageView& image, int y, int x0, int w, std::uint8_t* ext) {
  const int xa = std::max(x0 - 1, 0);
  const int xb = std::min(x0 + w + 1, image.cols);
  luma_row(image, y, xa, xb, ext + (xa - (x0 - 1)));
  if (xa == x0) ext[0] = ext[1];
  if (xb == x0 + w) ext[w + 1] = ext[w];
}

// One table row from one row of channel values: out[c + 1] = prev[c + 1] + sum(v[0..c]),
// modulo 2^32 (IntegralImage::Entry). Unsigned arithmetic wraps, so any width is fine: every
// entry is the true sum modulo 2^32, which is all a rectangle's sum needs. With SSE2 the row
// sums are an in-register prefix scan of 4 lanes (16 pixels per step), added to the row
// above in the same registers; otherwise a plain loop.
void accumulate_row(const std::uint8_t* v, int w, const std::uint32_t* prev, std::uint32_t* out) {
  out[0] = 0;
  int c = 0;
  std::uint32_t row_sum = 0;
#ifdef WMILTRACK_SSSE3_LUMA
  if (vmath::avx2()) c = detail::accumulate_row_avx2(v, w, prev, out, &row_sum);
#endif
#ifdef WMILTRACK_SSE2_SCAN
  const __m128i zero = _mm_setzero_si128();
  // the running sum, in every lane
  __m128i carry = _mm_set1_epi32(static_cast<int>(row_sum));
  for (; c + 16 <= w; c += 16) {
    const __m128i bytes = _mm_loadu_si128(reinterpret_cast<const __m128i*>(v + c));
    const __m128i lo = _mm_unpacklo_epi8(bytes, zero), hi = _mm_unpackhi_epi8(bytes, zero);
    const __m128i quads[4] = {_mm_unpacklo_epi16(lo, zero), _mm_unpackhi_epi16(lo, zero),
                              _mm_unpacklo_epi16(hi, zero), _mm_unpackhi_epi16(hi, zero)};
    for (int j = 0; j < 4; ++j) {
      __m128i x = quads[j];
      x = _mm_add_epi32(x, _mm_slli_si128(x, 4));
      x = _mm_add_epi32(x, _mm_slli_si128(x, 8));
      // The block's own total, broadcast, is added to the carry apart from x: the chain from
      // block to block is one addition.
      const __m128i total = _mm_shuffle_epi32(x, 0xFF);
      x = _mm_add_epi32(x, carry);
      carry = _mm_add_epi32(carry, total);
      const __m128i above = _mm_loadu_si128(reinterpret_cast<const __m128i*>(prev + c + 4 * j + 1));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(out + c + 4 * j + 1), _mm_add_epi32(above, x));
    }
  }
  row_sum = static_cast<std::uint32_t>(_mm_cvtsi128_si32(carry));
#endif
  for (; c < w; ++c) {
    row_sum += v[c];
    out[c + 1] = prev[c + 1] + row_sum;
  }
}

}  // namespace


// compute() and compute_channels() build a new table in a fresh object and swap it in only
// when complete: an exception (a bad argument, std::bad_alloc) leaves *this as it was.
void IntegralImage::compute(const ImageView& image, Rect roi) {
  // The luma table alone, through the vectorised row code of build_channels: the same exact
  // integer sums as a plain running-sum loop, so the same entries.
  IntegralImage next;
  next.build_channels(image, roi, {kLuma});
  swap(next);
}

void IntegralImage::compute_channels(const ImageView& image, Rect roi,
                                     const std::vector<int>& channels) {
  IntegralImage next;
  next.build_channels(image, roi, channels);
  swap(next);
}

void IntegralImage::copy_plane(int k, double* out) const {
  // Each pixel is the modular difference of four neighbouring entries (exact: 0..255); the
  // true sums are rebuilt from the pixels.
  const Entry* t = plane(k);
  const std::ptrdiff_t s = stride();
  std::fill_n(out, s, 0.0);
  for (int y = 1; y <= height_; ++y) {
    const Entry* up = t + (y - 1) * s;
    const Entry* row = t + y * s;
    double* o = out + y * s;
    const double* o_up = o - s;
    o[0] = 0.0;
    double row_sum = 0.0;
    for (int x = 1; x <= width_; ++x) {
      row_sum += static_cast<double>((row[x] - row[x - 1]) - (up[x] - up[x - 1]));
      o[x] = o_up[x] + row_sum;
    }
  }
}

void IntegralImage::rebuild(const ImageView& image, Rect roi, const std::vector<int>& channels) {
  try {
    build_channels(image, roi, channels);
  } catch (...) {
    data_.clear();  // not computed (the capacity stays for the next rebuild)
    throw;
  }
}

void IntegralImage::swap(IntegralImage& other) noexcept {
  std::swap(x0_, other.x0_);
  std::swap(y0_, other.y0_);
  std::swap(width_, other.width_);
  std::swap(height_, other.height_);
  channels_.swap(other.channels_);
  data_.swap(other.data_);
}

void IntegralImage::build_channels(const ImageView& image, Rect roi,
                                   const std::vector<int>& channels) {
  if (channels.empty()) throw std::invalid_argument("integral image: no channels requested");
  bool need_luma = false, need_grad = false, need_colour = false;
  for (int ch : channels) {
    if (ch < 0 || ch >= kNumChannelKinds) {
      throw std::invalid_argument("integral image: unknown channel id " + std::to_string(ch) +
                                  " (valid: 0 .. " + std::to_string(kNumChannelKinds - 1) + ")");
    }
    need_luma = need_luma || ch == kLuma;
    need_grad = need_grad || ch == kGrad;
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
  for (int k = 0; k < n_planes; ++k) std::fill_n(data_.data() + k * ps, s, Entry{0});

  const std::size_t ext = static_cast<std::size_t>(w) + 2;
  const std::size_t wz = static_cast<std::size_t>(w);
  // Three luma rows (above, at, below the current row) with one extra column on each side.
  std::vector<std::uint8_t> lum(3 * ext);
  std::uint8_t* above = lum.data();
  std::uint8_t* here = above + ext;
  std::uint8_t* below = here + ext;
  // Rows of channel values: gradient, 2 opponent colours.
  std::vector<std::uint8_t> rows(3 * wz);
  std::uint8_t* grad = rows.data();
  std::uint8_t* opp_rg = grad + wz;
  std::uint8_t* opp_yb = grad + 2 * wz;
  const int last_row = image.rows - 1;
  if (need_grad) {
    luma_row_ext(image, std::max(y0_ - 1, 0), x0_, w, above);
    luma_row_ext(image, std::min(y0_ + 1, last_row), x0_, w, below);
  }
  bool want_rg = false, want_yb = false;
  for (int ch : channels) {
    want_rg = want_rg || ch == kOppRG;
    want_yb = want_yb || ch == kOppYB;
  }

  // The ROI's bytes of the frame row kAhead rows below the current one are asked for ahead of
  // use, into L2: a new video frame is not in cache, and the hardware prefetcher starts afresh
  // on every row, so without this the scan waits on memory at the start of each row (a 240 x 240
  // region of a cold 640 x 480 frame: 71 us without, 30 us with, 28 us when already in cache).
  constexpr int kAhead = 6;
  const std::ptrdiff_t row_bytes = static_cast<std::ptrdiff_t>(w + 2) * image.col_stride;
  const auto prefetch_row = [&](int y) {
    if (y > last_row) return;
    const std::uint8_t* p = image.data + y * image.row_stride +
                            std::max(x0_ - 1, 0) * image.col_stride;
    for (std::ptrdiff_t b = 0; b < row_bytes; b += 64) prefetch_l2(p + b);
  };
  for (int r = 0; r < kAhead; ++r) prefetch_row(y0_ + 1 + r);

  for (int r = 0; r < height_; ++r) {
    const int y = y0_ + r;
    prefetch_row(y + 1 + kAhead);
    if (need_grad) {
      if (r > 0) {
        std::swap(above, here);  // the old current row is now above
        std::swap(here, below);  // the old lower row is now current
        luma_row_ext(image, std::min(y + 1, last_row), x0_, w, below);
      } else {
        luma_row_ext(image, y, x0_, w, here);
      }
      const std::uint8_t* __restrict l_up = above + 1;
      const std::uint8_t* __restrict l_mid = here;
      const std::uint8_t* __restrict l_down = below + 1;
      std::uint8_t* __restrict g_out = grad;
      for (int c = 0; c < w; ++c) {
        const int gx = l_mid[c + 2] - l_mid[c];
        const int gy = l_down[c] - l_up[c];
        g_out[c] = static_cast<std::uint8_t>((std::abs(gx) + std::abs(gy)) >> 1);
      }
    } else if (need_luma) {
      luma_row(image, y, x0_, x0_ + w, here + 1);
    }
    if (want_rg || want_yb) {
      const std::uint8_t* px = image.data + y * image.row_stride + x0_ * image.col_stride;
      if (want_rg && want_yb) {
        dispatch_pixels(image, px, w, [=](int c, const std::uint8_t* p, std::ptrdiff_t cs) {
          const int b = p[0], g = p[cs], rr = p[2 * cs];
          opp_rg[c] = static_cast<std::uint8_t>((rr - g + 255) >> 1);
          opp_yb[c] = static_cast<std::uint8_t>((rr + g - 2 * b + 510) >> 2);
        });
      } else if (want_rg) {
        dispatch_pixels(image, px, w, [=](int c, const std::uint8_t* p, std::ptrdiff_t cs) {
          opp_rg[c] = static_cast<std::uint8_t>((p[2 * cs] - p[cs] + 255) >> 1);
        });
      } else {
        dispatch_pixels(image, px, w, [=](int c, const std::uint8_t* p, std::ptrdiff_t cs) {
          opp_yb[c] = static_cast<std::uint8_t>((p[2 * cs] + p[cs] - 2 * p[0] + 510) >> 2);
        });
      }
    }
    for (int k = 0; k < n_planes; ++k) {
      const int ch = channels[static_cast<std::size_t>(k)];
      const std::uint8_t* v = ch == kLuma    ? here + 1
                              : ch == kGrad  ? grad
                              : ch == kOppRG ? opp_rg
                                             : opp_yb;
      Entry* plane_k = data_.data() + k * ps;
      accumulate_row(v, w, plane_k + r * s, plane_k + (r + 1) * s);
    }
  }
}

}  // namespace wmiltrack
