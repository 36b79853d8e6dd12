// Helpers shared by the binding files: argument checks that raise the right Python errors.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "wmiltrack/haar.hpp"
#include "wmiltrack/integral.hpp"
#include "wmiltrack/shared.hpp"

namespace wmiltrack::bindings {

namespace py = pybind11;

// C-contiguous arrays of a fixed dtype; other dtypes and layouts are converted once.
template <typename T>
using CArray = py::array_t<T, py::array::c_style | py::array::forcecast>;

// A request's model array (mu1, sigma1, mu0, sigma0): taken as it is when it already is a
// C-ordered float64 array, which is what CArray's own conversion returns for one, without
// numpy's conversion call (eight of them a frame, as much time as a tenth of a paper preset's
// Python glue); anything else converted as CArray converts it, or a TypeError naming `name`.
inline CArray<double> model_array(const py::object& value, const char* name) {
  if (CArray<double>::check_(value)) return py::reinterpret_borrow<CArray<double>>(value);
  CArray<double> converted = CArray<double>::ensure(value);
  if (!converted) {
    throw py::type_error(std::string(name) + " must be an array of numbers, got " +
                         std::string(py::str(py::type::handle_of(value).attr("__name__"))));
  }
  return converted;
}

// An integer array copied into int32 values the binding owns (so that another thread cannot
// change them between a check and their use), with its shape.
struct Int32Array {
  std::vector<std::int32_t> values;
  std::vector<py::ssize_t> shape;
  const std::int32_t* data() const { return values.data(); }
  py::ssize_t size() const { return static_cast<py::ssize_t>(values.size()); }
  py::ssize_t ndim() const { return static_cast<py::ssize_t>(shape.size()); }
};

// `obj` (an array or a sequence) as int32 values, never converted silently: integers outside
// int32 raise ValueError, floats are accepted only when every value is an integer in range
// (else ValueError), and other dtypes (bool, complex, object, strings) raise TypeError.
Int32Array int32_array(const py::handle& obj, const char* name);

// The table of an IntegralImage, or ValueError when it was never computed. The snapshot
// stays valid and unchanged while held, whatever other threads do to the object.
std::shared_ptr<const IntegralImage> computed_table(const SharedIntegralImage& ii);

// An 8-bit frame (H x W, H x W x 1, 3 or 4) as a strided view, without copying.
ImageView image_view(const py::array& frame);

void bind_integral(py::module_& m);
void bind_haar(py::module_& m);
void bind_scoring(py::module_& m);
void bind_colour(py::module_& m);
void bind_search(py::module_& m);
void bind_learn(py::module_& m);
void bind_draws(py::module_& m);
void bind_batch(py::module_& m);
// The correlation-filter kernels (bind_cf.cpp), one function per bound class.
void bind_cf_features(py::module_& m);
void bind_translation_response(py::module_& m);
void bind_spectrum(py::module_& m);
void bind_translation_filter(py::module_& m);
void bind_scale_response(py::module_& m);
void bind_scale_filter(py::module_& m);

// ValueError(message) unless ok. A message that formats values is passed as a callable that
// makes it, so that it is built only on failure: these checks run on every frame, and building
// a std::string with std::to_string each time cost fct 13 us a frame (one per selected feature).
inline void require(bool ok, const char* message) {
  if (!ok) throw py::value_error(message);
}
template <class MakeMessage,
          class = std::enable_if_t<std::is_invocable_v<const MakeMessage&>>>
inline void require(bool ok, const MakeMessage& make_message) {
  if (!ok) throw py::value_error(make_message());
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
