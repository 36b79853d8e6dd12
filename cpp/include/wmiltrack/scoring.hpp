// Gaussian naive-Bayes weak classifiers and candidate scoring over a search grid.
#pragma once

#include "wmiltrack/vmath.hpp"

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "wmiltrack/haar.hpp"
#include "wmiltrack/integral.hpp"

namespace wmiltrack {

// Per-feature log-likelihood ratio of two Gaussians with the references' guards:
//   p_c(x) = exp(-(x - mu_c)^2 / (2 sigma_c^2 + eps)) / (sigma_c + eps),  eps = 1e-30
//   h(x)   = ln(p_1(x) + guard) - ln(p_0(x) + guard)
// guard = 1e-30 for the compressive-tracking family, 1e-5 for MILTrack.
class WeakGaussians {
 public:
  WeakGaussians(const double* mu1, const double* sigma1, const double* mu0, const double* sigma0,
                int n, double guard);

  int size() const { return static_cast<int>(mu1_.size()); }

  // out[i] (+)= h_k(x[i]) for i < n. Each h_k(x[i]) depends on x[i] alone (not on n, the
  // other values or the buffers' alignment): the same value gives the same bits here and in
  // score_grid. `scratch` is unused (kept for the signature).
  void log_ratio(int k, const double* x, int n, double* out, bool accumulate,
                 double* scratch) const;
  // Feature k's terms of the log ratio (vmath::LogRatioTerms, with the exact path's quadratic).
  vmath::LogRatioTerms terms(int k) const;
  double guard() const { return guard_; }

 private:
  Eigen::ArrayXd mu1_, a1_, lb1_, mu0_, a0_, lb0_;  // per feature (see the constructor)
  double guard_;
  double fast_cut_;  // above this log-density the guard cannot change a double
};

// Largest i with (i * step)^2 < radius^2: the grid spans offsets -n*step .. n*step.
inline int grid_half_size(int radius, int step) {
  return static_cast<int>((static_cast<std::int64_t>(radius) + step - 1) / step - 1);
}

// Largest search radius score_grid accepts (the grid is walked in full: (2r/step)^2 cells).
constexpr int kMaxSearchRadius = 4096;

struct GridResult {
  int dx = 0;
  int dy = 0;
  double score = 0.0;
  int candidates = 0;  // 0: no candidate box fits in the frame; dx = dy = 0 then
};

// A cue's map over a frame region [x0, x0 + cols) x [y0, y0 + rows), and its weight in the
// merge. A box-mean cue (centre = false) gives the integral image of its map, (rows + 1) x
// (cols + 1) with a zero first row and column, and values a candidate by the map's mean over
// the box; a centre cue (centre = true) gives the map itself, rows x cols, and values a
// candidate by the map at the box's centre pixel (x + w / 2, y + h / 2, rounded down); a pooled
// centre cue, on a grid of step s, by the map's largest value within s / 2 (rounded down)
// pixels of that pixel in each direction, so that a sharp peak between the grid's points is
// not missed.
struct CueTable {
  const double* table = nullptr;  // row-major
  int rows = 0;
  int cols = 0;
  int x0 = 0;
  int y0 = 0;
  double weight = 0.0;
  bool centre = false;
  bool pooled = false;  // a centre cue read at its best within half a grid step
};

// Cues merged into the choice of a search's best candidate (rcwmil-plus's colour likelihood,
// after Staple, and any other cue): the candidate with the largest
//   (1 - sum of weights) * logistic(raw / k - offset) + sum of weight * (the cue's value of the box)
// wins (the first such in row-major order), and its raw score is reported; candidates whose
// raw score is not finite take no part. logistic(z) is computed as 0.5 (1 + tanh(z / 2)).
// With `relative`, raw is read from the grid's best finite raw score (raw - best for raw): the
// confidence is then relative to this frame's best candidate, so the classifier's ordering still
// counts when its absolute confidence has collapsed over the whole grid.
struct CueMerge {
  std::vector<CueTable> cues;  // at least one
  double offset = 0.0;
  int k = 1;  // raw scores are divided by k (the number of selected features)
  bool relative = false;  // see above
};

// Scores the boxes `box` + (i*step, j*step) with (i*step)^2 + (j*step)^2 < radius^2 that lie
// fully inside the frame, as the sum of the selected features' log ratios. Returns the first
// maximum in row-major order (dy outer, dx inner). When `scores` is not null it receives the
// (2n+1) x (2n+1) grid, -inf where no candidate was scored. With `cues` the choice is the
// merged one (see CueMerge; `candidates` then counts those with a finite raw score), and
// a candidate box outside a cue's table throws std::out_of_range.
GridResult score_grid(const IntegralImage& ii, const FeatureBank& bank, const std::int32_t* selected,
                      int n_selected, const WeakGaussians& weak, const Rect& box, int radius,
                      int step, int frame_width, int frame_height, double* scores,
                      const CueMerge* cues = nullptr);

// How well the box with top-left corner (x, y) fits a target model over all the bank's
// features: minus the mean of log(1 + z^2), z = (value - mu[k]) / sigma[k] (a heavy-tailed
// template fit; rcwmil-plus compares scales with it). The mean is numpy's (pairwise sum /
// M). Throws as project() does for a box outside the integral image.
double template_fit(const IntegralImage& ii, const FeatureBank& bank, int x, int y,
                    const double* mu, const double* sigma);

// One stage of a coarse-to-fine search: a grid of this radius and step.
struct SearchStage {
  int radius;
  int step;
};

// score_grid() for each stage in turn, each centred where the previous one moved the box
// (a stage without candidates leaves it in place). Returns each stage's result, whose dx/dy
// are relative to that stage's centre. One call for the whole search of a frame; `cues` (may
// be null) are merged into every stage's choice.
std::vector<GridResult> search(const IntegralImage& ii, const FeatureBank& bank,
                               const std::int32_t* selected, int n_selected,
                               const WeakGaussians& weak, Rect box,
                               const std::vector<SearchStage>& stages, int frame_width,
                               int frame_height, const CueMerge* cues = nullptr);

}  // namespace wmiltrack
