// Discriminative correlation filters (DCF) trained and applied in the Fourier domain:
// a multi-channel translation filter (Staple / DSST style: one filter per feature channel
// sharing the denominator, a Gaussian label, a cosine window) and a 1-D scale filter over a
// pyramid of scale samples (DSST). FFTs are Eigen's (unsupported/Eigen/FFT, kissfft).
//
// Both filters keep the numerator A = conj(Y) X_k and the denominator B = sum_k |X_k|^2
// (divided by the number of samples) as running averages A <- (1 - rate) A + rate A_new,
// and answer a sample Z with the real part of ifft(sum_k conj(A_k) Z_k / (B + lambda)).
// An object is not safe to share between threads without a lock (learn() changes it).
#pragma once

#include <complex>
#include <vector>

#include "wmiltrack/fhog.hpp"

namespace wmiltrack::cf {

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
  // Throws std::invalid_argument for a size below 1, sigma <= 0 or lambda < 0.
  TranslationFilter(int rows, int cols, int channels, double sigma, double lambda);

  int rows() const { return rows_; }
  int cols() const { return cols_; }
  int channels() const { return channels_; }
  bool trained() const { return trained_; }
  // The cosine (Hann) window multiplied into every feature plane, rows x cols.
  const std::vector<float>& window() const { return window_; }
  // The Gaussian label, peak at (0, 0), circular, rows x cols.
  const std::vector<float>& label() const { return label_; }

  // Fold in a sample (the features around the target, centred): the first call (or
  // rate == 1) replaces the model. Throws std::invalid_argument for features of another
  // shape or a rate outside (0, 1].
  void learn(const FeatureMap& x, double rate);

  // The response to a sample; `exclusion`: half-width (cells) of the window around the
  // peak that PSR leaves out. Throws std::logic_error before the first learn(),
  // std::invalid_argument for features of another shape or exclusion < 0.
  TranslationResponse respond(const FeatureMap& z, int exclusion) const;

 private:
  std::vector<std::complex<float>> spectra(const FeatureMap& x) const;
  void check(const FeatureMap& x) const;

  int rows_, cols_, channels_;
  double lambda_;
  bool trained_ = false;
  std::vector<float> window_;
  std::vector<float> label_;
  // Half spectra (columns 0 .. cols / 2; the rest is their Hermitian mirror).
  std::vector<std::complex<float>> label_f_;  // conj(fft2(label)), rows x (cols / 2 + 1)
  std::vector<std::complex<float>> num_;      // channels x rows x (cols / 2 + 1)
  std::vector<float> den_;                    // rows x (cols / 2 + 1)
};

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

 private:
  std::vector<std::complex<float>> spectra(const std::vector<float>& samples) const;

  int n_, dims_;
  double lambda_;
  bool trained_ = false;
  std::vector<float> window_;
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
