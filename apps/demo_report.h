#pragma once
// The demo's one page: every step's key figures against the truth, the
// pictures a user would rather look at than read (calibration residuals and
// uncertainty, the overlay before and after the alignment, distorted and
// corrected frames, the PIV error maps, the masks with one camera and five),
// links to each step's own page, and one metrics.json with all the figures.
#include <string>

#include "apps/demo_alignment.h"
#include "apps/demo_calibration.h"
#include "apps/demo_correction.h"
#include "apps/demo_piv.h"
#include "apps/demo_render.h"

namespace glasspiv {

// The steps' results (all must be set), as run_demo collects them.
struct DemoSession {
  double formats_worst_px = 0;  // step 1: the four formats' largest difference
  const DemoCalibrationSummary* calibration = nullptr;          // step 4
  const DemoRenderSummary* render = nullptr;                    // step 5
  const DemoCorrectionSummary* correction = nullptr;            // step 6
  const DemoCalibrationSummary* reactor_calibration = nullptr;  // step 7
  const DemoAlignmentSummary* alignment = nullptr;              // step 8
  const DemoPivSummary* piv = nullptr;                          // step 9
  int binning = 1;
  double seconds = 0;
};

struct DemoReportFiles {
  std::string html, metrics_json;
};

// Writes index.html and metrics.json into out_dir (atomically); the steps'
// files are referred to relative to it.
DemoReportFiles write_demo_report(const std::string& out_dir, const DemoSession& session);

}  // namespace glasspiv
