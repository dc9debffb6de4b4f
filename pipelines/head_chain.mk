# The single-head chain (family "head" of formats/species.md: the sunflower, the gaillardia, the
# daisy): one head of involucral bracts, ray florets and disk florets on a dynamic phyllotaxis.
#
# The species Makefile sets its key poses, KEYS_disk, KEYS_ray and KEYS_bract (.floret files and
# the .func files they name), includes pipelines/species.mk and pipelines/heads.mk, then this file,
# then pipelines/common.mk. Its species.toml gives ALPHA, BRACTS, BRACT_SCALE, RAY_SCALE,
# DISK_SCALE (optional), RAY_LEAD, RAY_DEVELOPMENT_FRAMES and BRACT_DEVELOPMENT_FRAMES (optional: the
# rays' and bracts' windows, so that they open with the head), HERO (optional: the frame of the
# phase-effect still, else two thirds of the run), TEMPLATE_FRAMES, SHEET, STILL_SIZE and ANIM_SIZE; the canopy
# runs as many frames as the head's RBA sequence ($(Q)/head.toml [dynamics] frames). The stages:
#
# 1. key poses -> one .floret per template frame of each floret type (heads.mk);
# 2. frames -> OBJ frames of constant topology, and each type's base rows, fixed on the
#    receptacle in fccompose (heads.mk);
# 3. head: the dynamic phyllotaxis of $(Q)/head.toml (centripetal fractionation on a receptacle
#    that grows), each floret developing from its emergence; the receptacle mesh of every frame
#    (head/receptacle/);
# 4. dimorph: types by the cone model: bracts (the BRACTS outermost primordia), ray florets (an
#    empty outward cone of ALPHA degrees, developing RAY_LEAD frames ahead), disk florets;
# 5. canopy: fccompose of $(SPECIES).fcc: every floret emerges at its first RBA frame and develops
#    over its own window, colliding with its neighbours (the receptacle is not simulated);
# 6. pictures: the development (a sheet of the SHEET frames), the head from the front, from
#    the side and from below (its back: the receptacle's underside, with its phyllaries and its
#    stem where head.toml [receptacle] gives them), the hero still at frame HERO (the phase
#    effect: outer florets open, inner ones in bud; two thirds of the way by default), a GIF.

FRAMES := $(shell sed -n 's/^frames *= *\([0-9]*\).*/\1/p' $(HERE)/$(Q)/head.toml)
LAST := $(shell printf '%04d' $$(($(FRAMES) - 1)))
TYPES := disk ray bract
VIEWS := $(B)/canopy $(B)/head/receptacle

.PHONY: all frames obj head dimorph canopy pictures check usd

all: pictures check usd

frames: $(foreach t,$(TYPES),$(B)/$(t)_frames/frame_$(TLAST).floret)
obj: $(foreach t,$(TYPES),$(B)/$(t).weights)
head: $(B)/head/scene.scn
dimorph: $(B)/head/typed.scn
canopy: $(B)/canopy/frame_$(LAST).obj
pictures: $(foreach p,sheet.png front.png side.png back.png mid.png,$(B)/$(SPECIES)_$(p)) $(B)/$(SPECIES).gif

$(B)/head/scene.scn: $(Q)/head.toml $(B)/quality.txt $(PHYLLO_SRC)
	rm -rf $(B)/head
	$(BIN)phyllotaxis -q $(Q)/head.toml -o $(B)/head

$(B)/head/typed.scn: $(B)/head/scene.scn Makefile species.toml $(DIMORPH_SRC)
	$(BIN)dimorph -q $(B)/head/scene.scn --alpha $(ALPHA) --bracts $(BRACTS) --bract-id 2 --bract-scale $(BRACT_SCALE) \
		--ray-scale $(RAY_SCALE) $(if $(DISK_SCALE),--disk-scale $(DISK_SCALE)) \
		--ray-id 1 --disk-id 0 --ray-lead $(RAY_LEAD) \
		$(if $(RAY_DEVELOPMENT_FRAMES),--ray-development-frames $(RAY_DEVELOPMENT_FRAMES)) \
		$(if $(BRACT_DEVELOPMENT_FRAMES),--bract-development-frames $(BRACT_DEVELOPMENT_FRAMES)) -o $@

$(B)/canopy/frame_$(LAST).obj: $(SPECIES).fcc $(B)/head/typed.scn $(foreach t,$(TYPES),$(B)/$(t).weights) $(FCC_SRC)
	rm -rf $(B)/canopy
	$(BIN)fccompose -q --strict $(SPECIES).fcc --frames $$(($(FRAMES) - 1)) -o $(B)/canopy

$(B)/$(SPECIES)_sheet.png: $(B)/canopy/frame_$(LAST).obj colors.toml $(RENDER_SRC)
	$(RENDER) $(VIEWS) --sheet $(SHEET) --columns 3 --elevation 55 --fit-all --size 420x420 \
		--title '$(SPECIES) ($(QUALITY)): development from the naked meristem' -o $@

$(B)/$(SPECIES)_front.png: $(B)/canopy/frame_$(LAST).obj colors.toml $(RENDER_SRC)
	$(RENDER) $(VIEWS) --frame -1 --elevation 62 --azimuth 20 --size $(STILL_SIZE) -o $@

$(B)/$(SPECIES)_side.png: $(B)/canopy/frame_$(LAST).obj colors.toml $(RENDER_SRC)
	$(RENDER) $(VIEWS) --frame -1 --elevation 12 --azimuth 20 --size $(STILL_SIZE) -o $@

$(B)/$(SPECIES)_back.png: $(B)/canopy/frame_$(LAST).obj colors.toml $(RENDER_SRC)
	$(RENDER) $(VIEWS) --frame -1 --elevation -30 --azimuth 20 --size $(STILL_SIZE) -o $@

$(B)/$(SPECIES)_mid.png: $(B)/canopy/frame_$(LAST).obj colors.toml $(RENDER_SRC)
	$(RENDER) $(VIEWS) --frame $(if $(HERO),$(HERO),$$(($(FRAMES) * 2 / 3))) --elevation 50 --azimuth 20 --size $(STILL_SIZE) -o $@

$(B)/$(SPECIES).gif: $(B)/canopy/frame_$(LAST).obj colors.toml $(RENDER_SRC)
	$(RENDER) $(VIEWS) --elevation 45 --fit-all --size $(ANIM_SIZE) --fps 12 -o $@

USD_DEPS := $(B)/canopy/frame_$(LAST).obj
