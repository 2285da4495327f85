//! The shared limits of fitup: the range of every number it reads and the one cap on
//! how many poses or samples a single call may produce.
//!
//! Both are checked *before* anything is allocated: a producer that turns a step size
//! into a number of samples (densifying a path, following it, sweeping a part in
//! steps, sampling a robot motion or program, IK checks along a Cartesian move,
//! drilling) first computes the count from the length and the step with
//! [`SampleBudget::take_steps`], and a count beyond [`MAX_SAMPLES`] is a
//! [`LimitError::TooMany`] naming the count, the cap and the argument that asked for
//! it, instead of gigabytes of allocation and an abort.

/// The largest magnitude of any number in a document (mm, degrees, …): far beyond any
/// real cell (1000 km), small enough that products and squares stay finite. URDF
/// numbers (after m → mm), STL coordinates, program and hole-table values share it.
pub const MAX_ABS_VALUE: f64 = 1e9;

/// The most poses or samples one call may produce or compute, counted over the whole
/// call (all edges of a path, all moves of a program, all holes of a drilling run).
///
/// 1,000,000 samples of a robot trajectory take ≈ 200 MB and are 14 hours of motion at
/// the default 0.05 s interval; a million poses of a densified path are 1 km at 1 mm.
pub const MAX_SAMPLES: usize = 1_000_000;

/// A step size that cannot be turned into a number of samples, or one that would give
/// more than [`MAX_SAMPLES`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LimitError {
    /// The step is not a finite number > 0.
    #[error("`{argument}` must be a finite number > 0, not {value}")]
    BadStep {
        /// The argument or option that gave the step (e.g. `step`, `interval`).
        argument: &'static str,
        /// Its value.
        value: f64,
    },
    /// The call would produce more than the cap.
    #[error("`{argument}` = {value} would make {count} {what} in this call, more than the cap of {cap} (fitup's limit on the poses/samples one call may produce); use a larger `{argument}`", count = Count(*count))]
    TooMany {
        /// The argument or option whose value asked for the count.
        argument: &'static str,
        /// Its value (mm, rad, s or a plain count, as the argument is written).
        value: f64,
        /// What is counted (`poses`, `samples`, `IK checks`, `steps`).
        what: &'static str,
        /// The count the call would reach (may be astronomically large or infinite).
        count: f64,
        /// The cap, [`MAX_SAMPLES`].
        cap: usize,
    },
}

/// Prints a count exactly while it fits, in scientific notation beyond.
struct Count(f64);

impl std::fmt::Display for Count {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.0.is_finite() && self.0 < 1e15 {
            write!(f, "{}", self.0 as u64)
        } else if self.0.is_finite() {
            write!(f, "{:.3e}", self.0)
        } else {
            f.write_str("infinitely many")
        }
    }
}

/// Refuses a step that is not a finite number > 0 (mm, rad, s).
pub fn check_step(argument: &'static str, value: f64) -> Result<f64, LimitError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(LimitError::BadStep { argument, value })
    }
}

/// The running count of what one call has produced, against [`MAX_SAMPLES`].
///
/// One budget travels through a whole call (a program's moves, a path's edges), so
/// the cap bounds the total, not each piece.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleBudget {
    used: usize,
    cap: usize,
    what: &'static str,
}

impl SampleBudget {
    /// A budget of [`MAX_SAMPLES`] for counting `what` (`poses`, `samples`, …).
    pub fn new(what: &'static str) -> Self {
        Self::with_cap(what, MAX_SAMPLES)
    }

    /// A budget with another cap (tests; a caller that must stay below the shared one).
    pub fn with_cap(what: &'static str, cap: usize) -> Self {
        Self { used: 0, cap, what }
    }

    /// How many were taken so far.
    pub fn used(&self) -> usize {
        self.used
    }

    /// Takes `count` more (a float, so that an absurd count is refused before any
    /// conversion or allocation); `argument = value` is what asked for them.
    pub fn take(
        &mut self,
        count: f64,
        argument: &'static str,
        value: f64,
    ) -> Result<usize, LimitError> {
        let total = self.used as f64 + count;
        // NaN counts fail both comparisons: refused like an infinite count.
        let fits = count >= 0.0 && total <= self.cap as f64;
        if !fits {
            return Err(LimitError::TooMany {
                argument,
                value,
                what: self.what,
                count: if count.is_nan() { f64::INFINITY } else { total },
                cap: self.cap,
            });
        }
        let n = count as usize;
        self.used += n;
        Ok(n)
    }

    /// The number of steps of at most `step` that cover `length` (at least 1), taken
    /// from the budget: the step is checked first ([`check_step`]), the count is
    /// computed before anything is allocated.
    pub fn take_steps(
        &mut self,
        length: f64,
        step: f64,
        argument: &'static str,
    ) -> Result<usize, LimitError> {
        check_step(argument, step)?;
        self.take(steps(length, step), argument, step)
    }
}

/// `⌈length / step⌉`, at least 1, as a float (infinite for an infinite length).
pub fn steps(length: f64, step: f64) -> f64 {
    (length.abs() / step).ceil().max(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_checked_and_counted_before_allocation() {
        let mut b = SampleBudget::new("poses");
        assert_eq!(b.take_steps(10.0, 1.0, "step").unwrap(), 10);
        assert_eq!(b.take_steps(0.0, 1.0, "step").unwrap(), 1);
        assert_eq!(b.used(), 11);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                b.take_steps(1.0, bad, "step"),
                Err(LimitError::BadStep {
                    argument: "step",
                    ..
                })
            ));
        }
        // 1 m at 1e-9 mm: 1e12 poses, refused with the count, the cap and the argument.
        let e = b.take_steps(1000.0, 1e-9, "step").unwrap_err();
        let LimitError::TooMany {
            argument,
            count,
            cap,
            ..
        } = &e
        else {
            panic!("{e}")
        };
        assert_eq!((*argument, *cap), ("step", MAX_SAMPLES));
        assert!(*count > 1e12 - 1.0);
        let text = e.to_string();
        assert!(
            text.contains("`step` = 0.000000001") && text.contains("1000000000011 poses"),
            "{text}"
        );
        assert!(text.contains("cap of 1000000"), "{text}");
        // A refused request takes nothing.
        assert_eq!(b.used(), 11);
    }

    #[test]
    fn the_cap_bounds_the_total_of_a_call() {
        let mut b = SampleBudget::with_cap("samples", 100);
        assert_eq!(b.take(60.0, "interval", 0.1).unwrap(), 60);
        let e = b.take(41.0, "interval", 0.1).unwrap_err();
        assert!(matches!(e, LimitError::TooMany { count, .. } if count == 101.0));
        assert_eq!(b.take(40.0, "interval", 0.1).unwrap(), 40);
        assert!(b.take(f64::INFINITY, "interval", 0.0).is_err());
        assert!(b.take(f64::NAN, "interval", 0.0).is_err());
        let e = SampleBudget::new("poses")
            .take(1e300, "step", 1e-300)
            .unwrap_err();
        assert!(e.to_string().contains("1.000e300 poses"), "{e}");
    }
}
