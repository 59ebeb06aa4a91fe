#!/usr/bin/env bash
# The test command of the README: installs missing packages, builds in Release, runs the whole suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
cd "${RSVIO_BUILD_DIR:-build}"
ctest --output-on-failure -j2 --timeout 600
