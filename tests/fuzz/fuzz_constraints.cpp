// Fuzzes the path from plain arrays to a stepping solver with bytes decoded as a model:
//   particle count, positions, inverse masses        → ParticleState
//   family records (family, indices, parameters)     → make_<family>_constraints
//   strategy name, colouring options                 → constraint_graph → Colouring
//   mode, threads, time step, substeps, iterations…  → Solver → one step()
// Indices may be out of range and repeated, values NaN, ±inf, huge or tiny, names unknown.
// InvalidInput (bad input) and NumericalFailure (a step that left the finite numbers) are
// the expected answers; findings are crashes, sanitizer reports, hangs, and broken
// promises checked here: a step that returns normally leaves every position finite, and a
// step that throws NumericalFailure leaves the positions exactly as they were before it.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/model.hpp>
#include <tessera/coloring/model_graph.hpp>
#include <tessera/parallel/solver.hpp>

#pragma GCC diagnostic error "-Wswitch"

namespace {

using namespace tessera;

/// Reads the input front to back; past the end every read gives 0.
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool empty() const { return at_ >= size_; }
  std::uint8_t byte() { return at_ < size_ ? data_[at_++] : 0; }
  /// A value from a byte: mostly small numbers around [-4, 4), sometimes the edge cases.
  Real value() {
    const std::uint8_t tag = byte();
    if (tag < 224) return Real(int(tag) - 112) / Real(28);
    constexpr Real inf = std::numeric_limits<Real>::infinity();
    const std::array<Real, 31> special = {
        std::numeric_limits<Real>::quiet_NaN(), inf, -inf, 0, Real(-0.0), Real(1e-12),
        Real(1e12), Real(1e-30), Real(1e30), Real(-1e30), Real(1e6), Real(-1e6), Real(0.5),
        Real(0.49999), Real(-0.99999), Real(2), Real(1.99999), Real(1e-6), Real(1e-3),
        Real(-1e-12), std::numeric_limits<Real>::denorm_min(), std::numeric_limits<Real>::max(),
        std::numeric_limits<Real>::lowest(), std::numeric_limits<Real>::min(), Real(1),
        Real(1) / Real(60), Real(100), Real(1e4), Real(0.3), Real(-1), Real(3)};
    if (std::size_t(tag - 224) < special.size()) return special[tag - 224];
    Real raw = 0;  // tag 255: the next bytes as they are
    std::uint8_t bits[sizeof(Real)];
    for (auto& b : bits) b = byte();
    std::memcpy(&raw, bits, sizeof(Real));
    return raw;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

void require(bool condition, const char* what) {
  if (!condition) {
    std::fprintf(stderr, "fuzz: promise broken: %s\n", what);
    std::abort();
  }
}

struct Decoded {
  std::size_t particles = 0;
  std::vector<Vector3r> positions;
  std::vector<Real> inverse_masses;
};

/// Up to `count` constraints of `arity` indices each, indices in [0, particles + 2): some out
/// of range, some repeated.
std::vector<ParticleIndex> indices(Bytes& in, std::size_t arity, std::size_t particles) {
  const std::size_t count = in.byte() % 9;
  std::vector<ParticleIndex> result(count * arity + (in.byte() % 16 == 0 ? 1 : 0));
  for (ParticleIndex& i : result) i = ParticleIndex(in.byte() % (particles + 2));
  return result;
}

/// One family record: its constraints built from the bytes into the model, or InvalidInput.
void add_family(Bytes& in, const Decoded& d, ConstraintSets& sets) {
  const std::size_t n = d.particles;
  const std::span<const Vector3r> rest = d.positions;
  // One case per family, and no default: a family added to the list without a case here
  // fails the build (-Werror=switch below).
  switch (ConstraintFamily(in.byte() % kConstraintFamilyCount)) {
    case ConstraintFamily::distance: {
      const auto p = indices(in, 2, n);
      sets.distance = make_distance_constraints({p, rest, in.value(), in.value()});
      break;
    }
    case ConstraintFamily::dihedral: {
      const auto p = indices(in, 4, n);
      sets.dihedral = make_dihedral_constraints({p, rest, in.value(), in.value()});
      break;
    }
    case ConstraintFamily::isometric_bending: {
      const auto p = indices(in, 4, n);
      sets.isometric_bending = make_isometric_bending_constraints({p, rest, in.value(), in.value()});
      break;
    }
    case ConstraintFamily::volume: {
      const auto p = indices(in, 4, n);
      sets.volume = make_volume_constraints({p, rest, in.value(), in.value()});
      break;
    }
    case ConstraintFamily::edge_point_distance:
    case ConstraintFamily::triangle_point_distance:
    case ConstraintFamily::edge_edge_distance: {
      const int kind = in.byte() % 3;
      const auto p = indices(in, std::size_t(kind == 0 ? 3 : 4), n);
      std::vector<Real> distances;
      if (in.byte() % 2)
        for (std::size_t c = 0; c < p.size() / 3 + in.byte() % 2; ++c) distances.push_back(in.value());
      ProximityDistanceConstraintInput input{p, n, in.value(), distances, in.value(), in.value()};
      if (kind == 0) sets.edge_point_distance = make_edge_point_distance_constraints(input);
      if (kind == 1) sets.triangle_point_distance = make_triangle_point_distance_constraints(input);
      if (kind == 2) sets.edge_edge_distance = make_edge_edge_distance_constraints(input);
      break;
    }
    case ConstraintFamily::strain_triangle: {
      const auto p = indices(in, 3, n);
      sets.strain_triangle = make_strain_triangle_constraints(
          {p, rest, in.value(), in.value(), in.value(), in.byte() % 2 == 1, in.byte() % 2 == 1});
      break;
    }
    case ConstraintFamily::strain_tetra: {
      const auto p = indices(in, 4, n);
      const Vector3r stretch(in.value(), in.value(), in.value());
      const Vector3r shear(in.value(), in.value(), in.value());
      sets.strain_tetra = make_strain_tetra_constraints(
          {p, rest, stretch, shear, in.byte() % 2 == 1, in.byte() % 2 == 1});
      break;
    }
    case ConstraintFamily::fem_triangle: {
      const auto p = indices(in, 3, n);
      sets.fem_triangle = make_fem_triangle_constraints(
          {p, rest, in.value(), in.value(), in.value(), in.value(), in.value()});
      break;
    }
    case ConstraintFamily::fem_tetra: {
      const auto p = indices(in, 4, n);
      sets.fem_tetra =
          make_fem_tetra_constraints({p, rest, in.value(), in.value(), in.byte() % 2 == 1});
      break;
    }
    case ConstraintFamily::shape_matching: {
      // Offsets from the bytes, usually consistent, sometimes not.
      const std::size_t clusters = in.byte() % 4;
      std::vector<std::uint32_t> offsets{std::uint32_t(in.byte() % 8 == 0 ? 1 : 0)};
      std::vector<ParticleIndex> p;
      for (std::size_t c = 0; c < clusters; ++c) {
        const std::size_t size = in.byte() % 6;
        for (std::size_t e = 0; e < size; ++e) p.push_back(ParticleIndex(in.byte() % (n + 2)));
        offsets.push_back(std::uint32_t(p.size() + (in.byte() % 16 == 0 ? 1 : 0)));
      }
      sets.shape_matching = make_shape_matching_constraints(
          {offsets, p, rest, d.inverse_masses, in.value(), in.byte() % 2 == 1});
      break;
    }
    case ConstraintFamily::particle_tet_contact: {
      const auto p = indices(in, 5, n);
      std::vector<Vector3r> barycentric, normals;
      for (std::size_t c = 0; c < p.size() / 5 + in.byte() % 2; ++c) {
        barycentric.emplace_back(in.value(), in.value(), in.value());
        // Mostly unit normals, sometimes not.
        const Vector3r normal(in.value(), in.value(), in.value());
        normals.push_back(in.byte() < 224 && normal.norm() > Real(1e-3) ? Vector3r(normal.normalized())
                                                                         : normal);
      }
      const ParticleState state(d.positions, d.inverse_masses);
      sets.particle_tet_contact =
          make_particle_tet_contacts({p, barycentric, normals, in.value()}, state);
      break;
    }
    case ConstraintFamily::tether: {
      const auto p = indices(in, 2, n);
      std::vector<Real> reach;
      for (std::size_t c = 0; c < p.size() / 2 + (in.byte() % 8 == 0 ? 1 : 0); ++c)
        reach.push_back(in.value());
      sets.tether = make_tether_constraints(
          {.particles = p,
           .rest_positions = rest,
           .max_distances = in.byte() % 2 ? std::span<const Real>(reach) : std::span<const Real>(),
           .max_distance = in.byte() % 2 ? in.value() : Real(0),
           .stiffness = in.value(),
           .compliance = in.value()});
      break;
    }
    case ConstraintFamily::collider_contact: {
      const auto p = indices(in, 1, n);
      // Mostly unit normals, sometimes not; counts off by one now and then.
      const std::size_t count = p.size() + (in.byte() % 8 == 0 ? 1 : 0);
      std::vector<Vector3r> normals, anchors;
      std::vector<Real> offsets, speeds;
      for (std::size_t c = 0; c < count; ++c) {
        const Vector3r normal(in.value(), in.value(), in.value());
        normals.push_back(in.byte() < 224 && normal.norm() > Real(1e-3)
                              ? Vector3r(normal.normalized())
                              : normal);
        offsets.push_back(in.value());
        anchors.emplace_back(in.value(), in.value(), in.value());
        speeds.push_back(in.value());
      }
      sets.collider_contact = make_collider_contacts(
          {p, n, normals, offsets, anchors, speeds, in.value(), in.value(), in.value()});
      break;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Bytes in(data, size);
  Decoded d;
  d.particles = in.byte() % 33;
  for (std::size_t i = 0; i < d.particles; ++i) {
    // Mostly a jittered grid point, so rest shapes are not all degenerate.
    const Real jitter = in.byte() < 192 ? Real(0) : in.value();
    d.positions.emplace_back(Real(i % 3) + jitter, Real(i / 3 % 3), Real(i / 9) + in.value() / 8);
  }
  for (std::size_t i = 0; i < d.particles; ++i)
    d.inverse_masses.push_back(in.byte() < 200 ? Real(1) : in.value());
  // A few records address a particle count other than the model's (a batch built for
  // another model must be refused by the graph or the solver, not read out of bounds).
  const std::size_t constraint_particles = in.byte() % 16 == 0 ? d.particles + 3 : d.particles;
  Decoded for_constraints = d;
  for_constraints.particles = constraint_particles;
  for_constraints.positions.resize(constraint_particles, Vector3r::Zero());
  for_constraints.inverse_masses.resize(constraint_particles, Real(1));

  const ColouringRegistry registry = ColouringRegistry::with_builtin_strategies();
  const std::vector<std::string_view> names = registry.names();
  try {
    Model model;
    model.particles = ParticleState(d.positions, d.inverse_masses);
    const std::size_t records = in.byte() % 4;
    for (std::size_t r = 0; r < records; ++r) add_family(in, for_constraints, model.constraints);

    const std::uint8_t strategy_byte = in.byte();
    const std::string strategy = strategy_byte < 240 ? std::string(names[strategy_byte % names.size()])
                                                     : std::string("no-such-strategy");
    ColouringOptions options;
    options.seed = in.byte();
    options.reduce = in.byte() % 2 == 1;
    options.balance = in.byte() % 2 == 1;
    options.locality = in.byte() % 2 == 1;
    options.particles_per_part = in.byte() % 8;
    options.reduction_rounds = in.byte() % 4;

    SolverSettings settings;
    settings.mode = SolverMode(in.byte() % 4);
    settings.threads = 1 + in.byte() % 2;
    settings.semantics = in.byte() % 2 ? ConstraintSemantics::compliance : ConstraintSemantics::stiffness;
    settings.time_step = in.byte() < 224 ? Real(1) / Real(60) : in.value();
    settings.substeps = in.byte() % 4;
    settings.iterations = in.byte() % 5;
    settings.velocity_damping = in.byte() < 224 ? Real(0) : in.value();
    settings.jacobi_relaxation = in.byte() < 224 ? kDefaultJacobiRelaxation : in.value();
    settings.block_size = in.byte() % 20;
    settings.hybrid_threshold = in.byte() % 20;
    if (in.byte() >= 240) settings.gravity = Vector3r(in.value(), in.value(), in.value());
    // Part-major over the colouring's parts, or runs of its particle order (a part size only
    // where it sizes runs: any other is InvalidInput), or the order auto picks (part-major
    // only with 32 parts of one particle each: the scenes have at most 32 particles).
    constexpr SweepOrder kOrders[] = {SweepOrder::colour_major, SweepOrder::part_major,
                                      SweepOrder::automatic};
    settings.sweep_order = kOrders[in.byte() % 3];
    settings.particles_per_part = in.byte() % 8;

    const Colouring colouring = registry.get(strategy).colour(constraint_graph(model), options);
    Solver solver(std::move(model), colouring, settings);
    for (int step = 0; step < 2; ++step) {
      const std::vector<Vector3r> before = solver.positions();
      try {
        solver.step();
      } catch (const NumericalFailure&) {
        const std::vector<Vector3r> after = solver.positions();
        require(std::equal(before.begin(), before.end(), after.begin(), after.end(),
                           [](const Vector3r& a, const Vector3r& b) {
                             return std::memcmp(a.data(), b.data(), sizeof(Real) * 3) == 0;
                           }),
                "NumericalFailure left the positions changed");
        break;
      }
      for (const Vector3r& p : solver.positions())
        require(p.allFinite(), "step() returned normally with a non-finite position");
    }
  } catch (const InvalidInput&) {
  }
  return 0;
}
