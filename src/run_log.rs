//! Writing a run's log (`skillc run -o`): CSV or MCAP as the file's name says, encoded on a
//! thread of its own while the run goes on, or after it.
//!
//! A run steps the arm on one core; its log, encoded after the run, cost 2.7 µs a tick on top
//! as CSV and 8.0 µs as MCAP (the slide on the 2-core machine this was built on). Live, the
//! run's [`LogTap`] hands the ticks over in batches as they are logged and a writer thread
//! encodes them on the other core, so that the file is ready soon after the last tick (0.9 and
//! 1.6 µs a tick on top, most of it the file's write at the end: benches/README.md). The bytes are the same either way (both
//! go through [`CsvLog`] and [`skill_ros::bag::RunLogWriter`]), and the file is written
//! atomically at the end: a run that fails to start writes nothing.

use std::path::Path;
use std::sync::mpsc::Receiver;
use std::thread::JoinHandle;

use skill_runtime::exec::{CsvLog, LogBatch, LogTap, RunLog, TapEvent};
use skill_runtime::sim::Scene;

use skill_kit::atomic;
use skill_kit::load::{error_chain, Failure};

/// A log being encoded while its run goes on.
pub struct LiveLog {
    tap: LogTap,
    writer: JoinHandle<Result<Vec<u8>, String>>,
}

impl LiveLog {
    /// Starts encoding the log of a run in `scene` for `path` on a thread of its own; the runs
    /// send it their ticks through [`LiveLog::tap`].
    pub fn start(path: &Path, scene: &Scene) -> Result<LiveLog, Failure> {
        let (tap, events) = LogTap::channel();
        let encoder = Encoder::for_path(path, scene)?;
        let writer = std::thread::Builder::new()
            .name("run log".into())
            .spawn(move || encode(encoder, &events))
            .map_err(|err| Failure::Usage(format!("cannot start the log writer: {err}")))?;
        Ok(LiveLog { tap, writer })
    }

    /// The tap for the runs' [`skill_runtime::exec::ExecOptions::tap`].
    pub fn tap(&self) -> LogTap {
        self.tap.clone()
    }

    /// Waits for the writer to encode what the runs sent, and writes the file atomically.
    pub fn finish(self, path: &Path) -> Result<(), Failure> {
        self.tap.end();
        let encoded = self
            .writer
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        let bytes = encoded.map_err(|err| Failure::Usage(format!("cannot write `{}`: {err}", path.display())))?;
        write_file(path, &bytes)
    }
}

/// Encodes the events of a tap until its end (or until every sender has gone).
fn encode(mut encoder: Encoder, events: &Receiver<TapEvent>) -> Result<Vec<u8>, String> {
    let mut failed = None;
    while let Ok(event) = events.recv() {
        match event {
            TapEvent::Log { step, .. } => encoder.start_log(step),
            // After an error the rest is drained unencoded; the first error is the one told.
            TapEvent::Ticks { .. } if failed.is_some() => {}
            ticks @ TapEvent::Ticks { .. } => failed = ticks.batch().and_then(|batch| encoder.push(batch).err()),
            TapEvent::End => break,
        }
    }
    match failed {
        Some(err) => Err(err),
        None => encoder.finish(),
    }
}

/// Writes the logs of a run that is over to `path` (atomically), as [`LiveLog`] would have.
pub fn write_after(path: &Path, logs: &[(Option<&str>, &RunLog)], scene: &Scene) -> Result<(), Failure> {
    let mut encoder = Encoder::for_path(path, scene)?;
    let wrap = |err: String| Failure::Usage(format!("cannot write `{}`: {err}", path.display()));
    for (step, log) in logs {
        encoder.start_log(step.map(str::to_owned));
        encoder.push(log.batch()).map_err(wrap)?;
    }
    let bytes = encoder.finish().map_err(wrap)?;
    write_file(path, &bytes)
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), Failure> {
    atomic::write(path, bytes).map_err(|err| Failure::Usage(format!("cannot write `{}`: {err}", path.display())))
}

/// What a log is encoded as.
enum Encoder {
    Csv(CsvLog),
    #[cfg(feature = "mcap")]
    Mcap(Box<McapEncoder>),
}

impl Encoder {
    /// MCAP when `path` ends in `.mcap`, else CSV.
    fn for_path(path: &Path, scene: &Scene) -> Result<Encoder, Failure> {
        if !skill_ros::bag::is_mcap(path) {
            return Ok(Encoder::Csv(CsvLog::default()));
        }
        #[cfg(feature = "mcap")]
        return Ok(Encoder::Mcap(Box::new(McapEncoder::new(scene))));
        #[cfg(not(feature = "mcap"))]
        {
            let _ = scene;
            Err(Failure::Usage(format!(
                "cannot write `{}`: this skillc was built without the `mcap` feature",
                path.display()
            )))
        }
    }

    fn start_log(&mut self, step: Option<String>) {
        match self {
            Encoder::Csv(csv) => csv.start_log(step),
            #[cfg(feature = "mcap")]
            Encoder::Mcap(mcap) => mcap.start_log(step),
        }
    }

    /// The next ticks of the current log, and its part samples of those ticks (a CSV log has
    /// no columns for them).
    fn push(&mut self, batch: LogBatch<'_>) -> Result<(), String> {
        match self {
            Encoder::Csv(csv) => {
                csv.push(batch.states, batch.ticks);
                Ok(())
            }
            #[cfg(feature = "mcap")]
            Encoder::Mcap(mcap) => mcap.push(batch),
        }
    }

    fn finish(self) -> Result<Vec<u8>, String> {
        match self {
            Encoder::Csv(csv) => Ok(csv.finish().into_bytes()),
            #[cfg(feature = "mcap")]
            Encoder::Mcap(mcap) => mcap.finish(),
        }
    }
}

/// An MCAP log's writer, with the scene's robot (its joint names, `/tf` and
/// `/robot_description`) when the scene's URDF reads, and the scene's objects.
#[cfg(feature = "mcap")]
struct McapEncoder {
    writer: skill_ros::bag::RunLogWriter,
}

#[cfg(feature = "mcap")]
impl McapEncoder {
    fn new(scene: &Scene) -> McapEncoder {
        // The names, the transforms and the description are for viewers: without the robot the
        // joints are called joint_1... and the bag has no /tf.
        let urdf = std::fs::read_to_string(scene.urdf_path()).ok();
        let robot = urdf
            .as_deref()
            .and_then(|text| skill_runtime::robot::Robot::from_urdf_str(text, scene.spec().robot.tool.as_deref()).ok());
        let names: Vec<String> = robot
            .as_ref()
            .map(|robot| robot.joints().iter().map(|joint| joint.name.clone()).collect())
            .unwrap_or_default();
        let description = match (&robot, &urdf) {
            (Some(robot), Some(urdf)) => Some(skill_ros::bag::RobotDescription { robot, urdf }),
            _ => None,
        };
        McapEncoder {
            writer: skill_ros::bag::RunLogWriter::new(&names, description.as_ref(), &scene.spec().objects),
        }
    }

    fn start_log(&mut self, step: Option<String>) {
        self.writer.start_log(step);
    }

    fn push(&mut self, batch: LogBatch<'_>) -> Result<(), String> {
        self.writer.push(batch).map_err(|err| error_chain(&err))
    }

    fn finish(self) -> Result<Vec<u8>, String> {
        self.writer.finish().map_err(|err| error_chain(&err))
    }
}
