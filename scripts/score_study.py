"""Does ``TrackResult.score`` tell tracked frames from lost ones?

Runs trackers over the shared OTB sequences and over generated sequences in which the target
is fully occluded or vanishes (the scene is swapped for another one), records per frame the
candidate confidence signals and the IoU with the ground truth, and prints for each signal
the ROC AUC of "target tracked" (IoU > 0) against "lost" (IoU == 0, or target not visible)
and the score distributions.

    python scripts/score_study.py [--otb ../shared/data/otb] [--variants rcwmil,rcwmil-plus]
        [--seeds 0,1,2] [--json out.json]

``--variants`` takes tracker specs with overrides, as ``wmiltrack eval`` does
(``rcwmil-plus:score_colour=0``). ``--seeds`` runs each variant with each tracker seed (the
feature bank and negative sampling); the figures are printed per seed, then for the frames of
all seeds pooled, since the frames a tracker loses differ from seed to seed. The default is
seeds 0, 1, 2, as for every accuracy figure of the project (one seed can swing a sequence).

Signals (all computed from what one update already has):

* ``logistic``: the former score, logistic(best raw score / K).
* ``margin``: the best candidate's raw score minus the mean raw score of the coarse search
  grid, divided by K (how much the winner stands out from its neighbourhood).
* ``rel``: best raw score / K divided by its exponential running mean over earlier frames.
* ``score``: what ``Tracker.update`` returns now.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

import wmiltrack
from wmiltrack import _core
from wmiltrack.data.sequences import list_otb_sequences, load_otb_sequence
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.eval.metrics import iou
from wmiltrack.trackers import parse_spec, split_specs


def roc_auc(pos: np.ndarray, neg: np.ndarray) -> float:
    """P(score of a positive > score of a negative), ties counted half (Mann-Whitney U)."""
    pos = pos[np.isfinite(pos)]
    neg = neg[np.isfinite(neg)]
    if pos.size == 0 or neg.size == 0:
        return math.nan
    allv = np.concatenate([pos, neg])
    order = np.argsort(allv, kind="mergesort")
    ranks = np.empty(allv.size)
    sorted_v = allv[order]
    i = 0
    while i < allv.size:  # average ranks of ties
        j = i
        while j + 1 < allv.size and sorted_v[j + 1] == sorted_v[i]:
            j += 1
        ranks[order[i : j + 1]] = 0.5 * (i + j) + 1.0
        i = j + 1
    u = ranks[: pos.size].sum() - pos.size * (pos.size + 1) / 2.0
    return float(u / (pos.size * neg.size))


def fit_logistic(x: np.ndarray, y: np.ndarray, iters: int = 200) -> tuple[float, float]:
    """Class-balanced logistic regression p = sigmoid(a (x - b)) by Newton's method."""
    x = np.clip(np.asarray(x, dtype=np.float64), -50, 50)
    yv = y.astype(np.float64)
    w = np.where(y, 0.5 / max(y.sum(), 1), 0.5 / max((~y).sum(), 1))
    X = np.stack([x, np.ones_like(x)], axis=1)
    theta = np.zeros(2)
    for _ in range(iters):
        p = 1.0 / (1.0 + np.exp(-(X @ theta)))
        g = X.T @ (w * (p - yv))
        H = (X * (w * p * (1 - p))[:, None]).T @ X + 1e-9 * np.eye(2)
        step = np.linalg.solve(H, g)
        theta -= step
        if np.abs(step).max() < 1e-10:
            break
    a, c = theta
    return float(a), float(-c / a)


class Probe(wmiltrack.Tracker):
    """A tracker that also records the grid statistics of each update (for this study)."""

    def init(self, frame: np.ndarray, box: Any) -> None:
        super().init(frame, box)
        scale = self.parts.scale
        if scale is not None:  # the chosen scale's raw score, if it moved
            search = scale.search

            def probed(*args: Any) -> tuple[tuple[int, int, int, int], float]:
                moved, self.raw_best = search(*args)
                return moved, self.raw_best

            scale.search = probed  # type: ignore[method-assign]

    def _coarse_grid_mean(self, origin: tuple[int, int, int, int], coarse: tuple[int, int]) -> None:
        """Mean raw score of the coarse grid around the search's origin."""
        model = self.parts.appearance
        sel, pool = model.selected, model.pool
        weak = (pool.mu1[sel], pool.sigma1[sel], pool.mu0[sel], pool.sigma0[sel])
        _, _, _, n, grid = _core.score_grid(model.ii, model.bank(origin[2], origin[3]), sel, *weak,
                                            self.params.guard, origin, coarse[0], coarse[1],
                                            self._frame_wh, True)
        g = grid[np.isfinite(grid)]
        self.grid_mean = float(g.mean()) if g.size else math.nan

    def _probe(self, state: Any) -> Any:
        """A stage after locate: the coarse grid's mean and the search's raw score."""
        self._coarse_grid_mean(state.origin, self._grids[0])
        self.raw_best = state.raw
        return state

    stages = (wmiltrack.Tracker.stages[0], _probe, *wmiltrack.Tracker.stages[1:])


def run(frames: list[np.ndarray], gt: np.ndarray, visible: np.ndarray, variant: str,
        seed: int = 0) -> dict[str, Any]:
    name, overrides = parse_spec(variant)
    t = Probe(name, seed=seed, **overrides)
    t.init(frames[0], gt[0])
    k = t.parts.appearance.k
    rows: dict[str, list[float]] = {"logistic": [], "margin": [], "rel": [], "ref_ratio": [],
                                    "ref_diff": [], "mean_k": [], "score": [], "iou": []}
    first: list[float] = []
    ema = math.nan
    for i in range(1, len(frames)):
        r = t.update(frames[i])
        raw = t.raw_best
        if not math.isfinite(raw):
            raw = math.nan
        mean_k = raw / k
        rows["logistic"].append(1.0 / (1.0 + math.exp(-mean_k)) if math.isfinite(mean_k) else 0.0)
        rows["mean_k"].append(mean_k if math.isfinite(mean_k) else -50.0)
        rows["margin"].append((raw - t.grid_mean) / k)
        rows["rel"].append(mean_k / ema if math.isfinite(ema) and ema > 0 else 1.0)
        if len(first) < 5 and math.isfinite(mean_k):
            first.append(mean_k)
        ref = float(np.mean(first)) if first else math.nan
        rows["ref_ratio"].append(mean_k / ref if ref > 0 else math.nan)
        rows["ref_diff"].append(mean_k - ref)
        if math.isfinite(mean_k):
            ema = mean_k if not math.isfinite(ema) else 0.9 * ema + 0.1 * mean_k
        rows["score"].append(r.score)
        ov = float(iou(np.array([r.box]), gt[i : i + 1])[0]) if visible[i] else 0.0
        rows["iou"].append(ov)
    return {k2: np.array(v) for k2, v in rows.items()}


def synthetic_cases(seed: int) -> list[tuple[str, list[np.ndarray], np.ndarray, np.ndarray]]:
    """Generated sequences where the target is fully occluded or vanishes for a stretch."""
    out = []
    base = make_sequence(150, seed=seed, occlusion=False, illumination=False, clutter=True)
    frames = [f.copy() for f in base.load()]
    gt = np.asarray(base.groundtruth, dtype=np.float64)
    rng = np.random.default_rng(seed + 1000)
    # 1. full occlusion: a textured block covers the (enlarged) target box in frames 60..99
    occ = [f.copy() for f in frames]
    vis = np.ones(len(frames), dtype=bool)
    for i in range(60, 100):
        x, y, w, h = gt[i]
        x0, y0 = int(max(x - 0.25 * w, 0)), int(max(y - 0.25 * h, 0))
        x1, y1 = int(min(x + 1.25 * w, occ[i].shape[1])), int(min(y + 1.25 * h, occ[i].shape[0]))
        block = rng.integers(60, 200, size=(max(y1 - y0, 1) // 8 + 1, max(x1 - x0, 1) // 8 + 1, 3))
        block = np.kron(block, np.ones((8, 8, 1)))[: y1 - y0, : x1 - x0].astype(np.uint8)
        occ[i][y0:y1, x0:x1] = block
        vis[i] = False
    out.append((f"occlude-s{seed}", occ, gt, vis))
    # 2. vanish: from frame 75 on the camera shows another scene without the target
    other = make_sequence(150, seed=seed + 500, occlusion=False, illumination=False, clutter=True).load()
    van = frames[:75] + [o.copy() for o in other[75:]]
    vis2 = np.arange(len(frames)) < 75
    out.append((f"vanish-s{seed}", van, gt, vis2))
    return out


def summarise(report: dict[str, Any], key: str, variant: str, tag: str,
              acc: dict[str, dict[str, list[np.ndarray]]], signals: tuple[str, ...]) -> None:
    """Print and store (``report[key/group]``) the figures of one variant's frames."""
    for group in ("otb", "synthetic", "all"):
        if group == "all":
            keys = set(acc["otb"]) | set(acc["synthetic"])
            cat = {k: np.concatenate(acc["otb"].get(k, []) + acc["synthetic"].get(k, [])) for k in keys}
        else:
            cat = {k: np.concatenate(v) for k, v in acc[group].items()}
        if not cat:  # no sequence of this group (e.g. --synthetic-seeds 0)
            continue
        tracked = cat["iou"] > 0
        good = cat["iou"] > 0.5
        lost = ~tracked
        entry: dict[str, Any] = {"frames": int(tracked.size), "lost": int(lost.sum())}
        for s in signals:
            v = cat[s]
            entry[s] = {
                "auc_iou>0_vs_0": roc_auc(v[tracked], v[lost]),
                "auc_iou>0.5_vs_0": roc_auc(v[good], v[lost]),
                "median_iou>0.5": float(np.nanmedian(v[good])) if good.any() else math.nan,
                "median_iou==0": float(np.nanmedian(v[lost])) if lost.any() else math.nan,
                "q10_iou>0.5": float(np.nanpercentile(v[good], 10)) if good.any() else math.nan,
                "q90_iou==0": float(np.nanpercentile(v[lost], 90)) if lost.any() else math.nan,
            }
        if group == "all":
            a, b = fit_logistic(cat["mean_k"], tracked)
            entry["fit"] = {"gain": a, "offset": b}
            print(f"   balanced logistic fit of P(IoU>0 | raw/K): gain {a:.3f} offset {b:.3f}")
        report[f"{key}/{group}"] = entry
        print(f"== {variant} {tag} {group}: {entry['frames']} frames, {entry['lost']} lost")
        for s in signals:
            e = entry[s]
            print(f"   {s:9s} AUC(IoU>0 vs 0) {e['auc_iou>0_vs_0']:.3f}  AUC(IoU>.5 vs 0) "
                  f"{e['auc_iou>0.5_vs_0']:.3f}  median tracked {e['median_iou>0.5']:.3f} "
                  f"lost {e['median_iou==0']:.3f}  q10 tracked {e['q10_iou>0.5']:.3f} "
                  f"q90 lost {e['q90_iou==0']:.3f}")
        # best threshold for ok = score >= thr (balanced accuracy) on the current score
        v = cat["score"]
        best = max(((0.5 * (np.mean(v[tracked] >= th) + np.mean(v[lost] < th)), th)
                    for th in np.linspace(0.0, 1.0, 101)), default=(math.nan, math.nan))
        name, overrides = parse_spec(variant)
        thr = wmiltrack.Params.for_variant(name, **overrides).lost_threshold
        at = 0.5 * (np.mean(v[tracked] >= thr) + np.mean(v[lost] < thr))
        print(f"   score: balanced accuracy at lost_threshold {thr:.2f}: {at:.3f}")
        entry["score_best_threshold"] = {"balanced_accuracy": best[0], "threshold": best[1]}
        print(f"   score: best threshold {best[1]:.2f} (balanced accuracy {best[0]:.3f})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--otb", type=Path, default=Path("../shared/data/otb"))
    ap.add_argument("--variants", default="rcwmil")
    ap.add_argument("--seeds", default="0,1,2", help="tracker seeds, comma-separated (default 0,1,2)")
    ap.add_argument("--synthetic-seeds", type=int, default=3)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    signals = ("logistic", "margin", "rel", "ref_ratio", "ref_diff", "score")
    report: dict[str, Any] = {}
    seeds = [int(v) for v in args.seeds.split(",")]
    cases: list[tuple[str, str, list[np.ndarray], np.ndarray, np.ndarray]] = []
    for path in list_otb_sequences(args.otb):
        seq = load_otb_sequence(path)
        frames = seq.load()
        gt = np.asarray(seq.groundtruth, dtype=np.float64)
        n = min(len(frames), len(gt))
        frames, gt = frames[:n], gt[:n]
        vis = np.all(np.isfinite(gt), axis=1)
        cases.append(("otb", seq.name, frames, gt, vis))
    for s in range(args.synthetic_seeds):
        for name, fr, gt, vis in synthetic_cases(s):
            cases.append(("synthetic", name, fr, gt, vis))
    for variant in split_specs(args.variants):
        pooled: dict[str, dict[str, list[np.ndarray]]] = {"otb": {}, "synthetic": {}}
        for seed in seeds + ([-1] if len(seeds) > 1 else []):
            if seed >= 0:
                acc: dict[str, dict[str, list[np.ndarray]]] = {"otb": {}, "synthetic": {}}
                for group, name, frames, gt, vis in cases:
                    rows = run(frames, gt, vis, variant, seed)
                    for key, v in rows.items():
                        acc[group].setdefault(key, []).append(v)
                        pooled[group].setdefault(key, []).append(v)
                    ok = rows["iou"] > 0
                    print(f"{variant:11s} seed {seed} {name:18s} frames {len(ok):4d} lost(IoU=0) "
                          f"{np.sum(~ok):4d} " + " ".join(
                              f"{s}={roc_auc(rows[s][ok], rows[s][~ok]):.2f}" for s in signals))
                tag = f"seed {seed}"
            else:
                acc, tag = pooled, "seeds " + ",".join(map(str, seeds)) + " pooled"
            summarise(report, f"{variant}/{tag.replace(' ', '')}", variant, tag, acc, signals)
    if args.json:
        args.json.write_text(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
