#!/usr/bin/env bash
# Configure, build (out of tree, in build/bench) and run the C++ microbenchmarks.
#   benchmarks/cpp/run.sh [--quick] [--reps N] [--frame-only] [--fhog-only]
# Needs cmake, a C++17 compiler and a Python with Eigen from PyPI (cmeel-eigen, installed
# into the active environment if missing).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
build="$root/build/bench"
py="${PYTHON:-python3}"

if ! "$py" -c "import cmeel_eigen" >/dev/null 2>&1 && ! "$py" -m pip show cmeel-eigen >/dev/null 2>&1; then
  echo "cmeel-eigen not found: pip install cmeel-eigen" >&2
  "$py" -m pip install cmeel-eigen
fi
purelib="$("$py" -c "import sysconfig; print(sysconfig.get_paths()['purelib'])")"

mkdir -p "$build"
log="$build/build.log"
# SKBUILD_PROJECT_* are what scikit-build-core passes to the top-level project() call.
if ! { cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release \
         -DSKBUILD_PROJECT_NAME=wmiltrack -DSKBUILD_PROJECT_VERSION=0.1.0 \
         -DWMILTRACK_BUILD_BENCHMARKS=ON -DWMILTRACK_BUILD_PYTHON=OFF \
         -DPython_EXECUTABLE="$(command -v "$py")" \
         -DCMAKE_PREFIX_PATH="$purelib/cmeel.prefix" &&
       cmake --build "$build" --target bench_core -j 2; } >"$log" 2>&1; then
  cat "$log" >&2
  echo "build failed (log: $log)" >&2
  exit 1
fi
echo "# wmiltrack C++ core microbenchmarks ($(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | cut -d: -f2 | sed 's/^ //'), $(nproc 2>/dev/null || echo '?') cores)"
"$build/benchmarks/cpp/bench_core" "$@"
