// Fuzzes the JSON scene-file reader (parse_scene_json) with arbitrary bytes, and builds the
// scenes it accepts when they are generated and small (a fuzzed "cloth:30000x30000" would only
// measure the allocator; mesh paths are not opened, so the run does not depend on the disk).
// InvalidInput is the expected answer to bad input; a crash, a sanitizer report, a hang or a
// scene that violates its description is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include <tessera/core/error.hpp>
#include <tessera/io/scene_file.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace tessera::io;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const SceneDescription description = parse_scene_json(in, "fuzz.json", "/nonexistent");
    const auto& cells = description.bar_cells;
    const bool small =
        (description.source == SceneSource::cloth &&
         description.cloth_columns * description.cloth_rows <= 4096) ||
        (description.source == SceneSource::bar && cells[0] * cells[1] * cells[2] <= 256);
    if (!small) return 0;
    const Scene scene = build_scene(description);
    if (scene.model.particles.size() != scene.mesh.positions.size()) std::abort();
    for (const VertexIndex pinned : scene.pinned)
      if (pinned >= scene.mesh.positions.size() || scene.model.particles.inverse_mass[pinned] != 0)
        std::abort();
  } catch (const tessera::InvalidInput&) {
  }
  return 0;
}
