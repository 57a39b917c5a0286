//! The editor files in `editors/vscode`: the extension's manifest launches `skillc lsp` for
//! `.skill` files, and the TextMate grammar's patterns compile and tokenise every shipped skill
//! with no character left unmatched, run by a small TextMate engine on the `regex` crate (the
//! grammar uses no look-around, so its patterns mean the same in Oniguruma and here).

use regex::Regex;
use serde_json::Value;
use std::path::Path;

const EDITOR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/editors/vscode");

fn json(path: &str) -> Value {
    let text = std::fs::read_to_string(Path::new(EDITOR).join(path)).expect("the file is there");
    serde_json::from_str(&text).unwrap_or_else(|err| panic!("{path} is JSON: {err}"))
}

/// A grammar rule: a `match`, or a `begin`/`end` pair with the rules inside it.
#[derive(Debug)]
enum Rule {
    Match {
        regex: Regex,
        scope: String,
    },
    Region {
        begin: Regex,
        end: Regex,
        scope: String,
        inside: Vec<Rule>,
    },
}

/// The rules of a `patterns` list, with `include`s from the repository resolved.
fn rules(patterns: &Value, repository: &Value, errors: &mut Vec<String>) -> Vec<Rule> {
    let mut out = Vec::new();
    for pattern in patterns.as_array().expect("patterns is a list") {
        if let Some(include) = pattern["include"].as_str() {
            let name = include.strip_prefix('#').expect("includes name the repository");
            let entry = &repository[name];
            assert!(!entry.is_null(), "`{include}` is in the repository");
            out.extend(rules(&entry["patterns"], repository, errors));
            continue;
        }
        let compile = |key: &str, errors: &mut Vec<String>| -> Option<Regex> {
            let source = pattern[key].as_str()?;
            match Regex::new(source) {
                Ok(regex) => Some(regex),
                Err(err) => {
                    errors.push(format!("`{source}`: {err}"));
                    None
                }
            }
        };
        // The rule's scope and its captures' scopes, space-separated.
        let mut scope = pattern["name"].as_str().unwrap_or("").to_string();
        if let Some(captures) = pattern["captures"].as_object() {
            for capture in captures.values() {
                scope.push(' ');
                scope.push_str(capture["name"].as_str().unwrap_or(""));
            }
        }
        if pattern.get("match").is_some() {
            if let Some(regex) = compile("match", errors) {
                out.push(Rule::Match { regex, scope });
            }
        } else if let (Some(begin), Some(end)) = (compile("begin", errors), compile("end", errors)) {
            let inside = match pattern.get("patterns") {
                Some(inner) => rules(inner, repository, errors),
                None => Vec::new(),
            };
            out.push(Rule::Region {
                begin,
                end,
                scope,
                inside,
            });
        } else {
            errors.push(format!("a rule with neither match nor begin/end: {pattern}"));
        }
    }
    out
}

fn grammar() -> Vec<Rule> {
    let grammar = json("syntaxes/skill.tmLanguage.json");
    assert_eq!(grammar["scopeName"], "source.skill");
    let mut errors = Vec::new();
    let rules = rules(&grammar["patterns"], &grammar["repository"], &mut errors);
    assert!(errors.is_empty(), "patterns that do not compile: {errors:#?}");
    rules
}

/// Tokenises one line as TextMate does (at each place the rule whose match starts first, the
/// earlier rule on a tie; a region runs to its end, on this or a later line); returns the
/// characters no rule matched and the scopes used. `stack` holds the open regions.
fn tokenise<'a>(
    line: &str,
    top: &'a [Rule],
    stack: &mut Vec<&'a Rule>,
    scopes: &mut Vec<String>,
) -> Vec<(usize, char)> {
    let mut unmatched = Vec::new();
    let mut at = 0;
    while at < line.len() {
        let (rules, end): (&[Rule], Option<&Regex>) = match stack.last() {
            Some(Rule::Region { inside, end, .. }) => (inside.as_slice(), Some(end)),
            _ => (top, None),
        };
        // The earliest match of the region's end or of any rule.
        let mut best: Option<(usize, usize, Option<&Rule>)> = end
            .and_then(|end| end.find_at(line, at))
            .map(|m| (m.start(), m.end(), None));
        for rule in rules {
            let found = match rule {
                Rule::Match { regex, .. } => regex.find_at(line, at),
                Rule::Region { begin, .. } => begin.find_at(line, at),
            };
            if let Some(m) = found {
                if best.is_none_or(|(start, _, _)| m.start() < start) {
                    best = Some((m.start(), m.end(), Some(rule)));
                }
            }
        }
        let Some((start, stop, rule)) = best else {
            unmatched.extend(
                line[at..]
                    .char_indices()
                    .map(|(i, c)| (at + i, c))
                    .filter(|(_, c)| !c.is_whitespace()),
            );
            break;
        };
        if stack.is_empty() {
            unmatched.extend(
                line[at..start]
                    .char_indices()
                    .map(|(i, c)| (at + i, c))
                    .filter(|(_, c)| !c.is_whitespace()),
            );
        }
        match rule {
            None => {
                stack.pop();
            }
            Some(rule @ Rule::Region { scope, .. }) => {
                scopes.push(scope.clone());
                stack.push(rule);
            }
            Some(Rule::Match { scope, .. }) => scopes.extend(scope.split_whitespace().map(str::to_string)),
        }
        // An empty match must not stall the scan.
        at = if stop > at { stop } else { next_char(line, at) };
    }
    unmatched
}

fn next_char(line: &str, at: usize) -> usize {
    line[at..].chars().next().map_or(line.len(), |c| at + c.len_utf8())
}

fn shipped_skills() -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    for dir in ["stdlib-skills", "examples/tasks", "tests/data/lsp"] {
        for entry in std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(dir)).expect("a shipped folder") {
            let path = entry.expect("an entry").path();
            if path.extension().is_some_and(|e| e == "skill") {
                files.push(path);
            }
        }
    }
    // The language's arithmetic, which no shipped skill needs yet.
    files.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("compiler/tests/corpus/ok/arithmetic.skill"));
    files.sort();
    files
}

#[test]
fn the_grammar_tokenises_every_shipped_skill_with_nothing_unmatched() {
    let rules = grammar();
    let files = shipped_skills();
    assert!(files.len() >= 11, "{files:?}");
    let mut problems = Vec::new();
    let mut scopes = Vec::new();
    for path in &files {
        let text = std::fs::read_to_string(path).expect("text");
        let mut stack = Vec::new();
        for (number, line) in text.lines().enumerate() {
            for (column, c) in tokenise(line, &rules, &mut stack, &mut scopes) {
                problems.push(format!(
                    "{}:{}:{}: `{c}` in `{line}`",
                    path.display(),
                    number + 1,
                    column + 1
                ));
            }
        }
        assert!(
            stack.is_empty(),
            "{}: a region is still open at the end",
            path.display()
        );
    }
    assert!(problems.is_empty(), "unmatched: {problems:#?}");
    for scope in [
        "comment.line.documentation.skill",
        "keyword.other.unit.skill",
        "support.function.learn.skill",
        "entity.name.function.skill",
        "string.quoted.double.skill",
        "keyword.operator.arithmetic.skill",
    ] {
        assert!(scopes.iter().any(|s| s == scope), "`{scope}` is used");
    }
}

#[test]
fn the_grammar_names_every_learn_function_of_the_table_and_every_unit() {
    let grammar = json("syntaxes/skill.tmLanguage.json");
    let functions = grammar["repository"]["functions"]["patterns"][0]["match"]
        .as_str()
        .expect("a pattern");
    let regex = Regex::new(&format!("^(?:{functions})$")).expect("compiles");
    for function in skill_compiler::info::learn_functions() {
        assert!(
            regex.is_match(function.name),
            "`{}` is highlighted as a learn function",
            function.name
        );
    }
    let quantity = grammar["repository"]["quantities"]["patterns"][0]["match"]
        .as_str()
        .expect("a pattern");
    let regex = Regex::new(&format!("^(?:{quantity})$")).expect("compiles");
    for (unit, _, _) in skill_compiler::units::UNITS {
        for text in [format!("10 {unit}"), format!("-1.5{unit}")] {
            let captures = regex
                .captures(&text)
                .unwrap_or_else(|| panic!("`{text}` is a quantity"));
            assert_eq!(&captures[2], *unit, "`{text}`: the whole unit");
        }
    }
}

#[test]
fn a_comment_or_string_with_non_ascii_text_is_one_token() {
    let rules = grammar();
    let mut scopes = Vec::new();
    let mut stack = Vec::new();
    let line = "    terminal done: success \"5° µ·\" // ≥ 5° → µ";
    assert!(tokenise(line, &rules, &mut stack, &mut scopes).is_empty());
    assert!(stack.is_empty());
    assert!(
        scopes.contains(&"comment.line.double-slash.skill".to_string()),
        "{scopes:?}"
    );
    let mut stack = Vec::new();
    let unmatched = tokenise("state a { ° }", &rules, &mut stack, &mut Vec::new());
    assert_eq!(unmatched, vec![(10, '°')], "a stray character is reported");
}

#[test]
fn the_extension_launches_skillc_lsp_for_skill_files() {
    let manifest = json("package.json");
    let language = &manifest["contributes"]["languages"][0];
    assert_eq!(language["id"], "skill");
    assert_eq!(language["extensions"][0], ".skill");
    let configuration = language["configuration"].as_str().expect("a language configuration");
    let config = json(configuration);
    assert_eq!(config["comments"]["lineComment"], "//");
    let grammar = &manifest["contributes"]["grammars"][0];
    assert_eq!(grammar["scopeName"], "source.skill");
    assert!(Path::new(EDITOR)
        .join(grammar["path"].as_str().expect("a path"))
        .is_file());
    let main = manifest["main"].as_str().expect("an entry point");
    let script = std::fs::read_to_string(Path::new(EDITOR).join(main)).expect("the extension's script");
    assert!(script.contains("args: [\"lsp\"]"), "the server is `skillc lsp`");
    assert_eq!(
        manifest["contributes"]["configuration"]["properties"]["skillc.path"]["default"],
        "skillc"
    );
}

#[test]
fn neovim_hovers_goes_to_definition_and_shows_diagnostics_as_you_type() {
    // Debian's Neovim (0.7) is enough: the script starts the client with `vim.lsp.start_client`.
    let found = std::process::Command::new("nvim").arg("--version").output();
    if !found.is_ok_and(|output| output.status.success()) {
        eprintln!("skipped: `nvim` is not installed (apt-get install neovim runs this test)");
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("skillc-neovim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    let file = dir.join("arithmetic.skill");
    std::fs::copy(root.join("compiler/tests/corpus/ok/arithmetic.skill"), &file).expect("copied");
    let out = dir.join("out.txt");
    let status = std::process::Command::new("timeout")
        .args(["60", "nvim", "--headless", "-n", "-u", "NONE", "-c"])
        .arg(format!("luafile {}", root.join("tests/data/lsp/neovim.lua").display()))
        .env("SKILLC", env!("CARGO_BIN_EXE_skillc"))
        .env("FILE", &file)
        .env("OUT", &out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .expect("nvim runs");
    let text = std::fs::read_to_string(&out).unwrap_or_default();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(status.success(), "nvim ended with {status}: {text}");
    assert!(text.contains("initialized: true offset_encoding: utf-16"), "{text}");
    assert!(text.contains("param hold = 2 s"), "hover shows the default: {text}");
    // The declaration of `hold`: line 9 (0-based 8), after `param `.
    assert!(text.contains("character = 10,\n      line = 8"), "definition: {text}");
    assert!(
        text.contains("multiplies a duration by a length") && text.contains("[skill::check::bad_arithmetic]"),
        "the diagnostic as you type: {text}"
    );
}
