//! `[run] checkpoint_interval`: how often a run writes its checkpoint.
use serde::{Deserialize, Serialize};

/// How often a long run writes its checkpoint (scene key `[run] checkpoint_interval`): an integer is a number
/// of steps, a string a wall-clock duration (`"90 s"`, `"10 min"`, `"2 h"`), `"never"` (or 0) only at the end
/// and on interrupt. Default: every 10 minutes of wall-clock time.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "IntervalRepr", into = "IntervalRepr")]
pub enum CheckpointInterval {
    /// Every this many steps.
    Steps(u64),
    /// Every this many wall-clock seconds.
    WallSeconds(f64),
    /// Only at the end and on interrupt or divergence.
    Never,
}

impl Default for CheckpointInterval {
    fn default() -> Self {
        CheckpointInterval::WallSeconds(600.0)
    }
}

#[derive(Clone, Serialize, Deserialize)]
#[serde(untagged)]
enum IntervalRepr {
    Steps(u64),
    Text(String),
}

impl TryFrom<IntervalRepr> for CheckpointInterval {
    type Error = String;
    fn try_from(r: IntervalRepr) -> std::result::Result<Self, String> {
        match r {
            IntervalRepr::Steps(0) => Ok(CheckpointInterval::Never),
            IntervalRepr::Steps(n) => Ok(CheckpointInterval::Steps(n)),
            IntervalRepr::Text(t) => CheckpointInterval::parse(&t),
        }
    }
}

impl From<CheckpointInterval> for IntervalRepr {
    fn from(c: CheckpointInterval) -> Self {
        match c {
            CheckpointInterval::Steps(n) => IntervalRepr::Steps(n),
            CheckpointInterval::WallSeconds(s) => IntervalRepr::Text(format!("{s} s")),
            CheckpointInterval::Never => IntervalRepr::Text("never".into()),
        }
    }
}

/// Longest wall-clock checkpoint interval accepted: about a century (3.2e9 s).
pub const MAX_INTERVAL_SECONDS: f64 = 3.2e9;

impl CheckpointInterval {
    /// Parse `"never"`, `"<n> steps"`, or a duration `"<x> s|min|h"`.
    pub fn parse(text: &str) -> std::result::Result<Self, String> {
        let t = text.trim();
        if t == "never" {
            return Ok(CheckpointInterval::Never);
        }
        let split = t
            .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '+' || c == '-'))
            .unwrap_or(t.len());
        let (num, unit) = (t[..split].trim(), t[split..].trim());
        let bad = || {
            format!(
                "run.checkpoint_interval = {text:?} is not understood; use a step count (e.g. 5000), a wall-clock duration (\"90 s\", \"10 min\", \"2 h\") or \"never\""
            )
        };
        let x: f64 = num.parse().map_err(|_| bad())?;
        if !(x.is_finite() && x > 0.0) {
            return Err(bad());
        }
        let seconds = match unit {
            "s" | "sec" | "seconds" => x,
            "min" | "minutes" => 60.0 * x,
            "h" | "hours" => 3600.0 * x,
            "steps" | "step" if x.fract() == 0.0 => return Ok(CheckpointInterval::Steps(x as u64)),
            _ => return Err(bad()),
        };
        // Duration::from_secs_f64 panics above ~1.8e19 s: anything beyond a century is "never" in practice
        // and most likely a typo, so it is refused.
        if seconds > MAX_INTERVAL_SECONDS {
            return Err(format!(
                "run.checkpoint_interval = {text:?} is {seconds:e} s, above the limit of {MAX_INTERVAL_SECONDS:e} s; \
                 use \"never\" to checkpoint only at the end and on interrupt"
            ));
        }
        Ok(CheckpointInterval::WallSeconds(seconds))
    }
}
