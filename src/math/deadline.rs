//! One time budget per call: the instant a planner, a sweep, a query or a search must
//! end by, read the same way everywhere.
//!
//! A call takes its limit in milliseconds (`time_limit_ms`) or as a [`Duration`],
//! makes one [`Deadline`] when it starts and hands it down; every loop asks
//! [`Deadline::passed`] between pieces of work, and a piece whose cost can be
//! predicted is not started when it cannot end in time ([`Deadline::fits`]).

use std::time::{Duration, Instant};

/// The longest budget a deadline holds (2³⁰ s, about 34 years): a longer limit, or an
/// infinite one, is this (an [`Instant`] cannot hold every duration).
pub const MAX_BUDGET: Duration = Duration::from_secs(1 << 30);

/// The instant a call must end by.
///
/// # Examples
/// A search that works in pieces until its 50 ms are spent, and does not start a
/// piece it could not finish:
/// ```
/// use fitup::math::Deadline;
/// use std::time::Duration;
///
/// let deadline = Deadline::after_ms(50.0);
/// let mut pieces = 0;
/// while !deadline.passed() && deadline.fits(Duration::from_millis(1)) {
///     std::thread::sleep(Duration::from_millis(1)); // one piece of work
///     pieces += 1;
/// }
/// assert!(pieces > 0 && deadline.remaining() < Duration::from_millis(2));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Deadline(Instant);

impl Deadline {
    /// The deadline at `instant`.
    pub fn at(instant: Instant) -> Self {
        Self(instant)
    }

    /// `budget` from now (at most [`MAX_BUDGET`]).
    pub fn after(budget: Duration) -> Self {
        Self::from_start(Instant::now(), budget)
    }

    /// `budget` after `start` (at most [`MAX_BUDGET`]).
    pub fn from_start(start: Instant, budget: Duration) -> Self {
        Self(start + budget.min(MAX_BUDGET))
    }

    /// `ms` milliseconds from now: see [`budget_ms`] for what a value out of range
    /// gives.
    pub fn after_ms(ms: f64) -> Self {
        Self::after(budget_ms(ms))
    }

    /// `share` (0..=1) of a limit of `limit_ms` milliseconds after `start`: the part
    /// of a call's budget one phase may use (the rest is kept for what is in flight
    /// and for building the answer).
    pub fn share_of_ms(start: Instant, limit_ms: f64, share: f64) -> Self {
        Self::from_start(start, budget_ms(limit_ms * share.clamp(0.0, 1.0)))
    }

    /// The instant itself (for an API that takes an [`Instant`]).
    pub fn instant(self) -> Instant {
        self.0
    }

    /// Whether the deadline has come.
    pub fn passed(self) -> bool {
        Instant::now() >= self.0
    }

    /// The time left (zero once it has passed).
    pub fn remaining(self) -> Duration {
        self.0.saturating_duration_since(Instant::now())
    }

    /// Whether work taking `work` from now ends by the deadline.
    pub fn fits(self, work: Duration) -> bool {
        work <= self.remaining()
    }

    /// The earlier of two deadlines.
    pub fn min(self, other: Deadline) -> Deadline {
        Self(self.0.min(other.0))
    }
}

/// A limit in milliseconds as a [`Duration`]: a NaN, zero or negative limit is none at
/// all (zero), an infinite or huge one [`MAX_BUDGET`].
pub fn budget_ms(ms: f64) -> Duration {
    if ms.is_nan() || ms <= 0.0 {
        Duration::ZERO
    } else if ms / 1e3 >= MAX_BUDGET.as_secs_f64() {
        MAX_BUDGET
    } else {
        Duration::from_secs_f64(ms / 1e3)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn milliseconds_out_of_range_are_clamped_not_a_panic() {
        assert_eq!(budget_ms(f64::NAN), Duration::ZERO);
        assert_eq!(budget_ms(-5.0), Duration::ZERO);
        assert_eq!(budget_ms(f64::INFINITY), MAX_BUDGET);
        assert_eq!(budget_ms(1e300), MAX_BUDGET);
        assert_eq!(budget_ms(1500.0), Duration::from_millis(1500));
        // a deadline from any of them can be made and read
        for ms in [f64::NAN, -1.0, 0.0, 1e300, f64::INFINITY] {
            let d = Deadline::after_ms(ms);
            assert_eq!(d.passed(), d.remaining().is_zero());
        }
    }

    #[test]
    fn a_share_of_the_limit_ends_before_the_whole() {
        let start = Instant::now();
        let whole = Deadline::share_of_ms(start, 30_000.0, 1.0);
        let most = Deadline::share_of_ms(start, 30_000.0, 0.9);
        assert_eq!(whole.instant() - start, Duration::from_secs(30));
        assert_eq!(most.instant() - start, Duration::from_secs(27));
        assert_eq!(whole.min(most), most);
        assert!(!whole.passed() && whole.fits(Duration::from_secs(20)));
        assert!(!whole.fits(Duration::from_secs(31)));
        let past = Deadline::at(start);
        assert!(
            past.passed() && past.remaining().is_zero() && !past.fits(Duration::from_millis(1))
        );
    }
}
