#!/usr/bin/env bash
# The test suite under AddressSanitizer and UndefinedBehaviorSanitizer (docs/robustness.md, "Sanitizers and
# fuzzing"): configures build-asan, builds it with -j2 and runs `ctest -LE large` there. Any sanitizer report,
# in a test executable or in an mtled it starts, fails the run.
#
# usage: scripts/sanitize.sh [extra ctest arguments, e.g. -R BadInput]
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
build=$root/build-asan
logs=$build/sanitizer-logs

# GCC, like the default build: the build fingerprint (mtled/abi.hpp) names the compiler, and the
# out-of-tree-plugin test builds its plugin with the default compiler, which the kernel must accept.
# MTLED_SANITIZE adds the flags to every target (core, plugin modules, tests, mtled) and to every link, so
# the dlopen'ed plugins are instrumented too; GCC links libasan into each of them, one runtime per process.
# -O1: the sanitizers' recommended optimisation (readable stacks, tolerable speed).
# Warnings are not errors here: GCC 12 emits false -Wmaybe-uninitialized / -Wstringop-overflow positives
# under sanitizer instrumentation; the default build keeps -Werror.
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
  -DMTLED_SANITIZE=address,undefined \
  -DMTLED_BUILD_TESTS=ON -DMTLED_BUILD_BENCHMARKS=OFF -DMTLED_WARNINGS_AS_ERRORS=OFF > /dev/null
nice -n 10 cmake --build "$build" -j2

# Reports go to files (one per process, PID appended) so that those of the mtled processes the CLI tests
# start are not lost in captured output. halt_on_error: the first report stops the process.
rm -rf "$logs" && mkdir -p "$logs"
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:check_initialization_order=1:log_path=$logs/asan"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:log_path=$logs/ubsan"
export LSAN_OPTIONS="suppressions=$root/scripts/lsan.supp:print_suppressions=0"

# Excluded (the regular expression below), with why:
#   (none at present; add "name|name" with a reason when a test is too slow to be useful under ASan)
exclude='^$'
status=0
start=$(date +%s)
ctest --test-dir "$build" -j2 -LE large -E "$exclude" --timeout 3000 --output-on-failure "$@" || status=$?
echo "ctest wall time: $(( $(date +%s) - start )) s"

if compgen -G "$logs/*" > /dev/null; then
  echo "sanitizer reports:"
  for f in "$logs"/*; do
    echo "=== $f"
    head -60 "$f"
  done
  status=1
fi
exit $status
