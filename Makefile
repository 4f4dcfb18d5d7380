# plausible: the two commands of the README's Quick start, plus helpers.
# Each target sets itself up (virtual environment, install, system packages) and is idempotent.

PY       ?= python3
VENV     := .venv
BIN      := $(VENV)/bin
STAMP    := $(VENV)/.installed-$(shell cat pyproject.toml | sha1sum | cut -c1-12)
OUT      ?= out
JOBS     ?= 2
# three.js for the example page's test (tests/export/test_three.py); the version of
# examples/three/index.html's import map.
THREE_VERSION := 0.187.0
THREE_DIR     := .cache/npm/node_modules/three
# The Khronos glTF validator for the glTF export's tests (tests/export/test_gltf.py).
GLTF_VALIDATOR_VERSION := 2.0.0-dev.3.10
GLTF_VALIDATOR_DIR     := .cache/npm/node_modules/gltf-validator

# Blender as a Python module for plausible.blender (issue 46): bpy pins numpy<2 and CPython 3.11, so it
# gets an environment of its own, run out of process (src/plausible/blender/runner.py).
BLENDER_PY      ?= python3.11
BLENDER_VERSION := 5.0.1
BLENDER_VENV    := .venv-blender
BLENDER_STAMP   := $(BLENDER_VENV)/.installed-bpy-$(BLENDER_VERSION)
# The X11/GL client libraries bpy links against (it renders headless; Debian 12 names).
BLENDER_LIBS    := libx11-6 libxi6 libxfixes3 libxrender1 libxext6 libxkbcommon0 libsm6 libgl1

.PHONY: demo test test-all bench mitsuba-builtins setup llvm chromium glslang three gltf-validator blender blender-libs clean

setup: $(STAMP) llvm chromium glslang three gltf-validator blender

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[dev]"
	touch $@

# Dr.Jit's LLVM backend needs a shared libLLVM; Debian 12's libLLVM 15 crashes
# (`Cannot select: f32 = fmaximum`), libllvm19 works.
llvm:
	@if ! ls /usr/lib/*/libLLVM-19.so* >/dev/null 2>&1 && ! ls /usr/lib/*/libLLVM.so.19* >/dev/null 2>&1; then \
	  if [ "$$(id -u)" = 0 ]; then apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19 >/dev/null; \
	  else sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19 >/dev/null; fi; \
	fi

# A real browser for the report's test (tests/figures: every image of index.html loads).
chromium:
	@if ! command -v chromium >/dev/null 2>&1; then \
	  if [ "$$(id -u)" = 0 ]; then apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; \
	  else sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; fi; \
	fi

# The Khronos reference GLSL compiler for the shader export's tests (tests/export/test_glslang.py).
glslang:
	@if ! command -v glslangValidator >/dev/null 2>&1; then \
	  if [ "$$(id -u)" = 0 ]; then apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq glslang-tools >/dev/null; \
	  else sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq glslang-tools >/dev/null; fi; \
	fi

# three.js from the npm registry, pinned, into .cache/npm (npm from Debian if missing).
three:
	@if ! grep -qs '"version": "$(THREE_VERSION)"' $(THREE_DIR)/package.json; then \
	  if ! command -v npm >/dev/null 2>&1; then \
	    if [ "$$(id -u)" = 0 ]; then apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq npm >/dev/null; \
	    else sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq npm >/dev/null; fi; \
	  fi; \
	  mkdir -p .cache/npm && npm install --silent --no-audit --no-fund --prefix .cache/npm three@$(THREE_VERSION); \
	fi

# The Khronos glTF validator from the npm registry, pinned, into .cache/npm beside three.js
# (npm records both in .cache/npm/package.json, so neither install removes the other).
gltf-validator: three
	@if ! grep -qs '"version": "$(GLTF_VALIDATOR_VERSION)"' $(GLTF_VALIDATOR_DIR)/package.json; then \
	  npm install --silent --no-audit --no-fund --prefix .cache/npm gltf-validator@$(GLTF_VALIDATOR_VERSION); \
	fi

# Blender (bpy) in .venv-blender for the tests of tests/blender (about 1 GB installed, 375 MB download).
blender: blender-libs $(BLENDER_STAMP)

$(BLENDER_STAMP):
	test -x $(BLENDER_VENV)/bin/python || $(BLENDER_PY) -m venv $(BLENDER_VENV)
	$(BLENDER_VENV)/bin/python -m pip install -q --upgrade pip
	$(BLENDER_VENV)/bin/python -m pip install -q "bpy==$(BLENDER_VERSION)"
	$(BLENDER_VENV)/bin/python -c "import bpy"
	touch $@

blender-libs:
	@missing=$$(for p in $(BLENDER_LIBS); do dpkg -s $$p >/dev/null 2>&1 || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ]; then apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing >/dev/null; \
	  else sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing >/dev/null; fi; \
	fi

# The main job: every figure of the papers, measured, as a browsable report -> $(OUT)/index.html.
demo: setup
	$(BIN)/plausible figures --out $(OUT)

# The default test run (under 10 minutes on 2 cores).
test: setup
	$(BIN)/python -m pytest -q -n $(JOBS) -m "not slow"

# Everything, exhaustive sweeps included.
test-all: setup
	$(BIN)/python -m pytest -q -n $(JOBS)

bench: setup
	mkdir -p $(OUT)
	$(BIN)/python -m pytest -q benchmarks --benchmark-only -p no:xdist --benchmark-json=$(OUT)/bench.json
	$(BIN)/python benchmarks/report.py $(OUT)/bench.json > $(OUT)/benchmarks.md

# docs/mitsuba-builtins.md: Mitsuba 3's own BSDFs under plausible check (about 30 minutes on 2 cores).
mitsuba-builtins: setup
	$(BIN)/python scripts/mitsuba_builtins.py

clean:
	rm -rf $(VENV) $(BLENDER_VENV) $(OUT) .pytest_cache .cache/npm
