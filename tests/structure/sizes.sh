#!/bin/sh
# The house sizes: no source file over 1,200 lines, no C/C++ function over 150.
#   files:     *.c *.h *.cc *.hh *.js *.py *.sh under libformat/ scene/ bake/ tools/ cli/ gpu/
#              tests/ bench/ viewer/, tracked or new (not ignored); not viewer/vendor/ and not a
#              generated file (one that says "generated ... do not edit" in its first 5 lines)
#   functions: top-level function bodies of the C/C++ files, as tests/structure/func_sizes.awk
#              measures them (from the "{" to the "}" that closes it)
# Prints one cmocka-style line (tests/run.sh counts it) and every offender, as "FILE: N lines"
# or "FILE:LINE NAME N lines". Run from anywhere.
set -u
cd "$(dirname "$0")/../.."
MAX_FILE=1200
MAX_FUNC=150

sources() {
    git ls-files -co --exclude-standard -- libformat scene bake tools cli gpu tests bench viewer |
        grep -E '\.(c|h|cc|hh|js|py|sh)$' | grep -v '^viewer/vendor/' | while read -r f; do
            [ -f "$f" ] && echo "$f"
        done > "$1.all"
    tr '\n' '\0' < "$1.all" | xargs -0 awk 'FNR <= 5 && tolower($0) ~ /generated.*do not edit|do not edit.*generated/ {
        print FILENAME; nextfile }' > "$1.gen"
    grep -vxF -f "$1.gen" "$1.all"
}

tmp=$(mktemp); trap 'rm -f "$tmp" "$tmp.all" "$tmp.gen"' EXIT
sources "$tmp" > "$tmp"
n=$(wc -l < "$tmp")
bad=0
# Files over the limit.
big=$(tr '\n' '\0' < "$tmp" | xargs -0 awk -v max="$MAX_FILE" '
    FNR == 1 && NR > 1 && n > max { print f ": " n " lines" } { f = FILENAME; n = FNR }
    END { if (n > max) print f ": " n " lines" }')
# Functions over the limit.
long=$(grep -E '\.(c|h|cc|hh)$' "$tmp" | tr '\n' '\0' | xargs -0 awk -f tests/structure/func_sizes.awk |
    awk -v max="$MAX_FUNC" '$3 > max { print $1 " " $2 " " $3 " lines" }')
[ -n "$big" ] && { echo "$big"; bad=$((bad + $(echo "$big" | wc -l))); }
[ -n "$long" ] && { echo "$long"; bad=$((bad + $(echo "$long" | wc -l))); }
echo "[==========] Running 1 test(s)."
if [ "$bad" -eq 0 ] && [ "$n" -gt 100 ]; then
    echo "[       OK ] sizes ($n files: none over $MAX_FILE lines, no function over $MAX_FUNC)"; st=0
else
    echo "[  FAILED  ] sizes ($bad offenders in $n files: over $MAX_FILE lines a file or $MAX_FUNC a function)"; st=1
fi
echo "[==========] 1 test(s) run."
exit $st
