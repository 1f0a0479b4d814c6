// The uniform grid's query scan (spatial_hash.hpp), compiled once per SIMD target (Highway
// foreach_target) and dispatched at run time: each run of entries is tested a vector of boxes
// at a time (the six comparisons of an overlap as lane masks), and the overlapping entries'
// box indices are written out.
//
//   run of one (y, z) row:  e0 e1 e2 e3 e4 e5 e6 e7 │ e8 e9 ...     (entries of cells x0..x1)
//   per vector:             lo ≤ q.hi and q.lo ≤ hi on x, y, z,  ──►  mask  ──►  the boxes'
//                           box index ≥ the lowest asked for            indices
//
// Why: the scalar scan branched on every entry (most fail on x, but which ones is not
// predictable), and it was the largest single cost of a self-collision build (a quarter of
// the drape's detection).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "grid_scan.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/collision/spatial_hash.hpp>

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

std::size_t OverlappingEntries(const detail::GridLevelView& level, const std::int64_t* range,
                               const Aabb& query, std::uint32_t lowest_index,
                               std::uint32_t* hits) {
  // At most 16 lanes: the levels' arrays are padded by that (UniformGrid::Level::kPadding)
  // and the mask bits are read as 16.
  const hn::CappedTag<Real, 16> d;
  const std::size_t lanes = hn::Lanes(d);
  // Float lanes hold the box indices' test too (32 bits each); double lanes leave it to the
  // scalar loop over the hits.
  constexpr bool kIndexLanes = sizeof(Real) == sizeof(std::uint32_t);
  // As signed lanes (box indices stay below 2^31): index > lowest − 1.
  const hn::RebindToSigned<decltype(d)> di;
  const auto below_lowest = hn::Set(di, hn::TFromD<decltype(di)>(std::int64_t(lowest_index) - 1));
  const auto qlx = hn::Set(d, query.lo[0]), qly = hn::Set(d, query.lo[1]),
             qlz = hn::Set(d, query.lo[2]);
  const auto qhx = hn::Set(d, query.hi[0]), qhy = hn::Set(d, query.hi[1]),
             qhz = hn::Set(d, query.hi[2]);
  std::size_t count = 0;
  for (std::int64_t cz = range[4]; cz <= range[5]; ++cz)
    for (std::int64_t cy = range[2]; cy <= range[3]; ++cy) {
      const std::size_t row = std::size_t((cz * level.dims[1] + cy) * level.dims[0]);
      const std::size_t begin = level.cell_start[row + std::size_t(range[0])],
                        end = level.cell_start[row + std::size_t(range[1]) + 1];
      for (std::size_t e = begin; e < end; e += lanes) {
        // x first: most entries fail there. Lanes past the run's end are masked off (the
        // arrays are padded, so the load stays inside them).
        auto m = hn::And(hn::FirstN(d, end - e), hn::Le(hn::LoadU(d, level.lo[0] + e), qhx));
        m = hn::And(m, hn::Le(qlx, hn::LoadU(d, level.hi[0] + e)));
        if constexpr (kIndexLanes) {
          const auto index = hn::LoadU(di, reinterpret_cast<const hn::TFromD<decltype(di)>*>(
                                               level.index + e));
          m = hn::And(m, hn::RebindMask(d, hn::Gt(index, below_lowest)));
        }
        if (hn::AllFalse(d, m)) continue;
        m = hn::And(m, hn::Le(hn::LoadU(d, level.lo[1] + e), qhy));
        m = hn::And(m, hn::Le(qly, hn::LoadU(d, level.hi[1] + e)));
        m = hn::And(m, hn::Le(hn::LoadU(d, level.lo[2] + e), qhz));
        m = hn::And(m, hn::Le(qlz, hn::LoadU(d, level.hi[2] + e)));
        std::uint8_t bits[8] = {};
        hn::StoreMaskBits(d, m, bits);
        std::uint32_t word = std::uint32_t(bits[0]) | std::uint32_t(bits[1]) << 8;  // ≤ 16 lanes
        for (; word != 0; word &= word - 1) {
          const std::uint32_t index = level.index[e + std::size_t(__builtin_ctz(word))];
          if (kIndexLanes || index >= lowest_index) hits[count++] = index;
        }
      }
    }
  return count;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace tessera::detail {

HWY_EXPORT(OverlappingEntries);

std::size_t overlapping_entries(const GridLevelView& level, const std::int64_t* range,
                                const Aabb& query, std::uint32_t lowest_index,
                                std::uint32_t* hits) {
  return HWY_DYNAMIC_DISPATCH(OverlappingEntries)(level, range, query, lowest_index, hits);
}

}  // namespace tessera::detail
#endif
