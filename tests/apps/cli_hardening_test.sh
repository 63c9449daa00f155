#!/usr/bin/env bash
# Command-line checks of issue 40's hardening: no output replaces an input or a
# file of another kind (derived names included), no input that is not a regular
# file blocks a reader, no integer option wraps or saturates, and file-system
# and JSON problems read as one line in glasspiv's words. Every refusal: exit
# status 2, one line naming the option or field and the file, nothing written.
# usage: cli_hardening_test.sh GLASSPIV SOURCE_DIR
set -u
G=$1
src=$(cd "$2" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1

source "$src/tests/cli_checks.sh"

# refused PATTERN... -- COMMAND...: exit status 2 within 30 s, one line on
# stderr holding every PATTERN and no library text.
refused() {
  local patterns=()
  while [ "$1" != "--" ]; do patterns+=("$1"); shift; done
  shift
  expect 2 timeout 30 "$@"
  one_line
  for p in "${patterns[@]}"; do has err.txt "$p"; done
  ! grep -qE "internal error|json.exception|filesystem error" err.txt || fail "library text reached the user: $*"
}
unchanged() { cmp -s "$1" "$2" || fail "$1 was overwritten"; }
no_temporaries() { ! ls -A . | grep -q '\.tmp-' || fail "a temporary was left: $(ls -A . | grep '\.tmp-')"; }

# A small scene: a glass ball before a grey wall, one 160 x 120 camera.
cat >lens.yaml <<'YAML'
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
expect 0 "$G" render lens.yaml --setup -o photo.png --format 8
expect 0 "$G" render lens.yaml --sheet-pattern checker -o frame.tif --map lens.tmap

# --- 1. Inputs and outputs: derived names against every input and output, kinds.
cp photo.png shot_edges.png && cp photo.png keep.png
refused "shot_edges.png" "-o" "never overwrites" -- "$G" align check lens.yaml shot_edges.png -o shot.png
unchanged shot_edges.png keep.png
[ ! -e shot.png ] || fail "a refused align check wrote its overlay"
cp photo.png X_checker.png
refused "X_checker.png" "never overwrites" -- "$G" align refine lens.yaml X_checker.png --levels 8 -o X.png
unchanged X_checker.png keep.png
refused "cj_edges.png" "same output" -- "$G" align check lens.yaml photo.png --json cj_edges.png -o cj.png
[ ! -e cj.png ] && [ ! -e cj_edges.png ] || fail "a refused align check wrote an output"
refused "s_px.png" "same output" -- "$G" align sensitivity lens.yaml -o s.png --json s_px.png --step-px 64
# The same file under other names: ./, a hard link, a symbolic link.
ln photo.png hard.png
refused "hard.png" "never overwrites" -- "$G" align check lens.yaml photo.png -o ./hard_checker.png/../hard.png
refused "never overwrites" -- "$G" align check lens.yaml ./photo.png -o photo.png
ln -s photo.png soft_edges.png
refused "soft_edges.png" -- "$G" align check lens.yaml photo.png -o soft.png
unchanged photo.png keep.png
# A map output over a TIFF that is not a map; a JSON over an image; an image over text.
cp frame.tif frame.keep
refused "frame.tif" "--map" "not a transport map" -- "$G" render lens.yaml --sheet-pattern grid -o g.tif --map frame.tif
unchanged frame.tif frame.keep
[ ! -e g.tif ] || fail "a refused render wrote its image"
refused "keep.png" "--json" "not a JSON file" -- "$G" align check lens.yaml photo.png -o ov.png --json keep.png
printf 'a: 1\n' >notes.png
refused "notes.png" "-o" "not an image" -- "$G" render lens.yaml --setup -o notes.png
cp keep.png pic.yaml
refused "pic.yaml" "not a text file" -- "$G" camera convert "$src/data/cameras/example.yaml" pic.yaml
unchanged pic.yaml keep.png
printf 'x' >report_file
mkdir -p demo_out && printf 'a: 1\n' >demo_out/report.html && cp keep.png demo_out/index.html
refused "index.html" "not a text file" -- "$G" demo -o demo_out
refused "report_file" "not a folder" -- "$G" calib report "$src/data/calibration/opencv_left/target.yaml" -o report_file
no_temporaries

# --- 2. Inputs that are not regular files: refused at once, naming the option or file.
mkfifo fifo.png fifo.yaml fifo.json fifo.pgm fifo.tif fifo.vti
refused "fifo.png" "fifo" -- "$G" render lens.yaml --sheet-texture fifo.png -o t.tif
refused "fifo.yaml" "fifo" -- "$G" render fifo.yaml --setup -o t.tif
refused "fifo.png" "fifo" -- "$G" align check lens.yaml fifo.png -o t.png
refused "fifo.json" "fifo" -- "$G" align sensitivity lens.yaml -o t.png --pose-json fifo.json
refused "fifo.yaml" "fifo" -- "$G" camera show fifo.yaml
refused "fifo.yaml" "fifo" -- "$G" target print fifo.yaml --png t.png
refused "fifo.json" "fifo" -- "$G" calib report fifo.json -o rep
refused "fifo.json" "fifo" -- "$G" calib intrinsics fifo.json -o cam.yaml
refused "fifo.pgm" "fifo" -- "$G" piv fifo.pgm fifo.pgm -o v.txt
refused "fifo.tif" "fifo" -- "$G" correct lens.yaml --camera small fifo.tif -o corr
refused "fifo.png" "fifo" -- "$G" align pose lens.yaml --photo small=fifo.png
refused "fifo.vti" "fifo" -- "$G" simulate lens.yaml --flow vtk:fifo.vti -o sim
refused "/dev/null" "character device" -- "$G" correct lens.yaml --camera small /dev/null -o corr
mkdir -p adir
refused "adir" "--mask" "folder" -- "$G" piv frame.tif frame.tif --mask adir -o v.txt
sed 's/material: grey}/texture: fifo.png}/' lens.yaml >fifo_texture.yaml
refused "fifo_texture.yaml" "fifo.png" -- "$G" render fifo_texture.yaml --setup -o t.tif
[ ! -e t.tif ] && [ ! -e t.png ] && [ ! -e corr ] || fail "a refused command wrote an output"

# --- 3. Integers beyond their type: refused naming the option, never wrapped or saturated.
refused "--shard" "4294967296" -- "$G" correct lens.yaml --camera small frame.tif -o corr --shard 4294967296/2
refused "--shard" -- "$G" correct lens.yaml --camera small frame.tif -o corr --shard 0/99999999999999999999
refused "--seed" "out of this option's range" -- "$G" render lens.yaml --sheet-pattern particles -o t.tif --seed 18446744073709551617
refused "--levels" "out of this option's range" -- "$G" align refine lens.yaml photo.png --levels 8,4294967304
refused "--seed" "out of this option's range" -- "$G" align sensitivity lens.yaml -o t.png --seed 4294967296
refused "--threads" -- "$G" render lens.yaml --setup -o t.tif --threads 4294967297
refused "--samples" -- "$G" render lens.yaml --setup -o t.tif --samples 4294967298
refused "--binning" -- "$G" render lens.yaml --setup -o t.tif --binning 18446744073709551616
[ ! -e t.tif ] && [ ! -e corr ] || fail "a refused command wrote an output"

# --- 4. Messages in glasspiv's words.
long=$(printf 'a%.0s' $(seq 300))
refused "-o" "255 bytes" -- "$G" render lens.yaml --setup -o "$long/x.tif"
refused "-o" "255 bytes" -- "$G" correct lens.yaml --camera small frame.tif -o "$long"
refused "-o" "255 bytes" -- "$G" simulate lens.yaml --flow uniform:0.1,0,0 -o "$long"
refused "-o" "255 bytes" -- "$G" demo -o "$long"
cat lens.yaml - >two.yaml <<'YAML'
  - name: side
    model: {image_size_px: [80, 60], lens_model: pinhole, focal_length_px: [200, 200], principal_point_px: [39.5, 29.5]}
    pose: {position_mm: [200, 0, -450], look_at_mm: [0, 0, 40], up: [0, 1, 0]}
YAML
refused "--camera" "'side' is given twice" -- "$G" coverage two.yaml --camera side --camera side -o c.png
printf '{\n  "covariance": [[1, 0, 0, 0, 0, NaN]]\n}\n' >nan.json
refused "nan.json" "covariance[0][5]" "line 2" "NaN" -- "$G" align sensitivity lens.yaml -o t.png --pose-json nan.json
printf '{"covariance": [[1, 2' >cut.json
refused "cut.json" "ends early" -- "$G" align sensitivity lens.yaml -o t.png --pose-json cut.json
no_temporaries
echo "all checks passed"
