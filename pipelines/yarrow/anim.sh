#!/bin/sh
# The frames of the yarrow's development sheet and animation (build/yarrow/yarrow_sheet.png,
# yarrow.gif) as four OBJ sequences of one length (branches, canopy, receptacles, stem leaves),
# linked from the stage outputs (nothing is recomputed): branch-gen's per-frame branches, the
# canopy's frame of the same index and the stem leaves of that frame -- all on the canopy's clock,
# so picture k shows the branches, the leaves and the heads of frame k together. A frame with
# nothing of a sequence yet (no head before the first emerges, no leaf before the stem reaches
# it) is linked to an empty OBJ.
# Usage: sh anim.sh BUILD_DIR   (BUILD_DIR = build/yarrow)
set -e
B=$1
rm -rf "$B/anim"
mkdir -p "$B/anim/canopy" "$B/anim/branches" "$B/anim/receptacles" "$B/anim/leaves"
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
	l="$B/leaves/frame_$n.obj"
	if [ -f "$l" ] && grep -q '^f ' "$l"; then
		ln -s "../../leaves/frame_$n.obj" "$B/anim/leaves/frame_$n.obj"
	else
		ln -s "../empty.obj" "$B/anim/leaves/frame_$n.obj"
	fi
	k=$((k + 1))
done
echo "anim.sh: $k frames in $B/anim"
