// Plain C++ checks of the correlation-filter kernels (fhog.hpp, correlation.hpp); run by
// ctest and scripts/sanitize.sh.
#include <algorithm>
#include <complex>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <random>
#include <utility>
#include <stdexcept>
#include <vector>

#include "wmiltrack/correlation.hpp"
#include "wmiltrack/fhog.hpp"
#include "wmiltrack/vmath.hpp"

#include "../src/batch_fft.hpp"
#include "check.hpp"

namespace {

using namespace wmiltrack;
using namespace wmiltrack::cf;

template <typename F>
bool throws_invalid(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument&) {
    return true;
  }
  return false;
}

// A smooth random texture: white noise box-blurred twice, stretched to 0..255.
std::vector<std::uint8_t> texture(int rows, int cols, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(0.0, 1.0);
  std::vector<double> a(static_cast<std::size_t>(rows) * cols), b(a.size());
  for (auto& v : a) v = d(rng);
  for (int pass = 0; pass < 2; ++pass) {
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        double s = 0.0;
        int n = 0;
        for (int dr = -2; dr <= 2; ++dr) {
          for (int dc = -2; dc <= 2; ++dc) {
            const int rr = r + dr, cc = c + dc;
            if (rr < 0 || rr >= rows || cc < 0 || cc >= cols) continue;
            s += a[static_cast<std::size_t>(rr) * cols + cc];
            ++n;
          }
        }
        b[static_cast<std::size_t>(r) * cols + c] = s / n;
      }
    }
    a.swap(b);
  }
  const auto [lo, hi] = std::minmax_element(a.begin(), a.end());
  std::vector<std::uint8_t> out(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    out[i] = static_cast<std::uint8_t>(std::lround(255.0 * (a[i] - *lo) / (*hi - *lo)));
  }
  return out;
}

ImageView gray_view(const std::vector<std::uint8_t>& px, int rows, int cols) {
  ImageView v;
  v.data = px.data();
  v.rows = rows;
  v.cols = cols;
  v.channels = 1;
  v.row_stride = cols;
  return v;
}

void test_sample_gray() {
  const int rows = 40, cols = 50;
  const auto px = texture(rows, cols, 1);
  const ImageView v = gray_view(px, rows, cols);
  // A 1:1 region on whole pixels is the frame itself.
  const GrayPatch p = sample_gray(v, 25.0, 20.0, 20.0, 10.0, 20, 10);
  bool same = true;
  for (int r = 0; r < 10; ++r) {
    for (int c = 0; c < 20; ++c) {
      same = same && std::abs(p.pixels[r * 20 + c] * 255.0f - px[(15 + r) * cols + 15 + c]) < 1e-3f;
    }
  }
  CHECK(same);
  // Outside the frame: the edge pixel.
  const GrayPatch corner = sample_gray(v, -10.0, -10.0, 2.0, 2.0, 2, 2);
  for (float value : corner.pixels) CHECK(std::abs(value * 255.0f - px[0]) < 1e-3f);
  // Shrinking by 2 averages: a constant frame stays constant.
  const std::vector<std::uint8_t> flat(static_cast<std::size_t>(rows) * cols, 100);
  const GrayPatch half = sample_gray(gray_view(flat, rows, cols), 25.0, 20.0, 40.0, 40.0, 20, 20);
  for (float value : half.pixels) CHECK(std::abs(value - 100.0f / 255.0f) < 1e-5f);
  // Shrinking by 4 and more reads a lattice of pixels (every 2nd, 3rd, ...): a constant frame
  // still stays constant.
  const GrayPatch sparse = sample_gray(gray_view(flat, rows, cols), 25.0, 20.0, 45.0, 36.0, 5, 4);
  for (float value : sparse.pixels) CHECK(std::abs(value - 100.0f / 255.0f) < 1e-5f);
  // Several scales at once: each the same as its own sample_gray while every one reads every
  // pixel (an output pixel under 4 frame pixels)...
  const std::vector<double> factors = {0.5, 1.0, 1.7};
  const std::vector<GrayPatch> scales = sample_gray_scales(v, 12.3, 30.8, 14.0, 9.0, factors, 7, 5);
  CHECK(scales.size() == factors.size());
  for (std::size_t i = 0; i < factors.size(); ++i) {
    const GrayPatch one = sample_gray(v, 12.3, 30.8, 14.0 * factors[i], 9.0 * factors[i], 7, 5);
    CHECK(scales[i].pixels == one.pixels);
  }
  // ... and on the lattice of the smallest factor otherwise: the smallest is its own
  // sample_gray (every 4th pixel across, every 3rd down here), the larger reads it more densely
  // than its own would (every 5th across) and differs from it.
  const std::vector<GrayPatch> wide = sample_gray_scales(v, 25.0, 20.0, 14.0, 9.0, {4.0, 5.0}, 7, 5);
  CHECK(wide[0].pixels == sample_gray(v, 25.0, 20.0, 56.0, 36.0, 7, 5).pixels);
  CHECK(wide[1].pixels != sample_gray(v, 25.0, 20.0, 70.0, 45.0, 7, 5).pixels);
  CHECK(throws_invalid([&] { sample_gray_scales(v, 0.0, 0.0, 5.0, 5.0, {1.0, -1.0}, 5, 5); }));
  CHECK(throws_invalid([&] { sample_gray(v, 0.0, 0.0, 0.0, 10.0, 5, 5); }));
  CHECK(throws_invalid([&] { sample_gray(v, NAN, 0.0, 10.0, 10.0, 5, 5); }));
  CHECK(throws_invalid([&] { sample_gray(v, 0.0, 0.0, 10.0, 10.0, 0, 5); }));
}

void test_fhog() {
  const int rows = 40, cols = 48;
  const auto px = texture(rows, cols, 2);
  const GrayPatch p = sample_gray(gray_view(px, rows, cols), 24.0, 20.0, 48.0, 40.0, 48, 40);
  const FeatureMap x = fhog(p, 4);
  CHECK(x.channels == kFhogChannels && x.rows == 10 && x.cols == 12);
  CHECK(x.data.size() == static_cast<std::size_t>(31 * 10 * 12));
  bool bounded = true;
  for (float v : x.data) bounded = bounded && v >= 0.0f && v <= 0.4f + 1e-6f;
  CHECK(bounded);  // each value sums four truncated (<= 0.2) terms, times 0.5 (or 0.2357)
  // Block normalisation: halving the contrast changes the features very little.
  GrayPatch dim = p;
  for (auto& v : dim.pixels) v = 0.5f * v + 0.25f;
  const FeatureMap y = fhog(dim, 4);
  double diff = 0.0, norm = 0.0;
  for (std::size_t i = 0; i < x.data.size(); ++i) {
    diff += std::abs(x.data[i] - y.data[i]);
    norm += std::abs(x.data[i]);
  }
  CHECK(diff < 0.01 * norm);
  // A flat patch has no gradient: all zero.
  GrayPatch flat{8, 8, std::vector<float>(64, 0.3f)};
  const FeatureMap z = fhog(flat, 4);
  CHECK(std::all_of(z.data.begin(), z.data.end(), [](float v) { return v == 0.0f; }));
  CHECK(throws_invalid([&] { fhog(flat, 0); }));
  CHECK(throws_invalid([&] { fhog(flat, 9); }));
}

// The patches and fHOG on awkward sizes (1 pixel wide or high, output rows not a multiple of
// the resampling's 4-row blocks, sides not whole cells, cells 1 .. 8, a colour frame), each
// computed on the AVX2 copies and on the portable ones: the same bits (and, under the
// sanitizers, no read or write outside the buffers).
void test_fhog_paths() {
  const int rows = 61, cols = 83;
  const auto gray = texture(rows, cols, 7);
  std::vector<std::uint8_t> bgr(gray.size() * 3);
  for (std::size_t i = 0; i < gray.size(); ++i) {
    bgr[3 * i] = gray[i];
    bgr[3 * i + 1] = static_cast<std::uint8_t>(255 - gray[i]);
    bgr[3 * i + 2] = static_cast<std::uint8_t>(gray[i] / 2 + 60);
  }
  ImageView colour = gray_view(bgr, rows, cols);
  colour.channels = 3;
  colour.col_stride = 3;
  colour.row_stride = static_cast<std::ptrdiff_t>(cols) * 3;
  struct Case {
    double cx, cy, w, h;
    int out_cols, out_rows;
  };
  const Case cases[] = {{41.0, 30.0, 50.0, 40.0, 1, 1},   {41.0, 30.0, 50.0, 40.0, 1, 9},
                        {41.0, 30.0, 50.0, 40.0, 9, 1},   {20.3, 17.8, 23.0, 19.0, 37, 23},
                        {2.0, 60.0, 140.0, 90.0, 29, 18}, {41.0, 30.0, 300.0, 250.0, 64, 51},
                        {70.5, 5.5, 12.0, 9.0, 40, 30}};
  for (const ImageView& v : {gray_view(gray, rows, cols), colour}) {
    for (const Case& c : cases) {
      const GrayPatch native = sample_gray(v, c.cx, c.cy, c.w, c.h, c.out_cols, c.out_rows);
      vmath::force_portable(true);
      const GrayPatch portable = sample_gray(v, c.cx, c.cy, c.w, c.h, c.out_cols, c.out_rows);
      vmath::force_portable(false);
      CHECK(native.rows == c.out_rows && native.cols == c.out_cols);
      CHECK(native.pixels == portable.pixels);
      for (int cell = 1; cell <= 8; ++cell) {
        if (native.rows < cell || native.cols < cell) continue;
        const FeatureMap a = fhog(native, cell);
        vmath::force_portable(true);
        const FeatureMap b = fhog(native, cell);
        vmath::force_portable(false);
        CHECK(a.rows == native.rows / cell && a.cols == native.cols / cell);
        CHECK(a.data == b.data);
        // Planes 0-26 sum four clipped (<= 0.2) terms times 0.5; planes 27-30 eighteen, times
        // 0.2357.
        const std::size_t texture = static_cast<std::size_t>(27) * a.plane_size();
        CHECK(std::all_of(a.data.begin(), a.data.begin() + texture,
                          [](float x) { return x >= 0.0f && x <= 0.4f + 1e-6f; }));
        CHECK(std::all_of(a.data.begin() + texture, a.data.end(),
                          [](float x) { return x >= 0.0f && x <= 0.2357f * 18 * 0.2f + 1e-6f; }));
      }
    }
  }
}

// Circularly shifted copy of a feature map: value at (r, c) moves to (r + dr, c + dc).
FeatureMap roll(const FeatureMap& x, int dr, int dc) {
  FeatureMap y = x;
  for (int k = 0; k < x.channels; ++k) {
    for (int r = 0; r < x.rows; ++r) {
      for (int c = 0; c < x.cols; ++c) {
        const int rr = ((r + dr) % x.rows + x.rows) % x.rows;
        const int cc = ((c + dc) % x.cols + x.cols) % x.cols;
        y.data[(k * x.rows + rr) * x.cols + cc] = x.data[(k * x.rows + r) * x.cols + c];
      }
    }
  }
  return y;
}

void test_translation_filter() {
  const int rows = 30, cols = 36;
  const auto px = texture(rows * 4, cols * 4, 3);
  const GrayPatch p = sample_gray(gray_view(px, rows * 4, cols * 4), cols * 2.0, rows * 2.0,
                                  cols * 4.0, rows * 4.0, cols * 4, rows * 4);
  const FeatureMap x = fhog(p, 4);
  TranslationFilter f(rows, cols, kFhogChannels, 1.5, 1e-3);
  CHECK(!f.trained());
  bool logic = false;
  try {
    f.respond(x, 5);
  } catch (const std::logic_error&) {
    logic = true;
  }
  CHECK(logic);
  f.learn(x, 1.0);
  CHECK(f.trained());
  const TranslationResponse same = f.respond(x, 5);
  CHECK(std::abs(same.row_shift) < 0.05 && std::abs(same.col_shift) < 0.05);
  CHECK(same.psr > 20.0);
  // Shifted content: the peak moves with it (away from the window's edge, a small shift).
  const TranslationResponse moved = f.respond(roll(x, 2, -3), 5);
  CHECK(std::abs(moved.row_shift - 2.0) < 0.5 && std::abs(moved.col_shift + 3.0) < 0.5);
  // Unrelated features: a flat response, low PSR.
  const auto other = texture(rows * 4, cols * 4, 99);
  const FeatureMap noise = fhog(sample_gray(gray_view(other, rows * 4, cols * 4), cols * 2.0,
                                            rows * 2.0, cols * 4.0, rows * 4.0, cols * 4, rows * 4),
                                4);
  CHECK(f.respond(noise, 5).psr < 0.5 * same.psr);
  CHECK(throws_invalid([&] { f.learn(x, 0.0); }));
  CHECK(throws_invalid([&] { f.learn(x, 1.5); }));
  CHECK(throws_invalid([&] { f.respond(roll(fhog(GrayPatch{8, 8, std::vector<float>(64)}, 4), 0, 0), 5); }));
  CHECK(throws_invalid([&] { f.respond(x, -1); }));
  CHECK(throws_invalid([&] { TranslationFilter(0, 4, 1, 1.0, 0.0); }));
  CHECK(throws_invalid([&] { TranslationFilter(4, 4, 1, 0.0, 0.0); }));
  CHECK(throws_invalid([&] { TranslationFilter(4, 4, 1, 1.0, -1.0); }));
}

void test_scale_filter() {
  const int rows = 200, cols = 200;
  const auto px = texture(rows, cols, 4);
  const ImageView v = gray_view(px, rows, cols);
  std::vector<double> factors;
  for (int k = -16; k <= 16; ++k) factors.push_back(std::pow(1.02, k));
  const int dims = scale_sample_dims(32, 16, 4);
  CHECK(dims == 31 * 4 * 8);
  const std::vector<float> s = scale_samples(v, 100.0, 100.0, 64.0, 32.0, factors, 32, 16, 4);
  CHECK(s.size() == factors.size() * static_cast<std::size_t>(dims));
  ScaleFilter f(33, dims, std::sqrt(33.0) / 4.0, 1e-3);
  f.learn(s, 1.0);
  const ScaleResponse same = f.respond(s);
  CHECK(same.best == 16);
  // The target grew by 1.02^3: the sample that now looks like the learnt one is 3 further.
  const std::vector<float> grown =
      scale_samples(v, 100.0, 100.0, 64.0 / std::pow(1.02, 3), 32.0 / std::pow(1.02, 3), factors,
                    32, 16, 4);
  CHECK(std::abs(f.respond(grown).best - 19) <= 1);
  CHECK(throws_invalid([&] { scale_samples(v, 100.0, 100.0, 64.0, 32.0, {}, 32, 16, 4); }));
  CHECK(throws_invalid([&] { scale_samples(v, 100.0, 100.0, 64.0, 32.0, {0.0}, 32, 16, 4); }));
  CHECK(throws_invalid([&] { f.respond(std::vector<float>(5)); }));
  CHECK(throws_invalid([&] { ScaleFilter(2, 4, 1.0, 0.0); }));
}

// The 2-D transforms as they were before the batched ones (one Eigen::FFT call per row and
// per column): the batched transforms must give the same bits.
using Complex = std::complex<float>;
class EigenFft2 {
 public:
  EigenFft2(int rows, int cols)
      : rows_(rows), cols_(cols), half_(cols / 2 + 1), col_in_(static_cast<std::size_t>(rows)),
        col_out_(static_cast<std::size_t>(rows)), row_buf_(static_cast<std::size_t>(cols)),
        full_(static_cast<std::size_t>(rows) * cols) {
    half_fft_.SetFlag(Eigen::FFT<float>::HalfSpectrum);
  }

  int half() const { return half_; }

  // Columns 0 .. cols / 2 of numpy's fft2 of a real plane (rows x half()).
  void forward_half(const float* in, Complex* out) {
    for (int r = 0; r < rows_; ++r) {
      half_fft_.fwd(out + static_cast<std::size_t>(r) * half_,
                    in + static_cast<std::size_t>(r) * cols_, cols_);
    }
    columns(out, half_, false);
  }

  // numpy's real(ifft2(X)) of the Hermitian spectrum X whose half spectrum is `in`.
  void inverse_half_real(const Complex* in, float* out) {
    for (int r = 0; r < rows_; ++r) {
      Complex* row = &full_[static_cast<std::size_t>(r) * cols_];
      const Complex* mirror = in + static_cast<std::size_t>((rows_ - r) % rows_) * half_;
      std::copy(in + static_cast<std::size_t>(r) * half_,
                in + static_cast<std::size_t>(r) * half_ + half_, row);
      for (int c = half_; c < cols_; ++c) row[c] = std::conj(mirror[cols_ - c]);
    }
    columns(full_.data(), cols_, true);
    for (int r = 0; r < rows_; ++r) {
      fft_.inv(row_buf_.data(), &full_[static_cast<std::size_t>(r) * cols_], cols_);
      for (int c = 0; c < cols_; ++c) out[static_cast<std::size_t>(r) * cols_ + c] = row_buf_[c].real();
    }
  }

 private:
  // 1-D transforms down each of the first `width` columns of a rows x width array.
  void columns(Complex* data, int width, bool inverse) {
    for (int c = 0; c < width; ++c) {
      for (int r = 0; r < rows_; ++r) col_in_[r] = data[static_cast<std::size_t>(r) * width + c];
      if (inverse) {
        fft_.inv(col_out_.data(), col_in_.data(), rows_);
      } else {
        fft_.fwd(col_out_.data(), col_in_.data(), rows_);
      }
      for (int r = 0; r < rows_; ++r) data[static_cast<std::size_t>(r) * width + c] = col_out_[r];
    }
  }

  int rows_, cols_, half_;
  Eigen::FFT<float> fft_, half_fft_;
  std::vector<Complex> col_in_, col_out_, row_buf_, full_;
};

// One complex batch transform of n points (lanes at once) against one Eigen call per lane.
bool complex_batch_matches(int n, const std::vector<float>& re, const std::vector<float>& im,
                           std::size_t lanes, bool inverse) {
  const detail::BatchFft plan(n, inverse);
  std::vector<float> ore(re.size()), oim(re.size()), work(plan.scratch_size(lanes) + 1);
  plan.run(detail::ConstLanes{re.data(), im.data(), lanes},
           detail::Lanes{ore.data(), oim.data(), lanes}, lanes, work.data());
  Eigen::FFT<float> fft;
  fft.SetFlag(Eigen::FFT<float>::Unscaled);
  bool same = true;
  for (std::size_t b = 0; b < lanes; ++b) {
    std::vector<Complex> x(n), y(n);
    for (int i = 0; i < n; ++i) x[i] = Complex(re[i * lanes + b], im[i * lanes + b]);
    if (inverse) {
      fft.inv(y.data(), x.data(), n);
    } else {
      fft.fwd(y.data(), x.data(), n);
    }
    for (int i = 0; i < n; ++i) {
      same = same && y[i].real() == ore[i * lanes + b] && y[i].imag() == oim[i * lanes + b];
    }
  }
  return same;
}

// One real batch transform of n points (its half spectrum) against Eigen's, lane by lane.
bool real_batch_matches(int n, const std::vector<float>& re, std::size_t lanes) {
  const detail::BatchRealFft real(n);
  const std::size_t h = static_cast<std::size_t>(real.half());
  std::vector<float> ore(h * lanes), oim(h * lanes), work(real.scratch_size(lanes) + 1);
  real.run(re.data(), lanes, detail::Lanes{ore.data(), oim.data(), lanes}, lanes, work.data());
  Eigen::FFT<float> fft;
  fft.SetFlag(Eigen::FFT<float>::HalfSpectrum);
  bool same = true;
  for (std::size_t b = 0; b < lanes; ++b) {
    std::vector<float> x(n);
    std::vector<Complex> y(h);
    for (int i = 0; i < n; ++i) x[i] = re[i * lanes + b];
    fft.fwd(y.data(), x.data(), n);
    for (std::size_t i = 0; i < h; ++i) {
      same = same && y[i].real() == ore[i * lanes + b] && y[i].imag() == oim[i * lanes + b];
    }
  }
  return same;
}

void test_batch_fft_2d(std::mt19937& rng, std::normal_distribution<float>& g) {
  // 2-D, several planes at once, against one Eigen call per row and column.
  for (auto [rows, cols] : {std::pair{36, 45}, std::pair{45, 36}, std::pair{4, 4},
                            std::pair{5, 7}, std::pair{30, 32}, std::pair{24, 50}}) {
    const int planes = 3;
    const std::size_t plane = static_cast<std::size_t>(rows) * cols;
    std::vector<float> x(plane * planes);
    for (auto& v : x) v = g(rng);
    const detail::Fft2 fft(rows, cols);
    const std::size_t half = static_cast<std::size_t>(rows) * fft.half();
    std::vector<Complex> got(half * planes), want(half * planes);
    fft.forward_half(x.data(), planes, got.data());
    EigenFft2 ref(rows, cols);
    for (int p = 0; p < planes; ++p) ref.forward_half(&x[p * plane], &want[p * half]);
    CHECK(got == want);
    std::vector<float> back(plane), back_ref(plane);
    fft.inverse_half_real(got.data(), back.data());
    ref.inverse_half_real(got.data(), back_ref.data());
    CHECK(back == back_ref);
  }
}

void test_batch_fft() {
  std::mt19937 rng(7);
  std::normal_distribution<float> g(0.0f, 1.0f);
  // 1-D, every radix path (4, 2, 3, 5 and the generic one: 7, 11), forward and inverse,
  // complex and real inputs, several lanes at once.
  for (int n : {2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 14, 15, 16, 18, 20, 24, 25, 27, 30, 32,
                36, 40, 45, 48, 49, 50, 60, 64, 75, 77}) {
    const std::size_t lanes = 5;
    std::vector<float> re(n * lanes), im(n * lanes);
    for (auto& v : re) v = g(rng);
    for (auto& v : im) v = g(rng);
    for (bool inverse : {false, true}) CHECK(complex_batch_matches(n, re, im, lanes, inverse));
    CHECK(real_batch_matches(n, re, lanes));
  }
  test_batch_fft_2d(rng, g);
}

}  // namespace

int main() {
  test_sample_gray();
  test_fhog();
  test_fhog_paths();
  test_translation_filter();
  test_scale_filter();
  test_batch_fft();  // the AVX2 copy where the CPU has it
  vmath::force_portable(true);
  test_batch_fft();  // the baseline copy
  vmath::force_portable(false);
  if (wmiltrack_test::failures) {
    std::fprintf(stderr, "%d check(s) failed\n", wmiltrack_test::failures);
    return 1;
  }
  std::puts("test_cf: all checks passed");
  return 0;
}
