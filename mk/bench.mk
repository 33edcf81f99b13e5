# Benchmarks, printed as ratios against baselines measured in the same run: make bench (all of
# them), bench-cycles and bench-render (lbk against Blender Cycles), bench-suite (lbk against
# Cycles over the generated hard levels; make bench runs bench-suite-quick), bench-scale (a
# generated city of ~50 M texels; make bench runs its two smallest parts), mesa-bc-check.
.PHONY: bench bench-cycles bench-render bench-suite bench-suite-quick bench-stitch bench-scale bench-dist-shared mesa-bc-check

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
	@echo "== bench-stitch (seam stitching's share of bake CPU per level)"; $(MAKE) --no-print-directory bench-stitch
	@echo "== blender_import"; sh bench/blender_import.sh $(BUILD)/lbk $(BUILD)/bench-blender
	@echo "== bench-cycles"; $(MAKE) --no-print-directory bench-cycles
	@echo "== bench-suite-quick (hard levels: a few dev scenes)"; $(MAKE) --no-print-directory bench-suite-quick
	@echo "== render (lbk render vs Blender Cycles)"; $(MAKE) --no-print-directory bench-render
	@echo "== bench-diff (lbk diff: reseed study and power)"; $(MAKE) --no-print-directory bench-diff
	@echo "== bench-scale (quick: the generated city's 1/256 and 1/64)"; \
	  $(MAKE) --no-print-directory bench-scale BENCH_SCALE_ARGS="--fractions 1/256,1/64"
	@echo "== bench-dist-shared (base-only levels cut into 1-16 units sharing their caches)"; \
	  $(MAKE) --no-print-directory bench-dist-shared

# Distributed bakes of base-only levels whose units share the radiosity caches
# (bench/scale/dist_shared.py, bake/dist/DIST.md §Shared caches): N = 1 … 16 units' total work
# and critical path against the local bake, bytes moved, a projection to 64 and 256 machines.
# BENCH_DIST_SHARED_ARGS picks levels (--levels cornell,city256,city256-1k,city64).
bench-dist-shared: deps-tools
	@$(MAKE) --no-print-directory $(BUILD)/lbk
	@python3 bench/scale/dist_shared.py --lbk $(BUILD)/lbk --out $(BUILD)/bench-dist-shared $(BENCH_DIST_SHARED_ARGS)

# The scale bench (bench/scale/README.md): the generated city (~1.2 M triangles, ~50 M texels at
# 3.5 texels/m) at 1/64, 1/16, 1/4 and whole, each baked at the fast preset: time per phase, peak
# RSS and bytes per texel, texels and probes per CPU second, growth against the smallest part.
# Hours on 2 cores; BENCH_SCALE_ARGS narrows it (e.g. --fractions 1/64,1/16).
bench-scale: deps-tools
	@$(MAKE) --no-print-directory $(BUILD)/lbk
	@python3 bench/scale/run.py --lbk $(BUILD)/lbk --out $(BUILD)/bench-scale $(BENCH_SCALE_ARGS)

# Seam stitching's share of bake CPU per level (bench/stitch_share.c): the shared scenes and every
# generated hard level, both layouts (bench/levels; the _authored ones have many small charts).
# The --wrap routes the baker's stitch calls through the bench's CPU clock.
STITCH_LEVELS ?= $(BUILD)/bench-stitch-levels
$(BUILD)/bench/stitch_share: BENCH_EXTRA += -Wl,--wrap=bk_seams_stitch
bench-stitch: $(BUILD)/bench/stitch_share
	@python3 bench/levels/gen_levels.py --out $(STITCH_LEVELS) --set all > /dev/null
	@$(BUILD)/bench/stitch_share $(STITCH_LEVELS)/manifest.json

# lbk diff's calibration (bench/diff_reseed.py): every scene of scenes/ and a generated light-set
# and door level (bench/door_scene_write.c), every preset, 20 reseed pairs each (the measured
# false-alarm rate per receiver class against the stated one), then the power table. Hours at the
# high preset; BENCH_DIFF_ARGS narrows it (e.g. --presets fast --pairs 5).
bench-diff: $(BUILD)/lbk $(BUILD)/bench/door_scene_write
	@python3 bench/diff_reseed.py --lbk $(BUILD)/lbk --out $(BUILD)/bench-diff --power \
	  --door-scene-tool $(BUILD)/bench/door_scene_write $(BENCH_DIFF_ARGS)

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
	    $(BAKE_CFLAGS) -c $< -o $@.o
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

# The hard-level suite against Cycles (bench/levels/README.md), on bench-cycles' harness: every
# level of the dev and the validation set, reported apart (hours on 2 cores; LBK_BENCH_QUICK=1:
# short references); bench-suite-quick is make bench's few dev scenes with short references.
bench-suite bench-suite-quick: deps-tools deps-bench
	@$(MAKE) --no-print-directory $(if $(LBK_TREE),,$(BUILD)/lbk) $(CYC_DUMP)
	@LBK=$${LBK:-$(CYC_LBK)} LBK_TEXEL_DUMP=$${LBK_TEXEL_DUMP:-$(CYC_DUMP)} \
	  BENCH_LEVELS_WORK=$${BENCH_LEVELS_WORK:-$(BUILD)/bench-levels} \
	  python3 bench/levels/suite.py $(if $(filter bench-suite-quick,$@),--subset --quick)
