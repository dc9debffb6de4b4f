# A species' settings as make variables, read from its species.toml (formats/species.md).
#
# A species Makefile sets QUALITY, HERE (its folder), ROOT and B (its build folder), then includes
# this file: the [draft] or [final] table of $(HERE)/species.toml becomes make variables (names
# upper-cased, lists joined by commas: `sheet = [1, 6, 12]` -> `SHEET := 1,6,12`), with SPECIES,
# TITLE and USD_PARTS (`NAME=$(B)/path ...` of its [usd] parts, for canopy-export). They are
# written to $(B)/.species-$(QUALITY).mk by `python -m inflo.tools.species vars` (standard library
# only, rewritten only when they change) each time make reads the Makefile; a QUALITY the file
# has no table for, or a malformed species.toml, stops make with its one-line error.

SPECIES_PY := $(if $(wildcard $(ROOT)/.venv/bin/python),$(ROOT)/.venv/bin/python,python3)
SPECIES_VARS := $(B)/.species-$(QUALITY).mk
SPECIES_ERROR := $(shell $(SPECIES_PY) -m inflo.tools.species vars $(HERE)/species.toml --quality '$(QUALITY)' -o $(SPECIES_VARS) 2>&1 >/dev/null || echo '(inflo.tools.species vars failed)')
ifneq ($(strip $(SPECIES_ERROR)),)
$(error $(SPECIES_ERROR))
endif
include $(SPECIES_VARS)
