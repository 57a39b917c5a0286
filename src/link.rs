//! `skillc plant` and `skillc run --plant`: the simulated arm served in one process and the skill
//! engine with its controller in another, over Zenoh ([`skill_transport`]). Without the `zenoh`
//! feature both say how to get it.

use std::fmt::Write as _;
use std::path::PathBuf;

use skill_kit::load::{error_chain, load_scene, Failure};
use skill_kit::out::Verbosity;
use skill_runtime::sim::Scene;

/// Arguments of `skillc plant`.
#[derive(Debug, Clone, clap::Args)]
pub struct PlantArgs {
    /// The scene to simulate.
    #[arg(long)]
    pub scene: PathBuf,
    /// Change a scene value, as `skillc run --set` does (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Serve this shipped robot (`lwr4`, `iiwa14`) instead of the scene's, its tool starting where
    /// the scene's robot starts its tool; give the run the same `--robot`.
    #[arg(long, value_name = "NAME")]
    pub robot: Option<String>,
    /// Where to accept runs and ROS 2 peers: `tcp/HOST:PORT` (`tcp/0.0.0.0:7447` for every interface).
    #[arg(long, value_name = "tcp/HOST:PORT", value_parser = endpoint_arg)]
    pub listen: String,
    /// The ROS domain (0-232), as `ROS_DOMAIN_ID` sets it for ROS 2 tools.
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=232), allow_negative_numbers = true)]
    pub domain: u32,
    /// Stay at normal priority instead of taking SCHED_FIFO, e.g. on a machine shared with work
    /// that must not wait behind the plant; realtime runs then get more late commands (lockstep
    /// runs are the same either way).
    #[arg(long)]
    pub no_fifo: bool,
}

/// How `skillc run` reaches a plant in another process.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct LinkArgs {
    /// Run against the plant `skillc plant` serves at `tcp/HOST:PORT` instead of simulating
    /// here; the scene still gives the robot model and the wrist sensor's mount.
    #[arg(long, value_name = "tcp/HOST:PORT", value_parser = endpoint_arg)]
    pub plant: Option<String>,
    /// The ROS domain of --plant (0-232).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=232), allow_negative_numbers = true, requires = "plant")]
    pub domain: u32,
    /// With --plant: the plant steps once per command, so the run computes exactly what it
    /// computes in one process (the default).
    #[arg(long, requires = "plant", conflicts_with = "realtime")]
    pub lockstep: bool,
    /// With --plant: the plant ticks on its own 1 ms clock and holds the last command when one is
    /// late; the run prints the loop's timing.
    #[arg(long, requires = "plant")]
    pub realtime: bool,
}

/// An endpoint as `--listen` and `--plant` take it: read by Zenoh's own parser and held to
/// `tcp/HOST:PORT` ([`skill_transport::node::parse_endpoint`]), written back as Zenoh writes it;
/// a bad one is a usage error that names the flag (exit 2).
fn endpoint_arg(text: &str) -> Result<String, String> {
    #[cfg(feature = "zenoh")]
    return skill_transport::node::parse_endpoint(text)
        .map(|endpoint| endpoint.to_string())
        .map_err(|err| err.to_string());
    // Without Zenoh the command says how to get it.
    #[cfg(not(feature = "zenoh"))]
    Ok(text.to_owned())
}

/// The scene at `path` with `sets`, and the shipped `robot` swapped in when one is named.
pub fn scene_with_robot(path: &std::path::Path, sets: &[String], robot: Option<&str>) -> Result<Scene, Failure> {
    let Some(name) = robot else {
        return load_scene(path, sets);
    };
    let swap = skill_eval::robot::Swap::new(name, &skill_kit::defaults::root().map_err(Failure::Usage)?)?;
    let mut all = sets.to_vec();
    all.extend(swap.sets(path, sets).map_err(Failure::Input)?);
    load_scene(path, &all)
}

#[cfg(feature = "zenoh")]
mod enabled {
    use std::time::Duration;

    use skill_runtime::exec::SessionError;
    use skill_runtime::plant::Plant;
    use skill_runtime::robot::Robot;
    use skill_runtime::sim::RapierPlant;
    use skill_transport::node::{self, Role};
    use skill_transport::{LinkMode, RemoteOptions, RemotePlant, ServeOptions};

    use super::*;

    /// How long a run looks for its plant.
    const CONNECT_TIMEOUT: Duration = Duration::from_secs(10);
    /// In lockstep, how long a step waits for the plant (a slow machine's debug build included).
    const LOCKSTEP_SILENCE: Duration = Duration::from_secs(5);
    /// In realtime, how long without a state before the run fails (50 control periods).
    const REALTIME_SILENCE: Duration = Duration::from_millis(50);
    /// In realtime, how long the plant waits for a command before its damped stop.
    const PLANT_SILENCE: Duration = Duration::from_millis(20);

    /// Where the plant tells who it refused and what it faulted on: standard error, at once.
    fn notice(words: &str) {
        eprintln!("{words}");
    }

    pub(super) fn serve(args: &PlantArgs, verbosity: Verbosity) -> Result<String, Failure> {
        // Parsed by clap already; what Zenoh is given and what the banner names is Zenoh's own
        // reading of it.
        let endpoint = node::parse_endpoint(&args.listen).map_err(|err| Failure::Usage(err.to_string()))?;
        let scene = scene_with_robot(&args.scene, &args.sets, args.robot.as_deref())?;
        let mut plant = RapierPlant::from_scene(&scene).map_err(|err| Failure::Input(error_chain(&err)))?;
        let robot = plant.robot().clone();
        let stop = skill_kit::atomic::stop_on_signal();
        // Before the session: Zenoh's threads, which carry the loop's messages, inherit it.
        let scheduling = if args.no_fifo {
            "normal (--no-fifo)".to_owned()
        } else {
            node::scheduling_words(&node::realtime_scheduling())
        };
        let session = node::open(endpoint.as_str(), Role::Listen).map_err(|err| Failure::Usage(err.to_string()))?;
        let options = ServeOptions {
            domain: args.domain,
            period_s: 1e-3,
            silence: PLANT_SILENCE,
            node_name: "skillc_plant".into(),
            sensor_frame: scene.spec().robot.sensor.clone(),
            notice,
        };
        if !verbosity.quiet() {
            // A closed standard output does not stop the plant: it serves on and says nothing.
            let _ = skill_kit::out::print_or_code(&format!(
                "plant: serving `{}` ({}, {} joints) at {} on ROS domain {}: /joint_states, /wrench and \
                 /skillc/state out, /joint_effort_commands in; Ctrl-C stops\n  scheduling: {scheduling}\n",
                scene.file(),
                robot.name(),
                robot.dof(),
                endpoint,
                args.domain
            ));
        }
        let summary = skill_transport::serve(&session, &mut plant, &robot, &options, stop)
            .map_err(|err| Failure::Input(error_chain(&err)))?;
        node::close(&session);
        let mut text = String::new();
        let _ = writeln!(
            text,
            "plant: stopped after {} ticks ({:.3} s simulated): {} session(s), {} command(s) applied, {} late, {} \
             dropped, {} unreadable, {} damped stop(s), {} fault(s), {} foreign command(s) and {} session(s) refused",
            summary.ticks,
            plant.time(),
            summary.sessions,
            summary.commands,
            summary.late,
            summary.dropped,
            summary.malformed,
            summary.damped_stops,
            summary.faults,
            summary.foreign_commands,
            summary.refused_starts
        );
        // What the runs took from the witness, and the steps since the last one asked.
        let mut contact = summary.contact;
        if let Some(rest) = plant.take_contact_audit() {
            contact.get_or_insert_with(Default::default).merge(rest);
        }
        if let Some(audit) = contact {
            let _ = writeln!(text, "  {}", audit.summary());
        }
        Ok(text)
    }

    /// Connects to the plant `link` names and runs `run` on it with the scene's robot model (the
    /// one the plant must match); the loop's line in realtime.
    pub fn run_remote<T>(
        scene: &Scene,
        link: &LinkArgs,
        endpoint: &str,
        run: impl FnOnce(Robot, &mut dyn Plant) -> Result<T, SessionError>,
    ) -> Result<(T, Option<String>), Failure> {
        let endpoint = node::parse_endpoint(endpoint).map_err(|err| Failure::Usage(err.to_string()))?;
        let robot = skill_runtime::exec::scene_robot(scene).map_err(|err| Failure::Input(error_chain(&err)))?;
        let mode = if link.realtime {
            LinkMode::Realtime
        } else {
            LinkMode::Lockstep
        };
        let options = RemoteOptions {
            endpoint: endpoint.to_string(),
            domain: link.domain,
            mode,
            connect_timeout: CONNECT_TIMEOUT,
            silence: match mode {
                LinkMode::Lockstep => LOCKSTEP_SILENCE,
                LinkMode::Realtime => REALTIME_SILENCE,
            },
        };
        // In realtime, before the session, so that Zenoh's threads inherit it; lockstep polls
        // for every state and needs no priority over the machine's other work.
        let scheduling = (mode == LinkMode::Realtime).then(|| node::scheduling_words(&node::realtime_scheduling()));
        let mut plant = RemotePlant::connect(options, robot.dof()).map_err(|err| Failure::Input(error_chain(&err)))?;
        let result = run(robot, &mut plant);
        // States from another publisher than the plant's were ignored: said whatever the verdict.
        let foreign = plant.stats().foreign_line();
        if let (Err(_), Some(foreign)) = (&result, &foreign) {
            eprintln!("{foreign}");
        }
        let result = result.map_err(|err| Failure::Input(error_chain(&err)))?;
        let mut lines: Vec<String> = Vec::new();
        if let Some(scheduling) = scheduling {
            lines.push(format!("{}\n  scheduling: {scheduling}", plant.stats().line()));
        }
        lines.extend(foreign);
        Ok((result, (!lines.is_empty()).then(|| lines.join("\n  "))))
    }
}

#[cfg(feature = "zenoh")]
pub use enabled::run_remote;

/// Runs `skillc plant`.
pub fn plant(args: &PlantArgs, verbosity: Verbosity) -> u8 {
    #[cfg(feature = "zenoh")]
    let result = enabled::serve(args, verbosity);
    #[cfg(not(feature = "zenoh"))]
    let result: Result<String, Failure> = {
        let _ = (args, verbosity);
        Err(without_zenoh())
    };
    match result {
        Ok(text) => match skill_kit::out::print_or_code(&text) {
            Ok(()) => 0,
            Err(code) => code,
        },
        Err(failure) => failure.report(),
    }
}

/// The error of `plant` and `--plant` in a build without the `zenoh` feature.
#[cfg(not(feature = "zenoh"))]
pub fn without_zenoh() -> Failure {
    Failure::Usage("this skillc was built without the `zenoh` feature: build it with `cargo build --release` (the feature is on by default)".into())
}
