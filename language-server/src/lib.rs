//! `skillc lsp`: a language server over stdio. The protocol loop lives here; what it answers
//! comes from the [`engine`] (diagnostics through the same compilation `skillc check` makes,
//! hover, definition, references, completion, formatting, rename, document symbols).
//!
//! One thread answers every message in order. Diagnostics are published when a document
//! opens and, debounced, [`DEBOUNCE`] after the last change; every open document is compiled
//! again then, so a document that imports a changed one is up to date too. A request that
//! panics is answered with an internal error and the server goes on.

pub mod complete;
pub mod engine;
pub mod hover;
pub mod index;
pub mod text;

use engine::Engine;
use lsp_server::{Connection, ErrorCode, Message, Notification, Request, RequestId, Response};
use lsp_types::notification::{self as notif, Notification as _};
use lsp_types::request::{self as req, Request as _};
use lsp_types::{
    CompletionOptions, Diagnostic, InitializeResult, OneOf, PositionEncodingKind, PublishDiagnosticsParams,
    RenameOptions, ServerCapabilities, ServerInfo, TextDocumentSyncCapability, TextDocumentSyncKind,
    TextDocumentSyncOptions,
};
use serde::de::DeserializeOwned;
use std::collections::{BTreeMap, HashMap};
use std::panic::AssertUnwindSafe;
use std::str::FromStr;
use std::time::{Duration, Instant};
use text::{uri_to_name, Encoding};

/// How long after the last change diagnostics are published.
pub const DEBOUNCE: Duration = Duration::from_millis(150);

/// Runs the server on standard input and output; the exit code (0 after `shutdown` and
/// `exit`, 1 when the client went away without them).
pub fn run_stdio() -> u8 {
    let (connection, io_threads) = Connection::stdio();
    let code = serve(connection);
    match io_threads.join() {
        Ok(()) => code,
        Err(err) => {
            eprintln!("skillc lsp: {err}");
            code.max(1)
        }
    }
}

/// Serves one client on a connection until it exits; the exit code.
pub fn serve(connection: Connection) -> u8 {
    let (id, params) = match connection.initialize_start() {
        Ok(start) => start,
        Err(err) => {
            eprintln!("skillc lsp: {err}");
            return 1;
        }
    };
    let mut engine = Engine::new();
    engine.encoding = negotiate(&params);
    let encoding = match engine.encoding {
        Encoding::Utf8 => PositionEncodingKind::UTF8,
        Encoding::Utf16 => PositionEncodingKind::UTF16,
    };
    let result = InitializeResult {
        capabilities: capabilities(encoding),
        server_info: Some(ServerInfo {
            name: "skillc".to_string(),
            version: Some(env!("CARGO_PKG_VERSION").to_string()),
        }),
    };
    let result = serde_json::to_value(result).unwrap_or_default();
    // Not `initialize_finish`: it insists that the next message be `initialized` and blocks
    // until one comes; the loop below takes `initialized` as any other notification.
    if connection.sender.send(Response::new_ok(id, result).into()).is_err() {
        return 1;
    }
    let mut server = Server {
        connection: &connection,
        engine,
        pending: None,
        per_doc: BTreeMap::new(),
        published: HashMap::new(),
        shut_down: false,
    };
    server.run()
}

/// UTF-8 when the client offers it (`general.positionEncodings`), else UTF-16.
fn negotiate(params: &serde_json::Value) -> Encoding {
    let offered = params
        .pointer("/capabilities/general/positionEncodings")
        .and_then(|v| v.as_array())
        .is_some_and(|list| list.iter().any(|e| e.as_str() == Some("utf-8")));
    if offered {
        Encoding::Utf8
    } else {
        Encoding::Utf16
    }
}

fn capabilities(encoding: PositionEncodingKind) -> ServerCapabilities {
    ServerCapabilities {
        position_encoding: Some(encoding),
        text_document_sync: Some(TextDocumentSyncCapability::Options(TextDocumentSyncOptions {
            open_close: Some(true),
            change: Some(TextDocumentSyncKind::FULL),
            ..TextDocumentSyncOptions::default()
        })),
        hover_provider: Some(lsp_types::HoverProviderCapability::Simple(true)),
        definition_provider: Some(OneOf::Left(true)),
        references_provider: Some(OneOf::Left(true)),
        document_formatting_provider: Some(OneOf::Left(true)),
        document_symbol_provider: Some(OneOf::Left(true)),
        rename_provider: Some(OneOf::Right(RenameOptions {
            prepare_provider: Some(true),
            work_done_progress_options: Default::default(),
        })),
        completion_provider: Some(CompletionOptions {
            trigger_characters: Some([" ", ">", "(", ":"].iter().map(|c| c.to_string()).collect()),
            ..CompletionOptions::default()
        }),
        ..ServerCapabilities::default()
    }
}

struct Server<'a> {
    connection: &'a Connection,
    engine: Engine,
    /// When the debounced diagnostics are due.
    pending: Option<Instant>,
    /// The diagnostics each open document's compilation found, by file.
    per_doc: BTreeMap<String, Vec<(String, Vec<Diagnostic>)>>,
    /// What was last published for each file.
    published: HashMap<String, Vec<Diagnostic>>,
    shut_down: bool,
}

/// A request's failure: its error code and message.
type Failure = (ErrorCode, String);

impl Server<'_> {
    fn run(&mut self) -> u8 {
        loop {
            let wait = match self.pending {
                Some(due) => due.saturating_duration_since(Instant::now()),
                None => Duration::from_secs(3600),
            };
            match self.connection.receiver.recv_timeout(wait) {
                Ok(Message::Request(request)) => self.request(request),
                Ok(Message::Notification(notification)) => {
                    if notification.method == notif::Exit::METHOD {
                        return u8::from(!self.shut_down);
                    }
                    self.notification(notification);
                }
                Ok(Message::Response(_)) => {}
                Err(err) if err.is_timeout() => {
                    self.pending = None;
                    self.publish_all();
                }
                Err(_) => return 1,
            }
        }
    }

    fn send(&self, message: Message) {
        // A client that went away is noticed by the receiver.
        let _ = self.connection.sender.send(message);
    }

    fn request(&mut self, request: Request) {
        let id = request.id.clone();
        if self.shut_down {
            return self.reply(
                id,
                Err((ErrorCode::InvalidRequest, "the server is shut down".to_string())),
            );
        }
        if request.method == req::Shutdown::METHOD {
            self.shut_down = true;
            return self.reply(id, Ok(serde_json::Value::Null));
        }
        let engine = &self.engine;
        let answer = std::panic::catch_unwind(AssertUnwindSafe(|| answer(engine, request)));
        let answer = answer.unwrap_or_else(|_| {
            Err((
                ErrorCode::InternalError,
                "the server failed on this request".to_string(),
            ))
        });
        self.reply(id, answer);
    }

    fn reply(&self, id: RequestId, answer: Result<serde_json::Value, Failure>) {
        let response = match answer {
            Ok(value) => Response::new_ok(id, value),
            Err((code, message)) => Response::new_err(id, code as i32, message),
        };
        self.send(response.into());
    }

    fn notification(&mut self, notification: Notification) {
        match notification.method.as_str() {
            notif::DidOpenTextDocument::METHOD => {
                let Ok(params) = parse::<lsp_types::DidOpenTextDocumentParams>(notification.params) else {
                    return;
                };
                let name = uri_to_name(params.text_document.uri.as_str());
                self.engine.open(&name, &params.text_document.text);
                self.publish_all();
            }
            notif::DidChangeTextDocument::METHOD => {
                let Ok(params) = parse::<lsp_types::DidChangeTextDocumentParams>(notification.params) else {
                    return;
                };
                let name = uri_to_name(params.text_document.uri.as_str());
                let mut text = self.engine.text(&name).unwrap_or_default().to_string();
                for change in params.content_changes {
                    match change.range {
                        Some(range) => {
                            let lines = text::LineIndex::new(&text, self.engine.encoding);
                            let start = lines.offset(&text, range.start);
                            let end = lines.offset(&text, range.end).max(start);
                            text.replace_range(start..end, &change.text);
                        }
                        None => text = change.text,
                    }
                }
                self.engine.open(&name, &text);
                self.pending = Some(Instant::now() + DEBOUNCE);
            }
            notif::DidCloseTextDocument::METHOD => {
                let Ok(params) = parse::<lsp_types::DidCloseTextDocumentParams>(notification.params) else {
                    return;
                };
                let name = uri_to_name(params.text_document.uri.as_str());
                self.engine.close(&name);
                self.per_doc.remove(&name);
                self.publish_all();
            }
            notif::DidSaveTextDocument::METHOD => self.publish_all(),
            _ => {}
        }
    }

    /// Compiles every open document and publishes what changed, clearing files whose problems
    /// are gone.
    fn publish_all(&mut self) {
        for name in self.engine.open_names() {
            let engine = &self.engine;
            let found = std::panic::catch_unwind(AssertUnwindSafe(|| engine.diagnostics(&name)));
            self.per_doc.insert(name, found.unwrap_or_default());
        }
        let mut now: HashMap<String, Vec<Diagnostic>> = HashMap::new();
        for files in self.per_doc.values() {
            for (file, diags) in files {
                let all = now.entry(file.clone()).or_default();
                for diag in diags {
                    if !all.contains(diag) {
                        all.push(diag.clone());
                    }
                }
            }
        }
        let mut files: Vec<String> = now.keys().chain(self.published.keys()).cloned().collect();
        files.sort();
        files.dedup();
        for file in files {
            let diags = now.remove(&file).unwrap_or_default();
            if self.published.get(&file) == Some(&diags) {
                continue;
            }
            let Ok(uri) = lsp_types::Uri::from_str(&text::name_to_uri(&file)) else {
                continue;
            };
            let params = PublishDiagnosticsParams {
                uri,
                diagnostics: diags.clone(),
                version: None,
            };
            self.send(Notification::new(notif::PublishDiagnostics::METHOD.to_string(), params).into());
            if diags.is_empty() {
                self.published.remove(&file);
            } else {
                self.published.insert(file, diags);
            }
        }
    }
}

fn parse<P: DeserializeOwned>(params: serde_json::Value) -> Result<P, Failure> {
    serde_json::from_value(params).map_err(|err| (ErrorCode::InvalidParams, format!("invalid parameters: {err}")))
}

fn to_value<T: serde::Serialize>(value: T) -> Result<serde_json::Value, Failure> {
    serde_json::to_value(value).map_err(|err| (ErrorCode::InternalError, err.to_string()))
}

/// The answer to one request.
fn answer(engine: &Engine, request: Request) -> Result<serde_json::Value, Failure> {
    let name_of = |doc: &lsp_types::TextDocumentIdentifier| uri_to_name(doc.uri.as_str());
    match request.method.as_str() {
        req::HoverRequest::METHOD => {
            let params: lsp_types::HoverParams = parse(request.params)?;
            let at = params.text_document_position_params;
            to_value(engine.hover(&name_of(&at.text_document), at.position))
        }
        req::GotoDefinition::METHOD => {
            let params: lsp_types::GotoDefinitionParams = parse(request.params)?;
            let at = params.text_document_position_params;
            to_value(engine.definition(&name_of(&at.text_document), at.position))
        }
        req::References::METHOD => {
            let params: lsp_types::ReferenceParams = parse(request.params)?;
            let at = params.text_document_position;
            let found = engine.references(
                &name_of(&at.text_document),
                at.position,
                params.context.include_declaration,
            );
            to_value(found)
        }
        req::Completion::METHOD => {
            let params: lsp_types::CompletionParams = parse(request.params)?;
            let at = params.text_document_position;
            to_value(engine.completion(&name_of(&at.text_document), at.position))
        }
        req::Formatting::METHOD => {
            let params: lsp_types::DocumentFormattingParams = parse(request.params)?;
            to_value(engine.format(&name_of(&params.text_document)))
        }
        req::PrepareRenameRequest::METHOD => {
            let params: lsp_types::TextDocumentPositionParams = parse(request.params)?;
            let range = engine.prepare_rename(&name_of(&params.text_document), params.position);
            to_value(range.map(lsp_types::PrepareRenameResponse::Range))
        }
        req::Rename::METHOD => {
            let params: lsp_types::RenameParams = parse(request.params)?;
            let at = params.text_document_position;
            match engine.rename(&name_of(&at.text_document), at.position, &params.new_name) {
                Ok(edit) => to_value(edit),
                Err(message) => Err((ErrorCode::RequestFailed, message)),
            }
        }
        req::DocumentSymbolRequest::METHOD => {
            let params: lsp_types::DocumentSymbolParams = parse(request.params)?;
            to_value(lsp_types::DocumentSymbolResponse::Nested(
                engine.symbols(&name_of(&params.text_document)),
            ))
        }
        other => Err((ErrorCode::MethodNotFound, format!("unknown method `{other}`"))),
    }
}
