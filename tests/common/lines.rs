//! A child process's output read line by line on a thread, for tests that wait for a
//! line (`== done 2 ok`) or for a quiet spell. Shared by the watch, sequence-watch,
//! chain and viewer tests and the watch-latency benchmark.

#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read};
use std::process::Child;
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

/// Lines of one output stream, each with the instant it arrived, and the transcript
/// so far (for failure messages).
pub struct Lines {
    rx: Receiver<(Instant, String)>,
    /// Every line received so far, in order.
    pub seen: Vec<String>,
}

impl Lines {
    /// Starts reading `r` (a child's stdout or stderr) on a thread.
    pub fn read(r: impl Read + Send + 'static) -> Lines {
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(r).lines().map_while(Result::ok) {
                if tx.send((Instant::now(), line)).is_err() {
                    break;
                }
            }
        });
        Lines {
            rx,
            seen: Vec::new(),
        }
    }

    /// Waits until a line contains `needle` and returns it with its arrival time;
    /// panics with the transcript after `bound` (a bound on hangs, not a speed
    /// assertion) or when the stream ends first.
    pub fn wait_timed(&mut self, needle: &str, bound: Duration) -> (Instant, String) {
        let end = Instant::now() + bound;
        loop {
            let left = end.saturating_duration_since(Instant::now());
            match self.rx.recv_timeout(left) {
                Ok((t, l)) => {
                    self.seen.push(l.clone());
                    if l.contains(needle) {
                        return (t, l);
                    }
                }
                Err(RecvTimeoutError::Timeout) => panic!(
                    "no `{needle}` within {bound:?}; output:\n{}",
                    self.seen.join("\n")
                ),
                Err(RecvTimeoutError::Disconnected) => panic!(
                    "the output ended before `{needle}`; output:\n{}",
                    self.seen.join("\n")
                ),
            }
        }
    }

    /// Reads a child's stdout and stderr into one stream, stderr lines prefixed
    /// `stderr: ` (for tests that look for a line wherever the program prints it).
    pub fn read_merged(out: impl Read + Send + 'static, err: impl Read + Send + 'static) -> Lines {
        let (tx, rx) = channel();
        let tx2 = tx.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(out).lines().map_while(Result::ok) {
                if tx.send((Instant::now(), line)).is_err() {
                    break;
                }
            }
        });
        std::thread::spawn(move || {
            for line in BufReader::new(err).lines().map_while(Result::ok) {
                if tx2
                    .send((Instant::now(), format!("stderr: {line}")))
                    .is_err()
                {
                    break;
                }
            }
        });
        Lines {
            rx,
            seen: Vec::new(),
        }
    }

    /// Every line so far, without waiting, as one text.
    pub fn drain(&mut self) -> String {
        while let Ok((_, l)) = self.rx.try_recv() {
            self.seen.push(l);
        }
        self.seen.join("\n")
    }

    /// [`Lines::wait_timed`] without the time.
    pub fn wait_for(&mut self, needle: &str, bound: Duration) -> String {
        self.wait_timed(needle, bound).1
    }

    /// The lines that arrive within `d`.
    pub fn quiet(&mut self, d: Duration) -> Vec<String> {
        let end = Instant::now() + d;
        let mut got = Vec::new();
        while let Ok((_, l)) = self
            .rx
            .recv_timeout(end.saturating_duration_since(Instant::now()))
        {
            self.seen.push(l.clone());
            got.push(l);
        }
        got
    }

    /// The lines of watch run `n` seen so far (from `== run n` to before `== done n`).
    pub fn run(&self, n: usize) -> Vec<String> {
        let start = format!("== run {n}");
        let end = format!("== done {n}");
        self.seen
            .iter()
            .skip_while(|l| !l.starts_with(&start))
            .take_while(|l| !l.starts_with(&end))
            .cloned()
            .collect()
    }
}

/// A running program with its stdout and stderr in one [`Lines`] stream
/// ([`Lines::read_merged`]); killed when dropped.
pub struct Proc {
    /// The process.
    pub child: Killed,
    /// Its output, stdout and stderr merged.
    pub lines: Lines,
}

impl Proc {
    /// Starts `cmd` with stdout and stderr piped (stdin as the caller set it).
    pub fn spawn(cmd: &mut std::process::Command) -> Proc {
        use std::process::Stdio;
        let mut child = cmd
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let lines = Lines::read_merged(child.stdout.take().unwrap(), child.stderr.take().unwrap());
        Proc {
            child: Killed(child),
            lines,
        }
    }

    /// Waits (bounded: a hang fails the test) for a line containing `pat`.
    pub fn wait_for(&mut self, pat: &str, bound: Duration) -> String {
        self.lines.wait_for(pat, bound)
    }

    /// Every line so far (without waiting).
    pub fn drain(&mut self) -> String {
        self.lines.drain()
    }

    /// Every line received so far.
    pub fn seen(&self) -> &[String] {
        &self.lines.seen
    }

    /// Writes one line to the program's stdin (piped by the caller).
    pub fn send(&mut self, line: &str) {
        use std::io::Write;
        let stdin = self.child.0.stdin.as_mut().unwrap();
        writeln!(stdin, "{line}").unwrap();
        stdin.flush().unwrap();
    }
}

/// A child process killed and reaped when dropped, so a failed assertion leaves no
/// `fitup watch` or browser running.
pub struct Killed(pub Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}
