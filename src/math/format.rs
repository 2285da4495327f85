//! Numbers formatted for people: the one place that decides how fitup prints lengths,
//! angles and counts (CLI summaries, watch output, error messages, `fmt` in scripts).
//!
//! Rules: a fixed number of decimals with trailing zeros dropped (`12.5`, not
//! `12.500000`); rounding noise disappears (`29.999999999999996` → `30`,
//! `6.3e-15` → `0`); never `-0`; magnitudes of 10¹⁵ and more in scientific notation
//! (`1e308`, not 309 digits); `inf` and `NaN` spelled out.

/// Decimals used for lengths (mm) and angles (degrees) shown to people: 0.001 mm and
/// 0.001°.
pub const DEFAULT_DECIMALS: usize = 3;

/// The most decimals [`number`] prints (beyond, `f64` shows only noise).
pub const MAX_DECIMALS: usize = 15;

/// `x` rounded to `decimals` places (at most [`MAX_DECIMALS`]) without trailing zeros.
///
/// # Examples
///
/// ```
/// use fitup::math::format::number;
/// assert_eq!(number(29.999999999999996, 3), "30");
/// assert_eq!(number(-0.0001, 3), "0");
/// assert_eq!(number(12.5, 3), "12.5");
/// assert_eq!(number(1e308, 3), "1e308");
/// assert_eq!(number(f64::NAN, 3), "NaN");
/// ```
pub fn number(x: f64, decimals: usize) -> String {
    let decimals = decimals.min(MAX_DECIMALS);
    if x.is_nan() {
        return "NaN".into();
    }
    if x.is_infinite() {
        return if x > 0.0 { "inf" } else { "-inf" }.into();
    }
    if x.abs() >= 1e15 {
        // Scientific with up to `decimals` (at most 6) mantissa decimals, zeros dropped.
        let s = format!("{:.*e}", decimals.min(6), x);
        let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
        return format!("{}e{exponent}", trim_zeros(mantissa));
    }
    let s = trim_zeros(&format!("{x:.decimals$}"));
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

fn trim_zeros(s: &str) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s.to_string()
    }
}

/// A length in millimetres: `12.5 mm` (0.001 mm resolution).
pub fn length(mm: f64) -> String {
    format!("{} mm", number(mm, DEFAULT_DECIMALS))
}

/// An angle given in **degrees**: `30°` (0.001° resolution).
pub fn degrees(deg: f64) -> String {
    format!("{}°", number(deg, DEFAULT_DECIMALS))
}

/// An angle given in **radians**, shown in degrees: `30°`.
pub fn angle(rad: f64) -> String {
    degrees(rad.to_degrees())
}

/// A pose triple `X Y Z` (mm) and `A B C` (**degrees**):
/// `X 10 Y 0 Z 5 A 0° B 0° C 90°`.
pub fn xyzabc_deg(v: &[f64; 6]) -> String {
    format!(
        "X {} Y {} Z {} A {}° B {}° C {}°",
        number(v[0], DEFAULT_DECIMALS),
        number(v[1], DEFAULT_DECIMALS),
        number(v[2], DEFAULT_DECIMALS),
        number(v[3], DEFAULT_DECIMALS),
        number(v[4], DEFAULT_DECIMALS),
        number(v[5], DEFAULT_DECIMALS)
    )
}

/// A count with thousands separators: `50,000,000`.
pub fn count(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_lose_noise_not_meaning() {
        assert_eq!(number(29.999999999999996, 3), "30");
        assert_eq!(number(6.361109362927014e-15, 3), "0");
        assert_eq!(number(-0.0, 3), "0");
        assert_eq!(number(-0.0004, 3), "0");
        assert_eq!(number(-0.0006, 3), "-0.001");
        assert_eq!(number(0.1 + 0.2, 3), "0.3");
        assert_eq!(number(1.0 / 3.0, 6), "0.333333");
        assert_eq!(number(100.0, 3), "100");
        assert_eq!(number(-12.25, 1), "-12.2");
        assert_eq!(number(123456.0, 0), "123456");
        assert_eq!(number(1e308, 3), "1e308");
        assert_eq!(number(-1.5e20, 3), "-1.5e20");
        assert_eq!(number(f64::INFINITY, 3), "inf");
        assert_eq!(number(f64::NEG_INFINITY, 3), "-inf");
        assert_eq!(number(0.5, 99), "0.5");
        assert_eq!(length(12.5), "12.5 mm");
        assert_eq!(degrees(29.999999999999996), "30°");
        assert_eq!(angle(std::f64::consts::FRAC_PI_2), "90°");
        assert_eq!(
            xyzabc_deg(&[10.0, -0.0, 5.0000000001, 0.0, -1e-13, 90.0]),
            "X 10 Y 0 Z 5 A 0° B 0° C 90°"
        );
    }

    #[test]
    fn counts_are_grouped() {
        assert_eq!(count(0), "0");
        assert_eq!(count(999), "999");
        assert_eq!(count(1000), "1,000");
        assert_eq!(count(50_000_000), "50,000,000");
        assert_eq!(count(u64::MAX), "18,446,744,073,709,551,615");
    }
}
