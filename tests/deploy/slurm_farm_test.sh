#!/usr/bin/env bash
# pdsm workers on a real Slurm (issue #13): starts munge, slurmctld and slurmd on loopback in a
# temporary folder (one node, this machine), then does what docs/deploy.md tells a user to:
#   1. `sbatch --test-only` of deploy/slurm/pdsm_workers.sbatch with its defaults: they fit a
#      small node;
#   2. a coordinator, a job submitted, `sbatch --array=0-1 pdsm_workers.sbatch ADDR TOKEN`:
#      the fetched PDSM equals `pdsm bake` of the same scene byte for byte;
#   3. a second job running on the array, then `scancel`: every worker hands its leases back
#      at once (none expires: the lease is 10 minutes) and exits 0.
# Exit 77 (ctest: skipped), with the reason, where Slurm or munge is not installed or cannot
# start here; exit 1 on any failed check.
#
#   slurm_farm_test.sh PDSM PDSM_COORDINATOR PDSM_WORKER SBATCH_SCRIPT SCENE
set -euo pipefail

if [[ $# -ne 5 ]]; then
  echo "usage: $0 PDSM PDSM_COORDINATOR PDSM_WORKER SBATCH_SCRIPT SCENE" >&2
  exit 2
fi
for arg in "$@"; do [[ -e $arg ]] || { echo "$0: $arg does not exist" >&2; exit 2; }; done
pdsm=$(realpath "$1") coordinator_bin=$(realpath "$2") worker_bin=$(realpath "$3")
sbatch_script=$(realpath "$4") scene=$(realpath "$5")

skip() {
  echo "SKIPPED: $*" >&2
  exit 77
}
fail() {
  echo "FAILED: $*" >&2
  exit 1
}

for tool in munged mungekey slurmctld slurmd sbatch squeue scancel scontrol; do
  command -v "$tool" >/dev/null || skip "$tool not found (apt-get install slurm-wlm munge)"
done
[[ $(id -u) -eq 0 ]] || skip "needs root: slurmd runs jobs as their user and must be root"

work=$(mktemp -d /tmp/pdsm-slurm-test.XXXXXX)
chmod 0755 "$work"  # munged wants its socket folder not writable by others; slurmd reads it
pids=()
cleanup() {
  local status=$?
  if [[ -n ${SLURM_CONF:-} ]]; then scancel --quiet --user=root 2>/dev/null || true; fi
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  if [[ $status -ne 0 && $status -ne 77 ]]; then
    for log in "$work"/*.log "$work"/run/*.log; do
      [[ -f $log ]] && { echo "--- $log"; tail -n 40 "$log"; }
    done
  fi
  rm -rf "$work"
  exit "$status"
}
trap cleanup EXIT

# --- munge, with its own key and socket -----------------------------------------------------
mkdir -p "$work/munge"
chmod 0700 "$work/munge"
mungekey --create --keyfile="$work/munge/munge.key" >/dev/null 2>&1 || skip "mungekey failed"
munged --key-file="$work/munge/munge.key" --socket="$work/munge.sock" \
  --pid-file="$work/munge/munged.pid" --log-file="$work/munged.log" \
  --seed-file="$work/munge/munged.seed" --force --foreground >"$work/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [[ -S $work/munge.sock ]] && break; sleep 0.1; done
[[ -S $work/munge.sock ]] || skip "munged did not start ($(tail -n 3 "$work/munged.log" 2>/dev/null))"

# --- slurmctld and slurmd on loopback, on free ports ----------------------------------------
free_port() {
  /usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}
node=$(hostname -s)
cpus=$(nproc)
memory_mb=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2 ))
mkdir -p "$work/state" "$work/spool" "$work/run"
export SLURM_CONF=$work/slurm.conf
cat >"$SLURM_CONF" <<CONF
ClusterName=pdsmtest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
CommunicationParameters=NoInAddrAny,NoCtldInAddrAny
AuthType=auth/munge
AuthInfo=socket=$work/munge.sock
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/run/slurmctld.pid
SlurmdPidFile=$work/run/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
KillWait=30
MailProg=/bin/true
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory_mb State=UNKNOWN
PartitionName=pdsm Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -D -i -f "$SLURM_CONF" >"$work/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$node" >"$work/slurmd.out" 2>&1 &
pids+=($!)
up=0
for _ in $(seq 100); do
  if [[ $(sinfo -h -o %T 2>/dev/null) == idle ]]; then up=1; break; fi
  sleep 0.2
done
[[ $up == 1 ]] || skip "Slurm did not come up here: slurmctld: $(tail -n 2 "$work/slurmctld.log" 2>/dev/null); slurmd: $(tail -n 2 "$work/slurmd.log" 2>/dev/null)"
echo "slurm up: node $node, $cpus CPUs, ${memory_mb} MB"

# --- 1. the sbatch defaults fit a small node -------------------------------------------------
cd "$work"
printf 'worker-secret-%s\n' "$RANDOM$RANDOM" >"$work/worker_token"
printf 'client-secret-%s\n' "$RANDOM$RANDOM" >"$work/client_token"
chmod 0600 "$work/worker_token" "$work/client_token"
fit=$(sbatch --test-only "$sbatch_script" 127.0.0.1:1 "$work/worker_token" 2>&1) ||
  fail "sbatch --test-only with the script's defaults: $fit"
[[ $fit == *"to start at"* ]] || fail "the script's defaults do not fit this node: $fit"
echo "defaults fit: $fit"

# --- 2. a bake on Slurm workers equals the local bake ----------------------------------------
"$coordinator_bin" --listen 127.0.0.1:0 --data-dir "$work/data" --ready-file "$work/ready" \
  --client-token-file "$work/client_token" --worker-token-file "$work/worker_token" \
  --lease-seconds 600 >"$work/coordinator.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do [[ -s $work/ready ]] && break; sleep 0.1; done
address=$(head -n 1 "$work/ready")
[[ -n $address ]] || fail "the coordinator did not start"
client=(--server "$address" --token-file "$work/client_token")

bake=(--resolution 64x64 --samples 16 --sm-resolution 256 --tile-size 16)
slow_bake=(--resolution 128x128 --samples 4096 --sm-resolution 512 --tile-size 16)
"$pdsm" bake "$scene" "${bake[@]}" -o "$work/local.exr" --threads 1 --no-preview \
  >"$work/local_bake.log" 2>&1 || fail "pdsm bake: $(tail -n 3 "$work/local_bake.log")"
job=$("$pdsm" submit "$scene" "${bake[@]}" "${client[@]}" | tail -n 1)
PDSM_WORKER_BIN=$worker_bin sbatch --parsable --array=0-1 --cpus-per-task=1 --mem-per-cpu=500M \
  "$sbatch_script" "$address" "$work/worker_token" >"$work/array_id"
array=$(cut -d';' -f1 "$work/array_id")
echo "job $job, Slurm array $array"

state_of() { "$pdsm" status "$1" --json "${client[@]}" | /usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)["state"])'; }
wait_for_end() {
  local state=""
  for _ in $(seq 600); do
    state=$(state_of "$1")
    [[ $state == SUCCEEDED || $state == FAILED || $state == CANCELLED ]] && break
    sleep 0.2
  done
  echo "$state"
}
state=$(wait_for_end "$job")
[[ $state == SUCCEEDED ]] || fail "job $job ended $state: $(squeue -h 2>&1)"
"$pdsm" fetch "$job" -o "$work/farm.exr" "${client[@]}" >/dev/null
cmp "$work/local.exr" "$work/farm.exr" || fail "the Slurm bake differs from pdsm bake"
echo "bytes equal: $(stat -c %s "$work/farm.exr") bytes"

# --- 3. scancel while the workers hold leases ------------------------------------------------
stat_of() {
  "$pdsm" stats --json "${client[@]}" |
    /usr/bin/python3 -c 'import json, sys; print(int(json.load(sys.stdin)[sys.argv[1]]))' "$1"
}
slow=$("$pdsm" submit "$scene" "${slow_bake[@]}" "${client[@]}" | tail -n 1)
leased=0
for _ in $(seq 300); do
  leased=$(stat_of tasksLeased)
  [[ $leased -ge 2 ]] && break
  sleep 0.1
done
[[ $leased -ge 2 ]] || fail "the two workers never held leases of job $slow at once"
scancel "$array"
handed_back=0
for _ in $(seq 100); do  # 10 s, against a 600 s lease: only a hand-back frees them
  leased=$(stat_of tasksLeased)
  if [[ $leased -eq 0 ]]; then handed_back=1; break; fi
  sleep 0.1
done
[[ $handed_back == 1 ]] || fail "leases still held 10 s after scancel"
expired=$(stat_of leasesExpired)
[[ $expired -eq 0 ]] || fail "$expired leases expired instead of being handed back"
for _ in $(seq 150); do
  [[ -z $(squeue -h -j "$array" 2>/dev/null) ]] && break
  sleep 0.2
done
[[ -z $(squeue -h -j "$array" 2>/dev/null) ]] || fail "array $array still in squeue after scancel"
for task in 0 1; do
  log=$work/pdsm-worker-${array}_${task}.log
  [[ -f $log ]] || fail "no output file $log (the script's --output)"
  grep -q "hand" "$log" || fail "worker $task did not say it handed its leases back: $(tail -n 5 "$log")"
  grep -q "pdsm worker exited with status 0" "$log" ||
    fail "worker $task did not exit 0: $(tail -n 5 "$log")"
  echo "worker $task ($(basename "$log")):"; sed "s/^/    /" "$log"
done
"$pdsm" cancel "$slow" "${client[@]}" >/dev/null
echo "scancel: leases handed back, both workers exited 0"
echo "PASSED"
