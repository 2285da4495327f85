"""fitup.batch: jobs locally and on a Dask LocalCluster (loopback only, dashboard
off, two worker processes), one worker killed mid-batch, every result checked
against a serial run of the same job."""

import os
import signal

import numpy as np
import pytest

import fitup
from fitup import batch
from conftest import MODELS

CELL = str(MODELS / "cell.yaml")


def insertion_jobs(n):
    doc = fitup.Document(CELL)
    goal = fitup.translation(*doc.reference("plate_b", "hole1")["point"])
    return batch.grid(
        [CELL],
        kind="plan_insertion",
        component="screw4",
        goal=goal.tolist(),
        args=[{"smoothing": False, "time_limit_ms": 60000}],
        seeds=range(n),
    )


def test_a_failing_job_is_reported_with_its_inputs_and_the_batch_goes_on(tmp_path):
    jobs = insertion_jobs(2) + [
        batch.Job(document=CELL, kind="plan_path", component="no_such_screw",
                  goal=np.eye(4).tolist(), seed=5),
        batch.Job(document=str(tmp_path / "missing.yaml"), kind="sequence"),
    ]
    seen = []
    rows = batch.run(jobs, db=str(tmp_path / "b.db"), progress=lambda d, t, r: seen.append(d),
                     frame=False)
    assert seen == [1, 2, 3, 4]
    assert [r["ok"] for r in rows] == [True, True, False, False]
    bad = rows[2]
    assert bad["component"] == "no_such_screw" and bad["seed"] == 5
    assert bad["error_type"] == "DocumentError" and "no_such_screw" in bad["error"]
    assert rows[3]["error_file"].endswith("missing.yaml")
    stored = fitup.Database(str(tmp_path / "b.db")).paths()
    assert sorted(p["id"] for p in stored) == sorted(r["path_id"] for r in rows[:2])
    statuses = sorted(r["status"] for r in fitup.Database(str(tmp_path / "b.db")).runs())
    assert statuses == ["failed", "failed", "ok", "ok"]


def test_a_script_job_gets_its_arguments_and_seed(tmp_path):
    (tmp_path / "fitup.toml").write_text("")
    (tmp_path / "s.rhai").write_text('print(`seed ${args.seed} gap ${args.gap}`);\n')
    import shutil
    shutil.copytree(MODELS, tmp_path / "models")
    jobs = batch.grid([str(tmp_path / "models" / "cell.yaml")], kind="script",
                      script=str(tmp_path / "s.rhai"), args=[{"gap": 0.5}], seeds=[4])
    (row,) = batch.run(jobs, progress=False, frame=False)
    assert row["ok"], row["error"]
    assert row["output"] == "seed 4 gap 0.5"


def test_results_come_back_as_a_dataframe_when_pandas_is_installed():
    pandas = pytest.importorskip("pandas")
    table = batch.run(insertion_jobs(1), progress=False)
    assert isinstance(table, pandas.DataFrame) and list(table.columns) == list(batch.COLUMNS)
    assert bool(table["ok"].iloc[0])


def test_dask_cluster_with_a_killed_worker_matches_a_serial_run(tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    jobs = insertion_jobs(10)
    serial = [batch.run_job(j, None, i) for i, j in enumerate(jobs)]
    assert all(r["ok"] and r["found"] for r in serial), [r["error"] for r in serial]
    # The seeds give different searches (else the comparison below shows nothing).
    assert len({r["iterations"] for r in serial}) > 1

    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
        dashboard_address=None, worker_dashboard_address=None, silence_logs=40,
    ) as cluster, distributed.Client(cluster) as client:
        killed = []

        def kill_one(done, total, row):
            if killed:
                return
            busy = [w for w, keys in client.processing().items() if keys]
            pids = client.run(os.getpid)
            victim = busy[0] if busy else next(iter(pids))
            os.kill(pids[victim], signal.SIGKILL)
            killed.append((victim, pids[victim], done, bool(busy)))

        rows = batch.run(jobs, client=client, db=str(tmp_path / "dask.db"),
                         progress=kill_one, frame=False)

    # Killed mid-batch, while it held a job (which the scheduler ran again elsewhere).
    assert killed and killed[0][2] < len(jobs) and killed[0][3], killed
    assert len(rows) == len(jobs)
    for r, s in zip(rows, serial):
        assert r["ok"], r["error"]
        assert r["seed"] == s["seed"] and r["index"] == s["index"]
        # Same seed, same path: the key poses are equal to the last bit.
        assert np.array_equal(r["poses"], s["poses"]), r["seed"]
        assert r["iterations"] == s["iterations"]
    assert len({r["worker"] for r in rows}) >= 2
    stored = fitup.Database(str(tmp_path / "dask.db")).paths()
    ids = {p["id"] for p in stored}
    assert all(r["path_id"] in ids for r in rows)


def test_the_same_jobs_on_ray_match_a_serial_run(monkeypatch):
    """docs/python.md's Ray form: `ray.remote(run_job)` on a local Ray (loopback, no
    dashboard, no usage report); skipped where Ray is not installed (CI)."""
    ray = pytest.importorskip("ray")
    monkeypatch.setenv("RAY_USAGE_STATS_ENABLED", "0")
    jobs = insertion_jobs(4)
    serial = [batch.run_job(j, None, i) for i, j in enumerate(jobs)]
    ray.init(num_cpus=2, include_dashboard=False, _node_ip_address="127.0.0.1",
             log_to_driver=False)
    try:
        remote = ray.remote(max_retries=3)(batch.run_job)
        rows = ray.get([remote.remote(job, None, i) for i, job in enumerate(jobs)])
    finally:
        ray.shutdown()
    table = batch.table(rows, frame=False)
    assert [r["index"] for r in table] == list(range(len(jobs)))
    for r, s in zip(table, serial):
        assert r["ok"] and r["found"], r["error"]
        assert np.array_equal(r["poses"], s["poses"]) and r["iterations"] == s["iterations"]
