// tessera.Solver: the C++ Solver with NumPy state access.
//
// Which accessors copy:
//   positions, velocities          copy: (N, 3) in the user's numbering. The solver stores x, y
//                                  and z as separate arrays in its scheduled (colouring
//                                  locality) order, so an (N, 3) user-order array cannot view
//                                  them; the copy is one pass over the particles.
//   scheduled_positions,           no copy: three read-only (N,) views of x, y, z (velocities
//   scheduled_velocities           alike) in scheduled order, live (they change as the solver
//                                  steps) and valid while the solver lives; scheduled particle
//                                  i is user particle scheduled_to_user[i] (the identity when
//                                  the colouring did not renumber, e.g. locality=False).
// step(), project() and residual() release the GIL; the solver runs its own TBB arena.
#include <string>
#include <utility>
#include <vector>

#include <pybind11/stl.h>

#include <tessera/coloring/colouring_statistics.hpp>
#include <tessera/coloring/model_graph.hpp>
#include <tessera/core/fingerprint.hpp>
#include <tessera/parallel/solver.hpp>

#include "bindings.hpp"

namespace tessera::python {
namespace {

py::dict residual_dict(const Residual& residual) {
  py::dict d;
  d["constraints"] = residual.constraints;
  d["rms"] = residual.rms;
  d["max"] = residual.max;
  py::dict families;
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
    const FamilyResidual& r = residual.families[f];
    if (r.constraints == 0) continue;
    py::dict entry;
    entry["constraints"] = r.constraints;
    entry["rms"] = r.rms;
    entry["max"] = r.max;
    families[py::str(std::string(family_name(ConstraintFamily(f))))] = entry;
  }
  d["families"] = families;
  return d;
}

/// An (N, 3) user-order copy of three scheduled-order arrays.
py::array_t<Real> user_order(const Solver& solver, const AlignedVector<Real>& x,
                             const AlignedVector<Real>& y, const AlignedVector<Real>& z) {
  const std::size_t n = solver.particle_count();
  py::array_t<Real> result({py::ssize_t(n), py::ssize_t(3)});
  Real* out = result.mutable_data();
  const auto new_to_old = solver.schedule().particle_new_to_old();
  {
    py::gil_scoped_release release;
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t user = new_to_old.empty() ? i : new_to_old[i];
      out[3 * user] = x[i];
      out[3 * user + 1] = y[i];
      out[3 * user + 2] = z[i];
    }
  }
  return result;
}

py::tuple views(py::object self, const AlignedVector<Real>& x, const AlignedVector<Real>& y,
                const AlignedVector<Real>& z) {
  const std::size_t n = self.cast<const Solver&>().particle_count();
  return py::make_tuple(read_only_view(x.data(), n, self), read_only_view(y.data(), n, self),
                        read_only_view(z.data(), n, self));
}

SolverSettings make_settings(const std::string& mode, std::size_t threads,
                             const std::string& semantics, double time_step, std::size_t substeps,
                             std::size_t iterations, const py::object& gravity,
                             double velocity_damping, double jacobi_relaxation,
                             std::size_t block_size, std::size_t hybrid_threshold,
                             bool report_residuals, bool record_convergence, bool check_finite,
                             double divergence_rms, const std::string& sequential_order,
                             const std::string& contact_scheduling,
                             const std::string& particle_layout,
                             const std::string& sweep_order, std::size_t particles_per_part) {
  SolverSettings s;
  s.mode = parse_solver_mode(mode);
  s.threads = threads;
  if (semantics == "compliance")
    s.semantics = ConstraintSemantics::compliance;
  else if (semantics == "stiffness")
    s.semantics = ConstraintSemantics::stiffness;
  else
    throw InvalidInput("solver settings: semantics must be 'compliance' (XPBD) or 'stiffness' "
                       "(PBD), not '" + semantics + "'");
  s.time_step = Real(time_step);
  s.substeps = substeps;
  s.iterations = iterations;
  const std::vector<Real> g = to_reals(gravity, "solver settings: gravity", 3);
  s.gravity = Vector3r(g[0], g[1], g[2]);
  s.velocity_damping = Real(velocity_damping);
  s.jacobi_relaxation = Real(jacobi_relaxation);
  s.block_size = block_size;
  s.hybrid_threshold = hybrid_threshold;
  s.report_residuals = report_residuals;
  s.record_convergence = record_convergence;
  s.check_finite = check_finite;
  s.divergence_rms = Real(divergence_rms);
  s.sequential_order = parse_sequential_order(sequential_order);
  s.contact_scheduling = parse_contact_scheduling(contact_scheduling);
  s.particle_layout = parse_particle_layout(particle_layout);
  s.sweep_order = parse_sweep_order(sweep_order);
  s.particles_per_part = particles_per_part;
  return s;
}

}  // namespace

void bind_solver(py::module_& m) {
  py::class_<Solver> solver_class(m, "Solver",
                     "XPBD (or PBD) time stepping of a copy of a Model over a colouring's schedule.\n\n"
                     "Solver(model, colouring, mode='gs', threads=0, ...): colouring from\n"
                     "tessera.colour(model) (not needed for mode='sequential'); it is checked against\n"
                     "the model (ValueError if it does not fit). threads=0 uses every hardware\n"
                     "thread; any count gives bitwise the same result. positions/velocities copy\n"
                     "(user order); scheduled_positions/scheduled_velocities are read-only views.");
  solver_class
      .def(py::init([](const Model& model, const PyColouring* colouring, const std::string& mode,
                       std::size_t threads, const std::string& semantics, double time_step,
                       std::size_t substeps, std::size_t iterations, const py::object& gravity,
                       double velocity_damping, double jacobi_relaxation, std::size_t block_size,
                       std::size_t hybrid_threshold, bool report_residuals,
                       bool record_convergence, bool check_finite, double divergence_rms,
                       const std::string& sequential_order, const std::string& contact_scheduling,
                       const std::string& particle_layout, const std::string& sweep_order,
                       std::size_t particles_per_part) {
             const SolverSettings settings = make_settings(
                 mode, threads, semantics, time_step, substeps, iterations, gravity,
                 velocity_damping, jacobi_relaxation, block_size, hybrid_threshold,
                 report_residuals, record_convergence, check_finite, divergence_rms,
                 sequential_order, contact_scheduling, particle_layout, sweep_order,
                 particles_per_part);
             if (settings.mode == SolverMode::sequential && !colouring) return Solver(model, settings);
             if (!colouring)
               throw InvalidInput("solver: mode " + mode +
                                  " needs a colouring (tessera.colour(model))");
             py::gil_scoped_release release;
             const ColouringValidation check = validate(constraint_graph(model), colouring->colouring);
             if (!check)
               throw InvalidInput("solver: the colouring does not fit the model: " + check.problem);
             return settings.mode == SolverMode::sequential
                        ? Solver(model, settings)
                        : Solver(model, colouring->colouring, settings);
           }),
           py::arg("model"), py::arg("colouring") = py::none(), py::kw_only(),
           py::arg("mode") = "gs", py::arg("threads") = 0, py::arg("semantics") = "compliance",
           py::arg("time_step") = 1.0 / 60.0, py::arg("substeps") = 1, py::arg("iterations") = 10,
           py::arg("gravity") = py::make_tuple(0.0, -9.81, 0.0), py::arg("velocity_damping") = 0.0,
           py::arg("jacobi_relaxation") = double(kDefaultJacobiRelaxation),
           py::arg("block_size") = kDefaultBlockSize,
           py::arg("hybrid_threshold") = kDefaultHybridThreshold,
           py::arg("report_residuals") = true, py::arg("record_convergence") = false,
           py::arg("check_finite") = true, py::arg("divergence_rms") = 10.0,
           py::arg("sequential_order") = "groups",
           py::arg("contact_scheduling") =
               std::string(contact_scheduling_name(kDefaultContactScheduling)),
           py::arg("particle_layout") = std::string(particle_layout_name(kDefaultParticleLayout)),
           py::arg("sweep_order") = std::string(sweep_order_name(SweepOrder::automatic)),
           py::arg("particles_per_part") = 0)
      .def(
          "step",
          [](Solver& solver, std::size_t steps) {
            for (std::size_t s = 0; s < steps; ++s) solver.step();
          },
          py::arg("steps") = 1, py::call_guard<py::gil_scoped_release>(),
          "Advances `steps` time steps (each time_step, in substeps). Raises\n"
          "tessera.NumericalFailure, state restored to before the failing step, if a position or\n"
          "velocity became non-finite or the step diverged (RMS residual above divergence_rms).\n"
          "Releases the GIL.")
      .def(
          "project",
          [](Solver& solver, std::size_t iterations, std::optional<double> dt) {
            const SolverSettings& s = solver.settings();
            solver.project(iterations,
                           dt ? Real(*dt) : s.time_step / Real(s.substeps ? s.substeps : 1));
          },
          py::arg("iterations") = 1, py::arg("dt") = py::none(),
          py::call_guard<py::gil_scoped_release>(),
          "Projection sweeps at the current positions, no time integration (λ kept; see\n"
          "reset_lambdas). dt: the compliance time step, default time_step / substeps.")
      .def("reset_lambdas", &Solver::reset_lambdas, "Zeroes the XPBD multipliers.")
      .def(
          "residual", [](Solver& solver) {
            Residual r;
            {
              py::gil_scoped_release release;
              r = solver.residual();
            }
            return residual_dict(r);
          },
          "The constraint violation now: {'constraints', 'rms', 'max', 'families': {name:\n"
          "{'constraints', 'rms', 'max'}}}, normalised per family.")
      .def_property_readonly(
          "last_step",
          [](const Solver& solver) {
            const StepReport& report = solver.last_step();
            py::dict d;
            d["residual_before"] = residual_dict(report.residual_before);
            d["residual_after"] = residual_dict(report.residual_after);
            py::list history;
            for (const Residual& r : report.history) history.append(residual_dict(r));
            d["history"] = history;
            return d;
          },
          "Residuals before and after the last substep's iterations of the last step (and\n"
          "after every iteration with record_convergence).")
      .def_property_readonly("particle_count", &Solver::particle_count)
      .def_property_readonly(
          "positions",
          [](const Solver& s) {
            const ParticleState& p = s.scheduled_state();
            return user_order(s, p.x, p.y, p.z);
          },
          "(N, 3) copy of the positions, user numbering.")
      .def_property_readonly(
          "velocities",
          [](const Solver& s) {
            const ParticleState& p = s.scheduled_state();
            return user_order(s, p.velocity_x, p.velocity_y, p.velocity_z);
          },
          "(N, 3) copy of the velocities, user numbering.")
      .def_property_readonly(
          "scheduled_positions",
          [](py::object self) {
            const ParticleState& p = self.cast<const Solver&>().scheduled_state();
            return views(self, p.x, p.y, p.z);
          },
          "(x, y, z): read-only live views (no copy) in scheduled order; see scheduled_to_user.")
      .def_property_readonly(
          "scheduled_velocities",
          [](py::object self) {
            const ParticleState& p = self.cast<const Solver&>().scheduled_state();
            return views(self, p.velocity_x, p.velocity_y, p.velocity_z);
          },
          "(vx, vy, vz): read-only live views (no copy) in scheduled order.")
      .def_property_readonly(
          "scheduled_to_user",
          [](py::object self) -> py::array_t<ParticleIndex> {
            const Solver& s = self.cast<const Solver&>();
            const auto map = s.schedule().particle_new_to_old();
            if (!map.empty()) return read_only_view(map.data(), map.size(), self);
            py::array_t<ParticleIndex> identity(py::ssize_t(s.particle_count()));
            for (std::size_t i = 0; i < s.particle_count(); ++i)
              identity.mutable_data()[i] = ParticleIndex(i);
            return identity;
          },
          "The user's index of every scheduled particle.")
      .def(
          "set_positions",
          [](Solver& s, const py::object& positions) {
            const std::vector<Vector3r> p = to_vectors(positions, "positions", s.particle_count());
            for (std::size_t i = 0; i < p.size(); ++i) s.set_position(ParticleIndex(i), p[i]);
          },
          py::arg("positions"), "Sets every position from an (N, 3) array, user numbering.")
      .def(
          "set_velocities",
          [](Solver& s, const py::object& velocities) {
            const std::vector<Vector3r> v = to_vectors(velocities, "velocities", s.particle_count());
            for (std::size_t i = 0; i < v.size(); ++i) s.set_velocity(ParticleIndex(i), v[i]);
          },
          py::arg("velocities"), "Sets every velocity from an (N, 3) array, user numbering.")
      .def("multiplier", &Solver::lambda, py::arg("constraint"),
           "The XPBD multiplier λ of a constraint (global id); 0 for families without one.")
      .def(
          "state_hash",
          [](const Solver& s) { return state_hash(s.positions()); },
          "The positions' hash as `tessera run` prints it (equal hashes: bitwise equal states).")
      .def_property_readonly(
          "statistics",
          [](const Solver& s) {
            const SolverStatistics& st = s.statistics();
            py::dict d;
            d["particles"] = st.particles;
            py::dict per_family;
            for (std::size_t f = 0; f < kConstraintFamilyCount; ++f)
              if (st.constraints_per_family[f] > 0)
                per_family[py::str(std::string(family_name(ConstraintFamily(f))))] =
                    st.constraints_per_family[f];
            d["constraints_per_family"] = per_family;
            d["constraints"] = st.constraints;
            d["coloured_phases"] = st.coloured_phases;
            d["phase_sizes"] = st.phase_sizes;
            d["jacobi_constraints"] = st.jacobi_constraints;
            // Part-major: the parts the sweep ran and the constraints they held (0 otherwise).
            d["parts"] = st.part_count;
            // The order swept (sweep_order "auto": the one it chose), as the tool's summary.
            d["sweep_order"] = std::string(sweep_order_name(s.schedule().options().sweep_order));
            d["part_constraints"] = st.part_constraints;
            d["threads"] = st.threads;
            d["seconds_schedule"] = st.seconds_schedule;
            d["seconds_projection"] = st.seconds_projection;
            d["seconds_stepping"] = st.seconds_stepping;
            d["projections"] = st.projections;
            d["steps"] = st.steps;
            d["steps_in_one_region"] = st.steps_in_one_region;
            return d;
          },
          "What the solver counted and timed since construction.")
      .def_property_readonly(
          "settings",
          [](const Solver& s) {
            const SolverSettings& st = s.settings();
            py::dict d;
            d["mode"] = std::string(solver_mode_name(st.mode));
            d["threads"] = st.threads;
            d["semantics"] = st.semantics == ConstraintSemantics::compliance ? "compliance" : "stiffness";
            d["time_step"] = double(st.time_step);
            d["substeps"] = st.substeps;
            d["iterations"] = st.iterations;
            d["gravity"] = py::make_tuple(double(st.gravity.x()), double(st.gravity.y()), double(st.gravity.z()));
            d["velocity_damping"] = double(st.velocity_damping);
            d["jacobi_relaxation"] = double(st.jacobi_relaxation);
            d["block_size"] = st.block_size;
            d["hybrid_threshold"] = st.hybrid_threshold;
            d["report_residuals"] = st.report_residuals;
            d["record_convergence"] = st.record_convergence;
            d["check_finite"] = st.check_finite;
            d["contact_scheduling"] = std::string(contact_scheduling_name(st.contact_scheduling));
            return d;
          },
          "The settings the solver runs with.")
      .def("__repr__", [](const Solver& s) {
        return "<tessera.Solver " + std::string(solver_mode_name(s.settings().mode)) + ": " +
               std::to_string(s.particle_count()) + " particles, " +
               std::to_string(s.statistics().constraints) + " constraints, " +
               std::to_string(s.statistics().threads) + " threads>";
      });
  bind_collisions(m, solver_class);
}

}  // namespace tessera::python
