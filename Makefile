# kinema — every target sets up what it needs from Python 3.11+, Rust and the package registries.
#   make demo   set up, build (release), run the demonstration; writes to out/
#   make test   set up, build, then cargo test and pytest
#   make bench  set up, build, run the benchmarks (kinema beside its peers, one table each)
#   make fuzz   set up, build, run the fuzz suite (tests/test_fuzz.py) with many more cases
#   make docs   the documentation site (MkDocs, strict: a broken link or reference fails) → site/
#   make pictures  the README's pictures of the example scenes (docs/img/scene_*.png)
#   make fmt    format Rust and Python sources

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
PIP    := $(VENV)/bin/pip
STAMP  := $(VENV)/.deps-installed
TEST_STAMP := $(VENV)/.test-deps-installed
BUILT  := $(VENV)/.kinema-built
RUST_SOURCES := $(shell find crates -name '*.rs' -o -name Cargo.toml) Cargo.toml pyproject.toml

.PHONY: demo test test-rust test-python fuzz bench pictures fmt setup build viewer wheel-check clean docs

setup: $(STAMP)

$(STAMP): requirements/dev.txt
	$(PYTHON) -m venv $(VENV)
	$(PIP) install --disable-pip-version-check -q -r requirements/dev.txt
	touch $@

# The browser and Jupyter tests' extras (playwright drives the system's Chromium; nothing
# downloaded) and the outside readers of kinema's files (OVITO, VTK, MDAnalysis, freud, Blender, ...).
$(TEST_STAMP): $(STAMP) requirements/viewer-test.txt requirements/formats-test.txt requirements/blender-test.txt
	$(PIP) install --disable-pip-version-check -q -r requirements/viewer-test.txt -r requirements/formats-test.txt
	($(PYTHON) -m venv .venv-blender && .venv-blender/bin/pip install --disable-pip-version-check -q -r requirements/blender-test.txt) || echo "bpy (Blender) could not be installed: the Blender tests will say so and skip"
	touch $@

# Release build of the extension, installed into the venv in editable mode (python/ is used in place).
build: $(BUILT)

$(BUILT): $(STAMP) $(RUST_SOURCES)
	$(VENV)/bin/maturin develop --release -q
	touch $@

# The documentation site: docs/ with the API reference from the docstrings (mkdocstrings) and
# the command line's (mkdocs-click), built strictly (mkdocs.yml: a warning fails) into site/.
# JUPYTER_CONFIG_PATH: requirements/jupyter/jupyter_config.json has the notebooks' kernels
# started with CurveZMQ encryption, not over plain TCP (ipykernel warns of that once per notebook).
DOCS_STAMP := $(VENV)/.docs-deps-installed
$(DOCS_STAMP): $(STAMP) requirements/docs.txt
	$(PIP) install --disable-pip-version-check -q -r requirements/docs.txt
	touch $@

docs: $(BUILT) $(DOCS_STAMP)
	JUPYTER_CONFIG_PATH=$(CURDIR)/requirements/jupyter NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict

# The browser viewer's script: three.js and viewer/src bundled by esbuild (pinned in
# viewer/package-lock.json). The bundle is committed, so that building and installing kinema
# needs no Node; after changing viewer/src run `make viewer` and commit the bundle
# (tests/test_viewer_bundle.py checks that it is what viewer/src builds).
viewer:
	cd viewer && npm ci --no-audit --no-fund --loglevel=error && node build.mjs

# The package as a user installs it: the release wheel into a fresh venv outside the checkout
# (nothing of python/ on the path), then `kinema demo` and `kinema view --html` from it. CI
# runs this after `make test`.
WHEEL_DIR := target/wheel-check
wheel-check: $(STAMP)
	rm -rf $(WHEEL_DIR) && mkdir -p $(WHEEL_DIR)/run
	$(VENV)/bin/maturin build --release -q -o $(WHEEL_DIR)
	$(PYTHON) -m venv $(WHEEL_DIR)/venv
	$(WHEEL_DIR)/venv/bin/pip install --disable-pip-version-check -q $(WHEEL_DIR)/kinema-*.whl
	cd $(WHEEL_DIR)/run && ../venv/bin/kinema --version && ../venv/bin/kinema demo --out demo
	cd $(WHEEL_DIR)/run && test -s demo/demo.html && test -s demo/demo.mp4 && ../venv/bin/kinema view demo/trajectory.h5 --html view.html && test -s view.html
	@echo "wheel-check: the installed wheel ran kinema demo and kinema view --html"

demo: build
	$(VENV)/bin/kinema demo --out out

test: test-rust test-python

test-rust:
	cargo test --workspace --exclude kinema-py --release

test-python: build $(TEST_STAMP)
	command -v chromium >/dev/null || apt-get install -y -q chromium >/dev/null || (apt-get update -q >/dev/null && apt-get install -y -q chromium >/dev/null) || echo "chromium could not be installed: the browser tests will say so and skip"
	command -v lmp >/dev/null || apt-get install -y -q lammps >/dev/null || (apt-get update -q >/dev/null && apt-get install -y -q lammps >/dev/null) || echo "LAMMPS could not be installed: the tests of files LAMMPS writes will say so and skip"
	$(PY) -m pytest -q

# The fuzz suite alone, FUZZ_EXAMPLES cases per test (make test runs it with 40; 2000: 72,953 cases, 17 min).
FUZZ_EXAMPLES ?= 2000

fuzz: build
	KINEMA_FUZZ_EXAMPLES=$(FUZZ_EXAMPLES) $(PY) -m pytest -q tests/test_fuzz.py

bench: build $(TEST_STAMP)
	command -v lmp >/dev/null || apt-get install -y -q lammps >/dev/null || echo "LAMMPS could not be installed: the benchmarks beside it will say so"
	OPENBLAS_NUM_THREADS=1 $(PY) benchmarks/speed_targets.py
	$(PY) benchmarks/ode_overhead.py
	$(PY) benchmarks/render.py
	$(PY) benchmarks/viewer.py
	command -v lmp >/dev/null || apt-get install -y -q lammps >/dev/null || echo "LAMMPS could not be installed: the collision benchmark will say so and skip"
	$(PY) benchmarks/collisions_lammps.py
	$(PY) benchmarks/granular_gas.py --ncell 47 --steps 1000 --threads 2
	$(PY) benchmarks/granular_gas.py --ncell 47 --steps 1000 --threads 2 --model impulse --repeat 1
	$(PY) benchmarks/granular_gas.py --sizes --repeat 1
	$(PY) benchmarks/springs.py
	$(PY) benchmarks/mixed_radii.py
	$(PY) benchmarks/impacts.py
	$(PY) benchmarks/hard_sphere_gas.py
	$(PIP) install --disable-pip-version-check -q -r requirements/bench.txt
	command -v cmake >/dev/null && dpkg -s libclang-dev >/dev/null 2>&1 || apt-get install -y -q cmake libclang-dev >/dev/null || echo "cmake/libclang could not be installed: piles.py will say whether it could build its Box2D/Jolt peers"
	$(PY) benchmarks/piles.py
	cargo bench -p kinema --bench pile_solve
	$(PY) benchmarks/granular_lammps.py
	$(PY) benchmarks/angle_of_repose.py
	$(PY) benchmarks/pile_measures.py

pictures: build
	$(PY) docs/pictures.py docs/img

fmt: $(STAMP)
	cargo fmt --all
	$(VENV)/bin/ruff format python tests benchmarks examples
	$(VENV)/bin/ruff check --fix python tests benchmarks examples

clean:
	rm -rf target $(VENV) .venv-blender out
