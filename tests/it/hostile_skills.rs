//! Hostile inputs to the skill manager, the simulated manipulator and the task
//! template reader, driving the real binary (`fitup manipulator`, `fitup skills run`,
//! `fitup skills template`). Every case ends in bounded time (each wait below is a
//! bound on hangs, not a speed assertion) and memory where stated.

use crate::common;

use common::lines::{Killed, Lines};
use common::{fitup, repo};
use fitup::kinematics::JointKind;
use fitup::manipulator::client::{Client, ClientOptions, ManipulatorError, Port};
use fitup::manipulator::message::{
    msg_type, Body, ByteOrder, JointPosition, Packet, ReplyCode, RobotMode, Status, TriState,
};
use fitup::skills::{ControllerCommand, Plan};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::path::Path;
use std::process::{Child, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

const KINDS: [JointKind; 6] = [JointKind::Revolute; 6];

/// A running `fitup` with its stdout and stderr read line by line (killed on drop).
struct Proc {
    child: Killed,
    out: Lines,
    err: Lines,
}

fn spawn(dir: &Path, args: &[&str], stdin: bool) -> Proc {
    let mut child: Child = fitup()
        .current_dir(dir)
        .args(args)
        .stdin(if stdin { Stdio::piped() } else { Stdio::null() })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = Lines::read(child.stdout.take().unwrap());
    let err = Lines::read(child.stderr.take().unwrap());
    Proc {
        child: Killed(child),
        out,
        err,
    }
}

/// Waits for the process to end (bounded) and returns its exit code.
fn wait_exit(p: &mut Proc, bound: Duration) -> Option<i32> {
    let end = Instant::now() + bound;
    loop {
        if let Some(s) = p.child.0.try_wait().unwrap() {
            return s.code();
        }
        assert!(
            Instant::now() < end,
            "still running after {bound:?}; stdout:\n{}\nstderr:\n{}",
            p.out.seen.join("\n"),
            p.err.seen.join("\n")
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// `fitup manipulator` on the MZ07 of `models/mz07.yaml` (free ports, ×`speed`).
fn simulator(speed: &str) -> (Proc, SocketAddr, SocketAddr) {
    let mut args = common::MZ07_SIMULATOR.to_vec();
    args.extend(["--port", "0", "--state-port", "0", "--speed", speed]);
    let mut sim = spawn(&repo(), &args, false);
    let line = sim.out.wait_for("listening", Duration::from_secs(60));
    let (m, s) = common::listening_addrs(&line);
    (sim, m, s)
}

/// A plan of `skills` slow joint moves of the MZ07 (`seconds` each).
fn joint_plan(skills: usize, seconds: f64) -> Plan {
    let mut steps = Vec::new();
    let mut q = vec![0.0; 6];
    for i in 0..skills {
        let start = q.clone();
        let mut end = start.clone();
        end[0] += 0.1;
        q = end.clone();
        steps.push(common::gear_step(
            i,
            fitup::skills::PartState::Grasped,
            vec![ControllerCommand::Trajectory(vec![
                (start, 0.0),
                (end, seconds),
            ])],
        ));
    }
    common::mz07_plan(steps)
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

/// A listener that counts the connections made to it (and closes each at once).
fn counting_listener() -> (SocketAddr, Arc<AtomicUsize>) {
    let l = TcpListener::bind("127.0.0.1:0").unwrap();
    let a = l.local_addr().unwrap();
    let n = Arc::new(AtomicUsize::new(0));
    let n2 = n.clone();
    std::thread::spawn(move || {
        for c in l.incoming() {
            drop(c);
            n2.fetch_add(1, Ordering::SeqCst);
        }
    });
    (a, n)
}

/// `fitup skills run FILE --target TARGET [--state-port PORT] --plain` in `dir`,
/// killed after `bound`.
fn run_plain(
    dir: &Path,
    file: &str,
    target: SocketAddr,
    state_port: Option<u16>,
    bound: Duration,
) -> std::process::Output {
    let target = target.to_string();
    let port = state_port.map(|p| p.to_string());
    let mut args = vec!["skills", "run", file, "--target", &target];
    if let Some(p) = &port {
        args.extend(["--state-port", p.as_str()]);
    }
    args.push("--plain");
    common::run_bounded(dir, &args, bound)
}

fn status() -> Status {
    Status {
        drives_powered: TriState::On,
        e_stopped: TriState::Off,
        error_code: 0,
        in_error: TriState::Off,
        in_motion: TriState::Off,
        mode: RobotMode::Auto,
        motion_possible: TriState::On,
    }
}

/// The JOINT_POSITION + STATUS bytes a controller publishes (joints all 0).
fn state_bytes() -> Vec<u8> {
    let mut b = Packet::topic(
        msg_type::JOINT_POSITION,
        Body::JointPosition(JointPosition {
            sequence: 0,
            joints: [0.0; 10],
        }),
    )
    .encode(ByteOrder::Big);
    b.extend(Packet::topic(msg_type::STATUS, Body::Status(status())).encode(ByteOrder::Big));
    b
}

/// A state port that publishes every 50 ms to every client, writing each
/// publication in two parts 300 ms apart when `split` is set.
fn fake_state_port(split: bool) -> SocketAddr {
    let l = TcpListener::bind("127.0.0.1:0").unwrap();
    let a = l.local_addr().unwrap();
    std::thread::spawn(move || {
        for mut c in l.incoming().map_while(Result::ok) {
            std::thread::spawn(move || {
                let b = state_bytes();
                loop {
                    let r = if split {
                        c.write_all(&b[..7]).and_then(|_| {
                            std::thread::sleep(Duration::from_millis(300));
                            c.write_all(&b[7..])
                        })
                    } else {
                        c.write_all(&b)
                    };
                    if r.is_err() {
                        return;
                    }
                    std::thread::sleep(Duration::from_millis(50));
                }
            });
        }
    });
    a
}

#[test]
fn a_plan_value_that_does_not_fit_the_wire_is_refused_before_dispatch() {
    let dir = tempfile::tempdir().unwrap();
    let mut plan = joint_plan(2, 1.0);
    if let ControllerCommand::Trajectory(pts) = &mut plan.steps[1].commands[0] {
        pts[1].0[2] = 1e39; // finite in f64, infinite as the wire's f32
    }
    let file = write(dir.path(), "bomb.plan.json", &plan.to_json());
    let (motion, accepts) = counting_listener();
    let t0 = Instant::now();
    let o = run_plain(dir.path(), &file, motion, None, Duration::from_secs(20));
    let text = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    // Located: the file, the JSON path of the value, the cause.
    assert!(text.contains("bomb.plan.json"), "{text}");
    assert!(
        text.contains("steps[1].commands[0].trajectory[1][0][2]"),
        "{text}"
    );
    assert!(text.contains("32-bit float"), "{text}");
    assert!(text.lines().count() < 5, "{text}");
    // Nothing was dispatched: not one connection was made.
    std::thread::sleep(Duration::from_millis(200));
    assert_eq!(accepts.load(Ordering::SeqCst), 0);
    assert!(t0.elapsed() < Duration::from_secs(20));
}

#[test]
fn a_controller_that_drops_the_same_point_again_fails_the_run_after_bounded_attempts() {
    // A controller that publishes state but closes the motion connection on every
    // request (as the simulator did on a point it could not decode): the old manager
    // reconnected and resent forever.
    let state = fake_state_port(false);
    let l = TcpListener::bind("127.0.0.1:0").unwrap();
    let motion = l.local_addr().unwrap();
    let accepts = Arc::new(AtomicUsize::new(0));
    {
        let accepts = accepts.clone();
        std::thread::spawn(move || {
            for mut c in l.incoming().map_while(Result::ok) {
                accepts.fetch_add(1, Ordering::SeqCst);
                let mut b = [0u8; 64];
                let _ = c.read(&mut b);
                drop(c);
            }
        });
    }
    let dir = tempfile::tempdir().unwrap();
    let file = write(dir.path(), "p.plan.json", &joint_plan(1, 1.0).to_json());
    let o = run_plain(
        dir.path(),
        &file,
        motion,
        Some(state.port()),
        Duration::from_secs(40),
    );
    let text = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(text.contains("giving up"), "{text}");
    let n = accepts.load(Ordering::SeqCst);
    assert!((1..=3).contains(&n), "{n} motion connections\n{text}");
    assert!(text.lines().count() < 20, "{text}");
}

/// Peak resident memory of a running process (kB), from /proc.
fn peak_rss_kb(pid: u32) -> u64 {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    s.lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap()
}

#[test]
fn standard_input_without_a_newline_stays_in_bounded_memory() {
    let (_sim, m, s) = simulator("1");
    let dir = tempfile::tempdir().unwrap();
    let file = write(dir.path(), "slow.plan.json", &joint_plan(3, 20.0).to_json());
    let mut run = spawn(
        dir.path(),
        &[
            "skills",
            "run",
            &file,
            "--target",
            &m.to_string(),
            "--state-port",
            &s.port().to_string(),
            "--plain",
        ],
        true,
    );
    run.out.wait_for("running #0", Duration::from_secs(30));
    let mut stdin = run.child.0.stdin.take().unwrap();
    let chunk = vec![b'a'; 1 << 20];
    for _ in 0..64 {
        stdin.write_all(&chunk).unwrap(); // 64 MiB, no newline
    }
    stdin.write_all(b"\n").unwrap();
    stdin.flush().unwrap();
    let e = run.err.wait_for("standard input", Duration::from_secs(30));
    assert!(e.contains("longer than 4096 bytes"), "{e}");
    let pid = run.child.0.id();
    let peak = peak_rss_kb(pid);
    assert!(peak < 300 * 1024, "peak RSS {peak} kB");
    // Still steerable afterwards.
    stdin.write_all(b"abort\n").unwrap();
    stdin.flush().unwrap();
    run.out.wait_for("aborted", Duration::from_secs(30));
    assert_eq!(wait_exit(&mut run, Duration::from_secs(30)), Some(1));
}

#[test]
fn a_robot_with_more_joints_than_the_protocol_carries_is_refused_at_start() {
    let dir = common::project();
    let rows: String = (0..11)
        .map(|_| "    - {theta: 0, d: 100, a: 50, alpha: 90}\n".to_string())
        .collect();
    let doc = format!(
        "parts:\n  box: {{stl: meshes/table.stl}}\ncomponents:\n- {{name: b, part: box}}\nrobots:\n- name: snake\n  dh:\n    rows:\n{rows}  joints: [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]\n"
    );
    let path = write(dir.path(), "models/snake.yaml", &doc);
    let o = common::run_bounded(
        dir.path(),
        &[
            "manipulator",
            "--doc",
            &path,
            "--robot",
            "snake",
            "--port",
            "0",
            "--state-port",
            "0",
        ],
        Duration::from_secs(30),
    );
    let text = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(text.contains("11 joints"), "{text}");
    assert!(text.contains("at most 10"), "{text}");
    assert!(!text.contains("panicked"), "{text}");
}

#[test]
fn a_packet_in_two_parts_with_a_pause_is_accepted_by_both_ends() {
    // Server side: the simulator keeps the first part across its read timeout.
    let (_sim, m, s) = simulator("10");
    let mut t = TcpStream::connect(m).unwrap();
    t.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let ping = Packet::request(msg_type::PING, Body::Ping).encode(ByteOrder::Big);
    for cut in [2, 10, 30] {
        t.write_all(&ping[..cut]).unwrap();
        std::thread::sleep(Duration::from_millis(300));
        t.write_all(&ping[cut..]).unwrap();
        let r = Packet::read_from(&mut t, ByteOrder::Big).unwrap();
        assert_eq!(r.msg_type, msg_type::PING);
        assert_eq!(r.reply_code, ReplyCode::Success);
    }
    // A real client still works next to it.
    let mut c = Client::connect(m, s, KINDS.to_vec(), &ClientOptions::default()).unwrap();
    c.ping().unwrap();

    // Client side: state messages and a reply, each in two parts 300 ms apart,
    // behind the client's read timeouts.
    let state = fake_state_port(true);
    let l = TcpListener::bind("127.0.0.1:0").unwrap();
    let motion = l.local_addr().unwrap();
    std::thread::spawn(move || {
        if let Ok((mut c, _)) = l.accept() {
            let mut frames = fitup::manipulator::message::FrameReader::new(ByteOrder::Big);
            while let Ok(p) = frames.read_packet(&mut c) {
                let r = Packet::reply(p.msg_type, ReplyCode::Success, Body::Ping)
                    .encode(ByteOrder::Big);
                let _ = c.write_all(&r[..5]);
                std::thread::sleep(Duration::from_millis(300));
                let _ = c.write_all(&r[5..]);
            }
        }
    });
    let opts = ClientOptions {
        state_timeout: Duration::from_secs(2),
        reply_timeout: Duration::from_secs(2),
        ..ClientOptions::default()
    };
    let mut c = Client::connect(motion, state, KINDS.to_vec(), &opts).unwrap();
    c.ping().unwrap();
    c.ping().unwrap();
    // The state keeps flowing (no "silent" state port) through the split messages.
    std::thread::sleep(Duration::from_millis(1000));
    c.state().unwrap();
}

#[test]
fn a_flood_of_idle_connections_does_not_starve_a_real_client() {
    let (mut sim, m, s) = simulator("10");
    let t0 = Instant::now();
    // 1,100 connections that never send a byte, on the motion port, and 100 on the
    // state port that never read; all kept open during the test.
    let mut idle = Vec::new();
    for i in 0..1_200 {
        let to = if i < 1_100 { m } else { s };
        if let Ok(c) = TcpStream::connect_timeout(&to, Duration::from_secs(5)) {
            idle.push(c);
        }
    }
    assert!(idle.len() > 1_000, "{} connections made", idle.len());
    // A real client connects and gets its reply, while the flood is held open.
    let opts = ClientOptions {
        connect_timeout: Duration::from_secs(5),
        reply_timeout: Duration::from_secs(5),
        state_timeout: Duration::from_secs(5),
        ..ClientOptions::default()
    };
    let mut c = Client::connect(m, s, KINDS.to_vec(), &opts).unwrap_or_else(|e| {
        panic!("{e}\n{}", sim.err.seen.join("\n"));
    });
    c.ping().unwrap();
    let home = c.state().unwrap().joints;
    let mut to = home.clone();
    to[0] = 0.05;
    c.stream(&[(home, 0.0), (to.clone(), 0.2)]).unwrap();
    assert!(c
        .wait_until_at(&to, 1e-4, Duration::from_secs(20), &|| false)
        .unwrap());
    // More flood after the client spoke does not take its place.
    for _ in 0..200 {
        if let Ok(x) = TcpStream::connect_timeout(&m, Duration::from_secs(5)) {
            idle.push(x);
        }
    }
    c.ping().unwrap();
    // Most of the flood was closed by the simulator (the cap): read EOF on them.
    let mut closed = 0;
    for x in idle.iter_mut().take(1_000) {
        x.set_read_timeout(Some(Duration::from_millis(5))).unwrap();
        let mut b = [0u8; 1];
        match x.read(&mut b) {
            Ok(0) => closed += 1,
            Err(e)
                if !matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                closed += 1
            }
            _ => {}
        }
    }
    assert!(closed > 900, "{closed} of 1000 idle connections closed");
    sim.err.quiet(Duration::from_millis(100));
    assert!(
        sim.err.seen.iter().any(|l| l.contains("port full")),
        "{:?}",
        sim.err.seen
    );
    assert!(t0.elapsed() < Duration::from_secs(120));
}

#[test]
fn ping_errors_are_typed_not_panics_on_a_closed_port() {
    // A client whose motion connection the controller closed gets Disconnected.
    let state = fake_state_port(false);
    let (motion, _) = counting_listener();
    let mut c = Client::connect(motion, state, KINDS.to_vec(), &ClientOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let e = c.ping().unwrap_err();
    assert!(
        matches!(
            e,
            ManipulatorError::Disconnected {
                port: Port::Motion,
                ..
            }
        ),
        "{e}"
    );
}

/// A motion port whose state port by the rule (+2) would be beyond 65535 is refused
/// before any connection, with the port as a value.
#[test]
fn a_motion_port_without_a_state_port_by_the_rule_is_a_typed_address_error() {
    use fitup::manipulator::client::AddressError;
    use fitup::skills::{ManagerError, ManagerOptions, SkillManager};
    let options = ManagerOptions {
        target: "127.0.0.1:65535".into(),
        ..ManagerOptions::default()
    };
    let mut manager = SkillManager::new(joint_plan(1, 0.1), options);
    let t0 = Instant::now();
    let e = manager.run(&mut |_| {}).unwrap_err();
    match &e {
        ManagerError::Connection(ManipulatorError::Address {
            addr,
            cause: AddressError::NoStatePort { port: 65535 },
        }) => assert_eq!(addr, "127.0.0.1:65535"),
        other => panic!("{other}"),
    }
    assert!(e.to_string().contains("give the state port"), "{e}");
    assert!(t0.elapsed() < Duration::from_secs(10));
}

/// `fitup skills template FILE` in `dir`, which must end with exit 1: its output and
/// text.
fn refused_template(dir: &Path, file: &str) -> (std::process::Output, String) {
    let o = common::run_bounded(dir, &["skills", "template", file], Duration::from_secs(20));
    let text = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{}", common::short_text(&o));
    (o, text)
}

#[test]
fn an_alias_bomb_template_is_refused_fast_with_a_short_message() {
    let dir = tempfile::tempdir().unwrap();
    // ≈ 2 MB of nested aliases: expanded, 10^… strings.
    let mut t = String::from("a0: &a0 [\"lol\", \"lol\", \"lol\", \"lol\", \"lol\", \"lol\", \"lol\", \"lol\", \"lol\"]\n");
    let mut i = 1;
    while t.len() < 2_100_000 {
        let prev = format!("*a{}", i - 1);
        t += &format!(
            "a{i}: &a{i} [{}]\n",
            std::iter::repeat_n(prev.as_str(), 9)
                .collect::<Vec<_>>()
                .join(", ")
        );
        i += 1;
    }
    t += "operation: insertion\nworkflows: []\n";
    let file = write(dir.path(), "bomb.yaml", &t);
    let (o, text) = refused_template(dir.path(), &file);
    assert!(text.contains("bomb.yaml:1:"), "{}", common::short_text(&o));
    assert!(text.contains("anchors"), "{}", common::short_text(&o));
    assert!(text.len() < 2_000, "{} bytes of output", text.len());

    // A 2 MiB value is quoted as a short excerpt.
    let long = "x".repeat(2 << 20);
    let file = write(
        dir.path(),
        "long.yaml",
        &format!(
            "operation: {long}\nworkflows:\n  - {{from: FREE, to: In_WS, generator: locate}}\n"
        ),
    );
    let (o, text) = refused_template(dir.path(), &file);
    assert!(text.contains("long.yaml:1:"), "{}", common::short_text(&o));
    assert!(
        text.contains("unknown operation"),
        "{}",
        common::short_text(&o)
    );
    assert!(text.contains('…'), "{}", common::short_text(&o));
    assert!(text.len() < 2_000, "{} bytes of output", text.len());
    // And a 2 MiB value the schema refuses (serde's own message) too.
    let file = write(
        dir.path(),
        "field.yaml",
        &format!(
            "operation: insertion\n{}: 1\nworkflows: []\n",
            &long[..1000]
        ),
    );
    let (o, text) = refused_template(dir.path(), &file);
    assert!(text.contains("field.yaml:2:"), "{}", common::short_text(&o));
    assert!(text.len() < 2_000, "{} bytes of output", text.len());
}
