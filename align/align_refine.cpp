#include "align/align_refine.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <variant>

#include <ceres/ceres.h>
#include <opencv2/imgproc.hpp>

#include "align/refraction_pose.h"
#include "calib/fit/ceres_logging.h"
#include "render/scene.h"
#include "render/scene_index.h"
#include "util/stopwatch.h"

namespace glasspiv {
namespace {

constexpr double kMinFocalScale = 0.1;  // a focal length optimised down to a tenth is no result

// Parameter vector: camera perturbation (rotation 3 rad, translation 3 mm, both
// in the camera frame: camera_from_world = delta * start), then the optional
// focal scale offset, index offset, glass offset (3 mm).
struct Layout {
  bool focal, index, glass;
  int size() const { return 6 + focal + index + 3 * glass; }
};

struct Model {
  RigidTransform camera_from_world;
  double focal_scale = 1, index_offset = 0;
  Eigen::Vector3d glass_offset_mm = Eigen::Vector3d::Zero();
};

Model model_of(const double* p, const Layout& layout, const RigidTransform& start) {
  Model m;
  const RigidTransform delta = RigidTransform::from_rvec_tvec(Eigen::Vector3d(p[0], p[1], p[2]),
                                                              Eigen::Vector3d(p[3], p[4], p[5]));
  m.camera_from_world = delta * start;
  int k = 6;
  if (layout.focal) m.focal_scale = 1 + p[k++];
  if (layout.index) m.index_offset = p[k++];
  if (layout.glass) m.glass_offset_mm = Eigen::Vector3d(p[k], p[k + 1], p[k + 2]);
  return m;
}

// Zero mean, unit variance over the compared pixels; the rest zero.
cv::Mat normalised(const cv::Mat& feature, const cv::Mat& valid) {
  cv::Scalar mean, stddev;
  cv::meanStdDev(feature, mean, stddev, valid);
  cv::Mat out = (feature - mean[0]) / std::max(stddev[0], 1e-12);
  out.setTo(0, valid == 0);
  return out;
}

// What a level compares: the blurred image itself (coarse levels: a wide basin
// of attraction, blobs rather than edges) or its blurred gradient magnitude
// (fine levels: edges, whatever the lighting).
cv::Mat feature_of(const cv::Mat& image, double blur_px, bool intensity) {
  if (!intensity) return blurred_gradient_magnitude(image, blur_px);
  cv::Mat out;
  cv::GaussianBlur(image, out, cv::Size(), blur_px, blur_px, cv::BORDER_REPLICATE);
  return out;
}

// The distance that converts a third of a pixel into mm: the median distance
// from the camera to the solids in front of it (the setup it sees; the sheet
// is not needed for alignment), else 1 m.
double typical_distance_mm(const TraceScene& scene, const RigidTransform& camera_from_world) {
  std::vector<double> depths;
  for (const TraceSolid& solid : scene.solids)
    std::visit(
        [&](const auto& shape) {
          using T = std::decay_t<decltype(shape)>;
          if constexpr (!std::is_same_v<T, TriangleMesh>) {
            const double z = camera_from_world.apply(shape.centre_mm).z();
            if (z > 0) depths.push_back(z);
          }
        },
        solid.shape);
  if (depths.empty()) return 1000;
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  return std::max(1.0, depths[depths.size() / 2]);
}

// Samples per pixel and axis at binning b: as asked, or (0) as many as make a
// binned pixel average its area like the binned photo does, at most 4.
int level_samples(const RefineOptions& options, int b) {
  return options.samples_per_axis > 0 ? options.samples_per_axis : std::clamp(b, 1, 4);
}

// One level of the pyramid: the binned photo's features and what renders it.
class LevelProblem : public ceres::CostFunction {
 public:
  LevelProblem(const TraceScene& scene, const SceneIndex& index, const SetupLook& look, const CameraModel& camera,
               const RigidTransform& start, const cv::Mat& photo_features, const cv::Mat& valid, const Layout& layout,
               const RefineOptions& options, bool intensity, double distance_mm, int binning,
               const std::vector<RefineCorner>& corners, int* renders)
      : scene_(scene), index_(index), look_(look), camera_(camera), start_(start), photo_(photo_features),
        valid_(valid), layout_(layout), options_(options), intensity_(intensity), binning_(binning),
        corners_(corners), renders_(renders), samples_(level_samples(options, binning)) {
    for (int r = 0; r < valid.rows; ++r)
      for (int c = 0; c < valid.cols; ++c)
        if (valid.at<unsigned char>(r, c)) pixels_.push_back(r * valid.cols + c);
    // One measurement per blur footprint, of feature_sigma each.
    const double footprint_px = M_PI * std::pow(2 * std::max(options.blur_px, 0.5), 2);
    picture_weight_ = std::sqrt(1.0 / footprint_px) / options.feature_sigma;
    set_num_residuals(static_cast<int>(pixels_.size() + 2 * corners.size()));
    mutable_parameter_block_sizes()->push_back(layout.size());
    // Steps that move the picture by a third of a pixel of this level.
    const double f = camera.fx_px(), third_px = 1.0 / 3.0;
    const double half_diagonal_px = 0.5 * std::hypot(camera.width_px(), camera.height_px());
    steps_.assign(static_cast<std::size_t>(layout.size()), 0);
    for (int i = 0; i < 3; ++i) steps_[i] = third_px / f;
    for (int i = 3; i < 6; ++i) steps_[i] = third_px * distance_mm / f;
    int k = 6;
    if (layout.focal) steps_[k++] = third_px / half_diagonal_px;
    if (layout.index) steps_[k++] = 2e-3;
    if (layout.glass)
      for (int i = 0; i < 3; ++i) steps_[k++] = third_px * distance_mm / f;
  }

  // Weighs the picture by its residual as measured at p (at least
  // feature_sigma): a model that cannot match the photo closely (images behind
  // spheres aliased, lighting not modelled) counts for less against the
  // corners. Returns that RMS (feature units). One render.
  double weigh_picture_at(const double* p) {
    const double footprint_px = M_PI * std::pow(2 * std::max(options_.blur_px, 0.5), 2);
    picture_weight_ = 1;
    std::vector<double> r(static_cast<std::size_t>(num_residuals()));
    residuals(p, r.data());
    double sum2 = 0;
    for (std::size_t i = 0; i < pixels_.size(); ++i) sum2 += r[i] * r[i];
    const double rms = pixels_.empty() ? 0 : std::sqrt(sum2 / static_cast<double>(pixels_.size()));
    picture_weight_ = std::sqrt(1.0 / footprint_px) / std::max(options_.feature_sigma, rms);
    return rms;
  }

  // The objective at p, 1/2 the sum of the squared residuals, with the
  // picture's present weight. One render.
  double cost_at(const double* p) const {
    std::vector<double> r(static_cast<std::size_t>(num_residuals()));
    residuals(p, r.data());
    double sum2 = 0;
    for (double x : r) sum2 += x * x;
    return 0.5 * sum2;
  }

  // The residuals at p: normalised photo features minus normalised render features.
  bool residuals(const double* p, double* out) const {
    const Model m = model_of(p, layout_, start_);
    const bool glass_moves = layout_.index || layout_.glass;
    std::unique_ptr<SceneIndex> own_index;
    TraceScene adjusted;
    const TraceScene* scene = &scene_;
    const SceneIndex* index = &index_;
    if (glass_moves && (m.index_offset != 0 || m.glass_offset_mm != Eigen::Vector3d::Zero())) {
      adjusted = adjusted_glass(scene_, m.index_offset, m.glass_offset_mm);
      own_index = make_scene_index(adjusted);
      scene = &adjusted;
      index = own_index.get();
    }
    const CameraModel model = m.focal_scale == 1 ? camera_ : scaled_focal(camera_, m.focal_scale);
    std::vector<float> radiance = render_setup(*scene, *index, look_, model, m.camera_from_world,
                                                          options_.trace, samples_, options_.threads);
    ++*renders_;
    cv::Mat render(camera_.height_px(), camera_.width_px(), CV_32F, radiance.data());
    const cv::Mat features = normalised(feature_of(render, options_.blur_px, intensity_), valid_);
    const float* a = photo_.ptr<float>(0);
    const float* b = features.ptr<float>(0);
    for (std::size_t i = 0; i < pixels_.size(); ++i) out[i] = picture_weight_ * (a[pixels_[i]] - b[pixels_[i]]);
    double* corner_out = out + pixels_.size();
    lost_ = 0;
    for (std::size_t i = 0; i < corners_.size(); ++i) {
      const Eigen::Vector2d px = corner_residual_px(*scene, *index, model, m.camera_from_world, corners_[i]);
      corner_out[2 * i] = px.x() / options_.corner_sigma_px;
      corner_out[2 * i + 1] = px.y() / options_.corner_sigma_px;
    }
    if (options_.progress) options_.progress(0, *renders_);
    return true;
  }

  // Full-resolution px; a corner without a traced image counts as a fixed
  // miss (zero: it neither pulls nor breaks the solve) and is counted.
  Eigen::Vector2d corner_residual_px(const TraceScene& scene, const SceneIndex& index, const CameraModel& model,
                                     const RigidTransform& camera_from_world, const RefineCorner& c) const {
    const double b = binning_;
    const auto start = model.project(camera_from_world.apply(c.world_mm));
    if (!start) {
      ++lost_;
      return Eigen::Vector2d::Zero();
    }
    TracedProjectionOptions traced;
    const TracedProjection t = project_through_scene(scene, index, model, camera_from_world, c.world_mm, c.solid,
                                                     *start, traced);
    if (!t.ok()) {
      ++lost_;
      return Eigen::Vector2d::Zero();
    }
    // Binned pixel p_b covers full-resolution (p_b + 0.5) b - 0.5.
    return (t.pixel_px.array() + 0.5) * b - 0.5 - c.pixel_px.array();
  }

  // RMS over the corners with an image, full-resolution px, at p.
  double corner_rms_px(const double* p, int* lost) const {
    const Model m = model_of(p, layout_, start_);
    const TraceScene adjusted = adjusted_glass(scene_, m.index_offset, m.glass_offset_mm);
    const std::unique_ptr<SceneIndex> index = make_scene_index(adjusted);
    const CameraModel model = m.focal_scale == 1 ? camera_ : scaled_focal(camera_, m.focal_scale);
    lost_ = 0;
    double sum2 = 0;
    for (const RefineCorner& c : corners_) sum2 += corner_residual_px(adjusted, *index, model, m.camera_from_world, c).squaredNorm();
    *lost = lost_;
    const int n = static_cast<int>(corners_.size()) - lost_;
    return n > 0 ? std::sqrt(sum2 / n) : 0;
  }

  bool Evaluate(double const* const* parameters, double* residual, double** jacobians) const override {
    const int n = layout_.size(), m = num_residuals();
    if (!residuals(parameters[0], residual)) return false;
    if (!jacobians || !jacobians[0]) return true;
    std::vector<double> p(parameters[0], parameters[0] + n), plus(static_cast<std::size_t>(m)),
        minus(static_cast<std::size_t>(m));
    for (int j = 0; j < n; ++j) {
      const double h = steps_[static_cast<std::size_t>(j)];
      p[j] = parameters[0][j] + h;
      residuals(p.data(), plus.data());
      p[j] = parameters[0][j] - h;
      residuals(p.data(), minus.data());
      p[j] = parameters[0][j];
      for (int i = 0; i < m; ++i) jacobians[0][static_cast<std::size_t>(i) * n + j] = (plus[i] - minus[i]) / (2 * h);
    }
    return true;
  }

 private:
  const TraceScene& scene_;
  const SceneIndex& index_;
  const SetupLook& look_;
  const CameraModel& camera_;
  RigidTransform start_;
  cv::Mat photo_, valid_;
  Layout layout_;
  const RefineOptions& options_;
  bool intensity_;
  int binning_;
  const std::vector<RefineCorner>& corners_;
  int* renders_;
  int samples_;
  double picture_weight_ = 1;
  mutable int lost_ = 0;
  std::vector<int> pixels_;
  std::vector<double> steps_;
};

// The photo binned like binned(camera, b): b x b blocks averaged, the ragged
// right and bottom edge dropped.
cv::Mat binned_photo(const cv::Mat& photo, int b, int width, int height) {
  if (b == 1) return photo;
  cv::Mat out;
  cv::resize(photo(cv::Rect(0, 0, width * b, height * b)), out, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  return out;
}

}  // namespace

std::vector<RefineCorner> refine_corners(const std::vector<FiducialCorner>& corners,
                                         const std::vector<SceneFiducial>& fiducials,
                                         const std::vector<int>& rectangle_solids) {
  std::vector<RefineCorner> out;
  for (const FiducialCorner& c : corners) {
    const SceneFiducial& f = fiducials.at(static_cast<std::size_t>(c.fiducial));
    out.push_back({c.world_mm, rectangle_solids.at(static_cast<std::size_t>(f.rectangle)), c.pixel_px});
  }
  return out;
}

RefineResult refine_alignment(const TraceScene& scene, const SetupLook& look, const CameraModel& camera,
                              const RigidTransform& start_camera_from_world, const cv::Mat& photo32f,
                              const RefineParameters& parameters, const RefineOptions& options,
                              const std::vector<RefineCorner>& corners) {
  if (photo32f.type() != CV_32FC1 || photo32f.cols != camera.width_px() || photo32f.rows != camera.height_px())
    throw std::invalid_argument("refine_alignment: the photo must be CV_32FC1 of the camera's size");
  if (options.binning_levels.empty()) throw std::invalid_argument("refine_alignment: no binning levels");
  silence_ceres_logging();
  const Stopwatch total;
  const Layout layout{parameters.focal, parameters.refractive_index, parameters.glass_position};
  const std::unique_ptr<SceneIndex> index = make_scene_index(scene);
  const double distance_mm = typical_distance_mm(scene, start_camera_from_world);
  std::vector<double> p(static_cast<std::size_t>(layout.size()), 0.0);
  std::pair<double, double> glass_index_range{kMaxRefractiveIndex, kMinRefractiveIndex};
  for (const TraceSolid& solid : scene.solids)
    if (solid.material.kind == TraceMaterial::Kind::glass) {
      glass_index_range.first = std::min(glass_index_range.first, solid.material.refractive_index);
      glass_index_range.second = std::max(glass_index_range.second, solid.material.refractive_index);
    }
  RefineResult result;
  for (const int& b : options.binning_levels) {
    if (b < 1) throw std::invalid_argument("refine_alignment: binning levels must be >= 1");
    const Stopwatch level_time;
    const CameraModel level_camera = binned(camera, b);
    const cv::Mat photo = binned_photo(photo32f, b, level_camera.width_px(), level_camera.height_px());
    SimilarityOptions similarity;
    similarity.edge_blur_px = options.blur_px;
    const PhotoEdgeModel photo_model(photo, similarity);
    const bool intensity = b >= options.intensity_from_binning;
    const cv::Mat features = normalised(feature_of(photo, options.blur_px, intensity), photo_model.valid_mask());
    int renders = 0;
    auto* cost = new LevelProblem(scene, *index, look, level_camera, start_camera_from_world, features,
                                  photo_model.valid_mask(), layout, options, intensity, distance_mm, b, corners, &renders);
    RefineLevel level;
    level.binning = b;
    level.width_px = level_camera.width_px();
    level.height_px = level_camera.height_px();
    const auto ncc_at = [&](const std::vector<double>& q) {
      const Model m = model_of(q.data(), layout, start_camera_from_world);
      const TraceScene adjusted = adjusted_glass(scene, m.index_offset, m.glass_offset_mm);
      std::vector<float> radiance = render_setup(adjusted, look, scaled_focal(level_camera, m.focal_scale),
                                                 m.camera_from_world, options.trace, level_samples(options, b),
                                                 options.threads);
      return photo_model.compare(cv::Mat(level_camera.height_px(), level_camera.width_px(), CV_32F, radiance.data()))
          .gradient_ncc;
    };
    level.gradient_ncc_before = ncc_at(p);
    // The finest level also scores the start, to judge the whole refinement by.
    const bool last = &b == &options.binning_levels.back();
    const std::vector<double> start(p.size(), 0.0);
    if (last) {
      result.score_start = ncc_at(start);
      if (!corners.empty()) result.corner_rms_start_px = cost->corner_rms_px(start.data(), &result.corners_lost_start);
    }
    if (!corners.empty()) level.picture_rms_before = cost->weigh_picture_at(p.data());
    ceres::Problem problem;
    problem.AddResidualBlock(cost, nullptr, p.data());
    // The model stays one the tracer may trace: a positive focal length, every
    // glass index within the scene's limits (the optics need n > 0).
    int k = 6;
    if (layout.focal) problem.SetParameterLowerBound(p.data(), k++, kMinFocalScale - 1);
    if (layout.index) {
      problem.SetParameterLowerBound(p.data(), k, kMinRefractiveIndex - glass_index_range.first);
      problem.SetParameterUpperBound(p.data(), k, kMaxRefractiveIndex - glass_index_range.second);
    }
    ceres::Solver::Options solver;
    solver.linear_solver_type = ceres::DENSE_QR;
    solver.max_num_iterations = options.max_iterations;
    solver.function_tolerance = 1e-8;
    solver.parameter_tolerance = 1e-9;
    solver.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    level.iterations = static_cast<int>(summary.iterations.size()) - 1;
    if (last) {  // the finest level's objective, one weighting, at the start and at the result
      result.objective_start = cost->cost_at(start.data());
      result.objective_end = cost->cost_at(p.data());
    }
    result.successful_steps += summary.num_successful_steps;
    level.gradient_ncc_after = ncc_at(p);
    if (!corners.empty()) level.corner_rms_px_after = cost->corner_rms_px(p.data(), &level.corners_lost);
    level.renders = renders + 2 + (last ? 1 : 0);
    level.seconds = level_time.seconds();
    result.renders += level.renders;
    result.levels.push_back(level);
  }
  const Model m = model_of(p.data(), layout, start_camera_from_world);
  result.camera_from_world = m.camera_from_world;
  result.focal_scale = m.focal_scale;
  result.refractive_index_offset = m.index_offset;
  result.glass_offset_mm = m.glass_offset_mm;
  result.score_end = result.levels.back().gradient_ncc_after;
  result.corner_rms_end_px = result.levels.back().corner_rms_px_after;
  result.corners_lost_end = result.levels.back().corners_lost;
  // Judged at the finest level by the objective, one weighting at the start and
  // the result (with corners the picture may give up a little of its score for
  // them); a corner that loses its image counts as a miss of zero there, so
  // losing corners is worse in itself, and without corners so is a lower score.
  const bool worse = !(result.objective_end <= result.objective_start) ||
                     result.corners_lost_end > result.corners_lost_start ||
                     (corners.empty() && !(result.score_end >= result.score_start));
  if (result.successful_steps == 0 || result.objective_end == result.objective_start)
    result.status = RefineStatus::no_step;
  else if (worse)
    result.status = RefineStatus::worse;
  result.seconds = total.seconds();
  return result;
}

}  // namespace glasspiv
