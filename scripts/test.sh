#!/usr/bin/env bash
# Installs the dependencies, builds everything (Release) and runs the whole
# test suite with ctest. The second Quick start command and CI's entry point.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)"
