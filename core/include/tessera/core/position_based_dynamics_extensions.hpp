// Constraints Tessera adds beyond the seed's PositionBasedDynamics API, with its conventions
// (position_based_dynamics.hpp: corrections returned, never applied; static particles get
// exactly zero; degenerate or inactive input returns false with zero corrections) and, in
// XPBDExtensions, their compliance forms with the conventions of xpbd.hpp.
#pragma once

#include <tessera/core/real.hpp>

namespace tessera {

class PositionBasedDynamicsExtensions {
 public:
  // ---------------------------------------------------------------------------------------
  /// Tether, or long-range attachment (Kim, Chentanez, Müller 2012, "Long Range Attachments —
  /// A Method to Simulate Inextensible Clothing in Computer Games"): keeps p0 within reach d
  /// of its attachment p1.
  ///   C(p0, p1) = |p0 - p1| - d ≤ 0,   ∇_{p0} C = n = (p0 - p1)/|p0 - p1|,  ∇_{p1} C = -n.
  /// Unilateral: while |p0 - p1| ≤ d the tether is inactive (false, zero corrections);
  /// beyond it, the projection of C with stiffness k (as for an edge). Degenerate (false)
  /// when p0 and p1 coincide or both are static.
  static bool solve_TetherConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                     Real invMass1, const Real maxDistance,
                                     const Real stiffness, Vector3r& corr0, Vector3r& corr1);

  // ---------------------------------------------------------------------------------------
  /// Contact of particle p0 with a static collider, linearised at its closest point into the
  /// plane with unit outward normal n and offset o (the admissible side n · p ≥ o):
  ///   C(p0) = n · p0 - o ≥ 0,   ∇_{p0} C = n.
  /// Where C < 0 and p0 is movable: the push -C n back onto the plane, λ += -C, then
  /// position-based friction (Macklin, Müller, Chentanez, Kim 2014, "Unified particle physics
  /// for real-time applications", eq. 24) with d = -C on the tangential motion since the
  /// substep began, Δx = (p0 - C n) - anchor, Δx_t = Δx - (Δx · n) n: all of Δx_t is undone
  /// when |Δx_t| < μs d (static), Δx_t · min(μk d / |Δx_t|, 1) otherwise (dynamic). corr0 is
  /// the sum of both. lambda accumulates the penetration over the iterations of one substep
  /// (start it at 0). Returns false (zero correction, λ unchanged) when C ≥ 0, p0 is static
  /// (invMass0 = 0) or n is not a unit vector (| |n|² - 1 | > 1e-4).
  static bool solve_ColliderContactConstraint(const Vector3r& p0, Real invMass0,
                                              const Vector3r& normal, const Real offset,
                                              const Vector3r& anchor, const Real staticFriction,
                                              const Real dynamicFriction, Real& lambda,
                                              Vector3r& corr0);

  /// Restitution of a collider contact after the velocity update (Müller, Macklin, Chentanez,
  /// Jeschke, Kim 2020, "Detailed rigid body simulation with extended position based
  /// dynamics", eq. 34): with v_n = v0 · n and ṽ_n = normalSpeed, the normal velocity before
  /// the solve, corr_v0 = n (-v_n + max(-e ṽ_n, 0)), e = restitution. Returns false (zero
  /// correction) when the contact did not push in the position solve (lambda ≤ 0) or v0's
  /// particle is static.
  static bool velocitySolve_ColliderContactConstraint(const Vector3r& v0, Real invMass0,
                                                      const Vector3r& normal,
                                                      const Real normalSpeed,
                                                      const Real restitution, const Real lambda,
                                                      Vector3r& corr_v0);
};

class XPBDExtensions {
 public:
  /// The tether's compliance form: while |p0 - p1| ≤ d, false with zero corrections and λ
  /// unchanged; beyond it, the XPBD update of C = |p0 - p1| - d (λ stays ≤ 0 there: a tether
  /// only pulls).
  static bool solve_TetherConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                     Real invMass1, const Real maxDistance,
                                     const Real compliance, const Real dt, Real& lambda,
                                     Vector3r& corr0, Vector3r& corr1);
};

}  // namespace tessera
