//! Typed errors of the library. Every variant renders as one sentence that names the
//! culprit (file, element, parameter), so the command line can print it as it is.

use std::path::PathBuf;

/// Result alias for the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in shadowlab.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read.
    #[error("{path} {reason}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why, as a phrase that follows the path: "does not exist", "is a FIFO (named
        /// pipe), not a regular file", ….
        reason: String,
    },
    /// A scene or mesh file is malformed; `what` names the element and the problem.
    #[error("{path}: {what}")]
    Format {
        /// The file.
        path: PathBuf,
        /// The element at fault and what is wrong with it.
        what: String,
    },
    /// The scene is unusable (empty, non-finite, …).
    #[error("scene {scene}: {what}")]
    Scene {
        /// The scene's name or path.
        scene: String,
        /// What is wrong.
        what: String,
    },
    /// A parameter is unknown or out of range.
    #[error("{0}")]
    Param(String),
    /// A resource limit would be exceeded.
    #[error("{0}")]
    Limit(String),
    /// Writing an output failed.
    #[error("cannot write {path}: {what}")]
    Output {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        what: String,
    },
    /// shadowlab itself is at fault: an invariant broke (exit code 1, not the user's input).
    #[error("internal error: {0}")]
    Internal(String),
}

impl Error {
    /// A parameter error.
    pub fn param(msg: impl Into<String>) -> Self {
        Error::Param(msg.into())
    }

    /// A file that cannot be read; `reason` follows its path in the sentence.
    pub fn io(path: impl Into<PathBuf>, reason: impl Into<String>) -> Self {
        Error::Io {
            path: path.into(),
            reason: reason.into(),
        }
    }

    /// A format error for `path`.
    pub fn format(path: impl Into<PathBuf>, what: impl Into<String>) -> Self {
        Error::Format {
            path: path.into(),
            what: what.into(),
        }
    }

    /// True when the error is the user's input (exit code 2), false for other failures
    /// (exit code 1). Every kind is named, so a new one must say which it is.
    pub fn is_bad_input(&self) -> bool {
        match self {
            // A file that cannot be read, a malformed file, an unusable scene, a parameter,
            // a limit the input would exceed: all the user's input.
            Error::Io { .. }
            | Error::Format { .. }
            | Error::Scene { .. }
            | Error::Param(_)
            | Error::Limit(_) => true,
            // Writing an output failed after its checks passed, or shadowlab's own
            // invariant broke.
            Error::Output { .. } | Error::Internal(_) => false,
        }
    }
}
