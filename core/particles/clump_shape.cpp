#include "core/particles/clump_shape.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "core/common/error.hpp"
#include "core/common/rng.hpp"

namespace demcal::particles {

ShapeKind parse_shape_kind(const std::string& text, const std::string& where) {
  if (text == "sphere") return ShapeKind::kSphere;
  if (text == "rod") return ShapeKind::kRod;
  if (text == "helix") return ShapeKind::kHelix;
  if (text == "cluster") return ShapeKind::kCluster;
  throw InputError(where, "unknown shape '" + text + "' (known: sphere, rod, helix, cluster)");
}

std::string shape_kind_name(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::kSphere:
      return "sphere";
    case ShapeKind::kRod:
      return "rod";
    case ShapeKind::kHelix:
      return "helix";
    case ShapeKind::kCluster:
      return "cluster";
  }
  return "sphere";
}

std::vector<std::string> shape_params(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::kSphere:
      return {};
    case ShapeKind::kRod:
      return {"aspect_ratio", "spacing"};
    case ShapeKind::kHelix:
      return {"aspect_ratio", "offset_ratio", "revolutions", "spacing"};
    case ShapeKind::kCluster:
      return {"spheres", "irregularity", "seed", "spread"};
  }
  return {};
}

ShapeSpec make_shape_spec(const std::string& kind, const std::map<std::string, double>& params,
                          const std::string& where) {
  const ShapeKind k = parse_shape_kind(kind, where + ".kind");
  contact::require_own_params(params, shape_params(k), where, "shape '" + kind + "'");
  ShapeSpec s = contact::params_from_map<ShapeSpec>(params, where);
  s.kind = k;
  return s;
}

std::map<std::string, double> shape_values(const ShapeSpec& shape) {
  std::map<std::string, double> out;
  const auto own = shape_params(shape.kind);
  for (const auto& info : ShapeSpec::table())
    if (std::find(own.begin(), own.end(), std::string(info.name)) != own.end())
      out[std::string(info.name)] = shape.*info.field;
  return out;
}

namespace {

/// Moments of one column of the grid: the union of the spheres' chords through (x, y) merged,
/// and the integrals of 1, z and z^2 over it added to the running sums.
struct Moments {
  double m0 = 0, mx = 0, my = 0, mz = 0, xx = 0, yy = 0, zz = 0, xy = 0, xz = 0, yz = 0;
};

void add_column(double x, double y, double area, const std::vector<Vec3>& c,
                const std::vector<double>& r, std::vector<std::pair<double, double>>& chords,
                Moments& m) {
  chords.clear();
  for (std::size_t k = 0; k < c.size(); ++k) {
    const double h2 = r[k] * r[k] - (x - c[k].x) * (x - c[k].x) - (y - c[k].y) * (y - c[k].y);
    if (h2 > 0.0) chords.emplace_back(c[k].z - std::sqrt(h2), c[k].z + std::sqrt(h2));
  }
  if (chords.empty()) return;
  std::sort(chords.begin(), chords.end());
  auto integrate = [&](double a, double b) {
    const double l = b - a, s1 = 0.5 * (b * b - a * a), s2 = (b * b * b - a * a * a) / 3.0;
    m.m0 += area * l;
    m.mx += area * x * l;
    m.my += area * y * l;
    m.mz += area * s1;
    m.xx += area * x * x * l;
    m.yy += area * y * y * l;
    m.zz += area * s2;
    m.xy += area * x * y * l;
    m.xz += area * x * s1;
    m.yz += area * y * s1;
  };
  double a = chords[0].first, b = chords[0].second;
  for (std::size_t k = 1; k < chords.size(); ++k) {
    if (chords[k].first > b) {
      integrate(a, b);
      a = chords[k].first;
    }
    b = std::max(b, chords[k].second);
  }
  integrate(a, b);
}

MassProperties integrate_on_grid(const std::vector<Vec3>& c, const std::vector<double>& r, int n) {
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (std::size_t k = 0; k < c.size(); ++k)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], c[k][a] - r[k]);
      hi[a] = std::max(hi[a], c[k][a] + r[k]);
    }
  const double hx = (hi.x - lo.x) / n, hy = (hi.y - lo.y) / n;
  Moments m;
  std::vector<std::pair<double, double>> chords;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      add_column(lo.x + (i + 0.5) * hx, lo.y + (j + 0.5) * hy, hx * hy, c, r, chords, m);
  MassProperties p;
  p.volume = m.m0;
  p.centroid = Vec3{m.mx, m.my, m.mz} / m.m0;
  const Vec3& g = p.centroid;
  // Second moments about the centroid (parallel-axis shift), then I = tr(S) 1 - S.
  const double sxx = m.xx - m.m0 * g.x * g.x, syy = m.yy - m.m0 * g.y * g.y,
               szz = m.zz - m.m0 * g.z * g.z, sxy = m.xy - m.m0 * g.x * g.y,
               sxz = m.xz - m.m0 * g.x * g.z, syz = m.yz - m.m0 * g.y * g.z;
  p.inertia = {{{syy + szz, -sxy, -sxz}, {-sxy, sxx + szz, -syz}, {-sxz, -syz, sxx + syy}}};
  p.columns = n;
  return p;
}

double trace(const MassProperties& p) {
  return p.inertia[0][0] + p.inertia[1][1] + p.inertia[2][2];
}

/// Shoemake's uniform random direction from two uniforms.
Vec3 random_direction(Rng& rng) {
  const double z = rng.uniform(-1.0, 1.0), phi = 2.0 * M_PI * rng.uniform();
  const double s = std::sqrt(1.0 - z * z);
  return {s * std::cos(phi), s * std::sin(phi), z};
}

}  // namespace

MassProperties union_mass_properties(const std::vector<Vec3>& centres,
                                     const std::vector<double>& radii, double tolerance) {
  if (centres.empty() || centres.size() != radii.size())
    throw InputError("shape", "a clump needs at least one sphere and one radius per sphere");
  MassProperties last = integrate_on_grid(centres, radii, 64);
  for (int n = 128; n <= 4096; n *= 2) {
    MassProperties next = integrate_on_grid(centres, radii, n);
    const bool converged = std::abs(next.volume - last.volume) < tolerance * next.volume &&
                           std::abs(trace(next) - trace(last)) < tolerance * trace(next);
    last = next;
    if (converged) return last;
  }
  return last;
}

namespace {

/// Leaves out every sphere that lies inside another one (an earlier one of two equal ones is
/// kept): it adds nothing to the union, and as a member it would only double the contacts of
/// the sphere around it.
void drop_enclosed(std::vector<Vec3>& centres, std::vector<double>& radii) {
  const auto inside = [&](std::size_t k, std::size_t j) {
    const double gap = norm(centres[k] - centres[j]), slack = 1e-12 * radii[j];
    if (gap + radii[k] > radii[j] + slack) return false;
    const bool equal = gap + radii[j] <= radii[k] + slack;
    return !equal || j < k;
  };
  std::vector<Vec3> kept_centres;
  std::vector<double> kept_radii;
  for (std::size_t k = 0; k < centres.size(); ++k) {
    bool enclosed = false;
    for (std::size_t j = 0; j < centres.size() && !enclosed; ++j) enclosed = j != k && inside(k, j);
    if (enclosed) continue;
    kept_centres.push_back(centres[k]);
    kept_radii.push_back(radii[k]);
  }
  centres = std::move(kept_centres);
  radii = std::move(kept_radii);
}

}  // namespace

void shape_spheres(const ShapeSpec& s, std::vector<Vec3>& centres, std::vector<double>& radii) {
  centres.clear();
  radii.clear();
  if (s.kind == ShapeKind::kSphere) {
    centres.push_back({});
    radii.push_back(1.0);
    return;
  }
  if (s.kind == ShapeKind::kCluster) {
    // Sphere k touches a random earlier sphere at a random direction, its centre between half
    // (compact) and nine tenths (spread) of the radii sum away: always overlapping, so connected.
    Rng rng(static_cast<std::uint64_t>(s.seed));
    const int n = static_cast<int>(std::lround(s.spheres));
    centres.push_back({});
    radii.push_back(1.0);
    for (int k = 1; k < n; ++k) {
      const double rk = 1.0 - 0.4 * s.irregularity * rng.uniform();
      const std::size_t j = static_cast<std::size_t>(rng.uniform() * k) % centres.size();
      const double d = (radii[j] + rk) * (0.5 + 0.4 * s.irregularity);
      centres.push_back(centres[j] + d * random_direction(rng));
      radii.push_back(rk);
    }
    for (auto& c : centres) c *= s.spread;
    drop_enclosed(centres, radii);
    return;
  }
  // Rod and helix: equal spheres of radius 1 along x from -(AR - 1) to AR - 1, so the length is
  // 2 AR; neighbours at most spacing * 2 apart. The helix displaces centre k by offset from the
  // axis at the angle 2 pi revolutions k / (n - 1) (seed 004 §2.2.2.1, Table 2.1, eq. 2.1).
  const double half = s.aspect_ratio - 1.0;
  const int n = 1 + static_cast<int>(std::ceil(2.0 * half / (2.0 * s.spacing) - 1e-9));
  const double offset = s.kind == ShapeKind::kHelix ? 2.0 * s.offset_ratio : 0.0;
  for (int k = 0; k < n; ++k) {
    const double t = n == 1 ? 0.5 : static_cast<double>(k) / (n - 1);
    const double angle = 2.0 * M_PI * s.revolutions * t;
    centres.push_back({-half + 2.0 * half * t, offset * std::cos(angle), offset * std::sin(angle)});
    radii.push_back(1.0);
  }
}

ClumpTemplate make_template(const ShapeSpec& shape) {
  std::vector<Vec3> centres;
  std::vector<double> radii;
  shape_spheres(shape, centres, radii);
  const MassProperties p = union_mass_properties(centres, radii);

  // Principal axes: eigenvectors of the inertia tensor, made a right-handed rotation.
  Eigen::Matrix3d inertia;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) inertia(a, b) = p.inertia[a][b];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(inertia);
  Eigen::Matrix3d axes = eig.eigenvectors();
  if (axes.determinant() < 0.0) axes.col(2) *= -1.0;

  // Scale to a volume-equivalent radius of 1: lengths by k, volume k^3, inertia k^5.
  const double k = std::cbrt(4.0 / 3.0 * M_PI / p.volume);
  ClumpTemplate t;
  for (std::size_t i = 0; i < centres.size(); ++i) {
    const Vec3 d = centres[i] - p.centroid;
    const Eigen::Vector3d b = axes.transpose() * Eigen::Vector3d(d.x, d.y, d.z) * k;
    t.offsets.push_back({b.x(), b.y(), b.z()});
    t.radii.push_back(radii[i] * k);
    t.bounding_radius = std::max(t.bounding_radius, norm(t.offsets.back()) + t.radii.back());
    t.sphere_volume_sum += 4.0 / 3.0 * M_PI * std::pow(t.radii.back(), 3);
  }
  t.volume = p.volume * k * k * k;
  const double k5 = std::pow(k, 5);
  t.inertia = {eig.eigenvalues()(0) * k5, eig.eigenvalues()(1) * k5, eig.eigenvalues()(2) * k5};
  return t;
}

}  // namespace demcal::particles
