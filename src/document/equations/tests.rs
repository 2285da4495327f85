use super::*;

fn value(text: &str) -> Result<f64, EquationCause> {
    let (_, _, e) = parse(text)?;
    e.eval(&|n| if n == "x" { 3.0 } else { 0.0 })
}

#[test]
fn arithmetic_follows_the_usual_precedence() {
    assert_eq!(value("\"a\" = 1 + 2 * 3").unwrap(), 7.0);
    assert_eq!(value("\"a\" = (1 + 2) * 3").unwrap(), 9.0);
    assert_eq!(value("\"a\" = -2^2").unwrap(), -4.0);
    assert_eq!(value("\"a\" = 2^3^2").unwrap(), 512.0);
    assert_eq!(value("\"a\" = 10 - 4 - 3").unwrap(), 3.0);
    assert_eq!(value("\"a\" = 12 / 4 / 3").unwrap(), 1.0);
    assert_eq!(value("\"a\" = 2 * \"x\" + 1e1").unwrap(), 16.0);
    assert_eq!(value("\"a\" = max(1, min(\"x\", 2))").unwrap(), 2.0);
    assert!((value("\"a\" = sin(30) + cos(60)").unwrap() - 1.0).abs() < 1e-12);
    assert!((value("\"a\" = atn(1)").unwrap() - 45.0).abs() < 1e-12);
    assert!((value("\"a\" = 2 * PI").unwrap() - std::f64::consts::TAU).abs() < 1e-15);
}

#[test]
fn syntax_problems_read_as_their_words() {
    let cases: &[(&str, &str)] = &[
            ("a = 1", "an equation starts with the name it sets in double quotes: `\"Factor\" = 2`, `\"D1@lift\" = 10 * \"Factor\"`"),
            ("\"a\" 1", "expected `=` after the name"),
            ("\"a\" = 1 2", "expected an operator (`+ - * / ^`) or the end"),
            ("\"a = 1", "a name's closing `\"` is missing"),
            ("\" \" = 1", "an empty name `\"\"`"),
            ("\"a\u{200B}b\" = 1", "U+200B (ZERO WIDTH SPACE) is not allowed in names"),
            ("\"a\" = (1 + 2", "expected `)`"),
            ("\"a\" = )", "expected a number, a \"name\", a function or `(`"),
            ("\"a\" = 2 *", "the expression ends too early"),
            ("\"a\" = 2furlong", "unknown unit `furlong` ("),
            ("\"a\" = cube(4)", "unknown function `cube` ("),
            ("\"a\" = sqr 4", "expected `(` after `sqr`"),
            ("\"a\" = sqr()", "`sqr` takes 1 argument"),
            ("\"a\" = sqr(1, 2)", "`sqr` takes 1 argument"),
            ("\"a\" = max()", "`max` takes 2 or more arguments"),
            ("\"a\" = iif(1, 2)", "`iif` takes 3 arguments"),
        ];
    for (text, words) in cases {
        let e = value(text).unwrap_err();
        assert!(matches!(e, EquationCause::Syntax { .. }), "{text}: {e:?}");
        let shown = e.to_string();
        assert!(shown.starts_with("syntax at column "), "{text}: {shown}");
        assert!(shown.contains(&format!(": {words}")), "{text}: {shown}");
    }
    let e = value("\"a\" = 2furlong").unwrap_err().to_string();
    assert!(
        e.ends_with("); values are in document units: lengths mm, angles degrees"),
        "{e}"
    );
    let e = value("\"a\" = cube(4)").unwrap_err().to_string();
    assert!(e.ends_with("); names are written in double quotes"), "{e}");
}

#[test]
fn errors_name_their_cause_and_column() {
    assert_eq!(
        value("\"a\" = 1 / (\"x\" - 3)"),
        Err(EquationCause::DivisionByZero)
    );
    assert!(
        matches!(value("\"a\" = sqr(-1)"), Err(EquationCause::NonFinite(NonFiniteAt::Call { function: "sqr", arguments })) if arguments == [-1.0])
    );
    assert_eq!(
        value("\"a\" = sqr(-1)").unwrap_err().to_string(),
        "sqr(-1) is not a finite number"
    );
    assert_eq!(
        value("\"a\" = 1e300 * 1e300").unwrap_err().to_string(),
        "the result of `*` is not a finite number"
    );
    assert_eq!(
        value("\"a\" = 1e999").unwrap_err().to_string(),
        "`1e999` is not a finite number"
    );
    assert!(matches!(
        value("\"a\" = log(0)"),
        Err(EquationCause::NonFinite(_))
    ));
    assert!(matches!(
        value("\"a\" = 1e300 * 1e300"),
        Err(EquationCause::NonFinite(_))
    ));
    assert!(matches!(
        value("\"a\" = 1 +"),
        Err(EquationCause::Syntax { column: 10, .. })
    ));
    assert!(matches!(
        value("a = 1"),
        Err(EquationCause::Syntax { column: 1, .. })
    ));
    assert!(matches!(
        value("\"a\" = 10mmm"),
        Err(EquationCause::Syntax { column: 9, .. })
    ));
    assert!(matches!(
        value("\"a\" = sine(1)"),
        Err(EquationCause::Syntax { column: 7, .. })
    ));
    assert!(matches!(
        value("\"a\" = min(1)"),
        Err(EquationCause::Syntax { .. })
    ));
}

/// Issue 37: SolidWorks' `iif`/`if`, `sum`, `avg`, `min`/`max` of many and unit
/// suffixes, in document units.
#[test]
fn solidworks_functions_and_unit_suffixes() {
    let v = |t: &str| value(&format!("\"a\" = {t}")).unwrap();
    assert_eq!(v("10mm"), 10.0);
    assert_eq!(v("2in"), 50.8);
    assert_eq!(v("1.5cm + 1m"), 1015.0);
    assert_eq!(v("2ft"), 609.6);
    assert_eq!(v("45deg"), 45.0);
    assert!((v("1rad") - 57.295_779_513_082_32).abs() < 1e-12);
    assert!((v("sin(pi / 6 * 1rad)") - 0.5).abs() < 1e-12);
    assert!((v("tan(45deg)") - 1.0).abs() < 1e-12);
    assert_eq!(v("1e1mm"), 10.0);
    assert_eq!(v("sum(1, 2, \"x\")"), 6.0);
    assert_eq!(v("sum(4)"), 4.0);
    assert_eq!(v("avg(1, 2, 6)"), 3.0);
    assert_eq!(v("min(5, \"x\", 4)"), 3.0);
    assert_eq!(v("max(1, 7, \"x\", 2)"), 7.0);
    assert_eq!(v("abs(-2) + sqr(16)"), 6.0);
    assert_eq!(v("iif(\"x\" > 2, 10mm, 5mm)"), 10.0);
    assert_eq!(v("IIF(\"x\" < 2, 10, 5)"), 5.0);
    assert_eq!(v("if(\"x\" = 3, 1, 0)"), 1.0);
    assert_eq!(v("if(\"x\" <> 3, 1, 0)"), 0.0);
    assert_eq!(v("if(\"x\" >= 3, 1, 0) + if(\"x\" <= 2, 1, 0)"), 1.0);
    assert_eq!(v("if(\"x\" - 3, 1, 2)"), 2.0);
    // Only the branch taken is evaluated.
    assert_eq!(v("iif(\"x\" > 5, 1 / 0, 2)"), 2.0);
    let cause = value("\"a\" = 2inch + 1yd").unwrap_err();
    assert!(
        matches!(&cause, EquationCause::Syntax { column: 16, problem: SyntaxProblem::UnknownUnit { unit, .. } } if unit == "yd"),
        "{cause}"
    );
    assert!(matches!(
        value("\"a\" = iif(1, 2)"),
        Err(EquationCause::Syntax { .. })
    ));
    let e = value("\"a\" = sum()").unwrap_err();
    assert!(e.to_string().contains("1 or more"), "{e}");
    // A comparison only in a condition.
    assert!(matches!(
        value("\"a\" = 1 < 2"),
        Err(EquationCause::Syntax { .. })
    ));
}

#[test]
fn hostile_expressions_are_bounded() {
    let deep = format!("\"a\" = {}1{}", "(".repeat(100), ")".repeat(100));
    assert!(matches!(value(&deep), Err(EquationCause::TooLarge(_))));
    let long = format!("\"a\" = {}1", "1+".repeat(300));
    assert!(matches!(value(&long), Err(EquationCause::TooLarge(_))));
    let neg = format!("\"a\" = {}1", "-".repeat(400));
    assert!(matches!(value(&neg), Err(EquationCause::TooLarge(_))));
    let huge = format!("\"a\" = {}", "1".repeat(2000));
    assert!(matches!(value(&huge), Err(EquationCause::TooLarge(_))));
}
