//! The one steady-state criterion of the kinds that run to a steady flow.
//!
//! A monitored value (a flux) is fed after every check interval. It is steady when its relative change over one
//! interval falls below `tolerance`. With `drift` set, it is also steady once that change has stopped changing
//! (its own change below `tolerance`/100, relative): the transient is then gone and what remains is a constant
//! drift. With Ω₁ a slow secular drift exists even in periodic body-force runs (the rest population of fully
//! covered nodes keeps gaining mass from the fluid; measured 1e-11–2e-8 relative per step), which would
//! otherwise never let a tight tolerance be met. Without `drift` (plain fluid runs, where an approach that is
//! slow against the interval would trigger it early) only the first rule applies.
use serde::{Deserialize, Serialize};

/// The criterion and its memory of the last two values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Steadiness {
    /// Relative change per interval below which the value is steady.
    pub tolerance: f64,
    /// Also accept a constant drift (see the module documentation).
    pub drift: bool,
    last: Option<f64>,
    last_change: Option<f64>,
}

impl Steadiness {
    /// A criterion with nothing fed yet: steady once the relative change over an interval is below `tolerance`.
    pub fn new(tolerance: f64) -> Self {
        Self {
            tolerance,
            drift: false,
            last: None,
            last_change: None,
        }
    }

    /// The same criterion that also accepts a constant drift (see the module documentation).
    pub fn accepting_drift(self) -> Self {
        Self {
            drift: true,
            ..self
        }
    }

    /// Feed the value after one more interval; `Some(relative change over the interval)` once steady.
    pub fn update(&mut self, value: f64) -> Option<f64> {
        let mut out = None;
        if let Some(last) = self.last {
            let change = (value - last) / value;
            if change.abs() < self.tolerance {
                out = Some(change);
            } else if let Some(prev) = self.last_change {
                if self.drift && (change - prev).abs() < 0.01 * self.tolerance {
                    out = Some(change);
                }
            }
            self.last_change = Some(change);
        }
        self.last = Some(value);
        out
    }
}
