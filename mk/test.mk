# make test (ASan+UBSan binaries, the house checks, the install checks, the fuzz harnesses for a
# fixed number of inputs, the glTF-Validator, then make tsan's cases), all run by tests/run.sh.
.PHONY: test check test-build tsan

# ---- the test binaries (ASan + UBSan) -------------------------------------------------------
TEST_SUPPORT_OBJ := $(TEST_SUPPORT:%.c=$(BUILD)/asan/%.o)
$(TEST_SUPPORT_OBJ): TOOL_INC += -Itests
# A test binary is named after its source, wherever under tests/ it lives.
test_src_of = $(foreach s,$(TEST_SRC),$(if $(filter $(1).c,$(notdir $(s))),$(s)))
.SECONDEXPANSION:
$(BUILD)/tests/%: $$(call test_src_of,$$*) $(TEST_SUPPORT_OBJ) $(TOOL_ASAN) $(LIB_ASAN)
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O1 -g $(SAN) $(WARN) $(TOOL_INC) -Itests -c $< -o $@.o
	$(CXX) $(SAN) -o $@ $@.o $(TEST_SUPPORT_OBJ) $(TOOL_ASAN) $(LIB_ASAN) $(TEST_EXTRA) $(TOOL_LIBS) $(CMOCKA_LIBS)

# ---- fault injection: an LD_PRELOAD library that fails or kills at the N-th write call -------
# (tests/faults/fault_shim.c; test_faults runs the CLI's writers through it)
$(BUILD)/fault_shim.so: tests/faults/fault_shim.c
	@mkdir -p $(@D)
	$(CC) -std=c11 -O1 -g $(WARN) -fPIC -shared $< -o $@ -ldl

# ---- ThreadSanitizer: the determinism cases of tests/tsan/determinism.list -------------------
# Their own objects under $(BUILD)/tsan (TSan cannot be mixed with ASan). Embree's internal
# threads are not instrumented: tests/tsan/suppressions.txt silences reports inside Embree and
# TBB only, never in lbk code.
TSAN_TESTS := $(sort $(shell sed -n 's/^\(test_[a-z0-9_]*\).*/\1/p' tests/tsan/determinism.list))
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
	$(CXX) $(TSAN) -o $@ $@.o $(TEST_SUPPORT_TSAN) $(TOOL_TSAN) $(LIB_TSAN) $(TOOL_LIBS) $(CMOCKA_LIBS) \
	    -Wl,--wrap=_cmocka_run_group_tests
tsan: deps-test
	@$(MAKE) --no-print-directory $(TSAN_TESTS:%=$(BUILD)/tsan/bin/%)
	@BUILD=$(BUILD) TSAN_BIN=$(BUILD)/tsan/bin sh tests/run.sh

# ---- the house rules (tests/structure/: includes by layer, file and function sizes) ----------
# run by tests/run.sh like the test binaries, through a one-line wrapper.
STRUCTURE_CHECKS := $(patsubst tests/structure/%.sh,%,$(sort $(wildcard tests/structure/*.sh)))
$(STRUCTURE_CHECKS:%=$(BUILD)/tests/%): $(BUILD)/tests/%: tests/structure/%.sh
	@mkdir -p $(@D)
	@printf '#!/bin/sh\nexec sh "%s/$<" "$$@"\n' "$(CURDIR)" > $@ && chmod +x $@
# shell tests of other parts (tests/bench/*.sh: the level generators; start.shinc is their shared start), the same wrapper
SHELL_TESTS := $(patsubst tests/bench/%.sh,%,$(sort $(wildcard tests/bench/*.sh)))
$(SHELL_TESTS:%=$(BUILD)/tests/%): $(BUILD)/tests/%: tests/bench/%.sh
	@mkdir -p $(@D)
	@printf '#!/bin/sh\nexec sh "%s/$<" "$$@"\n' "$(CURDIR)" > $@ && chmod +x $@

# ---- make test ------------------------------------------------------------------------------
# What it builds (test-build) is built through a sub-make, so that HAVE_VULKAN sees what
# deps-test installed; the glTF-Validator comes from mk/deps.mk.
test-build: $(BUILD)/lbk $(BUILD)/lbk-asan $(TESTS:%=$(BUILD)/tests/%) $(BUILD)/fuzz_container $(BUILD)/fault_shim.so \
            $(FUZZ_HARNESSES:%=$(BUILD)/%) \
            install-check install-lib-check $(TSAN_TESTS:%=$(BUILD)/tsan/bin/%) \
            $(if $(HAVE_VULKAN),$(BUILD)/lbk-gpu-apply) $(STRUCTURE_CHECKS:%=$(BUILD)/tests/%) \
            $(SHELL_TESTS:%=$(BUILD)/tests/%)
test: deps-test
	@$(MAKE) --no-print-directory test-build
	@$(MAKE) --no-print-directory gltf-validator
	@$(MAKE) --no-print-directory engine-npm
	@LBK=$(BUILD)/lbk-asan LBK_FAULT_SHIM=$(BUILD)/fault_shim.so BUILD=$(BUILD) FUZZ=$(BUILD)/fuzz_container TSAN_BIN=$(BUILD)/tsan/bin \
	  FUZZ_MORE="$(foreach h,$(FUZZ_HARNESSES),$(h:fuzz_%=%)=$(BUILD)/$(h))" \
	  GLTF_VALIDATOR=$$(test -f $(GLTF_VALIDATOR)/package.json && echo $(GLTF_VALIDATOR)) \
	  sh tests/run.sh $(TESTS) $(STRUCTURE_CHECKS) $(SHELL_TESTS) install_check_shared install_check_static install_lib_check \
	    bake_check_shared bake_check_static; \
	st=$$?; n=$$(sed -n 's/^\[  SKIPPED \] \([0-9]*\) test(s).*/\1/p' $(BUILD)/tests/test_gpu.log 2>/dev/null); \
	if [ "$${n:-0}" -gt 0 ]; then echo "tests: $$n GPU tests SKIPPED, not run: $$(grep -m1 -o 'SKIPPED: .*' $(BUILD)/tests/test_gpu.log)"; fi; \
	exit $$st
check: test
