#include "align/mapping_comparison.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "render/parallel_rows.h"
#include "render/trace_scene_builder.h"

namespace glasspiv {
namespace {

struct Point {
  bool ok = false;
  Eigen::Vector2d st = Eigen::Vector2d::Zero();
  Eigen::Matrix2d J = Eigen::Matrix2d::Zero();
  std::uint64_t path = 0;
  bool glass = false;
};

Point sheet_point(const MappingModel& m, const SceneIndex& index, const Eigen::Vector2d& pixel, TraceResult* r) {
  Point p;
  const std::optional<CameraRay> ray = pixel_camera_ray(m.camera, m.camera_from_world, pixel);
  if (!ray) return p;
  trace_ray(*m.scene, index, *ray, TraceOptions{false, 1e-4, 32}, r);
  for (const SheetCrossing& c : r->crossings) {
    if (c.subtree != -1) continue;
    p.ok = true;
    p.st = Eigen::Vector2d(c.s_mm, c.t_mm);
    p.J = c.dst_dpixel;
    p.path = c.path;
    p.glass = c.depth > 0;
    break;
  }
  return p;
}

MappingPercentiles percentiles(std::vector<double> px, const std::vector<double>& mm) {
  MappingPercentiles p;
  p.count = static_cast<int>(px.size());
  if (px.empty()) return p;
  double s = 0, smm = 0;
  for (double x : px) s += x * x;
  for (double x : mm) smm += x * x;
  p.rms_px = std::sqrt(s / static_cast<double>(px.size()));
  p.rms_mm = std::sqrt(smm / static_cast<double>(mm.size()));
  std::sort(px.begin(), px.end());
  p.p95_px = px[static_cast<std::size_t>(0.95 * static_cast<double>(px.size() - 1))];
  p.max_px = px.back();
  return p;
}

}  // namespace

MappingDifference compare_mappings(const MappingModel& reference, const MappingModel& other, int step_px,
                                   const Eigen::Vector2d& extent_mm, int threads) {
  const std::unique_ptr<SceneIndex> ia = make_scene_index(*reference.scene);
  const std::unique_ptr<SceneIndex> ib = make_scene_index(*other.scene);
  const int step = std::max(1, step_px);
  const int cols = reference.camera.width_px() / step, rows = reference.camera.height_px() / step;
  struct Row {
    std::vector<Eigen::Vector2d> pixels;
    std::vector<float> px, mm;
    std::vector<unsigned char> glass;
    int other_path = 0;
  };
  std::vector<Row> out(static_cast<std::size_t>(std::max(rows, 0)));
  auto inside = [&](const Eigen::Vector2d& st) {
    return std::abs(st.x()) <= 0.5 * extent_mm.x() && std::abs(st.y()) <= 0.5 * extent_mm.y();
  };
  parallel_rows(rows, threads, [&](int r) {
    thread_local TraceResult scratch;
    Row& row = out[static_cast<std::size_t>(r)];
    for (int c = 0; c < cols; ++c) {
      const Eigen::Vector2d pixel(c * step + 0.5 * (step - 1), r * step + 0.5 * (step - 1));
      const Point a = sheet_point(reference, *ia, pixel, &scratch);
      if (!a.ok || !inside(a.st)) continue;
      const Point b = sheet_point(other, *ib, pixel, &scratch);
      if (!b.ok || !inside(b.st)) continue;
      if (a.path != b.path) {
        ++row.other_path;
        continue;
      }
      const Eigen::Vector2d d = b.st - a.st;
      const double det = a.J.determinant();
      if (!(std::abs(det) > 0)) continue;
      row.pixels.push_back(pixel);
      row.mm.push_back(static_cast<float>(d.norm()));
      row.px.push_back(static_cast<float>((a.J.inverse() * d).norm()));
      row.glass.push_back(a.glass ? 1 : 0);
    }
  }, {});
  MappingDifference result;
  std::vector<double> gpx, gmm, dpx, dmm;
  for (const Row& row : out) {
    result.other_path += row.other_path;
    for (std::size_t i = 0; i < row.pixels.size(); ++i) {
      result.pixels.push_back(row.pixels[i]);
      result.error_px.push_back(row.px[i]);
      result.error_mm.push_back(row.mm[i]);
      result.through_glass.push_back(row.glass[i]);
      (row.glass[i] ? gpx : dpx).push_back(row.px[i]);
      (row.glass[i] ? gmm : dmm).push_back(row.mm[i]);
    }
  }
  result.glass = percentiles(gpx, gmm);
  result.direct = percentiles(dpx, dmm);
  return result;
}

}  // namespace glasspiv
