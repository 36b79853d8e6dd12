"""``wmiltrack variants``: the presets' defaults as a table, or every parameter of one."""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Callable
from typing import Any

from .options import EXIT_CODES_EPILOG, Subparsers, UsageError

#: Parameters shown in the variants table, with their column titles.
VARIANT_COLUMNS = [
    ("features", "features"), ("M", "num_features"), ("K", "num_selected"), ("rects", "rects"),
    ("rect weights", "weights"), ("lambda", "learning_rate"), ("positives", "pos_radius"),
    ("negatives", "negatives"), ("selection", "selection"), ("instance weights", "instance_weights"),
    ("search", "search"), ("additions (rcwmil-plus)", "plus"),
]


def _weights(p: Any) -> str:
    if p.feature_kind == "subregion":
        w = f"+1/-1 at {p.positive_prob:.2f}/{1 - p.positive_prob:.2f}"
    else:
        w = {"sign": "+-1", "sign_sqrt": "+-1/sqrt(n)", "uniform": "U[-1,1]"}[p.weight_mode]
    return w + (" / area" if p.area_normalize else ", raw sums")


def _negatives(p: Any) -> str:
    how = "exactly" if p.neg_sampling == "exact" else "Bernoulli, max"
    return f"{p.neg_inner:g} <= d < {p.neg_outer:g}, {how} {p.neg_count}"


def _instance_weights(p: Any) -> str:
    if p.selection != "wmil":
        return "-"
    return {"exp": "exp(-d)/sum", "exp_sq": "exp(-d^2)", "uniform": "equal"}[p.instance_weights]


def _search(p: Any) -> str:
    s = f"{p.coarse_radius}/{p.coarse_step}"
    return s + (f" then {p.fine_radius}/{p.fine_step}" if p.fine_radius > 0 else "")


def _scale_parts(p: Any) -> list[str]:
    """The scale estimator and the correlation filter, as the additions column names them."""
    parts = []
    if p.scale_model == "dsst":
        parts.append(f"scale by DSST ({p.scale_samples} samples)")
    elif p.scale_steps:
        contrast = f", colour contrast {p.scale_contrast:g}" if p.scale_contrast > 0 else ""
        vote = (f", DSST vote {p.scale_dsst:g} ({p.scale_samples} samples)"
                if p.scale_dsst > 0 else "")
        parts.append(f"scale {p.scale_factor:g}^+-{p.scale_steps} ({p.scale_model}{contrast}{vote})")
    if p.template_weight > 0:
        cells = round(math.sqrt(p.template_area) / p.template_cell)
        kept = f", {p.template_channels} channels" if p.template_channels else ""
        parts.append(f"fHOG correlation filter {p.template_weight:g} (~{cells}x{cells} cells{kept})")
    return parts


def _plus(p: Any) -> str:
    """What a preset adds to the paper's tracker (rcwmil-plus, rcwmil-cf), or ``-``; a preset
    with a network is named by the preset it adds the network to (rcwmil-nano: rcwmil-cf)."""
    if p.network:
        from ..engine.params import VARIANTS

        base = _additions(p.replace(network=""))
        same = next((n for n, q in VARIANTS.items() if not q.network and _additions(q) == base), None)
        every = f", its likeness every {p.likeness_every} frames" if p.likeness_every > 1 else ""
        version = p.network.rsplit("-", 1)[-1]
        return (f"{same or base}'s additions and NanoTrack {version}'s network as a second expert "
                f"under a judge{every}") if same else f"{base}, NanoTrack {version}'s network{every}"
    return _additions(p)


def _additions(p: Any) -> str:
    """The additions column of a preset without a network."""
    parts = _scale_parts(p)
    if p.channels:
        parts.append("channels " + "+".join(p.channels))
    if p.colour_weight > 0:
        parts.append(f"colour {p.colour_weight:g}" + (" (luma on gray)" if p.gray_colour else ""))
    if p.motion != "none":
        parts.append(f"motion {p.motion}")
    if p.score_colour > 0:
        first = " (first frame)" if p.score_colour_model == "first" else ""
        parts.append(f"score colour {p.score_colour:g}{first}")
    if p.score_luma > 0:
        parts.append(f"score luma {p.score_luma:g} (first frame)")
    if p.redetect:
        parts.append("lost state and re-detection")
    return ", ".join(parts) or "-"


#: The cells of the table's columns that are not one parameter's value.
_CELLS: dict[str, Callable[[Any], str]] = {
    "features": lambda p: "sub-region (2x2)" if p.feature_kind == "subregion" else "random rects",
    "rects": lambda p: f"{p.rects_min}-{p.rects_max}",
    "weights": _weights,
    "pos_radius": lambda p: f"d < {p.pos_radius:g}",
    "negatives": _negatives,
    "selection": lambda p: {"wmil": "WMIL gradient", "milboost": "MILBoost (Noisy-OR)",
                            "none": "all features"}[p.selection],
    "instance_weights": _instance_weights,
    "plus": _plus,
    "search": _search,
}


def _cell(p: Any, key: str) -> str:
    """One cell of the variants table: preset ``p``'s column ``key``."""
    if key in _CELLS:
        return _CELLS[key](p)
    value = getattr(p, key)
    return f"{value:g}" if isinstance(value, float) else str(value)


def variant_table() -> str:
    """The defaults of every variant as a markdown table (the README's table)."""
    from ..engine.params import VARIANTS

    head = "| variant | " + " | ".join(title for title, _ in VARIANT_COLUMNS) + " |"
    rule = "|" + "---|" * (len(VARIANT_COLUMNS) + 1)
    rows = [f"| **{name}** | " + " | ".join(_cell(p, key) for _, key in VARIANT_COLUMNS) + " |"
            for name, p in VARIANTS.items()]
    return "\n".join([head, rule, *rows])


def peers_note() -> str:
    """The trackers ``eval``, ``demo`` and ``track`` take besides the presets."""
    from ..integrations.opencv_wheels import OPENCV_TRACKERS
    from ..networks.files import nanotrack_versions

    nano = ", ".join(f"nanotrack:{v}" for v in nanotrack_versions())
    return (f"Besides the presets: {nano} (NanoTrack alone, by its published tracking step; "
            "its model files: `wmiltrack models list`) and opencv:NAME, NAME one of "
            f"{', '.join(OPENCV_TRACKERS)}.")


def runtime_note() -> str:
    """Which runtime would run the networks here (rcwmil-nano, nanotrack:VERSION), and how to
    choose the other."""
    from ..networks.backends import choose_runtime, runtime_version

    chosen = choose_runtime("auto")
    name = "onnxruntime" if chosen == "onnxruntime" else "OpenCV's dnn"
    why = ("onnxruntime is installed" if chosen == "onnxruntime"
           else "onnxruntime (with onnx) is not installed")
    return (f"The networks (rcwmil-nano, nanotrack:VERSION) run on {name} "
            f"{runtime_version(chosen)} here, as {why}; choose with network_runtime=onnxruntime "
            "or =opencv (nanotrack:VERSION:runtime=...). Their boxes are the same for the same "
            "runtime and version only (the two runtimes' boxes differ a little: docs/performance.md).")


def _json_value(value: Any) -> Any:
    """A parameter value JSON has no type for (a tuple is a list already): its text."""
    return str(value)


def _cmd_variants(args: argparse.Namespace) -> int:
    from ..engine.params import VARIANTS

    if args.name and VARIANTS.get(args.name.lower()) is None:
        raise UsageError(f"unknown variant {args.name!r}; choose one of {', '.join(VARIANTS)}")
    if args.json:
        chosen = [args.name.lower()] if args.name else list(VARIANTS)
        doc = {name: VARIANTS[name].as_dict() for name in chosen}
        print(json.dumps(doc, indent=1, default=_json_value))
        return 0
    if args.name:
        p = VARIANTS[args.name.lower()]
        print(p.description)
        for key, value in p.as_dict().items():
            if key != "description":
                print(f"  {key} = {value!r}")
        return 0
    print(variant_table())
    print()
    print(peers_note())
    print()
    print(runtime_note())
    return 0


def add_variants(sub: Subparsers) -> None:
    """Add the ``variants`` subcommand to ``sub``."""
    p = sub.add_parser("variants", help="list the tracker variants and their default parameters",
                       description="Print the variants' defaults as a markdown table, or every "
                       "parameter of one variant.", epilog=EXIT_CODES_EPILOG)
    p.add_argument("name", nargs="?", help="show every parameter of this variant")
    p.add_argument("--json", action="store_true",
                   help="print every parameter (of every variant, or of NAME) as JSON: "
                   "{variant: {parameter: value}}")
    p.set_defaults(func=_cmd_variants)
