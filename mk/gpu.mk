# The GPU path (gpu/): built when the Vulkan headers and glslang are there (make deps installs
# them); without them tests/gpu/test_gpu.c compiles to SKIPPED tests. Shaders become C arrays
# (glslang --vn).
.PHONY: gpu
HAVE_VULKAN := $(shell test -f /usr/include/vulkan/vulkan.h && command -v $(GLSLANG) >/dev/null 2>&1 && echo 1)
GPU_SPV_H   := $(GPU_SHADERS:gpu/shaders/%.comp=$(BUILD)/gpu/%.spv.h)
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
$(BUILD)/tests/test_gpu: TEST_EXTRA = $(GPU_ASAN) $(VULKAN_LIBS)
$(BUILD)/bench/bench_gpu: $(GPU_REL)
$(BUILD)/bench/bench_gpu: TOOL_INC += -I$(BUILD)/gpu -DLBK_HAVE_VULKAN=1
$(BUILD)/bench/bench_gpu: BENCH_EXTRA = $(GPU_REL) $(VULKAN_LIBS)
$(BUILD)/lbk-gpu-apply: gpu/lbk_gpu_apply.c $(GPU_REL) $(BUILD)/liblbk.a
	$(CC) $(CSTD) $(OPT) $(WARN) $(TOOL_INC) -I$(BUILD)/gpu -DLBK_HAVE_VULKAN=1 -o $@ $< $(GPU_REL) $(BUILD)/liblbk.a $(VULKAN_LIBS) $(LIB_LIBS)
gpu: $(BUILD)/lbk-gpu-apply
else
gpu:
	@echo "lbk: the GPU path needs $(GPU_PKGS) (make deps installs them)"; exit 1
endif
