#!/usr/bin/env python3
"""Benchmarks of the Python module; prints medians.

    PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py [--runs 3] [--resolution 256]
        [--batch-resolution 128] [--skip-overhead] [--skip-batch]

1. Overhead of the module vs. the CLI on the kitten (data/meshes/kitten_niagara.obj): the CLI as a process
   (`chokeloops analyze ... --no-view --quiet`), the module as a process (`python3 -c "import chokeloops;
   chokeloops.analyze(...).write(...)"`: import included) and in this process (analyze + write, warm).
   The engine's own total (timings_ms) is printed next to each, to tell binding overhead from load noise.
2. Batch throughput over a set of bundled meshes with chokeloops.batch on a Dask LocalCluster of 1 and
   of 2 worker processes (the same two cores: 2 engine threads per input with 1 worker, 1 with 2), and
   `chokeloops batch --jobs 1/2` for comparison. Every run analyses every input again (resume=False).
"""
import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "build", "python"))
import chokeloops  # noqa: E402

KITTEN = os.path.join(ROOT, "data", "meshes", "kitten_niagara.obj")
# closed meshes that keep their genus at 128 and take seconds each
BATCH = ["kitten_euclid.off", "3holes_libigl.off", "fertility_libigl.off", "genus3_directional.off",
         "bunny_libigl.off", "rocker-arm_ajc.obj"]


def median_time(fn, runs):
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), times


def fmt(times):
    return "[" + ", ".join("%.2f" % t for t in times) + "]"


def overhead(args, tmp):
    res = str(args.resolution)
    cli_engine, mod_engine, proc_engine = [], [], []

    def cli():
        out = os.path.join(tmp, "cli")
        subprocess.run([args.cli, "analyze", KITTEN, "-o", out, "--resolution", res, "--no-view", "--quiet"],
                       check=True, stdout=subprocess.DEVNULL)
        import json
        cli_engine.append(json.load(open(os.path.join(out, "loops.json")))["timings_ms"]["total"] / 1000)

    code = ("import chokeloops, sys; r = chokeloops.analyze(sys.argv[1], resolution=int(sys.argv[2])); "
            "r.write(sys.argv[3], view=False); print(r.timings_ms['total'])")

    def module_process():
        p = subprocess.run([sys.executable, "-c", code, KITTEN, res, os.path.join(tmp, "proc")], check=True,
                           capture_output=True, text=True,
                           env=dict(os.environ, PYTHONPATH=os.path.join(ROOT, "build", "python")))
        proc_engine.append(float(p.stdout.split()[-1]) / 1000)

    def module_inprocess():
        r = chokeloops.analyze(KITTEN, resolution=args.resolution)
        r.write(os.path.join(tmp, "mod"), view=False)
        mod_engine.append(r.timings_ms["total"] / 1000)

    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import chokeloops"], check=True,
                   env=dict(os.environ, PYTHONPATH=os.path.join(ROOT, "build", "python")))
    import_s = time.perf_counter() - t0
    print("== overhead: kitten_niagara.obj at --resolution %s, %d runs each (median [runs], seconds)" % (res, args.runs))
    print("python3 -c 'import chokeloops' (process start + import): %.2f s" % import_s)
    rows = []
    # interleaved, so that a change of machine load hits all three alike
    cli_t, mp_t, mi_t = [], [], []
    for _ in range(args.runs):
        for fn, acc in ((cli, cli_t), (module_process, mp_t), (module_inprocess, mi_t)):
            t = time.perf_counter()
            fn()
            acc.append(time.perf_counter() - t)
    for name, t, eng in (("CLI process (analyze + report)", cli_t, cli_engine),
                         ("module, own process (import + analyze + write)", mp_t, proc_engine),
                         ("module, in process (analyze + write)", mi_t, mod_engine)):
        outside = statistics.median([w - e for w, e in zip(t, eng)])
        rows.append((name, statistics.median(t), statistics.median(eng), outside))
        print("%-50s wall %.2f s %s   engine total %.2f s   outside the engine %.2f s"
              % (name, statistics.median(t), fmt(t), statistics.median(eng), outside))
    c = rows[0][1]
    print("module in process vs CLI: %+.2f s (%+.1f%%); module process vs CLI: %+.2f s (%+.1f%%)"
          % (rows[2][1] - c, 100 * (rows[2][1] - c) / c, rows[1][1] - c, 100 * (rows[1][1] - c) / c))
    print("time outside the engine (start-up, import, binding, report): CLI %.2f s, module process %.2f s, "
          "module in process %.2f s" % (rows[0][3], rows[1][3], rows[2][3]))


def batch(args, tmp):
    import distributed
    inputs = [os.path.join(ROOT, "data", "meshes", n) for n in BATCH]
    cores = os.cpu_count() or 2
    print("== batch throughput: %d meshes at --resolution %d, %d runs each, %d cores"
          % (len(inputs), args.batch_resolution, args.runs, cores))
    for workers in (1, 2):
        t = time.perf_counter()
        with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                                      dashboard_address=None) as cluster, distributed.Client(cluster) as client:
            start = time.perf_counter() - t
            threads = max(1, cores // workers)
            n = [0]

            def run():
                n[0] += 1
                out = os.path.join(tmp, "dask%d-%d" % (workers, n[0]))
                rows = chokeloops.batch(inputs, out, client=client, resume=False, view=False,
                                        resolution=args.batch_resolution, threads=threads)
                assert all(r["status"] == "ok" for r in rows), [r["error"] for r in rows]

            med, times = median_time(run, args.runs)
        print("Dask LocalCluster, %d worker(s) x %d thread(s): %.2f s %s = %.2f inputs/s (cluster start %.1f s)"
              % (workers, threads, med, fmt(times), len(inputs) / med, start))
    for jobs in (1, 2):
        n = [0]

        def run_cli():
            n[0] += 1
            out = os.path.join(tmp, "cli%d-%d" % (jobs, n[0]))
            subprocess.run([args.cli, "batch", *inputs, "-o", out, "--jobs", str(jobs), "--resolution",
                            str(args.batch_resolution), "--no-view", "--quiet"], check=True, stdout=subprocess.DEVNULL)

        med, times = median_time(run_cli, args.runs)
        print("chokeloops batch --jobs %d (%d thread(s) each): %.2f s %s = %.2f inputs/s"
              % (jobs, max(1, cores // jobs), med, fmt(times), len(inputs) / med))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--resolution", type=int, default=256)
    ap.add_argument("--batch-resolution", type=int, default=128)
    ap.add_argument("--cli", default=os.path.join(ROOT, "build", "chokeloops"))
    ap.add_argument("--skip-overhead", action="store_true")
    ap.add_argument("--skip-batch", action="store_true")
    args = ap.parse_args()
    print("load average before: %.2f %.2f %.2f" % os.getloadavg())
    tmp = tempfile.mkdtemp(prefix="bench_python_")
    try:
        if not args.skip_overhead:
            overhead(args, tmp)
        if not args.skip_batch:
            batch(args, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print("load average after: %.2f %.2f %.2f" % os.getloadavg())


if __name__ == "__main__":
    main()
