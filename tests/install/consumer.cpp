// A minimal embedder: one distance projection through the installed or embedded library.
#include <cstdio>
#include <tessera/core/position_based_dynamics.hpp>

int main() {
  using tessera::Vector3r;
  Vector3r corr0, corr1;
  const bool ok = tessera::PositionBasedDynamics::solve_DistanceConstraint(
      Vector3r(0, 0, 0), 1, Vector3r(2, 0, 0), 1, 1, 1, corr0, corr1);
  // Both ends move 0.5 towards each other.
  if (!ok || corr0.x() != tessera::Real(0.5) || corr1.x() != tessera::Real(-0.5)) return 1;
  std::printf("consumer ok (Tessera %s, %s)\n", TESSERA_VERSION_STRING,
              tessera::kDoublePrecision ? "double" : "float");
  return 0;
}
