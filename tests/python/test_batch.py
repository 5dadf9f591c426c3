"""Batch analysis: a Dask LocalCluster of two workers, resume, the CLI command."""
import csv
import os
import shutil
import subprocess

import pytest

import chokeloops
from conftest import MESHES

MESH_NAMES = ["kitten_euclid.off", "3holes_libigl.off", "fertility_libigl.off"]
GENUS = {"kitten_euclid": 1, "3holes_libigl": 3, "fertility_libigl": 4}
OPTIONS = dict(resolution=48, threads=1)


@pytest.fixture
def inputs(tmp_path):
    """The three meshes and one broken file (a truncated OFF)."""
    broken = tmp_path / "broken.off"
    broken.write_text("OFF\n4 2 0\n0 0 0\n1 0 0\n")
    return [str(MESHES / n) for n in MESH_NAMES] + [str(broken)]


def check_rows(rows, inputs, outdir):
    assert [r["input"] for r in rows] == [os.path.abspath(p) for p in inputs]
    ok = [r for r in rows if r["status"] == "ok"]
    failed = [r for r in rows if r["status"] == "failed"]
    assert len(ok) == 3 and len(failed) == 1
    for r in ok:
        name = os.path.basename(r["outdir"])
        assert r["genus"] == GENUS[name] and r["handle_generators"] == GENUS[name]
        assert r["tunnel_generators"] == GENUS[name] and r["error"] == ""
        assert os.path.exists(os.path.join(r["outdir"], "loops.json"))
        assert r["seconds"] > 0
    assert failed[0]["input"].endswith("broken.off") and failed[0]["exit_code"] == 2
    assert "broken.off" in failed[0]["error"] and failed[0]["genus"] is None
    with open(os.path.join(outdir, "summary.csv"), newline="") as f:
        summary = list(csv.DictReader(f))
    assert [s["status"] for s in summary] == [r["status"] for r in rows]
    assert list(summary[0].keys()) == chokeloops._chokeloops.batch_columns()
    assert summary[3]["error"] == failed[0]["error"] and summary[3]["genus"] == ""
    kitten = summary[0]
    assert kitten["genus"] == "1" and kitten["deepest_loop"] != "" and kitten["most_persistent_side"] in ("handle", "tunnel")


def test_batch_on_a_two_worker_local_cluster(inputs, tmp_path):
    distributed = pytest.importorskip("distributed")
    outdir = tmp_path / "out"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None, worker_dashboard_address=None) as cluster, \
            distributed.Client(cluster.scheduler_address) as client:  # by address, as a remote scheduler
        assert len(client.scheduler_info()["workers"]) == 2
        rows = chokeloops.batch(inputs, outdir, client=client, view=False, **OPTIONS)
        check_rows(rows, inputs, outdir)
        assert not any(r["resumed"] for r in rows)
        # again on the cluster: the three finished inputs are skipped, the broken one is tried again
        again = chokeloops.batch(inputs, outdir, client=client, view=False, **OPTIONS)
    assert [r["resumed"] for r in again] == [True, True, True, False]
    check_rows(again, inputs, outdir)


def test_resume_skips_finished_inputs(inputs, tmp_path):
    outdir = tmp_path / "out"
    first = chokeloops.batch(inputs, outdir, view=False, **OPTIONS)
    check_rows(first, inputs, outdir)
    kitten_json = os.path.join(first[0]["outdir"], "loops.json")
    stamp = os.stat(kitten_json).st_mtime_ns
    # an interrupted run: bunny's directory lost its status.json (as when killed mid-way)
    os.remove(os.path.join(first[1]["outdir"], "status.json"))
    second = chokeloops.batch(inputs, outdir, view=False, **OPTIONS)
    assert [r["resumed"] for r in second] == [True, False, True, False]
    assert os.stat(kitten_json).st_mtime_ns == stamp  # not rewritten
    assert second[0]["genus"] == first[0]["genus"] and second[0]["seconds"] == first[0]["seconds"]
    check_rows(second, inputs, outdir)
    # other options are another analysis: nothing is skipped
    third = chokeloops.batch(inputs[:1], outdir, view=False, resolution=40, threads=1)
    assert third[0]["resumed"] is False and third[0]["status"] == "ok"
    # resume=False analyses everything again
    fourth = chokeloops.batch(inputs[:1], outdir, view=False, resume=False, resolution=40, threads=1)
    assert fourth[0]["resumed"] is False


def test_batch_in_local_processes(inputs, tmp_path):
    rows = chokeloops.batch(inputs, tmp_path / "out", jobs=2, view=False, **OPTIONS)
    check_rows(rows, inputs, tmp_path / "out")


def test_cli_batch(inputs, tmp_path, cli):
    outdir = tmp_path / "cli"
    args = [cli, "batch", *inputs, "-o", str(outdir), "--jobs", "2", "--threads", "1", "--resolution", "48", "--no-view"]
    p = subprocess.run(args, capture_output=True, text=True)
    assert p.returncode == 1, p.stderr  # one input failed
    assert "4 input(s): 3 ok (0 done earlier), 1 failed" in p.stdout
    summary = chokeloops.read_summary(outdir / "summary.csv")
    assert [s["status"] for s in summary] == ["ok", "ok", "ok", "failed"]
    assert [s["genus"] for s in summary[:3]] == ["1", "3", "4"]
    assert "broken.off" in summary[3]["error"]
    # the same summary as the Python batch gives (but for times and resumption)
    rows = chokeloops.batch(inputs, outdir, view=False, **OPTIONS)
    assert [r["resumed"] for r in rows] == [True, True, True, False]
    p = subprocess.run(args, capture_output=True, text=True)
    assert "3 ok (3 done earlier), 1 failed" in p.stdout
    # bad arguments: exit code 2, one line naming the mistake
    for bad, says in ((["-o", str(outdir)], "no input given"),
                      ([inputs[0]], "no output directory given"),
                      ([inputs[0], "-o", str(outdir), "--jobs", "0"], "--jobs expects an integer in [1, 1024], got '0'"),
                      ([inputs[0], "-o", str(outdir), "--bogus"], "unknown option --bogus"),
                      ([inputs[0], "-o", str(outdir), "--list", str(tmp_path / "nolist.txt")], "cannot read input list")):
        p = subprocess.run([cli, "batch", *bad], capture_output=True, text=True)
        assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1 and says in p.stderr, p.stderr
    # --list: inputs from a file
    listing = tmp_path / "inputs.txt"
    listing.write_text("# meshes\n" + "\n".join(inputs[:2]) + "\n")
    p = subprocess.run([cli, "batch", "--list", str(listing), "-o", str(outdir), "--resolution", "48", "--no-view"],
                       capture_output=True, text=True)
    assert p.returncode == 0 and "2 input(s): 2 ok (2 done earlier), 0 failed" in p.stdout
