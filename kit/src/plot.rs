//! SVG plots of a skill and its trials, after the thesis's Fig. 5.9, 5.11, 5.14 and 5.17: tool
//! paths in two projections with the compliant frames, force along the compliant z, world-frame
//! forces, a state timeline per trial, and what was learned of the force. A leaf: `skillc learn`,
//! `skillc run` and `skillc eval` hand it a [`Subject`] and its [`Trial`]s.

use std::path::Path;

use nalgebra::{Isometry3, Vector3};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use skill_runtime::exec::{BoundSkill, RunLog};
use skill_runtime::robot::{Robot, LWR4_FLANGE, LWR4_TOOL, LWR4_URDF};
use skill_runtime::skill::Learned;

use crate::profile::DesiredProfile;

/// A kind of plot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plot {
    /// Tool paths in two projections: the demonstration by segment, the learned rollout, every
    /// trial, the learned frames' z axes.
    Trajectory,
    /// Applied force along the compliant z during each trial, with the desired force.
    Force,
    /// Applied force in the world frame: the demonstration and the first skill trial.
    WorldForce,
    /// The states over time, one row per trial.
    Timeline,
    /// The demonstration's force along each learned frame's z, with the learned forces.
    LearnedForce,
}

impl Plot {
    /// The plot's name in file names and messages (`trajectory`, `world_force`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Plot::Trajectory => "trajectory",
            Plot::Force => "force",
            Plot::WorldForce => "world_force",
            Plot::Timeline => "timeline",
            Plot::LearnedForce => "learned_force",
        }
    }
}

/// The skill a plot is about.
#[derive(Debug, Clone, Copy)]
pub struct Subject<'a> {
    /// The skill's name.
    pub name: &'a str,
    /// The demonstration it was learned from.
    pub demo: &'a Path,
    /// The skill bound to what was learned, if learning worked.
    pub bound: Option<&'a BoundSkill<'a>>,
}

impl<'a> Subject<'a> {
    fn learned(&self) -> Option<&'a Learned> {
        self.bound.map(|bound| bound.learned)
    }
}

/// One trial drawn.
#[derive(Debug, Clone, Copy)]
pub struct Trial<'a> {
    /// The scene variant's name.
    pub variant: &'a str,
    /// The replay baseline rather than the skill.
    pub replay: bool,
    /// The trial could not run (its log is empty).
    pub error: bool,
    /// Its ticks.
    pub log: &'a RunLog,
}

impl Trial<'_> {
    fn mode(&self) -> &'static str {
        if self.replay {
            "replay"
        } else {
            "skill"
        }
    }
}

const SEGMENT_COLOURS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

/// The colour slot of a variant: its position among the variants seen so far (added if new).
fn colour_index(seen: &mut Vec<String>, variant: &str) -> usize {
    match seen.iter().position(|v| v == variant) {
        Some(index) => index,
        None => {
            seen.push(variant.to_string());
            seen.len() - 1
        }
    }
}

fn trial_colour(index: usize) -> RGBColor {
    const COLOURS: [RGBColor; 6] = [
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(23, 190, 207),
        RGBColor(188, 189, 34),
    ];
    COLOURS[index % COLOURS.len()]
}

/// The flange-to-tool transform of the bundled LWR-IV with its probe.
fn flange_to_tool() -> Isometry3<f64> {
    match Robot::from_urdf_str(LWR4_URDF, Some(LWR4_TOOL)) {
        Ok(robot) => {
            let mut data = robot.data();
            robot.forward_kinematics(&mut data, &skill_runtime::demogen::SCENE_Q0);
            match robot.link_index(LWR4_FLANGE) {
                Some(flange) => robot.link_in_base(&data, flange).inverse() * robot.tool_in_base(&data),
                None => Isometry3::identity(),
            }
        }
        Err(_) => Isometry3::identity(),
    }
}

/// Draws one kind of plot for a skill into `path` (SVG). [`Plot::LearnedForce`] draws the
/// demonstration and what was learned only; the others also draw `runs`.
pub fn draw(kind: Plot, path: &Path, skill: &Subject<'_>, runs: &[Trial<'_>]) -> Result<(), String> {
    let svg = render(kind, skill, runs)?;
    write_svg(path, &svg)
}

/// The plot `kind` as SVG text, drawn in memory: nothing reaches a file until it is whole.
pub fn render(kind: Plot, skill: &Subject<'_>, runs: &[Trial<'_>]) -> Result<String, String> {
    let mut svg = String::new();
    match kind {
        Plot::Trajectory => trajectory(&mut svg, skill, runs),
        Plot::Force => force(&mut svg, skill, runs),
        Plot::WorldForce => world_force(&mut svg, skill, runs),
        Plot::Timeline => timeline(&mut svg, runs),
        Plot::LearnedForce => learned_force(&mut svg, skill),
    }
    .map_err(|err| err.to_string())?;
    Ok(svg)
}

/// Writes a drawn plot all or nothing ([`crate::atomic::write`]): a full disk leaves no
/// cut-short SVG behind.
pub fn write_svg(path: &Path, svg: &str) -> Result<(), String> {
    crate::atomic::write(path, svg.as_bytes()).map_err(|err| format!("cannot write `{}`: {err}", path.display()))
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// Every chart here: time or metres against newtons or metres, drawn as SVG.
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The legend box, alike on every chart.
fn draw_legend<'a, 'b: 'a>(chart: &mut Chart<'a, 'b>) -> DrawResult {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 11))
        .draw()?;
    Ok(())
}

/// The demonstration a plot draws, read as `skillc learn` reads it.
fn read_demo(path: &Path) -> Result<skill_runtime::demo::Demo, String> {
    let bag = skill_ros::bag::BagOptions::default();
    crate::load::read_demo(path, &Default::default(), &bag)
        .map(|(loaded, _, _)| loaded.demo)
        .map_err(|failure| match failure {
            crate::load::Failure::Input(message) | crate::load::Failure::Usage(message) => message,
            crate::load::Failure::Closed => String::new(),
        })
}

/// Ticks after pre-positioning, every `stride`.
fn ticks(log: &RunLog, stride: usize) -> impl Iterator<Item = &skill_runtime::exec::Tick> {
    let prepose = log.states.iter().position(|s| s == "prepose").map(|i| i as u32);
    log.ticks
        .iter()
        .filter(move |t| Some(t.state) != prepose)
        .step_by(stride.max(1))
}

fn start_time(log: &RunLog) -> f64 {
    ticks(log, 1).next().map_or(0.0, |t| t.t_s)
}

fn bounds(points: impl Iterator<Item = (f64, f64)>) -> ((f64, f64), (f64, f64)) {
    let mut x = (f64::INFINITY, f64::NEG_INFINITY);
    let mut y = (f64::INFINITY, f64::NEG_INFINITY);
    for (px, py) in points {
        if px.is_finite() && py.is_finite() {
            x = (x.0.min(px), x.1.max(px));
            y = (y.0.min(py), y.1.max(py));
        }
    }
    if !x.0.is_finite() {
        return ((0.0, 1.0), (0.0, 1.0));
    }
    let pad = |(lo, hi): (f64, f64)| {
        let margin = ((hi - lo) * 0.08).max(0.005);
        (lo - margin, hi + margin)
    };
    (pad(x), pad(y))
}

fn trajectory(svg: &mut String, skill: &Subject<'_>, runs: &[Trial<'_>]) -> DrawResult {
    let offset = flange_to_tool();
    let demo = read_demo(skill.demo)?;
    let tool_of = |p: &Vector3<f64>, q: &nalgebra::UnitQuaternion<f64>| p + q * offset.translation.vector;
    let demo_tool: Vec<Vector3<f64>> = demo
        .position_m
        .iter()
        .zip(&demo.orientation)
        .map(|(p, q)| tool_of(p, q))
        .collect();
    let segment_of = |k: usize| {
        skill.learned().map_or(0, |l| {
            l.segments
                .iter()
                .position(|s| k >= s.start_index && k < s.end_index)
                .unwrap_or(0)
        })
    };
    let preview: Vec<Vector3<f64>> = skill
        .learned()
        .map(|l| skill_runtime::skill::rollout::preview(l, 0.01, Vector3::zeros()).0)
        .unwrap_or_default()
        .iter()
        .map(|s| tool_of(&s.position_m, &s.orientation))
        .collect();
    let run_paths: Vec<(String, bool, Vec<Vector3<f64>>)> = runs
        .iter()
        .map(|o| {
            let points = ticks(o.log, 20)
                .map(|t| Vector3::new(t.measured[0], t.measured[1], t.measured[2]))
                .collect();
            (o.variant.to_string(), o.replay, points)
        })
        .collect();
    let frames: Vec<(Vector3<f64>, Vector3<f64>)> = skill
        .learned()
        .map(|l| {
            let mut arrows = Vec::new();
            for frame in l.frames.values() {
                match frame {
                    skill_runtime::skill::LearnedFrame::Constant(pose) => {
                        let iso = pose.isometry();
                        arrows.push((
                            iso.translation.vector + demo.orientation[0] * offset.translation.vector,
                            iso.rotation * Vector3::z(),
                        ));
                    }
                    skill_runtime::skill::LearnedFrame::Samples(poses) => {
                        for pose in poses.iter().step_by(25) {
                            let iso = pose.isometry();
                            arrows.push((
                                iso.translation.vector + demo.orientation[0] * offset.translation.vector,
                                iso.rotation * Vector3::z(),
                            ));
                        }
                    }
                }
            }
            arrows
        })
        .unwrap_or_default();

    let root = SVGBackend::with_string(svg, (1300, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((1, 2));
    for (panel, (axis_name, pick)) in panels.iter().zip([
        ("x-z (side view)", (0usize, 2usize)),
        ("x-y (top view)", (0usize, 1usize)),
    ]) {
        let all = demo_tool
            .iter()
            .chain(preview.iter())
            .chain(run_paths.iter().flat_map(|(_, _, p)| p.iter()))
            .map(|p| (p[pick.0], p[pick.1]));
        let ((x0, x1), (y0, y1)) = bounds(all);
        let mut chart = ChartBuilder::on(panel)
            .caption(format!("{} — {axis_name}", skill.name), ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(55)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc(["x", "y", "z"][pick.0].to_string() + " [m]")
            .y_desc(["x", "y", "z"][pick.1].to_string() + " [m]")
            .draw()?;
        // The demonstration, coloured by segment.
        let n_segments = skill.learned().map_or(1, |l| l.segments.len().max(1));
        for segment in 0..n_segments {
            let points: Vec<(f64, f64)> = demo_tool
                .iter()
                .enumerate()
                .filter(|(k, _)| segment_of(*k) == segment && k % 10 == 0)
                .map(|(_, p)| (p[pick.0], p[pick.1]))
                .collect();
            let colour = SEGMENT_COLOURS[segment % SEGMENT_COLOURS.len()];
            chart
                .draw_series(LineSeries::new(points, colour.stroke_width(4)))?
                .label(format!("demonstration, segment {}", segment + 1))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(4)));
        }
        chart
            .draw_series(LineSeries::new(
                preview.iter().map(|p| (p[pick.0], p[pick.1])),
                BLACK.stroke_width(1),
            ))?
            .label("learned rollout")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK));
        let mut variant_index = Vec::<String>::new();
        for (variant, replay, points) in &run_paths {
            let colour = trial_colour(colour_index(&mut variant_index, variant));
            let xy: Vec<(f64, f64)> = points.iter().map(|p| (p[pick.0], p[pick.1])).collect();
            if *replay {
                chart.draw_series(DashedLineSeries::new(xy, 5, 4, colour.stroke_width(1)))?;
            } else {
                chart
                    .draw_series(LineSeries::new(xy, colour.stroke_width(2)))?
                    .label(variant.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2)));
            }
        }
        for (origin, z) in &frames {
            let tip = origin + z * 0.03;
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(origin[pick.0], origin[pick.1]), (tip[pick.0], tip[pick.1])],
                RGBColor(0, 0, 0).stroke_width(2),
            )))?;
            chart.draw_series(std::iter::once(Circle::new(
                (tip[pick.0], tip[pick.1]),
                3,
                BLACK.filled(),
            )))?;
        }
        draw_legend(&mut chart)?;
    }
    root.present()?;
    Ok(())
}

fn force(svg: &mut String, skill: &Subject<'_>, runs: &[Trial<'_>]) -> DrawResult {
    let replay_z = skill
        .learned()
        .and_then(|l| l.frames.values().next())
        .map_or(Vector3::z(), |f| f.at(0.0).rotation * Vector3::z());
    // Per trial: variant, replay or not, measured and desired force over time.
    type Series = (String, bool, Vec<(f64, f64)>, Vec<(f64, f64)>);
    let series: Vec<Series> = runs
        .iter()
        .map(|o| {
            let t0 = start_time(o.log);
            let replay = o.replay;
            let mut measured = Vec::new();
            let mut desired = Vec::new();
            for tick in ticks(o.log, 10) {
                let t = tick.t_s - t0;
                let value = if replay {
                    Vector3::new(tick.wrench_base[0], tick.wrench_base[1], tick.wrench_base[2]).dot(&replay_z)
                } else {
                    tick.wrench_cf[2]
                };
                measured.push((t, value));
                if tick.selection & 0b100 == 0 {
                    desired.push((t, tick.desired_cf[2]));
                }
            }
            (o.variant.to_string(), replay, measured, desired)
        })
        .collect();
    let ((x0, x1), (mut y0, mut y1)) = bounds(series.iter().flat_map(|(_, _, m, d)| m.iter().chain(d.iter()).copied()));
    // Impact spikes would flatten the rest: clip the view at a few times the desired force.
    let desired_peak = series
        .iter()
        .flat_map(|(_, _, _, d)| d.iter().map(|p| p.1))
        .fold(0.0, f64::max);
    if desired_peak > 0.0 {
        y1 = y1.min(desired_peak * 3.0);
        y0 = y0.max(-desired_peak);
    }
    let root = SVGBackend::with_string(svg, (1300, 480)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{} — applied force along the compliant z", skill.name),
            ("sans-serif", 18),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc("time since the skill started [s]")
        .y_desc("force [N]")
        .draw()?;
    let mut variants = Vec::<String>::new();
    for (variant, replay, measured, desired) in &series {
        let colour = trial_colour(colour_index(&mut variants, variant));
        let clipped: Vec<(f64, f64)> = measured.iter().map(|&(t, f)| (t, f.clamp(y0, y1))).collect();
        if *replay {
            chart
                .draw_series(DashedLineSeries::new(clipped, 5, 4, colour.stroke_width(1)))?
                .label(format!("{variant} (replay)"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(1)));
        } else {
            chart
                .draw_series(LineSeries::new(clipped, colour.stroke_width(2)))?
                .label(variant.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2)));
            chart.draw_series(
                desired
                    .iter()
                    .step_by(5)
                    .map(|&(t, f)| Circle::new((t, f.clamp(y0, y1)), 1, BLACK.filled())),
            )?;
        }
    }
    draw_legend(&mut chart)?;
    root.present()?;
    Ok(())
}

/// The demonstration's applied force along each learned frame's z, with the learned desired
/// forces over their segments (thesis Fig. 4.7, 5.9c).
fn learned_force(svg: &mut String, skill: &Subject<'_>) -> DrawResult {
    let demo = read_demo(skill.demo)?;
    let Some(bound) = skill.bound else {
        return Err("nothing learned to plot".into());
    };
    let learned = bound.learned;
    let t0 = demo.t_s.first().copied().unwrap_or(0.0);
    let root = SVGBackend::with_string(svg, (1300, 520)).into_drawing_area();
    root.fill(&WHITE)?;
    // Label, colour, points, drawn thick.
    type Line = (String, RGBColor, Vec<(f64, f64)>, bool);
    let mut lines: Vec<Line> = Vec::new();
    for (index, (decl, frame)) in bound.declared_frames().enumerate() {
        let segment_start = match &decl.source {
            skill_ir::FrameSource::ForceAlignedSamples { segment } => {
                learned.segments.get(segment.index()).map_or(0.0, |s| s.start_s)
            }
            _ => 0.0,
        };
        let points = demo
            .t_s
            .iter()
            .zip(&demo.force_n)
            .step_by(5)
            .map(|(t, f)| (t - t0, -f.dot(&(frame.at(t - segment_start).rotation * Vector3::z()))))
            .collect();
        lines.push((
            format!("demonstration along {}.z", decl.name),
            trial_colour(index),
            points,
            false,
        ));
    }
    for (decl, force) in bound.declared_forces() {
        let segment = match &decl.source {
            skill_ir::ForceSource::Constant { segment, .. }
            | skill_ir::ForceSource::Dmp { segment, .. }
            | skill_ir::ForceSource::Magnitude { segment, .. } => Some(segment.index()),
            _ => None,
        };
        let Some(segment) = segment.and_then(|s| learned.segments.get(s)) else {
            continue;
        };
        let duration = segment.end_s - segment.start_s;
        let profile = DesiredProfile::new(force, duration / 200.0);
        let points = (0..=200)
            .map(|k| {
                let t = duration * k as f64 / 200.0;
                (segment.start_s - t0 + t, profile.at(t))
            })
            .collect();
        lines.push((format!("learned `{}`", decl.name), BLACK, points, true));
    }
    let ((x0, x1), (y0, y1)) = bounds(lines.iter().flat_map(|(_, _, p, _)| p.iter().copied()));
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "{} — applied force along the compliant z, and the learned force",
                skill.name
            ),
            ("sans-serif", 18),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc("demonstration time [s]")
        .y_desc("force [N]")
        .draw()?;
    for segment in &learned.segments {
        let colour = SEGMENT_COLOURS[learned.segments.iter().position(|s| s == segment).unwrap_or(0) % 4].mix(0.08);
        chart.draw_series(std::iter::once(Rectangle::new(
            [(segment.start_s - t0, y0), (segment.end_s - t0, y1)],
            colour.filled(),
        )))?;
    }
    for (label, colour, points, thick) in lines {
        chart
            .draw_series(LineSeries::new(points, colour.stroke_width(if thick { 3 } else { 1 })))?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2)));
    }
    draw_legend(&mut chart)?;
    root.present()?;
    Ok(())
}

fn world_force(svg: &mut String, skill: &Subject<'_>, runs: &[Trial<'_>]) -> DrawResult {
    let demo = read_demo(skill.demo)?;
    let t_demo0 = demo.t_s.first().copied().unwrap_or(0.0);
    let demo_series: Vec<Vec<(f64, f64)>> = (0..3)
        .map(|axis| {
            demo.t_s
                .iter()
                .zip(&demo.force_n)
                .step_by(10)
                .map(|(t, f)| (t - t_demo0, -f[axis]))
                .collect()
        })
        .collect();
    let trial = runs.iter().find(|o| !o.replay && !o.error);
    let trial_series: Vec<Vec<(f64, f64)>> = match trial {
        Some(o) => {
            let t0 = start_time(o.log);
            (0..3)
                .map(|axis| ticks(o.log, 10).map(|t| (t.t_s - t0, t.wrench_base[axis])).collect())
                .collect()
        }
        None => vec![Vec::new(); 3],
    };
    let root = SVGBackend::with_string(svg, (1300, 700)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((2, 1));
    let trial_name = trial.map_or("no trial".to_string(), |o| o.variant.to_string());
    for (panel, (title, data)) in panels.iter().zip([
        (
            format!("{} — demonstration, applied force (world frame)", skill.name),
            &demo_series,
        ),
        (
            format!("{} — skill, {trial_name}, applied force (world frame)", skill.name),
            &trial_series,
        ),
    ]) {
        let ((x0, x1), (y0, y1)) = bounds(data.iter().flat_map(|s| s.iter().copied()));
        let mut chart = ChartBuilder::on(panel)
            .caption(title, ("sans-serif", 16))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(55)
            .build_cartesian_2d(x0..x1, y0.max(-60.0)..y1.min(60.0))?;
        chart.configure_mesh().x_desc("time [s]").y_desc("force [N]").draw()?;
        for (axis, series) in data.iter().enumerate() {
            let colour = SEGMENT_COLOURS[axis];
            chart
                .draw_series(LineSeries::new(
                    series.iter().map(|&(t, f)| (t, f.clamp(-60.0, 60.0))),
                    colour.stroke_width(1),
                ))?
                .label(["fx", "fy", "fz"][axis])
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2)));
        }
        draw_legend(&mut chart)?;
    }
    root.present()?;
    Ok(())
}

fn timeline(svg: &mut String, runs: &[Trial<'_>]) -> DrawResult {
    let rows = runs.len().max(1);
    let root = SVGBackend::with_string(svg, (1300, 60 + 56 * rows as u32)).into_drawing_area();
    root.fill(&WHITE)?;
    let duration = runs
        .iter()
        .map(|o| o.log.ticks.last().map_or(0.0, |t| t.t_s))
        .fold(1.0, f64::max);
    let mut chart = ChartBuilder::on(&root)
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(10)
        .build_cartesian_2d(0.0..duration, -0.5..rows as f64 - 0.5)?;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(0)
        .x_desc("time [s]")
        .draw()?;
    let mut names: Vec<String> = Vec::new();
    for (row, outcome) in runs.iter().enumerate() {
        let log = outcome.log;
        let mut start = 0usize;
        while start < log.ticks.len() {
            let state = log.ticks[start].state;
            let mut end = start;
            while end < log.ticks.len() && log.ticks[end].state == state {
                end += 1;
            }
            let name = log.states[state as usize].clone();
            let index = match names.iter().position(|n| *n == name) {
                Some(i) => i,
                None => {
                    names.push(name.clone());
                    names.len() - 1
                }
            };
            let colour = Palette99::pick(index);
            let (t0, t1) = (log.ticks[start].t_s, log.ticks[end - 1].t_s);
            chart.draw_series(std::iter::once(Rectangle::new(
                [(t0, row as f64 - 0.42), (t1, row as f64 + 0.02)],
                colour.filled(),
            )))?;
            if t1 - t0 > duration * 0.06 {
                chart.draw_series(std::iter::once(Text::new(
                    name,
                    (t0 + 0.05, row as f64 - 0.12),
                    ("sans-serif", 11),
                )))?;
            }
            start = end;
        }
    }
    // Trial names above their bars (text hangs down from its anchor).
    for (row, outcome) in runs.iter().enumerate() {
        let label = format!("{} ({})", outcome.variant, outcome.mode());
        chart.draw_series(std::iter::once(Text::new(
            label,
            (0.02, row as f64 + 0.44),
            ("sans-serif", 12),
        )))?;
    }
    root.present()?;
    Ok(())
}

/// One draw of a sweep, as its plot shows it.
#[derive(Debug, Clone, Copy)]
pub struct SweepPoint<'a> {
    /// The skill.
    pub skill: &'a str,
    /// Height change of the scene \[m\].
    pub height_m: f64,
    /// Tilt \[deg\].
    pub tilt_deg: f64,
    /// Whether the trial succeeded.
    pub success: bool,
}

/// A sweep's draws, one panel per skill: height change against tilt, successes green and
/// failures red.
pub fn sweep(path: &Path, points: &[SweepPoint<'_>]) -> Result<(), String> {
    let mut svg = String::new();
    sweep_panels(&mut svg, points).map_err(|err| err.to_string())?;
    write_svg(path, &svg)
}

fn sweep_panels(svg: &mut String, points: &[SweepPoint<'_>]) -> DrawResult {
    let mut skills: Vec<&str> = Vec::new();
    for point in points {
        if !skills.contains(&point.skill) {
            skills.push(point.skill);
        }
    }
    let panels = skills.len().max(1);
    let root = SVGBackend::with_string(svg, (420 * panels as u32, 400)).into_drawing_area();
    root.fill(&WHITE)?;
    let areas = root.split_evenly((1, panels));
    let height = points.iter().map(|p| p.height_m.abs() * 100.0).fold(1.0, f64::max) * 1.05;
    let tilt = points.iter().map(|p| p.tilt_deg.abs()).fold(1.0, f64::max) * 1.05;
    for (area, skill) in areas.iter().zip(&skills) {
        let mine: Vec<&SweepPoint<'_>> = points.iter().filter(|p| p.skill == *skill).collect();
        let ok = mine.iter().filter(|p| p.success).count();
        let mut chart = ChartBuilder::on(area)
            .caption(format!("{skill}: {ok}/{} succeeded", mine.len()), ("sans-serif", 15))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(-height..height, -tilt..tilt)?;
        chart
            .configure_mesh()
            .x_desc("height change [cm] (+: nearer)")
            .y_desc("tilt [deg]")
            .draw()?;
        chart.draw_series(
            mine.iter()
                .filter(|p| p.success)
                .map(|p| Circle::new((p.height_m * 100.0, p.tilt_deg), 3, GREEN.mix(0.7).filled())),
        )?;
        chart.draw_series(
            mine.iter()
                .filter(|p| !p.success)
                .map(|p| Cross::new((p.height_m * 100.0, p.tilt_deg), 5, RED.stroke_width(2))),
        )?;
    }
    root.present()?;
    Ok(())
}
