# Two commands do everything on a fresh clone: `make demo` and `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test bench clean venv

venv: $(STAMP)

# (Re)install whenever pyproject.toml changes.
$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[dev,bench,logs,dask]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/bootmap demo

# One pytest worker per core (pytest-xdist); a test module stays on one worker, so its module-scoped
# servers and databases start once. Compiled modules are kept (PYTHONDONTWRITEBYTECODE cleared): the
# suite starts bootmap in a hundred child processes, which would otherwise each compile it again.
test: $(STAMP)
	PYTHONDONTWRITEBYTECODE= $(BIN)/python -m pytest -q -n auto --dist loadscope

bench: $(STAMP)
	$(BIN)/python bench/resolve_bench.py

clean:
	rm -rf $(VENV) build dist .pytest_cache
