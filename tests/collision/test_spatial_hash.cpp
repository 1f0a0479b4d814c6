// The spatial hash against brute force: on random boxes of mixed sizes (points, slivers,
// boxes up to the cell size and larger queries) it finds exactly the overlapping pairs that
// an O(n²) loop finds, sorted, and the same list on 1 and 2 threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include <tbb/task_arena.h>

#include <tessera/collision/spatial_hash.hpp>

namespace tessera {
namespace {

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

TEST(SpatialHash, SelfPairsAreExactlyTheOverlappingPairs) {
  for (const Real largest : {Real(0.02), Real(0.1), Real(0.5)}) {
    const std::vector<Aabb> boxes = random_boxes(1500, largest, 7);
    SpatialHash hash;
    hash.build(boxes);
    std::vector<CandidatePair> pairs;
    hash.self_pairs(pairs);
    const std::vector<CandidatePair> expected = brute_force_self_pairs(boxes);
    EXPECT_FALSE(expected.empty());
    EXPECT_EQ(pairs, expected) << "largest extent " << largest;
  }
}

TEST(SpatialHash, QueryPairsAreExactlyTheOverlappingPairs) {
  const std::vector<Aabb> boxes = random_boxes(1000, Real(0.05), 11);
  // Queries larger than the cells: they span several cells on each axis.
  const std::vector<Aabb> queries = random_boxes(300, Real(0.3), 12);
  SpatialHash hash;
  hash.build(boxes);
  std::vector<CandidatePair> pairs;
  hash.query_pairs(queries, pairs);
  std::vector<CandidatePair> expected;
  for (std::uint32_t q = 0; q < queries.size(); ++q)
    for (std::uint32_t i = 0; i < boxes.size(); ++i)
      if (overlap(queries[q], boxes[i])) expected.push_back({q, i});
  EXPECT_FALSE(expected.empty());
  EXPECT_EQ(pairs, expected);
}

TEST(SpatialHash, AGivenCellSizeBelowTheLargestBoxIsRaised) {
  const std::vector<Aabb> boxes = random_boxes(800, Real(0.2), 3);
  SpatialHash hash;
  hash.build(boxes, Real(0.01));
  EXPECT_GE(hash.cell_size(), Real(0.19));
  std::vector<CandidatePair> pairs;
  hash.self_pairs(pairs);
  EXPECT_EQ(pairs, brute_force_self_pairs(boxes));
}

TEST(SpatialHash, PointsOnlyAndEmptyInput) {
  std::vector<Aabb> points = {{{0, 0, 0}, {0, 0, 0}}, {{0, 0, 0}, {0, 0, 0}}, {{1, 0, 0}, {1, 0, 0}}};
  SpatialHash hash;
  hash.build(points);
  std::vector<CandidatePair> pairs;
  hash.self_pairs(pairs);
  EXPECT_EQ(pairs, (std::vector<CandidatePair>{{0, 1}}));
  hash.build({});
  hash.self_pairs(pairs);
  EXPECT_TRUE(pairs.empty());
}

TEST(SpatialHash, TheSamePairsOnOneAndTwoThreads) {
  const std::vector<Aabb> boxes = random_boxes(20000, Real(0.06), 5);
  const auto pairs_on = [&](int threads) {
    std::vector<CandidatePair> pairs;
    tbb::task_arena(threads).execute([&] {
      SpatialHash hash;
      hash.build(boxes);
      hash.self_pairs(pairs);
    });
    return pairs;
  };
  const std::vector<CandidatePair> one = pairs_on(1);
  EXPECT_GT(one.size(), 1000u);
  EXPECT_TRUE(std::is_sorted(one.begin(), one.end()));
  EXPECT_EQ(one, pairs_on(2));
}

}  // namespace
}  // namespace tessera
