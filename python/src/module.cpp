// The Python module tessera._tessera (re-exported by the package tessera): exceptions,
// listings, scenes and meshes, the constraint graph and colouring. Model and Solver are bound
// in model.cpp and solver.cpp.
//
// Errors: tessera::InvalidInput becomes ValueError and tessera::NumericalFailure becomes
// tessera.NumericalFailure (a RuntimeError), both with the C++ message unchanged.
// The GIL is released while a graph is built and while a strategy and its post-passes run; a
// strategy written in Python takes it back for its own call.
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <tessera/coloring/colouring_statistics.hpp>
#include <tessera/coloring/run_colouring.hpp>
#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/model_graph.hpp>
#include <tessera/core/config.hpp>
#include <tessera/core/fingerprint.hpp>
#include <tessera/core/simd.hpp>
#include <tessera/io/mesh_readers.hpp>
#include <tessera/io/scene_file.hpp>
#include <tessera/io/scenes.hpp>
#include <tessera/parallel/schedule.hpp>

#include "bindings.hpp"

namespace tessera::python {

// ---- array conversions (declared in bindings.hpp) ----------------------------------------

std::string shape_of(const py::array& array) {
  std::string text = "(";
  for (py::ssize_t d = 0; d < array.ndim(); ++d)
    text += (d ? ", " : "") + std::to_string(array.shape(d));
  return text + (array.ndim() == 1 ? ",)" : ")");
}

std::vector<Vector3r> to_vectors(const py::handle& object, const std::string& what,
                                 std::size_t expected) {
  const RealArray array = RealArray::ensure(object);
  if (!array) throw py::error_already_set();
  const bool empty_list = array.ndim() == 1 && array.shape(0) == 0;
  if (!empty_list && (array.ndim() != 2 || array.shape(1) != 3))
    throw InvalidInput(what + " must have shape (N, 3), not " + shape_of(array));
  const std::size_t n = empty_list ? 0 : std::size_t(array.shape(0));
  if (expected != SIZE_MAX && n != expected)
    throw InvalidInput(what + " must have " + std::to_string(expected) + " rows (one per particle), not " +
                       std::to_string(n));
  std::vector<Vector3r> points(n);
  const Real* data = array.data();
  for (std::size_t i = 0; i < n; ++i) points[i] = Vector3r(data[3 * i], data[3 * i + 1], data[3 * i + 2]);
  return points;
}

std::vector<Real> to_reals(const py::handle& object, const std::string& what, std::size_t expected) {
  const RealArray array = RealArray::ensure(object);
  if (!array) throw py::error_already_set();
  if (array.ndim() != 1) throw InvalidInput(what + " must be a 1-D array, not " + shape_of(array));
  const std::size_t n = std::size_t(array.shape(0));
  if (expected != SIZE_MAX && n != expected)
    throw InvalidInput(what + " must have " + std::to_string(expected) + " values, not " +
                       std::to_string(n));
  return std::vector<Real>(array.data(), array.data() + n);
}

std::vector<std::uint32_t> to_indices(const py::handle& object, const std::string& what,
                                      std::size_t columns) {
  const py::array raw = py::array::ensure(object);
  if (!raw) throw py::error_already_set();
  if (raw.size() > 0 && raw.dtype().kind() != 'i' && raw.dtype().kind() != 'u')
    throw InvalidInput(what + " must be integers, not " + std::string(py::str(raw.dtype())));
  const IndexArray array = IndexArray::ensure(raw);
  const bool empty_list = array.ndim() == 1 && array.shape(0) == 0;
  if (columns > 0 && !empty_list &&
      (array.ndim() != 2 || array.shape(1) != py::ssize_t(columns)))
    throw InvalidInput(what + " must have shape (M, " + std::to_string(columns) + "), not " +
                       shape_of(array));
  if (columns == 0 && array.ndim() != 1)
    throw InvalidInput(what + " must be a 1-D array, not " + shape_of(array));
  std::vector<std::uint32_t> result(std::size_t(array.size()));
  const std::int64_t* data = array.data();
  for (std::size_t i = 0; i < result.size(); ++i) {
    if (data[i] < 0 || data[i] > std::int64_t(UINT32_MAX))
      throw InvalidInput(what + ": index " + std::to_string(data[i]) + " at position " +
                         std::to_string(i) + " is not in [0, 2^32)");
    result[i] = std::uint32_t(data[i]);
  }
  return result;
}

py::array_t<Real> vectors_to_numpy(std::span<const Vector3r> points) {
  py::array_t<Real> result({py::ssize_t(points.size()), py::ssize_t(3)});
  Real* out = result.mutable_data();
  for (std::size_t i = 0; i < points.size(); ++i)
    for (int k = 0; k < 3; ++k) out[3 * i + std::size_t(k)] = points[i][k];
  return result;
}

namespace {

py::dict simulation_dict(const io::SimulationSettings& s) {
  py::dict d;
  d["gravity"] = py::make_tuple(double(s.gravity.x()), double(s.gravity.y()), double(s.gravity.z()));
  d["time_step"] = double(s.time_step);
  d["substeps"] = s.substeps;
  d["iterations"] = s.iterations;
  d["frames"] = s.frames;
  d["velocity_damping"] = double(s.velocity_damping);
  d["strategy"] = s.strategy;
  d["mode"] = s.mode;
  d["sequential_order"] = s.sequential_order;
  d["divergence_rms"] = double(s.divergence_rms);
  d["threads"] = s.threads;
  return d;
}

/// A colouring strategy written in Python: fn(graph) returns one colour per constraint.
class PythonStrategy final : public ColouringStrategy {
 public:
  PythonStrategy(py::function function, py::object graph, std::string name)
      : function_(std::move(function)), graph_(std::move(graph)), name_(std::move(name)) {}
  ~PythonStrategy() override {
    py::gil_scoped_acquire gil;
    function_ = py::function();
    graph_ = py::object();
  }
  std::string_view name() const override { return name_; }
  std::string_view description() const override { return "a Python function"; }
  Colouring colour(const ConstraintGraph& graph, const ColouringOptions&) const override {
    std::vector<std::uint32_t> colours;
    {
      py::gil_scoped_acquire gil;
      const py::object result = function_(graph_);
      colours = to_indices(result, "strategy '" + name_ + "': the colours", 0);
    }
    if (colours.size() != graph.constraint_count())
      throw InvalidInput("strategy '" + name_ + "' returned " + std::to_string(colours.size()) +
                         " colours for " + std::to_string(graph.constraint_count()) +
                         " constraints");
    Colouring colouring = Colouring::from_colours(std::move(colours));
    if (const ColouringValidation check = validate(graph, colouring); !check)
      throw InvalidInput("strategy '" + name_ + "' gave an invalid colouring: " + check.problem);
    return colouring;
  }

 private:
  py::function function_;
  py::object graph_;
  std::string name_;
};

std::shared_ptr<ConstraintGraph> graph_of(const py::object& source, py::object& graph_object) {
  if (py::isinstance<ConstraintGraph>(source)) {
    graph_object = source;
    return source.cast<std::shared_ptr<ConstraintGraph>>();
  }
  const Model& model = source.cast<const Model&>();
  std::shared_ptr<ConstraintGraph> graph;
  {
    py::gil_scoped_release release;
    graph = std::make_shared<ConstraintGraph>(constraint_graph(model));
  }
  graph_object = py::cast(graph);
  return graph;
}

}  // namespace

// ---- colouring results (bindings.hpp) ---------------------------------------------------

py::dict PyColouring::statistics_dict() const {
  const ColouringStatistics& s = statistics;
  py::dict d;
  d["strategy"] = strategy;
  d["colours"] = s.colours;
  d["lower_bound"] = s.lower_bound;
  d["colours_per_lower_bound"] = s.colours_per_lower_bound;
  d["largest"] = s.largest;
  d["smallest"] = s.smallest;
  d["mean"] = s.mean;
  d["balance"] = s.balance;
  d["size_ratio"] = s.size_ratio;
  d["seconds"] = s.seconds;
  d["valid"] = s.valid;
  if (!s.valid) d["problem"] = s.problem;
  d["colouring_hash"] = colouring_hash(colouring.colours());
  d["sizes"] = s.sizes;
  return d;
}

PYBIND11_MODULE(_tessera, m) {
  m.doc() = "Tessera: parallel PBD/XPBD constraint projection (C++), from Python.";

  static py::exception<NumericalFailure> numerical_failure(m, "NumericalFailure",
                                                           PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr error) {
    try {
      if (error) std::rethrow_exception(error);
    } catch (const InvalidInput& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const NumericalFailure& e) {
      numerical_failure(e.what());
    }
  });

  m.attr("__version__") = TESSERA_VERSION_STRING;
  m.attr("real_dtype") = py::dtype::of<Real>();
  m.def(
      "info",
      [] {
        py::dict d;
        d["version"] = TESSERA_VERSION_STRING;
        d["precision"] = kDoublePrecision ? "double" : "float";
        d["simd_target"] = active_simd_target();
        d["simd_targets_available"] = available_simd_targets();
        d["threads_available"] = std::size_t(tbb::info::default_concurrency());
        d["hardware_threads"] = std::size_t(std::thread::hardware_concurrency());
        return d;
      },
      "What this build is: version, precision, SIMD target, threads (as `tessera info`).");
  m.def(
      "strategies",
      [] {
        const ColouringRegistry registry = ColouringRegistry::with_builtin_strategies();
        py::dict d;
        for (std::string_view name : registry.names())
          d[py::str(std::string(name))] = std::string(registry.get(name).description());
        return d;
      },
      "The built-in colouring strategies: {name: description}, in registry order.");
  m.def(
      "modes",
      [] {
        std::vector<std::string> names;
        for (SolverMode mode :
             {SolverMode::gs, SolverMode::jacobi, SolverMode::hybrid, SolverMode::sequential})
          names.emplace_back(solver_mode_name(mode));
        return names;
      },
      "The solver modes: gs, jacobi, hybrid, sequential.");

  bind_model(m);

  // ---- meshes and scenes ----------------------------------------------------------------
  py::class_<io::Mesh>(m, "Mesh", "A mesh as read from a file: positions, triangles, tetrahedra.")
      .def_property_readonly("positions", [](const io::Mesh& mesh) { return vectors_to_numpy(mesh.positions); },
                             "(N, 3) copy.")
      .def_property_readonly("triangles", [](const io::Mesh& mesh) { return elements_to_numpy(mesh.triangles, 3); },
                             "(T, 3) copy.")
      .def_property_readonly("tetrahedra", [](const io::Mesh& mesh) { return elements_to_numpy(mesh.tetrahedra, 4); },
                             "(K, 4) copy.")
      .def(
          "to_model",
          [](const io::Mesh& mesh, const py::object& pinned) {
            const std::vector<std::uint32_t> pins = to_indices(pinned, "pinned", 0);
            return io::make_model(mesh, pins);
          },
          py::arg("pinned") = py::array_t<std::uint32_t>(0),
          "A model with the default materials: tetrahedra make a FEM solid, otherwise triangles\n"
          "a distance + dihedral shell; the particles in `pinned` are static.")
      .def("__repr__", [](const io::Mesh& mesh) {
        return "<tessera.Mesh: " + std::to_string(mesh.vertex_count()) + " vertices, " +
               std::to_string(mesh.triangle_count()) + " triangles, " +
               std::to_string(mesh.tetrahedron_count()) + " tetrahedra>";
      });
  m.def("read_mesh", [](const std::filesystem::path& file) { return io::read_mesh(file); },
        py::arg("file"), "Reads .obj, TetGen .node/.ele/.face or Gmsh .msh (by extension).");

  py::class_<io::Scene, std::shared_ptr<io::Scene>>(
      m, "Scene", "A scene ready to simulate: the model, its mesh and its simulation settings.")
      .def_property_readonly("name", [](const io::Scene& s) { return s.description.name; })
      .def_property_readonly(
          "model", [](io::Scene& s) -> Model& { return s.model; }, py::return_value_policy::reference_internal,
          "The scene's model (a reference: changes to it change the scene).")
      .def_readonly("mesh", &io::Scene::mesh)
      .def_property_readonly("surface_triangles",
                             [](const io::Scene& s) { return elements_to_numpy(s.surface_triangles, 3); })
      .def_property_readonly("pinned", [](const io::Scene& s) {
        return copy_to_numpy<io::VertexIndex>(s.pinned, {py::ssize_t(s.pinned.size())});
      })
      .def_property_readonly("simulation", [](const io::Scene& s) { return simulation_dict(s.description.simulation); },
                             "The scene's settings: gravity, time_step, substeps, iterations, frames,\n"
                             "velocity_damping, strategy, mode, sequential_order, divergence_rms,\n"
                             "threads.")
      .def(
          "solver_settings",
          [](const io::Scene& s) {
            const io::SimulationSettings& sim = s.description.simulation;
            py::dict d;
            d["mode"] = sim.mode;
            d["threads"] = sim.threads;
            d["time_step"] = double(sim.time_step);
            d["substeps"] = sim.substeps;
            d["iterations"] = sim.iterations;
            d["gravity"] = py::make_tuple(double(sim.gravity.x()), double(sim.gravity.y()),
                                          double(sim.gravity.z()));
            d["velocity_damping"] = double(sim.velocity_damping);
            d["sequential_order"] = sim.sequential_order;
            d["divergence_rms"] = double(sim.divergence_rms);
            return d;
          },
          "The keyword arguments of tessera.Solver that run this scene as `tessera run` does.")
      .def("collision_settings", &scene_collision_settings,
           "The keyword arguments of Solver.set_collisions that give this scene's contacts as\n"
           "`tessera run` does (colliders, surface, solids, thickness, friction...), or None\n"
           "when it has none.")
      .def("__repr__", [](const io::Scene& s) {
        return "<tessera.Scene '" + s.description.name + "': " +
               std::to_string(s.model.particles.size()) + " particles, " +
               std::to_string(s.model.constraints.size()) + " constraints>";
      });
  m.def(
      "scene",
      [](const std::string& spec) {
        return std::make_shared<io::Scene>(io::build_scene(io::parse_scene_spec(spec)));
      },
      py::arg("spec"),
      "A scene from a spec as the tool takes it: 'cloth', 'cloth:N', 'cloth:CxR', 'bar',\n"
      "'bar:XxYxZ', a mesh file or a .json scene file.");
  m.def(
      "read_scene",
      [](const std::filesystem::path& file) {
        return std::make_shared<io::Scene>(io::build_scene(io::read_scene_file(file)));
      },
      py::arg("file"), "A JSON scene file (mesh paths relative to the file).");

  // ---- constraint graph and colouring ---------------------------------------------------
  py::class_<ConstraintGraph, std::shared_ptr<ConstraintGraph>>(
      m, "ConstraintGraph",
      "Constraint <-> movable-particle incidence (static particles left out). The arrays are\n"
      "read-only views into the graph (no copy), valid while it lives.")
      .def_property_readonly("particle_count", &ConstraintGraph::particle_count)
      .def_property_readonly("constraint_count", &ConstraintGraph::constraint_count)
      .def_property_readonly("incidence_count", &ConstraintGraph::incidence_count)
      .def_property_readonly("movable_particle_count", &ConstraintGraph::movable_particle_count)
      .def_property_readonly("lower_bound", &ConstraintGraph::colour_lower_bound,
                             "The most constraints meeting at one movable particle: no valid\n"
                             "colouring has fewer colours.")
      .def_property_readonly("constraint_offsets", [](py::object self) {
        auto span = self.cast<const ConstraintGraph&>().constraint_offsets();
        return read_only_view(span.data(), span.size(), self);
      })
      .def_property_readonly("constraint_particles", [](py::object self) {
        auto span = self.cast<const ConstraintGraph&>().constraint_particles();
        return read_only_view(span.data(), span.size(), self);
      })
      .def_property_readonly("particle_offsets", [](py::object self) {
        auto span = self.cast<const ConstraintGraph&>().particle_offsets();
        return read_only_view(span.data(), span.size(), self);
      })
      .def_property_readonly("particle_constraints", [](py::object self) {
        auto span = self.cast<const ConstraintGraph&>().particle_constraints();
        return read_only_view(span.data(), span.size(), self);
      })
      .def(
          "particles_of",
          [](py::object self, ConstraintIndex c) {
            const auto& graph = self.cast<const ConstraintGraph&>();
            if (c >= graph.constraint_count())
              throw InvalidInput("constraint " + std::to_string(c) + " does not exist (the graph has " +
                                 std::to_string(graph.constraint_count()) + ")");
            auto span = graph.particles_of(c);
            return read_only_view(span.data(), span.size(), self);
          },
          py::arg("constraint"), "The movable particles of a constraint (global id).")
      .def(
          "constraints_of",
          [](py::object self, ParticleIndex p) {
            const auto& graph = self.cast<const ConstraintGraph&>();
            if (p >= graph.particle_count())
              throw InvalidInput("particle " + std::to_string(p) + " does not exist (the graph has " +
                                 std::to_string(graph.particle_count()) + ")");
            auto span = graph.constraints_of(p);
            return read_only_view(span.data(), span.size(), self);
          },
          py::arg("particle"), "The constraints touching a particle, by increasing id.")
      .def("__repr__", [](const ConstraintGraph& g) {
        return "<tessera.ConstraintGraph: " + std::to_string(g.constraint_count()) + " constraints, " +
               std::to_string(g.particle_count()) + " particles, lower bound " +
               std::to_string(g.colour_lower_bound()) + ">";
      });
  m.def(
      "constraint_graph",
      [](const Model& model) {
        py::gil_scoped_release release;
        return std::make_shared<ConstraintGraph>(constraint_graph(model));
      },
      py::arg("model"), "The constraint graph of a model (the input of every strategy).");

  py::class_<PyColouring, std::shared_ptr<PyColouring>>(
      m, "Colouring",
      "A colour per constraint and, when a pass renumbered them, the particle order. Arrays\n"
      "are read-only views (no copy), valid while the colouring lives.")
      .def_property_readonly("strategy", [](const PyColouring& c) { return c.strategy; })
      .def_property_readonly("colour_count", [](const PyColouring& c) { return c.colouring.colour_count(); })
      .def_property_readonly("constraint_count", [](const PyColouring& c) { return c.colouring.constraint_count(); })
      .def_property_readonly("colours", [](py::object self) {
        auto span = self.cast<const PyColouring&>().colouring.colours();
        return read_only_view(span.data(), span.size(), self);
      }, "(M,) colour of every constraint (global id).")
      .def_property_readonly("sizes", [](const PyColouring& c) { return c.statistics.sizes; })
      .def(
          "constraints_of",
          [](py::object self, Colour k) {
            const Colouring& c = self.cast<const PyColouring&>().colouring;
            if (k >= c.colour_count())
              throw InvalidInput("colour " + std::to_string(k) + " does not exist (the colouring has " +
                                 std::to_string(c.colour_count()) + ")");
            auto span = c.constraints_of(k);
            return read_only_view(span.data(), span.size(), self);
          },
          py::arg("colour"), "The constraints of one colour, in schedule order.")
      .def_property_readonly("renumbers_particles", [](const PyColouring& c) { return c.colouring.renumbers_particles(); })
      .def_property_readonly("particle_new_to_old", [](py::object self) {
        auto span = self.cast<const PyColouring&>().colouring.particle_new_to_old();
        return read_only_view(span.data(), span.size(), self);
      }, "The user's index of each renumbered particle (empty when not renumbered).")
      .def_property_readonly("particle_old_to_new", [](py::object self) {
        auto span = self.cast<const PyColouring&>().colouring.particle_old_to_new();
        return read_only_view(span.data(), span.size(), self);
      }, "The inverse of particle_new_to_old (empty when not renumbered).")
      .def_property_readonly("valid", [](const PyColouring& c) { return c.statistics.valid; })
      .def_property_readonly("statistics", &PyColouring::statistics_dict,
                             "The keys and values of `tessera color --json` for this colouring.")
      .def_property_readonly("colouring_hash", [](const PyColouring& c) { return colouring_hash(c.colouring.colours()); })
      .def("__repr__", [](const PyColouring& c) {
        return "<tessera.Colouring '" + c.strategy + "': " + std::to_string(c.colouring.colour_count()) +
               " colours, " + std::to_string(c.colouring.constraint_count()) + " constraints>";
      });

  m.def(
      "colour",
      [](const py::object& source, const py::object& strategy, std::optional<std::size_t> threads,
         std::uint64_t seed, bool balance, bool locality, bool reduce,
         std::size_t particles_per_part, std::size_t reduction_rounds) {
        py::object graph_object;
        const std::shared_ptr<ConstraintGraph> graph = graph_of(source, graph_object);
        const ColouringRegistry registry = ColouringRegistry::with_builtin_strategies();
        std::shared_ptr<const ColouringStrategy> own;
        const ColouringStrategy* chosen = nullptr;
        std::string name;
        if (py::isinstance<py::str>(strategy)) {
          name = strategy.cast<std::string>();
          chosen = &registry.get(name);
        } else if (PyCallable_Check(strategy.ptr())) {
          name = py::hasattr(strategy, "__name__") ? py::str(strategy.attr("__name__")).cast<std::string>()
                                                   : std::string("python");
          own = std::make_shared<PythonStrategy>(strategy.cast<py::function>(), graph_object, name);
          chosen = own.get();
        } else {
          throw InvalidInput("strategy must be a name (tessera.strategies()) or a function "
                             "returning one colour per constraint");
        }
        if (threads && *threads == 0) throw InvalidInput("threads must be at least 1 (or None: every hardware thread)");
        const ColouringOptions options{.seed = seed,
                                       .particles_per_part = particles_per_part,
                                       .reduction_rounds = reduction_rounds,
                                       .reduce = reduce,
                                       .balance = balance,
                                       .locality = locality};
        auto result = std::make_shared<PyColouring>();
        result->strategy = name;
        {
          py::gil_scoped_release release;
          tbb::task_arena arena(threads ? int(*threads) : tbb::task_arena::automatic);
          ColouringRun run;
          arena.execute([&] { run = run_colouring(*chosen, *graph, options); });
          result->colouring = std::move(run.colouring);
          result->statistics = std::move(run.statistics);
        }
        return result;
      },
      py::arg("model"), py::arg("strategy") = "greedy", py::kw_only(), py::arg("threads") = py::none(),
      py::arg("seed") = 1, py::arg("balance") = false, py::arg("locality") = false,
      py::arg("reduce") = false, py::arg("particles_per_part") = 0, py::arg("reduction_rounds") = 24,
      "Colours a Model (or a ConstraintGraph) with a strategy: a name from\n"
      "tessera.strategies(), or a Python function taking the ConstraintGraph and returning one\n"
      "colour per constraint (checked: dense colours, no two constraints of a colour sharing a\n"
      "movable particle; ValueError otherwise). Then the post-passes asked for: reduce, balance,\n"
      "locality (renumbers particles). threads=None uses every hardware thread; the colouring\n"
      "is the same for any count. The GIL is released while it runs.");
  m.attr("color") = m.attr("colour");

  m.def(
      "validate",
      [](const py::object& source, const PyColouring& colouring) {
        py::object graph_object;
        const std::shared_ptr<ConstraintGraph> graph = graph_of(source, graph_object);
        const ColouringValidation check = validate(*graph, colouring.colouring);
        return py::make_tuple(check.valid, check.problem);
      },
      py::arg("model"), py::arg("colouring"),
      "(valid, problem): whether the colouring fits the Model's (or ConstraintGraph's) graph and\n"
      "no two constraints of one colour share a movable particle; problem names the first fault.");

  bind_solver(m);
}

}  // namespace tessera::python
