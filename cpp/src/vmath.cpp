#include "wmiltrack/vmath.hpp"

#include <atomic>
#include <cstdint>
#include <cstring>

// With WMILTRACK_AVX2_COPIES (x86-64, GCC/Clang) the loops are compiled twice, for AVX2 and for
// the baseline SSE2, and the AVX2 copy is taken when the CPU has it. The lane functions pass
// 32-byte vectors by value, inlined into this file's loops only (GCC's -Wpsabi note about that
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

// The three functions are written once, for a lane type: GCC/Clang vectors of 4 doubles (D)
// with 4 unsigned 64-bit lanes (U) and 4 signed masks (M) on x86-64, plain double / uint64 /
// bool elsewhere. Every operation is the same IEEE operation in either form, so the bits are
// the same; comparisons give masks, and `pick(m, a, b)` is the lane-wise m ? a : b.
#ifdef WMILTRACK_AVX2_COPIES
typedef double D __attribute__((vector_size(32)));
typedef std::uint64_t U __attribute__((vector_size(32)));
typedef std::int64_t M __attribute__((vector_size(32)));
constexpr int kLanes = 4;
inline U as_u(D x) { return reinterpret_cast<U>(x); }
inline D as_d(U u) { return reinterpret_cast<D>(u); }
inline D pick(M m, D a, D b) { return m ? a : b; }
inline U pick(M m, U a, U b) { return m ? a : b; }
inline D splat(double v) { return D{v, v, v, v}; }
#else
typedef double D;
typedef std::uint64_t U;
typedef bool M;
constexpr int kLanes = 1;
inline U as_u(D x) { return bits(x); }
inline D as_d(U u) { return from_bits(u); }
inline D pick(M m, D a, D b) { return m ? a : b; }
inline U pick(M m, U a, U b) { return m ? a : b; }
inline D splat(double v) { return v; }
#endif

WMILTRACK_KERNEL D exp_lanes(D x) {
  // Clamp far outside the finite range (NaN passes through: both comparisons are false).
  D xc = pick(x < -746.0, splat(-746.0), x);
  xc = pick(xc > 710.0, splat(710.0), xc);
  const D t = xc * kInvLn2 + kRound;
  const D kd = t - kRound;  // k = round(x / ln 2), as a double
  const D hi = xc - kd * kLn2Hi;
  const D lo = kd * kLn2Lo;
  const D r = hi - lo;  // |r| <= ln2 / 2
  const D r2 = r * r;
  const D c =
      r - r2 * (1.66666666666666019037e-01 +
                r2 * (-2.77777777770155933842e-03 +
                      r2 * (6.61375632143793436117e-05 +
                            r2 * (-1.65339022054652515390e-06 + r2 * 4.13813679705723846039e-08))));
  const D y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi);  // exp(r)
  // 2^k in two factors 2^k1 2^k2 (k1 = floor(k / 2)), each a normal double for every k the
  // clamp allows, so that results in the subnormal range and overflow come out right.
  const U k = as_u(t) - bits(kRound) + 2048;  // k + 2048 > 0
  const U k1 = k >> 1;                        // floor(k / 2) + 1024
  const U k2 = k - k1;                        // k - floor(k / 2) + 1024
  return y * as_d((k1 - 1) << 52) * as_d((k2 - 1) << 52);
}

WMILTRACK_KERNEL D log_lanes(D x) {
  // Subnormals are scaled into the normal range first.
  const M tiny = x < kMinNormal;
  const D xs = pick(tiny, x * kTwo54, x);
  const U u = as_u(xs);
  // The exponent, biased by 2048 so that it stays positive, and the mantissa in [1, 2),
  // halved (and the exponent raised) above sqrt(2).
  U e = ((u >> 52) & 0x7ff) + 1025;
  D m = as_d((u & kMantissa) | kOneBits);
  const M big = m > kSqrt2;
  m = pick(big, m * 0.5, m);
  e = pick(big, e + 1, e);
  // k as a double: the biased exponent in the mantissa of 2^52, less 2^52 and the bias.
  const D kd = ((as_d(kTwo52Bits | e) - kTwo52) - 2048.0) - pick(tiny, splat(54.0), splat(0.0));
  const D f = m - 1.0;
  const D s = f / (2.0 + f);
  const D z = s * s;
  const D w = z * z;
  const D t1 = w * (3.999999999940941908e-01 +
                    w * (2.222219843214978396e-01 + w * 1.531383769920937332e-01));
  const D t2 = z * (6.666666666666735130e-01 +
                    w * (2.857142874366239149e-01 +
                         w * (1.818357216161805012e-01 + w * 1.479819860511658591e-01)));
  const D R = t2 + t1;
  const D hfsq = 0.5 * f * f;
  const D y = kd * kLn2Hi - ((hfsq - (s * (hfsq + R) + kd * kLn2Lo)) - f);
  // Special values: log(0) = -inf, log(x < 0) = NaN, log(inf) = inf, log(NaN) = NaN.
  const double inf = __builtin_huge_val();
  D out = pick(x == 0.0, splat(-inf), y);
  out = pick(x < 0.0, splat(__builtin_nan("")), out);
  out = pick(x == inf, splat(inf), out);
  return pick(x == x, out, x);
}

WMILTRACK_KERNEL D log1p_lanes(D x) {
  const D u = 1.0 + x;
  // The rounding error of 1 + x (exact for |x| <= 1; for larger x it is that of u - x).
  const D c = pick(u >= 2.0, 1.0 - (u - x), x - (u - 1.0));
  const D y = log_lanes(u) + c / u;
  // u == 1: log(u) = 0 and c = x, so y = x. x = -1: -inf; x = inf: inf (c would be NaN).
  const double inf = __builtin_huge_val();
  return pick(u == inf, splat(inf), pick(u == 0.0, splat(-inf), y));
}

// y[i] = f(x[i]), kLanes values a step; the last, partial step goes through a padded copy.
template <D (*F)(D)>
WMILTRACK_KERNEL void apply(const double* x, double* y, int n) {
  int i = 0;
  for (; i + kLanes <= n; i += kLanes) {
    D v;
    std::memcpy(&v, x + i, sizeof v);
    v = F(v);
    std::memcpy(y + i, &v, sizeof v);
  }
  if (i < n) {
    double buf[kLanes] = {};
    std::memcpy(buf, x + i, sizeof(double) * static_cast<std::size_t>(n - i));
    D v;
    std::memcpy(&v, buf, sizeof v);
    v = F(v);
    std::memcpy(buf, &v, sizeof v);
    std::memcpy(y + i, buf, sizeof(double) * static_cast<std::size_t>(n - i));
  }
}

// weighted_rows: 4 * kLanes sums at a time in registers, each adding a[j][m] g[j] in the order
// j = 0, 1, ...; then kLanes at a time, then one at a time, the same way.
WMILTRACK_KERNEL void weighted_rows_impl(const double* a, int n, int width, const double* g,
                                        double* out) {
  constexpr int kVectors = 4;
  constexpr int kBlock = kVectors * kLanes;
  const std::size_t stride = static_cast<std::size_t>(width);
  int m0 = 0;
  for (; m0 + kBlock <= width; m0 += kBlock) {
    D acc[kVectors];
    for (D& v : acc) v = splat(0.0);
    for (int j = 0; j < n; ++j) {
      const double* row = a + static_cast<std::size_t>(j) * stride + m0;
      const D gj = splat(g[j]);
      for (int v = 0; v < kVectors; ++v) {
        D r;
        std::memcpy(&r, row + v * kLanes, sizeof r);
        acc[v] = acc[v] + r * gj;
      }
    }
    std::memcpy(out + m0, acc, sizeof acc);
  }
  for (; m0 + kLanes <= width; m0 += kLanes) {  // then one vector at a time
    D acc = splat(0.0);
    for (int j = 0; j < n; ++j) {
      D r;
      std::memcpy(&r, a + static_cast<std::size_t>(j) * stride + m0, sizeof r);
      acc = acc + r * splat(g[j]);
    }
    std::memcpy(out + m0, &acc, sizeof acc);
  }
  for (int m = m0; m < width; ++m) {
    double acc = 0.0;
    for (int j = 0; j < n; ++j) acc = acc + a[static_cast<std::size_t>(j) * stride + m] * g[j];
    out[m] = acc;
  }
}

}  // namespace

// The kernels, once per instruction set. Named (not file-local) so that a stripped module still
// labels them: tests/test_core_hardening.py checks that AVX instructions appear only in the
// *_avx2 kernels, which run only on a CPU that has AVX2.
namespace detail {
#define WMILTRACK_VMATH_LOOPS(SUFFIX, ATTR)                                                    \
  ATTR void weighted_rows_##SUFFIX(const double* a, int n, int width, const double* g,         \
                                   double* out) {                                              \
    weighted_rows_impl(a, n, width, g, out);                                                   \
  }                                                                                            \
  ATTR void exp_##SUFFIX(const double* x, double* y, int n) { apply<exp_lanes>(x, y, n); }     \
  ATTR void log_##SUFFIX(const double* x, double* y, int n) { apply<log_lanes>(x, y, n); }     \
  ATTR void log1p_##SUFFIX(const double* x, double* y, int n) { apply<log1p_lanes>(x, y, n); }

WMILTRACK_VMATH_LOOPS(base, )
#ifdef WMILTRACK_AVX2_COPIES
WMILTRACK_VMATH_LOOPS(avx2, __attribute__((target("avx2"))))
#endif
#undef WMILTRACK_VMATH_LOOPS
}  // namespace detail

namespace {

std::atomic<bool> g_portable{false};

#ifdef WMILTRACK_AVX2_COPIES
bool use_avx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has && !g_portable.load(std::memory_order_relaxed);
}
#endif

}  // namespace

void exp(const double* x, double* y, int n) {
#ifdef WMILTRACK_AVX2_COPIES
  if (use_avx2()) return detail::exp_avx2(x, y, n);
#endif
  detail::exp_base(x, y, n);
}

void log(const double* x, double* y, int n) {
#ifdef WMILTRACK_AVX2_COPIES
  if (use_avx2()) return detail::log_avx2(x, y, n);
#endif
  detail::log_base(x, y, n);
}

void log1p(const double* x, double* y, int n) {
#ifdef WMILTRACK_AVX2_COPIES
  if (use_avx2()) return detail::log1p_avx2(x, y, n);
#endif
  detail::log1p_base(x, y, n);
}

void weighted_rows(const double* a, int n, int width, const double* g, double* out) {
#ifdef WMILTRACK_AVX2_COPIES
  if (use_avx2()) return detail::weighted_rows_avx2(a, n, width, g, out);
#endif
  detail::weighted_rows_base(a, n, width, g, out);
}

bool avx2() {
#ifdef WMILTRACK_AVX2_COPIES
  return use_avx2();
#else
  return false;
#endif
}

const char* isa() {
#ifdef WMILTRACK_AVX2_COPIES
  return use_avx2() ? "avx2" : "sse2";
#else
  return "scalar";
#endif
}

void force_portable(bool portable) { g_portable.store(portable, std::memory_order_relaxed); }
// (Without the x86-64 build g_portable is never read: there is one path.)

}  // namespace wmiltrack::vmath
