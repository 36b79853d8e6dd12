#include <tuple>
#include <vector>

#include <pybind11/stl.h>

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

void bind_scoring(py::module_& m) {
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
      "score_grid",
      [](const SharedIntegralImage& shared, const FeatureBank& bank, const py::object& selected_obj,
         CArray<double> mu1, CArray<double> sigma1, CArray<double> mu0, CArray<double> sigma0,
         double guard, std::tuple<int, int, int, int> box, int radius, int step,
         std::tuple<int, int> frame_size, bool return_scores) -> py::tuple {
        // The sizes first: nothing is allocated for a grid the core would refuse.
        require(radius >= 1 && radius <= kMaxSearchRadius,
                "radius must be in 1 .. " + std::to_string(kMaxSearchRadius) +
                    " (the grid is walked in full), got " + std::to_string(radius));
        require(step >= 1, "step must be >= 1, got " + std::to_string(step));
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

  m.def(
      "search",
      [](const SharedIntegralImage& shared, const FeatureBank& bank, const py::object& selected_obj,
         const CArray<double>& mu1, const CArray<double>& sigma1, const CArray<double>& mu0,
         const CArray<double>& sigma0, double guard, std::tuple<int, int, int, int> box,
         const std::vector<std::tuple<int, int>>& stages_in,
         std::tuple<int, int> frame_size) -> py::tuple {
        std::vector<SearchStage> stages;
        for (const auto& [radius, step] : stages_in) {
          require(radius >= 1 && radius <= kMaxSearchRadius,
                  "radius must be in 1 .. " + std::to_string(kMaxSearchRadius) + ", got " +
                      std::to_string(radius));
          require(step >= 1, "step must be >= 1, got " + std::to_string(step));
          stages.push_back(SearchStage{radius, step});
        }
        const auto [x, y, w, h] = box;
        const auto [fw, fh] = frame_size;
        require(w > 0 && h > 0, "box must have positive size");
        const Int32Array selected = int32_array(selected_obj, "selected");
        require(selected.ndim() == 1 && selected.size() > 0, "selected must be a non-empty 1-D array");
        const py::ssize_t m = mu1.ndim() == 1 ? mu1.shape(0) : -1;
        for (const auto* a : {&mu1, &sigma1, &mu0, &sigma0}) {
          require(a->ndim() == 1 && a->shape(0) == m,
                  "mu1, sigma1, mu0, sigma0 must be 1-D with one entry per feature of the pool");
        }
        // The weak classifiers of the selected features, in selection order.
        std::vector<double> g[4];
        const CArray<double>* src[4] = {&mu1, &sigma1, &mu0, &sigma0};
        for (int a = 0; a < 4; ++a) {
          g[a].reserve(static_cast<std::size_t>(selected.size()));
          for (py::ssize_t k = 0; k < selected.size(); ++k) {
            const std::int32_t f = selected.data()[k];
            require(f >= 0 && f < m, "selected index " + std::to_string(f) +
                                         " outside the pool of " + std::to_string(m));
            g[a].push_back(src[a]->data()[f]);
          }
        }
        const WeakGaussians weak(g[0].data(), g[1].data(), g[2].data(), g[3].data(),
                                 static_cast<int>(selected.size()), guard);
        const auto ii = computed_table(shared);
        require_planes(*ii, bank);
        std::vector<GridResult> results;
        {
          py::gil_scoped_release release;
          results = search(*ii, bank, selected.data(), static_cast<int>(selected.size()), weak,
                           Rect{x, y, w, h}, stages, fw, fh);
        }
        py::tuple out(results.size());
        for (std::size_t i = 0; i < results.size(); ++i) {
          const GridResult& r = results[i];
          out[i] = py::make_tuple(r.dx, r.dy, r.score, r.candidates);
        }
        return out;
      },
      py::arg("ii"), py::arg("bank"), py::arg("selected"), py::arg("mu1"), py::arg("sigma1"),
      py::arg("mu0"), py::arg("sigma0"), py::arg("guard"), py::arg("box"), py::arg("stages"),
      py::arg("frame_size"),
      "A coarse-to-fine search in one call: score_grid for each (radius, step) of `stages`, each\n"
      "centred where the previous one moved the box.\n\n"
      "mu1, sigma1, mu0, sigma0 are the whole pool's Gaussians; `selected` picks the features\n"
      "(the strong classifier). Returns one (dx, dy, best_score, n_candidates) per stage, dx/dy\n"
      "relative to that stage's centre (a stage with no candidate does not move the box).");
}

}  // namespace wmiltrack::bindings
