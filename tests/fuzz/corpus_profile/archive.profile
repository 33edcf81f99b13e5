# Archive: keep everything (provenance, bake report) for later diffs, as small as zstd allows.
# Not a shipping profile; use it to store bakes next to the source level.
name        = archive
description = keeps every section incl. META and REPT, zstd-22, minimum alignment
alignment   = 16

[sections]
default = zstd:22

[lmap]
row_pitch_alignment = 0
