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

# One pytest worker more than there are cores (pytest-xdist): many tests wait on servers and child
# processes (start-up, time-outs), and the extra worker fills those waits (2 cores, one run each: three
# workers 5 min 35 s, two 6 min 2 s, four 5 min 54 s). A test module stays on one worker, so its
# module-scoped servers and databases start once. Compiled modules are kept (PYTHONDONTWRITEBYTECODE
# cleared): the suite starts bootmap in a hundred child processes, which would otherwise each compile it.
WORKERS ?= $(shell $(PYTHON) -c "import os; print((os.cpu_count() or 1) + 1)")
test: $(STAMP)
	PYTHONDONTWRITEBYTECODE= $(BIN)/python -m pytest -q -n $(WORKERS) --dist loadscope

bench: $(STAMP)
	$(BIN)/python bench/resolve_bench.py

clean:
	rm -rf $(VENV) build dist .pytest_cache
