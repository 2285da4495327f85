//! The limits every reader shares: a number beyond them is refused wherever it comes
//! from (document, STL, URDF, hole table, robot program), so no layer has its own idea
//! of "too large".

/// The largest magnitude of any number fitup reads (mm, degrees, …): far beyond any
/// real cell (1000 km), small enough that products and squares stay finite.
pub const MAX_ABS_VALUE: f64 = 1e9;

/// Whether `v` is a number fitup accepts: finite and at most [`MAX_ABS_VALUE`] in
/// magnitude (mm, degrees, or whatever unit the caller reads).
pub fn in_range(v: f64) -> bool {
    v.is_finite() && v.abs() <= MAX_ABS_VALUE
}
