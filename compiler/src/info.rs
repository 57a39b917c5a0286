//! Read-only facts about the language for tools (the language server): the learn functions of
//! the checker's one table, with their parameters and meaning.

/// One learn function as the checker's table declares it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LearnFunction {
    /// The name written in a template: `dmp`.
    pub name: &'static str,
    /// What it produces, which is where it may be written: `segments`, `cut` (of `cluster`),
    /// `point`, `frame`, `motion`, `force` or `threshold`.
    pub kind: &'static str,
    /// Its parameters, by name.
    pub params: &'static [&'static str],
    /// How many leading parameters may be given without their name.
    pub positional: usize,
    /// A call with its required arguments: `dmp(segment 1)`.
    pub example: &'static str,
    /// Other names people type for it.
    pub aliases: &'static [&'static str],
    /// What it learns, in one line.
    pub meaning: &'static str,
}

/// Every learn function, in the table's order (a name may appear once per kind: `dmp` is a
/// motion and a force).
pub fn learn_functions() -> Vec<LearnFunction> {
    crate::check::learn_function_table()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_learn_function_has_a_meaning_and_its_example_calls_it() {
        let table = learn_functions();
        assert!(table.len() > 20);
        for function in &table {
            assert!(!function.meaning.is_empty(), "{}", function.name);
            assert!(function.example.starts_with(function.name), "{}", function.name);
        }
        assert!(table.iter().any(|f| f.name == "dmp" && f.kind == "motion"));
        assert!(table.iter().any(|f| f.name == "dmp" && f.kind == "force"));
    }
}
