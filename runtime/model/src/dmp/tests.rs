//! Ground-truth tests of the DMPs: reproduction, new goals, time scaling, orientation, forces.

use nalgebra::{UnitQuaternion, Vector3};

use super::*;

const TAU: f64 = 10.0;

/// A smooth 3-D path (m) that starts and ends at rest: minimum jerk plus a bump.
fn path(t: f64) -> Vector3<f64> {
    let u = (t / TAU).clamp(0.0, 1.0);
    let min_jerk = 10.0 * u.powi(3) - 15.0 * u.powi(4) + 6.0 * u.powi(5);
    let bump = (std::f64::consts::PI * u).sin() * (3.0 * std::f64::consts::PI * u).sin();
    Vector3::new(0.4, -0.1, 0.3) + Vector3::new(0.3, 0.2, -0.15) * min_jerk + Vector3::new(0.05, -0.03, 0.04) * bump
}

fn demo(rate_hz: f64) -> (Vec<f64>, Vec<Vector3<f64>>) {
    let n = (TAU * rate_hz).round() as usize + 1;
    let t: Vec<f64> = (0..n).map(|k| k as f64 / rate_hz).collect();
    let p = t.iter().map(|&t| path(t)).collect();
    (t, p)
}

fn rms_error(dmp: &Dmp, dt: f64) -> f64 {
    let out = dmp.reproduce(dt, TAU);
    let sum: f64 = out
        .iter()
        .enumerate()
        .map(|(k, x)| (Vector3::new(x[0], x[1], x[2]) - path(k as f64 * dt)).norm_squared())
        .sum();
    (sum / out.len() as f64).sqrt()
}

#[test]
fn reproduces_smooth_10s_demo_under_1mm_with_50_bases_lwr_and_ridge() {
    let (t, p) = demo(1000.0);
    let ridge = Dmp::fit_points(&DmpConfig::default(), &t, &p).expect("valid demo");
    let lwr_config = DmpConfig {
        regression: Regression::Lwr,
        ..DmpConfig::default()
    };
    let lwr = Dmp::fit_points(&lwr_config, &t, &p).expect("valid demo");
    let (rms_ridge, rms_lwr) = (rms_error(&ridge, 1e-3), rms_error(&lwr, 1e-3));
    eprintln!(
        "reproduction RMS at 50 bases: ridge {:.4} mm, lwr {:.4} mm",
        rms_ridge * 1e3,
        rms_lwr * 1e3
    );
    assert!(rms_ridge < 1e-3, "ridge rms {rms_ridge}");
    // LWR fits each weight on its own: 1.08 mm with `width_factor` 1, 0.55 mm with the default 2.
    assert!(rms_lwr < 1e-3, "lwr rms {rms_lwr}");
    assert!(
        rms_ridge <= rms_lwr,
        "ridge {rms_ridge} should not be worse than lwr {rms_lwr}"
    );
}

#[test]
fn irregular_100hz_demo_reproduces_at_any_dt() {
    let n = 1001;
    // Jittered sampling around 100 Hz.
    let t: Vec<f64> = (0..n)
        .map(|k| {
            let jitter = if k == 0 || k == n - 1 {
                0.0
            } else {
                0.003 * (((k * 37) % 11) as f64 / 10.0 - 0.5)
            };
            (k as f64 * 0.01 + jitter).min(TAU)
        })
        .collect();
    let p: Vec<Vector3<f64>> = t.iter().map(|&t| path(t)).collect();
    let dmp = Dmp::fit_points(&DmpConfig::default(), &t, &p).expect("valid demo");
    for dt in [1e-3, 4e-3, 0.02, 0.1] {
        let rms = rms_error(&dmp, dt);
        assert!(rms < 1e-3, "dt {dt}: rms {rms}");
    }
}

#[test]
fn new_goal_is_reached_and_shape_is_kept() {
    let (t, p) = demo(1000.0);
    let dmp = Dmp::fit_points(&DmpConfig::default(), &t, &p).expect("valid demo");
    let offset = Vector3::new(0.05, -0.08, 0.03);
    let goal = path(TAU) + offset;
    let mut rollout = dmp.rollout();
    rollout.set_goal(goal.as_slice()).expect("3 channels");
    let dt = 1e-3;
    let steps = (3.0 * TAU / dt) as usize;
    let mut original = dmp.rollout();
    let mut previous_fraction = 0.0;
    for step in 0..steps {
        rollout.step(&dmp, dt);
        original.step(&dmp, dt);
        // The deformation is the response of a critically damped system to a monotone input:
        // it grows monotonically from 0 to the offset and stays parallel to it.
        let diff = Vector3::from_column_slice(rollout.position()) - Vector3::from_column_slice(original.position());
        let fraction = diff.dot(&offset) / offset.norm_squared();
        assert!(
            (diff - offset * fraction).norm() < 1e-9,
            "step {step}: deformation leaves the offset direction"
        );
        assert!(
            fraction >= previous_fraction - 1e-12 && fraction <= 1.0 + 1e-9,
            "step {step}: fraction {fraction}"
        );
        previous_fraction = fraction;
    }
    let end = Vector3::from_column_slice(rollout.position());
    assert!(
        (end - goal).norm() < 1e-3,
        "ends {} m from the new goal",
        (end - goal).norm()
    );
}

#[test]
fn tau_scales_time() {
    let (t, p) = demo(1000.0);
    let dmp = Dmp::fit_points(&DmpConfig::default(), &t, &p).expect("valid demo");
    let mut slow = dmp.rollout();
    slow.set_tau(2.0 * TAU).expect("positive");
    let dt = 1e-3;
    let normal = dmp.reproduce(dt, TAU);
    let mut max_error: f64 = 0.0;
    for expected in &normal[1..] {
        slow.step(&dmp, dt);
        slow.step(&dmp, dt);
        let x = slow.position();
        max_error = max_error.max((0..3).map(|c| (x[c] - expected[c]).abs()).fold(0.0, f64::max));
    }
    assert!(max_error < 1e-4, "x_slow(2t) differs from x(t) by {max_error} m");
}

#[test]
fn goal_and_tau_change_while_running() {
    let (t, p) = demo(1000.0);
    let dmp = Dmp::fit_points(&DmpConfig::default(), &t, &p).expect("valid demo");
    let mut rollout = dmp.rollout();
    let goal = path(TAU) + Vector3::new(0.0, 0.0, -0.1);
    for step in 0..20_000 {
        if step == 3000 {
            rollout.set_goal(goal.as_slice()).expect("3 channels");
            rollout.set_tau(0.8 * TAU).expect("positive");
        }
        rollout.step(&dmp, 1e-3);
    }
    let end = Vector3::from_column_slice(rollout.position());
    assert!(
        (end - goal).norm() < 1e-3,
        "ends {} m from the changed goal",
        (end - goal).norm()
    );
    let mut velocity = [0.0; 3];
    rollout.velocity_into(&mut velocity);
    assert!(velocity.iter().all(|v| v.abs() < 1e-3), "still moving: {velocity:?}");
}

fn orientation_path(t: f64) -> UnitQuaternion<f64> {
    let u = t / TAU;
    let smooth = 10.0 * u.powi(3) - 15.0 * u.powi(4) + 6.0 * u.powi(5);
    UnitQuaternion::from_euler_angles(
        0.3 + 1.2 * smooth,
        -0.4 * smooth,
        2.5 * smooth + 0.3 * (std::f64::consts::PI * u).sin().powi(2),
    )
}

#[test]
fn quaternion_dmp_reproduces_orientation_and_reaches_new_goal() {
    let n = 10_001;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
    // Flip every other sample's sign: the log map must not care.
    let q: Vec<UnitQuaternion<f64>> = t
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            let q = orientation_path(t);
            if k % 2 == 0 {
                q
            } else {
                UnitQuaternion::new_unchecked(-q.into_inner())
            }
        })
        .collect();
    let dmp = QuatDmp::fit(&DmpConfig::default(), &t, &q).expect("valid demo");
    let out = dmp.reproduce(1e-3, TAU);
    let rms = (out
        .iter()
        .enumerate()
        .map(|(k, q)| q.angle_to(&orientation_path(k as f64 * 1e-3)).powi(2))
        .sum::<f64>()
        / out.len() as f64)
        .sqrt();
    assert!(rms.to_degrees() < 0.1, "orientation rms {} deg", rms.to_degrees());

    let goal = UnitQuaternion::from_euler_angles(0.2, 0.3, -0.5) * dmp.goal;
    let mut rollout = dmp.rollout();
    rollout.set_goal(goal);
    for _ in 0..30_000 {
        rollout.step(&dmp, 1e-3);
    }
    assert!(rollout.orientation().angle_to(&goal).to_degrees() < 0.05);
    assert!(rollout.angular_velocity().norm() < 1e-3);
}

#[test]
fn force_dmp_reproduces_a_press_profile() {
    let t: Vec<f64> = (0..2001).map(|k| k as f64 * 1e-3).collect();
    // Starts and ends at rest (a DMP starts with zero velocity).
    let profile = |t: f64| {
        -12.0 * (std::f64::consts::PI * t / 2.0).sin().powi(2) - 3.0 * (std::f64::consts::PI * t).sin().powi(2)
    };
    let values: Vec<f64> = t.iter().map(|&t| profile(t)).collect();
    let dmp = fit_scalar(&DmpConfig::default(), &t, &values).expect("valid profile");
    let out = dmp.reproduce(1e-3, 2.0);
    let max_error = out
        .iter()
        .enumerate()
        .map(|(k, f)| (f[0] - profile(k as f64 * 1e-3)).abs())
        .fold(0.0, f64::max);
    assert!(max_error < 0.05, "force error {max_error} N");
    let forces: Vec<Vector3<f64>> = values.iter().map(|&f| Vector3::new(0.1 * f, 0.0, f)).collect();
    let dmp3 = fit_force(&DmpConfig::default(), &t, &forces).expect("valid profile");
    assert_eq!(dmp3.n_dims(), 3);
}

#[test]
fn bad_inputs_are_errors() {
    let t = [0.0, 0.1, 0.1, 0.3];
    let x = [0.0, 1.0, 2.0, 3.0];
    assert!(matches!(
        Dmp::fit(&DmpConfig::default(), &t, &[&x]),
        Err(DmpError::TimeNotIncreasing { index: 2 })
    ));
    assert!(matches!(
        Dmp::fit(&DmpConfig::default(), &t[..2], &[&x[..2]]),
        Err(DmpError::TooFewSamples { .. })
    ));
    let t = [0.0, 0.1, 0.2, 0.3];
    assert!(matches!(
        Dmp::fit(&DmpConfig::default(), &t, &[&x[..3]]),
        Err(DmpError::LengthMismatch { .. })
    ));
    let nan = [0.0, f64::NAN, 2.0, 3.0];
    assert!(matches!(
        Dmp::fit(&DmpConfig::default(), &t, &[&nan]),
        Err(DmpError::NonFinite { index: 1, .. })
    ));
    let config = DmpConfig {
        n_basis: 1,
        ..DmpConfig::default()
    };
    assert!(matches!(
        Dmp::fit(&config, &t, &[&x]),
        Err(DmpError::InvalidConfig { name: "n_basis", .. })
    ));
    let dmp = Dmp::fit(&DmpConfig::default(), &t, &[&x]).expect("valid");
    let mut rollout = dmp.rollout();
    assert!(matches!(
        rollout.set_goal(&[1.0, 2.0]),
        Err(DmpError::LengthMismatch { .. })
    ));
    assert!(rollout.set_tau(-1.0).is_err());
}

#[test]
fn dmp_round_trips_through_json() {
    let (t, p) = demo(100.0);
    let dmp = Dmp::fit_points(&DmpConfig::default(), &t, &p).expect("valid demo");
    let json = serde_json::to_string(&dmp).expect("serialisable");
    let mut back: Dmp = serde_json::from_str(&json).expect("deserialisable");
    assert_eq!(back.weights.len(), 3);
    back.validate().expect("consistent");
    // A hand-edited file with a missing weight is rejected, and its rollout does not panic.
    back.weights[1].pop();
    assert!(matches!(
        back.validate(),
        Err(DmpError::LengthMismatch { what: "weights", .. })
    ));
    let mut rollout = back.rollout();
    rollout.step(&back, 1e-3);
    assert_eq!(rollout.position(), back.start.as_slice());
    assert!((back.tau_s - dmp.tau_s).abs() < 1e-12);
}

/// A deterministic generator for the random-data test (no dependency).
fn uniform(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// The fit written the plain way: every basis at every sample through libm's `exp` (no
/// cutoff), the derivatives by `fit::derivatives`, dense `Φ`, and the ridge normal equations
/// or LWR's ratios.
fn reference_weights(config: &DmpConfig, t_s: &[f64], channels: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = t_s.len();
    let times: Vec<f64> = t_s.iter().map(|t| t - t_s[0]).collect();
    let tau = times[n - 1];
    let basis = Basis::new(config.n_basis, config.alpha_s, config.width_factor);
    let nb = basis.len();
    let phases: Vec<f64> = times.iter().map(|t| (-config.alpha_s * t / tau).exp()).collect();
    let psi = |s: f64| -> Vec<f64> {
        (0..nb)
            .map(|i| (-basis.widths[i] * (s - basis.centers[i]).powi(2)).exp())
            .collect()
    };
    let (k, d) = (config.stiffness, config.damping());
    channels
        .iter()
        .map(|x| {
            let (mut dx, mut ddx) = (vec![0.0; n], vec![0.0; n]);
            super::fit::derivatives(&times, x, &mut dx, &mut ddx);
            let (x0, g) = (x[0], x[n - 1]);
            let f: Vec<f64> = (0..n)
                .map(|t| (tau * tau * ddx[t] + d * tau * dx[t]) / k - (g - x[t]) + (g - x0) * phases[t])
                .collect();
            match config.regression {
                Regression::Lwr => (0..nb)
                    .map(|i| {
                        let (mut num, mut den) = (0.0, 0.0);
                        for (t, &s) in phases.iter().enumerate() {
                            let p = psi(s)[i];
                            num += p * s * f[t];
                            den += p * s * s;
                        }
                        num / den
                    })
                    .collect(),
                Regression::Ridge { lambda } => {
                    let phi = nalgebra::DMatrix::from_fn(n, nb, |t, i| {
                        let values = psi(phases[t]);
                        values[i] * phases[t] / values.iter().sum::<f64>()
                    });
                    let mut gram = phi.transpose() * &phi;
                    let trace = gram.trace();
                    for i in 0..nb {
                        gram[(i, i)] += (lambda + 1e-14) * trace / nb as f64;
                    }
                    let rhs = phi.transpose() * nalgebra::DVector::from_column_slice(&f);
                    gram.cholesky()
                        .expect("positive definite")
                        .solve(&rhs)
                        .as_slice()
                        .to_vec()
                }
            }
        })
        .collect()
}

#[test]
fn fast_fit_agrees_with_the_plain_computation_on_random_data() {
    // The fit evaluates only the bases above exp(−25) of the nearest one, in fixed lanes, with
    // its own exp (within 2 ulp of libm's); the plain computation takes every basis.
    let mut state = 15u64;
    let mut worst: f64 = 0.0;
    for case in 0..12 {
        let n = 20 + (uniform(&mut state) * 1500.0) as usize;
        let mut t = vec![0.3 * uniform(&mut state)];
        for _ in 1..n {
            let last = t[t.len() - 1];
            t.push(last + 1e-3 * (0.2 + uniform(&mut state)));
        }
        let channels: Vec<Vec<f64>> = (0..1 + case % 3)
            .map(|_| {
                let mut x = 0.0;
                (0..n)
                    .map(|_| {
                        x += 1e-3 * (uniform(&mut state) - 0.5);
                        x
                    })
                    .collect()
            })
            .collect();
        let config = DmpConfig {
            n_basis: 2 + (uniform(&mut state) * 60.0) as usize,
            width_factor: if case < 4 { 2.0 } else { 0.3 + 5.0 * uniform(&mut state) },
            alpha_s: 0.5 + 6.0 * uniform(&mut state),
            regression: if case % 2 == 0 {
                Regression::Ridge { lambda: 1e-6 }
            } else {
                Regression::Lwr
            },
            ..DmpConfig::default()
        };
        let refs: Vec<&[f64]> = channels.iter().map(Vec::as_slice).collect();
        let fast = Dmp::fit(&config, &t, &refs).expect("valid");
        let plain = reference_weights(&config, &t, &channels);
        for (fast, plain) in fast.weights.iter().zip(&plain) {
            let scale = plain.iter().fold(0.0f64, |m, w| m.max(w.abs()));
            for (a, b) in fast.iter().zip(plain) {
                let difference = (a - b).abs() / scale;
                worst = worst.max(difference);
                assert!(difference < 1e-9, "case {case}: {a} vs {b} (scale {scale})");
            }
        }
    }
    eprintln!("largest difference from the plain fit: {worst:.1e} of the largest weight");
}
