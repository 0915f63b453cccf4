#!/bin/sh
# mesobake frusta from the command line (FORMAT.md §7.2 kind 4): SWC and
# text skeletons, the chunks a frusta object is made of, the report keys
# the issue names, relief, determinism, twist (--twist and the .skel
# twist= field), colour maps (--relief-color: COLR), and bad input (a coded error that names the line, a
# non-zero exit, and no output file).
# usage: frusta_cli.sh MESOBAKE MESOINSPECT TEST_DATA_DIR [PNG_PROBE [WRITE_HEIGHT_PNG]]
set -u
bake=$1 inspect=$2 data=$3 probe=${4:-} writepng=${5:-}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { # DESCRIPTION COMMAND...
  d=$1; shift
  if "$@"; then echo "ok   $d"; else echo "FAIL $d"; fail=1; fi
}
# row FILE TYPE: the chunk's row of 'mesoinspect info'
row() { "$inspect" info "$1" | awk -v t="$2" '$2 == t'; }
# row0 FILE TYPE: the row of level 0's chunk (lod 0; a native level has its own RELF)
row0() { "$inspect" info "$1" | awk -v t="$2" '$2 == t && $5 == 0'; }
key() { grep -q "\"$2\":" "$1"; }
num() { sed -n "s/.*\"$2\":[[:space:]]*\([-0-9.e+]*\).*/\1/p" "$1"; }

# 1. A branching SWC tree with zero-radius tips.
"$bake" frusta -i "$data/neurom_simple.swc" -o "$tmp/simple.meso" --report "$tmp/simple.json" >/dev/null 2>&1
check "simple: bake succeeds" test -s "$tmp/simple.meso"
check "simple: validates fully" sh -c "'$inspect' validate --full '$tmp/simple.meso' >/dev/null"
for t in SKEL FRUS FSEG BALL; do
  check "simple: has $t on object 1" sh -c "'$inspect' info '$tmp/simple.meso' | awk '\$2 == \"$t\" && \$4 == 1' | grep -q ."
done
check "simple: object kind is frusta" sh -c "'$inspect' info '$tmp/simple.meso' | grep -q ' frusta '"
for k in segments joints branch_points cap_intersections_found cap_intersections_unhandled fit_error_max \
    fit_error_mean seconds_total bytes; do
  check "simple: report has $k" key "$tmp/simple.json" "$k"
done
# neurom_simple.swc: 9 nodes, 8 parent links, two of them zero-length
# (a repeated point), so 6 frusta; 2 branch points; nodes 2 and 7 join
# two segments each, but one of them is a merged zero-length pair.
check "simple: 6 segments" test "$(num "$tmp/simple.json" segments)" = 6
check "simple: 2 branch points" test "$(num "$tmp/simple.json" branch_points)" = 2
check "simple: FRUS has 6 records" test "$(row "$tmp/simple.meso" FRUS | awk '{print $9}')" = 6x1x1
check "simple: FSEG is 6 x 80 bytes" test "$(row "$tmp/simple.meso" FSEG | awk '{print $12}')" = 480
check "simple: info summarises FSEG (6 frusta, 2 balls)" sh -c "'$inspect' info '$tmp/simple.meso' | grep -q 'FSEG: 6 frusta' && '$inspect' info '$tmp/simple.meso' | grep -q 'BALL: 2 balls'"

# 2. The text skeleton format, with relief; determinism.
cat >"$tmp/arm.skel" <<'SKEL'
# a bent arm with a branch (x y z radius [parent])
0 0 0 0.3
0 2 0 0.3
1.5 3.5 0 0.2
1.5 5 0.5 0.1
-1 3 0 0.15 2   # from node 2
SKEL
"$bake" frusta -i "$tmp/arm.skel" -o "$tmp/arm1.meso" --relief bricks:64 --relief-depth 0.05 --report "$tmp/arm.json" \
  >/dev/null 2>&1
"$bake" frusta -i "$tmp/arm.skel" -o "$tmp/arm2.meso" --relief bricks:64 --relief-depth 0.05 >/dev/null 2>&1
check "arm: bake succeeds" test -s "$tmp/arm1.meso"
check "arm: validates fully" sh -c "'$inspect' validate --full '$tmp/arm1.meso' >/dev/null"
check "arm: two bakes are byte-identical" cmp -s "$tmp/arm1.meso" "$tmp/arm2.meso"
check "arm: RELF u16 64x64" test "$(row0 "$tmp/arm1.meso" RELF | awk '{print $7, $9}')" = "u16 64x64x1"
check "arm: 4 segments, 1 branch point" test "$(num "$tmp/arm.json" segments) $(num "$tmp/arm.json" branch_points)" = "4 1"
check "arm: report says text input" grep -q '"input":[[:space:]]*"text"' "$tmp/arm.json"
check "arm: META records the relief" sh -c "'$inspect' info '$tmp/arm1.meso' | grep -q '\"spec\":[[:space:]]*\"bricks:64\"'"
# Without the §2.2 fit the tapered joint leaves a seam gap; with it, none.
"$bake" frusta -i "$tmp/arm.skel" -o "$tmp/nofit.meso" --no-fit --report "$tmp/nofit.json" >/dev/null 2>&1
check "arm --no-fit: seam gap > 1e-4" awk -v g="$(num "$tmp/nofit.json" seam_gap_max)" 'BEGIN { exit !(g > 1e-4) }'
check "arm: fitted seam gap < 1e-9" awk -v g="$(num "$tmp/arm.json" seam_gap_max)" 'BEGIN { exit !(g < 1e-9) }'
check "arm --no-fit: fit_error_max 0" awk -v g="$(num "$tmp/nofit.json" fit_error_max)" 'BEGIN { exit !(g == 0) }'

# 3. A larger tree: cap intersections found and all handled.
"$bake" frusta -i "$data/neurom_Neuron.swc" -o "$tmp/neuron.meso" --report "$tmp/neuron.json" >/dev/null 2>&1
check "neuron: validates fully" sh -c "'$inspect' validate --full '$tmp/neuron.meso' >/dev/null"
check "neuron: cap intersections found" awk -v g="$(num "$tmp/neuron.json" cap_intersections_found)" 'BEGIN { exit !(g > 0) }'
check "neuron: none unhandled" test "$(num "$tmp/neuron.json" cap_intersections_unhandled)" = 0
"$bake" frusta -i "$data/neurom_Neuron.swc" -o "$tmp/keep.meso" --keep-cap-intersections --report "$tmp/keep.json" \
  >/dev/null 2>&1
check "neuron --keep-cap-intersections: some unhandled" \
  awk -v g="$(num "$tmp/keep.json" cap_intersections_unhandled)" 'BEGIN { exit !(g > 0) }'

# 3b. A closed mesh: CGAL's skeleton, fitted and simplified (a torus: its
# cycle is cut, the ring stays closed); open meshes are refused before CGAL.
if "$bake" frusta --help | grep -q "a mesh"; then
  "$bake" frusta -i "$data/torus.obj" -o "$tmp/torus.meso" --report "$tmp/torus.json" >/dev/null 2>"$tmp/torus.err"
  rc=$?
  if grep -q "need CGAL" "$tmp/torus.err"; then
    echo "skip mesh input: this build has no CGAL"
  else
    check "torus: bake succeeds" test "$rc" = 0
    check "torus: validates fully" sh -c "'$inspect' validate --full '$tmp/torus.meso' >/dev/null"
    check "torus: report says mesh input" grep -q '"input":[[:space:]]*"mesh"' "$tmp/torus.json"
    # the torus (R = 1, r = 0.25) is a ring of round cones: within 2 % of its diagonal
    check "torus: fit error within 2 % of the diagonal" \
      awk -v e="$(num "$tmp/torus.json" fit_error_max)" -v d="$(num "$tmp/torus.json" bbox_diagonal)" \
      'BEGIN { exit !(e > 0 && e < 0.02 * d) }'
    check "torus: at least 8 segments around the ring" awk -v n="$(num "$tmp/torus.json" segments)" 'BEGIN { exit !(n >= 8) }'
    "$bake" frusta -i "$data/cube_no_bottom.obj" -o "$tmp/open.meso" >/dev/null 2>"$tmp/open.err"
    check "open mesh: exit 3" test $? = 3
    check "open mesh: E3172 names a boundary edge" grep -q "E3172.*boundary edge" "$tmp/open.err"
    check "open mesh: no output file" test ! -e "$tmp/open.meso"
  fi
fi

# 3c. mesoinspect preview of a frusta object: libmeso (EGL) and the exact
# reference agree at the centre pixel (on the object) and leave the corners
# to the background.
if [ -n "$probe" ]; then
  printf '0 -1 0 0.6\n0 1 0 0.6\n' >"$tmp/rod.skel"
  "$bake" frusta -i "$tmp/rod.skel" -o "$tmp/rod.meso" >/dev/null 2>&1
  "$inspect" preview "$tmp/rod.meso" -o "$tmp/rod_ref.png" --size 64x64 --reference >/dev/null 2>&1
  check "preview --reference: writes a PNG" test -s "$tmp/rod_ref.png"
  ref_px=$("$probe" "$tmp/rod_ref.png")
  check "preview --reference: centre on the rod, corner background" \
    sh -c "test \"$(echo "$ref_px" | sed -n 6p)\" != \"$(echo "$ref_px" | sed -n 2p)\""
  if "$inspect" preview "$tmp/rod.meso" -o "$tmp/rod_gl.png" --size 64x64 >/dev/null 2>&1; then
    gl_px=$("$probe" "$tmp/rod_gl.png")
    check "preview (libmeso): same corner as the reference" \
      test "$(echo "$gl_px" | sed -n 2p)" = "$(echo "$ref_px" | sed -n 2p)"
    check "preview (libmeso): centre within 8/255 of the reference" awk -v a="$(echo "$gl_px" | sed -n 6p)" \
      -v b="$(echo "$ref_px" | sed -n 6p)" 'BEGIN { split(a, x, " "); split(b, y, " ");
        for (i = 1; i <= 3; ++i) { d = x[i] - y[i]; if (d < -8 || d > 8) exit 1 } }'
  else
    echo "skip preview (libmeso): no EGL in this build"
  fi
fi

# 3d. Twist (frusta paper §2.3): --twist DEG per unit length and the .skel
# twist=DEG field; 0 is no option at all (the same bytes); bad values exit 1.
"$bake" frusta -i "$tmp/arm.skel" -o "$tmp/tw0.meso" --relief bricks:64 --relief-depth 0.05 --twist 0 >/dev/null 2>&1
check "twist 0: same bytes as no --twist" cmp -s "$tmp/arm1.meso" "$tmp/tw0.meso"
check "untwisted: META has no twist" sh -c "! '$inspect' info '$tmp/arm1.meso' | grep -q '\"twist\"'"
"$bake" frusta -i "$tmp/arm.skel" -o "$tmp/tw.meso" --relief bricks:64 --relief-depth 0.05 --twist -45.5 >/dev/null 2>&1
check "twist: bake succeeds and validates" sh -c "'$inspect' validate --full '$tmp/tw.meso' >/dev/null"
check "twist: META records the rate" sh -c "'$inspect' info '$tmp/tw.meso' | grep -q '\"twist\":[[:space:]]*-45.5'"
check "twist: differs from untwisted" sh -c "! cmp -s '$tmp/arm1.meso' '$tmp/tw.meso'"
sed 's/^1.5 3.5 0 0.2$/1.5 3.5 0 0.2 twist=90/' "$tmp/arm.skel" >"$tmp/armtw.skel"
check "twist= field: in the test skeleton" grep -q "twist=90" "$tmp/armtw.skel"
"$bake" frusta -i "$tmp/armtw.skel" -o "$tmp/twf.meso" --relief bricks:64 --relief-depth 0.05 >/dev/null 2>&1
check "twist= field: bake succeeds, differs from untwisted" sh -c "test -s '$tmp/twf.meso' && ! cmp -s '$tmp/arm1.meso' '$tmp/twf.meso'"
for v in nan inf -inf abc 12deg "" 1e9 -360001; do
  "$bake" frusta -i "$tmp/arm.skel" -o "$tmp/badtw.meso" --twist "$v" >/dev/null 2>"$tmp/badtw.err"
  check "--twist '$v': exit 1" test $? = 1
  check "--twist '$v': message names --twist" grep -q -- "--twist expects" "$tmp/badtw.err"
  check "--twist '$v': no output" test ! -e "$tmp/badtw.meso"
done
"$bake" frusta -i "$tmp/arm.skel" -o "$tmp/badtw.meso" --twist 300000 >/dev/null 2>"$tmp/badtw.err"
check "--twist 300000 on segments of length ~2: exit 1 (over 1000 turns)" test $? = 1
check "--twist 300000: names the segment's line" grep -q "line [0-9]" "$tmp/badtw.err"
"$bake" frusta --help | grep -q -- "--twist DEG" && "$bake" frusta --help | grep -q "twist=DEG"
check "--help documents --twist and twist=DEG" test $? = 0

# 3e. Colour maps (--relief-color, FORMAT.md §7.2 kind 4 COLR): an 8-bit
# PNG (here a reference preview, RGBA) stored as U8 x 4, W x H x 1, with or
# without a relief; deterministic; the preview shows it; a missing file is
# exit 2 (E3560), a file that is no 8-bit PNG exit 3 (E3561), nothing written.
"$inspect" preview "$tmp/simple.meso" -o "$tmp/col.png" --size 24x16 --reference >/dev/null 2>&1
check "colour: a PNG to use" test -s "$tmp/col.png"
"$bake" frusta -i "$tmp/arm.skel" -o "$tmp/col1.meso" --relief bricks:64 --relief-depth 0.05 \
  --relief-color "$tmp/col.png" >/dev/null 2>&1
"$bake" frusta -i "$tmp/arm.skel" -o "$tmp/col2.meso" --relief bricks:64 --relief-depth 0.05 \
  --relief-color "$tmp/col.png" >/dev/null 2>&1
check "colour: bake succeeds" test -s "$tmp/col1.meso"
check "colour: validates fully" sh -c "'$inspect' validate --full '$tmp/col1.meso' >/dev/null"
check "colour: COLR u8 x 4, 24x16x1 on object 1" \
  test "$(row "$tmp/col1.meso" COLR | awk '{print $4, $7, $8, $9}')" = "1 u8 4 24x16x1"
check "colour: two bakes are byte-identical" cmp -s "$tmp/col1.meso" "$tmp/col2.meso"
for t in FRUS FSEG RELF; do # one FRUS and FSEG (at the coarsest native lod); level 0's RELF
  r=row; [ "$t" = RELF ] && r=row0
  a=$($r "$tmp/arm1.meso" $t | awk '{print $13}') b=$($r "$tmp/col1.meso" $t | awk '{print $13}')
  check "colour: $t as without it ($a)" test -n "$a" -a "$a" = "$b"
done
"$bake" frusta -i "$tmp/arm.skel" -o "$tmp/colplain.meso" --relief-color "$tmp/col.png" >/dev/null 2>&1
check "colour without relief: COLR and no RELF" \
  sh -c "'$inspect' info '$tmp/colplain.meso' | awk '\$2 == \"COLR\"' | grep -q . && ! '$inspect' info '$tmp/colplain.meso' | awk '\$2 == \"RELF\"' | grep -q ."
if [ -n "$probe" ]; then
  "$inspect" preview "$tmp/arm1.meso" -o "$tmp/arm_ref.png" --size 48x48 --reference >/dev/null 2>&1
  "$inspect" preview "$tmp/col1.meso" -o "$tmp/col_ref.png" --size 48x48 --reference >/dev/null 2>&1
  check "colour: the preview shows it (differs from the uncoloured one)" \
    sh -c "test \"\$('$probe' --diff '$tmp/arm_ref.png' '$tmp/col_ref.png' | cut -d' ' -f1)\" -gt 50"
  # preview --reference --level 1: the native level's own (halved) relief.
  "$inspect" preview "$tmp/arm1.meso" -o "$tmp/arm_ref1.png" --size 48x48 --reference --level 1 >/dev/null 2>&1
  check "levels: preview --reference --level 1 draws level 1's relief (another image)" \
    sh -c "test -s '$tmp/arm_ref1.png' && test \"\$('$probe' --diff '$tmp/arm_ref.png' '$tmp/arm_ref1.png' | cut -d' ' -f1)\" -gt 0"
fi
badcol() { # NAME EXIT CODE: --relief-color $tmp/NAME
  "$bake" frusta -i "$tmp/arm.skel" -o "$tmp/badcol.meso" --relief-color "$tmp/$1" >/dev/null 2>"$tmp/badcol.err"
  rc=$?
  check "colour $1: exit $2" test "$rc" = "$2"
  check "colour $1: error E$3 naming the file" grep -q "E$3.*$1" "$tmp/badcol.err"
  check "colour $1: no output file" test ! -e "$tmp/badcol.meso"
}
badcol nope.png 2 3560
printf 'not a png at all, just text\n' >"$tmp/text.png"
badcol text.png 3 3561
head -c 60 "$tmp/col.png" >"$tmp/cut.png"
badcol cut.png 3 3561
if [ -n "$writepng" ]; then
  "$writepng" "$tmp/deep16.png" 16 8
  badcol deep16.png 3 3561
  check "colour deep16.png: says 8-bit" grep -q "8-bit" "$tmp/badcol.err"
fi
"$bake" frusta --help | grep -q -- "--relief-color FILE.png"
check "--help documents --relief-color" test $? = 0

# 4. Bad input: a coded error naming the line, exit 3, no output.
bad() { # NAME CONTENT EXT CODE
  printf "$2" >"$tmp/$1.$3"
  "$bake" frusta -i "$tmp/$1.$3" -o "$tmp/$1.meso" >/dev/null 2>"$tmp/$1.err"
  rc=$?
  check "bad $1: exit 3" test "$rc" = 3
  check "bad $1: error E$4" grep -q "E$4" "$tmp/$1.err"
  check "bad $1: names the line" grep -q "line" "$tmp/$1.err"
  check "bad $1: no output file" test ! -e "$tmp/$1.meso"
}
bad fields "0 0 0\n" skel 3141
bad number "0 0 0 1\n0 x 0 1\n" skel 3142
bad radius "0 0 0 1\n0 1 0 -2\n" skel 3144
bad parent "0 0 0 1\n0 1 0 1 7\n" skel 3146
bad swc_cycle "1 1 0 0 0 1 2\n2 1 0 1 0 1 1\n" swc 3147
bad swc_nan "1 1 0 0 nan 1 -1\n" swc 3143
bad twist_word "0 0 0 1\n0 1 0 1 twist=ten\n" skel 3304
bad twist_nan "0 0 0 1\n0 1 0 1 twist=nan\n" skel 3304
bad twist_huge "0 0 0 1\n0 1 0 1 twist=1e7\n" skel 3304
bad twist_twice "0 0 0 1\n0 1 0 1 twist=1 twist=2\n" skel 3304
bad twist_root "0 0 0 1 twist=30\n0 1 0 1\n" skel 3304
check "bad twist_root: says root" grep -q "root" "$tmp/twist_root.err"
printf "# only comments\n" >"$tmp/empty.skel"
"$bake" frusta -i "$tmp/empty.skel" -o "$tmp/empty.meso" >/dev/null 2>"$tmp/empty.err"
check "bad empty: exit 3 with E3140" sh -c "test $? = 3 && grep -q E3140 '$tmp/empty.err'"
check "bad empty: no output file" test ! -e "$tmp/empty.meso"
"$bake" frusta -i "$tmp/arm.skel" -o "$tmp/vol.meso" --relief weave >/dev/null 2>"$tmp/vol.err"
check "relief volume: refused (exit 1)" test $? = 1
check "relief volume: says height fields" grep -q "height" "$tmp/vol.err"
"$bake" frusta -i "$tmp/missing.swc" -o "$tmp/missing.meso" >/dev/null 2>&1
check "missing input: exit 2" test $? = 2
# A failed bake leaves an existing output untouched.
cp "$tmp/arm1.meso" "$tmp/keep_me.meso"
"$bake" frusta -i "$tmp/fields.skel" -o "$tmp/keep_me.meso" >/dev/null 2>&1
check "failed bake: existing output untouched" cmp -s "$tmp/arm1.meso" "$tmp/keep_me.meso"
"$bake" frusta --help | grep -q -- "--relief-depth"
check "--help documents --relief-depth" test $? = 0
# Levels (FORMAT.md 7.10): a mesh stand-in at lod 1 by default, none with
# --levels 1 (the stand-in's error bound: test_frusta_standin); bad counts exit 1.
check "levels: the default file has a MESH and LODS" test -n "$(row "$tmp/arm1.meso" MESH)" -a -n "$(row "$tmp/arm1.meso" LODS)"
check "levels: report lists them" key "$tmp/arm.json" levels
# Native relief levels (the relief map halved: bake/height_field_levels.h)
# come first, each with its own RELF, then the stand-in; --levels 2 keeps
# the stand-in only (the error bounds: test_frusta_standin).
check "levels: native level 1 has its own RELF" sh -c "'$inspect' info '$tmp/arm1.meso' | awk '\$2 == 1 && \$3 == \"native\"' | grep -q . && test -n \"\$('$inspect' info '$tmp/arm1.meso' | awk '\$2 == \"RELF\" && \$5 == 1')\""
"$bake" frusta -i "$tmp/arm.skel" -o "$tmp/two.meso" --relief bricks:64 --relief-depth 0.05 --levels 2 >/dev/null 2>&1
check "--levels 2: one RELF, level 1 the stand-in" sh -c "test \$('$inspect' info '$tmp/two.meso' | awk '\$2 == \"RELF\"' | wc -l) -eq 1 && '$inspect' info '$tmp/two.meso' | awk '\$2 == 1 && \$3 == \"mesh\"' | grep -q ."
"$bake" frusta -i "$tmp/arm.skel" -o "$tmp/one.meso" --relief bricks:64 --relief-depth 0.05 --levels 1 >/dev/null 2>&1
check "--levels 1: no MESH, no LODS" test -z "$(row "$tmp/one.meso" MESH)$(row "$tmp/one.meso" LODS)"
for v in 0 17 two; do
  "$bake" frusta -i "$tmp/arm.skel" -o "$tmp/lv.meso" --levels "$v" >/dev/null 2>&1
  check "--levels '$v': exit 1" test $? = 1
done
"$bake" frusta --help | grep -q -- "--levels auto|N"
check "--help documents --levels" test $? = 0
exit $fail
