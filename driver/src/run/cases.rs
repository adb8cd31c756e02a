//! Kinds made of several independent cases run one after the other, each to its own end (a steady state or a
//! step limit): `cylinder_array` (one case per solid fraction and drive), `porous_flow` (one per diameter and
//! pressure drop). The state holds the outcomes of the finished cases and the case in progress, so a run is
//! checkpointed and resumed in the middle of a case like any other.
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use std::time::Instant;

use lbdem_kernels::Real;

use crate::engine::exec::Exec;
use crate::engine::lattice::FluidLattice;
use crate::error::Result;
use crate::observe::health::fluid_health;
use crate::output::snapshots::FixedSnapshots;

/// What a diverging steady-flow case suggests (its health check, and its steady-state loop's divergence check).
pub const DRIVE_HINT: &str =
    "lower the drive (acceleration, Reynolds number or pressure drop), raise tau, or refine";

/// One case in progress.
pub trait CaseRun: Sized {
    /// What defines the case (lattice units).
    type Case;
    /// What it measured.
    type Outcome: Clone;
    /// The precision of its lattice.
    type Float: Real;
    /// The case at its start.
    fn start(case: &Self::Case, exec: &Exec) -> Result<Self>;
    /// One chunk (a check interval); whether the case is over.
    fn advance(&mut self, case: &Self::Case) -> Result<bool>;
    /// The measurements of the case as it stands.
    fn outcome(&self, case: &Self::Case) -> Self::Outcome;
    /// The case's lattice.
    fn lattice(&self) -> &FluidLattice<Self::Float>;
    /// The case's lattice, to change its execution settings.
    fn lattice_mut(&mut self) -> &mut FluidLattice<Self::Float>;
    /// Steps a finished case took.
    fn outcome_steps(outcome: &Self::Outcome) -> u64;
    /// One line on a finished case, for the log.
    fn report(case: &Self::Case, outcome: &Self::Outcome) -> String;
    /// Steps done in this case.
    fn steps(&self) -> u64 {
        self.lattice().steps()
    }
    /// Health of the case after a chunk.
    fn health(&self) -> Result<()> {
        fluid_health(self.lattice(), DRIVE_HINT)
    }
    /// Use this process's execution settings (after a resume).
    fn apply(&mut self, exec: &Exec) {
        exec.apply(self.lattice_mut());
    }
    /// Snapshot `index` of the case (0 at its start, 1 at its end): its grains held fixed and its lattice,
    /// through [`crate::output::snapshots::write_fixed`] into the case's series of `at`. None by default.
    fn snapshot(&self, _case: &Self::Case, _at: &FixedSnapshots, _index: usize) -> Result<()> {
        Ok(())
    }
}

/// One case run to its end in memory (no checkpoint; the health check once at the end, outside the timed
/// loop, besides whatever the case's own chunks check): its outcome and the wall time of the loop in seconds.
pub fn solve<R: CaseRun>(case: &R::Case, exec: &Exec) -> Result<(R::Outcome, f64)> {
    let start = Instant::now();
    let mut run = R::start(case, exec)?;
    while !run.advance(case)? {}
    let outcome = run.outcome(case);
    let seconds = start.elapsed().as_secs_f64();
    run.health()?;
    Ok((outcome, seconds))
}

/// The finished cases and the one in progress.
#[derive(Serialize, Deserialize)]
#[serde(bound(
    serialize = "R: Serialize, R::Outcome: Serialize",
    deserialize = "R: DeserializeOwned, R::Outcome: DeserializeOwned"
))]
pub struct Cases<R: CaseRun> {
    /// Outcomes of the finished cases, in order.
    pub done: Vec<R::Outcome>,
    current: Option<R>,
    /// This process's execution settings (not checkpointed), for the cases it starts.
    #[serde(skip)]
    exec: Exec,
}

impl<R: CaseRun> Cases<R> {
    /// No case run yet.
    pub fn new(exec: &Exec) -> Self {
        Self {
            done: Vec::new(),
            current: None,
            exec: *exec,
        }
    }

    /// Take over after a resume with this process's execution settings.
    pub fn resume(&mut self, exec: &Exec) {
        self.exec = *exec;
        if let Some(r) = &mut self.current {
            r.apply(exec);
        }
    }

    /// Steps done over all cases.
    pub fn steps(&self) -> u64 {
        self.done.iter().map(R::outcome_steps).sum::<u64>()
            + self.current.as_ref().map_or(0, R::steps)
    }

    /// Whether all `cases` are done.
    pub fn finished(&self, cases: usize) -> bool {
        self.done.len() >= cases
    }

    /// One chunk of the next unfinished case of `cases` (starting it when needed). With `at` (a run with a
    /// directory), each case's first snapshot is written when it starts and its last when it ends, in the
    /// series of case k ([`FixedSnapshots::case`]): both in the same chunk as the state change, so a resumed
    /// run writes the same files.
    pub fn advance(&mut self, cases: &[R::Case], at: Option<&FixedSnapshots>) -> Result<()> {
        let k = self.done.len();
        let Some(case) = cases.get(k) else {
            return Ok(());
        };
        let at = at.map(|a| a.case(k));
        let mut run = match self.current.take() {
            Some(r) => r,
            None => {
                let r = R::start(case, &self.exec)?;
                if let Some(a) = &at {
                    r.snapshot(case, a, 0)?;
                }
                r
            }
        };
        if run.advance(case)? {
            if let Some(a) = &at {
                run.snapshot(case, a, 1)?;
            }
            let o = run.outcome(case);
            eprintln!("lbdem: {}", R::report(case, &o));
            self.done.push(o);
        } else {
            self.current = Some(run);
        }
        Ok(())
    }

    /// Health of the case in progress.
    pub fn health(&self) -> Result<()> {
        self.current.as_ref().map_or(Ok(()), R::health)
    }
}

/// The cases of a sweep kind in the scene's precision (the same runs, `A` in `f32` and `B` in `f64`): what
/// such a kind checkpoints.
#[derive(Serialize, Deserialize)]
#[serde(bound(
    serialize = "A: Serialize, A::Outcome: Serialize, B: Serialize, B::Outcome: Serialize",
    deserialize = "A: DeserializeOwned, A::Outcome: DeserializeOwned, B: DeserializeOwned, \
                   B::Outcome: DeserializeOwned"
))]
pub enum Sweep<A: CaseRun, B: CaseRun> {
    /// precision = "f32".
    F32(Cases<A>),
    /// precision = "f64".
    F64(Cases<B>),
}

macro_rules! both {
    ($sweep:expr, $c:ident => $body:expr) => {
        match $sweep {
            Sweep::F32($c) => $body,
            Sweep::F64($c) => $body,
        }
    };
}

impl<C, O: Clone, A, B> Sweep<A, B>
where
    A: CaseRun<Case = C, Outcome = O>,
    B: CaseRun<Case = C, Outcome = O>,
{
    /// No case run yet, in `f32` when `single` (else `f64`).
    pub fn new(single: bool, exec: &Exec) -> Self {
        if single {
            Sweep::F32(Cases::new(exec))
        } else {
            Sweep::F64(Cases::new(exec))
        }
    }

    /// [`Cases::resume`].
    pub fn resume(&mut self, exec: &Exec) {
        both!(self, c => c.resume(exec))
    }

    /// [`Cases::steps`].
    pub fn steps(&self) -> u64 {
        both!(self, c => c.steps())
    }

    /// [`Cases::finished`].
    pub fn finished(&self, cases: usize) -> bool {
        both!(self, c => c.finished(cases))
    }

    /// [`Cases::advance`].
    pub fn advance(&mut self, cases: &[C], at: Option<&FixedSnapshots>) -> Result<()> {
        both!(self, c => c.advance(cases, at))
    }

    /// [`Cases::health`].
    pub fn health(&self) -> Result<()> {
        both!(self, c => c.health())
    }

    /// Outcomes of the finished cases, in order.
    pub fn done(&self) -> &[O] {
        both!(self, c => &c.done)
    }
}

impl<A, B> crate::run::Persist for Sweep<A, B>
where
    A: CaseRun + Serialize + DeserializeOwned,
    B: CaseRun + Serialize + DeserializeOwned,
    A::Outcome: Serialize + DeserializeOwned,
    B::Outcome: Serialize + DeserializeOwned,
{
    const PRECISION: u8 = 0;
    fn precision(&self) -> u8 {
        match self {
            Sweep::F32(_) => 4,
            Sweep::F64(_) => 8,
        }
    }
}

/// The [`crate::run::Kind`] methods every sweep kind shares (`start`, `resume`, `steps_done`, `total_steps`,
/// `finished`, `advance`, `health`), for a kind whose state is a [`Sweep`], whose set-up lists its cases as
/// `cases` (each with its step limit `max_steps`) and its lattice units as `units`, and whose scene has the
/// `[scene]` header as `scene`. `advance` writes each case's snapshots ([`CaseRun::snapshot`]) into the run
/// directory.
macro_rules! sweep_kind_methods {
    () => {
        fn start(
            case: &$crate::run::Case<Self>,
            exec: &$crate::engine::exec::Exec,
        ) -> $crate::error::Result<Self::State> {
            let single = case.scene.scene.precision.float_bytes() == 4;
            Ok($crate::run::cases::Sweep::new(single, exec))
        }

        fn resume(
            _case: &$crate::run::Case<Self>,
            state: &mut Self::State,
            exec: &$crate::engine::exec::Exec,
        ) -> $crate::error::Result<()> {
            state.resume(exec);
            Ok(())
        }

        fn steps_done(state: &Self::State) -> u64 {
            state.steps()
        }

        fn total_steps(case: &$crate::run::Case<Self>, _state: &Self::State) -> Option<u64> {
            Some(case.setup.cases.iter().map(|c| c.max_steps).sum())
        }

        fn finished(case: &$crate::run::Case<Self>, state: &Self::State) -> bool {
            state.finished(case.setup.cases.len())
        }

        fn advance(
            case: &$crate::run::Case<Self>,
            state: &mut Self::State,
            dir: Option<&std::path::Path>,
        ) -> $crate::error::Result<()> {
            let h = &case.scene.scene;
            let at = dir.map(|d| {
                $crate::output::snapshots::FixedSnapshots::new(
                    d,
                    (h.name.as_deref(), Self::NAME, h.units),
                    case.setup.units,
                )
            });
            state.advance(&case.setup.cases, at.as_ref())
        }

        fn health(
            _case: &$crate::run::Case<Self>,
            state: &Self::State,
        ) -> $crate::error::Result<()> {
            state.health()
        }
    };
}
pub(crate) use sweep_kind_methods;
