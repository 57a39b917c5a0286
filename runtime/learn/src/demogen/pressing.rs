//! The skills that come down onto a spot: the touch, the press of the button, the press and hold,
//! the guarded move, and the double tap.

use nalgebra::Vector3;
use std::f64::consts::PI;

use super::person::{
    min_jerk, moving, pressing, rest, touch_down_lift_off, warp, warp_of, Phase, TipState, CONTACT_Z_M,
};
use super::record::Plan;
use super::{TruthSurface, SURFACE_Z_M};
use crate::rng::SplitMix64;

/// Touch the table and come back.
pub(super) fn touch(rng: &mut SplitMix64) -> Plan {
    let mut phases: Vec<Phase> = Vec::new();
    let up = Vector3::z();
    let friction = 0.4;
    let peak = 4.0;
    let force_n = peak;
    let hover = Vector3::new(0.5466, 0.0, 0.37);
    let contact = Vector3::new(0.5466, 0.0, CONTACT_Z_M);
    let back = Vector3::new(0.5466, 0.02, 0.37);
    let (w1, w2) = (warp_of(rng), warp_of(rng));
    let (rise, fall) = (rng.range(0.08, 0.1), rng.range(0.1, 0.12));
    phases.push(rest(hover));
    phases.push(moving("approach", rng.range(2.0, 2.3), hover, contact, w1));
    phases.push(Phase {
        label: "touch",
        duration_s: rise + fall,
        state: Box::new(move |u, _t| {
            let local = u * (rise + fall);
            let force = if local < rise {
                peak * 0.5 * (1.0 - (PI * local / rise).cos())
            } else {
                peak * 0.5 * (1.0 + (PI * (local - rise) / fall).cos())
            };
            TipState {
                position: contact,
                normal: up,
                normal_force: force,
            }
        }),
    });
    phases.push(moving("return", rng.range(1.9, 2.2), contact, back, w2));
    phases.push(rest(back));
    let surface = TruthSurface::Plane {
        point_m: [0.5466, 0.0, SURFACE_Z_M],
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

/// Press the spring-loaded button.
pub(super) fn press(rng: &mut SplitMix64) -> Plan {
    let mut phases: Vec<Phase> = Vec::new();
    let up = Vector3::z();
    let friction = 0.6;
    let peak = 8.0;
    let force_n = peak;
    // The button of `button.toml`: 2 N preload, 400 N/m, 8 mm of travel.
    let (preload, stiffness, travel) = (2.0, 400.0, 0.008);
    let hover = Vector3::new(0.5466, 0.0, 0.37);
    let contact = Vector3::new(0.5466, 0.0, CONTACT_Z_M);
    let back = Vector3::new(0.5466, -0.02, 0.37);
    let (w1, w2) = (warp_of(rng), warp_of(rng));
    let (rise, hold, release) = (rng.range(0.8, 1.0), rng.range(0.7, 0.9), rng.range(0.9, 1.1));
    let total = rise + hold + release;
    let wobble_phase = rng.range(0.0, 2.0 * PI);
    phases.push(rest(hover));
    phases.push(moving("approach", rng.range(1.9, 2.2), hover, contact, w1));
    phases.push(Phase {
        label: "press",
        duration_s: total,
        state: Box::new(move |u, t| {
            let local = u * total;
            let mut force = if local < rise {
                peak * min_jerk(local / rise)
            } else if local < rise + hold {
                peak * (1.0 + 0.03 * (2.0 * PI * 1.3 * t + wobble_phase).sin())
            } else {
                peak * (1.0 - min_jerk((local - rise - hold) / release))
            };
            force = force.max(0.0);
            let depth = ((force - preload) / stiffness).clamp(0.0, travel);
            TipState {
                position: contact - up * depth,
                normal: up,
                normal_force: force,
            }
        }),
    });
    phases.push(moving("retract", rng.range(1.5, 1.8), contact, back, w2));
    phases.push(rest(back));
    let surface = TruthSurface::Plane {
        point_m: [0.5466, 0.0, SURFACE_Z_M],
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

/// Press the table to a force, hold it for 2 s, release and retract.
pub(super) fn press_hold(rng: &mut SplitMix64) -> Plan {
    let mut phases: Vec<Phase> = Vec::new();
    let up = Vector3::z();
    let friction = 0.5;
    let level = 12.0;
    let force_n = level;
    let hover = Vector3::new(0.5466, 0.0, 0.37);
    let contact = Vector3::new(0.5466, 0.0, CONTACT_Z_M);
    let back = Vector3::new(0.5466, 0.02, 0.37);
    let (w1, w2) = (warp_of(rng), warp_of(rng));
    // A person leans in over a few tenths of a second, holds the force as steadily as a
    // hand can (±3 % at about 1 Hz) for the 2 s asked, and lets go a little faster.
    let (rise, release) = (rng.range(0.35, 0.45), rng.range(0.25, 0.35));
    let hold = 2.0;
    let hold_s = Some(hold);
    let total = rise + hold + release;
    let wobble_phase = rng.range(0.0, 2.0 * PI);
    phases.push(rest(hover));
    phases.push(moving("approach", rng.range(1.9, 2.2), hover, contact, w1));
    phases.push(Phase {
        label: "press_hold",
        duration_s: total,
        state: Box::new(move |u, t| {
            let local = u * total;
            let force = if local < rise {
                level * min_jerk(local / rise)
            } else if local < rise + hold {
                level * (1.0 + 0.03 * (2.0 * PI * 0.9 * t + wobble_phase).sin())
            } else {
                level * (1.0 - min_jerk((local - rise - hold) / release))
            };
            TipState {
                position: contact,
                normal: up,
                normal_force: force.max(0.0),
            }
        }),
    });
    phases.push(moving("retract", rng.range(1.5, 1.8), contact, back, w2));
    phases.push(rest(back));
    let surface = TruthSurface::Plane {
        point_m: [0.5466, 0.0, SURFACE_Z_M],
        normal: [0.0, 0.0, 1.0],
    };
    Plan {
        phases,
        turns_s: Vec::new(),
        phase_forces_n: Vec::new(),
        hold_s,
        surface,
        friction,
        force_n,
    }
}

/// Move down to the table and stop there in light contact (the recording ends in contact).
pub(super) fn guarded_move(rng: &mut SplitMix64) -> Plan {
    let mut phases: Vec<Phase> = Vec::new();
    let up = Vector3::z();
    let friction = 0.4;
    let level = 3.0;
    let force_n = level;
    let start = Vector3::new(0.5466, 0.0, 0.37);
    let goal = Vector3::new(0.60, 0.07, CONTACT_Z_M);
    let w1 = warp_of(rng);
    let move_s = rng.range(2.6, 3.0);
    let hold_phase = rng.range(0.0, 2.0 * PI);
    phases.push(rest(start));
    // Across first, then down: the sideways travel ends before the tool meets the table,
    // which it meets nearly straight down (a person lowers a tool onto a surface).
    phases.push(Phase {
        label: "move",
        duration_s: move_s,
        state: Box::new(move |u, _t| {
            let across = min_jerk(warp((u / 0.85).clamp(0.0, 1.0), w1));
            let down = min_jerk(((u - 0.25) / 0.75).clamp(0.0, 1.0));
            let mut position = start + (goal - start) * across;
            position.z = start.z + (goal.z - start.z) * down;
            TipState {
                position,
                normal: up,
                normal_force: 0.0,
            }
        }),
    });
    // The light touch-down and the steady hold; the recording ends in contact.
    let contact_s = rng.range(1.2, 1.4);
    phases.push(Phase {
        label: "contact",
        duration_s: contact_s,
        state: Box::new(move |u, t| TipState {
            position: goal,
            normal: up,
            normal_force: pressing(u * contact_s, f64::INFINITY, level, t, hold_phase),
        }),
    });
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

/// Tap the table twice, at two spots 5 cm apart, with a hop between the taps.
pub(super) fn double_tap(rng: &mut SplitMix64) -> Plan {
    let mut phases: Vec<Phase> = Vec::new();
    let up = Vector3::z();
    let friction = 0.4;
    let (first, second) = (5.0, 6.0);
    let force_n = first;
    let phase_forces_n = vec![first, second];
    let hover = Vector3::new(0.52, -0.05, 0.37);
    let spot1 = Vector3::new(0.52, -0.02, CONTACT_Z_M);
    let spot2 = Vector3::new(0.56, 0.01, CONTACT_Z_M);
    let leave = Vector3::new(0.58, 0.03, 0.37);
    let (w1, w2, w3) = (warp_of(rng), warp_of(rng), warp_of(rng));
    let wobble_phase = rng.range(0.0, 2.0 * PI);
    // A tap: down, a short press at a steady force (long enough to be a tap one means,
    // half a second), up.
    let tap = |label: &'static str, at: Vector3<f64>, level: f64, duration_s: f64| Phase {
        label,
        duration_s,
        state: Box::new(move |u, t| TipState {
            position: at,
            normal: up,
            normal_force: touch_down_lift_off(u * duration_s, duration_s, level)
                * (1.0 + 0.03 * (2.0 * PI * 1.1 * t + wobble_phase).sin()),
        }),
    };
    phases.push(rest(hover));
    phases.push(moving("approach", rng.range(1.8, 2.1), hover, spot1, w1));
    phases.push(tap("tap", spot1, first, rng.range(0.55, 0.65)));
    // The hop: up 2.5 cm nearly straight, across, and down nearly straight onto the
    // second spot.
    let height = 0.025;
    phases.push(Phase {
        label: "hop",
        duration_s: rng.range(1.1, 1.3),
        state: Box::new(move |u, _t| {
            let across = min_jerk(warp(((u - 0.15) / 0.7).clamp(0.0, 1.0), w2));
            let lift = if u < 0.5 {
                min_jerk(u / 0.4)
            } else {
                1.0 - min_jerk((u - 0.55) / 0.45)
            };
            let mut position = spot1 + (spot2 - spot1) * across;
            position.z += height * lift;
            TipState {
                position,
                normal: up,
                normal_force: 0.0,
            }
        }),
    });
    phases.push(tap("tap", spot2, second, rng.range(0.55, 0.65)));
    phases.push(moving("leave", rng.range(1.4, 1.7), spot2, leave, w3));
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
