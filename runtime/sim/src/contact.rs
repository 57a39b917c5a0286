//! Reading contacts: the contact wrench on the tool colliders from rapier's solver impulses,
//! about the sensor origin, and what the wrist sensor makes of it; and the contact forces on the
//! arm's other links, which the sensor does not see.
// `Real` is f32 or f64 depending on the rapier flavour: casts and conversions to it are identities in one.
#![allow(clippy::unnecessary_cast, clippy::useless_conversion)]

use nalgebra::{Rotation3, Vector3, Vector6};
use rapier3d::prelude::PairContacts;

use super::build::arm_link_of;
use super::convert::{from_vec3, iso_of};
use super::rapier_plant::RapierPlant;

impl RapierPlant {
    /// Sums the contact wrenches on the tool colliders about the sensor origin (base axes), and
    /// the normal of the tool's contacts with fixed objects (their normals on the tool weighted
    /// by their normal impulses; `None` without such contact).
    pub(super) fn contact_wrench(&self) -> (Vector6<f64>, Option<Vector3<f64>>) {
        let sensor_origin = self
            .bodies
            .get(self.links[self.sensor_body])
            .map(|rb| (iso_of(rb.position()) * self.sensor_in_body).translation.vector)
            .unwrap_or_else(Vector3::zeros);
        let inv_dt = 1.0 / f64::from(self.params.dt);
        let mut force = Vector3::zeros();
        let mut moment = Vector3::zeros();
        let mut normals = Vector3::zeros();
        for tool in &self.tool_colliders {
            for pair in self.narrow_phase.contact_pairs_with(*tool) {
                let PairContacts::Rigid(rigid) = &pair.contacts else {
                    continue;
                };
                let tool_is_first = pair.collider1 == *tool;
                let Some(tool_collider) = self.colliders.get(*tool) else {
                    continue;
                };
                let tool_pose = tool_collider.position();
                let other = if tool_is_first { pair.collider2 } else { pair.collider1 };
                let fixed = self
                    .colliders
                    .get(other)
                    .and_then(|c| c.parent())
                    .and_then(|body| self.bodies.get(body))
                    .is_some_and(|body| body.is_fixed());
                for manifold in rigid.solver_manifolds() {
                    let normal = from_vec3(manifold.data.normal);
                    let normal_on_tool = if tool_is_first { -normal } else { normal };
                    for point in &manifold.points {
                        if fixed {
                            normals += normal_on_tool * f64::from(point.data.impulse);
                        }
                        // rapier's impulses act on the first collider along the normal that points
                        // from the first to the second: the push on the first is −n λ.
                        let on_first = -(normal * f64::from(point.data.impulse)
                            + from_vec3(point.data.warmstart_tangent_world))
                            * inv_dt;
                        let (on_tool, local) = if tool_is_first {
                            (on_first, point.local_p1)
                        } else {
                            (-on_first, point.local_p2)
                        };
                        let at = from_vec3(tool_pose.transform_point(local));
                        force += on_tool;
                        moment += (at - sensor_origin).cross(&on_tool);
                    }
                }
            }
        }
        let normal = (normals.norm() > 0.0).then(|| normals.normalize());
        (
            Vector6::new(force.x, force.y, force.z, moment.x, moment.y, moment.z),
            normal,
        )
    }

    /// Sums the contact forces on each arm link that is not the tool (base axes) into
    /// `arm_forces`, and keeps the largest magnitude and its link. Reads the pairs of the scene's
    /// objects (a handful) rather than those of the arm's colliders (about twenty).
    fn sense_arm_contacts(&mut self) {
        self.arm_forces.iter_mut().for_each(|force| *force = Vector3::zeros());
        let inv_dt = 1.0 / f64::from(self.params.dt);
        for (object, _) in &self.object_colliders {
            for pair in self.narrow_phase.contact_pairs_with(*object) {
                let PairContacts::Rigid(rigid) = &pair.contacts else {
                    continue;
                };
                let object_is_first = pair.collider1 == *object;
                let arm = if object_is_first {
                    pair.collider2
                } else {
                    pair.collider1
                };
                let Some(link) = self.colliders.get(arm).and_then(|c| arm_link_of(c.user_data)) else {
                    continue;
                };
                let mut on_arm = Vector3::zeros();
                for manifold in rigid.solver_manifolds() {
                    let normal = from_vec3(manifold.data.normal);
                    for point in &manifold.points {
                        // As for the tool: the push on the first collider is −n λ (plus friction).
                        let on_first = -(normal * f64::from(point.data.impulse)
                            + from_vec3(point.data.warmstart_tangent_world))
                            * inv_dt;
                        on_arm += if object_is_first { -on_first } else { on_first };
                    }
                }
                if let Some(slot) = self.arm_forces.get_mut(link) {
                    *slot += on_arm;
                }
            }
        }
        let (mut largest, mut which) = (0.0, None);
        for (link, force) in self.arm_forces.iter().enumerate() {
            let magnitude = force.norm();
            if magnitude > largest {
                (largest, which) = (magnitude, Some(link));
            }
        }
        self.arm_contact = (largest, which);
    }

    /// The sensor frame's rotation in the base frame.
    fn sensor_rotation(&self) -> Rotation3<f64> {
        self.bodies
            .get(self.links[self.sensor_body])
            .map(|rb| (iso_of(rb.position()) * self.sensor_in_body).rotation)
            .unwrap_or_else(Rotation3::identity)
    }

    /// After a step: gathers the contact wrench and passes it through the wrist sensor
    /// (sensor axes), storing the ideal wrench and the sensor's reading in sensor and base axes;
    /// gathers the arm links' contact forces.
    pub(super) fn sense_contacts(&mut self, dt: f64) {
        self.sense_arm_contacts();
        let (ideal, normal) = self.contact_wrench();
        self.tool_normal = normal;
        self.read_sensor(ideal, self.sensor_rotation(), dt);
    }

    /// Passes the contact wrench `ideal` (about the sensor origin, base axes) through the wrist
    /// sensor whose frame has rotation `sensor_in_base`, storing the ideal wrench and the
    /// sensor's reading in sensor and base axes.
    pub(super) fn read_sensor(&mut self, ideal: Vector6<f64>, sensor_in_base: Rotation3<f64>, dt: f64) {
        self.ideal_wrench_base = ideal;
        let rot_t = sensor_in_base.inverse();
        let force = rot_t * Vector3::new(ideal[0], ideal[1], ideal[2]);
        let moment = rot_t * Vector3::new(ideal[3], ideal[4], ideal[5]);
        let ideal_sensor = Vector6::new(force.x, force.y, force.z, moment.x, moment.y, moment.z);
        self.wrench_sensor = self.sensor.measure(&ideal_sensor, dt);
        let rot = rot_t.inverse();
        let f_base = rot * Vector3::new(self.wrench_sensor[0], self.wrench_sensor[1], self.wrench_sensor[2]);
        let m_base = rot * Vector3::new(self.wrench_sensor[3], self.wrench_sensor[4], self.wrench_sensor[5]);
        self.wrench_base = Vector6::new(f_base.x, f_base.y, f_base.z, m_base.x, m_base.y, m_base.z);
    }
}
