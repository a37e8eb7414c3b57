#!/usr/bin/env bash
# `ctest -L container` (tests/deploy/container_farm_test.sh: the images built from a
# debootstrap base without any registry, then a coordinator and two workers as containers,
# byte-compared with pdsm bake). Starts dockerd for the check if none is running (as root;
# deploy/install_deps.sh installs docker.io and debootstrap) and stops it again afterwards.
# About 6 minutes on 2 cores from nothing, most of it the image's Release build.
set -euo pipefail
cd "$(dirname "$0")/.."
docker=docker
[[ -x /usr/bin/docker ]] && docker=/usr/bin/docker  # Debian's docker.io CLI (BuildKit built in)
started=""
if command -v dockerd >/dev/null && ! "$docker" info >/dev/null 2>&1; then
  log=$(mktemp /tmp/pdsm-dockerd.XXXXXX.log)
  dockerd >"$log" 2>&1 &
  started=$!
  for _ in $(seq 150); do "$docker" info >/dev/null 2>&1 && break; sleep 0.2; done
  "$docker" info >/dev/null 2>&1 || { echo "dockerd did not start:"; tail -n 20 "$log"; }
fi
status=0
(cd build && ctest --output-on-failure --timeout 2400 -L container) || status=$?
if [[ -n $started ]]; then
  kill "$started" 2>/dev/null || true
  wait "$started" 2>/dev/null || true
fi
exit "$status"
