// Microbenchmarks of wmiltrack's C++ core: integral image, Haar feature projection,
// candidate scoring, the correlation filters' patch resampling and fHOG, and a whole frame step of the tracker (the same kernels in the same
// order as Tracker.update, no Python: the floor the Python path is measured against). Plain
// std::chrono; each case is run `reps` times after one warm-up call and reports the minimum
// and median wall time of one call and a throughput from the minimum.
//
//   bench_core [--quick] [--reps N] [--frame-only] [--fhog-only] [--preset rcwmil|mil]
//
// The feature bank mimics the tracker's: every feature sums 2..4 random rectangles inside
// the target box with weights +-1/sqrt(n) (compressive-tracking style).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "wmiltrack/fhog.hpp"
#include "wmiltrack/haar.hpp"
#include "wmiltrack/integral.hpp"
#include "wmiltrack/learning.hpp"
#include "wmiltrack/scoring.hpp"

using namespace wmiltrack;
using Clock = std::chrono::steady_clock;

namespace {

volatile double g_sink = 0.0;  // keeps results alive so the work is not optimised away

struct Timing {
  double min_s;
  double median_s;
};

template <class F>
Timing time_it(int reps, F&& f) {
  f();  // warm-up: first-touch of buffers, caches
  std::vector<double> t(static_cast<std::size_t>(reps));
  for (int i = 0; i < reps; ++i) {
    const auto t0 = Clock::now();
    f();
    const auto t1 = Clock::now();
    t[static_cast<std::size_t>(i)] = std::chrono::duration<double>(t1 - t0).count();
  }
  std::sort(t.begin(), t.end());
  const std::size_t n = t.size();
  const double med = n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
  return {t.front(), med};
}

// Repetitions so that one case takes roughly `budget` seconds (at least 5, at most `cap`).
template <class F>
int calibrate(F&& f, double budget, int cap) {
  const auto t0 = Clock::now();
  f();
  const double one = std::chrono::duration<double>(Clock::now() - t0).count();
  const int n = one > 0 ? static_cast<int>(budget / one) : cap;
  return std::max(5, std::min(cap, n));
}

std::string si(double v) {
  const char* units[] = {"", "k", "M", "G", "T"};
  int u = 0;
  while (std::fabs(v) >= 1000.0 && u < 4) {
    v /= 1000.0;
    ++u;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f %s", v, units[u]);
  return buf;
}

void row(const char* bench, const std::string& cfg, int reps, Timing t, double work,
         const char* unit) {
  std::printf("| %-10s | %-32s | %6d | %10.2f | %10.2f | %12s%s/s |\n", bench, cfg.c_str(), reps,
              t.min_s * 1e6, t.median_s * 1e6, si(work / t.min_s).c_str(), unit);
}

struct Image {
  int rows, cols;
  std::vector<std::uint8_t> bgr;
  ImageView view() const {
    ImageView v;
    v.data = bgr.data();
    v.rows = rows;
    v.cols = cols;
    v.channels = 3;
    v.channel_stride = 1;
    v.col_stride = 3;
    v.row_stride = static_cast<std::ptrdiff_t>(cols) * 3;
    return v;
  }
};

Image random_image(int rows, int cols, std::mt19937& rng) {
  Image im{rows, cols, std::vector<std::uint8_t>(static_cast<std::size_t>(rows) * cols * 3)};
  std::uniform_int_distribution<int> d(0, 255);
  for (auto& p : im.bgr) p = static_cast<std::uint8_t>(d(rng));
  return im;
}

// A frame with the structure of a photograph (smooth shading, hard edges, a little noise):
// fHOG's cost depends on the content (how often neighbouring pixels vote into the same bin).
Image textured_image(int rows, int cols, std::mt19937& rng) {
  Image im{rows, cols, std::vector<std::uint8_t>(static_cast<std::size_t>(rows) * cols * 3)};
  std::normal_distribution<double> noise(0.0, 3.0);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const double shade = 60.0 * std::sin(c / 13.0) * std::cos(r / 17.0);
      const double block = ((c / 40 + r / 40) % 2) ? 40.0 : -40.0;
      for (int k = 0; k < 3; ++k) {
        const double v = 128.0 + shade + block * (k == 1 ? 1.0 : 0.5) + noise(rng);
        im.bgr[(static_cast<std::size_t>(r) * cols + c) * 3 + k] =
            static_cast<std::uint8_t>(std::clamp(v, 0.0, 255.0));
      }
    }
  }
  return im;
}

// The correlation filter's features of one region (_core.fhog_region): cf::sample_gray of
// the region around the frame's centre resampled to the template size, then cf::fhog with
// cell 4; and each of the two alone. Throughput: template pixels per second.
void bench_fhog(int reps_cap, double budget, std::mt19937& rng) {
  struct Frame {
    const char* name;
    Image img;
  };
  const Frame frames[] = {{"textured", textured_image(480, 640, rng)},
                          {"noise", random_image(480, 640, rng)}};
  struct Cfg {
    double region;
    int out;
  };
  const Cfg cfgs[] = {{192.0, 160}, {160.0, 160}, {100.0, 100}, {400.0, 160}};
  for (const Frame& fr : frames) {
    const ImageView view = fr.img.view();
    for (const Cfg& c : cfgs) {
      const double cx = 320.5, cy = 240.3;
      const std::string cfg = std::string(fr.name) + " " + std::to_string(int(c.region)) + "->" +
                              std::to_string(c.out) + " cell 4";
      const double px = static_cast<double>(c.out) * c.out;
      {
        auto f = [&] {
          const cf::FeatureMap x = cf::fhog(cf::sample_gray(view, cx, cy, c.region, c.region, c.out, c.out), 4);
          g_sink = g_sink + x.data[0];
        };
        const int reps = calibrate(f, budget, reps_cap);
        row("fhog_regn", cfg, reps, time_it(reps, f), px, "px");
      }
      {
        auto f = [&] {
          const cf::GrayPatch p = cf::sample_gray(view, cx, cy, c.region, c.region, c.out, c.out);
          g_sink = g_sink + p.pixels[0];
        };
        const int reps = calibrate(f, budget, reps_cap);
        row("sample", cfg, reps, time_it(reps, f), px, "px");
      }
      {
        const cf::GrayPatch p = cf::sample_gray(view, cx, cy, c.region, c.region, c.out, c.out);
        auto f = [&] {
          const cf::FeatureMap x = cf::fhog(p, 4);
          g_sink = g_sink + x.data[0];
        };
        const int reps = calibrate(f, budget, reps_cap);
        row("fhog", cfg, reps, time_it(reps, f), px, "px");
      }
    }
  }
}

FeatureBank random_bank(int m, int w, int h, std::mt19937& rng) {
  std::vector<std::int32_t> starts{0};
  std::vector<Rect> rects;
  std::vector<double> weights;
  std::uniform_int_distribution<int> nrect(2, 4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int f = 0; f < m; ++f) {
    const int n = nrect(rng);
    for (int r = 0; r < n; ++r) {
      Rect q;
      q.x = static_cast<int>(u(rng) * (w - 3));
      q.y = static_cast<int>(u(rng) * (h - 3));
      q.w = 1 + static_cast<int>(u(rng) * (w - q.x - 2));
      q.h = 1 + static_cast<int>(u(rng) * (h - q.y - 2));
      rects.push_back(q);
      weights.push_back((u(rng) < 0.5 ? -1.0 : 1.0) / std::sqrt(static_cast<double>(n)));
    }
    starts.push_back(static_cast<std::int32_t>(rects.size()));
  }
  return FeatureBank(std::move(starts), std::move(rects), std::move(weights));
}

void bench_integral(int reps_cap, double budget, std::mt19937& rng) {
  const Image img = random_image(720, 1280, rng);
  const int sizes[][2] = {{64, 64}, {128, 128}, {256, 256}, {320, 240}, {640, 480}, {1280, 720}};
  IntegralImage ii;
  for (const auto& s : sizes) {
    Rect roi{(1280 - s[0]) / 2, (720 - s[1]) / 2, s[0], s[1]};
    auto f = [&] {
      ii.compute(img.view(), roi);
      g_sink = g_sink + ii.data()[ii.stride() * ii.height() + ii.width()];
    };
    const int reps = calibrate(f, budget, reps_cap);
    const Timing t = time_it(reps, f);
    row("integral", "ROI " + std::to_string(s[0]) + "x" + std::to_string(s[1]) + " BGR", reps, t,
        static_cast<double>(s[0]) * s[1], "px");
  }
}

// compute_channels: the same ROI with 1, 4 and 8 planes (and compute() for comparison).
// Throughput counts pixel-channels (ROI pixels x planes) per second.
void bench_channels(int reps_cap, double budget, std::mt19937& rng) {
  const Image img = random_image(720, 1280, rng);
  const int sizes[][2] = {{160, 190}, {320, 240}, {640, 480}};
  struct Set {
    const char* name;
    std::vector<int> channels;
  };
  const Set sets[] = {
      {"luma", {kLuma}},
      {"luma+grad+opp", {kLuma, kGrad, kOppRG, kOppYB}},
      {"grad", {kGrad}},
      {"opp_rg+opp_yb", {kOppRG, kOppYB}},
  };
  IntegralImage ii;
  for (const auto& s : sizes) {
    const Rect roi{(1280 - s[0]) / 2, (720 - s[1]) / 2, s[0], s[1]};
    const std::string size = std::to_string(s[0]) + "x" + std::to_string(s[1]);
    {
      auto f = [&] {
        ii.compute(img.view(), roi);
        g_sink = g_sink + ii.data()[ii.plane_size() - 1];
      };
      const int reps = calibrate(f, budget, reps_cap);
      row("channels", size + " compute() luma", reps, time_it(reps, f),
          static_cast<double>(s[0]) * s[1], "pxch");
    }
    for (const Set& set : sets) {
      auto f = [&] {
        ii.compute_channels(img.view(), roi, set.channels);
        g_sink = g_sink + ii.data()[ii.plane_size() - 1];
      };
      const int reps = calibrate(f, budget, reps_cap);
      row("channels", size + " " + set.name, reps, time_it(reps, f),
          static_cast<double>(s[0]) * s[1] * static_cast<double>(set.channels.size()), "pxch");
    }
  }
}

void bench_project(int reps_cap, double budget, std::mt19937& rng) {
  const int box = 48;
  const Image img = random_image(480, 640, rng);
  IntegralImage ii;
  ii.compute(img.view(), Rect{0, 0, 640, 480});
  const int ms[] = {50, 100, 250};
  const int ns[] = {100, 1000, 2000};
  std::uniform_int_distribution<int> px(0, 640 - box - 1), py(0, 480 - box - 1);
  for (int m : ms) {
    const FeatureBank bank = random_bank(m, box, box, rng);
    for (int n : ns) {
      std::vector<std::int32_t> xs(static_cast<std::size_t>(n)), ys(static_cast<std::size_t>(n));
      for (int i = 0; i < n; ++i) {
        xs[static_cast<std::size_t>(i)] = px(rng);
        ys[static_cast<std::size_t>(i)] = py(rng);
      }
      std::vector<double> out(static_cast<std::size_t>(m) * n);
      auto f = [&] {
        project(ii, bank, nullptr, m, xs.data(), ys.data(), n, out.data());
        g_sink = g_sink + out[0];
      };
      const int reps = calibrate(f, budget, reps_cap);
      const Timing t = time_it(reps, f);
      row("project", std::to_string(m) + " features x " + std::to_string(n) + " boxes", reps, t,
          static_cast<double>(m) * n, "val");
    }
  }
}

void bench_score(int reps_cap, double budget, std::mt19937& rng) {
  const Image img = random_image(480, 640, rng);
  IntegralImage ii;
  ii.compute(img.view(), Rect{0, 0, 640, 480});
  struct Cfg {
    const char* name;
    int radius, step;
  };
  const Cfg cfgs[] = {{"coarse 25/4", 25, 4}, {"fine 10/1", 10, 1}, {"exhaustive 25/1", 25, 1}};
  const int boxes[] = {32, 64, 128};
  const int k = 50;  // selected features (rcwmil scores K of M; 50 is the upper end)
  std::normal_distribution<double> nd(0.0, 1.0);
  for (int bs : boxes) {
    const FeatureBank bank = random_bank(150, bs, bs, rng);
    std::vector<std::int32_t> sel(static_cast<std::size_t>(k));
    for (int i = 0; i < k; ++i) sel[static_cast<std::size_t>(i)] = i;
    std::vector<double> mu1(k), s1(k), mu0(k), s0(k);
    for (int i = 0; i < k; ++i) {
      mu1[i] = 100 * nd(rng);
      mu0[i] = 100 * nd(rng);
      s1[i] = 20 + std::fabs(20 * nd(rng));
      s0[i] = 20 + std::fabs(20 * nd(rng));
    }
    const WeakGaussians weak(mu1.data(), s1.data(), mu0.data(), s0.data(), k, 1e-30);
    const Rect box{320 - bs / 2, 240 - bs / 2, bs, bs};
    for (const Cfg& c : cfgs) {
      GridResult res;
      auto f = [&] {
        res = score_grid(ii, bank, sel.data(), k, weak, box, c.radius, c.step, 640, 480, nullptr);
        g_sink = g_sink + res.score;
      };
      const int reps = calibrate(f, budget, reps_cap);
      const Timing t = time_it(reps, f);
      row("score", std::string(c.name) + ", box " + std::to_string(bs) + ", K=" +
                       std::to_string(k), reps, t,
          static_cast<double>(res.candidates), "cand");
    }
  }
}


// A whole frame step of a tracker preset, kernel by kernel as Tracker.update runs them:
// integral image of the search region, coarse-to-fine search, projection of both bags,
// Gaussian update of each class, log ratios, feature selection. Frames cycle through
// `n_frames` distinct images (as a decoded video does: a new frame is not in cache). The bags
// are the tracker's (positives in a disc, negatives drawn from an annulus); the box does not
// move, which changes nothing in the cost. Prints the median per stage and per frame.
struct Preset {
  const char* name;
  int features, selected;
  int coarse_radius, coarse_step, fine_radius, fine_step;
  double pos_radius, neg_inner, neg_outer;
  int neg_count;
  bool milboost;
  double guard;
  bool select = true;  // false: every feature is scored (CT, FCT), no selection
};

std::vector<std::array<int, 2>> offsets_between(double inner, double outer) {
  std::vector<std::array<int, 2>> out;
  const int n = static_cast<int>(std::ceil(outer));
  for (int dy = -n; dy <= n; ++dy) {
    for (int dx = -n; dx <= n; ++dx) {
      const double d2 = dx * dx + dy * dy;
      if (d2 >= inner * inner && d2 < outer * outer) out.push_back({dx, dy});
    }
  }
  return out;
}

void bench_frame(int reps_cap, bool quick, const char* only, std::mt19937& rng) {
  const Preset presets[] = {
      {"rcwmil", 100, 20, 25, 4, 10, 1, 4.0, 8.0, 22.0, 50, false, 1e-30},
      {"mil", 250, 50, 25, 1, 0, 1, 4.0, 9.0, 37.5, 65, true, 1e-5},
      {"ct", 50, 50, 20, 1, 0, 1, 4.0, 8.0, 30.0, 50, false, 1e-30, false},
      {"fct", 100, 100, 25, 4, 10, 1, 4.0, 8.0, 30.0, 50, false, 1e-30, false},
      {"wmil", 150, 15, 25, 1, 0, 1, 4.0, 8.0, 37.5, 50, false, 1e-30},
      {"osil", 100, 20, 20, 1, 0, 1, 4.0, 8.0, 22.0, 50, false, 1e-30},
  };
  const int fw = 640, fh = 480;
  const int n_frames = quick ? 4 : 20;
  std::vector<Image> frames;
  for (int i = 0; i < n_frames; ++i) frames.push_back(random_image(fh, fw, rng));
  const char* stage_names[] = {"integral", "search", "projection", "gaussian update",
                               "log ratios", "selection"};
  constexpr int kStages = 6;
  for (const Preset& p : presets) {
    if (only != nullptr && std::strcmp(only, p.name) != 0) continue;
    for (int bs : {32, 64, 128}) {
      const FeatureBank bank = random_bank(p.features, bs, bs, rng);
      const int M = p.features, K = p.selected;
      const auto pos_off = offsets_between(0.0, p.pos_radius);
      const auto neg_all = offsets_between(p.neg_inner, p.neg_outer);
      const int P = static_cast<int>(pos_off.size()), N = p.neg_count, B = P + N;
      const Rect box{fw / 2 - bs / 2, fh / 2 - bs / 2, bs, bs};
      const int reach = std::max(p.coarse_radius, p.fine_radius) + (p.fine_radius > 0 ? p.fine_radius : 0);
      const int margin = reach + static_cast<int>(std::ceil(p.neg_outer)) + 1;
      const Rect roi{box.x - margin, box.y - margin, bs + 2 * margin, bs + 2 * margin};
      std::vector<SearchStage> stages{{p.coarse_radius, p.coarse_step}};
      if (p.fine_radius > 0) stages.push_back({p.fine_radius, p.fine_step});
      std::vector<double> mu1(static_cast<std::size_t>(M), 0.0), s1(static_cast<std::size_t>(M), 1.0),
          mu0 = mu1, s0 = s1, nm(static_cast<std::size_t>(M)), ns(static_cast<std::size_t>(M));
      std::vector<std::int32_t> sel(static_cast<std::size_t>(K));
      for (int k = 0; k < K; ++k) sel[static_cast<std::size_t>(k)] = k;
      std::vector<std::int32_t> xs(static_cast<std::size_t>(B)), ys(static_cast<std::size_t>(B));
      std::vector<double> values(static_cast<std::size_t>(M) * B), h(values.size()),
          scratch(static_cast<std::size_t>(B)), w(static_cast<std::size_t>(P));
      for (int j = 0; j < P; ++j) {
        w[static_cast<std::size_t>(j)] = std::exp(-std::hypot(pos_off[static_cast<std::size_t>(j)][0], pos_off[static_cast<std::size_t>(j)][1]));
      }
      std::vector<double> ep(static_cast<std::size_t>(P) * M), en(static_cast<std::size_t>(N) * M);
      std::vector<int> pick(neg_all.size());
      IntegralImage ii;
      bool first = true;
      std::vector<std::array<double, kStages>> times;
      const int steps = std::max(reps_cap, 2 * n_frames);
      for (int step = 0; step < steps + 1; ++step) {
        const Image& img = frames[static_cast<std::size_t>(step % n_frames)];
        const auto t0 = Clock::now();
        ii.compute(img.view(), roi);
        const auto t1 = Clock::now();
        if (!first) {
          std::vector<double> g[4];
          for (int k = 0; k < K; ++k) {
            const std::size_t f = static_cast<std::size_t>(sel[static_cast<std::size_t>(k)]);
            g[0].push_back(mu1[f]);
            g[1].push_back(s1[f]);
            g[2].push_back(mu0[f]);
            g[3].push_back(s0[f]);
          }
          const WeakGaussians weak(g[0].data(), g[1].data(), g[2].data(), g[3].data(), K, p.guard);
          const auto res = search(ii, bank, sel.data(), K, weak, box, stages, fw, fh);
          g_sink = g_sink + res.back().score;
        }
        const auto t2 = Clock::now();
        // Bags: every positive offset, `neg_count` distinct negatives (sorted, as the tracker).
        for (int j = 0; j < P; ++j) {
          xs[static_cast<std::size_t>(j)] = box.x + pos_off[static_cast<std::size_t>(j)][0];
          ys[static_cast<std::size_t>(j)] = box.y + pos_off[static_cast<std::size_t>(j)][1];
        }
        for (std::size_t i = 0; i < pick.size(); ++i) pick[i] = static_cast<int>(i);
        std::shuffle(pick.begin(), pick.end(), rng);
        std::sort(pick.begin(), pick.begin() + N);
        for (int j = 0; j < N; ++j) {
          const auto& o = neg_all[static_cast<std::size_t>(pick[static_cast<std::size_t>(j)])];
          xs[static_cast<std::size_t>(P + j)] = box.x + o[0];
          ys[static_cast<std::size_t>(P + j)] = box.y + o[1];
        }
        const auto t3 = Clock::now();
        project(ii, bank, nullptr, M, xs.data(), ys.data(), B, values.data());
        const auto t4 = Clock::now();
        const MatrixView vpos{values.data(), M, P, B, 1}, vneg{values.data() + P, M, N, B, 1};
        GaussianRule rule;
        rule.first = first;
        rule.mil = p.milboost;
        gaussian_update(vpos, mu1.data(), s1.data(), rule, nm.data(), ns.data(), scratch.data());
        mu1.swap(nm);
        s1.swap(ns);
        gaussian_update(vneg, mu0.data(), s0.data(), rule, nm.data(), ns.data(), scratch.data());
        mu0.swap(nm);
        s0.swap(ns);
        const auto t5 = Clock::now();
        const WeakGaussians all(mu1.data(), s1.data(), mu0.data(), s0.data(), M, p.guard);
        for (int k = 0; k < M; ++k) {
          all.log_ratio(k, values.data() + static_cast<std::ptrdiff_t>(k) * B, B,
                        h.data() + static_cast<std::ptrdiff_t>(k) * B, false, nullptr);
        }
        const auto t6 = Clock::now();
        const MatrixView hpos{h.data(), M, P, B, 1}, hneg{h.data() + P, M, N, B, 1};
        if (p.milboost) {
          for (int m = 0; m < M; ++m) {
            for (int j = 0; j < P; ++j) ep[static_cast<std::size_t>(j) * M + m] = std::exp(std::clamp(hpos.at(m, j), -300.0, 300.0));
            for (int j = 0; j < N; ++j) en[static_cast<std::size_t>(j) * M + m] = std::exp(std::clamp(hneg.at(m, j), -300.0, 300.0));
          }
          milboost_select(hpos, hneg, MatrixView{ep.data(), P, M, M, 1},
                          MatrixView{en.data(), N, M, M, 1}, K, p.guard, sel.data());
        } else if (p.select) {
          wmil_select(hpos, hneg, w.data(), K, false, sel.data());
        }
        const auto t7 = Clock::now();
        if (!first) {
          const auto us = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count() * 1e6; };
          times.push_back({us(t0, t1), us(t1, t2), us(t3, t4), us(t4, t5), us(t5, t6), us(t6, t7)});
          (void)t3;
        }
        first = false;
      }
      std::array<double, kStages> med{};
      std::vector<double> total;
      for (const auto& t : times) {
        double sum = 0.0;
        for (double v : t) sum += v;
        total.push_back(sum);
      }
      for (int s = 0; s < kStages; ++s) {
        std::vector<double> col;
        for (const auto& t : times) col.push_back(t[static_cast<std::size_t>(s)]);
        std::sort(col.begin(), col.end());
        med[static_cast<std::size_t>(s)] = col[col.size() / 2];
      }
      std::sort(total.begin(), total.end());
      const std::string cfg = std::string(p.name) + ", box " + std::to_string(bs) + ", " +
                              std::to_string(fw) + "x" + std::to_string(fh);
      std::printf("| frame      | %-32s | %6d | %10.2f | %10.2f | %12.0f fps    |", cfg.c_str(),
                  static_cast<int>(times.size()), total.front(), total[total.size() / 2],
                  1e6 / total[total.size() / 2]);
      std::printf("  ");
      for (int s = 0; s < kStages; ++s) std::printf("%s %.0f; ", stage_names[s], med[static_cast<std::size_t>(s)]);
      std::printf("\n");
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  bool frame_only = false;
  bool fhog_only = false;
  const char* only = nullptr;
  int reps_cap = 200;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else if (std::strcmp(argv[i], "--frame-only") == 0) {
      frame_only = true;
    } else if (std::strcmp(argv[i], "--fhog-only") == 0) {
      fhog_only = true;
    } else if (std::strcmp(argv[i], "--preset") == 0 && i + 1 < argc) {
      only = argv[++i];
    } else if (std::strcmp(argv[i], "--reps") == 0 && i + 1 < argc) {
      reps_cap = std::max(5, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr, "usage: %s [--quick] [--reps N] [--frame-only] [--fhog-only] [--preset NAME]\n", argv[0]);
      return 2;
    }
  }
  const double budget = quick ? 0.05 : 0.4;  // seconds per case, roughly
  if (quick) reps_cap = std::min(reps_cap, 20);
  std::mt19937 rng(12345);
  std::printf("| Benchmark  | Configuration                    | Reps   | Min us     | Median us  | Throughput (min)   |\n");
  std::printf("|------------|----------------------------------|--------|------------|------------|--------------------|\n");
  if (fhog_only) {
    bench_fhog(reps_cap, budget, rng);
    return g_sink == 12345.678 ? 1 : 0;
  }
  if (!frame_only) {
    bench_integral(reps_cap, budget, rng);
    bench_channels(reps_cap, budget, rng);
    bench_project(reps_cap, budget, rng);
    bench_score(reps_cap, budget, rng);
    bench_fhog(reps_cap, budget, rng);
  }
  bench_frame(reps_cap, quick, only, rng);
  std::printf("\nintegral: pixels of the ROI converted to luma and summed per second; project: "
              "feature values per second; channels: ROI pixels x planes per second; score: candidate boxes scored per second (each "
              "evaluates K=50 features and their Gaussian log-ratios); fhog_regn/sample/fhog: "
              "template pixels per second of cf::sample_gray + cf::fhog (cell 4), each alone; frame: one whole frame step of the "
              "preset in C++ (median us per stage after the row; the bag sampling between search and "
              "projection is not timed), the floor of Tracker.update.\n");
  return g_sink == 12345.678 ? 1 : 0;
}
