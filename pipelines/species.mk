# The top of every species Makefile: its settings, tools and sources (formats/species.md).
#
# A species Makefile sets QUALITY, HERE (its folder), ROOT and B (its build folder), includes this
# file, writes its own stages, and ends with `include $(ROOT)/pipelines/common.mk` (quality.txt,
# check, usd, clean). This file gives:
#
# - the [settings] and the [draft] or [final] table of $(HERE)/species.toml as make variables
#   (names upper-cased, lists joined by commas: `sheet = [1, 6, 12]` -> `SHEET := 1,6,12`), with
#   SPECIES, TITLE and USD_PARTS (`NAME=$(B)/path ...` of its [usd] parts, for canopy-export).
#   They are written to $(B)/.species-$(QUALITY).mk by `python -m inflo.tools.species vars`
#   (standard library only, rewritten only when they change) each time make reads the Makefile;
#   a QUALITY the file has no table for, or a malformed species.toml, stops make with its
#   one-line error;
# - Q (the quality), TLAST and LAST (the last template frame and frame, 4 digits);
# - BIN, PY: the tools and Python of the repository's .venv (else those on PATH);
# - the sources each stage depends on (FLORET_SRC ... EXPORT_SRC: formats/ and the tool's own
#   package), so that a change of a tool reruns the stages it makes;
# - RENDER: canopy-render with the species' background (setting `background`, else sky blue) and
#   its colors.toml.

.DEFAULT_GOAL := all

BIN := $(if $(wildcard $(ROOT)/.venv/bin/floret-animate),$(ROOT)/.venv/bin/,)
PY := $(if $(wildcard $(ROOT)/.venv/bin/python),$(ROOT)/.venv/bin/python,python3)

SPECIES_VARS := $(B)/.species-$(QUALITY).mk
SPECIES_ERROR := $(shell $(PY) -m inflo.tools.species vars $(HERE)/species.toml --quality '$(QUALITY)' -o $(SPECIES_VARS) 2>&1 >/dev/null || echo '(inflo.tools.species vars failed)')
ifneq ($(strip $(SPECIES_ERROR)),)
$(error $(SPECIES_ERROR))
endif
include $(SPECIES_VARS)
Q := $(QUALITY)
# the last template frame and the last frame (4 digits) where the settings or the Makefile give
# their counts (a head's FRAMES comes from its head.toml: it computes its LAST itself)
ifdef TEMPLATE_FRAMES
TLAST := $(shell printf '%04d' $$(($(TEMPLATE_FRAMES) - 1)))
endif
ifdef FRAMES
LAST := $(shell printf '%04d' $$(($(FRAMES) - 1)))
endif

SRC = $(wildcard $(ROOT)/formats/*.py $(foreach t,$(1),$(ROOT)/tools/$(t)/*.py))
FLORET_SRC := $(call SRC,floret_animate bspline)
POLY_SRC := $(call SRC,polygonize bspline)
PHYLLO_SRC := $(call SRC,phyllotaxis)
DIMORPH_SRC := $(call SRC,dimorph)
FCC_SRC := $(call SRC,fccompose pbd collide)
SUBDIV_SRC := $(call SRC,subdivide collide)
BRANCH_SRC := $(call SRC,branch_gen)
THYRSE_SRC := $(call SRC,thyrse branch_gen)
PETAL_SRC := $(call SRC,petal_grow pbd collide)
RENDER_SRC := $(call SRC,canopy_render)
# canopy-export takes its colour rules from canopy-render's colors.py
EXPORT_SRC := $(call SRC,canopy_export) $(ROOT)/tools/canopy_render/colors.py

# fccompose's iteration scheme (species.toml `scheme`, per quality; formats/fcc.md "Solver scheme"):
# `default` unless a quality names `fast`
SCHEME ?= default
BACKGROUND ?= 0.55,0.70,0.86
RENDER := $(BIN)canopy-render -q --background $(BACKGROUND) --colors colors.toml
