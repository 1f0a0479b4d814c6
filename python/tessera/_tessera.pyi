"""Type stubs of the extension tessera._tessera (written by hand; tests/test_stubs.py checks
that every public name of the module is declared here and nothing else)."""
from os import PathLike
from typing import Any, Callable, Sequence, TypedDict, Union

import numpy as np
import numpy.typing as npt

__version__: str
#: float32, or float64 in a TESSERA_DOUBLE build: the dtype of every array of reals.
real_dtype: np.dtype[Any]

RealArray = npt.NDArray[np.floating[Any]]
IndexArray = npt.NDArray[np.uint32]
ArrayLike = npt.ArrayLike
StrPath = Union[str, PathLike[str]]

class NumericalFailure(RuntimeError):
    """A step or projection made a position or velocity non-finite; the state was restored."""

class FamilyInfo(TypedDict):
    name: str
    arity: int
    parameters: dict[str, str]
    settable: bool

class FamilyResidual(TypedDict):
    constraints: int
    rms: float
    max: float

class Residual(TypedDict):
    constraints: int
    rms: float
    max: float
    families: dict[str, FamilyResidual]

class StepReport(TypedDict):
    residual_before: Residual
    residual_after: Residual
    history: list[Residual]

class ColouringStatistics(TypedDict, total=False):
    strategy: str
    colours: int
    lower_bound: int
    colours_per_lower_bound: float
    largest: int
    smallest: int
    mean: float
    balance: float
    size_ratio: float
    seconds: float
    valid: bool
    problem: str
    colouring_hash: str
    sizes: list[int]

class SolverStatistics(TypedDict):
    particles: int
    constraints_per_family: dict[str, int]
    constraints: int
    coloured_phases: int
    phase_sizes: list[int]
    jacobi_constraints: int
    parts: int
    part_constraints: int
    sweep_order: str
    threads: int
    seconds_schedule: float
    seconds_projection: float
    seconds_stepping: float
    projections: int
    steps: int
    steps_in_one_region: int

def info() -> dict[str, Any]:
    """Version, precision, SIMD target and threads of this build (as `tessera info`)."""

def strategies() -> dict[str, str]:
    """The built-in colouring strategies: {name: description}."""

def modes() -> list[str]:
    """The solver modes: gs, jacobi, hybrid, sequential."""

def families() -> list[FamilyInfo]:
    """Every constraint family: name, arity (0: clusters) and its parameters."""

class Model:
    """Particles and constraint families: what the solver simulates."""

    def __init__(self, positions: ArrayLike, inverse_masses: ArrayLike) -> None:
        """positions (N, 3), inverse masses (N,) (0: a static particle)."""
    def set_constraints(
        self,
        family: str,
        particles: ArrayLike,
        *,
        rest_positions: ArrayLike | None = None,
        offsets: ArrayLike | None = None,
        **parameters: float | bool | ArrayLike,
    ) -> None:
        """Replaces the constraints of `family`: particles (M, arity) (clusters: flat plus
        offsets), rest shape measured at rest_positions (default: the model's positions),
        parameters as numbers or per-constraint arrays (see families())."""
    def constraints(self, family: str) -> dict[str, Any]:
        """Copies of the family's arrays: 'particles', per-constraint parameters, switches."""
    @property
    def particle_count(self) -> int: ...
    @property
    def constraint_count(self) -> int: ...
    @property
    def constraint_counts(self) -> dict[str, int]:
        """Constraints per non-empty family."""
    @property
    def positions(self) -> RealArray:
        """(N, 3) copy."""
    @property
    def inverse_masses(self) -> RealArray:
        """(N,) copy."""
    def copy(self) -> Model: ...

class Mesh:
    """A mesh read from a file."""

    @property
    def positions(self) -> RealArray: ...
    @property
    def triangles(self) -> IndexArray: ...
    @property
    def tetrahedra(self) -> IndexArray: ...
    def to_model(self, pinned: ArrayLike = ...) -> Model:
        """Default materials: a FEM solid from tetrahedra, else a distance + dihedral shell."""

def read_mesh(file: StrPath) -> Mesh:
    """.obj, TetGen .node/.ele/.face or Gmsh .msh, by extension."""

class Scene:
    """A scene: model, mesh and simulation settings."""

    @property
    def name(self) -> str: ...
    @property
    def model(self) -> Model:
        """The scene's model (a reference, not a copy)."""
    @property
    def mesh(self) -> Mesh: ...
    @property
    def surface_triangles(self) -> IndexArray: ...
    @property
    def pinned(self) -> IndexArray: ...
    @property
    def simulation(self) -> dict[str, Any]: ...
    def solver_settings(self) -> dict[str, Any]:
        """Keyword arguments of Solver that run this scene as `tessera run` does."""
    def collision_settings(self) -> dict[str, Any] | None:
        """Keyword arguments of Solver.set_collisions for this scene's contacts, or None."""

def scene(spec: str) -> Scene:
    """'cloth', 'cloth:N', 'cloth:CxR', 'bar', 'bar:XxYxZ', a mesh file or a .json scene."""

def read_scene(file: StrPath) -> Scene:
    """A JSON scene file."""

class ConstraintGraph:
    """Constraint <-> movable-particle incidence; arrays are read-only views."""

    @property
    def particle_count(self) -> int: ...
    @property
    def constraint_count(self) -> int: ...
    @property
    def incidence_count(self) -> int: ...
    @property
    def movable_particle_count(self) -> int: ...
    @property
    def lower_bound(self) -> int:
        """The most constraints meeting at one movable particle."""
    @property
    def constraint_offsets(self) -> IndexArray: ...
    @property
    def constraint_particles(self) -> IndexArray: ...
    @property
    def particle_offsets(self) -> IndexArray: ...
    @property
    def particle_constraints(self) -> IndexArray: ...
    def particles_of(self, constraint: int) -> IndexArray: ...
    def constraints_of(self, particle: int) -> IndexArray: ...

def constraint_graph(model: Model) -> ConstraintGraph: ...

class Colouring:
    """Colour per constraint and particle order; arrays are read-only views."""

    @property
    def strategy(self) -> str: ...
    @property
    def colour_count(self) -> int: ...
    @property
    def constraint_count(self) -> int: ...
    @property
    def colours(self) -> IndexArray: ...
    @property
    def sizes(self) -> list[int]: ...
    def constraints_of(self, colour: int) -> IndexArray: ...
    @property
    def renumbers_particles(self) -> bool: ...
    @property
    def particle_new_to_old(self) -> IndexArray: ...
    @property
    def particle_old_to_new(self) -> IndexArray: ...
    @property
    def valid(self) -> bool: ...
    @property
    def statistics(self) -> ColouringStatistics:
        """The keys of `tessera color --json`."""
    @property
    def colouring_hash(self) -> str: ...

Strategy = Union[str, Callable[[ConstraintGraph], ArrayLike]]

def colour(
    model: Model | ConstraintGraph,
    strategy: Strategy = "greedy",
    *,
    threads: int | None = None,
    seed: int = 1,
    balance: bool = False,
    locality: bool = False,
    reduce: bool = False,
    particles_per_part: int = 0,
    reduction_rounds: int = 24,
) -> Colouring:
    """Colours with a named strategy or a Python function(graph) -> colours (checked),
    then the post-passes asked for. Releases the GIL."""

color = colour

def validate(model: Model | ConstraintGraph, colouring: Colouring) -> tuple[bool, str]:
    """(valid, problem)."""

class Solver:
    """XPBD/PBD time stepping of a copy of a model over a colouring's schedule."""

    def __init__(
        self,
        model: Model,
        colouring: Colouring | None = None,
        *,
        mode: str = "gs",
        threads: int = 0,
        semantics: str = "compliance",
        time_step: float = 1.0 / 60.0,
        substeps: int = 1,
        iterations: int = 10,
        gravity: Sequence[float] = (0.0, -9.81, 0.0),
        velocity_damping: float = 0.0,
        jacobi_relaxation: float = 1.5,
        block_size: int = 512,
        hybrid_threshold: int = 1024,
        report_residuals: bool = True,
        record_convergence: bool = False,
        check_finite: bool = True,
        divergence_rms: float = 10.0,
        sequential_order: str = "groups",
        contact_scheduling: str = "coloured",
        particle_layout: str = "interleaved",
        sweep_order: str = "auto",
        particles_per_part: int = 0,
    ) -> None: ...
    def step(self, steps: int = 1) -> None:
        """`steps` time steps; raises NumericalFailure (state restored). Releases the GIL."""
    def project(self, iterations: int = 1, dt: float | None = None) -> None:
        """Projection sweeps without time integration. Releases the GIL."""
    def reset_lambdas(self) -> None: ...
    def residual(self) -> Residual: ...
    @property
    def last_step(self) -> StepReport: ...
    @property
    def particle_count(self) -> int: ...
    @property
    def positions(self) -> RealArray:
        """(N, 3) copy, user numbering."""
    @property
    def velocities(self) -> RealArray:
        """(N, 3) copy, user numbering."""
    @property
    def scheduled_positions(self) -> tuple[RealArray, RealArray, RealArray]:
        """Read-only live views of x, y, z in scheduled order (no copy)."""
    @property
    def scheduled_velocities(self) -> tuple[RealArray, RealArray, RealArray]:
        """Read-only live views of the velocities in scheduled order (no copy)."""
    @property
    def scheduled_to_user(self) -> IndexArray:
        """The user's index of every scheduled particle."""
    def set_positions(self, positions: ArrayLike) -> None: ...
    def set_velocities(self, velocities: ArrayLike) -> None: ...
    def multiplier(self, constraint: int) -> float:
        """The XPBD multiplier of a constraint (global id)."""
    def state_hash(self) -> str:
        """The positions' hash as `tessera run` prints it."""
    @property
    def statistics(self) -> SolverStatistics: ...
    @property
    def settings(self) -> dict[str, Any]: ...
    def set_collisions(
        self,
        colliders: Sequence[dict[str, Any]] = ...,
        *,
        surface_triangles: ArrayLike | None = None,
        tetrahedra: ArrayLike | None = None,
        thickness: float = 0.005,
        friction: float = 0.4,
        dynamic_friction: float = 0.3,
        restitution: float = 0.0,
        self_collision: bool = False,
        self_collision_interval: int = 8,
    ) -> None:
        """Contacts every substep: colliders as dicts ('plane', 'sphere', 'box', 'capsule',
        'mesh'), self-collision of surface_triangles, particle-tet contacts of tetrahedra."""
    def clear_collisions(self) -> None: ...
    @property
    def collision_statistics(self) -> dict[str, Any] | None:
        """Contacts per substep (mean, max, by kind), detection and scheduling seconds."""
    def contact_counts(self) -> IndexArray:
        """(N,) contacts of the last substep per particle, user numbering."""

def penetration_depth(
    positions: ArrayLike, colliders: Sequence[dict[str, Any]] = ..., tetrahedra: ArrayLike | None = None
) -> float:
    """The deepest point inside a collider or another solid (the run summary's penetration_max)."""

def self_intersections(positions: ArrayLike, triangles: ArrayLike) -> int:
    """Intersecting pairs of triangles sharing no vertex, counted exactly."""
