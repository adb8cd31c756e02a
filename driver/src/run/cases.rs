//! Kinds made of several independent cases run one after the other, each to its own end (a steady state or a
//! step limit): `cylinder_array` (one case per solid fraction and drive), `porous_flow` (one per diameter and
//! pressure drop). The state holds the outcomes of the finished cases and the case in progress, so a run is
//! checkpointed and resumed in the middle of a case like any other.
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::engine::exec::Exec;
use crate::error::Result;

/// One case in progress.
pub trait CaseRun: Sized {
    /// What defines the case (lattice units).
    type Case;
    /// What it measured.
    type Outcome: Clone;
    /// The case at its start.
    fn start(case: &Self::Case, exec: &Exec) -> Result<Self>;
    /// One chunk (a check interval); whether the case is over.
    fn advance(&mut self, case: &Self::Case) -> Result<bool>;
    /// The measurements of the case as it stands.
    fn outcome(&self, case: &Self::Case) -> Self::Outcome;
    /// Steps done in this case.
    fn steps(&self) -> u64;
    /// Steps a finished case took.
    fn outcome_steps(outcome: &Self::Outcome) -> u64;
    /// Health of the case after a chunk.
    fn health(&self) -> Result<()>;
    /// Use this process's execution settings (after a resume).
    fn apply(&mut self, exec: &Exec);
    /// One line on a finished case, for the log.
    fn report(case: &Self::Case, outcome: &Self::Outcome) -> String;
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

    /// One chunk of the next unfinished case of `cases` (starting it when needed).
    pub fn advance(&mut self, cases: &[R::Case]) -> Result<()> {
        let Some(case) = cases.get(self.done.len()) else {
            return Ok(());
        };
        let mut run = match self.current.take() {
            Some(r) => r,
            None => R::start(case, &self.exec)?,
        };
        if run.advance(case)? {
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
