#!/usr/bin/env bash
# The whole test suite, from a fresh Debian 12 machine: install dependencies, build, run ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/install_deps.sh
bash scripts/build.sh
cd build
ctest --output-on-failure -j 2 --timeout 900
