//! Bounds on every number a user gives that sizes work or memory, checked before it is used:
//! clap value parsers for flags, and checks with a message naming the field for values that come
//! from files (a template's `resample`, a demonstration's duration).
//!
//! The bounds are generous for real use (a contact skill lasts seconds, sensors sample at most a
//! few kHz) and keep the worst case to seconds of work and tens of megabytes.

/// Rates for resampling and low-pass cut-offs \[Hz\].
pub const RATE_HZ: (f64, f64) = (0.1, 10_000.0);
/// Speed and force factors (`--speed`, `--force-scale`).
pub const FACTOR: (f64, f64) = (0.01, 100.0);
/// Sample periods (`rollout --dt`) \[s\].
pub const PERIOD_S: (f64, f64) = (1e-4, 1.0);
/// Each component of an offset (`--goal-offset`) \[m\].
pub const OFFSET_M: f64 = 10.0;
/// Longest demonstration \[s\] (the learned motions' longest duration too).
pub const DEMO_S: f64 = skill_runtime::skill::validate::MAX_TAU_S;
/// Most samples a demonstration may have after resampling.
pub const SAMPLES: f64 = 2e6;
/// Most segments a template may expect.
pub const SEGMENTS: u32 = 1000;
/// Largest force component a demonstration may hold \[N\] (industrial F/T sensors read up to a
/// few kN).
pub const DEMO_FORCE_N: f64 = 1e5;
/// Largest moment component a demonstration may hold \[N m\].
pub const DEMO_MOMENT_NM: f64 = 1e4;

/// `value` (named `name` in the message) within `[min, max]`.
pub fn check(name: &str, value: f64, (min, max): (f64, f64), unit: &str) -> Result<f64, String> {
    if !value.is_finite() {
        return Err(format!("{name} must be a finite number, not {value}"));
    }
    if !(min..=max).contains(&value) {
        return Err(format!(
            "{name} is {}{unit}; it must lie between {min}{unit} and {max}{unit}",
            number(value)
        ));
    }
    Ok(value)
}

/// `value` as people read it: plain for ordinary magnitudes, in exponent form otherwise.
pub fn number(value: f64) -> String {
    if value != 0.0 && !(1e-3..1e6).contains(&value.abs()) {
        format!("{value:e}")
    } else {
        format!("{value}")
    }
}

fn parse(text: &str) -> Result<f64, String> {
    text.trim()
        .parse::<f64>()
        .map_err(|_| format!("`{text}` is not a number"))
}

/// `text` as a number where infinity switches something off: only the word `inf` (or
/// `infinity`, either signed) may give it; a literal too large for a float (`1e400`) would
/// overflow to infinity silently, so it is refused, as is NaN.
pub fn number_or_inf(text: &str) -> Result<f64, String> {
    let value = parse(text)?;
    let word = text.trim().trim_start_matches(['+', '-']).to_ascii_lowercase();
    if value.is_nan() {
        return Err(format!("`{}` is not a number", text.trim()));
    }
    if value.is_infinite() && word != "inf" && word != "infinity" {
        return Err(format!(
            "`{}` is too large for a number (it would overflow to infinity); write `inf` to switch the limit off",
            text.trim()
        ));
    }
    Ok(value)
}

/// Clap parser for a rate in Hz (`--resample`, `--lowpass`).
pub fn rate_hz(text: &str) -> Result<f64, String> {
    check("the rate", parse(text)?, RATE_HZ, " Hz")
}

/// Clap parser for a speed or force factor (`--speed`, `--force-scale`).
pub fn factor(text: &str) -> Result<f64, String> {
    check("the factor", parse(text)?, FACTOR, "")
}

/// Clap parser for a sample period in seconds (`--dt`).
pub fn period_s(text: &str) -> Result<f64, String> {
    check("the period", parse(text)?, PERIOD_S, " s")
}

/// Clap parser for one offset component in metres (`--goal-offset`, comma separated).
pub fn offset_m(text: &str) -> Result<f64, String> {
    check("the offset", parse(text)?, (-OFFSET_M, OFFSET_M), " m")
}

/// Parses `NAME=VALUE` for `--limit`, checking the name and that the value is positive.
pub fn parse_limit(text: &str) -> Result<(String, f64), String> {
    let (name, value) = text
        .split_once('=')
        .ok_or_else(|| format!("`{text}`: write NAME=VALUE, e.g. force=60"))?;
    let value = number_or_inf(value).map_err(|err| format!("`{text}`: {err}"))?;
    let mut probe = skill_runtime::safety::Limits::for_skill(0.0, None);
    probe.set(name.trim(), value).map_err(|err| err.to_string())?;
    Ok((name.trim().to_string(), value))
}

#[cfg(test)]
mod tests {
    #[test]
    fn absurd_values_are_refused_with_their_value() {
        assert_eq!(super::rate_hz("100"), Ok(100.0));
        assert!(super::rate_hz("1.9e7").unwrap_err().contains("1.9"));
        assert!(super::factor("1e-12").is_err());
        assert!(super::factor("1e300").is_err());
        assert!(super::factor("inf").unwrap_err().contains("finite"));
        assert!(super::period_s("1e-9").is_err());
        assert!(super::offset_m("nan").is_err());
        assert!(super::offset_m("1e308").is_err());
        assert!(super::offset_m("abc").unwrap_err().contains("not a number"));
    }

    #[test]
    fn only_the_word_inf_is_infinite() {
        assert_eq!(super::number_or_inf("inf"), Ok(f64::INFINITY));
        assert_eq!(super::number_or_inf(" Infinity"), Ok(f64::INFINITY));
        assert_eq!(super::number_or_inf("60"), Ok(60.0));
        assert!(super::number_or_inf("1e400").unwrap_err().contains("overflow"));
        assert!(super::number_or_inf("-1e309").unwrap_err().contains("overflow"));
        assert!(super::number_or_inf("NaN").unwrap_err().contains("not a number"));
    }
}
