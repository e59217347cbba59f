"""Print a SHA-256 of the arrays in each run folder's trajectory.npz (bitwise-identity checks).

Usage: python scripts/trajectory_hashes.py OUT_ROOT   (OUT_ROOT holds one folder per run)
"""

import hashlib
import pathlib
import sys

import numpy as np


def array_hash(path: pathlib.Path) -> str:
    """SHA-256 over every array's name, dtype, shape and bytes, in name order."""
    digest = hashlib.sha256()
    with np.load(path) as z:
        for key in sorted(z.files):
            a = np.ascontiguousarray(z[key])
            for part in (key, str(a.dtype), str(a.shape)):
                digest.update(part.encode())
            digest.update(a.tobytes())
    return digest.hexdigest()[:16]


if __name__ == "__main__":
    for folder in sorted(p for p in pathlib.Path(sys.argv[1]).iterdir() if p.is_dir()):
        npz = folder / "trajectory.npz"
        print(f"{folder.name:18s} {array_hash(npz) if npz.exists() else 'MISSING'}")
