"""The native module: documents, interference, sweeps, planning, robots, programs,
sequences, the results database, scripts, and the typed errors."""

import math
import pathlib
import shutil
import pickle
import re
import threading
import time

import numpy as np
import pytest

import fitup
from conftest import MODELS, REPO

CELL = MODELS / "cell.yaml"


def test_poses_are_column_vector_matrices_of_the_document():
    yaml = pytest.importorskip("yaml")
    doc = fitup.Document(CELL)
    assert "screw4" in doc.components() and "plate_b" in doc.parts()
    raw = {c["name"]: c for c in yaml.safe_load(CELL.read_text())["components"]}
    for name in ("table", "screw5"):
        t = doc.pose(name)
        m = np.array(raw[name]["transform"], dtype=float)
        # The document's SolidWorks matrix acts on row vectors; ours is its transpose.
        assert np.allclose(t, m.T, atol=1e-9), name
        assert np.array_equal(t[3], [0, 0, 0, 1])
    c = doc.component("screw5")
    assert c["part"] == "screw" and not c["fixed"]
    assert np.array_equal(c["pose"], doc.pose("screw5"))


def test_a_reference_is_posed_by_the_component_pose():
    doc = fitup.Document(CELL)
    world = doc.reference("plate_b", "hole1")
    t = doc.pose("plate_b")
    moved = fitup.translation(0, 0, 25) @ t
    doc.set_pose("plate_b", moved)
    again = doc.reference("plate_b", "hole1")
    assert np.allclose(again["point"], world["point"] + [0, 0, 25], atol=1e-9)


def test_system_value_drives_the_angle_mate_in_si_units():
    doc = fitup.Document(CELL)
    doc.set_system_value("D1@角度1", math.radians(30))
    assert doc.system_value("D1@角度1") == pytest.approx(math.radians(30))
    d = doc.dimension("D1@角度1")
    assert d["kind"] == "angle" and d["document_value"] == pytest.approx(30)
    t = doc.pose("plate_b")
    assert math.degrees(math.atan2(t[1, 0], t[0, 0])) == pytest.approx(30, abs=1e-6)


def test_interference_contact_clearance_and_sweep():
    doc = fitup.Document(CELL)
    assert doc.interferences() == []
    assert not doc.interferes("screw1", "plate_a")
    gap = doc.clearance("screw4", "screw5")
    assert 0 < gap < 50
    assert doc.contact("screw4", "screw5")["state"] == "separate"
    # Slide screw5 60 mm along -X: it meets screw4 first.
    to = fitup.translation(-60, 0, 0) @ doc.pose("screw5")
    hit = doc.sweep("screw5", to[None])
    assert hit["hit"] and hit["with"] == "screw4" and 0 < hit["t"] < 1
    # Put screw5 onto screw4: they interfere, deeper than the tolerance.
    doc.set_pose("screw5", doc.pose("screw4"))
    assert doc.interferes("screw4", "screw5")
    c = doc.contact("screw4", "screw5")
    assert c["state"] == "interfering" and c["depth_mm"] > 0.01
    pairs = {(p["a"], p["b"]) for p in doc.interferences()}
    assert ("screw4", "screw5") in pairs


def test_plan_path_is_free_deterministic_and_revalidates():
    doc = fitup.Document(CELL)
    start = doc.pose("screw4")
    goal = fitup.translation(*doc.reference("plate_b", "hole1")["point"])
    path = doc.plan_insertion("screw4", goal, seed=1, smoothing=False, time_limit_ms=30000)
    assert path.found, path.reason
    poses = path.poses
    assert poses.shape[1:] == (4, 4) and len(path) == poses.shape[0] >= 2
    assert np.allclose(poses[0], start) and np.allclose(poses[-1], goal)
    assert doc.revalidate(path)["ok"]
    # Every pose along it (2 mm apart) is free: an independent static re-check.
    for t in path.densify(2.0):
        doc.set_pose("screw4", t)
        assert doc.interferences() == [], t
    doc.set_pose("screw4", start)
    again = doc.plan_insertion("screw4", goal, seed=1, smoothing=False, time_limit_ms=30000)
    assert np.array_equal(again.poses, poses)
    assert path.to_dict()["key_poses"] == len(path)
    # Following it seats the screw.
    doc.follow(path, 10.0)
    assert np.allclose(doc.pose("screw4"), goal)


def test_plan_path_and_disassembly_return_paths():
    doc = fitup.Document(CELL)
    goal = fitup.translation(0, 0, 40) @ doc.pose("screw5")
    p = doc.plan_path("screw5", goal, planner="rrt_connect", seed=3)
    assert p.found and p.planner.endswith("rrt_connect") and p.seed == 3
    d = doc.plan_disassembly("screw1", time_limit_ms=20000, seed=2)
    assert isinstance(d, fitup.Path)
    if d.found:
        assert np.allclose(d.poses[-1], doc.pose("screw1"))
    assert "rrt_connect" in fitup.planner_names()


def test_fixed_components_and_bad_options_are_refused():
    doc = fitup.Document(CELL)
    with pytest.raises(fitup.WorkspaceError, match="fixed"):
        doc.plan_path("table", np.eye(4))
    with pytest.raises(fitup.InputError, match="time_limit"):
        doc.plan_path("screw5", doc.pose("screw5"), time_limt_ms=5)
    with pytest.raises(fitup.InputError, match="planner"):
        doc.plan_path("screw5", doc.pose("screw5"), planner="rrt_conect")
    with pytest.raises(fitup.DocumentError, match="screw5"):
        doc.pose("screw55")


def test_bad_arrays_are_input_errors_and_value_errors():
    doc = fitup.Document(CELL)
    with pytest.raises(fitup.InputError, match=r"\(4, 4\)"):
        doc.set_pose("screw5", np.eye(3))
    scaled = np.eye(4) * 2
    scaled[3, 3] = 1
    with pytest.raises(ValueError, match="rigid"):
        doc.set_pose("screw5", scaled)
    nan = np.eye(4)
    nan[0, 3] = np.nan
    with pytest.raises(fitup.InputError):
        doc.set_pose("screw5", nan)


def test_a_bad_document_raises_a_located_error(tmp_path):
    (tmp_path / "fitup.toml").write_text("")
    bad = tmp_path / "bad.yaml"
    bad.write_text("parts:\n  a:\n    stl: missing.stl\ncomponents:\n  - name: [oops\n")
    with pytest.raises(fitup.DocumentError) as e:
        fitup.Document(bad)
    assert e.value.file.endswith("bad.yaml") and e.value.line is not None
    back = pickle.loads(pickle.dumps(e.value))
    assert type(back) is fitup.DocumentError
    assert (back.file, back.line, back.column, str(back)) == (
        e.value.file, e.value.line, e.value.column, str(e.value))


def test_save_as_writes_a_document_that_loads_again(project):
    doc = fitup.Document(project / "models" / "cell.yaml")
    moved = fitup.translation(5, 0, 0) @ doc.pose("screw5")
    doc.set_pose("screw5", moved)
    out = project / "models" / "cell_moved.yaml"
    doc.save_as(out)
    assert np.allclose(fitup.Document(out).pose("screw5"), moved)


def test_exports_and_save_as_never_replace_the_documents_sources(project):
    """A file the document was read from is never replaced, not even with overwrite."""
    models = project / "models"
    (models / "sub").mkdir()
    (models / "sub" / "sub.yaml").write_text(
        "parts:\n  plate:\n    stl: ../meshes/plate_a.stl\n"
        "components:\n- name: plate\n  part: plate\n  fixed: true\n")
    (models / "top.yaml").write_text(
        "parts:\n  screw:\n    stl: meshes/screw.stl\n"
        "assemblies:\n- name: Sub-1\n  file: sub/sub.yaml\n"
        "components:\n- name: screw\n  part: screw\n  fixed: true\n")
    doc = fitup.Document(models / "top.yaml")
    sources = [models / "top.yaml", models / "sub" / "sub.yaml", models / "meshes" / "screw.stl",
               models / "meshes" / "plate_a.stl", models / "sub" / ".." / "meshes" / "screw.stl"]
    before = {p: p.read_bytes() for p in sources}
    writers = {
        "export_stl": lambda p: doc.export_stl(p, overwrite=True),
        "export_stl components": lambda p: doc.export_stl(p, ["screw"], overwrite=True),
        "export_glb": lambda p: doc.export_glb(p, overwrite=True),
        "export_glb components": lambda p: doc.export_glb(p, True, components=["screw"]),
    }
    for target in sources:
        for name, write in writers.items():
            with pytest.raises(fitup.DocumentError, match="a source of the open document") as e:
                write(target)
            assert target.name in str(e.value), (name, str(e.value))
        if target != models / "top.yaml":
            with pytest.raises(fitup.DocumentError, match="a source of the open document"):
                doc.save_as(target)
    assert {p: p.read_bytes() for p in sources} == before
    # overwrite still replaces an earlier output and a user's file that is no source
    out = project / "out"
    out.mkdir()
    doc.export_glb(out / "own.glb")
    assert doc.export_glb(out / "own.glb", overwrite=True) == 2
    (out / "mine.stl").write_bytes(b"mine")
    with pytest.raises(fitup.DocumentError, match="refusing to overwrite"):
        doc.export_stl(out / "mine.stl")
    assert (out / "mine.stl").read_bytes() == b"mine"
    doc.export_stl(out / "mine.stl", overwrite=True)
    assert (out / "mine.stl").read_bytes()[:5] != b"mine"


def test_robot_fk_and_every_ik_branch():
    r = fitup.Robot.catalog("nachi_mz07")
    assert r.dof == 6 and r.solver == "opw"
    q = np.radians([10, -20, 30, 40, -50, 60])
    t = r.fk(q)
    branches = r.ik(t, reference=q)
    assert branches.shape[1] == 6 and branches.shape[0] >= 2
    assert np.allclose(branches[0], q, atol=1e-7)  # sorted by distance to the reference
    for b in branches:
        assert np.allclose(r.fk(b), t, atol=1e-6)
    batch = r.fk_batch(np.stack([q, q * 0.5, np.zeros(6)]))
    assert np.allclose(batch[1], r.fk(q * 0.5))
    per = r.ik_batch(batch)
    assert len(per) == 3 and all(len(p) >= 1 for p in per)
    unreachable = fitup.translation(1e5, 0, 0)
    assert r.ik(unreachable).shape == (0, 6)
    with pytest.raises(fitup.RobotError, match="6 joint values"):
        r.fk(np.zeros(5))
    assert "ur5" in fitup.catalog_names()


def test_ik_gives_the_library_solutions_to_the_bit():
    # `ik` writes each solution's joints straight from the solver (no list per
    # solution); `ik_batch` goes through the library's `Robot::inverse`: the same
    # solutions, in the same order, to the bit, each reproducing the target. The
    # catalog UR5's ±360° limits give more than eight solutions (past the stack store).
    rng = np.random.default_rng(38)
    for name in ("nachi_mz07", "ur5"):
        r = fitup.Robot.catalog(name)
        most = 0
        for _ in range(20):
            q = rng.uniform(-math.pi, math.pi, 6)
            if r.limit_violation(q) is not None:
                continue
            t = r.fk(q)
            for ref in (q, np.zeros(6)):
                branches = r.ik(t, ref)
                assert np.array_equal(branches, r.ik_batch(t[None], ref)[0]), name
                most = max(most, len(branches))
                for b in branches:
                    assert np.allclose(r.fk(b), t, atol=1e-6), name
        assert most > (8 if name == "ur5" else 1), (name, most)


def test_ik_along_a_path_follows_the_line():
    r = fitup.Robot.catalog("nachi_mz07")
    q0 = np.radians([0, 10, -10, 0, 30, 0])
    start = r.fk(q0)
    line = np.stack([fitup.translation(0, 2.0 * k, 0) @ start for k in range(50)])
    q = r.ik_path(line, start=q0)
    assert q.shape == (50, 6) and not np.isnan(q).any()
    assert np.allclose(r.fk_batch(q), line, atol=1e-6)
    assert np.abs(np.diff(q, axis=0)).max() < math.radians(5)  # one branch, no flips


def test_a_program_runs_on_the_document_robot():
    doc = fitup.Document(MODELS / "mz07.yaml")
    assert doc.robots() == ["mz07"]
    traj = doc.run_program("mz07", MODELS / "mz07_demo.prg")
    t, q, tcp = traj["t"], traj["joints"], traj["tcp"]
    assert len(t) == len(q) == len(tcp) > 10 and (np.diff(t) >= 0).all()
    robot = doc.robot("mz07")
    assert np.allclose(robot.fk_batch(q[:5]), tcp[:5], atol=1e-6)
    assert np.allclose(doc.joints("mz07"), q[-1])
    with pytest.raises(fitup.RobotError) as e:
        doc.run_program("mz07", text="Joint 0 0 0 0 0 0\nLine 1e6 0 0 0 0 0\n")
    assert e.value.line == 2


def test_sequence_of_the_wheel():
    doc = fitup.Document(MODELS / "wheel.yaml")
    plan = doc.plan_sequence()
    assert plan["sequences"][0]["order"] == ["axis", "gear", "cup"]
    assert plan["sequences"][0]["mounts"] == 0


def test_results_database_round_trip(tmp_path):
    db = fitup.Database(str(tmp_path / "fitup.db"))
    doc = fitup.Document(CELL)
    goal = fitup.translation(0, 0, 40) @ doc.pose("screw5")
    path = doc.plan_path("screw5", goal, seed=7)
    run = db.start_run("python test", str(CELL))
    pid = db.save_path("lift", path, run_id=run)
    db.finish_run(run, "ok", "stored one path")
    (stored,) = db.paths(name="lift")
    assert stored["id"] == pid and stored["run_id"] == run and stored["seed"] == 7
    assert np.allclose(stored["poses"], path.poses, atol=1e-12)
    assert [r["status"] for r in db.runs()] == ["ok"]
    cols, rows = db.query("SELECT name, component FROM paths WHERE id = ?", [pid])
    assert cols == ["name", "component"] and rows == [["lift", "screw5"]]
    with pytest.raises(fitup.DatabaseError):
        db.query("DELETE FROM paths")


def test_run_script_with_arguments_and_located_failure(project):
    (project / "twice.rhai").write_text(
        'print(`${args.n * 2} ${args.name}`);\nassert(args.fast, "fast is off");\n'
    )
    r = fitup.run_script(project / "twice.rhai", args={"n": 3, "name": "x", "fast": True})
    assert r["output"] == ["6 x"]
    with pytest.raises(fitup.ScriptError) as e:
        fitup.run_script(project / "twice.rhai", args={"n": 1, "name": "y", "fast": False})
    assert e.value.file.endswith("twice.rhai") and e.value.line == 2
    assert e.value.output == ["2 y"]
    db = project / "runs.db"
    fitup.run_script(
        project / "twice.rhai", doc=project / "models" / "cell.yaml",
        args={"n": 1, "name": "z", "fast": True}, db=str(db),
    )
    (run,) = fitup.Database(str(db)).runs()
    assert run["status"] == "ok" and "2 z" in run["output"]


def test_run_script_stops_at_its_time_limit(project):
    (project / "forever.rhai").write_text('print("started");\nlet x = 0;\nloop { x += 1; }\n')
    t0 = time.monotonic()
    with pytest.raises(fitup.ScriptError) as e:
        # No operation limit: only the time limit can stop the loop.
        fitup.run_script(project / "forever.rhai", max_operations=0, max_seconds=1)
    assert time.monotonic() - t0 < 30
    assert "time limit of 1 s" in e.value.cause and "max_seconds" in e.value.cause, e.value.cause
    assert e.value.file.endswith("forever.rhai") and e.value.line == 3
    assert e.value.output == ["started"]


def test_long_calls_release_the_gil(project):
    (project / "spin.rhai").write_text("let x = 0;\nfor i in 0..3000000 { x += 1; }\nprint(x);\n")
    done = threading.Event()
    out = {}

    def work():
        out["r"] = fitup.run_script(project / "spin.rhai")
        done.set()

    th = threading.Thread(target=work)
    th.start()
    ticks = 0
    while not done.is_set():
        ticks += 1  # runs only while the script's thread does not hold the GIL
    th.join()
    assert out["r"]["output"] == ["3000000"]
    assert ticks > 10_000, ticks


def test_the_readme_python_example_runs_as_written(monkeypatch, capsys):
    text = (REPO / "README.md").read_text()
    block = text.split("### From Python", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(REPO)
    exec(compile(block, "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert out.startswith("Path(lazy_rrt_connect: ") and out.rstrip().endswith(", 4, 4)")


def test_ik_of_a_numeric_robot_gives_every_branch_it_finds(tmp_path):
    # models/urdf's arm with its wrist moved 40 mm off the forearm's axis: no closed
    # form. `ik` asks the numeric solver for every solution (as a script's `ik`
    # does), not only the first one it finds.
    urdf = (MODELS / "urdf" / "fitup_arm6.urdf").read_text()
    urdf = re.sub(r'<link name="(\w+)">.*?</link>', r'<link name="\1"/>', urdf)
    wrist = '<origin xyz="0.55 0 0" rpy="0 0 0"/><parent link="link_4"/>'
    assert wrist in urdf
    (tmp_path / "arm.urdf").write_text(urdf.replace(wrist, wrist.replace("0.55 0 0", "0.55 0.04 0")))
    (tmp_path / "fitup.toml").write_text("")
    (tmp_path / "arm.yaml").write_text(
        "parts: {}\ncomponents: []\nrobots:\n- name: arm\n  urdf: arm.urdf\n")
    r = fitup.Document(tmp_path / "arm.yaml").robot("arm")
    assert r.solver == "numeric"
    q = np.array([0.3, -0.4, 0.6, 0.5, -0.7, 0.2])
    t = r.fk(q)
    branches = r.ik(t, reference=q)
    assert branches.shape[0] >= 2 and branches.shape[1] == 6
    assert np.allclose(branches[0], q, atol=1e-6)  # nearest the reference first
    assert len({tuple(np.round(b, 4)) for b in branches}) == branches.shape[0]
    for b in branches:
        assert np.allclose(r.fk(b), t, atol=1e-5)
        assert r.limit_violation(b) is None


def test_batch_forms_read_any_layout_of_their_arrays():
    # C-ordered arrays are read in place; Fortran-ordered and strided views (a copy
    # of each row) give the same answers.
    r = fitup.Robot.catalog("nachi_mz07")
    q = np.radians(np.linspace(-40, 40, 60).reshape(10, 6))
    want = r.fk_batch(q)
    assert want.flags["C_CONTIGUOUS"] and want.shape == (10, 4, 4)
    for view in (np.asfortranarray(q), np.repeat(q, 2, axis=0)[::2], q.astype(np.float32)):
        assert np.allclose(r.fk_batch(view), want, atol=1e-3 if view.dtype == np.float32 else 0)
    poses = np.asfortranarray(want)
    per = r.ik_batch(poses, reference=q[0])
    assert [len(p) > 0 for p in per] == [True] * 10
    assert np.allclose(r.ik_path(poses[::-1], start=q[-1]), q[::-1], atol=1e-7)


def ticks_during(call):
    """Main-thread loop turns stamped while `call` ran in another thread, 10 ms in
    from each end of the call (a thread holding the GIL through a native call lets
    none happen there), the window's length in s, and the call's result."""
    window = {}
    done = threading.Event()

    def work():
        window["start"] = time.perf_counter()
        window["result"] = call()
        window["end"] = time.perf_counter()
        done.set()

    stamps = []
    th = threading.Thread(target=work)
    th.start()
    while not done.is_set():
        stamps.append(time.perf_counter())
    th.join()
    lo, hi = window["start"] + 0.01, window["end"] - 0.01
    return sum(lo < s < hi for s in stamps), hi - lo, window["result"]


def test_long_library_calls_release_the_gil():
    cell = fitup.Document(CELL)
    goal = fitup.translation(*cell.reference("plate_b", "hole1")["point"])
    wheel = fitup.Document(MODELS / "wheel.yaml")
    r = fitup.Robot.catalog("nachi_mz07")
    q = np.radians([10, -20, 30, 40, -50, 60])
    poses = np.tile(r.fk(q), (40_000, 1, 1))
    calls = {
        "plan_insertion": lambda: cell.plan_insertion(
            "screw4", goal, seed=1, smoothing=False, time_limit_ms=30000).found,
        "plan_sequence": lambda: len(wheel.plan_sequence(max_sequences=50)["sequences"]),
        "ik_batch": lambda: len(r.ik_batch(poses, reference=q)),
        "ik_path": lambda: len(r.ik_path(poses, start=q)),
    }
    for name, call in calls.items():
        ticks, window, result = ticks_during(call)
        assert result, name
        if window > 0.02:  # long enough here to tell
            assert ticks > 0, (name, window)


def test_the_stubs_name_every_public_member_and_each_says_its_units():
    import ast

    tree = ast.parse((REPO / "python" / "fitup" / "_fitup.pyi").read_text())
    stubs = {
        c.name: {f.name: ast.unparse(f) for f in c.body if isinstance(f, ast.FunctionDef)}
        for c in tree.body
        if isinstance(c, ast.ClassDef)
    }
    functions = {f.name for f in tree.body if isinstance(f, ast.FunctionDef)}
    native = fitup._fitup
    assert functions == {n for n in dir(native) if callable(getattr(native, n))
                         and not n.startswith("_") and n not in stubs}
    for cls, members in stubs.items():
        public = {n for n in dir(getattr(native, cls)) if not n.startswith("_")}
        assert public == {n for n in members if not n.startswith("_")}, cls
        for n in public:
            doc = getattr(native, cls).__dict__[n].__doc__
            assert doc and doc.strip(), f"{cls}.{n} has no docstring"
            # A member taking poses says their unit (and the docstrings their frame).
            if "_Pose" in members[n]:
                assert "mm" in doc, f"{cls}.{n}: {doc}"


def test_the_stub_docstrings_are_the_modules():
    """Editors show the stubs' docstrings: each is the native member's own text
    (the Rust doc comment), so the two cannot drift apart. On a mismatch run
    ``python python/tools/stub_docs.py``."""
    import ast
    import inspect

    tree = ast.parse((REPO / "python" / "fitup" / "_fitup.pyi").read_text())
    native = fitup._fitup
    seen = 0
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            items = [(node, getattr(native, node.name))]
        elif isinstance(node, ast.ClassDef):
            cls = getattr(native, node.name)
            items = [(node, cls)] + [
                (m, cls.__dict__[m.name])
                for m in node.body
                if isinstance(m, ast.FunctionDef) and not m.name.startswith("_")
            ]
        else:
            continue
        for stub, obj in items:
            # A static or class method's own ``__doc__`` is its wrapper type's.
            obj = getattr(obj, "__func__", obj)
            want = inspect.cleandoc(obj.__doc__)
            assert ast.get_docstring(stub) == want, (
                f"{stub.name}: the stub's docstring differs from the module's; "
                "run `python python/tools/stub_docs.py`"
            )
            seen += 1
    assert seen > 50, seen


def test_keyword_values_of_the_wrong_type_name_the_keyword_and_what_it_takes():
    doc = fitup.Document(CELL)
    goal = doc.pose("screw5")
    # The library's vocabulary words, the same a script gets: the key, the value,
    # what the key takes (with its unit).
    cases = [
        ({"seed": "x"}, 'planning option `seed` must be a whole number ≥ 0, not "x"'),
        ({"seed": -1}, "planning option `seed` must be a whole number ≥ 0, not -1"),
        ({"time_limit_ms": "soon"},
         'planning option `time_limit_ms` must be a number (ms), not "soon"'),
        ({"smoothing": "yes"}, 'planning option `smoothing` must be true or false, not "yes"'),
        ({"planner": 3}, "planning option `planner` must be one of `greedy_ant`"),
        ({"start": "here"}, "planning option `start` must be a 4x4 array of numbers, not 'here'"),
        ({"bounds": [[0, 0, 0], [0, 1, 1]]},
         "planning option `bounds` must be a box (min below max on every axis) (mm), not "),
    ]
    for kw, message in cases:
        with pytest.raises(fitup.InputError) as e:
            doc.plan_path("screw5", goal, **kw)
        assert str(e.value).startswith(message), (kw, str(e.value))
    wheel = fitup.Document(MODELS / "wheel.yaml")
    with pytest.raises(fitup.InputError,
                       match='sequence option `order` must be an array of names, not "axis"'):
        wheel.plan_sequence(order="axis")
    with pytest.raises(fitup.InputError,
                       match=r'sequence option `gravity` must be 3 numbers \[x, y, z\], not "down"'):
        wheel.plan_sequence(gravity="down")


def test_mass_properties_equal_trimesh_and_overlap_reads_the_push():
    """Mass properties against trimesh (when installed: CI installs it) to 1e-6,
    and the interference depth of a screw pushed 5 mm into the table."""
    doc = fitup.Document(MODELS / "cell.yaml")
    m = doc.mass_properties(["table"], density=2700.0)
    table = doc.component("table")
    assert m["mass_kg"] == pytest.approx(m["volume_mm3"] * 2700.0e-9, rel=1e-12)
    try:
        import trimesh
    except ImportError:
        trimesh = None
    if trimesh is not None:
        mesh = trimesh.load(MODELS / "meshes" / "table.stl", process=False, force="mesh")
        mesh.apply_transform(table["pose"])
        ref = trimesh.triangles.mass_properties(mesh.triangles, density=2700.0e-9)
        assert m["volume_mm3"] == pytest.approx(ref["volume"], rel=1e-6)
        assert m["mass_kg"] == pytest.approx(ref["mass"], rel=1e-6)
        np.testing.assert_allclose(m["centre_of_mass"], ref["center_mass"], rtol=1e-6, atol=1e-6)
        scale = np.abs(ref["inertia"]).max()
        np.testing.assert_allclose(m["inertia"], ref["inertia"], rtol=0, atol=1e-6 * scale)
    # in the table's own frame the centre of mass is the part's
    local = doc.mass_properties(["table"], density=2700.0, frame=table["pose"])
    assert local["mass_kg"] == pytest.approx(m["mass_kg"])
    pose = doc.pose("screw4")
    pose[2, 3] -= 5.0
    doc.set_pose("screw4", pose)
    o = doc.overlap("screw4", "table")
    assert o["depth_mm"] == pytest.approx(5.0, abs=1e-6)
    assert o["direction"] == pytest.approx([0.0, 0.0, 1.0], abs=1e-9)
    assert o["volume_mm3"] > 0
    assert doc.contact("screw4", "table")["depth_mm"] == pytest.approx(5.0, abs=1e-6)


def glb_nodes(path):
    """The component nodes of a GLB fitup wrote (the root's children), by name:
    ``(matrix or None, vertices (N, 3) mm, triangles (M, 3))``, read from the file's
    own JSON and binary chunks."""
    import json
    import struct

    data = path.read_bytes()
    assert data[:4] == b"glTF"
    size = struct.unpack_from("<I", data, 12)[0]
    meta = json.loads(data[20:20 + size])
    blob = 20 + size + 8

    def array(accessor, kind, width):
        a = meta["accessors"][accessor]
        view = meta["bufferViews"][a["bufferView"]]
        at = blob + view["byteOffset"] + a.get("byteOffset", 0)
        return np.frombuffer(data, kind, a["count"] * (3 if a["type"] == "VEC3" else 1),
                             at).reshape(-1, width)

    nodes = {}
    for k in meta["nodes"][0]["children"]:
        node = meta["nodes"][k]
        prim = meta["meshes"][node["mesh"]]["primitives"][0]
        vertices = array(prim["attributes"]["POSITION"], "<f4", 3).astype(float) * 1000.0
        triangles = array(prim["indices"], "<u4", 3).astype(float)
        nodes[node["name"]] = (node.get("matrix"), vertices, triangles)
    return nodes


def test_the_solidworks_document_edits(project):
    """Issue 37 from Python: mates as objects, suppression and visibility, custom
    properties, added/renamed/replaced components, world meshes and exports."""
    doc = fitup.Document(project / "models" / "cell.yaml")
    mates = {m["name"]: m for m in doc.mates()}
    assert mates["screw1_seated"]["aligned"] is False and mates["screw1_seated"]["active"]
    doc.flip_mate("screw1_seated")
    assert doc.pose("screw1")[2, 2] == pytest.approx(-1.0)
    doc.set_mate_aligned("screw1_seated", None)
    doc.set_mate_suppressed("screw2_seated", True)
    doc.delete_mate("screw3_in_hole")
    assert "screw3_in_hole" not in {m["name"] for m in doc.mates()}
    with pytest.raises(fitup.InputError):
        doc.add_mate("m", "coincident", "screw4/origin", "screw5/origin", valeu=1)
    doc.set_suppressed("screw4", True)
    doc.set_hidden("screw5", True)
    doc.set_property("Description", "M5 screw", part="screw")
    doc.set_property("Price", 0.25, component="screw5")
    assert doc.properties(part="screw") == [("Description", "M5 screw")]
    assert doc.remove_property("Price", component="screw5") == "0.25"
    name = doc.add_component("screw", fitup.translation(0, 0, 900))
    assert name == "screw-1"
    doc.rename_component(name, "spare")
    assert doc.component("spare")["part"] == "screw"
    c = doc.component("screw4")
    assert c["suppressed"] and doc.component("screw5")["hidden"]
    # the suppressed screw weighs nothing in the assembly; the mesh leaves out both
    everyone = [n for n in doc.components() if n != "screw4"]
    assert doc.mass_properties()["mass_kg"] == pytest.approx(
        doc.mass_properties(everyone)["mass_kg"], rel=1e-12)
    v, t = doc.world_mesh(["spare"])
    assert v.shape[1] == 3 and t.shape[1] == 3 and v[:, 2].min() == pytest.approx(900.0)
    out = project / "out"
    out.mkdir()
    assert doc.export_stl(out / "spare.stl", ["spare"]) == 84 + 50 * t.shape[0]
    assert doc.export_glb(out / "cell.glb") == len(doc.components()) - 2
    # per component, the pose baked in: the node has no matrix, its mesh is the
    # world mesh (f32 metres); in a frame 900 mm up it sits on the frame's origin
    lifted = fitup.translation(0, 0, 900)
    for name, frame, want in [("spare.glb", None, v), ("spare_up.glb", lifted, v - [0, 0, 900])]:
        assert doc.export_glb(out / name, components=["spare"], frame=frame) == 1
        nodes = glb_nodes(out / name)
        assert list(nodes) == ["spare"]
        matrix, gv, gt = nodes["spare"]
        assert matrix is None and np.array_equal(gt, t)
        assert np.abs(gv - want).max() < 1e-3
    assert nodes["spare"][1][:, 2].min() == pytest.approx(0.0, abs=1e-3)
    with pytest.raises(fitup.DocumentError, match="`screw4` is suppressed"):
        doc.export_glb(out / "screw4.glb", components=["screw4"])
    assert not (out / "screw4.glb").exists()
    doc.save_as(project / "models" / "edited.yaml")
    back = fitup.Document(project / "models" / "edited.yaml")
    assert back.component("screw4")["suppressed"] and back.properties(part="screw")


def test_equations_and_global_variables(project):
    """Issue 37, capability 8 from Python: equations drive dimensions, global
    variables by name, a refused equation names its cause, saves keep them."""
    path = project / "models" / "solidworks" / "lift.yaml"
    doc = fitup.Document(path)
    eqs = doc.equations()
    assert [e["name"] for e in eqs] == ["Factor", "Clearance", "D1@lift", "D1@turn"]
    assert eqs[2]["text"] == '"D1@lift" = 10 * "Factor"' and eqs[2]["value"] == 20.0
    assert eqs[0]["global"] and not eqs[2]["global"]
    doc.set_global_variable("Factor", 3.0)
    assert doc.dimension("D1@lift")["value"] == pytest.approx(30.0)
    assert doc.pose("plate")[2, 3] == pytest.approx(780.0)
    with pytest.raises(fitup.DocumentError, match="division by zero"):
        doc.set_equation(1, '"Clearance" = 1 / ("Factor" - 3)')
    assert doc.global_variable("Clearance") == 5.0
    i = doc.add_equation('"Half" = "Factor" / 2', index=0)
    assert i == 0 and doc.global_variable("Half") == 1.5
    doc.delete_equation(0)
    doc.save()
    again = fitup.Document(path)
    assert [e["text"] for e in again.equations()] == [e["text"] for e in doc.equations()]
    assert again.global_variable("Factor") == 3.0


def test_equation_functions_and_driven_joints(project):
    """Issue 37: SolidWorks' equation functions and unit suffixes (iif, sum, 2in,
    45deg), and a robot joint an equation drives refused by set_joints, naming the
    equation (the library decides; Python only converts)."""
    doc = fitup.Document(project / "models" / "solidworks" / "lift.yaml")
    doc.add_equation('"Wide" = iif("Factor" > 1, sum(1in, 2mm, 3), 0)')
    assert doc.global_variable("Wide") == pytest.approx(25.4 + 2 + 3)
    arm = fitup.Document(project / "models" / "mz07.yaml")
    dims = arm.dimensions()
    assert len(dims) == 6  # the six joints, D1@角度1 … 6
    arm.add_equation(f'"{dims[1]}" = 20deg + 5')
    q = arm.joints("mz07")
    assert math.degrees(q[1]) == pytest.approx(25.0)
    q[1] = 0.0
    with pytest.raises(fitup.DocumentError, match=r"driven by equation \[0\]"):
        arm.set_joints("mz07", q)
    assert math.degrees(arm.joints("mz07")[1]) == pytest.approx(25.0)
    q = arm.joints("mz07")
    q[0] = 0.1
    arm.set_joints("mz07", q)
    assert arm.joints("mz07")[0] == pytest.approx(0.1)


def test_parts_from_files_replaced_parts_and_source_files(project):
    """Issue 37, capabilities 6 and 7 from Python (CodeStack's add, replace and
    copy-path macros): a part added from a mesh file inside the project and placed,
    a component's part replaced (refused until the new part has its mates'
    references, then re-solved), and every part's source file."""
    doc = fitup.Document(project / "models" / "gearbox.yaml")
    meshes = (project / "models" / "meshes").resolve()

    def source(part):
        return pathlib.Path(doc.part_file(part)).resolve()

    assert source("screw") == meshes / "gearbox_screw.stl"
    assert pathlib.Path(doc.component("screw1")["part_file"]).resolve() == source("screw")
    assert doc.add_part("cap2", "meshes/gearbox_cap.stl") == "cap2"
    assert source("cap2") == meshes / "gearbox_cap.stl"
    name = doc.add_component("cap2", fitup.translation(500, 500, 760))
    assert name == "cap2-1" and doc.pose(name)[:3, 3] == pytest.approx([500, 500, 760])
    with pytest.raises(fitup.FitupError):
        doc.add_part("outside", "../../elsewhere.stl")
    doc.add_part("screw_new", "meshes/gearbox_screw.stl")
    z = doc.pose("screw1")[2, 3]
    with pytest.raises(fitup.DocumentError, match="axis"):
        doc.replace_part("screw1", "screw_new")
    assert doc.component("screw1")["part"] == "screw"
    doc.set_reference("screw_new", "axis", "axis", point=[0, 0, 0], direction=[0, 0, 1])
    doc.set_reference("screw_new", "under_head", "plane", point=[0, 0, 12], direction=[0, 0, -1])
    doc.replace_part("screw1", "screw_new")
    assert doc.component("screw1")["part"] == "screw_new"
    # the seat mate now holds the new under-head plane on the cover: 2 mm lower
    assert doc.pose("screw1")[2, 3] == pytest.approx(z - 2.0, abs=1e-6)
    doc.save_as(project / "models" / "replaced.yaml")
    back = fitup.Document(project / "models" / "replaced.yaml")
    assert back.component("screw1")["part"] == "screw_new" and back.pose("cap2-1")[2, 3] == pytest.approx(760)


def test_a_suppressed_part_is_read_when_unsuppressed(project):
    """Issue 37, capability 5: a part only a suppressed component uses is not read
    when the document opens, so its missing mesh file does not stop it; unsuppressing
    it reads the file (refused, naming the file and the document's line, nothing
    changed, while it is missing), and its world mesh is refused meanwhile."""
    models = project / "models"
    text = (models / "cell.yaml").read_text()
    text = text.replace("\nparts:\n", "\nparts:\n  ghost:\n    stl: meshes/ghost.stl\n", 1)
    text = text.replace(
        "\ncomponents:\n", "\ncomponents:\n- name: ghost\n  part: ghost\n  suppressed: true\n", 1
    )
    (models / "ghost.yaml").write_text(text)
    line = 1 + text.splitlines().index("    stl: meshes/ghost.stl")
    doc = fitup.Document(models / "ghost.yaml")
    assert doc.component("ghost")["suppressed"]
    with pytest.raises(fitup.DocumentError, match="not loaded"):
        doc.world_mesh(["ghost"])
    with pytest.raises(fitup.DocumentError) as refused:
        doc.set_suppressed("ghost", False)
    message = str(refused.value)
    assert f"ghost.yaml:{line}:" in message and "meshes/ghost.stl" in message, message
    assert doc.component("ghost")["suppressed"]
    (models / "meshes" / "ghost.stl").write_bytes((models / "meshes" / "plate_a.stl").read_bytes())
    doc.set_suppressed("ghost", False)
    vertices, _ = doc.world_mesh(["ghost"])
    assert len(vertices) > 0


def test_remove_component(project):
    """Issue 37, capability 7: a component with mates is refused unless its mates go
    with it; the others keep their poses."""
    doc = fitup.Document(project / "models" / "cell.yaml")
    with pytest.raises(fitup.DocumentError, match="screw1_in_hole"):
        doc.remove_component("screw1")
    before = doc.pose("screw2")
    assert doc.remove_component("screw1", with_mates=True) == ["screw1_in_hole", "screw1_seated"]
    assert "screw1" not in doc.components()
    assert (doc.pose("screw2") == before).all()
    assert doc.remove_component("screw4") == []


def test_sub_assemblies(project):
    """Issue 37, capability 2 from Python: the tree by full names, composed poses,
    a sub-assembly moved with what it holds, saved and reloaded."""
    path = project / "models" / "solidworks" / "cart.yaml"
    doc = fitup.Document(path)
    assert doc.sub_assemblies() == ["Cart-1", "Cart-1/Axle-1", "Cart-1/Axle-2"]
    assert doc.children() == ["Cart-1", "table"]
    assert doc.children("Cart-1/Axle-2") == ["Cart-1/Axle-2/Wheel-1", "Cart-1/Axle-2/Wheel-2"]
    assert doc.parent("Cart-1/Axle-2/Wheel-2") == "Cart-1/Axle-2"
    assert doc.parent("Cart-1") is None
    assert doc.pose("Cart-1/Axle-2/Wheel-2")[:3, 3] == pytest.approx([350.0, 330.0, 760.0])
    pose = doc.sub_assembly_pose("Cart-1")
    pose[2, 3] += 10.0
    doc.set_sub_assembly_pose("Cart-1", pose)
    assert doc.pose("Cart-1/Axle-2/Wheel-2")[2, 3] == pytest.approx(770.0)
    doc.add_sub_assembly("Spare-1")
    doc.add_component("wheel", None, "Spare-1/Wheel-1")
    doc.save()
    again = fitup.Document(path)
    assert again.children("Spare-1") == ["Spare-1/Wheel-1"]
    assert again.pose("Cart-1/Axle-2/Wheel-2")[2, 3] == pytest.approx(770.0)


def test_sub_documents_and_suppressed_sub_assemblies(tmp_path):
    """Issue 37 from Python: a sub-assembly that is another document (``file:``),
    loaded through the levels, suppressed as a whole, saved back to its own file
    only."""
    (tmp_path / "fitup.toml").write_text("")
    (tmp_path / "sub").mkdir()
    shutil.copy(MODELS / "meshes" / "screw.stl", tmp_path / "sub" / "m.stl")
    (tmp_path / "sub" / "axle.yaml").write_text(
        "parts:\n  wheel:\n    stl: m.stl\n"
        "components:\n- name: Wheel-1\n  part: wheel\n"
        "- name: Wheel-2\n  part: wheel\n  transform:\n"
        "  - [1, 0, 0, 0]\n  - [0, 1, 0, 0]\n  - [0, 0, 1, 0]\n  - [0, 100, 0, 1]\n")
    (tmp_path / "top.yaml").write_text(
        "parts:\n  base:\n    stl: sub/m.stl\n"
        "assemblies:\n- name: Axle-1\n  file: sub/axle.yaml\n  transform:\n"
        "  - [1, 0, 0, 0]\n  - [0, 1, 0, 0]\n  - [0, 0, 1, 0]\n  - [10, 0, 5, 1]\n"
        "components:\n- name: base\n  part: base\n  fixed: true\n")
    doc = fitup.Document(tmp_path / "top.yaml")
    assert doc.sub_assembly_file("Axle-1") == "sub/axle.yaml"
    assert doc.children("Axle-1") == ["Axle-1/Wheel-1", "Axle-1/Wheel-2"]
    assert doc.pose("Axle-1/Wheel-2")[:3, 3] == pytest.approx([10.0, 100.0, 5.0])
    axle_before = (tmp_path / "sub" / "axle.yaml").read_text()
    doc.save()
    assert doc.saved_sub_documents() == []
    assert (tmp_path / "sub" / "axle.yaml").read_text() == axle_before
    assert "Wheel" not in (tmp_path / "top.yaml").read_text()
    doc.set_sub_assembly_suppressed("Axle-1", True)
    assert doc.sub_assembly_suppressed("Axle-1")
    assert doc.component("Axle-1/Wheel-2")["suppressed"]
    doc.save()
    again = fitup.Document(tmp_path / "top.yaml")
    assert again.sub_assembly_suppressed("Axle-1")
    assert again.component("Axle-1/Wheel-1")["suppressed"]
    doc.rename_component("Axle-1/Wheel-2", "Axle-1/Wheel-9")
    doc.save()
    assert [p.endswith("axle.yaml") for p in doc.saved_sub_documents()] == [True]
    assert "Wheel-9" in (tmp_path / "sub" / "axle.yaml").read_text()


def test_coordinate_systems(project):
    """Issue 37, capability 10 from Python: a part's coordinate system in the part
    and in the world, a coincident mate between two of them, one added and saved."""
    path = project / "models" / "solidworks" / "fixture_cs.yaml"
    doc = fitup.Document(path)
    c = math.cos(math.pi / 6)
    part = doc.part_coordinate_system("table", "Coordinate System1")
    # column-vector pose: the columns are the system's X, Y, Z and origin (mm)
    assert part[:3, 0] == pytest.approx([c, 0.5, 0.0])
    assert part[:3, 1] == pytest.approx([-0.5, c, 0.0])
    assert part[:3, 3] == pytest.approx([600.0, 400.0, 750.0])
    ref = doc.reference("plate-1", "Coordinate System1")
    assert ref["kind"] == "coordinate_system" and ref["direction"] is None
    world = doc.coordinate_system("plate-1", "Coordinate System1")
    assert np.allclose(ref["pose"], world)
    assert np.allclose(world, doc.pose("plate-1") @ doc.part_coordinate_system("plate", "Coordinate System1"))
    doc.add_mate("cs_mate", "coincident", "table/Coordinate System1", "plate-1/Coordinate System1")
    assert np.allclose(doc.coordinate_system("plate-1", "Coordinate System1"), part, atol=1e-9)
    with pytest.raises(fitup.errors.DocumentError, match="coordinate systems"):
        doc.set_mate_aligned("cs_mate", False)
    with pytest.raises(fitup.errors.InputError, match="perpendicular"):
        doc.set_reference("plate", "Skew", "coordinate_system", point=[0, 0, 0], x=[1, 0, 0], y=[0.5, 1, 0])
    doc.set_reference("plate", "Top", "coordinate_system", point=[0, 0, 10], x=[0, 1, 0], y=[-1, 0, 0])
    top = doc.part_coordinate_system("plate", "Top")
    assert top[:3, 2] == pytest.approx([0.0, 0.0, 1.0])
    doc.set_reference("plate", "Moved", "coordinate_system", pose=top)
    doc.save()
    again = fitup.Document(path)
    assert np.allclose(again.part_coordinate_system("plate", "Moved"), top)
    assert np.allclose(again.pose("plate-1"), doc.pose("plate-1"))


def test_a_robot_inside_a_sub_document(tmp_path):
    """Issue 37: a sub-document's robot is reached by its full name, placed by the
    sub-assembly's frame, driven, and saved back to its own file."""
    (tmp_path / "fitup.toml").write_text("")
    shutil.copytree(MODELS / "urdf", tmp_path / "cell" / "urdf")  # its package is cell/
    (tmp_path / "top.yaml").write_text(
        "parts: {}\nassemblies:\n- name: Cell-1\n  file: cell/urdf/arm6_cell.yaml\n"
        "  transform:\n  - [0, 1, 0, 0]\n  - [-1, 0, 0, 0]\n  - [0, 0, 1, 0]\n"
        "  - [100, 0, 500, 1]\ncomponents: []\n")
    doc = fitup.Document(tmp_path / "top.yaml")
    alone = fitup.Document(tmp_path / "cell" / "urdf" / "arm6_cell.yaml")
    assert doc.robots() == ["Cell-1/arm6"]
    q = np.array([0.3, -0.4, 0.5, 0.2, -0.6, 0.7])
    doc.set_joints("Cell-1/arm6", q)
    assert np.allclose(doc.joints("Cell-1/arm6"), q)
    # the frame as a column-vector pose: 90 degrees about z, then (100, 0, 500)
    frame = np.array([[0.0, -1, 0, 100], [1, 0, 0, 0], [0, 0, 1, 500], [0, 0, 0, 1]])
    tcp = doc.robot("Cell-1/arm6").fk(q)
    assert np.allclose(tcp, frame @ alone.robot("arm6").fk(q), atol=1e-6)
    dim = doc.dimension("D1@Cell-1/角度2@arm6")
    assert dim["value"] == pytest.approx(-0.4)
    doc.save()
    text = (tmp_path / "cell" / "urdf" / "arm6_cell.yaml").read_text()
    assert "urdf: fitup_arm6.urdf" in text and "arm6:" not in text and "Cell-1" not in text
    assert np.allclose(fitup.Document(tmp_path / "top.yaml").joints("Cell-1/arm6"), q)
