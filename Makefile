# The two set-up commands: `make demo` and `make test`. Both create .venv when missing and
# install idempotently (a stamp file records the last install of pyproject.toml).
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
FRONT_STAMP := static/.built

.PHONY: demo test install lint frontend bench clean

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

test: install frontend lint
	$(BIN)/python -m pytest -q

bench: install
	$(BIN)/python -m bench.run_all

clean:
	rm -rf $(VENV) static/assets $(FRONT_STAMP)
