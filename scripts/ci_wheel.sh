#!/usr/bin/env bash
# The wheel as a user gets it:
#   1. `python -m build` makes the sdist, then the wheel from that sdist (so the sdist is proven
#      to hold everything a build needs), in a throw-away tool venv;
#   2. the wheel is installed (`--only-binary=:all:`) into a fresh virtual environment, with a
#      PATH holding only that venv's bin/ and an empty folder, CC/CXX and friends unset, after
#      checking that no compiler, linker or build tool can be found that way;
#   3. the wheel's smoke tests - the same [tool.cibuildwheel] test-sources, test-requires and
#      test-command that cibuildwheel runs, read from pyproject.toml - run from a temporary
#      folder outside the source tree, and the imported modules are checked to come from the
#      fresh venv.
#
#   scripts/ci_wheel.sh            (PYTHON=python3.12 scripts/ci_wheel.sh for another Python)
#
# The wheel is this machine's (linux_x86_64 tag, not repaired by auditwheel); the manylinux and
# macOS wheels come from cibuildwheel with the same tests.  About 2 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
src="$(pwd)"
PYTHON="${PYTHON:-python3}"
work="$(mktemp -d "${TMPDIR:-/tmp}/wmiltrack-wheel.XXXXXX")"
trap 'rm -rf "$work"' EXIT

echo "== ci_wheel: sdist, then the wheel built from it (python -m build)"
"$PYTHON" -m venv "$work/tools"
"$work/tools/bin/python" -m pip install --quiet --upgrade pip build
"$work/tools/bin/python" -m build --outdir "$work/dist" . >"$work/build.log" 2>&1 \
  || { tail -n 40 "$work/build.log"; echo "ci_wheel: python -m build failed"; exit 1; }
sdist=("$work"/dist/*.tar.gz)
wheel=("$work"/dist/*.whl)
[ "${#sdist[@]}" -eq 1 ] && [ -f "${sdist[0]}" ] && [ "${#wheel[@]}" -eq 1 ] && [ -f "${wheel[0]}" ] \
  || { echo "ci_wheel: expected one sdist and one wheel in $work/dist"; ls -l "$work/dist"; exit 1; }
echo "built $(basename "${sdist[0]}") and $(basename "${wheel[0]}")"

# The sdist holds the build's inputs; the wheel holds both compiled modules and no C++ source.
tar -tzf "${sdist[0]}" | sed 's|^[^/]*/||' >"$work/sdist.txt"
need=(pyproject.toml CMakeLists.txt README.md cpp/include/ cpp/src/ cpp/bindings/
      src/wmiltrack/__init__.py src/wmiltrack/_learn.pyx src/wmiltrack/py.typed)
[ -f LICENSE ] && need+=(LICENSE)
for f in "${need[@]}"; do
  grep -q "^$f" "$work/sdist.txt" || { echo "ci_wheel: the sdist lacks $f"; exit 1; }
done
"$work/tools/bin/python" - "${wheel[0]}" "$src" <<'EOF'
import sys, zipfile
from pathlib import Path

names = zipfile.ZipFile(sys.argv[1]).namelist()
exts = {n.split("/")[-1].split(".")[0] for n in names if n.endswith((".so", ".pyd"))}
assert {"_core", "_learn"} <= exts, f"compiled modules in the wheel: {sorted(exts)}"
assert not [n for n in names if n.endswith((".cpp", ".h", ".hpp"))], "C++ sources in the wheel"
assert any(n.endswith("py.typed") for n in names), "py.typed missing from the wheel"
if (Path(sys.argv[2]) / "LICENSE").is_file():
    assert any(n.endswith(".dist-info/licenses/LICENSE") or n.endswith(".dist-info/LICENSE") for n in names), \
        "LICENSE missing from the wheel's metadata"
print(f"wheel: {len(names)} files, compiled modules {sorted(exts)}")
EOF

echo "== ci_wheel: fresh venv, no compiler on PATH, install the wheel (binary only)"
"$PYTHON" -m venv "$work/venv"
mkdir "$work/empty"
nocc_path="$work/venv/bin:$work/empty"
# Run with only the venv's bin/ (and an empty folder) on PATH and no compiler variables.
nocc() {
  env -u CC -u CXX -u CPP -u LD -u CMAKE -u CMAKE_C_COMPILER -u CMAKE_CXX_COMPILER \
      -u CMAKE_GENERATOR -u CMAKE_MAKE_PROGRAM -u PYTHONPATH -u VIRTUAL_ENV PATH="$nocc_path" "$@"
}
check_no_compiler() {
  local tool found=""
  for tool in cc c++ gcc g++ clang clang++ ld cmake ninja make; do
    if nocc "$work/venv/bin/python" -c "import shutil, sys; sys.exit(shutil.which('$tool') is None)"; then
      found+=" $tool"
    fi
  done
  [ -z "$found" ] || { echo "ci_wheel: found on the restricted PATH:$found"; exit 1; }
}
check_no_compiler
nocc "$work/venv/bin/python" -m pip install --quiet --only-binary=:all: "${wheel[0]}"
check_no_compiler  # nothing installed brought a compiler or build tool along

echo "== ci_wheel: smoke tests from outside the source tree ([tool.cibuildwheel] test-command)"
mkdir "$work/smoke"
"$work/tools/bin/python" - "$src/pyproject.toml" "$work/smoke" "$work/requires.txt" "$work/commands" <<'EOF'
import shutil, sys, tomllib
from pathlib import Path

cfg = tomllib.loads(Path(sys.argv[1]).read_text())["tool"]["cibuildwheel"]
root, dest = Path(sys.argv[1]).parent, Path(sys.argv[2])
for rel in cfg.get("test-sources", []):
    (dest / rel).parent.mkdir(parents=True, exist_ok=True)
    (shutil.copytree if (root / rel).is_dir() else shutil.copy2)(root / rel, dest / rel)
Path(sys.argv[3]).write_text("".join(f"{r}\n" for r in cfg.get("test-requires", [])))
cmds = cfg["test-command"]
Path(sys.argv[4]).write_text("\0".join([cmds] if isinstance(cmds, str) else cmds) + "\0")
EOF
if [ -s "$work/requires.txt" ]; then
  nocc "$work/venv/bin/python" -m pip install --quiet --only-binary=:all: -r "$work/requires.txt"
fi
cd "$work/smoke"
nocc python - "$src" <<'EOF'
import importlib, sys
from pathlib import Path

venv, source = Path(sys.prefix).resolve(), Path(sys.argv[1]).resolve()
for name in ("wmiltrack", "wmiltrack._core", "wmiltrack._learn"):
    path = Path(importlib.import_module(name).__file__).resolve()
    assert path.is_relative_to(venv) and not path.is_relative_to(source), f"{name} from {path}"
print(f"imported wmiltrack, _core and _learn from {venv}")
EOF
while IFS= read -r -d '' cmd; do
  echo "\$ $cmd"
  nocc "$BASH" -c "$cmd"   # as cibuildwheel, through a shell; bash by its absolute path
done <"$work/commands"
echo "== ci_wheel: ok"
