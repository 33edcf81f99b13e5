# Handheld / mobile (Switch class, Android/iOS GPUs): ASTC is the native block format and
# there is no BC support, so both lightmap planes are ASTC 4×4: HDR for the irradiance, LDR RGBA
# for ratio + direction — 2 bytes per texel in GPU memory. Storage is flash with a slow CPU: every
# section zstd-19 (the ASTC blocks compress a little further), 4 KiB alignment (flash pages).
name        = handheld
description = Switch / mobile class: ASTC 4x4 HDR + LDR lightmaps, every section zstd-19, 4 KiB aligned
alignment   = 4096

[sections]
default = zstd:19
META = drop
REPT = drop
# The per-texel error map (TERR, lbk bake --error-map) is a diagnostic for the editor and lbk view.
TERR = drop

[lmap]
# Vulkan / NVN linear uploads: 256-byte rows keep a buffer-to-image copy aligned on every driver.
row_pitch_alignment = 256
plane0 = astc4x4_hdr
plane1 = astc4x4
