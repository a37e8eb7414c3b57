#!/usr/bin/env bash
# The whole test suite, from a fresh Debian 12 machine: install dependencies, build, run ctest;
# then the sanitizer and fuzz jobs (scripts/sanitize.sh, docs/sanitizers.md), unless
# PDSM_SANITIZERS=0; then the container images built and run for real
# (scripts/container_check.sh, `ctest -L container`), unless PDSM_CONTAINER_CHECK=0.
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/install_deps.sh
bash scripts/build.sh
(cd build && ctest --output-on-failure -j 2 --timeout 900 -LE container)
if [[ "${PDSM_SANITIZERS:-1}" != 0 ]]; then
  bash scripts/sanitize.sh asan tsan fuzz
fi
if [[ "${PDSM_CONTAINER_CHECK:-1}" != 0 ]]; then
  bash scripts/container_check.sh
fi
