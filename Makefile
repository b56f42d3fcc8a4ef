# PhotoDEM — the README's commands. Every target sets up what it needs from nothing.
SHELL := /bin/bash
PY ?= python3
VENV := .venv
VENV_QGIS := .venv-qgis
SYS_PY := /usr/bin/python3
STAMP_A := $(VENV)/.installed
STAMP_B := $(VENV_QGIS)/.installed
export QT_QPA_PLATFORM ?= offscreen
export MPLBACKEND ?= Agg

# Debian packages of tier B: QGIS 3.22 with the core's dependencies from Debian.
APT_PACKAGES := qgis python3-qgis qgis-providers python3-pyqt5 python3-rasterio python3-fiona \
	python3-shapely python3-pyproj python3-skimage python3-scipy python3-matplotlib python3-yaml python3-opencv \
	python3-pytest python3-pytestqt python3-venv qttools5-dev-tools pyqt5-dev-tools \
	python3-dask python3-distributed

.PHONY: demo test test-a test-b test-fast gui bench lint zip venv venv-qgis apt clean

venv: $(STAMP_A)
$(STAMP_A): pyproject.toml
	$(PY) -m venv $(VENV)
	$(VENV)/bin/pip install -q --upgrade pip
	$(VENV)/bin/pip install -q -e ".[gui,test]"
	touch $@

apt:
	@if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	  missing=$$(for p in $(APT_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || echo $$p; done); \
	  if [ -n "$$missing" ]; then \
	    echo "Installing Debian packages: $$missing"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing >/dev/null; \
	  fi; \
	else echo "Not root or no apt-get: install these Debian packages yourself: $(APT_PACKAGES)"; fi

venv-qgis: $(STAMP_B)
$(STAMP_B): pyproject.toml | apt
	$(SYS_PY) -m venv --system-site-packages $(VENV_QGIS)
	$(VENV_QGIS)/bin/pip install -q --no-deps -e .
	@# Debian has neither laspy nor lazrs: LAS/LAZ from PyPI (pure Python + a binary wheel; no
	@# dependency beyond Debian's numpy), else the LAS/LAZ tests skip with that reason
	$(VENV_QGIS)/bin/pip install -q --no-deps "laspy>=2" lazrs || \
	  echo "laspy/lazrs could not be installed: LAS and LAZ are not available in tier B"
	touch $@

demo: venv
	$(VENV)/bin/photodem demo demo-output

test: test-a test-b

test-a: venv
	$(VENV)/bin/ruff check .
	PHOTODEM_TEST_TRACE=.test-trace/a $(VENV)/bin/python -m pytest -q tests -m "not qgis" \
	  -p no:cacheprovider || { status=$$?; $(PY) tools/hang_report.py .test-trace/a; exit $$status; }

# While working: tier A without the tests marked slow (end-to-end runs); `make test` runs all.
test-fast: venv
	$(VENV)/bin/ruff check .
	PHOTODEM_TEST_TRACE=.test-trace/fast $(VENV)/bin/python -m pytest -q tests \
	  -m "not qgis and not slow" -p no:cacheprovider \
	  || { status=$$?; $(PY) tools/hang_report.py .test-trace/fast; exit $$status; }

test-b: venv-qgis
	bash tools/run_tier_b.sh $(VENV_QGIS)/bin/python

gui: venv
	$(VENV)/bin/photodem gui

# Peers are installed in the bench environment only.
VENV_BENCH := .venv-bench
BENCH_PEERS := orthority opencv-python-headless xdem cloth-simulation-filter pysmrf
$(VENV_BENCH)/.installed: pyproject.toml
	$(PY) -m venv $(VENV_BENCH)
	$(VENV_BENCH)/bin/pip install -q --upgrade pip
	$(VENV_BENCH)/bin/pip install -q -e ".[dask]" $(BENCH_PEERS)
	touch $@

bench: $(VENV_BENCH)/.installed
	$(VENV_BENCH)/bin/python -m bench

lint: venv
	$(VENV)/bin/ruff check .

zip: venv-qgis
	$(VENV_QGIS)/bin/python tools/build_zip.py dist

clean:
	rm -rf $(VENV) $(VENV_QGIS) $(VENV_BENCH) dist build demo-output .pytest_cache .ruff_cache
