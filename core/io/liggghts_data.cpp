#include "core/io/liggghts_data.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "core/common/error.hpp"

namespace demcal::io {
namespace {

struct Atom {
  int type = 1;
  double diameter = 0.0, density = 0.0;
  Vec3 x, v, omega;
};

double sphere_density(double mass, double radius) {
  return mass / (4.0 / 3.0 * M_PI * radius * radius * radius);
}

/// The line without its trailing '#' comment and surrounding blanks.
std::string strip(const std::string& line) {
  std::string s = line.substr(0, line.find('#'));
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

class DataReader {
 public:
  explicit DataReader(const std::string& path) : path_(path), in_(path) {
    if (!in_) throw InputError(path, "cannot open the data file");
  }

  DataBox read(std::map<long, Atom>& atoms) {
    std::string line;
    next_raw(line);  // the title line is free text
    std::string section;
    while (next(line)) {
      if (line == "Atoms" || line == "Velocities") {
        section = line;
        continue;
      }
      if (section.empty()) {
        read_header(line);
      } else if (section == "Atoms") {
        read_atom(line, atoms);
      } else {
        read_velocity(line, atoms);
      }
    }
    if (atoms.size() != expected_)
      fail("expected " + std::to_string(expected_) + " atoms, read " +
           std::to_string(atoms.size()));
    return box_;
  }

 private:
  bool next_raw(std::string& line) {
    if (!std::getline(in_, line)) return false;
    ++line_no_;
    return true;
  }
  /// The next non-blank line, comments stripped.
  bool next(std::string& line) {
    while (next_raw(line)) {
      line = strip(line);
      if (!line.empty()) return true;
    }
    return false;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(path_ + ":" + std::to_string(line_no_), what);
  }

  void read_header(const std::string& line) {
    std::istringstream s(line);
    double a = 0.0, b = 0.0;
    if (ends_with(line, "atom types")) return;  // the type is read per atom
    if (ends_with(line, "atoms")) {
      if (!(s >> expected_)) fail("malformed atom count");
    } else if (ends_with(line, "xlo xhi") || ends_with(line, "ylo yhi") ||
               ends_with(line, "zlo zhi")) {
      if (!(s >> a >> b)) fail("malformed box bounds");
      const int axis = line[line.size() - 3] - 'x';  // the x, y or z of "xhi", "yhi", "zhi"
      box_.lo[axis] = a;
      box_.hi[axis] = b;
    } else {
      fail("unsupported header line '" + line + "' (spheres only)");
    }
  }
  void read_atom(const std::string& line, std::map<long, Atom>& atoms) {
    std::istringstream s(line);
    long id = 0;
    Atom a;
    if (!(s >> id >> a.type >> a.diameter >> a.density >> a.x.x >> a.x.y >> a.x.z))
      fail("expected: atom-ID atom-type diameter density x y z");
    if (a.type < 1) fail("atom type must be >= 1");
    if (!(a.diameter > 0.0) || !(a.density > 0.0)) fail("diameter and density must be > 0");
    if (!atoms.emplace(id, a).second) fail("atom " + std::to_string(id) + " given twice");
  }

  void read_velocity(const std::string& line, std::map<long, Atom>& atoms) {
    std::istringstream s(line);
    long id = 0;
    Vec3 v, w;
    if (!(s >> id >> v.x >> v.y >> v.z >> w.x >> w.y >> w.z))
      fail("expected: atom-ID vx vy vz wx wy wz");
    const auto it = atoms.find(id);
    if (it == atoms.end()) fail("velocity of unknown atom " + std::to_string(id));
    it->second.v = v;
    it->second.omega = w;
  }

  std::string path_;
  std::ifstream in_;
  int line_no_ = 0;
  std::size_t expected_ = 0;
  DataBox box_;
};

}  // namespace

void write_liggghts_data(const std::string& path, const particles::ParticleStore& store,
                         const DataBox& box, bool with_velocities) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw InputError(path, "cannot write the data file");
  int types = 1;
  for (std::size_t i = 0; i < store.size(); ++i) {
    if (store.body[i] >= 0) {
      std::fclose(f);
      throw InputError(path, "a data file of spheres cannot hold clumps");
    }
    types = std::max(types, store.material[i] + 1);
  }
  std::fprintf(f, "LIGGGHTS data file (atom_style granular) written by demcal\n\n");
  std::fprintf(f, "%zu atoms\n%d atom types\n\n", store.size(), types);
  std::fprintf(f, "%.17g %.17g xlo xhi\n%.17g %.17g ylo yhi\n%.17g %.17g zlo zhi\n", box.lo.x,
               box.hi.x, box.lo.y, box.hi.y, box.lo.z, box.hi.z);
  std::fprintf(f, "\nAtoms\n\n");
  for (std::size_t i = 0; i < store.size(); ++i) {
    const double r = store.radius[i];
    std::fprintf(f, "%zu %d %.17g %.17g %.17g %.17g %.17g\n", i + 1, store.material[i] + 1, 2.0 * r,
                 sphere_density(store.mass[i], r), store.x[i].x, store.x[i].y, store.x[i].z);
  }
  if (with_velocities) {
    std::fprintf(f, "\nVelocities\n\n");
    for (std::size_t i = 0; i < store.size(); ++i)
      std::fprintf(f, "%zu %.17g %.17g %.17g %.17g %.17g %.17g\n", i + 1, store.v[i].x,
                   store.v[i].y, store.v[i].z, store.omega[i].x, store.omega[i].y,
                   store.omega[i].z);
  }
  if (std::fclose(f) != 0) throw InputError(path, "cannot write the data file");
}

DataBox read_liggghts_data(const std::string& path, particles::ParticleStore& store) {
  std::map<long, Atom> atoms;
  const DataBox box = DataReader(path).read(atoms);
  for (const auto& [id, a] : atoms) {
    const auto i =
        store.add_sphere(a.x, 0.5 * a.diameter, a.density, static_cast<std::uint16_t>(a.type - 1));
    store.v[i] = a.v;
    store.omega[i] = a.omega;
  }
  return box;
}

}  // namespace demcal::io
