# Prints "FILE:LINE NAME LINES" for every top-level C/C++ function body (a line ending in ") {",
# or a "{" line after a line ending in ")", at depth 0 and not an initializer, up to the "}" that
# closes it; LINE is the line of the "{"). The bodies of namespace { } and extern "C" { } count as
# top level. Counting is by braces on code lines: comments and strings that hold braces are rare
# here and only make a function look longer, never shorter.
FNR == 1 { depth = 0; start = 0; incomment = 0; prev = ""; sig = "" }
{
    line = $0
    gsub(/"([^"\\]|\\.)*"/, "\"\"", line)     # strings
    gsub(/'([^'\\]|\\.)*'/, "''", line)         # characters
    sub(/\/\/.*$/, "", line)
    gsub(/\/\*([^*]|\*[^\/])*\*\//, "", line)  # one-line comments
    if (incomment) { if (line ~ /\*\//) { sub(/^.*\*\//, "", line); incomment = 0 } else next }
    if (line ~ /\/\*/) { sub(/\/\*.*$/, "", line); incomment = 1 }
    opens = gsub(/\{/, "{", line); closes = gsub(/\}/, "}", line)
    if (line ~ /^(namespace|extern "")[^;]*\{[ \t]*$/) opens = 0   # a namespace's body is top level
    if (depth == 0 && line ~ /^[A-Za-z_].*\(/) sig = line  # where a signature begins
    if (depth == 0 && opens > 0 && line !~ /^typedef/ && line !~ /=[ \t]*\{/ &&
        (line ~ /\)[ \t]*(const|noexcept|override)?[ \t]*\{[ \t]*$/ || prev ~ /\)[ \t]*$/ && line ~ /^\{/)) {
        start = FNR; name = (line ~ /^[A-Za-z_].*\(/) ? line : sig
        gsub(/__attribute__[ \t]*\(\([^)]*\)\)/, "", name)
        sub(/\(.*/, "", name); n = split(name, w, /[ \t*&]+/); name = w[n]
    }
    depth += opens - closes; if (depth < 0) depth = 0
    if (depth == 0 && start) { print FILENAME ":" start " " name " " FNR - start + 1; start = 0 }
    if (line !~ /^[ \t]*$/) prev = line
}
