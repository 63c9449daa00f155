#include "render/setup_render.h"

#include <stdexcept>

#include "render/parallel_rows.h"
#include "render/row_camera_rays.h"
#include "render/trace_scene_builder.h"

namespace glasspiv {

namespace {

double opaque_radiance(const TraceScene& scene, const SetupLook& look, const OpaqueHit& hit) {
  const auto index = static_cast<std::size_t>(hit.solid_index);
  double texture = 1;
  if (index < look.textures.size() && look.textures[index]) {
    if (const auto* rect = std::get_if<Rectangle>(&scene.solids[index].shape)) {
      const Eigen::Vector3d rel = hit.point_mm - rect->centre_mm;
      texture = look.textures[index]->at(rel.dot(rect->right), rel.dot(rect->up));
    }
  }
  return look.ambient * scene.solids[index].material.albedo * texture;
}

}  // namespace

std::vector<float> render_setup(const TraceScene& scene, const SetupLook& look, const CameraModel& camera,
                                const RigidTransform& camera_from_world, const TraceOptions& options,
                                int samples_per_axis, int threads, const std::function<void(int, int)>& progress,
                                SetupRenderStats* stats) {
  const std::unique_ptr<SceneIndex> index = make_scene_index(scene);
  return render_setup(scene, *index, look, camera, camera_from_world, options, samples_per_axis, threads, progress,
                      stats);
}

std::vector<float> render_setup(const TraceScene& scene, const SceneIndex& index, const SetupLook& look,
                                const CameraModel& camera, const RigidTransform& camera_from_world,
                                const TraceOptions& options, int samples_per_axis, int threads,
                                const std::function<void(int, int)>& progress, SetupRenderStats* stats) {
  if (samples_per_axis < 1) throw std::invalid_argument("render_setup: samples_per_axis must be >= 1");
  const int width = camera.width_px(), height = camera.height_px();
  const int k = samples_per_axis;
  std::vector<float> image(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 0.0f);
  std::vector<SetupRenderStats> row_stats(static_cast<std::size_t>(height));
  const int used = parallel_rows(
      height, threads,
      [&](int row) {
        thread_local TraceResult r;
        SetupRenderStats& st = row_stats[static_cast<std::size_t>(row)];
        RowCameraRays rays(camera, camera_from_world, row, k);
        for (int col = 0; col < width; ++col) {
          double sum = 0;
          for (int sy = 0; sy < k; ++sy) {
            for (int sx = 0; sx < k; ++sx) {
              const std::optional<CameraRay>& ray = rays.next();
              if (!ray) {
                ++st.unproject_failures;
                continue;
              }
              trace_ray(scene, index, *ray, options, &r);
              ++st.camera_rays;
              st.branches_traced += r.counts.branches_traced;
              st.closed_form_rays += r.counts.closed_form;
              sum += r.background_weight * look.background_radiance;
              for (const OpaqueHit& h : r.opaque_hits) sum += h.weight * opaque_radiance(scene, look, h);
            }
          }
          image[static_cast<std::size_t>(row) * width + col] = static_cast<float>(sum / (k * k));
        }
      },
      progress);
  if (stats) {
    *stats = SetupRenderStats{};
    for (const SetupRenderStats& st : row_stats) {
      stats->camera_rays += st.camera_rays;
      stats->branches_traced += st.branches_traced;
      stats->unproject_failures += st.unproject_failures;
      stats->closed_form_rays += st.closed_form_rays;
    }
    stats->threads = used;
  }
  return image;
}

}  // namespace glasspiv
