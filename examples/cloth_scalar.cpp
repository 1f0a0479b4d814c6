// A cloth pinned at two corners falls under gravity, simulated with the classic PBD loop
// and Tessera's scalar kernel API: one constraint at a time, in input order, on one thread.
// It is the reference the parallel solver is measured against, and the smallest complete
// use of tessera::PositionBasedDynamics.
//
//   cloth_scalar [--size N] [--frames F] [--substeps S] [--iterations K]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/io/generators.hpp>

namespace {

using tessera::PositionBasedDynamics;
using tessera::Real;
using tessera::Vector3r;

struct Options {
  std::size_t size = 64;
  int frames = 60;
  int substeps = 8;
  int iterations = 4;
};

bool parse_count(const char* text, long minimum, long& value) {
  char* end = nullptr;
  value = std::strtol(text, &end, 10);
  return end != text && *end == '\0' && value >= minimum && value <= 1000000;
}

bool parse_options(int argc, char** argv, Options& options) {
  for (int i = 1; i < argc; ++i) {
    const std::string name = argv[i];
    long value = 0;
    if (i + 1 >= argc || !parse_count(argv[i + 1], name == "--size" ? 2 : 1, value)) {
      std::fprintf(stderr, "cloth_scalar: '%s' needs a whole number%s\n", name.c_str(),
                   name == "--size" ? " of at least 2" : " of at least 1");
      return false;
    }
    if (name == "--size") options.size = static_cast<std::size_t>(value);
    else if (name == "--frames") options.frames = static_cast<int>(value);
    else if (name == "--substeps") options.substeps = static_cast<int>(value);
    else if (name == "--iterations") options.iterations = static_cast<int>(value);
    else {
      std::fprintf(stderr, "cloth_scalar: unknown option '%s'\n", name.c_str());
      return false;
    }
    ++i;
  }
  return true;
}

/// Unsigned dihedral angle of the stencil (wing0, wing1, edge0, edge1), as the kernel
/// defines it.
Real dihedral_angle(const Vector3r& p0, const Vector3r& p1, const Vector3r& p2,
                    const Vector3r& p3) {
  const Vector3r n1 = (p2 - p0).cross(p3 - p0).normalized();
  const Vector3r n2 = (p3 - p1).cross(p2 - p1).normalized();
  return std::acos(std::clamp(n1.dot(n2), Real(-1), Real(1)));
}

struct Cloth {
  tessera::io::ClothGrid grid;
  std::vector<Vector3r> x, p, v;
  std::vector<Real> inverse_mass;
  std::vector<Real> rest_length, rest_angle;
};

/// RMS of the relative distance violation |‖p0 − p1‖ − l0| / l0 and of the bending angle
/// violation |φ − φ0| (radians) at the given positions.
std::pair<Real, Real> residuals(const Cloth& cloth, const std::vector<Vector3r>& q) {
  const auto& e = cloth.grid.edge_indices;
  const auto& b = cloth.grid.bending_indices;
  double distance = 0, bending = 0;
  for (std::size_t c = 0; c < cloth.rest_length.size(); ++c) {
    const double r = ((q[e[2 * c]] - q[e[2 * c + 1]]).norm() - cloth.rest_length[c]) /
                     cloth.rest_length[c];
    distance += r * r;
  }
  for (std::size_t c = 0; c < cloth.rest_angle.size(); ++c) {
    const double r = dihedral_angle(q[b[4 * c]], q[b[4 * c + 1]], q[b[4 * c + 2]],
                                    q[b[4 * c + 3]]) - cloth.rest_angle[c];
    bending += r * r;
  }
  return {Real(std::sqrt(distance / double(std::max<std::size_t>(1, cloth.rest_length.size())))),
          Real(std::sqrt(bending / double(std::max<std::size_t>(1, cloth.rest_angle.size()))))};
}

/// One sweep over every constraint, in input order, applying each correction at once.
void project_all(Cloth& cloth) {
  const auto& e = cloth.grid.edge_indices;
  const auto& b = cloth.grid.bending_indices;
  auto& p = cloth.p;
  const auto& w = cloth.inverse_mass;
  const Real stretch_stiffness = 1, bending_stiffness = Real(0.1);
  Vector3r c0, c1, c2, c3;
  for (std::size_t c = 0; c < cloth.rest_length.size(); ++c) {
    const auto i = e[2 * c], j = e[2 * c + 1];
    if (PositionBasedDynamics::solve_DistanceConstraint(p[i], w[i], p[j], w[j],
                                                        cloth.rest_length[c],
                                                        stretch_stiffness, c0, c1)) {
      p[i] += c0;
      p[j] += c1;
    }
  }
  for (std::size_t c = 0; c < cloth.rest_angle.size(); ++c) {
    const auto i0 = b[4 * c], i1 = b[4 * c + 1], i2 = b[4 * c + 2], i3 = b[4 * c + 3];
    if (PositionBasedDynamics::solve_DihedralConstraint(
            p[i0], w[i0], p[i1], w[i1], p[i2], w[i2], p[i3], w[i3], cloth.rest_angle[c],
            bending_stiffness, c0, c1, c2, c3)) {
      p[i0] += c0;
      p[i1] += c1;
      p[i2] += c2;
      p[i3] += c3;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (!parse_options(argc, argv, options)) return 2;

  Cloth cloth;
  const Real side = 1;  // metres
  cloth.grid = tessera::io::make_cloth_grid(options.size, options.size,
                                            side / Real(options.size - 1));
  const std::size_t n = cloth.grid.vertex_count();
  cloth.x = cloth.grid.positions;
  cloth.p = cloth.x;
  cloth.v.assign(n, Vector3r::Zero());
  const Real total_mass = Real(0.2);  // kg
  cloth.inverse_mass.assign(n, Real(n) / total_mass);
  // Pin the two corners of the top row.
  cloth.inverse_mass[n - options.size] = 0;
  cloth.inverse_mass[n - 1] = 0;

  const auto& e = cloth.grid.edge_indices;
  const auto& b = cloth.grid.bending_indices;
  for (std::size_t c = 0; c < cloth.grid.edge_count(); ++c)
    cloth.rest_length.push_back((cloth.x[e[2 * c]] - cloth.x[e[2 * c + 1]]).norm());
  for (std::size_t c = 0; c < cloth.grid.bending_count(); ++c)
    cloth.rest_angle.push_back(dihedral_angle(cloth.x[b[4 * c]], cloth.x[b[4 * c + 1]],
                                              cloth.x[b[4 * c + 2]], cloth.x[b[4 * c + 3]]));

  std::printf("cloth %zux%zu: %zu particles (2 pinned), %zu distance + %zu dihedral constraints\n",
              options.size, options.size, n, cloth.rest_length.size(), cloth.rest_angle.size());
  std::printf("%d frames of 1/60 s, %d substeps of %d iterations each, Real = %s\n",
              options.frames, options.substeps, options.iterations,
              tessera::kDoublePrecision ? "double" : "float");

  const Real frame_dt = Real(1) / 60;
  const Real dt = frame_dt / Real(options.substeps);
  const int steps = options.frames * options.substeps;
  const Vector3r gravity(0, 0, Real(-9.81));
  std::pair<Real, Real> before{}, after{};
  double projection_seconds = 0;
  for (int step = 0; step < steps; ++step) {
    for (std::size_t i = 0; i < n; ++i) {
      if (cloth.inverse_mass[i] > 0) cloth.v[i] += dt * gravity;
      cloth.p[i] = cloth.x[i] + dt * cloth.v[i];
    }
    if (step == steps - 1) before = residuals(cloth, cloth.p);
    const auto start = std::chrono::steady_clock::now();
    for (int k = 0; k < options.iterations; ++k) project_all(cloth);
    projection_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (step == steps - 1) after = residuals(cloth, cloth.p);
    for (std::size_t i = 0; i < n; ++i) {
      cloth.v[i] = (cloth.p[i] - cloth.x[i]) / dt;
      cloth.x[i] = cloth.p[i];
    }
  }

  for (const Vector3r& q : cloth.x) {
    if (!q.allFinite()) {
      std::fprintf(stderr, "cloth_scalar: the simulation produced a non-finite position\n");
      return 1;
    }
  }
  const double projections = double(steps) * options.iterations *
                             double(cloth.rest_length.size() + cloth.rest_angle.size());
  Real lowest = cloth.x[0].z();
  for (const Vector3r& q : cloth.x) lowest = std::min(lowest, q.z());
  std::printf("projection: %.3f s, %.2f M constraint projections/s (1 thread, scalar API)\n",
              projection_seconds, projections / projection_seconds * 1e-6);
  std::printf("lowest point after %.2f s: z = %.3f m\n", options.frames * double(frame_dt),
              double(lowest));
  std::printf("last substep residual before projection: distance %.3e, bending %.3e rad\n",
              double(before.first), double(before.second));
  std::printf("last substep residual after projection:  distance %.3e, bending %.3e rad\n",
              double(after.first), double(after.second));
  return 0;
}
