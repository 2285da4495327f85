//! A viewer session: the worker thread, the local servers the browser talks to (the
//! web viewer's files over HTTP, the data over Rerun's gRPC proxy), and the `.rrd`
//! file of `--record`.
//!
//! The web viewer is served by fitup itself (not by Rerun's file server) so that every
//! response carries a Content-Security-Policy that allows only this machine: the page
//! bundled with Rerun would otherwise load analytics and web fonts and fetch an examples
//! manifest from the internet. Both servers listen on 127.0.0.1 only.

use super::backend::{self, SinkFactory};
use super::{Viewer, ViewerError};
use rerun::sink::{LogSink, SinkFlushError};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// What a session does.
#[derive(Clone, Default)]
pub struct SessionOptions {
    /// Serve the web viewer on localhost (`--view`).
    pub serve: bool,
    /// Save every recording to this `.rrd` file (`--record`; in watch mode the file holds
    /// the latest run).
    pub record: Option<PathBuf>,
    /// Name of a first recording started at once (`None`: the first [`Viewer::new_run`]).
    pub first_run: Option<String>,
    /// Where the session reports problems (a recording that cannot be written…).
    pub report: Option<Report>,
}

/// Where a session reports its problems (one line of text each).
pub type Report = Arc<dyn Fn(&str) + Send + Sync>;

/// A running viewer session. Dropping it stops the servers after a final flush.
pub struct Session {
    viewer: Viewer,
    url: Option<String>,
    grpc: Option<Arc<rerun::grpc_server::GrpcServerSink>>,
    web: Option<WebServer>,
    /// The published gRPC port: only the served page's origin gets through.
    _gate: Option<super::origin::OriginGate>,
}

/// Flush timeout when a session ends: enough for a big scene over loopback.
const FINAL_FLUSH: Duration = Duration::from_secs(10);

impl Session {
    /// Starts the worker and, with `serve`, the two local servers.
    ///
    /// # Errors
    /// A server that cannot listen; a `record` folder that cannot be created.
    pub fn start(opts: SessionOptions) -> Result<Session, ViewerError> {
        let (grpc, web, url, gate) = if opts.serve {
            // Rerun's server allows CORS from rerun.io and any localhost port, which
            // its options cannot narrow: it listens on an unpublished port behind
            // the origin gate, whose port is the one the page and its CSP name.
            let server = |e: std::io::Error| ViewerError::Server(e.to_string());
            let gate_listener = TcpListener::bind("127.0.0.1:0").map_err(server)?;
            let grpc_port = gate_listener.local_addr().map_err(server)?.port();
            let rerun_port = free_port()?;
            let grpc = rerun::grpc_server::GrpcServerSink::new(
                "127.0.0.1",
                rerun_port,
                rerun::ServerOptions::default(),
            )
            .map_err(|e| ViewerError::Server(e.to_string()))?;
            let web = WebServer::start(grpc_port)?;
            let gate = super::origin::OriginGate::start(
                gate_listener,
                std::net::SocketAddr::from(([127, 0, 0, 1], rerun_port)),
                web.port,
            )
            .map_err(server)?;
            let url = format!(
                "http://127.0.0.1:{}/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{grpc_port}%2Fproxy",
                web.port
            );
            (Some(Arc::new(grpc)), Some(web), Some(url), Some(gate))
        } else {
            (None, None, None, None)
        };
        if let Some(file) = &opts.record {
            let dir = file
                .parent()
                .filter(|p| !p.as_os_str().is_empty())
                .unwrap_or(Path::new("."));
            std::fs::create_dir_all(dir).map_err(|e| ViewerError::Recording {
                path: file.clone(),
                reason: format!("cannot create the folder {}: {e}", dir.display()),
            })?;
        }
        let shared = grpc.clone();
        let record = opts.record.clone();
        let sinks: SinkFactory = Box::new(move || {
            let mut out: Vec<Box<dyn LogSink>> = Vec::new();
            if let Some(g) = &shared {
                out.push(Box::new(SharedSink(g.clone())));
            }
            if let Some(file) = &record {
                let sink = rerun::sink::FileSink::new(file.clone())
                    .map_err(|e| format!("cannot write {}: {e}", file.display()))?;
                out.push(Box::new(sink));
            }
            Ok(out)
        });
        let report: Box<dyn Fn(&str) + Send> = match opts.report.clone() {
            Some(r) => Box::new(move |s: &str| r(s)),
            None => Box::new(|s: &str| eprintln!("{s}")),
        };
        let (tx, rx) = std::sync::mpsc::channel();
        let first = opts.first_run.clone();
        std::thread::Builder::new()
            .name("fitup-viewer".into())
            .spawn(move || backend::run(rx, sinks, first, report))
            .map_err(|e| ViewerError::Server(format!("cannot start the viewer thread: {e}")))?;
        Ok(Session {
            viewer: Viewer::from_sender(tx),
            url,
            grpc,
            web,
            _gate: gate,
        })
    }

    /// The handle to log through (clones share this session).
    pub fn viewer(&self) -> Viewer {
        self.viewer.clone()
    }

    /// The address to open in a browser, when serving.
    pub fn url(&self) -> Option<&str> {
        self.url.as_deref()
    }

    /// Sends every message of a saved recording to the open viewers (`fitup view`).
    /// Returns the number of messages.
    ///
    /// # Errors
    /// A file that cannot be opened or is not a Rerun recording; a session not serving.
    pub fn replay(&self, file: &Path) -> Result<usize, ViewerError> {
        let grpc = self
            .grpc
            .as_ref()
            .ok_or_else(|| ViewerError::Server("replay needs a serving session".into()))?;
        let n = super::read::for_each_message(file, |msg| grpc.send(msg))?;
        let _ = grpc.flush_blocking(FINAL_FLUSH);
        Ok(n)
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        self.viewer.flush(FINAL_FLUSH);
        if let Some(web) = self.web.take() {
            web.stop();
        }
    }
}

/// Opens `url` in the user's browser (`--open`).
pub fn open_browser(url: &str) -> std::io::Result<()> {
    let opener = if cfg!(target_os = "macos") {
        "open"
    } else if cfg!(windows) {
        "explorer"
    } else {
        "xdg-open"
    };
    std::process::Command::new(opener)
        .arg(url)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .map(|_| ())
}

/// One gRPC server shared by the session's recordings (each recording owns its sinks).
struct SharedSink(Arc<rerun::grpc_server::GrpcServerSink>);

impl LogSink for SharedSink {
    fn send(&self, msg: rerun::log::LogMsg) {
        self.0.send(msg)
    }

    fn flush_blocking(&self, timeout: Duration) -> Result<(), SinkFlushError> {
        self.0.flush_blocking(timeout)
    }

    fn default_batcher_config(&self) -> rerun::log::ChunkBatcherConfig {
        rerun::log::ChunkBatcherConfig::LOW_LATENCY
    }
}

fn free_port() -> Result<u16, ViewerError> {
    let l = TcpListener::bind("127.0.0.1:0").map_err(|e| ViewerError::Server(e.to_string()))?;
    l.local_addr()
        .map(|a| a.port())
        .map_err(|e| ViewerError::Server(e.to_string()))
}

/// The Content-Security-Policy of every page: this machine only. `connect-src` names
/// the gRPC port; wasm needs `wasm-unsafe-eval`; the page's own inline script and
/// styles need `unsafe-inline`.
pub fn content_security_policy(grpc_port: u16) -> String {
    format!(
        "default-src 'self'; script-src 'self' 'unsafe-inline' 'wasm-unsafe-eval'; \
         style-src 'self' 'unsafe-inline'; img-src 'self' data: blob:; font-src 'self' data:; \
         worker-src 'self' blob:; connect-src 'self' http://127.0.0.1:{grpc_port} http://localhost:{grpc_port}; \
         frame-src 'none'; object-src 'none'; form-action 'none'"
    )
}

/// A minimal HTTP server for the web viewer's files, with the CSP on every response.
struct WebServer {
    port: u16,
    stop: Arc<AtomicBool>,
}

impl WebServer {
    fn start(grpc_port: u16) -> Result<WebServer, ViewerError> {
        let data = re_web_viewer_server::WebViewerData::load(None)
            .map_err(|e| ViewerError::Server(format!("the web viewer's files: {e}")))?;
        let data = Arc::new(data);
        let listener =
            TcpListener::bind("127.0.0.1:0").map_err(|e| ViewerError::Server(e.to_string()))?;
        let port = listener
            .local_addr()
            .map_err(|e| ViewerError::Server(e.to_string()))?
            .port();
        let stop = Arc::new(AtomicBool::new(false));
        let csp: Arc<str> = content_security_policy(grpc_port).into();
        let flag = stop.clone();
        std::thread::Builder::new()
            .name("fitup-viewer-http".into())
            .spawn(move || {
                for conn in listener.incoming() {
                    if flag.load(Ordering::Relaxed) {
                        break;
                    }
                    let Ok(conn) = conn else { continue };
                    let (data, csp) = (data.clone(), csp.clone());
                    let _ = std::thread::Builder::new()
                        .name("fitup-viewer-http-conn".into())
                        .spawn(move || {
                            let _ = serve_one(conn, &data, &csp);
                        });
                }
            })
            .map_err(|e| ViewerError::Server(e.to_string()))?;
        Ok(WebServer { port, stop })
    }

    fn stop(self) {
        self.stop.store(true, Ordering::Relaxed);
        // Wake the accept loop.
        let _ = TcpStream::connect(("127.0.0.1", self.port));
    }
}

/// Longest request head read (the browser's GETs are far smaller).
const MAX_HEAD: u64 = 16 * 1024;

fn serve_one(
    mut conn: TcpStream,
    data: &re_web_viewer_server::WebViewerData,
    csp: &str,
) -> std::io::Result<()> {
    conn.set_read_timeout(Some(Duration::from_secs(10)))?;
    let mut reader = BufReader::new(conn.try_clone()?.take(MAX_HEAD));
    let mut request = String::new();
    reader.read_line(&mut request)?;
    // Skip the headers.
    loop {
        let mut line = String::new();
        if reader.read_line(&mut line)? == 0 || line == "\r\n" || line == "\n" {
            break;
        }
    }
    let mut words = request.split_whitespace();
    let method = words.next().unwrap_or("");
    let target = words.next().unwrap_or("/");
    let path = target.split('?').next().unwrap_or("/");
    let found: Option<(&str, &[u8])> = match path {
        "/" | "/index.html" => Some(("text/html; charset=utf-8", data.index_html())),
        "/favicon.ico" => Some(("image/x-icon", data.favicon())),
        "/apple-touch-icon.png" => Some(("image/png", data.apple_touch_icon())),
        "/sw.js" => Some(("text/javascript", data.sw_js())),
        "/re_viewer.js" => Some(("text/javascript", data.viewer_js())),
        "/re_viewer_bg.wasm" => Some(("application/wasm", data.viewer_wasm())),
        _ => None,
    };
    let (status, mime, body): (&str, &str, &[u8]) = match (method, found) {
        ("GET" | "HEAD", Some((m, b))) => ("200 OK", m, b),
        ("GET" | "HEAD", None) => ("404 Not Found", "text/plain", b"not found"),
        _ => ("405 Method Not Allowed", "text/plain", b"only GET"),
    };
    let head = format!(
        "HTTP/1.1 {status}\r\nContent-Type: {mime}\r\nContent-Length: {len}\r\n\
         rerun-final-length: {len}\r\nContent-Security-Policy: {csp}\r\n\
         Cache-Control: no-cache\r\nConnection: close\r\n\r\n",
        len = body.len()
    );
    conn.write_all(head.as_bytes())?;
    if method != "HEAD" {
        conn.write_all(body)?;
    }
    conn.flush()
}
