# Fuzzing (clang libFuzzer; tests/fuzz/README.md): make fuzz, make fuzz-long, make fuzz-corpus, make fuzz-cov.
# make test builds every harness and runs each for a fixed number of inputs.
.PHONY: fuzz fuzz-long fuzz-corpus fuzz-cov
FUZZ_FLAGS := -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined -g -O1
$(BUILD)/fuzz_container: tests/fuzz/fuzz_container.c $(LIB_SRC)
	@mkdir -p $(@D)
	$(CLANG) $(CSTD) $(FUZZ_FLAGS) $(LIB_FP) $(WARN) $(LIB_INC) -o $@ $^ $(LIB_LIBS)
# The other harnesses: their objects instrumented once under fuzz-obj/.
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
# What each harness links (the glTF one: the importer's objects, one line to edit when they change)
FUZZ_GLTF_OBJ := $(addprefix $(BUILD)/fuzz-obj/,tests/fuzz/fuzz_gltf.o scene/gltf_import.o scene/gltf_guard.o \
                   scene/gltf_materials.o scene/gltf_geometry.o scene/gltf_meshopt.o scene/gltf_extras.o \
                   scene/tinygltf_impl.o scene/scene.o scene/exr_read.o)
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
	$(CLANGXX) -fsanitize=fuzzer,address,undefined -o $@ $^ $(ASTCENC_LIBS) $(LIB_LIBS)
$(BUILD)/fuzz_part: $(FUZZ_PART_OBJ) $(FUZZ_LIB_OBJ)
	$(CLANGXX) -fsanitize=fuzzer,address,undefined -o $@ $^ $(BAKE_LIBS) $(LIB_LIBS)
-include $(wildcard $(BUILD)/fuzz-obj/*/*.d $(BUILD)/fuzz-obj/*/*/*.d)

# The seed corpora (tests/fuzz/README.md), regenerated from the current writers (deterministic:
# the bakes are byte-reproducible, a fixed thread count): corpus/ the golden files, the containers
# make_corpus.c builds (every section type) and small real bakes; corpus_part/ units of
# part_scene.gltf and sets_scene.gltf (lbk plan + lbk bake-unit), the hand-made regression parts
# given the current part format version (the harness repairs their checksums); corpus_profile/
# the shipped profiles; corpus_gltf/ the shared scenes and a GLB lbk export wrote. corpus_exr/ is
# Blender's and lbk export's EXRs, which carry no lbk format version: left as they are. Run it
# when a writer's output or a format version changes and commit the result; make test's
# fuzz_seeds check fails while a seed is older than its writer.
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
	  $(BUILD)/lbk bake-unit $$d/p$$n.json 0 -o tests/fuzz/corpus_part/unit0of$$n.lbkpart -q --threads 2 || exit 1; done && \
	  $(BUILD)/lbk plan tests/fuzz/sets_scene.gltf -o $$d/o.lbk --plan $$d/s.json --units 16 --samples 4 --target-error none \
	    --texel-density 1 --glg-spacing 8 -q && \
	  $(BUILD)/lbk bake-unit $$d/s.json 15 -o tests/fuzz/corpus_part/sets_unit15of16.lbkpart -q --threads 2 || exit 1; rm -rf $$d
	@v=$$(sed -n 's/^#define BK_PART_VERSION  *\([0-9]*\).*/\1/p' bake/dist/dist.h) && for f in tests/fuzz/corpus_part/regress_*.lbkpart; do \
	  printf "\\$$(printf %o $$v)\\000\\000\\000" | dd of=$$f bs=1 seek=8 conv=notrunc status=none || exit 1; done
	cp tools/convert/profiles/*.profile tests/fuzz/corpus_profile/
	cp scenes/cornell_box/CornellBox-Original.gltf tests/fuzz/corpus_gltf/cornell.gltf
	cp tests/fuzz/sets_scene.gltf tests/fuzz/corpus_gltf/sets_scene.gltf
	@d=$$(mktemp -d) && $(BUILD)/lbk export tests/fuzz/corpus/bake_sets.lbk --gltf $$d/sets_export.glb --scene tests/fuzz/sets_scene.gltf -q && \
	  cp $$d/sets_export.glb tests/fuzz/corpus_gltf/ && rm -rf $$d
fuzz: deps-test
	@$(MAKE) --no-print-directory $(BUILD)/fuzz_container
	@mkdir -p $(BUILD)/fuzz-corpus
	$(BUILD)/fuzz_container -max_total_time=$${FUZZ_SECONDS:-60} -max_len=65536 -artifact_prefix=$(BUILD)/ $(BUILD)/fuzz-corpus tests/fuzz/corpus
	@for h in $(FUZZ_HARNESSES); do n=$${h#fuzz_}; $(MAKE) --no-print-directory $(BUILD)/$$h && mkdir -p $(BUILD)/fuzz-corpus-$$n && \
	  $(BUILD)/$$h -max_total_time=$${FUZZ_SECONDS:-60} -max_len=65536 -rss_limit_mb=2048 -artifact_prefix=$(BUILD)/ \
	    $(BUILD)/fuzz-corpus-$$n \
	    tests/fuzz/corpus_$$n || exit 1; done
	@$(MAKE) --no-print-directory fuzz-cov
# Each harness's coverage from its committed seeds alone (libFuzzer's cov: at INITED, -runs=0;
# a scratch folder first, so nothing is written into the seeds): a harness whose seeds its code
# refuses (an old format) shows a few dozen instead of thousands.
fuzz-cov: deps-test
	@$(MAKE) --no-print-directory $(BUILD)/fuzz_container $(FUZZ_HARNESSES:%=$(BUILD)/%)
	@printf '%-16s %6s %8s\n' harness seeds cov; \
	for h in fuzz_container $(FUZZ_HARNESSES); do n=$${h#fuzz_}; c=tests/fuzz/corpus_$$n; [ $$h = fuzz_container ] && c=tests/fuzz/corpus; \
	  d=$$(mktemp -d) && cov=$$($(BUILD)/$$h -runs=0 -max_len=65536 -rss_limit_mb=2048 $$d $$c 2>&1 | sed -n 's/.*INITED cov: \([0-9]*\).*/\1/p' | tail -n 1); \
	  rm -rf $$d; printf '%-16s %6s %8s\n' $$h $$(ls $$c | wc -l) $${cov:-?}; done
# Hours of fuzzing (FUZZ_HOURS, default 1, per harness, one after the other): a finding stops it
# with the reproducer in build/ (crash-*, leak-*, timeout-*); what the runs found stays in
# build/fuzz-corpus*.
fuzz-long:
	@$(MAKE) --no-print-directory fuzz FUZZ_SECONDS=$$(( $${FUZZ_HOURS:-1} * 3600 ))
