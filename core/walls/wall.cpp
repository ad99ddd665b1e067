#include "core/walls/wall.hpp"

#include <cmath>

namespace demcal::walls {
namespace {

bool plane_geometry(const Plane& p, const Vec3& x, double r, double range, WallGeometry& g) {
  const double d = dot(x - p.point, p.normal);
  g.delta = r - d;
  if (-g.delta > range) return false;
  g.n = -p.normal;
  g.point = x - p.normal * d;
  return true;
}

bool cylinder_geometry(const Cylinder& c, const Vec3& x, double r, double range, WallGeometry& g) {
  const Vec3 rel = x - c.point;
  const double s = dot(rel, c.axis);
  if (s < c.lo || s > c.hi) return false;
  const Vec3 radial = rel - c.axis * s;
  const double rho = norm(radial);
  g.delta = r - (c.radius - rho);
  if (-g.delta > range || rho == 0.0) return false;
  g.n = radial / rho;
  g.point = c.point + c.axis * s + g.n * c.radius;
  return true;
}

bool disk_geometry(const Disk& k, const Vec3& x, double r, double range, WallGeometry& g) {
  const Vec3 rel = x - k.centre;
  const double h = dot(rel, k.normal);
  const Vec3 in_plane = rel - k.normal * h;
  const double rho = norm(in_plane);
  if (rho <= k.radius) {
    // Face contact on whichever side the sphere is.
    g.delta = r - std::abs(h);
    if (-g.delta > range) return false;
    g.n = h >= 0.0 ? -k.normal : k.normal;
    g.point = x - k.normal * h;
    return true;
  }
  // Rim contact: nearest point on the edge circle.
  const Vec3 rim = k.centre + in_plane * (k.radius / rho);
  const Vec3 to_rim = rim - x;
  const double d = norm(to_rim);
  g.delta = r - d;
  if (-g.delta > range || d == 0.0) return false;
  g.n = to_rim / d;
  g.point = rim;
  return true;
}

}  // namespace

bool wall_geometry(const Shape& shape, const Vec3& x, double r, double range, WallGeometry& out) {
  return std::visit(
      [&](const auto& s) {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, Plane>)
          return plane_geometry(s, x, r, range, out);
        else if constexpr (std::is_same_v<S, Cylinder>)
          return cylinder_geometry(s, x, r, range, out);
        else if constexpr (std::is_same_v<S, Disk>)
          return disk_geometry(s, x, r, range, out);
        else
          return mesh_contacts(s, x, r, range, &out) > 0;
      },
      shape);
}

Wall make_wall(std::string name, Shape shape, std::uint16_t material) {
  Wall w;
  w.name = std::move(name);
  w.pivot = std::visit(
      [](const auto& s) {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, Disk>) {
          return s.centre;
        } else if constexpr (std::is_same_v<S, Mesh>) {
          Vec3 c{};
          for (const auto& v : s.vertices) c += v;
          return s.vertices.empty() ? c : c / static_cast<double>(s.vertices.size());
        } else {
          return s.point;
        }
      },
      shape);
  w.shape = std::move(shape);
  if (auto* mesh = std::get_if<Mesh>(&w.shape)) mesh->fit_bounds();
  w.material = material;
  return w;
}

void advance(Wall& wall, double dt) {
  const Vec3 shift = wall.velocity * dt;
  wall.displacement += shift;
  wall.pivot += shift;
  const double w = norm(wall.omega);
  const double angle = w * dt;
  const Vec3 axis = w > 0.0 ? wall.omega / w : Vec3{0, 0, 1};
  auto move_point = [&](Vec3& p) {
    p += shift;
    if (angle != 0.0) p = wall.pivot + rotate(p - wall.pivot, axis, angle);
  };
  auto turn = [&](Vec3& dir) {
    if (angle != 0.0) dir = rotate(dir, axis, angle);
  };
  std::visit(
      [&](auto& s) {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, Plane>) {
          move_point(s.point);
          turn(s.normal);
        } else if constexpr (std::is_same_v<S, Cylinder>) {
          move_point(s.point);
          turn(s.axis);
        } else if constexpr (std::is_same_v<S, Disk>) {
          move_point(s.centre);
          turn(s.normal);
        } else {
          for (auto& v : s.vertices) move_point(v);
          if (s.fitted) s.fit_bounds();
        }
      },
      wall.shape);
}

}  // namespace demcal::walls
