# hapticrom: every target creates the environment it needs.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
PIP := $(BIN)/pip install --quiet -c constraints.txt

.PHONY: demo test test-slow lint bench bench-accuracy clean venv js

$(STAMP): pyproject.toml constraints.txt
	$(PY) -m venv $(VENV)
	$(PIP) -e ".[dev,bench]"
	touch $(STAMP)

venv: $(STAMP)

# What tests/embed needs: the npm packages of embed/ and Debian's chromium (installed if missing).
JS_STAMP := embed/node_modules/.package-lock.json
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

$(JS_STAMP): embed/package.json embed/package-lock.json
	cd embed && npm ci --no-audit --no-fund

js: $(JS_STAMP)
	command -v chromium >/dev/null 2>&1 || ($(SUDO) apt-get update && $(SUDO) apt-get install -y chromium)

UNITS := unit-bare-forward unit-double-forward unit-triple-reverse-pogo

demo: $(STAMP)
	mkdir -p out
	$(BIN)/hapticrom simulate examples/forearm.toml --json out/forearm.json --plot out/forearm.png --vtk out/forearm.vtu
	for u in $(UNITS); do \
	  $(BIN)/hapticrom simulate examples/$$u.toml --json out/$$u.json --plot out/$$u.png || exit 1; \
	done
	$(BIN)/hapticrom simulate examples/unit-sweep.toml --json out/unit-sweep.json --plot out/unit-sweep.png
	$(BIN)/hapticrom models list --root models
	$(BIN)/hapticrom predict --csv examples/designs.csv --json out/designs-nn.json
	$(BIN)/python examples/surrogate_vs_fe.py
	$(BIN)/hapticrom plan examples/forearm-layout.toml --out out/plan.json --plot out/plan.png
	$(BIN)/hapticrom play out/plan.json examples/pattern-sweep.toml --device sim --out out/play --overwrite
	$(BIN)/hapticrom calibrate examples/measurement-forearm.csv \
	  --fit skin_E_kPa,fat_thickness_mm,tissue_loss_factor --out out/calibration.json --plot out/calibration.png
	$(BIN)/hapticrom plan examples/forearm-layout.toml --tissue out/calibration.json --out out/plan-person.json

test: $(STAMP) js
	$(BIN)/ruff check .
	$(BIN)/lint-imports
	HAPTICROM_REQUIRE_JS=1 $(BIN)/python -m pytest -q

test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -m slow

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/lint-imports

bench: $(STAMP)
	$(BIN)/python bench/fem/solver.py $(if $(BASELINE),--baseline $(BASELINE))
	$(BIN)/python bench/fem/accuracy.py
	$(BIN)/python bench/fem/effects.py
	$(BIN)/python bench/fem/absorber.py
	$(BIN)/python bench/fem/backends.py
	$(BIN)/python bench/datasets/generate.py
	$(BIN)/python bench/datasets/mesh_plan.py
	$(BIN)/python bench/surrogate/latency.py
	$(BIN)/python bench/planner/plan.py

# What accuracy costs in time: writes docs/accuracy-vs-time.md and .png (about 10 minutes).
bench-accuracy: $(STAMP)
	$(BIN)/hapticrom bench accuracy --out docs/accuracy-vs-time.md

clean:
	rm -rf $(VENV) out
