#!/usr/bin/env bash
# Installs the Debian packages glasspiv builds against. Idempotent: packages
# already present are not touched, and apt is only called when one is missing.
# Usage: scripts/install-deps.sh [--clang]   (--clang: also clang 14 and its
# sanitizer runtimes, for the sanitizer and fuzzing builds)
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config ccache
  libeigen3-dev libopencv-dev libopencv-contrib-dev libapriltag-dev
  libceres-dev libmrcal-dev python3-mrcal python3-numpy
  libyaml-cpp-dev libcli11-dev libfmt-dev nlohmann-json3-dev libpugixml-dev
  libcairo2-dev libpoppler-cpp-dev  # PDF targets; poppler reads them back in the tests
  libgtest-dev libgmock-dev libtbb-dev
  libembree-dev libopenimageio-dev libassimp-dev libvtk9-dev
)
if [ "${1:-}" = "--clang" ]; then packages+=(clang-14 libclang-rt-14-dev); fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
