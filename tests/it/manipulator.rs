//! The simulated manipulator and the skill manager over loopback, driving the real
//! binaries: `fitup manipulator` and `fitup skills run`.

use crate::common;

use common::lines::Proc;
use common::{fitup, repo};
use fitup::kinematics::JointKind;
use fitup::manipulator::client::{Client, ClientOptions, Lost, ManipulatorError, Port, Request};
use fitup::manipulator::message::{msg_type, Body, ByteOrder, Packet};
use fitup::manipulator::RefusalCode;
use fitup::skills::Plan;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::process::Stdio;
use std::time::{Duration, Instant};

const KINDS: [JointKind; 6] = [JointKind::Revolute; 6];

/// `fitup ARGS…` from the repository root, its output lines on a channel.
fn spawn(args: &[&str], stdin: bool) -> Proc {
    Proc::spawn(fitup().current_dir(repo()).args(args).stdin(if stdin {
        Stdio::piped()
    } else {
        Stdio::null()
    }))
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// `fitup manipulator` on the MZ07 of `models/mz07.yaml`; returns it and its ports.
fn simulator(port: u16, state: u16, speed: &str) -> (Proc, SocketAddr, SocketAddr) {
    simulator_of("models/mz07.yaml", "mz07", port, state, speed)
}

fn simulator_of(
    doc: &str,
    robot: &str,
    port: u16,
    state: u16,
    speed: &str,
) -> (Proc, SocketAddr, SocketAddr) {
    let (p, s) = (port.to_string(), state.to_string());
    let mut sim = spawn(
        &[
            "manipulator",
            "--doc",
            doc,
            "--robot",
            robot,
            "--port",
            &p,
            "--state-port",
            &s,
            "--speed",
            speed,
        ],
        false,
    );
    let line = sim.wait_for("listening", Duration::from_secs(60));
    let (m, st) = common::listening_addrs(&line);
    (sim, m, st)
}

fn client(m: SocketAddr, s: SocketAddr) -> Client {
    Client::connect(m, s, KINDS.to_vec(), &ClientOptions::default()).unwrap()
}

/// The arm reaches where [`joint_plan`]`(3, …)` ends: joint 1 at 0.3, joint 3 at 0.15.
fn assert_at_the_end_of_three_skills(c: &Client) {
    let mut end_q = vec![0.0; 6];
    end_q[0] = 0.3;
    end_q[2] = 0.15;
    assert!(c
        .wait_until_at(&end_q, 1e-3, Duration::from_secs(10), &|| false)
        .unwrap());
}

#[test]
fn a_joint_limit_trajectory_is_refused_with_the_reason() {
    let (mut sim, m, s) = simulator(0, 0, "10");
    let mut c = client(m, s);
    c.ping().unwrap();
    let home = c.state().unwrap().joints;
    assert_eq!(home, vec![0.0; 6]);
    // Joint 2 of the MZ07 stops at −135°.
    let mut bad = home.clone();
    bad[1] = (-150f64).to_radians();
    let e = c.stream(&[(home.clone(), 0.0), (bad, 1.0)]).unwrap_err();
    match &e {
        ManipulatorError::Refused {
            request,
            msg_type,
            code,
            error_code,
        } => {
            assert_eq!(*request, Request::Point { sequence: 1 }, "{e}");
            assert_eq!(
                *msg_type,
                fitup::manipulator::message::msg_type::JOINT_TRAJ_PT
            );
            assert_eq!(*code, Some(RefusalCode::JointLimit(1)), "{e}");
            assert_eq!(*error_code, Some(1001), "{e}");
            assert!(e.to_string().contains("joint 2"), "{e}");
        }
        other => panic!("{other}"),
    }
    sim.wait_for(
        "refused point 1: joint 2 outside its limits",
        Duration::from_secs(10),
    );
    // The arm did not move, and a new trajectory (sequence 0) clears the error.
    std::thread::sleep(Duration::from_millis(200));
    assert_eq!(c.state().unwrap().joints, home);
    let mut ok = home.clone();
    ok[0] = 0.2;
    c.stream(&[(home.clone(), 0.0), (ok.clone(), 0.5)]).unwrap();
    assert!(c
        .wait_until_at(&ok, 1e-4, Duration::from_secs(20), &|| false)
        .unwrap());
    // A point out of order is refused too.
    let e = c.send_point(5, &ok, 0.1).unwrap_err();
    assert!(
        matches!(
            e,
            ManipulatorError::Refused {
                code: Some(RefusalCode::OutOfOrder),
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn a_trajectory_into_the_table_is_refused_as_a_collision() {
    // The arm `mz07_a` of the two-arm demo cell, folded back and down: its forearm
    // and flange reach into the table.
    let (mut sim, m, s) = simulator_of("models/cell_robots.yaml", "mz07_a", 0, 0, "10");
    let mut c = client(m, s);
    let home = c.state().unwrap().joints;
    let folded = vec![
        0.0,
        (-134f64).to_radians(),
        180f64.to_radians(),
        0.0,
        0.0,
        0.0,
    ];
    let e = c.stream(&[(home.clone(), 0.0), (folded, 2.0)]).unwrap_err();
    assert!(
        matches!(
            e,
            ManipulatorError::Refused {
                code: Some(RefusalCode::Collision),
                ..
            }
        ),
        "{e}"
    );
    let why = sim.wait_for("refused point 1", Duration::from_secs(30));
    assert!(why.contains("`table`"), "{why}");
    std::thread::sleep(Duration::from_millis(200));
    assert_eq!(
        c.state().unwrap().joints,
        home,
        "a refused point must not move the arm"
    );
}

#[test]
fn malformed_messages_to_the_simulator_cost_only_that_connection() {
    let (mut sim, m, s) = simulator(0, 0, "10");
    // Framing garbage (an unknown type in a sane frame is answered instead: see
    // simple_message_peer.rs).
    let garbage: [&[u8]; 3] = [
        b"GET / HTTP/1.1\r\n\r\n",   // a length prefix sane in neither order
        &[0, 0, 0, 64, 0, 0, 0, 11], // truncated, then silence
        &[0xff, 0xff, 0xff, 0xff],   // negative length
    ];
    for g in garbage {
        let mut t = TcpStream::connect(m).unwrap();
        t.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        t.write_all(g).unwrap();
        if g.len() == 8 {
            // Half a packet: the simulator waits; closing our side ends it.
            t.shutdown(std::net::Shutdown::Write).unwrap();
        }
        // The simulator closes the connection (EOF), it does not hang or crash.
        let mut buf = Vec::new();
        let _ = t.read_to_end(&mut buf);
    }
    sim.wait_for("closing the connection", Duration::from_secs(10));
    // Still serving.
    let mut c = client(m, s);
    c.ping().unwrap();
    // A request it does not serve gets FAILURE (REP-I0006); the connection stays.
    let mut t = TcpStream::connect(m).unwrap();
    t.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let jp = Body::JointPosition(fitup::manipulator::message::JointPosition {
        sequence: 0,
        joints: [0.0; 10],
    });
    for _ in 0..2 {
        Packet::request(msg_type::JOINT_POSITION, jp.clone())
            .write_to(&mut t, ByteOrder::Big)
            .unwrap();
        let r = Packet::read_from(&mut t, ByteOrder::Big).unwrap();
        assert_eq!(r.msg_type, msg_type::JOINT_POSITION);
        assert_eq!(
            r.reply_code,
            fitup::manipulator::message::ReplyCode::Failure
        );
    }
    c.ping().unwrap();
}

/// A fake controller that answers with `reply` bytes on both ports.
fn fake_controller(state_bytes: Vec<u8>, motion_bytes: Vec<u8>) -> (SocketAddr, SocketAddr) {
    let serve = |bytes: Vec<u8>| {
        let l = TcpListener::bind("127.0.0.1:0").unwrap();
        let a = l.local_addr().unwrap();
        std::thread::spawn(move || {
            if let Ok((mut t, _)) = l.accept() {
                let mut b = [0u8; 256];
                t.set_read_timeout(Some(Duration::from_millis(20))).unwrap();
                let _ = t.read(&mut b);
                let _ = t.write_all(&bytes);
                std::thread::sleep(Duration::from_millis(100));
            }
        });
        a
    };
    (serve(motion_bytes), serve(state_bytes))
}

#[test]
fn malformed_messages_from_the_controller_are_typed_errors() {
    let opts = ClientOptions {
        state_timeout: Duration::from_secs(1),
        reply_timeout: Duration::from_secs(1),
        ..ClientOptions::default()
    };
    // Garbage on the state port.
    let (m, s) = fake_controller(b"\x7f\xff\xff\xff garbage".to_vec(), vec![]);
    let e = Client::connect(m, s, KINDS.to_vec(), &opts).err().unwrap();
    assert!(
        matches!(
            e,
            ManipulatorError::Disconnected {
                port: Port::State,
                cause: Lost::Codec(_)
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("bad length prefix"), "{e}");
    // A truncated JOINT_POSITION.
    let jp = Packet::topic(
        msg_type::JOINT_POSITION,
        Body::JointPosition(fitup::manipulator::message::JointPosition {
            sequence: 0,
            joints: [0.0; 10],
        }),
    )
    .encode(ByteOrder::Big);
    let (m, s) = fake_controller(jp[..30].to_vec(), vec![]);
    let e = Client::connect(m, s, KINDS.to_vec(), &opts).err().unwrap();
    assert!(e.to_string().contains("truncated"), "{e}");
    // Silence on the state port: bounded.
    let (m, s) = fake_controller(vec![], vec![]);
    let t0 = Instant::now();
    let e = Client::connect(m, s, KINDS.to_vec(), &opts).err().unwrap();
    assert!(
        matches!(
            e,
            ManipulatorError::Disconnected {
                port: Port::State,
                cause: Lost::Closed | Lost::Silent { .. }
            }
        ),
        "{e}"
    );
    assert!(t0.elapsed() < Duration::from_secs(30));
}

#[test]
fn remote_targets_need_the_explicit_flag() {
    let e = fitup::manipulator::client::resolve("10.1.2.3:11000", false).unwrap_err();
    assert!(matches!(e, ManipulatorError::NotLocal(_)), "{e}");
    assert!(fitup::manipulator::client::resolve("10.1.2.3:11000", true).is_ok());
    let plan = write_plan(&joint_plan(1, 1.0));
    let o = fitup()
        .current_dir(repo())
        .args([
            "skills",
            "run",
            plan.path().to_str().unwrap(),
            "--target",
            "10.1.2.3:11000",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--allow-remote"), "{err}");
}

/// A plan of joint moves of the MZ07: each skill turns joint 1 (and 3) a little,
/// `seconds` per skill.
fn joint_plan(skills: usize, seconds: f64) -> Plan {
    let mut q = vec![0.0; 6];
    let mut steps = Vec::new();
    for i in 0..skills {
        let start = q.clone();
        let mut pts = vec![(start.clone(), 0.0)];
        let n = 10;
        for k in 1..=n {
            let mut p = start.clone();
            p[0] += 0.1 * k as f64 / n as f64;
            p[2] += 0.05 * k as f64 / n as f64;
            pts.push((p, seconds / n as f64));
        }
        q = pts.last().unwrap().0.clone();
        let end = if i + 1 == skills {
            fitup::skills::PartState::Adjusted
        } else {
            fitup::skills::PartState::Grasped
        };
        steps.push(common::gear_move_step(i, end, pts));
    }
    common::mz07_plan(steps)
}

fn write_plan(plan: &Plan) -> tempfile::NamedTempFile {
    let f = tempfile::Builder::new().suffix(".json").tempfile().unwrap();
    std::fs::write(f.path(), plan.to_json()).unwrap();
    f
}

#[test]
fn pause_and_resume_mid_run() {
    let (_sim, m, s) = simulator(0, 0, "1");
    let plan = write_plan(&joint_plan(3, 2.0));
    let target = m.to_string();
    let state = s.port().to_string();
    let mut run = spawn(
        &[
            "skills",
            "run",
            plan.path().to_str().unwrap(),
            "--target",
            &target,
            "--state-port",
            &state,
        ],
        true,
    );
    run.wait_for("running #1", Duration::from_secs(30));
    std::thread::sleep(Duration::from_millis(500));
    run.send("pause");
    run.wait_for("paused", Duration::from_secs(10));
    // The arm holds still while paused.
    let c = client(m, s);
    std::thread::sleep(Duration::from_millis(200));
    let a = c.state().unwrap().joints;
    std::thread::sleep(Duration::from_millis(600));
    let b = c.state().unwrap().joints;
    assert_eq!(a, b, "the arm moved while paused");
    assert!(a[0] > 0.1 && a[0] < 0.2, "paused inside skill #1: {a:?}");
    run.send("manual output 3 1");
    run.wait_for("manual", Duration::from_secs(10));
    run.send("resume");
    run.wait_for("resumed", Duration::from_secs(10));
    run.wait_for("done", Duration::from_secs(60));
    let finished: Vec<_> = run
        .seen()
        .iter()
        .filter(|l| l.starts_with("finished"))
        .collect();
    assert_eq!(finished.len(), 3, "{:?}", run.seen());
    assert_at_the_end_of_three_skills(&c);
}

#[test]
fn killing_the_simulator_mid_skill_interrupts_and_resumes_without_repeating() {
    let (port, state_port) = (free_port(), free_port());
    let (sim, m, s) = simulator(port, state_port, "1");
    let plan = write_plan(&joint_plan(3, 2.0));
    let db_dir = tempfile::tempdir().unwrap();
    let db_file = db_dir.path().join("log.db");
    let mut run = spawn(
        &[
            "skills",
            "run",
            plan.path().to_str().unwrap(),
            "--target",
            &m.to_string(),
            "--state-port",
            &s.port().to_string(),
            "--db",
            db_file.to_str().unwrap(),
        ],
        false,
    );
    run.wait_for("finished #0", Duration::from_secs(30));
    run.wait_for("running #1", Duration::from_secs(30));
    std::thread::sleep(Duration::from_millis(700));
    drop(sim); // SIGKILL mid-skill
    run.wait_for("interrupted #1", Duration::from_secs(30));
    let (_sim2, _, _) = simulator(port, state_port, "1");
    run.wait_for("reconnected", Duration::from_secs(30));
    run.wait_for("done", Duration::from_secs(60));
    let count = |p: &str| run.seen().iter().filter(|l| l.starts_with(p)).count();
    assert_eq!(count("running #0"), 1, "{:?}", run.seen());
    assert_eq!(count("finished #0"), 1, "{:?}", run.seen());
    assert_eq!(count("finished #1"), 1, "{:?}", run.seen());
    assert_eq!(count("finished #2"), 1, "{:?}", run.seen());
    // The execution log is in the database, written as it happened.
    let mut db = fitup::db::Database::open(&fitup::db::Target::Sqlite(db_file.clone())).unwrap();
    let log = db.skill_log(None).unwrap();
    let events: Vec<(Option<i64>, &str)> = log.iter().map(|e| (e.skill, e.event_name())).collect();
    let finished: Vec<_> = events.iter().filter(|e| e.1 == "finished").collect();
    assert_eq!(
        finished,
        [
            &(Some(0), "finished"),
            &(Some(1), "finished"),
            &(Some(2), "finished")
        ],
        "{events:?}"
    );
    assert!(events.contains(&(Some(1), "interrupted")), "{events:?}");
    assert!(events.contains(&(None, "reconnected")), "{events:?}");
    assert_eq!(events.last(), Some(&(None, "done")));
    assert!(log.iter().all(|e| e.plan.ends_with(".json")));
    assert_eq!(log[1].part.as_deref(), Some("gear"));
    // The restarted controller started at home and ends where the plan ends.
    let c = client(m, s);
    assert_at_the_end_of_three_skills(&c);
}

/// The client's errors carry their causes as values (issue 25): an address that
/// does not parse keeps its `io::Error`, a value the wire cannot carry names the
/// request, the joint and the value, a tool value the same, a wait that ran out
/// names how long — and every one still reads clearly.
#[test]
fn client_errors_name_their_causes_in_fields() {
    use fitup::manipulator::client::{resolve, AddressError, WireError};
    use fitup::manipulator::message::ToolAction;
    use std::error::Error as _;
    let e = resolve("127.0.0.1:notaport", false).unwrap_err();
    match &e {
        ManipulatorError::Address {
            addr,
            cause: AddressError::Resolve(io),
        } => {
            assert_eq!(addr, "127.0.0.1:notaport");
            assert_eq!(io.kind(), std::io::ErrorKind::InvalidInput, "{e}");
        }
        other => panic!("{other}"),
    }
    assert!(e.source().is_some(), "the cause is the error's source");
    assert!(
        e.to_string()
            .starts_with("bad address `127.0.0.1:notaport`: "),
        "{e}"
    );

    let (_sim, m, s) = simulator(0, 0, "10");
    let mut c = client(m, s);
    let mut q = vec![0.0; 6];
    q[2] = 1e39; // finite in f64, infinite as the wire's f32
    let e = c.send_point(0, &q, 0.1).unwrap_err();
    match &e {
        ManipulatorError::NotOnWire {
            request: Request::Point { sequence: 0 },
            cause: WireError::Joint { joint: 2, value },
        } => assert_eq!(*value, 1e39),
        other => panic!("{other}"),
    }
    assert!(
        e.to_string()
            .contains("trajectory point 0 cannot be sent: joint 3 = "),
        "{e}"
    );
    let e = c.send_point(0, &[0.0; 6], f64::NAN).unwrap_err();
    assert!(
        matches!(
            &e,
            ManipulatorError::NotOnWire {
                cause: WireError::Duration(d),
                ..
            } if d.is_nan()
        ),
        "{e}"
    );
    let e = c.send_point(0, &[0.0; 5], 0.1).unwrap_err();
    assert!(
        matches!(
            e,
            ManipulatorError::NotOnWire {
                cause: WireError::JointCount { got: 5, joints: 6 },
                ..
            }
        ),
        "{e}"
    );
    let e = c.tool(ToolAction::Grasp, 0, f32::INFINITY).unwrap_err();
    match &e {
        ManipulatorError::NotOnWire {
            request: Request::Tool { action },
            cause: WireError::ToolValue(v),
        } => {
            assert_eq!(action, "Grasp");
            assert!(v.is_infinite());
        }
        other => panic!("{other}"),
    }
    // A target the arm does not reach within the wait (nothing was sent).
    let e = c
        .wait_until_at(&[1.0; 6], 1e-6, Duration::from_millis(50), &|| false)
        .unwrap_err();
    match &e {
        ManipulatorError::Timeout { waited } => assert_eq!(*waited, Duration::from_millis(50)),
        other => panic!("{other}"),
    }
    assert!(e.to_string().contains("within 0.05 s"), "{e}");
}
