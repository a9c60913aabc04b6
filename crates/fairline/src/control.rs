//! The one shape every algorithm has, and the hooks a caller uses to watch
//! and stop a long run.
//!
//! Every algorithm of the crate is a function over the mesh (or the
//! surfaces) and an options struct, returning `Result<Output, Error>`:
//!
//! ```text
//! pub fn taubin_smooth(mesh: &SurfaceMesh, options: &TaubinOptions)
//!     -> Result<Output<SmoothReport>, SmoothError>
//! ```
//!
//! - The options struct implements `Default`, has a builder setter per
//!   field and is `#[non_exhaustive]`, so fields can be added without
//!   breaking callers. Fixed vertices are always `fixed: Vec<VertexId>`
//!   (builder `.fixed(…)`); a region is always the faces it holds,
//!   `region: Vec<FaceId>` (builder `.region(…)`); reading either from a
//!   file is the job of [`crate::io`].
//! - The input is never modified; [`Output`] carries the new positions (or
//!   [`SurfaceOutput`] the new surfaces) and a report that derives
//!   `serde::Serialize`, so every front end (CLI, workbench, Python) writes
//!   the same JSON.
//! - Long algorithms take a [`Control`] in their options (builder
//!   `.control(…)`): it receives [`Progress`] and, when the caller raises
//!   the cancel flag, the algorithm stops at its next checkpoint and returns
//!   its error type's `Cancelled` variant (built from [`Cancelled`]).

use crate::Vec3;
use serde::Serialize;
use std::fmt;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Builder setters `pub fn field(mut self, v: T) -> Self`, one per listed
/// field, for the options structs of the crate (the one shape: a builder
/// setter per field).
macro_rules! setters {
    ($ty:ident { $($field:ident: $t:ty),* $(,)? }) => {
        impl $ty {
            $(
                #[doc = concat!("Sets [`", stringify!($ty), "::", stringify!($field), "`].")]
                pub fn $field(mut self, v: $t) -> Self {
                    self.$field = v;
                    self
                }
            )*
        }
    };
}
pub(crate) use setters;

/// What an algorithm over a mesh returns: the new vertex positions (one per
/// vertex, in vertex order; the input mesh is untouched) and its report.
#[derive(Clone, Debug, PartialEq)]
pub struct Output<R> {
    /// New position of every vertex.
    pub positions: Vec<Vec3>,
    /// What the run did (serialises to the JSON `--report` of the CLI).
    pub report: R,
}

/// What an algorithm over B-spline surfaces returns: the new surfaces and
/// the report.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceOutput<S, R> {
    /// The new surfaces (or surface).
    pub surfaces: S,
    /// What the run did.
    pub report: R,
}

/// Where a long run is: `done` of `total` units of the named `stage`
/// (iterations, lights, rows …). `total` is 0 when it is not known.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Progress {
    /// Short lower-case name of the stage ("iterations", "lights" …).
    pub stage: &'static str,
    /// Units done.
    pub done: u64,
    /// Units in all (0: unknown).
    pub total: u64,
}

/// The run was cancelled through [`Control::cancel`] or the caller's flag.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("cancelled")]
pub struct Cancelled;

type ProgressFn = dyn Fn(Progress) + Send + Sync;

/// Progress callback and cancellation flag of one run. Cheap to clone (two
/// `Arc`s); the default watches nothing and never cancels.
#[derive(Clone, Default)]
pub struct Control {
    progress: Option<Arc<ProgressFn>>,
    cancel: Option<Arc<AtomicBool>>,
}

impl fmt::Debug for Control {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Control")
            .field("progress", &self.progress.is_some())
            .field("cancelled", &self.is_cancelled())
            .finish()
    }
}

impl PartialEq for Control {
    /// Two controls are equal when they share the same callback and flag
    /// (options structs derive `PartialEq`; a control never changes results).
    fn eq(&self, other: &Self) -> bool {
        let same_progress = match (&self.progress, &other.progress) {
            (None, None) => true,
            (Some(a), Some(b)) => Arc::ptr_eq(a, b),
            _ => false,
        };
        let same_cancel = match (&self.cancel, &other.cancel) {
            (None, None) => true,
            (Some(a), Some(b)) => Arc::ptr_eq(a, b),
            _ => false,
        };
        same_progress && same_cancel
    }
}

impl Control {
    /// A control that watches nothing and never cancels.
    pub fn new() -> Self {
        Self::default()
    }

    /// Call `f` with every progress step (from the thread running the
    /// algorithm; keep it quick).
    pub fn on_progress(mut self, f: impl Fn(Progress) + Send + Sync + 'static) -> Self {
        self.progress = Some(Arc::new(f));
        self
    }

    /// Stop the run at its next checkpoint once `flag` becomes true.
    pub fn cancel_flag(mut self, flag: Arc<AtomicBool>) -> Self {
        self.cancel = Some(flag);
        self
    }

    /// A control for one part of this run: the same cancel flag, and each
    /// progress step passed through `map` before this control's callback
    /// gets it (e.g. offset into the steps of the whole run).
    pub fn mapped(&self, map: impl Fn(Progress) -> Progress + Send + Sync + 'static) -> Control {
        let progress: Option<Arc<ProgressFn>> = self.progress.clone().map(|outer| {
            let f: Arc<ProgressFn> = Arc::new(move |p| outer(map(p)));
            f
        });
        Control {
            progress,
            cancel: self.cancel.clone(),
        }
    }

    /// Raise the cancel flag (creates none: without
    /// [`Control::cancel_flag`] this does nothing).
    pub fn cancel(&self) {
        if let Some(flag) = &self.cancel {
            flag.store(true, Ordering::Relaxed);
        }
    }

    /// Whether the caller asked to stop.
    pub fn is_cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|flag| flag.load(Ordering::Relaxed))
    }

    /// Report progress (no check for cancellation).
    pub fn progress(&self, stage: &'static str, done: u64, total: u64) {
        if let Some(f) = &self.progress {
            f(Progress { stage, done, total });
        }
    }

    /// A checkpoint: `Err(Cancelled)` once the caller asked to stop.
    pub fn checkpoint(&self) -> Result<(), Cancelled> {
        if self.is_cancelled() {
            Err(Cancelled)
        } else {
            Ok(())
        }
    }

    /// Report progress, then check for cancellation: the call an iteration
    /// loop makes once per step.
    pub fn step(&self, stage: &'static str, done: u64, total: u64) -> Result<(), Cancelled> {
        self.progress(stage, done, total);
        self.checkpoint()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[test]
    fn default_control_never_cancels_and_reports_nowhere() {
        let c = Control::new();
        c.cancel();
        assert!(!c.is_cancelled());
        assert_eq!(c.step("iterations", 1, 2), Ok(()));
    }

    #[test]
    fn progress_reaches_the_callback_and_the_flag_stops_the_run() {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&seen);
        let flag = Arc::new(AtomicBool::new(false));
        let c = Control::new()
            .on_progress(move |p| sink.lock().map(|mut v| v.push(p)).unwrap_or(()))
            .cancel_flag(Arc::clone(&flag));
        assert_eq!(c.step("lights", 1, 3), Ok(()));
        flag.store(true, Ordering::Relaxed);
        assert_eq!(c.step("lights", 2, 3), Err(Cancelled));
        let seen = seen.lock().map(|v| v.clone()).unwrap_or_default();
        assert_eq!(seen.len(), 2);
        assert_eq!(
            seen[1],
            Progress {
                stage: "lights",
                done: 2,
                total: 3
            }
        );
        let copy = c.clone();
        assert_eq!(copy, c);
        assert_ne!(Control::new().cancel_flag(flag), c);
    }
}
