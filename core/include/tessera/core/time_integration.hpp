// The two passes over the particles that bracket a substep's sweeps (XPBD, Macklin et al.
// 2016, algorithm 1), as SIMD loops dispatched at run time like the kernels:
//
//   predict:             x_prev = x;  movable: v += g h,  x += h v
//   ─ sweeps ─
//   update and predict:  x_prev = x;  movable: v = (x − x_prev) s + g h,  x += h v
//                        static:  v = 0          (s = max(0, 1 − damping h) / h)
//
// The second is the velocity update of one substep and the prediction of the next in one
// pass. Both optionally write the interleaved copy the sweeps use (ParticleArrays, stride 4),
// and the second can read the sweeps' positions from it, so moving between the layouts costs
// no pass of its own. Static particles (w = 0) keep their position exactly.
//
// Ranges: [first, last) with first a multiple of kMaxLanes; the loops run whole vectors, so
// they may touch the arrays' padding up to padded_size(size()) (padding particles are static
// at the origin and stay so), and the interleaved copy must hold 4 · padded_size(size())
// values.
#pragma once

#include <cstddef>

#include <tessera/core/particle_state.hpp>
#include <tessera/core/real.hpp>

namespace tessera {

struct IntegrationStep {
  Real h;                       // substep length
  Real gravity_h[3];            // g · h
  Real velocity_scale = 0;      // s above (update_velocities_and_predict only)
};

/// predict on particles [first, last); xyzw (may be null) gets x, y, z, w of each.
void predict_positions(ParticleState& state, const IntegrationStep& step, Real* xyzw,
                       std::size_t first, std::size_t last);

/// update and predict on particles [first, last). Positions are read from xyzw when
/// read_interleaved, else from the state; the prediction goes to the state and, when xyzw is
/// not null, to xyzw (x, y, z; w is left as it is).
void update_velocities_and_predict(ParticleState& state, const IntegrationStep& step,
                                   Real* xyzw, bool read_interleaved, std::size_t first,
                                   std::size_t last);

}  // namespace tessera
