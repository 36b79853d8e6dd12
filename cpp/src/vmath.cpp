#include "wmiltrack/vmath.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>

// With WMILTRACK_AVX2_COPIES (x86-64, GCC/Clang) the loops are compiled twice, for AVX2 and for
// the baseline SSE2, and the AVX2 copy is taken when the CPU has it. The lane functions pass
// vectors by value, inlined into this file's loops only (GCC's -Wpsabi note about that
// ABI concerns calls across files: CMakeLists turns it off here).

namespace wmiltrack::vmath {

namespace {

inline std::uint64_t bits(double x) {
  std::uint64_t u;
  std::memcpy(&u, &x, sizeof u);
  return u;
}

inline double from_bits(std::uint64_t u) {
  double x;
  std::memcpy(&x, &u, sizeof x);
  return x;
}

// ln 2 in two parts: kLn2Hi has its low 32 bits zero, so k * kLn2Hi is exact for |k| < 2^20.
constexpr double kLn2Hi = 6.93147180369123816490e-01;
constexpr double kLn2Lo = 1.90821492927058770002e-10;
constexpr double kInvLn2 = 1.44269504088896338700e+00;
// Adding 1.5 * 2^52 rounds a double of magnitude < 2^51 to an integer, which then sits in
// the low bits of the sum.
constexpr double kRound = 6755399441055744.0;
constexpr double kSqrt2 = 1.41421356237309514547e+00;
constexpr double kTwo52 = 4503599627370496.0;
constexpr double kTwo54 = 18014398509481984.0;
constexpr double kMinNormal = 2.2250738585072014e-308;
constexpr std::uint64_t kMantissa = 0x000fffffffffffffULL;
constexpr std::uint64_t kOneBits = 0x3ff0000000000000ULL;
constexpr std::uint64_t kTwo52Bits = 0x4330000000000000ULL;

// The kernels (vmath_lanes.inc) are written once, for a lane type, and included once per
// width: GCC/Clang vectors of 2 doubles (the SSE2 copy) and of 4 (the AVX2 copy) on x86-64,
// plain double / uint64 / bool elsewhere. D holds the doubles, U as many unsigned 64-bit
// lanes, M the masks that comparisons give; `pick(m, a, b)` is the lane-wise m ? a : b. Every
// operation is the same IEEE operation at any width, so the bits are the same. first(x) is
// lane 0; all_true(m) whether every lane of a mask is set.
#ifdef WMILTRACK_AVX2_COPIES
#define WMILTRACK_VMATH_WIDTH(NS, N)                                  \
  namespace NS {                                                      \
  typedef double D __attribute__((vector_size(8 * N)));               \
  typedef std::uint64_t U __attribute__((vector_size(8 * N)));        \
  typedef std::int64_t M __attribute__((vector_size(8 * N)));         \
  typedef float F __attribute__((vector_size(8 * N)));                \
  typedef std::int32_t I __attribute__((vector_size(8 * N)));         \
  inline I as_i(F x) { return reinterpret_cast<I>(x); }               \
  inline F as_f(I u) { return reinterpret_cast<F>(u); }               \
  inline F to_f(I u) { return __builtin_convertvector(u, F); }        \
  constexpr int kLanes = N;                                           \
  constexpr int kFloatLanes = 2 * N;                                  \
  inline F splat_f(float v) { return F{} + v; }                       \
  inline U as_u(D x) { return reinterpret_cast<U>(x); }               \
  inline D as_d(U u) { return reinterpret_cast<D>(u); }               \
  inline D pick(M m, D a, D b) { return m ? a : b; }                  \
  inline U pick(M m, U a, U b) { return m ? a : b; }                  \
  inline D splat(double v) { return D{} + v; }                        \
  inline double first(D x) { return x[0]; }                          \
  inline bool all_true(M m) {                                         \
    bool all = true;                                                  \
    for (int q = 0; q < N; ++q) all = all && m[q] != 0;               \
    return all;                                                       \
  }                                                                   \
  }
WMILTRACK_VMATH_WIDTH(lanes2, 2)
WMILTRACK_VMATH_WIDTH(lanes4, 4)
#undef WMILTRACK_VMATH_WIDTH
namespace lanes2 {
#include "vmath_lanes.inc"
}  // namespace lanes2
namespace lanes4 {
#include "vmath_lanes.inc"
}  // namespace lanes4
namespace base_lanes = lanes2;
#else
namespace lanes1 {
typedef double D;
typedef std::uint64_t U;
typedef bool M;
typedef float F;
typedef std::int32_t I;
inline I as_i(F x) {
  I u;
  std::memcpy(&u, &x, sizeof u);
  return u;
}
inline F as_f(I u) {
  F x;
  std::memcpy(&x, &u, sizeof x);
  return x;
}
inline F to_f(I u) { return static_cast<F>(u); }
constexpr int kLanes = 1;
constexpr int kFloatLanes = 1;
inline F splat_f(float v) { return v; }
inline U as_u(D x) { return bits(x); }
inline D as_d(U u) { return from_bits(u); }
inline D pick(M m, D a, D b) { return m ? a : b; }
inline U pick(M m, U a, U b) { return m ? a : b; }
inline D splat(double v) { return v; }
inline double first(D x) { return x; }
inline bool all_true(M m) { return m; }
#include "vmath_lanes.inc"
}  // namespace lanes1
namespace base_lanes = lanes1;
#endif

}  // namespace

// The kernels, once per instruction set. Named (not file-local) so that a stripped module still
// labels them: tests/core/test_core_hardening.py checks that AVX instructions appear only in the
// *_avx2 kernels, which run only on a CPU that has AVX2.
namespace detail {
#define WMILTRACK_VMATH_LOOPS(SUFFIX, ATTR, NS)                                                \
  ATTR void weighted_rows_##SUFFIX(const double* a, int n, int width, const double* g,         \
                                   double* out) {                                              \
    NS::weighted_rows_impl(a, n, width, g, out);                                               \
  }                                                                                            \
  ATTR void weighted_rows_f32_##SUFFIX(const float* a, int n, int width, const float* g,       \
                                       float* out) {                                           \
    NS::weighted_rows_f32_impl(a, n, width, g, out);                                           \
  }                                                                                            \
  ATTR void exp_##SUFFIX(const double* x, double* y, int n) {                                  \
    NS::apply<NS::exp_lanes>(x, y, n);                                                         \
  }                                                                                            \
  ATTR void log_##SUFFIX(const double* x, double* y, int n) {                                  \
    NS::apply<NS::log_lanes>(x, y, n);                                                         \
  }                                                                                            \
  ATTR void log1p_##SUFFIX(const double* x, double* y, int n) {                                \
    NS::apply<NS::log1p_lanes>(x, y, n);                                                       \
  }                                                                                            \
  ATTR void log_ratio_##SUFFIX(const LogRatioTerms& t, const double* x, int n, double* out,    \
                               bool accumulate) {                                              \
    NS::log_ratio_impl(t, x, n, out, accumulate);                                              \
  }

WMILTRACK_VMATH_LOOPS(base, , base_lanes)
#ifdef WMILTRACK_AVX2_COPIES
WMILTRACK_VMATH_LOOPS(avx2, __attribute__((target("avx2"))), lanes4)
#endif
#undef WMILTRACK_VMATH_LOOPS
}  // namespace detail

namespace {

std::atomic<bool> g_portable{false};

}  // namespace

LogRatioTerms make_log_ratio_terms(double mu1, double a1, double lb1, double mu0, double a0,
                                   double lb0, double guard, double cut) {
  LogRatioTerms t{mu1, a1, lb1, mu0, a0, lb0, guard, cut};
  // Centred on the sharper class (the larger a): the cross terms then carry the smaller a, so
  // that their rounding stays at the scale of h (centred on the wider class, a tiny sigma's
  // a (mu_1 - mu_0)^2 would cancel against itself).
  const double delta = mu1 - mu0;
  const double inf = __builtin_huge_val();
  double r1 = -inf, r0 = -inf;  // l_c > cut  <=>  |x - mu_c| < r_c (none when lb_c <= cut)
  if (lb1 > cut) r1 = std::sqrt((lb1 - cut) / a1);
  if (lb0 > cut) r0 = std::sqrt((lb0 - cut) / a0);
  double lo, hi;  // the range of d = x - centre where both hold
  if (a1 >= a0) {
    t.centre = mu1;
    t.qb = 2.0 * a0 * delta;
    t.qc = (lb1 - lb0) + a0 * (delta * delta);
    lo = std::max(-r1, -delta - r0);
    hi = std::min(r1, -delta + r0);
  } else {
    t.centre = mu0;
    t.qb = 2.0 * a1 * delta;
    t.qc = (lb1 - lb0) - a1 * (delta * delta);
    lo = std::max(-r0, delta - r1);
    hi = std::min(r0, delta + r1);
  }
  t.qa = a0 - a1;
  t.lo = inf;
  t.hi = -inf;  // empty: never exact
  if (r1 > 0.0 && r0 > 0.0 && lo < hi) {
    t.lo = lo;
    t.hi = hi;
  }
  return t;
}

bool avx2() {
#ifdef WMILTRACK_AVX2_COPIES
  static const bool has = __builtin_cpu_supports("avx2");
  return has && !g_portable.load(std::memory_order_relaxed);
#else
  return false;
#endif
}

void exp(const double* x, double* y, int n) {
#ifdef WMILTRACK_AVX2_COPIES
  if (avx2()) return detail::exp_avx2(x, y, n);
#endif
  detail::exp_base(x, y, n);
}

void log(const double* x, double* y, int n) {
#ifdef WMILTRACK_AVX2_COPIES
  if (avx2()) return detail::log_avx2(x, y, n);
#endif
  detail::log_base(x, y, n);
}

void log1p(const double* x, double* y, int n) {
#ifdef WMILTRACK_AVX2_COPIES
  if (avx2()) return detail::log1p_avx2(x, y, n);
#endif
  detail::log1p_base(x, y, n);
}

void log_ratio(const LogRatioTerms& t, const double* x, int n, double* out, bool accumulate) {
#ifdef WMILTRACK_AVX2_COPIES
  if (avx2()) return detail::log_ratio_avx2(t, x, n, out, accumulate);
#endif
  detail::log_ratio_base(t, x, n, out, accumulate);
}

void weighted_rows(const double* a, int n, int width, const double* g, double* out) {
#ifdef WMILTRACK_AVX2_COPIES
  if (avx2()) return detail::weighted_rows_avx2(a, n, width, g, out);
#endif
  detail::weighted_rows_base(a, n, width, g, out);
}

void weighted_rows_f32(const float* a, int n, int width, const float* g, float* out) {
#ifdef WMILTRACK_AVX2_COPIES
  if (avx2()) return detail::weighted_rows_f32_avx2(a, n, width, g, out);
#endif
  detail::weighted_rows_f32_base(a, n, width, g, out);
}

const char* isa() {
#ifdef WMILTRACK_AVX2_COPIES
  return avx2() ? "avx2" : "sse2";
#else
  return "scalar";
#endif
}

// (Without WMILTRACK_AVX2_COPIES there is one path and g_portable is never read.)
void force_portable(bool portable) { g_portable.store(portable, std::memory_order_relaxed); }

}  // namespace wmiltrack::vmath
