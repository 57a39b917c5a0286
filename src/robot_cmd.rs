//! `skillc robot URDF \[--tool LINK\] \[--q Q1,...,Qn\] \[--json\]`: inspect a robot description.

use std::io::Write as _;
use std::path::PathBuf;

use skill_runtime::robot::Robot;

/// Print a robot's chain (joints, axes, limits, masses) and, at a configuration, the tool pose,
/// the tool Jacobian and the gravity torques.
#[derive(Debug, Clone, clap::Args)]
pub struct RobotArgs {
    /// The URDF file.
    pub urdf: PathBuf,
    /// The tool link (default: the last link of the chain).
    #[arg(long, value_name = "LINK")]
    pub tool: Option<String>,
    /// Joint positions in rad, comma separated (default: all zero).
    #[arg(long, value_name = "Q1,...,Qn", value_delimiter = ',', allow_hyphen_values = true)]
    pub q: Option<Vec<f64>>,
    /// Print exactly one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs `skillc robot`, printing to stdout.
pub fn run(args: &RobotArgs) -> Result<(), Box<dyn std::error::Error>> {
    let robot = Robot::from_urdf_file(&args.urdf, args.tool.as_deref())?;
    let inspection = robot.inspect(args.q.as_deref())?;
    let text = if args.json {
        serde_json::to_string_pretty(&inspection)? + "\n"
    } else {
        inspection.to_text()
    };
    // Write errors (a closed pipe) become an error, not a panic as `println!` would.
    std::io::stdout().lock().write_all(text.as_bytes())?;
    Ok(())
}
