//! Collision operators, node by node.
//!
//! * BGK (dissertation eq. 4.1): f_i ← f_i − ω (f_i − f_i^eq(ρ, u)), ω = 1/τ.
//! * Guo, Zheng & Shi (2002) forcing for a body-force density F (lattice units, force per node):
//!   u = (Σ f_i c_i + F/2)/ρ and the source S_i = (1 − ω/2) w_i [3 (c_i − u) + 9 (c_i·u) c_i]·F, which adds
//!   exactly F of momentum per step and no mass.
//! * Noble & Torczynski (1998) partially-saturated method, PSM (eq. 4.4–4.6):
//!   f_i ← f_i − (1 − B) ω (f_i − f_i^eq(ρ, u)) + Σ_s B_s Ω^S_{i,s} + (1 − B) S_i,
//!   Ω^S_{i,s} = f_ī − f_ī^eq(ρ, u) + f_i^eq(ρ, u_s) − f_i  (the "non-equilibrium bounce-back", Ω₁),
//!   with B the weighting of eq. 4.5, B(ε, τ) = ε(τ − ½)/((1 − ε) + (τ − ½)), or optionally B = ε.
//!   The solid operator Ω^S can be Ω₁ above (eq. 4.6, the dissertation's and the default), or the
//!   "superposition" operator Ω₂ of Holdych (2003) / Owen, Leonardi & Feng (2011, eq. 29):
//!   Ω^S_{i,s} = f_i^eq(ρ, u_s) − f_i + (1 − ω)(f_i − f_i^eq(ρ, u)). Both conserve mass and hand the solid
//!   the same momentum ρ(u − u_s) per unit B without forcing. They differ at fully covered nodes (B = 1): Ω₁
//!   never relaxes the rest population, which gains (2/3)ρu² every step wherever the pre-collision velocity
//!   inside a solid is non-zero, so in open systems (pressure boundaries) mass accumulates without bound inside
//!   solids; Ω₂ relaxes every population and stays bounded but lets fluid seep through solids. Ω₃ (Owen
//!   et al. 2011, eq. 33), Ω^S_{i,s} = f_ī − f_ī^eq(ρ, u_s) + f_i^eq(ρ, u_s) − f_i, is moving-wall bounce-back
//!   at B = 1: tight and bounded, with twice Ω₁'s momentum exchange per unit B. But with free grains Ω₃ is
//!   unstable: at B = 1 the fluid inside a grain leaves each collision with its velocity relative to the
//!   grain reversed, the grain takes the reaction, and the relative velocity w evolves as
//!   w ← −(1 + 2 m_f/m_s) w (m_f the covered fluid mass, m_s the grain's), which grows for any finite grain
//!   mass. Ω₁ sets w to 0 instead (w ← −(m_f/m_s) w). The linearised Ω₁ (`LinearizedNonEquilibriumBounceBack`),
//!   Ω^S_{i,s} = f_ī − f_i + 3 w_i ρ c_i·(u + u_s), keeps Ω₁'s momentum exchange and interior behaviour and
//!   drops only the even, O(Ma²) part of Ω₁'s equilibrium difference, which is what pumps mass into the rest
//!   population: it is the operator for moving grains with pressure boundaries.
//!   Several solids s may cover one node; their fractions add and are capped at 1 (ε = min(Σ ε_s, 1)), and the
//!   total weight B(ε) is shared in proportion to ε_s.
//!   The momentum each solid receives (eq. 4.7, in lattice units: impulse per step = force) is
//!   F_s = −B_s Σ_i Ω^S_{i,s} c_i, returned per share so the caller can reduce it to force and torque (eq. 4.8).
//!   By construction the fluid momentum change at the node is (1 − B) F − Σ_s F_s: momentum is exchanged, never
//!   created.
use super::d2q9::{density, equilibrium, momentum, velocity, weights, OPPOSITE, Q};
use crate::Real;

/// Which weighting function B(ε, τ) the partially-saturated collision uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Weighting {
    /// Noble & Torczynski's B(ε, τ) = ε(τ − ½)/((1 − ε) + (τ − ½)) (dissertation eq. 4.5). B(0)=0, B(1)=1.
    #[default]
    NobleTorczynski,
    /// B = ε.
    SolidFraction,
}

/// Which solid collision operator Ω^S the partially-saturated collision uses, named by the literature (the
/// Ω numbering of Owen, Leonardi & Feng 2011, Int. J. Numer. Meth. Eng. 87:66; [`SolidOperator::symbol`]).
///
/// Scene files name them by the same words, in snake case (serde): `"non_equilibrium_bounce_back"` (Ω₁),
/// `"superposition"` (Ω₂), `"moving_wall_bounce_back"` (Ω₃), `"linearized_non_equilibrium_bounce_back"` (Ω₁ₗ),
/// `"lambda_consistent"` (ΩΛ). The words of earlier scene files (`bounce_back`, which meant Ω₁, `moving_wall`,
/// `linearized`) are refused with an error naming the new word: `bounce_back` read as Ω₃, the kernel's
/// moving-wall bounce-back, would change a scene's physics without a word.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum SolidOperator {
    /// Ω₁, Noble & Torczynski's (1998) non-equilibrium bounce-back (dissertation eq. 4.6):
    /// f_ī − f_ī^eq(ρ, u) + f_i^eq(ρ, u_s) − f_i.
    #[default]
    NonEquilibriumBounceBack,
    /// Ω₂, the superposition operator of Holdych (2003) (Owen et al. 2011, eq. 29).
    Superposition,
    /// Ω₃ (Owen et al. 2011, eq. 33): f_ī − f_ī^eq(ρ, u_s) + f_i^eq(ρ, u_s) − f_i. At B = 1 this is the
    /// classic moving-wall bounce-back, f_i ← f_ī + 6 w_i ρ c_i·u_s: it never touches the rest population, so
    /// fully covered regions neither leak fluid (unlike Ω₂) nor accumulate mass (unlike Ω₁). Momentum handed
    /// over per unit B is 2ρ(u_s − u), twice Ω₁'s. Not for free grains: at B = 1 it reverses the velocity of
    /// the fluid inside a grain relative to the grain, and with the grain's reaction the coupled mode grows by
    /// 1 + 2 m_fluid/m_grain per step (see the module notes).
    MovingWallBounceBack,
    /// Ω₁ₗ, Ω₁ with the equilibrium difference linearised: f_ī − f_i + 3 w_i ρ c_i·(u + u_s). It is Ω₁ minus
    /// the part of f_i^eq(ρ, u_s) − f_ī^eq(ρ, u) that is even in c_i (second order in the Mach number), so it
    /// hands over exactly Ω₁'s momentum ρ(u_s − u) per unit B and sets the fluid velocity at a fully covered
    /// node to u_s as Ω₁ does (stable with free grains), but never touches the rest population: fully covered
    /// regions of open systems do not accumulate mass.
    LinearizedNonEquilibriumBounceBack,
    /// ΩΛ, the magic-parameter-consistent partially saturated operator (see [`lambda_collide`]): partly covered
    /// nodes are two-relaxation-time fluid with viscosity ν/(1 − B), Λ kept, and a Brinkman friction
    /// 3νκB ρ(u* − u_s) towards the solid; fully covered nodes bounce back, link by link, what arrives from
    /// nodes that are not fully covered (Ladd 1994) and reset the rest to the solid's equilibrium. With TRT its
    /// steady solutions (drag, permeability, wall location) do not depend on τ at fixed Λ.
    LambdaConsistent,
}

impl SolidOperator {
    /// Every operator, in the order of the enum (its serde variant indices).
    pub const ALL: [SolidOperator; 5] = [
        SolidOperator::NonEquilibriumBounceBack,
        SolidOperator::Superposition,
        SolidOperator::MovingWallBounceBack,
        SolidOperator::LinearizedNonEquilibriumBounceBack,
        SolidOperator::LambdaConsistent,
    ];

    /// The weighting B each operator was validated with: B = ε for ΩΛ (NT's eq. 4.5 in its Λ form
    /// under-weights partly covered cells, drag −4 % to −16 % at l = 40), Noble & Torczynski's eq. 4.5 for the
    /// others (the dissertation's).
    pub fn weighting(self) -> Weighting {
        match self {
            SolidOperator::LambdaConsistent => Weighting::SolidFraction,
            _ => Weighting::NobleTorczynski,
        }
    }

    /// The name scene files use (serde), e.g. `"lambda_consistent"`.
    pub fn name(self) -> &'static str {
        match self {
            SolidOperator::NonEquilibriumBounceBack => "non_equilibrium_bounce_back",
            SolidOperator::Superposition => "superposition",
            SolidOperator::MovingWallBounceBack => "moving_wall_bounce_back",
            SolidOperator::LinearizedNonEquilibriumBounceBack => {
                "linearized_non_equilibrium_bounce_back"
            }
            SolidOperator::LambdaConsistent => "lambda_consistent",
        }
    }

    /// The operator named `name` (see [`SolidOperator::name`]); `Err` with a message naming the new word for
    /// the words of earlier scene files, and listing the names otherwise.
    pub fn from_name(name: &str) -> Result<Self, &'static str> {
        if let Some(op) = Self::ALL.into_iter().find(|op| op.name() == name) {
            return Ok(op);
        }
        Err(match name {
            "bounce_back" => {
                "`bounce_back` is the old scene word for Omega_1: write \"non_equilibrium_bounce_back\" \
                 (the kernel's bounce-back at full cover is Omega_3, \"moving_wall_bounce_back\")"
            }
            "moving_wall" => "`moving_wall` is the old scene word for Omega_3: write \"moving_wall_bounce_back\"",
            "linearized" => {
                "`linearized` is the old scene word for Omega_1l: write \
                 \"linearized_non_equilibrium_bounce_back\""
            }
            "lambda" | "omega_lambda" => "write \"lambda_consistent\" for Omega_Lambda",
            _ => {
                "unknown solid operator: use one of \"non_equilibrium_bounce_back\" (Omega_1), \
                 \"superposition\" (Omega_2), \"moving_wall_bounce_back\" (Omega_3), \
                 \"linearized_non_equilibrium_bounce_back\" (Omega_1l), \"lambda_consistent\" (Omega_Lambda)"
            }
        })
    }

    /// The operator's symbol: "Ω₁", "Ω₂", "Ω₃", "Ω₁ₗ" or "ΩΛ".
    pub fn symbol(self) -> &'static str {
        match self {
            SolidOperator::NonEquilibriumBounceBack => "Ω₁",
            SolidOperator::Superposition => "Ω₂",
            SolidOperator::MovingWallBounceBack => "Ω₃",
            SolidOperator::LinearizedNonEquilibriumBounceBack => "Ω₁ₗ",
            SolidOperator::LambdaConsistent => "ΩΛ",
        }
    }
}

/// Scene words by name (refusing the old words with a hint, [`SolidOperator::from_name`]); binary formats
/// (the driver's checkpoints) by variant index, as the derived `Serialize` writes them.
#[cfg(feature = "serde")]
impl<'de> serde::Deserialize<'de> for SolidOperator {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        const NAMES: &[&str] = &[
            "non_equilibrium_bounce_back",
            "superposition",
            "moving_wall_bounce_back",
            "linearized_non_equilibrium_bounce_back",
            "lambda_consistent",
        ];
        struct Id;
        impl<'de> serde::de::Visitor<'de> for Id {
            type Value = SolidOperator;
            fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
                f.write_str("a solid operator name, e.g. \"lambda_consistent\"")
            }
            fn visit_u64<E: serde::de::Error>(self, i: u64) -> Result<SolidOperator, E> {
                usize::try_from(i)
                    .ok()
                    .and_then(|i| SolidOperator::ALL.get(i).copied())
                    .ok_or_else(|| E::invalid_value(serde::de::Unexpected::Unsigned(i), &self))
            }
            fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<SolidOperator, E> {
                SolidOperator::from_name(s).map_err(E::custom)
            }
            fn visit_bytes<E: serde::de::Error>(self, b: &[u8]) -> Result<SolidOperator, E> {
                match core::str::from_utf8(b) {
                    Ok(s) => self.visit_str(s),
                    Err(_) => Err(E::invalid_value(serde::de::Unexpected::Bytes(b), &self)),
                }
            }
        }
        impl<'de> serde::de::DeserializeSeed<'de> for Id {
            type Value = SolidOperator;
            fn deserialize<D: serde::Deserializer<'de>>(
                self,
                d: D,
            ) -> Result<SolidOperator, D::Error> {
                d.deserialize_identifier(self)
            }
        }
        struct Op;
        impl<'de> serde::de::Visitor<'de> for Op {
            type Value = SolidOperator;
            fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
                f.write_str("a solid operator name, e.g. \"lambda_consistent\"")
            }
            fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<SolidOperator, E> {
                SolidOperator::from_name(s).map_err(E::custom)
            }
            fn visit_enum<A: serde::de::EnumAccess<'de>>(
                self,
                a: A,
            ) -> Result<SolidOperator, A::Error> {
                use serde::de::VariantAccess;
                let (op, v) = a.variant_seed(Id)?;
                v.unit_variant()?;
                Ok(op)
            }
        }
        d.deserialize_enum("SolidOperator", NAMES, Op)
    }
}

/// Links of a covered node whose neighbour is **not** fully covered: bit i (1 ≤ i ≤ 8) is set when the node
/// x + c_i is fluid or only partly covered (ε < 1), clear when it is fully covered, a solid obstacle node or
/// outside the lattice behind a wall. Only [`SolidOperator::LambdaConsistent`] reads it (at fully covered
/// nodes); [`ALL_LINKS_OPEN`] makes a fully covered node bounce back every link.
pub type OpenLinks = u16;

/// Every link open (bits 1–8): the mask to use when the neighbourhood is not known.
pub const ALL_LINKS_OPEN: OpenLinks = 0x1fe;

/// ΩΛ's friction constant κ: the friction coefficient of a partly covered node is β = κ (τ⁺ − ½) B = 3κνB.
///
/// **κ is a calibration, not a derived value.** The Brinkman schemes it follows (Ginzburg 2008, Phys. Rev. E
/// 77:066704; Ginzburg, Silva & Talon 2015, Phys. Rev. E 91:023307) fix how the friction must scale with the
/// viscosity for the solution to be τ-free (β ∝ ν, used here), not its size. **What it compensates, measured**
/// (`driver/examples/wall_offsets.rs`; README "What κ compensates"): with κ = 0 a wall that cuts cells sits at
/// its geometric place for flow driven by a body force (to 1e-3 spacing along the lattice axes, within 0.03 at
/// an angle), but 0.04–0.05 spacing inside the solid for flow driven by a pressure gradient (growing with
/// ε(1 − ε), the same at every Λ); the friction thickens every cut wall by about 0.04–0.1 spacing at κ = 1.21.
/// Flow through the gaps of a pack or an array is largely pressure-driven, so κ > 0 there, and the κ a case
/// needs grows with its pressure-driven share (0.33 / 0.51 / 0.99 for the l = 40 arrays at c = 0.2 / 0.4 /
/// 0.6), which no single constant fits. κ = 1.21 is the least-squares fit of the drag of the periodic square
/// array of cylinders at **l = 30 nodes**, c = 0.2 / 0.4 / 0.6, against Sangani & Acrivos (1982) (drag linear in κ between the two values
/// run, 1.21 and 1.27; `cargo run --release -p lbdem --example kappa_calibration`), with the full-cover gap
/// [`LAMBDA_FULL_GAP`] of 0.05 (with the earlier gap of 1e-3 the fit was 1.27). No acceptance test uses l = 30. Held-out
/// errors (every τ, TRT at Λ = 3/16, B = ε; README "ΩΛ's friction constant κ"): l = 20, c = 0.2 / 0.4 and
/// l = 40, c = 0.2 / 0.4 / 0.6, see the README table; at l = 40 they exceed the 1 % target for c ≥ 0.4.
/// The scatter of the error with how a disc sits on the lattice (sign changes between l = 30 and l = 40 at
/// fixed κ) is of the size of κ's effect, which is why a single calibration case is not trusted here.
pub const LAMBDA_FRICTION: f64 = 1.21;

/// ΩΛ's wall-pressure constant α: a partly covered node of weight B gets, for each solid s covering it, the
/// force (ε_s/Σε) α B (1 − B/2) c_s² ∇ₜρ_s, where ∇ₜρ_s is the density gradient along that solid's surface
/// ([`SolidShare::wall_gradient`], [`wall_gradient`]); solid s takes the opposite (momentum is exchanged, not
/// created).
///
/// **What it corrects, measured (not derived).** A cut cell answers a body force and a pressure gradient
/// differently: with the force weighted by 1 − B and no friction (κ = 0) its wall sits at the geometric place
/// under a body force (to 1e-3 spacing along the axes) but 0.04–0.05 spacing inside the solid under a pressure
/// gradient, growing with ε(1 − ε) and the same at every τ and Λ (`driver/examples/wall_offsets.rs`; README
/// "What κ compensates"). The streamed populations deliver the whole of −c_s²∇ρ to the node's fluid, where a
/// body force delivers 1 − B of itself; the measured offset is cancelled by a counter-force of about
/// 2 B c_s²∇ₜρ, not B c_s²∇ₜρ. The α of the force α B c_s²∇ₜρ that zeroes the offset of a narrow straight
/// channel section fed by an exact-walled wide channel is nearly the same for ε = 0.1 … 0.9 and falls with the
/// section's length (2.42 / 2.18 / 2.05 over 80 / 160 / 320 columns, the same at τ = 1.5, ≈ 2.13 at Λ = 1/12):
/// α = 2 in developed flow, the rest an entrance effect. Only the tangential part is used: the full gradient
/// (its normal part pushing the fluid into the wall) went unstable at α = 3 and the normal part carries no flux.
///
/// **Why B (1 − B/2) and not B (stability).** Along the wall, a cut cell's fluid feels the pressure force and
/// this counter-force together: −(1 − α B g(B)) c_s²∇ₜρ with g the shape. With g = 1 and α = 2 the bracket
/// is negative for B > ½: such a cell's fluid is pushed towards higher density, a negative squared sound speed
/// along the wall, and where a throat is filled with such cells a density bump there grows instead of
/// spreading (measured: the quick fracture scene's grains at fluid radius 0.95 diverged by step 500). With
/// g = 1 − B/2 the bracket is 1 − αB + αB²/2 = (1 − B)² at α = 2, never negative; α = 2 is the largest α
/// for which it stays non-negative at every B (its minimum is 1 − α/2 at B = 1). g agrees with 1 to first
/// order in B; at κ = 0 the offsets of the 80-column pressure-driven section are −0.004 / −0.013 / −0.021 /
/// −0.024 / −0.014 spacing at ε = 0.1 / 0.3 / 0.5 / 0.7 / 0.9 (with g = 1: −0.004 / −0.009 / −0.011 /
/// −0.010 / −0.006; uncorrected: +0.04–0.05), and the same pack runs to its steady state.
pub const LAMBDA_PRESSURE: f64 = 2.0;

/// ΩΛ's friction constant κ in its wall-pressure form ([`LambdaTerms::WALL_PRESSURE`], with α =
/// [`LAMBDA_PRESSURE`]). With the pressure answer of the cut cells corrected, what κ has left to stand for is
/// the curvature of a wall (convex walls sit 0.02–0.03 spacing inside the solid at κ = 0) and the entrance of
/// short gaps. **Set by hand, against the acceptance cases, and said so:** drag is linear in κ (measured at
/// κ = 0.3 and 0.6, τ = 0.8); the l = 20 array (c = 0.2) loses more than 2 % of its drag below κ ≈ 0.375 and
/// the l = 40 array (c = 0.6) gains more than 1 % above κ ≈ 0.666; 0.5 is about the middle. Least-squares fits
/// over the other even cell sides (c = 0.2 / 0.4 / 0.6, τ = 0.8, neither 20 nor 40) give 0.70 from l = 24 and
/// 0.64 from l = 28: the resolution trend (coarse arrays low, fine ones high) pulls them up, and the scatter
/// with how a disc sits on the lattice is of the size of κ's effect, so no single fit is trusted. README,
/// "ΩΛ's wall-pressure form".
pub const LAMBDA_WALL_FRICTION: f64 = 0.5;

/// The density gradient along a wall at a partly covered node, ∇ₜρ = (t·∇ρ) t with t ⟂ `normal` (a unit
/// normal of the solid's surface; zero gives zero), from the node's density `rho` and those of its four axis
/// neighbours `neighbours` = [x + 1, y + 1, x − 1, y − 1] (D2Q9 directions 1–4), `None` where the neighbour
/// is fully covered, an obstacle or beyond a wall: central differences where both neighbours of an axis are
/// given, one-sided where one is, zero where neither. What [`SolidShare::wall_gradient`] holds.
#[inline]
pub fn wall_gradient<T: Real>(rho: T, neighbours: [Option<T>; 4], normal: [T; 2]) -> [T; 2] {
    let diff = |plus: Option<T>, minus: Option<T>| match (plus, minus) {
        (Some(p), Some(m)) => T::lit(0.5) * (p - m),
        (Some(p), None) => p - rho,
        (None, Some(m)) => rho - m,
        (None, None) => T::zero(),
    };
    let g = [
        diff(neighbours[0], neighbours[2]),
        diff(neighbours[1], neighbours[3]),
    ];
    let t = [-normal[1], normal[0]];
    let along = t[0] * g[0] + t[1] * g[1];
    [along * t[0], along * t[1]]
}

/// ΩΛ treats a node as fully covered when its summed fraction is at least 1 − this gap (see
/// [`lambda_fully_covered`]).
///
/// **Why (measured, not derived; no paper gives it).** ΩΛ's partly-covered rule does not tend to its
/// fully-covered rule as ε → 1: with B → 1 the local rates go to ω⁺ → 0 and ω⁻ → 2 (Λ⁺/(1 − B) and
/// Λ⁻(1 − B)), so the node bounces every link back with its own trapezoidal velocity u*, damps its
/// non-hydrodynamic modes only in proportion to 1 − B, and stays tied to the solid only by the bounded friction
/// β = κΛ⁺B. Free grains that leave such nodes go into a period-2 oscillation (velocity and spin flipping sign
/// every step) that grows until the run diverges, the sooner the larger τ (Λ⁻ = Λ/Λ⁺ smaller, β larger):
/// * a lone free rock grain at τ = 0.8 whose cover leaves one node 1 − ε = 4.2e-5, 2.2e-5 or 1.3e-6 short
///   of full cover diverged (1.4e-4 and 3.4e-4 did not; `driver/tests/omega_grain.rs`,
///   `driver/examples/omega_probe.rs`), which a gap of 1e-3 cured;
/// * a **pack** of free rock grains (the `terzaghi` column, two seeds; the quick fracture scene's bonded
///   ellipses) still diverged with a gap of 1e-3 from τ = 1.25 (column) and at τ = 2 (both), and with a gap
///   of 0.01 at τ = 2; with gaps of 0.015, 0.02 and 0.05 they ran to the end at τ = 2 (and 0.02 at 1.4).
///
/// 0.05 is about three times the smallest gap measured stable in a pack at τ = 2 and five times the largest
/// measured unstable there. What it costs: nodes covered to 95–99.9 % bounce their open links back instead of
/// passing 0.1–5 % of a node's fluid through friction, so a boundary moves by at most 0.05 spacing there; with
/// κ refitted (1.27 → 1.21, [`LAMBDA_FRICTION`]) the `terzaghi` column's permeability fell by 1.7 % (6.378e-5
/// → 6.269e-5 cm², the same at τ = 0.8, 1.4 and 2 to 3e-4) and the square arrays' drag moved by tenths of a
/// percent (README, "ΩΛ's friction constant κ").
pub const LAMBDA_FULL_GAP: f64 = 0.05;

/// Whether ΩΛ treats a node whose fractions sum to `eps_sum` as fully covered: ε ≥ 1 − [`LAMBDA_FULL_GAP`].
#[inline(always)]
pub fn lambda_fully_covered<T: Real>(eps_sum: T) -> bool {
    eps_sum >= T::one() - T::lit(LAMBDA_FULL_GAP)
}

/// The PSM weight B for a (capped) solid fraction `eps` ∈ [0, 1] and relaxation time `tau`.
#[inline(always)]
pub fn weighting<T: Real>(kind: Weighting, eps: T, tau: T) -> T {
    match kind {
        Weighting::NobleTorczynski => {
            let a = tau - T::lit(0.5);
            eps * a / ((T::one() - eps) + a)
        }
        Weighting::SolidFraction => eps,
    }
}

/// The collision operator of the fluid: BGK (one relaxation time) or Ginzburg's two-relaxation-time operator.
///
/// **TRT** (Ginzburg, Verhaeghe & d'Humières 2008, Commun. Comput. Phys. 3:427; Ginzburg, d'Humières &
/// Kuzmin 2010): each pair of opposite populations is split into its symmetric and antisymmetric parts,
/// f_i^± = ½(f_i ± f_ī), e_i^± = ½(f_i^eq ± f_ī^eq), and the parts relax at their own rates:
/// f_i ← f_i − ω⁺(f_i⁺ − e_i⁺) − ω⁻(f_i⁻ − e_i⁻), ω^± = 1/τ^±. τ⁺ sets the viscosity, ν = (τ⁺ − ½)/3; τ⁻
/// follows from the "magic" parameter Λ = (τ⁺ − ½)(τ⁻ − ½). Steady solutions (with bounce-back walls) depend on
/// τ⁺ and τ⁻ only through ν and Λ, so at fixed Λ the wall location and the permeability are the same at every
/// viscosity; Λ = 3/16 puts the half-way bounce-back wall of a Poiseuille channel exactly half-way. With
/// Λ = (τ − ½)², τ⁻ = τ⁺ and the operator is BGK (to roundoff).
///
/// Guo forcing splits the same way: S_i = (1 − ω⁺/2) S_i⁺ + (1 − ω⁻/2) S_i⁻ with S_i⁻ = 3 w_i c_i·F and
/// S_i⁺ = w_i [9 (c_i·u)(c_i·F) − 3 u·F] (the odd and even parts of Guo's w_i [3 (c_i − u) + 9 (c_i·u) c_i]·F),
/// and u = (Σ f c + F/2)/ρ. S⁺ carries no mass and S⁻ exactly F of momentum, so the step adds F whatever ω^±.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Collision<T> {
    /// Bhatnagar–Gross–Krook, one relaxation time τ (dissertation eq. 4.1).
    #[default]
    Bgk,
    /// Two relaxation times with the magic parameter of [`Trt`].
    Trt(Trt<T>),
}

/// The magic parameter Λ of a two-relaxation-time collision, checked positive and finite by [`Trt::new`].
///
/// Deserialised values are not checked: pass them through [`Collision::rates`] (the driver's `set_collision`
/// does) before use.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Trt<T> {
    magic: T,
}

/// Why a collision operator was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CollisionError {
    /// τ (τ⁺) is not finite or not above ½.
    Tau,
    /// Λ is not finite or not positive.
    Magic,
    /// τ⁻ = ½ + Λ/(τ⁺ − ½) is not finite or not above ½ (Λ too small or too large for this τ⁺).
    TauMinus,
}

impl<T: Real> Trt<T> {
    /// Λ = 3/16: half-way bounce-back walls exactly half-way for Poiseuille flow (the default).
    pub const DEFAULT_MAGIC: f64 = 3.0 / 16.0;

    /// TRT with magic parameter `magic` = Λ; refuses Λ ≤ 0 and non-finite Λ.
    pub fn new(magic: T) -> Result<Self, CollisionError> {
        if magic.is_finite() && magic > T::zero() {
            Ok(Self { magic })
        } else {
            Err(CollisionError::Magic)
        }
    }

    /// The magic parameter Λ.
    #[inline(always)]
    pub fn magic(&self) -> T {
        self.magic
    }

    /// τ⁻ = ½ + Λ/(τ⁺ − ½).
    #[inline(always)]
    pub fn tau_minus(&self, tau_plus: T) -> T {
        T::lit(0.5) + self.magic / (tau_plus - T::lit(0.5))
    }
}

impl<T: Real> Default for Trt<T> {
    fn default() -> Self {
        Self {
            magic: T::lit(Self::DEFAULT_MAGIC),
        }
    }
}

/// The relaxation rates of a collision: ω⁺ = 1/τ⁺ for the symmetric parts, ω⁻ = 1/τ⁻ for the antisymmetric
/// ones (BGK: both 1/τ). Built by [`Collision::rates`] (checked) or [`Collision::rates_unchecked`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rates<T> {
    /// ω⁺ = 1/τ⁺.
    pub plus: T,
    /// ω⁻ = 1/τ⁻.
    pub minus: T,
}

impl<T: Real> Collision<T> {
    /// Check the operator with relaxation time `tau` (τ⁺) and return its rates: refuses τ ≤ ½, and for TRT a
    /// τ⁻ that is not finite and above ½.
    pub fn rates(&self, tau: T) -> Result<Rates<T>, CollisionError> {
        if !(tau.is_finite() && tau > T::lit(0.5)) {
            return Err(CollisionError::Tau);
        }
        if let Collision::Trt(t) = self {
            if !(t.magic.is_finite() && t.magic > T::zero()) {
                return Err(CollisionError::Magic);
            }
            let tm = t.tau_minus(tau);
            if !(tm.is_finite() && tm > T::lit(0.5)) {
                return Err(CollisionError::TauMinus);
            }
        }
        Ok(self.rates_unchecked(tau))
    }

    /// The rates without checks (the step passes call this once per pass; the driver checked the operator with
    /// [`Collision::rates`] when it was chosen). The same arithmetic as [`Collision::rates`], so the same bits.
    #[inline(always)]
    pub fn rates_unchecked(&self, tau: T) -> Rates<T> {
        let plus = T::one() / tau;
        match self {
            Collision::Bgk => Rates { plus, minus: plus },
            Collision::Trt(t) => Rates {
                plus,
                minus: T::one() / t.tau_minus(tau),
            },
        }
    }
}

/// Two-relaxation-time collision of one node, in place, without body force. Conserves mass and momentum to
/// roundoff; with `rates.minus == rates.plus` it is BGK to roundoff.
#[inline(always)]
pub fn trt_collide<T: Real>(f: &mut [T; Q], rates: Rates<T>) {
    let rho = density(f);
    let j = momentum(f);
    let inv = T::one() / rho;
    trt_relax(f, rho, [j[0] * inv, j[1] * inv], rates, None);
}

/// Two-relaxation-time collision of one node with Guo forcing split into its even and odd parts (force density
/// `force`, lattice units): adds exactly `force` of momentum and no mass.
#[inline(always)]
pub fn trt_collide_forced<T: Real>(f: &mut [T; Q], rates: Rates<T>, force: [T; 2]) {
    let (rho, u) = macroscopic(f, force);
    trt_relax(f, rho, u, rates, Some(force));
}

/// The TRT relaxation (and forcing) of `f` towards the equilibrium of (ρ, u), pair by pair: with
/// n^± = f^± − e^±, f_i ← f_i − ω⁺ n⁺ − ω⁻ n⁻ and f_ī ← f_ī − ω⁺ n⁺ + ω⁻ n⁻, written as
/// f_i − (A + B), f_ī − (A − B) with A = (ω⁺/2)(f_i + f_ī) − ω⁺ e⁺ and B = (ω⁻/2)(f_i − f_ī) − ω⁻ e⁻.
#[inline(always)]
fn trt_relax<T: Real>(f: &mut [T; Q], rho: T, u: [T; 2], rates: Rates<T>, force: Option<[T; 2]>) {
    let w = weights::<T>();
    let one = T::one();
    let half = T::lit(0.5);
    let three = T::lit(3.0);
    let four_half = T::lit(4.5);
    let [ux, uy] = u;
    let usq = T::lit(1.5) * (ux * ux + uy * uy);
    let (hp, hm) = (half * rates.plus, half * rates.minus);
    // ω⁺ w ρ and 3 ω⁻ w ρ for the axis and diagonal weights.
    let (p1, p5) = (rates.plus * (w[1] * rho), rates.plus * (w[5] * rho));
    let (m1, m5) = (
        three * (rates.minus * (w[1] * rho)),
        three * (rates.minus * (w[5] * rho)),
    );
    // Forcing: (1 − ω⁺/2) w [9 (c·u)(c·F) − 3 u·F] and (1 − ω⁻/2) 3 w c·F, per weight.
    let (sp, sm, uf) = match force {
        Some(fc) => (
            one - hp,
            one - hm,
            Some((fc, three * (ux * fc[0] + uy * fc[1]))),
        ),
        None => (T::zero(), T::zero(), None),
    };
    let pair = |fi: T, fo: T, p: T, m: T, wi: T, cu: T, cf: T| -> (T, T) {
        let a = hp * (fi + fo) - p * ((one + four_half * cu * cu) - usq);
        let b = hm * (fi - fo) - m * cu;
        let (mut gi, mut go) = (fi - (a + b), fo - (a - b));
        if let Some((_, uf3)) = uf {
            let even = sp * (wi * (T::lit(9.0) * cu * cf - uf3));
            let odd = sm * (wi * (three * cf));
            gi += even + odd;
            go += even - odd;
        }
        (gi, go)
    };
    let fc = uf.map(|(fc, _)| fc).unwrap_or([T::zero(); 2]);
    let (f1, f3) = pair(f[1], f[3], p1, m1, w[1], ux, fc[0]);
    let (f2, f4) = pair(f[2], f[4], p1, m1, w[1], uy, fc[1]);
    let (f5, f7) = pair(f[5], f[7], p5, m5, w[5], ux + uy, fc[0] + fc[1]);
    let (f8, f6) = pair(f[8], f[6], p5, m5, w[5], ux - uy, fc[0] - fc[1]);
    let mut f0 = f[0] - rates.plus * (f[0] - w[0] * rho * (one - usq));
    if let Some((_, uf3)) = uf {
        f0 -= sp * (w[0] * uf3);
    }
    *f = [f0, f1, f2, f3, f4, f5, f6, f7, f8];
}

/// The fluid collision of one node chosen by `collision` with rates `rates` (from [`Collision::rates`]), with
/// Guo forcing when `force` is not zero. BGK is the BGK path bitwise ([`bgk_collide`] / [`bgk_collide_forced`]).
#[inline(always)]
pub fn fluid_collide<T: Real>(
    f: &mut [T; Q],
    collision: &Collision<T>,
    rates: Rates<T>,
    force: [T; 2],
) {
    let forced = force[0] != T::zero() || force[1] != T::zero();
    match (collision, forced) {
        (Collision::Bgk, false) => bgk_collide(f, rates.plus),
        (Collision::Bgk, true) => bgk_collide_forced(f, rates.plus, force),
        (Collision::Trt(_), false) => trt_collide(f, rates),
        (Collision::Trt(_), true) => trt_collide_forced(f, rates, force),
    }
}

/// Fluid density and velocity at a node with the Guo half-force shift: u = (Σ f c + F/2)/ρ.
#[inline(always)]
pub fn macroscopic<T: Real>(f: &[T; Q], force: [T; 2]) -> (T, [T; 2]) {
    let rho = density(f);
    let j = momentum(f);
    let half = T::lit(0.5);
    let inv = T::one() / rho;
    (
        rho,
        [
            (j[0] + half * force[0]) * inv,
            (j[1] + half * force[1]) * inv,
        ],
    )
}

/// Guo source term S_i (without the (1 − ω/2) prefactor applied twice: this returns the full S_i).
#[inline(always)]
pub fn guo_source<T: Real>(omega: T, u: [T; 2], force: [T; 2]) -> [T; Q] {
    let w = weights::<T>();
    let pre = T::one() - T::lit(0.5) * omega;
    let three = T::lit(3.0);
    let nine = T::lit(9.0);
    let mut s = [T::zero(); Q];
    for (i, si) in s.iter_mut().enumerate() {
        let c = velocity::<T>(i);
        let cu = c[0] * u[0] + c[1] * u[1];
        let ax = three * (c[0] - u[0]) + nine * cu * c[0];
        let ay = three * (c[1] - u[1]) + nine * cu * c[1];
        *si = pre * w[i] * (ax * force[0] + ay * force[1]);
    }
    s
}

/// BGK collision of one node, in place, without body force. Conserves mass and momentum to roundoff.
#[inline(always)]
pub fn bgk_collide<T: Real>(f: &mut [T; Q], omega: T) {
    let rho = density(f);
    let j = momentum(f);
    let inv = T::one() / rho;
    let feq = equilibrium(rho, [j[0] * inv, j[1] * inv]);
    for i in 0..Q {
        f[i] = f[i] - omega * (f[i] - feq[i]);
    }
}

/// BGK collision of one node with Guo forcing (force density `force` in lattice units).
#[inline(always)]
pub fn bgk_collide_forced<T: Real>(f: &mut [T; Q], omega: T, force: [T; 2]) {
    let (rho, u) = macroscopic(f, force);
    let feq = equilibrium(rho, u);
    let s = guo_source(omega, u, force);
    for i in 0..Q {
        f[i] = f[i] - omega * (f[i] - feq[i]) + s[i];
    }
}

/// BGK collision over whole structure-of-arrays slices (one slice per direction, all the same length):
/// the node-local operator applied to every node. No streaming.
pub fn bgk_collide_slices<T: Real>(planes: [&mut [T]; Q], omega: T, force: [T; 2]) {
    let [p0, p1, p2, p3, p4, p5, p6, p7, p8] = planes;
    let n = p0.len();
    let (p1, p2, p3, p4) = (&mut p1[..n], &mut p2[..n], &mut p3[..n], &mut p4[..n]);
    let (p5, p6, p7, p8) = (&mut p5[..n], &mut p6[..n], &mut p7[..n], &mut p8[..n]);
    let forced = force[0] != T::zero() || force[1] != T::zero();
    for k in 0..n {
        let mut f = [
            p0[k], p1[k], p2[k], p3[k], p4[k], p5[k], p6[k], p7[k], p8[k],
        ];
        if forced {
            bgk_collide_forced(&mut f, omega, force);
        } else {
            bgk_collide(&mut f, omega);
        }
        p0[k] = f[0];
        p1[k] = f[1];
        p2[k] = f[2];
        p3[k] = f[3];
        p4[k] = f[4];
        p5[k] = f[5];
        p6[k] = f[6];
        p7[k] = f[7];
        p8[k] = f[8];
    }
}

/// One solid covering part of a lattice cell: its solid fraction ε_s of the cell and its rigid-body velocity
/// u_s = V + ω × (x − X) evaluated at the node.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SolidShare<T> {
    /// Fraction of the cell area covered by this solid, in [0, 1].
    pub fraction: T,
    /// Solid velocity at the node (lattice units).
    pub velocity: [T; 2],
    /// The density gradient along this solid's surface at the node, ∇ₜρ (lattice units; [`wall_gradient`]),
    /// read by [`SolidOperator::LambdaConsistent`] at partly covered nodes only (its wall-pressure force,
    /// [`LAMBDA_PRESSURE`]); zero for none. Derived from the populations at the start of each step, so not
    /// saved.
    #[cfg_attr(feature = "serde", serde(skip))]
    pub wall_gradient: [T; 2],
}

/// Parameters of the partially-saturated collision.
#[derive(Clone, Copy, Debug)]
pub struct PsmParams<T> {
    /// Relaxation time τ (> ½).
    pub tau: T,
    /// Weighting function B.
    pub weighting: Weighting,
    /// Solid collision operator Ω^S.
    pub solid: SolidOperator,
    /// Body-force density applied to the fluid (weighted by 1 − B at covered nodes).
    pub force: [T; 2],
    /// The fluid collision (BGK or TRT) of the fluid part, (1 − B) of the update.
    pub collision: Collision<T>,
    /// ΩΛ's constants (read by [`SolidOperator::LambdaConsistent`] only).
    pub lambda: LambdaTerms,
}

/// ΩΛ's two constants at partly covered nodes: the friction κ ([`LAMBDA_FRICTION`]) and the wall-pressure α
/// ([`LAMBDA_PRESSURE`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LambdaTerms {
    /// κ: the friction coefficient of a partly covered node is β = κ (τ⁺ − ½) B.
    pub friction: f64,
    /// α: a partly covered node's fluid gets (ε_s/Σε) α B (1 − B/2) c_s² ∇ₜρ_s from each solid s
    /// ([`SolidShare::wall_gradient`]); 0 for none.
    pub pressure: f64,
}

impl LambdaTerms {
    /// Friction only (κ = [`LAMBDA_FRICTION`], α = 0): ΩΛ's first form, the default until 2026-12-07 (the
    /// validation tables made before then used it); kept selectable.
    pub const FRICTION_ONLY: Self = Self {
        friction: LAMBDA_FRICTION,
        pressure: 0.0,
    };
    /// The wall-pressure form (α = [`LAMBDA_PRESSURE`], κ = [`LAMBDA_WALL_FRICTION`]), the default: the square
    /// arrays within 1 % at l = 40 at every τ.
    pub const WALL_PRESSURE: Self = Self {
        friction: LAMBDA_WALL_FRICTION,
        pressure: LAMBDA_PRESSURE,
    };
}

impl Default for LambdaTerms {
    fn default() -> Self {
        Self::WALL_PRESSURE
    }
}

/// Noble–Torczynski partially-saturated collision of one node, in place.
///
/// `shares` are the solids covering the node; `exchange[s]` receives the momentum handed to solid `s` this
/// step (force on the solid in lattice units, F_s = −B_s Σ_i Ω^S_{i,s} c_i). `exchange` must be at least as
/// long as `shares`; extra entries are left untouched. Returns the total weight B used at the node.
///
/// With no shares, or all fractions zero, this is bitwise the BGK (or forced BGK) collision.
///
/// [`SolidOperator::LambdaConsistent`] also needs the node's open links ([`psm_collide_links`]); here every
/// link is taken as open, which is right for a node whose neighbours are all not fully covered.
#[inline]
pub fn psm_collide<T: Real>(
    f: &mut [T; Q],
    params: &PsmParams<T>,
    shares: &[SolidShare<T>],
    exchange: &mut [[T; 2]],
) -> T {
    psm_collide_links(f, params, shares, ALL_LINKS_OPEN, exchange)
}

/// [`psm_collide`] with the node's open links (used by [`SolidOperator::LambdaConsistent`] only).
#[inline]
pub fn psm_collide_links<T: Real>(
    f: &mut [T; Q],
    params: &PsmParams<T>,
    shares: &[SolidShare<T>],
    open: OpenLinks,
    exchange: &mut [[T; 2]],
) -> T {
    let rates = params.collision.rates_unchecked(params.tau);
    let forced = params.force[0] != T::zero() || params.force[1] != T::zero();
    let mut eps_sum = T::zero();
    for s in shares {
        eps_sum += s.fraction;
    }
    if eps_sum.partial_cmp(&T::zero()) != Some(core::cmp::Ordering::Greater) {
        // Uncovered node (or NaN fractions, which we refuse to spread): plain BGK, bitwise.
        for e in exchange.iter_mut().take(shares.len()) {
            *e = [T::zero(); 2];
        }
        fluid_collide(f, &params.collision, rates, params.force);
        return T::zero();
    }
    let eps = if eps_sum > T::one() {
        T::one()
    } else {
        eps_sum
    };
    if params.solid == SolidOperator::LambdaConsistent {
        return lambda_collide(f, params, rates, shares, eps_sum, open, exchange);
    }
    operator_collide(f, params, rates, forced, shares, eps_sum, eps, exchange)
}

/// The partially-saturated collision of a covered node (Σε > 0, `eps` = min(Σε, 1)) under the operators Ω₁, Ω₂,
/// Ω₃ and Ω₁ₗ: the body of [`psm_collide_links`] after its checks, shared with the batched pass
/// ([`psm_collide_lanes`]) so that both run the same arithmetic. `forced` says whether `params.force` is not zero.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn operator_collide<T: Real>(
    f: &mut [T; Q],
    params: &PsmParams<T>,
    rates: Rates<T>,
    forced: bool,
    shares: &[SolidShare<T>],
    eps_sum: T,
    eps: T,
    exchange: &mut [[T; 2]],
) -> T {
    let omega = rates.plus;
    let b_total = weighting(params.weighting, eps, params.tau);
    let (rho, u) = if forced {
        macroscopic(f, params.force)
    } else {
        let rho = density(f);
        let j = momentum(f);
        let inv = T::one() / rho;
        (rho, [j[0] * inv, j[1] * inv])
    };
    let feq = equilibrium(rho, u);
    // The part of Ω^S common to every share (each share adds f_i^eq(ρ, u_s), and for Ω₃ also −f_ī^eq(ρ, u_s)):
    // Ω₁: f_ī − f_ī^eq(ρ, u) − f_i;  Ω₂: (1 − ω)(f_i − f_i^eq(ρ, u)) − f_i;  Ω₃: f_ī − f_i.
    let mut common = [T::zero(); Q];
    match params.solid {
        SolidOperator::NonEquilibriumBounceBack => {
            for i in 0..Q {
                let o = OPPOSITE[i];
                common[i] = (f[o] - feq[o]) - f[i];
            }
        }
        SolidOperator::Superposition => match params.collision {
            Collision::Bgk => {
                let keep = T::one() - omega;
                for i in 0..Q {
                    common[i] = keep * (f[i] - feq[i]) - f[i];
                }
            }
            Collision::Trt(_) => {
                // The fluid's post-collision non-equilibrium, (1 − ω⁺) n⁺ + (1 − ω⁻) n⁻.
                let (kp, km) = (T::one() - rates.plus, T::one() - rates.minus);
                let half = T::lit(0.5);
                for i in 0..Q {
                    let o = OPPOSITE[i];
                    let np = half * ((f[i] + f[o]) - (feq[i] + feq[o]));
                    let nm = half * ((f[i] - f[o]) - (feq[i] - feq[o]));
                    common[i] = (kp * np + km * nm) - f[i];
                }
            }
        },
        SolidOperator::MovingWallBounceBack => {
            for i in 0..Q {
                common[i] = f[OPPOSITE[i]] - f[i];
            }
        }
        SolidOperator::LinearizedNonEquilibriumBounceBack => {
            let w = weights::<T>();
            let three = T::lit(3.0);
            for i in 0..Q {
                let c = velocity::<T>(i);
                let cu = c[0] * u[0] + c[1] * u[1];
                common[i] = f[OPPOSITE[i]] - f[i] + three * w[i] * rho * cu;
            }
        }
        // Handled by `lambda_collide` above.
        SolidOperator::LambdaConsistent => {}
    }
    let bounce_back = params.solid == SolidOperator::MovingWallBounceBack;
    let linearized = params.solid == SolidOperator::LinearizedNonEquilibriumBounceBack;
    let w_lin = weights::<T>();
    let one_minus_b = T::one() - b_total;
    let mut post = [T::zero(); Q];
    match params.collision {
        Collision::Bgk => {
            for i in 0..Q {
                post[i] = f[i] - one_minus_b * omega * (f[i] - feq[i]);
            }
            if forced {
                let s = guo_source(omega, u, params.force);
                for i in 0..Q {
                    post[i] += one_minus_b * s[i];
                }
            }
        }
        Collision::Trt(_) => {
            let mut g = *f;
            trt_relax(&mut g, rho, u, rates, forced.then_some(params.force));
            for i in 0..Q {
                post[i] = f[i] + one_minus_b * (g[i] - f[i]);
            }
        }
    }
    for (share, ex) in shares.iter().zip(exchange.iter_mut()) {
        let b_s = b_total * (share.fraction / eps_sum);
        let feq_s = if linearized {
            // Only the linear part 3 w_i ρ c_i·u_s is used.
            let mut l = [T::zero(); Q];
            for (i, li) in l.iter_mut().enumerate() {
                let c = velocity::<T>(i);
                *li = T::lit(3.0)
                    * w_lin[i]
                    * rho
                    * (c[0] * share.velocity[0] + c[1] * share.velocity[1]);
            }
            l
        } else {
            equilibrium(rho, share.velocity)
        };
        let mut mx = T::zero();
        let mut my = T::zero();
        for i in 0..Q {
            let omega_s = if bounce_back {
                common[i] + (feq_s[i] - feq_s[OPPOSITE[i]])
            } else {
                common[i] + feq_s[i]
            };
            let d = b_s * omega_s;
            post[i] += d;
            let c = velocity::<T>(i);
            mx += d * c[0];
            my += d * c[1];
        }
        *ex = [-mx, -my];
    }
    *f = post;
    b_total
}

/// The weight B(ε) of [`SolidOperator::LambdaConsistent`], free of τ at fixed Λ: ε for
/// [`Weighting::SolidFraction`]; for [`Weighting::NobleTorczynski`], eq. 4.5 with τ − ½ replaced by √Λ,
/// B = ε√Λ/((1 − ε) + √Λ), Λ = (τ⁺ − ½)(τ⁻ − ½) (the same B as eq. 4.5 for BGK, where √Λ = τ − ½).
#[inline(always)]
pub fn lambda_weighting<T: Real>(kind: Weighting, eps: T, rates: Rates<T>) -> T {
    match kind {
        Weighting::SolidFraction => eps,
        Weighting::NobleTorczynski => {
            let half = T::lit(0.5);
            let a = ((T::one() / rates.plus - half) * (T::one() / rates.minus - half)).sqrt();
            eps * a / ((T::one() - eps) + a)
        }
    }
}

/// ΩΛ, the magic-parameter-consistent partially saturated collision ([`SolidOperator::LambdaConsistent`]).
///
/// **Why BGK-PSM drag depends on τ.** Written as a two-relaxation-time update, the Noble–Torczynski collision
/// (1 − B)·BGK + B·Ω^S is, at a covered node, TRT with local rates ω⁺_loc = (1 − B)ω, ω⁻_loc = (1 − B)ω + 2B
/// (Ω₁, Ω₃) and a friction towards u_s whose coefficient (B per step for Ω₁) does not scale with the
/// viscosity. The steady TRT solution depends on its rates only through ν and Λ = (1/ω⁺ − ½)(1/ω⁻ − ½)
/// (Ginzburg, Verhaeghe & d'Humières 2008, Commun. Comput. Phys. 3:427; d'Humières & Ginzburg 2009, Comput.
/// Math. Appl. 58:823) when every local Λ⁺ = 1/ω⁺ − ½ scales with ν, every local product Λ⁺Λ⁻ is fixed
/// and every force scales with ν (Stokes flow: u ∝ F/ν). The PSM rates and friction break all three, so the
/// effective solid surface moves with τ (Pan, Luo & Miller 2006, Comput. Fluids 35:898, for bounce-back).
///
/// **ΩΛ** restores the three scalings (this crate's construction; the parts are published):
/// * partly covered node (0 < ε < 1 − [`LAMBDA_FULL_GAP`]), weight B = [`lambda_weighting`]: TRT with Λ⁺_loc = Λ⁺/(1 − B) (the
///   viscosity of a fluid layer of thickness 1 − B carrying the cell's shear, ν/(1 − B)) and
///   Λ⁻_loc = Λ⁻(1 − B) (so Λ⁺_loc Λ⁻_loc = Λ), plus a Brinkman friction F_s = −β_s ρ (u* − u_s) towards
///   each solid, β_s = κ Λ⁺ B ε_s/Σε ([`LAMBDA_FRICTION`] κ; Λ⁺ = τ⁺ − ½ = 3ν, the scaling of the
///   viscosity-independent Brinkman schemes of Ginzburg 2008, Phys. Rev. E 77:066704, and of Ginzburg, Silva &
///   Talon 2015, Phys. Rev. E 91:023307), applied as a Guo force with the trapezoidal velocity
///   u* = (Σ f c + F/2)/ρ solved for implicitly: u*(1 + β/2) = (Σ f c + (1 − B)F_body/2)/ρ + Σ_s β_s u_s/2.
///   The body force is weighted by 1 − B. In a planar shear layer driven by a body force, with κ = 0, the wall
///   sits at its geometric position (ε of the cell on the solid side) at every τ; under a pressure gradient the
///   cut cells pass too much fluid, which the friction compensates (measured: [`LAMBDA_FRICTION`]) or, in the
///   wall-pressure form ([`LambdaTerms::WALL_PRESSURE`]), a force (ε_s/Σε) α B (1 − B/2) c_s² ∇ₜρ_s along each solid's
///   surface corrects ([`LAMBDA_PRESSURE`]; solid s takes its opposite; it enters u* as the body force does);
/// * fully covered node (ε ≥ 1 − [`LAMBDA_FULL_GAP`]): the populations that arrived from neighbours that are
///   not fully covered
///   (`open` links) are bounced back with the solid velocity, f_i ← f_ī + 6 w_i ρ c_i·u_s (Ladd 1994,
///   J. Fluid Mech. 271:285: half-way bounce-back, exact at Λ = 3/16 for a planar wall at every τ); the
///   populations from fully covered neighbours are replaced by the solid's equilibrium shape over those
///   directions carrying the mass that remains, so the fluid inside a solid moves with it (the interior
///   dynamics of Ω₁, which keeps free grains stable; Ω₃'s reversal there makes them unstable). Several solids
///   at one node act in proportion to ε_s/Σε.
///
/// Mass is conserved exactly and the momentum each solid receives, `exchange[s]`, is what the fluid loses
/// (fluid momentum change = (1 − B) F_body − Σ_s exchange[s]); with no solid it is the fluid collision.
/// The velocity the node's collision uses (u*, or Σ_s (ε_s/Σε) u_s at a fully covered node) is
/// [`psm_velocity`]: the velocity to measure fluxes with.
#[inline]
fn lambda_collide<T: Real>(
    f: &mut [T; Q],
    params: &PsmParams<T>,
    rates: Rates<T>,
    shares: &[SolidShare<T>],
    eps_sum: T,
    open: OpenLinks,
    exchange: &mut [[T; 2]],
) -> T {
    if lambda_fully_covered(eps_sum) {
        lambda_full(f, shares, eps_sum, open, exchange);
        return T::one();
    }
    lambda_partial(f, params, rates, shares, eps_sum, exchange)
}

/// ΩΛ at a fully covered node (`eps_sum` ≥ 1 − [`LAMBDA_FULL_GAP`]): see [`lambda_collide`]. Shared with the
/// batched pass ([`psm_collide_lanes`]).
#[inline(always)]
fn lambda_full<T: Real>(
    f: &mut [T; Q],
    shares: &[SolidShare<T>],
    eps_sum: T,
    open: OpenLinks,
    exchange: &mut [[T; 2]],
) {
    let rho = density(f);
    {
        let w = weights::<T>();
        let mut post = [T::zero(); Q];
        for (share, ex) in shares.iter().zip(exchange.iter_mut()) {
            let b_s = share.fraction / eps_sum;
            let p = full_cover_populations(f, rho, share.velocity, open, &w);
            let (mut mx, mut my) = (T::zero(), T::zero());
            for i in 0..Q {
                let d = b_s * (p[i] - f[i]);
                post[i] += b_s * p[i];
                let c = velocity::<T>(i);
                mx += d * c[0];
                my += d * c[1];
            }
            *ex = [-mx, -my];
        }
        *f = post;
    }
}

/// ΩΛ at a partly covered node (0 < `eps_sum` < 1 − [`LAMBDA_FULL_GAP`]): see [`lambda_collide`]. Shared with
/// the batched pass ([`psm_collide_lanes`]).
#[inline(always)]
fn lambda_partial<T: Real>(
    f: &mut [T; Q],
    params: &PsmParams<T>,
    rates: Rates<T>,
    shares: &[SolidShare<T>],
    eps_sum: T,
    exchange: &mut [[T; 2]],
) -> T {
    let rho = density(f);
    let eps = eps_sum;
    let b = lambda_weighting(params.weighting, eps, rates);
    let one = T::one();
    let half = T::lit(0.5);
    let (lp, lm) = (one / rates.plus - half, one / rates.minus - half);
    let one_minus_b = one - b;
    let local = Rates {
        plus: one / (half + lp / one_minus_b),
        minus: one / (half + lm * one_minus_b),
    };
    let beta = T::lit(params.lambda.friction) * lp * b;
    let fb = lambda_explicit_force(params, b, shares, eps_sum);
    let u = lambda_velocity(rho, momentum(f), fb, beta, shares, eps_sum);
    let mut total = fb;
    let push = lambda_push(params, b);
    for (s, ex) in shares.iter().zip(exchange.iter_mut()) {
        let share = s.fraction / eps_sum;
        let bs = beta * share;
        let ps = push * share;
        let fs = [
            -(bs * rho) * (u[0] - s.velocity[0]),
            -(bs * rho) * (u[1] - s.velocity[1]),
        ];
        total[0] += fs[0];
        total[1] += fs[1];
        *ex = [
            -(fs[0] + ps * s.wall_gradient[0]),
            -(fs[1] + ps * s.wall_gradient[1]),
        ];
    }
    trt_relax(f, rho, u, local, Some(total));
    b
}

/// The explicit force of a partly covered ΩΛ node (weight `b`): the body force weighted by 1 − B plus each
/// share's wall-pressure force (ε_s/Σε) α B (1 − B/2) c_s² ∇ₜρ_s (α = `params.lambda.pressure`, c_s² = ⅓, ∇ₜρ_s the
/// share's [`SolidShare::wall_gradient`]), summed in share order.
#[inline(always)]
fn lambda_explicit_force<T: Real>(
    params: &PsmParams<T>,
    b: T,
    shares: &[SolidShare<T>],
    eps_sum: T,
) -> [T; 2] {
    let force = params.force;
    let one_minus_b = T::one() - b;
    let mut fb = [one_minus_b * force[0], one_minus_b * force[1]];
    let push = lambda_push(params, b);
    for s in shares {
        let ps = push * (s.fraction / eps_sum);
        fb[0] += ps * s.wall_gradient[0];
        fb[1] += ps * s.wall_gradient[1];
    }
    fb
}

/// The wall-pressure factor of a partly covered ΩΛ node of weight `b`: α B (1 − B/2) c_s² (α =
/// `params.lambda.pressure`, c_s² = ⅓), which times (ε_s/Σε) ∇ₜρ_s is solid s's wall-pressure force
/// ([`LAMBDA_PRESSURE`]).
#[inline(always)]
fn lambda_push<T: Real>(params: &PsmParams<T>, b: T) -> T {
    T::lit(params.lambda.pressure / 3.0) * (b * (T::one() - T::lit(0.5) * b))
}

/// u* of a partly covered ΩΛ node: u*(1 + β/2) = (Σ f c + F_b/2)/ρ + Σ_s (β ε_s/Σε) u_s/2, the trapezoidal
/// velocity of the Guo scheme with the friction F_s = −β (ε_s/Σε) ρ (u* − u_s) solved for implicitly.
#[inline(always)]
fn lambda_velocity<T: Real>(
    rho: T,
    j: [T; 2],
    fb: [T; 2],
    beta: T,
    shares: &[SolidShare<T>],
    eps_sum: T,
) -> [T; 2] {
    let half = T::lit(0.5);
    let inv = T::one() / rho;
    let mut num = [(j[0] + half * fb[0]) * inv, (j[1] + half * fb[1]) * inv];
    for s in shares {
        let bs = half * beta * (s.fraction / eps_sum);
        num[0] += bs * s.velocity[0];
        num[1] += bs * s.velocity[1];
    }
    let den = T::one() + half * beta;
    [num[0] / den, num[1] / den]
}

/// The post-collision populations of a fully covered ΩΛ node for one solid moving at `u_s`: links open to
/// nodes that are not fully covered bounce back (f_i ← f_ī + 6 w_i ρ c_i·u_s); the other directions (the
/// rest direction always among them) share the remaining mass in the proportions of f^eq(1, u_s).
#[inline(always)]
fn full_cover_populations<T: Real>(
    f: &[T; Q],
    rho: T,
    u_s: [T; 2],
    open: OpenLinks,
    w: &[T; Q],
) -> [T; Q] {
    let shape = equilibrium(T::one(), u_s);
    let six = T::lit(6.0);
    let mut p = [T::zero(); Q];
    let mut reflected = T::zero();
    let mut weight = T::zero();
    for i in 0..Q {
        if i != 0 && open & (1 << i) != 0 {
            let c = velocity::<T>(i);
            p[i] = f[OPPOSITE[i]] + six * w[i] * rho * (c[0] * u_s[0] + c[1] * u_s[1]);
            reflected += p[i];
        } else {
            weight += shape[i];
        }
    }
    let remaining = rho - reflected;
    for i in 0..Q {
        if i == 0 || open & (1 << i) == 0 {
            p[i] = remaining * (shape[i] / weight);
        }
    }
    p
}

/// The velocity a partially saturated collision uses at a node (to measure fluxes with): (Σ f c + F/2)/ρ for
/// Ω₁, Ω₂, Ω₃ and Ω₁ₗ; for ΩΛ the trapezoidal u* with the solids' friction at a partly covered node (what makes
/// ΩΛ's measured flux independent of τ) and Σ_s (ε_s/Σε) u_s at a fully covered one. Returns (ρ, u).
#[inline]
pub fn psm_velocity<T: Real>(
    f: &[T; Q],
    params: &PsmParams<T>,
    shares: &[SolidShare<T>],
) -> (T, [T; 2]) {
    let mut eps_sum = T::zero();
    for s in shares {
        eps_sum += s.fraction;
    }
    if params.solid != SolidOperator::LambdaConsistent
        || eps_sum.partial_cmp(&T::zero()) != Some(core::cmp::Ordering::Greater)
    {
        return macroscopic(f, params.force);
    }
    let rho = density(f);
    if lambda_fully_covered(eps_sum) {
        let mut u = [T::zero(); 2];
        for s in shares {
            let b = s.fraction / eps_sum;
            u[0] += b * s.velocity[0];
            u[1] += b * s.velocity[1];
        }
        return (rho, u);
    }
    let rates = params.collision.rates_unchecked(params.tau);
    let b = lambda_weighting(params.weighting, eps_sum, rates);
    let lp = T::one() / rates.plus - T::lit(0.5);
    let beta = T::lit(params.lambda.friction) * lp * b;
    let fb = lambda_explicit_force(params, b, shares, eps_sum);
    (
        rho,
        lambda_velocity(rho, momentum(f), fb, beta, shares, eps_sum),
    )
}

/// Nodes per batch of the batched partially-saturated collision ([`psm_collide_lanes`]): eight lanes fill an
/// AVX-512 register of f64 (two AVX2 registers).
pub const PSM_LANES: usize = 8;

/// The batch kernel a covered node can take ([`lane_class`]); the other nodes take [`psm_collide_links`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LaneClass {
    /// One share, ε > 0, under Ω₁, Ω₂, Ω₃ or Ω₁ₗ.
    Operator,
    /// One share, 0 < ε < 1 − [`LAMBDA_FULL_GAP`], under ΩΛ.
    LambdaPartial,
    /// One share, ε ≥ 1 − [`LAMBDA_FULL_GAP`], under ΩΛ.
    LambdaFull,
}

/// Which batch kernel a node covered by `shares` takes: `None` for a node with several shares (or none) or a
/// fraction that is not positive (NaN included), which [`psm_collide_links`] treats.
#[inline(always)]
pub fn lane_class<T: Real>(params: &PsmParams<T>, shares: &[SolidShare<T>]) -> Option<LaneClass> {
    let [share] = shares else {
        return None;
    };
    // The sum [`psm_collide_links`] forms, in its order.
    let eps_sum = T::zero() + share.fraction;
    if eps_sum.partial_cmp(&T::zero()) != Some(core::cmp::Ordering::Greater) {
        return None;
    }
    Some(match params.solid {
        SolidOperator::LambdaConsistent if lambda_fully_covered(eps_sum) => LaneClass::LambdaFull,
        SolidOperator::LambdaConsistent => LaneClass::LambdaPartial,
        _ => LaneClass::Operator,
    })
}

/// A batch of [`PSM_LANES`] covered nodes of one [`LaneClass`], structure of arrays: populations `f[q][lane]`,
/// each node's single share and open links, and (out) the momentum handed to each share.
#[derive(Clone, Copy, Debug)]
pub struct PsmLanes<T> {
    /// Populations, direction-major: `f[q][lane]`. In: gathered; out: post-collision.
    pub f: [[T; PSM_LANES]; Q],
    /// The share covering each node.
    pub share: [SolidShare<T>; PSM_LANES],
    /// Open links of each node (read by ΩΛ at fully covered nodes only).
    pub open: [OpenLinks; PSM_LANES],
    /// Out: momentum handed to each node's share (as `exchange` of [`psm_collide_links`]).
    pub exchange: [[T; 2]; PSM_LANES],
}

impl<T: Real> Default for PsmLanes<T> {
    fn default() -> Self {
        Self {
            f: [[T::zero(); PSM_LANES]; Q],
            share: [SolidShare::default(); PSM_LANES],
            open: [0; PSM_LANES],
            exchange: [[T::zero(); 2]; PSM_LANES],
        }
    }
}

/// Run a body on the first `$n` lanes of `$lanes`: the nodes one after the other, each with its own arithmetic
/// (so each node's bits are [`psm_collide_links`]'s), in one loop over the lanes with no call and no branch on the
/// uniform choices (operator, collision, forcing, weighting), which the callers make constants. A macro rather
/// than a function taking a closure: the closure was not inlined into the loop. Compiled inside the fluid step's
/// `with_simd` (AVX-512 or AVX2), the compiler vectorises this loop across the lanes: a node costs 11–13 ns
/// in a batch against 27–43 ns alone (`benches/examples/psm_lanes.rs`, 2026-12-05). Tried and slower (1.7× the
/// step's cost per covered node): the kernels written once over a lane-vector type whose every operation is
/// its own loop over `[T; PSM_LANES]` (README, "Cost of a covered node").
macro_rules! for_lanes {
    ($lanes:expr, $n:expr, |$f:ident, $share:ident, $open:ident| $body:block) => {{
        let lanes: &mut PsmLanes<_> = $lanes;
        let n: usize = $n;
        for l in 0..n.min(PSM_LANES) {
            let mut $f: [_; Q] = core::array::from_fn(|q| lanes.f[q][l]);
            let $share = lanes.share[l];
            let $open = lanes.open[l];
            let ex = {
                let $f = &mut $f;
                $body
            };
            for q in 0..Q {
                lanes.f[q][l] = $f[q];
            }
            lanes.exchange[l] = ex;
        }
    }};
}

/// [`operator_collide`] over the lanes with `params` built by the caller from literal variants (so that every
/// choice in the body is a constant once inlined).
#[inline(always)]
fn operator_lanes<T: Real>(lanes: &mut PsmLanes<T>, n: usize, params: &PsmParams<T>, forced: bool) {
    let rates = params.collision.rates_unchecked(params.tau);
    for_lanes!(lanes, n, |f, share, _open| {
        let eps_sum = T::zero() + share.fraction;
        let eps = if eps_sum > T::one() {
            T::one()
        } else {
            eps_sum
        };
        let mut ex = [[T::zero(); 2]];
        operator_collide(f, params, rates, forced, &[share], eps_sum, eps, &mut ex);
        ex[0]
    });
}

/// The partially-saturated collision of the first `n` (at most [`PSM_LANES`]) nodes of a batch that all take the
/// kernel `class` ([`lane_class`]; a mismatched class is misuse): bitwise [`psm_collide_links`] of each node (the
/// same functions, on the same values, in the same order). Lanes from `n` on are left as they are.
#[inline(always)]
pub fn psm_collide_lanes<T: Real>(
    lanes: &mut PsmLanes<T>,
    n: usize,
    params: &PsmParams<T>,
    class: LaneClass,
) {
    match class {
        LaneClass::LambdaFull => for_lanes!(lanes, n, |f, share, open| {
            let eps_sum = T::zero() + share.fraction;
            let mut ex = [[T::zero(); 2]];
            lambda_full(f, &[share], eps_sum, open, &mut ex);
            ex[0]
        }),
        LaneClass::LambdaPartial => match params.weighting {
            Weighting::NobleTorczynski => lambda_partial_lanes(
                lanes,
                n,
                &PsmParams {
                    weighting: Weighting::NobleTorczynski,
                    ..*params
                },
            ),
            Weighting::SolidFraction => lambda_partial_lanes(
                lanes,
                n,
                &PsmParams {
                    weighting: Weighting::SolidFraction,
                    ..*params
                },
            ),
        },
        LaneClass::Operator => operator_dispatch(lanes, n, params),
    }
}

/// [`lambda_partial`] over the lanes (`params.weighting` a literal at the call).
#[inline(always)]
fn lambda_partial_lanes<T: Real>(lanes: &mut PsmLanes<T>, n: usize, params: &PsmParams<T>) {
    let rates = params.collision.rates_unchecked(params.tau);
    for_lanes!(lanes, n, |f, share, _open| {
        let eps_sum = T::zero() + share.fraction;
        let mut ex = [[T::zero(); 2]];
        lambda_partial(f, params, rates, &[share], eps_sum, &mut ex);
        ex[0]
    });
}

/// [`operator_lanes`] with every uniform choice (operator, collision, forcing, weighting) turned into a literal.
#[inline(always)]
fn operator_dispatch<T: Real>(lanes: &mut PsmLanes<T>, n: usize, params: &PsmParams<T>) {
    let forced = params.force[0] != T::zero() || params.force[1] != T::zero();
    let zero = [T::zero(); 2];
    macro_rules! go {
        ($solid:expr, $collision:expr) => {
            match (params.weighting, forced) {
                (Weighting::NobleTorczynski, false) => operator_lanes(
                    lanes,
                    n,
                    &PsmParams {
                        tau: params.tau,
                        weighting: Weighting::NobleTorczynski,
                        solid: $solid,
                        force: zero,
                        collision: $collision,
                        lambda: params.lambda,
                    },
                    false,
                ),
                (Weighting::SolidFraction, false) => operator_lanes(
                    lanes,
                    n,
                    &PsmParams {
                        tau: params.tau,
                        weighting: Weighting::SolidFraction,
                        solid: $solid,
                        force: zero,
                        collision: $collision,
                        lambda: params.lambda,
                    },
                    false,
                ),
                (Weighting::NobleTorczynski, true) => operator_lanes(
                    lanes,
                    n,
                    &PsmParams {
                        tau: params.tau,
                        weighting: Weighting::NobleTorczynski,
                        solid: $solid,
                        force: params.force,
                        collision: $collision,
                        lambda: params.lambda,
                    },
                    true,
                ),
                (Weighting::SolidFraction, true) => operator_lanes(
                    lanes,
                    n,
                    &PsmParams {
                        tau: params.tau,
                        weighting: Weighting::SolidFraction,
                        solid: $solid,
                        force: params.force,
                        collision: $collision,
                        lambda: params.lambda,
                    },
                    true,
                ),
            }
        };
    }
    macro_rules! by_collision {
        ($solid:expr) => {
            match params.collision {
                Collision::Bgk => go!($solid, Collision::Bgk),
                Collision::Trt(t) => go!($solid, Collision::Trt(Trt { magic: t.magic })),
            }
        };
    }
    match params.solid {
        SolidOperator::NonEquilibriumBounceBack => {
            by_collision!(SolidOperator::NonEquilibriumBounceBack)
        }
        SolidOperator::Superposition => by_collision!(SolidOperator::Superposition),
        SolidOperator::MovingWallBounceBack => by_collision!(SolidOperator::MovingWallBounceBack),
        SolidOperator::LinearizedNonEquilibriumBounceBack => {
            by_collision!(SolidOperator::LinearizedNonEquilibriumBounceBack)
        }
        // Not an operator-class node ([`lane_class`]); the scalar kernel, node by node, in case of misuse.
        SolidOperator::LambdaConsistent => {
            for l in 0..n.min(PSM_LANES) {
                let mut f: [T; Q] = core::array::from_fn(|q| lanes.f[q][l]);
                let mut ex = [[T::zero(); 2]];
                psm_collide_links(&mut f, params, &[lanes.share[l]], lanes.open[l], &mut ex);
                for (q, fq) in f.iter().enumerate() {
                    lanes.f[q][l] = *fq;
                }
                lanes.exchange[l] = ex[0];
            }
        }
    }
}
