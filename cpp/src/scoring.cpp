#include "wmiltrack/scoring.hpp"

#include "fmath.hpp"
#include "grid_runs.hpp"

#include "wmiltrack/learning.hpp"
#include "wmiltrack/vmath.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

// The search's feature sums read 4 candidates a step with SSE2 (every x86-64) and 8 with AVX2
// where the CPU has it (chosen at run time through vmath::avx2()); WMILTRACK_NO_SIMD or
// another compiler: one candidate at a time. Every path adds the same exact rectangle sums in
// the same order, so the values have the same bits.
#if defined(WMILTRACK_AVX2_COPIES)
#define WMILTRACK_GRID_SIMD 1
#include <immintrin.h>
#endif

namespace wmiltrack {

namespace {

// values[run.first + t] = feature k at candidate t of each run, one candidate at a time (any
// step; t * step apart in the table).
void grid_values_scalar(const IntegralImage::Entry* table, const std::vector<GridRun>& runs,
                        int step, const CompiledFeatures& f, int k, double* values) {
  for (const GridRun& run : runs) {
    for (int t = 0; t < run.count; ++t) {
      values[run.first + t] = f.value(table + run.base + static_cast<std::ptrdiff_t>(t) * step, k);
    }
  }
}
}  // namespace

#ifdef WMILTRACK_GRID_SIMD

namespace detail {
// values[run.first + t] = the feature with rectangles c[0..n) at candidate t of each run, the
// candidates of a run consecutive in `table`, 4 a step (SSE2). A run's last step overlaps the
// one before when the count is not a multiple of 4: it recomputes the same values.
// One run of at least 4 candidates (inlined into both copies below).
inline __attribute__((always_inline)) void run_sse2(const IntegralImage::Entry* b0, int count,
                                                    const CompiledFeatures::Corners* c, int n,
                                                    double* o) {
    for (int t = 0;; t += 4) {
      t = std::min(t, count - 4);
      const IntegralImage::Entry* b = b0 + t;
      __m128d lo = _mm_setzero_pd(), hi = _mm_setzero_pd();
      for (int r = 0; r < n; ++r) {
        const auto at = [b](std::ptrdiff_t off) {
          return _mm_loadu_si128(reinterpret_cast<const __m128i*>(b + off));
        };
        const __m128i sum = _mm_sub_epi32(_mm_sub_epi32(at(c[r].br), at(c[r].tr)),
                                          _mm_sub_epi32(at(c[r].bl), at(c[r].tl)));
        const __m128d w = _mm_set1_pd(c[r].weight);
        lo = _mm_add_pd(lo, _mm_mul_pd(w, _mm_cvtepi32_pd(sum)));
        hi = _mm_add_pd(hi, _mm_mul_pd(w, _mm_cvtepi32_pd(_mm_srli_si128(sum, 8))));
      }
      _mm_storeu_pd(o + t, lo);
      _mm_storeu_pd(o + t + 2, hi);
      if (t == count - 4) break;
    }
}

void grid_values_sse2(const IntegralImage::Entry* table, const std::vector<GridRun>& runs,
                      const CompiledFeatures::Corners* c, int n, double* values) {
  for (const GridRun& run : runs) {
    const IntegralImage::Entry* b0 = table + run.base;
    double* o = values + run.first;
    if (run.count < 4) {
      for (int t = 0; t < run.count; ++t) o[t] = CompiledFeatures::value_of(b0 + t, c, n);
      continue;
    }
    run_sse2(b0, run.count, c, n, o);
  }
}

// The same, 8 candidates a step (AVX2). Run only where vmath::avx2() says so; named so that
// the portable-build test finds it (see vmath.hpp).
__attribute__((target("avx2"))) void grid_values_avx2(const IntegralImage::Entry* table,
                                                      const std::vector<GridRun>& runs,
                                                      const CompiledFeatures::Corners* c, int n,
                                                      double* values) {
  for (const GridRun& run : runs) {
    const IntegralImage::Entry* b0 = table + run.base;
    double* o = values + run.first;
    if (run.count < 8) {
      if (run.count >= 4) {
        run_sse2(b0, run.count, c, n, o);
      } else {
        for (int t = 0; t < run.count; ++t) o[t] = CompiledFeatures::value_of(b0 + t, c, n);
      }
      continue;
    }
    for (int t = 0;; t += 8) {
      t = std::min(t, run.count - 8);
      const IntegralImage::Entry* b = b0 + t;
      __m256d lo = _mm256_setzero_pd(), hi = _mm256_setzero_pd();
      for (int r = 0; r < n; ++r) {
        const __m256i br = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(b + c[r].br));
        const __m256i tr = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(b + c[r].tr));
        const __m256i bl = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(b + c[r].bl));
        const __m256i tl = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(b + c[r].tl));
        const __m256i sum = _mm256_sub_epi32(_mm256_sub_epi32(br, tr), _mm256_sub_epi32(bl, tl));
        const __m256d w = _mm256_set1_pd(c[r].weight);
        lo = _mm256_add_pd(lo, _mm256_mul_pd(w, _mm256_cvtepi32_pd(_mm256_castsi256_si128(sum))));
        hi = _mm256_add_pd(hi, _mm256_mul_pd(w, _mm256_cvtepi32_pd(_mm256_extracti128_si256(sum, 1))));
      }
      _mm256_storeu_pd(o + t, lo);
      _mm256_storeu_pd(o + t + 4, hi);
      if (t == run.count - 8) break;
    }
  }
}

}  // namespace detail

namespace {
// What the vector loops read: a table, the runs' bases in it and the rectangles' corner
// offsets (the integral image itself, or a copy split by column phase).
struct GridTable {
  const IntegralImage::Entry* table;
  std::vector<GridRun> runs;
  std::vector<CompiledFeatures::Corners> own;  // remapped corners (empty: the compiled ones)
  std::vector<IntegralImage::Entry> copy;      // the split copy (empty: the integral image)
  const CompiledFeatures* compiled;

  GridTable(const IntegralImage::Entry* t, const std::vector<GridRun>& r, const CompiledFeatures& f)
      : table(t), runs(r), compiled(&f) {}
  const CompiledFeatures::Corners* corners(int r) const {
    return own.empty() ? &compiled->corners(r) : own.data() + r;
  }
};

// The part of plane 0 that a step-`step` grid's candidates reach (extent `e` from each
// candidate's corner), copied split by column phase: phase p, row r, entry j holds the
// table's entry at row R0 + r, column C0 + p + j * step. Candidate columns differ by
// multiples of the step, so a corner at column offset C0 + a from the region's first
// candidate column lies in phase a % step, and consecutive candidates are consecutive entries.
GridTable decimate(const IntegralImage& ii, const Rect& e, int step, const std::vector<GridRun>& runs,
                   const CompiledFeatures& f) {
  const std::ptrdiff_t s = ii.stride();
  std::ptrdiff_t row0 = std::numeric_limits<std::ptrdiff_t>::max(), row1 = -1;
  std::ptrdiff_t col0 = row0, col1 = -1;
  for (const GridRun& run : runs) {
    const std::ptrdiff_t row = run.base / s, col = run.base % s;
    row0 = std::min(row0, row);
    row1 = std::max(row1, row);
    col0 = std::min(col0, col);
    col1 = std::max(col1, col + static_cast<std::ptrdiff_t>(run.count - 1) * step);
  }
  const std::ptrdiff_t r_first = row0 + e.y, r_last = row1 + e.y + e.h;
  const std::ptrdiff_t c_first = col0 + e.x, c_last = col1 + e.x + e.w;
  const std::ptrdiff_t rows = r_last - r_first + 1;
  const std::ptrdiff_t width = (c_last - c_first) / step + 1;  // entries per phase row
  const std::ptrdiff_t phase_size = rows * width;
  GridTable g(nullptr, runs, f);
  g.copy.resize(static_cast<std::size_t>(phase_size * step));
  const IntegralImage::Entry* table = ii.data();
  for (std::ptrdiff_t r = 0; r < rows; ++r) {
    const IntegralImage::Entry* src = table + (r_first + r) * s + c_first;
    for (int p = 0; p < step; ++p) {
      IntegralImage::Entry* dst = g.copy.data() + p * phase_size + r * width;
      for (std::ptrdiff_t j = 0; p + j * step <= c_last - c_first; ++j) dst[j] = src[p + j * step];
    }
  }
  g.table = g.copy.data();
  for (GridRun& run : g.runs) {
    const std::ptrdiff_t row = run.base / s, col = run.base % s;
    run.base = (row - row0) * width + (col - col0) / step;
  }
  const auto remap = [&](std::ptrdiff_t off) {
    const std::ptrdiff_t dr = off / s - e.y, a = off % s - e.x;  // both >= 0
    return (a % step) * phase_size + dr * width + a / step;
  };
  g.own.reserve(static_cast<std::size_t>(f.num_rects()));
  for (int r = 0; r < f.num_rects(); ++r) {
    const CompiledFeatures::Corners& q = f.corners(r);
    g.own.push_back(CompiledFeatures::Corners{remap(q.tl), remap(q.tr), remap(q.bl), remap(q.br), q.weight});
  }
  return g;
}
}  // namespace
#endif

void run_values(const IntegralImage::Entry* table, const std::vector<GridRun>& runs,
                const CompiledFeatures::Corners* c, int n, bool vector, double* values) {
#ifdef WMILTRACK_GRID_SIMD
  if (vector && vmath::avx2()) {
    detail::grid_values_avx2(table, runs, c, n, values);
    return;
  }
  if (vector) {
    detail::grid_values_sse2(table, runs, c, n, values);
    return;
  }
#else
  (void)vector;
#endif
  for (const GridRun& run : runs) {
    for (int t = 0; t < run.count; ++t) {
      values[run.first + t] = CompiledFeatures::value_of(table + run.base + t, c, n);
    }
  }
}

// ---- The exhaustive search's fused score (issue 28): candidates outer, features inner ------
//
// Where a feature's log ratio takes the exact path (both log densities above the cut, the case
// for nearly every candidate with CT's guard of 1e-30), the score of a candidate is summed here
// in one pass: each feature's value in float from the exact 32-bit rectangle sums, then
// h = C + d (B + A d) with d = value - centre in float, added to the candidate's total in double.
// Values outside the exact range take the guarded formula in float, as
// log(e^l_1 + guard) - log(e^l_0 + guard) (fmath.hpp). Each candidate's total depends on its own
// rectangle sums alone, computed by the same float and double operations in the same order
// whether it is one of 8 lanes (the vector body, compiled for AVX2 and for the SSE2 baseline)
// or alone (runs of fewer than 8 candidates, and builds without the vector extension): the
// same bits on every path.
struct FusedFeature {
  int r0, r1;                       // its rectangles
  float centre, qa, qb, qc, lo, hi;  // LogRatioTerms' quadratic, in float
  float mu1, mu0, a1, lb1, a0, lb0;  // and its log densities l_c = lb_c - (x - mu_c)^2 a_c
  float ln_guard;
};

namespace {

float to_float_sum(const IntegralImage::Entry* b, const CompiledFeatures::Corners& c) {
  const std::uint32_t s = (b[c.br] - b[c.tr]) - (b[c.bl] - b[c.tl]);
  return static_cast<float>(static_cast<std::int32_t>(s));
}

// The guarded log ratio in float at value v, for floats or vectors of them.
template <class F, class I>
inline __attribute__((always_inline)) F guarded_of(F v, const FusedFeature& f) {
  const F d = v - f.mu1;
  const F d0 = v - f.mu0;
  const F l1 = f.lb1 - (d * d) * f.a1;
  const F l0 = f.lb0 - (d0 * d0) * f.a0;
  return fmath::log_exp_plus_diff<F, I>(l1, l0, f.ln_guard);
}

float guarded(float v, const FusedFeature& f) { return guarded_of<float, std::int32_t>(v, f); }

// One candidate (top-left table entry b): its total over the features.
double fused_one(const IntegralImage::Entry* b, const CompiledFeatures::Corners* c,
                 const float* wf, const std::vector<FusedFeature>& ff) {
  double total = 0.0;
  for (const FusedFeature& f : ff) {
    float v = 0.0f;
    for (int r = f.r0; r < f.r1; ++r) v = v + wf[r] * to_float_sum(b, c[r]);
    const float d = v - f.centre;
    float h;
    if (d > f.lo && d < f.hi) {
      h = f.qc + d * (f.qb + f.qa * d);
    } else {
      h = guarded(v, f);
    }
    total = total + static_cast<double>(h);
  }
  return total;
}

}  // namespace

#ifdef WMILTRACK_GRID_SIMD
namespace {
typedef float V8f __attribute__((vector_size(32)));
typedef std::int32_t V8i __attribute__((vector_size(32)));
typedef double V4d __attribute__((vector_size(32)));

// 8 G candidates of a run from table entry b (consecutive): their totals into out[0..8 G), G
// groups of 8 side by side.
template <int G>
WMILTRACK_KERNEL void fused_groups(const IntegralImage::Entry* b, const CompiledFeatures::Corners* c,
                                   const float* wf, const std::vector<FusedFeature>& ff,
                                   double* out) {
  V4d acc[2 * G];
  for (V4d& a : acc) a = V4d{} + 0.0;
  for (const FusedFeature& f : ff) {
    V8f v[G];
    for (int g = 0; g < G; ++g) v[g] = V8f{} + 0.0f;
    for (int r = f.r0; r < f.r1; ++r) {
      const CompiledFeatures::Corners& q = c[r];
      for (int g = 0; g < G; ++g) {
        V8i br, tr, bl, tl;
        std::memcpy(&br, b + 8 * g + q.br, sizeof br);
        std::memcpy(&tr, b + 8 * g + q.tr, sizeof tr);
        std::memcpy(&bl, b + 8 * g + q.bl, sizeof bl);
        std::memcpy(&tl, b + 8 * g + q.tl, sizeof tl);
        v[g] = v[g] + wf[r] * __builtin_convertvector((br - tr) - (bl - tl), V8f);
      }
    }
    for (int g = 0; g < G; ++g) {
      const V8f d = v[g] - f.centre;
      const V8f h = f.qc + d * (f.qb + f.qa * d);
      const auto exact = (d > f.lo) & (d < f.hi);
      // Lanes outside the exact range: the guarded formula in float, lane by lane the same.
      const V8f hf = fmath::all_of(exact) ? h : (exact ? h : guarded_of<V8f, V8i>(v[g], f));
      typedef float V4f __attribute__((vector_size(16)));
      V4f h0, h1;
      std::memcpy(&h0, &hf, sizeof h0);
      std::memcpy(&h1, reinterpret_cast<const char*>(&hf) + sizeof h0, sizeof h1);
      const V4d hd0 = __builtin_convertvector(h0, V4d), hd1 = __builtin_convertvector(h1, V4d);
      acc[2 * g] = acc[2 * g] + hd0;
      acc[2 * g + 1] = acc[2 * g + 1] + hd1;
    }
  }
  std::memcpy(out, acc, sizeof acc);
}

WMILTRACK_KERNEL void fused_body(const IntegralImage::Entry* table, const std::vector<GridRun>& runs,
                                 const CompiledFeatures::Corners* c, const float* wf,
                                 const std::vector<FusedFeature>& ff, double* total) {
  for (const GridRun& run : runs) {
    const IntegralImage::Entry* b0 = table + run.base;
    double* o = total + run.first;
    if (run.count < 8) {
      for (int t = 0; t < run.count; ++t) o[t] = fused_one(b0 + t, c, wf, ff);
      continue;
    }
    // 8 a step, the last step ending the run (recomputing some: the same values). (Two groups
    // side by side were measured slower: register pressure.)
    for (int t = 0;; t += 8) {
      t = std::min(t, run.count - 8);
      fused_groups<1>(b0 + t, c, wf, ff, o + t);
      if (t == run.count - 8) break;
    }
  }
}
}  // namespace

namespace detail {
void fused_scores_base(const IntegralImage::Entry* table, const std::vector<GridRun>& runs,
                       const CompiledFeatures::Corners* c, const float* wf,
                       const std::vector<FusedFeature>& ff, double* total) {
  fused_body(table, runs, c, wf, ff, total);
}
__attribute__((target("avx2"))) void fused_scores_avx2(
    const IntegralImage::Entry* table, const std::vector<GridRun>& runs,
    const CompiledFeatures::Corners* c, const float* wf, const std::vector<FusedFeature>& ff,
    double* total) {
  fused_body(table, runs, c, wf, ff, total);
}
}  // namespace detail
#endif

namespace {
// total[run.first + t] for every candidate of the runs (see above).
// (`step`: the table distance of a run's consecutive candidates, 1 on the SIMD builds' tables.)
void fused_scores(const IntegralImage::Entry* table, const std::vector<GridRun>& runs, int step,
                  const CompiledFeatures::Corners* c, const float* wf,
                  const std::vector<FusedFeature>& ff, double* total) {
#ifdef WMILTRACK_GRID_SIMD
  (void)step;
  if (vmath::avx2()) {
    detail::fused_scores_avx2(table, runs, c, wf, ff, total);
  } else {
    detail::fused_scores_base(table, runs, c, wf, ff, total);
  }
#else
  for (const GridRun& run : runs) {
    for (int t = 0; t < run.count; ++t) {
      total[run.first + t] = fused_one(table + run.base + static_cast<std::ptrdiff_t>(t) * step, c, wf, ff);
    }
  }
#endif
}
}  // namespace

namespace {
constexpr double kEps = 1e-30;
}  // namespace

WeakGaussians::WeakGaussians(const double* mu1, const double* sigma1, const double* mu0,
                             const double* sigma0, int n, double guard)
    : guard_(guard) {
  if (!(guard > 0.0)) throw std::invalid_argument("weak classifiers: guard must be > 0");
  // ln(p + guard) == ln(p) in double once p > guard * 2^60.
  fast_cut_ = std::log(guard) + 60.0 * std::log(2.0);
  using Map = Eigen::Map<const Eigen::ArrayXd>;
  const Map m1(mu1, n), s1(sigma1, n), m0(mu0, n), s0(sigma0, n);
  const auto valid = [](const Map& mu, const Map& sigma) {
    return (sigma > 0.0).all() && sigma.isFinite().all() && mu.isFinite().all();
  };
  if (!valid(m1, s1) || !valid(m0, s0)) {
    throw std::invalid_argument("weak classifiers: need finite means and sigmas > 0");
  }
  // Per feature: a = 1 / (2 sigma^2 + eps) and lb = -ln(sigma + eps) (the C library's log).
  const auto neg_log = [](double v) { return -std::log(v); };
  mu1_ = m1;
  a1_ = (2.0 * s1 * s1 + kEps).inverse();
  lb1_ = (s1 + kEps).unaryExpr(neg_log);
  mu0_ = m0;
  a0_ = (2.0 * s0 * s0 + kEps).inverse();
  lb0_ = (s0 + kEps).unaryExpr(neg_log);
}

// Each value chooses the exact or the guarded formula on its own (vmath::log_ratio), so that a
// value depends on its own inputs only, never on the other samples of the batch or the buffer's
// alignment. MILTrack's guard (1e-5) sends every value down the guarded path.
vmath::LogRatioTerms WeakGaussians::terms(int k) const {
  return vmath::make_log_ratio_terms(mu1_[k], a1_[k], lb1_[k], mu0_[k], a0_[k], lb0_[k], guard_,
                                     fast_cut_);
}

void WeakGaussians::log_ratio(int k, const double* x, int n, double* out, bool accumulate,
                              double* /*scratch*/) const {
  vmath::log_ratio(terms(k), x, n, out, accumulate);
}

namespace {

// A centre cue's value for a candidate of a grid of `step` pixels centred at (px, py) of
// its map: the map there, or, pooled, the map's largest value within half a step of it
// (clipped to the map). A correlation filter's peak is a few pixels wide; read at the grid's
// points alone, a coarse grid (step 4) can miss it and pick a wide secondary peak instead.
double centre_value(const CueTable& cue, std::int64_t px, std::int64_t py, int step) {
  const std::int64_t half = cue.pooled ? step / 2 : 0;
  if (half == 0) return cue.table[py * cue.cols + px];
  const std::int64_t c0 = std::max<std::int64_t>(px - half, 0);
  const std::int64_t c1 = std::min<std::int64_t>(px + half, cue.cols - 1);
  const std::int64_t r0 = std::max<std::int64_t>(py - half, 0);
  const std::int64_t r1 = std::min<std::int64_t>(py + half, cue.rows - 1);
  double best = -std::numeric_limits<double>::infinity();
  for (std::int64_t r = r0; r <= r1; ++r) {
    const double* row = cue.table + r * cue.cols;
    for (std::int64_t c = c0; c <= c1; ++c) best = std::max(best, row[c]);
  }
  return best;
}

// The candidate chosen by the merged score of CueMerge (-1 when no raw score is finite) on a
// grid of `step` pixels; `finite` receives the number of candidates with a finite raw score.
int merged_best(const CueMerge& merge, const Rect& box, const std::vector<int>& dx,
                const std::vector<int>& dy, int step, const std::vector<double>& raw,
                int& finite) {
  const double area = static_cast<double>(box.w) * static_cast<double>(box.h);
  const double k = static_cast<double>(std::max(merge.k, 1));
  double total = 0.0;  // the cues' weights
  for (const CueTable& cue : merge.cues) total += cue.weight;
  double reference = 0.0;  // raw scores are read from here: 0, or the grid's best (relative)
  if (merge.relative) {
    reference = -std::numeric_limits<double>::infinity();
    for (const double r : raw) {
      if (std::isfinite(r) && r > reference) reference = r;
    }
  }
  int best = -1;
  double best_value = 0.0;
  finite = 0;
  for (std::size_t q = 0; q < raw.size(); ++q) {
    if (!std::isfinite(raw[q])) continue;
    ++finite;
    const double conf = 0.5 * (1.0 + std::tanh(0.5 * ((raw[q] - reference) / k - merge.offset)));
    double value = (1.0 - total) * conf;
    for (const CueTable& cue : merge.cues) {
      const std::int64_t cx = static_cast<std::int64_t>(box.x) + dx[q] - cue.x0;
      const std::int64_t cy = static_cast<std::int64_t>(box.y) + dy[q] - cue.y0;
      if (cue.centre) {
        const std::int64_t px = cx + box.w / 2, py = cy + box.h / 2;
        if (px < 0 || py < 0 || px >= cue.cols || py >= cue.rows) {
          throw std::out_of_range("score_grid: a candidate's centre lies outside a cue's map");
        }
        value += cue.weight * centre_value(cue, px, py, step);
        continue;
      }
      if (cx < 0 || cy < 0 || cx + box.w > cue.cols || cy + box.h > cue.rows) {
        throw std::out_of_range("score_grid: a candidate box lies outside a cue's table");
      }
      const std::ptrdiff_t stride = static_cast<std::ptrdiff_t>(cue.cols) + 1;
      const double* top = cue.table + cy * stride + cx;
      const double* bottom = top + static_cast<std::ptrdiff_t>(box.h) * stride;
      const double s = bottom[box.w] - top[box.w] - bottom[0] + top[0];
      value += cue.weight * (s / area);
    }
    if (best < 0 || value > best_value) {
      best = static_cast<int>(q);
      best_value = value;
    }
  }
  return best;
}

}  // namespace

namespace {

void check_grid(const IntegralImage& ii, int n_selected, const WeakGaussians& weak, const Rect& box,
                int radius, int step) {
  if (!ii.computed()) throw std::invalid_argument("score_grid: the integral image has not been computed");
  if (radius < 1 || step < 1) throw std::invalid_argument("score_grid: radius and step must be >= 1");
  if (radius > kMaxSearchRadius) {
    throw std::invalid_argument("score_grid: radius must be <= " + std::to_string(kMaxSearchRadius));
  }
  if (box.w <= 0 || box.h <= 0) throw std::invalid_argument("score_grid: box must have positive size");
  if (weak.size() != n_selected) {
    throw std::invalid_argument("score_grid: one weak classifier per selected feature is needed");
  }
}

// score_grid on checked arguments with the selected features already compiled (`e`: the
// bank's extent), so that the stages of a search compile them once.
GridResult grid_stage(const IntegralImage& ii, const Rect& e, const CompiledFeatures& compiled,
                      const WeakGaussians& weak, const Rect& box, int radius, int step,
                      int frame_width, int frame_height, double* scores, const CueMerge* cues) {
  const int n = grid_half_size(radius, step);
  const int side = 2 * n + 1;
  const long r2 = static_cast<long>(radius) * radius;

  // Gather the candidates that fit in the frame, in row-major order, as runs of
  // consecutive grid columns within one grid row (equally spaced in the table).
  std::vector<int> cand_dx, cand_dy;
  std::vector<GridRun> runs;
  // (room for the whole square grid at once: growing them candidate by candidate moved them
  // about a dozen times a search)
  cand_dx.reserve(static_cast<std::size_t>(side) * side);
  cand_dy.reserve(static_cast<std::size_t>(side) * side);
  runs.reserve(static_cast<std::size_t>(side));
  for (int j = -n; j <= n; ++j) {
    bool open = false;
    for (int i = -n; i <= n; ++i) {
      const long dx = static_cast<long>(i) * step, dy = static_cast<long>(j) * step;
      // 64-bit positions: box.x + dx and x + box.w must not wrap around near INT_MAX.
      const std::int64_t x = static_cast<std::int64_t>(box.x) + dx;
      const std::int64_t y = static_cast<std::int64_t>(box.y) + dy;
      const bool in = dx * dx + dy * dy < r2 && x >= 0 && y >= 0 && x + box.w <= frame_width &&
                      y + box.h <= frame_height;
      if (!in) {
        open = false;
        continue;
      }
      // Inside the frame, x and y fit in an int; the extent's corner may not.
      const std::int64_t ex = x + e.x, ey = y + e.y;
      if (ex > std::numeric_limits<int>::max() || ey > std::numeric_limits<int>::max() ||
          !ii.covers(Rect{static_cast<int>(ex), static_cast<int>(ey), e.w, e.h})) {
        throw std::out_of_range("score_grid: a candidate inside the frame is outside the integral image");
      }
      if (!open) {
        runs.push_back(GridRun{static_cast<int>(cand_dx.size()), 0,
                           (y - ii.y0()) * ii.stride() + (x - ii.x0())});
        open = true;
      }
      ++runs.back().count;
      cand_dx.push_back(static_cast<int>(dx));
      cand_dy.push_back(static_cast<int>(dy));
    }
  }
  const int c = static_cast<int>(cand_dx.size());
  GridResult result;
  result.candidates = c;
  if (scores != nullptr) {
    std::fill(scores, scores + side * side, -std::numeric_limits<double>::infinity());
  }
  if (c == 0) return result;

  // Feature values, one feature at a time over all candidates (run by run, several
  // candidates of a run a step: consecutive table entries), then the log ratios.
  std::vector<double> total(static_cast<std::size_t>(c), 0.0);
  const IntegralImage::Entry* table = ii.data();
  const bool vector = compiled.max_rect_area() <= kMaxSignedRectArea &&
                      (step == 1 || ii.num_channels() == 1);
  // The fused float score where the exact path is the rule (not MILTrack's guard, under which
  // every value takes the guarded path) on step-1 grids (a coarse grid's short runs of the
  // phase-split copy measured slower fused: fct 0.95x): the same choice on every build.
  const bool fused = vector && weak.guard() < 1e-15 && step == 1;
#ifdef WMILTRACK_GRID_SIMD
  const bool wide = vector && vmath::avx2();
  // A grid of step > 1 reads every step-th entry of a row: the vector loops read it from a
  // copy of the table's rows split by column phase (entry j of phase p is column p + j*step),
  // where a run's candidates are consecutive. The entries are copied exactly.
  GridTable grid{table, runs, compiled};
  if (vector && step > 1) grid = decimate(ii, e, step, runs, compiled);
  const IntegralImage::Entry* fused_table = grid.table;
  const std::vector<GridRun>& fused_runs = grid.runs;
  const CompiledFeatures::Corners* fused_corners = compiled.num_rects() > 0 ? grid.corners(0) : nullptr;
  const int fused_step = 1;
#else
  const IntegralImage::Entry* fused_table = table;
  const std::vector<GridRun>& fused_runs = runs;
  const CompiledFeatures::Corners* fused_corners =
      compiled.num_rects() > 0 ? &compiled.corners(0) : nullptr;
  const int fused_step = step;
#endif
  if (fused) {
    std::vector<FusedFeature> ff(static_cast<std::size_t>(compiled.size()));
    std::vector<float> wf(static_cast<std::size_t>(compiled.num_rects()));
    for (int r = 0; r < compiled.num_rects(); ++r) {
      wf[static_cast<std::size_t>(r)] = static_cast<float>(compiled.corners(r).weight);
    }
    for (int k = 0; k < compiled.size(); ++k) {
      const vmath::LogRatioTerms t = weak.terms(k);
      FusedFeature& f = ff[static_cast<std::size_t>(k)];
      f.r0 = compiled.first_rect(k);
      f.r1 = compiled.end_rect(k);
      f.centre = static_cast<float>(t.centre);
      f.mu1 = static_cast<float>(t.mu1);
      f.qa = static_cast<float>(t.qa);
      f.qb = static_cast<float>(t.qb);
      f.qc = static_cast<float>(t.qc);
      // The exact range narrowed to floats strictly inside the double one.
      f.lo = std::nextafter(static_cast<float>(t.lo), std::numeric_limits<float>::infinity());
      f.hi = std::nextafter(static_cast<float>(t.hi), -std::numeric_limits<float>::infinity());
      f.mu0 = static_cast<float>(t.mu0);
      f.a1 = static_cast<float>(t.a1);
      f.lb1 = static_cast<float>(t.lb1);
      f.a0 = static_cast<float>(t.a0);
      f.lb0 = static_cast<float>(t.lb0);
      f.ln_guard = static_cast<float>(std::log(weak.guard()));
    }
    fused_scores(fused_table, fused_runs, fused_step, fused_corners, wf.data(), ff, total.data());
  } else {
    std::vector<double> values(static_cast<std::size_t>(c));  // (the fused path needs none)
    for (int k = 0; k < compiled.size(); ++k) {
#ifdef WMILTRACK_GRID_SIMD
      const int r0 = compiled.first_rect(k), n_rects = compiled.end_rect(k) - r0;
      if (wide) {
        detail::grid_values_avx2(grid.table, grid.runs, grid.corners(r0), n_rects, values.data());
      } else if (vector) {
        detail::grid_values_sse2(grid.table, grid.runs, grid.corners(r0), n_rects, values.data());
      } else {
        grid_values_scalar(table, runs, step, compiled, k, values.data());
      }
#else
      grid_values_scalar(table, runs, step, compiled, k, values.data());
#endif
      weak.log_ratio(k, values.data(), c, total.data(), true, nullptr);
    }
  }

  int best = -1;
  if (cues != nullptr) {
    best = merged_best(*cues, box, cand_dx, cand_dy, step, total, result.candidates);
    if (best < 0) {
      result.candidates = 0;
      return result;
    }
  } else {
    for (int q = 0; q < c; ++q) {
      if (std::isnan(total[q])) continue;
      if (best < 0 || total[q] > total[best]) best = q;
    }
    if (best < 0) throw std::runtime_error("score_grid: every candidate scored NaN");
  }
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

}  // namespace

GridResult score_grid(const IntegralImage& ii, const FeatureBank& bank, const std::int32_t* selected,
                      int n_selected, const WeakGaussians& weak, const Rect& box, int radius,
                      int step, int frame_width, int frame_height, double* scores,
                      const CueMerge* cues) {
  check_grid(ii, n_selected, weak, box, radius, step);
  // Compiled first: a feature index outside the bank or a rectangle on a plane the integral
  // image lacks is an error even when no candidate fits in the frame.
  const CompiledFeatures compiled(bank, selected, n_selected, ii);
  return grid_stage(ii, bank.extent(), compiled, weak, box, radius, step, frame_width,
                    frame_height, scores, cues);
}

double template_fit(const IntegralImage& ii, const FeatureBank& bank, int x, int y,
                    const double* mu, const double* sigma) {
  const int m = bank.size();
  std::vector<double> t(static_cast<std::size_t>(m));
  project(ii, bank, nullptr, m, &x, &y, 1, t.data());
  for (int k = 0; k < m; ++k) {
    const double z = (t[k] - mu[k]) / sigma[k];
    t[k] = std::log1p(z * z);
  }
  return -((0.0 + pairwise_sum(t.data(), m, 1)) / static_cast<double>(m));
}

std::vector<GridResult> search(const IntegralImage& ii, const FeatureBank& bank,
                               const std::int32_t* selected, int n_selected,
                               const WeakGaussians& weak, Rect box,
                               const std::vector<SearchStage>& stages, int frame_width,
                               int frame_height, const CueMerge* cues) {
  std::vector<GridResult> out;
  out.reserve(stages.size());
  // The features are compiled once, for every stage (after the first stage's checks, in
  // score_grid's order).
  std::optional<CompiledFeatures> compiled;
  for (const SearchStage& stage : stages) {
    check_grid(ii, n_selected, weak, box, stage.radius, stage.step);
    if (!compiled) compiled.emplace(bank, selected, n_selected, ii);
    const GridResult r = grid_stage(ii, bank.extent(), *compiled, weak, box, stage.radius,
                                    stage.step, frame_width, frame_height, nullptr, cues);
    if (r.candidates > 0) {
      box.x += r.dx;
      box.y += r.dy;
    }
    out.push_back(r);
  }
  return out;
}

}  // namespace wmiltrack
