"""Report stage of the evaluation: tables, JSON, plots and box files.

Every table starts with a caption line naming the machine, the versions and the conventions
it was made with (:func:`caption`), so a copied table carries them along.
"""

from __future__ import annotations

import math
import os
import platform
import re
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from .runner import RunOutcome

__all__ = [
    "box_path",
    "caption",
    "cpu_model",
    "environment",
    "format_ope_table",
    "format_vot_table",
    "json_safe",
    "plural",
    "read_results",
    "safe_name",
    "threshold_text",
    "write_plots",
    "write_run_boxes",
]

FloatArray = npt.NDArray[np.float64]

_UNSAFE = re.compile(r"[^A-Za-z0-9._+-]")


def safe_name(name: str) -> str:
    """Make a tracker name usable as a folder name (``opencv:MIL`` -> ``opencv_MIL``).

    Parameters
    ----------
    name:
        Tracker name.

    Returns
    -------
    str
        ``name`` with every character outside ``[A-Za-z0-9._+-]`` replaced by ``_``.
    """
    out = _UNSAFE.sub("_", name.strip())
    return out if out not in ("", ".", "..") else "_" + out


def plural(n: int, word: str, words: str | None = None) -> str:
    """``n`` and the noun that agrees with it: ``plural(1, "sequence")`` is ``"1 sequence"``,
    ``plural(2, "sequence")`` ``"2 sequences"`` (``words``: an irregular plural)."""
    return f"{n} {word if n == 1 else (words if words is not None else word + 's')}"


def caption(env: Mapping[str, Any], settings: Mapping[str, Any]) -> str:
    """One line naming the machine, versions and conventions of a table.

    Parameters
    ----------
    env:
        :func:`environment`.
    settings:
        ``seeds``, ``missing`` (``None``: not stated, e.g. for the VOT-style protocol),
        ``cv_threads``, ``jobs`` (as ``run_eval`` records them).

    Returns
    -------
    str
        E.g. ``Machine: AMD EPYC, 2 cores; Python 3.11.7, numpy 2.4.6, OpenCV 5.0.0
        (opencv-python-headless 5.0.0.93); seeds 0,1,2; frames without a box: hold the last
        box; OpenCV threads: 1; -j 1.``
    """
    seeds = settings.get("seeds")
    seed_text = "seeds " + ",".join(str(s) for s in seeds) if seeds else "no tracker run"
    rule = {
        "hold": "hold the last box",
        "miss": "a frame a tracker reports lost is a miss",
    }.get(str(settings.get("missing")), str(settings.get("missing")))
    threads = settings.get("cv_threads")
    rule_text = "" if settings.get("missing") is None else f"frames without a box: {rule}; "
    return (
        f"Machine: {env['cpu']}, {env['cpu_count']} cores; Python {env['python']}, numpy "
        f"{env['numpy']}, OpenCV {env['opencv']} ({env['opencv_wheel']}); {seed_text}; "
        f"{rule_text}OpenCV threads: "
        f"{'OpenCV default' if threads is None else threads}; -j {settings.get('jobs')}."
    )


def box_path(root: Path, tracker: str, seq: str, repeat: int) -> Path:
    """Box file of one run: ``root/<safe tracker name>/<seq>[.r<repeat>].txt`` (repeat 0 has
    no suffix)."""
    suffix = "" if repeat == 0 else f".r{repeat}"
    return root / safe_name(tracker) / f"{seq}{suffix}.txt"


def write_run_boxes(root: Path, run: RunOutcome, boxes: npt.ArrayLike) -> Path:
    """Write one run's scored boxes (one ``x,y,w,h`` line per frame, ``NaN`` where none).

    Parameters
    ----------
    root:
        Folder of the box files.
    run:
        The run (for its tracker, sequence and repeat).
    boxes:
        The boxes to write (:func:`wmiltrack.eval.scoring.run_boxes`).

    Returns
    -------
    pathlib.Path
        The file written.
    """
    from ..data.boxes import write_boxes

    path = box_path(root, run.tracker, run.sequence, run.repeat)
    write_boxes(path, np.asarray(boxes, dtype=np.float64))
    return path


def read_results(
    results_dir: Path, gts: Mapping[str, FloatArray], notes: list[str]
) -> list[RunOutcome]:
    """Box files ``results_dir/<tracker>/<seq>[.r<k>].txt`` as untimed runs.

    Parameters
    ----------
    results_dir:
        Folder of tracker folders.
    gts:
        ``{sequence: ground truth}``; files of other sequences are ignored.
    notes:
        Receives a line for every file cut, skipped or missing.

    Returns
    -------
    list of RunOutcome
        A NaN row is a frame without a box; every other frame counts as found.

    Raises
    ------
    FileNotFoundError
        If the folder or every box file is missing.
    """
    from ..data.boxes import read_boxes

    if not results_dir.is_dir():
        raise FileNotFoundError(f"results folder not found: {results_dir}")
    pattern = re.compile(r"^(?P<seq>.+?)(?:\.r(?P<rep>\d+))?\.txt$")
    runs: list[RunOutcome] = []
    for tdir in sorted(p for p in results_dir.iterdir() if p.is_dir()):
        found = 0
        for f in sorted(tdir.glob("*.txt")):
            m = pattern.match(f.name)
            if m is None or m.group("seq") not in gts:
                continue
            seq = m.group("seq")
            gt = gts[seq]
            boxes = read_boxes(f)
            if len(boxes) > len(gt):
                notes.append(
                    f"{tdir.name}/{f.name}: {len(boxes)} boxes for {len(gt)} "
                    f"ground-truth frames; scoring the first {len(gt)}"
                )
                boxes = boxes[: len(gt)]
            elif len(boxes) < len(gt):
                notes.append(
                    f"{tdir.name}/{f.name}: only {len(boxes)} boxes for {len(gt)} "
                    "ground-truth frames; skipped"
                )
                continue
            rep = int(m.group("rep") or 0)
            oks = np.all(np.isfinite(boxes), axis=1)
            runs.append(RunOutcome(tdir.name, seq, rep, rep, boxes, oks))
            found += 1
        missing = sorted(set(gts) - {r.sequence for r in runs if r.tracker == tdir.name})
        if found and missing:
            notes.append(f"{tdir.name}: no box file for {', '.join(missing)}")
    if not runs:
        raise FileNotFoundError(
            f"no box files <tracker>/<sequence>.txt for the dataset's sequences under {results_dir}"
        )
    return runs


def write_plots(scored: Mapping[str, Any], out: Path, n_seq: int) -> dict[str, str]:
    """Write ``success_ope.png`` and ``precision_ope.png`` of :func:`score_ope`'s summary, and
    beside them ``accuracy_speed.png`` (mean AUC against update FPS of the same run) when the
    runs were timed.

    Parameters
    ----------
    scored:
        Output of :func:`wmiltrack.eval.scoring.score_ope`.
    out:
        Folder.
    n_seq:
        Number of sequences (for the titles).

    Every plot gives a tracker the same colour, fixed by the order of the summary (the order
    the trackers were given: :func:`wmiltrack.eval.plots.tracker_styles`).

    Returns
    -------
    dict
        ``{"success_plot": path, "precision_plot": path}``, and ``"accuracy_speed_plot"``
        when some tracker has a speed.
    """
    from .plots import plot_accuracy_speed, plot_precision, plot_success

    summ = scored["summary"]
    order = list(summ)
    seqs = plural(n_seq, "sequence")
    succ = out / "success_ope.png"
    prec = out / "precision_ope.png"
    plot_success(
        {t: s["success_curve"] for t, s in summ.items()},
        {t: s["auc"] for t, s in summ.items()},
        succ,
        title=f"Success plots of OPE ({seqs})",
        order=order,
    )
    plot_precision(
        {t: s["precision_curve"] for t, s in summ.items()},
        {t: s["precision_20"] for t, s in summ.items()},
        prec,
        title=f"Precision plots of OPE ({seqs})",
        order=order,
    )
    files = {"success_plot": str(succ), "precision_plot": str(prec)}
    speeds = {t: float(s.get("fps", float("nan"))) for t, s in summ.items()}
    if any(np.isfinite(v) and v > 0 for v in speeds.values()):
        both = out / "accuracy_speed.png"
        plot_accuracy_speed({t: s["auc"] for t, s in summ.items()}, speeds, both,
                            title=f"Accuracy and speed ({seqs}, same run)", order=order)
        files["accuracy_speed_plot"] = str(both)
    return files


def write_longterm_plots(scored: Mapping[str, Any], out: Path, n_seq: int) -> dict[str, str]:
    """Write ``precision_recall_longterm.png`` and ``fscore_longterm.png`` of
    :func:`wmiltrack.eval.longterm.longterm_scores`'s summary, each tracker in the colour the
    order of the summary gives it (as :func:`write_plots`).

    Returns
    -------
    dict
        ``{"precision_recall_plot": path, "fscore_plot": path}``.
    """
    from .plots import plot_fscore_bars, plot_precision_recall

    summ = scored["summary"]
    seqs = plural(n_seq, "sequence")
    pr_path = out / "precision_recall_longterm.png"
    f_path = out / "fscore_longterm.png"
    plot_precision_recall(
        {t: (s["curve"]["precision"], s["curve"]["recall"]) for t, s in summ.items()},
        {t: s["f_score"] for t, s in summ.items()},
        pr_path,
        title=f"Tracking precision-recall ({seqs})",
        order=list(summ),
    )
    plot_fscore_bars(
        {t: s["f_score"] for t, s in summ.items()},
        {t: s["ok_f_score"] for t, s in summ.items()},
        f_path,
        title=f"Tracking F-score ({seqs})",
        order=list(summ),
    )
    return {"precision_recall_plot": str(pr_path), "fscore_plot": str(f_path)}


def format_longterm_table(scored: Mapping[str, Any], *, title: str) -> str:
    """The long-term protocol's markdown table: per tracker the F-score, precision and recall at
    its best confidence threshold and at its own lost flag, then each sequence's F-scores.

    Parameters
    ----------
    scored:
        :func:`wmiltrack.eval.longterm.longterm_scores`.
    title:
        The caption (:func:`caption`).
    """
    from .plots import ranked

    summ = scored["summary"]
    order = ranked({t: s["f_score"] for t, s in summ.items()})
    lines = [
        "Long-term tracking (VOT-LT measures): tracking precision Pr, recall Re and F-score "
        "F = 2 Pr Re / (Pr + Re); per sequence, then averaged over sequences at each confidence "
        "threshold, F at the threshold that maximises it (as the VOT toolkit); 'lost flag': "
        "the frames the tracker says it has the target. Frames where the target is absent "
        "count against precision. Threshold 'any': every frame with a box is reported, "
        "whatever its confidence; 'none': no frame is.",
        "",
        title,
        "",
    ]
    rows = []
    for t in order:
        s = summ[t]
        rows.append([t, _f(s["f_score"], ".3f"), _f(s["precision"], ".3f"),
                     _f(s["recall"], ".3f"), threshold_text(s["threshold"]), _f(s["ok_f_score"], ".3f"),
                     _f(s["ok_precision"], ".3f"), _f(s["ok_recall"], ".3f"), s["confidence"],
                     str(s.get("errors", 0))])
    lines += _markdown(["Tracker", "F", "Pr", "Re", "threshold", "F (lost flag)", "Pr (lost flag)",
                        "Re (lost flag)", "confidence", "failed runs"], rows, [])
    seqs = sorted({q for t in order for q in scored["results"][t]})
    lines += ["", "Per sequence: F at the tracker's best threshold / F at its lost flag "
              "(absent frames in brackets).", ""]
    seq_rows = []
    for q in seqs:
        cells = []
        absent = 0
        for t in order:
            r = scored["results"][t].get(q)
            if r is None:
                cells.append("-")
                continue
            absent = r["absent_frames"]
            cells.append(f"{_f(r['f_score'], '.3f')} / {_f(r['ok_f_score'], '.3f')}")
        seq_rows.append([f"{q} ({absent})", *cells])
    lines += _markdown(["Sequence", *order], seq_rows, [])
    return "\n".join(lines) + "\n"


def threshold_text(v: Any) -> str:
    """A long-term confidence threshold as the table prints it: ``any`` for -inf (every frame
    with a box counts as reported), ``none`` for +inf (no frame does), else 3 digits."""
    if v is not None and math.isinf(float(v)):
        return "any" if float(v) < 0 else "none"
    return _f(v, ".3g")


def _f(v: Any, spec: str) -> str:
    if v is None:
        return "-"
    x = float(v)
    return "-" if math.isnan(x) else format(x, spec)


def _pm(d: Mapping[str, Any], key: str, spec: str, repeats: int) -> str:
    text = _f(d.get(key), spec)
    std = d.get(key + "_std")
    if repeats > 1 and text != "-" and std is not None and not math.isnan(float(std)):
        text += " ± " + format(float(std), spec)
    return text


def _ms(v: Any) -> str:
    return _f(None if v is None else float(v) * 1000.0, ".1f")


def _markdown(
    headers: Sequence[str], rows: Sequence[Sequence[str]], bold_rows: Sequence[Sequence[str]]
) -> list[str]:
    lines = ["| " + " | ".join(headers) + " |", "|" + "|".join(["---"] * len(headers)) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    lines += ["| **" + r[0] + "** | " + " | ".join(r[1:]) + " |" for r in bold_rows]
    return lines


def _accuracy_cells(tracker: str, m: Mapping[str, Any], repeats: int) -> list[str]:
    """The OPE table's cells from the tracker's name to the frames without a box, for one
    sequence's figures or a tracker's summary (the same keys)."""
    return [
        tracker + (" (!)" if m["errors"] else ""),
        str(m["n_frames"]),
        str(m["n_missing"]),
        _pm(m, "auc", ".3f", repeats),
        _pm(m, "success_50", ".3f", repeats),
        _pm(m, "precision_20", ".3f", repeats),
        _pm(m, "norm_precision_20", ".3f", repeats),
        _pm(m, "mean_center_error", ".1f", repeats),
        _f(m["n_lost"], ".0f"),
        _f(m["n_no_prediction"], ".0f"),
    ]


def format_ope_table(
    scored: Mapping[str, Any],
    repeats: int,
    timed: bool,
    *,
    title: str = "",
    missing: str = "hold",
    reference: str = "opencv:MIL",
) -> str:
    """Markdown table of :func:`~wmiltrack.eval.scoring.score_ope`'s output with a mean row
    per tracker.

    Parameters
    ----------
    scored:
        Output of :func:`~wmiltrack.eval.scoring.score_ope`.
    repeats:
        Number of repeats (``> 1`` adds ``± std``).
    timed:
        Include the FPS, FPS ratio and initialisation-time columns.
    title:
        First line (:func:`caption`), or empty.
    missing:
        The convention the boxes were scored with, for the notes.
    reference:
        The tracker the FPS ratio divides by, for the notes.

    Returns
    -------
    str
    """
    headers = [
        "Sequence",
        "Tracker",
        "Frames",
        "GT missing",
        "AUC",
        "SR@0.5",
        "P@20",
        "NP@0.2",
        "CLE px",
        "Lost",
        "No box",
    ]
    if timed:
        headers += ["FPS", "FPS ratio", "Init ms"]
    results = scored["results"]
    rows = _ope_rows(results, repeats, timed, reference)
    bold: list[list[str]] = []
    for tracker, s in scored["summary"].items():
        row = [f"mean ({s['n_sequences']} seq)", *_accuracy_cells(tracker, s, repeats)]
        if timed:
            row += [_f(s["fps"], ".1f"), _f(s["fps_ratio"], ".2f"), _ms(s["init_time"])]
        bold.append(row)
    notes = _ope_notes(timed, missing, reference)
    notes += _run_notes(results, repeats, "(!) tracker errors (remaining frames scored as misses):")
    head = [title, ""] if title else []
    return "\n".join(head + _markdown(headers, rows, bold) + notes) + "\n"


def _sequence_order(results: Mapping[str, Any]) -> list[str]:
    """Every sequence any tracker ran, in the order first met (tracker by tracker), so that a
    table's rows follow the dataset even when a tracker skipped some sequences."""
    seqs: list[str] = []
    for tr in results.values():
        seqs += [s for s in tr if s not in seqs]
    return seqs


def _ope_rows(
    results: Mapping[str, Any], repeats: int, timed: bool, reference: str
) -> list[list[str]]:
    """The OPE table's per-sequence rows, every tracker under each sequence; the FPS ratio
    divides by ``reference``'s FPS on the same sequence (NaN where it did not run)."""
    rows: list[list[str]] = []
    for seq in _sequence_order(results):
        for tracker, tr in results.items():
            if seq not in tr:
                continue
            m = tr[seq]["mean"]
            row = [seq, *_accuracy_cells(tracker, m, repeats)]
            if timed:
                ref = results.get(reference, {}).get(seq)
                base = math.nan if ref is None else float(ref["mean"]["fps"])
                ratio = float(m["fps"]) / base if base > 0 else math.nan
                row += [_pm(m, "fps", ".1f", repeats), _f(ratio, ".2f"), _ms(m["init_time"])]
            rows.append(row)
    return rows


def _ope_notes(timed: bool, missing: str, reference: str) -> list[str]:
    """The OPE table's notes: what each figure means, the missing-box rule the boxes were
    scored with and, for a timed table, how speed was measured."""
    rule = (
        "a frame where a tracker gave no box gets its last box (OTB/got10k toolkits)"
        if missing == "hold"
        else "every frame a tracker reports lost has no box"
    )
    notes = [
        "",
        (
            "AUC: mean of the success curve at IoU thresholds 0, 0.05, ..., 1 (IoU > t). "
            "SR@0.5: IoU > 0.5. P@20: centre error <= 20 px. NP@0.2: centre error divided by "
            "the ground-truth size per axis <= 0.2. CLE: mean centre error (inf when a frame "
            "has no box). GT missing: frames whose ground truth is absent or degenerate, left "
            f"out of every figure. Same rule for every tracker: {rule}; a frame left without "
            "a box is a miss in every figure (IoU 0, infinite centre error). Lost: frames the "
            "tracker reported lost. No box: scored frames left without a box (summed over "
            "sequences; mean over repeats)."
        ),
    ]
    if timed:
        notes.append(
            "FPS: update-only frames per second on pre-decoded frames (mean rows: all "
            f"updates / all update time). FPS ratio: FPS / FPS of {reference} in the same "
            "run. Init ms: time of init(). With -j > 1 the processes share the cores, so "
            "speed is best measured with -j 1."
        )
    return notes


def _run_notes(results: Mapping[str, Any], repeats: int, error_title: str) -> list[str]:
    """Table notes shared by the OPE and VOT tables: repeats, then any tracker errors."""
    notes = []
    if repeats > 1:
        notes.append(f"{repeats} repeats with different seeds: mean ± standard deviation.")
    errs = [
        (t, sq, r["error"])
        for t, tr in results.items()
        for sq, v in tr.items()
        for r in v["runs"]
        if r.get("error")
    ]
    if errs:
        notes.append(error_title)
        notes += [f"  {t} on {sq}: {e}" for t, sq, e in errs]
    return notes


def format_vot_table(
    scored: Mapping[str, Any],
    repeats: int,
    skip: int = 5,
    burnin: int = 10,
    *,
    title: str = "",
) -> str:
    """Markdown table of :func:`~wmiltrack.eval.scoring.score_vot`'s output with a summary
    row per tracker.

    Parameters
    ----------
    scored:
        Output of :func:`~wmiltrack.eval.scoring.score_vot`.
    repeats:
        Number of repeats (``> 1`` adds ``± std``).
    skip, burnin:
        The protocol's settings, for the notes.
    title:
        First line (:func:`caption`), or empty.

    Returns
    -------
    str
    """
    headers = [
        "Sequence",
        "Tracker",
        "Frames",
        "Accuracy",
        "Failures",
        "Robustness",
        "FPS",
        "Init ms",
    ]
    results = scored["results"]
    rows = _vot_rows(results, repeats)
    bold = _vot_summary_rows(scored["summary"], repeats)
    notes = [
        "",
        (
            "VOT-style supervised protocol (VOT2015's rules on axis-aligned OTB boxes, so "
            "not VOT's own numbers): failure = overlap 0 with the ground truth; the "
            f"tracker is re-initialised {plural(skip, 'frame')} later; accuracy = mean overlap "
            f"leaving out the first {plural(burnin, 'frame')} from each (re)initialisation; "
            "robustness = "
            "exp(-100 * failures / frames) (VOT2016 reliability). Summary rows: accuracy = "
            "mean over sequences, failures = total (per sequence in brackets). FPS: "
            "update-only, frames decoded before timing."
        ),
    ]
    notes += _run_notes(results, repeats, "(!) tracker errors:")
    head = [title, ""] if title else []
    return "\n".join(head + _markdown(headers, rows, bold) + notes) + "\n"


def _vot_rows(results: Mapping[str, Any], repeats: int) -> list[list[str]]:
    """The VOT table's per-sequence rows, every tracker under each sequence, a tracker with
    errors marked ``(!)``."""
    rows: list[list[str]] = []
    for seq in _sequence_order(results):
        for tracker, tr in results.items():
            if seq not in tr:
                continue
            m = tr[seq]["mean"]
            rows.append(
                [
                    seq,
                    tracker + (" (!)" if m["errors"] else ""),
                    str(m["n_frames"]),
                    _pm(m, "accuracy", ".3f", repeats),
                    _pm(m, "failures", ".1f", repeats),
                    _pm(m, "robustness", ".3f", repeats),
                    _pm(m, "fps", ".1f", repeats),
                    _ms(m["init_time"]),
                ]
            )
    return rows


def _vot_summary_rows(summary: Mapping[str, Any], repeats: int) -> list[list[str]]:
    """The VOT table's summary row per tracker: mean accuracy, total failures with the
    failures per sequence in brackets, robustness and speed over the whole dataset."""
    bold: list[list[str]] = []
    for tracker, s in summary.items():
        fails = (
            _pm(s, "failures", ".1f", repeats)
            + " ("
            + _pm(s, "failures_per_sequence", ".2f", repeats)
            + "/seq)"
        )
        bold.append(
            [
                f"all ({s['n_sequences']} seq)",
                tracker + (" (!)" if s["errors"] else ""),
                str(s["n_frames"]),
                _pm(s, "accuracy", ".3f", repeats),
                fails,
                _pm(s, "robustness", ".3f", repeats),
                _f(s["fps"], ".1f"),
                _ms(s["init_time"]),
            ]
        )
    return bold




# ----------------------------------------------------------------------------- machine
def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``; ``platform.processor()`` elsewhere)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "?"


def environment(cv_threads: int | None = None) -> dict[str, Any]:
    """Machine and versions that timings depend on, for benchmark reports.

    ``cv_threads``: the ``cv2.setNumThreads`` value the runs used (``None``: left alone);
    ``opencv_threads`` is then the count OpenCV reports under it (``setNumThreads(0)`` runs
    on 1 thread, for instance), read with the setting applied and then restored.

    Returns
    -------
    dict
        Date, Python, platform, CPU model and count, numpy, the installed OpenCV wheel and
        version with its thread count, matplotlib (None if absent) and wmiltrack.
    """
    import cv2

    from .. import __version__
    from ..integrations.opencv_wheels import installed_opencv

    try:
        import matplotlib

        mpl: str | None = matplotlib.__version__
    except ImportError:
        mpl = None
    dist, ver = installed_opencv()
    before = cv2.getNumThreads()
    if cv_threads is not None:
        cv2.setNumThreads(int(cv_threads))
    used = int(cv2.getNumThreads())
    cv2.setNumThreads(before)
    return {
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "cpu": cpu_model(),
        "cpu_count": os.cpu_count(),
        "numpy": np.__version__,
        "opencv": cv2.__version__,
        "opencv_wheel": f"{dist} {ver}",
        "opencv_threads": used,
        "matplotlib": mpl,
        "wmiltrack": __version__,
    }


def json_safe(obj: Any) -> Any:
    """A copy fit for strict JSON: NaN -> None, infinities -> "inf"/"-inf", numpy scalars ->
    Python numbers, tuples -> lists, dict keys -> str (recursively)."""
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        if math.isnan(f):
            return None
        if math.isinf(f):
            return "inf" if f > 0 else "-inf"
        return f
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    return obj
