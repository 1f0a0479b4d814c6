"""Colouring from Python: every strategy valid, the tool's statistics and colouring hashes for
the same scene, strategies written in Python checked and scheduled, read-only views."""
import numpy as np
import pytest

import tessera

SCENES = ["cloth:12", "bar:2x2x5"]


def first_fit(graph):
    """Greedy first-fit in constraint-id order, written in Python."""
    colours = np.zeros(graph.constraint_count, dtype=np.int64)
    offsets, particles = graph.constraint_offsets, graph.constraint_particles
    taken = [set() for _ in range(graph.particle_count)]
    for c in range(graph.constraint_count):
        mine = particles[offsets[c]:offsets[c + 1]]
        used = set().union(*(taken[p] for p in mine))
        colour = next(k for k in range(len(used) + 1) if k not in used)
        colours[c] = colour
        for p in mine:
            taken[p].add(colour)
    return colours


def test_strategies_are_listed_with_descriptions():
    strategies = tessera.strategies()
    assert list(strategies)[:2] == ["greedy", "largest-first"] and "metis" in strategies
    assert strategies["greedy"] == "first-fit in input order (the usual PBD baseline)"


@pytest.mark.parametrize("spec", SCENES)
def test_every_strategy_is_valid_and_matches_the_tool(spec, tool):
    model = tessera.scene(spec).model
    graph = tessera.constraint_graph(model)
    expected = {entry["strategy"]: entry for entry in tool("color", spec, "--strategy", "all")}
    assert list(expected) == list(tessera.strategies())
    for name in tessera.strategies():
        colouring = tessera.colour(graph, name, threads=2)
        assert tessera.validate(model, colouring) == (True, "")
        statistics = colouring.statistics
        assert list(statistics) == list(expected[name])  # same keys, same order
        for key, value in expected[name].items():
            if key != "seconds":
                assert statistics[key] == value, (name, key)
        assert colouring.colouring_hash == expected[name]["colouring_hash"]
        assert colouring.colour_count == statistics["colours"] >= graph.lower_bound
        assert sum(colouring.sizes) == colouring.constraint_count == model.constraint_count


def test_post_passes_match_the_tool_and_renumber_particles(tool):
    expected = tool("color", "cloth:12", "--strategy", "stencil", "--balance", "--locality")[0]
    colouring = tessera.colour(tessera.scene("cloth:12").model, "stencil", balance=True,
                               locality=True, threads=1)
    assert colouring.colouring_hash == expected["colouring_hash"]
    assert colouring.statistics["balance"] == expected["balance"]
    assert colouring.renumbers_particles
    new_to_old, old_to_new = colouring.particle_new_to_old, colouring.particle_old_to_new
    np.testing.assert_array_equal(old_to_new[new_to_old], np.arange(len(new_to_old)))


def test_arrays_are_read_only_views():
    model = tessera.scene("cloth:6").model
    graph = tessera.constraint_graph(model)
    colouring = tessera.colour(graph, "dsatur")
    for array in (colouring.colours, colouring.constraints_of(0), graph.constraint_offsets,
                  graph.particles_of(0), graph.particle_constraints):
        assert not array.flags.writeable and not array.flags.owndata
    with pytest.raises(ValueError):
        colouring.colours[0] = 7
    k = int(colouring.colours[5])
    assert 5 in colouring.constraints_of(k)
    # The views keep their owner alive.
    colours = tessera.colour(model, "greedy").colours
    del colouring, graph
    assert colours.sum() > 0
    with pytest.raises(ValueError, match=r"^colour 99 does not exist \(the colouring has \d+\)$"):
        tessera.colour(model).constraints_of(99)


def test_a_python_strategy_is_checked_and_gives_the_builtin_result():
    model = tessera.scene("cloth:10").model
    greedy = tessera.colour(model, "greedy")
    mine = tessera.colour(model, first_fit)
    assert mine.strategy == "first_fit" and mine.valid
    np.testing.assert_array_equal(mine.colours, greedy.colours)
    # Post-passes run on it as on a built-in strategy's colouring.
    balanced = tessera.colour(model, first_fit, balance=True)
    assert balanced.colouring_hash == tessera.colour(model, "greedy", balance=True).colouring_hash


def test_a_python_strategy_is_scheduled_like_a_builtin_one():
    scene = tessera.scene("cloth:10")
    hashes = []
    for strategy in ("greedy", first_fit):
        solver = tessera.Solver(scene.model, tessera.colour(scene.model, strategy), substeps=2)
        solver.step(3)
        hashes.append(solver.state_hash())
    assert hashes[0] == hashes[1]


def test_bad_python_strategies_are_value_errors():
    model = tessera.scene("cloth:4").model
    m = model.constraint_count
    with pytest.raises(ValueError, match=r"^strategy 'zeros' gave an invalid colouring: .*share"):
        tessera.colour(model, _named("zeros", lambda g: np.zeros(m, dtype=int)))
    with pytest.raises(ValueError, match=rf"^strategy 'short' returned 3 colours for {m} constraints$"):
        tessera.colour(model, _named("short", lambda g: [0, 1, 2]))
    with pytest.raises(ValueError, match=r"^strategy 'negative': the colours: index -1"):
        tessera.colour(model, _named("negative", lambda g: -np.ones(m, dtype=int)))
    with pytest.raises(ZeroDivisionError):
        tessera.colour(model, lambda g: 1 // 0)
    with pytest.raises(ValueError) as error:
        tessera.colour(model, "no-such")
    assert str(error.value) == ("unknown colouring strategy 'no-such' (known: " +
                                ", ".join(tessera.strategies()) + ")")


def test_validate_reports_a_colouring_of_another_model():
    small, large = tessera.scene("cloth:4").model, tessera.scene("cloth:5").model
    valid, problem = tessera.validate(large, tessera.colour(small))
    assert not valid and problem
    with pytest.raises(ValueError, match=r"^solver: the colouring does not fit the model: "):
        tessera.Solver(large, tessera.colour(small))


def _named(name, function):
    function.__name__ = name
    return function
