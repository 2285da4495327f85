//! The origin gate in front of the viewer's gRPC port: a browser page may read the
//! scene only when it is the web viewer fitup itself serves.
//!
//! Rerun's gRPC server answers CORS requests from `localhost:*`, `127.0.0.1:*` and
//! `rerun.io` with an allow-origin header, and that list cannot be narrowed through
//! its options; so the port fitup publishes (in the page's `?url=` and its CSP) is this
//! gate, and Rerun listens on another loopback port behind it. The gate reads each
//! connection's HTTP/1.1 request head (a browser speaks HTTP/1.1 to a plain `http://`
//! port, gRPC-web included) and refuses with `403` and no CORS header any request whose
//! `Origin` is not the page's own ([`allowed_origin`]); allowed requests are
//! forwarded with `Connection: close`, so every request of a browser arrives on a new
//! connection and is checked. A connection that opens with the HTTP/2 preface is a
//! native gRPC client (browsers cannot speak cleartext HTTP/2) and is passed through.
//!
//! Plain `std` networking, compiled with or without the `viewer` feature, so it is
//! tested without Rerun.

use crate::math::Deadline;
use std::io::{self, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// Whether a request with `Origin: origin` may use the gRPC port: only the web
/// viewer page fitup serves on `page_port`, as `http://127.0.0.1:PORT` or
/// `http://localhost:PORT` (the same page under either host name). Every other
/// origin — another port on this machine, `https://rerun.io`, `null` — is refused.
pub fn allowed_origin(origin: &str, page_port: u16) -> bool {
    let origin = origin.trim();
    [
        format!("http://127.0.0.1:{page_port}"),
        format!("http://localhost:{page_port}"),
    ]
    .iter()
    .any(|own| origin.eq_ignore_ascii_case(own))
}

/// The HTTP/2 connection preface (`PRI * HTTP/2.0…`): a native gRPC client.
const H2_PREFACE: &[u8] = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n";

/// The largest request head read before refusing (browsers send a few KB).
const MAX_HEAD: usize = 32 * 1024;

/// How long a client may take to send its request head.
const HEAD_TIMEOUT: Duration = Duration::from_secs(10);

/// How long the gate waits for the upstream server to accept (it starts on another
/// thread at the same time as the gate).
const UPSTREAM_WAIT: Duration = Duration::from_secs(5);

/// Connections served at once; more wait in the listen queue.
const MAX_CONNECTIONS: usize = 64;

/// A running gate; dropping it stops accepting connections.
pub struct OriginGate {
    port: u16,
    stop: Arc<AtomicBool>,
}

impl OriginGate {
    /// Serves `listener` (a loopback socket: its port is the one published to the
    /// page), forwarding allowed requests to `upstream`; `page_port` is the port of
    /// the page whose origin is allowed.
    ///
    /// # Errors
    /// The listener's address cannot be read or the thread cannot start.
    pub fn start(
        listener: TcpListener,
        upstream: SocketAddr,
        page_port: u16,
    ) -> io::Result<OriginGate> {
        let port = listener.local_addr()?.port();
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let active = Arc::new(AtomicUsize::new(0));
        std::thread::Builder::new()
            .name("fitup-viewer-gate".into())
            .spawn(move || {
                for conn in listener.incoming() {
                    if flag.load(Ordering::Relaxed) {
                        break;
                    }
                    let Ok(conn) = conn else { continue };
                    if active.load(Ordering::Relaxed) >= MAX_CONNECTIONS {
                        let _ = refuse(conn, "503 Service Unavailable", "too many connections");
                        continue;
                    }
                    active.fetch_add(1, Ordering::Relaxed);
                    let counter = active.clone();
                    let spawned = std::thread::Builder::new()
                        .name("fitup-viewer-gate-conn".into())
                        .spawn(move || {
                            let _ = serve(conn, upstream, page_port);
                            counter.fetch_sub(1, Ordering::Relaxed);
                        });
                    if spawned.is_err() {
                        // the closure (and its connection) is dropped unserved
                        active.fetch_sub(1, Ordering::Relaxed);
                    }
                }
            })?;
        Ok(OriginGate { port, stop })
    }

    /// The gate's port (127.0.0.1).
    pub fn port(&self) -> u16 {
        self.port
    }
}

impl Drop for OriginGate {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        // wake the accept loop so it sees the flag
        let _ = TcpStream::connect(("127.0.0.1", self.port));
    }
}

/// A short refusal with no CORS header: the browser gives the page nothing.
fn refuse(mut conn: TcpStream, status: &str, why: &str) -> io::Result<()> {
    let _ = conn.set_write_timeout(Some(HEAD_TIMEOUT));
    write!(
        conn,
        "HTTP/1.1 {status}\r\nContent-Type: text/plain\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{why}",
        why.len()
    )?;
    conn.flush()?;
    let _ = conn.shutdown(Shutdown::Both);
    Ok(())
}

/// One connection: read the head, check the origin, forward or refuse.
fn serve(mut client: TcpStream, upstream: SocketAddr, page_port: u16) -> io::Result<()> {
    client.set_read_timeout(Some(HEAD_TIMEOUT))?;
    let mut buf = Vec::with_capacity(4096);
    let mut chunk = [0u8; 4096];
    let head_end = loop {
        if buf.len() >= 3 && H2_PREFACE.starts_with(&buf[..buf.len().min(H2_PREFACE.len())]) {
            if buf.len() >= H2_PREFACE.len() {
                break None; // HTTP/2: a native client, passed through
            }
        } else if let Some(i) = find(&buf, b"\r\n\r\n") {
            break Some(i + 4);
        }
        if buf.len() > MAX_HEAD {
            return refuse(
                client,
                "431 Request Header Fields Too Large",
                "request head too large",
            );
        }
        let n = client.read(&mut chunk)?;
        if n == 0 {
            return Ok(());
        }
        buf.extend_from_slice(&chunk[..n]);
    };
    let first = match head_end {
        None => buf,
        Some(end) => {
            let head = String::from_utf8_lossy(&buf[..end]).into_owned();
            let origin = head
                .split("\r\n")
                .skip(1)
                .filter_map(|l| l.split_once(':'))
                .find(|(k, _)| k.trim().eq_ignore_ascii_case("origin"))
                .map(|(_, v)| v.trim().to_string());
            if let Some(o) = &origin {
                if !allowed_origin(o, page_port) {
                    return refuse(
                        client,
                        "403 Forbidden",
                        "origin not allowed: only the fitup viewer page may read this port",
                    );
                }
            }
            let mut out = rewrite_head(&head).into_bytes();
            out.extend_from_slice(&buf[end..]);
            out
        }
    };
    client.set_read_timeout(None)?;
    let mut up = connect(upstream)?;
    up.write_all(&first)?;
    let (mut from_client, mut to_up) = (client.try_clone()?, up.try_clone()?);
    let upward = std::thread::Builder::new()
        .name("fitup-viewer-gate-up".into())
        .spawn(move || {
            let _ = io::copy(&mut from_client, &mut to_up);
            let _ = to_up.shutdown(Shutdown::Write);
        })?;
    let _ = io::copy(&mut up, &mut client);
    // the response is complete (the upstream closes after it): end both ways
    let _ = client.shutdown(Shutdown::Both);
    let _ = up.shutdown(Shutdown::Both);
    let _ = upward.join();
    Ok(())
}

/// The head with `Connection: close` instead of any `Connection`/`Keep-Alive`
/// header, so the next request of the client comes on a new, checked connection.
fn rewrite_head(head: &str) -> String {
    let mut lines: Vec<&str> = head.trim_end_matches("\r\n").split("\r\n").collect();
    lines.retain(|l| {
        let key = l.split(':').next().unwrap_or("").trim();
        !(key.eq_ignore_ascii_case("connection") || key.eq_ignore_ascii_case("keep-alive"))
    });
    let mut out = lines.join("\r\n");
    out.push_str("\r\nConnection: close\r\n\r\n");
    out
}

/// Connects to the upstream server, waiting for it to start listening.
fn connect(upstream: SocketAddr) -> io::Result<TcpStream> {
    let deadline = Deadline::after(UPSTREAM_WAIT);
    loop {
        match TcpStream::connect_timeout(&upstream, Duration::from_secs(1)) {
            Ok(s) => return Ok(s),
            Err(e) if deadline.passed() => return Err(e),
            Err(_) => std::thread::sleep(Duration::from_millis(50)),
        }
    }
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[test]
    fn only_the_served_page_is_an_allowed_origin() {
        assert!(allowed_origin("http://127.0.0.1:9876", 9876));
        assert!(allowed_origin("http://localhost:9876", 9876));
        assert!(allowed_origin("HTTP://LOCALHOST:9876", 9876));
        for bad in [
            "https://rerun.io",
            "https://rerun.io:443",
            "http://127.0.0.1:9877",
            "http://127.0.0.1",
            "http://localhost",
            "https://127.0.0.1:9876",
            "http://127.0.0.1:9876.evil.example",
            "http://evil.example",
            "null",
            "",
        ] {
            assert!(!allowed_origin(bad, 9876), "{bad}");
        }
    }

    /// A fake upstream that answers every request with a permissive CORS header
    /// (as Rerun's does for rerun.io) and records what it received.
    fn upstream() -> (SocketAddr, Arc<Mutex<Vec<String>>>) {
        let l = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = l.local_addr().unwrap();
        let seen = Arc::new(Mutex::new(Vec::new()));
        let log = seen.clone();
        std::thread::spawn(move || {
            for c in l.incoming() {
                let Ok(mut c) = c else { continue };
                let mut buf = vec![0u8; 65536];
                let mut got = Vec::new();
                while find(&got, b"\r\n\r\n").is_none() && find(&got, H2_PREFACE).is_none() {
                    let n = c.read(&mut buf).unwrap_or(0);
                    if n == 0 {
                        break;
                    }
                    got.extend_from_slice(&buf[..n]);
                }
                log.lock()
                    .unwrap()
                    .push(String::from_utf8_lossy(&got).into_owned());
                let _ = c.write_all(
                    b"HTTP/1.1 200 OK\r\nAccess-Control-Allow-Origin: https://rerun.io\r\nContent-Length: 2\r\n\r\nok",
                );
                let _ = c.shutdown(Shutdown::Both);
            }
        });
        (addr, seen)
    }

    fn ask(port: u16, request: &[u8]) -> String {
        let mut c = TcpStream::connect(("127.0.0.1", port)).unwrap();
        c.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        let _ = c.write_all(request);
        let mut out = Vec::new();
        let _ = c.read_to_end(&mut out);
        String::from_utf8_lossy(&out).into_owned()
    }

    #[test]
    fn the_gate_refuses_other_origins_and_forwards_the_page() {
        let (up, seen) = upstream();
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let page = 45_678;
        let gate = OriginGate::start(listener, up, page).unwrap();
        let req = |origin: Option<&str>, method: &str| {
            let o = origin.map_or(String::new(), |o| format!("Origin: {o}\r\n"));
            format!(
                "{method} /rerun.sdk_comms.v1alpha1.MessageProxyService/ReadMessages HTTP/1.1\r\nHost: 127.0.0.1:{}\r\n{o}Connection: keep-alive\r\nContent-Type: application/grpc-web+proto\r\nContent-Length: 0\r\n\r\n",
                gate.port()
            )
        };
        for bad in ["https://rerun.io", "http://127.0.0.1:1", "null"] {
            for method in ["OPTIONS", "POST"] {
                let r = ask(gate.port(), req(Some(bad), method).as_bytes());
                assert!(r.starts_with("HTTP/1.1 403"), "{bad} {method}: {r}");
                assert!(
                    !r.to_ascii_lowercase()
                        .contains("access-control-allow-origin"),
                    "{r}"
                );
            }
        }
        assert!(
            seen.lock().unwrap().is_empty(),
            "refused requests reached upstream"
        );
        let own = format!("http://127.0.0.1:{page}");
        let r = ask(gate.port(), req(Some(&own), "POST").as_bytes());
        assert!(r.starts_with("HTTP/1.1 200") && r.ends_with("ok"), "{r}");
        let r = ask(gate.port(), req(None, "POST").as_bytes());
        assert!(r.starts_with("HTTP/1.1 200"), "{r}");
        {
            let seen = seen.lock().unwrap();
            assert_eq!(seen.len(), 2, "{seen:?}");
            for head in seen.iter() {
                assert!(head.contains("\r\nConnection: close\r\n"), "{head}");
                assert!(!head.contains("keep-alive"), "{head}");
            }
        }
        // a native HTTP/2 client is passed through unchanged
        let mut h2 = H2_PREFACE.to_vec();
        h2.extend_from_slice(b"\x00\x00\x00\x04\x00\x00\x00\x00\x00");
        let r = ask(gate.port(), &h2);
        assert!(r.starts_with("HTTP/1.1 200"), "{r}");
        assert!(seen.lock().unwrap()[2].starts_with("PRI * HTTP/2.0"));
        // a head that never ends is refused, bounded
        // (exactly one byte over, so every byte is read before the refusal)
        let mut huge = b"GET / HTTP/1.1\r\nX: ".to_vec();
        huge.resize(MAX_HEAD + 1, b'a');
        let r = ask(gate.port(), &huge);
        assert!(r.starts_with("HTTP/1.1 431"), "{r}");
    }
}
