# Previous-generation console (PS4 / Xbox One class): data comes from a slow hard disk or optical
# disc and there is no general-purpose hardware decompressor on the load path, so the bytes read
# dominate load time: every shipped section is zstd-compressed (level 19 decodes as fast as
# level 3; only the offline pack step is slower) and decoded once into GPU memory at load.
# 2 KiB alignment matches the optical/HDD sector size the platform streams in.
name        = console-previous
description = PS4 / Xbox One class: every section zstd-19, 2 KiB aligned for sector-sized reads
alignment   = 2048

[sections]
default = zstd:19
META = drop
REPT = drop
# The per-texel error map (TERR, lbk bake --error-map) is a diagnostic for the editor and lbk view.
TERR = drop

[lmap]
# GNM/D3D11.X linear texture rows: 256-byte pitch alignment.
row_pitch_alignment = 256
