// Each substep's contacts coloured among themselves (parallel/src/contact_colouring.hpp): the
// guarantee the solver relies on, checked constraint by constraint. Every contact is placed
// once (a colour or the overflow) and each slot holds the contact it names; no two contacts
// of a colour share a movable particle; a shared static particle separates nothing; a
// particle in more than 64 contacts sends the rest to the overflow; first-fit uses no more
// colours than the most contacts at a particle allows; the scratch masks come back zero.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <span>
#include <vector>

#include <tessera/io/generators.hpp>
#include <tessera/parallel/schedule.hpp>

#include "contact_colouring.hpp"

namespace tessera {
namespace contact_colouring_tests {

/// The vertices of a 10 × 10 cloth; vertex 0 is static.
struct Cloth {
  std::vector<Vector3r> positions;
  std::vector<Real> inverse_mass;
  Cloth() {
    positions = io::make_cloth_grid(10, 10, Real(0.1)).positions;
    inverse_mass.assign(positions.size(), Real(1));
    inverse_mass[0] = 0;
  }
};

/// Distance "contacts" between the given particle pairs (any family colours the same way).
DistanceConstraints contacts_between(const std::vector<ParticleIndex>& pairs,
                                     const std::vector<Vector3r>& positions) {
  return make_distance_constraints({pairs, positions, Real(1), Real(0)});
}

/// The particles of constraint j of a distance batch.
std::array<ParticleIndex, 2> ends(const DistanceConstraints& batch, std::size_t j) {
  return {batch.particles.particle[0][j], batch.particles.particle[1][j]};
}

/// colour_contacts into a new result.
detail::ColouredContacts colour(const ConstraintSets& found, std::span<std::uint64_t> scratch,
                                const std::vector<Real>& inverse_mass) {
  detail::ColouredContacts result;
  detail::colour_contacts(found, scratch, inverse_mass, result);
  return result;
}

void expect_valid(const detail::ColouredContacts& coloured, const ConstraintSets& found,
                  const std::vector<Real>& inverse_mass) {
  const auto& slots = coloured.source[std::size_t(ConstraintFamily::distance)];
  const auto& overflow = coloured.overflow[std::size_t(ConstraintFamily::distance)];
  const DistanceConstraints& laid_out = coloured.constraints.distance;
  // Every found contact exactly once, and each slot holds the contact it names.
  std::multiset<std::uint32_t> placed(overflow.begin(), overflow.end());
  for (std::size_t k = 0; k < coloured.colour_count(); ++k)
    for (const ScheduleBlock& block : coloured.colour_blocks(k))
      for (std::uint32_t j = block.begin; j < block.end; ++j) {
        placed.insert(slots[j]);
        EXPECT_EQ(ends(laid_out, j), ends(found.distance, slots[j]));
      }
  ASSERT_EQ(placed.size(), found.distance.size());
  for (std::uint32_t c = 0; c < found.distance.size(); ++c) EXPECT_EQ(placed.count(c), 1u);
  for (std::size_t k = 0; k < coloured.colour_count(); ++k) {
    // One block per family: the solver cuts a colour into one share per thread.
    std::set<ConstraintFamily> families;
    for (const ScheduleBlock& block : coloured.colour_blocks(k)) {
      EXPECT_TRUE(families.insert(block.family).second) << "colour " << k;
    }
    std::set<ParticleIndex> moved;
    for (const ScheduleBlock& block : coloured.colour_blocks(k))
      for (std::uint32_t j = block.begin; j < block.end; ++j)
        for (const ParticleIndex p : ends(laid_out, j))
          if (inverse_mass[p] > 0) {
            EXPECT_TRUE(moved.insert(p).second) << "colour " << k;
          }
  }
}

TEST(ContactColouring, NoColourMovesAParticleTwice) {
  const Cloth cloth;
  // Random pairs of the cloth's vertices.
  std::mt19937 random(7);
  std::uniform_int_distribution<ParticleIndex> any(0, ParticleIndex(cloth.positions.size() - 1));
  std::vector<ParticleIndex> pairs;
  while (pairs.size() < 2 * 300) {
    const ParticleIndex a = any(random), b = any(random);
    if (a != b) pairs.insert(pairs.end(), {a, b});
  }
  ConstraintSets found;
  found.distance = contacts_between(pairs, cloth.positions);
  std::vector<std::uint64_t> scratch(cloth.positions.size(), 0);
  const auto coloured = colour(found, scratch, cloth.inverse_mass);
  EXPECT_EQ(coloured.constraint_count, found.size());
  expect_valid(coloured, found, cloth.inverse_mass);
  // A movable particle's contacts need a colour each; first-fit finds one among the first
  // (contacts at the contact's two movable particles − 1).
  std::vector<std::size_t> degree(cloth.positions.size(), 0);
  for (std::size_t c = 0; c < found.distance.size(); ++c)
    for (const ParticleIndex p : ends(found.distance, c))
      if (cloth.inverse_mass[p] > 0) ++degree[p];
  const std::size_t most = *std::max_element(degree.begin(), degree.end());
  EXPECT_GE(coloured.colour_count(), most);
  EXPECT_LE(coloured.colour_count(), 2 * most - 1);
  for (const std::uint64_t word : scratch) EXPECT_EQ(word, 0u);
  // The same input gives the same layout, also coloured into a result that held a larger
  // substep's contacts before (the solver keeps one and colours each substep into it).
  ConstraintSets more;
  more.distance = contacts_between(
      [&] {
        std::vector<ParticleIndex> doubled = pairs;
        const auto count = ParticleIndex(cloth.positions.size());
        for (const ParticleIndex p : pairs) doubled.insert(doubled.end(), {p, (p + 1) % count});
        return doubled;
      }(),
      cloth.positions);
  detail::ColouredContacts again = colour(more, scratch, cloth.inverse_mass);
  ASSERT_GT(again.constraint_count, coloured.constraint_count);
  detail::colour_contacts(found, scratch, cloth.inverse_mass, again);
  EXPECT_EQ(again.source, coloured.source);
  EXPECT_EQ(again.overflow, coloured.overflow);
  EXPECT_EQ(again.colour_offsets, coloured.colour_offsets);
  EXPECT_EQ(again.ranges, coloured.ranges);
  EXPECT_EQ(again.blocks, coloured.blocks);
  EXPECT_EQ(again.constraint_count, coloured.constraint_count);
  EXPECT_EQ(again.constraints.distance.particles.particle, coloured.constraints.distance.particles.particle);
  EXPECT_EQ(again.constraints.distance.rest_length, coloured.constraints.distance.rest_length);
  EXPECT_EQ(again.constraints.size(), coloured.constraints.size());
  expect_valid(again, found, cloth.inverse_mass);
}

TEST(ContactColouring, AStaticParticleSeparatesNothingAndTheSixtyFifthContactOverflows) {
  const Cloth cloth;
  // 80 contacts from static particle 0 to 80 different particles, then 79 on particle 55.
  std::vector<ParticleIndex> pairs;
  for (ParticleIndex p = 1; p <= 80; ++p) pairs.insert(pairs.end(), {0, p});
  for (ParticleIndex p = 1; p <= 80; ++p)
    if (p != 55) pairs.insert(pairs.end(), {55, p});
  ConstraintSets found;
  found.distance = contacts_between(pairs, cloth.positions);
  std::vector<std::uint64_t> scratch(cloth.positions.size(), 0);
  const auto coloured = colour(found, scratch, cloth.inverse_mass);
  expect_valid(coloured, found, cloth.inverse_mass);
  // The 80 contacts on the static particle all take colour 0 (they share nothing movable);
  // then each of 55's contacts takes the next colour its other particle leaves free: colour 0
  // is taken by that particle's contact with particle 0, so 55's take 1 ... 63, and the
  // 16 left over overflow.
  EXPECT_EQ(coloured.colour_count(), detail::kContactColours);
  const auto& overflow = coloured.overflow[std::size_t(ConstraintFamily::distance)];
  EXPECT_EQ(overflow.size(), 79u - (detail::kContactColours - 1));
  for (const std::uint32_t c : overflow) EXPECT_EQ(ends(found.distance, c)[0], 55u);
  const auto& first = coloured.colour_blocks(0);
  std::size_t in_colour_0 = 0;
  for (const ScheduleBlock& block : first) in_colour_0 += block.end - block.begin;
  EXPECT_EQ(in_colour_0, 80u) << "a static particle separates nothing";
  for (const std::uint64_t word : scratch) EXPECT_EQ(word, 0u);
  // Coloured next into the same result, contacts without overflow leave none of this
  // substep's overflow or colours behind.
  ConstraintSets fewer;
  fewer.distance = contacts_between({0, 1, 55, 2, 55, 3}, cloth.positions);
  detail::ColouredContacts reused = coloured;
  detail::colour_contacts(fewer, scratch, cloth.inverse_mass, reused);
  const auto fresh = colour(fewer, scratch, cloth.inverse_mass);
  EXPECT_EQ(reused.overflow, fresh.overflow);
  EXPECT_TRUE(reused.overflow[std::size_t(ConstraintFamily::distance)].empty());
  EXPECT_EQ(reused.colour_offsets, fresh.colour_offsets);
  EXPECT_EQ(reused.blocks, fresh.blocks);
  EXPECT_EQ(reused.source, fresh.source);
  EXPECT_EQ(reused.constraints.distance.particles.particle,
            fresh.constraints.distance.particles.particle);
  EXPECT_EQ(reused.constraints.distance.rest_length, fresh.constraints.distance.rest_length);
  EXPECT_EQ(reused.constraints.distance.stiffness, fresh.constraints.distance.stiffness);
  EXPECT_EQ(reused.constraints.distance.compliance, fresh.constraints.distance.compliance);
  EXPECT_EQ(reused.constraints.distance.lambda, fresh.constraints.distance.lambda);
  expect_valid(reused, fewer, cloth.inverse_mass);
}

}  // namespace contact_colouring_tests
}  // namespace tessera
