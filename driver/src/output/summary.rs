//! The one summary schema: every kind's `summary.json` is a header (version, kind, scene, units, derived
//! figures, warnings, execution settings, steps, wall time) followed by the kind's `results`. The schema is
//! written down as a JSON Schema in `docs/summary.schema.json` and every kind's summary is validated against it
//! in the tests. Only `wall_seconds` and `execution` depend on the machine and the moment; everything else is
//! the same bytes for the same scene, whatever the thread count, SIMD level, streaming scheme or interruptions.
use serde::Serialize;

use crate::engine::exec::Exec;
use crate::units::UnitLabels;

/// Version of the summary schema (`docs/summary.schema.json`).
pub const SCHEMA_VERSION: u32 = 1;

/// How the run was executed (speed only: no result depends on these).
#[derive(Clone, Debug, Serialize)]
pub struct Execution {
    /// Worker threads.
    pub threads: usize,
    /// Instruction set of the fluid's bulk pass.
    pub simd: &'static str,
    /// Streaming scheme of the fluid.
    pub streaming: &'static str,
}

impl Execution {
    /// The settings of `exec` (threads as rayon runs them: call inside the run's pool).
    pub fn of(exec: &Exec) -> Self {
        Self {
            threads: rayon::current_num_threads(),
            simd: exec.simd.name(),
            streaming: exec.streaming.name(),
        }
    }
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Version of the summary schema ([`SCHEMA_VERSION`]).
    pub schema_version: u32,
    /// Version of lbdem that wrote it.
    pub lbdem_version: &'static str,
    /// `[scene] kind`.
    pub kind: &'static str,
    /// Path of the scene file the run started from (its copy, for a resumed run).
    pub scene_file: String,
    /// The scene as parsed (defaults filled in).
    pub scene: serde_json::Value,
    /// Unit labels of the physical values.
    pub units: UnitLabels,
    /// Every derived figure (what `lbdem check` prints).
    pub derived: serde_json::Value,
    /// Warnings about the settings.
    pub warnings: Vec<String>,
    /// Threads, SIMD level, streaming scheme.
    pub execution: Execution,
    /// Steps done in all.
    pub steps: u64,
    /// Step this process started from (0, or the checkpoint's step for a resumed run).
    pub segment_first_step: u64,
    /// Wall-clock seconds of this process's part of the run.
    pub wall_seconds: f64,
    /// What the kind measured.
    pub results: serde_json::Value,
    /// The results that are not finite numbers (`results.<key>` paths; NaN and ±∞ are written as `null`). A
    /// run with any of them exits non-zero.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub non_finite: Vec<String>,
}

/// The `results.<path>` of every value of `results` that is not a finite number: JSON has no NaN or infinity,
/// so `serde_json` turns them into `null`. Keys named in `not_measured` may be `null` legitimately (see
/// `crate::run::Kind::NOT_MEASURED`).
pub fn non_finite(results: &serde_json::Value, not_measured: &[&str]) -> Vec<String> {
    fn walk(v: &serde_json::Value, path: String, skip: &[&str], out: &mut Vec<String>) {
        match v {
            serde_json::Value::Null => {
                let leaf = path.rsplit('.').next().unwrap_or_default();
                let leaf = leaf.split('[').next().unwrap_or_default();
                if !skip.contains(&leaf) {
                    out.push(path)
                }
            }
            serde_json::Value::Number(n) if n.as_f64().is_some_and(|x| !x.is_finite()) => {
                out.push(path)
            }
            serde_json::Value::Array(a) => {
                for (i, e) in a.iter().enumerate() {
                    walk(e, format!("{path}[{i}]"), skip, out);
                }
            }
            serde_json::Value::Object(m) => {
                for (k, e) in m {
                    walk(e, format!("{path}.{k}"), skip, out);
                }
            }
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk(results, "results".into(), not_measured, &mut out);
    out
}
