#include <pybind11/stl.h>

#include <cmath>
#include <limits>
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
  require(nd == 2 || nd == 3, [&] { return "frame must be H x W or H x W x C, got " + std::to_string(nd) +
                                  " dimensions"; });
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
          [&] { return "frame must have 1, 3 (BGR) or 4 (BGRA) channels, got " + std::to_string(v.channels); });
  return v;
}

namespace {

constexpr std::int64_t kInt32Min = std::numeric_limits<std::int32_t>::min();
constexpr std::int64_t kInt32Max = std::numeric_limits<std::int32_t>::max();

[[noreturn]] void out_of_int32(const char* name, const std::string& value) {
  throw py::value_error(std::string(name) + " holds " + value + ", outside the int32 range [" +
                        std::to_string(kInt32Min) + ", " + std::to_string(kInt32Max) + "]");
}

template <typename T>
py::array_t<T, py::array::c_style | py::array::forcecast> as_c_array(const py::array& a) {
  return py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(a);
}

}  // namespace

Int32Array int32_array(const py::handle& obj, const char* name) {
  py::array a = py::array::ensure(obj);
  if (!a) {
    PyErr_Clear();
    throw py::type_error(std::string(name) + " must be an array of integers");
  }
  Int32Array out;
  out.shape.assign(a.shape(), a.shape() + a.ndim());
  out.values.resize(static_cast<std::size_t>(a.size()));
  const char kind = a.dtype().kind();
  if (kind == 'i' && a.itemsize() == 4) {  // already int32: copied as is
    const auto c = as_c_array<std::int32_t>(a);
    std::copy(c.data(), c.data() + c.size(), out.values.begin());
  } else if (kind == 'u' && a.itemsize() == 8) {
    const auto c = as_c_array<std::uint64_t>(a);
    for (py::ssize_t i = 0; i < c.size(); ++i) {
      const std::uint64_t v = c.data()[i];
      if (v > static_cast<std::uint64_t>(kInt32Max)) out_of_int32(name, std::to_string(v));
      out.values[i] = static_cast<std::int32_t>(v);
    }
  } else if (kind == 'i' || kind == 'u') {
    const auto c = as_c_array<std::int64_t>(a);
    for (py::ssize_t i = 0; i < c.size(); ++i) {
      const std::int64_t v = c.data()[i];
      if (v < kInt32Min || v > kInt32Max) out_of_int32(name, std::to_string(v));
      out.values[i] = static_cast<std::int32_t>(v);
    }
  } else if (kind == 'f') {
    const auto c = as_c_array<double>(a);
    for (py::ssize_t i = 0; i < c.size(); ++i) {
      const double v = c.data()[i];
      if (!std::isfinite(v) || std::floor(v) != v) {
        throw py::value_error(std::string(name) + " holds " + py::repr(py::float_(v)).cast<std::string>() +
                              ", not an integer (float coordinates and indices are not rounded)");
      }
      if (v < static_cast<double>(kInt32Min) || v > static_cast<double>(kInt32Max)) {
        out_of_int32(name, py::repr(py::float_(v)).cast<std::string>());
      }
      out.values[i] = static_cast<std::int32_t>(v);
    }
  } else {
    throw py::type_error(std::string(name) + " must hold integers, got dtype " +
                         py::str(a.dtype()).cast<std::string>());
  }
  return out;
}

std::shared_ptr<const IntegralImage> computed_table(const SharedIntegralImage& ii) {
  auto table = ii.snapshot();
  if (!table) {
    throw py::value_error(
        "the IntegralImage has not been computed yet: call compute() or compute_channels() first");
  }
  return table;
}

namespace {

void require_plane(const IntegralImage& self, int plane) {
  if (plane < 0 || plane >= self.num_channels()) {
    throw py::index_error("plane " + std::to_string(plane) + " outside the integral image's " +
                          std::to_string(self.num_channels()) + " plane(s)");
  }
}

}  // namespace

static void def_integral_compute(py::class_<SharedIntegralImage>& cls) {
  cls
      .def(py::init<>())
      .def(
          "compute",
          [](SharedIntegralImage& self, const py::array& frame, std::tuple<int, int, int, int> roi) {
            const ImageView view = image_view(frame);
            const auto [x, y, w, h] = roi;
            py::gil_scoped_release release;
            self.compute(view, Rect{x, y, w, h});
          },
          py::arg("frame"), py::arg("roi"),
          "Rebuild over roi = (x, y, w, h), clipped to the frame.")
      .def(
          "compute_channels",
          [](SharedIntegralImage& self, const py::array& frame, std::tuple<int, int, int, int> roi,
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
      .def_property_readonly(
          "computed", [](const SharedIntegralImage& self) { return self.snapshot() != nullptr; },
          "Whether a compute() or compute_channels() succeeded (the other members need one).")
      .def_property_readonly(
          "num_channels",
          [](const SharedIntegralImage& self) { return computed_table(self)->num_channels(); })
      .def_property_readonly(
          "channels",
          [](const SharedIntegralImage& self) {
            const auto ii = computed_table(self);
            py::tuple t(ii->channels().size());
            for (std::size_t k = 0; k < ii->channels().size(); ++k) t[k] = ii->channels()[k];
            return t;
          },
          "The channel id of each plane.")
      .def_property_readonly(
          "x0", [](const SharedIntegralImage& self) { return computed_table(self)->x0(); })
      .def_property_readonly(
          "y0", [](const SharedIntegralImage& self) { return computed_table(self)->y0(); })
      .def_property_readonly(
          "width", [](const SharedIntegralImage& self) { return computed_table(self)->width(); });
}

static void def_integral_reads(py::class_<SharedIntegralImage>& cls) {
  cls
      .def_property_readonly(
          "height", [](const SharedIntegralImage& self) { return computed_table(self)->height(); })
      .def(
          "table",
          [](const SharedIntegralImage& self, int plane) {
            const auto ii = computed_table(self);
            require_plane(*ii, plane);
            CArray<double> out({ii->height() + 1, ii->width() + 1});
            ii->copy_plane(plane, out.mutable_data());
            return out;
          },
          py::arg("plane") = 0,
          "A copy of plane `plane`'s (height + 1) x (width + 1) table; row and column 0 are zero.")
      .def(
          "rect_sum",
          [](const SharedIntegralImage& self, int x, int y, int w, int h, int plane) {
            const auto ii = computed_table(self);
            const Rect r{x, y, w, h};
            if (!ii->covers(r)) throw py::index_error("rectangle outside the integral image");
            require_plane(*ii, plane);
            return ii->sum(r, plane);
          },
          py::arg("x"), py::arg("y"), py::arg("w"), py::arg("h"), py::arg("plane") = 0,
          "Exact sum over columns [x, x+w) and rows [y, y+h), in frame coordinates, on a plane.");
}

void bind_integral(py::module_& m) {
  m.attr("MAX_RECT_AREA") = kMaxExactRectArea;
  m.attr("CH_LUMA") = static_cast<int>(kLuma);
  m.attr("CH_GRAD") = static_cast<int>(kGrad);
  m.attr("CH_OPP_RG") = static_cast<int>(kOppRG);
  m.attr("CH_OPP_YB") = static_cast<int>(kOppYB);
  m.attr("NUM_CHANNEL_KINDS") = kNumChannelKinds;

  py::class_<SharedIntegralImage> cls(
      m, "IntegralImage",
      "Integral image of a frame region, luma from BGR(A) as OpenCV's BGR2GRAY.\n\n"
      "Every method and property but `computed` raises ValueError until compute() or\n"
      "compute_channels() succeeded. Threads may share one object: readers (project,\n"
      "score_grid, rect_sum, table, the properties) each see one complete table, the one\n"
      "current when they started, while another thread recomputes it; a failed compute leaves\n"
      "the object unchanged.");
  def_integral_compute(cls);
  def_integral_reads(cls);
}

}  // namespace wmiltrack::bindings
