"""Print a SHA-256 of the arrays in each run folder's trajectory.npz (bitwise-identity checks).

Usage: python scripts/trajectory_hashes.py OUT_ROOT   (OUT_ROOT holds one folder per run)
"""
import hashlib, sys, pathlib
import numpy as np
root = pathlib.Path(sys.argv[1])
for d in sorted(p for p in root.iterdir() if p.is_dir()):
    f = d / "trajectory.npz"
    if not f.exists():
        print(d.name, "MISSING"); continue
    with np.load(f) as z:
        h = hashlib.sha256()
        for k in sorted(z.files):
            a = z[k]; h.update(k.encode()); h.update(str(a.dtype).encode()); h.update(str(a.shape).encode()); h.update(np.ascontiguousarray(a).tobytes())
        print(f"{d.name:18s} {h.hexdigest()[:16]} keys={sorted(z.files)}")
