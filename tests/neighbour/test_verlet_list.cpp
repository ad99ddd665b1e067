// The half Verlet list on its cell grid against the O(N^2) definition it stands for: every pair
// with |x_j - x_i| < r_i + r_j + reach (minimum image across periodic faces) listed once as
// (i, j > i), rows sorted, the same on 1 and 2 threads; a rebuild carries each surviving pair's
// history and starts new pairs from zero; members of one rigid clump are never paired.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "core/neighbour/verlet_list.hpp"

namespace demcal::neighbour {
namespace {

using Pairs = std::set<std::pair<int, int>>;

struct Cloud {
  std::vector<Vec3> x;
  std::vector<double> radius;
  Domain domain;
};

/// n polydisperse spheres (radius 0.5-1.5 mm) at random in a 20 mm box, overlaps allowed.
Cloud random_cloud(int n, std::array<bool, 3> periodic, unsigned seed) {
  Cloud c;
  c.domain.lo = {0.0, 0.0, 0.0};
  c.domain.hi = {0.02, 0.02, 0.02};
  c.domain.periodic = periodic;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> at(0.0, 0.02), size(0.5e-3, 1.5e-3);
  for (int i = 0; i < n; ++i) {
    c.x.push_back({at(rng), at(rng), at(rng)});
    c.radius.push_back(size(rng));
  }
  return c;
}

Pairs brute_force(const Cloud& c, double reach, const std::vector<std::int32_t>& body = {}) {
  Pairs out;
  const int n = static_cast<int>(c.x.size());
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      if (!body.empty() && body[i] >= 0 && body[i] == body[j]) continue;
      if (norm(c.domain.separation(c.x[i], c.x[j])) < c.radius[i] + c.radius[j] + reach)
        out.insert({i, j});
    }
  return out;
}

Pairs listed(const VerletList& list) {
  Pairs out;
  for (std::size_t i = 0; i + 1 < list.row_start.size(); ++i)
    for (int k = list.row_start[i]; k < list.row_start[i + 1]; ++k)
      out.insert({static_cast<int>(i), list.nbr[k]});
  return out;
}

void expect_rows_sorted_above_the_diagonal(const VerletList& list) {
  for (std::size_t i = 0; i + 1 < list.row_start.size(); ++i)
    for (int k = list.row_start[i]; k < list.row_start[i + 1]; ++k) {
      EXPECT_GT(list.nbr[k], static_cast<int>(i));
      if (k > list.row_start[i]) {
        EXPECT_LT(list.nbr[k - 1], list.nbr[k]);
      }
    }
}

TEST(VerletList, ListsExactlyThePairsInRangeOnceEach) {
  const double reach = 0.3e-3;
  for (const auto periodic :
       {std::array<bool, 3>{false, false, false}, std::array<bool, 3>{true, true, false},
        std::array<bool, 3>{true, true, true}}) {
    const Cloud c = random_cloud(600, periodic, 7);
    const Pairs expected = brute_force(c, reach);
    ASSERT_GT(expected.size(), 500u);  // a dense enough cloud to mean something
    for (const int threads : {1, 2}) {
      VerletList list;
      std::vector<double> history;
      list.build(c.x, c.radius, c.domain, reach, threads, history, 3);
      EXPECT_EQ(listed(list), expected)
          << "periodic " << periodic[0] << periodic[1] << periodic[2] << ", threads " << threads;
      EXPECT_EQ(list.pairs(), expected.size());
      EXPECT_EQ(history.size(), 3 * list.pairs());
      expect_rows_sorted_above_the_diagonal(list);
    }
  }
}

TEST(VerletList, FewerThanThreeCellsAcrossAPeriodicAxisFindEachPairOnce) {
  // A box 3.5 mm thick along z: one or two cells, so the stencil meets a cell twice.
  Cloud c = random_cloud(300, {true, true, true}, 11);
  c.domain.hi[2] = 0.0035;
  for (auto& x : c.x) c.domain.wrap(x);
  VerletList list;
  std::vector<double> history;
  list.build(c.x, c.radius, c.domain, 0.3e-3, 1, history, 1);
  EXPECT_EQ(listed(list), brute_force(c, 0.3e-3));
  EXPECT_EQ(list.pairs(), brute_force(c, 0.3e-3).size());
}

TEST(VerletList, RebuildCarriesTheHistoryOfSurvivingPairsAndZeroesNewOnes) {
  Cloud c = random_cloud(400, {true, false, true}, 3);
  const double reach = 0.3e-3;
  VerletList list;
  std::vector<double> history;
  list.build(c.x, c.radius, c.domain, reach, 1, history, 2);
  // Each pair's history names it: (i, j).
  for (std::size_t i = 0; i + 1 < list.row_start.size(); ++i)
    for (int k = list.row_start[i]; k < list.row_start[i + 1]; ++k) {
      history[2 * k] = static_cast<double>(i);
      history[2 * k + 1] = list.nbr[k];
    }
  const Pairs before = listed(list);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> kick(-0.4e-3, 0.4e-3);
  for (auto& x : c.x) {
    x += Vec3{kick(rng), kick(rng), kick(rng)};
    c.domain.wrap(x);
  }
  list.build(c.x, c.radius, c.domain, reach, 2, history, 2);
  const Pairs after = listed(list);
  EXPECT_EQ(after, brute_force(c, reach));
  int kept = 0, fresh = 0;
  for (std::size_t i = 0; i + 1 < list.row_start.size(); ++i)
    for (int k = list.row_start[i]; k < list.row_start[i + 1]; ++k) {
      const int j = list.nbr[k];
      if (before.count({static_cast<int>(i), j})) {
        EXPECT_EQ(history[2 * k], static_cast<double>(i));
        EXPECT_EQ(history[2 * k + 1], static_cast<double>(j));
        ++kept;
      } else {
        EXPECT_EQ(history[2 * k], 0.0);
        EXPECT_EQ(history[2 * k + 1], 0.0);
        ++fresh;
      }
    }
  EXPECT_GT(kept, 100);  // the kick keeps most pairs and makes some new ones
  EXPECT_GT(fresh, 10);
}

TEST(VerletList, MembersOfOneClumpAreNeverPaired) {
  const Cloud c = random_cloud(300, {false, false, false}, 9);
  std::vector<std::int32_t> body(c.x.size(), -1);
  for (std::size_t i = 0; i < body.size() / 2; ++i) body[i] = static_cast<std::int32_t>(i / 3);
  VerletList list;
  std::vector<double> history;
  list.build(c.x, c.radius, c.domain, 0.3e-3, 2, history, 1, body.data());
  const Pairs expected = brute_force(c, 0.3e-3, body);
  EXPECT_EQ(listed(list), expected);
  EXPECT_LT(expected.size(), brute_force(c, 0.3e-3).size());
}

}  // namespace
}  // namespace demcal::neighbour
