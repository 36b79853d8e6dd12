// Internal to the core (not installed): feature values over runs of boxes whose top-left
// corners are consecutive entries of an integral image's row, read several boxes a step (the
// search's candidate grid in scoring.cpp, the bags' boxes in haar.cpp's project).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "wmiltrack/haar.hpp"
#include "wmiltrack/integral.hpp"

namespace wmiltrack {

// A run of boxes: consecutive columns of one row, `count` boxes from table offset `base`.
struct GridRun {
  int first;            // index of the run's first box
  int count;            // boxes in the run
  std::ptrdiff_t base;  // table offset of the first box's top-left corner
};

// Largest rectangle whose sum of 0..255 values is below 2^31: the vector loops convert the
// 32-bit sums to doubles as signed integers.
constexpr std::int64_t kMaxSignedRectArea = 2147483647LL / 255;

// values[run.first + t] = sum over rectangles c[0..n) of weight * rectangle sum, added in order
// from 0.0 (CompiledFeatures::value_of), at box t of each run. With `vector` (the rectangles
// are at most kMaxSignedRectArea pixels, one plane) 8 boxes a step with AVX2, 4 with SSE2;
// otherwise one at a time. The same bits on every path.
void run_values(const IntegralImage::Entry* table, const std::vector<GridRun>& runs,
                const CompiledFeatures::Corners* c, int n, bool vector, double* values);

}  // namespace wmiltrack
