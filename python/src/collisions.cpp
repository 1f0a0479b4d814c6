// tessera.Solver's collision stage: colliders given as dicts, the stage's statistics as a
// dict, per-particle contact counts, and the checks `tessera run` reports (penetration depth,
// self-intersections) as module functions.
//
//   {"shape": "plane",   "normal": (0, 1, 0), "offset": 0}          n·x = offset, free along n
//   {"shape": "sphere",  "centre": (x, y, z), "radius": r}
//   {"shape": "box",     "centre": (x, y, z), "half_extents": (hx, hy, hz)}   axis-aligned
//   {"shape": "capsule", "a": (x, y, z), "b": (x, y, z), "radius": r}
//   {"shape": "mesh",    "positions": (V, 3), "triangles": (T, 3)}  a static triangle mesh
#include <string>
#include <vector>

#include <pybind11/stl.h>

#include <tessera/collision/self_intersections.hpp>
#include <tessera/collision/solid_contacts.hpp>
#include <tessera/io/scene_description.hpp>
#include <tessera/parallel/solver.hpp>

#include "bindings.hpp"

namespace tessera::python {
namespace {

Vector3r vector_of(const py::dict& d, const char* key, const std::string& where) {
  if (!d.contains(key)) throw InvalidInput(where + ": missing '" + key + "'");
  const std::vector<Real> v = to_reals(d[key], where + " '" + key + "'", 3);
  return Vector3r(v[0], v[1], v[2]);
}

Real real_of(const py::dict& d, const char* key, const std::string& where) {
  if (!d.contains(key)) throw InvalidInput(where + ": missing '" + key + "'");
  return Real(py::cast<double>(d[key]));
}

Collider collider_of(const py::handle& object, std::size_t index) {
  const std::string where = "colliders[" + std::to_string(index) + "]";
  if (!py::isinstance<py::dict>(object))
    throw InvalidInput(where + ": a collider is a dict with a 'shape'");
  const py::dict d = py::reinterpret_borrow<py::dict>(object);
  if (!d.contains("shape")) throw InvalidInput(where + ": missing 'shape'");
  const std::string shape = py::cast<std::string>(d["shape"]);
  if (shape == "plane") {
    const Vector3r normal = vector_of(d, "normal", where);
    if (!(normal.norm() > 0)) throw InvalidInput(where + ": the plane's normal is zero");
    // n·x = offset with any n: scaled to a unit normal, as scene files take it.
    return PlaneCollider{normal.normalized(), real_of(d, "offset", where) / normal.norm()};
  }
  if (shape == "sphere") return SphereCollider{vector_of(d, "centre", where), real_of(d, "radius", where)};
  if (shape == "box") return BoxCollider{vector_of(d, "centre", where), vector_of(d, "half_extents", where)};
  if (shape == "capsule")
    return CapsuleCollider{vector_of(d, "a", where), vector_of(d, "b", where), real_of(d, "radius", where)};
  if (shape == "mesh") {
    if (!d.contains("positions") || !d.contains("triangles"))
      throw InvalidInput(where + ": a mesh collider needs 'positions' (V, 3) and 'triangles' (T, 3)");
    return MeshCollider(to_vectors(d["positions"], where + " 'positions'"),
                        to_indices(d["triangles"], where + " 'triangles'", 3));
  }
  throw InvalidInput(where + ": unknown shape '" + shape +
                     "' (known: plane, sphere, box, capsule, mesh)");
}

std::vector<Collider> colliders_of(const py::iterable& colliders) {
  std::vector<Collider> result;
  for (const py::handle& c : colliders) result.push_back(collider_of(c, result.size()));
  return result;
}

/// A scene's colliders as the dicts set_collisions takes.
py::list collider_dicts(const io::Scene& scene) {
  py::list result;
  std::size_t mesh = 0;
  const auto tuple = [](const Vector3r& v) {
    return py::make_tuple(double(v.x()), double(v.y()), double(v.z()));
  };
  for (const io::ColliderDescription& c : scene.description.collisions.colliders) {
    py::dict d;
    switch (c.shape) {
      case io::ColliderShape::plane:
        d["shape"] = "plane", d["normal"] = tuple(c.normal), d["offset"] = double(c.offset);
        break;
      case io::ColliderShape::sphere:
        d["shape"] = "sphere", d["centre"] = tuple(c.centre), d["radius"] = double(c.radius);
        break;
      case io::ColliderShape::box:
        d["shape"] = "box", d["centre"] = tuple(c.centre), d["half_extents"] = tuple(c.half_extents);
        break;
      case io::ColliderShape::capsule:
        d["shape"] = "capsule", d["a"] = tuple(c.a), d["b"] = tuple(c.b), d["radius"] = double(c.radius);
        break;
      case io::ColliderShape::mesh: {
        const io::Mesh& source = scene.collider_meshes.at(mesh++);
        d["shape"] = "mesh";
        d["positions"] = vectors_to_numpy(source.positions);
        d["triangles"] = elements_to_numpy(source.triangles, 3);
        break;
      }
    }
    result.append(d);
  }
  return result;
}

}  // namespace

void bind_collisions(py::module_& m, py::class_<Solver>& solver) {
  solver
      .def(
          "set_collisions",
          [](Solver& s, const py::iterable& colliders, const py::object& surface_triangles,
             const py::object& tetrahedra, double thickness, double friction,
             double dynamic_friction, double restitution, bool self_collision,
             std::size_t self_collision_interval) {
            CollisionSettings settings;
            settings.colliders = colliders_of(colliders);
            settings.thickness = Real(thickness);
            settings.static_friction = Real(friction);
            settings.dynamic_friction = Real(dynamic_friction);
            settings.restitution = Real(restitution);
            settings.self_collision = self_collision;
            settings.self_collision_interval = self_collision_interval;
            const std::vector<std::uint32_t> triangles =
                surface_triangles.is_none() ? std::vector<std::uint32_t>()
                                            : to_indices(surface_triangles, "surface_triangles", 3);
            const std::vector<std::uint32_t> tets =
                tetrahedra.is_none() ? std::vector<std::uint32_t>()
                                     : to_indices(tetrahedra, "tetrahedra", 4);
            if (self_collision && triangles.empty())
              throw InvalidInput("collisions: self_collision needs surface_triangles");
            py::gil_scoped_release release;
            s.set_collisions(std::move(settings), triangles, tets);
          },
          py::arg("colliders") = py::list(), py::kw_only(),
          py::arg("surface_triangles") = py::none(), py::arg("tetrahedra") = py::none(),
          py::arg("thickness") = double(kDefaultThickness),
          py::arg("friction") = double(kDefaultStaticFriction),
          py::arg("dynamic_friction") = double(kDefaultDynamicFriction),
          py::arg("restitution") = 0.0, py::arg("self_collision") = false,
          py::arg("self_collision_interval") = kDefaultSelfCollisionInterval,
          "Contacts found every substep: `colliders`, a list of dicts ({'shape': 'plane',\n"
          "'normal': (0, 1, 0), 'offset': 0}, 'sphere' with 'centre' and 'radius', 'box' with\n"
          "'centre' and 'half_extents', 'capsule' with 'a', 'b' and 'radius', 'mesh' with\n"
          "'positions' (V, 3) and 'triangles' (T, 3)); with self_collision the surface\n"
          "(surface_triangles, (T, 3), user numbering) against itself; the boundary faces of\n"
          "tetrahedra ((K, 4)) get particle-tet contacts. thickness in metres, friction the\n"
          "static and dynamic Coulomb coefficients, restitution in [0, 1]. ValueError for bad\n"
          "values. Scene.collision_settings() gives a scene's as keyword arguments.")
      .def("clear_collisions", &Solver::clear_collisions, "Turns collision detection off.")
      .def_property_readonly(
          "collision_statistics",
          [](const Solver& s) -> py::object {
            const CollisionStage* stage = s.collisions();
            if (stage == nullptr) return py::none();
            const CollisionStatistics& c = stage->statistics();
            const SolverStatistics& st = s.statistics();
            py::dict d;
            d["substeps"] = c.substeps;
            d["contacts_mean"] = c.contacts_mean();
            d["contacts_max"] = c.contacts_max;
            d["collider_contacts"] = c.collider_contacts;
            d["vertex_triangle_contacts"] = c.vertex_triangle_contacts;
            d["edge_edge_contacts"] = c.edge_edge_contacts;
            d["particle_tet_contacts"] = c.particle_tet_contacts;
            d["seconds_detection"] = c.seconds_detection;
            d["self_collision_detections"] = c.self_detections;
            d["self_collision_reboxes"] = c.self_reboxes;
            d["seconds_self_collision_built"] = c.seconds_self_built;
            d["seconds_self_collision_reboxed"] = c.seconds_self_reboxed;
            d["seconds_self_collision_refined"] = c.seconds_self_refined;
            d["seconds_contact_scheduling"] = st.seconds_contact_scheduling;
            d["contact_colours_max"] = st.contact_colours_max;
            d["contacts_overflowed"] = st.contacts_overflowed;
            return d;
          },
          "None without collisions; else the contacts per substep (mean, max, and of the last\n"
          "substep by kind), detection and scheduling seconds, the most contact colours in a\n"
          "substep, and the contacts that found no colour.")
      .def(
          "contact_counts",
          [](const Solver& s) {
            const std::vector<std::uint32_t> counts = s.contact_counts();
            return copy_to_numpy<std::uint32_t>(counts, {py::ssize_t(counts.size())});
          },
          "(N,) the number of contacts of the last substep each particle is in, user numbering.");

  m.def(
      "penetration_depth",
      [](const py::object& positions, const py::iterable& colliders, const py::object& tetrahedra) {
        const std::vector<Vector3r> p = to_vectors(positions, "positions");
        const std::vector<Collider> c = colliders_of(colliders);
        const std::vector<std::uint32_t> tets =
            tetrahedra.is_none() ? std::vector<std::uint32_t>() : to_indices(tetrahedra, "tetrahedra", 4);
        py::gil_scoped_release release;
        return double(std::max(penetration_depth(c, p), solid_penetration_depth(p, tets)));
      },
      py::arg("positions"), py::arg("colliders") = py::list(), py::arg("tetrahedra") = py::none(),
      "The deepest point (metres) inside a collider or, with tetrahedra, a boundary vertex\n"
      "inside another solid body: the run summary's penetration_max.");
  m.def(
      "self_intersections",
      [](const py::object& positions, const py::object& triangles) {
        const std::vector<Vector3r> p = to_vectors(positions, "positions");
        const std::vector<std::uint32_t> t = to_indices(triangles, "triangles", 3);
        for (const std::uint32_t v : t)
          if (v >= p.size())
            throw InvalidInput("self_intersections: triangle names vertex " + std::to_string(v) +
                               ", there are " + std::to_string(p.size()));
        py::gil_scoped_release release;
        return count_self_intersections(p, t);
      },
      py::arg("positions"), py::arg("triangles"),
      "Intersecting pairs of triangles that share no vertex, counted exactly (the run\n"
      "summary's self_intersections).");
}

py::object scene_collision_settings(const io::Scene& scene) {
  const io::CollisionDescription& c = scene.description.collisions;
  if (!c.enabled()) return py::none();
  py::dict d;
  d["colliders"] = collider_dicts(scene);
  // As `tessera run` does: self-collision works on the surface, a solid's boundary faces get
  // particle–tet contacts; without self-collision neither is searched.
  if (c.self_collision) {
    d["surface_triangles"] = elements_to_numpy(scene.surface_triangles, 3);
    d["tetrahedra"] = elements_to_numpy(scene.mesh.tetrahedra, 4);
  }
  d["thickness"] = double(c.thickness);
  d["friction"] = double(c.static_friction);
  d["dynamic_friction"] = double(c.dynamic_friction);
  d["restitution"] = double(c.restitution);
  d["self_collision"] = c.self_collision;
  d["self_collision_interval"] = c.self_collision_interval;
  return d;
}

}  // namespace tessera::python
