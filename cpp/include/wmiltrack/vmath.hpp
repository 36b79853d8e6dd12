// exp, log and log1p over arrays of doubles, several values per instruction; the weak
// classifiers' guarded log ratio built on them; and one matrix-vector product with a fixed
// order of summation.
//
// Why not the C library: glibc's scalar exp/log cost 5-20 ns a call, and the learning and
// scoring kernels make thousands of such calls a frame (WMIL selection: three per instance per
// round; the MILTrack guard: three per feature value). These run 4 values at a time with AVX2
// (chosen at run time when the CPU has it) and 2 with the SSE2 baseline, at a few ns a value.
//
// Same bits everywhere: each function is one fixed sequence of IEEE additions, multiplications
// and divisions and integer bit operations (no FMA: the core is built with -ffp-contract=off),
// so the AVX2 and SSE2 copies, a scalar build, and every x86-64 CPU give the same result for the
// same input.
// The results are not the C library's: both are within about 1 ulp of the true value, and may
// differ from each other in the last bit.
//
// Algorithms (fdlibm's, as in Sun's freely distributable libm): exp reduces x = k ln2 + r with
// a two-part ln2 and evaluates exp(r) in fdlibm's rational form from a degree-5 polynomial in
// r^2; log writes x = 2^k m, m in [sqrt(1/2), sqrt(2)), and evaluates log(m) through
// s = (m-1)/(m+1) with a degree-7 polynomial in s^2; log1p(x) is log(1 + x) plus the rounding
// error of 1 + x, divided by 1 + x (exact to first order, so tiny x keep full relative
// precision).
//
// Special values: exp(-inf) = 0, exp(+inf) = +inf, exp overflows to +inf above ~709.78 and
// underflows (through the subnormals) to 0 below ~-745.13; log(0) = -inf, log(+inf) = +inf,
// log of a negative number is NaN; log1p(-1) = -inf, log1p(x < -1) = NaN; NaN gives NaN.
#pragma once

// Kernels compiled twice, for AVX2 and for the baseline, with the same bits: on x86-64 with
// GCC/Clang. WMILTRACK_KERNEL marks a body to be inlined into each copy (so that it is compiled
// for that copy's instruction set).
#if (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__) && !defined(WMILTRACK_NO_SIMD)
#define WMILTRACK_AVX2_COPIES 1
#define WMILTRACK_KERNEL inline __attribute__((always_inline))
#else
#define WMILTRACK_KERNEL inline
#endif

namespace wmiltrack::vmath {

// y[i] = exp(x[i]) for i < n. x and y may be the same array.
void exp(const double* x, double* y, int n);

// y[i] = log(x[i]) for i < n. x and y may be the same array.
void log(const double* x, double* y, int n);

// y[i] = log(1 + x[i]) for i < n. x and y may be the same array.
void log1p(const double* x, double* y, int n);

// out[m] = sum_j a[j * width + m] * g[j] for m < width, each sum adding its terms in the order
// j = 0, 1, ..., n - 1 from 0.0 (so the bits are those of a plain loop over j), several m at a
// time. The weighted-MIL selection scores every feature with this in each round.
void weighted_rows(const double* a, int n, int width, const double* g, double* out);
// The same in float (products and sums in float, each sum in the order j = 0, 1, ...): twice
// the values per instruction and half the bytes; the weighted-MIL selection's scores.
void weighted_rows_f32(const float* a, int n, int width, const float* g, float* out);

// One weak classifier's guarded Gaussian log ratio (scoring.hpp's WeakGaussians, which owns the
// formula): l_c(x) = lb_c - (x - mu_c)^2 a_c and
//   h(x) = l_1 - l_0                                  where both l_c > cut (the guard cannot
//                                                     change a double there),
//   h(x) = log((exp(l_1) + guard) / (exp(l_0) + guard)) elsewhere, with this file's exp/log.
//   Where both l_c > cut, h is computed as C + d (B + A d) with d = x - centre, the centre
//   being the mean of the sharper class (the larger a_c), A = a_0 - a_1 and B, C to match: the
//   same function in 5 operations instead of 9, equal up to rounding at the scale of h; "both
//   l_c > cut" is tested as lo < d < hi. make_log_ratio_terms fills these.
struct LogRatioTerms {
  double mu1, a1, lb1, mu0, a0, lb0, guard, cut;
  double centre = 0.0, qa = 0.0, qb = 0.0, qc = 0.0, lo = 0.0, hi = 0.0;
};
LogRatioTerms make_log_ratio_terms(double mu1, double a1, double lb1, double mu0, double a0,
                                   double lb0, double guard, double cut);

// out[i] = h(x[i]) (or out[i] += h(x[i]) with accumulate) for i < n; each value depends on its
// own x alone.
void log_ratio(const LogRatioTerms& t, const double* x, int n, double* out, bool accumulate);

// Whether this CPU takes the AVX2 copies (false when forced portable, or on a build without
// them). Other kernels of the core that have an AVX2 copy (WMILTRACK_AVX2_COPIES) ask this.
bool avx2();

// Which code path the calls above take on this CPU: "avx2" or "sse2" on x86-64 with GCC/Clang,
// "scalar" otherwise (one value at a time). The results are the same on every path.
const char* isa();

// For tests and benchmarks: force the baseline copies (true) or go back to the CPU's best
// (false). Process-wide; meant to be set while no tracker runs.
void force_portable(bool portable);

}  // namespace wmiltrack::vmath
