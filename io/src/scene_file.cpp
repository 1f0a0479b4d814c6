// Scene specs and JSON scene files into SceneDescriptions (parsing only: building is
// build_scene's, in scenes.cpp).
//
// The JSON reader walks the object key by key against a table of the keys it knows, so an
// unknown or misspelt key is an error that names it, and every value is checked for its type
// and range with a message that names the key.
#include <tessera/io/scene_file.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <utility>

#include <nlohmann/json.hpp>

#include <tessera/core/error.hpp>

namespace tessera::io {
namespace {

using Json = nlohmann::json;

constexpr std::string_view kAxes = "xyz";

/// True when `number` is finite and converts to a finite Real (converting a double beyond the
/// range of float is undefined behaviour, so this is checked before any cast).
bool fits_real(double number) {
  return std::isfinite(number) && std::abs(number) <= double(std::numeric_limits<Real>::max());
}

/// The product of `counts`, or 0 when it exceeds `limit` (checked before each multiplication,
/// so nothing wraps).
std::size_t product_up_to(std::initializer_list<std::size_t> counts, std::size_t limit) {
  std::size_t product = 1;
  for (const std::size_t count : counts) {
    if (count != 0 && product > limit / count) return 0;
    product *= count;
  }
  return product;
}

/// Parses "AxBxC" (count parts) into positive integers; false on any other text.
bool parse_sizes(std::string_view text, std::size_t* sizes, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t end = i + 1 < count ? text.find('x') : text.size();
    if (end == std::string_view::npos) return false;
    const std::string_view part = text.substr(0, end);
    if (part.empty() || part.size() > 9) return false;
    const auto [next, error] = std::from_chars(part.data(), part.data() + part.size(), sizes[i]);
    if (error != std::errc() || next != part.data() + part.size()) return false;
    text.remove_prefix(std::min(text.size(), end + 1));
  }
  return true;
}

/// Reads the keys of one JSON object against `fields`; throws for an unknown key.
class ObjectReader {
 public:
  ObjectReader(const Json& object, std::string file, std::string path)
      : object_(object), file_(std::move(file)), path_(std::move(path)) {
    if (!object_.is_object()) fail(where() + " must be an object");
  }

  [[noreturn]] void fail(const std::string& problem) const {
    throw InvalidInput(file_ + ": " + problem);
  }
  std::string where() const { return path_.empty() ? "the scene" : "'" + path_ + "'"; }
  std::string key_name(const std::string& key) const {
    return "'" + (path_.empty() ? key : path_ + "." + key) + "'";
  }

  /// Throws for the first key not in `known`.
  void only(std::initializer_list<std::string_view> known) const {
    for (const auto& [key, value] : object_.items())
      if (std::find(known.begin(), known.end(), key) == known.end())
        fail("unknown key " + key_name(key));
  }
  const Json* find(const std::string& key) const {
    const auto found = object_.find(key);
    return found == object_.end() ? nullptr : &*found;
  }

  static std::string show(const Json& value) {
    std::string text = value.dump();
    if (text.size() > 40) text = text.substr(0, 37) + "...";
    return text;
  }

  void read_real(const std::string& key, Real& out, double low, bool low_inclusive,
                 double high = std::numeric_limits<double>::infinity(),
                 bool high_inclusive = false) const {
    const Json* value = find(key);
    if (!value) return;
    const auto range = [&] {
      std::ostringstream text;
      text << (low_inclusive ? "in [" : "in (") << low << ", " << high
           << (high_inclusive ? "]" : ")");
      return text.str();
    };
    if (!value->is_number()) fail(key_name(key) + " must be a number " + range() + ", not " + show(*value));
    const double number = value->get<double>();
    const bool above = low_inclusive ? number >= low : number > low;
    const bool below = high_inclusive ? number <= high : number < high;
    if (!fits_real(number) || !above || !below)
      fail(key_name(key) + " must be a number " + range() + ", not " + show(*value));
    out = static_cast<Real>(number);
  }

  void read_count(const std::string& key, std::size_t& out, std::size_t low) const {
    const Json* value = find(key);
    if (!value) return;
    const std::string need = low == 0 ? "a non-negative integer" : "a positive integer";
    if (!value->is_number_integer() || value->get<std::int64_t>() < 0)
      fail(key_name(key) + " must be " + need + ", not " + show(*value));
    const auto number = value->get<std::uint64_t>();
    if (number < low || number > std::uint64_t(1) << 31)
      fail(key_name(key) + " must be " + need + " up to 2^31, not " + show(*value));
    out = static_cast<std::size_t>(number);
  }

  /// A string that must be one of `choices`; returns its index.
  template <std::size_t N>
  bool read_choice(const std::string& key, const std::array<std::string_view, N>& choices,
                   std::size_t& out) const {
    const Json* value = find(key);
    if (!value) return false;
    std::string list;
    for (std::string_view choice : choices) list += (list.empty() ? "" : ", ") + std::string(choice);
    if (!value->is_string()) fail(key_name(key) + " must be one of " + list + ", not " + show(*value));
    const std::string text = value->get<std::string>();
    const auto found = std::find(choices.begin(), choices.end(), text);
    if (found == choices.end()) fail(key_name(key) + " must be one of " + list + ", not " + show(*value));
    out = static_cast<std::size_t>(found - choices.begin());
    return true;
  }

  bool read_string(const std::string& key, std::string& out) const {
    const Json* value = find(key);
    if (!value) return false;
    if (!value->is_string() || value->get<std::string>().empty())
      fail(key_name(key) + " must be a non-empty string, not " + show(*value));
    out = value->get<std::string>();
    return true;
  }

  const std::string& file() const { return file_; }

 private:
  const Json& object_;
  std::string file_;
  std::string path_;
};

void read_shell(const ObjectReader& scene, const Json& json, ShellOptions& shell) {
  const ObjectReader reader(json, scene.file(), "shell");
  reader.only({"material", "bending", "distance_compliance", "bending_compliance",
               "youngs_modulus", "poisson_ratio", "mass"});
  std::size_t choice = 0;
  if (reader.read_choice("material", kShellMaterialNames, choice)) shell.material = ShellMaterial(choice);
  if (reader.read_choice("bending", kShellBendingNames, choice)) shell.bending = ShellBending(choice);
  reader.read_real("distance_compliance", shell.distance_compliance, 0, true);
  reader.read_real("bending_compliance", shell.bending_compliance, 0, true);
  reader.read_real("youngs_modulus", shell.youngs_modulus, 0, false);
  reader.read_real("poisson_ratio", shell.poisson_ratio, 0, true, 0.5, false);
  reader.read_real("mass", shell.mass, 0, false);
}

void read_solid(const ObjectReader& scene, const Json& json, SolidOptions& solid) {
  const ObjectReader reader(json, scene.file(), "solid");
  reader.only({"material", "youngs_modulus", "poisson_ratio", "volume_compliance",
               "distance_compliance", "mass"});
  std::size_t choice = 0;
  if (reader.read_choice("material", kSolidMaterialNames, choice)) solid.material = SolidMaterial(choice);
  reader.read_real("youngs_modulus", solid.youngs_modulus, 0, false);
  reader.read_real("poisson_ratio", solid.poisson_ratio, 0, true, 0.5, false);
  reader.read_real("volume_compliance", solid.volume_compliance, 0, true);
  reader.read_real("distance_compliance", solid.distance_compliance, 0, true);
  reader.read_real("mass", solid.mass, 0, false);
}

/// A 3-vector key of an object: three finite numbers.
bool read_vector(const ObjectReader& reader, const std::string& key, Vector3r& out) {
  const Json* value = reader.find(key);
  if (!value) return false;
  if (!value->is_array() || value->size() != 3 ||
      !std::all_of(value->begin(), value->end(),
                   [](const Json& v) { return v.is_number() && fits_real(v.get<double>()); }))
    reader.fail(reader.key_name(key) + " must be an array of 3 finite numbers, not " +
                ObjectReader::show(*value));
  for (Eigen::Index k = 0; k < 3; ++k) out[k] = static_cast<Real>((*value)[std::size_t(k)].get<double>());
  return true;
}

ColliderDescription read_collider(const ObjectReader& scene, const Json& json, std::size_t index,
                                  const std::filesystem::path& base) {
  const ObjectReader reader(json, scene.file(), "colliders[" + std::to_string(index) + "]");
  ColliderDescription collider;
  std::size_t shape = 0;
  if (!reader.read_choice("shape", kColliderShapeNames, shape))
    reader.fail(reader.where() + " needs a 'shape' (plane, sphere, box, capsule or mesh)");
  collider.shape = ColliderShape(shape);
  const auto need = [&](bool found, const char* key) {
    if (!found) reader.fail(reader.where() + " (a " + std::string(kColliderShapeNames[shape]) +
                            ") needs '" + key + "'");
  };
  switch (collider.shape) {
    case ColliderShape::plane: {
      reader.only({"shape", "normal", "offset"});
      need(read_vector(reader, "normal", collider.normal), "normal");
      if (!(collider.normal.norm() > 0))
        reader.fail(reader.key_name("normal") + " must not be zero");
      reader.read_real("offset", collider.offset, -std::numeric_limits<double>::infinity(), false);
      break;
    }
    case ColliderShape::sphere:
      reader.only({"shape", "centre", "radius"});
      need(read_vector(reader, "centre", collider.centre), "centre");
      need(reader.find("radius") != nullptr, "radius");
      reader.read_real("radius", collider.radius, 0, false);
      break;
    case ColliderShape::box:
      reader.only({"shape", "centre", "half_extents"});
      need(read_vector(reader, "centre", collider.centre), "centre");
      need(read_vector(reader, "half_extents", collider.half_extents), "half_extents");
      if (!(collider.half_extents.minCoeff() > 0))
        reader.fail(reader.key_name("half_extents") + " must be positive");
      break;
    case ColliderShape::capsule:
      reader.only({"shape", "a", "b", "radius"});
      need(read_vector(reader, "a", collider.a), "a");
      need(read_vector(reader, "b", collider.b), "b");
      need(reader.find("radius") != nullptr, "radius");
      reader.read_real("radius", collider.radius, 0, false);
      break;
    case ColliderShape::mesh: {
      reader.only({"shape", "file"});
      std::string file;
      need(reader.read_string("file", file), "file");
      collider.mesh_file =
          std::filesystem::path(file).is_absolute() ? std::filesystem::path(file) : base / file;
      break;
    }
  }
  return collider;
}

void read_collisions(const ObjectReader& reader, const std::filesystem::path& base,
                     CollisionDescription& collisions) {
  if (const Json* colliders = reader.find("colliders")) {
    if (!colliders->is_array())
      reader.fail("'colliders' must be an array of colliders, not " + ObjectReader::show(*colliders));
    collisions.colliders.clear();
    for (std::size_t i = 0; i < colliders->size(); ++i)
      collisions.colliders.push_back(read_collider(reader, (*colliders)[i], i, base));
  }
  reader.read_real("thickness", collisions.thickness, 0, true);
  if (reader.find("friction")) {
    reader.read_real("friction", collisions.static_friction, 0, true);
    collisions.dynamic_friction = collisions.static_friction;
  }
  reader.read_real("dynamic_friction", collisions.dynamic_friction, 0, true);
  reader.read_real("restitution", collisions.restitution, 0, true, 1, true);
  if (const Json* self = reader.find("self_collision")) {
    if (!self->is_boolean())
      reader.fail("'self_collision' must be true or false, not " + ObjectReader::show(*self));
    collisions.self_collision = self->get<bool>();
  }
  reader.read_count("self_collision_interval", collisions.self_collision_interval, 1);
  if (collisions.self_collision && !(collisions.thickness > 0))
    reader.fail("'thickness' must be positive with 'self_collision' on");
}

PinRule read_pins(const ObjectReader& scene, const Json& value) {
  if (value.is_string()) {
    try {
      return parse_pin_rule(value.get<std::string>());
    } catch (const InvalidInput& error) {
      scene.fail(std::string("'pins': ") + error.what());
    }
  }
  if (value.is_array()) {
    PinRule rule;
    rule.kind = PinRule::Kind::list;
    for (std::size_t i = 0; i < value.size(); ++i) {
      const Json& entry = value[i];
      if (!entry.is_number_integer() || entry.get<std::int64_t>() < 0 ||
          entry.get<std::uint64_t>() > std::numeric_limits<VertexIndex>::max())
        scene.fail("'pins'[" + std::to_string(i) + "] must be a vertex number, not " +
                   ObjectReader::show(entry));
      rule.vertices.push_back(entry.get<VertexIndex>());
    }
    return rule;
  }
  scene.fail("'pins' must be a rule (\"default\", \"none\", \"lowest-y\", ...) or an array of "
             "vertex numbers, not " + ObjectReader::show(value));
}

SceneDescription describe(const Json& json, const std::string& name,
                          const std::filesystem::path& base) {
  const ObjectReader reader(json, name, "");
  reader.only({"name", "generator", "mesh", "pins", "tethers", "tether_compliance",
               "tether_reach_scale", "tether_attachments", "shell", "solid", "gravity", "time_step", "substeps",
               "iterations", "frames", "velocity_damping", "chebyshev", "chebyshev_rho",
               "strategy", "mode", "sequential_order", "divergence_rms", "threads",
               "colliders", "thickness", "friction", "dynamic_friction", "restitution",
               "self_collision", "self_collision_interval", "contact_scheduling"});
  const Json* generator = reader.find("generator");
  const Json* mesh = reader.find("mesh");
  if ((generator != nullptr) == (mesh != nullptr))
    reader.fail("the scene needs exactly one of 'generator' (e.g. \"cloth:128x128\") and 'mesh' (a file)");

  SceneDescription description;
  if (generator) {
    std::string spec;
    reader.read_string("generator", spec);
    const auto names = [&](const std::string& kind) {
      return spec == kind || spec.rfind(kind + ":", 0) == 0;
    };
    if (!names("cloth") && !names("bar") && !names("drape") && !names("pile"))  // never a path here
      reader.fail("'generator' must be \"cloth\", \"cloth:CxR\", \"drape:N\", \"pile:N\", \"bar\" or \"bar:XxYxZ\", not " +
                  ObjectReader::show(*generator));
    try {
      description = parse_scene_spec(spec);
    } catch (const InvalidInput& error) {
      reader.fail(std::string("'generator': ") + error.what());
    }
  } else {
    std::string file;
    reader.read_string("mesh", file);
    description.source = SceneSource::mesh;
    description.mesh_file = std::filesystem::path(file).is_absolute() ? std::filesystem::path(file)
                                                                     : base / file;
    description.name = file;
  }
  reader.read_string("name", description.name);
  if (const Json* pins = reader.find("pins")) description.pins = read_pins(reader, *pins);
  std::size_t tethers = 0;
  if (reader.read_choice("tethers", kTetherRuleNames, tethers))
    description.tethers = TetherRule(tethers);
  reader.read_real("tether_compliance", description.tether_compliance, 0, true);
  reader.read_real("tether_reach_scale", description.tether_reach_scale, 1, true);
  reader.read_count("tether_attachments", description.tether_attachments, 1);
  if (const Json* shell = reader.find("shell")) read_shell(reader, *shell, description.shell);
  read_collisions(reader, base, description.collisions);
  if (const Json* solid = reader.find("solid")) read_solid(reader, *solid, description.solid);

  SimulationSettings& simulation = description.simulation;
  if (const Json* gravity = reader.find("gravity")) {
    if (!gravity->is_array() || gravity->size() != 3 ||
        !std::all_of(gravity->begin(), gravity->end(), [](const Json& g) {
          return g.is_number() && fits_real(g.get<double>());
        }))
      reader.fail("'gravity' must be an array of 3 finite numbers, not " + ObjectReader::show(*gravity));
    for (Eigen::Index k = 0; k < 3; ++k)
      simulation.gravity[k] = static_cast<Real>((*gravity)[std::size_t(k)].get<double>());
  }
  reader.read_real("time_step", simulation.time_step, 0, false);
  reader.read_count("substeps", simulation.substeps, 1);
  reader.read_count("iterations", simulation.iterations, 1);
  reader.read_count("frames", simulation.frames, 0);
  reader.read_real("velocity_damping", simulation.velocity_damping, 0, true);
  if (const Json* chebyshev = reader.find("chebyshev")) {
    if (!chebyshev->is_boolean())
      reader.fail("'chebyshev' must be true or false, not " + ObjectReader::show(*chebyshev));
    simulation.chebyshev = chebyshev->get<bool>();
  }
  if (reader.find("chebyshev_rho")) {
    Real rho = 0;
    reader.read_real("chebyshev_rho", rho, 0, false, 1, false);
    simulation.chebyshev_rho = rho;
  }
  reader.read_string("strategy", simulation.strategy);
  reader.read_string("mode", simulation.mode);
  reader.read_string("sequential_order", simulation.sequential_order);
  if (std::string scheduling; reader.read_string("contact_scheduling", scheduling))
    simulation.contact_scheduling = scheduling;
  reader.read_real("divergence_rms", simulation.divergence_rms, 0, false);
  reader.read_count("threads", simulation.threads, 0);
  return description;
}

}  // namespace

PinRule parse_pin_rule(std::string_view text) {
  PinRule rule;
  if (text == "default") return rule;
  if (text == "none") {
    rule.kind = PinRule::Kind::none;
    return rule;
  }
  for (const auto& [prefix, kind] : {std::pair{std::string_view("lowest-"), PinRule::Kind::lowest},
                                     std::pair{std::string_view("highest-"), PinRule::Kind::highest}})
    if (text.size() == prefix.size() + 1 && text.substr(0, prefix.size()) == prefix &&
        kAxes.find(text.back()) != std::string_view::npos) {
      rule.kind = kind;
      rule.axis = kAxes.find(text.back());
      return rule;
    }
  throw InvalidInput("unknown pin rule '" + std::string(text) +
                     "' (known: default, none, lowest-x, lowest-y, lowest-z, highest-x, "
                     "highest-y, highest-z)");
}

std::string describe_pin_rule(const PinRule& rule) {
  switch (rule.kind) {
    case PinRule::Kind::scene_default: return "default";
    case PinRule::Kind::none: return "none";
    case PinRule::Kind::lowest: return std::string("lowest-") + kAxes[rule.axis];
    case PinRule::Kind::highest: return std::string("highest-") + kAxes[rule.axis];
    case PinRule::Kind::list: return "list of " + std::to_string(rule.vertices.size()) + " vertices";
  }
  return {};
}

namespace {

void make_drape(SceneDescription& description, std::size_t vertices) {
  description.source = SceneSource::cloth;
  description.cloth_columns = description.cloth_rows = vertices;
  description.pins.kind = PinRule::Kind::none;
  // The cloth spans [0, 1]² at y = 0; the sphere's top is 0.1 m below its centre.
  CollisionDescription& collisions = description.collisions;
  ColliderDescription sphere;
  sphere.shape = ColliderShape::sphere;
  sphere.centre = Vector3r(Real(0.5), Real(-0.35), Real(0.5));
  sphere.radius = Real(0.25);
  ColliderDescription ground;
  ground.shape = ColliderShape::plane;
  ground.normal = Vector3r(0, 1, 0);
  ground.offset = Real(-0.6);
  collisions.colliders = {sphere, ground};
  collisions.self_collision = true;
  // Below half the grid spacing, so the flat cloth's own neighbours are never in contact.
  collisions.thickness = std::min(Real(0.005), Real(0.4) / Real(vertices - 1));
  description.simulation.frames = 120;
}

/// Blocks dropped crosswise onto the ground, with self-collision: their vertex–face contacts
/// are particle–tet contacts (solid_contacts.hpp).
void make_pile(SceneDescription& description, std::size_t bodies) {
  description.source = SceneSource::pile;
  description.pile_bodies = bodies;
  description.pins.kind = PinRule::Kind::none;
  CollisionDescription& collisions = description.collisions;
  ColliderDescription ground;
  ground.shape = ColliderShape::plane;
  ground.normal = Vector3r(0, 1, 0);
  ground.offset = 0;
  collisions.colliders = {ground};
  collisions.self_collision = true;
  description.simulation.frames = 90;
}

}  // namespace

SceneDescription parse_scene_spec(std::string_view spec) {
  const auto fail = [&](const std::string& problem) -> SceneDescription {
    throw InvalidInput("scene '" + std::string(spec) + "': " + problem);
  };
  SceneDescription description;
  description.name = std::string(spec);
  const auto generator = [&](std::string_view name) {
    return spec == name || (spec.size() > name.size() && spec.substr(0, name.size()) == name &&
                            spec[name.size()] == ':');
  };
  if (generator("cloth")) {
    description.source = SceneSource::cloth;
    description.simulation.substeps = kClothSubsteps;
    if (spec.size() > 5) {
      std::string_view sizes = spec.substr(6);
      // "cloth:CxR:alternating": the chequerboard diagonals (DiagonalPattern::alternating).
      constexpr std::string_view kAlternating = ":alternating";
      if (sizes.size() > kAlternating.size() &&
          sizes.substr(sizes.size() - kAlternating.size()) == kAlternating) {
        sizes.remove_suffix(kAlternating.size());
        description.cloth_diagonals = DiagonalPattern::alternating;
      }
      std::size_t both[2] = {0, 0};
      if (parse_sizes(sizes, both, 2)) {
      } else if (parse_sizes(sizes, both, 1)) {
        both[1] = both[0];
      } else {
        return fail("expected cloth:N or cloth:CxR with vertex counts, e.g. cloth:256x256");
      }
      if (both[0] < 2 || both[1] < 2) return fail("a cloth needs at least 2 vertices per side");
      if (product_up_to({both[0], both[1]}, std::size_t(1) << 31) == 0)
        return fail("more than 2^31 vertices");
      description.cloth_columns = both[0];
      description.cloth_rows = both[1];
    }
    return description;
  }
  if (generator("drape")) {
    // A square cloth falling flat onto a sphere and the ground, against itself too.
    std::size_t n[1] = {kDrapeVertices};
    if (spec.size() > 5 && !parse_sizes(spec.substr(6), n, 1))
      return fail("expected drape or drape:N with a vertex count per side, e.g. drape:128");
    if (n[0] < 2) return fail("a cloth needs at least 2 vertices per side");
    if (product_up_to({n[0], n[0]}, std::size_t(1) << 31) == 0) return fail("more than 2^31 vertices");
    make_drape(description, n[0]);
    return description;
  }
  if (generator("pile")) {
    std::size_t n[1] = {kPileBodies};
    if (spec.size() > 4 && !parse_sizes(spec.substr(5), n, 1))
      return fail("expected pile or pile:N with a number of blocks, e.g. pile:8");
    if (n[0] < 1) return fail("a pile needs at least 1 block");
    if (n[0] > kMaxPileBodies) return fail("at most " + std::to_string(kMaxPileBodies) + " blocks");
    make_pile(description, n[0]);
    return description;
  }
  if (generator("bar")) {
    description.source = SceneSource::bar;
    if (spec.size() > 3) {
      std::size_t cells[3] = {0, 0, 0};
      if (!parse_sizes(spec.substr(4), cells, 3))
        return fail("expected bar:XxYxZ with cell counts, e.g. bar:10x10x80");
      if (cells[0] < 1 || cells[1] < 1 || cells[2] < 1) return fail("a bar needs at least 1 cell per side");
      if (product_up_to({cells[0] + 1, cells[1] + 1, cells[2] + 1}, std::size_t(1) << 31) == 0)
        return fail("more than 2^31 vertices");
      description.bar_cells = {cells[0], cells[1], cells[2]};
    }
    return description;
  }
  if (spec.empty()) return fail("empty");
  const std::filesystem::path path{std::string(spec)};
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (extension == ".json") return read_scene_file(path);
  description.source = SceneSource::mesh;
  description.mesh_file = path;
  return description;
}

SceneDescription read_scene_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InvalidInput(file.string() + ": cannot open the scene file");
  SceneDescription description = parse_scene_json(in, file.string(), file.parent_path());
  if (description.name.empty()) description.name = file.string();
  return description;
}

SceneDescription parse_scene_json(std::istream& in, const std::string& name,
                                  const std::filesystem::path& base) {
  Json json;
  try {
    json = Json::parse(in, nullptr, /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const Json::exception& error) {
    // "[json.exception.parse_error.101] parse error at line 3, column 14: syntax error ...",
    // "[json.exception.out_of_range.406] number overflow parsing '1e400'"
    std::string message = error.what();
    const std::size_t at = message.find(" at line ");
    if (at != std::string::npos) {
      message = message.substr(at + 4);
    } else if (const std::size_t bracket = message.find("] "); bracket != std::string::npos) {
      message = message.substr(bracket + 2);
    }
    std::replace(message.begin(), message.end(), '\n', ' ');
    throw InvalidInput(name + ": " + message);
  }
  try {
    return describe(json, name, base);
  } catch (const Json::exception& error) {  // every value's type is checked first: a safety net
    throw InvalidInput(name + ": " + error.what());
  }
}

}  // namespace tessera::io
