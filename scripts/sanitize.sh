#!/usr/bin/env bash
# Memory-safety checks of the C++ core (and of the compiled modules in a real tracking run).
#
#   scripts/sanitize.sh [asan] [tsan] [valgrind] [python]      (no argument: all four)
#
#   asan      build the C++ tests with -DWMILTRACK_SANITIZE=ON (AddressSanitizer + UBSan, Eigen
#             asserts on) out of tree in build/sanitize and run them; any report fails.
#   tsan      build the C++ tests with -DWMILTRACK_TSAN=ON (ThreadSanitizer) in build/tsan and
#             run test_threads: writer threads recompute one SharedIntegralImage (the object
#             behind Python's IntegralImage) while reader threads project and score on it;
#             any race report fails.
#   valgrind  build the same tests without sanitizers (and without -march=native: valgrind
#             does not decode AVX-512) in build/memcheck, run them under valgrind memcheck.
#   python    build the extension modules (_core and the Cython _learn) with ASan + UBSan in
#             build/sanitize-py, copy them next to a copy of the Python sources, and run a short
#             tracking run of every variant (plus the awkward geometries and frame layouts of
#             tests/engine/test_reliability.py) with libasan preloaded into the interpreter
#             (LD_PRELOAD, ASAN_OPTIONS=detect_leaks=0: CPython's own allocations are not
#             leaks). The run imports the sanitized modules, never the installed ones.
#
# Needs: cmake, a C++17 compiler with -fsanitize (gcc or clang), the Python that will run the
# tracker on PATH (numpy, pybind11, Cython and opencv as for the package), and Eigen: taken
# from cmeel-eigen in that Python's site-packages, pip-installed there when missing.
# valgrind only for the `valgrind` step. Set JOBS to change build parallelism (default 2).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
PY=${PYTHON:-python}
JOBS=${JOBS:-2}
STEPS=("$@")
[ ${#STEPS[@]} -eq 0 ] && STEPS=(asan tsan valgrind python)

log() { printf '== sanitize: %s\n' "$*"; }

# Configure and build quietly; on failure show the log. Usage: build DIR TARGETS -- CMAKE_ARGS
build() {
  local dir=$1; shift
  local targets=()
  while [ "$1" != "--" ]; do targets+=("$1"); shift; done
  shift
  mkdir -p "$dir"
  if ! { cmake -S . -B "$dir" -DPython_EXECUTABLE="$(command -v "$PY")" "$@" &&
         cmake --build "$dir" --target "${targets[@]}" -j "$JOBS"; } >"$dir/build.log" 2>&1; then
    tail -n 60 "$dir/build.log" >&2
    echo "build in $dir failed (full log: $dir/build.log)" >&2
    return 1
  fi
}

ensure_eigen() {
  # cmeel-eigen in any of the interpreter's site directories (a venv made with
  # --system-site-packages sees the base interpreter's): pip-installed when in none.
  local find_prefix='import os, site, sysconfig
dirs = [sysconfig.get_paths()["purelib"], *site.getsitepackages()]
hits = [os.path.join(d, "cmeel.prefix") for d in dirs
        if os.path.exists(os.path.join(d, "cmeel.prefix/share/eigen3/cmake/Eigen3Config.cmake"))]
print(hits[0] if hits else "")'
  local prefix
  prefix=$("$PY" -c "$find_prefix")
  if [ -z "$prefix" ]; then
    log "Eigen (cmeel-eigen) not in $PY's site-packages: installing it"
    "$PY" -m pip install --quiet cmeel-eigen
    prefix=$("$PY" -c "$find_prefix")
  fi
  export CMAKE_PREFIX_PATH="${prefix}${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
}

# Sanitizer runtime options: stop at the first report with a non-zero exit code.
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
SAN_CXX="-O1 -g -fno-omit-frame-pointer"

run_asan() {
  log "C++ tests under AddressSanitizer + UndefinedBehaviorSanitizer (build/sanitize)"
  build build/sanitize test_core test_cf test_threads -- -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="$SAN_CXX" \
    -DWMILTRACK_BUILD_TESTS=ON -DWMILTRACK_SANITIZE=ON -DWMILTRACK_TSAN=OFF -DWMILTRACK_BUILD_PYTHON=OFF
  local opts="detect_leaks=1:abort_on_error=0:halt_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1"
  ASAN_OPTIONS="$opts" build/sanitize/test_core
  ASAN_OPTIONS="$opts" build/sanitize/test_cf
  ASAN_OPTIONS="$opts" build/sanitize/test_threads
  log "asan: clean"
}

run_tsan() {
  log "threaded C++ test under ThreadSanitizer (build/tsan)"
  build build/tsan test_threads -- -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="$SAN_CXX" \
    -DWMILTRACK_BUILD_TESTS=ON -DWMILTRACK_SANITIZE=OFF -DWMILTRACK_TSAN=ON -DWMILTRACK_BUILD_PYTHON=OFF
  # setarch -R: TSan's shadow memory layout needs the ASLR of older kernels (newer ones map
  # the binary where TSan cannot work: "unexpected memory mapping").
  local run=()
  command -v setarch >/dev/null && run=(setarch "$(uname -m)" -R)
  TSAN_OPTIONS="halt_on_error=1:abort_on_error=0:second_deadlock_stack=1" "${run[@]}" build/tsan/test_threads

  log "the same rules through the Python bindings: _core built with TSan (build/tsan-py)"
  local pybind_dir libtsan site
  # Build requirements that `pip install .` does not leave in the environment (as in CI).
  if ! "$PY" -c "import pybind11, Cython" >/dev/null 2>&1; then
    log "pybind11/Cython not in $PY's environment: installing them"
    "$PY" -m pip install --quiet "pybind11>=2.12" "cython>=3.0"
  fi
  pybind_dir=$("$PY" -c "import pybind11; print(pybind11.get_cmake_dir())")
  build build/tsan-py _core _learn -- -Dpybind11_DIR="$pybind_dir" \
    -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="$SAN_CXX" \
    -DCMAKE_C_FLAGS="-fsanitize=thread -fno-omit-frame-pointer" \
    -DSKBUILD_PROJECT_NAME=wmiltrack -DSKBUILD_PROJECT_VERSION=0.0.0 \
    -DWMILTRACK_BUILD_PYTHON=ON -DWMILTRACK_SANITIZE=OFF -DWMILTRACK_TSAN=ON
  site=build/tsan-py/site
  rm -rf "$site" && mkdir -p "$site/wmiltrack"
  cp -r src/wmiltrack/. "$site/wmiltrack/"
  rm -f "$site"/wmiltrack/*.so
  cp build/tsan-py/_core*.so build/tsan-py/_learn*.so "$site/wmiltrack/"
  libtsan=$(${CXX:-c++} -print-file-name=libtsan.so)
  [ -f "$libtsan" ] || { echo "libtsan.so not found ($libtsan)" >&2; return 1; }
  # The interpreter is not instrumented: TSan sees the core's accesses and the GIL's mutex.
  # Preload into the interpreter itself, not into a wrapper script (a pyenv shim is bash,
  # which crashes under TSan).
  local py_exe
  py_exe=$("$PY" -c "import sys; print(sys.executable)")
  LD_PRELOAD="$libtsan" TSAN_OPTIONS="halt_on_error=1:abort_on_error=0:report_signal_unsafe=0" \
    WMILTRACK_SANITIZED_SITE="$ROOT/$site" WMILTRACK_TESTS="$ROOT/tests/core" "${run[@]}" "$py_exe" - <<'PYEOF'
import os, sys
sys.meta_path = [f for f in sys.meta_path if "editable" not in type(f).__module__.lower()]
sys.path.insert(0, os.environ["WMILTRACK_SANITIZED_SITE"])
sys.path.insert(1, os.environ["WMILTRACK_TESTS"])
import wmiltrack._core
assert wmiltrack._core.__file__.startswith(os.environ["WMILTRACK_SANITIZED_SITE"])
import test_core_hardening as h
for name in ("SHARED_SCRIPT", "MUTATE_SCRIPT", "MULTI_SCRIPT"):
    try:
        exec(compile(getattr(h, name), name, "exec"), {"__name__": "__main__"})
    except SystemExit as e:
        if e.code:
            sys.exit(f"{name} failed")
print("threaded binding scripts: clean")
PYEOF
  log "tsan: clean"
}

run_valgrind() {
  command -v valgrind >/dev/null || { echo "valgrind not installed (apt-get install -y valgrind)" >&2; return 1; }
  log "C++ tests under valgrind memcheck (build/memcheck)"
  build build/memcheck test_core -- -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" \
    -DWMILTRACK_BUILD_TESTS=ON -DWMILTRACK_SANITIZE=OFF -DWMILTRACK_TSAN=OFF -DWMILTRACK_NATIVE=OFF \
    -DWMILTRACK_BUILD_PYTHON=OFF
  valgrind --tool=memcheck --error-exitcode=99 --leak-check=full --show-leak-kinds=definite,indirect \
    --errors-for-leak-kinds=definite,indirect --track-origins=yes -q build/memcheck/test_core
  log "valgrind: clean"
}

run_python() {
  log "tracking run of the sanitized extension modules (build/sanitize-py)"
  local pybind_dir libasan site
  pybind_dir=$("$PY" -c "import pybind11; print(pybind11.get_cmake_dir())")
  build build/sanitize-py _core _learn -- -Dpybind11_DIR="$pybind_dir" \
    -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="$SAN_CXX" \
    -DCMAKE_C_FLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer" \
    -DSKBUILD_PROJECT_NAME=wmiltrack -DSKBUILD_PROJECT_VERSION=0.0.0 \
    -DWMILTRACK_BUILD_PYTHON=ON -DWMILTRACK_SANITIZE=ON -DWMILTRACK_TSAN=OFF
  site=build/sanitize-py/site
  rm -rf "$site" && mkdir -p "$site/wmiltrack"
  # The whole package (it has subpackages: engine/, data/, ...), then the sanitized modules.
  cp -r src/wmiltrack/. "$site/wmiltrack/"
  find "$site/wmiltrack" -name '*.so' -delete
  cp build/sanitize-py/_core*.so build/sanitize-py/_learn*.so "$site/wmiltrack/"
  libasan=$(${CXX:-c++} -print-file-name=libasan.so)
  [ -f "$libasan" ] || { echo "libasan.so not found ($libasan)" >&2; return 1; }
  # detect_leaks=0: the interpreter's own allocations are not ours to report.
  LD_PRELOAD="$libasan" ASAN_OPTIONS="detect_leaks=0:halt_on_error=1:abort_on_error=0" \
    WMILTRACK_SANITIZED_SITE="$ROOT/$site" WMILTRACK_TESTS="$ROOT/tests/engine" "$PY" - <<'PYEOF'
import os, sys, time
# Import the sanitized copy, never the installed package (an editable install's finder
# would otherwise win over sys.path).
sys.meta_path = [f for f in sys.meta_path if "editable" not in type(f).__module__.lower()]
sys.path.insert(0, os.environ["WMILTRACK_SANITIZED_SITE"])
sys.path.insert(1, os.environ["WMILTRACK_TESTS"])
import wmiltrack, wmiltrack._core, wmiltrack._learn
for mod in (wmiltrack._core, wmiltrack._learn):
    assert mod.__file__.startswith(os.environ["WMILTRACK_SANITIZED_SITE"]), mod.__file__
import wmiltrack.data.synthetic
t0 = time.perf_counter()
seq = wmiltrack.data.synthetic.make_preset("all", seed=0, n_frames=40)
frames, gt = seq.load(), seq.groundtruth
n_frames = 0
for v in sorted(wmiltrack.variants()):
    t = wmiltrack.Tracker(v, seed=0)
    t.init(frames[0], tuple(gt[0]))
    for f in frames[1:]:
        t.update(f)
        n_frames += 1
import test_reliability as rel
results = rel.run_cases_in_process()
bad = [r for r in results if r["verdict"]]
for r in bad:
    print("FAILED", r["name"], r["verdict"])
print(f"sanitized run: {n_frames} tracked frames (6 variants), {len(results)} reliability cases, "
      f"{len(bad)} failed, {time.perf_counter() - t0:.1f} s")
sys.exit(1 if bad else 0)
PYEOF
  log "python: clean"
}

for step in "${STEPS[@]}"; do
  case "$step" in
    asan) ensure_eigen; run_asan ;;
    tsan) ensure_eigen; run_tsan ;;
    valgrind) ensure_eigen; run_valgrind ;;
    python) ensure_eigen; run_python ;;
    *) echo "unknown step $step (asan, tsan, valgrind, python)" >&2; exit 2 ;;
  esac
done
