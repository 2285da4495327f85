//! The one writer for everything the command line prints. A closed pipe
//! (`fitup check doc.yaml | head`) is not an error: the reader has what it wanted, so
//! the process stops quietly with exit code 0, as `head`'s upstream tools do — no panic
//! message (Rust's `println!` would panic on `EPIPE`), no half-line of noise.
//!
//! Stopping mid-run is safe for the user's files: every save is atomic (written to a
//! temporary file and renamed), so a run stopped between two operations leaves each
//! file either old or new.

use std::io::{self, Write};

/// Which stream a line goes to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stream {
    /// Results.
    Stdout,
    /// Errors and warnings.
    Stderr,
}

/// Writes `text` to `stream` and flushes. On a closed pipe the process exits with
/// status 0; any other write error is ignored (there is nowhere left to report it).
pub fn write(stream: Stream, text: &str) {
    let result = match stream {
        Stream::Stdout => {
            let mut out = io::stdout().lock();
            out.write_all(text.as_bytes()).and_then(|()| out.flush())
        }
        Stream::Stderr => {
            let mut err = io::stderr().lock();
            err.write_all(text.as_bytes()).and_then(|()| err.flush())
        }
    };
    if let Err(e) = result {
        if e.kind() == io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
    }
}

/// `text` and a newline to standard output. Control and invisible characters of
/// the text (a name's escape sequence, a bidi override; not newlines and tabs) are
/// written escaped ([`crate::diagnostics::printable`]) and database passwords removed
/// ([`crate::diagnostics::redact_credentials`]): every line fitup prints may hold user
/// strings.
pub fn line(text: &str) {
    let text = crate::diagnostics::redact_credentials(text);
    let text = crate::diagnostics::printable(&text, true);
    let mut s = String::with_capacity(text.len() + 1);
    s.push_str(&text);
    s.push('\n');
    write(Stream::Stdout, &s);
}

/// `text` and a newline to standard error, escaped as by [`line`].
pub fn error_line(text: &str) {
    let text = crate::diagnostics::redact_credentials(text);
    let text = crate::diagnostics::printable(&text, true);
    let mut s = String::with_capacity(text.len() + 1);
    s.push_str(&text);
    s.push('\n');
    write(Stream::Stderr, &s);
}

/// `println!` through [`line`].
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::cli::out::line(&::std::format!($($arg)*))
    };
}

/// `eprintln!` through [`error_line`].
macro_rules! errln {
    ($($arg:tt)*) => {
        $crate::cli::out::error_line(&::std::format!($($arg)*))
    };
}

pub(crate) use {errln, outln};
