"""Which threads a large CHOLMOD factorization really runs on.

``python -m benchmarks.cholmod_threads [--size 513] [--repeat 2]`` builds the ``hanging``
cloth at that resolution, takes the global step's matrix of its first step, and factors it
as the solver does (supernodal from 78² up when the count is unknown) under
:func:`clothsim.factorization.single_threaded` and under
:func:`clothsim.factorization.cholmod_threads`, interleaved, printing for each the wall
time, the process's CPU, the CPU of the calling thread and of every other thread of the
process that worked (read from ``/proc/self/task``; Linux), and the thread pools as
threadpoolctl set them. Threads that work under ``single_threaded`` are CHOLMOD's own
OpenMP team: SuiteSparse 5's CHOLMOD runs loops of its supernodal factorization with
``num_threads(CHOLMOD_OMP_NUM_THREADS)``, a size fixed when it was compiled (4 by default),
which neither threadpoolctl nor ``OMP_NUM_THREADS`` changes. ``OMP_THREAD_LIMIT``, read
when libgomp loads, caps it, but is no remedy: set to 2, it made one 513² factorization
take many times its CPU (run this with it set to see; it takes minutes then).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path


def thread_cpu() -> dict[str, float]:
    """CPU seconds (user + system) of each thread of this process, by thread id."""
    tick = os.sysconf("SC_CLK_TCK")
    out = {}
    for task in Path("/proc/self/task").iterdir():
        try:
            fields = (task / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:   # the thread ended
            continue
        out[task.name] = (int(fields[11]) + int(fields[12])) / tick
    return out


def system_matrix(size: int):
    """The global step's matrix of the first step of ``hanging`` at ``size``², and the
    CHOLMOD mode the solver factored it in."""
    import clothsim.solvers.local_global as lg
    from clothsim.scene import load_scene

    scene = load_scene("hanging", [f"cloth.resolution=[{size}, {size}]"])
    sim = scene.build_simulation(scene.build_model())
    seen = {}
    real = lg.factor_system

    def spy(*args, **kwargs):
        sysf = real(*args, **kwargs)
        seen.update(A=sysf.A_FF_factor.A, mode=sysf.A_FF_factor.cholmod_mode)
        return sysf

    lg.factor_system = spy
    try:
        sim.step()
    finally:
        lg.factor_system = real
    return seen["A"], seen["mode"]


def factor_once(A, mode: str, limit: str) -> dict:
    """One factorization under ``limit`` ("single_threaded" or "cholmod_threads")."""
    from clothsim.factorization import Factor, _pools, cholmod_threads, single_threaded

    with single_threaded(), (cholmod_threads(A.shape[0]) if limit == "cholmod_threads"
                             else single_threaded()):
        pools = sorted({(p["internal_api"], p["num_threads"]) for p in _pools().info()})
        before, me = thread_cpu(), str(__import__("threading").get_native_id())
        w, c = time.perf_counter(), time.process_time()
        Factor(A, cholmod_mode=mode, check_conditioning=False)
        wall, cpu = time.perf_counter() - w, time.process_time() - c
        after = thread_cpu()
    others = sorted((round(t - before.get(tid, 0.0), 2) for tid, t in after.items()
                     if tid != me and t - before.get(tid, 0.0) >= 0.02), reverse=True)
    return {"wall": wall, "cpu": cpu, "caller": after[me] - before.get(me, 0.0),
            "others": others, "pools": pools}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.cholmod_threads")
    parser.add_argument("--size", type=int, default=513)
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args([] if argv is None else argv)
    A, mode = system_matrix(args.size)
    print(f"{args.size}²: {A.shape[0]} rows, {mode}; OMP_THREAD_LIMIT="
          f"{os.environ.get('OMP_THREAD_LIMIT', 'unset')}, load average "
          f"{Path('/proc/loadavg').read_text().split()[0]}")
    print("| limit | wall | process CPU | calling thread | other threads that worked | "
          "pools (api, threads) |\n|---|---|---|---|---|---|")
    for i in range(args.repeat):
        order = ("single_threaded", "cholmod_threads")
        for limit in order if i % 2 == 0 else order[::-1]:
            r = factor_once(A, mode, limit)
            print(f"| {limit} | {r['wall']:.2f} s | {r['cpu']:.2f} s | {r['caller']:.2f} s | "
                  f"{', '.join(f'{t:.2f} s' for t in r['others']) or '-'} | {r['pools']} |",
                  flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
