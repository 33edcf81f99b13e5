#!/bin/sh
# Runs every test binary, each with its own log, and prints one closing line:
# "N passed, N failed" counts test binaries' cmocka cases summed (", N skipped" when a check
# could not run: the glTF-Validator without npm, or without the shared scenes).
set -u
: "${BUILD:=build}"
pass=0; fail=0; skipped=0; failed=""
for t in "$@"; do
  log="$BUILD/tests/$t.log"
  t0=$(date +%s)
  if "$BUILD/tests/$t" >"$log" 2>&1; then st=0; else st=$?; fi
  secs=$(( $(date +%s) - t0 ))
  p=$(grep -c '^\[       OK \]' "$log"); f=$(grep -c '^\[  FAILED  \]' "$log")
  [ "$st" -ne 0 ] && [ "$f" -eq 0 ] && f=1
  pass=$((pass + p)); fail=$((fail + f))
  if [ "$st" -ne 0 ]; then failed="$failed $t"; echo "FAIL $t (exit $st)"; tail -n 30 "$log"; else echo "ok   $t ($p cases, ${secs} s)"; fi
done
# The libFuzzer harness over the seed corpus for a fixed number of inputs (seeded, so runs
# repeat); inputs it finds go to a scratch directory, never into tests/fuzz/corpus.
if [ -n "${FUZZ:-}" ] && [ -x "$FUZZ" ]; then
  runs="${FUZZ_RUNS:-20000}"; scratch="$BUILD/fuzz-scratch"; log="$BUILD/tests/fuzz_container.log"
  rm -rf "$scratch"; mkdir -p "$scratch" "$BUILD/tests"
  if "$FUZZ" -runs="$runs" -seed=1 -rss_limit_mb=2048 "$scratch" tests/fuzz/corpus >"$log" 2>&1; then
    pass=$((pass + 1)); echo "ok   fuzz_container ($runs inputs)"
  else
    fail=$((fail + 1)); failed="$failed fuzz_container"; echo "FAIL fuzz_container"; tail -n 30 "$log"
  fi
fi
# The Khronos glTF-Validator over `lbk export --gltf` of the shared scenes (0 errors each).
scenes="${LBK_SCENES:-../shared/scenes}"
log="$BUILD/tests/gltf_validator.log"
if [ -z "${GLTF_VALIDATOR:-}" ]; then
  skipped=$((skipped + 1)); echo "SKIPPED gltf_validator (npm/node not found: apt-get install npm)"
elif [ ! -d "$scenes" ]; then
  skipped=$((skipped + 1)); echo "SKIPPED gltf_validator (no shared scenes at $scenes; set LBK_SCENES)"
elif sh tests/tools/gltf_validator.sh "$BUILD/lbk" "${LBK:-$BUILD/lbk-asan}" "$GLTF_VALIDATOR" "$BUILD/gltf-validator" >"$log" 2>&1; then
  pass=$((pass + 1)); echo "ok   gltf_validator ($(grep -c ' 0 errors' "$log") exports, 0 errors)"
else
  fail=$((fail + 1)); failed="$failed gltf_validator"; echo "FAIL gltf_validator"; tail -n 30 "$log"
fi
if [ "$skipped" -gt 0 ]; then echo "tests: $pass passed, $fail failed, $skipped skipped"; else echo "tests: $pass passed, $fail failed"; fi
[ -z "$failed" ]
