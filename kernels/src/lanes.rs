//! Transcendental functions over a batch of lanes, bitwise equal to the `libm` crate's scalar functions.
//!
//! The coverage kernel ([`crate::coverage::ellipse_grid_fractions`]) takes one `atan2` per crossing of an
//! ellipse with a lattice line, a tenth of the full-size fracture step when called one at a time. Here the
//! `libm` algorithm (FreeBSD msun's `s_atan.c` / `e_atan2.c`, as ported by the `libm` crate 0.2) is written
//! once over `L` lanes, with its branches turned into selects between values computed by the same operations
//! in the same order, so that the compiler can vectorise the lane loop and every lane still gets the bits of
//! [`libm::atan2`]. The inputs the scalar function treats as special (NaN, infinities, zeros, x = 1 and
//! ratios |y/x| beyond 2^±62, a superset of its own special ranges) are recomputed by [`libm::atan2`] itself.

/// atan(0.5), atan(1), atan(1.5), atan(∞): high parts (`libm`'s `ATANHI`, given by their bits).
const ATANHI: [f64; 4] = [
    f64::from_bits(0x3fddac67_0561bb4f),
    f64::from_bits(0x3fe921fb_54442d18),
    f64::from_bits(0x3fef730b_d281f69b),
    f64::from_bits(0x3ff921fb_54442d18),
];

/// The low parts of the same (`libm`'s `ATANLO`).
const ATANLO: [f64; 4] = [
    f64::from_bits(0x3c7a2b7f_222f65e2),
    f64::from_bits(0x3c81a626_33145c07),
    f64::from_bits(0x3c700788_7af0cbbd),
    f64::from_bits(0x3c91a626_33145c07),
];

/// The odd polynomial of atan on [−7/16, 7/16] (`libm`'s `AT`).
const AT: [f64; 11] = [
    f64::from_bits(0x3fd55555_5555550d),
    f64::from_bits(0xbfc99999_9998ebc4),
    f64::from_bits(0x3fc24924_920083ff),
    f64::from_bits(0xbfbc71c6_fe231671),
    f64::from_bits(0x3fb745cd_c54c206e),
    f64::from_bits(0xbfb3b0f2_af749a6d),
    f64::from_bits(0x3fb10d66_a0d03d51),
    f64::from_bits(0xbfadde2d_52defd9a),
    f64::from_bits(0x3fa97b4b_24760deb),
    f64::from_bits(0xbfa2b444_2c6a6c2f),
    f64::from_bits(0x3f90ad3a_e322da11),
];

/// π rounded, and its remainder (`libm`'s `PI`, `PI_LO` in `atan2`).
const PI: f64 = f64::from_bits(0x400921fb_54442d18);
const PI_LO: f64 = f64::from_bits(0x3ca1a626_33145c07);

/// 2^62: ratios |y/x| beyond 2^62 or below 2^−62 go to the scalar function (it treats |y/x| > 2^64, and
/// |y/x| < 2^−64 with x < 0, specially; both lie inside these bounds).
const RATIO_LIMIT: f64 = 4_611_686_018_427_387_904.0;

/// `libm::atan2(y[l], x[l])` for every lane, bitwise.
///
/// For an ordinary lane (both finite and non-zero, x ≠ 1, 2^−62 ≤ |y/x| ≤ 2^62) this is `libm`'s path: z =
/// |y / x| (the same division: |y/x| and |y|/|x| are one correctly rounded quotient), atan(z) by the argument
/// reduction chosen from z's interval (the bounds 7/16, 11/16, 19/16 and 39/16 compared as values, which is
/// what `libm`'s comparisons of the high word do, every bound having a zero low word), the same two-part
/// polynomial, then the quadrant from the signs of x and y. The reduction's numerator and
/// denominator are selected before one division: each candidate is computed by `libm`'s own operations, and
/// the unreduced case divides z by 1, which is exact.
#[inline(always)]
pub(crate) fn atan2_f64<const L: usize>(y: &[f64; L], x: &[f64; L]) -> [f64; L] {
    let mut out = [0.0; L];
    let mut special = [false; L];
    for l in 0..L {
        let (yv, xv) = (y[l], x[l]);
        let (ay, ax) = (yv.abs(), xv.abs());
        // NaN fails every comparison, so a NaN lane is special too.
        let ordinary = ax < f64::INFINITY
            && ay < f64::INFINITY
            && ax > 0.0
            && ay > 0.0
            && xv != 1.0
            && ay <= ax * RATIO_LIMIT
            && ay * RATIO_LIMIT >= ax;
        special[l] = !ordinary;
        let z = ay / ax;
        // atan(z), z ≥ 0: the reduction of `libm::atan` for z's interval.
        let (num, den, hi, lo, reduced) = if z < 0.4375 {
            (z, 1.0, 0.0, 0.0, false)
        } else if z < 0.6875 {
            (2. * z - 1., 2. + z, ATANHI[0], ATANLO[0], true)
        } else if z < 1.1875 {
            (z - 1., z + 1., ATANHI[1], ATANLO[1], true)
        } else if z < 2.4375 {
            (z - 1.5, 1. + 1.5 * z, ATANHI[2], ATANLO[2], true)
        } else {
            (-1., z, ATANHI[3], ATANLO[3], true)
        };
        let t = num / den;
        let zz = t * t;
        let w = zz * zz;
        let s1 = zz * (AT[0] + w * (AT[2] + w * (AT[4] + w * (AT[6] + w * (AT[8] + w * AT[10])))));
        let s2 = w * (AT[1] + w * (AT[3] + w * (AT[5] + w * (AT[7] + w * AT[9]))));
        let r = if reduced {
            hi - (t * (s1 + s2) - lo - t)
        } else {
            t - t * (s1 + s2)
        };
        // (`libm` returns z itself for z < 2^−27: so does the formula, since there t (s1 + s2) < 2^−55 t is
        // below half an ulp of t.)
        out[l] = match (xv < 0.0, yv < 0.0) {
            (false, false) => r,
            (false, true) => -r,
            (true, false) => PI - (r - PI_LO),
            (true, true) => (r - PI_LO) - PI,
        };
    }
    // One test for the batch (a vector reduction), the lanes one by one only when one is special.
    if special.iter().fold(false, |any, &s| any | s) {
        for l in 0..L {
            if special[l] {
                out[l] = libm::atan2(y[l], x[l]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;
    use std::vec::Vec;

    /// A deterministic stream of bit patterns (xorshift64*).
    struct Bits(u64);
    impl Bits {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
        }
        /// A finite value with a random sign and an exponent in 2^(−e .. e).
        fn value(&mut self, e: i32) -> f64 {
            let m = 1.0 + (self.next() >> 11) as f64 / (1u64 << 53) as f64;
            let k = (self.next() % (2 * e as u64 + 1)) as i32 - e;
            let s = if self.next() & 1 == 0 { 1.0 } else { -1.0 };
            s * m * libm::exp2(k as f64)
        }
    }

    fn check<const L: usize>(y: [f64; L], x: [f64; L]) {
        let got = atan2_f64(&y, &x);
        for l in 0..L {
            let want = libm::atan2(y[l], x[l]);
            assert!(
                got[l].to_bits() == want.to_bits() || (got[l].is_nan() && want.is_nan()),
                "atan2({:e}, {:e}): lanes {:e}, libm {:e}",
                y[l],
                x[l],
                got[l],
                want
            );
        }
    }

    /// Random pairs over every quadrant, with the ratio spread from 2^−80 to 2^80 (both sides of the
    /// special-case bounds), against `libm::atan2`, bitwise.
    #[test]
    fn lanes_are_bitwise_libm_on_random_pairs() {
        let mut r = Bits(0x9e37_79b9_7f4a_7c15);
        for e in [2, 8, 40, 80, 600] {
            for _ in 0..20_000 {
                let y: [f64; 8] = core::array::from_fn(|_| r.value(e));
                let x: [f64; 8] = core::array::from_fn(|_| r.value(e));
                check(y, x);
            }
        }
        // Points near the unit circle, as the coverage kernel passes them.
        for _ in 0..100_000 {
            let y: [f64; 8] = core::array::from_fn(|_| r.value(1) * 0.7);
            let x: [f64; 8] = core::array::from_fn(|_| r.value(1) * 0.7);
            check(y, x);
        }
    }

    /// Ratios at and next to every bound of the reduction (7/16, 11/16, 19/16, 39/16, 2^−27) and of the
    /// special-case ranges (2^±62, 2^±64), with x a power of two so that y/x is the ratio exactly, in all four
    /// quadrants; and the special inputs themselves (zeros, infinities, NaN, x = 1, subnormals).
    #[test]
    fn lanes_are_bitwise_libm_at_the_bounds_and_special_inputs() {
        let bounds = [
            0.4375,
            0.6875,
            1.1875,
            2.4375,
            libm::exp2(-27.0),
            libm::exp2(62.0),
            libm::exp2(-62.0),
            libm::exp2(64.0),
            libm::exp2(-64.0),
            libm::exp2(66.0),
            1.0,
        ];
        let mut cases: Vec<(f64, f64)> = Vec::new();
        for b in bounds {
            let mut v = b;
            for _ in 0..4 {
                v = f64::from_bits(v.to_bits() - 1);
            }
            for _ in 0..9 {
                for xs in [0.5, 1.0, 2.0, 1024.0] {
                    for (sy, sx) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
                        cases.push((sy * v * xs, sx * xs));
                    }
                }
                v = f64::from_bits(v.to_bits() + 1);
            }
        }
        let specials = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            f64::MAX,
            1e-300,
            3.0,
        ];
        for &y in &specials {
            for &x in &specials {
                cases.push((y, x));
            }
        }
        for chunk in cases.chunks(8) {
            let y = core::array::from_fn(|l| chunk[l % chunk.len()].0);
            let x = core::array::from_fn(|l| chunk[l % chunk.len()].1);
            check::<8>(y, x);
        }
        // Other lane counts than the kernel's.
        check::<1>([0.3], [-0.2]);
        check::<3>([0.3, -1e-9, 2.0], [-0.2, 4.0, 1.0]);
    }
}
