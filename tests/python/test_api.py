"""The module on numpy arrays: round trips, a mesh from arrays, errors as Python exceptions."""
import json
import subprocess
import threading

import numpy as np
import pytest

import chokeloops
from conftest import MESHES, counts, read_off, torus_sdf


def test_torus_sdf_array_gives_one_handle_and_one_tunnel_generator():
    sdf, h, origin = torus_sdf(64)
    r = chokeloops.analyze(sdf, voxel_size=h, origin=origin)
    assert r.genus == 1 and r.closed and r.warnings == []
    c = counts(r.loops)
    assert c.get(("handle", "generator")) == 1 and c.get(("tunnel", "generator")) == 1
    for l in r.loops:
        assert l["found"]
        assert isinstance(l["points"], np.ndarray) and l["points"].shape[1] == 3 and len(l["points"]) > 10
    handle = next(l for l in r.loops if l["side"] == "handle")
    tunnel = next(l for l in r.loops if l["side"] == "tunnel")
    # exact: 2 pi r = 0.754 around the tube, 2 pi (R - r) = 1.131 around the hole
    assert abs(handle["length"] - 0.754) < 0.02
    assert abs(tunnel["length"] - 1.131) < 0.03
    # loops lie on the surface, which lies in the box given by origin and voxel size
    V, F = r.surface
    assert V.dtype == np.float64 and V.shape[1] == 3 and F.dtype == np.int32 and F.shape[1] == 3
    assert V.min() >= -0.5 and V.max() <= 0.5 and F.max() < len(V)
    assert r.voxel_size == pytest.approx(h) and tuple(r.origin) == origin


def test_plane_start_keyword_gives_the_membranes_loops():
    # plane_start=False takes every generator's loop from its membrane: on the torus the same two loops
    # within a small fraction of their length (the loop stage's own test compares them on more shapes).
    sdf, h, origin = torus_sdf(64)
    a = chokeloops.analyze(sdf, voxel_size=h, origin=origin)
    b = chokeloops.analyze(sdf, voxel_size=h, origin=origin, plane_start=False)
    assert len(a.loops) == len(b.loops) == 2
    for x, y in zip(a.loops, b.loops):
        assert x["side"] == y["side"] and x["found"] and y["found"]
        assert abs(x["length"] / y["length"] - 1) < 2e-3
    # ... but not the same points: the keyword reached the loop stage
    assert any(not np.array_equal(x["points"], y["points"]) for x, y in zip(a.loops, b.loops))


def test_result_arrays_are_views_not_copies():
    sdf, h, origin = torus_sdf(40)
    r = chokeloops.analyze(sdf, voxel_size=h, origin=origin)
    V1, _ = r.surface
    V2, _ = r.surface
    assert not V1.flags.owndata and np.shares_memory(V1, V2) and not V1.flags.writeable
    p1, p2 = r.loops[0]["points"], r.loops[0]["points"]
    assert np.shares_memory(p1, p2)
    g = r.sdf
    assert g.shape == sdf.shape and g.flags.f_contiguous and np.shares_memory(g, r.sdf)
    np.testing.assert_allclose(g, sdf.astype(np.float32))
    del r  # the arrays keep the result alive
    assert np.isfinite(V1).all() and np.isfinite(g).all()


def test_persistence_of_an_array():
    sdf, h, origin = torus_sdf(40)
    d = chokeloops.persistence(sdf)
    assert d.ndim == 2 and d.shape[1] == 3
    dims, birth, death = d[:, 0], d[:, 1], d[:, 2]
    assert set(np.unique(dims)) <= {0.0, 1.0, 2.0}
    assert np.isinf(death).sum() == 1 and dims[np.isinf(death)][0] == 0  # one essential class: the box
    assert (death[np.isfinite(death)] >= birth[np.isfinite(death)]).all()
    # the torus' two loops: a dim-1 class born inside the solid and dying outside it (its handle) ...
    assert ((dims == 1) & (birth < 0) & (death > 0)).sum() == 1
    # same pairs whatever the memory order and dtype of the array, and the same as analyze()'s diagram
    for a in (np.asfortranarray(sdf), sdf.astype(np.float32), np.ascontiguousarray(sdf)):
        np.testing.assert_array_equal(chokeloops.persistence(a), d)
    np.testing.assert_array_equal(chokeloops.analyze(sdf, voxel_size=h, origin=origin).diagram, d)


def test_levelset_round_trip_matches_the_file():
    path = MESHES / "kitten_euclid.off"
    g = chokeloops.levelset(path, resolution=48)
    assert isinstance(g, chokeloops.Grid) and g.ndim == 3 and g.dtype == np.float32
    assert g.flags.f_contiguous and not g.flags.owndata  # the engine's own storage, not copied
    assert max(g.shape) > 48 and g.voxel_size > 0 and len(g.origin) == 3
    assert g.min() < 0 < g.max()
    from_grid = chokeloops.analyze(g)
    from_file = chokeloops.analyze(str(path), resolution=48)
    assert from_grid.genus == from_file.genus == 1
    assert counts(from_grid.loops) == counts(from_file.loops)
    np.testing.assert_array_equal(from_grid.diagram, from_file.diagram)
    np.testing.assert_allclose(from_grid.surface[0], from_file.surface[0])


def test_mesh_from_arrays():
    V, F = read_off(MESHES / "kitten_euclid.off")
    r = chokeloops.analyze((V, F), resolution=48)
    assert r.genus == 1 and r.input_genus == 1
    c = counts(r.loops)
    assert c.get(("handle", "generator")) == 1 and c.get(("tunnel", "generator")) == 1
    from_file = chokeloops.analyze(str(MESHES / "kitten_euclid.off"), resolution=48)
    assert counts(from_file.loops) == c
    np.testing.assert_array_equal(r.diagram, from_file.diagram)
    # the level set of arrays too, and float32/int32 inputs are accepted
    g = chokeloops.levelset((V.astype(np.float32), F.astype(np.int32)), resolution=48)
    assert g.shape == chokeloops.levelset(MESHES / "kitten_euclid.off", resolution=48).shape


def test_to_json_and_write(tmp_path):
    sdf, h, origin = torus_sdf(40)
    r = chokeloops.analyze(sdf, voxel_size=h, origin=origin, side="handle")
    j = json.loads(r.to_json())
    assert len(j["loops"]) == len(r.loops) == 1 and j["loops"][0]["side"] == "handle"
    assert j["parameters"]["side"] == "handle" and j["surface"]["genus"] == 1
    r.write(str(tmp_path / "out"))
    for f in ("surface.ply", "loops.ply", "loops.obj", "loops.json", "view.html"):
        assert (tmp_path / "out" / f).stat().st_size > 0
    assert json.loads((tmp_path / "out" / "loops.json").read_text()) == j


def cli_error(cli, *args):
    p = subprocess.run([cli, *args], capture_output=True, text=True)
    line = p.stderr.strip().splitlines()[-1]
    return p.returncode, line.split(": error: ", 1)[1]


def test_errors_are_python_exceptions_with_the_cli_messages(cli, tmp_path):
    missing = str(tmp_path / "missing.obj")
    with pytest.raises(chokeloops.InputError) as e:
        chokeloops.analyze(missing)
    code, message = cli_error(cli, "analyze", missing, "-o", str(tmp_path / "o"))
    assert code == 2 and str(e.value) == message
    assert isinstance(e.value, ValueError) and isinstance(e.value, chokeloops.Error)

    broken = tmp_path / "broken.off"
    broken.write_text("OFF\n3 1 0\n0 0 0\n1 0\n")
    with pytest.raises(ValueError) as e:
        chokeloops.analyze(str(broken))
    assert str(e.value) == cli_error(cli, "analyze", str(broken), "-o", str(tmp_path / "o"))[1]

    # resources: a memory budget that no grid fits (CLI exit code 3); a MemoryError
    kitten = str(MESHES / "kitten_euclid.off")
    with pytest.raises(chokeloops.ResourceError) as e:
        chokeloops.analyze(kitten, resolution=256, max_memory="1M")
    assert isinstance(e.value, MemoryError)
    code, message = cli_error(cli, "analyze", kitten, "--resolution", "256", "--max-memory", "1M", "-o", str(tmp_path / "o"))
    assert code == 3 and str(e.value) == message

    with pytest.raises(chokeloops.InputError) as e:
        chokeloops.analyze(kitten, dmax="lots")
    assert str(e.value) == cli_error(cli, "analyze", kitten, "--dmax", "lots", "-o", str(tmp_path / "o"))[1]


def test_exception_classes():
    E = chokeloops
    assert issubclass(E.InputError, ValueError) and issubclass(E.ResourceError, MemoryError)
    assert issubclass(E.InternalError, RuntimeError)
    for cls in (E.InputError, E.ResourceError, E.InternalError):
        assert issubclass(cls, E.Error)
    assert not issubclass(E.InputError, MemoryError) and not issubclass(E.ResourceError, ValueError)


def test_bad_arrays_and_arguments():
    sdf, h, origin = torus_sdf(24)
    bad = sdf.copy()
    bad[3, 4, 5] = np.nan
    with pytest.raises(chokeloops.InputError, match="NaN"):
        chokeloops.analyze(bad)
    with pytest.raises(chokeloops.InputError, match="3-D"):
        chokeloops.persistence(sdf[0])
    with pytest.raises(chokeloops.InputError):
        chokeloops.analyze(np.zeros((1, 5, 5)))
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    with pytest.raises(chokeloops.InputError, match="refers to vertex 7"):
        chokeloops.analyze((V, np.array([[0, 1, 7]])))
    with pytest.raises(chokeloops.InputError, match=r"\(n, 3\)"):
        chokeloops.analyze((V[:, :2], np.array([[0, 1, 2]])))
    with pytest.raises(chokeloops.InputError, match="side"):
        chokeloops.analyze(sdf, side="sideways")
    with pytest.raises(TypeError, match="colour"):
        chokeloops.analyze(sdf, colour="red")
    with pytest.raises(TypeError):
        chokeloops.analyze(42)


def test_threads_run_concurrently_and_agree():
    """The GIL is released: two analyses in Python threads both finish with the same result."""
    sdf, h, origin = torus_sdf(48)
    out = [None, None]

    def work(i):
        out[i] = chokeloops.analyze(sdf, voxel_size=h, origin=origin, threads=1)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert out[0].to_json().split('"timings_ms"')[0] == out[1].to_json().split('"timings_ms"')[0]


def test_progress_callback_sees_each_stage_and_its_exception_stops_the_analysis():
    sdf, h, origin = torus_sdf(48)
    seen = []
    watched = chokeloops.analyze(sdf, voxel_size=h, origin=origin, threads=1,
                                 progress=lambda stage, fraction: seen.append((stage, fraction)))
    stages = [s for s, _ in seen]
    assert stages[-1] == "done"
    for stage in ("persistence", "chokes", "surface", "loops"):
        assert stage in stages
    loops = [f for s, f in seen if s == "loops"]
    # the stage's start, one report per loop (one thread: the calling one finishes them all), the end
    assert loops[0] == 0 and loops[-1] == 1 and loops == sorted(loops) and len(loops) == len(watched.loops) + 2
    plain = chokeloops.analyze(sdf, voxel_size=h, origin=origin, threads=1)
    assert [l["length"] for l in watched.loops] == [l["length"] for l in plain.loops]

    class Stop(Exception):
        pass

    def stop_in_the_loop_stage(stage, fraction):
        if stage == "loops" and fraction > 0:
            raise Stop(fraction)

    with pytest.raises(Stop) as stopped:
        chokeloops.analyze(sdf, voxel_size=h, origin=origin, threads=1, progress=stop_in_the_loop_stage)
    assert stopped.value.args[0] == pytest.approx(1 / len(plain.loops))
    with pytest.raises(TypeError, match="progress"):
        chokeloops.analyze(sdf, voxel_size=h, origin=origin, progress=3)
    with pytest.raises(TypeError):
        chokeloops.levelset(str(MESHES / "3holes_libigl.off"), progress=print)
