//! Adversarial input to `skillc lsp`: frames that declare more than the limit, input cut off
//! in the middle of a frame, and imports of devices, FIFOs, standard input, directories and
//! files over the size limit, each generated here. Every check runs on a thread the test
//! waits for with a deadline, so a server that blocks fails the test instead of hanging it.

use lsp_server::{Connection, Message, Notification, Request, RequestId};
use serde_json::{json, Value};
use skill_language_server::engine::{Engine, MAX_IMPORT_BYTES};
use skill_language_server::stdio::{self, FrameError, MAX_FRAME_BYTES};
use std::io::Cursor;
use std::sync::mpsc;
use std::time::Duration;

/// Far longer than any of these takes; only a server that blocks reaches it.
const DEADLINE: Duration = Duration::from_secs(20);

/// Runs `work` on a thread and returns its result, failing if it does not finish in time.
fn finishes<T: Send + 'static>(what: &str, work: impl FnOnce() -> T + Send + 'static) -> T {
    let (done, result) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = done.send(work());
    });
    result
        .recv_timeout(DEADLINE)
        .unwrap_or_else(|_| panic!("{what}: did not finish"))
}

fn frame(body: &str) -> Vec<u8> {
    format!("Content-Length: {}\r\n\r\n{body}", body.len()).into_bytes()
}

fn initialize_frame() -> Vec<u8> {
    frame(&json!({ "jsonrpc": "2.0", "id": 1, "method": "initialize", "params": { "capabilities": {} } }).to_string())
}

#[test]
fn a_frame_over_the_limit_is_refused_before_its_body_is_read() {
    for declared in [
        "1000000000000".to_string(),
        (MAX_FRAME_BYTES + 1).to_string(),
        "99999999999999999999999999999999".to_string(),
    ] {
        let input = format!("Content-Length: {declared}\r\n\r\n{{}}");
        let result = finishes("a huge frame", move || {
            stdio::read_message(&mut Cursor::new(input.into_bytes()))
        });
        match result {
            Err(FrameError::TooLarge { declared: said, limit }) => {
                assert_eq!(said, declared);
                assert_eq!(limit, MAX_FRAME_BYTES);
            }
            other => panic!("{declared}: {other:?}"),
        }
        let message = FrameError::TooLarge {
            declared: declared.clone(),
            limit: MAX_FRAME_BYTES,
        }
        .to_string();
        assert!(message.contains("64 MiB"), "the limit is named: {message}");
    }
    // At the limit exactly, the frame is read (and here cut off, having sent two bytes).
    let input = format!("Content-Length: {MAX_FRAME_BYTES}\r\n\r\n{{}}");
    assert!(matches!(
        stdio::read_message(&mut Cursor::new(input.into_bytes())),
        Err(FrameError::Truncated)
    ));
}

#[test]
fn the_server_on_a_byte_stream_ends_with_1_on_a_huge_frame_after_answering_what_came_before() {
    let mut input = initialize_frame();
    input.extend_from_slice(b"Content-Length: 1000000000000\r\n\r\n{\"jsonrpc\":\"2.0\"");
    let (code, reader, output) = finishes("the server on a huge frame", move || {
        let output = SharedBuffer::default();
        let (connection, transport) = stdio::connect(Cursor::new(input), output.clone());
        let code = skill_language_server::serve(connection);
        transport.writer.join().expect("the writer ends").expect("writes");
        let reader = transport.reader.join().expect("the reader ends");
        (code, reader, output.text())
    });
    assert_eq!(code, 1);
    assert!(matches!(reader, Err(FrameError::TooLarge { .. })), "{reader:?}");
    assert!(output.contains("\"id\":1"), "initialize was answered: {output}");
}

#[test]
fn input_that_ends_inside_a_frame_ends_the_server_cleanly() {
    let cases: [(&str, &[u8]); 4] = [
        ("in the headers", b"Content-Length: 10\r\n"),
        ("in a header line", b"Content-Len"),
        ("in the body", b"Content-Length: 100\r\n\r\n{\"jsonrpc\":"),
        ("with no Content-Length", b"Content-Type: x\r\n\r\n{}"),
    ];
    for (what, bytes) in cases {
        let result = stdio::read_message(&mut Cursor::new(bytes.to_vec()));
        match (what, &result) {
            ("with no Content-Length", Err(FrameError::Header(_))) => {}
            (_, Err(FrameError::Truncated)) => {}
            _ => panic!("{what}: {result:?}"),
        }
    }
    assert!(matches!(stdio::read_message(&mut Cursor::new(Vec::new())), Ok(None)));
    let long = format!("X-Long: {}\r\n", "a".repeat(1 << 20)).into_bytes();
    assert!(matches!(
        stdio::read_message(&mut Cursor::new(long)),
        Err(FrameError::Header(_))
    ));
    assert!(matches!(
        stdio::read_message(&mut Cursor::new(frame("{bad!!}"))),
        Err(FrameError::Malformed(_))
    ));

    let mut input = initialize_frame();
    input.extend_from_slice(b"Content-Length: 100\r\n\r\n{\"jsonrpc\":");
    let (code, reader) = finishes("the server on a cut-off frame", move || {
        let (connection, transport) = stdio::connect(Cursor::new(input), std::io::sink());
        let code = skill_language_server::serve(connection);
        (code, transport.reader.join().expect("the reader ends"))
    });
    assert_eq!(code, 1);
    assert!(matches!(reader, Err(FrameError::Truncated)), "{reader:?}");
}

#[test]
fn a_session_over_a_byte_stream_reads_every_frame_and_exits_0() {
    let mut input = initialize_frame();
    for message in [
        json!({ "jsonrpc": "2.0", "method": "initialized", "params": {} }),
        json!({ "jsonrpc": "2.0", "id": 2, "method": "shutdown" }),
        json!({ "jsonrpc": "2.0", "method": "exit" }),
    ] {
        input.extend(frame(&message.to_string()));
    }
    let (code, output) = finishes("a session", move || {
        let output = SharedBuffer::default();
        let (connection, transport) = stdio::connect(Cursor::new(input), output.clone());
        let code = skill_language_server::serve(connection);
        transport.writer.join().expect("the writer ends").expect("writes");
        transport.reader.join().expect("the reader ends").expect("reads");
        (code, output.text())
    });
    assert_eq!(code, 0);
    assert!(output.contains("\"id\":2"), "{output}");
}

/// An output the test can read after the writer thread took it.
#[derive(Clone, Default)]
struct SharedBuffer(std::sync::Arc<std::sync::Mutex<Vec<u8>>>);

impl SharedBuffer {
    fn text(&self) -> String {
        String::from_utf8_lossy(&self.0.lock().expect("lock")).into_owned()
    }
}

impl std::io::Write for SharedBuffer {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        self.0.lock().expect("lock").extend_from_slice(bytes);
        Ok(bytes.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

// ---------------------------------------------------------------- imports

fn scratch_dir(what: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("skillc-lsp-{what}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    dir
}

const SKILL: &str =
    "skill s {\n    learn { segments = none }\n    state a { on timeout 5 s -> done }\n    terminal done: success\n}\n";

/// The diagnostics the server's engine (reading disk) reports at the import of `path`, on
/// line 0 of a document that imports it; on a thread, with a deadline.
fn import_diagnostics(dir: &std::path::Path, path: &str) -> Vec<String> {
    let doc = format!("{}/doc.skill", dir.to_string_lossy());
    let text = format!("import \"{path}\"\n{SKILL}");
    finishes(&format!("importing {path}"), move || {
        let mut engine = Engine::new();
        engine.open(&doc, &text);
        let found = engine.check(&doc);
        found
            .into_iter()
            .filter(|(file, _)| *file == doc)
            .flat_map(|(_, diags)| diags)
            .filter(|d| d.range.start.line == 0)
            .map(|d| d.message)
            .collect()
    })
}

#[test]
fn imports_of_devices_standard_input_directories_and_large_files_are_diagnostics() {
    let dir = scratch_dir("imports");
    let zero = import_diagnostics(&dir, "/dev/zero");
    assert!(
        zero.iter()
            .any(|m| m.contains("`/dev/zero`") && m.contains("a device is not a regular file")),
        "{zero:?}"
    );
    let stdin = import_diagnostics(&dir, "/dev/stdin");
    let stdin_is_file = std::fs::metadata("/dev/stdin").is_ok_and(|m| m.is_file());
    if stdin_is_file {
        eprintln!("standard input is a regular file here: /dev/stdin is read as one");
    } else {
        assert!(stdin.iter().any(|m| m.contains("`/dev/stdin`")), "{stdin:?}");
    }
    let folder = import_diagnostics(&dir, &dir.to_string_lossy());
    assert!(folder.iter().any(|m| m.contains("a folder")), "{folder:?}");

    let large = dir.join("large.skill");
    let file = std::fs::File::create(&large).expect("create");
    file.set_len(MAX_IMPORT_BYTES + 1).expect("a sparse file");
    let over = import_diagnostics(&dir, "large.skill");
    assert!(over.iter().any(|m| m.contains("larger than 8 MiB")), "{over:?}");
    file.set_len(MAX_IMPORT_BYTES).expect("resize");
    let at_limit = import_diagnostics(&dir, "large.skill");
    assert!(
        at_limit.iter().all(|m| !m.contains("larger than 8 MiB")),
        "a file of the limit is read: {at_limit:?}"
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn an_import_of_a_fifo_is_a_diagnostic_not_a_hang() {
    let dir = scratch_dir("fifo");
    let fifo = dir.join("pipe.skill");
    match std::process::Command::new("mkfifo").arg(&fifo).status() {
        Ok(status) if status.success() => {}
        other => {
            eprintln!("skipped: mkfifo is not available here ({other:?})");
            return;
        }
    }
    let found = import_diagnostics(&dir, "pipe.skill");
    assert!(
        found.iter().any(|m| m.contains("pipe.skill") && m.contains("a FIFO")),
        "{found:?}"
    );

    // Through the protocol: the diagnostics are published and a request after is answered.
    let (server, client) = Connection::memory();
    let thread = std::thread::spawn(move || skill_language_server::serve(server));
    client
        .sender
        .send(
            Request::new(
                RequestId::from(1),
                "initialize".to_string(),
                json!({ "capabilities": {} }),
            )
            .into(),
        )
        .expect("send");
    let uri = format!("file://{}/doc.skill", dir.to_string_lossy());
    let text = format!("import \"pipe.skill\"\n{SKILL}");
    let notify = |method: &str, params: Value| {
        client
            .sender
            .send(Notification::new(method.to_string(), params).into())
            .expect("send");
    };
    notify("initialized", json!({}));
    notify(
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": uri, "languageId": "skill", "version": 1, "text": text } }),
    );
    client
        .sender
        .send(
            Request::new(
                RequestId::from(2),
                "textDocument/documentSymbol".to_string(),
                json!({ "textDocument": { "uri": uri } }),
            )
            .into(),
        )
        .expect("send");
    let (mut published, mut answered) = (None, false);
    while published.is_none() || !answered {
        match client.receiver.recv_timeout(DEADLINE).expect("the server answers") {
            Message::Notification(n) if n.params["uri"] == uri => {
                published = Some(n.params["diagnostics"].to_string());
            }
            Message::Response(r) if r.id == RequestId::from(2) => answered = true,
            _ => {}
        }
    }
    let published = published.unwrap_or_default();
    assert!(published.contains("a FIFO"), "{published}");
    notify("exit", Value::Null);
    assert_eq!(thread.join().expect("ends"), 1, "exit without shutdown");
    std::fs::remove_dir_all(&dir).expect("clean up");
}
