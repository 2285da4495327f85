//! `fitup import FILE.step [--out DIR] [--deflection MM] [--memory-limit-mb MB] [--force]`: a STEP assembly as
//! a new document (library: [`crate::document::import`]).

use super::out::{errln, outln};
use super::Exit;
use crate::document::import::{import_step, ImportOptions};
use crate::mesh::step::{
    ChildReader, Isolation, StepOptions, DEFAULT_ANGULAR_DEFLECTION, DEFAULT_LINEAR_DEFLECTION,
};
use std::path::PathBuf;

/// Options of `import`.
#[derive(Debug, clap::Args, Clone)]
pub struct ImportArgs {
    /// The STEP file (`.step`, `.stp`; AP203/AP214/AP242, any length unit).
    pub file: PathBuf,
    /// The project folder to write the document (`<stem>.yaml`) and `meshes/` into:
    /// created with a `fitup.toml` when missing or empty [default: `<stem>` beside the
    /// current folder].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Linear deflection of the tessellation, mm (smaller is finer).
    #[arg(long, default_value_t = DEFAULT_LINEAR_DEFLECTION)]
    pub deflection: f64,
    /// Angular deflection of the tessellation, degrees.
    #[arg(long, default_value_t = DEFAULT_ANGULAR_DEFLECTION.to_degrees())]
    pub angle: f64,
    /// Time limit of reading and meshing, seconds.
    #[arg(long, default_value_t = 300.0)]
    pub time_limit_s: f64,
    /// Memory cap of the Open CASCADE reader (a child process), MiB.
    #[arg(long, default_value_t = crate::mesh::step::DEFAULT_MEMORY_LIMIT >> 20)]
    pub memory_limit_mb: u64,
    /// Replace existing files at the output paths (never a folder, FIFO or link).
    #[arg(long)]
    pub force: bool,
}

pub(super) fn import(a: &ImportArgs) -> Exit {
    if !(a.time_limit_s.is_finite() && a.time_limit_s > 0.0 && a.time_limit_s <= 86_400.0) {
        errln!("error: --time-limit-s must be a number of seconds in (0, 86400]");
        return Exit::Usage;
    }
    if a.memory_limit_mb < 64 || a.memory_limit_mb > 1 << 20 {
        errln!("error: --memory-limit-mb must be between 64 and 1048576");
        return Exit::Usage;
    }
    let out = a.out.clone().unwrap_or_else(|| {
        PathBuf::from(
            a.file
                .file_stem()
                .map(|s| s.to_os_string())
                .unwrap_or_else(|| "imported".into()),
        )
    });
    let options = ImportOptions {
        step: StepOptions {
            linear_deflection: a.deflection,
            angular_deflection: a.angle.to_radians(),
            time_limit: std::time::Duration::from_secs_f64(a.time_limit_s),
            isolation: match Isolation::process_default() {
                Isolation::Child(c) => Isolation::Child(ChildReader {
                    memory_limit: a.memory_limit_mb << 20,
                    ..c
                }),
                other => other,
            },
            ..StepOptions::default()
        },
        force: a.force,
    };
    let report = match import_step(&a.file, &out, &options) {
        Ok(r) => r,
        Err(e) => {
            errln!(
                "error: {}",
                crate::diagnostics::printable(&e.to_string(), false)
            );
            return Exit::Failure;
        }
    };
    let t = &report.model.timings;
    outln!(
        "wrote {} ({} parts, {} components; file unit {}, deflection {} mm / {:.1}°){}",
        report.document.display(),
        report.parts.len(),
        report.components,
        if report.model.file_unit.is_empty() {
            "?"
        } else {
            &report.model.file_unit
        },
        a.deflection,
        a.angle,
        if report.new_project {
            ", a new project"
        } else {
            ""
        }
    );
    for p in &report.parts {
        let off = (p.volume_ratio - 1.0).abs() > 0.015;
        outln!(
            "  {:<16} {:>8} triangles  volume {:.4} of exact  ×{}  {}{}",
            crate::diagnostics::printable(&p.name, false),
            p.triangles,
            p.volume_ratio,
            p.instances,
            crate::diagnostics::printable(&p.stl, false),
            if off {
                "  warning: more than 1.5 % off the exact volume: use a smaller --deflection"
            } else {
                ""
            }
        );
        if p.mended > 0 {
            outln!(
                "  {:<16} note: {} gap(s) in Open CASCADE's mesh closed (a face's missing triangles filled or a node split in), at the exact volume",
                "",
                p.mended
            );
        }
    }
    outln!(
        "  Open CASCADE: parse {:.3} s, transfer {:.3} s, mesh {:.3} s{}; import {:.3} s in all",
        t.parse.as_secs_f64(),
        t.transfer.as_secs_f64(),
        t.mesh.as_secs_f64(),
        report
            .model
            .reader_peak_memory
            .map_or(String::new(), |m| format!(
                " (a child process, peak {} MB)",
                m / 1_000_000
            )),
        t.total.as_secs_f64()
    );
    Exit::Ok
}
