#!/usr/bin/env bash
# Configures and builds rsvio in Release into ./build (or $RSVIO_BUILD_DIR).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${RSVIO_BUILD_DIR:-build}
JOBS=${RSVIO_JOBS:-$(nproc)}
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release "$@" > "$BUILD_DIR.cmake.log" 2>&1 || {
  cat "$BUILD_DIR.cmake.log" >&2; echo "rsvio: cmake configure failed (log above)" >&2; exit 1; }
cmake --build "$BUILD_DIR" -j"$JOBS"
