//! Errors from loading a scene: each names the file and, where there is one, the line or field.

use std::path::PathBuf;

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    /// TOML syntax or schema error; `message` carries the line and column.
    #[error("{}: {message}", path.display())]
    Toml { path: PathBuf, message: String },
    /// A value that parsed but makes no sense (NaN, out of range, unknown name).
    #[error("{}: field `{field}`: {message}", path.display())]
    Field { path: PathBuf, field: String, message: String },
    /// A malformed OBJ or MTL line.
    #[error("{}:{line}: {message}", path.display())]
    Line { path: PathBuf, line: usize, message: String },
    /// A problem in a whole file, with no single line to blame.
    #[error("{}: {message}", path.display())]
    File { path: PathBuf, message: String },
}

impl SceneError {
    pub(crate) fn field(
        path: &std::path::Path,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        SceneError::Field { path: path.to_owned(), field: field.into(), message: message.into() }
    }

    pub(crate) fn line(path: &std::path::Path, line: usize, message: impl Into<String>) -> Self {
        SceneError::Line { path: path.to_owned(), line, message: message.into() }
    }

    pub(crate) fn file(path: &std::path::Path, message: impl Into<String>) -> Self {
        SceneError::File { path: path.to_owned(), message: message.into() }
    }
}
