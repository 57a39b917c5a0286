//! The per-tick log of a run and its CSV export.

use crate::plant::Plant;

/// One control tick.
#[derive(Debug, Clone, PartialEq)]
pub struct Tick {
    /// Time since the run started \[s\].
    pub t_s: f64,
    /// Index into [`RunLog::states`].
    pub state: u32,
    /// Commanded tool position \[m\] and orientation `[w, x, y, z]`, base frame.
    pub desired: [f64; 7],
    /// Measured tool position \[m\] and orientation `[w, x, y, z]`, base frame.
    pub measured: [f64; 7],
    /// Applied wrench at the tool point, base frame `[f; m]` (N, N m).
    pub wrench_base: [f64; 6],
    /// The same wrench in the compliant frame's axes.
    pub wrench_cf: [f64; 6],
    /// Desired applied wrench in the compliant frame's axes (zero on position axes).
    pub desired_cf: [f64; 6],
    /// The compliant frame's orientation in the base frame `[w, x, y, z]` (its z axis is
    /// [`Tick::frame_z`]).
    pub frame: [f64; 4],
    /// Position-controlled axes as bits (bit i = axis i of `x y z rx ry rz`).
    pub selection: u8,
    /// Commanded joint torques after limits \[N m\].
    pub torques: JointValues<MAX_INLINE_DOF>,
    /// Joint positions \[rad\] then joint velocities \[rad/s\], as sensed this tick (2 × dof).
    pub joint_state: JointValues<{ 2 * MAX_INLINE_DOF }>,
}

impl Tick {
    /// The compliant frame's z axis, base frame.
    pub fn frame_z(&self) -> [f64; 3] {
        let [w, x, y, z] = self.frame;
        // The third column of the rotation matrix of the unit quaternion (w, x, y, z).
        [
            2.0 * (x * z + w * y),
            2.0 * (y * z - w * x),
            1.0 - 2.0 * (x * x + y * y),
        ]
    }

    /// The desired applied force in the base frame's axes \[N\] (zero on position axes):
    /// [`Tick::desired_cf`]'s force turned out of the compliant frame.
    pub fn desired_force_base(&self) -> [f64; 3] {
        let [w, x, y, z] = self.frame;
        let rotation = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z));
        let f = rotation * nalgebra::Vector3::new(self.desired_cf[0], self.desired_cf[1], self.desired_cf[2]);
        [f.x, f.y, f.z]
    }
}

/// Arms with up to this many joints log a tick without allocating (a longer arm's joint values
/// go to the heap).
pub const MAX_INLINE_DOF: usize = 8;

/// A tick's joint values: up to `N` stored inline (no allocation per tick), more on the heap.
/// Reads as a slice (`Deref<Target = [f64]>`).
#[derive(Clone)]
pub struct JointValues<const N: usize> {
    len: usize,
    inline: [f64; N],
    heap: Vec<f64>,
}

impl<const N: usize> JointValues<N> {
    /// The values of `parts` one after the other (inline if they fit).
    pub fn from_slices(parts: &[&[f64]]) -> Self {
        let len = parts.iter().map(|part| part.len()).sum();
        let mut out = JointValues {
            len,
            inline: [0.0; N],
            heap: Vec::new(),
        };
        if len <= N {
            let values = parts.iter().flat_map(|part| part.iter());
            for (slot, value) in out.inline.iter_mut().zip(values) {
                *slot = *value;
            }
        } else {
            out.heap = parts.concat();
        }
        out
    }

    /// The values as a slice.
    pub fn as_slice(&self) -> &[f64] {
        if self.len <= N {
            &self.inline[..self.len]
        } else {
            &self.heap
        }
    }
}

impl<const N: usize> std::ops::Deref for JointValues<N> {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        self.as_slice()
    }
}

impl<'a, const N: usize> IntoIterator for &'a JointValues<N> {
    type Item = &'a f64;
    type IntoIter = std::slice::Iter<'a, f64>;
    fn into_iter(self) -> Self::IntoIter {
        self.as_slice().iter()
    }
}

impl<const N: usize> PartialEq for JointValues<N> {
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

impl<const N: usize> std::fmt::Debug for JointValues<N> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.as_slice().fmt(f)
    }
}

/// A stretch of a log as its writers take it: the log's state and part names as they stand,
/// ticks in order, and the part samples of those ticks (their ticks count the whole log's,
/// their parts index `part_names`). A whole log is [`RunLog::batch`]; a tap's batches are
/// [`TapEvent::batch`].
#[derive(Debug, Clone, Copy)]
pub struct LogBatch<'a> {
    /// State names the ticks refer to.
    pub states: &'a [String],
    /// The ticks.
    pub ticks: &'a [Tick],
    /// The moving parts' names.
    pub part_names: &'a [String],
    /// Where the parts stood during these ticks.
    pub parts: &'a [PartSample],
}

/// Every tick of a run, with the names of the states ticks refer to, and where the scene's
/// moving parts went.
#[derive(Debug, Default)]
pub struct RunLog {
    /// State names (`prepose`, `replay:<motion>` and the skill's states).
    pub states: Vec<String>,
    /// The ticks in time order.
    pub ticks: Vec<Tick>,
    /// The scene's moving parts (a button's cap) by their object's name, as the plant named
    /// them ([`Plant::visit_parts`]).
    pub part_names: Vec<String>,
    /// Where the parts stood, in tick order: every [`PART_PERIOD_TICKS`] ticks, each part
    /// whose offset moved [`PART_MOVE_M`] or more since its last sample (and its first).
    pub parts: Vec<PartSample>,
    /// Each part's offset at its last sample.
    last_offsets: Vec<f64>,
    /// Where the ticks are also sent as they are logged.
    tap: Option<Tapped>,
}

/// Where one of the scene's moving parts stood at a tick of its log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartSample {
    /// The tick: an index into the log's [`RunLog::ticks`].
    pub tick: usize,
    /// The part: an index into [`RunLog::part_names`].
    pub part: u32,
    /// How far the part has moved from its rest along its own axis, m (a button's depth).
    pub offset_m: f64,
}

/// The scene's moving parts are sampled every this many ticks (10 ms at 1 kHz, the rate of a
/// run log's `/tf`).
pub const PART_PERIOD_TICKS: usize = 10;

/// A part's sample is logged when it has moved this far since its last one, m.
pub const PART_MOVE_M: f64 = 1e-5;

/// A log's place on a tap: the tap, the log's number on it and how many ticks and part
/// samples have been sent.
#[derive(Debug)]
struct Tapped {
    tap: LogTap,
    log: usize,
    sent: usize,
    sent_parts: usize,
}

/// A copy holds the states, ticks and parts, not the tap: only the log being recorded sends
/// them on.
impl Clone for RunLog {
    fn clone(&self) -> Self {
        RunLog {
            states: self.states.clone(),
            ticks: self.ticks.clone(),
            part_names: self.part_names.clone(),
            parts: self.parts.clone(),
            last_offsets: self.last_offsets.clone(),
            tap: None,
        }
    }
}

/// Two logs are equal when their states, ticks and parts are: a tap is where they went, not
/// what they hold.
impl PartialEq for RunLog {
    fn eq(&self, other: &Self) -> bool {
        self.states == other.states
            && self.ticks == other.ticks
            && self.part_names == other.part_names
            && self.parts == other.parts
    }
}

/// Ticks are sent on in batches of this many (about 0.4 MB at 1 ms a tick, a second apart).
const TAP_BATCH_TICKS: usize = 1024;

/// A channel to a log writer on another thread: the runs of [`crate::ExecOptions::tap`]
/// send their ticks on as they log them, in batches, so that a file is written while the arm
/// moves rather than after (`skillc run -o`). Each log started on the tap gets a number, in
/// the order the logs were started.
#[derive(Clone)]
pub struct LogTap {
    sender: std::sync::mpsc::Sender<TapEvent>,
    /// The number the next log started gets.
    next_log: std::sync::Arc<std::sync::atomic::AtomicUsize>,
}

impl std::fmt::Debug for LogTap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("LogTap")
    }
}

/// Options that tap the same channel are the same options.
impl PartialEq for LogTap {
    fn eq(&self, other: &Self) -> bool {
        std::sync::Arc::ptr_eq(&self.next_log, &other.next_log)
    }
}

/// What a [`LogTap`] carries, in the order it happened.
#[derive(Debug)]
pub enum TapEvent {
    /// A log started: its number, and the task step it is of, if any.
    Log {
        /// The log's number (0 for the first started on the tap, then 1, ...).
        log: usize,
        /// The task step.
        step: Option<String>,
    },
    /// Ticks of a log started before.
    Ticks {
        /// The log's number.
        log: usize,
        /// The log's state names as they stand (a later batch may have more).
        states: Vec<String>,
        /// The ticks logged since the log's previous batch.
        ticks: Vec<Tick>,
        /// The log's part names as they stand (a later batch may have more).
        part_names: Vec<String>,
        /// The part samples logged since the previous batch (their ticks index the whole
        /// log's ticks, not this batch's).
        parts: Vec<PartSample>,
    },
    /// Nothing more comes: sent by whoever made the tap once its runs are over.
    End,
}

impl TapEvent {
    /// The ticks this event carries, as a batch (`None` for the other events).
    pub fn batch(&self) -> Option<LogBatch<'_>> {
        match self {
            TapEvent::Ticks {
                states,
                ticks,
                part_names,
                parts,
                ..
            } => Some(LogBatch {
                states,
                ticks,
                part_names,
                parts,
            }),
            TapEvent::Log { .. } | TapEvent::End => None,
        }
    }
}

impl LogTap {
    /// A tap and the receiving end of its channel.
    pub fn channel() -> (LogTap, std::sync::mpsc::Receiver<TapEvent>) {
        let (sender, receiver) = std::sync::mpsc::channel();
        let tap = LogTap {
            sender,
            next_log: std::sync::Arc::default(),
        };
        (tap, receiver)
    }

    /// Tells the writer that nothing more comes.
    pub fn end(&self) {
        let _ = self.sender.send(TapEvent::End);
    }
}

impl RunLog {
    /// The whole log as one batch.
    pub fn batch(&self) -> LogBatch<'_> {
        LogBatch {
            states: &self.states,
            ticks: &self.ticks,
            part_names: &self.part_names,
            parts: &self.parts,
        }
    }

    /// An empty log whose ticks `tap` (if any) also receives, as a log of task step `step`.
    pub fn tapped(tap: Option<&LogTap>, step: Option<&str>) -> RunLog {
        let tap = tap.map(|tap| {
            let log = tap.next_log.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let _ = tap.sender.send(TapEvent::Log {
                log,
                step: step.map(str::to_owned),
            });
            Tapped {
                tap: tap.clone(),
                log,
                sent: 0,
                sent_parts: 0,
            }
        });
        RunLog {
            tap,
            ..RunLog::default()
        }
    }

    /// Logs `tick`, samples the plant's moving parts on every [`PART_PERIOD_TICKS`]-th tick,
    /// and sends a full batch on (every tick of a run is logged through here).
    pub(crate) fn record(&mut self, tick: Tick, plant: &dyn Plant) {
        self.ticks.push(tick);
        let index = self.ticks.len() - 1;
        if index.is_multiple_of(PART_PERIOD_TICKS) {
            let RunLog {
                part_names,
                parts,
                last_offsets,
                ..
            } = self;
            plant.visit_parts(&mut |name, offset_m| {
                let part = match part_names.iter().position(|known| known == name) {
                    Some(part) => part,
                    None => {
                        part_names.push(name.to_owned());
                        last_offsets.push(f64::NAN);
                        part_names.len() - 1
                    }
                };
                // A new part's last offset is NaN: its first sample is always logged.
                let last = last_offsets[part];
                if last.is_nan() || (offset_m - last).abs() >= PART_MOVE_M {
                    last_offsets[part] = offset_m;
                    parts.push(PartSample {
                        tick: index,
                        part: part as u32,
                        offset_m,
                    });
                }
            });
        }
        self.offer();
    }

    /// Sends the ticks not yet sent when a batch is full.
    pub(crate) fn offer(&mut self) {
        if let Some(tapped) = &self.tap {
            if self.ticks.len() - tapped.sent >= TAP_BATCH_TICKS {
                self.send_rest();
            }
        }
    }

    /// Sends the ticks not yet sent and lets go of the tap, and gives back memory reserved for
    /// ticks never logged: the log is complete.
    pub(crate) fn finish(&mut self) {
        self.send_rest();
        self.tap = None;
        self.ticks.shrink_to_fit();
    }

    fn send_rest(&mut self) {
        let Some(tapped) = &mut self.tap else { return };
        if tapped.sent == self.ticks.len() {
            return;
        }
        let batch = TapEvent::Ticks {
            log: tapped.log,
            states: self.states.clone(),
            ticks: self.ticks[tapped.sent..].to_vec(),
            part_names: self.part_names.clone(),
            parts: self.parts[tapped.sent_parts..].to_vec(),
        };
        tapped.sent = self.ticks.len();
        tapped.sent_parts = self.parts.len();
        // A writer that has gone away takes nothing more; the log itself keeps every tick.
        let _ = tapped.tap.sender.send(batch);
    }

    /// Reserves room for `ticks` more ticks, so that recording them does not allocate.
    pub fn reserve(&mut self, ticks: usize) {
        self.ticks.reserve(ticks);
    }

    /// The index of a state name, added if new.
    pub fn state_index(&mut self, name: &str) -> u32 {
        match self.states.iter().position(|s| s == name) {
            Some(index) => index as u32,
            None => {
                self.states.push(name.to_string());
                (self.states.len() - 1) as u32
            }
        }
    }

    /// The log as CSV, one row per tick.
    pub fn to_csv(&self) -> String {
        csv(&[(None, self)])
    }
}

/// Powers of ten a fixed-point column is scaled by.
const POW10: [f64; 10] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];

/// Two-digit pairs "00" to "99", for writing integers two digits at a time.
const PAIRS: &[u8; 200] = b"0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// Appends `value` with `precision` decimals, exactly as `format!("{value:.precision$}")` does,
/// in a fraction of its time (the log's 60 columns a tick cost 7 µs through `write!`).
///
/// The value is scaled by 10^precision and rounded to an integer whose digits are written
/// directly. The scaled product is exact to within an ulp, so the rounding agrees with the
/// formatter's exact decimal rounding except when the product lies within that ulp of a half:
/// those (about one value in 10^4), large values, and non-finite ones go through `write!`.
fn push_fixed(out: &mut Vec<u8>, value: f64, precision: usize) {
    let fallback = |out: &mut Vec<u8>| {
        let _ = std::io::Write::write_fmt(out, format_args!("{value:.precision$}"));
    };
    let Some(&scale) = POW10.get(precision) else {
        return fallback(out);
    };
    let scaled = value.abs() * scale;
    // Below 2^36 an ulp of `scaled` is at most 2^-16, far inside the guard band below.
    if scaled.is_nan() || scaled >= 68_719_476_736.0 {
        return fallback(out);
    }
    // Truncation is the floor of a non-negative value (no libm call).
    let whole = scaled as u64;
    let fraction = scaled - whole as f64;
    if (fraction - 0.5).abs() < 1e-4 {
        return fallback(out);
    }
    let mut rest = whole + u64::from(fraction > 0.5);
    // The formatter keeps the sign of a negative value that rounds to zero (`-0.0000`).
    if value.is_sign_negative() {
        out.push(b'-');
    }
    // Digits from the right: `precision` decimals, the point, at least one integer digit.
    let mut buffer = [0u8; 32];
    let mut at = buffer.len();
    let mut decimals = precision;
    while decimals >= 2 {
        let pair = (rest % 100) as usize * 2;
        rest /= 100;
        at -= 2;
        buffer[at..at + 2].copy_from_slice(&PAIRS[pair..pair + 2]);
        decimals -= 2;
    }
    if decimals == 1 {
        at -= 1;
        buffer[at] = b'0' + (rest % 10) as u8;
        rest /= 10;
    }
    if precision > 0 {
        at -= 1;
        buffer[at] = b'.';
    }
    // The integer part: pairs while three or more digits are left, then the last one or two.
    while rest >= 100 {
        let pair = (rest % 100) as usize * 2;
        rest /= 100;
        at -= 2;
        buffer[at..at + 2].copy_from_slice(&PAIRS[pair..pair + 2]);
    }
    if rest >= 10 {
        let pair = rest as usize * 2;
        at -= 2;
        buffer[at..at + 2].copy_from_slice(&PAIRS[pair..pair + 2]);
    } else {
        at -= 1;
        buffer[at] = b'0' + rest as u8;
    }
    out.extend_from_slice(&buffer[at..]);
}

/// Consecutive logs as one CSV (a task's steps on one robot): each row's state is written
/// `<step>/<state>` for a log given with a step name.
pub fn csv(logs: &[(Option<&str>, &RunLog)]) -> String {
    let mut out = CsvLog::default();
    for (step, log) in logs {
        out.start_log(step.map(str::to_owned));
        out.push(&log.states, &log.ticks);
    }
    out.finish()
}

/// A CSV log written as its ticks arrive (through a [`LogTap`]), or of whole logs ([`csv`]).
#[derive(Debug, Default)]
pub struct CsvLog {
    out: Vec<u8>,
    header: bool,
    /// The task step of the log being written.
    step: Option<String>,
}

impl CsvLog {
    /// The next ticks are the next log's, of task step `step` (its rows' states written
    /// `step/state`).
    pub fn start_log(&mut self, step: Option<String>) {
        self.step = step;
    }

    /// Appends the rows of `ticks`, the next ticks of the current log, whose state names are
    /// `states`.
    pub fn push(&mut self, states: &[String], ticks: &[Tick]) {
        let Some(first) = ticks.first() else { return };
        if !self.header {
            csv_header(&mut self.out, first.torques.len());
            self.header = true;
        }
        csv_rows(&mut self.out, self.step.as_deref(), states, ticks);
    }

    /// The whole text.
    pub fn finish(mut self) -> String {
        if !self.header {
            csv_header(&mut self.out, 0);
        }
        String::from_utf8(self.out).expect("the log is ASCII numbers and the skill's UTF-8 state and step names")
    }
}

/// Appends the CSV log's header line for an arm of `dof` joints.
fn csv_header(out: &mut Vec<u8>, dof: usize) {
    out.extend_from_slice(b"t,state,xd,yd,zd,qwd,qxd,qyd,qzd,x,y,z,qw,qx,qy,qz,fx,fy,fz,mx,my,mz,");
    out.extend_from_slice(b"cf_fx,cf_fy,cf_fz,cf_mx,cf_my,cf_mz,cf_fx_d,cf_fy_d,cf_fz_d,cf_mx_d,cf_my_d,cf_mz_d,");
    out.extend_from_slice(b"cf_zx,cf_zy,cf_zz,sel_x,sel_y,sel_z,sel_rx,sel_ry,sel_rz");
    for prefix in ["tau", "q", "qd"] {
        for joint in 1..=dof {
            out.extend_from_slice(format!(",{prefix}{joint}").as_bytes());
        }
    }
    out.push(b'\n');
}

/// Appends the CSV rows of `ticks`, ticks of a log with `states` (of task step `step`).
fn csv_rows(out: &mut Vec<u8>, step: Option<&str>, states: &[String], ticks: &[Tick]) {
    for tick in ticks {
        let state = states.get(tick.state as usize).map_or("?", String::as_str);
        push_fixed(out, tick.t_s, 4);
        out.push(b',');
        if let Some(step) = step {
            out.extend_from_slice(step.as_bytes());
            out.push(b'/');
        }
        out.extend_from_slice(state.as_bytes());
        let columns = [
            (&tick.desired[..], 6),
            (&tick.measured[..], 6),
            (&tick.wrench_base[..], 4),
            (&tick.wrench_cf[..], 4),
            (&tick.desired_cf[..], 4),
            (&tick.frame_z()[..], 5),
        ];
        for (values, precision) in columns {
            for value in values {
                out.push(b',');
                push_fixed(out, *value, precision);
            }
        }
        for bit in 0..6 {
            out.extend_from_slice(if tick.selection & (1 << bit) != 0 { b",P" } else { b",F" });
        }
        for value in &tick.torques {
            out.push(b',');
            push_fixed(out, *value, 4);
        }
        for value in &tick.joint_state {
            out.push(b',');
            push_fixed(out, *value, 6);
        }
        out.push(b'\n');
    }
}

#[cfg(test)]
mod tests {
    use super::{csv, push_fixed, CsvLog, JointValues, LogTap, RunLog, TapEvent, Tick, TAP_BATCH_TICKS};
    use nalgebra::{UnitQuaternion, Vector3};

    /// A tick of a 2-joint arm at `t_s` in state `state`, its numbers varying with `t_s`.
    fn tick_at(t_s: f64, state: u32) -> Tick {
        Tick {
            t_s,
            state,
            desired: [t_s, 0.1, 0.2, 1.0, 0.0, 0.0, 0.0],
            measured: [t_s * 0.9, 0.1, 0.2, 1.0, 0.0, 0.0, 0.0],
            wrench_base: [0.0, 0.0, -t_s, 0.0, 0.0, 0.0],
            wrench_cf: [0.0; 6],
            desired_cf: [0.0, 0.0, 5.0, 0.0, 0.0, 0.0],
            frame: [1.0, 0.0, 0.0, 0.0],
            selection: 0b11_1011,
            torques: JointValues::from_slices(&[&[t_s, -t_s]]),
            joint_state: JointValues::from_slices(&[&[0.5, t_s], &[0.0, 0.1]]),
        }
    }

    /// Logs `ticks` ticks into `log` the way the rig does (push, then offer), a second state
    /// added half way.
    fn log_ticks(log: &mut RunLog, ticks: usize, t0: f64) {
        let first = log.state_index("approach");
        for k in 0..ticks {
            let state = if k < ticks / 2 { first } else { log.state_index("press") };
            log.ticks.push(tick_at(t0 + k as f64 * 1e-3, state));
            log.offer();
        }
        log.finish();
    }

    #[test]
    fn a_tapped_log_sends_every_tick_once_in_order_with_its_step() {
        let (tap, events) = LogTap::channel();
        let mut skill = RunLog::tapped(Some(&tap), None);
        log_ticks(&mut skill, 2 * TAP_BATCH_TICKS + 17, 0.0);
        let mut step = RunLog::tapped(Some(&tap), Some("press"));
        log_ticks(&mut step, 10, 0.0);
        let untapped = RunLog::tapped(None, Some("ignored"));
        tap.end();
        drop(tap);
        assert!(untapped.tap.is_none() && skill.tap.is_none() && step.tap.is_none());
        let (other, _events) = LogTap::channel();
        let mut recording = RunLog::tapped(Some(&other), None);
        recording.ticks.push(tick_at(0.0, 0));
        assert!(recording.clone().tap.is_none(), "a copy sends nothing on");
        assert_eq!(recording.clone(), recording);

        let events: Vec<TapEvent> = events.iter().collect();
        let mut rebuilt = CsvLog::default();
        let mut batches = Vec::new();
        for event in &events {
            match event {
                TapEvent::Log { log, step } => {
                    assert_eq!(*log, batches.len(), "logs are numbered as they start");
                    batches.push(0);
                    rebuilt.start_log(step.clone());
                }
                TapEvent::Ticks { log, states, ticks, .. } => {
                    assert_eq!(*log + 1, batches.len(), "a log's ticks come after it started");
                    batches[*log] += 1;
                    rebuilt.push(states, ticks);
                }
                TapEvent::End => {}
            }
        }
        assert!(matches!(events.last(), Some(TapEvent::End)));
        assert_eq!(batches, [3, 1], "full batches, then the rest at the end");
        let whole = csv(&[(None, &skill), (Some("press"), &step)]);
        assert_eq!(rebuilt.finish(), whole);
        assert!(whole.contains(",press/approach,") && whole.contains(",press,"));
        assert_eq!(CsvLog::default().finish(), csv(&[]), "no ticks: the header alone");
    }

    /// The frame's z axis and the desired force in base axes equal what nalgebra's rotation of
    /// the stored quaternion gives, for frames turned every way.
    #[test]
    fn a_ticks_frame_turns_its_desired_force_into_the_base() {
        for (roll, pitch, yaw) in [(0.0, 0.0, 0.0), (0.3, -1.1, 2.0), (3.0, 0.5, -0.7), (-1.5, 1.5, 0.1)] {
            let rotation = UnitQuaternion::from_euler_angles(roll, pitch, yaw);
            let q = rotation.quaternion();
            let tick = Tick {
                t_s: 0.0,
                state: 0,
                desired: [0.0; 7],
                measured: [0.0; 7],
                wrench_base: [0.0; 6],
                wrench_cf: [0.0; 6],
                desired_cf: [1.0, -2.0, 10.0, 0.0, 0.0, 0.0],
                frame: [q.w, q.i, q.j, q.k],
                selection: 0,
                torques: JointValues::from_slices(&[]),
                joint_state: JointValues::from_slices(&[]),
            };
            let z = rotation * Vector3::z();
            let f = rotation * Vector3::new(1.0, -2.0, 10.0);
            for axis in 0..3 {
                assert!((tick.frame_z()[axis] - z[axis]).abs() < 1e-12, "{roll} {pitch} {yaw}");
                assert!((tick.desired_force_base()[axis] - f[axis]).abs() < 1e-12);
            }
        }
    }

    fn fixed(value: f64, precision: usize) -> String {
        let mut out = Vec::new();
        push_fixed(&mut out, value, precision);
        String::from_utf8(out).expect("ASCII")
    }

    #[test]
    fn fixed_point_columns_match_the_formatter_exactly() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut cases = vec![
            0.0,
            -0.0,
            -0.00001,
            0.00005,
            0.5,
            -0.5,
            1.5,
            2.5,
            0.125,
            0.0625,
            123_456.789,
            1e9,
            -7e10,
            1e300,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
        ];
        for _ in 0..400_000 {
            let bits = next();
            // Values like a log's (|v| up to a few hundred), and halves at every precision.
            let magnitude = 10f64.powi((bits % 9) as i32 - 5);
            let unit = (next() >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            cases.push(unit * 2.0 * magnitude * 300.0);
            let precision = (bits % 7) as i32;
            cases.push(((next() % 2_000_000) as f64 - 1e6 + 0.5) / 10f64.powi(precision));
        }
        for value in cases {
            for precision in [0, 3, 4, 5, 6] {
                assert_eq!(
                    fixed(value, precision),
                    format!("{value:.precision$}"),
                    "{value:e} at {precision}"
                );
            }
        }
    }
}
