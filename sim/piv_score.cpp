#include "sim/piv_score.h"

#include <algorithm>

namespace glasspiv {
namespace {

bool usable_at(const cv::Mat& usable, double x_px, double y_px) {
  if (usable.empty()) return true;
  const int x = static_cast<int>(std::lround(x_px)), y = static_cast<int>(std::lround(y_px));
  return x >= 0 && y >= 0 && x < usable.cols && y < usable.rows && usable.at<std::uint8_t>(y, x) != 0;
}

// (ds, dt) in mm at sheet point (s, t), bilinear between the truth's cells;
// false off its grid or where a neighbouring cell has none (inside a solid).
bool sheet_truth_at(const SheetTruth& truth, double s_mm, double t_mm, double* ds_mm, double* dt_mm) {
  const SheetGrid& g = truth.grid;
  const double c = g.col(s_mm), r = g.row(t_mm);
  if (!(c >= 0 && r >= 0 && c <= g.cols - 1 && r <= g.rows - 1)) return false;
  const int c0 = std::min(static_cast<int>(c), std::max(g.cols - 2, 0));
  const int r0 = std::min(static_cast<int>(r), std::max(g.rows - 2, 0));
  const int c1 = std::min(c0 + 1, g.cols - 1), r1 = std::min(r0 + 1, g.rows - 1);
  const double fc = c - c0, fr = r - r0;
  double ds = 0, dt = 0;
  for (int k = 0; k < 4; ++k) {
    const int cc = k & 1 ? c1 : c0, rr = k & 2 ? r1 : r0;
    const double w = (k & 1 ? fc : 1 - fc) * (k & 2 ? fr : 1 - fr);
    const std::size_t i = static_cast<std::size_t>(rr) * g.cols + cc;
    if (!std::isfinite(truth.ds_mm[i]) || !std::isfinite(truth.dt_mm[i])) return false;
    ds += w * truth.ds_mm[i];
    dt += w * truth.dt_mm[i];
  }
  *ds_mm = ds;
  *dt_mm = dt;
  return true;
}

}  // namespace

std::vector<Eigen::Vector2d> camera_truth_on_vectors(const PivField& f, const CameraTruth& truth,
                                                     const cv::Mat& usable) {
  std::vector<Eigen::Vector2d> out(f.size(), Eigen::Vector2d::Constant(NAN));
  for (std::size_t i = 0; i < f.size() && i < truth.u_px.size(); ++i)
    if (usable_at(usable, f.x_px(i), f.y_px(i))) out[i] = Eigen::Vector2d(truth.u_px[i], truth.v_px[i]);
  return out;
}

std::vector<Eigen::Vector2d> sheet_truth_on_vectors(const PivField& f, const SheetGrid& grid, const SheetTruth& truth,
                                                    const cv::Mat& usable) {
  std::vector<Eigen::Vector2d> out(f.size(), Eigen::Vector2d::Constant(NAN));
  for (std::size_t i = 0; i < f.size(); ++i) {
    double ds = 0, dt = 0;
    if (usable_at(usable, f.x_px(i), f.y_px(i)) &&
        sheet_truth_at(truth, grid.s_mm(f.x_px(i)), grid.t_mm(f.y_px(i)), &ds, &dt))
      out[i] = Eigen::Vector2d(ds, -dt) / grid.mm_per_px;
  }
  return out;
}

PivScore score_vectors(const PivField& f, const std::vector<Eigen::Vector2d>& truth_px, GridValues* errors,
                       const std::vector<bool>* only, std::vector<bool>* scored, Eigen::Vector2d* mean_px) {
  PivScore s;
  Eigen::Vector2d measured = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> e(f.size(), Eigen::Vector2d::Constant(NAN));
  if (scored) scored->assign(f.size(), false);
  double sum = 0, top = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (f.flags[i] == VectorFlag::invalid || !truth_px[i].allFinite() || (only && !(*only)[i])) continue;
    e[i] = Eigen::Vector2d(f.u_px[i], f.v_px[i]) - truth_px[i];
    sum += e[i].squaredNorm();
    top = std::max(top, e[i].norm());
    measured += Eigen::Vector2d(f.u_px[i], f.v_px[i]);
    ++s.vectors;
    if (scored) (*scored)[i] = true;
  }
  if (mean_px) *mean_px = s.vectors ? Eigen::Vector2d(measured / s.vectors) : Eigen::Vector2d::Constant(NAN);
  if (s.vectors) {
    s.rms_px = std::sqrt(sum / s.vectors);
    s.max_px = top;
  }
  if (errors) {
    errors->vector_px = std::move(e);
    use_vector_cells(f.grid, errors);
  }
  return s;
}

void use_vector_cells(const InterrogationGrid& g, GridValues* errors) {
  errors->grid.cols = g.cols;
  errors->grid.rows = g.rows;
  errors->grid.step_x_px = g.cols > 1 ? g.x_px(1) - g.x_px(0) : 1;
  errors->grid.step_y_px = g.rows > 1 ? g.y_px(1) - g.y_px(0) : 1;
  errors->summarize();
}

}  // namespace glasspiv
