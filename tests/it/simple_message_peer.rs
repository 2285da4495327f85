//! simple_message against peers fitup did not write: a minimal client and a minimal
//! controller written here from REP-I0006's byte layout (prefix `length: shared_int`;
//! header `msg_type, comm_type, reply_code: shared_int`; bodies as the REP lists
//! them), in both byte orders, driving the real binaries — `fitup manipulator` as
//! the server and `fitup skills run --target` as the client. Nothing here uses
//! fitup's codec: a bug shared by fitup's encoder and decoder cannot hide.

use crate::common;

use common::lines::Proc;
use common::{fitup, free_pair, repo};
use fitup::skills::Plan;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::process::Stdio;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

// ---- The peer's own codec, from REP-I0006 ----------------------------------------

const PING: i32 = 1;
const GET_VERSION: i32 = 2;
const JOINT_POSITION: i32 = 10;
const JOINT_TRAJ_PT: i32 = 11;
const STATUS: i32 = 13;
const JOINT_FEEDBACK: i32 = 15;
const FITUP_TOOL: i32 = 65001;

const TOPIC: i32 = 1;
const REQUEST: i32 = 2;
const REPLY: i32 = 3;

const INVALID: i32 = 0;
const SUCCESS: i32 = 1;
const FAILURE: i32 = 2;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Order {
    Big,
    Little,
}

const BOTH: [Order; 2] = [Order::Big, Order::Little];

impl Order {
    fn name(self) -> &'static str {
        match self {
            Order::Big => "big",
            Order::Little => "little",
        }
    }
    fn int(self, v: i32) -> [u8; 4] {
        match self {
            Order::Big => v.to_be_bytes(),
            Order::Little => v.to_le_bytes(),
        }
    }
    fn real(self, v: f32) -> [u8; 4] {
        self.int(v.to_bits() as i32)
    }
    fn get_int(self, b: &[u8]) -> i32 {
        let w = [b[0], b[1], b[2], b[3]];
        match self {
            Order::Big => i32::from_be_bytes(w),
            Order::Little => i32::from_le_bytes(w),
        }
    }
    fn get_real(self, b: &[u8]) -> f32 {
        f32::from_bits(self.get_int(b) as u32)
    }
}

/// One message as received: header fields and the body bytes.
#[derive(Debug, Clone)]
struct Msg {
    msg_type: i32,
    comm: i32,
    reply: i32,
    body: Vec<u8>,
}

/// Prefix + header + `body`.
fn frame(o: Order, msg_type: i32, comm: i32, reply: i32, body: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend(o.int(12 + body.len() as i32));
    out.extend(o.int(msg_type));
    out.extend(o.int(comm));
    out.extend(o.int(reply));
    out.extend(body);
    out
}

fn ints(o: Order, v: &[i32]) -> Vec<u8> {
    v.iter().flat_map(|&x| o.int(x)).collect()
}

/// JOINT_TRAJ_PT body: sequence, joint_data[10], velocity, duration.
fn traj_pt(o: Order, seq: i32, joints: &[f32], velocity: f32, duration: f32) -> Vec<u8> {
    let mut b = o.int(seq).to_vec();
    for i in 0..10 {
        b.extend(o.real(joints.get(i).copied().unwrap_or(0.0)));
    }
    b.extend(o.real(velocity));
    b.extend(o.real(duration));
    b
}

/// JOINT_POSITION body: sequence (0), joint_data[10].
fn joint_position(o: Order, joints: &[f32]) -> Vec<u8> {
    let mut b = o.int(0).to_vec();
    for i in 0..10 {
        b.extend(o.real(joints.get(i).copied().unwrap_or(0.0)));
    }
    b
}

/// Reads one message (bounded by the stream's read timeout; lengths checked).
fn read_msg(s: &mut impl Read, o: Order) -> std::io::Result<Msg> {
    let mut p = [0u8; 4];
    s.read_exact(&mut p)?;
    let len = o.get_int(&p);
    if !(12..=1024).contains(&len) {
        return Err(std::io::Error::other(format!("bad length {len}")));
    }
    let mut m = vec![0u8; len as usize];
    s.read_exact(&mut m)?;
    Ok(Msg {
        msg_type: o.get_int(&m[0..]),
        comm: o.get_int(&m[4..]),
        reply: o.get_int(&m[8..]),
        body: m[12..].to_vec(),
    })
}

/// The REP-I0006 appendix A examples (printed big-endian), as bytes in order `o`:
/// every field is 4 bytes, so the little-endian stream reverses each word.
fn appendix(example: &str, o: Order) -> Vec<u8> {
    let s: String = example.split_whitespace().collect();
    let big: Vec<u8> = (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
        .collect();
    match o {
        Order::Big => big,
        Order::Little => big
            .chunks(4)
            .flat_map(|w| w.iter().rev().copied().collect::<Vec<_>>())
            .collect(),
    }
}

const APPENDIX_JOINT_POSITION: &str = "00000038 0000000A 00000001 00000000 00000000 B81AD9FA
    B6836312 B7C043F5 B8B81516 B865D055 B8B6365E 00000000 00000000 00000000 00000000";
const APPENDIX_JOINT_TRAJ_PT: &str = "00000040 0000000B 00000002 00000000 00000001 A7600000
    3EA7CDE8 BF5D9E57 C0490FDB 3F34815F C0490FDB 00000000 00000000 00000000 00000000
    3DCCCCCD 40A00000";
const APPENDIX_STATUS: &str = "00000028 0000000D 00000001 00000000 00000001 FFFFFFFF
    00000000 00000000 00000000 00000002 00000001";

// ---- Driving `fitup manipulator` ---------------------------------------------------

/// `fitup ARGS…` from the repository root, its output lines on a channel.
fn spawn(args: &[&str]) -> Proc {
    Proc::spawn(fitup().current_dir(repo()).args(args).stdin(Stdio::null()))
}

/// `fitup manipulator --port P` on the MZ07 (no `--state-port`: the rule gives it),
/// with `extra` arguments; returns it and the ports it printed.
fn manipulator(extra: &[&str]) -> (Proc, u16, SocketAddr, SocketAddr) {
    let p = free_pair();
    let ps = p.to_string();
    let mut args = common::MZ07_SIMULATOR.to_vec();
    args.extend(["--port", &ps, "--speed", "20"]);
    args.extend(extra);
    let mut sim = spawn(&args);
    let line = sim.wait_for("listening", Duration::from_secs(60));
    let (m, st) = common::listening_addrs(&line);
    (sim, p, m, st)
}

fn connect(a: SocketAddr) -> TcpStream {
    let t = TcpStream::connect(a).unwrap();
    t.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    t.set_nodelay(true).unwrap();
    t
}

/// Sends `bytes` and reads the reply (skipping nothing: the next message on the
/// motion connection must be the reply).
fn call(t: &mut TcpStream, o: Order, bytes: &[u8]) -> Msg {
    t.write_all(bytes).unwrap();
    read_msg(t, o).unwrap()
}

/// A motion connection of order `o` that has spoken (a header-only PING), so that
/// state connections opened after it speak `o` too.
fn motion(m: SocketAddr, o: Order) -> TcpStream {
    let mut t = connect(m);
    let r = call(&mut t, o, &frame(o, PING, REQUEST, INVALID, &[]));
    assert_eq!((r.msg_type, r.comm, r.reply), (PING, REPLY, SUCCESS));
    t
}

/// The next STATUS on a state connection whose `in_error` is `want` (bounded);
/// returns its body as ints.
fn status_with_in_error(s: &mut TcpStream, o: Order, want: i32) -> Vec<i32> {
    let end = Instant::now() + Duration::from_secs(10);
    while Instant::now() < end {
        let m = read_msg(s, o).unwrap();
        assert_eq!(m.comm, TOPIC);
        if m.msg_type == STATUS {
            assert_eq!(m.body.len(), 28);
            let v: Vec<i32> = m.body.chunks(4).map(|c| o.get_int(c)).collect();
            if v[3] == want {
                return v;
            }
        }
    }
    panic!("no STATUS with in_error {want}");
}

/// The arm's joints from the next JOINT_POSITION (rad).
fn joints_now(s: &mut TcpStream, o: Order) -> Vec<f32> {
    loop {
        let m = read_msg(s, o).unwrap();
        if m.msg_type == JOINT_POSITION {
            assert_eq!(m.body.len(), 44);
            assert_eq!(o.get_int(&m.body), 0, "sequence is 0 in joint state");
            return m.body[4..].chunks(4).map(|c| o.get_real(c)).collect();
        }
    }
}

#[test]
fn a_header_only_ping_and_a_full_ping_succeed_in_both_orders() {
    let (_sim, _, m, _) = manipulator(&[]);
    for o in BOTH {
        let mut t = connect(m);
        // industrial_core's PingMessage: length 12, PING, SERVICE_REQUEST, INVALID.
        let bytes = frame(o, PING, REQUEST, INVALID, &[]);
        assert_eq!(bytes.len(), 16);
        for _ in 0..2 {
            let r = call(&mut t, o, &bytes);
            assert_eq!(
                (r.msg_type, r.comm, r.reply),
                (PING, REPLY, SUCCESS),
                "{o:?}"
            );
            assert!(r.body.is_empty(), "reply in the request's form");
        }
        // REP-I0006's form: ten zero ints each way.
        let r = call(
            &mut t,
            o,
            &frame(o, PING, REQUEST, INVALID, &ints(o, &[0; 10])),
        );
        assert_eq!(
            (r.msg_type, r.comm, r.reply),
            (PING, REPLY, SUCCESS),
            "{o:?}"
        );
        assert_eq!(r.body, vec![0u8; 40]);
    }
}

#[test]
fn unsupported_requests_get_failure_and_unknown_topics_are_ignored_in_both_orders() {
    let (mut sim, _, m, _) = manipulator(&[]);
    for o in BOTH {
        let mut t = connect(m);
        // GET_VERSION (REP-I0006: request is header only; this server does not serve it).
        let r = call(&mut t, o, &frame(o, GET_VERSION, REQUEST, INVALID, &[]));
        assert_eq!(
            (r.msg_type, r.comm, r.reply),
            (GET_VERSION, REPLY, FAILURE),
            "{o:?}"
        );
        // An unknown type with a body; JOINT_POSITION as a request (deprecated use).
        let r = call(
            &mut t,
            o,
            &frame(o, 777, REQUEST, INVALID, &ints(o, &[1, 2, 3])),
        );
        assert_eq!(
            (r.msg_type, r.comm, r.reply),
            (777, REPLY, FAILURE),
            "{o:?}"
        );
        let r = call(
            &mut t,
            o,
            &frame(
                o,
                JOINT_POSITION,
                REQUEST,
                INVALID,
                &joint_position(o, &[0.0; 6]),
            ),
        );
        assert_eq!((r.msg_type, r.reply), (JOINT_POSITION, FAILURE), "{o:?}");
        // Topics it does not act on, a reply nobody asked for, a bad comm_type: no
        // answer, no disconnection: the next message is the PING's reply.
        let mut quiet = frame(o, JOINT_FEEDBACK, TOPIC, INVALID, &ints(o, &[0; 33]));
        quiet.extend(appendix(APPENDIX_JOINT_POSITION, o));
        quiet.extend(appendix(APPENDIX_STATUS, o));
        quiet.extend(frame(o, 4242, TOPIC, INVALID, &[]));
        quiet.extend(frame(o, JOINT_TRAJ_PT, REPLY, SUCCESS, &[]));
        quiet.extend(frame(o, PING, 9, INVALID, &[]));
        quiet.extend(frame(o, PING, REQUEST, INVALID, &[]));
        let r = call(&mut t, o, &quiet);
        assert_eq!(
            (r.msg_type, r.comm, r.reply),
            (PING, REPLY, SUCCESS),
            "{o:?}"
        );
    }
    let log = sim.drain();
    assert!(!log.contains("closing the connection"), "{log}");
}

#[test]
fn a_flood_of_refused_requests_is_answered_each_and_logged_a_bounded_number_of_times() {
    let (mut sim, _, m, _) = manipulator(&[]);
    let n = 20_000;
    let mut t = connect(m);
    let o = Order::Little;
    let one = frame(o, GET_VERSION, REQUEST, INVALID, &[]);
    let all: Vec<u8> = (0..n).flat_map(|_| one.clone()).collect();
    let mut w = t.try_clone().unwrap();
    // Written from another thread: the replies come back while the requests go out.
    let writer = std::thread::spawn(move || w.write_all(&all).is_ok());
    for i in 0..n {
        let r = read_msg(&mut t, o).unwrap_or_else(|e| panic!("reply {i}: {e}"));
        assert_eq!((r.msg_type, r.reply), (GET_VERSION, FAILURE));
    }
    assert!(writer.join().unwrap());
    let r = call(&mut t, o, &frame(o, PING, REQUEST, INVALID, &[]));
    assert_eq!(r.reply, SUCCESS);
    std::thread::sleep(Duration::from_millis(200));
    let log = sim.drain();
    let lines = log
        .lines()
        .filter(|l| l.contains("replied FAILURE"))
        .count();
    assert!((1..=8).contains(&lines), "{lines} log lines:\n{log}");
    assert!(log.contains("not logged"), "{log}");
}

#[test]
fn a_non_finite_or_out_of_range_point_gets_failure_and_code_4000_in_both_orders() {
    let (_sim, p, m, s) = manipulator(&[]);
    // The port rule: no --state-port given, the state port is P + 2.
    assert_eq!(m.port(), p);
    assert_eq!(s.port(), p + 2);
    for o in BOTH {
        let mut t = motion(m, o);
        let mut st = connect(s);
        let home = joints_now(&mut st, o);
        let bad: [(&str, Vec<u8>); 6] = [
            ("NaN joint", traj_pt(o, 0, &[f32::NAN], 1.0, 1.0)),
            (
                "infinite joint",
                traj_pt(o, 0, &[0.0, f32::INFINITY], 1.0, 1.0),
            ),
            ("NaN duration", traj_pt(o, 0, &home, 1.0, f32::NAN)),
            ("negative duration", traj_pt(o, 0, &home, 1.0, -1.0)),
            ("velocity above 1", traj_pt(o, 0, &home, 2.0, 0.0)),
            ("a 7th joint on a 6-axis arm", {
                let mut q = home.clone();
                q[6] = 0.5;
                traj_pt(o, 0, &q, 1.0, 1.0)
            }),
        ];
        for (what, body) in bad {
            let r = call(&mut t, o, &frame(o, JOINT_TRAJ_PT, REQUEST, INVALID, &body));
            assert_eq!(
                (r.msg_type, r.comm, r.reply),
                (JOINT_TRAJ_PT, REPLY, FAILURE),
                "{what}, {o:?}"
            );
            let v = status_with_in_error(&mut st, o, 1);
            assert_eq!(v[2], 4000, "{what}, {o:?}: STATUS {v:?}");
            assert_eq!(v[6], 0, "motion not possible while in error");
            // A new trajectory clears it, so that the next case is seen on its own.
            let good = traj_pt(o, 0, &home, 1.0, 0.1);
            let r = call(&mut t, o, &frame(o, JOINT_TRAJ_PT, REQUEST, INVALID, &good));
            assert_eq!(r.reply, SUCCESS, "{what}, {o:?}");
            status_with_in_error(&mut st, o, 0);
        }
        // A wrong body size is a bad point too (the stream stays in step).
        let r = call(
            &mut t,
            o,
            &frame(o, JOINT_TRAJ_PT, REQUEST, INVALID, &ints(o, &[0; 5])),
        );
        assert_eq!((r.msg_type, r.reply), (JOINT_TRAJ_PT, FAILURE), "{o:?}");
        // The connection still works: a good point (a new trajectory) succeeds and
        // clears the error; the arm did not move.
        let r = call(
            &mut t,
            o,
            &frame(
                o,
                JOINT_TRAJ_PT,
                REQUEST,
                INVALID,
                &traj_pt(o, 0, &home, 1.0, 0.1),
            ),
        );
        assert_eq!(r.reply, SUCCESS, "{o:?}");
        let v = status_with_in_error(&mut st, o, 0);
        assert_eq!(v[2], 0);
        let now = joints_now(&mut st, o);
        for (a, b) in now.iter().zip(&home) {
            assert!((a - b).abs() < 1e-6, "{now:?} vs {home:?}");
        }
    }
}

#[test]
fn the_appendix_joint_traj_pt_is_answered_in_both_orders() {
    let (_sim, _, m, s) = manipulator(&[]);
    for o in BOTH {
        let mut t = motion(m, o);
        let mut st = connect(s);
        let home = joints_now(&mut st, o);
        let start = frame(
            o,
            JOINT_TRAJ_PT,
            REQUEST,
            INVALID,
            &traj_pt(o, 0, &home, 1.0, 0.1),
        );
        assert_eq!(call(&mut t, o, &start).reply, SUCCESS);
        // The appendix point (sequence 1, velocity 0.1, duration 5 s): the REP's bytes
        // verbatim. Its joints are within the MZ07's limits; whether the move is
        // free of the cell is the controller's call, but it is a reply, not a
        // disconnection.
        let bytes = appendix(APPENDIX_JOINT_TRAJ_PT, o);
        assert_eq!(bytes.len(), 68);
        let r = call(&mut t, o, &bytes);
        assert_eq!((r.msg_type, r.comm), (JOINT_TRAJ_PT, REPLY), "{o:?}");
        assert!(r.reply == SUCCESS || r.reply == FAILURE, "{r:?}");
        // STOP_TRAJECTORY (-4) is acknowledged.
        let stop = frame(
            o,
            JOINT_TRAJ_PT,
            REQUEST,
            INVALID,
            &traj_pt(o, -4, &[], 0.0, 0.0),
        );
        assert_eq!(call(&mut t, o, &stop).reply, SUCCESS);
        let r = call(&mut t, o, &frame(o, PING, REQUEST, INVALID, &[]));
        assert_eq!(r.reply, SUCCESS);
    }
}

#[test]
fn state_messages_follow_the_rep_layout_in_the_order_heard_or_forced() {
    // Detected: a state connection speaks the order of the last motion connection
    // heard before it (big-endian before any).
    let (_sim, _, m, s) = manipulator(&[]);
    let mut st = connect(s);
    joints_now(&mut st, Order::Big);
    for o in [Order::Little, Order::Big, Order::Little] {
        let _t = motion(m, o);
        let mut st = connect(s);
        let m1 = read_msg(&mut st, o).unwrap();
        let m2 = read_msg(&mut st, o).unwrap();
        // JOINT_POSITION (length 56) then STATUS (length 40), topics, reply INVALID.
        assert_eq!(
            (m1.msg_type, m1.comm, m1.reply, m1.body.len()),
            (JOINT_POSITION, TOPIC, INVALID, 44)
        );
        assert_eq!(
            (m2.msg_type, m2.comm, m2.reply, m2.body.len()),
            (STATUS, TOPIC, INVALID, 28)
        );
        let v: Vec<i32> = m2.body.chunks(4).map(|c| o.get_int(c)).collect();
        assert_eq!(v[0], 1, "drives powered");
        assert_eq!(v[5], 2, "AUTO mode");
    }
    // Forced: every connection speaks it, a client in the other order is refused
    // (its length prefix is garbage in the forced order) and only it.
    for o in BOTH {
        let other = if o == Order::Big {
            Order::Little
        } else {
            Order::Big
        };
        let (mut sim, _, m, s) = manipulator(&["--byte-order", o.name()]);
        assert!(sim.drain().contains(if o == Order::Big {
            "big-endian"
        } else {
            "little-endian"
        }));
        let mut st = connect(s);
        joints_now(&mut st, o);
        let mut wrong = connect(m);
        wrong
            .write_all(&frame(other, PING, REQUEST, INVALID, &[]))
            .unwrap();
        let mut buf = Vec::new();
        let _ = wrong.read_to_end(&mut buf);
        assert!(buf.is_empty(), "{buf:?}");
        sim.wait_for("bad length prefix", Duration::from_secs(10));
        let _t = motion(m, o);
    }
}

#[test]
fn the_state_port_flag_overrides_the_rule_on_the_server() {
    let q = free_pair();
    let qs = (q + 1).to_string();
    let (_sim, p, m, s) = manipulator(&["--state-port", &qs]);
    assert_eq!((m.port(), s.port()), (p, q + 1));
    let mut st = connect(s);
    joints_now(&mut st, Order::Big);
}

// ---- Driving `fitup skills run` against a controller written here ----------------

/// What the controller written here saw.
#[derive(Default)]
struct Seen {
    /// (sequence, joints) of every JOINT_TRAJ_PT.
    points: Vec<(i32, Vec<f32>)>,
    /// Message types of every request.
    requests: Vec<i32>,
    /// Frames it could not read (a bad length: the wrong byte order).
    errors: Vec<String>,
}

/// A controller speaking order `o` on motion port `motion` and state port `state`:
/// replies like industrial_core's typed messages (header-only PING reply; the
/// JOINT_TRAJ_PT reply echoes the point), moves the arm to each point at once, and
/// publishes a JOINT_FEEDBACK (which a client that does not know it must ignore),
/// JOINT_POSITION and STATUS every 20 ms.
fn controller(o: Order, motion: u16, state: u16) -> (Arc<Mutex<Seen>>, Arc<AtomicBool>) {
    let seen = Arc::new(Mutex::new(Seen::default()));
    let stop = Arc::new(AtomicBool::new(false));
    let joints = Arc::new(Mutex::new(vec![0f32; 6]));
    let ml = TcpListener::bind(("127.0.0.1", motion)).unwrap();
    let sl = TcpListener::bind(("127.0.0.1", state)).unwrap();
    for l in [&ml, &sl] {
        l.set_nonblocking(true).unwrap();
    }
    {
        let (seen, stop, joints) = (seen.clone(), stop.clone(), joints.clone());
        std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                let Ok((mut c, _)) = ml.accept() else {
                    std::thread::sleep(Duration::from_millis(5));
                    continue;
                };
                c.set_nonblocking(false).unwrap();
                c.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
                let (seen, joints) = (seen.clone(), joints.clone());
                std::thread::spawn(move || loop {
                    let m = match read_msg(&mut c, o) {
                        Ok(m) => m,
                        Err(e) => {
                            if e.kind() != std::io::ErrorKind::UnexpectedEof {
                                seen.lock().unwrap().errors.push(e.to_string());
                            }
                            return;
                        }
                    };
                    assert_eq!((m.comm, m.reply), (REQUEST, INVALID));
                    seen.lock().unwrap().requests.push(m.msg_type);
                    let reply = match m.msg_type {
                        PING => frame(o, PING, REPLY, SUCCESS, &[]),
                        JOINT_TRAJ_PT => {
                            assert_eq!(m.body.len(), 52);
                            let seq = o.get_int(&m.body);
                            let q: Vec<f32> =
                                m.body[4..44].chunks(4).map(|c| o.get_real(c)).collect();
                            let (velocity, duration) =
                                (o.get_real(&m.body[44..]), o.get_real(&m.body[48..]));
                            assert!((0.0..=1.0).contains(&velocity) && duration >= 0.0);
                            if seq >= 0 {
                                *joints.lock().unwrap() = q[..6].to_vec();
                            }
                            seen.lock().unwrap().points.push((seq, q));
                            frame(o, JOINT_TRAJ_PT, REPLY, SUCCESS, &m.body)
                        }
                        FITUP_TOOL => frame(o, FITUP_TOOL, REPLY, SUCCESS, &m.body),
                        t => frame(o, t, REPLY, FAILURE, &[]),
                    };
                    if c.write_all(&reply).is_err() {
                        return;
                    }
                });
            }
        });
    }
    {
        let stop = stop.clone();
        std::thread::spawn(move || {
            let mut clients: Vec<TcpStream> = Vec::new();
            while !stop.load(Ordering::Relaxed) {
                while let Ok((c, _)) = sl.accept() {
                    c.set_nonblocking(false).unwrap();
                    clients.push(c);
                }
                let q = joints.lock().unwrap().clone();
                let mut b = frame(o, JOINT_FEEDBACK, TOPIC, INVALID, &ints(o, &[0; 33]));
                b.extend(frame(
                    o,
                    JOINT_POSITION,
                    TOPIC,
                    INVALID,
                    &joint_position(o, &q),
                ));
                b.extend(frame(
                    o,
                    STATUS,
                    TOPIC,
                    INVALID,
                    &ints(o, &[1, 0, 0, 0, 0, 2, 1]),
                ));
                clients.retain_mut(|c| c.write_all(&b).is_ok());
                std::thread::sleep(Duration::from_millis(20));
            }
        });
    }
    (seen, stop)
}

/// Two skills of small joint moves from zero, each with a tool command.
fn plan() -> Plan {
    let mut q = vec![0.0; 6];
    let mut steps = Vec::new();
    for i in 0..2 {
        let start = q.clone();
        let mut pts = vec![(start.clone(), 0.0)];
        for k in 1..=4 {
            let mut p = start.clone();
            p[0] += 0.1 * k as f64 / 4.0;
            p[2] -= 0.05 * k as f64 / 4.0;
            pts.push((p, 0.05));
        }
        q = pts.last().unwrap().0.clone();
        steps.push(common::gear_move_step(
            i,
            fitup::skills::PartState::Grasped,
            pts,
        ));
    }
    common::mz07_plan(steps)
}

fn run_plan(args: &[&str]) -> (Option<i32>, String) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("p.plan.json");
    std::fs::write(&file, plan().to_json()).unwrap();
    let mut all = vec!["skills", "run", file.to_str().unwrap(), "--plain"];
    all.extend(args);
    let o = common::run_bounded(dir.path(), &all, Duration::from_secs(60));
    (o.status.code(), common::text(&o))
}

fn assert_plan_ran(seen: &Seen, o: Order, text: &str) {
    assert!(seen.errors.is_empty(), "{o:?}: {:?}\n{text}", seen.errors);
    // Each skill's trajectory streamed from sequence 0, in order.
    let seqs: Vec<i32> = seen.points.iter().map(|p| p.0).collect();
    assert_eq!(seqs, [0, 1, 2, 3, 4, 0, 1, 2, 3, 4], "{o:?}\n{text}");
    let last = &seen.points.last().unwrap().1;
    let want = [0.2f32, 0.0, -0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    for (a, b) in last.iter().zip(want) {
        assert!((a - b).abs() < 1e-6, "{o:?}: {last:?}");
    }
    assert_eq!(
        seen.requests.iter().filter(|&&t| t == FITUP_TOOL).count(),
        2,
        "{o:?}"
    );
}

#[test]
fn skills_run_drives_a_controller_written_from_the_rep_in_both_orders() {
    for o in BOTH {
        let p = free_pair();
        // The port rule on the client: only --target P given, state at P + 2.
        let (seen, stop) = controller(o, p, p + 2);
        let target = format!("127.0.0.1:{p}");
        let (code, text) = run_plan(&["--target", &target, "--byte-order", o.name()]);
        stop.store(true, Ordering::Relaxed);
        assert_eq!(code, Some(0), "{o:?}\n{text}");
        assert!(text.contains("done"), "{text}");
        assert_plan_ran(&seen.lock().unwrap(), o, &text);
    }
}

#[test]
fn skills_run_state_port_flag_overrides_the_rule() {
    let p = free_pair();
    let q = free_pair();
    let (seen, stop) = controller(Order::Little, p, q);
    let target = format!("127.0.0.1:{p}");
    let qs = q.to_string();
    let (code, text) = run_plan(&[
        "--target",
        &target,
        "--state-port",
        &qs,
        "--byte-order",
        "little",
    ]);
    stop.store(true, Ordering::Relaxed);
    assert_eq!(code, Some(0), "{text}");
    assert_plan_ran(&seen.lock().unwrap(), Order::Little, &text);
}

#[test]
fn skills_run_against_fitup_manipulator_uses_the_same_port_rule() {
    // `fitup manipulator --port P` and `skills run --target 127.0.0.1:P`, nothing
    // else: the two sides agree on P + 2 (they did not: 11002 vs P + 2).
    let (_sim, p, _, _) = manipulator(&[]);
    let mut pl = plan();
    // Start from the MZ07's saved pose (all zeros in models/mz07.yaml is not
    // assumed): the first point of each skill is where the arm is; the simulator
    // refuses nothing for a plan of small moves.
    pl.steps.truncate(1);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("p.plan.json");
    std::fs::write(&file, pl.to_json()).unwrap();
    for o in BOTH {
        let target = format!("127.0.0.1:{p}");
        let o_name = o.name();
        let args = [
            "skills",
            "run",
            file.to_str().unwrap(),
            "--plain",
            "--target",
            &target,
            "--byte-order",
            o_name,
        ];
        let out = common::run_bounded(dir.path(), &args, Duration::from_secs(60));
        let text = common::text(&out);
        assert_eq!(out.status.code(), Some(0), "{o:?}\n{text}");
        assert!(text.contains("done"), "{text}");
    }
}

#[test]
fn help_states_the_byte_order_and_the_port_rule() {
    for args in [["manipulator", "--help"], ["skills", "run --help"]] {
        let mut cmd = fitup();
        cmd.arg(args[0]);
        cmd.args(args[1].split(' '));
        let o = cmd.output().unwrap();
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains("--byte-order"), "{text}");
        assert!(text.contains("little"), "{text}");
        assert!(text.contains("motion port + 2"), "{text}");
    }
}
