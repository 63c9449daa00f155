#!/usr/bin/env bash
# One command from a fresh Debian machine to a passing test suite: installs the
# dependencies, builds (Release with assertions on) and runs every test with ctest.
# Set GLASSPIV_SANITIZE=ON to build and test with AddressSanitizer and UBSan too.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${GLASSPIV_SANITIZE:-OFF}" = "ON" ]; then
  # clang: it builds this tree under ASan + UBSan in well under half GCC's
  # time. -O1 (the sanitizers need no more), line tables for the reports, no
  # benchmarks.
  bash scripts/install-deps.sh --clang
  GLASSPIV_BUILD_DIR=build-sanitize bash scripts/build.sh -DGLASSPIV_SANITIZE=ON -DGLASSPIV_BUILD_BENCH=OFF \
    -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
    -DCMAKE_CXX_FLAGS_RELEASE="-O1 -gline-tables-only" -DCMAKE_C_FLAGS_RELEASE="-O1 -gline-tables-only"
  ctest --test-dir build-sanitize --output-on-failure --parallel "$(nproc)"
else
  bash scripts/build.sh
  ctest --test-dir build --output-on-failure --parallel "$(nproc)"
fi
