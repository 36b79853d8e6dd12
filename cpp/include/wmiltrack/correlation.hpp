// Discriminative correlation filters (DCF) trained and applied in the Fourier domain:
// a multi-channel translation filter (Staple / DSST style: one filter per feature channel
// sharing the denominator, a Gaussian label, a cosine window) and a 1-D scale filter over a
// pyramid of scale samples (DSST). FFTs are Eigen's kissfft (unsupported/Eigen/FFT); the
// translation filter's 2-D ones run it batched (cpp/src/batch_fft.hpp: every row, then every
// column, of every plane at once, with kissfft's own arithmetic, so the same bits).
//
// Both filters keep the numerator A = conj(Y) X_k and the denominator B = sum_k |X_k|^2
// (divided by the number of samples) as running averages A <- (1 - rate) A + rate A_new,
// and answer a sample Z with the real part of ifft(sum_k conj(A_k) Z_k / (B + lambda)).
// An object is not safe to share between threads without a lock (learn() changes it).
#pragma once

#include <complex>
#include <memory>
#include <vector>

#include "wmiltrack/fhog.hpp"

namespace wmiltrack::cf {

namespace detail {
class Fft2;  // batched 2-D transforms (cpp/src/batch_fft.hpp)
}  // namespace detail

// A sample as a translation filter takes it: its features (projected onto the filter's
// compressed channels, if it has any) times the cosine window, as half spectra (channels x
// rows x (cols / 2 + 1)). Made by TranslationFilter::transform; a filter can answer it and
// later learn from it, so that a frame's search and its learning share one transform.
struct Spectrum {
  int channels = 0;
  int rows = 0;
  int cols = 0;
  std::vector<std::complex<float>> data;
};

// A translation filter's answer to one sample.
struct TranslationResponse {
  int rows = 0;
  int cols = 0;
  // Response per circular shift: values[r * cols + c] is the score of the content having
  // moved by (r, c) cells (r, c taken modulo rows, cols); (0, 0) is no motion.
  std::vector<float> values;
  double row_shift = 0.0;  // the peak's shift in cells, in [-rows/2, rows/2), sub-cell
  double col_shift = 0.0;  //   (a parabola through the peak and its two neighbours)
  double peak = 0.0;       // the largest value
  double psr = 0.0;        // (peak - mean) / std of the values outside the peak's window
  double apce = 0.0;       // (max - min)^2 / mean((value - min)^2)
};

class TranslationFilter {
 public:
  // A filter over rows x cols cells of `channels` features; sigma: the Gaussian label's
  // standard deviation in cells; lambda: the regularisation added to the denominator.
  // compressed in 1 .. channels - 1: the features are projected onto that many channels
  // (ECO's compression), the principal axes of the first learnt sample's cells (their
  // second moments), fixed from then on; 0 (or >= channels): no projection.
  // Throws std::invalid_argument for a size below 1, sigma <= 0, lambda < 0 or
  // compressed < 0.
  TranslationFilter(int rows, int cols, int channels, double sigma, double lambda,
                    int compressed = 0);

  int rows() const { return rows_; }
  int cols() const { return cols_; }
  int channels() const { return channels_; }
  // Channels of the filter itself (compressed, or channels without a projection).
  int filter_channels() const { return kept_; }
  bool trained() const { return trained_; }
  // The projection, kept x channels row-major (empty without one or before the first learn).
  const std::vector<float>& projection() const { return projection_; }
  // The cosine (Hann) window multiplied into every feature plane, rows x cols.
  const std::vector<float>& window() const { return window_; }
  // The Gaussian label, peak at (0, 0), circular, rows x cols.
  const std::vector<float>& label() const { return label_; }

  // Fold in a sample (the features around the target, centred): the first call (or
  // rate == 1) replaces the model. Throws std::invalid_argument for features of another
  // shape or a rate outside (0, 1].
  // The first call also fits the projection of a compressed filter.
  void learn(const FeatureMap& x, double rate);

  // The sample as this filter takes it. Throws std::invalid_argument for features of another
  // shape, std::logic_error for a compressed filter before its first learn().
  Spectrum transform(const FeatureMap& x) const;

  // Fold in a transformed sample whose target sits (row_shift, col_shift) cells (sub-cell)
  // from the sample's centre: the sample is first moved circularly by minus that shift (a
  // phase ramp on its spectrum, as ECO trains on its search sample), so that the target is
  // centred. Throws std::invalid_argument for a spectrum of another filter's shape, a rate
  // outside (0, 1] or a shift that is not finite; std::logic_error for a compressed filter's
  // first learn (which needs the features).
  void learn(const Spectrum& s, double rate, double row_shift = 0.0, double col_shift = 0.0);

  // The response to a sample; `exclusion`: half-width (cells) of the window around the
  // peak that PSR leaves out. Throws std::logic_error before the first learn(),
  // std::invalid_argument for features of another shape or exclusion < 0.
  TranslationResponse respond(const FeatureMap& z, int exclusion) const;
  TranslationResponse respond(const Spectrum& z, int exclusion) const;

 private:
  void check(const FeatureMap& x) const;
  void check(const Spectrum& s) const;
  void fit_projection(const FeatureMap& x);

  int rows_, cols_, channels_, kept_;
  double lambda_;
  bool trained_ = false;
  std::vector<float> projection_;             // kept_ x channels_, row-major
  std::vector<float> window_;
  std::vector<float> label_;
  // The plans of the 2-D transforms of this grid, built once (immutable: shared by copies and
  // safe to use from several threads at once).
  std::shared_ptr<const detail::Fft2> fft_;
  // Half spectra (columns 0 .. cols / 2; the rest is their Hermitian mirror).
  std::vector<std::complex<float>> label_f_;  // conj(fft2(label)), rows x (cols / 2 + 1)
  std::vector<std::complex<float>> num_;      // kept x rows x (cols / 2 + 1)
  std::vector<float> den_;                    // rows x (cols / 2 + 1)
};

// A response's values at every pixel of the frame region [x0, x1) x [y0, y1) taken as the
// target's centre, for a search centred at (cx, cy) with cells of cell_w x cell_h frame
// pixels: bilinear between the response's cells (the response wraps around), divided by its
// peak when the peak is positive, clipped to [0, 1]; (y1 - y0) x (x1 - x0) values, row-major.
// Throws std::invalid_argument for an empty region or cells that are not positive.
std::vector<double> response_map(const TranslationResponse& r, double cx, double cy,
                                 double cell_w, double cell_h, int x0, int y0, int x1, int y1);

// A scale filter's answer to one set of scale samples.
struct ScaleResponse {
  std::vector<float> values;  // one per scale sample
  int best = 0;               // index of the largest value
  double offset = 0.0;        // sub-index refinement of best in [-0.5, 0.5] (parabola;
                              // 0 at the ends)
};

class ScaleFilter {
 public:
  // A filter over num_scales samples of `dims` features each; the label is a Gaussian of
  // standard deviation sigma (in samples) peaked on sample (num_scales - 1) / 2, the one
  // at the current scale. Throws std::invalid_argument for num_scales < 3, dims < 1,
  // sigma <= 0 or lambda < 0.
  ScaleFilter(int num_scales, int dims, double sigma, double lambda);

  int num_scales() const { return n_; }
  int dims() const { return dims_; }
  bool trained() const { return trained_; }
  const std::vector<float>& window() const { return window_; }

  // samples: num_scales x dims, row-major (sample s's features in row s). The Hann window
  // over the scales is applied here. Same rules as TranslationFilter::learn.
  void learn(const std::vector<float>& samples, double rate);
  ScaleResponse respond(const std::vector<float>& samples) const;

  // The samples as this filter takes them (windowed, bins 0 .. n / 2 of their transform along
  // the scales: channels = dims, rows = 1, cols = num_scales), so that a frame's estimate and
  // its learning share one transform. Throws std::invalid_argument for samples of another
  // shape.
  Spectrum transform(const std::vector<float>& samples) const;
  // Fold in transformed samples whose target size sits `shift` samples (sub-sample) from the
  // middle one: the label is moved there (a phase ramp), as if the samples had been taken
  // around that size. Throws std::invalid_argument for a spectrum of another shape, a rate
  // outside (0, 1] or a shift that is not finite.
  void learn(const Spectrum& s, double rate, double shift = 0.0);
  ScaleResponse respond(const Spectrum& s) const;

 private:
  void check(const Spectrum& s) const;

  int n_, dims_;
  double lambda_;
  bool trained_ = false;
  std::vector<float> window_;
  // The windowed transform along the scales as two matrices (bins x scales, row-major): the
  // real and imaginary parts of w[s] e^{-2 pi i k s / n}. For 33 scales a matrix product over
  // all features costs less than one small FFT per feature.
  std::vector<float> dft_re_, dft_im_;
  // Half spectra (bins 0 .. n / 2; the rest is their Hermitian mirror).
  std::vector<std::complex<float>> label_f_;  // conj(fft(label)), n / 2 + 1
  std::vector<std::complex<float>> num_;      // dims x (n / 2 + 1)
  std::vector<float> den_;                    // n / 2 + 1
};

// Scale samples around (cx, cy): for each factor f, the region of size (w f) x (h f) is
// resampled to model_cols x model_rows (sample_gray) and described by fhog(cell), its
// values flattened into one row of the result (factors.size() rows, as ScaleFilter takes).
// Throws std::invalid_argument for no factors, a non-positive factor, or the errors of
// sample_gray and fhog.
std::vector<float> scale_samples(const ImageView& frame, double cx, double cy, double w,
                                 double h, const std::vector<double>& factors, int model_cols,
                                 int model_rows, int cell);

// Features per scale sample of scale_samples: kFhogChannels * (model_rows / cell) *
// (model_cols / cell).
int scale_sample_dims(int model_cols, int model_rows, int cell);

}  // namespace wmiltrack::cf
