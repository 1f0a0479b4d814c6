// tessera.Model: particles and constraint families from NumPy arrays, and the one table that
// says, for every family, which parameters Python may pass and where they go.
//
// Everything else here is generic over ConstraintSets::for_each: a family is found by its
// family_name, its arity comes from its batch type, its structural input (indices, rest
// positions, particle count, inverse masses, CSR offsets) is filled by whichever fields its
// input struct has. A family added to ConstraintSets needs one Family<> entry below to be
// settable from Python (without one it does not compile: Family<Batch> is undefined).
//
// Parameters: a number sets the input's value for every constraint and is validated by the
// family's make_<family>_constraints (its messages). A 1-D array of one value per constraint
// is accepted where the table says per_constraint: the batch is built with the default, then
// the array is checked by building the family's first constraint with the array's first
// non-finite, smallest and largest value (the builders' checks are ranges, so the extremes
// decide for all of them; the message is the builder's plus "(name[i])"), then copied in.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include <pybind11/stl.h>

#include <tessera/core/model.hpp>

#include "bindings.hpp"

namespace tessera::python {
namespace {

// ---- the table -------------------------------------------------------------------------

/// A Real parameter of a family's input: `input` in the input struct (one value for every
/// constraint); `values`, when set, the batch's per-constraint array it fills (read back by
/// Model.constraints); per_constraint: Python may also pass one value per constraint.
template <class Input, class Batch>
struct RealParameter {
  const char* name;
  Real Input::*input;
  AlignedVector<Real> Batch::*values = nullptr;
  bool per_constraint = false;
};
/// A batch-wide switch.
template <class Input, class Batch>
struct FlagParameter {
  const char* name;
  bool Input::*input;
  bool Batch::*value;
};
/// A 3-vector for every constraint (strain tetra's stiffnesses per axis).
template <class Input, class Batch>
struct VectorParameter {
  const char* name;
  Vector3r Input::*input;
};

template <class Batch>
struct Family;  // one specialisation per family: Input, make(), parameters()

#define TESSERA_REAL(field, per) \
  RealParameter<Input, Batch> { #field, &Input::field, &Batch::field, per }

template <>
struct Family<DistanceConstraints> {
  using Batch = DistanceConstraints;
  using Input = DistanceConstraintInput;
  static Batch make(const Input& input) { return make_distance_constraints(input); }
  static auto parameters() {
    return std::tuple{TESSERA_REAL(stiffness, true), TESSERA_REAL(compliance, true)};
  }
};
template <>
struct Family<DihedralConstraints> {
  using Batch = DihedralConstraints;
  using Input = DihedralConstraintInput;
  static Batch make(const Input& input) { return make_dihedral_constraints(input); }
  static auto parameters() {
    return std::tuple{TESSERA_REAL(stiffness, true), TESSERA_REAL(compliance, true)};
  }
};
template <>
struct Family<IsometricBendingConstraints> {
  using Batch = IsometricBendingConstraints;
  using Input = IsometricBendingConstraintInput;
  static Batch make(const Input& input) { return make_isometric_bending_constraints(input); }
  static auto parameters() {
    return std::tuple{TESSERA_REAL(stiffness, true), TESSERA_REAL(compliance, true)};
  }
};
template <>
struct Family<VolumeConstraints> {
  using Batch = VolumeConstraints;
  using Input = VolumeConstraintInput;
  static Batch make(const Input& input) { return make_volume_constraints(input); }
  static auto parameters() {
    return std::tuple{TESSERA_REAL(stiffness, true), TESSERA_REAL(compliance, true)};
  }
};
template <ProximityKind Kind>
struct Family<ProximityDistanceConstraints<Kind>> {
  using Batch = ProximityDistanceConstraints<Kind>;
  using Input = ProximityDistanceConstraintInput;
  static Batch make(const Input& input) {
    if constexpr (Kind == ProximityKind::edge_point)
      return make_edge_point_distance_constraints(input);
    else if constexpr (Kind == ProximityKind::triangle_point)
      return make_triangle_point_distance_constraints(input);
    else
      return make_edge_edge_distance_constraints(input);
  }
  static auto parameters() {
    return std::tuple{TESSERA_REAL(rest_distance, true), TESSERA_REAL(compression_stiffness, true),
                      TESSERA_REAL(stretch_stiffness, true)};
  }
};
template <>
struct Family<StrainTriangleConstraints> {
  using Batch = StrainTriangleConstraints;
  using Input = StrainTriangleConstraintInput;
  static Batch make(const Input& input) { return make_strain_triangle_constraints(input); }
  static auto parameters() {
    return std::tuple{TESSERA_REAL(xx_stiffness, true), TESSERA_REAL(yy_stiffness, true),
                      TESSERA_REAL(xy_stiffness, true),
                      FlagParameter<Input, Batch>{"normalize_stretch", &Input::normalize_stretch,
                                                  &Batch::normalize_stretch},
                      FlagParameter<Input, Batch>{"normalize_shear", &Input::normalize_shear,
                                                  &Batch::normalize_shear}};
  }
};
template <>
struct Family<StrainTetraConstraints> {
  using Batch = StrainTetraConstraints;
  using Input = StrainTetraConstraintInput;
  static Batch make(const Input& input) { return make_strain_tetra_constraints(input); }
  static auto parameters() {
    return std::tuple{
        VectorParameter<Input, Batch>{"stretch_stiffness", &Input::stretch_stiffness},
        VectorParameter<Input, Batch>{"shear_stiffness", &Input::shear_stiffness},
        FlagParameter<Input, Batch>{"normalize_stretch", &Input::normalize_stretch,
                                    &Batch::normalize_stretch},
        FlagParameter<Input, Batch>{"normalize_shear", &Input::normalize_shear,
                                    &Batch::normalize_shear}};
  }
};
template <>
struct Family<FEMTriangleConstraints> {
  using Batch = FEMTriangleConstraints;
  using Input = FEMTriangleConstraintInput;
  static Batch make(const Input& input) { return make_fem_triangle_constraints(input); }
  // One material for all: positive definiteness couples the five values, so no per-constraint
  // arrays (the extremes of each would not decide).
  static auto parameters() {
    return std::tuple{TESSERA_REAL(youngs_modulus_x, false), TESSERA_REAL(youngs_modulus_y, false),
                      TESSERA_REAL(youngs_modulus_shear, false),
                      TESSERA_REAL(poisson_ratio_xy, false), TESSERA_REAL(poisson_ratio_yx, false)};
  }
};
template <>
struct Family<FEMTetraConstraints> {
  using Batch = FEMTetraConstraints;
  using Input = FEMTetraConstraintInput;
  static Batch make(const Input& input) { return make_fem_tetra_constraints(input); }
  // One material for all: the builder derives each compliance from E.
  static auto parameters() {
    return std::tuple{TESSERA_REAL(youngs_modulus, false), TESSERA_REAL(poisson_ratio, false),
                      FlagParameter<Input, Batch>{"handle_inversion", &Input::handle_inversion,
                                                  &Batch::handle_inversion}};
  }
};
template <>
struct Family<ShapeMatchingConstraints> {
  using Batch = ShapeMatchingConstraints;
  using Input = ShapeMatchingInput;
  static Batch make(const Input& input) { return make_shape_matching_constraints(input); }
  static auto parameters() {
    return std::tuple{TESSERA_REAL(stiffness, true),
                      FlagParameter<Input, Batch>{"allow_stretch", &Input::allow_stretch,
                                                  &Batch::allow_stretch}};
  }
};

/// Contacts are made by collision detection from positions and velocities (their build runs
/// the seed's init at the velocities of that moment), not set from Python: no make(), so
/// set_constraints refuses them with a message, and they list no parameters.
template <>
struct Family<ParticleTetContacts> {
  using Batch = ParticleTetContacts;
  using Input = ParticleTetContactInput;
  static auto parameters() { return std::tuple{}; }
};

/// Tethers from Python reach their rest distance (rest= positions, or the model's) unless
/// max_distance= gives the reach (one number, or one per tether); the geodesic long-range
/// attachments of a mesh are what tessera.scene() adds (C++: make_long_range_attachments).
template <>
struct Family<TetherConstraints> {
  using Batch = TetherConstraints;
  using Input = TetherConstraintInput;
  static Batch make(const Input& input) { return make_tether_constraints(input); }
  static auto parameters() {
    return std::tuple{TESSERA_REAL(max_distance, true), TESSERA_REAL(stiffness, true),
                      TESSERA_REAL(compliance, true)};
  }
};

/// Collider contacts are made each substep by the collision module from the colliders and the
/// particles' positions and velocities, not set from Python (like particle–tet contacts).
template <>
struct Family<ColliderContacts> {
  using Batch = ColliderContacts;
  using Input = ColliderContactInput;
  static auto parameters() { return std::tuple{}; }
};

#undef TESSERA_REAL

// ---- generic over the families ---------------------------------------------------------

/// Particles per constraint; 0 for a family of clusters (CSR: offsets + particles).
template <class Batch>
constexpr std::size_t arity_of() {
  if constexpr (requires { decltype(Batch::particles)::kParticlesPerConstraint; })
    return std::size_t(decltype(Batch::particles)::kParticlesPerConstraint);
  else
    return 0;
}

/// Calls body(batch) for the batch of `sets` named `name`; InvalidInput listing the names
/// for an unknown one.
template <class Sets, class Body>
void with_family(Sets& sets, const std::string& name, Body&& body) {
  bool found = false;
  sets.for_each([&](ConstraintFamily family, auto& batch) {
    if (!found && family_name(family) == name) {
      found = true;
      body(batch);
    }
  });
  if (found) return;
  std::string known;
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f)
    known += (f ? ", " : "") + std::string(family_name(ConstraintFamily(f)));
  throw InvalidInput("unknown constraint family '" + name + "' (known: " + known + ")");
}

bool is_sequence(const py::handle& value) {
  if (py::isinstance<py::array>(value)) return py::reinterpret_borrow<py::array>(value).ndim() > 0;
  return py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value);
}

/// The structural fields of a family's input, whichever it has.
template <class Input>
void fill_structure(Input& input, std::span<const std::uint32_t> particles,
                    std::span<const std::uint32_t> offsets, std::span<const Vector3r> rest,
                    std::span<const Real> inverse_masses) {
  input.particles = particles;
  if constexpr (requires { input.rest_positions; }) input.rest_positions = rest;
  if constexpr (requires { input.particle_count; }) input.particle_count = rest.size();
  if constexpr (requires { input.inverse_masses; }) input.inverse_masses = inverse_masses;
  if constexpr (requires { input.offsets; }) input.offsets = offsets;
}

template <class Batch>
std::size_t constraint_count_of(std::span<const std::uint32_t> particles,
                                std::span<const std::uint32_t> offsets) {
  constexpr std::size_t arity = arity_of<Batch>();
  if constexpr (arity == 0)
    return offsets.empty() ? 0 : offsets.size() - 1;
  else
    return particles.size() / arity;
}

template <class Batch>
Batch build_family(const Model& model, const py::object& particles_object,
                   const py::object& rest_object, const py::object& offsets_object,
                   py::dict parameters) {
  using F = Family<Batch>;
  using Input = typename F::Input;
  constexpr std::size_t arity = arity_of<Batch>();
  const std::string family = Batch::kFamily;
  const std::size_t n = model.particles.size();

  const std::vector<std::uint32_t> particles =
      to_indices(particles_object, family + " particles", arity);
  std::vector<std::uint32_t> offsets;
  if constexpr (arity == 0) {
    if (offsets_object.is_none())
      throw InvalidInput(family + " constraints: clusters need offsets= (count + 1 entry offsets "
                                  "into particles)");
    offsets = to_indices(offsets_object, family + " offsets", 0);
  } else if (!offsets_object.is_none()) {
    throw InvalidInput(family + " constraints: offsets= is only for families of clusters");
  }
  std::vector<Vector3r> rest;
  if (rest_object.is_none()) {
    rest.reserve(n);
    for (std::size_t i = 0; i < n; ++i) rest.push_back(model.particles.position(i));
  } else {
    rest = to_vectors(rest_object, family + " rest_positions", n);
  }
  const std::vector<Real> inverse_masses(model.particles.inverse_mass.begin(),
                                         model.particles.inverse_mass.begin() + std::ptrdiff_t(n));
  const std::size_t count = constraint_count_of<Batch>(particles, offsets);

  Input input;
  fill_structure(input, particles, offsets, rest, inverse_masses);

  // Parameters: scalars into the input, per-constraint arrays kept for after the build.
  struct PendingArray {
    std::string name;
    Real Input::*input;
    AlignedVector<Real> Batch::*values;
    std::vector<Real> data;
  };
  std::vector<PendingArray> arrays;
  std::vector<std::string> known;
  auto take = [&](const auto& parameter) -> std::optional<py::object> {
    known.emplace_back(parameter.name);
    if (!parameters.contains(parameter.name)) return std::nullopt;
    py::object value = parameters[parameter.name];
    PyDict_DelItemString(parameters.ptr(), parameter.name);
    return value;
  };
  std::apply(
      [&](const auto&... parameter) {
        auto one = [&](const auto& p) {
          using P = std::decay_t<decltype(p)>;
          const std::optional<py::object> value = take(p);
          if (!value) return;
          if constexpr (std::is_same_v<P, RealParameter<Input, Batch>>) {
            if (is_sequence(*value)) {
              if (!p.per_constraint)
                throw InvalidInput(family + " constraints: " + p.name +
                                   " takes one number for all constraints, not an array");
              arrays.push_back({p.name, p.input, p.values,
                                to_reals(*value, family + " " + p.name, count)});
            } else {
              input.*p.input = Real(py::float_(*value).cast<double>());
            }
          } else if constexpr (std::is_same_v<P, FlagParameter<Input, Batch>>) {
            if (!py::isinstance<py::bool_>(*value) &&
                !py::isinstance(*value, py::module_::import("numpy").attr("bool_")))
              throw InvalidInput(family + " constraints: " + p.name + " must be True or False");
            input.*p.input = value->template cast<bool>();
          } else {
            const std::vector<Real> xyz = to_reals(*value, family + " " + p.name, 3);
            input.*p.input = Vector3r(xyz[0], xyz[1], xyz[2]);
          }
        };
        (one(parameter), ...);
      },
      F::parameters());
  if (!parameters.empty()) {
    std::string list;
    for (const std::string& name : known) list += (list.empty() ? "" : ", ") + name;
    throw InvalidInput(family + " constraints: unknown parameter '" +
                       py::str(parameters.begin()->first).cast<std::string>() +
                       "' (known: " + (list.empty() ? "none" : list) + ")");
  }

  Batch batch = F::make(input);

  for (PendingArray& pending : arrays) {
    if (count == 0) continue;
    // The first constraint alone, built with the candidate values that decide the range.
    std::vector<std::uint32_t> first_offsets;
    std::span<const std::uint32_t> first_particles;
    if constexpr (arity == 0) {
      first_offsets = {0, offsets[1]};
      first_particles = std::span(particles).first(offsets[1]);
    } else {
      first_particles = std::span(particles).first(arity);
    }
    const auto& data = pending.data;
    std::vector<std::size_t> candidates;
    const auto non_finite =
        std::find_if(data.begin(), data.end(), [](Real v) { return !std::isfinite(v); });
    if (non_finite != data.end()) candidates.push_back(std::size_t(non_finite - data.begin()));
    candidates.push_back(std::size_t(std::min_element(data.begin(), data.end()) - data.begin()));
    candidates.push_back(std::size_t(std::max_element(data.begin(), data.end()) - data.begin()));
    for (std::size_t c : candidates) {
      Input one = input;
      fill_structure(one, first_particles, first_offsets, rest, inverse_masses);
      one.*pending.input = data[c];
      try {
        F::make(one);
      } catch (const InvalidInput& error) {
        throw InvalidInput(std::string(error.what()) + " (" + pending.name + "[" +
                           std::to_string(c) + "])");
      }
    }
    AlignedVector<Real>& target = batch.*pending.values;
    std::copy(data.begin(), data.end(), target.begin());
  }
  return batch;
}

/// Model.constraints(family): the family's arrays as NumPy copies.
template <class Batch>
py::dict family_arrays(const Batch& batch) {
  using F = Family<Batch>;
  using Input = typename F::Input;
  constexpr std::size_t arity = arity_of<Batch>();
  const std::size_t count = batch.size();
  py::dict result;
  if constexpr (arity == 0) {
    std::vector<std::uint32_t> offsets(count + 1, 0);
    if (count > 0) std::copy_n(batch.offsets.begin(), count + 1, offsets.begin());
    result["offsets"] = copy_to_numpy<std::uint32_t>(offsets, {py::ssize_t(count + 1)});
    result["particles"] = copy_to_numpy<ParticleIndex>(
        std::span(batch.particle.data(), batch.entry_count()), {py::ssize_t(batch.entry_count())});
  } else {
    py::array_t<ParticleIndex> particles({py::ssize_t(count), py::ssize_t(arity)});
    auto out = particles.template mutable_unchecked<2>();
    for (std::size_t c = 0; c < count; ++c)
      for (std::size_t k = 0; k < arity; ++k)
        out(py::ssize_t(c), py::ssize_t(k)) = batch.particles.particle[k][c];
    result["particles"] = particles;
  }
  std::apply(
      [&](const auto&... parameter) {
        // Unused for the contact families, whose parameter lists are empty.
        [[maybe_unused]] auto one = [&](const auto& p) {
          using P = std::decay_t<decltype(p)>;
          if constexpr (std::is_same_v<P, RealParameter<Input, Batch>>) {
            if (p.values)
              result[p.name] = copy_to_numpy<Real>(std::span((batch.*p.values).data(), count),
                                                   {py::ssize_t(count)});
          } else if constexpr (std::is_same_v<P, FlagParameter<Input, Batch>>) {
            result[p.name] = bool(batch.*p.value);
          }
        };
        (one(parameter), ...);
      },
      F::parameters());
  return result;
}

/// tessera.families(): every family with its arity and parameters.
py::list family_table() {
  py::list result;
  ConstraintSets sets;
  sets.for_each([&](ConstraintFamily family, auto& batch) {
    using Batch = std::decay_t<decltype(batch)>;
    using F = Family<Batch>;
    using Input = typename F::Input;
    py::dict parameters;
    std::apply(
        [&](const auto&... parameter) {
          // Unused for the contact families, whose parameter lists are empty.
          [[maybe_unused]] auto one = [&](const auto& p) {
            using P = std::decay_t<decltype(p)>;
            if constexpr (std::is_same_v<P, RealParameter<Input, Batch>>)
              parameters[p.name] = p.per_constraint ? "number or per-constraint array" : "number";
            else if constexpr (std::is_same_v<P, FlagParameter<Input, Batch>>)
              parameters[p.name] = "bool";
            else
              parameters[p.name] = "3 numbers";
          };
          (one(parameter), ...);
        },
        F::parameters());
    py::dict entry;
    entry["name"] = std::string(family_name(family));
    entry["arity"] = arity_of<Batch>();
    entry["parameters"] = parameters;
    entry["settable"] = requires(const Input& input) { F::make(input); };
    result.append(entry);
  });
  return result;
}

}  // namespace

void bind_model(py::module_& m) {
  m.def("families", &family_table,
        "Every constraint family: name, arity (particles per constraint; 0 for clusters, given\n"
        "as offsets + particles), the parameters Model.set_constraints takes for it, and\n"
        "settable (False for contacts, which collision detection makes).");

  py::class_<Model>(m, "Model",
                    "Particles and constraint families: what the solver simulates.\n\n"
                    "Model(positions, inverse_masses): positions (N, 3), inverse masses (N,), 0 for a\n"
                    "static (pinned) particle. Add constraints with set_constraints().")
      .def(py::init([](const py::object& positions, const py::object& inverse_masses) {
             const std::vector<Vector3r> points = to_vectors(positions, "positions");
             const std::vector<Real> masses = to_reals(inverse_masses, "inverse_masses");
             Model model;
             model.particles = ParticleState(points, masses);
             return model;
           }),
           py::arg("positions"), py::arg("inverse_masses"))
      .def(
          "set_constraints",
          [](Model& model, const std::string& family, const py::object& particles,
             const py::object& rest_positions, const py::object& offsets, py::kwargs parameters) {
            py::dict remaining;
            for (auto item : parameters) remaining[item.first] = item.second;
            with_family(model.constraints, family, [&](auto& batch) {
              using Batch = std::decay_t<decltype(batch)>;
              if constexpr (requires(const typename Family<Batch>::Input& input) {
                              Family<Batch>::make(input);
                            })
                batch = build_family<Batch>(model, particles, rest_positions, offsets, remaining);
              else
                throw InvalidInput(std::string(Batch::kFamily) +
                                   " constraints are made by collision detection, not set from "
                                   "Python");
            });
          },
          py::arg("family"), py::arg("particles"), py::kw_only(),
          py::arg("rest_positions") = py::none(), py::arg("offsets") = py::none(),
          "Replaces the constraints of `family` (a name from tessera.families()).\n\n"
          "particles: (M, arity) particle indices (clusters: a flat array plus offsets=, M + 1\n"
          "entry offsets). rest_positions: (N, 3), default the model's positions; rest lengths,\n"
          "angles, volumes and shapes are measured there. Further keywords are the family's\n"
          "parameters (tessera.families()): a number for all constraints or, where allowed, an\n"
          "array of one value per constraint. Raises ValueError naming the constraint for bad input.")
      .def(
          "constraints",
          [](const Model& model, const std::string& family) {
            py::dict result;
            with_family(model.constraints, family,
                        [&](const auto& batch) { result = family_arrays(batch); });
            return result;
          },
          py::arg("family"),
          "The arrays of one family (copies): 'particles' (M, arity) (clusters: 'offsets' and\n"
          "flat 'particles'), each per-constraint parameter (M,) and each switch.")
      .def_property_readonly("particle_count", [](const Model& model) { return model.particles.size(); })
      .def_property_readonly("constraint_count",
                             [](const Model& model) { return model.constraints.size(); })
      .def_property_readonly(
          "constraint_counts",
          [](const Model& model) {
            py::dict result;
            model.constraints.for_each([&](ConstraintFamily family, const auto& batch) {
              if (batch.size() > 0) result[py::str(std::string(family_name(family)))] = batch.size();
            });
            return result;
          },
          "Constraints per non-empty family, in global-id order.")
      .def_property_readonly(
          "positions",
          [](const Model& model) {
            const ParticleState& p = model.particles;
            py::array_t<Real> result({py::ssize_t(p.size()), py::ssize_t(3)});
            auto out = result.mutable_unchecked<2>();
            for (std::size_t i = 0; i < p.size(); ++i) {
              out(py::ssize_t(i), 0) = p.x[i];
              out(py::ssize_t(i), 1) = p.y[i];
              out(py::ssize_t(i), 2) = p.z[i];
            }
            return result;
          },
          "(N, 3) copy of the positions.")
      .def_property_readonly(
          "inverse_masses",
          [](const Model& model) {
            return copy_to_numpy<Real>(std::span(model.particles.inverse_mass.data(), model.particles.size()),
                                       {py::ssize_t(model.particles.size())});
          },
          "(N,) copy of the inverse masses.")
      .def("copy", [](const Model& model) { return Model(model); }, "An independent copy.")
      .def("__repr__", [](const Model& model) {
        std::string families;
        model.constraints.for_each([&](ConstraintFamily family, const auto& batch) {
          if (batch.size() > 0)
            families += (families.empty() ? "" : ", ") + std::string(family_name(family)) + " " +
                        std::to_string(batch.size());
        });
        return "<tessera.Model: " + std::to_string(model.particles.size()) + " particles, " +
               std::to_string(model.constraints.size()) + " constraints" +
               (families.empty() ? "" : " (" + families + ")") + ">";
      });
}

}  // namespace tessera::python
