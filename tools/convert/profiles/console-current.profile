# Current-generation console (PS5 / Xbox Series class): the platform's storage path decompresses
# in hardware (Kraken, BCPack/zlib via DirectStorage) from the package the platform builds, so
# GPU-resident payloads ship uncompressed inside the .lbk: compressing them with zstd would hide
# them from the hardware decompressor and force a CPU decode plus a copy before upload.
# Sections start on 64 KiB boundaries, the GPU page size, so an uncompressed section can be
# mapped or DMA'd straight into a texture or buffer (zero copy).
name        = console-current
description = PS5 / Xbox Series class: 64 KiB aligned, GPU payloads uncompressed for the hardware decompressor
alignment   = 65536

[sections]
# CPU-side tables nobody uploads: zstd keeps them small.
default = zstd:19
# Provenance and the bake report are editor data; the runtime never reads them.
META = drop
REPT = drop
# GPU-resident payloads: raw, so the hardware decompressor and zero-copy upload see them as is.
LMAP = none
GLG  = none
LLG  = none
DLS  = none
OCTP = none

[lmap]
# D3D12_TEXTURE_DATA_PITCH_ALIGNMENT: rows of a buffer-to-texture copy start every 256 bytes,
# so pages whose width is not a multiple of 64 texels are widened (see README.md).
row_pitch_alignment = 256
