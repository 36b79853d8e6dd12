// _core.BagRequest and the core's copies of numpy's draws (the negatives a frame step draws in
// C++ from the tracker's own numpy Generator, as numpy would).
#include <string>

#include "jobs.hpp"

namespace wmiltrack::bindings {

namespace {

// numpy's pcg64_state (numpy/random/src/pcg64/pcg64.h): its 128-bit LCG state and increment
// (low word first where numpy uses the compiler's 128-bit integers), then a buffered 32-bit half.
struct NumpyPcg64State {
  std::uint64_t* pcg_state;
  int has_uint32;
  std::uint32_t uinteger;
};

const Bitgen* bitgen_of(const py::object& bit_generator) {
  const py::object cap = py::getattr(bit_generator, "capsule", py::none());
  const char* name = py::isinstance<py::capsule>(cap) ? cap.cast<py::capsule>().name() : nullptr;
  if (name == nullptr || std::string(name) != "BitGenerator") return nullptr;
  return cap.cast<py::capsule>().get_pointer<Bitgen>();
}

// numpy's PCG64 next_double, if a PCG64 of our own shows the layout above: its state words
// equal to what bit_generator.state reports, and 8 doubles stepped here equal to its own (and
// its state after them); null otherwise, and generators then draw through next_double. Checked
// once: every PCG64 shares that function.
void* checked_pcg64_next_double() {
  static void* const fn = []() -> void* {
#if defined(__SIZEOF_INT128__)
    try {
      const py::object gen = py::module_::import("numpy.random").attr("PCG64")(20261126);
      const Bitgen* bg = bitgen_of(gen);
      if (bg == nullptr) return nullptr;
      const std::uint64_t* w = static_cast<const NumpyPcg64State*>(bg->state)->pcg_state;
      const py::dict state = gen.attr("state");
      const auto as_int = [](const std::uint64_t* v) -> py::object {
        return py::int_(v[1]).attr("__lshift__")(64).attr("__or__")(py::int_(v[0]));
      };
      const py::object name = state["bit_generator"];
      const py::dict words = state["state"];
      if (!name.equal(py::str("PCG64")) || !py::object(words["state"]).equal(as_int(w)) ||
          !py::object(words["inc"]).equal(as_int(w + 2))) {
        return nullptr;
      }
      std::uint64_t ours[4] = {w[0], w[1], w[2], w[3]};
      for (int k = 0; k < 8; ++k) {
        if (pcg64_next_double(ours) != bg->next_double(bg->state)) return nullptr;
      }
      for (int k = 0; k < 4; ++k) {
        if (ours[k] != w[k]) return nullptr;
      }
      return reinterpret_cast<void*>(bg->next_double);
    } catch (const py::error_already_set&) {
      return nullptr;
    }
#else
    return nullptr;
#endif
  }();
  return fn;
}

}  // namespace

NumpyBits::NumpyBits(const py::object& rng) {
  const py::object bitgen = py::getattr(rng, "bit_generator", py::none());
  const Bitgen* bg = bitgen.is_none() ? nullptr : bitgen_of(bitgen);
  if (bg == nullptr) throw py::type_error("rng must be a numpy.random.Generator");
  static_cast<Bitgen&>(bits_) = *bg;
  void* const pcg64 = checked_pcg64_next_double();
  if (pcg64 != nullptr && reinterpret_cast<void*>(bg->next_double) == pcg64) {
    bits_.pcg64_state = static_cast<NumpyPcg64State*>(bg->state)->pcg_state;
  }
  lock_ = bitgen.attr("lock");
  lock_.attr("acquire")();
}

NumpyBits::~NumpyBits() { lock_.attr("release")(); }

std::shared_ptr<const BagJob> make_bags(const BagRequest& r) {
  if (r.checked) return r.checked;
  auto made = std::make_shared<BagJob>();
  BagJob& job = *made;
  job.rng = r.rng;
  const auto offsets = [](const py::handle& obj, const char* name) {
    const Int32Array a = int32_array(obj, name);
    require(a.ndim() == 2 && a.shape[1] == 2, [&] { return std::string(name) + " must be an (n, 2) array"; });
    return a.values;
  };
  job.pos = offsets(r.pos_offsets, "pos_offsets");
  job.neg = offsets(r.neg_offsets, "neg_offsets");
  const std::string& mode = r.weights;
  BagSpec& spec = job.spec;
  spec.weights = mode == "exp"       ? InstanceWeights::kExp
                 : mode == "exp_sq"  ? InstanceWeights::kExpSq
                 : mode == "uniform" ? InstanceWeights::kUniform
                                     : InstanceWeights::kNone;
  require(spec.weights != InstanceWeights::kNone || mode == "none",
          [&] { return "weights must be 'exp', 'exp_sq', 'uniform' or 'none', got '" + mode + "'"; });
  spec.n_pos_offsets = static_cast<int>(job.pos.size() / 2);
  spec.n_neg_offsets = static_cast<int>(job.neg.size() / 2);
  if (spec.weights == InstanceWeights::kExp || spec.weights == InstanceWeights::kExpSq) {
    const auto terms = r.pos_terms.cast<CArray<double>>();
    require(terms.ndim() == 1 && terms.shape(0) == spec.n_pos_offsets,
            "pos_terms must hold one term per positive offset");
    job.terms.assign(terms.data(), terms.data() + terms.size());
  }
  spec.exact = r.exact;
  spec.neg_count = r.neg_count;
  spec.keep_prob = r.keep_prob;
  require(spec.neg_count >= 0, "neg_count must be >= 0");
  spec.pos = job.pos.data();
  spec.neg = job.neg.data();
  if (spec.n_neg_offsets > 0) spec.neg_extent = offsets_extent(spec.neg, spec.n_neg_offsets);
  spec.pos_terms = job.terms.empty() ? nullptr : job.terms.data();
  r.checked = std::move(made);
  return r.checked;
}

void bind_draws(py::module_& m) {
  py::class_<BagRequest>(
      m, "BagRequest",
      "A BagSampler's draw, by name: the numpy Generator `rng` the negatives are drawn from;\n"
      "pos_offsets (n, 2) and their weight terms pos_terms for weights = 'exp', 'exp_sq',\n"
      "'uniform' or 'none'; neg_offsets (n, 2); exact (neg_count distinct offsets, as numpy's\n"
      "choice) or a Bernoulli thinning with keep_prob truncated to neg_count. Checked, and its\n"
      "arrays copied, when it first runs: later changes to those arrays are not seen.")
      .def(py::init([](py::object rng, py::object pos_offsets, py::object pos_terms,
                       std::string weights, py::object neg_offsets, bool exact, int neg_count,
                       double keep_prob) {
             return BagRequest{std::move(rng), std::move(pos_offsets), std::move(pos_terms),
                               std::move(weights), std::move(neg_offsets), exact, neg_count,
                               keep_prob};
           }),
           py::arg("rng"), py::arg("pos_offsets"), py::arg("pos_terms"), py::arg("weights"),
           py::arg("neg_offsets"), py::arg("exact"), py::arg("neg_count"), py::arg("keep_prob"))
      .def_readonly("rng", &BagRequest::rng)
      .def_readonly("pos_offsets", &BagRequest::pos_offsets)
      .def_readonly("pos_terms", &BagRequest::pos_terms)
      .def_readonly("weights", &BagRequest::weights)
      .def_readonly("neg_offsets", &BagRequest::neg_offsets)
      .def_readonly("exact", &BagRequest::exact)
      .def_readonly("neg_count", &BagRequest::neg_count)
      .def_readonly("keep_prob", &BagRequest::keep_prob);

  m.def(
      "numpy_pcg64_stepped_here",
      [](const py::object& rng) {
        NumpyBits bits(rng);
        return bits.bits().pcg64_state != nullptr;
      },
      py::arg("rng"),
      "Whether the core's Bernoulli draws from this numpy Generator step its PCG64 state in C++\n"
      "(numpy's PCG64, its state layout checked once) rather than calling numpy's next_double\n"
      "for each number; the numbers are the same either way.");

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
}

}  // namespace wmiltrack::bindings
