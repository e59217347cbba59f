"""The :class:`Scene`: a validated scene document and what it builds.

``Scene.from_dict`` validates (:mod:`.validate`); ``build_model``, ``build_effects`` and
``build_simulation`` make the model, fresh effect objects and a ready simulation. Errors of
the core raised while building are reported at the scene key they come from.
"""

from __future__ import annotations

import copy
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..effects import EFFECTS
from ..errors import InputError, SceneError
from ..io.assignment import read_assignment, read_pins
from ..io.meshes import load_mesh
from ..mesh import Mesh, grid
from ..mesh_checks import check_mesh
from ..model import Model
from ..polygon import polygon
from ..simulation import Simulation
from ..springs import FAMILIES, Springs, grid_springs, mesh_springs, springs_from_pairs
from .checks import Invalid, integer, locate
from .effects import _PYTHON_ONLY_KEYS, constructor_params
from .keys import located, warn_again
from .overrides import blame, builds
from .pins import declared_pins
from .scale import check_extent, overflow_problem, scene_key, stiffness_problem
from .schema import MAX_SUBSTEPS
from .tables import read_index_list, read_spring_table, read_triangles, read_values, read_vertices
from .validate import validate, validate_solver

_FILE_KEYS = {"mesh": "cloth.mesh", "jacobson": "cloth.file", "files": "cloth.vertices"}
"""The key naming the file a cloth of each shape is read from."""


@dataclass(frozen=True, eq=False)
class Scene:
    """A validated scene.

    Attributes
    ----------
    data : dict
        The resolved document: every table with defaults filled in and file paths made
        absolute (see ``docs/scenes.md``).
    source : str
        Where it came from (file path, or ``"<dict>"``); starts every error message.
    base_dir : Path
        Directory that relative paths were resolved against.
    overrides : tuple of str
        The ``--set KEY=VALUE`` changes applied to the file's document before validation
        (:mod:`clothsim.scene.overrides`), recorded with a run.
    base : Scene or None
        The file's scene without those changes (when it is valid): an error it does not
        have is attributed to the ``--set`` changes.
    """

    data: dict
    source: str = "<dict>"
    base_dir: Path = field(default_factory=Path.cwd)
    overrides: tuple = ()
    base: Scene | None = field(default=None, repr=False)

    @classmethod
    def from_dict(cls, d: dict, *, source: str = "<dict>", base_dir=None) -> Scene:
        """Validate a scene document (as parsed from TOML) and return the scene.

        Parameters
        ----------
        d : dict
            The document: ``scene``, ``cloth``, ``springs``, ``solver`` tables and an
            ``effects`` array (units as in ``docs/scenes.md``).
        source : str
            Where it came from; starts every error message; its stem is the default name.
        base_dir : str or Path, optional
            Folder relative file names are resolved against (default: the working folder).

        Returns
        -------
        Scene

        Raises
        ------
        SceneError
            ``"<source>: <key.path>: <what is wrong>"`` for the first problem found.
        """
        base = Path.cwd() if base_dir is None else Path(base_dir)
        default_name = Path(source).stem if source != "<dict>" else "scene"
        default_name = re.sub(r"[^\w.-]+", "-", default_name, flags=re.ASCII)
        default_name = default_name.lstrip(".")[:100] or "scene"
        try:
            data = validate(d, base, default_name)
        except Invalid as exc:
            raise SceneError(source, exc.path, exc.detail) from None
        except RecursionError:
            raise SceneError(source, "", "nested too deeply") from None
        return cls(data, str(source), base)

    # -- plain properties
    @property
    def name(self) -> str:
        """``scene.name``: also the output folder's name."""
        return self.data["scene"]["name"]

    @property
    def description(self) -> str:
        """``scene.description``, one line."""
        return self.data["scene"]["description"]

    @property
    def frames(self) -> int:
        """Frames written after the initial one."""
        return self.data["scene"]["frames"]

    @property
    def fps(self) -> float:
        """Frames per second [1/s] (1 / h when the scene gives ``h``)."""
        return self.data["scene"]["fps"]

    @property
    def substeps(self) -> int:
        """Implicit Euler steps per frame."""
        return self.data["scene"]["substeps"]

    @property
    def h(self) -> float:
        """Time step [s]: ``scene.h`` as written, else 1 / (fps · substeps)."""
        given = self.data["scene"].get("h")
        return given if given is not None else 1.0 / (self.fps * self.substeps)

    def to_dict(self) -> dict:
        """The resolved document (JSON-ready deep copy; ``tolerance`` may be None).

        Returns
        -------
        dict
            Every table with defaults filled in, in the units of the scene reference.
        """
        return copy.deepcopy(self.data)

    def _error(self, path: str, detail: str) -> SceneError:
        return blame(SceneError(self.source, path, detail), self.overrides,
                     lambda: builds(self.base))

    # -- building
    def _files_mesh(self):
        c = self.data["cloth"]
        x = read_vertices(c["vertices"], "cloth.vertices")
        tris = (read_triangles(c["triangles"], "cloth.triangles", c["index_base"], len(x))
                if "triangles" in c else np.zeros((0, 3), np.int64))
        mesh = Mesh(x, tris)
        scale = float(np.abs(x).max()) if x.size else 0.0
        try:  # a mesh file's checks (errors only), on the cloth scaled to 1 (no overflow)
            check_mesh(Mesh(x / scale, tris) if scale > 0 else mesh, field="cloth.triangles",
                       warn=False)
        except InputError as exc:
            raise Invalid("cloth.triangles", str(exc).split(": ", 1)[1]) from None
        return mesh

    def _spring_table(self, vertex_count: int):
        sp = self.data["springs"]
        if "table" not in sp:
            return None
        return read_spring_table(sp["table"], "springs.table", sp["columns"],
                                 sp["index_base"], vertex_count)

    def build_model(self):
        """Build the mesh, springs and masses of ``[cloth]`` and ``[springs]``.

        Returns
        -------
        Model
        """
        try:
            return self._build_model()
        except Invalid as exc:
            raise self._error(exc.path, exc.detail) from None
        except SceneError:
            raise
        except InputError as exc:
            path, reason = locate(exc, "cloth")
            key = _FILE_KEYS.get(self.data["cloth"]["shape"])
            if key and path.startswith("cloth.vertices") and key != "cloth.vertices":
                path, reason = key, f"{path.removeprefix('cloth.')}: {reason}"  # in the file
            raise self._error(path, reason) from None
        except (OverflowError, RecursionError) as exc:  # e.g. an OBJ index beyond int64
            raise self._error(_FILE_KEYS.get(self.data["cloth"]["shape"], "cloth"),
                              f"a number is out of range: {exc}") from None

    def _build_model(self):

        c, sp = self.data["cloth"], self.data["springs"]
        shape = c["shape"]
        if shape == "jacobson":
            a = read_assignment(c["file"])
            springs = springs_from_pairs(a.mesh, a.spring_pairs, a.stiffness)
            return Model(a.mesh, springs, a.vertex_mass)
        if shape == "grid":
            nx, ny = c["resolution"]
            mesh = grid(nx, ny, size=tuple(c["size"]), center=c["center"], plane=c["plane"])
            springs = grid_springs(mesh, structural=sp.get("structural"),
                                   shear=sp.get("shear"), bending=sp.get("bending"),
                                   bending_pattern=sp["bending_pattern"])
        else:
            if shape == "mesh":
                mesh = load_mesh(c["mesh"], field="cloth.mesh")
            elif shape == "polygon":
                mesh = polygon(c["outline"], spacing=c["spacing"], center=c["center"],
                               plane=c["plane"])
            else:
                mesh = self._files_mesh()
            springs = mesh_springs(mesh, structural=sp.get("structural"),
                                   bending=sp.get("bending"))
        check_extent(mesh.vertices, shape)
        table = self._spring_table(mesh.vertex_count)
        if table is not None and len(table.pairs):
            x = mesh.vertices
            rest = np.where(np.isnan(table.rest),
                            np.linalg.norm(x[table.pairs[:, 0]] - x[table.pairs[:, 1]], axis=1),
                            table.rest)
            fam = np.full(len(rest), FAMILIES.index("structural"), np.int8)
            springs = Springs.concatenate([springs, Springs(table.pairs, table.stiffness,
                                                            rest, fam, None, table.damping)])
        vm = c.get("vertex_mass")
        if isinstance(vm, str):
            vm = read_values(vm, "cloth.vertex_mass")
            if len(vm) != mesh.vertex_count:
                raise Invalid("cloth.vertex_mass", f"expected {mesh.vertex_count} values (one "
                                                   f"per vertex), got {len(vm)}")
        return Model.build(mesh, springs, total_mass=c.get("mass"), vertex_mass=vm,
                           mass_lumping=c["mass_lumping"])

    def _implicit_pins(self, vertex_count: int | None = None) -> list:
        """Pins the cloth's files declare: the assignment's ``b``, the table's attachments."""
        c = self.data["cloth"]
        b = read_pins(c["file"]) if c["shape"] == "jacobson" else None
        t = None
        if "table" in self.data["springs"]:
            if vertex_count is None:
                vertex_count = self.build_model().vertex_count
            t = self._spring_table(vertex_count)
        return declared_pins(c, b, t)

    def build_effects(self, model=None) -> list:
        """Fresh effect objects: the cloth files' pins first, then the declared effects.

        The pins a cloth's files declare come first: a ``jacobson`` cloth's pins (its JSON's
        ``b`` list), then a spring table's attachments, held as ``[cloth] pin_method`` and
        ``pin_stiffness`` say (:mod:`clothsim.scene.pins`).

        Parameters
        ----------
        model : Model, optional
            The scene's model, used for vertex counts (default: built when needed).

        Returns
        -------
        list of Effect
            New, unbound effect objects (one set per simulation).

        Raises
        ------
        SceneError
            On an effect that cannot be built (naming its key).
        """
        return [e for _, e in self._checked_effects(model)]

    def _checked_effects(self, model=None) -> list[tuple[str, object]]:
        try:
            return self._effects(model)
        except Invalid as exc:
            raise self._error(exc.path, exc.detail) from None

    def _effects(self, model=None) -> list[tuple[str, object]]:
        out = self._implicit_pins(None if model is None else model.vertex_count)
        for i, e in enumerate(self.data["effects"]):
            params = constructor_params(e["kind"], e)
            path = f"effects[{i}]"
            if isinstance(params.get("vertices"), str):  # a pin's or a force's file
                n = (self.build_model() if model is None else model).vertex_count
                params["vertices"] = read_index_list(params["vertices"], f"{path}.vertices",
                                                     e.get("index_base", 0), n)
            if "contact" in _PYTHON_ONLY_KEYS.get(e["kind"], ()):   # an obstacle's mode
                params["contact"] = self.data.get("contact", {}).get("mode", "hold")
            try:
                out.append((path, EFFECTS[e["kind"]](**params)))
            except (InputError, TypeError, ValueError) as exc:
                raise Invalid(*locate(exc, path, e["kind"], path)) from None
        return out

    def build_simulation(self, model=None, *, method: str | None = None,
                         iterations: int | None = None, tolerance: float | None = None,
                         substeps: int | None = None):
        """A :class:`~clothsim.simulation.Simulation` of this scene, ready to step.

        Parameters
        ----------
        model : Model, optional
            Default: :meth:`build_model`.
        method, iterations, tolerance
            Override ``[solver]``.
        substeps : int, optional
            Override the steps per frame (h = 1 / (fps · substeps), or ``scene.h`` /
            substeps when the scene gives ``h``).

        Returns
        -------
        Simulation
            With the scene's effects built fresh and time step h [s].

        Raises
        ------
        SceneError
            On an invalid override or effect.
        """

        so = self.data["solver"]
        try:
            solver = validate_solver(so["method"] if method is None else method,
                                     so["iterations"] if iterations is None else iterations,
                                     so["tolerance"] if tolerance is None else tolerance,
                                     so["backend"], so["initial_guess"], so["cholmod_mode"])
            if substeps is not None:
                substeps = integer(substeps, "scene.substeps", minimum=1, maximum=MAX_SUBSTEPS)
        except Invalid as exc:
            raise self._error(exc.path, exc.detail) from None
        if substeps is None:
            h = self.h
        elif self.data["scene"].get("h") is not None:
            h = self.data["scene"]["h"] / substeps
        else:
            h = 1.0 / (self.fps * substeps)
        model = self.build_model() if model is None else model
        pairs = self._checked_effects(model)
        try:
            with warnings.catch_warnings(record=True) as caught:  # keys renamed below
                sim = Simulation(model, h=h, effects=[e for _, e in pairs],
                                 solver=solver["method"], iterations=solver["iterations"],
                                 tolerance=solver["tolerance"], backend=solver["backend"],
                                 initial_guess=solver["initial_guess"])
        except InputError as exc:  # among them clothsim.magnitudes.check_step's bounds
            # The simulation checked the magnitudes once (no silent freeze); on a refusal the
            # scene's own checks name the scene key the model's field comes from.
            self._check_stiffness(model, h)
            if (problem := overflow_problem(model, h)) is not None:
                raise self._error(scene_key(problem[0], self.data), problem[1]) from None
            raise located(self, exc, model, h) from None
        warn_again(self, model, caught)  # Simulation's effects[i] named as the scene's key
        if solver["cholmod_mode"] != "auto":
            if not hasattr(sim.solver, "cholmod_mode"):
                raise self._error("solver.cholmod_mode", f"applies to the local/global family "
                                  f"of solvers, not to {solver['method']!r}")
            sim.solver.cholmod_mode = solver["cholmod_mode"]
        return sim

    def _check_stiffness(self, model, h: float) -> None:
        """Reject springs so stiff that M + h²L cannot be factored (:func:`stiffness_problem`)."""
        table = len(self._spring_table(model.vertex_count).pairs) if "table" in self.data[
            "springs"] else 0
        if (problem := stiffness_problem(model, h, self.data, table)) is not None:
            raise self._error(*problem)


__all__ = ["Scene"]
