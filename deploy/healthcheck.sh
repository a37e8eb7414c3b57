#!/usr/bin/env bash
# Liveness probe of a pdsm coordinator, for Docker's HEALTHCHECK (installed in the image as
# /usr/local/bin/pdsm-healthcheck). It asks the job API for its statistics with the `pdsm`
# client already in the image, so it needs no extra tools and proves that the server answers
# real calls, not only that the port is open. Exit 0: healthy.
#
# Settings (environment):
#   PDSM_HEALTH_SERVER      address to ask                 (default 127.0.0.1:50051)
#   PDSM_HEALTH_TOKEN_FILE  token, used if readable (default: /run/secrets/monitor_token, the
#                           read-only one, else /run/secrets/client_token)
#   PDSM_HEALTH_TLS_CA      CA to trust when the coordinator serves TLS; its certificate must
#                           then name the address above (IP:127.0.0.1 in subjectAltName)
set -euo pipefail

args=(stats --server "${PDSM_HEALTH_SERVER:-127.0.0.1:50051}")
token_file=${PDSM_HEALTH_TOKEN_FILE:-}
if [[ -z $token_file ]]; then
  token_file=/run/secrets/monitor_token
  [[ -r $token_file ]] || token_file=/run/secrets/client_token
fi
if [[ -r $token_file ]]; then
  args+=(--token-file "$token_file")
fi
if [[ -n ${PDSM_HEALTH_TLS_CA:-} ]]; then
  args+=(--tls-ca "$PDSM_HEALTH_TLS_CA")
fi
exec pdsm "${args[@]}" >/dev/null
