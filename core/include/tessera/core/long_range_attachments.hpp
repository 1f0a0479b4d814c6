// Long-range attachments (Kim, Chentanez, Müller 2012): every movable particle that a path of
// mesh edges connects to a static one is tethered to its nearest attachment, along the mesh,
// with reach d = that path's rest length. A tether stops the slow drift a few Gauss–Seidel
// sweeps leave in long chains of edges (a hanging cloth stretching at its pins) in one
// projection, and it never fights an isometric motion: the straight distance to the
// attachment never exceeds the length of a path whose edges keep their lengths.
//
//   static particles ●──●──○──○──○──○      ○ movable, ● static (attachments)
//                     ╲ geodesic distance along the edges, one multi-source Dijkstra
//                      ○ → tether (○, nearest ●, d)
//
// "Nearest" is by rest path length (ties: the smaller attachment number), found by one
// Dijkstra search started from every attachment at once: the same answer as one search per
// attachment followed by a sort, for the cost of `attachments` searches. Deterministic.
//
// How many attachments. One tether to the nearest pin leaves a taut span between two pins
// free: a cloth hung by two corners exactly its width apart has to carry its weight in the
// top edge, and the middle of that edge may sag anywhere within its reach of one pin alone,
// so its edges stretch (the 256² default cloth: 58 % at the middle of the top edge after 1 s).
// Tethered to both pins, particle i of the span is held within i of one and n − i of the
// other; the two spheres touch only on the straight span, so the span stays straight.
//
//   ●───○───○───○───●     one attachment: the middle ○ may sag to anywhere within its
//        ╲       ╱           reach of the nearer ●, stretching the edges beside it;
//         ○─────○            two: within both reaches, which meet only on the straight span
//
// Each tether costs one projection of one movable particle; the scenes use two attachments
// (io::kDefaultTetherAttachments; measured in docs/performance.md, "Accuracy per second").
#pragma once

#include <cstddef>
#include <span>

#include <tessera/core/indices.hpp>
#include <tessera/core/real.hpp>
#include <tessera/core/tether_constraints.hpp>

namespace tessera {

struct LongRangeAttachmentOptions {
  /// Reach = reach_scale × the rest path length; 1 keeps the mesh within its rest reach, a
  /// value above 1 allows that much stretch along the mesh before a tether acts.
  Real reach_scale = 1;
  /// How many attachments each particle is tethered to, the nearest along the mesh first
  /// (fewer where fewer are connected). See "How many attachments" above.
  std::size_t attachments = 1;
  /// Stiffness k ∈ [0, 1] and XPBD compliance α ≥ 0 of every tether.
  Real stiffness = 1;
  Real compliance = 0;
};

/// The tethers of a mesh: `edges` lists 2 particle indices per edge (either order, repeats
/// allowed), the paths along which reach is measured at `rest_positions`; particles whose
/// inverse mass is 0 are the attachments. One tether per movable particle connected to an
/// attachment, in increasing particle order; none when there is no static particle. Throws
/// InvalidInput for an odd index count, an index out of range, sizes that differ, a non-finite
/// rest position, or a reach_scale, stiffness or compliance out of range.
TetherConstraints make_long_range_attachments(std::span<const Vector3r> rest_positions,
                                              std::span<const Real> inverse_masses,
                                              std::span<const ParticleIndex> edges,
                                              const LongRangeAttachmentOptions& options = {});
}  // namespace tessera
