#include "core/io/vtk.hpp"

#include <cmath>
#include <fstream>
#include <vector>

#include "core/common/error.hpp"

namespace demcal::io {
namespace {

std::ofstream open_vtk(const std::string& path, const char* title) {
  std::ofstream out(path);
  if (!out) throw InputError(path, "cannot write file");
  out.precision(10);
  out << "# vtk DataFile Version 3.0\n" << title << "\nASCII\nDATASET POLYDATA\n";
  return out;
}

void write_vectors(std::ofstream& out, const char* name, const std::vector<Vec3>& v) {
  out << "VECTORS " << name << " double\n";
  for (const auto& a : v) out << a.x << " " << a.y << " " << a.z << "\n";
}

/// Two unit vectors spanning the plane normal to n.
void basis(const Vec3& n, Vec3& u, Vec3& w) {
  const Vec3 a = std::abs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  u = normalized(cross(n, a));
  w = cross(n, u);
}

}  // namespace

void write_particles_vtk(const std::string& path, const sim::World& world) {
  const auto& p = world.particles;
  auto out = open_vtk(path, "demcal particles");
  out << "POINTS " << p.size() << " double\n";
  for (const auto& x : p.x) out << x.x << " " << x.y << " " << x.z << "\n";
  out << "VERTICES " << p.size() << " " << 2 * p.size() << "\n";
  for (std::size_t i = 0; i < p.size(); ++i) out << "1 " << i << "\n";
  out << "POINT_DATA " << p.size() << "\nSCALARS radius double 1\nLOOKUP_TABLE default\n";
  for (double r : p.radius) out << r << "\n";
  out << "SCALARS material int 1\nLOOKUP_TABLE default\n";
  for (auto m : p.material) out << m << "\n";
  write_vectors(out, "velocity", p.v);
  write_vectors(out, "angular_velocity", p.omega);
  write_vectors(out, "force", p.f);
}

void write_walls_vtk(const std::string& path, const sim::World& world, double extent) {
  constexpr int kSegments = 48;
  std::vector<Vec3> points;
  std::vector<std::vector<int>> polygons;
  std::vector<int> wall_of_polygon;
  for (std::size_t k = 0; k < world.walls.size(); ++k) {
    std::visit(
        [&](const auto& s) {
          using S = std::decay_t<decltype(s)>;
          const int base = static_cast<int>(points.size());
          if constexpr (std::is_same_v<S, walls::Plane>) {
            Vec3 u, w;
            basis(s.normal, u, w);
            for (int c = 0; c < 4; ++c) {
              const double a = (c == 0 || c == 3) ? -extent : extent, b = c < 2 ? -extent : extent;
              points.push_back(s.point + u * a + w * b);
            }
            polygons.push_back({base, base + 1, base + 2, base + 3});
            wall_of_polygon.push_back(static_cast<int>(k));
          } else if constexpr (std::is_same_v<S, walls::Cylinder>) {
            Vec3 u, w;
            basis(s.axis, u, w);
            const double lo = std::isfinite(s.lo) ? s.lo : -extent,
                         hi = std::isfinite(s.hi) ? s.hi : extent;
            for (int c = 0; c < kSegments; ++c) {
              const double phi = 2.0 * M_PI * c / kSegments;
              const Vec3 radial = (u * std::cos(phi) + w * std::sin(phi)) * s.radius;
              points.push_back(s.point + s.axis * lo + radial);
              points.push_back(s.point + s.axis * hi + radial);
            }
            for (int c = 0; c < kSegments; ++c) {
              const int a = base + 2 * c, b = base + 2 * ((c + 1) % kSegments);
              polygons.push_back({a, b, b + 1, a + 1});
              wall_of_polygon.push_back(static_cast<int>(k));
            }
          } else if constexpr (std::is_same_v<S, walls::Mesh>) {
            points.insert(points.end(), s.vertices.begin(), s.vertices.end());
            for (const auto& t : s.triangles) {
              polygons.push_back({base + t[0], base + t[1], base + t[2]});
              wall_of_polygon.push_back(static_cast<int>(k));
            }
          } else {
            Vec3 u, w;
            basis(s.normal, u, w);
            std::vector<int> poly;
            for (int c = 0; c < kSegments; ++c) {
              const double phi = 2.0 * M_PI * c / kSegments;
              points.push_back(s.centre + (u * std::cos(phi) + w * std::sin(phi)) * s.radius);
              poly.push_back(base + c);
            }
            polygons.push_back(poly);
            wall_of_polygon.push_back(static_cast<int>(k));
          }
        },
        world.walls[k].shape);
  }
  auto out = open_vtk(path, "demcal walls");
  out << "POINTS " << points.size() << " double\n";
  for (const auto& x : points) out << x.x << " " << x.y << " " << x.z << "\n";
  std::size_t size = 0;
  for (const auto& poly : polygons) size += poly.size() + 1;
  out << "POLYGONS " << polygons.size() << " " << size << "\n";
  for (const auto& poly : polygons) {
    out << poly.size();
    for (int id : poly) out << " " << id;
    out << "\n";
  }
  out << "CELL_DATA " << polygons.size() << "\nSCALARS wall int 1\nLOOKUP_TABLE default\n";
  for (int w : wall_of_polygon) out << w << "\n";
}

}  // namespace demcal::io
