"""Which held vertices switch between sticking and sliding, and on what forces (a diagnostic).

Run from the repository root::

    .venv/bin/python -m benchmarks.contact_chatter --size 65 --frames 90 --last 6

Runs a built-in obstacle scene in ``"hold"`` mode (as shipped, at ``size``² vertices) and,
for each of the last frames, compares every held vertex's static-friction decision
(:func:`clothsim.effects.holding.hold_step`) with the one of the step before: how many
switched from sticking to sliding and back, how many of them also switched in the frame
before, and for those that started to slide their tangential force against the friction
cone μ F_n and against the margin :data:`~clothsim.effects.holding.NOISE_MARGIN` × the
solve's unbalanced force (the forces' noise). A ratio far above 1 in the last column says
the switch is the friction law's, not the noise's. Writes nothing.
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np

from clothsim.effects.holding import NOISE_MARGIN

from .contact import _scene


def _quantiles(a: np.ndarray) -> str:
    if not len(a):
        return "-"
    return "/".join(f"{q:.2g}" for q in np.percentile(a, [10, 50, 90]))


def chatter(scene: str = "drape-sphere", size: int = 65, frames: int | None = None,
            last: int = 6):
    """Yield one line per frame of the last ``last`` of ``frames``: the switches' causes.

    Parameters
    ----------
    scene : {"drape-sphere", "drop-on-square"}
    size : int
        Vertices per side.
    frames : int, optional
        Frames to run (default: the scene's).
    last : int
        How many of the final frames to report.

    Yields
    ------
    str
        Per obstacle that holds vertices: held vertices, switches stick -> slide and
        slide -> stick, how many of the switching vertices switched in the frame before
        too, and for stick -> slide the 10/50/90th percentiles of |F_t| / (μ F_n), of
        (|F_t| − μ F_n) / (NOISE_MARGIN × noise), and of the switching vertices' speed.
    """
    sc = _scene(scene, size, "hold")
    sim = sc.build_simulation()
    frames = sc.frames if frames is None else frames
    obstacles = [e for e in sim.effects if hasattr(e, "_holding")]
    sim.expect_steps(frames * sc.substeps)
    flipped = {id(e): set() for e in obstacles}
    for f in range(frames):
        before = [e._holding for e in obstacles]
        for _ in range(sc.substeps):
            sim.step()
        speed = np.linalg.norm(sim.state.velocities, axis=1)
        for e, held in zip(obstacles, before):
            now = e._holding
            if not len(held.vertices) or held.planes.forces is None:
                continue
            R = held.reaction()
            fn = np.einsum("ij,ij->i", R, held.normals)
            ft = np.linalg.norm(R - fn[:, None] * held.normals, axis=1)
            stuck_now = dict(zip(now.vertices.tolist(), now.stick.tolist()))
            kept = np.array([v in stuck_now for v in held.vertices.tolist()], bool)
            nxt = np.array([stuck_now.get(v, False) for v in held.vertices.tolist()], bool)
            s2l, l2s = kept & held.stick & ~nxt, kept & ~held.stick & nxt
            switched = set(held.vertices[s2l | l2s].tolist())
            again = len(switched & flipped[id(e)])
            flipped[id(e)] = switched
            if f < frames - last:
                continue
            cone = e.friction * np.maximum(fn, 0.0)
            margin = NOISE_MARGIN * held.planes.noise
            yield (f"frame {f:3d} {e.kind}: held {len(held.vertices)}, stick->slide "
                   f"{int(s2l.sum())}, slide->stick {int(l2s.sum())}, switched the frame "
                   f"before too {again}; stick->slide |F_t|/(mu F_n) "
                   f"{_quantiles(ft[s2l] / np.maximum(cone[s2l], 1e-300))}, excess over "
                   f"the noise margin {_quantiles((ft - cone)[s2l] / max(margin, 1e-300))}, "
                   f"speed {_quantiles(speed[held.vertices[s2l | l2s]])} m/s")


def scene_parser(description: str, last: int) -> argparse.ArgumentParser:
    """The options of the hold-mode diagnostics: ``--scene``, ``--size``, ``--frames`` and
    ``--last`` (default ``last``)."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--scene", default="drape-sphere",
                        choices=("drape-sphere", "drop-on-square"))
    parser.add_argument("--size", type=int, default=65)
    parser.add_argument("--frames", type=int, default=None)
    parser.add_argument("--last", type=int, default=last)
    return parser


def main(argv=None) -> None:
    args = scene_parser(__doc__.splitlines()[0], 6).parse_args(argv)
    warnings.simplefilter("ignore")
    for line in chatter(args.scene, args.size, args.frames, args.last):
        print(line, flush=True)


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
