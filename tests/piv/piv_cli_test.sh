#!/usr/bin/env bash
# Command-line checks of `glasspiv piv`: a frame pair with a known shift, the
# file it writes, and its refusals (one line, exit status 2, nothing written).
# usage: piv_cli_test.sh GLASSPIV SOURCE_DIR
set -u
G=$1
src=$(cd "$2" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1

source "$src/tests/cli_checks.sh"

# frame W H DX DY: a 16-bit ASCII PGM of Gaussian particles (2.5 px, ~0.05
# per pixel) moved by (DX, DY) px, the same particles for the same seed.
frame() {
  awk -v W="$1" -v H="$2" -v DX="$3" -v DY="$4" 'BEGIN {
    srand(7); n = int(0.05 * (W + 32) * (H + 32));
    for (i = 0; i < n; i++) { px[i] = rand() * (W + 32) - 16 + DX; py[i] = rand() * (H + 32) - 16 + DY; }
    for (i = 0; i < n; i++)
      for (y = int(py[i]) - 3; y <= int(py[i]) + 3; y++)
        for (x = int(px[i]) - 3; x <= int(px[i]) + 3; x++)
          if (x >= 0 && y >= 0 && x < W && y < H) img[y * W + x] += exp(-8 * ((x - px[i]) ^ 2 + (y - py[i]) ^ 2) / 6.25);
    print "P2"; print W, H; print 65535;
    for (y = 0; y < H; y++) {
      line = "";
      for (x = 0; x < W; x++) { v = int(img[y * W + x] * 40000); if (v > 65535) v = 65535; line = line v " "; }
      print line;
    }
  }'
}
frame 128 96 0 0 >a.pgm
frame 128 96 3 -2 >b.pgm
frame 96 96 0 0 >small.pgm

# --- a pair moved by (+3, -2) px: u = +3, v = -2 (B relative to A, v along +y = down)
expect 0 "$G" piv a.pgm b.pgm -o v.txt --vtk v.vtk
has out.txt "7 x 5 vectors (window 32 px, step 16 px)"
has v.txt "# u_px v_px: displacement of frame B relative to frame A, u along +x, v along +y (px)"
has v.txt "# x_px y_px u_px v_px flag peak_ratio"
has v.txt "# passes: windows 64,32 px, overlap 0.5, deformation bspline5"
has v.vtk "DIMENSIONS 7 5 1"
awk '!/^#/ { n++; if ($5 != 0 || ($3 - 3) ^ 2 > 0.01 || ($4 + 2) ^ 2 > 0.01) bad++ }
     END { exit !(n == 35 && bad == 0) }' v.txt || fail "vectors differ from (3, -2): $(grep -v '^#' v.txt | head -3)"

# --- a mask (nonzero = usable): the left half masked gives flag 2 and nan there
awk 'BEGIN { print "P2"; print 128, 96; print 255;
  for (y = 0; y < 96; y++) { l = ""; for (x = 0; x < 128; x++) l = l (x < 64 ? 0 : 255) " "; print l } }' >mask.pgm
expect 0 "$G" piv a.pgm b.pgm --mask mask.pgm -o m.txt --window 32 --overlap 0.5
awk '!/^#/ { if ($1 < 63.5) { if ($5 != 2 || $3 != "nan") bad++ } else if ($5 == 2) bad++ } END { exit bad > 0 }' m.txt ||
  fail "mask not respected: $(grep -v '^#' m.txt | head -3)"

# --- a real recording (PIVlab's jet, 8-bit JPEG, data/piv_pairs): read, every
# vector written, the jet (leftwards, docs/piv.md) seen as negative u
jet="$src/data/piv_pairs/pivlab_jet"
expect 0 "$G" piv "$jet/Jet_0001A.jpg" "$jet/Jet_0001B.jpg" -o jet.txt
has out.txt "86 x 64 vectors (window 32 px, step 16 px)"
awk '!/^#/ { n++; if ($5 == 0 && $2 > 600 && $2 < 700 && $1 > 400 && $1 < 1200) { k++; su += $3 } }
     END { exit !(n == 5504 && k > 0 && su / k < -1) }' jet.txt || fail "jet vectors: $(grep -v '^#' jet.txt | head -3)"

# --- refusals: one line naming the file or the option, exit 2, nothing written
expect 2 "$G" piv a.pgm small.pgm -o r.txt
has err.txt "small.pgm: field 'image size'"
one_line
expect 2 "$G" piv a.pgm b.pgm --mask small.pgm -o r.txt
has err.txt "small.pgm: field 'image size'"
one_line
expect 2 "$G" piv a.pgm b.pgm -o r.txt --window 128,32
has err.txt "--window"
has err.txt "does not fit"
one_line
expect 2 "$G" piv a.pgm b.pgm -o r.txt --window 4
has err.txt "--window"
expect 2 "$G" piv a.pgm b.pgm -o r.txt --overlap 0.95
has err.txt "--overlap"
one_line
expect 2 "$G" piv a.pgm b.pgm -o r.txt --overlap -0.1
has err.txt "--overlap"
expect 2 "$G" piv a.pgm b.pgm -o r.txt --overlap nan
expect 2 "$G" piv a.pgm b.pgm -o r.txt --interpolation sinc
expect 2 "$G" piv a.pgm b.pgm -o r.txt --vtk r.vtu
has err.txt "--vtk"
expect 2 "$G" piv a.pgm b.pgm -o a.pgm
has err.txt "a.pgm"
printf 'not an image' >broken.tif
expect 2 "$G" piv a.pgm broken.tif -o r.txt
has err.txt "broken.tif"
one_line
[ ! -e r.txt ] && [ ! -e r.vtu ] || fail "a refused run wrote an output"
ls -a | grep -q '\.tmp-' && fail "a temporary was left"

# --- a failed write replaces nothing: an earlier vector file stays as it was
cp v.txt keep.txt
mkdir ro && cp v.txt ro/v.txt && chmod a-w ro
if [ "$(id -u)" -ne 0 ]; then
  expect 2 "$G" piv a.pgm b.pgm -o ro/v.txt
  cmp -s ro/v.txt keep.txt || fail "the earlier file was changed"
fi
chmod u+w ro
echo "piv_cli_test: all passed"
