#!/usr/bin/env bash
# The three code paths a build of the core can take give the same boxes and scores: the AVX2
# copies and the SSE2 baseline copies of the installed package (switched at run time with
# _core.set_simd_portable), and a scalar build (WMILTRACK_NO_SIMD: one value at a time, built
# here out of tree in build/scalar-py, like scripts/sanitize.sh builds its variants).
#
#   scripts/simd_paths.sh
#
# Every paper preset, rcwmil-plus and rcwmil-cf run 40 frames of a generated sequence on each path, and
# the correlation filters' features (gray patches, fHOG, scale samples) are computed on a few
# of its frames; tests/simd_paths_check.py compares the three runs and fails on any difference. Needs what
# scripts/sanitize.sh needs (cmake, a C++17 compiler, pybind11, Cython, cmeel-eigen in $PYTHON).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
PY=${PYTHON:-python}
JOBS=${JOBS:-2}
dir=build/scalar-py
mkdir -p "$dir"
# Build requirements that `pip install .` does not leave in the environment (as in CI).
if ! "$PY" -c "import pybind11, Cython" >/dev/null 2>&1; then
  echo "simd_paths: installing the build requirements pybind11 and Cython into $PY's environment"
  "$PY" -m pip install --quiet "pybind11>=2.12" "cython>=3.0"
fi
prefix=$("$PY" -c 'import os, sysconfig; print(os.path.join(sysconfig.get_paths()["purelib"], "cmeel.prefix"))')
if [ ! -f "$prefix/share/eigen3/cmake/Eigen3Config.cmake" ]; then
  echo "simd_paths: installing cmeel-eigen (Eigen headers) into $PY's environment"
  "$PY" -m pip install --quiet "cmeel-eigen>=3.4"
fi
pybind_dir=$("$PY" -c "import pybind11; print(pybind11.get_cmake_dir())")
if ! { cmake -S . -B "$dir" -DPython_EXECUTABLE="$(command -v "$PY")" -DCMAKE_BUILD_TYPE=Release \
         -DCMAKE_PREFIX_PATH="$prefix" -Dpybind11_DIR="$pybind_dir" \
         -DCMAKE_CXX_FLAGS="-DWMILTRACK_NO_SIMD" \
         -DSKBUILD_PROJECT_NAME=wmiltrack -DSKBUILD_PROJECT_VERSION=0.0.0 \
         -DWMILTRACK_BUILD_PYTHON=ON &&
       cmake --build "$dir" --target _core _learn -j "$JOBS"; } >"$dir/build.log" 2>&1; then
  tail -n 60 "$dir/build.log" >&2
  echo "scalar build failed (full log: $dir/build.log)" >&2
  exit 1
fi
site=$dir/site
rm -rf "$site" && mkdir -p "$site/wmiltrack"
cp -r src/wmiltrack/. "$site/wmiltrack/"
find "$site/wmiltrack" -name '*.so' -delete
cp "$dir"/_core*.so "$dir"/_learn*.so "$site/wmiltrack/"
out=$dir/runs
mkdir -p "$out"
# The installed package on its AVX2 and SSE2 paths, then the scalar copy.
"$PY" tests/simd_paths_check.py run "$out/native.json"
WMILTRACK_SANITIZED_SITE="$ROOT/$site" "$PY" tests/simd_paths_check.py run "$out/scalar.json"
"$PY" tests/simd_paths_check.py compare "$out/native.json" "$out/scalar.json"
