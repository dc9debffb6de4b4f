# What the head pipelines' Makefiles share (pipelines/sunflower, gaillardia, dahlia, dyssodia).
# A Makefile sets HERE, ROOT, B (its build folder under build/), QUALITY, Q and TLAST (the last
# template frame, 4 digits), then includes this file before its own rules. It gives:
#
# - BIN, PY: the tools and Python of the repository's .venv (else those on PATH);
# - WEIGHTS: the script writing the weight files (fixed vertices: the florets' base rows),
#   pipelines/yarrow/weights.py;
# - the sources each stage depends on (FLORET_SRC ... EXPORT_SRC: formats/ and the tool's own
#   package), so that a change of a tool reruns the stages it makes;
# - RENDER: canopy-render with the background and the pipeline's colors.toml;
# - $(B)/quality.txt (rewritten when QUALITY changes, so a draft/final switch rebuilds);
# - the pattern rules of step 2: a floret's template frames -> OBJ frames of constant topology
#   (polygonize; each organ's lambda and eta are in the key poses), and its weight file;
# - clean, FORCE, and .SECONDARY (the per-type OBJ sequences are not intermediate files).

.DEFAULT_GOAL := all

BIN := $(if $(wildcard $(ROOT)/.venv/bin/floret-animate),$(ROOT)/.venv/bin/,)
PY := $(if $(wildcard $(ROOT)/.venv/bin/python),$(ROOT)/.venv/bin/python,python3)
WEIGHTS := $(ROOT)/pipelines/yarrow/weights.py

SRC = $(wildcard $(ROOT)/formats/*.py $(foreach t,$(1),$(ROOT)/tools/$(t)/*.py))
FLORET_SRC := $(call SRC,floret_animate bspline)
POLY_SRC := $(call SRC,polygonize bspline)
PHYLLO_SRC := $(call SRC,phyllotaxis)
DIMORPH_SRC := $(call SRC,dimorph)
FCC_SRC := $(call SRC,fccompose pbd collide)
RENDER_SRC := $(call SRC,canopy_render)
EXPORT_SRC := $(call SRC,canopy_export) $(ROOT)/tools/canopy_render/colors.py

# a pipeline may set its own BACKGROUND before including this file
BACKGROUND ?= 0.55,0.70,0.86
RENDER := $(BIN)canopy-render -q --background $(BACKGROUND) --colors colors.toml

$(B)/quality.txt: FORCE
	@mkdir -p $(B)
	@if [ "$$(cat $@ 2>/dev/null)" != "$(QUALITY)" ]; then echo "$(QUALITY)" > $@; fi

$(B)/%_obj/frame_$(TLAST).obj: $(B)/%_frames/frame_$(TLAST).floret $(POLY_SRC)
	$(BIN)polygonize -q $(B)/$*_frames -o $(B)/$*_obj

$(B)/%.weights: $(B)/%_obj/frame_$(TLAST).obj $(WEIGHTS)
	$(PY) $(WEIGHTS) base $(B)/$*_obj/frame_0000.obj $@

.PHONY: clean FORCE
clean:
	rm -rf $(B)

FORCE:

.SECONDARY:
