#!/usr/bin/env bash
# End-to-end checks of the glasspiv command line: help everywhere, conversions,
# and that bad input gives exactly one line naming the file and field, exit 2.
# Usage: cli_test.sh GLASSPIV_EXECUTABLE SOURCE_DIR
set -u
glasspiv="$1"
src="$2"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
passed=0
failed=0

ok() { passed=$((passed + 1)); }
fail() { failed=$((failed + 1)); echo "FAIL: $*"; }

# expect_error STATUS PATTERN... -- command: exit status STATUS, one stderr line matching every PATTERN.
expect_error() {
  local status="$1"; shift
  local patterns=()
  while [ "$1" != "--" ]; do patterns+=("$1"); shift; done
  shift
  "$@" >"$work/out" 2>"$work/err"
  local got=$?
  local lines
  lines=$(wc -l <"$work/err")
  if [ "$got" -ne "$status" ]; then fail "$* -> exit $got, expected $status ($(cat "$work/err"))"; return; fi
  if [ "$lines" -ne 1 ]; then fail "$* -> $lines stderr lines, expected 1: $(cat "$work/err")"; return; fi
  for p in "${patterns[@]}"; do
    grep -q -- "$p" "$work/err" || { fail "$* -> '$(cat "$work/err")' lacks '$p'"; return; }
  done
  ok
}

expect_ok() {
  if "$@" >"$work/out" 2>"$work/err"; then ok; else fail "$* -> exit $? ($(cat "$work/err"))"; fi
}

cams="$src/data/cameras"

# --help on every command.
for cmd in "" "camera" "camera convert" "camera show" "camera compare" "demo" "calib" "calib detect" \
  "calib intrinsics" "calib report" "calib next" "target" "target print" "target show" "render" "correct" "coverage" \
  "align" "align pose" "align check" "align refine" "align sensitivity" "align fit" "piv" "simulate"; do
  # shellcheck disable=SC2086
  "$glasspiv" $cmd --help >"$work/out" 2>&1 && grep -q "Usage" "$work/out" && ok || fail "glasspiv $cmd --help"
done
"$glasspiv" --version | grep -q "glasspiv" && ok || fail "--version"

# Conversions through every format and back, and comparisons that must be exactly zero.
expect_ok "$glasspiv" camera convert "$cams/example.yaml" "$work/a.cameramodel"
expect_ok "$glasspiv" camera convert "$work/a.cameramodel" "$work/b.xml" --pixel-pitch-um 6.5
expect_ok "$glasspiv" camera convert "$work/b.xml" "$work/c.yaml" --to opencv
expect_ok "$glasspiv" camera convert "$work/c.yaml" "$work/d.yaml"
"$glasspiv" camera compare "$cams/example.yaml" "$work/d.yaml" >"$work/out" 2>&1
grep -q "RMS 0 px   max 0 px" "$work/out" && ok || fail "round trip through all formats is not exact: $(cat "$work/out")"
expect_ok "$glasspiv" camera show "$cams/wide_opencv8.yaml" --plot "$work/field.png"
[ -s "$work/field.png" ] && ok || fail "camera show --plot wrote no PNG"
expect_ok "$glasspiv" camera compare "$cams/example.yaml" "$cams/example_davis.xml" --use-poses --plot "$work/diff.png"
[ -s "$work/diff.png" ] && ok || fail "camera compare --plot wrote no PNG"

# Bad input: one line, the file and the field named, exit status 2, nothing written.
printf 'glasspiv_camera: 1\nname: x\nimage_size_px: [640, 480]\nlens_model: opencv4\nfocal_length_px: [-500, 500]\nprincipal_point_px: [320, 240]\ndistortion_coefficients: [0, 0, 0, 0]\n' >"$work/neg.yaml"
expect_error 2 "neg.yaml" "fx" -- "$glasspiv" camera show "$work/neg.yaml"
printf 'glasspiv_camera: 1\nname: x\nimage_size_px: [640, 480]\nlens_model: opencv4\nfocal_length_px: [500, 500]\nprincipal_point_px: [320, 240]\ndistortion_coefficients: [0, 0, 0, 0]\ncolour: red\n' >"$work/unknown.yaml"
expect_error 2 "unknown.yaml" "colour" -- "$glasspiv" camera show "$work/unknown.yaml"
printf 'glasspiv_camera: 1\nname: x\nimage_size_px: [640, 480]\nlens_model: opencv4\nfocal_length_px: [500, 500]\nprincipal_point_px: [320, 240]\ndistortion_coefficients: [.nan, 0, 0, 0]\n' >"$work/nan.yaml"
expect_error 2 "nan.yaml" "distortion_coefficients" "finite" -- "$glasspiv" camera show "$work/nan.yaml"
printf 'not: [valid' >"$work/broken.yaml"
expect_error 2 "broken.yaml" -- "$glasspiv" camera convert "$work/broken.yaml" "$work/never.yaml"
[ ! -e "$work/never.yaml" ] && ok || fail "a failed conversion left an output file"
expect_error 2 "does not exist" -- "$glasspiv" camera show "$work/missing.yaml"
expect_error 2 "x.txt" "extension" -- "$glasspiv" camera convert "$work/d.yaml" "$work/x.txt"
printf 'glasspiv_camera: 1\nname: tilted\nimage_size_px: [640, 480]\nlens_model: opencv14\nfocal_length_px: [500, 500]\nprincipal_point_px: [320, 240]\ndistortion_coefficients: [0.1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.01, 0]\n' >"$work/tilted.yaml"
expect_error 2 "t.cameramodel" "14" -- "$glasspiv" camera convert "$work/tilted.yaml" "$work/t.cameramodel"
expect_error 2 "never overwrites" -- "$glasspiv" camera convert "$work/d.yaml" "$work/d.yaml"
expect_error 2 "w.xml" "k1, k2, p1, p2 only" -- "$glasspiv" camera convert "$cams/wide_opencv8.yaml" "$work/w.xml"
expect_error 2 "p.xml" "pixel" -- "$glasspiv" camera convert "$work/a.cameramodel" "$work/p.xml"
expect_error 2 "same sensor" -- "$glasspiv" camera compare "$cams/example.yaml" "$cams/wide_opencv8.yaml"
expect_error 2 "--help" -- "$glasspiv" camera convert
expect_error 2 "--help" -- "$glasspiv" frobnicate
# An unknown subcommand is an error even with --help; usage lines name `glasspiv`, not a path.
expect_error 2 "frobnicate" "not a command" -- "$glasspiv" frobnicate --help
expect_error 2 "frobnicate" "glasspiv camera" -- "$glasspiv" camera frobnicate --help
"$glasspiv" camera show --help | grep -q "^Usage: glasspiv camera show " && ok || fail "usage line does not read 'glasspiv camera show'"
# Every option with a default shows it in --help.
for pair in "render:--min-weight" "render:--min-weight-reflected" "render:--reflection-grid" "render:--reflection-grid-tolerance" "render:--max-depth" "render:--pattern-mm" "render:--gain" "camera show:--step-px" \
  "camera compare:--step-px" "camera compare:--distance-mm" "correct:--min-weight" "coverage:--min-pixels"; do
  # shellcheck disable=SC2086
  "$glasspiv" ${pair%%:*} --help | grep -qE -- "${pair#*:} .*=[0-9]" && ok || fail "glasspiv ${pair%%:*} --help shows no default of ${pair#*:}"
done

# Numbers: finite only, unsigned ones not negative, and the work a value implies within a stated limit,
# refused at once (timeout: no option may start minutes of work or a huge allocation).
expect_error 2 "--step-px" "limit" "2.354 px" -- timeout 20 "$glasspiv" camera compare "$cams/example.yaml" "$cams/example.yaml" --step-px 0.01
expect_error 2 "--step-px" "limit" -- timeout 20 "$glasspiv" camera show "$cams/example.yaml" --step-px 0.001
expect_error 2 "--step-px" "finite" -- "$glasspiv" camera show "$cams/example.yaml" --step-px nan
expect_error 2 "--distance-mm" "finite" -- "$glasspiv" camera compare "$cams/example.yaml" "$cams/example.yaml" --distance-mm inf
expect_error 2 "x.yaml" "--plot" ".png" -- "$glasspiv" camera show "$cams/example.yaml" --plot "$work/x.yaml"
[ ! -e "$work/x.yaml" ] && ok || fail "camera show --plot x.yaml wrote a file"
expect_error 2 "--plot" ".png" -- "$glasspiv" camera compare "$cams/example.yaml" "$cams/example.yaml" --plot "$work/x.tif"
printf 'x' >"$work/dummy_obs.yaml"
expect_error 2 "--outlier-k" "finite" -- "$glasspiv" calib report "$work/dummy_obs.yaml" -o "$work/r" --outlier-k nan
expect_error 2 "--distance-mm" "above 0" -- "$glasspiv" camera compare "$cams/example.yaml" "$cams/example.yaml" --distance-mm -1
[ "$(wc -c <"$work/err")" -lt 200 ] && ok || fail "a range message printed hundreds of digits: $(cat "$work/err")"
expect_error 2 "--dpi" "finite" -- "$glasspiv" target print "$src/data/targets/chessboard_9x6.yaml" --png "$work/x.png" --dpi nan

# A calibration session on real photos (OpenCV's left*.jpg), then a report from
# the saved observations, and the same fit read back from the camera file.
left="$src/data/calibration/opencv_left"
expect_ok "$glasspiv" calib intrinsics "$left" --target "$left/target.yaml" -o "$work/left.cameramodel" \
  --observations-out "$work/left_obs.yaml" --report "$work/left_report"
[ -s "$work/left_report/report.html" ] && grep -q "residuals.png" "$work/left_report/report.html" && ok \
  || fail "calib intrinsics wrote no report"
for png in residuals coverage uncertainty distortion cross_validation; do
  [ -s "$work/left_report/$png.png" ] && ok || fail "report lacks $png.png"
done
expect_ok "$glasspiv" camera show "$work/left.cameramodel"
expect_ok "$glasspiv" calib report "$work/left_obs.yaml" -o "$work/left_report2"
expect_ok "$glasspiv" calib intrinsics "$work/left_obs.yaml" -o "$work/left2.yaml" --no-report
# Where the board should go next: the pose in words, the pictures and the JSON;
# the corners must be the target's.
expect_ok "$glasspiv" calib next "$work/left_obs.yaml" --target "$left/target.yaml" -o "$work/left_next"
grep -q "^next view: tilt the board" "$work/out" && [ -s "$work/left_next/placement.png" ] \
  && [ -s "$work/left_next/after.png" ] && grep -q '"worst_after_px"' "$work/left_next/next_view.json" && ok \
  || fail "calib next wrote no proposal"
expect_error 2 "left_obs.yaml" "target" -- "$glasspiv" calib next "$work/left_obs.yaml" \
  --target "$src/data/targets/chessboard_9x6.yaml" -o "$work/x_next"
"$glasspiv" camera compare "$work/left.cameramodel" "$work/left2.yaml" >"$work/out" 2>&1
# Saved observations are the detected floats exactly; only Ceres' threaded sums
# may differ in the last bits, far below 1e-6 px.
awk '/max/ {for (i = 1; i < NF; ++i) if ($i == "max") exit !($(i + 1) < 1e-6)}' "$work/out" && ok \
  || fail "fit from saved observations differs: $(cat "$work/out")"
expect_error 2 "aprilgrid" "found in none" -- "$glasspiv" calib intrinsics "$left" --target "$src/data/targets/aprilgrid_6x6.yaml" -o "$work/x.yaml"
expect_error 2 "--target" -- "$glasspiv" calib intrinsics "$left" -o "$work/x.yaml"
printf 'not an image' >"$work/fake.png"
expect_error 2 "fake.png" -- "$glasspiv" calib intrinsics "$work/fake.png" --target "$left/target.yaml" -o "$work/x.yaml"
[ ! -e "$work/x.yaml" ] && ok || fail "a failed calibration wrote a camera file"

# Render: a small ball-lens scene (inline 160 x 120 camera), textured sheet,
# the transport map cache, the setup, and bad input.
cat >"$work/lens.yaml" <<'YAML'
glasspiv_scene: 1
fluid: air
solids:
  - {type: sphere, centre_mm: [0, 0, 0], diameter_mm: 40, material: N-BK7}
  - {type: rectangle, centre_mm: [0, 0, 120], size_mm: [200, 200], normal: [0, 0, -1], up: [0, 1, 0], material: grey}
materials:
  grey: {opaque: 0.5}
sheet: {origin_mm: [0, 0, 40], s_axis: [-1, 0, 0], t_axis: [0, 1, 0], extent_mm: [100, 100], thickness_mm: 1}
background: {radiance: 0}
cameras:
  - name: small
    model: {image_size_px: [160, 120], lens_model: pinhole, focal_length_px: [400, 400], principal_point_px: [79.5, 59.5]}
    pose: {position_mm: [0, 0, -500], look_at_mm: [0, 0, 40], up: [0, 1, 0]}
YAML
expect_ok "$glasspiv" render "$work/lens.yaml" --sheet-pattern checker -o "$work/lens.tif" --map "$work/lens.tmap"
[ -s "$work/lens.tif" ] && [ -s "$work/lens.tmap" ] && ok || fail "render wrote no image or map"
grep -q "traced a new transport map" "$work/out" && ok || fail "first render did not trace: $(cat "$work/out")"
expect_ok "$glasspiv" render "$work/lens.yaml" --sheet-texture "$work/lens.tif" -o "$work/lens2.exr" --map "$work/lens.tmap"
grep -q "nothing re-traced" "$work/out" && ok || fail "second render re-traced: $(cat "$work/out")"
expect_ok "$glasspiv" render "$work/lens.yaml" --sheet-pattern particles -o "$work/lens3.png" --map "$work/lens.tmap" --no-reflections
grep -q "another setup" "$work/out" && ok || fail "changed settings reused the map: $(cat "$work/out")"
# A reflected cut-off at or below --min-weight traces the same map; above it, another.
expect_ok "$glasspiv" render "$work/lens.yaml" --sheet-pattern checker -o "$work/lens4.png" --map "$work/lens4.tmap"
expect_ok "$glasspiv" render "$work/lens.yaml" --sheet-pattern checker -o "$work/lens4.png" --map "$work/lens4.tmap" --min-weight-reflected 0.005
grep -q "nothing re-traced" "$work/out" && ok || fail "a reflected cut-off below --min-weight re-traced: $(cat "$work/out")"
expect_ok "$glasspiv" render "$work/lens.yaml" --sheet-pattern checker -o "$work/lens4.png" --map "$work/lens4.tmap" --min-weight-reflected 0.5
grep -q "another setup" "$work/out" && ok || fail "a reflected cut-off above --min-weight reused the map: $(cat "$work/out")"
# The reflection grid traces another map, and says what it interpolated.
expect_ok "$glasspiv" render "$work/lens.yaml" --sheet-pattern checker -o "$work/lens5.png" --map "$work/lens5.tmap" --reflection-grid 1
expect_ok "$glasspiv" render "$work/lens.yaml" --sheet-pattern checker -o "$work/lens5.png" --map "$work/lens5.tmap" --reflection-grid 2
grep -q "another setup" "$work/out" && grep -q "reflection grid 2: [0-9]* reflected subtrees and [1-9][0-9]* whole samples interpolated" "$work/out" \
  && ok || fail "--reflection-grid 2 reused the map or did not report: $(cat "$work/out")"
# Whole samples are the default; without them, another map, every chain traced.
expect_ok "$glasspiv" render "$work/lens.yaml" --sheet-pattern checker -o "$work/lens5.png" --map "$work/lens5.tmap" --no-whole-samples
grep -q "another setup" "$work/out" && grep -q "reflection grid 2: [0-9]* reflected subtrees and 0 whole samples" "$work/out" \
  && ok || fail "--no-whole-samples reused the map or interpolated samples: $(cat "$work/out")"
expect_error 2 "--reflection-grid" -- "$glasspiv" render "$work/lens.yaml" --sheet-pattern checker -o "$work/x.tif" --reflection-grid 0
expect_error 2 "--reflection-grid-tolerance" -- "$glasspiv" render "$work/lens.yaml" --sheet-pattern checker -o "$work/x.tif" --reflection-grid-tolerance -1
expect_ok "$glasspiv" render "$work/lens.yaml" --setup -o "$work/setup.png" --format 8 --background 1
[ -s "$work/setup.png" ] && ok || fail "render --setup wrote nothing"
cat "$work/lens.yaml" - >"$work/two.yaml" <<'YAML'
  - name: side
    model: {image_size_px: [80, 60], lens_model: pinhole, focal_length_px: [200, 200], principal_point_px: [39.5, 29.5]}
    pose: {position_mm: [200, 0, -450], look_at_mm: [0, 0, 40], up: [0, 1, 0]}
YAML
expect_ok "$glasspiv" render "$work/two.yaml" --camera all --sheet-pattern grid -o "$work/two.tif" --map "$work/two.tmap"
[ -s "$work/two_small.tif" ] && [ -s "$work/two_side.tif" ] && [ -s "$work/two_small.tmap" ] && [ -s "$work/two_side.tmap" ] \
  && ok || fail "render --camera all did not write one image and map per camera"
cp "$src/data/targets/charuco_11x8_15mm.yaml" "$work/board.yaml"
sed 's/material: grey}/texture: board.yaml}/' "$work/lens.yaml" >"$work/board_scene.yaml"
expect_ok "$glasspiv" render "$work/board_scene.yaml" --setup -o "$work/board.png" --format 8
[ -s "$work/board.png" ] && ok || fail "render --setup with a target texture wrote nothing"
expect_error 2 "exactly one" -- "$glasspiv" render "$work/lens.yaml" -o "$work/x.tif"
expect_error 2 "x.png" "--format" "float" -- "$glasspiv" render "$work/lens.yaml" --setup -o "$work/x.png" --format float
expect_error 2 "x.jpg" "-o" -- "$glasspiv" render "$work/lens.yaml" --setup -o "$work/x.jpg"
expect_error 2 "lens.yaml" "--camera" "small" -- "$glasspiv" render "$work/lens.yaml" --setup --camera nope -o "$work/x.tif"
sed 's/look_at_mm: \[0, 0, 40\]/look_at_mm: [0, 0, -1000]/' "$work/lens.yaml" >"$work/away.yaml"
expect_error 2 "away.yaml" "sees none of the sheet" -- "$glasspiv" render "$work/away.yaml" --sheet-pattern grid -o "$work/x.tif"
sed 's/diameter_mm: 40/diameter_mm: -40/' "$work/lens.yaml" >"$work/neg.yaml"
expect_error 2 "neg.yaml" "diameter_mm" -- "$glasspiv" render "$work/neg.yaml" --setup -o "$work/x.tif"
sed 's/material: grey}/material: N-BK7}/' "$work/lens.yaml" >"$work/glassrect.yaml"
expect_error 2 "glassrect.yaml" "opaque" -- "$glasspiv" render "$work/glassrect.yaml" --setup -o "$work/x.tif"
expect_error 2 "lens.tif" "input" -- "$glasspiv" render "$work/lens.yaml" --sheet-texture "$work/lens.tif" -o "$work/lens.tif"
[ ! -e "$work/x.tif" ] && ok || fail "a failed render wrote an image"
for opt in --min-weight --min-weight-reflected --background --gain --pattern-mm; do
  expect_error 2 "$opt" "finite" -- "$glasspiv" render "$work/lens.yaml" --sheet-pattern checker -o "$work/x.tif" "$opt" nan
done
expect_error 2 "--seed" "negative" -- "$glasspiv" render "$work/lens.yaml" --sheet-pattern particles -o "$work/x.tif" --seed -1
expect_error 2 "--samples" -- "$glasspiv" render "$work/lens.yaml" --setup -o "$work/x.tif" --samples 0x10
expect_error 2 "--pattern-mm" "limit" -- timeout 20 "$glasspiv" render "$work/lens.yaml" --sheet-pattern checker -o "$work/x.tif" --pattern-mm 1e-6
expect_error 2 "--particle-diameter-mm" "limit" -- timeout 20 "$glasspiv" render "$work/lens.yaml" --sheet-pattern particles -o "$work/x.tif" --particle-diameter-mm 1e-300
expect_error 2 "--particle-density" "limit" -- timeout 20 "$glasspiv" render "$work/lens.yaml" --sheet-pattern particles -o "$work/x.tif" --particle-density 1e300
expect_error 2 "--threads" -- "$glasspiv" render "$work/lens.yaml" --setup -o "$work/x.tif" --threads 1000000
grep -q "2 solids;" "$work/out" || "$glasspiv" render "$work/lens.yaml" --setup -o "$work/x.tif" --binning 16 >"$work/out" 2>&1
grep -q "2 solids;" "$work/out" && ok || fail "render did not report '2 solids': $(cat "$work/out")"
grep -v 'rectangle' "$work/lens.yaml" >"$work/one.yaml"
expect_ok "$glasspiv" render "$work/one.yaml" --setup -o "$work/one.tif" --binning 16
grep -q "1 solid;" "$work/out" && ok || fail "render said '1 solids': $(cat "$work/out")"
rm -f "$work/x.tif"

# No output may be a file the command reads (the scene's camera files and textures included),
# outputs are distinct, and an existing output that is not a regular file is refused, all before any tracing.
mkdir -p "$work/own"
printf 'glasspiv_camera: 1\nname: small\nimage_size_px: [160, 120]\nlens_model: pinhole\nfocal_length_px: [400, 400]\nprincipal_point_px: [79.5, 59.5]\n' >"$work/own/cam.yaml"
cp "$work/setup.png" "$work/own/tex.png"
cat >"$work/own/s.yaml" <<'YAML'
glasspiv_scene: 1
fluid: air
solids:
  - {type: sphere, centre_mm: [0, 0, 0], diameter_mm: 40, material: N-BK7}
  - {type: rectangle, centre_mm: [0, 0, 120], size_mm: [200, 200], normal: [0, 0, -1], up: [0, 1, 0], texture: tex.png}
sheet: {origin_mm: [0, 0, 40], s_axis: [-1, 0, 0], t_axis: [0, 1, 0], extent_mm: [100, 100], thickness_mm: 1}
cameras:
  - name: small
    file: cam.yaml
    pose: {position_mm: [0, 0, -500], look_at_mm: [0, 0, 40], up: [0, 1, 0]}
YAML
cp "$work/own/cam.yaml" "$work/own/cam.keep"
expect_error 2 "cam.yaml" "--map" "never overwrites" -- "$glasspiv" render "$work/own/s.yaml" --sheet-pattern grid -o "$work/own/x.tif" --map "$work/own/cam.yaml"
cmp -s "$work/own/cam.yaml" "$work/own/cam.keep" && ok || fail "render --map overwrote the scene's camera file"
expect_error 2 "tex.png" "--map" "never overwrites" -- "$glasspiv" render "$work/own/s.yaml" --sheet-pattern grid -o "$work/own/x.tif" --map "$work/own/tex.png"
expect_error 2 "tex.png" "-o" "never overwrites" -- "$glasspiv" render "$work/own/s.yaml" --setup -o "$work/own/tex.png"
expect_error 2 "x.tif" "same output" -- "$glasspiv" render "$work/own/s.yaml" --sheet-pattern grid -o "$work/own/x.tif" --map "$work/own/x.tif"
expect_error 2 "tex.png" "never overwrites" -- "$glasspiv" coverage "$work/own/s.yaml" -o "$work/own/tex.png"
ln -s cam.keep "$work/own/link.tif"
expect_error 2 "link.tif" "symbolic link" -- "$glasspiv" render "$work/own/s.yaml" --setup -o "$work/own/link.tif"
[ -L "$work/own/link.tif" ] && cmp -s "$work/own/cam.keep" "$work/own/cam.yaml" && ok || fail "render replaced a symbolic link"
mkfifo "$work/own/fifo.tmap"
expect_error 2 "fifo.tmap" "--map" "fifo" -- timeout 20 "$glasspiv" render "$work/own/s.yaml" --sheet-pattern grid -o "$work/own/x.tif" --map "$work/own/fifo.tmap"
expect_error 2 "--map" "cannot be created" -- "$glasspiv" render "$work/own/s.yaml" --sheet-pattern grid -o "$work/own/x.tif" --map "$work/own/cam.keep/m.tmap"
[ ! -s "$work/out" ] && ok || fail "a bad --map was reported after work began: $(cat "$work/out")"
[ ! -e "$work/own/x.tif" ] && ok || fail "a refused render wrote its image"
ln -s cam.keep "$work/own/link.yaml"
expect_error 2 "link.yaml" "symbolic link" -- "$glasspiv" camera convert "$cams/example.yaml" "$work/own/link.yaml"
ln -s cam.keep "$work/own/link.png"
expect_error 2 "link.png" "--plot" "symbolic link" -- "$glasspiv" camera show "$work/own/cam.yaml" --plot "$work/own/link.png"
mkdir -p "$work/demo_bad"
mkfifo "$work/demo_bad/fifo"
expect_error 2 "fifo" "-o" -- timeout 20 "$glasspiv" demo -o "$work/demo_bad"

# Correct: frames rendered through the ball lens by the two-camera scene, then
# corrected (camera grid, sheet grid, several cameras), resumed, sharded, and bad input.
mkdir -p "$work/frames" "$work/side"
for i in 1 2 3; do
  expect_ok "$glasspiv" render "$work/two.yaml" --camera small --sheet-pattern particles --particle-density 0.5 \
    --particle-diameter-mm 1.5 --seed "$i" -o "$work/frames/f$i.tif" --map "$work/small.tmap"
  expect_ok "$glasspiv" render "$work/two.yaml" --camera side --sheet-pattern particles --particle-density 0.5 \
    --particle-diameter-mm 1.5 --seed "$i" -o "$work/side/f$i.tif" --map "$work/side.tmap"
done
expect_ok "$glasspiv" correct "$work/two.yaml" --camera small "$work/frames" -o "$work/corr"
[ -s "$work/corr/f1.tif" ] && [ -s "$work/corr/f3.tif" ] && [ -s "$work/corr/mask.tif" ] && ok \
  || fail "correct wrote no corrected frames or mask: $(ls "$work/corr")"
grep -q "corrected 3 frames" "$work/out" && ok || fail "correct did not report 3 frames: $(cat "$work/out")"
ls "$work/corr" | grep -q '\.tmp' && fail "correct left temporary files" || ok
rm "$work/corr/f2.tif"
expect_ok "$glasspiv" correct "$work/two.yaml" --camera small "$work/frames" -o "$work/corr"
grep -q "corrected 1 frame " "$work/out" && grep -q "2 already done" "$work/out" && grep -q "reused the correction operator" "$work/out" \
  && ok || fail "a rerun did not redo only the missing frame from the cached operator: $(cat "$work/out")"
expect_ok "$glasspiv" correct "$work/two.yaml" --camera small "$work/frames" -o "$work/sheet" --grid sheet --method lsq --format float
[ -s "$work/sheet/f1.tif" ] && [ -s "$work/sheet/sheet_grid.yaml" ] && ok || fail "correct --grid sheet wrote no frame or grid file"
expect_ok "$glasspiv" correct "$work/two.yaml" --camera small "$work/frames" -o "$work/shard" --prepare-only
[ -s "$work/shard/mask.tif" ] && [ ! -e "$work/shard/f1.tif" ] && ok || fail "--prepare-only corrected frames or wrote no mask"
for k in 0 1; do expect_ok "$glasspiv" correct "$work/two.yaml" --camera small "$work/frames" -o "$work/shard" --shard "$k/2"; done
[ "$(ls "$work/shard"/f*.tif | wc -l)" -eq 3 ] && ok || fail "two shards did not write the three frames"
expect_ok "$glasspiv" correct "$work/two.yaml" --frame "small=$work/frames/f1.tif" --frame "side=$work/side/f1.tif" \
  -o "$work/both.tif" --method lsq
[ -s "$work/both.tif" ] && [ -s "$work/both_mask.tif" ] && [ -s "$work/both_coverage.tif" ] && ok \
  || fail "two-camera correct wrote no image, mask or coverage"
expect_ok "$glasspiv" correct "$work/two.yaml" --frame "small=$work/frames" --frame "side=$work/side/f*.tif" -o "$work/pairs" \
  --camera-weight side=0.5
expect_error 2 "--camera-weight" -- "$glasspiv" correct "$work/two.yaml" --frame "small=$work/frames/f1.tif" -o "$work/bad.tif" --camera-weight side=1
expect_error 2 "--camera-weight" -- "$glasspiv" correct "$work/two.yaml" --frame "small=$work/frames/f1.tif" -o "$work/bad.tif" --camera-weight small=-1
[ "$(ls "$work/pairs"/f*.tif | wc -l)" -eq 3 ] && ok || fail "two-camera series did not write three instants"
expect_ok "$glasspiv" coverage "$work/two.yaml" -o "$work/coverage.png"
[ -s "$work/coverage.png" ] && grep -q "together" "$work/out" && ok || fail "coverage wrote no picture or figures"
cp "$work/frames/f1.tif" "$work/f1_copy.tif"
expect_error 2 "image size" "small" -- "$glasspiv" correct "$work/two.yaml" --camera small "$work/side/f1.tif" -o "$work/bad"
expect_error 2 "--camera" "nope" -- "$glasspiv" correct "$work/two.yaml" --camera nope "$work/frames" -o "$work/bad"
expect_error 2 "--frame" "has 3" -- "$glasspiv" correct "$work/two.yaml" --frame "small=$work/frames" --frame "side=$work/side/f1.tif" -o "$work/bad"
expect_error 2 "input" -- "$glasspiv" correct "$work/two.yaml" --camera small "$work/frames/f1.tif" -o "$work/frames"
expect_error 2 "same output" -- "$glasspiv" correct "$work/two.yaml" --camera small "$work/frames/f1.tif" "$work/side/f1.tif" -o "$work/bad"
expect_error 2 "--shard" -- "$glasspiv" correct "$work/two.yaml" --camera small "$work/frames" -o "$work/bad" --shard 2/2
expect_error 2 "--mm-per-px" "limit" -- timeout 20 "$glasspiv" correct "$work/two.yaml" --camera small "$work/frames" -o "$work/bad" --grid sheet --mm-per-px 1e-300
[ "$(wc -c <"$work/err")" -lt 300 ] && ok || fail "a message printed a number of hundreds of digits: $(cat "$work/err")"
expect_error 2 "--min-weight" "finite" -- "$glasspiv" coverage "$work/two.yaml" -o "$work/c.png" --min-weight nan
mkdir -p "$work/m"
cp "$work/frames/f1.tif" "$work/m/mask.tif"
expect_error 2 "mask.tif" "never overwrites" -- "$glasspiv" correct "$work/two.yaml" --camera small "$work/m/mask.tif" -o "$work/m"
head -c 3000 "$work/frames/f1.tif" >"$work/trunc.tif"
expect_error 2 "trunc.tif" -- "$glasspiv" correct "$work/two.yaml" --camera small "$work/trunc.tif" -o "$work/bad"
op=$(ls "$work/corr/cache/"*.gop | head -n 1)
printf 'garbage' | dd of="$op" bs=1 seek=200 conv=notrunc 2>/dev/null
expect_error 2 ".gop" "delete it" -- "$glasspiv" correct "$work/two.yaml" --camera small "$work/frames" -o "$work/corr"
# kill -9 in the middle of a series leaves no file under a final name half-written.
for i in $(seq 4 40); do cp "$work/frames/f1.tif" "$work/frames/f$i.tif"; done
rm -f "$op"
"$glasspiv" correct "$work/two.yaml" --camera small "$work/frames" -o "$work/killed" --method lsq >/dev/null 2>&1 &
pid=$!
sleep 1.5
kill -9 "$pid" 2>/dev/null
wait "$pid" 2>/dev/null
bad=0
for f in "$work/killed"/f*.tif; do
  [ -e "$f" ] || continue
  "$glasspiv" correct "$work/two.yaml" --camera small "$f" -o "$work/check" --no-cache >/dev/null 2>&1 || bad=1
done
[ "$bad" -eq 0 ] && ok || fail "a killed series left an unreadable frame"
expect_ok "$glasspiv" correct "$work/two.yaml" --camera small "$work/frames" -o "$work/killed" --method lsq
[ "$(ls "$work/killed"/f*.tif | wc -l)" -eq 40 ] && ok || fail "the rerun after kill -9 did not complete the series"

# align: refusals before any work, and a sensitivity map of the reactor.
reactor="$src/data/scenes/reactor.yaml"
"$glasspiv" render "$reactor" --setup -o "$work/setup_photo.png" --binning 8 >/dev/null 2>&1 || fail "render --setup for align"
expect_error 2 "reactor.yaml" "no fiducials" -- "$glasspiv" align pose "$reactor" "$work/setup_photo.png"
expect_error 2 "setup_photo.png" "size" "px" -- "$glasspiv" align check "$reactor" "$work/setup_photo.png" -o "$work/ov.png"
expect_error 2 "ov.txt" ".png" -- "$glasspiv" align check "$reactor" "$work/setup_photo.png" -o "$work/ov.txt"
expect_error 2 "--levels" -- "$glasspiv" align refine "$reactor" "$work/setup_photo.png" --levels 0
expect_ok "$glasspiv" align sensitivity "$reactor" -o "$work/sens.png" --step-px 64 --json "$work/sens.json"
[ -s "$work/sens.png" ] && [ -s "$work/sens_px.png" ] && grep -q median_mm "$work/sens.json" && ok \
  || fail "align sensitivity outputs"

# align end to end on the reactor with markers, binned 4 x 4: a setup render as
# the photo, pose from its markers into a new scene, check, refine, sensitivity.
mkdir -p "$work/al/scenes" "$work/al/cameras"
cp -r "$src/data/scenes/reactor_markers.yaml" "$src/data/scenes/markers" "$work/al/scenes/"
cp "$cams/example.yaml" "$work/al/cameras/"
al="$work/al/scenes"
expect_ok "$glasspiv" render "$al/reactor_markers.yaml" --setup -o "$work/al/photo.png" --binning 4 --format 8
expect_ok "$glasspiv" align pose "$al/reactor_markers.yaml" "$work/al/photo.png" --binning 4 -o "$al/posed.yaml" \
  --json "$work/al/pose.json"
grep -q '"covariance"' "$work/al/pose.json" && grep -q "pose:" "$al/posed.yaml" && ok || fail "align pose outputs"
expect_error 2 "posed_elsewhere.yaml" "scene's own folder" -- "$glasspiv" align pose "$al/reactor_markers.yaml" \
  "$work/al/photo.png" --binning 4 -o "$work/al/posed_elsewhere.yaml"
expect_error 2 "photo.png" "size" -- "$glasspiv" align pose "$al/reactor_markers.yaml" "$work/al/photo.png"
expect_ok "$glasspiv" align check "$al/posed.yaml" "$work/al/photo.png" --binning 4 -o "$work/al/check.png" \
  --json "$work/al/check.json"
[ -s "$work/al/check_edges.png" ] && [ -s "$work/al/check_checker.png" ] && grep -q gradient_ncc "$work/al/check.json" \
  && ok || fail "align check outputs"
expect_ok "$glasspiv" align refine "$al/posed.yaml" "$work/al/photo.png" --binning 4 --levels 8 \
  --scene-out "$al/refined.yaml"
expect_ok "$glasspiv" align sensitivity "$al/posed.yaml" --binning 4 -o "$work/al/sens.png" \
  --pose-json "$work/al/pose.json" --step-px 32
# Refused in one line, exit 2, nothing written: a photo given twice (or a
# copy) to align pose; sensitivities with nothing to measure or perturbed
# models that are no scene (an index below 0.5 asserted in the optics, a
# rotation tolerance of 1e300 deg ended in std::terminate from a worker); a
# refinement from a camera turned away from the setup.
cp "$work/al/photo.png" "$work/al/copy.png"
expect_error 2 "photo.png" "same file as" -- "$glasspiv" align pose "$al/posed.yaml" "$work/al/photo.png" \
  "$work/al/photo.png" --binning 4 --json "$work/al/dup.json"
expect_error 2 "copy.png" "same bytes as" -- "$glasspiv" align pose "$al/posed.yaml" "$work/al/photo.png" \
  "$work/al/copy.png" --binning 4 --json "$work/al/dup.json"
[ ! -e "$work/al/dup.json" ] && ok || fail "a refused align pose wrote its JSON"
expect_error 2 "--index" "refractive index" -- "$glasspiv" align sensitivity "$reactor" -o "$work/sx.png" \
  --step-px 64 --index 2
expect_error 2 "--camera-deg" -- "$glasspiv" align sensitivity "$reactor" -o "$work/sx.png" --step-px 64 \
  --camera-deg 1e300
expect_error 2 "--diameter-mm" "mm across" -- "$glasspiv" align sensitivity "$reactor" -o "$work/sx.png" \
  --step-px 64 --diameter-mm 100
expect_error 2 "every tolerance is 0" -- "$glasspiv" align sensitivity "$reactor" -o "$work/sx.png" --step-px 64 \
  --camera-mm 0 --camera-deg 0 --glass-mm 0 --diameter-mm 0 --index 0
sed 's/rvec: \[[^]]*\]/rvec: [0, 3.14159, 0]/' "$al/posed.yaml" >"$al/away.yaml"
expect_error 2 "away.yaml" "sees the sheet directly" -- "$glasspiv" align sensitivity "$al/away.yaml" --binning 4 \
  -o "$work/sx.png" --step-px 32
[ ! -e "$work/sx.png" ] && ok || fail "a refused sensitivity wrote its map"
expect_error 2 "away.yaml" "took no step" "nothing written" -- "$glasspiv" align refine "$al/away.yaml" \
  "$work/al/photo.png" --binning 4 --levels 8 --scene-out "$al/away_refined.yaml" --json "$work/al/away.json"
[ ! -e "$al/away_refined.yaml" ] && [ ! -e "$work/al/away.json" ] && ok || fail "a failed refinement wrote its pose"
cmp -s "$src/data/scenes/reactor_markers.yaml" "$al/reactor_markers.yaml" && ok || fail "align changed its input scene"

# align fit: the ball layer binned 16 x 16, its plate photo rendered through the
# drawing itself (the fit must stay at the drawing and explain the photo), then
# the refusals: another plate, a photo of the wrong size, two photos of one
# camera without the plate's positions, offsets that do not match the photos.
layer="$src/data/scenes/ball_layer.yaml"
speckle="$src/data/targets/speckle_150x120_0.5mm.yaml"
mkdir -p "$work/fit"
expect_ok "$glasspiv" target print "$speckle" -o "$work/fit/plate.svg" --png "$work/fit/plate.png" --dpi 254
expect_ok "$glasspiv" render "$layer" --sheet-texture "$work/fit/plate.png" --texture-mm-per-px 0.1 --binning 16 \
  --samples 3 -o "$work/fit/photo.tif"
expect_ok "$glasspiv" align fit "$layer" "$work/fit/photo.tif" --plate "$speckle" --binning 16 --levels 2,1 \
  -o "$work/fit/fitted.yaml" --json "$work/fit/fit.json"
grep -q '"explained_variance": 0.9' "$work/fit/fit.json" && [ -s "$work/fit/fitted.yaml" ] && ok \
  || fail "align fit outputs"
expect_ok "$glasspiv" render "$work/fit/fitted.yaml" --sheet-pattern checker --binning 16 -o "$work/fit/check.png"
sed 's/^seed: 1/seed: 2/' "$speckle" > "$work/fit/other.yaml"
expect_error 2 "photo.tif" "does not show this plate" "nothing written" -- "$glasspiv" align fit "$layer" \
  "$work/fit/photo.tif" --plate "$work/fit/other.yaml" --binning 16 --levels 2 -o "$work/fit/other_fit.yaml"
[ ! -e "$work/fit/other_fit.yaml" ] && ok || fail "a refused fit wrote its scene"
expect_error 2 "photo.tif" "size" -- "$glasspiv" align fit "$layer" "$work/fit/photo.tif" --plate "$speckle" \
  --binning 8 -o "$work/fit/f.yaml"
cp "$work/fit/photo.tif" "$work/fit/photo2.tif" && printf x >> "$work/fit/photo2.tif"
expect_error 2 "second photo" "--plate-offsets-mm" -- "$glasspiv" align fit "$layer" "$work/fit/photo.tif" \
  "$work/fit/photo2.tif" --plate "$speckle" --binning 16 -o "$work/fit/f.yaml"
expect_error 2 "--plate-offsets-mm" "2 offsets for 1" -- "$glasspiv" align fit "$layer" "$work/fit/photo.tif" \
  --plate "$speckle" --binning 16 --plate-offsets-mm 0,4 -o "$work/fit/f.yaml"

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
