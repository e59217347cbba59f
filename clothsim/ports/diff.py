"""Compare two models: springs, stiffnesses, rest lengths, damping, masses, pins, the
external force on each vertex and the step settings, each difference with its likely cause.

The sides are read by :func:`clothsim.ports.model_folder.model_tables` (a scene, a
Simulation, or a port model folder: the files are listed there). Vertices are paired by
their initial positions, so the two may number them differently.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from .compare import cloth_size, match_vertices
from .model_folder import SETTING_UNITS, ModelTables, model_tables

__all__ = ["ModelDiff", "ModelTables", "diff_models", "model_tables"]


@dataclass
class ModelDiff:
    """Differences between models A and B.

    Attributes
    ----------
    identical : bool
        True when springs, stiffnesses, rest lengths, damping, masses, pins, forces and the
        settings both sides state agree.
    cause : str
        The likely cause of the difference (or a confirmation).
    lines : list of str
        One line per difference found.
    """

    identical: bool
    cause: str
    lines: list[str] = field(default_factory=list)

    def report(self) -> str:
        """The verdict and cause, then the differences, one per line.

        Returns
        -------
        str
        """
        return "\n".join([("IDENTICAL" if self.identical else "DIFFERENT") + f": {self.cause}"]
                         + [f"  {t}" for t in self.lines])


def _listing(items, limit=6) -> str:
    items = list(items)
    text = ", ".join(str(i) for i in items[:limit])
    return text + (f", … ({len(items)} in all)" if len(items) > limit else "")


def _pairs_text(pairs) -> str:
    return _listing(f"{a}-{b}" for a, b in pairs)


def diff_models(a, b, *, rtol: float = 1e-12) -> ModelDiff:
    """Differences of model B from model A, vertices numbered as in A.

    Parameters
    ----------
    a, b : scene, Simulation, factory, folder or ModelTables
    rtol : float
        Relative tolerance of stiffness, rest length and mass comparisons.

    Returns
    -------
    ModelDiff
    """
    A, B = model_tables(a), model_tables(b)
    lines, causes = [], []
    if len(A.x0) != len(B.x0):
        msg = f"{len(A.x0)} vertices in A, {len(B.x0)} in B"
        return ModelDiff(False, msg, [msg])
    try:
        perm = match_vertices(B.x0, A.x0)
    except InputError as exc:
        return ModelDiff(False, f"the initial shapes differ: {exc}", [str(exc)])
    inv = np.empty_like(perm)
    inv[perm] = np.arange(len(perm))
    if np.any(perm != np.arange(len(perm))):
        lines.append("vertex numbering differs (matched by initial position)")
    bsp = inv[B.springs]

    def table(springs, k, r):
        keys = [tuple(sorted(map(int, p))) for p in springs]
        count = Counter(keys)
        ksum, rest = {}, {}
        for key, ki, ri in zip(keys, k, r):
            ksum[key] = ksum.get(key, 0.0) + float(ki)
            rest.setdefault(key, float(ri))
        return count, ksum, rest

    ca, ka, ra = table(A.springs, A.stiffness, A.rest)
    cb, kb, rb = table(bsp, B.stiffness, B.rest)
    for name, count in (("A", ca), ("B", cb)):
        dup = sorted(key for key, c in count.items() if c > 1)
        if dup:
            lines.append(f"{len(dup)} springs duplicated in {name} (stiffness counted twice): "
                         f"{_pairs_text(dup)}")
            causes.append(f"{len(dup)} duplicated springs in {name}")
    only_a, only_b = sorted(set(ca) - set(cb)), sorted(set(cb) - set(ca))
    for name, only in (("A", only_a), ("B", only_b)):
        if only:
            lines.append(f"{len(only)} springs only in {name}: {_pairs_text(only)}")
            causes.append(f"{len(only)} springs only in {name}")
    common = sorted(set(ca) & set(cb))
    dk = [key for key in common if abs(ka[key] - kb[key]) > rtol * max(abs(ka[key]), 1e-300)]
    dr = [key for key in common if abs(ra[key] - rb[key]) > rtol * max(ra[key], 1e-12)
          + 1e-15 * cloth_size(A.x0)]
    if dk:
        key = dk[0]
        lines.append(f"{len(dk)} springs with other stiffness, e.g. {key[0]}-{key[1]}: "
                     f"{ka[key]:.9g} vs {kb[key]:.9g} N/m")
        causes.append(f"{len(dk)} stiffnesses differ")
    if dr:
        key = dr[0]
        lines.append(f"{len(dr)} springs with other rest length, e.g. {key[0]}-{key[1]}: "
                     f"{ra[key]:.9g} vs {rb[key]:.9g} m")
        causes.append(f"{len(dr)} rest lengths differ")
    for name, t in (("A", A), ("B", B)):
        if t.masses is not None and (len(t.masses) != len(t.x0)
                                     or not np.all(np.isfinite(t.masses))):
            bad = (len(t.masses) if len(t.masses) != len(t.x0)
                   else int(np.sum(~np.isfinite(t.masses))))
            text = (f"masses of {name}: {bad} not finite" if len(t.masses) == len(t.x0)
                    else f"masses of {name}: {bad} for {len(t.x0)} vertices")
            lines.append(text)
            causes.insert(0, text)
    if (A.masses is not None and B.masses is not None and len(A.masses) == len(A.x0)
            and len(B.masses) == len(B.x0)):
        mb = B.masses[perm]
        dm = ~(np.abs(A.masses - mb) <= rtol * np.abs(A.masses))
        if dm.any():
            i = int(np.flatnonzero(dm)[np.argmax(np.nan_to_num(np.abs(A.masses - mb)[dm],
                                                               nan=np.inf))])
            lines.append(f"{int(dm.sum())} masses differ, e.g. vertex {i}: {A.masses[i]:.9g} vs "
                         f"{mb[i]:.9g} kg (totals {A.masses.sum():.9g} vs {mb.sum():.9g})")
            causes.append(f"{int(dm.sum())} masses differ")
    pa = A.pins
    pb = {int(inv[v]): val for v, val in B.pins.items()}
    for name, mine, other in (("A", pa, pb), ("B", pb, pa)):
        only = sorted(set(mine) - set(other))
        if only:
            kinds = {mine[v] for v in only}
            what = ("attachments (penalty pins" + (f", k = {mine[only[0]][1]:g} N/m)"
                                                   if len(kinds) == 1 else ")")
                    if all(m == "penalty" for m, _ in kinds) else "pins")
            text = (f"{len(only)} {what} only in {name}: vertices "
                    f"{' and '.join(map(str, only)) if len(only) <= 2 else _listing(only)}")
            lines.append(text)
            causes.insert(0, text)
    other_pins = [v for v in set(pa) & set(pb) if pa[v] != pb[v]]
    if other_pins:
        v = sorted(other_pins)[0]
        lines.append(f"{len(other_pins)} pins differ in method or stiffness, e.g. vertex {v}: "
                     f"{pa[v]} vs {pb[v]}")
        causes.append(f"{len(other_pins)} pins differ")
    if A.damping is not None or B.damping is not None:
        _, ca_d, _ = table(A.springs, _or_zeros(A.damping, len(A.springs)), A.rest)
        _, cb_d, _ = table(bsp, _or_zeros(B.damping, len(B.springs)), B.rest)
        dd = [key for key in common if abs(ca_d[key] - cb_d[key])
              > rtol * max(abs(ca_d[key]), abs(cb_d[key]), 1e-300)]
        if dd:
            key = dd[0]
            lines.append(f"{len(dd)} springs with other damping, e.g. {key[0]}-{key[1]}: "
                         f"{ca_d[key]:.9g} vs {cb_d[key]:.9g} N s/m")
            causes.append(f"{len(dd)} spring dampings differ")
    _force_lines(A, B, perm, rtol, lines, causes)
    _setting_lines(A.settings, B.settings, lines, causes)
    unstated = [f"{what} (stated by {'A' if name == 'B' else 'B'} only)"
                for what, name in _unstated(A, B)]
    if not causes and not lines:
        parts = ["pins", "masses"] + (["forces"] if A.forces is not None
                                      and B.forces is not None else [])
        parts += ["settings"] if set(A.settings) & set(B.settings) else []
        other = f"; not compared: {', '.join(unstated)}" if unstated else ""
        return ModelDiff(True, f"{len(A.x0)} vertices, {len(ca)} springs, "
                               f"{', '.join(parts[:-1])} and {parts[-1]} agree{other}", [])
    if not causes:
        return ModelDiff(True, "same model up to vertex numbering", lines)
    return ModelDiff(False, causes[0] if len(causes) == 1 else "; ".join(causes[:3]), lines)


def _unstated(A, B):
    """(what, side) for the forces and settings one side does not state."""
    for name, t, o in (("A", A, B), ("B", B, A)):
        if t.forces is None and o.forces is not None:
            yield "forces", name
        missing = [k for k in o.settings if k not in t.settings]
        if missing and t.settings:
            yield "setting " + " ".join(missing), name
        elif missing:
            yield "settings", name


def _or_zeros(a, n):
    return np.zeros(n) if a is None else np.asarray(a, np.float64)


def _vector(v) -> str:
    return "(" + ", ".join(f"{c:.6g}" for c in v) + ")"


def _gravity(f, masses, rtol=1e-9):
    """g [m/s²] when f = m g on every vertex for one g, else None."""
    if masses is None or np.any(masses <= 0):
        return None
    g = f / masses[:, None]
    return g[0] if np.allclose(g, g[0], rtol=rtol, atol=1e-12 * np.abs(g).max()) else None


def _uniform(f, rtol=1e-9):
    """The force on every vertex [N] when it is the same everywhere, else None."""
    return f[0] if np.allclose(f, f[0], rtol=rtol, atol=1e-12 * np.abs(f).max()) else None


def _force_lines(A, B, perm, rtol, lines, causes) -> None:
    """Compare the external force on each vertex at the first step; name a gravity mix-up."""
    if A.forces is None or B.forces is None:
        return
    fa, fb = np.asarray(A.forces, float), np.asarray(B.forces, float)[perm]
    scale = max(float(np.abs(fa).max()), float(np.abs(fb).max()), 1e-300)
    diff = np.linalg.norm(fa - fb, axis=1)
    bad = ~(diff <= rtol * scale)
    if not bad.any():
        return
    masses = A.masses if A.masses is not None else B.masses
    masses = None if masses is None or len(masses) != len(fa) else masses
    ua, ub = _uniform(fa), _uniform(fb)
    ga, gb = _gravity(fa, masses), _gravity(fb, masses)
    if ub is not None and ua is None and ga is not None:
        text = (f"force: gravity convention: B applies {_vector(ub)} N on every vertex, A "
                f"m·g with g = {_vector(ga)} m/s² (the coursework's −9.8 N per vertex is not "
                f"m·g unless every mass is 1 kg)")
    elif ua is not None and ub is None and gb is not None:
        text = (f"force: gravity convention: A applies {_vector(ua)} N on every vertex, B "
                f"m·g with g = {_vector(gb)} m/s² (the coursework's −9.8 N per vertex is not "
                f"m·g unless every mass is 1 kg)")
    elif ga is not None and gb is not None:
        text = f"force: gravity differs: g = {_vector(ga)} (A) vs {_vector(gb)} (B) m/s²"
    else:
        i = int(np.argmax(diff))
        text = (f"force: {int(bad.sum())} vertices feel another external force, e.g. vertex "
                f"{i}: {_vector(fa[i])} vs {_vector(fb[i])} N (totals {_vector(fa.sum(0))} vs "
                f"{_vector(fb.sum(0))} N)")
    lines.append(text)
    causes.insert(0, text)


#: Why a setting matters, for the one-line cause.
_SETTING_WHY = {
    "initial_guess": "a fixed iteration count then ends elsewhere ([solver] initial_guess)",
    "iterations": "an unconverged step depends on it ([solver] iterations)",
    "precision": "check with --precision float32 when one side computes in float32",
    "h": "every step differs ([scene] h)",
    "damping": "velocities differ after each step ([[effects]] kind = \"damping\")",
    "tolerance": "the stopping rule differs ([solver] tolerance)",
    "method": "another solver stops elsewhere before convergence ([solver] method)",
}


def _setting_lines(sa: dict, sb: dict, lines, causes) -> None:
    """One line per step setting both sides state and that differs."""
    for key in SETTING_UNITS:
        if key not in sa or key not in sb:
            continue
        a, b = sa[key], sb[key]
        same = (abs(a - b) <= 1e-12 * max(abs(a), abs(b)) if isinstance(a, float)
                and isinstance(b, float) else a == b)
        if same:
            continue
        unit = f" {SETTING_UNITS[key]}" if SETTING_UNITS[key] else ""
        text = (f"setting {key}: {a:.9g} vs {b:.9g}{unit}" if isinstance(a, float)
                else f"setting {key}: {a} vs {b}{unit}") + f": {_SETTING_WHY[key]}"
        lines.append(text)
        causes.append(text.split(":")[0] + " differs")
