#!/bin/sh
# Runs every test binary, each with its own log, and prints one closing line:
# "N passed, N failed" counts test binaries' cmocka cases summed.
set -u
: "${BUILD:=build}"
pass=0; fail=0; failed=""
for t in "$@"; do
  log="$BUILD/tests/$t.log"
  if "$BUILD/tests/$t" >"$log" 2>&1; then st=0; else st=$?; fi
  p=$(grep -c '^\[       OK \]' "$log"); f=$(grep -c '^\[  FAILED  \]' "$log")
  [ "$st" -ne 0 ] && [ "$f" -eq 0 ] && f=1
  pass=$((pass + p)); fail=$((fail + f))
  if [ "$st" -ne 0 ]; then failed="$failed $t"; echo "FAIL $t (exit $st)"; tail -n 30 "$log"; else echo "ok   $t ($p cases)"; fi
done
echo "tests: $pass passed, $fail failed"
[ -z "$failed" ]
