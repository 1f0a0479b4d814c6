// The time-integration passes (time_integration.hpp), compiled once per SIMD target
// (Highway foreach_target) and dispatched at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "time_integration.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/time_integration.hpp>

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

/// How both passes end: x, y, z kept as the previous positions, v stored as the velocities,
/// and the prediction x + h·v (movable lanes; a static particle keeps its place) written to
/// the state's arrays and, when given, to the sweeps' interleaved copy (with w, the inverse
/// mass).
template <class D, class V, class M>
HWY_INLINE void StoreStepAndPrediction(D d, ParticleState& state, std::size_t i, M movable, V h,
                                       V x, V y, V z, V vx, V vy, V vz, V w, Real* xyzw) {
  hn::Store(x, d, state.previous_x.data() + i);
  hn::Store(y, d, state.previous_y.data() + i);
  hn::Store(z, d, state.previous_z.data() + i);
  hn::Store(vx, d, state.velocity_x.data() + i);
  hn::Store(vy, d, state.velocity_y.data() + i);
  hn::Store(vz, d, state.velocity_z.data() + i);
  const V px = hn::IfThenElse(movable, hn::Add(x, hn::Mul(h, vx)), x);
  const V py = hn::IfThenElse(movable, hn::Add(y, hn::Mul(h, vy)), y);
  const V pz = hn::IfThenElse(movable, hn::Add(z, hn::Mul(h, vz)), z);
  hn::Store(px, d, state.x.data() + i);
  hn::Store(py, d, state.y.data() + i);
  hn::Store(pz, d, state.z.data() + i);
  if (xyzw != nullptr) hn::StoreInterleaved4(px, py, pz, w, d, xyzw + 4 * i);
}

void PredictPositions(ParticleState& state, const IntegrationStep& step, Real* xyzw,
                      std::size_t first, std::size_t last) {
  const hn::ScalableTag<Real> d;
  const std::size_t lanes = hn::Lanes(d);
  const auto h = hn::Set(d, step.h), zero = hn::Zero(d);
  const auto gx = hn::Set(d, step.gravity_h[0]), gy = hn::Set(d, step.gravity_h[1]),
             gz = hn::Set(d, step.gravity_h[2]);
  for (std::size_t i = first; i < last; i += lanes) {
    const auto x = hn::Load(d, state.x.data() + i), y = hn::Load(d, state.y.data() + i),
               z = hn::Load(d, state.z.data() + i);
    const auto w = hn::Load(d, state.inverse_mass.data() + i);
    const auto movable = hn::Lt(zero, w);
    // v += h·g (movable lanes).
    auto vx = hn::Load(d, state.velocity_x.data() + i);
    auto vy = hn::Load(d, state.velocity_y.data() + i);
    auto vz = hn::Load(d, state.velocity_z.data() + i);
    vx = hn::IfThenElse(movable, hn::Add(vx, gx), vx);
    vy = hn::IfThenElse(movable, hn::Add(vy, gy), vy);
    vz = hn::IfThenElse(movable, hn::Add(vz, gz), vz);
    StoreStepAndPrediction(d, state, i, movable, h, x, y, z, vx, vy, vz, w, xyzw);
  }
}

void UpdateVelocitiesAndPredict(ParticleState& state, const IntegrationStep& step, Real* xyzw,
                                bool read_interleaved, std::size_t first, std::size_t last) {
  const hn::ScalableTag<Real> d;
  const std::size_t lanes = hn::Lanes(d);
  const auto h = hn::Set(d, step.h), zero = hn::Zero(d), scale = hn::Set(d, step.velocity_scale);
  const auto gx = hn::Set(d, step.gravity_h[0]), gy = hn::Set(d, step.gravity_h[1]),
             gz = hn::Set(d, step.gravity_h[2]);
  for (std::size_t i = first; i < last; i += lanes) {
    hn::Vec<decltype(d)> x, y, z, interleaved_w;
    if (read_interleaved) {
      hn::LoadInterleaved4(d, xyzw + 4 * i, x, y, z, interleaved_w);
    } else {
      x = hn::Load(d, state.x.data() + i);
      y = hn::Load(d, state.y.data() + i);
      z = hn::Load(d, state.z.data() + i);
    }
    const auto w = hn::Load(d, state.inverse_mass.data() + i);
    const auto movable = hn::Lt(zero, w);
    // v = (x − previous)·scale + h·g (movable lanes; 0 for static ones).
    const auto vx = hn::IfThenElseZero(
        movable, hn::Add(hn::Mul(hn::Sub(x, hn::Load(d, state.previous_x.data() + i)), scale), gx));
    const auto vy = hn::IfThenElseZero(
        movable, hn::Add(hn::Mul(hn::Sub(y, hn::Load(d, state.previous_y.data() + i)), scale), gy));
    const auto vz = hn::IfThenElseZero(
        movable, hn::Add(hn::Mul(hn::Sub(z, hn::Load(d, state.previous_z.data() + i)), scale), gz));
    StoreStepAndPrediction(d, state, i, movable, h, x, y, z, vx, vy, vz, w, xyzw);
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace tessera {

HWY_EXPORT(PredictPositions);
HWY_EXPORT(UpdateVelocitiesAndPredict);

void predict_positions(ParticleState& state, const IntegrationStep& step, Real* xyzw,
                       std::size_t first, std::size_t last) {
  HWY_DYNAMIC_DISPATCH(PredictPositions)(state, step, xyzw, first, last);
}

void update_velocities_and_predict(ParticleState& state, const IntegrationStep& step,
                                   Real* xyzw, bool read_interleaved, std::size_t first,
                                   std::size_t last) {
  HWY_DYNAMIC_DISPATCH(UpdateVelocitiesAndPredict)(state, step, xyzw, read_interleaved, first,
                                                   last);
}

}  // namespace tessera
#endif
