# lbk — light bake kit. `make demo` and `make test` do all set-up on a fresh Debian machine.
# Sources are picked up by wildcard: adding a file to a folder needs no edit here.

PREFIX   ?= /usr/local
BUILD    ?= build
CC       ?= cc
CXX      ?= c++
CLANG    ?= clang

# Debian packages the build needs; `make deps` installs the missing ones when run as root.
DEB_PKGS := build-essential pkg-config libzstd-dev libxxhash-dev libembree-dev libopenexr-dev \
            libdraco-dev libtinygltf-dev libstb-dev nlohmann-json3-dev libqhull-dev libspng-dev \
            libcjson-dev libcmocka-dev clang libclang-rt-14-dev libastcenc-dev

WARN     := -Wall -Wextra -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Wno-unused-parameter
CSTD     := -std=c11 -D_POSIX_C_SOURCE=200809L -D_DEFAULT_SOURCE
OPT      ?= -O2 -g
SAN      := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined

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

LIB_SRC   := $(sort $(wildcard libformat/src/*.c))
BAKE_CSRC := $(sort $(wildcard bake/*/*.c))
BAKE_CXXSRC := $(sort $(wildcard bake/*/*.cc))
TOOL_CSRC := $(sort $(wildcard cli/*.c bake/*/*.c tools/*/*.c))
TOOL_CXXSRC := $(BAKE_CXXSRC) $(sort $(wildcard tools/*/*.cc))
TOOL_MAIN := cli/main.c
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

.PHONY: all lib bake-lib deps demo test check bench mesa-bc-check fuzz install install-check clean help gltf-validator
all: $(BUILD)/lbk $(BUILD)/liblbk.a $(BUILD)/liblbk.so $(BUILD)/lbk.pc \
     $(BUILD)/liblbkbake.a $(BUILD)/liblbkbake.so $(BUILD)/lbk-bake.pc

help:
	@echo "make            build liblbk.a/.so + lbk.pc, liblbkbake.a/.so + lbk-bake.pc and the lbk CLI into $(BUILD)/"
	@echo "make demo       install missing packages, bake the embedded scene, inspect it, write a PNG"
	@echo "make test       install missing packages, build with ASan+UBSan, run the whole suite"
	@echo "make bench      benchmarks, printed as ratios against baselines measured in the same run"
	@echo "make mesa-bc-check  BC6H/BC4 codecs against Mesa's (optional: libegl-dev libgl-dev)"
	@echo "make fuzz       libFuzzer harness for the container reader (clang)"
	@echo "make install PREFIX=/usr/local"

# ---- dependencies -------------------------------------------------------------------------
deps:
	@missing=$$(for p in $(DEB_PKGS); do dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'install ok installed' || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    echo "lbk: installing missing Debian packages:" $$missing; \
	    (apt-get update -qq || true) && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing >/dev/null; \
	  else \
	    echo "lbk: missing Debian packages. Run as root:"; \
	    echo "  sudo apt-get install -y" $$missing; exit 1; \
	  fi; \
	fi

# ---- compile rules --------------------------------------------------------------------------
$(BUILD)/rel/libformat/%.o: libformat/%.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(OPT) $(WARN) $(LIB_INC) -MMD -MP -c $< -o $@
$(BUILD)/pic/libformat/%.o: libformat/%.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(OPT) $(WARN) -fPIC -fvisibility=hidden -DLBK_BUILDING_SHARED $(LIB_INC) -MMD -MP -c $< -o $@
$(BUILD)/asan/libformat/%.o: libformat/%.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O1 -g $(SAN) $(WARN) $(LIB_INC) -MMD -MP -c $< -o $@
$(BUILD)/pic/bake/%.o: bake/%.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(OPT) $(WARN) -fPIC -fvisibility=hidden -DLBK_BAKE_BUILDING_SHARED $(TOOL_INC) -MMD -MP -c $< -o $@
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
	$(CXX) -std=c++17 $(OPT) -w $(TOOL_INC) -MMD -MP -c $< -o $@
$(BUILD)/asan/%.o: %.cc
	@mkdir -p $(@D)
	$(CXX) -std=c++17 -O1 -g $(SAN) -w $(TOOL_INC) -MMD -MP -c $< -o $@

# ---- the library ----------------------------------------------------------------------------
$(BUILD)/liblbk.a: $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^
$(BUILD)/liblbk.so: $(LIB_PIC)
	$(CC) -shared -Wl,-soname,liblbk.so.1 -o $@ $^ $(LIB_LIBS)
# The library's version, from LBK_LIBRARY_VERSION_{MAJOR,MINOR,PATCH} in lbk.h (never the format's).
LIB_VERSION := $(shell for k in MAJOR MINOR PATCH; do sed -n "s/^\#define LBK_LIBRARY_VERSION_$$k  *\([0-9][0-9]*\).*/\1/p" libformat/include/lbk/lbk.h; done | paste -sd. -)
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
$(BUILD)/lbk-bake.pc: Makefile
	@mkdir -p $(@D)
	@printf 'prefix=%s\nincludedir=$${prefix}/include\nlibdir=$${prefix}/lib\n\nName: lbk-bake\nDescription: light bake kit baker library\nVersion: 1.0.0\nRequires: lbk\nCflags: -I$${includedir}\nLibs: -L$${libdir} -llbkbake\nLibs.private: %s -lstdc++\n' '$(PREFIX)' '$(BAKE_LIBS)' > $@
bake-lib: $(BUILD)/liblbkbake.a $(BUILD)/liblbkbake.so $(BUILD)/lbk-bake.pc

# ---- the CLI --------------------------------------------------------------------------------
$(BUILD)/lbk: $(BUILD)/rel/$(TOOL_MAIN:.c=.o) $(TOOL_OBJ) $(BUILD)/liblbkbake.a $(BUILD)/liblbk.a
	$(CXX) -o $@ $(BUILD)/rel/$(TOOL_MAIN:.c=.o) $(TOOL_OBJ) $(BUILD)/liblbkbake.a $(BUILD)/liblbk.a $(TOOL_LIBS)
$(BUILD)/lbk-asan: $(BUILD)/asan/$(TOOL_MAIN:.c=.o) $(TOOL_ASAN) $(LIB_ASAN)
	$(CXX) $(SAN) -o $@ $^ $(TOOL_LIBS)

# ---- tests (ASan + UBSan) ------------------------------------------------------------------
TEST_SUPPORT_OBJ := $(TEST_SUPPORT:%.c=$(BUILD)/asan/%.o)
$(TEST_SUPPORT_OBJ): TOOL_INC += -Itests
# A test binary is named after its source, wherever under tests/ it lives.
test_src_of = $(foreach s,$(TEST_SRC),$(if $(filter $(1).c,$(notdir $(s))),$(s)))
.SECONDEXPANSION:
$(BUILD)/tests/%: $$(call test_src_of,$$*) $(TEST_SUPPORT_OBJ) $(TOOL_ASAN) $(LIB_ASAN)
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O1 -g $(SAN) $(WARN) $(TOOL_INC) -Itests -c $< -o $@.o
	$(CXX) $(SAN) -o $@ $@.o $(TEST_SUPPORT_OBJ) $(TOOL_ASAN) $(LIB_ASAN) $(TOOL_LIBS) -lcmocka

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
	$(CC) $(CSTD) $(WARN) -DLBK_CLI='"$(INST)/bin/lbk"' tests/install/bake_check.c -o $(BUILD)/tests/bake_check_shared \
	    $$($(INST_PC) --cflags --libs lbk-bake) -Wl,-rpath,$(INST)/lib -lcmocka
	$(CC) $(CSTD) $(WARN) -DLBK_CLI='"$(INST)/bin/lbk"' tests/install/bake_check.c -o $(BUILD)/tests/bake_check_static \
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

test: deps
	@$(MAKE) --no-print-directory $(BUILD)/lbk $(BUILD)/lbk-asan $(TESTS:%=$(BUILD)/tests/%) $(BUILD)/fuzz_container install-check
	@$(MAKE) --no-print-directory gltf-validator
	@LBK=$(BUILD)/lbk-asan BUILD=$(BUILD) FUZZ=$(BUILD)/fuzz_container \
	  GLTF_VALIDATOR=$$(test -f $(GLTF_VALIDATOR)/package.json && echo $(GLTF_VALIDATOR)) \
	  sh tests/run.sh $(TESTS) install_check_shared install_check_static \
	    bake_check_shared bake_check_static
check: test

# ---- fuzzing (clang libFuzzer) --------------------------------------------------------------
FUZZ_FLAGS := -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined -g -O1
$(BUILD)/fuzz_container: tests/fuzz/fuzz_container.c $(LIB_SRC)
	@mkdir -p $(@D)
	$(CLANG) $(CSTD) $(FUZZ_FLAGS) $(LIB_INC) -o $@ $^ $(LIB_LIBS)
fuzz: deps $(BUILD)/fuzz_container
	@mkdir -p $(BUILD)/fuzz-corpus
	$(BUILD)/fuzz_container -max_total_time=$${FUZZ_SECONDS:-60} $(BUILD)/fuzz-corpus tests/fuzz/corpus

# ---- benchmarks -----------------------------------------------------------------------------
$(BUILD)/bench/%: bench/%.c $(TOOL_OBJ) $(BUILD)/liblbkbake.a $(BUILD)/liblbk.a
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O2 -g $(WARN) $(TOOL_INC) -c $< -o $@.o
	$(CXX) -o $@ $@.o $(TOOL_OBJ) $(BUILD)/liblbkbake.a $(BUILD)/liblbk.a $(TOOL_LIBS)
# The BC codecs against Mesa's (llvmpipe, surfaceless EGL): optional, needs libegl-dev libgl-dev.
mesa-bc-check: $(TOOL_OBJ) $(BUILD)/liblbkbake.a $(BUILD)/liblbk.a
	@mkdir -p $(BUILD)/bench
	$(CC) $(CSTD) -O2 -g $(WARN) $(TOOL_INC) -c bench/mesa_bc_check.c -o $(BUILD)/bench/mesa_bc_check.o
	$(CXX) -o $(BUILD)/bench/mesa_bc_check $(BUILD)/bench/mesa_bc_check.o $(TOOL_OBJ) $(BUILD)/liblbkbake.a \
	    $(BUILD)/liblbk.a $(TOOL_LIBS) -lEGL -lGL
	$(BUILD)/bench/mesa_bc_check
bench: deps
	@$(MAKE) --no-print-directory $(BUILD)/lbk $(BENCHES:%=$(BUILD)/bench/%)
	@for b in $(BENCHES); do echo "== $$b"; $(BUILD)/bench/$$b || exit 1; done
	@echo "== blender_import"; sh bench/blender_import.sh $(BUILD)/lbk $(BUILD)/bench-blender

# ---- demo -----------------------------------------------------------------------------------
demo: deps
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
