//! Progress of long computations as the commands report it: phases ("engine ROM",
//! "transient: step 400 of 6000") and counted steps (a sweep's runs). The library only says
//! what happens; a front end installed once per process ([`set_front_end`]) shows it (the
//! command-line tool: a spinner or bar on a terminal, nothing otherwise). Without one, nothing
//! is shown.

use std::sync::OnceLock;

/// A front end's view of one long computation.
pub trait Indicator: Send + Sync {
    /// The current phase.
    fn phase(&self, msg: &str);
    /// One counted step done (for an indicator made with a total).
    fn inc(&self);
    /// The computation ended: clear the display.
    fn finish(&self);
}

/// Makes an indicator: for phases (`None`) or for `Some(total)` counted steps; None shows
/// nothing (not a terminal).
pub type FrontEnd = fn(Option<u64>) -> Option<Box<dyn Indicator>>;

static FRONT_END: OnceLock<FrontEnd> = OnceLock::new();

/// Installs the process's front end (the first call wins).
pub fn set_front_end(f: FrontEnd) {
    let _ = FRONT_END.set(f);
}

/// The progress of one computation, shown by the installed front end (if any) and cleared
/// when dropped.
#[derive(Default)]
pub struct Progress {
    indicator: Option<Box<dyn Indicator>>,
}

impl Progress {
    /// Progress shown as phases.
    pub fn new() -> Self {
        Self::make(None)
    }

    /// Progress counted in `total` steps.
    pub fn counter(total: u64) -> Self {
        Self::make(Some(total))
    }

    fn make(total: Option<u64>) -> Self {
        Self {
            indicator: FRONT_END.get().and_then(|f| f(total)),
        }
    }

    pub fn phase(&self, msg: &str) {
        if let Some(i) = &self.indicator {
            i.phase(msg);
        }
    }

    pub fn inc(&self) {
        if let Some(i) = &self.indicator {
            i.inc();
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if let Some(i) = &self.indicator {
            i.finish();
        }
    }
}
