//! `skillc lsp`, the real binary over stdio: a session from `initialize` to `exit`, and a
//! malformed message that ends the server instead of hanging it. The engine and the protocol
//! loop in memory are tested in language-server/tests/engine.rs.

use serde_json::{json, Value};
use std::time::{Duration, Instant};

fn frame(message: &Value) -> Vec<u8> {
    let body = message.to_string();
    format!("Content-Length: {}\r\n\r\n{body}", body.len()).into_bytes()
}

/// Reads one framed message.
fn read_message(reader: &mut impl std::io::BufRead) -> Option<Value> {
    let mut length = None;
    loop {
        let mut line = String::new();
        if reader.read_line(&mut line).ok()? == 0 {
            return None;
        }
        let line = line.trim_end();
        if line.is_empty() {
            break;
        }
        if let Some(value) = line.strip_prefix("Content-Length: ") {
            length = value.parse::<usize>().ok();
        }
    }
    let mut body = vec![0; length?];
    reader.read_exact(&mut body).ok()?;
    serde_json::from_slice(&body).ok()
}

#[test]
fn the_binary_over_stdio() {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .arg("lsp")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("skillc lsp starts");
    let mut stdin = child.stdin.take().expect("stdin");
    let (sender, messages) = std::sync::mpsc::channel();
    let stdout = child.stdout.take().expect("stdout");
    std::thread::spawn(move || {
        let mut reader = std::io::BufReader::new(stdout);
        while let Some(message) = read_message(&mut reader) {
            if sender.send(message).is_err() {
                break;
            }
        }
    });
    let next = |pred: &dyn Fn(&Value) -> bool| -> Value {
        let deadline = Instant::now() + Duration::from_secs(30);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let message = messages.recv_timeout(left).expect("the server says something");
            if pred(&message) {
                return message;
            }
        }
    };
    let send = |stdin: &mut std::process::ChildStdin, message: Value| {
        stdin.write_all(&frame(&message)).expect("write");
        stdin.flush().expect("flush");
    };
    send(
        &mut stdin,
        json!({ "jsonrpc": "2.0", "id": 1, "method": "initialize", "params": { "capabilities": {} } }),
    );
    let init = next(&|m| m["id"] == 1);
    assert_eq!(init["result"]["capabilities"]["positionEncoding"], "utf-16");
    send(
        &mut stdin,
        json!({ "jsonrpc": "2.0", "method": "initialized", "params": {} }),
    );
    let file = "file:///tmp/skillc-lsp-binary/µ.skill";
    let text = "// µ°\nskill s {\n    learn { segments = none }\n    state a { on timeout 5 mm -> done }\n    terminal done: success\n}\n";
    send(
        &mut stdin,
        json!({ "jsonrpc": "2.0", "method": "textDocument/didOpen", "params": { "textDocument": { "uri": "file:///tmp/skillc-lsp-binary/%C2%B5.skill", "languageId": "skill", "version": 1, "text": text } } }),
    );
    let published = next(&|m| m["method"] == "textDocument/publishDiagnostics");
    assert_eq!(
        published["params"]["uri"], "file:///tmp/skillc-lsp-binary/%C2%B5.skill",
        "{file}"
    );
    let diags = published["params"]["diagnostics"].as_array().expect("a list");
    assert_eq!(diags.len(), 1, "{diags:?}");
    assert_eq!(diags[0]["code"], "skill::check::unit_mismatch");
    assert_eq!(diags[0]["source"], "skillc");
    let column = text.lines().nth(3).expect("line").find("5 mm").expect("5 mm");
    assert_eq!(diags[0]["range"]["start"], json!({ "line": 3, "character": column }));
    send(
        &mut stdin,
        json!({ "jsonrpc": "2.0", "id": 2, "method": "textDocument/hover", "params": { "textDocument": { "uri": "file:///tmp/skillc-lsp-binary/%C2%B5.skill" }, "position": { "line": 3, "character": column + 2 } } }),
    );
    let hover = next(&|m| m["id"] == 2);
    let value = hover["result"]["contents"]["value"].as_str().expect("markdown");
    assert!(value.contains("a length"), "{value}");
    let started = Instant::now();
    send(&mut stdin, json!({ "jsonrpc": "2.0", "id": 3, "method": "shutdown" }));
    let shutdown = next(&|m| m["id"] == 3);
    assert!(shutdown.get("error").is_none(), "{shutdown}");
    send(&mut stdin, json!({ "jsonrpc": "2.0", "method": "exit" }));
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        assert!(started.elapsed() < Duration::from_secs(5), "the server did not exit");
        std::thread::sleep(Duration::from_millis(10));
    };
    assert!(status.success(), "{status:?}");
    assert!(started.elapsed() < Duration::from_secs(2), "{:?}", started.elapsed());
}

#[test]
fn the_binary_ends_on_a_malformed_message_instead_of_hanging() {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .arg("lsp")
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("skillc lsp starts");
    let mut stdin = child.stdin.take().expect("stdin");
    stdin.write_all(b"Content-Length: 7\r\n\r\n{bad!!}").expect("write");
    stdin.flush().expect("flush");
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        assert!(started.elapsed() < Duration::from_secs(10), "the server hangs");
        std::thread::sleep(Duration::from_millis(10));
    };
    assert!(!status.success(), "{status:?}");
    drop(stdin);
}
