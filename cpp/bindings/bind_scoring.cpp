#include <tuple>

#include "common.hpp"
#include "wmiltrack/scoring.hpp"

namespace wmiltrack::bindings {

namespace {

struct Gaussians {
  CArray<double> mu1, sigma1, mu0, sigma0;
};

WeakGaussians make_weak(const Gaussians& g, py::ssize_t n, double guard) {
  for (const auto* a : {&g.mu1, &g.sigma1, &g.mu0, &g.sigma0}) {
    require(a->ndim() == 1 && a->shape(0) == n,
            "mu1, sigma1, mu0, sigma0 must be 1-D with one entry per feature");
  }
  return WeakGaussians(g.mu1.data(), g.sigma1.data(), g.mu0.data(), g.sigma0.data(),
                       static_cast<int>(n), guard);
}

}  // namespace

static void bind_weak_scores(py::module_& m) {
  m.def(
      "log_ratio",
      [](const CArray<double>& values, CArray<double> mu1, CArray<double> sigma1,
         CArray<double> mu0, CArray<double> sigma0, double guard) {
        require(values.ndim() == 2, "values must be features x samples");
        const auto k = values.shape(0), n = values.shape(1);
        const WeakGaussians weak = make_weak({mu1, sigma1, mu0, sigma0}, k, guard);
        CArray<double> out({k, n});
        double* o = out.mutable_data();
        const double* v = values.data();
        {
          py::gil_scoped_release release;
          std::vector<double> scratch(2 * static_cast<std::size_t>(n) + 1);
          for (py::ssize_t f = 0; f < k; ++f) {
            weak.log_ratio(static_cast<int>(f), v + f * n, static_cast<int>(n), o + f * n, false,
                           scratch.data());
          }
        }
        return out;
      },
      py::arg("values"), py::arg("mu1"), py::arg("sigma1"), py::arg("mu0"), py::arg("sigma0"),
      py::arg("guard"),
      "Per-feature Gaussian log-likelihood ratio h(x) = ln(p1 + guard) - ln(p0 + guard).");

  m.def(
      "template_fit",
      [](const SharedIntegralImage& shared, const FeatureBank& bank, int x, int y,
         const CArray<double>& mu, const CArray<double>& sigma) {
        const py::ssize_t n = bank.size();
        require(mu.ndim() == 1 && mu.shape(0) == n && sigma.ndim() == 1 && sigma.shape(0) == n,
                "mu and sigma must hold one entry per feature of the bank");
        const auto table = computed_table(shared);
        require_planes(*table, bank);
        return template_fit(*table, bank, x, y, mu.data(), sigma.data());
      },
      py::arg("ii"), py::arg("bank"), py::arg("x"), py::arg("y"), py::arg("mu"), py::arg("sigma"),
      "How well the box with top-left corner (x, y) fits the target model (mu, sigma) over all\n"
      "features of the bank: -mean(log1p(z**2)), z = (value - mu) / sigma.");

}

static void bind_score_grid(py::module_& m) {
  m.def(
      "score_grid",
      [](const SharedIntegralImage& shared, const FeatureBank& bank, const py::object& selected_obj,
         CArray<double> mu1, CArray<double> sigma1, CArray<double> mu0, CArray<double> sigma0,
         double guard, std::tuple<int, int, int, int> box, int radius, int step,
         std::tuple<int, int> frame_size, bool return_scores) -> py::tuple {
        // The sizes first: nothing is allocated for a grid the core would refuse.
        require(radius >= 1 && radius <= kMaxSearchRadius,
                [&] { return "radius must be in 1 .. " + std::to_string(kMaxSearchRadius) +
                    " (the grid is walked in full), got " + std::to_string(radius); });
        require(step >= 1, [&] { return "step must be >= 1, got " + std::to_string(step); });
        const auto [x, y, w, h] = box;
        const auto [fw, fh] = frame_size;
        require(w > 0 && h > 0, "box must have positive size");
        const Int32Array selected = int32_array(selected_obj, "selected");
        require(selected.ndim() == 1 && selected.size() > 0, "selected must be a non-empty 1-D array");
        const auto ii = computed_table(shared);
        require_planes(*ii, bank);
        const WeakGaussians weak = make_weak({mu1, sigma1, mu0, sigma0}, selected.size(), guard);
        // radius <= kMaxSearchRadius: side <= 2 * 4095 + 1, no overflow.
        const int side = 2 * grid_half_size(radius, step) + 1;
        CArray<double> scores;
        double* scores_ptr = nullptr;
        if (return_scores) {
          scores = CArray<double>({side, side});
          scores_ptr = scores.mutable_data();
        }
        GridResult r;
        {
          py::gil_scoped_release release;
          r = score_grid(*ii, bank, selected.data(), static_cast<int>(selected.size()), weak,
                         Rect{x, y, w, h}, radius, step, fw, fh, scores_ptr);
        }
        if (return_scores) return py::make_tuple(r.dx, r.dy, r.score, r.candidates, scores);
        return py::make_tuple(r.dx, r.dy, r.score, r.candidates);
      },
      py::arg("ii"), py::arg("bank"), py::arg("selected"), py::arg("mu1"), py::arg("sigma1"),
      py::arg("mu0"), py::arg("sigma0"), py::arg("guard"), py::arg("box"), py::arg("radius"),
      py::arg("step"), py::arg("frame_size"), py::arg("return_scores") = false,
      "Score the grid of offsets (i*step, j*step) inside a disc of `radius` around `box`.\n\n"
      "Returns (dx, dy, best_score, n_candidates[, scores]); the best is the first maximum in\n"
      "row-major order; n_candidates == 0 means no candidate box fits in the frame.\n"
      "radius must be in 1 .. 4096 and step >= 1 (checked before anything is allocated).");

}

void bind_scoring(py::module_& m) {
  bind_weak_scores(m);
  bind_score_grid(m);
}

}  // namespace wmiltrack::bindings
