#!/bin/sh
# Runs every test binary, each with its own log, and prints one closing line:
# "tests: N passed, N failed, N skipped", the test binaries' cmocka cases summed (a skipped
# case is counted as skipped, never as passed, and never disappears from the totals).
# FUZZ: the libFuzzer harness, run for FUZZ_RUNS inputs. TSAN_BIN: the folder of the
# ThreadSanitizer builds, whose cases of tests/tsan/determinism.list are run last.
set -u
: "${BUILD:=build}"
pass=0; fail=0; skip=0; failed=""
mkdir -p "$BUILD/tests"

# run_one NAME LOG CMD...: runs CMD into LOG and adds its cmocka cases to the totals.
run_one() {
  name=$1; log=$2; shift 2
  t0=$(date +%s)
  if "$@" >"$log" 2>&1 </dev/null; then st=0; else st=$?; fi
  secs=$(( $(date +%s) - t0 ))
  # one line per case until cmocka's "[==========] N test(s) run." (its summary lists them again)
  set -- $(awk '/^\[==========\] .* run\./ { exit } /^\[       OK \]/ { p++ } /^\[  FAILED  \]/ { f++ }
                /^\[  SKIPPED \]/ { s++ } END { print p + 0, f + 0, s + 0 }' "$log")
  p=$1; f=$2; s=$3
  [ "$st" -ne 0 ] && [ "$f" -eq 0 ] && f=1
  # a run that passes no case at all tests nothing (a filter that matches no case, say)
  [ "$st" -eq 0 ] && [ "$p" -eq 0 ] && [ "$s" -eq 0 ] && { f=1; st=1; echo "no case ran" >>"$log"; }
  pass=$((pass + p)); fail=$((fail + f)); skip=$((skip + s))
  if [ "$st" -ne 0 ]; then
    failed="$failed $name"; echo "FAIL $name (exit $st)"; tail -n 30 "$log"
  else
    extra=""; [ "$s" -gt 0 ] && extra=", $s skipped"
    echo "ok   $name ($p cases$extra, ${secs} s)"
  fi
}

for t in "$@"; do
  run_one "$t" "$BUILD/tests/$t.log" "$BUILD/tests/$t"
  # test_gpu again on lavapipe's code for AVX2 hosts without AVX-512 (Mesa's gallium drivers read
  # GALLIUM_OVERRIDE_CPU_CAPS; others ignore it): that is where llvmpipe's double roundEven was
  # off (gpu/GPU.md, "Exactness"), and a host with AVX-512 would never run that code otherwise.
  if [ "$t" = test_gpu ]; then
    run_one test_gpu_avx2 "$BUILD/tests/test_gpu_avx2.log" env GALLIUM_OVERRIDE_CPU_CAPS=avx "$BUILD/tests/$t"
  fi
done

# The libFuzzer harness over the seed corpus for a fixed number of inputs (seeded, so runs
# repeat); inputs it finds go to a scratch directory, never into tests/fuzz/corpus.
if [ -n "${FUZZ:-}" ] && [ -x "$FUZZ" ]; then
  runs="${FUZZ_RUNS:-20000}"; scratch="$BUILD/fuzz-scratch"; log="$BUILD/tests/fuzz_container.log"
  rm -rf "$scratch"; mkdir -p "$scratch"
  if "$FUZZ" -runs="$runs" -seed=1 -max_len=65536 -rss_limit_mb=2048 -artifact_prefix="$scratch/" "$scratch" tests/fuzz/corpus >"$log" 2>&1; then
    pass=$((pass + 1)); echo "ok   fuzz_container ($runs inputs)"
  else
    fail=$((fail + 1)); failed="$failed fuzz_container"; echo "FAIL fuzz_container"; tail -n 30 "$log"
  fi
fi

# The other harnesses (FUZZ_MORE: NAME=BINARY pairs; corpus tests/fuzz/corpus_NAME), each for a
# fixed number of inputs (FUZZ_MORE_RUNS, default 2000: the glTF importer runs ~150 inputs/s).
for h in ${FUZZ_MORE:-}; do
  name=${h%%=*}; bin=${h#*=}
  [ -x "$bin" ] || continue
  runs="${FUZZ_MORE_RUNS:-2000}"; scratch="$BUILD/fuzz-scratch-$name"; log="$BUILD/tests/fuzz_$name.log"
  rm -rf "$scratch"; mkdir -p "$scratch"
  if "$bin" -runs="$runs" -seed=1 -max_len=65536 -rss_limit_mb=2048 -artifact_prefix="$scratch/" "$scratch" "tests/fuzz/corpus_$name" >"$log" 2>&1; then
    pass=$((pass + 1)); echo "ok   fuzz_$name ($runs inputs)"
  else
    fail=$((fail + 1)); failed="$failed fuzz_$name"; echo "FAIL fuzz_$name"; tail -n 30 "$log"
  fi
done

# ThreadSanitizer: any report fails the run (halt_on_error); the suppressions cover Embree and
# TBB internals only (see the file).
if [ -n "${TSAN_BIN:-}" ]; then
  export TSAN_OPTIONS="halt_on_error=1 exitcode=66 second_deadlock_stack=1 suppressions=$(pwd)/tests/tsan/suppressions.txt ${TSAN_OPTIONS:-}"
  while read -r bin filter; do
    case "$bin" in ''|'#'*) continue;; esac
    export LBK_TEST_FILTER="$filter"
    run_one "tsan $bin:$filter" "$BUILD/tests/tsan_${bin}_${filter}.log" "$TSAN_BIN/$bin"
  done <tests/tsan/determinism.list
  unset LBK_TEST_FILTER
fi


# The Khronos glTF-Validator over `lbk export --gltf` of the shared scenes (0 errors each). The
# scenes are in scenes/ (LBK_SCENES overrides): a missing one fails, naming it (gltf_validator.sh).
log="$BUILD/tests/gltf_validator.log"
if [ -z "${GLTF_VALIDATOR:-}" ]; then
  skip=$((skip + 1)); echo "SKIPPED gltf_validator (npm/node not found: apt-get install npm)"
elif sh tests/tools/gltf_validator.sh "$BUILD/lbk" "${LBK:-$BUILD/lbk-asan}" "$GLTF_VALIDATOR" "$BUILD/gltf-validator" >"$log" 2>&1; then
  pass=$((pass + 1)); echo "ok   gltf_validator ($(grep -c ' 0 errors' "$log") exports, 0 errors)"
else
  fail=$((fail + 1)); failed="$failed gltf_validator"; echo "FAIL gltf_validator"; tail -n 30 "$log"
fi
# A distributed bake through a single-node Slurm cluster the script starts and stops itself
# (tests/e2e/slurm_dist.sh; installs Slurm and munge as root, SKIPPED only when not root and
# they are missing). Release lbk: the units run in Slurm jobs, ASan adds nothing there.
log="$BUILD/tests/slurm_dist.log"
if [ -x "$BUILD/lbk" ] && [ -n "${LBK:-}" ]; then
  sh tests/e2e/slurm_dist.sh "$BUILD/lbk" >"$log" 2>&1; st=$?
  if [ $st -eq 0 ]; then pass=$((pass + 1)); echo "ok   slurm_dist ($(tail -n 1 "$log"))"
  elif [ $st -eq 77 ]; then skip=$((skip + 1)); echo "SKIPPED slurm_dist ($(grep -m1 SKIPPED "$log"))"
  else fail=$((fail + 1)); failed="$failed slurm_dist"; echo "FAIL slurm_dist"; tail -n 30 "$log"; fi
fi
echo "tests: $pass passed, $fail failed, $skip skipped"
[ -z "$failed" ]
