// The constraint families, listed once. Everything that has to touch every family — the
// family enum and names, ConstraintSets and its for_each, the schedule's reordering, the
// solver's dispatch, sequential projection, residuals, frame output, the fuzz decoder and the
// family-generic tests — is generated from TESSERA_CONSTRAINT_FAMILIES below, or iterates it.
//
//   a family = one batch type (core/include/tessera/core/<family>_constraints.hpp) holding
//     kFamily, kTraits                      its message name and capabilities (FamilyTraits)
//     particles / CSR layout                which particles each constraint reads
//     per_constraint_arrays(b)              every array indexed by constraint
//     batch_wide_fields(b)                  the fields that hold for the whole batch
//   and, as overloads on that type, its entry points:
//     make_<family>_constraints             validation at the door
//     project_constraints                   the batched SIMD kernel over [begin, end)
//     project_sequentially                  the scalar API, one constraint after another
//     constraint_residuals                  the batched residual (constraint_residual.hpp)
//     xpbd_residuals                        only with kTraits.xpbd: the same of C + α̃λ
//     solve_velocity_constraints            only with kTraits.velocity_pass
//
// check_family<Batch>() makes forgetting one a compile error: a field left out of both lists,
// a capability without its arrays, a missing entry point (the generic callers do not compile).
// docs/adding-a-family.md walks through adding one.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>

#include <tessera/core/collider_contact_constraints.hpp>
#include <tessera/core/constraint_batch.hpp>
#include <tessera/core/dihedral_constraints.hpp>
#include <tessera/core/distance_constraints.hpp>
#include <tessera/core/fem_tetra_constraints.hpp>
#include <tessera/core/fem_triangle_constraints.hpp>
#include <tessera/core/isometric_bending_constraints.hpp>
#include <tessera/core/particle_tet_contact_constraints.hpp>
#include <tessera/core/proximity_distance_constraints.hpp>
#include <tessera/core/shape_matching_constraints.hpp>
#include <tessera/core/strain_tetra_constraints.hpp>
#include <tessera/core/strain_triangle_constraints.hpp>
#include <tessera/core/tether_constraints.hpp>
#include <tessera/core/volume_constraints.hpp>

/// X(name, Batch) for every family, in global-id order (a model's constraint ids run through
/// the families in this order). `name` is the family's enum value, its ConstraintSets member
/// and its family_name. A new family goes at the end, so the ids of existing scenes stay.
#define TESSERA_CONSTRAINT_FAMILIES(X)                          \
  X(distance, DistanceConstraints)                              \
  X(dihedral, DihedralConstraints)                              \
  X(isometric_bending, IsometricBendingConstraints)             \
  X(volume, VolumeConstraints)                                  \
  X(edge_point_distance, EdgePointDistanceConstraints)          \
  X(triangle_point_distance, TrianglePointDistanceConstraints)  \
  X(edge_edge_distance, EdgeEdgeDistanceConstraints)            \
  X(strain_triangle, StrainTriangleConstraints)                 \
  X(strain_tetra, StrainTetraConstraints)                       \
  X(fem_triangle, FEMTriangleConstraints)                       \
  X(fem_tetra, FEMTetraConstraints)                             \
  X(shape_matching, ShapeMatchingConstraints)                   \
  X(particle_tet_contact, ParticleTetContacts)                  \
  X(tether, TetherConstraints)                                  \
  X(collider_contact, ColliderContacts)

namespace tessera {

/// The constraint families, in global-id order.
enum class ConstraintFamily : std::uint8_t {
#define TESSERA_FAMILY_ENUM(name, Batch) name,
  TESSERA_CONSTRAINT_FAMILIES(TESSERA_FAMILY_ENUM)
#undef TESSERA_FAMILY_ENUM
};

#define TESSERA_FAMILY_ONE(name, Batch) +1
inline constexpr std::size_t kConstraintFamilyCount = 0 TESSERA_CONSTRAINT_FAMILIES(TESSERA_FAMILY_ONE);
#undef TESSERA_FAMILY_ONE

/// "distance", "dihedral", "isometric_bending", ... (the names the tool and reports use).
constexpr std::string_view family_name(ConstraintFamily family) {
  constexpr std::string_view kNames[] = {
#define TESSERA_FAMILY_NAME(name, Batch) #name,
      TESSERA_CONSTRAINT_FAMILIES(TESSERA_FAMILY_NAME)
#undef TESSERA_FAMILY_NAME
  };
  return std::size_t(family) < kConstraintFamilyCount ? kNames[std::size_t(family)] : "unknown";
}

/// What a family is and can do (its batch type's kTraits), looked up at run time.
constexpr FamilyTraits family_traits(ConstraintFamily family) {
  constexpr FamilyTraits kTraits[] = {
#define TESSERA_FAMILY_TRAITS(name, Batch) Batch::kTraits,
      TESSERA_CONSTRAINT_FAMILIES(TESSERA_FAMILY_TRAITS)
#undef TESSERA_FAMILY_TRAITS
  };
  return kTraits[std::size_t(family)];
}

/// The batch type of a family, and the family of a batch type.
template <ConstraintFamily Family>
struct FamilyBatch;
#define TESSERA_FAMILY_BATCH(name, Batch) \
  template <>                             \
  struct FamilyBatch<ConstraintFamily::name> { using type = Batch; };
TESSERA_CONSTRAINT_FAMILIES(TESSERA_FAMILY_BATCH)
#undef TESSERA_FAMILY_BATCH
template <ConstraintFamily Family>
using FamilyBatchOf = typename FamilyBatch<Family>::type;

template <class Batch>
constexpr ConstraintFamily family_of() {
#define TESSERA_FAMILY_OF(name, B) \
  if constexpr (std::is_same_v<Batch, B>) return ConstraintFamily::name; else
  TESSERA_CONSTRAINT_FAMILIES(TESSERA_FAMILY_OF)
#undef TESSERA_FAMILY_OF
  static_assert(!sizeof(Batch), "not a constraint family's batch type");
}

/// One batch per family; an empty batch (the default) holds no constraints.
struct ConstraintSets {
#define TESSERA_FAMILY_MEMBER(name, Batch) Batch name;
  TESSERA_CONSTRAINT_FAMILIES(TESSERA_FAMILY_MEMBER)
#undef TESSERA_FAMILY_MEMBER

  /// Calls visit(family, batch) for every family, in ConstraintFamily order.
  template <class Visit>
  void for_each(Visit&& visit) {
#define TESSERA_FAMILY_VISIT(name, Batch) visit(ConstraintFamily::name, name);
    TESSERA_CONSTRAINT_FAMILIES(TESSERA_FAMILY_VISIT)
  }
  template <class Visit>
  void for_each(Visit&& visit) const {
    TESSERA_CONSTRAINT_FAMILIES(TESSERA_FAMILY_VISIT)
#undef TESSERA_FAMILY_VISIT
  }

  /// The batch of a family, by enum value or by type.
  template <ConstraintFamily Family>
  FamilyBatchOf<Family>& get() {
#define TESSERA_FAMILY_GET(name, Batch) \
  if constexpr (Family == ConstraintFamily::name) return name; else
    TESSERA_CONSTRAINT_FAMILIES(TESSERA_FAMILY_GET)
#undef TESSERA_FAMILY_GET
    static_assert(std::size_t(Family) < kConstraintFamilyCount, "not a family");
  }
  template <ConstraintFamily Family>
  const FamilyBatchOf<Family>& get() const {
    return const_cast<ConstraintSets&>(*this).get<Family>();
  }
  template <class Batch>
  Batch& of_type() {
    return get<family_of<Batch>()>();
  }
  template <class Batch>
  const Batch& of_type() const {
    return get<family_of<Batch>()>();
  }

  /// Constraints per family, in ConstraintFamily order.
  std::array<std::size_t, kConstraintFamilyCount> sizes() const {
    std::array<std::size_t, kConstraintFamilyCount> result{};
    for_each([&](ConstraintFamily family, const auto& batch) {
      result[std::size_t(family)] = batch.size();
    });
    return result;
  }
  std::size_t size() const {
    std::size_t total = 0;
    for_each([&](ConstraintFamily, const auto& batch) { total += batch.size(); });
    return total;
  }
};

// ------------------------------------------------------------------ what generic code uses

/// Whether the family's constraints have a fixed number of particles (ConstraintParticles).
template <class Batch>
inline constexpr bool kFixedArity = Batch::kTraits.arity > 0;

/// The settings a family is projected with: a family without an XPBD form runs its PBD
/// stiffness form under either semantics; the others as given. Every other setting is kept
/// (lambda_starts_at_zero too: the contacts have λ and no XPBD form).
template <class Batch>
constexpr ProjectionSettings settings_for(const ProjectionSettings& settings) {
  ProjectionSettings result = settings;
  if constexpr (!Batch::kTraits.xpbd) result.semantics = ConstraintSemantics::stiffness;
  return result;
}

/// The family's multipliers (nullptr for a family without them).
template <class Batch>
Real* lambda_of(Batch& batch) {
  if constexpr (Batch::kTraits.multiplier)
    return batch.lambda.data();
  else
    return nullptr;
}

/// The number of particles a batch was validated against.
template <class Batch>
std::size_t built_for_particles(const Batch& batch) {
  if constexpr (kFixedArity<Batch>)
    return batch.particles.particle_count;
  else
    return batch.particle_count;
}

namespace detail {

/// Converts to anything: counts an aggregate's fields by how many it can be braced with.
struct AnyField {
  template <class T>
  operator T() const;
};
template <class T, std::size_t... I>
constexpr bool braces_with(std::index_sequence<I...>) {
  return requires { T{(void(I), AnyField{})...}; };
}
template <class T, std::size_t N = 0>
constexpr std::size_t field_count() {
  if constexpr (braces_with<T>(std::make_index_sequence<N + 1>()))
    return field_count<T, N + 1>();
  else
    return N;
}

template <class Tuple>
constexpr std::size_t tuple_size_of() {
  return std::tuple_size_v<std::remove_cvref_t<Tuple>>;
}

/// The compile-time checks of one family's description (see the top of this file).
template <class Batch>
constexpr bool check_family() {
  constexpr FamilyTraits traits = Batch::kTraits;
  using Arrays = decltype(Batch::per_constraint_arrays(std::declval<Batch&>()));
  using Wide = decltype(Batch::batch_wide_fields(std::declval<Batch&>()));
  std::size_t layout = 0;
  if constexpr (traits.arity > 0) {
    static_assert(decltype(Batch::particles)::kParticlesPerConstraint == traits.arity,
                  "kTraits.arity differs from the batch's ConstraintParticles<N>");
    layout = 1;  // particles
  } else {
    using Entries = decltype(Batch::per_entry_arrays(std::declval<Batch&>()));
    layout = Batch::kLayoutFields + tuple_size_of<Entries>();
  }
  static_assert(!traits.xpbd || traits.multiplier, "an XPBD form needs a multiplier (lambda)");
  static_assert(traits.multiplier == requires(Batch b) { b.lambda; },
                "kTraits.multiplier and the presence of a lambda array disagree");
  static_assert(traits.xpbd == requires(Batch b) { b.compliance; },
                "kTraits.xpbd and the presence of a compliance array disagree");
  static_assert(!traits.xpbd || requires(const ParticleArrays& p, const Batch& b, Real* out) {
    xpbd_residuals(p, b, std::size_t(0), std::size_t(0), Real(0), out);
  }, "an XPBD family needs xpbd_residuals (TESSERA_XPBD_RESIDUAL_ENTRY_POINT)");
  static_assert(traits.cell == CellShape::none || traits.cell == CellShape::segment ||
                    traits.arity >= (traits.cell == CellShape::triangle ? 3 : 4),
                "the cell shape needs more slots than the family has");
  return field_count<Batch>() == layout + tuple_size_of<Arrays>() + tuple_size_of<Wide>();
}

#define TESSERA_CHECK_FAMILY(name, Batch)                                               \
  static_assert(check_family<Batch>(),                                                  \
                #Batch ": a field is in neither per_constraint_arrays() nor "           \
                       "batch_wide_fields() (the schedule would drop it when reordering)");
TESSERA_CONSTRAINT_FAMILIES(TESSERA_CHECK_FAMILY)
#undef TESSERA_CHECK_FAMILY

}  // namespace detail

}  // namespace tessera
