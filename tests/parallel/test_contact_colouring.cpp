// Contacts coloured on top of the static colouring (parallel/src/contact_colouring.hpp): the
// guarantee the solver relies on, checked constraint by constraint. Every contact is placed
// once (a colour or the overflow); no two contacts of a colour share a movable particle; a
// contact in colour k shares none with static phase k (it runs right after it); a shared
// static particle separates nothing; a particle in more than 64 contacts sends the rest to
// the overflow; the scratch masks come back zero.
#include <gtest/gtest.h>

#include <bit>
#include <random>
#include <set>
#include <vector>

#include <tessera/io/generators.hpp>
#include <tessera/parallel/schedule.hpp>

#include "contact_colouring.hpp"
#include "scenes.hpp"

namespace tessera {
namespace {

/// A 10 × 10 cloth with its edges as the model; vertex 0 is static.
struct Cloth {
  Model model;
  std::vector<Vector3r> positions;
  std::vector<Real> inverse_mass;
  Cloth() {
    const io::ClothGrid grid = io::make_cloth_grid(10, 10, Real(0.1));
    positions = grid.positions;
    inverse_mass.assign(positions.size(), Real(1));
    inverse_mass[0] = 0;
    model.particles = ParticleState(positions, inverse_mass);
    model.constraints.distance =
        make_distance_constraints({grid.edge_indices, positions, Real(1), Real(0)});
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

void expect_valid(const detail::ColouredContacts& coloured, const ConstraintSets& found,
                  const Schedule& schedule, const std::vector<Real>& inverse_mass) {
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
    std::set<ParticleIndex> moved;
    for (const ScheduleBlock& block : coloured.colour_blocks(k))
      for (std::uint32_t j = block.begin; j < block.end; ++j)
        for (const ParticleIndex p : ends(laid_out, j))
          if (inverse_mass[p] > 0) EXPECT_TRUE(moved.insert(p).second) << "colour " << k;
    if (k >= schedule.phase_count()) continue;
    for (const ScheduleBlock& block : schedule.phase_blocks(k))
      for (std::uint32_t j = block.begin; j < block.end; ++j)
        for (const ParticleIndex p : ends(schedule.coloured().distance, j))
          EXPECT_EQ(moved.count(p), 0u) << "static phase " << k << " moves " << p;
  }
}

TEST(ContactColouring, EachColourSharesNoMovableParticleWithItselfOrItsStaticPhase) {
  const Cloth cloth;
  ScheduleOptions options;
  const Colouring colouring = test::colour_model(cloth.model);
  const Schedule schedule(cloth.model, &colouring, options);
  ASSERT_TRUE(schedule.particle_new_to_old().empty()) << "the test's numbering is the schedule's";
  ASSERT_GT(schedule.phase_count(), 2u);
  const auto masks = detail::static_phase_masks(schedule, cloth.inverse_mass);
  // Random pairs (the cloth is not renumbered by greedy, so user = scheduled numbering).
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
  const auto coloured =
      detail::colour_contacts(found, masks, scratch, cloth.inverse_mass, options);
  EXPECT_GT(coloured.colour_count(), schedule.phase_count()) << "300 contacts need colours of their own";
  EXPECT_EQ(coloured.constraint_count, found.size());
  expect_valid(coloured, found, schedule, cloth.inverse_mass);
  for (const std::uint64_t word : scratch) EXPECT_EQ(word, 0u);
  // The same input gives the same layout.
  const auto again = detail::colour_contacts(found, masks, scratch, cloth.inverse_mass, options);
  EXPECT_EQ(again.source, coloured.source);
  EXPECT_EQ(again.colour_offsets, coloured.colour_offsets);
}

TEST(ContactColouring, AStaticParticleSeparatesNothingAndTheSixtyFifthContactOverflows) {
  const Cloth cloth;
  ScheduleOptions options;
  const Colouring colouring = test::colour_model(cloth.model);
  const Schedule schedule(cloth.model, &colouring, options);
  ASSERT_TRUE(schedule.particle_new_to_old().empty()) << "the test's numbering is the schedule's";
  const auto masks = detail::static_phase_masks(schedule, cloth.inverse_mass);
  EXPECT_EQ(masks[0], 0u) << "a static particle carries no colour";
  // 80 contacts from static particle 0 to 80 different particles, then 80 on particle 55.
  std::vector<ParticleIndex> pairs;
  for (ParticleIndex p = 1; p <= 80; ++p) pairs.insert(pairs.end(), {0, p});
  for (ParticleIndex p = 1; p <= 80; ++p)
    if (p != 55) pairs.insert(pairs.end(), {55, p});
  ConstraintSets found;
  found.distance = contacts_between(pairs, cloth.positions);
  std::vector<std::uint64_t> scratch(cloth.positions.size(), 0);
  const auto coloured =
      detail::colour_contacts(found, masks, scratch, cloth.inverse_mass, options);
  expect_valid(coloured, found, schedule, cloth.inverse_mass);
  // Particle 55's contacts: 64 colours minus the static phases it is in, the rest overflow.
  const std::size_t phases_of_55 = std::size_t(std::popcount(masks[55]));
  const auto& overflow = coloured.overflow[std::size_t(ConstraintFamily::distance)];
  std::size_t on_55 = 0;
  for (const std::uint32_t c : overflow) on_55 += ends(found.distance, c)[0] == 55;
  // Each of 55's contacts also meets its other particle, which may cost a colour more, so
  // at least the count a lone particle 55 would send.
  EXPECT_GE(on_55, 79 - (detail::kContactColours - phases_of_55));
  EXPECT_EQ(overflow.size(), on_55) << "the contacts on the static particle all found colours";
  for (const std::uint64_t word : scratch) EXPECT_EQ(word, 0u);
}

}  // namespace
}  // namespace tessera
