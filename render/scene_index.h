#pragma once
// Nearest-hit queries over a set of solids: the one place the tracer asks
// "what does this ray meet first?". Two implementations with identical
// results: a linear search (the reference, for tests and tiny scenes) and an
// Embree BVH whose user geometries call the same exact double-precision
// intersect() of render/shapes.h, so the BVH changes the speed, never the answer.
// No I/O.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <optional>
#include <vector>

#include "render/shapes.h"

namespace glasspiv {

class SceneIndex {
 public:
  virtual ~SceneIndex() = default;
  // The nearest hit with t > t_min over all solids (d unit); ties go to the
  // lower solid index. shape_index is set. Solid skip_index is not tested
  // (-1: every solid is): the tracer names the sphere a ray leaves from its
  // surface, which that ray cannot meet again.
  virtual std::optional<Hit> first_hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                                       int skip_index = -1) const = 0;
  // Bounds of every solid together (empty box for no solids).
  const Eigen::AlignedBox3d& bounds_mm() const { return bounds_; }
  // The largest scale_mm() of the solids (0 for none): sizes the guard of rays
  // that do not start on a hit.
  double max_scale_mm() const { return max_scale_; }
  // Whether the ray (o, d) can meet any solid at all: a slab test against
  // bounds_mm() grown by a margin. false proves a miss; true proves nothing.
  bool may_hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const;

 protected:
  explicit SceneIndex(const std::vector<Shape>& shapes);
  Eigen::AlignedBox3d bounds_;
  double max_scale_ = 0;
};

class LinearSceneIndex final : public SceneIndex {
 public:
  explicit LinearSceneIndex(std::vector<Shape> shapes);
  std::optional<Hit> first_hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                               int skip_index = -1) const override;

 private:
  std::vector<Shape> shapes_;
};

class EmbreeSceneIndex final : public SceneIndex {
 public:
  // Builds the BVH (Embree's robust, high-quality build). Throws
  // std::runtime_error if Embree fails.
  explicit EmbreeSceneIndex(std::vector<Shape> shapes);
  ~EmbreeSceneIndex() override;
  EmbreeSceneIndex(const EmbreeSceneIndex&) = delete;
  EmbreeSceneIndex& operator=(const EmbreeSceneIndex&) = delete;
  std::optional<Hit> first_hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                               int skip_index = -1) const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The index a scene of this many solids should use: Embree from a handful of
// solids on, where the BVH beats the linear search.
std::unique_ptr<SceneIndex> make_scene_index(std::vector<Shape> shapes);

}  // namespace glasspiv
