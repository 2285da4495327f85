//! Hostile database use through the real binary: scripts' `db.query` trying to reach
//! files outside the project (ATTACH, VACUUM INTO), change settings (PRAGMA), write
//! fitup's tables, run forever (recursive CTE) or return millions of rows; a
//! PostgreSQL "server" that accepts and never answers; credentials in URLs.
//!
//! Bounds: every command ends within [`HANG`] (killed and failed after; a bound on
//! hangs, not a speed assertion); a 5,000,000-row query peaks under [`PEAK_RSS_MB`];
//! no file appears outside the project, user files keep their content hashes and the
//! stored results stay intact; a password in a URL is printed nowhere. The real
//! PostgreSQL half runs when `FITUP_TEST_POSTGRES` names a server (as in
//! `tests/db.rs`) and is skipped with a note otherwise.

use crate::common;
use common::{snapshot, user_files, Snapshot};

use common::{project, spawn};
use std::path::Path;
use std::time::{Duration, Instant};

/// Generous bound on any single command.
const HANG: Duration = Duration::from_secs(60);

/// Peak resident memory allowed for a run whose query would return 5M rows.
const PEAK_RSS_MB: u64 = 500;

/// Exit code and combined output of `fitup ARGS` in `dir`, bounded by [`HANG`].
fn run(dir: &Path, args: &[&str]) -> (i32, String) {
    let o = common::finish(spawn(dir, args), &args.join(" "), HANG);
    (o.status.code().unwrap_or(-1), common::text(&o))
}

/// Writes `scripts/NAME` and runs it with `extra` arguments.
fn run_script(dir: &Path, name: &str, source: &str, extra: &[&str]) -> (i32, String) {
    std::fs::write(dir.join("scripts").join(name), source).unwrap();
    let script = format!("scripts/{name}");
    let mut args = vec!["run", script.as_str()];
    args.extend_from_slice(extra);
    run(dir, &args)
}

/// Every file of `before` is still there with the same content (files the test wrote
/// since are not user files).
fn unchanged(before: &Snapshot, dir: &Path) {
    common::assert_kept(before, &user_files(dir));
}

/// Writes a note to the test's stderr (the harness would swallow `eprintln!`).
fn note(text: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "note: {text}");
}

/// A project whose `fitup.db` holds one stored snapshot of the demo cell.
fn project_with_results() -> tempfile::TempDir {
    let dir = project();
    let (code, t) = run_script(
        dir.path(),
        "store.rhai",
        "let doc = open_doc(\"models/cell.yaml\");\nlet db = open_db();\ndb.save(doc);\n",
        &[],
    );
    assert_eq!(code, 0, "{t}");
    dir
}

/// Row counts of fitup's tables and the file's integrity, read directly.
fn stored(dir: &Path) -> (Vec<(String, i64)>, String) {
    let c = rusqlite::Connection::open(dir.join("fitup.db")).unwrap();
    let counts = [
        "snapshots",
        "component_poses",
        "dimension_values",
        "paths",
        "schema_version",
    ]
    .iter()
    .map(|t| {
        let n: i64 = c
            .query_row(&format!("SELECT COUNT(*) FROM {t}"), [], |r| r.get(0))
            .unwrap();
        (t.to_string(), n)
    })
    .collect();
    let ok: String = c
        .query_row("PRAGMA integrity_check", [], |r| r.get(0))
        .unwrap();
    (counts, ok)
}

/// A script that runs each statement of `sqls` in `try` and prints `REFUSED i: …` or
/// `ACCEPTED i`.
fn each_refused_script(sqls: &[String]) -> String {
    let list: Vec<String> = sqls.iter().map(|s| format!("{s:?}")).collect();
    format!(
        "let db = open_db();\nlet sqls = [{}];\nfor i in 0..sqls.len() {{\n    try {{\n        db.query(sqls[i]);\n        print(`ACCEPTED ${{i}}`);\n    }} catch (e) {{\n        print(`REFUSED ${{i}}: ${{e}}`);\n    }}\n}}\n",
        list.join(", ")
    )
}

/// The start of every refusal of the query jail.
const JAIL: &str = "db.query is read-only and reads this database only: ";

/// Asserts that every statement failed, each with its `needle` in the message.
fn assert_all_refused(t: &str, cases: &[(String, &str)]) {
    assert!(!t.contains("ACCEPTED"), "a statement was accepted:\n{t}");
    assert!(!t.contains("panicked"), "{t}");
    for (i, (sql, needle)) in cases.iter().enumerate() {
        let line = t
            .lines()
            .find(|l| l.starts_with(&format!("REFUSED {i}:")))
            .unwrap_or_else(|| panic!("no verdict for `{sql}`:\n{t}"));
        assert!(
            line.contains(needle),
            "`{sql}`: expected `{needle}` in `{line}`"
        );
    }
}

#[test]
fn attach_outside_the_project_is_refused_and_creates_nothing() {
    let dir = project_with_results();
    let p = dir.path();
    let outside = tempfile::tempdir().unwrap();
    let secret = outside.path().join("secret.db");
    rusqlite::Connection::open(&secret)
        .unwrap()
        .execute_batch("CREATE TABLE s(x); INSERT INTO s VALUES ('hidden-value');")
        .unwrap();
    let before_outside = snapshot(outside.path());
    let before = user_files(p);
    let before_db = stored(p);
    let missing = outside.path().join("created.db");
    let into = outside.path().join("copy.db");
    let attach = format!("{JAIL}ATTACH would open another database file");
    let cases: Vec<(String, &str)> = vec![
        (
            format!("ATTACH DATABASE '{}' AS o", secret.display()),
            &attach,
        ),
        (
            format!("ATTACH DATABASE '{}' AS o", missing.display()),
            &attach,
        ),
        (format!("ATTACH '{}' AS o", secret.display()), &attach),
        // Reading the attached file afterwards finds no such database.
        ("SELECT x FROM o.s".to_string(), "no such table: o.s"),
        (
            format!("VACUUM INTO '{}'", into.display()),
            "the statement would change the database",
        ),
        (
            "DETACH DATABASE main".to_string(),
            "DETACH changes the connection",
        ),
        (
            format!(
                "SELECT load_extension('{}')",
                outside.path().join("x.so").display()
            ),
            "the function `load_extension` reaches outside the database",
        ),
    ];
    let sqls: Vec<String> = cases.iter().map(|c| c.0.clone()).collect();
    let (code, t) = run_script(p, "attach.rhai", &each_refused_script(&sqls), &[]);
    assert_eq!(code, 0, "{t}");
    assert_all_refused(&t, &cases);
    assert!(!t.contains("hidden-value"), "{t}");
    assert!(!missing.exists(), "ATTACH created {}", missing.display());
    assert!(!into.exists(), "VACUUM INTO wrote {}", into.display());
    assert_eq!(snapshot(outside.path()), before_outside);
    unchanged(&before, p);
    assert_eq!(stored(p), before_db);
}

#[test]
fn pragma_writes_and_writes_to_fitups_tables_are_refused() {
    let dir = project_with_results();
    let p = dir.path();
    let before = user_files(p);
    let before_db = stored(p);
    let s = |x: &str| x.to_string();
    let set = |p: &str| format!("{JAIL}`PRAGMA {p} = …` changes a setting");
    let (sync, fk, jm, uv, ws, wc) = (
        set("synchronous"),
        set("foreign_keys"),
        set("journal_mode"),
        set("user_version"),
        set("writable_schema"),
        set("wal_checkpoint"),
    );
    let cases: Vec<(String, &str)> = vec![
        (s("PRAGMA synchronous=OFF"), &sync),
        (s("PRAGMA foreign_keys=OFF"), &fk),
        (s("PRAGMA journal_mode=DELETE"), &jm),
        (s("PRAGMA user_version=99"), &uv),
        (s("PRAGMA writable_schema=ON"), &ws),
        (s("PRAGMA wal_checkpoint(TRUNCATE)"), &wc),
        (
            s("INSERT INTO paths (name) VALUES ('x')"),
            "INSERT into `paths` writes",
        ),
        (
            s("UPDATE component_poses SET x_mm = 0"),
            "UPDATE of `component_poses` writes",
        ),
        (s("DELETE FROM snapshots"), "DELETE from `snapshots` writes"),
        (s("DROP TABLE schema_version"), "changes the schema"),
        (s("CREATE TABLE mine(a)"), "changes the schema"),
        (s("CREATE TEMP VIEW v AS SELECT 1"), "changes the schema"),
        (s("ALTER TABLE runs ADD COLUMN z"), JAIL),
        (s("BEGIN IMMEDIATE"), "transactions are fitup's"),
        (s("REINDEX"), JAIL),
        (s("ANALYZE"), JAIL),
        (
            s("SELECT 1; DELETE FROM snapshots"),
            "DELETE from `snapshots` writes",
        ),
    ];
    let sqls: Vec<String> = cases.iter().map(|c| c.0.clone()).collect();
    let (code, t) = run_script(p, "writes.rhai", &each_refused_script(&sqls), &[]);
    assert_eq!(code, 0, "{t}");
    assert_all_refused(&t, &cases);
    unchanged(&before, p);
    assert_eq!(stored(p), before_db);
    let c = rusqlite::Connection::open(p.join("fitup.db")).unwrap();
    let mode: String = c
        .query_row("PRAGMA journal_mode", [], |r| r.get(0))
        .unwrap();
    assert_eq!(mode, "wal");
    // Reads, schema queries and parameters still work in the same jail.
    let (code, t) = run_script(
        p,
        "reads.rhai",
        "let db = open_db();\nlet n = db.query(\"SELECT COUNT(*) AS n FROM component_poses WHERE x_mm > ?1\", [-1e9])[0].n;\nlet cols = db.query(\"SELECT name FROM pragma_table_info('paths')\").len();\nprint(`poses ${n} columns ${cols}`);\n",
        &[],
    );
    assert_eq!(code, 0, "{t}");
    assert!(t.contains("columns 2"), "{t}");
}

#[test]
fn a_recursive_query_stops_at_the_time_limit_with_the_stated_message() {
    let dir = project_with_results();
    let p = dir.path();
    let forever =
        "WITH RECURSIVE c(x) AS (SELECT 1 UNION ALL SELECT x + 1 FROM c) SELECT COUNT(*) FROM c";
    // The default: 10 s.
    let start = Instant::now();
    let (code, t) = run_script(
        p,
        "forever.rhai",
        &format!("let db = open_db();\nprint(\"start\");\nlet r = db.query({forever:?});\nprint(\"unreachable\");\n"),
        &[],
    );
    let took = start.elapsed();
    assert_eq!(code, 1, "{t}");
    assert!(
        t.contains("forever.rhai:3") && t.contains("query stopped after 10 s"),
        "{t}"
    );
    assert!(t.contains("up to 600 s with #{max_seconds"), "{t}");
    assert!(!t.contains("unreachable") && !t.contains("panicked"), "{t}");
    assert!(took < Duration::from_secs(40), "took {took:?}");
    // A script's own limit, and one beyond the maximum.
    let (code, t) = run_script(
        p,
        "short.rhai",
        &format!("let db = open_db();\ndb.query({forever:?}, [], #{{max_seconds: 0.5}});\n"),
        &[],
    );
    assert_eq!(code, 1, "{t}");
    assert!(
        t.contains("short.rhai:2") && t.contains("query stopped after 0.5 s"),
        "{t}"
    );
    let (code, t) = run_script(
        p,
        "long.rhai",
        "let db = open_db();\ndb.query(\"SELECT 1\", [], #{max_seconds: 100000});\n",
        &[],
    );
    assert_eq!(code, 1, "{t}");
    assert!(
        t.contains("long.rhai:2") && t.contains("at most 600 s"),
        "{t}"
    );
}

/// Runs `fitup ARGS` in `dir` and samples its peak resident memory (VmHWM, MB).
fn run_measured(dir: &Path, args: &[&str]) -> (i32, String, u64) {
    let child = spawn(dir, args);
    let status = format!("/proc/{}/status", child.id());
    let peak = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
    let (pk, stop) = (
        peak.clone(),
        std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false)),
    );
    let st = stop.clone();
    let sampler = std::thread::spawn(move || {
        use std::sync::atomic::Ordering::Relaxed;
        while !st.load(Relaxed) {
            if let Ok(s) = std::fs::read_to_string(&status) {
                if let Some(kb) = s
                    .lines()
                    .find_map(|l| l.strip_prefix("VmHWM:"))
                    .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
                {
                    pk.fetch_max(kb / 1024, Relaxed);
                }
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    });
    let o = common::finish(child, &args.join(" "), HANG);
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    sampler.join().unwrap();
    (
        o.status.code().unwrap_or(-1),
        common::text(&o),
        peak.load(std::sync::atomic::Ordering::Relaxed),
    )
}

#[test]
fn five_million_rows_are_refused_by_the_cap_in_bounded_memory() {
    let dir = project_with_results();
    let p = dir.path();
    let rows = "WITH RECURSIVE c(x) AS (SELECT 1 UNION ALL SELECT x + 1 FROM c LIMIT 5000000) SELECT x, 'a row of padding text' AS t FROM c";
    std::fs::write(
        p.join("scripts/many.rhai"),
        format!("let db = open_db();\nlet r = db.query({rows:?});\nprint(r.len());\n"),
    )
    .unwrap();
    let (code, t, peak) = run_measured(p, &["run", "scripts/many.rhai"]);
    assert_eq!(code, 1, "{t}");
    assert!(
        t.contains("many.rhai:2") && t.contains("more than 100,000 rows or 64 MiB"),
        "{t}"
    );
    assert!(peak > 0, "VmHWM was never read");
    note(&format!(
        "5M-row SQLite query refused at the default caps: peak RSS {peak} MB"
    ));
    assert!(peak < PEAK_RSS_MB, "peak RSS {peak} MB");
    // Raised limits stay bounded by the byte cap: 64 MiB of rows, not 5M of them.
    std::fs::write(
        p.join("scripts/more.rhai"),
        format!("let db = open_db();\nlet r = db.query({rows:?}, [], #{{max_rows: 1000000, max_seconds: 120}});\nprint(r.len());\n"),
    )
    .unwrap();
    let (code, t, peak) = run_measured(p, &["run", "scripts/more.rhai"]);
    assert_eq!(code, 1, "{t}");
    assert!(t.contains("more than 1,000,000 rows or 64 MiB"), "{t}");
    note(&format!(
        "the same with max_rows 1,000,000: peak RSS {peak} MB"
    ));
    assert!(
        peak < PEAK_RSS_MB,
        "peak RSS {peak} MB with max_rows 1,000,000"
    );
    // A result within the caps is returned whole.
    let (code, t) = run_script(
        p,
        "fine.rhai",
        &format!(
            "let db = open_db();\nprint(`rows ${{db.query({:?}).len()}}`);\n",
            rows.replace("5000000", "100000")
        ),
        &[],
    );
    assert_eq!(code, 0, "{t}");
    assert!(t.contains("rows 100000"), "{t}");
}

#[test]
fn a_save_in_watch_mode_cancels_a_running_query() {
    let dir = project_with_results();
    let p = dir.path();
    let script = p.join("scripts/slow.rhai");
    std::fs::write(
        &script,
        "let db = open_db();\nprint(\"querying\");\ndb.query(\"WITH RECURSIVE c(x) AS (SELECT 1 UNION ALL SELECT x + 1 FROM c) SELECT COUNT(*) FROM c\", [], #{max_seconds: 600});\n",
    )
    .unwrap();
    let mut w = common::Watch::start(p, "scripts/slow.rhai", &[]);
    w.out.wait_for("querying", HANG);
    std::thread::sleep(Duration::from_millis(500));
    let saved = Instant::now();
    std::fs::write(&script, "print(\"fixed\");\n").unwrap();
    // Far less than the query's 600 s: the save stopped it.
    w.out.wait_for("== done 1 cancelled", HANG);
    w.out.wait_for("== done 2 ok", HANG);
    assert!(saved.elapsed() < HANG);
    assert!(w.out.seen.iter().any(|l| l == "fixed"));
}

#[cfg(feature = "postgres")]
/// A TCP server on 127.0.0.1 that accepts every connection and never answers; the
/// connections are held until the test ends.
fn silent_server() -> (u16, std::thread::JoinHandle<()>) {
    let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = l.local_addr().unwrap().port();
    let h = std::thread::spawn(move || {
        let mut held = Vec::new();
        l.set_nonblocking(true).unwrap();
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(300) {
            match l.accept() {
                Ok((s, _)) => held.push(s),
                Err(_) => std::thread::sleep(Duration::from_millis(10)),
            }
        }
    });
    (port, h)
}

#[test]
#[cfg(feature = "postgres")]
fn a_silent_postgres_server_fails_in_bounded_time_and_no_password_is_printed() {
    let dir = project();
    let p = dir.path();
    let (port, _server) = silent_server();
    let urls = [
        format!("postgres://u:secret@127.0.0.1:{port}/db"),
        format!("postgresql://u@127.0.0.1:{port}/db?password=secret&sslmode=disable"),
    ];
    std::fs::write(
        p.join("scripts/pg.rhai"),
        "let db = open_db(args.url);\nprint(db.location);\n",
    )
    .unwrap();
    for (i, url) in urls.iter().enumerate() {
        let start = Instant::now();
        let (code, t) = run(p, &["run", "scripts/pg.rhai", "--", &format!("url={url}")]);
        assert_eq!(code, 1, "{t}");
        assert!(
            t.contains("pg.rhai:1") && t.contains("no answer from the server within 10 s"),
            "{t}"
        );
        assert!(!t.contains("secret"), "the password was printed:\n{t}");
        assert!(start.elapsed() < Duration::from_secs(40));
        // The same through the command line, `--db` and FITUP_DB.
        let (code, t) = run(p, &["db", "runs", "--db", url]);
        assert_eq!(code, 1, "{t}");
        assert!(t.contains("no answer from the server"), "{t}");
        assert!(!t.contains("secret"), "the password was printed:\n{t}");
        if i > 0 {
            continue;
        }
        let o = common::finish(
            common::fitup()
                .current_dir(p)
                .args(["db", "paths"])
                .env("FITUP_DB", url)
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap(),
            "db paths (FITUP_DB)",
            HANG,
        );
        let t = common::text(&o);
        assert_eq!(o.status.code(), Some(1), "{t}");
        assert!(!t.contains("secret"), "the password was printed:\n{t}");
        // `fitup run --db URL` records the run there: a warning, never the password.
        std::fs::write(p.join("scripts/plain.rhai"), "print(\"ran\");\n").unwrap();
        let (code, t) = run(p, &["run", "scripts/plain.rhai", "--db", url]);
        assert!(t.contains("not recorded"), "{code}: {t}");
        assert!(!t.contains("secret"), "the password was printed:\n{t}");
    }
    // The URL written in the script itself: the error quotes that source line, and the
    // password is still not printed.
    std::fs::write(
        p.join("scripts/inline.rhai"),
        format!(
            "let db = open_db(\"postgres://u:secret@127.0.0.1:{port}/db?connect_timeout=1\");\n"
        ),
    )
    .unwrap();
    let (code, t) = run(p, &["run", "scripts/inline.rhai"]);
    assert_eq!(code, 1, "{t}");
    assert!(
        t.contains("inline.rhai:1") && t.contains("postgres://u@127.0.0.1"),
        "{t}"
    );
    assert!(!t.contains("secret"), "the password was printed:\n{t}");
    // A malformed URL's error does not quote it either.
    let (code, t) = run(p, &["db", "runs", "--db", "postgres://u:secret@[::1/db"]);
    assert_eq!(code, 1, "{t}");
    assert!(!t.contains("secret"), "the password was printed:\n{t}");
}

#[test]
#[cfg(feature = "postgres")]
fn postgres_queries_are_read_only_jailed_and_bounded() {
    let Some(pg) = crate::db::postgres() else {
        return;
    };
    let dir = project();
    let p = dir.path();
    let url_arg = format!("url={}", pg.url());
    // Store something first.
    let (code, t) = run_script(
        p,
        "store.rhai",
        "let doc = open_doc(\"models/cell.yaml\");\nlet db = open_db(args.url);\ndb.save(doc);\n",
        &["--", &url_arg],
    );
    assert_eq!(code, 0, "{t}");
    let outside = tempfile::tempdir().unwrap();
    let copied = outside.path().join("copied.csv");
    let s = |x: &str| x.to_string();
    let cases: Vec<(String, &str)> = vec![
        (
            format!("COPY snapshots TO '{}'", copied.display()),
            "`COPY` is not a query",
        ),
        (
            s("COPY (SELECT 1) TO PROGRAM 'touch /tmp/fitup_pwned'"),
            "`COPY` is not a query",
        ),
        (s("SELECT pg_read_file('/etc/hostname')"), "pg_read_file"),
        (s("SELECT * FROM pg_ls_dir('.')"), "pg_ls"),
        (
            s("SELECT set_config('statement_timeout', '0', false)"),
            "set_config",
        ),
        (s("SELECT pg_advisory_lock(42)"), "pg_advisory"),
        (s("INSERT INTO paths (name) VALUES ('x')"), "is not a query"),
        (s("DELETE FROM snapshots"), "is not a query"),
        (s("DROP TABLE runs"), "is not a query"),
        (
            s("SET default_transaction_read_only = off"),
            "is not a query",
        ),
        (
            s("WITH d AS (DELETE FROM snapshots RETURNING 1) SELECT * FROM d"),
            "read-only transaction",
        ),
        (s("SELECT nextval('runs_id_seq')"), "read-only transaction"),
    ];
    let sqls: Vec<String> = cases.iter().map(|c| c.0.clone()).collect();
    let source = each_refused_script(&sqls).replace("open_db()", "open_db(args.url)");
    let (code, t) = run_script(p, "pgjail.rhai", &source, &["--", &url_arg]);
    assert_eq!(code, 0, "{t}");
    assert_all_refused(&t, &cases);
    assert!(!copied.exists() && !Path::new("/tmp/fitup_pwned").exists());
    // The data is intact.
    let mut c = postgres::Client::connect(pg.url(), postgres::NoTls).unwrap();
    let n: i64 = c
        .query_one("SELECT COUNT(*) FROM snapshots", &[])
        .unwrap()
        .get(0);
    assert_eq!(n, 1);
    // Time: pg_sleep and a recursive CTE stop at the limit; rows: the cap.
    let (code, t) = run_script(
        p,
        "pgslow.rhai",
        "let db = open_db(args.url);\ndb.query(\"SELECT pg_sleep(60)\", [], #{max_seconds: 1});\n",
        &["--", &url_arg],
    );
    assert_eq!(code, 1, "{t}");
    assert!(
        t.contains("pgslow.rhai:2") && t.contains("query stopped after 1 s"),
        "{t}"
    );
    let (code, t) = run_script(
        p,
        "pgforever.rhai",
        "let db = open_db(args.url);\ndb.query(\"WITH RECURSIVE c(x) AS (SELECT 1 UNION ALL SELECT x + 1 FROM c) SELECT COUNT(*) FROM c\", [], #{max_seconds: 1});\n",
        &["--", &url_arg],
    );
    assert_eq!(code, 1, "{t}");
    assert!(t.contains("query stopped after 1 s"), "{t}");
    std::fs::write(
        p.join("scripts/pgmany.rhai"),
        "let db = open_db(args.url);\nlet r = db.query(\"SELECT g, 'padding text' AS t FROM generate_series(1, 5000000) AS g\");\n",
    )
    .unwrap();
    let (code, t, peak) = run_measured(p, &["run", "scripts/pgmany.rhai", "--", &url_arg]);
    assert_eq!(code, 1, "{t}");
    assert!(t.contains("more than 100,000 rows or 64 MiB"), "{t}");
    note(&format!(
        "5M-row PostgreSQL query refused at the default caps: peak RSS {peak} MB"
    ));
    assert!(peak < PEAK_RSS_MB, "peak RSS {peak} MB");
    // Ordinary reads work.
    let (code, t) = run_script(
        p,
        "pgread.rhai",
        "let db = open_db(args.url);\nprint(`snapshots ${db.query(\"SELECT COUNT(*) AS n FROM snapshots\")[0].n}`);\n",
        &["--", &url_arg],
    );
    assert_eq!(code, 0, "{t}");
    assert!(t.contains("snapshots 1"), "{t}");
}
