# inflo top-level Makefile: make <species> (make species lists them: lily, yarrow, sunflower, ...) | make test | make test-blender | make bench | make golden | make clean
# The first target run on a fresh clone creates .venv and installs inflo with its test extras.

QUALITY ?= draft
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.inflo-installed
PYTEST_ARGS ?=

export QUALITY
# numba caches compiled kernels beside the sources; keep them out of the way of stale builds
export PATH := $(CURDIR)/$(VENV)/bin:$(PATH)

.PHONY: test-fast lint all venv bytecode kernels test test-blender bench golden golden-check species new-species $(SPECIES_DIRS) clean distclean

all: lily

venv: $(STAMP) bytecode kernels

$(STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip setuptools wheel
	$(PY) -m pip install --quiet -e '.[test]'
	@sh tools/canopy_render/ensure_system_gl.sh
	@sh tools/canopy_view/ensure_browser.sh
	@touch $(STAMP)

# the canopy's numba kernels compiled ahead, at install (make venv; python -m inflo.tools.warm: a
# 20-floret canopy run once, about 1.8 min on 2 cores on a fresh machine, 3 s once numba's cache holds
# them), so that a first canopy run loads them in about a second instead of compiling them for about
# 100 s (issue 51's start-up; docs/architecture.md). Rerun when the modules holding them change. The
# species targets and make test do not wait for it (they compile what they call as they go: a first
# make -B lily took 2.1 min with an empty cache, 0.9 min after this step's 1.8)
KERNELS := $(VENV)/.inflo-kernels
KERNEL_SRC := $(wildcard tools/collide/*.py tools/pbd/*.py tools/fccompose/*.py tools/common/*.py tools/warm/*.py)
kernels: $(KERNELS)
$(KERNELS): $(STAMP) $(KERNEL_SRC)
	@$(PY) -m inflo.tools.warm
	@touch $@

# the sources' bytecode, written ahead (0.1 s when nothing changed): where PYTHONDONTWRITEBYTECODE is
# set (as on this project's VMs and many container images) Python would otherwise compile every
# imported module of every CLI call again, 0.15-0.3 s of each call's start (docs/architecture.md)
bytecode: $(STAMP)
	@$(PY) -m compileall -q tools formats > /dev/null

# make test runs two pytest processes side by side (2 cores): the species builds and the tests that
# read build/<species> (tests/test_golden.py and tests/test_pipeline_*.py in one process; each species
# is built once per session by conftest's species_build, whichever test asks first), and every other
# test file; each process's report is printed whole, and the target fails if
# either does. With PYTEST_ARGS (a selection: -k, a file) it is one plain pytest run.
# Two of the portability builds (tests/test_portable.py: a numba target compiled afresh, numpy's
# baseline SIMD) run in the first process too, so that the two end near the same time (the second
# was 22.5 min against the first's 12 in CI). Each process prints its 15 longest tests.
BUILD_TESTS := tests/test_golden.py $(sort $(wildcard tests/test_pipeline_*.py))
PORTABLE_MOVED := $(foreach v,numba-generic numpy-baseline-simd,'tests/test_portable.py::test_stage_outputs_are_byte_identical_under[$(v)]')
test: $(STAMP) bytecode lint
ifeq ($(strip $(PYTEST_ARGS)),)
	@mkdir -p build; \
	$(PY) -m pytest -q -p no:cacheprovider --durations=15 $(BUILD_TESTS) $(PORTABLE_MOVED) > build/.test-builds.log 2>&1 & builds=$$!; \
	$(PY) -m pytest -q --durations=15 $(foreach f,$(BUILD_TESTS),--ignore=$(f)) $(foreach t,$(PORTABLE_MOVED),--deselect $(t)) \
		> build/.test-rest.log 2>&1; rest=$$?; \
	wait $$builds; b=$$?; \
	echo "== tests that build species or read their builds: $(BUILD_TESTS)"; cat build/.test-builds.log; \
	echo "== every other test"; cat build/.test-rest.log; \
	test $$b -eq 0 -a $$rest -eq 0
else
	$(PY) -m pytest -q $(PYTEST_ARGS)
endif

# ruff over the whole tree ([tool.ruff] in pyproject.toml); make test runs it first (about a second)
lint: $(STAMP)
	$(VENV)/bin/ruff check --quiet .

# the fast door while working: every test but the species builds (and the tests that read them),
# the ones marked slow (the portability builds, a scaffolded species, the longest canopies) and
# Blender's; about 3 minutes on 2 cores. `make test` stays the full suite (CI runs it).
test-fast: $(STAMP) bytecode
	$(PY) -m pytest -q -p no:cacheprovider -m "not slow and not blender" $(foreach f,$(BUILD_TESTS),--ignore=$(f)) $(PYTEST_ARGS)

# tests/test_blender.py in real Blender: bpy 4.5 LTS (a 370 MB wheel) in its own venv, not in CI's make test
test-blender: $(STAMP) bytecode
	@test -x .venv-blender/bin/python || $(PYTHON) -m venv .venv-blender
	@.venv-blender/bin/python -c 'import bpy' 2>/dev/null || .venv-blender/bin/python -m pip install --quiet 'bpy==4.5.*'
	$(PY) -m pytest -q tests/test_blender.py $(PYTEST_ARGS)
	$(PY) -m pytest -q tests/test_blender_addon.py $(PYTEST_ARGS)

# the Blender add-on (blender/inflo_blender/, docs/blender.md): a zip for Edit > Preferences >
# Add-ons (Blender 4.2 and 4.5 LTS); standard library only, no venv needed
.PHONY: blender-addon
blender-addon: build/inflo_blender.zip
build/inflo_blender.zip: $(wildcard blender/inflo_blender/*.py blender/inflo_blender/*.toml) blender/make_zip.py
	$(PYTHON) blender/make_zip.py -o $@

bench: $(STAMP) bytecode
	$(PY) -m bench.run

# golden stage outputs (tests/golden/README.md): rebuild every species at draft quality and take
# its outputs as the new goldens after an intended change; golden-check only reports differences
golden: $(STAMP) bytecode
	$(PY) -m inflo.tools.golden refresh all

golden-check: $(STAMP) bytecode
	$(PY) -m inflo.tools.golden check all --rebuild

# every species is a folder pipelines/<species>/ with its species.toml (formats/species.md): found,
# not listed; `make <species>` builds one, `make species` lists them
SPECIES_DIRS := $(sort $(patsubst pipelines/%/species.toml,%,$(wildcard pipelines/*/species.toml)))

species: $(STAMP)
	@$(PY) -m inflo.tools.species list

# a new species from an existing one, by data (docs/new_species.md): make new-species NAME=daisy FROM=sunflower
new-species: $(STAMP)
	@$(PY) -m inflo.tools.species new '$(NAME)' --from '$(FROM)' $(if $(TITLE),--title '$(TITLE)')

$(SPECIES_DIRS): $(STAMP) bytecode
	$(MAKE) -C pipelines/$@ QUALITY=$(QUALITY)

# a species' plant (a stem with leaves carrying several of its flowers, offset in age): make lily-plant,
# make eustoma-plant
.PHONY: lily-plant eustoma-plant
lily-plant: $(STAMP) bytecode
	$(MAKE) -C pipelines/lily plant QUALITY=$(QUALITY)

eustoma-plant: $(STAMP) bytecode
	$(MAKE) -C pipelines/eustoma plant QUALITY=$(QUALITY)

clean:
	rm -rf build bench/out .pytest_cache .hypothesis
	find . -path ./$(VENV) -prune -o -name __pycache__ -type d -prune -exec rm -rf {} +

distclean: clean
	rm -rf $(VENV) *.egg-info
