// Internal to the core: Eigen's kissfft (unsupported/Eigen/src/FFT/ei_kissfft_impl.h) run on
// many 1-D transforms of the same length at once, for the translation filter's 2-D transforms.
//
// Why: a 2-D transform of a template plane is rows + columns small 1-D transforms; Eigen runs
// them one by one, each a recursion of scalar complex butterflies (and the columns through a
// gather and a scatter). Here the transforms are "lanes" of one batch: element i of every
// transform sits in a contiguous run (element-major, split real and imaginary parts: lane b of
// element i at re[i * stride + b]), so every butterfly is a loop over the lanes that the
// compiler vectorises.
//
// The arithmetic is kissfft's own, operation for operation (the same factorisation, the same
// twiddles: they come from Eigen's own plan object; the same products and sums in the same
// order; complex products as GCC expands them without -ffast-math: re = ar br - ai bi,
// im = ar bi + ai br; no FMA since the core is built with -ffp-contract=off), so each lane
// gives the bits Eigen::FFT<float> gives for that transform alone (tests/test_cf.cpp checks
// it against Eigen). IEEE sums and products do not depend on the vector width, so every SIMD
// path gives the same bits too.
#pragma once

#include <algorithm>
#include <complex>
#include <cstddef>
#include <cstring>
#include <vector>

#include <unsupported/Eigen/FFT>

#include "wmiltrack/vmath.hpp"

#if defined(__SSE2__) && !defined(WMILTRACK_NO_SIMD)
#include <xmmintrin.h>
#define WMILTRACK_TRANSPOSE_SSE 1
#endif

namespace wmiltrack::cf::detail {

// Split-complex lanes: element i of lane b is (re[i * stride + b], im[i * stride + b]).
struct Lanes {
  float* re;
  float* im;
  std::size_t stride;  // floats from one element to the next
};
struct ConstLanes {
  const float* re;
  const float* im;  // nullptr: a real input (imaginary parts 0)
  std::size_t stride;
};

// dst[c * dst_stride + r] = src[r * src_stride + c] for r < rows, c < cols: a matrix
// transposed (only moves, so the same bits on every path), 4 x 4 blocks at a time where SSE is
// there.
inline void transpose(const float* src, std::size_t src_stride, std::size_t rows,
                      std::size_t cols, float* dst, std::size_t dst_stride) {
  std::size_t r = 0;
#ifdef WMILTRACK_TRANSPOSE_SSE
  for (; r + 4 <= rows; r += 4) {
    const float* s0 = src + r * src_stride;
    const float* s1 = s0 + src_stride;
    const float* s2 = s1 + src_stride;
    const float* s3 = s2 + src_stride;
    std::size_t c = 0;
    for (; c + 4 <= cols; c += 4) {
      __m128 a = _mm_loadu_ps(s0 + c), b = _mm_loadu_ps(s1 + c), e = _mm_loadu_ps(s2 + c),
             f = _mm_loadu_ps(s3 + c);
      _MM_TRANSPOSE4_PS(a, b, e, f);
      float* d = dst + c * dst_stride + r;
      _mm_storeu_ps(d, a);
      _mm_storeu_ps(d + dst_stride, b);
      _mm_storeu_ps(d + 2 * dst_stride, e);
      _mm_storeu_ps(d + 3 * dst_stride, f);
    }
    for (; c < cols; ++c) {
      float* d = dst + c * dst_stride + r;
      d[0] = s0[c];
      d[1] = s1[c];
      d[2] = s2[c];
      d[3] = s3[c];
    }
  }
#endif
  for (; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) dst[c * dst_stride + r] = src[r * src_stride + c];
  }
}

// Before a loop over the lanes of a butterfly: its iterations are independent (lane b reads and
// writes lane b of elements that never overlap: their stride is at least the lane count), which
// the compiler cannot prove for a butterfly's 6 to 10 pointers into one buffer; without the
// pragma it does not vectorise the radix-3, -4 and -5 butterflies at all.
#if defined(__clang__)
#define WMILTRACK_LANES_LOOP _Pragma("clang loop vectorize(assume_safety)")
#elif defined(__GNUC__)
#define WMILTRACK_LANES_LOOP _Pragma("GCC ivdep")
#else
#define WMILTRACK_LANES_LOOP
#endif

// One complex transform length and direction: kissfft's plan (kiss_cpx_fft: twiddles, radices),
// and where kissfft's recursion reads each input element. Immutable once built, so one plan
// serves any number of threads.
struct FftPlan {
  int n = 0;
  bool inverse = false;
  int max_radix = 0;
  std::vector<float> tw_re, tw_im;
  std::vector<int> radix, remainder;  // per stage (kiss_cpx_fft's m_stageRadix, ...Remainder)
  std::vector<std::size_t> fstride;   // per stage: the product of the radices before it
  std::vector<std::size_t> perm;      // output position -> input element of the first copy
};

// The butterflies of kiss_cpx_fft, on lanes (f: the p m elements of one sub-transform).
WMILTRACK_KERNEL void fft_bfly2(const FftPlan& plan, Lanes f, std::size_t fstride, int m,
                                std::size_t lanes) {
  const float* tw_re = plan.tw_re.data();
  const float* tw_im = plan.tw_im.data();
  for (int k = 0; k < m; ++k) {
    const float wr = tw_re[k * fstride], wi = tw_im[k * fstride];
    float* ar = f.re + k * f.stride;
    float* ai = f.im + k * f.stride;
    float* br = f.re + (m + k) * f.stride;
    float* bi = f.im + (m + k) * f.stride;
    WMILTRACK_LANES_LOOP
    for (std::size_t b = 0; b < lanes; ++b) {
      const float tr = br[b] * wr - bi[b] * wi;
      const float ti = br[b] * wi + bi[b] * wr;
      br[b] = ar[b] - tr;
      bi[b] = ai[b] - ti;
      ar[b] = ar[b] + tr;
      ai[b] = ai[b] + ti;
    }
  }
}

WMILTRACK_KERNEL void fft_bfly4(const FftPlan& plan, Lanes f, std::size_t fstride, int m,
                                std::size_t lanes) {
  const float* tw_re = plan.tw_re.data();
  const float* tw_im = plan.tw_im.data();
  const float neg = static_cast<float>(plan.inverse ? -1 : 1);  // negative_if_inverse
  const std::size_t m_ = static_cast<std::size_t>(m);
  for (std::size_t k = 0; k < m_; ++k) {
    const float w1r = tw_re[k * fstride], w1i = tw_im[k * fstride];
    const float w2r = tw_re[k * fstride * 2], w2i = tw_im[k * fstride * 2];
    const float w3r = tw_re[k * fstride * 3], w3i = tw_im[k * fstride * 3];
    float* f0r = f.re + k * f.stride;
    float* f0i = f.im + k * f.stride;
    float* f1r = f.re + (k + m_) * f.stride;
    float* f1i = f.im + (k + m_) * f.stride;
    float* f2r = f.re + (k + 2 * m_) * f.stride;
    float* f2i = f.im + (k + 2 * m_) * f.stride;
    float* f3r = f.re + (k + 3 * m_) * f.stride;
    float* f3i = f.im + (k + 3 * m_) * f.stride;
    WMILTRACK_LANES_LOOP
    for (std::size_t b = 0; b < lanes; ++b) {
      const float s0r = f1r[b] * w1r - f1i[b] * w1i, s0i = f1r[b] * w1i + f1i[b] * w1r;
      const float s1r = f2r[b] * w2r - f2i[b] * w2i, s1i = f2r[b] * w2i + f2i[b] * w2r;
      const float s2r = f3r[b] * w3r - f3i[b] * w3i, s2i = f3r[b] * w3i + f3i[b] * w3r;
      const float s5r = f0r[b] - s1r, s5i = f0i[b] - s1i;
      float x0r = f0r[b] + s1r, x0i = f0i[b] + s1i;
      const float s3r = s0r + s2r, s3i = s0i + s2i;
      const float d4r = s0r - s2r, d4i = s0i - s2i;
      const float s4r = d4i * neg, s4i = -d4r * neg;
      f2r[b] = x0r - s3r;
      f2i[b] = x0i - s3i;
      x0r = x0r + s3r;
      x0i = x0i + s3i;
      f0r[b] = x0r;
      f0i[b] = x0i;
      f1r[b] = s5r + s4r;
      f1i[b] = s5i + s4i;
      f3r[b] = s5r - s4r;
      f3i[b] = s5i - s4i;
    }
  }
}

WMILTRACK_KERNEL void fft_bfly3(const FftPlan& plan, Lanes f, std::size_t fstride, int m,
                                std::size_t lanes) {
  const float* tw_re = plan.tw_re.data();
  const float* tw_im = plan.tw_im.data();
  const std::size_t m_ = static_cast<std::size_t>(m);
  const float e = tw_im[fstride * m_];  // epi3.imag()
  for (std::size_t k = 0; k < m_; ++k) {
    const float w1r = tw_re[k * fstride], w1i = tw_im[k * fstride];
    const float w2r = tw_re[k * fstride * 2], w2i = tw_im[k * fstride * 2];
    float* f0r = f.re + k * f.stride;
    float* f0i = f.im + k * f.stride;
    float* f1r = f.re + (k + m_) * f.stride;
    float* f1i = f.im + (k + m_) * f.stride;
    float* f2r = f.re + (k + 2 * m_) * f.stride;
    float* f2i = f.im + (k + 2 * m_) * f.stride;
    WMILTRACK_LANES_LOOP
    for (std::size_t b = 0; b < lanes; ++b) {
      const float s1r = f1r[b] * w1r - f1i[b] * w1i, s1i = f1r[b] * w1i + f1i[b] * w1r;
      const float s2r = f2r[b] * w2r - f2i[b] * w2i, s2i = f2r[b] * w2i + f2i[b] * w2r;
      const float s3r = s1r + s2r, s3i = s1i + s2i;
      float s0r = s1r - s2r, s0i = s1i - s2i;
      const float m1r = f0r[b] - 0.5f * s3r, m1i = f0i[b] - 0.5f * s3i;
      s0r = s0r * e;
      s0i = s0i * e;
      f0r[b] = f0r[b] + s3r;
      f0i[b] = f0i[b] + s3i;
      f2r[b] = m1r + s0i;
      f2i[b] = m1i - s0r;
      f1r[b] = m1r + -s0i;
      f1i[b] = m1i + s0r;
    }
  }
}

WMILTRACK_KERNEL void fft_bfly5(const FftPlan& plan, Lanes f, std::size_t fstride, int m,
                                std::size_t lanes) {
  const float* tw_re = plan.tw_re.data();
  const float* tw_im = plan.tw_im.data();
  const std::size_t m_ = static_cast<std::size_t>(m);
  const float yar = tw_re[fstride * m_], yai = tw_im[fstride * m_];
  const float ybr = tw_re[fstride * 2 * m_], ybi = tw_im[fstride * 2 * m_];
  for (std::size_t u = 0; u < m_; ++u) {
    const float w1r = tw_re[u * fstride], w1i = tw_im[u * fstride];
    const float w2r = tw_re[2 * u * fstride], w2i = tw_im[2 * u * fstride];
    const float w3r = tw_re[3 * u * fstride], w3i = tw_im[3 * u * fstride];
    const float w4r = tw_re[4 * u * fstride], w4i = tw_im[4 * u * fstride];
    float* f0r = f.re + u * f.stride;
    float* f0i = f.im + u * f.stride;
    float* f1r = f.re + (u + m_) * f.stride;
    float* f1i = f.im + (u + m_) * f.stride;
    float* f2r = f.re + (u + 2 * m_) * f.stride;
    float* f2i = f.im + (u + 2 * m_) * f.stride;
    float* f3r = f.re + (u + 3 * m_) * f.stride;
    float* f3i = f.im + (u + 3 * m_) * f.stride;
    float* f4r = f.re + (u + 4 * m_) * f.stride;
    float* f4i = f.im + (u + 4 * m_) * f.stride;
    WMILTRACK_LANES_LOOP
    for (std::size_t b = 0; b < lanes; ++b) {
      const float s0r = f0r[b], s0i = f0i[b];
      const float s1r = f1r[b] * w1r - f1i[b] * w1i, s1i = f1r[b] * w1i + f1i[b] * w1r;
      const float s2r = f2r[b] * w2r - f2i[b] * w2i, s2i = f2r[b] * w2i + f2i[b] * w2r;
      const float s3r = f3r[b] * w3r - f3i[b] * w3i, s3i = f3r[b] * w3i + f3i[b] * w3r;
      const float s4r = f4r[b] * w4r - f4i[b] * w4i, s4i = f4r[b] * w4i + f4i[b] * w4r;
      const float s7r = s1r + s4r, s7i = s1i + s4i;
      const float s10r = s1r - s4r, s10i = s1i - s4i;
      const float s8r = s2r + s3r, s8i = s2i + s3i;
      const float s9r = s2r - s3r, s9i = s2i - s3i;
      float x0r = s0r + s7r, x0i = s0i + s7i;
      x0r = x0r + s8r;
      x0i = x0i + s8i;
      f0r[b] = x0r;
      f0i[b] = x0i;
      const float s5r = s0r + ((s7r * yar) + (s8r * ybr));
      const float s5i = s0i + ((s7i * yar) + (s8i * ybr));
      const float s6r = (s10i * yai) + (s9i * ybi);
      const float s6i = -(s10r * yai) - (s9r * ybi);
      f1r[b] = s5r - s6r;
      f1i[b] = s5i - s6i;
      f4r[b] = s5r + s6r;
      f4i[b] = s5i + s6i;
      const float s11r = s0r + ((s7r * ybr) + (s8r * yar));
      const float s11i = s0i + ((s7i * ybr) + (s8i * yar));
      const float s12r = -(s10i * ybi) + (s9i * yai);
      const float s12i = (s10r * ybi) - (s9r * yai);
      f2r[b] = s11r + s12r;
      f2i[b] = s11i + s12i;
      f3r[b] = s11r - s12r;
      f3i[b] = s11i - s12i;
    }
  }
}

WMILTRACK_KERNEL void fft_bfly_generic(const FftPlan& plan, Lanes f, std::size_t fstride, int m,
                                       int p, std::size_t lanes, float* scratch) {
  const float* tw_re = plan.tw_re.data();
  const float* tw_im = plan.tw_im.data();
  const int norig = static_cast<int>(plan.tw_re.size());
  float* sr = scratch;
  float* si = scratch + static_cast<std::size_t>(p) * lanes;
  for (int u = 0; u < m; ++u) {
    int k = u;
    for (int q1 = 0; q1 < p; ++q1) {
      std::memcpy(sr + q1 * lanes, f.re + k * f.stride, lanes * sizeof(float));
      std::memcpy(si + q1 * lanes, f.im + k * f.stride, lanes * sizeof(float));
      k += m;
    }
    k = u;
    for (int q1 = 0; q1 < p; ++q1) {
      int twidx = 0;
      float* fr = f.re + k * f.stride;
      float* fi = f.im + k * f.stride;
      std::memcpy(fr, sr, lanes * sizeof(float));
      std::memcpy(fi, si, lanes * sizeof(float));
      for (int q = 1; q < p; ++q) {
        twidx += static_cast<int>(fstride) * k;
        if (twidx >= norig) twidx -= norig;
        const float wr = tw_re[twidx], wi = tw_im[twidx];
        const float* xr = sr + q * lanes;
        const float* xi = si + q * lanes;
        WMILTRACK_LANES_LOOP
        for (std::size_t b = 0; b < lanes; ++b) {
          const float tr = xr[b] * wr - xi[b] * wi;
          const float ti = xr[b] * wi + xi[b] * wr;
          fr[b] = fr[b] + tr;
          fi[b] = fi[b] + ti;
        }
      }
      k += m;
    }
  }
}

// kiss_cpx_fft::work(0, out, in, 1, 1) without its recursion: the recursion's leaves copy
// input element perm[o] to output position o, and each stage's butterflies run on every
// sub-transform of that stage, deepest stage first. The sub-transforms of a stage are disjoint
// and each one's butterflies follow all of its own deeper stages, as in the recursion, so every
// value is computed by the same operations from the same inputs.
WMILTRACK_KERNEL void fft_run_body(const FftPlan& plan, ConstLanes in, Lanes out,
                                   std::size_t lanes, float* scratch) {
  for (int o = 0; o < plan.n; ++o) {
    const std::size_t at = plan.perm[static_cast<std::size_t>(o)] * in.stride;
    const std::size_t to = static_cast<std::size_t>(o) * out.stride;
    std::memcpy(out.re + to, in.re + at, lanes * sizeof(float));
    if (in.im == nullptr) {
      std::fill(out.im + to, out.im + to + lanes, 0.0f);
    } else {
      std::memcpy(out.im + to, in.im + at, lanes * sizeof(float));
    }
  }
  for (std::size_t stage = plan.radix.size(); stage-- > 0;) {
    const int p = plan.radix[stage], m = plan.remainder[stage];
    const std::size_t fstride = plan.fstride[stage];
    const std::size_t block = static_cast<std::size_t>(p) * static_cast<std::size_t>(m);
    for (std::size_t first = 0; first < static_cast<std::size_t>(plan.n); first += block) {
      const Lanes f{out.re + first * out.stride, out.im + first * out.stride, out.stride};
      switch (p) {
        case 2: fft_bfly2(plan, f, fstride, m, lanes); break;
        case 3: fft_bfly3(plan, f, fstride, m, lanes); break;
        case 4: fft_bfly4(plan, f, fstride, m, lanes); break;
        case 5: fft_bfly5(plan, f, fstride, m, lanes); break;
        default: fft_bfly_generic(plan, f, fstride, m, p, lanes, scratch); break;
      }
    }
  }
}

#ifdef WMILTRACK_AVX2_COPIES
// The transforms compiled for AVX2 (8 lanes a step): the same IEEE operations in the same order
// (no fused multiply-add), so the same bits as the baseline copy. Named *_avx2 for the
// portable-build test (tests/core/test_core_hardening.py); run only where vmath::avx2().
__attribute__((target("avx2"))) inline void batch_fft_run_avx2(const FftPlan& plan,
                                                               ConstLanes in, Lanes out,
                                                               std::size_t lanes,
                                                               float* scratch) {
  fft_run_body(plan, in, out, lanes, scratch);
}
#endif

class BatchFft {
 public:
  BatchFft(int n, bool inverse) {
    Eigen::internal::kiss_cpx_fft<float> kiss;  // Eigen's own twiddles and factors
    kiss.make_twiddles(n, inverse);
    kiss.factorize(n);
    plan_.n = n;
    plan_.inverse = inverse;
    plan_.tw_re.resize(kiss.m_twiddles.size());
    plan_.tw_im.resize(kiss.m_twiddles.size());
    for (std::size_t i = 0; i < kiss.m_twiddles.size(); ++i) {
      plan_.tw_re[i] = kiss.m_twiddles[i].real();
      plan_.tw_im[i] = kiss.m_twiddles[i].imag();
    }
    plan_.radix = kiss.m_stageRadix;
    plan_.remainder = kiss.m_stageRemainder;
    plan_.max_radix = *std::max_element(plan_.radix.begin(), plan_.radix.end());
    std::size_t stride = 1;
    for (int p : plan_.radix) {
      plan_.fstride.push_back(stride);
      stride *= static_cast<std::size_t>(p);
    }
    plan_.perm.resize(static_cast<std::size_t>(n));
    leaves(0, 0, 0);
  }

  int size() const { return plan_.n; }

  // Unscaled transforms (kissfft's work) of `lanes` lanes of `in` into `out` (n elements each;
  // out must not overlap in). scratch: at least scratch_size(lanes) floats.
  void run(ConstLanes in, Lanes out, std::size_t lanes, float* scratch) const {
#ifdef WMILTRACK_AVX2_COPIES
    if (vmath::avx2()) return batch_fft_run_avx2(plan_, in, out, lanes, scratch);
#endif
    fft_run_body(plan_, in, out, lanes, scratch);
  }
  std::size_t scratch_size(std::size_t lanes) const {
    // bfly_generic's (radices other than 2 .. 5; a length of 1 is one stage of radix 1)
    return 2 * static_cast<std::size_t>(plan_.max_radix) * lanes;
  }

 private:
  // The input element each output position of kiss_cpx_fft::work's leaves copies.
  void leaves(std::size_t stage, std::size_t out_at, std::size_t in_at) {
    const int p = plan_.radix[stage], m = plan_.remainder[stage];
    const std::size_t fstride = plan_.fstride[stage];
    for (int q = 0; q < p; ++q) {
      if (m > 1) {
        leaves(stage + 1, out_at + static_cast<std::size_t>(q) * m, in_at + q * fstride);
      } else {
        plan_.perm[out_at + static_cast<std::size_t>(q)] = in_at + q * fstride;
      }
    }
  }

  FftPlan plan_;
};

// Eigen::FFT<float>'s forward transform of real inputs with the HalfSpectrum flag
// (kissfft_impl::fwd(Complex*, const Scalar*, nfft)): bins 0 .. n / 2 of each lane.
// Lengths that are multiples of 4 take kissfft's half-length complex transform of the
// (even, odd) pairs and its recombination; others the full complex transform.
class BatchRealFft {
 public:
  explicit BatchRealFft(int n)
      : n_(n), packed_(n % 4 == 0), plan_(packed_ ? n / 2 : n, false) {
    if (packed_) {
      const int ncfft2 = n / 4, ncfft = ncfft2 * 2;
      // kissfft_impl::real_twiddles, the same expression
      const float pi = std::acos(-1.0f);
      rtw_re_.resize(static_cast<std::size_t>(ncfft2));
      rtw_im_.resize(rtw_re_.size());
      for (int k = 1; k <= ncfft2; ++k) {
        const std::complex<float> w =
            std::exp(std::complex<float>(0, -pi * (static_cast<float>(k) / ncfft + 0.5f)));
        rtw_re_[k - 1] = w.real();
        rtw_im_[k - 1] = w.imag();
      }
    }
  }

  int size() const { return n_; }
  int half() const { return n_ / 2 + 1; }

  // in: n elements of `lanes` real values, element i at in + i * in_stride; out: half()
  // elements, split complex. scratch: at least scratch_size(lanes) floats.
  void run(const float* in, std::size_t in_stride, Lanes out, std::size_t lanes,
           float* scratch) const {
    if (!packed_) {
      // the full transform (imaginary parts 0), then its first half
      float* full_re = scratch;
      float* full_im = scratch + static_cast<std::size_t>(n_) * lanes;
      plan_.run(ConstLanes{in, nullptr, in_stride}, Lanes{full_re, full_im, lanes}, lanes,
                full_im + static_cast<std::size_t>(n_) * lanes);
      for (int k = 0; k < half(); ++k) {
        std::memcpy(out.re + k * out.stride, full_re + k * lanes, lanes * sizeof(float));
        std::memcpy(out.im + k * out.stride, full_im + k * lanes, lanes * sizeof(float));
      }
      return;
    }
    const std::size_t ncfft = static_cast<std::size_t>(n_ / 2), ncfft2 = ncfft / 2;
    // element j of the packed input: (in[2 j], in[2 j + 1])
    plan_.run(ConstLanes{in, in + in_stride, 2 * in_stride}, out, lanes, scratch);
    float* d0r = out.re;
    float* d0i = out.im;
    float* dnr = out.re + ncfft * out.stride;
    float* dni = out.im + ncfft * out.stride;
    for (std::size_t b = 0; b < lanes; ++b) {
      const float r = d0r[b], i = d0i[b];
      dnr[b] = r - i;  // nyquist (set after the loop in kissfft; nothing in it reads it)
      dni[b] = 0.0f;
      d0r[b] = r + i;  // dc
      d0i[b] = 0.0f;
    }
    // The loop reads dst[0] only as dst[ncfft - k] for k = ncfft, never: k <= ncfft2 < ncfft.
    for (std::size_t k = 1; k <= ncfft2; ++k) {
      const float wr = rtw_re_[k - 1], wi = rtw_im_[k - 1];
      float* pr = out.re + k * out.stride;
      float* pi = out.im + k * out.stride;
      float* nr = out.re + (ncfft - k) * out.stride;
      float* ni = out.im + (ncfft - k) * out.stride;
      for (std::size_t b = 0; b < lanes; ++b) {
        const float fpkr = pr[b], fpki = pi[b];
        const float fpnkr = nr[b], fpnki = -ni[b];
        const float f1kr = fpkr + fpnkr, f1ki = fpki + fpnki;
        const float f2kr = fpkr - fpnkr, f2ki = fpki - fpnki;
        const float twr = f2kr * wr - f2ki * wi, twi = f2kr * wi + f2ki * wr;
        pr[b] = (f1kr + twr) * 0.5f;
        pi[b] = (f1ki + twi) * 0.5f;
        nr[b] = (f1kr - twr) * 0.5f;
        ni[b] = -(f1ki - twi) * 0.5f;
      }
    }
  }

  std::size_t scratch_size(std::size_t lanes) const {
    return packed_ ? plan_.scratch_size(lanes)
                   : 2 * static_cast<std::size_t>(n_) * lanes + plan_.scratch_size(lanes);
  }

 private:
  int n_;
  bool packed_;
  BatchFft plan_;
  std::vector<float> rtw_re_, rtw_im_;
};

// 2-D transforms of rows x cols row-major real planes, as the translation filter takes them:
// Eigen::FFT<float>'s 1-D transforms along the rows, then along the columns (the arithmetic of
// the per-row, per-column Eigen calls exactly; see above), every row (and every column) of
// every plane of a call in one batch. Spectra of real arrays are Hermitian
// (X[r][c] = conj(X[-r][-c])), so only their columns 0 .. cols / 2 are kept ("half spectra",
// rows x (cols / 2 + 1)); the inverse rebuilds the rest. Immutable once built (the plans);
// the working buffers are per thread, so one Fft2 serves any number of threads.
class Fft2 {
 public:
  Fft2(int rows, int cols)
      : rows_(rows), cols_(cols), half_(cols / 2 + 1), row_fwd_(cols), col_fwd_(rows, false),
        col_inv_(rows, true), row_inv_(cols, true) {}

  int rows() const { return rows_; }
  int cols() const { return cols_; }
  int half() const { return half_; }

  // Columns 0 .. cols / 2 of numpy's fft2 of each of `planes` real planes (rows x cols each,
  // one after the other in `in`) into `out` (rows x half() each).
  void forward_half(const float* in, int planes, std::complex<float>* out) const {
    const std::size_t rows = static_cast<std::size_t>(rows_), cols = static_cast<std::size_t>(cols_);
    const std::size_t half = static_cast<std::size_t>(half_), np = static_cast<std::size_t>(planes);
    const std::size_t row_lanes = np * rows;  // one lane per row of every plane
    const std::size_t col_lanes = np * half;  // one lane per kept column of every plane
    float* buf = scratch(cols * row_lanes + 4 * half * row_lanes +
                         std::max(row_fwd_.scratch_size(row_lanes), col_fwd_.scratch_size(col_lanes)));
    float* t = buf;                                   // cols x (planes rows): the planes' columns
    float* sr = t + cols * row_lanes;                 // half x (planes rows): the rows' spectra
    float* si = sr + half * row_lanes;
    float* ur = si + half * row_lanes;                // rows x (planes half): the same, transposed
    float* ui = ur + half * row_lanes;
    float* work = ui + half * row_lanes;
    for (std::size_t p = 0; p < np; ++p) {
      transpose(in + p * rows * cols, cols, rows, cols, t + p * rows, row_lanes);
    }
    row_fwd_.run(t, row_lanes, Lanes{sr, si, row_lanes}, row_lanes, work);
    for (std::size_t p = 0; p < np; ++p) {
      transpose(sr + p * rows, row_lanes, half, rows, ur + p * half, col_lanes);
      transpose(si + p * rows, row_lanes, half, rows, ui + p * half, col_lanes);
    }
    // the column transforms' output over the row stage's (no longer needed) buffers
    float* vr = t;
    float* vi = sr;
    col_fwd_.run(ConstLanes{ur, ui, col_lanes}, Lanes{vr, vi, col_lanes}, col_lanes, work);
    for (std::size_t p = 0; p < np; ++p) {
      std::complex<float>* o = out + p * rows * half;
      for (std::size_t u = 0; u < rows; ++u) {
        for (std::size_t k = 0; k < half; ++k) {
          const std::size_t at = u * col_lanes + p * half + k;
          o[u * half + k] = std::complex<float>(vr[at], vi[at]);
        }
      }
    }
  }

  // numpy's real(ifft2(X)) of the Hermitian spectrum X whose half spectrum is `in`
  // (Eigen's inverses: each 1-D pass scaled by 1 / its length).
  void inverse_half_real(const std::complex<float>* in, float* out) const {
    const std::size_t rows = static_cast<std::size_t>(rows_), cols = static_cast<std::size_t>(cols_);
    const std::size_t half = static_cast<std::size_t>(half_), plane = rows * cols;
    float* buf = scratch(6 * plane + std::max(col_inv_.scratch_size(cols), row_inv_.scratch_size(rows)));
    float* fr = buf;  // rows x cols: the full spectrum (lanes: columns)
    float* fi = fr + plane;
    float* gr = fi + plane;  // rows x cols: after the column pass
    float* gi = gr + plane;
    float* hr = gi + plane;  // cols x rows: the same, transposed (lanes: rows)
    float* hi = hr + plane;
    float* work = hi + plane;
    for (std::size_t r = 0; r < rows; ++r) {
      const std::complex<float>* row = in + r * half;
      const std::complex<float>* mirror = in + ((rows - r) % rows) * half;
      for (std::size_t c = 0; c < half; ++c) {
        fr[r * cols + c] = row[c].real();
        fi[r * cols + c] = row[c].imag();
      }
      for (std::size_t c = half; c < cols; ++c) {
        const std::complex<float> v = std::conj(mirror[cols - c]);
        fr[r * cols + c] = v.real();
        fi[r * cols + c] = v.imag();
      }
    }
    col_inv_.run(ConstLanes{fr, fi, cols}, Lanes{gr, gi, cols}, cols, work);
    const float col_scale = static_cast<float>(1. / static_cast<double>(rows_));
    for (std::size_t i = 0; i < plane; ++i) {
      gr[i] *= col_scale;
      gi[i] *= col_scale;
    }
    transpose(gr, cols, rows, cols, hr, rows);
    transpose(gi, cols, rows, cols, hi, rows);
    row_inv_.run(ConstLanes{hr, hi, rows}, Lanes{fr, fi, rows}, rows, work);  // fr: cols x rows
    const float row_scale = static_cast<float>(1. / static_cast<double>(cols_));
    for (std::size_t i = 0; i < plane; ++i) fr[i] *= row_scale;
    transpose(fr, rows, cols, rows, out, cols);
  }

 private:
  // This thread's working buffer, at least n floats (grows, never shrinks).
  static float* scratch(std::size_t n) {
    thread_local std::vector<float> buf;
    if (buf.size() < n) buf.resize(n);
    return buf.data();
  }

  int rows_, cols_, half_;
  BatchRealFft row_fwd_;
  BatchFft col_fwd_, col_inv_, row_inv_;
};

}  // namespace wmiltrack::cf::detail
