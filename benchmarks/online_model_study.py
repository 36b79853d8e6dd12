"""A study, not a preset: NanoTrack's published step with an online discriminative model learnt
on the network's own search features (one backbone pass a frame), measured on a development
half the way ``devset.py`` measures presets.

The model is a multi-channel correlation filter on the backbone's search map (v3: 96 x 16 x 16),
learnt on the first frame with the target's neighbourhood as the negatives (a Gaussian label on
the target's cell; MOSSE-style running numerator and denominator) and updated at ``lr`` only on
frames whose Siamese logit is above ``t_learn`` and whose own response is above ``gate``. Its
response, shifted onto the head's grid, is mixed into the Siamese map (share ``fuse``) before the
published penalties and window; the head's regression gives the box. The lost flag is the
Siamese score's logit below ``t_lost`` on ``lost_frames`` frames in a row; while lost, the step
goes on and ``redetect`` whole-frame windows a frame are searched after ``redetect_after`` lost
frames (a window whose logit, plus ``like_w`` times its likeness to the first template read off
the same search map, beats the own answer by ``margin`` takes the box); found after
``found_frames`` frames above ``t_found``. ``fuse=0, t_lost=-inf, redetect=0`` is NanoTrack
alone (its boxes to 1e-12).

    python benchmarks/online_model_study.py --roots ../shared/data/otb,$MORE,$MORE2 \\
        --half 1 --set '{"fuse": 0.3}' -j 2 [--json out.json]

The measured designs and their figures are on the performance page ("rcwmil-nano, second step:
a study"). NanoTrack v3's files come from the models folder (``wmiltrack models fetch
nanotrack-v3``) or ``WMILTRACK_NANO_BACKBONE``/``_HEAD``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import devset  # noqa: E402

from wmiltrack.data.sequences import load_dataset  # noqa: E402
from wmiltrack.engine.frames import as_frame, clip_box  # noqa: E402
from wmiltrack.engine.result import TrackResult  # noqa: E402
from wmiltrack.eval.metrics import ope_metrics  # noqa: E402
from wmiltrack.eval.runner import run_sequence  # noqa: E402
from wmiltrack.networks.files import nanotrack_files  # noqa: E402
from wmiltrack.networks.nanotrack import (  # noqa: E402
    EXEMPLAR,
    INSTANCE,
    MIN_SIDE,
    STRIDE,
    NanoNetwork,
    nanotrack_constants,
)
from wmiltrack.networks.siamese import as_bgr, context_side, crop  # noqa: E402

DEFAULTS: dict[str, Any] = dict(
    fuse=0.3, lr=0.02, sigma=0.6, lam=0.01, gate=0.5, t_lost=5.2, t_learn=6.0, t_found=6.0,
    lost_frames=3, found_frames=2, redetect=2, redetect_after=10, like_w=5.0, margin=1.0)
CELLS = 16  # the search map's side (255 px / stride 16)


def _logit(p: float) -> float:
    p = min(max(p, 1e-9), 1 - 1e-9)
    return math.log(p / (1 - p))


class OnlineFilter:
    """A multi-channel correlation filter on ``(c, 16, 16)`` search maps (see the module)."""

    def __init__(self, sigma: float, lam: float) -> None:
        self.sigma, self.lam = sigma, lam
        hann = np.hanning(CELLS + 2)[1:-1]
        self.window = np.outer(hann, hann).astype(np.float32)

    def label(self, dy: float, dx: float) -> np.ndarray:
        """The label's spectrum: a Gaussian on the cell ``(dy, dx)`` from the map's centre."""
        ys = np.arange(CELLS) - (CELLS - 1) / 2 - dy
        xs = np.arange(CELLS) - (CELLS - 1) / 2 - dx
        ys, xs = (ys + CELLS / 2) % CELLS - CELLS / 2, (xs + CELLS / 2) % CELLS - CELLS / 2
        g = np.exp(-0.5 * (ys[:, None] ** 2 + xs[None, :] ** 2) / self.sigma ** 2)
        return np.fft.rfft2(np.fft.ifftshift(g).astype(np.float32))

    def spectrum(self, features: np.ndarray) -> np.ndarray:
        return np.fft.rfft2(features[0] * self.window, axes=(-2, -1))

    def start(self, x: np.ndarray) -> None:
        self.a, self.b = np.conj(self.label(0.0, 0.0))[None] * x, (np.abs(x) ** 2).sum(0)
        self.peak = 1.0
        self.peak = float(self.respond(x).max())

    def learn(self, x: np.ndarray, dy: float, dx: float, rate: float) -> None:
        self.a = (1 - rate) * self.a + rate * (np.conj(self.label(dy, dx))[None] * x)
        self.b = (1 - rate) * self.b + rate * (np.abs(x) ** 2).sum(0)

    def respond(self, x: np.ndarray) -> np.ndarray:
        """The response on the 16 x 16 cells, centred, over the first frame's peak."""
        a, b = self.a, self.b
        r = np.fft.irfft2((np.conj(a) * x).sum(0) / (b + self.lam * b.mean()), s=(CELLS, CELLS))
        return np.fft.fftshift(r).astype(np.float64) / self.peak


def on_grid(r: np.ndarray, n: int) -> np.ndarray:
    """A 16 x 16 cell response on the head's ``n x n`` points (v3's 15 sit between cells)."""
    if n == CELLS - 1:
        r = 0.25 * (r[:-1, :-1] + r[1:, :-1] + r[:-1, 1:] + r[1:, 1:])
    return r.ravel()


class OnlineNano:
    """NanoTrack v3's step with the online filter fused in, a logit lost flag and re-detection
    (see the module's docstring for the settings, ``DEFAULTS`` for their values)."""

    def __init__(self, version: str = "v3", **settings: Any) -> None:
        files = nanotrack_files(version)
        self.net = NanoNetwork(files[0], files[1], "auto", 1)
        self.k = nanotrack_constants(version)
        self.s = {**DEFAULTS, **settings}
        self.filter = OnlineFilter(self.s["sigma"], self.s["lam"])
        n = self.k.grid
        hann = np.hanning(n)
        self.cosine = np.outer(hann, hann).ravel()
        ticks = -(n // 2) * STRIDE + STRIDE * np.arange(n, dtype=np.float64)
        self.px, self.py = np.tile(ticks, n), np.repeat(ticks, n)

    def init(self, frame: Any, box: Any) -> None:
        img = as_bgr(as_frame(frame))
        x, y, w, h = (float(v) for v in clip_box(box, img.shape[1], img.shape[0]))
        self.centre, self.size = (x + (w - 1) / 2, y + (h - 1) / 2), (w, h)
        self.frame_wh = (img.shape[1], img.shape[0])
        self.fill = tuple(float(v) for v in img.reshape(-1, 3).mean(axis=0))
        exemplar = crop(img, *self.centre, round(context_side(w, h)), EXEMPLAR, self.fill)  # type: ignore[arg-type]
        self.template = self.net.features(exemplar)
        z = self.template.astype(np.float64).ravel()
        self.z0 = z / (np.linalg.norm(z) + 1e-12)
        self.filter.start(self.filter.spectrum(self._features(img, self.centre, self.size)[0]))
        self.lost, self.run, self.lost_for = False, 0, 0
        self.held, self.sweep = self.centre, []  # type: list[tuple[float, float]]

    def _features(self, img: np.ndarray, centre: tuple[float, float], size: tuple[float, float]
                  ) -> tuple[np.ndarray, float]:
        side = context_side(*size)
        search = crop(img, centre[0], centre[1], side * INSTANCE / EXEMPLAR, INSTANCE, self.fill)  # type: ignore[arg-type]
        return self.net.features(search), EXEMPLAR / side

    def search(self, img: np.ndarray, centre: tuple[float, float], size: tuple[float, float],
               window: bool) -> tuple[tuple[float, float], tuple[float, float], dict[str, Any]]:
        """One search: the new centre and size and the evidence (logit, the filter's response
        at the chosen point, the likeness, the label's offset, the map's spectrum)."""
        feats, scale = self._features(img, centre, size)
        logits, sides = self.net.head(self.template, feats)
        logits = logits.reshape(2, -1).astype(np.float64)
        scores = 1.0 / (1.0 + np.exp(logits[0] - logits[1]))
        left, top, right, bottom = sides.reshape(4, -1).astype(np.float64)
        boxes = np.stack([self.px + (right - left) / 2, self.py + (bottom - top) / 2,
                          left + right, top + bottom])
        x = self.filter.spectrum(feats)
        online = on_grid(self.filter.respond(x), self.k.grid)
        penalty = self._penalty(boxes, size[0] * scale, size[1] * scale)
        fuse = self.s["fuse"]
        pscore = penalty * ((1 - fuse) * scores + fuse * np.clip(online, 0.0, 1.5))
        if window:
            infl = self.k.window_influence
            pscore = pscore * (1 - infl) + self.cosine * infl
        best = int(np.argmax(pscore))
        lr = float(penalty[best] * scores[best]) * self.k.lr
        bx, by, bw, bh = boxes[:, best] / scale
        (fw, fh), (w, h) = self.frame_wh, size
        cx, cy = min(max(centre[0] + bx, 0.0), fw), min(max(centre[1] + by, 0.0), fh)
        nw = min(max(w * (1 - lr) + bw * lr, MIN_SIDE), fw)
        nh = min(max(h * (1 - lr) + bh * lr, MIN_SIDE), fh)
        evidence = {"logit": _logit(float(scores[best])), "online": float(online[best]),
                    "like": self._likeness(feats, best), "dx": float(bx * scale / STRIDE),
                    "dy": float(by * scale / STRIDE), "x": x}
        return (cx, cy), (nw, nh), evidence

    def _penalty(self, boxes: np.ndarray, w: float, h: float) -> np.ndarray:
        def sz(a: Any, b: Any) -> Any:
            pad = (a + b) * 0.5
            return np.sqrt((a + pad) * (b + pad))
        bw, bh = np.maximum(boxes[2], 1e-6), np.maximum(boxes[3], 1e-6)
        s, r = sz(bw, bh) / sz(w, h), (w / h) / (bw / bh)
        out: np.ndarray = np.exp(-(np.maximum(s, 1 / s) * np.maximum(r, 1 / r) - 1) * self.k.penalty_k)
        return out

    def _likeness(self, feats: np.ndarray, best: int) -> float:
        """The cosine of the 8 x 8 cells under the chosen point with the first template."""
        f, n = feats[0], self.k.grid
        r0 = int(min(max(best // n - 3, 0), f.shape[1] - 8))
        c0 = int(min(max(best % n - 3, 0), f.shape[2] - 8))
        v = f[:, r0:r0 + 8, c0:c0 + 8].astype(np.float64).ravel()
        return float(v @ self.z0 / (np.linalg.norm(v) + 1e-12))

    def update(self, frame: Any) -> TrackResult:
        s = self.s
        img = as_bgr(as_frame(frame))
        centre, size, ev = self.search(img, self.centre, self.size, window=True)
        logit = ev["logit"]
        if not self.lost:
            self.centre, self.size = centre, size
            self.run = self.run + 1 if logit < s["t_lost"] else 0
            if self.run >= s["lost_frames"]:
                self.lost, self.run, self.lost_for, self.sweep = True, 0, 0, []
            elif logit >= s["t_learn"] and ev["online"] >= s["gate"]:
                self.filter.learn(ev["x"], ev["dy"], ev["dx"], s["lr"])
                self.held = self.centre
        else:
            self.lost_for += 1
            self.centre, self.size, logit = self._redetect(img, centre, size, ev)
            self.run = self.run + 1 if logit >= s["t_found"] else 0
            if self.run >= s["found_frames"]:
                self.lost, self.run = False, 0
        (cx, cy), (w, h) = self.centre, self.size
        score = 1.0 / (1.0 + math.exp(-(logit - s["t_lost"])))
        return TrackResult((float(cx - w / 2), float(cy - h / 2), float(w), float(h)), score,
                           not self.lost)

    def _redetect(self, img: np.ndarray, centre: tuple[float, float], size: tuple[float, float],
                  ev: dict[str, Any]) -> tuple[tuple[float, float], tuple[float, float], float]:
        """A lost frame: the step's own answer, or a whole-frame window's that beats it."""
        s = self.s
        best = (ev["logit"] + s["like_w"] * ev["like"], centre, size, ev["logit"])
        if s["redetect"] <= 0 or self.lost_for < s["redetect_after"]:
            return best[1], best[2], best[3]
        if not self.sweep:
            self.sweep = sweep(*self.frame_wh, self.size, self.held)
        places, self.sweep = self.sweep[:s["redetect"]], self.sweep[s["redetect"]:]
        for place in places:
            c2, s2, e2 = self.search(img, place, self.size, window=False)
            value = e2["logit"] + s["like_w"] * e2["like"]
            if e2["logit"] >= s["t_found"] and value > best[0] + s["margin"]:
                best = (value, c2, s2, e2["logit"])
        return best[1], best[2], best[3]


def sweep(fw: int, fh: int, size: tuple[float, float], near: tuple[float, float]
          ) -> list[tuple[float, float]]:
    """Search-window centres over the frame, nearest to ``near`` first."""
    step = max(0.8 * 2 * context_side(*size) * (INSTANCE / EXEMPLAR) * 0.44, 8.0)
    xs = np.arange(step / 2, fw + step / 2, step).clip(0, fw)
    ys = np.arange(step / 2, fh + step / 2, step).clip(0, fh)
    centres = [(float(x), float(y)) for y in ys for x in xs]
    centres.sort(key=lambda c: (c[0] - near[0]) ** 2 + (c[1] - near[1]) ** 2)
    return centres


def _job(job: tuple[dict[str, Any], int, str, str]) -> dict[str, Any]:
    settings, seed, root, name = job
    import cv2

    cv2.setNumThreads(1)
    seq = load_dataset(root, [name])[0]
    start = devset.jitter(seq.init_box, seed, name, 1.0)
    run = run_sequence(lambda: OnlineNano(**settings), seq.load(), start, seed=seed,
                       raise_errors=True)
    return {"spec": "study", "seed": seed, "name": name, "boxes": run.boxes.tolist(),
            "lost": (~run.oks).tolist(), "scores": run.scores.tolist(),
            "seconds": float(np.nansum(run.update_times)), "updates": run.n_updates}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--roots", default=os.environ.get("WMILTRACK_DEVSET"))
    ap.add_argument("--half", choices=("1", "2", "all"), default="1")
    ap.add_argument("--set", default="{}", help="JSON of settings over DEFAULTS")
    ap.add_argument("-j", "--jobs", type=int, default=1)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    if not args.roots:
        ap.error("give --roots or set WMILTRACK_DEVSET")
    roots = [Path(r) for r in args.roots.split(",")]
    where = devset.find_sequences(roots)
    names = sorted(where)
    use = {"1": devset.halves(names)[0], "2": devset.halves(names)[1], "all": names}[args.half]
    settings = json.loads(args.set)
    gts = {n: load_dataset(where[n], [n])[0].groundtruth for n in use}
    jobs = [(settings, seed, str(where[n]), n) for seed in (0, 1, 2)
            for n in sorted(use, key=lambda n: -len(gts[n]))]
    with ProcessPoolExecutor(args.jobs) as pool:
        runs = list(pool.map(_job, jobs))
    per_seed = [np.mean([ope_metrics(np.asarray(r["boxes"]), gts[r["name"]], missing="hold").auc
                         for r in runs if r["seed"] == seed]) for seed in (0, 1, 2)]
    flags = devset.summarise(runs, gts, use, devset.sparse_sequences(roots))
    print(f"half {args.half}: {np.mean(per_seed):.3f} (sd {np.std(per_seed):.3f}); lost flag on "
          f"IoU>=0.5 {100 * flags['well_tracked_flagged_lost']:.1f} %, on IoU=0 or absent "
          f"{100 * flags['off_target_flagged_lost']:.1f} %")
    if args.json is not None:
        args.json.write_text(json.dumps({"settings": {**DEFAULTS, **settings}, "runs": runs}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
