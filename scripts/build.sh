#!/usr/bin/env bash
# Installs the Debian packages (idempotent) and builds hairmvs (Release) into ./build: every
# target, or only the targets given as arguments (e.g. `bash scripts/build.sh hairmvs`).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_dependencies.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
if [ "$#" -gt 0 ]; then
  cmake --build build -j"$(nproc)" --target "$@"
else
  cmake --build build -j"$(nproc)"
fi
