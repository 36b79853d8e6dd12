#include <tuple>

#include "common.hpp"
#include "wmiltrack/colour.hpp"

namespace wmiltrack::bindings {

namespace {

Rect region_of(const ImageView& view, std::tuple<int, int, int, int> region) {
  const auto [x, y, w, h] = region;
  require(x >= 0 && y >= 0 && w >= 0 && h >= 0 &&
              static_cast<std::int64_t>(x) + w <= view.cols &&
              static_cast<std::int64_t>(y) + h <= view.rows,
          "region must lie inside the frame");
  return Rect{x, y, w, h};
}

void require_colour(const ImageView& view, int bits) {
  require(view.channels >= 3, "the colour model needs a BGR or BGRA frame");
  require(bits >= 1 && bits <= 8, "bits must be in 1..8, got " + std::to_string(bits));
}

}  // namespace

void bind_colour(py::module_& m) {
  m.def(
      "colour_map",
      [](const py::array& frame, std::tuple<int, int, int, int> region_in, int bits,
         const CArray<double>& likelihood) {
        const ImageView view = image_view(frame);
        require_colour(view, bits);
        const Rect region = region_of(view, region_in);
        require(likelihood.ndim() == 1 && likelihood.shape(0) == (py::ssize_t{1} << (3 * bits)),
                "likelihood must hold 2**(3 * bits) values");
        CArray<double> out({region.h, region.w});
        double* o = out.mutable_data();
        const double* l = likelihood.data();
        {
          py::gil_scoped_release release;
          colour_map(view, region, bits, l, o);
        }
        return out;
      },
      py::arg("frame"), py::arg("region"), py::arg("bits"), py::arg("likelihood"),
      "likelihood[bin] of every pixel of region = (x, y, w, h) (inside the frame): an h x w\n"
      "float64 array. bin = (b >> s) << 2 bits | (g >> s) << bits | (r >> s), s = 8 - bits.");

  m.def(
      "colour_counts",
      [](const py::array& frame, std::tuple<int, int, int, int> region_in,
         std::tuple<int, int, int, int> inside_in, std::tuple<int, int, int, int> core_in,
         int bits) {
        const ImageView view = image_view(frame);
        require_colour(view, bits);
        const Rect region = region_of(view, region_in);
        const auto span = [](std::tuple<int, int, int, int> t) {
          const auto [r0, r1, c0, c1] = t;
          return Span{r0, r1, c0, c1};
        };
        const Span inside = span(inside_in), core = span(core_in);
        const py::ssize_t n = py::ssize_t{1} << (3 * bits);
        CArray<double> fg(n), bg(n);
        double* f = fg.mutable_data();
        double* b = bg.mutable_data();
        {
          py::gil_scoped_release release;
          std::fill(f, f + n, 0.0);
          std::fill(b, b + n, 0.0);
          colour_counts(view, region, inside, core, bits, f, b);
        }
        return py::make_tuple(fg, bg);
      },
      py::arg("frame"), py::arg("region"), py::arg("inside"), py::arg("core"), py::arg("bits"),
      "Colour histogram counts of region = (x, y, w, h): (fg, bg), 2**(3 * bits) float64 each;\n"
      "fg counts the pixels in core, bg those outside inside (both (row0, row1, col0, col1)\n"
      "relative to the region, half-open).");
}

}  // namespace wmiltrack::bindings
