//! `fairline._native`: the thin PyO3 layer between numpy and the `fairline`
//! library. Every function here takes plain arrays (positions `V` as an
//! (n, 3) float64 array, faces as a flat `u32` index array plus offsets, as
//! in [`fairline::Soup`]), options with the CLI's names and defaults, and
//! returns arrays plus the report as JSON text (the keys of the CLI's
//! `--report`). The pure-Python package `fairline` (python/fairline) wraps
//! these with shape/dtype checks, docstrings and numpy/trimesh conversions.
//!
//! The commands themselves (which steps, which report, which warnings) are
//! the command layer's (`fairline_commands`), shared with the CLI and the
//! workbench; this layer converts arrays and errors.
//!
//! Every computation runs with the GIL released (`Python::detach`), and
//! Ctrl-C stops it within a second ([`compute`]).

#![forbid(unsafe_code)]

mod commands;
mod curves;
mod mesh;
mod surfaces;

use fairline::{Soup, SurfaceMesh, Vec3};
use numpy::{
    PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyType;

/// What kind of failure an error is; decides the Python exception class
/// (python/fairline/_errors.py), in step with the CLI's exit status.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Bad input or options (CLI exit status 2): `FairlineError`, a ValueError.
    BadInput,
    /// A file could not be opened, read or written by the operating system:
    /// `FairlineFileError` (also an OSError).
    File,
    /// The computation failed (CLI exit status 1):
    /// `FairlineComputationError` (also a RuntimeError).
    Computation,
    /// A signal handler raised while the computation ran (Ctrl-C): its
    /// exception, a KeyboardInterrupt, is raised as it is ([`compute`]).
    Interrupted,
}

/// An error on its way to Python: its kind and the message the CLI prints
/// after `error: `.
#[derive(Debug)]
pub struct Failure {
    pub kind: Kind,
    pub message: String,
}

impl Failure {
    pub fn bad(message: impl Into<String>) -> Self {
        Failure {
            kind: Kind::BadInput,
            message: message.into(),
        }
    }
    pub fn computation(message: impl Into<String>) -> Self {
        Failure {
            kind: Kind::Computation,
            message: message.into(),
        }
    }
}

impl From<fairline::io::IoError> for Failure {
    fn from(e: fairline::io::IoError) -> Self {
        let kind = match &e {
            fairline::io::IoError::Io { .. } => Kind::File,
            _ => Kind::BadInput,
        };
        Failure {
            kind,
            message: e.to_string(),
        }
    }
}

impl From<fairline_commands::CommandError> for Failure {
    /// The command layer's kinds as the Python exception classes; the
    /// message worded with the package's keyword names, the region named
    /// `region` and the lights `lights`.
    fn from(e: fairline_commands::CommandError) -> Self {
        use fairline_commands::{ErrorKind, FrontEnd, Subject};
        let kind = match e.kind() {
            ErrorKind::BadInput => Kind::BadInput,
            ErrorKind::Io => Kind::File,
            ErrorKind::Computation | ErrorKind::Cancelled => Kind::Computation,
        };
        let message = e.message(FrontEnd::Python);
        let message = match e.subject() {
            Some(Subject::Region) => format!("region: {message}"),
            Some(Subject::Lights) => format!("lights: {message}"),
            _ => message,
        };
        Failure { kind, message }
    }
}

impl From<fairline::MeshError> for Failure {
    /// The library's message, with the CLI's `repair` hint in the
    /// package's words when repair fixes it (a non-manifold edge …).
    fn from(e: fairline::MeshError) -> Self {
        let hint =
            fairline_commands::repair::repair_hint(&e, fairline_commands::FrontEnd::Python, None);
        match hint {
            Some(h) => Failure::bad(format!("{e}; hint: {h}")),
            None => Failure::bad(e.to_string()),
        }
    }
}

impl From<Failure> for PyErr {
    fn from(f: Failure) -> PyErr {
        let class = match f.kind {
            Kind::BadInput => "FairlineError",
            Kind::File => "FairlineFileError",
            Kind::Computation => "FairlineComputationError",
            Kind::Interrupted => {
                return INTERRUPTION
                    .with(|i| i.borrow_mut().take())
                    .unwrap_or_else(|| pyo3::exceptions::PyKeyboardInterrupt::new_err(()));
            }
        };
        Python::attach(|py| {
            let cls = py
                .import("fairline._errors")
                .and_then(|m| m.getattr(class))
                .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
            match cls {
                Ok(cls) => PyErr::from_type(cls, f.message),
                // the package is always importable when this module is; if
                // not, a plain ValueError still carries the message
                Err(_) => pyo3::exceptions::PyValueError::new_err(f.message),
            }
        })
    }
}

pub type Res<T> = Result<T, Failure>;

/// Positions and faces from the arrays the Python layer hands over.
///
/// `v` must be (n, 3); `offsets` must start at 0, never decrease and end at
/// `indices.len()` (the Python layer builds them; checked again here so
/// that no input can panic).
pub fn soup_from(
    v: &PyReadonlyArray2<'_, f64>,
    indices: &PyReadonlyArray1<'_, u32>,
    offsets: &PyReadonlyArray1<'_, u32>,
) -> Res<Soup> {
    let shape = v.shape();
    if shape.len() != 2 || shape[1] != 3 {
        return Err(Failure::bad(format!(
            "V must have shape (n, 3), got {shape:?}"
        )));
    }
    // contiguous arrays (what the Python layer passes) are copied in one go
    let positions: Vec<Vec3> = match v.as_slice() {
        Ok(flat) => flat
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect(),
        Err(_) => v
            .as_array()
            .rows()
            .into_iter()
            .map(|r| Vec3::new(r[0], r[1], r[2]))
            .collect(),
    };
    let copy = |a: &PyReadonlyArray1<'_, u32>| -> Vec<u32> {
        match a.as_slice() {
            Ok(s) => s.to_vec(),
            Err(_) => a.as_array().iter().copied().collect(),
        }
    };
    let indices = copy(indices);
    let offsets = copy(offsets);
    if offsets.first() != Some(&0)
        || offsets.windows(2).any(|w| w[1] < w[0])
        || offsets.last().map(|&o| o as usize) != Some(indices.len())
    {
        return Err(Failure::bad(
            "F: face offsets must start at 0, never decrease and end at the number of indices",
        ));
    }
    Ok(Soup {
        positions,
        offsets,
        indices,
    })
}

/// A [`SurfaceMesh`] from the arrays (errors as the library names them:
/// `face 3 refers to vertex 10, but the mesh has 5 vertices`).
pub fn mesh_from(soup: &Soup) -> Res<SurfaceMesh> {
    Ok(SurfaceMesh::from_soup(soup)?)
}

/// Positions as an (n, 3) array.
pub fn positions_array<'py>(py: Python<'py>, p: &[Vec3]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = p.iter().flat_map(|q| q.to_array()).collect();
    // the flat vector has exactly 3 n entries, so the reshape cannot fail
    PyArray1::from_vec(py, flat)
        .reshape([p.len(), 3])
        .unwrap_or_else(|_| PyArray2::zeros(py, [0, 3], false))
}

/// Positions and faces of a soup as (V, indices, offsets).
pub type SoupArrays<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray1<u32>>,
);

pub fn soup_arrays<'py>(py: Python<'py>, soup: &Soup) -> SoupArrays<'py> {
    (
        positions_array(py, &soup.positions),
        PyArray1::from_slice(py, &soup.indices),
        PyArray1::from_slice(py, &soup.offsets),
    )
}

/// How often a computation in progress looks for a pending signal
/// (Ctrl-C): well inside the one second a KeyboardInterrupt may take.
const SIGNAL_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// How long an interrupted computation is given to stop at its next
/// checkpoint before the KeyboardInterrupt is raised anyway (the run then
/// ends in the background, its result dropped).
const STOP_GRACE: std::time::Duration = std::time::Duration::from_millis(400);

thread_local! {
    /// The exception a signal handler raised during [`compute`] (a
    /// KeyboardInterrupt for Ctrl-C), raised in place of its [`Failure`].
    static INTERRUPTION: std::cell::RefCell<Option<PyErr>> = const { std::cell::RefCell::new(None) };
}

/// What a computation sends back: its result, or the payload of its panic.
type Finished<T> = std::thread::Result<Res<T>>;

/// Runs `f` with the GIL released, on a worker of rayon's pool as the CLI
/// runs its commands (crates/fairline-cli/src/main.rs): the library's
/// parallel loops then start from a worker instead of handing every loop to
/// the pool and sleeping until it is done.
///
/// Meanwhile the calling thread looks for signals every [`SIGNAL_POLL`]
/// (`Python::check_signals`, with the GIL taken for that moment): when a
/// handler raises (Ctrl-C: KeyboardInterrupt), the run's [`Control`] is
/// cancelled, so the algorithm stops at its next checkpoint, and the
/// exception is raised within [`STOP_GRACE`] whether or not it has stopped.
/// A panic in `f` is passed on to the caller.
///
/// [`Control`]: fairline::Control
pub fn compute<T: Send + 'static>(
    py: Python<'_>,
    f: impl FnOnce(&fairline::Control) -> Res<T> + Send + 'static,
) -> Res<T> {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::mpsc::RecvTimeoutError;
    let flag = std::sync::Arc::new(AtomicBool::new(false));
    let control = fairline::Control::new().cancel_flag(std::sync::Arc::clone(&flag));
    let (tx, mut rx) = std::sync::mpsc::channel::<Finished<T>>();
    rayon::spawn(move || {
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(&control)));
        // the caller may have gone (interrupted): the result is dropped
        let _ = tx.send(result);
    });
    let wait = |py: Python<'_>, rx: std::sync::mpsc::Receiver<Finished<T>>, timeout| {
        py.detach(move || {
            let got = rx.recv_timeout(timeout);
            (rx, got)
        })
    };
    loop {
        let (back, got) = wait(py, rx, SIGNAL_POLL);
        rx = back;
        match got {
            Ok(Ok(result)) => return result,
            Ok(Err(panic)) => std::panic::resume_unwind(panic),
            Err(RecvTimeoutError::Disconnected) => {
                return Err(Failure::computation(
                    "the computation ended without a result",
                ));
            }
            Err(RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals() {
                    flag.store(true, Ordering::Relaxed);
                    // a run that stops in time frees its memory before the
                    // exception is seen; its result is dropped either way
                    let _ = wait(py, rx, STOP_GRACE);
                    INTERRUPTION.with(|i| *i.borrow_mut() = Some(e));
                    return Err(Failure {
                        kind: Kind::Interrupted,
                        message: "interrupted".into(),
                    });
                }
            }
        }
    }
}

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    commands::register(m)?;
    mesh::register(m)?;
    surfaces::register(m)?;
    Ok(())
}
