// Correlation filters in the Fourier domain (see correlation.hpp).
#include "wmiltrack/correlation.hpp"

#include "wmiltrack/vmath.hpp"

#include "batch_fft.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <unsupported/Eigen/FFT>

namespace wmiltrack::cf {

namespace {

using Complex = std::complex<float>;
constexpr double kPi = 3.14159265358979323846;

// out (rows x n, row-major) = m (rows x inner, row-major) times x (inner x n, row-major), each
// row vmath::weighted_rows_f32 of x (its sums in the order j = 0, 1, ...; the same bits on
// every code path), then multiplied by scale[i] when scale is given.
void mix_rows(const float* m, int rows, int inner, const float* x, std::size_t n,
              const float* scale, float* out) {
  for (int k = 0; k < rows; ++k) {
    float* o = out + static_cast<std::size_t>(k) * n;
    vmath::weighted_rows_f32(x, inner, static_cast<int>(n), m + static_cast<std::size_t>(k) * inner, o);
    if (scale != nullptr) {
      for (std::size_t i = 0; i < n; ++i) o[i] *= scale[i];
    }
  }
}

// MATLAB's hann(n): 0.5 (1 - cos(2 pi k / (n - 1))), k = 0 .. n - 1; 1 for n == 1.
std::vector<float> hann(int n) {
  std::vector<float> w(static_cast<std::size_t>(n), 1.0f);
  if (n > 1) {
    for (int k = 0; k < n; ++k) {
      w[k] = static_cast<float>(0.5 * (1.0 - std::cos(2.0 * kPi * k / (n - 1))));
    }
  }
  return w;
}

void check_rate(double rate) {
  if (!(rate > 0.0 && rate <= 1.0)) {
    throw std::invalid_argument("the learning rate must be in (0, 1], got " + std::to_string(rate));
  }
}

void check_filter_args(double sigma, double lambda) {
  if (!(sigma > 0.0 && std::isfinite(sigma))) {
    throw std::invalid_argument("sigma must be positive and finite");
  }
  if (!(lambda >= 0.0 && std::isfinite(lambda))) {
    throw std::invalid_argument("lambda must be non-negative and finite");
  }
}

// Vertex of the parabola through (-1, a), (0, b), (1, c), in [-0.5, 0.5]; 0 unless b is a
// strict maximum of a curved parabola.
double parabola_offset(double a, double b, double c) {
  const double curve = a - 2.0 * b + c;
  if (!(curve < 0.0)) return 0.0;
  return std::clamp(0.5 * (a - c) / curve, -0.5, 0.5);
}

template <typename Num, typename Den>
void blend(std::vector<Num>& model, const std::vector<Num>& sample, double rate, bool first,
           std::vector<Den>& den_model, const std::vector<Den>& den_sample) {
  if (first || rate >= 1.0) {
    model = sample;
    den_model = den_sample;
    return;
  }
  const float keep = static_cast<float>(1.0 - rate), take = static_cast<float>(rate);
  for (std::size_t i = 0; i < model.size(); ++i) model[i] = keep * model[i] + take * sample[i];
  for (std::size_t i = 0; i < den_model.size(); ++i) {
    den_model[i] = keep * den_model[i] + take * den_sample[i];
  }
}

}  // namespace

// ------------------------------------------------------------------ translation filter
TranslationFilter::TranslationFilter(int rows, int cols, int channels, double sigma, double lambda,
                                     int compressed)
    : rows_(rows), cols_(cols), channels_(channels), kept_(channels), lambda_(lambda) {
  if (rows < 1 || cols < 1 || channels < 1) {
    throw std::invalid_argument("TranslationFilter: rows, cols and channels must be at least 1");
  }
  if (compressed < 0) {
    throw std::invalid_argument("TranslationFilter: compressed must be >= 0");
  }
  if (compressed > 0 && compressed < channels) kept_ = compressed;
  check_filter_args(sigma, lambda);
  const std::vector<float> wr = hann(rows), wc = hann(cols);
  window_.resize(static_cast<std::size_t>(rows) * cols);
  label_.resize(window_.size());
  for (int r = 0; r < rows; ++r) {
    const int dr = std::min(r, rows - r);
    for (int c = 0; c < cols; ++c) {
      const int dc = std::min(c, cols - c);
      const std::size_t at = static_cast<std::size_t>(r) * cols + c;
      window_[at] = wr[r] * wc[c];
      label_[at] = static_cast<float>(std::exp(-0.5 * (dr * dr + dc * dc) / (sigma * sigma)));
    }
  }
  fft_ = std::make_shared<const detail::Fft2>(rows, cols);
  label_f_.resize(static_cast<std::size_t>(rows) * fft_->half());
  fft_->forward_half(label_.data(), 1, label_f_.data());
  for (auto& v : label_f_) v = std::conj(v);
}

void TranslationFilter::check(const FeatureMap& x) const {
  if (x.channels != channels_ || x.rows != rows_ || x.cols != cols_ ||
      x.data.size() != x.plane_size() * static_cast<std::size_t>(x.channels)) {
    throw std::invalid_argument(
        "TranslationFilter: features of shape (" + std::to_string(x.channels) + ", " +
        std::to_string(x.rows) + ", " + std::to_string(x.cols) + ") for a filter of (" +
        std::to_string(channels_) + ", " + std::to_string(rows_) + ", " + std::to_string(cols_) +
        ")");
  }
}

void TranslationFilter::check(const Spectrum& s) const {
  if (s.channels != kept_ || s.rows != rows_ || s.cols != cols_ ||
      s.data.size() != label_f_.size() * static_cast<std::size_t>(kept_)) {
    throw std::invalid_argument("TranslationFilter: a spectrum of (" + std::to_string(s.channels) +
                                ", " + std::to_string(s.rows) + ", " + std::to_string(s.cols) +
                                ") for a filter of (" + std::to_string(kept_) + ", " +
                                std::to_string(rows_) + ", " + std::to_string(cols_) + ")");
  }
}

// The principal axes of the sample's cells: eigenvectors of sum over cells of x x^T (the
// features' second moments, as fDSST takes them), largest eigenvalues first, each signed so
// that its largest entry is positive (the eigen solver's sign is arbitrary).
void TranslationFilter::fit_projection(const FeatureMap& x) {
  const Eigen::Index plane = static_cast<Eigen::Index>(x.plane_size());
  const Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>
      features(x.data.data(), channels_, plane);
  const Eigen::MatrixXd moments = (features.cast<double>() * features.cast<double>().transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(moments);
  if (solver.info() != Eigen::Success) {
    throw std::runtime_error("TranslationFilter: the features' eigen decomposition failed");
  }
  projection_.assign(static_cast<std::size_t>(kept_) * channels_, 0.0f);
  for (int k = 0; k < kept_; ++k) {
    Eigen::VectorXd axis = solver.eigenvectors().col(channels_ - 1 - k);
    Eigen::Index big = 0;
    axis.cwiseAbs().maxCoeff(&big);
    if (axis(big) < 0.0) axis = -axis;
    for (int j = 0; j < channels_; ++j) {
      projection_[static_cast<std::size_t>(k) * channels_ + j] = static_cast<float>(axis(j));
    }
  }
}

Spectrum TranslationFilter::transform(const FeatureMap& x) const {
  check(x);
  const bool project = kept_ < channels_;
  if (project && projection_.empty()) {
    throw std::logic_error("TranslationFilter: a compressed filter learns before it transforms");
  }
  const std::size_t plane = x.plane_size();
  // The kept channels (projected, or the features' own), times the window.
  std::vector<float> windowed(static_cast<std::size_t>(kept_) * plane);
  if (project) {
    mix_rows(projection_.data(), kept_, channels_, x.data.data(), plane, window_.data(),
             windowed.data());
  } else {
    for (int k = 0; k < kept_; ++k) {
      const float* src = &x.data[k * plane];
      float* dst = &windowed[k * plane];
      for (std::size_t i = 0; i < plane; ++i) dst[i] = src[i] * window_[i];
    }
  }
  const std::size_t half = static_cast<std::size_t>(rows_) * fft_->half();
  Spectrum out;
  out.channels = kept_;
  out.rows = rows_;
  out.cols = cols_;
  out.data.resize(half * static_cast<std::size_t>(kept_));
  fft_->forward_half(windowed.data(), kept_, out.data.data());
  return out;
}

void TranslationFilter::learn(const FeatureMap& x, double rate) {
  check(x);
  check_rate(rate);
  if (kept_ < channels_ && projection_.empty()) fit_projection(x);
  learn(transform(x), rate);
}

void TranslationFilter::learn(const Spectrum& s, double rate, double row_shift,
                              double col_shift) {
  check(s);
  check_rate(rate);
  if (!std::isfinite(row_shift) || !std::isfinite(col_shift)) {
    throw std::invalid_argument("TranslationFilter: the shift must be finite");
  }
  if (kept_ < channels_ && projection_.empty()) {
    throw std::logic_error("TranslationFilter: a compressed filter's first learn needs features");
  }
  const float inv_n = 1.0f / static_cast<float>(static_cast<std::size_t>(rows_) * cols_);
  const std::size_t half_cols = static_cast<std::size_t>(cols_ / 2 + 1);
  const std::size_t half = label_f_.size();
  // conj(Y) times the moved sample: Y's conjugate times e^{2 pi i (u a / rows + v b / cols)}
  // (u the signed row frequency), one ramp per axis.
  std::vector<Complex> target(half);
  const bool moved = row_shift != 0.0 || col_shift != 0.0;
  std::vector<Complex> ramp_c(half_cols, Complex(1.0f, 0.0f));
  for (std::size_t v = 0; moved && v < half_cols; ++v) {
    const double phase = 2.0 * kPi * static_cast<double>(v) * col_shift / cols_;
    ramp_c[v] = Complex(static_cast<float>(std::cos(phase)), static_cast<float>(std::sin(phase)));
  }
  for (int u = 0; u < rows_; ++u) {
    const int signed_u = u <= rows_ / 2 ? u : u - rows_;
    const double phase = 2.0 * kPi * signed_u * row_shift / rows_;
    const Complex ramp_r = moved ? Complex(static_cast<float>(std::cos(phase)),
                                           static_cast<float>(std::sin(phase)))
                                 : Complex(1.0f, 0.0f);
    for (std::size_t v = 0; v < half_cols; ++v) {
      const std::size_t i = static_cast<std::size_t>(u) * half_cols + v;
      target[i] = moved ? label_f_[i] * (ramp_r * ramp_c[v]) * inv_n : label_f_[i] * inv_n;
    }
  }
  std::vector<Complex> num(s.data.size());
  std::vector<float> den(half, 0.0f);
  for (int k = 0; k < kept_; ++k) {
    const Complex* xk = &s.data[k * half];
    Complex* nk = &num[k * half];
    for (std::size_t i = 0; i < half; ++i) {
      den[i] += std::norm(xk[i]) * inv_n;
      nk[i] = target[i] * xk[i];
    }
  }
  blend(num_, num, rate, !trained_, den_, den);
  trained_ = true;
}

// A response's confidences around its peak at (pr, pc): the PSR over the values outside the
// peak's (2 exclusion + 1)^2 circular window, and the APCE (peak over mean energy above the
// minimum).
static void set_confidences(const std::vector<float>& v, int rows, int cols, int pr, int pc,
                            int exclusion, TranslationResponse& out) {
  const std::size_t plane = static_cast<std::size_t>(rows) * cols;
  double sum = 0.0, sum2 = 0.0;
  std::size_t count = 0;
  const float lo = *std::min_element(v.begin(), v.end());
  double energy = 0.0;
  // The circular distance from the peak, min((i - p) mod n, (p - i) mod n), without a division
  // per cell (i and p in [0, n): one of the differences is >= 0, the other is its n-complement).
  const auto circular = [](int i, int p, int n) {
    const int d = i >= p ? i - p : p - i;
    return std::min(d, n - d);
  };
  for (int r = 0; r < rows; ++r) {
    const int drr = circular(r, pr, rows);
    for (int c = 0; c < cols; ++c) {
      const double value = v[static_cast<std::size_t>(r) * cols + c];
      energy += (value - lo) * (value - lo);
      const int dcc = circular(c, pc, cols);
      if (drr <= exclusion && dcc <= exclusion) continue;
      sum += value;
      sum2 += value * value;
      ++count;
    }
  }
  if (count >= 2) {
    const double mean = sum / static_cast<double>(count);
    const double var = std::max(0.0, sum2 / static_cast<double>(count) - mean * mean);
    out.psr = var > 0.0 ? (out.peak - mean) / std::sqrt(var) : 0.0;
  }
  energy /= static_cast<double>(plane);
  out.apce = energy > 0.0 ? (out.peak - lo) * (out.peak - lo) / energy : 0.0;
}

TranslationResponse TranslationFilter::respond(const FeatureMap& z, int exclusion) const {
  if (!trained_) throw std::logic_error("TranslationFilter: learn() before respond()");
  return respond(transform(z), exclusion);
}

TranslationResponse TranslationFilter::respond(const Spectrum& zf_in, int exclusion) const {
  if (!trained_) throw std::logic_error("TranslationFilter: learn() before respond()");
  check(zf_in);
  if (exclusion < 0) throw std::invalid_argument("TranslationFilter: exclusion must be >= 0");
  const std::size_t plane = static_cast<std::size_t>(rows_) * cols_;
  const std::vector<Complex>& zf = zf_in.data;
  const std::size_t half = label_f_.size();
  std::vector<Complex> acc(half, Complex(0.0f, 0.0f));
  for (int k = 0; k < kept_; ++k) {
    const Complex* a = &num_[k * half];
    const Complex* zk = &zf[k * half];
    for (std::size_t i = 0; i < half; ++i) acc[i] += std::conj(a[i]) * zk[i];
  }
  const float lambda = static_cast<float>(lambda_);
  for (std::size_t i = 0; i < half; ++i) acc[i] /= den_[i] + lambda;
  TranslationResponse out;
  out.rows = rows_;
  out.cols = cols_;
  out.values.resize(plane);
  fft_->inverse_half_real(acc.data(), out.values.data());

  const auto& v = out.values;
  const std::size_t best =
      static_cast<std::size_t>(std::max_element(v.begin(), v.end()) - v.begin());
  const int pr = static_cast<int>(best / cols_), pc = static_cast<int>(best % cols_);
  const auto at = [&](int r, int c) {
    return static_cast<double>(v[static_cast<std::size_t>((r % rows_ + rows_) % rows_) * cols_ +
                                 (c % cols_ + cols_) % cols_]);
  };
  out.peak = v[best];
  const double dr = rows_ >= 3 ? parabola_offset(at(pr - 1, pc), out.peak, at(pr + 1, pc)) : 0.0;
  const double dc = cols_ >= 3 ? parabola_offset(at(pr, pc - 1), out.peak, at(pr, pc + 1)) : 0.0;
  out.row_shift = (pr > (rows_ - 1) / 2 ? pr - rows_ : pr) + dr;
  out.col_shift = (pc > (cols_ - 1) / 2 ? pc - cols_ : pc) + dc;

  set_confidences(v, rows_, cols_, pr, pc, exclusion, out);
  return out;
}

std::vector<double> response_map(const TranslationResponse& r, double cx, double cy,
                                 double cell_w, double cell_h, int x0, int y0, int x1, int y1) {
  if (x1 <= x0 || y1 <= y0) throw std::invalid_argument("response_map: an empty region");
  if (!(cell_w > 0.0 && cell_h > 0.0)) {
    throw std::invalid_argument("response_map: cells must have a positive size");
  }
  const int rows = r.rows, cols = r.cols, w = x1 - x0, h = y1 - y0;
  const auto wrap = [](long i, int n) { return static_cast<int>(((i % n) + n) % n); };
  // Along the columns for every response row first (the response is far smaller than the
  // region), then along the rows.
  std::vector<int> c0(static_cast<std::size_t>(w)), c1(c0.size());
  std::vector<double> fu(c0.size());
  for (int x = 0; x < w; ++x) {
    const double u = (x0 + x - cx) / cell_w;
    const double f = std::floor(u);
    c0[x] = wrap(static_cast<long>(f), cols);
    c1[x] = wrap(static_cast<long>(f) + 1, cols);
    fu[x] = u - f;
  }
  std::vector<double> across(static_cast<std::size_t>(rows) * w);
  for (int i = 0; i < rows; ++i) {
    const float* row = &r.values[static_cast<std::size_t>(i) * cols];
    double* dst = &across[static_cast<std::size_t>(i) * w];
    for (int x = 0; x < w; ++x) {
      dst[x] = static_cast<double>(row[c0[x]]) * (1.0 - fu[x]) + static_cast<double>(row[c1[x]]) * fu[x];
    }
  }
  const double peak = r.peak;
  std::vector<double> out(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    const double v = (y0 + y - cy) / cell_h;
    const double f = std::floor(v);
    const double fv = v - f;
    const double* a = &across[static_cast<std::size_t>(wrap(static_cast<long>(f), rows)) * w];
    const double* b = &across[static_cast<std::size_t>(wrap(static_cast<long>(f) + 1, rows)) * w];
    double* dst = &out[static_cast<std::size_t>(y) * w];
    for (int x = 0; x < w; ++x) {
      double value = a[x] * (1.0 - fv) + b[x] * fv;
      if (peak > 0.0) value /= peak;
      dst[x] = std::clamp(value, 0.0, 1.0);
    }
  }
  return out;
}

// ------------------------------------------------------------------ scale filter
ScaleFilter::ScaleFilter(int num_scales, int dims, double sigma, double lambda)
    : n_(num_scales), dims_(dims), lambda_(lambda) {
  if (num_scales < 3 || dims < 1) {
    throw std::invalid_argument("ScaleFilter: num_scales must be >= 3 and dims >= 1");
  }
  check_filter_args(sigma, lambda);
  window_ = hann(num_scales);
  std::vector<Complex> label(static_cast<std::size_t>(num_scales));
  const double centre = (num_scales - 1) / 2;
  for (int s = 0; s < num_scales; ++s) {
    label[s] = Complex(static_cast<float>(
        std::exp(-0.5 * (s - centre) * (s - centre) / (sigma * sigma))), 0.0f);
  }
  const int half = num_scales / 2 + 1;
  std::vector<Complex> label_f(label.size());
  Eigen::FFT<float> fft;
  fft.fwd(label_f.data(), label.data(), num_scales);
  label_f_.assign(label_f.begin(), label_f.begin() + half);
  for (auto& v : label_f_) v = std::conj(v);
  dft_re_.resize(static_cast<std::size_t>(half) * num_scales);
  dft_im_.resize(dft_re_.size());
  for (int k = 0; k < half; ++k) {
    for (int s = 0; s < num_scales; ++s) {
      // (k s mod n) keeps the angle small, so that cos and sin stay exact to float
      const double angle = -2.0 * kPi * static_cast<double>((static_cast<long>(k) * s) % num_scales) /
                           num_scales;
      const std::size_t at = static_cast<std::size_t>(k) * num_scales + s;
      dft_re_[at] = static_cast<float>(window_[s] * std::cos(angle));
      dft_im_[at] = static_cast<float>(window_[s] * std::sin(angle));
    }
  }
}

void ScaleFilter::check(const Spectrum& s) const {
  if (s.channels != dims_ || s.rows != 1 || s.cols != n_ ||
      s.data.size() != label_f_.size() * static_cast<std::size_t>(dims_)) {
    throw std::invalid_argument("ScaleFilter: a spectrum of (" + std::to_string(s.channels) + ", " +
                                std::to_string(s.cols) + ") for a filter of (" +
                                std::to_string(dims_) + ", " + std::to_string(n_) + ")");
  }
}

// Bins 0 .. n / 2 of the windowed samples' transform along the scales, per feature
// (dims x (n / 2 + 1)): two matrix products (bins x scales times scales x dims, mix_rows),
// interleaved feature-major.
Spectrum ScaleFilter::transform(const std::vector<float>& samples) const {
  if (samples.size() != static_cast<std::size_t>(n_) * dims_) {
    throw std::invalid_argument("ScaleFilter: " + std::to_string(samples.size()) +
                                " values for " + std::to_string(n_) + " samples of " +
                                std::to_string(dims_) + " features");
  }
  const std::size_t half = label_f_.size(), dims = static_cast<std::size_t>(dims_);
  std::vector<float> re(half * dims), im(half * dims);  // bins x features
  mix_rows(dft_re_.data(), static_cast<int>(half), n_, samples.data(), dims, nullptr, re.data());
  mix_rows(dft_im_.data(), static_cast<int>(half), n_, samples.data(), dims, nullptr, im.data());
  Spectrum out;
  out.channels = dims_;
  out.rows = 1;
  out.cols = n_;
  out.data.resize(half * dims);  // feature-major: feature d's bins at d * half
  for (std::size_t b = 0; b < half; ++b) {
    for (std::size_t d = 0; d < dims; ++d) {
      out.data[d * half + b] = Complex(re[b * dims + d], im[b * dims + d]);
    }
  }
  return out;
}

void ScaleFilter::learn(const std::vector<float>& samples, double rate) {
  check_rate(rate);
  learn(transform(samples), rate);
}

void ScaleFilter::learn(const Spectrum& s, double rate, double shift) {
  check(s);
  check_rate(rate);
  if (!std::isfinite(shift)) throw std::invalid_argument("ScaleFilter: the shift must be finite");
  const std::size_t half = label_f_.size();
  std::vector<Complex> target(label_f_);
  for (std::size_t k = 0; shift != 0.0 && k < half; ++k) {
    const double phase = 2.0 * kPi * static_cast<double>(k) * shift / n_;
    target[k] *= Complex(static_cast<float>(std::cos(phase)), static_cast<float>(std::sin(phase)));
  }
  std::vector<Complex> num(s.data.size());
  std::vector<float> den(half, 0.0f);
  for (int d = 0; d < dims_; ++d) {
    const Complex* xd = &s.data[static_cast<std::size_t>(d) * half];
    Complex* nd = &num[static_cast<std::size_t>(d) * half];
    for (std::size_t k = 0; k < half; ++k) {
      den[k] += std::norm(xd[k]);
      nd[k] = target[k] * xd[k];
    }
  }
  blend(num_, num, rate, !trained_, den_, den);
  trained_ = true;
}

ScaleResponse ScaleFilter::respond(const std::vector<float>& samples) const {
  if (!trained_) throw std::logic_error("ScaleFilter: learn() before respond()");
  return respond(transform(samples));
}

ScaleResponse ScaleFilter::respond(const Spectrum& s) const {
  if (!trained_) throw std::logic_error("ScaleFilter: learn() before respond()");
  check(s);
  const std::vector<Complex>& zf = s.data;
  const std::size_t half = label_f_.size();
  std::vector<Complex> acc(half, Complex(0.0f, 0.0f));
  for (int d = 0; d < dims_; ++d) {
    const Complex* a = &num_[static_cast<std::size_t>(d) * half];
    const Complex* zd = &zf[static_cast<std::size_t>(d) * half];
    for (std::size_t k = 0; k < half; ++k) acc[k] += std::conj(a[k]) * zd[k];
  }
  const float lambda = static_cast<float>(lambda_);
  // The full (Hermitian) spectrum from its first half, then the inverse.
  std::vector<Complex> full(static_cast<std::size_t>(n_)), time(full.size());
  for (std::size_t k = 0; k < half; ++k) full[k] = acc[k] / (den_[k] + lambda);
  for (std::size_t k = half; k < full.size(); ++k) full[k] = std::conj(full[full.size() - k]);
  Eigen::FFT<float> fft;
  fft.inv(time.data(), full.data(), n_);
  ScaleResponse out;
  out.values.resize(static_cast<std::size_t>(n_));
  for (int s = 0; s < n_; ++s) out.values[s] = time[s].real();
  out.best = static_cast<int>(std::max_element(out.values.begin(), out.values.end()) -
                              out.values.begin());
  if (out.best > 0 && out.best < n_ - 1) {
    out.offset = parabola_offset(out.values[out.best - 1], out.values[out.best],
                                 out.values[out.best + 1]);
  }
  return out;
}

// ------------------------------------------------------------------ scale samples
int scale_sample_dims(int model_cols, int model_rows, int cell) {
  if (cell < 1 || model_cols < cell || model_rows < cell) {
    throw std::invalid_argument("the scale model must hold at least one cell");
  }
  return kFhogChannels * (model_rows / cell) * (model_cols / cell);
}

std::vector<float> scale_samples(const ImageView& frame, double cx, double cy, double w,
                                 double h, const std::vector<double>& factors, int model_cols,
                                 int model_rows, int cell) {
  if (factors.empty()) throw std::invalid_argument("scale_samples: no scale factors");
  const int dims = scale_sample_dims(model_cols, model_rows, cell);
  const std::vector<GrayPatch> patches =
      sample_gray_scales(frame, cx, cy, w, h, factors, model_cols, model_rows);
  std::vector<float> out(factors.size() * static_cast<std::size_t>(dims));
  for (std::size_t s = 0; s < patches.size(); ++s) {
    const FeatureMap x = fhog(patches[s], cell);
    std::copy(x.data.begin(), x.data.end(), out.begin() + static_cast<std::ptrdiff_t>(s * dims));
  }
  return out;
}

}  // namespace wmiltrack::cf
