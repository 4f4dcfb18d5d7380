# plausible: the two commands of the README's Quick start, plus helpers.
# Each target sets itself up (virtual environment, install, system packages) and is idempotent.

PY       ?= python3
VENV     := .venv
BIN      := $(VENV)/bin
STAMP    := $(VENV)/.installed-$(shell cat pyproject.toml | sha1sum | cut -c1-12)
OUT      ?= out
JOBS     ?= 2

.PHONY: demo test test-all bench mitsuba-builtins setup llvm chromium glslang clean

setup: $(STAMP) llvm chromium glslang

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
	rm -rf $(VENV) $(OUT) .pytest_cache
