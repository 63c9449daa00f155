#!/usr/bin/env bash
# One command from a fresh Debian machine to glasspiv's demo: installs the
# dependencies, builds, and runs `glasspiv demo` on the embedded example.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
./build/apps/glasspiv demo "$@"
