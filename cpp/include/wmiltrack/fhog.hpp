// Patches and fHOG features for the correlation filters (correlation.hpp).
//
// A correlation filter looks at a fixed-size template: the frame region around the target is
// resampled to a fixed number of pixels (so its cost does not grow with the target), turned
// to gray, and described by Felzenszwalb's HOG variant ("fHOG", 31 values per cell: 18
// contrast-sensitive and 9 contrast-insensitive orientation bins, and 4 gradient energies).
// Each cell's histogram is normalised by the gradient energy of the four 2 x 2-cell blocks
// around it, which is what makes the features stable under a change of brightness or
// contrast (a shadow) where raw intensities are not.
#pragma once

#include <cstddef>
#include <vector>

#include "wmiltrack/integral.hpp"

namespace wmiltrack::cf {

// A gray image with values in [0, 1], row-major.
struct GrayPatch {
  int rows = 0;
  int cols = 0;
  std::vector<float> pixels;
};

// Channels stored one after another ("planes"), each row-major: value (k, r, c) at
// data[(k * rows + r) * cols + c].
struct FeatureMap {
  int channels = 0;
  int rows = 0;
  int cols = 0;
  std::vector<float> data;
  std::size_t plane_size() const { return static_cast<std::size_t>(rows) * cols; }
};

constexpr int kFhogChannels = 31;

// The frame region of size w x h (frame pixels, may be fractional) centred on (cx, cy),
// in coordinates where pixel (r, c) covers [c, c + 1) x [r, r + 1) (so a box (x, y, w, h)
// has its centre at (x + w / 2, y + h / 2)), resampled to out_cols x out_rows gray pixels (luma as OpenCV's BGR2GRAY, / 255). Parts
// of the region outside the frame take the nearest edge pixel. Each output pixel is a
// tent-weighted average of the frame pixels under it (radius: one output pixel in frame
// pixels, at least one), i.e. bilinear when enlarging and an anti-aliased average when
// shrinking. Where an output pixel spans 4 frame pixels or more along an axis, the tent reads
// every floor(span / 2)-th pixel along it (at least four under each tent): a region many
// times the patch's size costs about what one twice its size does. Throws std::invalid_argument for a non-positive or non-finite size, an output
// size below 1, or an empty frame.
GrayPatch sample_gray(const ImageView& frame, double cx, double cy, double w, double h,
                      int out_cols, int out_rows);

// sample_gray of the regions (w f) x (h f) around (cx, cy) for each factor f, all resampled to
// out_cols x out_rows; the frame's luma under them is converted once, on the lattice the
// smallest factor needs (so a larger one may read more pixels than its own sample_gray). Same errors as
// sample_gray, and std::invalid_argument for a non-positive or non-finite factor.
std::vector<GrayPatch> sample_gray_scales(const ImageView& frame, double cx, double cy, double w,
                                          double h, const std::vector<double>& factors,
                                          int out_cols, int out_rows);

// fHOG of a gray patch: floor(rows / cell) x floor(cols / cell) cells, kFhogChannels
// planes. Gradients are central differences (edge replicated); each pixel votes its
// gradient magnitude into the two nearest of 18 signed orientation bins (linearly) and the
// four nearest cells (bilinearly). Then, with N(cell) the energy of its 9 unsigned bins
// and n_j = 1 / sqrt(sum of N over the 2 x 2 block j + 1e-4) for the four blocks holding
// the cell (border cells reuse their own row/column): planes 0-17 are
// 0.5 * sum_j min(h_o n_j, 0.2), planes 18-26 the same on the unsigned bins h_o + h_{o+9},
// planes 27-30 0.2357 * sum_o min(h_o n_j, 0.2) for block j. Throws std::invalid_argument
// for cell < 1 or a patch smaller than one cell.
FeatureMap fhog(const GrayPatch& patch, int cell);

}  // namespace wmiltrack::cf
