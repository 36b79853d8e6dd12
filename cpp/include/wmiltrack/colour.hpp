// The pixel work of rcwmil-plus's colour model (Staple-style foreground/background colour
// histograms; wmiltrack.engine.colour keeps the histograms and merges the cue): the bin of
// every pixel of a region, its foreground probability, and the histogram counts of a frame.
#pragma once

#include <cstdint>

#include "wmiltrack/integral.hpp"

namespace wmiltrack {

// Bin of a BGR pixel with `bits` bits per channel: (b >> s) << 2 bits | (g >> s) << bits |
// (r >> s), s = 8 - bits; 2^(3 bits) bins.
inline std::uint32_t colour_bin(std::uint8_t b, std::uint8_t g, std::uint8_t r, int bits) {
  const int s = 8 - bits;
  return (static_cast<std::uint32_t>(b >> s) << (2 * bits)) |
         (static_cast<std::uint32_t>(g >> s) << bits) | static_cast<std::uint32_t>(r >> s);
}

// A rectangle of rows [r0, r1) and columns [c0, c1) of a region (empty when r1 <= r0 or
// c1 <= c0).
struct Span {
  int r0 = 0, r1 = 0, c0 = 0, c1 = 0;
  bool holds(int r, int c) const { return r >= r0 && r < r1 && c >= c0 && c < c1; }
};

// out[r * region.w + c] = likelihood[bin of the pixel at (region.x + c, region.y + r)] for
// the region (inside the frame; 3 or 4 channels, BGR(A)). Throws std::invalid_argument for
// a gray frame, bits outside 1..8 or a region outside the frame.
void colour_map(const ImageView& image, const Rect& region, int bits, const double* likelihood,
                double* out);

// Colour histogram counts of a region: every pixel of `core` (relative to the region) adds
// 1 to fg[bin], every pixel outside `inside` adds 1 to bg[bin]. fg and bg hold 2^(3 bits)
// entries and are added to (zero them first). Same errors as colour_map().
void colour_counts(const ImageView& image, const Rect& region, const Span& inside,
                   const Span& core, int bits, double* fg, double* bg);

// One frame of the model's update, on n bins: each count histogram is divided by its sum
// (at least 1), blended into the model (model = (1 - rate) model + rate counts; the counts
// themselves when `first`), and likelihood = fg / (fg + bg) (0.5 where both are 0). The same
// operations in the same order as the numpy code it replaced (the same bits). The counts are
// overwritten.
void colour_update(double* fg_model, double* bg_model, double* fg_counts, double* bg_counts,
                   int n, double rate, bool first, double* likelihood);

}  // namespace wmiltrack
