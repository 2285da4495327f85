//! The viewer in a real browser: `fitup watch --view` on a project, headless Chromium
//! driven over the DevTools protocol, the script saved twice. The page must show the
//! cell and switch to the newer run, and must request nothing outside this machine.
//!
//! Needs Debian's `chromium` (`.ci/run` installs it); without it the test is skipped
//! with a note, and fails under `CI=true`. Screenshots are left in
//! `out/viewer-tests/browser-*.png` to look at.
#![cfg(feature = "viewer")]

use crate::common;

use common::repo;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc::channel;
use std::time::{Duration, Instant};

/// The longest any single step may take (a connection, an answer, a frame).
const STEP: Duration = Duration::from_secs(30);
/// The whole test is killed after this: the watchdog ends chromium and fitup, so every
/// blocked read fails and the test panics instead of hanging.
const WHOLE_TEST: Duration = Duration::from_secs(600);

/// Kills the given processes when the test outlives [`WHOLE_TEST`]; dropping it (the
/// test ended either way) stops the watchdog.
struct Watchdog(Option<std::sync::mpsc::Sender<()>>);

impl Watchdog {
    fn start(pids: Vec<u32>) -> Watchdog {
        let (tx, rx) = channel::<()>();
        std::thread::spawn(move || {
            if rx.recv_timeout(WHOLE_TEST) == Err(std::sync::mpsc::RecvTimeoutError::Timeout) {
                eprintln!("browser test: over {WHOLE_TEST:?}, killing {pids:?}");
                for pid in pids {
                    let _ = Command::new("kill")
                        .args(["-KILL", &pid.to_string()])
                        .status();
                }
            }
        });
        Watchdog(Some(tx))
    }
}

impl Drop for Watchdog {
    fn drop(&mut self) {
        if let Some(tx) = self.0.take() {
            let _ = tx.send(());
        }
    }
}

fn chromium() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .flat_map(|name| std::env::split_paths(&path).map(move |d| d.join(name)))
        .find(|p| p.is_file())
}

// ---- a minimal WebSocket client (RFC 6455), enough for the DevTools protocol ----

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

fn b64_encode(data: &[u8]) -> String {
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for i in 0..4 {
            if i <= c.len() {
                s.push(B64[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

fn b64_decode(s: &str) -> Vec<u8> {
    let mut out = Vec::with_capacity(s.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0);
    for c in s.bytes() {
        let Some(v) = B64.iter().position(|&b| b == c) else {
            continue;
        };
        acc = acc << 6 | v as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    out
}

struct Ws {
    s: TcpStream,
}

impl Ws {
    fn connect(url: &str) -> Ws {
        let rest = url.strip_prefix("ws://").expect("ws url");
        let (host, path) = rest.split_at(rest.find('/').unwrap());
        let mut s = connect(host);
        write!(
            s,
            "GET {path} HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
             Sec-WebSocket-Key: {}\r\nSec-WebSocket-Version: 13\r\n\r\n",
            b64_encode(b"fitup-viewer-tst")
        )
        .unwrap();
        let mut head = Vec::new();
        let mut b = [0u8; 1];
        while !head.ends_with(b"\r\n\r\n") {
            s.read_exact(&mut b).unwrap();
            head.push(b[0]);
        }
        assert!(
            head.starts_with(b"HTTP/1.1 101"),
            "{}",
            String::from_utf8_lossy(&head)
        );
        Ws { s }
    }

    fn send(&mut self, text: &str) {
        let p = text.as_bytes();
        let mut f = vec![0x81u8];
        match p.len() {
            n if n < 126 => f.push(0x80 | n as u8),
            n if n < 65536 => {
                f.push(0x80 | 126);
                f.extend_from_slice(&(n as u16).to_be_bytes());
            }
            n => {
                f.push(0x80 | 127);
                f.extend_from_slice(&(n as u64).to_be_bytes());
            }
        }
        let mask = [1u8, 2, 3, 4];
        f.extend_from_slice(&mask);
        f.extend(p.iter().enumerate().map(|(i, b)| b ^ mask[i % 4]));
        self.s.write_all(&f).unwrap();
    }

    /// The next text message, or `None` when nothing arrives within `timeout`.
    fn recv(&mut self, timeout: Duration) -> Option<String> {
        let mut msg = Vec::new();
        loop {
            // Wait for the first byte with `timeout` without consuming it, so a timeout
            // never leaves half a frame header read.
            self.s
                .set_read_timeout(Some(timeout.max(Duration::from_millis(1))))
                .unwrap();
            if msg.is_empty() && !matches!(self.s.peek(&mut [0u8; 1]), Ok(n) if n > 0) {
                return None;
            }
            self.s.set_read_timeout(Some(STEP)).unwrap();
            let mut h = [0u8; 2];
            self.s.read_exact(&mut h).expect("DevTools frame header");
            let len = match h[1] & 0x7f {
                126 => {
                    let mut l = [0u8; 2];
                    self.s.read_exact(&mut l).unwrap();
                    u16::from_be_bytes(l) as usize
                }
                127 => {
                    let mut l = [0u8; 8];
                    self.s.read_exact(&mut l).unwrap();
                    u64::from_be_bytes(l) as usize
                }
                n => n as usize,
            };
            let mut p = vec![0u8; len];
            self.s.read_exact(&mut p).unwrap();
            msg.extend_from_slice(&p);
            if h[0] & 0x80 != 0 {
                return Some(String::from_utf8_lossy(&msg).into_owned());
            }
        }
    }
}

/// A DevTools session on one page: commands by id, every event kept.
struct Page {
    ws: Ws,
    next: u64,
    /// Every request the page made: (DevTools id, url).
    requests: Vec<(String, String)>,
    /// Ids of requests the browser blocked before sending (the CSP).
    blocked: std::collections::HashSet<String>,
}

impl Page {
    fn call(&mut self, method: &str, params: serde_json::Value) -> serde_json::Value {
        self.next += 1;
        let id = self.next;
        self.ws
            .send(&serde_json::json!({"id": id, "method": method, "params": params}).to_string());
        let end = Instant::now() + STEP * 4;
        while let Some(left) = end.checked_duration_since(Instant::now()) {
            let Some(m) = self.ws.recv(left) else {
                break;
            };
            let v: serde_json::Value = serde_json::from_str(&m).unwrap();
            if v["id"].as_u64() == Some(id) {
                assert!(v.get("error").is_none(), "{method}: {v}");
                return v["result"].clone();
            }
            self.event(&v);
        }
        panic!("no answer to {method}");
    }

    fn event(&mut self, v: &serde_json::Value) {
        match v["method"].as_str() {
            Some("Network.requestWillBeSent") | Some("Network.webSocketCreated") => {
                let p = &v["params"];
                let url = p["request"]["url"].as_str().or(p["url"].as_str());
                if let Some(u) = url {
                    let id = p["requestId"].as_str().unwrap_or("").to_string();
                    self.requests.push((id, u.to_string()));
                }
            }
            Some("Network.loadingFailed") => {
                let p = &v["params"];
                if p.get("blockedReason").is_some_and(|r| !r.is_null()) {
                    self.blocked
                        .insert(p["requestId"].as_str().unwrap_or("").to_string());
                }
            }
            _ => {}
        }
    }

    /// Reads events for `d`.
    fn idle(&mut self, d: Duration) {
        let end = Instant::now() + d;
        while let Some(left) = end.checked_duration_since(Instant::now()) {
            let Some(m) = self.ws.recv(left.min(Duration::from_millis(500))) else {
                continue;
            };
            if let Ok(v) = serde_json::from_str::<serde_json::Value>(&m) {
                self.event(&v);
            }
        }
    }

    fn screenshot(&mut self, file: &Path) -> Vec<u8> {
        let r = self.call(
            "Page.captureScreenshot",
            serde_json::json!({"format": "png"}),
        );
        let png = b64_decode(r["data"].as_str().unwrap());
        std::fs::write(file, &png).unwrap();
        png
    }
}

/// A TCP connection to `addr` (host:port) with every step bounded.
fn connect(addr: &str) -> TcpStream {
    let addr: std::net::SocketAddr = addr.parse().expect("host:port");
    let s = TcpStream::connect_timeout(&addr, STEP).expect("connect");
    s.set_read_timeout(Some(STEP)).unwrap();
    s.set_write_timeout(Some(STEP)).unwrap();
    s
}

/// The body of `GET path` from DevTools' HTTP endpoint. Chromium keeps the connection
/// open after the answer (whatever `Connection` says), so read exactly `Content-Length`.
fn http_get(port: u16, path: &str) -> String {
    let mut s = connect(&format!("127.0.0.1:{port}"));
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut r = BufReader::new(s);
    let mut len = 0usize;
    loop {
        let mut line = String::new();
        r.read_line(&mut line).expect("DevTools answer head");
        let l = line.trim_end();
        if l.is_empty() {
            break;
        }
        if let Some((k, v)) = l.split_once(':') {
            if k.eq_ignore_ascii_case("content-length") {
                len = v.trim().parse().expect("Content-Length");
            }
        }
    }
    let mut body = vec![0u8; len];
    r.read_exact(&mut body).expect("DevTools answer body");
    String::from_utf8_lossy(&body).into_owned()
}

fn is_local(url: &str) -> bool {
    ["data:", "blob:", "about:", "chrome:", "chrome-extension:"]
        .iter()
        .any(|p| url.starts_with(p))
        || [
            "http://127.0.0.1:",
            "ws://127.0.0.1:",
            "http://localhost:",
            "ws://localhost:",
        ]
        .iter()
        .any(|p| url.starts_with(p))
}

const SCRIPT: &str = "let doc = open_doc(\"models/cell.yaml\");\n\
                      let s = doc.component(\"screw4\");\n\
                      for i in 0..LIFT { s.translate(0, 0, 1); }\n";

/// Screenshots of a page still loading (the spinner, an empty viewer) are small; one
/// showing the cell with its panels is ~300 kB.
const DRAWN: usize = 150_000;

#[test]
fn the_browser_shows_the_newest_run_and_asks_nothing_of_the_internet() {
    let Some(browser) = chromium() else {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true but no chromium: .ci/run installs it"
        );
        eprintln!(
            "note: no chromium on the PATH; the browser test is skipped (.ci/run installs it)"
        );
        return;
    };
    let dir = common::project();
    let p = dir.path();
    let script = p.join("scripts/cell.rhai");
    std::fs::write(&script, SCRIPT.replace("LIFT", "20")).unwrap();
    let mut watch = common::Watch::start(p, "scripts/cell.rhai", &["--view"]);
    let bound = Duration::from_secs(120);
    let url = watch
        .out
        .wait_for("viewer: http://127.0.0.1:", bound)
        .trim_start_matches("viewer: ")
        .to_string();
    watch.out.wait_for("== done 1 ok", bound);

    let profile = tempfile::tempdir().unwrap();
    let chrome = common::lines::Killed(
        Command::new(browser)
            .args([
                "--headless=new",
                "--no-sandbox",
                "--no-first-run",
                "--window-size=1280,800",
                "--remote-debugging-port=0",
            ])
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .arg("about:blank")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let _watchdog = Watchdog::start(vec![watch.process.0.id(), chrome.0.id()]);
    // Chromium writes its DevTools port (then the browser's path) once it listens.
    let port_file = profile.path().join("DevToolsActivePort");
    let start = Instant::now();
    let port: u16 = loop {
        let text = std::fs::read_to_string(&port_file).unwrap_or_default();
        if text.lines().count() >= 2 {
            break text.lines().next().unwrap().parse().unwrap();
        }
        assert!(start.elapsed() < STEP * 2, "chromium did not start");
        std::thread::sleep(Duration::from_millis(200));
    };
    let targets: serde_json::Value = serde_json::from_str(&http_get(port, "/json/list")).unwrap();
    let ws_url = targets
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["type"] == "page")
        .and_then(|t| t["webSocketDebuggerUrl"].as_str())
        .expect("a page target")
        .to_string();
    let mut page = Page {
        ws: Ws::connect(&ws_url),
        next: 0,
        requests: Vec::new(),
        blocked: Default::default(),
    };
    page.call("Network.enable", serde_json::json!({}));
    page.call("Page.enable", serde_json::json!({}));
    // WebGL: forcing WebGPU crashes under software rendering.
    page.call(
        "Page.navigate",
        serde_json::json!({"url": format!("{url}&renderer=webgl")}),
    );
    let shots = repo().join("out/viewer-tests");
    std::fs::create_dir_all(&shots).unwrap();
    // The first complete frame takes ~20–40 s under software rendering: look every 5 s
    // for up to two minutes.
    let start = Instant::now();
    let first = loop {
        page.idle(Duration::from_secs(5));
        let png = page.screenshot(&shots.join("browser-1.png"));
        if png.len() > DRAWN || start.elapsed() > STEP * 4 {
            break png;
        }
    };
    // Give the viewer a moment to settle on the run (the camera, the panels).
    page.idle(Duration::from_secs(5));
    let first = {
        let again = page.screenshot(&shots.join("browser-1.png"));
        if again.len() > DRAWN {
            again
        } else {
            first
        }
    };

    // Two saves: runs 2 and 3; the open page follows to the newest without a reload.
    std::fs::write(&script, SCRIPT.replace("LIFT", "60")).unwrap();
    watch.out.wait_for("== done 2 ok", bound);
    page.idle(Duration::from_secs(2));
    std::fs::write(&script, SCRIPT.replace("LIFT", "120")).unwrap();
    watch.out.wait_for("== done 3 ok", bound);
    page.idle(Duration::from_secs(15));
    let second = page.screenshot(&shots.join("browser-2.png"));

    // The cell was drawn (a loading page compresses to far less) and the newer run
    // changed the picture (screw4 lifted 120 mm instead of 20, run 3 selected).
    assert!(
        first.len() > DRAWN && second.len() > DRAWN,
        "screenshots {} / {} bytes: nothing drawn? (out/viewer-tests/browser-*.png)",
        first.len(),
        second.len()
    );
    assert_ne!(first, second, "the newer run shows");
    // The page loaded the viewer from fitup and the data from fitup's gRPC proxy.
    assert!(
        page.requests
            .iter()
            .any(|(_, u)| u.contains("re_viewer_bg.wasm")),
        "{:?}",
        page.requests
    );
    assert!(
        page.requests
            .iter()
            .any(|(_, u)| u.contains("MessageProxyService")),
        "{:?}",
        page.requests
    );
    // What the bundled page tries (web fonts, analytics) is blocked by fitup's policy
    // before it leaves the browser; nothing else goes out.
    let outside: Vec<&String> = page
        .requests
        .iter()
        .filter(|(id, u)| !is_local(u) && !page.blocked.contains(id))
        .map(|(_, u)| u)
        .collect();
    assert!(
        outside.is_empty(),
        "requests outside localhost: {outside:?}"
    );
}
