//! The commands' errors (`hil sweep`, `merge`, `bench`, `faults`, `compare`): what failed, on
//! which file, and why — each printed as one line after the command's name.

use std::path::{Path, PathBuf};

use crate::scenario::ScenarioError;

/// Why a command stopped.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file or directory could not be read, written, created or opened.
    #[error("{what} {}: {source}", path.display())]
    Io {
        /// What was done: "cannot read", "cannot write", ...
        what: &'static str,
        /// On what.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A file the command wrote earlier (`sweep.json`, `runs.csv`) does not read back.
    #[error("{}: {message}", path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// A scenario, sweep spec or recipe is not valid (file:line, key, hint).
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The host-process firmware could not be built.
    #[error("building the firmware: {0}")]
    Build(std::io::Error),
    /// An output directory holds results that are not this command's (another spec, shard,
    /// recipe or firmware): refused rather than mixed in.
    #[error("{0}")]
    Mismatch(String),
    /// More runs than the harness takes on at once, or none at all.
    #[error("{0}")]
    Size(String),
    /// An I/O error not tied to one file (the worker pool's channel).
    #[error(transparent)]
    Pool(#[from] std::io::Error),
    /// A JSON value could not be written (not expected: the values are the harness's own).
    #[error(transparent)]
    Json(#[from] serde_json::Error),
}

impl Error {
    /// For `map_err`: `what` failed on `path`.
    pub fn io<'a>(what: &'static str, path: &'a Path) -> impl Fn(std::io::Error) -> Error + 'a {
        move |source| Error::Io {
            what,
            path: path.to_path_buf(),
            source,
        }
    }

    /// For `map_err`: `path` does not read back.
    pub fn unreadable<'a, E: std::fmt::Display>(path: &'a Path) -> impl Fn(E) -> Error + 'a {
        move |e| Error::Unreadable {
            path: path.to_path_buf(),
            message: e.to_string(),
        }
    }
}
