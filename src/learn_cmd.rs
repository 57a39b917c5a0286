//! `skillc learn SKILL DEMO.csv -o OUT.learned.json` and `skillc rollout`: learning a template's
//! features from one demonstration, and previewing what was learned.

use std::fmt::Write as _;
use std::path::PathBuf;

use skill_runtime::exec::bind;
use skill_runtime::skill::{LearnOptions, Learned, LearnedForce, LearnedFrame};

use crate::atomic;
use crate::load::{learn_from_file, load_skill, read_learned, Failure};
use crate::plot::{self, Plot, Subject};

/// Arguments of `skillc learn`.
#[derive(Debug, Clone, clap::Args)]
pub struct LearnArgs {
    /// The `.skill` file.
    pub skill_file: PathBuf,
    /// The demonstration CSV (columns t, px, py, pz, qw, qx, qy, qz, fx, fy, fz, mx, my, mz).
    pub demo: PathBuf,
    /// Where to write the learned features (JSON, written atomically).
    #[arg(short, long)]
    pub output: PathBuf,
    /// The skill to learn, when the file defines several.
    #[arg(long)]
    pub skill: Option<String>,
    /// Low-pass cut-off \[Hz\], overriding the template's `lowpass`.
    #[arg(long, value_name = "HZ")]
    pub lowpass: Option<f64>,
    /// Resampling rate \[Hz\], overriding the template's `resample`.
    #[arg(long, value_name = "HZ")]
    pub resample: Option<f64>,
    /// The file's forces are the force the robot applies (not, as skillc expects, the force the
    /// environment exerts on the tool): negate them before learning.
    #[arg(long)]
    pub applied_force: bool,
    /// Also draw what was learned into this folder (SVG): the demonstration against the
    /// rollout with segments and frames, forces in the world and compliant frames.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
}

/// Runs `skillc learn`.
pub fn run(args: &LearnArgs) -> u8 {
    match learn(args) {
        Ok(summary) => {
            print!("{summary}");
            0
        }
        Err(failure) => failure.report(),
    }
}

fn learn(args: &LearnArgs) -> Result<String, Failure> {
    let (_, skill) = load_skill(&args.skill_file, args.skill.as_deref())?;
    let options = LearnOptions {
        lowpass_hz: args.lowpass,
        resample_hz: args.resample,
    };
    let learned = learn_from_file(&skill, &args.demo, &options, args.applied_force)?;
    let json = serde_json::to_string_pretty(&learned).map_err(|err| Failure::Usage(err.to_string()))? + "\n";
    atomic::write(&args.output, json.as_bytes())
        .map_err(|err| Failure::Usage(format!("cannot write `{}`: {err}", args.output.display())))?;
    let mut out = summary(&learned);
    let _ = writeln!(out, "wrote `{}`", args.output.display());
    if let Some(dir) = &args.plot {
        std::fs::create_dir_all(dir)
            .map_err(|err| Failure::Usage(format!("cannot create `{}`: {err}", dir.display())))?;
        let bound = bind(&skill, &learned).map_err(|err| Failure::Input(err.to_string()))?;
        let subject = Subject {
            name: &learned.skill,
            demo: &args.demo,
            bound: Some(&bound),
        };
        for kind in [Plot::Trajectory, Plot::LearnedForce] {
            let path = dir.join(format!("{}_{}.svg", learned.skill, kind.name()));
            plot::draw(kind, &path, &subject, &[])
                .map_err(|err| Failure::Usage(format!("cannot plot `{}`: {err}", kind.name())))?;
            let _ = writeln!(out, "wrote `{}`", path.display());
        }
    }
    Ok(out)
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
    for warning in &learned.demo.warnings {
        let _ = writeln!(out, "  warning: {warning}");
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

/// Arguments of `skillc rollout`.
#[derive(Debug, Clone, clap::Args)]
pub struct RolloutArgs {
    /// The learned file.
    pub learned: PathBuf,
    /// Write the rollout here (CSV in the demonstration's columns) instead of standard output.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Move every motion goal by DX,DY,DZ metres (base frame).
    #[arg(long, value_name = "DX,DY,DZ", value_delimiter = ',', allow_hyphen_values = true)]
    pub goal_offset: Option<Vec<f64>>,
    /// Sample period \[s\].
    #[arg(long, default_value_t = 0.001)]
    pub dt: f64,
}

/// Runs `skillc rollout`: the kinematic rollout of every learned motion in segment order.
pub fn rollout(args: &RolloutArgs) -> u8 {
    let run = || -> Result<(), Failure> {
        if !(args.dt > 0.0 && args.dt.is_finite()) {
            return Err(Failure::Usage("--dt must be a positive number of seconds".into()));
        }
        let learned = read_learned(&args.learned)?;
        let offset = match args.goal_offset.as_deref() {
            Some([dx, dy, dz]) => nalgebra::Vector3::new(*dx, *dy, *dz),
            Some(_) => return Err(Failure::Usage("--goal-offset takes three numbers: DX,DY,DZ".into())),
            None => nalgebra::Vector3::zeros(),
        };
        let (samples, _) = skill_runtime::skill::rollout::preview(&learned, args.dt, offset);
        let mut text = String::from("t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,mx,my,mz\n");
        for sample in &samples {
            let q = sample.orientation.quaternion();
            let p = sample.position_m;
            let _ = writeln!(
                text,
                "{:.4},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},0,0,0,0,0,0",
                sample.t_s, p.x, p.y, p.z, q.w, q.i, q.j, q.k
            );
        }
        match &args.output {
            Some(path) => {
                atomic::write(path, text.as_bytes())
                    .map_err(|err| Failure::Usage(format!("cannot write `{}`: {err}", path.display())))?;
                eprintln!("wrote `{}` ({} samples)", path.display(), samples.len());
            }
            None => print!("{text}"),
        }
        Ok(())
    };
    match run() {
        Ok(()) => 0,
        Err(failure) => failure.report(),
    }
}
