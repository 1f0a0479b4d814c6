// Which SIMD target the batched kernels run on, and forcing one for tests and benchmarks.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/real.hpp>

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

std::size_t LanesOfReal() { return hwy::HWY_NAMESPACE::Lanes(hwy::HWY_NAMESPACE::ScalableTag<Real>()); }
std::int64_t CompiledTarget() { return HWY_TARGET; }

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <hwy/targets.h>

#include <tessera/core/error.hpp>
#include <tessera/core/simd.hpp>

namespace tessera {

HWY_EXPORT(LanesOfReal);
HWY_EXPORT(CompiledTarget);

std::vector<std::string> available_simd_targets() {
  std::vector<std::string> names;
  for (const std::int64_t target : hwy::SupportedAndGeneratedTargets())
    names.emplace_back(hwy::TargetName(target));
  return names;
}

std::string active_simd_target() {
  return hwy::TargetName(HWY_DYNAMIC_DISPATCH(CompiledTarget)());
}

std::size_t active_simd_lanes() { return HWY_DYNAMIC_DISPATCH(LanesOfReal)(); }

void force_simd_target(const std::string& name) {
  if (name.empty()) {
    hwy::SetSupportedTargetsForTest(0);
    hwy::GetChosenTarget().Update(hwy::SupportedTargets());
    return;
  }
  hwy::SetSupportedTargetsForTest(0);
  for (const std::int64_t target : hwy::SupportedAndGeneratedTargets()) {
    if (name == hwy::TargetName(target)) {
      hwy::SetSupportedTargetsForTest(target);
      hwy::GetChosenTarget().Update(hwy::SupportedTargets());
      return;
    }
  }
  hwy::GetChosenTarget().Update(hwy::SupportedTargets());
  std::string known;
  for (const std::string& available : available_simd_targets())
    known += (known.empty() ? "" : ", ") + available;
  throw InvalidInput("SIMD target '" + name + "' is not available here (available: " + known +
                     ")");
}

}  // namespace tessera
#endif  // HWY_ONCE
