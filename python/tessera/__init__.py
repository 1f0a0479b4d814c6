"""Tessera from Python: parallel PBD/XPBD constraint projection on multicore CPUs.

Build models from NumPy arrays (``Model``) or scenes (``scene``, ``read_scene``, ``read_mesh``),
colour their constraint graphs with any strategy (``colour``, ``strategies``, or a Python
function), and step the parallel solver (``Solver``). Arrays of real numbers use
``real_dtype`` (float32, or float64 in a TESSERA_DOUBLE build). Bad input raises ValueError
with Tessera's message; a step that leaves the finite numbers raises ``NumericalFailure``.

    import tessera
    scene = tessera.scene("cloth:64")
    colouring = tessera.colour(scene.model, "stencil", locality=True)
    solver = tessera.Solver(scene.model, colouring, **scene.solver_settings())
    solver.step(60)
    print(solver.residual()["rms"], solver.positions.shape)
"""
from ._tessera import (
    ConstraintGraph,
    Colouring,
    Mesh,
    Model,
    NumericalFailure,
    Scene,
    Solver,
    __version__,
    color,
    colour,
    constraint_graph,
    families,
    info,
    modes,
    penetration_depth,
    read_mesh,
    read_scene,
    real_dtype,
    scene,
    self_intersections,
    strategies,
    validate,
)

__all__ = [
    "ConstraintGraph",
    "Colouring",
    "Mesh",
    "Model",
    "NumericalFailure",
    "Scene",
    "Solver",
    "__version__",
    "color",
    "colour",
    "constraint_graph",
    "families",
    "info",
    "modes",
    "penetration_depth",
    "read_mesh",
    "read_scene",
    "real_dtype",
    "scene",
    "self_intersections",
    "strategies",
    "validate",
]
