//! Reading `.skill` files (and their imports) from disk into the pure compiler.

pub use skill_compiler::decode;
use skill_compiler::{Compilation, LoadError};
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

/// Compiles a `.skill` file from disk, reading its imports relative to it.
pub fn compile_path(path: &Path) -> Result<Compilation, ReadError> {
    compile_path_with(path, &[])
}

/// [`compile_path`] with `--param NAME=VALUE` settings.
pub fn compile_path_with(path: &Path, params: &[String]) -> Result<Compilation, ReadError> {
    let name = path.to_string_lossy().replace('\\', "/");
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io {
        path: name.clone(),
        source,
    })?;
    crate::atomic::note_input(path);
    let mut load = |import: &str| -> Result<String, LoadError> {
        crate::atomic::note_input(Path::new(import));
        let bytes = std::fs::read(import).map_err(|err| LoadError {
            reason: err.to_string().to_lowercase(),
        })?;
        String::from_utf8(bytes).map_err(|_| LoadError {
            reason: "not valid UTF-8 text".to_string(),
        })
    };
    Ok(skill_compiler::compile_bytes(&name, bytes, params, &mut load))
}
