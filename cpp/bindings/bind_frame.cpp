#include <pybind11/stl.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "common.hpp"
#include "wmiltrack/frame.hpp"
#include "wmiltrack/sampling.hpp"
#include "wmiltrack/scoring.hpp"

namespace wmiltrack::bindings {

namespace {

// ---- search -------------------------------------------------------------------------------

// One target's search, its arguments checked and copied (so that it runs without the GIL).
struct SearchJob {
  SharedIntegralImage* ii = nullptr;
  py::object keep;                 // the frame (and the objects below) stay alive meanwhile
  std::optional<ImageView> frame;  // compute the integral image over roi first
  Rect roi;
  const FeatureBank* bank = nullptr;
  Int32Array selected;
  std::unique_ptr<WeakGaussians> weak;
  Rect box;
  std::vector<SearchStage> stages;
  int fw = 0, fh = 0;
  CArray<double> cue_table;  // the colour cue's integral image (with `cue`)
  std::optional<BoxMeanCue> cue;
  std::vector<GridResult> out;

  void run() {
    if (frame) ii->compute(*frame, roi);
    const auto table = ii->snapshot();
    if (!table) throw std::invalid_argument("the integral image has not been computed");
    out = search(*table, *bank, selected.data(), static_cast<int>(selected.size()), *weak, box,
                 stages, fw, fh, cue ? &*cue : nullptr);
  }
};

SearchJob make_search(SharedIntegralImage& ii, const py::object& frame,
                      const std::optional<std::tuple<int, int, int, int>>& roi,
                      const FeatureBank& bank, const py::object& selected_obj,
                      const CArray<double>& mu1, const CArray<double>& sigma1,
                      const CArray<double>& mu0, const CArray<double>& sigma0, double guard,
                      std::tuple<int, int, int, int> box,
                      const std::vector<std::tuple<int, int>>& stages,
                      std::tuple<int, int> frame_size, const py::object& colour) {
  SearchJob job;
  job.ii = &ii;
  for (const auto& [radius, step] : stages) {
    require(radius >= 1 && radius <= kMaxSearchRadius,
            "radius must be in 1 .. " + std::to_string(kMaxSearchRadius) + ", got " +
                std::to_string(radius));
    require(step >= 1, "step must be >= 1, got " + std::to_string(step));
    job.stages.push_back(SearchStage{radius, step});
  }
  const auto [x, y, w, h] = box;
  require(w > 0 && h > 0, "box must have positive size");
  job.box = Rect{x, y, w, h};
  std::tie(job.fw, job.fh) = frame_size;
  job.selected = int32_array(selected_obj, "selected");
  require(job.selected.ndim() == 1 && job.selected.size() > 0,
          "selected must be a non-empty 1-D array");
  const py::ssize_t m = mu1.ndim() == 1 ? mu1.shape(0) : -1;
  for (const auto* a : {&mu1, &sigma1, &mu0, &sigma0}) {
    require(a->ndim() == 1 && a->shape(0) == m,
            "mu1, sigma1, mu0, sigma0 must be 1-D with one entry per feature of the pool");
  }
  // The weak classifiers of the selected features, in selection order.
  std::vector<double> g[4];
  const CArray<double>* src[4] = {&mu1, &sigma1, &mu0, &sigma0};
  for (int a = 0; a < 4; ++a) {
    for (py::ssize_t k = 0; k < job.selected.size(); ++k) {
      const std::int32_t f = job.selected.data()[k];
      require(f >= 0 && f < m,
              "selected index " + std::to_string(f) + " outside the pool of " + std::to_string(m));
      g[a].push_back(src[a]->data()[f]);
    }
  }
  job.weak = std::make_unique<WeakGaussians>(g[0].data(), g[1].data(), g[2].data(), g[3].data(),
                                             static_cast<int>(job.selected.size()), guard);
  job.bank = &bank;
  if (!frame.is_none()) {
    require(roi.has_value(), "a frame needs its roi");
    job.frame = image_view(py::reinterpret_borrow<py::array>(frame));
    const auto [rx, ry, rw, rh] = *roi;
    job.roi = Rect{rx, ry, rw, rh};
    job.keep = frame;
    if (bank.planes_needed() > 1) {
      throw py::value_error("the feature bank sums over several planes: compute_channels first");
    }
  } else {
    require_planes(*computed_table(ii), bank);
  }
  if (!colour.is_none()) {
    const auto items = colour.cast<py::tuple>();
    require(items.size() == 5 || items.size() == 6,
            "colour must be (table, x0, y0, weight, offset) or (..., offset, relative)");
    const auto table = items[0].cast<CArray<double>>();
    const auto x0 = items[1].cast<int>();
    const auto y0 = items[2].cast<int>();
    const auto weight = items[3].cast<double>();
    const auto offset = items[4].cast<double>();
    const bool relative = items.size() == 6 && items[5].cast<bool>();
    require(table.ndim() == 2 && table.shape(0) >= 1 && table.shape(1) >= 1,
            "colour: the table must be a 2-D integral image (rows + 1) x (cols + 1)");
    require(weight >= 0.0 && weight <= 1.0, "colour: the weight must be in [0, 1]");
    job.cue_table = table;
    BoxMeanCue cue;
    cue.table = job.cue_table.data();
    cue.rows = static_cast<int>(table.shape(0) - 1);
    cue.cols = static_cast<int>(table.shape(1) - 1);
    cue.x0 = x0;
    cue.y0 = y0;
    cue.weight = weight;
    cue.offset = offset;
    cue.relative = relative;
    cue.k = static_cast<int>(job.selected.size());
    job.cue = cue;
  }
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

// ---- learn --------------------------------------------------------------------------------

struct LearnJob {
  std::shared_ptr<const IntegralImage> table;
  const FeatureBank* bank = nullptr;
  Int32Array xs, ys;
  LearnStep step;
  CArray<double> w_pos;
  CArray<double> model[4];
  CArray<double> extra_neg;
  CArray<double> second[2];
  bool has_second = false;
  py::object selected = py::none(), h = py::none();
  std::int32_t* sel_ptr = nullptr;
  double* h_ptr = nullptr;
  // A frame step's learning job takes its boxes from the bags drawn in the same call, without
  // the GIL (take_bags): their weights, and the log ratios when asked, live here meanwhile.
  std::vector<double> bag_w_pos;
  std::unique_ptr<std::vector<double>> bag_h;

  // The bags drawn where the search landed on `ii` (computed by then): the boxes, the
  // positives' weights, and WMIL dropped when no positive fits in the frame. The job keeps
  // them (xs, ys, step.n_pos), and the caller hands them back from there.
  void take_bags(Bags&& bags, const SharedIntegralImage& ii) {
    const int n_boxes = static_cast<int>(bags.xs.size());
    xs.values = std::move(bags.xs);
    ys.values = std::move(bags.ys);
    xs.shape = ys.shape = {static_cast<py::ssize_t>(n_boxes)};
    step.n_pos = bags.n_pos;
    step.n_neg = n_boxes - bags.n_pos;
    if (bags.n_pos == 0) {  // nothing to select from (nor ratios to return)
      step.select = LearnSelect::kNone;
      sel_ptr = nullptr;
    } else if (step.select == LearnSelect::kWmil) {
      bag_w_pos = std::move(bags.w_pos);
      step.w_pos = bag_w_pos.data();
    } else if (step.select == LearnSelect::kRatios) {
      bag_h = std::make_unique<std::vector<double>>(
          static_cast<std::size_t>(bank->size()) *
          static_cast<std::size_t>(n_boxes + step.n_extra));
      h_ptr = bag_h->data();
    }
    table = ii.snapshot();
    if (!table) throw std::invalid_argument("the integral image has not been computed");
    if (bank->planes_needed() > table->num_channels()) {
      throw std::invalid_argument(
          "the feature bank sums over more planes than the integral image has");
    }
  }

  void run() {
    step.xs = xs.data();
    step.ys = ys.data();
    if (step.n_extra > 0) step.extra_neg = extra_neg.data();
    if (has_second) {
      step.second_mu = second[0].mutable_data();
      step.second_sigma = second[1].mutable_data();
    }
    learn_step(*table, *bank, step, model[0].mutable_data(), model[1].mutable_data(),
               model[2].mutable_data(), model[3].mutable_data(), sel_ptr, h_ptr);
  }
};

LearnJob make_learn(const SharedIntegralImage& shared, const FeatureBank& bank,
                    const py::object& xs_obj, const py::object& ys_obj, int n_pos,
                    const CArray<double>& mu1, const CArray<double>& sigma1,
                    const CArray<double>& mu0, const CArray<double>& sigma0, double lam,
                    bool first_pos, bool first_neg, bool direct_first, bool mil,
                    double sigma_floor, double guard, const std::string& select,
                    const py::object& w_pos_obj, int k, bool code_gradient,
                    const py::object& extra_neg, const py::object& second,
                    bool bags_later = false) {
  LearnJob job;
  if (bags_later) {
    job.xs.shape = job.ys.shape = {0};
  } else {
    job.xs = int32_array(xs_obj, "xs");
    job.ys = int32_array(ys_obj, "ys");
  }
  require(job.xs.ndim() == 1 && job.ys.ndim() == 1 && job.xs.size() == job.ys.size(),
          "xs and ys must be 1-D of one length");
  const int B = static_cast<int>(job.xs.size());
  require(bags_later || (n_pos >= 0 && n_pos <= B), "n_pos must be in 0..len(xs)");
  const py::ssize_t M = bank.size();
  for (const auto* a : {&mu1, &sigma1, &mu0, &sigma0}) {
    require(a->ndim() == 1 && a->shape(0) == M,
            "mu1, sigma1, mu0, sigma0 must hold one entry per feature of the bank");
  }
  LearnStep& step = job.step;
  step.n_pos = n_pos;
  step.n_neg = B - n_pos;
  step.rule.lam = lam;
  step.rule.direct_first = direct_first;
  step.rule.mil = mil;
  step.rule.sigma_floor = sigma_floor;
  step.first_pos = first_pos;
  step.first_neg = first_neg;
  step.guard = guard;
  if (select == "none") {
    step.select = LearnSelect::kNone;
  } else if (select == "wmil") {
    step.select = LearnSelect::kWmil;
    if (!bags_later) {
      job.w_pos = CArray<double>::ensure(w_pos_obj);
      require(job.w_pos && job.w_pos.ndim() == 1 && job.w_pos.shape(0) == n_pos && n_pos > 0,
              "w_pos must hold one weight per positive");
      step.w_pos = job.w_pos.data();
    }
    require(k >= 1 && k <= M, "k must be in 1.." + std::to_string(M));
    step.k = k;
    step.code_gradient = code_gradient;
  } else if (select == "ratios") {
    step.select = LearnSelect::kRatios;
  } else {
    throw py::value_error("select must be 'none', 'wmil' or 'ratios', got '" + select + "'");
  }
  if (!extra_neg.is_none()) {
    job.extra_neg = CArray<double>::ensure(extra_neg);
    require(job.extra_neg && job.extra_neg.ndim() == 2 && job.extra_neg.shape(0) == M,
            "extra_neg must be a 2-D array of feature values, one row per feature of the bank");
    step.n_extra = static_cast<int>(job.extra_neg.shape(1));
  }
  if (!second.is_none()) {
    const auto [mu, sigma, lam2, first2] =
        second.cast<std::tuple<CArray<double>, CArray<double>, double, bool>>();
    require(mu.ndim() == 1 && mu.shape(0) == M && sigma.ndim() == 1 && sigma.shape(0) == M,
            "second: mu and sigma must hold one entry per feature of the bank");
    job.has_second = true;
    job.second[0] = CArray<double>(M);
    job.second[1] = CArray<double>(M);
    std::copy(mu.data(), mu.data() + M, job.second[0].mutable_data());
    std::copy(sigma.data(), sigma.data() + M, job.second[1].mutable_data());
    step.second_rule = step.rule;
    step.second_rule.lam = lam2;
    step.second_rule.first = first2;
  }
  if (!bags_later) {  // else take_bags reads it once the search has computed it
    job.table = computed_table(shared);
    require_planes(*job.table, bank);
  }
  job.bank = &bank;
  // The model out: copies of the model in, updated in place by the core.
  const CArray<double>* in[4] = {&mu1, &sigma1, &mu0, &sigma0};
  for (int a = 0; a < 4; ++a) {
    job.model[a] = CArray<double>(M);
    std::copy(in[a]->data(), in[a]->data() + M, job.model[a].mutable_data());
  }
  if (step.select == LearnSelect::kWmil) {
    py::array_t<std::int32_t> s(k);
    job.sel_ptr = s.mutable_data();
    job.selected = s;
  } else if (step.select == LearnSelect::kRatios && !bags_later) {
    CArray<double> hh({M, static_cast<py::ssize_t>(B + step.n_extra)});
    job.h_ptr = hh.mutable_data();
    job.h = hh;
  }
  return job;
}

py::tuple learn_result(LearnJob& job) {
  py::object mu2 = py::none(), sigma2 = py::none();
  if (job.has_second) {
    mu2 = job.second[0];
    sigma2 = job.second[1];
  }
  if (job.bag_h) {  // the log ratios of bags taken in the core: handed over without a copy
    std::vector<double>* h = job.bag_h.get();
    const py::capsule owner(h, [](void* p) { delete static_cast<std::vector<double>*>(p); });
    job.bag_h.release();  // the capsule owns it now
    const py::ssize_t M = std::max<py::ssize_t>(job.bank->size(), 1);
    job.h = py::array_t<double>({M, static_cast<py::ssize_t>(h->size()) / M}, h->data(), owner);
  }
  const py::object selected = job.step.select == LearnSelect::kWmil ? job.selected : py::none();
  return py::make_tuple(job.model[0], job.model[1], job.model[2], job.model[3], selected, job.h,
                        mu2, sigma2);
}

using SearchArgs =
    std::tuple<SharedIntegralImage*, const FeatureBank*, py::object, CArray<double>,
               CArray<double>, CArray<double>, CArray<double>, double,
               std::tuple<int, int, int, int>, std::vector<std::tuple<int, int>>,
               std::tuple<int, int>, py::object, std::optional<std::tuple<int, int, int, int>>,
               py::object>;
using LearnArgs =
    std::tuple<const SharedIntegralImage*, const FeatureBank*, py::object, py::object, int,
               CArray<double>, CArray<double>, CArray<double>, CArray<double>, double, bool,
               bool, bool, bool, double, double, std::string, py::object, int, bool, py::object,
               py::object>;

SearchJob make_search(const SearchArgs& a) {
  require(std::get<0>(a) != nullptr && std::get<1>(a) != nullptr,
          "every job needs an IntegralImage and a FeatureBank");
  return make_search(*std::get<0>(a), std::get<11>(a), std::get<12>(a), *std::get<1>(a),
                     std::get<2>(a), std::get<3>(a), std::get<4>(a), std::get<5>(a),
                     std::get<6>(a), std::get<7>(a), std::get<8>(a), std::get<9>(a),
                     std::get<10>(a), std::get<13>(a));
}

// With bags_later, the boxes (xs, ys, n_pos, w_pos) are ignored: take_bags gives them.
LearnJob make_learn(const LearnArgs& a, bool bags_later = false) {
  require(std::get<0>(a) != nullptr && std::get<1>(a) != nullptr,
          "every job needs an IntegralImage and a FeatureBank");
  return make_learn(*std::get<0>(a), *std::get<1>(a), std::get<2>(a), std::get<3>(a),
                    std::get<4>(a), std::get<5>(a), std::get<6>(a), std::get<7>(a),
                    std::get<8>(a), std::get<9>(a), std::get<10>(a), std::get<11>(a),
                    std::get<12>(a), std::get<13>(a), std::get<14>(a), std::get<15>(a),
                    std::get<16>(a), std::get<17>(a), std::get<18>(a), std::get<19>(a),
                    std::get<20>(a), std::get<21>(a), bags_later);
}

// ---- bag sampling -------------------------------------------------------------------------

// A numpy.random.Generator's bit generator, held (with its lock) for the draws of one call.
class NumpyBits {
 public:
  explicit NumpyBits(const py::object& rng) {
    const py::object bitgen = py::getattr(rng, "bit_generator", py::none());
    const py::object cap = bitgen.is_none() ? py::none() : py::getattr(bitgen, "capsule", py::none());
    const char* name = py::isinstance<py::capsule>(cap) ? cap.cast<py::capsule>().name() : nullptr;
    if (name == nullptr || std::string(name) != "BitGenerator") {
      throw py::type_error("rng must be a numpy.random.Generator");
    }
    bits_ = *cap.cast<py::capsule>().get_pointer<BitSource>();
    lock_ = bitgen.attr("lock");
    lock_.attr("acquire")();
  }
  NumpyBits(const NumpyBits&) = delete;
  NumpyBits& operator=(const NumpyBits&) = delete;
  ~NumpyBits() { lock_.attr("release")(); }
  BitSource& bits() { return bits_; }

 private:
  BitSource bits_{};
  py::object lock_;
};

// BagSampler's offsets and draw settings, checked and copied.
struct BagJob {
  py::object rng;
  std::vector<std::int32_t> pos, neg;
  std::vector<double> terms;
  BagSpec spec;
};

BagJob make_bags(const py::tuple& args) {
  require(args.size() == 8, "bags must be (rng, pos_offsets, pos_terms, weights, neg_offsets, "
                            "exact, neg_count, keep_prob)");
  BagJob job;
  job.rng = args[0];
  const auto offsets = [](const py::handle& obj, const char* name) {
    const Int32Array a = int32_array(obj, name);
    require(a.ndim() == 2 && a.shape[1] == 2, std::string(name) + " must be an (n, 2) array");
    return a.values;
  };
  job.pos = offsets(args[1], "pos_offsets");
  job.neg = offsets(args[4], "neg_offsets");
  const auto mode = args[3].cast<std::string>();
  BagSpec& spec = job.spec;
  spec.weights = mode == "exp"      ? InstanceWeights::kExp
                 : mode == "exp_sq" ? InstanceWeights::kExpSq
                 : mode == "uniform" ? InstanceWeights::kUniform
                                     : InstanceWeights::kNone;
  require(spec.weights != InstanceWeights::kNone || mode == "none",
          "weights must be 'exp', 'exp_sq', 'uniform' or 'none', got '" + mode + "'");
  spec.n_pos_offsets = static_cast<int>(job.pos.size() / 2);
  spec.n_neg_offsets = static_cast<int>(job.neg.size() / 2);
  if (spec.weights == InstanceWeights::kExp || spec.weights == InstanceWeights::kExpSq) {
    const auto terms = args[2].cast<CArray<double>>();
    require(terms.ndim() == 1 && terms.shape(0) == spec.n_pos_offsets,
            "pos_terms must hold one term per positive offset");
    job.terms.assign(terms.data(), terms.data() + terms.size());
  }
  spec.exact = args[5].cast<bool>();
  spec.neg_count = args[6].cast<int>();
  spec.keep_prob = args[7].cast<double>();
  require(spec.neg_count >= 0, "neg_count must be >= 0");
  spec.pos = job.pos.data();
  spec.neg = job.neg.data();
  spec.pos_terms = job.terms.empty() ? nullptr : job.terms.data();
  return job;
}

void require_threads(int threads) {
  require(threads >= 1, "threads must be >= 1, got " + std::to_string(threads));
}

// Runs every job on up to `threads` threads with the GIL released once; their results, in
// order (the first error is raised after all ran).
template <class Job, class Result>
py::list run_all(std::vector<Job>& jobs, int threads, Result result) {
  {
    py::gil_scoped_release release;
    parallel_for(static_cast<int>(jobs.size()), threads,
                 [&jobs](int i) { jobs[static_cast<std::size_t>(i)].run(); });
  }
  py::list out;
  for (Job& job : jobs) out.append(result(job));
  return out;
}

// ---- whole frame steps ---------------------------------------------------------------------

using FrameStepArgs = std::tuple<SearchArgs, LearnArgs, py::tuple>;

// frame_step() for several targets: each target's search, bag draws and learning in turn, the
// targets on up to `threads` threads with the GIL released once (the learning jobs are built
// before, and take their boxes from the draws in C++). Every job owns its integral image or
// reads a computed one; every job draws from its own generator (their locks are held
// meanwhile).
py::list run_frame_steps(std::vector<FrameStepArgs>& args, int threads) {
  require_threads(threads);
  const std::size_t n = args.size();
  std::vector<SearchJob> searches;
  std::vector<BagJob> bag_jobs;
  searches.reserve(n);
  bag_jobs.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const SearchArgs& search_args = std::get<0>(args[i]);
    require(std::get<0>(std::get<1>(args[i])) == std::get<0>(search_args),
            "frame_step: the learning step must read the search's IntegralImage");
    searches.push_back(make_search(search_args));
    bag_jobs.push_back(make_bags(std::get<2>(args[i])));
  }
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      require(searches[i].ii != searches[j].ii || (!searches[i].frame && !searches[j].frame),
              "frame steps " + std::to_string(j) + " and " + std::to_string(i) +
                  " share an IntegralImage that one of them computes");
      // (Two Generators may wrap one bit generator: it is its lock that each job takes.)
      require(!py::getattr(bag_jobs[i].rng, "bit_generator", bag_jobs[i].rng)
                   .is(py::getattr(bag_jobs[j].rng, "bit_generator", bag_jobs[j].rng)),
              "frame steps " + std::to_string(j) + " and " + std::to_string(i) +
                  " draw from the same generator");
    }
  }
  std::vector<LearnJob> learns;  // their boxes come from the draws below
  learns.reserve(n);
  for (FrameStepArgs& a : args) learns.push_back(make_learn(std::get<1>(a), true));
  std::vector<std::unique_ptr<NumpyBits>> rngs;
  rngs.reserve(n);
  for (BagJob& job : bag_jobs) rngs.push_back(std::make_unique<NumpyBits>(job.rng));
  {
    py::gil_scoped_release release;
    parallel_for(static_cast<int>(n), threads, [&](int k) {
      const std::size_t i = static_cast<std::size_t>(k);
      SearchJob& search = searches[i];
      search.run();
      Rect box = search.box;  // where the search lands
      for (const GridResult& r : search.out) {
        if (r.candidates > 0) {
          box.x += r.dx;
          box.y += r.dy;
        }
      }
      Bags bags = sample_bags(bag_jobs[i].spec, box, search.fw, search.fh, rngs[i]->bits());
      learns[i].take_bags(std::move(bags), *search.ii);  // on the table the search read
      learns[i].run();
    });
  }
  rngs.clear();  // the generators' locks released (with the GIL)
  py::list out;
  for (std::size_t i = 0; i < n; ++i) {
    const LearnJob& learn = learns[i];
    py::array_t<std::int32_t> xs(learn.xs.size(), learn.xs.data());
    py::array_t<std::int32_t> ys(learn.ys.size(), learn.ys.data());
    out.append(py::make_tuple(search_result(searches[i]), learn_result(learns[i]),
                              py::make_tuple(xs, ys, learn.step.n_pos)));
  }
  return out;
}

}  // namespace

void bind_frame(py::module_& m) {
  m.def(
      "search",
      [](SharedIntegralImage& ii, const FeatureBank& bank, const py::object& selected,
         const CArray<double>& mu1, const CArray<double>& sigma1, const CArray<double>& mu0,
         const CArray<double>& sigma0, double guard, std::tuple<int, int, int, int> box,
         const std::vector<std::tuple<int, int>>& stages, std::tuple<int, int> frame_size,
         const py::object& frame, std::optional<std::tuple<int, int, int, int>> roi,
         const py::object& colour) {
        SearchJob job = make_search(ii, frame, roi, bank, selected, mu1, sigma1, mu0, sigma0,
                                    guard, box, stages, frame_size, colour);
        {
          py::gil_scoped_release release;
          job.run();
        }
        return search_result(job);
      },
      py::arg("ii"), py::arg("bank"), py::arg("selected"), py::arg("mu1"), py::arg("sigma1"),
      py::arg("mu0"), py::arg("sigma0"), py::arg("guard"), py::arg("box"), py::arg("stages"),
      py::arg("frame_size"), py::arg("frame") = py::none(), py::arg("roi") = py::none(),
      py::arg("colour") = py::none(),
      "A coarse-to-fine search in one call: score_grid for each (radius, step) of `stages`, each\n"
      "centred where the previous one moved the box.\n\n"
      "mu1, sigma1, mu0, sigma0 are the whole pool's Gaussians; `selected` picks the features\n"
      "(the strong classifier). With `frame` (and `roi`), `ii` is first recomputed over roi\n"
      "(luma), in the same call. Returns one (dx, dy, best_score, n_candidates) per stage,\n"
      "dx/dy relative to that stage's centre (a stage with no candidate does not move the box).\n"
      "colour = (table, x0, y0, weight, offset) merges a cue into every stage's choice: the\n"
      "candidate with the largest (1 - weight) logistic(score / len(selected) - offset) +\n"
      "weight * (mean of the integral image `table`, whose region starts at frame pixel\n"
      "(x0, y0), over the box) wins; its score is reported, and n counts the candidates with a\n"
      "finite score. A candidate outside the table raises IndexError. A sixth element\n"
      "`relative` (bool) measures each score from the stage's best finite score instead:\n"
      "logistic((score - best) / len(selected) - offset).");

  m.def(
      "search_many",
      [](const std::vector<SearchArgs>& jobs_in, int threads) {
        require_threads(threads);
        std::vector<SearchJob> jobs;
        jobs.reserve(jobs_in.size());
        for (const SearchArgs& a : jobs_in) jobs.push_back(make_search(a));
        for (std::size_t i = 0; i < jobs.size(); ++i) {
          for (std::size_t j = 0; j < jobs.size(); ++j) {
            require(i == j || !jobs[i].frame || jobs[i].ii != jobs[j].ii,
                    "job " + std::to_string(i) + " computes an IntegralImage that job " +
                        std::to_string(j) + " also uses");
          }
        }
        return run_all(jobs, threads, search_result);
      },
      py::arg("jobs"), py::arg("threads"),
      "search() for several targets in one call, on up to `threads` threads with the GIL\n"
      "released once: each job is the tuple of search()'s arguments in order (ii, bank,\n"
      "selected, mu1, sigma1, mu0, sigma0, guard, box, stages, frame_size, frame, roi,\n"
      "colour). A job that computes its integral image (frame not None) needs one no other\n"
      "job uses (ValueError). Returns the results in order; the first error is raised after\n"
      "all ran.");

  m.def(
      "learn",
      [](const SharedIntegralImage& shared, const FeatureBank& bank, const py::object& xs,
         const py::object& ys, int n_pos, const CArray<double>& mu1, const CArray<double>& sigma1,
         const CArray<double>& mu0, const CArray<double>& sigma0, double lam, bool first_pos,
         bool first_neg, bool direct_first, bool mil, double sigma_floor, double guard,
         const std::string& select, const py::object& w_pos, int k, bool code_gradient,
         const py::object& extra_neg, const py::object& second) {
        LearnJob job = make_learn(shared, bank, xs, ys, n_pos, mu1, sigma1, mu0, sigma0, lam,
                                  first_pos, first_neg, direct_first, mil, sigma_floor, guard,
                                  select, w_pos, k, code_gradient, extra_neg, second);
        {
          py::gil_scoped_release release;
          job.run();
        }
        return learn_result(job);
      },
      py::arg("ii"), py::arg("bank"), py::arg("xs"), py::arg("ys"), py::arg("n_pos"),
      py::arg("mu1"), py::arg("sigma1"), py::arg("mu0"), py::arg("sigma0"), py::kw_only(),
      py::arg("lam"), py::arg("first_pos"), py::arg("first_neg"), py::arg("direct_first"),
      py::arg("mil"), py::arg("sigma_floor"), py::arg("guard"), py::arg("select"),
      py::arg("w_pos") = py::none(), py::arg("k") = 0, py::arg("code_gradient") = false,
      py::arg("extra_neg") = py::none(), py::arg("second") = py::none(),
      "The learning half of a frame step in one call (the same bits as project, the Gaussian\n"
      "update of each class, log_ratio and wmil_select called one by one).\n\n"
      "Boxes (xs[i], ys[i]): n_pos positives, then negatives; extra_neg (M x e feature\n"
      "values) adds e negatives after them. second = (mu, sigma, lam, first): a second target\n"
      "model updated from the positives alone with its own lambda. Returns (mu1, sigma1, mu0,\n"
      "sigma0, selected, h, mu2, sigma2): the updated model (new arrays; a class without\n"
      "samples keeps its model), the WMIL selection (select='wmil'; else None), the log ratios\n"
      "of both bags, M x (len(xs) + e) (select='ratios'; else None), and the second model\n"
      "updated (None without one).");

  m.def(
      "frame_step",
      [](const SearchArgs& search, const LearnArgs& learn, const py::tuple& bags) {
        std::vector<FrameStepArgs> one{FrameStepArgs{search, learn, bags}};
        return py::tuple(run_frame_steps(one, 1)[0]);
      },
      py::arg("search"), py::arg("learn"), py::arg("bags"),
      "A tracker's whole frame step in one call: search() with the arguments `search`; then the\n"
      "bags around the box where it landed, sampled as BagSampler does from bags = (rng,\n"
      "pos_offsets, pos_terms, weights, neg_offsets, exact, neg_count, keep_prob), the negatives\n"
      "drawn from the numpy Generator `rng` (continuing its stream as numpy's choice / random\n"
      "would); then learn() with the arguments `learn` on the integral image the search read\n"
      "(the same object: computed by the search when it is given a frame and roi, else already\n"
      "computed), its xs, ys, n_pos and w_pos replaced by the bags (and select='none' when no\n"
      "positive fits in the frame). Returns (search's result, learn's result, (xs, ys, n_pos) of\n"
      "the bags).");

  m.def(
      "frame_step_many",
      [](std::vector<FrameStepArgs> jobs, int threads) { return run_frame_steps(jobs, threads); },
      py::arg("jobs"), py::arg("threads"),
      "frame_step() for several targets in one call, on up to `threads` threads with the GIL\n"
      "released once: each job is the tuple (search, learn, bags) of frame_step()'s arguments.\n"
      "Jobs must not share a generator, nor an IntegralImage that one of them computes\n"
      "(ValueError). Returns the results in order; the first error is raised after all jobs\n"
      "ran.");

  m.def(
      "numpy_choice_sorted",
      [](const py::object& rng, std::int64_t n, std::int64_t k) {
        NumpyBits bits(rng);
        return choice_sorted(bits.bits(), n, k);
      },
      py::arg("rng"), py::arg("n"), py::arg("k"),
      "sorted(Generator.choice(n, k, replace=False)), drawn from `rng` as numpy draws it.");
  m.def(
      "numpy_bernoulli_first",
      [](const py::object& rng, std::int64_t n, double p, std::int64_t limit) {
        NumpyBits bits(rng);
        return bernoulli_first(bits.bits(), n, p, limit);
      },
      py::arg("rng"), py::arg("n"), py::arg("p"), py::arg("limit"),
      "The first `limit` indices i with Generator.random(n)[i] < p, drawn from `rng` as numpy\n"
      "draws them.");

  m.def(
      "learn_many",
      [](const std::vector<LearnArgs>& jobs_in, int threads) {
        require_threads(threads);
        std::vector<LearnJob> jobs;
        jobs.reserve(jobs_in.size());
        for (const LearnArgs& a : jobs_in) jobs.push_back(make_learn(a));
        return run_all(jobs, threads, learn_result);
      },
      py::arg("jobs"), py::arg("threads"),
      "learn() for several targets in one call, on up to `threads` threads with the GIL\n"
      "released once: each job is the tuple of learn()'s arguments in order (ii, bank, xs, ys,\n"
      "n_pos, mu1, sigma1, mu0, sigma0, lam, first_pos, first_neg, direct_first, mil,\n"
      "sigma_floor, guard, select, w_pos, k, code_gradient, extra_neg, second). Returns the\n"
      "results in order; the first error is raised after all jobs ran.");
}

}  // namespace wmiltrack::bindings
