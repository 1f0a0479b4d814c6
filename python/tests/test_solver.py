"""tessera.Solver: bitwise the tool's solve (state hash), copies and views of the state,
errors with their messages, and the GIL released while it steps."""
import threading
import time

import numpy as np
import pytest

import tessera


@pytest.mark.parametrize("mode", tessera.modes())
@pytest.mark.parametrize("spec, strategy", [("cloth:12", "greedy"), ("bar:2x2x4", "dsatur")])
def test_a_solve_is_bitwise_the_tools(tool, spec, strategy, mode):
    expected = tool("run", spec, "--frames", "4", "--strategy", strategy, "--mode", mode)
    scene = tessera.scene(spec)
    # `tessera run` colours with the locality pass (and the balance pass only when asked).
    colouring = tessera.colour(scene.model, strategy, locality=True)
    settings = scene.solver_settings() | {"mode": mode}
    solver = tessera.Solver(scene.model, colouring, **settings)
    solver.step(4)
    assert solver.state_hash() == expected["state_hash"]
    assert solver.residual()["rms"] == expected["residual_rms_final"]
    assert solver.statistics["projections"] == expected["projections"]


def test_both_particle_layouts_give_the_same_state(tool):
    scene = tessera.scene("cloth:12")
    colouring = tessera.colour(scene.model, "greedy", locality=True)
    hashes = {}
    for layout in ("interleaved", "separate"):
        solver = tessera.Solver(scene.model, colouring,
                                **(scene.solver_settings() | {"particle_layout": layout}))
        solver.step(3)
        hashes[layout] = solver.state_hash()
    assert hashes["interleaved"] == hashes["separate"]
    assert hashes["separate"] == tool("run", "cloth:12", "--frames", "3", "--strategy", "greedy",
                                      "--particle-layout", "separate")["state_hash"]
    with pytest.raises(ValueError, match="particle layout"):
        tessera.Solver(scene.model, colouring, particle_layout="aos")


def test_part_major_sweeps_as_the_tool_does_for_any_thread_count(tool):
    scene = tessera.scene("cloth:40")

    def hashes(colouring, **settings):
        found = set()
        for threads in (1, 2):
            solver = tessera.Solver(scene.model, colouring, **(
                scene.solver_settings() | {"sweep_order": "part-major", "threads": threads}
                | settings))
            solver.step(3)
            found.add(solver.state_hash())
            statistics = solver.statistics
            assert statistics["parts"] >= 4
            assert 0 < statistics["part_constraints"] < statistics["constraints"]
        return found

    metis = tessera.colour(scene.model, "metis", locality=True, particles_per_part=256)
    expected = tool("run", "cloth:40", "--frames", "3", "--strategy", "metis",
                    "--particles-per-part", "256", "--sweep-order", "part-major")
    assert hashes(metis) == {expected["state_hash"]}
    assert expected["sweep_order"] == "part-major" and expected["parts"] >= 4
    # A colouring without parts: runs of 200 movable particles of its particle order.
    greedy = tessera.colour(scene.model, "greedy", locality=True)
    expected = tool("run", "cloth:40", "--frames", "3", "--strategy", "greedy",
                    "--particles-per-part", "200", "--sweep-order", "part-major")
    assert hashes(greedy, particles_per_part=200) == {expected["state_hash"]}
    assert expected["parts"] == 8


def test_auto_sweep_order_chooses_as_the_tool_does(tool):
    # Auto, the default, sweeps part-major from 32 parts up: runs of 50 of cloth:40's 1,598
    # movable particles are 32, runs of 52 are 31. statistics names the order chosen.
    scene = tessera.scene("cloth:40")
    greedy = tessera.colour(scene.model, "greedy", locality=True)
    for per_run, order in ((50, "part-major"), (52, "colour-major")):
        solver = tessera.Solver(scene.model, greedy,
                                **(scene.solver_settings() | {"particles_per_part": per_run}))
        solver.step(3)
        assert solver.statistics["sweep_order"] == order
        expected = tool("run", "cloth:40", "--frames", "3", "--strategy", "greedy",
                        "--particles-per-part", str(per_run))
        assert expected["sweep_order"] == order
        assert solver.state_hash() == expected["state_hash"]


def test_a_model_from_arrays_solves_as_the_scene_it_copies():
    scene = tessera.scene("cloth:10")
    model = tessera.Model(scene.model.positions, scene.model.inverse_masses)
    for family in scene.model.constraint_counts:
        arrays = scene.model.constraints(family)
        # Tethers reach along the mesh (geodesic), not their straight rest distance: pass it.
        reach = {"max_distance": arrays["max_distance"]} if family == "tether" else {}
        model.set_constraints(family, arrays["particles"], stiffness=arrays["stiffness"],
                              compliance=arrays["compliance"], **reach)
    hashes = set()
    for source, threads in ((scene.model, 1), (model, 1), (model, 2)):
        solver = tessera.Solver(source, tessera.colour(source, "stencil", locality=True),
                                threads=threads, substeps=4)
        solver.step(5)
        hashes.add(solver.state_hash())
    assert len(hashes) == 1


def test_positions_and_velocities_copies_and_views_agree():
    scene = tessera.scene("cloth:9")
    colouring = tessera.colour(scene.model, "greedy", locality=True)
    solver = tessera.Solver(scene.model, colouring, substeps=2)
    np.testing.assert_array_equal(solver.positions, scene.model.positions)
    solver.step(3)
    x = solver.positions
    assert x.shape == (81, 3) and x.dtype == tessera.real_dtype and x.flags.writeable
    views = solver.scheduled_positions
    user = solver.scheduled_to_user
    np.testing.assert_array_equal(user, colouring.particle_new_to_old)
    for axis in range(3):
        assert not views[axis].flags.writeable and not views[axis].flags.owndata
        np.testing.assert_array_equal(views[axis], x[user, axis])
    v = solver.velocities
    for axis, view in enumerate(solver.scheduled_velocities):
        np.testing.assert_array_equal(view, v[user, axis])
    # The views are live: they follow the solver.
    before = views[1].copy()
    solver.step()
    assert not np.array_equal(before, views[1])
    np.testing.assert_array_equal(views[1], solver.positions[user, 1])
    # Without renumbering, scheduled order is the user's.
    plain = tessera.Solver(scene.model, tessera.colour(scene.model, "greedy"))
    np.testing.assert_array_equal(plain.scheduled_to_user, np.arange(81))


def test_set_positions_and_velocities_round_trip():
    scene = tessera.scene("cloth:6")
    solver = tessera.Solver(scene.model, tessera.colour(scene.model, locality=True))
    rng = np.random.default_rng(3)
    x = rng.random((36, 3)).astype(tessera.real_dtype)
    v = rng.random((36, 3))
    solver.set_positions(x)
    solver.set_velocities(v)
    np.testing.assert_array_equal(solver.positions, x)
    np.testing.assert_array_equal(solver.velocities, v.astype(tessera.real_dtype))
    with pytest.raises(ValueError, match=r"^positions must have 36 rows \(one per particle\), not 35$"):
        solver.set_positions(x[:35])
    x[4, 0] = np.inf
    with pytest.raises(ValueError, match=r"^particle 4: position is not finite$"):
        solver.set_positions(x)


def test_residuals_statistics_and_projection():
    scene = tessera.scene("cloth:8")
    solver = tessera.Solver(scene.model, tessera.colour(scene.model), iterations=3,
                            record_convergence=True)
    solver.step(2)
    report = solver.last_step
    assert len(report["history"]) == 4
    assert report["history"][-1] == report["residual_after"]
    assert set(report["residual_after"]["families"]) == {"distance", "dihedral", "tether"}
    statistics = solver.statistics
    assert statistics["steps"] == 2 and statistics["projections"] == 2 * 3 * (294 + 124)
    assert statistics["constraints_per_family"] == {"distance": 161, "dihedral": 133, "tether": 124}
    before = solver.residual()["rms"]
    solver.project(50)
    assert solver.residual()["rms"] < before
    assert solver.settings["iterations"] == 3 and solver.settings["mode"] == "gs"
    # Two threads, several substeps, coloured phases only: each step's substeps but the last
    # run as one parallel region, with the bits of one thread.
    two = tessera.Solver(scene.model, tessera.colour(scene.model), threads=2, substeps=4)
    one = tessera.Solver(scene.model, tessera.colour(scene.model), threads=1, substeps=4)
    two.step(3)
    one.step(3)
    assert two.statistics["steps_in_one_region"] == 3
    assert one.statistics["steps_in_one_region"] == 0
    assert np.array_equal(two.positions, one.positions)


def test_errors_carry_their_messages():
    scene = tessera.scene("cloth:3")
    colouring = tessera.colour(scene.model)
    with pytest.raises(ValueError, match=r"^solver settings: block size must be at least 1$"):
        tessera.Solver(scene.model, colouring, block_size=0)
    with pytest.raises(ValueError, match=r"^solver settings: gravity is not finite$"):
        tessera.Solver(scene.model, colouring, gravity=(0, np.nan, 0))
    with pytest.raises(ValueError, match=r"^unknown solver mode 'fast'|mode"):
        tessera.Solver(scene.model, colouring, mode="fast")
    with pytest.raises(ValueError, match=r"^solver: mode gs needs a colouring"):
        tessera.Solver(scene.model)
    solver = tessera.Solver(scene.model, colouring, time_step=np.finfo(np.float32).max / 4)
    x, v = solver.positions, solver.velocities
    with pytest.raises(tessera.NumericalFailure) as failure:
        solver.step()
    assert isinstance(failure.value, RuntimeError)
    assert str(failure.value) == (
        "solver: step 1 made particle 0 non-finite; positions and velocities are restored to "
        "before it (check the time step, compliance and velocities)")
    np.testing.assert_array_equal(solver.positions, x)
    np.testing.assert_array_equal(solver.velocities, v)


def test_the_gil_is_released_while_stepping_and_colouring():
    """A second Python thread counts while the main thread is inside step() or colour(); with
    the GIL held it could not run at all until the call returned."""
    scene = tessera.scene("cloth:96")
    colouring = tessera.colour(scene.model, "greedy")
    solver = tessera.Solver(scene.model, colouring, threads=1, iterations=150,
                            report_residuals=False)
    count, stop = [0], threading.Event()

    def counter():
        while not stop.is_set():
            count[0] += 1

    thread = threading.Thread(target=counter)
    thread.start()
    try:
        time.sleep(0.05)
        for call in (lambda: solver.step(), lambda: solver.project(150),
                     lambda: tessera.colour(scene.model, "dsatur", balance=True, threads=1)):
            start_count, start = count[0], time.perf_counter()
            call()
            elapsed, counted = time.perf_counter() - start, count[0] - start_count
            assert elapsed > 0.02, "the call is too short to tell"
            assert counted > 1000, (counted, elapsed)
    finally:
        stop.set()
        thread.join()
