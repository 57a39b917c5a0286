//! `skillc lsp`: the engine on in-memory files (hover, completion, definition, references,
//! rename, formatting, symbols, snapshotted), diagnostics against `skillc check`'s, the protocol
//! over an in-memory connection (the binary over stdio: tests/lsp_stdio.rs).

use lsp_server::{Connection, Message, Notification, Request, RequestId, Response};
use lsp_types::Position;
use serde_json::{json, Value};
use skill_language_server::engine::Engine;
use skill_language_server::text::{Encoding, LineIndex};
use std::time::{Duration, Instant};

const PROBE: &str = include_str!("../../tests/data/lsp/probe.skill");
const ROOT: &str = "/mem/probe.skill";
const LIB: &str = "/mem/lib.skill";

fn lib_text() -> String {
    let touch = include_str!("../../stdlib-skills/touch.skill");
    touch.replace("skill touch", "skill tap")
}

fn engine(encoding: Encoding) -> Engine {
    let mut engine = Engine::in_memory();
    engine.encoding = encoding;
    engine.open(ROOT, PROBE);
    engine.open(LIB, &lib_text());
    engine
}

/// The position of the `nth` (from 0) occurrence of `needle` in `text`, `skip` bytes into it.
fn at(text: &str, needle: &str, nth: usize, skip: usize, encoding: Encoding) -> Position {
    let offset = text
        .match_indices(needle)
        .nth(nth)
        .unwrap_or_else(|| panic!("`{needle}` #{nth} is in the text"))
        .0;
    LineIndex::new(text, encoding).position(text, offset + skip)
}

fn pos(needle: &str, nth: usize, skip: usize) -> Position {
    at(PROBE, needle, nth, skip, Encoding::Utf16)
}

fn hover_text(engine: &Engine, position: Position) -> String {
    hover_text_in(engine, ROOT, position)
}

/// The hover's text at `position` in the document `name`.
fn hover_text_in(engine: &Engine, name: &str, position: Position) -> String {
    match engine.hover(name, position).map(|h| h.contents) {
        Some(lsp_types::HoverContents::Markup(markup)) => markup.value,
        other => format!("{other:?}"),
    }
}

#[test]
fn hover_explains_functions_units_states_params_limits_and_learned_names() {
    let engine = engine(Encoding::Utf16);
    let cases = [
        ("learn function", pos("force_aligned", 0, 2)),
        ("point function", pos("end(segment", 0, 1)),
        ("motion dmp", pos("dmp(segment 1", 0, 0)),
        ("unit", pos("2 s", 0, 2)),
        ("state doc comment", pos("-> settle", 0, 4)),
        ("learned frame", pos("in contact", 0, 4)),
        ("threshold", pos(">= touch", 0, 4)),
        ("param default", pos("dwell hold", 0, 7)),
        ("limit bound", pos("force: 40 N", 0, 1)),
        ("capture", pos("at found", 0, 4)),
        ("named guard", pos("motion_done", 0, 1)),
        ("builtin frame", pos("in base", 0, 4)),
        ("imported skill", pos("tap(demo", 0, 1)),
        ("step argument", pos("demo:", 0, 1)),
        ("import", pos("\"lib.skill\"", 0, 2)),
    ];
    let mut out = String::new();
    for (what, position) in cases {
        out.push_str(&format!(
            "## {what} ({}:{})\n{}\n\n",
            position.line,
            position.character,
            hover_text(&engine, position)
        ));
    }
    insta::assert_snapshot!(out);
    assert!(
        engine.hover(ROOT, pos("// Tilt", 0, 3)).is_none(),
        "nothing in a comment"
    );
}

fn show(location: &lsp_types::Location) -> String {
    let file = location.uri.as_str().rsplit('/').next().unwrap_or("").to_string();
    format!(
        "{file}:{}:{}-{}:{}",
        location.range.start.line,
        location.range.start.character,
        location.range.end.line,
        location.range.end.character
    )
}

#[test]
fn definition_and_references_cover_every_kind_of_name() {
    let engine = engine(Encoding::Utf16);
    let cases = [
        ("state", pos("-> settle", 0, 4)),
        ("terminal", pos("-> done", 0, 4)),
        ("frame", pos("in contact", 0, 4)),
        ("frame in guard", pos("force(contact.z)", 0, 7)),
        ("motion", pos("move approach", 0, 6)),
        ("threshold", pos(">= touch", 0, 4)),
        ("param", pos("dwell hold", 0, 7)),
        ("param set by a step", pos("hold: 3 s", 0, 1)),
        ("capture", pos("at found", 0, 4)),
        ("skill of a step", pos("= probe(", 0, 3)),
        ("imported skill", pos("tap(demo", 0, 1)),
        ("step in at:", pos("first.settle", 0, 1)),
        ("state in at:", pos("first.settle", 0, 7)),
        ("fallback", pos("-> rescue", 0, 4)),
        ("import", pos("\"lib.skill\"", 0, 2)),
    ];
    let mut out = String::new();
    for (what, position) in cases {
        let definition = engine
            .definition(ROOT, position)
            .map(|l| show(&l))
            .unwrap_or_else(|| "none".into());
        let references: Vec<String> = engine.references(ROOT, position, true).iter().map(show).collect();
        out.push_str(&format!(
            "{what}: definition {definition}; references {}\n",
            references.join(" ")
        ));
    }
    insta::assert_snapshot!(out);
}

fn labels(engine: &Engine, position: Position) -> String {
    let mut labels: Vec<String> = engine.completion(ROOT, position).into_iter().map(|i| i.label).collect();
    labels.sort();
    labels.join(" ")
}

#[test]
fn completion_offers_what_may_stand_at_each_place() {
    let mut engine = engine(Encoding::Utf16);
    let mut out = String::new();
    // Each case edits the probe (a line being typed) and completes at its end.
    let cases: [(&str, &str, &str); 12] = [
        ("after ->", "on timeout 30 s -> missed", "on timeout 30 s -> "),
        ("after in", "control position all in base", "control position all in "),
        ("after move", "move back at found", "move "),
        ("after move ... at", "move back at found", "move back at "),
        ("after a number", "on timeout 30 s -> missed", "on timeout 30 "),
        ("a guard after on", "on dwell hold -> retract", "on "),
        ("a statement", "on dwell hold -> retract", ""),
        (
            "after a comparison",
            "on force(contact.z) >= touch -> settle",
            "on force(contact.z) >= ",
        ),
        ("a motion function", "motion back = dmp(segment 2)", "motion back = "),
        ("a limit", "force: 40 N", ""),
        (
            "a step's skill",
            "step first = probe(demo: \"probe.csv\", hold: 3 s)",
            "step first = ",
        ),
        (
            "a step's arguments",
            "step first = probe(demo: \"probe.csv\", hold: 3 s)",
            "step first = probe(",
        ),
    ];
    for (what, line, typed) in cases {
        let text = PROBE.replacen(line, typed, 1);
        engine.open(ROOT, &text);
        let offset = text.find(PROBE.split(line).next().unwrap_or("")).unwrap_or(0)
            + PROBE.split(line).next().unwrap_or("").len()
            + typed.len();
        let position = LineIndex::new(&text, Encoding::Utf16).position(&text, offset);
        out.push_str(&format!("{what}: {}\n", labels(&engine, position)));
    }
    engine.open(ROOT, PROBE);
    let functions = engine.completion(ROOT, pos("dmp(segment 2)", 0, 0));
    let dmp = functions.iter().find(|i| i.label == "dmp").expect("dmp is offered");
    out.push_str(&format!("dmp: {:?} inserts {:?}\n", dmp.detail, dmp.insert_text));
    assert!(
        engine.completion(ROOT, pos("// Tilt", 0, 5)).is_empty(),
        "nothing in a comment"
    );
    insta::assert_snapshot!(out);
}

#[test]
fn rename_edits_every_use_and_refuses_keywords() {
    let engine = engine(Encoding::Utf16);
    let edit = engine
        .rename(ROOT, pos("-> settle", 0, 4), "rest")
        .expect("a state renames");
    assert!(edit.changes.is_some(), "edits");
    let mut lines: Vec<String> = edit
        .changes
        .iter()
        .flatten()
        .flat_map(|(uri, edits)| {
            edits
                .iter()
                .map(move |e| show(&lsp_types::Location::new(uri.clone(), e.range)))
        })
        .collect();
    lines.sort();
    assert_eq!(lines.len(), 3, "declaration, transition, `at: first.settle`: {lines:?}");
    let skill = engine
        .rename(ROOT, pos("tap(demo", 0, 1), "tap2")
        .expect("an imported skill renames");
    assert_eq!(
        skill.changes.expect("edits").len(),
        2,
        "the task's file and the skill's file"
    );
    for keyword in ["state", "on", "skill", "all"] {
        let err = engine
            .rename(ROOT, pos("-> settle", 0, 4), keyword)
            .expect_err("a keyword is refused");
        assert!(err.contains("keyword"), "{err}");
    }
    assert!(engine.rename(ROOT, pos("-> settle", 0, 4), "2x").is_err());
    assert!(
        engine.rename(ROOT, pos("-> settle", 0, 4), "done").is_err(),
        "clashes with a terminal"
    );
    assert!(
        engine.rename(ROOT, pos("motion_done", 0, 1), "x").is_err(),
        "a built-in guard"
    );
    insta::assert_snapshot!(lines.join("\n"));
}

#[test]
fn formatting_is_skillc_fmt_as_one_edit() {
    let engine = engine(Encoding::Utf16);
    let edits = engine.format(ROOT).expect("the probe parses");
    assert_eq!(edits.len(), 1);
    let source = skill_compiler::SourceFile::new(ROOT, PROBE);
    let (ast, _) = skill_compiler::syntax::parse(&source, 0);
    assert_eq!(edits[0].new_text, skill_compiler::fmt::format(&source, &ast));
    assert_eq!(edits[0].range.start, Position::new(0, 0));
    assert_eq!(
        edits[0].range.end,
        LineIndex::new(PROBE, Encoding::Utf16).position(PROBE, PROBE.len())
    );
    let mut formatted = Engine::in_memory();
    formatted.open(ROOT, &edits[0].new_text);
    assert_eq!(
        formatted.format(ROOT),
        Some(Vec::new()),
        "a formatted file needs no edit"
    );
    formatted.open(ROOT, "skill {");
    assert_eq!(formatted.format(ROOT), None, "a file that does not parse is left alone");
}

#[test]
fn document_symbols_list_skills_tasks_and_their_parts() {
    let engine = engine(Encoding::Utf16);
    let mut out = String::new();
    for symbol in engine.symbols(ROOT) {
        out.push_str(&format!(
            "{} {:?} {}\n",
            symbol.name, symbol.kind, symbol.range.start.line
        ));
        for child in symbol.children.unwrap_or_default() {
            out.push_str(&format!(
                "  {} {:?}: {}\n",
                child.name,
                child.kind,
                child.detail.unwrap_or_default()
            ));
        }
    }
    insta::assert_snapshot!(out);
}

/// A file with errors, warnings, related spans and non-ASCII text before them on their lines.
const BROKEN: &str = "skill s {\n    learn {\n        segments = none\n        motion m = dmp(segment 1)\n        motion m = dmp(segment 1)\n    }\n    state a { /* ° */ move m  /// µ·\n        on timeout 5 mm -> b // ° µ\n    }\n    terminal b: success \"5° µ\"\n}\n";

#[test]
fn diagnostics_are_skillc_checks_with_columns_in_the_clients_encoding() {
    let dir = std::env::temp_dir().join(format!("skillc-lsp-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let text = "// µ° ·\nskill s {\n    learn {\n        segments = none\n        motion m = dmp(segment 1)\n        motion m = dmp(segment 1)\n    }\n    state a {\n        move m\n        /// 5° µ·\n        on timeout 5 mm -> b\n    }\n    terminal b: success \"5° µ\" terminal b: failure\n}\n";
    let path = dir.join("broken.skill");
    std::fs::write(&path, text).expect("write");
    let name = path.to_string_lossy().to_string();
    let check = skill_kit::frontend::compile_path(&path).expect("readable");
    assert!(check.diags.len() >= 3, "{:?}", check.diags);
    for encoding in [Encoding::Utf16, Encoding::Utf8] {
        let mut engine = Engine::new();
        engine.encoding = encoding;
        engine.open(&name, text);
        let published = engine.diagnostics(&name);
        assert_eq!(published.len(), 1, "one file");
        assert_eq!(published[0].0, name);
        let lsp = &published[0].1;
        assert_eq!(lsp.len(), check.diags.len());
        let lines = LineIndex::new(text, encoding);
        for (ours, theirs) in lsp.iter().zip(&check.diags) {
            assert_eq!(
                ours.code,
                Some(lsp_types::NumberOrString::String(theirs.code.as_str().to_string()))
            );
            assert!(
                ours.message.starts_with(&theirs.message),
                "{} / {}",
                ours.message,
                theirs.message
            );
            assert_eq!(ours.range, lines.range(text, theirs.span()));
            // The column is the client's: on a line with non-ASCII text, UTF-16 and UTF-8 differ.
            let (line, column) = check.files[0].line_col(theirs.span().start);
            assert_eq!(ours.range.start.line as usize, line - 1);
            let prefix = &text[text.lines().take(line - 1).map(|l| l.len() + 1).sum::<usize>()..theirs.span().start];
            assert_eq!(prefix.chars().count(), column - 1);
            let units = match encoding {
                Encoding::Utf16 => prefix.encode_utf16().count(),
                Encoding::Utf8 => prefix.len(),
            };
            assert_eq!(ours.range.start.character as usize, units);
        }
        let duplicate = lsp
            .iter()
            .find(|d| d.related_information.is_some())
            .expect("a duplicate has related spans");
        let related = &duplicate.related_information.as_ref().expect("related")[0];
        assert!(related.location.uri.as_str().ends_with("broken.skill"));
        assert_eq!(related.location.range.start.line, 4, "the first `motion m`");
        // The terminal line carries `°` and `µ` before the duplicate `b`.
        let on_terminal = lsp
            .iter()
            .find(|d| d.range.start.line == 12)
            .expect("a diagnostic on the terminal line");
        let expected = at(text, "terminal b: failure", 0, 9, encoding);
        assert_eq!(on_terminal.range.start, expected, "{encoding:?}");
    }
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn an_import_is_read_from_the_open_document_before_the_disk() {
    let mut engine = Engine::in_memory();
    engine.open(ROOT, PROBE);
    let missing = engine.diagnostics(ROOT);
    assert!(
        missing[0].1.iter().any(|d| d.message.contains("lib.skill")),
        "the import is missing: {missing:?}"
    );
    engine.open(LIB, &lib_text());
    let fine = engine.diagnostics(ROOT);
    assert_eq!(fine.len(), 1);
    assert!(fine[0].1.is_empty(), "{fine:?}");
    engine.open(LIB, &lib_text().replace("move approach from current", "move aproach"));
    let broken = engine.diagnostics(ROOT);
    let in_lib = broken
        .iter()
        .find(|(file, _)| file == LIB)
        .expect("the import's problem is published for it");
    assert!(in_lib.1.iter().any(|d| d.message.contains("aproach")), "{in_lib:?}");
}

#[test]
fn nothing_panics_on_any_position_of_any_shipped_or_broken_file() {
    let mut texts: Vec<String> = vec![
        PROBE.to_string(),
        BROKEN.to_string(),
        "skill".into(),
        "".into(),
        "\u{feff}skill s { state a {".into(),
    ];
    for dir in ["stdlib-skills", "examples/tasks"] {
        for entry in std::fs::read_dir(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(dir))
            .expect("shipped skills")
        {
            texts.push(std::fs::read_to_string(entry.expect("entry").path()).expect("text"));
        }
    }
    // Files cut anywhere, as while typing: every one a prefix of the probe.
    let boundaries: Vec<usize> = (0..PROBE.len()).filter(|&at| PROBE.is_char_boundary(at)).collect();
    for at in boundaries.iter().step_by(boundaries.len() / 25) {
        texts.push(PROBE[..*at].to_string());
    }
    let mut answered = 0;
    for text in &texts {
        let mut engine = Engine::in_memory();
        engine.open(ROOT, text);
        let lines = LineIndex::new(text, Encoding::Utf16);
        let step = (text.len() / 40).max(1);
        for offset in (0..=text.len()).step_by(step) {
            let position = lines.position(text, offset);
            answered += usize::from(engine.hover(ROOT, position).is_some());
            let _ = engine.definition(ROOT, position);
            let _ = engine.references(ROOT, position, true);
            let _ = engine.completion(ROOT, position);
            let _ = engine.rename(ROOT, position, "renamed");
        }
        let _ = engine.symbols(ROOT);
        let _ = engine.format(ROOT);
        let _ = engine.diagnostics(ROOT);
        let _ = engine.hover(ROOT, Position::new(9999, 9999));
    }
    assert!(answered > 50, "hover answered {answered} times");
}

// ---------------------------------------------------------------- the protocol

fn request(id: i32, method: &str, params: Value) -> Message {
    Request::new(RequestId::from(id), method.to_string(), params).into()
}

fn notification(method: &str, params: Value) -> Message {
    Notification::new(method.to_string(), params).into()
}

/// Waits for the response to request `id`, collecting notifications on the way.
fn response(client: &Connection, id: i32, seen: &mut Vec<Notification>) -> Response {
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        match client.receiver.recv_timeout(left).expect("the server answers") {
            Message::Response(response) if response.id == RequestId::from(id) => return response,
            Message::Notification(n) => seen.push(n),
            _ => {}
        }
    }
}

fn initialize(client: &Connection, encodings: Value) -> Value {
    client
        .sender
        .send(request(
            1,
            "initialize",
            json!({ "capabilities": { "general": { "positionEncodings": encodings } } }),
        ))
        .expect("send");
    let answer = response(client, 1, &mut Vec::new());
    client
        .sender
        .send(notification("initialized", json!({})))
        .expect("send");
    answer.result.expect("initialize succeeds")
}

#[test]
fn the_protocol_over_a_memory_connection() {
    let (server, client) = Connection::memory();
    let thread = std::thread::spawn(move || skill_language_server::serve(server));
    let result = initialize(&client, json!(["utf-8", "utf-16"]));
    assert_eq!(result["capabilities"]["positionEncoding"], "utf-8");
    assert_eq!(result["capabilities"]["renameProvider"]["prepareProvider"], true);

    let dir = std::env::temp_dir().join(format!("skillc-lsp-proto-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let name = format!("{}/a b.skill", dir.to_string_lossy());
    let file_uri = format!("file://{}", name.replace(' ', "%20"));
    let broken = "// ° µ\nskill s {\n    learn { segments = none }\n    state a { on timeout 5 mm -> done }\n    terminal done: success\n}\n";
    client
        .sender
        .send(notification(
            "textDocument/didOpen",
            json!({ "textDocument": { "uri": file_uri, "languageId": "skill", "version": 1, "text": broken } }),
        ))
        .expect("send");
    let diags = loop {
        let Message::Notification(n) = client
            .receiver
            .recv_timeout(Duration::from_secs(20))
            .expect("published")
        else {
            continue;
        };
        if n.params["uri"] == file_uri {
            break n.params["diagnostics"].as_array().cloned().unwrap_or_default();
        }
    };
    assert_eq!(diags.len(), 1, "{diags:?}");
    assert_eq!(diags[0]["code"], "skill::check::unit_mismatch");
    assert_eq!(diags[0]["range"]["start"]["line"], 3);

    // Several quick changes publish once, after the last; the fix clears the diagnostics.
    let fixed = broken.replace("5 mm", "5 s");
    let started = Instant::now();
    for (version, text) in [(2, broken.replace("5 mm", "6 mm")), (3, fixed.clone())] {
        client
            .sender
            .send(notification(
                "textDocument/didChange",
                json!({ "textDocument": { "uri": file_uri, "version": version }, "contentChanges": [{ "text": text }] }),
            ))
            .expect("send");
    }
    let cleared = loop {
        let Message::Notification(n) = client
            .receiver
            .recv_timeout(Duration::from_secs(20))
            .expect("published")
        else {
            continue;
        };
        if n.params["uri"] == file_uri {
            break n.params["diagnostics"].as_array().cloned().unwrap_or_default();
        }
    };
    assert!(cleared.is_empty(), "{cleared:?}");
    assert!(started.elapsed() >= skill_language_server::DEBOUNCE, "debounced");

    // Hover in UTF-8 columns: `done` on line 3.
    let column = fixed.lines().nth(3).expect("line").find("done").expect("done") as u32;
    client
        .sender
        .send(request(
            2,
            "textDocument/hover",
            json!({ "textDocument": { "uri": file_uri }, "position": { "line": 3, "character": column + 1 } }),
        ))
        .expect("send");
    let hover = response(&client, 2, &mut Vec::new());
    let value = hover.result.expect("hover answers");
    assert!(
        value["contents"]["value"]
            .as_str()
            .expect("markdown")
            .contains("terminal done: success"),
        "{value}"
    );

    client
        .sender
        .send(request(3, "textDocument/unknownThing", json!({})))
        .expect("send");
    assert_eq!(
        response(&client, 3, &mut Vec::new()).error.expect("an error").code,
        -32601
    );
    client
        .sender
        .send(request(4, "textDocument/hover", json!({ "textDocument": 5 })))
        .expect("send");
    assert_eq!(
        response(&client, 4, &mut Vec::new()).error.expect("an error").code,
        -32602
    );
    client
        .sender
        .send(request(
            5,
            "textDocument/definition",
            json!({ "textDocument": { "uri": "file:///nowhere.skill" }, "position": { "line": 0, "character": 0 } }),
        ))
        .expect("send");
    assert_eq!(response(&client, 5, &mut Vec::new()).result, Some(Value::Null));
    client
        .sender
        .send(request(6, "textDocument/rename", json!({ "textDocument": { "uri": file_uri }, "position": { "line": 3, "character": column + 1 }, "newName": "state" })))
        .expect("send");
    let refused = response(&client, 6, &mut Vec::new())
        .error
        .expect("a keyword is refused");
    assert!(refused.message.contains("keyword"), "{}", refused.message);
    client
        .sender
        .send(notification(
            "textDocument/didClose",
            json!({ "textDocument": { "uri": file_uri } }),
        ))
        .expect("send");

    let started = Instant::now();
    client.sender.send(request(7, "shutdown", Value::Null)).expect("send");
    assert!(response(&client, 7, &mut Vec::new()).error.is_none());
    client.sender.send(notification("exit", Value::Null)).expect("send");
    let code = thread.join().expect("the server thread ends");
    assert_eq!(code, 0);
    assert!(started.elapsed() < Duration::from_secs(1), "{:?}", started.elapsed());
    std::fs::remove_dir_all(&dir).expect("clean up");
}

// ---------------------------------------------------------------- the binary

#[test]
fn requests_before_initialize_and_after_shutdown_are_refused_and_exit_without_shutdown_is_1() {
    let (server, client) = Connection::memory();
    let thread = std::thread::spawn(move || skill_language_server::serve(server));
    client
        .sender
        .send(request(1, "textDocument/hover", json!({})))
        .expect("send");
    assert_eq!(
        response(&client, 1, &mut Vec::new()).error.expect("refused").code,
        -32002,
        "server not initialized"
    );
    // No `initialized` notification: the server answers all the same.
    client
        .sender
        .send(request(2, "initialize", json!({ "capabilities": {} })))
        .expect("send");
    assert!(response(&client, 2, &mut Vec::new()).result.is_some());
    client
        .sender
        .send(request(
            3,
            "textDocument/documentSymbol",
            json!({ "textDocument": { "uri": "file:///none.skill" } }),
        ))
        .expect("send");
    assert_eq!(response(&client, 3, &mut Vec::new()).result, Some(json!([])));
    client.sender.send(request(4, "shutdown", Value::Null)).expect("send");
    assert!(response(&client, 4, &mut Vec::new()).error.is_none());
    client
        .sender
        .send(request(5, "textDocument/hover", json!({})))
        .expect("send");
    assert_eq!(
        response(&client, 5, &mut Vec::new()).error.expect("refused").code,
        -32600
    );
    client.sender.send(notification("exit", Value::Null)).expect("send");
    assert_eq!(thread.join().expect("ends"), 0);

    let (server, client) = Connection::memory();
    let thread = std::thread::spawn(move || skill_language_server::serve(server));
    initialize(&client, json!([]));
    client.sender.send(notification("exit", Value::Null)).expect("send");
    assert_eq!(thread.join().expect("ends"), 1, "exit without shutdown");

    let (server, client) = Connection::memory();
    let thread = std::thread::spawn(move || skill_language_server::serve(server));
    initialize(&client, json!([]));
    drop(client);
    assert_eq!(thread.join().expect("ends"), 1, "the client went away");
}

#[test]
fn references_and_rename_reach_the_open_documents_that_import_a_skill() {
    let engine = engine(Encoding::Utf16);
    let lib = lib_text();
    let position = at(&lib, "skill tap", 0, 7, Encoding::Utf16);
    let found: Vec<String> = engine.references(LIB, position, true).iter().map(show).collect();
    assert_eq!(
        found,
        [
            "lib.skill:7:6-7:9",
            "probe.skill:42:18-42:21",
            "probe.skill:43:22-43:25"
        ],
        "the declaration and the two steps of the task that imports it"
    );
    let without: Vec<String> = engine.references(LIB, position, false).iter().map(show).collect();
    assert_eq!(without.len(), 2, "{without:?}");
    let edit = engine.rename(LIB, position, "tap_once").expect("renames");
    let files: Vec<String> = edit
        .changes
        .iter()
        .flatten()
        .map(|(uri, edits)| format!("{} {}", uri.as_str(), edits.len()))
        .collect();
    assert_eq!(files.len(), 2, "{files:?}");
    assert!(files.contains(&"file:///mem/probe.skill 2".to_string()), "{files:?}");
}

#[test]
fn completion_of_an_axis_frame_in_learn() {
    let mut engine = engine(Encoding::Utf16);
    let typed = PROBE.replace("threshold touch = 2 N", "force press = constant(segment 2, along: ");
    engine.open(ROOT, &typed);
    let offset = typed.find("along: ").expect("typed") + "along: ".len();
    let position = LineIndex::new(&typed, Encoding::Utf16).position(&typed, offset);
    let labels: Vec<String> = engine.completion(ROOT, position).into_iter().map(|i| i.label).collect();
    assert_eq!(labels, ["contact", "base", "tool"]);
}

#[test]
fn completion_of_entry_actions_control_modes_and_outcomes() {
    let mut engine = engine(Encoding::Utf16);
    for (line, typed, expected) in [
        (
            "        move approach\n",
            "        entry \n",
            "reset_integral shift_goal tare",
        ),
        (
            "        move approach\n",
            "        control position x y z, \n",
            "force position",
        ),
        (
            "    terminal missed: failure\n",
            "    terminal missed: \n",
            "failure success",
        ),
    ] {
        let text = PROBE.replacen(line, typed, 1);
        engine.open(ROOT, &text);
        let offset = text.find(typed).expect("typed") + typed.len() - 1;
        let position = LineIndex::new(&text, Encoding::Utf16).position(&text, offset);
        assert_eq!(labels(&engine, position), expected, "{typed:?}");
    }
}

#[test]
fn a_parameter_inside_arithmetic_is_found_hovered_and_renamed() {
    let text = include_str!("../../compiler/tests/corpus/ok/arithmetic.skill");
    let name = "/mem/arithmetic.skill";
    let mut engine = Engine::in_memory();
    engine.open(name, text);
    let here = |needle: &str, skip: usize| at(text, needle, 0, skip, Encoding::Utf16);
    // `inset` in `within inset + 2 cm` and in `-inset - 5 mm` lead to its declaration.
    let declared = here("param inset", 6);
    for use_at in [here("within inset", 7), here("-inset - 5 mm", 1)] {
        let found = engine.definition(name, use_at).expect("a definition");
        assert_eq!(found.range.start, declared, "{use_at:?}");
    }
    let references = engine.references(name, declared, true);
    assert_eq!(references.len(), 3, "the declaration and two uses: {references:?}");
    let hover = hover_text_in(&engine, name, here("hold / 2", 0));
    assert!(hover.contains("2 s"), "the default is shown: {hover}");
    let watch = hover_text_in(&engine, name, here("watch force", 1));
    assert!(watch.contains("expects no contact"), "hover on `watch`: {watch}");
    let edit = engine.rename(name, declared, "margin").expect("renames");
    let edits: usize = edit.changes.iter().flat_map(|c| c.values()).map(Vec::len).sum();
    assert_eq!(edits, 3);
}

#[test]
fn the_keyword_since_is_hovered_and_its_capture_found() {
    let text = include_str!("../../compiler/tests/corpus/ok/captures.skill");
    let name = "/mem/captures.skill";
    let mut engine = Engine::in_memory();
    engine.open(name, text);
    let hover = |position: Position| hover_text_in(&engine, name, position);
    let keyword = hover(at(text, "since found", 0, 2, Encoding::Utf16));
    assert!(keyword.contains("capture NAME"), "hover on `since`: {keyword}");
    assert!(
        keyword.contains("rather than from where the state was entered"),
        "{keyword}"
    );
    // The name after it is still the capture's, with its own hover.
    let capture = hover(at(text, "since found", 0, 7, Encoding::Utf16));
    assert!(
        !capture.contains("rather than from where"),
        "hover on the capture: {capture}"
    );
    assert!(capture.contains("found"), "{capture}");
}

#[test]
fn a_parameter_inside_another_parameters_default_is_found_and_renamed() {
    let text = "skill s {\n    param hold = 4 s\n    param settle = hold / 4\n    learn {\n        segments = max_force\n        motion m = dmp(segment 1)\n    }\n    state a {\n        move m\n        on dwell settle -> d\n        on motion_done -> d\n    }\n    terminal d: success\n}\n";
    let name = "/mem/derived.skill";
    let mut engine = Engine::in_memory();
    engine.open(name, text);
    let declared = at(text, "hold = 4 s", 0, 0, Encoding::Utf16);
    let found = engine
        .definition(name, at(text, "hold / 4", 0, 1, Encoding::Utf16))
        .expect("a definition");
    assert_eq!(found.range.start, declared);
    let edit = engine.rename(name, declared, "pause").expect("renames");
    let edits: usize = edit.changes.iter().flat_map(|c| c.values()).map(Vec::len).sum();
    assert_eq!(edits, 2, "the declaration and the use in `settle`'s default");
}
