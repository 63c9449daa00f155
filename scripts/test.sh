#!/usr/bin/env bash
# One command from a fresh Debian machine to a passing test suite: installs the
# dependencies, builds (Release with assertions on) and runs every test with ctest.
# Set GLASSPIV_SANITIZE=ON to build and test with AddressSanitizer and UBSan
# instead (scripts/sanitize-options.sh); GLASSPIV_SANITIZE_SCOPE=core there
# builds and runs only the tests labelled core (tests/CMakeLists.txt), as CI does.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${GLASSPIV_SANITIZE:-OFF}" = "ON" ]; then
  bash scripts/install-deps.sh --clang
  source scripts/sanitize-options.sh
  target="" labels=()
  if [ "${GLASSPIV_SANITIZE_SCOPE:-all}" = "core" ]; then target=core_tests labels=(-L '^core$'); fi
  GLASSPIV_BUILD_DIR="$sanitize_build_dir" GLASSPIV_BUILD_TARGET="$target" bash scripts/build.sh "${sanitize_options[@]}"
  ctest --test-dir "$sanitize_build_dir" --output-on-failure --parallel "$(nproc)" "${labels[@]}"
else
  bash scripts/build.sh
  ctest --test-dir build --output-on-failure --parallel "$(nproc)"
fi
