# The two set-up commands: `make demo` and `make test`. Both create .venv when missing and
# install idempotently (a stamp file records the last install of pyproject.toml).
# `make test-fast` is the quick tier (lint, types, tests not marked slow); `make wheel`
# builds dist/proxima-*.whl (it needs the console built: `make frontend`).
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
FRONT_STAMP := static/.built

.PHONY: demo test test-fast install lint typecheck frontend bench wheel clean

$(BIN)/python:
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

# torch first, pinned to the local CPU build, so that nothing later pulls a CUDA build.
$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -q torch==2.13.0
	$(BIN)/python -m pip install -q -e ".[dev]"
	touch $(STAMP)

install: $(STAMP)

frontend: $(FRONT_STAMP)

FRONT_SRC := $(shell find frontend -path frontend/node_modules -prune -o -type f -print 2>/dev/null)

$(FRONT_STAMP): $(FRONT_SRC)
	@if [ -f frontend/package.json ]; then \
		cd frontend && npm ci --no-audit --no-fund && npm run build && touch ../$(FRONT_STAMP); \
	else mkdir -p static && touch $(FRONT_STAMP); fi

demo: install frontend
	$(BIN)/proxima demo

# The README's and docs/console.md's pictures: the browser tests save them under
# runs/screenshots/ (ignored, so `make test` leaves the tree clean); this reruns those
# tests and copies the pictures over docs/screenshots/.
.PHONY: screenshots
screenshots: install frontend
	rm -rf runs/screenshots
	$(BIN)/python -m pytest -q tests/ui
	cp runs/screenshots/*.png docs/screenshots/

lint: install
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

typecheck: install
	$(BIN)/mypy

test: install frontend lint typecheck
	$(BIN)/python -m pytest -q -n 2

# No model training, simulator processes, browser, RTSP server or wheel build (the tests
# marked slow, see tests/conftest.py); under 3 minutes on a 2-core machine.
test-fast: install lint typecheck
	$(BIN)/python -m pytest -q -m "not slow"

# Every benchmark at bounded sizes; results in bench/results/latest/ (bench/run_all.py).
bench: install
	$(BIN)/python -m bench.run_all

wheel: install frontend
	rm -rf dist
	$(BIN)/python -m pip wheel -q --no-deps --no-build-isolation -w dist .

clean:
	rm -rf $(VENV) static/assets $(FRONT_STAMP) build dist
