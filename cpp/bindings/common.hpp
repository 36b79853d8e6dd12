// Helpers shared by the binding files: argument checks that raise the right Python errors.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <string>

#include "wmiltrack/haar.hpp"
#include "wmiltrack/integral.hpp"

namespace wmiltrack::bindings {

namespace py = pybind11;

// C-contiguous arrays of a fixed dtype; other dtypes and layouts are converted once.
template <typename T>
using CArray = py::array_t<T, py::array::c_style | py::array::forcecast>;

// An 8-bit frame (H x W, H x W x 1, 3 or 4) as a strided view, without copying.
ImageView image_view(const py::array& frame);

void bind_integral(py::module_& m);
void bind_haar(py::module_& m);
void bind_scoring(py::module_& m);

inline void require(bool ok, const std::string& message) {
  if (!ok) throw py::value_error(message);
}

// ValueError when the bank sums over planes the integral image does not have (the core
// would refuse them too, with std::out_of_range -> IndexError; this names the mismatch).
inline void require_planes(const IntegralImage& ii, const FeatureBank& bank) {
  if (bank.planes_needed() > ii.num_channels()) {
    throw py::value_error("the feature bank sums over " + std::to_string(bank.planes_needed()) +
                          " plane(s) but the integral image has " +
                          std::to_string(ii.num_channels()) +
                          " (build it with compute_channels)");
  }
}

}  // namespace wmiltrack::bindings
