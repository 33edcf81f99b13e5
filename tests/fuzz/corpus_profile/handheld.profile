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
# No row pitch: Vulkan's buffer-to-image copy takes any row length that is a whole number of
# blocks (bufferRowLength; the offset a multiple of the 16-byte block), NVN the same, and the
# driver tiles the texture at upload. A 256-byte pitch (64 texels of ASTC 4x4) cost 2.06-2.78 GPU
# B/texel on the shared scenes and 16 on the lamp's 4-texel-wide page instead of 2.00.
row_pitch_alignment = 0
plane0 = astc4x4_hdr
plane1 = astc4x4
