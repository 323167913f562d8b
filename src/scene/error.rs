//! Errors from loading a scene: each names the file and, where there is one, the line or field.

use std::path::PathBuf;

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// (`error` is part of the message, not a `source`: shown with its causes, as the
    /// command does, it would otherwise be repeated.)
    #[error("{}: {}", one_line(path.display()), one_line(error))]
    Io { path: PathBuf, error: std::io::Error },
    /// TOML syntax or schema error; `message` carries the line and column.
    #[error("{}: {}", one_line(path.display()), one_line(message))]
    Toml { path: PathBuf, message: String },
    /// A value that parsed but makes no sense (NaN, out of range, unknown name).
    #[error("{}: field `{}`: {}", one_line(path.display()), one_line(field), one_line(message))]
    Field { path: PathBuf, field: String, message: String },
    /// A malformed OBJ or MTL line.
    #[error("{}:{line}: {}", one_line(path.display()), one_line(message))]
    Line { path: PathBuf, line: usize, message: String },
    /// A glTF value that is malformed or cannot be drawn, at its JSON path
    /// (`meshes[0].primitives[1].attributes["POSITION"]`).
    #[error("{}: {}: {}", one_line(path.display()), one_line(at), one_line(message))]
    Json { path: PathBuf, at: String, message: String },
    /// A problem in a whole file, with no single line to blame.
    #[error("{}: {}", one_line(path.display()), one_line(message))]
    File { path: PathBuf, message: String },
}

/// `s` with control characters and line separators escaped, so that an error naming a file or
/// quoting the input stays on one line (a file named `a\nb.obj` is shown as `a\\nb.obj`).
pub fn one_line(s: impl std::fmt::Display) -> String {
    let s = s.to_string();
    if !s.chars().any(|c| c.is_control() || matches!(c, '\u{2028}' | '\u{2029}')) {
        return s;
    }
    s.chars()
        .map(|c| {
            if c.is_control() || matches!(c, '\u{2028}' | '\u{2029}') {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

impl SceneError {
    /// The file the error is about.
    pub fn path(&self) -> &std::path::Path {
        match self {
            SceneError::Io { path, .. }
            | SceneError::Toml { path, .. }
            | SceneError::Field { path, .. }
            | SceneError::Line { path, .. }
            | SceneError::Json { path, .. }
            | SceneError::File { path, .. } => path,
        }
    }

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
