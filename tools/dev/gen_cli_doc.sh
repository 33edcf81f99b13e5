#!/bin/sh
# Writes docs/cli.md from the binary's own help: `lbk --help`, then `lbk CMD --help` for every
# command `lbk --help` lists, each under its heading in a fenced block. The help is the source
# (`lbk bake`'s options come from the table of cli/bake_options.c); tests/tools/test_cli_doc.c
# fails when docs/cli.md is not what this script writes.
#
#   sh tools/dev/gen_cli_doc.sh [LBK] [OUT]     (default build/lbk, docs/cli.md; OUT - : stdout)
set -eu
lbk=${1:-build/lbk}
out=${2:-docs/cli.md}
[ -x "$lbk" ] || { echo "gen_cli_doc: $lbk is not an executable lbk (make first)" >&2; exit 2; }
# Paths from where the script was called; the help itself from the repository root with no
# profile path of the caller's (lbk convert --help lists the profiles it finds).
case $lbk in /*) ;; *) lbk=$(pwd)/$lbk;; esac
case $out in /*|-) ;; *) out=$(pwd)/$out;; esac
cd "$(dirname "$0")/../.."
unset LBK_PROFILE_PATH

# The commands: the lines "  NAME  summary" between "commands:" and the next blank line.
cmds=$("$lbk" --help | awk '/^commands:/ { on = 1; next } on && /^$/ { exit } on { print $1 }')
[ -n "$cmds" ] || { echo "gen_cli_doc: $lbk --help lists no commands" >&2; exit 1; }

gen() {
  echo "# The lbk command line"
  echo
  echo "Written by \`sh tools/dev/gen_cli_doc.sh\` from \`lbk --help\` and \`lbk COMMAND --help\`; do not"
  echo "edit by hand (tests/tools/test_cli_doc.c checks it against the binary)."
  echo
  echo "## lbk"
  echo
  echo '```'
  "$lbk" --help
  echo '```'
  for c in $cmds; do
    echo
    echo "## lbk $c"
    echo
    echo '```'
    "$lbk" "$c" --help
    echo '```'
  done
}

if [ "$out" = - ]; then
  gen
else
  tmp="$out.tmp.$$"
  trap 'rm -f "$tmp"' EXIT
  gen >"$tmp"
  mv "$tmp" "$out"
fi
