// Patches and fHOG features for the correlation filters (see fhog.hpp).
#include "wmiltrack/fhog.hpp"

#include <algorithm>
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
// max(1, step) around it weights the frame pixels.
Taps make_taps(double start, double step, int n, int limit) {
  Taps t;
  t.first.reserve(static_cast<std::size_t>(n) + 1);
  const double radius = std::max(1.0, step);
  for (int j = 0; j < n; ++j) {
    t.first.push_back(static_cast<int>(t.index.size()));
    const double centre = start + (j + 0.5) * step - 0.5;
    const int lo = static_cast<int>(std::floor(centre - radius)) + 1;
    const int hi = static_cast<int>(std::ceil(centre + radius)) - 1;
    double total = 0.0;
    const std::size_t begin = t.weight.size();
    for (int i = lo; i <= hi; ++i) {
      const double w = 1.0 - std::abs(i - centre) / radius;
      if (w <= 0.0) continue;
      t.index.push_back(std::clamp(i, 0, limit - 1));
      t.weight.push_back(static_cast<float>(w));
      total += w;
    }
    if (t.weight.size() == begin) {  // cannot happen with radius >= 1, kept for safety
      t.index.push_back(std::clamp(static_cast<int>(std::lround(centre)), 0, limit - 1));
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

inline float luma(const ImageView& f, int r, int c) {
  const std::uint8_t* p = f.data + r * f.row_stride + c * f.col_stride;
  if (f.channels == 1) return static_cast<float>(p[0]);
  return static_cast<float>(bgr_to_gray(p[0], p[f.channel_stride], p[2 * f.channel_stride]));
}

// The taps of one output patch, both axes.
struct PatchTaps {
  Taps x, y;
  int out_cols = 0, out_rows = 0;
};

// The frame's luma over rows [r0, r1] x columns [c0, c1] (inclusive), converted once so that
// several resamplings (scale samples) read floats.
struct LumaCrop {
  int r0 = 0, c0 = 0, rows = 0, cols = 0;
  std::vector<float> values;
  LumaCrop(const ImageView& frame, int row0, int row1, int col0, int col1)
      : r0(row0), c0(col0), rows(row1 - row0 + 1), cols(col1 - col0 + 1),
        values(static_cast<std::size_t>(rows) * cols) {
    for (int r = 0; r < rows; ++r) {
      float* out = &values[static_cast<std::size_t>(r) * cols];
      for (int c = 0; c < cols; ++c) out[c] = luma(frame, r0 + r, c0 + c);
    }
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

PatchTaps patch_taps(const ImageView& frame, double cx, double cy, double w, double h,
                     int out_cols, int out_rows) {
  if (!(std::isfinite(cx) && std::isfinite(cy) && std::isfinite(w) && std::isfinite(h)) ||
      !(w > 0.0 && h > 0.0)) {
    throw std::invalid_argument("sample_gray: the centre must be finite and the size positive");
  }
  if (out_cols < 1 || out_rows < 1) {
    throw std::invalid_argument("sample_gray: the output size must be at least 1 x 1");
  }
  return PatchTaps{make_taps(cx - w / 2.0, w / out_cols, out_cols, frame.cols),
                   make_taps(cy - h / 2.0, h / out_rows, out_rows, frame.rows), out_cols,
                   out_rows};
}

// The patch from a crop that holds every pixel its taps read: rows first (each output row
// mixes the crop rows under it over the crop's columns), then columns.
GrayPatch resample(const LumaCrop& crop, const PatchTaps& t) {
  GrayPatch out;
  out.rows = t.out_rows;
  out.cols = t.out_cols;
  out.pixels.assign(static_cast<std::size_t>(out.rows) * out.cols, 0.0f);
  const auto [lo, hi] = std::minmax_element(t.x.index.begin(), t.x.index.end());
  const int cmin = *lo - crop.c0, span = *hi - *lo + 1;
  std::vector<float> column_mix(static_cast<std::size_t>(span));
  for (int j = 0; j < out.rows; ++j) {
    std::fill(column_mix.begin(), column_mix.end(), 0.0f);
    for (int k = t.y.first[j]; k < t.y.first[j + 1]; ++k) {
      const float wy = t.y.weight[k];
      const float* src =
          &crop.values[static_cast<std::size_t>(t.y.index[k] - crop.r0) * crop.cols + cmin];
      for (int c = 0; c < span; ++c) column_mix[c] += wy * src[c];
    }
    float* row = &out.pixels[static_cast<std::size_t>(j) * out.cols];
    for (int i = 0; i < out.cols; ++i) {
      float v = 0.0f;
      for (int k = t.x.first[i]; k < t.x.first[i + 1]; ++k) {
        v += t.x.weight[k] * column_mix[t.x.index[k] - crop.c0 - cmin];
      }
      row[i] = v / 255.0f;
    }
  }
  return out;
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
  const PatchTaps t = patch_taps(frame, cx, cy, w, h, out_cols, out_rows);
  int r0 = frame.rows, r1 = -1, c0 = frame.cols, c1 = -1;
  extend(t.y, r0, r1);
  extend(t.x, c0, c1);
  return resample(LumaCrop(frame, r0, r1, c0, c1), t);
}

std::vector<GrayPatch> sample_gray_scales(const ImageView& frame, double cx, double cy, double w,
                                          double h, const std::vector<double>& factors,
                                          int out_cols, int out_rows) {
  check_frame(frame);
  std::vector<PatchTaps> taps;
  taps.reserve(factors.size());
  int r0 = frame.rows, r1 = -1, c0 = frame.cols, c1 = -1;
  for (double f : factors) {
    if (!(f > 0.0 && std::isfinite(f))) {
      throw std::invalid_argument("sample_gray_scales: factors must be positive and finite");
    }
    taps.push_back(patch_taps(frame, cx, cy, w * f, h * f, out_cols, out_rows));
    extend(taps.back().y, r0, r1);
    extend(taps.back().x, c0, c1);
  }
  std::vector<GrayPatch> out;
  if (taps.empty()) return out;
  const LumaCrop crop(frame, r0, r1, c0, c1);
  out.reserve(taps.size());
  for (const PatchTaps& t : taps) out.push_back(resample(crop, t));
  return out;
}

FeatureMap fhog(const GrayPatch& patch, int cell) {
  if (cell < 1) throw std::invalid_argument("fhog: cell must be at least 1");
  if (patch.rows < cell || patch.cols < cell) {
    throw std::invalid_argument("fhog: the patch (" + std::to_string(patch.rows) + " x " +
                                std::to_string(patch.cols) + ") is smaller than one cell (" +
                                std::to_string(cell) + ")");
  }
  if (patch.pixels.size() != static_cast<std::size_t>(patch.rows) * patch.cols) {
    throw std::invalid_argument("fhog: the patch's pixels do not match its size");
  }
  constexpr int kBins = 18;
  constexpr float kPi = 3.14159265358979323846f;
  const int rows = patch.rows, cols = patch.cols;
  const int cr = rows / cell, cc = cols / cell;
  const std::size_t ncell = static_cast<std::size_t>(cr) * cc;
  // Histograms with a border of cells around them (one before, two after: the outer half
  // cells' pixels, and those beyond the last whole cell, vote into it; it is dropped), so that
  // the voting needs no bounds checks.
  const int hcols = cc + 3;
  const std::size_t hrow = static_cast<std::size_t>(hcols) * kBins;
  std::vector<float> bordered(static_cast<std::size_t>(cr + 3) * hrow, 0.0f);
  // Orientation without std::atan2 (otherwise the costliest step): atan of the smaller over
  // the larger of |gx|, |gy| in [0, 1] by a degree-11 odd minimax polynomial (largest error
  // 1.7e-6 rad, checked against numpy in tests/test_correlation.py), then unfolded into the
  // octant of (gx, gy).
  constexpr float kA1 = 0.99997726f, kA3 = -0.33262347f, kA5 = 0.19354346f,
                  kA7 = -0.11643287f, kA9 = 0.05265332f, kA11 = -0.01172120f;
  const float bins_per_radian = static_cast<float>(kBins) / (2.0f * kPi);
  // Cell coordinate of each column's pixel centre (cells' centres at integers), plus one for
  // the border.
  const float inv_cell = 1.0f / static_cast<float>(cell);
  std::vector<int> col_cell(static_cast<std::size_t>(cols));
  std::vector<float> col_frac(static_cast<std::size_t>(cols));
  for (int c = 0; c < cols; ++c) {
    const float x = (static_cast<float>(c) + 0.5f) * inv_cell - 0.5f;
    const int x0 = static_cast<int>(std::floor(x));
    col_cell[c] = x0 + 1;
    col_frac[c] = x - static_cast<float>(x0);
  }
  // Per row: the gradients' magnitude and orientation bin of every pixel (a branch-free loop
  // the compiler vectorises), then their votes into the row's cells along x, then the row's
  // votes into the two cell rows around it.
  std::vector<float> gx(static_cast<std::size_t>(cols)), gy(gx.size()), mag(gx.size()),
      frac(gx.size()), row_hist(hrow);
  std::vector<int> bin(gx.size());
  const float* pix = patch.pixels.data();
  for (int r = 0; r < rows; ++r) {
    const float y = (static_cast<float>(r) + 0.5f) * inv_cell - 0.5f;
    const int y0 = static_cast<int>(std::floor(y));
    const float fy = y - static_cast<float>(y0);
    const float* up = pix + static_cast<std::size_t>(std::max(r - 1, 0)) * cols;
    const float* mid = pix + static_cast<std::size_t>(r) * cols;
    const float* down = pix + static_cast<std::size_t>(std::min(r + 1, rows - 1)) * cols;
    for (int c = 0; c < cols; ++c) gy[c] = down[c] - up[c];
    gx[0] = mid[std::min(1, cols - 1)] - mid[0];
    for (int c = 1; c + 1 < cols; ++c) gx[c] = mid[c + 1] - mid[c - 1];
    if (cols > 1) gx[cols - 1] = mid[cols - 1] - mid[cols - 2];
    for (int c = 0; c < cols; ++c) {
      const float dx = gx[c], dy = gy[c];
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
      frac[c] = o - static_cast<float>(o0);
      bin[c] = o0 >= kBins ? o0 - kBins : o0;
      mag[c] = std::sqrt(dx * dx + dy * dy);
    }
    std::fill(row_hist.begin(), row_hist.end(), 0.0f);
    for (int c = 0; c < cols; ++c) {
      const int o0 = bin[c], o1 = o0 + 1 == kBins ? 0 : o0 + 1;
      const float a = mag[c] * (1.0f - frac[c]), b = mag[c] * frac[c];
      const float fx = col_frac[c];
      float* h0 = &row_hist[static_cast<std::size_t>(col_cell[c]) * kBins];
      float* h1 = h0 + kBins;
      h0[o0] += a * (1.0f - fx);
      h0[o1] += b * (1.0f - fx);
      h1[o0] += a * fx;
      h1[o1] += b * fx;
    }
    float* top = &bordered[static_cast<std::size_t>(y0 + 1) * hrow];
    float* bottom = top + hrow;
    const float wt = 1.0f - fy;
    for (std::size_t k = 0; k < hrow; ++k) {
      top[k] += wt * row_hist[k];
      bottom[k] += fy * row_hist[k];
    }
  }
  // The cells themselves, without the border, bin-major (plane o holds bin o of every cell),
  // so that the normalisation below runs over cells, several at a time.
  const std::size_t plane = ncell;
  std::vector<float> hist(plane * kBins);
  for (int r = 0; r < cr; ++r) {
    const float* src = &bordered[static_cast<std::size_t>(r + 1) * hrow + kBins];
    for (int c = 0; c < cc; ++c) {
      const std::size_t at = static_cast<std::size_t>(r) * cc + c;
      for (int o = 0; o < kBins; ++o) hist[o * plane + at] = src[c * kBins + o];
    }
  }
  // Energy of each cell's unsigned histogram.
  std::vector<float> energy(ncell, 0.0f);
  for (int o = 0; o < kBins / 2; ++o) {
    const float* a = &hist[o * plane];
    const float* b = &hist[(o + kBins / 2) * plane];
    for (std::size_t i = 0; i < ncell; ++i) energy[i] += (a[i] + b[i]) * (a[i] + b[i]);
  }
  const auto en = [&](int r, int c) {
    return energy[static_cast<std::size_t>(std::clamp(r, 0, cr - 1)) * cc +
                  std::clamp(c, 0, cc - 1)];
  };
  // The four block normalisers of every cell (its 2 x 2 blocks of cells, edges replicated).
  constexpr int kDy[4] = {-1, -1, 1, 1};
  constexpr int kDx[4] = {-1, 1, -1, 1};
  std::vector<float> norm(4 * plane);
  for (int r = 0; r < cr; ++r) {
    for (int c = 0; c < cc; ++c) {
      const std::size_t at = static_cast<std::size_t>(r) * cc + c;
      for (int j = 0; j < 4; ++j) {
        const float sum = en(r, c) + en(r + kDy[j], c) + en(r, c + kDx[j]) +
                          en(r + kDy[j], c + kDx[j]);
        norm[j * plane + at] = 1.0f / std::sqrt(sum + 1e-4f);
      }
    }
  }
  FeatureMap out;
  out.channels = kFhogChannels;
  out.rows = cr;
  out.cols = cc;
  out.data.assign(out.plane_size() * kFhogChannels, 0.0f);
  const float* n0 = &norm[0];
  const float* n1 = &norm[plane];
  const float* n2 = &norm[2 * plane];
  const float* n3 = &norm[3 * plane];
  // The texture features sum each normaliser's clipped values over the 18 signed bins (in
  // bin order); they are accumulated in their output planes and scaled at the end.
  float* texture[4];
  for (int j = 0; j < 4; ++j) texture[j] = &out.data[(kBins + kBins / 2 + j) * plane];
  for (int o = 0; o < kBins; ++o) {
    const float* h = &hist[o * plane];
    float* dst = &out.data[o * plane];
    for (std::size_t i = 0; i < plane; ++i) {
      const float v0 = std::min(h[i] * n0[i], 0.2f), v1 = std::min(h[i] * n1[i], 0.2f);
      const float v2 = std::min(h[i] * n2[i], 0.2f), v3 = std::min(h[i] * n3[i], 0.2f);
      dst[i] = 0.5f * (((v0 + v1) + v2) + v3);
      texture[0][i] += v0;
      texture[1][i] += v1;
      texture[2][i] += v2;
      texture[3][i] += v3;
    }
  }
  for (int o = 0; o < kBins / 2; ++o) {
    const float* a = &hist[o * plane];
    const float* b = &hist[(o + kBins / 2) * plane];
    float* dst = &out.data[(kBins + o) * plane];
    for (std::size_t i = 0; i < plane; ++i) {
      const float u = a[i] + b[i];
      dst[i] = 0.5f * (((std::min(u * n0[i], 0.2f) + std::min(u * n1[i], 0.2f)) +
                        std::min(u * n2[i], 0.2f)) + std::min(u * n3[i], 0.2f));
    }
  }
  for (int j = 0; j < 4; ++j) {
    for (std::size_t i = 0; i < plane; ++i) texture[j][i] *= 0.2357f;
  }
  return out;
}

}  // namespace wmiltrack::cf
