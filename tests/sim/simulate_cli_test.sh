#!/usr/bin/env bash
# Command-line checks of `glasspiv simulate`: help, refusals (nothing written), one small run.
# usage: simulate_cli_test.sh GLASSPIV SOURCE_DIR
set -u
G=$1
S=$2/data/scenes/flat_window.yaml
src=$(cd "$2" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1

source "$src/tests/cli_checks.sh"

# --- help
expect 0 "$G" simulate --help
has out.txt "--flow"
has out.txt "rotation:OMEGA"
has out.txt "--density-ppp"

# --- refusals: one line, exit 2, nothing written
expect 2 "$G" simulate "$S" --flow uniform:1,0,0 --density-ppp 0 --binning 8 -o bad
has err.txt "--density-ppp"; one_line; nothing_in bad
expect 2 "$G" simulate "$S" --flow swirl:1 --binning 8 -o bad
has err.txt "unknown flow 'swirl'"; one_line; nothing_in bad
expect 2 "$G" simulate "$S" --flow uniform:1,0 --binning 8 -o bad
has err.txt "takes 3"; one_line; nothing_in bad
expect 2 "$G" simulate "$S" --flow rotation:abc --binning 8 -o bad
has err.txt "not a finite number"; one_line; nothing_in bad
expect 2 "$G" simulate "$S" --flow uniform:1,0,0 --bit-depth 10 --binning 8 -o bad
has err.txt "--bit-depth"; one_line; nothing_in bad
expect 2 "$G" simulate "$S" --flow uniform:1,0,0 --camera nosuch --binning 8 -o bad
has err.txt "no camera 'nosuch'"; one_line; nothing_in bad
expect 2 "$G" simulate "$S" --flow vtk:missing.vti --binning 8 -o bad
has err.txt "missing.vti"; one_line; nothing_in bad
# A legacy VTK field (binary: big-endian doubles) with a NaN, and one that does not cover the sheet
# (file lengths in m: +-1 m covers the 200 mm sheet, +-10 mm does not).
vtk_field() {  # ORIGIN SPACING LAST_U_BYTES
  printf '# vtk DataFile Version 3.0\nfield\nBINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\nORIGIN %s %s %s\nSPACING %s %s %s\nPOINT_DATA 8\nVECTORS U double\n' "$1" "$1" "$1" "$2" "$2" "$2"
  for _ in $(seq 23); do printf '\0\0\0\0\0\0\0\0'; done
  printf "$3"
  printf '\n'
}
vtk_field -1 2 '\177\370\0\0\0\0\0\0' >nan.vtk
expect 2 "$G" simulate "$S" --flow vtk:nan.vtk --binning 8 -o bad
has err.txt "nan.vtk"; one_line; nothing_in bad
vtk_field -0.01 0.02 '\0\0\0\0\0\0\0\0' >small.vtk
expect 2 "$G" simulate "$S" --flow vtk:small.vtk --binning 8 -o bad
has err.txt "small.vtk"; one_line; nothing_in bad
# Damaged VTK files are refused from what they declare, one line and none of
# VTK's own report (no escape bytes), before VTK reads memory it never filled:
# a binary file cut short, an ASCII one a vector short, a literal nan, and 9 KB
# that declare 2.5e8 points (6 GB).
quiet_refusal() {  # FILE PHRASE
  expect 2 "$G" simulate "$S" --flow "vtk:$1" --binning 8 -o bad
  has err.txt "$1"; has err.txt "$2"; one_line; nothing_in bad
  if LC_ALL=C grep -q "$(printf '\033')" err.txt; then fail "escape bytes on stderr"; fi
}
vtk_field -1 2 '\0\0\0\0\0\0\0\0' | head -c 300 >cut.vtk
quiet_refusal cut.vtk "bytes are left"
ascii_field() {  # the header of an ASCII field of 2 x 2 x 2 points, then stdin as its data
  printf '# vtk DataFile Version 3.0\nfield\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\nORIGIN -1 -1 -1\nSPACING 2 2 2\nPOINT_DATA 8\nVECTORS U double\n'
  cat
}
printf '0 0 0\n%.0s' $(seq 7) | ascii_field >short_ascii.vtk
quiet_refusal short_ascii.vtk "ends after 21 of its 24 values"
{ printf '0 0 0\n%.0s' $(seq 7); printf '0 nan 0\n'; } | ascii_field >nan_ascii.vtk
quiet_refusal nan_ascii.vtk "not a finite number"
{ printf '# vtk DataFile Version 3.0\nhuge\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 250000000 float\n'; head -c 9000 /dev/zero; } >huge.vtk
quiet_refusal huge.vtk "over the limit"
{ printf '# vtk DataFile Version 3.0\nlarge\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 1000000 float\n'; head -c 9000 /dev/zero; } >large.vtk
quiet_refusal large.vtk "bytes are left"
# A pulse separation or a flow that carries tracers across the whole sheet names
# the option, not the scene.
expect 2 "$G" simulate "$S" --flow uniform:1,0,0 --dt-s 1e300 --binning 8 -o bad
has err.txt "--dt-s"; has err.txt "more than the sheet's extent"; one_line; nothing_in bad
expect 2 "$G" simulate "$S" --flow uniform:1e300,0,0 --binning 8 -o bad
has err.txt "--dt-s"; has err.txt "1e+300 m/s"; one_line; nothing_in bad
vtk_field -1 2 '\0\0\0\0\0\0\0\0' >still.vtk
expect 0 "$G" simulate "$S" --flow vtk:still.vtk --binning 8 -o still
[ -s still/metadata.json ] || fail "vtk:still.vtk wrote no metadata.json"

# --- one small run writes the files
expect 0 "$G" simulate "$S" --flow rotation:28 --binning 8 --seed 3 -o run
for f in cam0_A.tif cam0_B.tif cam0_A_ref.tif cam0_B_ref.tif cam0_truth_px.txt truth_sheet_mm.txt metadata.json; do
  [ -s "run/$f" ] || fail "run/$f missing"
done
has run/metadata.json '"seed": 3'
has run/metadata.json '"flow": "rotation:28"'
has run/cam0_truth_px.txt "# x_px y_px u_px v_px flag peak_ratio"
# The same seed gives the same frames.
expect 0 "$G" simulate "$S" --flow rotation:28 --binning 8 --seed 3 -o again
# (TIFFs carry their write time, so the frames are compared through what PIV makes of them.)
cmp -s run/cam0_truth_px.txt again/cam0_truth_px.txt || fail "the same seed gave another truth"
expect 0 "$G" piv run/cam0_A.tif run/cam0_B.tif -o run.txt
expect 0 "$G" piv again/cam0_A.tif again/cam0_B.tif -o again.txt
cmp -s <(grep -v "^#" run.txt) <(grep -v "^#" again.txt) || fail "the same seed gave other frames"
# PIV on the reference pair agrees with the truth (same grid, same columns).
expect 0 "$G" piv run/cam0_A_ref.tif run/cam0_B_ref.tif -o ref.txt --window 64,32,32
rms=$(paste <(grep -v '^#' ref.txt) <(grep -v '^#' run/cam0_truth_px.txt) |
  awk '$5 != 2 && $11 != 2 { s += ($3 - $9)^2 + ($4 - $10)^2; n++ } END { printf "%.4f", sqrt(s / n) }')
awk -v r="$rms" 'BEGIN { exit !(r < 0.1) }' || fail "PIV on the reference pair: RMS $rms px against the truth"
# The one-quarter rule: a warning, and the run still succeeds.
expect 0 "$G" simulate "$S" --flow uniform:8,0,0 --binning 8 -o fast
has err.txt "one-quarter rule"
has fast/metadata.json "one-quarter rule"
echo "simulate CLI checks passed"
