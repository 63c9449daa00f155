#include "align/model_fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "align/model_adjustment.h"
#include "render/parallel_rows.h"
#include "render/trace_scene_builder.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

constexpr double kRadPerDeg = M_PI / 180.0;
constexpr int kGainTerms = 6;    // 1, x, y, x^2, x y, y^2
constexpr int kOffsetTerms = 3;  // 1, x, y
constexpr double kGradientStep = 0.25;  // of a footprint

enum class Kind { camera_rotation, camera_position, camera_focal, sheet_rotation, sheet_position, sphere_centre,
                  sphere_diameter, index, gain, offset };

struct Param {
  Kind kind;
  int view = -1;   // camera and photometric parameters
  int solid = -1;  // sphere parameters
  int axis = 0;
  double prior_sigma = 0;  // in the parameter's own unit (rad, mm, 1); 0: no prior (photometric)
  std::string name;
  double report_scale = 1;  // own unit -> reported unit (rad -> deg)
};

Eigen::Matrix3d rotation_of(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (a == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

// The model a parameter vector describes: deltas from the drawing for the
// geometry, absolute photometric coefficients.
struct Model {
  TraceScene scene;
  std::vector<RigidTransform> camera_from_world;
  std::vector<double> focal_scale;
};

// camera_of[v]: the photo whose camera parameters photo v shares (photos of one
// camera share its pose and focal length).
Model apply(const TraceScene& drawing, const std::vector<PlatePhoto>& photos, const std::vector<int>& camera_of,
            const std::vector<Param>& params, const Eigen::VectorXd& theta) {
  Model m;
  m.scene = drawing;
  const std::size_t views = photos.size();
  std::vector<Eigen::Vector3d> cam_w(views, Eigen::Vector3d::Zero()), cam_c(views, Eigen::Vector3d::Zero());
  m.focal_scale.assign(views, 1.0);
  Eigen::Vector3d sheet_w = Eigen::Vector3d::Zero(), sheet_p = Eigen::Vector3d::Zero();
  double index_offset = 0;
  for (std::size_t k = 0; k < params.size(); ++k) {
    const Param& p = params[k];
    const double v = theta[static_cast<Eigen::Index>(k)];
    switch (p.kind) {
      case Kind::camera_rotation: cam_w[static_cast<std::size_t>(p.view)][p.axis] = v; break;
      case Kind::camera_position: cam_c[static_cast<std::size_t>(p.view)][p.axis] = v; break;
      case Kind::camera_focal: m.focal_scale[static_cast<std::size_t>(p.view)] = 1 + v; break;
      case Kind::sheet_rotation: sheet_w[p.axis] = v; break;
      case Kind::sheet_position: sheet_p[p.axis] = v; break;
      case Kind::sphere_centre:
        std::get<Sphere>(m.scene.solids[static_cast<std::size_t>(p.solid)].shape).centre_mm[p.axis] += v;
        break;
      case Kind::sphere_diameter:
        std::get<Sphere>(m.scene.solids[static_cast<std::size_t>(p.solid)].shape).radius_mm += 0.5 * v;
        break;
      case Kind::index: index_offset = v; break;
      case Kind::gain:
      case Kind::offset: break;
    }
  }
  if (index_offset != 0)
    for (TraceSolid& s : m.scene.solids)
      if (s.material.kind == TraceMaterial::Kind::glass) s.material.refractive_index += index_offset;
  // Sheet: axes M = [s t n] turned about its own axes, moved along them.
  const SheetPlane& d = drawing.sheet;
  Eigen::Matrix3d axes;
  axes << d.s_axis, d.t_axis, d.normal();
  const Eigen::Matrix3d moved = axes * rotation_of(sheet_w);
  m.scene.sheet.origin_mm = d.origin_mm + axes * sheet_p;
  m.scene.sheet.s_axis = moved.col(0);
  m.scene.sheet.t_axis = moved.col(1);
  // Cameras: turned about their centre (camera frame), the centre moved (world).
  for (std::size_t v = 0; v < views; ++v) {
    const std::size_t cv = static_cast<std::size_t>(camera_of[v]);
    m.focal_scale[v] = m.focal_scale[cv];
    const RigidTransform& c0 = photos[v].camera_from_world;
    const Eigen::Vector3d centre = -c0.rotation.transpose() * c0.translation_mm + cam_c[cv];
    RigidTransform c;
    c.rotation = rotation_of(cam_w[cv]) * c0.rotation;
    c.translation_mm = -c.rotation * centre;
    m.camera_from_world.push_back(c);
  }
  return m;
}

// Where a traced pixel lands on the sheet, and what the prediction needs of it.
struct Landing {
  bool ok = false;
  Eigen::Vector2d st = Eigen::Vector2d::Zero();
  Eigen::Matrix2d J = Eigen::Matrix2d::Zero();
  double weight = 0;
  Eigen::Vector3d point = Eigen::Vector3d::Zero(), direction = Eigen::Vector3d::Zero();
  std::uint64_t path = 0;
  int first = -1;  // index of that crossing in the TraceResult
};

// The first sheet crossing of the pixel's refracted chain.
Landing land(const TraceScene& scene, const SceneIndex& index, const CameraModel& camera,
             const RigidTransform& camera_from_world, const Eigen::Vector2d& pixel, const TraceOptions& options,
             TraceResult* scratch, std::vector<int>* solids_met) {
  Landing l;
  const std::optional<CameraRay> ray = pixel_camera_ray(camera, camera_from_world, pixel);
  if (!ray) return l;
  trace_ray(scene, index, *ray, options, scratch);
  if (solids_met) {
    solids_met->clear();
    for (int s : scratch->solids_met)
      if (std::find(solids_met->begin(), solids_met->end(), s) == solids_met->end()) solids_met->push_back(s);
  }
  for (std::size_t i = 0; i < scratch->crossings.size(); ++i) {
    const SheetCrossing& c = scratch->crossings[i];
    if (c.subtree != -1) continue;
    l.ok = true;
    l.first = static_cast<int>(i);
    l.st = Eigen::Vector2d(c.s_mm, c.t_mm);
    l.J = c.dst_dpixel;
    l.weight = c.weight;
    l.point = c.point_mm;
    l.direction = c.direction;
    l.path = c.path;
    break;
  }
  return l;
}

// A pixel of a photo in use at this level: the mean of its k x k subsamples.
struct Sample {
  int view = 0;
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // the level's binned pixel
  double x = 0, y = 0;                              // position over the full image, [-1, 1]
  double value = 0;  // mean over the subsamples of w A + ghosts
  double photo = 0;
  int sub_begin = 0, sub_end = 0;  // into Evaluation::subs
};

// One subsample: its refracted chain's landing, the plate's picture A over its
// footprint (J / k) and A's gradient.
struct Sub {
  int sample = 0;
  int k = 1;  // the pixel's subsamples per axis (its footprint is J / k)
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  Landing landing;
  double picture = 0;
  Eigen::Vector2d grad_st = Eigen::Vector2d::Zero();  // dA/d(s, t), 1/mm
  int solids_begin = 0, solids_end = 0;  // into Evaluation::solids
};

struct Evaluation {
  std::vector<Sample> samples;
  std::vector<Sub> subs;
  std::vector<int> solids;
  std::vector<int> pixel_sample;  // per view image pixel (offset by view_base): sample index or -1
  std::vector<int> view_base;
  long rays = 0;
};

struct LevelData {
  int binning = 1;
  int samples_per_axis = 1;
  std::vector<CameraModel> cameras;  // binned, unscaled focal
  std::vector<cv::Mat> photos;       // binned
};

cv::Mat bin_photo(const cv::Mat& photo, int b, int width, int height) {
  cv::Mat out(height, width, CV_32F);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      double sum = 0;
      for (int i = 0; i < b; ++i)
        for (int j = 0; j < b; ++j) sum += photo.at<float>(r * b + i, c * b + j);
      out.at<float>(r, c) = static_cast<float>(sum / (b * b));  // NaN anywhere: NaN
    }
  return out;
}

bool inside_plate(const Landing& l, const PlatePicture& plate) {
  const double reach_s = 0.5 * (std::abs(l.J(0, 0)) + std::abs(l.J(0, 1)));
  const double reach_t = 0.5 * (std::abs(l.J(1, 0)) + std::abs(l.J(1, 1)));
  return std::abs(l.st.x()) + reach_s <= 0.5 * plate.width_mm && std::abs(l.st.y()) + reach_t <= 0.5 * plate.height_mm;
}

// The model as photo v sees it: the plate moved along the sheet's normal by
// the photo's known offset.
SheetPlane offset_sheet(SheetPlane sheet, double offset_mm) {
  sheet.origin_mm += offset_mm * sheet.normal();
  return sheet;
}

bool inside_plate_point(const SheetCrossing& c, const PlatePicture& plate) {
  return std::abs(c.s_mm) <= 0.5 * plate.width_mm && std::abs(c.t_mm) <= 0.5 * plate.height_mm;
}

class Fitter {
 public:
  Fitter(const TraceScene& drawing, const std::vector<PlatePhoto>& photos, const PlatePicture& plate,
         const ModelFitFreedom& freedom, const ModelFitTolerances& tol, const ModelFitOptions& options)
      : drawing_(drawing), photos_(photos), plate_(plate), options_(options) {
    for (std::size_t v = 0; v < photos.size(); ++v) {
      int first = static_cast<int>(v);
      for (std::size_t u = 0; u < v; ++u)
        if (!photos[v].name.empty() && photos[u].name == photos[v].name) {
          first = static_cast<int>(u);
          break;
        }
      camera_of_.push_back(first);
    }
    build_parameters(freedom, tol);
  }

  ModelFitResult run();

 private:
  void build_parameters(const ModelFitFreedom& f, const ModelFitTolerances& tol);
  Evaluation evaluate(const Model& m, const LevelData& level);
  double predicted(const Sample& s, const Eigen::VectorXd& theta) const;
  double gain(const Sample& s, const Eigen::VectorXd& theta) const;
  // Jacobian columns (sparse: sample, value), one per parameter.
  struct Column {
    std::vector<int> rows;
    std::vector<double> values;
  };
  std::vector<Column> jacobian(const Model& m, const LevelData& level, const Evaluation& e,
                               const Eigen::VectorXd& theta, long* rays);
  // d(s, t)/d(parameter) of the samples `rows` by forward differences of re-traced pixels.
  void retraced(const TraceScene& scene, const std::vector<RigidTransform>& poses, const std::vector<double>& focal,
                const LevelData& level, const Evaluation& e, const std::vector<int>& rows, double step,
                std::vector<Eigen::Vector2d>* dst, long* rays);
  void normal_equations(const std::vector<Column>& cols, const std::vector<double>& residual,
                        const std::vector<double>& weight, double sigma, const Eigen::VectorXd& theta,
                        Eigen::MatrixXd* H, Eigen::VectorXd* g) const;
  double prior_cost(const Eigen::VectorXd& theta) const;
  Eigen::MatrixXd gauge(const Eigen::VectorXd& theta) const;
  void weak_combinations(const Eigen::MatrixXd& H, const Eigen::VectorXd& theta, ModelFitResult* result) const;

  const TraceScene& drawing_;
  const std::vector<PlatePhoto>& photos_;
  PlatePicture plate_;
  ModelFitOptions options_;
  std::vector<Param> params_;
  std::vector<int> glass_spheres_;
  std::vector<int> camera_of_;  // per photo: the first photo of the same camera (PlatePhoto::name)
};

void Fitter::build_parameters(const ModelFitFreedom& f, const ModelFitTolerances& tol) {
  const char* xyz[] = {"x", "y", "z"};
  const char* stn[] = {"s", "t", "normal"};
  for (std::size_t v = 0; v < photos_.size(); ++v) {
    if (camera_of_[v] != static_cast<int>(v)) continue;  // shares an earlier photo's camera
    const std::string cam = photos_[v].name.empty() ? "cam" + std::to_string(v) : photos_[v].name;
    if (f.camera_pose) {
      for (int a = 0; a < 3; ++a)
        params_.push_back({Kind::camera_rotation, static_cast<int>(v), -1, a, tol.camera_rotation_deg * kRadPerDeg,
                           cam + ".rotation_" + xyz[a] + "_deg", 1 / kRadPerDeg});
      for (int a = 0; a < 3; ++a)
        params_.push_back({Kind::camera_position, static_cast<int>(v), -1, a, tol.camera_position_mm,
                           cam + ".centre_" + xyz[a] + "_mm", 1});
    }
    if (f.camera_focal)
      params_.push_back({Kind::camera_focal, static_cast<int>(v), -1, 0, tol.camera_focal_relative,
                         cam + ".focal_scale", 1});
  }
  if (f.sheet_pose) {
    for (int a = 0; a < 3; ++a)
      params_.push_back({Kind::sheet_rotation, -1, -1, a, tol.sheet_rotation_deg * kRadPerDeg,
                         std::string("sheet.rotation_") + stn[a] + "_deg", 1 / kRadPerDeg});
    for (int a = 0; a < 3; ++a)
      params_.push_back({Kind::sheet_position, -1, -1, a, tol.sheet_position_mm,
                         std::string("sheet.position_") + stn[a] + "_mm", 1});
  }
  for (std::size_t i = 0; i < drawing_.solids.size(); ++i) {
    const TraceSolid& s = drawing_.solids[i];
    if (s.material.kind != TraceMaterial::Kind::glass || !std::holds_alternative<Sphere>(s.shape)) continue;
    glass_spheres_.push_back(static_cast<int>(i));
    const std::string name = "sphere[" + std::to_string(i) + "]";
    if (f.sphere_centres)
      for (int a = 0; a < 3; ++a)
        params_.push_back({Kind::sphere_centre, -1, static_cast<int>(i), a, tol.sphere_centre_mm,
                           name + ".centre_" + xyz[a] + "_mm", 1});
    if (f.sphere_diameters)
      params_.push_back({Kind::sphere_diameter, -1, static_cast<int>(i), 0, tol.sphere_diameter_mm,
                         name + ".diameter_mm", 1});
  }
  bool any_glass = false;
  for (const TraceSolid& s : drawing_.solids) any_glass |= s.material.kind == TraceMaterial::Kind::glass;
  if (f.refractive_index && any_glass)
    params_.push_back({Kind::index, -1, -1, 0, tol.refractive_index, "glass.index_offset", 1});
  for (std::size_t v = 0; v < photos_.size(); ++v) {
    for (int a = 0; a < kGainTerms; ++a) params_.push_back({Kind::gain, static_cast<int>(v), -1, a, 0, "", 1});
    for (int a = 0; a < kOffsetTerms; ++a) params_.push_back({Kind::offset, static_cast<int>(v), -1, a, 0, "", 1});
  }
}

int photometric_base(const std::vector<Param>& params, int view) {
  for (std::size_t k = 0; k < params.size(); ++k)
    if (params[k].kind == Kind::gain && params[k].view == view) return static_cast<int>(k);
  return -1;
}

double Fitter::gain(const Sample& s, const Eigen::VectorXd& theta) const {
  const int b = photometric_base(params_, s.view);
  const double basis[kGainTerms] = {1, s.x, s.y, s.x * s.x, s.x * s.y, s.y * s.y};
  double g = 0;
  for (int a = 0; a < kGainTerms; ++a) g += theta[b + a] * basis[a];
  return g;
}

double Fitter::predicted(const Sample& s, const Eigen::VectorXd& theta) const {
  const int b = photometric_base(params_, s.view) + kGainTerms;
  const double basis[kOffsetTerms] = {1, s.x, s.y};
  double o = 0;
  for (int a = 0; a < kOffsetTerms; ++a) o += theta[b + a] * basis[a];
  return gain(s, theta) * s.value + o;
}

Evaluation Fitter::evaluate(const Model& m, const LevelData& level) {
  Evaluation e;
  TraceOptions trace = options_.trace;
  trace.record_solids_met = true;
  const int k = level.samples_per_axis;
  const SheetTexture& tex = *plate_.texture;
  for (std::size_t v = 0; v < photos_.size(); ++v) {
    const CameraModel cam = scaled_focal(level.cameras[v], m.focal_scale[v]);
    TraceScene scene = m.scene;
    scene.sheet = offset_sheet(scene.sheet, photos_[v].plate_offset_mm);
    const std::unique_ptr<SceneIndex> index = make_scene_index(scene);
    const int w = cam.width_px(), h = cam.height_px();
    const double full_w = photos_[v].camera.width_px(), full_h = photos_[v].camera.height_px();
    const cv::Mat& photo = level.photos[v];
    struct Row {
      std::vector<Sample> samples;
      std::vector<Sub> subs;
      std::vector<int> solids;
    };
    std::vector<Row> rows(static_cast<std::size_t>(h));
    parallel_rows(h, options_.threads, [&](int r) {
      thread_local TraceResult scratch;
      std::vector<int> met;
      Row& row = rows[static_cast<std::size_t>(r)];
      for (int c = 0; c < w; ++c) {
        const float value = photo.at<float>(r, c);
        if (!std::isfinite(value)) continue;
        Sample s;
        s.view = static_cast<int>(v);
        s.pixel = Eigen::Vector2d(c, r);
        s.photo = value;
        s.sub_begin = static_cast<int>(row.subs.size());
        const std::size_t solids_at = row.solids.size();
        bool ok = true;
        // The centre first: a pixel whose ray meets no solid maps the plate
        // linearly (a plane seen through nothing but air), so one
        // footprint-averaged sample is exact; one that meets glass is
        // subsampled k x k.
        int kp = 1;
        Landing centre;
        if (k > 1) {
          centre = land(scene, *index, cam, m.camera_from_world[v], s.pixel, trace, &scratch, &met);
          if (!centre.ok) continue;
          // Through air: as many subsamples as keep each footprint within the
          // picture's finest level (a coarser mip level blurs the plate more
          // than the photo's pixels do).
          const double texels = std::max(centre.J.col(0).norm(), centre.J.col(1).norm()) / tex.mm_per_texel();
          const int k_air = std::clamp(static_cast<int>(std::ceil(texels / SheetTexture::kMaxTapsPerAxis)), 1, k);
          kp = met.empty() ? k_air : k;
        }
        for (int j = 0; j < kp && ok; ++j)
          for (int i = 0; i < kp && ok; ++i) {
            Sub sub;
            sub.k = kp;
            sub.pixel = s.pixel + Eigen::Vector2d((i + 0.5) / kp - 0.5, (j + 0.5) / kp - 0.5);
            // (one sample: the centre just traced, its crossings still in scratch)
            sub.landing = k > 1 && kp == 1 ? centre
                                           : land(scene, *index, cam, m.camera_from_world[v], sub.pixel, trace,
                                                  &scratch, &met);
            if (!sub.landing.ok) {
              ok = false;
              break;
            }
            sub.landing.J /= kp;  // a subsample covers 1/k of the pixel along each axis
            const Eigen::Matrix2d& J = sub.landing.J;
            const double det = J.determinant();
            if (!inside_plate(sub.landing, plate_) || !std::isfinite(det) || std::abs(det) < 1e-18) {
              ok = false;
              break;
            }
            const Eigen::Vector2d st = sub.landing.st;
            sub.picture = tex.average(st.x(), st.y(), J);
            // dA per footprint step along each axis, by central differences a
            // quarter footprint wide: wider ones give the gradient of a blurred
            // picture (Gauss-Newton then crawls along the index-distance valley).
            Eigen::Vector2d dpix;
            for (int a = 0; a < 2; ++a) {
              const Eigen::Vector2d step = kGradientStep * J.col(a);
              dpix[a] = (tex.average(st.x() + step.x(), st.y() + step.y(), J) -
                         tex.average(st.x() - step.x(), st.y() - step.y(), J)) /
                        (2 * kGradientStep);
            }
            sub.grad_st = J.transpose().inverse() * dpix;
            double ghosts = 0;
            for (std::size_t q = 0; q < scratch.crossings.size(); ++q) {
              const SheetCrossing& g = scratch.crossings[q];
              if (static_cast<int>(q) != sub.landing.first && inside_plate_point(g, plate_))
                ghosts += g.weight * tex.average(g.s_mm, g.t_mm, g.dst_dpixel / kp);
            }
            s.value += sub.landing.weight * sub.picture + ghosts;
            sub.solids_begin = static_cast<int>(row.solids.size());
            row.solids.insert(row.solids.end(), met.begin(), met.end());
            sub.solids_end = static_cast<int>(row.solids.size());
            row.subs.push_back(sub);
          }
        // A pixel over which the mapping bends by more than a tenth of a
        // pixel (a rim, a squeezed view) is predicted by its subsamples'
        // linear pieces less well than the photo integrates it: left out.
        if (ok && kp > 1 && k > 1) {
          const Eigen::Matrix2d inv = centre.J.inverse();
          for (int q = s.sub_begin; q < static_cast<int>(row.subs.size()) && ok; ++q) {
            const Sub& sub = row.subs[static_cast<std::size_t>(q)];
            const Eigen::Vector2d linear = centre.st + centre.J * (sub.pixel - s.pixel);
            if ((inv * (sub.landing.st - linear)).norm() > options_.max_bend_px) ok = false;
          }
        }
        if (!ok) {
          row.subs.resize(static_cast<std::size_t>(s.sub_begin));
          row.solids.resize(solids_at);
          continue;
        }
        s.value /= kp * kp;
        s.sub_end = static_cast<int>(row.subs.size());
        const int bin = level.binning;
        s.x = ((c + 0.5) * bin - 0.5 - 0.5 * (full_w - 1)) / (0.5 * full_w);
        s.y = ((r + 0.5) * bin - 0.5 - 0.5 * (full_h - 1)) / (0.5 * full_h);
        row.samples.push_back(s);
      }
    });
    e.view_base.push_back(static_cast<int>(e.pixel_sample.size()));
    e.pixel_sample.resize(e.pixel_sample.size() + static_cast<std::size_t>(w) * static_cast<std::size_t>(h), -1);
    e.rays += static_cast<long>(w) * h;
    for (int r = 0; r < h; ++r) {
      Row& row = rows[static_cast<std::size_t>(r)];
      const int solid_offset = static_cast<int>(e.solids.size()), sub_offset = static_cast<int>(e.subs.size());
      e.solids.insert(e.solids.end(), row.solids.begin(), row.solids.end());
      for (Sample s : row.samples) {
        const int index_of_sample = static_cast<int>(e.samples.size());
        e.rays += s.sub_end - s.sub_begin;
        for (int q = s.sub_begin; q < s.sub_end; ++q) {
          Sub sub = row.subs[static_cast<std::size_t>(q)];
          sub.sample = index_of_sample;
          sub.solids_begin += solid_offset;
          sub.solids_end += solid_offset;
          e.subs.push_back(sub);
        }
        s.sub_begin += sub_offset;
        s.sub_end += sub_offset;
        e.pixel_sample[static_cast<std::size_t>(e.view_base.back() + r * w + static_cast<int>(s.pixel.x()))] =
            index_of_sample;
        e.samples.push_back(s);
      }
    }
  }
  return e;
}

void Fitter::retraced(const TraceScene& scene, const std::vector<RigidTransform>& poses,
                      const std::vector<double>& focal, const LevelData& level, const Evaluation& e,
                      const std::vector<int>& subs, double step, std::vector<Eigen::Vector2d>* dst, long* rays) {
  dst->assign(subs.size(), Eigen::Vector2d::Zero());
  if (subs.empty()) return;
  std::vector<CameraModel> cams;
  std::vector<TraceScene> scenes(photos_.size(), scene);
  std::vector<std::unique_ptr<SceneIndex>> indexes;
  for (std::size_t v = 0; v < photos_.size(); ++v) {
    cams.push_back(scaled_focal(level.cameras[v], focal[v]));
    scenes[v].sheet = offset_sheet(scene.sheet, photos_[v].plate_offset_mm);
    indexes.push_back(make_scene_index(scenes[v]));
  }
  TraceOptions chain = options_.trace;  // the derivatives follow the refracted chain only
  chain.reflections = false;
  constexpr int kChunk = 256;
  const int chunks = static_cast<int>((subs.size() + kChunk - 1) / kChunk);
  parallel_rows(chunks, options_.threads, [&](int chunk) {
    thread_local TraceResult scratch;
    const std::size_t end = std::min(subs.size(), static_cast<std::size_t>(chunk + 1) * kChunk);
    for (std::size_t i = static_cast<std::size_t>(chunk) * kChunk; i < end; ++i) {
      const Sub& sub = e.subs[static_cast<std::size_t>(subs[i])];
      const int view = e.samples[static_cast<std::size_t>(sub.sample)].view;
      const Landing l = land(scenes[static_cast<std::size_t>(view)], *indexes[static_cast<std::size_t>(view)],
                             cams[static_cast<std::size_t>(view)], poses[static_cast<std::size_t>(view)], sub.pixel,
                             chain, &scratch, nullptr);
      // Another sequence of surfaces (a rim): no derivative.
      if (l.ok && l.path == sub.landing.path) (*dst)[i] = (l.st - sub.landing.st) / step;
    }
  });
  *rays += static_cast<long>(subs.size());
}

// d(s, t) of a crossing when the sheet moves: its last segment met by the moved plane.
Eigen::Vector2d moved_sheet_st(const Landing& l, const SheetPlane& sheet) {
  const Eigen::Vector3d n = sheet.normal();
  const double lambda = n.dot(sheet.origin_mm - l.point) / n.dot(l.direction);
  const Eigen::Vector3d p = l.point + lambda * l.direction - sheet.origin_mm;
  return Eigen::Vector2d(p.dot(sheet.s_axis), p.dot(sheet.t_axis));
}

std::vector<Fitter::Column> Fitter::jacobian(const Model& m, const LevelData& level, const Evaluation& e,
                                              const Eigen::VectorXd& theta, long* rays) {
  const std::size_t n = e.samples.size();
  std::vector<Column> cols(params_.size());
  // A column is gathered densely over the samples, then kept sparse.
  std::vector<double> dense(n, 0.0);
  std::vector<int> touched;
  auto add = [&](int sub_index, const Eigen::Vector2d& dst) {
    const Sub& sub = e.subs[static_cast<std::size_t>(sub_index)];
    const double value = sub.landing.weight * sub.grad_st.dot(dst);
    if (value == 0 || !std::isfinite(value)) return;
    double& d = dense[static_cast<std::size_t>(sub.sample)];
    if (d == 0) touched.push_back(sub.sample);
    d += value / (sub.k * sub.k);
  };
  auto keep = [&](std::size_t k) {
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    for (int row : touched) {
      const double v = dense[static_cast<std::size_t>(row)] * gain(e.samples[static_cast<std::size_t>(row)], theta);
      dense[static_cast<std::size_t>(row)] = 0;
      if (v == 0) continue;
      cols[k].rows.push_back(row);
      cols[k].values.push_back(v);
    }
    touched.clear();
  };
  // Each view's subsamples, those that meet glass, and those that meet each solid.
  std::vector<std::vector<int>> view_subs(photos_.size()), view_glass(photos_.size());
  std::vector<std::vector<int>> solid_subs(drawing_.solids.size());
  for (std::size_t i = 0; i < e.subs.size(); ++i) {
    const Sub& sub = e.subs[i];
    const std::size_t view = static_cast<std::size_t>(e.samples[static_cast<std::size_t>(sub.sample)].view);
    view_subs[view].push_back(static_cast<int>(i));
    if (sub.solids_end > sub.solids_begin) view_glass[view].push_back(static_cast<int>(i));
    for (int j = sub.solids_begin; j < sub.solids_end; ++j)
      solid_subs[static_cast<std::size_t>(e.solids[static_cast<std::size_t>(j)])].push_back(static_cast<int>(i));
  }
  // A camera's subsamples: those of every photo it took.
  std::vector<std::vector<int>> camera_subs(photos_.size());
  for (std::size_t v = 0; v < photos_.size(); ++v) {
    auto& c = camera_subs[static_cast<std::size_t>(camera_of_[v])];
    c.insert(c.end(), view_subs[v].begin(), view_subs[v].end());
  }
  for (auto& c : camera_subs) std::sort(c.begin(), c.end());
  std::vector<Eigen::Vector2d> dst;
  for (std::size_t k = 0; k < params_.size(); ++k) {
    const Param& p = params_[k];
    switch (p.kind) {
      case Kind::camera_rotation: {
        const CameraModel cam = scaled_focal(level.cameras[static_cast<std::size_t>(p.view)],
                                             m.focal_scale[static_cast<std::size_t>(p.view)]);
        const Eigen::Vector3d axis = Eigen::Vector3d::Unit(p.axis);
        for (int q : camera_subs[static_cast<std::size_t>(p.view)]) {
          const Sub& sub = e.subs[static_cast<std::size_t>(q)];
          const UnprojectResult u = cam.unproject(sub.pixel);
          if (!u.ok()) continue;
          const Eigen::Vector3d d(u.normalized.x(), u.normalized.y(), 1.0);
          const Eigen::Vector3d dd = -axis.cross(d);
          const Eigen::Vector2d dn(dd.x() - d.x() * dd.z(), dd.y() - d.y() * dd.z());
          // The subsample's J is per subsample step: times k per pixel.
          add(q, sub.landing.J * sub.k * (u.dpixel_dnormalized * dn));
        }
        break;
      }
      case Kind::camera_focal: {
        const CameraModel cam = scaled_focal(level.cameras[static_cast<std::size_t>(p.view)],
                                             m.focal_scale[static_cast<std::size_t>(p.view)]);
        const Eigen::Vector2d c(cam.cx_px(), cam.cy_px());
        const double scale = m.focal_scale[static_cast<std::size_t>(p.view)];
        for (int q : camera_subs[static_cast<std::size_t>(p.view)]) {
          const Sub& sub = e.subs[static_cast<std::size_t>(q)];
          add(q, sub.landing.J * sub.k * (-(sub.pixel - c) / scale));
        }
        break;
      }
      case Kind::sheet_rotation:
      case Kind::sheet_position: {
        const double h = p.kind == Kind::sheet_rotation ? 1e-7 : 1e-5;
        Eigen::VectorXd t = theta;
        t[static_cast<Eigen::Index>(k)] += h;
        const SheetPlane moved = apply(drawing_, photos_, camera_of_, params_, t).scene.sheet;
        for (std::size_t q = 0; q < e.subs.size(); ++q) {
          const Landing& l = e.subs[q].landing;
          const double offset = photos_[static_cast<std::size_t>(e.samples[static_cast<std::size_t>(e.subs[q].sample)].view)].plate_offset_mm;
          add(static_cast<int>(q), (moved_sheet_st(l, offset_sheet(moved, offset)) - l.st) / h);
        }
        break;
      }
      case Kind::camera_position:
      case Kind::sphere_centre:
      case Kind::sphere_diameter:
      case Kind::index: {
        const double h = p.kind == Kind::index ? options_.step_index : options_.step_mm;
        Eigen::VectorXd t = theta;
        t[static_cast<Eigen::Index>(k)] += h;
        const Model moved = apply(drawing_, photos_, camera_of_, params_, t);
        std::vector<int> subs;
        if (p.kind == Kind::camera_position) {
          subs = camera_subs[static_cast<std::size_t>(p.view)];
        } else if (p.kind == Kind::index) {
          for (const auto& g : view_glass) subs.insert(subs.end(), g.begin(), g.end());
        } else {
          subs = solid_subs[static_cast<std::size_t>(p.solid)];
        }
        retraced(moved.scene, moved.camera_from_world, moved.focal_scale, level, e, subs, h, &dst, rays);
        for (std::size_t i = 0; i < subs.size(); ++i) add(subs[i], dst[i]);
        break;
      }
      case Kind::gain:
      case Kind::offset: {
        for (std::size_t i = 0; i < n; ++i) {
          const Sample& s = e.samples[i];
          if (s.view != p.view) continue;
          const double gb[kGainTerms] = {1, s.x, s.y, s.x * s.x, s.x * s.y, s.y * s.y};
          cols[k].rows.push_back(static_cast<int>(i));
          cols[k].values.push_back(p.kind == Kind::gain ? gb[p.axis] * s.value : gb[p.axis]);
        }
        continue;
      }
    }
    keep(k);
  }
  return cols;
}

double sparse_dot(const std::vector<int>& ra, const std::vector<double>& va, const std::vector<int>& rb,
                  const std::vector<double>& vb, const std::vector<double>& w) {
  if (ra.empty() || rb.empty() || ra.back() < rb.front() || rb.back() < ra.front()) return 0;
  double sum = 0;
  std::size_t i = 0, j = 0;
  while (i < ra.size() && j < rb.size()) {
    if (ra[i] < rb[j]) {
      ++i;
    } else if (rb[j] < ra[i]) {
      ++j;
    } else {
      sum += va[i] * vb[j] * w[static_cast<std::size_t>(ra[i])];
      ++i;
      ++j;
    }
  }
  return sum;
}

void Fitter::normal_equations(const std::vector<Column>& cols, const std::vector<double>& residual,
                              const std::vector<double>& weight, double sigma, const Eigen::VectorXd& theta,
                              Eigen::MatrixXd* H, Eigen::VectorXd* g) const {
  const int P = static_cast<int>(params_.size());
  H->setZero(P, P);
  g->setZero(P);
  const double inv_var = 1 / (sigma * sigma);
  parallel_rows(P, options_.threads, [&](int a) {
    const Column& ca = cols[static_cast<std::size_t>(a)];
    double ga = 0;
    for (std::size_t i = 0; i < ca.rows.size(); ++i) {
      const std::size_t r = static_cast<std::size_t>(ca.rows[i]);
      ga += ca.values[i] * weight[r] * residual[r];
    }
    (*g)[a] = ga * inv_var;
    for (int b = a; b < P; ++b) {
      const Column& cb = cols[static_cast<std::size_t>(b)];
      (*H)(a, b) = sparse_dot(ca.rows, ca.values, cb.rows, cb.values, weight) * inv_var;
    }
  });
  for (int a = 0; a < P; ++a)
    for (int b = 0; b < a; ++b) (*H)(a, b) = (*H)(b, a);
  for (int k = 0; k < P; ++k) {
    const double s = params_[static_cast<std::size_t>(k)].prior_sigma;
    if (s > 0) {
      (*H)(k, k) += 1 / (s * s);
      (*g)[k] += theta[k] / (s * s);
    } else {
      (*H)(k, k) += 1e-12;  // photometric: no prior; keeps an unused term solvable
    }
  }
}

double Fitter::prior_cost(const Eigen::VectorXd& theta) const {
  double c = 0;
  for (std::size_t k = 0; k < params_.size(); ++k) {
    const double s = params_[k].prior_sigma;
    if (s > 0) c += 0.5 * std::pow(theta[static_cast<Eigen::Index>(k)] / s, 2);
  }
  return c;
}

double huber(double u, double k) { return std::abs(u) <= k ? 0.5 * u * u : k * std::abs(u) - 0.5 * k * k; }
double huber_weight(double u, double k) { return std::abs(u) <= k ? 1.0 : k / std::abs(u); }

double robust_sigma(std::vector<double> r) {
  if (r.empty()) return 1;
  const auto mid = r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2);
  std::nth_element(r.begin(), mid, r.end());
  const double med = *mid;
  for (double& x : r) x = std::abs(x - med);
  std::nth_element(r.begin(), mid, r.end());
  return 1.4826 * *mid;
}

double rms(const std::vector<double>& r) {
  double s = 0;
  for (double x : r) s += x * x;
  return r.empty() ? 0 : std::sqrt(s / static_cast<double>(r.size()));
}

// The gauge: the six rigid motions of the world (translations along, turns
// about the world axes through the origin) that move camera, glass and plate
// together and so change no photo, as columns in parameter units.
Eigen::MatrixXd Fitter::gauge(const Eigen::VectorXd& theta) const {
  const Model m = apply(drawing_, photos_, camera_of_, params_, theta);
  const int P = static_cast<int>(params_.size());
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(P, 6);
  const SheetPlane& sheet = m.scene.sheet;
  Eigen::Matrix3d axes;
  axes << sheet.s_axis, sheet.t_axis, sheet.normal();
  for (int a = 0; a < 6; ++a) {
    const bool turn = a >= 3;
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(a % 3);
    auto moved = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d { return turn ? Eigen::Vector3d(e.cross(p)) : e; };
    for (int k = 0; k < P; ++k) {
      const Param& p = params_[static_cast<std::size_t>(k)];
      double v = 0;
      switch (p.kind) {
        case Kind::camera_rotation:
          if (turn) v = -(m.camera_from_world[static_cast<std::size_t>(p.view)].rotation * e)[p.axis];
          break;
        case Kind::camera_position: {
          const RigidTransform& c = m.camera_from_world[static_cast<std::size_t>(p.view)];
          v = moved(-c.rotation.transpose() * c.translation_mm)[p.axis];
          break;
        }
        case Kind::sheet_rotation:
          if (turn) v = (axes.transpose() * e)[p.axis];
          break;
        case Kind::sheet_position: v = (axes.transpose() * moved(sheet.origin_mm))[p.axis]; break;
        case Kind::sphere_centre:
          v = moved(std::get<Sphere>(m.scene.solids[static_cast<std::size_t>(p.solid)].shape).centre_mm)[p.axis];
          break;
        default: break;
      }
      g(k, a) = v;
    }
  }
  return g;
}

// What the photos cannot pin down: the combinations of parameters along which
// the photos' information (whitened by the tolerances: 1 = as much as the
// drawing's tolerance gives) is below 1, the gauge projected out first.
void Fitter::weak_combinations(const Eigen::MatrixXd& H, const Eigen::VectorXd& theta, ModelFitResult* result) const {
  const int P = static_cast<int>(params_.size());
  std::vector<int> geo;
  for (int k = 0; k < P; ++k)
    if (params_[static_cast<std::size_t>(k)].prior_sigma > 0) geo.push_back(k);
  const int G = static_cast<int>(geo.size());
  if (G == 0) return;
  // The photos' information on the geometry, the photometric terms eliminated
  // (Schur complement), whitened.
  std::vector<int> photometric;
  for (int k = 0; k < P; ++k)
    if (params_[static_cast<std::size_t>(k)].prior_sigma == 0) photometric.push_back(k);
  Eigen::MatrixXd Hgg(G, G), Hgp(G, static_cast<int>(photometric.size())),
      Hpp(static_cast<int>(photometric.size()), static_cast<int>(photometric.size()));
  for (int a = 0; a < G; ++a) {
    for (int b = 0; b < G; ++b) Hgg(a, b) = H(geo[static_cast<std::size_t>(a)], geo[static_cast<std::size_t>(b)]);
    for (std::size_t b = 0; b < photometric.size(); ++b) Hgp(a, static_cast<int>(b)) = H(geo[static_cast<std::size_t>(a)], photometric[b]);
  }
  for (std::size_t a = 0; a < photometric.size(); ++a)
    for (std::size_t b = 0; b < photometric.size(); ++b) Hpp(static_cast<int>(a), static_cast<int>(b)) = H(photometric[a], photometric[b]);
  Eigen::MatrixXd info = Hgg;
  if (!photometric.empty()) info -= Hgp * Hpp.ldlt().solve(Hgp.transpose());
  Eigen::VectorXd S(G);
  for (int a = 0; a < G; ++a) {
    const double sk = params_[static_cast<std::size_t>(geo[static_cast<std::size_t>(a)])].prior_sigma;
    S[a] = sk;
    info(a, a) -= 1 / (sk * sk);  // the photos' share only
  }
  Eigen::MatrixXd W = S.asDiagonal() * info * S.asDiagonal();
  // Project out the gauge (whitened, orthonormalised).
  const Eigen::MatrixXd g_all = gauge(theta);
  Eigen::MatrixXd g(G, 6);
  for (int a = 0; a < G; ++a) g.row(a) = g_all.row(geo[static_cast<std::size_t>(a)]) / S[a];
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(g);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(G, std::min(6, G));
  const Eigen::MatrixXd proj = Eigen::MatrixXd::Identity(G, G) - Q * Q.transpose();
  W = proj * W * proj;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(W);
  for (int k = 0; k < G; ++k) {
    const double information = eig.eigenvalues()[k];
    const Eigen::VectorXd v = eig.eigenvectors().col(k);
    if (information >= 1 || (Q.transpose() * v).norm() > 0.5) continue;  // determined, or a gauge direction
    WeakCombination w;
    w.information = std::max(0.0, information);
    std::vector<int> order(static_cast<std::size_t>(G));
    for (int a = 0; a < G; ++a) order[static_cast<std::size_t>(a)] = a;
    std::sort(order.begin(), order.end(), [&](int x, int y) { return std::abs(v[x]) > std::abs(v[y]); });
    for (int i = 0; i < std::min(G, 6); ++i) {
      const int a = order[static_cast<std::size_t>(i)];
      if (std::abs(v[a]) < 0.15) break;
      w.parts.emplace_back(params_[static_cast<std::size_t>(geo[static_cast<std::size_t>(a)])].name, v[a]);
    }
    result->weak.push_back(w);
  }
}

ModelFitResult Fitter::run() {
  const auto t0 = std::chrono::steady_clock::now();
  ModelFitResult result;
  const int P = static_cast<int>(params_.size());
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(P);
  bool photometric_started = false;
  Eigen::MatrixXd H;
  Eigen::VectorXd g;
  std::vector<Column> cols;
  const int level_count = static_cast<int>(options_.binning_levels.size());
  for (int li = 0; li < level_count; ++li) {
    const auto tl = std::chrono::steady_clock::now();
    LevelData level;
    level.binning = options_.binning_levels[static_cast<std::size_t>(li)];
    level.samples_per_axis = options_.samples_per_axis;
    for (const PlatePhoto& p : photos_) {
      level.cameras.push_back(level.binning > 1 ? binned(p.camera, level.binning) : p.camera);
      level.photos.push_back(level.binning > 1 ? bin_photo(p.photo, level.binning, level.cameras.back().width_px(),
                                                           level.cameras.back().height_px())
                                               : p.photo);
    }
    ModelFitLevel report;
    report.binning = level.binning;
    Model model = apply(drawing_, photos_, camera_of_, params_, theta);
    Evaluation e = evaluate(model, level);
    report.traced_rays += e.rays;
    if (e.samples.empty())
      throw InputError("", "photo", "no pixel of the photos sees the plate through the model (binning " +
                                        std::to_string(level.binning) + ")");
    if (!photometric_started) {
      // Lighting start: photo = a w A + b by linear least squares, per view.
      for (std::size_t v = 0; v < photos_.size(); ++v) {
        double sx = 0, sy = 0, sxx = 0, sxy = 0, cnt = 0;
        for (const Sample& s : e.samples) {
          if (s.view != static_cast<int>(v)) continue;
          const double x = s.value;
          sx += x, sy += s.photo, sxx += x * x, sxy += x * s.photo, cnt += 1;
        }
        const double var = sxx - sx * sx / cnt;
        const double a = var > 0 ? (sxy - sx * sy / cnt) / var : 1.0;
        const int b = photometric_base(params_, static_cast<int>(v));
        theta[b] = a;
        theta[b + kGainTerms] = (sy - a * sx) / cnt;
      }
      photometric_started = true;
    }
    auto residuals = [&](const Evaluation& ev, const Eigen::VectorXd& th) {
      std::vector<double> r(ev.samples.size());
      for (std::size_t i = 0; i < r.size(); ++i) r[i] = predicted(ev.samples[i], th) - ev.samples[i].photo;
      return r;
    };
    std::vector<double> r = residuals(e, theta);
    report.pixels = static_cast<int>(r.size());
    report.rms_before = rms(r);
    {
      double mean = 0, sq = 0;
      for (const Sample& s : e.samples) mean += s.photo;
      mean /= static_cast<double>(e.samples.size());
      for (const Sample& s : e.samples) sq += (s.photo - mean) * (s.photo - mean);
      report.photo_sd = std::sqrt(sq / static_cast<double>(e.samples.size()));
    }
    double mu = 1e-3;
    for (int it = 0; it < options_.max_iterations; ++it) {
      const double sigma = std::max(robust_sigma(r), 1e-9 * (1 + rms(r)));
      if (it == 0) report.noise = sigma;
      std::vector<double> w(r.size());
      for (std::size_t i = 0; i < r.size(); ++i) w[i] = huber_weight(r[i] / sigma, options_.huber_k);
      long rays = 0;
      cols = jacobian(model, level, e, theta, &rays);
      report.traced_rays += rays;
      normal_equations(cols, r, w, sigma, theta, &H, &g);
      bool accepted = false;
      Eigen::VectorXd step;
      for (int tries = 0; tries < 8 && !accepted; ++tries) {
        Eigen::MatrixXd A = H;
        for (int k = 0; k < P; ++k) A(k, k) += mu * H(k, k);
        step = A.ldlt().solve(-g);
        if (!step.allFinite()) {
          mu *= 10;
          continue;
        }
        const Eigen::VectorXd trial = theta + step;
        Model trial_model = apply(drawing_, photos_, camera_of_, params_, trial);
        Evaluation te = evaluate(trial_model, level);
        report.traced_rays += te.rays;
        const std::vector<double> tr = residuals(te, trial);
        // Both costs over the pixels valid in both.
        double c_old = prior_cost(theta), c_new = prior_cost(trial);
        for (std::size_t i = 0; i < te.samples.size(); ++i) {
          const Sample& s = te.samples[i];
          const int w_px = level.cameras[static_cast<std::size_t>(s.view)].width_px();
          const int old = e.pixel_sample[static_cast<std::size_t>(
              e.view_base[static_cast<std::size_t>(s.view)] + static_cast<int>(s.pixel.y()) * w_px +
              static_cast<int>(s.pixel.x()))];
          if (old < 0) continue;
          c_old += huber(r[static_cast<std::size_t>(old)] / sigma, options_.huber_k);
          c_new += huber(tr[i] / sigma, options_.huber_k);
        }
        if (c_new < c_old) {
          accepted = true;
          theta = trial;
          model = std::move(trial_model);
          e = std::move(te);
          r = tr;
          mu = std::max(mu / 3, 1e-7);
        } else {
          mu *= 4;
        }
      }
      report.iterations = it + 1;
      if (options_.progress) options_.progress(li, it, level_count);
      if (!accepted) break;
      double largest = 0;  // the step in units of each parameter's tolerance
      for (int k = 0; k < P; ++k)
        if (params_[static_cast<std::size_t>(k)].prior_sigma > 0)
          largest = std::max(largest, std::abs(step[k]) / params_[static_cast<std::size_t>(k)].prior_sigma);
      if (largest < 1e-3) break;
    }
    report.rms_after = rms(r);
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - tl).count();
    if (li == level_count - 1) {
      result.residual_rms_end = report.rms_after;
      result.explained_variance =
          report.photo_sd > 0 ? 1 - std::pow(report.rms_after / report.photo_sd, 2) : 0.0;
      // The covariance at the solution: the normal matrix there.
      const double sigma = std::max(robust_sigma(r), 1e-9 * (1 + rms(r)));
      std::vector<double> w(r.size());
      for (std::size_t i = 0; i < r.size(); ++i) w[i] = huber_weight(r[i] / sigma, options_.huber_k);
      long rays = 0;
      cols = jacobian(model, level, e, theta, &rays);
      normal_equations(cols, r, w, sigma, theta, &H, &g);
      // Spheres no pixel looks through.
      for (int solid : glass_spheres_) {
        bool seen = false;
        for (std::size_t k = 0; k < params_.size() && !seen; ++k)
          if (params_[k].solid == solid && !cols[k].rows.empty()) seen = true;
        if (!seen) result.unseen_spheres.push_back(solid);
      }
      // Level at the drawing, for the report: the finest level's residual before any step.
      // The drawing's geometry with the fitted lighting: the residual the fit started from.
      Eigen::VectorXd th0 = theta;
      for (int k = 0; k < P; ++k)
        if (params_[static_cast<std::size_t>(k)].prior_sigma > 0) th0[k] = 0;
      const Evaluation e0 = evaluate(apply(drawing_, photos_, camera_of_, params_, th0), level);
      result.residual_rms_start = rms(residuals(e0, th0));
    }
    result.levels.push_back(report);
  }

  // Result: the model, the parameters with their sigma, the covariance.
  const Model final_model = apply(drawing_, photos_, camera_of_, params_, theta);
  result.scene = final_model.scene;
  result.camera_from_world = final_model.camera_from_world;
  result.focal_scale = final_model.focal_scale;
  const Eigen::MatrixXd cov_all = H.ldlt().solve(Eigen::MatrixXd::Identity(P, P));
  std::vector<int> geometric;
  for (int k = 0; k < P; ++k)
    if (params_[static_cast<std::size_t>(k)].prior_sigma > 0) geometric.push_back(k);
  const int G = static_cast<int>(geometric.size());
  result.covariance.resize(G, G);
  for (int a = 0; a < G; ++a)
    for (int b = 0; b < G; ++b) {
      const Param& pa = params_[static_cast<std::size_t>(geometric[static_cast<std::size_t>(a)])];
      const Param& pb = params_[static_cast<std::size_t>(geometric[static_cast<std::size_t>(b)])];
      result.covariance(a, b) = cov_all(geometric[static_cast<std::size_t>(a)], geometric[static_cast<std::size_t>(b)]) *
                                pa.report_scale * pb.report_scale;
    }
  for (int a = 0; a < G; ++a) {
    const int k = geometric[static_cast<std::size_t>(a)];
    const Param& p = params_[static_cast<std::size_t>(k)];
    FittedParameter f;
    f.name = p.name;
    double base = 0;
    if (p.kind == Kind::camera_position) {
      const RigidTransform& c0 = photos_[static_cast<std::size_t>(p.view)].camera_from_world;
      base = (-c0.rotation.transpose() * c0.translation_mm)[p.axis];
    } else if (p.kind == Kind::sphere_centre) {
      base = std::get<Sphere>(drawing_.solids[static_cast<std::size_t>(p.solid)].shape).centre_mm[p.axis];
    } else if (p.kind == Kind::sphere_diameter) {
      base = 2 * std::get<Sphere>(drawing_.solids[static_cast<std::size_t>(p.solid)].shape).radius_mm;
    } else if (p.kind == Kind::camera_focal) {
      base = 1;
    }
    f.drawing = base;
    f.fitted = base + theta[k] * p.report_scale;
    f.sigma = std::sqrt(std::max(0.0, result.covariance(a, a)));
    f.prior_sigma = p.prior_sigma * p.report_scale;
    result.parameters.push_back(f);
  }
  weak_combinations(H, theta, &result);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace

ModelFitResult fit_model(const TraceScene& drawing, const std::vector<PlatePhoto>& photos, const PlatePicture& plate,
                         const ModelFitFreedom& freedom, const ModelFitTolerances& tolerances,
                         const ModelFitOptions& options) {
  if (options.binning_levels.empty()) throw std::invalid_argument("fit_model: no levels");
  if (plate.texture == nullptr) throw std::invalid_argument("fit_model: no plate picture");
  if (photos.empty()) throw InputError("", "photo", "no plate photo given");
  for (const PlatePhoto& p : photos)
    if (p.photo.type() != CV_32FC1 || p.photo.cols != p.camera.width_px() || p.photo.rows != p.camera.height_px())
      throw InputError("", "photo",
                       "the photo of " + p.name + " is " + std::to_string(p.photo.cols) + " x " +
                           std::to_string(p.photo.rows) + " px, its camera " + std::to_string(p.camera.width_px()) +
                           " x " + std::to_string(p.camera.height_px()));
  Fitter f(drawing, photos, plate, freedom, tolerances, options);
  return f.run();
}

}  // namespace glasspiv
