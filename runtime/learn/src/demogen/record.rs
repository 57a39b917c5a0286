//! A demonstration recorded: a skill's phases sampled at 1 kHz, with the person's tremor and
//! wander, the wrist's turning, friction, and the wrist sensor's noise and bias, and the ground
//! truth beside it.

use nalgebra::{UnitQuaternion, Vector3};

use super::person::{tool, Phase, Wobble};
use super::{
    pressing, sliding, Demonstration, GroundTruth, Sample, StdSkill, TruthSegment, TruthSurface, Variation, RATE_HZ,
    TIP_RADIUS_M,
};
use crate::rng::SplitMix64;

/// What a skill's person does, phase by phase, and what the generator knows of it beyond the
/// samples.
pub(super) struct Plan {
    /// The phases in time order.
    pub(super) phases: Vec<Phase>,
    /// Where the strokes of a multi-stroke contact turn \[s\] ([`GroundTruth::turns_s`]).
    pub(super) turns_s: Vec<f64>,
    /// The steady force of each contact phase \[N\] ([`GroundTruth::phase_forces_n`]).
    pub(super) phase_forces_n: Vec<f64>,
    /// How long the force was held \[s\] ([`GroundTruth::hold_s`]).
    pub(super) hold_s: Option<f64>,
    /// The surface touched.
    pub(super) surface: TruthSurface,
    /// The Coulomb friction coefficient.
    pub(super) friction: f64,
    /// The characteristic applied force \[N\] ([`GroundTruth::force_n`]).
    pub(super) force_n: f64,
}

pub(super) fn generate_at_1khz(skill: StdSkill, seed: u64, variation: &Variation) -> Demonstration {
    let mut rng = SplitMix64::new(seed);
    let tool = tool();
    let Plan {
        phases,
        turns_s,
        phase_forces_n,
        hold_s,
        surface,
        friction,
        force_n,
    } = match skill {
        StdSkill::Slide => sliding::slide(&mut rng),
        StdSkill::Wipe => sliding::wipe(&mut rng, variation),
        StdSkill::Touch => pressing::touch(&mut rng),
        StdSkill::Press => pressing::press(&mut rng),
        StdSkill::Contour => sliding::contour(&mut rng),
        StdSkill::PressHold => pressing::press_hold(&mut rng),
        StdSkill::GuardedMove => pressing::guarded_move(&mut rng),
        StdSkill::DoubleTap => pressing::double_tap(&mut rng),
        StdSkill::SlideThenPress => sliding::slide_then_press(&mut rng),
    };

    // Person and sensor imperfections.
    let tremor = Wobble::new(&mut rng, 0.15e-3, 8.0, 11.0, 3);
    let wander = Wobble::new(&mut rng, 0.4e-3, 0.2, 0.6, 2);
    let wrist = Wobble::new(&mut rng, 0.2f64.to_radians(), 6.0, 9.0, 2);
    let drift = Wobble::new(&mut rng, 0.5f64.to_radians(), 0.1, 0.3, 2);
    let force_noise = 0.15;
    let torque_noise = 0.004;
    let bias = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.2;
    let torque_bias = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.005;

    let dt = 1.0 / RATE_HZ;
    let mut samples = Vec::new();
    let mut segments = Vec::new();
    let mut t0 = 0.0;
    let mut previous_tip: Option<Vector3<f64>> = None;
    let mut peak = (0.0f64, 0.0f64);
    for phase in &phases {
        let n = (phase.duration_s * RATE_HZ).round() as usize;
        let start_s = t0;
        for k in 0..n {
            let t = t0 + k as f64 * dt;
            let u = k as f64 / n as f64;
            let state = (phase.state)(u, t);
            let in_contact = state.normal_force > 0.0;
            // In contact, static friction holds the tip against the hand's tremor: the tremor
            // shows in the force instead, and only the intended path slides.
            let shake = if in_contact {
                Vector3::zeros()
            } else {
                tremor.at(t) + wander.at(t)
            };
            let tip = state.position + shake;
            let velocity = previous_tip.map_or(Vector3::zeros(), |p| (tip - p) / dt);
            previous_tip = Some(tip);
            let tangential = velocity - state.normal * state.normal.dot(&velocity);
            let friction_force = -tangential * (friction * state.normal_force / tangential.norm().max(0.005));
            let hand = if in_contact {
                tremor.at(t) * (state.normal_force * 400.0)
            } else {
                Vector3::zeros()
            };
            let force = state.normal * state.normal_force + friction_force + hand;
            if state.normal_force > peak.1 {
                peak = (t, state.normal_force);
            }
            let rotation_vector = wrist.at(t) + drift.at(t);
            let orientation = UnitQuaternion::from_scaled_axis(rotation_vector) * tool.orientation;
            let flange = tip - orientation * tool.tip_in_flange;
            let contact_point = tip - state.normal * TIP_RADIUS_M;
            let torque = (contact_point - flange).cross(&force);
            let noise = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * force_noise;
            let torque_noise_v = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * torque_noise;
            samples.push(Sample {
                t_s: t,
                position_m: flange,
                orientation,
                force_n: force + bias + noise,
                torque_nm: torque + torque_bias + torque_noise_v,
            });
        }
        t0 += n as f64 * dt;
        if phase.label != "rest" {
            segments.push(TruthSegment {
                label: phase.label.to_string(),
                start_s,
                end_s: t0,
            });
        }
    }
    // The rests belong to the neighbouring motion: the first to the approach, the last to the leaving.
    if let Some(first) = segments.first_mut() {
        first.start_s = 0.0;
    }
    if let Some(last) = segments.last_mut() {
        last.end_s = t0 - dt;
    }

    Demonstration {
        samples,
        truth: GroundTruth {
            skill,
            scene: if skill == StdSkill::Wipe && variation.curve_deg > 0.0 {
                "cylinder.toml".to_string()
            } else {
                skill.scene().to_string()
            },
            seed,
            rate_hz: RATE_HZ,
            tip_in_flange_m: tool.tip_in_flange.into(),
            tip_radius_m: TIP_RADIUS_M,
            segments,
            surface,
            force_n,
            peak_time_s: peak.0,
            friction,
            sensor_noise_n: force_noise,
            sensor_bias_n: bias.into(),
            turns_s,
            phase_forces_n,
            hold_s,
        },
    }
}
