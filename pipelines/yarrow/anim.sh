#!/bin/sh
# The frames of the yarrow's development sheet and animation (build/yarrow/yarrow_sheet.png,
# yarrow.gif) as three OBJ sequences of one length (branches, canopy, receptacles), linked from the stage outputs (nothing is
# recomputed): branch-gen's per-frame branches and the canopy's frame of the same index -- both on
# the canopy's clock, so picture k shows the branches and the heads of frame k together. A canopy
# frame with no head yet (before the first emerges) is linked to an empty OBJ.
# Usage: sh anim.sh BUILD_DIR   (BUILD_DIR = build/yarrow)
set -e
B=$1
rm -rf "$B/anim"
mkdir -p "$B/anim/canopy" "$B/anim/branches" "$B/anim/receptacles"
printf '# empty: no head yet\n' > "$B/anim/empty.obj"
k=0
for f in "$B"/canopy/frame_*.obj; do
	n=$(printf '%04d' $k)
	if grep -q '^f ' "$f"; then
		ln -s "../../canopy/$(basename "$f")" "$B/anim/canopy/frame_$n.obj"
	else
		ln -s "../empty.obj" "$B/anim/canopy/frame_$n.obj"
	fi
	r="$B/receptacles/frame_$n.obj"
	if [ -f "$r" ] && grep -q '^f ' "$r"; then
		ln -s "../../receptacles/frame_$n.obj" "$B/anim/receptacles/frame_$n.obj"
	else
		ln -s "../empty.obj" "$B/anim/receptacles/frame_$n.obj"
	fi
	b="$B/branches/frames/branches_$n.obj"
	if [ -f "$b" ] && grep -q '^f ' "$b"; then
		ln -s "../../branches/frames/branches_$n.obj" "$B/anim/branches/frame_$n.obj"
	else
		ln -s "../empty.obj" "$B/anim/branches/frame_$n.obj"
	fi
	k=$((k + 1))
done
echo "anim.sh: $k frames in $B/anim"
