"""tessera.Solver's collision stage from Python: a scene's contacts solve bitwise as the tool
solves them, colliders given as dicts hold a falling cloth up, the checks the run summary
reports (penetration, self-intersections) give known answers, and bad colliders are errors."""
import re

import numpy as np
import pytest

import tessera


@pytest.mark.parametrize("spec", ["pile:2", "drape:8"])
def test_a_scene_with_contacts_solves_bitwise_as_the_tool(tool, spec):
    expected = tool("run", spec, "--frames", "60", "--strategy", "greedy")
    scene = tessera.scene(spec)
    settings = scene.collision_settings()
    assert settings is not None and settings["self_collision"]
    solver = tessera.Solver(scene.model, tessera.colour(scene.model, "greedy", locality=True),
                            **scene.solver_settings())
    solver.set_collisions(**settings)
    solver.step(60)
    assert solver.state_hash() == expected["state_hash"]
    found = solver.collision_statistics
    assert found["contacts_max"] == expected["contacts_max"]
    assert found["contacts_mean"] == pytest.approx(expected["contacts_mean"])
    assert found["seconds_self_collision_built"] > 0  # the first substep builds
    assert (found["seconds_self_collision_built"] + found["seconds_self_collision_reboxed"] +
            found["seconds_self_collision_refined"]) <= found["seconds_detection"]
    positions = solver.positions
    assert tessera.penetration_depth(positions, settings["colliders"],
                                     settings.get("tetrahedra")) == pytest.approx(
                                         expected["penetration_max"], abs=1e-7)
    assert tessera.self_intersections(positions, settings["surface_triangles"]) == 0
    counts = solver.contact_counts()
    assert counts.shape == (scene.model.particle_count,) and counts.sum() > 0


def test_colliders_as_dicts_hold_a_falling_cloth_up():
    scene = tessera.scene("cloth:12")
    model = tessera.Model(scene.model.positions, np.ones(scene.model.particle_count))
    edges = scene.model.constraints("distance")["particles"]
    model.set_constraints("distance", edges)
    lowest = float(scene.model.positions[:, 1].min())
    colliders = [{"shape": "plane", "normal": (0, 2, 0), "offset": 2 * (lowest - 0.3)},
                 {"shape": "sphere", "centre": (0.5, lowest - 0.2, 0.5), "radius": 0.1},
                 {"shape": "box", "centre": (5, 0, 5), "half_extents": (0.1, 0.1, 0.1)},
                 {"shape": "capsule", "a": (5, 0, 0), "b": (6, 0, 0), "radius": 0.1},
                 {"shape": "mesh", "positions": [(9, 0, 9), (10, 0, 9), (9, 0, 10)],
                  "triangles": [(0, 1, 2)]}]
    results = []
    for threads in (1, 2):
        solver = tessera.Solver(model, tessera.colour(model), threads=threads, substeps=8,
                                iterations=1)
        solver.set_collisions(colliders, thickness=0.005)
        solver.step(60)
        positions = solver.positions
        assert tessera.penetration_depth(positions, colliders) <= 0.005
        assert positions[:, 1].min() > lowest - 0.3
        assert solver.collision_statistics["collider_contacts"] > 0
        results.append(solver.state_hash())
    assert results[0] == results[1]
    # Without the stage the cloth falls through the plane.
    solver.clear_collisions()
    assert solver.collision_statistics is None
    solver.step(60)
    assert solver.positions[:, 1].min() < lowest - 0.3


def test_the_checks_give_known_answers():
    below = np.array([[0.0, -0.1, 0.0], [0.0, 1.0, 0.0]])
    assert tessera.penetration_depth(below, [{"shape": "plane", "normal": (0, 1, 0), "offset": 0}]) == \
        pytest.approx(0.1)
    assert tessera.penetration_depth(below) == 0
    # Two triangles crossing through each other, and the same two apart.
    crossing = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0],
                         [0.2, 0.2, -0.5], [0.2, 0.2, 0.5], [0.3, 0.3, 0.5]], dtype=float)
    triangles = [(0, 1, 2), (3, 4, 5)]
    assert tessera.self_intersections(crossing, triangles) == 1
    apart = crossing + np.array([[0, 0, 0]] * 3 + [[5, 0, 0]] * 3)
    assert tessera.self_intersections(apart, triangles) == 0


def test_bad_collisions_are_value_errors_that_say_what_is_wrong():
    scene = tessera.scene("cloth:4")
    solver = tessera.Solver(scene.model, tessera.colour(scene.model))
    cases = [
        (([{"shape": "cone"}],), {}, "colliders[0]: unknown shape 'cone'"),
        (([{"shape": "sphere", "centre": (0, 0, 0)}],), {}, "colliders[0]: missing 'radius'"),
        (([{"shape": "sphere", "centre": (0, 0, 0), "radius": -1}],), {}, "radius"),
        (([],), {"thickness": -1.0}, "thickness"),
        (([],), {"friction": -0.5}, "friction"),
        (([],), {"self_collision": True}, "self_collision needs surface_triangles"),
        (([],), {"surface_triangles": [(0, 1, 99)], "self_collision": True}, "names particle 99"),
        (([{"shape": "mesh", "positions": [(0, 0, 0)], "triangles": [(0, 1, 2)]}],), {},
         "mesh collider"),
    ]
    for arguments, keywords, message in cases:
        with pytest.raises(ValueError, match=re.escape(message)):
            solver.set_collisions(*arguments, **keywords)
    with pytest.raises(ValueError, match="unknown contact scheduling 'graph'"):
        tessera.Solver(scene.model, tessera.colour(scene.model), contact_scheduling="graph")
