# lbk — light bake kit. `make demo` and `make test` do all set-up on a fresh Debian machine:
# they depend on the deps targets of mk/deps.mk, the one place that installs packages.
# Sources are picked up by wildcard: adding a file to a folder needs no edit here.
#
#   mk/config.mk   tools, compiler flags, the libraries' flags (pkg-config, with fallbacks)
#   mk/sources.mk  the source lists (wildcards) and object lists
#   mk/deps.mk     packages: Debian package lists, make deps / deps-tools / deps-test /
#                  deps-bench, the npm glTF-Validator
#   mk/build.mk    compile rules, liblbk and liblbkbake (.a, .so, .pc), the viewer page, lbk
#   mk/gpu.mk      the Vulkan path (gpu/), lbk-gpu-apply
#   mk/fuzz.mk     the libFuzzer harnesses, make fuzz / fuzz-long / fuzz-corpus
#   mk/test.mk     the test binaries (ASan+UBSan), TSan, the house checks, make test
#   mk/install.mk  make install / install-lib and their checks
#   mk/bench.mk    make bench / bench-cycles / bench-render / bench-scale / mesa-bc-check

include mk/config.mk mk/sources.mk

.PHONY: all lib bake-lib demo clean help
all: $(BUILD)/lbk $(BUILD)/liblbk.a $(BUILD)/liblbk.so $(BUILD)/lbk.pc \
     $(BUILD)/liblbkbake.a $(BUILD)/liblbkbake.so $(BUILD)/lbk-bake.pc

help:
	@echo "make            build liblbk.a/.so + lbk.pc, liblbkbake.a/.so + lbk-bake.pc and the lbk CLI into $(BUILD)/"
	@echo "make lib        liblbk alone (.a, .so, lbk.pc);  make bake-lib  liblbkbake (.a, .so, lbk-bake.pc)"
	@echo "make deps       install the missing Debian packages (all of them) and the glTF-Validator (npm)"
	@echo "                (deps-tools, deps-test, deps-bench: what demo, test, bench need; gltf-validator)"
	@echo "make demo       bake the embedded scene, inspect it, write a PNG"
	@echo "make test       build with ASan+UBSan, run the whole suite, then make tsan's cases (also: make check)"
	@echo "                (demo, test, bench, fuzz install missing packages only as root with CI set"
	@echo "                or with LBK_INSTALL_DEPS=1; else they print the apt-get line and stop)"
	@echo "make test-build everything make test runs, built but not run"
	@echo "make tsan       the determinism cases of tests/tsan/determinism.list under ThreadSanitizer"
	@echo "make install-check, install-lib-check   the install checks of make test"
	@echo "make install-lib PREFIX=/usr/local   liblbk only (needs a C compiler, zstd, xxHash)"
	@echo "WERROR=1        every compiler warning is an error (CI)"
	@echo "make bench      benchmarks, printed as ratios against baselines measured in the same run"
	@echo "make bench-cycles  lbk against Blender Cycles at equal time (part of make bench; bench/cycles/README.md)"
	@echo "make bench-render  lbk render against Blender Cycles"
	@echo "make bench-scale   a generated city of ~50 M texels at growing parts: time, memory, growth (bench/scale/README.md)"
	@echo "make mesa-bc-check  BC6H/BC4 codecs against Mesa's (optional: libegl-dev libgl-dev)"
	@echo "make fuzz       the libFuzzer harnesses (container, glTF import, sky EXR, profiles, parts), FUZZ_SECONDS each"
	@echo "make fuzz-long  the same for FUZZ_HOURS (default 1) each;  make fuzz-corpus  regenerate the seed corpus"
	@echo "make gpu        the Vulkan DLS apply tool $(BUILD)/lbk-gpu-apply (make test runs the GPU tests on lavapipe)"
	@echo "make install PREFIX=/usr/local"
	@echo "make clean      remove $(BUILD)/"

# fuzz.mk before test.mk: make test builds and runs the harnesses it names
include mk/deps.mk mk/build.mk mk/gpu.mk mk/fuzz.mk mk/test.mk mk/install.mk mk/bench.mk

demo: deps-tools
	@$(MAKE) --no-print-directory $(BUILD)/lbk
	@sh scenes/demo.sh $(BUILD)

clean:
	rm -rf $(BUILD)

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
