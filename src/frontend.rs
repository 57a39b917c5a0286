//! Reading `.skill` files (and their imports) from disk into the pure compiler.

use skill_compiler::{Code, Compilation, Diag, LoadError, SourceFile, Span};
use std::path::Path;

/// Why a file named on the command line could not be compiled at all.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be read.
    #[error("cannot read `{path}`: {source}")]
    Io {
        /// The path as given.
        path: String,
        /// The OS error.
        source: std::io::Error,
    },
}

/// Turns raw bytes into a source file, or a diagnostic pointing at the first invalid byte.
pub fn decode(name: &str, bytes: Vec<u8>) -> Result<SourceFile, Box<(SourceFile, Diag)>> {
    match String::from_utf8(bytes) {
        Ok(text) => Ok(SourceFile::new(name, text)),
        Err(err) => {
            let valid_up_to = err.utf8_error().valid_up_to();
            let lossy = String::from_utf8_lossy(err.as_bytes()).into_owned();
            // Offsets in the lossy text match up to the first invalid byte.
            let source = SourceFile::new(name, lossy);
            let diag = Diag::new(
                Code::InvalidUtf8,
                0,
                Span::new(valid_up_to, valid_up_to + 1),
                format!("`{name}` is not valid UTF-8 text"),
                "invalid byte here",
            )
            .help("skill templates are UTF-8 text; is this a binary file?");
            Err(Box::new((source, diag)))
        }
    }
}

/// Compiles a `.skill` file from disk, reading its imports relative to it.
pub fn compile_path(path: &Path) -> Result<Compilation, ReadError> {
    let name = path.to_string_lossy().replace('\\', "/");
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io {
        path: name.clone(),
        source,
    })?;
    let root = match decode(&name, bytes) {
        Ok(root) => root,
        Err(invalid) => {
            let (source, diag) = *invalid;
            return Ok(Compilation {
                files: vec![source],
                diags: vec![diag],
                ast: Default::default(),
                program: None,
            });
        }
    };
    let mut load = |import: &str| -> Result<String, LoadError> {
        let bytes = std::fs::read(import).map_err(|err| LoadError {
            reason: err.to_string().to_lowercase(),
        })?;
        String::from_utf8(bytes).map_err(|_| LoadError {
            reason: "not valid UTF-8 text".to_string(),
        })
    };
    Ok(skill_compiler::compile(root, &mut load))
}
