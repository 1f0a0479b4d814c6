// SolverSettings::particle_layout: the sweeps in the interleaved layout (x, y, z, w per
// particle, batch-inl.h's register transpose) give bitwise the state the separate arrays give,
// for every family, every mode and every SIMD target, and the layout is what the sweeps see.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include <tessera/core/shape_matching_constraints.hpp>
#include <tessera/io/scene_description.hpp>
#include <tessera/io/scene_file.hpp>
#include <tessera/parallel/solver.hpp>

#include "batch_test_support.hpp"
#include "scenes.hpp"

namespace tessera {
namespace particle_layout_tests {

Model scene_model(const std::string& spec, const std::string& material) {
  io::SceneDescription description = io::parse_scene_spec(spec);
  if (material == "isometric") description.shell.bending = io::ShellBending::isometric;
  if (material == "strain_triangle") description.shell.material = io::ShellMaterial::strain_triangle;
  if (material == "fem_triangle") description.shell.material = io::ShellMaterial::fem_triangle;
  if (material == "strain_tetra") description.solid.material = io::SolidMaterial::strain_tetra;
  if (material == "volume_and_distance")
    description.solid.material = io::SolidMaterial::volume_and_distance;
  io::Scene scene = io::build_scene(description);
  if (material == "shape_matching") {  // a cluster per tetrahedron, on top of the FEM bar
    std::vector<std::uint32_t> offsets = {0};
    std::vector<ParticleIndex> particles;
    for (const auto v : scene.mesh.tetrahedra) {
      particles.push_back(ParticleIndex(v));
      if (particles.size() % 4 == 0) offsets.push_back(std::uint32_t(particles.size()));
    }
    std::vector<Real> inverse_masses(scene.model.particles.inverse_mass.begin(),
                                     scene.model.particles.inverse_mass.begin() +
                                         std::ptrdiff_t(scene.model.particles.size()));
    ShapeMatchingInput input;
    input.offsets = offsets;
    input.particles = particles;
    input.rest_positions = scene.mesh.positions;
    input.inverse_masses = inverse_masses;
    input.stiffness = Real(0.5);
    scene.model.constraints.shape_matching = make_shape_matching_constraints(input);
  }
  return std::move(scene.model);
}

/// Positions and velocities after three steps of a model stretched by gravity.
std::pair<std::vector<Vector3r>, std::vector<Vector3r>> three_steps(const Model& model,
                                                                    SolverMode mode,
                                                                    ParticleLayout layout) {
  SolverSettings settings;
  settings.mode = mode;
  settings.threads = 2;
  settings.substeps = 4;
  settings.iterations = 2;
  settings.particle_layout = layout;
  Solver solver = test::make_solver(model, settings, "stencil");
  for (int step = 0; step < 3; ++step) solver.step();
  return {solver.positions(), solver.velocities()};
}

TEST(ParticleLayout, EveryFamilyModeAndTargetGivesTheSameBitsInBothLayouts) {
  const std::vector<std::pair<std::string, std::string>> scenes = {
      {"cloth:12x10", "distance"},         {"cloth:12x10", "isometric"},
      {"cloth:12x10", "strain_triangle"},  {"cloth:12x10", "fem_triangle"},
      {"bar:2x2x5", "fem_tetra"},          {"bar:2x2x5", "strain_tetra"},
      {"bar:2x2x5", "volume_and_distance"}, {"bar:2x2x5", "shape_matching"}};
  test::for_each_simd_target([&](const std::string&) {
    for (const auto& [spec, material] : scenes) {
      const Model model = scene_model(spec, material);
      for (const SolverMode mode : test::kSolverModes) {
        SCOPED_TRACE(spec + " " + material + ", mode " + test::mode_name(mode));
        const auto separate = three_steps(model, mode, ParticleLayout::separate);
        const auto interleaved = three_steps(model, mode, ParticleLayout::interleaved);
        EXPECT_TRUE(test::same_bits(separate.first, interleaved.first));
        EXPECT_TRUE(test::same_bits(separate.second, interleaved.second));
        std::vector<Vector3r> start;
        for (std::size_t i = 0; i < model.particles.size(); ++i)
          start.push_back(model.particles.position(i));
        EXPECT_FALSE(test::same_bits(start, separate.first)) << "the scene moves";
      }
    }
  });
}

TEST(ParticleLayout, TheSweepsSeeTheChosenLayoutAndTheStateIsSeparateAfterwards) {
  const Model cloth = scene_model("cloth:8x8", "distance");
  for (const ParticleLayout layout : {ParticleLayout::separate, ParticleLayout::interleaved}) {
    SolverSettings settings;
    settings.mode = SolverMode::gs;
    settings.particle_layout = layout;
    Solver solver = test::make_solver(cloth, settings, "stencil");
    std::size_t stride = 0;
    solver.set_phase_hook([&](std::size_t phase, ParticleArrays particles) {
      if (phase != Solver::kBeforePhases) return;
      stride = particles.stride;
      if (particles.interleaved()) {  // x, y, z, w of a particle side by side
        EXPECT_EQ(particles.y, particles.x + 1);
        EXPECT_EQ(particles.inverse_mass, particles.x + 3);
      }
    });
    solver.step();
    EXPECT_EQ(stride, layout == ParticleLayout::interleaved ? 4u : 1u);
    EXPECT_EQ(solver.scheduled_state().x.size(), padded_size(cloth.particles.size()));
  }
}

TEST(ParticleLayout, ANamedLayoutParsesAndAnUnknownOneIsNamed) {
  EXPECT_EQ(parse_particle_layout("separate"), ParticleLayout::separate);
  EXPECT_EQ(parse_particle_layout("interleaved"), ParticleLayout::interleaved);
  EXPECT_EQ(particle_layout_name(ParticleLayout::interleaved), "interleaved");
  try {
    parse_particle_layout("aos");
    FAIL() << "no error";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("aos"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("interleaved"), std::string::npos) << e.what();
  }
}

}  // namespace particle_layout_tests
}  // namespace tessera
