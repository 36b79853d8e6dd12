#!/usr/bin/env bash
# Run the VOT toolkit (0.7.4, in its own venv) on wmiltrack, offline, on a workspace made from
# two shared OTB-layout sequences; print the summary and draw the EAO curves.
#   bash scripts/vot/run.sh [WORKSPACE]      (default results/vot-workspace)
# Env: WMILTRACK_PYTHON  interpreter with wmiltrack and vot-trax (default: python on PATH)
#      VOT_VENV          venv for the toolkit (default build/vot-venv; created when missing)
#      WMILTRACK_OTB     shared sequences (default ../shared/data/otb)
set -euo pipefail
REPO="$(cd "$(dirname "$0")/../.." && pwd)"
PY="${WMILTRACK_PYTHON:-$(command -v python)}"
VENV="${VOT_VENV:-$REPO/build/vot-venv}"
WS="$(mkdir -p "${1:-$REPO/results/vot-workspace}" && cd "${1:-$REPO/results/vot-workspace}" && pwd)"
OTB="${WMILTRACK_OTB:-$REPO/../shared/data/otb}"
TRACKERS="wmiltrack_rcwmil wmiltrack_ct"

if [ ! -x "$VENV/bin/vot" ]; then
  # vot-toolkit declares opencv-python (GUI build); it only needs cv2, so the headless wheel
  # goes in instead. attributee 0.1.9: the version 0.7.4 works with.
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet --no-deps vot-toolkit==0.7.4 attributee==0.1.9
  "$VENV/bin/pip" install --quiet PyLaTeX PyYAML bidict cachetools colorama dominate jsonschema \
    lazy-object-proxy numba numpy ordered-set phx-class-registry pillow requests six tqdm \
    vot-trax matplotlib opencv-python-headless
fi
"$PY" -c "import wmiltrack.vot, trax" || { echo "install wmiltrack with vot-trax into $PY first" >&2; exit 1; }

"$PY" "$REPO/scripts/vot/make_workspace.py" "$WS" --otb "$OTB" --python "$PY" --variants rcwmil,ct
cd "$WS"
# shellcheck disable=SC2086
"$VENV/bin/vot" evaluate --workspace "$WS" $TRACKERS
# shellcheck disable=SC2086
"$VENV/bin/vot" analysis --workspace "$WS" --name summary $TRACKERS
"$PY" "$REPO/scripts/vot/summarize.py" "$WS/analysis/summary.json" --plot "$WS/eao.png"
echo "EAO plot: $WS/eao.png"
