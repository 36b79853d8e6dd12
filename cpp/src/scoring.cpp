#include "wmiltrack/scoring.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace wmiltrack {

namespace {
constexpr double kEps = 1e-30;
using ArrayMap = Eigen::Map<Eigen::ArrayXd>;
using ConstArrayMap = Eigen::Map<const Eigen::ArrayXd>;
}  // namespace

WeakGaussians::WeakGaussians(const double* mu1, const double* sigma1, const double* mu0,
                             const double* sigma0, int n, double guard)
    : guard_(guard) {
  if (!(guard > 0.0)) throw std::invalid_argument("weak classifiers: guard must be > 0");
  // ln(p + guard) == ln(p) in double once p > guard * 2^60.
  fast_cut_ = std::log(guard) + 60.0 * std::log(2.0);
  const auto push = [](double mu, double sigma, std::vector<double>& m, std::vector<double>& a,
                       std::vector<double>& lb) {
    if (!(sigma > 0.0) || !std::isfinite(sigma) || !std::isfinite(mu)) {
      throw std::invalid_argument("weak classifiers: need finite means and sigmas > 0");
    }
    m.push_back(mu);
    a.push_back(1.0 / (2.0 * sigma * sigma + kEps));
    lb.push_back(-std::log(sigma + kEps));
  };
  for (int k = 0; k < n; ++k) {
    push(mu1[k], sigma1[k], mu1_, a1_, lb1_);
    push(mu0[k], sigma0[k], mu0_, a0_, lb0_);
  }
}

void WeakGaussians::log_ratio(int k, const double* x, int n, double* out, bool accumulate,
                              double* scratch) const {
  ConstArrayMap v(x, n);
  ArrayMap l1(scratch, n), l0(scratch + n, n);
  l1 = lb1_[k] - (v - mu1_[k]).square() * a1_[k];
  l0 = lb0_[k] - (v - mu0_[k]).square() * a0_[k];
  ArrayMap h(out, n);
  if (l1.minCoeff() > fast_cut_ && l0.minCoeff() > fast_cut_) {
    // Both densities dwarf the guard everywhere: the ratio is exact in the log domain.
    if (accumulate) h += l1 - l0; else h = l1 - l0;
  } else {
    if (accumulate) h += ((l1.exp() + guard_) / (l0.exp() + guard_)).log();
    else h = ((l1.exp() + guard_) / (l0.exp() + guard_)).log();
  }
}

GridResult score_grid(const IntegralImage& ii, const FeatureBank& bank, const std::int32_t* selected,
                      int n_selected, const WeakGaussians& weak, const Rect& box, int radius,
                      int step, int frame_width, int frame_height, double* scores) {
  if (radius < 1 || step < 1) throw std::invalid_argument("score_grid: radius and step must be >= 1");
  if (weak.size() != n_selected) {
    throw std::invalid_argument("score_grid: one weak classifier per selected feature is needed");
  }
  const int n = grid_half_size(radius, step);
  const int side = 2 * n + 1;
  const long r2 = static_cast<long>(radius) * radius;
  const Rect& e = bank.extent();

  // Gather the candidates that fit in the frame, in row-major order.
  std::vector<int> cand_dx, cand_dy;
  std::vector<std::ptrdiff_t> base;
  for (int j = -n; j <= n; ++j) {
    for (int i = -n; i <= n; ++i) {
      const long dx = static_cast<long>(i) * step, dy = static_cast<long>(j) * step;
      if (dx * dx + dy * dy >= r2) continue;
      const int x = box.x + static_cast<int>(dx), y = box.y + static_cast<int>(dy);
      if (x < 0 || y < 0 || x + box.w > frame_width || y + box.h > frame_height) continue;
      if (!ii.covers(Rect{x + e.x, y + e.y, e.w, e.h})) {
        throw std::out_of_range("score_grid: a candidate inside the frame is outside the integral image");
      }
      cand_dx.push_back(static_cast<int>(dx));
      cand_dy.push_back(static_cast<int>(dy));
      base.push_back((y - ii.y0()) * ii.stride() + (x - ii.x0()));
    }
  }
  const int c = static_cast<int>(base.size());
  GridResult result;
  result.candidates = c;
  if (scores != nullptr) {
    std::fill(scores, scores + side * side, -std::numeric_limits<double>::infinity());
  }
  if (c == 0) return result;

  // Feature values, one contiguous row per feature, then the summed log ratios.
  const CompiledFeatures compiled(bank, selected, n_selected, ii.stride());
  std::vector<double> values(static_cast<std::size_t>(c)), total(static_cast<std::size_t>(c), 0.0),
      scratch(2 * static_cast<std::size_t>(c));
  for (int k = 0; k < compiled.size(); ++k) {
    for (int q = 0; q < c; ++q) values[q] = compiled.value(ii.data() + base[q], k);
    weak.log_ratio(k, values.data(), c, total.data(), true, scratch.data());
  }

  int best = -1;
  for (int q = 0; q < c; ++q) {
    if (std::isnan(total[q])) continue;
    if (best < 0 || total[q] > total[best]) best = q;
  }
  if (best < 0) throw std::runtime_error("score_grid: every candidate scored NaN");
  result.dx = cand_dx[best];
  result.dy = cand_dy[best];
  result.score = total[best];
  if (scores != nullptr) {
    for (int q = 0; q < c; ++q) {
      scores[(cand_dy[q] / step + n) * side + (cand_dx[q] / step + n)] = total[q];
    }
  }
  return result;
}

}  // namespace wmiltrack
