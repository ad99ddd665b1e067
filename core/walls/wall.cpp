#include "core/walls/wall.hpp"

#include <cmath>

namespace demcal::walls {

bool wall_geometry(const Shape& shape, const Vec3& x, double r, double range, WallGeometry& out) {
  return std::visit(
      [&](const auto& s) {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, Mesh>) {
          // mesh_contacts writes up to kMaxContacts contacts, the deepest first.
          WallGeometry contacts[Mesh::kMaxContacts];
          if (mesh_contacts(s, x, r, range, contacts) == 0) return false;
          out = contacts[0];
          return true;
        } else
          return primitive_geometry(s, x, r, range, out);
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
