// Primitives (vertices, triangles or edges of a mesh) in leaves of kLeafSize, the unit of a
// self-collision build's broad phase: one grid query per leaf, not per primitive, and the
// distances of a primitive against every member of the leaves its leaf meets, read as
// blocks of lanes instead of gathered pair by pair.
//
//   members by Morton order of their points at the first build (leaves stay compact: a
//   mesh's neighbours stay neighbours as it bends)
//
//     leaf 0: m0 … m15 │ leaf 1: m0 … m15 │ … │ leaf L−1: m m m ∅ … ∅     (kLeafSize each)
//
//   per leaf, its members' fields as blocks of kLeafSize lanes (field-major):
//     [ f0: m0 … m15 │ f1: m0 … m15 │ … ]    one 64-byte line per field (16 floats, 8 doubles)
//
// Why: a build's grids met ~17 triangle boxes per vertex and ~15 edge boxes per edge, nearly
// all of them its in-plane neighbours; scanning ~70 grid entries per primitive and
// gathering each hit's record took most of a build (perf on the drape: the scan 25 %, the
// gathers 23 % of the run). A leaf's box covers its members' boxes, so a pair whose boxes
// overlap has leaves whose boxes overlap: testing every member of the met leaves by
// distance finds the same contacts, at a few more lanes of arithmetic and no scan per
// primitive.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <vector>

#include <tessera/collision/spatial_hash.hpp>
#include <tessera/core/real.hpp>

#include "segment_distances.hpp"

namespace tessera::detail {

class PrimitiveLeaves {
 public:
  static constexpr std::size_t kLeafSize = kBlockLanes;
  /// A padding member (the last leaf's room past the primitives).
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

  /// Orders primitives 0 .. points.size() − 1 into leaves by the Morton code of their points
  /// (10 bits per axis over the points' box; ties by index): deterministic.
  void order(std::span<const Vector3r> points) {
    count_ = points.size();
    Vector3r lo = Vector3r::Constant(std::numeric_limits<Real>::max()), hi = -lo;
    for (const Vector3r& p : points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    std::vector<std::uint64_t> keyed(count_);
    for (std::size_t i = 0; i < count_; ++i) {
      std::uint64_t code = 0;
      for (int axis = 0; axis < 3; ++axis) {
        const double span = double(hi[axis]) - double(lo[axis]);
        const double at = span > 0 ? (double(points[i][axis]) - double(lo[axis])) / span : 0;
        const std::uint64_t cell = std::min<std::uint64_t>(1023, std::uint64_t(at * 1024));
        for (int bit = 0; bit < 10; ++bit) code |= ((cell >> bit) & 1) << (3 * bit + axis);
      }
      keyed[i] = code << 32 | i;
    }
    std::sort(keyed.begin(), keyed.end());
    member_.assign(leaf_count() * kLeafSize, kNone);
    for (std::size_t k = 0; k < count_; ++k) member_[k] = std::uint32_t(keyed[k]);
  }
  std::size_t leaf_count() const { return (count_ + kLeafSize - 1) / kLeafSize; }
  /// Leaf l's members (kLeafSize entries, kNone past the primitives).
  const std::uint32_t* members(std::size_t leaf) const { return member_.data() + leaf * kLeafSize; }

  /// Each leaf's box: the union of its members' (`boxes` by primitive); with `grid`, the
  /// leaves' grid over them too (the leaves that are met, not only querying).
  template <class ParallelOver>
  void box(std::span<const Aabb> boxes, ParallelOver&& parallel_over, bool grid = true) {
    leaf_boxes_.resize(leaf_count());
    parallel_over(leaf_count(), [&](std::size_t leaf) {
      const std::uint32_t* m = members(leaf);
      Aabb box = boxes[m[0]];
      for (std::size_t k = 1; k < kLeafSize && m[k] != kNone; ++k)
        for (int axis = 0; axis < 3; ++axis)
          box.lo[axis] = std::min(box.lo[axis], boxes[m[k]].lo[axis]),
          box.hi[axis] = std::max(box.hi[axis], boxes[m[k]].hi[axis]);
      leaf_boxes_[leaf] = box;
    });
    if (grid) grid_.build(leaf_boxes_);
  }
  const Aabb& leaf_box(std::size_t leaf) const { return leaf_boxes_[leaf]; }
  const UniformGrid& grid() const { return grid_; }

 private:
  std::size_t count_ = 0;
  std::vector<std::uint32_t> member_;
  std::vector<Aabb> leaf_boxes_;
  UniformGrid grid_;
};

/// Fields per member of every leaf, as blocks of kLeafSize lanes (a padding member's lanes
/// repeat a member's with an empty box: they pair with nothing).
template <std::size_t Fields>
class LeafFields {
 public:
  static constexpr std::size_t kLanes = PrimitiveLeaves::kLeafSize;
  void resize(std::size_t leaves) { data_.resize(leaves * Fields * kLanes); }
  Real* block(std::size_t leaf, std::size_t field) {
    return data_.data() + (leaf * Fields + field) * kLanes;
  }
  const Real* block(std::size_t leaf, std::size_t field) const {
    return data_.data() + (leaf * Fields + field) * kLanes;
  }
  const Real* data() const { return data_.data(); }

 private:
  std::vector<Real> data_;
};

/// The leaves one query meets and its answers by lane (one thread's, kept between calls).
struct LeafQuery {
  std::vector<std::uint32_t> leaves;
  std::vector<Real> squared, allowed;
  std::vector<std::uint32_t> within;

  void clear() { leaves.clear(); }
  /// Room for the answers over every met leaf.
  void fit() {
    const std::size_t lanes = leaves.size() * PrimitiveLeaves::kLeafSize + kSegmentBatchLanes;
    if (within.size() < lanes) squared.resize(lanes), allowed.resize(lanes), within.resize(lanes);
  }
};

}  // namespace tessera::detail
