//! The server's transport over standard input and output: frames (`Content-Length` headers,
//! then that many bytes of JSON) read with bounded memory, and messages written back.
//!
//! lsp-server's own `Connection::stdio()` trusts a frame's `Content-Length` and allocates it
//! before reading a byte; [`read_message`] refuses a frame over [`MAX_FRAME_BYTES`] before
//! allocating anything, bounds each header line to [`MAX_HEADER_LINE`] bytes, and grows its
//! buffer only as bytes arrive, so a frame that declares more than it sends costs what it sent.

use lsp_server::{Connection, Message};
use std::fmt;
use std::io::{BufRead, Read, Write};
use std::thread::JoinHandle;

/// The largest frame the server reads: 64 MiB of JSON. A larger one ends the server (exit
/// code 1) with a message on standard error naming this limit.
pub const MAX_FRAME_BYTES: u64 = 64 << 20;

/// The longest header line (`Content-Length: 123`, ...) the server reads, in bytes.
pub const MAX_HEADER_LINE: u64 = 8 << 10;

/// Why the input stopped being readable.
#[derive(Debug)]
pub enum FrameError {
    /// The frame declares more bytes than [`MAX_FRAME_BYTES`] (or the limit given).
    TooLarge {
        /// What its `Content-Length` says.
        declared: String,
        /// The limit, in bytes.
        limit: u64,
    },
    /// The input ended inside a frame: in its headers or before its last byte.
    Truncated,
    /// A header line is longer than [`MAX_HEADER_LINE`], not `Name: value`, or the headers
    /// have no usable `Content-Length`.
    Header(String),
    /// The frame's bytes are not a JSON-RPC message.
    Malformed(String),
    /// Reading failed.
    Io(std::io::Error),
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameError::TooLarge { declared, limit } => write!(
                f,
                "a message declares Content-Length {declared}, over the limit of {limit} bytes ({} MiB)",
                limit >> 20
            ),
            FrameError::Truncated => write!(f, "the input ended in the middle of a message"),
            FrameError::Header(what) => write!(f, "malformed message header: {what}"),
            FrameError::Malformed(what) => write!(f, "malformed message: {what}"),
            FrameError::Io(err) => write!(f, "cannot read the input: {err}"),
        }
    }
}

impl std::error::Error for FrameError {}

/// Reads one frame's body: `Ok(None)` at the end of the input between frames. Refuses a frame
/// declaring more than `limit` bytes before reading or allocating its body.
pub fn read_frame(input: &mut impl BufRead, limit: u64) -> Result<Option<Vec<u8>>, FrameError> {
    let mut length: Option<u64> = None;
    let mut line = Vec::new();
    let mut first = true;
    loop {
        line.clear();
        let read = input
            .by_ref()
            .take(MAX_HEADER_LINE + 1)
            .read_until(b'\n', &mut line)
            .map_err(FrameError::Io)?;
        if read == 0 {
            return if first { Ok(None) } else { Err(FrameError::Truncated) };
        }
        first = false;
        if !line.ends_with(b"\n") {
            return if line.len() as u64 > MAX_HEADER_LINE {
                Err(FrameError::Header(format!(
                    "a header line is longer than {MAX_HEADER_LINE} bytes"
                )))
            } else {
                Err(FrameError::Truncated)
            };
        }
        let text = String::from_utf8_lossy(&line);
        let text = text.trim_end_matches(['\r', '\n']);
        if text.is_empty() {
            break;
        }
        let Some((name, value)) = text.split_once(':') else {
            return Err(FrameError::Header(format!("{text:?} is not `Name: value`")));
        };
        if name.trim().eq_ignore_ascii_case("Content-Length") {
            let value = value.trim();
            let parsed = value.parse::<u64>();
            match parsed {
                Ok(n) if n <= limit => length = Some(n),
                Ok(_) => {
                    return Err(FrameError::TooLarge {
                        declared: value.to_string(),
                        limit,
                    })
                }
                // All digits but no u64: larger than any limit.
                Err(_) if !value.is_empty() && value.bytes().all(|b| b.is_ascii_digit()) => {
                    return Err(FrameError::TooLarge {
                        declared: value.to_string(),
                        limit,
                    })
                }
                Err(_) => return Err(FrameError::Header(format!("Content-Length {value:?} is not a number"))),
            }
        }
    }
    let length = length.ok_or_else(|| FrameError::Header("no Content-Length".to_string()))?;
    // Grown as bytes come, never sized by the header alone.
    let mut body = Vec::with_capacity(length.min(64 << 10) as usize);
    input
        .by_ref()
        .take(length)
        .read_to_end(&mut body)
        .map_err(FrameError::Io)?;
    if (body.len() as u64) < length {
        return Err(FrameError::Truncated);
    }
    Ok(Some(body))
}

/// Reads one message (see [`read_frame`]), at most [`MAX_FRAME_BYTES`] long.
pub fn read_message(input: &mut impl BufRead) -> Result<Option<Message>, FrameError> {
    read_message_within(input, MAX_FRAME_BYTES)
}

/// [`read_message`] with another frame limit.
pub fn read_message_within(input: &mut impl BufRead, limit: u64) -> Result<Option<Message>, FrameError> {
    let Some(body) = read_frame(input, limit)? else {
        return Ok(None);
    };
    serde_json::from_slice::<Message>(&body)
        .map(Some)
        .map_err(|err| FrameError::Malformed(err.to_string()))
}

/// The threads that move messages between a connection and a byte stream.
#[derive(Debug)]
pub struct Transport {
    /// Reads messages until the input ends, an `exit` notification, or an error (returned).
    pub reader: JoinHandle<Result<(), FrameError>>,
    /// Writes messages until the server's side of the connection is dropped.
    pub writer: JoinHandle<std::io::Result<()>>,
}

/// A connection whose messages are read from `input` and written to `output` by two threads.
/// The server's receiver disconnects when the reader stops, for any reason.
pub fn connect<R, W>(input: R, output: W) -> (Connection, Transport)
where
    R: BufRead + Send + 'static,
    W: Write + Send + 'static,
{
    let (server, client) = Connection::memory();
    let Connection { sender, receiver } = client;
    let reader = std::thread::Builder::new()
        .name("skillc-lsp-reader".to_string())
        .spawn(move || {
            let mut input = input;
            loop {
                let Some(message) = read_message(&mut input)? else {
                    return Ok(());
                };
                let exit = matches!(&message, Message::Notification(n) if n.method == "exit");
                if sender.send(message).is_err() || exit {
                    return Ok(());
                }
            }
        })
        .expect("spawn the reader thread");
    let writer = std::thread::Builder::new()
        .name("skillc-lsp-writer".to_string())
        .spawn(move || {
            let mut output = output;
            for message in receiver {
                message.write(&mut output)?;
            }
            output.flush()
        })
        .expect("spawn the writer thread");
    (server, Transport { reader, writer })
}
