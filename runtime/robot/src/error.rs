//! Errors from reading a robot description and building its model.

use std::path::PathBuf;

/// Why a URDF could not be turned into a [`Robot`](super::Robot).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RobotError {
    /// The file could not be read.
    #[error("cannot read `{path}`: {source}")]
    Io {
        /// The file that was asked for.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// The text is not a URDF that urdf-rs understands (bad XML, missing attributes, bad numbers).
    #[error("malformed urdf `{file}`: {message}")]
    Urdf {
        /// The file (or `<string>`).
        file: String,
        /// urdf-rs's description.
        message: String,
    },
    /// A link name (the tool, the sensor frame, …) that the robot does not declare.
    #[error("unknown link `{name}` in robot `{robot}` (links: {known})")]
    UnknownLink {
        /// The name asked for.
        name: String,
        /// The robot's name.
        robot: String,
        /// The links it has, comma separated.
        known: String,
    },
    /// A joint whose parent or child is not a `<link>` of the file.
    #[error("joint `{joint}` refers to unknown link `{link}`")]
    JointLinkMissing {
        /// The joint.
        joint: String,
        /// The missing link.
        link: String,
    },
    /// A link that is the child of two joints.
    #[error("link `{link}` is the child of several joints: a robot description must be a tree")]
    SeveralParents {
        /// The link.
        link: String,
    },
    /// Not exactly one link without a parent.
    #[error("expected exactly one root link (a link that is no joint's child), found {count}: {roots}")]
    Roots {
        /// How many there were.
        count: usize,
        /// Their names, comma separated.
        roots: String,
    },
    /// No tool link named and several ends of equally long chains to choose from.
    #[error("robot `{robot}` branches into several ends ({ends}): name the tool link (`tool = \"...\"` in the scene, `--tool` on the command line)")]
    AmbiguousTool {
        /// The robot's name.
        robot: String,
        /// The candidate end links, comma separated.
        ends: String,
    },
    /// A file that is not a URDF (xacro, SDF, MJCF, other XML, not XML).
    #[error("robot file `{file}` is {what}, not a URDF: {hint}")]
    NotUrdf {
        /// The file (or `<string>`).
        file: String,
        /// What it looks like.
        what: String,
        /// What to do instead.
        hint: String,
    },
    /// No joint positions within the limits put the tool at the pose asked for.
    #[error("no joint positions of robot `{robot}` put the tool at {target} (closest: {miss_mm:.1} mm, {miss_deg:.1}° away): the pose is out of reach or beyond the joint limits")]
    Unreachable {
        /// The robot's name.
        robot: String,
        /// The pose asked for, as text.
        target: String,
        /// Remaining position error \[mm\].
        miss_mm: f64,
        /// Remaining orientation error \[deg\].
        miss_deg: f64,
    },
    /// A problem in the model a file describes, with the file's name.
    #[error("robot `{file}`: {source}")]
    InFile {
        /// The file (or `<string>`).
        file: String,
        /// The problem.
        #[source]
        source: Box<RobotError>,
    },
    /// A joint type the model does not support (floating, planar, spherical).
    #[error("joint `{joint}` has unsupported type `{kind}` (supported: revolute, continuous, prismatic, fixed)")]
    UnsupportedJoint {
        /// The joint.
        joint: String,
        /// Its URDF type.
        kind: String,
    },
    /// No revolute or prismatic joint on the way to the tool.
    #[error("robot `{robot}` has no movable joint before tool link `{tool}`")]
    NoMovingJoint {
        /// The robot's name.
        robot: String,
        /// The tool link.
        tool: String,
    },
    /// A zero-length joint axis.
    #[error("joint `{joint}` has a zero or non-finite axis")]
    BadAxis {
        /// The joint.
        joint: String,
    },
    /// Joint limits that cannot hold (lower above upper, non-positive effort or velocity).
    #[error("joint `{joint}` has invalid limits: {reason}")]
    BadLimit {
        /// The joint.
        joint: String,
        /// What is wrong.
        reason: String,
    },
    /// A mass below zero.
    #[error("link `{link}` has negative mass {mass} kg")]
    NegativeMass {
        /// The link.
        link: String,
        /// The mass read.
        mass: f64,
    },
    /// A mass of zero with an inertia tensor that is not positive semi-definite (a massless
    /// link with a valid tensor loads, with a note).
    #[error("link `{link}` has zero mass and an inertia tensor that is not positive semi-definite (eigenvalues {eigenvalues})")]
    ZeroMass {
        /// The link.
        link: String,
        /// Its eigenvalues, for the message.
        eigenvalues: String,
    },
    /// A number in the file too large for a float: it would overflow to infinity and switch a
    /// limit off, or poison the dynamics. Only the word `inf` may stand for infinity.
    #[error("`{file}`, line {line}: `{text}` in `{attribute}` of `<{element}>` is too large for a number (it would overflow to infinity); write a finite value, or `inf` where no limit is meant")]
    Overflow {
        /// The file.
        file: String,
        /// The 1-based line.
        line: usize,
        /// The element the attribute belongs to.
        element: String,
        /// The attribute.
        attribute: String,
        /// The number as written.
        text: String,
    },
    /// An inertia tensor that is not symmetric positive definite.
    #[error("link `{link}` has an inertia tensor that is not positive definite (eigenvalues {eigenvalues})")]
    InertiaNotSpd {
        /// The link.
        link: String,
        /// Its eigenvalues, for the message.
        eigenvalues: String,
    },
    /// A movable joint that moves no mass at all: the dynamics would be singular.
    #[error("joint `{joint}` moves no mass: link `{link}` needs an `<inertial>` with a positive mass")]
    MissingInertial {
        /// The joint.
        joint: String,
        /// The link right after it.
        link: String,
    },
    /// A NaN or infinite number where a finite one is needed.
    #[error("non-finite number in `{item}`")]
    NonFinite {
        /// What it was (`joint a1 origin`, `link l1 mass`, …).
        item: String,
    },
    /// A joint vector of the wrong length.
    #[error("expected {expected} joint values for robot `{robot}`, got {got}")]
    WrongDof {
        /// The robot's name.
        robot: String,
        /// Its number of joints.
        expected: usize,
        /// What was given.
        got: usize,
    },
}
