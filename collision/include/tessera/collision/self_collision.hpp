// Cloth self-collision: the contacts of a triangle mesh with itself, found once per substep
// and answered by the proximity distance families (compression only, rest distance = the
// thickness):
//
//   vertex–triangle  p  over (a, b, c), p not a corner          → triangle_point (p, a, b, c)
//   edge–edge        (p0, p1) against (p2, p3), no shared vertex → edge_edge (p0, p1, p2, p3)
//
//        p •                       p0 •────• p1
//          ¦ d < h + m                  ¦ d < h + m
//     a ───┴─── b             p2 •──────┴────• p3
//          c
//
// Which distance: a pair is a contact when it can come closer than r = thickness + margin
// at some moment of the substep's straight motion from the previous positions (start of the
// substep) to the predicted ones. The test is conservative and cheap: the distance at the
// start minus the most any two of its points can approach each other,
//
//   d_start − max |Δp − Δx| < r      over the corners x of the triangle (Δ = predicted − previous)
//
// (a point of a moving triangle moves by a convex combination of its corners' motions, so
// the pair's difference moves by a convex combination of the Δp − Δx; edge–edge takes the
// most over the four corner pairs). Only relative motion counts: a cloth falling as a whole
// has its resting contacts only. Testing the predicted positions instead would miss a vertex
// that crosses a triangle within the substep: it is found at neither end. Contacts are
// therefore registered before the crossing, at the start-of-substep side.
//
// Reusing a detection (the grids are the cost; the rule is cheap). Each particle is given a
// straight path at the detection, its reference
//
//   R(τ) = A + τ V       τ the substeps since the build, V = Δ − ū its motion then against
//                        the bulk's (ū the median motion, of an even sample), A its start
//                        then (less the bulk's way)
//
// and a budget b = skin + k (k + 1) |Δ − Δ_prev| (k = motion_scale; Δ_prev its motion of the
// substep before: the room for k substeps of the change of its motion). On a later substep
// τ, write for each particle
//
//   w = |start − W − R(τ)|   how far it is from its path (W the bulk's way since the build:
//                            the cloth may drift as a whole)
//   m = |Δ − ū − V|          how far its motion is from its path's
//
// A pair's references come closer by at most ρ = max |V_i − V_j| per substep (over a corner
// i of the one and j of the other: each hull point moves by a convex combination of its
// corners' velocities), so at substep τ the rule's left side d_start − max |Δp − Δx| is at
// least d_c − (τ − τ_c) ρ − ρ − (w_max + m_max)(first) − (w_max + m_max)(second), d_c the
// distance of the references at τ_c, the substep the pair was tested. A detection therefore
// lists as candidates the pairs with
//
//   d_c < r + (T − τ_c + 1) ρ + b(first) + b(second)     T = horizon, b the corners' largest
//
// and while every particle keeps w ≤ b/2 and m ≤ b/2 and τ ≤ T (covers()), each pair that
// meets the rule is a candidate: filtering the candidates (refine()) gives exactly the
// contacts of a detection of its own. The broad phase grows each primitive's box, swept from
// its references at τ_c to those at T, by its largest b + |V|: a pair in contact at substep τ
// has d(R(τ)) < r + ρ + b + b with ρ at most the sum of the two speeds, and both R(τ) lie in
// the swept boxes, so the boxes of every contact overlap and the grids miss none. (A pair
// that meets the candidate rule but only recedes may be missed: it is no contact.) A cloth moving on straight lines, whatever
// its speeds, keeps its candidates the whole horizon; a cloth in the plane with itself has as
// candidates the neighbours that approach, not every one within its budgets. (The frame
// before was the bulk's motion alone: a fast fold left its room within two substeps, and each
// particle's room was its whole speed against the median; the paths measured on the drape
// stay 30 times closer to the particles after a substep, docs/performance.md.)
//
// Filtering without measuring most candidates. Most candidates are neighbours in the cloth's
// plane, a little beyond the reach, and stay there. A candidate keeps the least its bound can
// be over the horizon, d_c − (T − τ_c + 1) ρ, and its ρ: at substep τ the bound is that plus
// (T − τ) ρ (the motion still to come is not yet closed; credited 10⁻⁵ short, for the
// rounding of two terms as large as T ρ). A candidate whose bound at τ less each side's
// largest w and m passes r (by a rounding allowance: 10⁻³ r plus 10⁻⁵ of the largest
// coordinate) cannot be a contact: the filter skips its exact distance. The same
// contacts as measuring every candidate, at a fraction of the reads (on the drape, a fifth of
// the candidates are measured; with the horizon's end bound instead of τ's, a third).
//
// Limit (the kernel measures |p − q|, unsigned): a contact keeps a vertex on its side only
// while the vertex has not passed the triangle when the kernel first sees it. Starting from a
// resolved state (distance ≥ thickness), that holds while the relative motion of the pair in
// one substep stays below the thickness: relative speed × substep < thickness, i.e. each
// particle's speed × substep < thickness / 2. Faster cloth needs smaller substeps. The
// margin covers what the solver moves the particles beyond the prediction (other
// constraints, iterations); 0.1–0.5 × thickness is typical.
//
// Also: the thickness (plus margin) must stay below the rest distance between primitives
// that share no vertex (about 0.7 × the edge length on a grid), or the flat cloth is in
// contact with itself at rest.
//
// Determinism: contacts are listed sorted by (vertex, triangle) and (edge, edge) for any
// thread count.
//
// Rounding: the candidate rule has no allowance of its own; the budgets' skin is the room a
// particle on its path keeps (with skin 0 and no change of motion, b = 0 and a rounding
// off the path is a re-box).
//
// Cost (bench/collision_benchmarks.cpp, the drape at frame 60 and the folded 128² cloth):
// the work is in the candidates' boxes, not in the contacts. Each of the 48,641 edges' boxes
// (h long, grown by r/2 + budget + speed, swept along the paths) overlaps ~15 others, ~10 of
// them sharing no vertex (a segment distance each), and each of the 16,384 vertices meets ~17
// triangle boxes. A build therefore works by leaves of 16 primitives (8 in double, a cache
// line per field): one grid query per leaf, each member tested against the met leaves'
// members in vectors read in place, box overlap and topology as masks before the distance.
// Hence also reuse: the stage calls update(), which filters the candidates while every
// particle keeps to its room, re-boxes only the primitives of the particles that left it
// (each re-anchored on the path of its motion now), and builds again past kReboxedShare of
// the mesh or past the horizon.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <tessera/collision/spatial_hash.hpp>
#include <tessera/core/indices.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/proximity_distance_constraints.hpp>
#include <tessera/core/real.hpp>

namespace tessera {

struct SelfCollisionSettings {
  /// Rest distance of a contact: the cloth's thickness (> 0).
  Real thickness = 0;
  /// Detection distance beyond the thickness (≥ 0): a contact exists from thickness + margin.
  Real margin = 0;
  /// Compression stiffness of the contact constraints, in [0, 1].
  Real stiffness = 1;
  /// Whether to find edge–edge contacts. They take most of the detection (three edges per
  /// vertex, each measured against the edges near it); without them a crossing of two edges
  /// whose vertices stay out of reach of the other's triangles goes unseen.
  /// update() builds again when this changes; refine() finds edge–edge contacts only among
  /// the candidates of a detection that had it on.
  bool edge_edge = true;
  /// The substeps of change of motion a particle's room is meant to last (see "Reusing a
  /// detection" above): each particle's budget is skin + k (k + 1) |Δ − Δ_prev|, Δ_prev its
  /// motion of the call before. ≥ 1.
  Real motion_scale = 1;
  /// Distance every particle may stray from its path before covers() fails, on top of its
  /// motion_scale substeps of change of motion. ≥ 0. Larger: more candidates to refine per
  /// substep, fewer detections.
  Real skin = 0;
  /// The most substeps after a detection its candidates serve: update() builds again after
  /// that many. A build shortens it to the substeps in which its fast particles (the 90th
  /// percentile of |V|) close kHorizonReachShare of the reach, and to at most
  /// SelfCollision::kLongestHorizon: each candidate pair's distance allows for (horizon + 1)
  /// substeps of the relative motion of the pair's paths. Read at a build. ≥ 0.
  std::size_t horizon = 8;
};

/// The particle arrays detection reads (SoA): predicted positions x, y, z and the positions
/// at the start of the substep. The arrays hold `count` particles.
struct SelfCollisionPositions {
  const Real* x;
  const Real* y;
  const Real* z;
  const Real* previous_x;
  const Real* previous_y;
  const Real* previous_z;
  const Real* inverse_mass;
  std::size_t count;

  static SelfCollisionPositions of(const ParticleState& state) {
    return {state.x.data(),          state.y.data(),          state.z.data(),
            state.previous_x.data(), state.previous_y.data(), state.previous_z.data(),
            state.inverse_mass.data(), state.size()};
  }
};

class SelfCollision {
 public:
  /// The contacts of one detection, as the particle lists of the proximity families.
  struct Contacts {
    /// Four particles per contact (p, a, b, c), sorted by (p, triangle index).
    std::vector<ParticleIndex> triangle_point;
    /// Four particles per contact (p0, p1, p2, p3), edge (p0, p1) before edge (p2, p3) in
    /// the edge order, sorted by that pair of edges.
    std::vector<ParticleIndex> edge_edge;
    /// The mesh's triangle index of each vertex–triangle contact.
    std::vector<std::uint32_t> triangle_point_triangle;

    std::size_t triangle_point_count() const { return triangle_point.size() / 4; }
    std::size_t edge_edge_count() const { return edge_edge.size() / 4; }
  };

  /// The mesh: three particle indices per triangle, below particle_count. Builds the unique
  /// edges. Throws InvalidInput naming the triangle for an index out of range, a particle
  /// named twice in a triangle, or an index count that is not a multiple of 3.
  SelfCollision(std::span<const std::uint32_t> triangles, std::size_t particle_count);
  SelfCollision(SelfCollision&&) noexcept;
  SelfCollision& operator=(SelfCollision&&) noexcept;
  ~SelfCollision();

  /// Finds this substep's contacts (see the top of this file), overwriting `out`. Reuses the
  /// object's buffers, so one object serves one caller at a time; parallel inside (TBB).
  /// Throws InvalidInput for a particle count other than the mesh's, or a thickness that is
  /// not positive and finite, or a negative margin.
  void detect(const SelfCollisionPositions& positions, const SelfCollisionSettings& settings,
              Contacts& out);
  void detect(const ParticleState& state, const SelfCollisionSettings& settings,
              Contacts& out) {
    detect(SelfCollisionPositions::of(state), settings, out);
  }

  /// The contacts of the next substep among the candidates the last detect() found: each
  /// pair tested again by the contact rule at `positions` (start and predicted), in the
  /// same order. While covers(positions) holds, this is the list a detection of its own
  /// would give. Each call is one substep on the particles' paths (they stop at the
  /// horizon). Same errors as detect().
  void refine(const SelfCollisionPositions& positions, const SelfCollisionSettings& settings,
              Contacts& out);
  void refine(const ParticleState& state, const SelfCollisionSettings& settings, Contacts& out) {
    refine(SelfCollisionPositions::of(state), settings, out);
  }

  /// What update() did.
  enum class Update { refined, reboxed, built };
  /// This substep's contacts (overwriting `out`) at the least cost that keeps them exact:
  /// the candidates filtered (refine) when every particle is within its room; else the
  /// primitives of the particles that outran it re-anchored, re-boxed and queried again
  /// (the rest keep their candidates), or a full build when those passed kReboxedShare of
  /// the mesh since the last build, past the last build's horizon, when edge_edge changed or
  /// the reach grew, or before any. The same contacts as detect() in every case. Same errors
  /// as detect().
  Update update(const SelfCollisionPositions& positions, const SelfCollisionSettings& settings,
                Contacts& out);
  Update update(const ParticleState& state, const SelfCollisionSettings& settings, Contacts& out) {
    return update(SelfCollisionPositions::of(state), settings, out);
  }
  /// Above this share of the mesh's triangles and edges re-boxed since the last build,
  /// update() builds again. Measured on the 120-frame drape, 2 threads (detection seconds,
  /// one run each, ~3 % apart run to run): 0.05 51.7, 0.1 49.9, 0.2 49.9, 0.35 52.9: flat
  /// between a tenth and a fifth (docs/performance.md).
  static constexpr double kReboxedShare = 0.1;

  /// Whether the last detection's candidates still hold every contact at `positions`, taken
  /// as the substep after the last detect(), update() or refine(): that substep is within
  /// the horizon, and each particle's distance from its path (in the frame of the bulk's way)
  /// and its motion against its path's are each within half its budget. False before any
  /// detection or for another particle count.
  bool covers(const SelfCollisionPositions& positions);
  bool covers(const ParticleState& state) { return covers(SelfCollisionPositions::of(state)); }

  /// The last detection's candidate pairs (vertex–triangle and edge–edge), which refine()
  /// filters.
  std::size_t candidate_count() const {
    return triangle_point_candidate_count() + edge_edge_candidate_count();
  }
  std::size_t triangle_point_candidate_count() const { return candidate_triangle_point_.size(); }
  std::size_t edge_edge_candidate_count() const { return candidate_edge_edge_.size(); }
  /// How many candidates the last filtering measured (the rest were ruled out by their
  /// distance at the anchors; see "Filtering" above).
  std::size_t measured_candidate_count() const { return measured_candidates_; }

  std::size_t particle_count() const { return particle_count_; }
  std::span<const std::uint32_t> triangles() const { return triangles_; }
  /// Two particles per unique edge (lower first), sorted.
  std::span<const std::uint32_t> edges() const { return edges_; }

 private:
  struct Pair {
    std::uint32_t first, second;
  };
  /// A candidate pair, the least the distance of its primitives' references can be over
  /// the horizon, less one substep of their relative motion: d_c − (T − τ_c + 1) ρ, and ρ,
  /// the most that relative motion closes per substep: at substep τ the least is
  /// bound + (T − τ) ρ.
  struct Candidate {
    std::uint32_t first, second;
    Real bound, rate;
  };
  /// The candidate of a pair at squared distance `squared` whose relative motion closes
  /// `allowed` over `steps` substeps (d_c = √squared, ρ = allowed / steps).
  static Candidate candidate_of(std::uint32_t first, std::uint32_t second, Real squared,
                                Real allowed, Real steps) {
    return {first, second, std::sqrt(squared) - allowed, allowed / steps};
  }
  /// How far a particle has left its room this substep: its way since it was anchored
  /// (w, in the frame) and its motion against the bulk's (m).
  struct Departure {
    Real way, motion;
  };
  struct Reach {
    Real distance;  // thickness + margin
  };
  /// The bulk's motion and way since the last build (medians), and the substep since the
  /// build: the frame the paths live in.
  struct Frame {
    Vector3r way;
    Vector3r motion;
    Real substep = 0;
  };
  void check(const SelfCollisionPositions& positions, const SelfCollisionSettings& settings) const;
  /// Each particle's motion over the substep, into motion_ (scratch of every call).
  void measure_motion(const SelfCollisionPositions& positions);
  /// The same, and the reach of the settings.
  Reach compute_motion(const SelfCollisionPositions& positions,
                       const SelfCollisionSettings& settings);
  Vector3r bulk_motion();
  Frame frame(const SelfCollisionPositions& positions);
  /// Particle i anchored on a path at this substep: its velocity V = Δ − bulk, its virtual
  /// anchor A = start − way − τ V (so that R(τ) = A + τ V is its start less the way) and its
  /// budget skin + k (k + 1) |Δ − Δ_prev| (skin alone without a previous motion).
  void anchor_on_path(std::uint32_t i, const Frame& frame, const SelfCollisionPositions& positions,
                      const SelfCollisionSettings& settings);
  /// The substeps left in the horizon, plus one: the relative motions a pair tested now
  /// allows for.
  Real substeps_allowed() const { return Real(horizon_ - substep_) + 1; }
  /// The horizon of a build whose particles are on their paths: the substeps in which the
  /// fast ones close kHorizonReachShare of the reach, at most settings.horizon.
  std::size_t horizon_for(Real reach, const SelfCollisionSettings& settings);
  static constexpr Real kHorizonReachShare = Real(0.75);
  /// The longest horizon a build takes, whatever the setting: a larger one would only sweep
  /// the fast particles' boxes across the scene.
  static constexpr std::size_t kLongestHorizon = 1024;
  /// Every particle's reference at this substep (A + τ V), and the records of the new
  /// primitives (new_triangles_, new_edges_), whose particles were re-anchored.
  void refresh_references(const SelfCollisionSettings& settings);
  /// The ball of particles `ids`' velocities: their mean and the largest distance from it.
  template <std::size_t N>
  void velocity_ball(const std::uint32_t (&ids)[N], Real (&centre)[3], Real& radius) const;
  /// Particle i's departure from its room under `frame`, both parts squared.
  Departure squared_departure(std::uint32_t i, const Frame& frame,
                              const SelfCollisionPositions& positions) const;
  /// Whether particle i, departed by `squared`, has left its room (see "Reusing a
  /// detection").
  bool outran(const Departure& squared, std::uint32_t i) const;
  /// The candidate rule on the anchors: closer than the reach plus the two budgets. A
  /// candidate is appended to `out` with its distance.
  void add_edge_edge_candidate(std::uint32_t e, std::uint32_t f, Real reach,
                               const SelfCollisionPositions& positions,
                               std::vector<Candidate>& out) const;
  /// The same for every edge f that collect(visit) visits, their distances a vector at a
  /// time (segment_distances.cpp), in the order visited. Reads edge_anchors_.
  template <class Collect>
  void add_edge_edge_candidates(std::uint32_t e, Real reach,
                                const SelfCollisionPositions& positions,
                                std::vector<Candidate>& out, Collect&& collect) const;
  /// Edge e's record in edge_anchors_, from its particles' budgets and velocities.
  void set_edge_anchors(std::uint32_t e);
  /// The same rule for vertex p and every triangle t that collect(visit) visits, their
  /// distances a vector at a time (triangle_distances.cpp), in the order visited. Reads
  /// triangle_anchors_.
  template <class Collect>
  void add_triangle_point_candidates(std::uint32_t p, Real reach,
                                     const SelfCollisionPositions& positions,
                                     std::vector<Candidate>& out, Collect&& collect) const;
  /// Triangle t's record in triangle_anchors_: its budget and velocity ball (which change
  /// with a re-anchoring only).
  void set_triangle_anchors(std::uint32_t t);
  /// Every particle's departure from its room under `frame`, into departure_, and the
  /// rounding allowance of the filter's bound; with `outran_list`, also the particles that
  /// left their room (ascending), from the same squared lengths.
  void measure_departures(const SelfCollisionPositions& positions, const Frame& frame,
                          std::vector<std::uint32_t>* outran_list = nullptr);
  Aabb vertex_box(std::uint32_t p, Real reach) const;
  Aabb triangle_box(std::uint32_t t) const;
  Aabb edge_box(std::uint32_t e, Real reach) const;
  /// Every particle anchored at its start; the grids and the candidates.
  /// Returns the bulk's motion it anchored the budgets to.
  Vector3r build(const SelfCollisionPositions& positions, const SelfCollisionSettings& settings,
             Real reach);
  /// The particles of outran_ re-anchored, their primitives re-boxed and their candidates
  /// found again; false (nothing done) when a build would cost less.
  bool rebox(const SelfCollisionPositions& positions, const SelfCollisionSettings& settings,
             Real reach, const Frame& now);
  /// The candidates that meet the contact rule at `positions`, into the pair lists.
  void filter_candidates(const SelfCollisionPositions& positions,
                         const SelfCollisionSettings& settings, Real reach);
  /// `into` without the pairs whose first is flagged in `drop_first` or whose second is in
  /// `drop_second` (either may be null: nothing dropped by it), merged with `more`. Both
  /// sorted by (first, second), and no kept pair of `into` is in `more`.
  void merge_sorted(std::vector<Candidate>& into, const std::vector<Candidate>& more,
                    const std::uint8_t* drop_first = nullptr,
                    const std::uint8_t* drop_second = nullptr);
  /// The pairs as the particle lists of `out`.
  void emit(Contacts& out) const;

  std::size_t particle_count_;
  std::vector<std::uint32_t> triangles_;
  std::vector<std::uint32_t> edges_;
  // Buffers reused across detections.
  std::vector<Vector3r> motion_;           // predicted − previous per particle
  std::vector<Vector3r> previous_motion_;  // the motion of the last detect/update/refine
  std::vector<Real> budget_;               // per particle, set when it was anchored
  // Each particle's path: R(τ) = anchor + τ velocity (in the frame: start − bulk way), set
  // when it was anchored; its speed |velocity|; its reference at the last build or re-box.
  std::vector<Vector3r> anchor_, velocity_, reference_;
  std::vector<Real> speed_;
  std::vector<Vector3r> frame_origin_;  // start positions at the last build
  std::size_t substep_ = 0;             // τ: substeps since the last build
  std::size_t horizon_ = 0;             // T of the last build
  Real built_reach_ = 0;                // the reach (thickness + margin) of the last build
  std::vector<Real> scratch_;           // the medians' copies
  // Incidence: each vertex's triangles and edges (CSR).
  std::vector<std::uint32_t> vertex_triangle_start_, vertex_triangles_;
  std::vector<std::uint32_t> vertex_edge_start_, vertex_edges_;
  // Re-boxing since the last build: flags and lists, their boxes and grids; this update's
  // new ones; the particles that outran their room.
  std::vector<std::uint8_t> reboxed_triangle_, reboxed_edge_;
  std::vector<std::uint32_t> reboxed_triangles_, reboxed_edges_;
  std::vector<Aabb> reboxed_triangle_boxes_, reboxed_edge_boxes_;
  UniformGrid reboxed_triangle_grid_, reboxed_edge_grid_;
  std::vector<std::uint8_t> new_vertex_, new_triangle_, new_edge_;
  std::vector<std::uint32_t> new_triangles_, new_edges_, outran_;
  std::vector<Candidate> found_triangle_point_, found_others_, found_edge_edge_, merged_;
  // merge_sorted's block boundaries (blocks + 1 each): the kept pairs before each block,
  // and where each block's run of new pairs starts.
  std::vector<std::size_t> merge_kept_, merge_run_;
  std::vector<Departure> departure_;  // per particle, this substep's
  // Per vertex w + m, per triangle and per edge the largest w plus the largest m of its
  // corners: the filter's bound, this substep's.
  std::vector<Real> vertex_spread_, triangle_spread_, edge_spread_;
  Real departure_allowance_ = 0;      // rounding room of the filter's bound
  /// Rounding room of the edge pairs' candidate rule (kAllowancePerCoordinate × the largest
  /// reference coordinate): a build measures a pair from whichever edge's leaf comes first,
  /// the filter from the lower edge, and the segment distance is not symmetric to the bit; a
  /// pair at the limit in the filter's bits stays a candidate (more candidates, not fewer
  /// contacts).
  Real edge_slack_ = 0;
  std::vector<std::uint32_t> outran_scratch_;  // measure_departures' list when none is asked
  /// The allowance per unit of the largest coordinate.
  static constexpr Real kAllowancePerCoordinate = Real(1e-5);
  std::size_t measured_candidates_ = 0;
  std::vector<Aabb> vertex_boxes_, triangle_boxes_, edge_boxes_;
  /// Each edge's larger budget and the ball of its corners' velocities (centre, radius),
  /// fixed from its particles' anchoring to the next (the references, which move every
  /// substep, are read from reference_): one record, 32 bytes in float (64 in double), each
  /// within one cache line, per edge met.
  struct alignas(8 * sizeof(Real)) EdgeAnchors {
    Real budget, radius, centre[3];
  };
  std::vector<EdgeAnchors> edge_anchors_;
  bool built_with_edge_edge_ = false;  // the last build's SelfCollisionSettings::edge_edge
  /// Each triangle's largest budget and the ball of its corners' velocities, as EdgeAnchors.
  struct alignas(8 * sizeof(Real)) TriangleAnchors {
    Real budget, radius, centre[3];
  };
  std::vector<TriangleAnchors> triangle_anchors_;
  std::vector<Pair> triangle_point_pairs_, edge_edge_pairs_;
  // The last detection's candidates, which refine() filters.
  std::vector<Candidate> candidate_triangle_point_, candidate_edge_edge_;
  struct Chunks;  // the parallel loops' per-chunk buffers (chunked_output.hpp)
  std::unique_ptr<Chunks> chunks_;
  /// The build's broad phase: vertices, triangles and edges in leaves, ordered at the first
  /// build, and the triangles' and edges' records as blocks of lanes (primitive_leaves.hpp).
  struct Leaves;
  std::unique_ptr<Leaves> leaves_;
  bool leaves_ordered_ = false;
  /// The candidates sorted by (first, second), first below `keys` (a counting sort by first).
  void sort_candidates(std::vector<Candidate>& candidates, std::size_t keys);
  std::vector<std::uint32_t> key_start_;
};

/// The contacts as constraint batches: rest distance = thickness, compression stiffness =
/// settings.stiffness, stretch stiffness 0 (a contact only pushes apart).
struct SelfCollisionConstraints {
  TrianglePointDistanceConstraints triangle_point;
  EdgeEdgeDistanceConstraints edge_edge;
};
SelfCollisionConstraints make_self_collision_constraints(const SelfCollision::Contacts& contacts,
                                                         std::size_t particle_count,
                                                         const SelfCollisionSettings& settings);
/// The same into two batches (every field replaced, the arrays' capacity kept).
void make_self_collision_constraints(const SelfCollision::Contacts& contacts,
                                     std::size_t particle_count,
                                     const SelfCollisionSettings& settings,
                                     TrianglePointDistanceConstraints& triangle_point,
                                     EdgeEdgeDistanceConstraints& edge_edge);

}  // namespace tessera
