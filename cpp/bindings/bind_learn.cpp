// _core.LearnRequest and _core.learn: a target's learning step (projection, Gaussian updates,
// log ratios and WMIL selection) in one call.
#include <string>

#include "jobs.hpp"

namespace wmiltrack::bindings {

void LearnJob::take_bags(Bags&& bags, const SharedIntegralImage& ii) {
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
        static_cast<std::size_t>(bank->size()) * static_cast<std::size_t>(n_boxes + step.n_extra));
    h_ptr = bag_h->data();
  }
  table = ii.snapshot();
  if (!table) throw std::invalid_argument("the integral image has not been computed");
  if (bank->planes_needed() > table->num_channels()) {
    throw std::invalid_argument("the feature bank sums over more planes than the integral image has");
  }
}

void LearnJob::run() {
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

// The request's feature selection (none, WMIL's with its positives' weights, or MILBoost's log
// ratios) into the job's step.
static void take_selection(const LearnRequest& r, LearnJob& job, bool bags_later, py::ssize_t M) {
  LearnStep& step = job.step;
  const int n_pos = r.n_pos;
  const int k = r.k;
  if (r.select == "none") {
    step.select = LearnSelect::kNone;
  } else if (r.select == "wmil") {
    step.select = LearnSelect::kWmil;
    if (!bags_later) {
      job.w_pos = CArray<double>::ensure(r.w_pos);
      require(job.w_pos && job.w_pos.ndim() == 1 && job.w_pos.shape(0) == n_pos && n_pos > 0,
              "w_pos must hold one weight per positive");
      step.w_pos = job.w_pos.data();
    }
    require(k >= 1 && k <= M, [&] { return "k must be in 1.." + std::to_string(M); });
    step.k = k;
    step.code_gradient = r.code_gradient;
  } else if (r.select == "ratios") {
    step.select = LearnSelect::kRatios;
  } else {
    throw py::value_error("select must be 'none', 'wmil' or 'ratios', got '" + r.select + "'");
  }
}

// The request's extra negatives and second target model into the job.
static void take_extras(const LearnRequest& r, LearnJob& job, py::ssize_t M) {
  LearnStep& step = job.step;
  if (!r.extra_neg.is_none()) {
    job.extra_neg = CArray<double>::ensure(r.extra_neg);
    require(job.extra_neg && job.extra_neg.ndim() == 2 && job.extra_neg.shape(0) == M,
            "extra_neg must be a 2-D array of feature values, one row per feature of the bank");
    step.n_extra = static_cast<int>(job.extra_neg.shape(1));
  }
  if (!r.second.is_none()) {
    const auto [mu, sigma, lam2, first2] =
        r.second.cast<std::tuple<CArray<double>, CArray<double>, double, bool>>();
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
}

// The job's outputs: the model's copies that the core updates in place, and the selection's
// or the log ratios' arrays.
static void make_outputs(const LearnRequest& r, LearnJob& job, bool bags_later, py::ssize_t M, int B) {
  const LearnStep& step = job.step;
  const int k = r.k;
  // The model out: copies of the model in, updated in place by the core.
  const CArray<double>* in[4] = {&r.mu1, &r.sigma1, &r.mu0, &r.sigma0};
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
}

LearnJob make_learn(const LearnRequest& r, py::object keep, bool bags_later) {
  require(!r.ii.is_none() && !r.bank.is_none(),
          "a learning step needs an IntegralImage and a FeatureBank");
  const SharedIntegralImage& shared = *r.ii.cast<const SharedIntegralImage*>();
  const FeatureBank& bank = *r.bank.cast<const FeatureBank*>();
  LearnJob job;
  job.keep = std::move(keep);
  if (bags_later) {
    job.xs.shape = job.ys.shape = {0};
  } else {
    job.xs = int32_array(r.xs, "xs");
    job.ys = int32_array(r.ys, "ys");
  }
  require(job.xs.ndim() == 1 && job.ys.ndim() == 1 && job.xs.size() == job.ys.size(),
          "xs and ys must be 1-D of one length");
  const int B = static_cast<int>(job.xs.size());
  const int n_pos = r.n_pos;
  require(bags_later || (n_pos >= 0 && n_pos <= B), "n_pos must be in 0..len(xs)");
  const py::ssize_t M = bank.size();
  for (const auto* a : {&r.mu1, &r.sigma1, &r.mu0, &r.sigma0}) {
    require(a->ndim() == 1 && a->shape(0) == M,
            "mu1, sigma1, mu0, sigma0 must hold one entry per feature of the bank");
  }
  LearnStep& step = job.step;
  step.n_pos = n_pos;
  step.n_neg = B - n_pos;
  step.rule.lam = r.lam;
  step.rule.direct_first = r.direct_first;
  step.rule.mil = r.mil;
  step.rule.sigma_floor = r.sigma_floor;
  step.first_pos = r.first_pos;
  step.first_neg = r.first_neg;
  step.guard = r.guard;
  take_selection(r, job, bags_later, M);
  take_extras(r, job, M);
  if (!bags_later) {  // else take_bags reads it once the search has computed it
    job.table = computed_table(shared);
    require_planes(*job.table, bank);
  }
  job.bank = &bank;
  make_outputs(r, job, bags_later, M, B);
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

static void bind_learn_request(py::class_<LearnRequest>& cls) {
  cls
      .def(py::init([](py::object ii, py::object bank, py::object xs, py::object ys, int n_pos,
                       const py::object& mu1, const py::object& sigma1, const py::object& mu0,
                       const py::object& sigma0, double lam, bool first_pos, bool first_neg,
                       bool direct_first, bool mil, double sigma_floor, double guard,
                       std::string select, py::object w_pos, int k, bool code_gradient,
                       py::object extra_neg, py::object second) {
             return LearnRequest{std::move(ii), std::move(bank), std::move(xs), std::move(ys),
                                 n_pos, model_array(mu1, "mu1"), model_array(sigma1, "sigma1"),
                                 model_array(mu0, "mu0"), model_array(sigma0, "sigma0"), lam,
                                 first_pos, first_neg, direct_first, mil,
                                 sigma_floor, guard, std::move(select), std::move(w_pos), k,
                                 code_gradient, std::move(extra_neg), std::move(second)};
           }),
           py::arg("ii"), py::arg("bank"), py::arg("xs"), py::arg("ys"), py::arg("n_pos"),
           py::arg("mu1"), py::arg("sigma1"), py::arg("mu0"), py::arg("sigma0"),
           py::arg("lam"), py::arg("first_pos"), py::arg("first_neg"), py::arg("direct_first"),
           py::arg("mil"), py::arg("sigma_floor"), py::arg("guard"), py::arg("select"),
           py::arg("w_pos") = py::none(), py::arg("k") = 0, py::arg("code_gradient") = false,
           py::arg("extra_neg") = py::none(), py::arg("second") = py::none())
      .def_readonly("ii", &LearnRequest::ii)
      .def_readonly("bank", &LearnRequest::bank)
      .def_readonly("xs", &LearnRequest::xs)
      .def_readonly("ys", &LearnRequest::ys)
      .def_readonly("n_pos", &LearnRequest::n_pos)
      .def_readonly("mu1", &LearnRequest::mu1)
      .def_readonly("sigma1", &LearnRequest::sigma1)
      .def_readonly("mu0", &LearnRequest::mu0)
      .def_readonly("sigma0", &LearnRequest::sigma0)
      .def_readonly("lam", &LearnRequest::lam)
      .def_readonly("first_pos", &LearnRequest::first_pos)
      .def_readonly("first_neg", &LearnRequest::first_neg)
      .def_readonly("direct_first", &LearnRequest::direct_first)
      .def_readonly("mil", &LearnRequest::mil)
      .def_readonly("sigma_floor", &LearnRequest::sigma_floor)
      .def_readonly("guard", &LearnRequest::guard)
      .def_readonly("select", &LearnRequest::select)
      .def_readonly("w_pos", &LearnRequest::w_pos)
      .def_readonly("k", &LearnRequest::k)
      .def_readonly("code_gradient", &LearnRequest::code_gradient)
      .def_readonly("extra_neg", &LearnRequest::extra_neg)
      .def_readonly("second", &LearnRequest::second);
}

void bind_learn(py::module_& m) {
  py::class_<LearnRequest> cls(
      m, "LearnRequest",
      "A learning step's inputs, by name: the integral image `ii` and FeatureBank `bank`;\n"
      "the boxes' top-left corners (xs[i], ys[i]): n_pos positives, then negatives; the\n"
      "model in (mu1, sigma1, mu0, sigma0); the update rule (lam, first_pos, first_neg,\n"
      "direct_first, mil, sigma_floor) and the log guard; select = 'none', 'wmil' (with the\n"
      "positives' weights w_pos, k features, code_gradient) or 'ratios' (the log ratios\n"
      "returned); extra_neg (M x e feature values) adds e negatives after the boxes; second =\n"
      "(mu, sigma, lam, first) is a second target model updated from the positives alone with\n"
      "its own lambda. Checked when it runs.");
  bind_learn_request(cls);
  m.def(
      "learn",
      [](const py::object& request) {
        LearnJob job = make_learn(request.cast<const LearnRequest&>(), request);
        {
          py::gil_scoped_release release;
          job.run();
        }
        return learn_result(job);
      },
      py::arg("request"),
      "The learning half of a frame step in one call (a LearnRequest; the same bits as\n"
      "project, the Gaussian update of each class, log_ratio and wmil_select called one by\n"
      "one). Returns (mu1, sigma1, mu0, sigma0, selected, h, mu2, sigma2): the updated model\n"
      "(new arrays; a class without samples keeps its model), the WMIL selection\n"
      "(select='wmil'; else None), the log ratios of both bags, M x (len(xs) + e)\n"
      "(select='ratios'; else None), and the second model updated (None without one).");
}

}  // namespace wmiltrack::bindings
