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

  m.def(
      "colour_update",
      [](py::array_t<double, py::array::c_style> fg_model, py::array_t<double, py::array::c_style> bg_model,
         py::array_t<double, py::array::c_style> fg_counts, py::array_t<double, py::array::c_style> bg_counts,
         double rate, bool first, py::array_t<double, py::array::c_style> likelihood) {
        const py::ssize_t n = fg_model.size();
        for (const auto* a : {&fg_model, &bg_model, &fg_counts, &bg_counts, &likelihood}) {
          require(a->ndim() == 1 && a->size() == n, "all five arrays must be 1-D of one length");
          require(a->writeable(), "the arrays must be writeable float64");
        }
        require(rate > 0.0 && rate <= 1.0, "rate must be in (0, 1]");
        double* f = fg_model.mutable_data();
        double* b = bg_model.mutable_data();
        double* fc = fg_counts.mutable_data();
        double* bc = bg_counts.mutable_data();
        double* l = likelihood.mutable_data();
        py::gil_scoped_release release;
        colour_update(f, b, fc, bc, static_cast<int>(n), rate, first, l);
      },
      py::arg("fg_model").noconvert(), py::arg("bg_model").noconvert(),
      py::arg("fg_counts").noconvert(), py::arg("bg_counts").noconvert(), py::arg("rate"),
      py::arg("first"), py::arg("likelihood").noconvert(),
      "One frame of the colour model's update, in place: the counts normalised to sum 1, the\n"
      "model blended ((1 - rate) model + rate counts; the counts when first), and likelihood =\n"
      "fg / (fg + bg) (0.5 where both are 0). All five arrays: C-contiguous float64 of one\n"
      "length (TypeError otherwise: a converted copy would be updated instead).");
}

}  // namespace wmiltrack::bindings
