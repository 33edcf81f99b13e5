# Current-generation console (PS5 / Xbox Series class): the platform's storage path decompresses
# in hardware (Kraken, BCPack/zlib via DirectStorage) from the package the platform builds, so
# GPU-resident payloads ship uncompressed inside the .lbk: compressing them with zstd would hide
# them from the hardware decompressor and force a CPU decode plus a copy before upload.
# Sections start on 64 KiB boundaries, the GPU page size, so an uncompressed section can be
# mapped or DMA'd straight into a texture or buffer (zero copy). Lightmaps are block-compressed
# the way shipping engines store them (BC6H for the HDR irradiance, BC5 + BC4 for the direction
# and the ratio): 2.5 bytes per texel in GPU memory instead of 8 (measured errors:
# tools/convert/profiles/README.md).
name        = console-current
description = PS5 / Xbox Series class: 64 KiB aligned, BC6H + BC5/BC4 lightmaps, GPU payloads uncompressed for the hardware decompressor
alignment   = 65536

[sections]
# CPU-side tables nobody uploads: zstd keeps them small.
default = zstd:19
# Provenance and the bake report are editor data; the runtime never reads them.
META = drop
REPT = drop
# The per-texel error map (TERR, lbk bake --error-map) is a diagnostic for the editor and lbk view.
TERR = drop
# GPU-resident payloads: raw, so the hardware decompressor and zero-copy upload see them as is.
LMAP = none
GLG  = none
LLG  = none
DLS  = none
OCTP = none

[lmap]
# No row pitch: a console keeps textures tiled in GPU memory, so the pack's linear pages are tiled
# by the platform's texture copy at load (which takes any source pitch), and widening a page to a
# 256-byte pitch would only grow the texture (a multiple of 128 texels for the BC4 ratio's 8-byte
# blocks): measured 2.79-3.20 B/texel instead of 2.50 on the shared scenes, 80 on the lamp's tiny
# page (README.md). Pages are padded to whole 4x4 blocks only.
row_pitch_alignment = 0
# plane 0, HDR irradiance: BC6H_UF16 (1 B/texel); plane 1: BC5 direction + BC4 ratio (1.5 B/texel)
plane0 = bc6h
plane1 = bc5_bc4
