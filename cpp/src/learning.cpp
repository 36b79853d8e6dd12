#include "wmiltrack/learning.hpp"

#include "wmiltrack/vmath.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace wmiltrack {

double pairwise_sum(const double* a, std::ptrdiff_t n, std::ptrdiff_t stride) {
  if (n < 8) {
    double res = 0.0;
    for (std::ptrdiff_t i = 0; i < n; ++i) res = res + a[i * stride];
    return res;
  }
  if (n <= 128) {
    double r[8];
    for (int j = 0; j < 8; ++j) r[j] = a[j * stride];
    std::ptrdiff_t i = 8;
    for (; i < n - (n % 8); i += 8) {
      for (int j = 0; j < 8; ++j) r[j] = r[j] + a[(i + j) * stride];
    }
    double res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for (; i < n; ++i) res = res + a[i * stride];
    return res;
  }
  std::ptrdiff_t n2 = n / 2;
  n2 -= n2 % 8;
  return pairwise_sum(a, n2, stride) + pairwise_sum(a + n2 * stride, n - n2, stride);
}

namespace {

// numpy.add.reduce over row m: 0.0 plus the pairwise sum.
double row_sum(const MatrixView& v, int m) {
  return 0.0 + pairwise_sum(v.row(m), v.cols, v.col_stride);
}

// ((row - centre) ** 2).mean() as numpy computes it.
double row_sq_dev_mean(const MatrixView& v, int m, double centre, double* scratch) {
  const double* r = v.row(m);
  for (int j = 0; j < v.cols; ++j) {
    const double d = r[j * v.col_stride] - centre;
    scratch[j] = d * d;
  }
  return (0.0 + pairwise_sum(scratch, v.cols, 1)) / static_cast<double>(v.cols);
}

// numpy.maximum(a, b): NaN propagates.
double max_nan(double a, double b) { return (std::isnan(a) || a >= b) ? a : b; }

// ln sigma(z_j) into out[j] and 1 - sigma(z_j) into rest[j], j < n, from one exp(-|z|)
// without overflow (1 - sigma(z) stays exact for large z, where computing 1 - sigma would round
// to 0). `e` is scratch of n values.
void log_sigmoid_and_rest(const double* z, int n, double* out, double* rest, double* e) {
  for (int j = 0; j < n; ++j) e[j] = z[j] >= 0 ? -z[j] : z[j];
  vmath::exp(e, e, n);
  vmath::log1p(e, out, n);
  for (int j = 0; j < n; ++j) {
    const bool up = z[j] >= 0;
    rest[j] = (up ? e[j] : 1.0) / (1.0 + e[j]);
    out[j] = up ? -out[j] : z[j] - out[j];
  }
}

// sigma(z_j) into sig[j] and 1 - sigma(z_j) into rest[j], j < n, from one e = exp(-|z|):
// 1 / (1 + e) and e / (1 + e), each exact to a few ulps for any z (no 1 - sigma cancellation).
void sigmoid_and_rest(const double* z, int n, double* sig, double* rest) {
  for (int j = 0; j < n; ++j) rest[j] = z[j] >= 0 ? -z[j] : z[j];
  vmath::exp(rest, rest, n);
  for (int j = 0; j < n; ++j) {
    const double e = rest[j];
    const double big = 1.0 / (1.0 + e);
    const double small = e * big;
    const bool up = z[j] >= 0;
    sig[j] = up ? big : small;
    rest[j] = up ? small : big;
  }
}

// Bag totals (sums of sigma or of w sigma) in [kSafeTotal, kHuge] are normalised directly;
// others (underflow, NaN, absurd weights) through the log domain.
constexpr double kSafeTotal = 1e-200;
constexpr double kHuge = 1e200;

// out[j] = w[j] exp(logv[j]) / sum_m w[m] exp(logv[m]), computed without underflow.
void normalised(const double* logv, const double* w, double* out, int n) {
  double top = -std::numeric_limits<double>::infinity();
  for (int j = 0; j < n; ++j) {
    if (w[j] > 0 && logv[j] > top) top = logv[j];
  }
  if (top == -std::numeric_limits<double>::infinity()) {
    for (int j = 0; j < n; ++j) out[j] = 0.0;
    return;
  }
  for (int j = 0; j < n; ++j) out[j] = logv[j] - top;
  vmath::exp(out, out, n);
  double total = 0.0;
  for (int j = 0; j < n; ++j) {
    out[j] = w[j] * out[j];
    total += out[j];
  }
  for (int j = 0; j < n; ++j) out[j] /= total;
}

// Adds feature `best` to the strong classifier (the first unused one if best < 0, i.e. when
// every candidate scored NaN).
void take(int best, int step, const MatrixView& h_pos, const MatrixView& h_neg,
          std::vector<double>& H_pos, std::vector<double>& H_neg, std::vector<unsigned char>& used,
          std::int32_t* selected) {
  if (best < 0) {
    for (int m = 0; m < static_cast<int>(used.size()); ++m) {
      if (!used[static_cast<std::size_t>(m)]) {
        best = m;
        break;
      }
    }
  }
  used[static_cast<std::size_t>(best)] = 1;
  selected[step] = best;
  for (int j = 0; j < h_pos.cols; ++j) H_pos[static_cast<std::size_t>(j)] += h_pos.at(best, j);
  for (int j = 0; j < h_neg.cols; ++j) H_neg[static_cast<std::size_t>(j)] += h_neg.at(best, j);
}

void check_selection(const MatrixView& h_pos, const MatrixView& h_neg, int k) {
  if (h_neg.rows != h_pos.rows) {
    throw std::invalid_argument("h_pos and h_neg disagree in the number of features");
  }
  if (k < 1 || k > h_pos.rows) {
    throw std::invalid_argument("k must be in 1.." + std::to_string(h_pos.rows) + ", got " +
                                std::to_string(k));
  }
}

}  // namespace

void gaussian_update(const MatrixView& values, const double* mu, const double* sigma,
                     const GaussianRule& rule, double* new_mu, double* new_sigma,
                     double* scratch) {
  if (values.cols < 1) throw std::invalid_argument("gaussian_update needs at least one sample");
  const double lam = rule.lam;
  const double keep = 1.0 - lam;
  const double cross = lam * (1.0 - lam);
  const double n = static_cast<double>(values.cols);
  for (int m = 0; m < values.rows; ++m) {
    const double mean = row_sum(values, m) / n;
    if (rule.mil) {
      double var;
      if (rule.first) {
        var = row_sq_dev_mean(values, m, mean, scratch) + 1e-9;
        new_mu[m] = mean;
      } else {
        new_mu[m] = lam * mu[m] + keep * mean;
        var = lam * (sigma[m] * sigma[m]) + keep * row_sq_dev_mean(values, m, new_mu[m], scratch);
      }
      new_sigma[m] = max_nan(std::sqrt(var), rule.sigma_floor);
      continue;
    }
    const double s = std::sqrt(row_sq_dev_mean(values, m, mean, scratch));  // numpy's std
    if (rule.first && rule.direct_first) {
      new_mu[m] = mean;
      new_sigma[m] = max_nan(s, rule.sigma_floor);
      continue;
    }
    const double d = mu[m] - mean;
    const double var = (lam * (sigma[m] * sigma[m]) + keep * (s * s)) + cross * (d * d);
    new_sigma[m] = max_nan(std::sqrt(var), rule.sigma_floor);
    new_mu[m] = lam * mu[m] + keep * mean;
  }
}

// The log ratios instance-major, in float: row j holds every feature's h on instance j (the
// positives, then the negatives), rows wz floats apart, each padded with zeros after the M
// features (every float of hT is written here: its buffer need not be zeroed first).
static void instance_major(const MatrixView& h_pos, const MatrixView& h_neg, std::size_t wz,
                           float* hT) {
  const int M = h_pos.rows, P = h_pos.cols, N = h_neg.cols;
  for (int j = 0; j < P; ++j) {
    float* row = hT + static_cast<std::size_t>(j) * wz;
    for (int m = 0; m < M; ++m) row[m] = static_cast<float>(h_pos.at(m, j));
    std::fill(row + M, row + wz, 0.0f);
  }
  for (int j = 0; j < N; ++j) {
    float* row = hT + static_cast<std::size_t>(P + j) * wz;
    for (int m = 0; m < M; ++m) row[m] = static_cast<float>(h_neg.at(m, j));
    std::fill(row + M, row + wz, 0.0f);
  }
}

// The unused feature of the largest score (the first of equal ones; NaN scores never), or -1.
static int best_unused(const float* score, const std::vector<unsigned char>& used, int M) {
  int best = -1;
  float best_score = -std::numeric_limits<float>::infinity();
  for (int m = 0; m < M; ++m) {
    const float sc = score[m];
    if (used[static_cast<std::size_t>(m)] || std::isnan(sc)) continue;
    if (best < 0 || sc > best_score) {
      best = m;
      best_score = sc;
    }
  }
  return best;
}

void wmil_select(const MatrixView& h_pos, const MatrixView& h_neg, const double* w_pos, int k,
                 bool code_gradient, std::int32_t* selected) {
  check_selection(h_pos, h_neg, k);
  const int M = h_pos.rows, P = h_pos.cols, N = h_neg.cols;
  std::vector<double> H_pos(static_cast<std::size_t>(P), 0.0), H_neg(static_cast<std::size_t>(N), 0.0);
  std::vector<double> g(static_cast<std::size_t>(P + N), 0.0);
  std::vector<double> tmp(static_cast<std::size_t>(std::max(P, N))), rest(tmp.size()),
      scratch(tmp.size()), minus_h(static_cast<std::size_t>(N));
  const std::vector<double> ones(static_cast<std::size_t>(std::max(N, 1)), 1.0);
  std::vector<unsigned char> used(static_cast<std::size_t>(M), 0);
  // Instance-major float copy of the log ratios (row j: every feature's h on instance j, the
  // positives then the negatives; rows padded with zeros to a multiple of 8 features), so
  // that the scoring runs over features: M independent float sums, each adding its terms in
  // the order j = 0, 1, ..., several features a step (vmath::weighted_rows_f32; the same bits
  // at any vector width). Float halves the bytes and doubles the lanes; a score only ranks the
  // features of one round.
  const int width = (M + 7) / 8 * 8;
  const std::size_t wz = static_cast<std::size_t>(width);
  // (not value-initialised: zeroing (P + N) x width floats cost about 2 % of a paper preset's
  // frame, and instance_major writes every one)
  const std::unique_ptr<float[]> hT(new float[static_cast<std::size_t>(P + N) * wz]);
  std::vector<float> gf(static_cast<std::size_t>(P + N)), score(wz);
  instance_major(h_pos, h_neg, wz, hT.get());
  double* g_pos = g.data();
  double* g_neg = g.data() + P;
  double* sig = tmp.data();
  for (int step = 0; step < k; ++step) {
    // Positive bag: d ln(sum_j w_j sigma_j) / dH_j = w_j sigma_j (1 - sigma_j) / sum w sigma.
    // sigma and 1 - sigma from one exp(-|H|) each; the log domain (which cannot underflow)
    // only when sum w sigma is not a normal double far above the smallest.
    if (P > 0) {
      sigmoid_and_rest(H_pos.data(), P, sig, rest.data());
      double total = 0.0;
      for (int j = 0; j < P; ++j) total += w_pos[j] * sig[j];
      if (total >= kSafeTotal && total <= kHuge) {
        for (int j = 0; j < P; ++j) g_pos[j] = (w_pos[j] * sig[j]) / total;
      } else {
        log_sigmoid_and_rest(H_pos.data(), P, tmp.data(), rest.data(), scratch.data());
        normalised(tmp.data(), w_pos, g_pos, P);
        vmath::exp(tmp.data(), sig, P);
      }
      if (code_gradient) {
        // The reference code's w sigma (1 - w sigma) / sum(w sigma) (spec 5, compat).
        for (int j = 0; j < P; ++j) g_pos[j] = g_pos[j] * (1.0 - w_pos[j] * sig[j]);
      } else {
        for (int j = 0; j < P; ++j) g_pos[j] = g_pos[j] * rest[static_cast<std::size_t>(j)];
      }
    }
    // Negative bag: d ln(sum_j (1 - sigma_j)) / dH_j = -sigma_j (1 - sigma_j) / sum(1 - sigma).
    if (N > 0) {
      for (int j = 0; j < N; ++j) minus_h[static_cast<std::size_t>(j)] = -H_neg[static_cast<std::size_t>(j)];
      sigmoid_and_rest(minus_h.data(), N, sig, rest.data());
      double total = 0.0;
      for (int j = 0; j < N; ++j) total += sig[j];
      if (total >= kSafeTotal && total <= kHuge) {
        for (int j = 0; j < N; ++j) g_neg[j] = sig[j] / total;
      } else {
        log_sigmoid_and_rest(minus_h.data(), N, tmp.data(), rest.data(), scratch.data());
        normalised(tmp.data(), ones.data(), g_neg, N);
      }
      for (int j = 0; j < N; ++j) g_neg[j] = -g_neg[j] * rest[static_cast<std::size_t>(j)];
    }
    // score_m = sum_j h_mj g_j over the positives then the negatives.
    for (int j = 0; j < P + N; ++j) gf[static_cast<std::size_t>(j)] = static_cast<float>(g[static_cast<std::size_t>(j)]);
    vmath::weighted_rows_f32(hT.get(), P + N, width, gf.data(), score.data());
    take(best_unused(score.data(), used, M), step, h_pos, h_neg, H_pos, H_neg, used, selected);
  }
}

namespace {

typedef double V4 __attribute__((vector_size(32)));

// prod_q (guard + 1 / (1 + x_q)) for x_q = c_q e_q, as prod (1 + guard (1 + x_q)) / prod (1 + x_q)
// with x_q capped at 1e30 (NaN stays NaN); for doubles and for vectors of 4 (lane by lane).
template <class T>
WMILTRACK_KERNEL T four_factors_of(T x0, T x1, T x2, T x3, double guard) {
  const T top = T{} + 1e30;
  const auto cap = [top](T x) { return x > top ? top : x; };
  const T d0 = 1.0 + cap(x0), d1 = 1.0 + cap(x1), d2 = 1.0 + cap(x2), d3 = 1.0 + cap(x3);
  const T n0 = 1.0 + guard * d0, n1 = 1.0 + guard * d1, n2 = 1.0 + guard * d2, n3 = 1.0 + guard * d3;
  return ((n0 * n1) * (n2 * n3)) / ((d0 * d1) * (d2 * d3));
}

WMILTRACK_KERNEL double four_factors(double e0, double e1, double e2, double e3, double c0,
                                     double c1, double c2, double c3, double guard) {
  return four_factors_of<double>(c0 * e0, c1 * e1, c2 * e2, c3 * e3, guard);
}

WMILTRACK_KERNEL V4 four_factors(const V4* e, double c0, double c1, double c2, double c3,
                                 double guard) {
  return four_factors_of<V4>(c0 * e[0], c1 * e[1], c2 * e[2], c3 * e[3], guard);
}

// The body of milboost_select, inlined into an AVX2 copy and a baseline copy (below): its
// loops over the features are plain element-wise IEEE arithmetic, which the compiler
// vectorises at either width with the same bits (no FMA, no reordering of sums).
WMILTRACK_KERNEL void milboost_body(const MatrixView& h_pos, const MatrixView& h_neg,
                                    const MatrixView& exp_pos, const MatrixView& exp_neg, int k,
                                    double guard, std::int32_t* selected) {
  const int M = h_pos.rows, P = h_pos.cols, N = h_neg.cols;
  const std::size_t Mz = static_cast<std::size_t>(M);
  std::vector<double> H_pos(static_cast<std::size_t>(P), 0.0), H_neg(static_cast<std::size_t>(N), 0.0);
  std::vector<double> D(Mz), prod(Mz), L(Mz), logs(Mz);
  std::vector<double> c_pos(static_cast<std::size_t>(P)), c_neg(static_cast<std::size_t>(N));
  std::vector<unsigned char> used(Mz, 0);
  double* Dp = D.data();
  double* pp = prod.data();
  double* Lp = L.data();
  double* lg = logs.data();
  const double inv_p = P > 0 ? 1.0 / P : 0.0;
  const double inv_n = N > 0 ? 1.0 / N : 0.0;
  std::vector<unsigned char> nan_neg(Mz, 0);  // features with a NaN e^h on a negative
  for (int j = 0; j < N; ++j) {
    const double* e = exp_neg.row(j);
    for (int m = 0; m < M; ++m) {
      if (std::isnan(e[m])) nan_neg[static_cast<std::size_t>(m)] = 1;
    }
  }
  const auto clamp60 = [](double z) { return z > 60.0 ? 60.0 : (z < -60.0 ? -60.0 : z); };
  for (int step = 0; step < k; ++step) {
    for (int m = 0; m < M; ++m) {
      Dp[m] = 1.0;
      pp[m] = 1.0;
      Lp[m] = 0.0;
    }
    // e^H of every instance, H clamped to [-60, 60].
    for (int j = 0; j < P; ++j) c_pos[static_cast<std::size_t>(j)] = clamp60(H_pos[static_cast<std::size_t>(j)]);
    for (int j = 0; j < N; ++j) c_neg[static_cast<std::size_t>(j)] = clamp60(H_neg[static_cast<std::size_t>(j)]);
    vmath::exp(c_pos.data(), c_pos.data(), P);
    vmath::exp(c_neg.data(), c_neg.data(), N);
    // Positive bag: prod_j (1 - sigma(H_j + h_mj)) = 1 / prod_j (1 + e^H_j e^h_mj).
    // Capping the product at 1e30 changes 1 - 1/D by < 1e-30, far below the guard.
    for (int j = 0; j < P; ++j) {
      const double c = c_pos[static_cast<std::size_t>(j)];
      const double* e = exp_pos.row(j);
      for (int m = 0; m < M; ++m) {
        const double t = Dp[m] * (1.0 + c * e[m]);
        Dp[m] = t < 1e30 ? t : 1e30;
      }
    }
    // Negatives: sum_j ln(guard + 1 - sigma), as logs of products of <= 60 factors (each
    // factor >= guard = 1e-5, so a product stays above 1e-300; 60 is a multiple of 4). The logs of features
    // already chosen are never used: not added.
    // Four factors share one division: guard + 1 / (1 + x) = (1 + guard (1 + x)) / (1 + x),
    // with x = e^H e^h capped at 1e30 (the factor moves by < 1e-30 / guard there), so that
    // the products of four numerators or denominators stay below 1e130. x is NaN only where
    // e^H or e^h is: a NaN e^H takes the one-division-a-factor loop, a feature with a NaN e^h
    // gets a NaN likelihood (as that loop gives it).
    bool c_nan = false;
    for (int j = 0; j < N; ++j) c_nan = c_nan || std::isnan(c_neg[static_cast<std::size_t>(j)]);
    int chunk = 0;
    for (int j = 0; j < N;) {
      const int n4 = c_nan ? 1 : std::min(4, N - j);
      if (n4 == 4) {
        const double c0 = c_neg[static_cast<std::size_t>(j)], c1 = c_neg[static_cast<std::size_t>(j + 1)],
                     c2 = c_neg[static_cast<std::size_t>(j + 2)], c3 = c_neg[static_cast<std::size_t>(j + 3)];
        const double *e0 = exp_neg.row(j), *e1 = exp_neg.row(j + 1), *e2 = exp_neg.row(j + 2),
                     *e3 = exp_neg.row(j + 3);
        // Four features a step in a GCC vector (two SSE2 or one AVX2 register: the same
        // operations on every lane), the rest one at a time the same way.
        int m = 0;
        for (; m + 4 <= M; m += 4) {
          V4 x[4], pv;
          std::memcpy(&x[0], e0 + m, sizeof(V4));
          std::memcpy(&x[1], e1 + m, sizeof(V4));
          std::memcpy(&x[2], e2 + m, sizeof(V4));
          std::memcpy(&x[3], e3 + m, sizeof(V4));
          std::memcpy(&pv, pp + m, sizeof(V4));
          pv = pv * four_factors(x, c0, c1, c2, c3, guard);
          std::memcpy(pp + m, &pv, sizeof(V4));
        }
        for (; m < M; ++m) {
          pp[m] = pp[m] * four_factors(e0[m], e1[m], e2[m], e3[m], c0, c1, c2, c3, guard);
        }
      } else {
        for (int q = 0; q < n4; ++q) {
          const double c = c_neg[static_cast<std::size_t>(j + q)];
          const double* e = exp_neg.row(j + q);
          for (int m = 0; m < M; ++m) pp[m] = pp[m] * (guard + 1.0 / (1.0 + c * e[m]));
        }
      }
      j += n4;
      chunk += n4;
      if (chunk == 60 || j == N) {
        vmath::log(pp, lg, M);
        for (int m = 0; m < M; ++m) {
          if (!used[static_cast<std::size_t>(m)]) Lp[m] += lg[m];
          pp[m] = 1.0;
        }
        chunk = 0;
      }
    }
    if (!c_nan) {
      for (int m = 0; m < M; ++m) {
        if (nan_neg[static_cast<std::size_t>(m)]) Lp[m] = std::numeric_limits<double>::quiet_NaN();
      }
    }
    // -ln(1 - 1/D + guard) for the positive bag's likelihood.
    if (P > 0) {
      for (int m = 0; m < M; ++m) lg[m] = 1.0 - 1.0 / Dp[m] + guard;
      vmath::log(lg, lg, M);
    }
    int best = -1;
    double best_nll = std::numeric_limits<double>::infinity();
    for (int m = 0; m < M; ++m) {
      if (used[static_cast<std::size_t>(m)]) continue;
      double nll = 0.0;
      if (P > 0) nll = -lg[m] * inv_p;
      nll = nll - Lp[m] * inv_n;
      if (std::isnan(nll)) continue;
      if (best < 0 || nll < best_nll) {
        best = m;
        best_nll = nll;
      }
    }
    take(best, step, h_pos, h_neg, H_pos, H_neg, used, selected);
  }
}

}  // namespace

// Named copies of the body per instruction set (see vmath.hpp: the portable-build test finds
// AVX instructions only in functions named *_avx2).
namespace detail {
void milboost_select_base(const MatrixView& h_pos, const MatrixView& h_neg,
                          const MatrixView& exp_pos, const MatrixView& exp_neg, int k,
                          double guard, std::int32_t* selected) {
  milboost_body(h_pos, h_neg, exp_pos, exp_neg, k, guard, selected);
}
#ifdef WMILTRACK_AVX2_COPIES
__attribute__((target("avx2"))) void milboost_select_avx2(
    const MatrixView& h_pos, const MatrixView& h_neg, const MatrixView& exp_pos,
    const MatrixView& exp_neg, int k, double guard, std::int32_t* selected) {
  milboost_body(h_pos, h_neg, exp_pos, exp_neg, k, guard, selected);
}
#endif
}  // namespace detail

void milboost_select(const MatrixView& h_pos, const MatrixView& h_neg, const MatrixView& exp_pos,
                     const MatrixView& exp_neg, int k, double guard, std::int32_t* selected) {
  check_selection(h_pos, h_neg, k);
  const int M = h_pos.rows, P = h_pos.cols, N = h_neg.cols;
  if (exp_pos.rows != P || exp_neg.rows != N || (P > 0 && exp_pos.cols != M) ||
      (N > 0 && exp_neg.cols != M) || (P > 0 && exp_pos.col_stride != 1) ||
      (N > 0 && exp_neg.col_stride != 1)) {
    throw std::invalid_argument("exp_pos/exp_neg must be samples x features with contiguous rows");
  }
#ifdef WMILTRACK_AVX2_COPIES
  if (vmath::avx2()) {
    detail::milboost_select_avx2(h_pos, h_neg, exp_pos, exp_neg, k, guard, selected);
    return;
  }
#endif
  detail::milboost_select_base(h_pos, h_neg, exp_pos, exp_neg, k, guard, selected);
}

}  // namespace wmiltrack
