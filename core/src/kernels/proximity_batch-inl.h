// The batched loop the three proximity families share (point–edge, point–triangle, edge–edge):
// gather the N particles of W constraints, evaluate the family's lane formula
// (proximity-inl.h), project with the stiffness chosen by the sign of C, scatter the movable
// particles. Why one loop: the families differ only in their formula and N, and a single loop
// keeps their gather/scatter and padding behaviour identical.
#if defined(TESSERA_CORE_KERNELS_PROXIMITY_BATCH_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_PROXIMITY_BATCH_INL_H_
#undef TESSERA_CORE_KERNELS_PROXIMITY_BATCH_INL_H_
#else
#define TESSERA_CORE_KERNELS_PROXIMITY_BATCH_INL_H_
#endif

#include <cstddef>

#include <tessera/core/constraint_batch.hpp>

#include "batch-inl.h"
#include "proximity-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// The SoA arrays of one proximity family's batch.
template <int N>
struct ProximityArrays {
  const ConstraintParticles<N>& particles;
  const Real* rest_distance;
  const Real* compression_stiffness;
  const Real* stretch_stiffness;
};

/// Projects constraints [begin, end) W at a time. Formula::evaluate(positions, rest) returns
/// the family's ConstraintValue<RealLanes, N> for the N gathered positions.
template <int N, class Formula>
HWY_INLINE void project_proximity_range(ParticleArrays particles,
                                        const ProximityArrays<N>& constraints,
                                        std::size_t begin, std::size_t end) {
  const RealTag d;
  const std::size_t lanes = hn::Lanes(d);
  const ParticleIndex* slot[N];
  for (int k = 0; k < N; ++k) slot[k] = constraints.particles.particle[k].data();
  for (std::size_t i = begin; i < end; i += lanes) {
    const LaneMask active = hn::FirstN(d, end - i);
    ParticleLanes gathered[N];
    Vec3<RealLanes> position[N];
    RealLanes w[N];
    for (int k = 0; k < N; ++k) {
      gathered[k] = gather_particles(particles, slot[k] + i);
      position[k] = gathered[k].position;
      w[k] = gathered[k].inverse_mass;
    }
    const ConstraintValue<RealLanes, N> value =
        Formula::evaluate(position, hn::LoadU(d, constraints.rest_distance + i));
    const RealLanes stiffness =
        proximity_stiffness(value.C, hn::LoadU(d, constraints.compression_stiffness + i),
                            hn::LoadU(d, constraints.stretch_stiffness + i));
    Vec3<RealLanes> corr[N];
    project_pbd(value, w, stiffness, corr);
    for (int k = 0; k < N; ++k)
      scatter_corrected(particles, slot[k] + i, gathered[k], corr[k], active);
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_PROXIMITY_BATCH_INL_H_
