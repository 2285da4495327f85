//! `--view`, `--open`, `--record` of `run`/`watch`, and `fitup view FILE.rrd`.

use super::out::errln;
#[cfg(feature = "viewer")]
use super::out::outln;
use super::{CliError, Exit, ViewArgs};
use crate::script::Project;
use std::path::Path;

/// A started viewer session, or nothing when no viewer flag was given.
#[cfg(feature = "viewer")]
pub(super) type Live = Option<crate::viewer::Session>;
/// Without the `viewer` feature there is never a session.
#[cfg(not(feature = "viewer"))]
pub(super) type Live = Option<std::convert::Infallible>;

/// Starts the session the flags ask for; `first_run` names a first recording (for
/// `run`; `watch` starts one per run). The `.rrd` file must lie inside the project
/// and may not be one of `sources` (the run's script, the open document's files and
/// program: [`crate::project::OutputRule::sources`]), not even with `force`.
#[cfg(feature = "viewer")]
pub(super) fn start(
    a: &ViewArgs,
    force: bool,
    sources: &[std::path::PathBuf],
    project: &Project,
    first_run: Option<String>,
) -> Result<Live, CliError> {
    use crate::viewer::{Session, SessionOptions};
    if !a.view && a.record.is_none() {
        return Ok(None);
    }
    let record = match &a.record {
        Some(r) => {
            let path_error = |source| CliError::Path {
                what: "--record",
                path: r.clone(),
                source,
            };
            let abs = std::path::absolute(r).map_err(path_error)?;
            let rule = crate::project::OutputRule::forced(force).protecting(sources);
            let path = project
                .resolve_output(&abs.to_string_lossy(), &rule)
                .map_err(|source| CliError::Refused {
                    what: "--record",
                    source,
                    root_hint: false,
                })?;
            // The recording is streamed while the run goes on: listed as fitup's own
            // by its magic, so the next run (or watch rerun) may replace it.
            crate::project::register_stream(&path, crate::project::RRD_MAGIC)
                .map_err(path_error)?;
            Some(path)
        }
        None => None,
    };
    let session = Session::start(SessionOptions {
        serve: a.view,
        record,
        first_run,
        report: Some(std::sync::Arc::new(|s: &str| errln!("{s}"))),
    })?;
    if let Some(url) = session.url() {
        announce(url, a.open);
    }
    Ok(Some(session))
}

#[cfg(not(feature = "viewer"))]
pub(super) fn start(
    a: &ViewArgs,
    _force: bool,
    _sources: &[std::path::PathBuf],
    _project: &Project,
    _first_run: Option<String>,
) -> Result<Live, CliError> {
    if a.view || a.record.is_some() {
        return Err(crate::viewer::not_built().into());
    }
    Ok(None)
}

/// The viewer handle of a session (off without one).
#[cfg(feature = "viewer")]
pub(super) fn handle(live: &Live) -> crate::viewer::Viewer {
    live.as_ref().map(|s| s.viewer()).unwrap_or_default()
}

#[cfg(not(feature = "viewer"))]
pub(super) fn handle(_live: &Live) -> crate::viewer::Viewer {
    crate::viewer::Viewer::default()
}

#[cfg(feature = "viewer")]
fn announce(url: &str, open: bool) {
    outln!("viewer: {url}");
    if open {
        if let Err(e) = crate::viewer::open_browser(url) {
            errln!("warning: cannot open a browser ({e}); open the address above yourself");
        }
    }
}

/// After `fitup run --view`: everything is sent; keep serving until Ctrl-C.
#[cfg(feature = "viewer")]
pub(super) fn finish(live: Live) {
    let Some(session) = live else { return };
    if !session.viewer().flush(std::time::Duration::from_secs(30)) {
        errln!("warning: the viewer did not take everything within 30 s");
    }
    if let Some(url) = session.url() {
        outln!("viewer: serving {url} until Ctrl-C");
        loop {
            std::thread::sleep(std::time::Duration::from_secs(3600));
        }
    }
}

#[cfg(not(feature = "viewer"))]
pub(super) fn finish(_live: Live) {}

/// `fitup view FILE.rrd [--open]`.
#[cfg(feature = "viewer")]
pub(super) fn view_file(file: &Path, open: bool) -> Exit {
    use crate::viewer::{Session, SessionOptions};
    // Read it first: a bad file is an error before anything is served.
    if let Err(e) = crate::viewer::read_recording(file) {
        errln!("error: {e}");
        return Exit::Failure;
    }
    let session = match Session::start(SessionOptions {
        serve: true,
        ..SessionOptions::default()
    }) {
        Ok(s) => s,
        Err(e) => {
            errln!("error: {e}");
            return Exit::Failure;
        }
    };
    match session.replay(file) {
        Ok(n) => outln!("{}: {n} messages", file.display()),
        Err(e) => {
            errln!("error: {e}");
            return Exit::Failure;
        }
    }
    if let Some(url) = session.url() {
        announce(url, open);
    }
    finish(Some(session));
    Exit::Ok
}

#[cfg(not(feature = "viewer"))]
pub(super) fn view_file(_file: &Path, _open: bool) -> Exit {
    errln!("error: {}", crate::viewer::not_built());
    Exit::Failure
}
