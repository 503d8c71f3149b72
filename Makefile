# Two commands do all set-up on a fresh machine (Python >= 3.11 with venv):
#   make run    the main job
#   make test   the test suite (what .ci/run calls)
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
# The venv holds exactly the versions of requirements.lock (our reproducible set-up; pyproject.toml
# declares compatible ranges for users' environments). It is rebuilt when either file changes.
STAMP := $(VENV)/.installed-$(shell $(PY) -c "import hashlib;print(hashlib.sha1(open('pyproject.toml','rb').read()+open('requirements.lock','rb').read()+open('requirements-nodeps.txt','rb').read()).hexdigest()[:12])")

.PHONY: run test bench docs clean lock test-lower test-latest

$(STAMP): pyproject.toml requirements.lock requirements-nodeps.txt
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -r requirements.lock
	$(BIN)/python -m pip install -q --no-deps -r requirements-nodeps.txt
	$(BIN)/python -m pip install -q --no-deps --no-build-isolation -e .
	rm -f $(VENV)/.installed-*
	touch $@

PRESET ?= quick

run: $(STAMP)
	$(BIN)/slipchain reproduce --preset $(PRESET)

test: $(STAMP)
	$(BIN)/python -m pytest -n 2 -q

# The documentation site -> docs/_build/html (warnings are errors; the gallery is executed).
docs: $(STAMP)
	$(BIN)/sphinx-build -W --keep-going -b html docs docs/_build/html
	$(BIN)/sphinx-build -W --keep-going -b linkcheck docs docs/_build/linkcheck

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_engine.py
	$(BIN)/python benchmarks/dt_convergence.py

# Regenerate requirements.lock from pyproject.toml's ranges (pip-tools; keeps the pinned versions
# that still satisfy the ranges; add --upgrade to move to the newest).
lock:
	$(PY) -m venv .venv-lock && .venv-lock/bin/python -m pip install -q pip-tools
	.venv-lock/bin/pip-compile -q --extra test --extra docs --output-file requirements.lock --strip-extras --allow-unsafe \
		--no-emit-index-url --no-emit-find-links --annotation-style line $(ARGS) pyproject.toml

# The suite at the lower bounds of pyproject.toml's ranges, and at the newest releases (own venvs).
test-lower:
	.ci/bounds lower

test-latest:
	.ci/bounds latest

clean:
	rm -rf $(VENV) .venv-lock .venv-lower .venv-latest .numba_cache results dist
