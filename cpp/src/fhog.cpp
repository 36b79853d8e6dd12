// Patches and fHOG features for the correlation filters (see fhog.hpp).
#include "wmiltrack/fhog.hpp"

#include <algorithm>
#include <cmath>
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
  std::vector<float> hist(ncell * kBins, 0.0f);
  // Orientation without std::atan2 (otherwise the costliest step): atan of the smaller over
  // the larger of |gx|, |gy| in [0, 1] by a degree-11 odd minimax polynomial (largest error
  // 1.7e-6 rad, checked against numpy in tests/test_correlation.py), then unfolded into the
  // octant of (gx, gy).
  constexpr float kA1 = 0.99997726f, kA3 = -0.33262347f, kA5 = 0.19354346f,
                  kA7 = -0.11643287f, kA9 = 0.05265332f, kA11 = -0.01172120f;
  const float bins_per_radian = static_cast<float>(kBins) / (2.0f * kPi);
  // Cell coordinate of each column's pixel centre (cells' centres at integers).
  const float inv_cell = 1.0f / static_cast<float>(cell);
  std::vector<int> col_cell(static_cast<std::size_t>(cols));
  std::vector<float> col_frac(static_cast<std::size_t>(cols));
  for (int c = 0; c < cols; ++c) {
    const float x = (static_cast<float>(c) + 0.5f) * inv_cell - 0.5f;
    col_cell[c] = static_cast<int>(std::floor(x));
    col_frac[c] = x - static_cast<float>(col_cell[c]);
  }
  const float* pix = patch.pixels.data();
  for (int r = 0; r < rows; ++r) {
    const float y = (static_cast<float>(r) + 0.5f) * inv_cell - 0.5f;
    const int y0 = static_cast<int>(std::floor(y));
    const float fy = y - static_cast<float>(y0);
    const float* up = pix + static_cast<std::size_t>(std::max(r - 1, 0)) * cols;
    const float* mid = pix + static_cast<std::size_t>(r) * cols;
    const float* down = pix + static_cast<std::size_t>(std::min(r + 1, rows - 1)) * cols;
    for (int c = 0; c < cols; ++c) {
      const float gx = mid[std::min(c + 1, cols - 1)] - mid[std::max(c - 1, 0)];
      const float gy = down[c] - up[c];
      const float mag = std::sqrt(gx * gx + gy * gy);
      if (mag == 0.0f) continue;
      const float ax = std::abs(gx), ay = std::abs(gy);
      const float t = std::min(ax, ay) / std::max(ax, ay), t2 = t * t;
      float angle = t * (kA1 + t2 * (kA3 + t2 * (kA5 + t2 * (kA7 + t2 * (kA9 + t2 * kA11)))));
      if (ay > ax) angle = 0.5f * kPi - angle;
      if (gx < 0.0f) angle = kPi - angle;
      if (gy < 0.0f) angle = 2.0f * kPi - angle;
      const float o = angle * bins_per_radian;
      int o0 = static_cast<int>(o);
      const float fo = o - static_cast<float>(o0);
      o0 %= kBins;
      const int o1 = (o0 + 1) % kBins;
      const int x0 = col_cell[c];
      const float fx = col_frac[c];
      for (int dy = 0; dy < 2; ++dy) {
        const int yy = y0 + dy;
        if (yy < 0 || yy >= cr) continue;
        const float wy = mag * (dy ? fy : 1.0f - fy);
        for (int dx = 0; dx < 2; ++dx) {
          const int xx = x0 + dx;
          if (xx < 0 || xx >= cc) continue;
          const float w = wy * (dx ? fx : 1.0f - fx);
          float* h = &hist[(static_cast<std::size_t>(yy) * cc + xx) * kBins];
          h[o0] += w * (1.0f - fo);
          h[o1] += w * fo;
        }
      }
    }
  }
  // Energy of each cell's unsigned histogram.
  std::vector<float> energy(ncell);
  for (std::size_t i = 0; i < ncell; ++i) {
    const float* h = &hist[i * kBins];
    float e = 0.0f;
    for (int o = 0; o < kBins / 2; ++o) e += (h[o] + h[o + kBins / 2]) * (h[o] + h[o + kBins / 2]);
    energy[i] = e;
  }
  const auto en = [&](int r, int c) {
    return energy[static_cast<std::size_t>(std::clamp(r, 0, cr - 1)) * cc +
                  std::clamp(c, 0, cc - 1)];
  };
  FeatureMap out;
  out.channels = kFhogChannels;
  out.rows = cr;
  out.cols = cc;
  out.data.assign(out.plane_size() * kFhogChannels, 0.0f);
  const std::size_t plane = out.plane_size();
  constexpr int kDy[4] = {-1, -1, 1, 1};
  constexpr int kDx[4] = {-1, 1, -1, 1};
  for (int r = 0; r < cr; ++r) {
    for (int c = 0; c < cc; ++c) {
      float n[4];
      for (int j = 0; j < 4; ++j) {
        const float s = en(r, c) + en(r + kDy[j], c) + en(r, c + kDx[j]) +
                        en(r + kDy[j], c + kDx[j]);
        n[j] = 1.0f / std::sqrt(s + 1e-4f);
      }
      const std::size_t at = static_cast<std::size_t>(r) * cc + c;
      const float* h = &hist[at * kBins];
      float texture[4] = {0.0f, 0.0f, 0.0f, 0.0f};
      for (int o = 0; o < kBins; ++o) {
        float sum = 0.0f;
        for (int j = 0; j < 4; ++j) {
          const float v = std::min(h[o] * n[j], 0.2f);
          sum += v;
          texture[j] += v;
        }
        out.data[o * plane + at] = 0.5f * sum;
      }
      for (int o = 0; o < kBins / 2; ++o) {
        const float u = h[o] + h[o + kBins / 2];
        float sum = 0.0f;
        for (int j = 0; j < 4; ++j) sum += std::min(u * n[j], 0.2f);
        out.data[(kBins + o) * plane + at] = 0.5f * sum;
      }
      for (int j = 0; j < 4; ++j) {
        out.data[(kBins + kBins / 2 + j) * plane + at] = 0.2357f * texture[j];
      }
    }
  }
  return out;
}

}  // namespace wmiltrack::cf
