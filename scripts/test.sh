#!/usr/bin/env bash
# The whole test suite, from a fresh Debian 12 machine: install dependencies, build, run ctest;
# then the sanitizer and fuzz jobs (scripts/sanitize.sh, docs/sanitizers.md), unless
# PDSM_SANITIZERS=0.
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/install_deps.sh
bash scripts/build.sh
(cd build && ctest --output-on-failure -j 2 --timeout 900)
if [[ "${PDSM_SANITIZERS:-1}" != 0 ]]; then
  bash scripts/sanitize.sh asan tsan fuzz
fi
