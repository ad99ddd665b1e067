#include "core/walls/mesh.hpp"

#include <algorithm>
#include <cmath>

#include "core/walls/wall.hpp"

namespace demcal::walls {

void Mesh::append(const Mesh& other) {
  const int base = static_cast<int>(vertices.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  for (const auto& t : other.triangles)
    triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  fitted = false;
}

void Mesh::vertex_bounds(Vec3& box_lo, Vec3& box_hi) const {
  box_lo = box_hi = vertices.empty() ? Vec3{} : vertices.front();
  for (const auto& v : vertices)
    for (int k = 0; k < 3; ++k) {
      box_lo[k] = std::min(box_lo[k], v[k]);
      box_hi[k] = std::max(box_hi[k], v[k]);
    }
}

void Mesh::fit_bounds() {
  vertex_bounds(lo, hi);
  fitted = true;
}

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                               int& feature) {
  // Voronoi regions of the triangle (Ericson §5.1.5).
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    feature = 4;
    return a;
  }
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) {
    feature = 5;
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    feature = 1;
    return a + ab * (d1 / (d1 - d3));
  }
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) {
    feature = 6;
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    feature = 3;
    return a + ac * (d2 / (d2 - d6));
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    feature = 2;
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  feature = 0;
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

namespace {

/// Whether triangle t's bounding box lies farther than `reach` from x along some axis: then the
/// triangle does too.
bool box_out_of_reach(const Mesh& mesh, const std::array<int, 3>& t, const Vec3& x, double reach) {
  const auto& v = mesh.vertices;
  const Vec3 &a = v[t[0]], &b = v[t[1]], &c = v[t[2]];
  for (int k = 0; k < 3; ++k)
    if (std::min({a[k], b[k], c[k]}) > x[k] + reach || std::max({a[k], b[k], c[k]}) < x[k] - reach)
      return true;
  return false;
}

/// mesh_contacts over the triangles `each_triangle(visit)` hands to visit, in ascending order.
template <class EachTriangle>
int contacts_among(const Mesh& mesh, const Vec3& x, double r, double range, WallGeometry* out,
                   EachTriangle each_triangle) {
  struct Candidate {
    Vec3 point;
    double dist;
    bool face;
  };
  constexpr int kMaxCandidates = 32;
  std::array<Candidate, kMaxCandidates> cand;
  int n_cand = 0;
  const double reach = r + range;
  if (mesh.fitted)
    for (int k = 0; k < 3; ++k)
      if (x[k] + reach < mesh.lo[k] || x[k] - reach > mesh.hi[k]) return 0;
  const auto& v = mesh.vertices;
  each_triangle([&](const std::array<int, 3>& t) {
    // Box rejection before the Voronoi search.
    if (box_out_of_reach(mesh, t, x, reach)) return;
    const Vec3 &a = v[t[0]], &b = v[t[1]], &c = v[t[2]];
    int feature = 0;
    const Vec3 q = closest_point_on_triangle(x, a, b, c, feature);
    const double d2 = norm2(q - x);
    if (d2 > reach * reach || d2 == 0.0) return;
    if (n_cand == kMaxCandidates) {
      // Keep the nearest kMaxCandidates (only dense fans around a vertex get here).
      auto far = std::max_element(cand.begin(), cand.end(),
                                  [](const auto& l, const auto& m) { return l.dist < m.dist; });
      if (far->dist * far->dist <= d2) return;
      *far = {q, std::sqrt(d2), feature == 0};
      return;
    }
    cand[n_cand++] = {q, std::sqrt(d2), feature == 0};
  });
  if (n_cand == 0) return 0;
  // Faces first, then edges and vertices, each nearest first; a non-face candidate shadowed by an
  // accepted contact (its point on or beyond that contact's tangent plane) is the same surface.
  std::sort(cand.begin(), cand.begin() + n_cand, [](const Candidate& l, const Candidate& m) {
    if (l.face != m.face) return l.face;
    return l.dist < m.dist;
  });
  std::array<Candidate, kMaxCandidates> kept;
  std::array<Vec3, kMaxCandidates> dir;
  int n_kept = 0;
  for (int i = 0; i < n_cand; ++i) {
    const Candidate& c = cand[i];
    const Vec3 u = (c.point - x) / c.dist;
    bool shadowed = false;
    if (!c.face)
      for (int k = 0; k < n_kept && !shadowed; ++k)
        shadowed = dot(c.point - x, dir[k]) >= kept[k].dist * (1.0 - 1e-9);
    if (shadowed) continue;
    dir[n_kept] = u;
    kept[n_kept++] = c;
  }
  // Deepest first, at most kMaxContacts.
  std::array<int, kMaxCandidates> order;
  for (int i = 0; i < n_kept; ++i) order[i] = i;
  std::sort(order.begin(), order.begin() + n_kept,
            [&](int l, int m) { return kept[l].dist < kept[m].dist; });
  const int n = std::min(n_kept, Mesh::kMaxContacts);
  for (int i = 0; i < n; ++i) {
    const int k = order[i];
    out[i].n = dir[k];
    out[i].delta = r - kept[k].dist;
    out[i].point = kept[k].point;
  }
  return n;
}

}  // namespace

int mesh_contacts(const Mesh& mesh, const Vec3& x, double r, double range, WallGeometry* out) {
  return contacts_among(mesh, x, r, range, out, [&](auto visit) {
    for (const auto& t : mesh.triangles) visit(t);
  });
}

int mesh_contacts(const Mesh& mesh, std::span<const int> candidates, const Vec3& x, double r,
                  double range, WallGeometry* out) {
  return contacts_among(mesh, x, r, range, out, [&](auto visit) {
    for (const int t : candidates) visit(mesh.triangles[static_cast<std::size_t>(t)]);
  });
}

void mesh_candidates(const Mesh& mesh, const Vec3& x, double reach, std::vector<int>& out) {
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    if (!box_out_of_reach(mesh, mesh.triangles[t], x, reach)) out.push_back(static_cast<int>(t));
}

Mesh make_quad(const Vec3& corner, const Vec3& u, const Vec3& v) {
  Mesh m;
  m.vertices = {corner, corner + u, corner + u + v, corner + v};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

Mesh make_box(const Vec3& lo, const Vec3& hi) {
  const Vec3 d = hi - lo;
  const Vec3 ex{d.x, 0, 0}, ey{0, d.y, 0}, ez{0, 0, d.z};
  Mesh m;
  m.append(make_quad(lo, ey, ex));
  m.append(make_quad(lo + ez, ex, ey));
  m.append(make_quad(lo, ex, ez));
  m.append(make_quad(lo + ey, ez, ex));
  m.append(make_quad(lo, ez, ey));
  m.append(make_quad(lo + ex, ey, ez));
  return m;
}

namespace {
void basis(const Vec3& n, Vec3& u, Vec3& w) {
  const Vec3 t = std::abs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  u = normalized(cross(n, t));
  w = cross(n, u);
}
}  // namespace

Mesh make_disk(const Vec3& centre, const Vec3& normal, double radius, int segments) {
  Vec3 u, w;
  basis(normalized(normal), u, w);
  Mesh m;
  m.vertices.push_back(centre);
  for (int s = 0; s < segments; ++s) {
    const double phi = 2.0 * M_PI * s / segments;
    m.vertices.push_back(centre + (u * std::cos(phi) + w * std::sin(phi)) * radius);
  }
  for (int s = 0; s < segments; ++s) m.triangles.push_back({0, 1 + s, 1 + (s + 1) % segments});
  return m;
}

Mesh make_vane_head(const Vec3& centre, const Vec3& axis, double radius, double vane_height,
                    int vanes, int segments) {
  const Vec3 a = normalized(axis);
  Vec3 u, w;
  basis(a, u, w);
  Mesh m = make_disk(centre, a, radius, segments);
  for (int k = 0; k < vanes; ++k) {
    const double phi = 2.0 * M_PI * k / vanes;
    const Vec3 radial = (u * std::cos(phi) + w * std::sin(phi)) * radius;
    m.append(make_quad(centre, radial, -a * vane_height));
  }
  return m;
}

Mesh make_wedge_hopper(double half_angle, double outlet, double height, double bin, double y_lo,
                       double y_hi) {
  const double spread = height * std::tan(half_angle);
  const double xo = 0.5 * outlet, xt = xo + spread;
  const Vec3 ey{0, y_hi - y_lo, 0};
  Mesh m;
  m.append(make_quad({-xo, y_lo, 0}, ey, {-spread, 0, height}));
  m.append(make_quad({xo, y_lo, 0}, ey, {spread, 0, height}));
  if (bin > 0.0) {
    m.append(make_quad({-xt, y_lo, height}, ey, {0, 0, bin}));
    m.append(make_quad({xt, y_lo, height}, ey, {0, 0, bin}));
  }
  return m;
}

}  // namespace demcal::walls
