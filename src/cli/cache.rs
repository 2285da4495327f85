//! `fitup cache prune [--dry-run] [--max-mb MB] [DIR]`: removes what is stale from a
//! project's STEP tessellation store (library:
//! [`crate::document::tessellations::prune_project_store`]).

use super::out::{errln, outln};
use super::Exit;
use std::path::PathBuf;

/// Options of `cache`.
#[derive(Debug, clap::Args, Clone)]
pub struct CacheArgs {
    /// What to do with the cache.
    #[command(subcommand)]
    pub command: CacheCommand,
}

/// The `cache` subcommands.
#[derive(Debug, clap::Subcommand, Clone)]
#[non_exhaustive]
pub enum CacheCommand {
    /// Remove stale STEP tessellations from `.fitup-cache/step`: entries whose STEP file
    /// is gone or changed, whose tessellation no document asks for, left by an older
    /// fitup, then the least recently used above `--max-mb`.
    Prune {
        /// A folder of the project [default: the current folder]; its project is the
        /// nearest folder upwards holding `fitup.toml`, else the folder itself.
        dir: Option<PathBuf>,
        /// Only list what would be removed.
        #[arg(long)]
        dry_run: bool,
        /// Bring the store down to this size, MiB (least recently used first).
        #[arg(long, default_value_t = crate::mesh::step::DEFAULT_STORE_CAP >> 20)]
        max_mb: u64,
    },
}

pub(super) fn cache(a: &CacheArgs) -> Exit {
    match &a.command {
        CacheCommand::Prune {
            dir,
            dry_run,
            max_mb,
        } => prune(dir.as_deref(), *dry_run, *max_mb),
    }
}

fn prune(dir: Option<&std::path::Path>, dry_run: bool, max_mb: u64) -> Exit {
    let dir = dir.unwrap_or(std::path::Path::new("."));
    // For the message only: the project is searched (and then used) through folders
    // held from `/` down, never by name.
    match std::fs::metadata(dir) {
        Ok(m) if !m.is_dir() => {
            errln!("error: {}: not a folder", dir.display());
            return Exit::Failure;
        }
        Err(e) => {
            errln!("error: {}: {e}", dir.display());
            return Exit::Failure;
        }
        Ok(_) => {}
    }
    let project = match crate::project::Project::for_folder(dir) {
        Ok(p) => p,
        Err(e) => {
            errln!("error: {}: {e}", dir.display());
            return Exit::Failure;
        }
    };
    let root = project.root().to_path_buf();
    let max_bytes = max_mb.saturating_mul(1 << 20);
    let (report, used) =
        match crate::document::tessellations::prune_project_store(&project, dry_run, max_bytes) {
            Ok(r) => r,
            Err(e) => {
                errln!("error: {e}");
                return Exit::Failure;
            }
        };
    for (doc, why) in &used.unreadable {
        errln!(
            "warning: {}: not readable as a document, so the tessellations it asks for are not known: keeping every tessellation of a current STEP file ({})",
            doc.display(),
            crate::diagnostics::printable(why, false)
        );
    }
    let verb = if dry_run { "would remove" } else { "removed" };
    let show = |p: &std::path::Path| {
        crate::diagnostics::printable(
            &p.strip_prefix(&root).unwrap_or(p).display().to_string(),
            false,
        )
        .into_owned()
    };
    for p in &report.removed {
        outln!(
            "{verb} {} ({} KB): {}{}",
            show(&p.file),
            p.bytes.div_ceil(1000),
            p.reason,
            p.source
                .as_deref()
                .map_or(String::new(), |s| format!(" — {}", show(s)))
        );
    }
    for (file, kind) in &report.failed {
        errln!("error: cannot remove {}: {kind}", show(file));
    }
    let freed: u64 = report.removed.iter().map(|p| p.bytes).sum();
    outln!(
        "{}: {verb} {} files ({:.1} MB); kept {} tessellations ({:.1} MB) for {} documents",
        show(&root.join(crate::mesh::step::STEP_STORE)),
        report.removed.len(),
        freed as f64 / 1e6,
        report.kept,
        report.kept_bytes as f64 / 1e6,
        used.documents
    );
    if report.failed.is_empty() {
        Exit::Ok
    } else {
        Exit::Failure
    }
}
