// Bindings of the correlation-filter kernels: gray patches, fHOG, the translation and scale
// filters (correlation.hpp), one function per bound class (module.cpp calls them, the classes
// a method returns before the classes that return them, so that signatures name Python types).
// Arguments are checked here; the work runs without the GIL.
#include <cmath>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <pybind11/stl.h>

#include "common.hpp"
#include "wmiltrack/correlation.hpp"
#include "wmiltrack/fhog.hpp"

namespace wmiltrack::bindings {

namespace {

using cf::FeatureMap;
using cf::GrayPatch;
using Pair = std::tuple<double, double>;
using Size = std::tuple<int, int>;

py::array_t<float> to_array(const std::vector<float>& v, std::vector<py::ssize_t> shape) {
  py::array_t<float> out(shape);
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

py::array_t<float> feature_array(const FeatureMap& x) {
  return to_array(x.data, {x.channels, x.rows, x.cols});
}

FeatureMap feature_map(const py::array& features) {
  const auto a = CArray<float>::ensure(features);
  require(static_cast<bool>(a), "features must be a float array");
  require(a.ndim() == 3, [&] { return "features must be channels x rows x cols, got " +
                             std::to_string(a.ndim()) + " dimensions"; });
  FeatureMap x;
  x.channels = static_cast<int>(a.shape(0));
  x.rows = static_cast<int>(a.shape(1));
  x.cols = static_cast<int>(a.shape(2));
  x.data.assign(a.data(), a.data() + a.size());
  return x;
}

std::vector<float> sample_rows(const py::array& samples, int rows, int cols) {
  const auto a = CArray<float>::ensure(samples);
  require(static_cast<bool>(a), "samples must be a float array");
  require(a.ndim() == 2 && a.shape(0) == rows && a.shape(1) == cols,
          [&] { return "samples must have shape (" + std::to_string(rows) + ", " + std::to_string(cols) + ")"; });
  return std::vector<float>(a.data(), a.data() + a.size());
}

void check_region(Pair centre, Pair size) {
  const auto [cx, cy] = centre;
  const auto [w, h] = size;
  require(std::isfinite(cx) && std::isfinite(cy), "centre must be finite");
  require(std::isfinite(w) && std::isfinite(h) && w > 0 && h > 0,
          "size must be positive and finite");
}

GrayPatch sample(const ImageView& view, Pair centre, Pair size, Size out_size) {
  const auto [cx, cy] = centre;
  const auto [w, h] = size;
  const auto [ow, oh] = out_size;
  return cf::sample_gray(view, cx, cy, w, h, ow, oh);
}

// The arguments of scale samples (scale_samples, ScaleFilter.sample), checked.
void check_scale_samples(Pair centre, Pair size, const std::vector<double>& factors,
                         Size model_size, int cell) {
  check_region(centre, size);
  require(!factors.empty(), "factors must not be empty");
  for (double f : factors) {
    require(std::isfinite(f) && f > 0.0, "factors must be positive and finite");
  }
  const auto [mw, mh] = model_size;
  require(cell >= 1, [&] { return "cell must be at least 1, got " + std::to_string(cell); });
  require(mw >= cell && mh >= cell, "model_size must hold at least one cell");
}

struct LockedTranslation {
  cf::TranslationFilter filter;
  std::mutex lock;
  LockedTranslation(int rows, int cols, int channels, double sigma, double lambda, int compressed)
      : filter(rows, cols, channels, sigma, lambda, compressed) {}
  explicit LockedTranslation(const cf::TranslationFilter& f) : filter(f) {}
};

struct LockedScale {
  cf::ScaleFilter filter;
  std::mutex lock;
  LockedScale(int n, int dims, double sigma, double lambda) : filter(n, dims, sigma, lambda) {}
  explicit LockedScale(const cf::ScaleFilter& f) : filter(f) {}
};

void check_rate(double rate) {
  require(rate > 0.0 && rate <= 1.0, [&] { return "rate must be in (0, 1], got " + std::to_string(rate); });
}

void require_shape(const LockedTranslation& t, const FeatureMap& x) {
  require(x.channels == t.filter.channels() && x.rows == t.filter.rows() &&
              x.cols == t.filter.cols(),
          "features must have shape (channels, rows, cols) of the filter");
}

void require_shape(const LockedTranslation& t, const cf::Spectrum& s) {
  require(s.channels == t.filter.filter_channels() && s.rows == t.filter.rows() &&
              s.cols == t.filter.cols(),
          "the spectrum is not of this filter's shape");
}

// transform() under the lock (a compressed filter's projection comes from its first learn);
// the caller has released the GIL.
cf::Spectrum transform_locked(LockedTranslation& t, const FeatureMap& x) {
  std::lock_guard<std::mutex> guard(t.lock);
  if (t.filter.filter_channels() < t.filter.channels() && t.filter.projection().empty()) {
    throw py::value_error("a compressed filter learns before it transforms a sample");
  }
  return t.filter.transform(x);
}

// respond() to features or to a transformed sample, checked, without the GIL, under the lock.
template <typename Sample>
cf::TranslationResponse respond_locked(LockedTranslation& t, const Sample& z, int exclusion) {
  require(exclusion >= 0, "exclusion must be >= 0");
  require_shape(t, z);
  py::gil_scoped_release release;
  std::lock_guard<std::mutex> guard(t.lock);
  if (!t.filter.trained()) throw py::value_error("call learn() before respond()");
  return t.filter.respond(z, exclusion);
}

}  // namespace

// The free functions: gray patches, fHOG and scale samples of a frame region.
static void bind_fhog(py::module_& m) {
  m.attr("FHOG_CHANNELS") = cf::kFhogChannels;
  m.def(
      "cf_gray_patch",
      [](const py::array& frame, Pair centre, Pair size, Size out_size) {
        const ImageView view = image_view(frame);
        check_region(centre, size);
        require(std::get<0>(out_size) >= 1 && std::get<1>(out_size) >= 1,
                "out_size must be at least (1, 1)");
        GrayPatch p;
        {
          py::gil_scoped_release release;
          p = sample(view, centre, size, out_size);
        }
        return to_array(p.pixels, {p.rows, p.cols});
      },
      py::arg("frame"), py::arg("centre"), py::arg("size"), py::arg("out_size"),
      "The frame region of size = (w, h) centred on centre = (cx, cy) (frame pixels, may be\n"
      "fractional; outside the frame the nearest edge pixel), resampled to out_size = (w, h)\n"
      "pixels of luma / 255 (float32, rows x cols): tent-weighted, bilinear when enlarging and\n"
      "an anti-aliased average when shrinking.");
  m.def(
      "fhog",
      [](const py::array& patch, int cell) {
        const auto a = CArray<float>::ensure(patch);
        require(static_cast<bool>(a) && a.ndim() == 2, "patch must be a 2-D float array");
        require(cell >= 1, [&] { return "cell must be at least 1, got " + std::to_string(cell); });
        require(a.shape(0) >= cell && a.shape(1) >= cell, "the patch is smaller than one cell");
        GrayPatch p;
        p.rows = static_cast<int>(a.shape(0));
        p.cols = static_cast<int>(a.shape(1));
        p.pixels.assign(a.data(), a.data() + a.size());
        FeatureMap x;
        {
          py::gil_scoped_release release;
          x = cf::fhog(p, cell);
        }
        return feature_array(x);
      },
      py::arg("patch"), py::arg("cell") = 4,
      "fHOG (Felzenszwalb's 31 features per cell: 18 signed and 9 unsigned orientation bins,\n"
      "4 block energies) of a gray patch: float32 (31, rows // cell, cols // cell).");
}

static void bind_fhog_samples(py::module_& m) {
  m.def(
      "fhog_region",
      [](const py::array& frame, Pair centre, Pair size, Size out_size, int cell) {
        const ImageView view = image_view(frame);
        check_region(centre, size);
        require(cell >= 1, [&] { return "cell must be at least 1, got " + std::to_string(cell); });
        require(std::get<0>(out_size) >= cell && std::get<1>(out_size) >= cell,
                "out_size must hold at least one cell");
        FeatureMap x;
        {
          py::gil_scoped_release release;
          x = cf::fhog(sample(view, centre, size, out_size), cell);
        }
        return feature_array(x);
      },
      py::arg("frame"), py::arg("centre"), py::arg("size"), py::arg("out_size"),
      py::arg("cell") = 4, "fhog(cf_gray_patch(frame, centre, size, out_size), cell) in one call.");
  m.def(
      "scale_samples",
      [](const py::array& frame, Pair centre, Pair size, const std::vector<double>& factors,
         Size model_size, int cell) {
        const ImageView view = image_view(frame);
        check_scale_samples(centre, size, factors, model_size, cell);
        const auto [mw, mh] = model_size;
        const auto [cx, cy] = centre;
        const auto [w, h] = size;
        const int dims = cf::scale_sample_dims(mw, mh, cell);
        std::vector<float> s;
        {
          py::gil_scoped_release release;
          s = cf::scale_samples(view, cx, cy, w, h, factors, mw, mh, cell);
        }
        return to_array(s, {static_cast<py::ssize_t>(factors.size()), dims});
      },
      py::arg("frame"), py::arg("centre"), py::arg("size"), py::arg("factors"),
      py::arg("model_size"), py::arg("cell") = 4,
      "For each factor f: fHOG (cell) of the region of size (w f, h f) around centre,\n"
      "resampled to model_size = (w, h); float32 (len(factors), dims), one sample a row.");
}

void bind_cf_features(py::module_& m) {
  bind_fhog(m);
  bind_fhog_samples(m);
}

void bind_translation_response(py::module_& m) {
  py::class_<cf::TranslationResponse>(
      m, "TranslationResponse",
      "A translation filter's response to one sample and the confidences of its peak.")
      .def_property_readonly(
          "values", [](const cf::TranslationResponse& r) { return to_array(r.values, {r.rows, r.cols}); },
          "Score per circular shift (rows x cols): [r, c] is the content moved by (r, c) cells.")
      .def_readonly("row_shift", &cf::TranslationResponse::row_shift,
                    "The peak's shift in cells (sub-cell), in [-rows/2, rows/2).")
      .def_readonly("col_shift", &cf::TranslationResponse::col_shift,
                    "The peak's shift in cells (sub-cell), in [-cols/2, cols/2).")
      .def_readonly("peak", &cf::TranslationResponse::peak, "The largest value.")
      .def_readonly("psr", &cf::TranslationResponse::psr,
                    "Peak-to-sidelobe ratio: (peak - mean) / std outside the peak's window.")
      .def_readonly("apce", &cf::TranslationResponse::apce,
                    "Average peak-to-correlation energy: (max - min)^2 / mean((v - min)^2).")
      .def(
          "map",
          [](const cf::TranslationResponse& r, Pair centre, Pair cell,
             std::tuple<int, int, int, int> region) {
            const auto [cx, cy] = centre;
            const auto [cw, ch] = cell;
            const auto [x0, y0, x1, y1] = region;
            require(std::isfinite(cx) && std::isfinite(cy), "centre must be finite");
            require(std::isfinite(cw) && std::isfinite(ch) && cw > 0 && ch > 0,
                    "cell must be positive and finite");
            require(x1 > x0 && y1 > y0, "region must be (x0, y0, x1, y1) with x1 > x0, y1 > y0");
            std::vector<double> v;
            {
              py::gil_scoped_release release;
              v = cf::response_map(r, cx, cy, cw, ch, x0, y0, x1, y1);
            }
            py::array_t<double> out({static_cast<py::ssize_t>(y1 - y0), static_cast<py::ssize_t>(x1 - x0)});
            std::copy(v.begin(), v.end(), out.mutable_data());
            return out;
          },
          py::arg("centre"), py::arg("cell"), py::arg("region"),
          "The response at every pixel of region = (x0, y0, x1, y1) taken as the target's\n"
          "centre, for a search centred at centre = (cx, cy) with cells of cell = (w, h) frame\n"
          "pixels: bilinear between cells (wrapping around), divided by the peak when it is\n"
          "positive, clipped to [0, 1]; float64 (y1 - y0, x1 - x0).");
}

void bind_spectrum(py::module_& m) {
  py::class_<cf::Spectrum>(
      m, "Spectrum",
      "A sample as one translation filter takes it (its windowed, possibly compressed\n"
      "features' half spectra), from TranslationFilter.sample or .transform.")
      .def_readonly("channels", &cf::Spectrum::channels)
      .def_readonly("rows", &cf::Spectrum::rows)
      .def_readonly("cols", &cf::Spectrum::cols);
}

static void def_translation_model(py::class_<LockedTranslation>& cls) {
  cls
      .def(py::init([](int rows, int cols, int channels, double sigma, double lam,
                       int compressed) {
             require(rows >= 1 && cols >= 1 && channels >= 1,
                     "rows, cols and channels must be at least 1");
             require(std::isfinite(sigma) && sigma > 0.0, "sigma must be positive");
             require(std::isfinite(lam) && lam >= 0.0, "lam must be non-negative");
             require(compressed >= 0, "compressed must be >= 0");
             return std::make_unique<LockedTranslation>(rows, cols, channels, sigma, lam,
                                                        compressed);
           }),
           py::arg("rows"), py::arg("cols"), py::arg("channels"), py::arg("sigma"),
           py::arg("lam"), py::arg("compressed") = 0,
           "compressed in 1 .. channels - 1 projects the features onto that many channels, the\n"
           "principal axes of the first learnt sample (ECO), fixed from then on.")
      .def(
          "copy",
          [](LockedTranslation& t) {
            std::lock_guard<std::mutex> guard(t.lock);
            return std::make_unique<LockedTranslation>(t.filter);
          },
          "An independent copy (the model as it is now).")
      .def_property_readonly("rows", [](const LockedTranslation& t) { return t.filter.rows(); })
      .def_property_readonly("cols", [](const LockedTranslation& t) { return t.filter.cols(); })
      .def_property_readonly("channels",
                             [](const LockedTranslation& t) { return t.filter.channels(); })
      .def_property_readonly(
          "filter_channels", [](const LockedTranslation& t) { return t.filter.filter_channels(); },
          "Channels of the filter itself: compressed, or channels without a projection.")
      .def_property_readonly(
          "projection",
          [](LockedTranslation& t) {
            std::lock_guard<std::mutex> guard(t.lock);
            const auto& p = t.filter.projection();
            const py::ssize_t k = p.empty() ? 0 : t.filter.filter_channels();
            return to_array(p, {k, t.filter.channels()});
          },
          "The projection (filter_channels x channels; 0 rows without one or before learn).");
}

static void def_translation_sampling(py::class_<LockedTranslation>& cls) {
  cls
      .def(
          "sample",
          [](LockedTranslation& t, const py::array& frame, Pair centre, Pair size, Size out_size,
             int cell) {
            const ImageView view = image_view(frame);
            check_region(centre, size);
            require(cell >= 1, [&] { return "cell must be at least 1, got " + std::to_string(cell); });
            const auto [ow, oh] = out_size;
            require(ow / cell == t.filter.cols() && oh / cell == t.filter.rows(),
                    "out_size / cell must be the filter's (cols, rows)");
            py::gil_scoped_release release;
            return transform_locked(t, cf::fhog(sample(view, centre, size, out_size), cell));
          },
          py::arg("frame"), py::arg("centre"), py::arg("size"), py::arg("out_size"),
          py::arg("cell") = 4,
          "transform(fhog_region(frame, centre, size, out_size, cell)) in one call.")
      .def(
          "transform",
          [](LockedTranslation& t, const py::array& features) {
            const FeatureMap x = feature_map(features);
            require_shape(t, x);
            py::gil_scoped_release release;
            return transform_locked(t, x);
          },
          py::arg("features"),
          "The sample as this filter takes it (features x window, projected, half spectra).")
      .def(
          "learn_spectrum",
          [](LockedTranslation& t, const cf::Spectrum& s, double rate, Pair shift) {
            check_rate(rate);
            const auto [rs, cs] = shift;
            require(std::isfinite(rs) && std::isfinite(cs), "shift must be finite");
            require_shape(t, s);
            py::gil_scoped_release release;
            std::lock_guard<std::mutex> guard(t.lock);
            if (!t.filter.trained()) throw py::value_error("the first learn() takes features");
            t.filter.learn(s, rate, rs, cs);
          },
          py::arg("spectrum"), py::arg("rate"), py::arg("shift") = Pair{0.0, 0.0},
          "Fold in a transformed sample whose target sits shift = (rows, cols) cells from its\n"
          "centre (moved circularly so that the target is centred, as ECO trains on its search\n"
          "sample).");
}

static void def_translation_learning(py::class_<LockedTranslation>& cls) {
  cls
      .def(
          "respond_spectrum",
          [](LockedTranslation& t, const cf::Spectrum& s, int exclusion) {
            return respond_locked(t, s, exclusion);
          },
          py::arg("spectrum"), py::arg("exclusion") = 5,
          "respond() to a transformed sample.")
      .def_property_readonly("trained", [](LockedTranslation& t) {
        std::lock_guard<std::mutex> guard(t.lock);
        return t.filter.trained();
      })
      .def_property_readonly(
          "window",
          [](const LockedTranslation& t) {
            return to_array(t.filter.window(), {t.filter.rows(), t.filter.cols()});
          },
          "The Hann window multiplied into every plane (rows x cols).")
      .def_property_readonly(
          "label",
          [](const LockedTranslation& t) {
            return to_array(t.filter.label(), {t.filter.rows(), t.filter.cols()});
          },
          "The Gaussian label, peak at (0, 0), circular (rows x cols).")
      .def(
          "learn",
          [](LockedTranslation& t, const py::array& features, double rate) {
            check_rate(rate);
            const FeatureMap x = feature_map(features);
            require_shape(t, x);
            py::gil_scoped_release release;
            std::lock_guard<std::mutex> guard(t.lock);
            t.filter.learn(x, rate);
          },
          py::arg("features"), py::arg("rate"),
          "Fold in a sample (channels x rows x cols, centred on the target): the first call\n"
          "replaces the model, later ones blend it in at rate.")
      .def(
          "respond",
          [](LockedTranslation& t, const py::array& features, int exclusion) {
            return respond_locked(t, feature_map(features), exclusion);
          },
          py::arg("features"), py::arg("exclusion") = 5,
          "The response to a sample, its sub-cell peak and confidences (PSR leaves out the\n"
          "(2 exclusion + 1)^2 cells around the peak).");
}

void bind_translation_filter(py::module_& m) {
  py::class_<LockedTranslation> cls(
      m, "TranslationFilter",
      "A multi-channel linear correlation filter over rows x cols cells, trained and applied\n"
      "in the Fourier domain: a Hann window on every plane, a Gaussian label (sigma cells)\n"
      "peaked at shift (0, 0), numerator conj(Y) X_k / N and denominator sum |X_k|^2 / N kept\n"
      "as running averages, response real(ifft2(sum conj(A_k) Z_k / (B + lam)))).");
  def_translation_model(cls);
  def_translation_sampling(cls);
  def_translation_learning(cls);
}

void bind_scale_response(py::module_& m) {
  py::class_<cf::ScaleResponse>(m, "ScaleResponse", "A scale filter's response.")
      .def_property_readonly(
          "values",
          [](const cf::ScaleResponse& r) {
            return to_array(r.values, {static_cast<py::ssize_t>(r.values.size())});
          },
          "One score per scale sample.")
      .def_readonly("best", &cf::ScaleResponse::best, "Index of the largest score.")
      .def_readonly("offset", &cf::ScaleResponse::offset,
                    "Sub-sample refinement of best, in [-0.5, 0.5] (0 at the ends).");
}

static void def_scale_model(py::class_<LockedScale>& cls) {
  cls
      .def(py::init([](int num_scales, int dims, double sigma, double lam) {
             require(num_scales >= 3, "num_scales must be at least 3");
             require(dims >= 1, "dims must be at least 1");
             require(std::isfinite(sigma) && sigma > 0.0, "sigma must be positive");
             require(std::isfinite(lam) && lam >= 0.0, "lam must be non-negative");
             return std::make_unique<LockedScale>(num_scales, dims, sigma, lam);
           }),
           py::arg("num_scales"), py::arg("dims"), py::arg("sigma"), py::arg("lam"))
      .def(
          "copy",
          [](LockedScale& s) {
            std::lock_guard<std::mutex> guard(s.lock);
            return std::make_unique<LockedScale>(s.filter);
          },
          "An independent copy (the model as it is now).")
      .def_property_readonly("num_scales", [](const LockedScale& s) { return s.filter.num_scales(); })
      .def_property_readonly("dims", [](const LockedScale& s) { return s.filter.dims(); })
      .def_property_readonly("trained", [](LockedScale& s) {
        std::lock_guard<std::mutex> guard(s.lock);
        return s.filter.trained();
      })
      .def(
          "learn",
          [](LockedScale& s, const py::array& samples, double rate) {
            check_rate(rate);
            const std::vector<float> v =
                sample_rows(samples, s.filter.num_scales(), s.filter.dims());
            py::gil_scoped_release release;
            std::lock_guard<std::mutex> guard(s.lock);
            s.filter.learn(v, rate);
          },
          py::arg("samples"), py::arg("rate"),
          "Fold in num_scales x dims samples (the first call replaces the model).")
      .def(
          "respond",
          [](LockedScale& s, const py::array& samples) {
            const std::vector<float> v =
                sample_rows(samples, s.filter.num_scales(), s.filter.dims());
            py::gil_scoped_release release;
            std::lock_guard<std::mutex> guard(s.lock);
            if (!s.filter.trained()) throw py::value_error("call learn() before respond()");
            return s.filter.respond(v);
          },
          py::arg("samples"), "The response to num_scales x dims samples.");
}

static void def_scale_spectra(py::class_<LockedScale>& cls) {
  cls
      .def(
          "sample",
          [](LockedScale& s, const py::array& frame, Pair centre, Pair size,
             const std::vector<double>& factors, Size model_size, int cell) {
            const ImageView view = image_view(frame);
            check_scale_samples(centre, size, factors, model_size, cell);
            require(static_cast<int>(factors.size()) == s.filter.num_scales(),
                    "factors must hold num_scales values");
            const auto [mw, mh] = model_size;
            require(cf::scale_sample_dims(mw, mh, cell) == s.filter.dims(),
                    "model_size and cell must give the filter's dims");
            const auto [cx, cy] = centre;
            const auto [w, h] = size;
            py::gil_scoped_release release;
            const std::vector<float> v = cf::scale_samples(view, cx, cy, w, h, factors, mw, mh, cell);
            return s.filter.transform(v);
          },
          py::arg("frame"), py::arg("centre"), py::arg("size"), py::arg("factors"),
          py::arg("model_size"), py::arg("cell") = 4,
          "The scale samples (scale_samples) as this filter takes them, in one call.")
      .def(
          "learn_spectrum",
          [](LockedScale& s, const cf::Spectrum& sp, double rate, double shift) {
            check_rate(rate);
            require(std::isfinite(shift), "shift must be finite");
            require(sp.channels == s.filter.dims() && sp.rows == 1 && sp.cols == s.filter.num_scales(),
                    "the spectrum is not of this filter's shape");
            py::gil_scoped_release release;
            std::lock_guard<std::mutex> guard(s.lock);
            s.filter.learn(sp, rate, shift);
          },
          py::arg("spectrum"), py::arg("rate"), py::arg("shift") = 0.0,
          "Fold in transformed samples whose target size sits shift samples from the middle.")
      .def(
          "respond_spectrum",
          [](LockedScale& s, const cf::Spectrum& sp) {
            require(sp.channels == s.filter.dims() && sp.rows == 1 && sp.cols == s.filter.num_scales(),
                    "the spectrum is not of this filter's shape");
            py::gil_scoped_release release;
            std::lock_guard<std::mutex> guard(s.lock);
            if (!s.filter.trained()) throw py::value_error("call learn() before respond()");
            return s.filter.respond(sp);
          },
          py::arg("spectrum"), "respond() to transformed samples.");
}

void bind_scale_filter(py::module_& m) {
  py::class_<LockedScale> cls(
      m, "ScaleFilter",
      "A 1-D correlation filter over num_scales samples of dims features (DSST): a Hann\n"
      "window over the scales, a Gaussian label (sigma samples) peaked on the middle sample,\n"
      "numerator conj(Y) X_d and denominator sum |X_d|^2 kept as running averages.");
  def_scale_model(cls);
  def_scale_spectra(cls);
}

}  // namespace wmiltrack::bindings
