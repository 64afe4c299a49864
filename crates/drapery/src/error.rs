//! The library's error type. Errors are values: the library never prints and never exits.

/// Everything that can go wrong in drapery, with enough context to name the file,
/// the field or the element at fault.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad input in a file: `path` names the file, `message` the field or line at fault.
    #[error("{path}: {message}")]
    Input {
        /// The file (scene, mesh) at fault.
        path: String,
        /// What is wrong, naming the field, line or element.
        message: String,
    },
    /// A value given through the library API is out of range or inconsistent.
    #[error("{0}")]
    Invalid(String),
    /// A field of a scene or model description is out of range or inconsistent. `field` is
    /// its path in the scene's terms (`cloth[0].stretch_stiffness`, `solver.tolerance`), which
    /// each front end words: the TOML loader adds the file and the line.
    #[error("{field}: {message}")]
    Field {
        /// Path of the field at fault, `table[index].key` or `table.key`.
        field: String,
        /// What is wrong with it (`must be a finite number ≥ 0, got -1`).
        message: String,
    },
    /// A time step failed: non-finite state, a solver that did not converge, or an energy blow-up.
    #[error("simulation failed at step {step} (t = {time:.6} s): {reason}")]
    StepFailed {
        /// Index of the step that failed (0-based).
        step: u64,
        /// Simulated time at the start of that step.
        time: f64,
        /// What went wrong and where.
        reason: String,
    },
    /// An I/O error on a named file. The message includes the underlying error's, which is
    /// therefore not also given as [`std::error::Error::source`] (an error chain printed
    /// whole would repeat it).
    #[error("{path}: {cause}")]
    Io {
        /// The file that could not be read or written.
        path: String,
        /// The underlying error.
        cause: std::io::Error,
    },
}

impl Error {
    /// Shorthand for an [`Error::Input`].
    pub fn input(path: impl std::fmt::Display, message: impl Into<String>) -> Self {
        Error::Input {
            path: path.to_string(),
            message: message.into(),
        }
    }
    /// Shorthand for an [`Error::Field`].
    pub fn field(field: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Field {
            field: field.into(),
            message: message.into(),
        }
    }
    /// Shorthand for an [`Error::Io`].
    pub fn io(path: impl std::fmt::Display, cause: std::io::Error) -> Self {
        Error::Io {
            path: path.to_string(),
            cause,
        }
    }
}

/// Result alias used across the crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_io_error_names_the_file_and_its_cause_once() {
        let e = Error::io("frames/f.obj", std::io::Error::other("disk on fire"));
        let mut text = e.to_string();
        // what a caller printing the whole chain (anyhow's `{:#}`) would add
        let mut next = std::error::Error::source(&e);
        while let Some(s) = next {
            text += &format!(": {s}");
            next = s.source();
        }
        assert_eq!(text, "frames/f.obj: disk on fire");
    }
}
