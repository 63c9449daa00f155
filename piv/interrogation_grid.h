#pragma once
// The interrogation grid of one PIV pass: square windows of window_px, their
// centres step_px apart, in glasspiv's pixel convention (docs/conventions.md):
// (0, 0) is the centre of the top-left pixel, x right (columns), y down (rows).
//
// Worked example (as OpenPIV's grid.h): a 1024 x 768 px image, 32 px windows,
// 50 % overlap -> step 16 px. Along x: (1024 - 32) / 16 + 1 = 63 columns of
// windows; the first covers pixels 0..31, so its centre is at x = 15.5 px, the
// last covers 992..1023, centre 1007.5 px. Along y: (768 - 32) / 16 + 1 = 47
// rows, centres 15.5 .. 751.5 px. When the windows do not tile the image
// exactly the leftover pixels are split, the smaller half before the first
// window: a 1000 px side with 32 px windows and step 16 gives 61 windows
// covering 992 px, 8 px over, 4 before -> first centre at 4 + 15.5 = 19.5 px.
// No I/O.

namespace glasspiv {

struct InterrogationGrid {
  int window_px = 0;  // side of the square window
  int step_px = 0;    // distance between neighbouring window centres
  int cols = 0, rows = 0;
  int left0_px = 0, top0_px = 0;  // first pixel column / row of window (0, 0)

  int size() const { return cols * rows; }
  int index(int col, int row) const { return row * cols + col; }
  // First pixel column / row covered by a window.
  int left_px(int col) const { return left0_px + col * step_px; }
  int top_px(int row) const { return top0_px + row * step_px; }
  // Window centres: the mean of the covered pixel centres.
  double x_px(int col) const { return left_px(col) + 0.5 * (window_px - 1); }
  double y_px(int row) const { return top_px(row) + 0.5 * (window_px - 1); }
};

// step = round(window_px * (1 - overlap)), at least 1 px. overlap in [0, 1).
// Throws std::invalid_argument outside that range or for window_px < 1.
int step_from_overlap(int window_px, double overlap);

// Every window of window_px that fits inside width_px x height_px, centres
// step_px apart, the grid centred as above. Throws std::invalid_argument when
// window_px < 1, step_px < 1 or the window is larger than the image.
InterrogationGrid interrogation_grid(int width_px, int height_px, int window_px, int step_px);

}  // namespace glasspiv
