#include "core/walls/reach.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace demcal::walls {
namespace {

bool may_reach_shape(const Plane& p, const Vec3& x, double r, double range, double margin) {
  return dot(x - p.point, p.normal) - r <= range + margin;
}

bool may_reach_shape(const Cylinder& c, const Vec3& x, double r, double range, double margin) {
  const Vec3 rel = x - c.point;
  const double s = dot(rel, c.axis);
  if (s < c.lo - margin || s > c.hi + margin) return false;
  const double inner = c.radius - r - range - margin;
  return inner <= 0.0 || norm2(rel - c.axis * s) >= inner * inner;
}

/// Every point of a disk, face or rim, lies in its plane: a sphere |h| - r above it is at least
/// that far from all of them.
bool may_reach_shape(const Disk& k, const Vec3& x, double r, double range, double margin) {
  return std::abs(dot(x - k.centre, k.normal)) - r <= range + margin;
}

/// |a - b| for two ends of an extent that may be infinite (the same infinity: no change).
double end_shift(double a, double b) {
  return a == b ? 0.0 : std::abs(a - b);
}

double shift(const Plane& a, const Plane& b, double extent) {
  return norm(b.point - a.point) + extent * norm(b.normal - a.normal);
}

double shift(const Cylinder& a, const Cylinder& b, double extent) {
  return norm(b.point - a.point) + extent * norm(b.axis - a.axis) + std::abs(b.radius - a.radius) +
         std::max(end_shift(a.lo, b.lo), end_shift(a.hi, b.hi));
}

double shift(const Disk& a, const Disk& b, double extent) {
  return norm(b.centre - a.centre) + extent * norm(b.normal - a.normal);
}

double shift(const Mesh& a, const Mesh& b, double) {
  if (a.vertices.size() != b.vertices.size() || a.triangles != b.triangles)
    return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (std::size_t v = 0; v < a.vertices.size(); ++v)
    worst = std::max(worst, norm2(b.vertices[v] - a.vertices[v]));
  return std::sqrt(worst);
}

}  // namespace

ReachTest::ReachTest(const Shape& shape, double range, double margin)
    : shape_(&shape), range_(range), margin_(margin) {
  if (const Mesh* m = std::get_if<Mesh>(&shape)) m->vertex_bounds(lo_, hi_);
}

bool ReachTest::may_reach(const Vec3& x, double r) const {
  return std::visit(
      [&](const auto& s) {
        if constexpr (std::is_same_v<std::decay_t<decltype(s)>, Mesh>) {
          if (s.vertices.empty()) return false;
          const double reach = r + range_ + margin_;
          return x.x >= lo_.x - reach && x.x <= hi_.x + reach && x.y >= lo_.y - reach &&
                 x.y <= hi_.y + reach && x.z >= lo_.z - reach && x.z <= hi_.z + reach;
        } else {
          return may_reach_shape(s, x, r, range_, margin_);
        }
      },
      *shape_);
}

Vec3 reference_point(const Shape& shape) {
  return std::visit(
      [](const auto& s) -> Vec3 {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, Plane> || std::is_same_v<S, Cylinder>)
          return s.point;
        else if constexpr (std::is_same_v<S, Disk>)
          return s.centre;
        else
          return s.vertices.empty() ? Vec3{} : s.vertices[0];
      },
      shape);
}

double surface_shift(const Shape& before, const Shape& now, double extent) {
  if (before.index() != now.index()) return std::numeric_limits<double>::infinity();
  return std::visit(
      [&](const auto& a) {
        using S = std::decay_t<decltype(a)>;
        return shift(a, std::get<S>(now), extent);
      },
      before);
}

}  // namespace demcal::walls
