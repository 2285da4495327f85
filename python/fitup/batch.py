"""Many fitup jobs — documents × planners or scripts × arguments × seeds — on a
Dask distributed cluster, or locally.

Each job is one call of the plain, picklable function :func:`run_job`, so the same
batch runs on anything that can call a function on a worker (Dask here, Ray with
``ray.remote(run_job)``; see docs/python.md). A job never raises: a failure comes
back as a row with ``ok = False``, the error and the job's inputs, and the batch
goes on. A worker that dies mid-job (killed, out of memory) loses only its running
jobs, which Dask's scheduler runs again on another worker.

Results go to the results database when ``db`` names one (each job a run; planned
paths with their key poses; a PostgreSQL URL when the workers are on several
machines, since every worker writes there itself), and come back as a table: a
pandas ``DataFrame`` when pandas is installed, else a list of dicts, in the order
of the jobs.

Units: mm and radians; goals are 4×4 column-vector pose matrices (world, mm).
"""

from __future__ import annotations

import dataclasses
import json
import os
import socket
import sys
import time
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Union

#: What a job does.
KINDS = ("plan_path", "plan_insertion", "plan_disassembly", "sequence", "script")

#: The columns every result row has, in order (a failed job has None where it got
#: no answer).
COLUMNS = (
    "index",
    "name",
    "kind",
    "document",
    "component",
    "script",
    "planner",
    "seed",
    "args",
    "ok",
    "error",
    "error_type",
    "error_file",
    "error_line",
    "found",
    "reason",
    "length_mm",
    "rotation_rad",
    "iterations",
    "checks",
    "time_ms",
    "key_poses",
    "poses",
    "order",
    "mounts",
    "output",
    "run_id",
    "path_id",
    "worker",
    "wall_s",
)


@dataclasses.dataclass(frozen=True)
class Job:
    """One job: what to run on which document with which arguments and seed.

    ``kind`` is one of :data:`KINDS`. Planning kinds need ``component`` (and
    ``goal``, a 4×4 pose, world, mm, except ``plan_disassembly``) and take the
    keywords of ``Document.plan_path`` in ``args`` (``planner``,
    ``time_limit_ms``, …). ``sequence`` takes ``Document.plan_sequence``'s keywords.
    ``script`` runs the Rhai file ``script`` with ``document`` as ``doc`` and
    ``args`` (plus ``seed``) as the map ``args``. ``document`` and ``script`` must be
    paths every worker can read.
    """

    document: str
    kind: str = "plan_path"
    component: Optional[str] = None
    goal: Optional[Any] = None
    script: Optional[str] = None
    args: Dict[str, Any] = dataclasses.field(default_factory=dict)
    seed: int = 0
    name: Optional[str] = None

    def label(self) -> str:
        """A one-line description (the run's name in the results database)."""
        what = self.script if self.kind == "script" else self.component or ""
        planner = self.args.get("planner", "")
        extra = f" {planner}" if planner else ""
        return f"batch {self.kind} {what}{extra} seed={self.seed} on {self.document}"

    def inputs(self) -> Dict[str, Any]:
        """The job's inputs as row columns."""
        return {
            "name": self.name,
            "kind": self.kind,
            "document": self.document,
            "component": self.component,
            "script": self.script,
            "planner": self.args.get("planner"),
            "seed": self.seed,
            "args": json.dumps(self.args, sort_keys=True, default=repr),
        }


def grid(
    documents: Iterable[str],
    *,
    kind: str = "plan_path",
    component: Optional[str] = None,
    goal: Optional[Any] = None,
    script: Optional[str] = None,
    planners: Sequence[Optional[str]] = (None,),
    args: Sequence[Dict[str, Any]] = ({},),
    seeds: Iterable[int] = (0,),
) -> List[Job]:
    """Every combination of ``documents`` × ``planners`` × ``args`` × ``seeds`` as jobs
    of one ``kind`` (a planner of None keeps the call's default)."""
    seeds = list(seeds)
    out = []
    for d in documents:
        for p in planners:
            for a in args:
                for s in seeds:
                    a2 = dict(a)
                    if p is not None:
                        a2["planner"] = p
                    out.append(
                        Job(
                            document=str(d),
                            kind=kind,
                            component=component,
                            goal=goal,
                            script=script,
                            args=a2,
                            seed=int(s),
                        )
                    )
    return out


def _row(job: Job, index: Optional[int]) -> Dict[str, Any]:
    row = dict.fromkeys(COLUMNS)
    row.update(job.inputs())
    row["index"] = index
    return row


def _failure(row: Dict[str, Any], e: BaseException) -> None:
    row["ok"] = False
    row["error"] = f"{type(e).__name__}: {e}"
    row["error_type"] = type(e).__name__
    row["error_file"] = getattr(e, "file", None)
    row["error_line"] = getattr(e, "line", None)


def run_job(job: Job, db: Optional[str] = None, index: Optional[int] = None) -> Dict[str, Any]:
    """Runs one job and returns its result row (see :data:`COLUMNS`); never raises.

    With ``db`` (a SQLite file or a ``postgres://`` URL) the job is recorded as a run,
    and a planned path is stored with its key poses (``run_id``, ``path_id``).
    """
    import numpy as np

    import fitup

    started = time.perf_counter()
    row = _row(job, index)
    row["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    database = None
    run_id = None
    try:
        if job.kind not in KINDS:
            raise fitup.InputError(
                f"unknown job kind {job.kind!r}: expected one of {', '.join(KINDS)}",
                cause="unknown job kind",
            )
        if db is not None and job.kind != "script":
            database = fitup.Database(db)
            run_id = database.start_run(job.label(), job.document)
            row["run_id"] = run_id
        if job.kind.startswith("plan_"):
            doc = fitup.Document(job.document)
            kw = dict(job.args)
            kw["seed"] = job.seed
            if job.kind == "plan_disassembly":
                path = doc.plan_disassembly(job.component, **kw)
            else:
                goal = np.asarray(job.goal, dtype=float)
                path = getattr(doc, job.kind)(job.component, goal, **kw)
            d = path.to_dict()
            for k in ("found", "reason", "planner", "length_mm", "rotation_rad",
                      "iterations", "checks", "time_ms", "key_poses", "poses"):
                row[k] = d[k]
            if database is not None:
                name = job.name or f"{job.component} seed {job.seed}"
                row["path_id"] = database.save_path(name, path, run_id=run_id)
        elif job.kind == "sequence":
            doc = fitup.Document(job.document)
            kw = dict(job.args)
            kw.setdefault("seed", job.seed)
            plan = doc.plan_sequence(**kw)
            best = plan["sequences"][0]
            row["found"] = True
            row["order"] = best["order"]
            row["mounts"] = best["mounts"]
            row["time_ms"] = plan["time_ms"]
            row["output"] = json.dumps(best)
        else:
            args = dict(job.args)
            args.setdefault("seed", job.seed)
            r = fitup.run_script(job.script, doc=job.document, args=args, db=db)
            row["found"] = True
            row["output"] = "\n".join(r["output"])
            row["time_ms"] = r["elapsed_s"] * 1e3
        row["ok"] = True
        if database is not None:
            database.finish_run(run_id, "ok", row["output"] or "")
    except Exception as e:  # one job's failure never stops the batch
        _failure(row, e)
        if database is not None and run_id is not None:
            try:
                database.finish_run(run_id, "failed", row["error"])
            except Exception:  # the row already says what went wrong
                pass
    row["wall_s"] = time.perf_counter() - started
    return row


def table(rows: List[Dict[str, Any]], frame: Optional[bool] = None):
    """Rows as a pandas ``DataFrame`` when pandas is installed (or ``frame`` is True),
    else the list itself (``frame`` False)."""
    if frame is False:
        return rows
    try:
        import pandas
    except ImportError:
        if frame:
            raise
        return rows
    return pandas.DataFrame(rows, columns=list(COLUMNS))


def _printer(total: int) -> Callable[[int, int, Dict[str, Any]], None]:
    started = time.perf_counter()
    failed = [0]

    def show(done: int, total: int, row: Dict[str, Any]) -> None:
        if not row.get("ok"):
            failed[0] += 1
        end = "\n" if done == total else "\r"
        sys.stderr.write(
            f"fitup.batch: {done}/{total} done, {failed[0]} failed, "
            f"{time.perf_counter() - started:.1f} s{end}"
        )
        sys.stderr.flush()

    return show


def run(
    jobs: Sequence[Job],
    *,
    address: Optional[str] = None,
    client: Any = None,
    db: Optional[str] = None,
    retries: int = 2,
    progress: Union[bool, Callable[[int, int, Dict[str, Any]], None]] = True,
    frame: Optional[bool] = None,
):
    """Runs ``jobs`` and returns their result rows in job order (see :func:`table`).

    ``client`` (a ``dask.distributed.Client``) or ``address`` (a scheduler's
    address, e.g. ``"tcp://10.0.0.5:8786"``) runs them on that cluster, one task per
    job; neither runs them here, one after the other. ``retries``: Dask's retries of
    a task that raised (run_job itself never does; workers that die are handled by
    the scheduler, which reruns their jobs elsewhere up to its
    ``distributed.scheduler.allowed-failures``). A job that still cannot run
    (``KilledWorker``) is a failed row with its inputs. ``progress``: True prints
    ``done/total`` to stderr, a callable gets ``(done, total, row)`` after each job.
    """
    jobs = list(jobs)
    total = len(jobs)
    show = _printer(total) if progress is True else (progress or None)
    rows: List[Optional[Dict[str, Any]]] = [None] * total
    own = None
    if client is None and address is not None:
        from dask.distributed import Client

        client = own = Client(address)
    try:
        if client is None:
            for i, job in enumerate(jobs):
                rows[i] = run_job(job, db, i)
                if show:
                    show(i + 1, total, rows[i])
        else:
            from dask.distributed import as_completed

            futures = [
                client.submit(run_job, job, db, i, pure=False, retries=retries)
                for i, job in enumerate(jobs)
            ]
            index = {f.key: i for i, f in enumerate(futures)}
            done = 0
            for fut in as_completed(futures):
                i = index[fut.key]
                try:
                    row = fut.result()
                except Exception as e:  # KilledWorker, a cancelled or lost task
                    row = _row(jobs[i], i)
                    _failure(row, e)
                rows[i] = row
                done += 1
                if show:
                    show(done, total, row)
    finally:
        if own is not None:
            own.close()
    return table(rows, frame)  # type: ignore[arg-type]


__all__ = ["Job", "KINDS", "COLUMNS", "grid", "run_job", "run", "table"]
