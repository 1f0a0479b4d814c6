// Helpers for testing batched kernels against the scalar API.
//
// A batch test builds random constraints whose movable particles are all distinct (as inside
// one colour), with some slots pointing at static particles shared between constraints, runs
// the batched kernel on a range [begin, end) of random length, and compares every particle
// with the scalar API applied constraint by constraint on a copy. It does so on every SIMD
// target the machine can run.
#pragma once

#include <algorithm>
#include <cstring>
#include <functional>
#include <initializer_list>
#include <numeric>
#include <string>
#include <vector>

#include <tessera/core/constraint_batch.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/simd.hpp>

#include "test_support.hpp"

namespace tessera::test {

/// Batch vs scalar tolerance of the batch tests (relative): the same formula, but FMA
/// contraction and vector math functions round differently from the scalar build.
inline constexpr Real kBatchTolerance = kDoublePrecision ? Real(1e-12) : Real(1e-5);

/// Runs body(target) once per SIMD target this machine supports, with dispatch forced to that
/// target, and restores the default afterwards.
inline void for_each_simd_target(const std::function<void(const std::string&)>& body) {
  // Restored on the way out, a throw included: one executable runs a module's tests.
  struct Restore {
    ~Restore() { force_simd_target(""); }
  } restore;
  for (const std::string& target : available_simd_targets()) {
    force_simd_target(target);
    SCOPED_TRACE("SIMD target " + target);
    body(target);
  }
}

/// Random particles and constraint index tuples of N particles each, such that no movable
/// particle appears in two constraints. With probability static_fraction a constraint has one
/// slot on a static particle shared by many constraints, and each of its own particles is
/// static. Particle numbering is a random permutation, so gathers are scattered over memory.
template <int N>
struct DisjointConstraintSet {
  std::vector<Vector3r> positions;
  std::vector<Real> inverse_masses;
  std::vector<ParticleIndex> indices;  // N per constraint
  std::size_t count = 0;

  /// The particle positions of constraint c, slot by slot.
  std::array<Vector3r, N> points(std::size_t c) const {
    std::array<Vector3r, N> p;
    for (int k = 0; k < N; ++k) p[k] = positions[indices[c * N + k]];
    return p;
  }
};

/// `make_points(random)` returns the N rest points of one well-conditioned constraint.
template <int N, class MakePoints>
DisjointConstraintSet<N> make_disjoint_constraints(Random& random, std::size_t count,
                                                   Real static_fraction,
                                                   MakePoints&& make_points) {
  constexpr std::size_t kSharedStatic = 3;
  DisjointConstraintSet<N> set;
  set.count = count;
  const std::size_t particle_count = count * N + kSharedStatic;
  std::vector<ParticleIndex> permutation(particle_count);
  std::iota(permutation.begin(), permutation.end(), ParticleIndex(0));
  for (std::size_t i = particle_count - 1; i > 0; --i)
    std::swap(permutation[i], permutation[std::size_t(random.integer(0, int(i)))]);
  set.positions.assign(particle_count, Vector3r::Zero());
  set.inverse_masses.assign(particle_count, Real(0));
  for (std::size_t s = 0; s < kSharedStatic; ++s)
    set.positions[permutation[count * N + s]] = random.vector(-10, 10);
  for (std::size_t c = 0; c < count; ++c) {
    std::array<Vector3r, N> points = make_points(random);
    // Sometimes one slot is a static particle shared with other constraints: the constraint
    // is translated so that slot's point lands on it (translation keeps it well-conditioned).
    int shared_slot = -1;
    ParticleIndex shared = 0;
    if (random.uniform(0, 1) < static_fraction) {
      shared_slot = random.integer(0, N - 1);
      shared = permutation[count * N + std::size_t(random.integer(0, int(kSharedStatic) - 1))];
      const Vector3r shift = set.positions[shared] - points[std::size_t(shared_slot)];
      for (Vector3r& p : points) p += shift;
    }
    for (int k = 0; k < N; ++k) {
      if (k == shared_slot) {
        set.indices.push_back(shared);
        continue;
      }
      const ParticleIndex index = permutation[c * N + std::size_t(k)];
      set.inverse_masses[index] =
          random.uniform(0, 1) < static_fraction ? Real(0) : random.inverse_mass();
      set.positions[index] = points[std::size_t(k)];
      set.indices.push_back(index);
    }
  }
  return set;
}

/// Rest positions from one random rest stencil per constraint: each particle that only one
/// constraint uses gets slot k of make_stencil(random) (drawn for every constraint in order)
/// plus a shift. The shift is default_shift(c, stencil), except on a constraint with a slot on
/// a shared static particle, where it moves that slot's stencil point onto the particle's
/// (one) position. Particles used by several constraints keep their current positions.
template <int N, class MakeStencil, class DefaultShift>
std::vector<Vector3r> translated_rest_stencils(const DisjointConstraintSet<N>& set,
                                               Random& random, MakeStencil&& make_stencil,
                                               DefaultShift&& default_shift) {
  std::vector<Vector3r> rest = set.positions;
  std::vector<int> uses(set.positions.size(), 0);
  for (ParticleIndex i : set.indices) ++uses[i];
  for (std::size_t c = 0; c < set.count; ++c) {
    const std::array<Vector3r, N> s = make_stencil(random);
    Vector3r shift = default_shift(c, s);
    const ParticleIndex* i = &set.indices[std::size_t(N) * c];
    for (std::size_t k = 0; k < std::size_t(N); ++k)
      if (uses[i[k]] > 1) shift = set.positions[i[k]] - s[k];
    for (std::size_t k = 0; k < std::size_t(N); ++k) {
      const ParticleIndex p = i[k];
      if (uses[p] == 1) rest[p] = s[k] + shift;
    }
  }
  return rest;
}

/// A random sub-range [begin, end) of [0, count) whose length is not a multiple of lanes
/// (unless count is too small for that).
inline std::pair<std::size_t, std::size_t> random_range(Random& random, std::size_t count) {
  const std::size_t begin = std::size_t(random.integer(0, int(count / 4)));
  std::size_t end = std::size_t(random.integer(int(begin + count / 2), int(count)));
  if ((end - begin) % kMaxLanes == 0 && end > begin + 1) --end;
  return {begin, end};
}

/// Every particle of `state` equals the expected position within kBatchTolerance (relative to
/// the scene scale `scale`).
inline ::testing::AssertionResult positions_match(const ParticleState& state,
                                                  const std::vector<Vector3r>& expected,
                                                  Real scale = 1) {
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const Vector3r p = state.position(i);
    if (!p.allFinite() ||
        (p - expected[i]).norm() > kBatchTolerance * std::max({scale, expected[i].norm()}))
      return ::testing::AssertionFailure()
             << "particle " << i << ": batch " << p.transpose() << ", scalar "
             << expected[i].transpose() << " (|diff| " << (p - expected[i]).norm() << ")";
  }
  return ::testing::AssertionSuccess();
}

/// Bitwise equality of two particle states' positions.
inline bool same_bits(const ParticleState& a, const ParticleState& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}

/// The scalar reference of a batch test: for constraints [begin, end) one by one,
/// solve(i, c, corr) runs the scalar API on constraint c (particles i[0 .. N)) at the current
/// `expected` positions, and each correction is added to its particle when it is movable.
template <int N, class Solve>
void project_scalar_range(const DisjointConstraintSet<N>& set, std::size_t begin,
                          std::size_t end, std::vector<Vector3r>& expected, Solve&& solve) {
  const std::vector<Real>& w = set.inverse_masses;
  for (std::size_t c = begin; c < end; ++c) {
    const ParticleIndex* i = &set.indices[std::size_t(N) * c];
    Vector3r corr[N];
    solve(i, c, corr);
    for (int k = 0; k < N; ++k)
      if (w[i[k]] > 0) expected[i[k]] += corr[k];
  }
}

/// The message of the InvalidInput that make() throws, or "" when it throws none (the
/// validation tests of the batch builders).
template <class Make>
std::string error_of(Make&& make) {
  try {
    make();
  } catch (const InvalidInput& error) {
    return error.what();
  }
  return "";
}

// ------------------------------------------------------------ the tests every family repeats
//
// The families' batch tests share their structure; these run it for a family given
//   make_set(random, count) -> DisjointConstraintSet<N>   (the family's random constraints)
//   build(set, random)      -> the family's batch          (make_<family>_constraints)
//   project(particles, constraints, begin, end, settings)  (project_<family>_constraints)

/// ProjectionSettings::lambda_starts_at_zero: projecting [begin, end) of `constraints` with it,
/// whatever λ holds (here 0.75 everywhere), gives bitwise the positions and λ of projecting
/// with λ = 0 stored in the range and without it; λ outside the range is untouched. project is
/// called as project(particles, constraints, begin, end, settings).
template <class Batch, class Project>
void expect_lambda_starting_at_zero_reads_no_lambda(const ParticleState& state,
                                                    const Batch& constraints, std::size_t begin,
                                                    std::size_t end, ProjectionSettings settings,
                                                    Project&& project) {
  Batch reset = constraints, started = constraints;
  std::fill(reset.lambda.begin(), reset.lambda.end(), Real(0.75));
  std::fill(started.lambda.begin(), started.lambda.end(), Real(0.75));
  std::fill(reset.lambda.begin() + long(begin), reset.lambda.begin() + long(end), Real(0));
  ParticleState from_reset = state, from_start = state;
  settings.lambda_starts_at_zero = false;
  project(ParticleArrays::of(from_reset), reset, begin, end, settings);
  settings.lambda_starts_at_zero = true;
  project(ParticleArrays::of(from_start), started, begin, end, settings);
  EXPECT_TRUE(same_bits(from_reset, from_start)) << "range [" << begin << ", " << end << ")";
  EXPECT_EQ(std::memcmp(reset.lambda.data(), started.lambda.data(),
                        reset.lambda.size() * sizeof(Real)),
            0)
      << "λ differ (range [" << begin << ", " << end << "))";
  for (std::size_t c = 0; c < started.lambda.size(); ++c) {
    if (c < begin || c >= end) {
      EXPECT_EQ(started.lambda[c], Real(0.75)) << "λ " << c << " changed";
    }
  }
}

/// Batch against the scalar API for a family with both semantics (PBD stiffness and XPBD
/// compliance with λ), on every SIMD target, for seeds 1..6 of 1..300 constraints projected
/// over a random range from λ = 0.25: positions match scalar(set, constraints, begin, end,
/// settings, expected, expected_lambda) (which projects the range constraint by constraint
/// into expected and expected_lambda); λ inside the range matches the scalar λ under
/// compliance, and every other λ is untouched.
template <class MakeSet, class Build, class Project, class Scalar>
void expect_batch_matches_scalar_with_lambda(MakeSet&& make_set, Build&& build,
                                             Project&& project, Scalar&& scalar) {
  for_each_simd_target([&](const std::string&) {
    for (unsigned seed = 1; seed <= 6; ++seed) {
      Random random(seed);
      const std::size_t count = std::size_t(random.integer(1, 300));
      const auto set = make_set(random, count);
      auto constraints = build(set, random);
      const auto [begin, end] = random_range(random, count);
      for (const auto semantics :
           {ConstraintSemantics::stiffness, ConstraintSemantics::compliance}) {
        const ProjectionSettings settings{semantics, Real(1) / 120};
        ParticleState state(set.positions, set.inverse_masses);
        std::vector<Vector3r> expected = set.positions;
        std::vector<Real> expected_lambda(count, Real(0.25));
        std::fill(constraints.lambda.begin(), constraints.lambda.begin() + long(count),
                  Real(0.25));
        scalar(set, constraints, begin, end, settings, expected, expected_lambda);
        project(ParticleArrays::of(state), constraints, begin, end, settings);
        EXPECT_TRUE(positions_match(state, expected, 10));
        for (std::size_t c = 0; c < count; ++c) {
          if (semantics == ConstraintSemantics::compliance && c >= begin && c < end) {
            EXPECT_NEAR(constraints.lambda[c], expected_lambda[c],
                        kBatchTolerance * (1 + std::abs(expected_lambda[c])));
          } else {
            EXPECT_EQ(constraints.lambda[c], Real(0.25)) << "λ outside the range changed";
          }
        }
        if (semantics == ConstraintSemantics::compliance)
          expect_lambda_starting_at_zero_reads_no_lambda(
              ParticleState(set.positions, set.inverse_masses), constraints, begin, end,
              settings, project);
      }
    }
  });
}

/// Two states projected the same way five times over 257 constraints (seed 42) stay bitwise
/// equal, on every SIMD target.
template <class MakeSet, class Build, class Project>
void expect_bitwise_reproducible(MakeSet&& make_set, Build&& build, Project&& project) {
  for_each_simd_target([&](const std::string&) {
    Random random(42);
    const auto set = make_set(random, 257);
    auto constraints = build(set, random);
    ParticleState first(set.positions, set.inverse_masses), second = first;
    for (int iteration = 0; iteration < 5; ++iteration) {
      project(ParticleArrays::of(first), constraints, 0, 257, ProjectionSettings{});
      project(ParticleArrays::of(second), constraints, 0, 257, ProjectionSettings{});
    }
    EXPECT_TRUE(same_bits(first, second));
  });
}

/// Runs project(arrays, constraints, begin, end, settings) on `state` in the separate or the
/// interleaved particle layout.
template <class Project, class Batch>
void project_in_layout(Project&& project, ParticleState& state, Batch& constraints,
                       std::size_t begin, std::size_t end, const ProjectionSettings& settings,
                       bool interleaved) {
  if (!interleaved) {
    project(ParticleArrays::of(state), constraints, begin, end, settings);
    return;
  }
  AlignedVector<Real> xyzw(4 * state.size());
  interleave_particles(state, xyzw.data(), 0, state.size());
  project(ParticleArrays::of_interleaved(xyzw.data(), state.size()), constraints, begin, end,
          settings);
  deinterleave_positions(xyzw.data(), state, 0, state.size());
}

/// A range projected in one call gives the same bits (positions and λ) as its constraints
/// projected one call each, twice over, in both particle layouts, with either semantics, for
/// ranges starting on and off a block's start, on every target. Why: a batched kernel may
/// overlap its blocks (batch_loop-inl.h gathers a block ahead and scatters a block behind the
/// one it projects), which is exact only because a range's constraints share no movable
/// particle; a range of one constraint overlaps nothing.
template <class MakeSet, class Build, class Project>
void expect_range_is_its_constraints_one_by_one(MakeSet&& make_set, Build&& build,
                                                Project&& project) {
  constexpr std::size_t kCount = 3 * kMaxLanes + 5;
  for_each_simd_target([&](const std::string& target) {
    Random random(5);
    const auto set = make_set(random, kCount);
    const auto built = build(set, random);
    for (const bool interleaved : {false, true}) {
      for (const ProjectionSettings& settings :
           {ProjectionSettings{}, ProjectionSettings{ConstraintSemantics::compliance,
                                                     Real(1) / 120}}) {
        for (const std::size_t begin : {std::size_t(0), std::size_t(3)}) {
          auto whole = built, single = built;
          ParticleState in_one_call(set.positions, set.inverse_masses), one_by_one = in_one_call;
          for (int pass = 0; pass < 2; ++pass) {
            project_in_layout(project, in_one_call, whole, begin, kCount, settings, interleaved);
            for (std::size_t c = begin; c < kCount; ++c)
              project_in_layout(project, one_by_one, single, c, c + 1, settings, interleaved);
          }
          SCOPED_TRACE(target + (interleaved ? ", interleaved" : ", separate") +
                       (settings.semantics == ConstraintSemantics::compliance ? ", XPBD"
                                                                              : ", PBD") +
                       ", begin " + std::to_string(begin));
          for (const auto member : {&ParticleState::x, &ParticleState::y, &ParticleState::z})
            EXPECT_EQ(std::memcmp((in_one_call.*member).data(), (one_by_one.*member).data(),
                                  (in_one_call.*member).size() * sizeof(Real)),
                      0);
          EXPECT_EQ(std::memcmp(whole.lambda.data(), single.lambda.data(),
                                whole.lambda.size() * sizeof(Real)),
                    0);
          EXPECT_FALSE(same_bits(in_one_call, ParticleState(set.positions, set.inverse_masses)));
        }
      }
    }
  });
}

/// Over 100 constraints (seed 7): an empty range writes nothing; projecting them all with each
/// of `settings` in turn never moves a static particle, and (with expect_movement) does move
/// some movable one.
template <class MakeSet, class Build, class Project>
void expect_static_particles_and_empty_ranges_not_written(
    MakeSet&& make_set, Build&& build, Project&& project,
    std::initializer_list<ProjectionSettings> settings, bool expect_movement) {
  Random random(7);
  const auto set = make_set(random, 100);
  auto constraints = build(set, random);
  ParticleState state(set.positions, set.inverse_masses);
  const ParticleState before = state;
  project(ParticleArrays::of(state), constraints, 40, 40, ProjectionSettings{});
  EXPECT_TRUE(same_bits(state, before));
  for (const ProjectionSettings& s : settings)
    project(ParticleArrays::of(state), constraints, 0, 100, s);
  bool moved = false;
  for (std::size_t i = 0; i < set.positions.size(); ++i) {
    if (set.inverse_masses[i] == 0) {
      EXPECT_EQ(state.position(i), before.position(i)) << "static particle " << i << " moved";
    } else {
      moved = moved || state.position(i) != before.position(i);
    }
  }
  if (expect_movement) {
    EXPECT_TRUE(moved);
  }
}

}  // namespace tessera::test
