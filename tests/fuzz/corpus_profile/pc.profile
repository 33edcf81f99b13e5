# PC: loaded with mmap from an SSD; no hardware decompressor we can target with zstd, and file
# size matters for downloads, so everything is zstd (level 19: smaller download, fast decode).
# 4 KiB alignment is the page size, so uncompressed sections of a user profile derived from this
# one can still be mapped without a copy.
name        = pc
description = PC: 4 KiB (page) aligned, every section zstd-19, editor data dropped
alignment   = 4096

[sections]
default = zstd:19
META = drop
REPT = drop
# The per-texel error map (TERR, lbk bake --error-map) is a diagnostic for the editor and lbk view.
TERR = drop

[lmap]
# D3D12 buffer-to-texture copies want a 256-byte row pitch (Vulkan is satisfied by it too).
row_pitch_alignment = 256
