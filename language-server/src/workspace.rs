//! Which open documents need checking again, and what to publish: the incremental part of
//! diagnostics, apart from the protocol loop so that tests can count what an edit costs.
//!
//! An edit of a file (opening, changing, closing or saving it) queues the file itself, first,
//! and the open documents whose last check read it ([`Engine::readers`]: by import, directly
//! or not), and no other. The queue is a set: a document queued twice is checked once, so a
//! burst of edits costs one check per document it touches. [`Workspace::check_next`] checks
//! one document, so the server can answer requests between checks.

use crate::engine::Engine;
use lsp_types::Diagnostic;
use std::collections::{BTreeSet, HashMap, HashSet, VecDeque};

/// The open documents, the queue of those to check and the diagnostics found and published.
#[derive(Debug, Default)]
pub struct Workspace {
    /// The documents.
    pub engine: Engine,
    /// Documents to check, in order; each at most once (`queued`).
    queue: VecDeque<String>,
    queued: HashSet<String>,
    /// The diagnostics each open document's last check found, by file.
    per_doc: HashMap<String, Vec<(String, Vec<Diagnostic>)>>,
    /// For each file, the documents whose last check reported on it (problems or none).
    reporters: HashMap<String, BTreeSet<String>>,
    /// What was last published for each file (files with problems only).
    published: HashMap<String, Vec<Diagnostic>>,
    /// Files whose diagnostics may have changed since they were last published.
    unpublished: BTreeSet<String>,
}

impl Workspace {
    /// A workspace over an engine.
    pub fn new(engine: Engine) -> Self {
        Workspace {
            engine,
            ..Workspace::default()
        }
    }

    /// Notes that `file` changed (opened, edited, closed or saved): queues it, ahead of the
    /// rest when it is open, and the open documents that read it.
    pub fn changed(&mut self, file: &str) {
        if self.engine.text(file).is_some() {
            if self.queued.contains(file) {
                self.queue.retain(|queued| queued != file);
            } else {
                self.queued.insert(file.to_string());
            }
            self.queue.push_front(file.to_string());
        } else {
            self.forget(file);
        }
        for reader in self.engine.readers(file) {
            if self.queued.insert(reader.clone()) {
                self.queue.push_back(reader);
            }
        }
    }

    /// Whether any document waits to be checked.
    pub fn has_work(&self) -> bool {
        !self.queue.is_empty()
    }

    /// How many documents wait to be checked.
    pub fn queued(&self) -> usize {
        self.queue.len()
    }

    /// Checks the next queued document; false when none was queued. A check that panics
    /// counts as one without diagnostics.
    pub fn check_next(&mut self) -> bool {
        let Some(name) = self.queue.pop_front() else {
            return false;
        };
        self.queued.remove(&name);
        if self.engine.text(&name).is_none() {
            self.forget(&name);
            return true;
        }
        let engine = &mut self.engine;
        let found = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| engine.check(&name)));
        self.record(&name, found.unwrap_or_default());
        true
    }

    /// Checks every queued document.
    pub fn check_all(&mut self) {
        while self.check_next() {}
    }

    /// Drops what a document that is no longer open reported.
    fn forget(&mut self, name: &str) {
        self.record(name, Vec::new());
        self.per_doc.remove(name);
    }

    fn record(&mut self, name: &str, found: Vec<(String, Vec<Diagnostic>)>) {
        if let Some(before) = self.per_doc.get(name) {
            for (file, _) in before {
                if let Some(set) = self.reporters.get_mut(file) {
                    set.remove(name);
                    if set.is_empty() {
                        self.reporters.remove(file);
                    }
                }
                self.unpublished.insert(file.clone());
            }
        }
        for (file, _) in &found {
            self.reporters.entry(file.clone()).or_default().insert(name.to_string());
            self.unpublished.insert(file.clone());
        }
        self.per_doc.insert(name.to_string(), found);
    }

    /// What to publish: for each file whose diagnostics changed since they were last
    /// published, the union of what the open documents' checks report in it (a file with
    /// problems no check reports any more gets an empty list).
    pub fn publications(&mut self) -> Vec<(String, Vec<Diagnostic>)> {
        let files = std::mem::take(&mut self.unpublished);
        let mut out = Vec::new();
        for file in files {
            let mut all: Vec<Diagnostic> = Vec::new();
            for doc in self.reporters.get(&file).into_iter().flatten() {
                let Some(found) = self.per_doc.get(doc) else { continue };
                for (_, diags) in found.iter().filter(|(f, _)| *f == file) {
                    for diag in diags {
                        if !all.contains(diag) {
                            all.push(diag.clone());
                        }
                    }
                }
            }
            let reported = self.reporters.contains_key(&file);
            match self.published.get(&file) {
                Some(before) if *before == all => continue,
                // Nothing was published and there is nothing: publish the empty list only for
                // a file a check reported on (it was checked), not for one that disappeared.
                None if all.is_empty() && !reported => continue,
                _ => {}
            }
            if all.is_empty() {
                self.published.remove(&file);
            } else {
                self.published.insert(file.clone(), all.clone());
            }
            out.push((file, all));
        }
        out
    }
}
