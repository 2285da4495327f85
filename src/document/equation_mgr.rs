//! The document's equations (SolidWorks' `IEquationMgr`): list, add, change, delete,
//! global variables by name, and their evaluation on every rebuild. The expression
//! language and its bounds are in [`super::equations`].

use super::equations::{
    self, order, shown, Equation, EquationCause, EquationError, EquationLimit, EquationTarget,
    MAX_EQUATIONS,
};
use super::{nfc_name, Document, DocumentError};
use std::collections::HashMap;

impl Document {
    /// The equations in order (`IEquationMgr.Equation(i)`, `Value(i)`,
    /// `GlobalVariable(i)`), each with its value at the last rebuild (mm, degrees, or
    /// unitless for a global variable).
    pub fn equations(&self) -> &[Equation] {
        &self.equations
    }

    /// The index of the equation setting `target` (a global variable or a dimension's
    /// full name), if any.
    pub fn equation_index(&self, target: &str) -> Option<usize> {
        let target = nfc_name(target);
        self.equations.iter().position(|e| e.target == *target)
    }

    /// The value of global variable `name` at the last rebuild (no unit).
    pub fn global_variable(&self, name: &str) -> Result<f64, DocumentError> {
        match self.equation_index(name) {
            Some(i) if self.equations[i].is_global() => Ok(self.equations[i].value),
            _ => Err(self.global_not_found(name)),
        }
    }

    fn global_not_found(&self, name: &str) -> DocumentError {
        DocumentError::not_found(
            "global variable",
            name,
            self.equations
                .iter()
                .filter(|e| e.is_global())
                .map(|e| e.target.as_str()),
        )
    }

    /// Adds the equation `text` (`"Factor" = 2`, `"D1@lift" = 10 * "Factor"`) at
    /// `index` (`None`: at the end; SolidWorks' `IEquationMgr.Add3`) and rebuilds.
    /// Returns its index. Refused, with nothing changed, when it does not parse, sets
    /// a name another equation sets, uses an unknown name, closes a circle, does not
    /// evaluate to a finite number, gives a dimension a value it refuses or leaves
    /// mates that cannot be satisfied.
    pub fn add_equation(
        &mut self,
        index: Option<usize>,
        text: &str,
    ) -> Result<usize, DocumentError> {
        let n = self.equations.len();
        let at = index.unwrap_or(n);
        if at > n {
            return Err(DocumentError::OutOfRange {
                what: "equation index".into(),
                value: at.to_string(),
                rule: "at most the number of equations (none: at the end)",
            });
        }
        let e = parsed(text, at)?;
        self.change_equations(|list| list.insert(at, e))?;
        Ok(at)
    }

    /// Replaces equation `index` by `text` (`IEquationMgr.Equation(i) = …`) and
    /// rebuilds; refused as [`add_equation`](Self::add_equation).
    pub fn set_equation(&mut self, index: usize, text: &str) -> Result<(), DocumentError> {
        self.check_equation_index(index)?;
        let mut e = parsed(text, index)?;
        // An equation of a sub-document stays that document's.
        e.scope = self.equations[index].scope.clone();
        self.change_equations(|list| list[index] = e)
    }

    /// Deletes equation `index` (`IEquationMgr.Delete`) and rebuilds: what it set
    /// keeps its value, as in SolidWorks. Refused when another equation uses the
    /// global variable it sets. Returns the deleted equation.
    pub fn delete_equation(&mut self, index: usize) -> Result<Equation, DocumentError> {
        self.check_equation_index(index)?;
        let removed = self.equations[index].clone();
        self.change_equations(|list| {
            list.remove(index);
        })?;
        Ok(removed)
    }

    /// Sets global variable `name` to `value` (rewrites its equation as `"name" =
    /// value`, as CodeStack's "change global variable" does) and rebuilds. Refused for
    /// a name no equation sets as a global variable and for a value that is not
    /// finite.
    pub fn set_global_variable(&mut self, name: &str, value: f64) -> Result<(), DocumentError> {
        let i = match self.equation_index(name) {
            Some(i) if self.equations[i].is_global() => i,
            _ => return Err(self.global_not_found(name)),
        };
        if !value.is_finite() {
            return Err(DocumentError::OutOfRange {
                what: format!("global variable `{name}`"),
                value: value.to_string(),
                rule: "a finite number",
            });
        }
        let text = format!("\"{}\" = {value:?}", self.equations[i].target);
        self.set_equation(i, &text)
    }

    /// The equation that drives dimension `full_name`, if any (its value is then the
    /// equation's, and [`set_dimension`](Self::set_dimension) refuses to change it).
    pub fn driving_equation(&self, full_name: &str) -> Option<usize> {
        self.equation_index(full_name)
            .filter(|&i| self.equations[i].kind == EquationTarget::Dimension)
    }

    /// The equations that use or set `name` (a dimension's full name or a global
    /// variable), by index.
    pub fn equations_using(&self, name: &str) -> Vec<usize> {
        let name = nfc_name(name);
        self.equations
            .iter()
            .enumerate()
            .filter(|(_, e)| {
                let mut names = Vec::new();
                e.expr.names(&mut names);
                e.target == *name || names.iter().any(|n| *n == *name)
            })
            .map(|(i, _)| i)
            .collect()
    }

    fn check_equation_index(&self, index: usize) -> Result<(), DocumentError> {
        if index >= self.equations.len() {
            return Err(DocumentError::OutOfRange {
                what: "equation index".into(),
                value: index.to_string(),
                rule: "0-based, below the number of equations",
            });
        }
        Ok(())
    }

    /// Changes the list of equations and rebuilds; on failure nothing changes.
    fn change_equations(
        &mut self,
        change: impl FnOnce(&mut Vec<Equation>),
    ) -> Result<(), DocumentError> {
        let before = self.equations.clone();
        change(&mut self.equations);
        if let Err(e) = self.rebuild() {
            self.equations = before;
            return Err(e);
        }
        Ok(())
    }

    /// Evaluates the equations in dependency order and gives each driven dimension its
    /// value (without solving the mates). On failure the dimensions may be partly
    /// set: the caller restores them.
    pub(crate) fn apply_equations(&mut self) -> Result<(), EquationError> {
        let err = |doc: &Self, index: usize, cause| EquationError {
            index,
            text: shown(&doc.equations[index].text()),
            cause,
        };
        if self.equations.len() > MAX_EQUATIONS {
            return Err(err(
                self,
                MAX_EQUATIONS,
                EquationCause::TooLarge(EquationLimit::Equations {
                    count: self.equations.len(),
                }),
            ));
        }
        let dimensions = self.dimensions();
        let mut sets: HashMap<&str, usize> = HashMap::new();
        for (i, e) in self.equations.iter().enumerate() {
            if let Some(&first) = sets.get(e.target.as_str()) {
                let cause = EquationCause::SetTwice {
                    name: e.target.clone(),
                    first,
                };
                return Err(err(self, i, cause));
            }
            if e.kind == EquationTarget::Dimension && !dimensions.contains(&e.target) {
                let hint = crate::diagnostics::suggestion(
                    &e.target,
                    dimensions.iter().map(String::as_str),
                );
                let cause = EquationCause::NotADimension {
                    name: e.target.clone(),
                    hint,
                };
                return Err(err(self, i, cause));
            }
            sets.insert(&e.target, i);
        }
        // Names used but set by no equation: dimensions at their current value.
        let mut current: HashMap<String, f64> = HashMap::new();
        for (i, e) in self.equations.iter().enumerate() {
            let mut names = Vec::new();
            e.expr.names(&mut names);
            for n in names {
                if sets.contains_key(n.as_str()) || current.contains_key(&n) {
                    continue;
                }
                match self.dimension(&n) {
                    Ok(d) => {
                        current.insert(n, d.document_value());
                    }
                    Err(_) => {
                        let known = sets
                            .keys()
                            .copied()
                            .chain(dimensions.iter().map(String::as_str));
                        let hint = crate::diagnostics::suggestion(&n, known);
                        return Err(err(self, i, EquationCause::UnknownName { name: n, hint }));
                    }
                }
            }
        }
        let ordered = order(&self.equations, &sets)?;
        let mut values = vec![0.0; self.equations.len()];
        for &i in &ordered {
            let lookup = |n: &str| match sets.get(n) {
                Some(&j) => values[j],
                None => current.get(n).copied().unwrap_or(0.0),
            };
            values[i] = self.equations[i]
                .expr
                .eval(&lookup)
                .map_err(|c| err(self, i, c))?;
        }
        for &i in &ordered {
            if self.equations[i].kind != EquationTarget::Dimension {
                continue;
            }
            let name = self.equations[i].target.clone();
            let kind = self
                .dimension(&name)
                .map_err(|e| err(self, i, EquationCause::Value(Box::new(e))))?
                .kind;
            let internal = super::Dimension::from_document(kind, values[i]);
            self.set_dimension_value(&name, internal)
                .map_err(|e| err(self, i, EquationCause::Value(Box::new(e))))?;
        }
        for (e, v) in self.equations.iter_mut().zip(values) {
            e.value = v;
        }
        Ok(())
    }
}

/// Parses `text` as the equation at `index`.
fn parsed(text: &str, index: usize) -> Result<Equation, DocumentError> {
    parse_equation(text).map_err(|cause| DocumentError::Equation {
        at: None,
        source: EquationError {
            index,
            text: shown(text),
            cause,
        },
    })
}

/// An equation from its text, not yet evaluated: a target with `@` is a dimension,
/// any other a global variable.
pub(crate) fn parse_equation(text: &str) -> Result<Equation, EquationCause> {
    let (target, expression, expr) = equations::parse(text)?;
    let kind = if target.contains('@') {
        EquationTarget::Dimension
    } else {
        EquationTarget::Global
    };
    Ok(Equation {
        target,
        kind,
        expression,
        value: 0.0,
        expr,
        scope: None,
    })
}

/// `text` with every name in double quotes passed through `rename` (the quotes and
/// everything else kept as written).
fn rename_quoted<E>(
    text: &str,
    rename: &mut dyn FnMut(&str) -> Result<String, E>,
) -> Result<String, E> {
    let mut out = String::with_capacity(text.len() + 16);
    let mut rest = text;
    while let Some(open) = rest.find('"') {
        out.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        let Some(close) = after.find('"') else {
            out.push_str(&rest[open..]);
            return Ok(out);
        };
        out.push('"');
        let name = super::nfc_name(after[..close].trim());
        out.push_str(&rename(&name)?);
        out.push('"');
        rest = &after[close + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

impl Equation {
    /// The same equation with every name (its target and those it uses) passed
    /// through `rename`; value and scope kept. `index` is the equation's index where
    /// it goes, for the error when the renamed text does not parse.
    pub(crate) fn renamed(
        &self,
        index: usize,
        rename: &mut dyn FnMut(&str) -> Result<String, DocumentError>,
    ) -> Result<Equation, DocumentError> {
        let text = rename_quoted(&self.text(), rename)?;
        let mut e = parse_equation(&text).map_err(|cause| DocumentError::Equation {
            at: None,
            source: EquationError {
                index,
                text: shown(&text),
                cause,
            },
        })?;
        e.value = self.value;
        e.scope = self.scope.clone();
        Ok(e)
    }
}

/// A file's equations (`texts`) parsed, evaluated and applied to the dimensions they
/// drive in `doc`; an error is located at its equation's line (`positions` of the
/// scan of `path`).
pub(super) fn load(
    texts: &[String],
    doc: &mut Document,
    positions: &super::scan::Positions,
    path: &std::path::Path,
) -> Result<(), DocumentError> {
    use super::equations::MAX_EQUATIONS;
    use crate::diagnostics::SourceError;
    let located = |source: EquationError| {
        let item = source.index.min(texts.len().saturating_sub(1));
        let at = positions
            .get(&format!("equations/{item}"))
            .unwrap_or((0, 0));
        DocumentError::Equation {
            at: SourceError::at(path, at, &source),
            source,
        }
    };
    if texts.len() > MAX_EQUATIONS {
        return Err(located(EquationError {
            index: MAX_EQUATIONS,
            text: shown(&texts[MAX_EQUATIONS]),
            cause: EquationCause::TooLarge(EquationLimit::Equations { count: texts.len() }),
        }));
    }
    let mut list = Vec::with_capacity(texts.len());
    for (index, text) in texts.iter().enumerate() {
        let e = parse_equation(text).map_err(|cause| {
            located(EquationError {
                index,
                text: shown(text),
                cause,
            })
        })?;
        list.push(e);
    }
    // The file's own first, then the sub-documents' (already in `doc`, renamed).
    list.append(&mut doc.equations);
    doc.equations = list;
    doc.apply_equations().map_err(located)
}
