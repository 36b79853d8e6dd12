#include <vector>

#include "common.hpp"
#include "wmiltrack/haar.hpp"

namespace wmiltrack::bindings {

namespace {

FeatureBank make_bank(const CArray<std::int32_t>& starts, const CArray<std::int32_t>& rects,
                      const CArray<double>& weights, const py::object& channels) {
  require(starts.ndim() == 1, "starts must be 1-D");
  require(rects.ndim() == 2 && rects.shape(1) == 4, "rects must be R x 4 (x, y, w, h)");
  require(weights.ndim() == 1 && weights.shape(0) == rects.shape(0),
          "weights must be 1-D with one entry per rect");
  std::vector<std::int32_t> s(starts.data(), starts.data() + starts.size());
  std::vector<Rect> r(static_cast<std::size_t>(rects.shape(0)));
  auto rv = rects.unchecked<2>();
  for (py::ssize_t i = 0; i < rects.shape(0); ++i) r[i] = Rect{rv(i, 0), rv(i, 1), rv(i, 2), rv(i, 3)};
  std::vector<double> w(weights.data(), weights.data() + weights.size());
  std::vector<std::int32_t> planes;
  if (!channels.is_none()) {
    const auto p = channels.cast<CArray<std::int32_t>>();
    require(p.ndim() == 1 && p.shape(0) == rects.shape(0),
            "channels must be 1-D with one plane index per rect");
    planes.assign(p.data(), p.data() + p.size());
  }
  return FeatureBank(std::move(s), std::move(r), std::move(w), std::move(planes));
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
      [](const IntegralImage& ii, const FeatureBank& bank, const CArray<std::int32_t>& xs,
         const CArray<std::int32_t>& ys, const py::object& features) {
        require(xs.ndim() == 1 && ys.ndim() == 1 && xs.shape(0) == ys.shape(0),
                "xs and ys must be 1-D of equal length");
        require_planes(ii, bank);
        CArray<std::int32_t> idx;
        const std::int32_t* idx_ptr = nullptr;
        int n_feat = bank.size();
        if (!features.is_none()) {
          idx = features.cast<CArray<std::int32_t>>();
          require(idx.ndim() == 1, "features must be 1-D");
          idx_ptr = idx.data();
          n_feat = static_cast<int>(idx.shape(0));
        }
        const int n_boxes = static_cast<int>(xs.shape(0));
        CArray<double> out({n_feat, n_boxes});
        double* out_ptr = out.mutable_data();
        {
          py::gil_scoped_release release;
          project(ii, bank, idx_ptr, n_feat, xs.data(), ys.data(), n_boxes, out_ptr);
        }
        return out;
      },
      py::arg("ii"), py::arg("bank"), py::arg("xs"), py::arg("ys"), py::arg("features") = py::none(),
      "Feature values (features x boxes) for boxes with top-left corners (xs, ys).");
}

}  // namespace wmiltrack::bindings
