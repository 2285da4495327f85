//! Equations and global variables (SolidWorks' `IEquationMgr`): `"Factor" = 2`,
//! `"D1@lift" = 10 * "Factor"`.
//!
//! An equation sets a global variable (a name without `@`) or a driving dimension
//! (`D1@<mate>`, a robot joint's `D1@…`) to an expression of numbers, other global
//! variables and dimensions. Values are in the **document's units**, as the file
//! writes them: lengths mm, angles degrees; the trigonometric functions take and give
//! degrees (SolidWorks' default "angular equation units"). Global variables have no
//! unit.
//!
//! Equations are evaluated in dependency order on every rebuild; a dimension an
//! equation uses but does not set is read at its current value. Every input is
//! bounded ([`MAX_EQUATIONS`], [`MAX_EQUATION_LEN`], [`MAX_NODES`], [`MAX_NESTING`]):
//! parsing and evaluation never recurse deeper than [`MAX_NODES`].

use std::collections::HashMap;

/// At most this many equations in a document.
pub const MAX_EQUATIONS: usize = 1000;
/// At most this many bytes in one equation's text.
pub const MAX_EQUATION_LEN: usize = 1000;
/// At most this many numbers, names, operators and function calls in one expression.
pub const MAX_NODES: usize = 256;
/// At most this many nested parentheses (and function calls) in one expression.
pub const MAX_NESTING: usize = 32;
/// At most this many bytes in a global variable's name.
pub const MAX_NAME_LEN: usize = 256;

/// Why an equation was refused: which one (0-based index, as `equation(i)`, and its
/// text) and the cause.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("equation [{index}] {text}: {cause}")]
pub struct EquationError {
    /// 0-based index in the document's equations (SolidWorks' `Equation(i)`).
    pub index: usize,
    /// The equation's text (shortened when long).
    pub text: String,
    /// What is wrong.
    pub cause: EquationCause,
}

/// What is wrong with an equation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EquationCause {
    /// The text is not `"name" = expression`.
    #[error("syntax at column {column}: {problem}")]
    Syntax {
        /// 1-based column (in characters) in the equation's text.
        column: usize,
        /// What was expected.
        problem: SyntaxProblem,
    },
    /// A name used in the expression is neither a global variable nor a dimension.
    #[error("unknown name \"{name}\" ({hint})")]
    UnknownName {
        /// The name.
        name: String,
        /// Close matches.
        hint: String,
    },
    /// The equation sets a name with `@` that is no dimension of the document.
    #[error("\"{name}\" is not a dimension of this document ({hint}); names without `@` are global variables")]
    NotADimension {
        /// The name.
        name: String,
        /// Close matches.
        hint: String,
    },
    /// Two equations set one name.
    #[error("\"{name}\" is set by equation [{first}] already")]
    SetTwice {
        /// The name.
        name: String,
        /// The index of the first equation that sets it.
        first: usize,
    },
    /// The equations depend on each other in a circle.
    #[error("circular: {}", .0.iter().map(|n| format!("\"{n}\"")).collect::<Vec<_>>().join(" uses "))]
    Cycle(Vec<String>),
    /// A division by zero.
    #[error("division by zero")]
    DivisionByZero,
    /// A result that is not a finite number (`sqr(-1)`, `log(0)`, an overflow).
    #[error("{0} is not a finite number")]
    NonFinite(NonFiniteAt),
    /// The dimension refused the value (a negative distance, beyond 1e9 mm, a joint
    /// limit).
    #[error("{0}")]
    Value(#[source] Box<super::DocumentError>),
    /// Past one of the bounds ([`MAX_EQUATIONS`], [`MAX_EQUATION_LEN`],
    /// [`MAX_NODES`], [`MAX_NESTING`], [`MAX_NAME_LEN`]).
    #[error("{0}")]
    TooLarge(#[source] EquationLimit),
}

/// What an equation's text holds where its grammar wants something else (the
/// cause of an [`EquationCause::Syntax`]).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum SyntaxProblem {
    /// The text does not start with the name it sets.
    NoTarget,
    /// No `=` after the name.
    NoEquals,
    /// Text after the expression that is no operator.
    NoOperator,
    /// A name's closing `"` is missing.
    UnclosedName,
    /// An empty name `""`.
    EmptyName,
    /// A control or invisible character in a name.
    NameCharacter(char),
    /// A `(` that is not closed.
    NoCloseParen,
    /// Something that does not begin a number, a name, a function or `(`.
    NoOperand,
    /// The text ends before the expression does.
    EndsEarly,
    /// Digits that do not make a number.
    NotANumber {
        /// The text read.
        text: String,
    },
    /// A unit suffix fitup does not know (the message names the closest units).
    UnknownUnit {
        /// The unit as written.
        unit: String,
    },
    /// A function fitup does not know (the message names the closest functions).
    UnknownFunction {
        /// The word as written.
        word: String,
    },
    /// A function's name without `(` after it.
    NoOpenParen {
        /// The function as written.
        function: String,
    },
    /// A call with too few or too many arguments.
    Arguments {
        /// The function as written.
        function: String,
        /// The fewest arguments it takes.
        least: usize,
        /// The most (`usize::MAX`: no limit).
        most: usize,
    },
}

impl std::fmt::Display for SyntaxProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SyntaxProblem::NoTarget => f.write_str(
                "an equation starts with the name it sets in double quotes: `\"Factor\" = 2`, `\"D1@lift\" = 10 * \"Factor\"`",
            ),
            SyntaxProblem::NoEquals => f.write_str("expected `=` after the name"),
            SyntaxProblem::NoOperator => {
                f.write_str("expected an operator (`+ - * / ^`) or the end")
            }
            SyntaxProblem::UnclosedName => f.write_str("a name's closing `\"` is missing"),
            SyntaxProblem::EmptyName => f.write_str("an empty name `\"\"`"),
            SyntaxProblem::NameCharacter(c) => write!(
                f,
                "{} is not allowed in names",
                crate::diagnostics::describe_char(*c)
            ),
            SyntaxProblem::NoCloseParen => f.write_str("expected `)`"),
            SyntaxProblem::NoOperand => {
                f.write_str("expected a number, a \"name\", a function or `(`")
            }
            SyntaxProblem::EndsEarly => f.write_str("the expression ends too early"),
            SyntaxProblem::NotANumber { text } => write!(f, "`{text}` is not a number"),
            SyntaxProblem::UnknownUnit { unit } => write!(
                f,
                "unknown unit `{unit}` ({}); values are in document units: lengths mm, angles degrees",
                crate::diagnostics::suggestion(&unit.to_lowercase(), UNITS.iter().map(|u| u.0))
            ),
            SyntaxProblem::UnknownFunction { word } => {
                let names = FUNCTIONS.iter().map(|f| f.0).chain(["pi"]);
                write!(
                    f,
                    "unknown function `{word}` ({}); names are written in double quotes",
                    crate::diagnostics::suggestion(&word.to_lowercase(), names)
                )
            }
            SyntaxProblem::NoOpenParen { function } => {
                write!(f, "expected `(` after `{function}`")
            }
            SyntaxProblem::Arguments {
                function,
                least,
                most,
            } => match (*least, *most) {
                (1, 1) => write!(f, "`{function}` takes 1 argument"),
                (n, MANY) => write!(f, "`{function}` takes {n} or more arguments"),
                (n, _) => write!(f, "`{function}` takes {n} arguments"),
            },
        }
    }
}

/// Where a value that is not a finite number came from (the cause of an
/// [`EquationCause::NonFinite`]).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum NonFiniteAt {
    /// A number as written (`1e999`).
    Number {
        /// Its digits.
        text: String,
    },
    /// A function's result (`sqr(-1)`, `log(0)`).
    Call {
        /// The function's name.
        function: &'static str,
        /// Its arguments.
        arguments: Vec<f64>,
    },
    /// An operator's result (`+ - * / ^`).
    Operator(char),
    /// Any other value.
    Value,
}

impl std::fmt::Display for NonFiniteAt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NonFiniteAt::Number { text } => write!(f, "`{text}`"),
            NonFiniteAt::Call {
                function,
                arguments,
            } => {
                let shown: Vec<String> = arguments.iter().map(|x| x.to_string()).collect();
                write!(f, "{function}({})", shown.join(", "))
            }
            NonFiniteAt::Operator(op) => write!(f, "the result of `{op}`"),
            NonFiniteAt::Value => f.write_str("a value"),
        }
    }
}

/// Which bound of the equations was passed (the cause of an
/// [`EquationCause::TooLarge`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum EquationLimit {
    /// More than [`MAX_EQUATIONS`] equations.
    #[error("{count} equations: a document holds at most {MAX_EQUATIONS}")]
    Equations {
        /// How many there are.
        count: usize,
    },
    /// An equation longer than [`MAX_EQUATION_LEN`] bytes.
    #[error("{bytes} bytes: an equation holds at most {MAX_EQUATION_LEN}")]
    Length {
        /// Its length.
        bytes: usize,
    },
    /// More than [`MAX_NODES`] numbers, names and operations in one expression.
    #[error("more than {MAX_NODES} numbers, names and operations in one expression")]
    Nodes,
    /// A name longer than [`MAX_NAME_LEN`] bytes.
    #[error("a name of {bytes} bytes: at most {MAX_NAME_LEN}")]
    Name {
        /// Its length.
        bytes: usize,
    },
    /// More than [`MAX_NESTING`] nested parentheses.
    #[error("more than {MAX_NESTING} nested parentheses")]
    Nesting,
}

/// What an equation sets.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EquationTarget {
    /// A global variable (no unit).
    Global,
    /// A driving dimension (its value in mm or degrees).
    Dimension,
}

/// One equation: `"target" = expression`, and its value at the last rebuild.
#[derive(Debug, Clone, PartialEq)]
pub struct Equation {
    /// The name it sets, NFC: a global variable or a dimension's full name.
    pub target: String,
    /// A global variable or a dimension.
    pub kind: EquationTarget,
    /// The right-hand side as written (trimmed).
    pub expression: String,
    /// Its value at the last evaluation, in document units (mm, degrees, or none for a
    /// global variable).
    pub value: f64,
    pub(crate) expr: Expr,
    /// The sub-assembly whose document (`assemblies: - {file: …}`) it belongs to
    /// (full name), `None` for this document's own: where a save writes it.
    pub(crate) scope: Option<String>,
}

impl Equation {
    /// The equation as SolidWorks' `IEquationMgr.Equation(i)` writes it:
    /// `"target" = expression`.
    pub fn text(&self) -> String {
        format!("\"{}\" = {}", self.target, self.expression)
    }

    /// Whether it sets a global variable (`IEquationMgr.GlobalVariable(i)`).
    pub fn is_global(&self) -> bool {
        self.kind == EquationTarget::Global
    }
}

/// An expression's tree.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Expr {
    Number(f64),
    Name(String),
    Neg(Box<Expr>),
    Binary(char, Box<Expr>, Box<Expr>),
    /// A comparison (`<`, `>`, `<=`, `>=`, `=`, `<>`): 1 when it holds, else 0.
    Compare(&'static str, Box<Expr>, Box<Expr>),
    Call(Function, Vec<Expr>),
}

/// The functions of SolidWorks' equations (angles in degrees).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Function {
    Sin,
    Cos,
    Tan,
    Sec,
    Cosec,
    Cotan,
    Arcsin,
    Arccos,
    Atn,
    Arcsec,
    Arccosec,
    Arccotan,
    Abs,
    Exp,
    Log,
    Sqr,
    Int,
    Sgn,
    Min,
    Max,
    Sum,
    Avg,
    /// `iif(condition, then, else)` (`if` too): only the branch taken is evaluated.
    Iif,
}

/// How many arguments a function of [`FUNCTIONS`] takes: exactly `n`, or `n` or more
/// (`usize::MAX` in the table's third column means "any number from the second").
const MANY: usize = usize::MAX;

/// Every function name, as written in equations, with its least number of arguments
/// and its most ([`MANY`]: no limit but [`MAX_NODES`]).
const FUNCTIONS: &[(&str, Function, usize, usize)] = &[
    ("sin", Function::Sin, 1, 1),
    ("cos", Function::Cos, 1, 1),
    ("tan", Function::Tan, 1, 1),
    ("sec", Function::Sec, 1, 1),
    ("cosec", Function::Cosec, 1, 1),
    ("cotan", Function::Cotan, 1, 1),
    ("arcsin", Function::Arcsin, 1, 1),
    ("arccos", Function::Arccos, 1, 1),
    ("atn", Function::Atn, 1, 1),
    ("arcsec", Function::Arcsec, 1, 1),
    ("arccosec", Function::Arccosec, 1, 1),
    ("arccotan", Function::Arccotan, 1, 1),
    ("abs", Function::Abs, 1, 1),
    ("exp", Function::Exp, 1, 1),
    ("log", Function::Log, 1, 1),
    ("sqr", Function::Sqr, 1, 1),
    ("sqrt", Function::Sqr, 1, 1),
    ("int", Function::Int, 1, 1),
    ("sgn", Function::Sgn, 1, 1),
    ("min", Function::Min, 2, MANY),
    ("max", Function::Max, 2, MANY),
    ("sum", Function::Sum, 1, MANY),
    ("avg", Function::Avg, 1, MANY),
    ("iif", Function::Iif, 3, 3),
    ("if", Function::Iif, 3, 3),
];

impl Function {
    fn name(self) -> &'static str {
        FUNCTIONS
            .iter()
            .find(|f| f.1 == self)
            .map(|f| f.0)
            .unwrap_or("?")
    }

    fn apply(self, a: &[f64]) -> f64 {
        let d = |x: f64| x.to_radians();
        let x = a[0];
        match self {
            Function::Sin => d(x).sin(),
            Function::Cos => d(x).cos(),
            Function::Tan => d(x).tan(),
            Function::Sec => 1.0 / d(x).cos(),
            Function::Cosec => 1.0 / d(x).sin(),
            Function::Cotan => 1.0 / d(x).tan(),
            Function::Arcsin => x.asin().to_degrees(),
            Function::Arccos => x.acos().to_degrees(),
            Function::Atn => x.atan().to_degrees(),
            Function::Arcsec => (1.0 / x).acos().to_degrees(),
            Function::Arccosec => (1.0 / x).asin().to_degrees(),
            Function::Arccotan => (1.0 / x).atan().to_degrees(),
            Function::Abs => x.abs(),
            Function::Exp => x.exp(),
            Function::Log => x.ln(),
            Function::Sqr => x.sqrt(),
            Function::Int => x.trunc(),
            Function::Sgn => {
                if x > 0.0 {
                    1.0
                } else if x < 0.0 {
                    -1.0
                } else {
                    0.0
                }
            }
            Function::Min => a.iter().copied().fold(f64::INFINITY, f64::min),
            Function::Max => a.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            Function::Sum => a.iter().sum(),
            Function::Avg => a.iter().sum::<f64>() / a.len() as f64,
            // Evaluated lazily by `Expr::eval`; here with all three known.
            Function::Iif => {
                if x != 0.0 {
                    a[1]
                } else {
                    a[2]
                }
            }
        }
    }
}

/// The unit suffixes a number may carry (SolidWorks' `10mm`, `2in`, `45deg`), with
/// the factor to document units (lengths mm, angles degrees).
const UNITS: &[(&str, f64)] = &[
    ("mm", 1.0),
    ("cm", 10.0),
    ("m", 1000.0),
    ("um", 0.001),
    ("µm", 0.001),
    ("in", 25.4),
    ("inch", 25.4),
    ("ft", 304.8),
    ("deg", 1.0),
    ("rad", 180.0 / std::f64::consts::PI),
];

/// `"target" = expression` parsed: the target (NFC), the expression's text and tree.
pub(crate) fn parse(text: &str) -> Result<(String, String, Expr), EquationCause> {
    if text.len() > MAX_EQUATION_LEN {
        return Err(EquationCause::TooLarge(EquationLimit::Length {
            bytes: text.len(),
        }));
    }
    let chars: Vec<char> = text.chars().collect();
    let mut p = Parser {
        chars: &chars,
        at: 0,
        nodes: 0,
        nesting: 0,
    };
    p.skip_space();
    if p.peek() != Some('"') {
        return Err(p.error(SyntaxProblem::NoTarget));
    }
    let target = p.name()?;
    p.skip_space();
    if p.peek() != Some('=') {
        return Err(p.error(SyntaxProblem::NoEquals));
    }
    p.at += 1;
    let start = p.at;
    let expr = p.expression()?;
    p.skip_space();
    if p.at < chars.len() {
        return Err(p.error(SyntaxProblem::NoOperator));
    }
    let expression: String = chars[start..].iter().collect::<String>().trim().to_string();
    Ok((target, expression, expr))
}

struct Parser<'a> {
    chars: &'a [char],
    at: usize,
    nodes: usize,
    nesting: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<char> {
        self.chars.get(self.at).copied()
    }

    fn skip_space(&mut self) {
        while self.peek().is_some_and(char::is_whitespace) {
            self.at += 1;
        }
    }

    fn error(&self, problem: SyntaxProblem) -> EquationCause {
        EquationCause::Syntax {
            column: self.at + 1,
            problem,
        }
    }

    /// Counts a node of the tree against [`MAX_NODES`].
    fn node(&mut self) -> Result<(), EquationCause> {
        self.nodes += 1;
        if self.nodes > MAX_NODES {
            return Err(EquationCause::TooLarge(EquationLimit::Nodes));
        }
        Ok(())
    }

    /// A name in double quotes (the quote is next), NFC and checked.
    fn name(&mut self) -> Result<String, EquationCause> {
        let open = self.at;
        self.at += 1;
        let start = self.at;
        while self.peek().is_some_and(|c| c != '"') {
            self.at += 1;
        }
        if self.peek().is_none() {
            self.at = open;
            return Err(self.error(SyntaxProblem::UnclosedName));
        }
        let raw: String = self.chars[start..self.at].iter().collect();
        self.at += 1;
        let name = raw.trim();
        if name.is_empty() {
            self.at = open;
            return Err(self.error(SyntaxProblem::EmptyName));
        }
        if name.len() > MAX_NAME_LEN {
            return Err(EquationCause::TooLarge(EquationLimit::Name {
                bytes: name.len(),
            }));
        }
        if let Err(c) = crate::diagnostics::checked_name(name) {
            self.at = open;
            return Err(self.error(SyntaxProblem::NameCharacter(c)));
        }
        Ok(super::nfc_name(name).into_owned())
    }

    /// `expression (comparison expression)?`: `iif`'s condition.
    fn condition(&mut self) -> Result<Expr, EquationCause> {
        let left = self.expression()?;
        self.skip_space();
        let next = |k: usize| self.chars.get(self.at + k).copied();
        let op = match (next(0), next(1)) {
            (Some('<'), Some('=')) => "<=",
            (Some('>'), Some('=')) => ">=",
            (Some('<'), Some('>')) => "<>",
            (Some('<'), _) => "<",
            (Some('>'), _) => ">",
            (Some('='), _) => "=",
            _ => return Ok(left),
        };
        self.at += op.len();
        self.node()?;
        let right = self.expression()?;
        Ok(Expr::Compare(op, Box::new(left), Box::new(right)))
    }

    /// `term (('+' | '-') term)*`.
    fn expression(&mut self) -> Result<Expr, EquationCause> {
        let mut left = self.term()?;
        loop {
            self.skip_space();
            match self.peek() {
                Some(op @ ('+' | '-')) => {
                    self.at += 1;
                    self.node()?;
                    let right = self.term()?;
                    left = Expr::Binary(op, Box::new(left), Box::new(right));
                }
                _ => return Ok(left),
            }
        }
    }

    /// `unary (('*' | '/') unary)*`.
    fn term(&mut self) -> Result<Expr, EquationCause> {
        let mut left = self.unary()?;
        loop {
            self.skip_space();
            match self.peek() {
                Some(op @ ('*' | '/')) => {
                    self.at += 1;
                    self.node()?;
                    let right = self.unary()?;
                    left = Expr::Binary(op, Box::new(left), Box::new(right));
                }
                _ => return Ok(left),
            }
        }
    }

    /// `('-' | '+')* power`: `-2^2` is `-(2^2)`.
    fn unary(&mut self) -> Result<Expr, EquationCause> {
        self.skip_space();
        match self.peek() {
            Some('-') => {
                self.at += 1;
                self.node()?;
                Ok(Expr::Neg(Box::new(self.unary()?)))
            }
            Some('+') => {
                self.at += 1;
                self.node()?;
                self.unary()
            }
            _ => self.power(),
        }
    }

    /// `atom ('^' unary)?`, right-associative.
    fn power(&mut self) -> Result<Expr, EquationCause> {
        let base = self.atom()?;
        self.skip_space();
        if self.peek() == Some('^') {
            self.at += 1;
            self.node()?;
            let exponent = self.unary()?;
            return Ok(Expr::Binary('^', Box::new(base), Box::new(exponent)));
        }
        Ok(base)
    }

    fn enter(&mut self) -> Result<(), EquationCause> {
        self.nesting += 1;
        if self.nesting > MAX_NESTING {
            return Err(EquationCause::TooLarge(EquationLimit::Nesting));
        }
        Ok(())
    }

    /// A number, a `"name"`, `pi`, `(expression)` or `function(arguments)`.
    fn atom(&mut self) -> Result<Expr, EquationCause> {
        self.skip_space();
        self.node()?;
        match self.peek() {
            Some('"') => Ok(Expr::Name(self.name()?)),
            Some('(') => {
                self.at += 1;
                self.enter()?;
                let e = self.expression()?;
                self.skip_space();
                if self.peek() != Some(')') {
                    return Err(self.error(SyntaxProblem::NoCloseParen));
                }
                self.at += 1;
                self.nesting -= 1;
                Ok(e)
            }
            Some(c) if c.is_ascii_digit() || c == '.' => self.number(),
            Some(c) if c.is_alphabetic() => self.call(),
            Some(_) => Err(self.error(SyntaxProblem::NoOperand)),
            None => Err(self.error(SyntaxProblem::EndsEarly)),
        }
    }

    fn number(&mut self) -> Result<Expr, EquationCause> {
        let start = self.at;
        while self.peek().is_some_and(|c| c.is_ascii_digit() || c == '.') {
            self.at += 1;
        }
        if matches!(self.peek(), Some('e' | 'E')) {
            let mark = self.at;
            self.at += 1;
            if matches!(self.peek(), Some('+' | '-')) {
                self.at += 1;
            }
            if self.peek().is_some_and(|c| c.is_ascii_digit()) {
                while self.peek().is_some_and(|c| c.is_ascii_digit()) {
                    self.at += 1;
                }
            } else {
                self.at = mark;
            }
        }
        let text: String = self.chars[start..self.at].iter().collect();
        let v: f64 = text.parse().map_err(|_| EquationCause::Syntax {
            column: start + 1,
            problem: SyntaxProblem::NotANumber { text: text.clone() },
        })?;
        // A unit suffix (`10mm`, `2in`, `45deg`): the value in document units.
        let mut v = v;
        if self.peek().is_some_and(char::is_alphabetic) {
            let unit_at = self.at;
            while self.peek().is_some_and(char::is_alphabetic) {
                self.at += 1;
            }
            let unit: String = self.chars[unit_at..self.at].iter().collect();
            let Some(&(_, factor)) = UNITS.iter().find(|u| u.0 == unit.to_lowercase()) else {
                self.at = unit_at;
                return Err(self.error(SyntaxProblem::UnknownUnit { unit }));
            };
            v *= factor;
        }
        if !v.is_finite() {
            return Err(EquationCause::NonFinite(NonFiniteAt::Number { text }));
        }
        Ok(Expr::Number(v))
    }

    /// `pi` or a function call.
    fn call(&mut self) -> Result<Expr, EquationCause> {
        let start = self.at;
        while self.peek().is_some_and(|c| c.is_alphanumeric() || c == '_') {
            self.at += 1;
        }
        let word: String = self.chars[start..self.at].iter().collect();
        let lower = word.to_lowercase();
        if lower == "pi" {
            return Ok(Expr::Number(std::f64::consts::PI));
        }
        let Some(&(_, f, least, most)) = FUNCTIONS.iter().find(|f| f.0 == lower) else {
            self.at = start;
            return Err(self.error(SyntaxProblem::UnknownFunction { word }));
        };
        self.skip_space();
        if self.peek() != Some('(') {
            return Err(self.error(SyntaxProblem::NoOpenParen { function: word }));
        }
        self.at += 1;
        self.enter()?;
        let arguments = |function| SyntaxProblem::Arguments {
            function,
            least,
            most,
        };
        self.skip_space();
        if self.peek() == Some(')') {
            return Err(self.error(arguments(word)));
        }
        let mut args = Vec::with_capacity(least);
        loop {
            // The condition of `iif` may compare (`"D1@a" > 20`).
            args.push(if f == Function::Iif && args.is_empty() {
                self.condition()?
            } else {
                self.expression()?
            });
            self.skip_space();
            match self.peek() {
                Some(',') if args.len() < most => self.at += 1,
                Some(')') if args.len() >= least => break,
                _ => return Err(self.error(arguments(word))),
            }
        }
        self.at += 1;
        self.nesting -= 1;
        Ok(Expr::Call(f, args))
    }
}

impl Expr {
    /// The names it uses, each once, in order of appearance.
    pub(crate) fn names(&self, out: &mut Vec<String>) {
        match self {
            Expr::Number(_) => {}
            Expr::Name(n) => {
                if !out.contains(n) {
                    out.push(n.clone());
                }
            }
            Expr::Neg(e) => e.names(out),
            Expr::Binary(_, a, b) | Expr::Compare(_, a, b) => {
                a.names(out);
                b.names(out);
            }
            Expr::Call(_, args) => args.iter().for_each(|a| a.names(out)),
        }
    }

    /// Its value with `value` giving each name's (every name is known: checked
    /// before). The depth is bounded by [`MAX_NODES`].
    pub(crate) fn eval(&self, value: &dyn Fn(&str) -> f64) -> Result<f64, EquationCause> {
        let v = match self {
            Expr::Number(v) => *v,
            Expr::Name(n) => value(n),
            Expr::Neg(e) => -e.eval(value)?,
            Expr::Binary(op, a, b) => {
                let (a, b) = (a.eval(value)?, b.eval(value)?);
                match op {
                    '+' => a + b,
                    '-' => a - b,
                    '*' => a * b,
                    '/' if b == 0.0 => return Err(EquationCause::DivisionByZero),
                    '/' => a / b,
                    _ => a.powf(b),
                }
            }
            Expr::Compare(op, a, b) => {
                let (a, b) = (a.eval(value)?, b.eval(value)?);
                let holds = match *op {
                    "<" => a < b,
                    ">" => a > b,
                    "<=" => a <= b,
                    ">=" => a >= b,
                    "<>" => a != b,
                    _ => a == b,
                };
                f64::from(u8::from(holds))
            }
            Expr::Call(Function::Iif, args) => {
                // Only the branch taken: `iif("x" > 0, 1 / "x", 0)` is defined at 0.
                if args[0].eval(value)? != 0.0 {
                    args[1].eval(value)?
                } else {
                    args[2].eval(value)?
                }
            }
            Expr::Call(f, args) => {
                let mut a = Vec::with_capacity(args.len());
                for e in args {
                    a.push(e.eval(value)?);
                }
                let v = f.apply(&a);
                if !v.is_finite() {
                    return Err(EquationCause::NonFinite(NonFiniteAt::Call {
                        function: f.name(),
                        arguments: a,
                    }));
                }
                v
            }
        };
        if !v.is_finite() {
            return Err(EquationCause::NonFinite(match self {
                Expr::Binary(op, ..) => NonFiniteAt::Operator(*op),
                _ => NonFiniteAt::Value,
            }));
        }
        Ok(v)
    }
}

/// The equations' text shortened for messages.
pub(crate) fn shown(text: &str) -> String {
    let mut out: String = text.chars().take(80).collect();
    if out.len() < text.len() {
        out.push('…');
    }
    crate::diagnostics::printable(&out, false).into_owned()
}

/// The order to evaluate `equations` in (each after the equations setting the names
/// it uses), or the first circle found. `sets`: name → index of the equation setting
/// it. Iterative (Kahn's algorithm): no recursion however long the chain.
pub(crate) fn order(
    equations: &[Equation],
    sets: &HashMap<&str, usize>,
) -> Result<Vec<usize>, EquationError> {
    let n = equations.len();
    let mut uses: Vec<Vec<usize>> = Vec::with_capacity(n);
    let mut used_by: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, e) in equations.iter().enumerate() {
        let mut names = Vec::new();
        e.expr.names(&mut names);
        let deps: Vec<usize> = names
            .iter()
            .filter_map(|m| sets.get(m.as_str()).copied())
            .collect();
        for &d in &deps {
            used_by[d].push(i);
        }
        uses.push(deps);
    }
    let mut waiting: Vec<usize> = uses.iter().map(Vec::len).collect();
    let mut ready: Vec<usize> = (0..n).rev().filter(|&i| waiting[i] == 0).collect();
    let mut out = Vec::with_capacity(n);
    while let Some(i) = ready.pop() {
        out.push(i);
        for &j in &used_by[i] {
            waiting[j] -= 1;
            if waiting[j] == 0 {
                ready.push(j);
            }
        }
    }
    if out.len() == n {
        return Ok(out);
    }
    // A circle: walk from the first equation left waiting along its waiting uses.
    let start = (0..n).find(|&i| waiting[i] > 0).unwrap_or(0);
    let mut path = vec![start];
    let mut seen = vec![usize::MAX; n];
    seen[start] = 0;
    let mut at = start;
    while let Some(&next) = uses[at].iter().find(|&&d| waiting[d] > 0) {
        if seen[next] != usize::MAX {
            let cycle: Vec<String> = path[seen[next]..]
                .iter()
                .chain(std::iter::once(&next))
                .map(|&k| equations[k].target.clone())
                .collect();
            return Err(EquationError {
                index: next,
                text: shown(&equations[next].text()),
                cause: EquationCause::Cycle(cycle),
            });
        }
        seen[next] = path.len();
        path.push(next);
        at = next;
    }
    Err(EquationError {
        index: start,
        text: shown(&equations[start].text()),
        cause: EquationCause::Cycle(vec![equations[start].target.clone()]),
    })
}

#[cfg(test)]
mod tests;
