#pragma once
// Half Verlet list (each pair once, j > i) built on a cell grid, with a skin. Rows are sorted by j
// so the per-contact history of the old list can be carried to the new one by merging rows
// (the explicit history-mapping step of DEM-Engine, keyed by the ordered pair (i, j)).
#include <cstdint>
#include <vector>

#include "core/common/bytes.hpp"
#include "core/common/domain.hpp"
#include "core/common/vec3.hpp"

namespace demcal::neighbour {

class VerletList {
 public:
  std::vector<int> row_start;  ///< size N+1: pairs of i are nbr[row_start[i] .. row_start[i+1])
  std::vector<int> nbr;        ///< partner j of each pair, sorted within a row

  /// Rebuilds the list for pairs with |x_j - x_i| < r_i + r_j + reach, where reach = interaction
  /// range beyond contact + skin. Carries `history` (stride doubles per pair) from the old list.
  /// Positions must already be wrapped into the periodic box. With `body` (one entry per
  /// particle, -1 = none), pairs of two members of one rigid clump are left out.
  void build(const std::vector<Vec3>& x, const std::vector<double>& radius, const Domain& domain,
             double reach, int threads, std::vector<double>& history, int stride,
             const std::int32_t* body = nullptr);

  /// Squared displacement of particle i, now at x, since the last build. Once some particle has
  /// moved more than half the skin, a pair outside the list could have come into range.
  double displacement2(int i, const Vec3& x) const { return norm2(x - x_at_build_[i]); }

  std::size_t pairs() const { return nbr.size(); }
  std::size_t builds() const { return builds_; }

  /// The list's state in a checkpoint record (core/common/bytes.hpp): the rows, the positions of
  /// the last build and the build count (the buffers a build reuses carry nothing from one build
  /// to the next).
  template <class A, RecordOf<VerletList> L>
  friend void record_fields(A& a, L& list) {
    a.field(list.row_start);
    a.field(list.nbr);
    a.field(list.x_at_build_);
    a.field(list.builds_);
  }

 private:
  std::vector<Vec3> x_at_build_;
  std::vector<int> cell_start_, cell_items_;
  std::vector<int> old_start_, old_nbr_;  ///< the rows of the build before last (memory reused)
  std::vector<double> spare_history_;     ///< the history of the build before last (memory reused)
  std::vector<std::vector<int>> partners_;  ///< per thread: the partners of its rows, in a build
  std::size_t builds_ = 0;
};

}  // namespace demcal::neighbour
