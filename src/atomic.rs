//! Writing output files without destroying anything: atomic replacement of regular files,
//! symlinks written through to their target, device nodes written directly, everything else
//! (directories, FIFOs, sockets, block devices) refused; and the check that an output is not
//! one of the command's inputs.
//!
//! What [`write()`] does with an output path:
//!
//! - a regular file, or nothing yet: a temporary file beside it, then a rename over it, so a
//!   reader never sees a half-written output (an existing file's permissions are kept);
//! - a symlink: the same, on the file the link points to (followed to the end, also when it
//!   dangles); the link itself stays, so `skillc fmt link.skill` formats the file behind it;
//! - a character device (`/dev/null`, `/dev/stdout`, a terminal): written directly, as a shell
//!   redirection would; a device cannot be replaced by a rename and is not a file to keep;
//! - anything else (a directory, a FIFO, a socket, a block device): refused with a message.
//!   A FIFO with no reader would block forever, and a block device is a disk.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Symlinks followed before giving up (the kernel's own limit is 40).
const MAX_LINKS: usize = 40;

/// Writes `contents` to `path` as the module docs describe.
pub fn write(path: &Path, contents: &[u8]) -> std::io::Result<()> {
    let target = resolve_links(path)?;
    match std::fs::metadata(&target) {
        Ok(meta) if meta.is_file() => replace(&target, contents, Some(meta.permissions())),
        Ok(meta) if is_char_device(&meta) => {
            let mut file = std::fs::OpenOptions::new().write(true).open(&target)?;
            file.write_all(contents)?;
            file.flush()
        }
        Ok(meta) if meta.is_dir() => Err(std::io::Error::other("it is a directory")),
        Ok(_) => Err(std::io::Error::other(
            "it is not a regular file (a FIFO, socket or block device); skillc writes regular files and character devices such as /dev/null only",
        )),
        Err(err) if err.kind() == std::io::ErrorKind::NotFound => replace(&target, contents, None),
        Err(err) => Err(err),
    }
}

/// The path a write to `path` lands on: `path` itself unless it is a symlink, else the end of
/// its chain of links (which need not exist yet).
pub fn resolve_links(path: &Path) -> std::io::Result<PathBuf> {
    let mut current = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match std::fs::symlink_metadata(&current) {
            Ok(meta) if meta.file_type().is_symlink() => {
                let link = std::fs::read_link(&current)?;
                current = match current.parent() {
                    Some(dir) if link.is_relative() => dir.join(link),
                    _ => link,
                };
            }
            Ok(_) => return Ok(current),
            Err(err) if err.kind() == std::io::ErrorKind::NotFound => return Ok(current),
            Err(err) => return Err(err),
        }
    }
    Err(std::io::Error::other(format!(
        "more than {MAX_LINKS} symbolic links in a row (a loop?)"
    )))
}

/// Refuses an output that is one of the inputs (the same file, through any path or link), so a
/// command never overwrites what it reads: `skillc compile x.skill -o x.skill`,
/// `skillc learn s.skill demo.csv -o demo.csv`. Outputs that do not exist yet are fine.
///
/// `flag` names the output in the message (e.g. `-o`). For callers outside this crate's
/// commands: `atomic::refuse_inputs(out, "-o", &[&args.file, &args.scene])?` before any work.
pub fn refuse_inputs(output: &Path, flag: &str, inputs: &[&Path]) -> Result<(), String> {
    let Ok(out_meta) = std::fs::metadata(output) else {
        return Ok(());
    };
    if is_char_device(&out_meta) {
        // `/dev/null` or `/dev/stdout` as both input and output is not a file being destroyed.
        return Ok(());
    }
    for input in inputs {
        if same_file(output, &out_meta, input) {
            return Err(format!(
                "{flag} `{}` is also an input (`{}`): refusing to overwrite it; choose another output",
                output.display(),
                input.display()
            ));
        }
    }
    Ok(())
}

fn same_file(output: &Path, out_meta: &std::fs::Metadata, input: &Path) -> bool {
    let Ok(in_meta) = std::fs::metadata(input) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let _ = output;
        out_meta.dev() == in_meta.dev() && out_meta.ino() == in_meta.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (out_meta, in_meta);
        match (std::fs::canonicalize(output), std::fs::canonicalize(input)) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        }
    }
}

#[cfg(unix)]
fn is_char_device(meta: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::FileTypeExt;
    meta.file_type().is_char_device()
}

#[cfg(not(unix))]
fn is_char_device(_meta: &std::fs::Metadata) -> bool {
    false
}

/// A temporary file beside `target`, then a rename over it.
fn replace(target: &Path, contents: &[u8], permissions: Option<std::fs::Permissions>) -> std::io::Result<()> {
    let dir = match target.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let file_name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".to_string());
    let tmp = dir.join(format!(".{file_name}.tmp-{}", std::process::id()));
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(contents)?;
        file.sync_all()?;
        if let Some(permissions) = permissions {
            std::fs::set_permissions(&tmp, permissions)?;
        }
        std::fs::rename(&tmp, target)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("skillc-atomic-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir
    }

    #[test]
    fn writes_and_replaces_without_leaving_temporaries() {
        let dir = temp_dir("replace");
        let path = dir.join("out.json");
        super::write(&path, b"one").expect("first write");
        super::write(&path, b"two").expect("second write");
        assert_eq!(std::fs::read_to_string(&path).expect("read back"), "two");
        let leftovers: Vec<_> = std::fs::read_dir(&dir).expect("list").filter_map(Result::ok).collect();
        assert_eq!(leftovers.len(), 1, "only the target remains");
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn a_missing_directory_is_an_error_not_a_panic() {
        let path = std::path::Path::new("/nonexistent-skillc-dir/out.json");
        assert!(super::write(path, b"x").is_err());
    }

    #[test]
    fn a_directory_is_refused() {
        let dir = temp_dir("dir");
        let err = super::write(&dir, b"x").expect_err("a directory");
        assert!(err.to_string().contains("directory"), "{err}");
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_is_written_through_and_kept() {
        let dir = temp_dir("link");
        let target = dir.join("target.txt");
        std::fs::write(&target, "old").expect("target");
        let link = dir.join("link.txt");
        std::os::unix::fs::symlink("target.txt", &link).expect("link");
        super::write(&link, b"new").expect("write through");
        assert!(std::fs::symlink_metadata(&link).expect("link").file_type().is_symlink());
        assert_eq!(std::fs::read_to_string(&target).expect("target"), "new");
        // A dangling link creates its target.
        let dangling = dir.join("dangling.txt");
        std::os::unix::fs::symlink("made.txt", &dangling).expect("link");
        super::write(&dangling, b"made").expect("write through");
        assert_eq!(std::fs::read_to_string(dir.join("made.txt")).expect("made"), "made");
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[cfg(unix)]
    #[test]
    fn devices_are_written_directly_and_fifos_refused() {
        use std::os::unix::fs::FileTypeExt;
        super::write(std::path::Path::new("/dev/null"), b"gone").expect("/dev/null takes anything");
        let meta = std::fs::metadata("/dev/null").expect("still there");
        assert!(meta.file_type().is_char_device(), "not replaced by a file");
        if std::path::Path::new("/dev/full").exists() {
            assert!(super::write(std::path::Path::new("/dev/full"), b"x").is_err());
        }
        let dir = temp_dir("fifo");
        let fifo = dir.join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|status| status.success()) {
            let err = super::write(&fifo, b"x").expect_err("a FIFO is refused, not waited on");
            assert!(err.to_string().contains("FIFO"), "{err}");
        }
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn an_input_is_not_an_output() {
        let dir = temp_dir("inputs");
        let input = dir.join("x.skill");
        std::fs::write(&input, "skill x {}").expect("input");
        let other = dir.join("y.json");
        assert!(
            super::refuse_inputs(&other, "-o", &[&input]).is_ok(),
            "a new file is fine"
        );
        let err = super::refuse_inputs(&input, "-o", &[&input]).expect_err("same file");
        assert!(err.contains("x.skill"), "{err}");
        let dotted = dir.join(".").join("x.skill");
        assert!(
            super::refuse_inputs(&dotted, "-o", &[&input]).is_err(),
            "another spelling"
        );
        std::fs::remove_dir_all(&dir).expect("clean up");
    }
}
