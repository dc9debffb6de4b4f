# The end of every species Makefile: the rules every species shares (formats/species.md).
#
# Included last, after the species has set (in its Makefile) what these rules depend on:
#
# - CHECK_DEPS: what its check reads; `check` runs check_$(SPECIES).py (or, with CHECK_SRC set
#   empty, the shared head check with the facts of species.toml [check]) on the build and keeps
#   its report, $(B)/check.txt, only when it passes (printed either way);
# - USD_DEPS: the last frames of its USD parts ([usd] parts of species.toml, USD_PARTS); `usd`
#   writes $(B)/$(SPECIES).usdc with canopy-export (USD_FLAGS, `--mtl` unless set: materials.mtl
#   beside each part's OBJ frames), coloured by colors.toml, its [usd] units and translate, 24 fps;
#   and $(B)/viewer/ (`viewer`): the same parts as $(SPECIES).glb, index.html and three.js;
# - $(B)/quality.txt, rewritten only when QUALITY changes, so a draft/final switch reruns what
#   depends on it; clean; FORCE.

USD_FLAGS ?= --mtl
# the check: the species' own check_<species>.py, or (CHECK_SRC empty: a head whose facts are all
# in species.toml [check]) the shared one, python -m inflo.tools.species.checks
ifeq ($(origin CHECK_SRC),undefined)
CHECK_SRC := check_$(SPECIES).py
endif
CHECK ?= $(if $(CHECK_SRC),$(PY) $(CHECK_SRC),$(PY) -m inflo.tools.species.checks $(HERE))

$(B)/quality.txt: FORCE
	@mkdir -p $(B)
	@if [ "$$(cat $@ 2>/dev/null)" != "$(QUALITY)" ]; then echo "$(QUALITY)" > $@; fi

check: $(B)/check.txt
$(B)/check.txt: $(CHECK_DEPS) $(CHECK_SRC)
	@$(CHECK) $(B) > $@.tmp; status=$$?; cat $@.tmp; \
		if [ $$status -eq 0 ]; then mv $@.tmp $@; else rm -f $@.tmp; exit 1; fi

ifneq ($(strip $(USD_PARTS)),)
usd: $(B)/$(SPECIES).usdc $(B)/viewer/index.html
$(B)/$(SPECIES).usdc: $(USD_DEPS) colors.toml $(EXPORT_SRC)
	$(BIN)canopy-export -q $(USD_FLAGS) $(USD_PARTS) $(USD_TRANSLATE) --colors colors.toml --units $(USD_UNITS) --fps 24 -o $@
# the same parts as one binary glTF (growth as morph targets) and the page that plays it, with
# three.js beside it: open with `canopy-view $(B)` or any static server (formats/gltf.md); at most
# VIEWER_MB megabytes (frames thinned to fit: a final yarrow's 100 frames of branches would be 235 MB)
VIEWER_MB ?= 50
viewer: $(B)/viewer/index.html
$(B)/viewer/index.html: $(USD_DEPS) colors.toml $(EXPORT_SRC) $(call SRC,canopy_view)
	$(BIN)canopy-export -q $(USD_PARTS) $(USD_TRANSLATE) --colors colors.toml --units $(USD_UNITS) --fps 24 \
		--title "$(TITLE)" --figure "$(QUALITY) build" --max-mb $(VIEWER_MB) --viewer -o $(B)/viewer/$(SPECIES).glb
endif

clean:
	rm -rf $(B)

FORCE:

.PHONY: check usd viewer clean FORCE
