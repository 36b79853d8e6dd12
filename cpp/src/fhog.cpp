// Patches and fHOG features for the correlation filters (see fhog.hpp).
#include "wmiltrack/fhog.hpp"

#include "wmiltrack/vmath.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace wmiltrack::cf {

namespace {

// The frame pixels one output sample (along one axis) averages, and their weights.
struct Taps {
  std::vector<int> first;     // per output index: offset into index/weight
  std::vector<int> index;     // frame coordinate (clamped to the frame)
  std::vector<float> weight;  // normalised to sum 1 per output index
};

// Output sample j covers frame coordinates [start + j * step, start + (j + 1) * step); its
// centre is start + (j + 0.5) * step - 0.5 in pixel-centre coordinates. A tent of radius
// max(1, step) around it weights the frame pixels on a lattice of every `stride`-th pixel
// (indices in lattice units: frame coordinate index * stride, clamped to the frame).
Taps make_taps(double start, double step, int n, int limit, int stride) {
  Taps t;
  t.first.reserve(static_cast<std::size_t>(n) + 1);
  const double radius = std::max(1.0, step);
  const int last = (limit - 1) / stride;  // the last lattice point inside the frame
  // At most 2 radius / stride + 2 taps an output (below 11 with lattice_stride's strides):
  // room for all of them, no reallocation in the loop.
  const double most = std::min(2.0 * radius / stride + 2.0, 64.0);
  t.index.reserve(static_cast<std::size_t>(n) * static_cast<std::size_t>(most));
  t.weight.reserve(t.index.capacity());
  for (int j = 0; j < n; ++j) {
    t.first.push_back(static_cast<int>(t.index.size()));
    const double centre = start + (j + 0.5) * step - 0.5;
    const int lo = static_cast<int>(std::floor((centre - radius) / stride)) + 1;
    const int hi = static_cast<int>(std::ceil((centre + radius) / stride)) - 1;
    double total = 0.0;
    const std::size_t begin = t.weight.size();
    for (int i = lo; i <= hi; ++i) {
      const double w = 1.0 - std::abs(i * stride - centre) / radius;
      if (w <= 0.0) continue;
      t.index.push_back(std::clamp(i, 0, last));
      t.weight.push_back(static_cast<float>(w));
      total += w;
    }
    if (t.weight.size() == begin) {  // cannot happen with radius >= stride, kept for safety
      t.index.push_back(std::clamp(static_cast<int>(std::lround(centre / stride)), 0, last));
      t.weight.push_back(1.0f);
      total = 1.0;
    }
    for (std::size_t k = begin; k < t.weight.size(); ++k) {
      t.weight[k] = static_cast<float>(t.weight[k] / total);
    }
  }
  t.first.push_back(static_cast<int>(t.index.size()));
  return t;
}

// The lattice step of a resampling whose output samples are `step` frame pixels apart:
// every pixel up to a step of 4, then every floor(step / 2)-th, so that a tent still reads
// at least four lattice points across (a region several times the patch's size costs what
// one twice its size does, not its area).
int lattice_stride(double step) {
  if (!(step >= 4.0)) return 1;  // (and a size that is not finite: patch_taps refuses it)
  return static_cast<int>(std::min(std::floor(step / 2.0), 65536.0));
}

// The taps of one output patch, both axes (indices in the units of the lattice they were made
// for: the caller keeps its strides).
struct PatchTaps {
  Taps x, y;
  int out_cols = 0, out_rows = 0;
};

// Buffers reused from call to call by one thread (the correlation filter samples the same
// sizes every frame: no allocation, no page faults after the first), each one's contents
// meaningful only inside the function that fills it.
struct Scratch {
  std::vector<std::uint8_t> luma_row;
  std::vector<float> crop;                      // LumaCrop's values
  std::vector<float> mix, mix4;                 // resample's column mixes
  std::vector<int> x_index, y_index;            // resample's taps, fixed count per output
  std::vector<float> x_weight, y_weight;
  std::vector<float> grad;                      // fhog: col_frac and a row's votes
  std::vector<int> col_cell;                    // fhog: col_cell and a row's vote offsets
  std::vector<float> row_hist, bordered, hist, energy, padded, norm, texture;
};

Scratch& scratch() {
  thread_local Scratch s;
  return s;
}

// The frame's luma at lattice rows [r0, r1] x columns [c0, c1] (inclusive; frame row
// r * stride_y, column c * stride_x), converted once so that several resamplings (scale
// samples) read floats. Its values live in the thread's scratch.
struct LumaCrop {
  int r0 = 0, c0 = 0, rows = 0, cols = 0;
  const float* values = nullptr;
  LumaCrop(const ImageView& frame, int row0, int row1, int col0, int col1, int stride_x,
           int stride_y, Scratch& s)
      : r0(row0), c0(col0), rows(row1 - row0 + 1), cols(col1 - col0 + 1) {
    s.crop.resize(static_cast<std::size_t>(rows) * cols);
    s.luma_row.resize(static_cast<std::size_t>(cols));
    ImageView lattice = frame;  // every stride_x-th column: luma_row reads them in a row
    lattice.col_stride *= stride_x;
    lattice.cols = (frame.cols - 1) / stride_x + 1;
    for (int r = 0; r < rows; ++r) {
      luma_row(lattice, (r0 + r) * stride_y, c0, c0 + cols, s.luma_row.data());
      float* out = &s.crop[static_cast<std::size_t>(r) * cols];
      const std::uint8_t* in = s.luma_row.data();
      for (int c = 0; c < cols; ++c) out[c] = static_cast<float>(in[c]);
    }
    values = s.crop.data();
  }
};

void check_frame(const ImageView& frame) {
  if (frame.data == nullptr || frame.rows < 1 || frame.cols < 1) {
    throw std::invalid_argument("sample_gray: empty frame");
  }
  if (!(frame.channels == 1 || frame.channels == 3 || frame.channels == 4)) {
    throw std::invalid_argument("sample_gray: the frame must have 1, 3 or 4 channels");
  }
}

// The taps of a region w x h around (cx, cy) resampled to out_cols x out_rows, on the lattice
// of every stride_x-th column and stride_y-th row of the frame.
PatchTaps patch_taps(const ImageView& frame, double cx, double cy, double w, double h,
                     int out_cols, int out_rows, int stride_x, int stride_y) {
  if (!(std::isfinite(cx) && std::isfinite(cy) && std::isfinite(w) && std::isfinite(h)) ||
      !(w > 0.0 && h > 0.0)) {
    throw std::invalid_argument("sample_gray: the centre must be finite and the size positive");
  }
  if (out_cols < 1 || out_rows < 1) {
    throw std::invalid_argument("sample_gray: the output size must be at least 1 x 1");
  }
  return PatchTaps{make_taps(cx - w / 2.0, w / out_cols, out_cols, frame.cols, stride_x),
                   make_taps(cy - h / 2.0, h / out_rows, out_rows, frame.rows, stride_y),
                   out_cols, out_rows};
}

// Taps with the same count for every output (the largest; the others padded with weight 0 on
// their last pixel, which adds exactly +0 to a sum of non-negative values: the same bits),
// tap k of output j at [k * n + j], so that a loop over the outputs has no inner loop of
// varying length. Outputs n .. padded_n - 1 repeat output n - 1's taps. Returns the count.
int fixed_taps(const Taps& t, int n, int padded_n, int shift, std::vector<int>& index,
               std::vector<float>& weight) {
  int count = 0;
  for (int j = 0; j < n; ++j) count = std::max(count, t.first[j + 1] - t.first[j]);
  index.resize(static_cast<std::size_t>(count) * padded_n);
  weight.resize(index.size());
  for (int j = 0; j < padded_n; ++j) {
    const int src = std::min(j, n - 1);
    const int first = t.first[src], size = t.first[src + 1] - first;
    for (int k = 0; k < count; ++k) {
      const std::size_t at = static_cast<std::size_t>(k) * padded_n + j;
      index[at] = t.index[first + std::min(k, size - 1)] - shift;
      weight[at] = k < size ? t.weight[first + k] : 0.0f;
    }
  }
  return count;
}

// Four floats with lane-wise IEEE arithmetic: one SSE register (GCC/Clang vector extension)
// or, with WMILTRACK_NO_SIMD or another compiler, four separate floats; the same bits.
#if (defined(__GNUC__) || defined(__clang__)) && !defined(WMILTRACK_NO_SIMD)
typedef float Lanes4 __attribute__((vector_size(16)));
inline Lanes4 lanes4_zero() { return Lanes4{0.0f, 0.0f, 0.0f, 0.0f}; }
inline Lanes4 lanes4_scale(float w, const float* p) {
  Lanes4 x;
  std::memcpy(&x, p, sizeof x);
  return w * x;
}
inline Lanes4 lanes4_add(Lanes4 a, Lanes4 b) { return a + b; }
inline Lanes4 lanes4_div(Lanes4 a, float d) { return a / d; }
inline void lanes4_store(Lanes4 a, float* p) { std::memcpy(p, &a, sizeof a); }
#else
struct Lanes4 {
  float v[4];
};
inline Lanes4 lanes4_zero() { return Lanes4{{0.0f, 0.0f, 0.0f, 0.0f}}; }
inline Lanes4 lanes4_scale(float w, const float* p) {
  return Lanes4{{w * p[0], w * p[1], w * p[2], w * p[3]}};
}
inline Lanes4 lanes4_add(Lanes4 a, Lanes4 b) {
  return Lanes4{{a.v[0] + b.v[0], a.v[1] + b.v[1], a.v[2] + b.v[2], a.v[3] + b.v[3]}};
}
inline Lanes4 lanes4_div(Lanes4 a, float d) {
  return Lanes4{{a.v[0] / d, a.v[1] / d, a.v[2] / d, a.v[3] / d}};
}
inline void lanes4_store(Lanes4 a, float* p) { std::memcpy(p, a.v, sizeof a.v); }
#endif

// m[c] = sum over k < n of w[k] src[k][c] (c < span), added in the order k = 0, 1, ... from
// 0 in registers: one pass over m, whatever the number of rows mixed (n <= kMaxRowTaps).
constexpr int kMaxRowTaps = 8;
template <int N>
void mix_rows_n(const float* const* src, const float* w, int span, float* __restrict m) {
  for (int c = 0; c < span; ++c) {
    float v = 0.0f;
    for (int k = 0; k < N; ++k) v += w[k] * src[k][c];
    m[c] = v;
  }
}
void mix_rows(const float* const* src, const float* w, int n, int span, float* m) {
  switch (n) {
    case 1: return mix_rows_n<1>(src, w, span, m);
    case 2: return mix_rows_n<2>(src, w, span, m);
    case 3: return mix_rows_n<3>(src, w, span, m);
    case 4: return mix_rows_n<4>(src, w, span, m);
    case 5: return mix_rows_n<5>(src, w, span, m);
    case 6: return mix_rows_n<6>(src, w, span, m);
    case 7: return mix_rows_n<7>(src, w, span, m);
    default: return mix_rows_n<8>(src, w, span, m);
  }
}

// Four rows of span values (one after the other in mix) interleaved: mix4[4 c + q] is row q's
// value c.
inline void interleave4(const float* mix, int span, float* mix4) {
  const float* m0 = mix;
  const float* m1 = m0 + span;
  const float* m2 = m1 + span;
  const float* m3 = m2 + span;
  for (int c = 0; c < span; ++c) {
    float* d = mix4 + static_cast<std::size_t>(4) * c;
    d[0] = m0[c];
    d[1] = m1[c];
    d[2] = m2[c];
    d[3] = m3[c];
  }
}

// The patch from a crop that holds every pixel its taps read: rows first (each output row
// mixes the crop rows under it over the crop's columns), then columns. Four output rows at a
// time: their column mixes are interleaved (mix4[4 c + q] for row q of the four), so that the
// column pass computes the four rows' pixels at once (Lanes4), each pixel's sum in the order
// of its taps, as one at a time would.
GrayPatch resample(const LumaCrop& crop, const PatchTaps& t, Scratch& s) {
  constexpr int kBlock = 4;
  GrayPatch out;
  out.rows = t.out_rows;
  out.cols = t.out_cols;
  out.pixels.resize(static_cast<std::size_t>(out.rows) * out.cols);
  const auto [lo, hi] = std::minmax_element(t.x.index.begin(), t.x.index.end());
  const int cmin = *lo - crop.c0, span = *hi - *lo + 1;
  const int padded_rows = (out.rows + kBlock - 1) / kBlock * kBlock;
  const int ky = fixed_taps(t.y, out.rows, padded_rows, crop.r0, s.y_index, s.y_weight);
  const int kx = fixed_taps(t.x, out.cols, out.cols, crop.c0 + cmin, s.x_index, s.x_weight);
  s.mix.resize(static_cast<std::size_t>(kBlock) * span);
  s.mix4.resize(static_cast<std::size_t>(kBlock) * span);
  float* const mix4 = s.mix4.data();
  const int* const xi = s.x_index.data();
  const float* const xw = s.x_weight.data();
  for (int j0 = 0; j0 < out.rows; j0 += kBlock) {
    for (int q = 0; q < kBlock; ++q) {
      const float* src[kMaxRowTaps];
      float wy[kMaxRowTaps];
      const int n = std::min(ky, kMaxRowTaps);
      for (int k = 0; k < n; ++k) {
        const std::size_t at = static_cast<std::size_t>(k) * padded_rows + j0 + q;
        wy[k] = s.y_weight[at];
        src[k] = crop.values + static_cast<std::size_t>(s.y_index[at]) * crop.cols + cmin;
      }
      float* const m = &s.mix[static_cast<std::size_t>(q) * span];
      mix_rows(src, wy, n, span, m);
      for (int k = n; k < ky; ++k) {  // (a region more than ~6 times the patch's height)
        const std::size_t at = static_cast<std::size_t>(k) * padded_rows + j0 + q;
        const float w = s.y_weight[at];
        const float* row = crop.values + static_cast<std::size_t>(s.y_index[at]) * crop.cols + cmin;
        for (int c = 0; c < span; ++c) m[c] += w * row[c];
      }
    }
    interleave4(s.mix.data(), span, mix4);
    float* rows[kBlock];
    for (int q = 0; q < kBlock; ++q) {
      // Rows past the patch (its last block) are computed into the block's first row, then
      // overwritten by the right values stored after them in the loop below (q ascending).
      const int r = j0 + q < out.rows ? j0 + q : j0;
      rows[q] = &out.pixels[static_cast<std::size_t>(r) * out.cols];
    }
    for (int i = 0; i < out.cols; ++i) {
      Lanes4 v = lanes4_zero();
      for (int k = 0; k < kx; ++k) {
        const std::size_t at = static_cast<std::size_t>(k) * out.cols + i;
        v = lanes4_add(v, lanes4_scale(xw[at], mix4 + static_cast<std::size_t>(kBlock) * xi[at]));
      }
      float r[kBlock];
      lanes4_store(lanes4_div(v, 255.0f), r);
      for (int q = kBlock - 1; q >= 0; --q) rows[q][i] = r[q];
    }
  }
  return out;
}

constexpr int kBins = 18;  // fHOG's signed orientation bins

// A cell's histogram in the votes' buffers: the 18 signed bins and a copy of bin 0 after bin
// 17 (bin 17's pixels vote into bins 17 and "18"), so that a pixel's two bins are always
// adjacent; the copy is added into bin 0 at the end.
constexpr int kCellStride = kBins + 1;

// Orientation without std::atan2 (otherwise the costliest step): atan of the smaller over
// the larger of |gx|, |gy| in [0, 1] by a degree-11 odd minimax polynomial (largest error
// 1.7e-6 rad, checked against numpy in tests/engine/test_correlation.py), then unfolded into the
// octant of (gx, gy). For one pixel with gradient (dx, dy), whose cells start at offset cell
// of a row's histograms (its second cell kCellStride later) with weight fx in the second: the
// offset of its lower bin o0 in the first cell, and its votes, magnitude m split between o0
// and o0 + 1 (1 - f, f) and between the cells (1 - fx, fx): v0 .. v3 = (o0, first cell),
// (o0 + 1, first), (o0, second), (o0 + 1, second).
WMILTRACK_KERNEL void orient_pixel(float dx, float dy, int cell, float fx, int& offset,
                                   float& v0, float& v1, float& v2, float& v3) {
  constexpr float kPi = 3.14159265358979323846f;
  constexpr float kA1 = 0.99997726f, kA3 = -0.33262347f, kA5 = 0.19354346f,
                  kA7 = -0.11643287f, kA9 = 0.05265332f, kA11 = -0.01172120f;
  const float bins_per_radian = static_cast<float>(kBins) / (2.0f * kPi);
  const float ax = std::abs(dx), ay = std::abs(dy);
  const float hi = std::max(ax, ay), lo = std::min(ax, ay);
  // (a flat pixel, hi = 0, gets t = 0 and votes with magnitude 0)
  const float t = lo / std::max(hi, std::numeric_limits<float>::min()), t2 = t * t;
  float angle = t * (kA1 + t2 * (kA3 + t2 * (kA5 + t2 * (kA7 + t2 * (kA9 + t2 * kA11)))));
  // Unfolded with arithmetic instead of branches (s * c exactly 0 or c, (1 - 2 s) exactly
  // +-1), so that the loop vectorises: pi/2 - a above the diagonal, pi - a for gx < 0,
  // 2 pi - a for gy < 0.
  const float s1 = static_cast<float>(ay > ax), s2 = static_cast<float>(dx < 0.0f),
              s3 = static_cast<float>(dy < 0.0f);
  angle = s1 * (0.5f * kPi) + (1.0f - 2.0f * s1) * angle;
  angle = s2 * kPi + (1.0f - 2.0f * s2) * angle;
  angle = s3 * (2.0f * kPi) + (1.0f - 2.0f * s3) * angle;
  const float o = angle * bins_per_radian;
  const int o0 = static_cast<int>(o);
  const float frac = o - static_cast<float>(o0);
  offset = cell + (o0 >= kBins ? o0 - kBins : o0);
  const float mag = std::sqrt(dx * dx + dy * dy);
  const float a = mag * (1.0f - frac), b = mag * frac;
  v0 = a * (1.0f - fx);
  v1 = b * (1.0f - fx);
  v2 = a * fx;
  v3 = b * fx;
}

// orient_pixel of pixels 0 .. n - 1 of a row, from their gradients (gx, gy), into the four
// planes of votes.
WMILTRACK_KERNEL void orient_pixels(const float* __restrict gx, const float* __restrict gy, int n,
                                    const int* __restrict col_cell,
                                    const float* __restrict col_frac, int* __restrict offset,
                                    float* __restrict p0, float* __restrict p1,
                                    float* __restrict p2, float* __restrict p3) {
  for (int c = 0; c < n; ++c) {
    orient_pixel(gx[c], gy[c], col_cell[c], col_frac[c], offset[c], p0[c], p1[c], p2[c], p3[c]);
  }
}

// orient_pixel of every pixel of a row (mid), with central differences (the edge pixel
// repeated: up / down are the rows above and below, or mid itself at the patch's edge);
// pixel c's cells at col_cell[c], weight col_frac[c]; its votes first in four planes of
// planes (cols apart: contiguous stores, the loop vectorises; two more planes hold the
// gradients), then interleaved into vote[4 c .. 4 c + 3] for the voting.
WMILTRACK_KERNEL void orient_row_body(const float* __restrict up, const float* __restrict mid,
                                      const float* __restrict down, int cols,
                                      const int* __restrict col_cell,
                                      const float* __restrict col_frac, int* __restrict offset,
                                      float* __restrict planes, float* __restrict vote) {
  float* const p0 = planes;
  float* const p1 = planes + cols;
  float* const p2 = planes + 2 * cols;
  float* const p3 = planes + 3 * cols;
  float* const gx = planes + 4 * cols;
  float* const gy = planes + 5 * cols;
  // The gradients first, so that the costly loop has no edge cases (and runs whole vectors).
  for (int c = 0; c < cols; ++c) gy[c] = down[c] - up[c];
  if (cols == 1) {
    gx[0] = 0.0f;
  } else {
    gx[0] = mid[1] - mid[0];
    for (int c = 1; c + 1 < cols; ++c) gx[c] = mid[c + 1] - mid[c - 1];
    gx[cols - 1] = mid[cols - 1] - mid[cols - 2];
  }
  orient_pixels(gx, gy, cols, col_cell, col_frac, offset, p0, p1, p2, p3);
  for (int c = 0; c < cols; ++c) {
    vote[4 * c] = p0[c];
    vote[4 * c + 1] = p1[c];
    vote[4 * c + 2] = p2[c];
    vote[4 * c + 3] = p3[c];
  }
}

// Two adjacent floats of a histogram plus two votes: one 8-byte add (GCC/Clang vector
// extension), or two with WMILTRACK_NO_SIMD or another compiler; the same bits.
inline void add_pair(float* h, const float* v) {
#if (defined(__GNUC__) || defined(__clang__)) && !defined(WMILTRACK_NO_SIMD)
  typedef float Pair __attribute__((vector_size(8)));
  Pair x, y;
  std::memcpy(&x, h, sizeof x);
  std::memcpy(&y, v, sizeof y);
  x += y;
  std::memcpy(h, &x, sizeof x);
#else
  h[0] += v[0];
  h[1] += v[1];
#endif
}

// norm[c] = 1 / sqrt(e[c] + ey[c] + e[c + dx] + ey[c + dx] + 1e-4) for c < n: the normaliser
// of the block of a cell (energy e, row of cells) with the cells in row ey and column c + dx.
WMILTRACK_KERNEL void block_norms(const float* __restrict e, const float* __restrict ey, int dx,
                                  int n, float* __restrict norm) {
  for (int c = 0; c < n; ++c) {
    const float sum = e[c] + ey[c] + e[c + dx] + ey[c + dx];
    norm[c] = 1.0f / std::sqrt(sum + 1e-4f);
  }
}

// One signed bin's plane (h, n cells) under the four normalisers (planes of norm, n apart):
// dst = 0.5 * sum_j min(h n_j, 0.2), and each min(h n_j, 0.2) added to texture plane j.
WMILTRACK_KERNEL void clip_signed(const float* __restrict h, const float* __restrict norm,
                                  std::size_t n, float* __restrict dst,
                                  float* __restrict texture) {
  const float* n0 = norm;
  const float* n1 = norm + n;
  const float* n2 = norm + 2 * n;
  const float* n3 = norm + 3 * n;
  float* t0 = texture;
  float* t1 = texture + n;
  float* t2 = texture + 2 * n;
  float* t3 = texture + 3 * n;
  for (std::size_t i = 0; i < n; ++i) {
    const float v0 = std::min(h[i] * n0[i], 0.2f), v1 = std::min(h[i] * n1[i], 0.2f);
    const float v2 = std::min(h[i] * n2[i], 0.2f), v3 = std::min(h[i] * n3[i], 0.2f);
    dst[i] = 0.5f * (((v0 + v1) + v2) + v3);
    t0[i] += v0;
    t1[i] += v1;
    t2[i] += v2;
    t3[i] += v3;
  }
}

// One unsigned bin's plane (a + b) under the four normalisers: 0.5 * sum_j min(u n_j, 0.2).
WMILTRACK_KERNEL void clip_unsigned(const float* __restrict a, const float* __restrict b,
                                    const float* __restrict norm, std::size_t n,
                                    float* __restrict dst) {
  const float* n0 = norm;
  const float* n1 = norm + n;
  const float* n2 = norm + 2 * n;
  const float* n3 = norm + 3 * n;
  for (std::size_t i = 0; i < n; ++i) {
    const float u = a[i] + b[i];
    dst[i] = 0.5f * (((std::min(u * n0[i], 0.2f) + std::min(u * n1[i], 0.2f)) +
                      std::min(u * n2[i], 0.2f)) + std::min(u * n3[i], 0.2f));
  }
}

// top[k] += wt row[k] and bottom[k] += fy row[k] (one row of pixels' votes into the two cell
// rows around it), then row[k] = 0 for the next row; k < n.
WMILTRACK_KERNEL void add_row_body(float* __restrict top, float* __restrict bottom,
                                   float* __restrict row, float wt, float fy, std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) {
    top[k] += wt * row[k];
    bottom[k] += fy * row[k];
    row[k] = 0.0f;
  }
}

// From the cells' histograms (hist: 18 planes of cr x cc cells) to the 31 planes of out:
// energy, the energies with the edge cells repeated once around them (padded, (cr + 2) x
// (cc + 2); a border cell's blocks reuse its own row / column), the four block normalisers
// of every cell (norm, 4 planes), the clipped features, the texture sums (texture, 4 planes).
WMILTRACK_KERNEL void normalise_body(const float* __restrict hist, int cr, int cc,
                                     float* __restrict energy, float* __restrict padded,
                                     float* __restrict norm, float* __restrict texture,
                                     float* __restrict out) {
  const std::size_t plane = static_cast<std::size_t>(cr) * cc;
  for (std::size_t i = 0; i < plane; ++i) energy[i] = 0.0f;
  for (int o = 0; o < kBins / 2; ++o) {
    const float* a = &hist[o * plane];
    const float* b = &hist[(o + kBins / 2) * plane];
    for (std::size_t i = 0; i < plane; ++i) energy[i] += (a[i] + b[i]) * (a[i] + b[i]);
  }
  const int pc = cc + 2;
  for (int r = -1; r <= cr; ++r) {
    const float* src = energy + static_cast<std::size_t>(r < 0 ? 0 : r < cr ? r : cr - 1) * cc;
    float* dst = padded + static_cast<std::size_t>(r + 1) * pc;
    dst[0] = src[0];
    for (int c = 0; c < cc; ++c) dst[c + 1] = src[c];
    dst[cc + 1] = src[cc - 1];
  }
  // Each block's sum in the order: the cell, the one above / below it, the one beside it, the
  // diagonal one.
  constexpr int kDy[4] = {-1, -1, 1, 1};
  constexpr int kDx[4] = {-1, 1, -1, 1};
  for (int j = 0; j < 4; ++j) {
    for (int r = 0; r < cr; ++r) {
      block_norms(padded + static_cast<std::size_t>(r + 1) * pc + 1,
                  padded + static_cast<std::size_t>(r + 1 + kDy[j]) * pc + 1, kDx[j], cc,
                  norm + j * plane + static_cast<std::size_t>(r) * cc);
    }
  }
  // The texture features sum each normaliser's clipped values over the 18 signed bins (in
  // bin order), then are scaled.
  for (std::size_t i = 0; i < 4 * plane; ++i) texture[i] = 0.0f;
  for (int o = 0; o < kBins; ++o) clip_signed(hist + o * plane, norm, plane, out + o * plane, texture);
  for (int o = 0; o < kBins / 2; ++o) {
    clip_unsigned(hist + o * plane, hist + (o + kBins / 2) * plane, norm, plane,
                  out + (kBins + o) * plane);
  }
  float* const texture_out = out + (kBins + kBins / 2) * plane;
  for (std::size_t i = 0; i < 4 * plane; ++i) texture_out[i] = texture[i] * 0.2357f;
}

#ifdef WMILTRACK_AVX2_COPIES
}  // namespace
namespace detail {
// The kernels above compiled for AVX2 (8 floats a step): the same IEEE operations in the same
// order (no fused multiply-add), so the same bits as the baseline copies. Named *_avx2 for the
// portable-build test (tests/core/test_core_hardening.py).
__attribute__((target("avx2"))) void fhog_orient_row_avx2(const float* up, const float* mid,
                                                         const float* down, int cols,
                                                         const int* col_cell,
                                                         const float* col_frac, int* offset,
                                                         float* planes, float* vote) {
  orient_row_body(up, mid, down, cols, col_cell, col_frac, offset, planes, vote);
}
__attribute__((target("avx2"))) void fhog_add_row_avx2(float* top, float* bottom, float* row,
                                                      float wt, float fy, std::size_t n) {
  add_row_body(top, bottom, row, wt, fy, n);
}
__attribute__((target("avx2"))) void fhog_normalise_avx2(const float* hist, int cr, int cc,
                                                        float* energy, float* padded,
                                                        float* norm, float* texture,
                                                        float* out) {
  normalise_body(hist, cr, cc, energy, padded, norm, texture, out);
}
}  // namespace detail
namespace {
#endif

// The kernels' entry points: the AVX2 copy where the CPU has it (vmath::avx2()).
void orient_row(const float* up, const float* mid, const float* down, int cols,
                const int* col_cell, const float* col_frac, int* offset, float* planes,
                float* vote) {
#ifdef WMILTRACK_AVX2_COPIES
  if (vmath::avx2()) {
    return detail::fhog_orient_row_avx2(up, mid, down, cols, col_cell, col_frac, offset,
                                        planes, vote);
  }
#endif
  orient_row_body(up, mid, down, cols, col_cell, col_frac, offset, planes, vote);
}

void add_row(float* top, float* bottom, float* row, float wt, float fy, std::size_t n) {
#ifdef WMILTRACK_AVX2_COPIES
  if (vmath::avx2()) return detail::fhog_add_row_avx2(top, bottom, row, wt, fy, n);
#endif
  add_row_body(top, bottom, row, wt, fy, n);
}

void normalise(const float* hist, int cr, int cc, float* energy, float* padded, float* norm,
               float* texture, float* out) {
#ifdef WMILTRACK_AVX2_COPIES
  if (vmath::avx2()) {
    return detail::fhog_normalise_avx2(hist, cr, cc, energy, padded, norm, texture, out);
  }
#endif
  normalise_body(hist, cr, cc, energy, padded, norm, texture, out);
}

// Bounds (inclusive) of the frame pixels a set of taps reads.
void extend(const Taps& t, int& lo, int& hi) {
  const auto [a, b] = std::minmax_element(t.index.begin(), t.index.end());
  lo = std::min(lo, *a);
  hi = std::max(hi, *b);
}

}  // namespace

GrayPatch sample_gray(const ImageView& frame, double cx, double cy, double w, double h,
                      int out_cols, int out_rows) {
  check_frame(frame);
  const int sx = out_cols > 0 ? lattice_stride(w / out_cols) : 1;
  const int sy = out_rows > 0 ? lattice_stride(h / out_rows) : 1;
  const PatchTaps t = patch_taps(frame, cx, cy, w, h, out_cols, out_rows, sx, sy);
  int r0 = frame.rows, r1 = -1, c0 = frame.cols, c1 = -1;
  extend(t.y, r0, r1);
  extend(t.x, c0, c1);
  Scratch& s = scratch();
  return resample(LumaCrop(frame, r0, r1, c0, c1, sx, sy, s), t, s);
}

std::vector<GrayPatch> sample_gray_scales(const ImageView& frame, double cx, double cy, double w,
                                          double h, const std::vector<double>& factors,
                                          int out_cols, int out_rows) {
  check_frame(frame);
  std::vector<GrayPatch> out;
  if (factors.empty()) return out;
  double smallest = factors.front();
  for (double f : factors) {
    if (!(f > 0.0 && std::isfinite(f))) {
      throw std::invalid_argument("sample_gray_scales: factors must be positive and finite");
    }
    smallest = std::min(smallest, f);
  }
  // One lattice for every scale (they share one crop): the finest any of them needs.
  const int sx = out_cols > 0 ? lattice_stride(w * smallest / out_cols) : 1;
  const int sy = out_rows > 0 ? lattice_stride(h * smallest / out_rows) : 1;
  std::vector<PatchTaps> taps;
  taps.reserve(factors.size());
  int r0 = frame.rows, r1 = -1, c0 = frame.cols, c1 = -1;
  for (double f : factors) {
    taps.push_back(patch_taps(frame, cx, cy, w * f, h * f, out_cols, out_rows, sx, sy));
    extend(taps.back().y, r0, r1);
    extend(taps.back().x, c0, c1);
  }
  Scratch& s = scratch();
  const LumaCrop crop(frame, r0, r1, c0, c1, sx, sy, s);
  out.reserve(taps.size());
  for (const PatchTaps& t : taps) out.push_back(resample(crop, t, s));
  return out;
}

// fhog's input checked: a cell of at least one pixel, a patch of at least one cell whose
// pixels match its size.
static void check_patch(const GrayPatch& patch, int cell) {
  if (cell < 1) throw std::invalid_argument("fhog: cell must be at least 1");
  if (patch.rows < cell || patch.cols < cell) {
    throw std::invalid_argument("fhog: the patch (" + std::to_string(patch.rows) + " x " +
                                std::to_string(patch.cols) + ") is smaller than one cell (" +
                                std::to_string(cell) + ")");
  }
  if (patch.pixels.size() != static_cast<std::size_t>(patch.rows) * patch.cols) {
    throw std::invalid_argument("fhog: the patch's pixels do not match its size");
  }
}

// Each column's first cell (its offset in a row's bordered histograms) and its weight in the
// second, from the pixel centre's cell coordinate (cells' centres at integers).
static void column_cells(int cols, float inv_cell, int* col_cell, float* col_frac) {
  for (int c = 0; c < cols; ++c) {
    const float x = (static_cast<float>(c) + 0.5f) * inv_cell - 0.5f;
    const int x0 = static_cast<int>(std::floor(x));
    col_cell[c] = (x0 + 1) * kCellStride;
    col_frac[c] = x - static_cast<float>(x0);
  }
}

// The cells' histograms without the border, bin-major (plane o holds bin o of every cell);
// bin 0 gathers its copy's votes.
static void gather_cells(const float* bordered, std::size_t hrow, int cr, int cc, float* hist) {
  const std::size_t plane = static_cast<std::size_t>(cr) * cc;
  for (int r = 0; r < cr; ++r) {
    const float* src = bordered + static_cast<std::size_t>(r + 1) * hrow + kCellStride;
    for (int c = 0; c < cc; ++c) {
      const std::size_t at = static_cast<std::size_t>(r) * cc + c;
      const float* cell_hist = src + c * kCellStride;
      hist[at] = cell_hist[0] + cell_hist[kBins];
      for (int o = 1; o < kBins; ++o) hist[o * plane + at] = cell_hist[o];
    }
  }
}

FeatureMap fhog(const GrayPatch& patch, int cell) {
  check_patch(patch, cell);
  Scratch& s = scratch();
  const int rows = patch.rows, cols = patch.cols;
  const int cr = rows / cell, cc = cols / cell;
  const std::size_t plane = static_cast<std::size_t>(cr) * cc;
  // Histograms with a border of cells around them (one before, two after: the outer half
  // cells' pixels, and those beyond the last whole cell, vote into it; it is dropped), so that
  // the voting needs no bounds checks.
  const int hcols = cc + 3;
  const std::size_t hrow = static_cast<std::size_t>(hcols) * kCellStride;
  s.bordered.assign(static_cast<std::size_t>(cr + 3) * hrow, 0.0f);
  s.row_hist.assign(hrow, 0.0f);  // add_row leaves it zero for the next row
  // Cell coordinate of each column's pixel centre (cells' centres at integers), plus one for
  // the border: the offset of the first of its two cells in a row's histograms, and its
  // weight in the second.
  const float inv_cell = 1.0f / static_cast<float>(cell);
  s.col_cell.resize(static_cast<std::size_t>(cols) * 2);  // col_cell, then the votes' offsets
  s.grad.resize(static_cast<std::size_t>(cols) * 11);  // col_frac, 6 planes, votes
  int* const col_cell = s.col_cell.data();
  int* const offset = col_cell + cols;
  float* const col_frac = s.grad.data();
  float* const planes = col_frac + cols;
  float* const vote = planes + 6 * cols;
  column_cells(cols, inv_cell, col_cell, col_frac);
  // Per row: every pixel's gradient, orientation and votes (a branch-free loop the compiler
  // vectorises, twice: AVX2 where the CPU has it), then the votes into the row's cells along x,
  // then the row's votes into the two cell rows around it. The votes go column by column 2
  // cells apart (c, c + 2 cell, ...; then c + 1, ...): two pixels voted one after the other
  // never share a histogram entry, so no vote waits for the previous one's store (neighbouring
  // pixels of a smooth image fall in the same bins).
  const int stride = 2 * cell;
  const float* pix = patch.pixels.data();
  float* const row_hist = s.row_hist.data();
  for (int r = 0; r < rows; ++r) {
    const float y = (static_cast<float>(r) + 0.5f) * inv_cell - 0.5f;
    const int y0 = static_cast<int>(std::floor(y));
    const float fy = y - static_cast<float>(y0);
    const float* up = pix + static_cast<std::size_t>(std::max(r - 1, 0)) * cols;
    const float* mid = pix + static_cast<std::size_t>(r) * cols;
    const float* down = pix + static_cast<std::size_t>(std::min(r + 1, rows - 1)) * cols;
    orient_row(up, mid, down, cols, col_cell, col_frac, offset, planes, vote);
    for (int phase = 0; phase < stride && phase < cols; ++phase) {
      for (int c = phase; c < cols; c += stride) {
        float* h = row_hist + offset[c];
        add_pair(h, vote + 4 * c);
        add_pair(h + kCellStride, vote + 4 * c + 2);
      }
    }
    float* top = &s.bordered[static_cast<std::size_t>(y0 + 1) * hrow];
    add_row(top, top + hrow, row_hist, 1.0f - fy, fy, hrow);
  }
  // The cells themselves, without the border, bin-major (plane o holds bin o of every cell),
  // so that the normalisation below runs over cells, several at a time; bin 0 gathers its
  // copy's votes.
  s.hist.resize(plane * kBins);
  float* const hist = s.hist.data();
  gather_cells(s.bordered.data(), hrow, cr, cc, hist);
  FeatureMap out;
  out.channels = kFhogChannels;
  out.rows = cr;
  out.cols = cc;
  out.data.resize(out.plane_size() * kFhogChannels);
  s.energy.resize(plane);
  s.padded.resize(static_cast<std::size_t>(cr + 2) * (cc + 2));
  s.norm.resize(4 * plane);
  s.texture.resize(4 * plane);
  normalise(hist, cr, cc, s.energy.data(), s.padded.data(), s.norm.data(), s.texture.data(),
            out.data.data());
  return out;
}

}  // namespace wmiltrack::cf
