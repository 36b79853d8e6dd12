// Several requests in one call: the searches, learning steps or whole frame steps of many
// targets on the core's threads with the GIL released once (MultiTracker, update_many).
#include <optional>
#include <string>
#include <tuple>
#include <utility>

#include "jobs.hpp"
#include "wmiltrack/worker_pool.hpp"

namespace wmiltrack::bindings {

namespace {

void require_threads(int threads) {
  require(threads >= 1, [&] { return "threads must be >= 1, got " + std::to_string(threads); });
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

// One frame step's requests: (search, learn, bags).
using FrameStep = std::tuple<py::object, py::object, py::object>;
// A learning step on bags drawn around a given box: (learn, bags, box, frame_size).
using LearnAt = std::tuple<py::object, py::object, Box, std::tuple<int, int>>;

// One target's bag draws and learning, after its search when it has one (a frame step), else
// around a box it was given (a learning step at a box).
struct BagsThenLearn {
  std::optional<SearchJob> search;
  const SharedIntegralImage* ii = nullptr;  // the table the learning reads (the search's)
  Rect box;                                 // where the bags are drawn (moved by the search)
  int fw = 0, fh = 0;
  std::shared_ptr<const BagJob> bags;
  LearnJob learn;

  void run(BitSource& bits) {
    if (search) {
      search->run();
      for (const GridResult& r : search->out) {
        if (r.candidates > 0) {
          box.x += r.dx;
          box.y += r.dy;
        }
      }
    }
    Bags drawn = sample_bags(bags->spec, box, fw, fh, bits);
    learn.take_bags(std::move(drawn), *ii);
    learn.run();
  }
};

// Every target's steps in turn, the targets on up to `threads` threads with the GIL released
// once (the learning jobs are built before, and take their boxes from the draws in C++). Every
// job owns its integral image or reads a computed one; every job draws from its own generator
// (their locks are held meanwhile). Each result is ([search's result,] learn's result, (xs, ys,
// n_pos) of the bags).
py::list run_bags_then_learn(std::vector<BagsThenLearn>& jobs, int threads) {
  const std::size_t n = jobs.size();
  // (Two Generators may wrap one bit generator: it is its lock that each job takes.)
  std::vector<py::object> bit_generators;
  bit_generators.reserve(n);
  for (const auto& job : jobs) {
    bit_generators.push_back(py::getattr(job.bags->rng, "bit_generator", job.bags->rng));
  }
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const bool computes = (jobs[i].search && jobs[i].search->frame) ||
                            (jobs[j].search && jobs[j].search->frame);
      require(jobs[i].ii != jobs[j].ii || !computes,
              [&] { return "steps " + std::to_string(j) + " and " + std::to_string(i) +
                  " share an IntegralImage that one of them computes"; });
      require(!bit_generators[i].is(bit_generators[j]),
              [&] { return "steps " + std::to_string(j) + " and " + std::to_string(i) +
                  " draw from the same generator"; });
    }
  }
  std::vector<std::unique_ptr<NumpyBits>> rngs;
  rngs.reserve(n);
  for (const auto& job : jobs) rngs.push_back(std::make_unique<NumpyBits>(job.bags->rng));
  {
    py::gil_scoped_release release;
    parallel_for(static_cast<int>(n), threads, [&](int k) {
      const std::size_t i = static_cast<std::size_t>(k);
      jobs[i].run(rngs[i]->bits());
    });
  }
  rngs.clear();  // the generators' locks released (with the GIL)
  py::list out;
  for (BagsThenLearn& job : jobs) {
    const LearnJob& learn = job.learn;
    py::array_t<std::int32_t> xs(learn.xs.size(), learn.xs.data());
    py::array_t<std::int32_t> ys(learn.ys.size(), learn.ys.data());
    const py::tuple bags = py::make_tuple(xs, ys, learn.step.n_pos);
    if (job.search) {
      out.append(py::make_tuple(search_result(*job.search), learn_result(job.learn), bags));
    } else {
      out.append(py::make_tuple(learn_result(job.learn), bags));
    }
  }
  return out;
}

// Each object of `requests` must be a T (a TypeError names the position otherwise).
template <class T>
void require_all(const std::vector<py::object>& requests, const char* kind) {
  for (std::size_t i = 0; i < requests.size(); ++i) {
    if (!py::isinstance<T>(requests[i])) {
      throw py::type_error("request " + std::to_string(i) + " is not a " + kind);
    }
  }
}

py::list run_frame_steps(const std::vector<FrameStep>& steps, int threads) {
  require_threads(threads);
  std::vector<BagsThenLearn> jobs(steps.size());
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const auto& [search, learn, bags] = steps[i];
    require_all<SearchRequest>({search}, "SearchRequest");
    require_all<LearnRequest>({learn}, "LearnRequest");
    require_all<BagRequest>({bags}, "BagRequest");
    const auto& search_request = search.cast<const SearchRequest&>();
    const auto& learn_request = learn.cast<const LearnRequest&>();
    require(learn_request.ii.is(search_request.ii),
            "frame_step: the learning step must read the search's IntegralImage");
    BagsThenLearn& job = jobs[i];
    job.search = make_search(search_request, search);
    job.ii = job.search->ii;
    job.box = job.search->box;
    job.fw = job.search->fw;
    job.fh = job.search->fh;
    job.bags = make_bags(bags.cast<const BagRequest&>());
    job.learn = make_learn(learn_request, learn, true);
  }
  return run_bags_then_learn(jobs, threads);
}

py::list run_learn_at(const std::vector<LearnAt>& steps, int threads) {
  require_threads(threads);
  std::vector<BagsThenLearn> jobs(steps.size());
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const auto& [learn, bags, box, frame_size] = steps[i];
    require_all<LearnRequest>({learn}, "LearnRequest");
    require_all<BagRequest>({bags}, "BagRequest");
    const auto& learn_request = learn.cast<const LearnRequest&>();
    require(!learn_request.ii.is_none(), "a learning step needs an IntegralImage");
    BagsThenLearn& job = jobs[i];
    job.ii = learn_request.ii.cast<const SharedIntegralImage*>();
    const auto [x, y, w, h] = box;
    require(w > 0 && h > 0, "box must have positive size");
    job.box = Rect{x, y, w, h};
    std::tie(job.fw, job.fh) = frame_size;
    job.bags = make_bags(bags.cast<const BagRequest&>());
    job.learn = make_learn(learn_request, learn, true);
  }
  return run_bags_then_learn(jobs, threads);
}

}  // namespace

static void bind_batched_search_and_learn(py::module_& m) {
  m.def(
      "search_many",
      [](const std::vector<py::object>& requests, int threads) {
        require_threads(threads);
        require_all<SearchRequest>(requests, "SearchRequest");
        std::vector<SearchJob> jobs;
        jobs.reserve(requests.size());
        for (const py::object& r : requests) jobs.push_back(make_search(r.cast<const SearchRequest&>(), r));
        for (std::size_t i = 0; i < jobs.size(); ++i) {
          for (std::size_t j = 0; j < jobs.size(); ++j) {
            require(i == j || !jobs[i].frame || jobs[i].ii != jobs[j].ii,
                    [&] { return "job " + std::to_string(i) + " computes an IntegralImage that job " +
                        std::to_string(j) + " also uses"; });
          }
        }
        return run_all(jobs, threads, search_result);
      },
      py::arg("requests"), py::arg("threads"),
      "search() for several SearchRequests in one call, on up to `threads` threads with the\n"
      "GIL released once. A request that computes its integral image (frame not None) needs one\n"
      "no other request uses (ValueError). Returns the results in order; the first error is\n"
      "raised after all ran.");

  m.def(
      "learn_many",
      [](const std::vector<py::object>& requests, int threads) {
        require_threads(threads);
        require_all<LearnRequest>(requests, "LearnRequest");
        std::vector<LearnJob> jobs;
        jobs.reserve(requests.size());
        for (const py::object& r : requests) jobs.push_back(make_learn(r.cast<const LearnRequest&>(), r));
        return run_all(jobs, threads, learn_result);
      },
      py::arg("requests"), py::arg("threads"),
      "learn() for several LearnRequests in one call, on up to `threads` threads with the GIL\n"
      "released once. Returns the results in order; the first error is raised after all ran.");

}

static void bind_frame_steps(py::module_& m) {
  m.def(
      "frame_step",
      [](const py::object& search, const py::object& learn, const py::object& bags) {
        return py::tuple(run_frame_steps({FrameStep{search, learn, bags}}, 1)[0]);
      },
      py::arg("search"), py::arg("learn"), py::arg("bags"),
      "A tracker's whole frame step in one call: the SearchRequest `search`; then the bags\n"
      "around the box where it landed, sampled as BagSampler does from the BagRequest `bags`\n"
      "(the negatives drawn from its numpy Generator, continuing its stream as numpy's choice /\n"
      "random would); then the LearnRequest `learn` on the integral image the search read (the\n"
      "same object: computed by the search when it is given a frame and roi, else already\n"
      "computed), its xs, ys, n_pos and w_pos replaced by the bags (and select='none' when no\n"
      "positive fits in the frame). Returns (search's result, learn's result, (xs, ys, n_pos) of\n"
      "the bags).");

  m.def(
      "frame_step_many",
      [](const std::vector<FrameStep>& steps, int threads) {
        return run_frame_steps(steps, threads);
      },
      py::arg("steps"), py::arg("threads"),
      "frame_step() for several targets in one call, on up to `threads` threads with the GIL\n"
      "released once: each step is a (SearchRequest, LearnRequest, BagRequest). Steps must not\n"
      "share a generator, nor an IntegralImage that one of them computes (ValueError). Returns\n"
      "the results in order; the first error is raised after all ran.");

  m.def(
      "learn_at",
      [](const py::object& learn, const py::object& bags, const Box& box,
         const std::tuple<int, int>& frame_size) {
        return py::tuple(run_learn_at({LearnAt{learn, bags, box, frame_size}}, 1)[0]);
      },
      py::arg("learn"), py::arg("bags"), py::arg("box"), py::arg("frame_size"),
      "The second half of frame_step() at a box the caller chose (a tracker whose search and\n"
      "scale estimate run in several calls): the bags around `box` (x, y, w, h) in a frame of\n"
      "`frame_size` (w, h), sampled as BagSampler does from the BagRequest `bags`, then the\n"
      "LearnRequest `learn` on them (its xs, ys, n_pos and w_pos replaced by the bags, and\n"
      "select='none' when no positive fits in the frame; its extra negatives kept). Returns\n"
      "(learn's result, (xs, ys, n_pos) of the bags).");

}

static void bind_batched_learn_at(py::module_& m) {
  m.def(
      "learn_at_many",
      [](const std::vector<LearnAt>& steps, int threads) { return run_learn_at(steps, threads); },
      py::arg("steps"), py::arg("threads"),
      "learn_at() for several targets in one call, on up to `threads` threads with the GIL\n"
      "released once: each step is a (LearnRequest, BagRequest, box, frame_size). Steps must not\n"
      "share a generator (ValueError). Returns the results in order; the first error is raised\n"
      "after all ran.");
}

void bind_batch(py::module_& m) {
  bind_batched_search_and_learn(m);
  bind_frame_steps(m);
  bind_batched_learn_at(m);
}

}  // namespace wmiltrack::bindings
