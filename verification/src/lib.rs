//! # lbdem-verification
//!
//! Property tests (in `tests/`, with proptest) and proof harnesses for the kernels' index arithmetic.
//!
//! Every proof harness body is written once, generic over a [`Chooser`]: under `cargo kani` the chooser is
//! `kani::any()` + `kani::assume` (a proof for every value in the stated ranges); under `cargo test` it is an
//! odometer ([`for_all`]) that enumerates every combination of the bounded ranges the body asks for, so over
//! that finite domain the test is itself an exhaustive proof. See `harness` for the bodies.
//!
//! Each harness states its bound, what the bounded-exhaustive run enumerates (the whole bounded domain, or a
//! table of values standing for a domain too large to enumerate, e.g. [`Chooser::float_from`]), and its Kani
//! side (or why it has none).
pub mod harness;

/// Number of proptest cases for a property whose usual count is `default`: `default`, unless the environment
/// variable `LBDEM_PROPTEST_CASES` holds a positive number, which then replaces it for this run (the
/// mutation-testing command sets it low to keep each mutant cheap; a soak run can set it high). The new
/// property files use it; proptest's own `PROPTEST_CASES` only reaches configs built from
/// `ProptestConfig::default()`.
pub fn proptest_cases(default: u32) -> u32 {
    match std::env::var("LBDEM_PROPTEST_CASES")
        .ok()
        .and_then(|v| v.trim().parse::<u32>().ok())
    {
        Some(n) if n > 0 => n,
        _ => default,
    }
}

/// Source of nondeterministic choices for a proof harness body.
pub trait Chooser {
    /// A value in `lo..=hi`.
    fn usize_in(&mut self, lo: usize, hi: usize) -> usize;
    /// A boolean.
    fn boolean(&mut self) -> bool {
        self.usize_in(0, 1) == 1
    }
    /// A float. Under the bounded-exhaustive odometer, each entry of `table` in turn (so the test covers the
    /// table, not every `f64`); under Kani, any `f64` at all (the table is then only a sample of the domain
    /// the proof covers).
    fn float_from(&mut self, table: &[f64]) -> f64 {
        table[self.usize_in(0, table.len() - 1)]
    }
}

/// Interesting `f64` values a harness can pick by index: zero, ±tiny, subnormal, ±1, large, ±inf, NaN.
pub const INTERESTING_F64: [f64; 10] = [
    0.0,
    1e-300,
    -1e-300,
    5e-324,
    1.0,
    -1.0,
    1e300,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NAN,
];

/// Bounded-exhaustive enumeration: runs `body` once for every sequence of choices it can make. Choices may
/// depend on earlier ones (the odometer records each range as it is asked for). Returns the number of runs.
pub fn for_all(mut body: impl FnMut(&mut dyn Chooser)) -> u64 {
    struct Odometer {
        digits: Vec<(usize, usize)>,
        pos: usize,
    }
    impl Chooser for Odometer {
        fn usize_in(&mut self, lo: usize, hi: usize) -> usize {
            assert!(lo <= hi, "empty range {lo}..={hi}");
            let v = if self.pos < self.digits.len() {
                self.digits[self.pos].0
            } else {
                self.digits.push((lo, hi));
                lo
            };
            self.pos += 1;
            v
        }
    }
    let mut odo = Odometer {
        digits: Vec::new(),
        pos: 0,
    };
    let mut runs = 0u64;
    loop {
        odo.pos = 0;
        body(&mut odo);
        runs += 1;
        odo.digits.truncate(odo.pos);
        // Advance: drop exhausted trailing digits, increment the last one that can move.
        loop {
            match odo.digits.last_mut() {
                None => return runs,
                Some((v, hi)) if *v < *hi => {
                    *v += 1;
                    break;
                }
                Some(_) => {
                    odo.digits.pop();
                }
            }
        }
    }
}

/// The Kani chooser: every value allowed by the assumptions.
#[cfg(kani)]
pub struct KaniChooser;

#[cfg(kani)]
impl Chooser for KaniChooser {
    fn usize_in(&mut self, lo: usize, hi: usize) -> usize {
        let v: usize = kani::any();
        kani::assume(v >= lo && v <= hi);
        v
    }
    fn float_from(&mut self, _table: &[f64]) -> f64 {
        kani::any()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn odometer_enumerates_every_combination_once() {
        let mut seen = std::collections::BTreeSet::new();
        let runs = for_all(|c| {
            let a = c.usize_in(0, 2);
            let b = c.usize_in(a, 3); // a range that depends on the first choice
            assert!(seen.insert((a, b)), "combination repeated");
        });
        // (0,0..3) 4 + (1,1..3) 3 + (2,2..3) 2 = 9
        assert_eq!(runs, 9);
        assert_eq!(seen.len(), 9);
    }
}
