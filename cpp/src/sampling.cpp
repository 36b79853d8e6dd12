#include "wmiltrack/sampling.hpp"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "wmiltrack/learning.hpp"

namespace wmiltrack {

namespace {

// Smallest all-ones bit mask >= max.
std::uint64_t mask_of(std::uint64_t max) {
  std::uint64_t mask = max;
  mask |= mask >> 1;
  mask |= mask >> 2;
  mask |= mask >> 4;
  mask |= mask >> 8;
  mask |= mask >> 16;
  mask |= mask >> 32;
  return mask;
}

// A uniform integer in [0, rng] as numpy's random_bounded_uint64(bitgen, 0, rng, 0, false)
// draws it for rng < 2^32 - 1: Lemire's multiply-and-reject on 32-bit draws.
std::uint64_t bounded(BitSource& bits, std::uint64_t rng) {
  if (rng == 0) return 0;
  const std::uint32_t r = static_cast<std::uint32_t>(rng);
  const std::uint32_t excl = r + 1;
  std::uint64_t m = static_cast<std::uint64_t>(bits.next_uint32(bits.state)) * excl;
  std::uint32_t leftover = static_cast<std::uint32_t>(m & 0xFFFFFFFFULL);
  if (leftover < excl) {
    const std::uint32_t threshold = (UINT32_MAX - r) % excl;
    while (leftover < threshold) {
      m = static_cast<std::uint64_t>(bits.next_uint32(bits.state)) * excl;
      leftover = static_cast<std::uint32_t>(m & 0xFFFFFFFFULL);
    }
  }
  return m >> 32;
}

bool inside(std::int64_t x, std::int64_t y, const Rect& box, int frame_w, int frame_h) {
  return x >= 0 && y >= 0 && x + box.w <= frame_w && y + box.h <= frame_h;
}

}  // namespace

std::vector<std::int64_t> choice_sorted(BitSource& bits, std::int64_t n, std::int64_t k) {
  if (k < 0 || k > n) throw std::invalid_argument("choice: need 0 <= k <= n");
  if (n > 10000 && k > n / 50) {
    throw std::invalid_argument("choice: numpy shuffles the tail for n > 10000 and k > n / 50; "
                                "not reproduced here");
  }
  if (n > 0xFFFFFFFELL) throw std::invalid_argument("choice: n must be below 2^32 - 1");
  std::vector<std::int64_t> picks(static_cast<std::size_t>(k));
  // Floyd's algorithm with numpy's open-addressing set of 1 + mask(1.2 k) slots.
  const std::uint64_t mask = mask_of(static_cast<std::uint64_t>(1.2 * static_cast<double>(k)));
  std::vector<std::uint64_t> set(mask + 1, UINT64_MAX);
  for (std::int64_t j = n - k; j < n; ++j) {
    const std::uint64_t val = bounded(bits, static_cast<std::uint64_t>(j));
    std::uint64_t loc = val & mask;
    while (set[loc] != UINT64_MAX && set[loc] != val) loc = (loc + 1) & mask;
    std::uint64_t pick = val;
    if (set[loc] != UINT64_MAX) {  // val taken already: j instead
      pick = static_cast<std::uint64_t>(j);
      loc = pick & mask;
      while (set[loc] != UINT64_MAX) loc = (loc + 1) & mask;
    }
    set[loc] = pick;
    picks[static_cast<std::size_t>(j - (n - k))] = static_cast<std::int64_t>(pick);
  }
  // numpy then shuffles the picks (its draws must be made; the order is dropped by sorting).
  for (std::int64_t i = k - 1; i >= 1; --i) {
    const std::uint64_t j = bounded(bits, static_cast<std::uint64_t>(i));
    std::swap(picks[static_cast<std::size_t>(i)], picks[static_cast<std::size_t>(j)]);
  }
  std::sort(picks.begin(), picks.end());
  return picks;
}

#if defined(__SIZEOF_INT128__)
namespace {
__extension__ typedef unsigned __int128 U128;  // (GCC and Clang)
// PCG64's LCG multiplier (PCG_DEFAULT_MULTIPLIER_128).
constexpr U128 kPcgMult = (static_cast<U128>(0x2360ED051FC65DA4ULL) << 64) | 0x4385DF649FCCF645ULL;

U128 load128(const std::uint64_t* w) { return (static_cast<U128>(w[1]) << 64) | w[0]; }
void store128(U128 v, std::uint64_t* w) {
  w[0] = static_cast<std::uint64_t>(v);
  w[1] = static_cast<std::uint64_t>(v >> 64);
}

// The double numpy makes of PCG64's output at state s (XSL-RR, then the top 53 bits).
double pcg_double(U128 s) {
  const std::uint64_t hi = static_cast<std::uint64_t>(s >> 64);
  const std::uint64_t x = hi ^ static_cast<std::uint64_t>(s);
  const unsigned rot = static_cast<unsigned>(hi >> 58);
  const std::uint64_t out = (x >> rot) | (x << ((64u - rot) & 63u));
  return static_cast<double>(out >> 11) * (1.0 / 9007199254740992.0);
}
}  // namespace

double pcg64_next_double(std::uint64_t* s) {
  const U128 next = load128(s) * kPcgMult + load128(s + 2);
  store128(next, s);
  return pcg_double(next);
}
#else
double pcg64_next_double(std::uint64_t* /*s*/) {
  throw std::logic_error("pcg64_next_double: no 128-bit integers on this build");
}
#endif

std::vector<std::int64_t> bernoulli_first(BitSource& bits, std::int64_t n, double p, std::int64_t limit) {
  std::vector<std::int64_t> kept;
  const auto take = [&](std::int64_t i, double u) {
    if (u < p && static_cast<std::int64_t>(kept.size()) < limit) kept.push_back(i);
  };
  std::int64_t i = 0;
#if defined(__SIZEOF_INT128__)
  if (bits.pcg64_state != nullptr) {
    // Four interleaved chains, each a jump of four steps (s -> m4 s + c4), so that four
    // 128-bit multiplies are in flight; then single steps, and the state after the n-th draw
    // written back.
    const U128 inc = load128(bits.pcg64_state + 2);
    U128 s = load128(bits.pcg64_state);
    if (n >= 4) {
      const U128 m2 = kPcgMult * kPcgMult, m4 = m2 * m2;
      const U128 c4 = inc * (m2 * kPcgMult + m2 + kPcgMult + 1);
      U128 a = s * kPcgMult + inc;
      U128 b = a * kPcgMult + inc;
      U128 c = b * kPcgMult + inc;
      U128 d = c * kPcgMult + inc;
      for (; i + 4 <= n; i += 4) {
        take(i, pcg_double(a));
        take(i + 1, pcg_double(b));
        take(i + 2, pcg_double(c));
        take(i + 3, pcg_double(d));
        s = d;
        a = a * m4 + c4;
        b = b * m4 + c4;
        c = c * m4 + c4;
        d = d * m4 + c4;
      }
    }
    for (; i < n; ++i) {
      s = s * kPcgMult + inc;
      take(i, pcg_double(s));
    }
    store128(s, bits.pcg64_state);
    return kept;
  }
#endif
  for (; i < n; ++i) take(i, bits.next_double(bits.state));
  return kept;
}

Rect offsets_extent(const std::int32_t* xy, int n) {
  if (n <= 0) throw std::invalid_argument("offsets_extent: no offsets");
  std::int32_t x0 = xy[0], x1 = x0, y0 = xy[1], y1 = y0;
  for (int i = 1; i < n; ++i) {
    x0 = std::min(x0, xy[2 * i]);
    x1 = std::max(x1, xy[2 * i]);
    y0 = std::min(y0, xy[2 * i + 1]);
    y1 = std::max(y1, xy[2 * i + 1]);
  }
  return Rect{x0, y0, x1 - x0, y1 - y0};
}

// The positives' instance weights (WMIL's), from their terms, as numpy computes them.
static void weigh_positives(const BagSpec& spec, const std::vector<double>& terms, Bags& bags) {
  const std::size_t np = static_cast<std::size_t>(bags.n_pos);
  switch (spec.weights) {
    case InstanceWeights::kNone:
      break;
    case InstanceWeights::kExp: {
      const double sum = 0.0 + pairwise_sum(terms.data(), bags.n_pos, 1);  // numpy's w.sum()
      for (const double t : terms) bags.w_pos.push_back(t / sum);
      break;
    }
    case InstanceWeights::kExpSq:
      bags.w_pos = terms;
      break;
    case InstanceWeights::kUniform:
      bags.w_pos.assign(np, 1.0 / static_cast<double>(np));
      break;
  }
}

Bags sample_bags(const BagSpec& spec, const Rect& box, int frame_w, int frame_h, BitSource& bits) {
  Bags bags;
  std::vector<double> terms;
  // (room for the positives and the most negatives the spec draws, so the bags grow once)
  const std::size_t most = static_cast<std::size_t>(spec.n_pos_offsets) +
                           static_cast<std::size_t>(std::max(spec.neg_count, 0));
  bags.xs.reserve(most);
  bags.ys.reserve(most);
  if (spec.pos_terms != nullptr) terms.reserve(static_cast<std::size_t>(spec.n_pos_offsets));
  for (int i = 0; i < spec.n_pos_offsets; ++i) {
    const std::int64_t x = static_cast<std::int64_t>(box.x) + spec.pos[2 * i];
    const std::int64_t y = static_cast<std::int64_t>(box.y) + spec.pos[2 * i + 1];
    if (!inside(x, y, box, frame_w, frame_h)) continue;
    bags.xs.push_back(static_cast<std::int32_t>(x));
    bags.ys.push_back(static_cast<std::int32_t>(y));
    if (spec.pos_terms != nullptr) terms.push_back(spec.pos_terms[i]);
  }
  bags.n_pos = static_cast<int>(bags.xs.size());
  weigh_positives(spec, terms, bags);
  // The negatives' candidates: the offsets whose box lies inside the frame, in order. Where
  // the offsets' bounding box lies inside (the usual case, away from the frame's edges), that
  // is all of them, and they are not copied.
  const int n_off = spec.n_neg_offsets;
  const Rect e = spec.neg_extent ? *spec.neg_extent
                                 : (n_off > 0 ? offsets_extent(spec.neg, n_off) : Rect{});
  const bool all_inside =
      n_off > 0 &&
      inside(static_cast<std::int64_t>(box.x) + e.x, static_cast<std::int64_t>(box.y) + e.y, box,
             frame_w, frame_h) &&
      inside(static_cast<std::int64_t>(box.x) + e.x + e.w,
             static_cast<std::int64_t>(box.y) + e.y + e.h, box, frame_w, frame_h);
  std::vector<int> inside_at;  // the candidates' offset indices (unless all_inside)
  if (!all_inside) {
    inside_at.reserve(static_cast<std::size_t>(n_off));
    for (int i = 0; i < n_off; ++i) {
      if (inside(static_cast<std::int64_t>(box.x) + spec.neg[2 * i],
                 static_cast<std::int64_t>(box.y) + spec.neg[2 * i + 1], box, frame_w, frame_h)) {
        inside_at.push_back(i);
      }
    }
  }
  const std::int64_t n = all_inside ? n_off : static_cast<std::int64_t>(inside_at.size());
  std::vector<std::int64_t> keep;
  if (spec.exact) {
    if (n > spec.neg_count) {
      keep = choice_sorted(bits, n, spec.neg_count);
    } else {
      keep.resize(static_cast<std::size_t>(n));
      for (std::int64_t i = 0; i < n; ++i) keep[static_cast<std::size_t>(i)] = i;
    }
  } else {
    keep = bernoulli_first(bits, n, spec.keep_prob, spec.neg_count);
  }
  bags.xs.reserve(bags.xs.size() + keep.size());
  bags.ys.reserve(bags.ys.size() + keep.size());
  for (const std::int64_t k : keep) {
    const int i = all_inside ? static_cast<int>(k) : inside_at[static_cast<std::size_t>(k)];
    bags.xs.push_back(static_cast<std::int32_t>(box.x + spec.neg[2 * i]));
    bags.ys.push_back(static_cast<std::int32_t>(box.y + spec.neg[2 * i + 1]));
  }
  return bags;
}

}  // namespace wmiltrack
