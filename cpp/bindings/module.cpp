// The compiled core of wmiltrack: integral images, Haar feature projection, candidate scoring.
#include "common.hpp"

PYBIND11_MODULE(_core, m) {
  m.doc() = "wmiltrack's C++/Eigen core: integral images, Haar-like features, candidate scoring";
  // True when built with -march=native (WMILTRACK_NATIVE=ON): not portable to older CPUs.
  m.attr("BUILD_NATIVE") = static_cast<bool>(WMILTRACK_NATIVE_BUILD);
  wmiltrack::bindings::bind_integral(m);
  wmiltrack::bindings::bind_haar(m);
  wmiltrack::bindings::bind_scoring(m);
  wmiltrack::bindings::bind_colour(m);
  wmiltrack::bindings::bind_frame(m);
}
