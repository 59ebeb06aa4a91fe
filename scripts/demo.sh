#!/usr/bin/env bash
# The main-job command of the README: installs missing packages, builds in Release, runs `rsvio demo`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
exec "${RSVIO_BUILD_DIR:-build}/bin/rsvio" demo --out "${1:-out/demo}"
