// The options `run` and `color` share: which scene, and the material and pin choices that
// override the scene's own. Parsed by CLI11 into SceneOptions, turned into a
// SceneDescription by describe_scene() (which also checks the choices).
#pragma once

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include <tessera/io/scene_file.hpp>

namespace tessera::cli {

/// The scene `run` and `color` take when none is named.
inline constexpr const char* kDefaultScene = "cloth:256x256";

struct SceneOptions {
  std::string scene = kDefaultScene;
  std::optional<std::string> shell_material;
  std::optional<std::string> bending;
  std::optional<std::string> solid_material;
  std::optional<std::string> pins;
  std::optional<std::string> tethers;
  std::optional<std::size_t> tether_attachments;
  std::optional<std::string> self_collision;
  std::optional<double> thickness;
  std::optional<double> friction;
};

/// Adds SCENE and --shell-material, --bending, --solid-material, --pins, --tethers,
/// --tether-attachments,
/// --self-collision, --thickness, --friction to `command`.
void add_scene_options(CLI::App& command, SceneOptions& options);

/// The scene named by the options, the overrides applied. Throws InvalidInput.
io::SceneDescription describe_scene(const SceneOptions& options);

}  // namespace tessera::cli
