#!/usr/bin/env bash
# Installs the Debian 12 packages rsvio needs, only those missing (apt-get update once, then install).
# Run as root (or with sudo available). Nothing is downloaded besides Debian packages.
set -euo pipefail
PKGS=(build-essential cmake pkg-config libeigen3-dev libopencv-dev libsuitesparse-dev libvtk9-dev xvfb xauth
      nlohmann-json3-dev libcli11-dev libyaml-cpp-dev libgtest-dev libgmock-dev libbenchmark-dev
      libpng-dev libjpeg62-turbo-dev)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "rsvio: all Debian packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO=sudo; else
    echo "rsvio: missing packages (${missing[*]}) and not root; run as root or install them" >&2; exit 1
  fi
fi
echo "rsvio: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
