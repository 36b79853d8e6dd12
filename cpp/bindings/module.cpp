// The compiled core of wmiltrack: integral images, Haar feature projection, candidate scoring.
#include "common.hpp"
#include "wmiltrack/vmath.hpp"

PYBIND11_MODULE(_core, m) {
  m.doc() = "wmiltrack's C++/Eigen core: integral images, Haar-like features, candidate scoring";
  // True when built with -march=native (WMILTRACK_NATIVE=ON): not portable to older CPUs.
  m.attr("BUILD_NATIVE") = static_cast<bool>(WMILTRACK_NATIVE_BUILD);
  // Which copy of the vectorised kernels runs ("avx2", "sse2" or "scalar"); all give the
  // same bits. set_simd_portable(True) forces the baseline copy (for tests and benchmarks).
  m.def("simd_path", [] { return std::string(wmiltrack::vmath::isa()); },
        "The copy of the vectorised kernels this CPU runs: 'avx2', 'sse2' or 'scalar'.");
  m.def("set_simd_portable", &wmiltrack::vmath::force_portable, pybind11::arg("portable"),
        "Force the baseline (SSE2) copy of the vectorised kernels, or go back to the CPU's best. "
        "The results are the same bits either way; this is for tests and benchmarks.");
  wmiltrack::bindings::bind_integral(m);
  wmiltrack::bindings::bind_haar(m);
  wmiltrack::bindings::bind_scoring(m);
  wmiltrack::bindings::bind_colour(m);
  wmiltrack::bindings::bind_search(m);
  wmiltrack::bindings::bind_learn(m);
  wmiltrack::bindings::bind_draws(m);
  wmiltrack::bindings::bind_batch(m);
  wmiltrack::bindings::bind_cf_features(m);
  wmiltrack::bindings::bind_translation_response(m);
  wmiltrack::bindings::bind_spectrum(m);
  wmiltrack::bindings::bind_translation_filter(m);
  wmiltrack::bindings::bind_scale_response(m);
  wmiltrack::bindings::bind_scale_filter(m);
}
