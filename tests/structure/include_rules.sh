#!/bin/sh
# The house rules of ARCHITECTURE.md ("Layers"), checked over every #include "..." line:
#   libformat/  includes only itself (lbk/*.h of libformat/include)
#   scene/      libformat and scene/
#   bake/       libformat, scene/, lbk/bake.h and bake/ folders on its own floor or below:
#               util < transport < layout, probes < denoise, encode < sets, dist < pipeline
#   tools/      libformat, lbk/bake.h, the scene library's public headers, tools/
#   cli/        anything but tests/ and bench/
#   gpu/        libformat and gpu/
# Prints one cmocka-style line per rule (tests/run.sh counts them) and every include that breaks
# it, as FILE:LINE: "INCLUDED" (why). Run from the repository root.
set -u
cd "$(dirname "$0")/../.."
SCENE_PUBLIC="scene/scene.h scene/import.h scene/tracer.h scene/parallel.h scene/clock.h"

floor_of() { # bake folder -> floor
    case $1 in
        include) echo 0;; util) echo 1;; transport) echo 2;; layout|probes) echo 3;;
        denoise|encode) echo 4;; sets|dist) echo 5;; pipeline) echo 6;; *) echo 99;;
    esac
}

# Every quoted include of the layered trees, as FILE:LINE:INCLUDED.
includes() {
    git ls-files -co --exclude-standard -- 'libformat/*' 'scene/*' 'bake/*' 'tools/*' 'cli/*' 'gpu/*' |
        grep -E '\.(c|h|cc|cpp)$' | while read -r f; do
            [ -f "$f" ] || continue
            sed -n 's/^[ \t]*#[ \t]*include[ \t]*"\([^"]*\)".*/\1/p;=' "$f" |
                awk -v f="$f" 'NR % 1 == 0 { if ($0 ~ /^[0-9]+$/) ln = $0; else print f ":" ln ":" $0 }'
        done
}

# The file an include names: a path from the root, lbk/X under libformat/include or
# bake/include, or a name beside the including file.
resolve() { # file included
    dir=$(dirname "$1")
    if [ -f "$dir/$2" ]; then echo "$dir/$2"
    elif [ -f "$2" ]; then echo "$2"
    elif [ -f "libformat/include/$2" ]; then echo "libformat/include/$2"
    elif [ -f "bake/include/$2" ]; then echo "bake/include/$2"
    else echo "?$2"; fi
}

# why_bad FILE TARGET: prints the broken rule, or nothing.
why_bad() {
    f=$1; t=$2
    case $t in \?*) echo "not found from the include paths"; return;; esac
    case $f in
        libformat/*) case $t in libformat/*) ;; *) echo "liblbk includes only itself";; esac ;;
        scene/*) case $t in libformat/*|scene/*) ;; *) echo "the scene library sits below bake/ and tools/";; esac ;;
        gpu/*) case $t in libformat/*|gpu/*) ;; *) echo "gpu/ stands on liblbk alone";; esac ;;
        tools/*)
            case $t in
                libformat/*|tools/*|bake/include/lbk/bake.h) ;;
                scene/*) case " $SCENE_PUBLIC " in *" $t "*) ;; *) echo "tools/ uses the scene library's public headers only ($SCENE_PUBLIC)";; esac ;;
                *) echo "tools/ is thin over the libraries: of bake/ only lbk/bake.h";; esac ;;
        cli/*) case $t in tests/*|bench/*) echo "cli/ never includes tests or benches";; esac ;;
        bake/*)
            case $t in
                libformat/*|scene/*) ;;
                bake/*)
                    ff=$(echo "$f" | cut -d/ -f2); tf=$(echo "$t" | cut -d/ -f2)
                    if [ "$ff" != "$tf" ] && [ "$(floor_of "$tf")" -gt "$(floor_of "$ff")" ] ||
                       { [ "$ff" != "$tf" ] && [ "$(floor_of "$tf")" -eq "$(floor_of "$ff")" ]; }; then
                        echo "bake/$ff/ (floor $(floor_of "$ff")) may not include bake/$tf/ (floor $(floor_of "$tf"))"
                    fi ;;
                *) echo "bake/ includes liblbk, the scene library and itself only";; esac ;;
    esac
}

bad=0; n=0
tmp=$(mktemp); trap 'rm -f "$tmp"' EXIT
includes > "$tmp"
while IFS=: read -r f ln inc; do
    case $inc in *.spv.h) continue;; esac   # SPIR-V arrays generated into the build folder
    n=$((n + 1))
    t=$(resolve "$f" "$inc")
    why=$(why_bad "$f" "$t")
    if [ -n "$why" ]; then echo "$f:$ln: \"$inc\" ($why)"; bad=$((bad + 1)); fi
done < "$tmp"
echo "[==========] Running 1 test(s)."
if [ "$bad" -eq 0 ] && [ "$n" -gt 100 ]; then
    echo "[       OK ] include_rules ($n includes)"; st=0
else
    echo "[  FAILED  ] include_rules ($bad of $n includes break the rules)"; st=1
fi
echo "[==========] 1 test(s) run."
exit $st
