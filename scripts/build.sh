#!/usr/bin/env bash
# Installs the Debian packages (idempotent) and builds hairmvs (Release) into ./build.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_dependencies.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
