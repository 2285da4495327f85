"""A 100-job batch on 1 and on 2 local Dask workers (docs/performance.md, "Python").

Run from the repository root: python python/bench/batch_scaling.py [JOBS]
Jobs: seed 002's insertion of screw4 into plate_b's hole in the demo cell
(`plan_insertion`, smoothing off), seeds 0..JOBS-1. Each configuration is a
LocalCluster on 127.0.0.1 (worker processes, one thread each, dashboard off); the
wall time covers submitting, running and collecting every job.
"""

import pathlib
import sys
import time

import fitup
from fitup import batch

REPO = pathlib.Path(__file__).resolve().parents[2]


def main():
    from dask.distributed import Client, LocalCluster

    n = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    cell = str(REPO / "models" / "cell.yaml")
    goal = fitup.translation(*fitup.Document(cell).reference("plate_b", "hole1")["point"])
    jobs = batch.grid([cell], kind="plan_insertion", component="screw4", goal=goal.tolist(),
                      args=[{"smoothing": False, "time_limit_ms": 60000}], seeds=range(n))
    for workers in (1, 2):
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                          host="127.0.0.1", dashboard_address=None, silence_logs=40) as c, \
                Client(c) as client:
            client.run(lambda: __import__("fitup"))  # the import is not the batch's cost
            t0 = time.perf_counter()
            rows = batch.run(jobs, client=client, progress=False, frame=False)
            wall = time.perf_counter() - t0
        ok = sum(r["ok"] and r["found"] for r in rows)
        busy = sum(r["wall_s"] for r in rows)
        print(f"{workers} worker(s): {n} jobs in {wall:.1f} s ({ok} found), "
              f"{busy / n * 1e3:.0f} ms per job on its worker")


if __name__ == "__main__":
    main()
