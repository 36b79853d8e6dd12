#include <limits>
#include <vector>

#include "common.hpp"
#include "wmiltrack/haar.hpp"

namespace wmiltrack::bindings {

namespace {

FeatureBank make_bank(const py::object& starts_obj, const py::object& rects_obj,
                      const CArray<double>& weights, const py::object& channels) {
  const Int32Array starts = int32_array(starts_obj, "starts");
  const Int32Array rects = int32_array(rects_obj, "rects");
  require(starts.ndim() == 1, "starts must be 1-D");
  require(rects.ndim() == 2 && rects.shape[1] == 4, "rects must be R x 4 (x, y, w, h)");
  require(weights.ndim() == 1 && weights.shape(0) == rects.shape[0],
          "weights must be 1-D with one entry per rect");
  std::vector<Rect> r(static_cast<std::size_t>(rects.shape[0]));
  for (std::size_t i = 0; i < r.size(); ++i) {
    const std::int32_t* q = rects.data() + 4 * i;
    r[i] = Rect{q[0], q[1], q[2], q[3]};
  }
  std::vector<double> w(weights.data(), weights.data() + weights.size());
  std::vector<std::int32_t> planes;
  if (!channels.is_none()) {
    Int32Array p = int32_array(channels, "channels");
    require(p.ndim() == 1 && p.shape[0] == rects.shape[0],
            "channels must be 1-D with one plane index per rect");
    planes = std::move(p.values);
  }
  return FeatureBank(starts.values, std::move(r), std::move(w), std::move(planes));
}

}  // namespace

void bind_haar(py::module_& m) {
  py::class_<FeatureBank>(m, "FeatureBank",
                          "Haar-like features: weighted rectangle sums at offsets from a box corner.")
      .def(py::init(&make_bank), py::arg("starts"), py::arg("rects"), py::arg("weights"),
           py::arg("channels") = py::none())
      .def_property_readonly("size", &FeatureBank::size)
      .def_property_readonly("num_rects", &FeatureBank::num_rects)
      .def_property_readonly(
          "channels",
          [](const FeatureBank& b) {
            CArray<std::int32_t> out(static_cast<py::ssize_t>(b.planes().size()));
            std::copy(b.planes().begin(), b.planes().end(), out.mutable_data());
            return out;
          },
          "Integral-image plane of each rectangle (a copy; zeros for a bank built without).")
      .def_property_readonly("planes_needed", &FeatureBank::planes_needed,
                             "Planes an integral image needs for this bank: 1 + the largest.")
      .def_property_readonly("extent", [](const FeatureBank& b) {
        const Rect& e = b.extent();
        return py::make_tuple(e.x, e.y, e.w, e.h);
      });

  m.def(
      "project",
      [](const SharedIntegralImage& shared, const FeatureBank& bank, const py::object& xs_obj,
         const py::object& ys_obj, const py::object& features) {
        // Copies: the core reads the values this call checked, whatever other threads do to
        // the caller's arrays while the GIL is released.
        const Int32Array xs = int32_array(xs_obj, "xs");
        const Int32Array ys = int32_array(ys_obj, "ys");
        require(xs.ndim() == 1 && ys.ndim() == 1 && xs.size() == ys.size(),
                "xs and ys must be 1-D of equal length");
        require(xs.size() <= std::numeric_limits<int>::max(), "too many boxes");
        const auto ii = computed_table(shared);
        require_planes(*ii, bank);
        Int32Array idx;
        const std::int32_t* idx_ptr = nullptr;
        int n_feat = bank.size();
        if (!features.is_none()) {
          idx = int32_array(features, "features");
          require(idx.ndim() == 1, "features must be 1-D");
          require(idx.size() <= std::numeric_limits<int>::max(), "too many features");
          idx_ptr = idx.data();
          n_feat = static_cast<int>(idx.size());
        }
        const int n_boxes = static_cast<int>(xs.size());
        CArray<double> out({n_feat, n_boxes});
        double* out_ptr = out.mutable_data();
        {
          py::gil_scoped_release release;
          project(*ii, bank, idx_ptr, n_feat, xs.data(), ys.data(), n_boxes, out_ptr);
        }
        return out;
      },
      py::arg("ii"), py::arg("bank"), py::arg("xs"), py::arg("ys"), py::arg("features") = py::none(),
      "Feature values (features x boxes) for boxes with top-left corners (xs, ys).\n\n"
      "xs, ys and features must hold integers in the int32 range: floats are accepted only\n"
      "when integral, anything else raises ValueError (out of range, fractional) or TypeError.");
}

}  // namespace wmiltrack::bindings
