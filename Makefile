# lbk — light bake kit. `make demo` and `make test` do all set-up on a fresh Debian machine.
# Sources are picked up by wildcard: adding a file to a folder needs no edit here.

PREFIX   ?= /usr/local
BUILD    ?= build
CC       ?= cc
CXX      ?= c++
CLANG    ?= clang

# Debian packages: liblbk alone (`make install-lib`), the baker and CLI, the tests on top.
DEB_LIB_PKGS  := build-essential libzstd-dev libxxhash-dev
# The GPU path (gpu/): Vulkan headers and loader, glslang, and Mesa's lavapipe (a CPU Vulkan
# device) so that its tests run on a machine without a GPU.
GPU_PKGS      := libvulkan-dev mesa-vulkan-drivers glslang-tools
DEB_TOOL_PKGS := $(DEB_LIB_PKGS) libembree-dev libopenexr-dev libdraco-dev libtinygltf-dev libstb-dev \
                 nlohmann-json3-dev libqhull-dev libspng-dev libcjson-dev \
                 libastcenc-dev
DEB_TEST_PKGS := $(DEB_TOOL_PKGS) pkg-config libcmocka-dev clang libclang-rt-14-dev
# lbk view's tests: node runs the page's container reader against liblbk, headless Chromium
# (SwiftShader WebGL) loads the page; without them those cases are SKIPPED (counted so).
VIEW_PKGS     := nodejs chromium
# A single-node Slurm cluster for the distributed-bake test (tests/e2e/slurm_dist.sh, which
# also installs them itself when run as root).
SLURM_PKGS    := munge slurmd slurmctld slurm-client
DEB_PKGS      := $(DEB_TEST_PKGS) $(GPU_PKGS) $(VIEW_PKGS) $(SLURM_PKGS)

WARN     := -Wall -Wextra -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Wno-unused-parameter
# The glTF shim: its own code warns like the C code; tinygltf, Draco, stb and nlohmann come in
# through -isystem, so warnings inside them (not ours to fix) do not count.
CXXWARN  := -Wall -Wextra -Wshadow -Wno-unused-parameter
# WERROR=1 (CI sets it) makes every warning of every compile an error: C and C++, release,
# ASan, TSan, tests, benchmarks and the clang fuzz build.
ifeq ($(WERROR),1)
WARN     += -Werror
CXXWARN  += -Werror
endif
CSTD     := -std=c11 -D_POSIX_C_SOURCE=200809L -D_DEFAULT_SOURCE
OPT      ?= -O2 -g
SAN      := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
# liblbk's arithmetic is defined operation by operation (the DLS apply paths must give the same
# bytes): never contract a multiply and an add into a fused one.
LIB_FP   := -ffp-contract=off

# xxHash's x86 runtime dispatch (AVX2/AVX-512 checksums) when the installed libxxhash has it
XXH_DISPATCH := $(shell printf '\043include <xxh_x86dispatch.h>\nint main(void){return (int)XXH3_64bits_dispatch("", 0);}\n' | \
                  $(CC) -x c - -o /dev/null -lxxhash 2>/dev/null && echo -DLBK_HAVE_XXH_DISPATCH)
LIB_INC  := -Ilibformat/include $(XXH_DISPATCH)
LIB_LIBS := -lzstd -lxxhash -lm
# The baker (liblbkbake) and the tools: everything heavy lives here, never in liblbk.
TOOL_INC := $(LIB_INC) -Ibake/include -I. -I/usr/include/draco -I/usr/include/stb
BAKE_LIBS:= -lembree3 -lOpenEXRCore -lqhull_r -lspng -lcjson -ldraco -lpthread -lm
# astcenc: the ASTC plane encodings of lbk convert / export / diff (tools/common/astc_codec.cc)
TOOL_LIBS:= $(BAKE_LIBS) -lastcenc $(LIB_LIBS)
TOOL_CXXINC := $(LIB_INC) -Ibake/include -I. -isystem /usr/include/draco -isystem /usr/include/stb

LIB_SRC   := $(sort $(wildcard libformat/src/*.c))
# liblbkbake holds the scene library (scene/: import, bk_scene, tracer, parallel-for, clock) and
# the baker (bake/*/) above it.
BAKE_CSRC := $(sort $(wildcard scene/*.c bake/*/*.c))
BAKE_CXXSRC := $(sort $(wildcard scene/*.cc bake/*/*.cc))
TOOL_CSRC := $(sort $(wildcard cli/*.c scene/*.c bake/*/*.c tools/*/*.c))
TOOL_CXXSRC := $(BAKE_CXXSRC) $(sort $(wildcard tools/*/*.cc))
TOOL_MAIN := cli/main.c
# The page of `lbk view` (viewer/: the scripts, the vendored npm builds and their licences),
# embedded in the lbk binary as C arrays, so an installed lbk writes the page without viewer/.
VIEW_FILES := $(sort $(wildcard viewer/*.html viewer/*.js viewer/vendor/*.js viewer/vendor/LICENSE.*))
VIEW_ASSETS_C := $(BUILD)/gen/viewer_assets.c
TOOL_CSRC += $(VIEW_ASSETS_C)
TEST_SRC  := $(sort $(wildcard tests/*/test_*.c))
TESTS     := $(notdir $(TEST_SRC:.c=))
TEST_SUPPORT := $(sort $(wildcard tests/support/*.c))
BENCHES   := $(patsubst bench/%.c,%,$(sort $(wildcard bench/bench_*.c)))

# Release objects
LIB_OBJ   := $(LIB_SRC:%.c=$(BUILD)/rel/%.o)
LIB_PIC   := $(LIB_SRC:%.c=$(BUILD)/pic/%.o)
BAKE_OBJ  := $(BAKE_CSRC:%.c=$(BUILD)/rel/%.o) $(BAKE_CXXSRC:%.cc=$(BUILD)/rel/%.o)
BAKE_PIC  := $(BAKE_CSRC:%.c=$(BUILD)/pic/%.o) $(BAKE_CXXSRC:%.cc=$(BUILD)/pic/%.o)
# cli/ and tools/ (the baker comes from liblbkbake.a)
TOOL_OBJ  := $(filter-out $(BUILD)/rel/$(TOOL_MAIN:.c=.o) $(BAKE_OBJ),$(TOOL_CSRC:%.c=$(BUILD)/rel/%.o)) \
             $(patsubst %.cc,$(BUILD)/rel/%.o,$(sort $(wildcard tools/*/*.cc)))
# Sanitizer objects for the test build
LIB_ASAN  := $(LIB_SRC:%.c=$(BUILD)/asan/%.o)
TOOL_ASAN := $(filter-out $(BUILD)/asan/$(TOOL_MAIN:.c=.o),$(TOOL_CSRC:%.c=$(BUILD)/asan/%.o)) $(TOOL_CXXSRC:%.cc=$(BUILD)/asan/%.o)

.PHONY: all lib bake-lib deps deps-bench demo test check bench bench-cycles bench-render mesa-bc-check fuzz fuzz-long install install-check clean help gltf-validator gpu test-build
all: $(BUILD)/lbk $(BUILD)/liblbk.a $(BUILD)/liblbk.so $(BUILD)/lbk.pc \
     $(BUILD)/liblbkbake.a $(BUILD)/liblbkbake.so $(BUILD)/lbk-bake.pc

help:
	@echo "make            build liblbk.a/.so + lbk.pc, liblbkbake.a/.so + lbk-bake.pc and the lbk CLI into $(BUILD)/"
	@echo "make deps       install the missing Debian packages"
	@echo "make demo       bake the embedded scene, inspect it, write a PNG"
	@echo "make test       build with ASan+UBSan, run the whole suite, then make tsan's cases"
	@echo "                (demo, test, bench, fuzz install missing packages only as root with CI set"
	@echo "                or with LBK_INSTALL_DEPS=1; else they print the apt-get line and stop)"
	@echo "make tsan       the determinism cases of tests/tsan/determinism.list under ThreadSanitizer"
	@echo "make install-lib PREFIX=/usr/local   liblbk only (needs a C compiler, zstd, xxHash)"
	@echo "WERROR=1        every compiler warning is an error (CI)"
	@echo "make bench      benchmarks, printed as ratios against baselines measured in the same run"
	@echo "make bench-cycles  lbk against Blender Cycles at equal time (part of make bench; bench/cycles/README.md)"
	@echo "make bench-render  lbk render against Blender Cycles"
	@echo "make mesa-bc-check  BC6H/BC4 codecs against Mesa's (optional: libegl-dev libgl-dev)"
	@echo "make fuzz       the libFuzzer harnesses (container, glTF import, sky EXR, profiles), FUZZ_SECONDS each"
	@echo "make fuzz-long  the same for FUZZ_HOURS (default 1) each"
	@echo "make gpu        the Vulkan DLS apply tool build/lbk-gpu-apply (make test runs the GPU tests on lavapipe)"
	@echo "make install PREFIX=/usr/local"

# ---- dependencies -------------------------------------------------------------------------
# `make deps` installs whatever of DEB_PKGS is missing: that is what it is asked for (through
# sudo when not root). The targets that need packages (test, demo, bench, fuzz) only check: they
# install the missing ones themselves when run as root with CI set (.ci/run) or when
# LBK_INSTALL_DEPS=1, and say which and why; otherwise they print the one command to run and stop.
# $(1): the packages; $(2): the reason to install without asking, empty to ask first; $(3): what
# happens without them, for packages that are optional (then a note instead of a stop).
define deps_sh
missing=$$(for p in $(1); do dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'install ok installed' || echo $$p; done); \
[ -z "$$missing" ] && exit 0; missing=$$(echo $$missing); \
if [ "$$(id -u)" = 0 ]; then sudo=; else sudo="sudo "; fi; \
why="$(2)"; \
[ -z "$$why" ] && [ "$${LBK_INSTALL_DEPS:-}" = 1 ] && why="LBK_INSTALL_DEPS=1"; \
[ -z "$$why" ] && [ -n "$${CI:-}" ] && [ -z "$$sudo" ] && why="CI=$$CI, running as root"; \
if [ -z "$$why" ] && [ -n "$(3)" ]; then \
  echo "lbk: not installed: $$missing; $(3)"; \
  echo "lbk: (make deps, or LBK_INSTALL_DEPS=1 make $(MAKECMDGOALS), installs them)"; exit 0; \
fi; \
if [ -z "$$why" ]; then \
  echo "lbk: make $(MAKECMDGOALS) needs Debian packages that are not installed: $$missing"; \
  echo "lbk: install them with"; echo "  $${sudo}apt-get install -y $$missing"; \
  echo "lbk: (or run make deps, or LBK_INSTALL_DEPS=1 make $(MAKECMDGOALS))"; exit 1; \
fi; \
echo "lbk: installing missing Debian packages ($$why): $$missing"; \
{ $${sudo}apt-get update -qq || true; } && $${sudo}env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing >/dev/null
endef
.PHONY: deps-tools deps-test
deps:
	@$(call deps_sh,$(DEB_PKGS),make deps)
deps-tools:
	@$(call deps_sh,$(DEB_TOOL_PKGS),)
# The GPU packages are optional for make test: without them (and not allowed to install them)
# tests/gpu/test_gpu.c is built without Vulkan and its cases count as skipped.
deps-test:
	@$(call deps_sh,$(DEB_TEST_PKGS),)
	@$(call deps_sh,$(GPU_PKGS),,the GPU tests will be SKIPPED (counted so))
	@$(call deps_sh,$(VIEW_PKGS),,the lbk view tests (JS reader, headless Chromium) will be SKIPPED (counted so))

# What `make bench-cycles` needs besides the build: Blender (Cycles) and Python 3.
BENCH_DEB_PKGS := blender python3
deps-bench:
	@$(call deps_sh,$(BENCH_DEB_PKGS),)

# ---- compile rules --------------------------------------------------------------------------
$(BUILD)/rel/libformat/%.o: libformat/%.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(OPT) $(LIB_FP) $(WARN) $(LIB_INC) -MMD -MP -c $< -o $@
$(BUILD)/pic/libformat/%.o: libformat/%.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(OPT) $(LIB_FP) $(WARN) -fPIC -fvisibility=hidden -DLBK_BUILDING_SHARED $(LIB_INC) -MMD -MP -c $< -o $@
$(BUILD)/asan/libformat/%.o: libformat/%.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O1 -g $(LIB_FP) $(SAN) $(WARN) $(LIB_INC) -MMD -MP -c $< -o $@
$(BUILD)/pic/bake/%.o: bake/%.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(OPT) $(WARN) -fPIC -fvisibility=hidden -DLBK_BAKE_BUILDING_SHARED $(TOOL_INC) -MMD -MP -c $< -o $@
$(BUILD)/pic/scene/%.o: scene/%.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(OPT) $(WARN) -fPIC -fvisibility=hidden -DLBK_BAKE_BUILDING_SHARED $(TOOL_INC) -MMD -MP -c $< -o $@
$(BUILD)/pic/scene/%.o: scene/%.cc
	@mkdir -p $(@D)
	$(CXX) -std=c++17 $(OPT) -w -fPIC -fvisibility=hidden -DLBK_BAKE_BUILDING_SHARED $(TOOL_INC) -MMD -MP -c $< -o $@
$(BUILD)/pic/bake/%.o: bake/%.cc
	@mkdir -p $(@D)
	$(CXX) -std=c++17 $(OPT) -w -fPIC -fvisibility=hidden -DLBK_BAKE_BUILDING_SHARED $(TOOL_INC) -MMD -MP -c $< -o $@
$(BUILD)/rel/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(OPT) $(WARN) $(TOOL_INC) -MMD -MP -c $< -o $@
$(BUILD)/asan/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O1 -g $(SAN) $(WARN) $(TOOL_INC) -MMD -MP -c $< -o $@
$(BUILD)/rel/%.o: %.cc
	@mkdir -p $(@D)
	$(CXX) -std=c++17 $(OPT) $(CXXWARN) $(TOOL_CXXINC) -MMD -MP -c $< -o $@
$(BUILD)/asan/%.o: %.cc
	@mkdir -p $(@D)
	$(CXX) -std=c++17 -O1 -g $(SAN) $(CXXWARN) $(TOOL_CXXINC) -MMD -MP -c $< -o $@

# ---- the library ----------------------------------------------------------------------------
$(BUILD)/liblbk.a: $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^
$(BUILD)/liblbk.so: $(LIB_PIC)
	$(CC) -shared -Wl,-soname,liblbk.so.1 -o $@ $^ $(LIB_LIBS)
# The library's version, from LBK_LIBRARY_VERSION_{MAJOR,MINOR,PATCH} in lbk.h (never the format's).
LIB_VERSION := $(shell for k in MAJOR MINOR PATCH; do sed -n "s/^\#define LBK_LIBRARY_VERSION_$$k  *\([0-9][0-9]*\).*/\1/p" libformat/include/lbk/lbk.h; done | paste -sd. -)
BAKE_VERSION := $(shell for k in MAJOR MINOR PATCH; do sed -n "s/^\#define LBK_BAKE_LIBRARY_VERSION_$$k  *\([0-9][0-9]*\).*/\1/p" bake/include/lbk/bake.h; done | paste -sd. -)
$(BUILD)/lbk.pc: Makefile libformat/include/lbk/lbk.h
	@mkdir -p $(@D)
	@printf 'prefix=%s\nincludedir=$${prefix}/include\nlibdir=$${prefix}/lib\n\nName: lbk\nDescription: light bake kit container library\nVersion: %s\nRequires.private: libzstd libxxhash\nCflags: -I$${includedir}\nLibs: -L$${libdir} -llbk\nLibs.private: -lm\n' '$(PREFIX)' '$(LIB_VERSION)' > $@
lib: $(BUILD)/liblbk.a $(BUILD)/liblbk.so $(BUILD)/lbk.pc

# ---- the baker library (lbk/bake.h): over liblbk, with the heavy dependencies ------------------
$(BUILD)/liblbkbake.a: $(BAKE_OBJ)
	@rm -f $@
	ar rcs $@ $^
$(BUILD)/liblbkbake.so: $(BAKE_PIC) $(BUILD)/liblbk.so
	$(CXX) -shared -Wl,-soname,liblbkbake.so.1 -Wl,--no-undefined -Wl,-rpath,'$$ORIGIN' -o $@ $(BAKE_PIC) \
	    -L$(BUILD) -llbk $(BAKE_LIBS)
$(BUILD)/lbk-bake.pc: Makefile bake/include/lbk/bake.h
	@mkdir -p $(@D)
	@printf 'prefix=%s\nincludedir=$${prefix}/include\nlibdir=$${prefix}/lib\n\nName: lbk-bake\nDescription: light bake kit baker library\nVersion: %s\nRequires: lbk\nCflags: -I$${includedir}\nLibs: -L$${libdir} -llbkbake\nLibs.private: %s -lstdc++\n' '$(PREFIX)' '$(BAKE_VERSION)' '$(BAKE_LIBS)' > $@
bake-lib: $(BUILD)/liblbkbake.a $(BUILD)/liblbkbake.so $(BUILD)/lbk-bake.pc

# ---- the viewer's page as C arrays (tools/view/view.h tl_view_assets) ------------------------
$(VIEW_ASSETS_C): $(VIEW_FILES) Makefile
	@mkdir -p $(@D)
	@{ echo '/* generated by make from viewer/ (do not edit) */'; echo '#include "tools/view/view.h"'; \
	  i=0; for f in $(VIEW_FILES); do echo "static const unsigned char a$$i[] = {"; \
	    od -An -v -tx1 $$f | sed 's/\([0-9a-f][0-9a-f]\)/0x\1,/g'; echo "};"; i=$$((i+1)); done; \
	  echo 'const tl_view_asset tl_view_assets[] = {'; \
	  i=0; for f in $(VIEW_FILES); do echo "    {\"$${f#viewer/}\", a$$i, sizeof a$$i},"; i=$$((i+1)); done; \
	  echo '};'; echo 'const size_t tl_view_asset_count = sizeof tl_view_assets / sizeof tl_view_assets[0];'; \
	} > $@.tmp && mv $@.tmp $@

# ---- the CLI --------------------------------------------------------------------------------
$(BUILD)/lbk: $(BUILD)/rel/$(TOOL_MAIN:.c=.o) $(TOOL_OBJ) $(BUILD)/liblbkbake.a $(BUILD)/liblbk.a
	$(CXX) -o $@ $(BUILD)/rel/$(TOOL_MAIN:.c=.o) $(TOOL_OBJ) $(BUILD)/liblbkbake.a $(BUILD)/liblbk.a $(TOOL_LIBS)
$(BUILD)/lbk-asan: $(BUILD)/asan/$(TOOL_MAIN:.c=.o) $(TOOL_ASAN) $(LIB_ASAN)
	$(CXX) $(SAN) -o $@ $^ $(TOOL_LIBS)

# ---- the GPU path (gpu/) --------------------------------------------------------------------
# Built when the Vulkan headers and glslang are there (make deps installs them); without them
# tests/gpu/test_gpu.c compiles to SKIPPED tests. Shaders become C arrays (glslang --vn).
GLSLANG    ?= glslangValidator
HAVE_VULKAN := $(shell test -f /usr/include/vulkan/vulkan.h && command -v $(GLSLANG) >/dev/null 2>&1 && echo 1)
GPU_SHADERS := $(sort $(wildcard gpu/shaders/*.comp))
GPU_SPV_H   := $(GPU_SHADERS:gpu/shaders/%.comp=$(BUILD)/gpu/%.spv.h)
GPU_HOST    := $(sort $(wildcard gpu/host/*.c))
$(BUILD)/gpu/%.spv.h: gpu/shaders/%.comp $(wildcard gpu/shaders/*.glsl)
	@mkdir -p $(@D)
	$(GLSLANG) -V --target-env vulkan1.1 --vn $*_spv -o $@ $< >/dev/null
# test_gpu and bench_gpu compile differently with and without Vulkan: rebuild them when that changes.
GPU_STAMP := $(BUILD)/gpu/vulkan-$(if $(HAVE_VULKAN),on,off)
$(GPU_STAMP):
	@mkdir -p $(@D) && rm -f $(BUILD)/gpu/vulkan-* && touch $@
$(BUILD)/tests/test_gpu $(BUILD)/bench/bench_gpu: $(GPU_STAMP)
ifeq ($(HAVE_VULKAN),1)
GPU_REL  := $(GPU_HOST:%.c=$(BUILD)/rel/%.o)
GPU_ASAN := $(GPU_HOST:%.c=$(BUILD)/asan/%.o)
$(GPU_REL) $(GPU_ASAN): $(GPU_SPV_H)
$(GPU_REL) $(GPU_ASAN) $(BUILD)/tests/test_gpu: TOOL_INC += -I$(BUILD)/gpu -DLBK_HAVE_VULKAN=1
$(BUILD)/tests/test_gpu: $(GPU_ASAN)
$(BUILD)/tests/test_gpu: TEST_EXTRA = $(GPU_ASAN) -lvulkan
$(BUILD)/bench/bench_gpu: $(GPU_REL)
$(BUILD)/bench/bench_gpu: TOOL_INC += -I$(BUILD)/gpu -DLBK_HAVE_VULKAN=1
$(BUILD)/bench/bench_gpu: BENCH_EXTRA = $(GPU_REL) -lvulkan
$(BUILD)/lbk-gpu-apply: gpu/lbk_gpu_apply.c $(GPU_REL) $(BUILD)/liblbk.a
	$(CC) $(CSTD) $(OPT) $(WARN) $(TOOL_INC) -I$(BUILD)/gpu -DLBK_HAVE_VULKAN=1 -o $@ $< $(GPU_REL) $(BUILD)/liblbk.a -lvulkan $(LIB_LIBS)
gpu: $(BUILD)/lbk-gpu-apply
else
gpu:
	@echo "lbk: the GPU path needs $(GPU_PKGS) (make deps installs them)"; exit 1
endif

# ---- tests (ASan + UBSan) ------------------------------------------------------------------
TEST_SUPPORT_OBJ := $(TEST_SUPPORT:%.c=$(BUILD)/asan/%.o)
$(TEST_SUPPORT_OBJ): TOOL_INC += -Itests
# A test binary is named after its source, wherever under tests/ it lives.
test_src_of = $(foreach s,$(TEST_SRC),$(if $(filter $(1).c,$(notdir $(s))),$(s)))
.SECONDEXPANSION:
$(BUILD)/tests/%: $$(call test_src_of,$$*) $(TEST_SUPPORT_OBJ) $(TOOL_ASAN) $(LIB_ASAN)
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O1 -g $(SAN) $(WARN) $(TOOL_INC) -Itests -c $< -o $@.o
	$(CXX) $(SAN) -o $@ $@.o $(TEST_SUPPORT_OBJ) $(TOOL_ASAN) $(LIB_ASAN) $(TEST_EXTRA) $(TOOL_LIBS) -lcmocka

# The install check: the libraries installed into $(BUILD)/inst, programs built against them with
# pkg-config only, linked once with the .so and once with the .a: install_check (liblbk) and
# bake_check (liblbkbake: includes only lbk/bake.h, compares with the installed lbk bake).
INST := $(abspath $(BUILD))/inst
INST_PC := PKG_CONFIG_PATH=$(INST)/lib/pkgconfig pkg-config
install-check: all
	@rm -rf $(INST)
	@$(MAKE) --no-print-directory install PREFIX=$(INST) >/dev/null
	@mkdir -p $(BUILD)/tests
	$(CC) $(CSTD) $(WARN) tests/install/install_check.c -o $(BUILD)/tests/install_check_shared \
	    $$($(INST_PC) --cflags --libs lbk) -Wl,-rpath,$(INST)/lib -lcmocka
	$(CC) $(CSTD) $(WARN) tests/install/install_check.c -o $(BUILD)/tests/install_check_static \
	    $$($(INST_PC) --cflags lbk) $(INST)/lib/liblbk.a \
	    $$($(INST_PC) --static --libs-only-other --libs-only-l lbk | sed 's/-llbk//') -lcmocka
	$(CC) $(CSTD) $(WARN) -DLBK_CLI='"$(INST)/bin/lbk"' -DLBK_BAKE_PC_VERSION="\"$$($(INST_PC) --modversion lbk-bake)\"" \
	    tests/install/bake_check.c -o $(BUILD)/tests/bake_check_shared \
	    $$($(INST_PC) --cflags --libs lbk-bake) -Wl,-rpath,$(INST)/lib -lcmocka
	$(CC) $(CSTD) $(WARN) -DLBK_CLI='"$(INST)/bin/lbk"' -DLBK_BAKE_PC_VERSION="\"$$($(INST_PC) --modversion lbk-bake)\"" \
	    tests/install/bake_check.c -o $(BUILD)/tests/bake_check_static \
	    $$($(INST_PC) --cflags lbk-bake) $(INST)/lib/liblbkbake.a $(INST)/lib/liblbk.a \
	    $$($(INST_PC) --static --libs-only-other --libs-only-l lbk-bake | sed 's/-llbkbake//; s/-llbk\b//') -lcmocka

# The Khronos glTF-Validator (npm package, runs under node) for the `lbk export --gltf` check of
# tests/tools/gltf_validator.sh, installed into the build folder at a pinned version. Without npm
# (and not root to install it) the check is reported SKIPPED.
GLTF_VALIDATOR_VERSION := 2.0.0-dev.3.10
GLTF_VALIDATOR := $(BUILD)/npm/node_modules/gltf-validator
$(GLTF_VALIDATOR)/package.json:
	@mkdir -p $(BUILD)/npm
	npm install --prefix $(BUILD)/npm --no-audit --no-fund --loglevel=error gltf-validator@$(GLTF_VALIDATOR_VERSION)
gltf-validator:
	@if ! command -v npm >/dev/null 2>&1 && [ "$$(id -u)" = 0 ]; then \
	  echo "lbk: installing npm (for the glTF-Validator check)"; \
	  (apt-get update -qq || true) && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq npm >/dev/null || true; \
	fi
	@if command -v npm >/dev/null 2>&1 && command -v node >/dev/null 2>&1; then \
	  $(MAKE) --no-print-directory $(GLTF_VALIDATOR)/package.json; \
	else echo "lbk: npm/node not found: the glTF-Validator check will be SKIPPED (apt-get install npm)"; fi

test: deps-test
	@$(MAKE) --no-print-directory test-build
	@$(MAKE) --no-print-directory gltf-validator
	@LBK=$(BUILD)/lbk-asan LBK_FAULT_SHIM=$(BUILD)/fault_shim.so BUILD=$(BUILD) FUZZ=$(BUILD)/fuzz_container TSAN_BIN=$(BUILD)/tsan/bin \
	  FUZZ_MORE="$(foreach h,$(FUZZ_HARNESSES),$(h:fuzz_%=%)=$(BUILD)/$(h))" \
	  GLTF_VALIDATOR=$$(test -f $(GLTF_VALIDATOR)/package.json && echo $(GLTF_VALIDATOR)) \
	  sh tests/run.sh $(TESTS) $(STRUCTURE_CHECKS) install_check_shared install_check_static install_lib_check \
	    bake_check_shared bake_check_static; \
	st=$$?; n=$$(sed -n 's/^\[  SKIPPED \] \([0-9]*\) test(s).*/\1/p' $(BUILD)/tests/test_gpu.log 2>/dev/null); \
	if [ "$${n:-0}" -gt 0 ]; then echo "tests: $$n GPU tests SKIPPED, not run: $$(grep -m1 -o 'SKIPPED: .*' $(BUILD)/tests/test_gpu.log)"; fi; \
	exit $$st
check: test

# ---- ThreadSanitizer: the determinism cases of tests/tsan/determinism.list -------------------
# Their own objects under $(BUILD)/tsan (TSan cannot be mixed with ASan). Embree's internal
# threads are not instrumented: tests/tsan/suppressions.txt silences reports inside Embree and
# TBB only, never in lbk code.
.PHONY: tsan
TSAN      := -fsanitize=thread -fno-omit-frame-pointer
TSAN_TESTS := $(sort $(shell sed -n 's/^\(test_[a-z0-9_]*\).*/\1/p' tests/tsan/determinism.list))
LIB_TSAN  := $(LIB_SRC:%.c=$(BUILD)/tsan/%.o)
TOOL_TSAN := $(filter-out $(BUILD)/tsan/$(TOOL_MAIN:.c=.o),$(TOOL_CSRC:%.c=$(BUILD)/tsan/%.o)) $(TOOL_CXXSRC:%.cc=$(BUILD)/tsan/%.o)
TEST_SUPPORT_TSAN := $(TEST_SUPPORT:%.c=$(BUILD)/tsan/%.o) $(BUILD)/tsan/tests/tsan/case_filter.o
$(TEST_SUPPORT_TSAN): TOOL_INC += -Itests
# only pattern rules name them: keep make from deleting them as intermediates
.SECONDARY: $(LIB_TSAN) $(TOOL_TSAN)
$(BUILD)/tsan/libformat/%.o: libformat/%.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O1 -g $(LIB_FP) $(TSAN) $(WARN) $(LIB_INC) -MMD -MP -c $< -o $@
$(BUILD)/tsan/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O1 -g $(TSAN) $(WARN) $(TOOL_INC) -MMD -MP -c $< -o $@
$(BUILD)/tsan/%.o: %.cc
	@mkdir -p $(@D)
	$(CXX) -std=c++17 -O1 -g $(TSAN) $(CXXWARN) $(TOOL_CXXINC) -MMD -MP -c $< -o $@
$(BUILD)/tsan/bin/%: $$(call test_src_of,$$*) $(TEST_SUPPORT_TSAN) $(TOOL_TSAN) $(LIB_TSAN)
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O1 -g $(TSAN) $(WARN) $(TOOL_INC) -Itests -c $< -o $@.o
	$(CXX) $(TSAN) -o $@ $@.o $(TEST_SUPPORT_TSAN) $(TOOL_TSAN) $(LIB_TSAN) $(TOOL_LIBS) -lcmocka \
	    -Wl,--wrap=_cmocka_run_group_tests
tsan: deps-test
	@$(MAKE) --no-print-directory $(TSAN_TESTS:%=$(BUILD)/tsan/bin/%)
	@BUILD=$(BUILD) TSAN_BIN=$(BUILD)/tsan/bin sh tests/run.sh

# The house rules (tests/structure/: includes by layer, file and function sizes), run by
# tests/run.sh like the test binaries through a one-line wrapper.
STRUCTURE_CHECKS := $(patsubst tests/structure/%.sh,%,$(sort $(wildcard tests/structure/*.sh)))
$(STRUCTURE_CHECKS:%=$(BUILD)/tests/%): $(BUILD)/tests/%: tests/structure/%.sh
	@mkdir -p $(@D)
	@printf '#!/bin/sh\nexec sh "%s/$<" "$$@"\n' "$(CURDIR)" > $@ && chmod +x $@

# What `make test` builds (after TSAN_TESTS is defined); make test builds it through a sub-make,
# so that HAVE_VULKAN sees what deps-test installed.
test-build: $(BUILD)/lbk $(BUILD)/lbk-asan $(TESTS:%=$(BUILD)/tests/%) $(BUILD)/fuzz_container $(BUILD)/fault_shim.so \
            $(FUZZ_HARNESSES:%=$(BUILD)/%) \
            install-check install-lib-check $(TSAN_TESTS:%=$(BUILD)/tsan/bin/%) \
            $(if $(HAVE_VULKAN),$(BUILD)/lbk-gpu-apply) $(STRUCTURE_CHECKS:%=$(BUILD)/tests/%)


# ---- liblbk alone: zstd, xxHash and a C compiler, nothing else -----------------------------
# install-lib builds and installs only the container library (static, shared, headers, lbk.pc).
# install-lib-check installs it into a throwaway DESTDIR from a build folder of its own, checks
# that nothing but libformat was compiled and that liblbk.so needs only zstd, xxHash and libc/libm,
# and builds tests/install/install_check.c against the staged copy (run by tests/run.sh).
.PHONY: install-lib install-lib-check
install-lib: $(BUILD)/liblbk.a $(BUILD)/liblbk.so $(BUILD)/lbk.pc
	install -d $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/include/lbk
	install -m 644 $(BUILD)/liblbk.a $(DESTDIR)$(PREFIX)/lib/liblbk.a
	install -m 755 $(BUILD)/liblbk.so $(DESTDIR)$(PREFIX)/lib/liblbk.so.1
	ln -sf liblbk.so.1 $(DESTDIR)$(PREFIX)/lib/liblbk.so
	install -m 644 libformat/include/lbk/*.h $(DESTDIR)$(PREFIX)/include/lbk/
	sed 's|^prefix=.*|prefix=$(PREFIX)|' $(BUILD)/lbk.pc > $(DESTDIR)$(PREFIX)/lib/pkgconfig/lbk.pc
LIBONLY := $(BUILD)/lib-only
LIBSTAGE := $(abspath $(LIBONLY))/stage
LIBPC = PKG_CONFIG_PATH=$(LIBSTAGE)/opt/lbk/lib/pkgconfig pkg-config --define-variable=prefix=$(LIBSTAGE)/opt/lbk
install-lib-check:
	@rm -rf $(LIBSTAGE) && mkdir -p $(BUILD)/tests
	@$(MAKE) --no-print-directory install-lib BUILD=$(LIBONLY) PREFIX=/opt/lbk DESTDIR=$(LIBSTAGE) >/dev/null
	@built=$$(cd $(LIBONLY) && find . -name '*.o' ! -path './*/libformat/*'); \
	  if [ -n "$$built" ]; then echo "install-lib compiled more than libformat:" $$built; exit 1; fi
	@needed=$$(readelf -d $(LIBSTAGE)/opt/lbk/lib/liblbk.so.1 | sed -n 's/.*Shared library: \[\(.*\)\]/\1/p' | sort | tr '\n' ' '); \
	  case "$$needed" in "libc.so.6 libm.so.6 libxxhash.so.0 libzstd.so.1 ") ;; \
	  *) echo "liblbk.so needs more than zstd, xxHash, libc and libm: $$needed"; exit 1;; esac
	$(CC) $(CSTD) $(WARN) tests/install/install_check.c -o $(BUILD)/tests/install_lib_check \
	    $$($(LIBPC) --cflags lbk) $(LIBSTAGE)/opt/lbk/lib/liblbk.a \
	    $$($(LIBPC) --static --libs-only-other --libs-only-l lbk | sed 's/-llbk//') -lcmocka

# ---- fault injection: an LD_PRELOAD library that fails or kills at the N-th write call -------
# (tests/faults/fault_shim.c; test_faults runs the CLI's writers through it)
$(BUILD)/fault_shim.so: tests/faults/fault_shim.c
	@mkdir -p $(@D)
	$(CC) -std=c11 -O1 -g $(WARN) -fPIC -shared $< -o $@ -ldl

# ---- fuzzing (clang libFuzzer) --------------------------------------------------------------
FUZZ_FLAGS := -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined -g -O1
$(BUILD)/fuzz_container: tests/fuzz/fuzz_container.c $(LIB_SRC)
	@mkdir -p $(@D)
	$(CLANG) $(CSTD) $(FUZZ_FLAGS) $(LIB_FP) $(WARN) $(LIB_INC) -o $@ $^ $(LIB_LIBS)
# The other harnesses (tests/fuzz/README.md): their objects instrumented once under fuzz-obj/.
CLANGXX   ?= clang++
FUZZ_OBJ_FLAGS := -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined -g -O1
FUZZ_LIB_OBJ := $(LIB_SRC:%.c=$(BUILD)/fuzz-obj/%.o)
FUZZ_HARNESSES := fuzz_gltf fuzz_exr fuzz_profile fuzz_part
$(BUILD)/fuzz-obj/libformat/%.o: libformat/%.c
	@mkdir -p $(@D)
	$(CLANG) $(CSTD) $(FUZZ_OBJ_FLAGS) $(LIB_FP) $(WARN) $(LIB_INC) -MMD -MP -c $< -o $@
$(BUILD)/fuzz-obj/%.o: %.c
	@mkdir -p $(@D)
	$(CLANG) $(CSTD) $(FUZZ_OBJ_FLAGS) $(WARN) $(TOOL_INC) -Wno-unused-command-line-argument -MMD -MP -c $< -o $@
$(BUILD)/fuzz-obj/%.o: %.cc
	@mkdir -p $(@D)
	$(CLANGXX) -std=c++17 $(FUZZ_OBJ_FLAGS) $(CXXWARN) $(TOOL_CXXINC) -MMD -MP -c $< -o $@
FUZZ_GLTF_OBJ := $(addprefix $(BUILD)/fuzz-obj/,tests/fuzz/fuzz_gltf.o scene/gltf_import.o scene/scene.o \
                   scene/exr_read.o)
FUZZ_EXR_OBJ := $(addprefix $(BUILD)/fuzz-obj/,tests/fuzz/fuzz_exr.o scene/exr_read.o scene/scene.o)
FUZZ_PROFILE_OBJ := $(addprefix $(BUILD)/fuzz-obj/,tests/fuzz/fuzz_profile.o tools/convert/profile.o \
                      tools/common/lmap_decode.o tools/common/error_util.o tools/common/astc_codec.o)
# the part harness merges, so it links the whole baker
FUZZ_PART_OBJ := $(BUILD)/fuzz-obj/tests/fuzz/fuzz_part.o $(BAKE_CSRC:%.c=$(BUILD)/fuzz-obj/%.o) \
                 $(BAKE_CXXSRC:%.cc=$(BUILD)/fuzz-obj/%.o)
$(BUILD)/fuzz_gltf: $(FUZZ_GLTF_OBJ) $(FUZZ_LIB_OBJ)
	$(CLANGXX) -fsanitize=fuzzer,address,undefined -o $@ $^ $(BAKE_LIBS) $(LIB_LIBS)
$(BUILD)/fuzz_exr: $(FUZZ_EXR_OBJ) $(FUZZ_LIB_OBJ)
	$(CLANGXX) -fsanitize=fuzzer,address,undefined -o $@ $^ $(BAKE_LIBS) $(LIB_LIBS)
$(BUILD)/fuzz_profile: $(FUZZ_PROFILE_OBJ) $(FUZZ_LIB_OBJ)
	$(CLANGXX) -fsanitize=fuzzer,address,undefined -o $@ $^ -lastcenc $(LIB_LIBS)
$(BUILD)/fuzz_part: $(FUZZ_PART_OBJ) $(FUZZ_LIB_OBJ)
	$(CLANGXX) -fsanitize=fuzzer,address,undefined -o $@ $^ $(BAKE_LIBS) $(LIB_LIBS)
-include $(wildcard $(BUILD)/fuzz-obj/*/*.d $(BUILD)/fuzz-obj/*/*/*.d)
# The seed corpus (tests/fuzz/README.md): the golden files, the containers make_corpus.c builds
# (every section type) and two small real bakes. Regenerate by hand; the files are committed.
.PHONY: fuzz-corpus
fuzz-corpus: $(BUILD)/liblbk.a $(BUILD)/lbk
	$(CC) $(CSTD) -O1 $(WARN) $(LIB_INC) tests/fuzz/make_corpus.c $(BUILD)/liblbk.a $(LIB_LIBS) -o $(BUILD)/make_corpus
	cp tests/golden/*.lbk tests/fuzz/corpus/
	$(BUILD)/make_corpus
	$(BUILD)/lbk bake tests/fuzz/sets_scene.gltf -o tests/fuzz/corpus/bake_sets.lbk -q --threads 2 \
	    --texel-density 2 --samples 8 --glg-spacing 3
	$(BUILD)/lbk bake scenes/cornell_box/CornellBox-Original.gltf -o tests/fuzz/corpus/bake_cornell.lbk -q --threads 2 \
	    --texel-density 2 --samples 8 --glg-spacing 2.5
	$(BUILD)/lbk bake scenes/cornell_box/CornellBox-Original.gltf -o tests/fuzz/corpus/bake_cornell_terr.lbk -q --threads 2 \
	    --texel-density 2 --samples 8 --glg-spacing 2.5 --error-map
	@d=$$(mktemp -d) && for n in 1 2; do \
	  $(BUILD)/lbk plan tests/fuzz/part_scene.gltf -o $$d/o.lbk --plan $$d/p$$n.json --units $$n --samples 4 --target-error none \
	    --texel-density 2 --glg-spacing 8 -q && \
	  $(BUILD)/lbk bake-unit $$d/p$$n.json 0 -o tests/fuzz/corpus_part/unit0of$$n.lbkpart -q || exit 1; done; rm -rf $$d
fuzz: deps-test
	@$(MAKE) --no-print-directory $(BUILD)/fuzz_container
	@mkdir -p $(BUILD)/fuzz-corpus
	$(BUILD)/fuzz_container -max_total_time=$${FUZZ_SECONDS:-60} -max_len=65536 -artifact_prefix=$(BUILD)/ $(BUILD)/fuzz-corpus tests/fuzz/corpus
	@for h in $(FUZZ_HARNESSES); do n=$${h#fuzz_}; $(MAKE) --no-print-directory $(BUILD)/$$h && mkdir -p $(BUILD)/fuzz-corpus-$$n && \
	  $(BUILD)/$$h -max_total_time=$${FUZZ_SECONDS:-60} -max_len=65536 -rss_limit_mb=2048 -artifact_prefix=$(BUILD)/ \
	    $(BUILD)/fuzz-corpus-$$n \
	    tests/fuzz/corpus_$$n || exit 1; done
# Hours of fuzzing (FUZZ_HOURS, default 1, per harness, one after the other): a finding stops it
# with the reproducer in build/ (crash-*, leak-*, timeout-*); what the runs found stays in
# build/fuzz-corpus*.
.PHONY: fuzz-long
fuzz-long:
	@$(MAKE) --no-print-directory fuzz FUZZ_SECONDS=$$(( $${FUZZ_HOURS:-1} * 3600 ))

# ---- benchmarks -----------------------------------------------------------------------------
$(BUILD)/bench/%: bench/%.c $(TOOL_OBJ) $(BUILD)/liblbkbake.a $(BUILD)/liblbk.a
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O2 -g $(WARN) $(TOOL_INC) -c $< -o $@.o
	$(CXX) -o $@ $@.o $(TOOL_OBJ) $(BUILD)/liblbkbake.a $(BUILD)/liblbk.a $(BENCH_EXTRA) $(TOOL_LIBS)
# The BC codecs against Mesa's (llvmpipe, surfaceless EGL): optional, needs libegl-dev libgl-dev.
mesa-bc-check: $(TOOL_OBJ) $(BUILD)/liblbkbake.a $(BUILD)/liblbk.a
	@mkdir -p $(BUILD)/bench
	$(CC) $(CSTD) -O2 -g $(WARN) $(TOOL_INC) -c bench/mesa_bc_check.c -o $(BUILD)/bench/mesa_bc_check.o
	$(CXX) -o $(BUILD)/bench/mesa_bc_check $(BUILD)/bench/mesa_bc_check.o $(TOOL_OBJ) $(BUILD)/liblbkbake.a \
	    $(BUILD)/liblbk.a $(TOOL_LIBS) -lEGL -lGL
	$(BUILD)/bench/mesa_bc_check
bench: deps-tools deps-bench
	@$(MAKE) --no-print-directory $(BUILD)/lbk $(BENCHES:%=$(BUILD)/bench/%)
	@for b in $(BENCHES); do echo "== $$b"; $(BUILD)/bench/$$b || exit 1; done
	@echo "== blender_import"; sh bench/blender_import.sh $(BUILD)/lbk $(BUILD)/bench-blender
	@echo "== bench-cycles"; $(MAKE) --no-print-directory bench-cycles
	@echo "== render (lbk render vs Blender Cycles)"; $(MAKE) --no-print-directory bench-render

# lbk against Cycles (bench/cycles/README.md). LBK_TREE=/path/to/other/checkout compares that
# tree's baker instead: its build/lbk (built there first) and texel_dump linked against its
# baker objects, so the rebuilt layout is the one its lbk bakes.
ifdef LBK_TREE
CYC_LBK  := $(LBK_TREE)/$(BUILD)/lbk
CYC_DUMP := $(BUILD)/bench/cycles/texel_dump-tree
$(CYC_DUMP): bench/cycles/texel_dump.c FORCE
	@$(MAKE) --no-print-directory -C $(LBK_TREE) $(BUILD)/lbk
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O2 -g $(WARN) -I$(LBK_TREE)/libformat/include -I$(LBK_TREE)/bake/include -I$(LBK_TREE) \
	    -I/usr/include/draco -I/usr/include/stb -c $< -o $@.o
	$(CXX) -o $@ $@.o $$(ls $(LBK_TREE)/$(BUILD)/rel/scene/*.o $(LBK_TREE)/$(BUILD)/rel/bake/*/*.o | sort) $(LBK_TREE)/$(BUILD)/liblbk.a $(TOOL_LIBS)
FORCE:
else
CYC_LBK  ?= $(BUILD)/lbk
CYC_DUMP ?= $(BUILD)/bench/cycles/texel_dump
endif
bench-cycles: deps-tools deps-bench
	@$(MAKE) --no-print-directory $(if $(LBK_TREE),,$(BUILD)/lbk) $(CYC_DUMP)
	@LBK=$${LBK:-$(CYC_LBK)} LBK_TEXEL_DUMP=$${LBK_TEXEL_DUMP:-$(CYC_DUMP)} python3 bench/cycles/run.py

# lbk render against converged Cycles renders (bench/render/README.md); the Cycles scene converter
# comes from LBK_CYCLES_HARNESS (default bench/cycles).
LBK_CYCLES_HARNESS ?= bench/cycles
bench-render: $(BUILD)/lbk
	@LBK_CYCLES_HARNESS=$(LBK_CYCLES_HARNESS) python3 bench/render/run.py --lbk $(BUILD)/lbk --out $(BUILD)/bench-render $(BENCH_RENDER_ARGS)

# ---- demo -----------------------------------------------------------------------------------
demo: deps-tools
	@$(MAKE) --no-print-directory $(BUILD)/lbk
	@sh scenes/demo.sh $(BUILD)

# ---- install --------------------------------------------------------------------------------
install: all
	install -d $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/include/lbk
	install -m 755 $(BUILD)/lbk $(DESTDIR)$(PREFIX)/bin/lbk
	install -m 644 $(BUILD)/liblbk.a $(DESTDIR)$(PREFIX)/lib/liblbk.a
	install -m 755 $(BUILD)/liblbk.so $(DESTDIR)$(PREFIX)/lib/liblbk.so.1
	ln -sf liblbk.so.1 $(DESTDIR)$(PREFIX)/lib/liblbk.so
	install -m 644 libformat/include/lbk/*.h $(DESTDIR)$(PREFIX)/include/lbk/
	sed 's|^prefix=.*|prefix=$(PREFIX)|' $(BUILD)/lbk.pc > $(DESTDIR)$(PREFIX)/lib/pkgconfig/lbk.pc
	install -m 644 $(BUILD)/liblbkbake.a $(DESTDIR)$(PREFIX)/lib/liblbkbake.a
	install -m 755 $(BUILD)/liblbkbake.so $(DESTDIR)$(PREFIX)/lib/liblbkbake.so.1
	ln -sf liblbkbake.so.1 $(DESTDIR)$(PREFIX)/lib/liblbkbake.so
	install -m 644 bake/include/lbk/*.h $(DESTDIR)$(PREFIX)/include/lbk/
	sed 's|^prefix=.*|prefix=$(PREFIX)|' $(BUILD)/lbk-bake.pc > $(DESTDIR)$(PREFIX)/lib/pkgconfig/lbk-bake.pc
	install -d $(DESTDIR)$(PREFIX)/share/lbk/profiles
	install -m 644 tools/convert/profiles/*.profile $(DESTDIR)$(PREFIX)/share/lbk/profiles/

clean:
	rm -rf $(BUILD)

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
