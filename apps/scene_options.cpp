// The scene options shared by `run` and `color` (see scene_options.hpp): the material and pin
// overrides are checked against io's own name tables before the scene spec is parsed, so a
// typo is reported before any file is read; they then overwrite the parsed description
// field by field.
#include "scene_options.hpp"

#include <array>
#include <string_view>

#include <tessera/core/error.hpp>

#include "option_checks.hpp"

namespace tessera::cli {
namespace {

template <class Enum, std::size_t N>
Enum choose(const std::string& option, const std::string& value,
            const std::array<std::string_view, N>& names) {
  for (std::size_t i = 0; i < N; ++i)
    if (names[i] == value) return Enum(i);
  std::string known;
  for (std::string_view name : names) known += (known.empty() ? "" : ", ") + std::string(name);
  throw InvalidInput(option + ": unknown value '" + value + "' (known: " + known + ")");
}

/// choose() of an option given, nothing of one left out.
template <class Enum, std::size_t N>
std::optional<Enum> choose_if_given(const std::string& option,
                                    const std::optional<std::string>& value,
                                    const std::array<std::string_view, N>& names) {
  std::optional<Enum> chosen;
  if (value) chosen.emplace(choose<Enum>(option, *value, names));
  return chosen;
}

}  // namespace

void add_scene_options(CLI::App& command, SceneOptions& options) {
  command.add_option("scene", options.scene,
                     "cloth, cloth:N, cloth:CxR (vertices), drape, drape:N (a cloth falling "
                     "onto a sphere), pile, pile:N (FEM blocks falling onto each other), bar, bar:XxYxZ (cells), a mesh file (.obj, .node/.ele, "
                     ".msh) or a scene file (.json)")
      ->capture_default_str();
  command.add_option("--shell-material", options.shell_material,
                     "triangle meshes: distance, strain_triangle or fem_triangle");
  command.add_option("--bending", options.bending,
                     "triangle meshes: dihedral, isometric or none");
  command.add_option("--solid-material", options.solid_material,
                     "tetrahedral meshes: fem_tetra, strain_tetra or volume_and_distance");
  command.add_option("--pins", options.pins,
                     "default, none, lowest-x|y|z or highest-x|y|z");
  command.add_option("--tethers", options.tethers,
                     "auto (default: every movable particle tethered to its nearest pins along "
                     "the mesh) or none");
  command.add_option("--tether-attachments", options.tether_attachments,
                     "tethers auto: how many pins each particle is tethered to, the nearest along "
                     "the mesh first (default 2)")
      ->check(integer_from(1, std::size_t(1) << 20));
  command.add_option("--self-collision", options.self_collision,
                     "on or off: the surface's contacts with itself (default: the scene's)");
  command.add_option("--thickness", options.thickness,
                     "contact distance in metres (default: the scene's, 0.005)")
      ->check(finite_number_above(0, true, "metres"));
  command.add_option("--friction", options.friction,
                     "friction coefficient against colliders, static and dynamic (default: the "
                     "scene's, 0.4 and 0.3)")
      ->check(finite_number_above(0, true, ""));
}

io::SceneDescription describe_scene(const SceneOptions& options) {
  // The cheap checks of the overrides first, so a typo is reported before a big scene loads.
  const auto shell_material = choose_if_given<io::ShellMaterial>(
      "--shell-material", options.shell_material, io::kShellMaterialNames);
  const auto bending =
      choose_if_given<io::ShellBending>("--bending", options.bending, io::kShellBendingNames);
  const auto solid_material = choose_if_given<io::SolidMaterial>(
      "--solid-material", options.solid_material, io::kSolidMaterialNames);
  const auto tethers =
      choose_if_given<io::TetherRule>("--tethers", options.tethers, io::kTetherRuleNames);
  if (options.self_collision && *options.self_collision != "on" && *options.self_collision != "off")
    throw InvalidInput("--self-collision: unknown value '" + *options.self_collision +
                       "' (known: on, off)");
  std::optional<io::PinRule> pins;
  if (options.pins) {
    try {
      pins = io::parse_pin_rule(*options.pins);
    } catch (const InvalidInput& error) {
      throw InvalidInput(std::string("--pins: ") + error.what());
    }
  }
  io::SceneDescription description = io::parse_scene_spec(options.scene);
  if (shell_material) description.shell.material = *shell_material;
  if (bending) description.shell.bending = *bending;
  if (solid_material) description.solid.material = *solid_material;
  if (pins) description.pins = *pins;
  if (tethers) description.tethers = *tethers;
  if (options.tether_attachments) description.tether_attachments = *options.tether_attachments;
  io::CollisionDescription& collisions = description.collisions;
  if (options.self_collision) collisions.self_collision = *options.self_collision == "on";
  if (options.thickness) collisions.thickness = Real(*options.thickness);
  if (options.friction) collisions.static_friction = collisions.dynamic_friction = Real(*options.friction);
  if (collisions.self_collision && !(collisions.thickness > 0))
    throw InvalidInput("--thickness: must be positive with self-collision on");
  return description;
}

}  // namespace tessera::cli
