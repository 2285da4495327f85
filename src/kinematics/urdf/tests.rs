use super::*;

/// A two-link URDF with `joint` as the joint's inner elements and `visual` as the
/// child link's content; the joint is on line 3, the visual on line 4.
fn urdf(kind: &str, joint: &str, visual: &str) -> String {
    format!(
        "<robot name=\"r\">\n<link name=\"a\"/>\n<joint name=\"j\" type=\"{kind}\"><parent link=\"a\"/><child link=\"b\"/>{joint}</joint>\n<link name=\"b\">{visual}</link>\n</robot>"
    )
}

fn refused(text: &str) -> SourceError {
    parse_urdf(Path::new("r.urdf"), text, None).unwrap_err()
}

/// Every number read is finite and, after m → mm, within the document's range; the
/// error names the file, the attribute's line and column.
#[test]
fn numbers_out_of_the_document_range_are_refused_at_their_attribute() {
    let axis = "<axis xyz=\"0 0 1\"/>";
    let cases = [
        ("revolute", format!("<origin xyz=\"1e200 0 0\"/>{axis}"), "", "xyz", 3),
        // 1e7 m is 1e10 mm: finite, but beyond 1e9 mm.
        ("revolute", format!("<origin xyz=\"0 1e7 0\"/>{axis}"), "", "xyz", 3),
        ("revolute", format!("<origin rpy=\"0 0 1e300\"/>{axis}"), "", "rpy", 3),
        ("revolute", "<axis xyz=\"0 0 1e300\"/>".to_string(), "", "xyz", 3),
        ("revolute", format!("{axis}<limit lower=\"-1e300\" upper=\"1\"/>"), "", "lower", 3),
        ("prismatic", format!("{axis}<limit lower=\"0\" upper=\"1e7\"/>"), "", "upper", 3),
        ("revolute", format!("{axis}<origin xyz=\"0 0 0 0\"/>"), "", "xyz", 3),
        (
            "revolute",
            axis.to_string(),
            "<visual><geometry><mesh filename=\"m.stl\" scale=\"1e306 1 1\"/></geometry></visual>",
            "scale",
            4,
        ),
        (
            "revolute",
            axis.to_string(),
            "<visual><origin xyz=\"1e200 0 0\"/><geometry><mesh filename=\"m.stl\"/></geometry></visual>",
            "xyz",
            4,
        ),
        (
            "revolute",
            axis.to_string(),
            "<visual><geometry><mesh filename=\"m.stl\" scale=\"1 0 1\"/></geometry></visual>",
            "flat",
            4,
        ),
        (
            "revolute",
            axis.to_string(),
            "<visual><geometry><mesh filename=\"m.stl\" scale=\"1 x 1\"/></geometry></visual>",
            "scale",
            4,
        ),
    ];
    for (kind, joint, visual, needle, line) in cases {
        let text = urdf(kind, &joint, visual);
        let e = refused(&text);
        let shown = e.to_string();
        assert_eq!(e.line, Some(line), "{shown}");
        assert!(
            shown.contains("r.urdf") && shown.contains(needle),
            "{shown}"
        );
        // The column is the attribute's value, not the element's start.
        let row = text.lines().nth(line - 1).unwrap();
        let col = e.column.unwrap();
        assert!(col > row.find('<').unwrap() + 1, "{shown}");
    }
    // In range: 1000 km (1e6 m = 1e9 mm) loads.
    let ok = urdf(
        "revolute",
        "<origin xyz=\"1e6 0 0\"/><axis xyz=\"0 0 1\"/>",
        "",
    );
    assert!(parse_urdf(Path::new("r.urdf"), &ok, None).is_ok());
}

#[test]
fn a_huge_attribute_is_quoted_short() {
    let big = format!(
        "<origin xyz=\"{} 0 0\"/><axis xyz=\"0 0 1\"/>",
        "9".repeat(1 << 20)
    );
    let e = refused(&urdf("revolute", &big, ""));
    assert!(e.message.len() < 300, "{}", e.message.len());
}
