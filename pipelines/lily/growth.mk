# The growth-map lily (Ijiri et al. 2008, sec. 6.1, figs. 1, 2, 7): the bud grown into
# the open flower by petal-grow's growth maps instead of the four key poses. Included by Makefile:
#
#   make lily METHOD=growth                 (top level)   or   make -C pipelines/lily growth
#
# Outputs under build/lily/growth/ (the key-pose lily's build/lily/ stays as it is).

GB := $(B)/growth
PY := $(if $(wildcard $(ROOT)/.venv/bin/python),$(ROOT)/.venv/bin/python,python3)
GROWTH_SRC := $(call SRC,petal_grow pbd collide)

.PHONY: growth growth-frames growth-pictures growth-check

ifeq ($(METHOD),growth)
.DEFAULT_GOAL := growth
else ifneq ($(METHOD),)
ifneq ($(METHOD),keys)
$(error METHOD must be keys (the default) or growth, found '$(METHOD)')
endif
endif

growth: growth-pictures growth-check
growth-frames: $(GB)/canopy/frame_$(LAST).obj
growth-pictures: $(GB)/lily_growth_sheet.png $(GB)/lily_growth_beside.png $(GB)/lily_growth_fig13.png
growth-check: $(GB)/check.txt

# 1. the bud: petal (680 triangles) and sepal (560) meshes with uv, placed by growth.toml
$(B)/growth_bud/petal.obj: growth_keys.py
	$(PY) growth_keys.py -o $(B)/growth_bud

# 2. petal-grow: 100 keyframes, the midrib reflexing early, the joint +23 deg over steps 1-60
$(GB)/canopy/frame_$(LAST).obj: growth.toml $(B)/growth_bud/petal.obj $(GROWTH_SRC)
	$(BIN)petal-grow -q growth.toml -o $(GB)/canopy

# the column: the key-pose lily's pistil (three-lobed stigma) and six stamens (versatile anthers)
# scaled to this lily's size, on a receptacle of its own (make_keys.py), with the same timing
GROWTH_COLUMN_KEYS := growth_column_bud.floret growth_column_early.floret growth_column_mid.floret growth_column_late.floret growth_column_open.floret
$(GB)/column_frames/frame_$(LAST).floret: $(GROWTH_COLUMN_KEYS) column_growth.func $(FLORET_SRC)
	$(BIN)floret-animate -q $(GROWTH_COLUMN_KEYS) --growth column_growth.func --frames $(FRAMES) -o $(GB)/column_frames

$(GB)/column_obj/frame_$(LAST).obj: $(GB)/column_frames/frame_$(LAST).floret $(POLY_SRC)
	$(BIN)polygonize -q $(GB)/column_frames -o $(GB)/column_obj

# 3. pictures: frames 1, 10, ..., 100 (fig. 1), and the open growth-map lily beside the key-pose one
$(GB)/lily_growth_sheet.png: $(GB)/canopy/frame_$(LAST).obj $(GB)/column_obj/frame_$(LAST).obj colors.toml
	$(RENDER) $(GB)/canopy $(GB)/column_obj --sheet-every 10 --columns 6 --label 'frame {n}' --size $(TILE) --fit-all -o $@

$(GB)/lily_growth_beside.png: $(GB)/canopy/frame_$(LAST).obj $(GB)/column_obj/frame_$(LAST).obj $(B)/painted/.done $(B)/column_keyframes/.done colors.toml growth_beside.py
	$(PY) growth_beside.py $(B) -o $@

# fig. 13: one petal at keyframe 75, from the side and from the top (the swelling about the midrib)
$(GB)/lily_growth_fig13.png: $(GB)/canopy/frame_$(LAST).obj colors.toml growth_fig13.py growth_keys.py
	$(PY) growth_fig13.py $(GB)/canopy --keyframe 75 -o $@

# 4. exact static test of every keyframe (tepals, and tepals against the column), joint angles,
#    the midrib's reflex and the flat lamina
$(GB)/check.txt: $(GB)/canopy/frame_$(LAST).obj $(GB)/column_obj/frame_$(LAST).obj check_growth.py
	@$(PY) check_growth.py $(GB)/canopy $(GB)/column_obj > $@.tmp; status=$$?; cat $@.tmp; \
		if [ $$status -eq 0 ]; then mv $@.tmp $@; else rm -f $@.tmp; exit 1; fi
