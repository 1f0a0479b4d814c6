// Embedding Tessera's parallel solver: a cloth built by hand through the public API (particles,
// distance and dihedral bending constraints), coloured with a named strategy, stepped by the
// coloured Gauss-Seidel solver on TBB workers, and read back in the user's particle numbering.
// It exits non-zero (so ctest fails) unless the pinned corners stayed exactly where they were,
// the free corner fell, no edge is stretched by 10 % or more and every position is finite.
//
// User code: 58 lines (not counting blank lines and comments).
#include <cstdio>
#include <utility>
#include <vector>

#include <tessera/coloring/run_colouring.hpp>
#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/model_graph.hpp>
#include <tessera/core/model.hpp>
#include <tessera/parallel/residual.hpp>
#include <tessera/parallel/solver.hpp>

using namespace tessera;

int main() {
  // A 1 m × 1 m cloth of n × n particles lying flat in the xz plane; particle r·n + c is at
  // column c of row r. The two corners of row 0 are pinned (inverse mass 0).
  constexpr ParticleIndex n = 20;
  const Real spacing = Real(1) / Real(n - 1);
  std::vector<Vector3r> rest;
  std::vector<Real> inverse_masses;
  for (ParticleIndex r = 0; r < n; ++r)
    for (ParticleIndex c = 0; c < n; ++c) {
      rest.emplace_back(Real(c) * spacing, Real(0), Real(r) * spacing);
      inverse_masses.push_back(r == 0 && (c == 0 || c == n - 1) ? Real(0) : Real(1));
    }

  // Quad a b / d e (a = r·n + c, b right of a, d below a) is split along a-e into triangles
  // (a, b, e) and (a, e, d). Distance constraints on every mesh edge; a dihedral stencil
  // (wing, wing, shared edge) across every interior edge: the diagonal a-e, the quad's right
  // edge b-e and its lower edge d-e when a neighbouring quad is there.
  std::vector<ParticleIndex> edges, stencils;
  for (ParticleIndex r = 0; r + 1 < n; ++r)
    for (ParticleIndex c = 0; c + 1 < n; ++c) {
      const ParticleIndex a = r * n + c, b = a + 1, d = a + n, e = d + 1;
      edges.insert(edges.end(), {a, b, a, d, a, e});
      if (c + 2 == n) edges.insert(edges.end(), {b, e});
      if (r + 2 == n) edges.insert(edges.end(), {d, e});
      stencils.insert(stencils.end(), {b, d, a, e});
      if (c + 2 < n) stencils.insert(stencils.end(), {a, e + 1, b, e});
      if (r + 2 < n) stencils.insert(stencils.end(), {a, e + n, d, e});
    }

  // The model: particles plus one batch per constraint family (inextensible edges, XPBD
  // bending compliance 1e-3). Each make_* validates its input and throws InvalidInput.
  Model model;
  model.particles = ParticleState(rest, inverse_masses);
  model.constraints.distance = make_distance_constraints({edges, rest});
  model.constraints.dihedral = make_dihedral_constraints({stencils, rest, Real(1), Real(1e-3)});

  // Colour the constraint graph with a named strategy; the locality pass also renumbers the
  // particles internally, which the solver hides: everything below is in our numbering.
  const ColouringRun run =
      run_colouring(ColouringRegistry::with_builtin_strategies().get("stencil"),
                    constraint_graph(model), ColouringOptions{.locality = true});

  // Two seconds: 120 steps of 1/60 s, each 4 substeps of 10 Gauss-Seidel sweeps, damped so
  // the cloth settles hanging from its pinned corners. The solver runs in its own task arena
  // of `threads` workers; any thread count gives bitwise the same positions.
  const SolverSettings settings{.mode = SolverMode::gs, .threads = 2, .substeps = 4,
                                .iterations = 10, .velocity_damping = 2};
  Solver solver(std::move(model), run.colouring, settings);
  for (int step = 0; step < 120; ++step) solver.step();

  // Read back (user's numbering) and check what physics says must hold. The residuals are
  // those before and after the iterations of the last substep.
  const std::vector<Vector3r> x = solver.positions();
  const ParticleIndex free_corner = n * n - 1;
  const double fall = double(rest[free_corner].y() - x[free_corner].y());
  const StepReport& report = solver.last_step();
  bool ok = fall > 0.5 && report.residual_after.of(ConstraintFamily::distance).max < 0.1;
  for (ParticleIndex i = 0; i < n * n; ++i)
    ok = ok && x[i].allFinite() && (inverse_masses[i] != 0 || x[i] == rest[i]);

  std::printf("%zu particles, %zu constraints in %zu colours (%s), %zu threads\n", x.size(),
              run.statistics.constraints, run.statistics.colours,
              run.statistics.strategy.c_str(), solver.statistics().threads);
  std::printf("free corner fell %.3f m in 2 s\nresidual before: %s\nresidual after:  %s\n", fall,
              format_residual(report.residual_before).c_str(),
              format_residual(report.residual_after).c_str());
  std::puts(ok ? "ok" : "FAILED: a pinned corner moved, the cloth did not fall, an edge "
                        "stretched by 10 % or a position is not finite");
  return ok ? 0 : 1;
}
