"""tessera.Model from NumPy arrays: every family builds, arrays round-trip, bad input is a
ValueError with Tessera's message."""
import numpy as np
import pytest

import tessera

# A non-flat tetrahedron and a fifth point off its faces: every family's first constraint is
# non-degenerate on these.
POINTS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=np.float64)
MASSES = np.array([1.0, 1.0, 0.5, 2.0, 0.0])
STENCIL = {2: [[0, 1], [1, 2]], 3: [[0, 1, 2], [1, 2, 3]], 4: [[0, 1, 2, 3], [1, 2, 3, 4]]}


def test_particles_round_trip_in_the_real_dtype():
    model = tessera.Model(POINTS, MASSES)
    assert model.particle_count == 5 and model.constraint_count == 0
    assert model.positions.dtype == tessera.real_dtype
    np.testing.assert_array_equal(model.positions, POINTS.astype(tessera.real_dtype))
    np.testing.assert_array_equal(model.inverse_masses, MASSES.astype(tessera.real_dtype))


def test_every_family_builds_from_arrays_and_its_arrays_round_trip():
    names = [f["name"] for f in tessera.families()]
    assert names[:2] == ["distance", "dihedral"] and "shape_matching" in names
    model = tessera.Model(POINTS, MASSES)
    for family in tessera.families():
        name, arity = family["name"], family["arity"]
        if not family["settable"]:  # contacts: made by collision detection
            with pytest.raises(ValueError, match="made by collision detection"):
                model.set_constraints(name, [0, 1, 2, 3, 4])
            continue
        if arity == 0:  # clusters: offsets + flat particles
            model.set_constraints(name, [0, 1, 2, 3, 1, 2, 3, 4], offsets=[0, 4, 8],
                                  stiffness=[0.25, 0.5])
            arrays = model.constraints(name)
            np.testing.assert_array_equal(arrays["offsets"], [0, 4, 8])
            np.testing.assert_array_equal(arrays["particles"], [0, 1, 2, 3, 1, 2, 3, 4])
            np.testing.assert_array_equal(arrays["stiffness"], np.float32([0.25, 0.5]))
            continue
        particles = np.array(STENCIL[arity], dtype=np.int64)
        # Every per-constraint parameter gets its own values, so a mix-up would show.
        per_constraint = [p for p, kind in family["parameters"].items() if "array" in kind]
        values = {p: np.array([0.1 + i, 0.2 + i]) / 10 for i, p in enumerate(per_constraint)}
        model.set_constraints(name, particles, **values)
        arrays = model.constraints(name)
        np.testing.assert_array_equal(arrays["particles"], particles)
        assert arrays["particles"].dtype == np.uint32
        for p, v in values.items():
            np.testing.assert_array_equal(arrays[p], v.astype(tessera.real_dtype), err_msg=p)
    counts = model.constraint_counts
    settable = [f["name"] for f in tessera.families() if f["settable"]]
    assert list(counts) == settable and all(c == 2 for c in counts.values())
    assert model.constraint_count == 2 * len(settable)
    assert f"{2 * len(settable)} constraints" in repr(model)


def test_scalar_parameters_and_switches_reach_the_batch():
    model = tessera.Model(POINTS, MASSES)
    model.set_constraints("fem_tetra", [[0, 1, 2, 3]], youngs_modulus=5e3, poisson_ratio=0.25,
                          handle_inversion=False)
    arrays = model.constraints("fem_tetra")
    assert arrays["youngs_modulus"][0] == 5e3 and arrays["poisson_ratio"][0] == np.float32(0.25)
    assert arrays["handle_inversion"] is False
    model.set_constraints("distance", [[0, 1]], compliance=1e-4)
    assert model.constraints("distance")["compliance"][0] == np.float32(1e-4)


def test_rest_positions_default_to_the_model_and_can_be_given():
    model = tessera.Model(POINTS, MASSES)
    model.set_constraints("distance", [[0, 1]])
    rest = POINTS.copy()
    rest[1] = [3, 0, 0]
    other = tessera.Model(POINTS, MASSES)
    other.set_constraints("distance", [[0, 1]], rest_positions=rest)
    graph_a = tessera.Solver(model, mode="sequential", gravity=(0, 0, 0))
    graph_b = tessera.Solver(other, mode="sequential", gravity=(0, 0, 0))
    assert graph_a.residual()["max"] == 0
    assert graph_b.residual()["max"] == pytest.approx(2 / 3)  # |1 - 3| / 3


@pytest.mark.parametrize("call, message", [
    (lambda m: m.set_constraints("distance", [[0, 5]]),
     "distance constraint 0: particle index 5 is out of range (5 particles)"),
    (lambda m: m.set_constraints("volume", [[0, 1, 1, 2]]),
     "volume constraint 0: particle 1 appears twice"),
    (lambda m: m.set_constraints("distance", [[0, 1]], stiffness=-0.5),
     "distance constraints: stiffness is -0.5, must be finite and ≥ 0"),
    (lambda m: m.set_constraints("distance", [[0, 1], [1, 2]], compliance=[0.0, np.nan]),
     "distance constraints: compliance is nan, must be finite and ≥ 0 (compliance[1])"),
    (lambda m: m.set_constraints("distance", [[0, 1], [1, 2]], compliance=[0.0]),
     "distance compliance must have 2 values, not 1"),
    (lambda m: m.set_constraints("fem_tetra", [[0, 1, 2, 3]], youngs_modulus=[1.0]),
     "FEM tetra constraints: youngs_modulus takes one number for all constraints, not an array"),
    (lambda m: m.set_constraints("distance", [[0, 1]], stifness=1),
     "distance constraints: unknown parameter 'stifness' (known: stiffness, compliance)"),
    (lambda m: m.set_constraints("fem_tetra", [[0, 1, 2, 3]], handle_inversion=1),
     "FEM tetra constraints: handle_inversion must be True or False"),
    (lambda m: m.set_constraints("distance", [[0, 1, 2]]),
     "distance particles must have shape (M, 2), not (1, 3)"),
    (lambda m: m.set_constraints("distance", [[0, -1]]),
     "distance particles: index -1 at position 1 is not in [0, 2^32)"),
    (lambda m: m.set_constraints("distance", [[0.0, 1.0]]),
     "distance particles must be integers, not float64"),
    (lambda m: m.set_constraints("shape_matching", [0, 1, 2]),
     "shape matching constraints: clusters need offsets= (count + 1 entry offsets into particles)"),
    (lambda m: m.set_constraints("bending", [[0, 1]]),
     "unknown constraint family 'bending' (known: " +
     ", ".join(f["name"] for f in tessera.families()) + ")"),
])
def test_bad_constraint_input_is_a_value_error_with_the_message(call, message):
    model = tessera.Model(POINTS, MASSES)
    with pytest.raises(ValueError) as error:
        call(model)
    assert str(error.value) == message


def test_bad_particles_are_value_errors_with_the_message():
    with pytest.raises(ValueError, match=r"^particles: 5 positions but 3 inverse masses$"):
        tessera.Model(POINTS, MASSES[:3])
    bad = POINTS.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match=r"^particle 2: position is not finite$"):
        tessera.Model(bad, MASSES)
    with pytest.raises(ValueError, match=r"^positions must have shape \(N, 3\), not \(5, 2\)$"):
        tessera.Model(POINTS[:, :2], MASSES)


def test_scenes_meshes_and_files():
    cloth = tessera.scene("cloth:8")
    # 161 edges, 28 on the boundary; two tethers from each of the 62 movable particles, one
    # to each pin
    assert cloth.model.constraint_counts == {"distance": 161, "dihedral": 133, "tether": 124}
    assert list(cloth.pinned) == [56, 63]
    np.testing.assert_array_equal(cloth.model.inverse_masses[cloth.pinned], [0, 0])
    assert cloth.solver_settings()["substeps"] == 160  # the cloth scenes' (kClothSubsteps)
    curtain = tessera.read_scene(tessera_source("examples/scenes/curtain.json"))
    assert curtain.name == "curtain" and curtain.simulation["frames"] == 150
    mesh = tessera.read_mesh(tessera_source("tests/io/data/cube.node"))
    assert mesh.tetrahedra.shape[1] == 4 and mesh.positions.shape[1] == 3
    model = mesh.to_model(pinned=[0])
    assert model.inverse_masses[0] == 0 and "fem_tetra" in model.constraint_counts
    with pytest.raises(ValueError, match=r"^scene 'cloth:1x5'"):
        tessera.scene("cloth:1x5")


def tessera_source(relative):
    from conftest import SOURCE_DIR
    return str(SOURCE_DIR / relative)
