# Tools, compiler flags and the libraries' flags (pkg-config where a library ships a .pc).
# Nothing here installs anything: that is mk/deps.mk.

PREFIX   ?= /usr/local
BUILD    ?= build
CC       ?= cc
CXX      ?= c++
CLANG    ?= clang
CLANGXX  ?= clang++
GLSLANG  ?= glslangValidator
PKG_CONFIG ?= pkg-config

WARN     := -Wall -Wextra -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Wno-unused-parameter
# The glTF shim: its own code warns like the C code; tinygltf, Draco, stb and nlohmann come in
# through -isystem, so warnings inside them (not ours to fix) do not count.
CXXWARN  := -Wall -Wextra -Wshadow -Wno-unused-parameter
# WERROR=1 (CI sets it) makes every warning of every compile an error: C and C++, release,
# shared, ASan, TSan, tests, benchmarks and the clang fuzz build.
ifeq ($(WERROR),1)
WARN     += -Werror
CXXWARN  += -Werror
endif
CSTD     := -std=c11 -D_POSIX_C_SOURCE=200809L -D_DEFAULT_SOURCE
OPT      ?= -O2 -g
SAN      := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
TSAN     := -fsanitize=thread -fno-omit-frame-pointer
# liblbk's arithmetic is defined operation by operation (the DLS apply paths must give the same
# bytes): never contract a multiply and an add into a fused one.
LIB_FP   := -ffp-contract=off

# ---- the libraries ----------------------------------------------------------------------------
# $(call pc,--cflags|--libs,MODULES,FALLBACK): what pkg-config says for MODULES when all their .pc
# files are installed, else FALLBACK (the flags lbk named before it asked pkg-config), so that a
# machine without pkg-config or without a .pc still builds.
pc = $(shell $(PKG_CONFIG) --exists $(2) 2>/dev/null && $(PKG_CONFIG) $(1) $(2) || echo '$(3)')
# -I DIR as -isystem DIR: for the C++ shim, whose headers' own warnings are not ours
isystem = $(patsubst -I%,-isystem %,$(1))

# xxHash's x86 runtime dispatch (AVX2/AVX-512 checksums) when the installed libxxhash has it
XXH_DISPATCH := $(shell printf '\043include <xxh_x86dispatch.h>\nint main(void){return (int)XXH3_64bits_dispatch("", 0);}\n' | \
                  $(CC) -x c - -o /dev/null -lxxhash 2>/dev/null && echo -DLBK_HAVE_XXH_DISPATCH)
# liblbk: zstd and xxHash (.pc: libzstd, libxxhash)
LIB_INC  := $(strip -Ilibformat/include $(XXH_DISPATCH) $(call pc,--cflags,libzstd libxxhash,))
LIB_LIBS := $(strip $(call pc,--libs,libzstd libxxhash,-lzstd -lxxhash) -lm)
# The baker (liblbkbake) and the tools: everything heavy lives here, never in liblbk.
# Through pkg-config: qhull_r, spng, libcjson, libwebp (EXT_texture_webp), draco (draco.pc says -I/usr/include, where its
# <draco/...> includes resolve; -I/usr/include/draco is only the fallback) and stb (headers only:
# stb_image is compiled into the glTF shim, so only its --cflags). Named directly because Debian
# ships no .pc for them (CMake configs only): Embree 3 (-lembree3), meshoptimizer (-lmeshoptimizer,
# EXT_meshopt_compression's decoders) and astcenc (-lastcenc). And
# OpenEXR: its OpenEXR.pc names the whole C++ library set (-lOpenEXR -lIex -lIlmThread -lImath ...);
# lbk uses only the C core (<OpenEXR/openexr.h>, -lOpenEXRCore), which has no .pc of its own.
BAKE_PC     := qhull_r spng libcjson draco libwebp
BAKE_CFLAGS := $(strip $(call pc,--cflags,$(BAKE_PC),-I/usr/include/draco) $(call pc,--cflags,stb,-I/usr/include/stb))
BAKE_LIBS   := $(strip -lembree3 -lOpenEXRCore -lmeshoptimizer $(call pc,--libs,$(BAKE_PC),-lqhull_r -lspng -lcjson -ldraco -lwebp) -lpthread -lm)
TOOL_INC    := $(LIB_INC) -Ibake/include -I. $(BAKE_CFLAGS)
TOOL_CXXINC := $(LIB_INC) -Ibake/include -I. $(call isystem,$(BAKE_CFLAGS))
# astcenc: the ASTC plane encodings of lbk convert / export / diff (tools/common/astc_codec.cc)
ASTCENC_LIBS := -lastcenc
TOOL_LIBS   := $(BAKE_LIBS) $(ASTCENC_LIBS) $(LIB_LIBS)
# the tests (cmocka.pc) and the GPU path (vulkan.pc)
CMOCKA_LIBS := $(strip $(call pc,--libs,cmocka,-lcmocka))
VULKAN_LIBS := $(strip $(call pc,--libs,vulkan,-lvulkan))
