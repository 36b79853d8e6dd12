#include <memory>
#include <mutex>
#include <tuple>
#include <utility>
#include <vector>

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

// The core's histograms with a lock: a Python object may be reached from several threads,
// and its methods run without the GIL.
struct LockedHistograms {
  ColourHistograms hist;
  std::mutex lock;
  LockedHistograms(int bits, double rate) : hist(bits, rate) {}
};

py::array_t<double> copy_of(const std::vector<double>& v) {
  py::array_t<double> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

// A colour frame for these histograms and a region inside it, checked.
std::pair<ImageView, Rect> colour_region(const LockedHistograms& h, const py::array& frame,
                                         std::tuple<int, int, int, int> region) {
  const ImageView view = image_view(frame);
  require_colour(view, h.hist.bits());
  return {view, region_of(view, region)};
}

Span span_of(std::tuple<int, int, int, int> t) {
  const auto [r0, r1, c0, c1] = t;
  return Span{r0, r1, c0, c1};
}

}  // namespace

void bind_colour(py::module_& m) {
  py::class_<LockedHistograms>(
      m, "ColourHistograms",
      "Foreground and background colour histograms (2**(3 * bits) bins each, blended over\n"
      "frames at `rate`) and the per-bin likelihood fg / (fg + bg), 0.5 where both are 0.\n"
      "bin = (b >> s) << 2 bits | (g >> s) << bits | (r >> s), s = 8 - bits.")
      .def(py::init<int, double>(), py::arg("bits"), py::arg("rate"))
      .def(
          "copy",
          [](LockedHistograms& h) {
            std::lock_guard<std::mutex> guard(h.lock);
            auto out = std::make_unique<LockedHistograms>(h.hist.bits(), h.hist.rate());
            out->hist = h.hist;
            return out;
          },
          "An independent copy (the histograms as they are now).")
      .def_property_readonly("bits", [](const LockedHistograms& h) { return h.hist.bits(); })
      .def_property_readonly("rate", [](const LockedHistograms& h) { return h.hist.rate(); })
      .def_property_readonly("learnt", [](LockedHistograms& h) {
        std::lock_guard<std::mutex> guard(h.lock);
        return h.hist.learnt();
      })
      .def(
          "learn",
          [](LockedHistograms& h, const py::array& frame, std::tuple<int, int, int, int> region_in,
             std::tuple<int, int, int, int> inside, std::tuple<int, int, int, int> core) {
            const auto [view, region] = colour_region(h, frame, region_in);
            py::gil_scoped_release release;
            std::lock_guard<std::mutex> guard(h.lock);
            h.hist.learn(view, region, span_of(inside), span_of(core));
          },
          py::arg("frame"), py::arg("region"), py::arg("inside"), py::arg("core"),
          "Fold in one frame: the pixels of core count for the foreground, those of region =\n"
          "(x, y, w, h) outside inside for the background (inside, core: (row0, row1, col0,\n"
          "col1) relative to the region, half-open); each count histogram is normalised to sum\n"
          "1 and blended in ((1 - rate) model + rate counts; the counts on the first frame).")
      .def(
          "likelihood_integral",
          [](LockedHistograms& h, const py::array& frame, std::tuple<int, int, int, int> region_in) {
            const auto [view, region] = colour_region(h, frame, region_in);
            CArray<double> out({region.h + 1, region.w + 1});
            double* o = out.mutable_data();
            {
              py::gil_scoped_release release;
              std::lock_guard<std::mutex> guard(h.lock);
              if (!h.hist.learnt()) throw py::value_error("call learn() before likelihood_integral()");
              h.hist.likelihood_integral(view, region, o);
            }
            return out;
          },
          py::arg("frame"), py::arg("region"),
          "Integral image (h + 1) x (w + 1), zero first row and column, of the likelihood of\n"
          "every pixel of region = (x, y, w, h) (inside the frame); the sums of cv2.integral.")
      .def(
          "likelihood_sums",
          [](LockedHistograms& h, const py::array& frame, std::tuple<int, int, int, int> region_in,
             std::tuple<int, int, int, int> inner) {
            const auto [view, region] = colour_region(h, frame, region_in);
            py::gil_scoped_release release;
            std::lock_guard<std::mutex> guard(h.lock);
            if (!h.hist.learnt()) throw py::value_error("call learn() before likelihood_sums()");
            return h.hist.likelihood_sums(view, region, span_of(inner));
          },
          py::arg("frame"), py::arg("region"), py::arg("inner"),
          "(inner sum, region sum) of the likelihood of the pixels of region = (x, y, w, h)\n"
          "(inside the frame) and of its part inner = (row0, row1, col0, col1), relative to the\n"
          "region and clipped to it.")
      .def_property_readonly("foreground", [](LockedHistograms& h) {
        std::lock_guard<std::mutex> guard(h.lock);
        return copy_of(h.hist.foreground());
      }, "A copy of the foreground histogram (sums to 1 once learnt).")
      .def_property_readonly("background", [](LockedHistograms& h) {
        std::lock_guard<std::mutex> guard(h.lock);
        return copy_of(h.hist.background());
      }, "A copy of the background histogram.")
      .def_property_readonly("likelihood", [](LockedHistograms& h) {
        std::lock_guard<std::mutex> guard(h.lock);
        return copy_of(h.hist.likelihood());
      }, "A copy of P(target | bin).");
}

}  // namespace wmiltrack::bindings
