// The learning kernels of a frame step: the online Gaussian update of the weak classifiers
// and the greedy feature selections (WMIL, MILBoost).
//
// The tracker's Python layer calls them through its Cython module (wmiltrack._learn); they
// live here so that the C++ benchmarks time the same code in the same order as a frame step
// of the tracker. Every kernel reproduces the numbers of the numpy/Cython code it replaced bit
// for bit (the paper presets' boxes are pinned): the same operations in the same order, no
// fused multiply-adds (-ffp-contract=off), and the C library's exp/log/log1p.
#pragma once

#include <cstddef>
#include <cstdint>

namespace wmiltrack {

// A read-only matrix of doubles with arbitrary strides (in elements, not bytes).
struct MatrixView {
  const double* data = nullptr;
  int rows = 0;
  int cols = 0;
  std::ptrdiff_t row_stride = 0;
  std::ptrdiff_t col_stride = 1;
  double at(int r, int c) const { return data[r * row_stride + c * col_stride]; }
  const double* row(int r) const { return data + r * row_stride; }
};

// numpy's float64 pairwise summation of n values `stride` apart (blocks of at most 128
// with 8 partial sums, halves above): numpy.add.reduce's result, bit for bit.
double pairwise_sum(const double* a, std::ptrdiff_t n, std::ptrdiff_t stride);

// How one class's Gaussians take in a frame's samples.
struct GaussianRule {
  double lam = 0.85;          // weight of the old model
  bool first = false;         // the class's first update
  bool direct_first = true;   // CT family: the first update replaces the model
  bool mil = false;           // MILTrack's rule (variance around the updated mean)
  double sigma_floor = 1e-4;  // lower bound of every sigma
};

// One class's Gaussians after the samples `values` (features x samples, samples >= 1):
// new_mu, new_sigma (one entry per feature). CT family (spec 1.1):
//   mu' = lam mu + (1 - lam) mean,
//   sigma' = sqrt(lam sigma^2 + (1 - lam) std^2 + lam (1 - lam) (mu - mean)^2)
// (mean, std: numpy's, two passes), or mean/std directly on a first update with direct_first;
// MILTrack (spec 1.2): mu' as above, var' = lam sigma^2 + (1 - lam) mean((v - mu')^2), the
// first update mean/var + 1e-9. Then max(sigma', sigma_floor). `scratch` holds >= samples
// doubles.
void gaussian_update(const MatrixView& values, const double* mu, const double* sigma,
                     const GaussianRule& rule, double* new_mu, double* new_sigma,
                     double* scratch);

// Greedy WMIL selection of k of the M features (spec section 5): with H = 0 on every
// instance, k times take the unused feature maximising <h_m, dL/dH> for
// L = ln sum_j w_j sigma(H+_j) + ln sum_j (1 - sigma(H-_j)) and add its h to H.
// h_pos, h_neg: M x P and M x N weak log ratios; w_pos: P weights; code_gradient: the
// reference code's w s (1 - w s) / sum(w s) instead of the derivative. selected: k indices.
// k must be in 1..M.
void wmil_select(const MatrixView& h_pos, const MatrixView& h_neg, const double* w_pos, int k,
                 bool code_gradient, std::int32_t* selected);

// Greedy MILBoost selection (spec section 4): the Noisy-OR positive bag divided by its size
// (as MILTrack's code does) plus one bag per negative. Takes e^h instead of h, sample-major
// (exp_pos: P x M, exp_neg: N x M; exp of h clipped to [-300, 300]) so that the caller
// chooses the exp (the Python layer uses numpy's, as before), and h itself (M x P, M x N) to
// build H. selected: k indices, k in 1..M.
void milboost_select(const MatrixView& h_pos, const MatrixView& h_neg, const MatrixView& exp_pos,
                     const MatrixView& exp_neg, int k, double guard, std::int32_t* selected);

}  // namespace wmiltrack
