// The scalar API's side of "one formula per family": a family's scalar function evaluates its
// lane formula on one lane (Real) and hands the value here, which projects it with the shared
// PBD or XPBD rule (kernels/projection-inl.h) and writes the corrections back as Eigen vectors.
// Include after the family's kernels/<family>-inl.h (single static target, no foreach_target).
#ifndef TESSERA_CORE_SRC_SCALAR_PROJECTION_HPP_
#define TESSERA_CORE_SRC_SCALAR_PROJECTION_HPP_

#include <tessera/core/real.hpp>

#include "kernels/projection-inl.h"

namespace tessera::detail {

namespace lanes = HWY_NAMESPACE;

template <int N>
void write_corrections(const lanes::Vec3<Real> (&lane_corr)[N], Vector3r* const (&corr)[N]) {
  for (int i = 0; i < N; ++i) *corr[i] = lanes::to_eigen(lane_corr[i]);
}

/// PBD projection of one lane (stiffness semantics); true when the lane was projected.
template <int N, class Value>
bool project_scalar_pbd(const Value& value, const Real (&w)[N],
                        Real stiffness, Vector3r* const (&corr)[N]) {
  lanes::Vec3<Real> lane_corr[N];
  const bool projected = lanes::project_pbd(value, w, stiffness, lane_corr);
  write_corrections<N>(lane_corr, corr);
  return projected;
}

/// XPBD projection of one lane (compliance semantics, updates λ); true when projected.
template <int N, class Value>
bool project_scalar_xpbd(const Value& value, const Real (&w)[N],
                         Real compliance, Real dt, Real& lambda, Vector3r* const (&corr)[N]) {
  lanes::Vec3<Real> lane_corr[N];
  const bool projected =
      lanes::project_xpbd(value, w, compliance, lanes::TimeStep<Real>::of(dt), lambda, lane_corr);
  write_corrections<N>(lane_corr, corr);
  return projected;
}

}  // namespace tessera::detail

#endif  // TESSERA_CORE_SRC_SCALAR_PROJECTION_HPP_
