#!/usr/bin/env bash
# The sanitizer pass: installs missing Debian packages, builds rsvio with AddressSanitizer (+ LeakSanitizer)
# and UndefinedBehaviorSanitizer into build-asan/ (or $RSVIO_ASAN_BUILD_DIR) and runs the whole ctest suite
# there. Any sanitizer report makes its test fail (ASan aborts; UBSan does not recover). Leaks inside
# third-party libraries (VTK, Mesa/X, fontconfig) are suppressed by library name in
# scripts/lsan_suppressions.txt; nothing of rsvio's own is suppressed. Mesa's GL driver (*_dri.so), which
# libGL dlopens per X display and unloads with it, is kept loaded in this build (viz/src/vtk_helpers.h,
# keepGlDriverLoaded): unloaded, what its globals held shows up as leaks from "<unknown module>".
# Tests built with RSVIO_SANITIZE may use smaller problem sizes (they say so where they do).
# RSVIO_SANITIZE_TESTS=all (default) runs the whole suite; =ci (what .ci/run uses, to stay within CI's
# time budget) leaves out the long end-to-end tests listed in scripts/sanitize_ci_exclude.txt.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
bash scripts/install_deps.sh
BUILD_DIR=${RSVIO_ASAN_BUILD_DIR:-build-asan}
JOBS=${RSVIO_JOBS:-$(nproc)}
LAUNCHER=()
if command -v ccache >/dev/null 2>&1; then LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
mkdir -p "$BUILD_DIR"
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DRSVIO_SANITIZE=ON -DRSVIO_BUILD_BENCH=OFF "${LAUNCHER[@]}" "$@" \
  > "$BUILD_DIR/cmake.log" 2>&1 || { cat "$BUILD_DIR/cmake.log" >&2; echo "rsvio: cmake configure failed (log above)" >&2; exit 1; }
# The build runs the test executables (gtest discovery), so the sanitizer options apply already.
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:detect_stack_use_after_return=0:strict_string_checks=1:check_initialization_order=1"
export LSAN_OPTIONS="suppressions=$ROOT/scripts/lsan_suppressions.txt:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$ROOT/scripts/ubsan_suppressions.txt"
cmake --build "$BUILD_DIR" -j"$JOBS"
cd "$BUILD_DIR"
EXCLUDE=()
case "${RSVIO_SANITIZE_TESTS:-all}" in
  all) ;;
  ci) EXCLUDE=(-E "^($(grep -v '^#' "$ROOT/scripts/sanitize_ci_exclude.txt" | grep -v '^$' | sed 's/\./\\./g' | paste -sd'|'))\$")
      echo "rsvio: sanitizer pass without the $(grep -cv '^#' "$ROOT/scripts/sanitize_ci_exclude.txt") long tests of scripts/sanitize_ci_exclude.txt" ;;
  *) echo "rsvio: RSVIO_SANITIZE_TESTS must be all or ci, not '${RSVIO_SANITIZE_TESTS}'" >&2; exit 2 ;;
esac
ctest --output-on-failure -j2 --timeout 900 "${EXCLUDE[@]}"
