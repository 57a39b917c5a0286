//! Incremental checking: in a workspace of 2 000 generated open documents, an edit re-checks
//! the edited document and the open documents that import it, directly or not, and no other
//! (counted by the engine's compilations); a burst of opens checks each document once; and
//! over the protocol an edit among 2 000 open documents is published.

use lsp_server::{Connection, Message, Notification, Request, RequestId};
use serde_json::{json, Value};
use skill_language_server::engine::Engine;
use skill_language_server::workspace::Workspace;
use std::time::Duration;

const DOCS: usize = 2_000;
const BASE: &str = "/mem/base.skill";
const SHARED: &str = "/mem/shared.skill";

fn skill(name: &str, timeout: &str) -> String {
    format!(
        "skill {name} {{\n    learn {{ segments = none }}\n    state a {{ on timeout {timeout} -> done }}\n    terminal done: success\n}}\n"
    )
}

fn doc_name(i: usize) -> String {
    format!("/mem/doc{i}.skill")
}

/// Every tenth document imports `shared.skill`, which imports `base.skill`.
fn doc_text(i: usize, timeout: &str) -> String {
    let import = if i.is_multiple_of(10) {
        "import \"shared.skill\"\n"
    } else {
        ""
    };
    format!("{import}{}", skill(&format!("s{i}"), timeout))
}

fn importers() -> Vec<String> {
    let mut names: Vec<String> = (0..DOCS).filter(|i| i.is_multiple_of(10)).map(doc_name).collect();
    names.sort();
    names
}

/// The generated workspace, opened and checked.
fn workspace() -> Workspace {
    let mut workspace = Workspace::new(Engine::in_memory());
    let mut all = vec![
        (BASE.to_string(), skill("base", "5 s")),
        (
            SHARED.to_string(),
            format!("import \"base.skill\"\n{}", skill("shared", "5 s")),
        ),
    ];
    all.extend((0..DOCS).map(|i| (doc_name(i), doc_text(i, "5 s"))));
    for (name, text) in &all {
        workspace.engine.open(name, text);
        workspace.changed(name);
    }
    workspace.check_all();
    workspace
}

/// How many compilations an edit of `name` to `text` costs.
fn edit(workspace: &mut Workspace, name: &str, text: &str) -> usize {
    let before = workspace.engine.compilations();
    workspace.engine.open(name, text);
    workspace.changed(name);
    workspace.check_all();
    workspace.engine.compilations() - before
}

#[test]
fn a_burst_of_opens_checks_each_document_once() {
    let workspace = workspace();
    assert_eq!(workspace.engine.compilations(), DOCS + 2);
}

#[test]
fn an_edit_rechecks_the_document_and_its_importers_only() {
    let mut workspace = workspace();
    workspace.publications();

    // A document nothing imports: itself.
    assert_eq!(edit(&mut workspace, &doc_name(7), &doc_text(7, "6 mm")), 1);
    let published = workspace.publications();
    assert_eq!(published.len(), 1, "{published:?}");
    assert_eq!(published[0].0, doc_name(7));
    assert_eq!(published[0].1.len(), 1, "the unit mismatch");
    // An importer: itself (nothing imports it).
    assert_eq!(edit(&mut workspace, &doc_name(10), &doc_text(10, "6 s")), 1);

    // The shared skill: itself and its 200 importers.
    assert_eq!(workspace.engine.readers(SHARED), importers());
    let text = format!("import \"base.skill\"\n{}", skill("shared", "6 s"));
    assert_eq!(edit(&mut workspace, SHARED, &text), 1 + DOCS / 10);

    // The skill the shared one imports: itself, the shared one and, through it, the 200.
    let mut readers = importers();
    readers.push(SHARED.to_string());
    readers.sort();
    assert_eq!(workspace.engine.readers(BASE), readers);
    assert_eq!(edit(&mut workspace, BASE, &skill("base", "7 mm")), 2 + DOCS / 10);
    let published = workspace.publications();
    let base = published.iter().find(|(file, _)| file == BASE).expect("base published");
    assert_eq!(base.1.len(), 1, "once, not once per importer: {:?}", base.1);

    // Closing the shared skill: its importers now fail to import it.
    let before = workspace.engine.compilations();
    workspace.engine.close(SHARED);
    workspace.changed(SHARED);
    workspace.check_all();
    assert_eq!(workspace.engine.compilations() - before, DOCS / 10);
    // Opening it again: the importers read it again.
    let text = format!("import \"base.skill\"\n{}", skill("shared", "5 s"));
    assert_eq!(edit(&mut workspace, SHARED, &text), 1 + DOCS / 10);
}

#[test]
fn references_compile_only_the_documents_that_read_the_declaring_file() {
    let workspace = workspace();
    let before = workspace.engine.compilations();
    // `skill shared` on line 1 of shared.skill.
    let found = workspace
        .engine
        .references(SHARED, lsp_types::Position::new(1, 8), true);
    assert_eq!(found.len(), 1, "the declaration: {found:?}");
    assert_eq!(
        workspace.engine.compilations() - before,
        1 + DOCS / 10,
        "shared.skill and its importers, not the other documents"
    );
}

#[test]
fn a_document_opened_after_its_importer_rechecks_the_importer() {
    let mut workspace = Workspace::new(Engine::in_memory());
    workspace.engine.open(&doc_name(0), &doc_text(0, "5 s"));
    workspace.changed(&doc_name(0));
    workspace.check_all();
    let missing = workspace.publications();
    assert!(
        missing
            .iter()
            .any(|(_, d)| d.iter().any(|d| d.message.contains("cannot import"))),
        "{missing:?}"
    );
    let before = workspace.engine.compilations();
    workspace.engine.open(SHARED, &skill("shared", "5 s"));
    workspace.changed(SHARED);
    workspace.check_all();
    assert_eq!(
        workspace.engine.compilations() - before,
        2,
        "the new document and its importer"
    );
    let now = workspace.publications();
    let doc = now.iter().find(|(f, _)| *f == doc_name(0)).expect("republished");
    assert!(doc.1.is_empty(), "{:?}", doc.1);
}

#[test]
fn an_edit_among_2000_open_documents_is_published_over_the_protocol() {
    let (server, client) = Connection::memory();
    let thread = std::thread::spawn(move || skill_language_server::serve(server));
    let send = |message: Message| client.sender.send(message).expect("send");
    let notify = |method: &str, params: Value| send(Notification::new(method.to_string(), params).into());
    send(
        Request::new(
            RequestId::from(1),
            "initialize".to_string(),
            json!({ "capabilities": {} }),
        )
        .into(),
    );
    notify("initialized", json!({}));
    let uri = |name: &str| format!("file://{name}");
    let open = |name: &str, text: &str| {
        notify(
            "textDocument/didOpen",
            json!({ "textDocument": { "uri": uri(name), "languageId": "skill", "version": 1, "text": text } }),
        );
    };
    open(BASE, &skill("base", "5 s"));
    open(SHARED, &format!("import \"base.skill\"\n{}", skill("shared", "5 s")));
    for i in 0..DOCS {
        open(&doc_name(i), &doc_text(i, "5 s"));
    }
    let target = uri(&doc_name(1234));
    notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": target, "version": 2 }, "contentChanges": [{ "text": doc_text(1234, "5 mm") }] }),
    );
    let diags = loop {
        let message = client
            .receiver
            .recv_timeout(Duration::from_secs(60))
            .expect("published");
        if let Message::Notification(n) = message {
            let diags = n.params["diagnostics"].as_array().cloned().unwrap_or_default();
            if n.params["uri"] == target.as_str() && !diags.is_empty() {
                break diags;
            }
        }
    };
    assert_eq!(diags[0]["code"], "skill::check::unit_mismatch");
    notify("exit", Value::Null);
    assert_eq!(thread.join().expect("ends"), 1);
}
