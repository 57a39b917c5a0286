//! The language server's engine, without the protocol: the open documents, and for each
//! request the compilation of a document (the one `skillc check` makes), its symbol index and
//! the answer in the protocol's types. Pure but for reading imports that are not open from
//! disk, which [`Engine::in_memory`] switches off for tests.
//!
//! Imports are read from disk by [`read_import`] only: regular files of at most
//! [`MAX_IMPORT_BYTES`], so that an import of a device (`/dev/zero`), a FIFO or the server's
//! own standard input (`/dev/stdin`) is a diagnostic at the import, not a hang or an
//! allocation without end. [`Engine::check`] records the files each open document's
//! compilation read, so that an edit re-checks only the documents that read the edited file
//! ([`Engine::readers`]).

use super::complete;
use super::index::{Index, Kind, What};
use super::text::{name_to_uri, Encoding, LineIndex};
use lsp_types::{
    DiagnosticRelatedInformation, DiagnosticSeverity, DocumentSymbol, Hover, HoverContents, Location, MarkupContent,
    MarkupKind, NumberOrString, Position, Range, SymbolKind, TextEdit, Uri, WorkspaceEdit,
};
use skill_compiler::{ast, Compilation, LoadError, Severity, SourceFile};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::io::Read;
use std::str::FromStr;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The largest imported file read from disk: 8 MiB, as `skillc check` (the kit's
/// `MAX_SOURCE_BYTES`). A larger one is a diagnostic at the import.
pub const MAX_IMPORT_BYTES: u64 = 8 << 20;

/// Reads an imported file from disk, as the server does and with the words `skillc check`
/// uses (the kit's `frontend::read_source`): only a regular file (after following links),
/// checked before it is opened (opening a FIFO for reading blocks until a writer comes), and
/// at most [`MAX_IMPORT_BYTES`]. The error says what the path is instead (a folder, a device,
/// a FIFO, a socket) or that it is too large.
pub fn read_import(path: &str) -> Result<String, LoadError> {
    let fail = |reason: String| LoadError { reason };
    let io = |err: std::io::Error| fail(err.to_string().to_lowercase());
    let not_a_file = |metadata: &std::fs::Metadata| {
        fail(format!(
            "{} is not a regular file; only files are read",
            file_kind(metadata)
        ))
    };
    let metadata = std::fs::metadata(path).map_err(io)?;
    if !metadata.is_file() {
        return Err(not_a_file(&metadata));
    }
    let file = std::fs::File::open(path).map_err(io)?;
    // The path may have been replaced between the two looks; the open file is what is read.
    let opened = file.metadata().map_err(io)?;
    if !opened.is_file() {
        return Err(not_a_file(&opened));
    }
    let mut bytes = Vec::new();
    file.take(MAX_IMPORT_BYTES + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > MAX_IMPORT_BYTES {
        return Err(fail(format!(
            "it is larger than {} MiB, the most a .skill file may hold",
            MAX_IMPORT_BYTES >> 20
        )));
    }
    String::from_utf8(bytes).map_err(|_| fail("not valid UTF-8 text".to_string()))
}

/// What a file that is not a regular one is, in words (as the kit's `kind_of`).
fn file_kind(metadata: &std::fs::Metadata) -> &'static str {
    let kind = metadata.file_type();
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return "a FIFO";
        }
        if kind.is_socket() {
            return "a socket";
        }
        if kind.is_char_device() || kind.is_block_device() {
            return "a device";
        }
    }
    if kind.is_dir() {
        "a folder"
    } else {
        "it"
    }
}

/// The open documents and how to answer questions about them.
#[derive(Debug)]
pub struct Engine {
    /// Open documents by file name (a path for `file:` URIs), with their text.
    docs: BTreeMap<String, String>,
    /// Whether imports that are not open are read from disk.
    read_disk: bool,
    /// How positions count characters.
    pub encoding: Encoding,
    /// For each open document [`Engine::check`]ed, every path its compilation asked for
    /// (read or not): the files whose change may change its diagnostics.
    reads: HashMap<String, BTreeSet<String>>,
    /// How many compilations this engine made.
    compiled: AtomicUsize,
}

/// A compiled document: the compilation, the syntax tree of every file and the index.
#[derive(Debug)]
pub struct Analysis {
    /// What `skillc check` computes for the document.
    pub compilation: Compilation,
    /// The syntax tree of every file of the compilation (empty for one that did not parse).
    pub asts: Vec<ast::File>,
    /// Declarations and uses.
    pub index: Index,
    lines: Vec<LineIndex>,
}

impl Analysis {
    /// The protocol range of a span in file `file`.
    pub fn range(&self, file: usize, span: skill_compiler::Span) -> Range {
        self.lines[file].range(&self.compilation.files[file].text, span)
    }

    /// The byte offset of a position in file `file`.
    pub fn offset(&self, file: usize, position: Position) -> usize {
        self.lines[file].offset(&self.compilation.files[file].text, position)
    }

    /// The location of a span.
    pub fn location(&self, file: usize, span: skill_compiler::Span) -> Option<Location> {
        Some(Location::new(
            uri(&self.compilation.files[file].name)?,
            self.range(file, span),
        ))
    }
}

/// The URI of a file name.
pub fn uri(name: &str) -> Option<Uri> {
    Uri::from_str(&name_to_uri(name)).ok()
}

/// Words a declared name cannot be renamed to: the grammar's keywords.
pub use skill_compiler::syntax::KEYWORDS;

impl Default for Engine {
    fn default() -> Self {
        Engine::new()
    }
}

impl Engine {
    /// An engine that reads imports from disk when they are not open.
    pub fn new() -> Self {
        Engine {
            docs: BTreeMap::new(),
            read_disk: true,
            encoding: Encoding::Utf16,
            reads: HashMap::new(),
            compiled: AtomicUsize::new(0),
        }
    }

    /// An engine that sees only the documents opened in it.
    pub fn in_memory() -> Self {
        Engine {
            read_disk: false,
            ..Engine::new()
        }
    }

    /// Opens (or replaces) a document.
    pub fn open(&mut self, name: &str, text: &str) {
        self.docs.insert(name.to_string(), text.to_string());
    }

    /// Closes a document.
    pub fn close(&mut self, name: &str) {
        self.docs.remove(name);
        self.reads.remove(name);
    }

    /// How many compilations (of a document and its imports) this engine has made: for tests
    /// and benchmarks of what an edit costs.
    pub fn compilations(&self) -> usize {
        self.compiled.load(Ordering::Relaxed)
    }

    /// The open documents whose last [`Engine::check`] read (or tried to read) `file`, by
    /// import, directly or not: those an edit of `file` may change.
    pub fn readers(&self, file: &str) -> Vec<String> {
        let mut found: Vec<String> = self
            .reads
            .iter()
            .filter(|(doc, reads)| reads.contains(file) && self.docs.contains_key(*doc))
            .map(|(doc, _)| doc.clone())
            .collect();
        found.sort();
        found
    }

    /// [`Engine::diagnostics`], remembering which files the compilation read for
    /// [`Engine::readers`].
    pub fn check(&mut self, name: &str) -> Vec<(String, Vec<lsp_types::Diagnostic>)> {
        let Some((analysis, read)) = self.analyse_reading(name) else {
            self.reads.remove(name);
            return Vec::new();
        };
        let found = diagnostics_of(&analysis);
        self.reads.insert(name.to_string(), read);
        found
    }

    /// The names of the open documents.
    pub fn open_names(&self) -> Vec<String> {
        self.docs.keys().cloned().collect()
    }

    /// The text of an open document.
    pub fn text(&self, name: &str) -> Option<&str> {
        self.docs.get(name).map(String::as_str)
    }

    /// Compiles an open document, reading its imports from the open documents or disk.
    pub fn analyse(&self, name: &str) -> Option<Analysis> {
        self.analyse_reading(name).map(|(analysis, _)| analysis)
    }

    /// [`Engine::analyse`], with every path the compilation asked for.
    fn analyse_reading(&self, name: &str) -> Option<(Analysis, BTreeSet<String>)> {
        let text = self.docs.get(name)?;
        self.compiled.fetch_add(1, Ordering::Relaxed);
        let mut read = BTreeSet::new();
        let mut load = |path: &str| -> Result<String, LoadError> {
            read.insert(path.to_string());
            if let Some(open) = self.docs.get(path) {
                return Ok(open.clone());
            }
            if !self.read_disk {
                return Err(LoadError {
                    reason: "no such file".to_string(),
                });
            }
            // As `skillc check` reads them (kit/src/frontend.rs), so that messages are the
            // same, but only regular files of bounded size.
            read_import(path)
        };
        let compilation = skill_compiler::compile_bytes(name, text.as_bytes().to_vec(), &[], &mut load);
        let mut asts = Vec::with_capacity(compilation.files.len());
        for (file, source) in compilation.files.iter().enumerate() {
            if file == 0 {
                asts.push(compilation.ast.clone());
            } else if skill_compiler::is_param_file(&source.name) {
                asts.push(ast::File::default());
            } else {
                asts.push(skill_compiler::syntax::parse(source, file).0);
            }
        }
        let index = Index::build(&compilation.files, &asts);
        let lines = compilation
            .files
            .iter()
            .map(|f| LineIndex::new(&f.text, self.encoding))
            .collect();
        let analysis = Analysis {
            compilation,
            asts,
            index,
            lines,
        };
        Some((analysis, read))
    }

    /// The diagnostics of a document's compilation, by the file they are in (the document
    /// first, then imports with problems): what `skillc check` prints for it.
    pub fn diagnostics(&self, name: &str) -> Vec<(String, Vec<lsp_types::Diagnostic>)> {
        self.analyse(name).map(|a| diagnostics_of(&a)).unwrap_or_default()
    }

    /// What the name at a position is.
    pub fn hover(&self, name: &str, position: Position) -> Option<Hover> {
        let analysis = self.analyse(name)?;
        let offset = analysis.offset(0, position);
        let occurrence = analysis.index.at(0, offset)?;
        let text = super::hover::describe(&analysis, occurrence)?;
        Some(Hover {
            contents: HoverContents::Markup(MarkupContent {
                kind: MarkupKind::Markdown,
                value: text,
            }),
            range: Some(analysis.range(0, occurrence.span)),
        })
    }

    /// Where the name at a position is declared.
    pub fn definition(&self, name: &str, position: Position) -> Option<Location> {
        let analysis = self.analyse(name)?;
        let offset = analysis.offset(0, position);
        match &analysis.index.at(0, offset)?.what {
            What::Def(id) => {
                let def = &analysis.index.defs[*id];
                analysis.location(def.file, def.span)
            }
            What::Import(Some(file)) => analysis.location(*file, skill_compiler::Span::new(0, 0)),
            _ => None,
        }
    }

    /// Every use of the name at a position, with its declaration when `declaration` is set.
    pub fn references(&self, name: &str, position: Position, declaration: bool) -> Vec<Location> {
        let Some(analysis) = self.analyse(name) else {
            return Vec::new();
        };
        let offset = analysis.offset(0, position);
        let Some(What::Def(id)) = analysis.index.at(0, offset).map(|o| o.what.clone()) else {
            return Vec::new();
        };
        let def = &analysis.index.defs[id];
        let declared_at = (analysis.compilation.files[def.file].name.clone(), def.span);
        self.uses_everywhere(&analysis, id)
            .into_iter()
            .filter(|(file, span)| declaration || (file, span) != (&declared_at.0, &declared_at.1))
            .filter_map(|(file, span)| self.location_in(&analysis, &file, span))
            .collect()
    }

    /// Every use of declaration `id` of `analysis`, in its compilation and in every other open
    /// document whose compilation reads the file it is declared in (a task that imports the
    /// skill being edited; by what its last [`Engine::check`] read, or all not yet checked):
    /// (file name, span) pairs, the declaration among them.
    fn uses_everywhere(&self, analysis: &Analysis, id: usize) -> Vec<(String, skill_compiler::Span)> {
        let def = &analysis.index.defs[id];
        let def_file = analysis.compilation.files[def.file].name.clone();
        let mut found: Vec<(String, skill_compiler::Span)> = analysis
            .index
            .uses(id)
            .into_iter()
            .map(|o| (analysis.compilation.files[o.file].name.clone(), o.span))
            .collect();
        let root = &analysis.compilation.files[0].name;
        // Only documents whose last check read the declaring file (or never checked) can use
        // the declaration: the others are not compiled.
        let may_use =
            |name: &String| *name == def_file || self.reads.get(name).is_none_or(|read| read.contains(&def_file));
        for other in self.docs.keys().filter(|name| *name != root && may_use(name)) {
            let Some(elsewhere) = self.analyse(other) else { continue };
            let same = elsewhere.index.defs.iter().position(|d| {
                d.span == def.span && d.kind == def.kind && elsewhere.compilation.files[d.file].name == def_file
            });
            if let Some(same) = same {
                for o in elsewhere.index.uses(same) {
                    found.push((elsewhere.compilation.files[o.file].name.clone(), o.span));
                }
            }
        }
        found.sort_by(|a, b| (&a.0, a.1.start).cmp(&(&b.0, b.1.start)));
        found.dedup();
        found
    }

    /// The location of a span in a file named `file`, which `analysis` may not hold (a file of
    /// another document's compilation): its text is the open document's or the disk's.
    fn location_in(&self, analysis: &Analysis, file: &str, span: skill_compiler::Span) -> Option<Location> {
        if let Some(index) = analysis.compilation.files.iter().position(|f| f.name == file) {
            return analysis.location(index, span);
        }
        let text = match self.docs.get(file) {
            Some(text) => text.clone(),
            None if self.read_disk => read_import(file).ok()?,
            None => return None,
        };
        let source = SourceFile::new(file, text);
        let lines = LineIndex::new(&source.text, self.encoding);
        Some(Location::new(uri(file)?, lines.range(&source.text, span)))
    }

    /// The range of the declared name at a position, if it can be renamed.
    pub fn prepare_rename(&self, name: &str, position: Position) -> Option<Range> {
        let analysis = self.analyse(name)?;
        let offset = analysis.offset(0, position);
        let occurrence = analysis.index.at(0, offset)?;
        matches!(occurrence.what, What::Def(_)).then(|| analysis.range(0, occurrence.span))
    }

    /// The edits that rename the declared name at a position, everywhere it is used.
    // lsp-types keys `WorkspaceEdit::changes` by `Uri`, which caches a parse in a `Cell`; the
    // keys here are built once and never changed.
    #[allow(clippy::mutable_key_type)]
    pub fn rename(&self, name: &str, position: Position, new_name: &str) -> Result<WorkspaceEdit, String> {
        let valid = new_name
            .chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && new_name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !valid {
            return Err(format!(
                "`{new_name}` is not a name: a letter or `_`, then letters, digits or `_`"
            ));
        }
        if KEYWORDS.contains(&new_name) {
            return Err(format!("`{new_name}` is a keyword"));
        }
        let analysis = self.analyse(name).ok_or("the document is not open")?;
        let offset = analysis.offset(0, position);
        let Some(What::Def(id)) = analysis.index.at(0, offset).map(|o| o.what.clone()) else {
            return Err("there is no declared name here".to_string());
        };
        let def = &analysis.index.defs[id];
        if def.name == new_name {
            return Ok(WorkspaceEdit::default());
        }
        if let Some(clash) = analysis.index.lookup(def.parent, new_name, &[def.kind]) {
            let clash = &analysis.index.defs[clash];
            let scope_of = |kind| {
                matches!(
                    kind,
                    Kind::Param | Kind::Capture | Kind::Frame | Kind::Motion | Kind::Force | Kind::Threshold
                )
            };
            let same_namespace = clash.kind == def.kind
                || (scope_of(clash.kind) && scope_of(def.kind))
                || matches!(
                    (clash.kind, def.kind),
                    (Kind::State | Kind::Terminal, Kind::State | Kind::Terminal)
                );
            if same_namespace {
                return Err(format!(
                    "`{new_name}` is already declared here ({} `{new_name}`)",
                    clash.kind.word()
                ));
            }
        }
        let mut changes: HashMap<Uri, Vec<TextEdit>> = HashMap::new();
        for (file, span) in self.uses_everywhere(&analysis, id) {
            let Some(location) = self.location_in(&analysis, &file, span) else {
                continue;
            };
            changes
                .entry(location.uri)
                .or_default()
                .push(TextEdit::new(location.range, new_name.to_string()));
        }
        Ok(WorkspaceEdit::new(changes))
    }

    /// `skillc fmt`'s result as one edit of the whole document; no edit when it is formatted,
    /// `None` when it does not parse (as `skillc fmt` leaves such a file alone).
    pub fn format(&self, name: &str) -> Option<Vec<TextEdit>> {
        let text = self.docs.get(name)?;
        let source = SourceFile::new(name, text.as_str());
        let (ast, diags) = skill_compiler::syntax::parse(&source, 0);
        if !diags.is_empty() {
            return None;
        }
        let formatted = skill_compiler::fmt::format(&source, &ast);
        if formatted == *source.text {
            return Some(Vec::new());
        }
        let lines = LineIndex::new(text, self.encoding);
        let end = lines.position(text, text.len());
        Some(vec![TextEdit::new(Range::new(Position::new(0, 0), end), formatted)])
    }

    /// The skills, tasks and their parts a document declares.
    pub fn symbols(&self, name: &str) -> Vec<DocumentSymbol> {
        let Some(analysis) = self.analyse(name) else {
            return Vec::new();
        };
        let index = &analysis.index;
        let symbol = |id: usize, children: Option<Vec<DocumentSymbol>>| {
            let def = &index.defs[id];
            let kind = match def.kind {
                Kind::Skill => SymbolKind::CLASS,
                Kind::Task => SymbolKind::MODULE,
                Kind::Step => SymbolKind::FUNCTION,
                Kind::Param => SymbolKind::CONSTANT,
                Kind::Frame => SymbolKind::STRUCT,
                Kind::Motion => SymbolKind::METHOD,
                Kind::Force | Kind::Threshold => SymbolKind::FIELD,
                Kind::State => SymbolKind::ENUM_MEMBER,
                Kind::Terminal => SymbolKind::EVENT,
                Kind::Capture => SymbolKind::VARIABLE,
            };
            #[allow(deprecated)] // `deprecated` is a required field of the struct.
            DocumentSymbol {
                name: def.name.clone(),
                detail: Some(def.detail.clone()),
                kind,
                tags: None,
                deprecated: None,
                range: analysis.range(def.file, def.full),
                selection_range: analysis.range(def.file, def.span),
                children,
            }
        };
        index
            .defs
            .iter()
            .enumerate()
            .filter(|(_, d)| d.file == 0 && d.parent.is_none())
            .map(|(id, _)| {
                let children = index
                    .defs
                    .iter()
                    .enumerate()
                    .filter(|(_, d)| d.parent == Some(id))
                    .map(|(child, _)| symbol(child, None))
                    .collect();
                symbol(id, Some(children))
            })
            .collect()
    }

    /// What may be written at a position.
    pub fn completion(&self, name: &str, position: Position) -> Vec<lsp_types::CompletionItem> {
        let Some(text) = self.docs.get(name) else {
            return Vec::new();
        };
        let lines = LineIndex::new(text, self.encoding);
        let offset = lines.offset(text, position);
        let mut analysis = self.analyse(name);
        let parse_failed = analysis.as_ref().is_some_and(|a| {
            a.compilation
                .diags
                .iter()
                .any(|d| d.file == 0 && d.code.as_str().starts_with("skill::syntax::"))
        });
        if parse_failed {
            // A line being typed rarely parses: the names come from the file without it.
            let start = text[..offset].rfind('\n').map_or(0, |at| at + 1);
            let end = text[offset..].find('\n').map_or(text.len(), |at| offset + at);
            let mut without = text.clone();
            without.replace_range(start..end, &" ".repeat(end - start));
            let mut scratch = Engine {
                docs: self.docs.clone(),
                read_disk: self.read_disk,
                encoding: self.encoding,
                ..Engine::new()
            };
            scratch.open(name, &without);
            analysis = scratch.analyse(name);
        }
        complete::complete(text, offset, analysis.as_ref())
    }
}

/// The diagnostics of a compilation by file: the document first, then imports with problems.
fn diagnostics_of(analysis: &Analysis) -> Vec<(String, Vec<lsp_types::Diagnostic>)> {
    let mut by_file: BTreeMap<usize, Vec<lsp_types::Diagnostic>> = BTreeMap::new();
    by_file.insert(0, Vec::new());
    for diag in &analysis.compilation.diags {
        by_file.entry(diag.file).or_default().push(to_lsp(diag, analysis));
    }
    by_file
        .into_iter()
        .map(|(file, diags)| (analysis.compilation.files[file].name.clone(), diags))
        .collect()
}

/// A compiler diagnostic in the protocol's terms: its primary label's range, severity, code
/// and message (with its help line), and the other labels as related information.
fn to_lsp(diag: &skill_compiler::Diag, analysis: &Analysis) -> lsp_types::Diagnostic {
    let file = diag.file;
    let mut message = diag.message.clone();
    if let Some(help) = &diag.help {
        message.push_str("\nhelp: ");
        message.push_str(help);
    }
    let related: Vec<DiagnosticRelatedInformation> = diag
        .labels
        .iter()
        .skip(1)
        .filter_map(|label| {
            Some(DiagnosticRelatedInformation {
                location: analysis.location(file, label.span)?,
                message: label.text.clone(),
            })
        })
        .collect();
    lsp_types::Diagnostic {
        range: analysis.range(file, diag.span()),
        severity: Some(match diag.severity() {
            Severity::Error => DiagnosticSeverity::ERROR,
            Severity::Warning => DiagnosticSeverity::WARNING,
        }),
        code: Some(NumberOrString::String(diag.code.as_str().to_string())),
        code_description: None,
        source: Some("skillc".to_string()),
        message,
        related_information: (!related.is_empty()).then_some(related),
        tags: None,
        data: None,
    }
}
