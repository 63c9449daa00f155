#include "render/overlap.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>

namespace glasspiv {

namespace {

// Closest point of a box to p (box frame clamping).
Eigen::Vector3d closest_on_box(const Box& b, const Eigen::Vector3d& p) {
  const Eigen::Vector3d local = b.world_from_box.transpose() * (p - b.centre_mm);
  const Eigen::Vector3d clamped = local.cwiseMax(-b.half_extent_mm).cwiseMin(b.half_extent_mm);
  return b.world_from_box * clamped + b.centre_mm;
}

// Closest point of a solid cylinder to p.
Eigen::Vector3d closest_on_cylinder(const Cylinder& c, const Eigen::Vector3d& p) {
  const Eigen::Vector3d f = p - c.centre_mm;
  const double axial = std::clamp(f.dot(c.axis), -c.half_length_mm, c.half_length_mm);
  Eigen::Vector3d radial = f - f.dot(c.axis) * c.axis;
  const double r = radial.norm();
  if (r > c.radius_mm) radial *= c.radius_mm / r;
  return c.centre_mm + axial * c.axis + radial;
}

// Separating-axis test of two oriented boxes, shrunk by the tolerance.
bool boxes_overlap(const Box& a, const Box& b, double tol) {
  const Eigen::Matrix3d& ra = a.world_from_box;
  const Eigen::Matrix3d& rb = b.world_from_box;
  const Eigen::Vector3d ha = (a.half_extent_mm.array() - tol).cwiseMax(0.0);
  const Eigen::Vector3d hb = (b.half_extent_mm.array() - tol).cwiseMax(0.0);
  const Eigen::Vector3d d = b.centre_mm - a.centre_mm;
  std::vector<Eigen::Vector3d> axes;
  for (int i = 0; i < 3; ++i) axes.push_back(ra.col(i));
  for (int i = 0; i < 3; ++i) axes.push_back(rb.col(i));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const Eigen::Vector3d x = ra.col(i).cross(rb.col(j));
      if (x.norm() > 1e-9) axes.push_back(x.normalized());
    }
  for (const Eigen::Vector3d& n : axes) {
    const double pa = (ra.transpose() * n).cwiseAbs().dot(ha), pb = (rb.transpose() * n).cwiseAbs().dot(hb);
    if (std::abs(d.dot(n)) >= pa + pb) return false;  // separated (touching counts as apart)
  }
  return true;
}

// Surface points for the sampled test, about n per edge or circle.
std::vector<Eigen::Vector3d> surface_samples(const Shape& s) {
  constexpr int n = 8;
  std::vector<Eigen::Vector3d> pts;
  if (const auto* m = std::get_if<TriangleMesh>(&s)) {
    const auto& v = m->vertices_mm();
    pts = v;
    for (const MeshTriangle& t : m->triangles()) pts.push_back((v[t[0]] + v[t[1]] + v[t[2]]) / 3);
  } else if (const auto* b = std::get_if<Box>(&s)) {
    for (int axis = 0; axis < 3; ++axis)
      for (int side : {-1, 1})
        for (int i = 0; i <= n; ++i)
          for (int j = 0; j <= n; ++j) {
            Eigen::Vector3d l;
            l[axis] = side * b->half_extent_mm[axis];
            l[(axis + 1) % 3] = (2.0 * i / n - 1) * b->half_extent_mm[(axis + 1) % 3];
            l[(axis + 2) % 3] = (2.0 * j / n - 1) * b->half_extent_mm[(axis + 2) % 3];
            pts.push_back(b->world_from_box * l + b->centre_mm);
          }
  } else if (const auto* c = std::get_if<Cylinder>(&s)) {
    const Eigen::Vector3d u = c->axis.unitOrthogonal(), w = c->axis.cross(u);
    for (int k = 0; k < 4 * n; ++k) {
      const double phi = 2 * M_PI * k / (4 * n);
      const Eigen::Vector3d radial = std::cos(phi) * u + std::sin(phi) * w;
      for (int i = 0; i <= n; ++i) {
        const double axial = (2.0 * i / n - 1) * c->half_length_mm;
        pts.push_back(c->centre_mm + axial * c->axis + c->radius_mm * radial);  // side
        pts.push_back(c->centre_mm + (i % 2 ? 1 : -1) * c->half_length_mm * c->axis +
                      (c->radius_mm * i / n) * radial);  // caps
      }
    }
  } else if (const auto* sp = std::get_if<Sphere>(&s)) {
    for (int k = 0; k < 16 * n; ++k) {  // Fibonacci sphere
      const double z = 1 - (2.0 * k + 1) / (16 * n), r = std::sqrt(1 - z * z), phi = 2.399963229728653 * k;
      pts.push_back(sp->centre_mm + sp->radius_mm * Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z));
    }
  }
  return pts;
}

bool sampled_overlap(const Shape& a, const Shape& b, double tol) {
  for (const Eigen::Vector3d& p : surface_samples(a))
    if (contains(b, p, tol)) return true;
  for (const Eigen::Vector3d& p : surface_samples(b))
    if (contains(a, p, tol)) return true;
  return false;
}

}  // namespace

bool overlap(const Shape& a, const Shape& b, double tol) {
  if (std::holds_alternative<Rectangle>(a) || std::holds_alternative<Rectangle>(b)) return false;
  const auto* sa = std::get_if<Sphere>(&a);
  const auto* sb = std::get_if<Sphere>(&b);
  if (sa && sb) return (sa->centre_mm - sb->centre_mm).norm() < sa->radius_mm + sb->radius_mm - tol;
  if (sb) return overlap(b, a, tol);  // sphere first
  if (sa) {
    if (const auto* box = std::get_if<Box>(&b))
      return (closest_on_box(*box, sa->centre_mm) - sa->centre_mm).norm() < sa->radius_mm - tol;
    if (const auto* cyl = std::get_if<Cylinder>(&b))
      return (closest_on_cylinder(*cyl, sa->centre_mm) - sa->centre_mm).norm() < sa->radius_mm - tol;
  }
  const auto* ba = std::get_if<Box>(&a);
  const auto* bb = std::get_if<Box>(&b);
  if (ba && bb) return boxes_overlap(*ba, *bb, tol);
  return sampled_overlap(a, b, tol);
}

std::optional<std::pair<int, int>> find_overlap(const std::vector<Shape>& shapes, double tol) {
  std::vector<Eigen::AlignedBox3d> boxes;
  boxes.reserve(shapes.size());
  for (const Shape& s : shapes) boxes.push_back(bounds_mm(s));
  std::vector<int> order(shapes.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int i, int j) { return boxes[i].min().x() < boxes[j].min().x(); });
  std::optional<std::pair<int, int>> first;
  for (std::size_t a = 0; a < order.size(); ++a) {
    for (std::size_t b = a + 1; b < order.size(); ++b) {
      const int i = order[a], j = order[b];
      if (boxes[j].min().x() >= boxes[i].max().x() - tol) break;  // sweep: nothing further overlaps i in x
      if (!boxes[i].intersects(boxes[j])) continue;
      if (!overlap(shapes[i], shapes[j], tol)) continue;
      const std::pair<int, int> p(std::min(i, j), std::max(i, j));
      if (!first || p < *first) first = p;
    }
  }
  return first;
}

}  // namespace glasspiv
