#!/usr/bin/env bash
# Builds pdsm's container images with no container registry at all: the Debian 12 base image
# is made here from the Debian archive (debootstrap, then `docker import`), and
# deploy/Dockerfile is built on it (its DEBIAN_IMAGE argument), so the only network access is
# to the Debian mirror, as for deploy/install_deps.sh.
#
#   bash deploy/build_images.sh [--tag TAG] [--mirror URL] [--rebuild-base]
#
#   --tag TAG        image tag (default: the project's VERSION from CMakeLists.txt, the tag
#                    deploy/k8s/kustomization.yaml pins)
#   --mirror URL     Debian mirror (default http://deb.debian.org/debian)
#   --rebuild-base   make the base again even if pdsm-base:debian-12 exists
#
# Makes pdsm-base:debian-12, pdsm-coordinator:TAG and pdsm-worker:TAG, and prints their
# sizes and the time each step took. Needs root (debootstrap), debootstrap and a running
# dockerd (Debian: apt-get install debootstrap docker.io). BuildKit is used (DOCKER_BUILDKIT=1)
# for COPY --chmod and deploy/Dockerfile.dockerignore; Debian's docker.io CLI has it built in
# (a newer CLI needs its buildx plugin), so the script uses /usr/bin/docker where it exists
# unless DOCKER names another.
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
tag=$(sed -n 's/^project(pdsm VERSION \([0-9.]*\).*/\1/p' "$repo/CMakeLists.txt")
mirror=http://deb.debian.org/debian
rebuild_base=0
while [[ $# -gt 0 ]]; do
  case $1 in
    --tag) tag=$2; shift 2 ;;
    --mirror) mirror=$2; shift 2 ;;
    --rebuild-base) rebuild_base=1; shift ;;
    *) echo "usage: $0 [--tag TAG] [--mirror URL] [--rebuild-base]" >&2; exit 2 ;;
  esac
done
[[ -n $tag ]] || { echo "$0: no --tag and no VERSION in CMakeLists.txt" >&2; exit 2; }
if [[ -z ${DOCKER:-} ]]; then
  DOCKER=docker
  [[ -x /usr/bin/docker ]] && DOCKER=/usr/bin/docker
fi
docker() { "$DOCKER" "$@"; }
command -v "$DOCKER" >/dev/null || { echo "$0: docker not found (apt-get install docker.io)" >&2; exit 1; }
docker info >/dev/null 2>&1 || { echo "$0: dockerd is not running or not reachable" >&2; exit 1; }

base=pdsm-base:debian-12
seconds() { date +%s; }

if [[ $rebuild_base == 1 ]] || ! docker image inspect "$base" >/dev/null 2>&1; then
  command -v debootstrap >/dev/null || { echo "$0: debootstrap not found (apt-get install debootstrap)" >&2; exit 1; }
  [[ $(id -u) -eq 0 ]] || { echo "$0: debootstrap needs root" >&2; exit 1; }
  root=$(mktemp -d /tmp/pdsm-base.XXXXXX)
  trap 'rm -rf "$root"' EXIT
  start=$(seconds)
  echo "== base: debootstrap bookworm from $mirror"
  debootstrap --variant=minbase bookworm "$root" "$mirror" >"$root.log" 2>&1 ||
    { tail -n 20 "$root.log" >&2; exit 1; }
  # What Debian's official image also does: no apt caches or docs kept in layers.
  rm -rf "$root"/var/cache/apt/archives/*.deb "$root"/var/lib/apt/lists/*
  tar -C "$root" -c . | docker import \
    --change 'ENV PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin' \
    --change 'CMD ["bash"]' - "$base" >/dev/null
  rm -rf "$root" "$root.log"
  trap - EXIT
  echo "== base: $base in $(( $(seconds) - start )) s"
fi

for target in coordinator worker; do
  start=$(seconds)
  echo "== build: pdsm-$target:$tag"
  DOCKER_BUILDKIT=1 docker build --progress=plain -f "$repo/deploy/Dockerfile" \
    --build-arg DEBIAN_IMAGE="$base" --target "$target" -t "pdsm-$target:$tag" "$repo"
  echo "== build: pdsm-$target:$tag in $(( $(seconds) - start )) s"
done
docker image ls --format '{{.Repository}}:{{.Tag}}  {{.Size}}' |
  grep -E "^(pdsm-base:debian-12|pdsm-coordinator:$tag|pdsm-worker:$tag) " || true
