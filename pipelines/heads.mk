# The head chain (pipelines/sunflower, gaillardia, dahlia, dyssodia; orlaya and lilac take its
# floret rules): included after pipelines/species.mk once the Makefile has set Q and TLAST (the
# last template frame, 4 digits). It gives:
#
# - WEIGHTS: the script writing the weight files (fixed vertices: the florets' base rows),
#   tools/species/weights.py (python -m inflo.tools.species.weights);
# - the pattern rules of steps 1 and 2: a floret type's key poses (KEYS_<type>) -> its template
#   frames (floret-animate); a floret's template frames -> OBJ frames of constant topology
#   (polygonize; each organ's lambda and eta are in the key poses), and its weight file;
# - .SECONDARY (the per-type OBJ sequences are not intermediate files).

WEIGHTS := $(ROOT)/tools/species/weights.py

$(B)/%_obj/frame_$(TLAST).obj: $(B)/%_frames/frame_$(TLAST).floret $(POLY_SRC)
	$(BIN)polygonize -q $(B)/$*_frames -o $(B)/$*_obj

$(B)/%.weights: $(B)/%_obj/frame_$(TLAST).obj $(WEIGHTS)
	$(PY) -m inflo.tools.species.weights base $(B)/$*_obj/frame_0000.obj $@

.SECONDARY:

# step 1: a floret type's key poses (KEYS_<type>: .floret files, and the .func files they name)
# -> one .floret per template frame
.SECONDEXPANSION:
$(B)/%_frames/frame_$(TLAST).floret: $$(KEYS_$$*) $(B)/quality.txt $(FLORET_SRC)
	$(BIN)floret-animate -q $(filter %.floret,$(KEYS_$*)) --frames $(TEMPLATE_FRAMES) -o $(B)/$*_frames
