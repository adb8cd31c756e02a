//! `lbdem resume DIR`: continue an interrupted run from `DIR/checkpoint.bin` with the scene copy
//! `DIR/scene.toml` saved at its start. The checkpoint header's kind tag picks the run loop; a new scene kind
//! driven by [`crate::longrun::LongRun`] adds one arm to [`resume`].
use std::path::Path;

use crate::checkpoint::{Checkpoint, CHECKPOINT_FILE};
use crate::coupled_demo::{resume_demo, DemoOptions, DEMO_KIND};
use crate::error::{LbdemError, Result};
use crate::solid::scene::{resume_dry, DRY_KIND};

/// Continue the run in `dir` to its end.
pub fn resume(dir: &Path, quiet: bool) -> Result<()> {
    let path = dir.join(CHECKPOINT_FILE);
    if !path.exists() {
        let hint = if dir.join("summary.json").exists() {
            "this directory holds a finished run from before checkpoints were written; nothing to resume"
        } else {
            "give the output directory of a run started with `lbdem run SCENE --out DIR`"
        };
        return Err(LbdemError::Checkpoint {
            path: path.display().to_string(),
            problem: "does not exist".into(),
            hint: hint.into(),
        });
    }
    let header = Checkpoint::read_header(&path)?;
    match header.kind.as_str() {
        DRY_KIND => resume_dry(dir, quiet, None).map(|_| ()),
        crate::fracture::FRACTURE_KIND => crate::fracture::resume_fracture(dir, quiet).map(|_| ()),
        DEMO_KIND => resume_demo(
            dir,
            &DemoOptions {
                quiet,
                ..Default::default()
            },
        ),
        other => Err(LbdemError::Checkpoint {
            path: path.display().to_string(),
            problem: format!("was written by a `{other}` run, which this lbdem cannot resume"),
            hint: "resume it with the lbdem version that wrote it".into(),
        }),
    }
}
