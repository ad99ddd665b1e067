#include "core/neighbour/verlet_list.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "core/common/error.hpp"

namespace demcal::neighbour {
namespace {

/// Uniform cell grid over the particles (periodic axes: over the box).
struct Grid {
  std::array<int, 3> n{1, 1, 1};
  Vec3 lo;
  Vec3 inv_cell;
  std::array<bool, 3> periodic{};

  int coord(const Vec3& x, int k) const {
    int c = static_cast<int>(std::floor((x[k] - lo[k]) * inv_cell[k]));
    return std::clamp(c, 0, n[k] - 1);
  }
  int index(int cx, int cy, int cz) const { return (cz * n[1] + cy) * n[0] + cx; }
  int cells() const { return n[0] * n[1] * n[2]; }

  /// True when some periodic axis has fewer than 3 cells, so that a stencil meets a cell twice.
  bool stencil_repeats = false;

  /// The distinct cells around (cx, cy, cz); fewer than 27 where a periodic axis has < 3 cells.
  int stencil(int cx, int cy, int cz, std::array<int, 27>& out) const {
    int count = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          std::array<int, 3> c{cx + dx, cy + dy, cz + dz};
          bool inside = true;
          for (int k = 0; k < 3; ++k) {
            if (c[k] >= 0 && c[k] < n[k]) continue;
            if (periodic[k])
              c[k] = (c[k] + n[k]) % n[k];
            else
              inside = false;
          }
          if (!inside) continue;
          const int id = index(c[0], c[1], c[2]);
          if (!stencil_repeats ||
              std::find(out.begin(), out.begin() + count, id) == out.begin() + count)
            out[count++] = id;
        }
    return count;
  }
};

Grid make_grid(const std::vector<Vec3>& x, const Domain& domain, double cell,
               std::size_t n_particles) {
  Grid g;
  g.periodic = domain.periodic;
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const Vec3& p : x)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  // Cap the grid at a few cells per particle: a far-flung particle must not allocate a huge grid.
  const double max_cells = 4.0 * static_cast<double>(n_particles) + 64.0;
  for (;;) {
    double total = 1.0;
    for (int k = 0; k < 3; ++k) {
      if (domain.periodic[k]) {
        g.lo[k] = domain.lo[k];
        const double len = domain.hi[k] - domain.lo[k];
        g.n[k] = std::max(1, static_cast<int>(std::floor(len / cell)));
        g.inv_cell[k] = g.n[k] / len;
      } else {
        g.lo[k] = lo[k];
        g.n[k] = std::max(1, static_cast<int>(std::floor((hi[k] - lo[k]) / cell)) + 1);
        g.inv_cell[k] = 1.0 / cell;
      }
      total *= g.n[k];
    }
    if (total <= max_cells) {
      for (int k = 0; k < 3; ++k) g.stencil_repeats |= g.periodic[k] && g.n[k] < 3;
      return g;
    }
    cell *= std::cbrt(total / max_cells) * 1.01;
  }
}

}  // namespace

void VerletList::build(const std::vector<Vec3>& x, const std::vector<double>& radius,
                       const Domain& domain, double reach, int threads,
                       std::vector<double>& history, int stride, const std::int32_t* body) {
  const int n = static_cast<int>(x.size());
  double r_max = 0.0;
  for (double r : radius) r_max = std::max(r_max, r);
  const Grid grid = make_grid(x, domain, 2.0 * r_max + reach, x.size());

  // Counting sort of the particles into cells.
  std::vector<int> cell_of(n);
  cell_start_.assign(grid.cells() + 1, 0);
  for (int i = 0; i < n; ++i) {
    cell_of[i] = grid.index(grid.coord(x[i], 0), grid.coord(x[i], 1), grid.coord(x[i], 2));
    ++cell_start_[cell_of[i] + 1];
  }
  for (int c = 0; c < grid.cells(); ++c) cell_start_[c + 1] += cell_start_[c];
  cell_items_.resize(n);
  {
    std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (int i = 0; i < n; ++i) cell_items_[fill[cell_of[i]]++] = i;
  }

  // The old rows and history go to buffers kept from the build before, whose memory is reused:
  // a build allocates nothing once the list has reached its size.
  std::vector<int>& old_start = old_start_;
  std::vector<int>& old_nbr = old_nbr_;
  old_start.swap(row_start);
  old_nbr.swap(nbr);
  row_start.assign(n + 1, 0);

  const MinimumImage image(domain);
  const bool any_periodic = grid.periodic[0] || grid.periodic[1] || grid.periodic[2];
  auto for_each_partner = [&](int i, auto&& visit) {
    // The candidates of one cell's items in cell_items_[begin, end).
    auto scan = [&](int begin, int end) {
      for (int k = begin; k < end; ++k) {
        const int j = cell_items_[k];
        if (j <= i || (body && body[i] >= 0 && body[i] == body[j])) continue;
        const double cut = radius[i] + radius[j] + reach;
        if (norm2(image(x[j] - x[i])) < cut * cut) visit(j);
      }
    };
    const int cx = grid.coord(x[i], 0), cy = grid.coord(x[i], 1), cz = grid.coord(x[i], 2);
    if (!any_periodic) {
      // The stencil is a box clipped to the grid; along x its cells are consecutive, so the
      // items of each of its (y, z) rows are one run of cell_items_. Rows are sorted below, so
      // the order in which candidates are met does not matter.
      const int x0 = std::max(cx - 1, 0), x1 = std::min(cx + 1, grid.n[0] - 1);
      for (int cz2 = std::max(cz - 1, 0); cz2 <= std::min(cz + 1, grid.n[2] - 1); ++cz2)
        for (int cy2 = std::max(cy - 1, 0); cy2 <= std::min(cy + 1, grid.n[1] - 1); ++cy2)
          scan(cell_start_[grid.index(x0, cy2, cz2)], cell_start_[grid.index(x1, cy2, cz2) + 1]);
      return;
    }
    std::array<int, 27> cells;
    const int nc = grid.stencil(cx, cy, cz, cells);
    for (int s = 0; s < nc; ++s) scan(cell_start_[cells[s]], cell_start_[cells[s] + 1]);
  };

  // One pass over the candidates: each thread lists the partners of its own rows, sorted, in a
  // buffer of its own; the buffers are then laid end to end in thread order (= row order).
  const bool carry = stride > 0 && old_start.size() == static_cast<std::size_t>(n + 1);
  std::vector<double>& new_history = spare_history_;
  if (static_cast<int>(partners_.size()) < threads) partners_.resize(threads);
#pragma omp parallel num_threads(threads)
  {
    const int tid = omp_get_thread_num(), nt = omp_get_num_threads();
    const int lo = static_cast<int>(static_cast<long>(n) * tid / nt);
    const int hi = static_cast<int>(static_cast<long>(n) * (tid + 1) / nt);
    auto& mine = partners_[tid];
    mine.clear();
    for (int i = lo; i < hi; ++i) {
      const auto row_begin = static_cast<std::ptrdiff_t>(mine.size());
      for_each_partner(i, [&](int j) { mine.push_back(j); });
      std::sort(mine.begin() + row_begin, mine.end());
      row_start[i + 1] = static_cast<int>(static_cast<std::ptrdiff_t>(mine.size()) - row_begin);
    }
#pragma omp barrier
#pragma omp single
    {
      for (int i = 0; i < n; ++i) row_start[i + 1] += row_start[i];
      nbr.resize(row_start[n]);
      new_history.assign(static_cast<std::size_t>(nbr.size()) * stride, 0.0);
    }
    std::copy(mine.begin(), mine.end(), nbr.begin() + row_start[lo]);
    if (carry)
      for (int i = lo; i < hi; ++i) {
        // Merge the sorted old and new rows of i: a pair found in both keeps its history.
        int a = old_start[i], b = row_start[i];
        while (a < old_start[i + 1] && b < row_start[i + 1]) {
          if (old_nbr[a] < nbr[b]) {
            ++a;
          } else if (nbr[b] < old_nbr[a]) {
            ++b;
          } else {
            std::copy_n(history.begin() + static_cast<std::ptrdiff_t>(a) * stride, stride,
                        new_history.begin() + static_cast<std::ptrdiff_t>(b) * stride);
            ++a;
            ++b;
          }
        }
      }
  }
  history.swap(new_history);
  x_at_build_ = x;
  ++builds_;
}

}  // namespace demcal::neighbour
