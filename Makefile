# Two entry points: `make demo` and `make test`. Both create .venv on first use.
# `make docs` builds the documentation site into build/docs/html.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
CORE   := $(VENV)/.installed-core

.PHONY: demo test lint bench docs clean

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

# the demo needs the library alone; the tests, docs and lint need the test extra
$(CORE): pyproject.toml $(VENV)/bin/python
	$(PY) -m pip install --quiet -e .
	touch $(CORE)

$(STAMP): pyproject.toml $(VENV)/bin/python
	$(PY) -m pip install --quiet -e ".[test]"
	touch $(CORE) $(STAMP)

demo: $(CORE)
	$(VENV)/bin/mechsys demo --out out

# two workers (pytest-xdist): this project's machines have two cores; the tests that start a
# Jupyter kernel then run in one process of their own (decision 0052)
test: $(STAMP)
	$(PY) -m pytest -n 2 -m "not jupyter_kernel" tests
	$(PY) -m pytest -m jupyter_kernel tests

lint: $(STAMP)
	$(VENV)/bin/ruff check src tests examples benchmarks docs/conf.py docs/_gen

bench: $(STAMP)
	$(PY) -m pip install --quiet -e ".[bench]"
	$(PY) benchmarks/kinematic_sweep.py --write docs/performance.md
	$(PY) benchmarks/peers/run.py --write docs/performance.md
	$(PY) benchmarks/energy_drift.py --write docs/free_motion.md

# The documentation site: regenerated reference pages, the gallery (examples run only when
# changed, pictures cached in docs/gallery/_media), then Sphinx with warnings as errors.
docs: $(STAMP)
	$(PY) -m mechsys._docgen docs/constraints.md
	$(PY) docs/_gen/gen_mech_map.py docs/mech_to_mechsys.md
	$(PY) docs/_gen/gen_gallery.py
	$(PY) -m sphinx -W --keep-going -q -b html docs build/docs/html
	@echo "site: build/docs/html/index.html"

clean:
	rm -rf $(VENV) out build *.egg-info src/*.egg-info
	find src -name '*.nbi' -delete -o -name '*.nbc' -delete
