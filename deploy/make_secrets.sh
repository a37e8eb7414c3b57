#!/usr/bin/env bash
# Generates the three bearer tokens pdsm uses, as one-line files in deploy/secrets/:
#   client_token   for `pdsm submit/status/fetch/...` (the job API)
#   worker_token   for pdsm-worker (the worker API)
#   monitor_token  read-only: `pdsm status/list/watch/stats`, dashboards, health checks
# docker-compose.yml mounts them as compose secrets; `bash deploy/make_secrets.sh
# deploy/k8s/secrets` writes the files the Kubernetes kustomization turns into its Secret
# (docs/deploy.md). Existing tokens are kept unless --force is given, so running it again
# after an upgrade only adds the ones that are missing.
#
#   bash deploy/make_secrets.sh [--force] [DIR]     (DIR defaults to deploy/secrets)
set -euo pipefail

force=0
if [[ ${1:-} == --force ]]; then
  force=1
  shift
fi
dir=${1:-"$(cd "$(dirname "$0")" && pwd)/secrets"}

command -v openssl >/dev/null || { echo "$0: openssl is needed (apt-get install openssl)" >&2; exit 1; }
mkdir -p "$dir"
# The directory keeps other users of this machine out. The files themselves are world-readable
# because Docker Compose bind-mounts them with the host's owner and mode, and the containers
# run as uid 10001, not as you.
chmod 0700 "$dir"

for name in client_token worker_token monitor_token; do
  file=$dir/$name
  if [[ -s $file && $force == 0 ]]; then
    echo "kept      $file"
    continue
  fi
  (umask 022 && openssl rand -hex 32 >"$file.tmp")
  chmod 0644 "$file.tmp"
  mv -f "$file.tmp" "$file"
  echo "generated $file"
done
