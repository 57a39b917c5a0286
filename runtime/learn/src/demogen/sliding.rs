//! The skills that slide along a surface in contact: the slide, the wipe, the contour over the
//! drum, and the slide that ends in a press.

use nalgebra::Vector3;
use std::f64::consts::PI;

use super::person::{
    min_jerk, moving, pressing, rest, touch_down_lift_off, warp, warp_of, Phase, TipState, CONTACT_Z_M, REST_S,
};
use super::record::Plan;
use super::{TruthSurface, Variation, SURFACE_Z_M, TIP_RADIUS_M};
use crate::rng::SplitMix64;

/// Slide over the table at a constant force.
pub(super) fn slide(rng: &mut SplitMix64) -> Plan {
    let mut phases: Vec<Phase> = Vec::new();
    let up = Vector3::z();
    let friction = 0.4;
    let f0 = 10.0;
    let force_n = f0;
    let hover = Vector3::new(0.48, -0.08, 0.365);
    let c1 = Vector3::new(0.48, -0.08, CONTACT_Z_M);
    let c2 = Vector3::new(0.62, 0.07, CONTACT_Z_M);
    let leave = Vector3::new(0.64, 0.09, 0.37);
    let (w1, w2, w3) = (warp_of(rng), warp_of(rng), warp_of(rng));
    let slow_phase = rng.range(0.0, 2.0 * PI);
    let settle = 0.25;
    let slide_s = rng.range(4.0, 4.4);
    let contact_s = settle + slide_s + settle;
    phases.push(rest(hover));
    phases.push(moving("approach", rng.range(1.5, 1.8), hover, c1, w1));
    phases.push(Phase {
        label: "slide",
        duration_s: contact_s,
        state: Box::new(move |u, t| {
            let local = u * contact_s;
            let s = ((local - settle) / slide_s).clamp(0.0, 1.0);
            let progress = min_jerk(warp(s, w2));
            let lateral = Vector3::new(0.0, 0.02 * (PI * progress).sin(), 0.0);
            let position = c1 + (c2 - c1) * progress + lateral;
            let force = pressing(local, contact_s, f0, t, slow_phase);
            TipState {
                position,
                normal: up,
                normal_force: force,
            }
        }),
    });
    phases.push(moving("leave", rng.range(1.4, 1.7), c2, leave, w3));
    phases.push(rest(leave));
    let surface = TruthSurface::Plane {
        point_m: [0.55, 0.0, SURFACE_Z_M],
        normal: [0.0, 0.0, 1.0],
    };
    Plan {
        phases,
        turns_s: Vec::new(),
        phase_forces_n: Vec::new(),
        hold_s: None,
        surface,
        friction,
        force_n,
    }
}

/// Wipe the table (or, varied, the drum) back and forth with a constant force: several strokes in
/// one contact, and more passes when the variation asks for them.
pub(super) fn wipe(rng: &mut SplitMix64, variation: &Variation) -> Plan {
    let mut phases: Vec<Phase> = Vec::new();
    let mut turns_s = Vec::new();
    let mut phase_forces_n = Vec::new();
    let up = Vector3::z();
    let friction = 0.4;
    let f0 = 8.0;
    let force_n = f0;
    // A curved part: the drum of `cylinder.toml` (axis along y through (0.5466, ·, 0.15),
    // radius 0.15 m), wiped across its crown.
    let curved = variation.curve_deg > 0.0;
    let drum_centre = Vector3::new(0.5466, 0.0, 0.15);
    let drum_radius = 0.15 + TIP_RADIUS_M;
    let half_arc = variation.curve_deg.min(60.0).to_radians();
    let (first_angle, last_angle) = (-half_arc, half_arc);
    let radial = |angle: f64| Vector3::new(angle.sin(), 0.0, angle.cos());
    let (hover, c1, c2, leave) = if curved {
        let c1 = drum_centre + radial(first_angle) * drum_radius;
        let c2 = drum_centre + radial(last_angle) * drum_radius;
        (c1 + up * 0.06, c1, c2, c1 + Vector3::new(0.02, 0.02, 0.065))
    } else {
        (
            Vector3::new(0.50, -0.06, 0.365),
            Vector3::new(0.50, -0.06, CONTACT_Z_M),
            Vector3::new(0.60, 0.04, CONTACT_Z_M),
            Vector3::new(0.52, -0.04, 0.37),
        )
    };
    // Where the tip is and the surface's normal there, `along` the stroke (0 at `c1`, 1
    // at `c2`) and `bow` to its side.
    let side = if curved {
        Vector3::y()
    } else {
        Vector3::new(-(c2 - c1).y, (c2 - c1).x, 0.0).normalize()
    };
    let place = move |along: f64, bow: f64| {
        if curved {
            let normal = radial(first_angle + (last_angle - first_angle) * along);
            (drum_centre + normal * drum_radius + side * bow, normal)
        } else {
            (c1 + (c2 - c1) * along + side * bow, up)
        }
    };
    let (w1, w3) = (warp_of(rng), warp_of(rng));
    // Four strokes: out, back, out, back, each with its own timing and a sideways bow
    // (a hand does not retrace its path).
    let draw_strokes = |rng: &mut SplitMix64| -> Vec<(f64, f64, f64)> {
        (0..4)
            .map(|_| (rng.range(0.9, 1.2), warp_of(rng), rng.range(-0.012, 0.012)))
            .collect()
    };
    let strokes = draw_strokes(rng);
    let settle = 0.25;
    let approach_s = rng.range(1.5, 1.8);
    let slow_phase = rng.range(0.0, 2.0 * PI);
    phases.push(rest(hover));
    phases.push(moving("approach", approach_s, hover, c1, w1));
    let mut at = REST_S + approach_s;
    let mut pass = |strokes: Vec<(f64, f64, f64)>, level: f64, at: f64, phases: &mut Vec<Phase>| {
        let wiping_s: f64 = strokes.iter().map(|s| s.0).sum();
        let contact_s = settle + wiping_s + settle;
        let mut turn = at + settle;
        for stroke in &strokes[..strokes.len() - 1] {
            turn += stroke.0;
            turns_s.push(turn);
        }
        phases.push(Phase {
            label: "wipe",
            duration_s: contact_s,
            state: Box::new(move |u, t| {
                let local = u * contact_s;
                let mut begin = settle;
                let mut along = 0.0;
                let mut bow = 0.0;
                for (k, (duration, warp_amount, sway)) in strokes.iter().enumerate() {
                    if local >= begin {
                        let progress = min_jerk(warp(((local - begin) / duration).clamp(0.0, 1.0), *warp_amount));
                        along = if k.is_multiple_of(2) { progress } else { 1.0 - progress };
                        bow = sway * (PI * progress).sin();
                    }
                    begin += duration;
                }
                let (position, normal) = place(along, bow);
                let force = pressing(local, contact_s, level, t, slow_phase);
                TipState {
                    position,
                    normal,
                    normal_force: force,
                }
            }),
        });
        contact_s
    };
    at += pass(strokes, f0, at, &mut phases);
    // More passes (variants only): lift 4 cm, come back down and wipe again, each pass
    // at its own force.
    if variation.passes > 1 {
        phase_forces_n.push(f0);
    }
    for _ in 1..variation.passes {
        let top = c1 + up * 0.04;
        let (lift_s, back_s) = (rng.range(0.8, 1.0), rng.range(0.8, 1.0));
        phases.push(moving("lift", lift_s, c1, top, warp_of(rng)));
        phases.push(moving("return", back_s, top, c1, warp_of(rng)));
        at += lift_s + back_s;
        let strokes = draw_strokes(rng);
        let level = rng.range(6.0, 14.0);
        phase_forces_n.push(level);
        at += pass(strokes, level, at, &mut phases);
    }
    phases.push(moving("leave", rng.range(1.4, 1.7), c1, leave, w3));
    phases.push(rest(leave));
    let surface = if curved {
        TruthSurface::Cylinder {
            axis_point_m: drum_centre.into(),
            axis: [0.0, 1.0, 0.0],
            radius_m: 0.15,
        }
    } else {
        TruthSurface::Plane {
            point_m: [0.55, 0.0, SURFACE_Z_M],
            normal: [0.0, 0.0, 1.0],
        }
    };
    Plan {
        phases,
        turns_s,
        phase_forces_n,
        hold_s: None,
        surface,
        friction,
        force_n,
    }
}

/// Follow the drum's curved surface with a varying force.
pub(super) fn contour(rng: &mut SplitMix64) -> Plan {
    let mut phases: Vec<Phase> = Vec::new();
    let friction = 0.3;
    // The drum of `cylinder.toml`: axis along y through (0.5466, ·, 0.15), radius 0.15 m.
    let centre = Vector3::new(0.5466, 0.0, 0.15);
    let radius = 0.15 + TIP_RADIUS_M;
    let (start_angle, end_angle) = (-30f64.to_radians(), 30f64.to_radians());
    let radial = move |angle: f64| Vector3::new(angle.sin(), 0.0, angle.cos());
    let hover = centre + radial(start_angle) * (radius + 0.06);
    let c1 = centre + radial(start_angle) * radius;
    let c2 = centre + radial(end_angle) * radius;
    let leave = centre + radial(end_angle) * (radius + 0.06);
    let (w1, w2, w3) = (warp_of(rng), warp_of(rng), warp_of(rng));
    let settle = 0.25;
    let follow_s = rng.range(4.8, 5.2);
    let contact_s = settle + follow_s + settle;
    let (base, swing) = (7.0, 3.0);
    // Mean of base + swing·sin(π s) over the contour.
    let force_n = base + swing * 2.0 / PI;
    phases.push(rest(hover));
    phases.push(moving("approach", rng.range(1.5, 1.8), hover, c1, w1));
    phases.push(Phase {
        label: "contour",
        duration_s: contact_s,
        state: Box::new(move |u, _t| {
            let local = u * contact_s;
            let s = ((local - settle) / follow_s).clamp(0.0, 1.0);
            let progress = min_jerk(warp(s, w2));
            let angle = start_angle + (end_angle - start_angle) * progress;
            let normal = radial(angle);
            let mut position = centre + normal * radius;
            position.y = 0.01 * (PI * progress).sin();
            let profile = base + swing * (PI * s).sin();
            let force = touch_down_lift_off(local, contact_s, 1.0) * profile;
            TipState {
                position,
                normal,
                normal_force: force,
            }
        }),
    });
    phases.push(moving("leave", rng.range(1.4, 1.7), c2, leave, w3));
    phases.push(rest(leave));
    let surface = TruthSurface::Cylinder {
        axis_point_m: centre.into(),
        axis: [0.0, 1.0, 0.0],
        radius_m: 0.15,
    };
    Plan {
        phases,
        turns_s: Vec::new(),
        phase_forces_n: Vec::new(),
        hold_s: None,
        surface,
        friction,
        force_n,
    }
}

/// Slide over the table at a light force, press harder where the slide ends, retract.
pub(super) fn slide_then_press(rng: &mut SplitMix64) -> Plan {
    let mut phases: Vec<Phase> = Vec::new();
    let up = Vector3::z();
    let friction = 0.4;
    let (light, firm) = (5.0, 15.0);
    let force_n = light;
    let phase_forces_n = vec![light, firm];
    let hover = Vector3::new(0.48, -0.08, 0.365);
    let c1 = Vector3::new(0.48, -0.08, CONTACT_Z_M);
    let c2 = Vector3::new(0.60, 0.02, CONTACT_Z_M);
    let leave = Vector3::new(0.62, 0.04, 0.37);
    let (w1, w2, w3) = (warp_of(rng), warp_of(rng), warp_of(rng));
    let slow_phase = rng.range(0.0, 2.0 * PI);
    // One slow variation of the hand's force (±4 % at 0.7 Hz) over both contact phases.
    let vary = move |t: f64| 1.0 + 0.04 * (2.0 * PI * 0.7 * t + slow_phase).sin();
    let (settle, pause) = (0.25, 0.15);
    let slide_s = rng.range(3.0, 3.4);
    let sliding_s = settle + slide_s + pause;
    let (ramp, hold, release) = (rng.range(0.35, 0.45), rng.range(0.9, 1.1), rng.range(0.25, 0.35));
    let pressing_s = ramp + hold + release;
    phases.push(rest(hover));
    phases.push(moving("approach", rng.range(1.5, 1.8), hover, c1, w1));
    phases.push(Phase {
        label: "slide",
        duration_s: sliding_s,
        state: Box::new(move |u, t| {
            let local = u * sliding_s;
            let s = ((local - settle) / slide_s).clamp(0.0, 1.0);
            let progress = min_jerk(warp(s, w2));
            let lateral = Vector3::new(0.0, 0.015 * (PI * progress).sin(), 0.0);
            TipState {
                position: c1 + (c2 - c1) * progress + lateral,
                normal: up,
                normal_force: touch_down_lift_off(local, f64::INFINITY, light) * vary(t),
            }
        }),
    });
    // At the slide's end, still: lean in to the firm force, hold it, let go.
    phases.push(Phase {
        label: "press",
        duration_s: pressing_s,
        state: Box::new(move |u, t| {
            let local = u * pressing_s;
            let level = if local < ramp {
                light + (firm - light) * min_jerk(local / ramp)
            } else if local < ramp + hold {
                firm
            } else {
                firm * (1.0 - min_jerk((local - ramp - hold) / release))
            };
            TipState {
                position: c2,
                normal: up,
                normal_force: level * vary(t),
            }
        }),
    });
    phases.push(moving("leave", rng.range(1.4, 1.7), c2, leave, w3));
    phases.push(rest(leave));
    let surface = TruthSurface::Plane {
        point_m: [0.55, 0.0, SURFACE_Z_M],
        normal: [0.0, 0.0, 1.0],
    };
    Plan {
        phases,
        turns_s: Vec::new(),
        phase_forces_n,
        hold_s: None,
        surface,
        friction,
        force_n,
    }
}
