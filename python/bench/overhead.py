"""One call's cost from Python against the same call from Rhai and from Rust, in one
run (docs/performance.md, "Python").

Run from the repository root, in the virtualenv holding the module:

    python python/bench/overhead.py            # runs the Rust bench first
    python python/bench/overhead.py --no-rust  # Python and Rhai only
    python python/bench/overhead.py --bench-bin PATH  # that bench binary, not cargo's

`FITUP_CALLS=ik_ur5e,floor` runs only the calls named (here and in the Rust bench).

The Rust and Rhai columns come from `cargo bench --profile dev --bench call_overhead`
(tests/bench/call_overhead.rs), started by this script, the dev profile being the one
`.ci/run` builds the module with; the Python column and a second Rhai column (through
`fitup.run_script` in this process, the module's own build) are timed here right
after. The set-up script, the UR5e and the Rhai calls are the Rust bench's files
(tests/bench/call_overhead/). Calls: FK of the demo MZ07 (`Robot.fk`), IK of every
branch (`Robot.ik`; the MZ07, and a UR5e of the published D-H lengths without
limits; the UR5e's `ik_near` and the script's `ik_solutions` from Rhai and Rust
only; `ik_each_ur5e` times `Robot.ik` against Rust's `inverse_each`), an
interference check of one pair of the demo cell (`Document.interferes`), a short plan
(screw5 lifted 40 mm, RRT-Connect, seed 3), the floor (a trivial call: `Robot.dof`,
Rhai's `q.len()`), and the batch forms per pose (`fk_batch`, `ik_batch`, 20 000
poses). Medians of 7 rounds of CPU time: the calling thread's for Python
(`time.thread_time_ns`, as the Rust bench), the process's for `run_script` (the script
runs on a thread of its own); Rhai figures minus the same loop binding the loop
counter, as in the Rust bench.
"""

import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

# numpy's BLAS threads spin between calls and take a core from the timed loop.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import fitup  # noqa: E402

ROUNDS = 7
REPO = pathlib.Path(__file__).resolve().parents[2]

# The set-up script, the UR5e and the Rhai calls of tests/bench/call_overhead.rs.
SHARED = REPO / "tests" / "bench" / "call_overhead"
SETUP = (SHARED / "setup.rhai").read_text()
UR5E_YAML = (SHARED / "ur5e.yaml").read_text()
RHAI = {}
for line in (SHARED / "calls.txt").read_text().splitlines():
    if line and not line.startswith("#"):
        name, n, expr = line.split(" ", 2)
        RHAI[name] = (expr, int(n))
N_KINEMATICS = RHAI["fk"][1]
UR5E_Q = [10.0, -60.0, 80.0, -110.0, -70.0, 30.0]


def loadavg():
    return pathlib.Path("/proc/loadavg").read_text().split()[:3]


ONLY = os.environ.get("FITUP_CALLS")


def wanted(name):
    return ONLY is None or name in ONLY.split(",")


def median_ns(f, n):
    out = []
    for _ in range(ROUNDS):
        t0 = time.thread_time_ns()
        for _ in range(n):
            f()
        out.append((time.thread_time_ns() - t0) / n)
    return statistics.median(out)


def median_batch_ns(f, n):
    out = []
    for _ in range(ROUNDS):
        t0 = time.thread_time_ns()
        f()
        out.append((time.thread_time_ns() - t0) / n)
    return statistics.median(out)


def rhai_ns(project, call, n):
    def cpu(expr):
        script = project / "scripts" / "bench.rhai"
        script.write_text(SETUP + f"for i in 0..{n} {{ let x = {expr}; }}\n")
        t0 = time.process_time()
        fitup.run_script(script, max_operations=0)
        return time.process_time() - t0

    out = []
    for _ in range(ROUNDS):
        out.append((cpu(call) - cpu("i")) / n * 1e9)
    return statistics.median(out)


def rust_rows():
    """`CALL name rust rhai` lines of the Rust bench, by name."""
    cmd = ["cargo", "bench", "--profile", "dev", "--bench", "call_overhead"]
    if "--bench-bin" in sys.argv:
        cmd = [sys.argv[sys.argv.index("--bench-bin") + 1]]
    print("$", " ".join(cmd), " # load", *loadavg(), flush=True)
    out = subprocess.run(cmd, cwd=REPO, check=True, capture_output=True, text=True).stdout
    rows = {}
    for line in out.splitlines():
        if line.startswith("CALL "):
            _, name, rust, rhai = line.split()
            rows[name] = (float(rust), float(rhai))
    return rows


def main():
    rust = {} if "--no-rust" in sys.argv else rust_rows()
    print("python calls, load", *loadavg(), flush=True)
    arm = fitup.Document(REPO / "models" / "mz07.yaml").robot("mz07")
    q = np.radians([10.0, -20.0, 30.0, 40.0, -50.0, 60.0])
    t = arm.fk(q)
    cell = fitup.Document(REPO / "models" / "cell.yaml")
    goal = fitup.translation(0, 0, 40) @ cell.pose("screw5")
    assert cell.plan_path("screw5", goal, planner="rrt_connect", seed=3).found
    assert len(arm.ik(t, q)) > 1
    with tempfile.TemporaryDirectory() as d:
        (pathlib.Path(d) / "ur5e.yaml").write_text(UR5E_YAML)
        ur = fitup.Document(pathlib.Path(d) / "ur5e.yaml").robot("ur5e")
    uq = np.radians(UR5E_Q)
    tu = ur.fk(uq)
    assert len(ur.ik(tu, uq)) > 1
    # The Python call of each name of calls.txt (Python has no `ik_near` and no
    # `ik_solutions`: its `ik` returns one array).
    calls = {
        "fk": lambda: arm.fk(q),
        "ik_all": lambda: arm.ik(t, q),
        "ik_ur5e": lambda: ur.ik(tu, uq),
        # The same call against Rust's `inverse_each` into a stack array.
        "ik_each_ur5e": lambda: ur.ik(tu, uq),
        "floor": lambda: arm.dof,
        "interferes": lambda: cell.interferes("screw4", "screw5"),
        "plan_short": lambda: cell.plan_path("screw5", goal, planner="rrt_connect", seed=3),
    }
    py = {k: median_ns(f, RHAI[k][1]) for k, f in calls.items() if wanted(k)}
    qs = np.tile(q, (N_KINEMATICS, 1))
    ts = np.tile(t, (N_KINEMATICS, 1, 1))
    batches = {
        "fk": lambda: arm.fk_batch(qs),
        "ik_all": lambda: arm.ik_batch(ts, q),
    }
    batch = {k: median_batch_ns(f, N_KINEMATICS) for k, f in batches.items() if wanted(k)}
    with tempfile.TemporaryDirectory() as d:
        p = pathlib.Path(d)
        (p / "fitup.toml").write_text("")
        (p / "scripts").mkdir()
        shutil.copytree(REPO / "models", p / "models")
        (p / "models" / "ur5e.yaml").write_text(UR5E_YAML)
        rh = {k: rhai_ns(p, call, n) for k, (call, n) in RHAI.items() if wanted(k)}
    print("done, load", *loadavg())
    print()
    print(
        "ns per call | Rust | Rhai (cargo bench) | Rhai (in Python) | Python | Python − Rust"
        " | Python / Rust"
    )
    print("---|---|---|---|---|---|---")
    for k in rh:
        r, rb = rust.get(k, (float("nan"), float("nan")))
        p = py.get(k, float("nan"))
        ratio = p / r if r > 0 else float("nan")
        print(f"{k} | {r:.0f} | {rb:.0f} | {rh[k]:.0f} | {p:.0f} | {p - r:.0f} | {ratio:.2f}")
    for k in batch:
        r = rust.get(k, (float("nan"),))[0]
        print(f"{k} batch, per pose | {r:.0f} | | | {batch[k]:.0f} | {batch[k] - r:.0f}")


if __name__ == "__main__":
    main()
