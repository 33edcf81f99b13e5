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
            libcjson-dev libcmocka-dev clang libclang-rt-14-dev

WARN     := -Wall -Wextra -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Wno-unused-parameter
CSTD     := -std=c11 -D_POSIX_C_SOURCE=200809L -D_DEFAULT_SOURCE
OPT      ?= -O2 -g
SAN      := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined

LIB_INC  := -Ilibformat/include
LIB_LIBS := -lzstd -lxxhash -lm
# The tools: everything heavy lives here, never in liblbk.
TOOL_INC := $(LIB_INC) -I. -I/usr/include/draco -I/usr/include/stb
TOOL_LIBS:= -lembree3 -lOpenEXRCore -lqhull_r -lspng -lcjson -ldraco -lpthread -lm $(LIB_LIBS)

LIB_SRC   := $(sort $(wildcard libformat/src/*.c))
TOOL_CSRC := $(sort $(wildcard cli/*.c bake/*/*.c tools/*/*.c))
TOOL_CXXSRC := $(sort $(wildcard bake/*/*.cc))
TOOL_MAIN := cli/main.c
TEST_SRC  := $(sort $(wildcard tests/*/test_*.c))
TESTS     := $(notdir $(TEST_SRC:.c=))
TEST_SUPPORT := $(sort $(wildcard tests/support/*.c))
BENCHES   := $(patsubst bench/%.c,%,$(sort $(wildcard bench/bench_*.c)))

# Release objects
LIB_OBJ   := $(LIB_SRC:%.c=$(BUILD)/rel/%.o)
LIB_PIC   := $(LIB_SRC:%.c=$(BUILD)/pic/%.o)
TOOL_OBJ  := $(filter-out $(BUILD)/rel/$(TOOL_MAIN:.c=.o),$(TOOL_CSRC:%.c=$(BUILD)/rel/%.o)) $(TOOL_CXXSRC:%.cc=$(BUILD)/rel/%.o)
# Sanitizer objects for the test build
LIB_ASAN  := $(LIB_SRC:%.c=$(BUILD)/asan/%.o)
TOOL_ASAN := $(filter-out $(BUILD)/asan/$(TOOL_MAIN:.c=.o),$(TOOL_CSRC:%.c=$(BUILD)/asan/%.o)) $(TOOL_CXXSRC:%.cc=$(BUILD)/asan/%.o)

.PHONY: all lib deps deps-bench demo test check bench bench-cycles fuzz install install-check clean help
all: $(BUILD)/lbk $(BUILD)/liblbk.a $(BUILD)/liblbk.so $(BUILD)/lbk.pc

help:
	@echo "make            build liblbk.a, liblbk.so, lbk.pc and the lbk CLI into $(BUILD)/"
	@echo "make demo       install missing packages, bake the embedded scene, inspect it, write a PNG"
	@echo "make test       install missing packages, build with ASan+UBSan, run the whole suite"
	@echo "make bench      benchmarks, printed as ratios against baselines measured in the same run"
	@echo "make bench-cycles  lbk against Blender Cycles at equal time (part of make bench; bench/cycles/README.md)"
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

# What `make bench-cycles` needs besides the build: Blender (Cycles) and Python 3.
BENCH_DEB_PKGS := blender python3
deps-bench:
	@missing=$$(for p in $(BENCH_DEB_PKGS); do dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'install ok installed' || echo $$p; done); \
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
$(BUILD)/lbk.pc: Makefile
	@mkdir -p $(@D)
	@printf 'prefix=%s\nincludedir=$${prefix}/include\nlibdir=$${prefix}/lib\n\nName: lbk\nDescription: light bake kit container library\nVersion: 1.0.0\nRequires.private: libzstd libxxhash\nCflags: -I$${includedir}\nLibs: -L$${libdir} -llbk\nLibs.private: -lm\n' '$(PREFIX)' > $@
lib: $(BUILD)/liblbk.a $(BUILD)/liblbk.so $(BUILD)/lbk.pc

# ---- the CLI --------------------------------------------------------------------------------
$(BUILD)/lbk: $(BUILD)/rel/$(TOOL_MAIN:.c=.o) $(TOOL_OBJ) $(BUILD)/liblbk.a
	$(CXX) -o $@ $(BUILD)/rel/$(TOOL_MAIN:.c=.o) $(TOOL_OBJ) $(BUILD)/liblbk.a $(TOOL_LIBS)
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

# The install check: the library installed into $(BUILD)/inst, a program built against it with
# pkg-config only, linked once with liblbk.so and once with liblbk.a.
INST := $(abspath $(BUILD))/inst
install-check: all
	@rm -rf $(INST)
	@$(MAKE) --no-print-directory install PREFIX=$(INST) >/dev/null
	@mkdir -p $(BUILD)/tests
	$(CC) $(CSTD) $(WARN) tests/install/install_check.c -o $(BUILD)/tests/install_check_shared \
	    $$(PKG_CONFIG_PATH=$(INST)/lib/pkgconfig pkg-config --cflags --libs lbk) -Wl,-rpath,$(INST)/lib -lcmocka
	$(CC) $(CSTD) $(WARN) tests/install/install_check.c -o $(BUILD)/tests/install_check_static \
	    $$(PKG_CONFIG_PATH=$(INST)/lib/pkgconfig pkg-config --cflags lbk) $(INST)/lib/liblbk.a \
	    $$(PKG_CONFIG_PATH=$(INST)/lib/pkgconfig pkg-config --static --libs-only-other --libs-only-l lbk | sed 's/-llbk//') -lcmocka

test: deps
	@$(MAKE) --no-print-directory $(BUILD)/lbk $(BUILD)/lbk-asan $(TESTS:%=$(BUILD)/tests/%) $(BUILD)/fuzz_container install-check
	@LBK=$(BUILD)/lbk-asan BUILD=$(BUILD) FUZZ=$(BUILD)/fuzz_container sh tests/run.sh $(TESTS) install_check_shared install_check_static
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
$(BUILD)/bench/%: bench/%.c $(TOOL_OBJ) $(BUILD)/liblbk.a
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O2 -g $(WARN) $(TOOL_INC) -c $< -o $@.o
	$(CXX) -o $@ $@.o $(TOOL_OBJ) $(BUILD)/liblbk.a $(TOOL_LIBS)
bench: deps deps-bench
	@$(MAKE) --no-print-directory $(BUILD)/lbk $(BENCHES:%=$(BUILD)/bench/%)
	@for b in $(BENCHES); do echo "== $$b"; $(BUILD)/bench/$$b || exit 1; done
	@echo "== bench-cycles"; $(MAKE) --no-print-directory bench-cycles

# lbk against Cycles (bench/cycles/README.md). LBK_TREE=/path/to/other/checkout compares that
# tree's baker instead: its build/lbk (built there first) and texel_dump linked against its
# baker objects, so the rebuilt layout is the one its lbk bakes.
ifdef LBK_TREE
CYC_LBK  := $(LBK_TREE)/$(BUILD)/lbk
CYC_DUMP := $(BUILD)/bench/cycles/texel_dump-tree
$(CYC_DUMP): bench/cycles/texel_dump.c FORCE
	@$(MAKE) --no-print-directory -C $(LBK_TREE) $(BUILD)/lbk
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O2 -g $(WARN) -I$(LBK_TREE)/libformat/include -I$(LBK_TREE) -I/usr/include/draco -I/usr/include/stb \
	    -c $< -o $@.o
	$(CXX) -o $@ $@.o $$(ls $(LBK_TREE)/$(BUILD)/rel/bake/*/*.o | sort) $(LBK_TREE)/$(BUILD)/liblbk.a $(TOOL_LIBS)
FORCE:
else
CYC_LBK  ?= $(BUILD)/lbk
CYC_DUMP ?= $(BUILD)/bench/cycles/texel_dump
endif
bench-cycles: deps deps-bench
	@$(MAKE) --no-print-directory $(if $(LBK_TREE),,$(BUILD)/lbk) $(CYC_DUMP)
	@LBK=$${LBK:-$(CYC_LBK)} LBK_TEXEL_DUMP=$${LBK_TEXEL_DUMP:-$(CYC_DUMP)} python3 bench/cycles/run.py

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
	install -d $(DESTDIR)$(PREFIX)/share/lbk/profiles
	install -m 644 tools/convert/profiles/*.profile $(DESTDIR)$(PREFIX)/share/lbk/profiles/

clean:
	rm -rf $(BUILD)

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
