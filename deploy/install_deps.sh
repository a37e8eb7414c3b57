#!/usr/bin/env bash
# Installs every build, test and runtime dependency of pdsm from Debian 12's archive.
# Run as root on a fresh Debian 12 (bookworm) machine. Idempotent.
set -euo pipefail

# What building the binaries needs (the container image's build stage installs only this:
# `install_deps.sh --build-only`).
packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config git ca-certificates
  # RPC and schema: the scene is a protobuf message read with its JSON mapping
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc libabsl-dev
  # math, rendering, files
  libglm-dev libosmesa6-dev libgl-dev libopenexr-dev openexr libpng-dev
  # meshes, flags, logs
  libassimp-dev libcli11-dev libspdlog-dev libfmt-dev
  # exact polygon clipping for the reference, job state
  libboost-dev libsqlite3-dev libssl-dev
  # TLS certificates (deploy/make_secrets.sh, the service tests)
  openssl
  # pdsm-view's window; Embree occlusion rays for `pdsm reference`
  libglfw3-dev libembree-dev
  # the services' Prometheus /metrics endpoint (metrics/metrics_http_server.h)
  libcpp-httplib-dev
  # the Python module for tools (python/): pybind11 and the interpreter's headers
  pybind11-dev python3-dev
)
# What the test suite needs on top.
test_packages=(
  libgtest-dev libgmock-dev
  # clang: the thread-safety analysis test (scripts/check_thread_safety.py); clang-format:
  # the format check (tests/CMakeLists.txt); clang's sanitizer and libFuzzer runtimes and
  # llvm-symbolizer for the sanitizer and fuzz jobs (scripts/sanitize.sh)
  clang clang-format libclang-rt-14-dev llvm
  # the windowed pdsm-view test runs under a virtual X server; sweep.png is drawn by gnuplot
  xvfb xauth gnuplot-nox
  # tests/deploy/check_manifests.py: parses the deployment manifests; the Python module's
  # test and its docs example (numpy arrays, a matplotlib plot)
  python3 python3-yaml python3-numpy python3-matplotlib
  # the Slurm farm test (tests/deploy/slurm_farm_test.sh) starts its own munged, slurmctld
  # and slurmd on loopback; nothing of the packages' own configuration is used
  slurm-wlm munge
  # the container check (scripts/container_check.sh): a Debian base made with debootstrap,
  # the images built and run by Debian's Docker
  docker.io debootstrap
)
if [[ ${1:-} == --build-only ]]; then
  test_packages=()
elif [[ $# -gt 0 ]]; then
  echo "usage: $0 [--build-only]" >&2
  exit 2
fi

# Opt-in, never by default nor in CI: Blender (Cycles) for the benchmark that anchors pdsm to a
# path tracer (bench/cycles_compare.py; docs/accuracy.md, "An independent anchor").
if [[ "${PDSM_WITH_BLENDER:-0}" == 1 ]]; then
  test_packages+=(blender)
fi

export DEBIAN_FRONTEND=noninteractive
if [[ "${PDSM_SKIP_APT_UPDATE:-0}" != 1 ]]; then
  apt-get update -q
fi
apt-get install -y -q --no-install-recommends "${packages[@]}" "${test_packages[@]}"
