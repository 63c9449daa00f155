#!/usr/bin/env bash
# Command-line checks of `glasspiv target print | show` and `glasspiv calib detect`.
# usage: target_cli_test.sh GLASSPIV SOURCE_DIR
set -u
G=$1
D=$2/data/targets
src=$(cd "$2" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1

source "$src/tests/cli_checks.sh"

# --- target show
expect 0 "$G" target show "$D/charuco_11x8_15mm.yaml"
has out.txt "70 corners: a 10 x 7 grid, 15 mm apart"
has out.txt "44 markers, ids 0 to 43"
has out.txt "top-left square black"
expect 0 "$G" target show "$D/aprilgrid_6x6.yaml"
has out.txt "144 corners: 4 per tag"
expect 0 "$G" target show "$D/chessboard_9x6.yaml"
has out.txt "pattern 225 x 150 mm"

# --- single markers: show, print with the caption
printf 'glasspiv_target: 1\nkind: aruco_marker\ndictionary: DICT_4X4_50\nmarker_id: 7\nmarker_size_mm: 30\n' >m.yaml
expect 0 "$G" target show m.yaml
has out.txt "4 corners: ids 0 to 3"
has out.txt "marker 7 of DICT_4X4_50"
expect 0 "$G" target print m.yaml -o m.svg --png m.png --dpi 300
has m.svg "ArUco marker DICT_4X4_50 id 7, marker 30 mm"
[ -s m.png ] || fail "no m.png"
printf 'glasspiv_target: 1\nkind: apriltag\ndictionary: tag36h11\ntag_id: 3\ntag_size_mm: 40\n' >t.yaml
expect 0 "$G" target print t.yaml -o t.svg
has t.svg "AprilTag tag36h11 id 3, tag size 40 mm"
printf 'glasspiv_target: 1\nkind: apriltag\ndictionary: tag36h11\ntag_id: 587\ntag_size_mm: 40\n' >bad_tag.yaml
expect 2 "$G" target show bad_tag.yaml
has err.txt "bad_tag.yaml: field 'tag_id'"

# --- target print
expect 0 "$G" target print "$D/charuco_11x8_15mm.yaml" -o board.svg --png board.png --dpi 150
has board.svg 'width="180mm" height="159.5mm" viewBox="0 0 180 159.5"'
has board.svg "print at 100% scale; check: this bar is 100 mm"
[ -s board.png ] || fail "no board.png"
expect 0 "$G" target print --help
has out.txt "SVG or PDF"
# PDF: the SVG's page (180 x 159.5 mm = 510.236220 x 452.125984 pt); its scale
# and marks are checked by targets_pdf_test (rendered back by poppler).
expect 0 "$G" target print "$D/charuco_11x8_15mm.yaml" -o board.pdf --png board2.png
has out.txt "wrote board.pdf: 180.0 x 159.5 mm page"
head -c 5 board.pdf | grep -q '%PDF-' || fail "board.pdf is not a PDF"
grep -aq 'MediaBox \[ 0 0 510.23622 452.12598' board.pdf || fail "board.pdf: wrong page size"
[ -s board2.png ] || fail "no board2.png beside the PDF"
expect 2 "$G" target print "$D/charuco_11x8_15mm.yaml" -o board.eps
has err.txt "must end in .svg or .pdf"
expect 2 "$G" target print "$D/charuco_11x8_15mm.yaml"
expect 2 "$G" target print "$D/charuco_11x8_15mm.yaml" --png p.png --dpi 0
has err.txt "--dpi"
# A failed print leaves nothing: the SVG is not written when the PNG cannot be made,
# and an earlier SVG of that name is not replaced.
sed 's/square_size_mm: 25/square_size_mm: 60/' "$D/chessboard_9x6.yaml" >big.yaml
expect 2 "$G" target print big.yaml -o big.svg --png big.png --dpi 2400
has err.txt "megapixels"
[ ! -e big.svg ] && [ ! -e big.png ] || fail "a failed target print left big.svg or big.png"
echo "earlier" >big.svg
expect 2 "$G" target print big.yaml -o big.svg --png big.png --dpi 2400
[ "$(cat big.svg)" = "earlier" ] || fail "a failed target print replaced big.svg"
ls -a | grep -q '\.tmp' && fail "a failed target print left a temporary file"
# Outputs: never the spec, never a link, never twice the same file.
ln -s big.yaml link.svg
expect 2 "$G" target print big.yaml -o link.svg
has err.txt "never overwrites its inputs"
echo "keep" >other.txt
ln -s other.txt link2.svg
expect 2 "$G" target print "$D/chessboard_9x6.yaml" -o link2.svg
has err.txt "symbolic link"
[ -L link2.svg ] && [ "$(cat other.txt)" = "keep" ] || fail "target print replaced a symbolic link"

# --- a bad spec: one line naming the file and the field, status 2
printf 'glasspiv_target: 1\nkind: charuco\nsquares: [11, 8]\nsquare_size_mm: 15\nmarker_size_mm: 15\ndictionary: DICT_5X5_100\n' >bad.yaml
expect 2 "$G" target show bad.yaml
has err.txt "bad.yaml: field 'marker_size_mm'"
[ "$(wc -l <err.txt)" -eq 1 ] || fail "error is not one line"

# --- calib detect
expect 0 "$G" target print "$D/charuco_11x8_15mm.yaml" --png a.png --dpi 150
# c.png: the same picture with a byte after the PNG's end, a file of its own
# (an exact copy is refused below: one photo is one view).
cp a.png c.png
printf '\0' >>c.png
expect 0 "$G" calib detect a.png c.png --target "$D/charuco_11x8_15mm.yaml" -o obs.yaml --vnl corners.vnl \
  --overlay-dir overlays
has out.txt "a.png: 70 of 70 corners, 44 markers"
has out.txt "wrote obs.yaml: 140 corners in 2 of 2 images"
has obs.yaml "glasspiv_observations: 1"
has corners.vnl "# filename x y level"
[ "$(grep -c '^a.png ' corners.vnl)" -eq 70 ] || fail "corners.vnl: not 70 lines for a.png"
[ -s overlays/a_corners.png ] && [ -s overlays/c_corners.png ] || fail "overlays missing"
expect 0 "$G" calib detect a.png --target "$D/charuco_11x8_15mm.yaml" -o obs.json
has obs.json '"glasspiv_observations": 1'

# The same photo twice is one view, whichever way it is named: refused before any detection.
mkdir -p photos
cp a.png photos/a.png
cp a.png photos/copy.png
expect 2 "$G" calib detect photos --target "$D/charuco_11x8_15mm.yaml" -o obs_dup.yaml
has err.txt "photos/copy.png: has the same bytes as 'photos/a.png'"; one_line
rm photos/copy.png
expect 2 "$G" calib detect photos photos/a.png --target "$D/charuco_11x8_15mm.yaml" -o obs_dup.yaml
has err.txt "photos/a.png: is the same file as 'photos/a.png'"; one_line
ln -s photos/a.png link.png
expect 2 "$G" calib detect link.png photos --target "$D/charuco_11x8_15mm.yaml" -o obs_dup.yaml
has err.txt "is the same file as 'link.png'"; one_line
[ ! -e obs_dup.yaml ] || fail "a refused detection wrote obs_dup.yaml"

expect 0 "$G" target print "$D/charuco_11x8_15mm.yaml" --png small.png --dpi 100
expect 2 "$G" calib detect a.png small.png --target "$D/charuco_11x8_15mm.yaml" -o obs.yaml
has err.txt "small.png: field 'image size': is 709 x 532 px but 'a.png' is 1063 x 798 px"
echo "not an image" >corrupt.png
expect 2 "$G" calib detect a.png corrupt.png --target "$D/charuco_11x8_15mm.yaml" -o obs.yaml
has err.txt "corrupt.png: cannot be read as an image"
expect 2 "$G" calib detect a.png --target "$D/chessboard_9x6.yaml" -o obs.yaml
has err.txt "chessboard_9x6.yaml: the target"
has err.txt "was found in none of the 1 images"
expect 2 "$G" calib detect a.png --target "$D/aprilgrid_6x6.yaml" -o obs.yaml --vnl c.vnl
has err.txt "c.vnl: field '--vnl'"

# --- speckle plates: show, print (SVG, PDF, PNG); detection refuses them
S="$D/speckle_150x120_0.5mm.yaml"
expect 0 "$G" target show "$S"
has out.txt "dots of 0.5 mm, one in each cell of a 223 x 179 grid"
expect 0 "$G" target print "$S" -o plate.svg --png plate.png --dpi 300
has plate.svg "speckle plate 150 x 120 mm, dot diameter 0.5 mm, fill 0.4, seed 1"
has plate.svg "<circle cx="
[ -s plate.png ] || fail "no plate.png"
expect 0 "$G" target print "$S" -o plate.pdf
[ -s plate.pdf ] || fail "no plate.pdf"
expect 2 "$G" calib detect a.png --target "$S" -o obs.yaml
has err.txt "speckle_150x120_0.5mm.yaml: field 'kind': a speckle plate has no corners"
expect 2 "$G" calib intrinsics a.png --target "$S" -o cam.yaml
has err.txt "speckle_150x120_0.5mm.yaml: field 'kind': a speckle plate has no corners"
printf 'not read\n' >unread_obs.yaml
expect 2 "$G" calib next unread_obs.yaml --target "$S"
has err.txt "field 'kind': a speckle plate has no corners to detect, and calib next needs corners"
printf 'glasspiv_target: 1\nkind: speckle\nplate_size_mm: [50, 40]\ndot_diameter_mm: 1\nfill: 0.4\nseed: -1\n' >neg_seed.yaml
expect 2 "$G" target show neg_seed.yaml
has err.txt "neg_seed.yaml: field 'seed'"
echo "target CLI: all checks passed"
