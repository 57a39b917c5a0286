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
//!
//! Every file a command reads is an input, also those it finds itself (imports, a task step's
//! demonstration and learned file, the scene's URDF, a trials file's entries): the loaders call
//! [`note_input`], and [`write()`] refuses to replace a noted input, so no output ever replaces
//! what the command read, whatever path or link it is named by (device and inode compared).
//! Commands also check their outputs against the noted inputs before any long work
//! ([`refuse_inputs`]), so the refusal comes first, not after a run.
//!
//! A folder of outputs (the eval's report) is written as a unit by [`write_dir`]: into a hidden
//! temporary folder beside the target, then moved into place, so a reader sees the previous
//! report or the new one, never a mix. Every temporary file and folder is registered while it
//! exists; [`install_signal_cleanup`] removes them on SIGINT, SIGTERM or SIGHUP before the
//! process exits with 128 + the signal's number (130, 143, 129), so none outlives the process.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// Symlinks followed before giving up (the kernel's own limit is 40).
const MAX_LINKS: usize = 40;

/// One file the process has read: how it was named, and its identity.
struct Input {
    path: PathBuf,
    id: FileId,
}

/// A file's identity: device and inode on Unix, the canonical path elsewhere.
#[derive(PartialEq, Eq)]
enum FileId {
    #[cfg(unix)]
    Inode { dev: u64, ino: u64 },
    #[cfg(not(unix))]
    Path(PathBuf),
}

impl FileId {
    fn of(path: &Path, meta: &std::fs::Metadata) -> Option<FileId> {
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            let _ = path;
            Some(FileId::Inode {
                dev: meta.dev(),
                ino: meta.ino(),
            })
        }
        #[cfg(not(unix))]
        {
            let _ = meta;
            std::fs::canonicalize(path).ok().map(FileId::Path)
        }
    }
}

/// A temporary this process has made and not yet moved into place or removed.
enum Temporary {
    File(PathBuf),
    Dir(PathBuf),
}

/// The temporaries, with a number each so their owner can drop them.
static TEMPORARIES: std::sync::Mutex<Vec<(u64, Temporary)>> = std::sync::Mutex::new(Vec::new());

/// The next temporary's number.
static NEXT_TEMPORARY: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

fn temporaries() -> std::sync::MutexGuard<'static, Vec<(u64, Temporary)>> {
    TEMPORARIES.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Registers a temporary; returns its number for [`forget_temporary`].
fn register(temporary: Temporary) -> u64 {
    let id = NEXT_TEMPORARY.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    temporaries().push((id, temporary));
    id
}

/// Drops temporary `id` from the registry: it has been moved into place or removed.
fn forget_temporary(id: u64) {
    temporaries().retain(|(other, _)| *other != id);
}

/// Removes every registered temporary. Called on a signal; also safe to call at any time, it
/// leaves the registry empty.
pub fn remove_temporaries() {
    remove_temporaries_where(|_| true);
}

/// [`remove_temporaries`] for those whose path `pick` picks.
fn remove_temporaries_where(pick: impl Fn(&Path) -> bool) {
    let mut list = temporaries();
    let (picked, kept): (Vec<_>, Vec<_>) = list.drain(..).partition(|(_, temporary)| match temporary {
        Temporary::File(path) | Temporary::Dir(path) => pick(path),
    });
    *list = kept;
    for (_, temporary) in picked {
        match temporary {
            Temporary::File(path) => {
                let _ = std::fs::remove_file(path);
            }
            Temporary::Dir(path) => {
                let _ = std::fs::remove_dir_all(path);
            }
        }
    }
}

/// Starts a thread that, on SIGINT, SIGTERM or SIGHUP, removes the temporaries
/// ([`remove_temporaries`]) and exits with 128 + the signal's number. The binary calls it
/// first; a library user who wants the same cleanup calls it too.
#[cfg(unix)]
pub fn install_signal_cleanup() -> std::io::Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])?;
    std::thread::Builder::new().name("signals".into()).spawn(move || {
        for signal in signals.forever() {
            if GRACEFUL.load(Ordering::SeqCst) && !STOP_REQUESTED.swap(true, Ordering::SeqCst) {
                // A serving command stops at its next tick; a second signal exits at once.
                continue;
            }
            remove_temporaries();
            // The registry's lock is held from here on, so no temporary is made after
            // the cleanup.
            let _held = temporaries();
            std::process::exit(128 + signal);
        }
    })?;
    Ok(())
}

/// Set by a command that stops by itself on a signal ([`stop_on_signal`]).
static GRACEFUL: AtomicBool = AtomicBool::new(false);
/// Set by the first signal while [`GRACEFUL`].
static STOP_REQUESTED: AtomicBool = AtomicBool::new(false);

/// Makes the first SIGINT, SIGTERM or SIGHUP set the flag returned instead of exiting, so a
/// command that serves until stopped (`skillc plant`) can finish its tick, close its session and
/// report; a second signal exits as before.
pub fn stop_on_signal() -> &'static AtomicBool {
    GRACEFUL.store(true, Ordering::SeqCst);
    &STOP_REQUESTED
}

/// No signals to handle off Unix; temporaries are removed as their writes end.
#[cfg(not(unix))]
pub fn install_signal_cleanup() -> std::io::Result<()> {
    Ok(())
}

/// The inputs this process has read, in the order first read.
static INPUTS: std::sync::Mutex<Vec<Input>> = std::sync::Mutex::new(Vec::new());

/// Notes that the process reads `path` (through links), so no output of it replaces that file.
/// A path that does not exist (yet) or is a device notes nothing.
pub fn note_input(path: &Path) {
    let Ok(meta) = std::fs::metadata(path) else {
        return;
    };
    if !meta.is_file() {
        return;
    }
    let Some(id) = FileId::of(path, &meta) else {
        return;
    };
    let mut inputs = INPUTS.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    // An entry of a file deleted since, whose inode this file now has, is replaced.
    inputs.retain(|input| input.id != id || still_is(&input.path, &input.id));
    if !inputs.iter().any(|input| input.id == id) {
        inputs.push(Input {
            path: path.to_path_buf(),
            id,
        });
    }
}

/// A fingerprint of the contents of every input noted so far, whatever their paths: the
/// FNV-1a hashes of their bytes, sorted, hashed again. Two processes that read the same files
/// from different folders or machines agree on it.
pub fn inputs_fingerprint() -> String {
    let paths: Vec<PathBuf> = INPUTS
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
        .iter()
        .map(|input| input.path.clone())
        .collect();
    let mut hashes: Vec<String> = paths
        .iter()
        .map(|path| std::fs::read(path).map_or_else(|_| "unreadable".to_string(), |bytes| fnv(&bytes)))
        .collect();
    hashes.sort();
    fnv(hashes.join("\n").as_bytes())
}

/// The noted input that `path` (through links) is, as it was named when read.
fn noted_input(path: &Path) -> Option<PathBuf> {
    let meta = std::fs::metadata(path).ok().filter(std::fs::Metadata::is_file)?;
    let id = FileId::of(path, &meta)?;
    let inputs = INPUTS.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    inputs
        .iter()
        // A noted input deleted since frees its inode for another file: it counts only while
        // its path is still that file.
        .find(|input| input.id == id && still_is(&input.path, &input.id))
        .map(|input| input.path.clone())
}

/// Whether `path` is still the file `id` names.
fn still_is(path: &Path, id: &FileId) -> bool {
    std::fs::metadata(path)
        .ok()
        .and_then(|meta| FileId::of(path, &meta))
        .is_some_and(|now| now == *id)
}

/// The first noted input that lies inside the folder `dir`, as it was named when read.
fn noted_inside(dir: &Path) -> Option<PathBuf> {
    let dir = std::fs::canonicalize(dir).ok()?;
    let inputs = INPUTS.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    inputs
        .iter()
        .find(|input| std::fs::canonicalize(&input.path).is_ok_and(|path| path.starts_with(&dir)))
        .map(|input| input.path.clone())
}

/// Writes `contents` to `path` as the module docs describe; a file the process has read
/// ([`note_input`]) is refused.
pub fn write(path: &Path, contents: &[u8]) -> std::io::Result<()> {
    if let Some(input) = noted_input(path) {
        return Err(std::io::Error::other(format!(
            "it is also an input of this command (`{}`): refusing to overwrite it; choose another output",
            input.display()
        )));
    }
    write_over_input(path, contents)
}

/// [`write()`] without the input check: for a command whose output is its input by request
/// (`skillc fmt --write` formats files in place).
pub fn write_over_input(path: &Path, contents: &[u8]) -> std::io::Result<()> {
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
/// `skillc learn s.skill demo.csv -o demo.csv`. `inputs` are checked together with every input
/// noted so far ([`note_input`]). Outputs that do not exist yet are fine.
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
    let noted = noted_input(output);
    for input in inputs.iter().copied().chain(noted.as_deref()) {
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
    let (dir, file_name) = beside(target);
    let tmp = dir.join(temporary_name(&file_name));
    let id = register(Temporary::File(tmp.clone()));
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(contents)?;
        file.sync_all()?;
        if let Some(permissions) = permissions {
            std::fs::set_permissions(&tmp, permissions)?;
        }
        let _held = temporaries();
        std::fs::rename(&tmp, target)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    forget_temporary(id);
    result
}

/// The folder `target` lies in (`.` for a bare name) and its file name, where its temporary goes.
fn beside(target: &Path) -> (PathBuf, String) {
    let dir = match target.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".to_string());
    (dir, name)
}

/// A hidden name beside `name` that no other process or write of this one uses.
fn temporary_name(name: &str) -> String {
    let n = NEXT_TEMPORARY.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    format!(".{name}.tmp-{}-{n}", std::process::id())
}

/// What a folder [`write_dir`] may replace holds only these entries: the files a report of
/// skillc's writes. A folder with anything else is the user's, and is refused, not replaced.
const REPORT_ENTRIES: &[&str] = &["summary.json", "index.html", "plots"];

/// Writes a folder of outputs as a unit: `fill` writes into a fresh hidden folder beside `dir`,
/// which then takes `dir`'s place (the module docs). An existing `dir` is replaced only when it
/// is empty or holds nothing but what a report holds (`summary.json`, `index.html`, `plots`); otherwise the write
/// is refused before `fill` runs. On any error the new folder is removed and `dir` is as it was.
pub fn write_dir<T>(dir: &Path, fill: impl FnOnce(&Path) -> std::io::Result<T>) -> std::io::Result<T> {
    let dir = resolve_links(dir)?;
    let existing = match std::fs::metadata(&dir) {
        Ok(meta) if meta.is_dir() => {
            let foreign: Vec<String> = std::fs::read_dir(&dir)?
                .filter_map(Result::ok)
                .map(|entry| entry.file_name().to_string_lossy().into_owned())
                .filter(|name| !REPORT_ENTRIES.contains(&name.as_str()))
                .collect();
            if let Some(input) = noted_inside(&dir) {
                return Err(std::io::Error::other(format!(
                    "it holds `{}`, an input of this command: refusing to replace it; choose another folder",
                    input.display()
                )));
            }
            if let Some(name) = foreign.first() {
                return Err(std::io::Error::other(format!(
                    "it is a folder that holds `{name}`{}, which a skillc report does not: refusing to replace it; choose a new or empty folder",
                    if foreign.len() > 1 { format!(" and {} more", foreign.len() - 1) } else { String::new() }
                )));
            }
            true
        }
        Ok(_) => return Err(std::io::Error::other("it exists and is not a folder")),
        Err(err) if err.kind() == std::io::ErrorKind::NotFound => false,
        Err(err) => return Err(err),
    };
    let (parent, name) = beside(&dir);
    std::fs::create_dir_all(&parent)?;
    let tmp = parent.join(temporary_name(&name));
    let tmp_id = register(Temporary::Dir(tmp.clone()));
    let filled = std::fs::create_dir(&tmp).and_then(|()| fill(&tmp));
    let value = match filled {
        Ok(value) => value,
        Err(err) => {
            let _ = std::fs::remove_dir_all(&tmp);
            forget_temporary(tmp_id);
            return Err(err);
        }
    };
    let moved = if existing {
        // Both renames under the registry's lock: a signal's cleanup waits for them, so it sees
        // the previous report in place or the new one, and then only a temporary to remove.
        let aside = parent.join(format!(".{name}.old-{}", std::process::id()));
        let mut list = temporaries();
        let moved = std::fs::rename(&dir, &aside).and_then(|()| {
            std::fs::rename(&tmp, &dir).inspect_err(|_| {
                let _ = std::fs::rename(&aside, &dir);
            })
        });
        list.retain(|(other, _)| *other != tmp_id);
        let aside_id = NEXT_TEMPORARY.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        if moved.is_ok() {
            list.push((aside_id, Temporary::Dir(aside.clone())));
        }
        drop(list);
        if moved.is_ok() {
            let _ = std::fs::remove_dir_all(&aside);
            forget_temporary(aside_id);
        }
        moved
    } else {
        let held = temporaries();
        let moved = std::fs::rename(&tmp, &dir);
        drop(held);
        forget_temporary(tmp_id);
        moved
    };
    if let Err(err) = moved {
        let _ = std::fs::remove_dir_all(&tmp);
        forget_temporary(tmp_id);
        // Another process put its folder in place between our check and our rename: its report
        // is whole, ours is discarded, and the OS's "Directory not empty" says none of that.
        if matches!(
            err.kind(),
            std::io::ErrorKind::DirectoryNotEmpty | std::io::ErrorKind::AlreadyExists | std::io::ErrorKind::NotFound
        ) {
            return Err(std::io::Error::new(
                err.kind(),
                format!(
                    "another process wrote this folder while this one ran ({err}): its report is in place, whole, \
                     and this one was discarded; run again to replace it, or write to another folder"
                ),
            ));
        }
        return Err(err);
    }
    Ok(value)
}

/// A 64-bit FNV-1a hash of `bytes`, in hex.
pub fn fnv(bytes: &[u8]) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for byte in bytes {
        hash ^= u64::from(*byte);
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{hash:016x}")
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
    fn two_writers_of_one_report_folder_leave_one_whole_report_and_a_clear_message() {
        let parent = temp_dir("race");
        let dir = parent.join("report");
        let barrier = std::sync::Arc::new(std::sync::Barrier::new(2));
        let writers: Vec<_> = ["first", "second"]
            .into_iter()
            .map(|who| {
                let (dir, barrier) = (dir.clone(), barrier.clone());
                std::thread::spawn(move || {
                    super::write_dir(&dir, |tmp| {
                        // Both have checked that the folder is missing before either moves in.
                        barrier.wait();
                        std::fs::write(tmp.join("summary.json"), who)?;
                        std::fs::create_dir(tmp.join("plots"))?;
                        std::fs::write(tmp.join("plots").join("a.svg"), who)
                    })
                })
            })
            .collect();
        let results: Vec<std::io::Result<()>> = writers.into_iter().map(|w| w.join().expect("thread")).collect();
        let lost: Vec<&std::io::Error> = results.iter().filter_map(|r| r.as_ref().err()).collect();
        assert_eq!(lost.len(), 1, "{results:?}");
        assert!(
            lost[0].to_string().contains("another process wrote this folder"),
            "{}",
            lost[0]
        );
        let winner = std::fs::read_to_string(dir.join("summary.json")).expect("a whole report");
        assert_eq!(
            std::fs::read_to_string(dir.join("plots/a.svg")).expect("its plot"),
            winner
        );
        let left: Vec<String> = std::fs::read_dir(&parent)
            .expect("parent")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(left, ["report"], "no temporary left beside it");
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

    fn entries(dir: &std::path::Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .expect("list")
            .filter_map(Result::ok)
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn a_folder_is_written_as_a_unit_and_replaces_only_a_report() {
        let root = temp_dir("write-dir");
        let report = root.join("report");
        super::write_dir(&report, |dir| {
            std::fs::create_dir(dir.join("plots"))?;
            std::fs::write(dir.join("summary.json"), "one")
        })
        .expect("new folder");
        assert_eq!(entries(&root), ["report"], "no temporary beside it");
        super::write_dir(&report, |dir| std::fs::write(dir.join("index.html"), "two")).expect("replaces a report");
        assert_eq!(entries(&report), ["index.html"], "the old report's files are gone");
        assert_eq!(entries(&root), ["report"]);
        // A failing fill leaves the previous report as it was and no temporary.
        let err = super::write_dir(&report, |dir| {
            std::fs::write(dir.join("summary.json"), "half")?;
            Err::<(), _>(std::io::Error::other("disk full"))
        })
        .expect_err("fill failed");
        assert_eq!(err.to_string(), "disk full");
        assert_eq!(entries(&report), ["index.html"]);
        assert_eq!(entries(&root), ["report"]);
        // A folder with the user's own files is refused before anything is written.
        let mine = root.join("mine");
        std::fs::create_dir(&mine).expect("mine");
        std::fs::write(mine.join("thesis.tex"), "precious").expect("file");
        let err = super::write_dir(&mine, |_| Ok(())).expect_err("not a report");
        assert!(err.to_string().contains("thesis.tex"), "{err}");
        assert_eq!(entries(&mine), ["thesis.tex"]);
        std::fs::remove_dir_all(&root).expect("clean up");
    }

    #[test]
    fn a_folder_holding_an_input_is_not_replaced() {
        let root = temp_dir("dir-input");
        let report = root.join("report");
        std::fs::create_dir(&report).expect("report");
        let summary = report.join("summary.json");
        std::fs::write(&summary, "{}").expect("summary");
        super::note_input(&summary);
        let err = super::write_dir(&report, |_| Ok(())).expect_err("holds an input");
        assert!(err.to_string().contains("summary.json"), "{err}");
        assert_eq!(std::fs::read_to_string(&summary).expect("kept"), "{}");
        std::fs::remove_dir_all(&root).expect("clean up");
    }

    #[test]
    fn a_noted_input_is_never_written_over() {
        let root = temp_dir("noted");
        let demo = root.join("demo.csv");
        std::fs::write(&demo, "t,px").expect("demo");
        #[cfg(unix)]
        std::os::unix::fs::symlink("demo.csv", root.join("alias.csv")).expect("link");
        super::note_input(&root.join("./demo.csv"));
        let err = super::write(&demo, b"log").expect_err("an input");
        assert!(err.to_string().contains("also an input"), "{err}");
        #[cfg(unix)]
        {
            let err = super::write(&root.join("alias.csv"), b"log").expect_err("the same file by a link");
            assert!(err.to_string().contains("demo.csv"), "{err}");
            let err = super::refuse_inputs(&root.join("alias.csv"), "-o", &[]).expect_err("noted");
            assert!(err.starts_with("-o `"), "{err}");
        }
        assert_eq!(std::fs::read_to_string(&demo).expect("kept"), "t,px");
        // In place on request.
        super::write_over_input(&demo, b"formatted").expect("in place");
        assert_eq!(std::fs::read_to_string(&demo).expect("written"), "formatted");
        std::fs::remove_dir_all(&root).expect("clean up");
    }

    #[test]
    fn a_signal_mid_write_leaves_the_previous_folder_and_no_temporary() {
        let root = temp_dir("signal");
        let report = root.join("report");
        super::write_dir(&report, |dir| std::fs::write(dir.join("summary.json"), "old")).expect("first");
        // What the signal handler does, while the new report is half written.
        let err = super::write_dir(&report, |dir| {
            std::fs::write(dir.join("summary.json"), "new")?;
            // Only this test's: the other tests of this process write files meanwhile.
            let root = root.clone();
            super::remove_temporaries_where(move |path| path.starts_with(&root));
            Ok(())
        })
        .expect_err("its temporary is gone");
        let _ = err;
        assert_eq!(entries(&root), ["report"], "no temporary left");
        assert_eq!(
            std::fs::read_to_string(report.join("summary.json")).expect("old"),
            "old"
        );
        std::fs::remove_dir_all(&root).expect("clean up");
    }
}
