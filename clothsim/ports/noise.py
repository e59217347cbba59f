"""Is a step's difference noise? Uncorrelated from vertex to vertex, spread over the cloth.

A port that solves another model, or iterates otherwise, differs from clothsim's step
smoothly: springs couple neighbouring vertices, and the local/global iteration leaves its
error in the cloth's slow modes. A difference that is as rough as white noise (two
vertices joined by a spring differ as much as two vertices drawn at random) and spread over
many vertices is no model and no iteration: the port's arithmetic or its output adds it
(a race between threads, a value read before it is written, a lossy output, random
jitter). ``check`` then says so ("noisy") instead of "start-dependent" (undecided: "the
port iterates otherwise") or "pinned vertex moved" ("its pins are missing") for pinned
vertices off by the same noise.

The two measures, of the difference d = x_port − x_clothsim over the free vertices:

- roughness: mean over springs (a, b) of |d_a − d_b|² divided by 2 mean |d − d̄|²; 1 for
  independent noise, ≪ 1 for a smooth difference;
- spread: (Σ |d_i|²)² / (n Σ |d_i|⁴), the share of vertices carrying it (about 0.6 for
  Gaussian noise, 1/n for one vertex off: a local error, named at its vertex by the
  verdicts, is not noise).
"""

from __future__ import annotations

import numpy as np

#: Smallest roughness (1 for independent noise; 0.71 for the structural springs left out
#: of a hanging cloth) and spread (0.6 for Gaussian noise) of a difference called noise.
ROUGH = 0.85
SPREAD = 0.25

__all__ = ["noise_note"]


def noise_note(model, problem, x_cs, x_port, tol: float) -> str:
    """The note of a step whose difference from clothsim's answer is noise, else "".

    Parameters
    ----------
    model : Model
        The step's model (its springs give the neighbours).
    problem : StepProblem
        The step's problem (its exactly pinned vertices are left out of the measures).
    x_cs, x_port : ndarray, shape (n, 3)
        clothsim's and the port's x_{k+1} [m].
    tol : float
        The step's tolerance [m].

    Returns
    -------
    str
    """
    d = np.asarray(x_port, float) - np.asarray(x_cs, float)
    n = len(d)
    free = np.ones(n, bool)
    free[problem.fixed_vertices] = False
    if free.sum() < 16 or not np.isfinite(d).all():
        return ""
    a, b = model.springs.spring_vertices.T
    both = free[a] & free[b]
    if not both.any():
        return ""
    df = d[free]
    spread2 = np.sum(df * df, axis=1)
    var = float(np.mean(np.sum((df - df.mean(axis=0)) ** 2, axis=1)))
    if var <= 0:
        return ""
    rough = float(np.mean(np.sum((d[a[both]] - d[b[both]]) ** 2, axis=1))) / (2 * var)
    spread = float(spread2.sum() ** 2 / (len(df) * np.sum(spread2 ** 2)))
    if rough < ROUGH or spread < SPREAD:
        return ""
    rms = float(np.sqrt(spread2.mean()))
    return (f"the difference from clothsim's step is noise: uncorrelated from vertex to "
            f"vertex (two vertices joined by a spring differ {rough:.2f} times as much as "
            f"independent noise would) and spread over the cloth ({spread:.2f} of its "
            f"vertices' share), {rms:.2e} m rms, {rms / tol:.3g} × the tolerance; no model "
            f"and no iteration leaves such a difference: the port's arithmetic or its "
            f"output adds it (a race between threads, a value read before it is written, "
            f"a lossy output)")
