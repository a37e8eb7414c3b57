#!/usr/bin/env bash
# Configures and builds pdsm into ./build (Release with line tables). Idempotent.
# -g1 (line tables and function names, enough for backtraces and perf) instead of CMake's
# full -g: the same code, and 24 % less compile CPU (medians of 6 compiles of 3 of the
# heaviest translation units, gcc 12: -g 22.3 s, -g1 17.0 s), which CI pays on every run.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG"
cmake --build build -j "$(nproc)"
