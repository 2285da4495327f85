//! One option vocabulary per request: every script call that takes an options map
//! accepts exactly the keys of the library's table (`fitup::options`), as a user runs
//! it (`fitup run`). Each key is given alone with a value of its kind; the call may
//! then fail for another reason (an unknown component, an unreachable pose — chosen so
//! nothing long runs), but never with an option error. A key outside the table is
//! refused by name with close matches. Python's keywords go through the same tables
//! (python/tests/test_options.py walks `fitup.option_keys`).

use crate::common;
use fitup::options::{
    Check, Drill, Kind, Limits, Motion, Options, PathFilter, Plan, Sequence, Sweep, Vocabulary,
};

/// A Rhai value of `kind`.
fn sample(kind: &Kind) -> String {
    match kind {
        Kind::Number => "1.5".into(),
        Kind::Count => "3".into(),
        Kind::Bool => "true".into(),
        Kind::Text => "\"nope\"".into(),
        Kind::Choice(names) => format!("\"{}\"", names[names.len() - 1]),
        Kind::Names => "[\"nope\"]".into(),
        Kind::Vector => "[0, 0, -1]".into(),
        Kind::Box => "#{min: [-1, -1, -1], max: [1, 1, 1]}".into(),
        Kind::Pose => "[0, 0, 0, 0, 0, 90]".into(),
        Kind::NumberMap => "#{nope: 2.5}".into(),
        Kind::Switch(_) => "#{}".into(),
    }
}

/// The calls that take `vocabulary`'s map, `OPTS` standing for it, with the keys
/// every call gets so it ends fast (left out when the key itself is the one tried).
struct Calls {
    vocabulary: &'static Vocabulary,
    calls: &'static [&'static str],
    fast: &'static [(&'static str, &'static str)],
}

const CALLS: &[Calls] = &[
    Calls {
        vocabulary: Plan::VOCABULARY,
        calls: &[
            "d.plan_path(\"nope\", pose(0, 0, 0, 0, 0, 0), OPTS)",
            "d.plan_disassembly(\"nope\", OPTS)",
        ],
        fast: &[],
    },
    Calls {
        vocabulary: Check::VOCABULARY,
        calls: &[
            "d.interferences(OPTS)",
            "d.touching(OPTS)",
            "d.interferes(\"nope\", \"screw4\", OPTS)",
            "d.contact(\"nope\", \"screw4\", OPTS)",
        ],
        fast: &[],
    },
    Calls {
        vocabulary: Sweep::VOCABULARY,
        calls: &["d.sweep(\"nope\", pose(0, 0, 0, 0, 0, 0), OPTS)"],
        fast: &[],
    },
    Calls {
        vocabulary: Sequence::VOCABULARY,
        calls: &["d.assembly_sequence(OPTS)"],
        fast: &[("components", "[\"nope\"]")],
    },
    Calls {
        vocabulary: Motion::VOCABULARY,
        calls: &[
            "arm.move_line(pose(9000, 0, 0, 0, 0, 0), OPTS)",
            "arm.move_joint([0, 0, 0, 0, 0, 999], OPTS)",
        ],
        fast: &[],
    },
    Calls {
        vocabulary: Drill::VOCABULARY,
        calls: &["arm.drill_program([#{}], OPTS)"],
        fast: &[],
    },
    Calls {
        vocabulary: PathFilter::VOCABULARY,
        calls: &["db.paths(OPTS)"],
        fast: &[],
    },
    Calls {
        vocabulary: Limits::VOCABULARY,
        calls: &["db.query(\"SELECT 1\", [], OPTS)"],
        fast: &[],
    },
];

/// `#{key: value, …}` for `key`, with the call's fast keys.
fn map(calls: &Calls, key: &str, value: &str) -> String {
    let mut items = vec![format!("{key}: {value}")];
    for (k, v) in calls.fast {
        if *k != key {
            items.push(format!("{k}: {v}"));
        }
    }
    format!("#{{{}}}", items.join(", "))
}

#[test]
fn every_script_call_takes_exactly_its_vocabularys_keys() {
    let dir = common::project();
    fitup::demo::write_robots(&dir.path().join("models")).unwrap();
    let mut script = String::from(
        "let d = open_doc(\"models/cell.yaml\");\n\
         let arm = open_doc(\"models/mz07.yaml\").robot(\"mz07\");\n\
         let db = open_db(\"keys.db\");\n",
    );
    let mut expected = 0;
    for c in CALLS {
        for call in c.calls {
            for k in c.vocabulary.keys {
                let opts = map(c, k.name, &sample(&k.kind));
                script += &format!(
                    "try {{ {}; print(\"KEY|{}|{}|ok\"); }} catch (e) {{ print(`KEY|{}|{}|${{e}}`); }}\n",
                    call.replace("OPTS", &opts),
                    c.vocabulary.request,
                    k.name,
                    c.vocabulary.request,
                    k.name
                );
                expected += 1;
            }
            let opts = map(c, "time_limt_ms", "1");
            script += &format!(
                "try {{ {}; print(\"BOGUS|{}|accepted\"); }} catch (e) {{ print(`BOGUS|{}|${{e}}`); }}\n",
                call.replace("OPTS", &opts),
                c.vocabulary.request,
                c.vocabulary.request
            );
        }
    }
    std::fs::write(dir.path().join("scripts/keys.rhai"), &script).unwrap();
    let out = common::run_in(dir.path(), &["run", "scripts/keys.rhai"]);
    let text = common::text(&out);
    assert!(out.status.success(), "{text}");
    let keys: Vec<&str> = text.lines().filter(|l| l.starts_with("KEY|")).collect();
    assert_eq!(keys.len(), expected, "{text}");
    for line in keys {
        let mut words = line.splitn(4, '|');
        let (_, request, key) = (words.next(), words.next().unwrap(), words.next().unwrap());
        assert!(
            !line.contains(&format!("unknown {request} option"))
                && !line.contains(&format!("option `{key}` must be"))
                && !line.contains(&format!("option `{key}` and")),
            "the library's key `{key}` of `{request}` is refused by a script call: {line}"
        );
    }
    let bogus: Vec<&str> = text.lines().filter(|l| l.starts_with("BOGUS|")).collect();
    assert_eq!(
        bogus.len(),
        CALLS.iter().map(|c| c.calls.len()).sum::<usize>()
    );
    for line in bogus {
        let request = line.split('|').nth(1).unwrap();
        let c = CALLS
            .iter()
            .find(|c| c.vocabulary.request == request)
            .unwrap();
        let hinted = if c.vocabulary.key("time_limit_ms").is_some() {
            line.contains("did you mean `time_limit_ms`")
        } else {
            line.contains("did you mean") || line.contains("known: ")
        };
        assert!(
            line.contains(&format!("unknown {request} option `time_limt_ms`")) && hinted,
            "a key outside the table must be refused with close matches: {line}"
        );
    }
}

/// Bad values are refused by the table's words: the key, the value, what it takes
/// and its unit; the old radian spelling of a key warns and still works.
#[test]
fn script_option_errors_name_key_value_and_rule() {
    let dir = common::project();
    let script = "let d = open_doc(\"models/cell.yaml\");\n\
        for o in [#{step: \"fast\"}, #{narrow: #{max_turn: 5}}, #{edge: \"stepwise\"}, #{seed: -1}] {\n\
            try { d.plan_path(\"screw5\", pose(0, 0, 0, 0, 0, 0), o); } catch (e) { print(`ERR ${e}`); }\n\
        }\n\
        try { d.interferences(#{tolerance: \"0.1\"}); } catch (e) { print(`ERR ${e}`); }\n";
    let out = common::run_script_in(dir.path(), "bad.rhai", script);
    let text = common::text(&out);
    let errors: Vec<&str> = text.lines().filter(|l| l.starts_with("ERR ")).collect();
    assert_eq!(errors.len(), 5, "{text}");
    for (line, words) in errors.iter().zip([
        &["planning option `step` must be a number (mm), not \"fast\""][..],
        &["`narrow.max_turn`", "did you mean `max_turn_deg`"],
        &[
            "option `edge` must be one of `continuous`, `step`",
            "\"stepwise\"",
        ],
        &["option `seed` must be a whole number ≥ 0, not -1"],
        &["interference option `tolerance` must be a number (mm), not \"0.1\""],
    ]) {
        for w in words {
            assert!(line.contains(w), "{line} should say {w}");
        }
    }
}
