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
