#!/usr/bin/env bash
# The container images, built and run for real (issue #13): deploy/build_images.sh makes the
# Debian 12 base with debootstrap and builds deploy/Dockerfile on it (no registry), then a
# coordinator and two workers run as containers on a private Docker network, with the
# coordinator published on 127.0.0.1 only. A bake submitted from this machine must equal, byte
# for byte, `pdsm bake` of the same scene run both inside the image and with this build's
# binary; `docker stop` must let each worker hand back and exit 0.
# Exit 77 (ctest: skipped), with the reason, where docker, dockerd or debootstrap is missing;
# exit 1 on any failed check.
#
#   container_farm_test.sh REPO PDSM SCENE
set -euo pipefail

if [[ $# -ne 3 ]]; then
  echo "usage: $0 REPO PDSM SCENE" >&2
  exit 2
fi
repo=$(realpath "$1") pdsm=$(realpath "$2") scene=$(realpath "$3")

skip() { echo "SKIPPED: $*" >&2; exit 77; }
fail() { echo "FAILED: $*" >&2; exit 1; }

DOCKER=${DOCKER:-docker}
[[ $DOCKER == docker && -x /usr/bin/docker ]] && DOCKER=/usr/bin/docker  # Debian's docker.io
export DOCKER
docker() { "$DOCKER" "$@"; }
command -v "$DOCKER" >/dev/null || skip "docker not found (apt-get install docker.io)"
docker info >/dev/null 2>&1 || skip "dockerd is not running (as root: dockerd &)"
command -v debootstrap >/dev/null || skip "debootstrap not found (apt-get install debootstrap)"

tag=$(sed -n 's/^project(pdsm VERSION \([0-9.]*\).*/\1/p' "$repo/CMakeLists.txt")
echo "== building the images (deploy/build_images.sh --tag $tag)"
build_log=$(mktemp /tmp/pdsm-image-build.XXXXXX.log)
if ! bash "$repo/deploy/build_images.sh" --tag "$tag" >"$build_log" 2>&1; then
  tail -n 60 "$build_log" >&2
  rm -f "$build_log"
  fail "deploy/build_images.sh failed"
fi
grep '^== ' "$build_log"
rm -f "$build_log"
docker image ls --format '{{.Repository}}:{{.Tag}} {{.Size}}' |
  grep -E "^(pdsm-base:debian-12|pdsm-(coordinator|worker):$tag) "

run_id=pdsm-test-$$
work=$(mktemp -d /tmp/pdsm-container-test.XXXXXX)
cleanup() {
  local status=$?
  if [[ $status -ne 0 && $status -ne 77 ]]; then
    for c in "$run_id-coordinator" "$run_id-worker-0" "$run_id-worker-1"; do
      echo "--- docker logs $c"; docker logs --tail 30 "$c" 2>&1 || true
    done
  fi
  docker rm -f "$run_id-coordinator" "$run_id-worker-0" "$run_id-worker-1" >/dev/null 2>&1 || true
  docker network rm "$run_id" >/dev/null 2>&1 || true
  rm -rf "$work"
  exit "$status"
}
trap cleanup EXIT

# Tokens as the compose file mounts them: world-readable files in a private folder (the
# containers run as uid 10001).
mkdir -p "$work/secrets" "$work/out"
chmod 0700 "$work"
for name in client_token worker_token; do printf '%s-%s\n' "$name" "$RANDOM$RANDOM$RANDOM" >"$work/secrets/$name"; done
chmod 0755 "$work/secrets" && chmod 0644 "$work/secrets"/*
chmod 0777 "$work/out"
cp "$scene" "$work/out/scene.json"
chmod 0644 "$work/out/scene.json"

docker network create "$run_id" >/dev/null
docker run -d --name "$run_id-coordinator" --network "$run_id" -p 127.0.0.1::50051 \
  -v "$work/secrets:/run/secrets:ro" "pdsm-coordinator:$tag" \
  --listen 0.0.0.0:50051 --data-dir /data --client-token-file /run/secrets/client_token \
  --worker-token-file /run/secrets/worker_token >/dev/null
for i in 0 1; do
  docker run -d --name "$run_id-worker-$i" --network "$run_id" \
    -v "$work/secrets:/run/secrets:ro" "pdsm-worker:$tag" \
    --coordinator "$run_id-coordinator:50051" --token-file /run/secrets/worker_token \
    --threads 1 --cache-dir /cache >/dev/null
done
address=$(docker port "$run_id-coordinator" 50051/tcp | grep -m1 '^127\.0\.0\.1:')
[[ -n $address ]] || fail "the coordinator's port is not published on 127.0.0.1"
client=(--server "$address" --token-file "$work/secrets/client_token")
for _ in $(seq 100); do "$pdsm" stats "${client[@]}" >/dev/null 2>&1 && break; sleep 0.2; done

bake=(--resolution 128x128 --samples 32 --sm-resolution 512 --tile-size 32)
job=$("$pdsm" submit "$work/out/scene.json" "${bake[@]}" "${client[@]}" | tail -n 1)
echo "== job $job on two worker containers"
state=""
for _ in $(seq 900); do
  state=$("$pdsm" status "$job" --json "${client[@]}" |
    /usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)["state"])')
  [[ $state == SUCCEEDED || $state == FAILED || $state == CANCELLED ]] && break
  sleep 0.2
done
[[ $state == SUCCEEDED ]] || fail "job $job ended $state"
"$pdsm" fetch "$job" -o "$work/farm.exr" "${client[@]}" >/dev/null

docker run --rm --entrypoint pdsm -v "$work/out:/w" "pdsm-coordinator:$tag" \
  bake /w/scene.json "${bake[@]}" -o /w/image_local.exr --threads 2 --no-preview >/dev/null 2>&1 ||
  fail "pdsm bake inside the image failed"
"$pdsm" bake "$work/out/scene.json" "${bake[@]}" -o "$work/host_local.exr" --threads 2 \
  --no-preview >/dev/null 2>&1 || fail "pdsm bake failed"
cmp "$work/farm.exr" "$work/out/image_local.exr" || fail "the container farm's PDSM differs from pdsm bake in the image"
cmp "$work/farm.exr" "$work/host_local.exr" || fail "the container farm's PDSM differs from this build's pdsm bake"
echo "== bytes equal: farm, image's pdsm bake and this build's pdsm bake ($(stat -c %s "$work/farm.exr") bytes)"

for i in 0 1; do
  docker stop -t 60 "$run_id-worker-$i" >/dev/null
  code=$(docker inspect -f '{{.State.ExitCode}}' "$run_id-worker-$i")
  [[ $code == 0 ]] || fail "worker $i exited $code after docker stop"
done
docker stop -t 60 "$run_id-coordinator" >/dev/null
code=$(docker inspect -f '{{.State.ExitCode}}' "$run_id-coordinator")
[[ $code == 0 ]] || fail "the coordinator exited $code after docker stop"
echo "== docker stop: workers and coordinator exited 0"
echo "PASSED"
