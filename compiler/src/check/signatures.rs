//! The functions of a `learn` block in one table: their names, what each produces, its
//! parameters and an example. The checker binds arguments against it and takes its
//! "did you mean" candidates and "frames come from ..." lists from it; a test holds
//! `docs/language.md` to it. Each entry's [`Function`] is its mapping to the IR.

use ir::ConstraintModel as M;
use skill_ir as ir;
use Function as F;
use Produces as P;

/// What a learn function produces, which is also where it may be written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Produces {
    /// `segments = ...`
    Segmentation,
    /// `cut: ...` of a `cluster` segmentation.
    Cut,
    /// A point of the demonstration, e.g. the first argument of `force_at`.
    Point,
    /// `frame F = ...`
    Frame,
    /// `motion M = ...`
    Motion,
    /// `force P = ...`
    Force,
    /// `threshold T = ...`
    Threshold,
}

/// Which function an entry is; the checker lowers each to its IR form.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Function {
    NoSegments,
    MaxForce,
    Cluster,
    Changepoint,
    Count,
    Distance,
    PeakForce,
    End,
    Start,
    /// A frame fitted with one constraint model.
    Model(ir::ConstraintModel),
    /// A frame fitted with the best of several constraint models.
    Constraint,
    ForceAligned,
    Fixed,
    Dmp,
    Strokes,
    Constant,
    ForceAt,
    Magnitude,
    Tracked,
}

/// The signature of one learn function.
#[derive(Debug)]
pub(super) struct Signature {
    /// The name written in a template.
    pub(super) name: &'static str,
    /// What it produces.
    pub(super) produces: Produces,
    /// Which function it is, for lowering.
    pub(super) function: Function,
    /// Its parameters, by name.
    pub(super) params: &'static [&'static str],
    /// How many leading parameters may be given without their name.
    pub(super) positional: usize,
    /// A call with its required arguments, quoted as "write `EXAMPLE`" when one is missing.
    pub(super) example: &'static str,
    /// Other names people type for it, which "did you mean" maps to it.
    pub(super) aliases: &'static [&'static str],
}

const fn sig(
    name: &'static str,
    produces: Produces,
    function: Function,
    params: &'static [&'static str],
    positional: usize,
    example: &'static str,
) -> Signature {
    Signature {
        name,
        produces,
        function,
        params,
        positional,
        example,
        aliases: &[],
    }
}

impl Signature {
    /// This signature, with other names people type for it.
    const fn aka(self, aliases: &'static [&'static str]) -> Signature {
        Signature { aliases, ..self }
    }
}

/// The parameters of `cluster` and `changepoint`, longer than fit on their lines below.
const CLUSTER_PARAMS: &[&str] = &[
    "linkage",
    "time_weight",
    "connectivity",
    "cut",
    "min_length",
    "features",
];
const CHANGEPOINT_PARAMS: &[&str] = &["min_length", "models", "particles", "features"];

/// Every learn function. The order within a kind is the order of help lists, and the order
/// of the constraint models is the order `constraint` tries them in.
#[rustfmt::skip] // One line a function reads as a table.
pub(super) const LEARN_FUNCTIONS: &[Signature] = &[
    sig("none", P::Segmentation, F::NoSegments, &[], 0, "none"),
    sig("max_force", P::Segmentation, F::MaxForce, &[], 0, "max_force"),
    sig("cluster", P::Segmentation, F::Cluster, CLUSTER_PARAMS, 0, "cluster(cut: count(3))"),
    sig("changepoint", P::Segmentation, F::Changepoint, CHANGEPOINT_PARAMS, 0, "changepoint(min_length: 0.2 s) expect 3"),

    sig("count", P::Cut, F::Count, &["n"], 1, "count(3)"),
    sig("distance", P::Cut, F::Distance, &["d"], 1, "distance(2.5)"),

    sig("peak_force", P::Point, F::PeakForce, &["segment"], 1, "peak_force(segment 2)").aka(&["peak", "max_force_point"]),
    sig("end", P::Point, F::End, &["segment"], 1, "end(segment 1)"),
    sig("start", P::Point, F::Start, &["segment"], 1, "start(segment 1)"),

    sig("fixed_point", P::Frame, F::Model(M::FixedPoint), &["segment"], 1, "fixed_point(segment 2)").aka(&["point"]),
    sig("point_on_plane", P::Frame, F::Model(M::PointOnPlane), &["segment"], 1, "point_on_plane(segment 2)"),
    sig("planar", P::Frame, F::Model(M::Planar), &["segment"], 1, "planar(segment 2)").aka(&["plane"]),
    sig("cylinder", P::Frame, F::Model(M::ConcentricCylinder), &["segment"], 1, "cylinder(segment 2)").aka(&["concentric_cylinder"]),
    sig("prismatic", P::Frame, F::Model(M::Prismatic), &["segment"], 1, "prismatic(segment 2)"),
    sig("axial_rotation", P::Frame, F::Model(M::AxialRotation), &["segment"], 1, "axial_rotation(segment 2)").aka(&["hinge"]),
    sig("constraint", P::Frame, F::Constraint, &["segment", "models"], 1, "constraint(segment 2)"),
    sig("force_aligned", P::Frame, F::ForceAligned, &["segment", "at"], 1, "force_aligned(segment 2)` or `force_aligned(at: peak_force)"),
    sig("fixed", P::Frame, F::Fixed, &["origin", "rpy"], 0, "fixed(origin: [0 m, 0 m, 0.1 m])"),

    sig("dmp", P::Motion, F::Dmp, &["segment", "basis"], 1, "dmp(segment 1)"),
    sig("strokes", P::Motion, F::Strokes, &["segment", "basis", "min_length"], 1, "strokes(segment 2)").aka(&["stroke", "periodic", "cycles"]),

    sig("constant", P::Force, F::Constant, &["segment", "along"], 1, "constant(segment 2, along: surface.z)"),
    sig("force_at", P::Force, F::ForceAt, &["point", "along"], 1, "force_at(end(segment 1), along: contact.z)"),
    sig("dmp", P::Force, F::Dmp, &["segment", "basis"], 1, "dmp(segment 2)"),
    sig("magnitude", P::Force, F::Magnitude, &["segment", "along", "basis"], 1, "magnitude(segment 2, along: surface.z)"),
    sig("tracked", P::Force, F::Tracked, &[], 0, "tracked"),

    sig("force_at", P::Threshold, F::ForceAt, &["point", "along", "scale"], 1, "force_at(end(segment 1), along: contact.z)"),
];

impl Signature {
    /// The function of this name that produces `produces`.
    pub(super) fn find(produces: Produces, name: &str) -> Option<&'static Signature> {
        LEARN_FUNCTIONS
            .iter()
            .find(|sig| sig.produces == produces && sig.name == name)
    }

    /// The names of the functions that produce `produces`, in table order.
    pub(super) fn names(produces: Produces) -> Vec<&'static str> {
        LEARN_FUNCTIONS
            .iter()
            .filter(|sig| sig.produces == produces)
            .map(|sig| sig.name)
            .collect()
    }

    /// The name `alias` stands for, if it is an alias of a learn function.
    pub(super) fn alias_of(alias: &str) -> Option<&'static str> {
        LEARN_FUNCTIONS
            .iter()
            .find(|sig| sig.aliases.contains(&alias))
            .map(|sig| sig.name)
    }

    /// The constraint models by name, in the order `constraint` tries them.
    pub(super) fn constraint_models() -> Vec<(&'static str, ir::ConstraintModel)> {
        LEARN_FUNCTIONS
            .iter()
            .filter_map(|sig| match sig.function {
                Function::Model(model) => Some((sig.name, model)),
                _ => None,
            })
            .collect()
    }
}

impl Signature {
    /// What the function learns, in one line: the meaning column of docs/language.md's `learn`
    /// table, for tools (the language server's hover). The match is exhaustive, so a new
    /// function cannot be added without one.
    pub(super) fn meaning(&self) -> &'static str {
        match (self.function, self.produces) {
            (F::NoSegments, _) => "the whole demonstration as one segment",
            (F::MaxForce, _) => "two segments split at the force peak (touch)",
            (F::Cluster, _) => "agglomerative clustering of standardised features (position, force, force_magnitude)",
            (F::Changepoint, _) => "CHAMP-style change-point detection; `expect N` is required because the method does not fix the count",
            (F::Count, _) => "cut the cluster tree into N segments",
            (F::Distance, _) => "cut the cluster tree at a linkage distance",
            (F::PeakForce, _) => "the sample of largest force, in the demonstration or within one segment",
            (F::End, _) => "the last sample of a segment",
            (F::Start, _) => "the first sample of a segment",
            (F::Model(_), _) => "one of the six constraint models fitted on a segment",
            (F::Constraint, _) => "fit the candidate constraint models (default all six) and keep the best",
            (F::ForceAligned, _) => "a frame with z along the applied force without its component along the motion (friction): per sample over a segment, or one frame at a point",
            (F::Fixed, _) => "a literal frame in the base frame",
            (F::Dmp, P::Force) => "DMPs of the applied force vector (base frame)",
            (F::Dmp, _) => "position DMP and quaternion DMP of a segment",
            (F::Strokes, _) => "the segment cut into strokes where its main direction of travel reverses, a DMP pair per stroke",
            (F::Constant, _) => "a constant force from the lowest-variance in-contact region of a segment",
            (F::ForceAt, P::Threshold) => "a learned scalar threshold: the force at a point along an axis, scaled",
            (F::ForceAt, _) => "the force at a point along an axis",
            (F::Magnitude, _) => "the applied force along a (moving) frame axis, as a DMP",
            (F::Tracked, _) => "no desired force: force-controlled axes comply, guards watch",
        }
    }
}

/// A read-only view of one entry of [`LEARN_FUNCTIONS`], for tools outside the checker.
pub(crate) fn public_table() -> Vec<crate::info::LearnFunction> {
    LEARN_FUNCTIONS
        .iter()
        .map(|sig| crate::info::LearnFunction {
            name: sig.name,
            kind: match sig.produces {
                P::Segmentation => "segments",
                P::Cut => "cut",
                P::Point => "point",
                P::Frame => "frame",
                P::Motion => "motion",
                P::Force => "force",
                P::Threshold => "threshold",
            },
            params: sig.params,
            positional: sig.positional,
            example: sig.example,
            aliases: sig.aliases,
            meaning: sig.meaning(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether `text` has `word` with no identifier character on either side.
    fn has_word(text: &str, word: &str) -> bool {
        let is_ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
        text.match_indices(word).any(|(at, _)| {
            let before = text[..at].chars().next_back();
            let after = text[at + word.len()..].chars().next();
            !before.is_some_and(is_ident) && !after.is_some_and(is_ident)
        })
    }

    #[test]
    fn the_language_docs_describe_every_learn_function_and_parameter() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/language.md");
        let docs = std::fs::read_to_string(path).expect("docs/language.md is readable");
        let mut missing = Vec::new();
        for sig in LEARN_FUNCTIONS {
            // The lines that show the function as a call, or else name it.
            let call = format!("{}(", sig.name);
            let mut lines: Vec<&str> = docs.lines().filter(|line| line.contains(&call)).collect();
            if lines.is_empty() {
                lines = docs.lines().filter(|line| has_word(line, sig.name)).collect();
            }
            if lines.is_empty() {
                missing.push(format!("`{}`", sig.name));
                continue;
            }
            for param in sig.params {
                // A parameter is shown by name (`along: F.z`) or, when positional, as a
                // placeholder (`segment N`, `POINT`, `count(N)`).
                let shown = lines
                    .iter()
                    .any(|line| has_word(line, param) || has_word(&line.to_lowercase(), param));
                if !shown {
                    missing.push(format!("`{}` of `{}`", param, sig.name));
                }
            }
        }
        assert!(
            missing.is_empty(),
            "docs/language.md does not describe {}",
            missing.join(", ")
        );
    }

    #[test]
    fn names_are_unique_per_kind_and_positional_params_exist() {
        for (i, a) in LEARN_FUNCTIONS.iter().enumerate() {
            assert!(a.positional <= a.params.len(), "{}", a.name);
            for b in &LEARN_FUNCTIONS[i + 1..] {
                assert!(
                    a.name != b.name || a.produces != b.produces,
                    "`{}` twice for {:?}",
                    a.name,
                    a.produces
                );
            }
        }
    }
}
