#!/usr/bin/env bash
# Installs, builds and runs every test (GoogleTest through CTest, OpenCL tests on PoCL).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
cd build
ctest --output-on-failure -j"$(nproc)" --timeout 900
