// What the three translation units of the Python module share: the NumPy conversions (copies
// in, copies or read-only views out) and the function each unit binds its part with.
//
//   module.cpp   the module, exceptions, listings, scenes and meshes, graph and colouring
//   model.cpp    tessera.Model and the per-family table (every family's parameters, one place)
//   solver.cpp   tessera.Solver
//   collisions.cpp  its collision stage, and the contact checks (penetration, intersections)
//
// Arrays of Real are float32 in the default build and float64 with TESSERA_DOUBLE; input
// arrays of any numeric type are converted (a copy) to Real or to 32-bit indices.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <tessera/coloring/colouring.hpp>
#include <tessera/coloring/colouring_statistics.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/indices.hpp>
#include <tessera/core/real.hpp>

namespace tessera {
class Solver;
namespace io {
struct Scene;
}
}  // namespace tessera

namespace tessera::python {

namespace py = pybind11;

/// Input arrays converted to C order and to the element type (a copy when they differ).
using RealArray = py::array_t<Real, py::array::c_style | py::array::forcecast>;
using IndexArray = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;

/// "(5, 3)" for messages.
std::string shape_of(const py::array& array);

/// An (N, 3) array of positions as Vector3r; InvalidInput "<what> must have shape (N, 3)..."
/// otherwise (N = expected unless expected is SIZE_MAX).
std::vector<Vector3r> to_vectors(const py::handle& object, const std::string& what,
                                 std::size_t expected = SIZE_MAX);
/// A 1-D array of Real of length `expected` (any length when SIZE_MAX).
std::vector<Real> to_reals(const py::handle& object, const std::string& what,
                           std::size_t expected = SIZE_MAX);
/// Integers as 32-bit indices; InvalidInput for a negative value or one of 2^32 or more.
/// `columns` > 0: the array must have shape (M, columns) (an empty 1-D array is M = 0);
/// columns == 0: any 1-D array.
std::vector<std::uint32_t> to_indices(const py::handle& object, const std::string& what,
                                      std::size_t columns);

/// A new NumPy array holding a copy of `values` with the given shape.
template <class T>
py::array_t<T> copy_to_numpy(std::span<const T> values, std::vector<py::ssize_t> shape) {
  py::array_t<T> result(shape);
  std::copy(values.begin(), values.end(), result.mutable_data());
  return result;
}
/// (M, arity) copy of element indices (triangles, tetrahedra) stored back to back.
inline py::array_t<std::uint32_t> elements_to_numpy(const std::vector<std::uint32_t>& indices,
                                                    std::size_t arity) {
  return copy_to_numpy<std::uint32_t>(indices,
                                      {py::ssize_t(indices.size() / arity), py::ssize_t(arity)});
}
/// (N, 3) copy of positions.
py::array_t<Real> vectors_to_numpy(std::span<const Vector3r> points);

/// A read-only NumPy view of `count` values at `data`, kept valid by holding `owner` (the
/// Python object that owns the memory).
template <class T>
py::array_t<T> read_only_view(const T* data, std::size_t count, py::handle owner) {
  py::array_t<T> view({py::ssize_t(count)}, {py::ssize_t(sizeof(T))}, data, owner);
  py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return view;
}

/// tessera.Colouring: a colouring and what run_colouring measured of it.
struct PyColouring {
  Colouring colouring;
  ColouringStatistics statistics;
  /// The strategy's name as the tool prints it (without the post-passes).
  std::string strategy;
  /// The statistics under the keys of `tessera color --json`, in its order.
  py::dict statistics_dict() const;
};

void bind_model(py::module_& m);
void bind_solver(py::module_& m);
/// The collision stage's methods on tessera.Solver and the contact checks of the module.
void bind_collisions(py::module_& m, py::class_<Solver>& solver);
/// A scene's collision settings as set_collisions' keyword arguments (None without any).
py::object scene_collision_settings(const io::Scene& scene);

}  // namespace tessera::python
