// _core.SearchRequest and _core.search: a target's coarse-to-fine search, cues merged in.
#include <string>

#include "jobs.hpp"

namespace wmiltrack::bindings {

void SearchJob::run() {
  if (frame) ii->compute(*frame, roi);
  const auto table = ii->snapshot();
  if (!table) throw std::invalid_argument("the integral image has not been computed");
  out = search(*table, *bank, selected.data(), static_cast<int>(selected.size()), *weak, box,
               stages, fw, fh, merge ? &*merge : nullptr);
}

namespace {

// The cues' tables and how they merge with the classifier (CueMerge), from
// cues = (tables, offset, relative), tables = [(table, x0, y0, weight[, centre[, pooled]]), ...].
void take_cues(SearchJob& job, const py::object& cues) {
  const auto items = cues.cast<py::tuple>();
  require(items.size() == 3, "cues must be (tables, offset, relative)");
  const auto tables = items[0].cast<py::sequence>();
  require(py::len(tables) >= 1, "cues: at least one (table, x0, y0, weight)");
  job.merge.emplace();
  job.merge->offset = items[1].cast<double>();
  job.merge->relative = items[2].cast<bool>();
  job.merge->k = static_cast<int>(job.selected.size());
  double total = 0.0;
  for (const py::handle entry : tables) {
    const auto cue = entry.cast<py::tuple>();
    require(cue.size() >= 4 && cue.size() <= 6,
            "cues: each table must be (table, x0, y0, weight[, centre[, pooled]])");
    CueTable t;
    t.centre = cue.size() >= 5 && cue[4].cast<bool>();
    t.pooled = cue.size() == 6 && cue[5].cast<bool>();
    require(!t.pooled || t.centre, "cues: only a centre map can be pooled");
    const auto table = cue[0].cast<CArray<double>>();
    const py::ssize_t extra = t.centre ? 0 : 1;  // an integral image has a zero row and column
    require(table.ndim() == 2 && table.shape(0) >= 1 && table.shape(1) >= 1,
            [&] { return t.centre ? "cues: a centre map must be a 2-D array"
                     : "cues: a table must be a 2-D integral image (rows + 1) x (cols + 1)"; });
    t.table = table.data();
    t.rows = static_cast<int>(table.shape(0) - extra);
    t.cols = static_cast<int>(table.shape(1) - extra);
    t.x0 = cue[1].cast<int>();
    t.y0 = cue[2].cast<int>();
    t.weight = cue[3].cast<double>();
    require(t.weight >= 0.0 && t.weight <= 1.0, "cues: a weight must be in [0, 1]");
    total += t.weight;
    job.cue_tables.push_back(table);
    job.merge->cues.push_back(t);
  }
  require(total <= 1.0 + 1e-12, "cues: the weights add up to more than 1");
}

}  // namespace

SearchJob make_search(const SearchRequest& r, py::object keep) {
  require(!r.ii.is_none() && !r.bank.is_none(), "a search needs an IntegralImage and a FeatureBank");
  SearchJob job;
  job.keep = std::move(keep);
  job.ii = r.ii.cast<SharedIntegralImage*>();
  const FeatureBank& bank = *r.bank.cast<const FeatureBank*>();
  for (const auto& [radius, step] : r.stages) {
    require(radius >= 1 && radius <= kMaxSearchRadius,
            [&] { return "radius must be in 1 .. " + std::to_string(kMaxSearchRadius) + ", got " +
                std::to_string(radius); });
    require(step >= 1, [&] { return "step must be >= 1, got " + std::to_string(step); });
    job.stages.push_back(SearchStage{radius, step});
  }
  const auto [x, y, w, h] = r.box;
  require(w > 0 && h > 0, "box must have positive size");
  job.box = Rect{x, y, w, h};
  std::tie(job.fw, job.fh) = r.frame_size;
  job.selected = int32_array(r.selected, "selected");
  require(job.selected.ndim() == 1 && job.selected.size() > 0,
          "selected must be a non-empty 1-D array");
  const py::ssize_t m = r.mu1.ndim() == 1 ? r.mu1.shape(0) : -1;
  for (const auto* a : {&r.mu1, &r.sigma1, &r.mu0, &r.sigma0}) {
    require(a->ndim() == 1 && a->shape(0) == m,
            "mu1, sigma1, mu0, sigma0 must be 1-D with one entry per feature of the pool");
  }
  // The weak classifiers of the selected features, in selection order.
  std::vector<double> g[4];
  const CArray<double>* src[4] = {&r.mu1, &r.sigma1, &r.mu0, &r.sigma0};
  for (int a = 0; a < 4; ++a) {
    for (py::ssize_t k = 0; k < job.selected.size(); ++k) {
      const std::int32_t f = job.selected.data()[k];
      require(f >= 0 && f < m,
              [&] { return "selected index " + std::to_string(f) + " outside the pool of " + std::to_string(m); });
      g[a].push_back(src[a]->data()[f]);
    }
  }
  job.weak = std::make_unique<WeakGaussians>(g[0].data(), g[1].data(), g[2].data(), g[3].data(),
                                             static_cast<int>(job.selected.size()), r.guard);
  job.bank = &bank;
  if (!r.frame.is_none()) {
    require(r.roi.has_value(), "a frame needs its roi");
    job.frame = image_view(py::reinterpret_borrow<py::array>(r.frame));
    const auto [rx, ry, rw, rh] = *r.roi;
    job.roi = Rect{rx, ry, rw, rh};
    if (bank.planes_needed() > 1) {
      throw py::value_error("the feature bank sums over several planes: compute_channels first");
    }
  } else {
    require_planes(*computed_table(*job.ii), bank);
  }
  if (!r.cues.is_none()) take_cues(job, r.cues);
  return job;
}

py::tuple search_result(const SearchJob& job) {
  py::tuple out(job.out.size());
  for (std::size_t i = 0; i < job.out.size(); ++i) {
    const GridResult& r = job.out[i];
    out[i] = py::make_tuple(r.dx, r.dy, r.score, r.candidates);
  }
  return out;
}

static void bind_search_request(py::class_<SearchRequest>& cls) {
  cls
      .def(py::init([](py::object ii, py::object bank, py::object selected,
                       const py::object& mu1, const py::object& sigma1, const py::object& mu0,
                       const py::object& sigma0, double guard, Box box,
                       std::vector<std::tuple<int, int>> stages, std::tuple<int, int> frame_size,
                       py::object frame, std::optional<Box> roi, py::object cues) {
             return SearchRequest{std::move(ii), std::move(bank), std::move(selected),
                                  model_array(mu1, "mu1"), model_array(sigma1, "sigma1"),
                                  model_array(mu0, "mu0"), model_array(sigma0, "sigma0"), guard,
                                  box, std::move(stages), frame_size, std::move(frame), roi,
                                  std::move(cues)};
           }),
           py::arg("ii"), py::arg("bank"), py::arg("selected"), py::arg("mu1"), py::arg("sigma1"),
           py::arg("mu0"), py::arg("sigma0"), py::arg("guard"), py::arg("box"), py::arg("stages"),
           py::arg("frame_size"), py::arg("frame") = py::none(), py::arg("roi") = py::none(),
           py::arg("cues") = py::none())
      .def_readonly("ii", &SearchRequest::ii)
      .def_readonly("bank", &SearchRequest::bank)
      .def_readonly("selected", &SearchRequest::selected)
      .def_readonly("mu1", &SearchRequest::mu1)
      .def_readonly("sigma1", &SearchRequest::sigma1)
      .def_readonly("mu0", &SearchRequest::mu0)
      .def_readonly("sigma0", &SearchRequest::sigma0)
      .def_readonly("guard", &SearchRequest::guard)
      .def_readonly("box", &SearchRequest::box)
      .def_readonly("stages", &SearchRequest::stages)
      .def_readonly("frame_size", &SearchRequest::frame_size)
      .def_readonly("frame", &SearchRequest::frame)
      .def_readonly("roi", &SearchRequest::roi)
      .def_readonly("cues", &SearchRequest::cues);
}

void bind_search(py::module_& m) {
  py::class_<SearchRequest> cls(
      m, "SearchRequest",
      "A coarse-to-fine search's inputs, by name: the integral image `ii` and FeatureBank\n"
      "`bank`; `selected` (the strong classifier's features) and the whole pool's Gaussians\n"
      "mu1, sigma1, mu0, sigma0; the log guard; the starting `box` (x, y, w, h); `stages`, a\n"
      "list of (radius, step); `frame_size` (w, h). With `frame` and `roi`, `ii` is first\n"
      "recomputed over roi (luma) in the same call. `cues` = (tables, offset, relative) merges\n"
      "cues into every stage's choice: `tables` is a list of (table, x0, y0, weight[, centre[,\n"
      "pooled]]),\n"
      "each `table` an integral image of a cue's map whose region starts at frame pixel (x0,\n"
      "y0) (or, with centre=True, the map itself), the weights adding up to W <= 1; the\n"
      "candidate with the largest (1 - W) logistic(score / len(selected) - offset) + the sum of\n"
      "weight * (mean of the map over the box, or the map at the box's centre pixel; with\n"
      "pooled=True, its best within half a step of it) wins, and\n"
      "with `relative` each score is measured from the stage's best finite score. Checked when\n"
      "it runs.");
  bind_search_request(cls);
  m.def(
      "search",
      [](const py::object& request) {
        SearchJob job = make_search(request.cast<const SearchRequest&>(), request);
        {
          py::gil_scoped_release release;
          job.run();
        }
        return search_result(job);
      },
      py::arg("request"),
      "A coarse-to-fine search in one call (a SearchRequest): score_grid for each (radius,\n"
      "step) stage, each centred where the previous one moved the box. Returns one (dx, dy,\n"
      "best_score, n_candidates) per stage, dx/dy relative to that stage's centre (a stage with\n"
      "no candidate does not move the box); with cues n counts the candidates with a finite\n"
      "score, and a candidate outside a cue's table raises IndexError.");
}

}  // namespace wmiltrack::bindings
