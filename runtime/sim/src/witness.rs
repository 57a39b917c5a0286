//! The contact witness: every simulated step's contact force on the tool checked against the
//! analytic distance between the tool's collision shapes and the scene's objects.
//!
//! rapier finds contacts with its own collision code; the witness uses none of it. Each object
//! is a signed distance function written from the scene's numbers (a box, a cylinder, a button's
//! cap at its current depth), and the tool is a set of balls: its sphere primitives exactly, its
//! cylinders, capsules and boxes as chains or grids of balls that cover them (so a distance to
//! them is never overestimated, by construction: the cover's radius is the cell's half-diagonal
//! plus the shape's radius). Two rules, [`ContactAudit`]'s:
//! - a force on the tool above [`ContactAudit::FORCE_N`] only while some ball of the tool is
//!   within [`ContactAudit::FORCE_FREE_BEYOND_M`] of an object;
//! - an exact ball (a sphere primitive: the probe's tip) never deeper into an object than
//!   `|F| / k` plus [`ContactAudit::DEPTH_SLACK_M`], `k` the scene's contact stiffness.
//!
//! The covers of non-spherical shapes are looser than the shapes (at a cylinder's flat ends by up
//! to its radius), so the first rule is lenient there and the second is checked on spheres only.

use nalgebra::{Isometry3, Point3, Vector3};

use super::scene::{ObjectShape, Scene};
use crate::plant::{ContactAudit, ContactFinding};
use crate::robot::{Robot, Shape};

/// A ball of the tool, in its link's frame.
#[derive(Debug, Clone, Copy)]
struct Ball {
    /// Index into [`Robot::links`].
    link: usize,
    centre: Point3<f64>,
    radius: f64,
    /// A sphere primitive (its distance is exact), not a piece of a cover.
    exact: bool,
}

/// A scene object as the witness sees it.
#[derive(Debug, Clone)]
struct Object {
    name: String,
    /// World → object frame.
    to_local: Isometry3<f64>,
    shape: ObjectShape,
}

/// The signed distance from `p` (object frame) to a cylinder along z of `radius` centred at
/// `z_centre` with half-length `half`: negative inside.
fn cylinder_distance(p: &Point3<f64>, radius: f64, z_centre: f64, half: f64) -> f64 {
    let radial = p.x.hypot(p.y) - radius;
    let axial = (p.z - z_centre).abs() - half;
    radial.max(0.0).hypot(axial.max(0.0)) + radial.max(axial).min(0.0)
}

/// The signed distance from `p` (object frame) to a box of full extents `size` centred on the
/// origin: negative inside.
fn box_distance(p: &Point3<f64>, size: &[f64; 3]) -> f64 {
    let q = Vector3::new(
        p.x.abs() - size[0] / 2.0,
        p.y.abs() - size[1] / 2.0,
        p.z.abs() - size[2] / 2.0,
    );
    q.map(|c| c.max(0.0)).norm() + q.max().min(0.0)
}

impl Object {
    /// The signed distance from world point `p` to the object, a button's cap `depth` m down.
    fn distance(&self, p: &Point3<f64>, depth: f64) -> f64 {
        let local = self.to_local * p;
        match self.shape {
            ObjectShape::Box { size } => box_distance(&local, &size),
            ObjectShape::Cylinder { radius, length } => cylinder_distance(&local, radius, 0.0, length / 2.0),
            ObjectShape::Button { radius, height, .. } => cylinder_distance(&local, radius, -depth, height / 2.0),
        }
    }
}

/// Balls covering `shape` (placed at `shape_in_link` on `link`): one exact ball for a sphere,
/// chains along the axis for cylinders and capsules, a grid for boxes.
fn cover(link: usize, shape_in_link: &Isometry3<f64>, shape: &Shape) -> Vec<Ball> {
    let ball = |local: Vector3<f64>, radius: f64, exact: bool| Ball {
        link,
        centre: shape_in_link * Point3::from(local),
        radius,
        exact,
    };
    match *shape {
        Shape::Sphere { radius } => vec![ball(Vector3::zeros(), radius, true)],
        Shape::Cylinder { radius, length } | Shape::Capsule { radius, length } => {
            // Centres every radius/2 along the axis: a ball of radius sqrt(r² + (s/2)²) covers
            // the slab of the shape between two centres (3 % more than the radius).
            let pieces = (length / (radius / 2.0)).ceil().max(1.0) as usize;
            let spacing = length / pieces as f64;
            let covering = radius.hypot(spacing / 2.0);
            (0..=pieces)
                .map(|i| {
                    ball(
                        Vector3::new(0.0, 0.0, -length / 2.0 + i as f64 * spacing),
                        covering,
                        false,
                    )
                })
                .collect()
        }
        Shape::Cuboid { size } => {
            let cell = size.min().max(1e-3);
            let counts = size.map(|extent| (extent / cell).ceil().max(1.0) as usize);
            let step = Vector3::new(
                size.x / counts.x as f64,
                size.y / counts.y as f64,
                size.z / counts.z as f64,
            );
            let covering = step.norm() / 2.0;
            let mut balls = Vec::with_capacity(counts.x * counts.y * counts.z);
            for i in 0..counts.x {
                for j in 0..counts.y {
                    for k in 0..counts.z {
                        let centre = Vector3::new(
                            (i as f64 + 0.5) * step.x - size.x / 2.0,
                            (j as f64 + 0.5) * step.y - size.y / 2.0,
                            (k as f64 + 0.5) * step.z - size.z / 2.0,
                        );
                        balls.push(ball(centre, covering, false));
                    }
                }
            }
            balls
        }
    }
}

/// The witness of one simulation: the tool's balls, the scene's objects, what it found.
#[derive(Debug, Clone)]
pub(super) struct Witness {
    balls: Vec<Ball>,
    objects: Vec<Object>,
    stiffness: f64,
    audit: ContactAudit,
}

/// The simulation's state at one step, as the witness reads it.
pub(super) struct StepState<'a> {
    /// Plant time, s.
    pub(super) t_s: f64,
    /// The noise-free contact force on the tool, base axes, N.
    pub(super) force: Vector3<f64>,
    /// Each tool link's pose in the world (indexed by [`Robot::links`], `None` for the others).
    pub(super) link_pose: &'a dyn Fn(usize) -> Option<Isometry3<f64>>,
    /// How far the object of this name is pressed in, m (buttons; 0 for the others).
    pub(super) depth: &'a dyn Fn(&str) -> f64,
    /// The tool point (the tool link's origin), base frame.
    pub(super) tool: Vector3<f64>,
}

impl Witness {
    /// The witness of `scene` for `robot`, whose tool is every link from `sensor_link` on.
    pub(super) fn new(robot: &Robot, sensor_link: usize, scene: &Scene) -> Self {
        let balls = robot
            .links()
            .iter()
            .enumerate()
            .skip(sensor_link)
            .filter(|(_, link)| link.body.is_some())
            .flat_map(|(index, link)| {
                link.collisions
                    .iter()
                    .flat_map(move |collision| cover(index, &collision.shape_in_link, &collision.shape))
            })
            .collect();
        let objects = scene
            .spec()
            .objects
            .iter()
            .map(|(name, object)| Object {
                name: name.clone(),
                to_local: object.pose().inverse(),
                shape: object.shape(),
            })
            .collect();
        Witness {
            balls,
            objects,
            stiffness: scene.spec().sim.contact_stiffness,
            audit: ContactAudit::default(),
        }
    }

    /// Checks one step.
    pub(super) fn check(&mut self, state: &StepState<'_>) {
        let audit = &mut self.audit;
        audit.ticks += 1;
        let force_n = state.force.norm();
        audit.max_force_n = audit.max_force_n.max(force_n);
        if self.objects.is_empty() {
            if force_n > ContactAudit::FORCE_N {
                audit.touching_ticks += 1;
                audit.far_ticks += 1;
                keep_larger(
                    &mut audit.far_force,
                    finding(state, force_n, f64::INFINITY, 0.0, "(no object)"),
                    |f| f.force_n,
                );
            }
            return;
        }
        let depths: Vec<f64> = self.objects.iter().map(|object| (state.depth)(&object.name)).collect();
        // The nearest object to any ball (the cover's distance), and the deepest exact ball.
        let mut nearest = (f64::INFINITY, 0usize);
        let mut deepest = (f64::INFINITY, 0usize);
        let mut pose_of = (usize::MAX, None);
        for ball in &self.balls {
            if pose_of.0 != ball.link {
                pose_of = (ball.link, (state.link_pose)(ball.link));
            }
            let Some(pose) = pose_of.1 else { continue };
            let centre = pose * ball.centre;
            for (index, (object, depth)) in self.objects.iter().zip(&depths).enumerate() {
                let gap = object.distance(&centre, *depth) - ball.radius;
                if gap < nearest.0 {
                    nearest = (gap, index);
                }
                if ball.exact && gap < deepest.0 {
                    deepest = (gap, index);
                }
            }
        }
        if force_n > ContactAudit::FORCE_N {
            audit.touching_ticks += 1;
            if nearest.0 > ContactAudit::FORCE_FREE_BEYOND_M {
                audit.far_ticks += 1;
                let name = &self.objects[nearest.1].name;
                keep_larger(
                    &mut audit.far_force,
                    finding(state, force_n, nearest.0, 0.0, name),
                    |f| f.force_n,
                );
            }
        }
        if deepest.0 < 0.0 {
            audit.max_depth_m = audit.max_depth_m.max(-deepest.0);
            let allowed = force_n / self.stiffness + ContactAudit::DEPTH_SLACK_M;
            if -deepest.0 > allowed {
                audit.deep_ticks += 1;
                let name = &self.objects[deepest.1].name;
                keep_larger(
                    &mut audit.too_deep,
                    finding(state, force_n, deepest.0, allowed, name),
                    |f| -f.gap_m - f.allowed_m,
                );
            }
        }
    }

    /// What was found since the last call; starts afresh.
    pub(super) fn take(&mut self) -> ContactAudit {
        std::mem::take(&mut self.audit)
    }
}

fn finding(state: &StepState<'_>, force_n: f64, gap_m: f64, allowed_m: f64, object: &str) -> ContactFinding {
    ContactFinding {
        t_s: state.t_s,
        force_n,
        gap_m,
        allowed_m,
        object: object.to_owned(),
        tool_m: [state.tool.x, state.tool.y, state.tool.z],
    }
}

fn keep_larger(slot: &mut Option<ContactFinding>, new: ContactFinding, key: fn(&ContactFinding) -> f64) {
    if slot.as_ref().is_none_or(|old| key(&new) > key(old)) {
        *slot = Some(new);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_distance_is_exact_outside_inside_and_at_an_edge() {
        let size = [0.2, 0.4, 0.1];
        // Above the top face, beside a side face, beyond an edge (3-4-5), inside.
        assert!((box_distance(&Point3::new(0.0, 0.0, 0.08), &size) - 0.03).abs() < 1e-12);
        assert!((box_distance(&Point3::new(0.0, 0.25, 0.0), &size) - 0.05).abs() < 1e-12);
        assert!((box_distance(&Point3::new(0.13, 0.0, 0.09), &size) - 0.05).abs() < 1e-12);
        assert!((box_distance(&Point3::new(0.0, 0.0, 0.04), &size) + 0.01).abs() < 1e-12);
    }

    #[test]
    fn cylinder_distance_is_exact_on_its_side_end_and_rim() {
        // Radius 0.1, length 0.2 along z.
        let d = |x: f64, z: f64| cylinder_distance(&Point3::new(x, 0.0, z), 0.1, 0.0, 0.1);
        assert!((d(0.15, 0.0) - 0.05).abs() < 1e-12);
        assert!((d(0.0, 0.13) - 0.03).abs() < 1e-12);
        assert!((d(0.13, 0.14) - 0.05).abs() < 1e-12);
        assert!((d(0.09, 0.0) + 0.01).abs() < 1e-12);
        // A cap centred 0.02 m down: its top at 0.08.
        assert!((cylinder_distance(&Point3::new(0.0, 0.0, 0.1), 0.1, -0.02, 0.1) - 0.02).abs() < 1e-12);
    }

    #[test]
    fn covers_contain_their_shapes() {
        // Points on a cylinder's surface and a box's corners lie inside some ball of the cover.
        let pose = Isometry3::identity();
        let cylinder = cover(
            0,
            &pose,
            &Shape::Cylinder {
                radius: 0.008,
                length: 0.1,
            },
        );
        assert!(cylinder.iter().all(|ball| !ball.exact));
        for i in 0..=200 {
            let z = -0.05 + 0.1 * f64::from(i) / 200.0;
            for angle in [0.0, 1.0, 2.5, 4.0] {
                let p = Point3::new(0.008 * f64::cos(angle), 0.008 * f64::sin(angle), z);
                assert!(
                    cylinder.iter().any(|b| (p - b.centre).norm() <= b.radius + 1e-12),
                    "{p}"
                );
            }
        }
        let size = Vector3::new(0.05, 0.02, 0.01);
        let cuboid = cover(0, &pose, &Shape::Cuboid { size });
        for corner in 0..8 {
            let sign = |bit: i32| if corner & (1 << bit) == 0 { -0.5 } else { 0.5 };
            let p = Point3::new(sign(0) * size.x, sign(1) * size.y, sign(2) * size.z);
            assert!(cuboid.iter().any(|b| (p - b.centre).norm() <= b.radius + 1e-12), "{p}");
        }
        let sphere = cover(
            3,
            &Isometry3::translation(0.0, 0.0, 0.11),
            &Shape::Sphere { radius: 0.01 },
        );
        assert_eq!(sphere.len(), 1);
        assert!(sphere[0].exact && sphere[0].link == 3 && (sphere[0].centre.z - 0.11).abs() < 1e-15);
    }

    /// The LWR-IV's probe (tip sphere 10 mm, 0.11 m from the probe link's origin along its z)
    /// pointing down with its tip centre at `tip`, over a table whose top is at z = 0.3.
    fn witness_step(witness: &mut Witness, robot: &Robot, tip: [f64; 3], force_n: f64) -> ContactAudit {
        let probe = robot.require_link("probe").expect("the LWR-IV has its probe");
        let down = nalgebra::UnitQuaternion::from_euler_angles(std::f64::consts::PI, 0.0, 0.0);
        let pose = Isometry3::from_parts(nalgebra::Translation3::new(tip[0], tip[1], tip[2] + 0.11), down);
        let link_pose = |link: usize| (link == probe).then_some(pose);
        let depth = |_: &str| 0.0;
        witness.check(&StepState {
            t_s: 1.0,
            force: Vector3::new(0.0, 0.0, force_n),
            link_pose: &link_pose,
            depth: &depth,
            tool: Vector3::from(tip),
        });
        witness.take()
    }

    #[test]
    fn the_witness_names_a_force_away_from_every_object_and_a_tool_sunk_too_deep() {
        let robot = crate::robot::LWR4.load().expect("the shipped LWR-IV loads");
        let sensor = robot.require_link(crate::robot::LWR4_FLANGE).expect("its flange");
        let scene = Scene::from_toml(
            "[robot]\nurdf = \"lwr4.urdf\"\n[objects.table]\nkind = \"box\"\nxyz = [0.5, 0.0, 0.275]\nsize = [0.4, 0.4, 0.05]\n",
            "witness.toml",
            std::path::Path::new("."),
        )
        .expect("the scene reads");
        let mut witness = Witness::new(&robot, sensor, &scene);
        // 10 N with the tip 0.2 mm into the top (10 N / 5e4 N/m explains 0.2 mm): fine.
        let resting = witness_step(&mut witness, &robot, [0.5, 0.0, 0.3098], 10.0);
        assert_eq!((resting.ticks, resting.touching_ticks), (1, 1));
        assert!(!resting.violated(), "{resting:?}");
        assert!((resting.max_depth_m - 0.0002).abs() < 1e-9, "{resting:?}");
        // 10 N with the tip 0.8 mm above the top: within the 1 mm band, fine.
        assert!(!witness_step(&mut witness, &robot, [0.5, 0.0, 0.3108], 10.0).violated());
        // 10 N with the tip 15 mm past the table's edge (x = 0.7) at the same height: named.
        let past = witness_step(&mut witness, &robot, [0.725, 0.0, 0.3098], 10.0);
        assert_eq!(past.far_ticks, 1, "{past:?}");
        let far = past.far_force.expect("a finding");
        assert_eq!(far.object, "table");
        // The tip sphere is nearest: its centre 25 mm out and 9.8 mm up from the edge.
        let expected = 0.025f64.hypot(0.0098) - 0.01;
        assert!((far.gap_m - expected).abs() < 1e-12, "{far:?} vs {expected}");
        // 1 N with the tip 5 mm deep: 1 N explains 0.02 mm, so 3.98 mm too deep.
        let sunk = witness_step(&mut witness, &robot, [0.5, 0.0, 0.305], 1.0);
        assert_eq!(sunk.deep_ticks, 1, "{sunk:?}");
        let deep = sunk.too_deep.expect("a finding");
        assert!(
            (-deep.gap_m - 0.005).abs() < 1e-9 && (deep.allowed_m - 0.00102).abs() < 1e-9,
            "{deep:?}"
        );
        // No force far from everything: nothing to name, and a 0.005 N force counts as none.
        assert!(!witness_step(&mut witness, &robot, [0.5, 0.0, 0.5], 0.005).violated());
    }
}
