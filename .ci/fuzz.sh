#!/usr/bin/env bash
# Builds the libFuzzer targets under fuzz/ (clang, ASan+UBSan; the top-level project with IDENT_BUILD_FUZZERS=ON) and runs each one for a bounded time
# on a copy of its committed seed corpus. Fails (exit 1) if any target finds a crash, leak, timeout
# or property violation; the reproducer is left in $IDENT_FUZZ_OUT/<target>/ (artifact prefix).
#
#   .ci/fuzz.sh                      every target, 60 s each
#   IDENT_FUZZ_SECONDS=10 .ci/fuzz.sh csv_fuzzer rls_fuzzer
#
# Environment: IDENT_FUZZ_SECONDS (default 60) per target, IDENT_FUZZ_TIMEOUT (default 10: seconds one input may
# take before it counts as a hang; a slower build needs more), IDENT_FUZZ_BUILD (default build-fuzz),
# IDENT_FUZZ_OUT (default $IDENT_FUZZ_BUILD/runs), CXX (default clang++), IDENT_FUZZ_JOBS (default 2: build
# parallelism and the number of targets fuzzed at the same time), IDENT_FUZZ_PARALLEL (default
# IDENT_FUZZ_JOBS: the number of targets fuzzed at the same time, if it should differ).
# Prints one summary line per target: name, executions, corpus size, result.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${IDENT_FUZZ_SECONDS:-60}"
timeout="${IDENT_FUZZ_TIMEOUT:-10}"
build="${IDENT_FUZZ_BUILD:-$root/build-fuzz}"
out="${IDENT_FUZZ_OUT:-$build/runs}"
jobs="${IDENT_FUZZ_JOBS:-2}"
parallel="${IDENT_FUZZ_PARALLEL:-$jobs}"

if ! command -v "${CXX:-clang++}" >/dev/null; then
  echo "fuzz.sh: ${CXX:-clang++} not found (apt-get install clang libclang-rt-14-dev)" >&2
  exit 1
fi
if [ "$#" -gt 0 ]; then
  targets=("$@")
else
  targets=()
  for src in "$root"/fuzz/*_fuzzer.cc; do targets+=("$(basename "$src" .cc)"); done
fi

mkdir -p "$build"
# Reuse a build tree already configured with IDENT_BUILD_FUZZERS=ON; otherwise configure the top-level
# project with only what the fuzzers need (no tests, benchmarks, examples; -O1 and line tables: half the
# compile time of -O2 -g, and reports keep file:line). Only the requested targets are built.
if ! grep -q '^IDENT_BUILD_FUZZERS:BOOL=ON' "$build/CMakeCache.txt" 2>/dev/null; then
  if ! CXX="${CXX:-clang++}" cmake -S "$root" -B "$build" -G Ninja -DIDENT_BUILD_FUZZERS=ON \
        -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
        -DIDENT_BUILD_TESTS=OFF -DIDENT_BUILD_BENCHMARKS=OFF -DIDENT_BUILD_EXAMPLES=OFF -DIDENT_INSTALL=OFF \
        >"$build/configure.log" 2>&1; then
    tail -n 30 "$build/configure.log" >&2
    echo "fuzz.sh: configuring the fuzz build failed (log: $build/configure.log)" >&2
    exit 1
  fi
fi
if ! cmake --build "$build" -j"$jobs" --target "${targets[@]}" >"$build/fuzz-build.log" 2>&1; then
  tail -n 30 "$build/fuzz-build.log" >&2
  echo "fuzz.sh: building the fuzz targets failed (log: $build/fuzz-build.log)" >&2
  exit 1
fi

# Runs one target on a copy of its seed corpus; writes "<execs> <corpus size> <status>" to $work/result.
run_target() {
  local t="$1" work="$out/$1"
  rm -rf "$work" && mkdir -p "$work/corpus"
  local seeds="$root/fuzz/corpus/$t"
  [ -d "$seeds" ] && cp -r "$seeds"/. "$work/corpus/"
  local log="$work/log.txt" status=ok
  # -timeout: one input taking longer is a hang; -rss_limit_mb: runaway memory is a finding.
  if ! "$build/fuzz/$t" "$work/corpus" -max_total_time="$seconds" -timeout="$timeout" -rss_limit_mb=2048 \
        -artifact_prefix="$work/" -print_final_stats=1 >"$log" 2>&1; then
    status="FAILED (see $log)"
  fi
  local execs
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  echo "${execs:-0} $(ls "$work/corpus" | wc -l) $status" >"$work/result"
}

# $parallel targets at a time, so the whole run takes about ceil(targets/parallel) x seconds; each target
# runs for $seconds of wall time and gets (cores / parallel) of a core meanwhile.
running=0
for t in "${targets[@]}"; do
  run_target "$t" &
  running=$((running + 1))
  if [ "$running" -ge "$parallel" ]; then wait -n || true; running=$((running - 1)); fi
done
wait || true

failed=0
total=0
for t in "${targets[@]}"; do
  read -r execs corpus status <"$out/$t/result" || { execs=0; corpus=0; status="FAILED (no result)"; }
  [ "$status" = ok ] || failed=1
  total=$((total + execs))
  printf '%-24s %12s execs  corpus %5s  %s\n' "$t" "$execs" "$corpus" "$status"
done
printf '%-24s %12s execs  findings: %s\n' "total" "$total" "$([ $failed = 0 ] && echo none || echo YES)"
exit $failed
