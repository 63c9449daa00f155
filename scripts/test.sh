#!/usr/bin/env bash
# One command from a fresh Debian machine to a passing test suite: installs the
# dependencies, builds (Release with assertions on) and runs every test with ctest.
# Set GLASSPIV_SANITIZE=ON to build and test with AddressSanitizer and UBSan too.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${GLASSPIV_SANITIZE:-OFF}" = "ON" ]; then
  GLASSPIV_BUILD_DIR=build-sanitize bash scripts/build.sh -DGLASSPIV_SANITIZE=ON
  ctest --test-dir build-sanitize --output-on-failure --parallel "$(nproc)"
else
  bash scripts/build.sh
  ctest --test-dir build --output-on-failure --parallel "$(nproc)"
fi
