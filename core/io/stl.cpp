#include "core/io/stl.hpp"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

#include "core/common/error.hpp"
#include "core/io/read_file.hpp"

namespace demcal::io {
namespace {

/// Adds facets, merging vertices that coincide exactly (STL repeats every shared vertex).
class MeshBuilder {
 public:
  void add(const Vec3& a, const Vec3& b, const Vec3& c) {
    mesh_.triangles.push_back({index(a), index(b), index(c)});
  }
  walls::Mesh take() { return std::move(mesh_); }

 private:
  int index(const Vec3& v) {
    const auto key = std::make_tuple(v.x, v.y, v.z);
    auto it = ids_.find(key);
    if (it != ids_.end()) return it->second;
    const int id = static_cast<int>(mesh_.vertices.size());
    mesh_.vertices.push_back(v);
    ids_.emplace(key, id);
    return id;
  }
  walls::Mesh mesh_;
  std::map<std::tuple<double, double, double>, int> ids_;
};

Vec3 facet_normal(const walls::Mesh& m, const std::array<int, 3>& t) {
  const Vec3 n = cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]);
  const double l = norm(n);
  return l > 0.0 ? n / l : Vec3{};
}

walls::Mesh read_ascii(const std::string& text, const std::string& path, double scale) {
  std::istringstream in(text);
  MeshBuilder b;
  std::string word;
  Vec3 v[3];
  int nv = 0;
  while (in >> word) {
    if (word == "vertex") {
      if (nv == 3) throw InputError(path, "facet with more than three vertices");
      if (!(in >> v[nv].x >> v[nv].y >> v[nv].z)) throw InputError(path, "malformed vertex");
      v[nv] = v[nv] * scale;
      ++nv;
    } else if (word == "endloop") {
      if (nv != 3) throw InputError(path, "facet without three vertices");
      b.add(v[0], v[1], v[2]);
      nv = 0;
    }
  }
  walls::Mesh m = b.take();
  if (m.triangles.empty()) throw InputError(path, "no facets in ASCII STL");
  return m;
}

walls::Mesh read_binary(const std::string& data, const std::string& path, double scale) {
  std::uint32_t count = 0;
  std::memcpy(&count, data.data() + 80, 4);
  if (data.size() < 84 + 50ull * count)
    throw InputError(path, "binary STL shorter than its " + std::to_string(count) + " facets");
  MeshBuilder b;
  for (std::uint32_t f = 0; f < count; ++f) {
    const char* rec = data.data() + 84 + 50ull * f + 12;  // skip the normal
    Vec3 v[3];
    for (int k = 0; k < 3; ++k) {
      float xyz[3];
      std::memcpy(xyz, rec + 12 * k, 12);
      v[k] = Vec3{xyz[0], xyz[1], xyz[2]} * scale;
    }
    b.add(v[0], v[1], v[2]);
  }
  return b.take();
}

}  // namespace

walls::Mesh read_stl(const std::string& path, double scale) {
  return parse_stl(read_file(path, "STL file"), path, scale);
}

walls::Mesh parse_stl(const std::string& data, const std::string& path, double scale) {
  // Binary files may also start with "solid": trust the facet count when it matches the size.
  if (data.size() >= 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, data.data() + 80, 4);
    if (data.size() == 84 + 50ull * count) return read_binary(data, path, scale);
  }
  if (data.compare(0, 5, "solid") == 0) return read_ascii(data, path, scale);
  if (data.size() < 84) throw InputError(path, "not an STL file (too short)");
  return read_binary(data, path, scale);
}

void write_stl_ascii(const std::string& path, const walls::Mesh& m, const std::string& name) {
  std::ofstream out(path);
  if (!out) throw InputError(path, "cannot write STL file");
  out.precision(17);
  out << "solid " << name << "\n";
  for (const auto& t : m.triangles) {
    const Vec3 n = facet_normal(m, t);
    out << "  facet normal " << n.x << " " << n.y << " " << n.z << "\n    outer loop\n";
    for (int k : t) {
      const Vec3& v = m.vertices[k];
      out << "      vertex " << v.x << " " << v.y << " " << v.z << "\n";
    }
    out << "    endloop\n  endfacet\n";
  }
  out << "endsolid " << name << "\n";
}

void write_stl_binary(const std::string& path, const walls::Mesh& m) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw InputError(path, "cannot write STL file");
  char header[80] = "demcal binary STL";
  out.write(header, 80);
  const auto count = static_cast<std::uint32_t>(m.triangles.size());
  out.write(reinterpret_cast<const char*>(&count), 4);
  for (const auto& t : m.triangles) {
    float rec[12];
    const Vec3 n = facet_normal(m, t);
    rec[0] = static_cast<float>(n.x), rec[1] = static_cast<float>(n.y),
    rec[2] = static_cast<float>(n.z);
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) rec[3 + 3 * k + c] = static_cast<float>(m.vertices[t[k]][c]);
    out.write(reinterpret_cast<const char*>(rec), 48);
    const std::uint16_t attr = 0;
    out.write(reinterpret_cast<const char*>(&attr), 2);
  }
}

}  // namespace demcal::io
