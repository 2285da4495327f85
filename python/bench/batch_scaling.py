"""The same 100-job batch serially, then on a local Dask cluster of 1 and of 2 worker
processes (docs/performance.md, "Python").

Run from the repository root, in the virtualenv holding the module and
``dask[distributed]``:

    python python/bench/batch_scaling.py [JOBS]      # JOBS defaults to 100

Jobs: seed 002's insertion of screw4 into plate_b's hole in the demo cell
(``plan_insertion``, smoothing off), seeds 0..JOBS-1. Each cluster is a
``LocalCluster`` on 127.0.0.1 (worker processes, one thread each, dashboards off);
``RAYON_NUM_THREADS=1`` (unless set) keeps each job on one core, so a worker is one
core's worth. The wall time covers submitting, running and collecting every job (the
workers have imported fitup before). Every cluster's rows are checked against the
serial run: same seeds, same key poses to the last bit, same iterations. Prints wall
time, jobs/s, the 2-worker / 1-worker ratio and the load average around each run;
exits 1 when a result differs.
"""

import os
import pathlib
import sys
import time

# One core per job: the colliders' rayon pool would otherwise take every core of the
# machine in each worker process (they inherit this).
os.environ.setdefault("RAYON_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import fitup  # noqa: E402
from fitup import batch  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[2]


def loadavg():
    return " ".join(pathlib.Path("/proc/loadavg").read_text().split()[:3])


def differences(rows, serial):
    """Where `rows` differ from the serial run (empty when they agree)."""
    bad = []
    for r, s in zip(rows, serial):
        same = (r["ok"] and r["found"] and r["seed"] == s["seed"]
                and r["iterations"] == s["iterations"]
                and np.array_equal(r["poses"], s["poses"]))
        if not same:
            bad.append((s["seed"], r["error"] or r["reason"]))
    if len(rows) != len(serial):
        bad.append(("count", len(rows)))
    return bad


def timed(label, run, n):
    before = loadavg()
    t0 = time.perf_counter()
    rows = run()
    wall = time.perf_counter() - t0
    busy = sum(r["wall_s"] for r in rows) / n
    print(f"{label:10} {n} jobs in {wall:7.1f} s  {n / wall:6.2f} jobs/s  "
          f"{busy * 1e3:5.0f} ms per job on its worker  load {before} -> {loadavg()}",
          flush=True)
    return rows, n / wall


def main():
    from dask.distributed import Client, LocalCluster

    n = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    cell = str(REPO / "models" / "cell.yaml")
    goal = fitup.translation(*fitup.Document(cell).reference("plate_b", "hole1")["point"])
    jobs = batch.grid([cell], kind="plan_insertion", component="screw4", goal=goal.tolist(),
                      args=[{"smoothing": False, "time_limit_ms": 60000}], seeds=range(n))
    print(f"RAYON_NUM_THREADS={os.environ['RAYON_NUM_THREADS']}, {os.cpu_count()} cores")
    serial, _ = timed("serial", lambda: batch.run(jobs, progress=False, frame=False), n)
    failed = [r["seed"] for r in serial if not (r["ok"] and r["found"])]
    if failed:
        sys.exit(f"serial run: no path for seeds {failed}")
    rate = {}
    bad = False
    for workers in (1, 2):
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                          host="127.0.0.1", dashboard_address=None,
                          worker_dashboard_address=None, silence_logs=40) as c, \
                Client(c) as client:
            client.run(lambda: __import__("fitup"))  # the import is not the batch's cost
            rows, rate[workers] = timed(
                f"{workers} worker{'s' if workers > 1 else ''}",
                lambda: batch.run(jobs, client=client, progress=False, frame=False), n)
        diff = differences(rows, serial)
        if diff:
            bad = True
            print(f"  {len(diff)} results differ from the serial run: {diff[:5]}")
        else:
            print(f"  all {n} results equal the serial run's (key poses, iterations)")
    print(f"2 workers / 1 worker: {rate[2] / rate[1]:.2f}x the jobs per second")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
