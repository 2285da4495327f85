//! The names of a document: kept in Unicode NFC (lookups by another spelling of the
//! same text find them), refused with a hidden character when given through the API,
//! and warned about when two of one kind differ only by case.

use super::file::DocumentFile;
use super::{scan, DocumentError};
use crate::diagnostics::SourceError;
use indexmap::IndexMap;
use std::path::Path;

/// `name` in Unicode NFC, the form every name of a document is kept in: lookups by
/// another spelling of the same text (`é` decomposed) find it. Borrows when `name` is
/// NFC already (ASCII and most text).
pub fn nfc_name(name: &str) -> std::borrow::Cow<'_, str> {
    use unicode_normalization::UnicodeNormalization;
    if unicode_normalization::is_nfc_quick(name.chars()) == unicode_normalization::IsNormalized::Yes
    {
        std::borrow::Cow::Borrowed(name)
    } else {
        std::borrow::Cow::Owned(name.nfc().collect())
    }
}

/// A name given through the API (a new robot, …) as the document keeps it: NFC, and
/// refused when it holds a control or invisible character (as in a file).
pub(crate) fn new_name(name: &str, what: &str) -> Result<String, DocumentError> {
    crate::diagnostics::checked_name(name)
        .map(std::borrow::Cow::into_owned)
        .map_err(|c| DocumentError::HiddenCharacter {
            what: what.to_string(),
            name: crate::diagnostics::printable(name, false).into_owned(),
            character: crate::diagnostics::describe_char(c),
        })
}

/// The document file with every name in NFC: all text except file paths (`stl`,
/// `step`, `urdf`, which name files on disk byte for byte) and `description`.
pub(super) fn nfc_file(file: DocumentFile) -> Result<DocumentFile, serde_yaml::Error> {
    fn walk(v: &mut serde_yaml::Value) {
        use serde_yaml::Value;
        match v {
            Value::String(s) => *s = nfc_name(s).into_owned(),
            Value::Sequence(items) => items.iter_mut().for_each(walk),
            Value::Mapping(m) => {
                let old = std::mem::take(m);
                for (k, mut val) in old {
                    let keep = matches!(k.as_str(), Some("stl" | "step" | "urdf" | "description"));
                    let k = match k {
                        Value::String(s) => Value::String(nfc_name(&s).into_owned()),
                        other => other,
                    };
                    if !keep {
                        walk(&mut val);
                    }
                    m.insert(k, val);
                }
            }
            Value::Tagged(t) => walk(&mut t.value),
            _ => {}
        }
    }
    let mut v = serde_yaml::to_value(&file)?;
    walk(&mut v);
    serde_yaml::from_value(v)
}

/// A name and where it is written (line, column), when the scan saw it.
type Placed = (String, Option<(usize, usize)>);

/// Names of one kind that differ only by case, as located warnings (see
/// [`Document::warnings`](super::Document::warnings)).
pub(super) fn case_warnings(
    file: &DocumentFile,
    path: &Path,
    positions: &scan::Positions,
) -> Vec<String> {
    let mut out = Vec::new();
    let mut kind = |what: &str, names: Vec<Placed>| {
        let mut by_case: IndexMap<String, Vec<&Placed>> = IndexMap::new();
        for n in &names {
            by_case.entry(n.0.to_lowercase()).or_default().push(n);
        }
        for group in by_case.values() {
            let mut spellings: Vec<&str> = group.iter().map(|n| n.0.as_str()).collect();
            spellings.dedup();
            if spellings.len() < 2 {
                continue;
            }
            let (line, col) = group[1].1.unwrap_or((0, 0));
            let list: Vec<String> = group
                .iter()
                .map(|(n, at)| match at {
                    Some((l, _)) => format!("`{n}` (line {l})"),
                    None => format!("`{n}`"),
                })
                .collect();
            out.push(
                SourceError::new(
                    path,
                    line,
                    col,
                    format!(
                        "{what} {} differ only by case: they are different names (lookups are exact), which is easy to confuse; rename one",
                        list.join(" and ")
                    ),
                )
                .to_string(),
            );
        }
    };
    let at = |p: String| positions.get(&p);
    kind(
        "parts",
        file.parts
            .keys()
            .map(|n| (n.clone(), at(format!("parts/{n}"))))
            .collect(),
    );
    kind(
        "components",
        file.components
            .iter()
            .enumerate()
            .map(|(i, c)| (c.name.clone(), at(format!("components/{i}/name"))))
            .collect(),
    );
    kind(
        "mates",
        file.mates
            .iter()
            .enumerate()
            .map(|(i, m)| (m.name.clone(), at(format!("mates/{i}/name"))))
            .collect(),
    );
    kind(
        "robots",
        file.robots
            .iter()
            .enumerate()
            .map(|(i, r)| (r.name.clone(), at(format!("robots/{i}/name"))))
            .collect(),
    );
    for (p, pf) in &file.parts {
        let refs = pf
            .planes
            .keys()
            .map(|r| (r.clone(), at(format!("parts/{p}/planes/{r}"))))
            .chain(
                pf.axes
                    .keys()
                    .map(|r| (r.clone(), at(format!("parts/{p}/axes/{r}")))),
            )
            .chain(
                pf.points
                    .keys()
                    .map(|r| (r.clone(), at(format!("parts/{p}/points/{r}")))),
            )
            .collect();
        kind(&format!("references of part `{p}`:"), refs);
        kind(
            &format!("features of part `{p}`:"),
            pf.features
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    (
                        f.name().to_string(),
                        at(format!("parts/{p}/features/{i}/name")),
                    )
                })
                .collect(),
        );
    }
    out
}
