//! A bag as it lies on disk, checked before any message is decoded: the MCAP files of a rosbag2
//! folder (from its `metadata.yaml`), and each file's record structure: the magic, every
//! record's declared length against the bytes the file holds, every chunk's sizes against its
//! record and the reader's bound, so that no size the file cannot back is ever allocated.
//!
//! The `mcap` crate streams records and checks CRCs when asked to (the reader enables it), but
//! it trusts a record's length until the file runs out, does not compare an uncompressed
//! chunk's `uncompressed_size` with its bytes, and bounds a compressed chunk's declared size only
//! when it decompresses the chunk whole. The walk here does all three first, seeking over each
//! record's body.

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use super::{sniff, sniff_bytes, BagError, Content, MCAP_MAGIC};

/// MCAP opcodes the walk looks into.
const OP_FOOTER: u8 = 0x02;
const OP_CHUNK: u8 = 0x06;
/// A chunk record's fixed fields before its compression name: start and end time, uncompressed
/// size, uncompressed CRC, the name's length.
const CHUNK_FIXED: u64 = 8 + 8 + 8 + 4 + 4;

/// The MCAP files of the bag at `path`: the file itself, or a rosbag2 folder's files in the
/// order its `metadata.yaml` lists them (`relative_file_paths`; without that list, the folder's
/// `.mcap` files by name).
pub(super) fn bag_files(path: &Path) -> Result<Vec<PathBuf>, BagError> {
    if !path.is_dir() {
        return Ok(vec![path.to_path_buf()]);
    }
    let dir = path.display().to_string();
    let folder_error = |reason: String| BagError::Folder {
        dir: dir.clone(),
        reason,
    };
    let mut in_folder: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(|source| BagError::Io {
            file: dir.clone(),
            source,
        })?
        .filter_map(|entry| entry.ok().map(|entry| entry.path()))
        .filter(|file| super::is_mcap(file) && file.is_file())
        .collect();
    in_folder.sort();
    let metadata_path = path.join("metadata.yaml");
    if !metadata_path.is_file() {
        let hint = match in_folder.as_slice() {
            [one] => format!(": pass the bag file `{}` itself", one.display()),
            [] => ": pass a `.mcap` file or a rosbag2 folder".to_owned(),
            many => format!(
                "; it holds {} `.mcap` files: pass one of them (`{}` ...)",
                many.len(),
                many[0].display()
            ),
        };
        return Err(BagError::NotABag { dir, hint });
    }
    let text = std::fs::read_to_string(&metadata_path).map_err(|source| BagError::Io {
        file: metadata_path.display().to_string(),
        source,
    })?;
    let metadata = Metadata::parse(&text);
    if let Some(storage) = metadata.storage.as_deref().filter(|s| *s != "mcap") {
        return Err(folder_error(format!(
            "is a rosbag2 bag stored as `{storage}` (`storage_identifier` in its `metadata.yaml`), and skillc reads only `mcap`: convert it (`ros2 bag convert`, or `mcap convert` for each `.db3`) and learn from the MCAP bag"
        )));
    }
    if let Some(mode) = metadata
        .compression_mode
        .as_deref()
        .filter(|m| !m.is_empty() && *m != "none")
    {
        let format = metadata.compression_format.as_deref().unwrap_or("?");
        return Err(folder_error(format!(
            "is a rosbag2 bag compressed by {} (`compression_mode: {mode}`, `compression_format: {format}` in its `metadata.yaml`), which skillc does not undo: convert it to an uncompressed bag with `ros2 bag convert` (MCAP's own chunk compression is read)",
            if mode.eq_ignore_ascii_case("file") { "file" } else { "message" }
        )));
    }
    if metadata.files.is_empty() {
        if in_folder.is_empty() {
            return Err(folder_error(
                "has a `metadata.yaml` but no `.mcap` file, and the metadata lists none (`relative_file_paths`): copy the bag's `.mcap` files into it".into(),
            ));
        }
        return Ok(in_folder);
    }
    let mut files = Vec::with_capacity(metadata.files.len());
    for name in &metadata.files {
        let file = path.join(name);
        if !file.is_file() {
            return Err(folder_error(format!(
                "lists `{name}` in its `metadata.yaml` (`relative_file_paths`), which is not a file in the folder: copy the whole bag, or fix the list"
            )));
        }
        files.push(file);
    }
    Ok(files)
}

/// The few fields of a rosbag2 `metadata.yaml` the reader needs, read line by line (the file is
/// machine-written: `key: value` lines and `- item` lists).
#[derive(Debug, Default, PartialEq, Eq)]
struct Metadata {
    storage: Option<String>,
    compression_format: Option<String>,
    compression_mode: Option<String>,
    files: Vec<String>,
}

impl Metadata {
    fn parse(text: &str) -> Metadata {
        let mut metadata = Metadata::default();
        let mut lines = text.lines().peekable();
        while let Some(line) = lines.next() {
            let Some((key, value)) = line.trim().split_once(':') else {
                continue;
            };
            let value = unquote(value);
            match key.trim() {
                "storage_identifier" => metadata.storage = Some(value.to_owned()),
                "compression_format" => metadata.compression_format = Some(value.to_owned()),
                "compression_mode" => metadata.compression_mode = Some(value.to_owned()),
                "relative_file_paths" if value.starts_with('[') => {
                    metadata.files = value
                        .trim_start_matches('[')
                        .trim_end_matches(']')
                        .split(',')
                        .map(unquote)
                        .filter(|item| !item.is_empty())
                        .map(str::to_owned)
                        .collect();
                }
                "relative_file_paths" => {
                    while let Some(item) = lines.peek().and_then(|next| next.trim().strip_prefix('-')) {
                        let item = unquote(item);
                        if !item.is_empty() {
                            metadata.files.push(item.to_owned());
                        }
                        lines.next();
                    }
                }
                _ => {}
            }
        }
        metadata
    }
}

/// A YAML scalar without its comment, surrounding blanks and quotes.
fn unquote(value: &str) -> &str {
    let value = value.trim();
    let value = match value.find(" #") {
        Some(at) if !value.starts_with(['"', '\'']) => value[..at].trim_end(),
        _ => value,
    };
    value
        .strip_prefix('"')
        .and_then(|v| v.strip_suffix('"'))
        .or_else(|| value.strip_prefix('\'').and_then(|v| v.strip_suffix('\'')))
        .unwrap_or(value)
}

/// Walks the MCAP file at `path` record by record without reading their bodies: it must start
/// with the magic, every record must fit in the bytes left, every chunk's compressed size must
/// fit its record, an uncompressed chunk's sizes must agree and no chunk may declare more than
/// `max_chunk` bytes uncompressed; the footer and the closing magic must end it.
pub(super) fn check_records(path: &Path, file: &str, max_chunk: u64) -> Result<(), BagError> {
    let io_error = |source: std::io::Error| BagError::Io {
        file: file.to_owned(),
        source,
    };
    let handle = File::open(path).map_err(io_error)?;
    let size = handle.metadata().map_err(io_error)?.len();
    let mut reader = BufReader::new(handle);
    let mut head = [0u8; 8];
    let got = read_up_to(&mut reader, &mut head).map_err(io_error)?;
    if head[..got] != MCAP_MAGIC[..] {
        let content = match sniff(path) {
            Ok(content) => content,
            Err(_) => sniff_bytes(&head[..got]),
        };
        return Err(BagError::NotMcap {
            file: file.to_owned(),
            reason: not_mcap(path, &content),
        });
    }
    let corrupt = |offset: u64, reason: String| BagError::Corrupt {
        file: file.to_owned(),
        offset,
        reason,
    };
    let cut_short = "the file was cut short (an interrupted recording?): recover what it holds with `mcap recover` and learn from that";
    let mut offset = MCAP_MAGIC.len() as u64;
    loop {
        let left = size - offset;
        if left < 9 {
            return Err(corrupt(
                offset,
                format!("the file ends after {left} byte(s) where a record or the footer should be: {cut_short}"),
            ));
        }
        let mut opcode_len = [0u8; 9];
        reader.read_exact(&mut opcode_len).map_err(io_error)?;
        let opcode = opcode_len[0];
        let len = u64::from_le_bytes(opcode_len[1..].try_into().expect("8 bytes"));
        let body_left = left - 9;
        if len > body_left {
            return Err(corrupt(
                offset,
                format!(
                    "a record (opcode 0x{opcode:02x}) declares {len} bytes, and only {body_left} remain in the file: it is corrupt, or {cut_short}"
                ),
            ));
        }
        if opcode == OP_CHUNK {
            check_chunk(&mut reader, len, max_chunk).map_err(|reason| match reason {
                ChunkProblem::Io(err) => io_error(err),
                ChunkProblem::Bad(reason) => corrupt(
                    offset,
                    format!("a chunk {reason}: the file is corrupt; export it again"),
                ),
            })?;
        } else {
            reader.seek_relative(len as i64).map_err(io_error)?;
        }
        offset += 9 + len;
        if opcode == OP_FOOTER {
            break;
        }
    }
    let mut tail = [0u8; 8];
    let got = read_up_to(&mut reader, &mut tail).map_err(io_error)?;
    if tail[..got] != MCAP_MAGIC[..] {
        return Err(corrupt(
            offset,
            format!("the footer is not followed by the closing MCAP magic: {cut_short}"),
        ));
    }
    Ok(())
}

/// What is wrong with a chunk.
enum ChunkProblem {
    Io(std::io::Error),
    Bad(String),
}

/// Reads a chunk's header (the reader at its start, `len` its length) and seeks past its body.
fn check_chunk(reader: &mut BufReader<File>, len: u64, max_chunk: u64) -> Result<(), ChunkProblem> {
    if len < CHUNK_FIXED {
        return Err(ChunkProblem::Bad(format!(
            "record of {len} bytes cannot hold a chunk's {CHUNK_FIXED}-byte header"
        )));
    }
    let mut fixed = [0u8; CHUNK_FIXED as usize];
    reader.read_exact(&mut fixed).map_err(ChunkProblem::Io)?;
    let uncompressed_size = u64::from_le_bytes(fixed[16..24].try_into().expect("8 bytes"));
    let name_len = u64::from(u32::from_le_bytes(fixed[28..32].try_into().expect("4 bytes")));
    let header = CHUNK_FIXED + name_len + 8;
    if header > len {
        return Err(ChunkProblem::Bad(format!(
            "header declares a {name_len}-byte compression name, longer than its {len}-byte record"
        )));
    }
    // A compression name is a short word (`zstd`, `lz4`); header <= len bounds it anyway.
    let mut name = vec![0u8; name_len as usize];
    reader.read_exact(&mut name).map_err(ChunkProblem::Io)?;
    let mut size = [0u8; 8];
    reader.read_exact(&mut size).map_err(ChunkProblem::Io)?;
    let compressed_size = u64::from_le_bytes(size);
    let room = len - header;
    let compression = String::from_utf8_lossy(&name);
    if compressed_size > room {
        return Err(ChunkProblem::Bad(format!(
            "declares {compressed_size} bytes of records, and its record holds {room}"
        )));
    }
    if compression.is_empty() && uncompressed_size != compressed_size {
        return Err(ChunkProblem::Bad(format!(
            "is not compressed and declares {uncompressed_size} bytes uncompressed, but holds {compressed_size}"
        )));
    }
    if uncompressed_size > max_chunk {
        return Err(ChunkProblem::Bad(format!(
            "declares {uncompressed_size} bytes uncompressed, more than the {} MiB a chunk may have here (and more than any recorder writes)",
            max_chunk >> 20
        )));
    }
    if !matches!(compression.as_ref(), "" | "zstd" | "lz4") {
        return Err(ChunkProblem::Bad(format!(
            "is compressed as `{compression}`; MCAP readers know `zstd` and `lz4`"
        )));
    }
    reader.seek_relative(room as i64).map_err(ChunkProblem::Io)
}

/// Reads into `buf` until it is full or the file ends; returns how much was read.
fn read_up_to(reader: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match reader.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(err) if err.kind() == std::io::ErrorKind::Interrupted => {}
            Err(err) => return Err(err),
        }
    }
    Ok(got)
}

/// Why a file named as a bag is not MCAP, and what to do: `is text, not MCAP …`.
fn not_mcap(path: &Path, content: &Content) -> String {
    let what = content.describe();
    let file = path.display();
    match content {
        Content::Text(_) => format!(
            "is {what}, not MCAP: if it is a CSV demonstration, rename it to `{}`",
            path.with_extension("csv").display()
        ),
        Content::Empty => "is empty, not MCAP: was the recording stopped before it wrote anything?".into(),
        Content::Sqlite | Content::Ros1Bag => format!(
            "is {what}, not MCAP: convert it (`mcap convert {file} {}`) and learn from that",
            path.with_extension("converted.mcap").display()
        ),
        Content::Compressed(how) => format!("is {what}, not MCAP: decompress it first (with `{how}`)"),
        Content::Mcap | Content::Binary(_) => {
            format!("is {what}, not MCAP: an MCAP file starts with the bytes `89 4d 43 41 50 30 0d 0a`")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metadata_lists_files_in_block_and_flow_style() {
        let text = "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  relative_file_paths:\n    - run_0.mcap\n    - 'run_1.mcap'\n  files:\n    - path: run_0.mcap\n  compression_format: \"\"\n  compression_mode: \"\"\n";
        assert_eq!(
            Metadata::parse(text),
            Metadata {
                storage: Some("mcap".into()),
                compression_format: Some(String::new()),
                compression_mode: Some(String::new()),
                files: vec!["run_0.mcap".into(), "run_1.mcap".into()],
            }
        );
        let text = "rosbag2_bagfile_information:\n  storage_identifier: sqlite3 # old\n  relative_file_paths: [a_0.db3, \"a_1.db3\"]\n";
        let metadata = Metadata::parse(text);
        assert_eq!(metadata.storage.as_deref(), Some("sqlite3"));
        assert_eq!(metadata.files, ["a_0.db3", "a_1.db3"]);
    }
}
