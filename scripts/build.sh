#!/usr/bin/env bash
# Configures and builds glasspiv (Release, assertions kept on) into build/.
# Usage: scripts/build.sh [extra cmake -D options...]
# GLASSPIV_BUILD_DIR (default build), GLASSPIV_BUILD_TARGET (targets separated
# by spaces; default all).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
build_dir="${GLASSPIV_BUILD_DIR:-build}"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "$@"
target=()
if [ -n "${GLASSPIV_BUILD_TARGET:-}" ]; then read -ra names <<<"$GLASSPIV_BUILD_TARGET"; target=(--target "${names[@]}"); fi
cmake --build "$build_dir" --parallel "$(nproc)" "${target[@]}"
