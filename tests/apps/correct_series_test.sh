#!/usr/bin/env bash
# glasspiv correct over a series: resume by each frame's provenance record,
# pixels that are not finite, camera weights against the mask, the scale of
# 16-bit output, paths in text outputs, and a file-size limit.
# Usage: correct_series_test.sh GLASSPIV_EXECUTABLE
set -u
glasspiv="$1"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
passed=0
failed=0

ok() { passed=$((passed + 1)); }
fail() { failed=$((failed + 1)); echo "FAIL: $*"; }
run() { "$@" >"$work/out" 2>"$work/err"; }
expect_ok() { if run "$@"; then ok; else fail "$* -> exit $? ($(cat "$work/err"))"; fi; }
# expect_error STATUS PATTERN... -- command: exit status STATUS, one stderr line matching every PATTERN.
expect_error() {
  local status="$1"; shift
  local patterns=()
  while [ "$1" != "--" ]; do patterns+=("$1"); shift; done
  shift
  run "$@"
  local got=$?
  if [ "$got" -ne "$status" ]; then fail "$* -> exit $got, expected $status ($(cat "$work/err"))"; return; fi
  if [ "$(wc -l <"$work/err")" -ne 1 ]; then fail "$* -> not one stderr line: $(cat "$work/err")"; return; fi
  for p in "${patterns[@]}"; do
    grep -q -- "$p" "$work/err" || { fail "$* -> '$(cat "$work/err")' lacks '$p'"; return; }
  done
  ok
}
has() { grep -q -- "$1" "$work/out" && ok || fail "$2: $(cat "$work/out")"; }

# A 160 x 120 uncompressed one-strip TIFF: every pixel the 4 bytes $3 (e.g.
# '\x00\x00\x00\x3f', little-endian), pixel $4 (if given) the bytes $5;
# sample format $2: 1 unsigned, 2 signed integer, 3 float (32 bits each).
le16() { printf "\\x$(printf %02x $(($1 & 255)))\\x$(printf %02x $(($1 >> 8 & 255)))"; }
le32() { le16 $(($1 & 65535)); le16 $(($1 >> 16 & 65535)); }
long() { le16 "$1"; le16 4; le32 1; le32 "$2"; }              # a tag of one LONG value
short() { le16 "$1"; le16 3; le32 1; le16 "$2"; le16 0; }     # a tag of one SHORT value
tiff_frame() {
  local file="$1" format="$2" word="$3" at="${4:--1}" special="${5:-}"
  {
    printf 'II*\x00'; le32 8
    le16 10
    long 256 160; long 257 120; short 258 32; short 259 1; short 262 1
    long 273 134; short 277 1; long 278 120; long 279 76800; short 339 "$format"
    le32 0
    if [ "$at" -ge 0 ]; then
      [ "$at" -gt 0 ] && printf "$word%.0s" $(seq "$at")
      printf "$special"
      [ "$at" -lt 19199 ] && printf "$word%.0s" $(seq $((19199 - at)))
    else
      printf "$word%.0s" $(seq 19200)
    fi
  } >"$file"
}

cat >"$work/lens.yaml" <<'YAML'
glasspiv_scene: 1
fluid: air
solids:
  - {type: sphere, centre_mm: [0, 0, 0], diameter_mm: 40, material: N-BK7}
sheet: {origin_mm: [0, 0, 40], s_axis: [-1, 0, 0], t_axis: [0, 1, 0], extent_mm: [100, 100], thickness_mm: 1}
background: {radiance: 0}
cameras:
  - name: small
    model: {image_size_px: [160, 120], lens_model: pinhole, focal_length_px: [400, 400], principal_point_px: [79.5, 59.5]}
    pose: {position_mm: [0, 0, -500], look_at_mm: [0, 0, 40], up: [0, 1, 0]}
  - name: side
    model: {image_size_px: [160, 120], lens_model: pinhole, focal_length_px: [400, 400], principal_point_px: [79.5, 59.5]}
    pose: {position_mm: [150, 0, -450], look_at_mm: [0, 0, 40], up: [0, 1, 0]}
YAML
mkdir -p "$work/frames" "$work/side"
for i in 1 2 3; do
  for cam in small side; do
    dir="$work/frames"; [ "$cam" = side ] && dir="$work/side"
    expect_ok "$glasspiv" render "$work/lens.yaml" --camera "$cam" --sheet-pattern particles --particle-density 0.5 \
      --particle-diameter-mm 1.5 --seed "$i" -o "$dir/f$i.tif" --map "$work/$cam.tmap"
  done
done

# 1. Resume by provenance: kept when nothing changed, redone (and said why)
# when the method, the format, the scene, an input or the file itself changed.
c=("$glasspiv" correct "$work/lens.yaml" --camera small "$work/frames" -o "$work/corr")
expect_ok "${c[@]}"
has "corrected 3 frames" "the first run did not correct 3 frames"
expect_ok "${c[@]}"
has "corrected 0 frames" "an unchanged rerun corrected frames"
has "3 already done" "an unchanged rerun did not keep the 3 frames"
expect_ok "${c[@]}" --method lsq
has "redoing 3 frames written before: 3 made with method accumulate, now lsq" "--method lsq kept frames made by accumulation"
has "least squares" "the rerun did not run least squares"
expect_ok "${c[@]}" --method lsq --format float
has "3 made with format uint16, now float32" "--format float kept 16-bit frames"
expect_ok "${c[@]}" --method lsq --format float
has "3 already done" "an unchanged rerun after the format change did not keep the frames"
cp "$work/corr/f2.tif" "$work/f2_whole.tif"
head -c $(($(wc -c <"$work/f2_whole.tif") - 1)) "$work/f2_whole.tif" >"$work/corr/f2.tif"
touch -d '2020-01-01' "$work/frames/f3.tif"
expect_ok "${c[@]}" --method lsq --format float
has "redoing 2 frames written before: 1 incomplete or unreadable; 1 its input frame changed (camera 'small')" \
  "a frame cut short or an input touched was not redone"
has "corrected 2 frames" "the rerun did not correct exactly the 2 frames"
[ "$(wc -c <"$work/corr/f2.tif")" -eq "$(wc -c <"$work/f2_whole.tif")" ] && ok || fail "the redone frame is not whole"
sed -i 's/position_mm: \[0, 0, -500\]/position_mm: [5, 0, -500]/' "$work/lens.yaml"
expect_ok "${c[@]}" --method lsq --format float
has "3 the correction operator of camera 'small' changed" "moving the camera by 5 mm kept the old frames"
has "corrected 3 frames" "moving the camera by 5 mm did not redo every frame"
sed -i 's/position_mm: \[5, 0, -500\]/position_mm: [0, 0, -500]/' "$work/lens.yaml"
# A frame of the right size without a record (another program's).
"$glasspiv" render "$work/lens.yaml" --camera small --sheet-pattern grid -o "$work/corr/f3.tif" --map "$work/small.tmap" >/dev/null 2>&1
expect_ok "${c[@]}" --method lsq --format float
has "1 no provenance record" "a frame written by another program was kept"
ls -a "$work/corr" | grep -q '\.tmp' && fail "correct left temporary files" || ok

# 2. Pixels that are not finite are left out, least squares runs on the rest;
# a frame without one finite pixel is refused.
mkdir -p "$work/nan" "$work/allnan"
tiff_frame "$work/nan/n1.tif" 3 '\x00\x00\x00\x3f' 9000 '\x00\x00\xc0\x7f'
expect_ok "$glasspiv" correct "$work/lens.yaml" --camera small "$work/nan" -o "$work/nan_out" --method lsq --format float
has "least squares" "lsq with a NaN pixel did not say least squares"
has "left out 1 pixel not finite in 1 frame" "the NaN pixel was not counted"
tiff_frame "$work/allnan/a1.tif" 3 '\x00\x00\xc0\x7f'
expect_error 2 "a1.tif" "no pixel is finite" -- "$glasspiv" correct "$work/lens.yaml" --camera small "$work/allnan" \
  -o "$work/allnan_out" --method lsq
[ ! -e "$work/allnan_out/a1.tif" ] && ok || fail "an all-NaN frame was written"

# 3. Camera weights weigh the data, never the mask.
two=("$glasspiv" correct "$work/lens.yaml" --frame "small=$work/frames/f1.tif" --frame "side=$work/side/f1.tif")
expect_ok "${two[@]}" -o "$work/w1.tif"
grep '^together' "$work/out" >"$work/together1"
expect_ok "${two[@]}" -o "$work/w2.tif" --camera-weight small=1e-4 --camera-weight side=1e-4
grep '^together' "$work/out" >"$work/together2"
cmp -s "$work/together1" "$work/together2" && ok || fail "equal small weights changed the mask: $(cat "$work/together1" "$work/together2")"
grep -q ": 0.00%" "$work/together2" && fail "equal small weights left nothing valid" || ok

# 4. The scale of 16-bit output: float counts are refused with --format 16 and
# kept with --format float; other integer types are refused before any work.
mkdir -p "$work/counts" "$work/int32"
tiff_frame "$work/counts/c1.tif" 3 '\x00\x00\x7a\x45'  # 4000.0
expect_error 2 "c1.tif" "--format float" -- "$glasspiv" correct "$work/lens.yaml" --camera small "$work/counts" -o "$work/counts16"
[ ! -e "$work/counts16/c1.tif" ] && ok || fail "a float frame of counts was written as 16 bits"
expect_ok "$glasspiv" correct "$work/lens.yaml" --camera small "$work/counts" -o "$work/countsf" --format float
tiff_frame "$work/int32/i1.tif" 2 '\xa0\x0f\x00\x00'  # 4000
expect_error 2 "i1.tif" "int32" -- "$glasspiv" correct "$work/lens.yaml" --camera small "$work/int32" -o "$work/int32_out"
[ ! -s "$work/out" ] && ok || fail "an int32 frame was refused after work began: $(cat "$work/out")"

# 5. Paths in text outputs: sheet_grid.yaml names the scene, quoted.
mkdir -p "$work/Experiment #3"
cp "$work/lens.yaml" "$work/Experiment #3/lens.yaml"
expect_ok "$glasspiv" correct "$work/Experiment #3/lens.yaml" --camera small "$work/frames/f1.tif" -o "$work/Experiment #3/out" \
  --grid sheet --no-cache
grep -qF "scene: \"$work/Experiment #3/lens.yaml\"" "$work/Experiment #3/out/sheet_grid.yaml" && ok \
  || fail "sheet_grid.yaml does not quote the scene path: $(cat "$work/Experiment #3/out/sheet_grid.yaml")"

# 6. A file-size limit: one line naming the output, exit 2, no temporary left.
mkdir -p "$work/limit"
(ulimit -f 30 && exec "$glasspiv" correct "$work/lens.yaml" --camera small "$work/frames" -o "$work/limit" --no-cache) \
  >"$work/out" 2>"$work/err"
got=$?
[ "$got" -eq 2 ] && [ "$(wc -l <"$work/err")" -eq 1 ] && grep -q "limit/f1.tif" "$work/err" && ok \
  || fail "a file-size limit gave exit $got: $(cat "$work/err")"
ls -a "$work/limit" | grep -q '\.tmp' && fail "a file-size limit left a temporary: $(ls -a "$work/limit")" || ok
[ ! -e "$work/limit/f1.tif" ] && ok || fail "a frame cut by the file-size limit was renamed into place"

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
