"""One option vocabulary per request: every keyword-taking call accepts exactly the
keys of the library's table (``fitup.option_keys``, the table a script's options map
goes through and docs/api.md prints), and refuses others by name."""

import warnings

import numpy as np
import pytest

import fitup
from conftest import MODELS

CELL = MODELS / "cell.yaml"


def sample(key):
    """A Python value of the key's kind."""
    kind = key["kind"]
    return {
        "number": 1.5,
        "count": 3,
        "bool": True,
        "text": "nope",
        "names": ["nope"],
        "vector": np.array([0.0, 0.0, -1.0]),
        "box": [[-1, -1, -1], [1, 1, 1]],
        "pose": np.eye(4),
        "number_map": {"nope": 2.5},
        "switch": {},
        "choice": (key["choices"] or [""])[-1],
    }[kind]


def calls(doc):
    """(request, call) for every keyword-taking call; each ends fast whatever the
    key (an unknown component, a cheap check)."""
    goal = np.eye(4)
    return [
        ("planning", lambda **kw: doc.plan_path("nope", goal, **kw)),
        ("planning", lambda **kw: doc.plan_insertion("nope", goal, **kw)),
        ("planning", lambda **kw: doc.plan_disassembly("nope", **kw)),
        ("interference", lambda **kw: doc.contacts(**kw)),
        ("interference", lambda **kw: doc.interferences(**kw)),
        ("interference", lambda **kw: doc.contact("nope", "screw4", **kw)),
        ("interference", lambda **kw: doc.interferes("nope", "screw4", **kw)),
        ("sweep", lambda **kw: doc.sweep("nope", goal[None], **kw)),
        ("sequence", lambda **kw: doc.plan_sequence(**{"components": ["nope"], **kw})),
    ]


def test_every_keyword_call_takes_exactly_its_vocabularys_keys():
    doc = fitup.Document(CELL)
    for request, call in calls(doc):
        keys = fitup.option_keys(request)
        assert keys, request
        for key in keys:
            try:
                call(**{key["key"]: sample(key)})
            except fitup.InputError as e:
                text = str(e)
                assert f"unknown {request} option" not in text, (request, key, text)
                assert f"option `{key['key']}` must be" not in text, (request, key, text)
            except fitup.FitupError:
                pass  # refused for another reason (the unknown component): fine
        hint = "did you mean `time_limit_ms`" if any(
            k["key"] == "time_limit_ms" for k in keys) else "known: "
        with pytest.raises(fitup.InputError, match=f"unknown {request} option `time_limt_ms`: {hint}"):
            call(time_limt_ms=1)


def test_database_filters_and_limits_are_their_tables(tmp_path):
    db = fitup.Database(str(tmp_path / "o.db"))
    for key in fitup.option_keys("path filter"):
        assert db.paths(**{key["key"]: sample(key)}) == []
    for key in fitup.option_keys("query limits"):
        db.query("SELECT 1", [], **{key["key"]: 300})
    with pytest.raises(fitup.InputError, match="did you mean `max_rows`"):
        db.query("SELECT 1", [], max_row=3)
    with pytest.warns(DeprecationWarning, match="`run_id` is deprecated"):
        assert db.paths(run_id=1) == []
    with pytest.raises(fitup.DatabaseError, match="max_seconds"):
        db.query("SELECT 1", [], max_seconds=0)


def test_every_request_has_a_table():
    for request in ("planning", "narrow", "interference", "sweep", "sequence", "motion", "drilling",
                    "path filter", "query limits"):
        for key in fitup.option_keys(request):
            assert key["meaning"] and key["kind"]
    with pytest.raises(fitup.InputError, match="planning"):
        fitup.option_keys("planing")


def test_bad_values_name_key_value_and_rule():
    doc = fitup.Document(CELL)
    with pytest.raises(fitup.InputError, match=r"planning option `step` must be a number \(mm\), not \"fast\""):
        doc.plan_path("screw5", np.eye(4), step="fast")
    with pytest.raises(fitup.InputError, match=r"`narrow.max_turn`.*did you mean `max_turn_deg`"):
        doc.plan_path("screw5", np.eye(4), narrow={"max_turn": 5})
    with pytest.raises(fitup.InputError, match="finite"):
        doc.interferences(tolerance=float("nan"))
    with pytest.raises(fitup.InputError, match="method"):
        doc.contacts(method="exakt")


def test_old_radian_keywords_warn_and_still_work():
    doc = fitup.Document(CELL)
    with pytest.warns(DeprecationWarning, match="`edge_step_rad` is deprecated.*`edge_step_deg`"):
        p = doc.plan_path("screw5", doc.pose("screw5"), edge="step", edge_step_rad=0.01, seed=1)
    assert p.found
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        doc.plan_path("screw5", doc.pose("screw5"), edge="step", edge_step_deg=0.5, seed=1)
