//! `skillc learn SKILL DEMO.csv|DEMO.mcap -o OUT.learned.json` and `skillc rollout`: learning a template's
//! features from one demonstration, and previewing what was learned.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use skill_runtime::demo::{Dialect, ForceSign, WrenchDeclaration, WrenchFrame, COLUMNS};
use skill_runtime::exec::bind;
use skill_runtime::skill::rollout::PreviewSample;
use skill_runtime::skill::{LearnOptions, Learned, LearnedForce, LearnedFrame};

use skill_kit::load::{learn_from_source, load_skill, read_learned, Failure};
use skill_kit::out::{self, Verbosity};
use skill_kit::plot::{self, Plot, Subject};
use skill_kit::{atomic, limits};

/// Arguments of `skillc learn`.
#[derive(Debug, Clone, clap::Args)]
pub struct LearnArgs {
    /// The `.skill` file.
    pub skill_file: PathBuf,
    /// The demonstration: CSV (columns t, px, py, pz, qw, qx, qy, qz, fx, fy, fz, mx, my, mz;
    /// separated by commas, semicolons, tabs or bars, detected from the header line), or a ROS 2
    /// bag as MCAP (`.mcap`: a PoseStamped topic or TF, and a WrenchStamped topic, the wrench
    /// linearly interpolated onto the pose's times).
    pub demo: PathBuf,
    /// Where to write the learned features (JSON, written atomically).
    #[arg(short, long)]
    pub output: PathBuf,
    /// The skill to learn, when the file defines several.
    #[arg(long)]
    pub skill: Option<String>,
    /// Low-pass cut-off in Hz (0.1 to 10000), overriding the template's `lowpass`.
    #[arg(long, value_name = "HZ", value_parser = limits::rate_hz)]
    pub lowpass: Option<f64>,
    /// Resampling rate in Hz (0.1 to 10000), overriding the template's `resample`.
    #[arg(long, value_name = "HZ", value_parser = limits::rate_hz)]
    pub resample: Option<f64>,
    /// The demonstration's field separator: `,`, `;`, `tab`, `|` or any single character
    /// (default: detected from the header line).
    #[arg(long, value_name = "SEP", value_parser = parse_delimiter)]
    pub delimiter: Option<u8>,
    /// The demonstration's names for skillc's columns, e.g. `t=time,px=x,py=y,pz=z` (skillc's
    /// name first). Common spellings (time, position.x, orientation.w, force_x, torque_x) are
    /// found without it.
    #[arg(long, value_name = "OURS=THEIRS,...", value_parser = parse_columns)]
    pub columns: Option<BTreeMap<String, String>>,
    /// The file's forces are the force the robot applies (not, as skillc expects, the force the
    /// environment exerts on the tool): negate them before learning. The same as
    /// `--force-sign applied`.
    #[arg(long, conflicts_with = "force_sign")]
    pub applied_force: bool,
    /// Which wrench the file stores: `on-tool` (what a wrist sensor reports) or `applied` (the
    /// robot's, negated before learning). Default: the file's `# force_sign:` line, else detected.
    #[arg(long, value_name = "SIGN")]
    pub force_sign: Option<ForceSign>,
    /// The axes of the file's force and moment columns: `base` (the robot base frame) or `sensor`
    /// (the wrist sensor's, taken as the flange's; rotated into the base frame by the flange
    /// orientation). Default: the file's `# wrench_frame:` line, else detected.
    #[arg(long, value_name = "FRAME")]
    pub wrench_frame: Option<WrenchFrame>,
    /// For a sensor-frame wrench: the angle in degrees (-360 to 360) the sensor's axes are turned
    /// from the flange's about the tool axis. Default: the file's `# sensor_turn:` line, else
    /// detected among 0, 90, 180 and 270.
    #[arg(long, value_name = "DEG", allow_hyphen_values = true, value_parser = parse_turn)]
    pub sensor_turn: Option<f64>,
    /// Keep the sensor bias: do not remove the mean wrench of a still, contact-free period.
    #[arg(long)]
    pub keep_bias: bool,
    /// The friction coefficient µ (0.01 to 100, default 0.5) that bounds how far the contact force
    /// may lean from a fitted plane's normal (atan µ); beyond it z follows the applied force.
    #[arg(long, value_name = "MU", value_parser = parse_friction)]
    pub friction: Option<f64>,
    /// MCAP: the `geometry_msgs/PoseStamped` topic with the flange pose in the base frame
    /// (default: the file's only PoseStamped topic, else TF).
    #[arg(long, value_name = "TOPIC", conflicts_with_all = ["tf_parent", "tf_child"])]
    pub pose_topic: Option<String>,
    /// MCAP: the `geometry_msgs/WrenchStamped` topic (default: the file's only one). Its header
    /// frame declares the wrench's axes when it names the pose's base frame or the TF tool frame.
    #[arg(long, value_name = "TOPIC")]
    pub wrench_topic: Option<String>,
    /// MCAP: read the pose from TF (`tf2_msgs/TFMessage`), the transform from this base frame.
    #[arg(long, value_name = "FRAME")]
    pub tf_parent: Option<String>,
    /// MCAP: read the pose from TF, the transform to this tool frame (one direct transform, not a chain).
    #[arg(long, value_name = "FRAME")]
    pub tf_child: Option<String>,
    /// The contact phase to learn from (1, 2, ...), when the demonstration has several (a part
    /// wiped three times with lift-offs between): default, the whole demonstration, or the
    /// longest phase when the template expects one contact (said so).
    #[arg(long, value_name = "N", value_parser = parse_phase, allow_negative_numbers = true)]
    pub phase: Option<usize>,
    /// Also draw what was learned into this folder (SVG): the demonstration against the
    /// rollout with segments and frames, forces in the world and compliant frames.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
}

/// `--friction`: a friction coefficient from 0.01 to 100.
pub fn parse_friction(text: &str) -> Result<f64, String> {
    let mu: f64 = text.trim().parse().map_err(|_| format!("`{text}` is not a number"))?;
    if (0.01..=100.0).contains(&mu) {
        Ok(mu)
    } else {
        Err(format!("{mu} is outside 0.01 to 100"))
    }
}

/// `--sensor-turn`: an angle from -360 to 360 degrees.
pub fn parse_turn(text: &str) -> Result<f64, String> {
    let deg: f64 = text.trim().parse().map_err(|_| format!("`{text}` is not a number"))?;
    if (-360.0..=360.0).contains(&deg) {
        Ok(deg)
    } else {
        Err(format!("{deg} is outside -360 to 360 degrees"))
    }
}

/// `--delimiter`: one character, or `tab`.
pub fn parse_delimiter(text: &str) -> Result<u8, String> {
    match text {
        "tab" | "\\t" | "\t" => Ok(b'\t'),
        _ => match text.as_bytes() {
            [byte] if byte.is_ascii() && *byte != b'"' && *byte != b'\n' && *byte != b'\r' => Ok(*byte),
            _ => Err(format!("`{text}` is not one ASCII character (or `tab`)")),
        },
    }
}

/// `--columns t=time,px=x,...`: skillc's column name, `=`, the file's. A pair written the
/// other way round (`time=t`) is read the right way, since only one side is one of skillc's.
pub fn parse_columns(text: &str) -> Result<BTreeMap<String, String>, String> {
    let mut map = BTreeMap::new();
    for pair in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let Some((left, right)) = pair.split_once('=') else {
            return Err(format!("`{pair}` must look like OURS=THEIRS, e.g. t=time"));
        };
        let (left, right) = (left.trim(), right.trim());
        let (ours, theirs) = if COLUMNS.contains(&left) {
            (left, right)
        } else if COLUMNS.contains(&right) {
            (right, left)
        } else {
            return Err(format!(
                "neither `{left}` nor `{right}` is one of skillc's columns ({})",
                COLUMNS.join(", ")
            ));
        };
        if theirs.is_empty() {
            return Err(format!("`{pair}` names no column of the file"));
        }
        if map.insert(ours.to_owned(), theirs.to_owned()).is_some() {
            return Err(format!("column `{ours}` is mapped twice"));
        }
    }
    Ok(map)
}

/// Runs `skillc learn`.
pub fn run(args: &LearnArgs, verbosity: Verbosity) -> u8 {
    let started = std::time::Instant::now();
    let result = learn(args).and_then(|(summary, warnings)| {
        if verbosity.verbose() {
            eprintln!("learned in {:.2} s", started.elapsed().as_secs_f64());
        }
        if verbosity.quiet() {
            // The summary (which lists them) is not printed: the warnings still are.
            for warning in warnings {
                eprintln!("warning: {warning}");
            }
            Ok(())
        } else {
            out::print(&summary)
        }
    });
    match result {
        Ok(()) => 0,
        Err(failure) => failure.report(),
    }
}

/// The flags that only apply to the other kind of demonstration file: given, they would be
/// silently ignored.
fn refuse_other_kinds_flags(args: &LearnArgs) -> Result<(), Failure> {
    let demo = args.demo.display();
    if skill_ros::bag::is_mcap(&args.demo) {
        let csv_flags = [
            ("--delimiter", args.delimiter.is_some()),
            ("--columns", args.columns.is_some()),
        ];
        if let Some((flag, _)) = csv_flags.iter().find(|(_, given)| *given) {
            return Err(Failure::Usage(format!(
                "{flag} is for CSV demonstrations; `{demo}` is a ROS 2 bag (MCAP): choose its topics with --pose-topic/--wrench-topic or --tf-parent/--tf-child"
            )));
        }
    } else {
        let bag_flags = [
            ("--pose-topic", args.pose_topic.is_some()),
            ("--wrench-topic", args.wrench_topic.is_some()),
            ("--tf-parent", args.tf_parent.is_some()),
            ("--tf-child", args.tf_child.is_some()),
        ];
        if let Some((flag, _)) = bag_flags.iter().find(|(_, given)| *given) {
            return Err(Failure::Usage(format!(
                "{flag} is for ROS 2 bags (`.mcap` files); `{demo}` is read as CSV"
            )));
        }
    }
    Ok(())
}

fn learn(args: &LearnArgs) -> Result<(String, Vec<String>), Failure> {
    atomic::refuse_inputs(&args.output, "-o", &[&args.skill_file, &args.demo]).map_err(Failure::Usage)?;
    refuse_other_kinds_flags(args)?;
    let (_, skill) = load_skill(&args.skill_file, args.skill.as_deref())?;
    // The skill's imports are inputs too.
    atomic::refuse_inputs(&args.output, "-o", &[]).map_err(Failure::Usage)?;
    let options = LearnOptions {
        lowpass_hz: args.lowpass,
        resample_hz: args.resample,
        wrench: WrenchDeclaration {
            frame: args.wrench_frame,
            sign: args.force_sign,
            sensor_turn_deg: args.sensor_turn,
        },
        keep_bias: args.keep_bias,
        friction_mu: args.friction,
        phase: args.phase,
    };
    let dialect = Dialect {
        delimiter: args.delimiter,
        columns: args.columns.clone().unwrap_or_default(),
    };
    let bag = skill_ros::bag::BagOptions {
        pose_topic: args.pose_topic.clone(),
        wrench_topic: args.wrench_topic.clone(),
        tf_parent: args.tf_parent.clone(),
        tf_child: args.tf_child.clone(),
    };
    let (learned, provenance) = learn_from_source(&skill, &args.demo, &dialect, &bag, &options, args.applied_force)?;
    let json = serde_json::to_string_pretty(&learned).map_err(|err| Failure::Usage(err.to_string()))? + "\n";
    // The plots are drawn in memory first; then every file is written, and on any failure the
    // ones this command created are removed: nothing new is left behind.
    let mut plots = Vec::new();
    if let Some(dir) = &args.plot {
        let bound = bind(&skill, &learned).map_err(|err| Failure::Input(err.to_string()))?;
        let subject = Subject {
            name: &learned.skill,
            demo: &args.demo,
            bound: Some(&bound),
        };
        for kind in [Plot::Trajectory, Plot::LearnedForce] {
            let svg = plot::render(kind, &subject, &[])
                .map_err(|err| Failure::Usage(format!("cannot plot `{}`: {err}", kind.name())))?;
            plots.push((dir.join(format!("{}_{}.svg", learned.skill, kind.name())), svg));
        }
    }
    // The learned file last: it replaces an earlier one only once every plot is written.
    let mut files: Vec<(&Path, &[u8])> = plots
        .iter()
        .map(|(path, svg)| (path.as_path(), svg.as_bytes()))
        .collect();
    files.push((args.output.as_path(), json.as_bytes()));
    write_all_or_none(&files, args.plot.as_deref())?;
    let mut out = summary(&learned);
    if let Some(provenance) = provenance {
        out = out.replacen('\n', &format!("\n  {provenance}\n"), 1);
    }
    let _ = writeln!(out, "wrote `{}`", args.output.display());
    for (path, _) in &plots {
        let _ = writeln!(out, "wrote `{}`", path.display());
    }
    Ok((out, learned.demo.warnings))
}

/// Writes each of `files` (each atomically), creating the folder `plot_dir` if it is missing; on
/// any failure, removes the files written and the folder created here, so a failed command
/// leaves nothing new behind. (A file that existed before and was already replaced stays
/// replaced: its old content is gone once the rename is done.)
fn write_all_or_none(files: &[(&Path, &[u8])], plot_dir: Option<&Path>) -> Result<(), Failure> {
    let created_dir = match plot_dir {
        Some(dir) if !dir.exists() => {
            std::fs::create_dir_all(dir)
                .map_err(|err| Failure::Usage(format!("cannot create `{}`: {err}", dir.display())))?;
            Some(dir)
        }
        _ => None,
    };
    let mut written: Vec<&Path> = Vec::new();
    for (path, bytes) in files {
        let existed = path.exists();
        if let Err(err) = atomic::write(path, bytes) {
            for done in &written {
                let _ = std::fs::remove_file(done);
            }
            if let Some(dir) = created_dir {
                let _ = std::fs::remove_dir(dir);
            }
            return Err(Failure::Usage(format!("cannot write `{}`: {err}", path.display())));
        }
        if !existed {
            written.push(path);
        }
    }
    Ok(())
}

/// A short human summary of what was learned.
pub fn summary(learned: &Learned) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "learned `{}` from `{}` ({} samples, {:.2} s, {:.0} Hz)",
        learned.skill, learned.demo.source, learned.demo.samples, learned.demo.duration_s, learned.demo.rate_hz
    );
    if let Some(noise) = learned.quality.position_noise_m {
        let _ = writeln!(
            out,
            "  position noise {} per axis; {}",
            if noise < 1e-5 {
                format!("{:.2} µm", noise * 1e6)
            } else {
                format!("{:.3} mm", noise * 1e3)
            },
            learned.quality.smoothing
        );
    }
    if let Some(wrench) = &learned.quality.wrench {
        let _ = writeln!(out, "  wrench: {}", wrench.frame);
        let _ = writeln!(out, "  bias: {}", wrench.bias);
        let _ = writeln!(out, "  sign: {}", wrench.sign);
    }
    for warning in &learned.demo.warnings {
        let _ = writeln!(out, "  warning: {warning}");
    }
    if let Some(phases) = &learned.quality.phases {
        let _ = writeln!(out, "  {}", phases_line(phases));
        for moved in &phases.moved {
            let _ = writeln!(
                out,
                "  segment {} starts at the contact's {}: {:.3} → {:.3} s",
                moved.segment, moved.end, moved.from_to_s[0], moved.from_to_s[1]
            );
        }
    }
    let _ = writeln!(out, "segments:");
    for (index, segment) in learned.segments.iter().enumerate() {
        let _ = writeln!(
            out,
            "  {}  {:7.3} s .. {:7.3} s  ({} samples)",
            index + 1,
            segment.start_s,
            segment.end_s,
            segment.end_index - segment.start_index
        );
    }
    for contact in &learned.quality.contacts {
        let _ = writeln!(out, "  {}", contact_line(contact));
    }
    if !learned.frames.is_empty() {
        let _ = writeln!(out, "frames:");
    }
    for (name, frame) in &learned.frames {
        let pose = frame.at(0.0);
        let z = pose.rotation * nalgebra::Vector3::z();
        let detail = match frame {
            LearnedFrame::Constant(_) => String::new(),
            LearnedFrame::Samples(poses) => format!(", {} samples", poses.len()),
        };
        let residual = learned
            .quality
            .constraints
            .get(name)
            .and_then(|fits| fits.iter().find(|f| f.chosen))
            .map(|fit| {
                format!(
                    ", residual {:.2} mm / {:.2}°",
                    fit.residual_m * 1e3,
                    fit.residual_rad.to_degrees()
                )
            })
            .unwrap_or_default();
        let _ = writeln!(
            out,
            "  {name:<10} {:<16} z = [{:+.3}, {:+.3}, {:+.3}]{residual}{detail}",
            frame.kind(),
            z.x,
            z.y,
            z.z
        );
        if let Some(window) = learned.quality.onset_frames.get(name) {
            let _ = writeln!(
                out,
                "  {:<10} z from the first contact window {:.3}-{:.3} s ({} samples, {:.2} N, scatter {:.1}°)",
                "", window.window_s[0], window.window_s[1], window.samples, window.mean_n, window.scatter_deg
            );
        }
        if let Some(check) = learned.quality.normals.get(name) {
            let _ = writeln!(
                out,
                "  {:<10} fitted normal {:.1}° from the mean applied force (friction cone {:.1}°): {}",
                "",
                check.angle_deg,
                check.cone_deg,
                if check.replaced {
                    "replaced by the force's direction"
                } else {
                    "kept"
                }
            );
            if let Some(spread) = check.spread_deg {
                let _ = writeln!(
                    out,
                    "  {:<10} the measured normal turns {spread:.1}° about its mean while sliding, {:.1}° about the path's shape: {}",
                    "",
                    check.unexplained_deg.unwrap_or(f64::NAN),
                    if check.follows_surface {
                        "a curved surface, z follows the measured normal sample by sample"
                    } else {
                        "z holds the plane's normal"
                    }
                );
            }
        }
    }
    if !learned.motions.is_empty() {
        let _ = writeln!(out, "motions (reconstruction RMS):");
    }
    for (name, motion) in &learned.motions {
        let quality = learned.quality.motions.get(name);
        let (position, rotation) = quality.map_or((f64::NAN, f64::NAN), |q| {
            let [x, y, z] = q.position_rms_m;
            (((x * x + y * y + z * z) / 3.0).sqrt(), q.orientation_rms_rad)
        });
        let _ = writeln!(
            out,
            "  {name:<10} segment {}  {:.2} s  {:.3} mm, {:.3}°",
            motion.segment + 1,
            motion.position.tau_s,
            position * 1e3,
            rotation.to_degrees()
        );
        if let Some(quality) = quality.filter(|q| !q.strokes_s.is_empty()) {
            let times: Vec<String> = quality
                .strokes_s
                .iter()
                .map(|[start, end]| format!("{start:.2}-{end:.2}"))
                .collect();
            let _ = writeln!(
                out,
                "  {:<10} {} stroke(s) at {} s (the worst stroke's RMS above)",
                "",
                quality.strokes_s.len(),
                times.join(", ")
            );
        }
    }
    if !learned.forces.is_empty() {
        let _ = writeln!(out, "forces:");
    }
    for (name, force) in &learned.forces {
        let text = match force {
            LearnedForce::Constant {
                value_n,
                std_n,
                region_s,
            } => {
                format!(
                    "constant {value_n:.2} N (σ {std_n:.2} N over {:.2}..{:.2} s)",
                    region_s[0], region_s[1]
                )
            }
            LearnedForce::At { value_n } => format!("at a point {value_n:.2} N"),
            LearnedForce::Literal { value_n } => format!("literal {value_n:.2} N"),
            LearnedForce::Tracked { .. } => "tracked".to_string(),
            LearnedForce::Dmp { dmp } => format!(
                "DMP of the force vector, {:.2} s, RMS {:.3} N",
                dmp.tau_s,
                learned.quality.forces_rms_n.get(name).copied().unwrap_or(f64::NAN)
            ),
            LearnedForce::Magnitude { dmp } => format!(
                "DMP of the normal force, {:.2} s, RMS {:.3} N",
                dmp.tau_s,
                learned.quality.forces_rms_n.get(name).copied().unwrap_or(f64::NAN)
            ),
        };
        let _ = writeln!(out, "  {name:<10} {text}");
    }
    for (name, threshold) in &learned.thresholds {
        let _ = writeln!(out, "threshold {name} = {:.2}", threshold.value);
    }
    out
}

/// `3 contact phases: 4.10-13.20 s, ...; learned phase 2 (the longest)`.
pub fn phases_line(phases: &skill_runtime::skill::PhaseReport) -> String {
    let count = phases.phases_s.len();
    let list: Vec<String> = phases
        .phases_s
        .iter()
        .zip(&phases.median_n)
        .map(|([start, end], median)| format!("{start:.2}-{end:.2} s ({median:.1} N)"))
        .collect();
    let mut line = match count {
        0 => format!("no contact phase (force under {:.2} N)", phases.on_n),
        1 => format!("1 contact phase: {}", list.join(", ")),
        _ => format!("{count} contact phases: {}", list.join(", ")),
    };
    if let Some(phase) = phases.learned {
        let why = match phases.chosen_by.as_str() {
            "longest" => " (the longest; --phase N picks another)",
            "--phase" => " (--phase)",
            _ => "",
        };
        let _ = write!(line, "; learned phase {phase}{why}");
    }
    line
}

/// Arguments of `skillc rollout`.
#[derive(Debug, Clone, clap::Args)]
pub struct RolloutArgs {
    /// The learned file.
    pub learned: PathBuf,
    /// Write the rollout here (CSV in the demonstration's columns) instead of standard output.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Move every motion goal by DX,DY,DZ metres (base frame; each at most 10 m).
    #[arg(long, value_name = "DX,DY,DZ", value_delimiter = ',', allow_hyphen_values = true, value_parser = limits::offset_m)]
    pub goal_offset: Option<Vec<f64>>,
    /// Sample period in seconds (0.0001 to 1).
    #[arg(long, default_value_t = 0.001, value_parser = limits::period_s)]
    pub dt: f64,
    /// The `.skill` file the learned file was learned from: with it the force and moment
    /// columns hold the learned forces (each on its segment, as the demonstration stores them:
    /// the wrench on the tool); without it they are 0.
    #[arg(long, value_name = "FILE")]
    pub template: Option<PathBuf>,
}

/// Most rows `skillc rollout` writes.
const MAX_ROLLOUT_ROWS: f64 = 5e6;

/// Runs `skillc rollout`: the kinematic rollout of every learned motion in segment order, a
/// segment without a motion held at the last pose for its demonstrated duration, with the
/// learned forces on their segments when the template is given.
pub fn rollout(args: &RolloutArgs, verbosity: Verbosity) -> u8 {
    let run = || -> Result<(), Failure> {
        let dt = limits::check("--dt", args.dt, limits::PERIOD_S, " s").map_err(Failure::Usage)?;
        if let Some(path) = &args.output {
            let mut inputs: Vec<&std::path::Path> = vec![&args.learned];
            inputs.extend(args.template.as_deref());
            atomic::refuse_inputs(path, "-o", &inputs).map_err(Failure::Usage)?;
        }
        let learned = read_learned(&args.learned)?;
        let rows: f64 = learned
            .motions
            .values()
            .map(|m| (m.position.tau_s / dt).ceil() + 1.0)
            .chain(
                learned
                    .segments
                    .iter()
                    .map(|s| ((s.end_s - s.start_s).max(0.0) / dt).ceil()),
            )
            .sum();
        if rows > MAX_ROLLOUT_ROWS {
            return Err(Failure::Usage(format!(
                "a rollout of `{}` at --dt {dt} s would write {rows:.0} rows, at most {MAX_ROLLOUT_ROWS:.0}: choose a larger --dt",
                args.learned.display()
            )));
        }
        let offset = match args.goal_offset.as_deref() {
            Some([dx, dy, dz]) => nalgebra::Vector3::new(*dx, *dy, *dz),
            Some(_) => return Err(Failure::Usage("--goal-offset takes three numbers: DX,DY,DZ".into())),
            None => nalgebra::Vector3::zeros(),
        };
        for value in offset.iter() {
            limits::check("--goal-offset", *value, (-limits::OFFSET_M, limits::OFFSET_M), " m")
                .map_err(Failure::Usage)?;
        }
        let template = match &args.template {
            Some(path) => {
                let (_, skill) = load_skill(path, Some(&learned.skill))?;
                Some((path, skill))
            }
            None => None,
        };
        let bound = match &template {
            Some((path, skill)) => Some(bind(skill, &learned).map_err(|err| {
                Failure::Input(format!(
                    "`{}` was not learned for skill `{}` of `{}`: {err}",
                    args.learned.display(),
                    skill.name,
                    path.display()
                ))
            })?),
            None => None,
        };
        let mut rows = timeline(&learned, dt, offset);
        let finite = |row: &Row| {
            row.position_m
                .iter()
                .chain(row.orientation.coords.iter())
                .chain(row.wrench.iter())
                .all(|v| v.is_finite())
        };
        let unplaced = match &bound {
            Some(bound) => place_forces(&mut rows, bound, dt),
            None => Vec::new(),
        };
        if let Some(bad) = rows.iter().find(|row| !finite(row)) {
            return Err(Failure::Input(format!(
                "the rollout of `{}` diverges (not finite at {:.3} s); nothing written",
                args.learned.display(),
                bad.t_s
            )));
        }
        if bound.is_none() && !learned.forces.is_empty() {
            verbosity.note(format_args!(
                "note: the force and moment columns are 0: give the template with --template FILE.skill to fill them from the learned forces"
            ));
        }
        for name in unplaced {
            verbosity.note(format_args!(
                "note: force `{name}` is not learned over a segment (a point, a literal or none): its columns stay 0"
            ));
        }
        let mut text = String::from("t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,mx,my,mz\n");
        for row in &rows {
            let q = row.orientation.quaternion();
            let p = row.position_m;
            let w = row.wrench;
            let _ = writeln!(
                text,
                "{:.4},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{},{},{},{},{},{}",
                row.t_s,
                p.x,
                p.y,
                p.z,
                q.w,
                q.i,
                q.j,
                q.k,
                column(w[0]),
                column(w[1]),
                column(w[2]),
                column(w[3]),
                column(w[4]),
                column(w[5])
            );
        }
        match &args.output {
            Some(path) => {
                atomic::write(path, text.as_bytes())
                    .map_err(|err| Failure::Usage(format!("cannot write `{}`: {err}", path.display())))?;
                verbosity.note(format_args!("wrote `{}` ({} samples)", path.display(), rows.len()));
                Ok(())
            }
            None => out::print(&text),
        }
    };
    match run() {
        Ok(()) => 0,
        Err(failure) => failure.report(),
    }
}

/// A force or moment column: `0` when there is none, else four decimals.
fn column(value: f64) -> String {
    if value == 0.0 {
        "0".to_string()
    } else {
        format!("{value:.4}")
    }
}

/// One row of a rollout.
struct Row {
    t_s: f64,
    position_m: nalgebra::Vector3<f64>,
    orientation: nalgebra::UnitQuaternion<f64>,
    /// The segment (0-based) the row belongs to.
    segment: usize,
    /// The wrench the environment exerts on the tool (the demonstration's columns), base frame.
    wrench: [f64; 6],
}

/// The preview's rows in segment order, a segment without a motion held at the last pose (the
/// first motion's start before any) for its demonstrated duration.
fn timeline(learned: &Learned, dt: f64, offset: nalgebra::Vector3<f64>) -> Vec<Row> {
    let (samples, names) = skill_runtime::skill::rollout::preview(learned, dt, offset);
    let segment_of = |motion: usize| {
        names
            .get(motion)
            .and_then(|name| learned.motions.get(name))
            .map_or(0, |m| m.segment)
    };
    let mut rows: Vec<Row> = Vec::with_capacity(samples.len());
    let mut shift = 0.0;
    let mut next = 0;
    for (segment, span) in learned.segments.iter().enumerate() {
        let start = next;
        while next < samples.len() && segment_of(samples[next].motion) == segment {
            next += 1;
        }
        if next > start {
            push_samples(&mut rows, &samples[start..next], shift, segment);
            continue;
        }
        let Some((t, position_m, orientation)) = rows
            .last()
            .map(|r| (r.t_s, r.position_m, r.orientation))
            .or_else(|| samples.first().map(|s| (s.t_s - dt, s.position_m, s.orientation)))
        else {
            continue;
        };
        let steps = ((span.end_s - span.start_s).max(0.0) / dt).ceil() as usize;
        for step in 1..=steps {
            rows.push(Row {
                t_s: t + step as f64 * dt,
                position_m,
                orientation,
                segment,
                wrench: [0.0; 6],
            });
        }
        shift += steps as f64 * dt;
    }
    // Motions of segments the file does not list (never written by `skillc learn`) follow.
    push_samples(&mut rows, &samples[next..], shift, usize::MAX);
    rows
}

/// Appends preview samples `shift` seconds later; a motion's first sample, at the time (and
/// the pose) the previous one ended, is left out so that time always increases, as in a
/// demonstration.
fn push_samples(rows: &mut Vec<Row>, samples: &[PreviewSample], shift: f64, segment: usize) {
    for sample in samples {
        let t_s = sample.t_s + shift;
        if rows.last().is_some_and(|last| t_s <= last.t_s) {
            continue;
        }
        rows.push(Row {
            t_s,
            position_m: sample.position_m,
            orientation: sample.orientation,
            segment,
            wrench: [0.0; 6],
        });
    }
}

/// Writes each learned force over a segment into its segment's rows (as the wrench on the tool,
/// the negative of the force the robot applies); returns the names of the forces with no
/// segment (a point, a literal, none).
fn place_forces(rows: &mut [Row], bound: &skill_runtime::exec::BoundSkill<'_>, dt: f64) -> Vec<String> {
    use skill_ir::{Axis, ForceSource, FrameRef};
    let mut unplaced = Vec::new();
    for (decl, force) in bound.declared_forces() {
        let (segment, along) = match &decl.source {
            ForceSource::Constant { segment, along } | ForceSource::Magnitude { segment, along, .. } => {
                (segment.index(), Some(along))
            }
            ForceSource::Dmp { segment, .. } => (segment.index(), None),
            _ => {
                unplaced.push(decl.name.clone());
                continue;
            }
        };
        let Some(first) = rows.iter().position(|r| r.segment == segment) else {
            continue;
        };
        let t0 = rows[first].t_s;
        let mut dmp = match force {
            LearnedForce::Dmp { dmp } | LearnedForce::Magnitude { dmp } => Some((dmp, dmp.rollout())),
            _ => None,
        };
        for (step, row) in rows[first..]
            .iter_mut()
            .take_while(|r| r.segment == segment)
            .enumerate()
        {
            let applied: Vec<f64> = match &mut dmp {
                Some((dmp, rollout)) => {
                    if step > 0 {
                        rollout.step(dmp, dt);
                    }
                    rollout.position().to_vec()
                }
                None => vec![force.value_n().unwrap_or(0.0)],
            };
            let (vector, moment) = match (along, applied.as_slice()) {
                (None, [x, y, z]) => (nalgebra::Vector3::new(*x, *y, *z), false),
                (Some(along), [value]) => {
                    let rotation = match along.frame {
                        FrameRef::Base => nalgebra::UnitQuaternion::identity(),
                        FrameRef::Tool => row.orientation,
                        FrameRef::Learned(id) => bound.frame(id).at(row.t_s - t0).rotation,
                    };
                    let (unit, moment) = match along.axis {
                        Axis::X => (nalgebra::Vector3::x(), false),
                        Axis::Y => (nalgebra::Vector3::y(), false),
                        Axis::Z => (nalgebra::Vector3::z(), false),
                        Axis::Rx => (nalgebra::Vector3::x(), true),
                        Axis::Ry => (nalgebra::Vector3::y(), true),
                        Axis::Rz => (nalgebra::Vector3::z(), true),
                    };
                    (rotation * unit * *value, moment)
                }
                _ => continue,
            };
            let columns = if moment { 3..6 } else { 0..3 };
            for (column, value) in columns.zip(vector.iter()) {
                row.wrench[column] -= value;
            }
        }
    }
    unplaced
}

/// What the geometric check did to a planar contact segment's boundaries (docs/method.md §3).
pub fn contact_line(contact: &skill_runtime::skill::ContactBoundaries) -> String {
    let moved = |label: &str, [before, after]: [f64; 2]| {
        if (after - before).abs() < 1e-9 {
            format!("{label} {after:.3} s kept")
        } else {
            format!("{label} {before:.3} → {after:.3} s ({:+.3} s)", after - before)
        }
    };
    let mut line = if contact.tolerance_m > 0.0 {
        format!(
            "segment {} on the plane of `{}` ({:.1} mm RMS from it, band {:.1} mm): {}, {}",
            contact.segment,
            contact.frame,
            contact.residual_m * 1e3,
            contact.tolerance_m * 1e3,
            moved("start", contact.start_s),
            moved("end", contact.end_s)
        )
    } else {
        format!(
            "segment {} boundaries not checked against `{}`",
            contact.segment, contact.frame
        )
    };
    if let Some(kept) = &contact.kept {
        line.push_str(&format!(" ({kept})"));
    }
    line
}

/// Parses `--phase N`: contact phases count from 1, and no demonstration holds more than
/// [`skill_kit::limits::SEGMENTS`] of them.
fn parse_phase(text: &str) -> Result<usize, String> {
    let max = skill_kit::limits::SEGMENTS;
    match text.trim().parse::<i64>() {
        Ok(phase) if (1..=i64::from(max)).contains(&phase) => Ok(phase as usize),
        Ok(_) => Err(format!("contact phases count from 1 to at most {max}")),
        Err(_) => Err("a contact phase is a whole number, 1 for the first".to_string()),
    }
}
