#!/usr/bin/env bash
# CI, after the extras are installed (.ci/run calls this near its end): build the documentation
# site in strict mode, so that a broken link, anchor, image or API reference fails, then run
# every examples/*.py, each in a fresh folder (they write their outputs into the working
# directory). About 20 s on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

echo "== docs: mkdocs build --strict"
python -m pip install --quiet -r docs/requirements.txt
NO_MKDOCS_2_WARNING=1 mkdocs build --strict --site-dir build/site

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for example in examples/*.py; do
    echo "== $example"
    mkdir "$work/$(basename "$example" .py)"
    (cd "$work/$(basename "$example" .py)" && MPLBACKEND=Agg python "$root/$example")
done
