// The requests a tracker makes of the core in a frame (search, learning, bag draws), checked and
// copied into jobs that run without the GIL. Shared by the binding files of each job and of the
// batch calls (bind_search.cpp, bind_learn.cpp, bind_draws.cpp, bind_batch.cpp).
#pragma once

#include <pybind11/stl.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "common.hpp"
#include "wmiltrack/learn_step.hpp"
#include "wmiltrack/sampling.hpp"
#include "wmiltrack/scoring.hpp"

namespace wmiltrack::bindings {

using Box = std::tuple<int, int, int, int>;

// ---- requests: what Python hands over, by name (bound as _core.SearchRequest, ...) ---------

// A coarse-to-fine search (see _core.search).
struct SearchRequest {
  py::object ii, bank, selected;
  CArray<double> mu1, sigma1, mu0, sigma0;
  double guard = 0.0;
  Box box;
  std::vector<std::tuple<int, int>> stages;
  std::tuple<int, int> frame_size;
  py::object frame = py::none();
  std::optional<Box> roi;
  py::object cues = py::none();
};

// A learning step (see _core.learn).
struct LearnRequest {
  py::object ii, bank, xs, ys;
  int n_pos = 0;
  CArray<double> mu1, sigma1, mu0, sigma0;
  double lam = 0.0;
  bool first_pos = false, first_neg = false, direct_first = true, mil = false;
  double sigma_floor = 0.0, guard = 0.0;
  std::string select = "none";
  py::object w_pos = py::none();
  int k = 0;
  bool code_gradient = false;
  py::object extra_neg = py::none(), second = py::none();
};

struct BagJob;  // (below)

// A BagSampler's draw (see _core.frame_step). Its arrays are checked and copied on its first
// run (`checked`), and read from that copy on every later one: a tracker makes its request once.
struct BagRequest {
  py::object rng, pos_offsets, pos_terms;
  std::string weights = "none";
  py::object neg_offsets;
  bool exact = false;
  int neg_count = 0;
  double keep_prob = 0.0;
  mutable std::shared_ptr<const BagJob> checked;
};

// ---- jobs: requests checked and copied, run without the GIL --------------------------------

struct SearchJob {
  SharedIntegralImage* ii = nullptr;
  py::object keep;                 // the request (frame, tables, arrays) stays alive meanwhile
  std::optional<ImageView> frame;  // compute the integral image over roi first
  Rect roi;
  const FeatureBank* bank = nullptr;
  Int32Array selected;
  std::unique_ptr<WeakGaussians> weak;
  Rect box;
  std::vector<SearchStage> stages;
  int fw = 0, fh = 0;
  std::vector<CArray<double>> cue_tables;  // the cues' integral images (with `merge`)
  std::optional<CueMerge> merge;
  std::vector<GridResult> out;

  void run();
};

SearchJob make_search(const SearchRequest& request, py::object keep);
py::tuple search_result(const SearchJob& job);

struct LearnJob {
  std::shared_ptr<const IntegralImage> table;
  const FeatureBank* bank = nullptr;
  py::object keep;  // the request stays alive meanwhile
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
  void take_bags(Bags&& bags, const SharedIntegralImage& ii);
  void run();
};

// With bags_later, the request's boxes (xs, ys, n_pos, w_pos) are ignored: take_bags gives them.
LearnJob make_learn(const LearnRequest& request, py::object keep, bool bags_later = false);
py::tuple learn_result(LearnJob& job);

// A numpy.random.Generator's bit generator, held (with its lock) for the draws of one call.
class NumpyBits {
 public:
  explicit NumpyBits(const py::object& rng);
  NumpyBits(const NumpyBits&) = delete;
  NumpyBits& operator=(const NumpyBits&) = delete;
  ~NumpyBits();
  BitSource& bits() { return bits_; }

 private:
  BitSource bits_{};
  py::object lock_;
};

// BagSampler's offsets and draw settings, checked and copied (spec points into the copies).
struct BagJob {
  py::object rng;
  std::vector<std::int32_t> pos, neg;
  std::vector<double> terms;
  BagSpec spec;
};

// The request's job, made on its first call (under the GIL) and shared from then on.
std::shared_ptr<const BagJob> make_bags(const BagRequest& request);

}  // namespace wmiltrack::bindings
