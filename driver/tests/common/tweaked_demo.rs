//! The coupled demo with a test's tweak: a scene kind that runs exactly like `coupled_demo` except where the
//! tweak steps in (a poisoned population before a chunk, a non-finite result), to drive the run loop's fault
//! paths (divergence, non-finite results) through the real loop.
#![allow(dead_code)]
use std::marker::PhantomData;
use std::path::Path;

use lbdem::engine::exec::{Exec, ExecTarget};
use lbdem::error::Result;
use lbdem::input::limits::Budget;
use lbdem::kinds::coupled_demo::{CoupledDemo, DemoState};
use lbdem::run::{Case, Kind, OutputStage};

/// Where a test steps into a coupled-demo run.
pub trait Tweak: 'static {
    /// Called on the state before each chunk.
    fn before_chunk(_state: &mut DemoState) {}
    /// Changes the results of the summary.
    fn results(results: serde_json::Value) -> serde_json::Value {
        results
    }
}

/// `coupled_demo` with the tweak `T`.
pub struct Tweaked<T>(PhantomData<T>);

fn demo<T: Tweak>(case: &Case<Tweaked<T>>) -> Case<CoupledDemo> {
    Case {
        scene: case.scene.clone(),
        setup: case.setup.clone(),
        budget: case.budget.clone(),
    }
}

impl<T: Tweak> Kind for Tweaked<T> {
    const NAME: &'static str = CoupledDemo::NAME;
    type Scene = <CoupledDemo as Kind>::Scene;
    type Setup = <CoupledDemo as Kind>::Setup;
    type State = DemoState;
    fn validate(scene: &Self::Scene) -> Result<()> {
        CoupledDemo::validate(scene)
    }
    fn setup(scene: &Self::Scene) -> Result<Self::Setup> {
        CoupledDemo::setup(scene)
    }
    fn budget(scene: &Self::Scene, setup: &Self::Setup) -> Result<Budget> {
        CoupledDemo::budget(scene, setup)
    }
    fn describe(case: &Case<Self>) -> String {
        CoupledDemo::describe(&demo(case))
    }
    fn start(case: &Case<Self>, exec: &Exec) -> Result<DemoState> {
        CoupledDemo::start(&demo(case), exec)
    }
    fn lattices(s: &mut DemoState) -> Vec<&mut dyn ExecTarget> {
        CoupledDemo::lattices(s)
    }
    fn check_resumed(case: &Case<Self>, s: &DemoState) -> Result<()> {
        CoupledDemo::check_resumed(&demo(case), s)
    }
    fn steps_done(s: &DemoState) -> u64 {
        CoupledDemo::steps_done(s)
    }
    fn total_steps(case: &Case<Self>, s: &DemoState) -> Option<u64> {
        CoupledDemo::total_steps(&demo(case), s)
    }
    fn finished(case: &Case<Self>, s: &DemoState) -> bool {
        CoupledDemo::finished(&demo(case), s)
    }
    fn advance(case: &Case<Self>, s: &mut DemoState, dir: Option<&Path>) -> Result<()> {
        T::before_chunk(s);
        CoupledDemo::advance(&demo(case), s, dir)
    }
    fn health(case: &Case<Self>, s: &DemoState) -> Result<()> {
        CoupledDemo::health(&demo(case), s)
    }
    fn write_outputs(
        case: &Case<Self>,
        s: &DemoState,
        dir: &Path,
        stage: OutputStage,
    ) -> Result<()> {
        CoupledDemo::write_outputs(&demo(case), s, dir, stage)
    }
    fn results(case: &Case<Self>, s: &DemoState) -> Result<serde_json::Value> {
        Ok(T::results(CoupledDemo::results(&demo(case), s)?))
    }
}
