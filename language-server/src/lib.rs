//! `skillc lsp`: a language server over stdio. The protocol loop lives here; what it answers
//! comes from the [`engine`] (diagnostics through the same compilation `skillc check` makes,
//! hover, definition, references, completion, formatting, rename, document symbols).
//!
//! One thread answers every message in order. An edit (a document opened, changed, closed or
//! saved) queues for checking that document and the open documents that import it, directly
//! or not, and no other ([`workspace`]); a document queued twice is checked once. Checks run
//! one document at a time when no message waits, so requests are answered between them;
//! after a change they wait [`DEBOUNCE`] after the last one. A request that panics is
//! answered with an internal error and the server goes on.
//!
//! The input is bounded ([`stdio`]): a message larger than [`MAX_FRAME_BYTES`] (64 MiB) ends
//! the server with exit code 1 and a message on standard error, before anything of that size
//! is allocated, as does input that ends in the middle of a message or is not JSON-RPC.
//! Imports are read from disk only when they are regular files of at most
//! [`engine::MAX_IMPORT_BYTES`] (8 MiB); a device, a FIFO, `/dev/stdin` or a larger file is a
//! diagnostic at the import ([`engine::read_import`]).

pub mod complete;
pub mod engine;
pub mod hover;
pub mod index;
pub mod stdio;
pub mod text;
pub mod workspace;

use engine::Engine;
use lsp_server::{Connection, ErrorCode, Message, Notification, Request, RequestId, Response};
use lsp_types::notification::{self as notif, Notification as _};
use lsp_types::request::{self as req, Request as _};
use lsp_types::{
    CompletionOptions, InitializeResult, OneOf, PositionEncodingKind, PublishDiagnosticsParams, RenameOptions,
    ServerCapabilities, ServerInfo, TextDocumentSyncCapability, TextDocumentSyncKind, TextDocumentSyncOptions,
};
use serde::de::DeserializeOwned;
use std::panic::AssertUnwindSafe;
use std::str::FromStr;
use std::time::{Duration, Instant};
use text::{uri_to_name, Encoding};
use workspace::Workspace;

/// The transport crate, for clients of [`serve`] (tests, benches) that do not depend on it.
pub use lsp_server;
pub use stdio::MAX_FRAME_BYTES;

/// How long after the last change diagnostics are published.
pub const DEBOUNCE: Duration = Duration::from_millis(150);

/// While checks are queued, how often what they found is published.
const PUBLISH_EVERY: Duration = Duration::from_millis(25);

/// Runs the server on standard input and output; the exit code (0 after `shutdown` and
/// `exit`, 1 when the client went away without them or sent a message the server refuses:
/// over [`MAX_FRAME_BYTES`], cut off, or not JSON-RPC).
pub fn run_stdio() -> u8 {
    let input = std::io::BufReader::new(std::io::stdin());
    let (connection, transport) = stdio::connect(input, std::io::stdout());
    let code = serve(connection);
    let mut code = match transport.writer.join() {
        Ok(Ok(())) => code,
        Ok(Err(err)) => {
            eprintln!("skillc lsp: cannot write to the client: {err}");
            code.max(1)
        }
        Err(_) => code.max(1),
    };
    // The reader has stopped unless the server ended before the client did (it may still
    // wait for input, and is left to the process's exit).
    let until = Instant::now() + Duration::from_millis(200);
    while !transport.reader.is_finished() && Instant::now() < until {
        std::thread::sleep(Duration::from_millis(5));
    }
    if transport.reader.is_finished() {
        match transport.reader.join() {
            Ok(Ok(())) => {}
            Ok(Err(err)) => {
                eprintln!("skillc lsp: {err}");
                code = code.max(1);
            }
            Err(_) => code = code.max(1),
        }
    }
    code
}

/// Serves one client on a connection until it exits; the exit code.
pub fn serve(connection: Connection) -> u8 {
    let (id, params) = match connection.initialize_start() {
        Ok(start) => start,
        Err(err) => {
            // A client gone before `initialize` says nothing more (the transport says why).
            if !err.channel_is_disconnected() {
                eprintln!("skillc lsp: {err}");
            }
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
        workspace: Workspace::new(engine),
        pending: None,
        last_published: Instant::now(),
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
    /// The documents and the checks queued.
    workspace: Workspace,
    /// Until when queued checks wait after a change (the debounce).
    pending: Option<Instant>,
    /// When diagnostics were last published.
    last_published: Instant,
    shut_down: bool,
}

/// A request's failure: its error code and message.
type Failure = (ErrorCode, String);

impl Server<'_> {
    fn run(&mut self) -> u8 {
        loop {
            if self.pending.is_some_and(|due| due <= Instant::now()) {
                self.pending = None;
            }
            let message = if self.workspace.has_work() && self.pending.is_none() {
                // Checks are due: messages that wait come first, then one check.
                match self.connection.receiver.try_recv() {
                    Ok(message) => message,
                    Err(err) if err.is_empty() => {
                        self.check_one();
                        continue;
                    }
                    Err(_) => return 1,
                }
            } else {
                let wait = match self.pending {
                    Some(due) => due.saturating_duration_since(Instant::now()),
                    None => Duration::from_secs(3600),
                };
                match self.connection.receiver.recv_timeout(wait) {
                    Ok(message) => message,
                    Err(err) if err.is_timeout() => continue,
                    Err(_) => return 1,
                }
            };
            match message {
                Message::Request(request) => self.request(request),
                Message::Notification(notification) => {
                    if notification.method == notif::Exit::METHOD {
                        return u8::from(!self.shut_down);
                    }
                    self.notification(notification);
                }
                Message::Response(_) => {}
            }
        }
    }

    /// Checks the next queued document, and publishes what the checks found when the queue
    /// is empty, or after the first check of an edit, or every [`PUBLISH_EVERY`].
    fn check_one(&mut self) {
        let first = self.last_published.elapsed() >= PUBLISH_EVERY;
        self.workspace.check_next();
        if first || !self.workspace.has_work() {
            self.publish();
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
        let engine = &self.workspace.engine;
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
                self.workspace.engine.open(&name, &params.text_document.text);
                self.workspace.changed(&name);
            }
            notif::DidChangeTextDocument::METHOD => {
                let Ok(params) = parse::<lsp_types::DidChangeTextDocumentParams>(notification.params) else {
                    return;
                };
                let name = uri_to_name(params.text_document.uri.as_str());
                let mut text = self.workspace.engine.text(&name).unwrap_or_default().to_string();
                for change in params.content_changes {
                    match change.range {
                        Some(range) => {
                            let lines = text::LineIndex::new(&text, self.workspace.engine.encoding);
                            let start = lines.offset(&text, range.start);
                            let end = lines.offset(&text, range.end).max(start);
                            text.replace_range(start..end, &change.text);
                        }
                        None => text = change.text,
                    }
                }
                self.workspace.engine.open(&name, &text);
                self.workspace.changed(&name);
                self.pending = Some(Instant::now() + DEBOUNCE);
            }
            notif::DidCloseTextDocument::METHOD => {
                let Ok(params) = parse::<lsp_types::DidCloseTextDocumentParams>(notification.params) else {
                    return;
                };
                let name = uri_to_name(params.text_document.uri.as_str());
                self.workspace.engine.close(&name);
                self.workspace.changed(&name);
                self.publish();
            }
            notif::DidSaveTextDocument::METHOD => {
                // The file on disk changed: what reads it from disk (not open) is checked.
                let Ok(params) = parse::<lsp_types::DidSaveTextDocumentParams>(notification.params) else {
                    return;
                };
                let name = uri_to_name(params.text_document.uri.as_str());
                self.workspace.changed(&name);
            }
            _ => {}
        }
    }

    /// Publishes the diagnostics that changed since they were last published.
    fn publish(&mut self) {
        self.last_published = Instant::now();
        for (file, diagnostics) in self.workspace.publications() {
            let Ok(uri) = lsp_types::Uri::from_str(&text::name_to_uri(&file)) else {
                continue;
            };
            let params = PublishDiagnosticsParams {
                uri,
                diagnostics,
                version: None,
            };
            self.send(Notification::new(notif::PublishDiagnostics::METHOD.to_string(), params).into());
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
