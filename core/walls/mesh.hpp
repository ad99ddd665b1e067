#pragma once
// Triangle-mesh walls: an indexed triangle soup (from code or STL) moved rigidly like any wall.
//
// Contact (sphere centre x, radius r): every triangle within reach gives its nearest point, on
// its face, one of its edges or one of its vertices (Ericson, Real-Time Collision Detection
// §5.1.5). Candidates are then reduced so one physical surface gives one contact:
//   - face contacts are always kept (two faces are two surfaces, e.g. a floor and a vane);
//   - an edge or vertex contact is dropped when it is "shadowed" by an accepted contact a, i.e.
//     its nearest point lies on or beyond the tangent plane of a (dot(p - x, n_a) >= d_a). On a
//     flat seam the neighbour's edge point lies in the face's plane; on a convex join the
//     neighbour's edge point is the same point; on either it is shadowed, so a sphere rolling
//     over a seam of coplanar triangles feels one force that is continuous across the seam, and
//     a convex edge gives one edge contact instead of two.
// This rule needs no vertex welding or adjacency, so it works on unwelded STL facets alike.
// History: a mesh keeps kMaxContacts history slots per particle; each slot remembers its last
// contact normal, and a new contact continues the slot whose normal is nearest (within 45 deg).
// A contact sliding across triangles of one surface (or rolling round a convex edge) changes its
// normal slowly, so it keeps its tangential spring; see forces.cpp.
#include <array>
#include <span>
#include <vector>

#include "core/common/vec3.hpp"

namespace demcal::walls {

struct WallGeometry;

struct Mesh {
  static constexpr int kMaxContacts = 4;  ///< contacts kept per particle (nearest first)
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
  /// Bounding box of the vertices, valid while `fitted`: a sphere out of its reach is rejected
  /// with one test instead of one per triangle. make_wall() and advance() keep a wall's mesh
  /// fitted; a mesh never fitted (or appended to since) tests every triangle.
  Vec3 lo, hi;
  bool fitted = false;

  std::size_t size() const { return triangles.size(); }
  /// Appends another mesh's triangles (the mesh is no longer fitted).
  void append(const Mesh& other);
  /// The vertices' bounding box (a point at the origin when there are none).
  void vertex_bounds(Vec3& box_lo, Vec3& box_hi) const;
  /// Sets lo, hi to the vertices' bounding box.
  void fit_bounds();
};

/// Nearest point on triangle (a, b, c) to p; `feature` 0 = face, 1..3 = edge ab, bc, ca,
/// 4..6 = vertex a, b, c.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                               int& feature);

/// The contacts of a sphere with a mesh (at most Mesh::kMaxContacts, deepest first), each with
/// the nearest point and n pointing from the centre into the wall; returns how many.
int mesh_contacts(const Mesh& mesh, const Vec3& x, double r, double range, WallGeometry* out);
/// The same among the triangles `candidates` (indices, ascending) only: the same contacts when
/// they hold every triangle within reach (mesh_candidates).
int mesh_contacts(const Mesh& mesh, std::span<const int> candidates, const Vec3& x, double r,
                  double range, WallGeometry* out);
/// Appends, ascending, the triangles whose bounding box comes within `reach` of x: every
/// triangle a sphere of radius r at x touches or comes within range of, for reach >= r + range.
void mesh_candidates(const Mesh& mesh, const Vec3& x, double reach, std::vector<int>& out);

// Builders. Triangles are two-sided: either face touches particles.
/// Quad corner, corner+u, corner+u+v, corner+v (two triangles).
Mesh make_quad(const Vec3& corner, const Vec3& u, const Vec3& v);
/// The six faces of an axis-aligned box (12 triangles).
Mesh make_box(const Vec3& lo, const Vec3& hi);
/// A flat disk as a fan of `segments` triangles.
Mesh make_disk(const Vec3& centre, const Vec3& normal, double radius, int segments = 24);
/// A shear head (seed 000 §2.7.4, FT4): a disk of `radius` at `centre` facing -axis, with
/// `vanes` radial blades of height `vane_height` hanging below it along -axis.
Mesh make_vane_head(const Vec3& centre, const Vec3& axis, double radius, double vane_height,
                    int vanes, int segments = 24);
/// A wedge hopper slice (seed 000 §2.7.6): two planar walls inclined `half_angle` (rad) from the
/// vertical, their lower edges `outlet` apart at z = 0, x symmetric about 0, reaching height
/// `height`, spanning y in [y_lo, y_hi]; above them vertical walls up to z = height + `bin`.
Mesh make_wedge_hopper(double half_angle, double outlet, double height, double bin, double y_lo,
                       double y_hi);

}  // namespace demcal::walls
