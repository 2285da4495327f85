//! Bindings for a document's equations and global variables (SolidWorks'
//! `IEquationMgr`). The library evaluates (`crate::document::equations`); these only
//! convert indices and values.

use super::api::Api;
use super::bind_document::DocHandle;
use super::convert::fail;
use super::ScriptResult;
use rhai::{Array, Dynamic};

/// A script's 0-based equation index as the library's.
fn index(i: i64) -> ScriptResult<usize> {
    usize::try_from(i).map_err(|_| fail(format!("equation index {i}: indices start at 0")))
}

/// The equation at `i`, or the library's out-of-range error.
fn at<R>(
    d: &DocHandle,
    i: i64,
    f: impl FnOnce(&crate::document::Equation) -> R,
) -> ScriptResult<R> {
    let i = index(i)?;
    let doc = d.lock()?;
    let n = doc.equations().len();
    doc.equations().get(i).map(f).ok_or_else(|| {
        fail(format!(
            "equation index {i}: the document has {n} equation{}",
            if n == 1 { "" } else { "s" }
        ))
    })
}

pub(super) fn register(api: &mut Api) {
    api.section("Equations", "Equations and global variables (SolidWorks' `IEquationMgr`): `\"Factor\" = 2`, `\"D1@lift\" = 10 * \"Factor\"`. Values are the document's units (lengths mm, angles degrees; trigonometric functions in degrees, SolidWorks' default); global variables have none. Functions: `sin cos tan sec cosec cotan arcsin arccos atn arcsec arccosec arccotan abs exp log sqr int sgn min max`, constant `pi`. Indices are 0-based as in the API. Every change evaluates all equations in dependency order and re-solves the mates; a change that does not evaluate (unknown name, circle, division by zero, a value that is not finite or that its dimension refuses) is refused with nothing changed, naming the equation and the cause.");
    api.f(
        "Document.equations() -> array",
        "Every equation's text, `\"name\" = expression`, in order (`IEquationMgr.Equation(i)` for each `i < GetCount`).",
        |d: &mut DocHandle| -> ScriptResult<Array> {
            Ok(d.lock()?
                .equations()
                .iter()
                .map(|e| Dynamic::from(e.text()))
                .collect())
        },
    );
    api.f(
        "Document.equation_count() -> int",
        "The number of equations (`IEquationMgr.GetCount`).",
        |d: &mut DocHandle| -> ScriptResult<i64> { Ok(d.lock()?.equations().len() as i64) },
    );
    api.f(
        "Document.equation(i: int) -> string",
        "Equation `i`'s text (`IEquationMgr.Equation(i)`).",
        |d: &mut DocHandle, i: i64| at(d, i, |e| e.text()),
    );
    api.f(
        "Document.equation_value(i: int) -> float",
        "Equation `i`'s value at the last rebuild (`IEquationMgr.Value(i)`): mm, degrees, or no unit for a global variable.",
        |d: &mut DocHandle, i: i64| at(d, i, |e| e.value),
    );
    api.f(
        "Document.is_global_variable(i: int) -> bool",
        "Whether equation `i` sets a global variable (`IEquationMgr.GlobalVariable(i)`); else it drives a dimension.",
        |d: &mut DocHandle, i: i64| at(d, i, |e| e.is_global()),
    );
    api.f(
        "Document.equation_index(name: string) -> int",
        "The index of the equation setting `name` (a global variable or a dimension `D1@…`), -1 when none does.",
        |d: &mut DocHandle, name: &str| -> ScriptResult<i64> {
            Ok(d.lock()?
                .equation_index(name)
                .map_or(-1, |i| i as i64))
        },
    );
    api.f(
        "Document.set_equation(i: int, text: string)",
        "Replaces equation `i` (`IEquationMgr.Equation(i) = text`) and rebuilds.",
        |d: &mut DocHandle, i: i64, text: &str| -> ScriptResult<()> {
            d.lock()?.set_equation(index(i)?, text).map_err(fail)
        },
    );
    api.f(
        "Document.add_equation(text: string) -> int",
        "Adds an equation at the end (`IEquationMgr.Add3(-1, text, true, …)`) and rebuilds; returns its index.",
        |d: &mut DocHandle, text: &str| -> ScriptResult<i64> {
            Ok(d.lock()?.add_equation(None, text).map_err(fail)? as i64)
        },
    );
    api.f(
        "Document.add_equation(i: int, text: string) -> int",
        "Adds an equation at index `i` (-1: at the end, as `Add3`) and rebuilds; returns its index.",
        |d: &mut DocHandle, i: i64, text: &str| -> ScriptResult<i64> {
            let at = if i == -1 { None } else { Some(index(i)?) };
            Ok(d.lock()?.add_equation(at, text).map_err(fail)? as i64)
        },
    );
    api.f(
        "Document.delete_equation(i: int)",
        "Deletes equation `i` (`IEquationMgr.Delete`) and rebuilds; what it set keeps its value. Refused while another equation uses the global variable it sets.",
        |d: &mut DocHandle, i: i64| -> ScriptResult<()> {
            d.lock()?.delete_equation(index(i)?).map_err(fail).map(|_| ())
        },
    );
    api.f(
        "Document.global_variable(name: string) -> float",
        "A global variable's value; an unknown name lists close matches.",
        |d: &mut DocHandle, name: &str| -> ScriptResult<f64> {
            d.lock()?.global_variable(name).map_err(fail)
        },
    );
    api.f(
        "Document.set_global_variable(name: string, value: float)",
        "Sets a global variable (its equation becomes `\"name\" = value`) and rebuilds: the dimensions it drives and the mates follow.",
        |d: &mut DocHandle, name: &str, v: Dynamic| -> ScriptResult<()> {
            let v = super::convert::num(&v, "value")?;
            d.lock()?.set_global_variable(name, v).map_err(fail)
        },
    );
}
