"""Make a VOT toolkit workspace from shared OTB-layout sequences (no download).

    python scripts/vot/make_workspace.py WORKSPACE [--otb ../shared/data/otb]
        [--sequences Crossing,vot15_bag] [--python /path/to/python] [--variants rcwmil,ct]

Writes ``WORKSPACE/config.yaml`` (stack: scripts/vot/stack.yaml), ``trackers.ini`` (one
``wmiltrack_<variant>`` entry per variant, served by ``<python> -m wmiltrack.vot``) and
``sequences/<name>/`` in the VOT layout: ``sequence`` (metadata), ``color/%08d.jpg`` (symbolic
links to the shared images) and ``groundtruth.txt`` (the sequence's own VOT polygons when it
has them, else its OTB rectangles), plus ``sequences/list.txt``, whose presence stops the
toolkit from downloading anything.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def convert(src: Path, dst: Path) -> int:
    images = sorted(p for p in (src / "img").iterdir() if p.suffix.lower() in (".jpg", ".jpeg"))
    rect_lines = [ln.strip() for ln in (src / "groundtruth_rect.txt").read_text().splitlines() if ln.strip()]
    vot_gt = src / "groundtruth.txt"
    lines = ([ln.strip() for ln in vot_gt.read_text().splitlines() if ln.strip()] if vot_gt.is_file()
             else [",".join(ln.replace("\t", ",").replace(" ", ",").split(",")) for ln in rect_lines])
    n = min(len(images), len(lines))
    (dst / "color").mkdir(parents=True, exist_ok=True)
    for i, img in enumerate(images[:n], start=1):
        link = dst / "color" / f"{i:08d}.jpg"
        if link.is_symlink() or link.exists():
            link.unlink()
        link.symlink_to(img.resolve())
    (dst / "groundtruth.txt").write_text("\n".join(lines[:n]) + "\n")
    (dst / "sequence").write_text("channels.color=color/%08d.jpg\nformat=default\nfps=30\n")
    return n


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("workspace", type=Path)
    ap.add_argument("--otb", type=Path, default=Path("../shared/data/otb"))
    ap.add_argument("--sequences", default="Crossing,vot15_bag")
    ap.add_argument("--python", default=sys.executable,
                    help="interpreter with wmiltrack and vot-trax (default: this one)")
    ap.add_argument("--variants", default="rcwmil")
    args = ap.parse_args()
    ws = args.workspace.resolve()
    seq_root = ws / "sequences"
    seq_root.mkdir(parents=True, exist_ok=True)
    names = [s.strip() for s in args.sequences.split(",") if s.strip()]
    for name in names:
        n = convert(args.otb / name, seq_root / name)
        print(f"{name}: {n} frames", file=sys.stderr)
    (seq_root / "list.txt").write_text("\n".join(names) + "\n")
    (ws / "config.yaml").write_text(f"registry:\n- ./trackers.ini\nstack: {HERE / 'stack.yaml'}\n")
    entries = []
    for v in args.variants.split(","):
        v = v.strip()
        entries.append(f"[wmiltrack_{v}]\nlabel = wmiltrack_{v}\nprotocol = traxpython\n"
                       f"command = wmiltrack.vot\npython = {args.python}\nenv_WMILTRACK_VARIANT = {v}\n")
    (ws / "trackers.ini").write_text("\n".join(entries))
    return 0


if __name__ == "__main__":
    sys.exit(main())
