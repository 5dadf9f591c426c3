"""Shared helpers of the Python tests (run by ctest: python.test_*; PYTHONPATH=build/python)."""
import os
import pathlib

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
DATA = pathlib.Path(os.environ.get("CHOKELOOPS_DATA", ROOT / "data"))
MESHES = DATA / "meshes"


def torus_sdf(n=64, R=0.3, r=0.12):
    """Signed distance of a torus on an n^3 grid over [-0.5, 0.5]^3, indexed [i, j, k]; (sdf, voxel, origin)."""
    x = np.linspace(-0.5, 0.5, n)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    sdf = np.sqrt((np.sqrt(X ** 2 + Y ** 2) - R) ** 2 + Z ** 2) - r
    return sdf, float(x[1] - x[0]), (-0.5, -0.5, -0.5)


def read_off(path):
    """A minimal OFF reader (the test's own, so that the mesh-from-arrays path is checked independently)."""
    words = []
    for line in open(path):
        line = line.split("#")[0].split()
        words.extend(line)
    assert words[0] == "OFF"
    nv, nf = int(words[1]), int(words[2])
    pos = 4
    V = np.array(words[pos:pos + 3 * nv], dtype=float).reshape(nv, 3)
    pos += 3 * nv
    F = []
    for _ in range(nf):
        k = int(words[pos])
        F.append([int(w) for w in words[pos + 1:pos + 1 + k]])
        pos += 1 + k
    return V, np.array(F, dtype=np.int64)


def counts(loops):
    out = {}
    for l in loops:
        key = (l["side"], l["kind"])
        out[key] = out.get(key, 0) + 1
    return out


@pytest.fixture
def cli():
    path = os.environ.get("CHOKELOOPS_CLI", str(ROOT / "build" / "chokeloops"))
    if not os.path.exists(path):
        pytest.fail("the chokeloops CLI is not built: " + path)
    return path
