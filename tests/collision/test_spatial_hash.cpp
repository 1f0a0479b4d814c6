// The uniform grid against brute force: on random boxes of mixed sizes (points, slivers,
// boxes up to the cell size, larger queries, clusters far apart) it finds exactly the overlapping pairs that
// an O(n²) loop finds, sorted, and the same list on 1 and 2 threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <vector>

#include <tbb/task_arena.h>

#include <tessera/collision/spatial_hash.hpp>
#include <tessera/core/error.hpp>

namespace tessera {
namespace spatial_hash_tests {

std::vector<Aabb> random_boxes(std::size_t n, Real largest, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<Real> position(-1, 1), extent(0, largest);
  std::vector<Aabb> boxes(n);
  for (std::size_t i = 0; i < n; ++i)
    for (int axis = 0; axis < 3; ++axis) {
      boxes[i].lo[axis] = position(random);
      // Every 7th box is a point, to cover zero extents.
      boxes[i].hi[axis] = boxes[i].lo[axis] + (i % 7 == 0 ? Real(0) : extent(random));
    }
  return boxes;
}

std::vector<CandidatePair> brute_force_self_pairs(const std::vector<Aabb>& boxes) {
  std::vector<CandidatePair> pairs;
  for (std::uint32_t i = 0; i < boxes.size(); ++i)
    for (std::uint32_t j = i + 1; j < boxes.size(); ++j)
      if (overlap(boxes[i], boxes[j])) pairs.push_back({i, j});
  return pairs;
}

TEST(UniformGrid, SelfPairsAreExactlyTheOverlappingPairs) {
  for (const Real largest : {Real(0.02), Real(0.1), Real(0.5)}) {
    const std::vector<Aabb> boxes = random_boxes(1500, largest, 7);
    UniformGrid grid;
    grid.build(boxes);
    std::vector<CandidatePair> pairs;
    grid.self_pairs(pairs);
    const std::vector<CandidatePair> expected = brute_force_self_pairs(boxes);
    EXPECT_FALSE(expected.empty());
    EXPECT_EQ(pairs, expected) << "largest extent " << largest;
  }
}

TEST(UniformGrid, QueryPairsAreExactlyTheOverlappingPairs) {
  const std::vector<Aabb> boxes = random_boxes(1000, Real(0.05), 11);
  // Queries larger than the cells: they span several cells on each axis.
  const std::vector<Aabb> queries = random_boxes(300, Real(0.3), 12);
  UniformGrid grid;
  grid.build(boxes);
  std::vector<CandidatePair> pairs;
  grid.query_pairs(queries, pairs);
  std::vector<CandidatePair> expected;
  for (std::uint32_t q = 0; q < queries.size(); ++q)
    for (std::uint32_t i = 0; i < boxes.size(); ++i)
      if (overlap(queries[q], boxes[i])) expected.push_back({q, i});
  EXPECT_FALSE(expected.empty());
  EXPECT_EQ(pairs, expected);
}

TEST(UniformGrid, AnyCellSizeGivesTheSamePairs) {
  const std::vector<Aabb> boxes = random_boxes(800, Real(0.2), 3);
  const std::vector<CandidatePair> expected = brute_force_self_pairs(boxes);
  for (const Real cell : {Real(0.03), Real(0.1), Real(0.2), Real(0.7)}) {
    UniformGrid grid;
    grid.build(boxes, cell);
    std::vector<CandidatePair> pairs;
    grid.self_pairs(pairs);
    EXPECT_EQ(pairs, expected) << "cell " << cell;
  }
}

TEST(UniformGrid, SpreadOutBoxesGrowTheCellAndStayExact) {
  // Two clusters 1000 apart and a few boxes far beyond: at the boxes' own size the grid
  // would need ~10^15 cells, so the cell grows; the pairs must not change.
  std::vector<Aabb> boxes = random_boxes(600, Real(0.05), 21);
  for (std::size_t i = 0; i < 300; ++i)
    for (int axis = 0; axis < 3; ++axis) boxes[i].lo[axis] += 1000, boxes[i].hi[axis] += 1000;
  boxes[5].lo[1] = boxes[5].hi[1] = -1e5f;
  boxes[6].lo[2] = boxes[6].hi[2] = 3e5f;
  UniformGrid grid;
  grid.build(boxes);
  EXPECT_GT(grid.cell_size(), Real(1));
  std::vector<CandidatePair> pairs;
  grid.self_pairs(pairs);
  EXPECT_EQ(pairs, brute_force_self_pairs(boxes));
}

TEST(UniformGrid, PointsOnlyAndEmptyInput) {
  std::vector<Aabb> points = {{{0, 0, 0}, {0, 0, 0}}, {{0, 0, 0}, {0, 0, 0}}, {{1, 0, 0}, {1, 0, 0}}};
  UniformGrid grid;
  grid.build(points);
  std::vector<CandidatePair> pairs;
  grid.self_pairs(pairs);
  EXPECT_EQ(pairs, (std::vector<CandidatePair>{{0, 1}}));
  grid.build({});
  grid.self_pairs(pairs);
  EXPECT_TRUE(pairs.empty());
}

TEST(UniformGrid, ANonFiniteBoxIsRefused) {
  std::vector<Aabb> boxes = random_boxes(10, Real(0.1), 1);
  boxes[4].hi[1] = std::numeric_limits<Real>::quiet_NaN();
  UniformGrid grid;
  EXPECT_THROW(grid.build(boxes), InvalidInput);
  boxes[4].hi[1] = std::numeric_limits<Real>::infinity();
  EXPECT_THROW(grid.build(boxes), InvalidInput);
}

TEST(UniformGrid, TheSamePairsOnOneAndTwoThreads) {
  const std::vector<Aabb> boxes = random_boxes(20000, Real(0.06), 5);
  const auto pairs_on = [&](int threads) {
    std::vector<CandidatePair> pairs;
    tbb::task_arena(threads).execute([&] {
      UniformGrid grid;
      grid.build(boxes);
      grid.self_pairs(pairs);
    });
    return pairs;
  };
  const std::vector<CandidatePair> one = pairs_on(1);
  EXPECT_GT(one.size(), 1000u);
  EXPECT_TRUE(std::is_sorted(one.begin(), one.end()));
  EXPECT_EQ(one, pairs_on(2));
}

}  // namespace spatial_hash_tests
}  // namespace tessera
