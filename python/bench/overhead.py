"""A Python call's overhead against the same call from Rhai (in the same process,
through fitup.run_script) — the Rust side is `cargo bench --bench robot_script`, run
back to back (docs/performance.md, "Python").

Run from the repository root: python python/bench/overhead.py
Calls: FK of the demo MZ07 (`Robot.fk` vs `arm.fk(q)`), nearest IK (`Robot.ik_path`
of one pose vs `arm.ik_near(t, q)`), and the batch forms per pose (`fk_batch`,
`ik_path` of 20 000 poses vs `fk_many`, `ik_many`). Medians of 7 rounds of 20 000
calls, wall clock; Rhai figures minus an empty loop of the same shape, as in the Rust
bench.
"""

import pathlib
import statistics
import tempfile
import time

import numpy as np

import fitup

N = 20_000
ROUNDS = 7
REPO = pathlib.Path(__file__).resolve().parents[2]


def median_ns(f, n=N):
    out = []
    for _ in range(ROUNDS):
        t0 = time.perf_counter()
        f()
        out.append((time.perf_counter() - t0) / n * 1e9)
    return statistics.median(out)


def rhai_ns(project, body, empty, n=N):
    setup = (
        'let d = open_doc("models/mz07.yaml");\nlet arm = d.robot("mz07");\n'
        "let q = [10.0, -20.0, 30.0, 40.0, -50.0, 60.0];\nlet t = arm.fk(q);\n"
    )
    (project / "call.rhai").write_text(setup + body + "\n")
    (project / "empty.rhai").write_text(setup + empty + "\n")

    def wall(script):
        t0 = time.perf_counter()
        fitup.run_script(project / script, max_operations=0)
        return time.perf_counter() - t0

    out = []
    for _ in range(ROUNDS):
        out.append((wall("call.rhai") - wall("empty.rhai")) / n * 1e9)
    return statistics.median(out)


def main():
    doc = fitup.Document(REPO / "models" / "mz07.yaml")
    arm = doc.robot("mz07")
    q = np.radians([10.0, -20.0, 30.0, 40.0, -50.0, 60.0])
    t = arm.fk(q)
    qs = np.tile(q, (N, 1))
    ts = np.tile(t, (N, 1, 1))
    one = t[None]

    def fk():
        for _ in range(N):
            arm.fk(q)

    def ik():
        for _ in range(N):
            arm.ik_path(one, q)

    py = {
        "fk": median_ns(fk),
        "ik_near": median_ns(ik),
        "fk_many": median_ns(lambda: arm.fk_batch(qs)),
        "ik_many": median_ns(lambda: arm.ik_path(ts, q)),
    }
    with tempfile.TemporaryDirectory() as d:
        p = pathlib.Path(d)
        (p / "fitup.toml").write_text("")
        fitup_models = p / "models"
        import shutil

        shutil.copytree(REPO / "models", fitup_models)
        loop = f"for i in 0..{N} {{ let x = CALL; }}"
        rh = {
            "fk": rhai_ns(p, loop.replace("CALL", "arm.fk(q)"), loop.replace("CALL", "q")),
            "ik_near": rhai_ns(p, loop.replace("CALL", "arm.ik_near(t, q)"), loop.replace("CALL", "q")),
            "fk_many": rhai_ns(
                p,
                f"let qs = []; for i in 0..{N} {{ qs.push(q); }}\nfor k in 0..10 {{ let x = arm.fk_many(qs); }}",
                f"let qs = []; for i in 0..{N} {{ qs.push(q); }}\nfor k in 0..10 {{ let x = 0; }}",
                n=10 * N,
            ),
            "ik_many": rhai_ns(
                p,
                f"let ts = []; for i in 0..{N} {{ ts.push(t); }}\nfor k in 0..10 {{ let x = arm.ik_many(ts); }}",
                f"let ts = []; for i in 0..{N} {{ ts.push(t); }}\nfor k in 0..10 {{ let x = 0; }}",
                n=10 * N,
            ),
        }
    print("call        python ns   rhai ns")
    for k in py:
        print(f"{k:10} {py[k]:10.0f} {rh[k]:9.0f}")


if __name__ == "__main__":
    main()
