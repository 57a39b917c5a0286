//! Bench binary (`cargo bench --bench lsp [-- ROUNDS]`): how long `skillc lsp` takes to publish
//! the diagnostics of an edit with 1, 100 and 2 000 open documents, and the memory each open
//! document costs.
//!
//! The documents are generated: small skills, every tenth importing a shared skill that imports
//! a base skill. For each workspace size it measures, as medians over ROUNDS edits (default 30):
//! - `engine`: the server's work for an edit of one document that nothing imports (queue it and
//!   the documents that read it, check, collect what to publish), on the [`Workspace`] alone;
//! - `engine shared`: the same for an edit of the shared skill (it and its importers);
//! - `protocol`: from sending `didChange` on an in-memory connection to receiving the document's
//!   `publishDiagnostics`, minus the server's [`DEBOUNCE`] (which it waits on purpose);
//! - `full re-check`: compiling every open document once, what each edit cost before checks
//!   became incremental;
//! - `open`: from the first `didOpen` to the last document's first `publishDiagnostics`;
//! - memory: the growth of the process's resident set (`VmRSS`) while the workspace is opened
//!   and checked, per document.

use skill_language_server::engine::Engine;
use skill_language_server::lsp_server::{Connection, Message, Notification, Request, RequestId};
use skill_language_server::workspace::Workspace;
use skill_language_server::DEBOUNCE;
use std::time::{Duration, Instant};

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

fn doc_text(i: usize, timeout: &str) -> String {
    let import = if i.is_multiple_of(10) {
        "import \"shared.skill\"\n"
    } else {
        ""
    };
    format!("{import}{}", skill(&format!("s{i}"), timeout))
}

fn shared_text(timeout: &str) -> String {
    format!("import \"base.skill\"\n{}", skill("shared", timeout))
}

/// Every document of a workspace of `n`: the base and shared skills, then `n` others.
fn documents(n: usize) -> Vec<(String, String)> {
    let mut all = vec![
        (BASE.to_string(), skill("base", "5 s")),
        (SHARED.to_string(), shared_text("5 s")),
    ];
    all.extend((0..n).map(|i| (doc_name(i), doc_text(i, "5 s"))));
    all
}

/// The resident set of this process, in KiB.
fn rss_kib() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|line| line.strip_prefix("VmRSS:"))
        .and_then(|rest| rest.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0)
}

fn median(mut values: Vec<Duration>) -> Duration {
    values.sort();
    values[values.len() / 2]
}

fn ms(d: Duration) -> String {
    format!("{:.3}", d.as_secs_f64() * 1e3)
}

/// The timing of an edit on the workspace alone: queue, check until the queue is empty,
/// collect the publications; asserts the edited file's diagnostics are among them.
fn engine_edit(workspace: &mut Workspace, name: &str, text: &str) -> Duration {
    let started = Instant::now();
    workspace.engine.open(name, text);
    workspace.changed(name);
    workspace.check_all();
    let published = workspace.publications();
    let took = started.elapsed();
    assert!(published.iter().any(|(file, _)| file == name), "{name} published");
    took
}

struct Row {
    n: usize,
    engine: Duration,
    engine_shared: Duration,
    protocol: Duration,
    full: Duration,
    opened: Duration,
    kib_per_doc: f64,
}

fn measure(n: usize, rounds: usize) -> Row {
    // Memory and the engine alone.
    let before = rss_kib();
    let mut workspace = Workspace::new(Engine::in_memory());
    for (name, text) in documents(n) {
        workspace.engine.open(&name, &text);
        workspace.changed(&name);
    }
    workspace.check_all();
    workspace.publications();
    let after = rss_kib();
    let kib_per_doc = after.saturating_sub(before) as f64 / (n + 2) as f64;

    // A document nothing imports (with one document, the only one).
    let index = if n == 1 { 0 } else { n / 2 + 1 };
    let target = doc_name(index);
    let mut engine = Vec::new();
    let mut engine_shared = Vec::new();
    for round in 0..rounds {
        let timeout = if round % 2 == 0 { "5 mm" } else { "5 s" };
        engine.push(engine_edit(&mut workspace, &target, &doc_text(index, timeout)));
        let timeout = if round % 2 == 0 { "6 s" } else { "5 s" };
        engine_shared.push(engine_edit(&mut workspace, SHARED, &shared_text(timeout)));
    }
    let started = Instant::now();
    for name in workspace.engine.open_names() {
        std::hint::black_box(workspace.engine.diagnostics(&name));
    }
    let full = started.elapsed();
    drop(workspace);

    // The protocol, on an in-memory connection.
    let (server, client) = Connection::memory();
    let thread = std::thread::spawn(move || skill_language_server::serve(server));
    let send = |message: Message| client.sender.send(message).expect("send");
    let notify = |method: &str, params: serde_json::Value| send(Notification::new(method.to_string(), params).into());
    send(
        Request::new(
            RequestId::from(1),
            "initialize".to_string(),
            serde_json::json!({ "capabilities": {} }),
        )
        .into(),
    );
    notify("initialized", serde_json::json!({}));
    let uri = |name: &str| format!("file://{name}");
    let all = documents(n);
    let opening = Instant::now();
    for (name, text) in &all {
        notify(
            "textDocument/didOpen",
            serde_json::json!({ "textDocument": { "uri": uri(name), "languageId": "skill", "version": 1, "text": text } }),
        );
    }
    // Every document published once: the opening is done.
    let mut seen = std::collections::HashSet::new();
    while seen.len() < all.len() {
        if let Message::Notification(n) = client
            .receiver
            .recv_timeout(Duration::from_secs(120))
            .expect("published")
        {
            if n.method == "textDocument/publishDiagnostics" {
                seen.insert(n.params["uri"].as_str().unwrap_or_default().to_string());
            }
        }
    }
    let opened = opening.elapsed();
    let target_uri = uri(&target);
    let mut protocol = Vec::new();
    for round in 0..rounds {
        let broken = round % 2 == 0;
        let timeout = if broken { "5 mm" } else { "5 s" };
        let started = Instant::now();
        notify(
            "textDocument/didChange",
            serde_json::json!({ "textDocument": { "uri": target_uri, "version": round + 2 }, "contentChanges": [{ "text": doc_text(index, timeout) }] }),
        );
        loop {
            let message = client
                .receiver
                .recv_timeout(Duration::from_secs(60))
                .expect("published");
            if let Message::Notification(n) = message {
                let count = n.params["diagnostics"].as_array().map_or(0, Vec::len);
                if n.params["uri"] == target_uri.as_str() && (count > 0) == broken {
                    break;
                }
            }
        }
        protocol.push(started.elapsed().saturating_sub(DEBOUNCE));
    }
    notify("exit", serde_json::Value::Null);
    let _ = thread.join();

    Row {
        n,
        engine: median(engine),
        engine_shared: median(engine_shared),
        protocol: median(protocol),
        full,
        opened,
        kib_per_doc,
    }
}

fn main() {
    let rounds = std::env::args()
        .skip(1)
        .find_map(|arg| arg.parse::<usize>().ok())
        .unwrap_or(30)
        .max(1);
    println!("open documents | engine: edit of a document (ms) | engine: edit of the shared skill (ms) | protocol: didChange to publish, minus the {} ms debounce (ms) | full re-check of every document (ms) | protocol: open every document until each is published (ms) | memory per document (KiB)", DEBOUNCE.as_millis());
    println!("---|---|---|---|---|---|---");
    for n in [1, 100, 2_000] {
        let row = measure(n, rounds);
        println!(
            "{} (+2) | {} | {} ({} checks) | {} | {} | {} | {:.1}",
            row.n,
            ms(row.engine),
            ms(row.engine_shared),
            1 + n.div_ceil(10),
            ms(row.protocol),
            ms(row.full),
            ms(row.opened),
            row.kib_per_doc
        );
    }
}
