// Internal to the core: exp and log in float, written once for a float type F (float, or a GCC
// vector of floats) and its int32 twin I, with plain IEEE float operations and integer bit
// operations in one fixed order, so that a value gives the same bits alone or as a lane of any
// vector (no FMA: the core is built with -ffp-contract=off). Used by the search's fused score
// (scoring.cpp) where a log ratio leaves the exact path.
#pragma once

#include <cstdint>
#include <cstring>
#include <type_traits>

namespace wmiltrack::fmath {

template <class To, class From>
inline To bit_cast(const From& x) {
  static_assert(sizeof(To) == sizeof(From), "bit_cast: sizes differ");
  To y;
  std::memcpy(&y, &x, sizeof y);
  return y;
}

// The int32 lanes as floats (exact below 2^24, rounded to nearest above).
template <class F, class I>
inline F to_float(I i) {
  if constexpr (std::is_same_v<I, std::int32_t>) {
    return static_cast<F>(i);
  } else {
    return __builtin_convertvector(i, F);
  }
}

// e^x for x clamped to [-87, 88] (NaN gives NaN): x = k ln2 + r, |r| <= ln2 / 2, e^r by a
// degree-7 polynomial (Cephes' expf coefficients), times 2^k built in the exponent bits.
template <class F, class I>
inline __attribute__((always_inline)) F exp_f(F x) {
  const F lo = F{} - 87.0f, hi = F{} + 88.0f;
  x = x < lo ? lo : x;
  x = x > hi ? hi : x;
  const F magic = F{} + 12582912.0f;  // 1.5 * 2^23: adding it rounds to an integer
  const F t = x * 1.44269504088896341f + magic;
  const F kf = t - magic;
  const F r = (x - kf * 0.693359375f) - kf * -2.12194440e-4f;
  F p = F{} + 1.9875691500e-4f;
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  const F y = (p * (r * r) + r) + 1.0f;
  const I k = bit_cast<I>(t) - bit_cast<I>(magic);
  return y * bit_cast<F>((k + 127) << 23);
}

// log x for positive normal x (NaN gives NaN): x = 2^e m, m in [sqrt(1/2), sqrt(2)),
// log m = f - f^2 / 2 + f^3 P(f) with f = m - 1 (Cephes' logf coefficients).
template <class F, class I>
inline __attribute__((always_inline)) F log_f(F x) {
  const I u = bit_cast<I>(x);
  I e = ((u >> 23) & 0xff) - 127;
  F m = bit_cast<F>((u & 0x7fffff) | 0x3f800000);
  const auto big = m > 1.41421356f;
  m = big ? m * 0.5f : m;
  e = big ? e + 1 : e;
  const F f = m - 1.0f;
  const F z = f * f;
  F y = F{} + 7.0376836292e-2f;
  y = y * f - 1.1514610310e-1f;
  y = y * f + 1.1676998740e-1f;
  y = y * f - 1.2420140846e-1f;
  y = y * f + 1.4249322787e-1f;
  y = y * f - 1.6668057665e-1f;
  y = y * f + 2.0000714765e-1f;
  y = y * f - 2.4999993993e-1f;
  y = y * f + 3.3333331174e-1f;
  y = (y * f) * z;
  const F ef = to_float<F, I>(e);
  y = y + ef * -2.12194440e-4f;
  y = y - 0.5f * z;
  const F out = (f + y) + ef * 0.693359375f;
  return x == x ? out : x;
}

// Whether every lane of a comparison's result is true (a bool, or a GCC vector mask).
template <class M>
inline __attribute__((always_inline)) bool all_of(M m) {
  if constexpr (std::is_same_v<M, bool>) {
    return m;
  } else {
    std::uint64_t w[sizeof(M) / 8];
    std::memcpy(w, &m, sizeof w);
    std::uint64_t all = ~std::uint64_t{0};
    for (std::uint64_t x : w) all &= x;
    return all == ~std::uint64_t{0};
  }
}

// log(e^l1 + g) - log(e^l0 + g) given ln g, each term as max(l, ln g) + log(1 + e^-|l - ln g|)
// (for any l: no overflow). Where every lane of both terms lies more than 17 from ln g,
// e^-|l - ln g| < 2^-24, so 1 + it rounds to 1 and log_f(1) is 0: the logs are exactly 0 and
// are not computed, with the same bits (the search's candidates far from the target, whose
// densities are far below the guard, take this path).
template <class F, class I>
inline __attribute__((always_inline)) F log_exp_plus_diff(F l1, F l0, float ln_g) {
  const F t1 = l1 - ln_g, t0 = l0 - ln_g;
  const F top1 = t1 > 0.0f ? l1 : F{} + ln_g;
  const F top0 = t0 > 0.0f ? l0 : F{} + ln_g;
  const F neg1 = t1 > 0.0f ? -t1 : t1;
  const F neg0 = t0 > 0.0f ? -t0 : t0;
  if (all_of(neg1 < -17.0f) && all_of(neg0 < -17.0f)) return (top1 + 0.0f) - (top0 + 0.0f);
  return (top1 + log_f<F, I>(1.0f + exp_f<F, I>(neg1))) - (top0 + log_f<F, I>(1.0f + exp_f<F, I>(neg0)));
}

}  // namespace wmiltrack::fmath
