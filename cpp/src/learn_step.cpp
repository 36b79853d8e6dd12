// The learning half of a tracker's frame step in one call (learn_step.hpp).
#include "wmiltrack/learn_step.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "wmiltrack/scoring.hpp"

namespace wmiltrack {

void learn_step(const IntegralImage& ii, const FeatureBank& bank, const LearnStep& step,
                double* mu1, double* sigma1, double* mu0, double* sigma0,
                std::int32_t* selected, double* h) {
  const int M = bank.size(), P = step.n_pos, E = step.n_extra, N = step.n_neg + E;
  const int boxes = P + step.n_neg, B = P + N;
  if (P < 0 || step.n_neg < 0 || E < 0) throw std::invalid_argument("learn_step: negative bag size");
  if (E > 0 && step.extra_neg == nullptr) {
    throw std::invalid_argument("learn_step: n_extra values need their array");
  }
  if (step.select == LearnSelect::kWmil && (P == 0 || step.w_pos == nullptr)) {
    throw std::invalid_argument("learn_step: WMIL selection needs positives and their weights");
  }
  // values: M x B, the projected boxes' columns then the extra negatives'. Every entry is
  // written below, so the buffers are not cleared first (std::vector would: 76 KB a frame).
  const std::size_t n_values = static_cast<std::size_t>(M) * static_cast<std::size_t>(B);
  const std::unique_ptr<double[]> values(new double[n_values]);
  if (E == 0) {
    project(ii, bank, nullptr, M, step.xs, step.ys, boxes, values.get());
  } else {
    std::vector<double> projected(static_cast<std::size_t>(M) * static_cast<std::size_t>(boxes));
    project(ii, bank, nullptr, M, step.xs, step.ys, boxes, projected.data());
    for (int m = 0; m < M; ++m) {
      double* row = values.get() + static_cast<std::ptrdiff_t>(m) * B;
      std::copy_n(projected.data() + static_cast<std::ptrdiff_t>(m) * boxes, boxes, row);
      std::copy_n(step.extra_neg + static_cast<std::ptrdiff_t>(m) * E, E, row + boxes);
    }
  }
  // The Gaussian update of each class that has samples, into fresh arrays then copied back
  // (the update reads the old model).
  std::vector<double> new_mu(static_cast<std::size_t>(M)), new_sigma(new_mu.size()),
      scratch(static_cast<std::size_t>(std::max(B, 1)));
  const auto update = [&](int first_col, int n, bool first, double* mu, double* sigma,
                          const GaussianRule& given) {
    if (n == 0) return;
    GaussianRule rule = given;
    rule.first = first;
    const MatrixView v{values.get() + first_col, M, n, B, 1};
    gaussian_update(v, mu, sigma, rule, new_mu.data(), new_sigma.data(), scratch.data());
    std::copy(new_mu.begin(), new_mu.end(), mu);
    std::copy(new_sigma.begin(), new_sigma.end(), sigma);
  };
  update(0, P, step.first_pos, mu1, sigma1, step.rule);
  update(P, N, step.first_neg, mu0, sigma0, step.rule);
  if (step.second_mu != nullptr && step.second_sigma != nullptr) {
    update(0, P, step.second_rule.first, step.second_mu, step.second_sigma, step.second_rule);
  }
  if (step.select == LearnSelect::kNone) return;
  // Log ratios of every feature on both bags under the updated model.
  std::unique_ptr<double[]> own;
  double* hr = h;
  if (step.select != LearnSelect::kRatios) {
    own.reset(new double[n_values]);
    hr = own.get();
  }
  const WeakGaussians weak(mu1, sigma1, mu0, sigma0, M, step.guard);
  for (int m = 0; m < M; ++m) {
    const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(m) * B;
    weak.log_ratio(m, values.get() + row, B, hr + row, false, nullptr);
  }
  if (step.select == LearnSelect::kWmil) {
    const MatrixView h_pos{hr, M, P, B, 1}, h_neg{hr + P, M, N, B, 1};
    wmil_select(h_pos, h_neg, step.w_pos, step.k, step.code_gradient, selected);
  }
}

}  // namespace wmiltrack
