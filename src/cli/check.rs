//! `fitup check DOC`.

use super::Exit;
// Every line goes through the CLI writer, which stops quietly on a closed pipe
// (`fitup check doc.yaml | head`); `println!` would panic there.
use super::out::{errln as eprintln, outln as println};
use crate::document::Document;
use std::path::Path;

/// Characters of a document's description that `check` prints (a description may be
/// as long as the 16 MiB document).
const DESCRIPTION_CHARS: usize = 2000;

/// Lines of a document's description that `check` prints.
const DESCRIPTION_LINES: usize = 20;

/// The description as `check` prints it: at most [`DESCRIPTION_LINES`] lines and
/// [`DESCRIPTION_CHARS`] characters, then how much was left out.
fn shown_description(d: &str) -> String {
    let mut end = d.len();
    for (lines, (i, _)) in d.match_indices('\n').enumerate() {
        if lines + 1 == DESCRIPTION_LINES {
            end = i;
            break;
        }
    }
    if let Some((i, _)) = d[..end].char_indices().nth(DESCRIPTION_CHARS) {
        end = i;
    }
    if end == d.len() {
        return d.to_string();
    }
    let rest = d[end..].chars().count();
    format!(
        "{}… ({} more characters of the description not shown)",
        &d[..end],
        crate::math::format::count(rest as u64)
    )
}

pub(super) fn check(path: &Path) -> Exit {
    let doc = match Document::open(path) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {}", e.render());
            return Exit::Failure;
        }
    };
    println!("{}: ok", path.display());
    if let Some(d) = doc.description() {
        println!("  {}", shown_description(d));
    }
    let mut warnings = doc.warnings().len();
    for w in doc.warnings() {
        println!("  warning: {w}");
    }
    println!("  parts ({}):", doc.parts().count());
    // Parts sharing one mesh (one file named by many parts) are inspected once.
    let mut inspected = std::collections::HashMap::new();
    for p in doc.parts() {
        if !p.is_loaded() {
            // A note, not a warning: SolidWorks opens such an assembly the same way.
            println!(
                "    {:<12} not loaded (only suppressed components use it)  {}",
                p.name, p.stl
            );
            continue;
        }
        let r = inspected
            .entry(std::sync::Arc::as_ptr(&p.mesh))
            .or_insert_with(|| p.mesh.inspect());
        let mut notes = Vec::new();
        if !r.is_watertight() {
            notes.push(format!(
                "not watertight ({} open, {} non-manifold, {} misoriented edges): containment cannot be tested",
                r.boundary_edges, r.non_manifold_edges, r.misoriented_edges
            ));
        }
        if r.degenerate_triangles > 0 {
            notes.push(format!("{} degenerate triangles", r.degenerate_triangles));
        }
        warnings += notes.len();
        // A STEP part: how its tessellation relates to the exact solid, and whether it
        // came from the project's store (no Open CASCADE read this time).
        let step = p.step.as_ref().map_or(String::new(), |g| {
            format!(
                " (STEP, volume {:.4} of exact, {})",
                g.volume_ratio,
                if g.from_store {
                    "stored tessellation"
                } else {
                    "tessellated now"
                }
            )
        });
        println!(
            "    {:<12} {:>7} triangles  {}{step}{}",
            p.name,
            p.mesh.triangles.len(),
            p.stl,
            if notes.is_empty() {
                String::new()
            } else {
                format!("  warning: {}", notes.join("; "))
            }
        );
    }
    println!("  components ({}):", doc.components().len());
    for c in doc.components() {
        // The Transform's Display is the pose for people (mm, degrees, no `-0`).
        println!(
            "    {:<12} {:<10} {}  at {}{}",
            c.name,
            c.part,
            if c.fixed { "fixed" } else { "free " },
            c.transform,
            if c.is_suppressed() {
                "  (suppressed)"
            } else {
                ""
            }
        );
    }
    println!("  mates ({}), all satisfied", doc.mates().len());
    for name in doc.dimensions() {
        if let Ok(d) = doc.dimension(&name) {
            println!("    {} = {}", d.name, d.document_value());
        }
    }
    if !doc.robots().is_empty() {
        println!("  robots ({}):", doc.robots().len());
        for r in doc.robots() {
            println!(
                "    {:<12} {} joints, {} solver, TCP at {}",
                r.name(),
                r.robot().dof(),
                match r.robot().solver() {
                    crate::kinematics::IkSolverKind::Opw => "closed-form (OPW)",
                    crate::kinematics::IkSolverKind::Ur => "closed-form (UR)",
                    crate::kinematics::IkSolverKind::Numeric => "numeric",
                },
                r.tcp()
            );
        }
    }
    if warnings > 0 {
        println!("  {warnings} warning(s)");
    }
    Exit::Ok
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_description_is_cut_with_what_was_left_out() {
        assert_eq!(shown_description("short\ntext"), "short\ntext");
        let long = "é".repeat(5000);
        let shown = shown_description(&long);
        assert!(shown.starts_with(&"é".repeat(2000)), "{shown}");
        assert!(
            shown.ends_with("… (3,000 more characters of the description not shown)"),
            "{shown}"
        );
        let lines = "line\n".repeat(100);
        let shown = shown_description(&lines);
        assert_eq!(shown.matches("line").count(), 20, "{shown}");
        assert!(
            shown.ends_with("(401 more characters of the description not shown)"),
            "{shown}"
        );
    }
}
