// The scalar API of the three proximity constraints (point–edge, point–triangle, edge–edge):
// one lane of each family's formula (kernels/proximity-inl.h), the same code the batched
// kernels run on W lanes, so the two paths find the same closest points and the same
// degenerate cases. compressionStiffness applies when C < 0 (closer than d0),
// stretchStiffness when C ≥ 0.
#include <tessera/core/position_based_dynamics.hpp>

#include "kernels/proximity-inl.h"
#include "scalar_projection.hpp"

namespace tessera {

namespace lanes = HWY_NAMESPACE;

namespace {

/// Projects one lane with the stiffness chosen by the sign of C and writes the corrections.
template <int N>
bool project_proximity(const lanes::ConstraintValue<Real, N>& value, const Real (&w)[N],
                       Real compression_stiffness, Real stretch_stiffness,
                       Vector3r* const (&corr)[N]) {
  return detail::project_scalar_pbd<N>(
      value, w, lanes::proximity_stiffness(value.C, compression_stiffness, stretch_stiffness),
      corr);
}

}  // namespace

bool PositionBasedDynamics::solve_EdgePointDistanceConstraint(
    const Vector3r& p, Real invMass, const Vector3r& p0, Real invMass0, const Vector3r& p1,
    Real invMass1, const Real restDist, const Real compressionStiffness,
    const Real stretchStiffness, Vector3r& corr, Vector3r& corr0, Vector3r& corr1) {
  const auto value = lanes::edge_point_distance_constraint<Real>(
      lanes::from_eigen(p), lanes::from_eigen(p0), lanes::from_eigen(p1), restDist);
  const Real w[3] = {invMass, invMass0, invMass1};
  return project_proximity<3>(value, w, compressionStiffness, stretchStiffness,
                              {&corr, &corr0, &corr1});
}

bool PositionBasedDynamics::solve_TrianglePointDistanceConstraint(
    const Vector3r& p, Real invMass, const Vector3r& p0, Real invMass0, const Vector3r& p1,
    Real invMass1, const Vector3r& p2, Real invMass2, const Real restDist,
    const Real compressionStiffness, const Real stretchStiffness, Vector3r& corr, Vector3r& corr0,
    Vector3r& corr1, Vector3r& corr2) {
  const auto value = lanes::triangle_point_distance_constraint<Real>(
      lanes::from_eigen(p), lanes::from_eigen(p0), lanes::from_eigen(p1), lanes::from_eigen(p2),
      restDist);
  const Real w[4] = {invMass, invMass0, invMass1, invMass2};
  return project_proximity<4>(value, w, compressionStiffness, stretchStiffness,
                              {&corr, &corr0, &corr1, &corr2});
}

bool PositionBasedDynamics::solve_EdgeEdgeDistanceConstraint(
    const Vector3r& p0, Real invMass0, const Vector3r& p1, Real invMass1, const Vector3r& p2,
    Real invMass2, const Vector3r& p3, Real invMass3, const Real restDist,
    const Real compressionStiffness, const Real stretchStiffness, Vector3r& corr0, Vector3r& corr1,
    Vector3r& corr2, Vector3r& corr3) {
  const auto value = lanes::edge_edge_distance_constraint<Real>(
      lanes::from_eigen(p0), lanes::from_eigen(p1), lanes::from_eigen(p2), lanes::from_eigen(p3),
      restDist);
  const Real w[4] = {invMass0, invMass1, invMass2, invMass3};
  return project_proximity<4>(value, w, compressionStiffness, stretchStiffness,
                              {&corr0, &corr1, &corr2, &corr3});
}

}  // namespace tessera
