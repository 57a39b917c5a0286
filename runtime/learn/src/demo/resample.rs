//! Resampling a demonstration to a fixed rate.

use super::{Demo, DemoError};

/// Resamples `demo` to `rate_hz`, starting at its first sample and ending at or before its last.
///
/// Positions, forces and torques are interpolated linearly, orientations by slerp. Works for
/// irregularly sampled input.
pub fn resample(demo: &Demo, rate_hz: f64) -> Result<Demo, DemoError> {
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(DemoError::InvalidParameter {
            name: "resample_hz",
            value: rate_hz,
            reason: "the rate must be a positive number of hertz".to_owned(),
        });
    }
    if demo.len() < 2 {
        return Err(DemoError::TooFewSamples {
            file: demo.source.clone(),
            found: demo.len(),
            required: 2,
        });
    }
    let t0 = demo.t_s[0];
    let duration = demo.duration_s();
    let n_out_f = (duration * rate_hz + 1e-9).floor() + 1.0;
    if n_out_f > 1e8 {
        return Err(DemoError::InvalidParameter {
            name: "resample_hz",
            value: rate_hz,
            reason: format!("would produce {n_out_f:.0} samples (at most 1e8)"),
        });
    }
    let n_out = n_out_f as usize;
    let mut out = Demo {
        source: demo.source.clone(),
        t_s: Vec::with_capacity(n_out),
        position_m: Vec::with_capacity(n_out),
        orientation: Vec::with_capacity(n_out),
        force_n: Vec::with_capacity(n_out),
        torque_nm: Vec::with_capacity(n_out),
    };
    let mut seg = 0usize;
    for k in 0..n_out {
        let t = (t0 + k as f64 / rate_hz).min(demo.t_s[demo.len() - 1]);
        while seg + 2 < demo.len() && demo.t_s[seg + 1] < t {
            seg += 1;
        }
        let (ta, tb) = (demo.t_s[seg], demo.t_s[seg + 1]);
        let u = ((t - ta) / (tb - ta)).clamp(0.0, 1.0);
        out.t_s.push(t);
        out.position_m
            .push(demo.position_m[seg].lerp(&demo.position_m[seg + 1], u));
        out.orientation
            .push(demo.orientation[seg].slerp(&demo.orientation[seg + 1], u));
        out.force_n.push(demo.force_n[seg].lerp(&demo.force_n[seg + 1], u));
        out.torque_nm
            .push(demo.torque_nm[seg].lerp(&demo.torque_nm[seg + 1], u));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use nalgebra::{UnitQuaternion, Vector3};

    use super::*;

    fn irregular_demo() -> Demo {
        let t_s: Vec<f64> = (0..200)
            .map(|k| 0.01 * k as f64 + 0.003 * ((k * 7 % 5) as f64 - 2.0) * f64::from(k > 0 && k < 199))
            .collect();
        Demo {
            source: "synthetic".into(),
            position_m: t_s.iter().map(|&t| Vector3::new(2.0 * t, -t, 0.5)).collect(),
            orientation: t_s
                .iter()
                .map(|&t| UnitQuaternion::from_euler_angles(0.0, 0.0, t))
                .collect(),
            force_n: t_s.iter().map(|&t| Vector3::new(0.0, 0.0, 3.0 * t)).collect(),
            torque_nm: t_s.iter().map(|_| Vector3::zeros()).collect(),
            t_s,
        }
    }

    #[test]
    fn resampling_linear_signals_is_exact() {
        let demo = irregular_demo();
        let out = resample(&demo, 1000.0).expect("valid rate");
        assert_eq!(out.len(), 1991);
        for k in 0..out.len() {
            let t = out.t_s[k];
            assert!((out.t_s[k] - k as f64 * 1e-3).abs() < 1e-9);
            assert!((out.position_m[k] - Vector3::new(2.0 * t, -t, 0.5)).norm() < 1e-12);
            assert!((out.force_n[k].z - 3.0 * t).abs() < 1e-12);
            assert!(out.orientation[k].angle_to(&UnitQuaternion::from_euler_angles(0.0, 0.0, t)) < 1e-9);
        }
    }

    #[test]
    fn bad_rate_is_rejected() {
        assert!(matches!(
            resample(&irregular_demo(), 0.0),
            Err(DemoError::InvalidParameter { .. })
        ));
        assert!(matches!(
            resample(&irregular_demo(), f64::NAN),
            Err(DemoError::InvalidParameter { .. })
        ));
    }
}
