"""chokeloops: the choking loops (handles and tunnels, with depth and persistence) of 3D shapes.

    import chokeloops
    r = chokeloops.analyze("data/meshes/kitten_niagara.obj", resolution=128)
    r.loops        # list of dicts (the fields of loops.json); "points" is an (n, 3) array
    r.surface      # (V, F) arrays of the zero level set
    r.diagram      # (n, 3) array: dim, birth, death of the signed distance's lower-star persistence
    r.warnings, r.to_json(), r.write("out/kitten")

    sdf = chokeloops.levelset("shape.obj", resolution=128)   # (nx, ny, nz) float32, sdf.origin, sdf.voxel_size
    chokeloops.analyze(sdf)                                    # the same as analysing the file
    chokeloops.analyze(my_array, voxel_size=0.01, origin=(0, 0, 0))
    chokeloops.analyze((V, F))                                 # a mesh from arrays
    chokeloops.persistence(array)                              # (n, 3): dim, birth, death

    chokeloops.batch(paths, "out/")                            # one directory per input + summary.csv
    chokeloops.batch(paths, "out/", client=dask_client)        # the same on a Dask cluster

Grid arrays are indexed a[i, j, k] = value at origin + voxel_size * (i, j, k); negative inside.
Options are the CLI's, as keywords: resolution (int or "auto"), voxel_size, margin, dmax, min_persistence
(a percentage string like "50%" or a length), side ("handle"/"tunnel"/"both"), max_memory (bytes or "8G"),
threads, shorten, slide, plane_start, check, fill_holes, iso, grid. Errors raise InputError (a ValueError: bad input,
CLI exit code 2) or ResourceError (a MemoryError: out of resources, exit code 3) with the CLI's message;
InternalError (a RuntimeError, exit code 4) is a bug in chokeloops; all derive from chokeloops.Error.
The engine runs with the GIL released.
"""
import csv
import os

import numpy as np

from . import _chokeloops as _c
from ._chokeloops import Error, InputError, InternalError, ResourceError, Result

__version__ = _c.__version__
__all__ = ["analyze", "levelset", "persistence", "batch", "read_summary", "Grid", "Result",
           "Error", "InputError", "ResourceError", "InternalError"]


class Grid(np.ndarray):
    """A signed distance grid: an (nx, ny, nz) array with .origin and .voxel_size (from levelset())."""

    def __array_finalize__(self, obj):
        self.origin = getattr(obj, "origin", (0.0, 0.0, 0.0))
        self.voxel_size = getattr(obj, "voxel_size", 1.0)
        self.warnings = getattr(obj, "warnings", [])


def analyze(source, voxel_size=None, origin=None, **options):
    """Every stage on a path (mesh or .vdb), a (V, F) pair of arrays, or a signed distance array.

    For an array, voxel_size and origin place it in space (a Grid from levelset() carries its own).
    progress: a callable (stage, fraction), called on this thread as stages start ("levelset",
    "persistence", "chokes", "surface", "loops", "done") and as each stage goes on (the loop stage at each
    loop done, ending at 1); an exception it raises stops the analysis and comes out of analyze() unchanged.
    Returns a Result: .loops, .surface, .diagram, .handle_diagram, .tunnel_diagram, .warnings, .genus,
    .sdf, .to_json(), .write(outdir).
    """
    if isinstance(source, Grid):
        if voxel_size is None:
            voxel_size = source.voxel_size
        if origin is None:
            origin = source.origin
        source = source.view(np.ndarray)
    return _c.analyze(source, voxel_size=voxel_size, origin=origin, **options)


def levelset(source, **options):
    """The signed distance grid of a path or a (V, F) pair: a Grid (numpy array, no copy) with .origin,
    .voxel_size and .warnings. Options: resolution, voxel_size, margin, max_memory, fill_holes, iso, grid,
    threads."""
    array, origin, voxel_size, warnings = _c.levelset(source, **options)
    g = array.view(Grid)
    g.origin = tuple(origin)
    g.voxel_size = voxel_size
    g.warnings = list(warnings)
    return g


def persistence(array, threads=None):
    """Lower-star persistence of a 3-D array on the Freudenthal triangulation of its grid: an (n, 3) array
    of (dim, birth, death); essential classes die at inf."""
    if isinstance(array, Grid):
        array = array.view(np.ndarray)
    return _c.persistence(array, threads=threads)


# ---- batch ------------------------------------------------------------------------------------------------

def _run_item(path, item_dir, resume=True, view=True, options=None):
    """One input (runs on a Dask worker or in a local process); never raises for a bad input."""
    return _c.analyze_item(path, item_dir, resume=resume, view=view, **(options or {}))


def _failed(path, item_dir, message, exit_code=4):
    return {"input": path, "status": "failed", "outdir": item_dir, "genus": None,
            "handle_generators": None, "tunnel_generators": None, "handle_chokes": None,
            "tunnel_chokes": None, "deepest_loop": None, "deepest_side": None, "deepest_depth": None,
            "most_persistent_loop": None, "most_persistent_side": None, "most_persistent": None,
            "seconds": 0.0, "resumed": False, "exit_code": exit_code, "error": message}


def batch(paths, outdir, client=None, jobs=1, resume=True, view=True, **options):
    """Analyses every path into outdir/<name>/ and writes outdir/summary.csv; returns its rows as dicts.

    client: a dask.distributed Client: the inputs run as tasks on its workers (paths and outdir must be
    visible to them under the same names, e.g. a shared file system). Without one, the inputs run here,
    one after the other (jobs=1) or in `jobs` separate processes.
    resume: inputs that finished earlier with the same options are skipped (their rows have resumed=True).
    A failing input never stops the others: its row has status "failed" and the error message. (An input
    that crashes its process is its own failure on Dask, which replaces the worker; with jobs > 1 it breaks
    the local pool and the inputs still queued fail too: run again, resume redoes only those.)
    options: as for analyze() (threads=N sets the engine's threads per input).
    """
    paths = [os.path.abspath(os.fspath(p)) for p in paths]
    outdir = os.path.abspath(os.fspath(outdir))
    os.makedirs(outdir, exist_ok=True)
    key = _c.options_key(**options)  # checks the options before any work
    dirs = _c.batch_item_dirs(paths, outdir)
    rows = [None] * len(paths)
    todo = []
    for i, (p, d) in enumerate(zip(paths, dirs)):
        done = _c.read_finished_item(d, key) if resume else None
        if done is not None:
            done["input"] = p
            rows[i] = done
        else:
            todo.append(i)

    if not todo:
        pass
    elif client is not None:
        futures = client.map(_run_item, [paths[i] for i in todo], [dirs[i] for i in todo],
                             resume=resume, view=view, options=options, pure=False)
        for i, fut in zip(todo, futures):
            try:
                rows[i] = fut.result()
            except Exception as e:  # a worker died (crash, killed): this input's failure only
                rows[i] = _failed(paths[i], dirs[i], "%s: %s" % (type(e).__name__, e))
    elif jobs <= 1:
        for i in todo:
            rows[i] = _run_item(paths[i], dirs[i], resume=resume, view=view, options=options)
    else:
        import concurrent.futures
        import multiprocessing
        # spawn, not fork: this process may already run the engine's threads.
        ctx = multiprocessing.get_context("spawn")
        with concurrent.futures.ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool:
            futures = {pool.submit(_run_item, paths[i], dirs[i], resume, view, options): i for i in todo}
            for fut in concurrent.futures.as_completed(futures):
                i = futures[fut]
                try:
                    rows[i] = fut.result()
                except Exception as e:
                    rows[i] = _failed(paths[i], dirs[i], "%s: %s" % (type(e).__name__, e))
    _c.write_batch_summary(rows, os.path.join(outdir, "summary.csv"))
    return rows


def read_summary(path):
    """The rows of a summary.csv (written by batch() or `chokeloops batch`) as dicts of strings."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))
