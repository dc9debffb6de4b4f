#!/bin/sh
# The frames of the yarrow animation (build/yarrow/yarrow.gif) as two OBJ sequences of one length,
# linked from the stage outputs (nothing is recomputed):
#   anim/branches: branch-gen's per-frame branches from the first frame with any branch to the last
#                  (the structure growing under the emerging heads), then the final branches held;
#   anim/canopy:   an empty OBJ while the branches grow (the heads are still primordia: the canopy
#                  of fccompose starts from the finished pattern), then every canopy frame (the heads
#                  opening, bud to flower).
# Usage: sh anim.sh BUILD_DIR   (BUILD_DIR = build/yarrow)
set -e
B=$1
rm -rf "$B/anim"
mkdir -p "$B/anim/canopy" "$B/anim/branches"
printf '# empty: no canopy yet\n' > "$B/anim/empty.obj"
k=0
for f in "$B"/branches/frames/branches_*.obj; do
	grep -q '^f ' "$f" || continue
	n=$(printf '%04d' $k)
	ln -s "../../branches/frames/$(basename "$f")" "$B/anim/branches/frame_$n.obj"
	ln -s "../empty.obj" "$B/anim/canopy/frame_$n.obj"
	k=$((k + 1))
done
for f in "$B"/canopy/frame_*.obj; do
	n=$(printf '%04d' $k)
	ln -s "../../canopy/$(basename "$f")" "$B/anim/canopy/frame_$n.obj"
	ln -s "../../branches/branches.obj" "$B/anim/branches/frame_$n.obj"
	k=$((k + 1))
done
echo "anim.sh: $k frames in $B/anim"
