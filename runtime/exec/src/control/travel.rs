//! The stiffness a pressing tool meets, estimated from its own travel, and the velocity a changing
//! desired force asks of the tool against it: the rate feed-forward of a force loop in place.
//!
//! A force-controlled axis of the hybrid law damps the tool's velocity (`−d v`, with `d` the
//! force axis's damping). Against a stiff surface the tool barely moves and the damping costs
//! nothing; against a button's spring (400 N/m) a force rising at `ḟ` moves the tool at
//! `v = ḟ / k`, and the damping takes `d ḟ / k` off what the tool applies: 0.5 N of lag at the
//! shipped press's 5 N/s with the default 40 N s/m. Knowing `k`, the law damps `v − ḟ_d / k`
//! instead, which the travel the force asks for does not pay (docs/method.md §6).
//!
//! `k` is the slope of the applied force on the tool's position along the force axis, fitted by
//! exponentially weighted least squares over the last [`TRAVEL_WINDOW_S`]. The fit is used only
//! while it is known: the tool travelled (the positions' spread is at least [`TRAVEL_MIN_M`]),
//! force rises with depth (a positive slope), and the slope's standard error is at most
//! [`STIFFNESS_MAX_REL_ERROR`] of it. Otherwise there is no feed-forward: the law damps as
//! before. Knowing `k` also bounds how fast a force profile can be followed: the travel its rate
//! asks for may use [`TRAVEL_SPEED_SHARE`] of the force axis's speed limit
//! ([`TravelFeedForward::clock_rate`]). Only a state that presses in place may use it: one that also moves along a path
//! travels along the force axis because the surface's shape does (a contour over a drum), which
//! this fit would take for a soft spring.

/// The time constant of the fit's exponential weights \[s\]: the fit forgets a spring within
/// a few of these once the cap meets its stop (a stiffness twenty times higher, and then no
/// feed-forward), and still averages about a hundred samples of the wrist sensor's noise.
pub const TRAVEL_WINDOW_S: f64 = 0.05;

/// The least spread (standard deviation) of the tool's positions in the window for a fit \[m\]:
/// the tool travels at least about 4 mm/s along the force axis.
pub const TRAVEL_MIN_M: f64 = 2.0e-4;

/// The largest standard error of the fitted stiffness, as a fraction of it, for a fit to be used.
pub const STIFFNESS_MAX_REL_ERROR: f64 = 0.3;

/// The least force the tool applies along the axis for a tick to enter the fit \[N\]; below it the
/// fit is forgotten (see [`TravelFeedForward::update`]).
pub const TRAVEL_CONTACT_N: f64 = 1.0;

/// The least effective number of samples in the window for a fit (20 ms at 1 kHz).
pub const TRAVEL_MIN_SAMPLES: f64 = 20.0;

/// The time constant of the low-pass on the desired force's rate \[s\]: a force profile's clock
/// slows with the force's lag tick by tick (the lag is noisy), and its rate with it.
pub const RATE_FILTER_S: f64 = 0.03;

/// The share of the force axis's speed limit a profile's travel may ask for; the rest is left to
/// the force loop to take up its error.
pub const TRAVEL_SPEED_SHARE: f64 = 0.9;

/// The fit of force on position along one axis, and the desired force's filtered rate.
#[derive(Debug, Clone, PartialEq)]
pub struct TravelFeedForward {
    /// The first position seen, subtracted from every one (the fit works on millimetres of
    /// travel, not on the distance from the base) \[m\].
    origin_m: Option<f64>,
    /// Sum of the weights, and of their squares (for the effective number of samples).
    weight: f64,
    weight_sq: f64,
    /// Weighted sums of `p`, `f`, `p²`, `p f`, `f²`.
    sums: [f64; 5],
    /// The last desired force and when it was commanded \[N, s\].
    last_desired: Option<(f64, f64)>,
    /// The desired force's rate, low-passed \[N/s\].
    rate_n_per_s: f64,
    /// The force axis's speed limit last given \[m/s\].
    limit_mps: f64,
}

impl Default for TravelFeedForward {
    fn default() -> Self {
        Self::new()
    }
}

impl TravelFeedForward {
    /// An estimate with nothing seen yet.
    pub fn new() -> Self {
        TravelFeedForward {
            origin_m: None,
            weight: 0.0,
            weight_sq: 0.0,
            sums: [0.0; 5],
            last_desired: None,
            rate_n_per_s: 0.0,
            limit_mps: f64::INFINITY,
        }
    }

    /// Takes one tick's measurement: the tool's position along the force axis `position_m`
    /// (positive into what it pushes), the force it applies along that axis `applied_n`, and the
    /// force it is asked for `desired_n`, at time `t_s`. A tick that repeats or goes back in time
    /// is ignored.
    pub fn update(&mut self, t_s: f64, position_m: f64, applied_n: f64, desired_n: f64) {
        if !(t_s.is_finite() && position_m.is_finite() && applied_n.is_finite() && desired_n.is_finite()) {
            return;
        }
        let Some((t_last, desired_last)) = self.last_desired else {
            self.last_desired = Some((t_s, desired_n));
            self.origin_m = Some(position_m);
            return;
        };
        let dt = t_s - t_last;
        if dt <= 0.0 {
            return;
        }
        let raw_rate = (desired_n - desired_last) / dt;
        let blend = 1.0 - (-dt / RATE_FILTER_S).exp();
        self.rate_n_per_s += blend * (raw_rate - self.rate_n_per_s);
        self.last_desired = Some((t_s, desired_n));

        // Exponential weights: each sample weighs `α = 1 − e^(−dt/τ)` when it comes and loses
        // `1 − α` of its weight per tick after. The means divide by the weights' sum, so they
        // are unbiased from the first sample on.
        if applied_n < TRAVEL_CONTACT_N {
            // Out of contact, the force does not depend on the position: what was fitted was
            // a contact being left, not a spring to feed forward against.
            self.forget();
            return;
        }
        let alpha = 1.0 - (-dt / TRAVEL_WINDOW_S).exp();
        let keep = 1.0 - alpha;
        let p = position_m - self.origin_m.unwrap_or(position_m);
        let f = applied_n;
        self.weight = keep * self.weight + alpha;
        self.weight_sq = keep * keep * self.weight_sq + alpha * alpha;
        for (sum, value) in self.sums.iter_mut().zip([p, f, p * p, p * f, f * f]) {
            *sum = keep * *sum + alpha * value;
        }
    }

    /// Forgets the fit (not the force rate): no stiffness is known until the window fills again.
    fn forget(&mut self) {
        self.weight = 0.0;
        self.weight_sq = 0.0;
        self.sums = [0.0; 5];
    }

    /// The stiffness the tool meets along the axis \[N/m\], when the window's fit knows it (see
    /// the module's rules); `None` while the tool has not travelled, the slope is not positive or
    /// it is too uncertain.
    pub fn stiffness(&self) -> Option<f64> {
        if self.effective_samples() < TRAVEL_MIN_SAMPLES {
            return None;
        }
        let [p, f, pp, pf, ff] = self.sums.map(|s| s / self.weight);
        let var_p = pp - p * p;
        let var_f = ff - f * f;
        let cov = pf - p * f;
        if var_p <= TRAVEL_MIN_M * TRAVEL_MIN_M || cov <= 0.0 {
            return None;
        }
        let slope = cov / var_p;
        // Residual variance of the force about the fitted line, and the slope's standard error
        // with the window's effective number of independent samples.
        let residual = (var_f - slope * cov).max(0.0);
        let effective = self.effective_samples();
        let error = (residual / (var_p * (effective - 2.0).max(1.0))).sqrt();
        (error <= STIFFNESS_MAX_REL_ERROR * slope).then_some(slope)
    }

    /// The desired force's rate, low-passed \[N/s\].
    pub fn force_rate(&self) -> f64 {
        self.rate_n_per_s
    }

    /// The velocity along the axis that the desired force's rate asks of the tool against the
    /// stiffness it meets, `ḟ_d / k` \[m/s\] (positive into what it pushes), at most `limit_mps`
    /// either way; zero while the stiffness is not known.
    pub fn velocity(&self, limit_mps: f64) -> f64 {
        let limit = limit_mps.max(0.0);
        match self.stiffness() {
            Some(k) => (self.rate_n_per_s / k).clamp(-limit, limit),
            None => 0.0,
        }
    }

    /// The window's effective number of samples, `(Σw)² / Σw²`: the count so far at first, then
    /// `(2 − α) / α`, about `2 τ / dt` (100 at 1 kHz).
    /// Notes the force axis's speed limit, which bounds the travel and so the rate a force
    /// profile can be followed at ([`TravelFeedForward::clock_rate`]).
    pub fn set_speed_limit(&mut self, limit_mps: f64) {
        self.limit_mps = limit_mps.max(0.0);
    }

    /// How fast a force profile's clock may run when at full clock its force would change at
    /// `nominal_n_per_s`: the travel that rate asks for, `|ḟ| / k`, may use [`TRAVEL_SPEED_SHARE`]
    /// of the speed limit; `None` (no bound) while the stiffness is not known or the limit not
    /// given. Feed-forward of what the travel allows, where the force's lag would otherwise have
    /// to grow until it slowed the clock (the lag-driven rate of the machine).
    pub fn clock_rate(&self, nominal_n_per_s: f64) -> Option<f64> {
        let k = self.stiffness()?;
        if !self.limit_mps.is_finite() || !nominal_n_per_s.is_finite() {
            return None;
        }
        let allowed = k * self.limit_mps * TRAVEL_SPEED_SHARE;
        Some(if nominal_n_per_s.abs() > allowed {
            allowed / nominal_n_per_s.abs()
        } else {
            1.0
        })
    }

    fn effective_samples(&self) -> f64 {
        if self.weight_sq > 0.0 {
            self.weight * self.weight / self.weight_sq
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic normal-ish noise (sum of 12 uniforms, minus 6): unit variance.
    fn noise(seed: &mut u64) -> f64 {
        (0..12)
            .map(|_| {
                *seed ^= *seed << 13;
                *seed ^= *seed >> 7;
                *seed ^= *seed << 17;
                (*seed >> 11) as f64 / (1u64 << 53) as f64
            })
            .sum::<f64>()
            - 6.0
    }

    /// Feeds `ticks` ticks at 1 kHz of a tool at `position(t)` applying `force(t)` plus 0.2 N
    /// of noise, asked for `desired(t)`.
    fn feed(
        travel: &mut TravelFeedForward,
        from_s: f64,
        ticks: usize,
        position: impl Fn(f64) -> f64,
        force: impl Fn(f64) -> f64,
        desired: impl Fn(f64) -> f64,
    ) {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        for i in 0..ticks {
            let t = from_s + i as f64 * 1e-3;
            travel.update(t, position(t), force(t) + 0.2 * noise(&mut seed), desired(t));
        }
    }

    #[test]
    fn a_spring_travelled_at_ten_millimetres_a_second_is_fitted_within_its_standard_error() {
        // The window's standard error is σ_f / (σ_p √N): 0.2 N / (0.6 mm · 10) ≈ 33 N/m, 17 % of
        // a 200 N/m spring and 8 % of a 400 N/m one; allowed: about two of them.
        for (k, within) in [(200.0, 0.35), (400.0, 0.15), (1000.0, 0.1)] {
            let mut travel = TravelFeedForward::new();
            // The cap goes down at 10 mm/s from 0.3 m, its spring at 2 N preload and `k` N/m.
            let position = |t: f64| 0.3 + 0.01 * t;
            let force = |t: f64| 2.0 + k * 0.01 * t;
            feed(&mut travel, 0.0, 300, position, force, force);
            let fitted = travel.stiffness().expect("a spring travelled is known");
            assert!((fitted - k).abs() <= within * k, "fitted {fitted:.0} N/m for {k} N/m");
            // The desired force rises at k · 10 mm/s: the velocity it asks for is 10 mm/s.
            assert!((travel.force_rate() - k * 0.01).abs() < 1e-6 * k);
            let v = travel.velocity(1.0);
            assert!(
                (v - 0.01).abs() <= 0.012 * within / (1.0 - within),
                "{k} N/m: {v} m/s for 10 mm/s"
            );
        }
    }

    #[test]
    fn a_tool_that_does_not_travel_or_finds_no_spring_gets_no_feed_forward() {
        // A stiff surface: the force rises and the tool stays (a micrometre of give).
        let mut stiff = TravelFeedForward::new();
        feed(
            &mut stiff,
            0.0,
            300,
            |t| 0.3 + 1e-6 * t,
            |t| 2.0 + 20.0 * t,
            |t| 2.0 + 20.0 * t,
        );
        assert_eq!(stiff.stiffness(), None);
        assert_eq!(stiff.velocity(1.0), 0.0);
        assert_eq!(stiff.clock_rate(20.0), None);
        // Moving deeper while the force falls is no spring (a surface that gives way).
        let mut giving = TravelFeedForward::new();
        feed(
            &mut giving,
            0.0,
            300,
            |t| 0.3 + 0.01 * t,
            |t| 6.0 - 400.0 * 0.01 * t,
            |_| 6.0,
        );
        assert_eq!(giving.stiffness(), None);
        // Moving at a constant force: no slope to speak of.
        let mut flat = TravelFeedForward::new();
        feed(&mut flat, 0.0, 300, |t| 0.3 + 0.01 * t, |_| 5.0, |_| 5.0);
        assert_eq!(flat.stiffness(), None);
    }

    #[test]
    fn losing_contact_forgets_the_spring() {
        let mut travel = TravelFeedForward::new();
        let position = |t: f64| 0.3 + 0.01 * t;
        let force = |t: f64| 2.0 + 4.0 * t;
        feed(&mut travel, 0.0, 300, position, force, force);
        assert!(travel.stiffness().is_some());
        // The tool leaves the cap: no force, whatever its position.
        feed(&mut travel, 0.3, 10, |t| 0.303 - 0.01 * (t - 0.3), |_| 0.0, |_| 0.0);
        assert_eq!(travel.stiffness(), None);
        assert_eq!(travel.velocity(1.0), 0.0);
        // Back on the spring, it takes a few window's worth of ticks to be known again.
        feed(&mut travel, 0.31, 10, position, force, force);
        assert_eq!(travel.stiffness(), None);
        feed(&mut travel, 0.32, 200, position, force, force);
        assert!(travel.stiffness().is_some());
    }

    #[test]
    fn the_velocity_and_the_clock_keep_within_the_speed_limit() {
        let mut travel = TravelFeedForward::new();
        let position = |t: f64| 0.3 + 0.01 * t;
        let force = |t: f64| 2.0 + 4.0 * t;
        // Asked for 40 N/s against 400 N/m: 100 mm/s, above a 12 mm/s limit.
        feed(&mut travel, 0.0, 300, position, force, |t| 2.0 + 40.0 * t);
        let k = travel.stiffness().expect("known");
        assert_eq!(travel.velocity(0.012), 0.012);
        assert_eq!(travel.velocity(-1.0), 0.0, "a negative limit is no limit to move at");
        // Without a limit noted there is no bound on the clock.
        assert_eq!(travel.clock_rate(40.0), None);
        travel.set_speed_limit(0.012);
        let rate = travel.clock_rate(40.0).expect("a bound");
        assert!((rate * 40.0 - k * 0.012 * TRAVEL_SPEED_SHARE).abs() < 1e-9);
        assert_eq!(travel.clock_rate(1.0), Some(1.0), "a slow profile runs at full clock");
        assert!(
            travel.clock_rate(-40.0).is_some_and(|r| (r - rate).abs() < 1e-12),
            "release alike"
        );
    }

    #[test]
    fn ticks_out_of_order_or_not_finite_are_ignored() {
        let mut travel = TravelFeedForward::new();
        let position = |t: f64| 0.3 + 0.01 * t;
        let force = |t: f64| 2.0 + 4.0 * t;
        feed(&mut travel, 0.0, 300, position, force, force);
        let before = travel.clone();
        travel.update(0.1, 0.5, 50.0, 50.0);
        travel.update(0.299, 0.5, 50.0, 50.0);
        travel.update(f64::NAN, 0.5, 50.0, 50.0);
        travel.update(0.4, f64::INFINITY, 50.0, 50.0);
        assert_eq!(travel, before);
    }
}
