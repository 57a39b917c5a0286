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

/// The largest `.skill` file read, imports included: the standard skills are 2-6 KiB, so a
/// file this size is no template but a mistake (a log, a device, a disk image).
pub const MAX_SOURCE_BYTES: u64 = 8 << 20;

/// Reads the source file at `path` when it is a regular file of at most
/// [`MAX_SOURCE_BYTES`]: a device (`/dev/zero`), a FIFO, a socket or standard input would block
/// or never end, so each is refused by what it is before it is opened.
pub fn read_source(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read as _;
    let what = std::fs::metadata(path)?.file_type();
    if !what.is_file() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{} is not a regular file; only files are read", kind_of(&what)),
        ));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(MAX_SOURCE_BYTES + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_SOURCE_BYTES {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "it is larger than {} MiB, the most a .skill file may hold",
                MAX_SOURCE_BYTES >> 20
            ),
        ));
    }
    Ok(bytes)
}

/// What a file that is not a regular one is, in words.
fn kind_of(what: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if what.is_fifo() {
            return "a FIFO";
        }
        if what.is_socket() {
            return "a socket";
        }
        if what.is_char_device() || what.is_block_device() {
            return "a device";
        }
    }
    if what.is_dir() {
        "a folder"
    } else {
        "not a regular file"
    }
}

/// Compiles a `.skill` file from disk, reading its imports relative to it.
pub fn compile_path(path: &Path) -> Result<Compilation, ReadError> {
    compile_path_with(path, &[])
}

/// [`compile_path`] with `--param NAME=VALUE` settings.
pub fn compile_path_with(path: &Path, params: &[String]) -> Result<Compilation, ReadError> {
    let name = path.to_string_lossy().replace('\\', "/");
    let bytes = read_source(path).map_err(|source| ReadError::Io {
        path: name.clone(),
        source,
    })?;
    crate::atomic::note_input(path);
    let mut load = |import: &str| -> Result<String, LoadError> {
        crate::atomic::note_input(Path::new(import));
        let bytes = read_source(Path::new(import)).map_err(|err| LoadError {
            // The OS's words lower-cased, as the rest of a diagnostic; ours as written.
            reason: match err.raw_os_error() {
                Some(_) => err.to_string().to_lowercase(),
                None => err.to_string(),
            },
        })?;
        String::from_utf8(bytes).map_err(|_| LoadError {
            reason: "not valid UTF-8 text".to_string(),
        })
    };
    Ok(skill_compiler::compile_bytes(&name, bytes, params, &mut load))
}
