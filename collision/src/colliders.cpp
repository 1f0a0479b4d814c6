// The analytic colliders' closest-surface queries, their validation, and contact generation:
// chunks of particles searched in parallel, each into its own reused buffer, then joined in
// chunk order so the hits do not depend on the number of threads.
#include <tessera/collision/colliders.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <tessera/core/error.hpp>

namespace tessera {

namespace {

/// Particles per chunk of contact generation: fixed, so the join order is too.
constexpr std::size_t kChunkSize = 256;
constexpr Real kUnitTolerance = Real(1e-4);

/// The direction used where a shape's outward normal is ambiguous (a sphere's centre).
const Vector3r kFallbackNormal = Vector3r::UnitY();

/// p's distance below this (relative to the coordinates' size) gives no usable direction.
bool too_close(const Vector3r& offset, const Vector3r& p) {
  return !(offset.norm() > kDegenerateTolerance * (Real(1) + p.cwiseAbs().maxCoeff()));
}

/// The unit vector perpendicular to `axis` closest to +y (+z when the axis is along y, +y when
/// there is no axis): the capsule's normal on its axis.
Vector3r perpendicular_towards_y(const Vector3r& axis) {
  const Real length = axis.norm();
  if (!(length > kDegenerateTolerance)) return kFallbackNormal;
  const Vector3r unit_axis = axis / length;
  Vector3r candidate = kFallbackNormal - kFallbackNormal.dot(unit_axis) * unit_axis;
  if (candidate.norm() < Real(1e-3)) candidate = Vector3r::UnitZ() - unit_axis.z() * unit_axis;
  return candidate.normalized();
}

SurfaceQuery surface_of(const PlaneCollider& plane, const Vector3r& p) {
  const Real distance = plane.normal.dot(p) - plane.offset;
  return {distance, plane.normal, p - distance * plane.normal};
}

/// A ball around centre: shared by the sphere and the capsule (centre = the closest axis
/// point, whose fallback normal is `on_centre`).
SurfaceQuery surface_of_ball(const Vector3r& centre, Real radius, const Vector3r& p,
                             const Vector3r& on_centre) {
  const Vector3r away = p - centre;
  const Vector3r normal = too_close(away, p) ? on_centre : Vector3r(away.normalized());
  return {away.norm() - radius, normal, centre + radius * normal};
}

SurfaceQuery surface_of(const SphereCollider& sphere, const Vector3r& p) {
  return surface_of_ball(sphere.centre, sphere.radius, p, kFallbackNormal);
}

SurfaceQuery surface_of(const CapsuleCollider& capsule, const Vector3r& p) {
  const Vector3r axis = capsule.b - capsule.a;
  const Real squared_length = axis.squaredNorm();
  const Real t = squared_length > 0
                     ? std::clamp((p - capsule.a).dot(axis) / squared_length, Real(0), Real(1))
                     : Real(0);
  return surface_of_ball(capsule.a + t * axis, capsule.radius, p,
                         perpendicular_towards_y(axis));
}

SurfaceQuery surface_of(const BoxCollider& box, const Vector3r& p) {
  const Vector3r local = box.rotation.transpose() * (p - box.centre);
  const Vector3r clamped = local.cwiseMax(-box.half_extents).cwiseMin(box.half_extents);
  const Vector3r outside = local - clamped;
  if (!too_close(outside, p)) {
    const Real distance = outside.norm();
    const Vector3r normal = box.rotation * (outside / distance);
    return {distance, normal, box.centre + box.rotation * clamped};
  }
  // Inside (or on the surface): the nearest face.
  int axis = 0;
  Real depth = box.half_extents[0] - std::abs(local[0]);
  for (int k = 1; k < 3; ++k) {
    const Real face_depth = box.half_extents[k] - std::abs(local[k]);
    if (face_depth < depth) {
      depth = face_depth;
      axis = k;
    }
  }
  const Real side = local[axis] < 0 ? Real(-1) : Real(1);
  Vector3r on_face = clamped;
  on_face[axis] = side * box.half_extents[axis];
  const Vector3r normal = side * box.rotation.col(axis);
  return {-std::max(depth, Real(0)), normal, box.centre + box.rotation * on_face};
}

SurfaceQuery surface_of(const MeshCollider& mesh, const Vector3r& p) {
  return mesh.closest_surface(p);
}

const char* kind_of(const Collider& collider) {
  constexpr const char* kinds[] = {"plane", "sphere", "box", "capsule", "mesh"};
  return kinds[collider.index()];
}

/// "collider <position> (<kind>)", made only for a message: the checks run every substep
/// (find_collider_contacts), and a string per collider and substep was the stage's one
/// allocation in steady state.
struct ColliderName {
  const Collider& collider;
  std::size_t position;
  std::string operator()() const {
    return "collider " + std::to_string(position) + " (" + kind_of(collider) + ")";
  }
};

void check_radius(Real radius, const ColliderName& name) {
  if (!std::isfinite(radius) || !(radius > 0))
    throw InvalidInput(name() + ": radius " + std::to_string(radius) + " must be finite and > 0");
}

void check_finite(const Vector3r& v, const ColliderName& name, const char* what) {
  if (!v.allFinite()) throw InvalidInput(name() + ": " + what + " is not finite");
}

void check_collider(const Collider& collider, std::size_t position) {
  const ColliderName name{collider, position};
  std::visit(
      [&](const auto& shape) {
        using Shape = std::decay_t<decltype(shape)>;
        if constexpr (std::is_same_v<Shape, PlaneCollider>) {
          check_finite(shape.normal, name, "normal");
          if (!std::isfinite(shape.offset)) throw InvalidInput(name() + ": offset is not finite");
          const Real squared = shape.normal.squaredNorm();
          if (!(std::abs(squared - 1) <= kUnitTolerance))
            throw InvalidInput(name() + ": normal must be a unit vector (its length is " +
                               std::to_string(std::sqrt(squared)) + ")");
        } else if constexpr (std::is_same_v<Shape, SphereCollider>) {
          check_finite(shape.centre, name, "centre");
          check_radius(shape.radius, name);
        } else if constexpr (std::is_same_v<Shape, BoxCollider>) {
          check_finite(shape.centre, name, "centre");
          check_finite(shape.half_extents, name, "half extents");
          if (!shape.rotation.allFinite()) throw InvalidInput(name() + ": rotation is not finite");
          if ((shape.half_extents.array() < 0).any())
            throw InvalidInput(name() + ": a half extent is negative");
          const Real error = (shape.rotation.transpose() * shape.rotation -
                              Matrix3r::Identity()).cwiseAbs().maxCoeff();
          if (!(error <= kUnitTolerance) || !(shape.rotation.determinant() > 0))
            throw InvalidInput(name() +
                               ": rotation is not a rotation (its columns must be orthonormal "
                               "and its determinant +1)");
        } else if constexpr (std::is_same_v<Shape, CapsuleCollider>) {
          check_finite(shape.a, name, "end a");
          check_finite(shape.b, name, "end b");
          check_radius(shape.radius, name);
        }
        // A MeshCollider cannot exist unvalidated: its constructor checks it.
      },
      collider);
}

void check_distance(Real value, const char* what) {
  if (!std::isfinite(value) || value < 0)
    throw InvalidInput(std::string("collider contacts: ") + what + " " +
                       std::to_string(value) + " must be finite and ≥ 0");
}

/// True when the box [lower, upper] and the bounds grown by reach do not overlap.
bool misses_bounds(const Bounds3& bounds, const Vector3r& lower, const Vector3r& upper,
                   Real reach) {
  return ((lower - bounds.upper).array() > reach).any() ||
         ((bounds.lower - upper).array() > reach).any();
}

bool outside_bounds(const Bounds3& bounds, const Vector3r& p, Real reach) {
  return misses_bounds(bounds, p, p, reach);
}

}  // namespace

void validate_colliders(std::span<const Collider> colliders) {
  for (std::size_t c = 0; c < colliders.size(); ++c) check_collider(colliders[c], c);
}

SurfaceQuery closest_surface(const Collider& collider, const Vector3r& p) {
  return std::visit([&](const auto& shape) { return surface_of(shape, p); }, collider);
}

namespace {

/// Whether p is certainly farther than `reach` from a ball's surface, from its squared
/// distance to the centre alone: the surface query's |p − centre| − radius ≥ reach there, so
/// its three roots are spared for the particles far from a sphere (most of a cloth). The
/// room of 10⁻⁴ of radius + reach is far above their rounding: the same contacts.
bool beyond_ball(const Vector3r& centre, Real radius, const Vector3r& p, Real reach) {
  const Real beyond = (radius + reach) * (Real(1) + Real(1e-4));
  return (p - centre).squaredNorm() > beyond * beyond;
}

/// Whether p is certainly out of a collider's reach without its surface query (spheres
/// only; the other shapes' queries are cheap or have their own bounds).
bool certainly_beyond(const Collider& collider, const Vector3r& p, Real reach) {
  const auto* sphere = std::get_if<SphereCollider>(&collider);
  return sphere && beyond_ball(sphere->centre, sphere->radius, p, reach);
}

}  // namespace

void ColliderHits::clear() {
  particles.clear();
  normals.clear();
  offsets.clear();
  anchors.clear();
  normal_speeds.clear();
  collider.clear();
}

void find_collider_contacts(std::span<const Collider> colliders, const ParticleState& state,
                            Real thickness, Real margin, ColliderHits& out) {
  validate_colliders(colliders);
  check_distance(thickness, "thickness");
  check_distance(margin, "margin");
  const Real reach = thickness + margin;
  const std::size_t particle_count = state.size();
  const std::size_t chunk_count = (particle_count + kChunkSize - 1) / kChunkSize;
  if (out.chunk_hits.size() < chunk_count) out.chunk_hits.resize(chunk_count);
  // Mesh bounds once per call, not once per particle.
  std::vector<Bounds3>& mesh_bounds = out.mesh_bounds;
  mesh_bounds.resize(colliders.size());
  for (std::size_t c = 0; c < colliders.size(); ++c)
    if (const auto* mesh = std::get_if<MeshCollider>(&colliders[c]))
      mesh_bounds[c] = mesh->bounds();

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunk_count, 1), [&](const auto& range) {
    for (std::size_t chunk = range.begin(); chunk != range.end(); ++chunk) {
      std::vector<ColliderHits::Hit>& hits = out.chunk_hits[chunk];
      hits.clear();
      const std::size_t end = std::min(particle_count, (chunk + 1) * kChunkSize);
      for (std::size_t i = chunk * kChunkSize; i < end; ++i) {
        if (!(state.inverse_mass[i] > 0)) continue;
        const Vector3r p = state.position(i);
        const Vector3r previous(state.previous_x[i], state.previous_y[i], state.previous_z[i]);
        const Vector3r velocity = state.velocity(i);
        for (std::size_t c = 0; c < colliders.size(); ++c) {
          const auto emit = [&](const Vector3r& normal, const Vector3r& surface_point) {
            hits.push_back({ParticleIndex(i), std::uint32_t(c), normal,
                            normal.dot(surface_point) + thickness, previous,
                            velocity.dot(normal)});
          };
          if (const auto* mesh = std::get_if<MeshCollider>(&colliders[c])) {
            // The segment previous → p cannot meet the mesh when the box around it misses.
            if (misses_bounds(mesh_bounds[c], previous.cwiseMin(p), previous.cwiseMax(p), reach))
              continue;
            Vector3r entry_point, entry_normal;
            if (outside_bounds(mesh_bounds[c], p, reach)) {
              if (mesh->first_entry(previous, p, entry_point, entry_normal))
                emit(entry_normal, entry_point);
              continue;
            }
            // A crossing of the surface is within the segment's length of p, so the segment
            // is only walked when p is no farther from the surface than that: particles at
            // rest, which move less than their distance to the surface, skip the walk.
            const SurfaceQuery surface = mesh->closest_surface(p);
            if (std::abs(surface.distance) <= (p - previous).norm() &&
                mesh->first_entry(previous, p, entry_point, entry_normal))
              emit(entry_normal, entry_point);
            else if (surface.distance < reach)
              emit(surface.normal, surface.point);
            continue;
          }
          if (certainly_beyond(colliders[c], p, reach)) continue;
          const SurfaceQuery surface = closest_surface(colliders[c], p);
          if (surface.distance < reach) emit(surface.normal, surface.point);
        }
      }
    }
  });

  std::size_t total = 0;
  for (std::size_t chunk = 0; chunk < chunk_count; ++chunk) total += out.chunk_hits[chunk].size();
  out.particles.resize(total);
  out.normals.resize(total);
  out.offsets.resize(total);
  out.anchors.resize(total);
  out.normal_speeds.resize(total);
  out.collider.resize(total);
  std::size_t k = 0;
  for (std::size_t chunk = 0; chunk < chunk_count; ++chunk)
    for (const ColliderHits::Hit& hit : out.chunk_hits[chunk]) {
      out.particles[k] = hit.particle;
      out.normals[k] = hit.normal;
      out.offsets[k] = hit.offset;
      out.anchors[k] = hit.anchor;
      out.normal_speeds[k] = hit.normal_speed;
      out.collider[k] = hit.collider;
      ++k;
    }
}

Real penetration_depth(std::span<const Collider> colliders, std::span<const Vector3r> positions) {
  validate_colliders(colliders);
  // max is exact and order-free, so the reduction is the same for any split.
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, positions.size(), kChunkSize), Real(0),
      [&](const tbb::blocked_range<std::size_t>& range, Real deepest) {
        for (std::size_t i = range.begin(); i != range.end(); ++i)
          for (const Collider& collider : colliders) {
            const auto* mesh = std::get_if<MeshCollider>(&collider);
            if (mesh && outside_bounds(mesh->bounds(), positions[i], 0)) continue;
            deepest = std::max(deepest, -closest_surface(collider, positions[i]).distance);
          }
        return deepest;
      },
      [](Real l, Real r) { return std::max(l, r); });
}

}  // namespace tessera
