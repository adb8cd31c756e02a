//! The stop request of a run: raised by Ctrl-C (SIGINT) or SIGTERM at the command line, or by a caller; the run
//! loop checks it between chunks, writes a checkpoint and the outputs so far, and stops (exit code 130).
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A stop request shared between a run and whoever may stop it (cheap to clone; clones share the flag).
#[derive(Clone, Debug, Default)]
pub struct Stop(Arc<AtomicBool>);

impl Stop {
    /// A fresh request, not raised.
    pub fn new() -> Self {
        Self::default()
    }

    /// Raise the request.
    pub fn request(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether the request is raised.
    pub fn requested(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }

    /// Lower the request (before starting another run with the same flag).
    pub fn clear(&self) {
        self.0.store(false, Ordering::SeqCst);
    }

    /// Raise this request on Ctrl-C (SIGINT) and SIGTERM; a second signal exits at once with code 130. Call
    /// once per process (the command line does). Failing to install the handler only loses the graceful stop,
    /// so that is a warning, not an error.
    pub fn install_signal_handler(&self) {
        let flag = self.0.clone();
        let result = ctrlc::set_handler(move || {
            if flag.swap(true, Ordering::SeqCst) {
                eprintln!("\nlbdem: second interrupt, exiting without a checkpoint");
                std::process::exit(130);
            }
            eprintln!("\nlbdem: interrupt received, writing a checkpoint (Ctrl-C again to abort)…");
        });
        if let Err(e) = result {
            eprintln!(
                "lbdem: warning: cannot install the Ctrl-C handler ({e}); Ctrl-C will stop without a checkpoint"
            );
        }
    }
}
