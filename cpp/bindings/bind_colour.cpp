#include <memory>
#include <string>
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

void require_frame(const ImageView& view, const ColourHistograms& hist) {
  if (hist.intensity()) {
    require(view.channels == 1 || view.channels >= 3,
            "the intensity model needs a gray, BGR or BGRA frame");
  } else {
    require(view.channels >= 3, "the colour model needs a BGR or BGRA frame");
  }
}

// The core's histograms with a lock: a Python object may be reached from several threads,
// and its methods run without the GIL.
struct LockedHistograms {
  ColourHistograms hist;
  std::mutex lock;
  LockedHistograms(int bits, double rate, bool intensity) : hist(bits, rate, intensity) {}
};

py::array_t<double> copy_of(const std::vector<double>& v) {
  py::array_t<double> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

// A frame for these histograms and a region inside it, checked.
std::pair<ImageView, Rect> colour_region(const LockedHistograms& h, const py::array& frame,
                                         std::tuple<int, int, int, int> region) {
  const ImageView view = image_view(frame);
  require_frame(view, h.hist);
  return {view, region_of(view, region)};
}

Span span_of(std::tuple<int, int, int, int> t) {
  const auto [r0, r1, c0, c1] = t;
  return Span{r0, r1, c0, c1};
}

}  // namespace

static void def_colour_model(py::class_<LockedHistograms>& cls) {
  cls
      .def(py::init([](int bits, double rate, bool intensity) {
             require(bits >= 1 && bits <= 8, [&] { return "bits must be in 1..8, got " + std::to_string(bits); });
             require(rate > 0.0 && rate <= 1.0, "rate must be in (0, 1]");
             return std::make_unique<LockedHistograms>(bits, rate, intensity);
           }),
           py::arg("bits"), py::arg("rate"), py::kw_only(), py::arg("intensity") = false)
      .def(
          "copy",
          [](LockedHistograms& h) {
            std::lock_guard<std::mutex> guard(h.lock);
            auto out = std::make_unique<LockedHistograms>(h.hist.bits(), h.hist.rate(),
                                                          h.hist.intensity());
            out->hist = h.hist;
            return out;
          },
          "An independent copy (the histograms as they are now).")
      .def_property_readonly("bits", [](const LockedHistograms& h) { return h.hist.bits(); })
      .def_property_readonly("rate", [](const LockedHistograms& h) { return h.hist.rate(); })
      .def_property_readonly("intensity",
                             [](const LockedHistograms& h) { return h.hist.intensity(); })
      .def_property_readonly("learnt", [](LockedHistograms& h) {
        std::lock_guard<std::mutex> guard(h.lock);
        return h.hist.learnt();
      })
      .def(
          "learn",
          [](LockedHistograms& h, const py::array& frame, std::tuple<int, int, int, int> region_in,
             std::tuple<int, int, int, int> inside, std::tuple<int, int, int, int> core, int step) {
            const auto [view, region] = colour_region(h, frame, region_in);
            require(step >= 1, [&] { return "step must be at least 1, got " + std::to_string(step); });
            py::gil_scoped_release release;
            std::lock_guard<std::mutex> guard(h.lock);
            h.hist.learn(view, region, span_of(inside), span_of(core), step);
          },
          py::arg("frame"), py::arg("region"), py::arg("inside"), py::arg("core"),
          py::kw_only(), py::arg("step") = 1,
          "Fold in one frame: the pixels of core count for the foreground, those of region =\n"
          "(x, y, w, h) outside inside for the background (inside, core: (row0, row1, col0,\n"
          "col1) relative to the region, half-open); each count histogram is normalised to sum\n"
          "1 and blended in ((1 - rate) model + rate counts; the counts on the first frame).\n"
          "step > 1: only the pixels whose frame row and column are multiples of step count.");
}

static void def_colour_sums(py::class_<LockedHistograms>& cls) {
  cls
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
             std::tuple<int, int, int, int> inner, int step) {
            const auto [view, region] = colour_region(h, frame, region_in);
            require(step >= 1, [&] { return "step must be at least 1, got " + std::to_string(step); });
            py::gil_scoped_release release;
            std::lock_guard<std::mutex> guard(h.lock);
            if (!h.hist.learnt()) throw py::value_error("call learn() before likelihood_sums()");
            const ColourHistograms::Sums s =
                h.hist.likelihood_sums(view, region, span_of(inner), step);
            return std::make_tuple(s.inner, s.region, s.inner_pixels, s.region_pixels);
          },
          py::arg("frame"), py::arg("region"), py::arg("inner"), py::kw_only(),
          py::arg("step") = 1,
          "(inner sum, region sum, inner pixels, region pixels): the likelihood summed over the\n"
          "pixels of region = (x, y, w, h) (inside the frame) and of its part inner = (row0,\n"
          "row1, col0, col1), relative to the region and clipped to it; with step > 1 over\n"
          "the pixels whose frame row and column are multiples of step only.")
      .def_property_readonly("foreground", [](LockedHistograms& h) {
        std::lock_guard<std::mutex> guard(h.lock);
        return copy_of(h.hist.foreground());
      }, "A copy of the foreground histogram (sums to 1 once learnt).")
      .def_property_readonly("background", [](LockedHistograms& h) {
        std::lock_guard<std::mutex> guard(h.lock);
        return copy_of(h.hist.background());
      }, "A copy of the background histogram.");
}

static void def_colour_likelihood(py::class_<LockedHistograms>& cls) {
  cls
      .def_property_readonly("likelihood", [](LockedHistograms& h) {
        std::lock_guard<std::mutex> guard(h.lock);
        return copy_of(h.hist.likelihood());
      }, "A copy of P(target | bin).");
}

void bind_colour(py::module_& m) {
  py::class_<LockedHistograms> cls(
      m, "ColourHistograms",
      "Foreground and background colour histograms (2**(3 * bits) bins each, blended over\n"
      "frames at `rate`) and the per-bin likelihood fg / (fg + bg), 0.5 where both are 0.\n"
      "bin = (b >> s) << 2 bits | (g >> s) << bits | (r >> s), s = 8 - bits; with intensity,\n"
      "the bin of the pixel's luma in all three (gray frames accepted). With step > 1, learn\n"
      "and likelihood_sums read the pixels whose frame row and column are multiples of step.");
  def_colour_model(cls);
  def_colour_sums(cls);
  def_colour_likelihood(cls);
}

}  // namespace wmiltrack::bindings
