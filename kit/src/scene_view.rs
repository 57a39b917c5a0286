//! A trial in 3-D as a static SVG: the tool's path over the scene's objects (their faces inside the view, in an
//! oblique projection with one scale on every axis), the contact points coloured by force, the
//! start and the end marked. Drawn with plotters, like the report's other plots; no WebGL.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Point3, Vector3};
use plotters::prelude::*;
use skill_runtime::exec::RunLog;
use skill_runtime::sim::{ObjectShape, ObjectSpec};

/// A force above this is contact \[N\] (the eval's contact threshold's order: sensor noise and
/// the tool's inertia stay below it in free motion).
const CONTACT_N: f64 = 1.0;

/// Every this many ticks a point of the path is drawn (10 ms at 1 kHz).
const STRIDE: usize = 10;

/// How far the view reaches past the tool's path on every side \[m\].
const MARGIN_M: f64 = 0.08;

/// An axis-aligned box in world coordinates: what the view shows.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Bounds {
    lo: Vector3<f64>,
    hi: Vector3<f64>,
}

impl Bounds {
    /// A cube around `points` (each side the largest extent plus the margin), so that one metre
    /// is as long on every axis.
    fn cube_around(points: &[Vector3<f64>]) -> Option<Bounds> {
        let first = *points.first()?;
        let (mut lo, mut hi) = (first, first);
        for p in points {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let half = (hi - lo).max() / 2.0 + MARGIN_M;
        let centre = (lo + hi) / 2.0;
        let half = Vector3::repeat(half);
        Some(Bounds {
            lo: centre - half,
            hi: centre + half,
        })
    }

    /// The part of a flat polygon inside the box (Sutherland–Hodgman, one face of the box at a
    /// time); empty when none is.
    fn clip_polygon(&self, polygon: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let mut out = polygon.to_vec();
        for axis in 0..3 {
            for (limit, keep_below) in [(self.lo[axis], false), (self.hi[axis], true)] {
                let inside = |p: &Vector3<f64>| if keep_below { p[axis] <= limit } else { p[axis] >= limit };
                let input = std::mem::take(&mut out);
                for (index, current) in input.iter().enumerate() {
                    let previous = &input[(index + input.len() - 1) % input.len()];
                    let crossing = || {
                        let t = (limit - previous[axis]) / (current[axis] - previous[axis]);
                        previous + (current - previous) * t
                    };
                    match (inside(previous), inside(current)) {
                        (true, true) => out.push(*current),
                        (true, false) => out.push(crossing()),
                        (false, true) => {
                            out.push(crossing());
                            out.push(*current);
                        }
                        (false, false) => {}
                    }
                }
            }
        }
        out
    }
}

/// The faces of an object's shape in world coordinates, each a polygon.
fn faces(object: &ObjectSpec) -> Vec<Vec<Vector3<f64>>> {
    let pose = object.pose();
    let world = |x: f64, y: f64, z: f64| (pose * Point3::new(x, y, z)).coords;
    match object.shape() {
        ObjectShape::Box { size } => {
            let h = [size[0] / 2.0, size[1] / 2.0, size[2] / 2.0];
            let mut out = Vec::with_capacity(6);
            // Each face: one axis held at -h or +h, the other two around its rim.
            for axis in 0..3 {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                for side in [-1.0, 1.0] {
                    let corner = |su: f64, sv: f64| {
                        let mut c = [0.0; 3];
                        c[axis] = side * h[axis];
                        c[u] = su * h[u];
                        c[v] = sv * h[v];
                        world(c[0], c[1], c[2])
                    };
                    out.push(vec![
                        corner(-1.0, -1.0),
                        corner(1.0, -1.0),
                        corner(1.0, 1.0),
                        corner(-1.0, 1.0),
                    ]);
                }
            }
            out
        }
        ObjectShape::Cylinder { radius, length } => cylinder_faces(&world, radius, length),
        ObjectShape::Button { radius, height, .. } => cylinder_faces(&world, radius, height),
    }
}

/// A cylinder along its local z: its two end discs (32-gons) and 32 side panels.
fn cylinder_faces(world: &dyn Fn(f64, f64, f64) -> Vector3<f64>, radius: f64, length: f64) -> Vec<Vec<Vector3<f64>>> {
    const SEGMENTS: usize = 32;
    let at = |k: usize, z: f64| {
        let angle = std::f64::consts::TAU * k as f64 / SEGMENTS as f64;
        world(radius * angle.cos(), radius * angle.sin(), z)
    };
    let (bottom, top) = (-length / 2.0, length / 2.0);
    let mut out: Vec<Vec<Vector3<f64>>> = [bottom, top]
        .into_iter()
        .map(|z| (0..SEGMENTS).map(|k| at(k, z)).collect())
        .collect();
    out.extend((0..SEGMENTS).map(|k| vec![at(k, bottom), at(k + 1, bottom), at(k + 1, top), at(k, top)]));
    out
}

/// Blue (no force) through yellow to red (the trial's largest force), for `share` in 0..=1.
fn force_colour(share: f64) -> RGBColor {
    let share = share.clamp(0.0, 1.0);
    let mix = |a: (f64, f64, f64), b: (f64, f64, f64), t: f64| {
        RGBColor(
            (a.0 + (b.0 - a.0) * t) as u8,
            (a.1 + (b.1 - a.1) * t) as u8,
            (a.2 + (b.2 - a.2) * t) as u8,
        )
    };
    let (blue, yellow, red) = ((40.0, 90.0, 200.0), (240.0, 200.0, 40.0), (200.0, 30.0, 30.0));
    if share < 0.5 {
        mix(blue, yellow, share * 2.0)
    } else {
        mix(yellow, red, share * 2.0 - 1.0)
    }
}

/// Plotters' 3-D charts put their y axis up: world (x, y, z) is drawn as (x, z, y).
fn drawn(p: Vector3<f64>) -> (f64, f64, f64) {
    (p.x, p.z, p.y)
}

/// Draws one trial's tool path over `objects` into `path` (SVG); `title` heads it. Every log in
/// `logs` is drawn (a task's steps one after the other).
pub fn draw(path: &Path, title: &str, logs: &[&RunLog], objects: &BTreeMap<String, ObjectSpec>) -> Result<(), String> {
    let mut svg = String::new();
    draw_inner(&mut svg, title, logs, objects).map_err(|err| err.to_string())?;
    crate::plot::write_svg(path, &svg)
}

fn draw_inner(
    svg: &mut String,
    title: &str,
    logs: &[&RunLog],
    objects: &BTreeMap<String, ObjectSpec>,
) -> Result<(), Box<dyn std::error::Error>> {
    let ticks = || logs.iter().flat_map(|log| log.ticks.iter().step_by(STRIDE));
    let position =
        |tick: &skill_runtime::exec::Tick| Vector3::new(tick.measured[0], tick.measured[1], tick.measured[2]);
    let tool: Vec<Vector3<f64>> = ticks()
        .map(position)
        .filter(|p| p.iter().all(|v| v.is_finite()))
        .collect();
    let bounds = Bounds::cube_around(&tool).ok_or("the trial has no ticks to draw")?;
    let force = |tick: &skill_runtime::exec::Tick| {
        Vector3::new(tick.wrench_base[0], tick.wrench_base[1], tick.wrench_base[2]).norm()
    };
    let peak = ticks().map(force).fold(0.0f64, f64::max);

    let root = SVGBackend::with_string(svg, (560, 440)).into_drawing_area();
    root.fill(&WHITE)?;
    let (chart_area, legend_area) = root.split_vertically(400);
    let mut chart = ChartBuilder::on(&chart_area)
        .caption(title, ("sans-serif", 14))
        .margin(8)
        .build_cartesian_3d(
            bounds.lo.x..bounds.hi.x,
            bounds.lo.z..bounds.hi.z,
            bounds.lo.y..bounds.hi.y,
        )?;
    chart.with_projection(|mut projection| {
        projection.yaw = 0.6;
        projection.pitch = 0.35;
        projection.scale = 0.85;
        projection.into_matrix()
    });
    let metres = |v: &f64| format!("{v:.2}");
    chart
        .configure_axes()
        .light_grid_style(BLACK.mix(0.0))
        .max_light_lines(0)
        .label_style(("sans-serif", 10))
        .x_formatter(&metres)
        .y_formatter(&metres)
        .z_formatter(&metres)
        .draw()?;

    // Each object as the part of its faces inside the view: translucent, outlined.
    let fill = RGBColor(150, 150, 160).mix(0.18).filled();
    let outline = RGBColor(110, 110, 120).stroke_width(1);
    for object in objects.values() {
        for face in faces(object) {
            let clipped = bounds.clip_polygon(&face);
            if clipped.len() < 3 {
                continue;
            }
            let mut rim: Vec<(f64, f64, f64)> = clipped.iter().map(|p| drawn(*p)).collect();
            chart.draw_series([Polygon::new(rim.clone(), fill)])?;
            rim.push(rim[0]);
            chart.draw_series([PathElement::new(rim, outline)])?;
        }
    }
    chart.draw_series(LineSeries::new(
        tool.iter().map(|p| drawn(*p)),
        BLACK.mix(0.6).stroke_width(1),
    ))?;
    let contacts: Vec<(Vector3<f64>, f64)> = ticks()
        .map(|tick| (position(tick), force(tick)))
        .filter(|(p, f)| *f > CONTACT_N && p.iter().all(|v| v.is_finite()))
        .collect();
    chart.draw_series(contacts.iter().map(|(p, f)| {
        Circle::new(
            drawn(*p),
            3,
            force_colour(if peak > 0.0 { f / peak } else { 0.0 }).filled(),
        )
    }))?;
    if let (Some(first), Some(last)) = (tool.first(), tool.last()) {
        chart.draw_series([Circle::new(drawn(*first), 5, GREEN.filled())])?;
        chart.draw_series([Cross::new(drawn(*last), 6, BLACK.stroke_width(2))])?;
    }

    // The legend: what the marks mean and the force scale.
    let text = ("sans-serif", 11).into_font();
    legend_area.draw(&Circle::new((14, 18), 5, GREEN.filled()))?;
    legend_area.draw(&Text::new("start", (24, 12), text.clone()))?;
    legend_area.draw(&Cross::new((74, 18), 6, BLACK.stroke_width(2)))?;
    legend_area.draw(&Text::new("end", (84, 12), text.clone()))?;
    legend_area.draw(&Text::new("contact force:", (124, 12), text.clone()))?;
    for step in 0..=20 {
        let x = 210 + step * 8;
        legend_area.draw(&Rectangle::new(
            [(x, 12), (x + 8, 24)],
            force_colour(f64::from(step) / 20.0).filled(),
        ))?;
    }
    legend_area.draw(&Text::new(
        format!("{CONTACT_N:.0} N … {peak:.1} N  (z up, metres)"),
        (384, 12),
        text,
    ))?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Bounds {
        Bounds {
            lo: Vector3::zeros(),
            hi: Vector3::repeat(1.0),
        }
    }

    /// The shoelace area of a flat polygon in 3-D.
    fn area(polygon: &[Vector3<f64>]) -> f64 {
        let mut sum = Vector3::zeros();
        for (index, a) in polygon.iter().enumerate() {
            sum += a.cross(&polygon[(index + 1) % polygon.len()]);
        }
        sum.norm() / 2.0
    }

    #[test]
    fn clipping_keeps_the_part_of_a_polygon_inside_the_box() {
        // A square twice the box's size through its middle: clipped to the box's cross-section.
        let square = [(-0.5, -0.5), (1.5, -0.5), (1.5, 1.5), (-0.5, 1.5)].map(|(x, y)| Vector3::new(x, y, 0.5));
        let clipped = unit().clip_polygon(&square);
        assert!((area(&clipped) - 1.0).abs() < 1e-12, "{clipped:?}");
        for p in &clipped {
            assert!(p.iter().all(|v| (-1e-12..=1.0 + 1e-12).contains(v)), "{p:?}");
        }
        // A triangle whose hypotenuse cuts the box's section: the section less the corner beyond
        // x + y = 1.5, whose legs are 0.5.
        let triangle = [
            Vector3::new(0.0, 0.0, 0.5),
            Vector3::new(1.5, 0.0, 0.5),
            Vector3::new(0.0, 1.5, 0.5),
        ];
        assert!((area(&unit().clip_polygon(&triangle)) - (1.0 - 0.125)).abs() < 1e-12);
        // Wholly outside: nothing; wholly inside: itself.
        let far = square.map(|p| p + Vector3::new(5.0, 0.0, 0.0));
        assert!(unit().clip_polygon(&far).is_empty());
        let small = square.map(|p| p * 0.2 + Vector3::repeat(0.4));
        assert_eq!(unit().clip_polygon(&small), small.to_vec());
    }

    #[test]
    fn the_view_is_a_cube_around_the_path() {
        let bounds = Bounds::cube_around(&[Vector3::new(0.5, 0.0, 0.3), Vector3::new(0.7, 0.1, 0.32)]).expect("points");
        let side = bounds.hi - bounds.lo;
        assert!((side.x - side.y).abs() < 1e-12 && (side.y - side.z).abs() < 1e-12);
        assert!((side.x - (0.2 + 2.0 * MARGIN_M)).abs() < 1e-12);
        assert_eq!(Bounds::cube_around(&[]), None);
    }

    #[test]
    fn a_box_has_six_faces_of_its_sides_areas_and_a_cylinder_its_ends_and_sides() {
        let object: ObjectSpec =
            toml::from_str("kind = \"box\"\nxyz = [0.5, 0.0, 0.2]\nrpy = [0.0, 0.3, 0.0]\nsize = [0.6, 0.8, 0.05]")
                .expect("object");
        let mut areas: Vec<f64> = faces(&object).iter().map(|face| area(face)).collect();
        areas.sort_by(f64::total_cmp);
        for (pair, expected) in areas.chunks(2).zip([0.6 * 0.05, 0.8 * 0.05, 0.6 * 0.8]) {
            assert!(pair.iter().all(|a| (a - expected).abs() < 1e-12), "{areas:?}");
        }
        let cylinder: ObjectSpec =
            toml::from_str("kind = \"cylinder\"\nxyz = [0.5, 0.0, 0.2]\nradius = 0.1\nlength = 0.4").expect("object");
        let faces = faces(&cylinder);
        assert_eq!(faces.len(), 2 + 32);
        // The 32-gon's area is (32/2) r² sin(2π/32), within 1 % of π r².
        let disc = area(&faces[0]);
        assert!((disc - 16.0 * 0.01 * (std::f64::consts::TAU / 32.0).sin()).abs() < 1e-12);
        assert!((disc / (std::f64::consts::PI * 0.01) - 1.0).abs() < 0.01);
    }
}
