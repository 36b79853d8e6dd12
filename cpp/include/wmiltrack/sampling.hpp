// Bag sampling in the core: the positives and the drawn negatives around a box, with the draw
// continuing a numpy.random.Generator's stream exactly (the same numbers numpy's own `choice`
// and `random` would give), so that a tracker's whole frame step can run in one call and still
// give the boxes of the Python sampler.
//
// Why our own copies of numpy's draws: the core must not depend on numpy, and numpy exposes its
// bit generators (bitgen_t: state and next_* functions) but not Generator.choice's algorithm.
// choice_sorted() and bernoulli_first() reproduce what Generator.choice(n, k, replace=False)
// and Generator.random(n) < p consume and return; tests/core/test_core_kernels.py checks them
// against numpy (picks, flags and the generator's state afterwards).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "wmiltrack/integral.hpp"

namespace wmiltrack {

// numpy's bitgen_t (numpy/random/bitgen.h): a bit generator's state and its draws, as the
// "BitGenerator" capsule of a numpy Generator's bit generator holds it.
struct Bitgen {
  void* state;
  std::uint64_t (*next_uint64)(void* st);
  std::uint32_t (*next_uint32)(void* st);
  double (*next_double)(void* st);
  std::uint64_t (*next_raw)(void* st);
};

// A source of random bits: numpy's generator as it is, plus, where the binding has checked
// that the generator is numpy's PCG64 and found its 128-bit state, that state (pcg64_state):
// bernoulli_first() then steps it here, four draws in flight, instead of calling next_double
// once per number (the same numbers and final state; numpy's PCG64 at about 2 ns a draw was
// most of a compressive tracker's bag sampling, some 4 000 draws a frame).
struct BitSource : Bitgen {
  std::uint64_t* pcg64_state = nullptr;  // {state low, high, increment low, high}, or null
};

// numpy's PCG64 double after the state `s` (state and increment as in BitSource::pcg64_state):
// the LCG steps s, the XSL-RR output of the new state, its top 53 bits / 2^53. Returns the
// double and leaves the new state in s. (Exposed for the binding's layout check.)
double pcg64_next_double(std::uint64_t* s);

// Generator.choice(n, k, replace=False) for n <= 10000 or k <= n / 50 (Floyd's algorithm with
// numpy's bounded draws, then the shuffle of the k picks that numpy makes), returned sorted.
// Throws std::invalid_argument outside that range or for k > n.
std::vector<std::int64_t> choice_sorted(BitSource& bits, std::int64_t n, std::int64_t k);

// The indices i < n with Generator.random() < p, drawn in order, the first `limit` of them
// (all n values are drawn, as numpy's random(n) does).
std::vector<std::int64_t> bernoulli_first(BitSource& bits, std::int64_t n, double p, std::int64_t limit);

// How a bag's positives are weighted (Params.instance_weights) for WMIL selection.
enum class InstanceWeights {
  kNone,     // no weights (no WMIL selection)
  kExp,      // terms exp(-d), divided by their sum (numpy's pairwise sum)
  kExpSq,    // terms exp(-d^2) as they are
  kUniform,  // 1 / n
};

// The sampler of one tracker (engine/sampling.py's BagSampler): offsets of the top-left corner.
struct BagSpec {
  const std::int32_t* pos = nullptr;  // (n_pos_offsets, 2) dx, dy, row-major disc order
  int n_pos_offsets = 0;
  const double* pos_terms = nullptr;  // the weight term of each positive offset (kExp, kExpSq)
  InstanceWeights weights = InstanceWeights::kNone;
  const std::int32_t* neg = nullptr;  // (n_neg_offsets, 2) dx, dy, row-major annulus order
  int n_neg_offsets = 0;
  // The bounding box of the negatives' offsets (offsets_extent), made once with the spec:
  // where it fits in the frame, every offset does. Without it each offset is checked.
  std::optional<Rect> neg_extent;
  bool exact = true;      // exactly neg_count distinct offsets (choice); else Bernoulli
  int neg_count = 0;
  double keep_prob = 0.0;  // the Bernoulli probability
};

// The n > 0 offsets (dx, dy) of `xy` as a rectangle: (x, y) the smallest dx and dy, (x + w,
// y + h) the largest.
Rect offsets_extent(const std::int32_t* xy, int n);

struct Bags {
  std::vector<std::int32_t> xs, ys;  // the positives' corners, then the negatives'
  int n_pos = 0;
  std::vector<double> w_pos;  // n_pos weights (empty for kNone)
};

// The bags around `box` in a frame_w x frame_h frame: the positives inside the frame, the
// negatives drawn from the offsets inside the frame (exactly as BagSampler.positives,
// negatives and weights do, numpy's draws included).
Bags sample_bags(const BagSpec& spec, const Rect& box, int frame_w, int frame_h, BitSource& bits);

}  // namespace wmiltrack
