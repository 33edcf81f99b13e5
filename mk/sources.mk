# The sources, picked up by wildcard (adding a file to a folder needs no edit), and their objects.

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
GPU_SHADERS := $(sort $(wildcard gpu/shaders/*.comp))
GPU_HOST    := $(sort $(wildcard gpu/host/*.c))

# Release objects
LIB_OBJ   := $(LIB_SRC:%.c=$(BUILD)/rel/%.o)
LIB_PIC   := $(LIB_SRC:%.c=$(BUILD)/pic/%.o)
BAKE_OBJ  := $(BAKE_CSRC:%.c=$(BUILD)/rel/%.o) $(BAKE_CXXSRC:%.cc=$(BUILD)/rel/%.o)
BAKE_PIC  := $(BAKE_CSRC:%.c=$(BUILD)/pic/%.o) $(BAKE_CXXSRC:%.cc=$(BUILD)/pic/%.o)
# cli/ and tools/ (the baker comes from liblbkbake.a)
TOOL_OBJ  := $(filter-out $(BUILD)/rel/$(TOOL_MAIN:.c=.o) $(BAKE_OBJ),$(TOOL_CSRC:%.c=$(BUILD)/rel/%.o)) \
             $(patsubst %.cc,$(BUILD)/rel/%.o,$(sort $(wildcard tools/*/*.cc)))
# Sanitizer objects for the test build (ASan+UBSan; TSan)
LIB_ASAN  := $(LIB_SRC:%.c=$(BUILD)/asan/%.o)
TOOL_ASAN := $(filter-out $(BUILD)/asan/$(TOOL_MAIN:.c=.o),$(TOOL_CSRC:%.c=$(BUILD)/asan/%.o)) $(TOOL_CXXSRC:%.cc=$(BUILD)/asan/%.o)
LIB_TSAN  := $(LIB_SRC:%.c=$(BUILD)/tsan/%.o)
TOOL_TSAN := $(filter-out $(BUILD)/tsan/$(TOOL_MAIN:.c=.o),$(TOOL_CSRC:%.c=$(BUILD)/tsan/%.o)) $(TOOL_CXXSRC:%.cc=$(BUILD)/tsan/%.o)
