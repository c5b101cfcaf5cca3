# lightgear: `make run` sets up .venv and runs the paper example; `make test` runs the suite (what
# CI runs), `make test-fast` the tests that run no FE, no solver and no other process (the inner loop).
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
export VTK_DEFAULT_OPENGL_WINDOW ?= vtkEGLRenderWindow
export NUMBA_CACHE_DIR ?= $(CURDIR)/.lightgear-cache/numba
export MPLBACKEND ?= Agg
# test processes (pytest-xdist): the suite's two halves on the two cores of a small machine, each
# test file on one process (its module fixtures, built scenes and runs, made once), handed out in
# the order collected: the longest files first (tests/conftest.py LONGEST_FIRST)
JOBS   ?= 2
# the fast tier: tests/tiers.py marks each test by what it reaches (FE, solver, processes)
FAST   := not (fe or solver or process or slow)

.PHONY: run test test-fast lint bench venv sysdeps clean

run: $(STAMP)
	$(PY) -m workflows.paper_example -o results/paper_example/paper_example.nc

# one BLAS thread a test process: the two processes fill the two cores, and OpenBLAS's own threads
# on the small eigenproblems of the step bound and the modes only spin (60 -> 10 s of CPU over three
# solver test files, benchmarks/README.md); set OPENBLAS_NUM_THREADS to override
test: export OPENBLAS_NUM_THREADS ?= 1
test: $(STAMP)
	$(VENV)/bin/ruff check --quiet .
	$(PY) -m pytest -q -n $(JOBS) --dist loadscope --no-loadscope-reorder

test-fast: $(STAMP)
	$(PY) -m pytest -q -m "$(FAST)"

lint: $(STAMP)
	$(VENV)/bin/ruff check .

bench: $(STAMP)
	$(PY) benchmarks/run_all.py

venv: $(STAMP)

# The pinned stack is installed by uv (pinned below): the same wheels as pip's, unpacked and
# byte-compiled in parallel, about 16 s against pip's 50 s on two cores. Byte-compiled as pip
# does: without the .pyc files, where PYTHONDONTWRITEBYTECODE is set (CI images, containers),
# every process would compile numpy, scipy, xarray and dask from source at each start (about 15 %
# more CPU over the test suite). Where uv cannot reach the index (a machine whose pip is
# configured for a mirror uv does not read), pip installs it instead.
UV_VERSION := 0.13.9
$(STAMP): pyproject.toml requirements.lock | sysdeps
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q uv==$(UV_VERSION) && \
	  $(VENV)/bin/uv pip install -q --compile-bytecode --python $(PY) -r requirements.lock \
	  || { echo "uv could not install the stack: installing it with pip"; \
	       $(PY) -m pip install -q --upgrade pip && $(PY) -m pip install -q -r requirements.lock; }
	@# the package itself, editable; -qq: pip's setuptools prints a notice on every editable install
	$(VENV)/bin/uv pip install -q --no-deps --python $(PY) -e . 2>/dev/null || $(PY) -m pip install -qq --no-deps -e .
	touch $(STAMP)

# Off-screen rendering (pyvista/VTK) and gmsh need a few shared libraries from the OS; the FE
# contact peer (`lightgear reference --solver calculix`) needs CalculiX (ccx).
SYSLIBS := libGL.so.1 libGLU.so.1 libEGL.so.1 libXcursor.so.1 libXft.so.2 libXinerama.so.1 libgomp.so.1
DEBPKGS := libgl1 libglu1-mesa libegl1 libegl-mesa0 libgl1-mesa-dri libxcursor1 libxft2 libxinerama1 libgomp1 calculix-ccx
sysdeps:
	@missing=""; for lib in $(SYSLIBS); do ldconfig -p | grep -q "$$lib" || missing="$$missing $$lib"; done; \
	command -v ccx >/dev/null || missing="$$missing ccx(calculix-ccx)"; \
	if [ -n "$$missing" ]; then \
	  echo "Missing system libraries and programs:$$missing"; \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	    echo "Installing: $(DEBPKGS)"; apt-get update -qq && apt-get install -y -qq $(DEBPKGS) >/dev/null; \
	  else \
	    echo "Install them with: sudo apt-get install $(DEBPKGS)"; exit 1; \
	  fi; \
	fi

clean:
	rm -rf $(VENV) .lightgear-cache .pytest_cache
