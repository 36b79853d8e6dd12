// The learning half of a tracker's frame step in one call: the feature values of both bags,
// the Gaussian update of each class, the log ratios of both bags under the updated model and,
// for WMIL, the feature selection. The same kernels in the same order as the separate calls
// (project, gaussian_update x 2, WeakGaussians::log_ratio, wmil_select), so the same bits;
// one call instead of five lets a tracker's update cross between Python and the core (and
// take and drop the GIL) fewer times.
#pragma once

#include <cstdint>

#include "wmiltrack/haar.hpp"
#include "wmiltrack/integral.hpp"
#include "wmiltrack/learning.hpp"

namespace wmiltrack {

enum class LearnSelect {
  kNone,    // no selection (CT, FCT; or no positive sample this frame)
  kWmil,    // WMIL selection of k features into `selected`
  kRatios,  // the log ratios of both bags into `h`, for a selection made by the caller
};

struct LearnStep {
  // Bags: top-left corners of n_pos positives followed by n_neg negatives.
  const std::int32_t* xs = nullptr;
  const std::int32_t* ys = nullptr;
  int n_pos = 0;
  int n_neg = 0;
  // Gaussian update of each class (GaussianRule::first is taken from first_pos/first_neg; a
  // class without samples this frame keeps its model).
  GaussianRule rule;
  bool first_pos = false;
  bool first_neg = false;
  double guard = 1e-30;  // of the log ratios
  LearnSelect select = LearnSelect::kNone;
  const double* w_pos = nullptr;  // n_pos instance weights (kWmil)
  int k = 0;                      // features to select (kWmil)
  bool code_gradient = false;
  // Negatives given as feature values (M x n_extra, row-major), taken after the projected
  // negatives as if they were more negative boxes (rcwmil-plus: the target's box at wrong
  // scales, projected with another bank).
  const double* extra_neg = nullptr;
  int n_extra = 0;
  // A second target model (M each, in place), updated from the positives alone by its own
  // rule after the main model (rcwmil-plus's scale likelihood); none when null.
  double* second_mu = nullptr;
  double* second_sigma = nullptr;
  GaussianRule second_rule;
};

// Runs the step on the bank's M features. mu1, sigma1, mu0, sigma0 (M each): the model in,
// the updated model out (in place). selected (k entries) is written for kWmil; h (M x
// (n_pos + n_neg + n_extra), row-major) for kRatios. Throws as the separate kernels do.
void learn_step(const IntegralImage& ii, const FeatureBank& bank, const LearnStep& step,
                double* mu1, double* sigma1, double* mu0, double* sigma0,
                std::int32_t* selected, double* h);

}  // namespace wmiltrack
