#!/usr/bin/env bash
# Builds the libFuzzer targets of tests/fuzz in build-fuzz (clang-14, ASan + UBSan) and runs each one in turn
# for SECONDS seconds (default 600), one job and one worker each (docs/robustness.md, "Sanitizers and
# fuzzing"). New inputs go to build-fuzz/corpus/TARGET (the seeds in tests/fuzz/corpus/TARGET are only read),
# crashes, leaks, timeouts and out-of-memory inputs to build-fuzz/crashes/TARGET/, libFuzzer's output to
# build-fuzz/runs/TARGET/fuzz-0.log. Exits non-zero when any target left a crash.
#
# usage: scripts/fuzz.sh [SECONDS] [TARGET...]    (targets: fuzz_scene fuzz_gmsh fuzz_vtk fuzz_abaqus fuzz_label_map fuzz_markups)
# Reproduce a crash: build-fuzz/bin/TARGET build-fuzz/crashes/TARGET/crash-...
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
build=$root/build-fuzz
seconds=${1:-600}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_scene fuzz_gmsh fuzz_vtk fuzz_abaqus fuzz_label_map fuzz_markups)

# Warnings are not errors here: the project's -Werror is kept for the GCC build, clang warns differently.
cmake -S . -B "$build" -DCMAKE_CXX_COMPILER=clang++-14 \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMTLED_BUILD_FUZZERS=ON -DMTLED_BUILD_TESTS=OFF \
  -DMTLED_BUILD_BENCHMARKS=OFF -DMTLED_WARNINGS_AS_ERRORS=OFF > /dev/null
nice -n 10 cmake --build "$build" -j2 --target "${targets[@]}"

# A report stops the run (libFuzzer then saves the input); stack traces symbolized.
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"

crashed=0
summary=()
for target in "${targets[@]}"; do
  corpus=$build/corpus/$target crashes=$build/crashes/$target run=$build/runs/$target
  mkdir -p "$corpus" "$crashes" "$run"
  rm -f "$run"/fuzz-*.log
  dict=()
  [ -f "tests/fuzz/$target.dict" ] && dict=(-dict="$root/tests/fuzz/$target.dict")
  echo "== $target: $seconds s"
  touch "$run/started"  # crashes newer than this are this run's
  start=$(date +%s)
  # -timeout: an input that takes 30 s is a hang (a finding; 10 s gave a false one on this loaded 2-core
  # machine, an ASan allocator stall); -rss_limit_mb: an input that needs 2 GB is a finding too.
  # -max_len: scenes and meshes of a few kB reach every branch; longer inputs only slow the search.
  (cd "$run" && nice -n 10 "$build/bin/$target" "$corpus" "$root/tests/fuzz/corpus/$target" "${dict[@]}" \
    -max_total_time="$seconds" -jobs=1 -workers=1 -timeout=30 -rss_limit_mb=2048 -max_len=8192 \
    -artifact_prefix="$crashes/" -print_final_stats=1 > /dev/null 2>&1) || true
  elapsed=$(( $(date +%s) - start ))
  log=$run/fuzz-0.log
  stat() { sed -n "s/^stat::$1: *//p" "$log" | tail -1; }
  execs=$(stat number_of_executed_units) rate=$(stat average_exec_per_sec)
  edges=$(grep -oE "(INITED|DONE) +cov: [0-9]+" "$log" | sed -E 's/.*cov: //' | paste -sd '>' -)
  found=$(find "$crashes" -type f -newer "$run/started" \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' -o -name 'oom-*' \) | wc -l)
  size=$(find "$corpus" -type f | wc -l)
  line="$target: ${elapsed} s, ${execs:-?} executions, ${rate:-?} exec/s, corpus ${size} files, coverage ${edges:-?}"
  line+=" edges, crashes ${found}"
  echo "$line"
  summary+=("$line")
  if [ "$found" -gt 0 ]; then
    crashed=1
    grep -m1 -E "ERROR: |runtime error|fuzz finding|uncaught|deadly signal" "$log" || true
  fi
done

echo "== summary ($(date -I), $(nproc) cores)"
printf '%s\n' "${summary[@]}"
exit $crashed
