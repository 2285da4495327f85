//! Task templates: the workflows of one operation, as editable YAML files validated
//! with located errors (`file:line:col`).
//!
//! ```yaml
//! operation: insertion        # insertion | screw | align
//! workflows:                  # a chain: each `from` is the previous `to`
//!   - {from: FREE, to: In_WS, generator: locate}
//!   - {from: In_WS, to: Grasped, generator: grasp}
//!   - {from: Grasped, to: Adjusted, generator: move}
//!   - {from: Adjusted, to: Assembled, generator: insert}
//! ```
//!
//! A user may delete states a fixture makes unnecessary (drop the `locate` line when
//! the part sits in a fixture at a known pose) or add their own steps; the chain must
//! stay contiguous and end at `Assembled`.

use super::PartState;
use crate::diagnostics::{locate, shorten, suggestion, SourceError};
use crate::document::scan::MAX_QUOTE;
use crate::sequence::Operation;
use serde::Deserialize;
use std::path::Path;

/// The skill generators a workflow can own.
pub const GENERATORS: [&str; 6] = ["locate", "grasp", "move", "insert", "screw", "align"];

/// One workflow of a template: from a state to the next, and its generator.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Workflow {
    /// Start state.
    pub from: PartState,
    /// Goal state.
    pub to: PartState,
    /// The generator's name (one of [`GENERATORS`]).
    pub generator: String,
}

impl Workflow {
    /// `from->to`, the workflow's name in skills and logs.
    pub fn name(&self) -> String {
        format!("{}->{}", self.from.name(), self.to.name())
    }
}

/// The workflows of one operation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Template {
    /// The operation the template is for.
    pub operation: Operation,
    /// The chain of workflows, in order.
    pub workflows: Vec<Workflow>,
}

/// A template that cannot be used.
pub type TemplateError = SourceError;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TemplateFile {
    operation: String,
    workflows: Vec<WorkflowFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct WorkflowFile {
    from: String,
    to: String,
    generator: String,
}

/// Which generators may take a part from `from` to `to`.
fn generator_fits(generator: &str, from: PartState, to: PartState) -> bool {
    use PartState::*;
    match generator {
        "locate" => to == InWs && from == Free,
        "grasp" => to == Grasped && matches!(from, Free | InWs),
        "move" => from == Grasped && to == Adjusted,
        "insert" | "screw" | "align" => to == Assembled && matches!(from, Grasped | Adjusted),
        _ => false,
    }
}

impl Template {
    /// Parses and validates a template; `path` names the file in errors.
    ///
    /// # Errors
    /// A YAML error, an unknown field, operation, state or generator (with "did you
    /// mean"), a broken chain, a generator that cannot make that step, a chain that
    /// does not end at `Assembled` — each at its line and column.
    pub fn parse(path: &Path, text: &str) -> Result<Self, TemplateError> {
        // The same YAML reader and budget as documents: no aliases (an alias bomb of
        // 2 MB expands to gigabytes), no duplicate keys, bounded nesting.
        let (file, _): (TemplateFile, _) = crate::document::scan::from_yaml(
            text,
            path,
            "invalid template",
            "the template is empty: a template is a YAML mapping with `operation:` and `workflows:`",
        )?;
        let q = |s: &str| shorten(s, MAX_QUOTE);
        let at = |needle: &str, from_line: usize| locate(text, needle, from_line).unwrap_or((0, 0));
        let err = |needle: &str, from_line: usize, msg: String| {
            let (l, c) = at(needle, from_line);
            SourceError::new(path, l, c, msg)
        };
        let operation = Operation::parse(&file.operation).ok_or_else(|| {
            err(
                &file.operation,
                1,
                format!("unknown operation `{}`", q(&file.operation)),
            )
            .with_help(suggestion(&file.operation, ["insertion", "screw", "align"]))
        })?;
        if file.workflows.is_empty() {
            return Err(err(
                "workflows",
                1,
                "a template needs at least one workflow".into(),
            ));
        }
        let names: Vec<&str> = PartState::ALL.iter().map(|s| s.name()).collect();
        let mut workflows = Vec::new();
        let mut line = at("workflows", 1).0.max(1);
        for w in &file.workflows {
            // Errors point at this entry: search from the line of its `from`.
            let entry_line = at(&format!("from: {}", w.from), line).0.max(line);
            let state = |s: &str| {
                PartState::parse(s).ok_or_else(|| {
                    err(s, entry_line, format!("unknown part state `{}`", q(s)))
                        .with_help(suggestion(s, names.iter().copied()))
                })
            };
            let from = state(&w.from)?;
            let to = state(&w.to)?;
            if !GENERATORS.contains(&w.generator.as_str()) {
                return Err(err(
                    &w.generator,
                    entry_line,
                    format!("unknown generator `{}`", q(&w.generator)),
                )
                .with_help(suggestion(&w.generator, GENERATORS)));
            }
            if let Some(prev) = workflows.last().map(|p: &Workflow| p.to) {
                if prev != from {
                    return Err(err(
                        &w.from,
                        entry_line,
                        format!(
                            "broken chain: this workflow starts at {} but the previous one ends at {}",
                            from.name(),
                            prev.name()
                        ),
                    ));
                }
            }
            if from >= to {
                return Err(err(
                    &w.to,
                    entry_line,
                    format!(
                        "a workflow must advance the part: {} -> {}",
                        from.name(),
                        to.name()
                    ),
                ));
            }
            if !generator_fits(&w.generator, from, to) {
                return Err(err(
                    &w.generator,
                    entry_line,
                    format!(
                        "generator `{}` cannot take a part from {} to {}",
                        w.generator,
                        from.name(),
                        to.name()
                    ),
                ));
            }
            workflows.push(Workflow {
                from,
                to,
                generator: w.generator.clone(),
            });
            line = entry_line + 1;
        }
        let last = workflows.last().expect("not empty");
        if last.to != PartState::Assembled {
            return Err(err(
                last.to.name(),
                line.saturating_sub(1).max(1),
                format!("the chain ends at {}, not Assembled", last.to.name()),
            ));
        }
        Ok(Self {
            operation,
            workflows,
        })
    }

    /// Reads and validates a template file.
    ///
    /// # Errors
    /// An unreadable file, or as [`parse`](Self::parse).
    pub fn read(path: &Path) -> Result<Self, TemplateError> {
        let text = crate::fsutil::read_text(path, crate::fsutil::FileKind::Document)
            .map_err(|e| SourceError::new(path, 0, 0, e.to_string()))?;
        Self::parse(path, &text)
    }

    /// [`read`](Self::read) of a file inside `project` (absolute, as
    /// [`crate::project::Project::resolve`] returns it), read through the project's held
    /// root folder: a folder swapped for a symbolic link after the path was checked is
    /// refused, never followed.
    ///
    /// # Errors
    /// As [`read`](Self::read).
    pub fn read_in(project: &crate::project::Project, path: &Path) -> Result<Self, TemplateError> {
        let text = project
            .read_text(path, crate::fsutil::FileKind::Document)
            .map_err(|e| SourceError::new(path, 0, 0, e.to_string()))?;
        Self::parse(path, &text)
    }
}

/// The default template text of an operation (the files of `models/templates/`).
pub fn default_template_text(operation: Operation) -> &'static str {
    match operation {
        Operation::Insertion => include_str!("../../models/templates/insertion.yaml"),
        Operation::Screw => include_str!("../../models/templates/screw.yaml"),
        Operation::Align => include_str!("../../models/templates/align.yaml"),
    }
}

/// The default template of an operation.
pub fn default_template(operation: Operation) -> Template {
    let name = format!("models/templates/{}.yaml", operation.name());
    Template::parse(Path::new(&name), default_template_text(operation))
        .expect("the bundled templates are valid (tested)")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bundled_templates_are_valid() {
        for op in [Operation::Insertion, Operation::Screw, Operation::Align] {
            let t = default_template(op);
            assert_eq!(t.operation, op);
            assert_eq!(t.workflows.last().unwrap().to, PartState::Assembled);
        }
    }

    #[test]
    fn a_fixture_template_without_locate_is_valid() {
        let text = "operation: insertion\nworkflows:\n  - {from: In_WS, to: Grasped, generator: grasp}\n  - {from: Grasped, to: Adjusted, generator: move}\n  - {from: Adjusted, to: Assembled, generator: insert}\n";
        let t = Template::parse(Path::new("t.yaml"), text).unwrap();
        assert_eq!(t.workflows.len(), 3);
        assert_eq!(t.workflows[0].from, PartState::InWs);
    }

    #[test]
    fn errors_are_located() {
        let p = Path::new("t.yaml");
        let text = "operation: insertion\nworkflows:\n  - {from: FREE, to: In_WS, generator: locate}\n  - {from: In_WS, to: Grasped, generator: grab}\n";
        let e = Template::parse(p, text).unwrap_err();
        assert_eq!(e.line, Some(4), "{e}");
        assert!(e.message.contains("grab"), "{e}");
        assert!(e.help.as_deref().unwrap().contains("grasp"), "{e:?}");

        let text = "operation: insertion\nworkflows:\n  - {from: FREE, to: In_WS, generator: locate}\n  - {from: Grasped, to: Adjusted, generator: move}\n";
        let e = Template::parse(p, text).unwrap_err();
        assert_eq!(e.line, Some(4), "{e}");
        assert!(e.message.contains("broken chain"), "{e}");

        let text =
            "operation: insertion\nworkflows:\n  - {from: FREE, to: In_Ws, generator: locate}\n";
        let e = Template::parse(p, text).unwrap_err();
        assert_eq!(e.line, Some(3), "{e}");
        assert!(e.help.as_deref().unwrap().contains("In_WS"), "{e:?}");

        let text =
            "operation: insertion\nworkflows:\n  - {from: FREE, to: In_WS, generator: locate}\n";
        let e = Template::parse(p, text).unwrap_err();
        assert!(e.message.contains("not Assembled"), "{e}");

        let text = "operation: insertion\nworkflow: []\n";
        let e = Template::parse(p, text).unwrap_err();
        assert_eq!(e.line, Some(2), "{e}");
    }

    #[test]
    fn aliases_and_long_values_are_refused_with_short_messages() {
        let p = Path::new("t.yaml");
        let text = "x: &a [1, 2]\ny: [*a, *a]\noperation: insertion\nworkflows: []\n";
        let e = Template::parse(p, text).unwrap_err();
        assert_eq!(e.line, Some(1), "{e}");
        assert!(e.message.contains("anchors"), "{e}");
        let long = "q".repeat(100_000);
        for text in [
            format!("operation: {long}\nworkflows: []\n"),
            // (YAML keys are at most 1024 characters.)
            format!("operation: insertion\n{}: 1\n", &long[..900]),
            format!("operation: insertion\nworkflows:\n  - {{from: {long}, to: In_WS, generator: locate}}\n"),
        ] {
            let e = Template::parse(p, &text).unwrap_err();
            assert!(e.line.is_some(), "{e}");
            assert!(e.to_string().len() < 600, "{} bytes", e.to_string().len());
            assert!(e.message.contains('…'), "{}", e.message);
        }
    }

    proptest::proptest! {
        #![proptest_config(crate::test_support::proptest_config(512))]

        /// Random byte edits of a valid template never panic: the result is a
        /// template or an error located in the file.
        #[test]
        fn mutated_templates_are_ok_or_located_errors(
            edits in proptest::collection::vec((0usize..400, proptest::num::u8::ANY, 0u8..3), 1..8),
        ) {
            let mut bytes = default_template_text(Operation::Insertion).as_bytes().to_vec();
            for (at, b, how) in edits {
                let at = at % (bytes.len() + 1);
                match how {
                    0 if at < bytes.len() => bytes[at] = b,
                    1 => bytes.insert(at, b),
                    _ => bytes.truncate(at.max(1)),
                }
            }
            let text = String::from_utf8_lossy(&bytes);
            if let Err(e) = Template::parse(Path::new("m.yaml"), &text) {
                proptest::prop_assert!(e.to_string().starts_with("m.yaml"), "{}", e);
                proptest::prop_assert!(e.to_string().len() < 1000, "{}", e);
            }
        }
    }
}

#[cfg(test)]
mod held_root_tests {
    use super::*;

    /// The project readers of a template, a hole table and a robot program read a path
    /// recorded inside the project through the held root: once its folder is a link to
    /// a folder outside, the read is refused (a read by name follows the link and
    /// returns the outside file).
    #[test]
    fn readers_in_a_project_never_follow_a_swapped_folder() {
        let dir = tempfile::tempdir().unwrap();
        let outside = tempfile::tempdir().unwrap();
        let files = [
            ("t.yaml", default_template_text(Operation::Insertion)),
            ("h.csv", "id,x,y,z,nx,ny,nz\nh0,0,0,0,0,0,1\n"),
            ("p.prg", include_str!("../../models/mz07_demo.prg")),
        ];
        std::fs::create_dir(dir.path().join("data")).unwrap();
        for (name, text) in files {
            std::fs::write(dir.path().join("data").join(name), text).unwrap();
            std::fs::write(outside.path().join(name), text).unwrap();
        }
        let project = crate::project::Project::new(dir.path()).unwrap();
        let data = project.root().join("data");
        assert!(Template::read_in(&project, &data.join("t.yaml")).is_ok());
        assert!(crate::kinematics::read_holes_in(&project, &data.join("h.csv")).is_ok());
        assert!(crate::kinematics::read_program_in(&project, &data.join("p.prg")).is_ok());
        // `data` swapped for a link to the outside folder after the paths were checked.
        std::fs::rename(&data, dir.path().join("away")).unwrap();
        std::os::unix::fs::symlink(outside.path(), &data).unwrap();
        assert!(
            Template::read(&data.join("t.yaml")).is_ok(),
            "by name: followed"
        );
        assert!(Template::read_in(&project, &data.join("t.yaml")).is_err());
        assert!(crate::kinematics::read_holes_in(&project, &data.join("h.csv")).is_err());
        assert!(crate::kinematics::read_program_in(&project, &data.join("p.prg")).is_err());
    }
}
