//! `skillc robot URDF [--tool LINK] [--q Q1,...,Qn] [--json]`: inspect a robot description (a
//! file, or a shipped robot by name: `lwr4`, `iiwa14`).

use std::path::PathBuf;

use skill_runtime::robot::{BuiltinRobot, Robot, RobotError};

use skill_kit::load::{error_chain, Failure};
use skill_kit::out;

/// Print a robot's chain (joints, axes, limits, masses) and, at a configuration, the tool pose,
/// the tool Jacobian and the gravity torques.
#[derive(Debug, Clone, clap::Args)]
pub struct RobotArgs {
    /// The URDF file, or a shipped robot's name (`lwr4`, `iiwa14`) when no such file exists.
    pub urdf: PathBuf,
    /// The tool link (default: the last link of the chain; a shipped robot's probe tip).
    #[arg(long, value_name = "LINK")]
    pub tool: Option<String>,
    /// Joint positions in rad, comma separated (default: all zero).
    #[arg(long, value_name = "Q1,...,Qn", value_delimiter = ',', allow_hyphen_values = true)]
    pub q: Option<Vec<f64>>,
    /// Print exactly one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs `skillc robot`, printing to stdout; the exit code.
pub fn run(args: &RobotArgs) -> u8 {
    match inspect(args).and_then(|text| out::print(&text)) {
        Ok(()) => 0,
        Err(failure) => failure.report(),
    }
}

/// A file that cannot be read is an IO error (exit 2); what it says is the input's problem
/// (exit 1), as under `skillc run`.
fn failure(err: &RobotError) -> Failure {
    match err {
        RobotError::Io { .. } => Failure::Usage(error_chain(err)),
        _ => Failure::Input(error_chain(err)),
    }
}

fn inspect(args: &RobotArgs) -> Result<String, Failure> {
    let builtin = args
        .urdf
        .to_str()
        .filter(|_| !args.urdf.exists())
        .and_then(BuiltinRobot::find);
    let robot = match builtin {
        Some(shipped) => Robot::from_urdf_str(shipped.urdf, Some(args.tool.as_deref().unwrap_or(shipped.tool))),
        None => Robot::from_urdf_file(&args.urdf, args.tool.as_deref()),
    }
    .map_err(|err| failure(&err))?;
    let inspection = robot.inspect(args.q.as_deref()).map_err(|err| match err {
        RobotError::WrongDof { .. } | RobotError::NonFinite { .. } => Failure::Usage(error_chain(&err)),
        _ => failure(&err),
    })?;
    if args.json {
        serde_json::to_string_pretty(&inspection)
            .map(|json| json + "\n")
            .map_err(|err| Failure::Usage(format!("cannot serialise the inspection: {err}")))
    } else {
        Ok(inspection.to_text())
    }
}
