#include <string>

#include "common.hpp"
#include "wmiltrack/frame.hpp"

namespace wmiltrack::bindings {

void bind_frame(py::module_& m) {
  m.def(
      "learn",
      [](const SharedIntegralImage& shared, const FeatureBank& bank, const py::object& xs_obj,
         const py::object& ys_obj, int n_pos, const CArray<double>& mu1,
         const CArray<double>& sigma1, const CArray<double>& mu0, const CArray<double>& sigma0,
         double lam, bool first_pos, bool first_neg, bool direct_first, bool mil,
         double sigma_floor, double guard, const std::string& select,
         const py::object& w_pos_obj, int k, bool code_gradient) -> py::tuple {
        const Int32Array xs = int32_array(xs_obj, "xs"), ys = int32_array(ys_obj, "ys");
        require(xs.ndim() == 1 && ys.ndim() == 1 && xs.size() == ys.size(),
                "xs and ys must be 1-D of one length");
        const int B = static_cast<int>(xs.size());
        require(n_pos >= 0 && n_pos <= B, "n_pos must be in 0..len(xs)");
        const py::ssize_t M = bank.size();
        for (const auto* a : {&mu1, &sigma1, &mu0, &sigma0}) {
          require(a->ndim() == 1 && a->shape(0) == M,
                  "mu1, sigma1, mu0, sigma0 must hold one entry per feature of the bank");
        }
        LearnStep step;
        step.xs = xs.data();
        step.ys = ys.data();
        step.n_pos = n_pos;
        step.n_neg = B - n_pos;
        step.rule.lam = lam;
        step.rule.direct_first = direct_first;
        step.rule.mil = mil;
        step.rule.sigma_floor = sigma_floor;
        step.first_pos = first_pos;
        step.first_neg = first_neg;
        step.guard = guard;
        CArray<double> w_pos;
        if (select == "none") {
          step.select = LearnSelect::kNone;
        } else if (select == "wmil") {
          step.select = LearnSelect::kWmil;
          w_pos = CArray<double>::ensure(w_pos_obj);
          require(w_pos && w_pos.ndim() == 1 && w_pos.shape(0) == n_pos && n_pos > 0,
                  "w_pos must hold one weight per positive");
          require(k >= 1 && k <= M, "k must be in 1.." + std::to_string(M));
          step.w_pos = w_pos.data();
          step.k = k;
          step.code_gradient = code_gradient;
        } else if (select == "ratios") {
          step.select = LearnSelect::kRatios;
        } else {
          throw py::value_error("select must be 'none', 'wmil' or 'ratios', got '" + select + "'");
        }
        const auto ii = computed_table(shared);
        require_planes(*ii, bank);
        // The model out: copies of the model in, updated in place by the core.
        CArray<double> out[4] = {CArray<double>(M), CArray<double>(M), CArray<double>(M),
                                 CArray<double>(M)};
        const CArray<double>* in[4] = {&mu1, &sigma1, &mu0, &sigma0};
        for (int a = 0; a < 4; ++a) {
          std::copy(in[a]->data(), in[a]->data() + M, out[a].mutable_data());
        }
        py::object selected = py::none(), h = py::none();
        std::int32_t* sel_ptr = nullptr;
        double* h_ptr = nullptr;
        if (step.select == LearnSelect::kWmil) {
          py::array_t<std::int32_t> s(k);
          sel_ptr = s.mutable_data();
          selected = s;
        } else if (step.select == LearnSelect::kRatios) {
          CArray<double> hh({M, static_cast<py::ssize_t>(B)});
          h_ptr = hh.mutable_data();
          h = hh;
        }
        double* o[4] = {out[0].mutable_data(), out[1].mutable_data(), out[2].mutable_data(),
                        out[3].mutable_data()};
        {
          py::gil_scoped_release release;
          learn_step(*ii, bank, step, o[0], o[1], o[2], o[3], sel_ptr, h_ptr);
        }
        return py::make_tuple(out[0], out[1], out[2], out[3], selected, h);
      },
      py::arg("ii"), py::arg("bank"), py::arg("xs"), py::arg("ys"), py::arg("n_pos"),
      py::arg("mu1"), py::arg("sigma1"), py::arg("mu0"), py::arg("sigma0"), py::kw_only(),
      py::arg("lam"), py::arg("first_pos"), py::arg("first_neg"), py::arg("direct_first"),
      py::arg("mil"), py::arg("sigma_floor"), py::arg("guard"), py::arg("select"),
      py::arg("w_pos") = py::none(), py::arg("k") = 0, py::arg("code_gradient") = false,
      "The learning half of a frame step in one call (the same bits as project, the Gaussian\n"
      "update of each class, log_ratio and wmil_select called one by one).\n\n"
      "Boxes (xs[i], ys[i]): n_pos positives, then negatives. Returns (mu1, sigma1, mu0,\n"
      "sigma0, selected, h): the updated model (new arrays; a class without samples keeps\n"
      "its model), the WMIL selection (select='wmil'; else None) and the log ratios of both\n"
      "bags, M x len(xs) (select='ratios'; else None).");
}

}  // namespace wmiltrack::bindings
