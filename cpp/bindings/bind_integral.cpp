#include <pybind11/stl.h>

#include <tuple>
#include <vector>

#include "common.hpp"

namespace wmiltrack::bindings {

ImageView image_view(const py::array& frame) {
  if (!py::isinstance<py::array_t<std::uint8_t>>(frame) ||
      frame.dtype().kind() != 'u' || frame.itemsize() != 1) {
    throw py::type_error("frame must be a uint8 array, got dtype " +
                         py::str(frame.dtype()).cast<std::string>());
  }
  const auto nd = frame.ndim();
  require(nd == 2 || nd == 3, "frame must be H x W or H x W x C, got " + std::to_string(nd) +
                                  " dimensions");
  ImageView v;
  v.data = static_cast<const std::uint8_t*>(frame.data());
  v.rows = static_cast<int>(frame.shape(0));
  v.cols = static_cast<int>(frame.shape(1));
  v.row_stride = frame.strides(0);
  v.col_stride = frame.strides(1);
  v.channels = nd == 3 ? static_cast<int>(frame.shape(2)) : 1;
  v.channel_stride = nd == 3 ? frame.strides(2) : 1;
  require(v.rows > 0 && v.cols > 0, "frame is empty");
  require(v.channels == 1 || v.channels == 3 || v.channels == 4,
          "frame must have 1, 3 (BGR) or 4 (BGRA) channels, got " + std::to_string(v.channels));
  return v;
}

namespace {

void require_plane(const IntegralImage& self, int plane) {
  if (plane < 0 || plane >= self.num_channels()) {
    throw py::index_error("plane " + std::to_string(plane) + " outside the integral image's " +
                          std::to_string(self.num_channels()) + " plane(s)");
  }
}

}  // namespace

void bind_integral(py::module_& m) {
  m.attr("CH_LUMA") = static_cast<int>(kLuma);
  m.attr("CH_GRAD") = static_cast<int>(kGrad);
  m.attr("CH_OPP_RG") = static_cast<int>(kOppRG);
  m.attr("CH_OPP_YB") = static_cast<int>(kOppYB);
  m.attr("CH_ORIENT0") = static_cast<int>(kOrient0);
  m.attr("CH_ORIENT1") = static_cast<int>(kOrient1);
  m.attr("CH_ORIENT2") = static_cast<int>(kOrient2);
  m.attr("CH_ORIENT3") = static_cast<int>(kOrient3);
  m.attr("NUM_CHANNEL_KINDS") = kNumChannelKinds;

  py::class_<IntegralImage>(m, "IntegralImage",
                            "Integral image of a frame region, luma from BGR(A) as OpenCV's BGR2GRAY.")
      .def(py::init<>())
      .def(
          "compute",
          [](IntegralImage& self, const py::array& frame, std::tuple<int, int, int, int> roi) {
            const ImageView view = image_view(frame);
            const auto [x, y, w, h] = roi;
            py::gil_scoped_release release;
            self.compute(view, Rect{x, y, w, h});
          },
          py::arg("frame"), py::arg("roi"),
          "Rebuild over roi = (x, y, w, h), clipped to the frame.")
      .def(
          "compute_channels",
          [](IntegralImage& self, const py::array& frame, std::tuple<int, int, int, int> roi,
             const std::vector<int>& channels) {
            const ImageView view = image_view(frame);
            const auto [x, y, w, h] = roi;
            py::gil_scoped_release release;
            self.compute_channels(view, Rect{x, y, w, h}, channels);
          },
          py::arg("frame"), py::arg("roi"), py::arg("channels"),
          "Rebuild over roi = (x, y, w, h), clipped to the frame, with plane k holding channel\n"
          "channels[k] (CH_* ids). ValueError for an unknown id, no channels, or a colour\n"
          "channel on a gray frame.")
      .def_property_readonly("num_channels", &IntegralImage::num_channels)
      .def_property_readonly(
          "channels",
          [](const IntegralImage& self) {
            py::tuple t(self.channels().size());
            for (std::size_t k = 0; k < self.channels().size(); ++k) t[k] = self.channels()[k];
            return t;
          },
          "The channel id of each plane.")
      .def_property_readonly("x0", &IntegralImage::x0)
      .def_property_readonly("y0", &IntegralImage::y0)
      .def_property_readonly("width", &IntegralImage::width)
      .def_property_readonly("height", &IntegralImage::height)
      .def(
          "table",
          [](const IntegralImage& self, int plane) {
            require_plane(self, plane);
            CArray<double> out({self.height() + 1, self.width() + 1});
            std::copy(self.plane(plane), self.plane(plane) + out.size(), out.mutable_data());
            return out;
          },
          py::arg("plane") = 0,
          "A copy of plane `plane`'s (height + 1) x (width + 1) table; row and column 0 are zero.")
      .def(
          "rect_sum",
          [](const IntegralImage& self, int x, int y, int w, int h, int plane) {
            const Rect r{x, y, w, h};
            if (!self.covers(r)) throw py::index_error("rectangle outside the integral image");
            require_plane(self, plane);
            return self.sum(r, plane);
          },
          py::arg("x"), py::arg("y"), py::arg("w"), py::arg("h"), py::arg("plane") = 0,
          "Exact sum over columns [x, x+w) and rows [y, y+h), in frame coordinates, on a plane.");
}

}  // namespace wmiltrack::bindings
