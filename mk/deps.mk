# Packages: the one place that installs anything (Debian packages, and the glTF-Validator from
# npm). No compile or test recipe installs; the targets that need packages depend on these.

# Debian packages: liblbk alone (`make install-lib`), the baker and CLI, the tests on top.
DEB_LIB_PKGS  := build-essential libzstd-dev libxxhash-dev
# The GPU path (gpu/): Vulkan headers and loader, glslang, and Mesa's lavapipe (a CPU Vulkan
# device) so that its tests run on a machine without a GPU.
GPU_PKGS      := libvulkan-dev mesa-vulkan-drivers glslang-tools
DEB_TOOL_PKGS := $(DEB_LIB_PKGS) pkg-config libembree-dev libopenexr-dev libdraco-dev libtinygltf-dev \
                 libstb-dev nlohmann-json3-dev libqhull-dev libspng-dev libcjson-dev \
                 libastcenc-dev libwebp-dev libmeshoptimizer-dev
DEB_TEST_PKGS := $(DEB_TOOL_PKGS) libcmocka-dev clang libclang-rt-14-dev python3
# lbk view's tests: node runs the page's container reader against liblbk, headless Chromium
# (SwiftShader WebGL) loads the page; without them those cases are SKIPPED (counted so).
VIEW_PKGS     := nodejs chromium
# npm, for the glTF-Validator check (gltf-validator below): installed only where no npm runs yet
# (a nodejs that bundles its own npm conflicts with Debian's npm package)
NPM_PKGS      := npm
# A single-node Slurm cluster for the distributed-bake test (tests/e2e/slurm_dist.sh, which
# also installs them itself when run as root).
SLURM_PKGS    := munge slurmd slurmctld slurm-client
DEB_PKGS      := $(DEB_TEST_PKGS) $(GPU_PKGS) $(VIEW_PKGS) $(SLURM_PKGS)
# What `make bench-cycles` needs besides the build: Blender (Cycles) and Python 3.
BENCH_DEB_PKGS := blender python3

# `make deps` installs whatever of DEB_PKGS is missing (through sudo when not root), then the
# glTF-Validator: that is what it is asked for. The targets that need packages (test, demo,
# bench, fuzz) depend on deps-tools, deps-test or deps-bench, which only check: they install the
# missing ones themselves when run as root with CI set (.ci/run) or when LBK_INSTALL_DEPS=1, and
# say which and why; otherwise they print the one command to run and stop.
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
.PHONY: deps deps-tools deps-test deps-bench gltf-validator engine-npm
deps:
	@$(call deps_sh,$(DEB_PKGS),make deps)
	@$(MAKE) --no-print-directory gltf-validator
	@$(MAKE) --no-print-directory engine-npm
deps-tools:
	@$(call deps_sh,$(DEB_TOOL_PKGS),)
# The GPU, view and Slurm packages are optional for make test: without them (and not allowed to
# install them) tests/gpu/test_gpu.c is built without Vulkan and its cases count as skipped, and
# so do the lbk view cases; slurm_dist.sh installs Slurm itself when root, else is SKIPPED.
deps-test:
	@$(call deps_sh,$(DEB_TEST_PKGS),)
	@$(call deps_sh,$(GPU_PKGS),,the GPU tests will be SKIPPED (counted so))
	@$(call deps_sh,$(VIEW_PKGS),,the lbk view tests (JS reader, headless Chromium) will be SKIPPED (counted so))
	@$(call deps_sh,$(SLURM_PKGS),,tests/e2e/slurm_dist.sh installs them itself when root; else it is SKIPPED)
deps-bench:
	@$(call deps_sh,$(BENCH_DEB_PKGS),)

# The Khronos glTF-Validator (npm package, runs under node) for the `lbk export --gltf` check of
# tests/tools/gltf_validator.sh, installed into the build folder at a pinned version. npm is
# installed when running as root (and where deps_sh would); without npm and node the check is
# reported SKIPPED. make test runs this after building.
GLTF_VALIDATOR_VERSION := 2.0.0-dev.3.10
GLTF_VALIDATOR := $(BUILD)/npm/node_modules/gltf-validator
$(GLTF_VALIDATOR)/package.json:
	@mkdir -p $(BUILD)/npm
	npm install --prefix $(BUILD)/npm --no-audit --no-fund --loglevel=error gltf-validator@$(GLTF_VALIDATOR_VERSION)
gltf-validator:
	@command -v npm >/dev/null 2>&1 || ($(call deps_sh,$(NPM_PKGS),$$([ "$$(id -u)" = 0 ] && echo 'running as root'),the glTF-Validator check will be SKIPPED)) || true
	@if command -v npm >/dev/null 2>&1 && command -v node >/dev/null 2>&1; then \
	  $(MAKE) --no-print-directory $(GLTF_VALIDATOR)/package.json; \
	else echo "lbk: npm/node not found: the glTF-Validator check will be SKIPPED (apt-get install npm)"; fi

# Stock Babylon.js (npm babylonjs + babylonjs-loaders, the UMD builds) and three.js (npm three, its
# ES modules and examples/jsm's GLTFLoader) for tests/tools/test_engine_view.c, which loads
# `lbk export --gltf` with each engine's own glTF loader in headless Chromium; installed into the
# build folder at pinned versions, like the glTF-Validator (npm comes with gltf-validator above).
# Without npm those cases are reported SKIPPED.
BABYLON_VERSION := 9.28.0
THREE_VERSION := 0.187.0
ENGINE_NPM := $(BUILD)/npm-engines/node_modules
$(ENGINE_NPM)/.lbk-$(BABYLON_VERSION)-$(THREE_VERSION):
	@mkdir -p $(BUILD)/npm-engines
	npm install --prefix $(BUILD)/npm-engines --no-audit --no-fund --loglevel=error \
	    babylonjs@$(BABYLON_VERSION) babylonjs-loaders@$(BABYLON_VERSION) three@$(THREE_VERSION)
	@touch $@
engine-npm:
	@if command -v npm >/dev/null 2>&1; then $(MAKE) --no-print-directory $(ENGINE_NPM)/.lbk-$(BABYLON_VERSION)-$(THREE_VERSION); \
	else echo "lbk: npm not found: test_engine_view's Babylon.js and three.js cases will be SKIPPED (apt-get install npm)"; fi
